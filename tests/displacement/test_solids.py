"""Solids for fabrication: watertightness, analytic volumes, tolerance, export, CLI."""

from __future__ import annotations

import argparse
import math
from pathlib import Path

import manifold3d
import numpy as np
import pytest
import trimesh
from hypothesis import given, settings
from hypothesis import strategies as st

import pwc
from displacement import solids
from displacement.commands.solid import register
from displacement.pwc_fields import double_pwc, pwc_angular_displace
from displacement.solids import (
    export,
    extrude,
    frame,
    frame_pieces,
    profile_area,
    profile_centroid,
    revolve,
    section_polygons,
    solid_info,
    sweep,
    to_trimesh,
)
from displacement.surfaces import UnitSquare

PROFILES = Path(__file__).resolve().parents[2] / "profiles"


def load(name: str) -> pwc.Curve:
    return pwc.load(PROFILES / f"{name}.pwc")


RECT = pwc.compile_text("0 0\n1 0\n1 1\n0 1", name="rect")
QUARTER_DISC = pwc.compile_text("0 0\n1 0\n0 1 :angle 90", name="quarter_disc")
# one piece: a half circle of radius 1/2 bulging out from the wall (x > 0)
SEMICIRCLE = pwc.compile_text("0 0\n0 1 :angle 180", name="semicircle")
CIRCLE_PATH = pwc.compile_text("1 0\n-1 0 :angle 180\n1 0 :angle 180", name="circle")
SQUARE_PATH = pwc.compile_text("1 -1\n1 1\n-1 1\n-1 -1\n1 -1", name="square")


# ------------------------------------------------------------------------ helpers
def assert_watertight(solid: manifold3d.Manifold) -> trimesh.Trimesh:
    assert solid.status() == manifold3d.Error.NoError
    assert not solid.is_empty()
    assert solid.volume() > 0
    mesh = to_trimesh(solid)
    assert mesh.is_watertight
    assert mesh.is_winding_consistent
    assert np.isfinite(mesh.vertices).all()
    assert solid_info(solid)["watertight"]
    return mesh


