"""libbsdf's microfacet framework with v-cavities masking, shared by the glossy lobes.

``reference/mdl-distribution-functions.md`` §2.4.  Each df module supplies its normal
distribution ``D(h) (n.h)`` over half vectors (in the anisotropy frame ``t, b, n``) and
its sampler of them, as kernels; its albedo table is built by
:func:`render.df._albedo.glossy_albedo_table`.

Notation (after orienting each lane so that ``wo.z > 0``): ``eta1`` is the IOR on
``wo``'s side, ``eta2`` the other; ``nk1 = wo.z``; ``tr = wi.z < 0``; ``refr = tr`` and
not thin-walled.  Half vector: ``normalize(wo + wi)`` for reflection,
``normalize(wo + mirror_z(wi))`` for thin-walled transmission,
``sign(eta1 - eta2) normalize(eta1 wo + eta2 wi)`` for refraction.  V-cavities
``G1(k) = min(1, 2 |n.h| |n.k| / |k.h|)``, ``G2 = min(G1(wo), G1(wi))`` (reflection,
thin-walled) or ``max(G1(wo) + G1(wi) - 1, 0)`` (refraction).  With ``P`` the
probability of the event given ``h`` (1 in ``scatter_reflect``; in
``scatter_transmit`` 1 for transmission and, on total internal reflection only, for
reflection; ``F`` / ``1 - F`` in ``scatter_reflect_transmit``)::

    pdf0 = D / (4 nk1)                                              reflection, thin wall
         = D (wo.h) |wi.h| eta2^2 / (nk1 (eta1 wo.h + eta2 wi.h)^2)   refraction
    eval = saturate(tint) P G2 pdf0,     pdf = P G1(wo) pdf0,     weight = tint G2 / G1(wo)

Sampling draws ``h`` from ``D (n.h)``, applies the v-cavities flip (Heitz & d'Eon 2014),
picks the event with probability ``P``, and reflects or refracts ``wo`` about ``h``.

The same framework as scalar numba kernels (the render core): :func:`mf_geometry` and
:func:`mf_finish` around the distribution's ``D`` for ``eval_pdf``, :func:`mf_sample_dir`
from a sampled half vector for ``sample``; the df module composes them into its lobe,
which :mod:`render.df._glossy_lobe` turns into the df's kernels.

Departures from libbsdf, all deliberate:

* the refraction pdf carries the Jacobian factor ``eta2^2`` that libbsdf omits (its
  sample weights are unchanged; only MIS and the pdf integral are corrected);
* ``pdf`` is 0 wherever ``eval`` is 0 (``G2 = 0`` in refraction, black ``tint``), and
  ``sample`` fails there instead of returning a zero-weight direction;
* libbsdf's Beckmann Smith masking is Walter's rational fit of ``G1``; here ``G1 =
  1 / (1 + Lambda)`` with the exact ``Lambda`` (``erfc``), the one the visible-normal
  sampler draws from, so the pdf is the density the sampler really has (the fit is
  within 0.35 % of it).

The ``microfacet_*`` dfs add two normal distributions (GGX and Beckmann, anisotropic
in the ``tangent_u`` frame, ``alpha = roughness``) and Smith masking
(``G2 = G1(wo) G1(wi)``, uncorrelated, for reflection and refraction, sampled through
the distribution of visible normals: Heitz 2018 for GGX, the stretched 1-D slope
inversion of Heitz & d'Eon 2014 for Beckmann), as one lobe (:func:`mf_setup`,
:func:`mf_value`, :func:`mf_single_sample`) that each df module sets up with its
distribution and masking.

**Energy compensation** (``multiscatter_tint``, libbsdf's Kelemen & Szirmay-Kalos lobe,
reference §2.4), shared by every glossy lobe (:func:`ms_lobe`, :func:`ms_eval`,
:func:`ms_choice`, :func:`ms_sampled`): in ``scatter_reflect`` and
``scatter_reflect_transmit`` a diffuse-like reflection lobe is added::

    f_ms = saturate(multiscatter_tint) (1 - E(wo)) (1 - E(wi)) |wi.z| / (pi (1 - E_avg))
    pdf  = E(wo) pdf_glossy + (1 - E(wo)) |wi.z| / pi       (reflection side)

with ``E`` the lobe's white directional albedo and ``E_avg`` its cosine-weighted mean,
read from the node's albedo table (:mod:`render.df._albedo`, where ``E_avg`` is stored
after each column); sampling picks the glossy lobe with probability ``E(wo)``.  With
``multiscatter_tint = 1`` a white lobe is lossless to the table's accuracy.
``scatter_transmit`` takes no compensation (libbsdf).
"""

