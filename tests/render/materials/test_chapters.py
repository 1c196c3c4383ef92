"""Hand-checked values of the Part 5 materials, worked out from the Handbook's listings."""

from __future__ import annotations

import math

import numpy as np
import pytest

from displacement.bump import HORIZON_MIN_COS, modify_normal_from_texture
from displacement.fields import FIELDS, Field
from displacement.state import ShadingState
from displacement.surfaces import UnitSquare
from render.df import DiffuseEdf, DiffuseReflectionBsdf, SimpleGlossyBsdf
from render.library.grid import grid_color
from render.library.resources import load_profile, load_texture
from render.materials import MATERIALS
from render.materials.chapter12 import glossy

M = MATERIALS
SQRT_HALF = math.sqrt(0.5)


def square(uv) -> ShadingState:
    return UnitSquare().state_at_uv(np.asarray(uv, dtype=np.float64).reshape(-1, 2))


def tint_of(m, state):
    return m.shade(state).bsdf.tint


# --- chapter 12 -----------------------------------------------------------------------


def test_waves_as_grayscale_tint_by_hand():
    # Figure 12.3: frequency (4, 4), gray_max (0.5, 0.5).  At u = 1/16 the u sine is at
    # its peak (sin(2 pi 4/16) = 1 -> 0.5); at v = 1/8 the v sine is 0 (-> 0.25): 0.75 grey
    m = M["waves_as_grayscale"]((4.0, 4.0), (0.5, 0.5))
    assert np.allclose(tint_of(m, square([[0.0625, 0.125]])), [[0.75] * 3])
    # Figure 12.2: only v, gray_max 1; v = 3/16: sin(3 pi/2) = -1 -> 0
    m = M["waves_as_grayscale"]((0.0, 4.0), (0.0, 1.0))
    assert np.allclose(tint_of(m, square([[0.3, 0.1875], [0.9, 0.0625]])), [[0.0] * 3, [1.0] * 3])
    assert m.geometry.displacement is None


def test_waves_as_displacement_by_hand():
    m = M["waves_as_displacement"]((4.0, 4.0), (0.075, 0.075))
    d = m.geometry.displacement(square([[0.0625, 0.125], [0.1875, 0.0625]]))
    assert np.allclose(d, [[0.0, 0.0, 0.075], [0.0, 0.0, 0.0]])
    assert np.allclose(tint_of(m, square([[0.5, 0.5]])), [[0.7] * 3])


def test_waves_switch_between_displacement_and_tint():
    args = dict(distance=(0.02, 0.02), frequency=(10.0, 10.0), tint=(0.6, 0.4, 0.0))
    on = M["waves"](**args, use_displacement=True)
    assert on.geometry.displacement.name == "waves"
    s = square([[0.025, 0.0]])
    assert np.allclose(on.geometry.displacement(s), [[0.0, 0.0, 0.02]])
    assert np.allclose(tint_of(on, s), [[0.6, 0.4, 0.0]])
    off = M["waves"](**args, use_displacement=False)
    assert off.geometry.displacement is None          # nothing to dice (section 12.2)
    # tint * uv_wave(10, 0.1, 0.5): u = 0.025 -> peak 0.5, v = 0 -> 0.3; total 0.8
    assert np.allclose(tint_of(off, s), [[0.48, 0.32, 0.0]])


def test_glossy_waves_passes_roughness_and_tint_through():
    m = M["glossy_waves"](distance=(0.02, 0.02), frequency=(10, 10), tint=(0.6, 0.4, 0.0),
                          roughness=0.25, use_displacement=True)
    node = m.surface.scattering
    assert node.name == "simple_glossy_bsdf"
    assert node.kwargs["roughness_u"] == 0.25 and node.kwargs["tint"] == (0.6, 0.4, 0.0)
    bsdf = m.shade(square([[0.3, 0.3]])).bsdf
    assert isinstance(bsdf, SimpleGlossyBsdf)
    assert np.allclose(bsdf.roughness_u, 0.25) and np.allclose(bsdf.roughness_v, 0.25)
    assert np.allclose(bsdf.tint, [[0.6, 0.4, 0.0]])
    off = M["glossy_waves"](frequency=(10, 10), tint=(0.6, 0.4, 0.0), use_displacement=False)
    assert np.allclose(off.shade(square([[0.025, 0.0]])).bsdf.tint, [[0.48, 0.32, 0.0]])


def test_glossy_defaults():
    node = M["glossy"]().surface.scattering
    assert dict(node.kwargs) == {"tint": (0.7, 0.7, 0.7), "roughness_u": 0.3}


