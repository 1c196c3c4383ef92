"""Parse MDL call expressions, as the Handbook prints them in figure captions, into materials.

>>> m = parse_material("glossy_waves(distance: float2(0.02, 0.02), frequency: "
...                    "float2(10.0, 10.0), tint: color(0.6, 0.4, 0.0), use_displacement: true)")
>>> m.geometry.displacement.name, m.surface.scattering.name
('waves', 'simple_glossy_bsdf')

Grammar (a small tokenizer and a recursive-descent parser; nothing is ever ``eval``-ed)::

    expression := ("-" | "+") expression | primary
    primary    := NUMBER | STRING | name [ "(" [ argument ("," argument)* ] ")" ]
                | name "[" [ INT ] "]" "(" expression ("," expression)* ")"
                | "(" expression ")"
    name       := ["::"] IDENT ("::" IDENT)*
    argument   := IDENT ":" expression | expression

Numbers are MDL literals (``4`` is an int, ``4.0``, ``.5``, ``1e-3``, ``2.0f`` are
floats); strings are double-quoted with ``\\"``, ``\\\\``, ``\\n``, ``\\t`` escapes;
``//`` and ``/* */`` comments are skipped.  Positional arguments come before named ones,
as in MDL.  Unary minus applies to constant numbers and vectors.

Array constructors ``T[](e1, e2, ...)`` and ``T[N](e1, ..., eN)`` (the Handbook's
``df::bsdf_component[](df::bsdf_component(weight: 0.5, component: ...), ...)``, §6.4.1)
take positional elements of type ``T``: the component structs ``bsdf_component``,
``color_bsdf_component``, ``edf_component``, ``color_edf_component`` (usually
``df::``-qualified) or the plain types ``float``, ``int``, ``bool``, ``float2``,
``float3``, ``color``, ``string`` (an int converts to a float; a scalar does not become a
color).  ``N``, when given, must equal the number of elements.  The mixers'
``bsdf_component[]`` parameter also takes an ``edf_component[]`` (their edf overloads),
and such a mix is an edf.

Names are resolved in this order.  The module part of a qualified call, enum value or
constant must be one of :data:`KNOWN_MODULES` (``df::``, ``state::``, ``tex::``,
``math::``, ``functions::``, ``geometry::``...) but does not otherwise change the
lookup (``geometry::grid`` is ``grid``); profiles may be qualified by any module
(``ornament_2::ornament_2``, ``pwc_examples::doric_flutes``):

* calls: the constructors ``float2``, ``float3``, ``color``, ``float``, ``int``,
  ``texture_2d`` and the structs ``material``, ``material_surface``,
  ``material_emission``, ``material_volume``, ``material_geometry``; then the materials
  of :data:`render.materials.MATERIALS`; then the distribution functions of
  :data:`render.material.df`; then the library functions
  :data:`render.library.FUNCTIONS` (``u()``, ``uv_wave(...)``, ``move_up(...)``,
  ``state::normal()``...), which give varying values;
* plain names: ``true``/``false``; enum values (``along_u``, ``along_v``, ``uvw``,
  ``object``, ``world``, ``scatter_reflect``..., ``intensity_power``...,
  ``gamma_linear``...); constants (``pink_stone``, ``math::PI``); profiles: ``NAME``
  is the compiled curve ``NAME.pwc`` on the profile search path and ``NAME_length``
  its length (``ornament_2::ornament_2_length``).

``texture_2d("file.png")`` reads the file relative to ``base_dir``, then
``gallery/textures``; its optional second argument is ``tex::gamma_default``,
``gamma_linear`` (the default here: the chapters' textures are data) or ``gamma_srgb``.

Arguments are checked against each callee's MDL signature (:func:`render.material.mdl_signature`):
unknown names and parameters get did-you-mean suggestions; types must match (an int
converts to a float; a scalar does not silently become a float2 or color: write
``float2(x)``); a function of the state cannot go to a ``uniform`` parameter.  Every
error, including a failing material function, is a :class:`MaterialExprError` with the
line and column of the offending token.
"""

from __future__ import annotations

import difflib
import math
import re
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from pwc.files import PROFILE_PATH_ENV
from render.library.functions import FUNCTIONS
from render.library.resources import (
    ResourceError,
    find_profile,
    load_profile,
    load_texture,
    profile_dirs,
    profile_names,
    search_paths,
)
from render.material import (
    DF_SIGNATURES,
    MdlParam,
    MdlType,
    Varying,
    df,
    evaluate,
    material,
    material_emission,
    material_geometry,
    material_surface,
    material_volume,
    mdl_signature,
)
from render.materials import CONSTANTS, MATERIALS

__all__ = [
    "MaterialExprError",
    "Token",
    "tokenize",
    "Node",
    "Number",
    "String",
    "Name",
    "Call",
    "Argument",
    "Negate",
    "ArrayConstructor",
    "parse",
    "Value",
    "evaluate_expression",
    "parse_material",
    "MAX_DEPTH",
    "KNOWN_MODULES",
]

#: Deepest nesting of calls and parentheses accepted.
MAX_DEPTH = 64

#: Module names accepted in qualified calls, enum values and constants (MDL's standard
#: modules and the Handbook's); profiles (data) may be qualified by any module name.
KNOWN_MODULES = frozenset({
    "df", "state", "tex", "math", "anno", "base", "functions", "geometry", "materials",
    "perlin_noise", "diffuse_reflection", "displacement", "pw_curve", "profile_arrays",
})


