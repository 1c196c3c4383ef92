"""The Handbook's Part 4 materials (chapters 9 and 10) and chapter 9's functions: names,
parameters and defaults as listed; stripe, checkerboard, uv and texture colours worked
out by hand from Listings 9.4-9.27; noise colours at lattice points (Listings 10.4-10.6);
shading at ordinary and extreme states without NaN; every figure caption parses; every
chapter of Parts 2-4 has at least three gallery figures."""

from __future__ import annotations

import inspect
import math
import runpy
import tomllib
from collections import Counter

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from repo import ROOT

from displacement.state import ShadingState
from displacement.surfaces import Torus, UnitSquare, UVSphere
from render.expr import MaterialExprError, parse_material
from render.library import FUNCTIONS, patterns
from render.material import material, mdl_signature
from render.materials import MATERIALS, PART4, chapter9

C0 = (0.0, 0.0, 0.0)
C1 = (1.0, 1.0, 1.0)

#: The Handbook's signatures, in listing order, with their defaults.
HANDBOOK = {
    # chapter 9
    "uv_as_color_material": [],
    "uv_as_color": [],
    "generic_diffuse_material": [("diffuse_color", C1)],
    "tex2d_diffuse": [],
    "tex2d_diffuse_scaled": [("u_scale", 1.0), ("v_scale", 1.0)],
    "uvw_space_as_color": [],
    "space_as_color": [("mode", "uvw"), ("scale", 1.0)],
    "horizontal_stripes": [("stripe_color", C0), ("bg_color", C1)],
    "horizontal_stripes_component": [("stripe_color", C0), ("bg_color", C1), ("mode", "uvw"),
                                     ("interval", 0.2), ("thickness", 0.1)],
    "red_stripes_on_yellow": [],
    "checkerboard": [("color_1", C0), ("color_2", C1), ("mode", "uvw")],
    # chapter 10
    "perlin_noise_material": [("color_1", C0), ("color_2", C1), ("scale", 1.0),
                              ("space", "object")],
    "summed_noise_material": [("color_1", C0), ("color_2", C1), ("scale", 1.0),
                              ("level_count", 4), ("turbulence", False), ("space", "object")],
}

#: Every figure caption of chapters 9 and 10 (Figures 9.1 and 9.9 print none).  Figures
#: 9.7 and 9.8 print ``mode: "object"``, a string for the enum ``mapping_mode``, which MDL
#: refuses (see test_the_handbooks_quoted_enum_is_refused_with_a_fix): here as MDL writes it.
CAPTIONS = [
    "tex2d_diffuse()",
    "tex2d_diffuse_scaled(u_scale: 10, v_scale: 5)",
    "uvw_space_as_color()",
    'space_as_color(mode: object, scale: 4)',
    'space_as_color(mode: world, scale: 4)',
    "horizontal_stripes(stripe_color: color(.4, .5, .3), bg_color: color(.8, .7, .1))",
    "red_stripes_on_yellow()",
    "checkerboard(color_1: color(.3, .4, .5), color_2: color(.8, .7, .1))",
    "perlin_noise_material(scale: 10)",
    "summed_noise_material(scale: 3)",
    "summed_noise_material(scale: 3, turbulence: true)",
]

WO = np.array([0.3, 0.4, math.sqrt(0.75)])
WI = np.array([-0.6, 0.0, 0.8])


def square(uv) -> ShadingState:
    return UnitSquare().state_at_uv(np.asarray(uv, dtype=np.float64).reshape(-1, 2))


def tint_of(m: material, state: ShadingState) -> np.ndarray:
    tint = m.surface.scattering.kwargs["tint"]
    return np.asarray(tint(state) if callable(tint) else np.broadcast_to(tint, (len(state), 3)))


def extreme_states() -> list[ShadingState]:
    rng = np.random.default_rng(11)
    uv = np.array([[0.0, 0.0], [1.0, 1.0], [0.0, 1.0], [0.5, 0.5], [-0.25, -3.75],
                   [-1.0, -1.0], [1e-12, 1.0 - 1e-12], [1e6 + 0.1, -1e6 + 0.7]])
    return [square(uv), square(rng.uniform(-3, 3, (200, 2))),
            UVSphere().state_at_uv(np.array([[0.3, 0.0], [0.3, 1.0], [0.0, 0.5], [1.0, 0.5]])),
            Torus().state_at_uv(rng.random((40, 2)))]


