"""render.embree: Embree 4 called from numba, checked against embreex and geometry.

The RTCRayHit layout is verified by experiment (known hits give known ids, normals and
barycentrics); every query agrees with embreex's ``EmbreeScene.run`` on the same rays.
"""

from __future__ import annotations

import threading

import numba
import numpy as np
import pytest
import trimesh
from embreex import rtcore_scene
from embreex.mesh_construction import TriangleMesh

from render import embree
from render.embree import (
    MISS,
    EmbreeScene,
    intersect1,
    intersect_packets,
    intersect_rays,
    new_scratch,
    occluded1,
    occluded_packets,
    occluded_rays,
)
from render.jit import njit

F32_ULP = np.float32(2.0**-23)


def _meshes():
    """A trimesh icosphere and a second mesh (a box beside it)."""
    s = trimesh.creation.icosphere(subdivisions=4)
    b = trimesh.creation.box(extents=(0.8, 1.5, 0.6))
    b.apply_translation((1.7, 0.2, -0.3))
    return [(np.asarray(m.vertices, np.float32), np.asarray(m.faces, np.uint32)) for m in (s, b)]


@pytest.fixture(scope="module")
def meshes():
    return _meshes()


@pytest.fixture(scope="module")
def scene(meshes):
    with EmbreeScene(meshes) as s:
        yield s


@pytest.fixture(scope="module")
def reference(meshes):
    ref = rtcore_scene.EmbreeScene()
    for v, f in meshes:
        TriangleMesh(ref, v, f.astype(np.int32))
    return ref


def _random_rays(rng, n):
    """Origins around both meshes, aimed at random points of a box about them."""
    o = rng.uniform(-3.0, 4.0, (n, 3)).astype(np.float32)
    aim = rng.uniform([-1.5, -1.5, -1.5], [2.5, 1.5, 1.5], (n, 3))
    return o, (aim - o).astype(np.float32)


def _within_ulps(a, b, ulps=2):
    return np.abs(a - b) <= ulps * F32_ULP * np.maximum(np.abs(a), np.abs(b)) + 1e-30


# ----------------------------------------------------------------- layout by experiment

def test_layout_ids_normal_barycentrics_and_record_size():
    """A known triangle of the second mesh: ids, Ng = (v1-v0) x (v2-v0), u/v as
    p = (1-u-v) v0 + u v1 + v v2, and Embree writes nothing past the 96-byte record."""
    tri_v = np.float32([[0, 0, 0], [2, 0, 0], [0, 3, 0], [5, 5, 5]])
    other = np.float32([[10, 10, 10], [11, 10, 10], [10, 11, 10]])
    meshes = [(other, np.uint32([[0, 1, 2]])),
              (tri_v, np.uint32([[0, 1, 3], [1, 0, 2]]))]  # the hit is prim 1, geom 1
    v0, v1, v2 = tri_v[1], tri_v[0], tri_v[2]
    with EmbreeScene(meshes) as s:
        scratch = new_scratch()
        w = scratch.view(np.uint32)
        scratch[24:] = 12345.0
        t, u, v, prim, geom, nx, ny, nz = intersect1(
            s.handle, 0.5, 0.75, 2.0, 0.0, 0.0, -1.0, 0.0, np.inf, scratch)
        assert (prim, geom) == (1, 1)
        assert t == pytest.approx(2.0, rel=1e-6)
        ng = np.cross(v1 - v0, v2 - v0)
        np.testing.assert_allclose([nx, ny, nz], ng, rtol=1e-6)
        p = (1 - u - v) * v0 + u * v1 + v * v2
        np.testing.assert_allclose(p, [0.5, 0.75, 0.0], atol=1e-6)
        assert w[embree._INST] == 0xFFFFFFFF  # instID[0]: no instance
        assert w[embree._INST_PRIM] == 0xFFFFFFFF  # instPrimID[0] (instance arrays on)
        assert (scratch[24:] == 12345.0).all()


