"""Generated code of checked MDL modules, compiled once per module content.

:func:`module_code` turns a :class:`~mdl.entities.CheckedModule` into a namespace of
Python functions (:mod:`render.mdlc.codegen`) and keeps it by the module's content key:
a process generates and compiles each module once, whichever scene or loader reads it.
:func:`lane_function` does the same for one data expression of a material (a tint, a
displacement), with the values it depends on as parameters.

The namespace holds the runtime (:mod:`render.mdlc.rt`), the module's constants
(``_K``), types (``_T``), natives (``_N``, the Python functions of the workbench's
library), resources (``_res``: textures, loaded on first use, beside the module first)
and the modules it calls (``_M``).
"""

from __future__ import annotations

import threading

import numpy as np

from mdl import lanes as LN
from mdl import mathlib
from mdl import types as T
from mdl.construct import construct
from render.mdlc import codegen, rt
from render.mdlc.natives import PROFILE_VALUES, bind_native

__all__ = ["module_code", "lane_function", "CODE_CACHE", "source_of", "resource_loader"]

#: content key -> namespace of the module's generated code
CODE_CACHE: dict[str, dict] = {}
_SOURCES: dict[str, str] = {}
_LOCK = threading.RLock()


class _Modules(dict):
    """``_M``: the generated code of called modules, compiled on first use."""

    def __init__(self, modules: dict):
        super().__init__()
        self._modules = modules

    def __missing__(self, qname):
        ns = module_code(self._modules[qname])
        obj = _Namespace(ns)
        self[qname] = obj
        return obj


class _Namespace:
    def __init__(self, ns: dict):
        self.__dict__.update({k: v for k, v in ns.items() if k.startswith(("f_", "ctor_"))})


def _zero(t: T.Type):
    return rt.zero_of(t)


#: the folder a scene's textures are looked for first (set while a scene is read)
SCENE_DIR: list = [None]


def resource_loader(module, kind: str, name: str, gamma, strict: bool = False):
    """Load a resource named in ``module`` (a texture, an MBSDF file for
    ``bsdf_measurement``, an IES file for ``light_profile``): beside the module file
    first, then in the scene's folder, then the texture search path.  A missing file is
    MDL's invalid resource (texture lookups give 0) unless ``strict`` (then
    :class:`ResourceError`)."""
    from render.library.resources import (
        ResourceError,
        load_light_profile,
        load_measurement,
        load_texture,
    )

    if kind not in codegen.RESOURCES:
        raise rt.MdlRuntimeError(f"{module.source.name}: {kind} resources are not supported "
                                 "by the workbench (2D textures, measured BSDFs and light "
                                 "profiles only)")
    mode = {"gamma_linear": "linear", "gamma_srgb": "srgb", None: "default",
            "gamma_default": "default"}.get(gamma, "default")
    bases = (None if module.path is None else module.path.parent, SCENE_DIR[0])
    try:
        if kind == "bsdf_measurement":
            return load_measurement(name, bases)
        if kind == "light_profile":
            return load_light_profile(name, bases)
        return load_texture(name, mode, bases)
    except ResourceError:
        if strict:
            raise
    return None


def _prelude(mg: codegen.ModuleGen) -> dict:
    module = mg.module
    # resources load now: beside the module, or in the scene's folder being read
    cache = {i: resource_loader(module, *r) for i, r in enumerate(mg.resources)}

    def res(i):
        return cache[i]

    curves = PROFILE_VALUES
    return {
        "np": np, "LN": LN, "MATH": mathlib, "construct": construct, "STATE": rt.STATE,
        "TEX": rt.TEX, "DEBUG": rt.DEBUG, "SCENE": rt.SCENE, "mcall": rt.mcall,
        "ncall": rt.ncall, "size_of": rt.size_of, "array_of": rt.array_of, "cv": rt.cv,
        "_K": mg.consts, "_T": mg.types, "_Z": _zero,
        "_N": [bind_native(o, curves) for o in mg.natives],
        "_M": _Modules(mg.mods), "_res": res,
        "_lookup1": lambda S, L, *a: rt.TEX.lookup(1, S, L, *a),
        "_lookup2": lambda S, L, *a: rt.TEX.lookup(2, S, L, *a),
        "_lookup3": lambda S, L, *a: rt.TEX.lookup(3, S, L, *a),
        "_lookup4": lambda S, L, *a: rt.TEX.lookup(4, S, L, *a),
    }


def _run(source: str, ns: dict, filename: str) -> None:
    exec(compile(source, filename, "exec"), ns)  # noqa: S102 - code we generated


def module_code(module) -> dict:
    """The namespace of ``module``'s generated functions (compiled once per key)."""
    with _LOCK:
        ns = CODE_CACHE.get(module.key)
        if ns is not None:
            return ns
        mg = codegen.ModuleGen(module, None)
        source = mg.generate()
        # natives and called modules are known once the source exists
        ns = _prelude(mg)
        _run(source, ns, f"<mdl {module.qname}>")
        CODE_CACHE[module.key] = ns
        _SOURCES[module.key] = source
        return ns


def source_of(module) -> str:
    """The generated Python of ``module`` (for ``pwc mdl info --python``)."""
    module_code(module)
    return _SOURCES[module.key]


_LANE_CACHE: dict = {}


def lane_function(module, expr, inputs: list, ret: T.Type):
    """A compiled ``f(S, L, *inputs)`` computing ``expr`` (a data expression of a
    material in ``module``); ``inputs`` are the nodes given as values (in order)."""
    key = (module.key, id(expr), tuple(id(n) for n in inputs), str(ret), str(SCENE_DIR[0]))
    with _LOCK:
        f = _LANE_CACHE.get(key)
        if f is not None:
            return f
        module_code(module)  # the module's own functions
        mg = codegen.ModuleGen(module, None)
        order = [f"x{k}" for k in range(len(inputs))]
        names = {id(n): p for n, p in zip(inputs, order, strict=True)}
        name = "lane_expression"
        source = codegen.lane_expression_source(mg, name, expr, names, order, ret)
        ns = dict(CODE_CACHE[module.key])
        ns.update(_prelude(mg))
        line, col = module.source.line_col(expr.span.start)
        _run(source, ns, f"<mdl {module.source.name}:{line}:{col}>")
        f = ns[name]
        f.mdl_source = source
        f.mdl_node = expr  # keeps the node alive: its id stays unique in the key
        if len(_LANE_CACHE) > 4096:
            _LANE_CACHE.pop(next(iter(_LANE_CACHE)))
        _LANE_CACHE[key] = f
        return f
