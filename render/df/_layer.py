"""The layering framework shared by weighted, Fresnel and custom-curve layers (libbsdf's algorithm).

``reference/mdl-distribution-functions.md`` §3.  A layer node combines a ``layer`` df,
evaluated in the frame of the node's own ``normal``, and a ``base`` df, evaluated in
the inherited frame, with per-direction factors::

    eval = f_layer(wo, wi) * layer.eval(wo_L, wi_L) + f_base(wo, wi) * base.eval(wo, wi)

(``wo_L``, ``wi_L``: the directions in the layer frame).  The weighted layer has
constant factors ``w`` and ``1 - w``; the directional layers (:class:`CurveLayer`)
have, for a curve ``C`` (Fresnel, Schlick-like custom curve)::

    f_layer = w C(|wo.h|),
    f_base  = max(0, 1 - w max(C(nk1), C(nk2r), Ĉ(wo), Ĉ(wi)))

where ``Ĉ(v) = ∫ C(|v.h|) layer.eval(v, x) dx`` is the layer's **curve-weighted
directional albedo** seen from ``v`` (its own curve context, half vectors and delta
lobes included; 0 where ``v`` lies on different sides of the two tangent planes).

Energy (white furnace).  libbsdf's base factor ``1 - w max(C(nk1), C(nk2r))`` alone
lets the node gain energy: a rough layer sees tilted half vectors with
``C(|wo.h|) > C(nk1)`` while a mirror or narrow glossy base keeps ``1 - w C(nk1)``
(measured with libbsdf's rule: ``fresnel_layer(1.5, glossy r 0.2, mirror)`` 1.0021 at
45 degrees, ``custom_curve_layer(0, 1, 1, glossy r 0.5, mirror)`` 1.0647 at normal
incidence).  The ``Ĉ`` terms close that gap.  **Bound**: per channel, with ``a_B(wo)``
the base's albedo (``<= 1``)::

    albedo(wo) = ∫ f_layer layer.eval + ∫ f_base base.eval
              <= w Ĉ(wo) + ∫ f_base base.eval          (the layer's term is w Ĉ(wo), or less
                                                        with the numerical Ĉ, an upper value)
              <= w Ĉ(wo) + (1 - w Ĉ(wo)) a_B(wo)       (f_base <= 1 - w Ĉ(wo), and Ĉ <= 1)
              <= 1.

``Ĉ(wo) <= 1`` because ``C <= 1`` and the layer's albedo is ``<= 1``; the ``Ĉ(wi)`` term
only keeps ``f_base`` symmetric (reciprocal wherever libbsdf's is) and can only lower
it.  The bound needs nothing of the base, so it holds for transmitting, glossy, delta
and nested bases, and by induction for nested layers.  The numerical ``Ĉ`` is an upper
estimate (below), within about 1e-3 of it, which is the only slack.

Where the node loses energy (as libbsdf does, documented in the reference): the base
keeps ``1 - w max(C(nk1), C(nk2r))`` of its lobe, so the part of it that leaves at
grazing angles (``C(nk2r) > C(nk1)``) is lost, and the layer's own loss (its albedo
below 1, its energy at ``C(|wo.h|) < C(nk1)``) is not handed to the base.  A smooth
white coat over a white Lambertian base loses 3 % at 60 degrees (Fresnel 1.5).

Departure from libbsdf: only ``f_base``, and only where ``Ĉ`` exceeds libbsdf's
``max(C(nk1), C(nk2r))`` (never for a mirror layer or a constant curve, where
``Ĉ = C(nk) albedo_L <= C(nk)``: those keep libbsdf's factors exactly).  The layer's
lobe, and hence the look of every coat, is libbsdf's.  With a diffuse base ``C(nk2r)``
exceeds ``Ĉ`` almost everywhere, so the change shows mostly over mirror and glossy bases
viewed near the angles where the rough coat's half vectors see more of the curve than
the macro normal.

Computing ``Ĉ`` (:class:`CurveAlbedo`): an importance-sampled quadrature through the
layer's own sampler over :data:`CURVE_ALBEDO_POINTS` Sobol points (:func:`sobol_points`),
with ``C(nk) albedo_L`` as control variate where the layer's albedo is a closed form or a
table (elemental dfs).  It is tabulated over the layer-frame polar angle, each side on
first use (the largest value over four azimuths, so anisotropic layers are bounded too;
linear in the angle between nodes plus a correction in concave intervals, so the table
stays an upper value), in the layer frame and without the two frames' side tests on
``wi``, which can only raise it.  A table is shared by every node whose curve and layer
have the same structure and parameter values within :data:`LANE_SPREAD_MAX`
(:func:`df_signature`): built once per material, not per shading batch.  Per-lane
parameters whose rows are alike (constants bound per lane, normals bent in the local
frame) are tabulated through calls of the node's own lane count; per-lane values that
differ (textures) cannot be: ``Ĉ`` is then integrated per call at the directions
themselves over :data:`CURVE_ALBEDO_DIRECT_POINTS` points (``Ĉ(wo)`` memoised), correct
but less accurate and at that many layer samples per lane and call.  Measured accuracy
where ``Ĉ`` matters (where it exceeds libbsdf's factor): the table is above the
integral, or below by at most 4e-4 for elemental layers and 3e-3 for layered ones (whose
lobes jump at total internal reflection).

Sampling picks the layer with probability ``P`` (a defensive mixture of the expected
contributions, :func:`render.df._combine.selection`), reuses ``u1`` rescaled, and
returns the mixture density ``P pdf_L + (1 - P) pdf_B`` (the ``pdf`` of Mitsuba's
``blendbsdf``) with the weight ``eval / pdf`` of the whole node, not of the chosen child
alone (delta events: the chosen child's weight times its factor over its probability).
A child's term in the pdf counts only where its
contribution to ``eval`` is positive, so ``pdf > 0`` exactly where ``eval > 0`` and
samples of a child whose factor vanishes at the drawn direction fail.  Nested nodes
sample in one descent and one evaluation of the whole tree (``_draw`` and ``_settle``,
:mod:`render.df._combine`).

The layer's own normal (libbsdf, §0 and §1.4): the layer child sees the directions
rotated into the frame of ``normal``; a lane whose ``wo`` or ``wi`` lies on different
sides of the inherited and the layer tangent planes gets nothing from the layer (the
counterpart of libbsdf absorbing directions on the wrong side of the geometric
normal, which a local frame does not carry).  The base keeps the inherited frame.
"""

