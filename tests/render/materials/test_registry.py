"""Every Part 5 material: the Handbook's names, parameters and defaults; construction with
defaults; shading at ordinary and extreme states without NaN."""

from __future__ import annotations

import inspect

import numpy as np
import pytest

from displacement.bump import HORIZON_MIN_COS
from displacement.state import ShadingState
from displacement.surfaces import Torus, UnitSquare, UVSphere
from render.library.resources import load_profile, load_texture
from render.material import material, mdl_signature
from render.materials import MATERIALS, PART5
from render.materials.chapter12 import glossy

R = inspect.Parameter.empty
F2 = (1.0, 1.0)

#: The Handbook's signatures (listing order and defaults), required parameters as R.
HANDBOOK = {
    "waves_as_grayscale": [("frequency", F2), ("gray_max", (0.5, 0.5))],
    "waves_as_displacement": [("frequency", F2), ("distance", (0.1, 0.1)), ("tint", (0.7,) * 3)],
    "waves": [("distance", (0.1, 0.1)), ("frequency", F2), ("tint", (0.7,) * 3),
              ("use_displacement", True)],
    "glossy": [("tint", (0.7,) * 3), ("roughness", 0.3)],
    "glossy_waves": [("distance", (0.1, 0.1)), ("frequency", F2), ("tint", (0.7,) * 3),
                     ("roughness", 0.3), ("use_displacement", True)],
    "waver": [("surface_and_volume", R), ("distance", (0.1, 0.1)), ("frequency", F2)],
    "glossy_yellow_waves": [("distance", (0.1, 0.1)), ("frequency", F2)],
    "glass_waves": [("distance", (0.1, 0.1)), ("frequency", F2)],
    "shaper": [("surface_and_volume", R), ("geometry", R)],
    "green_glass_waves": [("distance", (0.1, 0.1)), ("frequency", F2)],
    "diffuse_weave": [("scale", F2), ("displace", 0.0), ("tint", (0.7,) * 3)],
    "weave": [("scale", F2), ("displace", 0.0), ("surface_property", material())],
    "gold_weave": [("scale", F2), ("displace", 0.0)],
    "scaled_uv": [("u_scale", 1.0), ("v_scale", 1.0)],
    "scaled_uv_circle": [("u_scale", 1.0), ("v_scale", 1.0), ("outside_color", (0.7,) * 3)],
    "round_bumps": [("surface_material", R), ("bump_scale", 1.0), ("u_scale", 1.0),
                    ("v_scale", 1.0)],
    "glossy_round_bumps": [("bump_scale", 1.0), ("u_scale", 1.0), ("v_scale", 1.0)],
    "texture_bump": [("surface_material", R), ("texture", R), ("pixel_distance", F2),
                     ("texture_scale", F2)],
    "glossy_texture_weave_bump": [("tint", (0.7,) * 3), ("roughness", 0.5), ("pixel_distance", F2),
                                  ("texture_scale", F2)],
    "normal_as_color": [("normal", (1.0, 1.0, 1.0)), ("normal_color_as_emission", True)],
    "normal_map_bump": [("bump_scale", 1.0), ("texture_scale", F2), ("scale_vector_z", True),
                        ("surface_material", material()), ("texture", None), ("sample_min", 0.0),
                        ("sample_max", 1.0), ("use_normal_for_color", False),
                        ("normal_color_is_emission", True)],
    "glossy_normal_map_weave": [("bump_scale", 1.0), ("texture_scale", F2),
                                ("scale_vector_z", True), ("use_normal_for_color", False),
                                ("normal_color_is_emission", True)],
    "grid": [("cell_count", (4.0, 4.0)), ("line_color", (0.0,) * 3), ("bg_color", (0.7,) * 3),
             ("thickness", (0.0, 0.0)), ("texture_space", 0)],
    "vector_displacement": [("displacement", (0.0,) * 3), ("material_for_surface", None)],
    "raise": [("scale", 0.0), ("grid_count", (4.0, 4.0))],
    "triangle": [("height", 0.5)],
    "circle_linear": [("height", 0.5)],
    "circle_nonlinear": [("height", 0.5), ("count", (20.0, 20.0))],
    "bubble": [("radius", 0.25), ("height", 0.25), ("repeat", F2), ("grid_count", (4.0, 4.0)),
               ("normalize_grid", False)],
    "tee_displacement": [("uv_index", 0), ("repeat", 1.0), ("grid_count", (4.0, 4.0))],
    "grid_ornament_1": [("grid_count", 50.0)],
    "travertine": [("texture_u_scale", 1.0), ("texture_v_scale", 1.0)],
    "stone_ornament_2": [],
    "radial_pwc": [("pwc", R), ("surface_material", R), ("displace_dir", "along_v")],
    "corinthian_capital_grid": [],
    "marbloid": [("scale", 1.0), ("level_count", 5), ("space", "object")],
    "corinthian_capital_stone": [],
    "double_pwc": [("pwc_profile", R), ("pwc_sweep", R), ("surface_material", R),
                   ("radius_offset", 0.0)],
    "doric_matte_stone": [],
    "ionic_matte_stone": [],
}


