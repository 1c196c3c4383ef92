"""Tests of the pure-Python MDL syntax checker in ``tests/mdl_syntax.py``.

The fixtures are hand-cleaned copies of the MDL listings of the Handbook's pwc chapter
(margin notes removed, listings split by the page layout rejoined); a test checks that
every fixture line still occurs in the book text.
"""

from __future__ import annotations

import math
import re

import pytest
from hypothesis import assume, given, settings
from hypothesis import strategies as st
from mdl_syntax import Call, Const, EnumRef, MdlSyntaxError, Param, parse_module
from repo import HANDBOOK as SEED_TEXT
from repo import needs_handbook

LISTING_15_1 = """\
enum pw_type {
    segment,
    angle,
    sagitta,
    cyma_recta,
    cyma_reversa,
    flare
};
"""

LISTING_15_2 = """\
struct pw_point {
    pw_type type;
    float t = 0.0;
    float2 pt = float2(0.0);
    float2 center = float2(0.0);
    float radius = 0.0;
    float start_angle = 0.0;
    float end_angle = 0.0;
};
"""

LISTING_15_3 = """\
const float segments_length = 2.00056;

const pw_curve::pw_point[6] segments (
    pw_curve::pw_point( // 0 0
        pw_curve::segment, 0.0, float2(0.0, 0.0)),
    pw_curve::pw_point( // .7 0
        pw_curve::segment, 0.26243, float2(0.525, 0.0)),
    pw_curve::pw_point( // .7 .4
        pw_curve::segment, 0.41238, float2(0.525, 0.3)),
    pw_curve::pw_point( // 3/7 .4
        pw_curve::segment, 0.51414, float2(0.32142857, 0.3)),
    pw_curve::pw_point( // 3/7 4/3
        pw_curve::segment, 0.86404, float2(0.32142857, 1.0)),
    pw_curve::pw_point( // 4/7 1
        pw_curve::segment, 1.0, float2(0.42857143, 0.75)));
"""

LISTING_15_4 = """\
const float right_angle_arc_length = 2.23678;

const pw_curve::pw_point[11] right_angle_arc ( // :relative
    pw_curve::pw_point( // 0 0
        pw_curve::segment, 0.0, float2(0.0, 0.0)),
    pw_curve::pw_point( // .25 0
        pw_curve::segment, 0.05452, float2(0.12195122, 0.0)),
    pw_curve::pw_point( // 0 .55
        pw_curve::segment, 0.17447, float2(0.12195122, 0.26829268)),
    pw_curve::pw_point( // .125 .125 :angle -90
      pw_curve::angle, 0.21729, float2(0.18292683, 0.32926829),
      float2(0.18292683, 0.26829268), 0.06098, 3.14159, 1.5708),
    pw_curve::pw_point( // .375 0
      pw_curve::segment, 0.29907, float2(0.36585366, 0.32926829)),
    pw_curve::pw_point( // .125 -.125 :angle -90
      pw_curve::angle, 0.34189, float2(0.42682927, 0.26829268),
      float2(0.36585366, 0.26829268), 0.06098, 1.5708, 0.0),
    pw_curve::pw_point( // .125 0
      pw_curve::segment, 0.36915, float2(0.48780488, 0.26829268)),
    pw_curve::pw_point( // 0 1
      pw_curve::segment, 0.58723, float2(0.48780488, 0.75609756)),
    pw_curve::pw_point( // .25 .25 :angle -90
      pw_curve::angle, 0.67287, float2(0.6097561, 0.87804878),
      float2(0.6097561, 0.75609756), 0.12195, 3.14159, 1.5708),
    pw_curve::pw_point( // 0 .25
      pw_curve::segment, 0.7274, float2(0.6097561, 1.0)),
    pw_curve::pw_point( // a0 0
      pw_curve::segment, 1.0, float2(0.0, 1.0)));
"""