from __future__ import annotations

import math

from render.bsdf import Lobe
from render.df import _kernel_common as kc
from render.df._albedo import lane_table_albedo, lane_table_average
from render.df._signature import (
    MODE_MASK,
    REFLECT,
    REQUIRED,
    THIN_WALLED,
    TRANSMIT,
    Param,
    Signature,
)
from render.df.thin_film import FILM_PARAMS, film_rgb
from render.jit import njit

__all__ = ["mf_p_reflect", "mf_half", "mf_vcavities", "mf_geometry", "mf_finish",
           "mf_sample_dir", "GGX", "BECKMANN", "VCAVITIES", "SMITH", "mf_d", "mf_smith_g1",
           "mf_sample_d_cos", "mf_sample_visible", "ASHIKHMIN_SHIRLEY", "as_exponents", "as_d_cos",
           "as_azimuth", "as_sample", "mf_setup", "mf_value", "mf_single_sample",
           "mf_ms_lobe", "ms_lobe", "ms_eval", "ms_choice", "ms_sampled", "ms_on", "ms_albedo",
           "microfacet_signature", "mf_film_event", "mf_film_on"]


# --- kernels (the compiled render core) ----------------------------------------------------
# The framework's scalar pieces, shared by the microfacet dfs' kernels: the caller orients
# the lane, evaluates its distribution at the half vector that ``mf_geometry`` returns and
# finishes with ``mf_finish``; sampling draws a half vector and calls ``mf_sample_dir``.
# Operation order follows the numpy code (same bits; dot products sum (x + z) + y).

_REFLECT, _TRANSMIT = REFLECT, TRANSMIT
_MODE_MASK, _THIN_WALLED = MODE_MASK, THIN_WALLED


@njit
def mf_p_reflect(mode, thin_walled, kh1, eta1, eta2):
    """the microfacet reflection probability: probability of reflection given ``kh1 = wo.h``."""
    if mode == _REFLECT:
        return 1.0
    if mode == _TRANSMIT:
        if thin_walled:
            return 0.0
        b = eta1 / eta2
        return 1.0 if b * b * (1.0 - kh1 * kh1) > 1.0 else 0.0  # total internal reflection
    return kc.fresnel_dielectric(kh1, eta2 / eta1)[0]


@njit
def mf_half(flags, eta1, eta2, wox, woy, woz, wix, wiy, wiz):
    """The half vector and event of the microfacet evaluation for an oriented lane
    (``wo.z >= 0``): ``(ok, refr, hx, hy, hz, kh1, kh2, P)``, the half vector, its cosines
    with ``wo`` and (mirrored) ``wi``, and the event probability given ``h``."""
    mode = flags & _MODE_MASK
    thin = (flags & _THIN_WALLED) != 0
    nk1 = woz
    tr = wiz < 0.0
    refr = tr and not thin
    if not (nk1 > kc.COS_ZERO and abs(wiz) > kc.COS_ZERO) or (mode == _REFLECT and tr):
        return False, False, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0
    # half vector: reflection, thin-walled transmission (mirror wi up), refraction
    k2z = -wiz if tr else wiz
    if refr:
        hx, hy, hz, valid = kc.unitize(eta1 * wox + eta2 * wix, eta1 * woy + eta2 * wiy,
                                      eta1 * woz + eta2 * wiz)
        s = 1.0 if eta1 > eta2 else (-1.0 if eta1 < eta2 else 0.0)
        hx = hx * s
        hy = hy * s
        hz = hz * s
        kh2 = kc.dot3(wix, wiy, wiz, hx, hy, hz)
    else:
        hx, hy, hz, valid = kc.unitize(wox + wix, woy + wiy, woz + k2z)
        kh2 = kc.dot3(wix, wiy, k2z, hx, hy, hz)
    if not valid:
        return False, False, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0
    kh1 = kc.dot3(wox, woy, woz, hx, hy, hz)
    if not (hz > kc.COS_ZERO and kh1 > 0.0 and ((kh2 < 0.0) if refr else (kh2 > 0.0))):
        return False, False, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0
    p_refl = mf_p_reflect(mode, thin, kh1, eta1, eta2)
    P = 1.0 - p_refl if tr else p_refl
    if not P > 0.0:
        return False, False, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0
    return True, refr, hx, hy, hz, kh1, kh2, P


@njit
def mf_vcavities(refr, hz, nk1, wiz, kh1, kh2):
    """V-cavities masking ``(G1(wo), G2)`` at half vector cosine ``hz``."""
    g1_1 = min(1.0, 2.0 * hz * nk1 / kh1)
    g1_2 = min(1.0, 2.0 * hz * abs(wiz) / abs(kh2))
    G2 = max(g1_1 + g1_2 - 1.0, 0.0) if refr else min(g1_1, g1_2)
    return g1_1, G2


