"""Recursive-descent parser of MDL 1.x modules and expressions into :mod:`mdl.ast`.

The grammar is MDL's (specification 1.x, the MDL SDK's ``compilercore_parser.atg``):
a version line, ``import``/``using`` declarations, then exported or local constants,
typedefs, structs, enums, annotations, functions and materials.  Operators have C's
precedence; ``let`` binds an expression; ``cast<T>(e)`` converts; ``T[](...)`` and
``T[N](...)`` construct arrays; annotations ``[[ ... ]]`` may follow names, parameters,
fields, enum values and signatures.

Syntax errors are :class:`~mdl.diagnostics.MdlError` with the location and a fix; after
an error in one declaration the parser skips to the next and goes on, so a file gets
every syntax error at once (at most :data:`~mdl.diagnostics.MAX_ERRORS`).

Examples
--------
>>> from mdl.diagnostics import Source
>>> m = parse_module(Source("a.mdl", "mdl 1.6; export float f(float x) { return 2.0 * x; }"))
>>> m.version, m.decls[0].name, m.decls[0].exported
((1, 6), 'f', True)
>>> e = parse_expression(Source("<call>", "glossy(tint: color(0.5)).surface"))
>>> type(e).__name__, e.name
('Member', 'surface')
"""

from __future__ import annotations

import sys

from mdl import ast as A
from mdl.diagnostics import MAX_ERRORS, MdlError, Source, Span
from mdl.lexer import KEYWORDS, Token, tokenize

__all__ = ["parse_module", "parse_expression", "MAX_DEPTH", "SUPPORTED_VERSIONS"]

#: deepest nesting of parentheses, calls, blocks accepted (deeper: an error, not a crash)
MAX_DEPTH = 100
#: MDL versions this front end reads
#: MDL 1.0 to 1.10 (1.10 adds distribution functions and parameters, no syntax)
SUPPORTED_VERSIONS = tuple((1, m) for m in range(11))

_ASSIGN_OPS = ("=", "+=", "-=", "*=", "/=", "%=", "&=", "|=", "^=", "<<=", ">>=", ">>>=")
# binary operators by precedence, lowest first (C's)
_BINARY = [("||",), ("&&",), ("|",), ("^",), ("&",), ("==", "!="), ("<", "<=", ">=", ">"),
           ("<<", ">>", ">>>"), ("+", "-"), ("*", "/", "%")]
_PREC = {op: i for i, ops in enumerate(_BINARY) for op in ops}


def _unclosed_by_indent(text: str) -> int | None:
    """The first line ending in '{' after which the code goes back to its indentation
    (or less) without a '}' (a guess at the brace left open), or None."""
    lines = text.split("\n")

    def indent(s: str) -> int:
        return len(s) - len(s.lstrip())

    for i, line in enumerate(lines):
        code = line.split("//")[0].rstrip()
        if not code.endswith("{"):
            continue
        level = indent(line)
        for later in lines[i + 1:]:
            if not later.strip() or later.lstrip().startswith("//"):
                continue
            if indent(later) <= level:
                if not later.lstrip().startswith("}"):
                    return i + 1
                break
    return None


