"""An object's points, normals and tangents between world and object space
(:class:`render.scene.SceneObject`, one compiled pass each): the matrix algebra, unit
results at tiny and huge lengths, +z for rows too short to have a direction, and both
memory layouts the integrator passes (slices of its attribute rows, and copies)."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st

from displacement.surfaces import UnitSquare
from render.material import material
from render.scene import SceneObject, _unit_rows, make_transform

angles = st.floats(-180.0, 180.0)
scales = st.floats(0.01, 100.0) | st.floats(-100.0, -0.01)


def _object(rotate, scale, translate):
    return SceneObject(UnitSquare(), material(), make_transform(translate, rotate, scale))


def _rows(seed, n=64):
    return np.random.default_rng(seed).normal(size=(n, 3))


@given(st.tuples(angles, angles, angles), st.tuples(scales, scales, scales),
       st.tuples(*[st.floats(-1e3, 1e3)] * 3), st.integers(0, 2**32 - 1))
def test_the_matrix_algebra_of_points_normals_and_tangents(rotate, scale, translate, seed):
    obj = _object(rotate, scale, translate)
    m = obj.transform
    p = _rows(seed)
    world = p @ m[:3, :3].T + m[:3, 3]
    assert np.allclose(obj.to_object_points(world), p, rtol=1e-9, atol=1e-9 * (1 + np.abs(
        world).max()) * np.abs(obj.inv_linear).max())
    v = _rows(seed + 1)
    tv = obj.to_object_vectors(v)
    ref = v @ obj.inv_linear.T
    assert np.allclose(tv, ref / np.linalg.norm(ref, axis=1)[:, None], atol=1e-12)
    nv = obj.to_object_normals(v)
    ref = v @ obj.linear
    assert np.allclose(nv, ref / np.linalg.norm(ref, axis=1)[:, None], atol=1e-12)
    # a normal stays perpendicular to the tangents it was perpendicular to
    t = obj.to_object_vectors(np.cross(v, _rows(seed + 2)))
    assert np.all(np.abs(np.einsum("ij,ij->i", obj.to_object_normals(v), t)) < 1e-9)
    back = obj.to_world_normals(nv)
    assert np.allclose(back, v / np.linalg.norm(v, axis=1)[:, None], atol=1e-9)


@pytest.mark.parametrize("length", [1e-290, 1e-150, 1e-20, 1.0, 1e20, 1e150, 1e300])
def test_unit_at_tiny_and_huge_lengths(length):
    v = _rows(7) / np.linalg.norm(_rows(7), axis=1)[:, None]
    u = _unit_rows(v * length)
    assert np.all(np.isfinite(u))
    assert np.allclose(u, v, atol=1e-15)


def test_rows_too_short_for_a_direction_become_plus_z():
    # no component above TOL.unit_min (1e-300): no direction to keep
    v = np.array([[0.0, 0.0, 0.0], [5e-324, 0.0, 0.0], [-0.0, 0.0, -0.0], [1e-300, 0, 0],
                  [0.0, 3.0, 4.0]])
    assert np.allclose(_unit_rows(v), [[0, 0, 1], [0, 0, 1], [0, 0, 1], [0, 0, 1],
                                       [0.0, 0.6, 0.8]], rtol=0, atol=1e-15)
    obj = _object((10.0, 20.0, 30.0), (2.0, 3.0, 0.5), (1.0, 2.0, 3.0))
    assert obj.to_object_normals(np.zeros((2, 3))).tolist() == [[0, 0, 1], [0, 0, 1]]
    assert obj.to_object_vectors(np.zeros((1, 3))).tolist() == [[0, 0, 1]]


def test_strided_rows_and_copies_give_the_same_rows():
    a = np.random.default_rng(3).normal(size=(50, 14))
    obj = _object((30.0, -40.0, 75.0), (1.5, -2.0, 0.25), (0.5, -1.0, 2.0))
    for f in (obj.to_object_points, obj.to_object_normals, obj.to_object_vectors,
              obj.to_world_normals, _unit_rows):
        assert np.array_equal(f(a[:, 3:6]), f(np.ascontiguousarray(a[:, 3:6])))
    assert obj.to_object_points(np.zeros((0, 3))).shape == (0, 3)
    with pytest.raises(ValueError, match="rows of 3 numbers"):
        obj.to_object_points(np.zeros(3))
