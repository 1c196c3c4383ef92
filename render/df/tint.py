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

from render._typing import Arr, Arr2, ArrayLike, Rgb, Vec3
from render.bsdf import Bsdf, BsdfSample, Lobe, check_dirs, check_samples, lane_color, lanes
from render.df._combine import (
    Draw,
    Memo,
    any_positive,
    cheap_albedo,
    check_child,
    child_draw,
    child_eval_pdf,
    child_sample,
    child_settle,
    drawn,
)
from render.numerics import check_finite, saturate

__all__ = ["Tint", "tint"]


class Tint(Bsdf):
    """``df::tint`` over lanes.

    Parameters
    ----------
    tint : float, (3,) or (n, 3)
        Saturated to [0, 1].
    base : Bsdf or None
        None is MDL's black ``bsdf()``.
    """

    def __init__(self, tint: ArrayLike, base=None):
        self.tint = saturate(lane_color(tint, "tint"))
        self.base = check_child(base, "base")
        self.lobes = Lobe.NONE if self.base is None else self.base.lobes
        self._cheap_memo = Memo()

    def __repr__(self) -> str:
        return f"tint(tint={self.tint.tolist()}, base={self.base!r})"

    def _t(self, n: int) -> Rgb:
        return np.broadcast_to(lanes(self.tint, n, "tint"), (n, 3))

    def eval_pdf(self, wo: Vec3, wi: Vec3) -> tuple[Rgb, Arr]:
        wo, wi = check_dirs(wo, wi)
        return self._tinted_eval(*child_eval_pdf(self.base, wo, wi))

    def _tinted_eval(self, e: Rgb, p: Arr) -> tuple[Rgb, Arr]:
        """``(eval, pdf)`` from the base's ``(e, p)``."""
        value = self._t(len(e)) * e
        pdf = np.where(any_positive(value), p, 0.0)
        value = np.where((pdf > 0)[:, None], value, 0.0)
        return check_finite("tint.eval", value, True), check_finite("tint.pdf", pdf, True)

    def eval(self, wo: Vec3, wi: Vec3) -> Rgb:
        return self.eval_pdf(wo, wi)[0]

    def pdf(self, wo: Vec3, wi: Vec3) -> Arr:
        return self.eval_pdf(wo, wi)[1]

    def sample(self, wo: Vec3, u1: Arr, u2: Arr2) -> BsdfSample:
        # the base's own pdf and weight are the tint's: no evaluation here
        (wo,) = check_dirs(wo, names=("wo",))
        u1, u2 = check_samples(len(wo), u1, u2)
        return self._tinted_sample(child_sample(self.base, wo, u1, u2))

    def _tinted_sample(self, s: BsdfSample) -> BsdfSample:
        """The tint's sample from the base's sample ``s``."""
        weight = self._t(len(s.wi)) * s.weight
        ok = s.valid & any_positive(weight)
        return BsdfSample(
            np.where(ok[:, None], s.wi, 0.0),
            np.where(ok, s.pdf, 0.0),
            np.where(ok[:, None], weight, 0.0),
            np.where(ok, s.lobe, 0).astype(np.int32),
        ).checked()

    def _draw(self, wo: Vec3, u1: Arr, u2: Arr2) -> Draw:
        """Descend into the base (inside a layer or mix: see :mod:`render.df._combine`)."""
        d = child_draw(self.base, wo, u1, u2)
        return Draw(d.wi, drawn(d), (d,))

    def _settle(self, wo: Vec3, wi: Vec3, d: Draw) -> tuple[Rgb, Arr, BsdfSample]:
        """``eval_pdf(wo, wi)`` and the sample ``d`` settled at ``wi`` (its drawn direction
        wherever it was drawn), from one evaluation of the subtree."""
        e, p, s = child_settle(self.base, wo, wi, d.state[0])
        return (*self._tinted_eval(e, p), self._tinted_sample(s))

    def albedo(self, wo: Vec3) -> Rgb:
        (wo,) = check_dirs(wo, names=("wo",))
        if self.base is None:
            return np.zeros((len(wo), 3))
        return self._t(len(wo)) * self.base.albedo(wo)

    def _cheap_albedo(self, wo: Vec3) -> Rgb:
        return self._cheap_memo.get(wo, lambda: self._cheap_albedo_now(wo))

    def _cheap_albedo_now(self, wo: Vec3) -> Rgb:
        return self._t(len(wo)) * cheap_albedo(self.base, wo)


tint = Tint