class _Parser:
    def __init__(self, src: Source):
        self.src = src
        self.toks: list[Token] = tokenize(src)
        self.i = 0
        self.depth = 0
        self.errors = []
        self.version: tuple[int, int] | None = None

    # ------------------------------------------------------------------ helpers
    @property
    def tok(self) -> Token:
        return self.toks[self.i]

    def peek(self, k: int = 1) -> Token:
        return self.toks[min(self.i + k, len(self.toks) - 1)]

    def advance(self) -> Token:
        t = self.toks[self.i]
        if t.kind != "eof":
            self.i += 1
        return t

    def at(self, *kinds: str) -> bool:
        return self.tok.kind in kinds

    def accept(self, kind: str) -> Token | None:
        return self.advance() if self.tok.kind == kind else None

    def describe(self, t: Token) -> str:
        if t.kind == "eof":
            return "end of input"
        return f"'{t.text}'"

    def fail(self, message: str, token: Token | None = None, fix: str = "",
             after_previous: bool = False):
        """Raise a syntax error at ``token`` (default: the current one); at the end of
        input or with ``after_previous`` (a missing terminator), just after the previous
        token, on the line where the terminator belongs."""
        if token is not None:
            start, end = token.start, max(token.end, token.start + 1)
        elif (after_previous or self.tok.kind == "eof") and self.i > 0:
            start = self.toks[self.i - 1].end
            end = start + 1
        else:
            start, end = self.tok.start, max(self.tok.end, self.tok.start + 1)
        raise MdlError([self.src.diagnostic("error", message, start, end, fix)])

    def expect(self, kind: str, what: str | None = None, fix: str = "") -> Token:
        if self.tok.kind != kind:
            what = what or f"'{kind}'"
            terminator = kind in (";", ")", "]", "}")
            # a missing terminator is reported where it belongs: after the previous token
            after = terminator and self.i > 0 and self.tok.kind != "eof" and (
                self.src.line_col(self.tok.start)[0]
                != self.src.line_col(self.toks[self.i - 1].end)[0])
            self.fail(f"expected {what}, found {self.describe(self.tok)}",
                      fix=fix or (f"add '{kind}'" if terminator else ""), after_previous=after)
        return self.advance()

    def span_from(self, start: int) -> Span:
        end = self.toks[self.i - 1].end if self.i > 0 else start
        return Span(start, max(end, start))

    def enter(self) -> None:
        self.depth += 1
        if self.depth > MAX_DEPTH:
            self.fail(f"nesting too deep (more than {MAX_DEPTH} levels)",
                      fix="split the expression or block into smaller functions")

    def leave(self) -> None:
        self.depth -= 1

    def ident(self, what: str = "name") -> Token:
        t = self.tok
        if t.kind != "ident":
            fix = ""
            if t.kind in KEYWORDS:
                fix = f"'{t.text}' is a keyword of MDL; choose another name"
            self.fail(f"expected {what}, found {self.describe(t)}", fix=fix)
        return self.advance()

    # ------------------------------------------------------------------ module
    def module(self) -> A.Module:
        start = self.tok.start
        decls: list = []
        if self.at("mdl"):
            self.guard(lambda: self.version_line())
        elif not self.at("eof"):
            t = self.tok
            self.errors.append(self.src.diagnostic(
                "error", "missing 'mdl 1.x;' version header", t.start, t.end,
                "start the module with its MDL version, e.g. 'mdl 1.6;'"))
        seen_other = False
        while not self.at("eof"):
            if len(self.errors) >= MAX_ERRORS:
                break
            begin = self.i
            try:
                d = self.global_declaration(seen_other)
                if d is not None:
                    decls.append(d)
                    if not isinstance(d, (A.Import, A.Using)):
                        seen_other = True
            except MdlError as e:
                self.errors.extend(e.diagnostics)
                self.recover(begin)
        return A.Module(Span(start, len(self.src.text)), self.version, tuple(decls))

    def guard(self, f):
        try:
            return f()
        except MdlError as e:
            self.errors.extend(e.diagnostics)
            self.recover(self.i)

    def recover(self, begin: int) -> None:
        """Skip the broken declaration: to just after the next ``;`` at brace depth 0, or
        the ``}`` (and its ``;``) that closes the braces it opened."""
        depth, i = 0, begin
        while self.toks[i].kind != "eof":
            k = self.toks[i].kind
            if k == "{":
                depth += 1
            elif k == "}":
                depth -= 1
                if depth <= 0:
                    i += 1
                    if self.toks[i].kind == ";":
                        i += 1
                    break
            elif k == ";" and depth <= 0:
                i += 1
                break
            i += 1
        self.i = max(i, begin + 1)

    def version_line(self) -> None:
        mdl = self.advance()
        t = self.tok
        if t.kind not in ("float", "int"):
            self.fail(f"expected the MDL version after 'mdl', found {self.describe(t)}",
                      fix="write e.g. 'mdl 1.6;'")
        self.advance()
        text = t.text.rstrip("fFdD")
        try:
            major, minor = (int(x) for x in text.split("."))
        except ValueError:
            self.fail(f"malformed MDL version '{t.text}'", t, fix="write e.g. 'mdl 1.6;'")
        if (major, minor) not in SUPPORTED_VERSIONS:
            self.fail(f"unsupported MDL version {major}.{minor}", t,
                      fix="this front end reads MDL 1.0 to 1.10; write e.g. 'mdl 1.6;'")
        self.version = (major, minor)
        self.expect(";", fix="end the version line with ';'")
        del mdl

    def global_declaration(self, seen_other: bool):
        start = self.tok.start
        exported = False
        if self.at("export"):
            self.advance()
            exported = True
        t = self.tok
        if t.kind in ("import", "using"):
            if seen_other:
                self.fail(f"'{t.text}' declarations must precede all other declarations", t,
                          fix="move the import to the top of the module, after the mdl line")
            return self.import_decl(start, exported) if t.kind == "import" else \
                self.using_decl(start, exported)
        if t.kind == "module":
            self.advance()
            annos = self.annotations()
            self.expect(";")
            return A.ModuleAnnotations(self.span_from(start), annos)
        if t.kind == "annotation":
            return self.annotation_decl(start, exported)
        if t.kind == "struct":
            return self.struct_decl(start, exported)
        if t.kind == "enum":
            return self.enum_decl(start, exported)
        if t.kind == "typedef":
            self.advance()
            ty = self.type_name()
            name = self.ident("a type name")
            self.expect(";")
            return A.Typedef(self.span_from(start), ty, name.text, exported,
                             Span(name.start, name.end))
        if t.kind == "const":
            self.advance()
            decl = self.var_decl(start, const=True)
            self.expect(";", fix="end the constant declaration with ';'")
            return A.ConstDecl(self.span_from(start), decl, exported)
        if t.kind == "}":
            self.fail("unmatched '}'", t, fix="remove it, or add the '{' it closes")
        if t.kind == ";":
            self.advance()
            return None
        if t.kind not in ("ident", "uniform", "varying", "auto", "::"):
            self.fail(f"expected a declaration, found {self.describe(t)}", t,
                      fix="a module holds imports, constants, types, functions and materials")
        ty = self.type_name()
        ret_annos = self.annotations() if self.at("[[") else ()
        name = self.ident("a name")
        if self.at("("):
            return self.function_rest(start, ty, ret_annos, name, exported)
        self.fail(f"global variable '{name.text}': MDL modules hold no variables", name,
                  fix="declare it 'const', or make it a function parameter")

    def import_path(self) -> A.Name:
        """``[::|.::|..::] a::b[::*]`` (``*`` kept as the last part)."""
        start = self.tok.start
        parts: list[str] = []
        absolute = False
        if self.at("::"):
            self.advance()
            absolute = True
        elif self.at("."):
            self.advance()
            self.expect("::")
            parts.append(".")
        elif self.at(".."):
            while self.at(".."):
                self.advance()
                self.expect("::")
                parts.append("..")
        parts.append(self.ident("a module name").text)
        while self.at("::"):
            self.advance()
            if self.at("*"):
                self.advance()
                parts.append("*")
                break
            parts.append(self.ident("a name").text)
        return A.Name(self.span_from(start), tuple(parts), absolute)

    def import_decl(self, start: int, exported: bool):
        self.advance()
        paths = [self.import_path()]
        while self.accept(","):
            paths.append(self.import_path())
        self.expect(";", fix="end the import with ';'")
        if len(paths) == 1:
            return A.Import(self.span_from(start), paths[0], exported)
        return tuple(A.Import(p.span, p, exported) for p in paths)

    def using_decl(self, start: int, exported: bool):
        self.advance()
        if self.tok.kind == "ident" and self.peek().kind == "=":  # using alias = ::a::b;
            alias = self.advance().text
            self.advance()
            path = self.import_path()
            self.expect(";")
            return A.Using(self.span_from(start), path, (), exported, alias)
        path = self.import_path()
        if path.parts[-1] == "*":
            self.fail("write 'using ::module import *;' (the '*' follows 'import')",
                      fix="using ::math import *;")
        self.expect("import", fix="write 'using ::module import name, ...;'")
        if self.accept("*"):
            names = None
        else:
            names = [self.ident("a name to import").text]
            while self.accept(","):
                names.append(self.ident("a name to import").text)
            names = tuple(names)
        self.expect(";")
        return A.Using(self.span_from(start), path, names, exported)

    def trailing_comma_ok(self) -> bool:
        return self.version is not None and self.version >= (1, 8)

    def trailing_comma(self):
        self.fail(f"expected a name, found {self.describe(self.tok)}: a trailing ',' is "
                  "allowed from MDL 1.8 on", self.toks[self.i - 1],
                  fix="remove the ',' (or declare 'mdl 1.8;')")

    def annotation_decl(self, start: int, exported: bool):
        self.advance()
        name = self.ident("an annotation name")
        params = self.params()
        annos = self.annotations() if self.at("[[") else ()
        self.expect(";")
        return A.AnnotationDecl(self.span_from(start), name.text, tuple(params or ()), annos,
                                exported, Span(name.start, name.end))

    def struct_decl(self, start: int, exported: bool):
        self.advance()
        name = self.ident("a struct name")
        annos = self.annotations() if self.at("[[") else ()
        self.expect("{", fix="a struct's fields go in braces: struct s { float a; };")
        fields = []
        while not self.at("}"):
            if self.at("eof"):
                self.fail("missing '}' at the end of the struct", fix="add '};'")
            fstart = self.tok.start
            ty = self.type_name()
            fname = self.ident("a field name")
            default = None
            if self.accept("="):
                default = self.assignment()
            fannos = self.annotations() if self.at("[[") else ()
            self.expect(";", fix="end each field with ';'")
            fields.append(A.Field(self.span_from(fstart), ty, fname.text, default, fannos,
                                  Span(fname.start, fname.end)))
        self.advance()
        self.expect(";", fix="end the struct with '};'")
        return A.StructDecl(self.span_from(start), name.text, tuple(fields), annos, exported,
                            Span(name.start, name.end))

    def enum_decl(self, start: int, exported: bool):
        self.advance()
        name = self.ident("an enum name")
        annos = self.annotations() if self.at("[[") else ()
        self.expect("{")
        values = []
        while True:
            vstart = self.tok.start
            vname = self.ident("an enum value name")
            value = None
            if self.accept("="):
                value = self.assignment()
            vannos = self.annotations() if self.at("[[") else ()
            values.append(A.EnumValue(self.span_from(vstart), vname.text, value, vannos))
            if self.accept(","):
                if self.at("}"):
                    if self.trailing_comma_ok():
                        break
                    self.trailing_comma()
                continue
            break
        self.expect("}", fix="separate enum values with ',' and close with '};'")
        self.expect(";", fix="end the enum with '};'")
        return A.EnumDecl(self.span_from(start), name.text, tuple(values), annos, exported,
                          Span(name.start, name.end))

    def function_rest(self, start: int, ret: A.TypeName, ret_annos, name: Token,
                      exported: bool):
        if self.peek().kind == "*" and self.peek(2).kind == ")":  # variant f(*) = g(...)
            self.advance(), self.advance(), self.advance()
            params = None
        else:
            params = tuple(self.params())
        qualifier = None
        if self.at("uniform", "varying"):
            qualifier = self.advance().kind
        annos = self.annotations() if self.at("[[") else ()
        body = None
        if self.at("{"):
            body = self.block()
        elif self.accept("="):
            body = self.expression()
            self.expect(";", fix="end the definition with ';'")
        else:
            self.expect(";", "'{', '=' or ';' after the parameter list",
                        fix="give the function a body in braces")
        return A.FunctionDecl(self.span_from(start), ret, name.text, params, body, qualifier,
                              annos, ret_annos, exported, Span(name.start, name.end))

    def params(self) -> list[A.Param]:
        self.expect("(")
        params: list[A.Param] = []
        if self.accept(")"):
            return params
        while True:
            pstart = self.tok.start
            ty = self.type_name()
            pname = self.ident("a parameter name")
            default = None
            if self.accept("="):
                default = self.assignment()
            annos = self.annotations() if self.at("[[") else ()
            params.append(A.Param(self.span_from(pstart), ty, pname.text, default, annos,
                                  Span(pname.start, pname.end)))
            if self.accept(","):
                if self.at(")"):
                    if self.trailing_comma_ok():
                        break
                    self.trailing_comma()
                continue
            break
        self.expect(")", "',' or ')' in the parameter list",
                    fix="separate parameters with ',' and close the list with ')'")
        return params

    # ------------------------------------------------------------------ types, annotations
    def qualified_name(self, what: str = "a name") -> A.Name:
        start = self.tok.start
        absolute = bool(self.accept("::"))
        parts = [self.ident(what).text]
        while self.at("::") and self.peek().kind == "ident":
            self.advance()
            parts.append(self.advance().text)
        return A.Name(self.span_from(start), tuple(parts), absolute)

    def type_name(self) -> A.TypeName:
        start = self.tok.start
        qualifier = None
        if self.at("uniform", "varying"):
            qualifier = self.advance().kind
        if self.at("auto"):
            t = self.advance()
            name = A.Name(Span(t.start, t.end), ("auto",))
        else:
            name = self.qualified_name("a type")
        array = self.array_suffix() if self.at("[") else None
        return A.TypeName(self.span_from(start), name, array, qualifier)

    def array_suffix(self) -> A.ArraySuffix:
        start = self.expect("[").start
        if self.accept("]"):
            return A.ArraySuffix(self.span_from(start))
        if self.at("<"):
            self.advance()
            n = self.ident("a size name")
            self.expect(">", fix="a size-deferred array is written T[<N>]")
            self.expect("]")
            return A.ArraySuffix(self.span_from(start), None, n.text)
        size = self.conditional()
        self.expect("]", fix="close the array size with ']'")
        return A.ArraySuffix(self.span_from(start), size)

    def annotations(self) -> tuple[A.Annotation, ...]:
        self.expect("[[")
        annos = []
        while True:
            if self.at("]") and self.peek().kind == "]" and (not annos or self.trailing_comma_ok()):
                break
            astart = self.tok.start
            name = self.qualified_name("an annotation")
            args = self.arguments() if self.at("(") else ()
            annos.append(A.Annotation(self.span_from(astart), name, args))
            if not self.accept(","):
                break
        if not (self.at("]") and self.peek().kind == "]"):
            self.fail(f"expected ']]' to close the annotation block, found "
                      f"{self.describe(self.tok)}", fix="close annotations with ']]'")
        self.advance(), self.advance()
        return tuple(annos)

    # ------------------------------------------------------------------ statements
    def block(self) -> A.Block:
        start = self.expect("{").start
        self.enter()
        stmts = []
        while not self.at("}"):
            if self.at("eof"):
                line, _ = self.src.line_col(start)
                guess = _unclosed_by_indent(self.src.text)
                where = (f"; by the indentation, the '{{' of line {guess} is the one left "
                         "open" if guess is not None and guess != line else "")
                self.fail(f"missing '}}' at the end of the block opened on line {line}",
                          fix=f"add '}}' to close the '{{' it belongs to{where}")
            stmts.append(self.statement())
        self.advance()
        self.leave()
        return A.Block(self.span_from(start), tuple(stmts))

    def is_declaration(self) -> bool:
        """A type followed by a name ahead (``float x``, ``a::b[2] c``, ``uniform T x``)."""
        j = self.i
        toks = self.toks
        if toks[j].kind in ("uniform", "varying", "const"):
            return True
        if toks[j].kind == "auto":
            return True
        if toks[j].kind == "::":
            j += 1
        if toks[j].kind != "ident":
            return False
        j += 1
        while toks[j].kind == "::" and toks[j + 1].kind == "ident":
            j += 2
        if toks[j].kind == "[":
            depth = 0
            while toks[j].kind != "eof":
                if toks[j].kind == "[":
                    depth += 1
                elif toks[j].kind == "]":
                    depth -= 1
                    if depth == 0:
                        j += 1
                        break
                j += 1
        return toks[j].kind == "ident"

    def statement(self):
        t = self.tok
        start = t.start
        k = t.kind
        if k == "{":
            return self.block()
        if k == ";":
            self.advance()
            return A.Empty(Span(t.start, t.end))
        if k == "if":
            self.advance()
            self.expect("(", fix="write if (condition) ...")
            cond = self.expression()
            self.expect(")", fix="close the condition with ')'")
            then = self.sub_statement()
            other = None
            if self.accept("else"):
                other = self.sub_statement()
            return A.If(self.span_from(start), cond, then, other)
        if k == "while":
            self.advance()
            self.expect("(")
            cond = self.expression()
            self.expect(")")
            body = self.sub_statement()
            return A.While(self.span_from(start), cond, body)
        if k == "do":
            self.advance()
            body = self.sub_statement()
            self.expect("while", fix="a do loop ends with: while (condition);")
            self.expect("(")
            cond = self.expression()
            self.expect(")")
            self.expect(";")
            return A.DoWhile(self.span_from(start), body, cond)
        if k == "for":
            return self.for_statement()
        if k == "switch":
            return self.switch_statement()
        if k == "break":
            self.advance()
            self.expect(";")
            return A.Break(self.span_from(start))
        if k == "continue":
            self.advance()
            self.expect(";")
            return A.Continue(self.span_from(start))
        if k == "return":
            self.advance()
            if self.at(";"):
                self.fail("expected an expression, found ';'",
                          fix="MDL functions return a value: write 'return value;'")
            value = self.expression()
            self.expect(";", fix="end the return statement with ';'")
            return A.Return(self.span_from(start), value)
        if k in ("case", "default"):
            self.fail(f"'{k}' outside of a switch", fix="put it inside switch (value) { ... }")
        if k == "else":
            self.fail("'else' without an 'if'", fix="remove it, or add the 'if' it belongs to")
        if k in ("typedef", "struct", "enum"):
            self.fail(f"local '{k}' declarations are not supported",
                      fix="declare the type at module level")
        if self.is_declaration():
            decl = self.var_decl(start, const=bool(self.accept("const")))
            self.expect(";", fix="end the declaration with ';'")
            return A.DeclStmt(self.span_from(start), decl)
        expr = self.expression()
        self.expect(";", fix="end the statement with ';'")
        return A.ExprStmt(self.span_from(start), expr)

    def sub_statement(self):
        if self.at("}") or self.at("eof"):
            self.fail(f"expected an expression, found {self.describe(self.tok)}",
                      fix="give the branch a statement, or remove it")
        self.enter()
        try:
            return self.statement()
        finally:
            self.leave()

    def for_statement(self):
        start = self.advance().start
        self.expect("(", fix="write for (init; condition; update) ...")
        init = None
        if self.at(";"):
            self.advance()
        elif self.is_declaration():
            dstart = self.tok.start
            decl = self.var_decl(dstart, const=bool(self.accept("const")))
            self.expect(";")
            init = A.DeclStmt(self.span_from(dstart), decl)
        else:
            estart = self.tok.start
            e = self.expression()
            self.expect(";")
            init = A.ExprStmt(self.span_from(estart), e)
        cond = None if self.at(";") else self.expression()
        self.expect(";", fix="a for loop has three clauses separated by ';'")
        update = None if self.at(")") else self.expression()
        self.expect(")")
        body = self.sub_statement()
        return A.For(self.span_from(start), init, cond, update, body)

    def switch_statement(self):
        start = self.advance().start
        self.expect("(")
        value = self.expression()
        self.expect(")")
        self.expect("{")
        cases = []
        while not self.at("}"):
            cstart = self.tok.start
            if self.accept("case"):
                label = self.conditional()
            elif self.accept("default"):
                label = None
            elif self.at("eof"):
                self.fail("missing '}' at the end of the switch",
                          fix="add '}' to close the switch's '{'")
            else:
                self.fail(f"expected 'case' or 'default', found {self.describe(self.tok)}",
                          fix="statements of a switch follow a 'case VALUE:' label")
            self.expect(":", fix="a case label ends with ':'")
            stmts = []
            while not self.at("case", "default", "}"):
                if self.at("eof"):
                    self.fail("missing '}' at the end of the switch",
                              fix="add '}' to close the switch's '{'")
                stmts.append(self.statement())
            cases.append(A.Case(self.span_from(cstart), label, tuple(stmts)))
        self.advance()
        return A.Switch(self.span_from(start), value, tuple(cases))

    def var_decl(self, start: int, const: bool = False) -> A.VarDecl:
        ty = self.type_name()
        decls = []
        while True:
            dstart = self.tok.start
            name = self.ident("a name")
            annos = self.annotations() if self.at("[[") else ()
            init = ctor = None
            if self.accept("="):
                init = self.assignment()
            elif self.at("("):
                ctor = self.arguments()
            if not annos and self.at("[["):
                annos = self.annotations()
            decls.append(A.Declarator(self.span_from(dstart), name.text, init, ctor, annos,
                                      Span(name.start, name.end)))
            if not self.accept(","):
                break
        return A.VarDecl(self.span_from(start), ty, tuple(decls), const)

    # ------------------------------------------------------------------ expressions
    def expression(self):
        start = self.tok.start
        e = self.assignment()
        if self.at(","):
            items = [e]
            while self.accept(","):
                items.append(self.assignment())
            return A.Sequence(self.span_from(start), tuple(items))
        return e

    def assignment(self):
        self.enter()
        try:
            start = self.tok.start
            left = self.conditional()
            if self.tok.kind in _ASSIGN_OPS:
                op = self.advance().kind
                value = self.assignment()
                return A.Assign(self.span_from(start), op, left, value)
            return left
        finally:
            self.leave()

    def conditional(self):
        start = self.tok.start
        cond = self.binary(0)
        if self.accept("?"):
            then = self.expression()
            self.expect(":", "':' of the conditional operator",
                        fix="write condition ? value_if_true : value_if_false")
            other = self.assignment()
            return A.Conditional(self.span_from(start), cond, then, other)
        return cond

    def binary(self, level: int):
        """Precedence climbing over :data:`_BINARY` (left-associative): the operators of
        ``level`` and above, one call per operand rather than one per level."""
        start = self.tok.start
        left = self.unary()
        while (op_level := _PREC.get(self.tok.kind, -1)) >= level:
            op = self.advance().kind
            right = self.binary(op_level + 1)
            left = A.Binary(self.span_from(start), op, left, right)
        return left

    def unary(self):
        t = self.tok
        if t.kind in ("-", "+", "!", "~", "++", "--"):
            self.advance()
            self.enter()
            try:
                operand = self.unary()
            finally:
                self.leave()
            return A.Unary(self.span_from(t.start), t.kind, operand)
        if t.kind == "let":
            return self.let_expression()
        return self.postfix()

    def let_expression(self):
        start = self.advance().start
        decls = []
        braces = False
        if self.accept("{"):
            braces = True
            while not self.at("}"):
                if self.at("eof"):
                    self.fail("missing '}' to close the let block", fix="add '} in ...'")
                dstart = self.tok.start
                decls.append(self.var_decl(dstart))
                self.expect(";", fix="end each let binding with ';'")
            self.advance()
            if not decls:
                self.fail("empty let block", fix="declare at least one value, or drop 'let'")
        else:
            dstart = self.tok.start
            decls.append(self.var_decl(dstart))
            self.expect(";")
        self.expect("in", "'in' after the let bindings",
                    fix="write let { ... } in expression")
        body = self.assignment()
        return A.Let(self.span_from(start), tuple(decls), body, braces)

    def arguments(self) -> tuple[A.Argument, ...]:
        self.expect("(")
        args = []
        if self.accept(")"):
            return ()
        self.enter()
        while True:
            astart = self.tok.start
            name = None
            if self.tok.kind == "ident" and self.peek().kind == ":":
                name = self.advance().text
                self.advance()
                if self.at(",", ")"):
                    self.fail(f"expected a value for argument '{name}', found "
                              f"{self.describe(self.tok)}", fix=f"write {name}: value")
            if self.at(")") and args:
                self.fail("expected an argument after ','", fix="remove the trailing ','")
            value = self.assignment()
            args.append(A.Argument(self.span_from(astart), name, value))
            if self.accept(","):
                if self.at(")") and self.trailing_comma_ok():
                    break
                continue
            if self.at(")"):
                break
            if self.at("eof"):
                self.fail("missing ')' to close the argument list", fix="add ')'")
            self.fail(f"expected ',' or ')' in the argument list, found "
                      f"{self.describe(self.tok)}", fix="separate arguments with ','")
        self.leave()
        self.advance()
        return tuple(args)

    def array_constructor_ahead(self) -> bool:
        """``[ ... ] (`` ahead: an array type used as a constructor."""
        j, depth = self.i, 0
        toks = self.toks
        while toks[j].kind != "eof":
            if toks[j].kind == "[":
                depth += 1
            elif toks[j].kind == "]":
                depth -= 1
                if depth == 0:
                    return toks[j + 1].kind == "("
            j += 1
        return False

    def postfix(self):
        start = self.tok.start
        e = self.primary()
        while True:
            k = self.tok.kind
            if k == "(":
                args = self.arguments()
                e = A.Call(self.span_from(start), e, args)
            elif k == "[":
                if isinstance(e, A.Ref) and self.array_constructor_ahead():
                    suffix = self.array_suffix()
                    e = A.ArrayType(self.span_from(start), e.name, suffix)
                    continue
                if isinstance(e, A.Ref) and self.peek().kind == "]":
                    self.advance(), self.advance()
                    self.fail(f"expected '(' after '{e.name.text}[]', found "
                              f"{self.describe(self.tok)}",
                              fix=f"an array value is written {e.name.text}[](element, ...)")
                self.advance()
                self.enter()
                index = self.expression()
                self.leave()
                self.expect("]", fix="close the index with ']'")
                e = A.Index(self.span_from(start), e, index)
            elif k == ".":
                self.advance()
                name = self.ident("a field or component name")
                e = A.Member(self.span_from(start), e, name.text, Span(name.start, name.end))
            elif k in ("++", "--"):
                self.advance()
                e = A.Postfix(self.span_from(start), k, e)
            else:
                return e

    def primary(self):
        t = self.tok
        k = t.kind
        if k == "int":
            self.advance()
            return A.Literal(Span(t.start, t.end), "int", t.value, t.text)
        if k == "float":
            self.advance()
            value, is_double = t.value
            return A.Literal(Span(t.start, t.end), "double" if is_double else "float", value,
                             t.text)
        if k == "string":
            self.advance()
            return A.Literal(Span(t.start, t.end), "string", t.value, t.text)
        if k in ("true", "false"):
            self.advance()
            return A.Literal(Span(t.start, t.end), "bool", k == "true", t.text)
        if k in ("ident", "::"):
            name = self.qualified_name()
            return A.Ref(name.span, name)
        if k == "cast":
            self.advance()
            self.expect("<", fix="write cast<type>(value)")
            ty = self.type_name()
            self.expect(">")
            self.expect("(")
            self.enter()
            operand = self.expression()
            self.leave()
            self.expect(")")
            return A.Cast(self.span_from(t.start), ty, operand)
        if k == "(":
            self.advance()
            self.enter()
            e = self.expression()
            self.leave()
            self.expect(")", fix="close the parenthesis")
            return e
        if k == "auto":
            self.fail("'auto' is a type, not a value", fix="declare: auto x = value;")
        fix = "a value is a number, a string, a name, a call such as color(0.5), or (...)"
        if k in KEYWORDS:
            fix = f"'{k}' is a keyword of MDL; it cannot be used as a value"
        self.fail(f"expected an expression, found {self.describe(t)}", fix=fix)


