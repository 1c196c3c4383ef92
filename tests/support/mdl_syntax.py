"""Pure-Python syntax checker for NVIDIA MDL (Material Definition Language) 1.x.

There is no MDL compiler on the test machines, so the tests check the MDL text
emitted by :mod:`pwc` with this module.  It tokenizes and parses the part of
MDL used by function and material modules (the grammar follows the MDL 1.x
specification and the MDL SDK parser), runs a few cheap semantic checks that
catch real emitter bugs, and extracts module-level constants as Python data.

Semantic checks
---------------
* Every unqualified identifier is declared: a parameter, local or loop
  variable, a size name (``float[<N>]``), a module-level declaration (also
  later in the file), a ``using``-imported name, or a builtin type used as a
  constructor.
* Every qualified name (``math::cos``, ``pw_curve::pw_point``) belongs to an
  imported module, and names of the standard modules ``math``, ``state``,
  ``debug`` and ``tex`` exist there.
* No duplicate declarations; no global variables; functions with a block body
  contain a ``return``; ``break`` only in loops or ``switch``, ``continue``
  only in loops; the element count of array constants matches their size;
  vector constructors get the right number of values in constants.

Expression types, overload resolution and control flow are not checked.  Not
supported: local ``struct``/``enum``/``typedef`` declarations, ``cast<T>(x)``,
namespace aliases (``using a = ...``), variants ``f(*) = ...`` and the quoted
Unicode identifiers of MDL 1.8.

Examples
--------
>>> m = parse_module("mdl 1.6; const float2 p = float2(0.5, -1.0);")
>>> m.constants["p"].value
(0.5, -1.0)
"""

from __future__ import annotations

import math
import operator
import re
from dataclasses import dataclass, field

__all__ = [
    "Call",
    "Const",
    "EnumRef",
    "Function",
    "MdlSyntaxError",
    "Module",
    "Param",
    "parse_module",
]

_KEYWORDS = frozenset(
    "annotation auto break case cast const continue default do else enum export false for if import"
    " in let mdl module return struct switch true typedef uniform using varying while".split()
)
_SCALAR_TYPES = {"bool": bool, "int": int, "float": float, "double": float}
_BUILTIN_TYPES = frozenset(
    [*_SCALAR_TYPES, "color", "string", "bsdf", "edf", "vdf", "hair_bsdf", "light_profile"]
    + ["bsdf_measurement", "intensity_mode", "texture_2d", "texture_3d", "texture_cube"]
    + ["texture_ptex", "material", "material_surface", "material_emission"]
    + ["material_volume", "material_geometry"]
    + [f"{base}{n}" for base in _SCALAR_TYPES for n in "234"]
    + [f"{base}{c}x{r}" for base in ("float", "double") for c in "234" for r in "234"]
)
_BUILTIN_VALUES = frozenset(["intensity_radiant_exitance", "intensity_power"])

# Exported names of the standard modules whose members are checked (MDL 1.7).
_STDLIB_EXPORTS = {
    module: frozenset(names.split())
    for module, names in {
        "math": "PI TWO_PI HALF_PI abs acos all any asin atan atan2 average ceil clamp cos"
        " cross degrees distance dot eval_at_wavelength exp exp2 floor fmod frac isnan"
        " isfinite length lerp log log2 log10 luminance max max_value max_value_wavelength"
        " min min_value min_value_wavelength modf normalize pow radians round rsqrt saturate"
        " sign sin sincos smoothstep sqrt step tan transpose blackbody emission_color cosh"
        " sinh tanh float_bits_to_int int_bits_to_float DX DY",
        "state": "position normal geometry_normal motion texture_space_max texture_coordinate"
        " texture_tangent_u texture_tangent_v tangent_space geometry_tangent_u"
        " geometry_tangent_v direction animation_time wavelength_base coordinate_space"
        " coordinate_internal coordinate_object coordinate_world transform transform_point"
        " transform_vector transform_normal transform_scale rounded_corner_normal"
        " meters_per_scene_unit scene_units_per_meter object_id wavelength_min wavelength_max",
        "debug": "breakpoint assert print",
        "tex": "gamma_mode gamma_default gamma_linear gamma_srgb wrap_mode wrap_clamp"
        " wrap_repeat wrap_mirrored_repeat wrap_clip width height depth lookup_float"
        " lookup_float2 lookup_float3 lookup_float4 lookup_color texel_float texel_float2"
        " texel_float3 texel_float4 texel_color texture_isvalid width_offset height_offset"
        " depth_offset first_frame last_frame grid_to_object_space",
    }.items()
}
_MATH_CONSTANTS = {"math::PI": math.pi, "math::TWO_PI": 2 * math.pi, "math::HALF_PI": math.pi / 2}

