"""The pwc-list grammar and its diagnostics (spec/pwc-list.md §1)."""

from __future__ import annotations

import math

import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from pwc import PwcError, PwcSyntaxError, compile_source, parse
from pwc.format import format_list
from pwc.parser import decode_source, parse_number
from pwc.tree import Coord, PwcList, PwPoint


@pytest.mark.parametrize(("text", "value"), [
    ("15", 15.0), ("-3", -3.0), ("+2", 2.0), ("0.375", 0.375), (".5", 0.5), ("-.25", -0.25),
    ("1e-3", 1e-3), ("2.5E+2", 250.0), ("1/3", 1 / 3), ("-4/3", -4 / 3), ("2-1/3", 2 + 1 / 3),
    ("-2-1/3", -(2 + 1 / 3)), ("0", 0.0), ("1e-300", 1e-300), ("1e300", 1e300),
    ("1.5/2", 0.75), ("3.", 3.0),
])
def test_numbers(text, value):
    assert parse_number(text) == pytest.approx(value, rel=1e-15)


@pytest.mark.parametrize(("text", "reason"), [
    ("nan", "not a finite number"), ("inf", "not a finite number"),
    ("-inf", "not a finite number"), ("1/0", "division by zero"),
    ("2-1/0", "division by zero"), ("1e400", "too large"), ("abc", "not a number"),
    ("1..2", "not a number"), ("1/2/3", "not a number"), ("--1", "not a number"),
    ("1-", "not a number"), ("", "not a number"), ("0x10", "not a number"),
])
def test_bad_numbers(text, reason):
    with pytest.raises(ValueError, match=reason):
        parse_number(text)


def test_grammar_and_comments():
    tree, warnings = parse(
        "# a comment line\n:relative   # list property\n\n0 0\n  1/2 a3 :sag -.1 # tail\n"
        "a0 2-1/2 :cyma_recta\n1 1 :flare\n", "f.pwc")
    assert warnings == []
    assert tree.relative
    assert [p.loc.line for p in tree.points] == [4, 5, 6, 7]
    p = tree.points[1]
    assert (p.x, p.y, p.prop, p.arg) == (Coord(0.5), Coord(3.0, True), "sag", -0.1)
    assert p.text == "1/2 a3 :sag -.1"
    assert tree.points[2].x == Coord(0.0, True) and tree.points[2].y.value == 2.5


def test_crlf_bom_and_tabs():
    tree, _ = parse("\ufeff0\t0\r\n1 1 :angle 90\r\n")
    assert len(tree.points) == 2 and tree.points[1].arg == 90.0


def _error(text: str, file: str = "m.pwc") -> PwcError:
    with pytest.raises(PwcError) as info:
        compile_source(text, file=file)
    return info.value