LISTING_15_5 = """\
float2 point_along_pwc(
  float curve_position,
  pw_curve::pw_point[<N>] pwc)
{
  float2 result = pwc[N-1].pt;
  for (int i = 1; i < N; i++) {
    pw_curve::pw_point current = pwc[i];
    if (curve_position < current.t) {
      pw_curve::pw_point last = pwc[i-1];
      debug::assert(
        (current.t - last.t) != 0, "duplicated t value");
      float piece_position =
        (curve_position - last.t) / (current.t - last.t);
      if (current.type == pw_curve::segment) {
        result = math::lerp(
          last.pt, current.pt, piece_position);
      } else {
        float angle =
          math::lerp(
            current.start_angle, current.end_angle,
            piece_position);
        result = current.center + current.radius *
          float2(math::cos(angle), math::sin(angle));
      }
      break;
    }
  }
  return result;
}
"""

LISTING_15_6 = """\
float3 displace_to_point(
    float2 pw_point, float uv_position, float3 tangent)
{
    float3 result = pw_point.x * state::normal();
    result += (pw_point.y - uv_position) * tangent;
    return result;
}
"""

LISTING_15_7 = """\
enum displacement_direction {
    along_u,
    along_v
};
"""

LISTING_15_8 = """\
float3 displace_with_pwc(
    uniform pw_curve::pw_point[<N>] pwc,
    displacement_direction displace_dir)
{
    int uv_index = displace_dir == along_u ? 0 : 1;
    float uv_pos = state::texture_coordinate(0)[uv_index];
    float3 tangent =
        displace_dir == along_u
        ? state::texture_tangent_u(0)
        : state::texture_tangent_v(0);
    float2 pw_point =
        point_along_pwc(uv_pos, pwc);
    return
        displace_to_point(pw_point, uv_pos, tangent);
}
"""

LISTING_15_10 = """\
material travertine(
    float texture_u_scale = 1.0,
    float texture_v_scale = 1.0) =
material (
    surface: material_surface (
  scattering: df::diffuse_reflection_bsdf (
    tint: tex::lookup_color(
      texture_2d("travertine.png"),
      float2(texture_u_scale,
              texture_v_scale)))));
"""

LISTING_15_12 = """\
float3x3 y_rotation_3(float angle) {
    return float3x3(
        math::cos(angle), 0.0, math::sin(angle),
        0.0, 1.0, 0.0,
        -math::sin(angle), 0.0, math::cos(angle));
}
"""

LISTING_15_13 = """\
float3 displace_to_angular_point(
    float2 pw_point, float t, float radius = 0)
{
    float angle = t * math::PI * 2;
    float3 p = float3(
        pw_point[0] + radius,
        pw_point[1],
        0.0);
    p *= y_rotation_3(angle);
    p -= state::position();
    return p;
}
"""

LISTING_15_17 = """\
material marbloid (
    float scale = 1.0,
    int level_count = 5,
    functions::mapping_mode space = functions::object) =
let {
    double3 scaled_point =
        scale * functions::position(space);
    double noise_value =
        perlin_noise::summed_perlin_noise(
            scaled_point, level_count,
            level_scale: 0.8, turbulence: true);
    double z = 2 * scaled_point.z;
    double veins = 0.03 +
        0.3 * (1 + math::sin(z + 8.0 * noise_value));
    color tint(
        float(math::pow(veins, 1/1.8)),
        float(math::pow(veins, 1/1.4)),
        float(math::pow(veins, 1/1.1) * 0.9));
} in
material (
    surface: material_surface (
        scattering: df::diffuse_reflection_bsdf(tint: tint)));
"""

LISTING_15_19 = """\
float3 displace_to_pwc_point(
    float2 pw_point, float t,
    uniform pw_curve::pw_point[<N>] pwc,
    float radius_offset = 0.0)
{
    float angle = t * math::PI * 2;
    float3 p = float3(pw_point[0] + radius_offset,
                     pw_point[1],
                     0.0);
    float2 square_pt = point_along_pwc(t, pwc);
    float scale = math::length(square_pt);
    p.x *= scale;
    p *= y_rotation_3(angle);
    p -= state::position();
    return p;
}
"""

LISTING_15_20 = """\
material double_pwc(
    uniform pw_curve::pw_point[<N>] pwc_profile,
    uniform pw_curve::pw_point[<M>] pwc_sweep,
    material surface_material,
    float radius_offset = 0.0) =
let {
    float u = state::texture_coordinate(0)[0];
    float v = state::texture_coordinate(0)[1];
    float2 profile_point = point_along_pwc(
        v, pwc_profile);
    float3 displace_point = displace_to_pwc_point(
        profile_point, u, pwc_sweep, radius_offset);
} in
geometry::vector_displacement(
    displace_point,
    surface_material);
"""