from __future__ import annotations

import math
import threading
from enum import Enum
from functools import lru_cache

import numpy as np

from render._typing import Arr, Arr2, ArrayLike, Rgb, Vec3
from render.bsdf import Bsdf, BsdfSample, check_dirs, lane_color, lanes
from render.df import _kernel_common as kc
from render.df._combine import (
    Draw,
    LayerFrame,
    Memo,
    albedo_correction,
    any_positive,
    cheap_albedo,
    check_child,
    child_draw,
    child_sample,
    child_settle,
    drawn,
    is_mirror,
    lum,
    sample_by_draw,
    selection,
    union_lobes,
)
from render.df._common import ior_pair, lane_ior
from render.df._signature import THIN_WALLED
from render.frame import mirror_z
from render.jit import njit
from render.numerics import (
    ONE_MINUS_EPS,
    check_finite,
    fresnel_dielectric,
    saturate,
    unitize,
)

__all__ = [
    "LayerBsdf",
    "CurveLayer",
    "CurveAlbedo",
    "custom_curve",
    "f82_curve",
    "df_signature",
    "sobol_points",
    "CURVE_ALBEDO_POINTS",
    "CURVE_ALBEDO_DIRECT_POINTS",
    "CURVE_ALBEDO_SLOTS_MIN",
    "LANE_SPREAD_MAX",
    "fresnel_curve",
    "fresnel_eta",
    "f82_curve1",
    "curve_geometry",
]

#: quadrature points (:func:`sobol_points`) of a tabulated curve-weighted albedo ``Ĉ``;
#: each side of a table costs ``CURVE_ALBEDO_THETA * CURVE_ALBEDO_PHI`` times as many
#: layer samples, once per distinct layer and curve.  Measured accuracy at the nodes
#: (against 2e5 points): 1.2e-4 for a Lambertian layer, 1.5e-4 for a Fresnel-weighted
#: glossy layer of roughness 0.2, 1.1e-3 for the curve ``1 - c`` over roughness 0.5.
CURVE_ALBEDO_POINTS = 512
#: quadrature points of ``Ĉ`` integrated per call (per-lane layers or curves), at this
#: many layer samples per lane and call; accuracy with the layers above: 3e-4 to 3e-3 on
#: average over directions, 1.2e-2 at worst
CURVE_ALBEDO_DIRECT_POINTS = 128
#: table nodes over the layer-frame polar angle, per side (uniform in the angle, from the
#: pole to ``acos(CURVE_ALBEDO_MU_MIN)``)
CURVE_ALBEDO_THETA = 17
#: azimuths whose largest value each table node keeps (0, 45, 90, 135 degrees: the axes
#: and diagonals of an anisotropic layer's tangent frame)
CURVE_ALBEDO_PHI = 4
#: the last table node's cosine (grazing directions below it take its value)
CURVE_ALBEDO_MU_MIN = 1e-3
#: largest spread of parameter values (relative to ``1 + |value|``) over the lanes of a
#: node, and between nodes, that still shares one table: ``Ĉ`` moves by about as much,
#: within its accuracy
LANE_SPREAD_MAX = 1e-3
#: fewest lanes with which a layer holding per-lane (near-equal) parameters builds a table
#: (its ``THETA * PHI * POINTS`` evaluations per side go through calls of that many
#: lanes); with fewer lanes it uses a table built before, or integrates ``Ĉ`` per call
CURVE_ALBEDO_SLOTS_MIN = 256


# --- scalar kernels shared by the layers and directional_factor (the compiled core) ---
# The per-node factor math of weighted_layer, fresnel_layer, custom_curve_layer (and their
# colour forms) lives in those modules; these are the pieces they share: the direction
# geometry of CurveLayer._curves and the Fresnel and F82 curves, ported formula by
# formula (same operations in the same order) on render.df._kernel_common's helpers.

