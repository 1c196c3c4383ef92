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

from render.df import _kernel_common as kc
from render.df._signature import THIN_WALLED
from render.jit import njit

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
# geometry of CurveLayer._curves and the Fresnel and F82 curves, ported formula by
# formula (same operations in the same order) on render.df._kernel_common's helpers.

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
