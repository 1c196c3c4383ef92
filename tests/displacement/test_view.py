"""Tests of displacement.view and ``pwc view``: scene data, and real off-screen
screenshots whose grid lines are checked against where the displacement must put them.

The oracle profile is "slant": pw-points (0, 0), (0, 1), (1, 2), normalized to (0, 0),
(0, 0.5), (0.5, 1) (x = depth, y = run).  Its length is L = 0.5 + sqrt(1/2); at arc
length a = v L a point of the unit square displaced along v (Listing 15.8) goes to
(u, y(a), x(a)) with (x, y) = (0, a) for a <= 1/2 (a flat run) and
((a - 1/2) / sqrt 2, 1/2 + (a - 1/2) / sqrt 2) beyond (a 45-degree slope).  The grid's
v lines (cell count 4 L) lie at v = k / (4 L), i.e. at arc lengths a = k / 4.
"""

from __future__ import annotations

import math
import os
import subprocess

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from PIL import Image
from repo import PWC, ROOT, checkout_env
from scipy.ndimage import distance_transform_edt

import pwc
from displacement import view
from displacement.camera import Camera

PROFILES = ROOT / "profiles"
SQRT_HALF = math.sqrt(0.5)
L_SLANT = 0.5 + SQRT_HALF
SIZE = 300
BG_GREY = 218          # sRGB-encoded 0.7, the grid material's background (Listing 14.6)
DARK = BG_GREY // 2    # a pixel darker than this is grid line


@pytest.fixture(scope="module")
def slant():
    return pwc.compile_text("0 0\n0 1\n1 2", name="slant")


def slant_point(a):
    """(x = depth, y = run) of the slant profile at arc length a (by hand, see above)."""
    a = np.asarray(a, dtype=np.float64)
    s = np.maximum(a - 0.5, 0.0) * SQRT_HALF
    return np.stack([s, np.minimum(a, 0.5) + s], axis=-1)


def displaced_slant(uv, repeat=None):
    """(n, 3) points of the unit square displaced along v by slant (Listing 15.8),
    with Listing 14.27's repeat: frac(v r), the point / r, run offset floor(v r) / r."""
    uv = np.asarray(uv, dtype=np.float64)
    u, v = uv[:, 0], uv[:, 1]
    if repeat is None:
        p = slant_point(np.clip(v, 0.0, 1.0) * L_SLANT)
    else:
        k = np.floor(v * repeat)
        p = slant_point((v * repeat - k) * L_SLANT) / repeat
        p[:, 1] += k / repeat
    return np.stack([u, p[:, 1], p[:, 0]], axis=1)


def grid_line_uv(counts, samples=3000, margin=0.0):
    """uv samples on every grid line inside [0, 1]^2, as (u lines, v lines) arrays."""
    t = np.linspace(margin, 1.0 - margin, samples)
    u_lines = [np.stack([np.full_like(t, k / counts[0]), t], 1)
               for k in range(int(math.floor(counts[0] + 1e-9)) + 1)]
    v_lines = [np.stack([t, np.full_like(t, k / counts[1])], 1)
               for k in range(int(math.floor(counts[1] + 1e-9)) + 1)]
    return u_lines, v_lines


def raster_mask(camera, points, shape):
    """Boolean image with the pixels that the projected points fall in."""
    xy, _ = camera.project(points)
    i = np.floor(xy).astype(np.int64)
    keep = (i[:, 0] >= 0) & (i[:, 0] < shape[1]) & (i[:, 1] >= 0) & (i[:, 1] < shape[0])
    mask = np.zeros(shape, dtype=bool)
    mask[i[keep, 1], i[keep, 0]] = True
    return mask


def line_half_width_px(camera, uv, du, displaced):
    """Largest on-screen half-width of grid lines at uv samples (offset du in uv)."""
    a, _ = camera.project(displaced(uv))
    b, _ = camera.project(displaced(uv + du))
    return float(np.max(np.linalg.norm(b - a, axis=1)))


def check_grid_lines(img, camera, counts, displaced, half_width_px):
    """Dark pixels lie on the predicted grid lines (within the line's half-width plus
    two pixels), and the predicted centre lines of the interior lines are dark.

    Returns the fraction of dark pixels off the predicted lines (for negative controls).
    """
    grey = img[..., :3].astype(np.int64).min(axis=2)
    dark = grey < DARK
    u_lines, v_lines = grid_line_uv(counts)
    centres = raster_mask(camera, displaced(np.concatenate(u_lines + v_lines)), grey.shape)
    distance = distance_transform_edt(~centres)
    off = dark & (distance > half_width_px + 2.0)
    # interior lines only, away from the mesh's outline (where the line meets background)
    inner_u, inner_v = grid_line_uv(counts, margin=0.02)
    interior = [x for x in inner_u if 0.0 < x[0, 0] < 1.0] + \
               [x for x in inner_v if 0.0 < x[0, 1] < 1.0]
    must = raster_mask(camera, displaced(np.concatenate(interior)), grey.shape)
    return off.sum() / max(dark.sum(), 1), dark[must].mean(), int(dark.sum())