#: 7^7 / 6^6: normalises Hoffman's F82 term to its peak at c = 1/7
_F82_NORM = 7.0**7 / 6.0**6
_SIX_SEVENTHS = 6.0 / 7.0


@njit
def fresnel_curve(c, eta):
    """:meth:`FresnelCurve.value` of one channel: dielectric ``F(eta, saturate(c))``.

    An ``eta`` that is not positive and finite, or whose square underflows (an ``ior <=
    0`` the packer should have rejected, as the numpy class does) gives 1, the limit at
    both ends, never NaN nor numba's ZeroDivisionError.
    """
    if not (eta > 0.0 and eta * eta > 0.0 and eta < math.inf):
        return 1.0
    return kc.fresnel_dielectric(min(max(c, 0.0), 1.0), eta)[0]


@njit
def fresnel_eta(ior, ior_outside, woz, flags):
    """:meth:`FresnelCurve.eta` of one channel: ``ior / eta1`` from outside (``wo.z >= 0``
    or thin-walled), ``eta2 / ior`` from inside, ``(eta1, eta2)`` the IOR pair of ``wo``'s
    side (both are ``ior_outside`` there: the layer's ``ior`` replaces the far side's)."""
    inside = woz < 0.0 and (flags & THIN_WALLED) == 0
    den = ior if inside else ior_outside
    if den == 0.0:
        return math.inf  # an ior of 0 (rejected by the packer): F = 1, not an exception
    return (ior_outside if inside else ior) / den


@njit
def f82_curve1(c, r0, r90, f82, p):
    """:func:`f82_curve` of one channel (``p`` read as ``max(p, 0)``)."""
    p = max(p, 0.0)
    cc = min(max(c, 0.0), 1.0)
    base = r0 + (r90 - r0) * math.pow(1.0 - cc, p)
    a = (r0 + (r90 - r0) * math.pow(_SIX_SEVENTHS, p)) * _F82_NORM * (1.0 - f82)
    return min(max(base - a * (cc * math.pow(1.0 - cc, 6.0)), 0.0), 1.0)


