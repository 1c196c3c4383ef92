"""The example materials of the Handbook's chapters 3-8 (Parts 2 and 3): names, parameters
and defaults as listed; df trees with the structure of their listings (hand-checked);
values of layered and mixed bsdfs worked out from the listings' weights; shading at
ordinary and extreme states without NaN; the figure captions parse."""

from __future__ import annotations

import inspect
import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from displacement.state import ShadingState
from displacement.surfaces import Torus, UnitSquare, UVSphere
from render.expr import parse_material
from render.material import DfNode, material, material_surface, mdl_signature
from render.materials import CONSTANTS, MATERIALS, PARTS_2_3, chapter6, chapter8

R = inspect.Parameter.empty
C1 = (1.0, 1.0, 1.0)
C07 = (0.7, 0.7, 0.7)

#: The Handbook's signatures, in listing order, with their defaults.
HANDBOOK = {
    # chapter 3
    "plaster": [("tint", C07), ("roughness", 0.0)],
    "diffuse_transmission": [],
    "emission": [("tint", C1)],
    "emission_with_diffuse_backface": [("tint", C1), ("backtint", (0.8, 0.78, 0.75))],
    "specular": [],
    "mirror": [],
    "specular_transmission": [("tint", C1)],
    "specular_reflection_transmission": [],
    "glossy_reflection": [],
    "glossy_transmission": [],
    "glossy_reflection_transmission": [],
    # chapter 4
    "specular_reflect_transmit": [("tint", C1), ("ior", (1.3,) * 3)],
    "specular_reflect_transmit_thin_walled": [("tint", C1), ("ior", (1.3,) * 3)],
    "glossy_reflect_transmit": [("tint", C1), ("roughness", 0.0), ("volume_ior", (1.5,) * 3)],
    "glossy_reflect_transmit_layers": [("reflection_color", C1), ("transmission_color", C1),
                                       ("roughness", 0.0), ("volume_ior", (1.5,) * 3),
                                       ("layer_ior", (1.5,) * 3)],
    "glossy_reflect_transmit_absorb": [("surface_color", C1), ("roughness", 0.0),
                                       ("absorption", C1), ("volume_ior", (1.5,) * 3)],
    "glossy_reflect_transmit_absorb_falloff": [("surface_color", C1), ("transmission_color", C1),
                                               ("transmission_distance", 1.0), ("roughness", 0.0),
                                               ("volume_ior", 1.5)],
    "subsurface_scattering": [("surface_color", C1), ("scattering_color", (0.05,) * 3),
                              ("transmission_color", (0.1, 0.95, 0.65)),
                              ("transmission_distance", 0.3), ("roughness", 0.0),
                              ("volume_ior", 1.5)],
    # chapter 5
    "isotropic_volume": [("scattering", C1), ("absorption", C1)],
    "anisotropic_volume": [("absorption", C1), ("scattering", C1), ("directional_bias", 0.0),
                           ("ior", C1)],
    "red_light": [],
    "green_light": [],
    "blue_light": [],
    "blue_scattering": [],
    "blue_absorption": [],
    "spotlight_emission": [("spread_factor", 1.0), ("tint", C1)],
    # chapter 6
    "red": [],
    "shiny": [],
    "shiny_red": [("shiny_weight", 0.5)],
    "shiny_red_with_let": [("shiny_weight", 0.5)],
    "shiny_red_extract": [("shiny_weight", 0.5)],
    "diffuse": [("tint", (0.5,) * 3)],
    "glossy_over_diffuse": [("glossy_tint", (0.1,) * 3), ("glossy_roughness", 0.1),
                            ("glossy_weight", 0.5), ("diffuse_tint", (0.5,) * 3)],
    "shiny_red_specialized": [],
    "light_blue_ceramic": [],
    "shiny_tint": [("tint", C1)],
    "fresnel_glossy_over_diffuse": [("glossy_roughness", 0.1), ("diffuse_tint", (0.5,) * 3),
                                    ("ior", (1.3,) * 3)],
    "two_glossy_lobes": [("roughness_1", 0.1), ("weight_1", 0.5), ("tint_1", C07),
                         ("roughness_2", 0.5), ("weight_2", 0.5), ("tint_2", C07)],
    "diffuse_green_base": [],
    "wide_blue_glossy": [],
    "narrow_blue_glossy": [],
    "two_layers": [],
    "three_layers": [],
    "four_layers": [],
    "two_layers_v1": [],
    "three_layers_v1": [],
    "four_layers_v1": [],
    "five_layers": [],
    # chapter 7
    "phonglike_plastic": [("diffuse_color", C07), ("diffuse_intensity", 0.8),
                          ("highlight_color", C1), ("highlight_intensity", 0.2),
                          ("highlight_roughness", 0.2)],
    "phonglike_plastic_layered": [("diffuse_color", C07), ("highlight_color", C1),
                                  ("highlight_intensity", 0.2), ("highlight_roughness", 0.2)],
    "dielectric_plastic": [("diffuse_color", (0.5, 0.04, 0.04)), ("glossy_color", C1),
                           ("glossy_weight", 1.0), ("glossy_roughness", 0.05), ("ior", 1.54)],
    "dielectric_plastic_two_lobe": [("diffuse_color", (0.5, 0.04, 0.04)), ("glossy_color", C1),
                                    ("glossy_roughness_1", 0.05), ("glossy_weight_1", 0.5),
                                    ("glossy_roughness_2", 0.25), ("glossy_weight_2", 0.5),
                                    ("glossy_weight", 1.0), ("ior", 1.54)],
    "translucency": [("transmission_color", C1)],
    "translucent_plastic": [("diffuse_color", (0.5, 0.04, 0.04)), ("glossy_color", C1),
                            ("glossy_roughness_1", 0.05), ("glossy_weight_1", 0.5),
                            ("glossy_roughness_2", 0.25), ("glossy_weight_2", 0.5),
                            ("glossy_weight", 1.0), ("ior", 1.54), ("transmission_weight", 0.2),
                            ("transmission_color", (0.9,) * 3), ("transmission_exponent", 3.0)],
    # chapter 8
    "anisotropic_glossy": [("tint", C07), ("roughness_u", 1.0), ("roughness_v", 0.15)],
    "anisotropic_glossy_three_lobes": [("tint", C07), ("roughness", 0.1), ("bend_factor", 1.5)],
    "warp_and_weft": [("warp_color", (0.3, 0.22, 0.3)), ("warp_roughness", 0.3),
                      ("weft_color", (0.2, 0.3, 0.2)), ("weft_roughness", 0.15),
                      ("weft_bend_factor", 1.5), ("warp_to_weft", 3.0), ("shadowing", 0.0)],
    "iridescent_silk": [("warp_color", (0.3, 0.22, 0.3)), ("warp_roughness", 0.3),
                        ("weft_color", (0.2, 0.3, 0.2)), ("weft_roughness", 0.15),
                        ("weft_bend_factor", 1.5), ("warp_to_weft", 3.0),
                        ("transmission_weight", 0.2), ("transmission_color", (0.95, 1.0, 0.95)),
                        ("transmission_exponent", 3.0), ("shadowing", 0.0)],
}

