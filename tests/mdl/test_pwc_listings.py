"""The Handbook's chapter-15 listings (the pwc runtime as the book prints it) through the
MDL front end: they parse, resolve and check, constants fold to the book's values, and
each listing needs the others it names.

The fixtures are hand-cleaned copies of the MDL listings of the Handbook's pwc chapter
(margin notes removed, listings split by the page layout rejoined); a test checks that
every fixture line still occurs in the book text.
"""

from __future__ import annotations

import math
import re

import pytest
from repo import HANDBOOK as SEED_TEXT
from repo import needs_handbook

from mdl.diagnostics import MdlError
from mdl.entities import TypeEntity
from mdl.loader import Loader, ModuleText


class PwCurve:
    """The runtime module ``pwc compile`` writes, as ``::pw_curve`` (no renderer needed)."""

    def find(self, qname):
        if qname == "::pw_curve":
            from pwc.emit import runtime_mdl

            return ModuleText(qname, runtime_mdl(), "pw_curve.mdl", None, "generated")
        return None


def load(text: str, name: str = "t.mdl", providers=()):
    return Loader(providers=[PwCurve(), *providers]).load_text(text, name)


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


def _type(module, name):
    return next(e for e in module.scope[name] if isinstance(e, TypeEntity)).type


def test_listing_15_1_enum():
    module = load(PW_CURVE_MODULE)
    assert module.version == (1, 6)
    names = ["segment", "angle", "sagitta", "cyma_recta", "cyma_reversa", "flare"]
    assert _type(module, "pw_type").values == list(zip(names, range(6), strict=True))


def test_listing_15_2_struct():
    module = load(PW_CURVE_MODULE)
    fields = _type(module, "pw_point").fields
    assert [(str(f.type), f.name) for f in fields] == [
        ("t::pw_type", "type"), ("float", "t"), ("float2", "pt"), ("float2", "center"),
        ("float", "radius"), ("float", "start_angle"), ("float", "end_angle")]
    from mdl.printer import format_expression

    assert [None if f.default is None else format_expression(f.default) for f in fields] == [
        None, "0.0", "float2(0.0)", "float2(0.0)", "0.0", "0.0", "0.0"]
    assert module.exports() == {}
    text = PW_CURVE_MODULE.replace("enum pw_type", "export enum pw_type")
    exported = load(text.replace("struct pw_point", "export struct pw_point"))
    values = {"segment", "angle", "sagitta", "cyma_recta", "cyma_reversa", "flare"}
    assert set(exported.exports()) == {"pw_type", "pw_point", *values}


def test_listing_15_3_array():
    module = load(ARRAYS_MODULE)
    assert {m.qname for m in module.imports.values()} == {"::pw_curve"}
    assert module.constant("segments_length") == pytest.approx(2.00056)
    segments = module.constant("segments")
    assert len(segments) == 6
    assert segments[0] == {"type": "segment", "t": 0.0, "pt": (0.0, 0.0), "center": (0.0, 0.0),
                           "radius": 0.0, "start_angle": 0.0, "end_angle": 0.0}
    ts = [p["t"] for p in segments]
    assert ts == sorted(ts) and ts[0] == 0.0 and ts[-1] == 1.0
    assert segments[3]["pt"] == pytest.approx((0.32142857, 0.3))
    assert segments[-1]["pt"] == pytest.approx((0.42857143, 0.75))
    # every element keeps its source line as a comment
    comments = re.findall(r"pw_curve::pw_point\( // (.*)", LISTING_15_3)
    assert comments == ["0 0", ".7 0", ".7 .4", "3/7 .4", "3/7 4/3", "4/7 1"]


def test_listing_15_4_array_with_arcs():
    module = load(ARRAYS_MODULE)
    assert module.constant("right_angle_arc_length") == pytest.approx(2.23678)
    arc = module.constant("right_angle_arc")
    assert len(arc) == 11
    arcs = [p for p in arc if p["type"] == "angle"]
    assert len(arcs) == 3
    first = arcs[0]
    assert first["pt"] == pytest.approx((0.18292683, 0.32926829))  # end point of the arc
    assert first["center"] == pytest.approx((0.18292683, 0.26829268))  # centre
    assert first["radius"] == pytest.approx(0.06098)
    assert (first["start_angle"], first["end_angle"]) == pytest.approx((3.14159, 1.5708))
    assert math.dist(first["pt"], first["center"]) == pytest.approx(first["radius"], abs=1e-5)
    assert [p["t"] for p in arc] == sorted(p["t"] for p in arc)
    assert arc[-1]["type"] == "segment" and arc[-1]["t"] == 1.0 and arc[-1]["pt"] == (0.0, 1.0)


def test_function_listings():
    module = load(FUNCTIONS_MODULE)
    assert {m.qname for m in module.imports.values()} == {"::debug", "::math", "::state",
                                                           "::pw_curve"}
    assert {o.name for o in module.overloads} == {
        "point_along_pwc", "displace_to_point", "displace_with_pwc", "y_rotation_3",
        "displace_to_angular_point", "displace_to_pwc_point"}
    assert _type(module, "displacement_direction").values == [("along_u", 0), ("along_v", 1)]
    sig = {o.name: o.signature() for o in module.overloads}
    assert sig["point_along_pwc"] == ("float2 point_along_pwc(float curve_position, "
                                      "pw_curve::pw_point[<N>] pwc)")
    assert sig["displace_with_pwc"].startswith("float3 displace_with_pwc(uniform "
                                               "pw_curve::pw_point[<N>] pwc")
    assert sig["y_rotation_3"] == "float3x3 y_rotation_3(float angle)"
    assert "float radius = 0" in sig["displace_to_angular_point"]
    assert "float radius_offset = 0.0" in sig["displace_to_pwc_point"]
    # reading the state makes a function vary over the surface
    reads = {o.name: o.reads_state for o in module.overloads}
    assert not reads["point_along_pwc"] and not reads["y_rotation_3"]
    assert reads["displace_to_point"] and reads["displace_with_pwc"]


def test_material_listings():
    natives = pytest.importorskip("render.mdlc.natives", reason="the renderer provides "
                                  "::functions and ::geometry")
    WorkbenchModules = natives.WorkbenchModules  # noqa: N806

    module = load(MATERIALS_MODULE, providers=[WorkbenchModules()])
    assert {o.name for o in module.materials()} == {"travertine", "marbloid", "double_pwc"}
    marbloid = next(o for o in module.overloads if o.name == "marbloid")
    assert "functions::mapping_mode space = functions::object" in marbloid.signature()
    assert module.constant("pink_stone") == pytest.approx((0.7, 0.66, 0.63))


@pytest.mark.parametrize(
    ("listing", "message"),
    [
        (LISTING_15_7, "unknown type 'displacement_direction'"),
        (LISTING_15_12, "unknown function 'y_rotation_3'"),
        (LISTING_15_5, "unknown function 'point_along_pwc'"),
    ],
)
def test_function_listings_need_each_other(listing, message):
    with pytest.raises(MdlError, match=re.escape(message)):
        load(FUNCTIONS_MODULE.replace(listing, ""))


def test_function_listings_need_their_imports():
    with pytest.raises(MdlError, match="module 'state' is not imported"):
        load(FUNCTIONS_MODULE.replace("import ::state::*;", ""))