@njit
def curve_geometry(refractive, flags, ior_outside, ior_inside, woz, wiz,
                   ox, oy, oz, ix, iy, iz):
    """The cosines of :meth:`CurveLayer._curves`: ``(|wo.h|, nk1, nk2r)``.

    ``woz``, ``wiz``: the inherited-frame ``wo.z``, ``wi.z`` (they tell reflection from
    transmission, and the IOR side); ``o``, ``i``: ``wo_L``, ``wi_L`` in the layer frame.
    ``refractive``: the refraction half vector for transmission (the Fresnel layers,
    not on thin-walled surfaces); otherwise ``nk2r = nk2 = |wi_L.z|``.
    """
    s = -1.0 if oz < 0.0 else 1.0  # orient the layer frame so that wo_L is on top
    oz = oz * s
    iz = iz * s
    nk1 = min(max(oz, 0.0), 1.0)
    nk2 = min(abs(iz), 1.0)
    tr = woz * wiz < 0.0
    hx, hy, hz, ok = kc.unitize(ox + ix, oy + iy, oz + kc.mirror_z(iz, tr))
    refract = refractive and (flags & THIN_WALLED) == 0
    if refract and tr:
        eta1, eta2 = kc.ior_pair(ior_outside, ior_inside, woz < 0.0, False, False)
        rx, ry, rz, ok = kc.unitize(eta1 * ox + eta2 * ix, eta1 * oy + eta2 * iy,
                                    eta1 * oz + eta2 * iz)
        sg = 1.0 if eta1 > eta2 else -1.0  # np.sign; eta1 == eta2 fails below
        hx, hy, hz = rx * sg, ry * sg, rz * sg
        ok = ok and eta1 != eta2
    if not ok:
        hx, hy, hz = 0.0, 0.0, 1.0
    kh = min(abs(kc.dot3(ox, oy, oz, hx, hy, hz)), 1.0)
    nk2r = nk2
    if refract and tr:
        nk2r = min(max(2.0 * kh * hz - nk1, 0.0), 1.0)
    return kh, nk1, nk2r

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

    def _parts(self, wo: Vec3, wi: Vec3, P: Arr | None = None, draws=(None, None)):
        """Everything eval, pdf and sample need at ``(wo, wi)`` (``P``: the selection).

        ``draws``: the children's draws to settle at ``wi`` (:meth:`_settle`); their
        settled samples are returned last (None for a child not drawn).
        """
        lf = self.layer_frame
        wo_l, wi_l = lf.to_layer(wo), lf.to_layer(wi)
        agree_o = lf.agree(wo, wo_l)
        ok_l = agree_o & lf.agree(wi, wi_l)
        e_l, p_l, s_l = child_settle(self.layer, wo_l, wi_l, draws[0])
        e_b, p_b, s_b = child_settle(self.base, wo, wi, draws[1])
        f_l, f_b = self._factors(wo, wi, wo_l, wi_l)
        f_l = np.where(ok_l[:, None], f_l, 0.0)
        c_l = f_l * e_l
        c_b = f_b * e_b
        if P is None:
            P = self._select(wo, wo_l, agree_o)
        pdf = P * p_l * any_positive(c_l) + (1.0 - P) * p_b * any_positive(c_b)
        value = np.where((pdf > 0)[:, None], c_l + c_b, 0.0)
        return value, pdf, f_l, f_b, any_positive(c_l), any_positive(c_b), s_l, s_b

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
        return sample_by_draw(self, wo, u1, u2)

    def _draw(self, wo: Vec3, u1: Arr, u2: Arr2) -> Draw:
        """Pick the layer or the base per lane and descend into it (no evaluation)."""
        lf = self.layer_frame
        wo_l = lf.to_layer(wo)
        P = self._select(wo, wo_l, lf.agree(wo, wo_l))
        take_l = u1 < P
        u_l = np.clip(u1 / np.where(P > 0, P, 1.0), 0.0, ONE_MINUS_EPS)
        u_b = np.clip((u1 - P) / np.where(P < 1, 1.0 - P, 1.0), 0.0, ONE_MINUS_EPS)
        # A tilted frame settles the layer's sample now, at its own direction wi_l: the
        # evaluation in _settle sees to_layer(to_inherited(wi_l)), which rounding moves
        # off wi_l, and the layer's validity must be the one its own sample gives.
        draw_layer = child_draw if lf.identity else child_sample
        d_l = draw_layer(self.layer, wo_l, np.where(take_l, u_l, 0.0), u2)
        d_b = child_draw(self.base, wo, np.where(take_l, 0.0, u_b), u2)
        wi = np.where(take_l[:, None], lf.to_inherited(d_l.wi), d_b.wi)
        return Draw(wi, np.where(take_l, drawn(d_l), drawn(d_b)), (P, take_l, d_l, d_b))

    def _settle(self, wo: Vec3, wi: Vec3, d: Draw) -> tuple[Rgb, Arr, BsdfSample]:
        """``eval_pdf(wo, wi)`` and the sample ``d`` settled at ``wi`` (its drawn direction
        wherever it was drawn), from one evaluation of the subtree."""
        P, take_l, d_l, d_b = d.state
        value, pdf, f_l, f_b, on_l, on_b, s_l, s_b = self._parts(wo, wi, P, (d_l, d_b))
        valid = np.where(take_l, s_l.valid, s_b.valid)
        delta = np.where(take_l, s_l.is_delta, s_b.is_delta)
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
        s = BsdfSample(
            np.where(ok[:, None], wi, 0.0),
            np.where(ok_nd, pdf, np.where(ok_d, pdf_d, 0.0)),
            np.where(ok_nd[:, None], w_nd, np.where(ok_d[:, None], w_d, 0.0)),
            np.where(ok, lobe, 0).astype(np.int32),
        ).checked()
        name = type(self).__name__
        return check_finite(f"{name}.eval", value, True), check_finite(f"{name}.pdf", pdf, True), s

    def albedo(self, wo: Vec3) -> Rgb:
        """Directional albedo ``∫ eval dwi`` (plus delta lobes).

        ``est_L albedo_L + est_B albedo_B`` with the factors' values at ``wo`` (exact
        for the weighted layer), plus the integral of each factor's deviation from that
        value over the child's lobe (:func:`render.df._combine.albedo_correction`,
        skipped where it vanishes: a mirror layer in an untilted frame, constant
        factors; a mirror base takes its factor at the mirror direction).  Clipped to
        [0, 1]: the true albedo never exceeds 1 (module docstring).  Measured accuracy:
        ``tests/render/df``.
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
            if not self._directional:
                out += est_b * self.base.albedo(wo)
            elif is_mirror(self.base):
                # the base scatters only to the mirror direction: its factor there, exactly
                m = wo * np.array([-1.0, -1.0, 1.0])
                f_b = self._factors(wo, m, wo_l, lf.to_layer(m))[1]
                out += f_b * self.base.albedo(wo)
            else:
                out += est_b * self.base.albedo(wo)

                def f_base(wi):
                    return self._factors(wo, wi, wo_l, lf.to_layer(wi))[1]

                out += albedo_correction(self.base, wo, f_base, est_b)
        # the layers never gain energy (module docstring): clip the quadrature's noise
        return np.clip(out, 0.0, 1.0)

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
    """libbsdf's directional layering with a curve ``C`` (§3.2), per direction, without gain.

    With ``nk1 = saturate(n_L.wo)``, ``nk2 = |n_L.wi|`` and the half vector ``h``
    (reflection: ``wo + wi``; transmission: ``wi`` mirrored through the layer's tangent
    plane first, or the refraction half vector for the Fresnel layers on non-thin-walled
    surfaces, where ``nk2r = 2 (wo.h)(n_L.h) - nk1``)::

        f_layer = w C(|wo.h|),     f_base = max(0, 1 - w max(C(nk1), C(nk2r), Ĉ(wo), Ĉ(wi)))

    with ``Ĉ`` the layer's curve-weighted albedo (:class:`CurveAlbedo`, module
    docstring); estimates (for sampling) ``w C(nk1)`` and ``1 - w max(C(nk1), Ĉ(wo))``.
    Reflection versus transmission is decided in the inherited frame
    (``wo.z wi.z < 0``).

    Subclasses set ``self.weight`` ((1|n, 3) colour, saturated) and implement
    :meth:`_curve` (``c (n,) -> (n, 3)``, given the per-call context from
    :meth:`_context`), :meth:`_curve_params` (the curve's parameters, to tell whether
    they vary over lanes and to key the shared tables) and :meth:`_curve_constant`.
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
        self._curve_albedo = CurveAlbedo(self)

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

    def _curve_params(self) -> tuple:
        """The arrays the curve depends on (besides the direction's side)."""
        return (self.ior_outside, self.ior_inside)

    def _curve_constant(self) -> bool:
        """True if ``C`` takes one value at every cosine on every lane (then ``Ĉ <= C``)."""
        return False

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
        w = self._w(n)
        c1 = self._curve(nk1, self._context(wo))
        c_base = np.maximum(c1, self._curve_albedo.at(wo, wo_l, "wo"))
        return w * c1, np.maximum(1.0 - w * c_base, 0.0)

    def _factors(self, wo, wi, wo_l, wi_l):
        w = self._w(len(wo))
        c_h, c_max = self._curves(wo, wi, wo_l, wi_l, self._context(wo))
        ca = self._curve_albedo
        c_max = np.maximum(c_max, np.maximum(ca.at(wo, wo_l, "wo"), ca.at(wi, wi_l, "wi")))
        return w * c_h, np.maximum(1.0 - w * c_max, 0.0)

    def _curves(self, wo, wi, wo_l, wi_l, ctx) -> tuple[Rgb, Rgb]:
        """libbsdf's ``C(|wo.h|)`` and ``max(C(nk1), C(nk2r))`` (no weight), (n, 3) each."""
        n = len(wo)
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
        return c_h, c_max


