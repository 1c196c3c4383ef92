"""``::math`` at its edges: where MDL (or mathematics) defines a finite value, NaN and
infinity never escape; elsewhere the values are those of C's math library.

Property-based (hypothesis) over finite doubles of every magnitude, plus the named edge
cases of the module docstring of :mod:`mdl.mathlib`.
"""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from mdl import mathlib as M

finite = st.floats(allow_nan=False, allow_infinity=False)
moderate = st.floats(min_value=-1e150, max_value=1e150, allow_nan=False)
vec3 = st.tuples(finite, finite, finite)


def lanes(*xs):
    return np.array(xs, dtype=np.float64)


@given(vec3)
def test_length_and_normalize_of_any_finite_vector(v):
    a = lanes(v)
    n = M.length(a)
    assert np.isfinite(n).all() or max(map(abs, v)) > 1e307  # only a true overflow
    u = M.normalize(a)
    assert np.isfinite(u).all()
    norm = float(np.sqrt((u * u).sum()))
    assert norm == 0.0 if not any(v) else abs(norm - 1.0) < 1e-12


def test_length_does_not_overflow_or_underflow_in_between():
    assert M.length(lanes((3e200, 4e200, 0.0)))[0] == pytest.approx(5e200, rel=1e-15)
    assert M.length(lanes((3e-200, 4e-200, 0.0)))[0] == pytest.approx(5e-200, rel=1e-15)
    assert M.normalize(lanes((1e-310, 0.0, 0.0))).tolist() == [[1.0, 0.0, 0.0]]
    assert M.normalize(lanes((0.0, 0.0, 0.0))).tolist() == [[0.0, 0.0, 0.0]]
    assert M.distance(lanes((1e300, 0.0, 0.0)), lanes((-1e300, 0.0, 0.0))).tolist() == [2e300]


@given(finite, finite, finite)
def test_smoothstep_is_in_0_1_for_any_edges(a, b, x):
    s = M.smoothstep(lanes(a), lanes(b), lanes(x))
    assert np.isfinite(s).all() and 0.0 <= s[0] <= 1.0
    if a == b:
        assert s[0] == (0.0 if x < a else 1.0)


@given(finite)
def test_frac_is_in_0_1(x):
    f = M.frac(lanes(x))[0]
    assert 0.0 <= f <= 1.0
    assert f == x - math.floor(x)


@given(st.floats(min_value=-1.0 - 1e-9, max_value=1.0 + 1e-9))
def test_acos_asin_clamp_rounding_just_past_one(x):
    for f in (M.acos, M.asin):
        assert np.isfinite(f(lanes(x))).all()
    assert M.acos(lanes(1.0 + 1e-12))[0] == 0.0


@given(moderate, moderate, st.floats(min_value=-4.0, max_value=4.0))
def test_lerp_clamp_saturate_step_are_finite(a, b, t):
    assert np.isfinite(M.lerp(lanes(a), lanes(b), lanes(t))).all()
    assert 0.0 <= M.saturate(lanes(a))[0] <= 1.0
    lo, hi = min(a, b), max(a, b)
    assert lo <= M.clamp(lanes(t), lanes(lo), lanes(hi))[0] <= hi
    assert M.step(lanes(a), lanes(b))[0] == (0.0 if b < a else 1.0)


@given(finite)
def test_round_halves_away_from_zero(x):
    r = M.round_(lanes(x))[0]
    assert r == (math.floor(x + 0.5) if x >= 0 else -math.floor(-x + 0.5)) or \
        abs(x) >= 2 ** 52  # beyond 2^52 every double is whole: x itself
    assert M.round_(lanes(0.5, -0.5, 2.5, -2.5)).tolist() == [1.0, -1.0, 3.0, -3.0]