def test_barycentrics_reconstruct_random_hits(scene, meshes, rng):
    o, d = _random_rays(rng, 4000)
    h = scene.intersect(o, d)
    hit = h.geom_id >= 0
    assert hit.sum() > 1000
    p_ray = o[hit] + h.t[hit, None] * d[hit]
    p_bary = np.empty_like(p_ray)
    for g, (v, f) in enumerate(meshes):
        m = h.geom_id[hit] == g
        tri = v[f[h.prim_id[hit][m]]].astype(np.float64)
        uu, vv = h.u[hit][m, None], h.v[hit][m, None]
        p_bary[m] = (1 - uu - vv) * tri[:, 0] + uu * tri[:, 1] + vv * tri[:, 2]
        ng = np.cross(tri[:, 1] - tri[:, 0], tri[:, 2] - tri[:, 0])
        np.testing.assert_allclose(h.ng[hit][m], ng, rtol=1e-4, atol=1e-6)
    np.testing.assert_allclose(p_ray, p_bary, atol=2e-6 * 6)


# ------------------------------------------------------------------ against embreex

def test_intersect_agrees_with_embreex(scene, reference, rng):
    o, d = _random_rays(rng, 20000)
    h = scene.intersect(o, d)
    r = reference.run(o, d, output=1)
    np.testing.assert_array_equal(h.geom_id, r["geomID"])
    np.testing.assert_array_equal(h.prim_id, r["primID"])
    hit = h.geom_id >= 0
    assert 0.2 < hit.mean() < 0.9
    assert _within_ulps(h.t[hit], r["tfar"][hit]).all()
    for k in ("u", "v"):
        assert (np.abs(getattr(h, k)[hit] - r[k][hit]) <= 2 * F32_ULP).all()
    # packets of 8 (rtcIntersect8) give the same hits, bit for bit
    p = intersect_packets(scene.handle, o, d, np.zeros(len(o), np.float32),
                          np.full(len(o), np.inf, np.float32))
    for a, b in zip(p, h, strict=True):
        np.testing.assert_array_equal(a, b)


def test_occluded_agrees_with_embreex_and_intersect(scene, reference, rng):
    o, d = _random_rays(rng, 20000)
    tfar = rng.uniform(0.0, 3.0, len(o)).astype(np.float32)
    occ = scene.occluded(o, d, tfar=tfar)
    ref = reference.run(o, d, dists=tfar.copy(), query="OCCLUDED")
    np.testing.assert_array_equal(occ, ref >= 0)
    assert 0.1 < occ.mean() < 0.9
    np.testing.assert_array_equal(occ, scene.intersect(o, d, tfar=tfar).geom_id >= 0)
    lo, hi = np.zeros(len(o), np.float32), tfar
    np.testing.assert_array_equal(occluded_packets(scene.handle, o, d, lo, hi), occ)


# ------------------------------------------------------------------ conventions

def test_misses_leave_t_and_mark_ids(scene):
    o = np.float32([[0, 0, 5], [0, 0, 5], [0, 10, 0]])
    d = np.float32([[0, 0, 1], [1, 0, 0], [0, 1, 0]])
    for tfar in (np.inf, 7.5):
        h = scene.intersect(o, d, tfar=tfar)
        assert (h.geom_id == MISS).all() and (h.prim_id == MISS).all()
        assert (h.t == np.float32(tfar)).all()
        assert (h.u == 0).all() and (h.v == 0).all() and (h.ng == 0).all()
    assert not scene.occluded(o, d).any()


def test_tnear_and_tfar_are_honoured(scene):
    """Down the z axis through the unit sphere: surfaces at t = 2 and 4 from z = 3."""
    o, d = np.float32([[0, 0, 3]]), np.float32([[0, 0, -1]])
    assert scene.intersect(o, d).t[0] == pytest.approx(2.0, rel=1e-3)
    far = scene.intersect(o, d, tnear=2.5)
    assert far.t[0] == pytest.approx(4.0, rel=1e-3) and far.geom_id[0] == 0
    assert far.ng[0, 2] < 0  # the far side faces away from z
    assert scene.intersect(o, d, tfar=1.9).geom_id[0] == MISS
    assert scene.intersect(o, d, tnear=4.1).geom_id[0] == MISS
    assert not scene.occluded(o, d, tfar=1.9)[0] and scene.occluded(o, d, tfar=2.1)[0]
    assert not scene.occluded(o, d, tnear=4.1)[0]


