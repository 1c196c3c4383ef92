"""The layering framework shared by weighted, Fresnel and custom-curve layers (libbsdf's algorithm).

``reference/mdl-distribution-functions.md`` §3.  A layer node combines a ``layer`` df,
evaluated in the frame of the node's own ``normal``, and a ``base`` df, evaluated in
the inherited frame, with per-direction factors::

    eval = f_layer(wo, wi) * layer.eval(wo_L, wi_L) + f_base(wo, wi) * base.eval(wo, wi)

(``wo_L``, ``wi_L``: the directions in the layer frame).  The weighted layer has
constant factors ``w`` and ``1 - w``; the directional layers (:class:`CurveLayer`)
have ``f_layer = w C(k1.h)`` and ``f_base = 1 - w max(C(nk1), C(nk2r))`` for a curve
``C`` (Fresnel, Schlick-like custom curve).

Sampling picks the layer with probability ``P`` (a defensive mixture of the expected
contributions, :func:`render.df._combine.selection`), reuses ``u1`` rescaled, and
returns the mixture density ``P pdf_L + (1 - P) pdf_B`` (the ``pdf`` of Mitsuba's
``blendbsdf``) with the weight ``eval / pdf`` of the whole node, not of the chosen child
alone (delta events: the chosen child's weight times its factor over its probability).
A child's term in the pdf counts only where its
contribution to ``eval`` is positive, so ``pdf > 0`` exactly where ``eval > 0`` and
samples of a child whose factor vanishes at the drawn direction fail.

The layer's own normal (libbsdf, §0 and §1.4): the layer child sees the directions
rotated into the frame of ``normal``; a lane whose ``wo`` or ``wi`` lies on different
sides of the inherited and the layer tangent planes gets nothing from the layer (the
counterpart of libbsdf absorbing directions on the wrong side of the geometric
normal, which a local frame does not carry).  The base keeps the inherited frame.
"""

from __future__ import annotations

import numpy as np

from render._typing import Arr, Arr2, ArrayLike, Rgb, Vec3
from render.bsdf import Bsdf, BsdfSample, check_dirs, check_samples, lane_color, lanes
from render.df._combine import (
    LayerFrame,
    Memo,
    albedo_correction,
    any_positive,
    cheap_albedo,
    check_child,
    child_eval_pdf,
    child_sample,
    is_mirror,
    lum,
    selection,
    union_lobes,
)
from render.df._common import ior_pair, lane_ior
from render.frame import mirror_z
from render.numerics import ONE_MINUS_EPS, check_finite, fresnel_dielectric, saturate, unitize

__all__ = ["LayerBsdf", "CurveLayer", "custom_curve", "f82_curve"]


def custom_curve(c: Arr, r0: Rgb, r90: Rgb, exponent: Arr) -> Rgb:
    """MDL's Schlick-like curve ``R0 + (R90 - R0) (1 - saturate(c))^p`` per channel.

    Parameters
    ----------
    c : (n,) float64
        A cosine.
    r0, r90 : (1, 3) or (n, 3) float64
        Reflectivity at normal and grazing incidence (already saturated).
    exponent : float or (n,) float64
        ``p >= 0`` (``p = 0`` gives ``R90`` everywhere).

    Returns
    -------
    (n, 3) float64

    Examples
    --------
    >>> custom_curve(np.array([1.0, 0.0, 0.75]), np.array([[0.2] * 3]), np.array([[1.0] * 3]),
    ...              2.0)[:, 0].round(6).tolist()
    [0.2, 1.0, 0.25]
    """
    x = 1.0 - saturate(c)
    t = np.power(x, np.broadcast_to(exponent, x.shape))
    return r0 + (r90 - r0) * t[:, None]