class MaterialExprError(ValueError):
    """An error in a material expression, with where it is and how to fix it.

    Parameters
    ----------
    message : str
    col : int
        1-based column on ``line``.
    fix : str, optional
        A suggestion.
    line : int
        1-based line within the expression text (captions span lines).
    offset : int
        0-based character offset into the text.

    Examples
    --------
    >>> str(MaterialExprError("unknown material 'glosy'", 1, "did you mean 'glossy'?"))
    "1:1: unknown material 'glosy' (did you mean 'glossy'?)"
    """

    def __init__(self, message: str, col: int, fix: str | None = None, *, line: int = 1,
                 offset: int = 0):
        self.message = message
        self.col = col
        self.fix = fix
        self.line = line
        self.offset = offset
        super().__init__(str(self))

    def __str__(self) -> str:
        return f"{self.line}:{self.col}: {self.message}" + (f" ({self.fix})" if self.fix else "")

    def __reduce__(self):
        return (_rebuild_error, (self.message, self.col, self.fix, self.line, self.offset))


def _a(noun: str) -> str:
    """``noun`` with its indefinite article (``an int``, ``a float``)."""
    return ("an " if noun[:1] in "aeio" else "a ") + noun  # "a uniform", "a uvw"


def _rebuild_error(message, col, fix, line, offset):
    return MaterialExprError(message, col, fix, line=line, offset=offset)


# ---------------------------------------------------------------------------
# tokens


@dataclass(frozen=True)
class Token:
    """One token: ``kind`` in NUMBER, STRING, IDENT, SCOPE (``::``), ``(``, ``)``, ``[``,
    ``]``, ``,``, ``:``, ``-``, ``+``, EOF; ``value`` is the number or the unescaped string."""

    kind: str
    text: str
    value: Any
    offset: int
    line: int
    col: int


_NUMBER = re.compile(r"(?:\d+\.\d*|\.\d+|\d+)(?:[eE][+-]?\d+)?[fFdD]?")
_IDENT = re.compile(r"[A-Za-z_][A-Za-z0-9_]*")
_ESCAPES = {'"': '"', "\\": "\\", "n": "\n", "t": "\t", "'": "'"}
_PUNCT = {"(": "(", ")": ")", ",": ",", "-": "-", "+": "+", "[": "[", "]": "]"}


class _Source:
    """Offset -> (line, col) for error messages."""

    def __init__(self, text: str):
        self.text = text
        self.line_starts = [0] + [m.end() for m in re.finditer("\n", text)]

    def where(self, offset: int) -> tuple[int, int]:
        lo, hi = 0, len(self.line_starts) - 1
        while lo < hi:
            mid = (lo + hi + 1) // 2
            if self.line_starts[mid] <= offset:
                lo = mid
            else:
                hi = mid - 1
        return lo + 1, offset - self.line_starts[lo] + 1

    def error(self, message: str, offset: int, fix: str | None = None) -> MaterialExprError:
        line, col = self.where(offset)
        return MaterialExprError(message, col, fix, line=line, offset=offset)


def tokenize(text: str) -> list[Token]:
    """Split an expression into tokens (the last is EOF).

    Raises
    ------
    MaterialExprError
        An unexpected character, an unterminated string or comment, or a number that
        is not a finite float64.

    Examples
    --------
    >>> [t.kind for t in tokenize('color(0.5, "a") // note')]
    ['IDENT', '(', 'NUMBER', ',', 'STRING', ')', 'EOF']
    """
    if not isinstance(text, str):
        raise MaterialExprError(
            f"a material expression must be a string, got {type(text).__name__}", 1)
    src = _Source(text)
    tokens: list[Token] = []
    i, n = 0, len(text)

    def token(kind: str, start: int, end: int, value: Any = None) -> Token:
        line, col = src.where(start)
        return Token(kind, text[start:end], value, start, line, col)

    while i < n:
        c = text[i]
        if c.isspace():
            i += 1
            continue
        if text.startswith("//", i):
            end = text.find("\n", i)
            i = n if end < 0 else end + 1
            continue
        if text.startswith("/*", i):
            end = text.find("*/", i + 2)
            if end < 0:
                raise src.error("unterminated comment", i, "close it with */")
            i = end + 2
            continue
        m = _NUMBER.match(text, i)
        if m and (c.isdigit() or c == "."):
            literal = m.group()
            if m.end() < n and (text[m.end()].isalnum() or text[m.end()] == "_"):
                bad = _IDENT.match(text, m.end()) or re.compile(r"\w+").match(text, m.end())
                raise src.error(f"malformed number {text[i:bad.end()]!r}", i,
                                "separate the number from the name that follows")
            tokens.append(token("NUMBER", i, m.end(), _number(literal, src, i)))
            i = m.end()
            continue
        m = _IDENT.match(text, i)
        if m:
            tokens.append(token("IDENT", i, m.end(), m.group()))
            i = m.end()
            continue
        if text.startswith("::", i):
            tokens.append(token("SCOPE", i, i + 2))
            i += 2
            continue
        if c == ":":
            tokens.append(token(":", i, i + 1))
            i += 1
            continue
        if c in _PUNCT:
            tokens.append(token(c, i, i + 1))
            i += 1
            continue
        if c == '"':
            value, end = _string(text, i, src)
            tokens.append(token("STRING", i, end, value))
            i = end
            continue
        if c == ".":
            raise src.error("member access ('.') is not supported in material expressions", i,
                            "pass the whole material; materials take materials as arguments")
        raise src.error(f"unexpected character {c!r}", i)
    tokens.append(token("EOF", n, n))
    return tokens


