"""Chapter 7 of the Handbook, "Plastic": from a Phong-like mix to a translucent dielectric.

Listings 7.1-7.6: a normalized mix of diffuse and glossy (``phonglike_plastic``), the
same as a weighted layer, a Fresnel layer (``dielectric_plastic``), two glossy lobes
under the Fresnel layer, and diffuse transmission joined by a custom curve.

Reading notes:

* Listing 7.3 passes ``ior: color(ior)`` to ``df::fresnel_layer`` (a float since MDL
  1.4): the material's ``float ior`` is passed as that float.
* Section 7.7 calls the two-lobe material ``dielectric_plastic_two_lobes`` in its text;
  the listing's name is ``dielectric_plastic_two_lobe``.
* ``translucency`` (Listing 7.5) is also chapter 8's Listing 8.5.
"""

from __future__ import annotations

import numpy as np

from render.material import (
    Color,
    Float,
    Varying,
    df,
    evaluate,
    material,
    material_surface,
)
from render.materials._common import color
from render.materials.chapter6 import fresnel_layer_of, mix_of

__all__ = [
    "phonglike_plastic",
    "phonglike_plastic_layered",
    "dielectric_plastic",
    "dielectric_plastic_two_lobe",
    "translucency",
    "translucent_plastic",
]


def _one_minus(value, name: str):
    """``1.0 - value`` for a float argument (constant or varying)."""
    if callable(value):
        return Varying(lambda s: 1.0 - evaluate(value, s, "float", name), "1.0 - x",
                       {name: value})
    return 1.0 - float(value)


def _float_ior(ior) -> float:
    ior = float(ior)
    if not (np.isfinite(ior) and ior > 0.0):
        raise ValueError(f"ior must be finite and > 0 (an index of refraction), got {ior!r}")
    return ior


def phonglike_plastic(diffuse_color: Color = (0.7, 0.7, 0.7), diffuse_intensity: Float = 0.8,
                      highlight_color: Color = (1.0, 1.0, 1.0), highlight_intensity: Float = 0.2,
                      highlight_roughness: Float = 0.2) -> material:
    """Listing 7.1: ``df::normalized_mix`` of ``diffuse_reflection_bsdf(diffuse_color)``
    weighted ``diffuse_intensity`` and ``simple_glossy_bsdf(highlight_color,
    roughness_u: highlight_roughness)`` weighted ``highlight_intensity`` (weights summing
    above 1 are scaled down to sum to 1)."""
    return material(surface=material_surface(scattering=mix_of("normalized_mix", [
        (diffuse_intensity, df.diffuse_reflection_bsdf(tint=color(diffuse_color,
                                                                  "diffuse_color"))),
        (highlight_intensity, df.simple_glossy_bsdf(tint=color(highlight_color, "highlight_color"),
                                                    roughness_u=highlight_roughness)),
    ])))


def phonglike_plastic_layered(diffuse_color: Color = (0.7, 0.7, 0.7),
                              highlight_color: Color = (1.0, 1.0, 1.0),
                              highlight_intensity: Float = 0.2,
                              highlight_roughness: Float = 0.2) -> material:
    """Listing 7.2: ``df::weighted_layer(weight: highlight_intensity, base:
    diffuse_reflection_bsdf(diffuse_color), layer: simple_glossy_bsdf(highlight_color,
    roughness_u: highlight_roughness))``."""
    return material(surface=material_surface(scattering=df.weighted_layer(
        weight=highlight_intensity,
        base=df.diffuse_reflection_bsdf(tint=color(diffuse_color, "diffuse_color")),
        layer=df.simple_glossy_bsdf(tint=color(highlight_color, "highlight_color"),
                                    roughness_u=highlight_roughness))))


def dielectric_plastic(diffuse_color: Color = (0.5, 0.04, 0.04),
                       glossy_color: Color = (1.0, 1.0, 1.0), glossy_weight: Float = 1.0,
                       glossy_roughness: Float = 0.05, ior: Float = 1.54) -> material:
    """Listing 7.3: ``df::fresnel_layer(ior: color(ior), weight: glossy_weight, layer:
    simple_glossy_bsdf(glossy_color, roughness_u: glossy_roughness), base:
    diffuse_reflection_bsdf(diffuse_color))``.

    Examples
    --------
    >>> node = dielectric_plastic(ior=1.35).surface.scattering
    >>> node.name, node.kwargs["ior"], node.kwargs["layer"].kwargs["roughness_u"]
    ('fresnel_layer', 1.35, 0.05)
    """
    return material(surface=material_surface(scattering=fresnel_layer_of(
        _float_ior(ior), weight=glossy_weight,
        layer=df.simple_glossy_bsdf(tint=color(glossy_color, "glossy_color"),
                                    roughness_u=glossy_roughness),
        base=df.diffuse_reflection_bsdf(tint=color(diffuse_color, "diffuse_color")))))