# Directions in the local shading frame (+z = normal): wo toward the viewer, wi toward
# the light, both above the surface, and one below (transmission).
WO = np.array([0.3, 0.4, math.sqrt(0.75)])
WI = np.array([-0.6, 0.0, 0.8])
WT = np.array([0.2, -0.5, -math.sqrt(0.71)])


def square(uv) -> ShadingState:
    return UnitSquare().state_at_uv(np.asarray(uv, dtype=np.float64).reshape(-1, 2))


def tile(v, n):
    return np.tile(v, (n, 1))


def eval_at(m: material, state: ShadingState, wo=WO, wi=WI) -> np.ndarray:
    n = len(state)
    return m.shade(state).bsdf.eval(tile(wo, n), tile(wi, n))


def extreme_states() -> list[ShadingState]:
    rng = np.random.default_rng(11)
    uv = np.array([[0.0, 0.0], [1.0, 1.0], [0.5, 0.5], [-0.25, -3.75], [1e-12, 1.0 - 1e-12],
                   [1e6 + 0.1, -1e6 + 0.7]])
    return [square(uv), square(rng.uniform(-3, 3, (200, 2))),
            UVSphere().state_at_uv(np.array([[0.3, 0.0], [0.3, 1.0], [0.0, 0.5], [1.0, 0.5]])),
            Torus().state_at_uv(rng.random((40, 2)))]


def random_directions(rng, n, lower=False):
    v = rng.normal(size=(n, 3))
    v /= np.linalg.norm(v, axis=1, keepdims=True)
    v[:, 2] = np.abs(v[:, 2]) * (-1.0 if lower else 1.0)
    return v


# --- registry ---------------------------------------------------------------------------


def test_registry_has_every_listing():
    assert set(PARTS_2_3) == set(HANDBOOK)
    assert set(PARTS_2_3) <= set(MATERIALS)


@pytest.mark.parametrize("name", sorted(HANDBOOK))
def test_parameters_and_defaults_are_the_handbooks(name):
    params = list(inspect.signature(MATERIALS[name]).parameters.values())
    assert [p.name for p in params] == [p for p, _ in HANDBOOK[name]]
    for p, (_, default) in zip(params, HANDBOOK[name], strict=True):
        assert p.default == default, p.name
    mdl_signature(MATERIALS[name])  # every parameter carries its MDL type


