"""Material calls (the string form of scenes), through the MDL front end: every Handbook
caption call of chapters 12-15 parses and builds; malformed calls fail with exact
positions and fixes; garbage raises only MaterialExprError."""

from __future__ import annotations

import math
import pickle

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from displacement.fields import Field
from displacement.surfaces import UnitSquare
from render.expr import MAX_DEPTH, MaterialExprError, evaluate_expression, parse_material
from render.library.resources import load_profile
from render.material import material

#: The figure captions of chapters 12-14 as printed (Handbook line, text); chapter 15's
#: figures carry no calls.  Extracted from the ``` blocks that follow the figures.
CAPTIONS = [
    (5877, """\
waves_as_grayscale(
    frequency:
        float2(0.0, 4.0),
    gray_max:
        float2(0.0, 1.0))"""),
    (5894, """\
waves_as_grayscale(
  frequency:
    float2(4.0, 4.0),
  gray_max:
    float2(0.5, 0.5))"""),
    (5935, """\
waves_as_displacement(
    frequency:
        float2(0.0, 4.0),
    distance:
        float2(0.0, 0.1))"""),
    (5948, """\
waves_as_displacement(
    frequency:
        float2(4.0, 4.0),
    distance:
        float2(0.075, 0.075))"""),
    (6029, """\
waves(
    distance:
        float2(0.02, 0.02),
    frequency:
        float2(10.0, 10.0),
    tint:
        color(0.6, 0.4, 0.0),
    use_displacement: true)"""),
    (6047, """\
waves(
    distance:
        float2(0.02, 0.02),
    frequency:
        float2(10.0, 10.0),
    tint:
        color(0.6, 0.4, 0.0),
    use_displacement: false)"""),
    (6087, """\
glossy(
    tint:
        color(0.6, 0.4, 0.0))"""),
    (6135, """\
glossy_waves(
    distance:
        float2(0.02, 0.02),
    frequency:
        float2(10.0, 10.0),
    tint:
        color(0.6, 0.4, 0.0),
    use_displacement: true)"""),
    (6153, """\
glossy_waves(
  distance:
    float2(0.02, 0.02),
  frequency:
    float2(10, 10),
  tint:
    color(0.6, 0.4, 0.0),
  use_displacement: false)"""),
    (6234, """\
glossy_yellow_waves(
  distance:
    float2(0.02, 0.02),
  frequency:
    float2(10, 5))"""),
    (6270, """\
glass_waves(
    distance:
        float2(0.02, 0.02),
    frequency:
        float2(10, 5))"""),
    (6332, """\
green_glass_waves(
    distance:
        float2(0.04, 0.04),
    frequency:
        float2(20, 10))"""),
    (6418, """\
diffuse_weave(
  displace: 0.1,
  scale:
    float2(1, 1),
  tint:
    color(0.72, 0.75, 0.7))"""),
    (6437, """\
diffuse_weave(
  displace: 0.05,
  scale:
    float2(8, 4),
  tint:
    color(0.72, 0.75, 0.7))"""),
    (6492, """\
gold_weave(
    displace: 0.015,
    scale:
        float2(60, 30))"""),
    (6572, """\
scaled_uv(
  u_scale: 8,
  v_scale: 4)"""),
    (6582, """\
scaled_uv(
  u_scale: 80,
  v_scale: 40)"""),
    (6645, """\
scaled_uv_circle(
    u_scale: 8,
    v_scale: 4)"""),
    (6656, """\
scaled_uv_circle(
    u_scale: 80,
    v_scale: 40)"""),
    (6785, """\
glossy_round_bumps(
    u_scale: 8,
    v_scale: 4)"""),
    (6791, """\
glossy_round_bumps(
    u_scale: 4,
    v_scale: 4)"""),
    (6804, """\
glossy_round_bumps(
    u_scale: 80,
    v_scale: 40)"""),
    (6816, """\
glossy_round_bumps(
    u_scale: 80,
    v_scale: 40)"""),
    (6828, """\
glossy_round_bumps(
  u_scale: 80,
  v_scale: 40,
  bump_scale: -1.0)"""),
    (7069, """\
glossy_texture_weave_bump(
  tint:
    color(0.6, 0.4, 0.0),
  roughness: 0.3,
  texture_scale:
    float2(20, 10))"""),
    (7083, """\
glossy_texture_weave_bump(
  tint:
    color(0.6, 0.4, 0.0),
  roughness: 0.3,
  texture_scale:
    float2(100, 50))"""),
    (7392, """\
glossy_normal_map_weave(
    use_normal_for_color: true,
    normal_color_is_emission: false,
    texture_scale:
        float2(4, 4))"""),
    (7403, """\
glossy_normal_map_weave(
    use_normal_for_color: true,
    normal_color_is_emission: true,
    texture_scale:
        float2(4, 4))"""),
    (7416, """\
glossy_normal_map_weave(
    texture_scale:
        float2(4, 4))"""),
    (7427, """\
glossy_normal_map_weave(
    texture_scale:
        float2(40, 20))"""),
    (7440, """\
glossy_normal_map_weave(
  texture_scale:
    float2(4, 4),
  bump_scale: 0.2)"""),
    (7458, """\
glossy_normal_map_weave(
  texture_scale:
    float2(4, 4),
  bump_scale: 0.25,
  scale_vector_z: false)"""),
    (7473, """\
glossy_normal_map_weave(
    texture_scale:
        float2(40, 20),
    bump_scale: 0.25,
    scale_vector_z: true)"""),
    (7484, """\
glossy_normal_map_weave(
    texture_scale:
        float2(40, 20),
    bump_scale: 0.25,
    scale_vector_z: false)"""),
    (7733, """\
triangle(
    height: 0.25)"""),
    (7834, """\
circle_nonlinear(
  height: 0.5,
  count:
    float2(31.416, 20))"""),
    (8107, """\
bubble(
    radius: 0.35,
    height: 0.0,
    repeat:
        float2(1, 0))"""),
    (8123, """\
bubble(
    radius: 0.4,
    height: 0.2,
    repeat:
        float2(2, 0),
    grid_count:
        float2(4, 4))"""),
    (8142, """\
bubble(
  radius: 0.45,
  height: 0.42,
  repeat:
    float2(3, 0),
  grid_count:
    float2(8, 8),
  normalize_grid: true)"""),
    (8158, """\
bubble(
  radius: 0.4,
  height: -0.2,
  repeat:
    float2(4, 0),
  grid_count:
    float2(20, 20),
  normalize_grid: true)"""),
    (8449, """\
tee_displacement()"""),
    (8459, """\
tee_displacement(
  grid_count:
    float2(24, 24))"""),
    (8483, """\
tee_displacement(
    repeat: 3)"""),
    (8494, """\
tee_displacement(
    repeat: 3,
    grid_count:
        float2(24, 24))"""),
]