def test_waver_shaper_and_glass_compose_materials():
    sv = M["subsurface_scattering"](transmission_color=(0.8, 0.9, 1.0),
                                    scattering_color=(0.1, 0.1, 0.3), transmission_distance=2.0)
    w = M["waver"](sv, (0.02, 0.02), (10.0, 5.0))
    assert w.surface is sv.surface and w.volume is sv.volume and w.ior == (1.5, 1.5, 1.5)
    assert w.geometry.displacement.parameters == {"frequency": (10.0, 5.0),
                                                  "distance": (0.02, 0.02)}
    g = M["glass_waves"]((0.02, 0.02), (10.0, 5.0))
    assert np.allclose(g.volume.absorption_coefficient, -np.log([0.8, 0.9, 1.0]) / 2.0)
    assert np.allclose(g.volume.scattering_coefficient, -np.log([0.1, 0.1, 0.3]) / 2.0)
    assert g.volume.scattering.name == "anisotropic_vdf"
    assert g.volume.scattering.kwargs["directional_bias"] == -0.5
    geo = M["waves_as_displacement"]((20.0, 10.0), (0.04, 0.04))
    sh = M["shaper"](sv, geo)
    assert sh.geometry is geo.geometry and sh.surface is sv.surface
    assert M["green_glass_waves"]((0.04, 0.04), (20, 10)).geometry.displacement.parameters == {
        "frequency": (20.0, 10.0), "distance": (0.04, 0.04)}
    yellow = M["glossy_yellow_waves"]()
    assert yellow.surface.scattering.kwargs["tint"] == (0.6, 0.4, 0.0)


def test_diffuse_weave_height_map():
    texture = load_texture("weave_depth.png")
    m = M["diffuse_weave"](displace=0.05, scale=(8, 4), tint=(0.72, 0.75, 0.7))
    uv = np.array([[0.3, 0.7], [-0.2, 1.0]])
    scaled = np.stack([(uv[:, 0] * 8) % 1.0, (uv[:, 1] * 4) % 1.0], 1)
    expected = 0.05 * texture.lookup(scaled)[:, 0]
    assert np.allclose(m.geometry.displacement(square(uv))[:, 2], expected)
    assert M["diffuse_weave"]().geometry.displacement is None            # displace 0
    assert M["weave"]().shade(square([[0.5, 0.5]])).bsdf is None          # material(): black
    gold = M["gold_weave"](displace=0.015, scale=(60, 30))
    assert gold.surface.scattering.kwargs == {"tint": (0.6, 0.4, 0.0), "roughness_u": 0.3}
    assert gold.geometry.displacement.parameters["scale"] == (60.0, 30.0)


# --- chapter 13 -----------------------------------------------------------------------


def test_scaled_uv_and_circle_tints():
    s = square([[0.3, 0.55], [0.02, 0.02]])
    assert np.allclose(tint_of(M["scaled_uv"](2, 4), s), [[0.6, 0.2, 0.0], [0.04, 0.08, 0.0]])
    assert np.allclose(tint_of(M["scaled_uv_circle"](2, 4), s), [[0.6, 0.2, 0.0], [0.7] * 3])


def test_glossy_round_bumps_normals_by_hand():
    s = square([[0.75, 0.5], [0.02, 0.02], [0.5, 0.75]])
    sh = M["glossy_round_bumps"](bump_scale=4.0).shade(s)
    # inside: normalize(N + 4 (0.25 tu)) = (1, 0, 1)/sqrt 2; outside the circle: N
    assert np.allclose(sh.normal, [[SQRT_HALF, 0, SQRT_HALF], [0, 0, 1], [0, SQRT_HALF, SQRT_HALF]])
    assert sh.bsdf.tint.tolist() == [[0.6, 0.4, 0.0]]
    dimple = M["glossy_round_bumps"](u_scale=80, v_scale=40, bump_scale=-1.0).shade(
        square([[0.75 / 80, 0.5 / 40]]))
    assert np.allclose(dimple.normal, [[-0.25, 0.0, 1.0] / np.linalg.norm([-0.25, 0.0, 1.0])])


@pytest.mark.parametrize("bump_scale", [0.0, 1.0, -1.0, 100.0, -100.0])
def test_bumped_materials_stay_above_the_horizon(bump_scale):
    s = square(np.random.default_rng(3).uniform(-2.0, 3.0, (400, 2)))
    for m in (M["glossy_round_bumps"](bump_scale, 8, 4),
              M["glossy_normal_map_weave"](bump_scale, (4, 4)),
              M["glossy_normal_map_weave"](bump_scale, (40, 20), scale_vector_z=False)):
        n = m.shade(s).normal
        assert np.allclose(np.linalg.norm(n, axis=1), 1.0)
        assert np.all(n[:, 2] >= HORIZON_MIN_COS - 1e-12)
        if bump_scale == 0.0 and m.geometry.normal.name == "round_bump_normal":
            assert np.allclose(n, [[0.0, 0.0, 1.0]])