def test_axis_parallel_and_grazing_rays(reference, scene, meshes):
    """Axis-parallel rays (zero direction components) onto the box's faces hit at the
    exact distance; rays grazing the box face hit or miss as embreex says."""
    vb = meshes[1][0]
    box = EmbreeScene([(vb, meshes[1][1])])
    lo, hi = vb.min(axis=0), vb.max(axis=0)
    c = (lo + hi) / 2
    o, d, t = [], [], []
    for axis in range(3):
        for sign in (-1, 1):
            p = c.copy()
            p[axis] = c[axis] + sign * 5.0
            dd = np.zeros(3, np.float32)
            dd[axis] = -sign
            o.append(p)
            d.append(dd)
            t.append(5.0 - (hi - c)[axis])
    h = box.intersect(np.array(o), np.array(d))
    assert (h.geom_id == 0).all()
    np.testing.assert_allclose(h.t, t, rtol=1e-6)
    box.close()
    # grazing: along the +x face at tiny angles, starting outside the box
    eps = np.float32([0.0, 1e-7, 1e-5, 1e-3, -1e-7, -1e-5, -1e-3])
    g_o = np.tile(np.float32([hi[0] + 1e-4, c[1], hi[2] + 1.0]), (len(eps), 1))
    g_d = np.stack([-eps, np.zeros_like(eps), -np.ones_like(eps)], axis=1).astype(np.float32)
    hg = scene.intersect(g_o, g_d)
    r = reference.run(g_o, g_d, output=1)
    np.testing.assert_array_equal(hg.prim_id, r["primID"])
    assert (hg.geom_id[eps >= 1e-3] == 1).all() and (hg.geom_id[eps <= 0] == MISS).all()


def test_rays_from_exactly_on_a_surface(scene, reference, meshes, rng):
    """Origins on sphere triangles: with tnear = 0 about half re-hit their own triangle at
    t ~ 0 (as embreex); with tnear = 1e-4 none does, and rays into the sphere find the
    far side."""
    v, f = meshes[0]
    k = rng.integers(0, len(f), 2000)
    b = rng.dirichlet([1, 1, 1], len(k))
    p = np.einsum("ij,ijk->ik", b, v[f[k]].astype(np.float64)).astype(np.float32)
    n = np.cross(v[f[k, 1]] - v[f[k, 0]], v[f[k, 2]] - v[f[k, 0]])
    n = (n / np.linalg.norm(n, axis=1, keepdims=True)).astype(np.float32)
    for sign in (1, -1):
        h = scene.intersect(p, sign * n)
        np.testing.assert_array_equal(h.prim_id, reference.run(p, sign * n, output=1)["primID"])
        h2 = scene.intersect(p, sign * n, tnear=1e-4)
        assert not ((h2.prim_id == k) & (h2.geom_id == 0)).any()
    inward = scene.intersect(p, -n, tnear=1e-4)
    assert (inward.geom_id == 0).all() and (inward.t > 0.5).all()


def test_degenerate_triangles_are_never_hit():
    v = np.float32([[0, 0, 0], [1, 0, 0], [0, 1, 0], [2, 0, 0], [0.5, 0.5, 0]])
    f = np.uint32([[0, 0, 1], [0, 1, 3], [1, 1, 1], [0, 1, 2], [1, 4, 2]])  # 0-2, 4 zero area
    with EmbreeScene([(v, f)]) as s:
        xs = np.linspace(-0.1, 2.1, 45, dtype=np.float32)
        o = np.stack(np.meshgrid(xs, xs), -1).reshape(-1, 2)
        o = np.concatenate([o, np.ones((len(o), 1))], 1).astype(np.float32)
        d = np.tile(np.float32([0, 0, -1]), (len(o), 1))
        h = s.intersect(o, d)
        inside = (o[:, 0] > 0) & (o[:, 1] > 0) & (o[:, 0] + o[:, 1] < 1)
        border = np.isclose(o[:, 0], 0) | np.isclose(o[:, 1], 0) | np.isclose(o.sum(1) - 1, 1)
        assert set(h.prim_id[h.geom_id >= 0].tolist()) == {3}
        assert (h.prim_id[inside & ~border] == 3).all()
        # along the degenerate segment y = 0, grazing in its line
        g = s.intersect(np.float32([[-1, 0, 0]]), np.float32([[1, 0, 0]]))
        assert g.prim_id[0] in (MISS, 3)


