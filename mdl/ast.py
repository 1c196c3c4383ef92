"""The syntax tree of an MDL module: frozen dataclasses, each with its :class:`Span`.

Names are resolved and types assigned later (:mod:`mdl.checker`); the tree is exactly
what the text says, so :func:`mdl.printer.format_module` prints it back and parsing that
gives an equal tree (the round-trip property the tests check).
"""

from __future__ import annotations

from dataclasses import dataclass, field

from mdl.diagnostics import Span

__all__ = [
    "Node", "Name", "TypeName", "ArraySuffix", "Annotation", "Literal", "Ref", "Call",
    "Argument", "Unary", "Postfix", "Binary", "Assign", "Conditional", "Member", "Index",
    "Let", "Cast", "Sequence", "ArrayType", "Expr",
    "VarDecl", "Declarator", "Block", "ExprStmt", "DeclStmt", "If", "Switch", "Case", "While",
    "DoWhile", "For", "Break", "Continue", "Return", "Empty", "Stmt",
    "Import", "Using", "ModuleAnnotations", "ConstDecl", "Typedef", "StructDecl", "Field",
    "EnumDecl", "EnumValue", "Param", "FunctionDecl", "AnnotationDecl", "Module",
    "children",
]


@dataclass(frozen=True, eq=True)
class Node:
    span: Span = field(compare=False, repr=False)


# --------------------------------------------------------------------------- names, types
@dataclass(frozen=True)
class Name(Node):
    """``a``, ``a::b``, ``::a::b`` (``absolute``), or an import path with ``.``/``..``."""

    parts: tuple[str, ...]
    absolute: bool = False

    @property
    def text(self) -> str:
        return ("::" if self.absolute else "") + "::".join(self.parts)


@dataclass(frozen=True)
class ArraySuffix(Node):
    """``[N]`` (size an expression), ``[<N>]`` (``deferred`` the size name) or ``[]``."""

    size: Expr | None = None
    deferred: str | None = None


@dataclass(frozen=True)
class TypeName(Node):
    """``[uniform|varying] name [array]`` (``auto`` is the name ``auto``)."""

    name: Name
    array: ArraySuffix | None = None
    qualifier: str | None = None  # "uniform" | "varying" | None


@dataclass(frozen=True)
class Annotation(Node):
    name: Name
    args: tuple[Argument, ...] = ()


# --------------------------------------------------------------------------- expressions
@dataclass(frozen=True)
class Literal(Node):
    """``kind`` is ``bool``, ``int``, ``float``, ``double`` or ``string``; ``text`` the spelling."""

    kind: str
    value: object
    text: str = field(default="", compare=False)


@dataclass(frozen=True)
class Ref(Node):
    """A use of a name (variable, constant, enum value, function, type as constructor)."""

    name: Name


@dataclass(frozen=True)
class ArrayType(Node):
    """An array type used as a constructor: ``float[](...)``, ``T[3](...)``."""

    element: Name
    suffix: ArraySuffix


@dataclass(frozen=True)
class Argument(Node):
    name: str | None
    value: Expr


@dataclass(frozen=True)
class Call(Node):
    callee: Expr
    args: tuple[Argument, ...]


@dataclass(frozen=True)
class Unary(Node):
    op: str  # "-", "+", "!", "~", "++", "--" (prefix)
    operand: Expr


@dataclass(frozen=True)
class Postfix(Node):
    op: str  # "++", "--"
    operand: Expr


@dataclass(frozen=True)
class Binary(Node):
    op: str
    left: Expr
    right: Expr


@dataclass(frozen=True)
class Assign(Node):
    op: str  # "=", "+=", ...
    target: Expr
    value: Expr


@dataclass(frozen=True)
class Conditional(Node):
    cond: Expr
    then: Expr
    other: Expr


@dataclass(frozen=True)
class Member(Node):
    """``obj.name``: a struct field, or a vector component / swizzle."""

    obj: Expr
    name: str
    name_span: Span = field(compare=False, repr=False, default=Span(0, 0))


@dataclass(frozen=True)
class Index(Node):
    obj: Expr
    index: Expr


@dataclass(frozen=True)
class Let(Node):
    decls: tuple[VarDecl, ...]
    body: Expr
    braces: bool = field(default=True, compare=False)


@dataclass(frozen=True)
class Cast(Node):
    type: TypeName
    operand: Expr


@dataclass(frozen=True)
class Sequence(Node):
    """``a, b`` (the comma operator, in ``for`` clauses)."""

    items: tuple[Expr, ...]


Expr = (Literal | Ref | ArrayType | Call | Unary | Postfix | Binary | Assign | Conditional
        | Member | Index | Let | Cast | Sequence)


# --------------------------------------------------------------------------- statements
@dataclass(frozen=True)
class Declarator(Node):
    """One name of a declaration: ``x``, ``x = e``, ``x(args)`` (constructor form)."""

    name: str
    init: Expr | None = None
    ctor_args: tuple[Argument, ...] | None = None
    annotations: tuple[Annotation, ...] = ()
    name_span: Span = field(compare=False, repr=False, default=Span(0, 0))


