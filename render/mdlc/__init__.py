"""MDL modules in the renderer: loading, compiling and instantiating materials.

The language is :mod:`mdl` (the front end); this package is its back end for the
workbench:

* :mod:`render.mdlc.natives` -- the workbench's modules (``::df``, ``::materials``,
  ``::functions``, ``::pw_curve``, profiles as modules, the MDL library in
  ``render/library/mdl``);
* :mod:`render.mdlc.codegen` and :mod:`render.mdlc.compiler` -- MDL function bodies as
  generated Python over lanes, compiled once per module content;
* :mod:`render.mdlc.rt` -- what the generated code calls (``::state``, ``::tex``...);
* :mod:`render.mdlc.instance` -- materials as the render core's materials;
* :mod:`render.mdlc.knots` -- the creases of a displacement written in MDL, for dicing;
* :mod:`render.mdlc.environment` -- environment lights written in MDL
  (``base::sun_and_sky``, or any colour function of ``state::direction()``);
* :mod:`render.mdlc.backend` -- the workbench as ``pwc mdl``'s back end.

:func:`material_from_call` is the entry point of scenes: a call (``glossy(tint:
color(0.5))``, or ``stone_molding(scale: 2.0)`` into a named module) becomes a
:class:`render.material.material`.

Module search: the folders given (a scene's own folder first, then ``--mdl-path``
folders, then ``$PWC_MDL_PATH``), then the workbench's modules; ``::df`` and MDL's
standard modules cannot be shadowed.
"""

from __future__ import annotations

import re
from pathlib import Path

from mdl.checker import check_expression
from mdl.diagnostics import MdlError, Source
from mdl.loader import MDL_PATH_ENV, Loader, search_path_from_env
from render.mdlc.instance import MaterialInstanceError
from render.mdlc.natives import WorkbenchModules, register_profiles

__all__ = ["Session", "material_from_call", "CAPTION_CONTEXT", "MDL_PATH_ENV", "make_loader",
           "module_search_path"]

#: The names a scene's material call sees (the string form, as the Handbook prints its
#: calls): the workbench's materials and functions unqualified, the standard modules
#: qualified.  Any other module the call names (``base::``, ``pwc_examples::``, the
#: Handbook's ``perlin_noise::``...) is imported when it does: importing the five the
#: Handbook's calls use every time was half of a scene file's check (0.11 s of 0.21 s).
CAPTION_CONTEXT = """\
mdl 1.8;
import ::df::*;
import ::state::*;
import ::tex::*;
import ::math::*;
import ::anno::*;
import ::materials::*;
import ::functions::*;
import ::pw_curve::*;
using ::materials import *;
using ::functions import *;
using ::df import *;
using ::pw_curve import pw_point, pw_type, segment, angle, sagitta, cyma_recta, cyma_reversa,
    flare, displacement_direction, along_u, along_v;
"""


#: the modules :data:`CAPTION_CONTEXT` imports, and standard modules a call's ``name::``
#: does not import
_IN_CAPTION_CONTEXT = frozenset({"df", "state", "tex", "math", "anno", "materials",
                                 "functions", "pw_curve", "limits", "debug", "scene"})
#: the names a call qualifies (``a`` and ``b`` of ``::a::b::c``)
_QUALIFIERS = re.compile(r"(?:::)?([A-Za-z][A-Za-z0-9_]*)(?=\s*::)")


def module_search_path(base_dir=None, mdl_paths=()) -> list[Path]:
    """The folders searched for modules: ``base_dir``, ``mdl_paths``, ``$PWC_MDL_PATH``."""
    out = []
    if base_dir is not None:
        out.append(Path(base_dir))
    out += [Path(p) for p in mdl_paths]
    out += search_path_from_env()
    return out


def make_loader(base_dir=None, mdl_paths=()) -> Loader:
    """A loader with the workbench's modules and the module search path."""
    return Loader(module_search_path(base_dir, mdl_paths), [WorkbenchModules()])


