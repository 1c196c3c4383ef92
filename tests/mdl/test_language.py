"""The MDL language front end: literals, constant folding, statements, every error a
located diagnostic, and property-based tests (printed trees parse back to equal trees;
random text and token soup raise only MdlError; deep nesting is refused, not a crash)."""

from __future__ import annotations

import math

import pytest
from hypothesis import HealthCheck, assume, given, settings
from hypothesis import strategies as st

from mdl import ast as A
from mdl.diagnostics import MdlError, Source
from mdl.entities import ConstEntity, Overload, TypeEntity
from mdl.lexer import tokenize
from mdl.loader import Loader
from mdl.parser import MAX_DEPTH, parse_expression, parse_module
from mdl.printer import format_expression, format_module


def load(text: str, name: str = "t.mdl"):
    return Loader().load_text(text, name)


def const(text: str, name: str = "x"):
    return load(text).constant(name)


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
    got = const(f"mdl 1.7;\nconst auto x = {literal};")
    assert got == value and type(got) is type(value)


def test_literal_types():
    m = load("mdl 1.7; const auto a = 1.5; const auto b = 1.5d; const auto c = 1; "
             "const auto d = 0x7fffffff;")
    types = {n: str(m.scope[n][0].type) for n in "abcd"}
    assert types == {"a": "float", "b": "double", "c": "int", "d": "int"}


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
        ("-2147483648 - 1", 2**31 - 1),
        ("1 << 31", -(2**31)),
        ("-16 >> 2", -4),
        ("-16 >>> 28", 15),
        ("~5 & 0xff", 250),
        ("float2(1, 2)", (1.0, 2.0)),
        ("-float2(1.5)", (-1.5, -1.5)),
        ("float3(1, 2, 3).zx", (3.0, 1.0)),
        ("float4(1, 2, 3, 4)[2]", 3.0),
        ("int(2.7)", 2),
        ("int(-2.7)", -2),
        ("float3x2(1.0)", ((1.0, 0.0), (0.0, 1.0), (0.0, 0.0))),
        ("float2x2(1, 2, 3, 4)[1]", (3.0, 4.0)),
        ("float2x2(1, 2, 3, 4) * float2(1, 1)", (4.0, 6.0)),
        ("float2(1, 1) * float2x2(1, 2, 3, 4)", (3.0, 7.0)),
        ("float[](1.0, 2.0)", [1.0, 2.0]),
        ("int[2](3, 4)", [3, 4]),
        ("color(0.25)", (0.25, 0.25, 0.25)),
        ("color(0.5) * 2.0 + color(0.1, 0.2, 0.3)", (1.1, 1.2, 1.3)),
        ("math::PI / 2", math.pi / 2),
        ("math::sin(math::HALF_PI)", 1.0),
        ("math::lerp(float2(0), float2(2, 4), 0.25)", (0.5, 1.0)),
        ("math::length(float3(3e200, 4e200, 0))", 5e200),
        ("1.0 / 0.0", math.inf),
        ("1 < 2", True),
        ("float2(1, 2) == float2(1, 2)", True),
        ("float2(1, 2) != float2(1, 3)", True),
        ("true ? 1 : 2", 1),
        ("false || 1 > 2", False),
    ],
)
def test_constant_expressions(expression, value):
    got = const(f"mdl 1.7;\nimport ::math::*;\nconst auto x = {expression};")
    if isinstance(value, float) and math.isfinite(value):
        assert got == pytest.approx(value)
    elif isinstance(value, tuple) and isinstance(value[0], tuple):
        assert got == value
    else:
        assert got == pytest.approx(value) if isinstance(value, tuple) else got == value