def test_uniform_parameters_are_uniform():
    uniform = {(name, p.name) for name in HANDBOOK
               for p in mdl_signature(MATERIALS[name])[0] if p.type.uniform}
    assert uniform == {
        ("specular_reflect_transmit", "ior"), ("specular_reflect_transmit_thin_walled", "ior"),
        ("glossy_reflect_transmit", "volume_ior"),
        ("glossy_reflect_transmit_layers", "volume_ior"),
        ("glossy_reflect_transmit_layers", "layer_ior"),
        ("glossy_reflect_transmit_absorb", "absorption"),
        ("glossy_reflect_transmit_absorb", "volume_ior"),
        ("glossy_reflect_transmit_absorb_falloff", "transmission_color"),
        ("glossy_reflect_transmit_absorb_falloff", "transmission_distance"),
        ("glossy_reflect_transmit_absorb_falloff", "volume_ior"),
        ("subsurface_scattering", "scattering_color"),
        ("subsurface_scattering", "transmission_color"),
        ("subsurface_scattering", "transmission_distance"),
        ("subsurface_scattering", "volume_ior"),
        ("anisotropic_volume", "ior"), ("spotlight_emission", "spread_factor"),
        ("anisotropic_glossy_three_lobes", "bend_factor"),
        ("warp_and_weft", "weft_bend_factor"), ("warp_and_weft", "warp_to_weft"),
        ("iridescent_silk", "weft_bend_factor"), ("iridescent_silk", "warp_to_weft"),
    }


def test_part5_names_keep_their_part5_meaning():
    # chapter 6's glossy (Listing 6.6) and mirror (Figure 6.27) collide with Listing 12.8's
    # glossy and Listing 3.5's mirror: the registry keeps those, chapter 6 uses its own
    assert inspect.signature(MATERIALS["glossy"]).parameters["roughness"].default == 0.3
    assert MATERIALS["mirror"]().surface.scattering.kwargs["tint"] == (0.5, 0.5, 0.5)
    assert inspect.signature(chapter6.glossy).parameters["roughness"].default == 0.1
    assert chapter6.mirror().surface.scattering.kwargs["tint"] == (0.7, 0.7, 0.7)


def test_constants_of_the_listings():
    assert CONSTANTS["orange"] == (0.3, 0.15, 0.0) and CONSTANTS["yellow"] == (0.5, 0.4, 0.1)
    assert CONSTANTS["white"] == (0.7, 0.7, 0.7) and CONSTANTS["blue"] == (0.2, 0.3, 0.7)
    assert CONSTANTS["magenta"] == (0.3, 0.22, 0.3)
    assert "green" not in CONSTANTS  # chapters 6 and 8 define different greens


# --- every material: builds, shades, finite ----------------------------------------------


@pytest.mark.parametrize("name", sorted(HANDBOOK))
def test_builds_with_defaults_and_shades_finite(name):
    m = MATERIALS[name]()
    assert isinstance(m, material)
    rng = np.random.default_rng(5)
    for state in extreme_states():
        n = len(state)
        for front in (np.ones(n, dtype=bool), np.zeros(n, dtype=bool)):
            sh = m.shade(state, front)
            assert np.all(np.isfinite(sh.normal)) and np.all(np.isfinite(sh.intensity))
            assert np.all(sh.intensity >= 0.0)
            if sh.bsdf is None:
                continue
            wo = random_directions(rng, n)
            for wi in (random_directions(rng, n), random_directions(rng, n, lower=True)):
                f, pdf = sh.bsdf.eval(wo, wi), sh.bsdf.pdf(wo, wi)
                assert f.shape == (n, 3) and np.all(np.isfinite(f)) and np.all(f >= 0.0)
                assert np.all(np.isfinite(pdf)) and np.all(pdf >= 0.0)
            s = sh.bsdf.sample(wo, rng.random(n), rng.random((n, 2)))
            assert np.all(np.isfinite(s.wi)) and np.all(np.isfinite(s.weight))
            assert np.all(s.weight >= 0.0) and np.all(s.pdf >= 0.0)
            if sh.edf is not None:
                assert np.all(np.isfinite(sh.edf.eval(wo)))


# --- chapter 3 ---------------------------------------------------------------------------


def test_plaster_is_listing_3_2():
    node = MATERIALS["plaster"](tint=(0.3, 0.1, 0.1), roughness=0.25).surface.scattering
    assert node.name == "diffuse_reflection_bsdf"
    assert dict(node.kwargs) == {"tint": (0.3, 0.1, 0.1), "roughness": 0.25}
    # Lambert at roughness 0: tint / pi * cos(wi)
    f = eval_at(MATERIALS["plaster"](), square([[0.5, 0.5]]))
    assert np.allclose(f, 0.7 / math.pi * 0.8)


def test_emission_with_diffuse_backface_has_two_sides():
    m = MATERIALS["emission_with_diffuse_backface"](tint=(2.0, 2.0, 2.0))
    assert m.thin_walled
    s = square([[0.5, 0.5]] * 2)
    front = m.shade(s, np.array([True, True]))
    assert front.edf is not None and np.allclose(front.intensity, 2.0) and front.bsdf is None
    back = m.shade(s, np.array([False, False]))
    assert back.edf is None and np.allclose(back.intensity, 0.0)
    assert np.allclose(back.bsdf.eval(tile(WO, 2), tile(WI, 2)), 0.8 / math.pi * 0.8 *
                       np.array([1.0, 0.78 / 0.8, 0.75 / 0.8]))


