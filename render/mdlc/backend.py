"""The workbench as an MDL back end of ``pwc mdl`` (the ``pwc.mdl`` entry point).

``pwc mdl check`` finds the workbench's modules (``::df``, ``::materials``,
``::functions``, profiles...) through :meth:`Backend.providers`, and compiles every
function of a checked module to the generated code that renders it
(:meth:`Backend.compile`), so what the renderer cannot compile is reported by the check,
located, before a render.
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

    def python(self, module) -> str:
        from render.mdlc.compiler import source_of

        return source_of(module)


def backend() -> Backend:
    """The entry point: ``[project.entry-points."pwc.mdl"] workbench = ...``."""
    return Backend()