# ``]]`` is not a token: it closes annotations but also nested indexing ``a[b[i]]``.
_OPERATORS = sorted(
    ">>>= <<= >>= >>> :: [[ << >> <= >= == != && || ++ -- += -= *= /= %= &= |= ^= .."
    " ( ) [ ] { } < > + - * / % = ! ~ ? : , ; . & | ^".split(),
    key=len,
    reverse=True,
)
_TOKEN_RE = re.compile(
    r"(?P<space>\s+)|(?P<comment>//[^\n]*)|(?P<block>/\*)"
    r"|(?P<number>0[xX][0-9a-fA-F]+|(?:\d+\.\d*|\.\d+)(?:[eE][+-]?\d+)?[fFdD]?"
    r"|\d+[eE][+-]?\d+[fFdD]?|\d+)"
    r'|(?P<string>"(?:[^"\\\n]|\\.)*")|(?P<ident>[A-Za-z][A-Za-z0-9_]*)'
    r"|(?P<op>" + "|".join(re.escape(op) for op in _OPERATORS) + ")",
    re.ASCII,
)
_ESCAPES = {"a": "\a", "b": "\b", "f": "\f", "n": "\n", "r": "\r", "t": "\t", "v": "\v"}
_ASSIGN_OPS = frozenset("= += -= *= /= %= &= |= ^= <<= >>= >>>=".split())
_BINARY_LEVELS = (  # lowest precedence first
    ("||",),
    ("&&",),
    ("|",),
    ("^",),
    ("&",),
    ("==", "!="),
    ("<", "<=", ">", ">="),
    ("<<", ">>", ">>>"),
    ("+", "-"),
    ("*", "/", "%"),
)
_ARITHMETIC = {"+": operator.add, "-": operator.sub, "*": operator.mul, "/": operator.truediv}
_LVALUE_KINDS = ("name", "index", "member")


class MdlSyntaxError(Exception):
    """An MDL syntax or semantic error at a source position.

    Parameters
    ----------
    message : str
        What is wrong.
    line, col : int
        1-based position of the offending token.
    filename : str, optional
        Name used in the formatted message.
    """

    def __init__(self, message, line, col, filename="<mdl>"):
        super().__init__(f"{filename}:{line}:{col}: {message}")
        self.message, self.line, self.col, self.filename = message, line, col, filename


@dataclass(frozen=True)
class EnumRef:
    """A reference to a named value, normally an enum value such as ``pw_curve::segment``."""

    name: str


@dataclass
class Call:
    """A constant call of a struct constructor or function.

    Attributes
    ----------
    name : str
        Callee as written, e.g. ``"pw_curve::pw_point"``.
    args : list
        Evaluated positional arguments.
    kwargs : dict
        Evaluated named arguments.
    comment : str or None
        Comment following the call's ``(`` on the same line; ignored by ``==``.
    """

    name: str
    args: list
    kwargs: dict = field(default_factory=dict)
    comment: str | None = field(default=None, compare=False)


@dataclass
class Const:
    """A constant: type without array suffix, array size (None if not an array), value.

    ``value`` is Python data (numbers, tuples for vectors/matrices/colors, lists for
    arrays, :class:`Call`, :class:`EnumRef`, str, bool) or None when the initializer is
    not plain constant data.  ``comment`` is the comment after the ``(`` of a
    constructor-style initializer such as ``segments ( // :relative``.
    """

    type: str
    array_size: int | None
    value: object
    comment: str | None = None


@dataclass
class Param:
    """A parameter; ``default`` is the source text of its default value or None."""

    type: str
    name: str
    default: str | None = None
    qualifier: str | None = None


@dataclass
class Function:
    """Signature of a function or material; later overloads are kept in ``overloads``."""

    name: str
    return_type: str
    params: list[Param]
    qualifier: str | None = None
    has_body: bool = True
    line: int = 0
    overloads: list[Function] = field(default_factory=list)

    @property
    def is_material(self):
        """bool: True for a material definition."""
        return self.return_type == "material"


@dataclass
class Module:
    """The declarations of a parsed MDL module.

    Attributes
    ----------
    filename : str
        Name given to :func:`parse_module`.
    version : str or None
        MDL version of the header (``"1.6"``); None for an empty text.
    imports : list of str
        Import paths as written; ``using m import a, b;`` gives ``m::a`` and ``m::b``.
    exports : set of str
        Names declared with ``export`` (enum values of exported enums included).
    enums : dict
        Enum name -> list of (value name, int value).
    structs : dict
        Struct name -> list of (type, field name, default source text or None).
    functions : dict
        Function or material name -> :class:`Function`.
    constants : dict
        Module-level constant name -> :class:`Const`.
    """

    filename: str = "<mdl>"
    version: str | None = None
    imports: list[str] = field(default_factory=list)
    exports: set[str] = field(default_factory=set)
    enums: dict[str, list[tuple[str, int]]] = field(default_factory=dict)
    structs: dict[str, list[tuple[str, str, str | None]]] = field(default_factory=dict)
    functions: dict[str, Function] = field(default_factory=dict)
    constants: dict[str, Const] = field(default_factory=dict)


@dataclass
class _Token:
    kind: str  # 'ident', 'int', 'float', 'string', 'op' or 'eof'
    text: str
    value: object
    line: int
    col: int
    start: int
    end: int
    comment: str | None = None  # comment following the token on the same line