@pytest.mark.parametrize("name, ior, mode, tint", [
    ("specular", 1.0, "scatter_reflect", None),
    ("mirror", 1.0, "scatter_reflect", (0.5, 0.5, 0.5)),
    ("specular_transmission", 1.3, "scatter_transmit", (1.0, 1.0, 1.0)),
    ("specular_reflection_transmission", 1.3, "scatter_reflect_transmit", (0.6, 0.7, 0.8)),
])
def test_specular_materials(name, ior, mode, tint):
    m = MATERIALS[name]()
    node = m.surface.scattering
    assert node.name == "specular_bsdf" and node.kwargs.get("mode", "scatter_reflect") == mode
    assert node.kwargs.get("tint") == tint and m.ior == (ior,) * 3


@pytest.mark.parametrize("name, ior, roughness, mode, tint", [
    ("glossy_reflection", 1.0, 0.3, "scatter_reflect", 0.6),
    ("glossy_transmission", 1.3, 0.15, "scatter_transmit", 1.0),
    ("glossy_reflection_transmission", 1.3, 0.15, "scatter_reflect_transmit", 1.0),
])
def test_glossy_materials(name, ior, roughness, mode, tint):
    m = MATERIALS[name]()
    node = m.surface.scattering
    assert node.name == "simple_glossy_bsdf" and node.kwargs["mode"] == mode
    assert node.kwargs["roughness_u"] == roughness and "roughness_v" not in node.kwargs
    assert node.kwargs["tint"] == (tint,) * 3 and m.ior == (ior,) * 3


def test_glossy_transmission_does_not_reflect():
    s = square([[0.5, 0.5]])
    assert np.all(eval_at(MATERIALS["glossy_transmission"](), s) == 0.0)
    assert np.all(eval_at(MATERIALS["glossy_reflection_transmission"](), s) > 0.0)


# --- chapter 4 ---------------------------------------------------------------------------


def test_thin_walled_glass_differs_only_in_thin_walled():
    solid = MATERIALS["specular_reflect_transmit"](tint=(0.8, 0.9, 1.0))
    thin = MATERIALS["specular_reflect_transmit_thin_walled"](tint=(0.8, 0.9, 1.0))
    assert not solid.thin_walled and thin.thin_walled
    assert thin.ior == solid.ior == (1.3, 1.3, 1.3)
    assert repr(thin.surface.scattering) == repr(solid.surface.scattering)


def test_glossy_reflect_transmit_layers_tree():
    m = MATERIALS["glossy_reflect_transmit_layers"](reflection_color=(1.0, 0.0, 0.0),
                                                    transmission_color=(0.8, 0.9, 1.0),
                                                    roughness=0.02)
    top = m.surface.scattering
    assert top.name == "fresnel_layer" and top.kwargs["ior"] == 1.5 and m.ior == (1.5,) * 3
    layer, base = top.kwargs["layer"], top.kwargs["base"]
    assert (layer.name, layer.kwargs["mode"], layer.kwargs["tint"]) == (
        "simple_glossy_bsdf", "scatter_reflect", (1.0, 0.0, 0.0))
    assert (base.name, base.kwargs["mode"], base.kwargs["tint"]) == (
        "simple_glossy_bsdf", "scatter_transmit", (0.8, 0.9, 1.0))
    assert layer.kwargs["roughness_u"] == base.kwargs["roughness_u"] == 0.02


def test_coloured_layer_ior_uses_color_fresnel_layer():
    top = MATERIALS["glossy_reflect_transmit_layers"](layer_ior=(1.4, 1.5, 1.6)).surface.scattering
    assert top.name == "color_fresnel_layer" and tuple(top.kwargs["ior"]) == (1.4, 1.5, 1.6)


def test_absorption_coefficients_by_hand():
    m = MATERIALS["glossy_reflect_transmit_absorb"](absorption=(10, 6, 2))
    assert m.volume.absorption_coefficient == (10.0, 6.0, 2.0) and m.volume.scattering is None
    # Figure 4.11: transmission_color (0.8, 0.9, 1.0) kept after 0.05 m
    m = MATERIALS["glossy_reflect_transmit_absorb_falloff"](transmission_color=(0.8, 0.9, 1.0),
                                                           transmission_distance=0.05)
    sigma = np.array(m.volume.absorption_coefficient)
    assert np.allclose(np.exp(-sigma * 0.05), [0.8, 0.9, 1.0])
    assert np.allclose(sigma, [20 * math.log(1.25), 20 * math.log(10 / 9), 0.0])
    assert m.ior == (1.5, 1.5, 1.5)
    off = MATERIALS["glossy_reflect_transmit_absorb_falloff"](transmission_color=(0.5, 0.5, 0.5),
                                                             transmission_distance=0.0)
    assert off.volume.absorption_coefficient == (0.0, 0.0, 0.0)


# --- chapter 5 ---------------------------------------------------------------------------


