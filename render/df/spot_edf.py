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

from render._typing import Arr, Arr2, ArrayLike, Rgb, Vec3
from render.bsdf import Edf, EdfSample, check_dirs, check_samples
from render.df import _kernel_common as kc
from render.df._signature import Param, Signature
from render.frame import Frame
from render.jit import njit
from render.numerics import TOL, dot, unitize

__all__ = ["SpotEdf", "spot_edf"]

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
    ``+z`` to a zero vector, which the numpy class rejects)."""
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
    """``SpotEdf._t``: ``max((c - s)/(1 - s), 0)`` and the emitting test."""
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


# --- the numpy reference (deleted once the program adapters replace it) ----------------


class SpotEdf(Edf):
    """``df::spot_edf`` over lanes.

    Parameters
    ----------
    exponent : float
        Cosine power ``k`` (negative values act as 0).
    spread : float
        Full opening angle in radians, clamped to ``[TOL.spread_min, pi]``.
    global_distribution : bool
        Fix the axis in object space (MDL's default) instead of along the normal.
    global_frame : (3, 3) float64
        Maps distribution-frame vectors to object space (``M @ v``); the axis is
        ``M @ (0, 0, 1)``.
    object_to_local : (3, 3) or (n, 3, 3) float64, optional
        Rotation from object space into each lane's local shading frame, which the
        renderer knows.  Required when ``global_distribution`` is true.

    Examples
    --------
    >>> e = spot_edf(exponent=0.0, spread=np.pi, global_distribution=False)
    >>> bool(np.allclose(e.eval(np.array([[0.0, 0.6, 0.8]])), 1 / np.pi))
    True
    >>> spot_edf(exponent=2.0)
    Traceback (most recent call last):
    ...
    ValueError: spot_edf(global_distribution=True) needs object_to_local: ...
    """

    def __init__(
        self,
        exponent: float,
        spread: float = np.pi,
        global_distribution: bool = True,
        global_frame: ArrayLike = _IDENTITY,
        object_to_local: ArrayLike | None = None,
    ):
        if not (np.isfinite(exponent) and np.isfinite(spread)):
            raise ValueError(
                f"spot_edf needs a finite exponent and spread, got {exponent!r}, {spread!r}"
            )
        self.exponent = max(float(exponent), 0.0)
        self.spread = float(np.clip(spread, TOL.spread_min, np.pi))
        self.global_distribution = bool(global_distribution)
        # s = cos(spread/2); 1 - s = 2 sin^2(spread/4) without cancellation
        self.cos_spread = float(np.cos(0.5 * self.spread))
        self.one_minus_s = float(2.0 * np.sin(0.25 * self.spread) ** 2)
        k, s = self.exponent, self.cos_spread
        self._norm_eval = (k + 1.0) * (k + 2.0) / (2.0 * np.pi * self.one_minus_s * (k + 1.0 + s))
        self._norm_pdf = (k + 1.0) / (2.0 * np.pi * self.one_minus_s)
        if self.global_distribution:
            if object_to_local is None:
                raise ValueError(
                    "spot_edf(global_distribution=True) needs object_to_local: the rotation "
                    "from object space into the local shading frame (or pass "
                    "global_distribution=False)"
                )
            gf = np.asarray(global_frame, dtype=np.float64)
            o2l = np.asarray(object_to_local, dtype=np.float64)
            if gf.shape != (3, 3) or o2l.shape[-2:] != (3, 3) or o2l.ndim not in (2, 3):
                raise ValueError(
                    f"global_frame must be (3, 3) and object_to_local (3, 3) or (n, 3, 3); "
                    f"got {gf.shape} and {o2l.shape}"
                )
            axis, ok = unitize((o2l @ gf[:, 2]).reshape(-1, 3))
            if not np.all(ok):
                raise ValueError("spot_edf: global_frame maps +z to a zero vector")
            self.axis = axis
        else:
            self.axis = np.array([[0.0, 0.0, 1.0]])

    def __repr__(self) -> str:
        return (
            f"spot_edf(exponent={self.exponent}, spread={self.spread}, "
            f"global_distribution={self.global_distribution})"
        )

    def _t(self, wo: Vec3) -> tuple[Arr, np.ndarray]:
        """``t = (c - s)/(1 - s)`` (``1 - c`` from ``|wo - axis|^2 / 2``) and the emitting mask."""
        axis = np.broadcast_to(self.axis, wo.shape)
        one_minus_c = 0.5 * dot(wo - axis, wo - axis)
        t = 1.0 - one_minus_c / self.one_minus_s
        return np.maximum(t, 0.0), (t > 0.0) & (wo[:, 2] > TOL.cos_zero)

    def eval(self, wo: Vec3) -> Rgb:
        (wo,) = check_dirs(wo, names=("wo",))
        t, ok = self._t(wo)
        v = np.where(ok, self._norm_eval * t**self.exponent, 0.0)
        return np.repeat(v[:, None], 3, axis=1)

    def pdf(self, wo: Vec3) -> Arr:
        (wo,) = check_dirs(wo, names=("wo",))
        t, ok = self._t(wo)
        return np.where(ok, self._norm_pdf * t**self.exponent, 0.0)

    def sample(self, u1: Arr, u2: Arr2) -> EdfSample:
        n = len(np.asarray(u2))
        u1, u2 = check_samples(n, u1, u2)
        # t = (1 - u)^(1/(k+1)); 1 - cos = (1 - s)(1 - t)
        t = np.exp(np.log1p(-u2[:, 1]) / (self.exponent + 1.0))
        one_minus_c = self.one_minus_s * (1.0 - t)
        c = 1.0 - one_minus_c
        st = np.sqrt(np.maximum(one_minus_c * (2.0 - one_minus_c), 0.0))
        phi = 2.0 * np.pi * u2[:, 0]
        d = np.stack([st * np.cos(phi), st * np.sin(phi), c], axis=1)
        axis = np.broadcast_to(self.axis, (n, 3))
        wo = d if not self.global_distribution else Frame.from_normal(axis).to_world(d)
        tt, ok = self._t(wo)
        ok &= tt > 0.0
        pdf = np.where(ok, self._norm_pdf * tt**self.exponent, 0.0)
        ev = np.where(ok, self._norm_eval * tt**self.exponent, 0.0)
        w = np.where(ok, ev * wo[:, 2] / np.where(ok, pdf, 1.0), 0.0)
        return EdfSample(np.where(ok[:, None], wo, 0.0), pdf, np.repeat(w[:, None], 3, axis=1))


spot_edf = SpotEdf