# ------------------------------------------------------------ grid material
class TestGridMaterial:
    def test_near_grid_value_by_hand(self):
        # cell_count 4: thick = 0.05 / 4 = 0.0125 about multiples of 0.25
        f = np.array([0.0, 0.012, 0.013, 0.2374, 0.2376, 0.5, 0.7626, 1.0, -0.01, -0.013,
                      1e6 + 0.001, 1e6 + 0.1])
        expected = [True, True, False, False, True, True, False, True, True, False,
                    True, False]
        assert view.near_grid_value(f, 4.0).tolist() == expected

    def test_near_grid_value_thickness_and_edge(self):
        assert view.near_grid_value(np.array([0.09, 0.11]), 2.0, 0.1).tolist() == [True, False]
        # edge = 1.5 widens the default thickness 0.025 (cell_count 2) to 0.0375
        assert view.near_grid_value(np.array([0.03, 0.04]), 2.0, 0.0, 1.5).tolist() == \
            [True, False]

    def test_near_grid_value_rejects_bad_count(self):
        for bad in (0.0, -1.0, float("nan"), float("inf")):
            with pytest.raises(ValueError, match="cell_count"):
                view.near_grid_value(np.zeros(1), bad)

    @settings(max_examples=200)
    @given(f=st.floats(-50.0, 50.0, allow_nan=False),
           count=st.floats(0.5, 200.0, allow_nan=False))
    def test_near_grid_value_is_distance_to_nearest_line(self, f, count):
        thick = 0.05 / count
        distance = abs(f * count - round(f * count)) / count
        if abs(distance - thick) < 1e-9 * max(1.0, abs(f) * count):
            return  # a tie at the line's edge: either answer is rounding
        assert bool(view.near_grid_value(np.array([f]), count)[0]) == (distance <= thick)

    def test_grid_color(self):
        c = view.grid_color(np.array([[0.0, 0.3], [0.3, 0.3], [0.3, 0.5], [-0.25, 2.0]]))
        assert c.tolist() == [[0.0] * 3, [0.7] * 3, [0.0] * 3, [0.0] * 3]
        c = view.grid_color(np.array([[0.3, 0.3]]), line_color=(1, 0, 0), bg_color=(0, 0, 1))
        assert c.tolist() == [[0.0, 0.0, 1.0]]

    def test_grid_tile_default_lines_are_whole_texels(self):
        tile = view.grid_tile((4.0, 9.5))
        assert tile.shape == (80, 80, 3) and tile.dtype == np.uint8
        line = tile[..., 0] == 0
        assert set(np.unique(tile).tolist()) == {0, BG_GREY}
        # 5% of the cell each side of its edges: texels 0-3 and 76-79, in both directions
        expected = np.zeros(80, dtype=bool)
        expected[:4] = expected[-4:] = True
        assert (line[40] == expected).all() and (line[:, 40] == expected).all()
        assert (line == (expected[:, None] | expected[None, :])).all()

    def test_grid_tile_thickness(self):
        tile = view.grid_tile((4.0, 4.0), thickness=(0.025, 0.0))
        # u: half-width 0.025 uv = 0.1 cell = 8 texels; v: the default 4 texels
        assert int((tile[40, :, 0] == 0).sum()) == 16
        assert int((tile[:, 40, 0] == 0).sum()) == 8
        with pytest.raises(ValueError, match="half"):
            view.grid_tile((4.0, 4.0), thickness=(0.2, 0.0))
        with pytest.raises(ValueError, match="size"):
            view.grid_tile(size=1)


