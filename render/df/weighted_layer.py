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

import numpy as np

from render._typing import ArrayLike, Vec3
from render.bsdf import lane_color, lane_float, lanes
from render.df._layer import LayerBsdf
from render.df._signature import Param, Signature
from render.jit import njit
from render.numerics import saturate

__all__ = ["WeightedLayer", "weighted_layer", "ColorWeightedLayer", "color_weighted_layer",
           "SIGNATURE", "COLOR_SIGNATURE", "layer_factors", "layer_estimates",
           "layer_possible", "curve_h", "curve_nk", "curve_constant", "curve_is_one"]


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


class WeightedLayer(LayerBsdf):
    """``df::weighted_layer`` over lanes.

    Parameters
    ----------
    weight : float or (n,)
        Saturated to [0, 1].
    layer, base : Bsdf or None
        None is MDL's black ``bsdf()``.
    normal : (3,) or (n, 3)
        The layer's normal in the inherited local frame (default: the inherited one).
    tangent_u : (3,) or (n, 3)
        ``state::texture_tangent_u(0)`` in the inherited local frame (orients the frame
        of a tilted ``normal``).

    Examples
    --------
    >>> from render.df import diffuse_reflection_bsdf
    >>> wl = weighted_layer(weight=0.25, layer=diffuse_reflection_bsdf(tint=1.0),
    ...                     base=diffuse_reflection_bsdf(tint=0.0))
    >>> wo = np.array([[0.0, 0.0, 1.0]])
    >>> np.round(wl.eval(wo, wo) * np.pi, 12).tolist(), np.round(wl.albedo(wo), 12).tolist()
    ([[0.25, 0.25, 0.25]], [[0.25, 0.25, 0.25]])
    """

    _directional = False

    def __init__(self, weight: ArrayLike = 1.0, layer=None, base=None,
                 normal: ArrayLike = (0.0, 0.0, 1.0), tangent_u: ArrayLike = (1.0, 0.0, 0.0)):
        super().__init__(layer, base, normal, tangent_u)
        w = saturate(self._weight_param(weight))
        self.weight = w

    @staticmethod
    def _weight_param(weight):
        w = lane_float(weight, "weight")
        return w[..., None] * np.ones(3) if w.ndim else np.full((1, 3), float(w))

    def __repr__(self) -> str:
        return (f"{type(self).__name__}(weight={self.weight.tolist()}, layer={self.layer!r}, "
                f"base={self.base!r})")

    def _w(self, n: int) -> np.ndarray:
        return np.broadcast_to(lanes(self.weight, n, "weight"), (n, 3))

    def _factors(self, wo: Vec3, wi: Vec3, wo_l: Vec3, wi_l: Vec3):
        w = self._w(len(wo))
        return w, 1.0 - w

    def _estimates(self, wo: Vec3, wo_l: Vec3):
        return self._factors(wo, wo, wo_l, wo_l)

    def _possible(self, n: int):
        w = self._w(n)
        pos_l = np.full(n, self.layer is not None) & np.any(w > 0.0, axis=1)
        pos_b = np.full(n, self.base is not None) & np.any(w < 1.0, axis=1)
        return pos_l, pos_b


class ColorWeightedLayer(WeightedLayer):
    """``df::color_weighted_layer`` over lanes: ``weight`` is a colour, per channel.

    Examples
    --------
    >>> from render.df import diffuse_reflection_bsdf
    >>> cl = color_weighted_layer(weight=(1.0, 0.5, 0.0), layer=diffuse_reflection_bsdf(),
    ...                           base=diffuse_reflection_bsdf(tint=(0.0, 0.0, 0.5)))
    >>> np.round(cl.albedo(np.array([[0.0, 0.0, 1.0]])), 12).tolist()
    [[1.0, 0.5, 0.5]]
    """

    @staticmethod
    def _weight_param(weight):
        return lane_color(weight, "weight")


weighted_layer = WeightedLayer
color_weighted_layer = ColorWeightedLayer