#: Calls printed inline or as listing bodies (parameters replaced by literal values).
OTHER_CALLS = [
    "circle_linear()",                                    # Figure 14.8
    "circle_linear(\nheight: 0.25)",                      # Figure 14.9
    "raise(scale: 0.2)",                                  # Figure 14.4
    "raise(scale: 0.0)",                                  # Figure 14.3
    "vector_displacement(move_up(0.2), grid(float2(4.0)))",                       # Listing 14.9
    "vector_displacement(triangle_displacement(u(), 0.25))",                      # Listing 14.11
    "vector_displacement(circle_nonlinear_vector(u(), 0.5), grid(float2(31.416, 20)))",
    "waver(surface_and_volume: glossy(color(0.6, 0.4, 0.0), 0.3), distance: float2(0.1),"
    " frequency: float2(1.0))",                                                   # Listing 12.12
    "weave(scale: float2(60, 30), displace: 0.015, surface_property: glossy(tint: color(0.6, 0.4, "
    "0.0), roughness: 0.3))",                                                     # Listing 12.18
    "round_bumps(glossy(color(0.6, 0.4, 0.0)), 1.0, 80, 40)",                     # Listing 13.7
    'texture_bump(glossy(color(0.7), 0.5), texture_2d("weave_depth.png", tex::gamma_linear), '
    "float2(1.0), float2(20, 10))",                                               # Listing 13.13
    'normal_map_bump(bump_scale: 1.0, texture_scale: float2(4, 4), scale_vector_z: true, '
    'surface_material: glossy_yellow(), texture: texture_2d("weave_normal_map.png", '
    "tex::gamma_linear), sample_min: 0.0, sample_max: 1.0, use_normal_for_color: false, "
    "normal_color_is_emission: true)",                                            # Listing 13.20
    "geometry::vector_displacement(displace_with_pwc(ornament_1::ornament_1, along_v), "
    "geometry::grid(float2(50, 50 * 1)))".replace(" * 1", ""),                    # Listing 15.9
    "geometry::vector_displacement(displace_with_pwc(ornament_2::ornament_2, along_v), "
    "travertine(1.0, ornament_2::ornament_2_length))",                            # Listing 15.11
    "grid_ornament_1()", "stone_ornament_2()",
    "radial_pwc(corinthian::corinthian, geometry::grid(float2(50.0)))",           # Listing 15.16
    "corinthian_capital_grid()",
    "radial_pwc(corinthian::corinthian, marbloid(scale: 12))",                   # Listing 15.18
    "corinthian_capital_stone()",
    "double_pwc(corinthian::corinthian, pwc_examples::doric_flutes, "
    "diffuse_reflection::diffuse_reflection(tint: pink_stone), radius_offset: 0.25)",  # 15.21
    "double_pwc(corinthian::corinthian, pwc_examples::ionic_flutes, "
    "diffuse_reflection::diffuse_reflection(tint: pink_stone), radius_offset: 0.25)",  # 15.22
    "doric_matte_stone()", "ionic_matte_stone()",
    "marbloid(scale: 12, level_count: 5, space: functions::object)",
    "radial_pwc(corinthian::corinthian, grid(), along_u)",
    "material(surface: material_surface(scattering: df::diffuse_reflection_bsdf(tint: "
    "color(0.5), roughness: 0.2)))",
    "material(thin_walled: true, surface: material_surface(emission: material_emission("
    "emission: df::diffuse_edf(), intensity: color(3.0), mode: intensity_power)))",
    "glossy(tint: grid_color(float2(8.0), color(0.0), color(0.6, 0.4, 0.0)))",
    "glossy(tint: texture_2d_lookup_scaled(texture_2d(\"travertine.png\", tex::gamma_srgb), 2, 2))",
    "vector_displacement(move_up(uv_wave(float2(4.0), float2(-0.1), float2(0.1))))",
    "grid(line_color: color(u(), v(), 0.0))",            # the commented-out line of 14.5
    # what the string form could not do before it was MDL (issue 11's "Why")
    "spotlight_emission(spread_factor: 0.5 * math::PI / math::PI, tint: color(2.0))",
    "material(surface: glossy(tint: color(0.6, 0.4, 0.0)).surface)",
    "let { color c = color(0.2, 0.4, 0.6); } in diffuse(tint: c * 0.5)",
    "glossy(tint: tex::lookup_color(texture_2d(\"travertine.png\"), float2(u(), v())))",
    "glossy(tint: u() > 0.5 ? color(1.0, 0.0, 0.0) : color(0.0, 0.0, 1.0))",
    "shiny_red(shiny_weight: state::position().x > 0.0 ? 0.2 : 0.8)",
    "material(surface: material_surface(scattering: normalized_mix(components: "
    "df::bsdf_component[](df::bsdf_component(weight: 1.0, component: "
    "df::diffuse_reflection_bsdf())))))",
]

