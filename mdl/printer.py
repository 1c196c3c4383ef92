"""Print a syntax tree back as MDL text (canonical layout, parentheses where needed).

``parse(format(tree)) == tree`` for every tree the parser makes (spans aside): the
property the tests check with generated modules.

Examples
--------
>>> from mdl.diagnostics import Source
>>> from mdl.parser import parse_expression
>>> format_expression(parse_expression(Source("e", "a*(b+c)-f(x: 1)[2].y")))
'a * (b + c) - f(x: 1)[2].y'
"""

from __future__ import annotations

from mdl import ast as A

__all__ = ["format_module", "format_expression", "format_type"]

_PREC = {"||": 3, "&&": 4, "|": 5, "^": 6, "&": 7, "==": 8, "!=": 8, "<": 9, "<=": 9,
         ">=": 9, ">": 9, "<<": 10, ">>": 10, ">>>": 10, "+": 11, "-": 11, "*": 12, "/": 12,
         "%": 12}
# precedence of node kinds: sequence 0, assignment 1, conditional 2, binary 3..12,
# unary 13, postfix 14, primary 15
_UNARY, _POSTFIX, _PRIMARY = 13, 14, 15


def _prec(e) -> int:
    if isinstance(e, A.Sequence):
        return 0
    if isinstance(e, (A.Assign, A.Let)):  # a let's body runs on to the right as far as
        return 1                            # an assignment's value: an operand needs ()
    if isinstance(e, A.Conditional):
        return 2
    if isinstance(e, A.Binary):
        return _PREC[e.op]
    if isinstance(e, A.Unary):
        return _UNARY
    if isinstance(e, (A.Postfix, A.Call, A.Index, A.Member, A.ArrayType)):
        return _POSTFIX
    return _PRIMARY


def _name(n: A.Name) -> str:
    return n.text


def _literal(e: A.Literal) -> str:
    if e.kind == "bool":
        return "true" if e.value else "false"
    if e.kind == "int":
        return str(e.value)
    if e.kind == "string":
        out = []
        for c in e.value:
            if c in '"\\':
                out.append("\\" + c)
            elif c == "\n":
                out.append("\\n")
            elif c == "\t":
                out.append("\\t")
            elif not c.isprintable() or ord(c) > 126:
                out.append(f"\\u{ord(c):04x}" if ord(c) <= 0xFFFF else f"\\U{ord(c):08x}")
            else:
                out.append(c)
        return '"' + "".join(out) + '"'
    text = repr(float(e.value))
    if "e" in text and "." not in text.split("e")[0]:
        mant, exp = text.split("e")
        text = f"{mant}.0e{exp}"
    return text + ("d" if e.kind == "double" else "")


def format_type(t: A.TypeName) -> str:
    out = (t.qualifier + " " if t.qualifier else "") + _name(t.name)
    if t.array is not None:
        out += _suffix(t.array)
    return out


def _suffix(s: A.ArraySuffix) -> str:
    if s.deferred is not None:
        return f"[<{s.deferred}>]"
    if s.size is None:
        return "[]"
    return f"[{format_expression(s.size)}]"


def _args(args) -> str:
    return "(" + ", ".join((f"{a.name}: " if a.name else "") + _expr(a.value, 1)
                           for a in args) + ")"


def _annos(annos) -> str:
    if not annos:
        return ""
    return " [[ " + ", ".join(_name(a.name) + _args(a.args) for a in annos) + " ]]"


def _expr(e, need: int) -> str:
    text = _expr_raw(e)
    return f"({text})" if _prec(e) < need else text


def _expr_raw(e) -> str:
    if isinstance(e, A.Literal):
        text = _literal(e)
        return text
    if isinstance(e, A.Ref):
        return _name(e.name)
    if isinstance(e, A.ArrayType):
        return _name(e.element) + _suffix(e.suffix)
    if isinstance(e, A.Call):
        return _expr(e.callee, _POSTFIX) + _args(e.args)
    if isinstance(e, A.Index):
        return f"{_expr(e.obj, _POSTFIX)}[{_expr(e.index, 0)}]"
    if isinstance(e, A.Member):
        base = _expr(e.obj, _POSTFIX)
        if isinstance(e.obj, A.Literal) and e.obj.kind in ("int", "float", "double"):
            base = f"({base})"  # 0.x would lex as a number
        return f"{base}.{e.name}"
    if isinstance(e, A.Postfix):
        return _expr(e.operand, _POSTFIX) + e.op
    if isinstance(e, A.Unary):
        inner = _expr(e.operand, _UNARY)
        # keep "- -x" and "+ +x" from lexing as "--"/"++"
        sep = " " if inner[:1] in "+-" and e.op in "+-" else ""
        return e.op + sep + inner
    if isinstance(e, A.Binary):
        p = _PREC[e.op]
        return f"{_expr(e.left, p)} {e.op} {_expr(e.right, p + 1)}"
    if isinstance(e, A.Assign):
        return f"{_expr(e.target, 2)} {e.op} {_expr(e.value, 1)}"
    if isinstance(e, A.Conditional):
        return f"{_expr(e.cond, 3)} ? {_expr(e.then, 0)} : {_expr(e.other, 1)}"
    if isinstance(e, A.Sequence):
        return ", ".join(_expr(x, 1) for x in e.items)
    if isinstance(e, A.Cast):
        return f"cast<{format_type(e.type)}>({_expr(e.operand, 0)})"
    if isinstance(e, A.Let):
        decls = " ".join(_var_decl(d) + ";" for d in e.decls)
        return f"let {{ {decls} }} in {_expr(e.body, 1)}"
    raise TypeError(f"not an expression: {e!r}")


