"""render.df._kernel_common: the kernels' scalar helpers, called a lane at a time, against
closed forms written differently (Fresnel from the angles, Snell's law as a property of
the refracted direction, lengths by ``math.hypot``), values worked out by hand, and their
extremes: 0 and 1, grazing, degenerate, tiny and huge."""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from render.df import _kernel_common as kc


def _dirs(rng, n):
    v = rng.normal(size=(n, 3))
    return v / np.linalg.norm(v, axis=1)[:, None]


def _fresnel(ci, eta):
    """(n,) reflectances and transmitted cosines of :func:`kc.fresnel_dielectric`."""
    got = np.array([kc.fresnel_dielectric(c, eta) for c in np.atleast_1d(ci)])
    return got[:, 0], got[:, 1]


def _fresnel_from_angles(c, e):
    """The textbook form in the angles (Hecht): ``R_s = sin^2(ti - tt) / sin^2(ti + tt)``,
    ``R_p = tan^2(ti - tt) / tan^2(ti + tt)``, ``e`` the transmitted side's IOR over the
    incident side's, ``0 <= c <= 1``."""
    ti = math.acos(c)
    st_ = math.sin(ti) / e
    if st_ >= 1.0:
        return 1.0  # total internal reflection
    if ti == 0.0:
        return ((e - 1.0) / (e + 1.0)) ** 2  # the limit at normal incidence
    tt = math.asin(st_)
    rs = math.sin(ti - tt) / math.sin(ti + tt)
    rp = math.tan(ti - tt) / math.tan(ti + tt)
    return 0.5 * (rs * rs + rp * rp)


# --- Fresnel -------------------------------------------------------------------------------


@pytest.mark.parametrize("eta", [1.0001, 0.9999, 1.5, 1 / 1.5, 3.0, 1e-3])
def test_fresnel_is_the_angle_form_including_extremes(eta, rng):
    ci = np.concatenate([rng.uniform(-1, 1, 4000), [-1.0, 1.0, 1e-12, -1e-12, 1e-6, 0.5]])
    F, ct = _fresnel(ci, eta)
    e = np.where(ci >= 0, eta, 1 / eta)
    c = np.abs(ci)
    want = np.array([_fresnel_from_angles(x, y) for x, y in zip(c, e, strict=True)])
    np.testing.assert_allclose(F, want, rtol=1e-9, atol=1e-12)
    assert np.all((F >= 0) & (F <= 1)) and np.all(np.isfinite(ct))
    # Snell: e sin t = sin i, and the transmitted cosine on the other side (0 under TIR)
    tir = F == 1.0
    np.testing.assert_allclose((1 - ct * ct)[~tir], ((1 - c * c) / (e * e))[~tir], atol=1e-15)
    assert np.all(np.sign(ct[~tir & (c > 0)]) == -np.sign(ci[~tir & (c > 0)]))
    assert np.all(ct[tir & (e < 1)] == 0.0)
    # from below with eta is from above with 1 / eta, the transmitted cosine mirrored (to
    # rounding: 1 / (1 / eta) need not be eta, and near an index match F is sensitive to it)
    F2, ct2 = _fresnel(-ci, 1 / eta)
    np.testing.assert_allclose(F2[ci > 0], F[ci > 0], rtol=1e-9, atol=1e-15)
    np.testing.assert_allclose(ct2[ci > 0], -ct[ci > 0], rtol=1e-9, atol=1e-12)


@pytest.mark.parametrize("eta", [1.0001, 1.5, 3.0])
def test_fresnel_normal_incidence(eta):
    F, ct = _fresnel([1.0, -1.0], eta)
    assert F == pytest.approx(((eta - 1) / (eta + 1)) ** 2, rel=1e-12)
    assert ct.tolist() == [-1.0, 1.0]
    # a cosine beyond 1 (rounding of a dot product) is normal incidence
    assert kc.fresnel_dielectric(1.5, eta) == kc.fresnel_dielectric(1.0, eta)


def test_fresnel_index_matched_is_exactly_zero_even_at_grazing():
    c = np.array([1.0, 0.3, 1e-12, 0.0, -0.5, -0.0])
    F, ct = _fresnel(c, 1.0)
    assert np.all(F == 0.0)
    assert np.allclose(ct, [-1.0, -0.3, -1e-12, 0.0, 0.5, 0.0])