def test_volume_enclosures():
    iso = MATERIALS["isotropic_volume"](scattering=(0.2, 0.2, 0.2), absorption=(0.1, 0.1, 0.1))
    node = iso.surface.scattering
    assert (node.name, node.kwargs["mode"], node.kwargs["tint"]) == (
        "specular_bsdf", "scatter_transmit", (1.0, 1.0, 1.0))
    assert iso.volume.scattering is None and iso.ior == (1.0, 1.0, 1.0)
    assert iso.volume.scattering_coefficient == (0.2,) * 3
    assert iso.volume.absorption_coefficient == (0.1,) * 3
    an = MATERIALS["anisotropic_volume"](directional_bias=-0.99, ior=(1.33,) * 3)
    assert an.volume.scattering.name == "anisotropic_vdf"
    assert an.volume.scattering.kwargs["directional_bias"] == -0.99 and an.ior == (1.33,) * 3
    assert MATERIALS["blue_scattering"]().volume.scattering_coefficient == (0.1, 0.1, 0.15)
    assert MATERIALS["blue_scattering"]().volume.absorption_coefficient == (0.3, 0.3, 0.3)
    assert MATERIALS["blue_absorption"]().volume.absorption_coefficient == (0.0, 0.0, 0.2)
    assert MATERIALS["blue_absorption"]().volume.scattering_coefficient == (0.5, 0.5, 0.5)


def test_lights():
    for name, colour in (("red_light", (1, 0, 0)), ("green_light", (0, 1, 0)),
                         ("blue_light", (0, 0, 1))):
        m = MATERIALS[name]()
        assert m.thin_walled and m.surface.scattering is None
        assert m.surface.emission.emission.name == "diffuse_edf"
        assert m.surface.emission.intensity == colour
    spot = MATERIALS["spotlight_emission"](spread_factor=0.1, tint=(3.0, 3.0, 3.0))
    edf = spot.surface.emission.emission
    assert spot.thin_walled and edf.name == "spot_edf"
    assert edf.kwargs["exponent"] == 1.0 and edf.kwargs["global_distribution"] is True
    assert math.isclose(edf.kwargs["spread"], 0.1 * math.pi)


# --- chapter 6 ---------------------------------------------------------------------------


def test_shiny_red_is_a_weighted_layer_by_hand():
    s = square([[0.3, 0.7]])
    for name in ("shiny_red", "shiny_red_with_let", "shiny_red_extract"):
        top = MATERIALS[name](shiny_weight=0.25).surface.scattering
        assert top.name == "weighted_layer" and top.kwargs["weight"] == 0.25
        assert repr(top.kwargs["layer"]) == repr(MATERIALS["shiny"]().surface.scattering)
        assert repr(top.kwargs["base"]) == repr(MATERIALS["red"]().surface.scattering)
        # eval = w layer + (1 - w) base (section 3.1 of the reference)
        expect = 0.25 * eval_at(MATERIALS["shiny"](), s) + 0.75 * eval_at(MATERIALS["red"](), s)
        assert np.allclose(eval_at(MATERIALS[name](shiny_weight=0.25), s), expect)


def test_glossy_over_diffuse_and_its_specializations():
    top = MATERIALS["light_blue_ceramic"]().surface.scattering
    assert top.kwargs["weight"] == 0.5
    assert top.kwargs["layer"].kwargs["tint"] == (0.1, 0.1, 0.08)
    assert top.kwargs["layer"].kwargs["roughness_u"] == 0.2
    assert top.kwargs["base"].kwargs["tint"] == (0.7, 0.8, 0.9)
    s = square([[0.1, 0.2]])
    assert np.allclose(eval_at(MATERIALS["shiny_red_specialized"](), s),
                       eval_at(MATERIALS["shiny_red"](), s))
    assert np.allclose(eval_at(MATERIALS["shiny_tint"]((0.3, 0.03, 0.05)), s),
                       eval_at(MATERIALS["shiny_red"](), s))


def test_fresnel_glossy_over_diffuse_at_ior_1_is_the_diffuse_base():
    # Figure 6.13: "For an ior value of 1.0, there is no reflection at all"
    s = square([[0.5, 0.5]])
    m = MATERIALS["fresnel_glossy_over_diffuse"](ior=(1.0, 1.0, 1.0), diffuse_tint=(0.4,) * 3)
    assert np.allclose(eval_at(m, s), 0.4 / math.pi * 0.8)
    top = MATERIALS["fresnel_glossy_over_diffuse"]().surface.scattering
    assert top.name == "fresnel_layer" and top.kwargs["ior"] == 1.3 and top.kwargs["weight"] == 1.0
    assert top.kwargs["layer"].kwargs["tint"] == (0.7, 0.7, 0.7)


def test_two_glossy_lobes_clamped_mix_by_hand():
    s = square([[0.5, 0.5]])
    one = chapter6.glossy((0.2, 0.3, 0.25), 0.3)
    two = chapter6.glossy((0.6, 0.4, 0.2), 0.6)
    f1, f2 = eval_at(one, s), eval_at(two, s)
    args = dict(tint_1=(0.2, 0.3, 0.25), roughness_1=0.3, tint_2=(0.6, 0.4, 0.2), roughness_2=0.6)
    m = MATERIALS["two_glossy_lobes"]
    assert np.allclose(eval_at(m(weight_1=1.0, weight_2=0.0, **args), s), f1)   # Figure 6.16
    assert np.allclose(eval_at(m(weight_1=0.0, weight_2=1.0, **args), s), f2)   # Figure 6.17
    assert np.allclose(eval_at(m(weight_1=0.3, weight_2=0.5, **args), s), 0.3 * f1 + 0.5 * f2)
    # clamped: the second component gets what is left below 1
    assert np.allclose(eval_at(m(weight_1=0.75, weight_2=0.5, **args), s), 0.75 * f1 + 0.25 * f2)
    top = m().surface.scattering
    assert top.name == "clamped_mix"


