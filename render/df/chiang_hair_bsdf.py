"""MDL ``df::chiang_hair_bsdf``: the Chiang et al. hair fibre model, plus a diffuse lobe.

MDL signature (1.5)::

    hair_bsdf chiang_hair_bsdf(float diffuse_reflection_weight = 0.0,
        color diffuse_reflection_tint = color(1.0), float2 roughness_R = float2(0.0),
        float2 roughness_TT = roughness_R, float2 roughness_TRT = roughness_TT,
        float cuticle_angle = 0.0, color absorption_coefficient = color(0.0),
        float ior = 1.55, uniform string handle = "");

The fibre frame (as libbsdf): the fibre runs along ``tangent_u`` (local ``+x``), the
shading normal (``+z``) is the fibre's outward normal at the hit, ``+y`` completes the
frame.  For a direction ``w``: ``sin theta = w.x`` (against the normal plane), the
azimuth ``phi = atan2(w.z, w.y)`` about the fibre, and for ``wo`` the offset across the
fibre ``h = sin gamma_o`` from ``wo``'s projection on the normal plane.  The model
(Chiang, Bitterli, Tappan, Burley 2016, as pbrt-v3 writes it and libbsdf evaluates it):
lobes ``p = 0, 1, 2`` (R, TT, TRT) and ``p = 3`` (everything longer)::

    f(wo, wi) |cos| = sum_p M_p(theta_i, theta_o') A_p N_p(phi)        (wi's solid angle)

* ``M_p``: d'Eon's longitudinal lobe with variance ``v = roughness_X.x`` (at least 1e-7),
  ``theta_o'`` tilted by the cuticle scales (``-2 alpha``, ``alpha``, ``4 alpha`` for R, TT,
  TRT; ``alpha = cuticle_angle``); ``p = 3`` takes TRT's ``v`` untilted;
* ``N_p``: a logistic of scale ``s = sqrt(pi/8) roughness_X.y`` about
  ``Phi = 2 p gamma_t - 2 gamma_o + p pi``, trimmed to ``[-pi, pi]``; ``N_3 = 1 / (2 pi)``;
* ``A_0 = F``, ``A_1 = (1 - F)^2 T``, ``A_2 = A_1 T F``, ``A_3 = A_2 T F / (1 - T F)`` with
  ``F`` the dielectric Fresnel term of ``ior`` at ``cos theta_o cos gamma_o`` and
  ``T = exp(-absorption_coefficient 2 cos gamma_t / cos theta_t)``: lossless for
  ``absorption_coefficient = 0`` (the lobes' sum is 1).

``diffuse_reflection_weight`` ``w`` mixes in a cosine lobe about the normal of
``diffuse_reflection_tint``: ``w diffuse + (1 - w) hair``.  Sampling picks the diffuse
lobe with probability ``w``, then a fibre lobe in proportion to ``A_p`` (channel mean),
samples ``M_p`` exactly (d'Eon) and ``N_p`` by inverting the trimmed logistic; the pdf
is the mixture's density.  Not reciprocal (the model is not), not a surface lobe:
``wi`` covers the whole sphere.
"""

from __future__ import annotations

import math

import numpy as np

from render.bsdf import Lobe
from render.df import _kernel_common as kc
from render.df._registry import Df, Node
from render.df._signature import Param, Signature
from render.jit import njit

__all__ = ["ChiangHairBsdf", "chiang_hair_bsdf", "SIGNATURE", "eval_pdf", "sample", "albedo"]

SIGNATURE = Signature("hair_bsdf", (
    Param("diffuse_reflection_weight", "float", 0.0, clamp=(0.0, 1.0)),
    Param("diffuse_reflection_tint", "color", (1.0, 1.0, 1.0), clamp=(0.0, 1.0)),
    Param("roughness_R", "float2", (0.0, 0.0), clamp=(0.0, None)),
    Param("roughness_TT", "float2", "roughness_R", clamp=(0.0, None)),
    Param("roughness_TRT", "float2", "roughness_TT", clamp=(0.0, None)),
    Param("cuticle_angle", "float", 0.0),
    Param("absorption_coefficient", "color", (0.0, 0.0, 0.0), clamp=(0.0, None)),
    Param("ior", "float", 1.55),
    Param("handle", "string", "", uniform=True),
))
_W = SIGNATURE.offset("diffuse_reflection_weight")
_DT = SIGNATURE.offset("diffuse_reflection_tint")
_RR = SIGNATURE.offset("roughness_R")
_RTT = SIGNATURE.offset("roughness_TT")
_RTRT = SIGNATURE.offset("roughness_TRT")
_ALPHA = SIGNATURE.offset("cuticle_angle")
_SA = SIGNATURE.offset("absorption_coefficient")
_IOR = SIGNATURE.offset("ior")
_PI = math.pi
_TWO_PI = 2.0 * math.pi
_SQRT_PI_8 = math.sqrt(math.pi / 8.0)
_LOG_TWO_PI = math.log(2.0 * math.pi)
_V_MIN = 1e-7
_GLOSSY = int(Lobe.GLOSSY_REFLECTION)
_GLOSSY_T = int(Lobe.GLOSSY_TRANSMISSION)
_DIFFUSE = int(Lobe.DIFFUSE_REFLECTION)


