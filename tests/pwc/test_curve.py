"""Evaluation of compiled curves: Listing 15.5's search, repeat (Listing 14.27),
derivatives, the arc-length inverse, polylines, and properties over generated lists."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest
from hypothesis import given, settings
from pwc_strategies import compile_valid, valid_lists

from pwc import PwType, compile_text, point_along_pwc

TEE = "0 0\n.375 0\n.375 .25\n.125 .25\n.125 .5\n.875 .5\n.875 .25\n.625 .25\n.625 0\n1 0\n"
ARCS = "0 0\n1 0\n1 1 :angle 90\n2 2 :sag -.3\n3 3 :cyma_recta\n3 4 :flare\n0 5 :cyma_reversa\n"


def test_knots_and_ends():
    c = compile_text(ARCS)
    np.testing.assert_allclose(c.evaluate(c.t), c.pt, atol=1e-14)
    np.testing.assert_array_equal(c.evaluate([-5.0, -1e-300, 0.0]), np.repeat(c.pt[:1], 3, 0))
    np.testing.assert_array_equal(c.evaluate([1.0, 1.5, 1e300]), np.repeat(c.pt[-1:], 3, 0))


def test_shapes_and_dtypes():
    c = compile_text(ARCS)
    assert c.evaluate(0.3).shape == (2,)
    assert c.evaluate(np.zeros((3, 4))).shape == (3, 4, 2)
    assert c.evaluate(np.zeros(0)).shape == (0, 2)
    assert c.evaluate(np.zeros(5, np.float32)).dtype == np.float32
    np.testing.assert_array_equal(point_along_pwc(0.25, c), c.evaluate(0.25))


def test_nan_position_is_an_error_not_a_nan():
    c = compile_text(ARCS)
    with pytest.raises(ValueError, match="finite"):
        c.evaluate([0.5, np.nan])


def test_less_than_search_picks_the_piece_starting_at_a_knot():
    c = compile_text("0 0\n1 0\n1 1 :angle 90")
    # at s == t[1] Listing 15.5 chooses piece 2 (the first t that exceeds s): the ccw
    # quarter arc to (1, 1) leaves at 45 degrees below its chord, not along the segment
    np.testing.assert_allclose(c.tangent(c.t[1]), [0.5**0.5, 0.5**0.5], atol=1e-12)
    np.testing.assert_allclose(c.tangent(np.nextafter(c.t[1], 0)), [1.0, 0.0], atol=1e-12)


def test_arcs_are_exact_not_polylines():
    c = compile_text("0 0\n0 2 :sag 1", normalize=False)  # a semicircle of radius 1
    s = np.linspace(0, 1, 1001)
    d = np.linalg.norm(c.evaluate(s) - [0, 1], axis=1)
    np.testing.assert_allclose(d, 1.0, rtol=0, atol=2e-16 * 4)


def test_repeat_follows_listing_14_27():
    c = compile_text(TEE, normalize=False)  # runs along y from 0 to 1? no: tee runs in x
    s = np.linspace(0, 1, 31)
    p1 = c.evaluate(s, repeat=1.0)
    np.testing.assert_allclose(p1[:-1], c.evaluate(s[:-1]))
    np.testing.assert_array_equal(p1[-1], c.pt[0])  # frac(1) = 0: wraps, as in the book
    p3 = c.evaluate(s, repeat=3.0)
    k = np.floor(s * 3)
    expect = c.evaluate(s * 3 - k) / 3
    expect[:, 1] += k / 3
    np.testing.assert_allclose(p3, expect, atol=1e-15)
    for bad in (0.0, -1.0, np.inf, np.nan):
        with pytest.raises(ValueError, match="repeat"):
            c.evaluate(s, repeat=bad)


def test_repeat_of_1000_at_uv_0_and_1():
    c = compile_text("0 0\n.5 .5 :angle 90\n0 1")
    p = c.evaluate(np.array([0.0, 0.0005, 0.9999995, 1.0]), repeat=1000.0)
    assert np.all(np.isfinite(p))
    np.testing.assert_allclose(p[-1], [0.0, 1.0], atol=1e-12)  # last copy starts at run 1
    np.testing.assert_allclose(p[1], c.evaluate(0.5) / 1000, atol=1e-12)


def test_derivative_magnitude_is_the_length():
    c = compile_text(ARCS)
    s = np.random.default_rng(0).random(1000)
    np.testing.assert_allclose(np.linalg.norm(c.derivative(s), axis=-1), c.length, rtol=1e-12)
    h = 1e-7  # and it is the derivative of evaluate
    fd = (c.evaluate(s + h) - c.evaluate(s - h)) / (2 * h)
    far = np.min(np.abs(s[:, None] - c.t[None, :]), axis=1) > 2 * h
    np.testing.assert_allclose(fd[far], c.derivative(s[far]), rtol=1e-5, atol=1e-6)


def test_arc_length_inverse():
    c = compile_text(ARCS)
    s = np.linspace(0, 1, 101)
    np.testing.assert_allclose(c.position_at_length(c.arc_length(s)), s, atol=1e-15)
    assert c.arc_length(1.0) == pytest.approx(c.length)
    assert c.position_at_length(-1.0) == 0.0 and c.position_at_length(1e9) == 1.0


@pytest.mark.parametrize("tol", [1e-2, 1e-4, 1e-7])
def test_polyline_within_tolerance_and_through_every_point(tol):
    c = compile_text(ARCS)
    s, pts = c.polyline(tol)
    assert s[0] == 0 and s[-1] == 1 and np.all(np.diff(s) > 0)
    assert np.all(np.isin(c.t, s)) and np.array_equal(pts[np.isin(s, c.t)], c.pt)
    chord_mid = 0.5 * (pts[1:] + pts[:-1])
    curve_mid = c.evaluate(0.5 * (s[1:] + s[:-1]))
    assert np.linalg.norm(chord_mid - curve_mid, axis=1).max() <= tol * (1 + 1e-9)
    with pytest.raises(ValueError):
        c.polyline(0.0)


def test_bbox_includes_arc_extremes():
    c = compile_text("0 0\n0 2 :sag 1", normalize=False)
    np.testing.assert_allclose(c.bbox, [[0, 0], [1, 2]], atol=1e-15)


def test_float32_evaluation_is_close_to_float64():
    c = compile_text(ARCS)
    s = np.random.default_rng(1).random(10_000)
    err = np.abs(c.evaluate(s.astype(np.float32)) - c.evaluate(s)).max()
    assert 0 < err < 1e-5  # float32 tables and arithmetic: a few ulps of a unit-sized curve


# -- properties over generated lists ----------------------------------------------------

def _dense_length(c, n=400_001) -> float:
    """Arc length from dense evaluation: independent of the compiler's bookkeeping."""
    s = np.union1d(np.linspace(0, 1, n), c.t)  # knots included: no chord cuts a corner
    p = c.evaluate(np.nextafter(s, 0))  # the end of each piece, not the next one's start
    p[0] = c.pt[0]
    return float(np.linalg.norm(np.diff(p, axis=0), axis=1).sum())