def f82_curve(c: Arr, r0: Rgb, r90: Rgb, f82: Rgb, exponent: Arr) -> Rgb:
    """The custom curve with Hoffman's F82 tint (MDL 1.10), saturated; ``f82 = 1`` is plain.

    ``C = saturate(R0 + (R90 - R0)(1 - c)^p - a c (1 - c)^6)`` with
    ``a = (R0 + (R90 - R0)(6/7)^p) 7^7/6^6 (1 - saturate(f82))``.

    Examples
    --------
    >>> r0, r90 = np.array([[0.5] * 3]), np.array([[1.0] * 3])
    >>> c = np.array([1.0 / 7.0])
    >>> bool(np.allclose(f82_curve(c, r0, r90, np.zeros((1, 3)), 5.0), 0.0, atol=1e-12))
    True
    """
    base = custom_curve(c, r0, r90, exponent)
    p = np.broadcast_to(np.asarray(exponent, dtype=np.float64), c.shape)
    a = (r0 + (r90 - r0) * ((6.0 / 7.0) ** p)[:, None]) * (7.0**7 / 6.0**6) * (1.0 - f82)
    cc = saturate(c)
    return saturate(base - a * (cc * (1.0 - cc) ** 6)[:, None])


class LayerBsdf(Bsdf):
    """Base of the layer nodes: a ``layer`` over a ``base`` with per-direction factors.

    Subclasses implement :meth:`_factors` (the two factors at ``(wo, wi)``),
    :meth:`_estimates` (their expected values at ``wo``, for sampling) and
    :meth:`_possible` (lanes where each side can contribute at all).

    Parameters
    ----------
    layer, base : Bsdf or None
        None is MDL's ``bsdf()`` (black).
    normal : (3,) or (n, 3)
        The layer's normal in the inherited local frame (default ``+z``: the inherited
        normal; :meth:`render.material.DfNode.bind` converts MDL's object-space value).
    tangent_u : (3,) or (n, 3)
        ``state::texture_tangent_u(0)`` in the inherited local frame (orients the layer
        frame; default ``+x``).
    """

    #: whether ``_factors`` depends on the directions (else the albedo is exact).
    _directional = True

    def __init__(self, layer, base, normal: ArrayLike = (0.0, 0.0, 1.0),
                 tangent_u: ArrayLike = (1.0, 0.0, 0.0)):
        self.layer = check_child(layer, "layer")
        self.base = check_child(base, "base")
        self.layer_frame = LayerFrame(normal, tangent_u)
        self.lobes = union_lobes(self.layer, self.base)
        self._select_memo, self._cheap_memo = Memo(), Memo()

    # --- subclass hooks -----------------------------------------------------------------

    def _factors(self, wo: Vec3, wi: Vec3, wo_l: Vec3, wi_l: Vec3) -> tuple[Rgb, Rgb]:
        raise NotImplementedError

    def _estimates(self, wo: Vec3, wo_l: Vec3) -> tuple[Rgb, Rgb]:
        raise NotImplementedError

    def _possible(self, n: int) -> tuple[np.ndarray, np.ndarray]:
        raise NotImplementedError

    # --- shared machinery ---------------------------------------------------------------

    def _select(self, wo: Vec3, wo_l: Vec3, agree_o: np.ndarray) -> Arr:
        """Probability of sampling the layer, per lane."""
        return self._select_memo.get(wo, lambda: self._select_now(wo, wo_l, agree_o))

    def _select_now(self, wo: Vec3, wo_l: Vec3, agree_o: np.ndarray) -> Arr:
        n = len(wo)
        est_l, est_b = self._estimates(wo, wo_l)
        a_l = cheap_albedo(self.layer, wo_l)
        a_b = cheap_albedo(self.base, wo)
        pos_l, pos_b = self._possible(n)
        pos_l = pos_l & agree_o
        e = np.stack([lum(est_l * a_l), lum(est_b * a_b)], axis=1)
        return selection(e, np.stack([pos_l, pos_b], axis=1))[:, 0]

    def _parts(self, wo: Vec3, wi: Vec3, P: Arr | None = None):
        """Everything eval, pdf and sample need at ``(wo, wi)`` (``P``: the selection)."""
        lf = self.layer_frame
        wo_l, wi_l = lf.to_layer(wo), lf.to_layer(wi)
        agree_o = lf.agree(wo, wo_l)
        ok_l = agree_o & lf.agree(wi, wi_l)
        e_l, p_l = child_eval_pdf(self.layer, wo_l, wi_l)
        e_b, p_b = child_eval_pdf(self.base, wo, wi)
        f_l, f_b = self._factors(wo, wi, wo_l, wi_l)
        f_l = np.where(ok_l[:, None], f_l, 0.0)
        c_l = f_l * e_l
        c_b = f_b * e_b
        if P is None:
            P = self._select(wo, wo_l, agree_o)
        pdf = P * p_l * any_positive(c_l) + (1.0 - P) * p_b * any_positive(c_b)
        value = np.where((pdf > 0)[:, None], c_l + c_b, 0.0)
        return value, pdf, f_l, f_b, any_positive(c_l), any_positive(c_b)

    def eval_pdf(self, wo: Vec3, wi: Vec3) -> tuple[Rgb, Arr]:
        wo, wi = check_dirs(wo, wi)
        value, pdf = self._parts(wo, wi)[:2]
        name = type(self).__name__
        return check_finite(f"{name}.eval", value, True), check_finite(f"{name}.pdf", pdf, True)

    def eval(self, wo: Vec3, wi: Vec3) -> Rgb:
        return self.eval_pdf(wo, wi)[0]

    def pdf(self, wo: Vec3, wi: Vec3) -> Arr:
        return self.eval_pdf(wo, wi)[1]

    def sample(self, wo: Vec3, u1: Arr, u2: Arr2) -> BsdfSample:
        (wo,) = check_dirs(wo, names=("wo",))
        n = len(wo)
        u1, u2 = check_samples(n, u1, u2)
        lf = self.layer_frame
        wo_l = lf.to_layer(wo)
        P = self._select(wo, wo_l, lf.agree(wo, wo_l))
        take_l = u1 < P
        u_l = np.clip(u1 / np.where(P > 0, P, 1.0), 0.0, ONE_MINUS_EPS)
        u_b = np.clip((u1 - P) / np.where(P < 1, 1.0 - P, 1.0), 0.0, ONE_MINUS_EPS)
        s_l = child_sample(self.layer, wo_l, np.where(take_l, u_l, 0.0), u2)
        s_b = child_sample(self.base, wo, np.where(take_l, 0.0, u_b), u2)
        wi = np.where(take_l[:, None], lf.to_inherited(s_l.wi), s_b.wi)
        valid = np.where(take_l, s_l.valid, s_b.valid)
        delta = np.where(take_l, s_l.is_delta, s_b.is_delta)
        wi = np.where(valid[:, None], wi, np.array([0.0, 0.0, 1.0]))
        value, pdf, f_l, f_b, on_l, on_b = self._parts(wo, wi, P)
        # non-delta: the combined density; the chosen child must contribute at wi
        ok_nd = valid & ~delta & np.where(take_l, on_l, on_b) & (pdf > 0)
        w_nd = value / np.where(ok_nd, pdf, 1.0)[:, None]
        # delta: the chosen child's weight times its factor over its probability
        p_sel = np.where(take_l, P, 1.0 - P)
        w_d = np.where(take_l[:, None], f_l * s_l.weight, f_b * s_b.weight) / np.where(
            p_sel > 0, p_sel, 1.0
        )[:, None]
        pdf_d = p_sel * np.where(take_l, s_l.pdf, s_b.pdf)
        ok_d = valid & delta & any_positive(w_d) & (pdf_d > 0)
        ok = ok_nd | ok_d
        lobe = np.where(take_l, s_l.lobe, s_b.lobe)
        return BsdfSample(
            np.where(ok[:, None], wi, 0.0),
            np.where(ok_nd, pdf, np.where(ok_d, pdf_d, 0.0)),
            np.where(ok_nd[:, None], w_nd, np.where(ok_d[:, None], w_d, 0.0)),
            np.where(ok, lobe, 0).astype(np.int32),
        ).checked()

    def albedo(self, wo: Vec3) -> Rgb:
        """Directional albedo ``∫ eval dwi`` (plus delta lobes).

        ``est_L albedo_L + est_B albedo_B`` with the factors' values at ``wo`` (exact
        for the weighted layer), plus the integral of each factor's deviation from that
        value over the child's lobe (:func:`render.df._combine.albedo_correction`,
        skipped where it vanishes: a mirror child in an untilted frame, constant
        factors).  Measured accuracy: ``tests/render/df``.
        """
        (wo,) = check_dirs(wo, names=("wo",))
        n = len(wo)
        lf = self.layer_frame
        wo_l = lf.to_layer(wo)
        agree_o = lf.agree(wo, wo_l)
        est_l, est_b = self._estimates(wo, wo_l)
        est_l = np.where(agree_o[:, None], est_l, 0.0)
        out = np.zeros((n, 3))
        if self.layer is not None:
            out += est_l * self.layer.albedo(wo_l)
            exact = lf.identity and (not self._directional or is_mirror(self.layer))
            if not exact:

                def f_layer(wi_l):
                    wi = lf.to_inherited(wi_l)
                    f, _ = self._factors(wo, wi, wo_l, wi_l)
                    return np.where((agree_o & lf.agree(wi, wi_l))[:, None], f, 0.0)

                out += albedo_correction(self.layer, wo_l, f_layer, est_l)
        if self.base is not None:
            out += est_b * self.base.albedo(wo)
            exact = not self._directional or (lf.identity and is_mirror(self.base))
            if not exact:

                def f_base(wi):
                    return self._factors(wo, wi, wo_l, lf.to_layer(wi))[1]

                out += albedo_correction(self.base, wo, f_base, est_b)
        return np.clip(out, 0.0, None)

    def _cheap_albedo(self, wo: Vec3) -> Rgb:
        """Albedo estimate for selection: expected factors times the children's estimates."""
        return self._cheap_memo.get(wo, lambda: self._cheap_albedo_now(wo))

    def _cheap_albedo_now(self, wo: Vec3) -> Rgb:
        lf = self.layer_frame
        wo_l = lf.to_layer(wo)
        est_l, est_b = self._estimates(wo, wo_l)
        a_l = cheap_albedo(self.layer, wo_l) * lf.agree(wo, wo_l)[:, None]
        return est_l * a_l + est_b * cheap_albedo(self.base, wo)


