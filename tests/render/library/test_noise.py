"""Perlin noise (Handbook Listings 10.1-10.5) and marbloid's tint (Listing 15.17)."""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from displacement.surfaces import UnitSquare
from render.library.noise import (
    MAX_LEVELS,
    PERMUTATION,
    fade,
    grad,
    marbloid_tint,
    perlin_noise,
    perlin_noise_color,
    summed_noise_color,
    summed_perlin_noise,
)

# --- an independent scalar transcription of the Handbook's listing (the oracle) -------


def _reference_noise(x: float, y: float, z: float) -> float:
    p = [int(v) for v in PERMUTATION]

    def fade1(t):
        return t * t * t * (t * (t * 6.0 - 15.0) + 10.0)

    def lerp1(t, a, b):
        return a + t * (b - a)

    def grad1(hash_, x, y, z):
        h = hash_ & 15
        u = x if h < 8 else y
        if h < 4:
            v = y
        elif h in (12, 14):
            v = x
        else:
            v = z
        return (u if (h & 1) == 0 else -u) + (v if (h & 2) == 0 else -v)

    X, Y, Z = (int(math.floor(c)) & 255 for c in (x, y, z))
    x, y, z = x - math.floor(x), y - math.floor(y), z - math.floor(z)
    u, v, w = fade1(x), fade1(y), fade1(z)
    A = p[X] + Y
    AA = p[A] + Z
    AB = p[A + 1] + Z
    B = p[X + 1] + Y
    BA = p[B] + Z
    BB = p[B + 1] + Z
    return lerp1(w, lerp1(v, lerp1(u, grad1(p[AA], x, y, z), grad1(p[BA], x - 1, y, z)),
                          lerp1(u, grad1(p[AB], x, y - 1, z), grad1(p[BB], x - 1, y - 1, z))),
                 lerp1(v, lerp1(u, grad1(p[AA + 1], x, y, z - 1),
                                grad1(p[BA + 1], x - 1, y, z - 1)),
                          lerp1(u, grad1(p[AB + 1], x, y - 1, z - 1),
                                grad1(p[BB + 1], x - 1, y - 1, z - 1))))


def test_permutation_is_the_handbook_table_twice():
    assert PERMUTATION.shape == (512,)
    assert sorted(PERMUTATION[:256].tolist()) == list(range(256))
    assert PERMUTATION[:256].tolist() == PERMUTATION[256:].tolist()
    assert PERMUTATION[:6].tolist() == [151, 160, 137, 91, 90, 15]
    assert PERMUTATION[250:256].tolist() == [78, 66, 215, 61, 156, 180]


def test_vectorized_noise_matches_the_scalar_listing(rng):
    pts = np.concatenate([rng.uniform(-600.0, 600.0, (300, 3)), rng.uniform(-2.0, 2.0, (300, 3))])
    expected = [_reference_noise(*p) for p in pts]
    assert np.allclose(perlin_noise(pts), expected, rtol=0.0, atol=1e-14)


def test_hand_worked_value():
    # at (0.5, 0.5, 0.5) every fade is 0.5, so the value is the mean of the 8 corner terms;
    # worked through the table by hand: -0.25
    assert perlin_noise(np.array([0.5, 0.5, 0.5])) == pytest.approx(-0.25, abs=1e-15)


def test_fade_and_grad():
    t = np.linspace(0.0, 1.0, 11)
    assert fade(np.array([0.0, 1.0])).tolist() == [0.0, 1.0]
    assert np.allclose(fade(t) + fade(1.0 - t), 1.0)          # symmetric about 1/2
    # all 16 hashes: the 12 edge gradients (+4 repeats), each with two components +-1
    x, y, z = 0.1, 0.2, 0.4
    values = grad(np.arange(16), x, y, z)
    expected = [x + y, -x + y, x - y, -x - y, x + z, -x + z, x - z, -x - z,
                y + z, -y + z, y - z, -y - z, y + x, -y + z, y - x, -y - z]
    assert np.allclose(values, expected)


def test_zero_at_lattice_points(rng):
    pts = rng.integers(-100_000, 100_000, (500, 3)).astype(np.float64)
    assert np.all(perlin_noise(pts) == 0.0)


