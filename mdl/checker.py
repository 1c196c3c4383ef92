"""Name resolution, type checking and variability analysis of one MDL module.

:func:`check_module` turns a parsed module into a :class:`~mdl.entities.CheckedModule`:

* module scope: imports (``import ::m::*`` gives qualified access ``m::x``; ``using ::m
  import x`` unqualified access), structs, enums, typedefs, constants (folded to values),
  annotations, functions and materials (overloads), each checked for duplicates;
* every expression gets its type, its *variability* (uniform, auto -- the caller
  decides --, or varying over the surface), its constant value when it has one, what
  it resolved to, and the implicit conversion applied where it is used (int to float,
  float to double, enum to int, vectors alike);
* calls are resolved among overloads (exact matches first, then the fewest
  conversions; ambiguity is an error), with positional then named arguments and
  parameter defaults; ``uniform`` parameters refuse values that vary;
* function bodies: scopes, assignments to l-values, ``break``/``continue`` only in
  loops (and ``switch``), returns converted to the return type, the variability of
  locals by fixpoint (a local assigned a varying value, or assigned under varying
  control flow, varies);
* materials: their body is a ``material`` expression, ``let`` bindings included;
  distribution functions and material structs exist only there.

All errors are collected (a poisoned expression raises no follow-up errors) and raised
together as :class:`~mdl.diagnostics.MdlError`; warnings stay in
``module.diagnostics``.
"""

from __future__ import annotations

import numpy as np

from mdl import ast as A
from mdl import lanes as LN
from mdl import mathlib
from mdl import types as T
from mdl.diagnostics import MAX_ERRORS, Diagnostic, MdlError, Source, Span, did_you_mean
from mdl.entities import (
    AUTO,
    UNIFORM,
    VARYING,
    AnnotationEntity,
    AnnotationValue,
    CallInfo,
    CheckedModule,
    ConstEntity,
    EnumValueEntity,
    ExprInfo,
    Local,
    Overload,
    ParamInfo,
    SizeName,
    TypeEntity,
)
from mdl.loader import Loader, ModuleText, _CycleError, _NotFound, not_found_fix
from mdl.parser import parse_module

__all__ = ["check_module", "check_expression", "Checker", "MATERIAL_STRUCTS", "is_material_level"]

#: the built-in structs of the material model (material level only)
MATERIAL_STRUCTS = ("material", "material_surface", "material_emission", "material_volume",
                    "material_geometry")
_SWIZZLE = {"x": 0, "y": 1, "z": 2, "w": 3}
_ARITH = ("+", "-", "*", "/")


def is_material_level(t: T.Type) -> bool:
    """Types whose values exist only in materials: distribution functions and the
    material structs (and arrays of df components)."""
    if isinstance(t, T.DF):
        return True
    if isinstance(t, T.StructType) and t.builtin:
        return True
    if isinstance(t, T.ArrayT):
        return is_material_level(t.elem)
    if isinstance(t, T.StructType):
        return any(is_material_level(f.type) for f in t.fields)
    return False


class _Poison(Exception):
    """An error already reported; the expression's type becomes ERROR."""


