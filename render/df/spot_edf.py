"""MDL ``df::spot_edf``: a cosine-power spot lobe, cut off at ``spread``, local or global.

MDL signature::

    edf spot_edf(uniform float exponent, uniform float spread = math::PI,
                 uniform bool global_distribution = true,
                 uniform float3x3 global_frame = float3x3(1.0), uniform string handle = "");

Model (libbsdf, ``reference/mdl-distribution-functions.md`` §5).  With
``s = cos(spread / 2)``, ``k = max(exponent, 0)``, ``c = cos`` of the angle between the
emitted direction and the spot axis, and ``t = (c - s) / (1 - s)``::

    eval = t^k (k + 1)(k + 2) / (2 pi (1 - s)(k + 1 + s))   for c > s, else 0
    pdf  = t^k (k + 1) / (2 pi (1 - s)),   weight = eval cos(theta_o) / pdf

normalised so that ``∫ eval c = 1`` over the cone.  The axis is the shading normal
(``global_distribution = false``), or, with ``global_distribution = true`` (MDL's
default), the ``+z`` axis of ``global_frame`` fixed in **object space**: MDL's spec
meaning.  Only directions on the ``+z`` side of the surface emit (front face only;
samples below the horizon fail and ``pdf`` is 0 there).

Departures from libbsdf: libbsdf emits nothing at all when ``global_distribution`` is
true (an unimplemented mode); here it is implemented as the spec describes.  ``spread``
is clamped to ``[TOL.spread_min, pi]`` (the spec range; libbsdf allows up to 2 pi, which
would leave the lobe unnormalised over the emitting hemisphere, and spread 0 would be a
delta beam).
"""

from __future__ import annotations

import math

import numpy as np

from render.df import _kernel_common as kc
from render.df._registry import Df, Node
from render.df._signature import Param, Signature
from render.jit import njit
from render.numerics import TOL
from render.program import BASE, df_class

__all__ = [
    "SpotEdf",
    "spot_edf",
    "SIGNATURE",
    "edf_eval_pdf",
    "edf_sample",
]

_IDENTITY = ((1.0, 0.0, 0.0), (0.0, 1.0, 0.0), (0.0, 0.0, 1.0))


# --- signature and kernels (the compiled render core) ---------------------------------

SIGNATURE = Signature("edf", (
    Param("exponent", "float", uniform=True, clamp=(0.0, None)),
    Param("spread", "float", float(np.pi), uniform=True, clamp=(TOL.spread_min, float(np.pi))),
    Param("global_distribution", "bool", True, uniform=True),
    Param("global_frame", "float3x3", _IDENTITY, uniform=True),
    Param("handle", "string", "", uniform=True),
), context=tuple(f"object_to_local_{i}{j}" for i in range(3) for j in range(3)))
"""``object_to_local_ij`` is ``M[i, j]`` of the rotation ``M`` from object space into the
lane's local shading frame (``local = M @ v``; rows ``s``, ``t``, ``n`` of the frame, as
``material.shade`` passes ``object_to_local`` to :class:`SpotEdf`).  ``global_frame`` is
packed row-major (``float3x3``); the spot axis is its column 2 (slots 2, 5, 8)."""
_EXPONENT = SIGNATURE.offset("exponent")
_SPREAD = SIGNATURE.offset("spread")
_GLOBAL = SIGNATURE.offset("global_distribution")
_FRAME = SIGNATURE.offset("global_frame")
_O2L = SIGNATURE.offset("object_to_local_00")
_TWO_PI = 2.0 * float(np.pi)


@njit
def _pow(t, k):
    """``t ** k`` as numpy evaluates it for an array ``t`` and a float ``k`` (its fast
    paths for ``k`` = 0, 0.5, 1 and 2; libm's ``pow`` otherwise)."""
    if k == 2.0:
        return t * t
    if k == 1.0:
        return t
    if k == 0.0:
        return 1.0
    if k == 0.5:
        return math.sqrt(t)
    return math.pow(t, k)


@njit
def _spot(P, row, b):
    """The lane's lobe -> ``(k, 1 - s, norm_eval, norm_pdf, ax, ay, az, valid)``:
    :class:`SpotEdf`'s constructor per lane (``valid`` False where ``global_frame`` maps
    ``+z`` to a zero vector, which the earlier numpy class rejects)."""
    k = max(P[row, b + _EXPONENT], 0.0)
    spread = min(max(P[row, b + _SPREAD], kc.SPREAD_MIN), kc.PI)
    s = math.cos(0.5 * spread)
    sn = math.sin(0.25 * spread)
    oms = 2.0 * (sn * sn)  # 1 - s without cancellation
    norm_eval = (k + 1.0) * (k + 2.0) / (_TWO_PI * oms * (k + 1.0 + s))
    norm_pdf = (k + 1.0) / (_TWO_PI * oms)
    if P[row, b + _GLOBAL] == 0.0:
        return k, oms, norm_eval, norm_pdf, 0.0, 0.0, 1.0, True
    # the axis: object_to_local @ (global_frame column 2)
    vx = P[row, b + _FRAME + 2]
    vy = P[row, b + _FRAME + 5]
    vz = P[row, b + _FRAME + 8]
    o = b + _O2L
    ax = P[row, o] * vx + P[row, o + 1] * vy + P[row, o + 2] * vz
    ay = P[row, o + 3] * vx + P[row, o + 4] * vy + P[row, o + 5] * vz
    az = P[row, o + 6] * vx + P[row, o + 7] * vy + P[row, o + 8] * vz
    ax, ay, az, ok = kc.unitize(ax, ay, az)
    return k, oms, norm_eval, norm_pdf, ax, ay, az, ok


