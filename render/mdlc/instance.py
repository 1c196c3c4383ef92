"""MDL materials as the render core's materials: a material call becomes a
:class:`render.material.material` whose distribution functions are the core's df nodes.

A material definition is evaluated at the *material level* once per instance (once per
scene object), as the MDL SDK instantiates a material into a DAG:

* ``df::`` calls become :class:`render.material.DfNode` trees, the material structs
  (``material(...)``, ``material_surface(...)``...) the core's structs, a call of a
  material in MDL is instantiated in turn, a call of a material of the workbench
  (``::materials``) calls its Python definition; ``m.surface`` reads a field;
  ``cond ? a : b`` with a uniform condition chooses;
* every *data* value (a tint, a roughness, a displacement, a normal, a cutout) is either
  a constant -- when it depends on nothing that varies over the surface, it is computed
  once, here, so the core sees a constant and runs the same constant program as for a
  built-in material -- or a function of the shading state: the expression compiled to
  generated code (:mod:`render.mdlc.codegen`) with the values it depends on as
  arguments, run by the core where it evaluates varying arguments (per hit, over lanes);
* a data value that *is* a call of the workbench's library (``uv_wave(...)``,
  ``displace_with_pwc(...)``) is that Python function's own result, so a displacement
  keeps the knots the dicer aligns vertices to, exactly as the built-in materials do.

Errors (a uniform parameter given a varying value, a Python material refusing an
argument) are :class:`MaterialInstanceError` at the MDL call that caused them.
"""

from __future__ import annotations

import threading
from dataclasses import dataclass

import numpy as np

from mdl import ast as A
from mdl import lanes as LN
from mdl import types as T
from mdl.checker import Checker, is_material_level
from mdl.entities import AUTO, UNIFORM, ConstEntity, EnumValueEntity, Local, Overload
from render.mdlc import compiler
from render.mdlc.knots import merge_knots
from render.mdlc.natives import RESOURCE_QUERIES, df_key, native_value

__all__ = ["Const", "Vary", "MaterialInstanceError", "Instantiator", "to_core"]


#: built-in constructors of data values (``float2 p(x, y);`` in a let)
_DATA_CTORS = ("scalar", "vector", "color", "matrix")

#: the fix for material parts built other than MDL allows
_PARTS_FIX = "build material parts from constructor and material calls, let and ?: only"


class MaterialInstanceError(ValueError):
    """A material cannot be built from these arguments; ``module`` and ``node`` locate
    the call in its MDL source."""

    def __init__(self, message: str, module, node, fix: str = ""):
        super().__init__(message)
        self.message, self.module, self.node, self.fix = message, module, node, fix

    def diagnostic(self):
        span = self.node.span
        return self.module.source.diagnostic("error", self.message, span.start, span.end,
                                             self.fix)

    def __str__(self) -> str:
        return self.diagnostic().format()


@dataclass(frozen=True)
class Const:
    """A data value uniform over the surface (lane representation, one lane)."""

    value: object
    type: T.Type


class Vary:
    """A data value that varies over the surface: ``lanes(S)`` its lane value on the
    state's lanes, ``core`` the callable the render core evaluates (a
    :class:`render.material.Varying`, or a library function's own result)."""

    def __init__(self, type_: T.Type, lanes, core=None, name: str = "", knots=None):
        self.type = type_
        self._lanes = lanes
        self.name = name
        self._knots = knots  # (knots_u, knots_v), or a function giving them (lazily)
        self._cache = threading.local()
        self.core = core if core is not None else self._make_core()

    @property
    def knots(self) -> tuple:
        """``(knots_u, knots_v)`` of the value as a displacement (:mod:`render.mdlc.knots`);
        a library function's own field keeps its ``uv_knots``."""
        if callable(self._knots):
            self._knots = self._knots()
        if self._knots is None:
            self._knots = getattr(self.core, "uv_knots", None) or (None, None)
        return self._knots

    def lanes(self, S):
        c = self._cache
        if getattr(c, "state", None) is S:
            return c.value
        v = self._lanes(S)
        c.state, c.value = S, v
        return v

    def _make_core(self):
        from render.material import Varying

        t = self.type
        suffix = LN.suffix(t)

        def function(S):
            v = np.asarray(self.lanes(S))
            n = len(S)
            if v.dtype != np.float64 and T.elem_kind(t) != "bool":
                v = v.astype(np.float64)
            return np.broadcast_to(v, (n,) + suffix) if v.shape[0] != n else v

        return Varying(function, self.name or "mdl")

    def __reduce__(self):
        return (_rebuild_vary, (self.type, self._lanes, self.core, self.name, self.knots))


