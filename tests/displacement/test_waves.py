"""Chapter 12: fit, sinusoid, uv_wave and the waves displacement fields."""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from hypothesis.extra.numpy import arrays

from displacement.fields import FIELDS
from displacement.surfaces import Torus, UnitSquare, UVSphere
from displacement.waves import (
    fit,
    sinusoid,
    sinusoid2,
    uv_wave,
    waves,
    waves_as_displacement,
    waves_tint,
)

SQUARE = UnitSquare()


def test_fit_hand_values():
    # Listing 12.1: scale = (v - old_min) / (old_max - old_min)
    assert fit(0.5, 0.0, 1.0, 10.0, 20.0) == 15.0
    assert fit(-1.0, -1.0, 1.0, 0.0, 0.4) == 0.0
    assert fit(1.0, -1.0, 1.0, 0.0, 0.4) == pytest.approx(0.4)
    assert fit(3.0, 1.0, 2.0, 0.0, 1.0) == 2.0            # extrapolates, no clamp
    assert fit(0.25, 0.0, 1.0, 1.0, 0.0) == 0.75          # reversed new range
    np.testing.assert_allclose(
        fit(np.array([0.0, 1.0]), 0.0, 1.0, np.array([1.0, 2.0]), np.array([3.0, 6.0])), [1.0, 6.0]
    )


def test_fit_empty_range_raises():
    with pytest.raises(ValueError, match="old_min == old_max"):
        fit(0.5, 1.0, 1.0, 0.0, 1.0)
    with pytest.raises(ValueError, match="old_min == old_max"):
        fit(0.5, np.array([0.0, 1.0]), np.array([1.0, 1.0]), 0.0, 1.0)


def test_sinusoid_quarter_periods_and_frac():
    f = np.array([0.0, 0.25, 0.5, 0.75, 1.0, 1.25, -0.25, -0.75, -1.0])
    expected = np.array([0.0, 1.0, 0.0, -1.0, 0.0, 1.0, -1.0, 1.0, 0.0])
    np.testing.assert_allclose(sinusoid(f), expected, atol=1e-15)
    # minval/maxval: fit from [-1, 1]
    np.testing.assert_allclose(sinusoid(f, 1.0, 2.0, 4.0), 3.0 + expected, atol=1e-15)
    # frequency: periods inside one unit of f
    np.testing.assert_allclose(sinusoid(np.array([0.125, 0.375]), 2.0), [1.0, -1.0], atol=1e-15)
    # frequency zero: sin(0) = 0 fitted to the middle of the range
    assert sinusoid(0.3, 0.0, 0.0, 1.0) == 0.5
    assert sinusoid2(0.3, 0.0, 0.0, 1.0) == 0.0           # Listing 12.6 returns 0.0
    np.testing.assert_allclose(sinusoid2(0.3, 2.0, 0.0, 1.0), sinusoid(0.3, 2.0, 0.0, 1.0))


def test_sinusoid_extremes_are_finite():
    f = np.array([1e300, -1e300, 1e-300, -1e-300, 2.0**52 + 0.5])
    out = sinusoid(f, 1e6)
    assert np.all(np.isfinite(out)) and np.all(np.abs(out) <= 1.0)


def test_uv_wave_sums_components():
    uv = np.array([[0.25, 0.0], [0.0, 0.125], [0.25, 0.125]])
    out = uv_wave(uv, (1.0, 2.0), (0.0, -1.0), (1.0, 1.0))
    # u (frequency 1, range [0, 1]): sin(pi/2) -> 1, sin(0) -> 0.5;
    # v (frequency 2, range [-1, 1]): sin(0) -> 0, sin(pi/2) -> 1
    np.testing.assert_allclose(out, [1.0 + 0.0, 0.5 + 1.0, 1.0 + 1.0], atol=1e-15)
    state = SQUARE.state_at_uv(uv)
    np.testing.assert_array_equal(uv_wave(state, (1.0, 2.0), (0.0, -1.0), 1.0), out)
    with pytest.raises(ValueError, match="float2"):
        uv_wave(uv, (1.0, 2.0, 3.0))