@njit
def _i0(x):
    """The modified Bessel function ``I_0`` by its series, summed to convergence (for
    ``x <= 30``; pbrt's ten terms are 2 % short near 12)."""
    q = 0.25 * x * x
    term = 1.0
    val = 1.0
    for i in range(1, 200):
        term *= q / (i * i)
        val += term
        if term < 1e-17 * val:
            break
    return val


@njit
def _log_i0(x):
    """``log I_0(x)``: the series up to 30, then the asymptotic expansion (4 terms, relative
    error below 1e-8 there)."""
    if x <= 30.0:
        return math.log(_i0(x))
    r = 1.0 / x
    return (x - 0.5 * (_LOG_TWO_PI + math.log(x))
            + math.log1p(r * (0.125 + r * (9.0 / 128.0 + r * (225.0 / 3072.0
                                                                + r * 11025.0 / 98304.0)))))


@njit
def _mp(cos_i, cos_o, sin_i, sin_o, v):
    """d'Eon's longitudinal lobe ``exp(-b) I_0(a) / (2 v sinh(1/v))``, a density over
    ``theta_i`` with measure ``cos dtheta`` (logs throughout: exact for tiny ``v``)."""
    a = cos_i * cos_o / v
    b = sin_i * sin_o / v
    y = 1.0 / v
    log_sinh = y + math.log1p(-math.exp(-2.0 * y)) - math.log(2.0)
    return math.exp(_log_i0(a) - b - math.log(2.0 * v) - log_sinh)


@njit
def _logistic(x, s):
    x = abs(x)
    e = math.exp(-x / s)
    return e / (s * (1.0 + e) * (1.0 + e))


@njit
def _logistic_cdf(x, s):
    return 1.0 / (1.0 + math.exp(-x / s))


@njit
def _np(phi, p, s, gamma_o, gamma_t):
    """The azimuthal lobe of ``p`` (the trimmed logistic), at ``phi``."""
    if p == 3:
        return 1.0 / _TWO_PI
    d = phi - (2.0 * p * gamma_t - 2.0 * gamma_o + p * _PI)
    d = d - _TWO_PI * math.floor((d + _PI) / _TWO_PI)  # into [-pi, pi)
    k = _logistic_cdf(_PI, s) - _logistic_cdf(-_PI, s)
    return _logistic(d, s) / k


@njit
def _sample_trimmed_logistic(u, s):
    k = _logistic_cdf(_PI, s) - _logistic_cdf(-_PI, s)
    x = -s * math.log(1.0 / (u * k + _logistic_cdf(-_PI, s)) - 1.0)
    return min(max(x, -_PI), _PI)


@njit
def _geometry(P, row, b, wox, woy, woz):
    """``(sin_o, cos_o, phi_o, gamma_o, gamma_t, F, T0, T1, T2)`` of one lane."""
    sin_o = min(max(wox, -1.0), 1.0)
    cos_o = math.sqrt(max(1.0 - sin_o * sin_o, 0.0))
    phi_o = math.atan2(woz, woy)
    ln = math.hypot(woy, woz)
    cg = woz / ln if ln > 0.0 else 1.0
    sg = math.sqrt(max(1.0 - cg * cg, 0.0))
    if ln > 0.0 and woy > 0.0:
        sg = -sg
    gamma_o = math.asin(min(max(sg, -1.0), 1.0))
    eta = P[row, b + _IOR]
    sin_t = sin_o / eta
    cos_t = math.sqrt(max(1.0 - sin_t * sin_t, 0.0))
    eta_p = math.sqrt(max(eta * eta - sin_o * sin_o, 0.0)) / max(cos_o, 1e-8)
    sg_t = min(max(sg / eta_p, -1.0), 1.0) if eta_p > 0.0 else 0.0
    gamma_t = math.asin(sg_t)
    F = kc.fresnel_dielectric(max(cos_o * cg, 0.0), eta)[0]
    dist = 2.0 * math.sqrt(max(1.0 - sg_t * sg_t, 0.0)) / max(cos_t, 1e-8)
    t0 = math.exp(-P[row, b + _SA] * dist)
    t1 = math.exp(-P[row, b + _SA + 1] * dist)
    t2 = math.exp(-P[row, b + _SA + 2] * dist)
    return sin_o, cos_o, phi_o, gamma_o, gamma_t, F, t0, t1, t2


