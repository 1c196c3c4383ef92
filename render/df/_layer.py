"""The layering framework shared by weighted, Fresnel and custom-curve layers (libbsdf's algorithm).

``reference/mdl-distribution-functions.md`` §3.  A layer node combines a ``layer`` df,
evaluated in the frame of the node's own ``normal``, and a ``base`` df, evaluated in
the inherited frame, with per-direction factors::

    eval = f_layer(wo, wi) * layer.eval(wo_L, wi_L) + f_base(wo, wi) * base.eval(wo, wi)

(``wo_L``, ``wi_L``: the directions in the layer frame).  The weighted layer has
constant factors ``w`` and ``1 - w``; the directional layers (Fresnel and custom curve)
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

Computing ``Ĉ`` (:func:`render.interpreter.build_chat_table`): an importance-sampled
quadrature through the layer child's own sampler over ``CHAT_POINTS`` (512) Sobol points,
with ``C(nk) albedo_L`` as control variate where the layer is an elemental df.  It is
tabulated over the layer-frame polar angle on both sides (the largest value over four
azimuths, so anisotropic layers are bounded too; linear in the angle between nodes plus
a correction in concave intervals, so the table stays an upper value), in the layer
frame and without the two frames' side tests on ``wi``, which can only raise it.  A
table is built once per distinct layer and curve (:func:`render.program.combine`, cached
by value), when everything ``Ĉ`` depends on (the layer child, its frames, the curve's
parameters; not the weight) is the same on every lane.  Where it is not (a textured coat
bound per lane), the node keeps libbsdf's base factor ``1 - w max(C(nk1), C(nk2r))``:
that departure can gain energy by the amounts measured above, only over mirror and
narrow glossy bases.  Measured accuracy where ``Ĉ`` matters (where it exceeds libbsdf's
factor): the table is above the integral, or below by at most 4e-4 for elemental layers
and 3e-3 for layered ones (whose lobes jump at total internal reflection).

Sampling picks the layer with probability ``P`` (a defensive mixture of the expected
contributions, :func:`render.interpreter.prepare`), reuses ``u1`` rescaled, and
returns the mixture density ``P pdf_L + (1 - P) pdf_B`` (the ``pdf`` of Mitsuba's
``blendbsdf``) with the weight ``eval / pdf`` of the whole node, not of the chosen child
alone (delta events: the chosen child's weight times its factor over its probability).
A child's term in the pdf counts only where its
contribution to ``eval`` is positive, so ``pdf > 0`` exactly where ``eval > 0`` and
samples of a child whose factor vanishes at the drawn direction fail.  Nested nodes
sample in one descent and one evaluation of the whole tree (:func:`render.interpreter.sample`).

The layer's own normal (libbsdf, §0 and §1.4): the layer child sees the directions
rotated into the frame of ``normal``; a lane whose ``wo`` or ``wi`` lies on different
sides of the inherited and the layer tangent planes gets nothing from the layer (the
counterpart of libbsdf absorbing directions on the wrong side of the geometric
normal, which a local frame does not carry).  The base keeps the inherited frame.
"""

from __future__ import annotations

import math

import numpy as np

from render.df import _kernel_common as kc
from render.df._signature import THIN_WALLED
from render.df._workspace import (
    AGO,
    AL,
    CH,
    CO,
    CW,
    FR,
    FWI,
    FWO,
    KF,
    KON,
    KR,
    KSEL,
    NO_KID,
    PDF,
    SEL,
    R,
    agree,
    any_pos,
    chat_lookup,
    clamp_u,
    lum,
    selection,
    set_bases,
    set_dirs,
    to_frame0,
    work_size,
)
from render.jit import njit
from render.program import BASE, CHAT_NONE, CHAT_THETA, FLAGS, FRAME, KID0, LFRAME, OP, TABLE

__all__ = [
    "measured_curve1",
    "scale_cosine",
    "scale_half_vector",
    "fresnel_curve",
    "fresnel_eta",
    "f82_curve1",
    "curve_geometry",
    "curve_factors",
    "curve_estimates",
]

