"""What names in MDL denote: types, constants, enum values, functions and materials
(their overloads), annotations, parameters and local variables; and the checked module
that holds them.

A checked module (:class:`CheckedModule`) is what a back end compiles: its syntax tree,
the entities of its scope, and per expression (:class:`ExprInfo`, keyed by the node's
``id``) the type, whether it varies over the surface, its constant value if it has one,
and what it resolved to.
"""

from __future__ import annotations

from dataclasses import dataclass, field

from mdl import types as T
from mdl.diagnostics import Source, Span

__all__ = [
    "UNIFORM", "AUTO", "VARYING", "Entity", "TypeEntity", "ConstEntity", "EnumValueEntity",
    "ParamInfo", "Overload", "AnnotationEntity", "Local", "SizeName", "ExprInfo", "CallInfo",
    "CheckedModule", "AnnotationValue",
]

#: variability levels: a constant or uniform value; a value whose variability depends on
#: the caller (an unqualified parameter); a value that certainly varies over the surface
UNIFORM, AUTO, VARYING = 0, 1, 2


@dataclass(eq=False)
class Entity:
    name: str
    module: CheckedModule | None
    exported: bool = False
    span: Span | None = None

    @property
    def qname(self) -> str:
        prefix = self.module.qname if self.module is not None else ""
        return f"{prefix}::{self.name}"


@dataclass(eq=False)
class TypeEntity(Entity):
    type: T.Type = None


@dataclass(eq=False)
class ConstEntity(Entity):
    type: T.Type = None
    value: object = None       # the folded lane value (None: not yet folded / error)
    expr: object = None        # the initializer's syntax tree
    annotations: tuple = ()


@dataclass(eq=False)
class EnumValueEntity(Entity):
    enum: T.EnumType = None
    value: int = 0


@dataclass(frozen=True)
class AnnotationValue:
    """One annotation as the UI sees it: qualified name and argument values (Python)."""

    name: str
    args: tuple
    span: Span | None = None

    def __str__(self) -> str:
        return f"{self.name}({', '.join(_literal(a) for a in self.args)})"


def _literal(v) -> str:
    """A Python value as MDL writes it (annotation arguments)."""
    if isinstance(v, bool):
        return "true" if v else "false"
    if isinstance(v, str):
        body = v.replace("\\", "\\\\").replace('"', '\\"').replace("\n", "\\n")
        return f'"{body}"'
    if isinstance(v, float):
        return repr(v) if v != int(v) or abs(v) >= 1e16 else f"{v:.1f}"
    if isinstance(v, (tuple, list)):
        return "(" + ", ".join(_literal(x) for x in v) + ")"
    return repr(v)


@dataclass(eq=False)
class ParamInfo:
    name: str
    type: T.Type
    qualifier: str | None = None  # "uniform" | "varying" | None
    default: object = None        # syntax tree of the default, or None (required)
    annotations: tuple = ()       # AnnotationValue
    span: Span | None = None
    sizevar: T.SizeVar | None = None  # the size name this parameter binds (T[<N>])
    optional: bool = False            # a struct field without initializer (its type's zero)

    @property
    def uniform(self) -> bool:
        return self.qualifier == "uniform"

    @property
    def required(self) -> bool:
        return self.default is None and not self.optional


@dataclass(eq=False)
class Overload(Entity):
    """One function or material definition (an overload of its name).

    ``kind``: ``mdl`` (a body in MDL), ``intrinsic`` (a standard module's function the
    back end implements), ``native`` (a renderer's function or material, bound by the
    module's provider), ``struct`` (a struct's constructor), ``df`` (a distribution
    function constructor).
    """

    params: list[ParamInfo] = field(default_factory=list)
    ret: T.Type = T.ERROR
    ret_uniform: bool = False
    qualifier: str | None = None      # "uniform" | "varying" after the parameter list
    decl: object = None               # the FunctionDecl (or StructDecl)
    kind: str = "mdl"
    annotations: tuple = ()
    sizevars: dict = field(default_factory=dict)
    reads_state: bool | None = None   # set by the checker (transitively)
    index: int = 0                    # position among the name's overloads
    variant_of: Overload | None = None  # f(*) = g(...): the material it specializes

    @property
    def is_material(self) -> bool:
        return (isinstance(self.ret, T.StructType) and self.ret.builtin
                and self.ret.qname == "::material")

    def signature(self) -> str:
        """``float2 point_along_pwc(float curve_position, pw_point[<N>] pwc)``."""
        ps = []
        for p in self.params:
            q = f"{p.qualifier} " if p.qualifier else ""
            t = str(p.type)
            if isinstance(p.type, T.ArrayT) and p.sizevar is not None:
                t = f"{p.type.elem}[<{p.sizevar.name}>]"
            default = ""
            if p.default is not None:
                from mdl.printer import format_expression

                try:
                    default = " = " + format_expression(p.default)
                except TypeError:
                    default = " = ..."
            ps.append(f"{q}{t} {p.name}{default}")
        ret = ("uniform " if self.ret_uniform else "") + str(self.ret)
        return f"{ret} {self.name}({', '.join(ps)})" + (
            f" {self.qualifier}" if self.qualifier else "")

    @property
    def mangled(self) -> str:
        """A Python identifier unique in the module."""
        return f"{self.name}__{self.index}" if self.index else self.name