@njit
def _ap(p, F, t):
    """``A_p`` of one channel of transmittance ``t``."""
    a = (1.0 - F) * (1.0 - F) * t
    if p == 0:
        return F
    if p == 1:
        return a
    if p == 2:
        return a * t * F
    tf = t * F
    return a * t * F * tf / (1.0 - tf) if tf < 1.0 else 0.0


@njit
def _lobe_params(P, row, b, p):
    """``(v, s, tilt)`` of lobe ``p``: roughness and the cuticle tilt of ``theta_o``."""
    at = _RR if p == 0 else (_RTT if p == 1 else _RTRT)
    v = max(P[row, b + at], _V_MIN)
    s = max(P[row, b + at + 1] * _SQRT_PI_8, _V_MIN)
    alpha = P[row, b + _ALPHA]
    tilt = -2.0 * alpha if p == 0 else (alpha if p == 1 else (4.0 * alpha if p == 2 else 0.0))
    return v, s, tilt


@njit
def _hair(P, row, b, wox, woy, woz, wix, wiy, wiz):
    """The fibre lobes -> ``(f0, f1, f2, pdf)`` (``f`` with the cosine: per ``wi``'s solid
    angle)."""
    sin_o, cos_o, phi_o, gamma_o, gamma_t, F, t0, t1, t2 = _geometry(P, row, b, wox, woy, woz)
    sin_i = min(max(wix, -1.0), 1.0)
    cos_i = math.sqrt(max(1.0 - sin_i * sin_i, 0.0))
    phi = math.atan2(wiz, wiy) - phi_o
    f0 = f1 = f2 = 0.0
    pdf = 0.0
    total = 0.0
    for p in range(4):
        total += (_ap(p, F, t0) + _ap(p, F, t1) + _ap(p, F, t2)) / 3.0
    if not total > 0.0:
        return 0.0, 0.0, 0.0, 0.0
    for p in range(4):
        v, s, tilt = _lobe_params(P, row, b, p)
        st, ct = math.sin(tilt), math.cos(tilt)
        so = sin_o * ct + cos_o * st
        co = abs(cos_o * ct - sin_o * st)
        mn = _mp(cos_i, co, sin_i, so, v) * _np(phi, p, s, gamma_o, gamma_t)
        a0, a1, a2 = _ap(p, F, t0), _ap(p, F, t1), _ap(p, F, t2)
        f0 += mn * a0
        f1 += mn * a1
        f2 += mn * a2
        pdf += mn * (a0 + a1 + a2) / 3.0 / total
    return f0, f1, f2, pdf


@njit
def _eval(P, row, b, wox, woy, woz, wix, wiy, wiz):
    w = P[row, b + _W]
    f0 = f1 = f2 = pdf = 0.0
    if w < 1.0:
        h0, h1, h2, hp = _hair(P, row, b, wox, woy, woz, wix, wiy, wiz)
        f0, f1, f2, pdf = (1.0 - w) * h0, (1.0 - w) * h1, (1.0 - w) * h2, (1.0 - w) * hp
    if w > 0.0 and wiz > kc.COS_ZERO:
        d = wiz / _PI
        f0 += w * P[row, b + _DT] * d
        f1 += w * P[row, b + _DT + 1] * d
        f2 += w * P[row, b + _DT + 2] * d
        pdf += w * d
    if not (max(max(f0, f1), f2) > 0.0 and pdf > 0.0):
        return 0.0, 0.0, 0.0, 0.0
    return f0, f1, f2, pdf


@njit
def eval_pdf(P, row, b, flags, wox, woy, woz, wix, wiy, wiz):
    """``f |cos|`` (per ``wi``'s solid angle) and the pdf of :func:`sample`."""
    if not (P[row, b + _IOR] > 0.0) or (wox == 0.0 and woy == 0.0 and woz == 0.0):
        return 0.0, 0.0, 0.0, 0.0
    return _eval(P, row, b, wox, woy, woz, wix, wiy, wiz)