def test_constant_structs_enums_and_named_arguments():
    text = """mdl 1.7;
    import ::anno::*;
    export enum kind [[ anno::description("kinds") ]] { a, b = 4, c [[ anno::hidden() ]] };
    struct s { kind k = a; float2 p; };
    export const s one = s(k: c, p: float2(1.0, 2.0)), two(b);
    const float scale = 2.0;
    const float[2] scaled(scale * 1.5, -scale);
    """
    module = load(text)
    kind = next(e for e in module.scope["kind"] if isinstance(e, TypeEntity)).type
    assert kind.values == [("a", 0), ("b", 4), ("c", 5)]
    assert [str(a) for a in kind.annotations] == ['anno::description("kinds")']
    assert [str(a) for a in kind.value_annotations["c"]] == ["anno::hidden()"]
    assert module.constant("one") == {"k": "c", "p": (1.0, 2.0)}
    assert module.constant("two") == {"k": "b", "p": (0.0, 0.0)}
    assert module.constant("scaled") == [3.0, -2.0]
    assert set(module.exports()) == {"kind", "a", "b", "c", "one", "two"}


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
        float s = let float q = sin(1.0) + cos(0.5); in q;
        ;
        return total >> 1;
    }
    annotation anno_free();
    float identity(float x) = x;
    float identity(int x) = float(x);
    """
    module = load(text)
    count = module.functions("count")[0]
    assert count.qualifier == "varying"
    assert count.signature() == "int count(uniform int n, float[<K>] xs, int[K] ys) varying"
    assert [str(a) for a in count.params[0].annotations] == ["t::anno_free()"]
    assert module.using.keys() >= {"sin", "cos"}
    assert [str(o.params[0].type) for o in module.functions("identity")] == ["float", "int"]


def test_empty_text_and_comments_only():
    assert load("").version is None
    assert load("// nothing\n/* here */\n").overloads == []


def test_error_message_format():
    with pytest.raises(MdlError) as info:
        load("mdl 1.6;\nconst float x = ;", "bad.mdl")
    d = info.value.first
    assert (d.loc.line, d.loc.col, d.loc.file) == (2, 17, "bad.mdl")
    assert str(info.value).splitlines() == [
        "bad.mdl:2:17: error: expected an expression, found ';'",
        "    2 | const float x = ;",
        "      |                 ^",
        "  fix: a value is a number, a string, a name, a call such as color(0.5), or (...)"]


def test_every_error_of_a_file_is_reported():
    text = ("mdl 1.6;\nimport ::math::*;\nfloat f() { return math::sine(1.0); }\n"
            "float g() { return h(); }\nconst int k = 1.5;\nfloat h2(float x) { return y; }\n")
    with pytest.raises(MdlError) as info:
        load(text, "many.mdl")
    lines = [d.loc.line for d in info.value.diagnostics if d.severity == "error"]
    assert lines == [3, 4, 5, 6]
    # syntax errors: every broken declaration is reported, then checking stops
    text = "mdl 1.6;\nfloat f( { return 1.0; }\nconst int = 2;\nfloat g() { return 1.0 }\n"
    with pytest.raises(MdlError) as info:
        load(text, "syntax.mdl")
    assert [d.loc.line for d in info.value.diagnostics] == [2, 3, 4]


# -- invalid code ---------------------------------------------------------------------------------

INVALID = [
    # (name, text, line, message fragment, fix fragment)
    ("missing semicolon", "mdl 1.6;\nfloat f() {\n  float x = 1.0\n  return x;\n}\n", 3,
     "expected ';'", "end the declaration with ';'"),
    ("missing semicolon after const", "mdl 1.6;\nconst float a = 1.0\nconst float b = 2.0;\n",
     2, "expected ';'", "';'"),
    ("unbalanced parens", "mdl 1.6;\nfloat f(float x) {\n  return (x + 1.0;\n}\n", 3,
     "expected ')'", "close the parenthesis"),
    ("extra paren", "mdl 1.6;\nfloat f(float x) {\n  return x + 1.0);\n}\n", 3, "expected ';'",
     None),
    ("unknown identifier", "mdl 1.6;\nfloat f(float x) {\n  float y = x;\n  return y + z;\n}\n",
     4, "undeclared identifier 'z'", None),
    ("unknown identifier suggests", "mdl 1.6;\nfloat f(float width) {\n  return widht;\n}\n",
     3, "undeclared identifier 'widht'", "did you mean 'width'?"),
    ("unknown function", "mdl 1.6;\nfloat f(float x) {\n  return lerp(x, 1.0, 0.5);\n}\n", 3,
     "unknown function 'lerp'", None),
    ("local out of scope", "mdl 1.6;\nfloat f() {\n  { float y = 1.0; }\n  return y;\n}\n", 4,
     "undeclared identifier 'y'", None),
    ("unknown type", "mdl 1.6;\nfloat f(pw_point p) { return 1.0; }\n", 2,
     "unknown type 'pw_point'", None),
    ("unterminated float2(", "mdl 1.6;\n\nconst float2 p = float2(\n", 3, "found end of input",
     None),
    ("unterminated call in body", "mdl 1.6;\nfloat2 f() {\n  return float2(0.0, 1.0;\n}\n", 3,
     "expected ',' or ')'", None),
    ("bad number", "mdl 1.6;\nconst float x =\n  1.2.3;\n", 3, "malformed number '1.2.3'", None),
    ("bad number suffix", "mdl 1.6;\nconst float x = 12abc;\n", 2, "malformed number", None),
    ("bad octal", "mdl 1.6;\nconst int x = 09;\n", 2, "invalid octal literal", None),
    ("missing header", "// pw curves\nconst float x = 1.0;\n", 2,
     "missing 'mdl 1.x;' version header", "mdl 1.6;"),
    ("bad version", "mdl 2.0;\n", 1, "unsupported MDL version", "1.0 to 1.10"),
    ("duplicate const", "mdl 1.6;\nconst float x = 1.0;\nconst int x = 2;\n", 3,
     "duplicate declaration of 'x'", None),
    ("duplicate enum value", "mdl 1.6;\nenum a { u, v };\nenum b { w,\n v };\n", 4,
     "duplicate declaration of 'v'", None),
    ("duplicate function", "mdl 1.6;\nfloat f() { return 1.0; }\nfloat f() { return 2.0; }\n",
     3, "duplicate definition of function 'f'", None),
    ("struct and function", "mdl 1.6;\nstruct s { float a; };\nfloat s() { return 1.0; }\n",
     3, "duplicate declaration of 's'", None),
    ("duplicate local",
     "mdl 1.6;\nfloat f() {\n  float a = 1.0;\n  float a = 2.0;\n  return a;\n}\n", 4,
     "redeclaration of 'a'", None),
    ("duplicate field", "mdl 1.6;\nstruct s {\n  float a;\n  int a;\n};\n", 4,
     "duplicate field 'a'", None),
    ("break outside loop", "mdl 1.6;\nfloat f() {\n  if (true)\n    break;\n  return 1.0;\n}\n",
     4, "'break' outside of a loop", None),
    ("continue in switch",
     "mdl 1.6;\nint f(int x) {\n  switch (x) { case 0: continue; }\n  return x;\n}\n", 3,
     "'continue' outside of a loop", None),
    ("stray brace", "mdl 1.6;\nfloat f() {\n  return 1.0;\n}\n}\n", 5, "unmatched '}'", None),
    ("missing brace", "mdl 1.6;\nfloat f() {\n  return 1.0;\n", 3, "missing '}'", None),
    ("no return", "mdl 1.6;\nfloat f(float x) {\n  x += 1.0;\n}\n", 2,
     "has no return statement", None),
    ("return without value", "mdl 1.6;\nfloat f() {\n  return;\n}\n", 3,
     "expected an expression", None),
    ("global variable", "mdl 1.6;\nfloat x = 1.0;\n", 2, "global variable 'x'", "const"),
    ("not imported", "mdl 1.6;\nfloat f(float x) {\n  return math::sin(x);\n}\n", 3,
     "module 'math' is not imported", "import ::math::*;"),
    ("unknown stdlib function",
     "mdl 1.6;\nimport ::math::*;\nfloat f(float x) {\n  return math::sine(x);\n}\n", 4,
     "'sine' is not exported by standard module 'math'", "did you mean 'sin'?"),
    ("specific import only",
     "mdl 1.7;\nimport ::math::sin;\nconst auto x = math::PI;\n", 3,
     "'PI' is not imported from module '::math'", None),
    ("array size mismatch", "mdl 1.6;\nconst float[3] xs(\n  1.0,\n  2.0);\n", 2,
     "declared with 3 elements but initialized with 2", None),
    ("vector arity", "mdl 1.6;\nconst float2 p = float2(1.0, 2.0, 3.0);\n", 2,
     "float2 constructor needs 2 values but got 3", None),
    ("integer division by zero", "mdl 1.6;\nconst int x = 1 / 0;\n", 2,
     "integer division by zero", None),
    ("positional after named",
     "mdl 1.6;\nfloat f(float a, float b) = a;\nconst auto x = f(a: 1.0, 2.0);\n", 3,
     "positional argument after a named argument", None),
    ("assign to literal", "mdl 1.6;\nfloat f(float x) {\n  1.0 = x;\n  return x;\n}\n", 3,
     "not assignable", None),
    ("keyword as name", "mdl 1.6;\nfloat f(float in) { return in; }\n", 2,
     "expected a parameter name, found 'in'", "keyword"),
    ("type as name", "mdl 1.6;\nfloat f() {\n  float float2 = 1.0;\n  return float2;\n}\n", 3,
     "type name 'float2' cannot be used", None),
    ("unterminated string", 'mdl 1.6;\nconst string s = "abc;\n', 2, "unterminated string",
     None),
    ("unterminated comment", "mdl 1.6;\n/* /* nested */\nconst float x = 1.0;\n", 2,
     "unterminated block comment", None),
    ("bad character", "mdl 1.6;\nconst float x = 1.0 @ 2.0;\n", 2, "unexpected character '@'",
     None),
    ("leading underscore", "mdl 1.6;\nconst float _x = 1.0;\n", 2, "unexpected character '_'",
     None),
    ("size name outside parameters", "mdl 1.6;\nconst float[<N>] x = float[](1.0);\n", 2,
     "only allowed for parameters", None),
    ("import after declaration", "mdl 1.6;\nconst float x = 1.0;\nimport ::math::*;\n", 3,
     "must precede", None),
    ("trailing comma before 1.8", "mdl 1.7;\nenum e { a, b, };\n", 2,
     "a trailing ',' is allowed from MDL 1.8 on", "remove the ','"),
    ("missing else branch",
     "mdl 1.6;\nfloat f(float x) {\n  if (x > 0.0) return 1.0; else\n}\n", 4,
     "expected an expression, found '}'", None),
    ("wrong argument type",
     "mdl 1.6;\nimport ::math::*;\nfloat f() { return math::length(color(1.0)); }\n", 3,
     "no overload of 'math::length' takes (color)", "overloads:"),
    ("ambiguous overload",
     "mdl 1.6;\nfloat f(float a, double b) = a;\nfloat f(double a, float b) = b;\n"
     "const float x = f(1, 1);\n", 4, "ambiguous", "candidates"),
    ("uniform parameter gets a varying value",
     "mdl 1.6;\nimport ::state::*;\nfloat f(uniform float a) = a;\n"
     "float g() { return f(state::position().x); }\n", 4,
     "argument 'a' of f is uniform, but this value varies", None),
    ("uniform local assigned a varying value",
     "mdl 1.6;\nimport ::state::*;\nfloat g() {\n  uniform float a = 1.0;\n"
     "  a = state::normal().x;\n  return a;\n}\n", 5, "uniform 'a'", "remove 'uniform'"),
    ("material in a function",
     "mdl 1.6;\nmaterial m() = material();\nfloat g() { m(); return 1.0; }\n", 3,
     "material 'm' can only be used in a material", None),
    ("swizzle out of range",
     "mdl 1.6;\nfloat g(float2 v) { return v.z; }\n", 2, "float2 has no component 'z'",
     "components: x, y"),
    ("no such field",
     "mdl 1.6;\nstruct s { float width; };\nfloat g(s v) { return v.widht; }\n", 3,
     "struct t::s has no field 'widht'", "did you mean 'width'?"),
    ("index out of range", "mdl 1.6;\nconst float x = float[](1.0, 2.0)[2];\n", 2,
     "index 2 is out of range", None),
    ("condition not bool",
     "mdl 1.6;\nfloat g(float x) { if (x) return 1.0; return 0.0; }\n", 2,
     "a condition must be a bool, got a float", "compare it"),
    ("matrix dimensions",
     "mdl 1.6;\nfloat3 g(float2x3 m, float3 v) { return m * v; }\n", 2,
     "cannot multiply float2x3 by float3: it needs a vector of 2 components", None),
    ("import cycle",
     "mdl 1.6;\nimport ::t::*;\n", 2, "modules import each other in a cycle: ::t -> ::t",
     "third module"),
    ("missing module", "mdl 1.6;\nimport ::nowhere::*;\n", 2, "module '::nowhere' not found",
     "put nowhere.mdl beside the importing module"),
    ("prototype without body", "mdl 1.6;\nfloat f(float x);\n", 2,
     "declared but never defined", None),
    ("recursive struct", "mdl 1.6;\nstruct s { s inner; };\n", 2, "struct 's' contains itself",
     None),
]


@pytest.mark.parametrize(("text", "line", "message", "fix"), [c[1:] for c in INVALID],
                         ids=[c[0] for c in INVALID])
def test_invalid_code(text, line, message, fix):
    with pytest.raises(MdlError) as info:
        load(text)
    d = info.value.first
    assert message in d.message, str(info.value)
    assert d.loc.line == line, str(info.value)
    if fix is not None:
        assert fix in d.fix, str(info.value)
    assert d.loc.text and d.loc.col >= 1  # quoted line and caret


def test_trailing_comma_allowed_in_1_8():
    m = load("mdl 1.8;\nenum e { a, b, };\nfloat f(float x, ) = x;\n")
    assert next(e for e in m.scope["e"] if isinstance(e, TypeEntity)).type.values == [
        ("a", 0), ("b", 1)]


def test_warnings_do_not_fail():
    m = load("mdl 1.6;\nint f(int x) { if (x > 0) return 1; }\n")
    assert [d.severity for d in m.diagnostics] == ["warning"]
    assert "may end without returning a value" in m.diagnostics[0].message


# -- properties -----------------------------------------------------------------------------------

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
@settings(max_examples=200)
def test_float_expressions_evaluate_like_python(expression):
    try:
        expected = eval(expression)  # noqa: S307 - generated arithmetic only
    except ZeroDivisionError:
        assume(False)
    value = const(f"mdl 1.6;\nconst double x = {expression.replace('e', 'e')};")
    assert value == expected or (math.isnan(value) and math.isnan(expected)) or \
        value == pytest.approx(expected, rel=1e-12)


@given(_expressions(_int_literals, ["+", "-", "*"], max_leaves=4))
@settings(max_examples=200)
def test_int_expressions_evaluate_like_python(expression):
    value = const(f"mdl 1.6;\nconst int x = {expression};")
    expected = eval(expression)  # noqa: S307 - generated arithmetic only
    assert value == (expected + 2**31) % 2**32 - 2**31  # 32-bit wrap-around


# generated MDL expressions (any syntax the parser takes) for the round trip
_names = st.sampled_from(["a", "b", "pos", "math::sin", "::m::x", "tint", "v2"])
_leaves = st.one_of(
    st.integers(0, 2**31 - 1).map(str),
    st.floats(0.0, 1e9, allow_nan=False).map(lambda x: repr(x) + "f"),
    st.sampled_from(["true", "false", '"s"', '"a\\"b"', "1.5d", ".5"]),
    _names,
)


def _mdl_expressions():
    def extend(c):
        ops = ["+", "-", "*", "/", "%", "<", "<=", "==", "!=", "&&", "||", "&", "|", "^", "<<",
               ">>", ">>>"]
        return st.one_of(
            st.tuples(c, st.sampled_from(ops), c).map(lambda t: f"({t[0]} {t[1]} {t[2]})"),
            st.tuples(st.sampled_from(["-", "!", "~", "+"]), c).map(lambda t: f"{t[0]}({t[1]})"),
            st.tuples(c, c, c).map(lambda t: f"({t[0]} ? {t[1]} : {t[2]})"),
            st.tuples(_names, st.lists(c, max_size=3)).map(
                lambda t: f"{t[0]}({', '.join(t[1])})"),
            st.tuples(_names, c, c).map(lambda t: f"{t[0]}(x: {t[1]}, y: {t[2]})"),
            st.tuples(c, st.sampled_from(["x", "xy", "surface"])).map(lambda t: f"({t[0]}).{t[1]}"),
            st.tuples(c, c).map(lambda t: f"({t[0]})[{t[1]}]"),
            st.tuples(st.sampled_from(["float", "color", "df::bsdf_component"]),
                      st.lists(c, min_size=1, max_size=3)).map(
                lambda t: f"{t[0]}[]({', '.join(t[1])})"),
            st.tuples(c, c).map(lambda t: f"let {{ float q = {t[0]}; }} in ({t[1]})"),
            c.map(lambda e: f"cast<float>({e})"),
        )
    return st.recursive(_leaves, extend, max_leaves=10)


@given(_mdl_expressions())
@settings(max_examples=300, suppress_health_check=[HealthCheck.too_slow])
def test_printed_expressions_parse_back_to_the_same_tree(text):
    tree = parse_expression(Source("e", text))
    printed = format_expression(tree)
    again = parse_expression(Source("p", printed))
    assert again == tree, (text, printed)
    assert format_expression(again) == printed


_STATEMENTS = st.sampled_from([
    "x = a + 1;", "x += 2;", "x++;", "--x;", "if (a < b) x = 1; else { x = 2; }",
    "for (int i = 0; i < 3; ++i) { x *= 2; if (x > 9) break; }",
    "while (x > 0) { x -= 1; continue; }", "do { x = x - 1; } while (x > 5);",
    "switch (x) { case 0: x = 1; break; case 1: case 2: x = 3; default: x = 0; }",
    "float3 p(1.0, 2.0, 3.0);", "const int k = 2;", "auto q = float2(x, 1);", ";",
    "{ int y = x; x = y; }", "int[3] arr;", "arr[1] = x;",
])


@given(st.lists(_STATEMENTS, max_size=8))
@settings(max_examples=200)
def test_printed_modules_parse_back_to_the_same_tree(body):
    text = ("mdl 1.6;\nimport ::math::*;\nexport int f(int a, int b = 2) [[ anno::unused() ]]\n"
            "{\n    int x = 0;\n    int[3] arr;\n" + "\n".join("    " + s for s in body)
            + "\n    return x;\n}\nexport struct s { float a = 1.0; int[2] b; };\n"
            "export enum e { one = 1, two };\nexport const float2 c = float2(1, 2);\n"
            "export material m(color t = color(0.5)) = let { color q = t * 2.0; } in "
            "material(surface: material_surface(scattering: df::diffuse_reflection_bsdf(tint: "
            "q)));\n")
    tree = parse_module(Source("m", text))
    printed = format_module(tree)
    again = parse_module(Source("p", printed))
    assert again == tree
    assert format_module(again) == printed


def test_standard_modules_print_and_parse_back():
    from mdl import stdlib

    for name in sorted(stdlib.STANDARD_MODULES):
        tree = parse_module(Source(name, stdlib.source(name)))
        assert parse_module(Source(name, format_module(tree))) == tree


_TOKEN_SOUP = (
    "mdl 1.6 ; import :: * float float2 int x y N pw_curve ( ) [ ] { } < > [[ ]] = == + - * / "
    '% ! ? : , . 1 0.5 .5 1e-3 "s" // /* */ \n const struct enum export material let in if '
    "else for while do break continue return switch case default uniform varying using "
    "typedef annotation cast auto module << >>> ++ -- += &= ^".split(" ")
)


@given(st.text(max_size=200) | st.binary(max_size=200).map(lambda b: b.decode("latin-1")))
@settings(max_examples=300)
def test_garbage_parses_or_raises_mdl_error(text):
    try:
        load(text)
    except MdlError as e:
        for d in e.diagnostics:
            assert d.loc.line >= 1 and d.loc.col >= 1


@given(st.lists(st.sampled_from(_TOKEN_SOUP), max_size=60).map(" ".join))
@settings(max_examples=500)
def test_token_soup_parses_or_raises_mdl_error(text):
    try:
        load("mdl 1.6;\n" + text)
    except MdlError as e:
        for d in e.diagnostics:
            assert d.loc.line >= 1 and d.loc.col >= 1 and d.message


@given(st.integers(min_value=1, max_value=3000))
@settings(max_examples=20)
def test_deep_nesting_raises_mdl_error_not_recursion_error(depth):
    text = "mdl 1.6;\nconst float x = " + "(" * depth + "1.0" + ")" * depth + ";"
    try:
        assert load(text).constant("x") == 1.0
        assert depth < MAX_DEPTH
    except MdlError as error:
        assert "nesting too deep" in error.first.message


def test_tokens():
    kinds = [t.kind for t in tokenize(Source("t", "a::b[[x]] >>>= 1.5f 'q'"[:18]))]
    assert kinds == ["ident", "::", "ident", "[[", "ident", "]", "]", ">>>=", "float", "eof"]
    assert isinstance(parse_expression(Source("e", "f(-1)")).args[0].value, A.Unary)


@pytest.mark.parametrize(("text", "tokens"), [
    ("\ufeffa // end, no newline", [("ident", "a")]),
    ("a/b/=c", [("ident", "a"), ("/", "/"), ("ident", "b"), ("/=", "/="), ("ident", "c")]),
    ("a/*x/*y*/z*/b", [("ident", "a"), ("ident", "b")]),
    ("a //c\n\t/ /b", [("ident", "a"), ("/", "/"), ("/", "/"), ("ident", "b")]),
    ("v.x .5 1.", [("ident", "v"), (".", "."), ("ident", "x"), ("float", ".5"),
                   ("float", "1.")]),
    ("ifx if x_1", [("ident", "ifx"), ("if", "if"), ("ident", "x_1")]),
    ('"a" "b"', [("string", '"a" "b"')]),
    ("", []),
])
def test_tokens_at_the_edges(text, tokens):
    """Comments, a byte-order mark, operators beside comments, a '.' before a digit or a
    name, keywords inside words, adjacent strings, nothing at all."""
    toks = tokenize(Source("t", text))
    assert [(t.kind, t.text) for t in toks[:-1]] == tokens
    assert toks[-1].kind == "eof" and toks[-1].start == len(text)
    for t in toks[:-1]:
        assert text[t.start:t.end] == t.text


@pytest.mark.parametrize(("text", "message", "col"), [
    ("a 'q'", "quoted identifiers", 3), ("a _b", "unexpected character '_'", 3),
    ("a \u200b", "U+200B", 3), ("a @", "unexpected character '@'", 3),
    ("a /* b", "unterminated block comment", 3), ('a "b', "unterminated string", 3),
])
def test_a_bad_character_is_located(text, message, col):
    with pytest.raises(MdlError) as e:
        tokenize(Source("t", text))
    assert message in e.value.first.message and e.value.first.loc.col == col


def _grouping(e) -> str:
    """A binary tree's grouping, fully parenthesised."""
    if isinstance(e, A.Binary):
        return f"({_grouping(e.left)} {e.op} {_grouping(e.right)})"
    if isinstance(e, A.Unary):
        return f"{e.op}{_grouping(e.operand)}"
    return e.name.text