@pytest.fixture(scope="module")
def uv_texture():
    """The generator of gallery/textures/uv.png (a script, so loaded by path)."""
    return runpy.run_path(str(ROOT / "gallery" / "textures" / "make_uv_texture.py"))


# --- registry ---------------------------------------------------------------------------


def test_registry_has_every_listing():
    assert set(PART4) == set(HANDBOOK)
    assert set(PART4) <= set(MATERIALS)
    assert set(chapter9.__all__) - {"UV_TEXTURE"} <= set(PART4)


@pytest.mark.parametrize("name", sorted(HANDBOOK))
def test_parameters_and_defaults_are_the_handbooks(name):
    params = list(inspect.signature(MATERIALS[name]).parameters.values())
    assert [p.name for p in params] == [p for p, _ in HANDBOOK[name]]
    for p, (_, default) in zip(params, HANDBOOK[name], strict=True):
        assert p.default == default, p.name
    params, returns = mdl_signature(MATERIALS[name])
    assert str(returns) == "material"
    # the enum parameters are mapping_mode, constant as MDL's enum arguments are
    assert {p.name for p in params if p.type.is_enum} <= {"mode", "space"}


@pytest.mark.parametrize("name", sorted(HANDBOOK))
def test_builds_with_defaults_and_shades_finite(name):
    m = MATERIALS[name]()
    assert isinstance(m, material)
    assert m.surface.scattering.name == "diffuse_reflection_bsdf"
    rng = np.random.default_rng(5)
    for state in extreme_states():
        n = len(state)
        tint = tint_of(m, state)
        assert tint.shape == (n, 3) and np.all(np.isfinite(tint))
        for front in (np.ones(n, dtype=bool), np.zeros(n, dtype=bool)):
            sh = m.shade(state, front)
            assert np.all(np.isfinite(sh.normal))
            wo = rng.normal(size=(n, 3))
            wo[:, 2] = np.abs(wo[:, 2])
            wo /= np.linalg.norm(wo, axis=1, keepdims=True)
            wi = rng.normal(size=(n, 3))
            wi[:, 2] = np.abs(wi[:, 2])
            wi /= np.linalg.norm(wi, axis=1, keepdims=True)
            f = sh.bsdf.eval(wo, wi)
            assert f.shape == (n, 3) and np.all(np.isfinite(f)) and np.all(f >= 0.0)


# --- chapter 9: colours by hand -----------------------------------------------------------


@pytest.mark.parametrize("name", ["uv_as_color_material", "uv_as_color", "uvw_space_as_color"])
def test_texture_coordinates_as_color(name):
    s = square([[0.25, 0.75], [0.0, 1.0], [-0.5, 2.0]])
    # color(state::texture_coordinate(0)) = (u, v, w = 0), not clamped (Listings 9.4-9.6, 9.17)
    assert tint_of(MATERIALS[name](), s).tolist() == [[0.25, 0.75, 0.0], [0.0, 1.0, 0.0],
                                                      [-0.5, 2.0, 0.0]]
    # the bsdf saturates its tint: Lambert tint / pi * cos(wi)
    f = MATERIALS[name]().shade(s).bsdf.eval(np.tile(WO, (3, 1)), np.tile(WI, (3, 1)))
    assert np.allclose(f, np.array([[0.25, 0.75, 0.0], [0.0, 1.0, 0.0], [0.0, 1.0, 0.0]])
                       * 0.8 / math.pi)


def test_generic_diffuse_material_takes_the_color():
    m = MATERIALS["generic_diffuse_material"](diffuse_color=(0.2, 0.4, 0.6))
    assert m.surface.scattering.kwargs["tint"] == (0.2, 0.4, 0.6)
    assert tint_of(MATERIALS["generic_diffuse_material"](), square([[0.5, 0.5]])).tolist() == [
        [1.0, 1.0, 1.0]]