def required_arguments(name: str) -> dict:
    params, _ = mdl_signature(MATERIALS[name])
    values = {"material": glossy(), "texture_2d": load_texture("weave_depth.png"),
              "pw_curve": load_profile("corinthian")}
    return {p.name: values[p.type.name] for p in params if p.required}


def extreme_states() -> list[ShadingState]:
    uv = np.array([[0.0, 0.0], [1.0, 1.0], [0.0, 1.0], [0.5, 0.5], [-0.25, -3.75],
                   [1e-12, 1.0 - 1e-12], [37.3, -12.9], [1e6 + 0.1, -1e6 + 0.7]])
    rng = np.random.default_rng(7)
    return [UnitSquare().state_at_uv(uv), UnitSquare().state_at_uv(rng.uniform(-3, 3, (300, 2))),
            UVSphere().state_at_uv(np.array([[0.3, 0.0], [0.3, 1.0], [0.0, 0.5], [1.0, 0.5]])),
            Torus().state_at_uv(rng.random((50, 2)))]


def test_registry_covers_part5():
    assert set(PART5) == set(HANDBOOK) and set(PART5) <= set(MATERIALS)
    assert len(PART5) == 40


@pytest.mark.parametrize("name", sorted(HANDBOOK))
def test_parameters_and_defaults_are_the_handbooks(name):
    params = list(inspect.signature(MATERIALS[name]).parameters.values())
    assert [p.name for p in params] == [p for p, _ in HANDBOOK[name]]
    for p, (_, default) in zip(params, HANDBOOK[name], strict=True):
        if default is R:
            assert p.default is R, p.name
        elif isinstance(default, material):
            assert isinstance(p.default, material) and p.default.surface.scattering is None
        elif default is None and name == "vector_displacement":
            assert isinstance(p.default, material)          # grid(): checked below
        else:
            assert p.default == default, p.name


def test_vector_displacement_default_surface_is_grid():
    parameters = inspect.signature(MATERIALS["vector_displacement"]).parameters
    default = parameters["material_for_surface"].default
    s = UnitSquare().state_at_uv(np.array([[0.25, 0.6], [0.6, 0.6]]))
    assert default.surface.scattering.kwargs["tint"](s).tolist() == [[0.0] * 3, [0.7] * 3]


@pytest.mark.parametrize("name", sorted(MATERIALS))
def test_every_material_builds_and_shades_without_nan(name):
    m = MATERIALS[name](**required_arguments(name))
    assert isinstance(m, material)
    for state in extreme_states():
        sh = m.shade(state)
        n = len(state)
        assert sh.normal.shape == (n, 3) and np.all(np.isfinite(sh.normal))
        assert np.allclose(np.linalg.norm(sh.normal, axis=1), 1.0)
        assert np.all(np.einsum("ij,ij->i", sh.normal, state.normal) >= HORIZON_MIN_COS - 1e-12)
        assert np.all((sh.cutout_opacity >= 0.0) & (sh.cutout_opacity <= 1.0))
        assert np.all(np.isfinite(sh.intensity)) and np.all(sh.intensity >= 0.0)
        if sh.bsdf is not None:
            wo = np.tile([0.3, 0.4, np.sqrt(0.75)], (n, 1))
            wi = np.tile([-0.6, 0.0, 0.8], (n, 1))
            f = sh.bsdf.eval(wo, wi)
            assert np.all(np.isfinite(f)) and np.all(f >= 0.0)
        d = m.geometry.displacement
        if d is not None:
            assert np.all(np.isfinite(d(state)))


def test_material_functions_validate_material_arguments():
    with pytest.raises(ValueError, match="surface_and_volume must be a material"):
        MATERIALS["waver"](surface_and_volume=0.5)
    with pytest.raises(ValueError, match="material_for_surface must be a material"):
        MATERIALS["vector_displacement"]((0.0, 0.0, 0.1), "grid")
