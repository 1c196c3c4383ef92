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
>>> import numpy as np
>>> from render.df import diffuse_reflection_bsdf
>>> t = tint((1.0, 0.5, 2.0), diffuse_reflection_bsdf(tint=0.8))
>>> t.albedo(np.array([[0.0, 0.0, 1.0]])).round(12).tolist()
[[0.8, 0.4, 0.8]]
"""

from __future__ import annotations

from render.df._signature import REQUIRED, Param, Signature
from render.jit import njit
from render.program import O_TINT, df_class

__all__ = [
    "Tint",
    "tint",
    "SIGNATURE",
    "scale",
]


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
    """the tint factor: the tint, at every direction pair."""
    return P[row, b + _TINT], P[row, b + _TINT + 1], P[row, b + _TINT + 2]


# --- the Python class ------------------------------------------------------------------

Tint = df_class("Tint", "tint", O_TINT, SIGNATURE, module=__name__)
tint = Tint
