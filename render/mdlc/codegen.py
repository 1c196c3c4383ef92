"""MDL function bodies as generated Python that runs over lanes (SPMD, numpy).

Each checked module becomes one generated Python module: every MDL function a Python
function ``f(S, L, *params)`` over the ``L`` lanes of a shading state ``S``, every
struct a constructor that fills in its fields' defaults.  Values are the lane arrays of
:mod:`mdl.lanes` (uniform values have one lane and broadcast).  Operators, ``::math``
and the built-in constructors call the same functions the front end folds constants
with (:mod:`mdl.lanes`, :mod:`mdl.mathlib`, :mod:`mdl.construct`); ``::state``, ``::tex``
and natives are :mod:`render.mdlc.rt`.

Control flow follows the checker's variability analysis, as an SPMD compiler (ISPC)
does with MDL's ``uniform``/``varying``:

* a uniform condition is a Python ``if``/``while``: no masks;
* under a varying condition the code runs with an execution *mask*: assignments keep
  the old value on inactive lanes (``sel``), calls run on the active lanes only
  (``mcall``: their arguments and state gathered, results scattered back);
* ``break``, ``continue`` and ``return`` under varying control clear lanes from the
  loop's or the function's live mask; a loop runs while any lane is still in it, and
  a function whose lanes have all returned stops;
* ``switch`` computes the entry case per lane; cases fall through as in C.

Values have value semantics: writes to a component, field or element build a new
value (``set_component``, ``set_field``, ``set_index``), so no two variables share a
buffer.  Assignments inside an operand of ``?:``, ``&&`` or ``||`` are refused (they
would run unconditionally).
"""

from __future__ import annotations

import itertools

import numpy as np

from mdl import ast as A
from mdl import lanes as LN
from mdl import types as T
from mdl.checker import Checker, is_material_level
from mdl.diagnostics import MdlError
from mdl.entities import (
    UNIFORM,
    ConstEntity,
    EnumValueEntity,
    ExprInfo,
    Local,
    Overload,
    SizeName,
)

__all__ = ["ModuleGen", "CodegenError", "lane_expression_source", "RESOURCES"]

#: the resources the workbench reads (``texture_2d("f.png")``, ``bsdf_measurement("f.mbsdf")``,
#: ``light_profile("f.ies")``)
RESOURCES = ("texture_2d", "bsdf_measurement", "light_profile")

_BINOPS = {"+": "LN.add", "-": "LN.sub", "*": "LN.mul", "/": "LN.div", "%": "LN.mod",
           "==": "LN.eq", "!=": "LN.ne", "<": "LN.lt", "<=": "LN.le", ">": "LN.gt",
           ">=": "LN.ge", "&": "LN.band", "|": "LN.bor", "^": "LN.bxor", "<<": "LN.shl",
           ">>": "LN.shr", ">>>": "LN.ushr"}
_DTYPE = {np.int32: "np.int32", np.float64: "np.float64", np.bool_: "np.bool_"}


class CodegenError(Exception):
    """A construct the back end cannot compile; ``node`` locates it."""

    def __init__(self, message: str, node, fix: str = ""):
        super().__init__(message)
        self.message, self.node, self.fix = message, node, fix


class ModuleGen:
    """Collects the generated source of one module and its tables (constants, types,
    natives, resources, imported modules)."""

    def __init__(self, module, session):
        self.module = module
        self.session = session
        self.lines: list[str] = []
        self.consts: list = []
        self._const_ids: dict = {}
        self.types: list = []
        self._type_ids: dict = {}
        self.natives: list = []
        self._native_ids: dict = {}
        self.resources: list = []
        self.mods: dict[str, object] = {}
        self.counter = itertools.count()

    # ------------------------------------------------------------------ tables
    def const(self, value) -> str:
        key = id(value)
        if key not in self._const_ids:
            self._const_ids[key] = len(self.consts)
            self.consts.append(value)
        return f"_K[{self._const_ids[key]}]"

    def type_ref(self, t: T.Type) -> str:
        key = id(t) if isinstance(t, (T.StructType, T.EnumType)) else str(t)
        if key not in self._type_ids:
            self._type_ids[key] = len(self.types)
            self.types.append(t)
        return f"_T[{self._type_ids[key]}]"

    def zero_ref(self, t: T.Type) -> str:
        return f"_Z({self.type_ref(t)})"

    def native_ref(self, overload: Overload) -> str:
        key = id(overload)
        if key not in self._native_ids:
            self._native_ids[key] = len(self.natives)
            self.natives.append(overload)
        return f"_N[{self._native_ids[key]}]"

    def resource_ref(self, kind: str, name: str, gamma: str | None) -> str:
        self.resources.append((kind, name, gamma))
        return f"_res({len(self.resources) - 1})"

    def function_ref(self, o: Overload) -> str:
        if o.module is self.module:
            return _pyname(o)
        q = o.module.qname
        self.mods[q] = o.module
        return f"_M[{q!r}].{_pyname(o)}"

    # ------------------------------------------------------------------ module
    def generate(self) -> str:
        out = [f"# generated from MDL module {self.module.qname} (key {self.module.key})", ""]
        for o in self.module.overloads:
            if o.module is not self.module:
                continue
            if o.kind == "struct" and not is_material_level(o.ret):
                out += _FunctionGen(self, o).struct_ctor()
            elif o.kind == "mdl" and not o.is_material and o.decl is not None and \
                    o.decl.body is not None and not _touches_material_level(o):
                try:
                    out += _FunctionGen(self, o).function()
                except CodegenError as e:
                    raise _located(self.module, e) from None
        return "\n".join(out) + "\n"