@dataclass
class _Type:
    qualifier: str | None
    name: str
    array: str | None = None  # text between the brackets, None if not an array
    size: int | None = None  # constant array size

    def __str__(self):
        return self.name if self.array is None else f"{self.name}[{self.array}]"


@dataclass
class _Expr:
    # kind: 'literal', 'name', 'array_type' (``T[]``), 'unary', 'binary', 'call', 'index',
    # 'member' or 'other'.  A call's ``value`` is the callee, its ``args`` (label, expr) pairs.
    kind: str
    tok: _Token
    value: object = None
    args: list = field(default_factory=list)


class _NotConstant(Exception):
    """Raised while evaluating an expression that is not plain constant data."""


def parse_module(text, filename="<mdl>"):
    """Parse and check an MDL module.

    Parameters
    ----------
    text : str
        MDL source of one module.
    filename : str, optional
        Name used in error messages.

    Returns
    -------
    Module
        The module's declarations and constant data.

    Raises
    ------
    MdlSyntaxError
        On the first syntax or semantic error.
    """
    parser = _Parser(text, filename)
    try:
        return parser.parse()
    except RecursionError:
        tok = parser.peek()
        raise MdlSyntaxError("nesting too deep", tok.line, tok.col, filename) from None


def _tokenize(text, filename):
    """Split MDL source into tokens, attaching same-line comments to the preceding token."""
    tokens, pos, line, line_start = [], 0, 1, 0

    def fail(message, at):
        raise MdlSyntaxError(message, line, at - line_start + 1, filename)

    while pos < len(text):
        match = _TOKEN_RE.match(text, pos)
        if match is None:
            if text[pos] == '"':
                fail("unterminated string literal", pos)
            fail(f"unexpected character {text[pos]!r}", pos)
        kind, lexeme, end = match.lastgroup, match.group(), match.end()
        if kind == "block":  # block comments nest
            depth = 1
            while depth:
                ends = [i for i in (text.find("/*", end), text.find("*/", end)) if i >= 0]
                if not ends:
                    fail("unterminated block comment", pos)
                depth += 1 if text.startswith("/*", min(ends)) else -1
                end = min(ends) + 2
            lexeme = text[pos:end]
        if kind in ("comment", "block"):
            if tokens and tokens[-1].line == line and tokens[-1].comment is None:
                body = lexeme[2:] if kind == "comment" else lexeme[2:-2]
                tokens[-1].comment = body.strip()
        elif kind != "space":
            value = _literal_value(kind, lexeme, text, end, lambda msg, at=pos: fail(msg, at))
            if kind == "number":
                kind = "float" if isinstance(value, float) else "int"
            tokens.append(_Token(kind, lexeme, value, line, pos - line_start + 1, pos, end))
        if "\n" in lexeme:
            line += lexeme.count("\n")
            line_start = pos + lexeme.rindex("\n") + 1
        pos = end
    last = tokens[-1] if tokens else _Token("eof", "", None, 1, 1, 0, 0)
    end_col = last.col + len(last.text)
    tokens.append(_Token("eof", "", None, last.line, end_col, len(text), len(text)))
    return tokens


def _literal_value(kind, lexeme, text, end, fail):
    """Return the Python value of a string or number token (None for other kinds)."""
    if kind == "string":
        return re.sub(r"\\(.)", lambda m: _ESCAPES.get(m.group(1), m.group(1)), lexeme[1:-1])
    if kind != "number":
        return None
    if end < len(text) and (text[end].isalnum() or text[end] in "_."):
        rest = re.match(r"[\w.]*", text[end:]).group()
        fail(f"malformed number '{lexeme}{rest}'")
    if re.fullmatch(r"0[xX][0-9a-fA-F]+|\d+", lexeme):
        if re.fullmatch(r"0\d*[89]\d*", lexeme):
            fail(f"invalid octal literal '{lexeme}'")
        value = int(lexeme, 16 if lexeme[:2] in ("0x", "0X") else 8 if lexeme[0] == "0" else 10)
        if value > 0xFFFFFFFF:
            fail(f"integer literal '{lexeme}' out of range")
        return value
    value = float(lexeme.rstrip("fFdD"))
    if math.isinf(value):
        fail(f"floating-point literal '{lexeme}' out of range")
    return value


def _is_number(value):
    return isinstance(value, (int, float)) and not isinstance(value, bool)


def _wrap_int(value):
    """Wrap a Python int to MDL's 32-bit two's complement ``int``."""
    return (value + 2**31) % 2**32 - 2**31


def _arithmetic(op, a, b):
    """Apply ``+ - * / %`` with MDL semantics; integer division by zero raises ZeroDivisionError."""
    if not (_is_number(a) and _is_number(b)):
        raise _NotConstant
    if isinstance(a, int) and isinstance(b, int):
        if op in ("/", "%"):
            quotient = abs(a) // abs(b)  # C semantics: truncate towards zero
            quotient = quotient if (a < 0) == (b < 0) else -quotient
            return _wrap_int(quotient if op == "/" else a - b * quotient)
        return _wrap_int(_ARITHMETIC[op](a, b))
    if op == "%":
        raise _NotConstant
    a, b = float(a), float(b)
    if op == "/" and b == 0.0:  # IEEE 754 instead of Python's ZeroDivisionError
        if a == 0.0 or math.isnan(a):
            return math.nan
        return math.copysign(math.inf, a) * math.copysign(1.0, b)
    return _ARITHMETIC[op](a, b)


