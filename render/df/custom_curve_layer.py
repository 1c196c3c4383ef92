"""MDL ``df::custom_curve_layer`` and its colour variant: a layer weighted by a Schlick curve.

MDL signatures::

    bsdf custom_curve_layer(float normal_reflectivity, float grazing_reflectivity = 1.0,
                            float exponent = 5.0, float weight = 1.0, bsdf layer = bsdf(),
                            bsdf base = bsdf(), float3 normal = state::normal());
    bsdf color_custom_curve_layer(color normal_reflectivity,
                                  color grazing_reflectivity = color(1.0),
                                  color f82_factor = color(1.0),              // 1.10
                                  float exponent = 5.0, color weight = color(1.0),
                                  bsdf layer = bsdf(), bsdf base = bsdf(),
                                  float3 normal = state::normal());            // 1.4

Model (libbsdf, ``reference/mdl-distribution-functions.md`` §3.2): the directional
layering of :class:`render.df._layer.CurveLayer` with the curve::

    C(c) = R0 + (R90 - R0) (1 - saturate(c))^p,
    R0 = saturate(normal_reflectivity), R90 = saturate(grazing_reflectivity), p = max(exponent, 0)

and, for the colour variant, Hoffman's F82 tint
``C = saturate(C - a c (1 - c)^6)``, ``a = (R0 + (R90 - R0)(6/7)^p) 7^7/6^6 (1 - saturate(f82))``
and ``saturate(weight)`` folded into ``C`` per channel::

    eval = w C(|wo.h|) layer.eval(wo_L, wi_L) + (1 - w max(C(nk1), C(nk2))) base.eval(wo, wi)

Transmitted ``wi`` use the half vector of ``wi`` mirrored through the layer's tangent
plane (no refraction half vector: libbsdf uses it only for the Fresnel layers).

Energy: the node never gains energy (the bound and how ``Ĉ`` is computed:
:mod:`render.df._layer`).  libbsdf's rule alone does, by up to 6.5 %: with a rough coat
over a mirror or narrow glossy base, ``C(|wo.h|)`` at tilted half vectors exceeds
``C(nk1)`` while the base keeps ``1 - w C(nk1)``, which matters where the curve rises
steeply from normal incidence (``custom_curve_layer(0, 1, 1, glossy r 0.5, mirror)``:
1.0647 at normal incidence).  Here the base keeps ``1 - w max(C(nk1), C(nk2), Ĉ(wo),
Ĉ(wi))`` with ``Ĉ`` the coat's curve-weighted albedo, so that node is at most 1; the
coat's own lobe is libbsdf's.  Over diffuse bases ``C(nk2)`` dominates and libbsdf's
factors are kept almost everywhere (measured in
``tests/render/df/test_custom_curve_layer.py``).
"""

from __future__ import annotations

import numpy as np

from render._typing import Arr, ArrayLike, Rgb, Vec3
from render.bsdf import lane_color, lane_float, lanes
from render.df._layer import CurveLayer, f82_curve
from render.numerics import saturate

__all__ = [
    "CustomCurveLayer",
    "custom_curve_layer",
    "ColorCustomCurveLayer",
    "color_custom_curve_layer",
]