def _touches_material_level(o: Overload) -> bool:
    return is_material_level(o.ret) or any(is_material_level(p.type) for p in o.params)


def _located(module, e: CodegenError) -> MdlError:
    span = e.node.span if hasattr(e.node, "span") else e.node
    return MdlError([module.source.diagnostic("error", e.message, span.start, span.end,
                                              e.fix)])


def _pyname(o: Overload) -> str:
    prefix = "ctor_" if o.kind == "struct" else "f_"
    return prefix + o.mangled


class _FunctionGen:
    """Emits one function (or a lane expression) into Python source lines."""

    def __init__(self, mg: ModuleGen, o: Overload | None):
        self.mg = mg
        self.module = mg.module
        self.o = o
        self.lines: list[str] = []
        self.depth = 1
        self.mask: str | None = None        # the current execution mask (a variable)
        self.static: list[str] = []          # masks of enclosing varying branches
        self.live = None                     # "_live" when returns vary
        self.loops: list[dict] = []
        self.switches: list[dict] = []
        self.dirty = False
        self.names: dict[int, str] = {}      # id(Local) -> python name
        self.inputs: dict[int, str] = {}     # id(node) -> python name (lane expressions)
        self.in_conditional = 0

    # ------------------------------------------------------------------ emitting
    def emit(self, line: str) -> None:
        self.lines.append("    " * self.depth + line)

    def tmp(self, prefix: str = "t") -> str:
        return f"_{prefix}{next(self.mg.counter)}"

    def info(self, e) -> ExprInfo:
        i = self.module.info.get(id(e))
        if i is None:
            raise CodegenError("internal: expression was not checked", e,
                               "a bug of the workbench: please report it with the module")
        return i

    def local_name(self, loc: Local) -> str:
        if id(loc) not in self.names:
            base = loc.pyname or ("v_" + loc.name)
            self.names[id(loc)] = f"{base}_{next(self.mg.counter)}"
        return self.names[id(loc)]

    # ------------------------------------------------------------------ masks
    def dynamic_terms(self) -> list[str]:
        terms = []
        if self.live is not None:
            terms.append(self.live)
        for lp in self.loops:
            if lp.get("brk"):
                terms.append("~" + lp["brk"])
        if self.loops and self.loops[-1].get("cnt"):
            terms.append("~" + self.loops[-1]["cnt"])
        for sw in self.switches:
            if sw.get("brk"):
                terms.append("~" + sw["brk"])
        return terms

    def refresh_mask(self) -> None:
        """Recompute the mask variable from the branch mask and the dynamic flags."""
        terms = ([self.static[-1]] if self.static else []) + self.dynamic_terms()
        if not terms:
            self.mask = None
        else:
            name = self.tmp("m")
            self.emit(f"{name} = {' & '.join(terms) if len(terms) > 1 else terms[0]}")
            self.mask = name
        self.dirty = False

    def current_mask(self) -> str | None:
        if self.dirty:
            self.refresh_mask()
        return self.mask

    # ------------------------------------------------------------------ functions
    def header(self) -> list[str]:
        o = self.o
        params = []
        for p in o.params:
            params.append(f"p_{p.name}" + ("=None" if p.default is not None else ""))
        return [f"def {_pyname(o)}(S, L{''.join(', ' + x for x in params)}):"]

    def bind_params(self) -> None:
        o = self.o
        d = o.decl
        scope_params = d.params if isinstance(d, A.FunctionDecl) else None
        for k, p in enumerate(o.params):
            loc = self.module.locals.get(id(scope_params[k])) if scope_params else None
            if loc is not None:
                self.names[id(loc)] = f"p_{p.name}"
        for name, sv in o.sizevars.items():
            owner = next((p for p in o.params if p.sizevar is sv), None)
            if owner is not None:
                self.emit(f"n_{name} = size_of(p_{owner.name})")
        for p in o.params:
            if p.default is not None:
                self.emit(f"if p_{p.name} is None:")
                self.depth += 1
                self.emit(f"p_{p.name} = {self.expr_conv(p.default, p.type)}")
                self.depth -= 1

    def function(self) -> list[str]:
        o = self.o
        d: A.FunctionDecl = o.decl
        self.bind_params()
        if isinstance(d.body, A.Block):
            self.live = "_live" if _varying_returns(self.module, d.body) else None
            if self.live:
                self.emit(f"_ret = {self.mg.zero_ref(o.ret)}(L)")
                self.emit("_live = np.ones(L, dtype=bool)")
            for s in d.body.stmts:
                self.stmt(s)
            if self.live:
                self.emit("return _ret")
            else:
                self.emit(f"return {self.mg.zero_ref(o.ret)}(1)")
        else:
            self.emit(f"return {self.expr_conv(d.body, o.ret)}")
        return self.header() + self.lines + [""]

    def struct_ctor(self) -> list[str]:
        o = self.o
        st: T.StructType = o.ret
        self.depth = 1
        for f, p in zip(st.fields, o.params, strict=True):
            self.emit(f"if p_{p.name} is None:")
            self.depth += 1
            if f.default is not None:
                self.emit(f"p_{p.name} = {self.expr_conv(f.default, f.type)}")
            else:
                self.emit(f"p_{p.name} = {self.mg.zero_ref(f.type)}(1)")
            self.depth -= 1
        fields = ", ".join(f"p_{p.name}" for p in o.params)
        self.emit(f"return ({fields}{',' if len(o.params) == 1 else ''})")
        params = ", ".join(f"p_{p.name}=None" for p in o.params)
        return [f"def {_pyname(o)}(S, L{', ' + params if params else ''}):"] + self.lines + [""]

    # ------------------------------------------------------------------ statements
    def stmt(self, s) -> None:
        m = getattr(self, "s_" + type(s).__name__)
        m(s)

    def s_Block(self, s: A.Block) -> None:
        for x in s.stmts:
            self.stmt(x)

    def s_Empty(self, s) -> None:
        pass

    def s_ExprStmt(self, s: A.ExprStmt) -> None:
        e = s.expr
        if isinstance(e, A.Sequence):
            for x in e.items:
                self.effect(x)
        else:
            self.effect(e)

    def effect(self, e) -> None:
        """An expression evaluated for its effect."""
        if isinstance(e, A.Assign):
            self.assign(e)
        elif isinstance(e, (A.Postfix, A.Unary)) and e.op in ("++", "--"):
            self.increment(e.operand, e.op, e)
        elif isinstance(e, A.Call):
            code = self.expr(e)
            self.emit(code)
        else:
            self.emit(self.expr(e))

    def s_DeclStmt(self, s: A.DeclStmt) -> None:
        self.declare(s.decl)

    def declare(self, d: A.VarDecl) -> None:
        for dc in d.declarators:
            loc: Local = self.module.locals[id(dc)]
            name = self.local_name(loc)
            if dc.ctor_args is not None:
                code = self.expr_node_info(dc)
            elif dc.init is not None:
                code = self.expr_conv(dc.init, loc.type)
            else:
                code = self.default(loc.type, dc)
            self.emit(f"{name} = {code}")

    def default(self, t: T.Type, where) -> str:
        info = self.module.info.get(id(where))
        if info is not None and info.call is not None and info.call.kind == "overload":
            return self.call_code(where, info)
        if isinstance(t, T.ArrayT) and t.sizevar is not None:
            return f"LN.zeros({self.mg.type_ref(t)}, 1, int(n_{t.sizevar.name}[0]))"
        return f"{self.mg.zero_ref(t)}(1)"

    def s_If(self, s: A.If) -> None:
        ci = self.info(s.cond)
        cond = self.expr(s.cond)
        if ci.level == UNIFORM:
            self.emit(f"if LN.as_bool({cond}):")
            self.block(s.then)
            if s.other is not None:
                self.emit("else:")
                self.block(s.other)
            self.dirty = self.dirty or _has_exit(s)
            return
        c = self.tmp("c")
        self.emit(f"{c} = np.broadcast_to({cond}, (L,))")
        base = self.current_mask()
        for branch, neg in ((s.then, False), (s.other, True)):
            if branch is None:
                continue
            m = self.tmp("b")
            term = f"~{c}" if neg else c
            self.emit(f"{m} = {term}" if base is None else f"{m} = {base} & {term}")
            self.emit(f"if {m}.any():")
            self.depth += 1
            self.static.append(m)
            saved = self.mask
            self.mask = m
            self.dirty = False
            self.stmt(branch)
            self.static.pop()
            self.mask = saved
            self.depth -= 1
            if _has_exit(branch):
                self.dirty = True
                base = self.current_mask()
        self.dirty = self.dirty or _has_exit(s)

    def block(self, s) -> None:
        self.depth += 1
        saved = self.mask, self.dirty
        start = len(self.lines)
        self.stmt(s)
        if len(self.lines) == start:
            self.emit("pass")
        self.mask, self.dirty = saved[0], saved[1] or self.dirty
        self.depth -= 1

    def loop_is_varying(self, s) -> bool:
        cond = getattr(s, "cond", None)
        if cond is not None and self.info(cond).level > UNIFORM:
            return True
        return _varying_exit(self.module, s.body, loop=True)

    def s_While(self, s: A.While) -> None:
        self.loop(s, s.cond, s.body, None, do=False)

    def s_DoWhile(self, s: A.DoWhile) -> None:
        self.loop(s, s.cond, s.body, None, do=True)

    def s_For(self, s: A.For) -> None:
        if s.init is not None:
            self.stmt(s.init)
        self.loop(s, s.cond, s.body, s.update, do=False)

    def loop(self, s, cond, body, update, do: bool) -> None:
        varying = self.loop_is_varying(s)
        frame = {"varying": varying, "update": update, "cond": cond if do else None,
                 "brk": None, "cnt": None}
        if varying:
            frame["brk"] = self.tmp("brk")
            self.emit(f"{frame['brk']} = np.zeros(L, dtype=bool)")
            if _has_continue(body):
                frame["cnt"] = self.tmp("cnt")
        self.emit("while True:")
        self.depth += 1
        self.loops.append(frame)
        saved = self.mask
        cnt = frame["cnt"]
        frame["cnt"] = None  # the condition and the update see no 'continue' flag
        if varying:
            self.refresh_mask()
            self.emit(f"if {self.mask} is not None and not {self.mask}.any():")
            self.emit("    break")
        if cond is not None and not do:
            self.loop_condition(cond, frame)
        if cnt is not None:
            frame["cnt"] = cnt
            self.emit(f"{cnt} = np.zeros(L, dtype=bool)")
            self.refresh_mask()
        else:
            self.dirty = True
        self.stmt(body)
        frame["cnt"] = None
        self.dirty = True
        if update is not None:
            self.effect_all(update)
        if do and cond is not None:
            self.loop_condition(cond, frame)
        self.loops.pop()
        self.mask = saved
        self.depth -= 1
        self.dirty = True

    def effect_all(self, e) -> None:
        if isinstance(e, A.Sequence):
            for x in e.items:
                self.effect(x)
        else:
            self.effect(e)

    def loop_condition(self, cond, frame) -> None:
        c = self.expr(cond)
        if self.info(cond).level == UNIFORM:
            self.emit(f"if not LN.as_bool({c}):")
            self.emit("    break")
            return
        m = self.current_mask()
        c2 = self.tmp("c")
        self.emit(f"{c2} = np.broadcast_to({c}, (L,))")
        self.emit(f"{frame['brk']} = {frame['brk']} | ~{c2}" if m is None else
                  f"{frame['brk']} = {frame['brk']} | ({m} & ~{c2})")
        self.refresh_mask()
        self.emit(f"if {self.mask} is not None and not {self.mask}.any():")
        self.emit("    break")

    def s_Break(self, s) -> None:
        m = self.current_mask()
        if self.switches and (not self.loops or self.switches[-1]["depth"] > self.loops[-1].get(
                "depth", -1)):
            sw = self.switches[-1]
            if sw["brk"] is None:
                self.emit("break")
            else:
                self.emit(f"{sw['brk']} = {sw['brk']} | {m or 'True'}")
                self.dirty = True
            return
        lp = self.loops[-1]
        if lp["brk"] is None or (m is None and not self.static):
            self.emit("break")
        else:
            self.emit(f"{lp['brk']} = {lp['brk']} | {m}")
            self.dirty = True

    def s_Continue(self, s) -> None:
        lp = self.loops[-1]
        m = self.current_mask()
        if lp["cnt"] is None or (m is None and not self.static):
            if lp["update"] is not None:
                self.effect_all(lp["update"])
            if lp["cond"] is not None:  # do-while: the condition comes first
                self.loop_condition(lp["cond"], lp)
            self.emit("continue")
        else:
            self.emit(f"{lp['cnt']} = {lp['cnt']} | {m}")
            self.dirty = True

    def s_Return(self, s: A.Return) -> None:
        value = self.expr_conv(s.value, self.o.ret)
        m = self.current_mask()
        if self.live is None or (m is None and not self.static and not self.loops):
            if self.live is not None:
                self.emit(f"return LN.sel({self.live}, {value}, _ret)")
            else:
                self.emit(f"return {value}")
            return
        if m is None:
            m = self.live
        self.emit(f"_ret = LN.sel({m}, {value}, _ret)")
        self.emit(f"{self.live} = {self.live} & ~{m}")
        self.emit(f"if not {self.live}.any():")
        self.emit("    return _ret")
        self.dirty = True

    def s_Switch(self, s: A.Switch) -> None:
        vi = self.info(s.value)
        v = self.expr(s.value)
        labels = []
        default = None
        for k, c in enumerate(s.cases):
            if c.value is None:
                default = k
            else:
                li = self.info(c.value)
                labels.append((k, int(LN.uniform_value(li.const))))
        n = len(s.cases)
        e = self.tmp("e")
        sv = self.tmp("sv")
        self.emit(f"{sv} = {v}")
        if vi.level == UNIFORM:
            chain = " else ".join(f"{k} if LN.uniform_value({sv}) == {val}"
                                  for k, val in labels)
            fallback = default if default is not None else n
            self.emit(f"{e} = {chain + ' else ' if chain else ''}{fallback}")
            self.emit("for _sw in (0,):")
            self.depth += 1
            frame = {"brk": None, "depth": len(self.loops)}
            self.switches.append(frame)
            for k, c in enumerate(s.cases):
                self.emit(f"if {e} <= {k}:")
                self.depth += 1
                start = len(self.lines)
                for x in c.stmts:
                    self.stmt(x)
                if len(self.lines) == start:
                    self.emit("pass")
                self.depth -= 1
            self.switches.pop()
            self.depth -= 1
            self.dirty = True
            return
        # varying switch value: the entry case per lane
        fallback = default if default is not None else n
        conds = ", ".join(f"np.broadcast_to({sv} == {val}, (L,))" for _, val in labels)
        ks = ", ".join(str(k) for k, _ in labels)
        self.emit(f"{e} = np.select([{conds}], [{ks}], {fallback})" if labels else
                  f"{e} = np.full(L, {fallback})")
        brk = self.tmp("swb")
        self.emit(f"{brk} = np.zeros(L, dtype=bool)")
        frame = {"brk": brk, "depth": len(self.loops)}
        self.switches.append(frame)
        base = self.current_mask()
        for k, c in enumerate(s.cases):
            m = self.tmp("b")
            term = f"({e} <= {k}) & ~{brk}"
            self.emit(f"{m} = {term}" if base is None else f"{m} = {base} & {term}")
            self.emit(f"if {m}.any():")
            self.depth += 1
            self.static.append(m)
            saved = self.mask
            self.mask = m
            self.dirty = False
            start = len(self.lines)
            for x in c.stmts:
                self.stmt(x)
            if len(self.lines) == start:
                self.emit("pass")
            self.static.pop()
            self.mask = saved
            self.depth -= 1
            if _has_exit(A.Block(c.span, c.stmts)):
                self.dirty = True
                base = self.current_mask()
        self.switches.pop()
        self.dirty = True

    # ------------------------------------------------------------------ assignment
    def assign(self, e: A.Assign) -> str:
        info = self.info(e)
        ti = self.info(e.target)
        if e.op == "=":
            value = self.expr_conv(e.value, ti.type)
        else:
            lt, vt, rt = info.target
            cur = self.conv_code(self.lvalue_read(e.target), ti.type, lt)
            rhs = self.expr(e.value)
            value = self.binop(e.op[:-1], cur, rhs, lt, vt, e)
            value = self.conv_code(value, rt, ti.type)
        return self.store(e.target, value)

    def increment(self, target, op: str, node) -> str:
        ti = self.info(target)
        one = self.mg.const(LN.const(ti.type, 1))
        value = self.binop("+" if op == "++" else "-", self.lvalue_read(target), one, ti.type,
                           ti.type, node)
        return self.store(target, value)

    def lvalue_read(self, target) -> str:
        return self.expr(target)

    def store(self, target, value: str) -> str:
        """Write ``value`` to an l-value under the current mask; returns the variable."""
        m = self.current_mask()
        path = []
        node = target
        while isinstance(node, (A.Member, A.Index)):
            path.append(node)
            node = node.obj
        root = self.info(node).target
        var = self.local_name(root) if isinstance(root, Local) else None
        if var is None:
            raise CodegenError("cannot assign to this expression", target,
                               "assign to a variable, a field, a component or an element")
        if not path:
            self.emit(f"{var} = {value}" if m is None else f"{var} = LN.sel({m}, {value}, {var})")
            return var
        path.reverse()
        # read the containers along the path, innermost last
        containers = [var]
        accessors = []
        for p in path:
            if isinstance(p, A.Index):
                idx = self.tmp("i")
                self.emit(f"{idx} = {self.expr_conv(p.index, T.INT)}")
                accessors.append(("index", idx))
            else:
                k = self.info(p).target
                if isinstance(k, tuple):
                    accessors.append(("comp", k))
                else:
                    accessors.append(("field", k))
        for kind, a in accessors[:-1]:
            c = self.tmp("p")
            self.emit(f"{c} = {self.access(containers[-1], kind, a)}")
            containers.append(c)
        new = value
        for depth in range(len(accessors) - 1, -1, -1):
            kind, a = accessors[depth]
            mask = m if depth == len(accessors) - 1 else None
            new = self.update(containers[depth], kind, a, new, mask)
            if depth:
                t = self.tmp("u")
                self.emit(f"{t} = {new}")
                new = t
        self.emit(f"{var} = {new}")
        return var

    def access(self, obj: str, kind: str, a) -> str:
        if kind == "index":
            return f"LN.index({obj}, {a})"
        if kind == "field":
            return f"{obj}[{a}]"
        if len(a) == 1:
            return f"{obj}[:, {a[0]}]"
        return f"LN.swizzle({obj}, {a!r})"

    def update(self, obj: str, kind: str, a, value: str, mask) -> str:
        m = mask if mask is not None else "None"
        if kind == "index":
            return f"LN.set_index({obj}, {a}, {value}, {m})"
        if kind == "field":
            return f"LN.set_field({obj}, {a}, {value}, {m})"
        if len(a) == 1:
            return f"LN.set_component({obj}, {a[0]}, {value}, {m})"
        return f"LN.set_swizzle({obj}, {a!r}, {value}, {m})"

    # ------------------------------------------------------------------ expressions
    def expr_conv(self, e, t: T.Type) -> str:
        """``e``'s value converted to ``t``."""
        info = self.info(e)
        code = self.expr(e, skip_convert=True)
        src = info.type
        return self.conv_code(code, src, t)

    def conv_code(self, code: str, src: T.Type, dst: T.Type) -> str:
        if src == dst or not _lane_type(dst) or not _lane_type(src):
            return code
        dsrc, ddst = LN.dtype(src), LN.dtype(dst)
        if dsrc == ddst:
            return code
        return f"cv({code}, {_DTYPE[ddst]})"

    def expr(self, e, skip_convert: bool = False) -> str:
        info = self.info(e)
        if id(e) in self.inputs:
            code = self.inputs[id(e)]
        elif info.const is not None and _lane_type(info.type) and not _has_side_effects(e):
            code = self.mg.const(info.const)
        else:
            code = getattr(self, "e_" + type(e).__name__)(e, info)
        if info.convert is not None and not skip_convert:
            code = self.conv_code(code, info.type, info.convert)
        return code

    def expr_node_info(self, node) -> str:
        info = self.module.info[id(node)]
        if info.const is not None and _lane_type(info.type):
            return self.mg.const(info.const)
        return self.call_code(node, info)

    def e_Literal(self, e, info) -> str:
        if e.kind == "string":
            return repr(e.value)
        return self.mg.const(info.const)

    def e_Ref(self, e, info) -> str:
        t = info.target
        if isinstance(t, Local):
            if id(t) in self.names:
                return self.names[id(t)]
            if t.const and t.value is not None:
                return self.mg.const(t.value)
            return self.local_name(t)
        if isinstance(t, SizeName):
            return f"n_{t.var.name}"
        if isinstance(t, ConstEntity):
            if t.value is None:
                raise CodegenError(f"constant '{t.name}' has no value", e,
                                   "give the constant a value that folds")
            return self.mg.const(t.value) if _lane_type(t.type) or isinstance(
                t.type, (T.ArrayT, T.StructType)) else repr(t.value)
        if isinstance(t, EnumValueEntity):
            return self.mg.const(LN.const(t.enum, t.value))
        raise CodegenError(f"'{e.name.text}' cannot be used in a function", e,
                           "use a value, a constant or a call here")

    def e_Sequence(self, e, info) -> str:
        for x in e.items[:-1]:
            self.effect(x)
        return self.expr(e.items[-1])

    def e_Assign(self, e, info) -> str:
        if self.in_conditional:
            raise CodegenError("an assignment inside an operand of '?:', '&&' or '||' is not "
                               "supported", e, "assign in a statement before the expression")
        return self.assign(e)

    def e_Postfix(self, e, info) -> str:
        if self.in_conditional:
            raise CodegenError(f"'{e.op}' inside an operand of '?:', '&&' or '||' is not "
                               "supported", e, "increment in a statement of its own")
        old = self.tmp("o")
        self.emit(f"{old} = {self.expr(e.operand)}")
        self.increment(e.operand, e.op, e)
        return old

    def e_Unary(self, e, info) -> str:
        if e.op in ("++", "--"):
            if self.in_conditional:
                raise CodegenError(f"'{e.op}' inside an operand of '?:', '&&' or '||' is not "
                                   "supported", e, "increment in a statement of its own")
            return self.increment(e.operand, e.op, e)
        a = self.expr(e.operand)
        return {"-": f"LN.neg({a})", "+": a, "!": f"LN.lnot({a})", "~": f"LN.bnot({a})"}[e.op]

    def binop(self, op: str, a: str, b: str, lt: T.Type, rt: T.Type, node) -> str:
        if op == "*" and (isinstance(lt, T.Matrix) or isinstance(rt, T.Matrix)):
            if isinstance(lt, T.Matrix) and isinstance(rt, T.Matrix):
                return f"LN.matmul({a}, {b}, ('m', 'm'))"
            if isinstance(lt, T.Matrix) and isinstance(rt, T.Vector):
                return f"LN.matmul({a}, {b}, ('m', 'v'))"
            if isinstance(lt, T.Vector) and isinstance(rt, T.Matrix):
                return f"LN.matmul({a}, {b}, ('v', 'm'))"
        return f"{_BINOPS[op]}({a}, {b})"

    def e_Binary(self, e: A.Binary, info) -> str:
        lt, rt = info.target
        if e.op in ("&&", "||"):
            li = self.info(e.left)
            a = self.tmp("l")
            self.emit(f"{a} = {self.expr(e.left)}")
            self.in_conditional += 1
            try:
                if li.level == UNIFORM:
                    b = self.expr(e.right)
                    if e.op == "&&":
                        return f"({b} if LN.as_bool({a}) else {a})"
                    return f"({a} if LN.as_bool({a}) else {b})"
                m = self.current_mask()
                sub = self.tmp("m")
                term = a if e.op == "&&" else f"~{a}"
                self.emit(f"{sub} = {term}" if m is None else f"{sub} = {m} & {term}")
                b = self.under_mask(sub, e.right)
            finally:
                self.in_conditional -= 1
            return f"LN.land({a}, {b})" if e.op == "&&" else f"LN.lor({a}, {b})"
        a = self.expr(e.left)
        b = self.expr(e.right)
        return self.binop(e.op, a, b, lt, rt, e)

    def under_mask(self, mask: str, e) -> str:
        saved = self.mask, self.dirty
        self.mask, self.dirty = mask, False
        self.static.append(mask)
        try:
            return self.expr(e)
        finally:
            self.static.pop()
            self.mask, self.dirty = saved

    def e_Conditional(self, e: A.Conditional, info) -> str:
        ci = self.info(e.cond)
        c = self.tmp("q")
        self.emit(f"{c} = {self.expr(e.cond)}")
        self.in_conditional += 1
        try:
            if ci.level == UNIFORM:
                a = self.expr(e.then)
                b = self.expr(e.other)
                return f"({a} if LN.as_bool({c}) else {b})"
            m = self.current_mask()
            ma, mb = self.tmp("m"), self.tmp("m")
            self.emit(f"{ma} = {c}" if m is None else f"{ma} = {m} & {c}")
            self.emit(f"{mb} = ~{c}" if m is None else f"{mb} = {m} & ~{c}")
            a = self.under_mask(ma, e.then)
            b = self.under_mask(mb, e.other)
        finally:
            self.in_conditional -= 1
        return f"LN.sel({c}, {a}, {b})"

    def e_Member(self, e: A.Member, info) -> str:
        a = self.expr(e.obj)
        k = info.target
        if isinstance(k, tuple):
            return f"{a}[:, {k[0]}]" if len(k) == 1 else f"LN.swizzle({a}, {k!r})"
        return f"{a}[{k}]"

    def e_Index(self, e: A.Index, info) -> str:
        return f"LN.index({self.expr(e.obj)}, {self.expr_conv(e.index, T.INT)})"

    def e_Let(self, e: A.Let, info) -> str:
        for d in e.decls:
            self.declare(d)
        return self.expr(e.body)

    def e_Cast(self, e: A.Cast, info) -> str:
        return self.expr(e.operand)

    def e_Call(self, e: A.Call, info) -> str:
        return self.call_code(e, info)

    # ------------------------------------------------------------------ calls
    def arg_codes(self, call, params) -> list[str]:
        out = []
        for a, p in zip(call.args, params, strict=True):
            if a is None:
                out.append("None")
            else:
                t = Checker.bind_sizes(p.type, call.sizes)
                out.append(self.expr_conv(a, t) if _lane_type(t) else self.expr(a))
        return out

    def call_code(self, e, info) -> str:
        call = info.call
        kind = call.kind
        if kind in ("vector", "color", "matrix", "scalar", "color_spectrum"):
            vals = [self.expr(a, skip_convert=True) for a in call.args]
            types = [self.mg.type_ref(self.info(a).type) for a in call.args]
            return (f"construct({kind!r}, {self.mg.type_ref(call.type)}, [{', '.join(vals)}], "
                    f"[{', '.join(types)}])")
        if kind == "array":
            elem = call.type.elem
            vals = [self.expr_conv(a, elem) for a in call.args]
            if not vals:
                n = call.type.size or 0
                return f"LN.zeros({self.mg.type_ref(call.type)}, 1, {n})"
            return f"array_of([{', '.join(vals)}], {isinstance(elem, T.StructType)})"
        if kind == "resource":
            name_node, gamma_node = call.args
            if name_node is None:
                return "None"
            if str(call.type) not in RESOURCES:
                raise CodegenError(f"{call.type} resources are not supported by the workbench "
                                   "(2D textures, measured BSDFs and light profiles only)", e,
                                   "use a texture_2d")
            name = self.info(name_node).const
            gamma = None
            if gamma_node is not None:
                gamma = LN.to_python(self.info(gamma_node).const, self.info(gamma_node).type)
            return self.mg.resource_ref(str(call.type), name, gamma)
        if kind == "df_default":
            raise CodegenError("distribution functions exist only in materials", e,
                               "build the df in a material's expression")
        o: Overload = call.target
        args = self.arg_codes(call, o.params)
        zero = self.mg.zero_ref(info.type)
        if o.kind == "intrinsic":
            return self.intrinsic(o, args, e, info)
        if o.kind == "native":
            ref = self.mg.native_ref(o)
            m = self.current_mask() if info.level > UNIFORM else None
            return f"ncall({ref}, {m}, S, L, {zero}, {', '.join(args)})"
        if o.kind in ("mdl", "struct"):
            if o.is_material or _touches_material_level(o):
                raise CodegenError(f"'{o.name}' works on materials and cannot be called in "
                                   "a function", e, "call it in a material's expression")
            f = self.mg.function_ref(o)
            if info.level == UNIFORM and not o.reads_state:
                return f"{f}(S, 1{''.join(', ' + a for a in args)})"
            m = self.current_mask()
            if m is None:
                return f"{f}(S, L{''.join(', ' + a for a in args)})"
            return f"mcall({f}, {m}, S, L, {zero}{''.join(', ' + a for a in args)})"
        raise CodegenError(f"cannot call '{o.name}' here", e,
                           "call it in a material's expression")

    def intrinsic(self, o: Overload, args: list[str], e, info) -> str:
        mod = o.module.qname
        name = o.name
        if mod == "::math":
            fname = {"abs": "abs_", "all": "all_", "any": "any_", "max": "max_", "min": "min_",
                     "pow": "pow_", "round": "round_"}.get(name, name)
            return f"MATH.{fname}({', '.join(args)})"
        where = self.where(e)
        if mod == "::state":
            return f"STATE.{name}(S, L{''.join(', ' + a for a in args)})"
        if mod == "::tex":
            m = self.current_mask() if info.level > UNIFORM else None
            zero = self.mg.zero_ref(info.type)
            if name.startswith("lookup_"):
                k = {"float": 1, "float2": 2, "float3": 3, "float4": 4, "color": 3}[
                    name.removeprefix("lookup_")]
                if str(o.params[0].type) != "texture_2d":
                    raise CodegenError(f"tex::{name} of a {o.params[0].type} is not supported "
                                       "by the workbench (2D textures only)", e,
                                       "use a texture_2d")
                fill = [a if a != "None" else d for a, d in zip(
                    args, ["None", "None", "1", "1", "(0.0, 1.0)", "(0.0, 1.0)", "0.0"],
                    strict=False)]
                return f"ncall(_lookup{k}, {m}, S, L, {zero}, {', '.join(fill)})"
            if name.startswith("texel_"):
                k = {"float": 1, "float2": 2, "float3": 3, "float4": 4, "color": 3}[
                    name.removeprefix("texel_")]
                return f"TEX.texel({k}, S, L, {', '.join(args)})"
            if name in ("width", "height", "depth", "texture_isvalid"):
                return f"TEX.{name}(S, L, {args[0]})"
        if mod == "::debug":
            fname = {"assert": "assert_", "print": "print_", "breakpoint": "breakpoint_"}[name]
            m = self.current_mask()
            zero = self.mg.zero_ref(info.type)
            return (f"ncall(lambda S, L, *a: DEBUG.{fname}({where!r}, S, L, *a), {m}, S, L, "
                    f"{zero}{''.join(', ' + a for a in args)})")
        if mod == "::scene":
            if name == "data_isvalid":
                return f"SCENE.data_isvalid(S, L, {args[0]})"
            default = args[1] if args[1] != "None" else f"{self.mg.zero_ref(info.type)}(1)"
            return f"SCENE.lookup(S, L, {args[0]}, {default})"
        raise CodegenError(f"{mod}::{name} is not implemented by the workbench", e,
                           "see docs/mdl.md for what the workbench implements")

    def where(self, e) -> str:
        line, col = self.module.source.line_col(e.span.start)
        return f"{self.module.source.name}:{line}:{col}"


