"""MDL's types: scalars, vectors, matrices, color, strings, resources, distribution
functions, structs (the material structs included), enums and arrays.

Value types compare by structure; structs and enums by identity (two modules may
declare ``pw_point``).  :func:`implicit_cost` says whether and how cheaply a value
converts without a cast (MDL: ``int`` to ``float`` and ``double``, ``float`` to
``double``, the same for vectors of equal size, and enums to ``int``).

Examples
--------
>>> builtin("float3"), builtin("double2x3").cols, implicit_cost(INT, FLOAT)
(float3, 2, 1)
>>> implicit_cost(FLOAT, COLOR) is None     # write color(x)
True
"""

from __future__ import annotations

from dataclasses import dataclass, field

__all__ = [
    "Type", "Scalar", "Vector", "Matrix", "Color", "String", "Resource", "DF", "StructType",
    "EnumType", "ArrayT", "SizeVar", "ErrorType", "AutoType", "FieldInfo",
    "BOOL", "INT", "FLOAT", "DOUBLE", "COLOR", "STRING", "ERROR", "AUTO",
    "builtin", "BUILTIN_TYPE_NAMES", "implicit_cost", "is_numeric", "elem_kind", "width",
    "vector", "common_scalar",
]


class Type:
    """Base of MDL types; ``str(t)`` is MDL's spelling."""

    def __str__(self) -> str:
        return self.name

    def __repr__(self) -> str:
        return self.name

    name = "?"


@dataclass(frozen=True, repr=False)
class Scalar(Type):
    kind: str  # bool | int | float | double

    @property
    def name(self) -> str:
        return self.kind


@dataclass(frozen=True, repr=False)
class Vector(Type):
    elem: str  # bool | int | float | double
    size: int

    @property
    def name(self) -> str:
        return f"{self.elem}{self.size}"

    @property
    def scalar(self) -> Scalar:
        return Scalar(self.elem)


@dataclass(frozen=True, repr=False)
class Matrix(Type):
    """``floatCxR``: C columns of R rows (MDL matrices are column-major)."""

    elem: str  # float | double
    cols: int
    rows: int

    @property
    def name(self) -> str:
        return f"{self.elem}{self.cols}x{self.rows}"

    @property
    def column(self) -> Vector:
        return Vector(self.elem, self.rows)


@dataclass(frozen=True, repr=False)
class Color(Type):
    name = "color"


@dataclass(frozen=True, repr=False)
class String(Type):
    name = "string"


@dataclass(frozen=True, repr=False)
class Resource(Type):
    """``texture_2d``, ``texture_3d``, ``texture_cube``, ``texture_ptex``,
    ``light_profile``, ``bsdf_measurement`` (always uniform)."""

    kind: str

    @property
    def name(self) -> str:
        return self.kind


@dataclass(frozen=True, repr=False)
class DF(Type):
    """``bsdf``, ``edf``, ``vdf``, ``hair_bsdf``."""

    kind: str

    @property
    def name(self) -> str:
        return self.kind


@dataclass(frozen=True)
class FieldInfo:
    name: str
    type: Type
    default: object = None  # an ast expression, or None (the type's default)
    uniform: bool = False
    annotations: tuple = ()


@dataclass(eq=False, repr=False)
class StructType(Type):
    """A struct; ``qname`` is its qualified name (``::pw_curve::pw_point``)."""

    qname: str
    fields: list[FieldInfo] = field(default_factory=list)
    builtin: bool = False
    module: object = None
    annotations: tuple = ()

    @property
    def name(self) -> str:
        return self.qname.removeprefix("::")

    def field_index(self, name: str) -> int | None:
        for i, f in enumerate(self.fields):
            if f.name == name:
                return i
        return None

    __hash__ = object.__hash__


@dataclass(eq=False, repr=False)
class EnumType(Type):
    qname: str
    values: list[tuple[str, int]] = field(default_factory=list)
    module: object = None
    annotations: tuple = ()
    value_annotations: dict = field(default_factory=dict)

    @property
    def name(self) -> str:
        return self.qname.removeprefix("::")

    def value_of(self, name: str) -> int | None:
        for n, v in self.values:
            if n == name:
                return v
        return None

    def name_of(self, value: int) -> str | None:
        for n, v in self.values:
            if v == value:
                return n
        return None

    __hash__ = object.__hash__


@dataclass(eq=False)
class SizeVar:
    """The size name of a size-deferred array parameter (``N`` of ``T[<N>]``)."""

    name: str

    def __repr__(self) -> str:
        return self.name


@dataclass(frozen=True, repr=False)
class ArrayT(Type):
    """``T[N]`` (``size`` an int), ``T[<N>]`` / ``T[N]`` with a size name (``sizevar``),
    or ``T[]`` (both None: the size of its initializer)."""

    elem: Type
    size: int | None = None
    sizevar: SizeVar | None = None

    @property
    def name(self) -> str:
        if self.size is not None:
            return f"{self.elem}[{self.size}]"
        if self.sizevar is not None:
            return f"{self.elem}[{self.sizevar.name}]"
        return f"{self.elem}[]"