def test_defined_values_at_singular_points():
    assert M.atan2(lanes(0.0), lanes(0.0)).tolist() == [0.0]
    assert M.pow_(lanes(0.0), lanes(0.0)).tolist() == [1.0]
    assert M.sign(lanes(0.0, -3.0, 2.0)).tolist() == [0.0, -1.0, 1.0]
    assert M.blackbody(lanes(0.0, -10.0)).tolist() == [[0.0] * 3] * 2
    assert np.isfinite(M.blackbody(lanes(1.0, 1e9))).all()  # exp overflow, tiny spectra
    assert M.abs_(np.array([-2 ** 31], dtype=np.int32)).tolist() == [-2 ** 31]  # C's wrap
    assert M.pow_(np.array([2, 1, -1, 3], dtype=np.int32),
                  np.array([-1, -5, -3, 2], dtype=np.int32)).tolist() == [0, 1, -1, 9]


def test_outside_the_domain_the_values_are_ieee():
    """MDL defines no value here; the workbench gives C's (documented)."""
    assert np.isnan(M.sqrt(lanes(-1.0))).all() and np.isnan(M.log(lanes(-1.0))).all()
    assert M.log(lanes(0.0)).tolist() == [-math.inf]
    assert np.isnan(M.fmod(lanes(1.0), lanes(0.0))).all()
    assert M.rsqrt(lanes(0.0)).tolist() == [math.inf]


@given(st.floats(min_value=-700.0, max_value=700.0, allow_nan=False))
def test_elementwise_functions_are_cs(x):
    pairs = [(M.sin, math.sin), (M.cos, math.cos), (M.atan, math.atan), (M.exp, math.exp),
             (M.floor, math.floor), (M.ceil, math.ceil), (M.tanh, math.tanh)]
    for ours, c in pairs:
        assert ours(lanes(x))[0] == pytest.approx(c(x), rel=1e-15, abs=1e-300)
    ip, fp = M.modf(lanes(x))[0]
    assert ip + fp == x and math.copysign(1.0, fp) == math.copysign(1.0, x) or fp == 0.0
    s, c = M.sincos(lanes(x))[0]
    assert (s, c) == (math.sin(x), math.cos(x))


@given(st.floats(width=32, allow_nan=False))
def test_float_bits_round_trip(x):
    bits = M.float_bits_to_int(lanes(x))
    assert bits.dtype == np.int32
    assert M.int_bits_to_float(bits).tolist() == [x]


@settings(max_examples=50)
@given(st.lists(finite, min_size=9, max_size=9))
def test_transpose_twice_is_the_identity(xs):
    m = np.array(xs).reshape(1, 3, 3)
    assert np.array_equal(M.transpose(M.transpose(m)), m)


def test_spectral_functions_on_the_box_basis():
    c = lanes((0.2, 0.5, 0.9))
    assert M.eval_at_wavelength(c, 450.0).tolist() == [0.9]
    assert M.eval_at_wavelength(c, 530.0).tolist() == [0.5]
    assert M.eval_at_wavelength(c, 700.0).tolist() == [0.2]
    assert M.eval_at_wavelength(c, 300.0).tolist() == [0.0]
    assert M.max_value_wavelength(c).tolist() == [465.0]
    # a 6500 K black body is nearly white in linear sRGB, luminance 1
    rgb = M.blackbody(lanes(6500.0))[0]
    assert rgb @ M.LUMINANCE == pytest.approx(1.0)
    assert np.ptp(rgb) < 0.15
    warm, cool = M.blackbody(lanes(2000.0, 12000.0))
    assert warm[0] > warm[2] and cool[2] > cool[0]


def test_math_through_mdl_source_is_the_same_functions():
    """The checker folds constant calls with these functions; MDL sees the edges."""
    from mdl.loader import Loader

    m = Loader([]).load_text(
        "mdl 1.6;\nimport ::math::*;\n"
        "export const float a = math::length(float3(3e30, 4e30, 0.0));\n"
        "export const float3 n = math::normalize(float3(0.0));\n"
        "export const float s = math::smoothstep(1.0, 1.0, 1.0);\n"
        "export const float r = math::round(-2.5);\n"
        "export const float t = math::atan2(0.0, 0.0);\n")
    assert m.constant("a") == pytest.approx(5e30)
    assert tuple(m.constant("n")) == (0.0, 0.0, 0.0)
    assert (m.constant("s"), m.constant("r"), m.constant("t")) == (1.0, -3.0, 0.0)