def test_normal_map_bump_scale_zero_keeps_the_normal():
    s = square(np.random.default_rng(4).random((100, 2)))
    n = M["glossy_normal_map_weave"](bump_scale=0.0, texture_scale=(4, 4)).shade(s).normal
    assert np.allclose(n, [[0.0, 0.0, 1.0]])


def test_texture_bump_is_the_handbook_height_map_normal():
    texture = load_texture("weave_depth.png")
    s = square(np.random.default_rng(5).random((50, 2)))
    m = M["glossy_texture_weave_bump"](tint=(0.6, 0.4, 0.0), roughness=0.3, texture_scale=(20, 10))
    expected = modify_normal_from_texture(s, texture, (1.0, 1.0), (20.0, 10.0))
    assert np.allclose(m.shade(s).normal, expected)
    assert M["glossy_texture_weave_bump"]().surface.scattering.kwargs["roughness_u"] == 0.5


def test_normal_as_color_emission_and_reflection():
    s = square([[0.5, 0.5]])
    sh = M["normal_as_color"]().shade(s)                       # normal float3(1.0), emission
    assert sh.bsdf is None and isinstance(sh.edf, DiffuseEdf)
    assert np.allclose(sh.intensity, [[1.0 / math.pi] * 3])
    sh = M["normal_as_color"]((0.0, 0.0, 1.0), False).shade(s)
    assert sh.edf is None and np.allclose(sh.bsdf.tint, [[0.5, 0.5, 1.0]])


def test_normal_map_bump_default_texture_reads_zero():
    # texture_2d() reads 0: sample (-1, -1, -1), so n = -N - tu - tv, below the horizon; the
    # rule bends it to min_cos N + sqrt(1 - min_cos^2) (-1, -1, 0)/sqrt 2
    sh = M["normal_map_bump"]().shade(square([[0.3, 0.4]]))
    c = HORIZON_MIN_COS
    t = math.sqrt(1.0 - c * c) * SQRT_HALF
    assert np.allclose(sh.normal, [[-t, -t, c]]) and sh.bsdf is None


def test_normal_map_weave_as_color():
    s = square(np.random.default_rng(6).random((20, 2)))
    bumped = M["glossy_normal_map_weave"](texture_scale=(4, 4)).shade(s).normal
    reflect = M["glossy_normal_map_weave"](use_normal_for_color=True,
                                           normal_color_is_emission=False, texture_scale=(4, 4))
    assert reflect.geometry.normal is None
    sh = reflect.shade(s)
    assert sh.edf is None and np.allclose(sh.bsdf.tint, np.clip(0.5 + 0.5 * bumped, 0, 1))
    emit = M["glossy_normal_map_weave"](use_normal_for_color=True, texture_scale=(4, 4)).shade(s)
    assert emit.bsdf is None and np.allclose(emit.intensity, (0.5 + 0.5 * bumped) / math.pi)


# --- chapter 14 -----------------------------------------------------------------------


def test_grid_material_lines():
    m = M["grid"]()
    s = square([[0.25, 0.6], [0.6, 0.6], [0.6, 0.0], [1.0, 0.3], [0.1, 0.1]])
    assert isinstance(m.shade(s).bsdf, DiffuseReflectionBsdf)
    assert tint_of(m, s)[:, 0].tolist() == [0.0, 0.7, 0.0, 0.0, 0.7]


def test_vector_displacement_template():
    m = M["vector_displacement"]()
    assert m.thin_walled and m.geometry.displacement is None
    f = FIELDS["triangle"](0.25)
    m = M["vector_displacement"](f, glossy())
    assert m.geometry.displacement is f and m.surface.scattering.name == "simple_glossy_bsdf"
    wrapped = M["vector_displacement"](lambda st: st.normal * 0.1).geometry.displacement
    assert isinstance(wrapped, Field)
    assert wrapped(square([[0.5, 0.5]])).tolist() == [[0.0, 0.0, 0.1]]


def test_raise_triangle_and_circles():
    s = square([[0.25, 0.5], [0.5, 0.5]])
    r = M["raise"](scale=0.2, grid_count=(8.0, 8.0))
    assert np.allclose(r.geometry.displacement(s), [[0.0, 0.0, 0.2]] * 2)
    assert tint_of(r, square([[0.125, 0.3]]))[0, 0] == 0.0            # 8 cells: a line at 1/8
    t = M["triangle"](height=0.25)
    assert np.allclose(t.geometry.displacement(s)[:, 2], [0.125, 0.25])
    assert t.geometry.displacement.uv_knots[0].tolist() == [0.5]
    cl = M["circle_linear"]()
    assert tint_of(cl, square([[0.05, 0.33], [0.025, 0.33]]))[:, 0].tolist() == [0.0, 0.7]
    cn = M["circle_nonlinear"](height=0.5, count=(31.416, 20))
    top = cn.geometry.displacement(square([[0.5, 0.0]]))
    assert np.allclose(top, [[0.0, 0.0, 0.5]], atol=1e-15)


