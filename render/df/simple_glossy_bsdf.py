"""MDL ``df::simple_glossy_bsdf``: an anisotropic Ashikhmin–Shirley lobe with v-cavities masking.

MDL signature::

    bsdf simple_glossy_bsdf(float roughness_u, float roughness_v = roughness_u,
                            color tint = color(1.0), color multiscatter_tint = color(0.0),
                            float3 tangent_u = state::texture_tangent_u(0),
                            uniform scatter_mode mode = scatter_reflect,
                            uniform string handle = "");

What libbsdf really computes (``reference/mdl-distribution-functions.md`` §2.5): neither
GGX nor Beckmann, but the Ashikhmin–Shirley (Phong) half-vector distribution with
exponents ``e_u = 2 / roughness_u^2``, ``e_v = 2 / roughness_v^2`` (roughness clamped at
``1e-7``, so roughness 0 is a near-mirror lobe, not a delta)::

    D(h) (n.h) = sqrt((e_u + 1)(e_v + 1)) / (2 pi) * (n.h)^((e_u h_t^2 + e_v h_b^2) / (1 - (n.h)^2))

with v-cavities masking and libbsdf's scatter modes: **no Fresnel** in
``scatter_reflect`` and ``scatter_transmit`` (weight ``tint``; transmit reflects only on
total internal reflection), dielectric Fresnel on the renderer's IOR pair in
``scatter_reflect_transmit``.  The framework (half vectors, masking, pdfs, sampling) is
:mod:`render.df._microfacet`; half vectors are sampled in closed form (``phi`` from the
quadrant formula, ``cos theta_h = (1 - u)^(1 / (e_u cos^2 phi + e_v sin^2 phi + 1))``).

Departures from libbsdf:

* the exponent is evaluated as ``exp(x/2 * log1p(-s2))`` with ``s2 = h_t^2 + h_b^2``
  taken from the tangential components, exact down to roughness 1e-7; libbsdf instead
  sets the exponential factor to 1 whenever ``n.h > 0.99999``, which for narrow lobes
  (roughness below ~0.01) makes ``D`` integrate to far more than 1;
* the refraction pdf includes the ``eta2^2`` Jacobian (see ``_microfacet``);
* ``multiscatter_tint`` is not implemented yet (``albedo()`` gives the single-scattering
  table that the compensation would need).

Compiled kernels (the render core): :data:`SIGNATURE`, :func:`eval_pdf`, :func:`sample`
and :func:`albedo` below, one lane at a time, bit for bit the earlier numpy class's results
(``tests/render/df/test_simple_glossy_bsdf_kernels.py``).  :func:`albedo` takes two
arguments beyond the kernel contract, the program's table array ``T`` and this node's
offset ``t`` in it, filled by :func:`albedo_table` (see :mod:`render.df._albedo` for why
the tables are not frozen into the kernel).

References: Ashikhmin & Shirley, "An anisotropic Phong BRDF model" (2000); Heitz &
d'Eon, "Importance sampling microfacet-based BSDFs using the distribution of visible
normals" (2014).
"""

from __future__ import annotations

import math

import numpy as np

from render.bsdf import Lobe
from render.df import _kernel_common as kc
from render.df._albedo import lane_table_albedo, lanes_table, node_table
from render.df._microfacet import mf_finish, mf_geometry, mf_sample_dir
from render.df._signature import (
    MODE_FLAGS,
    MODE_MASK,
    REFLECT,
    REQUIRED,
    THIN_WALLED,
    Param,
    Signature,
)
from render.jit import njit
from render.program import O_SIMPLE_GLOSSY, df_class