def _flatten(decls):
    out = []
    for d in decls:
        if isinstance(d, tuple):
            out.extend(d)
        else:
            out.append(d)
    return tuple(out)


def _with_recursion(f):
    limit = sys.getrecursionlimit()
    if limit < 20 * MAX_DEPTH:
        sys.setrecursionlimit(20 * MAX_DEPTH)
    try:
        return f()
    finally:
        sys.setrecursionlimit(limit)


def parse_module(src: Source) -> A.Module:
    """Parse a whole module.

    Raises
    ------
    MdlError
        With every syntax error found (at most :data:`~mdl.diagnostics.MAX_ERRORS`).
    """
    p = _Parser(src)
    module = _with_recursion(p.module)
    if p.errors:
        raise MdlError(p.errors[:MAX_ERRORS])
    return A.Module(module.span, module.version, _flatten(module.decls))


def parse_expression(src: Source) -> A.Expr:
    """Parse one expression (a material call as a scene writes it).

    Raises
    ------
    MdlError
        A syntax error, or text after the expression.
    """
    p = _Parser(src)

    def run():
        if p.at("eof"):
            p.fail("empty expression", fix="write a call such as glossy()")
        e = p.expression()
        if not p.at("eof"):
            p.fail(f"unexpected {p.describe(p.tok)} after the expression",
                   fix="an expression is one value or call; remove what follows")
        return e

    return _with_recursion(run)