PINK_STONE = "const color pink_stone = color(.7, .66, .63);\n"

LISTINGS = {
    "15.1": LISTING_15_1,
    "15.2": LISTING_15_2,
    "15.3": LISTING_15_3,
    "15.4": LISTING_15_4,
    "15.5": LISTING_15_5,
    "15.6": LISTING_15_6,
    "15.7": LISTING_15_7,
    "15.8": LISTING_15_8,
    "15.10": LISTING_15_10,
    "15.12": LISTING_15_12,
    "15.13": LISTING_15_13,
    "15.17": LISTING_15_17,
    "15.19": LISTING_15_19,
    "15.20": LISTING_15_20,
    "15.21": PINK_STONE,
}

PW_CURVE_MODULE = "mdl 1.6;\n\n" + LISTING_15_1 + "\n" + LISTING_15_2
ARRAYS_MODULE = "mdl 1.6;\n\nimport ::pw_curve::*;\n\n" + LISTING_15_3 + "\n" + LISTING_15_4
FUNCTION_IMPORTS = """\
mdl 1.6;

import ::debug::*;
import ::math::*;
import ::state::*;
import ::pw_curve::*;
"""
FUNCTION_LISTINGS = [
    LISTING_15_5,
    LISTING_15_6,
    LISTING_15_7,
    LISTING_15_8,
    LISTING_15_12,
    LISTING_15_13,
    LISTING_15_19,
]
FUNCTIONS_MODULE = FUNCTION_IMPORTS + "\n" + "\n".join(FUNCTION_LISTINGS)
MATERIALS_MODULE = (
    FUNCTION_IMPORTS
    + "import ::df::*;\nimport ::tex::*;\nimport ::geometry::*;\n"
    + "import ::functions::*;\nimport ::perlin_noise::*;\n\n"
    + "\n".join(FUNCTION_LISTINGS + [LISTING_15_10, LISTING_15_17, LISTING_15_20, PINK_STONE])
)


def _squash(text):
    return re.sub(r"\s+", " ", text).strip()


# -- (a) the Handbook's listings ------------------------------------------------------------------


@needs_handbook
@pytest.mark.parametrize("number", list(LISTINGS))
def test_fixture_lines_occur_in_the_handbook(number):
    book = _squash(SEED_TEXT.read_text(encoding="utf-8"))
    for line in LISTINGS[number].splitlines():
        if line.strip():
            assert _squash(line) in book, f"Listing {number}: {line!r} not in the Handbook"


def _handbook_listing(number):
    """The fenced code block following the heading ``Listing <number>`` in the Handbook."""
    text = SEED_TEXT.read_text(encoding="utf-8")
    return re.search(rf"^Listing {re.escape(number)}\s*```\n(.*?)```", text, re.S | re.M).group(1)


@needs_handbook
@pytest.mark.parametrize("number", ["15.1", "15.6", "15.7", "15.12", "15.19"])
def test_listings_without_margin_notes_equal_the_handbook(number):
    assert _squash(_handbook_listing(number)) == _squash(LISTINGS[number])


def test_listing_15_1_enum():
    module = parse_module(PW_CURVE_MODULE)
    assert module.version == "1.6"
    names = ["segment", "angle", "sagitta", "cyma_recta", "cyma_reversa", "flare"]
    assert module.enums == {"pw_type": list(zip(names, range(6), strict=True))}


def test_listing_15_2_struct():
    module = parse_module(PW_CURVE_MODULE)
    assert module.structs["pw_point"] == [
        ("pw_type", "type", None),
        ("float", "t", "0.0"),
        ("float2", "pt", "float2(0.0)"),
        ("float2", "center", "float2(0.0)"),
        ("float", "radius", "0.0"),
        ("float", "start_angle", "0.0"),
        ("float", "end_angle", "0.0"),
    ]
    assert module.exports == set()
    text = PW_CURVE_MODULE.replace("enum pw_type", "export enum pw_type")
    exported = parse_module(text.replace("struct pw_point", "export struct pw_point"))
    values = {"segment", "angle", "sagitta", "cyma_recta", "cyma_reversa", "flare"}
    assert exported.exports == {"pw_type", "pw_point", *values}


