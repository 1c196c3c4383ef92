"""Chapter 14.3: the bubble profile (Listings 14.16-14.21)."""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from hypothesis.extra.numpy import arrays

from displacement.bubble import (
    BubbleArgs,
    bubble,
    bubble_point,
    displace_with_bubble,
    get_bubble_args,
    normalize_grid,
)
from displacement.fields import FIELDS
from displacement.surfaces import Torus, UnitSquare, UVSphere

SQUARE = UnitSquare()


def row(values, index=0, other=0.4):
    values = np.asarray(values, dtype=np.float64)
    uv = np.stack([values, np.full_like(values, other)], 1)
    return SQUARE.state_at_uv(uv if index == 0 else uv[:, ::-1])


def test_get_bubble_args_hand_values():
    # radius 0.35, height 0 (Figure 14.20): a semicircle of chord 0.7 on the unit base
    ba = get_bubble_args(0.35, 0.0)
    total = math.pi * 0.35 + 0.3
    assert ba.radius == 0.35 and ba.height == 0.0
    assert ba.angle_start == pytest.approx(2 * math.pi)          # 3 pi/2 + pi/2
    assert ba.angle_end == pytest.approx(3 * math.pi)            # 3 pi/2 - pi/2 + 2 pi
    assert ba.total_length == pytest.approx(total)
    assert ba.bubble_start == pytest.approx(0.15 / total)
    assert ba.bubble_end == pytest.approx((0.15 + math.pi * 0.35) / total)
    # radius 0.4, height 0.2 (Figure 14.21): half_angle = acos(0.5) = 60 degrees
    ba = get_bubble_args(0.4, 0.2)
    half = math.pi / 3
    chord = 0.8 * math.sin(half)
    arc = (2 * math.pi - 2 * half) * 0.4
    assert ba.total_length == pytest.approx(arc + 1 - chord)
    assert ba.bubble_start == pytest.approx((1 - chord) / 2 / (arc + 1 - chord))


@pytest.mark.parametrize("radius,height,match", [
    (0.25, 0.3, "outside \\[-radius, radius\\]"),
    (0.25, -0.25000001, "outside"),
    (0.0, 0.0, "radius must be"),
    (-0.5, 0.0, "radius must be"),
    (0.6, 0.0, "chord"),
    (np.nan, 0.0, "radius must be"),
    (0.3, np.inf, "outside"),
])
def test_bad_bubbles_raise(radius, height, match):
    with pytest.raises(ValueError, match=match):
        get_bubble_args(radius, height)


def test_bubble_point_semicircle():
    ba = get_bubble_args(0.5, 0.0)
    f = np.linspace(0.0, 1.0, 9)
    p = bubble_point(f, 1.0, ba)
    angle = 3 * math.pi - math.pi * f          # fit(f, 0, 1, angle_end, angle_start)
    expected = np.stack([0.5 + 0.5 * np.cos(angle), 0.5 * np.sin(angle)], 1)
    expected[-1] = [0.0, 0.0]                  # frac(1) = 0: the start again
    np.testing.assert_allclose(p, expected, atol=1e-15)


@pytest.mark.parametrize("radius,height", [(0.35, 0.0), (0.4, 0.2), (0.45, 0.42), (0.4, -0.2),
                                           (0.2, 0.2), (0.2, -0.2), (0.5, 0.0)])
def test_profile_is_arc_length_parametrised(radius, height):
    # equal steps of the fraction are equal steps along the profile: total_length * df
    ba = get_bubble_args(radius, height)
    f = np.linspace(0.0, 1.0 - 1e-12, 4001)
    p = bubble_point(f, 1.0, ba)
    steps = np.linalg.norm(np.diff(p, axis=0), axis=1)
    df = f[1] - f[0]
    # a step across a corner (base meets arc) is a chord of the bent path: skip those;
    # chords of the arc are shorter than the arc by at most (r dphi)^3 / (24 r^2)
    straddles = np.zeros(len(steps), dtype=bool)
    for knot in (ba.bubble_start, ba.bubble_end):
        straddles |= (f[:-1] < knot) & (f[1:] > knot)
    np.testing.assert_allclose(steps[~straddles], ba.total_length * df, rtol=1e-5)
    # continuous where the arc meets the base (inside (0, 1): frac wraps at the ends)
    for knot in (k for k in (ba.bubble_start, ba.bubble_end) if 1e-12 < k < 1 - 1e-12):
        a, b = bubble_point(np.array([knot - 1e-13, knot + 1e-13]), 1.0, ba)
        np.testing.assert_allclose(a, b, atol=1e-11)
    np.testing.assert_allclose(p[0], [0.0, 0.0])
    np.testing.assert_allclose(p[-1], [1.0, 0.0], atol=1e-11)


def test_height_equal_to_plus_radius_is_a_full_circle():
    r = 0.2
    ba = get_bubble_args(r, r)
    assert ba.total_length == pytest.approx(2 * math.pi * r + 1)
    assert ba.bubble_start == pytest.approx(0.5 / ba.total_length)
    top = bubble_point(np.array([(ba.bubble_start + ba.bubble_end) / 2]), 1.0, ba)
    np.testing.assert_allclose(top, [[0.5, 2 * r]], atol=1e-15)
    field = bubble(r, r, (1.0, 0.0))
    d = field(row(np.linspace(0, 1, 101)))
    assert np.all(np.isfinite(d))


def test_height_equal_to_minus_radius_is_flat():
    ba = get_bubble_args(0.3, -0.3)
    assert ba.bubble_start == pytest.approx(0.5) and ba.bubble_end == pytest.approx(0.5)
    f = np.linspace(0, 1, 101)
    s = row(f)
    d = bubble(0.3, -0.3, (1.0, 0.0))(s)
    assert np.all(np.isfinite(d))
    np.testing.assert_allclose(d, 0.0, atol=1e-15)            # no bubble: the base itself