def test_fresnel_grazing_and_total_internal_reflection():
    F, ct = _fresnel([0.0, -0.0, 1e-10], 1.5)
    assert F[0] == 1.0 and F[1] == 1.0 and F[2] == pytest.approx(1.0, abs=1e-9)
    # from inside glass (cos < 0): critical angle asin(1/1.5) = 41.81 degrees
    c_crit = np.cos(np.arcsin(1 / 1.5))
    F, ct = _fresnel([-(c_crit - 1e-9), -(c_crit + 1e-9), -0.01], 1.5)
    assert F[0] == 1.0 and F[2] == 1.0 and ct[0] == 0.0
    assert F[1] < 1.0 and ct[1] > 0
    # a tiny and a huge relative IOR: all but normal incidence reflects
    assert kc.fresnel_dielectric(0.5, 1e-300) == (1.0, -0.0)
    F, ct = kc.fresnel_dielectric(0.5, 1e300)
    assert F == pytest.approx(1.0, abs=1e-12) and ct == pytest.approx(-1.0)


def test_fresnel_value_by_hand():
    # cos 0.3, eta 1.5: cos_t = sqrt(1 - 0.91/2.25) = 0.771723;
    # rs = (0.3 - 1.5 cos_t)/(0.3 + 1.5 cos_t) = -0.588360,
    # rp = (0.45 - cos_t)/(0.45 + cos_t) = -0.263336
    F, ct = kc.fresnel_dielectric(0.3, 1.5)
    assert ct == pytest.approx(-0.771723, abs=1e-6)
    assert F == pytest.approx(0.5 * (0.588360**2 + 0.263336**2), abs=2e-6)


@settings(max_examples=300)
@given(st.floats(1e-4, 1.0), st.floats(0.2, 5.0))
def test_fresnel_is_symmetric_across_the_interface(c, eta):
    # Stokes: the reflectance seen from inside at the transmitted angle is the same.
    # (Below c ~ 1e-4 the round trip through cos_t is ill-conditioned: cos_i^2 is
    # recovered as 1 - (1 - cos_t^2) eta^2 with an absolute error ~1e-16 eta^2.)
    F1, ct = kc.fresnel_dielectric(c, eta)
    F2, ci = kc.fresnel_dielectric(ct, eta)
    assert 0.0 <= F1 <= 1.0
    if F1 < 1.0:
        assert F2 == pytest.approx(F1, abs=1e-9)
        assert ci == pytest.approx(c, abs=1e-8)


def test_fresnel3_is_one_call_per_channel():
    f3 = kc.fresnel_dielectric3(0.3, 1.0, 1.5, 3.0)
    assert f3 == tuple(kc.fresnel_dielectric(0.3, e)[0] for e in (1.0, 1.5, 3.0))
    assert f3[0] == 0.0 and 0.0 < f3[1] < f3[2] < 1.0


# --- refraction and reflection --------------------------------------------------------------


def _refract(k, m, b):
    got = np.array([kc.refract(*k[i], *m[i], b) for i in range(len(k))])
    return got[:, :3], got[:, 3].astype(bool)


@pytest.mark.parametrize("b", [1.0, 1 / 1.5, 1.5, 3.0, 1e-3])
def test_refract_obeys_snell_and_mirrors_under_tir(b, rng):
    k = _dirs(rng, 3000)
    m = _dirs(rng, 3000)
    k = np.where((np.einsum("ij,ij->i", k, m) < 0)[:, None], -k, k)
    k = np.concatenate([k, [[0.0, 0.0, 1.0], [1.0, 0.0, 0.0]]])  # normal and grazing
    m = np.concatenate([m, [[0.0, 0.0, 1.0], [0.0, 0.0, 1.0]]])
    w, tir = _refract(k, m, b)
    c = np.einsum("ij,ij->i", k, m)
    wm = np.einsum("ij,ij->i", w, m)
    assert np.all(np.isfinite(w))
    np.testing.assert_allclose(np.linalg.norm(w, axis=1), 1.0, atol=1e-14)
    sin2 = 1.0 - c * c
    assert np.array_equal(tir, b * b * sin2 > 1.0)
    # refracted: the tangential part is -b times k's, on the far side, cos_t from Snell
    tk = k - c[:, None] * m
    tw = w - wm[:, None] * m
    ok = ~tir
    np.testing.assert_allclose(tw[ok], -b * tk[ok], atol=1e-13)
    np.testing.assert_allclose(wm[ok], -np.sqrt(1.0 - b * b * sin2[ok]), atol=1e-13)
    # total internal reflection: the mirror direction (same cosine, tangential part negated)
    np.testing.assert_allclose(wm[tir], c[tir], atol=1e-13)
    np.testing.assert_allclose(tw[tir], -tk[tir], atol=1e-13)
    assert np.any(tir) == (b > 1.0)