class TestCellCounts:
    def test_length_scales_the_curve_direction(self, slant):
        assert view.cell_counts(slant, "v", 4.0) == pytest.approx([4.0, 4.0 * L_SLANT])
        assert view.cell_counts(slant, "u", 4.0) == pytest.approx([4.0 * L_SLANT, 4.0])
        assert view.cell_counts(slant, "radial", (2, 3)) == pytest.approx([2, 3 * L_SLANT])
        assert view.cell_counts(slant, "double", 50) == pytest.approx([50, 50 * L_SLANT])
        assert view.cell_counts(slant, "v", 4.0, normalize=False).tolist() == [4.0, 4.0]

    def test_listing_15_9_ornament_1(self):
        c = pwc.load(PROFILES / "ornament_1.pwc")
        assert view.cell_counts(c, "v", 50).tolist() == [50.0, 50.0 * c.length]

    def test_bad_counts(self, slant):
        for bad in (0.0, -4.0, float("nan"), float("inf"), (4.0, 0.0)):
            with pytest.raises(ValueError, match="grid_count"):
                view.cell_counts(slant, "v", bad)
        with pytest.raises(ValueError, match="unknown displacement"):
            view.cell_counts(slant, "w", 4.0)


# ------------------------------------------------------------------ inputs
class TestInputs:
    def test_surfaces(self):
        names = [type(view.make_surface(n)).__name__ for n in view.SURFACES]
        assert names == ["UnitSquare", "Plane", "UVSphere", "Cylinder", "Torus", "Cube"]
        ground = view.make_surface("plane").state_at_uv(np.array([[0.5, 0.5], [1.0, 1.0]]))
        assert ground.normal[0].tolist() == [0.0, 1.0, 0.0]
        assert ground.position.tolist() == [[0.0, 0.0, 0.0], [0.5, 0.0, -0.5]]
        with pytest.raises(ValueError, match="unknown surface 'cone'"):
            view.make_surface("cone")

    def test_field_argument_errors(self, slant):
        with pytest.raises(ValueError, match="sweep curve"):
            view.make_field(slant, "double")
        with pytest.raises(ValueError, match="only used with along='double'"):
            view.make_field(slant, "v", sweep=slant)
        with pytest.raises(ValueError, match="repeat applies"):
            view.make_field(slant, "radial", repeat=2.0)
        with pytest.raises(ValueError, match="radius_offset applies"):
            view.make_field(slant, "u", radius_offset=0.5)
        with pytest.raises(ValueError, match="unknown displacement"):
            view.make_field(slant, "sideways")

    def test_default_camera_frames_the_points(self):
        rng = np.random.default_rng(3)
        p = rng.normal(size=(50, 3)) * [3.0, 0.2, 1.0] + [10.0, -4.0, 2.0]
        for w, h in ((300, 300), (640, 200), (200, 640)):
            cam = view.default_camera(p, w, h)
            xy, depth = cam.project(p)
            assert (depth > 0).all() and cam.in_frustum(p).all()
            used = np.ptp(xy, axis=0) / [w, h]
            assert used.max() == pytest.approx(0.85, abs=0.02)
            centre = 0.5 * (xy.min(axis=0) + xy.max(axis=0))
            assert centre == pytest.approx([w / 2, h / 2], abs=0.02 * max(w, h))
        one = view.default_camera(np.ones((1, 3)), 100, 100)     # a single point
        assert one.in_frustum(np.ones((1, 3))).all()
        with pytest.raises(ValueError, match="finite point"):
            view.default_camera(np.full((2, 3), np.nan))


# -------------------------------------------------------------- scene data
def top_camera(size=SIZE):
    """Orthographic, straight down -z on the unit square: 1.2 units over the image."""
    return Camera(position=(0.5, 0.5, 5.0), look_at=(0.5, 0.5, 0.0), up=(0.0, 1.0, 0.0),
                  width=size, height=size, ortho_height=1.2)


