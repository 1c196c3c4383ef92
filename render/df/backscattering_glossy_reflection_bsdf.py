"""MDL ``df::backscattering_glossy_reflection_bsdf``: a retro-reflective glossy lobe.

MDL signature::

    bsdf backscattering_glossy_reflection_bsdf(
        float roughness_u, float roughness_v = roughness_u, color tint = color(1.0),
        color multiscatter_tint = color(0.0),
        float3 tangent_u = state::texture_tangent_u(0), uniform string handle = "");

Model (libbsdf's halfway-vector disk model, ``reference/mdl-distribution-functions.md``
§2.7).  Exponents ``e = 2 / r^2`` per axis (``r >= 1e-7``) and the disk density, for
``x^2 + y^2 <= 1``::

    p_disk(x, y) = sqrt((e_u + 1)(e_v + 1)) / pi * (1 - x^2 - y^2)^((e_u x^2 + e_v y^2)/(x^2 + y^2))

A disk point ``(x, y)`` is placed at ``wo``'s tip in the plane at height ``n.wo`` and
gives the half vector ``h = normalize(nk1 n + (x + wo_t) t + (y + wo_b) b)``; ``wi`` is
``wo`` mirrored about ``h``, so ``(x, y) = 0`` scatters straight back.  With
``p_k = p_disk((nk/nh) h_t - k_t, (nk/nh) h_b - k_b) (nk/nh)^2 / nh`` for
``k in {wo, wi}`` (the half-vector density seen from either side)::

    eval = saturate(tint) min(p_wo, p_wi) nk2 / (4 (wo.h) max(nk1, nk2))
    pdf  = p_wo / (4 (wo.h)),      weight = tint nk2 min(p_wo, p_wi) / (p_wo max(nk1, nk2))

which is reciprocal and never gains energy (weight <= tint).  Reflection only, no
Fresnel.  Departures: the exponent uses the exact ``log1p`` form (as in
``simple_glossy_bsdf``); ``albedo()`` is tabulated (``_albedo``); ``multiscatter_tint``
adds the energy-compensation lobe of :mod:`render.df._microfacet` from that table.

Compiled kernels (the render core): :data:`SIGNATURE`, :func:`eval_pdf`, :func:`sample`
and :func:`albedo` (with the table arguments ``T, t`` of :func:`albedo_table`, as in
``simple_glossy_bsdf``), bit for bit the earlier numpy class's results
(``tests/render/df/test_backscattering_glossy_reflection_bsdf_kernels.py``).
"""

from __future__ import annotations

import math

import numpy as np

from render.bsdf import (
    Lobe,
)
from render.df import _kernel_common as kc
from render.df._albedo import lanes_table, node_table
from render.df._microfacet import ms_albedo, ms_choice, ms_eval, ms_lobe, ms_on, ms_sampled
from render.df._signature import REQUIRED, Param, Signature
from render.df.simple_glossy_bsdf import as_azimuth
from render.jit import njit
from render.program import O_BACKSCATTERING_GLOSSY, df_class

__all__ = [
    "BackscatteringGlossyReflectionBsdf",
    "backscattering_glossy_reflection_bsdf",
    "SIGNATURE",
    "eval_pdf",
    "sample",
    "albedo",
    "albedo_table",
]

# --- signature and kernels (the compiled render core) ---------------------------------------
SIGNATURE = Signature("bsdf", (
    Param("roughness_u", "float", REQUIRED, clamp=(kc.ROUGHNESS_MIN, None)),
    Param("roughness_v", "float", "roughness_u", clamp=(kc.ROUGHNESS_MIN, None)),
    Param("tint", "color", (1.0, 1.0, 1.0), clamp=(0.0, 1.0)),
    Param("multiscatter_tint", "color", (0.0, 0.0, 0.0), clamp=(0.0, 1.0)),
    Param("tangent_u", "float3", "state::texture_tangent_u(0)"),
    Param("handle", "string", "", uniform=True),
))
_RU = SIGNATURE.offset("roughness_u")
_RV = SIGNATURE.offset("roughness_v")
_TINT = SIGNATURE.offset("tint")
_MS = SIGNATURE.offset("multiscatter_tint")
_TANGENT = SIGNATURE.offset("tangent_u")
_PI = math.pi
_GLOSSY_R = int(Lobe.GLOSSY_REFLECTION)