def test_refract_snell_and_tir_by_hand():
    n = np.array([[0.0, 0.0, 1.0]] * 3)
    k = np.array([[np.sin(0.5), 0, np.cos(0.5)], [np.sin(1.2), 0, np.cos(1.2)], [0, 0, 1.0]])
    w = np.array([kc.refract(*k[i], *n[i], b) for i, b in enumerate([1 / 1.5, 1.5, 1.0])])
    k2, tir = w[:, :3], w[:, 3].astype(bool)
    assert tir.tolist() == [False, True, False]
    assert np.sin(0.5) == pytest.approx(1.5 * np.hypot(*k2[0, :2]), rel=1e-14)
    assert k2[0, 2] < 0 and k2[0, 0] < 0
    assert np.allclose(k2[1], [-np.sin(1.2), 0.0, np.cos(1.2)])  # the mirror direction
    assert np.allclose(k2[2], [0, 0, -1.0])
    assert np.allclose(np.linalg.norm(k2, axis=1), 1.0)


def test_reflect_orient_mirror_and_clamp_by_hand():
    assert kc.reflect(1.0, 0.0, 1.0, 0.0, 0.0, 1.0) == (-1.0, 0.0, 1.0)
    s = math.sqrt(0.5)
    assert np.allclose(kc.reflect(0.0, 0.0, 1.0, s, 0.0, s), (1.0, 0.0, 0.0), atol=1e-15)
    assert kc.reflect_z(0.6, 0.0, 0.8) == (-0.6, -0.0, 0.8)
    assert kc.orient(-0.25) == (True, 0.25) and kc.orient(-0.0) == (False, -0.0)
    assert kc.mirror_z(0.5, True) == -0.5 and kc.mirror_z(0.5, False) == 0.5
    assert kc.clamp_u(1.0) == kc.ONE_MINUS_EPS and kc.clamp_u(-3.0) == 0.0
    assert kc.clamp_u(0.25) == 0.25 and kc.ONE_MINUS_EPS < 1.0
    assert kc.safe_sqrt(-1e-300) == 0.0 and kc.safe_sqrt(-1.0) == 0.0 and kc.safe_sqrt(4.0) == 2.0
    assert kc.dot3(1.0, 2.0, 3.0, 0.0, 1.0, 1.0) == 5.0


# --- unitize, frames, the cosine warp --------------------------------------------------------


def test_unitize_is_v_over_its_hypot_from_tiny_to_huge(rng):
    v = np.concatenate([rng.normal(size=(500, 3)) * 10.0 ** rng.uniform(-299, 300, (500, 1)),
                        [[3e-200, 0, 4e-200], [3e200, 0, 4e200], [1e308, 1e308, -1e308],
                         [0.0, 0.0, 0.0], [1e-301, 0.0, 0.0], [1e-320, 0, 0], [0, 1e-299, 0]]])
    got = np.array([kc.unitize(*row) for row in v])
    u, ok = got[:, :3], got[:, 3].astype(bool)
    # below UNIT_MIN (1e-300) a vector has no usable direction
    valid = np.abs(v).max(axis=1) > 1e-300
    assert np.array_equal(ok, valid) and not ok[-4:-1].any() and ok[-1]
    want = np.array([row / math.hypot(*row) for row in v[valid]])
    np.testing.assert_allclose(u[valid], want, rtol=1e-14, atol=1e-15)
    assert np.all(u[~valid] == 0.0)
    assert np.allclose(u[500:502], [[0.6, 0, 0.8]] * 2)