def test_gradient_at_a_lattice_point_is_that_corner_gradient(rng):
    # fade'(0) = 0, so next to a corner the noise is g . d: g has two components +-1, one 0
    corners = rng.integers(-50, 50, (200, 3)).astype(np.float64)
    h = 1e-6
    g = np.stack([(perlin_noise(corners + h * e) - perlin_noise(corners - h * e)) / (2 * h)
                  for e in np.eye(3)], axis=1)
    assert np.allclose(np.abs(g), np.round(np.abs(g)), atol=1e-6)
    assert np.all(np.sort(np.round(np.abs(g)), axis=1) == [0.0, 1.0, 1.0])


def test_range_determinism_and_period(rng):
    pts = rng.uniform(-1000.0, 1000.0, (400_000, 3))
    n = perlin_noise(pts)
    assert np.all(np.abs(n) <= 2.0)                 # the bound from |grad| <= 2 per corner
    assert n.min() < -0.8 and n.max() > 0.8         # the usable range is about [-1, 1]
    assert np.all(np.abs(n) < 1.05)
    assert abs(n.mean()) < 0.005
    assert np.array_equal(perlin_noise(pts[:1000]), n[:1000])
    assert np.allclose(perlin_noise(pts[:1000] + 256.0 * np.array([1.0, -2.0, 3.0])), n[:1000],
                       atol=1e-9)


def test_continuity_across_cell_faces(rng):
    base = rng.uniform(-20.0, 20.0, (2000, 3))
    for axis in range(3):
        on_face = base.copy()
        on_face[:, axis] = np.round(on_face[:, axis])
        e = np.eye(3)[axis]
        for eps in (1e-6, 1e-9):
            left = perlin_noise(on_face - eps * e)
            right = perlin_noise(on_face + eps * e)
            assert np.all(np.abs(left - right) <= 10.0 * eps)
        # C1: one-sided slopes agree across the face (fade is C2)
        h = 1e-4
        slope_left = (perlin_noise(on_face) - perlin_noise(on_face - h * e)) / h
        slope_right = (perlin_noise(on_face + h * e) - perlin_noise(on_face)) / h
        assert np.all(np.abs(slope_left - slope_right) < 0.05)


def test_gradient_statistics(rng):
    pts = rng.uniform(-200.0, 200.0, (200_000, 3))
    h = 1e-5
    g = np.stack([(perlin_noise(pts + h * e) - perlin_noise(pts - h * e)) / (2 * h)
                  for e in np.eye(3)], axis=1)
    assert np.all(np.abs(g.mean(axis=0)) < 0.01)
    std = g.std(axis=0)
    assert np.all((std > 0.6) & (std < 0.8))
    assert std.max() / std.min() < 1.1                  # nearly isotropic
    assert np.all(np.abs(g) < 3.0 * math.sqrt(3))     # bounded slopes


def test_huge_and_negative_coordinates_are_finite():
    pts = np.array([[1e300, -1e300, 1e15], [-0.0, -1e-300, 5e-324], [-1e-17, 2.0**52 + 0.5, -3.5]])
    n = perlin_noise(pts)
    assert np.all(np.isfinite(n)) and np.all(np.abs(n) <= 2.0)


@pytest.mark.parametrize("bad, match", [
    (np.array([[0.0, np.nan, 0.0]]), "NaN or infinite"),
    (np.array([[np.inf, 0.0, 0.0]]), "NaN or infinite"),
    (np.zeros((4, 2)), "3 coordinates"),
])
def test_bad_points_raise(bad, match):
    with pytest.raises(ValueError, match=match):
        perlin_noise(bad)


@settings(max_examples=200)
@given(st.lists(st.floats(-1e12, 1e12, allow_nan=False), min_size=3, max_size=3))
def test_noise_is_finite_and_bounded(point):
    n = perlin_noise(np.array(point))
    assert np.isfinite(n) and abs(float(n)) <= 2.0


# --- summed_perlin_noise ---------------------------------------------------------