STATE = UnitSquare().state_at_uv(np.random.default_rng(12).uniform(-1.0, 2.0, (64, 2)))


def check_builds(text: str) -> material:
    m = parse_material(text)
    assert isinstance(m, material)
    sh = m.shade(STATE)
    assert np.all(np.isfinite(sh.normal)) and np.all(np.isfinite(sh.intensity))
    if m.geometry.displacement is not None:
        assert np.all(np.isfinite(m.geometry.displacement(STATE)))
    return m


def test_caption_list_is_complete():
    assert len(CAPTIONS) == 44
    names = {text.split("(")[0] for _, text in CAPTIONS}
    assert {"waves_as_grayscale", "glass_waves", "gold_weave", "glossy_normal_map_weave", "bubble",
            "tee_displacement", "circle_nonlinear", "triangle"} <= names


@pytest.mark.parametrize("line, text", CAPTIONS, ids=[str(line) for line, _ in CAPTIONS])
def test_handbook_captions_parse_and_build(line, text):
    check_builds(text)


@pytest.mark.parametrize("text", OTHER_CALLS)
def test_listing_calls_parse_and_build(text):
    check_builds(text)


def test_caption_values_reach_the_material():
    m = parse_material(dict(CAPTIONS)[6135])         # Figure 12.9, glossy_waves
    assert m.geometry.displacement.parameters == {
        "distance": (0.02, 0.02), "frequency": (10.0, 10.0), "use_displacement": True}
    assert m.surface.scattering.kwargs["tint"] == (0.6, 0.4, 0.0)
    assert m.surface.scattering.kwargs["roughness_u"] == 0.3
    b = parse_material(dict(CAPTIONS)[8158])          # Figure 14.23, bubble with height < 0
    assert b.geometry.displacement.parameters["repeat"] == (4.0, 0.0)
    assert parse_material(dict(CAPTIONS)[6047]).geometry.displacement is None