class Checker:
    def __init__(self, loader: Loader, mt: ModuleText, tree: A.Module, src: Source):
        self.loader = loader
        self.mt = mt
        self.src = src
        self.tree = tree
        self.m = CheckedModule(mt.qname, src, tree, mt.path, mt.kind, mt.native,
                               version=tree.version)
        self.errors: list[Diagnostic] = []
        self.warnings: list[Diagnostic] = []
        self.scopes: list[dict] = []
        self.fn: Overload | None = None
        self.fn_ctx: dict = {}
        self.builtins: CheckedModule | None = None
        self.is_std = mt.kind == "std"
        self.material_body = False
        self.varying_control = 0
        self.loop_depth = 0
        self.switch_depth = 0
        self.varying_loops: set[int] = set()
        self.changed = False
        self.final = True
        self.cacheable = False

    # ------------------------------------------------------------------ diagnostics
    def order(self, d: Diagnostic):
        """Diagnostics of this module first, by position; then those of imports."""
        return (d.loc.file != self.src.name, d.loc.line, d.loc.col)

    def error(self, message: str, where, fix: str = "") -> None:
        span = where if isinstance(where, Span) else where.span
        if not self.final:
            return
        d = self.src.diagnostic("error", message, span.start, span.end, fix)
        if d not in self.errors:
            self.errors.append(d)
        if len(self.errors) >= MAX_ERRORS:
            raise MdlError(self.errors)

    def warning(self, message: str, where, fix: str = "") -> None:
        if not self.final:
            return
        span = where if isinstance(where, Span) else where.span
        d = self.src.diagnostic("warning", message, span.start, span.end, fix)
        if d not in self.warnings:
            self.warnings.append(d)

    def poison(self, message: str, where, fix: str = ""):
        self.error(message, where, fix)
        raise _Poison()

    # ------------------------------------------------------------------ module scope
    def run(self) -> CheckedModule:
        m = self.m
        if m.qname != "::builtins" and self.mt.kind != "std":
            self.builtins = self.loader.load("::builtins")
        imported = []
        for d in self.tree.decls:
            if isinstance(d, (A.Import, A.Using)):
                mod = self.import_decl(d)
                if mod is not None:
                    imported.append(mod)
        if self.builtins is not None:
            imported.append(self.builtins)
        m.key = self.loader.content_key(self.mt, imported)
        if not self.errors and self.cacheable and m.key in _CHECKED:
            return _CHECKED[m.key]
        self.declare_types()
        self.resolve_types()
        self.declare_values()
        self.compute_reads_state()
        self.check_definitions()
        if not self.errors:
            self.check_recursion()
        m.diagnostics = sorted(self.warnings, key=self.order)
        if self.errors:
            raise MdlError(sorted(self.errors, key=self.order) + m.diagnostics)
        if self.cacheable:
            _remember(m)
        return m

    def import_decl(self, d) -> CheckedModule | None:
        path = d.path if isinstance(d, A.Import) else d.module
        parts = list(path.parts)
        star = parts[-1] == "*"
        if isinstance(d, A.Import):
            if star:
                parts = parts[:-1]
                single = None
            else:
                single = parts[-1]
                parts = parts[:-1]
                if not parts:
                    self.error(f"'import {path.text}' names no module",
                               path, f"write 'import ::{single}::*;' to import a module")
                    return None
        else:
            single = None
        qname = self.resolve_module_path(parts, path)
        if qname is None:
            return None
        try:
            mod = self.loader.load(qname, self.m)
        except _NotFound:
            self.error(f"module '{qname}' not found", path, not_found_fix(self.loader, qname))
            return None
        except _CycleError as e:
            self.error(f"modules import each other in a cycle: {e.chain}", path,
                       "move the shared definitions into a third module")
            return None
        except MdlError as e:
            self.error(f"module '{qname}' has errors (listed below)", path,
                       "fix the errors in the imported module")
            self.errors.extend(x for x in e.diagnostics if x not in self.errors)
            return None
        aliases = self.module_aliases(qname)
        if isinstance(d, A.Import):
            if single is None:
                for a in aliases:
                    self.m.imports[a] = mod
            else:
                ents = mod.exports().get(single)
                if not ents:
                    self.error(f"module '{qname}' exports no '{single}'", path,
                               did_you_mean(single, mod.exports()) or
                               f"import the whole module: import {qname}::*;")
                    return mod
                for a in aliases:
                    holder = self.m.imports.get(a)
                    if holder is None or not isinstance(holder, _Partial):
                        holder = _Partial(mod) if holder is None else holder
                    if isinstance(holder, _Partial):
                        holder.names.add(single)
                    self.m.imports[a] = holder
        else:
            if d.alias is not None:
                self.m.imports[d.alias] = mod
                return mod
            exports = mod.exports()
            names = list(exports) if d.names is None else list(d.names)
            for n in names:
                if n not in exports:
                    self.error(f"module '{qname}' exports no '{n}'", path,
                               did_you_mean(n, exports))
                    continue
                self.m.using.setdefault(n, [])
                for e in exports[n]:
                    if e not in self.m.using[n]:
                        self.m.using[n].append(e)
                    if d.exported and e not in self.m.scope.setdefault(n, []):
                        self.m.scope[n].append(e)  # 'export using' re-exports
            # qualified access comes with 'using' too (MDL imports the module)
            for a in aliases:
                self.m.imports.setdefault(a, mod)
        return mod

    def resolve_module_path(self, parts: list[str], where) -> str | None:
        if not parts:
            self.error("empty module name", where, "name a module: import ::name::*;")
            return None
        if parts[0] in (".", ".."):
            base = [p for p in self.m.qname.split("::") if p][:-1]
            rest = list(parts)
            while rest and rest[0] in (".", ".."):
                if rest.pop(0) == "..":
                    if not base:
                        self.error("'..' goes above the top of the module hierarchy", where,
                                   "use fewer '..' or an absolute name ::a::b")
                        return None
                    base.pop()
            return "::" + "::".join(base + rest)
        return "::" + "::".join(parts)

    @staticmethod
    def module_aliases(qname: str) -> list[str]:
        parts = [p for p in qname.split("::") if p]
        out = ["::".join(parts)]
        if len(parts) > 1:
            out.append(parts[-1])
        return out

    def add(self, name: str, entity, where, kind: str) -> None:
        existing = self.m.scope.get(name, [])
        overloadable = (Overload, AnnotationEntity)
        if existing and not any(isinstance(entity, k) and all(isinstance(e, k) for e in existing)
                                for k in overloadable):
            self.error(f"duplicate declaration of '{name}'", where,
                       f"'{name}' is already declared in this module; rename one of them")
            return
        if name in T.BUILTIN_TYPE_NAMES or (name in MATERIAL_STRUCTS and not self.is_std):
            self.error(f"'{name}' is a built-in type name and cannot be redeclared", where,
                       "choose another name")
            return
        self.m.scope.setdefault(name, []).append(entity)

    def declare_types(self) -> None:
        for d in self.tree.decls:
            if isinstance(d, A.StructDecl):
                builtin = self.m.qname == "::builtins" and d.name in MATERIAL_STRUCTS
                st = T.StructType("::" + d.name if builtin else self.qualify(d.name),
                                  builtin=builtin, module=self.m)
                self.add(d.name, TypeEntity(d.name, self.m, d.exported or self.is_std,
                                            d.name_span, st), d.name_span, "struct")
            elif isinstance(d, A.EnumDecl):
                et = T.EnumType(self.qualify(d.name), module=self.m)
                self.add(d.name, TypeEntity(d.name, self.m, d.exported or self.is_std,
                                            d.name_span, et), d.name_span, "enum")
            elif isinstance(d, A.Typedef):
                self.add(d.name, TypeEntity(d.name, self.m, d.exported or self.is_std,
                                            d.name_span, None), d.name_span, "typedef")

    def qualify(self, name: str) -> str:
        return f"{self.m.qname}::{name}"

    def resolve_types(self) -> None:
        # typedefs first (structs may use them), in order
        for d in self.tree.decls:
            if isinstance(d, A.Typedef):
                ent = self.type_entity(d.name)
                try:
                    ent.type, _ = self.resolve_type(d.type)
                except _Poison:
                    ent.type = T.ERROR
        for d in self.tree.decls:
            if isinstance(d, A.EnumDecl):
                self.declare_enum(d)
        for d in self.tree.decls:
            if isinstance(d, A.StructDecl):
                self.declare_struct(d)

    def type_entity(self, name: str) -> TypeEntity | None:
        for e in self.m.scope.get(name, []):
            if isinstance(e, TypeEntity):
                return e
        return None

    def declare_enum(self, d: A.EnumDecl) -> None:
        ent = self.type_entity(d.name)
        if ent is None:
            return
        et: T.EnumType = ent.type
        et.annotations = self.annotations(d.annotations)
        nxt = 0
        for v in d.values:
            if v.value is not None:
                try:
                    info = self.expr(v.value)
                    val = self.fold_int(v.value, info, "an enum value")
                    nxt = val
                except _Poison:
                    pass
            if et.value_of(v.name) is not None:
                self.error(f"duplicate declaration of '{v.name}'", v, "enum values must "
                           "have distinct names")
                continue
            et.values.append((v.name, nxt))
            et.value_annotations[v.name] = self.annotations(v.annotations)
            self.add(v.name, EnumValueEntity(v.name, self.m, d.exported or self.is_std,
                                             v.span, et, nxt), v, "enum value")
            nxt += 1

    def declare_struct(self, d: A.StructDecl) -> None:
        ent = self.type_entity(d.name)
        if ent is None:
            return
        st: T.StructType = ent.type
        st.annotations = self.annotations(d.annotations)
        seen = set()
        params = []
        for f in d.fields:
            if f.name in seen:
                self.error(f"duplicate field '{f.name}'", f.name_span,
                           "rename one of the fields")
                continue
            seen.add(f.name)
            try:
                ft, q = self.resolve_type(f.type)
            except _Poison:
                ft, q = T.ERROR, None
            if ft is st:
                self.error(f"struct '{d.name}' contains itself", f, "use another type")
                ft = T.ERROR
            st.fields.append(T.FieldInfo(f.name, ft, f.default, q == "uniform",
                                         self.annotations(f.annotations)))
            params.append(ParamInfo(f.name, ft, q, f.default, (), f.name_span,
                                    optional=True))
        ctor = Overload(d.name, self.m, d.exported or self.is_std, d.name_span, params, st,
                        False, None, d, "struct")
        self.m.scope[d.name].append(ctor)
        self.m.overloads.append(ctor)

    def declare_values(self) -> None:
        for d in self.tree.decls:  # annotations first: declarations anywhere may use them
            if isinstance(d, A.AnnotationDecl):
                params = [self.param_info(p, {}) for p in d.params]
                self.add(d.name, AnnotationEntity(d.name, self.m, d.exported or self.is_std,
                                                  d.name_span, params), d.name_span,
                         "annotation")
        for d in self.tree.decls:
            if isinstance(d, A.ConstDecl):
                self.declare_const(d)
            elif isinstance(d, A.FunctionDecl):
                self.declare_function(d)
            elif isinstance(d, A.ModuleAnnotations):
                self.m.annotations = self.annotations(d.annotations)
        # prototypes without a definition
        for name, ents in self.m.scope.items():
            for o in ents:
                if isinstance(o, Overload) and o.kind == "mdl" and o.decl is not None and \
                        o.decl.body is None:
                    self.error(f"function '{name}' is declared but never defined", o.decl,
                               "give it a body { ... }, or remove the declaration")

    def declare_const(self, d: A.ConstDecl) -> None:
        try:
            t, _ = self.resolve_type(d.decl.type)
        except _Poison:
            t = T.ERROR
        for dc in d.decl.declarators:
            ent = ConstEntity(dc.name, self.m, d.exported or self.is_std, dc.name_span, t, None,
                              dc.init, self.annotations(dc.annotations))
            self.add(dc.name, ent, dc.name_span, "constant")
            init = dc.init
            try:
                if init is None and dc.ctor_args is None:
                    self.poison(f"constant '{dc.name}' has no value", dc.name_span,
                                f"write const {d.decl.type.name.text} {dc.name} = value;")
                if dc.ctor_args is not None:
                    info = self.construct_declared(t, dc.ctor_args, dc)
                    node = dc
                else:
                    info = self.expr(init)
                    node = init
                if isinstance(t, T.AutoType):
                    t = ent.type = info.type
                elif isinstance(t, T.ArrayT) and t.size is None and t.sizevar is None:
                    if isinstance(info.type, T.ArrayT):
                        t = ent.type = T.ArrayT(t.elem, info.type.size)
                if isinstance(t, T.ArrayT) and t.sizevar is not None:
                    self.poison("size-deferred arrays (T[<N>]) are only allowed for "
                                "parameters", d.decl.type, "give the array a size: T[3]")
                if dc.ctor_args is None:
                    self.assign_check(t, info, init, f"constant '{dc.name}'")
                if info.const is None:
                    self.poison(f"the value of constant '{dc.name}' is not a constant "
                                "expression", node, "use literals, other constants and "
                                "constructors")
                ent.value = self.converted_const(info, t)
            except _Poison:
                ent.type = T.ERROR

    def converted_const(self, info: ExprInfo, t: T.Type):
        v = info.const
        if info.type != t and isinstance(v, np.ndarray):
            return LN.convert(v, info.type, t)
        return v

    def param_info(self, p: A.Param, sizevars: dict) -> ParamInfo:
        try:
            t, q = self.resolve_type(p.type, allow_deferred=True, sizevars=sizevars)
        except _Poison:
            t, q = T.ERROR, None
        if p.name in T.BUILTIN_TYPE_NAMES:
            self.error(f"type name '{p.name}' cannot be used as a parameter name",
                       p.name_span, "rename the parameter")
        sv = None
        if isinstance(t, T.ArrayT) and p.type.array is not None and \
                p.type.array.deferred is not None:
            sv = t.sizevar
        return ParamInfo(p.name, t, q, p.default, self.annotations(p.annotations),
                         p.name_span, sv)

    def declare_function(self, d: A.FunctionDecl) -> None:
        if d.params is None:
            self.error("variants (f(*) = g(...)) are not supported", d.name_span,
                       "write the parameters out, then call g with them")
            return
        sizevars: dict = {}
        params = []
        seen = set()
        for p in d.params:  # first: a return type may be sized by a T[<N>] parameter
            if p.name in seen:
                self.error(f"duplicate parameter '{p.name}'", p.name_span,
                           "rename one of the parameters")
            seen.add(p.name)
            params.append(self.param_info(p, sizevars))
        try:
            ret, rq = self.resolve_type(d.ret, allow_deferred=False, sizevars=sizevars,
                                        is_return=True)
        except _Poison:
            ret, rq = T.ERROR, None
        if isinstance(ret, T.ArrayT) and ret.sizevar is not None and \
                ret.sizevar.name not in sizevars:
            self.error(f"unknown array size '{ret.sizevar.name}'", d.ret,
                       "the return size must name a size of a T[<N>] parameter")
        kind = "mdl"
        if d.body is None and self.mt.kind in ("std", "native"):
            kind = "intrinsic" if self.mt.kind == "std" else "native"
        existing = [e for e in self.m.scope.get(d.name, []) if isinstance(e, Overload)]
        for o in existing:
            if [p.type for p in o.params] == [p.type for p in params]:
                if o.decl is not None and o.decl.body is None and d.body is not None:
                    # the definition of an earlier prototype
                    o.decl, o.params, o.span = d, params, d.name_span
                    return
                if d.body is None and o.kind == "mdl":
                    return  # a prototype after the definition
                self.error(f"duplicate definition of function '{d.name}'", d.name_span,
                           "two overloads need different parameter types")
                return
        ov = Overload(d.name, self.m, d.exported or self.is_std, d.name_span, params, ret,
                      rq == "uniform", d.qualifier, d, kind, self.annotations(d.annotations),
                      sizevars, index=len(existing))
        if ov.is_material and d.body is not None and isinstance(d.body, A.Block):
            self.error(f"material '{d.name}' has a block body", d.name_span,
                       "a material is defined by an expression: material m(...) = "
                       "material(...);")
        self.add(d.name, ov, d.name_span, "function")
        self.m.overloads.append(ov)

    # ------------------------------------------------------------------ types
    def resolve_type(self, tn: A.TypeName, allow_deferred: bool = False, sizevars=None,
                     is_return: bool = False) -> tuple[T.Type, str | None]:
        name = tn.name
        if name.parts == ("auto",) and not name.absolute:
            base = T.AUTO
        else:
            base = self.lookup_type(name)
        if tn.array is not None:
            base = self.array_type(base, tn.array, allow_deferred, sizevars)
        return base, tn.qualifier

    def array_type(self, elem: T.Type, suf: A.ArraySuffix, allow_deferred: bool,
                   sizevars) -> T.Type:
        if isinstance(elem, T.ArrayT):
            self.poison("arrays of arrays are not allowed in MDL", suf,
                        "use a struct holding an array")
        if suf.deferred is not None:
            if not allow_deferred:
                self.poison("size-deferred arrays (T[<N>]) are only allowed for parameters",
                            suf, "give the array a size: T[3], or make it a parameter")
            if sizevars is None:
                sizevars = {}
            if suf.deferred in sizevars:
                self.poison(f"array size '{suf.deferred}' is declared twice", suf,
                            f"write T[{suf.deferred}] (without <>) to reuse the size")
            sv = T.SizeVar(suf.deferred)
            sizevars[suf.deferred] = sv
            return T.ArrayT(elem, None, sv)
        if suf.size is None:
            return T.ArrayT(elem)
        size = suf.size
        if isinstance(size, A.Ref) and not size.name.absolute and len(size.name.parts) == 1:
            n = size.name.parts[0]
            if sizevars is not None and n in sizevars:
                return T.ArrayT(elem, None, sizevars[n])
            sn = self.find_local(n)
            if isinstance(sn, SizeName):
                return T.ArrayT(elem, None, sn.var)
        info = self.expr(size)
        k = self.fold_int(size, info, "an array size")
        if k < 0:
            self.poison(f"array size {k} is negative", size, "sizes are >= 0")
        return T.ArrayT(elem, k)

    def lookup_type(self, name: A.Name) -> T.Type:
        if not name.absolute and len(name.parts) == 1:
            b = T.builtin(name.parts[0])
            if b is not None:
                return b
        ents = self.lookup(name, want="type")
        for e in ents:
            if isinstance(e, TypeEntity):
                if e.type is None:
                    self.poison(f"typedef '{name.text}' is used before it is defined", name,
                                "move the typedef above its first use")
                return e.type
        if ents:
            self.poison(f"'{name.text}' is not a type", name,
                        "a type is a built-in type, a struct, an enum or a typedef")
        self.poison(f"unknown type '{name.text}'", name,
                    did_you_mean(name.text, self.visible_names(types=True))
                    or "declare it, or import the module that exports it")

    # ------------------------------------------------------------------ lookup
    def find_local(self, name: str):
        for s in reversed(self.scopes):
            if name in s:
                return s[name]
        return None

    def module_for(self, parts: tuple[str, ...], absolute: bool):
        key = "::".join(parts)
        if absolute:
            for mod in self.m.imports.values():
                if mod.qname == "::" + key or (isinstance(mod, _Partial)
                                                and mod.module.qname == "::" + key):
                    return mod
            if self.m.qname == "::" + key:
                return self.m
            return None
        if key in self.m.imports:
            return self.m.imports[key]
        if key == self.m.name:
            return self.m
        return None

    def lookup(self, name: A.Name, want: str = "value") -> list:
        parts = name.parts
        if len(parts) == 1 and not name.absolute:
            n = parts[0]
            loc = self.find_local(n)
            if loc is not None and want == "value":
                return [loc]
            if n in self.m.scope:
                return self.m.scope[n]
            if n in self.m.using:
                return self.m.using[n]
            if self.builtins is not None and n in self.builtins.scope:
                return self.builtins.scope[n]
            return []
        if len(parts) == 1:  # ::x
            self.poison(f"'{name.text}' names no module", name,
                        f"write {parts[0]}, or module::{parts[0]}")
        mod = self.module_for(parts[:-1], name.absolute)
        n = parts[-1]
        if mod is None:
            modname = "::".join(parts[:-1])
            if self.loader.find("::" + modname) is not None:
                self.poison(f"module '{modname}' is not imported", name,
                            f"add 'import ::{modname}::*;' after the mdl line")
            aliases = [a for a in self.m.imports if "::" not in a]
            hint = did_you_mean(modname, aliases + [q.removeprefix("::") for q in
                                                    self.loader.known_names()])
            text = self.src.text[name.span.start:name.span.end]
            if len(parts) == 2 and not name.absolute and ":: " in text:
                hint = (hint + " " if hint else "") + \
                    "(a named argument is written 'name: value')"
            extra = self.loader.missing_hint("::" + modname)
            hint = "; ".join(x for x in (hint, extra) if x)
            self.poison(f"unknown module '{modname}'", name,
                        hint or "import it: the module must be beside this one, on the "
                        "search path, or one of the workbench's")
        if isinstance(mod, _Partial):
            if n not in mod.names:
                self.poison(f"'{n}' is not imported from module '{mod.module.qname}'", name,
                            f"import it (import {mod.module.qname}::{n};) or the whole "
                            f"module (import {mod.module.qname}::*;)")
            mod = mod.module
        if mod is self.m:
            return self.m.scope.get(n, [])
        ents = mod.exports().get(n, [])
        if not ents:
            kind = "standard module" if mod.kind == "std" else "module"
            self.poison(f"'{n}' is not exported by {kind} '{mod.name}'", name,
                        did_you_mean(n, mod.exports())
                        or f"see what it exports: pwc mdl info {mod.qname}")
        return ents

    def visible_names(self, types: bool = False) -> list[str]:
        names = set()
        for s in self.scopes:
            names.update(s)
        names.update(self.m.scope)
        names.update(self.m.using)
        if self.builtins is not None:
            names.update(self.builtins.scope)
        if types:
            names.update(T.BUILTIN_TYPE_NAMES)
        for alias, mod in self.m.imports.items():
            m = mod.module if isinstance(mod, _Partial) else mod
            if "::" not in alias:
                names.update(f"{alias}::{n}" for n in m.exports())
        return sorted(names)

    # ------------------------------------------------------------------ annotations
    def annotations(self, annos) -> tuple:
        out = []
        for a in annos:
            try:
                ents = self.lookup(a.name, want="annotation")
            except _Poison:
                continue
            decls = [e for e in ents if isinstance(e, AnnotationEntity)]
            if not decls:
                self.warning(f"unknown annotation '{a.name.text}' (ignored)", a.name,
                             did_you_mean(a.name.text, [n for n in self.visible_names()
                                                        if "anno::" in n]))
                continue
            values = []
            for arg in a.args:
                try:
                    info = self.expr(arg.value)
                except _Poison:
                    continue
                if info.const is None:
                    self.warning("annotation arguments must be constants (ignored)", arg,
                                 "write a literal or a constant")
                    continue
                values.append(LN.to_python(info.const, info.type))
            qn = decls[0].qname.removeprefix("::")
            out.append(AnnotationValue(qn, tuple(values), a.span))
        return tuple(out)

    # ------------------------------------------------------------------ variability
    def compute_reads_state(self) -> None:
        """Which functions read the state, directly or through calls (a syntactic
        over-approximation, by fixpoint)."""
        own = [o for o in self.m.overloads if o.kind == "mdl"]
        for o in self.m.overloads:
            if o.kind != "mdl":
                o.reads_state = o.qualifier == "varying"
        self.final = False
        try:
            calls = {o: self.called_names(o.decl) for o in own}
            for o in own:
                o.reads_state = o.qualifier == "varying"
            changed = True
            while changed:
                changed = False
                for o in own:
                    if o.reads_state:
                        continue
                    for name in calls[o]:
                        if self.name_reads_state(name):
                            o.reads_state = True
                            changed = True
                            break
        finally:
            self.final = True

    def check_recursion(self) -> None:
        """MDL has no recursion: a definition may not call itself, directly or through
        others of its module (modules cannot import each other in a cycle)."""
        own = [o for o in self.m.overloads if o.kind == "mdl" and o.decl is not None]
        edges: dict = {}
        for o in own:
            sites = []
            stack = [o.decl]
            while stack:
                x = stack.pop()
                info = self.m.info.get(id(x)) if isinstance(x, A.Call) else None
                if info is not None and info.call is not None and \
                        info.call.kind == "overload" and info.call.target.module is self.m \
                        and info.call.target.kind == "mdl":
                    sites.append((info.call.target, x))
                if isinstance(x, A.Node):
                    stack.extend(A.children(x))
            edges[o] = sorted(sites, key=lambda s: s[1].span.start)
        reported = set()
        for o in own:
            path = self._cycle(o, edges)
            if path is None or frozenset(map(id, path)) in reported:
                continue
            reported.add(frozenset(map(id, path)))
            site = next(x for t, x in edges[o] if t is path[1 % len(path)] or
                        (len(path) == 1 and t is o))
            names = " -> ".join(p.name for p in (*path, o))
            how = "calls itself" if len(path) == 1 else f"calls itself through {names}"
            self.error(f"recursion: '{o.name}' {how}; MDL does not allow recursive calls",
                       site, "rewrite it with a loop (for, while) and local variables")

    @staticmethod
    def _cycle(start, edges):
        """The shortest call path start -> ... -> start, as the list of its overloads
        (beginning with start), or None."""
        from collections import deque

        queue = deque([(start, [start])])
        seen = set()
        while queue:
            o, path = queue.popleft()
            for t, _ in edges.get(o, ()):
                if t is start:
                    return path
                if id(t) not in seen:
                    seen.add(id(t))
                    queue.append((t, path + [t]))
        return None

    def called_names(self, node) -> list[A.Name]:
        out = []
        stack = [node]
        while stack:
            x = stack.pop()
            if isinstance(x, A.Call) and isinstance(x.callee, A.Ref):
                out.append(x.callee.name)
            if isinstance(x, A.Node):
                stack.extend(A.children(x))
        return out

    def name_reads_state(self, name: A.Name) -> bool:
        try:
            ents = self.lookup(name)
        except _Poison:
            return False
        return any(isinstance(e, Overload) and bool(e.reads_state) for e in ents)

    # ------------------------------------------------------------------ definitions
    def check_definitions(self) -> None:
        for o in list(self.m.overloads):
            if o.kind == "struct":
                self.check_struct_defaults(o)
            elif o.decl is not None and o.module is self.m:
                self.check_definition(o)

    def check_struct_defaults(self, o: Overload) -> None:
        st = o.ret
        for f, _p in zip(st.fields, o.params, strict=False):
            if f.default is None:
                continue
            self.scopes = [{}]
            self.fn = o
            try:
                info = self.expr(f.default)
                self.assign_check(f.type, info, f.default, f"the default of field '{f.name}'")
            except _Poison:
                pass
        self.scopes = []
        self.fn = None

    def check_definition(self, o: Overload) -> None:
        d: A.FunctionDecl = o.decl
        self.fn = o
        self.material_body = o.is_material
        if o.kind != "mdl" or d.body is None:
            self.fn = None
            self.material_body = False
            return
        if not o.is_material and not self.is_std:
            for p in o.params:
                if is_material_level(p.type):
                    self.error(f"parameter '{p.name}' of type {p.type} is only allowed in "
                               "materials", p.span,
                               "distribution functions and material structs exist only in "
                               "material definitions")
            if is_material_level(o.ret):
                self.error(f"function '{o.name}' returns {o.ret}, which only materials can",
                           d.ret, "define a material instead: material m(...) = ...;")
        # the fixpoint of local variability: check the body until nothing changes
        for _attempt in range(8):
            self.final = False
            self.changed = False
            self.check_body(o, d)
            if not self.changed:
                break
        self.final = True
        self.check_body(o, d)
        self.fn = None
        self.material_body = False

    def check_body(self, o: Overload, d: A.FunctionDecl) -> None:
        scope: dict = {}
        self.scopes = [scope]
        self.fn_ctx = {"returns": 0, "loop": None}
        for sv_name, sv in o.sizevars.items():
            owner = next(p for p in o.params if p.sizevar is sv) if any(
                p.sizevar is sv for p in o.params) else None
            scope[sv_name] = SizeName(sv, owner, sv_name)
        for p, pd in zip(o.params, d.params, strict=True):
            level = UNIFORM if p.uniform else (VARYING if p.qualifier == "varying" else AUTO)
            loc = self.m.locals.get(id(pd))
            if loc is None:
                loc = Local(p.name, p.type, level, p.qualifier, False, True, p.span,
                            "p_" + p.name)
                self.m.locals[id(pd)] = loc
            loc.level = max(loc.level, level)
            if p.name in scope:
                pass
            scope[p.name] = loc
            if p.default is not None:
                try:
                    info = self.expr(p.default)
                    self.assign_check(p.type, info, p.default, f"the default of '{p.name}'")
                    if p.uniform and info.level == VARYING:
                        self.error(f"the default of uniform parameter '{p.name}' varies over "
                                   "the surface", p.default, "give a constant default")
                except _Poison:
                    pass
        try:
            if isinstance(d.body, A.Block):
                self.varying_control = 0
                self.loop_depth = self.switch_depth = 0
                for s in d.body.stmts:
                    self.stmt(s)
                if not self.fn_ctx["returns"]:
                    self.error(f"function '{o.name}' has no return statement", d.name_span,
                               "end the body with 'return value;'")
                elif not self.always_returns(d.body):
                    self.warning(f"function '{o.name}' may end without returning a value",
                                 d.name_span, "make every path end with 'return value;' "
                                 "(lanes that fall off the end get the type's zero)")
            elif d.body is not None:
                info = self.expr(d.body)
                self.assign_check(o.ret, info, d.body,
                                  f"the value of {'material' if o.is_material else 'function'}"
                                  f" '{o.name}'")
                if o.ret_uniform and info.level == VARYING:
                    self.error(f"'{o.name}' returns uniform {o.ret}, but its value varies",
                               d.body, "remove 'uniform' from the return type")
        except _Poison:
            pass
        self.scopes = []

    def always_returns(self, s) -> bool:
        if isinstance(s, A.Return):
            return True
        if isinstance(s, A.Block):
            return any(self.always_returns(x) for x in s.stmts)
        if isinstance(s, A.If):
            return s.other is not None and self.always_returns(s.then) and \
                self.always_returns(s.other)
        if isinstance(s, A.Switch):
            has_default = any(c.value is None for c in s.cases)
            return has_default and all(any(self.always_returns(x) for x in c.stmts)
                                       or not c.stmts for c in s.cases) and \
                any(self.always_returns(x) for x in s.cases[-1].stmts)
        if isinstance(s, (A.While, A.For)):
            cond = s.cond
            infinite = cond is None or (isinstance(cond, A.Literal) and cond.value is True)
            return infinite and not self.contains_break(s.body)
        if isinstance(s, A.DoWhile):
            return self.always_returns(s.body)
        return False

    def contains_break(self, s) -> bool:
        if isinstance(s, A.Break):
            return True
        if isinstance(s, (A.While, A.For, A.DoWhile, A.Switch)):
            return False
        if isinstance(s, A.Block):
            return any(self.contains_break(x) for x in s.stmts)
        if isinstance(s, A.If):
            return self.contains_break(s.then) or (s.other is not None
                                                   and self.contains_break(s.other))
        return False

    # ------------------------------------------------------------------ statements
    def stmt(self, s) -> None:
        try:
            self._stmt(s)
        except _Poison:
            pass

    def _stmt(self, s) -> None:
        if isinstance(s, A.Block):
            self.scopes.append({})
            for x in s.stmts:
                self.stmt(x)
            self.scopes.pop()
        elif isinstance(s, A.ExprStmt):
            self.expr(s.expr)
        elif isinstance(s, A.DeclStmt):
            self.local_decl(s.decl)
        elif isinstance(s, A.Empty):
            pass
        elif isinstance(s, A.If):
            c = self.condition(s.cond)
            self.varying_control += c
            self.scoped(s.then)
            if s.other is not None:
                self.scoped(s.other)
            self.varying_control -= c
        elif isinstance(s, (A.While, A.DoWhile)):
            self.loop(s, s.cond, s.body)
        elif isinstance(s, A.For):
            self.scopes.append({})
            if s.init is not None:
                self.stmt(s.init)
            self.loop(s, s.cond, s.body, s.update)
            self.scopes.pop()
        elif isinstance(s, A.Switch):
            self.switch(s)
        elif isinstance(s, A.Break):
            if self.loop_depth == 0 and self.switch_depth == 0:
                self.poison("'break' outside of a loop or switch", s,
                            "break ends a loop or a switch case")
            self.note_exit(s)
        elif isinstance(s, A.Continue):
            if self.loop_depth == 0:
                self.poison("'continue' outside of a loop", s, "continue goes to a loop's "
                            "next iteration")
            self.note_exit(s)
        elif isinstance(s, A.Return):
            self.ret(s)

    def scoped(self, s) -> None:
        self.scopes.append({})
        self.stmt(s)
        self.scopes.pop()

    def note_exit(self, s) -> None:
        if self.varying_control and self.fn_ctx.get("loop") is not None:
            key = self.fn_ctx["loop"]
            if key not in self.varying_loops:
                self.varying_loops.add(key)
                self.changed = True

    def condition(self, e) -> int:
        """Check a condition; 1 if it varies (the branches are varying control)."""
        info = self.expr(e)
        self.expect_bool(info, e)
        return 1 if info.level > UNIFORM else 0

    def expect_bool(self, info: ExprInfo, e) -> None:
        if isinstance(info.type, T.ErrorType):
            return
        if info.type == T.BOOL:
            return
        if isinstance(info.type, T.Scalar) or isinstance(info.type, T.EnumType):
            self.poison(f"a condition must be a bool, got {_a(info.type)}", e,
                        "compare it: (x != 0)")
        self.poison(f"a condition must be a bool, got {_a(info.type)}", e,
                    "write a comparison (a == b, a < b...) or a bool value")

    def loop(self, s, cond, body, update=None) -> None:
        key = id(s)
        outer = self.fn_ctx.get("loop")
        self.fn_ctx["loop"] = key
        varying = key in self.varying_loops
        if cond is not None:
            c = self.condition(cond)
            if c and not varying:
                self.varying_loops.add(key)
                self.changed = True
                varying = True
        self.varying_control += varying
        self.loop_depth += 1
        self.scoped(body)
        if update is not None:
            try:
                self.expr(update)
            except _Poison:
                pass
        self.loop_depth -= 1
        self.varying_control -= varying
        self.fn_ctx["loop"] = outer

    def switch(self, s: A.Switch) -> None:
        info = self.expr(s.value)
        if not (info.type == T.INT or isinstance(info.type, (T.EnumType, T.ErrorType))):
            self.poison(f"a switch value must be an int or an enum, got {_a(info.type)}",
                        s.value, "switch on an int (int(x)) or an enum, or use if/else")
        varying = info.level > UNIFORM
        seen = {}
        defaults = 0
        self.varying_control += varying
        self.switch_depth += 1
        self.scopes.append({})
        for c in s.cases:
            if c.value is None:
                defaults += 1
                if defaults > 1:
                    self.error("a switch has two 'default' labels", c, "remove one")
            else:
                try:
                    li = self.expr(c.value)
                    self.assign_check(info.type if isinstance(info.type, T.EnumType)
                                      else T.INT, li, c.value, "a case label")
                    v = self.fold_int(c.value, li, "a case label")
                    if v in seen:
                        self.error(f"duplicate case label {v}", c.value,
                                   "each case value appears once")
                    seen[v] = c
                except _Poison:
                    pass
            for x in c.stmts:
                self.stmt(x)
        self.scopes.pop()
        self.switch_depth -= 1
        self.varying_control -= varying

    def ret(self, s: A.Return) -> None:
        o = self.fn
        self.fn_ctx["returns"] += 1
        if self.material_body or o is None:
            self.poison("'return' outside of a function", s,
                        "a material's body is one expression: use let { ... } in ...")
        info = self.expr(s.value)
        self.assign_check(o.ret, info, s.value, f"the return value of '{o.name}'")
        if o.ret_uniform and info.level == VARYING:
            self.error(f"'{o.name}' returns uniform {o.ret}, but this value varies over the "
                       "surface", s.value, "return a uniform value, or remove 'uniform'")
        if self.varying_control and self.fn_ctx.get("loop") is not None:
            self.note_exit(s)

    def local_decl(self, d: A.VarDecl, let: bool = False) -> None:
        try:
            t, q = self.resolve_type(d.type, sizevars=None)
        except _Poison:
            t, q = T.ERROR, None
        if self.fn is not None and not self.material_body and is_material_level(t) and \
                not self.is_std:
            self.error(f"a {t} variable is only allowed in materials", d.type,
                       "compute distribution functions in a material's let block")
        for dc in d.declarators:
            if dc.name in T.BUILTIN_TYPE_NAMES:
                self.error(f"type name '{dc.name}' cannot be used as a variable name",
                           dc.name_span, "rename the variable")
            if dc.name in self.scopes[-1]:
                self.error(f"redeclaration of '{dc.name}'", dc.name_span,
                           f"'{dc.name}' is already declared in this block; rename one")
            vt = t
            init_info = None
            try:
                if dc.ctor_args is not None:
                    init_info = self.construct_declared(t, dc.ctor_args, dc)
                elif dc.init is not None:
                    init_info = self.expr(dc.init)
                    if isinstance(t, T.AutoType):
                        vt = init_info.type
                    elif isinstance(t, T.ArrayT) and t.size is None and t.sizevar is None:
                        if isinstance(init_info.type, T.ArrayT):
                            vt = init_info.type if init_info.type.elem == t.elem else t
                    self.assign_check(vt, init_info, dc.init, f"'{dc.name}'")
                elif d.const:
                    self.poison(f"constant '{dc.name}' has no value", dc.name_span,
                                f"write const ... {dc.name} = value;")
                elif isinstance(t, T.AutoType):
                    self.poison(f"'auto {dc.name}' needs an initializer", dc.name_span,
                                f"write auto {dc.name} = value;")
                elif isinstance(t, T.ArrayT) and t.size is None and t.sizevar is None:
                    self.poison(f"array '{dc.name}' has no size", d.type,
                                "give it a size (T[3]) or an initializer")
                else:
                    init_info = self.default_value(t, dc)
            except _Poison:
                vt = vt if not isinstance(vt, T.AutoType) else T.ERROR
            level = init_info.level if init_info is not None else UNIFORM
            loc = self.m.locals.get(id(dc))
            if loc is None:
                loc = Local(dc.name, vt, level, q, d.const, False, dc.name_span,
                            "v_" + dc.name)
                self.m.locals[id(dc)] = loc
            else:
                loc.type = vt
            self.raise_level(loc, level, dc)
            if self.varying_control and not let:
                self.raise_level(loc, VARYING, dc)
            if q == "uniform" and init_info is not None and init_info.level == VARYING:
                self.error(f"uniform '{dc.name}' is initialized with a value that varies over "
                           "the surface", dc.init or dc, "remove 'uniform', or use a "
                           "uniform value")
            if q == "varying":
                self.raise_level(loc, VARYING, dc)
            if d.const:
                if init_info is None or init_info.const is None:
                    self.error(f"the value of constant '{dc.name}' is not a constant "
                               "expression", dc.init or dc, "drop 'const', or use constants")
                else:
                    loc.value = self.converted_const(init_info, vt)
            self.scopes[-1][dc.name] = loc

    def raise_level(self, loc: Local, level: int, where) -> None:
        if level > loc.level:
            if loc.declared == "uniform" and level == VARYING:
                self.error(f"uniform '{loc.name}' is assigned a value that varies over the "
                           "surface", where, "remove 'uniform' from its declaration")
                return
            loc.level = level
            self.changed = True

    def default_value(self, t: T.Type, where) -> ExprInfo:
        """The info of a default-constructed value (``T x;``)."""
        if isinstance(t, T.StructType) and not t.builtin:
            ctor = next(e for e in t.module.scope.get(t.name.rsplit("::", 1)[-1], [])
                        if isinstance(e, Overload) and e.kind == "struct")
            level = VARYING if any(self.default_level(f) == VARYING for f in t.fields) \
                else UNIFORM
            info = ExprInfo(t, level, None, call=CallInfo("overload", ctor, t,
                                                          [None] * len(t.fields)))
        else:
            info = ExprInfo(t, UNIFORM, None)
        self.m.info[id(where)] = info
        return info

    def default_level(self, f: T.FieldInfo) -> int:
        if f.default is None:
            return UNIFORM
        return VARYING if self.reads_state_expr(f.default) else UNIFORM

    def reads_state_expr(self, e) -> bool:
        return any(self.name_reads_state(n) for n in self.called_names(e))

    # ------------------------------------------------------------------ expressions
    def expr(self, e) -> ExprInfo:
        """Check an expression; records and returns its :class:`ExprInfo` (raises
        _Poison after reporting an error)."""
        info = self._expr(e)
        self.m.info[id(e)] = info
        return info

    def try_expr(self, e) -> ExprInfo:
        try:
            return self.expr(e)
        except _Poison:
            info = ExprInfo(T.ERROR)
            self.m.info[id(e)] = info
            return info

    def _expr(self, e) -> ExprInfo:
        method = getattr(self, "e_" + type(e).__name__, None)
        if method is None:
            self.poison(f"unsupported expression {type(e).__name__}", e,
                        "rewrite it with calls, operators and variables")
        return method(e)

    def e_Literal(self, e: A.Literal) -> ExprInfo:
        t = {"bool": T.BOOL, "int": T.INT, "float": T.FLOAT, "double": T.DOUBLE,
             "string": T.STRING}[e.kind]
        v = e.value
        if e.kind == "int":
            if v > 0x80000000:
                self.warning(f"integer literal {e.text} does not fit in 32 bits; it wraps",
                             e, "MDL ints are 32-bit")
            v = int(np.array(v & 0xFFFFFFFF, dtype=np.int64).astype(np.uint32).view(np.int32))
        return ExprInfo(t, UNIFORM, LN.const(t, v))

    def e_Ref(self, e: A.Ref) -> ExprInfo:
        name = e.name
        if not name.absolute and len(name.parts) == 1 and T.builtin(name.parts[0]) is not None:
            self.poison(f"'{name.text}' is a type; it is not a value", e,
                        f"construct a value: {name.text}(...)")
        ents = self.lookup(name)
        if not ents:
            n = name.parts[-1]
            if len(name.parts) == 1 and not name.absolute and self.fn is not None:
                self.poison(f"undeclared identifier '{name.text}'", e,
                            did_you_mean(n, self.visible_names()) or
                            "declare it before use, or import the module that exports it")
            self.poison(f"undeclared identifier '{name.text}'", e,
                        did_you_mean(name.text, self.visible_names()))
        ent = ents[0]
        if isinstance(ent, Local):
            if ent.type is None:
                self.poison(f"'{ent.name}' is used in its own initializer", e,
                            "give it a value that does not use itself")
            return ExprInfo(ent.type, ent.level, ent.value, target=ent,
                            lvalue=not ent.const and not (ent.is_param and False))
        if isinstance(ent, SizeName):
            return ExprInfo(T.INT, UNIFORM, None, target=ent)
        if isinstance(ent, ConstEntity):
            if ent.value is None and ent.module is self.m and ent.type is not T.ERROR:
                # a constant used before its declaration: fold it now
                pass
            t = ent.type or T.ERROR
            if isinstance(t, T.ErrorType):
                raise _Poison()
            return ExprInfo(t, UNIFORM, ent.value, target=ent)
        if isinstance(ent, EnumValueEntity):
            return ExprInfo(ent.enum, UNIFORM, LN.const(ent.enum, ent.value), target=ent)
        if isinstance(ent, Overload) or isinstance(ent, TypeEntity):
            what = "a material" if isinstance(ent, Overload) and ent.is_material else (
                "a function" if isinstance(ent, Overload) else "a type")
            self.poison(f"'{name.text}' is {what}; it must be called", e,
                        f"write {name.text}(...) with its arguments")
        if isinstance(ent, AnnotationEntity):
            self.poison(f"'{name.text}' is an annotation", e,
                        "annotations go in [[ ... ]] after a declaration")
        self.poison(f"'{name.text}' cannot be used here", e,
                    "use a value, a constant or a call here")

    def e_Sequence(self, e: A.Sequence) -> ExprInfo:
        last = None
        for x in e.items:
            last = self.expr(x)
        return ExprInfo(last.type, last.level, None)

    def e_Let(self, e: A.Let) -> ExprInfo:
        self.scopes.append({})
        try:
            for d in e.decls:
                self.local_decl(d, let=True)
            body = self.expr(e.body)
        finally:
            self.scopes.pop()
        return ExprInfo(body.type, body.level, body.const)

    def e_Conditional(self, e: A.Conditional) -> ExprInfo:
        c = self.expr(e.cond)
        self.expect_bool(c, e.cond)
        vc = 1 if c.level > UNIFORM else 0
        self.varying_control += vc
        try:
            a = self.try_expr(e.then)
            b = self.try_expr(e.other)
        finally:
            self.varying_control -= vc
        if isinstance(a.type, T.ErrorType) or isinstance(b.type, T.ErrorType):
            raise _Poison()
        t = self.common_type(a.type, b.type)
        if t is None:
            self.poison(f"the branches of '?:' have different types: {a.type} and {b.type}",
                        e, "make both branches the same type (convert one with T(...))")
        if is_material_level(t) and c.level > UNIFORM:
            self.error(f"a {t} cannot be chosen per point: the condition of '?:' varies over "
                       "the surface", e.cond, "use a uniform condition (a uniform parameter)")
        a.convert = t if a.type != t else None
        b.convert = t if b.type != t else None
        const = None
        if c.const is not None and a.const is not None and b.const is not None:
            const = (self.converted_const(a, t) if LN.as_bool(c.const)
                     else self.converted_const(b, t))
        return ExprInfo(t, max(c.level, a.level, b.level), const)

    def common_type(self, a: T.Type, b: T.Type) -> T.Type | None:
        if a == b:
            return a
        if T.implicit_cost(a, b) is not None:
            return b
        if T.implicit_cost(b, a) is not None:
            return a
        if isinstance(a, T.ArrayT) and isinstance(b, T.ArrayT) and a.elem == b.elem and \
                a.size == b.size:
            return a
        return None

    def e_Assign(self, e: A.Assign) -> ExprInfo:
        target = self.expr(e.target)
        self.check_lvalue(e.target, target)
        value = self.expr(e.value)
        ops = None
        if e.op == "=":
            self.assign_check(target.type, value, e.value, "the assignment")
            level = value.level
        else:
            op = e.op[:-1]
            rt, lt, vt = self.binary_type(op, target.type, value.type, e)
            if rt != target.type and T.implicit_cost(rt, target.type) is None:
                self.poison(f"'{e.op}' gives {_a(rt)}, which cannot be stored in "
                            f"{_a(target.type)}", e,
                            f"write it out: x = {target.type}(x {op} ...)")
            value.convert = vt if vt != value.type else None
            ops = (lt, vt, rt)
            level = max(target.level, value.level)
        self.assigned(e.target, level, e)
        return ExprInfo(target.type, level, None, target=ops)

    def root_local(self, e):
        while isinstance(e, (A.Member, A.Index)):
            e = e.obj
        if isinstance(e, A.Ref):
            info = self.m.info.get(id(e))
            if info is not None and isinstance(info.target, Local):
                return info.target
        return None

    def check_lvalue(self, e, info: ExprInfo) -> None:
        root = self.root_local(e)
        base = e
        while isinstance(base, (A.Member, A.Index)):
            base = base.obj
        bi = self.m.info.get(id(base))
        if root is None and isinstance(base, A.Ref) and bi is not None and \
                isinstance(bi.target, ConstEntity):
            self.poison(f"'{base.name.text}' is a constant and cannot be assigned", e,
                        "copy it into a variable first")
        if root is None or not isinstance(e, (A.Ref, A.Member, A.Index)):
            self.poison("the left side of an assignment is not assignable", e,
                        "assign to a variable, a field, a component or an element")
        if root.const:
            self.poison(f"'{root.name}' is a constant and cannot be assigned", e,
                        "copy it into a variable first")
        if isinstance(e, A.Member):
            oi = self.m.info.get(id(e.obj))
            if oi is not None and isinstance(oi.type, T.Vector) and len(e.name) > 1 and \
                    len(set(e.name)) != len(e.name):
                self.poison(f"swizzle '.{e.name}' repeats a component and cannot be assigned",
                            e, "assign each component once")

    def assigned(self, target, level: int, where) -> None:
        root = self.root_local(target)
        if root is None:
            return
        level = max(level, self.index_level(target))
        if self.varying_control:
            level = VARYING
        self.raise_level(root, level, where)

    def index_level(self, e) -> int:
        level = UNIFORM
        while isinstance(e, (A.Member, A.Index)):
            if isinstance(e, A.Index):
                ii = self.m.info.get(id(e.index))
                if ii is not None:
                    level = max(level, ii.level)
            e = e.obj
        return level

    def e_Unary(self, e: A.Unary) -> ExprInfo:
        a = self.expr(e.operand)
        t = a.type
        if isinstance(t, T.ErrorType):
            raise _Poison()
        if e.op in ("++", "--"):
            self.check_lvalue(e.operand, a)
            if not T.is_numeric(t) or isinstance(t, (T.Matrix, T.Color)):
                self.poison(f"'{e.op}' needs a number, got {_a(t)}", e,
                            "use it on an int, float or double variable")
            self.assigned(e.operand, a.level, e)
            return ExprInfo(t, a.level, None)
        if e.op in ("-", "+"):
            if isinstance(t, T.EnumType):
                t = T.INT
                a.convert = T.INT
            if not T.is_numeric(t):
                self.poison(f"cannot negate {_a(t)}", e, "'-' applies to numbers, vectors, "
                            "colors and matrices")
            const = None
            if a.const is not None:
                const = LN.neg(self.converted_const(a, t)) if e.op == "-" else \
                    self.converted_const(a, t)
            return ExprInfo(t, a.level, const)
        if e.op == "!":
            if T.elem_kind(t) != "bool" or isinstance(t, T.Matrix):
                self.poison(f"'!' needs a bool, got {_a(t)}", e, "compare: (x == 0)")
            return ExprInfo(t, a.level, None if a.const is None else LN.lnot(a.const))
        if e.op == "~":
            if T.elem_kind(t) != "int" or isinstance(t, T.Matrix):
                self.poison(f"'~' needs an int, got {_a(t)}", e, "convert it: ~int(x)")
            return ExprInfo(t, a.level, None if a.const is None else LN.bnot(a.const))
        self.poison(f"unknown operator '{e.op}'", e, "use -, +, ! or ~")

    def e_Postfix(self, e: A.Postfix) -> ExprInfo:
        a = self.expr(e.operand)
        self.check_lvalue(e.operand, a)
        if not T.is_numeric(a.type) or isinstance(a.type, (T.Matrix, T.Color)):
            self.poison(f"'{e.op}' needs a number, got {_a(a.type)}", e,
                        "use it on an int, float or double variable")
        self.assigned(e.operand, a.level, e)
        return ExprInfo(a.type, a.level, None)

    def e_Binary(self, e: A.Binary) -> ExprInfo:
        if e.op in ("&&", "||"):
            a = self.expr(e.left)
            self.expect_bool(a, e.left)
            vc = 1 if a.level > UNIFORM else 0
            self.varying_control += vc
            try:
                b = self.expr(e.right)
            finally:
                self.varying_control -= vc
            self.expect_bool(b, e.right)
            const = None
            if a.const is not None and b.const is not None:
                const = LN.land(a.const, b.const) if e.op == "&&" else LN.lor(a.const, b.const)
            return ExprInfo(T.BOOL, max(a.level, b.level), const, target=(T.BOOL, T.BOOL))
        a = self.expr(e.left)
        b = self.expr(e.right)
        rt, lt, rt2 = self.binary_type(e.op, a.type, b.type, e)
        a.convert = lt if lt != a.type else None
        b.convert = rt2 if rt2 != b.type else None
        const = None
        if a.const is not None and b.const is not None:
            const = self.fold_binary(e, e.op, self.converted_const(a, lt),
                                     self.converted_const(b, rt2), lt, rt2)
        return ExprInfo(rt, max(a.level, b.level), const, target=(lt, rt2))

    def fold_binary(self, e, op, x, y, lt, rt):
        if op in ("/", "%") and T.elem_kind(lt) == "int" and T.elem_kind(rt) == "int" and \
                np.any(np.asarray(y) == 0):
            self.poison("integer division by zero", e, "divide by a value other than 0")
        return _eval_binary(op, x, y, lt, rt)

    def binary_type(self, op: str, a: T.Type, b: T.Type, e) -> tuple:
        """(result type, left operand type, right operand type) of ``a op b``."""
        if isinstance(a, T.ErrorType) or isinstance(b, T.ErrorType):
            raise _Poison()
        bad = f"'{op}' cannot combine {_a(a)} and {_a(b)}"
        if isinstance(a, T.EnumType) and isinstance(b, T.EnumType) and a is b and \
                op in ("==", "!="):
            return T.BOOL, a, b
        if isinstance(a, T.EnumType):
            a = T.INT
        if isinstance(b, T.EnumType):
            b = T.INT
        if op in ("==", "!="):
            t = self.common_type(a, b)
            if t is None or isinstance(t, (T.StructType, T.ArrayT, T.DF, T.Resource)):
                self.poison(bad, e, "compare values of the same type")
            return T.BOOL, t, t
        if op in ("<", "<=", ">", ">="):
            if isinstance(a, T.Scalar) and isinstance(b, T.Scalar) and a.kind != "bool" and \
                    b.kind != "bool":
                k = T.common_scalar(a.kind, b.kind)
                return T.BOOL, T.Scalar(k), T.Scalar(k)
            self.poison(bad, e, f"'{op}' compares two numbers (compare components of "
                        "vectors one by one)")
        if op in ("&", "|", "^"):
            if a == T.BOOL and b == T.BOOL:
                return T.BOOL, a, b
            return self.int_op(op, a, b, e, bad)
        if op in ("<<", ">>", ">>>"):
            if T.elem_kind(a) == "int" and T.elem_kind(b) == "int" and not isinstance(
                    a, T.Matrix):
                return a, a, b
            self.poison(bad, e, "shifts apply to ints")
        if op == "%":
            return self.int_op(op, a, b, e, bad)
        # + - * /
        if T.elem_kind(a) == "bool" or T.elem_kind(b) == "bool":
            self.poison(bad, e, "arithmetic applies to numbers (convert with int(...))")
        if isinstance(a, T.Matrix) or isinstance(b, T.Matrix):
            return self.matrix_op(op, a, b, e, bad)
        if isinstance(a, T.Color) or isinstance(b, T.Color):
            other = b if isinstance(a, T.Color) else a
            if isinstance(other, T.Color) or (isinstance(other, T.Scalar)):
                la = T.COLOR if isinstance(a, T.Color) else T.FLOAT
                lb = T.COLOR if isinstance(b, T.Color) else T.FLOAT
                return T.COLOR, la, lb
            self.poison(bad, e, "convert the vector: color(v) or float3(c)")
        if isinstance(a, (T.Scalar, T.Vector)) and isinstance(b, (T.Scalar, T.Vector)):
            k = T.common_scalar(T.elem_kind(a), T.elem_kind(b))
            if isinstance(a, T.Vector) and isinstance(b, T.Vector):
                if a.size != b.size:
                    self.poison(bad, e, "vectors must have the same size")
                t = T.Vector(k, a.size)
                return t, t, t
            if isinstance(a, T.Vector):
                return T.Vector(k, a.size), T.Vector(k, a.size), T.Scalar(k)
            if isinstance(b, T.Vector):
                return T.Vector(k, b.size), T.Scalar(k), T.Vector(k, b.size)
            return T.Scalar(k), T.Scalar(k), T.Scalar(k)
        self.poison(bad, e, _OPERANDS_FIX)

    def int_op(self, op, a, b, e, bad):
        if T.elem_kind(a) == "int" and T.elem_kind(b) == "int" and not isinstance(a, T.Matrix):
            if isinstance(a, T.Vector) and isinstance(b, T.Vector) and a.size != b.size:
                self.poison(bad, e, _OPERANDS_FIX)
            return (a if isinstance(a, T.Vector) else b), a, b
        self.poison(bad, e, f"'{op}' applies to ints" + (
            " (use math::fmod for floats)" if op == "%" else ""))

    def matrix_op(self, op, a, b, e, bad):
        if isinstance(a, T.Matrix) and isinstance(b, T.Matrix):
            k = T.common_scalar(a.elem, b.elem)
            if op in ("+", "-"):
                if (a.cols, a.rows) != (b.cols, b.rows):
                    self.poison(bad, e, "matrices must have the same size")
                t = T.Matrix(k, a.cols, a.rows)
                return t, t, t
            if op == "*":
                if a.cols != b.rows:
                    self.poison(f"cannot multiply {a} by {b}: {a} has {a.cols} columns, {b} "
                                f"has {b.rows} rows", e,
                                "the left matrix needs as many columns as the right has rows")
                return (T.Matrix(k, b.cols, a.rows), T.Matrix(k, a.cols, a.rows),
                        T.Matrix(k, b.cols, b.rows))
            self.poison(bad, e, _OPERANDS_FIX)
        m, other = (a, b) if isinstance(a, T.Matrix) else (b, a)
        if isinstance(other, T.Scalar) and other.kind != "bool":
            k = T.common_scalar(m.elem, other.kind)
            mt = T.Matrix(k, m.cols, m.rows)
            if op == "/" and other is a:
                self.poison(bad, e, _OPERANDS_FIX)
            return (mt, mt, T.Scalar(k)) if isinstance(a, T.Matrix) else (mt, T.Scalar(k), mt)
        if isinstance(other, T.Vector) and op == "*":
            k = T.common_scalar(m.elem, other.elem)
            if isinstance(a, T.Matrix):  # m * v: v has m.cols components
                if other.size != m.cols:
                    self.poison(f"cannot multiply {m} by {other}: it needs a vector of "
                                f"{m.cols} components", e,
                                f"use a float{m.cols}, or multiply from the other side")
                return (T.Vector(k, m.rows), T.Matrix(k, m.cols, m.rows),
                        T.Vector(k, other.size))
            if other.size != m.rows:  # v * m: v has m.rows components
                self.poison(f"cannot multiply {other} by {m}: it needs a vector of {m.rows} "
                            "components", e,
                            f"use a float{m.rows}, or multiply from the other side")
            return (T.Vector(k, m.cols), T.Vector(k, other.size), T.Matrix(k, m.cols, m.rows))
        self.poison(bad, e, _OPERANDS_FIX)

    def e_Member(self, e: A.Member) -> ExprInfo:
        a = self.expr(e.obj)
        t = a.type
        if isinstance(t, T.ErrorType):
            raise _Poison()
        if isinstance(t, T.StructType):
            k = t.field_index(e.name)
            if k is None:
                self.poison(f"struct {t.name} has no field '{e.name}'", e.name_span,
                            did_you_mean(e.name, [f.name for f in t.fields])
                            or f"fields: {', '.join(f.name for f in t.fields)}")
            ft = t.fields[k].type
            const = a.const[k] if isinstance(a.const, tuple) else None
            return ExprInfo(ft, a.level, const, target=k)
        if isinstance(t, T.Vector):
            ks = []
            for ch in e.name:
                if ch not in _SWIZZLE or _SWIZZLE[ch] >= t.size:
                    comps = "xyzw"[:t.size]
                    self.poison(f"{t} has no component '{e.name}'", e.name_span,
                                f"components: {', '.join(comps)} (or index it: v[0])")
                ks.append(_SWIZZLE[ch])
            if len(ks) > 4:
                self.poison(f"swizzle '.{e.name}' has more than 4 components", e.name_span)
            rt = t.scalar if len(ks) == 1 else T.Vector(t.elem, len(ks))
            const = None
            if a.const is not None:
                const = LN.component(a.const, ks[0]) if len(ks) == 1 else LN.swizzle(
                    a.const, tuple(ks))
            return ExprInfo(rt, a.level, const, target=tuple(ks))
        if isinstance(t, T.Color):
            self.poison(f"a color has no component '{e.name}'", e.name_span,
                        "convert it: float3(c).x, or use math::average / math::luminance")
        self.poison(f"{_a(t)} has no member '{e.name}'", e.name_span,
                    "only structs have fields and vectors components (.x .y .z .w)")

    def e_Index(self, e: A.Index) -> ExprInfo:
        a = self.expr(e.obj)
        i = self.expr(e.index)
        if isinstance(a.type, T.ErrorType):
            raise _Poison()
        if not (i.type == T.INT or isinstance(i.type, T.EnumType)):
            if isinstance(i.type, T.ErrorType):
                raise _Poison()
            self.poison(f"an index must be an int, got {_a(i.type)}", e.index,
                        "convert it: int(x)")
        if isinstance(i.type, T.EnumType):
            i.convert = T.INT
        t = a.type
        if isinstance(t, T.ArrayT):
            rt, n = t.elem, t.size
        elif isinstance(t, T.Vector):
            rt, n = t.scalar, t.size
        elif isinstance(t, T.Matrix):
            rt, n = t.column, t.cols
        elif isinstance(t, T.Color):
            self.poison("a color cannot be indexed", e, "convert it: float3(c)[0]")
        else:
            self.poison(f"{_a(t)} cannot be indexed", e,
                        "index arrays, vectors and matrices only")
        const = None
        if i.const is not None:
            k = int(LN.uniform_value(i.const))
            if n is not None and not 0 <= k < n:
                self.poison(f"index {k} is out of range for {t} (0 to {n - 1})", e.index,
                            f"use an index from 0 to {n - 1}")
            if a.const is not None:
                const = LN.index(a.const, np.array([k]))
        return ExprInfo(rt, max(a.level, i.level), const)

    def e_Cast(self, e: A.Cast) -> ExprInfo:
        t, _ = self.resolve_type(e.type)
        a = self.expr(e.operand)
        s = a.type
        ok = (s == t or (isinstance(s, T.EnumType) and isinstance(t, T.EnumType))
              or (isinstance(s, T.EnumType) and t == T.INT)
              or (s == T.INT and isinstance(t, T.EnumType))
              or (isinstance(s, T.StructType) and isinstance(t, T.StructType)
                  and [f.type for f in s.fields] == [f.type for f in t.fields])
              or (isinstance(s, T.ArrayT) and isinstance(t, T.ArrayT)))
        if not ok:
            self.poison(f"cannot cast {_a(s)} to {t}", e,
                        "cast<T> converts between enums, ints and structs of equal fields; "
                        "use T(value) for numbers")
        return ExprInfo(t, a.level, a.const if not isinstance(a.const, tuple) else a.const)

    def e_ArrayType(self, e: A.ArrayType) -> ExprInfo:
        self.poison(f"'{e.element.text}[...]' is an array type, not a value", e,
                    f"construct a value: {e.element.text}[](...)")

    # ------------------------------------------------------------------ calls
    def e_Call(self, e: A.Call) -> ExprInfo:
        callee = e.callee
        if isinstance(callee, A.ArrayType):
            return self.array_ctor(e, callee)
        if not isinstance(callee, A.Ref):
            self.poison("this expression cannot be called", callee,
                        "call a function, a material or a type by its name")
        name = callee.name
        if not name.absolute and len(name.parts) == 1:
            bt = T.builtin(name.parts[0])
            if bt is not None:
                return self.builtin_ctor(e, bt)
        ents = self.lookup(name)
        if not ents:
            self.poison(f"unknown function '{name.text}'", callee,
                        did_you_mean(name.text, [n for n in self.visible_names()
                                                 if self.is_callable_name(n)])
                        or "declare it, or import the module that exports it")
        first = ents[0]
        if isinstance(first, Local) or isinstance(first, (ConstEntity, EnumValueEntity,
                                                          SizeName)):
            self.poison(f"'{name.text}' is not a function", callee,
                        "only functions, materials and types can be called")
        if isinstance(first, TypeEntity):
            t = first.type
            overloads = [x for x in ents if isinstance(x, Overload)]
            if isinstance(t, T.StructType) and overloads:
                return self.resolve_call(e, overloads, name.text)
            if isinstance(t, T.EnumType):
                self.poison(f"an enum is not constructed; use a value of {t.name}, or "
                            f"cast<{t.name}>(int)", callee)
            if t is not None and T.builtin(str(t)) is not None:
                return self.builtin_ctor(e, t)
            if isinstance(t, T.ArrayT):
                self.poison("an array type is not called like a function", callee,
                            "construct arrays with T[](...)")
            self.poison(f"'{name.text}' cannot be constructed", callee,
                        "call a function, or construct a struct, vector, matrix or color")
        overloads = [x for x in ents if isinstance(x, Overload)]
        if not overloads:
            self.poison(f"'{name.text}' is not a function", callee,
                        "use it without '(...)', or call a function")
        return self.resolve_call(e, overloads, name.text)

    def is_callable_name(self, n: str) -> bool:
        return True

    def args_info(self, e: A.Call) -> list[ExprInfo]:
        infos = []
        named = False
        for a in e.args:
            if a.name is None and named:
                self.poison("positional argument after a named argument", a,
                            "put positional arguments first, or name this one")
            named = named or a.name is not None
            infos.append(self.try_expr(a.value))
        return infos

    def match(self, o: Overload, e: A.Call, infos: list[ExprInfo]):
        """(per-parameter argument index or None, per-argument cost, sizes) or a reason."""
        slots: list = [None] * len(o.params)
        names = [p.name for p in o.params]
        for k, a in enumerate(e.args):
            if a.name is None:
                if k >= len(o.params):
                    return f"takes {len(o.params)} argument{'s' if len(o.params) != 1 else ''}" \
                           f", got {len(e.args)}", a
                slots[k] = k
            else:
                if a.name not in names:
                    return f"has no parameter '{a.name}'", a
                j = names.index(a.name)
                if slots[j] is not None:
                    return f"gets the argument '{a.name}' twice", a
                slots[j] = k
        for j, p in enumerate(o.params):
            if slots[j] is None and p.required:
                return f"needs the argument '{p.name}' ({p.type})", e
        costs = []
        sizes: dict = {}
        for j, p in enumerate(o.params):
            k = slots[j]
            if k is None:
                continue
            at = infos[k].type
            if isinstance(at, T.ErrorType):
                costs.append(0)
                continue
            pt = self.bind_sizes(p.type, sizes)
            c = T.implicit_cost(at, pt)
            if c is None:
                return (f"argument '{p.name}' must be {_a(pt)}, got {_a(at)}",
                        e.args[k].value)
            if isinstance(pt, T.ArrayT) and pt.sizevar is not None and pt.size is None and \
                    isinstance(at, T.ArrayT):
                bound = at.size if at.size is not None else at.sizevar
                if pt.sizevar in sizes and sizes[pt.sizevar] != bound:
                    return (f"argument '{p.name}' must have {sizes[pt.sizevar]} elements "
                            f"(the size {pt.sizevar.name} of an earlier argument), got "
                            f"{bound}", e.args[k].value)
                sizes[pt.sizevar] = bound
            costs.append(c)
        return slots, costs, sizes

    @staticmethod
    def bind_sizes(t: T.Type, sizes: dict) -> T.Type:
        if isinstance(t, T.ArrayT) and t.sizevar is not None and t.sizevar in sizes:
            b = sizes[t.sizevar]
            return T.ArrayT(t.elem, b) if isinstance(b, int) else T.ArrayT(t.elem, None, b)
        return t

    def resolve_call(self, e: A.Call, overloads: list[Overload], label: str) -> ExprInfo:
        infos = self.args_info(e)
        if any(isinstance(i.type, T.ErrorType) for i in infos):
            raise _Poison()
        viable = []
        reasons = []
        for o in overloads:
            r = self.match(o, e, infos)
            if isinstance(r[0], str):
                reasons.append((o, r))
            else:
                viable.append((o, r))
        if not viable:
            if len(overloads) == 1:
                (msg, where) = reasons[0][1]
                fix = self.arg_fix(reasons[0][0], msg, e, infos)
                self.poison(f"{label} {msg}", where, fix)
            types = ", ".join(str(i.type) for i in infos)
            fix = "overloads: " + "; ".join(o.signature() for o in overloads[:6]) + (
                "; ..." if len(overloads) > 6 else "")
            elems = {str(p.type.elem) for o in overloads for p in o.params
                     if isinstance(p.type, T.ArrayT)}
            wrapped = [str(i.type) for i in infos if str(i.type) in elems]
            if wrapped:
                fix = f"wrap it in an array: {wrapped[0]}[]({wrapped[0]}(...), ...)"
            self.poison(f"no overload of '{label}' takes ({types})", e.callee, fix)
        best = [v for v in viable if not any(
            all(x <= y for x, y in zip(w[1][1], v[1][1], strict=True)) and w[1][1] != v[1][1]
            for w in viable)]
        if len(best) > 1:
            exact = [v for v in best if sum(v[1][1]) == min(sum(w[1][1]) for w in best)]
            if len(exact) == 1:
                best = exact
            else:
                self.poison(f"the call of '{label}' is ambiguous", e.callee,
                            "candidates: " + "; ".join(o.signature() for o, _ in best[:4])
                            + " (convert an argument to pick one)")
        o, (slots, costs, sizes) = best[0]
        for a in o.annotations:
            if a.name == "::anno::deprecated":
                why = f": {a.args[0]}" if a.args else ""
                self.warning(f"{label or o.name} is deprecated{why}", e.callee,
                             "see the function's documentation for its replacement")
        return self.finish_call(e, o, slots, sizes, infos, label)

    def arg_fix(self, o: Overload, msg: str, e: A.Call, infos) -> str:
        if msg.startswith("has no parameter"):
            bad = msg.split("'")[1]
            return did_you_mean(bad, [p.name for p in o.params]) or (
                "parameters: " + ", ".join(p.name for p in o.params))
        if msg.startswith("needs the argument"):
            p = msg.split("'")[1]
            return f"add {p}: <value>"
        if msg.startswith("takes"):
            return "remove the extra arguments"
        if "twice" in msg:
            return "give each argument once"
        if "must be" in msg:
            want = msg.split("must be ")[1].split(",")[0].removeprefix("a ").removeprefix(
                "an ").removeprefix("uniform ")
            got = msg.rsplit("got ", 1)[1].removeprefix("a ").removeprefix("an ")
            if want in ("float2", "float3", "float4", "color") and got in ("float", "int",
                                                                          "double"):
                return f"write {want}(x) to make {_a(want)} from a number"
            if {want, got} == {"float3", "color"}:
                return f"convert with {want}(...)"
            if want == "int" and got in ("float", "double"):
                return "write an integer, without a decimal point, or int(x)"
            if "[" in want and got == want.split("[")[0]:
                return f"wrap it in an array: {want.split('[')[0]}[](...)"
            p = next((p for p in o.params if f"'{p.name}'" in msg), None)
            if p is not None and isinstance(p.type, T.EnumType) and got == "string":
                return ("an enum value is a name, not a string: one of "
                        + ", ".join(n for n, _ in p.type.values))
        return ""

    def finish_call(self, e: A.Call, o: Overload, slots, sizes, infos, label) -> ExprInfo:
        args = []
        level = UNIFORM
        for j, p in enumerate(o.params):
            k = slots[j]
            if k is None:
                args.append(None)
                if p.default is not None and self.default_reads_state(o, p):
                    level = VARYING
                continue
            a = infos[k]
            pt = self.bind_sizes(p.type, sizes)
            if a.type != pt and not (isinstance(pt, T.ArrayT)):
                a.convert = pt
            if p.uniform and a.level == VARYING:
                self.error(f"argument '{p.name}' of {label} is uniform, but this value varies "
                           "over the surface", e.args[k].value,
                           "pass a constant or a uniform value (state functions vary)")
            if is_material_level(pt) is False and p.qualifier == "varying":
                pass
            level = max(level, a.level)
            args.append(e.args[k].value)
        if o.qualifier == "varying" or o.reads_state:
            level = VARYING
        if o.is_material and not self.material_body and self.fn is not None and \
                not self.is_std:
            self.poison(f"material '{label}' can only be used in a material", e.callee,
                        "call it in a material definition")
        if o.kind == "df" and not self.material_body and not self.is_std and \
                self.fn is not None and o.module is not self.m:
            self.poison(f"distribution function '{label}' can only be used in a material",
                        e.callee, "build distribution functions in a material definition")
        ret = self.bind_sizes(o.ret, sizes)
        if o.ret_uniform and level == AUTO:
            level = AUTO
        const = self.fold_call(o, args, e) if level == UNIFORM else None
        return ExprInfo(ret, level, const, call=CallInfo("overload", o, ret, args, sizes))

    def default_reads_state(self, o: Overload, p: ParamInfo) -> bool:
        if o.module is None:
            return False
        saved = (self.m, self.builtins)
        try:
            return self.reads_state_in(o.module, p.default)
        finally:
            self.m, self.builtins = saved

    def reads_state_in(self, module: CheckedModule, expr) -> bool:
        for n in self.called_names(expr):
            if "state" in n.parts[:-1] or n.parts[0] == "state":
                return True
            ents = _lookup_in(module, n)
            if any(isinstance(x, Overload) and x.reads_state for x in ents):
                return True
        return False

    def fold_call(self, o: Overload, args, e):
        """Constant calls of ``::math`` (and struct constructors with constant fields)."""
        if o.kind == "intrinsic" and o.module is not None and o.module.qname == "::math":
            vals = []
            for a, p in zip(args, o.params, strict=True):
                if a is None:
                    return None
                ai = self.m.info.get(id(a))
                if ai is None or ai.const is None:
                    return None
                vals.append(self.converted_const(ai, p.type))
            f = mathlib.FUNCTIONS.get(o.name)
            if f is None:
                return None
            try:
                with np.errstate(all="ignore"):
                    return f(*vals)
            except Exception:  # noqa: BLE001 - not foldable; the back end evaluates it
                return None
        if o.kind == "struct":
            vals = []
            for a, p in zip(args, o.params, strict=True):
                if a is None:
                    if p.default is None:
                        vals.append(LN.zeros(p.type))
                        continue
                    home = o.module if o.module is not None else self.m
                    di = home.info.get(id(p.default))
                    if di is None or di.const is None:
                        return None
                    vals.append(self.converted_const(di, p.type))
                    continue
                ai = self.m.info.get(id(a))
                if ai is None or ai.const is None:
                    return None
                vals.append(self.converted_const(ai, p.type))
            return tuple(vals)
        return None

    # ------------------------------------------------------------------ constructors
    def construct_declared(self, t: T.Type, args, where) -> ExprInfo:
        """``T x(args);``: the constructor of T applied to ``args``."""
        fake = A.Call(where.span if hasattr(where, "span") else Span(0, 0),
                      A.Ref(where.span, A.Name(where.span, (str(t),))), tuple(args))
        if isinstance(t, T.StructType):
            ents = [x for x in t.module.scope.get(t.name.rsplit("::", 1)[-1], [])
                    if isinstance(x, Overload) and x.kind == "struct"]
            info = self.resolve_call(fake, ents, t.name)
        elif isinstance(t, T.ArrayT):
            info = self.array_elements(fake, t.elem, t.size, t.name)
        else:
            info = self.builtin_ctor(fake, t)
        self.m.info[id(where)] = info
        self.m.info[id(fake)] = info
        where_info = info
        return where_info

    def builtin_ctor(self, e: A.Call, t: T.Type) -> ExprInfo:
        name = str(t)
        if isinstance(t, T.Resource):
            return self.resource_ctor(e, t)
        if isinstance(t, T.DF):
            if e.args:
                self.poison(f"{name}() takes no arguments (it is the black {name})", e,
                            "use a df:: function, e.g. df::diffuse_reflection_bsdf(...)")
            return ExprInfo(t, UNIFORM, None, call=CallInfo("df_default", None, t, []))
        infos = self.args_info(e)
        if any(isinstance(i.type, T.ErrorType) for i in infos):
            raise _Poison()
        level = max((i.level for i in infos), default=UNIFORM)
        names = [a.name for a in e.args]
        if any(names):
            comps = {"x": 0, "y": 1, "z": 2, "w": 3} if isinstance(t, T.Vector) else (
                {"r": 0, "g": 1, "b": 2} if isinstance(t, T.Color) else {"value": 0})
            if not all(n in comps for n in names if n):
                bad = next(n for n in names if n and n not in comps)
                self.poison(f"{name}(...) has no parameter '{bad}'", e,
                            f"parameters: {', '.join(comps)}")
            order = sorted(range(len(names)), key=lambda k: comps.get(names[k], k))
            infos = [infos[k] for k in order]
            args = [e.args[k].value for k in order]
        else:
            args = [a.value for a in e.args]
        n = len(infos)
        if isinstance(t, T.Scalar) or isinstance(t, T.String):
            if n == 0:
                return self.ctor_info(t, "scalar", [], level)
            if n != 1:
                self.poison(f"{name}(...) takes one value, got {n}", e,
                            f"write {name}(x)")
            s = infos[0].type
            if isinstance(t, T.String):
                if s != T.STRING:
                    self.poison(f"string(...) takes a string, got {_a(s)}", args[0],
                                "MDL does not convert numbers to strings; write a literal")
                return self.ctor_info(t, "scalar", args, level, infos)
            if not (isinstance(s, (T.Scalar, T.EnumType))):
                self.poison(f"{name}(...) takes a number or a bool, got {_a(s)}", args[0],
                            "take a component first: v.x")
            infos[0].convert = None
            return self.ctor_info(t, "scalar", args, level, infos)
        if isinstance(t, (T.Vector, T.Color)):
            size = T.width(t)
            kind = "color" if isinstance(t, T.Color) else "vector"
            if n == 0:
                return self.ctor_info(t, kind, [], level)
            if n == 1:
                s = infos[0].type
                if isinstance(s, (T.Scalar, T.EnumType)) and s != T.STRING:
                    return self.ctor_info(t, kind, args, level, infos)
                if T.width(s) == size and isinstance(s, (T.Vector, T.Color)):
                    return self.ctor_info(t, kind, args, level, infos)
                if isinstance(t, T.Color) and isinstance(s, T.ArrayT):
                    self.poison("color(wavelengths, amplitudes) needs two arrays", e,
                                "write color(float[](...), float[](...))")
                self.poison(f"cannot make {_a(name)} from {_a(s)}", args[0],
                            f"{name}(...) takes 1 or {size} numbers, or a vector of {size}")
            if isinstance(t, T.Color) and n == 2 and all(isinstance(i.type, T.ArrayT)
                                                         for i in infos):
                return self.ctor_info(t, "color_spectrum", args, level, infos)
            if n != size:
                self.poison(f"{name} constructor needs {size} values but got {n}", e,
                            f"write {name}(x) or {name}({', '.join('xyzw'[:size])})"
                            if kind == "vector" else "write color(x) or color(r, g, b)")
            for a, i in zip(args, infos, strict=True):
                if not isinstance(i.type, (T.Scalar, T.EnumType)) or i.type == T.STRING:
                    self.poison(f"{name}(...) components must be numbers, got {_a(i.type)}", a,
                                "pass numbers, or one vector of the right size")
            return self.ctor_info(t, kind, args, level, infos)
        if isinstance(t, T.Matrix):
            if n == 0:
                return self.ctor_info(t, "matrix", [], level)
            if n == 1 and isinstance(infos[0].type, T.Scalar):
                return self.ctor_info(t, "matrix", args, level, infos)
            if n == 1 and isinstance(infos[0].type, T.Matrix) and (
                    infos[0].type.cols, infos[0].type.rows) == (t.cols, t.rows):
                return self.ctor_info(t, "matrix", args, level, infos)
            if n == t.cols and all(isinstance(i.type, T.Vector) and i.type.size == t.rows
                                   for i in infos):
                return self.ctor_info(t, "matrix", args, level, infos)
            if n == t.cols * t.rows and all(isinstance(i.type, T.Scalar) for i in infos):
                return self.ctor_info(t, "matrix", args, level, infos)
            self.poison(f"{name}(...) takes 1 value, {t.cols} columns of {t.rows} or "
                        f"{t.cols * t.rows} values, got {n}", e,
                        f"write {name}(x) for a diagonal, or all {t.cols * t.rows} values")
        self.poison(f"{name} cannot be constructed here", e,
                    "construct numbers, vectors, matrices, colors, structs or arrays")

    def ctor_info(self, t, kind, args, level, infos=()) -> ExprInfo:
        const = None
        if all(i.const is not None for i in infos):
            try:
                const = _construct(kind, t, [i.const for i in infos], [i.type for i in infos])
            except Exception:  # noqa: BLE001 - not foldable
                const = None
        return ExprInfo(t, level, const, call=CallInfo(kind, None, t, list(args)))

    def resource_ctor(self, e: A.Call, t: T.Resource) -> ExprInfo:
        infos = self.args_info(e)
        if not e.args:
            return ExprInfo(t, UNIFORM, None, call=CallInfo("resource", None, t, [None, None]))
        params = ["name", "gamma", "selector"] if t.kind.startswith("texture") else ["name"]
        slots = [None] * len(params)
        for k, a in enumerate(e.args):
            j = k if a.name is None else (params.index(a.name) if a.name in params else -1)
            if j < 0 or j >= len(params):
                self.poison(f"{t}(...) takes ({', '.join(params)})", a,
                            f"pass at most {len(params)} arguments, by position or name")
            slots[j] = k
        ni = infos[slots[0]] if slots[0] is not None else None
        if ni is None or ni.type != T.STRING:
            self.poison(f"{t}(...) needs a file name (a string)", e,
                        f'write {t}("file.png")')
        if ni.const is None:
            self.poison(f"the file name of {t}(...) must be a constant string", e.args[
                slots[0]].value, "resources are named by literal strings")
        gamma = None
        if len(params) > 1 and slots[1] is not None:
            gi = infos[slots[1]]
            gtype = self.tex_gamma_type()
            if gtype is not None and gi.type is not gtype:
                self.poison(f"the gamma of {t}(...) must be a tex::gamma_mode, got "
                            f"{_a(gi.type)}", e.args[slots[1]].value,
                            "tex::gamma_default, tex::gamma_linear or tex::gamma_srgb")
            if gi.const is None:
                self.poison("the gamma must be a constant", e.args[slots[1]].value,
                            "tex::gamma_default, tex::gamma_linear or tex::gamma_srgb")
            gamma = e.args[slots[1]].value
        return ExprInfo(t, UNIFORM, None, call=CallInfo(
            "resource", None, t, [e.args[slots[0]].value, gamma]))

    def tex_gamma_type(self):
        try:
            tex = self.loader.load("::tex")
        except Exception:  # noqa: BLE001
            return None
        ent = tex.scope.get("gamma_mode", [None])[0]
        return getattr(ent, "type", None)

    def array_ctor(self, e: A.Call, callee: A.ArrayType) -> ExprInfo:
        elem = self.lookup_type(callee.element)
        if isinstance(elem, T.ArrayT):
            self.poison("arrays of arrays are not allowed in MDL", callee,
                        "use an array of structs that hold arrays")
        size = None
        suf = callee.suffix
        if suf.deferred is not None:
            self.poison("T[<N>](...) is not a value", suf, "write T[](...) or T[N](...)")
        size_node = None
        if suf.size is not None:
            si = self.expr(suf.size)
            if si.target is not None and isinstance(si.target, SizeName):
                size = si.target.var
            else:
                size = self.fold_int(suf.size, si, "an array size")
                size_node = suf.size
                if size < 1:
                    self.poison(f"array size must be 1 or more, got {size}", suf.size,
                                f"write {callee.element.text}[](...) to take the size from "
                                "the elements")
        shown = "" if suf.size is None else (str(size) if isinstance(size, int) else "N")
        label = f"{callee.element.text}[{shown}]"
        return self.array_elements(e, elem, size, label, size_node)

    def array_elements(self, e: A.Call, elem: T.Type, size, label: str,
                       size_node=None) -> ExprInfo:
        infos = self.args_info(e)
        for a in e.args:
            if a.name is not None:
                self.poison(f"array elements are positional; {label}(...) has no parameter "
                            f"'{a.name}'", a, f"remove '{a.name}:'")
        n = len(infos)
        if isinstance(size, int) and size != n and n:
            self.poison(f"array declared with {size} elements but initialized with {n}: "
                        f"{label}(...) has {n} element{'s' if n != 1 else ''}, not {size}",
                        size_node or e, f"give {size} element{'s' if size != 1 else ''}, or "
                        f"write T[](...) to take the size from them")
        if not infos and size is None:
            self.poison(f"{label}() has no elements", e, "give at least one element: "
                        f"{label}(..., ...)")
        level = UNIFORM
        for k, (a, i) in enumerate(zip(e.args, infos, strict=True)):
            if isinstance(i.type, T.ErrorType):
                raise _Poison()
            if T.implicit_cost(i.type, elem) is None:
                self.poison(f"element {k + 1} of {label}(...) must be {_a(elem)}, got "
                            f"{_a(i.type)}", a.value, self.arg_fix_types(elem, i.type))
            if i.type != elem:
                i.convert = elem
            level = max(level, i.level)
        if isinstance(size, T.SizeVar):
            t = T.ArrayT(elem, None, size)
        else:
            t = T.ArrayT(elem, n if n else size)
        const = None
        if infos and all(i.const is not None for i in infos) and not is_material_level(elem):
            vals = [self.converted_const(i, elem) for i in infos]
            const = LN._stack_structs(vals) if not isinstance(vals[0], np.ndarray) else \
                np.stack(vals, axis=1)
        return ExprInfo(t, level, const, call=CallInfo("array", None, t,
                                                       [a.value for a in e.args]))

    def arg_fix_types(self, want: T.Type, got: T.Type) -> str:
        if isinstance(want, (T.Vector, T.Color)) and isinstance(got, T.Scalar):
            return f"write {want}(x)"
        if {str(want), str(got)} == {"float3", "color"}:
            return f"convert with {want}(...)"
        if want == T.INT and isinstance(got, T.Scalar):
            return "write an integer, without a decimal point, or int(x)"
        if isinstance(want, T.StructType) and isinstance(got, T.DF):
            return f"wrap it: {want.name}(weight: ..., component: ...)"
        if isinstance(want, T.StructType) and isinstance(got, T.StructType):
            return f"write {got.name}[](...) for {got.name} elements"
        return ""

    # ------------------------------------------------------------------ conversions
    def assign_check(self, want: T.Type, info: ExprInfo, where, what: str) -> None:
        got = info.type
        if isinstance(want, T.ErrorType) or isinstance(got, T.ErrorType):
            return
        if isinstance(want, T.AutoType):
            return
        if isinstance(want, T.ArrayT) and isinstance(got, T.ArrayT) and want.elem == got.elem:
            if want.size is not None and got.size is not None and want.size != got.size:
                self.poison(f"{what} is {want}, got {_a(got)}", where,
                            f"give {want.size} elements")
            return
        if T.implicit_cost(got, want) is None:
            fix = self.arg_fix_types(want, got)
            if {str(want), str(got)} == {"float3", "color"}:
                fix = f"convert with {want}(...)"
            elif str(want) == "int" and isinstance(got, T.Scalar):
                fix = "convert with int(...)"
            self.poison(f"{what} must be {_a(want)}, got {_a(got)}", where, fix)
        if got != want:
            info.convert = want

    def fold_int(self, e, info: ExprInfo, what: str) -> int:
        if isinstance(info.type, T.ErrorType):
            raise _Poison()
        if not (info.type == T.INT or isinstance(info.type, T.EnumType)):
            self.poison(f"{what} must be an int, got {_a(info.type)}", e,
                        "use an int constant")
        if info.const is None:
            self.poison(f"{what} must be a constant", e, "use a literal or a constant")
        return int(LN.uniform_value(info.const))