__all__ = [
    "SimpleGlossyBsdf",
    "simple_glossy_bsdf",
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
    # not implemented (as the earlier numpy class did): the packer refuses non-zero values
    Param("multiscatter_tint", "color", (0.0, 0.0, 0.0), clamp=(0.0, 1.0)),
    Param("tangent_u", "float3", "state::texture_tangent_u(0)"),
    Param("mode", "scatter_mode", "scatter_reflect", uniform=True),
    Param("handle", "string", "", uniform=True),
), context=("ior_outside", "ior_inside"))
_RU = SIGNATURE.offset("roughness_u")
_RV = SIGNATURE.offset("roughness_v")
_TINT = SIGNATURE.offset("tint")
_TANGENT = SIGNATURE.offset("tangent_u")
_IOR_OUT = SIGNATURE.offset("ior_outside")
_IOR_IN = SIGNATURE.offset("ior_inside")
_PI = math.pi
_TWO_PI = 2.0 * math.pi
_HALF_PI = 0.5 * math.pi
_GLOSSY_R = int(Lobe.GLOSSY_REFLECTION)
_GLOSSY_T = int(Lobe.GLOSSY_TRANSMISSION)
_MODE_MASK_, _REFLECT_, _THIN_ = MODE_MASK, REFLECT, THIN_WALLED


@njit
def as_exponents(ru, rv):
    """Ashikhmin–Shirley's exponents: ``(e_u, e_v, norm)`` (roughness clamped at 1e-7)."""
    ru = max(ru, kc.ROUGHNESS_MIN)
    rv = max(rv, kc.ROUGHNESS_MIN)
    e_u = 2.0 / (ru * ru)
    e_v = 2.0 / (rv * rv)
    return e_u, e_v, math.sqrt((e_u + 1.0) * (e_v + 1.0)) / _TWO_PI


@njit
def as_d_cos(e_u, e_v, norm, ht, hb, hn):
    """Ashikhmin–Shirley's density: ``D(h) (n.h)`` in the anisotropy frame."""
    s2 = ht * ht + hb * hb
    if not (hn > 0.0 and s2 < 1.0):
        return 0.0
    # (n.h)^(x) = exp(x/2 * log(1 - s2)); x s2 = e_u ht^2 + e_v hb^2 stays finite as s2 -> 0
    ratio = math.log1p(-s2) / s2 if s2 > 0.0 else -1.0
    expo = 0.5 * (e_u * ht * ht + e_v * hb * hb) * ratio
    return norm * math.exp(expo)


@njit
def as_azimuth(e_u, e_v, u):
    """The anisotropic Phong azimuth: quadrant from ``u``, then
    ``tan(phi) = sqrt((e_u+1)/(e_v+1)) tan(pi u'/2)`` -> ``(cos phi, sin phi)``."""
    q = math.floor(4.0 * u)
    half = _HALF_PI * (4.0 * u - q)
    phi0 = math.atan2(math.sqrt(e_u + 1.0) * math.sin(half), math.sqrt(e_v + 1.0) * math.cos(half))
    if q == 0.0:
        phi = phi0
    elif q == 1.0:
        phi = _PI - phi0
    elif q == 2.0:
        phi = _PI + phi0
    else:
        phi = _TWO_PI - phi0
    return math.cos(phi), math.sin(phi)


@njit
def as_sample(e_u, e_v, u0, u1):
    """Ashikhmin–Shirley sampling: a half vector ``(ht, hb, hn)`` with density ``D (n.h)``."""
    cp, sp = as_azimuth(e_u, e_v, u0)
    e = e_u * cp * cp + e_v * sp * sp
    # cos theta = (1 - u1)^(1/(e+1)); keep 1 - cos accurate for huge exponents
    one_minus_cos = -math.expm1(math.log1p(-u1) / (e + 1.0))
    cos_t = 1.0 - one_minus_cos
    sin_t = math.sqrt(max(one_minus_cos * (2.0 - one_minus_cos), 0.0))
    return sin_t * cp, sin_t * sp, cos_t


@njit
def _setup(P, row, b, flags, flip):
    """the lane's setup for one lane -> ``(ok, e_u, e_v, norm, tx, ty, eta1, eta2)``."""
    e_u, e_v, norm = as_exponents(P[row, b + _RU], P[row, b + _RV])
    tx, ty, ok = kc.tangent_axes(P[row, b + _TANGENT], P[row, b + _TANGENT + 1],
                                P[row, b + _TANGENT + 2])
    if P[row, b + _TINT] == 0.0 and P[row, b + _TINT + 1] == 0.0 and P[row, b + _TINT + 2] == 0.0:
        ok = False
    o = P[row, b + _IOR_OUT]
    i = P[row, b + _IOR_IN]
    if not (o > 0.0 and i > 0.0):
        ok = False  # not an IOR (the packer and the earlier numpy class refuse it)
    eta1, eta2 = kc.ior_pair(o, i, flip, (flags & _THIN_) != 0, True)
    return ok, e_u, e_v, norm, tx, ty, eta1, eta2