# Every broken input a new user might write: (text, line, column, message part, fix part)
BROKEN = [
    ("", 1, 1, "no points", "at least two points"),
    ("# only a comment\n\n", 2, 1, "no points", "at least two points"),
    ("0 0\n", 1, 1, "only one point", "add at least one more point"),
    ("0 0\n1 1 :sagg .3\n", 2, 5, "unknown point property ':sagg'", "did you mean ':sag'?"),
    ("0 0\n1 1 :cyma_rectum\n", 2, 5, "unknown point property", "did you mean ':cyma_recta'?"),
    ("0 0\n1 1 :flair\n", 2, 5, "unknown point property", "did you mean ':flare'?"),
    (":relativ\n0 0\n1 1\n", 1, 1, "unknown property ':relativ'", "did you mean ':relative'?"),
    ("0 0\n1 1 :angle\n", 2, 11, "needs one argument", "1 1 :angle 90"),
    ("0 0\n1 1 :sag\n", 2, 9, "needs one argument, the sagitta", "1 1 :sag .25"),
    ("0 0\n1 1 :angle 90 45\n", 2, 15, "takes one argument", "remove '45'"),
    ("0 0\n1 1 :flare 2\n", 2, 12, "takes no arguments", "remove '2'"),
    ("0 0\n1 1 :cyma_recta x y\n", 2, 17, "takes no arguments", "remove 'x y'"),
    ("0 0\n1/0 1\n", 2, 1, "division by zero", "numbers look like"),
    ("0 0\n1 nan\n", 2, 3, "not a finite number", "numbers look like"),
    ("0 0\n1 1 :angle inf\n", 2, 12, "not a finite number", "numbers look like"),
    ("0 0 :angle 90\n1 1\n", 1, 5, "':angle' on the list's first point", "remove ':angle'"),
    ("# a comment\n1 1 :flare\n", 2, 5, "line 2 holds the first point, which ends no piece",
     "add the starting point on a line before it (e.g. '0 0')"),
    ("0 0\n:relative\n1 1\n", 2, 1, "':relative' after the first point", "top of the file"),
    ("0 0\n1\n", 2, 2, "needs two coordinates", "'X Y'"),
    ("0 0\n1 :sag 2\n", 2, 2, "needs two coordinates", "'X Y'"),
    ("0 0\n1 2 3\n", 2, 5, "unexpected '3'", "optionally followed by one property"),
    ("0 0\n:angle 90\n", 2, 1, "point property but this line has no coordinates", "1 1 :angle"),
    ("0 0\n1 1 :relative\n", 2, 5, "unknown point property ':relative'", "list property"),
    ("0 0\n1 1 :sag a.5\n", 2, 10, "'a' (absolute) prefix applies to coordinates only",
     "remove the 'a'"),
    ("hello world\n", 1, 1, "'hello' is not a number", "numbers look like"),
    ("0 0\n0 0 :angle 90\n", 2, 1, "joins two identical points", "move this point"),
    ("0 0\n0 0 :sag .1\n", 2, 1, "joins two identical points", "move this point"),
    ("0 0\n0 0 :cyma_recta\n", 2, 1, "joins two identical points", "move this point"),
    ("0 0\n1 0 :flare\n", 2, 1, "needs a previous piece", "put a segment or arc before"),
    ("0 0\n0 0\n1 1 :flare\n", 3, 1, "needs a previous piece", "put a segment or arc"),
    ("0 0\n1 1 :angle 360\n", 2, 1, "full circle or more", "between -360 and 360"),
    ("0 0\n1 1 :angle -400\n", 2, 1, "full circle or more", "between -360 and 360"),
    ("0 0\n0 0\n", 2, 1, "no length", "different coordinates"),
    ("0 0\n1 0\n-1 0 :flare\n", 3, 1, "straight behind its start", "off the line"),
]


@pytest.mark.parametrize(("text", "line", "col", "message", "fix"), BROKEN)
def test_diagnostics_name_file_line_column_and_fix(text, line, col, message, fix):
    err = _error(text)
    errors = [d for d in err.diagnostics if d.severity == "error"]
    d = errors[0]
    assert (d.loc.file, d.loc.line, d.loc.col) == ("m.pwc", line, col), d.format()
    assert message in d.message, d.format()
    assert fix in d.fix, d.format()
    report = str(err)
    assert f"m.pwc:{line}:{col}: error:" in report
    if d.loc.text:  # the culprit line is quoted with a caret under the column
        quoted = report.splitlines()
        i = next(k for k, s in enumerate(quoted) if s.startswith(f"m.pwc:{line}:{col}: error"))
        assert quoted[i + 1].endswith("| " + d.loc.text.rstrip("\r\n").expandtabs(1))
        assert quoted[i + 2].index("^") == quoted[i + 1].index("| ") + 2 + col - 1


def test_every_error_is_reported_not_just_the_first():
    err = _error("0 0\n1 1 :sagg 1\n2 nan\n3 3 :flare 1\n")
    assert [d.loc.line for d in err.diagnostics] == [2, 3, 4]


