"""Materials written in MDL become the render core's materials.

A material defined in a module shades exactly as the same material built in Python
(the same df program, the same parameters per lane, the same normal, cutout and
displacement), uniform parameters refuse varying values, modules are found in the
documented order (beside the scene, ``--mdl-path``, ``$PWC_MDL_PATH``, the workbench's
library), compiled code is cached by module content, and MDL materials pickle for
distributed rendering.
"""

from __future__ import annotations

import pickle

import cloudpickle
import numpy as np
import pytest

from displacement.fields import Field
from displacement.surfaces import UnitSquare, UVSphere
from mdl.diagnostics import MdlError
from mdl.loader import MDL_PATH_ENV
from render import material as M
from render.mdlc import Session, make_loader, material_from_call
from render.mdlc.compiler import module_code
from render.scene import SceneError, parse_scene

MODULE = """\
mdl 1.6;
import ::df::*;
import ::state::*;
import ::math::*;

export material diffuse_twin(color tint = color(0.5)) = material(
    surface: material_surface(scattering: df::diffuse_reflection_bsdf(tint: tint)));

color stripes(float scale) {
    float s = math::frac(state::texture_coordinate(0).x * scale);
    return s < 0.5 ? color(0.8, 0.1, 0.1) : color(0.9);
}

float3 wobble(float amount) {
    float3 n = state::normal();
    float3 t = state::texture_tangent_u(0);
    return math::normalize(n + amount * math::sin(20.0 * state::texture_coordinate(0).x) * t);
}

export material striped(float scale = 4.0, float roughness = 0.3) = let {
    float2 uv = float2(state::texture_coordinate(0).x, state::texture_coordinate(0).y);
} in material(
    surface: material_surface(scattering: df::simple_glossy_bsdf(
        tint: stripes(scale), roughness_u: roughness)),
    geometry: material_geometry(
        cutout_opacity: uv.y > 0.9 ? 0.0 : 1.0,
        normal: wobble(0.2)));

export material bumps(uniform float height = 0.05) = material(
    surface: material_surface(scattering: df::diffuse_reflection_bsdf(tint: color(0.7))),
    geometry: material_geometry(displacement: state::normal() * height
        * math::sin(6.0 * state::texture_coordinate(0).x)
        * math::cos(4.0 * state::texture_coordinate(0).y)));
"""


def twin_striped(scale=4.0, roughness=0.3):
    def tint(s):
        f = np.mod(s.uv[:, 0] * scale, 1.0)
        return np.where((f < 0.5)[:, None], [0.8, 0.1, 0.1], [0.9, 0.9, 0.9])

    def opacity(s):
        return np.where(s.uv[:, 1] > 0.9, 0.0, 1.0)

    def normal(s):
        v = s.normal + 0.2 * np.sin(20.0 * s.uv[:, 0])[:, None] * s.tangent_u
        return v / np.linalg.norm(v, axis=1, keepdims=True)

    return M.material(
        surface=M.material_surface(M.df.simple_glossy_bsdf(tint=tint, roughness_u=roughness)),
        geometry=M.material_geometry(cutout_opacity=opacity, normal=normal))


def twin_bumps(height=0.05):
    def d(s):
        return s.normal * (height * np.sin(6.0 * s.uv[:, 0]) * np.cos(4.0 * s.uv[:, 1]))[:, None]

    return M.material(surface=M.material_surface(M.df.diffuse_reflection_bsdf(tint=0.7)),
                      geometry=M.material_geometry(displacement=Field(d)))


@pytest.fixture
def module_dir(tmp_path):
    (tmp_path / "looks.mdl").write_text(MODULE, encoding="utf-8")
    return tmp_path


def states():
    rng = np.random.default_rng(3)
    return [UnitSquare().state_at_uv(rng.random((300, 2))),
            UVSphere().state_at_uv(rng.random((300, 2)))]


def assert_same_shading(a: M.material, b: M.material):
    rng = np.random.default_rng(5)
    for s in states():
        sa, sb = a.shade(s), b.shade(s)
        np.testing.assert_allclose(sa.normal, sb.normal, rtol=0, atol=1e-13)
        np.testing.assert_array_equal(sa.cutout_opacity, sb.cutout_opacity)
        assert (sa.bsdf is None) == (sb.bsdf is None)
        if sa.bsdf is None:
            continue
        pa, pb = sa.bsdf.program, sb.bsdf.program
        np.testing.assert_array_equal(pa.code, pb.code)  # the same df program
        np.testing.assert_allclose(pa.P, pb.P, rtol=0, atol=1e-13)
        wo = rng.normal(size=(len(s), 3))
        wi = rng.normal(size=(len(s), 3))
        wo[:, 2] = np.abs(wo[:, 2])
        wi[:, 2] = np.abs(wi[:, 2])
        wo /= np.linalg.norm(wo, axis=1, keepdims=True)
        wi /= np.linalg.norm(wi, axis=1, keepdims=True)
        np.testing.assert_allclose(sa.bsdf.eval(wo, wi), sb.bsdf.eval(wo, wi), rtol=1e-12,
                                   atol=1e-15)