@njit
def _value(P, row, b, flags, wox, woy, woz, wix, wiy, wiz, e_u, e_v, norm, tx, ty, eta1, eta2):
    """the microfacet evaluation for an oriented lane -> ``(w0, w1, w2, pdf)``."""
    ok, refr, hx, hy, hz, kh1, kh2, p_ev, g1_1, g2 = mf_geometry(
        flags, eta1, eta2, wox, woy, woz, wix, wiy, wiz)
    if not ok:
        return 0.0, 0.0, 0.0, 0.0
    # distribution in the anisotropy frame (t = (tx, ty, 0), b = (ty, -tx, 0))
    ht = hx * tx + hy * ty
    hb = hx * ty - hy * tx
    D = as_d_cos(e_u, e_v, norm, ht, hb, hz) / hz
    return mf_finish(D, refr, woz, kh1, kh2, eta1, eta2, p_ev, g1_1, g2,
                     P[row, b + _TINT], P[row, b + _TINT + 1], P[row, b + _TINT + 2])


@njit
def eval_pdf(P, row, b, flags, wox, woy, woz, wix, wiy, wiz):
    """``f |cos theta_i|`` and the pdf of :func:`sample` -> ``(f0, f1, f2, pdf)``."""
    flip = woz < 0.0
    if flip:  # orient: mirror both through the tangent plane
        woz = -woz
        wiz = -wiz
    ok, e_u, e_v, norm, tx, ty, eta1, eta2 = _setup(P, row, b, flags, flip)
    if not ok:
        return 0.0, 0.0, 0.0, 0.0
    w0, w1, w2, pdf = _value(P, row, b, flags, wox, woy, woz, wix, wiy, wiz,
                             e_u, e_v, norm, tx, ty, eta1, eta2)
    return w0 * pdf, w1 * pdf, w2 * pdf, pdf


@njit
def sample(P, row, b, flags, wox, woy, woz, u1, u2x, u2y):
    """-> ``(wix, wiy, wiz, pdf, w0, w1, w2, lobe)`` (all 0 where the sample fails)."""
    u1 = kc.clamp_u(u1)
    u2x = kc.clamp_u(u2x)
    u2y = kc.clamp_u(u2y)
    flip = woz < 0.0
    if flip:
        woz = -woz
    ok, e_u, e_v, norm, tx, ty, eta1, eta2 = _setup(P, row, b, flags, flip)
    if not ok:
        return 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0
    # half vector from D (n.h), in the anisotropy frame, then into the local frame
    ht, hb, hn = as_sample(e_u, e_v, u2x, u2y)
    ok, wix, wiy, wiz = mf_sample_dir(flags, eta1, eta2, wox, woy, woz,
                                      ht * tx + hb * ty, ht * ty - hb * tx, hn, u1)
    if not ok:
        return 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0
    w0, w1, w2, pdf = _value(P, row, b, flags, wox, woy, woz, wix, wiy, wiz,
                             e_u, e_v, norm, tx, ty, eta1, eta2)
    if not pdf > 0.0:
        return 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0
    lobe = _GLOSSY_T if wiz < 0.0 else _GLOSSY_R
    if flip:
        wiz = -wiz
    return wix, wiy, wiz, pdf, w0, w1, w2, lobe


@njit(allocates=True)
def sample_weights(P, flags, wo, pts):
    """First-channel sample weights (m, k) of :func:`sample` on row 0 of ``P`` for each
    ``wo`` (m, 3) and variates ``pts`` (k, 3): the albedo tables' Monte Carlo
    (:mod:`render.df._albedo`)."""
    m, k = wo.shape[0], pts.shape[0]
    out = np.empty((m, k))
    for i in range(m):
        for j in range(k):
            out[i, j] = sample(P, 0, 0, flags, wo[i, 0], wo[i, 1], wo[i, 2], pts[j, 0],
                               pts[j, 1], pts[j, 2])[4]
    return out