def _number(literal: str, src: _Source, offset: int) -> int | float:
    body = literal.rstrip("fFdD")
    is_float = body != literal or any(ch in body for ch in ".eE")
    if not is_float:
        if len(body.lstrip("0")) > 18:
            raise src.error(f"integer literal {literal} is too large", offset,
                            "MDL ints are 32-bit; write a float (e.g. 1e30) if you mean one")
        value = int(body)
        if value > 2**31 - 1:
            raise src.error(f"integer literal {literal} is too large", offset,
                            "MDL ints are 32-bit; write a float (e.g. 1e30) if you mean one")
        return value
    try:
        value = float(body)
    except (ValueError, OverflowError):
        value = math.inf
    if not math.isfinite(value):
        raise src.error(f"number {literal} is out of range", offset,
                        "numbers must be finite float64")
    return value


def _string(text: str, start: int, src: _Source) -> tuple[str, int]:
    out = []
    i = start + 1
    while i < len(text):
        c = text[i]
        if c == '"':
            return "".join(out), i + 1
        if c == "\n":
            break
        if c == "\\":
            if i + 1 < len(text) and text[i + 1] in _ESCAPES:
                out.append(_ESCAPES[text[i + 1]])
                i += 2
                continue
            raise src.error("unknown escape in string", i, r'use \", \\, \n or \t')
        out.append(c)
        i += 1
    raise src.error("unterminated string", start, 'close it with "')


# ---------------------------------------------------------------------------
# syntax tree


@dataclass(frozen=True)
class Node:
    """Base of the syntax tree; ``offset`` is where the node starts."""

    offset: int


@dataclass(frozen=True)
class Number(Node):
    value: int | float


@dataclass(frozen=True)
class String(Node):
    value: str


@dataclass(frozen=True)
class Name(Node):
    parts: tuple[str, ...]

    @property
    def text(self) -> str:
        return "::".join(self.parts)


@dataclass(frozen=True)
class Argument:
    name: str | None
    name_offset: int
    value: Node


@dataclass(frozen=True)
class Call(Node):
    callee: Name
    arguments: tuple[Argument, ...]
    close_offset: int


@dataclass(frozen=True)
class Negate(Node):
    operand: Node
    sign: float


@dataclass(frozen=True)
class ArrayConstructor(Node):
    """``element[size](arguments)``; ``size`` is None for ``element[](...)``."""

    element: Name
    size: int | None
    size_offset: int
    arguments: tuple[Argument, ...]
    close_offset: int


class _Parser:
    def __init__(self, text: str):
        self.src = _Source(text)
        self.tokens = tokenize(text)
        self.i = 0
        self.depth = 0

    @property
    def tok(self) -> Token:
        return self.tokens[self.i]

    def peek(self, k: int = 1) -> Token:
        return self.tokens[min(self.i + k, len(self.tokens) - 1)]

    def advance(self) -> Token:
        t = self.tokens[self.i]
        self.i = min(self.i + 1, len(self.tokens) - 1)
        return t

    def fail(self, message: str, token: Token | None = None, fix: str | None = None):
        t = token or self.tok
        raise MaterialExprError(message, t.col, fix, line=t.line, offset=t.offset)

    def describe(self, t: Token) -> str:
        return "the end of the expression" if t.kind == "EOF" else repr(t.text)

    def expect(self, kind: str, what: str, fix: str | None = None) -> Token:
        if self.tok.kind != kind:
            self.fail(f"expected {what}, found {self.describe(self.tok)}", fix=fix)
        return self.advance()

    def parse(self) -> Node:
        if self.tok.kind == "EOF":
            self.fail("empty material expression", fix="write a call such as glossy()")
        node = self.expression()
        if self.tok.kind != "EOF":
            self.fail(f"unexpected {self.describe(self.tok)} after the expression",
                      fix="a material expression is one call")
        return node

    def expression(self) -> Node:
        self.depth += 1
        if self.depth > MAX_DEPTH:
            self.fail(f"expression nested deeper than {MAX_DEPTH} levels")
        try:
            t = self.tok
            if t.kind in ("-", "+"):
                self.advance()
                return Negate(t.offset, self.expression(), -1.0 if t.kind == "-" else 1.0)
            return self.primary()
        finally:
            self.depth -= 1

    def primary(self) -> Node:
        t = self.tok
        if t.kind == "NUMBER":
            self.advance()
            return Number(t.offset, t.value)
        if t.kind == "STRING":
            self.advance()
            return String(t.offset, t.value)
        if t.kind == "(":
            self.advance()
            node = self.expression()
            self.expect(")", "')'", "close the parenthesis")
            return node
        if t.kind in ("IDENT", "SCOPE"):
            name = self.name()
            if self.tok.kind == "[":
                return self.array(name)
            if self.tok.kind == "(":
                return self.call(name)
            return name
        self.fail(f"expected a value, found {self.describe(t)}",
                  fix="a value is a number, a string, a name or a call such as color(0.5)")

    def name(self) -> Name:
        start = self.tok
        parts = []
        if self.tok.kind == "SCOPE":
            self.advance()
        while True:
            parts.append(self.expect("IDENT", "a name").value)
            if self.tok.kind != "SCOPE":
                break
            self.advance()
        return Name(start.offset, tuple(parts))

    def array(self, element: Name) -> ArrayConstructor:
        """``element[N](...)`` or ``element[](...)``; the current token is ``[``."""
        self.advance()  # "["
        size, size_offset = None, self.tok.offset
        example = f"{element.text}[](element, ...)"
        if self.tok.kind == "NUMBER":
            number = self.advance()
            if not isinstance(number.value, int) or number.value < 1:
                self.fail(f"array size must be a whole number >= 1, got {number.text}", number,
                          f"write {element.text}[] to take the size from the elements")
            size = number.value
        elif self.tok.kind != "]":
            self.fail(f"expected an array size or ']' after '{element.text}[', found "
                      f"{self.describe(self.tok)}",
                      fix=f"an array value is written {example} or {element.text}[N](...)")
        self.expect("]", "']'", "close the array size with ']'")
        if self.tok.kind != "(":
            self.fail(f"expected '(' after '{element.text}[{'' if size is None else size}]', "
                      f"found {self.describe(self.tok)}",
                      fix=f"an array value is written {example}; indexing is not supported")
        call = self.call(element, f"the array {element.text}[]")
        return ArrayConstructor(element.offset, element, size, size_offset, call.arguments,
                                call.close_offset)

    def call(self, callee: Name, what: str | None = None) -> Call:
        what = what or f"the call of {callee.text}"
        self.advance()  # "("
        arguments: list[Argument] = []
        if self.tok.kind != ")":
            while True:
                arguments.append(self.argument())
                if self.tok.kind == ",":
                    self.advance()
                    if self.tok.kind == ")":
                        self.fail("expected an argument after ','", fix="remove the trailing ','")
                    continue
                if self.tok.kind == ")":
                    break
                if self.tok.kind == "EOF":
                    self.fail(f"missing ')' to close {what}", fix="add ')' at the end")
                self.fail(f"expected ',' or ')' in {what}, found "
                          f"{self.describe(self.tok)}", fix="separate arguments with ','")
        close = self.advance()
        return Call(callee.offset, callee, tuple(arguments), close.offset)

    def argument(self) -> Argument:
        t = self.tok
        if t.kind == "IDENT" and self.peek().kind == ":":
            self.advance()
            self.advance()
            if self.tok.kind in (",", ")", "EOF"):
                self.fail(f"expected a value for argument {t.value!r}")
            return Argument(t.value, t.offset, self.expression())
        return Argument(None, t.offset, self.expression())