def layer_names(node: DfNode) -> list[str]:
    """The df names down the chain of bases."""
    out = []
    while isinstance(node, DfNode):
        out.append(node.name)
        node = node.kwargs.get("base")
    return out


def test_the_layer_series_of_section_6_5():
    assert layer_names(MATERIALS["two_layers"]().surface.scattering) == [
        "custom_curve_layer", "diffuse_reflection_bsdf"]
    assert layer_names(MATERIALS["three_layers"]().surface.scattering) == [
        "weighted_layer", "custom_curve_layer", "diffuse_reflection_bsdf"]
    assert layer_names(MATERIALS["four_layers"]().surface.scattering) == [
        "fresnel_layer", "weighted_layer", "custom_curve_layer", "diffuse_reflection_bsdf"]
    five = MATERIALS["five_layers"]().surface.scattering
    assert layer_names(five) == ["fresnel_layer", "weighted_layer", "custom_curve_layer",
                                 "diffuse_reflection_bsdf"]
    # the layers, top down: mirror (white), narrow blue, the orange/yellow clamped mix
    assert five.kwargs["ior"] == 1.6 and five.kwargs["weight"] == 1.0
    assert five.kwargs["layer"].name == "specular_bsdf"
    assert five.kwargs["layer"].kwargs["tint"] == (0.7, 0.7, 0.7)
    four = five.kwargs["base"]
    assert four.kwargs["weight"] == 0.3 and four.kwargs["layer"].kwargs["roughness_u"] == 0.2
    three = four.kwargs["base"]
    assert (three.kwargs["normal_reflectivity"], three.kwargs["grazing_reflectivity"],
            three.kwargs["exponent"], three.kwargs["weight"]) == (0.0, 1.0, 0.5, 1.0)
    assert three.kwargs["layer"].name == "clamped_mix"
    assert three.kwargs["base"].kwargs["tint"] == (0.1, 0.3, 0.05)
    assert MATERIALS["two_layers"]().surface.scattering.kwargs["layer"].kwargs["tint"] == (
        0.2, 0.3, 0.7)


# --- chapter 7 ---------------------------------------------------------------------------


def test_phonglike_plastic_normalized_mix_by_hand():
    s = square([[0.5, 0.5]])
    diffuse = MATERIALS["diffuse"]((0.15, 0.4, 0.0))
    glossy = chapter6.glossy((1.0, 1.0, 1.0), 0.2)
    fd, fg = eval_at(diffuse, s), eval_at(glossy, s)
    m = MATERIALS["phonglike_plastic"]
    assert np.allclose(eval_at(m(diffuse_color=(0.15, 0.4, 0.0)), s), 0.8 * fd + 0.2 * fg)
    # weights summing to 2 are halved (Figure 6.14)
    assert np.allclose(eval_at(m(diffuse_color=(0.15, 0.4, 0.0), diffuse_intensity=1.6,
                                 highlight_intensity=0.4), s), 0.8 * fd + 0.2 * fg)
    assert np.allclose(eval_at(m(diffuse_color=(0.15, 0.4, 0.0), highlight_intensity=0.0), s),
                       0.8 * fd)
    layered = eval_at(MATERIALS["phonglike_plastic_layered"](diffuse_color=(0.15, 0.4, 0.0)), s)
    assert np.allclose(layered, 0.8 * fd + 0.2 * fg)


def test_dielectric_plastics_tree():
    top = MATERIALS["dielectric_plastic"](ior=1.575, glossy_roughness=0.1).surface.scattering
    assert top.name == "fresnel_layer" and top.kwargs["ior"] == 1.575
    assert top.kwargs["layer"].kwargs["roughness_u"] == 0.1
    assert top.kwargs["base"].kwargs["tint"] == (0.5, 0.04, 0.04)
    two = MATERIALS["dielectric_plastic_two_lobe"]().surface.scattering
    assert two.name == "fresnel_layer" and two.kwargs["layer"].name == "normalized_mix"


def test_translucent_plastic_tree():
    m = MATERIALS["translucent_plastic"](transmission_weight=0.5)
    top = m.surface.scattering
    assert m.thin_walled and top.name == "custom_curve_layer"
    assert (top.kwargs["normal_reflectivity"], top.kwargs["grazing_reflectivity"],
            top.kwargs["exponent"], top.kwargs["weight"]) == (0.5, 1.0, 3.0, 1.0)
    assert repr(top.kwargs["layer"]) == repr(
        MATERIALS["dielectric_plastic_two_lobe"]().surface.scattering)
    assert top.kwargs["base"].name == "diffuse_transmission_bsdf"
    assert top.kwargs["base"].kwargs["tint"] == (0.9, 0.9, 0.9)
    # a varying transmission weight becomes a varying 1 - weight
    v = MATERIALS["translucent_plastic"](transmission_weight=lambda s: s.uv[:, 0])
    curve = v.surface.scattering.kwargs["normal_reflectivity"]
    assert np.allclose(curve(square([[0.25, 0.0], [1.0, 0.5]])), [0.75, 0.0])


