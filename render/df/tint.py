"""MDL ``df::tint``: a Bsdf scaled by a colour.

MDL signatures (overloads)::

    bsdf tint(color tint, bsdf base);
    bsdf tint(color reflection_tint, color transmission_tint, bsdf base);   // 1.6
    edf  tint(color tint, edf base);                                        // 1.7 varying
    vdf  tint(color tint, vdf base);                                        // 1.7

Model (libbsdf, ``reference/mdl-distribution-functions.md`` §4): ``eval = saturate(tint)
base.eval``, the sample weight scaled likewise, the pdf unchanged (except that it is 0
where the tinted value is, so ``pdf > 0`` exactly where ``eval > 0``).
``albedo = saturate(tint) base.albedo``.  The two-tint overload scales by
``saturate(reflection_tint)`` where ``wi`` is on ``wo``'s side and by
``saturate(transmission_tint)`` where it is not (its albedo is integrated through the
base's sampler where the base transmits).  The edf overload scales the emission, the
vdf overload the phase function (so a tinted vdf loses ``1 - tint`` at each scattering
event).  :func:`tint` picks the overload from its arguments, as MDL does.  The hair
overload waits for hair shading.

Examples
--------
>>> import numpy as np
>>> from render.df import diffuse_reflection_bsdf
>>> t = tint((1.0, 0.5, 2.0), diffuse_reflection_bsdf(tint=0.8))
>>> t.albedo(np.array([[0.0, 0.0, 1.0]])).round(12).tolist()
[[0.8, 0.4, 0.8]]
"""

from __future__ import annotations

from render.df._registry import Df, Node
from render.df._signature import REQUIRED, Param, Signature
from render.jit import njit

__all__ = [
    "Tint",
    "TintRt",
    "TintEdf",
    "TintVdf",
    "tint",
    "tint_rt",
    "tint_edf",
    "tint_vdf",
    "SIGNATURE",
    "RT_SIGNATURE",
    "EDF_SIGNATURE",
    "VDF_SIGNATURE",
    "scale",
    "scale_rt",
]


# --- signature and kernels (the compiled render core) ---------------------------------
# The factor of ScaledBsdf (the interpreter, render.program, evaluates the base and
# scales its value and sample weight; the pdf is the base's where the product is > 0).

#: ``df::tint`` (the bsdf overload; ``base`` None: MDL's ``bsdf()``)
SIGNATURE = Signature("bsdf", (
    Param("tint", "color", REQUIRED, clamp=(0.0, 1.0)),
    Param("base", "bsdf", REQUIRED),
))
#: the two-tint overload (MDL 1.6)
RT_SIGNATURE = Signature("bsdf", (
    Param("reflection_tint", "color", REQUIRED, clamp=(0.0, 1.0)),
    Param("transmission_tint", "color", REQUIRED, clamp=(0.0, 1.0)),
    Param("base", "bsdf", REQUIRED),
))
#: the edf overload (a varying tint since MDL 1.7)
EDF_SIGNATURE = Signature("edf", (
    Param("tint", "color", REQUIRED, clamp=(0.0, 1.0)),
    Param("base", "edf", REQUIRED),
))
#: the vdf overload (MDL 1.7)
VDF_SIGNATURE = Signature("vdf", (
    Param("tint", "color", REQUIRED, clamp=(0.0, 1.0)),
    Param("base", "vdf", REQUIRED),
))
_TINT = SIGNATURE.offset("tint")
_RT = RT_SIGNATURE.offset("reflection_tint")
_TT = RT_SIGNATURE.offset("transmission_tint")


@njit
def scale(P, row, b, flags, wox, woy, woz, wix, wiy, wiz):
    """the tint factor: the tint, at every direction pair."""
    return P[row, b + _TINT], P[row, b + _TINT + 1], P[row, b + _TINT + 2]


@njit
def scale_rt(P, row, b, flags, wox, woy, woz, wix, wiy, wiz):
    """the two-tint factor: ``reflection_tint`` where ``wi`` is on ``wo``'s side,
    ``transmission_tint`` where it is not."""
    at = b + (_RT if woz * wiz >= 0.0 else _TT)
    return P[row, at], P[row, at + 1], P[row, at + 2]


# --- the Python classes ----------------------------------------------------------------

#: a bsdf's or a vdf's tint (one factor, whatever the directions)
NODE = Node("tint", "bsdf", "modifier", SIGNATURE, directional=False, passes_film=True,
            scale=scale)
RT_NODE = Node("tint_rt", "bsdf", "modifier", RT_SIGNATURE, passes_film=True, scale=scale_rt)
EDF_NODE = Node("tint_edf", "edf", "modifier", EDF_SIGNATURE, directional=False, scale=scale)
# MDL's overloads of tint, in the order a call tries them
DF = Df("tint", SIGNATURE, (NODE,))
RT_DF = Df("tint_rt", RT_SIGNATURE, (RT_NODE,), mdl_name="tint")
EDF_DF = Df("tint_edf", EDF_SIGNATURE, (EDF_NODE,), mdl_name="tint")
VDF_DF = Df("tint_vdf", VDF_SIGNATURE, (NODE,), mdl_name="tint")
Tint, TintRt, TintEdf, TintVdf = DF.cls, RT_DF.cls, EDF_DF.cls, VDF_DF.cls
tint_rt, tint_edf, tint_vdf = TintRt, TintEdf, TintVdf


def tint(*args, **kwargs):
    """``df::tint``: the overload MDL would pick from the arguments: two tints (by name,
    or three arguments) for :class:`TintRt`, an edf ``base`` for :class:`TintEdf`, a vdf
    for :class:`TintVdf`, else :class:`Tint` (a bsdf)."""
    from render.program import ProgramEdf

    if "reflection_tint" in kwargs or "transmission_tint" in kwargs or len(args) == 3:
        return TintRt(*args, **kwargs)
    base = kwargs.get("base", args[1] if len(args) > 1 else None)
    if isinstance(base, ProgramEdf):
        return TintEdf(*args, **kwargs)
    if getattr(base, "signature", None) is not None and base.signature.kind == "vdf":
        return TintVdf(*args, **kwargs)
    return Tint(*args, **kwargs)


tint.mdl_name = "tint"
tint.__signature__ = Tint.__signature__  # the bsdf overload's parameters (the bind plan's)
