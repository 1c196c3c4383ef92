"""Chapter 12 of the Handbook: displacement mapping (Listings 12.4-12.18).

Displacement vectors come from :data:`displacement.fields.FIELDS`; the surfaces are
MDL df nodes.  Where the Handbook's displacement is trivially zero (``waves`` with
``use_displacement: false``, a weave with ``displace: 0``), ``geometry.displacement``
is None so the scene does not dice the object (the point of section 12.2).
"""

from __future__ import annotations

import numpy as np

from displacement.fields import FIELDS
from displacement.waves import uv_wave
from render.library.resources import load_texture
from render.material import (
    Bool,
    Color,
    Float,
    Material,
    UniformFloat,
    UniformFloat2,
    Varying,
    df,
    material,
    material_geometry,
    material_surface,
)
from render.materials._common import color, diffuse_surface, float2, scaled
from render.materials.earlier import subsurface_scattering

__all__ = [
    "waves_as_grayscale",
    "waves_as_displacement",
    "waves",
    "glossy",
    "glossy_waves",
    "waver",
    "glossy_yellow_waves",
    "glass_waves",
    "shaper",
    "green_glass_waves",
    "diffuse_weave",
    "weave",
    "gold_weave",
    "WEAVE_DEPTH",
]

#: Listing 12.16's height map (``gallery/textures/weave_depth.png``, read linear).
WEAVE_DEPTH = "weave_depth.png"


def waves_as_grayscale(frequency: UniformFloat2 = (1.0, 1.0),
                       gray_max: UniformFloat2 = (0.5, 0.5)) -> material:
    """Listing 12.4: ``tint = color(uv_wave(frequency, float2(0.0), gray_max))``.

    Examples
    --------
    >>> import numpy as np
    >>> from displacement.surfaces import UnitSquare
    >>> m = waves_as_grayscale((0.0, 4.0), (0.0, 1.0))
    >>> s = UnitSquare().state_at_uv(np.array([[0.3, 0.0625]]))   # sin(pi/2): 1
    >>> m.surface.scattering.kwargs["tint"](s).round(12).tolist()
    [[1.0, 1.0, 1.0]]
    """
    frequency = float2(frequency, "frequency")
    gray_max = float2(gray_max, "gray_max")

    def tint(state):
        gray = uv_wave(state.uv, frequency, (0.0, 0.0), gray_max)
        return np.repeat(gray[:, None], 3, axis=1)

    return material(surface=diffuse_surface(
        Varying(tint, "color(uv_wave)", {"frequency": frequency, "gray_max": gray_max})))


def waves_as_displacement(frequency: UniformFloat2 = (1.0, 1.0),
                          distance: UniformFloat2 = (0.1, 0.1),
                          tint: Color = (0.7, 0.7, 0.7)) -> material:
    """Listing 12.5: diffuse ``tint``; displacement
    ``normal * uv_wave(frequency, -distance, distance)``."""
    return material(
        surface=diffuse_surface(color(tint, "tint")),
        geometry=material_geometry(displacement=FIELDS["waves_as_displacement"](
            float2(frequency, "frequency"), float2(distance, "distance"))),
    )


def _wave_parts(distance, frequency, tint, use_displacement):
    """Listing 12.7's let-block: ``(modified_tint, displacement or None)``."""
    distance = float2(distance, "distance")
    frequency = float2(frequency, "frequency")
    tint = color(tint, "tint")
    if use_displacement:
        return tint, FIELDS["waves"](distance, frequency, True)
    modified = scaled(tint, lambda s: uv_wave(s.uv, frequency, 0.1, 0.5), "waves_tint")
    return modified, None


def waves(distance: UniformFloat2 = (0.1, 0.1), frequency: UniformFloat2 = (1.0, 1.0),
          tint: Color = (0.7, 0.7, 0.7), use_displacement: Bool = True) -> material:
    """Listing 12.7: displacement, or (``use_displacement: false``) the tint scaled by
    ``uv_wave(frequency, float2(0.1), float2(0.5))`` and no displacement at all."""
    modified_tint, displacement = _wave_parts(distance, frequency, tint, bool(use_displacement))
    return material(surface=diffuse_surface(modified_tint),
                    geometry=material_geometry(displacement=displacement))


def glossy(tint: Color = (0.7, 0.7, 0.7), roughness: Float = 0.3) -> material:
    """Listing 12.8: ``df::simple_glossy_bsdf(tint: tint, roughness_u: roughness)``."""
    return material(surface=material_surface(
        scattering=df.simple_glossy_bsdf(tint=color(tint, "tint"), roughness_u=roughness)))