@njit
def mf_geometry(flags, eta1, eta2, wox, woy, woz, wix, wiy, wiz):
    """The first half of the microfacet evaluation for an oriented lane (``wo.z >= 0``)
    with v-cavities masking.

    Returns ``(ok, refr, hx, hy, hz, kh1, kh2, P, g1_1, G2)``: the half vector, its
    cosines with ``wo`` and (mirrored) ``wi``, the event probability and the v-cavities
    masking terms; the caller evaluates ``D`` at ``h`` (only where ``ok``).
    """
    ok, refr, hx, hy, hz, kh1, kh2, P = mf_half(flags, eta1, eta2, wox, woy, woz,
                                                wix, wiy, wiz)
    if not ok:
        return False, False, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0
    g1_1, G2 = mf_vcavities(refr, hz, woz, wiz, kh1, kh2)
    if not G2 > 0.0:
        return False, False, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0
    return True, refr, hx, hy, hz, kh1, kh2, P, g1_1, G2


@njit
def mf_finish(D, refr, nk1, kh1, kh2, eta1, eta2, P, g1_1, G2, t0, t1, t2):
    """The second half of the microfacet evaluation: ``D = D(h)`` -> ``(w0, w1, w2, pdf)``
    (weight = eval / pdf; all 0 where the lobe does not reach)."""
    if refr:
        den = eta1 * kh1 + eta2 * kh2
        pdf0 = D * kh1 * abs(kh2) * eta2 * eta2 / (nk1 * (den * den))
    else:
        pdf0 = D / (4.0 * nk1)
    pdf = P * g1_1 * pdf0
    r = G2 / g1_1
    w0 = t0 * r
    w1 = t1 * r
    w2 = t2 * r
    # pdf > 0 exactly where eval = weight * pdf > 0 (also where the product underflows)
    if not max(max(w0 * pdf, w1 * pdf), w2 * pdf) > 0.0:
        return 0.0, 0.0, 0.0, 0.0
    return w0, w1, w2, pdf


@njit
def mf_film_event(flags, kh1, eta1, eta2, d, f0, f1, f2, tr):
    """A ``thin_film`` on a ``scatter_reflect_transmit`` lobe (``d > 0``): the film's RGB
    reflectance at ``kh1`` replaces Fresnel.  Returns ``(P, m0, m1, m2)``: the event's
    probability (reflection: the channels' mean ``F``) and the per-channel factors
    ``F_c / P`` (``(1 - F_c) / (1 - P)`` for transmission)."""
    r0, r1, r2 = film_rgb(kh1, eta1, f0, f1, f2, eta2, eta2, eta2, 0.0, 0.0, 0.0, d)
    pr = (r0 + r1 + r2) / 3.0
    if tr:
        q = 1.0 - pr
        if not q > 0.0:
            return 0.0, 0.0, 0.0, 0.0
        return q, (1.0 - r0) / q, (1.0 - r1) / q, (1.0 - r2) / q
    if not pr > 0.0:
        return 0.0, 0.0, 0.0, 0.0
    return pr, r0 / pr, r1 / pr, r2 / pr


@njit
def mf_film_on(flags, d):
    """Whether a film acts on this lobe: ``scatter_reflect_transmit`` and ``d > 0``."""
    return (flags & _MODE_MASK) == 2 and d > 0.0


