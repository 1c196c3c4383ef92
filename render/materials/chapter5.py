"""Chapter 5 of the Handbook, "Light in a volume": volume enclosures and shaped emission.

Listings 5.1-5.7.  A volume material is a clear, non-refracting enclosure
(``df::specular_bsdf(tint: color(1.0), mode: df::scatter_transmit)``) around a
homogeneous medium whose ``absorption_coefficient`` and ``scattering_coefficient`` are
per meter of world space; ``vdf()`` (no ``scattering`` vdf) scatters isotropically and
``df::anisotropic_vdf(directional_bias)`` is Henyey-Greenstein.

Reading notes:

* ``green_light`` and ``blue_light`` are not listed: "The green and blue lights are
  defined in the same manner" as Listing 5.3's ``red_light``; they emit
  ``color(0, 1, 0)`` and ``color(0, 0, 1)``.
* Listing 5.6 is chapter 3's ``emission`` again (:func:`render.materials.chapter3.emission`).
* Section 5.4 says the rest of the chapter uses ``isotropic_material`` and section 5.6
  assigns "the ``isotropic_material`` from Listing 5.2"; both mean Listing 5.1's
  ``isotropic_volume`` (Listing 5.2 is ``anisotropic_volume``).
"""

from __future__ import annotations

import math

from render.material import (
    Color,
    Float,
    UniformColor,
    UniformFloat,
    df,
    material,
    material_emission,
    material_surface,
    material_volume,
)
from render.materials._common import color

__all__ = [
    "isotropic_volume",
    "anisotropic_volume",
    "red_light",
    "green_light",
    "blue_light",
    "blue_scattering",
    "blue_absorption",
    "spotlight_emission",
]


def _clear_enclosure() -> material_surface:
    """The clear, non-refracting surface of Listings 5.1, 5.2, 5.4 and 5.5."""
    return material_surface(scattering=df.specular_bsdf(tint=(1.0, 1.0, 1.0),
                                                        mode="scatter_transmit"))


def _coefficient(value, name: str):
    c = color(value, name)
    if not callable(c) and min(c) < 0.0:
        raise ValueError(f"{name} must be >= 0 in every channel (a coefficient per meter), "
                         f"got {c}")
    return c


def isotropic_volume(scattering: Color = (1.0, 1.0, 1.0),
                     absorption: Color = (1.0, 1.0, 1.0)) -> material:
    """Listing 5.1: a clear enclosure of an isotropically scattering medium
    (``absorption_coefficient: absorption``, ``scattering_coefficient: scattering``).

    Examples
    --------
    >>> m = isotropic_volume(scattering=(0.5, 0.5, 0.5), absorption=0.0)
    >>> m.volume.scattering is None, m.volume.scattering_coefficient, m.ior
    (True, (0.5, 0.5, 0.5), (1.0, 1.0, 1.0))
    """
    return material(surface=_clear_enclosure(), volume=material_volume(
        absorption_coefficient=_coefficient(absorption, "absorption"),
        scattering_coefficient=_coefficient(scattering, "scattering")))


def anisotropic_volume(absorption: Color = (1.0, 1.0, 1.0), scattering: Color = (1.0, 1.0, 1.0),
                       directional_bias: Float = 0.0,
                       ior: UniformColor = (1.0, 1.0, 1.0)) -> material:
    """Listing 5.2: Listing 5.1 with ``df::anisotropic_vdf(directional_bias)`` (-1 pure
    backward, 0 isotropic, 1 pure forward scattering) and an ``ior``.

    Examples
    --------
    >>> anisotropic_volume(directional_bias=0.5).volume.scattering
    df::anisotropic_vdf(directional_bias: 0.5)
    """
    ior = color(ior, "ior")
    if callable(ior) or min(ior) <= 0.0:
        raise ValueError(f"ior must be a constant colour > 0 (uniform), got {ior}")
    if not callable(directional_bias) and not -1.0 <= float(directional_bias) <= 1.0:
        raise ValueError(f"directional_bias must be in [-1, 1] (-1 backward, 1 forward), got "
                         f"{directional_bias!r}")
    return material(ior=ior, surface=_clear_enclosure(), volume=material_volume(
        scattering=df.anisotropic_vdf(directional_bias=directional_bias),
        absorption_coefficient=_coefficient(absorption, "absorption"),
        scattering_coefficient=_coefficient(scattering, "scattering")))


def _light(intensity) -> material:
    return material(thin_walled=True, surface=material_surface(emission=material_emission(
        emission=df.diffuse_edf(), intensity=intensity)))


def red_light() -> material:
    """Listing 5.3: thin-walled ``df::diffuse_edf()`` with ``intensity: color(1.0, 0.0, 0.0)``."""
    return _light((1.0, 0.0, 0.0))


def green_light() -> material:
    """Section 5.9's green light, "defined in the same manner" as ``red_light``."""
    return _light((0.0, 1.0, 0.0))


def blue_light() -> material:
    """Section 5.9's blue light, "defined in the same manner" as ``red_light``."""
    return _light((0.0, 0.0, 1.0))


def blue_scattering() -> material:
    """Listing 5.4: absorption ``color(0.3)``, scattering ``color(0.1, 0.1, 0.15)``."""
    return material(surface=_clear_enclosure(), volume=material_volume(
        absorption_coefficient=(0.3, 0.3, 0.3), scattering_coefficient=(0.1, 0.1, 0.15)))


def blue_absorption() -> material:
    """Listing 5.5: absorption ``color(0.0, 0.0, 0.2)`` (the volume looks yellow),
    scattering ``color(0.5)``."""
    return material(surface=_clear_enclosure(), volume=material_volume(
        absorption_coefficient=(0.0, 0.0, 0.2), scattering_coefficient=(0.5, 0.5, 0.5)))


def spotlight_emission(spread_factor: UniformFloat = 1.0,
                       tint: Color = (1.0, 1.0, 1.0)) -> material:
    """Listing 5.7: thin-walled ``df::spot_edf(exponent: 1.0, spread: spread_factor *
    math::PI, global_distribution: true)`` with ``intensity: tint``.

    Parameters
    ----------
    spread_factor : float in [0, 1]
        The spread as a fraction of pi (1: the whole hemisphere).

    Examples
    --------
    >>> edf = spotlight_emission(0.5).surface.emission.emission
    >>> edf.name, edf.kwargs["spread"] == math.pi / 2, edf.kwargs["global_distribution"]
    ('spot_edf', True, True)
    """
    factor = float(spread_factor)
    if not 0.0 <= factor <= 1.0:
        raise ValueError(
            f"spread_factor must be in [0, 1] (a fraction of pi), got {spread_factor!r}")
    return material(thin_walled=True, surface=material_surface(emission=material_emission(
        emission=df.spot_edf(exponent=1.0, spread=factor * math.pi, global_distribution=True),
        intensity=color(tint, "tint"))))