class CurveAlbedo:
    """``Ĉ(v)``: a curve layer's curve-weighted directional albedo (see the module docstring).

    ``Ĉ(v) = ∫ C(|v.h|) layer.eval(v_L, x) dx`` over the layer child's lobe, per
    channel, with the curve context of ``v``'s side, 0 where ``v`` lies on different sides
    of the inherited and the layer tangent planes.  Evaluated as an upper estimate: the
    side tests on ``x`` are dropped (the integral runs in the layer frame, transmission
    told by the layer's tangent plane), and the tabulated form keeps the largest of
    four azimuths.  ``None``-layers, mirror layers (``Ĉ = C(nk) tint <= C(nk)``), constant
    curves and zero weights never reach libbsdf's ``max(C(nk1), C(nk2r))``: ``Ĉ = 0``
    there, at no cost.

    Parameters
    ----------
    node : CurveLayer
    """

    __slots__ = ("node", "mode", "table", "memo")

    def __init__(self, node: CurveLayer):
        self.node = node
        self.mode = None  # decided on first use: "none", "table" or "direct"
        self.table = None
        self.memo = {"wo": Memo(), "wi": Memo()}

    def at(self, w: Vec3, w_l: Vec3, role: str) -> Rgb:
        """``Ĉ`` at the inherited-frame directions ``w`` (n, 3) (``w_l``: in the layer frame).

        ``role`` ("wo" or "wi") picks the memo of the per-lane quadrature.
        """
        n = len(w)
        if self.mode is None:
            self._decide(n)
        if self.mode == "none":
            return np.zeros((n, 3))
        if self.mode == "table":
            value = self.table.lookup(w_l)
        else:
            value = self.memo[role].get(w, lambda: self.integrate(w_l))
        return np.where(self.node.layer_frame.agree(w, w_l)[:, None], value, 0.0)

    def _decide(self, n: int) -> None:
        """Choose how ``Ĉ`` is computed for calls with ``n`` lanes (see the module docstring)."""
        node = self.node
        layer = node.layer
        if (layer is None or is_mirror(layer) or not np.any(node.weight > 0.0)
                or node._curve_constant()):
            self.mode = "none"
            return
        self.mode = "direct"
        try:
            structure, values, counts = df_signature((node._curve_params(), layer))
        except _NoSignature:  # per-lane values that differ, or an opaque attribute
            return
        if counts and counts != {n}:
            return
        key = (type(node).__module__, type(node).__qualname__, node.thin_walled, structure)
        slots = n if counts else None
        if slots is not None and slots < CURVE_ALBEDO_SLOTS_MIN:
            self.table = _shared_table(key, values, None)  # too few lanes to build one
        else:
            self.table = _shared_table(key, values, lambda k: self._build_side(k, slots))
        if self.table is not None:
            self.mode = "table"

    def integrate(self, w_l: Vec3, points: int = CURVE_ALBEDO_DIRECT_POINTS) -> Rgb:
        """``Ĉ`` at layer-frame directions ``w_l`` (m, 3), one lane each (any layer).

        ``C(nk) albedo_L(w_l)`` plus the layer-sampled quadrature of
        ``(C(|w.h|) - C(nk)) layer.eval`` over ``points`` points of :func:`sobol_points`
        (a control variate where the layer's albedo is exact or tabulated, see
        :meth:`_controlled`), side tests on the sampled directions dropped.  One layer
        call of ``m`` lanes per point.
        """
        m = len(w_l)
        acc = np.zeros((m, 3))
        pts = sobol_points(points)
        for u in pts:
            acc += self._deviation(w_l, np.full(m, u[0]), np.broadcast_to(u[1:], (m, 2)))
        return self._finish(w_l, acc / len(pts), self._control(w_l))

    def _deviation(self, w_l: Vec3, u1: Arr, u2: Arr2) -> Rgb:
        """``(C(|w.h|) - C(nk))`` times the layer's sample weight, per lane (n, 3).

        Without the control variate (a layer whose albedo is itself a quadrature: a
        combiner) ``C(|w.h|)`` times the weight.
        """
        node = self.node
        s = node.layer.sample(w_l, u1, u2)
        x = np.where(s.valid[:, None], s.wi, np.array([0.0, 0.0, 1.0]))
        ctx = node._context(w_l)
        c_h, _ = node._curves(w_l, x, w_l, x, ctx)
        if self._controlled():
            c_h = c_h - node._curve(np.abs(w_l[:, 2]), ctx)
        return np.where(s.valid[:, None], c_h * s.weight, 0.0)

    def _controlled(self) -> bool:
        """Use ``C(nk) albedo_L`` as control variate: the layer's albedo is a closed form
        or a table (an elemental df), not a quadrature of its own."""
        return not hasattr(self.node.layer, "_cheap_albedo")

    def _control(self, w_l: Vec3) -> Rgb:
        """The control variate ``C(nk) albedo_L(w_l)`` (n, 3), or 0 without one."""
        node = self.node
        if not self._controlled():
            return np.zeros((len(w_l), 3))
        return node._curve(np.abs(w_l[:, 2]), node._context(w_l)) * node.layer.albedo(w_l)

    @staticmethod
    def _finish(w_l: Vec3, deviation: Rgb, control: Rgb) -> Rgb:
        out = np.where((np.abs(w_l[:, 2]) > 0.0)[:, None], deviation + control, 0.0)
        return np.clip(out, 0.0, 1.0)

    def _build_side(self, side: int, slots: int | None) -> np.ndarray:
        """(CURVE_ALBEDO_THETA, 3): ``Ĉ`` over the polar angle on one side (0: ``+z``).

        All ``directions x points`` evaluations go through calls of ``slots`` lanes (the
        lane count of per-lane parameters whose rows are alike: every lane stands for any
        direction), or through one call when the parameters take any lane count.
        """
        d = _table_directions(side)
        pts = sobol_points(CURVE_ALBEDO_POINTS)
        k = len(pts)
        w = np.repeat(d, k, axis=0)
        u = np.tile(pts, (len(d), 1))
        dev = _in_slots(slots, lambda i: self._deviation(w[i], u[i, 0], u[i, 1:]), len(w))
        control = _in_slots(slots, lambda i: self._control(d[i]), len(d))
        v = self._finish(d, dev.reshape(len(d), k, 3).mean(axis=1), control)
        v = v.reshape(CURVE_ALBEDO_THETA, CURVE_ALBEDO_PHI, 3).max(axis=1)
        v.setflags(write=False)
        return v