# ----------------------------------------------------------------------------- analysis
def _lane_type(t: T.Type) -> bool:
    return isinstance(t, (T.Scalar, T.Vector, T.Matrix, T.Color, T.EnumType))


def _has_side_effects(e) -> bool:
    stack = [e]
    while stack:
        x = stack.pop()
        if isinstance(x, (A.Assign, A.Postfix)) or (isinstance(x, A.Unary) and x.op in (
                "++", "--")):
            return True
        if isinstance(x, A.Node):
            stack.extend(A.children(x))
    return False


def _walk(s):
    yield s
    if isinstance(s, A.Block):
        for x in s.stmts:
            yield from _walk(x)
    elif isinstance(s, A.If):
        yield from _walk(s.then)
        if s.other is not None:
            yield from _walk(s.other)
    elif isinstance(s, (A.While, A.DoWhile, A.For)):
        yield from _walk(s.body)
    elif isinstance(s, A.Switch):
        for c in s.cases:
            for x in c.stmts:
                yield from _walk(x)


def _has_exit(s) -> bool:
    return any(isinstance(x, (A.Return, A.Break, A.Continue)) for x in _walk(s))


def _has_continue(s) -> bool:
    """A ``continue`` that belongs to this loop (not to a nested one)."""
    if isinstance(s, A.Continue):
        return True
    if isinstance(s, (A.While, A.DoWhile, A.For)):
        return False
    if isinstance(s, A.Block):
        return any(_has_continue(x) for x in s.stmts)
    if isinstance(s, A.If):
        return _has_continue(s.then) or (s.other is not None and _has_continue(s.other))
    if isinstance(s, A.Switch):
        return any(_has_continue(x) for c in s.cases for x in c.stmts)
    return False


