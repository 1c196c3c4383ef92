"""The library as MDL calls (FUNCTIONS) and the resource search paths."""

from __future__ import annotations

import numpy as np
import pytest

from displacement import bump, waves
from displacement.fields import Field
from displacement.surfaces import UnitSquare
from render.library import FUNCTIONS
from render.library.resources import (
    INVALID_TEXTURE,
    ResourceError,
    find_profile,
    find_texture,
    load_profile,
    load_texture,
    profile_names,
    search_paths,
)
from render.material import mdl_signature


def square(uv):
    return UnitSquare().state_at_uv(np.asarray(uv, dtype=np.float64).reshape(-1, 2))


def test_every_function_has_an_mdl_signature():
    for name, function in FUNCTIONS.items():
        params, returns = mdl_signature(function)
        assert returns is not None, name
        assert returns.name in ("float", "float2", "float3", "color"), name


def test_functions_return_varying_values_matching_the_library():
    s = square([[0.3, 0.0625], [0.8, 0.5]])
    wave = FUNCTIONS["uv_wave"]((0.0, 4.0), (0.0, 0.0), (0.0, 1.0))
    assert np.allclose(wave(s), waves.uv_wave(s.uv, (0.0, 4.0), 0.0, (0.0, 1.0)))
    assert FUNCTIONS["u"]()(s).tolist() == [0.3, 0.8]
    assert np.allclose(FUNCTIONS["fit"](FUNCTIONS["v"](), 0.0, 1.0, 10.0, 20.0)(s), [10.625, 15.0])
    assert np.allclose(FUNCTIONS["sinusoid"](FUNCTIONS["u"](), 1.0, 0.0, 1.0)(s),
                       waves.sinusoid(s.uv[:, 0], 1.0, 0.0, 1.0))
    assert np.allclose(FUNCTIONS["round_bump_normal"](4.0, 1.0, 1.0)(s),
                       bump.round_bump_normal(s, 4.0))
    assert np.allclose(FUNCTIONS["state::normal"]()(s), s.normal)
    assert np.allclose(FUNCTIONS["state::texture_tangent_v"](1)(s), 0.0)
    tex = load_texture("weave_depth.png")
    assert np.allclose(FUNCTIONS["texture_2d_lookup_scaled"](tex, 8.0, 4.0)(s),
                       tex.lookup_float3(np.stack([(s.uv[:, 0] * 8) % 1, (s.uv[:, 1] * 4) % 1], 1)))
    assert np.allclose(FUNCTIONS["color_from_normal"]((0.0, 0.0, 1.0), False)(s),
                       [[0.5, 0.5, 1.0]] * 2)


def test_displacement_functions_are_fields_with_knots():
    f = FUNCTIONS["triangle_displacement"](FUNCTIONS["u"](), 0.25)
    assert isinstance(f, Field)
    s = square([[0.25, 0.0], [0.5, 0.0]])
    assert f(s)[:, 2].tolist() == [0.125, 0.25]
    g = FUNCTIONS["displace_with_pwc"](load_profile("ornament_1"), "along_v")
    assert isinstance(g, Field) and g.uv_knots[1] is not None


def test_invalid_texture_reads_zero():
    s = square([[0.3, 0.7]])
    assert FUNCTIONS["texture_2d_lookup"](None)(s).tolist() == [[0.0, 0.0, 0.0]]
    assert INVALID_TEXTURE.lookup(np.array([[0.5, 0.5]])).tolist() == [[0.0, 0.0, 0.0]]


def test_summed_perlin_noise_function_checks_level_count():
    with pytest.raises(ValueError, match="level_count"):
        FUNCTIONS["summed_perlin_noise"]((0.0, 0.0, 0.0), level_count=-2)


# --- resources ---------------------------------------------------------------------------


def test_profiles_and_textures_are_found(root):
    assert find_profile("ornament_2") == root / "profiles" / "ornament_2.pwc"
    assert find_profile("../profiles/ornament_2") is None and find_profile("") is None
    needed = {"ornament_1", "ornament_2", "corinthian", "doric_flutes", "ionic_flutes"}
    assert needed <= set(profile_names())
    assert load_profile("ornament_2") is load_profile("ornament_2")          # cached
    assert find_texture("travertine.png") == root / "gallery" / "textures" / "travertine.png"
    assert find_texture("no\0file.png") is None
    t = load_texture("travertine.png", "srgb")
    assert t is load_texture("travertine.png", "srgb")
    assert t is not load_texture("travertine.png", "linear")


def test_missing_resources_suggest_a_fix():
    with pytest.raises(ResourceError, match="did you mean 'ornament_2'") as e:
        load_profile("ornament_3")
    assert e.value.hint == "did you mean 'ornament_2'?"
    with pytest.raises(ResourceError, match="did you mean 'weave_normal_map.png'"):
        load_texture("weave_normal_map.tif")


def test_search_paths_are_scoped(tmp_path):
    (tmp_path / "tiny.pwc").write_text("0 0\n1 1\n")
    assert find_profile("tiny") is None
    with search_paths(profile_dirs=tmp_path):
        assert find_profile("tiny") == tmp_path / "tiny.pwc"
        assert load_profile("tiny").length > 0
        assert find_profile("ornament_1") is not None           # defaults still searched
    assert find_profile("tiny") is None
    (tmp_path / "bad.png").write_bytes(b"not a png")
    with pytest.raises(ResourceError, match="cannot read texture"):
        load_texture("bad.png", base_dir=tmp_path)