class _Table:
    """``Ĉ`` over the polar angle, each side built on first use (thread-safe)."""

    __slots__ = ("build", "sides", "lock")

    def __init__(self, build):
        self.build = build  # side -> (CURVE_ALBEDO_THETA, 3)
        self.sides = [None, None]
        self.lock = threading.Lock()

    def side(self, k: int) -> np.ndarray:
        """(2, THETA, 3): side ``k``'s nodes and the concave correction of each interval."""
        with self.lock:  # a second thread waits for the first one's build
            if self.sides[k] is None:
                v = self.build(k)
                # second differences (the pole mirrored: Ĉ is even in the polar angle);
                # an interval takes the more concave of its ends, convex ones nothing
                ext = np.concatenate([v[1:2], v, v[-1:]])
                d2 = ext[:-2] - 2.0 * ext[1:-1] + ext[2:]
                d2[-1] = d2[-2]
                pad = np.zeros_like(v)
                pad[:-1] = 0.5 * np.maximum(0.0, -np.minimum(d2[:-1], d2[1:]))
                table = np.stack([v, pad])
                table.setflags(write=False)
                self.sides[k] = table
            return self.sides[k]

    def lookup(self, w_l: Vec3) -> Rgb:
        """``Ĉ`` at ``w_l`` (n, 3) from its side's nodes, (n, 3).

        Linear in the polar angle, plus ``pad f (1 - f)`` in concave intervals (``f`` the
        position in the interval): the error of linear interpolation of a quadratic with
        that second difference, so the value stays an upper estimate there too.
        """
        mu = w_l[:, 2]
        below = mu < 0.0
        empty = np.zeros((2, CURVE_ALBEDO_THETA, 3))
        table = np.stack([self.side(0) if not np.all(below) else empty,
                          self.side(1) if np.any(below) else empty])
        t = np.arccos(np.minimum(np.abs(mu), 1.0)) / _table_step()
        j = np.minimum(np.floor(t).astype(np.intp), CURVE_ALBEDO_THETA - 2)
        f = np.clip(t - j, 0.0, 1.0)[:, None]
        side = below.astype(np.intp)
        lin = table[side, 0, j] * (1.0 - f) + table[side, 0, j + 1] * f
        return lin + table[side, 1, j] * f * (1.0 - f)


