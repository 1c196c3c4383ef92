"""MDL ``df::weighted_layer`` and ``df::color_weighted_layer``: a layer over a base by a weight.

MDL signatures::

    bsdf weighted_layer(float weight = 1.0, bsdf layer = bsdf(), bsdf base = bsdf(),
                        float3 normal = state::normal());
    bsdf color_weighted_layer(color weight = color(1.0), bsdf layer = bsdf(),
                              bsdf base = bsdf(), float3 normal = state::normal());   // 1.4

Model (libbsdf, ``reference/mdl-distribution-functions.md`` §3.1).  With
``w = saturate(weight)`` (per channel for the colour variant)::

    eval = w layer.eval(wo_L, wi_L) + (1 - w) base.eval(wo, wi)

No directional dependence, no albedo: a white layer over a white base is lossless
at every weight.  The layer is evaluated in the frame of ``normal`` (``wo_L``,
``wi_L``), the base in the inherited frame (:mod:`render.df._layer`).  Sampling picks
the layer with probability ``P`` from the expected contributions ``w albedo_L`` and
``(1 - w) albedo_B`` (a defensive mixture; libbsdf uses ``P = w``, or ``average(w)``),
and returns the combined density ``P pdf_L + (1 - P) pdf_B``.

Departure from libbsdf: its ``color_weighted_layer_evaluate`` adds ``(1 - p) * pdf``
(the running sum) where the base's pdf is meant; here the pdf is the mixture density
the sampler really draws from.
"""

from __future__ import annotations

from render.df._registry import Df, Node
from render.df._signature import Param, Signature
from render.jit import njit

__all__ = [
    "WeightedLayer",
    "weighted_layer",
    "ColorWeightedLayer",
    "color_weighted_layer",
    "SIGNATURE",
    "COLOR_SIGNATURE",
    "layer_factors",
    "layer_estimates",
    "layer_possible",
    "curve_h",
    "curve_nk",
    "curve_constant",
    "curve_is_one",
]


# --- signature and kernels (the compiled render core) ---------------------------------
# The per-node factors of the layer (the interpreter, render.program, walks the tree,
# maps directions into the layer frame, applies the frame-agreement mask and sums).
# One set of kernels serves both forms: the float weight is packed as a grey colour.


def _layer_params(weight: Param) -> tuple:
    return (weight, Param("layer", "bsdf", None), Param("base", "bsdf", None),
            Param("normal", "float3", "state::normal()"))


#: ``df::weighted_layer`` (``layer``/``base`` None: MDL's ``bsdf()``)
SIGNATURE = Signature("bsdf", _layer_params(
    Param("weight", "float", 1.0, clamp=(0.0, 1.0), packed="color")))
#: ``df::color_weighted_layer`` (MDL 1.4)
COLOR_SIGNATURE = Signature("bsdf", _layer_params(
    Param("weight", "color", (1.0, 1.0, 1.0), clamp=(0.0, 1.0))))
_WEIGHT = COLOR_SIGNATURE.offset("weight")


@njit
def layer_factors(P, row, b, flags, wox, woy, woz, wix, wiy, wiz,
                  wolx, woly, wolz, wilx, wily, wilz, co0, co1, co2, ci0, ci1, ci2):
    """``(f_layer, f_base)`` per channel: ``w`` and ``1 - w`` (no directional dependence;
    the curve-albedo arguments ``co``, ``ci`` are not used)."""
    w0, w1, w2 = P[row, b + _WEIGHT], P[row, b + _WEIGHT + 1], P[row, b + _WEIGHT + 2]
    return w0, w1, w2, 1.0 - w0, 1.0 - w1, 1.0 - w2


@njit
def layer_estimates(P, row, b, flags, wox, woy, woz, wolx, woly, wolz, co0, co1, co2):
    """The factors' expected values at ``wo`` (for selection): the factors themselves."""
    w0, w1, w2 = P[row, b + _WEIGHT], P[row, b + _WEIGHT + 1], P[row, b + _WEIGHT + 2]
    return w0, w1, w2, 1.0 - w0, 1.0 - w1, 1.0 - w2


@njit
def layer_possible(P, row, b, flags):
    """``(layer, base)`` can contribute: a positive weight, a weight below 1 (some channel).
    The interpreter ANDs in whether each child exists and the frames agree."""
    w0, w1, w2 = P[row, b + _WEIGHT], P[row, b + _WEIGHT + 1], P[row, b + _WEIGHT + 2]
    return (w0 > 0.0 or w1 > 0.0 or w2 > 0.0), (w0 < 1.0 or w1 < 1.0 or w2 < 1.0)


@njit
def curve_h(P, row, b, flags, vx, vy, vz, xx, xy, xz):
    """The curve at the half vector: ``C = 1`` (the weighted layer's curve is constant)."""
    return 1.0, 1.0, 1.0


@njit
def curve_nk(P, row, b, flags, vx, vy, vz):
    """The curve at ``|v.z|``: 1."""
    return 1.0, 1.0, 1.0


@njit
def curve_constant(P, row, b, flags):
    """``C`` takes one value at every cosine (so ``Ĉ`` is never needed): always."""
    return True


@njit
def curve_is_one(P, row, b, flags):
    """``C == 1`` at every cosine: always."""
    return True


# --- the Python classes ----------------------------------------------------------------

NODE = Node("weighted_layer", "bsdf", "layer", COLOR_SIGNATURE, directional=False, passes_film=True,
            layer_factors=layer_factors, layer_estimates=layer_estimates,
            layer_possible=layer_possible, curve_constant=curve_constant)
DF = Df("weighted_layer", SIGNATURE, (NODE,))
COLOR_DF = Df("color_weighted_layer", COLOR_SIGNATURE, (NODE,))
WeightedLayer = DF.cls
weighted_layer = WeightedLayer
ColorWeightedLayer = COLOR_DF.cls
color_weighted_layer = ColorWeightedLayer