def segment_distance(points: np.ndarray, a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """(n,) distance from each point to the nearest of the segments a[i]-b[i] (any dim)."""
    out = np.full(len(points), np.inf)
    d = b - a
    dd = np.maximum(np.einsum("ij,ij->i", d, d), 1e-300)
    for lo in range(0, len(points), 512):
        p = points[lo : lo + 512, None, :]
        t = np.clip(np.einsum("pki,ki->pk", p - a[None], d) / dd, 0.0, 1.0)
        dist = np.linalg.norm(a[None] + t[..., None] * d[None] - p, axis=-1)
        out[lo : lo + 512] = dist.min(axis=1)
    return out


def boundary_distance(points: np.ndarray, curve: pwc.Curve) -> np.ndarray:
    """(n,) exact distance from 2-D points to the cross-section's boundary.

    The boundary is the curve's pieces (segments and exact arcs) plus the straight
    closure back to the wall; each piece's distance is computed in closed form.
    """
    pt = curve.pt
    a, b = pt[:-1], pt[1:]
    if not curve.is_closed:
        closure = np.array([pt[-1], [0.0, pt[-1, 1]], [0.0, pt[0, 1]], pt[0]])
        a, b = np.vstack([a, closure[:-1]]), np.vstack([b, closure[1:]])
    arc = np.zeros(len(a), dtype=bool)
    arc[: len(pt) - 1] = curve.is_arc[1:]
    dist = np.full((len(points), len(a)), np.inf)
    seg = ~arc
    dist[:, seg] = np.stack(
        [segment_distance(points, a[i : i + 1], b[i : i + 1]) for i in np.flatnonzero(seg)], -1
    )
    for i in np.flatnonzero(arc):
        c, r = curve.center[i + 1], curve.radius[i + 1]
        p0, p1 = curve.start_angle[i + 1], curve.end_angle[i + 1]
        rel = points - c
        phi = np.arctan2(rel[:, 1], rel[:, 0])
        inside = np.mod(phi - min(p0, p1), 2 * np.pi) <= abs(p1 - p0)
        ends = np.minimum(
            np.linalg.norm(points - a[i], axis=1), np.linalg.norm(points - b[i], axis=1)
        )
        dist[:, i] = np.where(inside, np.abs(np.linalg.norm(rel, axis=1) - r), ends)
    return dist.min(axis=1)


def dense_curve_points(curve: pwc.Curve, n: int = 20001) -> np.ndarray:
    return curve.evaluate(np.linspace(0.0, 1.0, n))


def polygon_moments(polygons) -> tuple[float, float, float]:
    """Area and first moments (∬x, ∬y) of polygons by the shoelace formula."""
    a = mx = my = 0.0
    for p in polygons:
        x, y = p[:, 0], p[:, 1]
        x1, y1 = np.roll(x, -1), np.roll(y, -1)
        c = x * y1 - x1 * y
        a += c.sum() / 2
        mx += ((x + x1) * c).sum() / 6
        my += ((y + y1) * c).sum() / 6
    return a, mx, my


def volume_bound(solid: manifold3d.Manifold, tolerance: float) -> float:
    """|V_mesh - V_exact| when the surfaces are within ``tolerance`` of each other.

    The symmetric difference lies inside the ``tolerance`` shell around the surface,
    whose volume is at most 2 * tolerance * area (to first order).
    """
    return 2.0 * tolerance * solid.surface_area()


def revolution_distance(points: np.ndarray, curve: pwc.Curve) -> np.ndarray:
    """Distance from 3-D points to the exact solid of revolution of ``curve``.

    The nearest point of a surface of revolution lies in the point's meridian plane,
    so the distance is the 2-D distance of (rho, y) to the cross-section's boundary.
    """
    rho = np.hypot(points[:, 0], points[:, 2])
    return boundary_distance(np.c_[rho, points[:, 1]], curve)


def uv_grid(n: int) -> np.ndarray:
    g = np.linspace(0.0, 1.0, n)
    return np.stack(np.meshgrid(g, g, indexing="ij"), -1).reshape(-1, 2)


# ------------------------------------------------------------- exact area, centroid
def test_profile_area_and_centroid_of_simple_shapes():
    assert profile_area(RECT) == 1.0
    assert profile_centroid(RECT).tolist() == [0.5, 0.5]
    # quarter disc: area pi/4, centroid 4 / (3 pi) on both axes
    assert profile_area(QUARTER_DISC) == pytest.approx(math.pi / 4, rel=1e-14)
    np.testing.assert_allclose(profile_centroid(QUARTER_DISC), [4 / (3 * math.pi)] * 2, rtol=1e-14)
    # half disc of radius 1/2 centred at (0, 1/2): centroid x = 4 r / (3 pi)
    assert profile_area(SEMICIRCLE) == pytest.approx(math.pi / 8, rel=1e-14)
    np.testing.assert_allclose(profile_centroid(SEMICIRCLE), [2 / (3 * math.pi), 0.5], rtol=1e-14)


def test_profile_area_is_independent_of_direction():
    backwards = pwc.compile_text("0 1\n1 1\n1 0\n0 0")
    assert profile_area(backwards) == 1.0
    assert profile_centroid(backwards).tolist() == [0.5, 0.5]


def test_profile_area_of_closed_curve_ignores_the_wall():
    # the unit-radius circle path, away from the wall: area pi, centroid at the origin
    assert profile_area(CIRCLE_PATH) == pytest.approx(math.pi, rel=1e-14)
    np.testing.assert_allclose(profile_centroid(CIRCLE_PATH), [0, 0], atol=1e-15)


@pytest.mark.parametrize("name", ["right_angle_arc", "ornament_2", "corinthian", "cyma_recta",
                                  "flare", "scotia", "torus"])
def test_profile_area_matches_fine_polygon(name):
    # chords cut off circular segments whose area is <= chord * sagitta: the sampled
    # polygon's moments converge to the exact ones within perimeter * tolerance
    curve = load(name)
    tol = 1e-7
    polygons = section_polygons(curve, tol)
    a, mx, my = polygon_moments(polygons)
    perimeter = sum(
        np.linalg.norm(np.diff(p, axis=0, append=p[:1]), axis=1).sum() for p in polygons
    )
    assert abs(profile_area(curve) - a) <= perimeter * tol
    centroid = profile_centroid(curve)
    assert abs(centroid[0] * profile_area(curve) - mx) <= perimeter * tol
    assert abs(centroid[1] * profile_area(curve) - my) <= perimeter * tol


def test_profile_area_degenerate_and_crossing():
    along_wall = pwc.compile_text("0 0\n0 1")
    assert profile_area(along_wall) == 0.0
    with pytest.raises(ValueError, match="encloses no area"):
        profile_centroid(along_wall)
    with pytest.raises(ValueError, match="crosses itself"):
        profile_area(load("segments"))
    with pytest.raises(ValueError, match="pwc.Curve"):
        profile_area("profiles/rect.pwc")


# -------------------------------------------------------------------- the section
def test_section_of_open_profile_is_closed_along_the_wall():
    # starts and ends off the wall: joined by horizontals and the wall
    curve = pwc.compile_text("1 0\n1 1\n0.5 1")
    (loop,) = section_polygons(curve, 1e-3)
    assert loop.tolist() == [[1.0, 0.0], [1.0, 1.0], [0.5, 1.0], [0.0, 1.0], [0.0, 0.0]]


def test_section_of_segments_pwc_splits_at_the_crossing():
    # Listing 15.3's list, normalized by 3/4: its last point (3/7, 3/4) lies inside the
    # outline, so the horizontal back to the wall cuts the step at (9/28, 3/4); the
    # region is the stepped block plus the small triangle above that cut
    curve = load("segments")
    polygons = section_polygons(curve, 1e-3)
    area, _, _ = polygon_moments(polygons)
    block = 0.525 * 0.3 + 9 / 28 * (0.75 - 0.3)
    flag = 0.5 * (3 / 7 - 9 / 28) * (1.0 - 0.75)
    assert area == pytest.approx(block + flag, rel=1e-12)
    assert len(polygons) == 2
    # the crossing point is exact (the step's x, the last point's y), not rounded by
    # the polygon clipper; so is every other vertex
    crossing = [curve.pt[3, 0], curve.pt[5, 1]]
    vertices = np.vstack(polygons)
    assert (vertices == crossing).all(axis=1).sum() == 2  # once in each lobe
    others = vertices[~(vertices == crossing).all(axis=1)]
    closure = [[0.0, curve.pt[5, 1]], [0.0, 0.0]]
    assert all((np.vstack([curve.pt, closure]) == v).all(axis=1).any() for v in others)


# ------------------------------------------------------------------------ extrude
def test_extrude_rectangle_is_a_box():
    solid = extrude(RECT, 2.5)
    mesh = assert_watertight(solid)
    assert solid.volume() == pytest.approx(2.5, rel=1e-15)
    np.testing.assert_array_equal(mesh.bounds, [[0, 0, 0], [1, 1, 2.5]])
    assert solid.genus() == 0


@pytest.mark.parametrize("name", ["right_angle_arc", "ornament_2", "corinthian"])
@pytest.mark.parametrize("tol", [1e-3, 1e-5])
def test_extrude_volume_is_area_times_length(name, tol):
    curve = load(name)
    length = 3.0
    solid = extrude(curve, length, tol)
    assert_watertight(solid)
    # exactly the sampled section's area times the length ...
    a, _, _ = polygon_moments(section_polygons(curve, tol))
    assert solid.volume() == pytest.approx(a * length, rel=1e-12)
    # ... and within the chord error of the exact area
    perimeter = sum(
        np.linalg.norm(np.diff(p, axis=0, append=p[:1]), axis=1).sum()
        for p in section_polygons(curve, tol)
    )
    assert abs(solid.volume() - profile_area(curve) * length) <= perimeter * tol * length


@pytest.mark.parametrize("tol", [1e-6, 1e-3, 0.05, 1e6])
def test_extrude_respects_tolerance(tol):
    curve = load("right_angle_arc")
    length = 1.0
    mesh = assert_watertight(extrude(curve, length, tol))
    # the solid's cross-section half way along, cut in float64 by trimesh
    lines = trimesh.intersections.mesh_plane(mesh, [0, 0, 1], [0, 0, length / 2])
    a, b = lines[:, 0, :2], lines[:, 1, :2]
    # every exact curve point is within tol of the solid's section ...
    exact = dense_curve_points(curve)
    assert segment_distance(exact, a, b).max() <= tol + 1e-9
    # ... and every point of the section within tol of the exact boundary
    if tol < 1:
        probes = np.concatenate([a, b, 0.5 * (a + b), 0.25 * a + 0.75 * b])
        assert boundary_distance(probes, curve).max() <= tol + 1e-9


def test_extrude_huge_tolerance_keeps_only_pw_points():
    curve = load("right_angle_arc")
    solid = extrude(curve, 1.0, 1e6)
    assert_watertight(solid)
    (loop,) = section_polygons(curve, 1e6)
    assert len(loop) == len(curve.pt)  # arcs became chords; starts and ends on the wall
    assert solid.volume() == pytest.approx(polygon_moments([loop])[0], rel=1e-12)


def test_extrude_one_piece_profile():
    tol = 1e-4
    solid = extrude(SEMICIRCLE, 2.0, tol)
    assert_watertight(solid)
    assert abs(solid.volume() - 2.0 * math.pi / 8) <= 2.0 * tol * math.pi / 2 * 2.0


def test_extrude_behind_the_wall_and_crossing_profiles():
    behind = pwc.compile_text("0 0\n-1 0\n-1 1\n0 1")
    solid = extrude(behind, 1.0)
    assert_watertight(solid)
    assert solid.volume() == pytest.approx(1.0, rel=1e-15)
    # Listing 15.3: block plus flag, two solids touching along one edge
    seg = extrude(load("segments"), 2.0)
    assert_watertight(seg)
    block = 0.525 * 0.3 + 9 / 28 * (0.75 - 0.3)
    flag = 0.5 * (3 / 7 - 9 / 28) * 0.25
    assert seg.volume() == pytest.approx(2.0 * (block + flag), rel=1e-12)
    # a dentil band returns to the wall between its teeth: four separate blocks
    dentils = extrude(load("dentil_band"), 1.0)
    assert_watertight(dentils)
    assert len(dentils.decompose()) == 4


@pytest.mark.parametrize("length", [0.0, -1.0, math.nan, math.inf])
def test_extrude_rejects_bad_length(length):
    with pytest.raises(ValueError, match="length must be a positive finite"):
        extrude(RECT, length)


@pytest.mark.parametrize("tol", [0.0, -1e-3, math.nan, math.inf])
def test_bad_tolerance_is_rejected_everywhere(tol):
    for build in (lambda: extrude(RECT, 1.0, tol), lambda: revolve(RECT, tol),
                  lambda: sweep(RECT, CIRCLE_PATH, tol), lambda: frame(RECT, 4, 4, tol)):
        with pytest.raises(ValueError, match="tolerance must be a positive finite"):
            build()


def test_profile_along_the_wall_is_rejected():
    with pytest.raises(ValueError, match="encloses no area"):
        extrude(pwc.compile_text("0 0\n0 1\n0 2"), 1.0)


# ------------------------------------------------------------------------ revolve
def ngon_cylinder(n: int, r: float = 1.0, h: float = 1.0) -> float:
    return 0.5 * n * math.sin(2 * math.pi / n) * r * r * h


@pytest.mark.parametrize("tol", [1e-6, 1e-4, 1e-2, 0.5, 1e6])
def test_revolved_rectangle_is_a_cylinder(tol):
    solid = revolve(RECT, tol)
    assert_watertight(solid)
    assert solid.genus() == 0
    # the circle is divided into n equal segments with the fewest that keep the
    # sagitta at radius 1 within tol / 2 (at least 3)
    n = (solid.num_vert() - 2) // 2  # two axis vertices plus n on each of two rings
    sagitta = lambda k: 1 - math.cos(math.pi / k)  # noqa: E731
    assert n == 3 or sagitta(n) <= tol / 2 < sagitta(n - 1)
    assert solid.volume() == pytest.approx(ngon_cylinder(n), rel=1e-13)
    # the inscribed polygon holds the circle of radius 1 - tol / 2
    if tol < 1:
        assert math.pi * (1 - tol / 2) ** 2 <= solid.volume() <= math.pi


def test_revolve_with_given_segments():
    for n in (3, 4, 7, 64):
        solid = revolve(RECT, segments=n)
        assert_watertight(solid)
        assert solid.volume() == pytest.approx(ngon_cylinder(n), rel=1e-13)
    for bad in (2, 0, -5, 3.5, True, "8"):
        with pytest.raises(ValueError, match="segments must be an integer >= 3"):
            revolve(RECT, segments=bad)


@pytest.mark.parametrize("name", ["right_angle_arc", "ornament_2", "corinthian", "torus"])
@pytest.mark.parametrize("offset", [0.0, 0.3])
def test_revolve_volume_obeys_pappus(name, offset):
    curve = load(name)
    tol = 1e-4
    solid = revolve(curve, tol, radius_offset=offset)
    assert_watertight(solid)
    exact = 2 * math.pi * (profile_centroid(curve)[0] + offset) * profile_area(curve)
    assert abs(solid.volume() - exact) <= volume_bound(solid, tol)
    # a profile from wall to wall closes on the axis (genus 0) or round a core (genus 1)
    assert solid.genus() == (0 if offset == 0 else 1)


def test_revolve_touching_the_axis():
    tol = 1e-4
    # quarter disc against the axis: a hemisphere
    hemisphere = revolve(QUARTER_DISC, tol)
    assert_watertight(hemisphere)
    assert abs(hemisphere.volume() - 2 * math.pi / 3) <= volume_bound(hemisphere, tol)
    # a one-piece half circle: a sphere of radius 1/2
    sphere = revolve(SEMICIRCLE, tol)
    assert_watertight(sphere)
    assert abs(sphere.volume() - math.pi / 6) <= volume_bound(sphere, tol)
    # two cones whose apexes touch on the axis at (0, 1)
    cones = revolve(pwc.compile_text("0 0\n1 0\n0 1\n1 2\n0 2", normalize=False), tol)
    assert_watertight(cones)
    n = solids._segments_for(1.0, tol / 2)
    assert cones.volume() == pytest.approx(2 * ngon_cylinder(n) / 3, rel=1e-12)


def test_revolve_rejects_profiles_behind_the_axis():
    behind = pwc.compile_text("0 0\n-0.5 0\n-0.5 1\n0 1")
    with pytest.raises(ValueError, match=r"behind the axis.*radius_offset >= 0\.5"):
        revolve(behind, 1e-3)
    # with the offset that brings it to the axis: a cylinder of radius 1/2
    tube = revolve(behind, 1e-4, radius_offset=0.5)
    assert_watertight(tube)
    assert abs(tube.volume() - math.pi / 4) <= volume_bound(tube, 1e-4)
    # the exact arc dips behind the axis even where its chords do not
    dip = pwc.compile_text("0 0\n0 1 :angle -90")
    with pytest.raises(ValueError, match="behind the axis"):
        revolve(dip, 1e6)
    with pytest.raises(ValueError, match="radius_offset must be finite"):
        revolve(RECT, 1e-3, radius_offset=math.nan)


def test_revolve_agrees_with_pwc_angular_displace():
    """The solid and the displaced unit square of Listing 15.14 are the same surface."""
    curve = load("corinthian")
    tol = 1e-3
    solid = revolve(curve, tol)
    mesh = assert_watertight(solid)
    state = UnitSquare().state_at_uv(uv_grid(61))
    displaced = state.position + pwc_angular_displace(curve, "along_v")(state)
    _, distance, _ = trimesh.proximity.closest_point(mesh, displaced)
    assert distance.max() <= tol + 1e-9
    # and every point of the solid's surface is within tol of the exact surface
    rng = np.random.default_rng(7)
    samples, _ = trimesh.sample.sample_surface(mesh, 4000, seed=rng)
    probes = np.vstack([mesh.vertices, samples])
    assert revolution_distance(probes, curve).max() <= tol + 1e-9


@settings(max_examples=20)
@given(
    width=st.floats(0.05, 1.0),
    height=st.floats(0.05, 1.0),
    offset=st.floats(0.0, 2.0),
    n=st.integers(3, 200),
)
def test_revolved_rectangles_are_exact_prisms(width, height, offset, n):
    # a rectangle from x = 0 to w, revolved at offset r: an n-gon annulus (or cylinder)
    curve = pwc.compile_text(f"0 0\n{width} 0\n{width} {height}\n0 {height}", normalize=False)
    solid = revolve(curve, 1.0, radius_offset=offset, segments=n)
    assert_watertight(solid)
    expected = ngon_cylinder(n, width + offset, height) - ngon_cylinder(n, offset, height)
    assert solid.volume() == pytest.approx(expected, rel=1e-11)


@settings(max_examples=15)
@given(tol=st.floats(1e-4, 0.3), offset=st.floats(0.0, 1.0))
def test_revolve_volume_within_bound_for_any_tolerance(tol, offset):
    curve = load("ovolo")
    solid = revolve(curve, tol, radius_offset=offset)
    assert_watertight(solid)
    exact = 2 * math.pi * (profile_centroid(curve)[0] + offset) * profile_area(curve)
    assert abs(solid.volume() - exact) <= volume_bound(solid, tol)


# -------------------------------------------------------------------------- sweep
def test_sweep_round_a_circle_is_a_revolution():
    curve = load("right_angle_arc")
    tol = 1e-4
    solid = sweep(curve, CIRCLE_PATH, tol, radius_offset=0.25)
    assert_watertight(solid)
    assert solid.genus() == 1
    exact = 2 * math.pi * (profile_centroid(curve)[0] + 0.25) * profile_area(curve)
    assert abs(solid.volume() - exact) <= volume_bound(solid, tol)


@pytest.mark.parametrize("offset", [0.0, 0.5])
def test_sweep_round_a_square(offset):
    # |path(u)|^2 along one side (x = 1, y uniform in [-1, 1]) averages 1 + 1/3, and the
    # four equal sides are traversed at equal speed: the volume is Pappus' times 4/3
    tol = 1e-5
    solid = sweep(RECT, SQUARE_PATH, tol, radius_offset=offset)
    assert_watertight(solid)
    exact = 2 * math.pi * (0.5 + offset) * 1.0 * 4 / 3
    assert abs(solid.volume() - exact) <= volume_bound(solid, tol)


def test_sweep_corinthian_along_doric_flutes_agrees_with_double_pwc():
    """Listing 15.21's capital: the solid matches the displaced surface of double_pwc."""
    profile, path = load("corinthian"), load("doric_flutes")
    tol, offset = 1e-3, 0.25
    solid = sweep(profile, path, tol, radius_offset=offset)
    mesh = assert_watertight(solid)
    assert solid.genus() == 1
    # volume: 2 pi A (x̄ + r) * mean over u of |path(u)|^2 (midpoint rule, 2e6 samples)
    u = (np.arange(2_000_000) + 0.5) / 2_000_000
    mean_s2 = np.mean(np.sum(path.evaluate(u) ** 2, axis=-1))
    exact = 2 * math.pi * (profile_centroid(profile)[0] + offset) * profile_area(profile) * mean_s2
    assert abs(solid.volume() - exact) <= volume_bound(solid, tol)
    state = UnitSquare().state_at_uv(uv_grid(81))
    displaced = state.position + double_pwc(profile, path, radius_offset=offset)(state)
    _, distance, _ = trimesh.proximity.closest_point(mesh, displaced)
    assert distance.max() <= tol + 1e-9


def test_sweep_touching_the_axis_and_one_piece_profiles():
    tol = 1e-4
    solid = sweep(SEMICIRCLE, load("ionic_flutes"), tol)
    assert_watertight(solid)
    assert solid.genus() == 0


def test_sweep_rejects_open_paths_origin_and_negative_x():
    with pytest.raises(ValueError, match="must be closed"):
        sweep(RECT, pwc.compile_text("1 0\n0 2 :angle 90"), 1e-3)
    with pytest.raises(ValueError, match="passes through the origin"):
        sweep(RECT, pwc.compile_text("1 0\n-1 0\n1 0"), 1e-3)
    with pytest.raises(ValueError, match="behind the axis"):
        sweep(pwc.compile_text("0 0\n-1 0\n-1 1\n0 1"), CIRCLE_PATH, 1e-3)


def test_huge_tolerance_still_gives_valid_sweeps_and_frames():
    profile = load("corinthian")
    coarse = sweep(profile, load("doric_flutes"), 1e6, radius_offset=0.25)
    assert_watertight(coarse)
    assert coarse.genus() == 1
    assert_watertight(frame(profile, 4.0, 4.0, 1e6))


def test_closed_profiles_are_their_own_cross_section():
    # the unit circle (a closed curve) is not joined to the wall
    tol = 1e-4
    rod = extrude(CIRCLE_PATH, 2.0, tol)
    assert_watertight(rod)
    assert abs(rod.volume() - 2 * math.pi) <= volume_bound(rod, tol)
    # revolved about an axis 2 away: a torus of volume 2 pi * 2 * pi
    ring = revolve(CIRCLE_PATH, tol, radius_offset=2.0)
    assert_watertight(ring)
    assert ring.genus() == 1
    assert abs(ring.volume() - 4 * math.pi**2) <= volume_bound(ring, tol)


# -------------------------------------------------------------------------- frame
def test_frame_of_a_square_molding():
    solid = frame(RECT, 4.0, 3.0)
    mesh = assert_watertight(solid)
    assert solid.genus() == 1
    assert solid.volume() == pytest.approx(10.0, rel=1e-14)  # 4*3 - 2*1 outer minus hole
    np.testing.assert_array_equal(mesh.bounds, [[0, 0, 0], [4, 3, 1]])


@pytest.mark.parametrize("name", ["ornament_2", "right_angle_arc", "segments"])
def test_frame_volume_and_pieces(name):
    curve = load(name)
    tol, width, height = 1e-4, 5.0, 7.0
    solid = frame(curve, width, height, tol)
    assert_watertight(solid)
    # each piece of length L holds A (L - 2 ȳ), ȳ measured from the outer edge
    polygons = section_polygons(curve, tol)
    ymin = min(p[:, 1].min() for p in polygons)
    a, _, my = polygon_moments(polygons)
    ybar = my / a - ymin
    expected = a * (2 * width + 2 * height - 8 * ybar)
    assert solid.volume() == pytest.approx(expected, rel=1e-12)
    pieces = frame_pieces(curve, width, height, tol)
    for piece in pieces:
        assert_watertight(piece)
    assert sum(p.volume() for p in pieces) == pytest.approx(solid.volume(), rel=1e-12)
    if name != "segments":
        ybar = profile_centroid(curve)[1] - curve.bbox[0, 1]
        exact = profile_area(curve) * (2 * width + 2 * height - 8 * ybar)
        assert abs(solid.volume() - exact) <= volume_bound(solid, tol)
        assert solid.genus() == 1


def test_frame_pieces_are_cut_on_the_mitres():
    width, height = 5.0, 4.0
    pieces = frame_pieces(load("ornament_2"), width, height)
    bottom, right, top, left = (to_trimesh(p).vertices for p in pieces)
    # the bottom piece ends on the planes x = y and x + y = width, and nowhere else
    ends = bottom[(bottom[:, 0] < width / 2)]
    assert (ends[:, 0] == ends[:, 1]).all()
    ends = bottom[(bottom[:, 0] > width / 2)]
    assert (ends[:, 0] + ends[:, 1] == width).all()
    assert right[:, 0].max() == width and top[:, 1].max() == height and left[:, 0].min() == 0.0


def test_frame_rejects_too_small_openings():
    with pytest.raises(ValueError, match="needs width and height above twice the band"):
        frame(RECT, 2.0, 5.0)
    with pytest.raises(ValueError, match="width must be a positive finite"):
        frame(RECT, -1.0, 5.0)


# ----------------------------------------------------------------------- booleans
def test_booleans_on_solids():
    cylinder = revolve(RECT, segments=64)  # radius 1 about y, 0 <= y <= 1
    box = extrude(RECT, 1.0)  # [0, 1]^3: one quarter of the 64-gon
    v = cylinder.volume()
    assert (cylinder ^ box).volume() == pytest.approx(v / 4, rel=1e-12)
    assert (cylinder - box).volume() == pytest.approx(3 * v / 4, rel=1e-12)
    union = cylinder + box
    assert union.volume() == pytest.approx(v + 1 - v / 4, rel=1e-12)
    assert isinstance(union, manifold3d.Manifold)
    assert_watertight(union)


# ------------------------------------------------------------------------- export
@pytest.mark.parametrize("suffix", [".stl", ".3mf", ".obj", ".STL"])
def test_export_round_trip(tmp_path, suffix):
    solid = revolve(load("corinthian"), 1e-3)
    path = export(solid, tmp_path / f"capital{suffix}")
    assert path.exists() and path.stat().st_size > 0
    loaded = trimesh.load(path, force="mesh")
    assert loaded.is_watertight
    # STL stores float32: relative volume error ~ a few float32 epsilons
    assert loaded.volume == pytest.approx(solid.volume(), rel=1e-6)
    assert len(loaded.faces) == solid.num_tri()


def test_export_rejects_unknown_types(tmp_path):
    with pytest.raises(ValueError, match="unsupported file type '.step'"):
        export(extrude(RECT, 1.0), tmp_path / "x.step")
    with pytest.raises(ValueError, match="unsupported file type"):
        export(extrude(RECT, 1.0), tmp_path / "x")
    with pytest.raises(ValueError, match="empty"):
        export(manifold3d.Manifold(), tmp_path / "x.stl")


# ---------------------------------------------------------------------------- CLI
def run_cli(*argv) -> int:
    parser = argparse.ArgumentParser(prog="pwc")
    register(parser.add_subparsers())
    args = parser.parse_args(["solid", *map(str, argv)])
    return args.func(args)


@pytest.mark.parametrize(
    "shape",
    [["--extrude", "2"], ["--revolve"], ["--revolve", "--segments", "12"],
     ["--sweep", PROFILES / "ionic_flutes.pwc", "--radius-offset", "0.25"],
     ["--frame", "5", "6"]],
)
def test_cli_builds_and_reports(tmp_path, capsys, shape):
    out = tmp_path / "solid.stl"
    assert run_cli(PROFILES / "ornament_2.pwc", *shape, "-o", out, "--tolerance", "1e-3") == 0
    text = capsys.readouterr().out
    assert "volume" in text and "triangles" in text and "watertight  yes" in text
    loaded = trimesh.load(out, force="mesh")
    volume = float(text.split("volume")[1].split()[0])
    assert loaded.volume == pytest.approx(volume, rel=1e-6)


@pytest.mark.parametrize(
    "argv, status, message",
    [
        (["nowhere.pwc", "--revolve", "-o", "{tmp}/a.stl"], 3, "nowhere.pwc: no such file"),
        (["toros", "--revolve", "-o", "{tmp}/a.stl"], 3, "did you mean 'torus'?"),
        (["{profiles}/torus.pwc", "--revolve", "-o", "{tmp}/a.step"], 2,
         "unsupported output type '.step'"),
        (["torus", "--revolve", "-o", "{tmp}/a.ply"], 2, "unsupported output type '.ply'"),
        (["{profiles}/torus.pwc", "--revolve", "-o", "{tmp}/afile/a.stl"], 3,
         "afile is a file, not a folder"),
        (["torus", "--revolve", "-o", "/proc/a.stl"], 3, "does not accept new files"),
        (["{profiles}/doric_flutes.pwc", "--revolve", "-o", "{tmp}/a.stl"], 1,
         "behind the axis"),
        (["{profiles}/torus.pwc", "--frame", "1", "1", "-o", "{tmp}/a.stl"], 1,
         "twice the band"),
        (["{profiles}/torus.pwc", "--extrude", "2", "--radius-offset", "1", "-o",
          "{tmp}/a.stl"], 2, "--radius-offset applies only"),
        (["{profiles}/torus.pwc", "--revolve", "--tolerance", "0", "-o", "{tmp}/a.stl"], 1,
         "tolerance must be a positive"),
        (["{profiles}", "--revolve", "-o", "{tmp}/a.stl"], 3, "is a directory"),
    ],
)
def test_cli_errors_are_one_line(tmp_path, capsys, argv, status, message):
    (tmp_path / "afile").write_text("")
    argv = [a.format(tmp=tmp_path, profiles=PROFILES) for a in argv]
    assert run_cli(*argv) == status
    err = capsys.readouterr().err
    assert message in err
    assert err.startswith("pwc solid: error: ") and err.count("\n") == 1
    assert "Traceback" not in err


def test_cli_creates_the_output_folder_and_takes_names(tmp_path, capsys, monkeypatch):
    monkeypatch.chdir(tmp_path)
    out = tmp_path / "newdir" / "x.stl"
    assert run_cli("torus", "--revolve", "-o", out) == 0
    assert trimesh.load(out, force="mesh").is_watertight
    assert "of 'torus'" in capsys.readouterr().out


def test_cli_prints_compiler_errors(tmp_path, capsys):
    bad = tmp_path / "bad.pwc"
    bad.write_text("0 0\n1 0 :sagg 3\n")
    assert run_cli(bad, "--revolve", "-o", tmp_path / "a.stl") == 1
    err = capsys.readouterr().err
    assert f"{bad}:2:5: error: unknown point property ':sagg'" in err
    assert "Traceback" not in err


def test_cli_needs_exactly_one_shape(tmp_path, capsys):
    with pytest.raises(SystemExit) as exit_info:
        run_cli(PROFILES / "torus.pwc", "-o", tmp_path / "a.stl")
    assert exit_info.value.code == 2
    with pytest.raises(SystemExit):
        run_cli(PROFILES / "torus.pwc", "--revolve", "--extrude", "1", "-o", tmp_path / "a.stl")