@njit
def mf_sample_dir(flags, eta1, eta2, wox, woy, woz, hx, hy, hz, u1, vflip, d, f0, f1, f2):
    """microfacet sampling from a half vector (local frame) to ``wi``, for an oriented
    lane: with ``vflip`` the half vector was drawn from ``D (n.h)`` and the v-cavities
    flip makes it visible; without, it was drawn from the visible normals already (the
    Smith variants).  Then the event, reflect or refract (``d``, ``f0..f2``: the thin
    film's thickness and ior, :func:`mf_film_event`; ``d = 0``: no film).

    Returns ``(ok, wix, wiy, wiz)``.
    """
    mode = flags & _MODE_MASK
    thin = (flags & _THIN_WALLED) != 0
    if vflip:
        # v-cavities: the facet rotated by pi about n, chosen with prob. ~ max(0, wo.h')
        a = max(kc.dot3(wox, woy, woz, hx, hy, hz), 0.0)
        a_alt = max(kc.dot3(wox, woy, woz, -hx, -hy, hz), 0.0)
        tot = a + a_alt
        if not tot > 0.0:
            return False, 0.0, 0.0, 0.0
        q = a_alt / tot
        take_alt = u1 < q
        # reuse u1 for the event choice
        if take_alt:
            u1 = u1 / (q if q > 0 else 1.0)
            hx = -hx
            hy = -hy
        else:
            u1 = (u1 - q) / (1.0 - q if q < 1 else 1.0)
    u1 = min(max(u1, 0.0), kc.ONE_MINUS_EPS)
    c = kc.dot3(wox, woy, woz, hx, hy, hz)
    if not c > 0.0:
        return False, 0.0, 0.0, 0.0
    if mf_film_on(flags, d):
        refl = u1 < mf_film_event(flags, c, eta1, eta2, d, f0, f1, f2, False)[0]
    else:
        refl = u1 < mf_p_reflect(mode, thin, c, eta1, eta2)
    two_c = 2.0 * c
    wix = two_c * hx - wox
    wiy = two_c * hy - woy
    wiz = two_c * hz - woz
    if not refl:
        if thin:
            wiz = -wiz
        else:
            # refraction about h with b = eta1/eta2 (never total internal: then refl is True)
            b = eta1 / eta2
            ct = math.sqrt(max(1.0 - b * b * (1.0 - c * c), 0.0))
            f = b * c - ct
            wix, wiy, wiz, _ = kc.unitize(-b * wox + f * hx, -b * woy + f * hy, -b * woz + f * hz)
    if not ((wiz > 0.0) if refl else (wiz < 0.0)):
        return False, 0.0, 0.0, 0.0
    return True, wix, wiy, wiz


# --- normal distributions and Smith masking (the microfacet_* dfs, simple_glossy_bsdf) ----
#: ``dist`` of the generic kernels: the normal distribution (Ashikhmin–Shirley's is
#: ``simple_glossy_bsdf``'s, with v-cavities masking only)
GGX, BECKMANN, ASHIKHMIN_SHIRLEY = 0, 1, 2
#: ``mask`` of the generic kernels: the masking-shadowing model
VCAVITIES, SMITH = 0, 1
_PI = math.pi
_TWO_PI = 2.0 * math.pi
_HALF_PI = 0.5 * math.pi
_INV_SQRT_PI = 1.0 / math.sqrt(math.pi)
_TWO_OVER_SQRT_PI = 2.0 / math.sqrt(math.pi)


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
def mf_d(dist, au, av, ht, hb, hn):
    """``D(h)`` in the anisotropy frame (``alpha_u`` along ``t``): GGX
    ``1 / (pi au av (ht^2/au^2 + hb^2/av^2 + hn^2)^2)``, Beckmann
    ``exp(-(ht^2/au^2 + hb^2/av^2) / hn^2) / (pi au av hn^4)``, Ashikhmin–Shirley
    :func:`as_d_cos` ``/ hn`` (exponents ``2 / alpha^2``); 0 for ``hn <= 0``."""
    if not hn > 0.0:
        return 0.0
    if dist == ASHIKHMIN_SHIRLEY:
        e_u, e_v, norm = as_exponents(au, av)
        return as_d_cos(e_u, e_v, norm, ht, hb, hn) / hn
    x = ht / au
    y = hb / av
    if dist == GGX:
        d = x * x + y * y + hn * hn
        return 1.0 / (_PI * au * av * (d * d))
    hn2 = hn * hn
    return math.exp(-(x * x + y * y) / hn2) / (_PI * au * av * (hn2 * hn2))


@njit
def mf_lambda(dist, au, av, kt, kb, kn):
    """Smith's ``Lambda(k)`` for a direction with ``|k.n| = kn`` (anisotropic: the
    roughness projected on ``k``'s azimuth).  GGX in a form without cancellation; Beckmann
    exact (``erfc``), not Walter's rational fit (Ashikhmin–Shirley has v-cavities only)."""
    kn = abs(kn)
    a2 = (au * kt) * (au * kt) + (av * kb) * (av * kb)  # tan^2 theta alpha^2, times kn^2
    if not a2 > 0.0:
        return 0.0
    if not kn > 0.0:
        return math.inf
    if dist == GGX:
        r = a2 / (kn * kn)
        return 0.5 * r / (math.sqrt(1.0 + r) + 1.0)
    a = kn / math.sqrt(a2)
    if a > 26.0:
        return 0.0
    return 0.5 * (math.exp(-a * a) * _INV_SQRT_PI / a - math.erfc(a))


@njit
def mf_smith_g1(dist, au, av, kt, kb, kn):
    """Smith's masking ``G1(k) = 1 / (1 + Lambda(k))``."""
    lam = mf_lambda(dist, au, av, kt, kb, kn)
    if lam == math.inf:
        return 0.0
    return 1.0 / (1.0 + lam)