def test_summed_noise_levels(rng):
    pts = rng.uniform(-10.0, 10.0, (500, 3))
    n0 = perlin_noise(pts)
    assert np.allclose(summed_perlin_noise(pts, 1), 0.5 + 0.5 * n0)
    assert np.allclose(summed_perlin_noise(pts, 1, turbulence=True), np.abs(n0))
    assert np.all(summed_perlin_noise(pts, 0) == 0.5)
    assert np.all(summed_perlin_noise(pts, 0, turbulence=True) == 0.0)
    # the recurrence of Listing 10.5's loop
    s3 = summed_perlin_noise(pts, 3, level_scale=0.7, point_scale=3.0)
    s4 = summed_perlin_noise(pts, 4, level_scale=0.7, point_scale=3.0)
    assert np.allclose(s4 - s3, 0.5 * 0.7**3 * perlin_noise(pts * 27.0))


def test_summed_noise_defaults_and_bounds(rng):
    pts = rng.uniform(-50.0, 50.0, (20_000, 3))
    s = summed_perlin_noise(pts)                     # 4 levels, 0.5, 2.0
    assert np.all((s >= 0.5 - (1 + 0.5 + 0.25 + 0.125)) & (s <= 0.5 + 1.875))
    t = summed_perlin_noise(pts, MAX_LEVELS, turbulence=True)
    assert np.all(np.isfinite(t)) and np.all(t >= 0.0)


@pytest.mark.parametrize("kwargs, match", [
    ({"level_count": -1}, r"level_count must be in \[0, 64\]"),
    ({"level_count": MAX_LEVELS + 1}, "level_count must be in"),
    ({"level_count": 2.5}, "level_count must be an int"),
    ({"level_count": True}, "level_count must be an int"),
    ({"level_scale": np.inf}, "must be finite"),
])
def test_summed_noise_bad_arguments(kwargs, match):
    with pytest.raises(ValueError, match=match):
        summed_perlin_noise(np.zeros((1, 3)), **kwargs)


# --- colours and marbloid ------------------------------------------------------------


def test_noise_colors_interpolate_between_the_two_colors(rng):
    s = UnitSquare().state_at_uv(rng.uniform(-2.0, 2.0, (300, 2)))
    c = perlin_noise_color(s, (0.0, 0.0, 0.0), (1.0, 0.5, 0.25), scale=10.0)
    t = 0.5 + 0.5 * perlin_noise(10.0 * s.position)
    assert np.allclose(c, t[:, None] * np.array([1.0, 0.5, 0.25]))
    c2 = summed_noise_color(s, 1.0, 0.0, scale=3.0, turbulence=True)
    assert np.allclose(c2, 1.0 - summed_perlin_noise(3.0 * s.position, turbulence=True)[:, None])


def test_marbloid_tint_by_hand():
    # at the origin the noise is 0 and z is 0: veins = 0.03 + 0.3 (1 + sin 0) = 0.33
    s = UnitSquare().state_at_uv(np.array([[0.0, 0.0]]))
    expected = [0.33 ** (1 / 1.8), 0.33 ** (1 / 1.4), 0.9 * 0.33 ** (1 / 1.1)]
    assert np.allclose(marbloid_tint(s, scale=12.0), [expected], atol=1e-15)


def test_marbloid_tint_formula_and_range(rng):
    s = UnitSquare().state_at_uv(rng.uniform(-3.0, 3.0, (2000, 2)))
    tint = marbloid_tint(s, scale=5.0, level_count=5, space="uvw")
    p = 5.0 * np.concatenate([s.uv, np.zeros((2000, 1))], axis=1)
    noise = summed_perlin_noise(p, 5, level_scale=0.8, turbulence=True)
    veins = 0.03 + 0.3 * (1.0 + np.sin(2.0 * p[:, 2] + 8.0 * noise))
    assert np.allclose(tint[:, 0], veins ** (1 / 1.8))
    assert np.all((veins >= 0.03) & (veins <= 0.63))
    lo = np.array([0.03 ** (1 / 1.8), 0.03 ** (1 / 1.4), 0.9 * 0.03 ** (1 / 1.1)])
    hi = np.array([0.63 ** (1 / 1.8), 0.63 ** (1 / 1.4), 0.9 * 0.63 ** (1 / 1.1)])
    assert np.all((tint >= lo - 1e-15) & (tint <= hi + 1e-15))
    # varying scale: a callable of state
    tint2 = marbloid_tint(s, scale=lambda st: np.full(len(st), 5.0), space="uvw")
    assert np.array_equal(tint, tint2)