@dataclass(frozen=True)
class VarDecl(Node):
    """``[const] type a = 1, b;`` (locals, let bindings, module constants)."""

    type: TypeName
    declarators: tuple[Declarator, ...]
    const: bool = False


@dataclass(frozen=True)
class Block(Node):
    stmts: tuple[Stmt, ...]


@dataclass(frozen=True)
class ExprStmt(Node):
    expr: Expr


@dataclass(frozen=True)
class DeclStmt(Node):
    """A declaration inside a function body (variables, constants, typedefs...)."""

    decl: object


@dataclass(frozen=True)
class If(Node):
    cond: Expr
    then: Stmt
    other: Stmt | None = None


@dataclass(frozen=True)
class Case(Node):
    value: Expr | None  # None: default
    stmts: tuple[Stmt, ...]


@dataclass(frozen=True)
class Switch(Node):
    value: Expr
    cases: tuple[Case, ...]


@dataclass(frozen=True)
class While(Node):
    cond: Expr
    body: Stmt


@dataclass(frozen=True)
class DoWhile(Node):
    body: Stmt
    cond: Expr


@dataclass(frozen=True)
class For(Node):
    init: Stmt | None
    cond: Expr | None
    update: Expr | None
    body: Stmt


@dataclass(frozen=True)
class Break(Node):
    pass


@dataclass(frozen=True)
class Continue(Node):
    pass


@dataclass(frozen=True)
class Return(Node):
    value: Expr | None


@dataclass(frozen=True)
class Empty(Node):
    pass


Stmt = (Block | ExprStmt | DeclStmt | If | Switch | While | DoWhile | For | Break | Continue
        | Return | Empty)


# --------------------------------------------------------------------------- declarations
@dataclass(frozen=True)
class Import(Node):
    """``import a::b::*;`` or ``import a::b::c;`` (``path`` includes the last part)."""

    path: Name
    exported: bool = False


@dataclass(frozen=True)
class Using(Node):
    """``using ::a::b import x, y;`` / ``using ::a::b import *;`` (``names`` None: all)."""

    module: Name
    names: tuple[str, ...] | None
    exported: bool = False
    alias: str | None = None  # using alias = ::a::b;


@dataclass(frozen=True)
class ModuleAnnotations(Node):
    annotations: tuple[Annotation, ...]


@dataclass(frozen=True)
class ConstDecl(Node):
    decl: VarDecl
    exported: bool = False


@dataclass(frozen=True)
class Typedef(Node):
    type: TypeName
    name: str
    exported: bool = False
    name_span: Span = field(compare=False, repr=False, default=Span(0, 0))


@dataclass(frozen=True)
class Field(Node):
    type: TypeName
    name: str
    default: Expr | None = None
    annotations: tuple[Annotation, ...] = ()
    name_span: Span = field(compare=False, repr=False, default=Span(0, 0))


@dataclass(frozen=True)
class StructDecl(Node):
    name: str
    fields: tuple[Field, ...]
    annotations: tuple[Annotation, ...] = ()
    exported: bool = False
    name_span: Span = field(compare=False, repr=False, default=Span(0, 0))


@dataclass(frozen=True)
class EnumValue(Node):
    name: str
    value: Expr | None = None
    annotations: tuple[Annotation, ...] = ()


@dataclass(frozen=True)
class EnumDecl(Node):
    name: str
    values: tuple[EnumValue, ...]
    annotations: tuple[Annotation, ...] = ()
    exported: bool = False
    name_span: Span = field(compare=False, repr=False, default=Span(0, 0))


@dataclass(frozen=True)
class Param(Node):
    type: TypeName
    name: str
    default: Expr | None = None
    annotations: tuple[Annotation, ...] = ()
    name_span: Span = field(compare=False, repr=False, default=Span(0, 0))


@dataclass(frozen=True)
class FunctionDecl(Node):
    """A function or a material (``ret`` is ``material``).

    ``body`` is a :class:`Block`, an expression (``= expr;``: every material, and
    expression-bodied functions), or None (a prototype).  ``params`` is None for a
    variant, ``f(*) = g(...)``.
    """

    ret: TypeName
    name: str
    params: tuple[Param, ...] | None
    body: Block | Expr | None
    qualifier: str | None = None  # "uniform" | "varying" after the parameter list
    annotations: tuple[Annotation, ...] = ()
    ret_annotations: tuple[Annotation, ...] = ()
    exported: bool = False
    name_span: Span = field(compare=False, repr=False, default=Span(0, 0))


@dataclass(frozen=True)
class AnnotationDecl(Node):
    name: str
    params: tuple[Param, ...]
    annotations: tuple[Annotation, ...] = ()
    exported: bool = False
    name_span: Span = field(compare=False, repr=False, default=Span(0, 0))


@dataclass(frozen=True)
class Module(Node):
    version: tuple[int, int] | None
    decls: tuple[object, ...]


def children(node: Node):
    """The nodes directly below ``node``, in field order (a tuple field's nodes in turn)."""
    for f in node.__dataclass_fields__:
        v = getattr(node, f)
        if isinstance(v, Node):
            yield v
        elif isinstance(v, tuple):
            yield from (x for x in v if isinstance(x, Node))
