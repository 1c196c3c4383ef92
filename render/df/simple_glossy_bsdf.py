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
* ``multiscatter_tint`` adds libbsdf's energy-compensation lobe
  (:mod:`render.df._microfacet`), from this lobe's own albedo table.

Compiled kernels (the render core): :data:`SIGNATURE`, :func:`eval_pdf`, :func:`sample`
and :func:`albedo`, one lane at a time: the glossy-lobe kernels of
:mod:`render.df._glossy_lobe` over this module's lobe.  All three take two arguments beyond
the kernel contract, the program's table array ``T`` and this node's offset ``t`` in it,
filled by :func:`albedo_table` (see :mod:`render.df._albedo` for why the tables are not
frozen into the kernel): the albedo and the compensation lobe read it.

References: Ashikhmin & Shirley, "An anisotropic Phong BRDF model" (2000); Heitz &
d'Eon, "Importance sampling microfacet-based BSDFs using the distribution of visible
normals" (2014).
"""

from __future__ import annotations

import math

import numpy as np

from render.bsdf import Lobe
from render.df import _glossy_lobe
from render.df import _kernel_common as kc
from render.df._albedo import glossy_albedo_table
from render.df._microfacet import (
    mf_film_event,
    mf_film_on,
    mf_finish,
    mf_geometry,
    mf_sample_dir,
    microfacet_signature,
    ms_lobe,
    ms_on,
)
from render.df._signature import MODE_MASK, THIN_WALLED
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
SIGNATURE = microfacet_signature()
_RU = SIGNATURE.offset("roughness_u")
_RV = SIGNATURE.offset("roughness_v")
_TINT = SIGNATURE.offset("tint")
_MS = SIGNATURE.offset("multiscatter_tint")
_FILM_D = SIGNATURE.offset("thin_film_thickness")
_FILM_N = SIGNATURE.offset("thin_film_ior")
_TANGENT = SIGNATURE.offset("tangent_u")
_IOR_OUT = SIGNATURE.offset("ior_outside")
_IOR_IN = SIGNATURE.offset("ior_inside")
_PI = math.pi
_TWO_PI = 2.0 * math.pi
_HALF_PI = 0.5 * math.pi
_MODE_MASK_, _THIN_ = MODE_MASK, THIN_WALLED


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
    """The lane's setup (:mod:`render.df._glossy_lobe`): ``s = (e_u, e_v, norm, tx, ty,
    eta1, eta2)``."""
    e_u, e_v, norm = as_exponents(P[row, b + _RU], P[row, b + _RV])
    tx, ty, ok = kc.tangent_axes(P[row, b + _TANGENT], P[row, b + _TANGENT + 1],
                                P[row, b + _TANGENT + 2])
    glossy = not (P[row, b + _TINT] == 0.0 and P[row, b + _TINT + 1] == 0.0
                  and P[row, b + _TINT + 2] == 0.0)
    ms = ms_on(flags & _MODE_MASK_, P[row, b + _MS], P[row, b + _MS + 1], P[row, b + _MS + 2])
    if not (glossy or ms):
        ok = False
    o = P[row, b + _IOR_OUT]
    i = P[row, b + _IOR_IN]
    if not (o > 0.0 and i > 0.0):
        ok = False  # not an IOR (the packer refuses it)
    eta1, eta2 = kc.ior_pair(o, i, flip, (flags & _THIN_) != 0, True)
    return ok, glossy, ms, flip, (e_u, e_v, norm, tx, ty, eta1, eta2)


@njit
def _value(P, row, b, flags, wox, woy, woz, wix, wiy, wiz, s):
    """the microfacet evaluation for an oriented lane -> ``(w0, w1, w2, pdf)``."""
    e_u, e_v, norm, tx, ty, eta1, eta2 = s
    ok, refr, hx, hy, hz, kh1, kh2, p_ev, g1_1, g2 = mf_geometry(
        flags, eta1, eta2, wox, woy, woz, wix, wiy, wiz)
    if not ok:
        return 0.0, 0.0, 0.0, 0.0
    # distribution in the anisotropy frame (t = (tx, ty, 0), b = (ty, -tx, 0))
    ht = hx * tx + hy * ty
    hb = hx * ty - hy * tx
    D = as_d_cos(e_u, e_v, norm, ht, hb, hz) / hz
    t0, t1, t2 = P[row, b + _TINT], P[row, b + _TINT + 1], P[row, b + _TINT + 2]
    d = P[row, b + _FILM_D]
    if mf_film_on(flags, d):  # a thin_film replaces Fresnel (render.df.thin_film)
        p_ev, m0, m1, m2 = mf_film_event(flags, kh1, eta1, eta2, d, P[row, b + _FILM_N],
                                         P[row, b + _FILM_N + 1], P[row, b + _FILM_N + 2],
                                         wiz < 0.0)
        if not p_ev > 0.0:
            return 0.0, 0.0, 0.0, 0.0
        t0, t1, t2 = t0 * m0, t1 * m1, t2 * m2
    return mf_finish(D, refr, woz, kh1, kh2, eta1, eta2, p_ev, g1_1, g2, t0, t1, t2)


@njit
def _ms_lobe(P, row, b, s, glossy):
    """:func:`ms_lobe` of a lane (the table's roughness: the parameters, not exponents)."""
    e_u, e_v, norm, tx, ty, eta1, eta2 = s
    return ms_lobe(P, row, b + _MS, P[row, b + _RU], P[row, b + _RV], P[row, b + _IOR_OUT],
                   P[row, b + _IOR_IN], tx, ty, glossy)


@njit
def _single_sample(P, row, b, flags, wox, woy, woz, u1, u2x, u2y, s):
    """half vector from D (n.h), in the anisotropy frame, then into the local frame."""
    e_u, e_v, norm, tx, ty, eta1, eta2 = s
    ht, hb, hn = as_sample(e_u, e_v, u2x, u2y)
    return mf_sample_dir(flags, eta1, eta2, wox, woy, woz,
                         ht * tx + hb * ty, ht * ty - hb * tx, hn, u1, True,
                         P[row, b + _FILM_D], P[row, b + _FILM_N], P[row, b + _FILM_N + 1],
                         P[row, b + _FILM_N + 2])


eval_pdf, sample, albedo, sample_weights = _glossy_lobe.kernels(__name__)


def albedo_table(row, flags: int) -> np.ndarray:
    """The node table :func:`albedo` reads (:func:`render.df._albedo.glossy_albedo_table`:
    a node table for one packed row, a lanes table for per-lane roughness or IOR)."""
    return glossy_albedo_table(SimpleGlossyBsdf, row, flags)

# --- the Python class ------------------------------------------------------------------

SimpleGlossyBsdf = df_class(
    "SimpleGlossyBsdf", "simple_glossy_bsdf", O_SIMPLE_GLOSSY, SIGNATURE,
    {"scatter_reflect": Lobe.GLOSSY_REFLECTION, "scatter_transmit": Lobe.GLOSSY,
     "scatter_reflect_transmit": Lobe.GLOSSY},
    albedo_table=albedo_table, module=__name__)
simple_glossy_bsdf = SimpleGlossyBsdf