@dataclass(frozen=True, repr=False)
class ErrorType(Type):
    """The type of an expression that already has an error (no further messages)."""

    name = "<error>"


@dataclass(frozen=True, repr=False)
class AutoType(Type):
    name = "auto"


BOOL, INT, FLOAT, DOUBLE = Scalar("bool"), Scalar("int"), Scalar("float"), Scalar("double")
COLOR, STRING, ERROR, AUTO = Color(), String(), ErrorType(), AutoType()


def vector(elem: str, n: int) -> Type:
    """``elem`` for n = 1, else the vector type."""
    return Scalar(elem) if n == 1 else Vector(elem, n)


def _builtin_table() -> dict[str, Type]:
    t: dict[str, Type] = {"bool": BOOL, "int": INT, "float": FLOAT, "double": DOUBLE,
                          "color": COLOR, "string": STRING}
    for e in ("bool", "int", "float", "double"):
        for n in (2, 3, 4):
            t[f"{e}{n}"] = Vector(e, n)
    for e in ("float", "double"):
        for c in (2, 3, 4):
            for r in (2, 3, 4):
                t[f"{e}{c}x{r}"] = Matrix(e, c, r)
    for k in ("texture_2d", "texture_3d", "texture_cube", "texture_ptex", "light_profile",
              "bsdf_measurement"):
        t[k] = Resource(k)
    for k in ("bsdf", "edf", "vdf", "hair_bsdf"):
        t[k] = DF(k)
    return t


_BUILTINS = _builtin_table()
#: names of the built-in types (material structs and ``intensity_mode`` are added by
#: the ``builtins`` module of :mod:`mdl.stdlib`)
BUILTIN_TYPE_NAMES = frozenset(_BUILTINS)


def builtin(name: str) -> Type | None:
    """The built-in value type called ``name``, or None."""
    return _BUILTINS.get(name)


def is_numeric(t: Type) -> bool:
    """int, float, double scalars, vectors and matrices, and color."""
    if isinstance(t, Scalar):
        return t.kind != "bool"
    if isinstance(t, Vector):
        return t.elem != "bool"
    return isinstance(t, (Matrix, Color))


def elem_kind(t: Type) -> str | None:
    """The scalar kind of a scalar, vector or matrix (``float`` for color)."""
    if isinstance(t, Scalar):
        return t.kind
    if isinstance(t, (Vector, Matrix)):
        return t.elem
    if isinstance(t, Color):
        return "float"
    return None


def width(t: Type) -> int:
    """Components of a vector (1 for scalars, 3 for color)."""
    if isinstance(t, Vector):
        return t.size
    if isinstance(t, Color):
        return 3
    return 1


_RANK = {"bool": 0, "int": 1, "float": 2, "double": 3}


def common_scalar(a: str, b: str) -> str:
    """The kind two numeric kinds convert to (``int``, ``float`` -> ``float``)."""
    return a if _RANK[a] >= _RANK[b] else b


def _scalar_cost(src: str, dst: str) -> int | None:
    if src == dst:
        return 0
    if src == "int" and dst in ("float", "double"):
        return 1 if dst == "float" else 2
    if src == "float" and dst == "double":
        return 1
    return None


def implicit_cost(src: Type, dst: Type) -> int | None:
    """Cost of converting ``src`` to ``dst`` implicitly: 0 identical, more for
    conversions, None when only an explicit constructor or cast converts."""
    if isinstance(src, ErrorType) or isinstance(dst, ErrorType):
        return 0
    if src == dst:
        return 0
    if isinstance(src, Scalar) and isinstance(dst, Scalar):
        return _scalar_cost(src.kind, dst.kind)
    if isinstance(src, Vector) and isinstance(dst, Vector) and src.size == dst.size:
        return _scalar_cost(src.elem, dst.elem)
    if isinstance(src, Matrix) and isinstance(dst, Matrix) and (src.cols, src.rows) == (
            dst.cols, dst.rows):
        return _scalar_cost(src.elem, dst.elem)
    if isinstance(src, EnumType) and dst == INT:
        return 1
    if isinstance(src, EnumType) and isinstance(dst, Scalar) and dst.kind in ("float",
                                                                             "double"):
        return 2
    if isinstance(src, ArrayT) and isinstance(dst, ArrayT):
        if src.elem != dst.elem:
            return None
        if dst.size is None and dst.sizevar is None:
            return 0
        if dst.sizevar is not None and dst.size is None:
            return 0 if src.sizevar is dst.sizevar else 1  # binds the size name
        if src.size is not None and src.size == dst.size:
            return 0
        return None
    return None