def test_listing_15_3_array():
    module = parse_module(ARRAYS_MODULE)
    assert module.imports == ["::pw_curve::*"]
    assert module.constants["segments_length"] == Const("float", None, 2.00056)
    segments = module.constants["segments"]
    assert (segments.type, segments.array_size, segments.comment) == ("pw_curve::pw_point", 6, None)
    assert segments.value[0] == Call(
        "pw_curve::pw_point", [EnumRef("pw_curve::segment"), 0.0, (0.0, 0.0)]
    )
    assert [p.comment for p in segments.value] == [
        "0 0",
        ".7 0",
        ".7 .4",
        "3/7 .4",
        "3/7 4/3",
        "4/7 1",
    ]
    assert {p.args[0] for p in segments.value} == {EnumRef("pw_curve::segment")}
    ts = [p.args[1] for p in segments.value]
    assert ts == sorted(ts) and ts[0] == 0.0 and ts[-1] == 1.0
    assert segments.value[3].args[2] == (0.32142857, 0.3)
    assert segments.value[-1].args[2] == (0.42857143, 0.75)


def test_listing_15_4_array_with_arcs():
    module = parse_module(ARRAYS_MODULE)
    assert module.constants["right_angle_arc_length"].value == 2.23678
    arc = module.constants["right_angle_arc"]
    assert (arc.array_size, len(arc.value), arc.comment) == (11, 11, ":relative")
    arcs = [p for p in arc.value if p.args[0] == EnumRef("pw_curve::angle")]
    assert len(arcs) == 3
    first = arcs[0]
    assert first.comment == ".125 .125 :angle -90"
    assert first.args[2] == (0.18292683, 0.32926829)  # end point of the arc
    assert first.args[3] == (0.18292683, 0.26829268)  # centre
    assert first.args[4] == pytest.approx(0.06098)  # radius
    assert first.args[5:] == [3.14159, 1.5708]  # start and end angle
    assert math.dist(first.args[2], first.args[3]) == pytest.approx(first.args[4], abs=1e-5)
    assert [p.args[1] for p in arc.value] == sorted(p.args[1] for p in arc.value)
    assert arc.value[-1] == Call(
        "pw_curve::pw_point", [EnumRef("pw_curve::segment"), 1.0, (0.0, 1.0)]
    )


def test_function_listings():
    module = parse_module(FUNCTIONS_MODULE)
    assert module.imports == ["::debug::*", "::math::*", "::state::*", "::pw_curve::*"]
    assert set(module.functions) == {
        "point_along_pwc",
        "displace_to_point",
        "displace_with_pwc",
        "y_rotation_3",
        "displace_to_angular_point",
        "displace_to_pwc_point",
    }
    assert module.enums == {"displacement_direction": [("along_u", 0), ("along_v", 1)]}
    point = module.functions["point_along_pwc"]
    assert point.return_type == "float2" and not point.is_material
    assert point.params == [
        Param("float", "curve_position"),
        Param("pw_curve::pw_point[<N>]", "pwc"),
    ]
    displace = module.functions["displace_with_pwc"]
    assert displace.params[0] == Param("pw_curve::pw_point[<N>]", "pwc", None, "uniform")
    assert module.functions["y_rotation_3"].return_type == "float3x3"
    assert module.functions["displace_to_angular_point"].params[2] == Param("float", "radius", "0")
    assert module.functions["displace_to_pwc_point"].params[3].default == "0.0"


def test_material_listings():
    module = parse_module(MATERIALS_MODULE)
    materials = {name for name, f in module.functions.items() if f.is_material}
    assert materials == {"travertine", "marbloid", "double_pwc"}
    marbloid = module.functions["marbloid"]
    assert marbloid.params[2] == Param("functions::mapping_mode", "space", "functions::object")
    assert module.constants["pink_stone"] == Const("color", None, (0.7, 0.66, 0.63))