def test_space_as_color_by_hand():
    # the unit square's object position is (u, v, 0): frac(4 * (0.3, 0.55, 0)) = (0.2, 0.2, 0)
    s = square([[0.3, 0.55], [-0.3, 0.0]])
    got = tint_of(MATERIALS["space_as_color"](mode="object", scale=4.0), s)
    assert np.allclose(got, [[0.2, 0.2, 0.0], [0.8, 0.0, 0.0]])  # frac(-1.2) = 0.8
    # uvw with the default scale 1: frac(u), frac(v)
    got = tint_of(MATERIALS["space_as_color"](), square([[1.25, -0.25]]))
    assert np.allclose(got, [[0.25, 0.75, 0.0]])
    # on a sphere, object space is centred on the sphere (radius 1 here): the pole
    pole = UVSphere().state_at_uv(np.array([[0.3, 1.0]]))
    expect = (4.0 * pole.position) % 1.0
    assert np.allclose(tint_of(MATERIALS["space_as_color"]("object", 4.0), pole), expect)


def test_horizontal_stripes_by_hand():
    m = MATERIALS["horizontal_stripes"](stripe_color=(0.4, 0.5, 0.3), bg_color=(0.8, 0.7, 0.1))
    # stripes 0.1 wide on every multiple of 0.2 of v: |v - 0.2 k| < 0.05
    v = np.array([0.0, 0.04, 0.06, 0.1, 0.14, 0.16, 0.41, 0.5, 0.97, 1.0, -0.02, -0.1])
    s = square(np.stack([np.full(v.shape, 0.3), v], axis=1))
    inside = [True, True, False, False, False, True, True, False, True, True, True, False]
    expect = np.where(np.array(inside)[:, None], (0.4, 0.5, 0.3), (0.8, 0.7, 0.1))
    assert np.array_equal(tint_of(m, s), expect)
    # u does not matter
    s2 = square(np.stack([np.full(v.shape, -7.9), v], axis=1))
    assert np.array_equal(tint_of(m, s2), expect)


def test_red_stripes_on_yellow_by_hand():
    m = MATERIALS["red_stripes_on_yellow"]()
    # interval 0.05, thickness 0.0075: |v - 0.05 k| < 0.00375
    s = square([[0.5, 0.1], [0.5, 0.103], [0.5, 0.105], [0.5, 0.125], [0.5, 0.148]])
    red, yellow = (0.5, 0.2, 0.0), (0.8, 0.7, 0.1)
    assert np.allclose(tint_of(m, s), [red, red, yellow, yellow, red])


def test_horizontal_stripes_component_passes_every_parameter():
    m = MATERIALS["horizontal_stripes_component"](stripe_color=(1.0, 0.0, 0.0), bg_color=C0,
                                                  mode="object", interval=0.5, thickness=0.2)
    # object y of the unit square is v: stripes |v - 0.5 k| < 0.1
    s = square([[0.0, 0.05], [0.0, 0.2], [0.0, 0.45], [0.0, 0.55], [0.0, 0.75]])
    assert tint_of(m, s)[:, 0].tolist() == [1.0, 0.0, 1.0, 1.0, 0.0]


def test_checkerboard_by_hand():
    m = MATERIALS["checkerboard"](color_1=(0.3, 0.4, 0.5), color_2=(0.8, 0.7, 0.1))
    # stripes |x - 0.2 k| < 0.05 in u and in v; color_1 where exactly one holds
    uv = [[0.0, 0.0], [0.1, 0.0], [0.0, 0.1], [0.1, 0.1], [0.3, 0.2], [0.21, 0.39],
          [-0.1, 0.0], [1.0, 1.0], [0.95, 0.1]]
    one, two = (0.3, 0.4, 0.5), (0.8, 0.7, 0.1)
    expect = [two, one, one, two, one, two, one, two, two]
    assert np.allclose(tint_of(m, square(uv)), expect)
    # the material's defaults swap the pattern's: black where exactly one stripe holds
    assert tint_of(MATERIALS["checkerboard"](), square([[0.1, 0.0], [0.0, 0.0]])).tolist() == [
        [0.0, 0.0, 0.0], [1.0, 1.0, 1.0]]


