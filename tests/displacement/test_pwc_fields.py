"""Chapter 15: pw-curve fields (Listings 15.6-15.8, 15.12-15.14, 15.19-15.20)."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from hypothesis.extra.numpy import arrays

import pwc
from displacement.fields import FIELDS
from displacement.pwc_fields import (
    displace_to_angular_point,
    displace_to_point,
    displace_to_pwc_point,
    displace_with_pwc,
    double_pwc,
    normalized_grid_count,
    pwc_angular_displace,
    texture_scale,
    y_rotation_3,
)
from displacement.surfaces import Cylinder, Torus, UnitSquare, UVSphere

PROFILES = Path(__file__).resolve().parents[2] / "profiles"
SQUARE = UnitSquare()
SEGMENTS = pwc.load(PROFILES / "segments.pwc")
ARC = pwc.load(PROFILES / "right_angle_arc.pwc")
CORINTHIAN = pwc.load(PROFILES / "corinthian.pwc")
DORIC = pwc.load(PROFILES / "doric_flutes.pwc")
CIRCLE = pwc.compile_text("1 0\n0 1 :angle 90\n-1 0 :angle 90\n0 -1 :angle 90\n1 0 :angle 90",
                          normalize=False)


def grid_state(u, v):
    u, v = np.broadcast_arrays(np.asarray(u, float), np.asarray(v, float))
    return SQUARE.state_at_uv(np.stack([u.ravel(), v.ravel()], 1))


def test_listing_15_3_values():
    # the compiled curve behind these tests is the Handbook's
    assert SEGMENTS.length == pytest.approx(2.00056, abs=1e-5)
    listing = [0.0, 0.26243, 0.41238, 0.51414, 0.86404, 1.0]
    np.testing.assert_allclose(SEGMENTS.t, listing, atol=1e-5)


def test_displace_to_point_hand_value():
    # Listing 15.6: x * normal + (y - uv_position) * tangent
    out = displace_to_point(np.array([[0.3, 0.9]]), np.array([0.4]),
                            np.array([[1.0, 0.0, 0.0]]), np.array([[0.0, 0.0, 2.0]]))
    np.testing.assert_allclose(out, [[0.5, 0.0, 0.6]])


def test_along_v_lands_on_the_pw_points():
    # at v = t_i the displaced point of the unit square is (u, pt.y, pt.x)
    field = displace_with_pwc(SEGMENTS, "along_v")
    for u in (0.0, 0.37, 1.0):
        s = grid_state(u, SEGMENTS.t)
        p = s.position + field(s)
        expected = np.stack([np.full(len(SEGMENTS.t), u), SEGMENTS.pt[:, 1], SEGMENTS.pt[:, 0]], 1)
        np.testing.assert_allclose(p, expected, atol=1e-12)
    assert field.uv_knots[0] is None
    np.testing.assert_array_equal(field.uv_knots[1], SEGMENTS.t)


def test_along_u_lands_on_the_pw_points():
    field = displace_with_pwc(ARC, "along_u")
    s = grid_state(ARC.t, 0.6)
    p = s.position + field(s)
    expected = np.stack([ARC.pt[:, 1], np.full(len(ARC.t), 0.6), ARC.pt[:, 0]], 1)
    np.testing.assert_allclose(p, expected, atol=1e-12)
    assert field.uv_knots[1] is None


def test_between_knots_the_point_is_on_the_curve():
    field = displace_with_pwc(ARC, "along_v")
    v = np.random.default_rng(14).uniform(0, 1, 200)
    s = grid_state(0.5, v)
    p = s.position + field(s)
    np.testing.assert_allclose(p[:, [2, 1]], ARC.evaluate(v), atol=1e-12)


def test_outside_unit_interval_clamps_to_the_ends():
    field = displace_with_pwc(SEGMENTS)
    s = grid_state(0.2, [-0.5, -1e-300, 1.0, 1.5, 1e300])
    p = s.position + field(s)
    first, last = SEGMENTS.pt[0], SEGMENTS.pt[-1]
    np.testing.assert_allclose(p[:2, [2, 1]], [first, first], atol=1e-12)
    np.testing.assert_allclose(p[2:4, [2, 1]], [last, last], atol=1e-12)
    # far outside the texture: finite (the tangent offset is large, not NaN)
    assert np.all(np.isfinite(p))


def test_repeat():
    v = np.linspace(0, 1, 41)[:-1]
    s = grid_state(0.3, v)
    once = displace_with_pwc(SEGMENTS, repeat=1)(s)
    np.testing.assert_allclose(once, displace_with_pwc(SEGMENTS)(s), atol=1e-12)
    # repeat 3: a third-size copy of the curve in each third of v
    field = displace_with_pwc(SEGMENTS, repeat=3)
    p = s.position + field(s)
    k = np.floor(3 * v)
    local = SEGMENTS.evaluate(3 * v - k) / 3 + np.stack([np.zeros_like(k), k / 3], 1)
    np.testing.assert_allclose(p[:, [2, 1]], local, atol=1e-12)
    np.testing.assert_allclose(field.uv_knots[1],
                               np.unique(np.concatenate([(SEGMENTS.t + j) / 3 for j in range(3)])))
    big = displace_with_pwc(SEGMENTS, repeat=1000)
    s = grid_state(0.3, np.linspace(-1, 2, 30001))
    assert np.all(np.isfinite(big(s)))
    assert len(big.uv_knots[1]) == 5 * 1000 + 1
    with pytest.raises(ValueError, match="repeat"):
        displace_with_pwc(SEGMENTS, repeat=0)


def test_curve_from_path_and_bad_input():
    s = grid_state(0.5, SEGMENTS.t)
    np.testing.assert_allclose(displace_with_pwc(PROFILES / "segments.pwc")(s),
                               displace_with_pwc(SEGMENTS)(s))
    with pytest.raises(ValueError, match="pwc.Curve"):
        displace_with_pwc(np.zeros((3, 2)))
    with pytest.raises(ValueError, match="along_u"):
        displace_with_pwc(SEGMENTS, "sideways")


def test_y_rotation_3_is_the_right_handed_turn_about_y():
    angles = np.array([0.0, math.pi / 2, 1.0, -2.5])
    m = y_rotation_3(angles)
    assert m.shape == (4, 3, 3)
    np.testing.assert_allclose(np.einsum("nij,nkj->nik", m, m), np.tile(np.eye(3), (4, 1, 1)),
                               atol=1e-15)
    np.testing.assert_allclose(np.linalg.det(m), 1.0)
    # MDL: p * M with M's nine arguments as columns; x turns towards -z
    np.testing.assert_allclose(np.array([1.0, 0.0, 0.0]) @ m[1], [0.0, 0.0, -1.0], atol=1e-15)
    np.testing.assert_allclose(np.array([0.0, 0.0, 1.0]) @ m[1], [1.0, 0.0, 0.0], atol=1e-15)
    # the Handbook's argument list, read as columns
    c, s = math.cos(1.0), math.sin(1.0)
    np.testing.assert_allclose(m[2][:, 0], [c, 0, s])
    np.testing.assert_allclose(m[2][:, 2], [-s, 0, c])
    # Listing 15.13's p *= y_rotation_3(angle), row by row
    rng = np.random.default_rng(20)
    pts, t = rng.normal(size=(50, 2)), rng.uniform(-2, 2, 50)
    p3 = np.stack([pts[:, 0], pts[:, 1], np.zeros(50)], 1)
    rotated = np.einsum("ni,nij->nj", p3, y_rotation_3(2 * math.pi * t))
    np.testing.assert_allclose(displace_to_angular_point(pts, t, np.zeros((50, 3))), rotated,
                               atol=1e-14)


def test_angular_point_hand_value():
    # pw point (0.5, 0.25), t = 1/8 (45 degrees), radius 0.25: distance 0.75 from y
    out = displace_to_angular_point(np.array([[0.5, 0.25]]), np.array([0.125]),
                                    np.array([[1.0, 1.0, 1.0]]), radius=0.25)
    h = 0.75 / math.sqrt(2)
    np.testing.assert_allclose(out, [[h - 1.0, 0.25 - 1.0, -h - 1.0]], atol=1e-15)


def test_pwc_angular_displace_is_a_solid_of_revolution():
    field = pwc_angular_displace(CORINTHIAN, "along_v")
    rng = np.random.default_rng(15)
    uv = rng.uniform(0, 1, (400, 2))
    s = SQUARE.state_at_uv(uv)
    p = s.position + field(s)
    pt = CORINTHIAN.evaluate(uv[:, 1])
    np.testing.assert_allclose(np.hypot(p[:, 0], p[:, 2]), np.abs(pt[:, 0]), atol=1e-12)
    np.testing.assert_allclose(p[:, 1], pt[:, 1], atol=1e-12)
    azimuth = np.mod(np.arctan2(-p[:, 2], p[:, 0]), 2 * math.pi)      # u turns x towards -z
    big = pt[:, 0] > 1e-6
    np.testing.assert_allclose(azimuth[big], 2 * math.pi * uv[big, 0], atol=1e-9)
    # the displaced point does not depend on the base surface (state::position() removed)
    for surface in (UVSphere(2.0), Torus(1.0, 0.2), Cylinder()):
        other = surface.state_at_uv(uv)
        np.testing.assert_allclose(other.position + field(other), p, atol=1e-12)
    assert field.uv_knots[0] is None
    np.testing.assert_array_equal(field.uv_knots[1], CORINTHIAN.t)
    assert FIELDS["radial_pwc"] is pwc_angular_displace


def test_angular_seam_closes_exactly_and_along_u():
    field = pwc_angular_displace(CORINTHIAN)
    v = np.linspace(0, 1, 33)
    a, b = grid_state(0.0, v), grid_state(1.0, v)
    # the rotated points are bit-identical at u = 0 and u = 1; adding back the base
    # position that Listing 15.13 subtracted leaves at most an ulp of difference
    pt = CORINTHIAN.evaluate(v)
    zero = np.zeros((len(v), 3))
    np.testing.assert_array_equal(displace_to_angular_point(pt, np.zeros_like(v), zero),
                                  displace_to_angular_point(pt, np.ones_like(v), zero))
    np.testing.assert_allclose(a.position + field(a), b.position + field(b), rtol=0, atol=1e-15)
    along_u = pwc_angular_displace(CORINTHIAN, "along_u")
    s, swapped = grid_state(0.3, v), grid_state(v, 0.3)
    np.testing.assert_allclose(swapped.position + along_u(swapped), s.position + field(s),
                               atol=1e-12)
    np.testing.assert_array_equal(along_u.uv_knots[0], CORINTHIAN.t)
    # Listing 15.13's radius
    shifted = pwc_angular_displace(CORINTHIAN, radius=0.25)
    p = s.position + shifted(s)
    np.testing.assert_allclose(np.hypot(p[:, 0], p[:, 2]),
                               CORINTHIAN.evaluate(v)[:, 0] + 0.25, atol=1e-12)


def test_double_pwc_with_a_circle_sweep_is_a_revolution():
    rng = np.random.default_rng(16)
    s = SQUARE.state_at_uv(rng.uniform(0, 1, (300, 2)))
    swept = double_pwc(CORINTHIAN, CIRCLE, radius_offset=0.25)
    revolved = pwc_angular_displace(CORINTHIAN, radius=0.25)
    np.testing.assert_allclose(swept(s), revolved(s), atol=1e-12)
    np.testing.assert_array_equal(swept.uv_knots[0], CIRCLE.t)
    np.testing.assert_array_equal(swept.uv_knots[1], CORINTHIAN.t)


def test_double_pwc_doric_radius_follows_the_sweep():
    # Listing 15.21: corinthian profile, doric flutes, radius_offset 0.25
    field = double_pwc(CORINTHIAN, DORIC, radius_offset=0.25)
    rng = np.random.default_rng(17)
    uv = rng.uniform(0, 1, (300, 2))
    s = SQUARE.state_at_uv(uv)
    p = s.position + field(s)
    sweep_length = np.linalg.norm(DORIC.evaluate(uv[:, 0]), axis=1)
    expected = (CORINTHIAN.evaluate(uv[:, 1])[:, 0] + 0.25) * sweep_length
    np.testing.assert_allclose(np.hypot(p[:, 0], p[:, 2]), expected, atol=1e-12)
    np.testing.assert_allclose(p[:, 1], CORINTHIAN.evaluate(uv[:, 1])[:, 1], atol=1e-12)
    # at the flute edges (the sweep's knots) the sweep point is on the unit circle
    edges = grid_state(DORIC.t, 0.5)
    q = edges.position + field(edges)
    np.testing.assert_allclose(np.hypot(q[:, 0], q[:, 2]), CORINTHIAN.evaluate([0.5])[0, 0] + 0.25,
                               atol=1e-9)
    # and the pure function of Listing 15.19
    out = displace_to_pwc_point(np.array([[0.5, 0.1]]), np.array([0.0]), DORIC,
                                np.zeros((1, 3)), 0.5)
    np.testing.assert_allclose(out, [[1.0, 0.1, 0.0]], atol=1e-12)


def test_texture_length_compensation():
    ornament_1 = pwc.load(PROFILES / "ornament_1.pwc")
    L = ornament_1.length
    np.testing.assert_allclose(normalized_grid_count(50, ornament_1), [50, 50 * L])  # 15.9
    np.testing.assert_allclose(normalized_grid_count((10, 20), ornament_1, "along_u"), [10 * L, 20])
    np.testing.assert_allclose(texture_scale(ornament_1), [1.0, L])          # Listing 15.11


def test_registry():
    for name in ("displace_with_pwc", "pwc_angular_displace", "double_pwc"):
        assert name in FIELDS
    s = grid_state(0.5, 0.5)
    np.testing.assert_allclose(FIELDS["double_pwc"](CORINTHIAN, DORIC)(s),
                               double_pwc(CORINTHIAN, DORIC)(s))


CURVES = [SEGMENTS, ARC, CORINTHIAN, DORIC]


@settings(max_examples=40)
@given(arrays(np.float64, (10, 2), elements=st.floats(-1e6, 1e6)), st.sampled_from(CURVES),
       st.sampled_from(["along_u", "along_v"]), st.sampled_from([None, 1.0, 3.0, 1000.0]))
def test_property_finite(uv, curve, direction, repeat):
    fields = [displace_with_pwc(curve, direction, repeat), pwc_angular_displace(curve, direction),
              double_pwc(curve, DORIC, 0.25)]
    for surface in (SQUARE, UVSphere(), Torus()):
        state = surface.state_at_uv(uv)
        for field in fields:
            assert np.all(np.isfinite(field(state)))