# --- scalar kernels shared by the layers and directional_factor (the compiled core) ---
# The per-node factor math of weighted_layer, fresnel_layer, custom_curve_layer (and their
# colour forms) lives in those modules; these are the pieces they share: the direction
# geometry of the curve layers and the Fresnel and F82 curves, on
# render.df._kernel_common's helpers.

#: 7^7 / 6^6: normalises Hoffman's F82 term to its peak at c = 1/7
_F82_NORM = 7.0**7 / 6.0**6
_SIX_SEVENTHS = 6.0 / 7.0


@njit
def fresnel_curve(c, eta):
    """the Fresnel curve of one channel: dielectric ``F(eta, saturate(c))``.

    An ``eta`` that is not positive and finite, or whose square underflows (an ``ior <=
    0`` the packer should have rejected, as the earlier numpy class does) gives 1, the limit at
    both ends, never NaN nor numba's ZeroDivisionError.
    """
    if not (eta > 0.0 and eta * eta > 0.0 and eta < math.inf):
        return 1.0
    return kc.fresnel_dielectric(min(max(c, 0.0), 1.0), eta)[0]


@njit
def fresnel_eta(ior, ior_outside, woz, flags):
    """the Fresnel curve's relative IOR of one channel: ``ior / eta1`` from outside (``wo.z >= 0``
    or thin-walled), ``eta2 / ior`` from inside, ``(eta1, eta2)`` the IOR pair of ``wo``'s
    side (both are ``ior_outside`` there: the layer's ``ior`` replaces the far side's)."""
    inside = woz < 0.0 and (flags & THIN_WALLED) == 0
    den = ior if inside else ior_outside
    if den == 0.0:
        return math.inf  # an ior of 0 (rejected by the packer): F = 1, not an exception
    return (ior_outside if inside else ior) / den


@njit
def f82_curve1(c, r0, r90, f82, p):
    """The F82-tint Schlick curve of one channel (``p`` read as ``max(p, 0)``)."""
    p = max(p, 0.0)
    cc = min(max(c, 0.0), 1.0)
    base = r0 + (r90 - r0) * math.pow(1.0 - cc, p)
    a = (r0 + (r90 - r0) * math.pow(_SIX_SEVENTHS, p)) * _F82_NORM * (1.0 - f82)
    return min(max(base - a * (cc * math.pow(1.0 - cc, 6.0)), 0.0), 1.0)


