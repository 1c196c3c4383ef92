"""MDL ``df::normalized_mix`` and ``df::color_normalized_mix``: components scaled to sum at most 1.

MDL signatures (bsdf, edf and vdf overloads; vdf is not implemented)::

    bsdf normalized_mix(bsdf_component[<N>] components);
    edf  normalized_mix(edf_component[<N>] components);
    bsdf color_normalized_mix(color_bsdf_component[<N>] components);     // 1.4
    edf  color_normalized_mix(color_edf_component[<N>] components);      // 1.4

Model (libbsdf, ``reference/mdl-distribution-functions.md`` §3.3): ``w_i = max(weight_i, 0)``;
where ``S = sum_i w_i > 1`` every ``w_i`` is divided by ``S``; then
``eval = sum_i w_i eval_i``.  ``color_normalized_mix`` normalises **each channel by its own
sum** (libbsdf; the spec divides every channel by the largest channel sum).  Sampling
and the pdf: :mod:`render.df._mix`.  A mix of white lossless components is lossless
whenever the weights sum to 1 or more.

Examples
--------
>>> from render.df import diffuse_reflection_bsdf
>>> m = normalized_mix([bsdf_component(3.0, diffuse_reflection_bsdf(tint=1.0)),
...                     bsdf_component(1.0, diffuse_reflection_bsdf(tint=0.0))])
>>> m.albedo(np.array([[0.0, 0.0, 1.0]])).tolist()
[[0.75, 0.75, 0.75]]
"""

from __future__ import annotations

import numpy as np

from render.df._mix import (
    COMPONENT_WIDTH,
    BsdfComponent,
    MixBsdf,
    MixEdf,
    as_components,
    bsdf_component,
    color_bsdf_component,
    color_edf_component,
    edf_component,
    mix_signatures,
)
from render.jit import njit

__all__ = [
    "normalized_mix",
    "color_normalized_mix",
    "NormalizedMix",
    "ColorNormalizedMix",
    "NormalizedMixEdf",
    "ColorNormalizedMixEdf",
    "bsdf_component",
    "color_bsdf_component",
    "edf_component",
    "color_edf_component",
    "SIGNATURE",
    "COLOR_SIGNATURE",
    "EDF_SIGNATURE",
    "COLOR_EDF_SIGNATURE",
    "mix_weights",
]


# --- signatures and kernels (the compiled render core) --------------------------------
# The effective weights (the interpreter, render.program, selects, sums and samples the
# components).  A mix node's slots: its k component weights as colours, component i's at
# ``b + 3 i`` (render.df._mix: the component signatures); one kernel serves every
# overload (a float weight is packed as a grey colour).

#: ``df::normalized_mix`` over ``bsdf_component``, ``color_bsdf_component`` (MDL 1.4),
#: ``edf_component``, ``color_edf_component`` (MDL 1.4)
SIGNATURE, COLOR_SIGNATURE, EDF_SIGNATURE, COLOR_EDF_SIGNATURE = mix_signatures()


@njit
def mix_weights(P, row, b, flags, k, i):
    """Component ``i``'s effective weight (of ``k``) per channel: ``max(weight, 0)``,
    divided by the channel's sum over the components where that sum exceeds 1."""
    s0 = s1 = s2 = 0.0
    for j in range(k):
        at = b + COMPONENT_WIDTH * j
        s0 += max(P[row, at], 0.0)
        s1 += max(P[row, at + 1], 0.0)
        s2 += max(P[row, at + 2], 0.0)
    at = b + COMPONENT_WIDTH * i
    w0, w1, w2 = max(P[row, at], 0.0), max(P[row, at + 1], 0.0), max(P[row, at + 2], 0.0)
    return (w0 / s0 if s0 > 1.0 else w0, w1 / s1 if s1 > 1.0 else w1,
            w2 / s2 if s2 > 1.0 else w2)


class _Normalized:
    def weights(self, n: int) -> np.ndarray:
        """(n, k, 3): ``max(weight, 0)``, divided by the channel's sum where it exceeds 1."""
        w = np.maximum(self._raw(n), 0.0)
        s = w.sum(axis=1, keepdims=True)
        return np.where(s > 1.0, w / np.where(s > 1.0, s, 1.0), w)


class NormalizedMix(_Normalized, MixBsdf):
    """``df::normalized_mix`` over ``bsdf_component`` values (a Bsdf)."""

    _mdl_name = "normalized_mix"


class ColorNormalizedMix(_Normalized, MixBsdf):
    """``df::color_normalized_mix`` over ``color_bsdf_component`` values (a Bsdf)."""

    _color = True
    _mdl_name = "color_normalized_mix"


class NormalizedMixEdf(_Normalized, MixEdf):
    """``df::normalized_mix`` over ``edf_component`` values (an Edf)."""

    _mdl_name = "normalized_mix"


class ColorNormalizedMixEdf(_Normalized, MixEdf):
    """``df::color_normalized_mix`` over ``color_edf_component`` values (an Edf)."""

    _color = True
    _mdl_name = "color_normalized_mix"


def _dispatch(components, color: bool, bsdf_cls, edf_cls, name: str):
    comps = as_components(components, color, name)
    if comps and comps[0]._kind is not BsdfComponent._kind:
        return edf_cls(comps)
    return bsdf_cls(comps)


def normalized_mix(components):
    """``df::normalized_mix``: a :class:`NormalizedMix` (Bsdf) or :class:`NormalizedMixEdf`.

    Parameters
    ----------
    components : sequence of bsdf_component or edf_component (or ``(weight, df)`` pairs)
    """
    return _dispatch(components, False, NormalizedMix, NormalizedMixEdf, "normalized_mix")


def color_normalized_mix(components):
    """``df::color_normalized_mix``: per-channel weights (:class:`ColorNormalizedMix` or
    :class:`ColorNormalizedMixEdf`)."""
    return _dispatch(components, True, ColorNormalizedMix, ColorNormalizedMixEdf,
                     "color_normalized_mix")
