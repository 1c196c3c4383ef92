"""Chapter 4 of the Handbook, "Glass": specular and glossy glass, Fresnel layers, absorption.

Listings 4.1-4.7 (4.8, ``subsurface_scattering``, is in :mod:`render.materials.earlier`
because Part 5's glass materials build on it).  Volume coefficients are per meter of
world space (``material_volume``); the integrator's homogeneous media use them.

Reading notes:

* Listing 4.4 passes ``uniform color layer_ior`` to ``df::fresnel_layer``'s ``ior``,
  which is a ``float`` since MDL 1.4: a grey colour becomes that float, a coloured one
  uses ``df::color_fresnel_layer`` (MDL 1.4's per-channel layerer).  See
  :func:`render.materials.chapter6.fresnel_layer_of`.
* The text after Listing 4.6 calls it ``material_gloss_reflect_transmit_absorb``; the
  listing and Figure 4.10 call it ``glossy_reflect_transmit_absorb``.
"""

from __future__ import annotations

import numpy as np

from render.material import (
    Color,
    Float,
    UniformColor,
    UniformFloat,
    df,
    material,
    material_surface,
    material_volume,
)
from render.materials._common import color
from render.materials.chapter6 import fresnel_layer_of
from render.materials.earlier import _coefficient

__all__ = [
    "specular_reflect_transmit",
    "specular_reflect_transmit_thin_walled",
    "glossy_reflect_transmit",
    "glossy_reflect_transmit_layers",
    "glossy_reflect_transmit_absorb",
    "glossy_reflect_transmit_absorb_falloff",
]


def _ior(value, name: str) -> tuple[float, float, float]:
    """A uniform colour IOR: three finite numbers > 0."""
    c = color(value, name)
    if callable(c):
        raise ValueError(f"{name} is uniform: pass a constant colour, not a function of state")
    if min(c) <= 0.0:
        raise ValueError(f"{name} must be > 0 in every channel (an index of refraction), got {c}")
    return c


def _glossy_reflect_transmit_bsdf(tint, roughness, name: str = "tint"):
    return df.simple_glossy_bsdf(tint=color(tint, name), roughness_u=roughness,
                                 mode="scatter_reflect_transmit")


def specular_reflect_transmit(tint: Color = (1.0, 1.0, 1.0),
                              ior: UniformColor = (1.3, 1.3, 1.3)) -> material:
    """Listing 4.1: ``df::specular_bsdf(tint, scatter_reflect_transmit)`` with ``ior``."""
    return material(ior=_ior(ior, "ior"), surface=material_surface(scattering=df.specular_bsdf(
        tint=color(tint, "tint"), mode="scatter_reflect_transmit")))


def specular_reflect_transmit_thin_walled(tint: Color = (1.0, 1.0, 1.0),
                                          ior: UniformColor = (1.3, 1.3, 1.3)) -> material:
    """Listing 4.2: Listing 4.1 with ``thin_walled: true`` (no refraction through the wall).

    Examples
    --------
    >>> m = specular_reflect_transmit_thin_walled(tint=(0.64, 0.72, 0.80))
    >>> m.thin_walled, m.ior, m.surface.scattering.kwargs["mode"]
    (True, (1.3, 1.3, 1.3), 'scatter_reflect_transmit')
    """
    m = specular_reflect_transmit(tint, ior)
    return material(thin_walled=True, ior=m.ior, surface=m.surface)


def glossy_reflect_transmit(tint: Color = (1.0, 1.0, 1.0), roughness: Float = 0.0,
                            volume_ior: UniformColor = (1.5, 1.5, 1.5)) -> material:
    """Listing 4.3: ``df::simple_glossy_bsdf(tint, roughness_u: roughness,
    scatter_reflect_transmit)``, ``ior: volume_ior``."""
    return material(ior=_ior(volume_ior, "volume_ior"), surface=material_surface(
        scattering=_glossy_reflect_transmit_bsdf(tint, roughness)))


