"""render.df._kernel_common: each scalar helper agrees with its numpy counterpart to rounding
(1e-13 relative: the two need not sum in the same order)."""

from __future__ import annotations

import numpy as np
import pytest

from render.df import _common
from render.df import _kernel_common as kc
from render.frame import Frame
from render.numerics import fresnel_dielectric, refract, unitize
from render.warp import square_to_cosine_hemisphere


def _dirs(rng, n):
    v = rng.normal(size=(n, 3))
    return v / np.linalg.norm(v, axis=1)[:, None]


def test_fresnel_equals_numpy_including_extremes(rng):
    ci = np.concatenate([rng.uniform(-1, 1, 4000), [0.0, -0.0, 1.0, -1.0, 1e-12, -1e-12, 1.5]])
    for eta in (1.0, 1.0001, 0.9999, 1.5, 1 / 1.5, 3.0, 1e-3):
        F, ct = fresnel_dielectric(ci, eta)
        got = np.array([kc.fresnel_dielectric(c, eta) for c in ci])
        np.testing.assert_array_equal(got[:, 0], F)
        np.testing.assert_array_equal(got[:, 1], ct)
    f3 = kc.fresnel_dielectric3(0.3, 1.0, 1.5, 3.0)
    assert f3 == tuple(float(fresnel_dielectric(np.array([0.3]), e)[0][0]) for e in (1, 1.5, 3))


def test_refract_equals_numpy_with_tir(rng):
    k = _dirs(rng, 3000)
    m = _dirs(rng, 3000)
    k = np.where((np.einsum("ij,ij->i", k, m) < 0)[:, None], -k, k)
    for b in (1.0, 1 / 1.5, 1.5, 3.0):
        want, tir = refract(k, m, b)
        got = np.array([kc.refract(*k[i], *m[i], b) for i in range(len(k))])
        np.testing.assert_allclose(got[:, :3], want, rtol=1e-13, atol=1e-15)
        np.testing.assert_array_equal(got[:, 3].astype(bool), tir)
    assert np.any(tir)


def test_unitize_frame_and_warp_equal_numpy(rng):
    v = np.concatenate([rng.normal(size=(500, 3)) * 10.0 ** rng.uniform(-300, 300, (500, 1)),
                        [[0.0, 0.0, 0.0], [1e-301, 0.0, 0.0]]])
    u, ok = unitize(v)
    got = np.array([kc.unitize(*row) for row in v])
    np.testing.assert_allclose(got[:, :3], u, rtol=1e-13, atol=1e-15)
    np.testing.assert_array_equal(got[:, 3].astype(bool), ok)
    n = np.concatenate([_dirs(rng, 500), [[0, 0, 1.0], [0, 0, -1.0], [0, 0, -0.0 - 1e-300]]])
    f = Frame.from_normal(n)
    got = np.array([kc.frame_from_normal(*row) for row in n])
    np.testing.assert_allclose(got, np.concatenate([f.s, f.t], axis=1), rtol=1e-13, atol=1e-15)
    uu = np.concatenate([rng.random((2000, 2)), [[0.5, 0.5], [0.0, 0.0], [kc.ONE_MINUS_EPS] * 2]])
    got = np.array([kc.cosine_hemisphere(a, b) for a, b in uu])
    np.testing.assert_array_equal(got, square_to_cosine_hemisphere(uu))


@pytest.mark.parametrize("glossy", [False, True])
@pytest.mark.parametrize("thin", [False, True])
def test_ior_pair_orient_tangent_axes(glossy, thin):
    outside = np.array([1.0, 1.0, 1.5, 1.0, 1.33])
    inside = np.array([1.5, 1.0, 1.0, 1.00005, 1.33 - 5e-5])
    flip = np.array([False, True, True, False, True])
    e1, e2 = _common.ior_pair(outside, inside, flip, thin, glossy)
    got = np.array([kc.ior_pair(o, i, f, thin, glossy)
                    for o, i, f in zip(outside, inside, flip, strict=True)])
    np.testing.assert_array_equal(got, np.stack([e1, e2], axis=1))
    assert kc.orient(-0.25) == (True, 0.25) and kc.orient(-0.0) == (False, -0.0)
    assert kc.mirror_z(0.5, True) == -0.5 and kc.mirror_z(0.5, False) == 0.5
    t = np.array([[1.0, 2.0, 3.0], [0.0, 0.0, 1.0], [1e-9, 0.0, 1.0], [0.0, -1.0, 0.0]])
    tx, ty, valid = _common.tangent_axes(t, len(t))
    got = np.array([kc.tangent_axes(*row) for row in t])
    np.testing.assert_array_equal(got, np.stack([tx, ty, valid], axis=1))
    assert kc.reflect(1.0, 0.0, 1.0, 0.0, 0.0, 1.0) == (-1.0, 0.0, 1.0)
    assert kc.reflect_z(0.6, 0.0, 0.8) == (-0.6, -0.0, 0.8)
    assert kc.clamp_u(1.0) == kc.ONE_MINUS_EPS and kc.clamp_u(-3.0) == 0.0