@njit
def mf_sample_d_cos(dist, au, av, u0, u1):
    """A half vector ``(ht, hb, hn)`` with density ``D(h) (n.h)``: the azimuth from
    ``tan phi = (av/au) tan(2 pi u0)``, then ``tan^2 theta`` from the inverted marginal
    (GGX ``u1 / ((1 - u1) k)``, Beckmann ``-log(1 - u1) / k``, ``k = cos^2 phi / au^2 +
    sin^2 phi / av^2``); Ashikhmin–Shirley's from :func:`as_sample`."""
    if dist == ASHIKHMIN_SHIRLEY:
        e_u, e_v, norm = as_exponents(au, av)
        return as_sample(e_u, e_v, u0, u1)
    phi = 2.0 * _PI * u0
    cx = au * math.cos(phi)
    cy = av * math.sin(phi)
    ln = math.hypot(cx, cy)
    cp = cx / ln
    sp = cy / ln
    k = (cp / au) * (cp / au) + (sp / av) * (sp / av)
    if dist == GGX:
        tan2 = u1 / ((1.0 - u1) * k)
    else:
        tan2 = -math.log1p(-u1) / k
    cos_t = 1.0 / math.sqrt(1.0 + tan2)
    sin_t = math.sqrt(tan2 / (1.0 + tan2))
    return sin_t * cp, sin_t * sp, cos_t


@njit
def _erfinv(x):
    """``erf^-1(x)`` for ``|x| < 1``: Giles' single-precision start, then Newton on
    ``math.erf`` to double precision (``x`` clamped 1e-16 inside the interval)."""
    x = min(max(x, -1.0 + 1e-16), 1.0 - 1e-16)
    w = -math.log((1.0 - x) * (1.0 + x))
    if w < 5.0:
        w = w - 2.5
        p = 2.81022636e-08
        p = 3.43273939e-07 + p * w
        p = -3.5233877e-06 + p * w
        p = -4.39150654e-06 + p * w
        p = 0.00021858087 + p * w
        p = -0.00125372503 + p * w
        p = -0.00417768164 + p * w
        p = 0.246640727 + p * w
        p = 1.50140941 + p * w
    else:
        w = math.sqrt(w) - 3.0
        p = -0.000200214257
        p = 0.000100950558 + p * w
        p = 0.00134934322 + p * w
        p = -0.00367342844 + p * w
        p = 0.00573950773 + p * w
        p = -0.0076224613 + p * w
        p = 0.00943887047 + p * w
        p = 1.00167406 + p * w
        p = 2.83297682 + p * w
    y = p * x
    for _ in range(3):
        d = _TWO_OVER_SQRT_PI * math.exp(-y * y)
        if not d > 0.0:
            break
        y = y - (math.erf(y) - x) / d
    return y


@njit
def _slope_cdf(s, tan_t):
    """``erfc(-s) + tan e^(-s^2) / sqrt(pi)``: twice the unnormalised visible-slope CDF."""
    return math.erfc(-s) + tan_t * math.exp(-s * s) * _INV_SQRT_PI


@njit
def _beckmann_slope_x(tan_t, u):
    """The visible Beckmann slope along the viewing azimuth (unit roughness): the root of
    ``erfc(-s) + tan e^(-s^2)/sqrt(pi) = u (erfc(-c) + tan e^(-c^2)/sqrt(pi))``,
    ``c = cot theta`` (the CDF of ``(1 - s tan) e^(-s^2)`` on ``s < c``), by Newton's
    method kept inside a shrinking bracket."""
    c = 1.0 / tan_t if tan_t > 1e-300 else 1e300
    hi = min(c, 8.0)
    lo = -8.0
    target = u * _slope_cdf(hi, tan_t)
    s = min(max(_erfinv(2.0 * u - 1.0), lo), hi)
    for _ in range(64):
        v = _slope_cdf(s, tan_t) - target
        if v > 0.0:
            hi = s
        else:
            lo = s
        dv = _TWO_OVER_SQRT_PI * math.exp(-s * s) * (1.0 - s * tan_t)
        step = v / dv if dv > 0.0 else 0.0
        nxt = s - step
        if not (lo < nxt < hi) or dv <= 0.0:
            nxt = 0.5 * (lo + hi)
        if abs(nxt - s) <= 1e-15 * (1.0 + abs(s)) or hi - lo <= 1e-15 * (1.0 + abs(s)):
            s = nxt
            break
        s = nxt
    return s