@dataclass(eq=False)
class AnnotationEntity(Entity):
    params: list[ParamInfo] = field(default_factory=list)


@dataclass(eq=False)
class Local:
    """A parameter, local variable, let binding or loop variable inside a definition."""

    name: str
    type: T.Type
    level: int = UNIFORM          # UNIFORM / AUTO / VARYING (fixpoint for locals)
    declared: str | None = None   # "uniform" | "varying" | None
    const: bool = False
    is_param: bool = False
    span: Span | None = None
    pyname: str = ""              # the back end's name for it
    value: object = None          # folded value of a const local


@dataclass(eq=False)
class SizeName:
    """The ``N`` of a size-deferred array parameter, usable as an ``int``."""

    var: T.SizeVar
    param: ParamInfo
    pyname: str = ""


@dataclass
class CallInfo:
    """How a call resolved.

    ``kind``: ``overload`` (``target`` an :class:`Overload`), ``vector``/``matrix``/
    ``color``/``scalar`` (a built-in type constructor of ``type``), ``array`` (an array
    constructor), ``resource`` (``texture_2d(...)``...), ``df_default`` (``bsdf()``...),
    ``enum`` (an enum converted from an int).  ``args`` lists one expression per
    parameter (None: the default), in the parameter order.
    """

    kind: str
    target: object = None
    type: T.Type = None
    args: list = field(default_factory=list)
    sizes: dict = field(default_factory=dict)  # SizeVar -> int or SizeVar (at the call)


@dataclass
class ExprInfo:
    type: T.Type
    level: int = UNIFORM
    const: object = None          # folded lane value, or None
    target: object = None         # Ref: Local / ConstEntity / EnumValueEntity / SizeName /
                                  # TypeEntity / list of Overloads; Member: field index
                                  # or component tuple; Binary: the operator's operand type
    call: CallInfo | None = None
    convert: T.Type | None = None  # convert the value to this type where it is used
    lvalue: bool = False

    @property
    def varying(self) -> bool:
        return self.level > UNIFORM


@dataclass(eq=False)
class CheckedModule:
    """A module whose names are resolved and whose definitions are type-checked."""

    qname: str                    # "::pw_curve"
    source: Source
    tree: object                  # mdl.ast.Module
    path: object = None           # pathlib.Path of the file, or None
    kind: str = "file"            # file | std | native | generated
    native: object = None         # the provider's binding data (native modules)
    scope: dict = field(default_factory=dict)      # name -> list[Entity]
    imports: dict = field(default_factory=dict)    # alias -> CheckedModule
    using: dict = field(default_factory=dict)      # name -> list[Entity]
    info: dict = field(default_factory=dict)       # id(node) -> ExprInfo
    locals: dict = field(default_factory=dict)     # id(declarator/param node) -> Local
    overloads: list = field(default_factory=list)  # every Overload defined here
    diagnostics: list = field(default_factory=list)
    annotations: tuple = ()
    version: tuple | None = None
    key: str = ""                 # content hash (this module and what it imports)

    @property
    def name(self) -> str:
        return self.qname.rsplit("::", 1)[-1]

    def exports(self) -> dict:
        """Exported name -> entities."""
        return {n: [e for e in es if e.exported] for n, es in self.scope.items()
                if any(e.exported for e in es)}

    def lookup(self, name: str) -> list:
        """The entities called ``name`` in this module's scope."""
        return self.scope.get(name, [])

    def functions(self, name: str) -> list[Overload]:
        return [e for e in self.scope.get(name, []) if isinstance(e, Overload)]

    def materials(self) -> list[Overload]:
        return [o for o in self.overloads if o.is_material]

    def constant(self, name: str):
        """The folded value of constant ``name`` as Python data (:func:`mdl.lanes.to_python`)."""
        from mdl.lanes import to_python

        for e in self.scope.get(name, []):
            if isinstance(e, ConstEntity):
                return to_python(e.value, e.type)
        raise KeyError(f"{self.qname} has no constant {name!r}")

    def __repr__(self) -> str:
        return f"CheckedModule({self.qname!r})"
