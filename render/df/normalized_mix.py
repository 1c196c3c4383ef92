"""MDL ``df::normalized_mix`` and ``df::color_normalized_mix``: components scaled to sum at most 1.

MDL signatures (bsdf, edf and vdf overloads)::

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
>>> import numpy as np
>>> from render.df import diffuse_reflection_bsdf
>>> m = normalized_mix([bsdf_component(3.0, diffuse_reflection_bsdf(tint=1.0)),
...                     bsdf_component(1.0, diffuse_reflection_bsdf(tint=0.0))])
>>> m.albedo(np.array([[0.0, 0.0, 1.0]])).tolist()
[[0.75, 0.75, 0.75]]
"""

from __future__ import annotations

from render.df._mix import (
    COMPONENT_WIDTH,
    bsdf_component,
    color_bsdf_component,
    color_edf_component,
    edf_component,
    mix_signatures,
)
from render.df._registry import Df, Node
from render.jit import njit
from render.program import mix_class, mix_dispatch

__all__ = [
    "normalized_mix",
    "color_normalized_mix",
    "NormalizedMix",
    "ColorNormalizedMix",
    "NormalizedMixEdf",
    "ColorNormalizedMixEdf",
    "NormalizedMixVdf",
    "ColorNormalizedMixVdf",
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


# --- the Python classes ----------------------------------------------------------------

NODE = Node("normalized_mix", "bsdf", "mix", SIGNATURE, passes_film=True, mix_weights=mix_weights)
EDF_NODE = Node("normalized_mix_edf", "edf", "mix", EDF_SIGNATURE, mix_weights=mix_weights)
NormalizedMix = mix_class("NormalizedMix", "normalized_mix", NODE, False, False,
                          module=__name__)
ColorNormalizedMix = mix_class("ColorNormalizedMix", "color_normalized_mix",
                               NODE, True, False, module=__name__)
NormalizedMixEdf = mix_class("NormalizedMixEdf", "normalized_mix", EDF_NODE,
                             False, True, module=__name__)
ColorNormalizedMixEdf = mix_class("ColorNormalizedMixEdf", "color_normalized_mix",
                                  EDF_NODE, True, True, module=__name__)

NormalizedMixVdf = mix_class("NormalizedMixVdf", "normalized_mix", NODE, False, False,
                      module=__name__, vdf=True)
ColorNormalizedMixVdf = mix_class("ColorNormalizedMixVdf", "color_normalized_mix", NODE,
                           True, False, module=__name__, vdf=True)


def normalized_mix(components):
    """``df::normalized_mix``: a Bsdf (or, over ``edf_component`` values, an Edf) whose
    weights are ``max(weight, 0)`` divided by their sum where it exceeds 1."""
    return mix_dispatch(components, NormalizedMix, NormalizedMixEdf, NormalizedMixVdf)


def color_normalized_mix(components):
    """``df::color_normalized_mix``: per-channel weights, normalised per channel."""
    return mix_dispatch(components, ColorNormalizedMix, ColorNormalizedMixEdf,
                        ColorNormalizedMixVdf)


DF = Df("normalized_mix", SIGNATURE, (NODE, EDF_NODE), constructor=normalized_mix)
COLOR_DF = Df("color_normalized_mix", COLOR_SIGNATURE, (NODE, EDF_NODE),
              constructor=color_normalized_mix)