class CustomCurveLayer(CurveLayer):
    """``df::custom_curve_layer`` over lanes.

    Parameters
    ----------
    normal_reflectivity, grazing_reflectivity : float or (n,)
        ``R0`` and ``R90``, saturated.
    exponent : float or (n,)
        ``p``; negative values act as 0.
    weight : float or (n,)
        Saturated to [0, 1].
    layer, base : Bsdf or None
        None is MDL's black ``bsdf()``.
    normal, tangent_u : (3,) or (n, 3)
        The layer's normal and ``state::texture_tangent_u(0)`` in the inherited local
        frame (see :class:`render.df._layer.LayerBsdf`).

    Examples
    --------
    >>> from render.df import specular_bsdf
    >>> c = custom_curve_layer(normal_reflectivity=0.2, grazing_reflectivity=1.0, exponent=1.0,
    ...                        layer=specular_bsdf())
    >>> wo = np.array([[0.0, 0.0, 1.0], [0.8, 0.0, 0.6]])
    >>> np.round(c.albedo(wo)[:, 0], 12).tolist()   # 0.2 + 0.8 (1 - cos)
    [0.2, 0.52]
    """

    def __init__(self, normal_reflectivity: ArrayLike, grazing_reflectivity: ArrayLike = 1.0,
                 exponent: ArrayLike = 5.0, weight: ArrayLike = 1.0, layer=None, base=None,
                 normal: ArrayLike = (0.0, 0.0, 1.0), tangent_u: ArrayLike = (1.0, 0.0, 0.0)):
        self._setup(normal_reflectivity, grazing_reflectivity, 1.0, exponent, weight, layer,
                    base, normal, tangent_u)

    def _setup(self, normal_reflectivity, grazing_reflectivity, f82_factor, exponent, weight,
               layer, base, normal, tangent_u) -> None:
        super().__init__(self._scalar_or_color(weight, "weight"), layer, base, normal, tangent_u)
        self.normal_reflectivity = saturate(
            self._scalar_or_color(normal_reflectivity, "normal_reflectivity"))
        self.grazing_reflectivity = saturate(
            self._scalar_or_color(grazing_reflectivity, "grazing_reflectivity"))
        self.f82_factor = saturate(self._scalar_or_color(f82_factor, "f82_factor"))
        self.exponent = np.maximum(lane_float(exponent, "exponent"), 0.0)

    @staticmethod
    def _scalar_or_color(x, name):
        a = lane_float(x, name)
        return a[:, None] * np.ones(3) if a.ndim else float(a)

    def __repr__(self) -> str:
        return (f"{type(self).__name__}(normal_reflectivity={self.normal_reflectivity.tolist()}, "
                f"grazing_reflectivity={self.grazing_reflectivity.tolist()}, "
                f"exponent={self.exponent.tolist()}, weight={self.weight.tolist()}, "
                f"layer={self.layer!r}, base={self.base!r})")

    def _params(self, n: int):
        r0 = np.broadcast_to(lanes(self.normal_reflectivity, n, "normal_reflectivity"), (n, 3))
        r90 = np.broadcast_to(lanes(self.grazing_reflectivity, n, "grazing_reflectivity"), (n, 3))
        f82 = np.broadcast_to(lanes(self.f82_factor, n, "f82_factor"), (n, 3))
        p = np.broadcast_to(lanes(self.exponent, n, "exponent"), (n,))
        return r0, r90, f82, p

    def _context(self, wo: Vec3):
        return self._params(len(wo))

    def _curve(self, c: Arr, ctx) -> Rgb:
        r0, r90, f82, p = ctx
        return f82_curve(c, r0, r90, f82, p)

    def _curve_max(self, n: int) -> Rgb:
        r0, r90, _, _ = self._params(n)
        return np.maximum(r0, r90)

    def _curve_params(self) -> tuple:
        return (self.normal_reflectivity, self.grazing_reflectivity, self.f82_factor,
                self.exponent)

    def _curve_constant(self) -> bool:
        r0, r90, f82 = self.normal_reflectivity, self.grazing_reflectivity, self.f82_factor
        p = np.reshape(self.exponent, (-1, 1))
        return bool(np.all((f82 == 1.0) & ((r0 == r90) | (p == 0.0))))

    def _curve_is_one(self, n: int) -> np.ndarray:
        r0, r90, f82, _ = self._params(n)
        return np.all((r0 == 1.0) & (r90 == 1.0) & (f82 == 1.0), axis=1)


class ColorCustomCurveLayer(CustomCurveLayer):
    """``df::color_custom_curve_layer``: colour reflectivities, F82 tint, colour weight.

    Examples
    --------
    >>> from render.df import specular_bsdf
    >>> c = color_custom_curve_layer(normal_reflectivity=(0.1, 0.2, 0.3), weight=(1.0, 1.0, 0.5),
    ...                              layer=specular_bsdf())
    >>> np.round(c.albedo(np.array([[0.0, 0.0, 1.0]])), 12).tolist()
    [[0.1, 0.2, 0.15]]
    """

    def __init__(self, normal_reflectivity: ArrayLike, grazing_reflectivity: ArrayLike = 1.0,
                 f82_factor: ArrayLike = 1.0, exponent: ArrayLike = 5.0, weight: ArrayLike = 1.0,
                 layer=None, base=None, normal: ArrayLike = (0.0, 0.0, 1.0),
                 tangent_u: ArrayLike = (1.0, 0.0, 0.0)):
        self._setup(normal_reflectivity, grazing_reflectivity, f82_factor, exponent, weight,
                    layer, base, normal, tangent_u)

    @staticmethod
    def _scalar_or_color(x, name):
        return lane_color(x, name)


custom_curve_layer = CustomCurveLayer
color_custom_curve_layer = ColorCustomCurveLayer