def _type_shape(name):
    """Return (element type, element count) of a vector, matrix or color type, else None."""
    if name == "color":
        return float, 3
    match = re.fullmatch(r"(bool|int|float|double)([234])(?:x([234]))?", name)
    return match and (_SCALAR_TYPES[match.group(1)], int(match.group(2)) * int(match.group(3) or 1))


def _construct(name, args):
    """Evaluate a builtin scalar, vector, matrix or color constructor; None for a wrong arity."""
    if not all(isinstance(arg, (int, float, tuple)) for arg in args):
        raise _NotConstant
    if name in _SCALAR_TYPES:
        if len(args) != 1 or isinstance(args[0], tuple):
            raise _NotConstant
        if name == "int" and not math.isfinite(args[0]):
            raise _NotConstant
        return _wrap_int(int(args[0])) if name == "int" else _SCALAR_TYPES[name](args[0])
    convert, size = _type_shape(name)
    flat = [v for arg in args for v in (arg if isinstance(arg, tuple) else [arg])]
    if len(flat) == 1 and "x" in name:  # a diagonal matrix; floatCxR is stored column by column
        rows = int(name[-1])
        flat = [flat[0] if i // rows == i % rows else 0 for i in range(size)]
    elif len(flat) == 1:
        flat *= size
    return tuple(convert(v) for v in flat) if len(flat) == size else None


class _Parser:
    """Recursive-descent parser with scope tracking; call :meth:`parse` once."""

    def __init__(self, text, filename):
        self.text, self.filename = text, filename
        self.toks = _tokenize(text, filename)
        self.i = 0
        self.version = (1, 0)
        self.module = Module(filename=filename)
        self.globals = {}  # name -> (kind, line) of module-level declarations
        self.scopes = []  # stack of sets of local names
        self.pending = []  # (token, name, what) of unqualified names, resolved at the end
        self.star_modules = set()  # modules whose members may be used qualified
        self.imported_names = set()  # individually imported qualified names
        self.using_names = set()  # names imported unqualified by 'using'
        self.enum_values = {}  # module enum value -> int
        self.loop_depth = self.break_depth = self.returns = 0

    # -- tokens --------------------------------------------------------------------------------
    def peek(self, k=0):
        return self.toks[min(self.i + k, len(self.toks) - 1)]

    def next(self):
        tok = self.peek()
        self.i = min(self.i + 1, len(self.toks) - 1)
        return tok

    def at(self, *texts, k=0):
        return self.peek(k).text in texts

    def accept(self, text):
        return self.next() if self.at(text) else None

    def error(self, message, tok=None):
        tok = tok or self.peek()
        raise MdlSyntaxError(message, tok.line, tok.col, self.filename)

    def found(self):
        tok = self.peek()
        return "end of input" if tok.kind == "eof" else f"'{tok.text}'"

    def expect(self, text, context=""):
        if self.at(text):
            return self.next()
        tok, prev = self.peek(), self.toks[self.i - 1] if self.i else self.peek()
        if prev.line != tok.line:  # report a missing ';' etc. right after the previous token
            message = f"expected '{text}'{context}, found {self.found()} on line {tok.line}"
            raise MdlSyntaxError(message, prev.line, prev.col + len(prev.text), self.filename)
        self.error(f"expected '{text}'{context}, found {self.found()}")

    def is_name(self, k=0):
        return self.peek(k).kind == "ident" and self.peek(k).text not in _KEYWORDS

    def ident(self, what="identifier"):
        if not self.is_name():
            self.error(f"expected {what}, found {self.found()}")
        return self.next()

    def decl_name(self):
        tok = self.ident("name")
        if tok.text in _BUILTIN_TYPES:
            self.error(f"type name '{tok.text}' cannot be used as a name", tok)
        return tok

    def source(self, start):
        """Source text from token ``start`` up to the last consumed token."""
        return self.text[start.start : self.toks[self.i - 1].end]

    # -- names and scopes ----------------------------------------------------------------------
    def scoped_name(self):
        first = self.peek()
        name = "::" if self.accept("::") else ""
        name += self.ident().text
        while self.at("::") and self.is_name(1):
            name += self.next().text + self.next().text
        return name, first

    def use_name(self, name, tok, what):
        """Check a used name; ``what`` names the error for an unknown unqualified name."""
        if name.count("::") == 1 and name.startswith("::"):  # ``::x`` is a name of this module
            name = name[2:]
        if "::" not in name:
            if name not in _BUILTIN_TYPES and not any(name in scope for scope in self.scopes):
                self.pending.append((tok, name, what))
            return
        module, _, member = name.lstrip(":").rpartition("::")
        if module not in self.star_modules and f"{module}::{member}" not in self.imported_names:
            self.error(f"'{name}' is used but module '{module}' is not imported", tok)
        if member not in _STDLIB_EXPORTS.get(module, {member}):
            self.error(f"'{member}' is not exported by standard module '{module}'", tok)

    def declare_local(self, tok):
        if tok.text in self.scopes[-1]:
            self.error(f"redeclaration of '{tok.text}'", tok)
        self.scopes[-1].add(tok.text)

    def declare_global(self, tok, kind, exported):
        if tok.text in self.globals:
            first, line = self.globals[tok.text]
            self.error(
                f"duplicate declaration of '{tok.text}' "
                f"(already declared as {first} on line {line})",
                tok,
            )
        self.globals[tok.text] = (kind, tok.line)
        if exported:
            self.module.exports.add(tok.text)

    # -- module level --------------------------------------------------------------------------
    def parse(self):
        if self.peek().kind == "eof":
            return self.module
        if not self.accept("mdl"):
            self.error("missing 'mdl 1.x;' version header")
        tok = self.peek()
        if tok.kind != "float" or not re.fullmatch(r"\d+\.\d+", tok.text):
            self.error("expected an MDL version such as 1.6 after 'mdl'")
        self.version = tuple(int(part) for part in tok.text.split("."))
        if self.version[0] != 1:
            self.error(f"unsupported MDL version {tok.text}")
        self.module.version = self.next().text
        self.expect(";", " after the MDL version")
        while self.at("import", "using") or (self.at("export") and self.at("using", k=1)):
            self.parse_import()
        if self.accept("module"):
            self.annotations()
            self.expect(";")
        while self.peek().kind != "eof":
            self.global_declaration()
        if "*" not in self.using_names:
            known = self.globals.keys() | self.using_names | _BUILTIN_VALUES
            for tok, name, what in self.pending:
                if name not in known:
                    self.error(f"{what} '{name}'", tok)
        return self.module

    def import_path(self):
        """Parse a qualified import path; return (text as written, components without dots)."""
        start = self.peek()
        if not self.accept("::"):
            while self.at(".", ".."):
                self.next()
                self.expect("::")
        parts = [self.ident("module name").text]
        while parts[-1] != "*" and self.accept("::"):
            parts.append(self.next().text if self.at("*") else self.ident().text)
        return self.source(start), parts

    def parse_import(self):
        if self.accept("import"):
            while True:
                text, parts = self.import_path()
                self.module.imports.append(text)
                if parts[-1] == "*":
                    self.star_modules.add("::".join(parts[:-1]))
                else:
                    self.imported_names.add("::".join(parts))
                if not self.accept(","):
                    break
        else:
            self.accept("export")
            self.next()  # 'using'
            text, parts = self.import_path()
            self.expect("import", " after the module name of 'using'")
            self.star_modules.add("::".join(parts))
            names = [self.next().text if self.at("*") else self.ident().text]
            while names != ["*"] and self.accept(","):
                names.append(self.ident().text)
            self.using_names.update(names)
            self.module.imports.extend(f"{text}::{name}" for name in names)
        self.expect(";", " after the import declaration")

    def global_declaration(self):
        if self.at("import", "using"):
            self.error("import declarations must precede all other declarations")
        if self.at("}"):
            self.error("unmatched '}'")
        exported = bool(self.accept("export"))
        if self.at("const"):
            self.constant_declaration(exported)
        elif self.at("struct"):
            self.struct_declaration(exported)
        elif self.at("enum"):
            self.enum_declaration(exported)
        elif self.accept("typedef"):
            self.parse_type()
            self.declare_global(self.decl_name(), "typedef", exported)
            self.expect(";", " after the typedef")
        elif self.accept("annotation"):
            name = self.decl_name()
            self.scopes.append(set())
            self.parameter_list()
            self.scopes.pop()
            self.annotations()
            self.expect(";", " after the annotation declaration")
            self.declare_global(name, "annotation", exported)
        else:
            self.function_declaration(exported)

    def parse_type(self, size_scope=None):
        """Parse ``[uniform|varying] name [array]``; size names ``<N>`` go into ``size_scope``."""
        qualifier = self.next().text if self.at("uniform", "varying") else None
        if self.at("auto"):
            return _Type(qualifier, self.next().text)
        name, tok = self.scoped_name()
        self.use_name(name, tok, "unknown type")
        typ = _Type(qualifier, name)
        if not self.accept("["):
            return typ
        if self.at("]"):
            typ.array = ""
        elif self.accept("<"):
            size_tok = self.ident("array size name")
            if size_scope is None:
                self.error("size-deferred arrays '[<N>]' are only allowed for parameters", size_tok)
            size_scope.add(size_tok.text)
            self.expect(">")
            typ.array = f"<{size_tok.text}>"
        else:
            start = self.peek()
            size = self.try_evaluate(self.assignment(allow_assign=False))
            typ.array = self.source(start)
            typ.size = size if _is_number(size) and isinstance(size, int) else None
        self.expect("]", " to close the array type")
        return typ

    def annotations(self):
        """Parse (and discard) an optional annotation block ``[[ a(...), b::c(...) ]]``."""
        if not self.accept("[["):
            return
        while True:
            name, tok = self.scoped_name()
            self.use_name(name, tok, "unknown annotation")
            self.call(_Expr("name", tok, name))
            if not self.accept(","):
                break
        self.expect("]", " to close the annotation block")
        self.expect("]", " to close the annotation block")

    def constant_declaration(self, exported, local=False):
        self.next()  # 'const'
        typ = self.parse_type()
        while True:
            name = self.decl_name()
            if self.at("("):  # constructor-style: T name(args); for arrays T[n] name(elements)
                callee = "name" if typ.array is None else "array_type"
                expr = self.call(_Expr(callee, name, typ.name))
            else:
                self.expect("=", f" or '(' after the constant name '{name.text}'")
                expr = self.assignment(allow_assign=False)
            value = self.try_evaluate(expr)
            self.annotations()
            size = typ.size
            if isinstance(value, list) and typ.array is not None:
                if size is not None and size != len(value):
                    self.error(
                        f"array constant '{name.text}' is declared with {size} elements "
                        f"but initialized with {len(value)}",
                        name,
                    )
                size = len(value)
            if local:
                self.declare_local(name)
            else:
                self.declare_global(name, "constant", exported)
                constructor_style = expr.kind == "call" and expr.value.tok is name
                comment = expr.tok.comment if constructor_style else None
                self.module.constants[name.text] = Const(typ.name, size, value, comment)
            if not self.accept(","):
                break
        self.expect(";", " after the constant declaration")

    def struct_declaration(self, exported):
        self.next()  # 'struct'
        name = self.decl_name()
        self.annotations()
        self.expect("{", " to open the struct")
        fields = []
        while not self.accept("}"):
            typ, field_tok, default = self.parse_type(), self.decl_name(), None
            if any(field_tok.text == f[1] for f in fields):
                self.error(f"duplicate field '{field_tok.text}'", field_tok)
            if self.accept("="):
                start = self.peek()
                self.expression()
                default = self.source(start)
            self.annotations()
            self.expect(";", " after the struct field")
            fields.append((str(typ), field_tok.text, default))
        self.expect(";", " after the struct declaration")
        self.declare_global(name, "struct", exported)
        self.module.structs[name.text] = fields

    def enum_declaration(self, exported):
        self.next()  # 'enum'
        name = self.decl_name()
        self.annotations()
        self.expect("{", " to open the enum")
        values, next_value = [], 0
        while True:
            value_tok = self.decl_name()
            if self.accept("="):
                value = self.try_evaluate(self.assignment())
                value = self.enum_values.get(value.name) if isinstance(value, EnumRef) else value
                if not (_is_number(value) and isinstance(value, int)):
                    self.error(f"enum value '{value_tok.text}' needs a constant integer", value_tok)
                next_value = value
            self.annotations()
            self.declare_global(value_tok, "enum value", exported)
            values.append((value_tok.text, next_value))
            self.enum_values[value_tok.text] = next_value
            next_value += 1
            if not self.accept(",") or (self.at("}") and self.version >= (1, 8)):
                break
        self.expect("}", " to close the enum")
        self.expect(";", " after the enum declaration")
        self.declare_global(name, "enum", exported)
        self.module.enums[name.text] = values

    def function_declaration(self, exported):
        ret = self.parse_type()
        self.annotations()
        name = self.decl_name()
        if self.at("=", ";", ","):
            self.error(f"global variable '{name.text}' is not allowed (missing 'const'?)", name)
        self.scopes.append(set())
        params = self.parameter_list()
        qualifier = self.next().text if self.at("uniform", "varying") else None
        self.annotations()
        self.returns, has_body = 0, True
        if self.accept("="):  # materials and expression-bodied functions
            self.expression()
            self.expect(";", " after the function body")
        elif self.at("{"):
            self.block()
            if not self.returns:
                self.error(f"function '{name.text}' has no return statement", name)
        else:
            self.expect(";", f" or a body after the parameters of '{name.text}'")
            has_body = False
        self.scopes.pop()
        func = Function(name.text, str(ret), params, qualifier, has_body, name.line)
        first = self.module.functions.get(name.text)
        if first is None:
            self.declare_global(name, "function", exported)
            self.module.functions[name.text] = func
            return
        signature = [p.type for p in params]
        for other in [first, *first.overloads]:
            if [p.type for p in other.params] == signature and other.has_body and has_body:
                self.error(f"duplicate definition of function '{name.text}'", name)
        first.overloads.append(func)

    def parameter_list(self):
        self.expect("(", " to open the parameter list")
        params = []
        while not self.at(")"):
            typ, name, default = self.parse_type(size_scope=self.scopes[-1]), self.decl_name(), None
            if self.accept("="):
                start = self.peek()
                self.assignment()
                default = self.source(start)
            self.annotations()
            self.declare_local(name)
            params.append(Param(str(typ), name.text, default, typ.qualifier))
            if not self.accept(","):
                break
            if self.at(")"):
                self.error("expected a parameter after ','")
        self.expect(")", " to close the parameter list")
        return params

    # -- statements ----------------------------------------------------------------------------
    def block(self):
        opening = self.expect("{")
        self.scopes.append(set())
        while not self.accept("}"):
            if self.peek().kind == "eof":
                self.error(f"missing '}}' for the block opened on line {opening.line}")
            self.statement()
        self.scopes.pop()

    def looks_like_declaration(self):
        """Lookahead: a type (name, optional ``[...]``) followed by a name starts a declaration."""
        if self.at("uniform", "varying", "auto"):
            return True
        k = 1 if self.at("::") else 0
        if not self.is_name(k):
            return False
        k += 1
        while self.at("::", k=k) and self.is_name(k + 1):
            k += 2
        depth = 0
        while self.at("[", k=k) or depth:
            if self.peek(k).kind == "eof":
                return False
            depth += self.at("[", k=k) - self.at("]", k=k)
            k += 1
        return self.is_name(k)

    def statement(self):
        tok = self.peek()
        word = tok.text if tok.kind in ("ident", "op") else None
        if word == "{":
            self.block()
        elif word in ("if", "while", "switch", "do"):
            self.next()
            if word == "do":
                self.loop_body()
                self.expect("while", " after the 'do' body")
            self.expect("(", f" after '{'while' if word == 'do' else word}'")
            self.expression()
            self.expect(")", " to close the condition")
            if word == "do":
                self.expect(";", " after 'do ... while (...)'")
            elif word == "while":
                self.loop_body()
            elif word == "switch":
                self.switch_body()
            else:
                self.statement()
                if self.accept("else"):
                    self.statement()
        elif word == "for":
            self.for_statement()
        elif word in ("break", "continue"):
            self.next()
            if not (self.break_depth if word == "break" else self.loop_depth):
                self.error(f"'{word}' outside of a loop", tok)
            self.expect(";", f" after '{word}'")
        elif word == "return":
            self.next()
            self.expression()
            self.returns += 1
            self.expect(";", " after the return statement")
        elif word == "const":
            self.constant_declaration(exported=False, local=True)
        elif word in ("struct", "enum", "typedef"):
            self.error(f"local '{word}' declarations are not supported")
        elif not self.accept(";"):
            if self.looks_like_declaration():
                self.var_declaration()
            else:
                self.expression()
                self.expect(";", " after the expression")

    def loop_body(self):
        self.loop_depth += 1
        self.break_depth += 1
        self.statement()
        self.loop_depth -= 1
        self.break_depth -= 1

    def switch_body(self):
        self.expect("{", " to open the switch body")
        self.break_depth += 1
        self.scopes.append(set())
        while not self.accept("}"):
            if self.accept("case"):
                self.expression()
            elif not self.accept("default"):
                self.error(f"expected 'case' or 'default' in the switch, found {self.found()}")
            self.expect(":")
            while not self.at("case", "default", "}") and self.peek().kind != "eof":
                self.statement()
        self.scopes.pop()
        self.break_depth -= 1

    def for_statement(self):
        self.next()  # 'for'
        self.expect("(", " after 'for'")
        self.scopes.append(set())
        if self.looks_like_declaration():
            self.var_declaration()
        elif not self.accept(";"):
            self.expression()
            self.expect(";", " after the loop initializer")
        if not self.at(";"):
            self.expression()
        self.expect(";", " after the loop condition")
        if not self.at(")"):
            self.expression()
        self.expect(")", " to close the 'for' header")
        self.loop_body()
        self.scopes.pop()

    def var_declaration(self):
        typ = self.parse_type()
        while True:
            name = self.decl_name()
            if self.at("("):
                self.call(_Expr("name", name, typ.name))
            elif self.accept("="):
                self.assignment()
            self.annotations()
            self.declare_local(name)
            if not self.accept(","):
                break
        self.expect(";", " after the declaration")

    # -- expressions ---------------------------------------------------------------------------
    def expression(self):
        expr = self.assignment()
        while self.at(","):
            expr = _Expr("other", self.next(), ",", [expr, self.assignment()])
        return expr

    def assignment(self, allow_assign=True):
        left, tok = self.binary(0), self.peek()
        if self.accept("?"):
            then = self.expression()
            self.expect(":", " in the conditional expression")
            return _Expr("other", tok, "?:", [left, then, self.assignment(allow_assign)])
        if allow_assign and tok.kind == "op" and tok.text in _ASSIGN_OPS:
            self.next()
            if left.kind not in _LVALUE_KINDS:
                self.error(f"left side of '{tok.text}' is not assignable", tok)
            return _Expr("other", tok, tok.text, [left, self.assignment()])
        return left

    def binary(self, level):
        if level == len(_BINARY_LEVELS):
            return self.unary()
        left = self.binary(level + 1)
        while self.peek().kind == "op" and self.peek().text in _BINARY_LEVELS[level]:
            tok = self.next()
            left = _Expr("binary", tok, tok.text, [left, self.binary(level + 1)])
        return left

    def unary(self):
        tok = self.peek()
        if tok.kind == "op" and tok.text in ("-", "+", "!", "~", "++", "--"):
            self.next()
            operand = self.unary()
            if tok.text in ("++", "--") and operand.kind not in _LVALUE_KINDS:
                self.error(f"operand of '{tok.text}' is not assignable", tok)
            return _Expr("unary", tok, tok.text, [operand])
        if self.accept("let"):  # let { declarations } in expression
            self.scopes.append(set())
            if self.accept("{"):
                while True:
                    self.var_declaration()
                    if self.accept("}"):
                        break
            else:
                self.var_declaration()
            self.expect("in", " after the 'let' declarations")
            body = self.assignment()
            self.scopes.pop()
            return _Expr("other", tok, "let", [body])
        expr = self.primary()
        while True:  # postfix operators
            tok = self.peek()
            if tok.text in ("++", "--"):
                if expr.kind not in _LVALUE_KINDS:
                    self.error(f"operand of '{tok.text}' is not assignable", tok)
                expr = _Expr("other", self.next(), tok.text, [expr])
            elif self.accept("."):
                member = self.ident("field name")
                expr = _Expr("member", member, member.text, [expr])
            elif tok.text == "(":
                expr = self.call(expr)
            elif self.accept("["):
                index = self.expression()
                self.expect("]", " to close the index")
                expr = _Expr("index", tok, None, [expr, index])
            else:
                return expr

    def primary(self):
        tok = self.peek()
        if tok.kind in ("int", "float"):
            return _Expr("literal", self.next(), tok.value)
        if tok.kind == "string":  # adjacent string literals are concatenated
            value = ""
            while self.peek().kind == "string":
                value += self.next().value
            return _Expr("literal", tok, value)
        if self.at("true", "false"):
            return _Expr("literal", self.next(), tok.text == "true")
        if self.accept("("):
            expr = self.expression()
            self.expect(")", " to close the parenthesis")
            return expr
        if not (self.at("::") or self.is_name()):
            self.error(f"expected an expression, found {self.found()}")
        name, first = self.scoped_name()
        if self.at("[") and self.at("]", k=1):  # array constructor T[](...)
            self.next()
            self.next()
            self.use_name(name, first, "unknown type")
            return _Expr("array_type", first, name)
        self.use_name(name, first, "unknown function" if self.at("(") else "undeclared identifier")
        return _Expr("name", first, name)

    def call(self, callee):
        paren = self.expect("(")
        args = []
        while not self.at(")"):
            label = None
            if self.is_name() and self.at(":", k=1):
                label = self.next().text
                self.next()
            elif args and args[-1][0] is not None:
                self.error("positional argument after a named argument")
            args.append((label, self.assignment()))
            if not self.accept(","):
                break
            if self.at(")"):
                self.error("expected an argument after ','")
        self.expect(")", " to close the argument list")
        return _Expr("call", paren, callee, args)

    # -- constant evaluation -------------------------------------------------------------------
    def try_evaluate(self, expr):
        """Evaluate a constant expression; None if it is not plain constant data."""
        try:
            return self.evaluate(expr)
        except _NotConstant:
            return None

    def evaluate(self, expr):
        kind, op = expr.kind, expr.value
        if kind == "literal":
            return op
        if kind == "name":
            const = self.module.constants.get(op)
            if const is not None and const.value is not None:
                return const.value
            if op.lstrip(":") in _MATH_CONSTANTS:
                return _MATH_CONSTANTS[op.lstrip(":")]
            if "::" in op or op in self.enum_values:
                return EnumRef(op)
        elif kind == "unary" and op in ("+", "-"):
            value = self.evaluate(expr.args[0])
            items = value if isinstance(value, tuple) else (value,)
            if all(_is_number(v) for v in items):
                negated = tuple(_wrap_int(-v) if isinstance(v, int) else -v for v in items)
                result = items if op == "+" else negated
                return result if isinstance(value, tuple) else result[0]
        elif kind == "binary" and op in (*_ARITHMETIC, "%"):
            try:
                return _arithmetic(op, *(self.evaluate(arg) for arg in expr.args))
            except ZeroDivisionError:
                self.error("integer division by zero in a constant expression", expr.tok)
        elif kind == "call":
            return self.call_value(expr)
        raise _NotConstant

    def call_value(self, expr):
        callee = expr.value
        args = [self.evaluate(arg) for label, arg in expr.args if label is None]
        kwargs = {label: self.evaluate(arg) for label, arg in expr.args if label is not None}
        sized_array = callee.kind == "index" and callee.args[0].kind == "name"  # T[n](...)
        if callee.kind == "array_type" or sized_array:
            if kwargs:
                raise _NotConstant
            return args
        if callee.kind != "name":
            raise _NotConstant
        if kwargs or not (callee.value in _SCALAR_TYPES or _type_shape(callee.value)):
            return Call(callee.value, args, kwargs, expr.tok.comment)
        value = _construct(callee.value, args)
        if value is None:
            count = sum(len(a) if isinstance(a, tuple) else 1 for a in args)
            self.error(
                f"{callee.value} constructor needs {_type_shape(callee.value)[1]} values "
                f"but got {count}",
                expr.tok,
            )
        return value
