"""Chapter 8 of the Handbook, "Fabric": anisotropic warp, three-lobed weft, iridescent silk.

Listings 8.1-8.6.  The warp is one anisotropic glossy lobe; the weft is three, two of
them on normals bent along ``state::texture_tangent_u(0)`` (Listing 8.2); a custom curve
joins them (a black layer over them adds self-shadowing), and another joins the result
with diffuse transmission (``translucency``, Listing 8.5 = Listing 7.5).

Reading notes:

* Listing 8.2 writes ``state:normal()`` and ``state::texture_tangent_u()``; Listing
  8.3, which uses it, has ``state::normal()`` and ``state::texture_tangent_u(0)``.
* Listing 8.4 names the weight of the weft layer ``warp_weight``: ``weighted_layer(
  weight: warp_weight, layer: weft, base: warp)`` gives the weft ``1 - 1/warp_to_weft``
  (2/3 by default) and the warp the rest.  Followed as printed.
* The constants ``magenta`` and ``green`` (section 8.6) are :data:`MAGENTA` and
  :data:`GREEN`; chapter 6's ``green`` is another colour.
"""

from __future__ import annotations

import numpy as np

from render.library.functions import FUNCTIONS
from render.material import (
    Color,
    Float,
    UniformFloat,
    Varying,
    df,
    material,
    material_surface,
)
from render.materials._common import color
from render.materials.chapter7 import _one_minus, translucency
from render.numerics import unitize

__all__ = [
    "MAGENTA",
    "GREEN",
    "bent_normal",
    "anisotropic_glossy",
    "anisotropic_glossy_three_lobes",
    "warp_and_weft",
    "iridescent_silk",
]

#: Section 8.6's ``const color magenta = color(.3, .22, .3)``.
MAGENTA = (0.3, 0.22, 0.3)
#: Section 8.6's ``const color green = color(.20, .3, .2)``.
GREEN = (0.2, 0.3, 0.2)


def bent_normal(bend_factor: float) -> Varying:
    """Listing 8.2: ``math::normalize(state::normal() + state::texture_tangent_u(0) *
    bend_factor)``.

    Where the sum has no length (a tangent equal to ``-normal / bend_factor``), the
    unbent normal is returned.

    Parameters
    ----------
    bend_factor : float
        Positive bends toward +u ("right"), negative toward -u ("left").

    Returns
    -------
    Varying
        ``state -> (n, 3)`` unit vectors.

    Examples
    --------
    >>> from displacement.surfaces import UnitSquare
    >>> s = UnitSquare().state_at_uv(np.array([[0.5, 0.5]]))
    >>> np.round(bent_normal(1.0)(s), 6).tolist()       # (1, 0, 1) / sqrt(2)
    [[0.707107, 0.0, 0.707107]]
    """
    bend = float(bend_factor)
    if not np.isfinite(bend):
        raise ValueError(f"bend_factor must be finite, got {bend_factor!r}")

    def function(state):
        n, ok = unitize(state.normal + state.tangent_u * bend)
        return np.where(ok[:, None], n, state.normal)

    return Varying(function, "math::normalize(state::normal() + state::texture_tangent_u(0) * b)",
                   {"bend_factor": bend})


def anisotropic_glossy(tint: Color = (0.7, 0.7, 0.7), roughness_u: Float = 1.0,
                       roughness_v: Float = 0.15) -> material:
    """Listing 8.1: ``df::simple_glossy_bsdf(tint, roughness_u, roughness_v,
    mode: df::scatter_reflect)``: a highlight stretched along one texture direction.

    Examples
    --------
    >>> anisotropic_glossy(tint=(0.3, 0.22, 0.3), roughness_v=0.3).surface.scattering.kwargs[
    ...     "roughness_v"]
    0.3
    """
    return material(surface=material_surface(scattering=df.simple_glossy_bsdf(
        tint=color(tint, "tint"), roughness_u=roughness_u, roughness_v=roughness_v,
        mode="scatter_reflect")))


