"""MDL ``df::directional_factor``: a Bsdf scaled by a Schlick-like curve of the half-vector angle.

MDL signature::

    bsdf directional_factor(color normal_tint = color(1.0), color grazing_tint = color(1.0),
                            color f82_factor = color(1.0),                          // 1.10
                            float exponent = 5.0, bsdf base = bsdf());

Model (libbsdf, ``reference/mdl-distribution-functions.md`` §4): the factor is the
custom curve of ``custom_curve_layer`` with Hoffman's F82 tint,
``C(c) = saturate(R0 + (R90 - R0)(1 - c)^p - a c (1 - c)^6)`` with ``R0 =
saturate(normal_tint)``, ``R90 = saturate(grazing_tint)``, ``p = max(exponent, 0)``,
evaluated at ``c = wo.h`` for the reflection half vector ``h`` (a transmitted ``wi`` is
mirrored through the tangent plane first)::

    eval = C(wo.h) base.eval(wo, wi),    pdf = base.pdf (0 where the product is)

The sample weight is scaled by ``C`` at the sampled direction.  Energy: never more
than the base (``C <= 1``).  ``albedo`` is exact for a constant curve and otherwise
integrated through the base's sampler (:data:`render.df._combine.ALBEDO_POINTS` QMC
points).  The EDF overload (MDL 1.7) is not implemented.
"""

from __future__ import annotations

import numpy as np

from render._typing import ArrayLike, Rgb, Vec3
from render.bsdf import Lobe, check_dirs, lane_color, lane_float, lanes
from render.df import _kernel_common as kc
from render.df._combine import albedo_correction, cheap_albedo, check_child, is_mirror
from render.df._layer import f82_curve, f82_curve1
from render.df._scaled import ScaledBsdf
from render.df._signature import Param, Signature
from render.frame import mirror_z
from render.jit import njit
from render.numerics import saturate, unitize

__all__ = ["DirectionalFactor", "directional_factor", "SIGNATURE", "scale"]


# --- signature and kernels (the compiled render core) ---------------------------------
# The factor of ScaledBsdf (the interpreter, render.program, evaluates the base and
# scales its value and sample weight; the pdf is the base's where the product is > 0).

#: ``df::directional_factor`` (the bsdf overload; ``base`` None: MDL's ``bsdf()``)
SIGNATURE = Signature("bsdf", (
    Param("normal_tint", "color", (1.0, 1.0, 1.0), clamp=(0.0, 1.0)),
    Param("grazing_tint", "color", (1.0, 1.0, 1.0), clamp=(0.0, 1.0)),
    Param("f82_factor", "color", (1.0, 1.0, 1.0), clamp=(0.0, 1.0)),
    Param("exponent", "float", 5.0, clamp=(0.0, None)),
    Param("base", "bsdf", None),
))
_R0 = SIGNATURE.offset("normal_tint")
_R90 = SIGNATURE.offset("grazing_tint")
_F82 = SIGNATURE.offset("f82_factor")
_EXPONENT = SIGNATURE.offset("exponent")


@njit
def scale(P, row, b, flags, wox, woy, woz, wix, wiy, wiz):
    """:meth:`DirectionalFactor._scale`: ``C(wo.h)`` per channel, ``h`` the reflection half
    vector (both directions mirrored to ``wo``'s side, then a transmitted ``wi`` through
    the tangent plane); 0 where ``wo.h < 0``."""
    s = -1.0 if woz < 0.0 else 1.0
    oz = woz * s
    iz = wiz * s
    hx, hy, hz, ok = kc.unitize(wox + wix, woy + wiy, oz + kc.mirror_z(iz, iz < 0.0))
    if not ok:
        hx, hy, hz = 0.0, 0.0, 1.0
    kh = kc.dot3(wox, woy, oz, hx, hy, hz)
    if not kh >= 0.0:
        return 0.0, 0.0, 0.0
    p = P[row, b + _EXPONENT]
    return (f82_curve1(kh, P[row, b + _R0], P[row, b + _R90], P[row, b + _F82], p),
            f82_curve1(kh, P[row, b + _R0 + 1], P[row, b + _R90 + 1], P[row, b + _F82 + 1], p),
            f82_curve1(kh, P[row, b + _R0 + 2], P[row, b + _R90 + 2], P[row, b + _F82 + 2], p))


