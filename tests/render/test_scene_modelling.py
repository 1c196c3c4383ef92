"""What a scene file may say about how its objects are modelled (the knobs of ``pwc
trade``): per-object dicing and displacement method, [render] curves, texture filter
and denoising; the patcher that writes them; and the summary of what was modelled."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from displacement.bake import bake, displaced_normal, read_normal_map, write_normal_map
from displacement.surfaces import UnitSquare
from displacement.waves import waves_as_displacement
from render import material as M
from render.displacement_method import apply, without_displacement
from render.library.resources import bundled_scenes, evaluation, load_profile, track_loads
from render.scene import SceneError, modelling_summary, parse_scene, patch_scene_text

SCENE = (bundled_scenes() / "fig_14_28.toml").read_text()  # grid square + displaced square
ORNAMENT = (bundled_scenes() / "fig_15_21.toml").read_text()  # ornament_1 along v
WEAVE = (bundled_scenes() / "fig_13_26.toml").read_text()  # a height-map texture


def scene(text: str, render=None, objects=None):
    return parse_scene(patch_scene_text(text, render, objects), "s.toml")


# -- patching --------------------------------------------------------------------------
def test_patching_replaces_and_adds_keys_and_keeps_the_rest():
    text = patch_scene_text(SCENE, {"spp": 3, "denoise": True, "curves": "float32"},
                            {1: {"dicing_tolerance": 2.0, "displacement_method": "bump"}})
    s = parse_scene(text, "s.toml")
    assert (s.settings.spp, s.settings.denoise, s.settings.curves) == (3, True, "float32")
    original = parse_scene(SCENE, "s.toml").settings
    assert (s.settings.max_depth, s.settings.width) == (original.max_depth, original.width)
    assert s.objects[1].dicing_tolerance == 2.0 and s.objects[1].displacement_method == "bump"
    assert s.objects[0].dicing_tolerance is None
    assert text.count("spp =") == 1
    # comments and materials are kept verbatim
    for line in SCENE.splitlines():
        if line.startswith(("#", "material")):
            assert line in text


def test_patching_adds_a_render_table_where_there_is_none():
    text = "[[objects]]\nsurface = \"square\"\nmaterial = \"diffuse()\"\n"
    s = parse_scene(patch_scene_text(text, {"spp": 2, "resolution": [4, 3]}), "s.toml")
    assert (s.settings.spp, s.settings.width, s.settings.height) == (2, 4, 3)
    with pytest.raises(ValueError, match="no \\[\\[objects\\]\\] table number 5"):
        patch_scene_text(text, objects={5: {"dicing_rate": 1.0}})


@given(st.integers(1, 4096), st.floats(1e-6, 1e6), st.sampled_from(["exact", "float32",
                                                                    "polyline"]))
@settings(max_examples=40)
def test_patched_values_read_back_exactly(spp, tolerance, curves):
    s = scene(SCENE, {"spp": spp, "curve_tolerance": tolerance, "curves": curves},
              {1: {"dicing_rate": tolerance}})
    assert s.settings.spp == spp and s.settings.curve_tolerance == tolerance
    assert s.settings.curves == curves and s.objects[1].dicing_rate == tolerance


# -- per-object dicing -----------------------------------------------------------------
def test_an_objects_own_dicing_settings_decide_its_triangles():
    waves = (bundled_scenes() / "fig_12_05.toml").read_text()  # floor, square, sphere
    fine = scene(waves, {"resolution": [64, 48]}).build().stats
    coarse = scene(waves, {"resolution": [64, 48]},
                   {1: {"dicing_tolerance": 8.0, "dicing_rate": 8.0}}).build().stats
    assert coarse[1]["triangles"] < fine[1]["triangles"] and coarse[1]["max_error_px"] <= 8.0
    assert coarse[2]["triangles"] == fine[2]["triangles"]  # the sphere keeps the scene's


# -- displacement methods --------------------------------------------------------------
def test_bump_and_normal_maps_keep_the_base_mesh_and_evaluate_a_normal():
    for method, extra in (("bump", {}), ("normal_map", {"normal_map_size": 64,
                                                        "normal_map_bits": 8})):
        s = scene(SCENE, {"resolution": [32, 24]}, {1: {"displacement_method": method,
                                                        **extra}})
        obj = s.objects[1]
        assert obj.displacement is None and obj.original_displacement is not None
        assert obj.material.geometry.normal is not None
        stats = s.build().stats[1]
        assert not stats["diced"] and stats["triangles"] == 2
        summary = modelling_summary(s, s.build().stats)[1]
        assert summary["displacement"] == method and summary["normal"] == "evaluated (bump)"
        assert "base mesh: 2 triangles" in summary["geometry"]


def test_bump_is_the_displaced_surfaces_normal():
    field = waves_as_displacement(4.0, 0.05)
    m = M.material(surface=M.material_surface(M.df.diffuse_reflection_bsdf()),
                   geometry=M.material_geometry(displacement=field))
    square = UnitSquare()
    bumped = apply(m, square, "bump")
    state = square.state_at_uv(np.random.default_rng(1).random((50, 2)))
    np.testing.assert_array_equal(bumped.geometry.normal(state),
                                  displaced_normal(field, square, state.uv, 1e-4)[0])
    assert without_displacement(m).geometry.displacement is None


@pytest.mark.parametrize("bits", [8, 16])
def test_a_normal_map_in_memory_is_the_map_written_and_read_back(bits, tmp_path):
    field = waves_as_displacement(4.0, 0.05)
    m = M.material(surface=M.material_surface(M.df.diffuse_reflection_bsdf()),
                   geometry=M.material_geometry(displacement=field))
    square = UnitSquare()
    in_memory = apply(m, square, "normal_map", 32, bits).geometry.normal
    assert in_memory.parameters["texture"] == f"baked normal map 32x32 {bits}-bit"
    path = write_normal_map(tmp_path / "n.png", bake(field, square, 32).normal, bits=bits)
    from render.materials import MATERIALS

    via_file = MATERIALS["normal_map_bump"](texture=read_normal_map(path)).geometry.normal
    state = square.state_at_uv(np.random.default_rng(2).random((200, 2)))
    np.testing.assert_allclose(in_memory(state), via_file(state), atol=1e-12)


@pytest.mark.parametrize(("objects", "words", "key"), [
    ({1: {"displacement_method": "relief"}}, "displacement_method must be one of",
     "displacement_method"),
    ({1: {"displacement_method": "normal_map", "normal_map_bits": 12}},
     "normal_map_bits must be one of", "normal_map_bits"),
    ({1: {"displacement_method": "normal_map", "normal_map_size": 1}},
     "normal_map_size must be a whole number >= 2", "normal_map_size"),
    ({1: {"dicing_rate": -1.0}}, "dicing_rate must be a number > 0", "dicing_rate"),
], ids=["method", "bits", "size", "rate"])
def test_bad_modelling_keys_are_reported_at_their_line(objects, words, key):
    text = patch_scene_text(SCENE, objects=objects)
    with pytest.raises(SceneError) as e:
        parse_scene(text, "s.toml")
    line = next(i for i, ln in enumerate(text.splitlines(), 1) if ln.startswith(key))
    assert words in e.value.message and e.value.line == line


@pytest.mark.parametrize(("render", "words"), [
    ({"curves": "spline"}, "curves must be one of 'exact', 'float32', 'polyline'"),
    ({"curve_tolerance": 0.0}, "curve_tolerance must be a number > 0"),
    ({"texture_filter": "cubic"}, "texture_filter must be one of 'nearest', 'bilinear'"),
    ({"denoise": 1}, "denoise must be true or false"),
], ids=["curves", "tolerance", "filter", "denoise"])
def test_bad_render_keys_are_reported_at_their_line(render, words):
    text = patch_scene_text(SCENE, render)
    with pytest.raises(SceneError) as e:
        parse_scene(text, "s.toml")
    key = next(iter(render))
    assert words in e.value.message
    assert e.value.line == next(i for i, ln in enumerate(text.splitlines(), 1)
                                if ln.startswith(key))


# -- curves and textures as the scene says ---------------------------------------------
def test_curves_load_as_the_scene_says():
    with track_loads() as loads:
        exact = scene(ORNAMENT)
    assert loads["profiles"] == {"ornament_1"} and not loads["textures"]
    with evaluation("polyline", 1e-3):
        poly = load_profile("ornament_1")
    with evaluation("float32"):
        f32 = load_profile("ornament_1")
    curve = load_profile("ornament_1")
    assert np.all(poly.type == 0) and poly.n > curve.n and f32.precision == "float32"
    assert curve.precision == "float64" and curve.n < poly.n  # the cache keeps them apart
    # the scene's displacement follows: a polyline ornament dices to other triangles
    a = exact.build().stats[1]
    b = scene(ORNAMENT, {"curves": "polyline", "curve_tolerance": 1e-2}).build().stats[1]
    assert a["triangles"] != b["triangles"]


def test_textures_filter_as_the_scene_says():
    with track_loads() as loads:
        bilinear = scene(WEAVE, {"resolution": [16, 12]})
    assert loads["textures"]
    nearest = scene(WEAVE, {"resolution": [16, 12], "texture_filter": "nearest"})
    from render.integrator import render

    a = render(bilinear, spp=1, progress=False).rgb()
    b = render(nearest, spp=1, progress=False).rgb()
    assert np.all(np.isfinite(a)) and np.all(np.isfinite(b)) and not np.array_equal(a, b)


def test_the_summary_says_what_each_object_is_made_of():
    s = parse_scene(ORNAMENT, "s.toml")
    summary = {m["name"]: m for m in modelling_summary(s, s.build().stats)}
    assert summary["floor"]["geometry"] == "base mesh: 2 triangles (not displaced)"
    assert summary["ornament"]["diced"] and summary["ornament"]["geometry"].startswith("diced")
    assert summary["ornament"]["dfs"] == ["diffuse_reflection_bsdf"]
    assert summary["light_left"]["emits"] and summary["light_left"]["dfs"] == ["diffuse_edf"]
    assert not any(m["volume"] for m in summary.values())


# -- model only what the camera can see ----------------------------------------------------
def _waves_square(distance: float, translate=(0.0, 0.0, 0.0), **render):
    text = (bundled_scenes() / "fig_14_28.toml").read_text()
    text = text.replace('material = """tee_displacement()"""',
                        f'material = "waves_as_displacement(frequency: float2(8.0), '
                        f'distance: float2({distance}))"')
    text = patch_scene_text(text, {"resolution": [64, 48], **render},
                            {1: {"translate": list(translate)}})
    return parse_scene(text, "s.toml")


def test_a_displacement_under_the_tolerance_is_shaded_as_bump_not_diced():
    scene = _waves_square(1e-5)  # ~0.005 px on screen
    stats = scene.build().stats[1]
    assert not stats["diced"] and stats["triangles"] == 2
    assert "under the 0.5 px tolerance: shaded as bump" in stats["not_diced"]
    obj = scene.objects[1]
    assert obj.displacement_method == "bump" and obj.material.geometry.normal is not None
    summary = modelling_summary(scene, scene.build().stats)[1]
    assert summary["geometry"].startswith("base mesh: 2 triangles (not diced: its "
                                          "displacement is")
    # asked to, it dices
    diced = _waves_square(1e-5, dice_invisible=True)
    assert diced.build().stats[1]["diced"]


def test_a_visible_displacement_is_diced_and_a_zero_one_dropped():
    assert _waves_square(0.05).build().stats[1]["diced"]
    zero = _waves_square(0.0)
    stats = zero.build().stats[1]
    assert stats["not_diced"] == "its displacement is zero" and stats["triangles"] == 2
    assert zero.objects[1].material.geometry.normal is None  # nothing to bump either


def test_a_displaced_object_out_of_view_is_not_diced():
    scene = _waves_square(0.05, translate=(40.0, 0.0, 0.0))
    stats = scene.build().stats[1]
    assert stats["not_diced"] == "out of view: shaded as bump" and stats["triangles"] == 2


def test_not_dicing_an_invisible_displacement_changes_the_image_by_noise_only():
    from render.integrator import render
    from trade.metrics import image_errors

    culled = render(_waves_square(1e-4, spp=16), progress=False)
    diced = render(_waves_square(1e-4, spp=16, dice_invisible=True), progress=False)
    assert not culled.stats["geometry"][1]["diced"] and diced.stats["geometry"][1]["diced"]
    again = render(_waves_square(1e-4, spp=16, seed=7, dice_invisible=True), progress=False)
    noise = image_errors(again.rgb(), diced.rgb())["rmse"]
    assert image_errors(culled.rgb(), diced.rgb())["rmse"] < 0.25 * noise


def test_pwc_render_says_what_it_modelled(tmp_path):
    from repo import run_pwc

    r = run_pwc("render", bundled_scenes() / "fig_14_03.toml", "-o", tmp_path / "x.exr",
                "--resolution", 16, 12, "--spp", 1, "--aov", "depth")
    assert r.returncode == 0, r.stderr
    lines = r.stderr.splitlines()
    assert ("  displaced_square: base mesh: 2 triangles (not diced: its displacement is "
            "zero); thin-walled, diffuse_reflection_bsdf") in lines
    assert "  light_left: base mesh: 2 triangles (not displaced); emits, diffuse_edf" in lines
    assert lines[-1] == ("  lights: ConstantEnvironment, area (light_left), area "
                         "(light_right); volumes: none; AOVs: depth")
