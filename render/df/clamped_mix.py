"""MDL ``df::clamped_mix`` and ``df::color_clamped_mix``: components summed in order until 1.

MDL signatures (bsdf, edf and vdf overloads; vdf is not implemented)::

    bsdf clamped_mix(bsdf_component[<N>] components);
    edf  clamped_mix(edf_component[<N>] components);
    bsdf color_clamped_mix(color_bsdf_component[<N>] components);     // 1.4
    edf  color_clamped_mix(color_edf_component[<N>] components);      // 1.4

Model (libbsdf, ``reference/mdl-distribution-functions.md`` §3.3): ``w_i = saturate(weight_i)``
accumulated in order; the first component that would push the running sum above 1 gets
``1 - (sum so far)`` and every later component is dropped (weight 0).  The colour
variant clamps each channel on its own.  ``eval = sum_i w_i eval_i``; sampling and the
pdf: :mod:`render.df._mix`.

Examples
--------
>>> from render.df import diffuse_reflection_bsdf
>>> m = clamped_mix([bsdf_component(0.7, diffuse_reflection_bsdf(tint=1.0)),
...                  bsdf_component(0.7, diffuse_reflection_bsdf(tint=0.5)),
...                  bsdf_component(0.7, diffuse_reflection_bsdf(tint=0.0))])
>>> m.weights(1)[0, :, 0].round(12).tolist()
[0.7, 0.3, 0.0]
>>> m.albedo(np.array([[0.0, 0.0, 1.0]])).round(12).tolist()
[[0.85, 0.85, 0.85]]
"""

from __future__ import annotations

import numpy as np

from render.df._mix import MixBsdf, MixEdf, bsdf_component  # noqa: F401 - used in doctests
from render.df.normalized_mix import _dispatch
from render.numerics import saturate

__all__ = [
    "clamped_mix",
    "color_clamped_mix",
    "ClampedMix",
    "ColorClampedMix",
    "ClampedMixEdf",
    "ColorClampedMixEdf",
]


class _Clamped:
    def weights(self, n: int) -> np.ndarray:
        """(n, k, 3): ``saturate(weight)`` cut where the running sum reaches 1."""
        w = saturate(self._raw(n))
        before = np.cumsum(w, axis=1) - w
        return np.clip(np.minimum(w, 1.0 - before), 0.0, None)


class ClampedMix(_Clamped, MixBsdf):
    """``df::clamped_mix`` over ``bsdf_component`` values (a Bsdf)."""

    _mdl_name = "clamped_mix"


class ColorClampedMix(_Clamped, MixBsdf):
    """``df::color_clamped_mix`` over ``color_bsdf_component`` values (a Bsdf)."""

    _color = True
    _mdl_name = "color_clamped_mix"


class ClampedMixEdf(_Clamped, MixEdf):
    """``df::clamped_mix`` over ``edf_component`` values (an Edf)."""

    _mdl_name = "clamped_mix"


class ColorClampedMixEdf(_Clamped, MixEdf):
    """``df::color_clamped_mix`` over ``color_edf_component`` values (an Edf)."""

    _color = True
    _mdl_name = "color_clamped_mix"


def clamped_mix(components):
    """``df::clamped_mix``: a :class:`ClampedMix` (Bsdf) or :class:`ClampedMixEdf`.

    Parameters
    ----------
    components : sequence of bsdf_component or edf_component (or ``(weight, df)`` pairs)
    """
    return _dispatch(components, False, ClampedMix, ClampedMixEdf, "clamped_mix")


def color_clamped_mix(components):
    """``df::color_clamped_mix``: per-channel clamping (:class:`ColorClampedMix` or
    :class:`ColorClampedMixEdf`)."""
    return _dispatch(components, True, ColorClampedMix, ColorClampedMixEdf, "color_clamped_mix")