@given(valid_lists())
@settings(max_examples=60)
def test_properties_of_generated_curves(text):
    c, _ = compile_valid(text)
    assert np.all(np.diff(c.t) > 0)
    size = max(1.0, float(np.abs(c.bbox).max()))
    # passes through every pw-point, and each piece meets its neighbours
    np.testing.assert_allclose(c.evaluate(c.t), c.pt, atol=1e-11 * size)
    left = c.evaluate(np.nextafter(c.t[1:-1], 0))
    np.testing.assert_allclose(left, c.pt[1:-1], atol=1e-9 * size)
    # tangent-continuous at cyma midpoints and where each flare starts
    kinds = c.type
    smooth = [i for i in range(1, c.n - 1) if
              (kinds[i] in (PwType.CYMA_RECTA, PwType.CYMA_REVERSA) and kinds[i + 1] == kinds[i]
               and c.line[i] == c.line[i + 1]) or kinds[i + 1] == PwType.FLARE]
    for i in smooth:
        np.testing.assert_allclose(c.tangent(np.nextafter(c.t[i], 0)), c.tangent(c.t[i]),
                                   atol=1e-6)
    # the length is the curve's arc length
    assert c.length == pytest.approx(_dense_length(c), rel=1e-6)
    s = np.random.default_rng(0).uniform(-0.5, 1.5, 2000)
    assert np.all(np.isfinite(c.evaluate(s))) and np.all(np.isfinite(c.derivative(s)))


@pytest.mark.parametrize("n", [2, 7, 300, 20_000])
def test_lookup_table_search_equals_listing_15_5_search(n):
    rng = np.random.default_rng(n)
    steps = rng.uniform(0.001, 1.0, (n - 1, 2)) * rng.choice([1e-4, 1.0], (n - 1, 1))
    text = ":relative\n0 0\n" + "".join(f"{float(dx)!r} {float(dy)!r}\n" for dx, dy in steps)
    c = compile_text(text)
    s = np.concatenate([c.t, np.nextafter(c.t, -1), np.nextafter(c.t, 2), rng.random(5000),
                        [-1.0, -0.0, 1.0, 3.0]])
    for dtype in (np.float64, np.float32):
        tab = c._tables64 if dtype == np.float64 else c._tables32
        ss = s.astype(dtype)
        i, _ = c._locate(ss, tab)
        expect = np.searchsorted(tab.t[:-1], ss, side="right")  # first t exceeding s
        expect[ss < 0] = 0
        np.testing.assert_array_equal(i, expect)


# -- the trade knobs: polylines and float32 (pwc trade, [render] curves) ------------------
@pytest.mark.parametrize("tolerance", [1e-2, 1e-4])
def test_as_polyline_is_a_curve_of_segments_within_the_tolerance(tolerance):
    c = compile_text("0 0\n1 0\n1 1 :angle 90\n0 2 :sag .4\n0 3 :cyma_recta")
    p = c.as_polyline(tolerance)
    assert np.all(p.type == 0) and np.all(np.diff(p.t) > 0) and p.n > c.n
    assert p.scale == c.scale and p.name == c.name
    # every vertex lies on the curve; every chord midpoint within the tolerance of it
    dense = c.evaluate(np.linspace(0.0, 1.0, 200_001))
    mid = 0.5 * (p.pt[1:] + p.pt[:-1])
    dist = np.min(np.linalg.norm(mid[:, None, :] - dense[None, ::50, :], axis=2), axis=1)
    assert dist.max() <= tolerance + 2e-4  # the dense sampling's own spacing
    # parametrized by its own arc length, slightly shorter than the arcs
    assert p.length == pytest.approx(np.linalg.norm(np.diff(p.pt, axis=0), axis=1).sum())
    assert c.length * (1 - 10 * tolerance) < p.length <= c.length


def test_in_float32_evaluates_as_mdl_float_and_returns_float64():
    c = compile_text("0 0\n1 0\n1 1 :angle 90")
    s = np.linspace(0.0, 1.0, 1001)
    f32 = c.in_float32()
    assert f32.precision == "float32" and c.precision == "float64"
    out = f32.evaluate(s)
    assert out.dtype == np.float64
    np.testing.assert_array_equal(out, c.evaluate(s.astype(np.float32)).astype(np.float64))
    assert np.abs(out - c.evaluate(s)).max() < 1e-6
    with pytest.raises(ValueError, match="precision must be"):
        dataclasses.replace(c, precision="float16")
