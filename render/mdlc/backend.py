"""The workbench as an MDL back end of ``pwc mdl`` (the ``pwc.mdl`` entry point).

``pwc mdl check`` finds the workbench's modules (``::df``, ``::materials``,
``::functions``, profiles...) through :meth:`Backend.providers`, and compiles every
function of a checked module to the generated code that renders it
(:meth:`Backend.compile`), so what the renderer cannot compile is reported by the check,
located, before a render; every exported material whose parameters all have defaults is
built too (its textures read, its Python natives called), so a missing texture or a value
a df refuses is reported as well.
"""

from __future__ import annotations

from mdl.diagnostics import MdlError

__all__ = ["Backend", "backend"]


class Backend:
    def providers(self):
        from render.mdlc.natives import WorkbenchModules

        return [WorkbenchModules()]

    def compile(self, module) -> None:
        from render.mdlc.codegen import CodegenError
        from render.mdlc.compiler import module_code

        try:
            module_code(module)
        except CodegenError as e:  # pragma: no cover - codegen errors are located MdlErrors
            raise MdlError([module.source.diagnostic("error", e.message, e.node.span.start,
                                                     e.node.span.end, e.fix)]) from None
        self.instantiate(module)
        self.find_resources(module)

    def find_resources(self, module) -> None:
        """A warning for each resource file (a texture, an MBSDF or IES file) named in ``module``
        that is not found (MDL reads it as an invalid resource, black; a scene refuses
        it)."""
        from mdl import ast as A
        from render.library.resources import find_texture

        base = None if module.path is None else module.path.parent
        known = {(d.loc.line, d.loc.col) for d in module.diagnostics}
        for info in list(module.info.values()):
            call = info.call
            if call is None or call.kind != "resource" or not call.args or \
                    call.args[0] is None:
                continue
            name_node = call.args[0]
            name = module.info[id(name_node)].const
            if not isinstance(name, str) or not isinstance(name_node, A.Node) or \
                    find_texture(name, base) is not None:
                continue
            what = "texture" if str(call.type) == "texture_2d" else str(call.type)
            d = module.source.diagnostic(
                "warning", f"{what} {name!r} not found beside the module or on the texture "
                f"path: MDL reads it as an invalid {what} (black), a scene refuses it",
                name_node.span.start, name_node.span.end,
                f"put {name} beside the module (or beside the scene that uses it)")
            if (d.loc.line, d.loc.col) not in known:
                module.diagnostics.append(d)

    def instantiate(self, module) -> None:
        """Build each exported material of ``module`` whose parameters all have defaults
        (raises :class:`MdlError` with every failure, located)."""
        from render.mdlc import compiler
        from render.mdlc.instance import Instantiator, MaterialInstanceError
        from render.mdlc.natives import register_profiles

        register_profiles(_imported(module))
        errors = []
        saved = compiler.SCENE_DIR[0]
        compiler.SCENE_DIR[0] = None if module.path is None else module.path.parent
        try:
            for o in module.materials():
                if not o.exported or any(p.default is None for p in o.params):
                    continue
                try:
                    Instantiator().call_overload(o, {}, module, o.decl)
                except MaterialInstanceError as e:
                    errors.append(e.diagnostic())
        finally:
            compiler.SCENE_DIR[0] = saved
        if errors:
            raise MdlError(errors)

    def python(self, module) -> str:
        from render.mdlc.compiler import source_of

        return source_of(module)


def _imported(module) -> list:
    """``module`` and every module it imports, transitively."""
    out, stack, seen = [], [module], set()
    while stack:
        m = stack.pop()
        m = m.module if not hasattr(m, "imports") else m  # a partial import
        if id(m) in seen:
            continue
        seen.add(id(m))
        out.append(m)
        stack.extend(m.imports.values())
    return out


def backend() -> Backend:
    """The entry point: ``[project.entry-points."pwc.mdl"] workbench = ...``."""
    return Backend()
