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
and :func:`albedo`: the glossy-lobe kernels of :mod:`render.df._glossy_lobe` over this
lobe, with the table arguments ``T, t`` of :func:`albedo_table`.
"""

from __future__ import annotations

import math

import numpy as np

from render.bsdf import (
    Lobe,
)
from render.df import _glossy_lobe
from render.df import _kernel_common as kc
from render.df._albedo import glossy_albedo_table
from render.df._microfacet import as_azimuth, ms_lobe, ms_on
from render.df._registry import Df, Node
from render.df._signature import REQUIRED, Param, Signature
from render.jit import njit

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
def _setup(P, row, b, flags, flip):
    """The lane's setup (:mod:`render.df._glossy_lobe`): ``s = (e_u, e_v, tx, ty)``."""
    ru = max(P[row, b + _RU], kc.ROUGHNESS_MIN)
    rv = max(P[row, b + _RV], kc.ROUGHNESS_MIN)
    tx, ty, ok = kc.tangent_axes(P[row, b + _TANGENT], P[row, b + _TANGENT + 1],
                                P[row, b + _TANGENT + 2])
    glossy = not (P[row, b + _TINT] == 0.0 and P[row, b + _TINT + 1] == 0.0
                  and P[row, b + _TINT + 2] == 0.0)
    ms = ms_on(0, P[row, b + _MS], P[row, b + _MS + 1], P[row, b + _MS + 2])
    if not (glossy or ms):
        ok = False
    return ok, glossy, ms, False, (2.0 / (ru * ru), 2.0 / (rv * rv), tx, ty)


@njit
def _value(P, row, b, flags, wox, woy, woz, wix, wiy, wiz, s):
    """The lobe at an oriented pair -> ``(w0, w1, w2, pdf)`` (0 where it does not reach)."""
    e_u, e_v, tx, ty = s
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
def _ms_lobe(P, row, b, s, glossy):
    """:func:`ms_lobe` of a lane (the table's roughness: the parameters, not exponents)."""
    e_u, e_v, tx, ty = s
    return ms_lobe(P, row, b + _MS, P[row, b + _RU], P[row, b + _RV], 1.0, 1.0, tx, ty, glossy)


@njit
def _single_sample(P, row, b, flags, wox, woy, woz, u1, u2x, u2y, s):
    """A single-scattering sample -> ``(ok, wix, wiy, wiz)``: a point of the anisotropic
    disk (phi as Ashikhmin–Shirley, r^2 = 1 - (1-u)^(1/(e+1))) placed at wo's tip gives
    the half vector; wi mirrors wo about it."""
    e_u, e_v, tx, ty = s
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


eval_pdf, sample, albedo, sample_weights = _glossy_lobe.kernels(__name__)


def albedo_table(row, flags: int = 0) -> np.ndarray:
    """The node table :func:`albedo` reads (:func:`render.df._albedo.glossy_albedo_table`:
    per lane where the roughness differs)."""
    return glossy_albedo_table(BackscatteringGlossyReflectionBsdf, row, flags)


# --- the Python class ------------------------------------------------------------------

NODE = Node("backscattering_glossy_reflection_bsdf", "bsdf", "leaf", SIGNATURE,
            eval_pdf=eval_pdf, sample=sample, albedo=albedo)
DF = Df("backscattering_glossy_reflection_bsdf", SIGNATURE, (NODE,),
        lobes=Lobe.GLOSSY_REFLECTION, albedo_table=albedo_table)
BackscatteringGlossyReflectionBsdf = DF.cls
backscattering_glossy_reflection_bsdf = BackscatteringGlossyReflectionBsdf
