"""MDL ``df::tint``: a Bsdf scaled by a colour.

MDL signature::

    bsdf tint(color tint, bsdf base);

Model (libbsdf, ``reference/mdl-distribution-functions.md`` §4): ``eval = saturate(tint)
base.eval``, the sample weight scaled likewise, the pdf unchanged (except that it is 0
where the tinted value is, so ``pdf > 0`` exactly where ``eval > 0``).
``albedo = saturate(tint) base.albedo``.  The EDF, VDF and hair overloads and the
two-tint reflection/transmission overload (MDL 1.6) are not implemented.

Examples
--------
>>> from render.df import diffuse_reflection_bsdf
>>> t = tint((1.0, 0.5, 2.0), diffuse_reflection_bsdf(tint=0.8))
>>> t.albedo(np.array([[0.0, 0.0, 1.0]])).round(12).tolist()
[[0.8, 0.4, 0.8]]
"""

from __future__ import annotations

import numpy as np

from render._typing import ArrayLike, Rgb, Vec3
from render.bsdf import Lobe, check_dirs, lane_color, lanes
from render.df._combine import cheap_albedo, check_child
from render.df._scaled import ScaledBsdf
from render.df._signature import REQUIRED, Param, Signature
from render.jit import njit
from render.numerics import saturate

__all__ = ["Tint", "tint", "SIGNATURE", "scale"]


# --- signature and kernels (the compiled render core) ---------------------------------
# The factor of ScaledBsdf (the interpreter, render.program, evaluates the base and
# scales its value and sample weight; the pdf is the base's where the product is > 0).

#: ``df::tint`` (the bsdf overload; ``base`` None: MDL's ``bsdf()``)
SIGNATURE = Signature("bsdf", (
    Param("tint", "color", REQUIRED, clamp=(0.0, 1.0)),
    Param("base", "bsdf", REQUIRED),
))
_TINT = SIGNATURE.offset("tint")


@njit
def scale(P, row, b, flags, wox, woy, woz, wix, wiy, wiz):
    """:meth:`Tint._scale`: the tint, at every direction pair."""
    return P[row, b + _TINT], P[row, b + _TINT + 1], P[row, b + _TINT + 2]


class Tint(ScaledBsdf):
    """``df::tint`` over lanes (eval, pdf and sampling: :class:`ScaledBsdf`).

    Parameters
    ----------
    tint : float, (3,) or (n, 3)
        Saturated to [0, 1].
    base : Bsdf or None
        None is MDL's black ``bsdf()``.
    """

    name = "tint"

    def __init__(self, tint: ArrayLike, base=None):
        super().__init__()
        self.tint = saturate(lane_color(tint, "tint"))
        self.base = check_child(base, "base")
        self.lobes = Lobe.NONE if self.base is None else self.base.lobes

    def __repr__(self) -> str:
        return f"tint(tint={self.tint.tolist()}, base={self.base!r})"

    def _t(self, n: int) -> Rgb:
        return np.broadcast_to(lanes(self.tint, n, "tint"), (n, 3))

    def _scale(self, wo: Vec3, wi: Vec3) -> Rgb:
        return self._t(len(wo))

    def albedo(self, wo: Vec3) -> Rgb:
        (wo,) = check_dirs(wo, names=("wo",))
        if self.base is None:
            return np.zeros((len(wo), 3))
        return self._t(len(wo)) * self.base.albedo(wo)

    def _cheap_albedo_now(self, wo: Vec3) -> Rgb:
        return self._t(len(wo)) * cheap_albedo(self.base, wo)


tint = Tint