def parse(text: str) -> Node:
    """Parse an expression into its syntax tree (no names are resolved).

    Raises
    ------
    MaterialExprError

    Examples
    --------
    >>> node = parse("glossy(tint: color(0.6, 0.4, 0.0))")
    >>> node.callee.text, [a.name for a in node.arguments]
    ('glossy', ['tint'])
    """
    return _Parser(text).parse()


# ---------------------------------------------------------------------------
# values and types


@dataclass(frozen=True)
class Value:
    """An evaluated expression: the Python value, its MDL type, and whether it varies.

    ``varying`` values are callables of the shading state (or Fields)."""

    value: Any
    type: MdlType
    varying: bool = False


def _t(name: str, values: tuple[str, ...] = ()) -> MdlType:
    return MdlType(name, False, values)


_ENUMS: dict[str, MdlType] = {}
for _enum_name, _values in (
    ("mapping_mode", ("uvw", "object", "world")),
    ("displacement_direction", ("along_u", "along_v")),
    ("scatter_mode", ("scatter_reflect", "scatter_transmit", "scatter_reflect_transmit")),
    ("intensity_mode", ("intensity_radiant_exitance", "intensity_power")),
    ("gamma_mode", ("gamma_default", "gamma_linear", "gamma_srgb")),
):
    for _value in _values:
        _ENUMS[_value] = _t(_enum_name, _values)

_NUMERIC_CONSTANTS = {"PI": math.pi, "TWO_PI": 2.0 * math.pi, "HALF_PI": 0.5 * math.pi}
#: element types of array constructors ``T[](...)``
_ARRAY_COMPONENTS = ("bsdf_component", "color_bsdf_component", "edf_component",
                     "color_edf_component", "vdf_component", "color_vdf_component")
_ARRAY_ELEMENTS = _ARRAY_COMPONENTS + ("float", "int", "bool", "float2", "float3", "color",
                                       "string")
#: array parameters that also take another array type (the mixers' edf overloads)
_ARRAY_COMPATIBLE = {"bsdf_component[]": ("edf_component[]", "vdf_component[]"),
                     "color_bsdf_component[]": ("color_edf_component[]",
                                                "color_vdf_component[]")}
_VECTOR_WIDTH = {"float2": 2, "float3": 3, "color": 3}
_CONSTRUCTORS = ("float2", "float3", "color", "float", "int", "texture_2d", "bsdf_measurement",
                 "light_profile", "float3x3", "material",
                 "material_surface", "material_emission", "material_volume", "material_geometry")

_F, _UF = MdlType("float"), MdlType("float", True)
_STRUCT_SIGNATURES: dict[str, tuple[Callable, list[MdlParam], MdlType]] = {
    "material": (material, [
        MdlParam("thin_walled", MdlType("bool", True), False, False),
        MdlParam("surface", _t("material_surface"), False),
        MdlParam("backface", _t("material_surface"), False),
        MdlParam("ior", MdlType("color"), False),
        MdlParam("volume", _t("material_volume"), False),
        MdlParam("geometry", _t("material_geometry"), False),
        MdlParam("hair", _t("hair_bsdf"), False),
    ], _t("material")),
    "material_surface": (material_surface, [
        MdlParam("scattering", _t("bsdf"), False),
        MdlParam("emission", _t("material_emission"), False),
    ], _t("material_surface")),
    "material_emission": (material_emission, [
        MdlParam("emission", _t("edf"), False),
        MdlParam("intensity", MdlType("color"), False),
        MdlParam("mode", MdlType("intensity_mode", True, _ENUMS["intensity_power"].values), False),
    ], _t("material_emission")),
    "material_volume": (material_volume, [
        MdlParam("scattering", _t("vdf"), False),
        MdlParam("absorption_coefficient", MdlType("color"), False),
        MdlParam("scattering_coefficient", MdlType("color"), False),
        MdlParam("emission_intensity", MdlType("color"), False),
    ], _t("material_volume")),
    "material_geometry": (material_geometry, [
        MdlParam("displacement", MdlType("float3"), False),
        MdlParam("cutout_opacity", _F, False),
        MdlParam("normal", MdlType("float3"), False),
    ], _t("material_geometry")),
}


