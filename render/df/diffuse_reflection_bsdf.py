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

from render._typing import Arr, ArrayLike
from render.bsdf import (
    Lobe,
)
from render.df import _kernel_common as kc
from render.df._registry import Df, Node
from render.df._signature import Param, Signature
from render.jit import njit

__all__ = [
    "DiffuseReflectionBsdf",
    "diffuse_reflection_bsdf",
    "oren_nayar_albedo",
    "SIGNATURE",
    "eval_pdf",
    "sample",
    "albedo",
]

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
    """The multiple-scattering ``G`` term of one ``mu`` (clamped to [0, 1])."""
    if mu < 0.0:
        mu = 0.0
    elif mu > 1.0:
        mu = 1.0
    s = math.sqrt(max(1.0 - mu * mu, 0.0))
    theta = math.atan2(s, mu)
    return s * (theta - s * mu) + (2.0 / 3.0) * s * (mu * (1.0 + s + s * s) / (1.0 + s) - 1.0)


@njit
def _value(P, row, b, wox, woy, woz, wix, wiy, wiz):
    """the diffuse sample weight for an oriented ``wo`` -> ``(v0, v1, v2, valid)``:
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
    pdf = wiz * kc.INV_PI
    return v0 * pdf, v1 * pdf, v2 * pdf, pdf


@njit
def sample(P, row, b, flags, wox, woy, woz, u1, u2x, u2y):
    """Cosine-weighted sample of one lane -> ``(wix, wiy, wiz, pdf, w0, w1, w2, lobe)``."""
    flip, woz = kc.orient(woz)
    wix, wiy, wiz = kc.cosine_hemisphere(kc.clamp_u(u2x), kc.clamp_u(u2y))
    v0, v1, v2, valid = _value(P, row, b, wox, woy, woz, wix, wiy, wiz)
    if not valid:
        return 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0
    return (wix, wiy, kc.mirror_z(wiz, flip), wiz * kc.INV_PI, v0, v1, v2,
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
    rho, omr = _rho(mu, sigma)
    return rho * t0 + omr * m0, rho * t1 + omr * m1, rho * t2 + omr * m2


@njit
def _rho(mu, sigma):
    """The white single-scattering albedo ``rho(mu) = A + B G(mu) / pi`` and ``1 - rho``
    (``B (C_A - G/pi)``, no cancellation at small ``sigma``)."""
    a = 1.0 / (1.0 + _K_C_A * sigma)
    g = _g_kernel(mu)
    return a + sigma * a * g / _PI, sigma * a * max(_K_C_A - g / _PI, 0.0)


@njit
def _rho_lanes(mu, sigma, out):
    for i in range(mu.shape[0]):
        out[i] = _rho(mu[i], sigma)[0]


# --- the Python class ------------------------------------------------------------------

NODE = Node("diffuse_reflection_bsdf", "bsdf", "leaf", SIGNATURE, eval_pdf=eval_pdf,
            sample=sample, albedo=albedo)
DF = Df("diffuse_reflection_bsdf", SIGNATURE, (NODE,), lobes=Lobe.DIFFUSE_REFLECTION)
DiffuseReflectionBsdf = DF.cls
diffuse_reflection_bsdf = DiffuseReflectionBsdf


def oren_nayar_albedo(mu: ArrayLike, roughness: float) -> Arr:
    """Directional albedo ``rho(mu)`` of the white single-scattering Oren–Nayar lobe
    (the closed form the :func:`albedo` kernel evaluates), for ``mu`` (n,) in [0, 1].

    Examples
    --------
    >>> np.round(oren_nayar_albedo(np.array([1.0, 0.5, 0.0]), 1.0), 4).tolist()
    [0.7765, 0.8653, 1.0]
    """
    mu = np.ascontiguousarray(np.clip(np.asarray(mu, dtype=np.float64), 0.0, 1.0))
    out = np.empty(mu.shape)
    _rho_lanes(mu, float(np.clip(roughness, 0.0, 1.0)), out)
    return out
