"""Stability of pwc-lists at the extremes (docs/stability.md, "pwc-lists"): angles of
1e-12 and 359.9999 degrees, coordinates of 1e-300 and 1e300 (and beyond: a clear error),
cusps, and 10^5 points.  Every compiled curve evaluates to finite points and unit
tangents; what cannot be compiled fails with a diagnostic naming the line and a fix."""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from repo import run_pwc

from displacement.camera import Camera
from displacement.dice import dice
from displacement.pwc_fields import displace_with_pwc
from displacement.surfaces import UnitSquare
from pwc import PwcError, PwType, compile_source
from pwc.tolerance import TOL

#: a profile of every piece kind, absolute coordinates: (x, y, property)
PIECES = [(0.0, 0.0, ""), (1.5, 0.0, ""), (1.5, 2.75, ""), (2.5, 3.75, ":sag {0.4}"),
          (4.0, 6.0, ":cyma_reversa"), (4.5, 6.5, ":angle -90"), (5.0, 8.0, ":flare"),
          (5.0, 9.0, ":cyma_recta"), (0.0, 9.0, "")]


def scaled_list(k: float) -> str:
    """:data:`PIECES` with every length (coordinates and sagittas) times ``k``."""
    lines = []
    for x, y, prop in PIECES:
        if "{" in prop:
            prop = prop.split("{")[0] + repr(float(prop.split("{")[1][:-1]) * k)
        lines.append(f"{x * k!r} {y * k!r} {prop}".rstrip())
    return "\n".join(lines) + "\n"


def assert_finite_curve(c, n: int = 10_001) -> None:
    """Points, derivatives and tangents finite; tangents unit; t strictly increasing."""
    s = np.linspace(0.0, 1.0, n)
    assert np.all(np.isfinite(c.evaluate(s)))
    assert np.all(np.isfinite(c.derivative(s)))
    tangent = c.tangent(s)
    np.testing.assert_allclose(np.linalg.norm(tangent, axis=-1), 1.0, atol=1e-12)
    assert c.t[0] == 0.0 and c.t[-1] == 1.0 and np.all(np.diff(c.t) > 0)
    # the curve passes through its pw_points, to the rounding of center + r (cos, sin)
    atol = 1e-12 + 8 * np.finfo(float).eps * float(c.radius.max())
    np.testing.assert_allclose(c.evaluate(c.t[:-1]), c.pt[:-1], rtol=0, atol=atol)


# -- angles ------------------------------------------------------------------------------
@pytest.mark.parametrize("angle", [1e-12, -1e-12])
def test_an_angle_of_1e_minus_12_degrees_is_a_segment_with_a_warning(angle):
    c, warnings = compile_source(f"0 0\n1 0 :angle {angle!r}", normalize=False)
    assert c.type[1] == PwType.SEGMENT
    assert "below 1e-06 degrees" in warnings[0].message and warnings[0].loc.line == 2
    assert c.length == 1.0  # the chord: the arc would deviate from it by 4e-15
    assert_finite_curve(c)


@pytest.mark.parametrize("angle", [359.9999, -359.9999])
def test_an_angle_of_359_9999_degrees_is_a_full_arc(angle):
    c, warnings = compile_source(f"0 0\n1 0 :angle {angle!r}", normalize=False)
    assert warnings == [] and c.type[1] == PwType.ANGLE
    theta = math.radians(abs(angle))
    r = 1.0 / (2.0 * math.sin(theta / 2.0))  # ~ 573,000 chords
    assert c.radius[1] == pytest.approx(r, rel=1e-9)
    assert c.length == pytest.approx(r * theta, rel=1e-9)
    # it ends where it should: r * 1e-16 of rounding on a radius of 5.7e5
    np.testing.assert_allclose(c.evaluate(np.array([0.0, 1.0])), [[0, 0], [1, 0]], atol=1e-9)
    assert_finite_curve(c)
    # it turns the given angle: the tangent is back to (almost) the start's direction
    assert float(np.dot(c.tangent(0.0), c.tangent(np.nextafter(1.0, 0.0)))) == pytest.approx(
        math.cos(math.radians(360.0 - abs(angle))), abs=1e-9)


@given(st.one_of(st.floats(1e-300, 1e-6, exclude_max=True),
                 st.floats(359.99, 360.0, exclude_max=True)), st.booleans())
@settings(max_examples=60)
def test_every_angle_near_zero_or_a_full_turn_compiles_to_a_finite_curve(angle, cw):
    angle = -angle if cw else angle
    c, _ = compile_source(f"0 0\n1 1\n2 1 :angle {angle!r}\n3 0")
    assert_finite_curve(c, 2001)


def test_a_full_turn_is_refused_with_the_fix():
    with pytest.raises(PwcError) as e:
        compile_source("0 0\n1 0 :angle 360")
    assert "<string>:2:1: error" in str(e.value) and "fix: use an angle between" in str(e.value)


# -- coordinates -------------------------------------------------------------------------
@pytest.mark.parametrize("k", [1e-300, 1e300])
def test_coordinates_of_1e_minus_300_and_1e300_give_the_same_normalized_curve(k):
    ref, _ = compile_source(scaled_list(1.0))
    c, warnings = compile_source(scaled_list(k))
    assert warnings == []
    np.testing.assert_allclose(c.t, ref.t, rtol=1e-12, atol=1e-15)
    np.testing.assert_allclose(c.pt, ref.pt, rtol=1e-12, atol=1e-14)
    np.testing.assert_allclose(c.center, ref.center, rtol=1e-12, atol=1e-13)
    np.testing.assert_allclose(c.radius, ref.radius, rtol=1e-12)
    assert c.length == pytest.approx(ref.length, rel=1e-12)
    assert c.scale == pytest.approx(ref.scale / k, rel=1e-12)
    assert_finite_curve(c)
    # unnormalized, in source units: finite too
    raw, _ = compile_source(scaled_list(k), normalize=False)
    assert raw.length == pytest.approx(ref.length / ref.scale * k, rel=1e-12)
    assert np.all(np.isfinite(raw.evaluate(np.linspace(0, 1, 1001))))


