"""Compilation: worked values of Listings 15.3/15.4, arc constructions and their sign
conventions, normalization, and the extremes the spec names."""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import given, settings
from pwc_strategies import compile_valid, valid_lists

from pwc import PwcError, PwType, compile_source, compile_text
from pwc.compiler import resolve_points
from pwc.parser import parse

SEGMENTS = "0 0\n.7 0\n.7 .4\n3/7 .4\n3/7 4/3\n4/7 1\n"
RIGHT_ANGLE_ARC = """:relative
0 0
.25 0
0 .55
.125 .125 :angle -90
.375 0
.125 -.125 :angle -90
.125 0
0 1
.25 .25 :angle -90
0 .25
a0 0
"""


def test_listing_15_3_segments():
    c = compile_text(SEGMENTS, "segments")
    assert c.length == pytest.approx(2.00056, abs=5e-6)
    np.testing.assert_allclose(c.t, [0, 0.26243, 0.41238, 0.51414, 0.86404, 1.0], atol=5e-6)
    np.testing.assert_allclose(
        c.pt, [[0, 0], [0.525, 0], [0.525, 0.3], [0.32142857, 0.3], [0.32142857, 1.0],
               [0.42857143, 0.75]], atol=5e-9)
    assert c.scale == pytest.approx(0.75)
    assert np.all(c.type == PwType.SEGMENT)


def test_listing_15_4_right_angle_arc():
    c = compile_text(RIGHT_ANGLE_ARC, "right_angle_arc")
    assert c.relative and c.n == 11
    assert c.length == pytest.approx(2.23678, abs=5e-6)
    np.testing.assert_allclose(
        c.t, [0, 0.05452, 0.17447, 0.21729, 0.29907, 0.34189, 0.36915, 0.58723, 0.67287,
              0.7274, 1.0], atol=5e-6)
    assert c.type[3] == PwType.ANGLE
    np.testing.assert_allclose(c.pt[3], [0.18292683, 0.32926829], atol=5e-9)
    np.testing.assert_allclose(c.center[3], [0.18292683, 0.26829268], atol=5e-9)
    assert c.radius[3] == pytest.approx(0.06098, abs=5e-6)
    assert (c.start_angle[3], c.end_angle[3]) == pytest.approx((math.pi, math.pi / 2))
    np.testing.assert_allclose(c.center[5], [0.36585366, 0.26829268], atol=5e-9)
    assert (c.start_angle[5], c.end_angle[5]) == pytest.approx((math.pi / 2, 0.0), abs=1e-12)
    np.testing.assert_allclose(c.center[8], [0.6097561, 0.75609756], atol=5e-9)
    assert c.radius[8] == pytest.approx(0.12195, abs=5e-6)
    np.testing.assert_allclose(c.pt[-1], [0.0, 1.0], atol=1e-15)  # "a0 0": x absolute


def test_relative_with_absolute_prefix():
    tree, _ = parse(":relative\n1 1\n2 a5\na0 1\n")
    np.testing.assert_array_equal(resolve_points(tree), [[1, 1], [3, 5], [0, 6]])
    tree, _ = parse("1 1\na2 a5\n")  # absolute lists ignore the prefix
    np.testing.assert_array_equal(resolve_points(tree), [[1, 1], [2, 5]])


def _left_of_chord(a, b, p) -> float:
    return (b[0] - a[0]) * (p[1] - a[1]) - (b[1] - a[1]) * (p[0] - a[0])


@pytest.mark.parametrize(("deg", "ccw"), [(90, True), (-90, False), (270, True), (-300, False)])
def test_angle_sign_is_counter_clockwise_positive(deg, ccw):
    c = compile_text(f"0 0\n1 1 :angle {deg}", normalize=False)
    assert (c.end_angle[1] > c.start_angle[1]) == ccw
    assert c.end_angle[1] - c.start_angle[1] == pytest.approx(math.radians(deg))
    r = math.sqrt(2) / (2 * abs(math.sin(math.radians(deg) / 2)))
    assert c.radius[1] == pytest.approx(r)
    side = _left_of_chord((0, 0), (1, 1), c.center[1])
    assert (side > 0) == (ccw == (abs(deg) < 180))  # minor arcs: centre on the ccw side
    assert -math.pi < c.start_angle[1] <= math.pi