class TestBuildScene:
    @pytest.fixture(scope="class")
    @classmethod
    def scene(cls, slant):
        return view.build_scene(slant, "square", "v", camera=top_camera())

    def test_keys(self, scene):
        import pyvista as pv

        assert set(scene) == {"surface", "texture", "curve", "vector_points", "vectors",
                              "normals", "camera"}
        for key in ("surface", "curve", "vector_points", "vectors", "normals"):
            assert isinstance(scene[key], pv.PolyData)
        assert isinstance(scene["texture"], pv.Texture)
        assert scene["texture"].repeat
        assert scene["texture"].to_array().shape[:2] == (80, 80)

    def test_displaced_vertices_keep_their_uv(self, scene):
        m = scene["surface"]
        uv = m.point_data["uv"]
        assert uv.min() == 0.0 and uv.max() == 1.0
        assert {(0.0, 0.0), (1.0, 0.0), (0.0, 1.0), (1.0, 1.0)} <= set(map(tuple, uv))
        # every vertex is the displaced point of its own (base) uv
        np.testing.assert_allclose(m.points, displaced_slant(uv), atol=1e-12)
        # the knot v = 0.5 / L (the slope's start) is a vertex row
        assert np.isclose(uv[:, 1], 0.5 / L_SLANT, atol=1e-12).sum() >= 2
        assert int(m.field_data["triangles"][0]) == m.n_cells > 0
        assert np.isfinite(m.points).all()

    def test_texture_scaled_by_curve_length(self, scene, slant):
        m = scene["surface"]
        counts = np.array([4.0, 4.0 * slant.length])
        assert slant.length == pytest.approx(L_SLANT, abs=1e-12)
        assert m.field_data["curve_length"][0] == slant.length
        np.testing.assert_allclose(m.field_data["cell_count"], counts)
        np.testing.assert_allclose(m.active_texture_coordinates,
                                   m.point_data["uv"] * counts, rtol=1e-6)

    def test_shading_normals_split_at_the_crease(self, scene):
        m = scene["surface"]
        n, v = m.point_data["Normals"], m.point_data["uv"][:, 1]
        knot = 0.5 / L_SLANT
        assert np.allclose(n[v < knot - 1e-9], [0.0, 0.0, 1.0])
        assert np.allclose(n[v > knot + 1e-9], [0.0, -SQRT_HALF, SQRT_HALF])
        at = n[np.isclose(v, knot, atol=1e-12)]
        assert np.isclose(at, [0.0, 0.0, 1.0]).all(axis=1).any()
        assert np.isclose(at, [0.0, -SQRT_HALF, SQRT_HALF]).all(axis=1).any()

    def test_vector_glyphs(self, scene):
        import pyvista as pv

        pts = scene["vector_points"]
        assert pts.n_points == 12 * 12
        centres = (np.arange(12) + 0.5) / 12
        uv = np.stack(np.meshgrid(centres, centres, indexing="xy"), -1).reshape(-1, 2)
        np.testing.assert_allclose(pts.points, np.c_[uv, np.zeros(144)], atol=1e-12)
        d = pts.point_data["displacement"]
        np.testing.assert_allclose(pts.points + d, displaced_slant(uv), atol=1e-12)
        arrow = pv.Arrow(start=(0, 0, 0), direction=(1, 0, 0), tip_length=0.2,
                         tip_radius=0.07, shaft_radius=0.025)
        glyphs = scene["vectors"]
        assert glyphs.n_points == 144 * arrow.n_points
        assert glyphs.n_cells == 144 * arrow.n_cells
        # each arrow runs from its base point to the displaced point: the glyphs' z range
        # is that of the tips (up to the arrows' own radius, 0.07 of their length)
        tip_z = (pts.points + d)[:, 2]
        longest = np.linalg.norm(d, axis=1).max()
        assert glyphs.bounds[5] == pytest.approx(tip_z.max(), abs=0.07 * longest)
        assert glyphs.bounds[4] >= -0.07 * longest

    def test_normal_glyphs(self, slant):
        import pyvista as pv

        scene = view.build_scene(slant, camera=top_camera(), normal_count=7)
        arrow = pv.Arrow(start=(0, 0, 0), direction=(1, 0, 0), tip_length=0.3,
                         tip_radius=0.12, shaft_radius=0.04)
        assert scene["normals"].n_points == 7 * arrow.n_points
        many = view.build_scene(slant, camera=top_camera(), normal_count=10**6)
        assert many["normals"].n_points == many["surface"].n_points * arrow.n_points

    def test_profile_beside_the_u0_edge(self, scene, slant):
        line = scene["curve"].points
        _, pts = slant.polyline(1e-3)
        assert np.all(line[:, 0] == line[0, 0]) and line[0, 0] < 0.0
        np.testing.assert_allclose(line[:, 1:], pts[:, ::-1], atol=1e-6)   # (run, depth)
        assert scene["curve"].n_lines == 1

    def test_along_u(self, slant):
        scene = view.build_scene(slant, along="u", camera=top_camera())
        m = scene["surface"]
        np.testing.assert_allclose(m.field_data["cell_count"], [4.0 * L_SLANT, 4.0])
        uv = m.point_data["uv"]
        p = slant_point(uv[:, 0] * L_SLANT)
        np.testing.assert_allclose(m.points, np.c_[p[:, 1], uv[:, 1], p[:, 0]], atol=1e-12)
        line = scene["curve"].points            # beside the v = 0 edge, run along x
        assert np.all(line[:, 1] == line[0, 1]) and line[0, 1] < 0.0

    def test_radial_is_a_solid_of_revolution(self, slant):
        scene = view.build_scene(slant, along="radial", radius_offset=0.25,
                                 window_size=(200, 200))
        m = scene["surface"]
        uv = m.point_data["uv"]
        p = slant_point(uv[:, 1] * L_SLANT)
        np.testing.assert_allclose(np.hypot(m.points[:, 0], m.points[:, 2]), p[:, 0] + 0.25,
                                   atol=1e-12)
        np.testing.assert_allclose(m.points[:, 1], p[:, 1], atol=1e-12)
        np.testing.assert_allclose(m.field_data["cell_count"], [4.0, 4.0 * L_SLANT])

    def test_double_follows_the_sweep(self, slant):
        sweep = pwc.compile_text("1 0\n1 1", name="sweep")        # |p(u)| = sqrt(1 + u^2)
        scene = view.build_scene(slant, along="double", sweep=sweep,
                                 window_size=(200, 200), normalize_grid=False)
        m = scene["surface"]
        uv = m.point_data["uv"]
        p = slant_point(uv[:, 1] * L_SLANT)
        np.testing.assert_allclose(np.hypot(m.points[:, 0], m.points[:, 2]),
                                   p[:, 0] * np.sqrt(1.0 + uv[:, 0] ** 2), atol=1e-12)
        assert m.field_data["cell_count"].tolist() == [4.0, 4.0]

    @pytest.mark.parametrize("surface", ["plane", "sphere", "cylinder", "torus", "cube"])
    def test_every_surface(self, surface):
        curve = pwc.load(PROFILES / "torus.pwc")
        scene = view.build_scene(curve, surface, "v", repeat=2, window_size=(160, 120),
                                 vector_count=3)
        m = scene["surface"]
        assert m.n_cells > 0 and np.isfinite(m.points).all()
        assert np.isfinite(m.point_data["Normals"]).all()
        uv = m.point_data["uv"]
        assert uv.min() >= 0.0 and uv.max() <= 1.0
        charts = 6 if surface == "cube" else 1
        assert scene["vector_points"].n_points == 9 * charts
        assert np.isfinite(scene["curve"].points).all()

    def test_cube_has_six_charts(self):
        from displacement.surfaces import Cube

        curve = pwc.compile_text("0 0\n1 1", name="ramp")      # depth = run, length sqrt 2
        scene = view.build_scene(curve, "cube", "v", window_size=(160, 120), vector_count=2)
        m = scene["surface"]
        # the ramp moves each face's point (u, v) by v along its normal (y(v) = v):
        # every chart's four displaced corners are vertices of the diced mesh
        corners = np.array([[0.0, 0.0], [1.0, 0.0], [0.0, 1.0], [1.0, 1.0]])
        for chart in Cube(1.0).charts:
            st_ = chart.state_at_uv(corners)
            expected = st_.position + corners[:, 1:2] * st_.normal
            d = np.linalg.norm(m.points[None, :, :] - expected[:, None, :], axis=2)
            assert d.min(axis=1).max() < 1e-12
        assert scene["vector_points"].n_points == 6 * 4