@settings(max_examples=60)
@given(st.floats(-20, 20), st.floats(-20, 20))
def test_checkerboard_mirrors_at_the_axes_and_alternates(u, v):
    m = MATERIALS["checkerboard"]()
    t = tint_of(m, square([[u, v], [-u, v], [u, -v], [-u, -v]]))
    assert np.all(t == t[0])
    # one cell (0.1) further in u flips the colour, away from the cell edges
    d = (abs(u) + 0.05) % 0.1
    e = (abs(v) + 0.05) % 0.1
    if min(d, 0.1 - d) > 1e-6 and min(e, 0.1 - e) > 1e-6:
        u0 = abs(u)
        a, b = tint_of(m, square([[u0, v], [u0 + 0.1, v]]))
        assert np.array_equal(a, 1.0 - b)


def test_tex2d_diffuse_reads_uv_png_at_cell_centres(uv_texture):
    cells = uv_texture["CELLS"]
    c = (np.arange(cells) + 0.5) / cells
    u, v = (a.ravel() for a in np.meshgrid(c, c))
    got = tint_of(MATERIALS["tex2d_diffuse"](), square(np.stack([u, v], axis=1)))
    # 8-bit sRGB quantization: half a step at the top of the curve is < 0.005 linear
    assert np.allclose(got, uv_texture["uv_color"](u, v), atol=5e-3)
    # the origin is the lower-left corner (section 9.3): the cell (0, 0) is dark and bluish,
    # the cell at the upper right bright yellow, and the origin cell has the white mark
    assert got[0, 2] > got[0, 0] and np.all(got[-1, :2] > 0.8)
    mark = tint_of(MATERIALS["tex2d_diffuse"](), square([[0.02, 0.05]]))
    assert np.allclose(mark, 1.0, atol=5e-3)


def test_uv_png_is_current(uv_texture, tmp_path):
    from displacement.textures import read_texture

    fresh = read_texture(uv_texture["main"](out_dir=tmp_path), gamma="linear").data
    shipped = read_texture(ROOT / "gallery" / "textures" / "uv.png", gamma="linear").data
    assert np.array_equal(fresh, shipped), "run python gallery/textures/make_uv_texture.py"


def test_tex2d_diffuse_scaled_repeats_the_image():
    scaled = MATERIALS["tex2d_diffuse_scaled"](u_scale=10.0, v_scale=5.0)
    plain = MATERIALS["tex2d_diffuse"]()
    # frac(10 * 0.13) = 0.3, frac(5 * 0.37) = 0.85; negative uv: frac is positive
    got = tint_of(scaled, square([[0.13, 0.37], [-0.07, -0.03]]))
    expect = tint_of(plain, square([[0.3, 0.85], [0.3, 0.85]]))
    assert np.allclose(got, expect, atol=1e-12)
    assert np.allclose(tint_of(MATERIALS["tex2d_diffuse_scaled"](), square([[0.3, 0.85]])),
                       expect[:1], atol=1e-12)


# --- chapter 9: the functions -------------------------------------------------------------


def test_stripe_by_hand_and_degenerate_intervals():
    f = np.array([0.0, 0.04, 0.06, 0.1, 0.14, 0.16, -0.18, 1e6 + 0.01, 1e6 + 0.1])
    assert patterns.stripe(f, 0.2, 0.1).tolist() == [True, True, False, False, False, True,
                                                     True, True, False]
    with np.errstate(all="raise"):
        assert patterns.stripe(f, 0.0, 0.1).all()  # ever denser stripes cover everything
        assert not patterns.stripe(f, 0.0, 0.0).any()
        assert not patterns.stripe(f, 0.2, 0.0).any()  # zero thickness: no stripe
        # thickness = interval: everything but the midpoints between centres (strict <, >)
        assert patterns.stripe(f, 0.2, 0.2).tolist() == [True] * 3 + [False] + [True] * 4 + [
            False]


@settings(max_examples=200)
@given(st.floats(-50, 50), st.floats(0.01, 5.0), st.floats(0.0, 1.0))
def test_stripe_is_the_distance_to_the_nearest_multiple(f, interval, fraction):
    thickness = fraction * interval
    d = abs(f) % interval
    near = min(d, interval - d)
    if abs(near - thickness / 2.0) > 1e-9 * (1.0 + abs(f) / interval):
        assert bool(patterns.stripe(f, interval, thickness)) == (near < thickness / 2.0)