def test_expression_equals_python_call():
    s = STATE
    a = parse_material("waves_as_grayscale(frequency: float2(4.0, 4.0), gray_max: float2(0.5))")
    from render.materials import MATERIALS

    b = MATERIALS["waves_as_grayscale"]((4.0, 4.0), (0.5, 0.5))
    assert np.array_equal(a.shade(s).bsdf.tint, b.shade(s).bsdf.tint)


def test_constants_stay_constants_and_varying_values_vary():
    """A value that depends on no state is computed once (the core then runs a constant
    program, as for the built-in material); one that does is a function of the state."""
    m = parse_material("glossy(tint: color(0.5) * 0.5 + color(0.1), roughness: 0.1 * 3)")
    assert m.surface.scattering.kwargs["tint"] == pytest.approx((0.35, 0.35, 0.35))
    assert m.surface.scattering.kwargs["roughness_u"] == pytest.approx(0.3)
    v = parse_material("glossy(tint: color(u(), v(), 0.0))").surface.scattering.kwargs["tint"]
    assert callable(v)
    assert np.allclose(v(STATE)[:, :2], STATE.uv) and np.all(v(STATE)[:, 2] == 0.0)


def test_profile_references():
    curve = load_profile("ornament_2")
    v = evaluate_expression("ornament_2::ornament_2")
    assert v.value is curve and str(v.type) == "pw_curve::pw_point[34]"
    v = evaluate_expression("ornament_2::ornament_2_length")
    assert str(v.type) == "float" and v.value == pytest.approx(curve.length, rel=1e-8)
    assert evaluate_expression("corinthian").value is load_profile("corinthian")


def test_profile_dirs_and_base_dir(tmp_path):
    (tmp_path / "my_molding.pwc").write_text("0 0\n.5 0\n.5 1\n")
    m = parse_material("radial_pwc(my_molding::my_molding, glossy())", profile_dirs=[tmp_path])
    assert isinstance(m.geometry.displacement, Field)
    with pytest.raises(MaterialExprError, match="unknown module 'my_molding'"):
        parse_material("radial_pwc(my_molding::my_molding, glossy())")
    from displacement.textures import write_texture

    write_texture(tmp_path / "ramp.png", np.tile(np.linspace(0.0, 1.0, 8), (4, 1)))
    m = parse_material('texture_bump(glossy(), texture_2d("ramp.png", tex::gamma_linear))',
                       base_dir=tmp_path)
    assert m.shade(STATE).normal.shape == (64, 3)


