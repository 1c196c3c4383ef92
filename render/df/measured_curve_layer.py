"""MDL ``df::measured_curve_layer`` and its colour form: a layer weighted by a measured curve.

MDL signatures::

    bsdf measured_curve_layer(color[<N>] curve_values, float weight = 1.0,
                              bsdf layer = bsdf(), bsdf base = bsdf(),
                              float3 normal = state::normal());                  // 1.1
    bsdf color_measured_curve_layer(color[<N>] curve_values, color weight = color(1.0),
                                    bsdf layer = bsdf(), bsdf base = bsdf(),
                                    float3 normal = state::normal());            // 1.4

Model (libbsdf, ``reference/mdl-distribution-functions.md`` §3.2): the directional
layering of :mod:`render.df._layer` with the curve ``C(c)`` read from ``curve_values``:
``N`` colours equally spaced in angle over ``[0, pi/2]`` (``curve_values[0]`` at normal
incidence), linear in the angle ``acos(c)`` between them, saturated::

    eval = w C(|wo.h|) layer.eval(wo_L, wi_L) + (1 - w max(C(nk1), C(nk2), Ĉ(wo), Ĉ(wi))) base.eval

with ``w = saturate(weight)`` folded into ``C`` per channel (the colour form), the
reflection half vector (a transmitted ``wi`` mirrored; libbsdf uses the refraction half
vector only for the Fresnel layers) and the curve-weighted albedo ``Ĉ`` that keeps the
node from gaining energy (the bound: :mod:`render.df._layer`).

The curve is uniform: one array for every lane, packed after the node's slots
(:data:`render.df._signature.ARRAYS`).
"""

from __future__ import annotations

from render.df import _curve_layer
from render.df._layer import curve_geometry, measured_curve3, measured_curve_constant
from render.df._registry import Df, Node
from render.df._signature import REQUIRED, Param, Signature
from render.jit import njit

__all__ = [
    "MeasuredCurveLayer",
    "measured_curve_layer",
    "ColorMeasuredCurveLayer",
    "color_measured_curve_layer",
    "SIGNATURE",
    "COLOR_SIGNATURE",
    "layer_factors",
    "layer_estimates",
    "layer_possible",
    "curve_h",
    "curve_nk",
    "curve_constant",
]


# --- signature and kernels (the compiled render core) ---------------------------------
def _params(weight: Param) -> tuple:
    return (Param("curve_values", "color[]", REQUIRED, uniform=True), weight,
            Param("layer", "bsdf", None), Param("base", "bsdf", None),
            Param("normal", "float3", "state::normal()"))


#: ``df::measured_curve_layer`` (the float weight packed as a grey colour)
SIGNATURE = Signature("bsdf", _params(
    Param("weight", "float", 1.0, clamp=(0.0, 1.0), packed="color")))
#: ``df::color_measured_curve_layer`` (MDL 1.4)
COLOR_SIGNATURE = Signature("bsdf", _params(
    Param("weight", "color", (1.0, 1.0, 1.0), clamp=(0.0, 1.0))))
_N = COLOR_SIGNATURE.offset("curve_values")
_WEIGHT = COLOR_SIGNATURE.offset("weight")
_AT = COLOR_SIGNATURE.width  # the curve's colours follow the node's slots


@njit
def _curve3(P, row, b, flags, woz, c):
    """``C(c)`` per channel (the same on either side)."""
    return measured_curve3(P, row, b + _AT, int(P[row, b + _N]), c)


@njit
def _geometry(P, row, b, flags, woz, wiz, ox, oy, oz, ix, iy, iz):
    """The curve's cosines (transmitted ``wi`` mirrored, no refraction half vector)."""
    return curve_geometry(False, flags, 1.0, 1.0, woz, wiz, ox, oy, oz, ix, iy, iz)


layer_factors, layer_estimates, curve_h, curve_nk = _curve_layer.kernels(__name__)


@njit
def layer_possible(P, row, b, flags):
    """``(layer, base)`` can contribute: some channel of ``w`` and of the curve
    positive; not ``w == 1`` with the curve 1 everywhere."""
    n = int(P[row, b + _N])
    at = b + _AT
    pos_l = False
    one = True
    for k in range(3):
        w = P[row, b + _WEIGHT + k]
        for j in range(n):
            v = min(max(P[row, at + 3 * j + k], 0.0), 1.0)
            pos_l = pos_l or w * v > 0.0
            one = one and v == 1.0 and w == 1.0
    return pos_l, not one


@njit
def curve_constant(P, row, b, flags):
    """The curve takes one value at every cosine (every colour equal)."""
    return measured_curve_constant(P, row, b + _AT, int(P[row, b + _N]))


# --- the Python classes ----------------------------------------------------------------

NODE = Node("measured_curve_layer", "bsdf", "layer", COLOR_SIGNATURE, passes_film=True,
            layer_factors=layer_factors, layer_estimates=layer_estimates,
            layer_possible=layer_possible, curve_h=curve_h, curve_nk=curve_nk,
            curve_constant=curve_constant)
DF = Df("measured_curve_layer", SIGNATURE, (NODE,))
COLOR_DF = Df("color_measured_curve_layer", COLOR_SIGNATURE, (NODE,))
MeasuredCurveLayer = DF.cls
measured_curve_layer = MeasuredCurveLayer
ColorMeasuredCurveLayer = COLOR_DF.cls
color_measured_curve_layer = ColorMeasuredCurveLayer