def test_exclusive_or_truth_table():
    a = np.array([False, False, True, True])
    b = np.array([False, True, False, True])
    assert patterns.exclusive_or(a, b).tolist() == [False, True, True, False]
    assert patterns.exclusive_or(a, b).tolist() == np.logical_xor(a, b).tolist()


def test_white_above_value_by_hand():
    s = square([[0.5, 0.25], [0.5, 0.75], [0.5, 0.5], [0.5, -2.0]])
    assert patterns.white_above_value(s, 0.5)[:, 0].tolist() == [0.0, 1.0, 0.0, 0.0]
    assert patterns.white_above_value(s)[:, 1].tolist() == [1.0, 1.0, 1.0, 0.0]  # y > 0.0


def test_library_calls_in_material_expressions():
    # the patterns as function calls for generic_diffuse_material (Listing 9.8)
    text = ("generic_diffuse_material(diffuse_color: checkerboard_pattern(color_1: "
            "color(.3, .4, .5), color_2: color(.8, .7, .1), mode: uvw))")
    s = square(np.random.default_rng(3).uniform(-2, 2, (100, 2)))
    # the pattern's color_1/color_2 are the material's (Listing 9.27 passes them through)
    expect = tint_of(MATERIALS["checkerboard"]((0.3, 0.4, 0.5), (0.8, 0.7, 0.1)), s)
    assert np.array_equal(tint_of(parse_material(text), s), expect)
    text = ("generic_diffuse_material(diffuse_color: horizontal_stripe_pattern("
            "stripe_color: color(.4, .5, .3), bg_color: color(.8, .7, .1)))")
    expect = tint_of(MATERIALS["horizontal_stripes"]((0.4, 0.5, 0.3), (0.8, 0.7, 0.1)), s)
    assert np.array_equal(tint_of(parse_material(text), s), expect)
    text = "generic_diffuse_material(diffuse_color: white_above_value(y_value: 0.5))"
    assert tint_of(parse_material(text), square([[0.0, 0.25], [0.0, 0.75]]))[:, 0].tolist() == [
        0.0, 1.0]
    for name in ("uvw_position", "object_position", "world_position"):
        assert np.array_equal(FUNCTIONS[name]()(s), s.position if name != "uvw_position"
                              else np.c_[s.uv, np.zeros(len(s))])


@pytest.mark.parametrize("call, match", [
    (lambda: MATERIALS["horizontal_stripes_component"](interval=0.0), "interval must be"),
    (lambda: MATERIALS["horizontal_stripes_component"](interval=-0.2), "interval must be"),
    (lambda: MATERIALS["horizontal_stripes_component"](interval=math.inf), "interval must be"),
    (lambda: MATERIALS["horizontal_stripes_component"](mode="texture"), "mode must be one of"),
    (lambda: MATERIALS["checkerboard"](mode="local"), "mode must be one of"),
    (lambda: MATERIALS["space_as_color"](mode="uv"), "mode must be one of"),
    (lambda: MATERIALS["checkerboard"](color_1=(1.0, 0.0)), "color_1 must be a color"),
    (lambda: MATERIALS["horizontal_stripes"](bg_color=(math.nan, 0, 0)), "bg_color must be"),
    (lambda: MATERIALS["generic_diffuse_material"](diffuse_color=(1, 2, 3, 4)), "diffuse_color"),
    (lambda: FUNCTIONS["checkerboard_pattern"](interval=0.0), "interval must be"),
])
def test_bad_arguments_raise_clear_errors(call, match):
    with pytest.raises(ValueError, match=match):
        call()


def test_bad_caption_values_are_located():
    with pytest.raises(MaterialExprError, match="mode"):
        parse_material('space_as_color(mode: "texture", scale: 4)')
    with pytest.raises(MaterialExprError, match="interval must be"):
        parse_material("horizontal_stripes_component(interval: 0)")