def anisotropic_glossy_three_lobes(tint: Color = (0.7, 0.7, 0.7), roughness: Float = 0.1,
                                   bend_factor: UniformFloat = 1.5) -> material:
    """Listing 8.3: three ``weighted_layer`` s of one anisotropic glossy bsdf
    (``anisotropic_glossy(tint, roughness_v: 1, roughness_u: roughness)``) on the
    unmodified normal (weight 0.5), the right-bent normal (0.5) and the left-bent normal
    (1.0, over ``bsdf()``): the weft's three highlights."""
    bend = float(bend_factor)
    left_normal = bent_normal(-bend)
    right_normal = bent_normal(bend)
    glossy_component = anisotropic_glossy(tint=tint, roughness_v=1.0,
                                          roughness_u=roughness).surface.scattering
    return material(surface=material_surface(scattering=df.weighted_layer(
        weight=0.5, normal=FUNCTIONS["state::normal"](), layer=glossy_component,
        base=df.weighted_layer(
            weight=0.5, normal=right_normal, layer=glossy_component,
            base=df.weighted_layer(weight=1.0, normal=left_normal, layer=glossy_component)))))


def _warp_weight(warp_to_weft: float) -> float:
    """Listing 8.4: ``warp_to_weft > 1 ? 1.0 - 1.0 / warp_to_weft : warp_to_weft``."""
    w = float(warp_to_weft)
    if not np.isfinite(w):
        raise ValueError(f"warp_to_weft must be finite, got {warp_to_weft!r}")
    return 1.0 - 1.0 / w if w > 1.0 else w


def warp_and_weft(warp_color: Color = MAGENTA, warp_roughness: Float = 0.3,
                  weft_color: Color = GREEN, weft_roughness: Float = 0.15,
                  weft_bend_factor: UniformFloat = 1.5, warp_to_weft: UniformFloat = 3.0,
                  shadowing: Float = 0.0) -> material:
    """Listing 8.4: ``df::custom_curve_layer(weight: shadowing, normal_reflectivity: 0.05,
    grazing_reflectivity: 1.0, exponent: 3, base: df::weighted_layer(weight: warp_weight,
    layer: weft, base: warp))`` with the default black layer (self-shadowing).

    Examples
    --------
    >>> top = warp_and_weft().surface.scattering
    >>> top.name, "layer" in top.kwargs, round(top.kwargs["base"].kwargs["weight"], 6)
    ('custom_curve_layer', False, 0.666667)
    """
    warp = anisotropic_glossy(tint=warp_color, roughness_u=1.0,
                              roughness_v=warp_roughness).surface.scattering
    weft = anisotropic_glossy_three_lobes(tint=weft_color, roughness=weft_roughness,
                                          bend_factor=weft_bend_factor).surface.scattering
    return material(surface=material_surface(scattering=df.custom_curve_layer(
        weight=shadowing, normal_reflectivity=0.05, grazing_reflectivity=1.0, exponent=3.0,
        base=df.weighted_layer(weight=_warp_weight(warp_to_weft), layer=weft, base=warp))))


def iridescent_silk(warp_color: Color = MAGENTA, warp_roughness: Float = 0.3,
                    weft_color: Color = GREEN, weft_roughness: Float = 0.15,
                    weft_bend_factor: UniformFloat = 1.5, warp_to_weft: UniformFloat = 3.0,
                    transmission_weight: Float = 0.2,
                    transmission_color: Color = (0.95, 1.0, 0.95),
                    transmission_exponent: Float = 3.0, shadowing: Float = 0.0) -> material:
    """Listing 8.6: thin-walled ``df::custom_curve_layer(weight: 1.0, normal_reflectivity:
    1.0 - transmission_weight, grazing_reflectivity: 1.0, exponent:
    transmission_exponent, layer: <warp_and_weft>, base: <translucency>)``."""
    glossy = warp_and_weft(warp_color=warp_color, warp_roughness=warp_roughness,
                           weft_color=weft_color, weft_roughness=weft_roughness,
                           weft_bend_factor=weft_bend_factor, warp_to_weft=warp_to_weft,
                           shadowing=shadowing).surface.scattering
    translucent = translucency(transmission_color=transmission_color).surface.scattering
    return material(thin_walled=True, surface=material_surface(scattering=df.custom_curve_layer(
        weight=1.0, normal_reflectivity=_one_minus(transmission_weight, "transmission_weight"),
        grazing_reflectivity=1.0, exponent=transmission_exponent,
        layer=glossy, base=translucent)))