_OPERANDS_FIX = ("convert an operand so both have matching types: float(i), float3(x), "
                 "color(v)...")


class _Partial:
    """An imported module of which only some names are imported (``import ::m::x;``)."""

    def __init__(self, module: CheckedModule):
        self.module = module
        self.names: set[str] = set()
        self.qname = module.qname
        self.kind = module.kind

    def exports(self):
        return {n: es for n, es in self.module.exports().items() if n in self.names}


def _lookup_in(module: CheckedModule, name: A.Name) -> list:
    if len(name.parts) == 1:
        return module.scope.get(name.parts[0], []) or module.using.get(name.parts[0], [])
    mod = module.imports.get("::".join(name.parts[:-1]))
    if mod is None:
        return []
    if isinstance(mod, _Partial):
        mod = mod.module
    return mod.exports().get(name.parts[-1], [])


def _a(t) -> str:
    s = str(t)
    return ("an " if s[:1] in "aeiou" else "a ") + s


def _eval_binary(op, x, y, lt, rt):
    if op in ("*",) and (isinstance(lt, T.Matrix) or isinstance(rt, T.Matrix)):
        if isinstance(lt, T.Matrix) and isinstance(rt, T.Matrix):
            return LN.matmul(x, y, ("m", "m"))
        if isinstance(lt, T.Matrix) and isinstance(rt, T.Vector):
            return LN.matmul(x, y, ("m", "v"))
        if isinstance(lt, T.Vector) and isinstance(rt, T.Matrix):
            return LN.matmul(x, y, ("v", "m"))
    f = {"+": LN.add, "-": LN.sub, "*": LN.mul, "/": LN.div, "%": LN.mod, "==": LN.eq,
         "!=": LN.ne, "<": LN.lt, "<=": LN.le, ">": LN.gt, ">=": LN.ge, "&": LN.band,
         "|": LN.bor, "^": LN.bxor, "<<": LN.shl, ">>": LN.shr, ">>>": LN.ushr}[op]
    with np.errstate(all="ignore"):
        return f(x, y)