# ------------------------------------------------------------- screenshots
def test_top_view_grid_lines_where_the_displacement_puts_them(slant, tmp_path):
    cam = top_camera()
    out = tmp_path / "top.png"
    img = view.screenshot(out, slant, camera=cam, show_vectors=False, show_curve=False,
                          lighting=False)
    assert img.shape == (SIZE, SIZE, 3)
    assert np.array_equal(np.asarray(Image.open(out))[..., :3], img)
    # the mesh: the unit square's image, 250 x 250 of the 300 x 300 pixels
    mesh = (img != 255).any(axis=2)
    assert 0.68 <= mesh.mean() <= 0.71
    counts = (4.0, 4.0 * L_SLANT)
    # lines: half-width 0.0125 of arc length = 3.125 px on the flat run (less on the slope)
    off, on, n_dark = check_grid_lines(img, cam, counts, displaced_slant, 3.125)
    assert n_dark > 2000
    assert off == 0.0
    assert on == 1.0
    # hand check of the slope: v lines at arc 0.75 and 1.0 are at y = 0.5 + 0.25/sqrt2
    # and 0.5 + 0.5/sqrt2, rows 150 - (y - 0.5) 250 (+-2.2 px half-width on the slope)
    column = img[:, 110, 0] < DARK
    for y in (0.5 + 0.25 * SQRT_HALF, 0.5 + 0.5 * SQRT_HALF):
        row = 150.0 - (y - 0.5) * 250.0
        assert column[int(row) - 1:int(row) + 2].all()
        assert not column[int(row) - 6] and not column[int(row) + 6]