@pytest.mark.parametrize(
    ("listing", "message"),
    [
        (LISTING_15_7, "unknown type 'displacement_direction'"),
        (LISTING_15_12, "unknown function 'y_rotation_3'"),
        (LISTING_15_5, "unknown function 'point_along_pwc'"),
    ],
)
def test_function_listings_need_each_other(listing, message):
    with pytest.raises(MdlSyntaxError, match=re.escape(message)):
        parse_module(FUNCTIONS_MODULE.replace(listing, ""))


def test_function_listings_need_their_imports():
    with pytest.raises(MdlSyntaxError, match="module 'state' is not imported"):
        parse_module(FUNCTIONS_MODULE.replace("import ::state::*;", ""))


# -- tokens, literals and constant expressions ----------------------------------------------------


@pytest.mark.parametrize(
    ("literal", "value"),
    [
        ("1", 1),
        ("0.5", 0.5),
        (".5", 0.5),
        ("1e-3", 1e-3),
        ("1.5f", 1.5),
        ("2.0d", 2.0),
        ("1.", 1.0),
        ("2E+2", 200.0),
        ("0x1F", 31),
        ("017", 15),
        ("0", 0),
        ("true", True),
        ('"a\\"b" "c"', 'a"bc'),
        ("-2", -2),
        ("- -2.5", 2.5),
    ],
)
def test_literals(literal, value):
    constant = parse_module(f"mdl 1.7;\nconst auto x = {literal};").constants["x"]
    assert constant.value == value and type(constant.value) is type(value)


@pytest.mark.parametrize(
    ("expression", "value"),
    [
        ("1 + 2 * 3", 7),
        ("(1 + 2) * 3", 9),
        ("10 - 4 - 3", 3),
        ("8 / 4 / 2", 1),
        ("-7 / 2", -3),
        ("-7 % 3", -1),
        ("7 / 2.0", 3.5),
        ("-(1 + 2) * -2", 6),
        ("2147483647 + 1", -(2**31)),
        ("float2(1, 2)", (1.0, 2.0)),
        ("-float2(1.5)", (-1.5, -1.5)),
        ("int(2.7)", 2),
        ("float3x2(1.0)", (1.0, 0.0, 0.0, 1.0, 0.0, 0.0)),
        ("float[](1.0, 2.0)", [1.0, 2.0]),
        ("int[2](3, 4)", [3, 4]),
        ("color(0.25)", (0.25, 0.25, 0.25)),
        ("math::PI / 2", math.pi / 2),
        ("1.0 / 0.0", math.inf),
        ("1 < 2", None),
        ("true ? 1 : 2", None),
    ],
)
def test_constant_expressions(expression, value):
    text = f"mdl 1.7;\nimport ::math::*;\nconst auto x = {expression};"
    assert parse_module(text).constants["x"].value == value


def test_constant_structs_enums_and_named_arguments():
    text = """mdl 1.7;
    import ::anno::*;
    export enum kind [[ anno::description("kinds") ]] { a, b = 4, c [[ anno::hidden() ]] };
    struct s { kind k = a; float2 p; };
    export const s one = s(k: c, p: float2(1.0, 2.0)), two(b);
    const float scale = 2.0;
    const float[2] scaled(scale * 1.5, -scale);
    """
    module = parse_module(text)
    assert module.enums["kind"] == [("a", 0), ("b", 4), ("c", 5)]
    assert module.constants["one"].value == Call("s", [], {"k": EnumRef("c"), "p": (1.0, 2.0)})
    assert module.constants["two"].value == Call("s", [EnumRef("b")])
    assert module.constants["scaled"] == Const("float", 2, [3.0, -2.0])
    assert module.exports == {"kind", "a", "b", "c", "one", "two"}


