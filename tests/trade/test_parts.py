"""The parts of ``pwc trade``: the knobs a scene offers, the image and geometric errors,
the peak-memory measurement, and the Pareto front."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from displacement.camera import Camera
from displacement.fields import constant
from displacement.surfaces import UnitSquare
from render import material as M
from render.library.resources import bundled_scenes, track_loads
from render.scene import RenderSettings, Scene, SceneObject, make_transform, parse_scene
from trade.knobs import describe, knobs_for, merge, patch_key, reference_patch
from trade.measure import PeakMemory
from trade.metrics import geometric_error, image_errors
from trade.sweep import pareto_front


def loaded(name: str):
    text = (bundled_scenes() / f"{name}.toml").read_text()
    with track_loads() as loads:
        scene = parse_scene(text, f"{name}.toml")
    return scene, loads


# -- knobs -------------------------------------------------------------------------------
def test_a_scene_without_displacement_profiles_or_textures_offers_only_samples_and_paths():
    scene, loads = loaded("fig_13_03")
    families = {k.family for k in knobs_for(scene, loads)}
    assert families <= {"samples", "paths", "textures"}
    assert ("textures" in families) == bool(loads["textures"])


def test_a_displaced_pwc_scene_offers_dicing_methods_and_curves_per_object():
    scene, loads = loaded("fig_15_21")
    knobs = {k.name: k for k in knobs_for(scene, loads)}
    assert {"samples", "dicing_tolerance (ornament)", "dicing_rate (ornament)",
            "displacement_method (ornament)", "curves", "max_depth", "rr_depth"} <= set(knobs)
    labels = [o.label for o in knobs["displacement_method (ornament)"].options]
    assert "ornament: bump" in labels and any("normal map 1024 px 16-bit" in x for x in labels)
    # no option repeats the scene's own value
    assert all(o.patch["render"].get("spp") != 64 or o.patch["render"]["denoise"]
               for o in knobs["samples"].options)
    assert all(o.patch["render"]["max_depth"] != 8 for o in knobs["max_depth"].options)
    ci = {k.name: k for k in knobs_for(scene, loads, "ci")}
    assert all(len(k.options) <= 5 for k in ci.values())  # spp 1, 4 and its own, denoised or not


def test_without_a_denoiser_no_denoised_option_is_offered():
    scene, loads = loaded("fig_15_21")
    samples = knobs_for(scene, loads, denoiser=False)[0]
    assert samples.name == "samples" and not any(o.patch["render"]["denoise"]
                                                 for o in samples.options)


def test_the_reference_is_finer_than_every_option():
    scene, loads = loaded("fig_12_05")
    ref = reference_patch(scene, 1024)
    assert ref["render"]["spp"] == 1024 and ref["render"]["max_depth"] == 16
    assert ref["render"]["curves"] == "exact" and not ref["render"]["denoise"]
    for knob in knobs_for(scene, loads):
        for o in knob.options:
            for i, keys in o.patch.get("objects", {}).items():
                for k in ("dicing_tolerance", "dicing_rate"):
                    if k in keys:
                        assert keys[k] >= ref["objects"][i][k]


def test_patches_merge_and_describe():
    a = {"render": {"spp": 4}}
    b = {"objects": {1: {"dicing_rate": 2.0}}, "render": {"denoise": True}}
    m = merge(a, b, {"render": {"spp": 8}})
    assert m == {"render": {"spp": 8, "denoise": True}, "objects": {1: {"dicing_rate": 2.0}}}
    assert describe(m, ["floor", "square"]) == "denoise on; spp 8; square: dicing_rate 2"
    assert patch_key(merge(b, a)) == patch_key(merge(a, b))
    assert describe({}, []) == "the scene as written"


# -- errors ------------------------------------------------------------------------------
def test_image_errors_by_hand(rng):
    ref = rng.random((12, 16, 3))
    e = image_errors(ref, ref)
    assert e == {"rmse": 0.0, "rel_rmse": 0.0, "flip": 0.0, "rel_mean": 0.0}
    e = image_errors(ref + 0.1, ref)
    assert e["rmse"] == pytest.approx(0.1) and e["rel_mean"] == pytest.approx(0.1 / ref.mean())
    assert 0.0 < e["flip"] < 1.0
    with pytest.raises(ValueError, match="shape"):
        image_errors(ref[:2], ref)


def test_the_geometric_error_of_a_flat_base_is_the_displacement_on_screen():
    # a square turned 45 degrees and moved 0.1 along its normal, seen by an orthographic
    # camera looking along x: the base mesh misses the true surface by 0.1 cos 45 on screen
    cam = Camera(position=(-2.0, 0.5, 0.5), look_at=(0.5, 0.5, 0.5), up=(0, 1, 0),
                 width=100, height=100, ortho_height=2.0)
    field = constant((0.0, 0.0, 0.1))
    mat = M.material(surface=M.material_surface(M.df.diffuse_reflection_bsdf()),
                     geometry=M.material_geometry(displacement=field))
    square = SceneObject(UnitSquare(), mat, make_transform(rotate=(0.0, 45.0, 0.0)))
    scene = Scene(cam, [square], [], RenderSettings(100, 100))
    diced = geometric_error(scene, scene.build())
    assert diced == pytest.approx(0.0, abs=1e-9)  # a translation dices exactly
    flat = Scene(cam, [SceneObject(UnitSquare(), M.material(), square.transform)], [],
                 RenderSettings(100, 100))
    base = geometric_error(scene, flat.build())
    # 50 px a unit (ortho height 2 over 100 px)
    assert base == pytest.approx(0.1 * np.cos(np.radians(45)) * 50, rel=1e-6)


def test_peak_memory_sees_what_a_block_allocates():
    with PeakMemory() as m:
        a = np.ones(50 * 2**20 // 8)  # 50 MB, touched
        del a
    assert 45 * 2**20 <= m.peak_bytes <= 80 * 2**20, (m.peak_bytes, m.method)
    with PeakMemory() as small:
        np.ones(1000)
    assert small.peak_bytes < 20 * 2**20


# -- the Pareto front ----------------------------------------------------------------------
@given(st.lists(st.tuples(st.floats(0.01, 100), st.floats(0, 1)), min_size=1, max_size=30))
@settings(max_examples=80)
def test_the_pareto_front_is_exactly_the_undominated_points(points):
    front = pareto_front(points)
    assert any(front)
    for (c, e), on in zip(points, front, strict=True):
        beaten = any(c2 <= c and e2 <= e and (c2, e2) != (c, e) for c2, e2 in points)
        assert on == (not beaten)