@pytest.mark.parametrize("sag", [0.1, -0.1, 0.5, -0.5, 2.0, -2.0])
def test_sagitta_is_the_distance_from_chord_midpoint_to_arc_midpoint(sag):
    c = compile_text(f"0 0\n1 0 :sag {sag}", normalize=False)
    mid = c.evaluate(0.5)
    assert mid[0] == pytest.approx(0.5, abs=1e-12)
    # positive = counter-clockwise about the centre, so the arc bulges to the chord's right
    # (outward, +x, for a profile running up the wall)
    assert mid[1] == pytest.approx(-sag, rel=1e-12)
    assert (c.end_angle[1] > c.start_angle[1]) == (sag > 0)


@pytest.mark.parametrize(("kind", "first_ccw"), [("cyma_recta", True), ("cyma_reversa", False)])
def test_cyma_two_sixty_degree_arcs_tangent_at_the_midpoint(kind, first_ccw):
    c = compile_text(f"0 0\n1 2 :{kind}", normalize=False)
    assert c.n == 3 and np.all(c.type[1:] == PwType[kind.upper()])
    np.testing.assert_allclose(c.pt[1], [0.5, 1.0], atol=1e-15)
    half = math.hypot(0.5, 1.0)
    np.testing.assert_allclose(c.radius[1:], half, rtol=1e-14)
    sweeps = c.end_angle[1:] - c.start_angle[1:]
    np.testing.assert_allclose(sweeps, [math.pi / 3, -math.pi / 3] if first_ccw
                               else [-math.pi / 3, math.pi / 3], rtol=1e-14)
    # equilateral: each centre is one radius from both ends of its arc
    for i, (a, b) in enumerate([((0, 0), (0.5, 1)), ((0.5, 1), (1, 2))], start=1):
        assert math.dist(c.center[i], a) == pytest.approx(half)
        assert math.dist(c.center[i], b) == pytest.approx(half)
    left = c.tangent(np.nextafter(c.t[1], 0))
    right = c.tangent(c.t[1])
    np.testing.assert_allclose(left, right, atol=1e-9)


def test_flare_is_tangent_to_the_previous_piece():
    c = compile_text("0 0\n0 1\n1 2 :flare", normalize=False)  # up, then curve right
    assert c.type[2] == PwType.FLARE
    np.testing.assert_allclose(c.tangent(c.t[1]), [0.0, 1.0], atol=1e-12)
    # radius |AB|^2 / (2 |AB . n|) with n the unit normal toward B
    assert c.radius[2] == pytest.approx(2 / 2)
    np.testing.assert_allclose(c.center[2], [1, 1], atol=1e-12)
    assert c.end_angle[2] < c.start_angle[2]  # B to the right of the tangent: clockwise


def test_flare_after_an_arc_follows_the_arc_tangent():
    c = compile_text("0 0\n1 1 :angle 90\n0 3 :flare", normalize=False)
    left = c.tangent(np.nextafter(c.t[1], 0))
    np.testing.assert_allclose(left, c.tangent(c.t[1]), atol=1e-9)


def test_flare_on_the_tangent_line_is_a_segment_with_a_warning():
    c, warnings = compile_source("0 0\n0 1\n0 3 :flare")
    assert c.type[2] == PwType.SEGMENT and "tangent line" in warnings[0].message


def test_normalization_and_no_normalize():
    c = compile_text("0 0\n-8 2\n3 4")
    assert c.scale == pytest.approx(1 / 8) and np.abs(c.pt).max() == pytest.approx(1.0)
    raw = compile_text("0 0\n-8 2\n3 4", normalize=False)
    assert raw.scale == 1.0 and raw.length == pytest.approx(c.length * 8)
    np.testing.assert_allclose(raw.t, c.t, rtol=1e-14)


def test_arc_bulges_may_exceed_one_after_normalization():
    c = compile_text("0 0\n0 1 :sag 3")
    assert np.abs(c.pt).max() == pytest.approx(1.0)
    assert np.abs(c.bbox).max() == pytest.approx(3.0)


# -- extremes (spec: compile to a finite, accurate curve, or fail with a clear error) ----