def test_statements_and_expressions():
    text = """mdl 1.6;
    import ::math::*;
    using ::math import sin, cos;
    /* a /* nested */ block comment */
    export int count(uniform int n [[ anno_free() ]], float[<K>] xs, int[K] ys) varying
    {
        int total = 0, i;
        do { total += 1; } while (total < 3);
        while (true) { if (total > n) break; else { total++; continue; } }
        for (;;) { break; }
        for (i = 0, total = 0; i < K; ++i) total += int(xs[i]) + ys[i];
        switch (total % 3) {
            case 0: total = -total; break;
            case 1: { const int k = 2; total <<= k; }
            default: total = total > 1 && !(total == 2) || total != 4 ? total ^ 1 : total | 2 & ~0;
        }
        let float s = sin(1.0) + cos(0.5); in s;
        ;
        return total >> 1;
    }
    annotation anno_free();
    float identity(float x) = x;
    float identity(int x) = float(x);
    float3 forward(float3 v);
    """
    module = parse_module(text)
    assert module.functions["count"].qualifier == "varying"
    assert module.functions["count"].params[1].type == "float[<K>]"
    assert module.functions["count"].params[0].qualifier == "uniform"
    assert module.imports == ["::math::*", "::math::sin", "::math::cos"]
    assert [
        f.params[0].type
        for f in [module.functions["identity"], *module.functions["identity"].overloads]
    ] == ["float", "int"]
    assert not module.functions["forward"].has_body


def test_empty_text_and_comments_only():
    assert parse_module("").version is None
    assert parse_module("// nothing\n/* here */\n").functions == {}


def test_error_message_format():
    with pytest.raises(MdlSyntaxError) as info:
        parse_module("mdl 1.6;\nconst float x = ;", filename="bad.mdl")
    error = info.value
    assert (error.line, error.col, error.filename) == (2, 17, "bad.mdl")
    assert str(error) == "bad.mdl:2:17: expected an expression, found ';'"


# -- (b) invalid code -----------------------------------------------------------------------------