def test_module_materials_shade_as_the_same_materials_built_in(module_dir):
    m, _ = material_from_call("diffuse_twin(tint: color(0.25, 0.5, 0.75))", "looks.mdl",
                              base_dir=module_dir)
    assert_same_shading(m, M.material(surface=M.material_surface(
        M.df.diffuse_reflection_bsdf(tint=(0.25, 0.5, 0.75)))))
    m, _ = material_from_call("striped(scale: 3.0, roughness: 0.2)", "looks.mdl",
                              base_dir=module_dir)
    assert_same_shading(m, twin_striped(3.0, 0.2))


def test_a_displacement_written_in_mdl_is_a_field(module_dir):
    m, _ = material_from_call("bumps(height: 0.1)", "looks.mdl", base_dir=module_dir)
    twin = twin_bumps(0.1)
    assert isinstance(m.displacement, Field)
    assert m.displacement.uv_knots == (None, None)
    for s in states():
        np.testing.assert_allclose(m.displacement(s), twin.displacement(s), rtol=0,
                                   atol=1e-15)
    assert_same_shading(m, twin)


def test_uniform_parameters_refuse_varying_values(module_dir):
    with pytest.raises(MdlError) as e:
        material_from_call("bumps(height: state::texture_coordinate(0).x)", "looks.mdl",
                           base_dir=module_dir)
    d = e.value.first
    assert "uniform" in d.message and (d.loc.line, d.loc.col) == (1, 15)


SCENE = """\
[camera]
position = [0.0, 0.0, 3.0]
look_at = [0.0, 0.0, 0.0]

[[objects]]
surface = "square"
material = {{ module = "{module}", call = "{call}" }}
"""


def scene_material(folder, module="shade_lib.mdl", call="m()", mdl_paths=()):
    text = SCENE.format(module=module, call=call)
    scene = parse_scene(text, str(folder / "s.toml"), base_dir=folder, mdl_paths=mdl_paths)
    return scene.objects[0].material


def grey_module(folder, value: float):
    folder.mkdir(parents=True, exist_ok=True)
    (folder / "shade_lib.mdl").write_text(
        "mdl 1.6;\nimport ::df::*;\nexport material m() = material(surface: material_surface("
        f"scattering: df::diffuse_reflection_bsdf(tint: color({value}))));\n", encoding="utf-8")


def tint(m) -> float:
    return float(np.asarray(m.surface.scattering.kwargs["tint"]).reshape(-1)[0])


def test_modules_are_found_beside_the_scene_then_mdl_path_then_env_then_library(
        tmp_path, monkeypatch):
    scene_dir, flag_dir, env_dir = tmp_path / "scene", tmp_path / "flag", tmp_path / "env"
    for d, v in ((scene_dir, 0.1), (flag_dir, 0.2), (env_dir, 0.3)):
        grey_module(d, v)
    monkeypatch.setenv(MDL_PATH_ENV, str(env_dir))
    assert tint(scene_material(scene_dir, mdl_paths=[flag_dir])) == 0.1
    empty = tmp_path / "empty"
    empty.mkdir()
    assert tint(scene_material(empty, mdl_paths=[flag_dir])) == 0.2
    assert tint(scene_material(empty)) == 0.3
    monkeypatch.delenv(MDL_PATH_ENV)
    # the workbench's library: the module Listings 15.21-15.22 import
    m = scene_material(empty, "diffuse_reflection.mdl",
                       "diffuse_reflection(tint: color(0.4))")
    assert isinstance(m, M.material)
    with pytest.raises(SceneError) as e:
        scene_material(empty)
    assert "s.toml:7:" in str(e.value) and "not found" in str(e.value)
    assert "--mdl-path" in str(e.value) and MDL_PATH_ENV in str(e.value)


