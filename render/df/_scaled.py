"""The modifiers that scale one base bsdf by a colour factor: ``tint`` and ``directional_factor``.

``eval = factor(wo, wi) base.eval(wo, wi)``; the pdf is the base's, set to 0 where the
scaled value is (so ``pdf > 0`` exactly where ``eval > 0``); the sample weight is the
base's times the factor at the sampled direction.  The base's own pdf is the node's, so
sampling needs no evaluation of its own (inside a layer or mix, :meth:`ScaledBsdf._draw`
and :meth:`ScaledBsdf._settle` take part in the one-evaluation protocol of
:mod:`render.df._combine`).
"""

from __future__ import annotations

import numpy as np

from render._typing import Arr, Arr2, Rgb, Vec3
from render.bsdf import Bsdf, BsdfSample, check_dirs, check_samples
from render.df._combine import (
    Draw,
    Memo,
    any_positive,
    child_draw,
    child_eval_pdf,
    child_sample,
    child_settle,
    drawn,
)
from render.numerics import check_finite

__all__ = ["ScaledBsdf"]


class ScaledBsdf(Bsdf):
    """A ``base`` bsdf (or None: black) scaled by :meth:`_scale`.

    Subclasses set ``base``, ``lobes`` and ``name`` (MDL's, for error messages), call
    ``super().__init__()``, and implement ``_scale``, ``albedo`` and
    ``_cheap_albedo_now``.
    """

    name = ""

    def __init__(self):
        self._cheap_memo = Memo()

    def _scale(self, wo: Vec3, wi: Vec3) -> Rgb:  # pragma: no cover - abstract hook
        """(n, 3) factor at the direction pairs."""
        raise NotImplementedError

    def eval_pdf(self, wo: Vec3, wi: Vec3) -> tuple[Rgb, Arr]:
        wo, wi = check_dirs(wo, wi)
        return self._scaled_eval(wo, wi, *child_eval_pdf(self.base, wo, wi))

    def _scaled_eval(self, wo: Vec3, wi: Vec3, e: Rgb, p: Arr) -> tuple[Rgb, Arr]:
        """``(eval, pdf)`` at ``(wo, wi)`` from the base's ``(e, p)`` there."""
        value = self._scale(wo, wi) * e
        pdf = np.where(any_positive(value), p, 0.0)
        value = np.where((pdf > 0)[:, None], value, 0.0)
        return (check_finite(f"{self.name}.eval", value, True),
                check_finite(f"{self.name}.pdf", pdf, True))

    def eval(self, wo: Vec3, wi: Vec3) -> Rgb:
        return self.eval_pdf(wo, wi)[0]

    def pdf(self, wo: Vec3, wi: Vec3) -> Arr:
        return self.eval_pdf(wo, wi)[1]

    def sample(self, wo: Vec3, u1: Arr, u2: Arr2) -> BsdfSample:
        (wo,) = check_dirs(wo, names=("wo",))
        u1, u2 = check_samples(len(wo), u1, u2)
        return self._scaled_sample(wo, child_sample(self.base, wo, u1, u2))

    def _scaled_sample(self, wo: Vec3, s: BsdfSample) -> BsdfSample:
        """The node's sample from the base's sample ``s``."""
        wi = np.where(s.valid[:, None], s.wi, np.array([0.0, 0.0, 1.0]))
        weight = self._scale(wo, wi) * s.weight
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
        return (*self._scaled_eval(wo, wi, e, p), self._scaled_sample(wo, s))

    def _cheap_albedo(self, wo: Vec3) -> Rgb:
        return self._cheap_memo.get(wo, lambda: self._cheap_albedo_now(wo))
