"""MDL ``df::diffuse_reflection_bsdf``: Lambert, or Fujii's improved Oren–Nayar above roughness 0.

MDL signature (1.10)::

    bsdf diffuse_reflection_bsdf(color tint = color(1.0), float roughness = 0.0,
                                 color multiscatter_tint = color(0.0),
                                 uniform string handle = "");

Model (libbsdf, ``reference/mdl-distribution-functions.md`` §2.1).  With
``sigma = saturate(roughness)``, ``A = 1 / (1 + (1/2 - 2/(3 pi)) sigma)``, ``B = sigma A``,
``mu1 = wo.z``, ``mu2 = wi.z`` and ``s = wo.wi - mu1 mu2`` (divided by
``max(mu1, mu2)`` when positive)::

    eval = mu2/pi * ( saturate(tint) (A + B s)
                      + saturate(multiscatter_tint) (1 - rho(mu1)) (1 - rho(mu2)) / (1 - rho_avg) )

where ``rho(mu)`` is the single-scattering directional albedo (exact, closed form) and
``rho_avg = A + (2/3 - 28/(15 pi)) B`` its cosine-weighted average.  With
``multiscatter_tint = 1`` the white lobe loses no energy (EON's compensation).  At
``roughness = 0`` this is Lambert, ``tint mu2 / pi``.  Sampling is cosine-weighted.

Departures from libbsdf: the ``1 / (pi/2 (1 + n.ng))`` renormalisation for shading
normals that differ from the geometric normal is left to the integrator (in the local
frame ``n = ng``; see :mod:`render.frame`).  ``handle`` only tags lobes and is not taken.

References: Fujii, "A tiny improvement of Oren-Nayar reflectance model" (2013);
Portsmouth et al., "EON: a practical energy-preserving rough diffuse BRDF" (2025).
"""

from __future__ import annotations

import math

import numpy as np

from render._typing import Arr, Arr2, ArrayLike, Rgb, Vec3
from render.bsdf import (
    Bsdf,
    BsdfSample,
    Lobe,
    check_dirs,
    check_samples,
    lane_color,
    lane_float,
    lanes,
)
from render.df import _kernel_common as kc
from render.df._common import INV_PI, orient
from render.df._signature import Param, Signature
from render.frame import mirror_z
from render.jit import njit
from render.numerics import TOL, check_finite, dot, safe_sqrt, saturate
from render.warp import square_to_cosine_hemisphere

__all__ = ["DiffuseReflectionBsdf", "diffuse_reflection_bsdf", "oren_nayar_albedo"]

#: ``1 - A = C_A sigma A``
_C_A = 0.5 - 2.0 / (3.0 * np.pi)
#: ``rho_avg = A + C_AVG B``
_C_AVG = 2.0 / 3.0 - 28.0 / (15.0 * np.pi)


# --- signature and kernels (the compiled render core) ---------------------------------

SIGNATURE = Signature("bsdf", (
    Param("tint", "color", (1.0, 1.0, 1.0), clamp=(0.0, 1.0)),
    Param("roughness", "float", 0.0, clamp=(0.0, 1.0)),
    Param("multiscatter_tint", "color", (0.0, 0.0, 0.0), clamp=(0.0, 1.0)),
    Param("handle", "string", "", uniform=True),
))
_TINT = SIGNATURE.offset("tint")
_ROUGHNESS = SIGNATURE.offset("roughness")
_MS_TINT = SIGNATURE.offset("multiscatter_tint")
_PI = float(np.pi)
_K_C_A = float(_C_A)
_K_C_AVG = float(_C_AVG)


@njit
def _g_kernel(mu):
    """:func:`_g` of one ``mu`` (clamped to [0, 1])."""
    if mu < 0.0:
        mu = 0.0
    elif mu > 1.0:
        mu = 1.0
    s = math.sqrt(max(1.0 - mu * mu, 0.0))
    theta = math.atan2(s, mu)
    return s * (theta - s * mu) + (2.0 / 3.0) * s * (mu * (1.0 + s + s * s) / (1.0 + s) - 1.0)