def test_displace_with_bubble_unit_square_hand_value():
    # radius 0.5, height 0: u = 0.25 is a quarter of the semicircle, at angle 3 pi / 4
    field = bubble(0.5, 0.0, (1.0, 0.0))
    s = row([0.25, 0.5, 0.0, 1.0, -0.75, 1.25])
    p = s.position + field(s)
    x = 0.5 + 0.5 * math.cos(2.75 * math.pi)
    z = 0.5 * math.sin(2.75 * math.pi)
    np.testing.assert_allclose(p[0], [x, 0.4, z], atol=1e-15)
    np.testing.assert_allclose(p[1], [0.5, 0.4, 0.5], atol=1e-15)
    np.testing.assert_allclose(field(s)[2:4], 0.0, atol=1e-15)  # uv exactly 0 and 1
    np.testing.assert_allclose(field(s)[4], field(s)[0], atol=1e-15)  # frac(-0.75) = 0.25
    np.testing.assert_allclose(field(s)[5], field(s)[0], atol=1e-15)


def test_direction_selection():
    ba = get_bubble_args(0.4, 0.2)
    s = SQUARE.state_at_uv(np.random.default_rng(11).uniform(0, 1, (30, 2)))
    zero = displace_with_bubble((0.0, 0.0), ba)
    np.testing.assert_array_equal(zero(s), np.zeros((30, 3)))
    assert zero.uv_knots == (None, None)
    np.testing.assert_array_equal(displace_with_bubble((-1.0, 0.0), ba)(s), np.zeros((30, 3)))
    in_v = displace_with_bubble((0.0, 2.0), ba)
    in_u = displace_with_bubble((2.0, 5.0), ba)                # u wins when repeat.u > 0
    assert in_v.uv_knots[0] is None and in_u.uv_knots[1] is None
    swapped = SQUARE.state_at_uv(s.uv[:, ::-1])
    du, dv = in_u(s), in_v(swapped)
    np.testing.assert_allclose(dv[:, [1, 0, 2]], du, atol=1e-15)
    # Listing 14.21's default repeat float2(1.0) displaces along u
    assert bubble().uv_knots[1] is None


def test_repeat_two_is_two_half_size_bubbles():
    ba = get_bubble_args(0.4, 0.2)
    f = np.linspace(0.0, 0.5, 51)[:-1]
    once = bubble_point(2 * f, 1.0, ba)
    twice = bubble_point(f, 2.0, ba)
    second = bubble_point(f + 0.5, 2.0, ba)
    np.testing.assert_allclose(twice, once / 2, atol=1e-15)
    np.testing.assert_allclose(second, once / 2 + [0.5, 0.0], atol=1e-15)
    knots = bubble(0.4, 0.2, (2.0, 0.0)).uv_knots[0]
    np.testing.assert_allclose(
        knots, np.sort([0.0, ba.bubble_start / 2, ba.bubble_end / 2, 0.5,
                        0.5 + ba.bubble_start / 2, 0.5 + ba.bubble_end / 2, 1.0]))


def test_repeat_thousand():
    field = bubble(0.4, 0.2, (1000.0, 0.0))
    u = np.linspace(0.0, 1.0, 10007)
    s = row(u)
    p = s.position + field(s)
    assert np.all(np.isfinite(p))
    assert np.max(p[:, 2]) <= (0.2 + 0.4) / 1000 + 1e-15       # bubble top / repeat
    assert len(field.uv_knots[0]) == 3 * 1000 + 1
    # every copy is the same shape: period 1/1000 in u
    a = field(row([0.1234]))
    b = field(row([0.1234 + 0.005]))
    np.testing.assert_allclose(a, b, atol=1e-12)


def test_normalize_grid_as_printed():
    ba = get_bubble_args(0.45, 0.42)
    L = ba.total_length
    np.testing.assert_allclose(normalize_grid((8.0, 8.0), (3.0, 0.0), ba), [8 * L, 8 * L])
    np.testing.assert_allclose(normalize_grid((8.0, 8.0), (1.0, 0.0), ba), [8.0, 8 * L])
    np.testing.assert_allclose(normalize_grid(4.0, 1.0, ba), [4.0, 4.0])
    np.testing.assert_allclose(normalize_grid((8.0, 8.0), (3.0, 0.0), ba, False), [8.0, 8.0])


def test_registry_and_types():
    assert FIELDS["bubble"] is bubble and FIELDS["displace_with_bubble"] is displace_with_bubble
    assert isinstance(get_bubble_args(0.25, 0.25), BubbleArgs)
    with pytest.raises(ValueError, match="BubbleArgs"):
        displace_with_bubble((1.0, 0.0), (0.25, 0.25))
    with pytest.raises(ValueError, match="float2"):
        displace_with_bubble((1.0, 0.0, 0.0), get_bubble_args(0.25, 0.25))


@settings(max_examples=60)
@given(
    st.floats(0.01, 0.5),
    st.floats(-1.0, 1.0),
    st.floats(0.01, 1000.0),
    arrays(np.float64, (12, 2), elements=st.floats(-1e6, 1e6)),
)
def test_property_finite(radius, height_fraction, repeat, uv):
    height = radius * height_fraction
    try:
        ba = get_bubble_args(radius, height)
    except ValueError as error:                      # only the chord-too-long case
        assert "chord" in str(error)
        return
    for surface in (SQUARE, UVSphere(), Torus()):
        d = displace_with_bubble((repeat, 0.0), ba)(surface.state_at_uv(uv))
        assert np.all(np.isfinite(d))
