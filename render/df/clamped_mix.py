"""MDL ``df::clamped_mix`` and ``df::color_clamped_mix``: components summed in order until 1.

MDL signatures (bsdf, edf and vdf overloads)::

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
>>> import numpy as np
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

from render.df._mix import (  # noqa: F401 - bsdf_component: used in doctests
    COMPONENT_WIDTH,
    bsdf_component,
    mix_signatures,
)
from render.df._registry import Df, Node
from render.jit import njit
from render.program import mix_class, mix_dispatch

__all__ = [
    "clamped_mix",
    "color_clamped_mix",
    "ClampedMix",
    "ColorClampedMix",
    "ClampedMixEdf",
    "ColorClampedMixEdf",
    "ClampedMixVdf",
    "ColorClampedMixVdf",
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

#: ``df::clamped_mix`` over ``bsdf_component``, ``color_bsdf_component`` (MDL 1.4),
#: ``edf_component``, ``color_edf_component`` (MDL 1.4)
SIGNATURE, COLOR_SIGNATURE, EDF_SIGNATURE, COLOR_EDF_SIGNATURE = mix_signatures()


@njit
def _clamped(P, row, at, i):
    """One channel (slot ``at`` of component 0): ``saturate(w_i)`` cut where the running
    sum reaches 1 (``before = cumsum - w_i``, as numpy's)."""
    total = 0.0
    w = 0.0
    for j in range(i + 1):
        w = min(max(P[row, at + COMPONENT_WIDTH * j], 0.0), 1.0)
        total += w
    return max(min(w, 1.0 - (total - w)), 0.0)


@njit
def mix_weights(P, row, b, flags, k, i):
    """Component ``i``'s effective weight (of ``k``) per channel: ``saturate(weight)``,
    the first that would push the running sum above 1 cut to the remainder, later ones 0."""
    return _clamped(P, row, b, i), _clamped(P, row, b + 1, i), _clamped(P, row, b + 2, i)


# --- the Python classes ----------------------------------------------------------------

NODE = Node("clamped_mix", "bsdf", "mix", SIGNATURE, passes_film=True, mix_weights=mix_weights)
EDF_NODE = Node("clamped_mix_edf", "edf", "mix", EDF_SIGNATURE, mix_weights=mix_weights)
ClampedMix = mix_class("ClampedMix", "clamped_mix", NODE, False, False, module=__name__)
ColorClampedMix = mix_class("ColorClampedMix", "color_clamped_mix", NODE, True, False,
                            module=__name__)
ClampedMixEdf = mix_class("ClampedMixEdf", "clamped_mix", EDF_NODE, False, True,
                          module=__name__)
ColorClampedMixEdf = mix_class("ColorClampedMixEdf", "color_clamped_mix", EDF_NODE,
                               True, True, module=__name__)

ClampedMixVdf = mix_class("ClampedMixVdf", "clamped_mix", NODE, False, False,
                      module=__name__, vdf=True)
ColorClampedMixVdf = mix_class("ColorClampedMixVdf", "color_clamped_mix", NODE,
                           True, False, module=__name__, vdf=True)


def clamped_mix(components):
    """``df::clamped_mix``: a Bsdf (or Edf) whose saturated weights are cut where their
    running sum reaches 1."""
    return mix_dispatch(components, ClampedMix, ClampedMixEdf, ClampedMixVdf)


def color_clamped_mix(components):
    """``df::color_clamped_mix``: per-channel weights, clamped per channel."""
    return mix_dispatch(components, ColorClampedMix, ColorClampedMixEdf,
                        ColorClampedMixVdf)


DF = Df("clamped_mix", SIGNATURE, (NODE, EDF_NODE), constructor=clamped_mix)
COLOR_DF = Df("color_clamped_mix", COLOR_SIGNATURE, (NODE, EDF_NODE),
              constructor=color_clamped_mix)