class Session:
    """One set of modules (a scene's): loads modules and builds materials from calls."""

    def __init__(self, base_dir=None, mdl_paths=()):
        self.base_dir = None if base_dir is None else Path(base_dir)
        self.loader = make_loader(base_dir, mdl_paths)

    def context(self, text: str, name: str):
        module = self.loader.load_text(text, name)
        register_profiles(list(self.loader.modules.values()))
        return module

    def mentioned_imports(self, expr_text: str) -> list[str]:
        """Imports of the modules a call names as ``name::`` beyond
        :data:`CAPTION_CONTEXT`'s."""
        words = set(_QUALIFIERS.findall(expr_text))
        return [f"import ::{w}::*;" for w in sorted(words - _IN_CAPTION_CONTEXT)
                if self.loader.find("::" + w) is not None]

    def caption_context(self, expr_text: str):
        """The scope of a string-form call: :data:`CAPTION_CONTEXT` plus the modules its
        names mention (``base::``, ``ornament_2::ornament_2``, or a bare profile name)."""
        extra = self.mentioned_imports(expr_text)
        words = set(_QUALIFIERS.findall(expr_text))
        for w in sorted(set(re.findall(r"\b([A-Za-z][A-Za-z0-9_]*)\b", expr_text))):
            stem = w[:-len("_length")] if w.endswith("_length") else w
            if stem in _IN_CAPTION_CONTEXT or stem in words:
                continue
            found = self.loader.find("::" + stem)
            if found is not None and isinstance(found.native, dict) and \
                    found.native.get("kind") == "profile":
                extra.append(f"import ::{stem}::*;")
                extra.append(f"using ::{stem} import {stem}, {stem}_length;")
        return self.context(CAPTION_CONTEXT + "\n".join(extra) + "\n", "<material call>")

    def module_context(self, module: str, where: str, expr_text: str = ""):
        """The scope of a call ``expr_text`` into ``module`` (a file name or
        ``::qualified::name``)."""
        qname, mt = self.find_module(module, where)
        lines = [line for line in CAPTION_CONTEXT.splitlines() if line.startswith(("mdl",
                                                                                    "import"))]
        lines += self.mentioned_imports(expr_text)
        lines += [f"import {qname}::*;", f"using {qname} import *;"]
        return self.context("\n".join(lines) + "\n", "<material call>")

    def find_module(self, module: str, where: str):
        """``(qualified name, ModuleText)`` of a scene's ``module = "..."`` value."""
        if module.startswith("::") or (not module.endswith(".mdl") and "::" in module):
            qname = module if module.startswith("::") else "::" + module
            mt = self.loader.find(qname)
            if mt is None:
                raise _not_found(module, self.loader, where)
            return qname, mt
        path = Path(module)
        if path.suffix != ".mdl":
            raise ValueError(f"module {module!r} is neither an .mdl file nor a qualified "
                             "name (::a::b)")
        candidates = [path] if path.is_absolute() else [
            d / path for d in self.loader.search_path] + [
            Path(__file__).resolve().parent.parent / "library" / "mdl" / path]
        for c in candidates:
            if c.is_file():
                qname = "::" + c.stem
                mt = self.loader.read(c, qname)
                existing = self.loader.modules.get(qname)
                if existing is None:
                    self.loader.check(mt)
                return qname, mt
        raise _not_found(module, self.loader, where)

    def check_call(self, text: str, source: Source, module: str | None = None):
        context = (self.module_context(module, source.name, text) if module is not None
                   else self.caption_context(text))
        tree, info = check_expression(self.loader, context, source)
        register_profiles(list(self.loader.modules.values()))
        # the call's nodes are located in its own text (a scene file)
        context.source = source
        return context, tree, info

    def material(self, text: str, source: Source | None = None, module: str | None = None):
        """The material (or value) a call builds; raises :class:`MdlError` located in
        ``source`` (default: the call text itself)."""
        from render.mdlc import compiler
        from render.mdlc.instance import Instantiator

        source = source or Source("<material call>", text)
        context, tree, info = self.check_call(text, source, module)
        saved = compiler.SCENE_DIR[0]
        compiler.SCENE_DIR[0] = self.base_dir
        try:
            return Instantiator().eval(context, tree, {}), info
        finally:
            compiler.SCENE_DIR[0] = saved


def _not_found(module: str, loader: Loader, where: str) -> ValueError:
    folders = ", ".join(str(d) for d in loader.search_path) or "(none)"
    return ValueError(f"module {module!r} not found in {folders} or the workbench's library "
                      f"(add folders with --mdl-path DIR or ${MDL_PATH_ENV})")


def material_from_call(call: str, module: str | None = None, *, base_dir=None, mdl_paths=(),
                       source_name: str = "<material call>", line: int = 1, col: int = 1):
    """A :class:`render.material.material` from a material call.

    Parameters
    ----------
    call : str
        ``glossy(tint: color(0.5))`` (string form: the workbench's materials by name), or a
        call of an export of ``module``.
    module : str, optional
        ``"mouldings.mdl"`` (found beside the scene, on the search path, or in the
        workbench's library) or ``"::a::b"``.
    base_dir, mdl_paths
        The scene's folder and ``--mdl-path`` folders.
    source_name, line, col
        Where ``call`` is written (a scene file), for diagnostics.

    Raises
    ------
    MdlError
        Syntax, name and type errors, located; errors of the materials' Python
        definitions at the call that passed the value.
    """
    session = Session(base_dir, mdl_paths)
    src = Source(source_name, call, line - 1, col - 1)
    try:
        value, info = session.material(call, src, module)
    except MaterialInstanceError as e:
        raise MdlError([e.diagnostic()]) from None
    return value, info


def run_function(module, name: str, state, *args, index: int = 0):
    """Run MDL function ``name`` of checked ``module`` on the lanes of ``state``.

    ``args`` are Python values (uniform: numbers, tuples, dicts for structs, lists for
    arrays) or numpy arrays with one row per lane (varying).  Returns the lane value
    (numpy; a tuple for a struct).  For tests and the Handbook check.
    """
    import numpy as np

    from mdl import lanes as LN
    from render.mdlc.compiler import module_code

    overloads = module.functions(name)
    if not overloads:
        raise KeyError(f"{module.qname} has no function {name!r}")
    o = overloads[index]
    ns = module_code(module)
    lanes = []
    for p, a in zip(o.params, args, strict=False):
        if isinstance(a, np.ndarray) and not isinstance(p.type, type(None)):
            lanes.append(a if a.dtype != np.float32 else a.astype(np.float64))
        elif hasattr(a, "__len__") and isinstance(a, tuple) and not a:
            lanes.append(None)
        else:
            lanes.append(LN.from_python(a, p.type))
    n = len(state)
    with np.errstate(all="ignore"):
        return ns[f"f_{o.mangled}"](state, n, *lanes)