def test_angle_of_1e_minus_7_degrees_is_a_segment_with_a_warning():
    c, w = compile_source("0 0\n1 1 :angle 1e-7")
    assert c.type[1] == PwType.SEGMENT and "straight segment" in w[0].message


def test_angle_of_359_999_degrees():
    c, w = compile_source("0 0\n1 0 :angle 359.999", normalize=False)
    assert w == [] and c.type[1] == PwType.ANGLE
    r = 1 / (2 * math.sin(math.radians(359.999) / 2))
    assert c.radius[1] == pytest.approx(r, rel=1e-12)
    assert c.length == pytest.approx(r * math.radians(359.999), rel=1e-12)
    ends = c.center[1] + c.radius[1] * np.array(
        [[math.cos(c.start_angle[1]), math.sin(c.start_angle[1])],
         [math.cos(c.end_angle[1]), math.sin(c.end_angle[1])]])
    np.testing.assert_allclose(ends, [[0, 0], [1, 0]], atol=1e-10)  # r ~ 57,000
    assert np.all(np.isfinite(c.evaluate(np.linspace(0, 1, 1001))))


def test_sagitta_of_1e_minus_12_chords_is_a_segment_with_a_warning():
    c, w = compile_source("0 0\n1 0 :sag 1e-12")
    assert c.type[1] == PwType.SEGMENT and "so flat" in w[0].message


def test_sagitta_of_a_million_chords():
    c, w = compile_source("0 0\n1 0 :sag 1e6", normalize=False)
    assert w == [] and c.type[1] == PwType.SAGITTA
    assert c.radius[1] == pytest.approx((0.25 + 1e12) / 2e6, rel=1e-12)
    mid = c.evaluate(0.5)
    np.testing.assert_allclose(mid, [0.5, -1e6], rtol=0, atol=1e-15 * c.radius[1])
    np.testing.assert_allclose(c.evaluate(np.array([0.0, 1.0])), [[0, 0], [1, 0]], atol=1e-9)


@pytest.mark.parametrize("k", [1e-9, 1e9])
def test_tiny_and_huge_coordinates_give_the_same_normalized_curve(k):
    ref = compile_text(RIGHT_ANGLE_ARC)
    lines = [":relative"] + [" ".join(
        (("a" if tok.startswith("a") else "") + repr(float(eval(tok.lstrip("a"))) * k))
        for tok in line.split()[:2]) + (" " + " ".join(line.split()[2:]) if
                                         len(line.split()) > 2 else "")
        for line in RIGHT_ANGLE_ARC.splitlines()[1:]]
    c = compile_text("\n".join(lines))
    np.testing.assert_allclose(c.t, ref.t, rtol=1e-12, atol=1e-15)
    np.testing.assert_allclose(c.pt, ref.pt, rtol=1e-12, atol=1e-14)
    assert c.length == pytest.approx(ref.length, rel=1e-12)
    assert c.scale == pytest.approx(ref.scale / k, rel=1e-12)


def test_mixed_scales_below_precision_fail_clearly():
    err = pytest.raises(PwcError, compile_text, "0 0\n1e9 0\n1e9 1e-9 :sag 1")
    assert "identical points" in str(err.value)


def test_one_hundred_thousand_points():
    n = 100_000
    rng = np.random.default_rng(1)
    steps = rng.uniform(0.1, 1.0, (n - 1, 2))
    props = np.where(np.arange(n - 1) % 3 == 0, " :sag .05", "")
    text = ":relative\n0 0\n" + "".join(
        f"{dx:.6f} {dy:.6f}{p}\n" for (dx, dy), p in zip(steps, props, strict=True))
    c = compile_text(text)
    assert c.n == n and np.all(np.diff(c.t) > 0)
    assert np.all(np.isfinite(c.evaluate(rng.random(10_000))))


@given(valid_lists())
@settings(max_examples=150)
def test_generated_lists_compile_to_finite_curves(text):
    c, _ = compile_valid(text)
    for name in ("t", "pt", "center", "radius", "start_angle", "end_angle"):
        assert np.all(np.isfinite(getattr(c, name)))
    assert c.t[0] == 0.0 and c.t[-1] == 1.0 and np.all(np.diff(c.t) > 0)
    assert np.abs(c.pt).max() == pytest.approx(1.0) or c.scale == 1.0