INVALID = [
    # (name, text, line, message fragment)
    (
        "missing semicolon",
        "mdl 1.6;\nfloat f() {\n  float x = 1.0\n  return x;\n}\n",
        3,
        "expected ';'",
    ),
    (
        "missing semicolon after const",
        "mdl 1.6;\nconst float a = 1.0\nconst float b = 2.0;\n",
        2,
        "expected ';'",
    ),
    (
        "unbalanced parens",
        "mdl 1.6;\nfloat f(float x) {\n  return (x + 1.0;\n}\n",
        3,
        "expected ')'",
    ),
    ("extra paren", "mdl 1.6;\nfloat f(float x) {\n  return x + 1.0);\n}\n", 3, "expected ';'"),
    (
        "unknown identifier",
        "mdl 1.6;\nfloat f(float x) {\n  float y = x;\n  return y + z;\n}\n",
        4,
        "undeclared identifier 'z'",
    ),
    (
        "unknown function",
        "mdl 1.6;\nfloat f(float x) {\n  return lerp(x, 1.0, 0.5);\n}\n",
        3,
        "unknown function 'lerp'",
    ),
    (
        "local out of scope",
        "mdl 1.6;\nfloat f() {\n  { float y = 1.0; }\n  return y;\n}\n",
        4,
        "undeclared identifier 'y'",
    ),
    (
        "unknown type",
        "mdl 1.6;\nfloat f(pw_point p) { return 1.0; }\n",
        2,
        "unknown type 'pw_point'",
    ),
    ("unterminated float2(", "mdl 1.6;\n\nconst float2 p = float2(\n", 3, "found end of input"),
    (
        "unterminated call in body",
        "mdl 1.6;\nfloat2 f() {\n  return float2(0.0, 1.0;\n}\n",
        3,
        "expected ')'",
    ),
    ("bad number", "mdl 1.6;\nconst float x =\n  1.2.3;\n", 3, "malformed number '1.2.3'"),
    ("bad number suffix", "mdl 1.6;\nconst float x = 12abc;\n", 2, "malformed number"),
    ("bad octal", "mdl 1.6;\nconst int x = 09;\n", 2, "invalid octal literal"),
    (
        "missing header",
        "// pw curves\nconst float x = 1.0;\n",
        2,
        "missing 'mdl 1.x;' version header",
    ),
    ("bad version", "mdl 2.0;\n", 1, "unsupported MDL version"),
    (
        "duplicate const",
        "mdl 1.6;\nconst float x = 1.0;\nconst int x = 2;\n",
        3,
        "duplicate declaration of 'x'",
    ),
    (
        "duplicate enum value",
        "mdl 1.6;\nenum a { u, v };\nenum b { w,\n v };\n",
        4,
        "duplicate declaration of 'v'",
    ),
    (
        "duplicate function",
        "mdl 1.6;\nfloat f() { return 1.0; }\nfloat f() { return 2.0; }\n",
        3,
        "duplicate definition of function 'f'",
    ),
    (
        "struct and function",
        "mdl 1.6;\nstruct s { float a; };\nfloat s() { return 1.0; }\n",
        3,
        "duplicate declaration of 's'",
    ),
    (
        "duplicate local",
        "mdl 1.6;\nfloat f() {\n  float a = 1.0;\n  float a = 2.0;\n  return a;\n}\n",
        4,
        "redeclaration of 'a'",
    ),
    (
        "duplicate field",
        "mdl 1.6;\nstruct s {\n  float a;\n  int a;\n};\n",
        4,
        "duplicate field 'a'",
    ),
    (
        "break outside loop",
        "mdl 1.6;\nfloat f() {\n  if (true)\n    break;\n  return 1.0;\n}\n",
        4,
        "'break' outside of a loop",
    ),
    (
        "continue in switch",
        "mdl 1.6;\nint f(int x) {\n  switch (x) { case 0: continue; }\n  return x;\n}\n",
        3,
        "'continue' outside of a loop",
    ),
    ("stray brace", "mdl 1.6;\nfloat f() {\n  return 1.0;\n}\n}\n", 5, "unmatched '}'"),
    ("missing brace", "mdl 1.6;\nfloat f() {\n  return 1.0;\n", 3, "missing '}'"),
    ("no return", "mdl 1.6;\nfloat f(float x) {\n  x += 1.0;\n}\n", 2, "has no return statement"),
    ("return without value", "mdl 1.6;\nfloat f() {\n  return;\n}\n", 3, "expected an expression"),
    ("global variable", "mdl 1.6;\nfloat x = 1.0;\n", 2, "global variable 'x'"),
    (
        "not imported",
        "mdl 1.6;\nfloat f(float x) {\n  return math::sin(x);\n}\n",
        3,
        "module 'math' is not imported",
    ),
    (
        "unknown stdlib function",
        "mdl 1.6;\nimport ::math::*;\nfloat f(float x) {\n  return math::sine(x);\n}\n",
        4,
        "'sine' is not exported by standard module 'math'",
    ),
    (
        "specific import only",
        "mdl 1.7;\nimport ::pw_curve::pw_point;\nconst auto x = pw_curve::segment;\n",
        3,
        "module 'pw_curve' is not imported",
    ),
    (
        "array size mismatch",
        "mdl 1.6;\nconst float[3] xs(\n  1.0,\n  2.0);\n",
        2,
        "declared with 3 elements but initialized with 2",
    ),
    (
        "vector arity",
        "mdl 1.6;\nconst float2 p = float2(1.0, 2.0, 3.0);\n",
        2,
        "float2 constructor needs 2 values but got 3",
    ),
    ("integer division by zero", "mdl 1.6;\nconst int x = 1 / 0;\n", 2, "integer division by zero"),
    (
        "positional after named",
        "mdl 1.6;\nfloat f(float a, float b) = a;\nconst auto x = f(a: 1.0, 2.0);\n",
        3,
        "positional argument after a named argument",
    ),
    (
        "assign to literal",
        "mdl 1.6;\nfloat f(float x) {\n  1.0 = x;\n  return x;\n}\n",
        3,
        "not assignable",
    ),
    (
        "keyword as name",
        "mdl 1.6;\nfloat f(float in) { return in; }\n",
        2,
        "expected name, found 'in'",
    ),
    (
        "type as name",
        "mdl 1.6;\nfloat f() {\n  float float2 = 1.0;\n  return float2;\n}\n",
        3,
        "type name 'float2' cannot be used",
    ),
    ("unterminated string", 'mdl 1.6;\nconst string s = "abc;\n', 2, "unterminated string"),
    (
        "unterminated comment",
        "mdl 1.6;\n/* /* nested */\nconst float x = 1.0;\n",
        2,
        "unterminated block comment",
    ),
    ("bad character", "mdl 1.6;\nconst float x = 1.0 @ 2.0;\n", 2, "unexpected character '@'"),
    ("leading underscore", "mdl 1.6;\nconst float _x = 1.0;\n", 2, "unexpected character '_'"),
    (
        "size name outside parameters",
        "mdl 1.6;\nconst float[<N>] x = float[](1.0);\n",
        2,
        "only allowed for parameters",
    ),
    (
        "import after declaration",
        "mdl 1.6;\nconst float x = 1.0;\nimport ::math::*;\n",
        3,
        "must precede",
    ),
    ("trailing comma before 1.8", "mdl 1.7;\nenum e { a, b, };\n", 2, "expected name, found '}'"),
    (
        "missing else branch",
        "mdl 1.6;\nfloat f(float x) {\n  if (x > 0.0) return 1.0; else\n}\n",
        4,
        "expected an expression, found '}'",
    ),
]


