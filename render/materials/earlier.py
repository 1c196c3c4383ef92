"""Materials from earlier chapters that Part 5's materials build on.

* ``diffuse`` (Listing 6.5) and ``glossy`` of chapter 6 differ from Part 5's ``glossy``
  (Listing 12.8, in :mod:`render.materials.chapter12`); only ``diffuse`` is here.
* ``subsurface_scattering`` (Listing 4.8), used by ``glass_waves`` (12.13) and
  ``green_glass_waves`` (12.15).  Its volume is an ``anisotropic_vdf`` node; the
  renderer's volume support binds it.
* ``diffuse_reflection::diffuse_reflection(tint)`` (Listings 15.21-15.22), called but
  never listed: read as Listing 6.5's ``diffuse`` (a ``diffuse_reflection_bsdf`` with
  that tint).  (``glossy_yellow()``, the other unlisted one, is in chapter 13's module.)
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
from render.materials._common import color, diffuse_surface

__all__ = ["diffuse", "diffuse_reflection", "subsurface_scattering", "PINK_STONE"]

#: Listing 15.21's ``const color pink_stone = color(.7, .66, .63)``.
PINK_STONE = (0.7, 0.66, 0.63)


def diffuse(tint: Color = (0.5, 0.5, 0.5)) -> material:
    """Listing 6.5: ``diffuse_reflection_bsdf(tint: tint)``."""
    return material(surface=diffuse_surface(color(tint, "tint")))


def diffuse_reflection(tint: Color = (0.5, 0.5, 0.5)) -> material:
    """``diffuse_reflection::diffuse_reflection`` of Listings 15.21-15.22 (not listed in
    the Handbook): Listing 6.5's ``diffuse``."""
    return diffuse(tint)


def _coefficient(c, distance: float, name: str) -> tuple[float, float, float]:
    c = np.asarray(color(c, name), dtype=np.float64)
    if distance <= 0.0:
        return (0.0, 0.0, 0.0)
    if np.any(c <= 0.0):
        raise ValueError(f"{name} must be > 0 in every channel (its log is taken), got {tuple(c)}")
    return tuple(float(x) for x in -np.log(c) / distance)


def subsurface_scattering(
    surface_color: Color = (1.0, 1.0, 1.0),
    scattering_color: UniformColor = (0.05, 0.05, 0.05),
    transmission_color: UniformColor = (0.1, 0.95, 0.65),
    transmission_distance: UniformFloat = 0.3,
    roughness: Float = 0.0,
    volume_ior: UniformFloat = 1.5,
) -> material:
    """Listing 4.8: a glossy reflect-transmit interface over a scattering, absorbing volume.

    Coefficients: ``-log(color) / transmission_distance`` (zero when the distance is
    ``<= 0``); volume phase function ``anisotropic_vdf(directional_bias: -0.5)``;
    ``ior: color(volume_ior)``.

    Examples
    --------
    >>> m = subsurface_scattering(transmission_distance=0.0)
    >>> m.volume.absorption_coefficient, m.ior
    ((0.0, 0.0, 0.0), (1.5, 1.5, 1.5))
    """
    distance = float(transmission_distance)
    volume_ior = float(volume_ior)
    if not (np.isfinite(distance) and np.isfinite(volume_ior) and volume_ior > 0.0):
        raise ValueError("transmission_distance must be finite and volume_ior finite and > 0")
    surface_bsdf = df.simple_glossy_bsdf(tint=color(surface_color, "surface_color"),
                                         roughness_u=roughness, mode="scatter_reflect_transmit")
    return material(
        ior=(volume_ior,) * 3,
        surface=material_surface(scattering=surface_bsdf),
        volume=material_volume(
            scattering=df.anisotropic_vdf(directional_bias=-0.5),
            scattering_coefficient=_coefficient(scattering_color, distance, "scattering_color"),
            absorption_coefficient=_coefficient(transmission_color, distance, "transmission_color"),
        ),
    )
