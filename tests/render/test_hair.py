"""render.hair: strands (checks with the strand, point and fix), their world-space curve
table, the fringe, and the frame of a hit (hair_hit) against a cylinder's closed form,
at the extremes: tiny and huge radii, rays grazing along the fibre, through the axis."""

from __future__ import annotations

import numpy as np
import pytest

from render.hair import (
    CURVE_COLUMNS,
    MAX_SEGMENT_RADII,
    MIN_RADIUS_ULPS,
    Strands,
    StrandsError,
    check_hair_bsdf,
    curve_point,
    fringe,
    from_table,
    hair_hit,
)

LINE = [[0.0, 0.0, 0.0], [1.0, 0.0, 0.0]]
BEZ = [[0.0, 0.0, 0.0], [1.0, 1.0, 0.0], [2.0, -1.0, 0.0], [3.0, 0.0, 0.0]]


# ------------------------------------------------------------------ strands and errors
def test_polylines_and_bezier_segments():
    s = Strands.polylines([LINE, [[0, 1, 0], [0, 2, 0], [1, 2, 0]]], radius=0.01)
    assert (s.kind, s.segment_count, s.strand_count) == ("linear", 3, 2)
    assert s.segments.tolist() == [0, 2, 3] and s.strand.tolist() == [0, 1, 1]
    b = Strands.bezier([BEZ + [[4, 1, 0], [5, 1, 0], [6, 0, 0]]],
                       radii=[[0.1, 0.1, 0.1, 0.05, 0.05, 0.05, 0.01]])
    assert (b.kind, b.segment_count) == ("bezier", 2) and b.segments.tolist() == [0, 3]
    assert np.allclose(b.points[:, 3], [0.1, 0.1, 0.1, 0.05, 0.05, 0.05, 0.01])


@pytest.mark.parametrize(("build", "kwargs", "match", "where"), [
    (Strands.polylines, {"strands": [[[0, 0, 0], [0, 0, 0], [1, 0, 0]]]},
     r"strand 1, points 1 and 2: a zero-length segment .* remove one of them", (0, 1)),
    (Strands.polylines, {"strands": [LINE, [[1, 0, 0], [1 + 1e-9, 0, 0]]]},
     r"strand 2, points 1 and 2: a zero-length segment", (1, 1)),
    (Strands.bezier, {"strands": [BEZ + [[3, 0, 0]] * 3]},
     r"strand 1, points 4 to 7: a zero-length Bézier segment .* remove three", (0, 3)),
    (Strands.bezier, {"strands": [BEZ[:3]]}, r"3 m \+ 1 control points .* got 3", (0, None)),
    (Strands.polylines, {"strands": [[[0, 0, 0]]]}, r"at least 2 points, got 1; add", (0, None)),
    (Strands.polylines, {"strands": [[[0, 0, 0], [1, np.nan, 0]]]},
     r"strand 1, point 2: coordinates must be finite", (0, 1)),
    (Strands.polylines, {"strands": [[[0, 0, 0], [1, 0]]]},
     r"strand 1, point 2: must be three numbers", (0, 1)),
    (Strands.polylines, {"strands": [LINE], "radius": 0.0}, r"radius must be a finite number > 0",
     (0, None)),
    (Strands.polylines, {"strands": [LINE], "radii": [[0.1]]},
     r"strand 1: 1 radii for 2 points; give one radius per point", (0, None)),
    (Strands.polylines, {"strands": [LINE], "radii": [[0.1, -0.1]]},
     r"strand 1, point 2: radius must be a finite number > 0, got -0.1", (0, 1)),
    (Strands.polylines, {"strands": [LINE, LINE], "radii": [[0.1, 0.1]]},
     r"radii has 1 lists for 2 strands", (None, None)),
    (Strands.polylines, {"strands": []}, r"points is empty", (None, None)),
    (Strands.polylines, {"strands": "abc"}, r"must be a list of strands", (None, None)),
])
def test_bad_strands_name_strand_point_and_fix(build, kwargs, match, where):
    with pytest.raises(StrandsError, match=match) as info:
        build(**kwargs)
    assert (info.value.strand, info.value.point) == where