@given(st.integers(-300, 300))
@settings(max_examples=40)
def test_any_scale_between_1e_minus_300_and_1e300_normalizes_alike(exponent):
    ref, _ = compile_source(scaled_list(1.0))
    c, _ = compile_source(scaled_list(10.0**exponent))
    np.testing.assert_allclose(c.pt, ref.pt, rtol=1e-12, atol=1e-14)
    np.testing.assert_allclose(c.t, ref.t, rtol=1e-12, atol=1e-15)


@pytest.mark.parametrize(("text", "line", "words"), [
    ("0 0\n5e-324 0\n5e-324 5e-324 :angle 90", 2, "outside [1e-305, 1e+305]"),
    ("0 0\n1e-320 0\n0 1e-320", 2, "outside [1e-305, 1e+305]"),
    ("0 0\n1e308 0\n1e308 1e308 :angle 90", 2, "outside [1e-305, 1e+305]"),
    (":relative\n0 0\n1.5e308 0\n1.5e308 0", 4, "overflow double precision"),
    ("0 0\n1 0 :sag 1e300", 2, "overflows double precision"),
], ids=["subnormal", "1e-320", "1e308", "relative-overflow", "sagitta-overflow"])
def test_coordinates_beyond_double_precision_fail_clearly(text, line, words):
    with pytest.raises(PwcError) as e:
        compile_source(text)
    d = [d for d in e.value.diagnostics if d.severity == "error"][0]
    assert d.loc.line == line and words in d.message and d.fix


def test_the_range_is_the_stated_one():
    assert (TOL.coordinate_min, TOL.coordinate_max) == (1e-305, 1e305)
    compile_source("0 0\n1e-305 0")
    compile_source("0 0\n1e305 0 :sag 1e304")


def test_the_command_reports_a_subnormal_list_without_a_traceback(tmp_path):
    f = tmp_path / "tiny.pwc"
    f.write_text("0 0\n1e-320 0\n0 1e-320 :angle 90\n")
    r = run_pwc("check", f)
    assert r.returncode == 1 and "Traceback" not in r.stderr
    assert f"{f}:2:1: error: the largest coordinate" in r.stderr and "fix:" in r.stderr


# -- cusps -------------------------------------------------------------------------------
CUSPS = {
    "segment folds back": "0 0\n0 1\n0 0.5\n1 0.5",
    "arc retraces itself": "0 0\n1 1 :angle 90\n0 0 :angle -90\n0 1",
    "segment into an arc backwards": "0 0\n1 0\n0 1 :angle -90\n0 2",
}


@pytest.mark.parametrize("text", CUSPS.values(), ids=CUSPS.keys())
def test_cusps_compile_to_finite_curves_with_reversed_tangents(text):
    c, _ = compile_source(text)
    assert_finite_curve(c)
    # at the cusp (the first inner knot) the tangent reverses, one-sided on either side
    knot = c.t[1]
    before, after = c.tangent(np.nextafter(knot, 0.0)), c.tangent(knot)
    assert np.dot(before, after) == pytest.approx(-1.0, abs=1e-12)


@pytest.mark.parametrize("text", CUSPS.values(), ids=CUSPS.keys())
def test_a_cusp_displaced_along_v_dices_to_finite_unit_normals(text):
    c, _ = compile_source(text)
    cam = Camera(position=(0.5, -1.0, 2.0), look_at=(0.5, 0.5, 0.3), width=96, height=96)
    mesh = dice(UnitSquare(), displace_with_pwc(c, "along_v"), cam)
    assert np.all(np.isfinite(mesh.vertices)) and np.all(np.isfinite(mesh.normals))
    np.testing.assert_allclose(np.linalg.norm(mesh.normals, axis=1), 1.0, atol=1e-9)
    # the cusp's knot is a grid line: the fold is diced exactly
    assert np.isclose(mesh.uv[:, 1], c.t[1], rtol=0, atol=1e-15).any()


# -- 10^5 points -------------------------------------------------------------------------
def test_one_hundred_thousand_points_of_every_kind(rng):
    n = 100_000
    steps = rng.uniform(0.1, 1.0, (n - 1, 2))
    kinds = np.array(["", " :sag .05", " :angle 30", " :cyma_recta", " :flare"])
    props = kinds[np.arange(n - 1) % len(kinds)]
    text = ":relative\n0 0\n" + "".join(
        f"{dx:.6f} {dy:.6f}{p}\n" for (dx, dy), p in zip(steps, props, strict=True))
    c, _ = compile_source(text)
    assert c.n > n  # each cyma adds a point
    assert_finite_curve(c, 1_000_001)
    # the length is the sum of the pieces, each measured independently
    chords = np.linalg.norm(np.diff(c.pt, axis=0), axis=1)
    sweep = np.abs(c.end_angle[1:] - c.start_angle[1:])
    pieces = np.where(c.is_arc[1:], c.radius[1:] * sweep, chords)
    assert pieces.sum() == pytest.approx(c.length, rel=1e-12)
    xy, _ = c.polyline(1e-4)
    assert np.all(np.isfinite(xy)) and len(xy) >= c.n