class DirectionalFactor(ScaledBsdf):
    """``df::directional_factor`` over lanes (eval, pdf and sampling: :class:`ScaledBsdf`).

    Parameters
    ----------
    normal_tint, grazing_tint : float, (3,) or (n, 3)
        ``R0`` and ``R90``, saturated.
    f82_factor : float, (3,) or (n, 3)
        Hoffman's F82 tint, saturated (1: none).
    exponent : float or (n,)
        Negative values act as 0.
    base : Bsdf or None
        None is MDL's black ``bsdf()``.

    Examples
    --------
    >>> from render.df import specular_bsdf
    >>> d = directional_factor(normal_tint=(0.9, 0.5, 0.1), grazing_tint=1.0, exponent=5.0,
    ...                        base=specular_bsdf())
    >>> wo = np.array([[0.0, 0.0, 1.0], [0.6, 0.0, 0.8]])
    >>> np.round(d.albedo(wo), 6).tolist()   # R0 + (1 - R0) 0.2^5 at 36.9 degrees
    [[0.9, 0.5, 0.1], [0.900032, 0.50016, 0.100288]]
    """

    name = "directional_factor"

    def __init__(self, normal_tint: ArrayLike = 1.0, grazing_tint: ArrayLike = 1.0,
                 f82_factor: ArrayLike = 1.0, exponent: ArrayLike = 5.0, base=None):
        super().__init__()
        self.normal_tint = saturate(lane_color(normal_tint, "normal_tint"))
        self.grazing_tint = saturate(lane_color(grazing_tint, "grazing_tint"))
        self.f82_factor = saturate(lane_color(f82_factor, "f82_factor"))
        self.exponent = np.maximum(lane_float(exponent, "exponent"), 0.0)
        self.base = check_child(base, "base")
        self.lobes = Lobe.NONE if self.base is None else self.base.lobes

    def __repr__(self) -> str:
        return (f"directional_factor(normal_tint={self.normal_tint.tolist()}, "
                f"grazing_tint={self.grazing_tint.tolist()}, exponent={self.exponent.tolist()}, "
                f"base={self.base!r})")

    def _params(self, n: int):
        return (
            np.broadcast_to(lanes(self.normal_tint, n, "normal_tint"), (n, 3)),
            np.broadcast_to(lanes(self.grazing_tint, n, "grazing_tint"), (n, 3)),
            np.broadcast_to(lanes(self.f82_factor, n, "f82_factor"), (n, 3)),
            np.broadcast_to(lanes(self.exponent, n, "exponent"), (n,)),
        )

    def _scale(self, wo: Vec3, wi: Vec3) -> Rgb:
        """``C(wo.h)`` with the reflection half vector (transmitted ``wi`` mirrored)."""
        n = len(wo)
        s = np.where(wo[:, 2] < 0.0, -1.0, 1.0)[:, None]
        o = wo * np.concatenate([np.ones((n, 2)), s], axis=1)
        i = wi * np.concatenate([np.ones((n, 2)), s], axis=1)
        h, ok = unitize(o + mirror_z(i, i[:, 2] < 0.0))
        h = np.where(ok[:, None], h, np.array([0.0, 0.0, 1.0]))
        kh = np.einsum("ij,ij->i", o, h)
        r0, r90, f82, p = self._params(n)
        return np.where((kh >= 0.0)[:, None], f82_curve(kh, r0, r90, f82, p), 0.0)

    def _constant(self, n: int) -> bool:
        r0, r90, f82, p = self._params(n)
        return bool(np.all(f82 == 1.0) and (np.all(r0 == r90) or np.all(p == 0.0)))

    def albedo(self, wo: Vec3) -> Rgb:
        """``C(nk1) base.albedo`` plus the integral of ``C(wo.h) - C(nk1)`` over the base's
        lobe (:func:`render.df._combine.albedo_correction`; exact for a mirror base or a
        constant curve)."""
        (wo,) = check_dirs(wo, names=("wo",))
        n = len(wo)
        if self.base is None:
            return np.zeros((n, 3))
        r0, r90, f82, p = self._params(n)
        est = f82_curve(np.abs(wo[:, 2]), r0, r90, f82, p)
        out = est * self.base.albedo(wo)
        if not (self._constant(n) or is_mirror(self.base)):
            out += albedo_correction(self.base, wo, lambda wi: self._scale(wo, wi), est)
        return np.clip(out, 0.0, None)

    def _cheap_albedo_now(self, wo: Vec3) -> Rgb:
        n = len(wo)
        r0, r90, f82, p = self._params(n)
        c = f82_curve(np.abs(wo[:, 2]), r0, r90, f82, p)
        return c * cheap_albedo(self.base, wo)


directional_factor = DirectionalFactor