def test_waves_as_displacement_figure_12_4():
    # Figure 12.4: frequency (0, 4), distance (0, 0.1): displacement along +z on the
    # unit square, 0.1 * sin(8 pi v), the u component switched off.
    field = waves_as_displacement(frequency=(0.0, 4.0), distance=(0.0, 0.1))
    v = np.array([0.0, 1 / 16, 1 / 8, 3 / 16, 0.5, 1.0])
    uv = np.stack([np.full_like(v, 0.37), v], 1)
    d = field(SQUARE.state_at_uv(uv))
    np.testing.assert_allclose(d[:, :2], 0.0, atol=0)
    np.testing.assert_allclose(d[:, 2], 0.1 * np.sin(8 * math.pi * v), atol=1e-15)


def test_waves_along_curved_normals_and_not_normalized():
    field = waves_as_displacement(frequency=(4.0, 4.0), distance=(0.075, 0.075))
    rng = np.random.default_rng(7)
    state = UVSphere(2.0).state_at_uv(rng.uniform(0, 1, (200, 2)))
    d = field(state)
    amount = uv_wave(state.uv, (4.0, 4.0), -0.075, 0.075)
    np.testing.assert_allclose(d, amount[:, None] * state.normal, atol=1e-15)
    assert np.all(np.linalg.norm(d, axis=1) <= 0.15 + 1e-15)
    assert np.linalg.norm(d, axis=1).min() < 0.1               # lengths vary


def test_waves_switch_and_defaults():
    uv = np.random.default_rng(8).uniform(-2, 2, (50, 2))
    state = Torus().state_at_uv(uv)
    on = waves(distance=(0.02, 0.02), frequency=(10.0, 10.0), use_displacement=True)
    off = waves(distance=(0.02, 0.02), frequency=(10.0, 10.0), use_displacement=False)
    ref = waves_as_displacement((10.0, 10.0), (0.02, 0.02))
    np.testing.assert_array_equal(on(state), ref(state))
    np.testing.assert_array_equal(off(state), np.zeros((50, 3)))
    assert off.uv_knots == (None, None)
    # Handbook defaults: frequency float2(1.0), distance float2(0.1)
    np.testing.assert_array_equal(waves()(state), waves_as_displacement(1.0, 0.1)(state))
    assert FIELDS["waves"] is waves and FIELDS["waves_as_displacement"] is waves_as_displacement


def test_waves_tint():
    uv = np.array([[0.25, 0.25], [0.75, 0.75]])
    tint = np.array([0.6, 0.4, 0.0])
    np.testing.assert_array_equal(waves_tint(uv, tint, 1.0, True), [tint, tint])
    # uv_wave(frequency, 0.1, 0.5): 0.5 + 0.5 at the crests, 0.1 + 0.1 in the troughs
    np.testing.assert_allclose(waves_tint(uv, tint, 1.0, False), [tint * 1.0, tint * 0.2])


def test_uv_zero_and_one_agree():
    field = waves_as_displacement((3.0, 5.0), (0.1, 0.2))
    a = field(SQUARE.state_at_uv(np.array([[0.0, 0.0]])))
    b = field(SQUARE.state_at_uv(np.array([[1.0, 1.0]])))
    np.testing.assert_array_equal(a, b)                      # frac(1) = 0


@settings(max_examples=50)
@given(
    arrays(np.float64, (8, 2), elements=st.floats(-1e9, 1e9)),
    st.tuples(st.floats(0, 1e4), st.floats(0, 1e4)),
    st.tuples(st.floats(-10, 10), st.floats(-10, 10)),
)
def test_property_bounded_and_finite(uv, frequency, distance):
    field = waves_as_displacement(frequency, distance)
    d = field(UVSphere().state_at_uv(uv))
    assert np.all(np.isfinite(d))
    assert np.all(np.linalg.norm(d, axis=1) <= abs(distance[0]) + abs(distance[1]) + 1e-9)