class _Evaluator:
    def __init__(self, text: str, base_dir):
        self.src = _Source(text)
        self.base_dir = None if base_dir is None else Path(base_dir)

    def error(self, message: str, offset: int, fix: str | None = None) -> MaterialExprError:
        return self.src.error(message, offset, fix)

    # --- names -----------------------------------------------------------------

    def all_names(self) -> list[str]:
        names = set(_CONSTRUCTORS) | set(MATERIALS) | set(DF_SIGNATURES) | set(_ENUMS)
        names |= set(CONSTANTS) | {"true", "false"} | set(_NUMERIC_CONSTANTS)
        names |= {k.split("::")[-1] for k in FUNCTIONS}
        names |= set(profile_names())
        return sorted(names)

    def suggest(self, word: str, candidates: Sequence[str]) -> str | None:
        hint = difflib.get_close_matches(word, list(candidates), 1, 0.6)
        return f"did you mean {hint[0]!r}?" if hint else None

    def evaluate(self, node: Node) -> Value:
        if isinstance(node, Number):
            if isinstance(node.value, int):
                return Value(node.value, _t("int"))
            return Value(float(node.value), _t("float"))
        if isinstance(node, String):
            return Value(node.value, _t("string"))
        if isinstance(node, Negate):
            return self.negate(node)
        if isinstance(node, Name):
            return self.name(node)
        if isinstance(node, Call):
            return self.call(node)
        if isinstance(node, ArrayConstructor):
            return self.array(node)
        raise self.error("unsupported expression", node.offset)  # pragma: no cover

    def negate(self, node: Negate) -> Value:
        v = self.evaluate(node.operand)
        if v.varying:
            raise self.error("cannot negate a function of the state here", node.offset,
                             "negate constants only")
        if v.type.name in ("int", "float"):
            return Value(-v.value if node.sign < 0 else v.value, v.type)
        if v.type.name in _VECTOR_WIDTH:
            return Value(tuple(node.sign * x for x in v.value), v.type)
        raise self.error(f"cannot negate {_a(v.type.name)}", node.offset,
                         "'-' applies to numbers and vectors")

    def name(self, node: Name) -> Value:
        last = node.parts[-1]
        if len(node.parts) == 1 and last in ("true", "false"):
            return Value(last == "true", _t("bool"))
        if last in _ENUMS or last in CONSTANTS or last in _NUMERIC_CONSTANTS:
            self.check_module(node)
        if last in _ENUMS:
            return Value(last, _ENUMS[last])
        if last in CONSTANTS:
            return Value(tuple(float(x) for x in CONSTANTS[last]), _t("color"))
        if last in _NUMERIC_CONSTANTS and (len(node.parts) == 1 or node.parts[-2] == "math"):
            return Value(_NUMERIC_CONSTANTS[last], _t("float"))
        if find_profile(last) is not None:
            return Value(self.load_profile(last, node.offset), MdlType("pw_curve", True))
        if last.endswith("_length") and find_profile(last[: -len("_length")]) is not None:
            curve = self.load_profile(last[: -len("_length")], node.offset)
            return Value(float(curve.length), _t("float"))
        if self.callable_kind(node) is not None:
            raise self.error(f"{node.text} must be called", node.offset,
                             f"write {node.text}(...) with its arguments")
        module = node.parts[-2] if len(node.parts) == 2 else None
        if module is not None and last in (module, f"{module}_length"):  # NAME::NAME
            close = difflib.get_close_matches(module, profile_names(), 1)
            raise self.error(
                f"no profile {module!r}: there is no {module}.pwc in "
                f"{', '.join(str(d) for d in profile_dirs())}", node.offset,
                (f"did you mean {close[0]!r}? or " if close else "")
                + f"put {module}.pwc beside the scene file, or add its folder with "
                f"--profiles DIR or ${PROFILE_PATH_ENV}")
        raise self.error(f"unknown name {node.text!r}", node.offset,
                         self.suggest(last, self.all_names()))

    def load_profile(self, name: str, offset: int):
        try:
            return load_profile(name)
        except Exception as e:  # pwc.PwcError, OSError: a profile that does not compile
            raise self.error(f"profile {name!r} does not load: {e}", offset) from None

    # --- calls -----------------------------------------------------------------

    def callable_kind(self, name: Name) -> str | None:
        last = name.parts[-1]
        if last in _CONSTRUCTORS:
            return "constructor"
        if last in MATERIALS:
            return "material"
        if last in DF_SIGNATURES:
            return "df"
        if name.text in FUNCTIONS or last in FUNCTIONS:
            return "function"
        return None

    def check_module(self, name: Name) -> None:
        """Qualified calls, enum values and constants must name a known module."""
        if len(name.parts) > 1 and name.parts[-2] not in KNOWN_MODULES:
            raise self.error(
                f"unknown module {name.parts[-2]!r} in {name.text!r}", name.offset,
                f"modules: {', '.join(sorted(KNOWN_MODULES))}"
                + ("; a named argument is written 'name: value'" if len(name.parts) == 2 else ""))

    def call(self, node: Call) -> Value:
        self.check_module(node.callee)
        kind = self.callable_kind(node.callee)
        last = node.callee.parts[-1]
        if kind is None:
            what = "function or material"
            raise self.error(f"unknown {what} {node.callee.text!r}", node.offset,
                             self.suggest(last, [n for n in self.all_names() if n not in _ENUMS]))
        if kind == "constructor":
            return self.construct(node, last)
        if kind == "material":
            function = MATERIALS[last]
        elif kind == "df":
            function = getattr(df, last)
        else:
            function = FUNCTIONS.get(node.callee.text) or FUNCTIONS[last]
        overloads = getattr(function, "overloads", None) if kind == "df" else None
        if overloads:  # MDL's overloads of one name: the first that takes the arguments
            first = None
            for candidate in overloads:
                params, returns = mdl_signature(candidate)
                try:
                    kwargs = self.bind(node, params)
                except MaterialExprError as e:
                    first = first or e
                    continue
                function = candidate
                break
            else:
                raise first
        else:
            params, returns = mdl_signature(function)
            kwargs = self.bind(node, params)
        try:
            result = function(**kwargs)
        except MaterialExprError:
            raise
        except Exception as e:  # the callee rejected a value: report it at the call
            raise self.error(f"{node.callee.text}(...): {e}", node.offset) from None
        if kind == "material":
            return Value(result, _t("material"))
        returns = returns or _t("float")
        if kind == "df" and getattr(result, "kind", None) in ("bsdf", "edf", "vdf"):
            returns = _t(result.kind)  # a mix of edf components is an edf
        return Value(result, returns, varying=callable(result) and not isinstance(result, material)
                     and returns.name not in ("bsdf", "edf", "vdf"))

    def bind(self, node: Call, params: list[MdlParam]) -> dict[str, Any]:
        """Match the call's arguments to ``params`` and check their types."""
        by_name = {p.name: p for p in params}
        given: dict[str, tuple[Argument, Value]] = {}
        named_seen = False
        for index, argument in enumerate(node.arguments):
            if argument.name is None:
                if named_seen:
                    raise self.error("positional argument after named arguments",
                                     argument.name_offset,
                                     "put positional arguments first, or name this one")
                if index >= len(params):
                    raise self.error(
                        f"{node.callee.text} takes {len(params)} argument"
                        f"{'' if len(params) == 1 else 's'}, got {len(node.arguments)}",
                        argument.name_offset, "remove the extra arguments")
                param = params[index]
            else:
                named_seen = True
                if argument.name not in by_name:
                    hint = self.suggest(argument.name, list(by_name))
                    if hint is None and params:
                        hint = f"parameters: {', '.join(p.name for p in params)}"
                    raise self.error(f"{node.callee.text} has no parameter {argument.name!r}",
                                     argument.name_offset, hint)
                param = by_name[argument.name]
                if param.name in given:
                    raise self.error(f"argument {param.name!r} given twice", argument.name_offset)
            given[param.name] = (argument, self.evaluate(argument.value))
        missing = [p for p in params if p.required and p.name not in given]
        if missing:
            p = missing[0]
            raise self.error(f"{node.callee.text} needs the argument {p.name!r} ({p.type})",
                             node.offset, f"add {p.name}: <{p.type.name}>")
        return {name: self.coerce(value, by_name[name], argument.value.offset, node.callee.text)
                for name, (argument, value) in given.items()}

    def coerce(self, v: Value, param: MdlParam, offset: int, callee: str) -> Any:
        """The Python value for ``param`` from ``v``, or a type error at ``offset``."""
        want = param.type
        where = f"argument {param.name!r} of {callee}"
        if v.varying and want.uniform:
            raise self.error(
                f"{where} is uniform: it needs a constant, not a function of the state",
                offset, "pass a constant value")
        if want.is_enum:
            if v.type.name == want.name:
                return v.value
            if v.type.name == "string" and v.value in want.values:
                return v.value
            if v.type.name == "string" or v.type.is_enum:
                raise self.error(f"{where} must be {_a(want.name)}, got {v.value!r}", offset,
                                 self.suggest(str(v.value), want.values)
                                 or f"one of {', '.join(want.values)}")
            raise self.error(f"{where} must be {_a(want.name)}, got {_a(v.type.name)}", offset,
                             f"one of {', '.join(want.values)}")
        if want.name == "float" and v.type.name in ("int", "float"):
            return v.value if v.varying else float(v.value)
        if want.name == v.type.name or v.type.name in _ARRAY_COMPATIBLE.get(want.name, ()):
            return v.value
        fix = None
        if want.name.endswith("[]"):
            fix = self.array_fix(want.name[:-2], v.type.name)
        elif want.name in _VECTOR_WIDTH and v.type.name in ("int", "float") and not v.varying:
            fix = f"write {want.name}({v.value})"
        elif {want.name, v.type.name} == {"float3", "color"}:
            fix = f"convert with {want.name}(...)"
        elif want.name == "int" and v.type.name == "float":
            fix = "write an integer, without a decimal point"
        raise self.error(f"{where} must be {_a(str(want))}, got {_a(v.type.name)}", offset, fix)

    # --- arrays ------------------------------------------------------------------

    @staticmethod
    def array_example(element: str) -> str:
        """An ``element[]`` array value as MDL writes it."""
        if element in _ARRAY_COMPONENTS:
            weight = "color(...)" if element.startswith("color_") else "..."
            return f"df::{element}[](df::{element}(weight: {weight}, component: ...), ...)"
        return f"{element}[](..., ...)"

    def array_fix(self, element: str, got: str) -> str:
        """How to write a ``element[]`` value where ``got`` was given."""
        if got == element:
            return f"wrap it in an array: {self.array_example(element)}"
        return f"write {self.array_example(element)}"

    def array(self, node: ArrayConstructor) -> Value:
        """``T[](e1, e2, ...)``: a tuple of element values, of type ``T[]``."""
        element = node.element
        last = element.parts[-1]
        if last not in _ARRAY_ELEMENTS:
            raise self.error(f"unknown array element type {element.text!r}", element.offset,
                             self.suggest(last, _ARRAY_ELEMENTS)
                             or f"element types: {', '.join(_ARRAY_ELEMENTS)}")
        self.check_module(element)
        label = f"{element.text}[{'' if node.size is None else node.size}]"
        if not node.arguments:
            raise self.error(f"{label}() has no elements", node.close_offset,
                             f"give at least one element: {self.array_example(last)}")
        if node.size is not None and node.size != len(node.arguments):
            count = len(node.arguments)
            raise self.error(
                f"{label}(...) has {count} element{'' if count == 1 else 's'}, not {node.size}",
                node.size_offset,
                f"give {node.size} element{'' if node.size == 1 else 's'}, or write "
                f"{element.text}[](...) to take the size from the elements")
        values = []
        for index, argument in enumerate(node.arguments):
            if argument.name is not None:
                raise self.error(f"array elements are positional; {label}(...) has no "
                                 f"parameter {argument.name!r}", argument.name_offset,
                                 f"remove '{argument.name}:'")
            values.append(self.array_element(self.evaluate(argument.value), last, index,
                                             argument.value.offset, label))
        return Value(tuple(v.value for v in values), _t(last + "[]"),
                     any(v.varying for v in values))

    def array_element(self, v: Value, want: str, index: int, offset: int, label: str) -> Value:
        """Element ``index`` of a ``want[]`` array, converted, or a type error at ``offset``."""
        if want == "float" and v.type.name in ("int", "float"):
            return v if v.varying else Value(float(v.value), _t("float"))
        if v.type.name == want:
            return v
        where = f"element {index + 1} of {label}(...)"
        fix = None
        if want in _VECTOR_WIDTH and v.type.name in ("int", "float") and not v.varying:
            fix = f"write {want}({v.value})"
        elif {want, v.type.name} == {"float3", "color"}:
            fix = f"convert with {want}(...)"
        elif want == "int" and v.type.name == "float":
            fix = "write an integer, without a decimal point"
        elif want in _ARRAY_COMPONENTS and v.type.name in ("bsdf", "edf"):
            weight = "color(...)" if want.startswith("color_") else "..."
            fix = f"wrap it: df::{want}(weight: {weight}, component: ...)"
        elif want in _ARRAY_COMPONENTS and v.type.name in _ARRAY_COMPONENTS:
            fix = f"write df::{v.type.name}[](...) for {v.type.name} elements"
        raise self.error(f"{where} must be {_a(want)}, got {_a(v.type.name)}", offset, fix)

    # --- constructors --------------------------------------------------------------

    def construct(self, node: Call, name: str) -> Value:
        if name in _STRUCT_SIGNATURES:
            cls, params, returns = _STRUCT_SIGNATURES[name]
            kwargs = self.bind(node, params)
            try:
                return Value(cls(**kwargs), returns)
            except Exception as e:
                raise self.error(f"{name}(...): {e}", node.offset) from None
        if name == "texture_2d":
            return self.texture(node)
        if name == "bsdf_measurement":
            return self.measurement(node)
        if name == "light_profile":
            return self.light_profile(node)
        for argument in node.arguments:
            if argument.name is not None:
                raise self.error(f"{name}(...) takes positional arguments only",
                                 argument.name_offset, f"write {name}(...) without argument names")
        values = [(a, self.evaluate(a.value)) for a in node.arguments]
        if name in ("float", "int"):
            only = values[0][1] if len(values) == 1 else None
            if only is None or only.type.name not in ("int", "float") or only.varying:
                raise self.error(f"{name}(...) takes one constant number", node.offset)
            x = values[0][1].value
            return Value(float(x), _t("float")) if name == "float" else Value(int(x), _t("int"))
        if name == "float3x3":
            return self.matrix(node, values)
        return self.vector(node, name, values)

    def matrix(self, node: Call, values: list[tuple[Argument, Value]]) -> Value:
        """MDL's ``float3x3``: ``float3x3(s)`` (``s`` on the diagonal), three ``float3``
        columns, or nine numbers in column-major order; the value is the matrix's rows
        (``M[i][j]``, row-major), uniform."""
        fix = ("write float3x3(1.0), float3x3(float3(...), float3(...), float3(...)) (its "
               "columns) or nine numbers, column by column")
        for argument, v in values:
            if v.varying:
                raise self.error("float3x3(...) takes constants", argument.value.offset,
                                 "matrices here are uniform: pass numbers")
        kinds = [v.type.name for _, v in values]
        if len(values) == 1 and kinds[0] in ("int", "float"):
            x = float(values[0][1].value)
            m = [[x if i == j else 0.0 for j in range(3)] for i in range(3)]
        elif len(values) == 3 and all(k == "float3" for k in kinds):
            cols = [v.value for _, v in values]
            m = [[float(cols[j][i]) for j in range(3)] for i in range(3)]
        elif len(values) == 9 and all(k in ("int", "float") for k in kinds):
            x = [float(v.value) for _, v in values]
            m = [[x[3 * j + i] for j in range(3)] for i in range(3)]
        else:
            raise self.error(f"float3x3(...) cannot take ({', '.join(kinds) or 'nothing'})",
                             node.offset, fix)
        return Value(tuple(tuple(r) for r in m), MdlType("float3x3", True))

    def light_profile(self, node: Call) -> Value:
        """``light_profile("file.ies")``: an IES LM-63 file read relative to ``base_dir``
        (a scene's directory) or as given."""
        from render.df._ies import IesError, read_ies

        params = [MdlParam("name", MdlType("string", True), True, "")]
        kwargs = self.bind(node, params)
        file = kwargs["name"]
        path = Path(file)
        if not path.is_absolute() and self.base_dir is not None:
            near = Path(self.base_dir) / path
            path = near if near.exists() else path
        if not path.exists():
            raise self.error(f"light_profile: no file {file!r}", node.arguments[0].value.offset,
                             "give the IES file's path, relative to the scene file")
        try:
            return Value(read_ies(path), MdlType("light_profile", True))
        except IesError as e:
            raise self.error(str(e), node.arguments[0].value.offset) from None

    def vector(self, node: Call, name: str, values: list[tuple[Argument, Value]]) -> Value:
        width = _VECTOR_WIDTH[name]
        if len(values) == 1 and values[0][1].type.name in _VECTOR_WIDTH:
            v = values[0][1]
            if _VECTOR_WIDTH[v.type.name] != width:
                raise self.error(f"cannot make {_a(name)} from {_a(v.type.name)}",
                                 values[0][0].value.offset)
            return Value(v.value, _t(name), v.varying)
        if len(values) not in (1, width):
            raise self.error(f"{name}(...) takes 1 or {width} numbers, got {len(values)}",
                             node.offset, f"write {name}(x) or {name}({', '.join('xyz'[:width])})")
        for argument, v in values:
            if v.type.name not in ("int", "float"):
                raise self.error(f"{name}(...) components must be numbers, got {_a(v.type.name)}",
                                 argument.value.offset)
        if not any(v.varying for _, v in values):
            components = [float(v.value) for _, v in values]
            if len(components) == 1:
                components = components * width
            return Value(tuple(components), _t(name))
        parts = [v.value for _, v in values]

        def function(state):
            columns = [evaluate(p, state, "float", name) for p in parts]
            if len(columns) == 1:
                columns = columns * width
            return np.stack(columns, axis=1)

        return Value(Varying(function, name, {"components": parts}), _t(name), True)

    def texture(self, node: Call) -> Value:
        params = [MdlParam("name", MdlType("string", True), False, ""),
                  MdlParam("gamma", MdlType("gamma_mode", True, _ENUMS["gamma_srgb"].values), False,
                           "gamma_linear")]
        kwargs = self.bind(node, params)
        file = kwargs.get("name", "")
        if not file:
            return Value(None, MdlType("texture_2d", True))  # texture_2d(): an invalid texture
        gamma = {"gamma_default": "default", "gamma_linear": "linear", "gamma_srgb": "srgb"}[
            kwargs.get("gamma", "gamma_linear")]
        try:
            return Value(load_texture(file, gamma, self.base_dir), MdlType("texture_2d", True))
        except ResourceError as e:
            raise self.error(e.message, node.arguments[0].value.offset, e.hint) from None
        except Exception as e:  # an unreadable file
            raise self.error(f"cannot read texture {file!r}: {e}",
                             node.arguments[0].value.offset) from None

    def measurement(self, node: Call) -> Value:
        """``bsdf_measurement("file.mbsdf")``: an MBSDF file read relative to ``base_dir``
        (a scene's directory) or as given."""
        from render.df._mbsdf import MbsdfError, read_mbsdf

        params = [MdlParam("name", MdlType("string", True), True, "")]
        kwargs = self.bind(node, params)
        file = kwargs["name"]
        path = Path(file)
        if not path.is_absolute() and self.base_dir is not None:
            near = Path(self.base_dir) / path
            path = near if near.exists() else path
        if not path.exists():
            raise self.error(f"bsdf_measurement: no file {file!r}", node.arguments[0].value.offset,
                             "give the MBSDF file's path, relative to the scene file")
        try:
            return Value(read_mbsdf(path), MdlType("bsdf_measurement", True))
        except MbsdfError as e:
            raise self.error(str(e), node.arguments[0].value.offset) from None