def glossy_reflect_transmit_layers(reflection_color: Color = (1.0, 1.0, 1.0),
                                   transmission_color: Color = (1.0, 1.0, 1.0),
                                   roughness: Float = 0.0,
                                   volume_ior: UniformColor = (1.5, 1.5, 1.5),
                                   layer_ior: UniformColor = (1.5, 1.5, 1.5)) -> material:
    """Listing 4.4: ``df::fresnel_layer(ior: layer_ior, layer: <glossy reflect>,
    base: <glossy transmit>)``, ``ior: volume_ior``.

    The reflection lobe carries ``reflection_color``, the transmission lobe
    ``transmission_color``, both with ``roughness``.
    """
    reflection = df.simple_glossy_bsdf(tint=color(reflection_color, "reflection_color"),
                                       roughness_u=roughness, mode="scatter_reflect")
    transmission = df.simple_glossy_bsdf(tint=color(transmission_color, "transmission_color"),
                                         roughness_u=roughness, mode="scatter_transmit")
    surface_bsdf = fresnel_layer_of(_ior(layer_ior, "layer_ior"), layer=reflection,
                                    base=transmission)
    return material(ior=_ior(volume_ior, "volume_ior"),
                    surface=material_surface(scattering=surface_bsdf))


def glossy_reflect_transmit_absorb(surface_color: Color = (1.0, 1.0, 1.0),
                                   roughness: Float = 0.0,
                                   absorption: UniformColor = (1.0, 1.0, 1.0),
                                   volume_ior: UniformColor = (1.5, 1.5, 1.5)) -> material:
    """Listing 4.6: Listing 4.3's surface over ``material_volume(absorption_coefficient:
    absorption)`` (per meter; Figure 4.10 needs ``color(10, 6, 2)``).

    Examples
    --------
    >>> glossy_reflect_transmit_absorb(absorption=(10, 6, 2)).volume.absorption_coefficient
    (10.0, 6.0, 2.0)
    """
    absorption = color(absorption, "absorption")
    if callable(absorption) or min(absorption) < 0.0:
        raise ValueError(f"absorption must be a constant colour >= 0 (per meter), got {absorption}")
    return material(ior=_ior(volume_ior, "volume_ior"),
                    surface=material_surface(
                        scattering=_glossy_reflect_transmit_bsdf(surface_color, roughness,
                                                                 "surface_color")),
                    volume=material_volume(absorption_coefficient=absorption))


def glossy_reflect_transmit_absorb_falloff(surface_color: Color = (1.0, 1.0, 1.0),
                                           transmission_color: UniformColor = (1.0, 1.0, 1.0),
                                           transmission_distance: UniformFloat = 1.0,
                                           roughness: Float = 0.0,
                                           volume_ior: UniformFloat = 1.5) -> material:
    """Listing 4.7: absorption ``-log(transmission_color) / transmission_distance``
    (``color(0.0)`` when the distance is ``<= 0``), ``ior: color(volume_ior)``.

    Light that travels ``transmission_distance`` through the glass keeps
    ``transmission_color`` of its energy.

    Examples
    --------
    >>> m = glossy_reflect_transmit_absorb_falloff(transmission_color=(0.8, 0.9, 1.0),
    ...                                            transmission_distance=0.05)
    >>> [round(x, 6) for x in m.volume.absorption_coefficient]
    [4.462871, 2.10721, 0.0]
    """
    distance = float(transmission_distance)
    volume_ior = float(volume_ior)
    if not (np.isfinite(distance) and np.isfinite(volume_ior) and volume_ior > 0.0):
        raise ValueError(
            f"transmission_distance must be finite and volume_ior finite and > 0, got "
            f"{transmission_distance!r} and {volume_ior!r}")
    return material(
        ior=(volume_ior,) * 3,
        surface=material_surface(scattering=_glossy_reflect_transmit_bsdf(
            surface_color, roughness, "surface_color")),
        volume=material_volume(absorption_coefficient=tuple(  # + 0.0: no -0.0 for color(1)
            x + 0.0 for x in _coefficient(transmission_color, distance, "transmission_color"))),
    )
