"""Array constructors in material calls: the Handbook's ``df::bsdf_component[](...)``
mixes (chapter 6), plain arrays, exact error columns, and robustness."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from displacement.surfaces import UnitSquare
from mdl import ast as A
from mdl.diagnostics import Source
from mdl.parser import parse_expression
from render.expr import MaterialExprError, evaluate_expression, parse_material
from render.material import DfNode, material

# Listing 6.12, as printed (without the margin notes "Component 1..3"); the book's
# fragment never closes normalized_mix's parenthesis (the test checks the error, then
# parses LISTING_6_12 with it closed)
LISTING_6_12_PRINTED = """\
normalized_mix (
  components:
    df::bsdf_component[] (
      df::bsdf_component (
        weight: 0.3,
        component: df::diffuse_reflection_bsdf (
          tint: color(1,0,0))),
      df::bsdf_component (
        weight: 0.2,
        component: df::diffuse_reflection_bsdf (
          tint: color(0,1,0))),
      df::bsdf_component (
        weight: 0.5,
        component: df::diffuse_reflection_bsdf (
          tint: color(0,0,1))))"""
LISTING_6_12 = LISTING_6_12_PRINTED + ")"

# Listing 6.13's body with Figure 6.16's arguments substituted for its parameters
LISTING_6_13_FIGURE_6_16 = """\
material (
    surface: material_surface (
        scattering: df::clamped_mix (
            components: df::bsdf_component[] (
                df::bsdf_component(
                    weight: 1.0,
                    component: df::simple_glossy_bsdf (
                        tint: color(0.2, 0.3, 0.25),
                        roughness_u: 0.3)),
                df::bsdf_component(
                    weight: 0.0,
                    component: df::simple_glossy_bsdf (
                        tint: color(0.6, 0.4, 0.2),
                        roughness_u: 0.6))
            )
        )
    )
)"""

# Listing 7.x (phonglike_plastic) with Figure 7.4's arguments and the defaults
PHONGLIKE_PLASTIC = """\
material (
    surface: material_surface (
        scattering: df::normalized_mix (
            components: df::bsdf_component[] (
                df::bsdf_component (
                    weight: 0.8,
                    component: df::diffuse_reflection_bsdf (
                        tint: color(.15, .4, 0) )),
                df::bsdf_component (
                    weight: 0.0,
                    component: df::simple_glossy_bsdf (
                        tint: color(1),
                        roughness_u: 0.2 ))))))"""


def _components(node: DfNode) -> list[tuple[float, DfNode]]:
    return [(float(c.kwargs["weight"]), c.kwargs["component"]) for c in node.kwargs["components"]]


def test_listing_6_12_normalized_mix_of_three_diffuse_components():
    with pytest.raises(MaterialExprError) as info:
        evaluate_expression(LISTING_6_12_PRINTED)
    lines = LISTING_6_12_PRINTED.splitlines()
    assert (info.value.line, info.value.col) == (len(lines), len(lines[-1]) + 1)
    assert info.value.message == "missing ')' to close the argument list"
    tree = parse_expression(Source("6.12", LISTING_6_12))
    array = tree.args[0].value
    assert isinstance(array, A.Call) and isinstance(array.callee, A.ArrayType)
    assert array.callee.suffix.size is None
    assert array.callee.element.parts == ("df", "bsdf_component") and len(array.args) == 3
    v = evaluate_expression(LISTING_6_12)
    assert str(v.type) == "bsdf" and not v.varying
    assert isinstance(v.value, DfNode) and v.value.name == "normalized_mix"
    parts = _components(v.value)
    assert [w for w, _ in parts] == [0.3, 0.2, 0.5]
    assert [c.kwargs["tint"] for _, c in parts] == [(1.0, 0.0, 0.0), (0.0, 1.0, 0.0),
                                                    (0.0, 0.0, 1.0)]
    # shaded: the weights sum to 1, so the albedo is the weighted sum of the tints
    m = parse_material(f"material(surface: material_surface(scattering: {LISTING_6_12}))")
    assert isinstance(m, material)
    state = UnitSquare().state_at_uv(np.array([[0.5, 0.5], [0.0, 1.0]]))
    bsdf = m.shade(state).bsdf
    assert np.allclose(bsdf.albedo(np.array([[0.0, 0.0, 1.0]] * 2)), [[0.3, 0.2, 0.5]] * 2)


def test_listing_6_13_two_glossy_lobes_clamped_mix():
    m = parse_material(LISTING_6_13_FIGURE_6_16)
    mix = m.surface.scattering
    assert mix.name == "clamped_mix"
    parts = _components(mix)
    assert [w for w, _ in parts] == [1.0, 0.0]
    assert [c.kwargs["roughness_u"] for _, c in parts] == [0.3, 0.6]
    assert [c.name for _, c in parts] == ["simple_glossy_bsdf"] * 2


def test_phonglike_plastic_and_sized_arrays():
    mix = parse_material(PHONGLIKE_PLASTIC).surface.scattering
    assert [w for w, _ in _components(mix)] == [0.8, 0.0]
    # T[N](...) with the right count is the same value as T[](...)
    sized = PHONGLIKE_PLASTIC.replace("bsdf_component[]", "bsdf_component[2]")
    assert repr(parse_material(sized).surface.scattering) == repr(mix)


def test_plain_arrays_and_conversions():
    v = evaluate_expression("float[](1, 2.5, -3)")
    assert str(v.type) == "float[3]" and v.value == [1.0, 2.5, -3.0]
    assert all(isinstance(x, float) for x in v.value)
    assert evaluate_expression("int[2](1, 2)").value == [1, 2]
    assert evaluate_expression("bool[](true, false)").value == [True, False]
    assert evaluate_expression('string[]("a", "b")').value == ["a", "b"]
    assert evaluate_expression("color[1](color(0.5))").value == [(0.5, 0.5, 0.5)]
    assert str(evaluate_expression("float2[](float2(1, 2))").type) == "float2[1]"
    assert evaluate_expression("float[](1, 2.5, -3)[1]").value == 2.5
    # a function of the state stays varying: the whole array is a function of the state
    varying = evaluate_expression("float[](u(), 1)")
    assert varying.varying and callable(varying.value)
    state = UnitSquare().state_at_uv(np.array([[0.25, 0.5], [0.75, 0.0]]))
    assert varying.value(state).tolist() == [[0.25, 1.0], [0.75, 1.0]]
    # the edf overload of the mixers: an edf_component[] makes an edf
    edf = evaluate_expression(
        "df::clamped_mix(components: df::edf_component[](df::edf_component(weight: 0.5, "
        "component: df::diffuse_edf())))")
    assert str(edf.type) == "edf" and edf.value.kind == "edf"
    color_mix = evaluate_expression(
        "df::color_normalized_mix(components: df::color_bsdf_component[]("
        "df::color_bsdf_component(weight: color(0.2, 0.4, 0.6), "
        "component: df::diffuse_reflection_bsdf())))")
    assert str(color_mix.type) == "bsdf"


_MIX = "df::normalized_mix(components: "
_DIFFUSE = "df::bsdf_component(weight: 0.5, component: df::diffuse_reflection_bsdf())"

#: (text, line, col, text at the reported offset, message part, fix part)
MALFORMED_ARRAYS = [
    ("float[3](1, 2)", 1, 7, "3]", "float[3](...) has 2 elements, not 3",
     "give 3 elements, or write T[](...)"),
    ("float[1](1, 2)", 1, 7, "1]", "has 2 elements, not 1", "give 1 element,"),
    ("float[]()", 1, 1, "float", "float[]() has no elements", "float[](..., ...)"),
    ("float[0](1)", 1, 7, "0", "array size must be 1 or more, got 0",
     "write float[](...) to take the size"),
    ("float[2.0](1, 2)", 1, 7, "2.0", "an array size must be an int, got a float", None),
    ("float[-1](1)", 1, 7, "-", "array size must be 1 or more, got -1", None),
    ("float[2(1, 2)", 1, 14, "", "expected ']', found end of input", "close the index with ']'"),
    ("float[]", 1, 8, "", "expected '(' after 'float[]', found end of input",
     "float[](element, ...)"),
    ("float[] 1", 1, 9, "1", "expected '(' after 'float[]', found '1'", None),
    ("float[](1, 2", 1, 13, "", "missing ')' to close the argument list", "add ')'"),
    ("float[](1 2)", 1, 11, "2", "expected ',' or ')' in the argument list, found '2'",
     "separate arguments with ','"),
    ("float[](1,)", 1, 11, ")", "expected an argument after ','", "remove the trailing ','"),
    ("float[](a: 1)", 1, 9, "a:", "array elements are positional", "remove 'a:'"),
    ("flaot[](1)", 1, 1, "flaot", "unknown type 'flaot'", "did you mean 'float'?"),
    ("foo::float[](1)", 1, 1, "foo", "unknown module 'foo'", None),
    ("color[](0.5)", 1, 9, "0.5", "element 1 of color[](...) must be a color, got a float",
     "write color(x)"),
    ("float3[](color(1))", 1, 10, "color", "must be a float3, got a color",
     "convert with float3(...)"),
    ("int[](1, 2.5)", 1, 10, "2.5", "element 2 of int[](...) must be an int, got a float",
     "write an integer"),
    ('float[](1, "x")', 1, 12, '"x"', "element 2 of float[](...) must be a float, got a string",
     None),
    (f"{_MIX}df::bsdf_component[](df::diffuse_reflection_bsdf()))", 1, 53,
     "df::diffuse_reflection_bsdf", "element 1 of df::bsdf_component[](...) must be a "
     "df::bsdf_component, got a bsdf",
     "wrap it: df::bsdf_component(weight: ..., component: ...)"),
    (f"{_MIX}df::bsdf_component[]({_DIFFUSE}, df::edf_component(weight: 1.0, "
     "component: df::diffuse_edf())))", 1, 128, "df::edf_component",
     "element 2 of df::bsdf_component[](...) must be a df::bsdf_component, got a "
     "df::edf_component", "write df::edf_component[](...)"),
    (f"{_MIX}{_DIFFUSE})", 1, 1, "df::normalized_mix",
     "no overload of 'df::normalized_mix' takes (df::bsdf_component)",
     "wrap it in an array: df::bsdf_component[](df::bsdf_component("),
    (f"{_MIX}float[](0.5))", 1, 1, "df::normalized_mix",
     "no overload of 'df::normalized_mix' takes (float[1])", "overloads: bsdf normalized_mix("),
    (f"df::color_normalized_mix(components: df::bsdf_component[]({_DIFFUSE}))", 1, 1,
     "df::color_normalized_mix", "takes (df::bsdf_component[1])",
     "color_bsdf_component[<N>] components"),
    (f"{_MIX}df::bsdf_component[2]({_DIFFUSE}))", 1, 51, "2]",
     "df::bsdf_component[2](...) has 1 element, not 2", None),
    # the Handbook's appendix instance (16.3.2) names the component 'base'
    ("df::normalized_mix(\n    components: df::bsdf_component[](\n        bsdf_component(\n"
     "            weight: 0.5,\n            base: df::diffuse_reflection_bsdf(\n"
     "                tint: color(0.7),\n                roughness: 0.1))))",
     5, 13, "base", "bsdf_component has no parameter 'base'", "parameters: weight, component"),
    ("glossy(tint: color[](color(0.5)))", 1, 14, "color[]",
     "must be a color, got a color[1]", None),
    ("[1, 2]", 1, 1, "[", "expected an expression, found '['", None),
    ("float[](])", 1, 9, "]", "expected an expression, found ']'", None),
]


@pytest.mark.parametrize("text, line, col, at, message, fix", MALFORMED_ARRAYS,
                         ids=[m[0][:40] for m in MALFORMED_ARRAYS])
def test_malformed_arrays(text, line, col, at, message, fix):
    with pytest.raises(MaterialExprError) as info:
        evaluate_expression(text)
    e = info.value
    assert (e.line, e.col) == (line, col), str(e)
    assert text[e.offset:].startswith(at), (text[e.offset:], str(e))
    assert message in e.message, str(e)
    if fix is not None:
        assert e.fix is not None and fix in e.fix, str(e)
    assert str(e).startswith(f"{line}:{col}: ")


def test_array_is_not_a_material():
    with pytest.raises(MaterialExprError, match="the expression is a float\\[1\\], not a material"):
        parse_material("float[](1)")


# --- robustness --------------------------------------------------------------------------

_VOCABULARY = ["df::normalized_mix", "df::clamped_mix", "df::color_clamped_mix",
               "df::bsdf_component", "df::edf_component", "df::color_bsdf_component",
               "df::diffuse_reflection_bsdf", "df::diffuse_edf", "bsdf_component", "float",
               "color", "int", "float2", "components", "weight", "component", "tint", "[", "]",
               "[]", "[2]", "[0]", "[1.5]", "[-1]", "(", ")", ",", ":", "::", "0", "1", "2",
               "0.5", "color(0.5)", "u()", "true", '"s"', "glossy()", "\n", " ", "/*", "*/"]


def _only_expr_errors(text: str) -> None:
    try:
        evaluate_expression(text)
    except MaterialExprError as e:
        assert e.line >= 1 and e.col >= 1 and 0 <= e.offset <= len(text)
        lines = text.split("\n")
        assert e.line <= len(lines) and e.col <= len(lines[e.line - 1]) + 1


@settings(max_examples=400, suppress_health_check=[HealthCheck.too_slow])
@given(st.lists(st.sampled_from(_VOCABULARY), max_size=30))
def test_array_token_soup_raises_only_material_expr_error(parts):
    _only_expr_errors("".join(parts))
    _only_expr_errors(" ".join(parts))


@settings(max_examples=400, suppress_health_check=[HealthCheck.too_slow])
@given(st.sampled_from([LISTING_6_12, LISTING_6_13_FIGURE_6_16, PHONGLIKE_PLASTIC,
                        LISTING_6_12_PRINTED]),
       st.integers(0, 10_000), st.integers(0, 3), st.sampled_from(list("[](),:-.0123ae_\" ")))
def test_mutated_array_listings_raise_only_material_expr_error(text, position, operation, char):
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