class CurveLayer(LayerBsdf):
    """libbsdf's directional layering with a curve ``C`` (§3.2), per direction.

    With ``nk1 = saturate(n_L.wo)``, ``nk2 = |n_L.wi|`` and the half vector ``h``
    (reflection: ``wo + wi``; transmission: ``wi`` mirrored through the layer's tangent
    plane first, or the refraction half vector for the Fresnel layers on non-thin-walled
    surfaces, where ``nk2r = 2 (wo.h)(n_L.h) - nk1``)::

        f_layer = w C(|wo.h|),     f_base = 1 - w max(C(nk1), C(nk2r)),

    estimates (for sampling) ``w C(nk1)`` and ``1 - w C(nk1)``.  Reflection versus
    transmission is decided in the inherited frame (``wo.z wi.z < 0``).

    Subclasses set ``self.weight`` ((1|n, 3) colour, saturated) and implement
    :meth:`_curve` (``c (n,) -> (n, 3)``, given the per-call context from
    :meth:`_context`).
    """

    #: use the refraction half vector for transmission (Fresnel layers)
    _refractive = False

    def __init__(self, weight, layer, base, normal, tangent_u, ior_outside=1.0, ior_inside=1.0,
                 thin_walled=False):
        super().__init__(layer, base, normal, tangent_u)
        self.weight = saturate(lane_color(weight, "weight"))
        self.ior_outside = lane_ior(ior_outside, "ior_outside")
        self.ior_inside = lane_ior(ior_inside, "ior_inside")
        self.thin_walled = bool(thin_walled)

    def _context(self, wo: Vec3):
        """Per-call values the curve needs (lanes of ``wo``)."""
        return None

    def _curve(self, c: Arr, ctx) -> Rgb:
        raise NotImplementedError

    def _curve_max(self, n: int) -> Rgb:
        """An upper bound of ``C`` over cosines (1 by default)."""
        return np.ones((n, 3))

    def _curve_is_one(self, n: int) -> np.ndarray:
        """(n,) bool: lanes where ``C == 1`` at every cosine (the base never shows)."""
        return np.zeros(n, dtype=bool)

    def _w(self, n: int) -> Rgb:
        return np.broadcast_to(lanes(self.weight, n, "weight"), (n, 3))

    def _possible(self, n: int):
        w = self._w(n)
        pos_l = np.full(n, self.layer is not None) & np.any(w * self._curve_max(n) > 0, axis=1)
        pos_b = np.full(n, self.base is not None) & ~(np.all(w == 1.0, axis=1)
                                                      & self._curve_is_one(n))
        return pos_l, pos_b

    def _estimates(self, wo: Vec3, wo_l: Vec3):
        n = len(wo)
        s = np.where(wo_l[:, 2] < 0.0, -1.0, 1.0)
        nk1 = np.clip(wo_l[:, 2] * s, 0.0, 1.0)
        c1 = self._w(n) * self._curve(nk1, self._context(wo))
        return c1, 1.0 - c1

    def _factors(self, wo, wi, wo_l, wi_l):
        n = len(wo)
        ctx = self._context(wo)
        w = self._w(n)
        # orient the layer frame so that wo_l is on top
        s = np.where(wo_l[:, 2] < 0.0, -1.0, 1.0)
        o = wo_l * np.stack([np.ones(n), np.ones(n), s], axis=1)
        i = wi_l * np.stack([np.ones(n), np.ones(n), s], axis=1)
        nk1 = np.clip(o[:, 2], 0.0, 1.0)
        nk2 = np.minimum(np.abs(i[:, 2]), 1.0)
        tr = wo[:, 2] * wi[:, 2] < 0.0
        h, ok = unitize(o + mirror_z(i, tr))
        nk2r = nk2
        if self._refractive and not self.thin_walled:
            eta1, eta2 = ior_pair(
                lanes(self.ior_outside, n, "ior_outside"),
                lanes(self.ior_inside, n, "ior_inside"),
                wo[:, 2] < 0.0,
                self.thin_walled,
                glossy=False,
            )
            h_r, ok_r = unitize(eta1[:, None] * o + eta2[:, None] * i)
            h_r = h_r * np.sign(eta1 - eta2)[:, None]
            ok_r &= eta1 != eta2
            h = np.where(tr[:, None], h_r, h)
            ok = np.where(tr, ok_r, ok)
        h = np.where(ok[:, None], h, np.array([0.0, 0.0, 1.0]))
        kh = np.minimum(np.abs(np.einsum("ij,ij->i", o, h)), 1.0)
        if self._refractive and not self.thin_walled:
            nk2r = np.where(tr, np.clip(2.0 * kh * h[:, 2] - nk1, 0.0, 1.0), nk2)
        c_h = self._curve(kh, ctx)
        c_max = np.maximum(self._curve(nk1, ctx), self._curve(nk2r, ctx))
        return w * c_h, 1.0 - w * c_max


class FresnelCurve:
    """Dielectric Fresnel per channel with the layer's ``ior`` (libbsdf's side rule).

    Outside (``wo.z >= 0`` or thin-walled): ``C = F(ior / eta1)``; inside:
    ``C = F(eta2 / ior)``, where ``(eta1, eta2)`` is the renderer's IOR pair on ``wo``'s
    side and the far side.
    """

    @staticmethod
    def eta(ior: Rgb, ior_outside: Arr, ior_inside: Arr, wo: Vec3, thin_walled: bool) -> Rgb:
        n = len(wo)
        flip = wo[:, 2] < 0.0
        eta1, eta2 = ior_pair(ior_outside, ior_inside, flip, thin_walled, glossy=False)
        inside = flip & (not thin_walled)
        ior = np.broadcast_to(ior, (n, 3))
        return np.where(inside[:, None], eta2[:, None] / ior, ior / eta1[:, None])

    @staticmethod
    def value(c: Arr, eta: Rgb) -> Rgb:
        cc = np.broadcast_to(np.clip(c, 0.0, 1.0)[:, None], eta.shape)
        return fresnel_dielectric(cc, eta)[0]