def _construct(kind: str, t: T.Type, vals: list, types: list):
    """Fold a built-in constructor (the back end calls the same)."""
    from mdl.construct import construct

    return construct(kind, t, vals, types)


#: checked modules by content key (module text, name, file and the keys of its imports):
#: a module is checked once per process however many loaders (scenes) read it
_CHECKED: dict[str, CheckedModule] = {}
_CHECKED_LIMIT = 512
#: parsed trees by (name, file, text)
_PARSED: dict[tuple, A.Module] = {}


def _remember(m: CheckedModule) -> None:
    if len(_CHECKED) >= _CHECKED_LIMIT:
        _CHECKED.pop(next(iter(_CHECKED)))
    _CHECKED[m.key] = m


def check_expression(loader: Loader, context: CheckedModule, src: Source, tree=None):
    """Check one expression (``src``, e.g. a material call in a scene file) in the scope
    of ``context`` (a checked module of imports); returns ``(tree, info)``.  The
    expression may build materials and distribution functions.

    Raises
    ------
    MdlError
        Its syntax and type errors, located in ``src``.
    """
    from mdl.parser import parse_expression

    if tree is None:
        tree = parse_expression(src)
    mt = ModuleText(context.qname, context.source.text, context.source.name, context.path,
                    context.kind)
    c = Checker(loader, mt, context.tree, src)
    c.m = context
    c.builtins = loader.load("::builtins")
    c.material_body = True
    c.scopes = [{}]
    try:
        info = c.expr(tree)
    except _Poison:
        info = None
    if c.errors:
        raise MdlError(c.errors + c.warnings)
    return tree, info


def check_module(loader: Loader, mt: ModuleText, cacheable: bool = True) -> CheckedModule:
    """Parse and check one module (its imports through ``loader``); a module whose
    content key was checked before in this process is not checked again (``cacheable``:
    a module registered under its name, which other modules may import)."""
    src = Source(mt.filename, mt.text)
    key = (mt.qname, mt.filename, mt.text)
    tree = _PARSED.get(key)
    if tree is None:
        tree = parse_module(src)
        if len(_PARSED) >= _CHECKED_LIMIT:
            _PARSED.pop(next(iter(_PARSED)))
        _PARSED[key] = tree
    c = Checker(loader, mt, tree, src)
    c.cacheable = cacheable
    return c.run()
