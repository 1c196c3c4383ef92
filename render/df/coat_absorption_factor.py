"""MDL ``df::coat_absorption_factor``: a Bsdf attenuated by the absorbing coat it lies under.

MDL signature (1.10)::

    bsdf coat_absorption_factor(color ior = color(1.0),
                                color absorption_coefficient = color(0.0),
                                float thickness = 0.0, bsdf base = bsdf());

Model (libbsdf, ``reference/mdl-distribution-functions.md`` §4): light reaching the
base crosses a coat of IOR ``ior`` and thickness ``d`` on the way in and out, along the
directions refracted into the coat::

    factor = exp(-sigma_a d (1 / cos1' + 1 / cos2')),   cos' = sqrt(1 - eta^2 (1 - cos^2))

per channel, ``eta = eta1 / ior`` (``eta1`` the IOR on ``wo``'s side), the cosines
``|wo.z|`` and ``|wi.z|``; for transmission (``wi`` on the other side) the path is
taken as half as long (libbsdf: it crosses the coat once).  As libbsdf, a coat less
dense than the medium (``eta > 1``) absorbs nothing.  ``eval = factor base.eval``, the
pdf the base's; never more than the base.
"""

from __future__ import annotations

import math

import numpy as np

from render.df import _kernel_common as kc
from render.df._registry import Df, Node
from render.df._signature import THIN_WALLED, Param, Signature
from render.jit import njit

__all__ = ["CoatAbsorptionFactor", "coat_absorption_factor", "SIGNATURE", "scale"]

#: ``df::coat_absorption_factor`` plus the renderer's IORs on the ``+z`` and ``-z`` sides
SIGNATURE = Signature("bsdf", (
    Param("ior", "color", (1.0, 1.0, 1.0)),
    Param("absorption_coefficient", "color", (0.0, 0.0, 0.0), clamp=(0.0, None)),
    Param("thickness", "float", 0.0, clamp=(0.0, None)),
    Param("base", "bsdf", None),
), context=("ior_outside", "ior_inside"))
_IOR = SIGNATURE.offset("ior")
_SA = SIGNATURE.offset("absorption_coefficient")
_D = SIGNATURE.offset("thickness")
_OUT = SIGNATURE.offset("ior_outside")
_IN = SIGNATURE.offset("ior_inside")


@njit
def _channel(sa, d, ior, e1, nk1, nk2, half):
    """One channel's attenuation ``exp(-sigma_a d (1/cos1' + 1/cos2') [/ 2])``."""
    depth = sa * d
    if not depth > 0.0 or not ior > 0.0:
        return 1.0
    eta = e1 / ior
    if not eta <= 1.0:
        return 1.0  # a coat less dense than the medium: no absorption (libbsdf)
    c1 = math.sqrt(max(1.0 - eta * eta * (1.0 - nk1 * nk1), 0.0))
    c2 = math.sqrt(max(1.0 - eta * eta * (1.0 - nk2 * nk2), 0.0))
    if not (c1 > 0.0 and c2 > 0.0):
        return 0.0
    dist = 1.0 / c1 + 1.0 / c2
    if half:
        dist *= 0.5
    return math.exp(-depth * dist)


@njit
def scale(P, row, b, flags, wox, woy, woz, wix, wiy, wiz):
    """the coat's attenuation per channel for the pair ``(wo, wi)``."""
    nk1 = min(abs(woz), 1.0)
    nk2 = min(abs(wiz), 1.0)
    if not (nk1 > kc.COS_ZERO and nk2 > kc.COS_ZERO):
        return 0.0, 0.0, 0.0
    inside = woz < 0.0 and (flags & THIN_WALLED) == 0
    e1 = P[row, b + _IN] if inside else P[row, b + _OUT]
    half = woz * wiz < 0.0
    d = P[row, b + _D]
    return (_channel(P[row, b + _SA], d, P[row, b + _IOR], e1, nk1, nk2, half),
            _channel(P[row, b + _SA + 1], d, P[row, b + _IOR + 1], e1, nk1, nk2, half),
            _channel(P[row, b + _SA + 2], d, P[row, b + _IOR + 2], e1, nk1, nk2, half))


def _check(values: dict) -> None:
    ior = np.asarray(values["ior"], dtype=np.float64)
    if not np.all(np.isfinite(ior)) or np.any(ior <= 0.0):
        raise ValueError(f"df::coat_absorption_factor: ior must be > 0 (the coat's index of "
                         f"refraction), got {values['ior']!r}")


NODE = Node("coat_absorption_factor", "bsdf", "modifier", SIGNATURE, scale=scale)
DF = Df("coat_absorption_factor", SIGNATURE, (NODE,), check=_check)
CoatAbsorptionFactor = DF.cls
coat_absorption_factor = CoatAbsorptionFactor