@njit
def _k_p_disk(x, y, e_u, e_v):
    """``_p_disk`` for one point (0 outside the unit disk)."""
    r2 = x * x + y * y
    if not r2 < 1.0:
        return 0.0
    ratio = math.log1p(-r2) / r2 if r2 > 0.0 else -1.0
    expo = (e_u * x * x + e_v * y * y) * ratio
    norm = math.sqrt((e_u + 1.0) * (e_v + 1.0)) / _PI
    return norm * math.exp(expo)


@njit
def _k_p_half(kx, ky, kz, hx, hy, hz, e_u, e_v, tx, ty):
    """the half-vector density for one lane."""
    kt = kx * tx + ky * ty
    kb = kx * ty - ky * tx
    ht = hx * tx + hy * ty
    hb = hx * ty - hy * tx
    # the disk point can lie in the unit disk only if nk/nh <= 2/|h_tan| (+ rounding)
    if not kz * math.hypot(ht, hb) <= 4.0 * hz:
        return 0.0
    d = kz / hz
    return _k_p_disk(d * ht - kt, d * hb - kb, e_u, e_v) * d * d / hz


@njit
def _setup(P, row, b):
    """``_setup`` for one lane -> ``(ok, e_u, e_v, tx, ty, glossy, ms)``."""
    ru = max(P[row, b + _RU], kc.ROUGHNESS_MIN)
    rv = max(P[row, b + _RV], kc.ROUGHNESS_MIN)
    tx, ty, ok = kc.tangent_axes(P[row, b + _TANGENT], P[row, b + _TANGENT + 1],
                                P[row, b + _TANGENT + 2])
    glossy = not (P[row, b + _TINT] == 0.0 and P[row, b + _TINT + 1] == 0.0
                  and P[row, b + _TINT + 2] == 0.0)
    ms = ms_on(0, P[row, b + _MS], P[row, b + _MS + 1], P[row, b + _MS + 2])
    if not (glossy or ms):
        ok = False
    return ok, 2.0 / (ru * ru), 2.0 / (rv * rv), tx, ty, glossy, ms


@njit
def _value(P, row, b, wox, woy, woz, wix, wiy, wiz, e_u, e_v, tx, ty):
    """``_kernel`` for an oriented lane -> ``(w0, w1, w2, pdf)`` (0 where it does not reach)."""
    nk1 = woz
    nk2 = wiz
    if not (nk1 > kc.COS_ZERO and nk2 > kc.COS_ZERO):
        return 0.0, 0.0, 0.0, 0.0
    hx, hy, hz, hv = kc.unitize(wox + wix, woy + wiy, woz + wiz)
    kh = kc.dot3(wox, woy, woz, hx, hy, hz)
    if not (hv and hz > kc.COS_ZERO and kh > 0.0):
        return 0.0, 0.0, 0.0, 0.0
    p1 = _k_p_half(wox, woy, woz, hx, hy, hz, e_u, e_v, tx, ty)
    p2 = _k_p_half(wix, wiy, wiz, hx, hy, hz, e_u, e_v, tx, ty)
    pmin = min(p1, p2)
    if not (pmin > 0.0 and p1 > 0.0):
        return 0.0, 0.0, 0.0, 0.0
    pdf = p1 / (4.0 * kh)
    # (min(p1, p2)/p1) (nk2 / max(nk1, nk2)): two ratios <= 1, no underflowing product
    ratio = (pmin / p1) * (nk2 / max(nk1, nk2))
    w0 = P[row, b + _TINT] * ratio
    w1 = P[row, b + _TINT + 1] * ratio
    w2 = P[row, b + _TINT + 2] * ratio
    if not max(max(w0 * pdf, w1 * pdf), w2 * pdf) > 0.0:
        return 0.0, 0.0, 0.0, 0.0
    return w0, w1, w2, pdf


