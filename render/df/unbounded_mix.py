"""MDL ``df::unbounded_mix`` and ``df::color_unbounded_mix``: components summed as weighted.

MDL signatures (bsdf and edf overloads; MDL 1.7)::

    bsdf unbounded_mix(bsdf_component[<N>] components);
    edf  unbounded_mix(edf_component[<N>] components);
    bsdf color_unbounded_mix(color_bsdf_component[<N>] components);
    edf  color_unbounded_mix(color_edf_component[<N>] components);

Model (libbsdf, ``reference/mdl-distribution-functions.md`` §3.3): ``w_i = max(weight_i,
0)`` with no limit: ``eval = sum_i w_i eval_i``, so a white mix whose weights sum above
1 **gains** energy (the spec leaves that to the author).  Sampling and the pdf:
:mod:`render.df._mix` (component ``i`` picked in proportion to its expected
contribution, the weight ``eval / pdf`` of the whole mix).

Examples
--------
>>> import numpy as np
>>> from render.df import diffuse_reflection_bsdf
>>> m = unbounded_mix([bsdf_component(0.75, diffuse_reflection_bsdf(tint=1.0)),
...                    bsdf_component(0.5, diffuse_reflection_bsdf(tint=0.5))])
>>> m.albedo(np.array([[0.0, 0.0, 1.0]])).tolist()
[[1.0, 1.0, 1.0]]
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
    "unbounded_mix",
    "color_unbounded_mix",
    "UnboundedMix",
    "ColorUnboundedMix",
    "UnboundedMixEdf",
    "ColorUnboundedMixEdf",
    "UnboundedMixVdf",
    "ColorUnboundedMixVdf",
    "SIGNATURE",
    "COLOR_SIGNATURE",
    "EDF_SIGNATURE",
    "COLOR_EDF_SIGNATURE",
    "mix_weights",
]

#: ``df::unbounded_mix`` over ``bsdf_component``, ``color_bsdf_component``,
#: ``edf_component``, ``color_edf_component``
SIGNATURE, COLOR_SIGNATURE, EDF_SIGNATURE, COLOR_EDF_SIGNATURE = mix_signatures()


@njit
def mix_weights(P, row, b, flags, k, i):
    """Component ``i``'s effective weight per channel: ``max(weight, 0)``, unbounded."""
    at = b + COMPONENT_WIDTH * i
    return max(P[row, at], 0.0), max(P[row, at + 1], 0.0), max(P[row, at + 2], 0.0)


NODE = Node("unbounded_mix", "bsdf", "mix", SIGNATURE, passes_film=True, mix_weights=mix_weights)
EDF_NODE = Node("unbounded_mix_edf", "edf", "mix", EDF_SIGNATURE, mix_weights=mix_weights)
UnboundedMix = mix_class("UnboundedMix", "unbounded_mix", NODE, False, False,
                         module=__name__)
ColorUnboundedMix = mix_class("ColorUnboundedMix", "color_unbounded_mix", NODE,
                              True, False, module=__name__)
UnboundedMixEdf = mix_class("UnboundedMixEdf", "unbounded_mix", EDF_NODE, False,
                            True, module=__name__)
ColorUnboundedMixEdf = mix_class("ColorUnboundedMixEdf", "color_unbounded_mix",
                                 EDF_NODE, True, True, module=__name__)

UnboundedMixVdf = mix_class("UnboundedMixVdf", "unbounded_mix", NODE, False, False,
                      module=__name__, vdf=True)
ColorUnboundedMixVdf = mix_class("ColorUnboundedMixVdf", "color_unbounded_mix", NODE,
                           True, False, module=__name__, vdf=True)


def unbounded_mix(components):
    """``df::unbounded_mix``: a Bsdf (or, over ``edf_component`` values, an Edf) whose
    weights are ``max(weight, 0)``, not normalised."""
    return mix_dispatch(components, UnboundedMix, UnboundedMixEdf, UnboundedMixVdf)


def color_unbounded_mix(components):
    """``df::color_unbounded_mix``: per-channel weights, not normalised."""
    return mix_dispatch(components, ColorUnboundedMix, ColorUnboundedMixEdf,
                        ColorUnboundedMixVdf)


DF = Df("unbounded_mix", SIGNATURE, (NODE, EDF_NODE), constructor=unbounded_mix)
COLOR_DF = Df("color_unbounded_mix", COLOR_SIGNATURE, (NODE, EDF_NODE),
              constructor=color_unbounded_mix)