def test_syntax_and_geometry_errors_are_distinct_types():
    assert isinstance(_error("0 0\n1 1 :sagg 1\n"), PwcSyntaxError)
    assert not isinstance(_error("0 0\n0 0 :sag 1\n"), PwcSyntaxError)


@pytest.mark.parametrize("data", [
    b"\x00\x01\x02binary", b"0 0\n1 1\n\xff\xfe garbage", b"\x89PNG\r\n\x1a\n\x00\x00",
])
def test_binary_data_is_rejected_with_a_location(data):
    with pytest.raises(PwcSyntaxError) as info:
        decode_source(data, "img.pwc")
    d = info.value.first
    assert d.loc.file == "img.pwc" and d.loc.line >= 1
    assert "not a text file" in d.message and "UTF-8" in d.fix


def test_warnings_do_not_stop_compilation():
    curve, warnings = compile_source("0 0\n1 0\n1 0\n1 1 :sag 0\n2 2 :angle 1e-7\n")
    messages = " | ".join(w.message for w in warnings)
    assert all(w.severity == "warning" for w in warnings)
    assert "identical points" in messages and ":sag 0" in messages and "1e-07" in messages
    assert curve.n == 4  # the duplicate is dropped; the flat arcs become segments
    assert [w.loc.line for w in warnings] == [3, 4, 5]


def test_duplicate_relative_is_a_warning():
    _, warnings = parse(":relative\n:relative\n0 0\n1 1\n")
    assert len(warnings) == 1 and "given twice" in warnings[0].message


# -- property-based: format/parse round trip, and garbage never crashes the parser -------

finite = st.floats(min_value=-1e12, max_value=1e12, allow_nan=False, allow_infinity=False)
coords = st.builds(Coord, finite, st.booleans())


@st.composite
def trees(draw):
    n = draw(st.integers(2, 12))
    points = [PwPoint(draw(coords), draw(coords))]
    for _ in range(n - 1):
        prop = draw(st.sampled_from([None, "angle", "sag", "cyma_recta", "cyma_reversa", "flare"]))
        arg = draw(finite) if prop in ("angle", "sag") else None
        points.append(PwPoint(draw(coords), draw(coords), prop, arg))
    return PwcList(tuple(points), draw(st.booleans()))


@given(trees())
@settings(max_examples=200)
def test_format_then_parse_is_identity(tree):
    again, warnings = parse(format_list(tree))
    assert again == tree and warnings == []


@given(st.text(alphabet=st.characters(codec="utf-8"), max_size=200))
@settings(max_examples=300)
def test_garbage_raises_only_pwc_errors_with_valid_locations(text):
    try:
        compile_source(text, file="g.pwc")
    except PwcError as e:
        n_lines = max(1, len(text.splitlines()))
        for d in e.diagnostics:
            assert d.loc.file == "g.pwc" and 1 <= d.loc.line <= n_lines and d.loc.col >= 1
            assert d.message and d.format()


@given(st.binary(max_size=200))
@settings(max_examples=200)
def test_random_bytes_raise_only_pwc_errors(data):
    try:
        compile_source(decode_source(data, "b.pwc"), file="b.pwc")
    except PwcError as e:
        assert all(d.loc.line >= 1 for d in e.diagnostics)


@given(st.lists(st.sampled_from(["0", "1", "-", ".", "/", "a", " ", ":sag", ":angle", "\n",
                                 "e", "3", ":flare", "#", ":relative"]), max_size=40))
@settings(max_examples=300)
def test_mutated_lists_raise_only_pwc_errors(parts):
    text = "0 0\n1 1\n" + "".join(parts)
    try:
        curve, _ = compile_source(text)
        assert all(math.isfinite(v) for v in curve.pt.ravel())
    except PwcError as e:
        assert e.diagnostics


def test_a_file_that_is_not_a_pwc_list_stops_after_fifty_errors():
    err = _error("word word\n" * 1000)
    assert len(err.diagnostics) == 51 and "too many errors" in err.diagnostics[-1].message