def test_world_table_is_float32_and_transformed():
    s = Strands.polylines([[[0.1, 0.2, 0.3], [1.1, 0.2, 0.3]]], radius=0.01)
    t = np.diag([2.0, 2.0, 2.0, 1.0])
    t[:3, 3] = (1.0, 0.0, -1.0)
    p, segs, table = s.world(t)
    assert segs.tolist() == [0]
    assert table.shape == (1, CURVE_COLUMNS)
    assert np.allclose(p[:, :3], [[1.2, 0.4, -0.4], [3.2, 0.4, -0.4]], atol=1e-6)
    assert np.allclose(p[:, 3], 0.02)
    assert np.array_equal(p, p.astype(np.float32).astype(np.float64))  # as Embree holds them
    # a linear segment as the Bézier curve of the same line and radii
    for u in (0.0, 0.3, 1.0):
        x, y, z, r, dx, dy, dz = curve_point(table, 0, u)
        assert np.allclose([x, y, z, r], (1 - u) * p[0] + u * p[1])
        assert np.allclose([dx, dy, dz], p[1, :3] - p[0, :3])
    lo, hi = s.bounds(t)
    assert np.allclose(lo, [1.18, 0.38, -0.42]) and np.allclose(hi, [3.22, 0.42, -0.38])


@pytest.mark.parametrize("kind", ["linear", "bezier"])
def test_long_thin_segments_are_split_into_the_same_curve(kind, rng):
    pts = [[0, 0, 0], [1, 0.5, 0], [2, -0.5, 0.3], [3, 0, 0]]
    radii = [1e-3, 2e-3, 1e-3, 5e-4]
    s = (Strands.polylines([pts], radii=[radii]) if kind == "linear" else
         Strands.bezier([pts], radii=[radii]))
    p, segs, table = s.world(np.eye(4))
    assert len(segs) == len(table) > s.segment_count
    # each piece at most MAX_SEGMENT_RADII of its smallest radius long (control polygon)
    step = 1 if kind == "linear" else 3
    ctrl = p[segs[:, None] + np.arange(step + 1)]
    length = np.linalg.norm(np.diff(ctrl[:, :, :3], axis=1), axis=2).sum(axis=1)
    assert np.all(length <= MAX_SEGMENT_RADII * ctrl[:, :, 3].min(axis=1) * (1 + 1e-6))
    # the pieces trace the input curve: points of the pieces lie on it (float32)
    if kind == "bezier":
        orig = s.points
        for _ in range(50):
            row, u = rng.integers(len(table)), rng.uniform()
            x = np.array(curve_point(table, row, u)[:4])
            # its parameter on the whole curve
            k = len(table)
            big = (row + u) / k
            v = 1 - big
            want = (v**3 * orig[0] + 3 * big * v * v * orig[1] + 3 * big * big * v * orig[2]
                    + big**3 * orig[3])
            assert np.allclose(x, want, atol=1e-6)
    with pytest.raises(StrandsError, match=r"more than 4096 pieces: give a larger radius"):
        # (just above float32's 16 steps at |x| = 1e4, and 1.04e6 radii long)
        Strands.polylines([[[-1e4, 0, 0], [1e4, 0, 0]]], radius=0.0192).world(np.eye(4))


def test_split_tubes_are_traced_exactly_by_embree(rng):
    # r / L = 1e-5: unsplit, Embree hits rays 20 radii off the axis; split, within 1 %
    from render.embree import Curves, EmbreeScene

    r = 1e-5
    s = Strands.polylines([[[-0.5, 0.3, 0.0], [0.5, 0.3, 0.0]]], radius=r)
    p, segs, _ = s.world(np.eye(4))
    scene = EmbreeScene([Curves(p, segs, "linear")])
    off = np.linspace(0.0, 3 * r, 301)
    x = rng.uniform(-0.45, 0.45, len(off))
    h = scene.intersect(np.column_stack([x, 0.3 + off, np.full(len(off), 2.0)]),
                        np.tile([0.0, 0.0, -1.0], (len(off), 1)))
    hit = h.geom_id >= 0
    assert hit[off < 0.99 * r].all() and not hit[off > 1.01 * r].any()


def test_radius_below_float32_resolution_is_refused():
    far = np.eye(4)
    far[0, 3] = 1000.0
    ok = Strands.polylines([LINE], radius=1e-5)
    ok.world(np.eye(4))  # 1e-5 at |x| <= 1: 84 float32 steps
    with pytest.raises(StrandsError, match=r"strand 1, point 1: radius 1e-05 .* below float32's "
                       r"resolution .* give a larger radius, or move the strand nearer"):
        ok.world(far)
    assert MIN_RADIUS_ULPS * np.finfo(np.float32).eps * 1001 > 1e-5