def test_uncompensated_grid_lines_would_be_elsewhere(slant):
    """A negative control: the same picture does not fit a grid that ignores the
    curve's length (cells 1/4 of v instead of 1/4 of the arc length)."""
    cam = top_camera()
    img = view.screenshot(None, slant, camera=cam, show_vectors=False, show_curve=False,
                          lighting=False)
    off, on, _ = check_grid_lines(img, cam, (4.0, 4.0), displaced_slant, 3.125)
    assert off > 0.1 and on < 0.8
    # and with --no-normalize-grid the picture matches that grid instead
    plain = view.screenshot(None, slant, camera=cam, show_vectors=False, show_curve=False,
                            lighting=False, normalize_grid=False)
    off, on, _ = check_grid_lines(plain, cam, (4.0, 4.0), displaced_slant,
                                  0.05 / 4.0 * L_SLANT * 250.0)
    assert off == 0.0 and on == 1.0


def test_oblique_perspective_view(slant):
    """A pinhole camera from the front-right, above: the grid lines are where
    Camera.project puts the analytic displaced points (so the PyVista camera is set
    exactly from the Camera the mesh was diced for)."""
    cam = Camera(position=(1.7, -1.0, 2.3), look_at=(0.5, 0.55, 0.15), up=(0.0, 0.0, 1.0),
                 fov_y_deg=32.0, width=SIZE, height=SIZE)
    img = view.screenshot(None, slant, camera=cam, show_vectors=False, show_curve=False,
                          lighting=False)
    counts = (4.0, 4.0 * L_SLANT)
    uv = np.concatenate(sum(grid_line_uv(counts, 400), []))
    half = max(line_half_width_px(cam, uv, [0.0125, 0.0], displaced_slant),
               line_half_width_px(cam, uv, [0.0, 0.0125 / L_SLANT], displaced_slant))
    assert 1.5 < half < 4.0
    off, on, n_dark = check_grid_lines(img, cam, counts, displaced_slant, half)
    assert n_dark > 1000
    assert off == 0.0
    assert on >= 0.99
    # the mesh's outline: the projected square's corners are inside the covered area
    mesh = (img != 255).any(axis=2)
    corners, _ = cam.project(displaced_slant(np.array([[0.02, 0.02], [0.98, 0.02],
                                                       [0.02, 0.98], [0.98, 0.98]])))
    assert mesh[corners[:, 1].astype(int), corners[:, 0].astype(int)].all()
    assert 0.2 < mesh.mean() < 0.9


def _widgets(plotter):
    return getattr(plotter, "widgets", plotter)      # PyVista >= 0.47 groups them here


def test_viewer_widgets_drive_the_scene(slant):
    """The sliders and check boxes are wired: moving the repeat slider (as VTK reports
    the end of an interaction) re-dices the mesh; the check boxes toggle the glyphs."""
    viewer = view.Viewer(slant, camera=top_camera(), off_screen=True, widgets=True)
    try:
        w = _widgets(viewer.plotter)
        sliders = {s.GetRepresentation().GetTitleText(): s for s in w.slider_widgets}
        assert set(sliders) == {"dicing rate (px)", "repeat"}
        assert len(w.button_widgets) == 3
        sliders["repeat"].GetRepresentation().SetValue(2.4)
        sliders["repeat"].InvokeEvent("EndInteractionEvent")
        assert viewer.repeat == 2.0
        m = viewer.scene["surface"]
        np.testing.assert_allclose(m.points, displaced_slant(m.point_data["uv"], 2.0),
                                   atol=1e-12)
        sliders["dicing rate (px)"].GetRepresentation().SetValue(8.0)
        sliders["dicing rate (px)"].InvokeEvent("EndInteractionEvent")
        assert viewer.scene["surface"].field_data["dicing_rate"][0] == 8.0
        assert viewer._normal_actor.GetVisibility() == 0
        normals_box = w.button_widgets[0]
        normals_box.GetRepresentation().SetState(1)
        normals_box.InvokeEvent("StateChangedEvent")
        assert viewer._normal_actor.GetVisibility() == 1
        image = viewer.screenshot()
        assert image.shape == (SIZE, SIZE, 3)
    finally:
        viewer.close()
    # radial: no repeat slider
    viewer = view.Viewer(slant, along="radial", window_size=(120, 120), off_screen=True)
    try:
        titles = [s.GetRepresentation().GetTitleText()
                  for s in _widgets(viewer.plotter).slider_widgets]
        assert titles == ["dicing rate (px)"]
    finally:
        viewer.close()


