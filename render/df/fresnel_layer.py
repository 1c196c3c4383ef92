"""MDL ``df::fresnel_layer`` and ``df::color_fresnel_layer``: a layer weighted by exact Fresnel.

MDL signatures::

    bsdf fresnel_layer(float ior, float weight = 1.0, bsdf layer = bsdf(),
                       bsdf base = bsdf(), float3 normal = state::normal());
    bsdf color_fresnel_layer(color ior, color weight = color(1.0), bsdf layer = bsdf(),
                             bsdf base = bsdf(), float3 normal = state::normal());   // 1.4

``ior`` was a ``color`` before MDL 1.4 and the Handbook passes ``ior: color(1.6)``
(Listing 6.11, Figure 6.36), so both take a colour (a float means grey) and evaluate
Fresnel **per channel**.

Model (libbsdf, ``reference/mdl-distribution-functions.md`` §3.2): the directional
layering of :class:`render.df._layer.CurveLayer` with the exact unpolarised dielectric
Fresnel curve ``C(c) = F(eta, c)`` (libbsdf's ``ior_fresnel``, not Schlick).  The layer's
``ior`` replaces the material's on the side the ray comes from: with ``(eta1, eta2)``
the renderer's IOR pair on ``wo``'s side and the far side, a ray from outside
(``wo.z >= 0``, or any thin-walled hit) uses ``eta = ior / eta1``, a ray from inside
``eta = eta2 / ior``.  Then::

    eval = w F(|wo.h|) layer.eval(wo_L, wi_L) + (1 - w max(F(nk1), F(nk2r))) base.eval(wo, wi)

with the refraction half vector (material IOR pair) for transmitted ``wi`` on
non-thin-walled surfaces.  ``color_fresnel_layer`` folds ``saturate(weight)`` into
``C`` per channel.  The layer's own lobe carries no Fresnel of its own
(``specular_bsdf(scatter_reflect)``), so the node applies exactly one.

Energy: the node never gains energy (the bound and how ``Ĉ`` is computed:
:mod:`render.df._layer`).  The base's factor is libbsdf's ``1 - w max(F(nk1), F(nk2r))``
lowered, only where needed, to ``1 - w Ĉ`` with ``Ĉ`` the coat's Fresnel-weighted albedo
(libbsdf's rule alone gains 0.2 % with a rough coat over a mirror at 45 degrees).  A
smooth (specular) coat keeps libbsdf's factors exactly and is lossless where the base
is, except for the part of the base's lobe that leaves at grazing angles
(``F(nk2) > F(nk1)``), which is lost.  Measured in ``tests/render/df/test_fresnel_layer.py``.
"""

from __future__ import annotations

import numpy as np

from render._typing import Arr, ArrayLike, Rgb, Vec3
from render.bsdf import lane_color, lanes
from render.df._layer import CurveLayer, FresnelCurve

__all__ = ["FresnelLayer", "fresnel_layer", "ColorFresnelLayer", "color_fresnel_layer"]


class FresnelLayer(CurveLayer):
    """``df::fresnel_layer`` over lanes.

    Parameters
    ----------
    ior : float, (3,) or (n, 3)
        The coat's index of refraction (per channel), > 0.
    weight : float or (n,)
        Saturated to [0, 1].
    layer, base : Bsdf or None
        None is MDL's black ``bsdf()``.
    normal, tangent_u : (3,) or (n, 3)
        The layer's normal and ``state::texture_tangent_u(0)`` in the inherited local
        frame (see :class:`render.df._layer.LayerBsdf`).
    ior_outside, ior_inside : float or (n,)
        The renderer's IORs on the ``+z`` and ``-z`` sides (``material.ior`` averaged).
    thin_walled : bool

    Examples
    --------
    >>> from render.df import specular_bsdf, diffuse_reflection_bsdf
    >>> coat = fresnel_layer(ior=1.5, layer=specular_bsdf(), base=diffuse_reflection_bsdf())
    >>> wo = np.array([[0.0, 0.0, 1.0]])
    >>> s = coat.sample(wo, np.array([0.01]), np.array([[0.5, 0.5]]))   # picks the coat
    >>> # F(1) = 0.04 over P = 0.95 * 0.04 / (0.04 + 0.96) + 0.05 / 2 = 0.063
    >>> [round(float(x), 6) for x in s.weight[0]], round(0.04 / 0.063, 6)
    ([0.634921, 0.634921, 0.634921], 0.634921)
    """

    _refractive = True

    def __init__(self, ior: ArrayLike, weight: ArrayLike = 1.0, layer=None, base=None,
                 normal: ArrayLike = (0.0, 0.0, 1.0), tangent_u: ArrayLike = (1.0, 0.0, 0.0),
                 ior_outside: ArrayLike = 1.0, ior_inside: ArrayLike = 1.0,
                 thin_walled: bool = False):
        super().__init__(self._weight_param(weight), layer, base, normal, tangent_u,
                         ior_outside, ior_inside, thin_walled)
        ior = lane_color(ior, "ior")
        if np.any(ior <= 0.0):
            raise ValueError(f"ior must be > 0 (an index of refraction), got {ior.tolist()}")
        self.ior = ior

    @staticmethod
    def _weight_param(weight):
        from render.bsdf import lane_float

        w = lane_float(weight, "weight")
        return w[:, None] * np.ones(3) if w.ndim else float(w)

    def __repr__(self) -> str:
        return (f"{type(self).__name__}(ior={self.ior.tolist()}, weight={self.weight.tolist()}, "
                f"layer={self.layer!r}, base={self.base!r})")

    def _context(self, wo: Vec3) -> Rgb:
        n = len(wo)
        return FresnelCurve.eta(
            lanes(self.ior, n, "ior"),
            np.broadcast_to(lanes(self.ior_outside, n, "ior_outside"), (n,)),
            np.broadcast_to(lanes(self.ior_inside, n, "ior_inside"), (n,)),
            wo,
            self.thin_walled,
        )

    def _curve(self, c: Arr, eta: Rgb) -> Rgb:
        return FresnelCurve.value(c, eta)

    def _curve_params(self) -> tuple:
        return (self.ior, self.ior_outside, self.ior_inside)

    def _curve_constant(self) -> bool:
        # eta = ior / ior_outside outside, ior_outside / ior inside: F = 0 where they match
        return bool(np.all(self.ior == np.reshape(self.ior_outside, (-1, 1))))


class ColorFresnelLayer(FresnelLayer):
    """``df::color_fresnel_layer``: ``weight`` is a colour, folded into the curve per channel.

    Examples
    --------
    >>> from render.df import specular_bsdf
    >>> c = color_fresnel_layer(ior=(1.5, 1.5, 1.0), weight=(1.0, 0.5, 1.0), layer=specular_bsdf())
    >>> np.round(c.albedo(np.array([[0.0, 0.0, 1.0]])), 6).tolist()
    [[0.04, 0.02, 0.0]]
    """

    @staticmethod
    def _weight_param(weight):
        return lane_color(weight, "weight")


fresnel_layer = FresnelLayer
color_fresnel_layer = ColorFresnelLayer