@njit
def _ms_lobe(P, row, b, tx, ty, glossy):
    """:func:`ms_lobe` of a lane (the table's roughness: the parameters, not exponents)."""
    return ms_lobe(P, row, b + _MS, P[row, b + _RU], P[row, b + _RV], 1.0, 1.0, tx, ty, glossy)


@njit
def eval_pdf(P, row, b, flags, wox, woy, woz, wix, wiy, wiz, T, t):
    """``f |cos theta_i|`` and the pdf of :func:`sample` -> ``(f0, f1, f2, pdf)`` (``T``,
    ``t``: the node's albedo table, read by the compensation lobe)."""
    if woz < 0.0:  # orient: mirror both through the tangent plane
        woz = -woz
        wiz = -wiz
    ok, e_u, e_v, tx, ty, glossy, ms = _setup(P, row, b)
    if not ok:
        return 0.0, 0.0, 0.0, 0.0
    w0, w1, w2, pdf = _value(P, row, b, wox, woy, woz, wix, wiy, wiz, e_u, e_v, tx, ty)
    if not ms:
        return w0 * pdf, w1 * pdf, w2 * pdf, pdf
    if not woz > kc.COS_ZERO:
        return 0.0, 0.0, 0.0, 0.0
    return ms_eval(T, t, False, _ms_lobe(P, row, b, tx, ty, glossy), wox, woy, woz,
                   wix, wiy, wiz, w0 * pdf, w1 * pdf, w2 * pdf, pdf)


@njit
def _single_sample(wox, woy, woz, u2x, u2y, e_u, e_v, tx, ty):
    """A single-scattering sample -> ``(ok, wix, wiy, wiz)``: a point of the anisotropic
    disk (phi as Ashikhmin–Shirley, r^2 = 1 - (1-u)^(1/(e+1))) placed at wo's tip gives
    the half vector; wi mirrors wo about it."""
    cp, sp = as_azimuth(e_u, e_v, u2x)
    e = e_u * cp * cp + e_v * sp * sp
    r = math.sqrt(max(-math.expm1(math.log1p(-u2y) / (e + 1.0)), 0.0))
    at = r * cp + (wox * tx + woy * ty)
    ab = r * sp + (wox * ty - woy * tx)
    hx, hy, hz, hv = kc.unitize(at * tx + ab * ty, at * ty - ab * tx, woz)
    if not (hv and woz > kc.COS_ZERO):
        return False, 0.0, 0.0, 0.0
    two_c = 2.0 * kc.dot3(wox, woy, woz, hx, hy, hz)
    wix = two_c * hx - wox
    wiy = two_c * hy - woy
    wiz = two_c * hz - woz
    if not wiz > 0.0:
        return False, 0.0, 0.0, 0.0
    return True, wix, wiy, wiz


@njit
def sample(P, row, b, flags, wox, woy, woz, u1, u2x, u2y, T, t):
    """-> ``(wix, wiy, wiz, pdf, w0, w1, w2, lobe)`` (all 0 where the sample fails)."""
    u1 = kc.clamp_u(u1)
    u2x = kc.clamp_u(u2x)
    u2y = kc.clamp_u(u2y)
    flip = woz < 0.0
    if flip:
        woz = -woz
    ok, e_u, e_v, tx, ty, glossy, ms = _setup(P, row, b)
    if not (ok and woz > kc.COS_ZERO):
        return 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0
    single = True
    c = _ms_lobe(P, row, b, tx, ty, glossy)
    if ms:
        single, u1 = ms_choice(T, t, False, c, wox, woy, woz, u1)
    if single:
        ok, wix, wiy, wiz = _single_sample(wox, woy, woz, u2x, u2y, e_u, e_v, tx, ty)
        if not ok:
            return 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0
    else:
        wix, wiy, wiz = kc.cosine_hemisphere(u2x, u2y)
    w0, w1, w2, pdf = _value(P, row, b, wox, woy, woz, wix, wiy, wiz, e_u, e_v, tx, ty)
    if ms:
        w0, w1, w2, pdf = ms_sampled(T, t, False, c, single, wox, woy, woz, wix, wiy, wiz,
                                     w0, w1, w2, pdf)
    if not pdf > 0.0:
        return 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0
    if flip:
        wiz = -wiz
    return wix, wiy, wiz, pdf, w0, w1, w2, _GLOSSY_R