@njit
def mf_sample_visible(dist, au, av, vt, vb, vn, u0, u1):
    """A half vector ``(ht, hb, hn)`` from the distribution of normals visible from
    ``v`` (anisotropy frame, ``vn > 0``), density ``G1(v) max(0, v.h) D(h) / vn``.

    GGX: Heitz's 2018 sampler (stretch ``v``, a point of the projected half disk,
    unstretch).  Beckmann: stretch ``v``, invert the visible slope distribution along its
    azimuth (:func:`_beckmann_slope_x`) and across it (a normal slope), rotate back,
    unstretch.
    """
    sx, sy, sz, _ = kc.unitize(au * vt, av * vb, vn)
    if dist == GGX:
        lensq = sx * sx + sy * sy
        if lensq > 0.0:
            inv = 1.0 / math.sqrt(lensq)
            t1x, t1y = -sy * inv, sx * inv
        else:
            t1x, t1y = 1.0, 0.0
        # T2 = V x T1 (T1 has no z component)
        t2x, t2y, t2z = -sz * t1y, sz * t1x, sx * t1y - sy * t1x
        r = math.sqrt(u0)
        phi = 2.0 * _PI * u1
        p1 = r * math.cos(phi)
        p2 = r * math.sin(phi)
        s = 0.5 * (1.0 + sz)
        p2 = (1.0 - s) * math.sqrt(max(1.0 - p1 * p1, 0.0)) + s * p2
        pz = math.sqrt(max(1.0 - p1 * p1 - p2 * p2, 0.0))
        nx = p1 * t1x + p2 * t2x + pz * sx
        ny = p1 * t1y + p2 * t2y + pz * sy
        nz = p2 * t2z + pz * sz
        hx, hy, hz, _ = kc.unitize(au * nx, av * ny, max(nz, 0.0))
        return hx, hy, hz
    # Beckmann: slopes in the stretched space, along and across v's azimuth
    sin_t = math.sqrt(max(sx * sx + sy * sy, 0.0))
    tan_t = sin_t / sz if sz > 0.0 else 1e300
    if sin_t > 0.0:
        cp, sp = sx / sin_t, sy / sin_t
    else:
        cp, sp = 1.0, 0.0
    a = _beckmann_slope_x(tan_t, u0)
    bq = _erfinv(2.0 * u1 - 1.0)
    mx = (cp * a - sp * bq) * au
    my = (sp * a + cp * bq) * av
    hx, hy, hz, _ = kc.unitize(-mx, -my, 1.0)
    return hx, hy, hz


def microfacet_signature() -> Signature:
    """MDL's signature of the glossy lobes with scatter modes (``simple_glossy_bsdf``,
    ``microfacet_{beckmann,ggx}_{smith,vcavities}_bsdf``; MDL 1.6), plus the renderer's
    IORs on the ``+z`` and ``-z`` sides."""
    return Signature("bsdf", (
        Param("roughness_u", "float", REQUIRED, clamp=(kc.ROUGHNESS_MIN, None)),
        Param("roughness_v", "float", "roughness_u", clamp=(kc.ROUGHNESS_MIN, None)),
        Param("tint", "color", (1.0, 1.0, 1.0), clamp=(0.0, 1.0)),
        Param("multiscatter_tint", "color", (0.0, 0.0, 0.0), clamp=(0.0, 1.0)),
        Param("tangent_u", "float3", "state::texture_tangent_u(0)"),
        Param("mode", "scatter_mode", "scatter_reflect", uniform=True),
        Param("handle", "string", "", uniform=True),
        *FILM_PARAMS,
    ), context=("ior_outside", "ior_inside"))


#: the lobes of the glossy dfs with scatter modes, by mode
MICROFACET_LOBES = {"scatter_reflect": Lobe.GLOSSY_REFLECTION, "scatter_transmit": Lobe.GLOSSY,
                    "scatter_reflect_transmit": Lobe.GLOSSY}

_SIG = microfacet_signature()
_FILM_D = _SIG.offset("thin_film_thickness")
_FILM_N = _SIG.offset("thin_film_ior")
_RU = _SIG.offset("roughness_u")
_RV = _SIG.offset("roughness_v")
_TINT = _SIG.offset("tint")
_MS = _SIG.offset("multiscatter_tint")
_TANGENT = _SIG.offset("tangent_u")
_IOR_OUT = _SIG.offset("ior_outside")
_IOR_IN = _SIG.offset("ior_inside")


# --- energy compensation (multiscatter_tint), shared by the glossy lobes -------------------
@njit
def _phi(x, y, tx, ty):
    """The azimuth of ``(x, y)`` from the anisotropy axis ``t``, folded into [0, pi/2]."""
    return math.atan2(abs(x * ty - y * tx), abs(x * tx + y * ty))