def test_fringe_is_deterministic_and_valid():
    a, b = fringe(count=12, seed=3), fringe(count=12, seed=3)
    assert np.array_equal(a.points, b.points) and a.strand_count == 12
    assert a.segment_count == 36
    assert not np.array_equal(a.points, fringe(count=12, seed=4).points)
    t = fringe(start=(-1, 1, 0), end=(1, 1, 0), count=30, tassel=1.0, length=0.5)
    tops = t.points[t.segments[t.strand == 0][0]]
    assert tops[1] == pytest.approx(1.0)
    # the tassel's waist: strands gathered to the middle at 30 % of the length
    waist = t.points.reshape(30, 10, 4)[:, 3, 0]
    assert np.abs(waist).max() < 0.15
    with pytest.raises(StrandsError, match="count must be a whole number"):
        fringe(count=0)
    with pytest.raises(StrandsError, match="tassel must be in"):
        fringe(tassel=2.0)


def test_from_table():
    s = from_table({"type": "polylines", "points": [LINE], "radius": 0.02})
    assert s.kind == "linear" and np.allclose(s.points[:, 3], 0.02)
    s = from_table({"type": "bezier", "points": [BEZ], "radii": [[1e-3, 2e-3, 2e-3, 1e-3]]})
    assert s.kind == "bezier"
    assert from_table({"type": "fringe", "count": 4}).strand_count == 4
    for spec, key, match in (
        ({"type": "polyline"}, "type", "type must be one of 'polylines', 'bezier', 'fringe'"),
        ({"type": "bezier", "point": []}, "point", "unknown key 'point' .did you mean 'points'"),
        ({"type": "bezier"}, "type", "needs points"),
        ({"type": "polylines", "points": [LINE], "radius": 1, "radii": [[1, 1]]}, "radii",
         "not both"),
        ({"type": "fringe", "lenght": 1.0}, "lenght", "did you mean 'length'"),
    ):
        with pytest.raises(StrandsError, match=match) as info:
            from_table(spec)
        assert info.value.key == key


def test_hair_bsdf_arguments_must_be_constant():
    from render import material as M

    check_hair_bsdf(None)
    check_hair_bsdf(M.df.chiang_hair_bsdf(roughness_R=(0.2, 0.3)))
    with pytest.raises(ValueError, match="absorption_coefficient must be a constant"):
        check_hair_bsdf(M.df.chiang_hair_bsdf(
            absorption_coefficient=lambda state: np.ones((len(state), 3))))
    m = M.material(hair=M.df.chiang_hair_bsdf())
    assert m.hair.kind == "hair_bsdf"
    with pytest.raises(ValueError, match="material.hair must be a hair_bsdf"):
        M.material(hair=M.df.diffuse_reflection_bsdf())


# ------------------------------------------------------------------------ the frame
def _cylinder(radius, length=2.0, kind="linear"):
    """A straight strand along x from -length/2 to length/2: its curve table, one row
    (not split, whatever its radius: the kernel's frame of any row)."""
    a, b = np.array([-length / 2, 0, 0]), np.array([length / 2, 0, 0])
    if kind == "linear":
        s = Strands.polylines([[a, b]], radius=radius)
    else:
        s = Strands.bezier([[a, a + (b - a) / 3, a + 2 * (b - a) / 3, b]], radius=radius)
    p32 = s.points.astype(np.float32).astype(np.float64)
    if kind == "linear":
        p32 = np.array([p32[0] + (p32[1] - p32[0]) * c / 3 for c in range(4)])
    return p32.reshape(1, CURVE_COLUMNS)


def _f32(v):
    return np.asarray(v, dtype=np.float32).astype(np.float64)