@njit(allocates=True)
def sample_weights(P, flags, wo, pts):
    """First-channel single-scattering sample weights (m, k) on row 0 of ``P`` for each
    ``wo`` (m, 3) and variates ``pts`` (k, 3): the albedo tables' Monte Carlo
    (:mod:`render.df._albedo`)."""
    m, k = wo.shape[0], pts.shape[0]
    out = np.zeros((m, k))
    ok, e_u, e_v, tx, ty, glossy, ms = _setup(P, 0, 0)
    if not ok:
        return out
    for i in range(m):
        woz = abs(wo[i, 2])
        for j in range(k):
            good, wix, wiy, wiz = _single_sample(wo[i, 0], wo[i, 1], woz, kc.clamp_u(pts[j, 1]),
                                                 kc.clamp_u(pts[j, 2]), e_u, e_v, tx, ty)
            if good:
                w0, w1, w2, pdf = _value(P, 0, 0, wo[i, 0], wo[i, 1], woz, wix, wiy, wiz,
                                         e_u, e_v, tx, ty)
                if pdf > 0.0:
                    out[i, j] = w0
    return out


@njit
def albedo(P, row, b, flags, wox, woy, woz, T, t):
    """Directional albedo ``tint E(wo)`` -> ``(a0, a1, a2)``, ``E`` read from this node's
    table at ``T[t:]`` (:func:`render.df._albedo.node_table`, built by :func:`albedo_table`)."""
    ok, e_u, e_v, tx, ty, glossy, ms = _setup(P, row, b)
    mu = abs(woz)
    if not (ok and mu > kc.COS_ZERO):
        return 0.0, 0.0, 0.0
    E = ms_albedo(T, t, False, max(P[row, b + _RU], kc.ROUGHNESS_MIN),
                  max(P[row, b + _RV], kc.ROUGHNESS_MIN), 1.0, 1.0, tx, ty, wox, woy, woz)
    a0, a1, a2 = P[row, b + _TINT] * E, P[row, b + _TINT + 1] * E, P[row, b + _TINT + 2] * E
    if ms:
        a0 += P[row, b + _MS] * (1.0 - E)
        a1 += P[row, b + _MS + 1] * (1.0 - E)
        a2 += P[row, b + _MS + 2] * (1.0 - E)
    return a0, a1, a2


def albedo_table(row, flags: int = 0) -> np.ndarray:
    """The node table :func:`albedo` reads: a :func:`~render.df._albedo.node_table` for
    one packed row (constant arguments), a :func:`~render.df._albedo.lanes_table` for
    rows (``(rows, SIGNATURE.width)``) whose roughness differs (per-lane arguments)."""
    rows = np.atleast_2d(np.asarray(row, dtype=np.float64))
    ru = np.maximum(rows[:, _RU], kc.ROUGHNESS_MIN)
    rv = np.maximum(rows[:, _RV], kc.ROUGHNESS_MIN)
    if np.all(ru == ru[0]) and np.all(rv == rv[0]):
        return node_table(BackscatteringGlossyReflectionBsdf, None, ru[0], rv[0])
    return lanes_table(BackscatteringGlossyReflectionBsdf, None, ru, rv)

# --- the Python class ------------------------------------------------------------------

BackscatteringGlossyReflectionBsdf = df_class(
    "BackscatteringGlossyReflectionBsdf", "backscattering_glossy_reflection_bsdf",
    O_BACKSCATTERING_GLOSSY, SIGNATURE, Lobe.GLOSSY_REFLECTION,
    albedo_table=albedo_table, module=__name__)
backscattering_glossy_reflection_bsdf = BackscatteringGlossyReflectionBsdf