@njit
def ms_on(mode, m0, m1, m2):
    """Whether the compensation lobe is on: a positive ``multiscatter_tint`` and a mode
    that reflects (``scatter_transmit`` takes none)."""
    return mode != _TRANSMIT and (m0 > 0.0 or m1 > 0.0 or m2 > 0.0)


@njit
def ms_albedo(T, t, flip, ru, rv, io, ii, tx, ty, ox, oy, oz):
    """The white single-scattering albedo ``E(wo)`` from the node's table, in [0, 1]."""
    E = lane_table_albedo(T, t, abs(oz), _phi(ox, oy, tx, ty), flip, ru, rv, io, ii)
    return min(max(E, 0.0), 1.0)


@njit
def ms_lobe(P, row, at_ms, ru, rv, io, ii, tx, ty, glossy):
    """The compensation lobe's inputs as one tuple: the table's coordinates (roughness
    ``ru``, ``rv``, at least ``ROUGHNESS_MIN``; the iors; the tangent axes), the
    ``multiscatter_tint`` at column ``at_ms`` of ``P`` and whether the single-scattering
    lobe can scatter (its tint is not black; else it is never picked)."""
    return (max(ru, kc.ROUGHNESS_MIN), max(rv, kc.ROUGHNESS_MIN), io, ii, tx, ty,
            P[row, at_ms], P[row, at_ms + 1], P[row, at_ms + 2], glossy)


@njit
def ms_eval(T, t, flip, c, ox, oy, oz, ix, iy, iz, f0, f1, f2, pdf_g):
    """The lobe with its compensation (``c``: :func:`ms_lobe`) at an oriented pair
    (``wo.z > 0``): the single-scattering eval ``f`` and pdf ``pdf_g`` plus the
    compensation lobe -> ``(f0, f1, f2, pdf)`` (0 where nothing scatters)."""
    ru, rv, io, ii, tx, ty, m0, m1, m2, glossy = c
    E1 = ms_albedo(T, t, flip, ru, rv, io, ii, tx, ty, ox, oy, oz)
    s = E1 if glossy else 0.0
    pdf = s * pdf_g
    if iz > kc.COS_ZERO:
        pdf += (1.0 - s) * iz / _PI
        Ea = min(max(lane_table_average(T, t, flip, ru, rv, io, ii), 0.0), 1.0)
        if Ea < 1.0:
            E2 = ms_albedo(T, t, flip, ru, rv, io, ii, tx, ty, ix, iy, iz)
            k = (1.0 - E1) * (1.0 - E2) * iz / (_PI * (1.0 - Ea))
            f0 += m0 * k
            f1 += m1 * k
            f2 += m2 * k
    if not (max(max(f0, f1), f2) > 0.0 and pdf > 0.0):
        return 0.0, 0.0, 0.0, 0.0
    return f0, f1, f2, pdf


@njit
def ms_choice(T, t, flip, c, ox, oy, oz, u1):
    """The lobe a sample takes: ``(single, u1')`` with the single-scattering lobe picked
    with probability ``E(wo)`` (0 for a black tint) and ``u1`` rescaled."""
    ru, rv, io, ii, tx, ty, m0, m1, m2, glossy = c
    E1 = ms_albedo(T, t, flip, ru, rv, io, ii, tx, ty, ox, oy, oz)
    s = E1 if glossy else 0.0
    if u1 < s:
        return True, min(u1 / s, kc.ONE_MINUS_EPS)
    return False, min((u1 - s) / (1.0 - s), kc.ONE_MINUS_EPS) if s < 1.0 else 0.0


@njit
def ms_sampled(T, t, flip, c, single, ox, oy, oz, ix, iy, iz, w0, w1, w2, pdf):
    """A sampled direction's weight with the compensation: the single-scattering lobe's
    weight ``w`` and pdf at the drawn ``wi`` (drawn by it where ``single``, else by the
    cosine lobe) -> ``(w0, w1, w2, pdf)`` of the whole, pdf 0 where the sample fails."""
    if single and not pdf > 0.0:
        return 0.0, 0.0, 0.0, 0.0
    f0, f1, f2, pdf = ms_eval(T, t, flip, c, ox, oy, oz, ix, iy, iz,
                              w0 * pdf, w1 * pdf, w2 * pdf, pdf)
    if not pdf > 0.0:
        return 0.0, 0.0, 0.0, 0.0
    return f0 / pdf, f1 / pdf, f2 / pdf, pdf