def glossy_waves(distance: UniformFloat2 = (0.1, 0.1), frequency: UniformFloat2 = (1.0, 1.0),
                 tint: Color = (0.7, 0.7, 0.7), roughness: Float = 0.3,
                 use_displacement: Bool = True) -> material:
    """Listing 12.9: ``waves`` with ``glossy(modified_tint, roughness).surface``."""
    modified_tint, displacement = _wave_parts(distance, frequency, tint, bool(use_displacement))
    return material(surface=glossy(modified_tint, roughness).surface,
                    geometry=material_geometry(displacement=displacement))


def waver(surface_and_volume: Material, distance: UniformFloat2 = (0.1, 0.1),
          frequency: UniformFloat2 = (1.0, 1.0)) -> material:
    """Listing 12.11: ior, surface and volume of ``surface_and_volume``, displaced by
    ``normal * uv_wave(frequency, -distance, distance)``."""
    _check_material(surface_and_volume, "surface_and_volume")
    return material(
        ior=surface_and_volume.ior,
        surface=surface_and_volume.surface,
        volume=surface_and_volume.volume,
        geometry=material_geometry(displacement=FIELDS["waver"](
            float2(frequency, "frequency"), float2(distance, "distance"))),
    )


def glossy_yellow_waves(distance: UniformFloat2 = (0.1, 0.1),
                        frequency: UniformFloat2 = (1.0, 1.0)) -> material:
    """Listing 12.12: ``waver(glossy(color(0.6, 0.4, 0.0), 0.3), distance, frequency)``."""
    return waver(glossy((0.6, 0.4, 0.0), 0.3), distance, frequency)


def glass_waves(distance: UniformFloat2 = (0.1, 0.1),
                frequency: UniformFloat2 = (1.0, 1.0)) -> material:
    """Listing 12.13: ``waver`` over Listing 4.8's ``subsurface_scattering``."""
    return waver(subsurface_scattering(transmission_color=(0.8, 0.9, 1.0),
                                       scattering_color=(0.1, 0.1, 0.3),
                                       transmission_distance=2.0),
                 distance, frequency)


def shaper(surface_and_volume: Material, geometry: Material) -> material:
    """Listing 12.14: ior, surface and volume of one material, geometry of another."""
    _check_material(surface_and_volume, "surface_and_volume")
    _check_material(geometry, "geometry")
    return material(ior=surface_and_volume.ior, surface=surface_and_volume.surface,
                    volume=surface_and_volume.volume, geometry=geometry.geometry)


def green_glass_waves(distance: UniformFloat2 = (0.1, 0.1),
                      frequency: UniformFloat2 = (1.0, 1.0)) -> material:
    """Listing 12.15: ``shaper(subsurface_scattering(...), waves_as_displacement(...))``."""
    return shaper(
        subsurface_scattering(transmission_color=(0.1, 0.4, 0.2), scattering_color=(0.1, 0.1, 0.1),
                              transmission_distance=1.0),
        waves_as_displacement(frequency=frequency, distance=distance),
    )


def _weave_displacement(scale, displace):
    """Listing 12.16's let-block: ``normal * displace * average(weave_depth(uv * scale))``."""
    scale = float2(scale, "scale")
    displace = float(displace)
    if displace == 0.0:
        return None
    return FIELDS["diffuse_weave"](load_texture(WEAVE_DEPTH, "linear"), scale, displace)


def diffuse_weave(scale: UniformFloat2 = (1.0, 1.0), displace: UniformFloat = 0.0,
                  tint: Color = (0.7, 0.7, 0.7)) -> material:
    """Listing 12.16: ``weave_depth.png`` as a height map, diffuse ``tint``."""
    return material(surface=diffuse_surface(color(tint, "tint")),
                    geometry=material_geometry(displacement=_weave_displacement(scale, displace)))


_DEFAULT_MATERIAL = material()


def weave(scale: UniformFloat2 = (1.0, 1.0), displace: UniformFloat = 0.0,
          surface_property: Material = _DEFAULT_MATERIAL) -> material:
    """Listing 12.17: the weave displacement with ``surface_property.surface``
    (default ``material()``: black)."""
    _check_material(surface_property, "surface_property")
    return material(surface=surface_property.surface,
                    geometry=material_geometry(displacement=_weave_displacement(scale, displace)))


def gold_weave(scale: UniformFloat2 = (1.0, 1.0), displace: UniformFloat = 0.0) -> material:
    """Listing 12.18: ``weave`` with ``glossy(tint: color(0.6, 0.4, 0.0), roughness: 0.3)``."""
    return weave(scale, displace, glossy(tint=(0.6, 0.4, 0.0), roughness=0.3))


def _check_material(value, name: str) -> None:
    if not isinstance(value, material):
        raise ValueError(f"{name} must be a material (e.g. glossy()), got {type(value).__name__}")