def _rays(rng, n, radius):
    """Rays (float32 values, as Embree traces them) toward random points of the cylinder
    of ``radius`` about the x axis from random directions, with their closed-form entry:
    (origin, direction, t, entry normal)."""
    out = []
    while len(out) < n:
        d = rng.normal(size=3)
        d /= np.linalg.norm(d)
        q = np.array([0.0, d[1], d[2]])
        side = np.cross([1.0, 0.0, 0.0], q / np.linalg.norm(q))
        # the ray's closest approach to the axis: at h r along `side`
        c = np.array([rng.uniform(-0.5, 0.5), 0, 0]) + rng.uniform(-0.999, 0.999) * radius * side
        o, d = _f32(c - 3.0 * d), _f32(d)  # |d| = 1 to float32 rounding, as in the kernel
        # entry on y^2 + z^2 = r^2 in the stable form: from the closest approach back by
        # the half chord (the quadratic's roots cancel to 1e-5 relative at r = 1e-5)
        oq, dq = o[1:], d[1:]
        s_star = -(oq @ dq) / (dq @ dq)
        m = oq + s_star * dq
        if m @ m >= radius ** 2:
            continue
        t = s_star - np.sqrt(radius ** 2 - m @ m) / np.sqrt(dq @ dq)
        p = o + t * d
        out.append((o, d, t, np.array([0.0, p[1], p[2]]) / radius))
    return out


@pytest.mark.parametrize("kind", ["linear", "bezier"])
@pytest.mark.parametrize("radius", [1e-5, 0.01, 0.3, 5.0])
def test_hit_frame_is_the_cylinders(kind, radius, rng):
    table = _cylinder(radius, kind=kind)
    r32 = float(np.float32(radius))
    for o, d, t, nrm in _rays(rng, 200, r32):
        u = (o + t * d)[0] / 2.0 + 0.5  # Embree's u on the straight segment
        # Embree's t carries float32 error: a few float32 steps off changes nothing
        t32 = t * (1 + 4e-7 * rng.uniform(-1, 1))
        px, py, pz, nx, ny, nz, tx, ty, tz = hair_hit(table, 0, u, *o, *d, t32)
        n, p = np.array([nx, ny, nz]), np.array([px, py, pz])
        assert np.allclose([tx, ty, tz], [1, 0, 0])
        assert np.linalg.norm(n) == pytest.approx(1.0, abs=1e-12) and abs(n[0]) < 1e-12
        assert np.allclose(n, nrm, atol=1e-8 + 1e-13 / radius), (n, nrm)
        assert np.hypot(p[1], p[2]) == pytest.approx(r32, rel=1e-9)
        assert np.allclose(p, o + t * d, atol=4e-6 * (1.0 + radius))
        assert -(d @ n) >= 0.0  # the entry side


@pytest.mark.parametrize("angle", [1e-1, 1e-3, 1e-5, 1e-7, 1e-9, 0.0])
def test_grazing_along_the_fibre_is_finite(angle, rng):
    radius = 0.01
    table = _cylinder(radius)
    for _ in range(50):
        phi = rng.uniform(0, 2 * np.pi)
        d = np.array([np.cos(angle), np.sin(angle) * np.cos(phi), np.sin(angle) * np.sin(phi)])
        o = np.array([-3.0, radius * 0.5 * np.cos(phi + 1), radius * 0.5 * np.sin(phi + 1)])
        for u, t in ((0.0, 2.0), (0.5, 3.0), (1.0, 4.0)):
            out = np.array(hair_hit(table, 0, u, *o, *d, t))
            assert np.all(np.isfinite(out))
            n = out[3:6]
            assert np.linalg.norm(n) == pytest.approx(1.0) and abs(n[0]) < 1e-9


def test_ray_through_the_axis_and_degenerate_tangent():
    table = _cylinder(0.1)
    # straight through the axis: h = 0, the normal faces the ray
    out = hair_hit(table, 0, 0.5, 0.0, 0.0, 3.0, 0.0, 0.0, -1.0, 2.9)
    assert np.allclose(out[3:6], [0, 0, 1]) and np.allclose(out[:3], [0, 0, 0.1])
    # a Bézier segment whose end control points repeat: c'(0) = 0, the chord instead
    s = Strands.bezier([[[0, 0, 0], [0, 0, 0], [1, 0, 0], [1, 0, 0]]], radius=0.1)
    table = s.world(np.eye(4))[2]
    out = hair_hit(table, 0, 0.0, 0.0, 0.0, 3.0, 0.0, 0.0, -1.0, 2.9)
    assert np.allclose(out[6:9], [1, 0, 0]) and np.all(np.isfinite(out))