def test_errors_in_a_module_are_reported_in_the_module(tmp_path):
    (tmp_path / "shade_lib.mdl").write_text(
        "mdl 1.6;\nimport ::df::*;\nexport material m() = material(surface: material_surface("
        "scattering: df::diffuse_reflection_bsdf(tint: colour(0.5))));\n", encoding="utf-8")
    with pytest.raises(SceneError) as e:
        scene_material(tmp_path)
    text = str(e.value)
    assert text.startswith(f"{tmp_path / 's.toml'}:7:")
    assert f"{tmp_path / 'shade_lib.mdl'}:3:" in text and "colour" in text


def test_compiled_code_is_cached_by_module_content(tmp_path):
    text = MODULE
    a = make_loader(tmp_path).load_text(text, "looks.mdl", "::looks", tmp_path / "looks.mdl")
    b = make_loader(tmp_path).load_text(text, "looks.mdl", "::looks", tmp_path / "looks.mdl")
    assert a is b  # checked once per content
    assert module_code(a) is module_code(b)
    c = make_loader(tmp_path).load_text(text.replace("0.2", "0.25"), "looks.mdl", "::looks",
                                        tmp_path / "looks.mdl")
    assert c is not a and module_code(c) is not module_code(a)


def test_mdl_materials_pickle_for_distributed_rendering(module_dir):
    m, _ = material_from_call("striped(scale: 3.0)", "looks.mdl", base_dir=module_dir)
    back = pickle.loads(cloudpickle.dumps(m))
    assert_same_shading(back, m)
    d, _ = material_from_call("bumps()", "looks.mdl", base_dir=module_dir)
    back = pickle.loads(cloudpickle.dumps(d))
    s = states()[0]
    np.testing.assert_array_equal(back.displacement(s), d.displacement(s))


def test_a_session_reuses_its_modules(module_dir):
    session = Session(module_dir)
    first, _ = session.material("striped()", module="looks.mdl")
    again, _ = session.material("striped(scale: 2.0)", module="looks.mdl")
    assert isinstance(first, M.material) and isinstance(again, M.material)
    assert len([q for q in session.loader.modules if q == "::looks"]) == 1


def test_a_call_imports_the_modules_it_names_and_no_more(module_dir):
    """The string form's scope imports a module beyond the standard ones and the
    workbench's only when the call names it (``perlin_noise::``, ``base::``), in a
    string-form call or in a call into a module: importing them all was half of a scene
    file's check."""
    plain = Session()
    plain.material("diffuse(tint: color(0.5))")
    loaded = set(plain.loader.modules)
    assert {"::materials", "::df"} <= loaded
    assert not loaded & {"::base", "::perlin_noise", "::pwc_examples", "::geometry"}
    noise = "perlin_noise::perlin_noise(float3(0.1, 0.2, 0.3))"
    for session, call, module in [(Session(), f"diffuse(tint: color({noise}))", None),
                                  (Session(module_dir), f"diffuse_twin(tint: color({noise}))",
                                   "looks.mdl")]:
        m, _ = session.material(call, module=module)
        assert isinstance(m, M.material) and "::perlin_noise" in session.loader.modules
        assert "::base" not in session.loader.modules


MDL_1_10 = """\
mdl 1.10;
import ::df::*;

export material velvet_under_lacquer(color absorption = color(0.2, 0.5, 0.9)) = material(
    surface: material_surface(scattering: df::coat_absorption_factor(
        ior: color(1.5), absorption_coefficient: absorption, thickness: 0.3,
        base: df::microflake_sheen_bsdf(roughness: 0.4, tint: color(0.8, 0.2, 0.2),
            multiscatter_tint: color(1.0)))));
"""


def test_an_mdl_1_10_module_uses_the_1_10_distribution_functions(tmp_path):
    """``mdl 1.10;`` is read (1.10 adds distribution functions, no syntax), and its
    dfs (microflake_sheen_bsdf, coat_absorption_factor) shade as the same material built
    in Python."""
    (tmp_path / "lacquer.mdl").write_text(MDL_1_10)
    m, _ = material_from_call("velvet_under_lacquer()", "lacquer.mdl", base_dir=tmp_path)
    assert_same_shading(m, M.material(surface=M.material_surface(
        M.df.coat_absorption_factor(
            ior=(1.5, 1.5, 1.5), absorption_coefficient=(0.2, 0.5, 0.9), thickness=0.3,
            base=M.df.microflake_sheen_bsdf(roughness=0.4, tint=(0.8, 0.2, 0.2),
                                            multiscatter_tint=(1.0, 1.0, 1.0))))))