def test_empty_scene_and_empty_mesh():
    rays = (np.zeros((3, 3), np.float32), np.eye(3, dtype=np.float32))
    with EmbreeScene([]) as s:
        h = s.intersect(*rays)
        assert (h.geom_id == MISS).all() and np.isinf(h.t).all()
        assert not s.occluded(*rays).any()
    tri = (np.float32([[-1, -1, 1], [1, -1, 1], [0, 2, 1]]), np.uint32([[0, 1, 2]]))
    empty = (np.zeros((0, 3), np.float32), np.zeros((0, 3), np.uint32))
    with EmbreeScene([empty, tri]) as s:
        h = s.intersect(*rays)
        assert h.geom_id.tolist() == [MISS, MISS, 1] and h.prim_id[2] == 0


@pytest.mark.parametrize("scale", [1e12, 2.0**40, 1e-12, 2.0**-40])
def test_huge_and_tiny_scenes_trace_like_the_unit_scene(meshes, scale, rng):
    """Hits agree with the unit scene up to float32 rounding for scene lengths from
    1e-12 to 1e12 (Embree's float32 products of three lengths stay normal there)."""
    v, f = meshes[0]
    o = np.tile(np.float32([0.01, -0.02, 0.03]), (3000, 1))
    d = rng.normal(size=(3000, 3)).astype(np.float32)
    with EmbreeScene([(v, f)]) as unit, EmbreeScene([(v * np.float32(scale), f)]) as big:
        h1 = unit.intersect(o, d)
        h = big.intersect(o * np.float32(scale), d)
    assert (h1.geom_id == 0).all()
    np.testing.assert_array_equal(h.prim_id, h1.prim_id)
    np.testing.assert_allclose(h.t / np.float32(scale), h1.t, rtol=1e-6)


def test_huge_tfar_and_direction_lengths(scene, rng):
    """t is in units of |d|: directions scaled by 1e-12 .. 1e30, tfar 1e30."""
    o, d = _random_rays(rng, 2000)
    h1 = scene.intersect(o, d)
    for s in (1e-12, 1e12, 1e30):
        h = scene.intersect(o, d * np.float32(s), tfar=1e30)
        np.testing.assert_array_equal(h.prim_id, h1.prim_id)
        hit = h.geom_id >= 0
        np.testing.assert_allclose(h.t[hit] * np.float32(s), h1.t[hit], rtol=1e-6)


def test_vertices_beyond_embree_range_are_refused(meshes):
    v, f = meshes[0]
    with pytest.raises(ValueError, match=r"mesh 1: vertex 0 .*1\.844e\+18.*rescale"):
        EmbreeScene([(v, f), (v * np.float32(1e30), f)])
    bad = v.copy()
    bad[5, 1] = np.nan
    with pytest.raises(ValueError, match="mesh 0: vertex 5"):
        EmbreeScene([(bad, f)])


# ------------------------------------------------------------------ threads

def test_threads_give_the_same_hits(scene, rng):
    o, d = _random_rays(rng, 30000)
    lo, hi = np.zeros(len(o), np.float32), np.full(len(o), np.inf, np.float32)
    numba.set_num_threads(1)
    try:
        one = intersect_rays(scene.handle, o, d, lo, hi)
        one_occ = occluded_rays(scene.handle, o, d, lo, hi)
    finally:
        numba.set_num_threads(numba.config.NUMBA_NUM_THREADS)
    two = intersect_rays(scene.handle, o, d, lo, hi)
    for a, b in zip(one, two, strict=True):
        np.testing.assert_array_equal(a, b)
    np.testing.assert_array_equal(one_occ, occluded_rays(scene.handle, o, d, lo, hi))
    # two Python threads, each with its own scratch, in a serial-looking kernel
    out = [None, None]

    def work(k):
        out[k] = _serial_t(scene.handle, o, d)

    ts = [threading.Thread(target=work, args=(k,)) for k in range(2)]
    for t in ts:
        t.start()
    for t in ts:
        t.join()
    np.testing.assert_array_equal(out[0], one[0])
    np.testing.assert_array_equal(out[1], one[0])