def _in_slots(slots: int | None, f, total: int) -> np.ndarray:
    """``f(index)`` over ``range(total)``: in one call, or in calls of exactly ``slots`` lanes."""
    if slots is None:
        return f(np.arange(total))
    out = []
    for start in range(0, total, slots):
        i = np.minimum(np.arange(start, start + slots), total - 1)  # pad the last call
        out.append(f(i)[: min(slots, total - start)])
    return np.concatenate(out)


@lru_cache(maxsize=8)
def sobol_points(m: int) -> np.ndarray:
    """The first ``m`` (a power of 2) points of Sobol's sequence in [0, 1)^3, shifted by ``1/(2m)``.

    Unscrambled, in Gray-code order (the points of ``scipy.stats.qmc.Sobol(3,
    scramble=False)``), direction numbers of Joe and Kuo for dimensions 2 and 3
    (primitive polynomials ``x + 1`` and ``x^2 + x + 1``, initial ``m = 1`` and
    ``m = 1, 3``).  The first ``m`` points of each coordinate are ``j / m``, so the
    shift makes them the midpoints ``(j + 1/2) / m``: no point on a cell edge.
    Columns ``u1, u2x, u2y`` as :func:`render.df._combine.albedo_points`.

    Examples
    --------
    >>> (sobol_points(4) - 1 / 8).tolist()
    [[0.0, 0.0, 0.0], [0.5, 0.5, 0.5], [0.75, 0.25, 0.25], [0.25, 0.75, 0.75]]
    """
    if m < 1 or m & (m - 1):
        raise ValueError(f"m must be a power of 2 (the Sobol points form a net), got {m}")
    bits = 32
    # direction integers m_k: m_k = 2 a_1 m_(k-1) ^ ... ^ 2^s m_(k-s) ^ m_(k-s)
    dims = [[1] * bits, [1], [1, 3]]
    for d, (s, a) in ((1, (1, ())), (2, (2, (1,)))):
        mk = dims[d]
        for k in range(s, bits):
            new = mk[k - s] ^ (mk[k - s] << s)
            for j, aj in enumerate(a, start=1):
                new ^= (mk[k - j] << j) if aj else 0
            mk.append(new)
    v = np.array([[mk[k] << (bits - 1 - k) for k in range(bits)] for mk in dims], dtype=np.uint64)
    i = np.arange(m, dtype=np.uint64)
    gray = i ^ (i >> np.uint64(1))
    x = np.zeros((m, 3), dtype=np.uint64)
    for k in range(bits):
        on = ((gray >> np.uint64(k)) & np.uint64(1)).astype(bool)
        x ^= np.where(on[:, None], v[:, k][None, :], np.uint64(0))
    pts = x.astype(np.float64) / 2.0**bits + 0.5 / m
    pts.setflags(write=False)
    return pts


def _table_step() -> float:
    return float(np.arccos(CURVE_ALBEDO_MU_MIN)) / (CURVE_ALBEDO_THETA - 1)


def _table_directions(side: int) -> Vec3:
    """One side's layer-frame table directions, (THETA * PHI, 3): polar angle, azimuth."""
    theta = np.arange(CURVE_ALBEDO_THETA) * _table_step()
    phi = np.arange(CURVE_ALBEDO_PHI) * (np.pi / CURVE_ALBEDO_PHI)
    t, p = np.meshgrid(theta, phi, indexing="ij")
    z = np.cos(t) * (-1.0 if side else 1.0)
    d = np.stack([np.sin(t) * np.cos(p), np.sin(t) * np.sin(p), z], axis=-1)
    return d.reshape(-1, 3)


class _NoSignature(Exception):
    """An object :func:`df_signature` cannot describe by value."""