@njit
def curve_geometry(refractive, flags, ior_outside, ior_inside, woz, wiz,
                   ox, oy, oz, ix, iy, iz):
    """The cosines of the layer's curves: ``(|wo.h|, nk1, nk2r)``.

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


@njit
def curve_factors(w0, w1, w2, h0, h1, h2, m0, m1, m2, co0, co1, co2, ci0, ci1, ci2):
    """A curve layer's factors per channel from its weight ``w``, ``C(|wo.h|)`` (``h``),
    ``max(C(nk1), C(nk2r))`` (``m``) and the curve-weighted albedos ``Ĉ(wo)``, ``Ĉ(wi)``:
    ``f_layer = w C(|wo.h|)``, ``f_base = max(0, 1 - w max(m, Ĉ(wo), Ĉ(wi)))``."""
    m0 = max(m0, max(co0, ci0))
    m1 = max(m1, max(co1, ci1))
    m2 = max(m2, max(co2, ci2))
    return (w0 * h0, w1 * h1, w2 * h2,
            max(1.0 - w0 * m0, 0.0), max(1.0 - w1 * m1, 0.0), max(1.0 - w2 * m2, 0.0))


@njit
def curve_estimates(w0, w1, w2, c0, c1, c2, co0, co1, co2):
    """A curve layer's expected factors at ``wo`` (for sampling): ``w C(nk1)`` and
    ``max(0, 1 - w max(C(nk1), Ĉ(wo)))``, from ``c = C(nk1)``."""
    return (w0 * c0, w1 * c1, w2 * c2, max(1.0 - w0 * max(c0, co0), 0.0),
            max(1.0 - w1 * max(c1, co1), 0.0), max(1.0 - w2 * max(c2, co2), 0.0))


@njit
def measured_curve1(P, row, at, n, c, ch):
    """A measured curve of ``n`` colours at ``P[row, at:at + 3 n]`` (equally spaced in
    angle over [0, pi/2], linear in between), channel ``ch`` at cosine ``c``, saturated:
    ``reference/mdl-distribution-functions.md`` §3.2 (0 for an empty curve)."""
    if n <= 0:
        return 0.0
    if n == 1:
        return min(max(P[row, at + ch], 0.0), 1.0)
    c = min(max(c, 0.0), 1.0)
    x = math.acos(c) * (2.0 / math.pi) * (n - 1)
    j = min(int(math.floor(x)), n - 2)
    f = min(max(x - j, 0.0), 1.0)
    v = (1.0 - f) * P[row, at + 3 * j + ch] + f * P[row, at + 3 * (j + 1) + ch]
    return min(max(v, 0.0), 1.0)


@njit
def measured_curve3(P, row, at, n, c):
    """:func:`measured_curve1` of the three channels."""
    return (measured_curve1(P, row, at, n, c, 0), measured_curve1(P, row, at, n, c, 1),
            measured_curve1(P, row, at, n, c, 2))


@njit
def measured_curve_constant(P, row, at, n):
    """Whether the measured curve at ``P[row, at:at + 3 n]`` takes one value at every
    cosine (every colour equal, as saturated)."""
    for j in range(1, n):
        for k in range(3):
            if (min(max(P[row, at + 3 * j + k], 0.0), 1.0)
                    != min(max(P[row, at + k], 0.0), 1.0)):
                return False
    return True


@njit
def scale_half_vector(wox, woy, woz, wix, wiy, wiz):
    """``(wo.h, n.h)`` of a directional modifier: ``h`` the reflection half vector with
    both directions mirrored to ``wo``'s side and a transmitted ``wi`` mirrored through
    the tangent plane (``wo.h = -1`` where it is negative: the factor is 0 there)."""
    s = -1.0 if woz < 0.0 else 1.0
    oz = woz * s
    iz = wiz * s
    hx, hy, hz, ok = kc.unitize(wox + wix, woy + wiy, oz + kc.mirror_z(iz, iz < 0.0))
    if not ok:
        hx, hy, hz = 0.0, 0.0, 1.0
    kh = kc.dot3(wox, woy, oz, hx, hy, hz)
    if not kh >= 0.0:
        return -1.0, hz
    return min(kh, 1.0), min(abs(hz), 1.0)


@njit
def scale_cosine(wox, woy, woz, wix, wiy, wiz):
    """``wo.h`` of :func:`scale_half_vector` (-1 where negative)."""
    return scale_half_vector(wox, woy, woz, wix, wiy, wiz)[0]


# --- what a layer node does in each phase of the interpreter -------------------------
# Templates that render.interpreter compiles with ``dispatch`` (the registry's generated
# dispatch) and ``walker`` (the interpreter itself) bound (render.jit.instantiate).  A
# layer's children are ``kids[k0]`` (the layer, chosen with probability SEL) and
# ``kids[k0 + 1]`` (the base); registers: render.df._workspace.

#: bound by render.interpreter: the generated dispatch (render.df._registry)
dispatch = None
#: bound by render.interpreter: the interpreter, whose passes a layer calls back
walker = None


def lobe_white_albedo(code, kids, P, row, tables, k, w):
    """The white albedo ``E(w)`` of layer ``k``'s lobe (its layer child, e.g. a
    ``sheen_bsdf`` leaf) from the lobe's own table: the Ĉ of a layer that declares
    ``chat_from_lobe`` (the sheen layer's ``1 - max(E(wo), E(wi))``)."""
    lay = kids[code[k, KID0]]
    if lay < 0:
        return 0.0
    e = dispatch.white_albedo(code[lay, OP], P, row, code[lay, BASE], code[lay, FLAGS], w[0],
                              w[1], w[2], tables, code[lay, TABLE])
    return min(max(e, 0.0), 1.0)


def chat(code, kids, P, row, tables, k, wl, agrees):
    """Ĉ of layer ``k`` at a layer-frame direction ``wl``: from its table, or its
    lobe's white albedo, or 0 (no table, or ``wl`` off the frames' common side)."""
    t = code[k, TABLE]
    if t != CHAT_NONE and agrees:
        return chat_lookup(tables, t, wl[0], wl[1], wl[2])
    if dispatch.CHAT_FROM_LOBE[code[k, OP]] and agrees:
        e = walker.lobe_white_albedo(code, kids, P, row, tables, k, wl)
        return e, e, e
    return 0.0, 0.0, 0.0


def prepare(code, kids, frames, P, tables, row, ws, k, ko, fo, wo):
    """Layer ``k`` at ``wo``: Ĉ(wo), whether ``wo`` agrees with the layer frame, the
    choice between layer and base (a defensive mixture of their expected contributions:
    the factors' estimates times the children's cheap albedos) and its cheap albedo."""
    op, b, fl, t = code[k, OP], code[k, BASE], code[k, FLAGS], code[k, TABLE]
    r = k * R
    k0 = code[k, KID0]
    lf = fo + code[k, LFRAME] * FR
    wol = ws[lf + FWO:lf + FWO + 3]
    ago = agree(code[k, LFRAME] == code[k, FRAME], wo, wol)
    ws[r + CO], ws[r + CO + 1], ws[r + CO + 2] = walker.layer_chat(code, kids, P, row, tables,
                                                                  k, wol, ago)
    ws[r + AGO] = 1.0 if ago else 0.0
    el0, el1, el2, eb0, eb1, eb2 = dispatch.layer_estimates(op, P, row, b, fl, wo, wol,
                                                            ws[r + CO:r + CO + 3], tables, t)
    pos_l, pos_b = dispatch.layer_possible(op, P, row, b, fl, tables, t)
    lay, bas = kids[k0], kids[k0 + 1]
    al0 = al1 = al2 = ab0 = ab1 = ab2 = 0.0
    if lay != NO_KID:
        q = lay * R + CH
        al0, al1, al2 = ws[q], ws[q + 1], ws[q + 2]
    else:
        pos_l = False
    if bas != NO_KID:
        q = bas * R + CH
        ab0, ab1, ab2 = ws[q], ws[q + 1], ws[q + 2]
    else:
        pos_b = False
    pos_l = pos_l and ago
    ka, kb = ko + k0 * KR, ko + (k0 + 1) * KR
    ws[ka + KSEL] = lum(el0 * al0, el1 * al1, el2 * al2)
    ws[kb + KSEL] = lum(eb0 * ab0, eb1 * ab1, eb2 * ab2)
    ws[ka + KON] = 1.0 if pos_l else 0.0
    ws[kb + KON] = 1.0 if pos_b else 0.0
    selection(ws, ko, k0, 2)
    ws[r + SEL] = ws[ka + KSEL]
    g = 1.0 if ago else 0.0
    ws[r + CH] = el0 * al0 * g + eb0 * ab0
    ws[r + CH + 1] = el1 * al1 * g + eb1 * ab1
    ws[r + CH + 2] = el2 * al2 * g + eb2 * ab2


def factors(code, kids, P, row, tables, ws, k, fo, wo, wi):
    """Layer ``k``'s factors ``(f_layer, f_base)`` at ``wi`` (its frames' registers
    set), after :func:`prepare` at ``wo``: the layer factor masked where a direction
    leaves the two tangent planes' common side; Ĉ(wi) kept in its register."""
    r = k * R
    lf = fo + code[k, LFRAME] * FR
    wol = ws[lf + FWO:lf + FWO + 3]
    wil = ws[lf + FWI:lf + FWI + 3]
    agi = agree(code[k, LFRAME] == code[k, FRAME], wi, wil)
    ws[r + CW], ws[r + CW + 1], ws[r + CW + 2] = walker.layer_chat(code, kids, P, row, tables,
                                                                  k, wil, agi)
    fl0, fl1, fl2, fb0, fb1, fb2 = dispatch.layer_factors(
        code[k, OP], P, row, code[k, BASE], code[k, FLAGS], wo, wi, wol, wil,
        ws[r + CO:r + CO + 3], ws[r + CW:r + CW + 3], tables, code[k, TABLE])
    if not (ws[r + AGO] > 0.0 and agi):
        fl0 = fl1 = fl2 = 0.0
    return fl0, fl1, fl2, fb0, fb1, fb2


def evaluate(code, kids, frames, P, tables, row, ws, k, ko, fo, wo, wi):
    """Layer ``k`` at ``wi`` after its children: ``f_layer layer + f_base base`` and the
    pdf of the mixture of the children's samplers -> ``(v0, v1, v2, pdf)``; each
    child's factor and whether it contributes in its registers."""
    k0 = code[k, KID0]
    fl0, fl1, fl2, fb0, fb1, fb2 = walker.layer_factors(code, kids, P, row, tables, ws, k, fo,
                                                        wo, wi)
    P_l = ws[k * R + SEL]
    ka, kb = ko + k0 * KR, ko + (k0 + 1) * KR
    ws[ka + KF], ws[ka + KF + 1], ws[ka + KF + 2] = fl0, fl1, fl2
    ws[kb + KF], ws[kb + KF + 1], ws[kb + KF + 2] = fb0, fb1, fb2
    lay, bas = kids[k0], kids[k0 + 1]
    cl0 = cl1 = cl2 = cb0 = cb1 = cb2 = pl = pb = 0.0
    if lay != NO_KID:
        q = lay * R
        cl0, cl1, cl2 = fl0 * ws[q], fl1 * ws[q + 1], fl2 * ws[q + 2]
        pl = ws[q + PDF]
    if bas != NO_KID:
        q = bas * R
        cb0, cb1, cb2 = fb0 * ws[q], fb1 * ws[q + 1], fb2 * ws[q + 2]
        pb = ws[q + PDF]
    on_l = any_pos(cl0, cl1, cl2)
    on_b = any_pos(cb0, cb1, cb2)
    ws[ka + KON] = 1.0 if on_l else 0.0
    ws[kb + KON] = 1.0 if on_b else 0.0
    pdf = (P_l * pl if on_l else 0.0) + ((1.0 - P_l) * pb if on_b else 0.0)
    return cl0 + cb0, cl1 + cb1, cl2 + cb2, pdf


def choose(code, ws, k, ko, u1):
    """The child a sample descends to -> ``(kid slot, u1 rescaled)``: the layer with
    probability SEL, else the base."""
    k0 = code[k, KID0]
    p = ws[k * R + SEL]
    if u1 < p:
        return k0, clamp_u(u1 / p if p > 0.0 else 0.0)
    return k0 + 1, clamp_u((u1 - p) / (1.0 - p) if p < 1.0 else 0.0)


def settle(code, ws, k, ko, j):
    """A delta sample through kid slot ``j``: ``(probability of the choice, factor)``."""
    o = ko + j * KR
    p = ws[k * R + SEL]
    return p if j == code[k, KID0] else 1.0 - p, ws[o + KF], ws[o + KF + 1], ws[o + KF + 2]


def factor_at(code, kids, frames, P, tables, row, ws, k, which, f0, f1, x, y, z):
    """Layer ``k``'s factor of its child ``which`` (0 the layer, 1 the base) at
    ``wi = (x, y, z)`` (frame ``f0``), after :func:`prepare` at ``wo``."""
    fo = code.shape[0] * R + kids.shape[0] * KR
    set_dirs(frames, ws, fo, f0, f1, FWI, x, y, z)
    fr = fo + code[k, FRAME] * FR
    a = walker.layer_factors(code, kids, P, row, tables, ws, k, fo, ws[fr + FWO:fr + FWO + 3],
                             ws[fr + FWI:fr + FWI + 3])
    if which == 0:
        return a[0], a[1], a[2]
    return a[3], a[4], a[5]


def albedo(code, kids, frames, P, tables, row, ws, k, ko, fo, f0, f1, points, ox, oy, oz, wo):
    """Layer ``k``'s directional albedo at ``wo``, from its children's (``AL``): the
    factors' estimates at ``wo`` times the children's albedos, plus, where the factors
    vary over ``wi``, the integral of their deviation through each child's sampler
    (:func:`render.interpreter.correction`); a mirror base takes its factor at the
    mirror direction.  Clipped to [0, 1]: a layer never gains energy."""
    op = code[k, OP]
    r = k * R
    k0 = code[k, KID0]
    lay, bas = kids[k0], kids[k0 + 1]
    lf = fo + code[k, LFRAME] * FR
    wol = ws[lf + FWO:lf + FWO + 3]
    el0, el1, el2, eb0, eb1, eb2 = dispatch.layer_estimates(
        op, P, row, code[k, BASE], code[k, FLAGS], wo, wol, ws[r + CO:r + CO + 3], tables,
        code[k, TABLE])
    if not ws[r + AGO] > 0.0:
        el0 = el1 = el2 = 0.0
    identity = code[k, LFRAME] == code[k, FRAME]
    directional = dispatch.DIRECTIONAL[op]
    a0 = a1 = a2 = 0.0
    if lay != NO_KID:
        q = lay * R + AL
        a0, a1, a2 = el0 * ws[q], el1 * ws[q + 1], el2 * ws[q + 2]
        if not (identity and (not directional or walker.is_mirror(code, lay))):
            d0, d1, d2 = walker.correction(code, kids, frames, P, tables, row, ws, k, lay, 0,
                                           el0, el1, el2, f0, f1, ox, oy, oz, points)
            a0, a1, a2 = a0 + d0, a1 + d1, a2 + d2
    if bas != NO_KID:
        q = bas * R + AL
        if directional and walker.is_mirror(code, bas):
            walker.prepare(code, kids, frames, P, tables, row, ws, k, k, f0, f1, ox, oy, oz)
            m0, m1, m2 = walker.layer_factor_at(code, kids, frames, P, tables, row, ws, k, 1,
                                                f0, f1, -ox, -oy, oz)
            a0, a1, a2 = a0 + m0 * ws[q], a1 + m1 * ws[q + 1], a2 + m2 * ws[q + 2]
        else:
            a0, a1, a2 = a0 + eb0 * ws[q], a1 + eb1 * ws[q + 1], a2 + eb2 * ws[q + 2]
            if directional:
                d0, d1, d2 = walker.correction(code, kids, frames, P, tables, row, ws, k, bas,
                                               1, eb0, eb1, eb2, f0, f1, ox, oy, oz, points)
                a0, a1, a2 = a0 + d0, a1 + d1, a2 + d2
    return min(max(a0, 0.0), 1.0), min(max(a1, 0.0), 1.0), min(max(a2, 0.0), 1.0)


def build_chat_table(code, kids, frames, P, tables, row, k, dirs, points, out):
    """The Ĉ table of curve layer ``k`` (both sides; compiled by the interpreter as
    :func:`render.interpreter.build_chat_table`): ``out`` (2, 2, THETA, 3) gets per
    side the node values (largest over the azimuths of ``dirs``) and the concave pad.

    ``dirs`` (2, THETA * PHI, 3): the layer-frame table directions of each side;
    ``points`` (m, 3) the Sobol points.  The layer child is sampled in its own frame;
    with an elemental layer ``C(nk) albedo_L`` is the control variate.
    """
    ws = np.empty(work_size(code.shape[0], kids.shape[0], frames.shape[0]))
    n = code.shape[0]
    ko = n * R
    fo = ko + kids.shape[0] * KR
    nf = frames.shape[0]
    op = code[k, OP]
    b = code[k, BASE]
    fl = code[k, FLAGS]
    lay = kids[code[k, KID0]]
    lframe = code[k, LFRAME]
    controlled = dispatch.ROLE[code[lay, OP]] == 0  # an elemental layer
    theta = CHAT_THETA
    nd = dirs.shape[1]
    phi = nd // theta
    m = points.shape[0]
    set_bases(frames, P, row, ws, fo, 0, nf)
    for side in range(2):
        for t in range(theta):
            for c in range(3):
                out[side, 0, t, c] = 0.0
        for d in range(nd):
            vx, vy, vz = dirs[side, d, 0], dirs[side, d, 1], dirs[side, d, 2]
            # the direction in frame 0, for the subtree's own frames
            gx, gy, gz = to_frame0(frames, ws, fo, lframe, vx, vy, vz)
            n0, n1, n2 = dispatch.curve_nk(op, P, row, b, fl, vx, vy, vz, tables, code[k, TABLE])
            s0 = s1 = s2 = 0.0
            for i in range(m):
                s = walker.sample(code, kids, frames, P, tables, row, ws, lay, 0, nf, gx, gy, gz,
                           points[i, 0], points[i, 1], points[i, 2], False)
                if s[7] == 0:
                    continue
                fx, fy, fz = s[0], s[1], s[2]
                # back into the layer frame
                lf = fo + lframe * FR
                if lframe > 0:
                    set_dirs(frames, ws, fo, 0, nf, FWI, fx, fy, fz)
                    fx, fy, fz = ws[lf + FWI], ws[lf + FWI + 1], ws[lf + FWI + 2]
                h0, h1, h2 = dispatch.curve_h(op, P, row, b, fl, vx, vy, vz, fx, fy, fz, tables,
                                     code[k, TABLE])
                if controlled:
                    h0, h1, h2 = h0 - n0, h1 - n1, h2 - n2
                s0 += h0 * s[4]
                s1 += h1 * s[5]
                s2 += h2 * s[6]
            c0, c1, c2 = s0 / m, s1 / m, s2 / m
            if controlled:
                a0, a1, a2 = dispatch.albedo(code[lay, OP], P, row, code[lay, BASE],
                                         code[lay, FLAGS], vx, vy, vz, tables,
                                         code[lay, TABLE])
                c0, c1, c2 = c0 + n0 * a0, c1 + n1 * a1, c2 + n2 * a2
            if not abs(vz) > 0.0:
                c0 = c1 = c2 = 0.0
            t = d // phi
            out[side, 0, t, 0] = max(out[side, 0, t, 0], min(max(c0, 0.0), 1.0))
            out[side, 0, t, 1] = max(out[side, 0, t, 1], min(max(c1, 0.0), 1.0))
            out[side, 0, t, 2] = max(out[side, 0, t, 2], min(max(c2, 0.0), 1.0))
        # the concave correction of each interval (second differences, pole mirrored)
        for c in range(3):
            for t in range(theta):
                out[side, 1, t, c] = 0.0
            for t in range(theta - 1):
                d2a = _second_difference(out, side, c, t, theta)
                d2b = _second_difference(out, side, c, t + 1, theta)
                out[side, 1, t, c] = 0.5 * max(0.0, -min(d2a, d2b))


@njit
def _second_difference(out, side, c, t, theta):
    """``v[t-1] - 2 v[t] + v[t+1]`` with the pole mirrored (``v[-1] = v[1]``) and the last
    node taking its neighbour's value."""
    if t == theta - 1:
        t = theta - 2
    prev = out[side, 0, 1, c] if t == 0 else out[side, 0, t - 1, c]
    return prev - 2.0 * out[side, 0, t, c] + out[side, 0, t + 1, c]