def _rebuild_vary(t, lanes, core, name, knots=None):
    return Vary(t, lanes, core, name, knots)


def to_core(v, t: T.Type):
    """A material-level value as the render core's argument."""
    if isinstance(v, Const):
        return native_value(v.value, v.type)
    if isinstance(v, Vary):
        return v.core
    return v


def _dummy_state():
    from displacement.state import ShadingState

    z = np.zeros((1, 3))
    return ShadingState(z, np.array([[0.0, 0.0, 1.0]]), np.zeros((1, 2)),
                        np.array([[1.0, 0.0, 0.0]]), np.array([[0.0, 1.0, 0.0]]))


_BUILTIN_STRUCTS = ("material", "material_surface", "material_emission", "material_volume",
                    "material_geometry")


class Instantiator:
    """Evaluates material definitions and expressions at the material level."""

    def __init__(self):
        self.depth = 0

    # ------------------------------------------------------------------ entry points
    def call_overload(self, o: Overload, args: dict, module, node):
        """Instantiate material (or evaluate material-level function) ``o`` with
        material-level ``args`` (name -> value; absent: the default)."""
        self.depth += 1
        if self.depth > 64:
            raise MaterialInstanceError("materials call each other more than 64 deep",
                                        module, node, "look for a material that calls itself")
        try:
            return self._call(o, args, module, node)
        finally:
            self.depth -= 1

    def _call(self, o: Overload, args: dict, module, node):
        for p in o.params:
            v = args.get(p.name)
            if p.uniform and isinstance(v, Vary):
                raise MaterialInstanceError(
                    f"argument '{p.name}' of {o.name} is uniform, but its value varies over "
                    "the surface", module, node, "pass a constant (or a uniform value)")
        if o.kind == "native":
            return self.native(o, args, module, node)
        if o.kind == "struct":
            return self.struct(o, args, module, node)
        if o.kind == "mdl":
            return self.mdl_material(o, args, module, node)
        raise MaterialInstanceError(f"'{o.name}' cannot be used in a material", module, node,
                                    "call a material, a df or a struct constructor here")

    def mdl_material(self, o: Overload, args: dict, module, node):
        m = o.module
        d: A.FunctionDecl = o.decl
        env: dict = {}
        for p, pd in zip(o.params, d.params, strict=True):
            loc = m.locals.get(id(pd))
            if p.name in args:
                v = args[p.name]
            elif p.default is not None:
                v = self.eval(m, p.default, env, want=p.type)
            else:
                raise MaterialInstanceError(f"{o.name} needs the argument '{p.name}'",
                                            module, node, f"add '{p.name}: value' to the call")
            if loc is not None:
                env[id(loc)] = v
        return self.eval(m, d.body, env, want=o.ret)

    def native(self, o: Overload, args: dict, module, node):
        from render.material import df

        data = o.module.native if isinstance(o.module.native, dict) else {}
        kind = data.get("kind")
        kwargs = {p.name: to_core(args[p.name], p.type) for p in o.params if p.name in args}
        try:
            if kind == "df" and o.name in RESOURCE_QUERIES:
                return RESOURCE_QUERIES[o.name][2](**kwargs)
            if kind == "df":
                return getattr(df, df_key(o))(**kwargs)  # the overload the checker chose
            if kind == "materials":
                from render.materials import MATERIALS

                return MATERIALS[o.name](**kwargs)
            if kind == "functions":
                from render.library.functions import FUNCTIONS

                return FUNCTIONS[o.name](**kwargs)
            if kind == "sky":
                from render.mdlc.natives import SkyFunction, sun_and_sky_light

                return SkyFunction(sun_and_sky_light(**kwargs))
        except MaterialInstanceError:
            raise
        except (ValueError, TypeError, LookupError) as e:
            raise MaterialInstanceError(
                f"{o.name}(...): {e}", module, _argument_node(node, o, str(e)),
                f"change the value it names (pwc mdl info {o.module.qname} lists the "
                "parameters)") from None
        raise MaterialInstanceError(f"'{o.name}' of {o.module.qname} has no implementation",
                                    module, node, "use another function of the module")

    def struct(self, o: Overload, args: dict, module, node):
        st: T.StructType = o.ret
        if st.builtin:
            from render import material as M

            cls = getattr(M, st.qname.removeprefix("::"))
            kwargs = {}
            for p in o.params:
                if p.name not in args:
                    continue
                v = args[p.name]
                core = to_core(v, p.type)
                if st.qname == "::material_geometry" and p.name == "displacement" and \
                        isinstance(v, Vary) and not hasattr(core, "uv_knots"):
                    from displacement.fields import Field

                    core = Field(core, v.knots, v.name or "mdl displacement")
                kwargs[p.name] = core
            try:
                return cls(**kwargs)
            except ValueError as e:
                raise MaterialInstanceError(f"{st.qname.removeprefix('::')}(...): {e}",
                                            module, _argument_node(node, o, str(e)),
                                            "change the value it names") from None
        if o.module.kind == "native":
            return self.native(o, args, module, node)
        raise MaterialInstanceError(f"struct {st.name} holds distribution functions; only "
                                    "the workbench's df structs are supported", module, node,
                                    "pass the distribution functions separately")

    # ------------------------------------------------------------------ evaluation
    def eval(self, m, e, env: dict, want: T.Type | None = None):
        """The material-level value of expression ``e`` of module ``m``."""
        info = m.info[id(e)]
        t = info.type
        if is_material_level(t) or isinstance(t, (T.Resource, T.String)):
            v = self.structural(m, e, env)
        else:
            v = self.data(m, e, env)
        if info.convert is not None:
            v = self.convert(v, t, info.convert)
        elif want is not None and isinstance(v, (Const, Vary)) and v.type != want and \
                not isinstance(want, (T.ArrayT, T.AutoType)):
            v = self.convert(v, v.type, want)
        return v

    def convert(self, v, src: T.Type, dst: T.Type):
        if isinstance(v, Const):
            return Const(LN.convert(v.value, src, dst), dst)
        if isinstance(v, Vary):
            inner = v
            return Vary(dst, lambda S: LN.convert(inner.lanes(S), src, dst), None, v.name,
                        lambda: inner.knots)
        return v

    def structural(self, m, e, env):
        info = m.info[id(e)]
        if isinstance(e, A.Ref):
            tgt = info.target
            if isinstance(tgt, Local):
                if id(tgt) not in env:
                    raise MaterialInstanceError(f"'{tgt.name}' has no value here", m, e,
                                                "give it a value before this use")
                return env[id(tgt)]
            if isinstance(tgt, ConstEntity):
                return Const(tgt.value, tgt.type)
            raise MaterialInstanceError(f"'{e.name.text}' cannot be used here", m, e,
                                        "use a value, a constant or a call here")
        if isinstance(e, A.Literal):
            return Const(e.value, info.type)
        if isinstance(e, A.Call):
            return self.call(m, e, env)
        if isinstance(e, A.Member):
            obj = self.eval(m, e.obj, env)
            try:
                return self.wrap(getattr(obj, e.name), info.type)
            except AttributeError:
                raise MaterialInstanceError(f"this value has no field '{e.name}'", m, e,
                                            "use one of the struct's fields") from None
        if isinstance(e, A.Conditional):
            c = self.eval(m, e.cond, env)
            if not isinstance(c, Const):
                raise MaterialInstanceError("the condition choosing a material part varies "
                                            "over the surface", m, e.cond,
                                            "use a uniform condition")
            return self.eval(m, e.then if LN.as_bool(c.value) else e.other, env)
        if isinstance(e, A.Let):
            inner = dict(env)
            for d in e.decls:
                for dc in d.declarators:
                    loc = m.locals[id(dc)]
                    if dc.init is not None:
                        inner[id(loc)] = self.eval(m, dc.init, inner, want=loc.type)
                    elif dc.ctor_args is not None and not is_material_level(loc.type) and \
                            m.info[id(dc)].call is not None and \
                            m.info[id(dc)].call.kind in _DATA_CTORS:
                        inner[id(loc)] = self.data_ctor(m, dc, inner)
                    elif dc.ctor_args is not None:
                        inner[id(loc)] = self.call(m, dc, inner)
                    else:
                        inner[id(loc)] = self.default_value(loc.type, m, dc)
            return self.eval(m, e.body, inner)
        if isinstance(e, A.Index):
            arr = self.eval(m, e.obj, env)
            i = self.eval(m, e.index, env)
            if isinstance(arr, (list, tuple)) and isinstance(i, Const):
                return arr[int(LN.uniform_value(i.value))]
        raise MaterialInstanceError(f"this {type(e).__name__.lower()} cannot build a "
                                    f"{info.type}", m, e, _PARTS_FIX)

    def data_ctor(self, m, dc, env):
        """``float2 p(x, y);`` in a let: a built-in constructor of data values."""
        from mdl.construct import construct

        call = m.info[id(dc)].call
        t = call.type
        args = [a for a in call.args if a is not None]
        vals = [self.eval(m, a, env) for a in args]
        types = [v.type if isinstance(v, (Const, Vary)) else m.info[id(a)].type
                 for v, a in zip(vals, args, strict=True)]
        if all(isinstance(v, Const) for v in vals):
            return Const(construct(call.kind, t, [v.value for v in vals], types), t)

        def lanes(S, vals=tuple(vals)):
            parts = [v.value if isinstance(v, Const) else v.lanes(S) for v in vals]
            n = len(S)
            parts = [LN.broadcast_lanes(x, n) if LN.lanes_of(x) == 1 else x for x in parts]
            return construct(call.kind, t, parts, types, n)

        return Vary(t, lanes, None, dc.name,
                    lambda: merge_knots(*[v.knots for v in vals if isinstance(v, Vary)]))

    def default_value(self, t: T.Type, m, node):
        if isinstance(t, T.DF):
            return None
        if isinstance(t, T.StructType) and t.builtin:
            from render import material as M

            return getattr(M, t.qname.removeprefix("::"))()
        return Const(LN.zeros(t), t)

    def wrap(self, value, t: T.Type):
        """A field of a core struct as a material-level value."""
        if is_material_level(t) or value is None:
            return value
        if callable(value):
            return Vary(t, lambda S, f=value: np.asarray(f(S)), value, getattr(
                value, "name", ""))
        return Const(LN.from_python(value, t) if not isinstance(t, T.ArrayT) else value, t)

    def call(self, m, e, env):
        info = m.info[id(e)]
        call = info.call
        if call is None:
            raise MaterialInstanceError("this value cannot be built here", m, e, _PARTS_FIX)
        if call.kind == "df_default":
            return None
        if call.kind == "resource":
            name_node, gamma_node = call.args
            if name_node is None:
                return Const(None, call.type)
            name = m.info[id(name_node)].const
            gamma = None
            if gamma_node is not None:
                gi = m.info[id(gamma_node)]
                gamma = LN.to_python(gi.const, gi.type)
            from render.library.resources import ResourceError

            try:
                tex = compiler.resource_loader(m, str(call.type), name, gamma, strict=True)
            except ResourceError as err:
                raise MaterialInstanceError(err.message, m, name_node, err.hint or "") from None
            return Const(tex, call.type)
        if call.kind == "array":
            elem = call.type.elem
            return [self.eval(m, a, env, want=elem) for a in call.args]
        if call.kind != "overload":
            raise MaterialInstanceError(f"a {call.kind} constructor cannot build a "
                                        f"{info.type}", m, e, _PARTS_FIX)
        o: Overload = call.target
        args = {}
        for p, a in zip(o.params, call.args, strict=True):
            if a is None:
                continue
            pt = Checker.bind_sizes(p.type, call.sizes)
            args[p.name] = self.eval(m, a, env, want=pt)
        return self.call_overload(o, args, m, e)

    # ------------------------------------------------------------------ data values
    def data(self, m, e, env):
        info = m.info[id(e)]
        t = info.type
        if info.const is not None:
            return Const(info.const, t)
        if isinstance(e, A.Ref) and isinstance(info.target, Local) and id(info.target) in env:
            return env[id(info.target)]
        if isinstance(e, A.Ref) and isinstance(info.target, ConstEntity):
            return Const(info.target.value, t)
        if isinstance(e, A.Ref) and isinstance(info.target, EnumValueEntity):
            return Const(LN.const(t, info.target.value), t)
        if isinstance(e, A.Member) and is_material_level(m.info[id(e.obj)].type):
            return self.structural(m, e, env)
        if isinstance(e, A.Call) and info.call is not None and info.call.kind == "overload" \
                and info.call.target.kind == "native":
            return self.native_data(m, e, env)
        return self.lane_value(m, e, env)

    def native_data(self, m, e, env):
        """A library function called with material-level arguments: its own result."""
        info = m.info[id(e)]
        o = info.call.target
        args = {}
        for p, a in zip(o.params, info.call.args, strict=True):
            if a is None:
                continue
            args[p.name] = self.eval(m, a, env, want=Checker.bind_sizes(p.type, info.call.sizes))
        result = self.native(o, args, m, e)
        if callable(result):
            return Vary(info.type, lambda S, f=result: np.asarray(f(S)), result, o.name)
        return Const(LN.const(info.type, result), info.type)

    def inputs(self, m, e, env) -> list:
        """The nodes of data expression ``e`` given as values to its lane function."""
        out = []
        stack = [e]
        while stack:
            x = stack.pop()
            xi = m.info.get(id(x))
            if isinstance(x, A.Ref) and xi is not None and isinstance(xi.target, Local) and \
                    id(xi.target) in env:
                out.append(x)
                continue
            if isinstance(x, A.Member) and xi is not None and \
                    is_material_level(m.info[id(x.obj)].type) and not is_material_level(xi.type):
                out.append(x)
                continue
            if isinstance(x, A.Node):
                stack.extend(A.children(x))
        return out

    def lane_value(self, m, e, env):
        info = m.info[id(e)]
        t = info.type
        nodes = self.inputs(m, e, env)
        values = []
        for n in nodes:
            ni = m.info[id(n)]
            if isinstance(n, A.Member):
                v = self.structural(m, n, env)
            else:
                v = env[id(ni.target)]
            if isinstance(v, (Const, Vary)) and ni.convert is None and v.type != ni.type and \
                    not isinstance(ni.type, T.ArrayT):
                v = self.convert(v, v.type, ni.type)
            values.append(v)
        f = compiler.lane_function(m, e, nodes, t)
        if info.level <= AUTO and all(isinstance(v, Const) for v in values):
            try:
                with np.errstate(all="ignore"):
                    out = f(_dummy_state(), 1, *[v.value for v in values])
            except Exception as err:  # noqa: BLE001 - report at the expression
                raise MaterialInstanceError(
                    f"evaluating this value failed: {err}", m, e,
                    "check what it computes (an index out of range, a failed assert...)") \
                    from None
            return Const(_one_lane(out), t)

        def lanes(S, f=f, values=tuple(values)):
            args = [v.value if isinstance(v, Const) else v.lanes(S) for v in values]
            with np.errstate(all="ignore"):
                return f(S, len(S), *args)

        def knots(values=tuple(values), nodes=tuple(nodes)):
            from render.mdlc.knots import merge_knots, uv_knots

            consts = [(m.info[id(n)].type, v.value) for n, v in zip(nodes, values, strict=True)
                      if isinstance(v, Const)]
            return merge_knots(uv_knots(m, e, consts),
                               *[v.knots for v in values if isinstance(v, Vary)])

        line, col = m.source.line_col(e.span.start)
        return Vary(t, lanes, None, f"mdl {m.source.name}:{line}:{col}", knots)


def _argument_node(node, o: Overload, message: str):
    """The argument of call ``node`` that ``message`` names (``material.ior must be...``,
    ``roughness must be...``), else the call."""
    import re

    if not isinstance(node, A.Call):
        return node
    names = [p.name for p in o.params]
    best = None
    for k, a in enumerate(node.args):
        name = a.name if a.name is not None else (names[k] if k < len(names) else None)
        m = re.search(rf"(^|[.\s']){re.escape(name)}\b", message) if name else None
        if m and (best is None or m.start() < best[0]):
            best = (m.start(), a)  # the argument the message names first
    return node if best is None else best[1]


def _one_lane(v):
    if isinstance(v, tuple):
        return tuple(_one_lane(x) for x in v)
    if isinstance(v, np.ndarray) and v.ndim and v.shape[0] != 1:
        return v[:1]
    return v


del UNIFORM
