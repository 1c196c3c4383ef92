"""Chapter 3 of the Handbook, "Light at a surface": one distribution function per material.

Diffuse reflection and transmission, emission (front only, or with a diffuse backface),
specular and glossy reflection, transmission and both (Listings 3.1-3.10 and the
unnumbered listings of sections 3.5-3.6).  Each function returns the listing's
:class:`~render.material.material` with the Handbook's parameters and defaults.

Reading notes:

* ``emission_with_diffuse_backface`` (section 3.5.1) prints ``backface:`` inside the
  ``material_surface(...)`` of ``surface``; ``material_surface`` has no such field, so it
  is read as the material's ``backface`` (what the text and the struct diagram say:
  "Defining a diffuse reflection BSDF for the backface field and setting thin_walled to
  true defines two different materials for the two sides of the polygon").
* ``plaster`` is Listing 3.2 (``tint`` and ``roughness``); Listing 3.1 is the same
  material without ``roughness``, and so are its defaults.
* ``mirror`` is Listing 3.5 (``specular_bsdf`` with ``tint: color(0.5)``).  Chapter 6's
  unnumbered ``mirror()`` of Figure 6.27 (``tint: white = color(0.7)``) is
  :func:`render.materials.chapter6.mirror`, used by chapter 6's layer series.
"""

from __future__ import annotations

from render.material import (
    Color,
    Float,
    df,
    material,
    material_emission,
    material_surface,
)
from render.materials._common import color, diffuse_surface

__all__ = [
    "plaster",
    "diffuse_transmission",
    "emission",
    "emission_with_diffuse_backface",
    "specular",
    "mirror",
    "specular_transmission",
    "specular_reflection_transmission",
    "glossy_reflection",
    "glossy_transmission",
    "glossy_reflection_transmission",
]


def plaster(tint: Color = (0.7, 0.7, 0.7), roughness: Float = 0.0) -> material:
    """Listing 3.2: ``df::diffuse_reflection_bsdf(tint: tint, roughness: roughness)``.

    Examples
    --------
    >>> plaster().surface.scattering
    df::diffuse_reflection_bsdf(tint: (0.7, 0.7, 0.7), roughness: 0.0)
    """
    return material(surface=material_surface(scattering=df.diffuse_reflection_bsdf(
        tint=color(tint, "tint"), roughness=roughness)))


def diffuse_transmission() -> material:
    """Listing 3.3: ``df::diffuse_transmission_bsdf(tint: color(1.0))`` (not thin-walled)."""
    return material(surface=material_surface(
        scattering=df.diffuse_transmission_bsdf(tint=(1.0, 1.0, 1.0))))


def _emission_surface(tint) -> material_surface:
    return material_surface(emission=material_emission(
        emission=df.diffuse_edf(), intensity=color(tint, "tint")))


def emission(tint: Color = (1.0, 1.0, 1.0)) -> material:
    """Section 3.5.1 (and Listing 5.6): front-side ``df::diffuse_edf()`` with
    ``intensity: tint``; no scattering.

    Examples
    --------
    >>> m = emission((2.0, 1.0, 0.5))
    >>> m.surface.emission.emission.name, m.surface.emission.intensity, m.thin_walled
    ('diffuse_edf', (2.0, 1.0, 0.5), False)
    """
    return material(surface=_emission_surface(tint))


def emission_with_diffuse_backface(tint: Color = (1.0, 1.0, 1.0),
                                   backtint: Color = (0.8, 0.78, 0.75)) -> material:
    """Section 3.5.1: thin-walled; the front emits ``tint`` (``diffuse_edf``), the back
    reflects diffusely with ``backtint`` (the floor's colour in the Handbook's scenes).

    The listing's ``backface:`` is the material's field (see the module notes).
    """
    return material(
        thin_walled=True,
        surface=_emission_surface(tint),
        backface=diffuse_surface(color(backtint, "backtint")),
    )


def specular() -> material:
    """Section 3.6.1: ``df::specular_bsdf()``, a perfect mirror (tint 1, scatter_reflect)."""
    return material(surface=material_surface(scattering=df.specular_bsdf()))


def mirror() -> material:
    """Listing 3.5: ``df::specular_bsdf(tint: color(0.5), mode: df::scatter_reflect)``."""
    return material(surface=material_surface(scattering=df.specular_bsdf(
        tint=(0.5, 0.5, 0.5), mode="scatter_reflect")))


def specular_transmission(tint: Color = (1.0, 1.0, 1.0)) -> material:
    """Section 3.6.2: ``ior: color(1.3)``, ``df::specular_bsdf(tint, scatter_transmit)``."""
    return material(ior=(1.3, 1.3, 1.3), surface=material_surface(scattering=df.specular_bsdf(
        tint=color(tint, "tint"), mode="scatter_transmit")))


def specular_reflection_transmission() -> material:
    """Listing 3.6: ``ior: color(1.3)``, ``df::specular_bsdf(tint: color(0.6, 0.7, 0.8),
    mode: df::scatter_reflect_transmit)``."""
    return material(ior=(1.3, 1.3, 1.3), surface=material_surface(scattering=df.specular_bsdf(
        tint=(0.6, 0.7, 0.8), mode="scatter_reflect_transmit")))


def glossy_reflection() -> material:
    """Listing 3.8: ``df::simple_glossy_bsdf(tint: color(0.6), roughness_u: 0.3,
    mode: df::scatter_reflect)``."""
    return material(surface=material_surface(scattering=df.simple_glossy_bsdf(
        tint=(0.6, 0.6, 0.6), roughness_u=0.3, mode="scatter_reflect")))


def glossy_transmission() -> material:
    """Listing 3.9: ``ior: color(1.3)``; ``df::simple_glossy_bsdf(tint: color(1),
    roughness_u: 0.15, mode: df::scatter_transmit)`` (dark where light is totally
    internally reflected: there is no reflection lobe)."""
    return material(ior=(1.3, 1.3, 1.3), surface=material_surface(scattering=df.simple_glossy_bsdf(
        tint=(1.0, 1.0, 1.0), roughness_u=0.15, mode="scatter_transmit")))


def glossy_reflection_transmission() -> material:
    """Listing 3.10: as :func:`glossy_transmission` with ``mode: df::scatter_reflect_transmit``."""
    return material(ior=(1.3, 1.3, 1.3), surface=material_surface(scattering=df.simple_glossy_bsdf(
        tint=(1.0, 1.0, 1.0), roughness_u=0.15, mode="scatter_reflect_transmit")))