@njit
def sample(P, row, b, flags, wox, woy, woz, u1, u2x, u2y):
    """-> ``(wix, wiy, wiz, pdf, w0, w1, w2, lobe)`` (all 0 where the sample fails)."""
    u1 = kc.clamp_u(u1)
    u2x = kc.clamp_u(u2x)
    u2y = kc.clamp_u(u2y)
    if not P[row, b + _IOR] > 0.0:
        return 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0
    w = P[row, b + _W]
    if u1 < w:
        wix, wiy, wiz = kc.cosine_hemisphere(u2x, u2y)
        lobe = _DIFFUSE
    else:
        u1 = min((u1 - w) / (1.0 - w), kc.ONE_MINUS_EPS)
        sin_o, cos_o, phi_o, gamma_o, gamma_t, F, t0, t1, t2 = _geometry(P, row, b, wox, woy,
                                                                         woz)
        total = 0.0
        for q in range(4):
            total += (_ap(q, F, t0) + _ap(q, F, t1) + _ap(q, F, t2)) / 3.0
        if not total > 0.0:
            return 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0
        p = 3
        cdf = 0.0
        ap = 0.0
        for q in range(4):
            ap = (_ap(q, F, t0) + _ap(q, F, t1) + _ap(q, F, t2)) / 3.0
            if u1 * total < cdf + ap and ap > 0.0:
                p = q
                break
            cdf += ap
        u1 = min(max((u1 * total - cdf) / ap, 0.0), kc.ONE_MINUS_EPS) if ap > 0.0 else 0.5
        v, s, tilt = _lobe_params(P, row, b, p)
        st, ct = math.sin(tilt), math.cos(tilt)
        so = sin_o * ct + cos_o * st
        co = abs(cos_o * ct - sin_o * st)
        # d'Eon's longitudinal sampling
        uu = max(u2x, 1e-5)
        cos_t = 1.0 + v * math.log(uu + (1.0 - uu) * math.exp(-2.0 / v))
        sin_t = math.sqrt(max(1.0 - cos_t * cos_t, 0.0))
        sin_i = -cos_t * so + sin_t * math.cos(_TWO_PI * u2y) * co
        sin_i = min(max(sin_i, -1.0), 1.0)
        cos_i = math.sqrt(max(1.0 - sin_i * sin_i, 0.0))
        if p < 3:
            dphi = 2.0 * p * gamma_t - 2.0 * gamma_o + p * _PI + _sample_trimmed_logistic(u1, s)
        else:
            dphi = _TWO_PI * u1
        phi_i = phi_o + dphi
        wix, wiy, wiz = sin_i, cos_i * math.cos(phi_i), cos_i * math.sin(phi_i)
        lobe = _GLOSSY if p == 0 else _GLOSSY_T
    f0, f1, f2, pdf = _eval(P, row, b, wox, woy, woz, wix, wiy, wiz)
    if not pdf > 0.0:
        return 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0
    return wix, wiy, wiz, pdf, f0 / pdf, f1 / pdf, f2 / pdf, lobe


@njit
def albedo(P, row, b, flags, wox, woy, woz):
    """The fibre lobes' albedo ``sum_p A_p`` mixed with the diffuse lobe's tint (the
    longitudinal and azimuthal lobes are normalised; cuticle tilts and the trimming of
    ``M_p`` at the poles make it approximate, as the model is)."""
    w = P[row, b + _W]
    sin_o, cos_o, phi_o, gamma_o, gamma_t, F, t0, t1, t2 = _geometry(P, row, b, wox, woy, woz)
    a0 = a1 = a2 = 0.0
    for p in range(4):
        a0 += _ap(p, F, t0)
        a1 += _ap(p, F, t1)
        a2 += _ap(p, F, t2)
    return ((1.0 - w) * a0 + w * P[row, b + _DT], (1.0 - w) * a1 + w * P[row, b + _DT + 1],
            (1.0 - w) * a2 + w * P[row, b + _DT + 2])


def _check(values: dict) -> None:
    ior = np.asarray(values["ior"], dtype=np.float64)
    if not np.all(np.isfinite(ior)) or np.any(ior <= 0.0):
        raise ValueError(f"df::chiang_hair_bsdf: ior must be > 0 (the fibre's index of "
                         f"refraction, 1.55 for keratin), got {values['ior']!r}")
    a = np.asarray(values["cuticle_angle"], dtype=np.float64)
    if not np.all(np.abs(a) < np.pi / 2):
        raise ValueError("df::chiang_hair_bsdf: cuticle_angle must be in (-pi/2, pi/2) "
                         f"radians, got {values['cuticle_angle']!r}")


NODE = Node("chiang_hair_bsdf", "bsdf", "leaf", SIGNATURE, eval_pdf=eval_pdf, sample=sample,
            albedo=albedo)
DF = Df("chiang_hair_bsdf", SIGNATURE, (NODE,), lobes=Lobe.GLOSSY | Lobe.DIFFUSE_REFLECTION,
        check=_check)
ChiangHairBsdf = DF.cls
chiang_hair_bsdf = ChiangHairBsdf