@njit
def _value(P, row, b, wox, woy, woz, wix, wiy, wiz):
    """``DiffuseReflectionBsdf._value`` for an oriented ``wo`` -> ``(v0, v1, v2, valid)``:
    the sample weight ``eval / pdf``."""
    t0, t1, t2 = P[row, b + _TINT], P[row, b + _TINT + 1], P[row, b + _TINT + 2]
    sigma = P[row, b + _ROUGHNESS]
    m0, m1, m2 = P[row, b + _MS_TINT], P[row, b + _MS_TINT + 1], P[row, b + _MS_TINT + 2]
    black = t0 == 0.0 and t1 == 0.0 and t2 == 0.0 and m0 == 0.0 and m1 == 0.0 and m2 == 0.0
    mu1 = woz
    mu2 = wiz
    if not (mu1 > kc.COS_ZERO and mu2 > kc.COS_ZERO) or black:
        return 0.0, 0.0, 0.0, False
    if not sigma > 0.0:
        return t0, t1, t2, True  # Lambert
    # Fujii's Oren–Nayar: s / t with t = max(mu1, mu2) where s > 0
    a = 1.0 / (1.0 + _K_C_A * sigma)
    bb = sigma * a
    s = max(kc.dot3(wox, woy, woz, wix, wiy, wiz) - mu1 * mu2, -1.0)
    tmax = max(max(mu1, mu2), kc.COS_ZERO)
    if s > 0.0:
        s = s / tmax
    single = a + bb * s
    v0 = single * t0
    v1 = single * t1
    v2 = single * t2
    if m0 > 0.0 or m1 > 0.0 or m2 > 0.0:
        # energy compensation: 1 - rho(mu) = B (C_A - G(mu)/pi)
        e1 = _K_C_A - _g_kernel(mu1) / _PI
        e2 = _K_C_A - _g_kernel(mu2) / _PI
        multi = bb * max(e1, 0.0) * max(e2, 0.0) / (_K_C_A - _K_C_AVG)
        v0 = v0 + multi * m0
        v1 = v1 + multi * m1
        v2 = v2 + multi * m2
    return v0, v1, v2, True


@njit
def eval_pdf(P, row, b, flags, wox, woy, woz, wix, wiy, wiz):
    """``eval`` (with ``|cos theta_i|``) and ``pdf`` of one lane -> ``(f0, f1, f2, pdf)``."""
    flip, woz = kc.orient(woz)
    wiz = kc.mirror_z(wiz, flip)
    v0, v1, v2, valid = _value(P, row, b, wox, woy, woz, wix, wiy, wiz)
    if not valid:
        return 0.0, 0.0, 0.0, 0.0
    pdf = wiz * INV_PI
    return v0 * pdf, v1 * pdf, v2 * pdf, pdf


@njit
def sample(P, row, b, flags, wox, woy, woz, u1, u2x, u2y):
    """Cosine-weighted sample of one lane -> ``(wix, wiy, wiz, pdf, w0, w1, w2, lobe)``."""
    flip, woz = kc.orient(woz)
    wix, wiy, wiz = kc.cosine_hemisphere(kc.clamp_u(u2x), kc.clamp_u(u2y))
    v0, v1, v2, valid = _value(P, row, b, wox, woy, woz, wix, wiy, wiz)
    if not valid:
        return 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0
    return (wix, wiy, kc.mirror_z(wiz, flip), wiz * INV_PI, v0, v1, v2,
            kc.LOBE_DIFFUSE_REFLECTION)


@njit
def albedo(P, row, b, flags, wox, woy, woz):
    """Directional albedo of one lane (closed form) -> ``(a0, a1, a2)``."""
    t0, t1, t2 = P[row, b + _TINT], P[row, b + _TINT + 1], P[row, b + _TINT + 2]
    sigma = P[row, b + _ROUGHNESS]
    m0, m1, m2 = P[row, b + _MS_TINT], P[row, b + _MS_TINT + 1], P[row, b + _MS_TINT + 2]
    black = t0 == 0.0 and t1 == 0.0 and t2 == 0.0 and m0 == 0.0 and m1 == 0.0 and m2 == 0.0
    mu = abs(woz)
    if not mu > kc.COS_ZERO or black:
        return 0.0, 0.0, 0.0
    a = 1.0 / (1.0 + _K_C_A * sigma)
    g = _g_kernel(mu)
    rho = a + sigma * a * g / _PI
    omr = sigma * a * max(_K_C_A - g / _PI, 0.0)
    return rho * t0 + omr * m0, rho * t1 + omr * m1, rho * t2 + omr * m2


