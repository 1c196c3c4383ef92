"""The local shading frame: orthonormal, right-handed, stable at the poles, tangent-aligned."""

from __future__ import annotations

import numpy as np
import pytest

from render.frame import Frame, cos_phi, mirror_z, sin_phi, tan_theta


def _normals(rng, n=2000):
    v = rng.normal(size=(n, 3))
    v = np.concatenate(
        [v, [[0, 0, 1.0], [0, 0, -1.0], [1e-12, 0, -1.0], [0, 1e-9, -1.0], [1.0, 0, 0]]]
    )
    return v / np.linalg.norm(v, axis=1, keepdims=True)


def test_from_normal_is_orthonormal_and_right_handed(rng):
    n = _normals(rng)
    f = Frame.from_normal(n)
    for a in (f.s, f.t, f.n):
        assert np.allclose(np.linalg.norm(a, axis=1), 1.0, atol=1e-12)
    assert np.allclose(np.einsum("ij,ij->i", f.s, f.t), 0.0, atol=1e-12)
    assert np.allclose(np.einsum("ij,ij->i", f.s, f.n), 0.0, atol=1e-12)
    assert np.allclose(np.cross(f.s, f.t), f.n, atol=1e-12)


def test_round_trip(rng):
    f = Frame.from_normal(_normals(rng))
    v = rng.normal(size=(len(f.n), 3))
    assert np.allclose(f.to_world(f.to_local(v)), v, atol=1e-12)
    assert np.allclose(f.to_local(f.n), [0.0, 0.0, 1.0], atol=1e-12)


def test_tangent_frame_follows_tangent_u(rng):
    n = _normals(rng)
    tu = rng.normal(size=n.shape)
    f = Frame.from_normal_tangent(n, tu)
    proj = tu - np.einsum("ij,ij->i", tu, n)[:, None] * n
    proj /= np.linalg.norm(proj, axis=1, keepdims=True)
    assert np.allclose(f.s, proj, atol=1e-10)
    assert np.allclose(np.cross(f.s, f.t), f.n, atol=1e-12)
    # a tangent parallel to the normal (or zero) falls back to from_normal
    g = Frame.from_normal_tangent(n[:2], np.stack([n[0] * 3, np.zeros(3)]))
    assert np.allclose(g.s, Frame.from_normal(n[:2]).s)


@pytest.mark.parametrize("length", [1e-150, 1e-20, 1.0, 1e20, 1e160, 1e300])
def test_tangent_frame_at_tiny_and_huge_tangents(rng, length):
    # the same frame whatever the tangent's length, one tangent for every row alike
    n = _normals(rng, 200)
    tu = rng.normal(size=3)
    ref = Frame.from_normal_tangent(n, np.broadcast_to(tu, n.shape))
    f = Frame.from_normal_tangent(n, tu * length)
    assert np.all(np.isfinite(f.s)) and np.all(np.isfinite(f.t))
    assert np.allclose(f.s, ref.s, atol=1e-12) and np.allclose(f.t, ref.t, atol=1e-12)


def test_tangent_within_rounding_of_the_normal_falls_back():
    n = np.array([[0.0, 0.6, 0.8]] * 3)
    tu = n + np.array([[1e-10, 0.0, 0.0], [1e-7, 0.0, 0.0], [0.0, 0.0, 0.0]])
    f = Frame.from_normal_tangent(n, tu)
    duff = Frame.from_normal(n[:1]).s[0]
    assert np.allclose(f.s[0], duff) and np.allclose(f.s[2], duff)  # noise, and parallel
    assert np.allclose(f.s[1], [1.0, 0.0, 0.0])  # 1e-7 off the normal: a real direction
    assert np.allclose(np.cross(f.s, f.t), n, atol=1e-12)


def test_spherical_helpers_at_poles_and_horizon():
    w = np.array([[0.0, 0.0, 1.0], [0.0, 0.0, -1.0], [1.0, 0.0, 0.0], [0.0, -1.0, 0.0]])
    assert cos_phi(w).tolist() == [1.0, 1.0, 1.0, 0.0]
    assert sin_phi(w).tolist() == [0.0, 0.0, 0.0, -1.0]
    assert tan_theta(w).tolist() == [0.0, 0.0, 0.0, 0.0]  # defined (0) in the tangent plane
    assert mirror_z(w)[:, 2].tolist() == [-1.0, 1.0, -0.0, -0.0]


def test_tan_theta_grazing():
    t = np.radians(89.9)
    assert tan_theta(np.array([[np.sin(t), 0.0, np.cos(t)]]))[0] == pytest.approx(
        np.tan(t), rel=1e-9
    )