def test_values_and_types():
    assert evaluate_expression("float2(1, 2)").value == (1.0, 2.0)
    assert evaluate_expression("float3(0.5)").value == (0.5, 0.5, 0.5)
    assert evaluate_expression("color(float3(1, 2, 3))").value == (1.0, 2.0, 3.0)
    assert evaluate_expression("-color(0.5)").value == (-0.5, -0.5, -0.5)
    assert evaluate_expression("-(-4)").value == 4 and evaluate_expression("+.5f").value == 0.5
    assert evaluate_expression("float(3)").value == 3.0
    assert evaluate_expression("int(3.7)").value == 3
    assert evaluate_expression("int(-3.7)").value == -3
    assert evaluate_expression("math::PI").value == pytest.approx(math.pi)
    assert evaluate_expression("pink_stone").value == (0.7, 0.66, 0.63)
    assert str(evaluate_expression("df::scatter_reflect_transmit").type) == "df::scatter_mode"
    assert evaluate_expression("df::scatter_reflect_transmit").value == "scatter_reflect_transmit"
    assert evaluate_expression("true").value is True
    assert evaluate_expression('"a\\"b\\\\c"').value == 'a"b\\c'
    assert evaluate_expression("texture_2d()").value is None
    v = evaluate_expression("float2(u(), 0.25)")
    assert v.varying and v.value(STATE).shape == (64, 2)
    assert np.array_equal(v.value(STATE)[:, 0], STATE.uv[:, 0])
    assert evaluate_expression("state::normal()").varying
    assert str(evaluate_expression("df::diffuse_edf()").type) == "edf"
    assert evaluate_expression("1 // a comment").value == 1
    assert evaluate_expression("/* a\ncomment */ 2.5e-1").value == 0.25
    assert evaluate_expression("7 / 2").value == 3 and evaluate_expression("7.0 / 2").value == 3.5
    assert evaluate_expression("glossy().ior").value == (1.0, 1.0, 1.0)


# --- errors ---------------------------------------------------------------------------