def test_viewer_re_dice_keeps_grid_lines_in_place(slant):
    """After set_repeat(2) (the repeat slider's callback) the grid lines are where two
    copies of the profile put them; a coarser dicing rate keeps them there."""
    cam = top_camera()
    viewer = view.Viewer(slant, camera=cam, off_screen=True, widgets=False, lighting=False,
                         show_vectors=False, show_curve=False)
    try:
        assert viewer.repeat is None
        viewer.set_repeat(1.2)                    # rounds to 1: still Listing 15.8 as is
        assert viewer.repeat is None
        viewer.set_repeat(2.4)
        assert viewer.repeat == 2.0

        def displaced(uv):
            return displaced_slant(uv, 2.0)

        counts = (4.0, 4.0 * L_SLANT)
        off, on, _ = check_grid_lines(viewer.screenshot(), cam, counts, displaced, 3.125)
        assert off == 0.0 and on == 1.0
        viewer.set_dicing_rate(16.0)
        assert viewer.scene["surface"].field_data["dicing_rate"][0] == 16.0
        off, on, _ = check_grid_lines(viewer.screenshot(), cam, counts, displaced, 3.125)
        assert off == 0.0 and on == 1.0
    finally:
        viewer.close()


def _colour(img, rgb, tol=30):
    return (np.abs(img.astype(np.int64) - rgb).max(axis=2) < tol)


def test_curve_vectors_and_normals_are_drawn(slant):
    """The profile (crimson), the displacement vectors (royal blue) and the normals
    (dark orange, unlit) are drawn where the scene data put them, and only when asked."""
    cam = Camera(position=(-1.2, -1.0, 2.3), look_at=(0.45, 0.55, 0.15), up=(0.0, 0.0, 1.0),
                 fov_y_deg=35.0, width=SIZE, height=SIZE)
    scene = view.build_scene(slant, camera=cam)
    full = view.screenshot(None, slant, camera=cam, show_vectors=True, show_curve=True,
                           show_normals=True)
    plain = view.screenshot(None, slant, camera=cam, show_vectors=False, show_curve=False,
                            show_normals=False)
    red, blue, orange = (_colour(full, c) for c in ((220, 20, 60), (65, 105, 225),
                                                     (255, 140, 0)))
    for mask in (red, blue, orange):
        assert not (mask & np.all([_colour(plain, c) for c in
                                   ((220, 20, 60), (65, 105, 225), (255, 140, 0))],
                                  axis=0)).any()
    assert not _colour(plain, (220, 20, 60)).any() and not _colour(plain, (255, 140, 0)).any()
    # the profile: along its projected polyline (every sample within a pixel), nowhere else
    line = scene["curve"].points
    t = np.linspace(0.0, 1.0, 200)[None, :, None]
    dense = (line[:-1, None] + t * (line[1:] - line[:-1])[:, None]).reshape(-1, 3)
    centre = raster_mask(cam, dense, red.shape)
    assert red.sum() > 200
    assert distance_transform_edt(~centre)[red].max() <= 3.0
    assert (distance_transform_edt(~red)[centre] <= 1.5).mean() > 0.9
    # vectors: on the segments from base to displaced points (plus the arrows' radius)
    pts = scene["vector_points"]
    base, tip = pts.points, pts.points + pts.point_data["displacement"]
    s = np.linspace(0.0, 1.0, 60)[:, None, None]
    segments = (base[None] + s * (tip - base)[None]).reshape(-1, 3)
    radius_px = 0.07 * np.linalg.norm(tip - base, axis=1).max() * cam.raster_scale(tip).max()
    assert blue.sum() > 100
    assert distance_transform_edt(~raster_mask(cam, segments, blue.shape))[blue].max() <= \
        radius_px + 2.0
    # normals: short arrows at the diced vertices
    vertices = raster_mask(cam, scene["surface"].points, orange.shape)
    length_px = 0.08 * 1.2 * cam.focal_px / 1.5      # gap = 0.08 extent, seen from ~1.5+
    assert orange.sum() > 20
    assert distance_transform_edt(~vertices)[orange].max() <= length_px + 4.0


# -------------------------------------------------------------------- CLI
def _pwc(*args, env=None, cwd=None):
    return subprocess.run([*PWC, "view", *map(str, args)], capture_output=True, text=True,
                          env=checkout_env(env), cwd=cwd, timeout=120)


def test_cli_help():
    r = _pwc("--help")
    assert r.returncode == 0
    for flag in ("--surface", "--along", "--repeat", "--grid-count", "--dicing-rate",
                 "--radius-offset", "--screenshot", "--size", "radial", "double"):
        assert flag in r.stdout


def test_cli_screenshot(tmp_path):
    out = tmp_path / "ornament.png"
    r = _pwc(PROFILES / "ornament_2.pwc", "--screenshot", out, "--size", "240", "180")
    assert r.returncode == 0, r.stderr
    assert "Traceback" not in r.stderr
    assert f"wrote {out}" in r.stdout
    img = np.asarray(Image.open(out).convert("RGB"))
    assert img.shape == (180, 240, 3)
    covered = (img != 255).any(axis=2).mean()
    assert 0.15 < covered < 0.8
    red = (img[..., 0] > 150) & (img[..., 1] < 80) & (img[..., 2] < 100)
    assert red.sum() > 30                                   # the profile is drawn