@njit(allocates=True)
def _serial_t(scene, o, d):
    scratch = new_scratch()
    t = np.empty(o.shape[0], np.float32)
    for i in range(o.shape[0]):
        t[i] = intersect1(scene, o[i, 0], o[i, 1], o[i, 2], d[i, 0], d[i, 1], d[i, 2],
                          0.0, np.inf, scratch)[0]
        if occluded1(scene, o[i, 0], o[i, 1], o[i, 2], d[i, 0], d[i, 1], d[i, 2],
                     0.0, np.inf, scratch) != (t[i] < np.inf):
            t[i] = np.nan
    return t


def test_one_device_created_once_across_threads(meshes):
    scenes = []
    ts = [threading.Thread(target=lambda: scenes.append(EmbreeScene(meshes))) for _ in range(4)]
    for t in ts:
        t.start()
    for t in ts:
        t.join()
    assert len(scenes) == 4 and embree._device is not None
    assert embree._get_device() == embree._device
    for s in scenes:
        s.close()


# ------------------------------------------------------------------ errors

@pytest.mark.parametrize(
    ("mesh", "match"),
    [
        ((np.zeros((3, 3), np.int32), np.uint32([[0, 1, 2]])), "mesh 0: vertices must be a float"),
        ((np.zeros((3, 2), np.float32), np.uint32([[0, 1, 2]])), r"vertices .* \(3, 2\)"),
        ((np.zeros((3, 3), np.float32), np.float32([[0, 1, 2]])), "faces must be an integer"),
        ((np.zeros((3, 3), np.float32), np.uint32([0, 1, 2])), r"faces .* \(3,\)"),
        ((np.zeros((3, 3), np.float32), np.int64([[0, 1, 3]])), r"indices must lie in \[0, 3\)"),
        ((np.zeros((3, 3), np.float32), np.int64([[0, -1, 2]])), r"indices must lie in \[0, 3\)"),
    ],
)
def test_bad_meshes_give_clear_errors(mesh, match):
    with pytest.raises(ValueError, match=match):
        EmbreeScene([mesh])


def test_bad_rays_scratch_and_closed_scene_give_clear_errors(meshes):
    s = EmbreeScene(meshes)
    with pytest.raises(ValueError, match=r"origins must be a real \(n, 3\) array"):
        s.intersect(np.zeros((4, 2)), np.zeros((4, 3)))
    with pytest.raises(ValueError, match="differ in length: 4 != 5"):
        s.occluded(np.zeros((4, 3)), np.ones((5, 3)))
    with pytest.raises(ValueError, match=r"tfar must be a real scalar or an \(4,\) array"):
        s.intersect(np.zeros((4, 3)), np.ones((4, 3)), tfar=np.ones(3))
    with pytest.raises(ValueError, match="new_scratch"):
        intersect1(s.handle, 0.0, 0.0, 0.0, 0.0, 0.0, 1.0, 0.0, np.inf,
                   np.zeros(8, np.float32))
    with pytest.raises(TypeError, match="mesh 0: expected a \\(vertices, faces\\) pair"):
        EmbreeScene([np.zeros((3, 3))])
    with pytest.raises(ValueError, match="quality must be one of"):
        EmbreeScene(meshes, quality="best")
    s.close()
    s.close()
    with pytest.raises(ValueError, match="closed"):
        s.handle  # noqa: B018


# ------------------------------------------------------------------ round curves (hair)
def _straight_curve(kind, radius=0.1):
    """A straight round curve along x from -1 to 1, beside a triangle far away."""
    if kind == "linear":
        pts = [[-1, 0, 0, radius], [1, 0, 0, radius]]
    else:
        pts = [[-1, 0, 0, radius], [-1 / 3, 0, 0, radius], [1 / 3, 0, 0, radius],
               [1, 0, 0, radius]]
    tri = (np.array([[0, 0, -50], [1, 0, -50], [0, 1, -50]], np.float32),
           np.array([[0, 1, 2]], np.uint32))
    return EmbreeScene([tri, embree.Curves(np.array(pts, float), np.array([0]), kind)])