def _cond_varying(module, cond) -> bool:
    info = module.info.get(id(cond))
    return info is not None and info.level > UNIFORM


def _varying_exit(module, s, loop: bool, under: bool = False) -> bool:
    """Whether ``s`` holds a break/continue/return (of this loop, when ``loop``) under
    varying control."""
    if isinstance(s, (A.Break, A.Continue)):
        return under
    if isinstance(s, A.Return):
        return under
    if isinstance(s, A.Block):
        return any(_varying_exit(module, x, loop, under) for x in s.stmts)
    if isinstance(s, A.If):
        u = under or _cond_varying(module, s.cond)
        return _varying_exit(module, s.then, loop, u) or (
            s.other is not None and _varying_exit(module, s.other, loop, u))
    if isinstance(s, A.Switch):
        u = under or _cond_varying(module, s.value)
        return any(_varying_exit(module, x, loop, u) for c in s.cases for x in c.stmts
                   if not isinstance(x, A.Break) or u)
    if isinstance(s, (A.While, A.DoWhile, A.For)):
        # only returns inside nested loops leave this loop
        u = under or _loop_cond_varying(module, s)
        return any(isinstance(x, A.Return) and (u or _under_varying(module, s.body, x))
                   for x in _walk(s.body))
    return False


def _loop_cond_varying(module, s) -> bool:
    """Whether a loop's condition varies."""
    return s.cond is not None and _cond_varying(module, s.cond)