@njit
def albedo(P, row, b, flags, wox, woy, woz, T, t):
    """Directional albedo ``tint E(wo)`` -> ``(a0, a1, a2)``, ``E`` read from this node's
    table at ``T[t:]`` (:func:`render.df._albedo.node_table`, built by :func:`albedo_table`)."""
    flip = woz < 0.0
    ok, e_u, e_v, norm, tx, ty, eta1, eta2 = _setup(P, row, b, flags, flip)
    mu = abs(woz)
    if not (ok and mu > kc.COS_ZERO):
        return 0.0, 0.0, 0.0
    phi = math.atan2(abs(wox * ty - woy * tx), abs(wox * tx + woy * ty))
    E = lane_table_albedo(T, t, mu, phi, flip, max(P[row, b + _RU], kc.ROUGHNESS_MIN),
                          max(P[row, b + _RV], kc.ROUGHNESS_MIN), P[row, b + _IOR_OUT],
                          P[row, b + _IOR_IN])
    return P[row, b + _TINT] * E, P[row, b + _TINT + 1] * E, P[row, b + _TINT + 2] * E


def albedo_table(row, flags: int) -> np.ndarray:
    """The node table :func:`albedo` reads: a :func:`~render.df._albedo.node_table` for
    one packed row (constant arguments), a :func:`~render.df._albedo.lanes_table` for
    rows whose roughness or IOR differ (per-lane arguments).

    Parameters
    ----------
    row : (SIGNATURE.width,) or (rows, SIGNATURE.width) float64
        The node's packed slots.
    flags : int
        Its mode and thin-walled flags.
    """
    from render.df._common import ScatterMode

    rows = np.atleast_2d(np.asarray(row, dtype=np.float64))
    mode = flags & _MODE_MASK_
    thin = (flags & _THIN_) != 0
    key = (ScatterMode.scatter_reflect if mode == _REFLECT_ or thin
           else {v: k for k, v in MODE_FLAGS.items()}[mode])
    cols = [_RU, _RV] if key is ScatterMode.scatter_reflect else [_RU, _RV, _IOR_OUT, _IOR_IN]
    ru = np.maximum(rows[:, _RU], kc.ROUGHNESS_MIN)
    rv = np.maximum(rows[:, _RV], kc.ROUGHNESS_MIN)
    if np.all(rows[:, cols] == rows[0, cols]):
        if key is ScatterMode.scatter_reflect:
            return node_table(SimpleGlossyBsdf, key, ru[0], rv[0])
        o, i = kc.ior_pair(rows[0, _IOR_OUT], rows[0, _IOR_IN], False, False, True)
        return node_table(SimpleGlossyBsdf, key, ru[0], rv[0], i / o, o / i)
    if key is ScatterMode.scatter_reflect:
        return lanes_table(SimpleGlossyBsdf, key, ru, rv)
    iors = rows[:, [_IOR_OUT, _IOR_IN]]
    etas = np.empty_like(iors)
    for k, (ro, ri) in enumerate(iors):
        o, i = kc.ior_pair(ro, ri, False, False, True)
        etas[k] = i / o, o / i
    return lanes_table(SimpleGlossyBsdf, key, ru, rv, iors, etas)

# --- the Python class ------------------------------------------------------------------

SimpleGlossyBsdf = df_class(
    "SimpleGlossyBsdf", "simple_glossy_bsdf", O_SIMPLE_GLOSSY, SIGNATURE,
    {"scatter_reflect": Lobe.GLOSSY_REFLECTION, "scatter_transmit": Lobe.GLOSSY,
     "scatter_reflect_transmit": Lobe.GLOSSY},
    unsupported=("multiscatter_tint",), albedo_table=albedo_table, module=__name__)
simple_glossy_bsdf = SimpleGlossyBsdf