def test_frame_from_normal_is_a_right_handed_orthonormal_basis(rng):
    n = np.concatenate([_dirs(rng, 500), [[0, 0, 1.0], [0, 0, -1.0], [1.0, 0, 0],
                                           [0, 0, -0.0 - 1e-300]]])
    got = np.array([kc.frame_from_normal(*row) for row in n])
    s, t = got[:, :3], got[:, 3:]
    assert np.all(np.isfinite(got))
    unit = n[:-1]  # the last is no unit normal: only finite
    s, t = s[:-1], t[:-1]
    np.testing.assert_allclose(np.linalg.norm(s, axis=1), 1.0, atol=1e-14)
    np.testing.assert_allclose(np.linalg.norm(t, axis=1), 1.0, atol=1e-14)
    for a, b in ((s, t), (s, unit), (t, unit)):
        np.testing.assert_allclose(np.einsum("ij,ij->i", a, b), 0.0, atol=1e-14)
    np.testing.assert_allclose(np.cross(s, t), unit, atol=1e-14)
    # the poles: the identity above, (x, -y) below
    assert got[-4].tolist() == [1.0, 0.0, 0.0, 0.0, 1.0, 0.0]
    assert (got[-3] + 0.0).tolist() == [1.0, 0.0, 0.0, 0.0, -1.0, 0.0]


def test_cosine_hemisphere_by_hand_and_at_the_edges(rng):
    s = math.sqrt(0.5)
    cases = {(0.5, 0.5): (0.0, 0.0, 1.0), (1.0, 0.5): (1.0, 0.0, 0.0),
             (0.0, 0.5): (-1.0, 0.0, 0.0), (0.5, 1.0): (0.0, 1.0, 0.0),
             (0.5, 0.0): (0.0, -1.0, 0.0), (1.0, 1.0): (s, s, 0.0)}
    for u, w in cases.items():
        assert np.allclose(kc.cosine_hemisphere(*u), w, atol=1e-15), u
    u = np.concatenate([rng.random((2000, 2)), [[0.0, 0.0], [kc.ONE_MINUS_EPS] * 2,
                                                 [1e-300, 0.5], [0.5, 1e-17]]])
    w = np.array([kc.cosine_hemisphere(a, b) for a, b in u])
    assert np.all(w[:, 2] >= 0.0)
    np.testing.assert_allclose(np.linalg.norm(w, axis=1), 1.0, atol=1e-14)


# --- the IOR pair and the tangent axes -------------------------------------------------------


@pytest.mark.parametrize("glossy", [False, True])
@pytest.mark.parametrize("thin", [False, True])
def test_ior_pair_by_hand(glossy, thin):
    outside = [1.0, 1.0, 1.5, 1.0, 1.33]
    inside = [1.5, 1.0, 1.0, 1.00005, 1.33 - 5e-5]
    flip = [False, True, True, False, True]
    # glossy: an inside within IOR_DELTA_MIN (1e-4) of the outside is pushed 1e-4 away
    # (an exact match makes the inside the denser side), before orienting
    pushed = [1.5, 1.0 + 1e-4, 1.0, 1.0 + 1e-4, 1.33 - 1e-4] if glossy else inside
    # viewed from below, a solid swaps the pair; a thin-walled surface never does
    want = [(o, i) if not (f and not thin) else (i, o)
            for o, i, f in zip(outside, pushed, flip, strict=True)]
    got = [kc.ior_pair(o, i, f, thin, glossy)
           for o, i, f in zip(outside, inside, flip, strict=True)]
    assert got == want


def test_tangent_axes_by_hand():
    r5 = math.sqrt(5.0)
    assert np.allclose(kc.tangent_axes(1.0, 2.0, 3.0)[:2], (1 / r5, 2 / r5), atol=1e-15)
    assert kc.tangent_axes(1.0, 2.0, 3.0)[2]
    assert kc.tangent_axes(0.0, -1.0, 0.0) == (0.0, -1.0, True)
    assert kc.tangent_axes(3e-200, 4e-200, 0.0)[2]
    # parallel to the normal (or within 1e-8 of it), zero, subnormal: +x, not valid
    for t in ((0.0, 0.0, 1.0), (1e-9, 0.0, 1.0), (0.0, 0.0, 0.0), (1e-310, 0.0, 0.0)):
        assert kc.tangent_axes(*t) == (1.0, 0.0, False), t