# --- the numpy reference (deleted once the program adapters replace it) ----------------


def _g(mu: Arr) -> Arr:
    """``G(theta)`` of the closed-form albedo, ``rho = A + B G / pi``; exact at mu -> 0.

    ``G = sin t (t - sin t cos t) + 2/3 tan t (1 - sin^3 t - cos t)``, with the last factor
    rewritten as ``mu (mu (1 + s + s^2)/(1 + s) - 1)`` (``s = sin t``) so that the
    ``tan t`` pole cancels analytically.
    """
    mu = np.clip(mu, 0.0, 1.0)
    s = safe_sqrt(1.0 - mu * mu)
    theta = np.arctan2(s, mu)
    return s * (theta - s * mu) + (2.0 / 3.0) * s * (mu * (1.0 + s + s * s) / (1.0 + s) - 1.0)


def oren_nayar_albedo(mu: ArrayLike, roughness: ArrayLike) -> Arr:
    """Directional albedo ``rho(mu)`` of the white single-scattering Oren–Nayar lobe.

    Parameters
    ----------
    mu : (n,) float64
        ``cos theta_o`` in [0, 1].
    roughness : float or (n,) float64
        Saturated to [0, 1].

    Returns
    -------
    (n,) float64
        ``A + B G(theta) / pi``; 1 at roughness 0 and at grazing incidence.

    Examples
    --------
    >>> np.round(oren_nayar_albedo(np.array([1.0, 0.5, 0.0]), 1.0), 4).tolist()
    [0.7765, 0.8653, 1.0]
    """
    sigma = saturate(roughness)
    a = 1.0 / (1.0 + _C_A * sigma)
    return a + sigma * a * _g(np.asarray(mu, dtype=np.float64)) / np.pi