def format_expression(e) -> str:
    """MDL text of an expression."""
    return _expr(e, 0)


def _declarator(d: A.Declarator) -> str:
    out = d.name + _annos(d.annotations)
    if d.init is not None:
        out += " = " + _expr(d.init, 1)
    elif d.ctor_args is not None:
        out += _args(d.ctor_args)
    return out


def _var_decl(d: A.VarDecl) -> str:
    return (("const " if d.const else "") + format_type(d.type) + " "
            + ", ".join(_declarator(x) for x in d.declarators))


def _stmt(s, indent: int) -> list[str]:
    pad = "    " * indent
    if isinstance(s, A.Block):
        return [pad + "{", *[x for t in s.stmts for x in _stmt(t, indent + 1)], pad + "}"]
    if isinstance(s, A.ExprStmt):
        return [pad + _expr(s.expr, 0) + ";"]
    if isinstance(s, A.DeclStmt):
        return [pad + _var_decl(s.decl) + ";"]
    if isinstance(s, A.Empty):
        return [pad + ";"]
    if isinstance(s, A.Break):
        return [pad + "break;"]
    if isinstance(s, A.Continue):
        return [pad + "continue;"]
    if isinstance(s, A.Return):
        return [pad + "return " + _expr(s.value, 0) + ";"]
    if isinstance(s, A.If):
        out = [pad + f"if ({_expr(s.cond, 0)})", *_sub(s.then, indent)]
        if s.other is not None:
            out += [pad + "else", *_sub(s.other, indent)]
        return out
    if isinstance(s, A.While):
        return [pad + f"while ({_expr(s.cond, 0)})", *_sub(s.body, indent)]
    if isinstance(s, A.DoWhile):
        return [pad + "do", *_sub(s.body, indent), pad + f"while ({_expr(s.cond, 0)});"]
    if isinstance(s, A.For):
        if s.init is None:
            init = ";"
        else:
            init = _stmt(s.init, 0)[0]
        cond = "" if s.cond is None else " " + _expr(s.cond, 0)
        update = "" if s.update is None else " " + _expr(s.update, 0)
        return [pad + f"for ({init}{cond};{update})", *_sub(s.body, indent)]
    if isinstance(s, A.Switch):
        out = [pad + f"switch ({_expr(s.value, 0)}) {{"]
        for c in s.cases:
            label = "default:" if c.value is None else f"case {_expr(c.value, 2)}:"
            out.append(pad + "    " + label)
            for t in c.stmts:
                out += _stmt(t, indent + 2)
        out.append(pad + "}")
        return out
    raise TypeError(f"not a statement: {s!r}")


def _sub(s, indent: int) -> list[str]:
    return _stmt(s, indent if isinstance(s, A.Block) else indent + 1)


def _params(params) -> str:
    if params is None:
        return "(*)"
    return "(" + ", ".join(
        format_type(p.type) + " " + p.name
        + ("" if p.default is None else " = " + _expr(p.default, 1)) + _annos(p.annotations)
        for p in params) + ")"


def _decl(d) -> list[str]:
    ex = "export " if getattr(d, "exported", False) else ""
    if isinstance(d, A.Import):
        return [f"{ex}import {_import_path(d.path)};"]
    if isinstance(d, A.Using):
        if d.alias is not None:
            return [f"{ex}using {d.alias} = {_import_path(d.module)};"]
        names = "*" if d.names is None else ", ".join(d.names)
        return [f"{ex}using {_import_path(d.module)} import {names};"]
    if isinstance(d, A.ModuleAnnotations):
        return ["module" + _annos(d.annotations) + ";"]
    if isinstance(d, A.ConstDecl):
        return [ex + _var_decl(d.decl) + ";"]
    if isinstance(d, A.Typedef):
        return [f"{ex}typedef {format_type(d.type)} {d.name};"]
    if isinstance(d, A.StructDecl):
        out = [f"{ex}struct {d.name}{_annos(d.annotations)} {{"]
        for f in d.fields:
            default = "" if f.default is None else " = " + _expr(f.default, 1)
            out.append(f"    {format_type(f.type)} {f.name}{default}{_annos(f.annotations)};")
        return out + ["};"]
    if isinstance(d, A.EnumDecl):
        values = ",\n".join(
            "    " + v.name + ("" if v.value is None else " = " + _expr(v.value, 1))
            + _annos(v.annotations) for v in d.values)
        return [f"{ex}enum {d.name}{_annos(d.annotations)} {{", values, "};"]
    if isinstance(d, A.AnnotationDecl):
        return [f"{ex}annotation {d.name}{_params(d.params)}{_annos(d.annotations)};"]
    if isinstance(d, A.FunctionDecl):
        head = (f"{ex}{format_type(d.ret)}{_annos(d.ret_annotations)} {d.name}"
                f"{_params(d.params)}" + (f" {d.qualifier}" if d.qualifier else "")
                + _annos(d.annotations))
        if d.body is None:
            return [head + ";"]
        if isinstance(d.body, A.Block):
            return [head, *_stmt(d.body, 0)]
        return [head + " =", "    " + _expr(d.body, 0) + ";"]
    raise TypeError(f"not a declaration: {d!r}")


def _import_path(n: A.Name) -> str:
    parts = list(n.parts)
    return ("::" if n.absolute else "") + "::".join(parts)


def format_module(m: A.Module) -> str:
    """MDL text of a module."""
    out = []
    if m.version is not None:
        out.append(f"mdl {m.version[0]}.{m.version[1]};")
    for d in m.decls:
        out += _decl(d)
    return "\n".join(out) + "\n"