@pytest.mark.parametrize(
    ("text", "line", "message"), [case[1:] for case in INVALID], ids=[case[0] for case in INVALID]
)
def test_invalid_code(text, line, message):
    with pytest.raises(MdlSyntaxError) as info:
        parse_module(text)
    assert message in info.value.message
    assert info.value.line == line, str(info.value)


def test_trailing_comma_allowed_in_1_8():
    assert parse_module("mdl 1.8;\nenum e { a, b, };\n").enums == {"e": [("a", 0), ("b", 1)]}


# -- (c) property-based tests ---------------------------------------------------------------------

_float_literals = st.floats(min_value=0.0, max_value=1e6, allow_nan=False).map(repr)
_int_literals = st.integers(min_value=0, max_value=100).map(str)


def _expressions(literals, operators, max_leaves=12):
    """Random fully parenthesized expression strings valid in both MDL and Python."""

    def extend(children):
        binary = st.tuples(children, st.sampled_from(operators), children).map(
            lambda t: f"({t[0]} {t[1]} {t[2]})"
        )
        return binary | children.map(lambda e: f"-({e})") | children.map(lambda e: f"({e})")

    return st.recursive(literals, extend, max_leaves=max_leaves)


@given(_expressions(_float_literals, ["+", "-", "*", "/"]))
@settings(max_examples=300, deadline=None)
def test_float_expressions_evaluate_like_python(expression):
    try:
        expected = eval(expression)  # noqa: S307 - generated arithmetic only
    except ZeroDivisionError:
        assume(False)
    value = parse_module(f"mdl 1.6;\nconst float x = {expression};").constants["x"].value
    assert value == expected or (math.isnan(value) and math.isnan(expected))


@given(_expressions(_int_literals, ["+", "-", "*"], max_leaves=4))
@settings(max_examples=200, deadline=None)
def test_int_expressions_evaluate_like_python(expression):
    value = parse_module(f"mdl 1.6;\nconst int x = {expression};").constants["x"].value
    assert value == eval(expression)  # noqa: S307 - generated arithmetic only


_TOKEN_SOUP = (
    "mdl 1.6 ; import :: * float float2 int x y N pw_curve ( ) [ ] { } < > [[ ]] = == + - * / "
    '% ! ? : , . 1 0.5 .5 1e-3 "s" // /* */ \n const struct enum export material let in if '
    "else for while do break continue return switch case default uniform".split(" ")
)


@given(st.text(max_size=200) | st.binary(max_size=200).map(lambda b: b.decode("latin-1")))
@settings(max_examples=300, deadline=None)
def test_garbage_parses_or_raises_syntax_error(text):
    try:
        parse_module(text)
    except MdlSyntaxError:
        pass


@given(st.lists(st.sampled_from(_TOKEN_SOUP), max_size=60).map(" ".join))
@settings(max_examples=500, deadline=None)
def test_token_soup_parses_or_raises_syntax_error(text):
    try:
        parse_module("mdl 1.6;\n" + text)
    except MdlSyntaxError as error:
        assert error.line >= 1 and error.col >= 1


@given(st.integers(min_value=1, max_value=3000))
@settings(max_examples=20, deadline=None)
def test_deep_nesting_raises_syntax_error_not_recursion_error(depth):
    text = "mdl 1.6;\nconst float x = " + "(" * depth + "1.0" + ")" * depth + ";"
    try:
        assert parse_module(text).constants["x"].value == 1.0
    except MdlSyntaxError as error:
        assert "nesting too deep" in error.message