class DiffuseReflectionBsdf(Bsdf):
    """``df::diffuse_reflection_bsdf`` over lanes (see the module docstring).

    Parameters
    ----------
    tint : float, (3,) or (n, 3)
        Saturated to [0, 1].
    roughness : float or (n,)
        Oren–Nayar ``sigma``, saturated to [0, 1]; 0 is Lambert.
    multiscatter_tint : float, (3,) or (n, 3)
        Energy-compensation tint (MDL 1.10), saturated; 0 disables the compensation.

    Examples
    --------
    >>> bsdf = diffuse_reflection_bsdf(tint=0.5)
    >>> wo = np.array([[0.0, 0.0, 1.0], [0.0, 0.0, 1.0]])
    >>> wi = np.array([[0.6, 0.0, 0.8], [0.6, 0.0, -0.8]])
    >>> np.round(bsdf.eval(wo, wi) * np.pi, 6).tolist()
    [[0.4, 0.4, 0.4], [0.0, 0.0, 0.0]]
    """

    lobes = Lobe.DIFFUSE_REFLECTION

    def __init__(
        self, tint: ArrayLike = 1.0, roughness: ArrayLike = 0.0, multiscatter_tint: ArrayLike = 0.0
    ):
        self.tint = saturate(lane_color(tint, "tint"))
        self.roughness = saturate(lane_float(roughness, "roughness"))
        self.multiscatter_tint = saturate(lane_color(multiscatter_tint, "multiscatter_tint"))
        self._black = np.all(self.tint == 0, axis=1) & np.all(self.multiscatter_tint == 0, axis=1)
        # terms that are exactly 0 and skipped: roughness 0 (A = 1, B = 0) is Lambert, and
        # multiscatter_tint 0 needs no energy compensation
        self._rough = bool(np.any(self.roughness > 0))
        self._compensated = bool(np.any(self.multiscatter_tint > 0))

    def __repr__(self) -> str:
        return (
            f"diffuse_reflection_bsdf(tint={self.tint.tolist()}, "
            f"roughness={self.roughness.tolist()}, "
            f"multiscatter_tint={self.multiscatter_tint.tolist()})"
        )

    def _params(self, n: int):
        return (
            lanes(self.tint, n, "tint"),
            np.broadcast_to(lanes(self.roughness, n, "roughness"), (n,)),
            lanes(self.multiscatter_tint, n, "multiscatter_tint"),
            np.broadcast_to(lanes(self._black, n, "tint"), (n,)),
        )

    def _value(self, wo: Vec3, wi: Vec3) -> tuple[Rgb, np.ndarray]:
        """``eval / pdf`` (the sample weight) for oriented ``wo``, and validity."""
        n = len(wo)
        tint, sigma, ms_tint, black = self._params(n)
        mu1, mu2 = wo[:, 2], wi[:, 2]
        valid = (mu1 > TOL.cos_zero) & (mu2 > TOL.cos_zero) & ~black
        if not self._rough:
            return np.where(valid[:, None], tint, 0.0), valid  # Lambert
        # Fujii's Oren–Nayar: s / t with t = max(mu1, mu2) where s > 0
        a = 1.0 / (1.0 + _C_A * sigma)
        b = sigma * a
        # s = sin t1 sin t2 cos(dphi) >= -1; rounding can give -1 - ulp at grazing opposite
        # azimuths, and A + B s < 0 with it at sigma = 1 (A = B)
        s = np.maximum(dot(wo, wi) - mu1 * mu2, -1.0)
        tmax = np.maximum(np.maximum(mu1, mu2), TOL.cos_zero)
        s = np.where(s > 0.0, s / tmax, s)
        value = (a + b * s)[:, None] * tint
        if self._compensated:
            # energy compensation: 1 - rho(mu) = B (C_A - G(mu)/pi), no cancellation at small sigma
            e1 = _C_A - _g(mu1) / np.pi
            e2 = _C_A - _g(mu2) / np.pi
            value = value + (
                b * np.maximum(e1, 0.0) * np.maximum(e2, 0.0) / (_C_A - _C_AVG)
            )[:, None] * ms_tint
        return np.where(valid[:, None], value, 0.0), valid

    def eval_pdf(self, wo: Vec3, wi: Vec3) -> tuple[Rgb, Arr]:
        wo, wi = check_dirs(wo, wi)
        _, wo, wi = orient(wo, wi)
        value, valid = self._value(wo, wi)
        pdf = np.where(valid, wi[:, 2] * INV_PI, 0.0)
        return check_finite(
            "diffuse_reflection_bsdf.eval", value * pdf[:, None], nonnegative=True
        ), pdf

    def eval(self, wo: Vec3, wi: Vec3) -> Rgb:
        return self.eval_pdf(wo, wi)[0]

    def pdf(self, wo: Vec3, wi: Vec3) -> Arr:
        return self.eval_pdf(wo, wi)[1]

    def sample(self, wo: Vec3, u1: Arr, u2: Arr2) -> BsdfSample:
        (wo,) = check_dirs(wo, names=("wo",))
        u1, u2 = check_samples(len(wo), u1, u2)
        flip, wo = orient(wo)
        wi = square_to_cosine_hemisphere(u2)
        value, valid = self._value(wo, wi)
        wi = np.where(valid[:, None], mirror_z(wi, flip), 0.0)
        pdf = np.where(valid, wi[:, 2] * np.where(flip, -1.0, 1.0) * INV_PI, 0.0)
        lobe = np.where(valid, int(Lobe.DIFFUSE_REFLECTION), 0).astype(np.int32)
        return BsdfSample(wi, pdf, value, lobe).checked()

    def albedo(self, wo: Vec3) -> Rgb:
        (wo,) = check_dirs(wo, names=("wo",))
        n = len(wo)
        tint, sigma, ms_tint, black = self._params(n)
        mu = np.abs(wo[:, 2])
        rho = oren_nayar_albedo(mu, sigma)
        a = 1.0 / (1.0 + _C_A * sigma)
        one_minus_rho = sigma * a * np.maximum(_C_A - _g(mu) / np.pi, 0.0)
        out = rho[:, None] * tint + one_minus_rho[:, None] * ms_tint
        return np.where(((mu > TOL.cos_zero) & ~black)[:, None], out, 0.0)


diffuse_reflection_bsdf = DiffuseReflectionBsdf
