"""libbsdf's microfacet framework with v-cavities masking, shared by the glossy lobes.

``reference/mdl-distribution-functions.md`` §2.4.  A subclass supplies the normal
distribution as an object with ``d_cos(ht, hb, hn) -> D(h) (n.h)`` and
``sample(u2) -> (ht, hb, hn)`` (a density ``D(h) (n.h)`` over half vectors, in the
anisotropy frame ``t, b, n``) and a ``_table_kind`` for the tabulated albedo.

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
from a sampled half vector for ``sample``; the df module composes them
(``simple_glossy_bsdf.eval_pdf``).

Departures from libbsdf, all deliberate:

* the refraction pdf carries the Jacobian factor ``eta2^2`` that libbsdf omits (its
  sample weights are unchanged; only MIS and the pdf integral are corrected);
* ``pdf`` is 0 wherever ``eval`` is 0 (``G2 = 0`` in refraction, black ``tint``), and
  ``sample`` fails there instead of returning a zero-weight direction;
* ``multiscatter_tint`` (energy compensation) is not implemented yet.
"""

from __future__ import annotations

import math

from render.bsdf import (
    Lobe,
)
from render.df import _kernel_common as kc
from render.df._signature import MODE_MASK, REFLECT, THIN_WALLED, TRANSMIT
from render.jit import njit

__all__ = ["mf_p_reflect", "mf_geometry", "mf_finish", "mf_sample_dir"]

_TR = int(Lobe.GLOSSY_TRANSMISSION)
_RE = int(Lobe.GLOSSY_REFLECTION)

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
def mf_geometry(flags, eta1, eta2, wox, woy, woz, wix, wiy, wiz):
    """The first half of the microfacet evaluation for an oriented lane (``wo.z >= 0``).

    Returns ``(ok, refr, hx, hy, hz, kh1, kh2, P, g1_1, G2)``: the half vector, its
    cosines with ``wo`` and (mirrored) ``wi``, the event probability and the v-cavities
    masking terms; the caller evaluates ``D`` at ``h`` (only where ``ok``).
    """
    mode = flags & _MODE_MASK
    thin = (flags & _THIN_WALLED) != 0
    nk1 = woz
    tr = wiz < 0.0
    refr = tr and not thin
    if not (nk1 > kc.COS_ZERO and abs(wiz) > kc.COS_ZERO) or (mode == _REFLECT and tr):
        return False, False, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0
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
        return False, False, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0
    kh1 = kc.dot3(wox, woy, woz, hx, hy, hz)
    if not (hz > kc.COS_ZERO and kh1 > 0.0 and ((kh2 < 0.0) if refr else (kh2 > 0.0))):
        return False, False, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0
    p_refl = mf_p_reflect(mode, thin, kh1, eta1, eta2)
    P = 1.0 - p_refl if tr else p_refl
    if not P > 0.0:
        return False, False, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0
    # v-cavities masking
    g1_1 = min(1.0, 2.0 * hz * nk1 / kh1)
    g1_2 = min(1.0, 2.0 * hz * abs(wiz) / abs(kh2))
    G2 = max(g1_1 + g1_2 - 1.0, 0.0) if refr else min(g1_1, g1_2)
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
def mf_sample_dir(flags, eta1, eta2, wox, woy, woz, hx, hy, hz, u1):
    """microfacet sampling from a half vector drawn from ``D (n.h)`` (local frame)
    to ``wi``, for an oriented lane: the v-cavities flip, the event, reflect or refract.

    Returns ``(ok, wix, wiy, wiz)``.
    """
    mode = flags & _MODE_MASK
    thin = (flags & _THIN_WALLED) != 0
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