#: (text, line, col, text at the reported offset, message part, fix part)
MALFORMED = [
    ("glosy()", 1, 1, "glosy", "unknown function 'glosy'", "did you mean 'glossy'?"),
    ("glossy(tnt: color(0.5))", 1, 8, "tnt", "glossy has no parameter 'tnt'",
     "did you mean 'tint'?"),
    ("glossy(tint: 0.5)", 1, 14, "0.5", "argument 'tint' must be a color, got a float",
     "write color(x)"),
    ("glossy(roughness: color(0.5))", 1, 19, "color", "must be a float, got a color", None),
    ("glossy(tint: float3(0.5))", 1, 14, "float3", "must be a color, got a float3",
     "convert with color(...)"),
    ("grid(texture_space: 1.5)", 1, 21, "1.5", "must be an int, got a float",
     "write an integer"),
    ("waves_as_grayscale(frequency: float2(u(), 4))", 1, 31, "float2", "is uniform, but this "
     "value varies over the surface", "pass a constant"),
    ("waver(glossy(), frequency: 3)", 1, 28, "3", "must be a float2, got an int",
     "write float2(x)"),
    ("waver()", 1, 1, "waver", "needs the argument 'surface_and_volume' (material)",
     "add surface_and_volume:"),
    ("df::simple_glossy_bsdf(tint: color(0.5))", 1, 1, "df::", "needs the argument 'roughness_u'",
     None),
    ("glossy(color(0.5), 0.3, 1)", 1, 25, "1)", "glossy takes 2 arguments, got 3", "remove"),
    ("glossy(tint: color(0.5), 0.3)", 1, 26, "0.3", "positional argument after a named", None),
    ("glossy(tint: color(0.5), tint: color(0.1))", 1, 26, "tint", "the argument 'tint' twice",
     "give each argument once"),
    ("glossy(tint: color(0.5)", 1, 24, "", "missing ')' to close the argument list", "add ')'"),
    ("glossy(tint: color(0.5),)", 1, 25, ")", "expected an argument after ','",
     "remove the trailing ','"),
    ("glossy(tint color(0.5))", 1, 13, "color", "expected ',' or ')' in the argument list",
     "separate arguments with ','"),
    ("glossy(tint: color(0.5)) extra", 1, 26, "extra", "unexpected 'extra' after the expression",
     None),
    ("glossy(,", 1, 8, ",", "expected an expression, found ','", None),
    ("glossy(tint: )", 1, 14, ")", "expected a value for argument 'tint'", None),
    ("", 1, 1, "", "empty expression", None),
    ("glossy", 1, 1, "glossy", "'glossy' is a material; it must be called", "write glossy(...)"),
    ("-glossy()", 1, 1, "-", "cannot negate a material", None),
    ("glossy(tint: color(0.5, 0.5))", 1, 14, "color", "color constructor needs 3 values but got "
     "2", "write color(x) or color(r, g, b)"),
    ('glossy(tint: color("a"))', 1, 20, '"a"', "cannot make a color from a string", None),
    ("color(0.5)", 1, 1, "color", "the expression is a color, not a material", None),
    ("radial_pwc(ornament_3::ornament_3, glossy())", 1, 12, "ornament_3",
     "unknown module 'ornament_3'", "did you mean 'ornament_"),
    ("radial_pwc(corinthian::corinthian, glossy(), along_w)", 1, 46, "along_w",
     "undeclared identifier 'along_w'", "did you mean 'along_"),
    ('marbloid(space: "texture")', 1, 17, '"texture"', "must be a functions::mapping_mode, got "
     "a string", "an enum value is a name, not a string: one of uvw, object, world"),
    ('texture_bump(glossy(), texture_2d("weave_depth.pgn"))', 1, 35, '"weave',
     "texture 'weave_depth.pgn' not found", "did you mean 'weave_depth.png'?"),
    ('normal_map_bump(texture: texture_2d("weave_normal_map.tif"))', 1, 37, '"weave',
     "not found", "did you mean 'weave_normal_map.png'?"),
    ("bubble(radius: 0.2, height: 0.3)", 1, 21, "height", "bubble(...): bubble height 0.3", None),
    ("marbloid(level_count: 100)", 1, 10, "level_count", "level_count must be in [0, 64]", None),
    ("grid(cell_count: float2(0))", 1, 6, "cell_count", "cell_count must not be 0", None),
    ('"unterminated', 1, 1, '"', "unterminated string", None),
    ("glossy(roughness: 1e999)", 1, 19, "1e999", "too large", None),
    ("glossy(roughness: 3x)", 1, 19, "3x", "malformed number '3x'", None),
    ("glossy(roughness: 0.3 @)", 1, 23, "@", "unexpected character '@'", None),
    ("raise(scale: 99999999999)", 1, 14, "999", "too large", None),
    ("glossy().surface", 1, 1, "glossy", "the expression is a material_surface, not a material",
     None),
    ("glossy(\n  tnt:\n    color(0.5))", 2, 3, "tnt", "no parameter 'tnt'", "did you mean 'tint'?"),
    ("glossy(\n    tint:\n        0.5)", 3, 9, "0.5", "must be a color", None),
    ("glossy(/* unclosed", 1, 8, "/*", "unterminated block comment", None),
    ("glossy(tint: color(0.5)))", 1, 25, ")", "unexpected ')' after the expression", None),
    ("glossy(tint:: color(0.5))", 1, 8, "tint", "unknown module 'tint'",
     "a named argument is written 'name: value'"),
    ("foo::glossy()", 1, 1, "foo", "unknown module 'foo'", None),
    ("glossy(tint: colours::pink_stone)", 1, 14, "colours", "unknown module 'colours'", None),
    ("glossy(tint: glossy().surface.scattering)", 1, 14, "glossy", "must be a color, got a bsdf",
     None),
    ("glossy(tint: u() > 0.5 ? glossy() : glossy())", 1, 14, "u()", "a material cannot be "
     "chosen per point", None),
    ("glossy(tint: 0.5 > 0.2 ? glossy() : glossy())", 1, 14, "0.5", "must be a color, got a "
     "material", None),
    ("material(surface: u() > 0.5 ? glossy().surface : diffuse().surface)", 1, 19, "u()",
     "cannot be chosen per point", "use a uniform condition"),
    ('space_as_color(mode: "object", scale: 4)', 1, 22, '"object"', "got a string",
     "an enum value is a name, not a string"),
]


