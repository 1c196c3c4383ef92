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
    lane_vector,
    lanes,
)
from render.df import _kernel_common as kc
from render.df._common import ScatterMode, ior_pair, lane_ior, orient, tangent_axes
from render.df._signature import MODE_MASK, REFLECT, THIN_WALLED, TRANSMIT
from render.frame import mirror_z
from render.jit import njit
from render.numerics import (
    ONE_MINUS_EPS,
    TOL,
    check_finite,
    dot,
    fresnel_dielectric,
    row_max,
    saturate,
    unitize,
)

__all__ = ["MicrofacetBsdf"]

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
    """``MicrofacetBsdf._p_reflect``: probability of reflection given ``kh1 = wo.h``."""
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
    """The first half of ``MicrofacetBsdf._kernel`` for an oriented lane (``wo.z >= 0``).

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
    """The second half of ``MicrofacetBsdf._kernel``: ``D = D(h)`` -> ``(w0, w1, w2, pdf)``
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
    """``MicrofacetBsdf.sample`` from a half vector drawn from ``D (n.h)`` (local frame)
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


class MicrofacetBsdf(Bsdf):
    """Base of the v-cavities microfacet lobes (``simple_glossy_bsdf``...).

    Parameters
    ----------
    roughness_u : float or (n,)
        Roughness along ``tangent_u``; clamped below at ``TOL.roughness_min``.
    roughness_v : float or (n,) or None
        Roughness across it; ``None`` means ``roughness_u`` (MDL's default).
    tint : float, (3,) or (n, 3)
        Saturated to [0, 1].
    tangent_u : (3,) or (n, 3)
        Anisotropy direction in the local frame (default ``+x``, which is
        ``state::texture_tangent_u(0)`` when the frame is built from it).
    mode : ScatterMode or str
    ior_outside, ior_inside : float or (n,)
        IORs on the ``+z`` / ``-z`` sides, given by the renderer (``material.ior``).
    thin_walled : bool
    """

    def __init__(
        self,
        roughness_u: ArrayLike,
        roughness_v: ArrayLike | None = None,
        tint: ArrayLike = 1.0,
        tangent_u: ArrayLike = (1.0, 0.0, 0.0),
        mode: ScatterMode | str = ScatterMode.scatter_reflect,
        ior_outside: ArrayLike = 1.0,
        ior_inside: ArrayLike = 1.0,
        thin_walled: bool = False,
    ):
        self.roughness_u = np.maximum(lane_float(roughness_u, "roughness_u"), TOL.roughness_min)
        rv = roughness_u if roughness_v is None else roughness_v
        self.roughness_v = np.maximum(lane_float(rv, "roughness_v"), TOL.roughness_min)
        self.tint = saturate(lane_color(tint, "tint"))
        self.tangent_u = lane_vector(tangent_u, "tangent_u")
        self.mode = ScatterMode.parse(mode)
        self.ior_outside = lane_ior(ior_outside, "ior_outside")
        self.ior_inside = lane_ior(ior_inside, "ior_inside")
        self.thin_walled = bool(thin_walled)
        self._black = np.all(self.tint == 0, axis=1)
        self.lobes = {
            ScatterMode.scatter_reflect: Lobe.GLOSSY_REFLECTION,
            ScatterMode.scatter_transmit: Lobe.GLOSSY,
            ScatterMode.scatter_reflect_transmit: Lobe.GLOSSY,
        }[self.mode]

    def __repr__(self) -> str:
        return (
            f"{self._mdl_name}(roughness_u={self.roughness_u.tolist()}, "
            f"roughness_v={self.roughness_v.tolist()}, tint={self.tint.tolist()}, "
            f"mode={self.mode.value}, ior_outside={self.ior_outside.tolist()}, "
            f"ior_inside={self.ior_inside.tolist()}, thin_walled={self.thin_walled})"
        )

    _mdl_name = "microfacet"

    # --- the subclass supplies the distribution -------------------------------------

    def _distribution(self, ru: Arr, rv: Arr):
        raise NotImplementedError

    # --- per-call lane setup ------------------------------------------------------------

    def _setup(self, n: int, flip: np.ndarray):
        ru = np.broadcast_to(lanes(self.roughness_u, n, "roughness_u"), (n,))
        rv = np.broadcast_to(lanes(self.roughness_v, n, "roughness_v"), (n,))
        tx, ty, tvalid = tangent_axes(lanes(self.tangent_u, n, "tangent_u"), n)
        eta1, eta2 = ior_pair(
            lanes(self.ior_outside, n, "ior_outside"),
            lanes(self.ior_inside, n, "ior_inside"),
            flip,
            self.thin_walled,
            glossy=True,
        )
        black = np.broadcast_to(lanes(self._black, n, "tint"), (n,))
        tint = np.broadcast_to(lanes(self.tint, n, "tint"), (n, 3))
        return self._distribution(ru, rv), tx, ty, tvalid & ~black, eta1, eta2, tint

    def _p_reflect(self, kh1: Arr, eta1: Arr, eta2: Arr) -> Arr:
        """Probability of reflection given the microfacet (cosine ``kh1 = wo.h``)."""
        if self.mode is ScatterMode.scatter_reflect:
            return np.ones_like(kh1)
        if self.mode is ScatterMode.scatter_transmit:
            if self.thin_walled:
                return np.zeros_like(kh1)
            b = eta1 / eta2
            return np.where(b * b * (1.0 - kh1 * kh1) > 1.0, 1.0, 0.0)  # total internal reflection
        F, _ = fresnel_dielectric(kh1, eta2 / eta1)
        return F

    def _kernel(self, wo: Vec3, wi: Vec3, setup) -> tuple[Rgb, Arr, np.ndarray]:
        """Oriented lanes -> (weight = eval/pdf, pdf, eval scale, valid)."""
        dist, tx, ty, ok, eta1, eta2, tint = setup
        nk1 = wo[:, 2]
        tr = wi[:, 2] < 0.0
        refr = tr & (not self.thin_walled)
        ok = ok & (nk1 > TOL.cos_zero) & (np.abs(wi[:, 2]) > TOL.cos_zero)
        if self.mode is ScatterMode.scatter_reflect:
            ok &= ~tr
        # half vector: reflection, thin-walled transmission (mirror wi up), refraction
        k2r = mirror_z(wi, tr)
        h, valid = unitize(wo + k2r)
        if np.any(refr & ok):
            h_refr, v2 = unitize(eta1[:, None] * wo + eta2[:, None] * wi)
            h_refr = h_refr * np.sign(eta1 - eta2)[:, None]
            h = np.where(refr[:, None], h_refr, h)
            valid = np.where(refr, v2, valid)
            kh2 = np.where(refr, dot(wi, h), dot(k2r, h))
        else:
            # no lane refracts (refracting lanes that are already invalid are zeroed below)
            refr = np.zeros_like(refr)
            kh2 = dot(k2r, h)
        ok &= valid
        kh1 = dot(wo, h)
        ok &= (h[:, 2] > TOL.cos_zero) & (kh1 > 0.0) & np.where(refr, kh2 < 0.0, kh2 > 0.0)
        p_refl = self._p_reflect(np.where(ok, kh1, 1.0), eta1, eta2)
        P = np.where(tr, 1.0 - p_refl, p_refl)
        ok &= P > 0.0
        # v-cavities masking
        hn = h[:, 2]
        safe_kh1 = np.where(ok, kh1, 1.0)
        safe_kh2 = np.where(ok, np.abs(kh2), 1.0)
        g1_1 = np.minimum(1.0, 2.0 * hn * nk1 / safe_kh1)
        g1_2 = np.minimum(1.0, 2.0 * hn * np.abs(wi[:, 2]) / safe_kh2)
        G2 = np.where(refr, np.maximum(g1_1 + g1_2 - 1.0, 0.0), np.minimum(g1_1, g1_2))
        ok &= G2 > 0.0
        # distribution in the anisotropy frame (t = (tx, ty, 0), b = (ty, -tx, 0))
        ht = h[:, 0] * tx + h[:, 1] * ty
        hb = h[:, 0] * ty - h[:, 1] * tx
        safe_hn = np.where(ok, hn, 1.0)
        D = dist.d_cos(ht, hb, safe_hn) / safe_hn
        safe_nk1 = np.where(ok, nk1, 1.0)
        den = eta1 * kh1 + eta2 * kh2
        safe_den = np.where(ok & refr, den * den, 1.0)
        pdf0 = np.where(
            refr, D * kh1 * np.abs(kh2) * eta2 * eta2 / (safe_nk1 * safe_den), D / (4.0 * safe_nk1)
        )
        pdf = P * g1_1 * pdf0
        weight = tint * (G2 / np.where(ok, g1_1, 1.0))[:, None]
        # pdf > 0 exactly where eval = weight * pdf > 0 (also where the product underflows)
        ok &= row_max(weight * pdf[:, None]) > 0.0
        return np.where(ok[:, None], weight, 0.0), np.where(ok, pdf, 0.0), ok

    # --- the Bsdf interface -------------------------------------------------------------

    def eval_pdf(self, wo: Vec3, wi: Vec3) -> tuple[Rgb, Arr]:
        wo, wi = check_dirs(wo, wi)
        flip, wo, wi = orient(wo, wi)
        weight, pdf, ok = self._kernel(wo, wi, self._setup(len(wo), flip))
        value = weight * pdf[:, None]
        return check_finite(f"{self._mdl_name}.eval", value, True), check_finite(
            f"{self._mdl_name}.pdf", pdf, True
        )

    def eval(self, wo: Vec3, wi: Vec3) -> Rgb:
        return self.eval_pdf(wo, wi)[0]

    def pdf(self, wo: Vec3, wi: Vec3) -> Arr:
        return self.eval_pdf(wo, wi)[1]

    def sample(self, wo: Vec3, u1: Arr, u2: Arr2) -> BsdfSample:
        (wo,) = check_dirs(wo, names=("wo",))
        n = len(wo)
        u1, u2 = check_samples(n, u1, u2)
        flip, wo = orient(wo)
        setup = self._setup(n, flip)
        dist, tx, ty, ok, eta1, eta2, _ = setup
        # half vector from D (n.h), in the anisotropy frame, then into the local frame
        ht, hb, hn = dist.sample(u2)
        h = np.stack([ht * tx + hb * ty, ht * ty - hb * tx, hn], axis=1)
        # v-cavities: the facet rotated by pi about n, chosen with prob. ~ max(0, wo.h')
        h_alt = h * np.array([-1.0, -1.0, 1.0])
        a = np.maximum(dot(wo, h), 0.0)
        a_alt = np.maximum(dot(wo, h_alt), 0.0)
        tot = a + a_alt
        ok &= tot > 0.0
        q = a_alt / np.where(tot > 0.0, tot, 1.0)
        take_alt = u1 < q
        # reuse u1 for the event choice
        u1 = np.where(
            take_alt, u1 / np.where(q > 0, q, 1.0), (u1 - q) / np.where(q < 1, 1.0 - q, 1.0)
        )
        u1 = np.clip(u1, 0.0, ONE_MINUS_EPS)
        h = np.where(take_alt[:, None], h_alt, h)
        c = dot(wo, h)
        ok &= c > 0.0
        refl = u1 < self._p_reflect(np.where(ok, c, 1.0), eta1, eta2)
        k_refl = 2.0 * c[:, None] * h - wo
        if np.all(refl):
            wi = k_refl
        else:
            if self.thin_walled:
                k_tr = mirror_z(k_refl)
            else:
                # refraction about h with b = eta1/eta2 (never total internal: then refl is True)
                b = eta1 / eta2
                ct = np.sqrt(np.maximum(1.0 - b * b * (1.0 - c * c), 0.0))
                k_tr, _ = unitize(-b[:, None] * wo + (b * c - ct)[:, None] * h)
            wi = np.where(refl[:, None], k_refl, k_tr)
        ok &= np.where(refl, wi[:, 2] > 0.0, wi[:, 2] < 0.0)
        weight, pdf, ok2 = self._kernel(wo, wi, setup)
        ok &= ok2
        lobe = np.where(wi[:, 2] < 0.0, _TR, _RE)
        return BsdfSample(
            np.where(ok[:, None], mirror_z(wi, flip), 0.0),
            np.where(ok, pdf, 0.0),
            np.where(ok[:, None], weight, 0.0),
            np.where(ok, lobe, 0).astype(np.int32),
        ).checked()

    def albedo(self, wo: Vec3) -> Rgb:
        """Directional albedo from tables built by quasi-Monte Carlo (``render.df._albedo``).

        Thin-walled surfaces and ``scatter_reflect`` share the reflection table (the
        Fresnel split cancels in the weights); roughness above 1 reads roughness 1.
        """
        from render.df._albedo import glossy_albedo

        (wo,) = check_dirs(wo, names=("wo",))
        n = len(wo)
        flip = wo[:, 2] < 0.0
        _, tx, ty, ok, eta1, eta2, tint = self._setup(n, flip)
        ru = np.broadcast_to(lanes(self.roughness_u, n, "roughness_u"), (n,))
        rv = np.broadcast_to(lanes(self.roughness_v, n, "roughness_v"), (n,))
        mu = np.abs(wo[:, 2])
        phi = np.arctan2(
            np.abs(wo[:, 0] * ty - wo[:, 1] * tx), np.abs(wo[:, 0] * tx + wo[:, 1] * ty)
        )
        if self.mode is ScatterMode.scatter_reflect or self.thin_walled:
            key_mode, eta = ScatterMode.scatter_reflect, np.ones(n)
        else:
            key_mode, eta = self.mode, eta2 / eta1
        E = glossy_albedo(type(self), key_mode, eta, ru, rv, mu, phi)
        return np.where((ok & (mu > TOL.cos_zero))[:, None], tint * E[:, None], 0.0)