# --- the microfacet_* dfs: their lobe over (dist, mask), for render.df._glossy_lobe ----------
@njit
def mf_setup(dist, mask, P, row, b, flags, flip):
    """A lane's setup (:mod:`render.df._glossy_lobe`) with distribution ``dist`` and masking
    ``mask``: ``s = (dist, mask, au, av, tx, ty, eta1, eta2)``."""
    au = max(P[row, b + _RU], kc.ROUGHNESS_MIN)
    av = max(P[row, b + _RV], kc.ROUGHNESS_MIN)
    tx, ty, ok = kc.tangent_axes(P[row, b + _TANGENT], P[row, b + _TANGENT + 1],
                                P[row, b + _TANGENT + 2])
    glossy = not (P[row, b + _TINT] == 0.0 and P[row, b + _TINT + 1] == 0.0
                  and P[row, b + _TINT + 2] == 0.0)
    ms = ms_on(flags & _MODE_MASK, P[row, b + _MS], P[row, b + _MS + 1], P[row, b + _MS + 2])
    o = P[row, b + _IOR_OUT]
    i = P[row, b + _IOR_IN]
    if not (o > 0.0 and i > 0.0):
        ok = False
    if not (glossy or ms):
        ok = False
    eta1, eta2 = kc.ior_pair(o, i, flip, (flags & _THIN_WALLED) != 0, True)
    return ok, glossy, ms, flip, (dist, mask, au, av, tx, ty, eta1, eta2)


@njit
def mf_ms_lobe(P, row, b, s, glossy):
    """:func:`ms_lobe` of a lane of a microfacet_* df."""
    dist, mask, au, av, tx, ty, eta1, eta2 = s
    return ms_lobe(P, row, b + _MS, au, av, P[row, b + _IOR_OUT], P[row, b + _IOR_IN], tx, ty,
                   glossy)


@njit
def mf_value(P, row, b, flags, wox, woy, woz, wix, wiy, wiz, s):
    """The single-scattering lobe at an oriented pair -> ``(w0, w1, w2, pdf)``."""
    dist, mask, au, av, tx, ty, eta1, eta2 = s
    ok, refr, hx, hy, hz, kh1, kh2, p_ev = mf_half(flags, eta1, eta2, wox, woy, woz,
                                                   wix, wiy, wiz)
    if not ok:
        return 0.0, 0.0, 0.0, 0.0
    ht = hx * tx + hy * ty
    hb = hx * ty - hy * tx
    if mask == VCAVITIES:
        g1_1, G2 = mf_vcavities(refr, hz, woz, wiz, kh1, kh2)
    else:
        g1_1 = mf_smith_g1(dist, au, av, wox * tx + woy * ty, wox * ty - woy * tx, woz)
        G2 = g1_1 * mf_smith_g1(dist, au, av, wix * tx + wiy * ty, wix * ty - wiy * tx, wiz)
    if not G2 > 0.0:
        return 0.0, 0.0, 0.0, 0.0
    D = mf_d(dist, au, av, ht, hb, hz)
    t0, t1, t2 = P[row, b + _TINT], P[row, b + _TINT + 1], P[row, b + _TINT + 2]
    d = P[row, b + _FILM_D]
    if mf_film_on(flags, d):
        p_ev, m0, m1, m2 = mf_film_event(flags, kh1, eta1, eta2, d, P[row, b + _FILM_N],
                                         P[row, b + _FILM_N + 1], P[row, b + _FILM_N + 2],
                                         wiz < 0.0)
        if not p_ev > 0.0:
            return 0.0, 0.0, 0.0, 0.0
        t0, t1, t2 = t0 * m0, t1 * m1, t2 * m2
    return mf_finish(D, refr, woz, kh1, kh2, eta1, eta2, p_ev, g1_1, G2, t0, t1, t2)


@njit
def mf_single_sample(P, row, b, flags, wox, woy, woz, u1, u2x, u2y, s):
    """A single-scattering sample at an oriented ``wo`` -> ``(ok, wix, wiy, wiz)``."""
    dist, mask, au, av, tx, ty, eta1, eta2 = s
    if not woz > kc.COS_ZERO:
        return False, 0.0, 0.0, 0.0
    if mask == VCAVITIES:
        ht, hb, hn = mf_sample_d_cos(dist, au, av, u2x, u2y)
    else:
        ht, hb, hn = mf_sample_visible(dist, au, av, wox * tx + woy * ty, wox * ty - woy * tx,
                                       woz, u2x, u2y)
    return mf_sample_dir(flags, eta1, eta2, wox, woy, woz, ht * tx + hb * ty,
                         ht * ty - hb * tx, hn, u1, mask == VCAVITIES, P[row, b + _FILM_D],
                         P[row, b + _FILM_N], P[row, b + _FILM_N + 1], P[row, b + _FILM_N + 2])