def _under_varying(module, root, target, loop_varies=_loop_cond_varying) -> bool:
    """Whether statement ``target`` inside ``root`` runs under varying control: an ``if``
    or ``switch`` on a varying value, or a loop for which ``loop_varies``."""
    def go(s, under):
        if s is target:
            return under
        if isinstance(s, A.Block):
            return any(go(x, under) for x in s.stmts)
        if isinstance(s, A.If):
            u = under or _cond_varying(module, s.cond)
            return go(s.then, u) or (s.other is not None and go(s.other, u))
        if isinstance(s, (A.While, A.DoWhile, A.For)):
            return go(s.body, under or loop_varies(module, s))
        if isinstance(s, A.Switch):
            u = under or _cond_varying(module, s.value)
            return any(go(x, u) for c in s.cases for x in c.stmts)
        return False
    return go(root, False)


def _varying_returns(module, body) -> bool:
    """Whether some return of the function happens under varying control (or inside a
    loop whose lanes may leave at different times)."""
    for x in _walk(body):
        if isinstance(x, A.Return) and _under_varying(module, body, x, _loop_varying):
            return True
    return False


def _loop_varying(module, s) -> bool:
    """Whether a loop's lanes may leave it at different times."""
    return _loop_cond_varying(module, s) or _varying_exit(module, s.body, loop=True)


def lane_expression_source(mg: ModuleGen, name: str, expr, inputs: dict, order: list,
                           ret: T.Type) -> str:
    """Source of ``def name(S, L, *order)`` computing ``expr`` (a material's data
    expression) where the nodes in ``inputs`` (id -> parameter name) are given."""
    g = _FunctionGen(mg, None)
    g.inputs = dict(inputs)
    code = g.expr_conv(expr, ret)
    params = "".join(", " + p for p in order)
    return "\n".join([f"def {name}(S, L{params}):", *g.lines, f"    return {code}", ""])