@pytest.mark.parametrize("kind", ["linear", "bezier"])
def test_round_curves_hits_u_and_normals(kind, rng):
    with _straight_curve(kind) as scene:
        n = 400
        x = rng.uniform(-0.9, 0.9, n)
        b = rng.uniform(-0.099, 0.099, n)  # offset across the tube
        o = np.column_stack([x, b, np.full(n, 3.0)])
        d = np.tile([0.0, 0.0, -1.0], (n, 1))
        h = scene.intersect(o, d)
        assert np.all(h.geom_id == 1) and np.all(h.prim_id == 0)
        # the tube's surface, the curve parameter along it, its outward normal
        assert np.allclose(h.t, 3.0 - np.sqrt(0.01 - b**2), atol=2e-5)
        assert np.allclose(h.u, (x + 1) / 2, atol=1e-5)
        ng = h.ng / np.linalg.norm(h.ng, axis=1)[:, None]
        p = o + h.t[:, None] * d
        assert np.allclose(ng, np.column_stack([np.zeros(n), p[:, 1:]]) / 0.1, atol=1e-3)
        # from inside: the far wall, its normal along the ray
        inner = scene.intersect(np.column_stack([x, np.zeros(n), np.zeros(n)]), d)
        assert np.all(inner.geom_id == 1) and np.allclose(inner.t, 0.1, atol=1e-5)
        assert np.all(np.einsum("ij,ij->i", inner.ng, d) > 0)
        # exactly along the axis Embree sees no tube (nor the linear curve's end sphere)
        along = scene.intersect([[-3.0, 0.0, 0.0], [3.0, 0.0, 0.0]],
                                [[1.0, 0.0, 0.0], [-1.0, 0.0, 0.0]])
        assert np.all(along.geom_id == MISS)
        # the linear curve's ends are spheres; the Bézier curve is open
        end = scene.intersect([[1.05, 0.0, 3.0]], [[0.0, 0.0, -1.0]])
        assert end.geom_id[0] == (1 if kind == "linear" else MISS)


def test_bad_curves_give_clear_errors():
    good = np.array([[0, 0, 0, 0.1], [1, 0, 0, 0.1]], float)
    for curves, match in (
        (embree.Curves(good[:, :3], np.array([0]), "linear"), r"points must be \(n, 4\)"),
        (embree.Curves(good, np.array([0]), "spline"), "kind must be 'linear' or 'bezier'"),
        (embree.Curves(good, np.array([1]), "linear"), "past the 2 points"),
        (embree.Curves(good, np.array([0]), "bezier"), "past the 2 points"),
        (embree.Curves(good, np.array([-1]), "linear"), "indices must be >= 0"),
        (embree.Curves(good * [1, 1, 1, -1], np.array([0]), "linear"), "radii >= 0"),
    ):
        with pytest.raises(ValueError, match=match):
            EmbreeScene([curves])


@pytest.mark.parametrize(("kind", "fat"), [("linear", 10.0), ("bezier", 1.2)])
def test_thin_long_round_curves_are_traced_too_thick(kind, fat, rng):
    # measured: Embree's round curves are exact where radius / length >~ 1e-3; at 1e-5 it
    # hits rays many radii off the axis (render.hair splits such segments, MAX_SEGMENT_RADII)
    def reach(r, length):
        a, b = np.array([-length / 2, 0.3, 0.0]), np.array([length / 2, 0.3, 0.0])
        pts = ([[*a, r], [*b, r]] if kind == "linear" else
               [[*(a + (b - a) * c / 3), r] for c in range(4)])
        with EmbreeScene([embree.Curves(np.array(pts), np.array([0]), kind)]) as scene:
            off = np.linspace(0.0, 30 * r, 601)
            x = rng.uniform(-0.3 * length, 0.3 * length, len(off))
            h = scene.intersect(np.column_stack([x, 0.3 + off, np.full(len(off), 2.0)]),
                                np.tile([0.0, 0.0, -1.0], (len(off), 1)))
            return off[h.geom_id >= 0].max() / r

    assert reach(1e-5, 1.0) > fat  # r / L = 1e-5
    assert reach(4e-3, 1.0) < 1.03  # r / L = 1 / MAX_SEGMENT_RADII


def test_the_cycle_rate_is_steady_as_its_span_grows():
    """:func:`render.embree.cycle_rate` measures the time-stamp counter from the process's
    first call on: a later call, over a span 30 times longer, agrees with the first
    (a constant-rate counter) to 5 %."""
    import time

    first = embree.cycle_rate()
    time.sleep(0.03)
    later = embree.cycle_rate()
    assert 1e8 < first < 1e11 and abs(later / first - 1) < 0.05