@pytest.mark.parametrize("text, line, col, at, message, fix", MALFORMED,
                         ids=[m[0][:40] for m in MALFORMED])
def test_malformed_calls(text, line, col, at, message, fix):
    with pytest.raises(MaterialExprError) as info:
        parse_material(text)
    e = info.value
    assert (e.line, e.col) == (line, col), str(e)
    assert text[e.offset:].startswith(at), (text[e.offset:], str(e))
    assert message in e.message, str(e)
    if fix is not None:
        assert e.fix is not None and fix in e.fix, str(e)
    assert str(e).startswith(f"{line}:{col}: ")


def test_nesting_limit():
    deep = "(" * (MAX_DEPTH + 5) + "glossy()" + ")" * (MAX_DEPTH + 5)
    with pytest.raises(MaterialExprError, match=f"nesting too deep \\(more than {MAX_DEPTH}"):
        parse_material(deep)
    ok = "(" * 10 + "glossy()" + ")" * 10
    assert isinstance(parse_material(ok), material)


def test_error_is_a_value_error_and_pickles():
    e = MaterialExprError("boom", 3, "fix it", line=2, offset=9)
    assert isinstance(e, ValueError)
    back = pickle.loads(pickle.dumps(e))
    assert (back.message, back.col, back.fix, back.line, back.offset) == ("boom", 3, "fix it", 2, 9)


def test_non_string_input():
    with pytest.raises(MaterialExprError, match="must be a string"):
        parse_material(42)


# --- robustness --------------------------------------------------------------------------

_VOCABULARY = ["glossy", "waves", "grid", "bubble", "raise", "radial_pwc", "double_pwc",
               "marbloid", "float2", "float3", "color", "texture_2d", "material",
               "material_surface", "df::diffuse_reflection_bsdf", "df::simple_glossy_bsdf",
               "u", "v", "move_up", "uv_wave", "corinthian::corinthian", "ornament_2_length",
               "along_u", "object", "true", "false", "tint", "scale", "repeat", "height",
               "radius", "(", ")", ",", ":", "::", "-", "+", ".", "0", "1", "0.5", "-3.5e2",
               "1e999", "1e-320", '"weave_depth.png"', '"x', "/*", "*/", "//", "\n", " ", "@",
               "\\", "'", "\u00e9", "\x00", "9" * 30, "*", "?", "let", "{", "}", "in", ";",
               ".surface", "[", "]", "math::PI"]


@settings(max_examples=400, suppress_health_check=[HealthCheck.too_slow])
@given(st.lists(st.sampled_from(_VOCABULARY), max_size=30))
def test_token_soup_raises_only_material_expr_error(parts):
    text = " ".join(parts)
    _only_expr_errors(text)


@settings(max_examples=300, suppress_health_check=[HealthCheck.too_slow])
@given(st.text(max_size=60))
def test_random_text_raises_only_material_expr_error(text):
    _only_expr_errors(text)


@settings(max_examples=300, suppress_health_check=[HealthCheck.too_slow])
@given(st.sampled_from([t for _, t in CAPTIONS] + OTHER_CALLS), st.integers(0, 10_000),
       st.integers(0, 3), st.sampled_from(list("(),:-.0123456789aez_\" ")))
def test_mutated_captions_raise_only_material_expr_error(text, position, operation, char):
    i = position % (len(text) + 1)
    if operation == 0:
        text = text[:i] + text[i + 1:]                 # delete
    elif operation == 1:
        text = text[:i] + char + text[i:]              # insert
    elif operation == 2:
        text = text[:i] + char + text[i + 1:]          # replace
    else:
        text = text[:i]                                # truncate
    _only_expr_errors(text)


def _only_expr_errors(text: str) -> None:
    try:
        m = parse_material(text)
    except MaterialExprError as e:
        assert e.line >= 1 and e.col >= 1 and 0 <= e.offset <= len(text)
        lines = text.split("\n")
        assert e.line <= len(lines) and e.col <= len(lines[e.line - 1]) + 1
        return
    assert isinstance(m, material)