def evaluate_expression(text: str, *, base_dir=None, profile_dirs=None, texture_dirs=None) -> Value:
    """Parse and evaluate any expression (a material, a color, a function call...).

    Parameters
    ----------
    text : str
    base_dir : path, optional
        Directory that relative texture file names are read from first (a scene file's
        directory).
    profile_dirs, texture_dirs : path or sequence of paths, optional
        Searched before ``profiles/`` and ``gallery/textures/``.

    Returns
    -------
    Value

    Raises
    ------
    MaterialExprError

    Examples
    --------
    >>> evaluate_expression("color(0.6, 0.4, 0.0)").value
    (0.6, 0.4, 0.0)
    >>> round(evaluate_expression("ornament_2::ornament_2_length").value, 5) > 1.0
    True
    """
    if not isinstance(text, str):
        raise MaterialExprError(
            f"a material expression must be a string, got {type(text).__name__}", 1)
    node = parse(text)
    with search_paths(profile_dirs=profile_dirs, texture_dirs=texture_dirs):
        return _Evaluator(text, base_dir).evaluate(node)


def parse_material(text: str, *, base_dir=None, profile_dirs=None, texture_dirs=None) -> material:
    """Build the material an MDL call expression describes (``glossy(tint: color(0.6))``).

    Parameters
    ----------
    text : str
        An expression whose value is a material (usually a call of a Handbook material).
    base_dir, profile_dirs, texture_dirs
        As :func:`evaluate_expression`.

    Returns
    -------
    material

    Raises
    ------
    MaterialExprError
        Syntax, unknown names (with suggestions), argument and type errors, and errors
        raised by the material functions, each with line and column.

    Examples
    --------
    >>> parse_material("triangle(height: 0.25)").geometry.displacement.name
    'triangle'
    >>> parse_material("glosy()")  # doctest: +ELLIPSIS
    Traceback (most recent call last):
    ...
    render.expr.MaterialExprError: 1:1: unknown function or material 'glosy' (did you mean ...)
    """
    value = evaluate_expression(text, base_dir=base_dir, profile_dirs=profile_dirs,
                                texture_dirs=texture_dirs)
    if value.type.name != "material":
        raise MaterialExprError(f"the expression is {_a(value.type.name)}, not a material", 1,
                                "write a material call such as glossy(tint: color(0.6, 0.4, 0.0))")
    return value.value