def test_the_handbooks_quoted_enum_is_refused_with_a_fix():
    with pytest.raises(MaterialExprError) as e:
        parse_material('space_as_color(mode: "object", scale: 4)')
    assert (e.value.line, e.value.col) == (1, 22)
    assert "not a string: one of uvw, object, world" in str(e.value)


# --- chapter 10 ---------------------------------------------------------------------------


def test_noise_materials_at_lattice_points():
    # object position (u, v, 0) times 10 at uv = (0.5, 0.3) is the lattice point (5, 3, 0):
    # perlin_noise is 0 there, so the tint is lerp(color_1, color_2, 0.5)
    s = square([[0.5, 0.3], [-0.2, 1.0]])
    m = MATERIALS["perlin_noise_material"](color_1=(0.2, 0.0, 1.0), color_2=(0.4, 1.0, 0.0),
                                           scale=10.0)
    assert np.allclose(tint_of(m, s), [[0.3, 0.5, 0.5]] * 2)
    # every octave (point * 2^i) stays on the lattice: the sum is 0
    assert np.allclose(tint_of(MATERIALS["summed_noise_material"](scale=10.0), s), 0.5)
    turbulence = MATERIALS["summed_noise_material"](scale=10.0, turbulence=True)
    assert np.allclose(tint_of(turbulence, s), 0.0)  # |0| is color_1


def test_noise_materials_stay_between_their_colors():
    s = square(np.random.default_rng(8).uniform(-5, 5, (500, 2)))
    for name, kw in (("perlin_noise_material", {"scale": 10}), ("summed_noise_material",
                                                                {"scale": 3}),
                     ("summed_noise_material", {"scale": 3, "turbulence": True})):
        t = tint_of(MATERIALS[name](**kw), s)
        assert np.all(np.isfinite(t)) and t.std() > 0.05, name
        assert np.all(np.abs(t[:, 0] - t[:, 1]) < 1e-12)  # grey between black and white


# --- captions and gallery -----------------------------------------------------------------


@pytest.mark.parametrize("text", CAPTIONS)
def test_figure_captions_parse_and_shade(text):
    m = parse_material(text)
    sh = m.shade(square([[0.25, 0.75], [-1.0, 2.5]]))
    assert np.all(np.isfinite(sh.bsdf.eval(np.tile(WO, (2, 1)), np.tile(WI, (2, 1)))))


def test_caption_values_reach_the_materials():
    s = square(np.random.default_rng(4).uniform(-2, 2, (50, 2)))
    pairs = [
        ("tex2d_diffuse_scaled(u_scale: 10, v_scale: 5)",
         MATERIALS["tex2d_diffuse_scaled"](10.0, 5.0)),
        ('space_as_color(mode: object, scale: 4)', MATERIALS["space_as_color"]("object", 4.0)),
        ("checkerboard(color_1: color(.3, .4, .5), color_2: color(.8, .7, .1))",
         MATERIALS["checkerboard"]((0.3, 0.4, 0.5), (0.8, 0.7, 0.1))),
        ("summed_noise_material(scale: 3, turbulence: true)",
         MATERIALS["summed_noise_material"](scale=3.0, turbulence=True)),
    ]
    for text, m in pairs:
        assert np.array_equal(tint_of(parse_material(text), s), tint_of(m, s)), text


def gallery_scenes() -> dict[str, dict]:
    return {p.stem: tomllib.loads(p.read_text(encoding="utf-8"))
            for p in sorted((ROOT / "gallery" / "scenes").glob("fig_*.toml"))}


def test_every_chapter_of_parts_2_to_4_has_three_gallery_figures():
    counts = Counter(int(name.split("_")[1]) for name in gallery_scenes())
    assert all(counts[chapter] >= 3 for chapter in range(3, 11)), counts


def test_chapter_9_and_10_scenes_use_the_captions():
    normalized = {" ".join(c.split()) for c in CAPTIONS}
    for name, scene in gallery_scenes().items():
        if name.startswith(("fig_09_", "fig_10_")):
            calls = {" ".join(o["material"].split()) for o in scene["objects"]}
            assert calls - {"diffuse(tint: color(0.45))"} <= normalized, name
            w, h = scene["render"]["resolution"]
            assert w >= 256 and h >= 192, name  # the gallery's reference size