@pytest.mark.parametrize(("text", "grouped"), [
    ("a || b && c", "(a || (b && c))"), ("a && b | c", "(a && (b | c))"),
    ("a | b ^ c & d", "(a | (b ^ (c & d)))"), ("a & b == c", "(a & (b == c))"),
    ("a != b <= c", "(a != (b <= c))"), ("a > b >> c", "(a > (b >> c))"),
    ("a << b - c", "(a << (b - c))"), ("a + b % c", "(a + (b % c))"),
    ("a * b + c", "((a * b) + c)"), ("a - b - c", "((a - b) - c)"),
    ("a / b % c * d", "(((a / b) % c) * d)"), ("a || b || c", "((a || b) || c)"),
    ("a < b == c < d", "((a < b) == (c < d))"), ("-a * b", "(-a * b)"),
    ("a * b + c * d << e & f", "((((a * b) + (c * d)) << e) & f)"),
])
def test_binary_operators_group_by_cs_precedence(text, grouped):
    assert _grouping(parse_expression(Source("e", text))) == grouped


@given(st.lists(st.sampled_from(["|", "^", "&", "<<", ">>", "+", "-", "*", "/", "%"]),
                min_size=1, max_size=10))
def test_binary_operators_group_as_python_does(ops):
    """For the operators whose order Python shares with C (not comparisons, which chain
    in Python, nor its words ``and``/``or``), random chains group as Python's own parser
    groups them."""
    import ast as py

    def python_grouping(e) -> str:
        if isinstance(e, py.BinOp):
            op = {py.BitOr: "|", py.BitXor: "^", py.BitAnd: "&", py.LShift: "<<",
                  py.RShift: ">>", py.Add: "+", py.Sub: "-", py.Mult: "*", py.Div: "/",
                  py.Mod: "%"}[type(e.op)]
            return f"({python_grouping(e.left)} {op} {python_grouping(e.right)})"
        return e.id

    text = "a0" + "".join(f" {op} a{i + 1}" for i, op in enumerate(ops))
    assert _grouping(parse_expression(Source("e", text))) == python_grouping(
        py.parse(text, mode="eval").body)


def test_entities_of_a_module():
    m = load("mdl 1.6;\nexport const float k = 2.0;\nexport float f(float x) = k * x;\n")
    assert isinstance(m.scope["k"][0], ConstEntity) and isinstance(m.functions("f")[0], Overload)