def test_translucency_transmits_only():
    m = MATERIALS["translucency"]((0.95, 1.0, 0.9))
    s = square([[0.5, 0.5]])
    assert m.thin_walled and np.all(eval_at(m, s) == 0.0)
    assert np.allclose(eval_at(m, s, WO, WT), np.array([0.95, 1.0, 0.9]) / math.pi *
                       math.sqrt(0.71))


# --- chapter 8 ---------------------------------------------------------------------------


def test_bent_normal_by_hand():
    s = square([[0.5, 0.5], [0.0, 1.0]])   # normal +z, tangent_u +x
    assert np.allclose(chapter8.bent_normal(1.5)(s), np.array([1.5, 0.0, 1.0]) / math.sqrt(3.25))
    assert np.allclose(chapter8.bent_normal(-1.5)(s),
                       np.array([-1.5, 0.0, 1.0]) / math.sqrt(3.25))
    assert np.allclose(chapter8.bent_normal(0.0)(s), [0.0, 0.0, 1.0])
    with pytest.raises(ValueError, match="bend_factor must be finite"):
        chapter8.bent_normal(math.inf)


@settings(max_examples=40)
@given(st.floats(-1e6, 1e6), st.floats(-50, 50), st.floats(-50, 50))
def test_bent_normal_is_unit_and_finite(bend, u, v):
    s = UVSphere().state_at_uv(np.array([[u, v], [0.3, 0.0], [0.3, 1.0]]))
    n = chapter8.bent_normal(bend)(s)
    assert np.all(np.isfinite(n)) and np.allclose(np.linalg.norm(n, axis=1), 1.0)


def test_bent_normal_falls_back_where_the_sum_vanishes():
    s = square([[0.5, 0.5]])
    s = ShadingState(position=s.position, normal=s.normal, uv=s.uv,
                     tangent_u=-s.normal, tangent_v=s.tangent_v)
    assert np.allclose(chapter8.bent_normal(1.0)(s), [[0.0, 0.0, 1.0]])


def test_three_lobes_tree():
    top = MATERIALS["anisotropic_glossy_three_lobes"](tint=(0.2, 0.3, 0.2),
                                                      roughness=0.15).surface.scattering
    mid = top.kwargs["base"]
    bottom = mid.kwargs["base"]
    assert [top.kwargs["weight"], mid.kwargs["weight"], bottom.kwargs["weight"]] == [0.5, 0.5, 1.0]
    assert "base" not in bottom.kwargs                       # over bsdf()
    lobe = top.kwargs["layer"]
    assert (lobe.kwargs["roughness_u"], lobe.kwargs["roughness_v"]) == (0.15, 1.0)
    assert lobe.kwargs["tint"] == (0.2, 0.3, 0.2) and lobe.kwargs["mode"] == "scatter_reflect"
    assert mid.kwargs["layer"] is lobe and bottom.kwargs["layer"] is lobe
    s = square([[0.5, 0.5]])
    assert np.allclose(top.kwargs["normal"](s), [[0.0, 0.0, 1.0]])
    assert np.allclose(mid.kwargs["normal"](s), np.array([1.5, 0, 1]) / math.sqrt(3.25))
    assert np.allclose(bottom.kwargs["normal"](s), np.array([-1.5, 0, 1]) / math.sqrt(3.25))


@pytest.mark.parametrize("warp_to_weft, weight", [(3.0, 2.0 / 3.0), (1.0, 1.0), (0.5, 0.5),
                                                  (4.0, 0.75)])
def test_warp_weight_by_hand(warp_to_weft, weight):
    top = MATERIALS["warp_and_weft"](warp_to_weft=warp_to_weft).surface.scattering
    assert math.isclose(top.kwargs["base"].kwargs["weight"], weight)


def test_warp_and_weft_tree():
    top = MATERIALS["warp_and_weft"](shadowing=0.3).surface.scattering
    assert top.name == "custom_curve_layer" and "layer" not in top.kwargs   # black layer
    assert (top.kwargs["weight"], top.kwargs["normal_reflectivity"],
            top.kwargs["grazing_reflectivity"], top.kwargs["exponent"]) == (0.3, 0.05, 1.0, 3.0)
    mix = top.kwargs["base"]
    assert mix.kwargs["layer"].name == "weighted_layer"              # the weft's three lobes
    warp = mix.kwargs["base"]
    assert (warp.kwargs["roughness_u"], warp.kwargs["roughness_v"]) == (1.0, 0.3)
    assert warp.kwargs["tint"] == (0.3, 0.22, 0.3)
    # shadowing 0: the black layer takes nothing, the fabric is its warp and weft
    s = square([[0.4, 0.6]])
    assert np.allclose(eval_at(MATERIALS["warp_and_weft"](), s),
                       eval_at(material(surface=material_surface(scattering=mix)), s))