def df_signature(obj) -> tuple[tuple, np.ndarray, frozenset]:
    """What a df (or parameter tuple) is made of, to tell dfs that behave alike.

    Recurses through attributes (``__dict__`` and ``__slots__``), lists, tuples and
    dicts.  Everything but floating-point numbers goes into ``structure`` (types,
    attribute names, array shapes, flags, integers); the floating-point parameters go
    into ``values``.  A parameter array counts by its first row (the leading axis is the
    lanes, as :func:`render.bsdf.lanes` reads it), so a scalar, a single row and ``n``
    equal rows are alike, and so are a grey colour and a scalar (a layer frame's lane
    count is skipped likewise); its rows may
    differ by up to :data:`LANE_SPREAD_MAX` (relative to ``1 + |value|``: normals bent in
    the local frame of a curved surface, say).  Memos and :class:`CurveAlbedo` caches are
    skipped.  Two dfs with equal structures and values within :data:`LANE_SPREAD_MAX`
    (:func:`_close`) have curve-weighted albedos within about that much.

    Returns
    -------
    structure : tuple
        Hashable.
    values : (k,) float64
    lanes : frozenset of int
        The row counts ``n > 1`` of the parameter arrays (empty: the object takes calls
        of any lane count).

    Raises
    ------
    _NoSignature
        An array whose rows differ by more than :data:`LANE_SPREAD_MAX` (per-lane
        values), or an attribute that cannot be compared by value (a function, an object
        without attributes).

    Examples
    --------
    >>> from render.df import simple_glossy_bsdf
    >>> a = df_signature(simple_glossy_bsdf(roughness_u=0.3))
    >>> b = df_signature(simple_glossy_bsdf(roughness_u=np.full(5, 0.3)))
    >>> a[0] == b[0], bool(np.array_equal(a[1], b[1])), sorted(b[2])
    (True, True, [5])
    >>> c = df_signature(simple_glossy_bsdf(roughness_u=0.31))
    >>> c[0] == a[0], _close(c[1], a[1])
    (True, False)
    """
    counts: set = set()
    values: list = []
    structure = _signature(obj, counts, values)
    v = np.concatenate(values) if values else np.zeros(0)
    return structure, v, frozenset(counts)


def _close(a: np.ndarray, b: np.ndarray) -> bool:
    """Parameter values alike to :data:`LANE_SPREAD_MAX` (relative to ``1 + |value|``)."""
    return bool(np.all(np.abs(a - b) <= LANE_SPREAD_MAX * (1.0 + np.abs(a))))


def _signature(obj, counts: set, values: list):
    if isinstance(obj, (np.ndarray, np.generic)):
        a = np.asarray(obj)
        row = a if a.ndim == 0 else a[0]
        if a.ndim >= 1 and a.shape[0] > 1:
            counts.add(a.shape[0])
            if np.any(a != row) and (a.dtype.kind != "f" or not _close(row, a)):
                raise _NoSignature("per-lane values that differ")
        if a.dtype.kind == "f":
            row = np.ravel(row).astype(np.float64)
            if row.size > 1 and np.all(row == row[0]):
                row = row[:1]  # a grey colour acts as a scalar
            values.append(row)
            return ("float", row.size)
        return ("value", a.dtype.str, a.shape[1:], np.ascontiguousarray(row).tobytes())
    if isinstance(obj, float):
        values.append(np.array([obj]))
        return ("float", 1)
    if obj is None or isinstance(obj, (bool, int, str, Enum)):
        return (type(obj).__name__, obj)
    if isinstance(obj, (list, tuple)):
        return (type(obj).__name__, tuple(_signature(x, counts, values) for x in obj))
    if isinstance(obj, dict):
        return ("dict", tuple((k, _signature(obj[k], counts, values)) for k in sorted(obj)))
    if isinstance(obj, (Memo, CurveAlbedo)):
        return ("cache",)
    if callable(obj):
        raise _NoSignature(type(obj).__name__)
    attrs = dict(getattr(obj, "__dict__", {}))
    for cls in type(obj).__mro__:
        for name in getattr(cls, "__slots__", ()):
            if hasattr(obj, name):
                attrs[name] = getattr(obj, name)
    if not attrs:
        raise _NoSignature(type(obj).__name__)
    if isinstance(obj, LayerFrame):
        attrs.pop("lanes", None)  # the row count of its arrays, reduced above
    return (type(obj).__module__, type(obj).__qualname__,
            tuple((k, _signature(attrs[k], counts, values)) for k in sorted(attrs)))


#: tables shared by nodes with the same layer and curve: structure -> [(values, _Table)],
#: at most _SHARED_MAX tables (the oldest structure is dropped first)
_SHARED: dict = {}
_SHARED_MAX = 256
_SHARED_LOCK = threading.Lock()


def _shared_table(structure, values: np.ndarray, build) -> _Table | None:
    """The table of a node whose parameters are ``(structure, values)``.

    An existing table is reused if its structure is equal and its values are within
    :data:`LANE_SPREAD_MAX` (:func:`_close`); otherwise a new one builds its sides with
    ``build(side)`` when first looked up (``build=None``: None instead).
    """
    with _SHARED_LOCK:
        entries = _SHARED.get(structure, [])
        for v, table in entries:
            if v.shape == values.shape and _close(values, v):
                return table
        if build is None:
            return None
        entries = _SHARED.setdefault(structure, entries)
        if sum(len(e) for e in _SHARED.values()) >= _SHARED_MAX:
            oldest = next(iter(_SHARED))
            if oldest is not structure:
                _SHARED.pop(oldest)
        table = _Table(build)
        entries.append((values, table))
    return table


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