def test_cli_radial_and_double_in_process(tmp_path, capsys):
    from pwc.cli import main

    out = tmp_path / "capital.png"
    assert main(["view", str(PROFILES / "corinthian.pwc"), "--along", "radial",
                 "--screenshot", str(out), "--size", "160", "160", "--grid-count", "8",
                 "--no-normalize-grid"]) == 0
    img = np.asarray(Image.open(out).convert("RGB"))
    assert img.shape == (160, 160, 3)
    assert 0.1 < (img != 255).any(axis=2).mean() < 0.8
    # the sweep's file may come before the profile's: the last file is the profile
    out = tmp_path / "double.png"
    assert main(["view", "--along", "double", str(PROFILES / "doric_flutes.pwc"),
                 str(PROFILES / "torus.pwc"), "--radius-offset", "0.5",
                 "--screenshot", str(out), "--size", "120", "100"]) == 0
    assert "torus along double" in capsys.readouterr().out
    assert np.asarray(Image.open(out)).shape[:2] == (100, 120)


def test_cli_errors_are_one_line(tmp_path):
    bad = tmp_path / "bad.pwc"
    bad.write_text("0 0\n1 1 (\n")
    env = {k: v for k, v in os.environ.items() if k not in ("DISPLAY", "WAYLAND_DISPLAY")}
    profile = PROFILES / "ornament_2.pwc"
    out = tmp_path / "x.png"
    cases = [
        ((tmp_path / "missing.pwc", "--screenshot", out), 3, "no such file"),
        ((bad, "--screenshot", out), 1, "bad.pwc:2:5: error"),
        ((profile, "--along", "double", "--screenshot", out), 2, "needs the sweep curve"),
        ((profile, "--along", "v", "extra.pwc", "--screenshot", out), 2, "takes no file"),
        ((profile, "--along", "sideways", "--screenshot", out), 2, "choose u, v, radial"),
        ((profile, "--along", "radial", "--repeat", "2", "--screenshot", out), 2,
         "--repeat applies"),
        ((profile, "--repeat", "-1", "--screenshot", out), 2, "--repeat must be"),
        ((profile, "--radius-offset", "0.5", "--screenshot", out), 2, "--radius-offset"),
        ((profile, "--grid-count", "0", "--screenshot", out), 2, "--grid-count"),
        ((profile, "--dicing-rate", "nan", "--screenshot", out), 2, "--dicing-rate"),
        ((profile, "--size", "8", "8", "--screenshot", out), 2, "--size"),
        ((profile, "--screenshot", tmp_path / "x.gif"), 2, "unsupported image type"),
        ((profile, "--screenshot", bad / "x.png"), 3, "bad.pwc is a file, not a folder"),
        (("ornament2", "--screenshot", out), 3, "did you mean 'ornament_2'?"),
        ((profile,), 3, "no display"),
        (("--screenshot", out), 2, "give the profile"),
        ((profile, "--along", "double", tmp_path / "nope.pwc", "--screenshot", out), 3,
         "no such file"),
    ]
    from pwc.cli import main

    for args, status, message in cases:
        if args == (profile,):
            r = _pwc(*args, env=env)           # no DISPLAY: a clear error, not a crash
            code, err = r.returncode, r.stderr
        else:
            r = None
            code, err = _main_captured(main, ["view", *map(str, args)])
        assert code == status, (args, err)
        assert message in err, (args, err)
        assert "Traceback" not in err
        if status != 1:
            assert len(err.strip().splitlines()) == 1, err
    assert not out.exists()


def _main_captured(main, argv):
    """Run ``pwc`` in-process, returning (status, stderr)."""
    import contextlib
    import io

    err = io.StringIO()
    with contextlib.redirect_stderr(err), contextlib.redirect_stdout(io.StringIO()):
        try:
            code = main(argv)
        except SystemExit as e:
            code = e.code
    return code, err.getvalue()


def test_cli_screenshot_by_name_into_a_new_folder(tmp_path):
    from pwc.cli import main

    out = tmp_path / "new" / "folder" / "o.png"
    code, err = _main_captured(main, ["view", "ornament_2", "--screenshot", str(out),
                                      "--size", "64", "48"])
    assert code == 0, err
    assert np.asarray(Image.open(out)).shape[:2] == (48, 64)