@njit
def _t(wox, woy, woz, ax, ay, az, oms):
    """the spot's cosine: ``max((c - s)/(1 - s), 0)`` and the emitting test."""
    dx = wox - ax
    dy = woy - ay
    dz = woz - az
    t = 1.0 - 0.5 * kc.dot3(dx, dy, dz, dx, dy, dz) / oms
    return max(t, 0.0), t > 0.0 and woz > kc.COS_ZERO


@njit
def edf_eval_pdf(P, row, b, flags, wox, woy, woz):
    """Emission per unit intensity toward ``wo`` and its density -> ``(e0, e1, e2, pdf)``."""
    k, oms, norm_eval, norm_pdf, ax, ay, az, valid = _spot(P, row, b)
    if not valid:
        return 0.0, 0.0, 0.0, 0.0
    t, ok = _t(wox, woy, woz, ax, ay, az, oms)
    if not ok:
        return 0.0, 0.0, 0.0, 0.0
    tk = _pow(t, k)
    e = norm_eval * tk
    return e, e, e, norm_pdf * tk


@njit
def edf_sample(P, row, b, flags, u1, u2x, u2y):
    """An emission direction in the cone -> ``(wox, woy, woz, pdf, w0, w1, w2)``
    (weight ``eval cos / pdf``)."""
    k, oms, norm_eval, norm_pdf, ax, ay, az, valid = _spot(P, row, b)
    if not valid:
        return 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0
    # t = (1 - u)^(1/(k+1)); 1 - cos = (1 - s)(1 - t)
    t = math.exp(math.log1p(-kc.clamp_u(u2y)) / (k + 1.0))
    omc = oms * (1.0 - t)
    c = 1.0 - omc
    st = math.sqrt(max(omc * (2.0 - omc), 0.0))
    phi = _TWO_PI * kc.clamp_u(u2x)
    dx = st * math.cos(phi)
    dy = st * math.sin(phi)
    if P[row, b + _GLOBAL] == 0.0:
        wox, woy, woz = dx, dy, c
    else:
        sx, sy, sz, tx, ty, tz = kc.frame_from_normal(ax, ay, az)
        wox = dx * sx + dy * tx + c * ax
        woy = dx * sy + dy * ty + c * ay
        woz = dx * sz + dy * tz + c * az
    tt, ok = _t(wox, woy, woz, ax, ay, az, oms)
    if not (ok and tt > 0.0):
        return 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0
    tk = _pow(tt, k)
    pdf = norm_pdf * tk
    w = norm_eval * tk * woz / pdf
    return wox, woy, woz, pdf, w, w, w


# --- the Python class ------------------------------------------------------------------

def _check(values: dict) -> None:
    """MDL's constraints, and the object frame a global spot needs."""
    for name in ("exponent", "spread"):
        if not np.all(np.isfinite(np.asarray(values[name], dtype=np.float64))):
            raise ValueError(f"df::spot_edf needs a finite {name}, got {values[name]!r}")
    frame = np.asarray(values["global_frame"], dtype=np.float64)
    if frame.shape != (3, 3) or not np.all(np.isfinite(frame)):
        raise ValueError(f"df::spot_edf: global_frame must be a finite 3x3 matrix (uniform), "
                         f"got shape {frame.shape}")
    if values["global_distribution"]:
        if values["object_to_local"] is None:
            raise ValueError("df::spot_edf with global_distribution = true needs "
                             "object_to_local (the rotation from object space into the "
                             "local shading frame; material.shade passes it), or set "
                             "global_distribution = false")
        if not np.any(frame[:, 2]):
            raise ValueError("df::spot_edf: global_frame maps +z to a zero vector (the spot "
                             "axis); give a rotation")


NODE = Node("spot_edf", "edf", "leaf", SIGNATURE, edf_eval_pdf=edf_eval_pdf,
            edf_sample=edf_sample)
_SpotEdf = df_class(Df("spot_edf", SIGNATURE, (NODE,), check=_check))


class SpotEdf(_SpotEdf):
    __doc__ = _SpotEdf.__doc__

    @property
    def axis(self) -> np.ndarray:
        """(rows, 3): the spot axis in the local shading frame (``+z`` for a local spot;
        ``object_to_local @ global_frame[:, 2]``, unit, for a global one), as the
        kernels compute it."""
        P = self.program.P
        b = self.program.code[self.program.root, BASE]
        out = np.tile([0.0, 0.0, 1.0], (len(P), 1))
        on = P[:, b + _GLOBAL] != 0.0
        g = P[:, b + _FRAME + np.array([2, 5, 8])]
        m = P[:, b + _O2L:b + _O2L + 9].reshape(-1, 3, 3)
        a = np.einsum("nij,nj->ni", m, g)
        length = np.linalg.norm(a, axis=1, keepdims=True)
        a = np.divide(a, length, out=np.zeros_like(a), where=length > 0.0)
        out[on] = a[on]
        return out


spot_edf = SpotEdf
DF = Df("spot_edf", SIGNATURE, (NODE,), constructor=SpotEdf)