def test_iridescent_silk_tree():
    m = MATERIALS["iridescent_silk"](transmission_weight=0.05, shadowing=0.3)
    top = m.surface.scattering
    assert m.thin_walled and top.name == "custom_curve_layer"
    assert math.isclose(top.kwargs["normal_reflectivity"], 0.95)
    assert top.kwargs["layer"].name == "custom_curve_layer"
    assert top.kwargs["layer"].kwargs["weight"] == 0.3
    assert top.kwargs["base"].kwargs["tint"] == (0.95, 1.0, 0.95)


# --- arguments and captions --------------------------------------------------------------


@pytest.mark.parametrize("call, match", [
    (lambda: MATERIALS["spotlight_emission"](spread_factor=1.5), "spread_factor must be in"),
    (lambda: MATERIALS["anisotropic_volume"](directional_bias=2.0), "directional_bias"),
    (lambda: MATERIALS["isotropic_volume"](scattering=(-1.0, 0.0, 0.0)), "scattering must be >= 0"),
    (lambda: MATERIALS["specular_reflect_transmit"](ior=(0.0, 1.0, 1.0)), "ior must be > 0"),
    (lambda: MATERIALS["glossy_reflect_transmit_absorb"](absorption=(-1, 0, 0)), "absorption"),
    (lambda: MATERIALS["dielectric_plastic"](ior=0.0), "ior must be finite and > 0"),
    (lambda: MATERIALS["warp_and_weft"](warp_to_weft=math.nan), "warp_to_weft must be finite"),
    (lambda: MATERIALS["plaster"](tint=(1.0, 2.0)), "tint must be a color"),
    (lambda: MATERIALS["glossy_reflect_transmit_absorb_falloff"](transmission_color=0.0),
     "transmission_color must be > 0"),
])
def test_bad_arguments_raise_clear_errors(call, match):
    with pytest.raises(ValueError, match=match):
        call()


CAPTIONS = [
    "plaster(tint: color(0.3, 0.1, 0.1))",
    "specular_reflect_transmit(tint: color(0.8, 0.9, 1.0))",
    "specular_reflect_transmit_thin_walled(tint: color(0.64, 0.72, 0.80))",
    "glossy_reflect_transmit(roughness: .02, tint: color(0.8, 0.9, 1.0))",
    "glossy_reflect_transmit_layers(reflection_color: color(1.0, 0.95, 0.9), "
    "transmission_color: color(0.8, 0.9, 1.0), roughness: 0.02)",
    "glossy_reflect_transmit_absorb(absorption: color(10, 6, 2))",
    "glossy_reflect_transmit_absorb_falloff(transmission_color: color(0.8, 0.9, 1.0), "
    "transmission_distance: .05, roughness: 0.02)",
    "subsurface_scattering(transmission_color: color(0.8, 0.9, 1.0), "
    "scattering_color: color(.1, .1, .1), transmission_distance: .1)",
    "spotlight_emission(spread_factor: 0.3)",
    "shiny_red()",
    "glossy_over_diffuse(glossy_tint: color(0.1, 0.1, 0.08), glossy_roughness: 0.2, "
    "diffuse_tint: color(0.7, 0.8, 0.9))",
    "two_glossy_lobes(weight_1: 1, tint_1: color(orange), roughness_1: 0.6, weight_2: 0, "
    "tint_2: color(yellow), roughness_2: 0.3)",
    "phonglike_plastic(diffuse_color: color(.15, .4, 0), highlight_roughness: .05)",
    "dielectric_plastic_two_lobe(diffuse_color: color(.15, .4, 0), ior: 1.5894, "
    "glossy_roughness_1: 0.1, glossy_roughness_2: .35)",
    "translucent_plastic(diffuse_color: color(.15, .4, 0), ior: 1.5894, glossy_roughness_1: 0.1, "
    "glossy_roughness_2: .35, transmission_weight: 0.5, transmission_color: color(0.95, 1.0, 0.9))",
    "anisotropic_glossy(tint: color(.3, .22, .3), roughness_v: .3)",
    "anisotropic_glossy_three_lobes(tint: color(.2, .3, .2), roughness: .15)",
    "warp_and_weft(warp_color: color(.3, .22, .3), weft_color: color(.2, .3, .2))",
    "iridescent_silk(transmission_weight: .5)",
    "iridescent_silk(warp_color: color(.2, .3, .6), weft_color: color(.07, .05, .05), "
    "transmission_color: color(.95, .95, 1), transmission_weight: .05, shadowing: .3, "
    "warp_roughness: .3, weft_roughness: .15)",
]


@pytest.mark.parametrize("text", CAPTIONS)
def test_figure_captions_parse_and_shade(text):
    m = parse_material(text)
    sh = m.shade(square([[0.25, 0.75]]))
    if sh.bsdf is not None:
        assert np.all(np.isfinite(sh.bsdf.eval(WO[None], WI[None])))


def test_caption_values_reach_the_tree():
    m = parse_material("two_glossy_lobes(weight_1: 1, tint_1: color(orange), roughness_1: 0.6, "
                       "weight_2: 0, tint_2: color(yellow), roughness_2: 0.3)")
    s = square([[0.5, 0.5]])
    assert np.allclose(eval_at(m, s), eval_at(chapter6.glossy((0.3, 0.15, 0.0), 0.6), s))
