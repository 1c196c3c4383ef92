"""Tests for displacement.camera: projection, frustum, pixel footprint and rays."""

import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from displacement.camera import RASTER_LIMIT, Camera


def front_camera(**kw):
    args = dict(position=(0.0, 0.0, 5.0), look_at=(0.0, 0.0, 0.0), up=(0.0, 1.0, 0.0),
                fov_y_deg=90.0, width=200, height=100)
    args.update(kw)
    return Camera(**args)


def test_project_pinhole_by_hand():
    # fov 90: focal = (100 / 2) / tan(45 deg) = 50 px per unit of x / depth
    cam = front_camera()
    pts = np.array([[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [1.0, 1.0, -5.0]])
    xy, depth = cam.project(pts)
    np.testing.assert_allclose(depth, [5.0, 5.0, 5.0, 10.0])
    # image centre (100, 50); +x right, +y up = raster y down
    np.testing.assert_allclose(xy, [[100.0, 50.0], [110.0, 50.0], [100.0, 40.0], [105.0, 45.0]],
                               atol=1e-12)


def test_raster_origin_is_top_left_corner():
    cam = front_camera()
    # the top-left image corner: x / depth = -width/2 / focal, y / depth = height/2 / focal
    xy, _ = cam.project(np.array([[-2.0 * 5.0 * 100 / 100, 1.0 * 5.0, 0.0]]))
    np.testing.assert_allclose(xy, [[0.0, 0.0]], atol=1e-12)


def test_project_orthographic_by_hand():
    cam = front_camera(ortho_height=4.0)     # 100 px / 4 units = 25 px per unit
    xy, depth = cam.project(np.array([[1.0, -1.0, 0.0], [0.0, 0.0, 7.0]]))
    np.testing.assert_allclose(xy, [[125.0, 75.0], [100.0, 50.0]])
    np.testing.assert_allclose(depth, [5.0, -2.0])
    np.testing.assert_allclose(cam.pixel_size_at(np.zeros((3, 3))), 0.04)
    assert cam.in_frustum(np.array([[0.0, 0.0, 7.0]])).tolist() == [False]  # behind


def test_behind_camera_is_finite_and_outside():
    cam = front_camera()
    pts = np.array([[0.0, 0.0, 5.0], [1.0, 2.0, 5.0], [3.0, 1.0, 9.0], [1e-30, 0.0, 5.0]])
    with np.errstate(all="raise"):
        xy, depth = cam.project(pts)
        size = cam.pixel_size_at(pts)
        scale = cam.raster_scale(pts)
    assert np.all(np.isfinite(xy)) and np.all(np.abs(xy) <= RASTER_LIMIT)
    assert np.all(depth <= 0.0)
    assert not cam.in_frustum(pts).any()
    assert np.all(np.isfinite(size)) and np.all(size > 0)
    assert np.all(np.isfinite(scale)) and np.all(scale > 0)


def test_pixel_size_formula():
    cam = front_camera(fov_y_deg=40.0)
    pts = np.array([[0.0, 0.0, 0.0], [3.0, -1.0, -10.0]])
    expected = 2.0 * np.array([5.0, 15.0]) * math.tan(math.radians(20.0)) / 100
    np.testing.assert_allclose(cam.pixel_size_at(pts), expected, rtol=1e-14)


def test_in_frustum_margin():
    cam = front_camera()
    # 2 px left of the image edge: x_raster = -2
    p = np.array([[-(100 + 2) / 50 * 5.0, 0.0, 0.0]])
    assert not cam.in_frustum(p)[0]
    assert cam.in_frustum(p, margin_px=3.0)[0]


@settings(max_examples=40)
@given(st.floats(-0.49, 0.49), st.floats(-0.49, 0.49), st.floats(0.5, 50.0),
       st.floats(10.0, 150.0))
def test_raster_scale_bounds_the_projection_jacobian(a, b, depth, fov):
    cam = Camera(position=(0.3, -0.2, 1.0), look_at=(1.0, 0.5, -2.0), up=(0.1, 1.0, 0.0),
                 fov_y_deg=fov, width=64, height=48)
    # a point inside the image at the given depth
    o, d = cam.generate_rays(np.array([32 + 64 * a]), np.array([24 + 48 * b]))
    p = o + d * depth
    s = cam.raster_scale(p)[0]
    assert s >= 1.0 / cam.pixel_size_at(p)[0] * (1 - 1e-12)
    # finite-difference Jacobian in all directions: |J e| <= s (to first order)
    h = 1e-6 * depth
    x0, _ = cam.project(p)
    rng = np.random.default_rng(0)
    e = rng.normal(size=(64, 3))
    e /= np.linalg.norm(e, axis=1, keepdims=True)
    x1, _ = cam.project(p + h * e)
    ratio = np.linalg.norm(x1 - x0, axis=1) / h
    assert ratio.max() <= s * (1 + 1e-4)
    assert ratio.max() >= 0.9 * s          # and it is attained (largest singular value)


@settings(max_examples=40)
@given(st.floats(0.0, 64.0), st.floats(0.0, 48.0), st.floats(0.1, 100.0),
       st.booleans())
def test_rays_round_trip(px, py, t, ortho):
    cam = Camera(position=(1.0, 2.0, 3.0), look_at=(0.0, 0.5, -1.0), up=(0.0, 1.0, 0.0),
                 fov_y_deg=60.0, width=64, height=48, ortho_height=3.0 if ortho else None)
    o, d = cam.generate_rays(np.array([px]), np.array([py]))
    np.testing.assert_allclose(np.linalg.norm(d, axis=1), 1.0, rtol=1e-14)
    xy, depth = cam.project(o + t * d)
    assert depth[0] > 0
    np.testing.assert_allclose(xy[0], [px, py], atol=1e-9 * max(1.0, t))


def test_pixel_centre_ray_points_along_view():
    cam = front_camera(width=2, height=2)
    o, d = cam.generate_rays(np.array([1.0]), np.array([1.0]))
    np.testing.assert_allclose(d, [[0.0, 0.0, -1.0]], atol=1e-15)
    np.testing.assert_allclose(o, [[0.0, 0.0, 5.0]])


def test_ortho_rays_are_parallel():
    cam = front_camera(ortho_height=2.0)
    o, d = cam.generate_rays(np.array([0.0, 200.0]), np.array([0.0, 100.0]))
    np.testing.assert_allclose(d, [[0, 0, -1.0], [0, 0, -1.0]])
    np.testing.assert_allclose(o, [[-2.0, 1.0, 5.0], [2.0, -1.0, 5.0]])


def test_grazing_and_huge_coordinates_stay_finite():
    cam = front_camera()
    pts = np.array([[1e12, 0.0, 5.0 - 1e-9], [0.0, 1e300, 0.0], [1e-300, 0.0, 4.999999]])
    xy, depth = cam.project(pts)
    assert np.all(np.isfinite(xy)) and np.all(np.isfinite(depth))
    assert np.all(np.isfinite(cam.raster_scale(pts)))


@pytest.mark.parametrize("kw, message", [
    (dict(look_at=(0.0, 0.0, 5.0)), "zero length"),
    (dict(up=(0.0, 0.0, 1.0)), "parallel"),
    (dict(fov_y_deg=180.0), "fov_y_deg"),
    (dict(fov_y_deg=0.0), "fov_y_deg"),
    (dict(width=0), "width and height"),
    (dict(height=2.5), "width and height"),
    (dict(ortho_height=-1.0), "ortho_height"),
    (dict(position=(np.nan, 0.0, 0.0)), "finite"),
])
def test_bad_arguments(kw, message):
    with pytest.raises(ValueError, match=message):
        front_camera(**kw)


def test_generate_rays_shape_mismatch():
    with pytest.raises(ValueError, match="same shape"):
        front_camera().generate_rays(np.zeros(3), np.zeros(2))