def dielectric_plastic_two_lobe(diffuse_color: Color = (0.5, 0.04, 0.04),
                                glossy_color: Color = (1.0, 1.0, 1.0),
                                glossy_roughness_1: Float = 0.05, glossy_weight_1: Float = 0.5,
                                glossy_roughness_2: Float = 0.25, glossy_weight_2: Float = 0.5,
                                glossy_weight: Float = 1.0, ior: Float = 1.54) -> material:
    """Listing 7.4: Listing 7.3 whose layer is a ``df::normalized_mix`` of two glossy lobes
    (``glossy_roughness_i`` weighted ``glossy_weight_i``, both ``glossy_color``)."""
    glossy_color = color(glossy_color, "glossy_color")
    lobes = mix_of("normalized_mix", [
        (glossy_weight_1, df.simple_glossy_bsdf(tint=glossy_color, roughness_u=glossy_roughness_1)),
        (glossy_weight_2, df.simple_glossy_bsdf(tint=glossy_color, roughness_u=glossy_roughness_2)),
    ])
    return material(surface=material_surface(scattering=fresnel_layer_of(
        _float_ior(ior), weight=glossy_weight, layer=lobes,
        base=df.diffuse_reflection_bsdf(tint=color(diffuse_color, "diffuse_color")))))


def translucency(transmission_color: Color = (1.0, 1.0, 1.0)) -> material:
    """Listings 7.5 and 8.5: thin-walled ``df::diffuse_transmission_bsdf(tint:
    transmission_color)`` (refraction disabled).

    Examples
    --------
    >>> m = translucency((0.95, 1.0, 0.9))
    >>> m.thin_walled, m.surface.scattering
    (True, df::diffuse_transmission_bsdf(tint: (0.95, 1.0, 0.9)))
    """
    return material(thin_walled=True, surface=material_surface(
        scattering=df.diffuse_transmission_bsdf(tint=color(transmission_color,
                                                           "transmission_color"))))


def translucent_plastic(diffuse_color: Color = (0.5, 0.04, 0.04),
                        glossy_color: Color = (1.0, 1.0, 1.0),
                        glossy_roughness_1: Float = 0.05, glossy_weight_1: Float = 0.5,
                        glossy_roughness_2: Float = 0.25, glossy_weight_2: Float = 0.5,
                        glossy_weight: Float = 1.0, ior: Float = 1.54,
                        transmission_weight: Float = 0.2,
                        transmission_color: Color = (0.9, 0.9, 0.9),
                        transmission_exponent: Float = 3.0) -> material:
    """Listing 7.6: thin-walled ``df::custom_curve_layer(weight: 1.0, normal_reflectivity:
    1.0 - transmission_weight, grazing_reflectivity: 1.0, exponent:
    transmission_exponent, layer: <dielectric_plastic_two_lobe>, base: <translucency>)``.

    Facing the viewer ``transmission_weight`` of the light goes to the translucent base;
    at grazing angles the opaque plastic takes all of it.
    """
    opaque = dielectric_plastic_two_lobe(
        diffuse_color=diffuse_color, glossy_color=glossy_color,
        glossy_roughness_1=glossy_roughness_1, glossy_weight_1=glossy_weight_1,
        glossy_roughness_2=glossy_roughness_2, glossy_weight_2=glossy_weight_2,
        glossy_weight=glossy_weight, ior=ior).surface.scattering
    translucent = translucency(transmission_color=transmission_color).surface.scattering
    return material(thin_walled=True, surface=material_surface(scattering=df.custom_curve_layer(
        weight=1.0, normal_reflectivity=_one_minus(transmission_weight, "transmission_weight"),
        grazing_reflectivity=1.0, exponent=transmission_exponent,
        layer=opaque, base=translucent)))