def test_bubble_grid_normalization():
    # Figure 14.22: repeat (3, 0) and normalize_grid: both counts scale by total_length
    # (the Handbook's condition repeat != 1 also holds for the undisplaced v)
    from displacement.bubble import get_bubble_args

    ba = get_bubble_args(0.45, 0.42)
    m = M["bubble"](radius=0.45, height=0.42, repeat=(3, 0), grid_count=(8, 8), normalize_grid=True)
    s = square(np.random.default_rng(8).random((200, 2)))
    count = (8 * ba.total_length, 8 * ba.total_length)
    assert np.allclose(tint_of(m, s), grid_color(s, count, 0.0, 0.7))
    assert m.geometry.displacement.uv_knots[1] is None
    with pytest.raises(ValueError):
        M["bubble"](radius=0.2, height=0.3)


def test_tee_displacement_scales_the_grid_by_the_profile_length():
    # the tee's total length is 3: 4 cells become 12 along u
    m = M["tee_displacement"]()
    s = square([[1.0 / 12.0, 0.4], [1.0 / 8.0, 0.4]])
    assert tint_of(m, s)[:, 0].tolist() == [0.0, 0.7]
    assert np.allclose(m.geometry.displacement(square([[0.25, 0.5]])), [[0.0, 0.0, 0.25]])
    v = M["tee_displacement"](uv_index=1, repeat=3, grid_count=(24, 24))
    assert v.geometry.displacement.uv_knots[0] is None
    assert tint_of(v, square([[0.4, 1.0 / 72.0]]))[0, 0] == 0.0


# --- chapter 15 -----------------------------------------------------------------------


def test_grid_ornament_1_and_travertine():
    curve = load_profile("ornament_1")
    m = M["grid_ornament_1"]()
    s = square(np.random.default_rng(9).random((100, 2)))
    assert np.allclose(tint_of(m, s), grid_color(s, (50.0, 50.0 * curve.length), 0.0, 0.7))
    assert np.allclose(m.geometry.displacement(s), FIELDS["displace_with_pwc"](curve, "along_v")(s))
    assert m.thin_walled
    texture = load_texture("travertine.png", "srgb")
    t = M["travertine"](2.0, 3.0)
    uv = np.array([[0.3, 0.7], [-0.6, 1.0]])
    expected = texture.lookup_float3(np.stack([(2 * uv[:, 0]) % 1.0, (3 * uv[:, 1]) % 1.0], 1))
    assert np.allclose(tint_of(t, square(uv)), expected)


def test_stone_ornament_2_uses_the_curve_length_for_the_texture():
    curve = load_profile("ornament_2")
    m = M["stone_ornament_2"]()
    s = square([[0.3, 0.7]])
    expected = M["travertine"](1.0, curve.length)
    assert np.allclose(tint_of(m, s), tint_of(expected, s))
    assert m.geometry.displacement.uv_knots[1].tolist() == curve.t.tolist()


def test_radial_pwc_and_capitals():
    curve = load_profile("corinthian")
    s = square(np.random.default_rng(10).random((50, 2)))
    m = M["radial_pwc"](curve, glossy(), "along_v")
    expected = FIELDS["pwc_angular_displace"](curve, "along_v")(s)
    assert np.allclose(m.geometry.displacement(s), expected)
    grid_capital = M["corinthian_capital_grid"]()
    assert np.allclose(tint_of(grid_capital, s), grid_color(s, (50.0, 50.0), 0.0, 0.7))
    stone = M["corinthian_capital_stone"]()
    assert np.allclose(tint_of(stone, square([[0.0, 0.0]])),
                       [[0.33 ** (1 / 1.8), 0.33 ** (1 / 1.4), 0.9 * 0.33 ** (1 / 1.1)]])
    with pytest.raises(ValueError, match="space must be"):
        M["marbloid"](space="texture")


def test_double_pwc_columns():
    s = square(np.random.default_rng(11).random((50, 2)))
    profile, doric = load_profile("corinthian"), load_profile("doric_flutes")
    m = M["doric_matte_stone"]()
    assert np.allclose(m.geometry.displacement(s), FIELDS["double_pwc"](profile, doric, 0.25)(s))
    assert np.allclose(tint_of(m, s), [[0.7, 0.66, 0.63]])
    ionic = M["ionic_matte_stone"]()
    assert ionic.geometry.displacement.parameters["sweep_curve"] == "ionic_flutes"
    assert ionic.geometry.displacement.parameters["radius_offset"] == 0.25
