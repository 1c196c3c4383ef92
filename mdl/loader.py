"""Find, read and check MDL modules: the standard modules, the renderer's (providers),
and files on a search path.

A module is named by its qualified name (``::pw_curve``, ``::nvidia::core``).  The
:class:`Loader` looks a name up, in order, among

1. the standard modules (:mod:`mdl.stdlib`);
2. its *providers*: objects with ``find(qname) -> ModuleText | None`` (and optionally
   ``names() -> iterable of qnames`` for suggestions) that a renderer registers for the
   modules it implements (``::df``, its function library, generated modules);
3. files: ``a/b.mdl`` for ``::a::b`` in each search folder, in order (a relative
   import ``.::x`` is looked up beside the importing module first).

Every module is checked once per loader (:mod:`mdl.checker`); errors in an imported
module are reported with the import that pulled it in.

Examples
--------
>>> loader = Loader()
>>> m = loader.load_text("mdl 1.6; import ::math::*; export float f(float x) = math::sin(x);",
...                      "f.mdl")
>>> [o.signature() for o in m.functions("f")]
['float f(float x)']
"""

from __future__ import annotations

import hashlib
import os
from collections.abc import Iterable, Sequence
from dataclasses import dataclass
from pathlib import Path

from mdl import stdlib
from mdl.diagnostics import Diagnostic, MdlError, Source, did_you_mean
from mdl.entities import CheckedModule

__all__ = ["ModuleText", "Loader", "module_file", "qname_of_path", "MDL_PATH_ENV"]

#: folders of MDL modules, separated by os.pathsep, searched after the scene's and
#: ``--mdl-path`` folders and before the workbench's own library
MDL_PATH_ENV = "PWC_MDL_PATH"


@dataclass
class ModuleText:
    """A module's text and where it came from.

    Parameters
    ----------
    qname : str
        ``::a::b``.
    text : str
    filename : str
        Name used in diagnostics.
    path : Path or None
        The file (resources named in the module are found beside it).
    kind : {"file", "std", "native", "generated"}
    native : object
        Provider data a back end uses to bind the module's prototypes (native modules).
    """

    qname: str
    text: str
    filename: str
    path: Path | None = None
    kind: str = "file"
    native: object = None


def module_file(qname: str) -> Path:
    """``::a::b`` -> ``a/b.mdl``."""
    parts = [p for p in qname.split("::") if p] or ["_"]
    return Path(*parts[:-1], parts[-1] + ".mdl")


def qname_of_path(path: Path) -> str:
    """The qualified name a file stands for when given directly (its stem)."""
    return "::" + Path(path).stem


class Loader:
    """Loads and checks modules; one loader is one consistent set of modules.

    Parameters
    ----------
    search_path : sequence of paths
        Folders searched for ``a/b.mdl``, in order.
    providers : sequence
        Objects with ``find(qname) -> ModuleText | None`` (see the module docstring).
    """

    def __init__(self, search_path: Sequence = (), providers: Sequence = ()):
        self.search_path = [Path(p) for p in search_path]
        self.providers = list(providers)
        self.modules: dict[str, CheckedModule] = {}
        self._loading: list[str] = []
        self._failed: dict[str, MdlError] = {}

    # ------------------------------------------------------------------ finding
    def find(self, qname: str, importer: CheckedModule | None = None) -> ModuleText | None:
        """Standard modules, then files (beside the importing module, then the search
        folders), then the providers; a provider's ``fixed()`` names (a renderer's
        ``::df``) cannot be shadowed by files."""
        name = qname.removeprefix("::")
        if "::" not in name and name in stdlib.STANDARD_MODULES:
            return ModuleText(qname, stdlib.source(name), f"<mdl standard module ::{name}>",
                              None, "std")
        for p in self.providers:
            if qname in getattr(p, "fixed", lambda: ())():
                return p.find(qname)
        rel = module_file(qname)
        folders = []
        if importer is not None and importer.path is not None:
            folders.append(Path(importer.path).parent)
        folders += self.search_path
        for d in folders:
            f = d / rel
            if f.is_file():
                return self.read(f, qname)
        for p in self.providers:
            found = p.find(qname)
            if found is not None:
                return found
        return None

    def read(self, path: Path, qname: str | None = None) -> ModuleText:
        """A module file's text (raises :class:`MdlError` if unreadable)."""
        path = Path(path)
        try:
            data = path.read_bytes()
        except OSError as e:
            src = Source(str(path), "")
            raise MdlError([src.diagnostic("error", f"cannot read {path}: "
                                           f"{e.strerror or e}", 0, 0,
                                           "check the file name and permissions")]) from None
        try:
            text = data.decode("utf-8-sig")
        except UnicodeDecodeError as e:
            line = data.count(b"\n", 0, e.start) + 1
            src = Source(str(path), data[:e.start].decode("utf-8", "replace"))
            d = src.diagnostic("error", "the file is not UTF-8 text (MDL modules are UTF-8)",
                               len(src.text), None, "save the module as UTF-8")
            raise MdlError([Diagnostic(d.severity, d.message,
                                       d.loc.__class__(str(path), line, 1, 1, ""),
                                       d.fix)]) from None
        return ModuleText(qname or qname_of_path(path), text, str(path), path, "file")

    def missing_hint(self, qname: str) -> str:
        """What the providers say about a module they do not have (a profile's search
        folders...), or ""."""
        hints = [getattr(p, "hint", lambda q: "")(qname) for p in self.providers]
        folders = ", ".join(str(d) for d in self.search_path)
        mdl = f"there is no {module_file(qname)} in {folders}" if folders else ""
        return "; ".join(x for x in [mdl, *hints] if x)

    def known_names(self) -> list[str]:
        """Module names this loader could load (for suggestions)."""
        names = {f"::{n}" for n in stdlib.STANDARD_MODULES if n != "builtins"}
        for p in self.providers:
            names.update(getattr(p, "names", lambda: ())())
        for d in self.search_path:
            if d.is_dir():
                names.update("::" + "::".join(f.relative_to(d).with_suffix("").parts)
                             for f in d.rglob("*.mdl"))
        return sorted(names)

    # ------------------------------------------------------------------ loading
    def load(self, qname: str, importer: CheckedModule | None = None) -> CheckedModule:
        """The checked module ``qname`` (raises :class:`MdlError` when it cannot be found
        or has errors)."""
        if not qname.startswith("::"):
            qname = "::" + qname
        if qname in self.modules:
            return self.modules[qname]
        if qname in self._failed:
            raise self._failed[qname]
        if qname in self._loading:
            chain = " -> ".join(self._loading[self._loading.index(qname):] + [qname])
            raise _CycleError(chain)
        text = self.find(qname, importer)
        if text is None:
            raise _NotFound(qname)
        return self.check(text)

    def load_text(self, text: str, filename: str = "<string>", qname: str | None = None,
                  path=None) -> CheckedModule:
        """Check module text (not registered under a name unless ``qname`` is given)."""
        mt = ModuleText(qname or qname_of_path(Path(filename)), text, filename,
                        None if path is None else Path(path), "file")
        return self.check(mt, register=qname is not None)

    def load_file(self, path) -> CheckedModule:
        """Check the module in ``path`` (registered under its stem, ``::stem``)."""
        path = Path(path).resolve()
        mt = self.read(path)
        if mt.qname in self.modules and self.modules[mt.qname].path == path:
            return self.modules[mt.qname]
        return self.check(mt)

    def reserved(self, qname: str) -> bool:
        """Whether ``qname`` is a standard module's or a provider's fixed name (a file
        cannot be that module)."""
        name = qname.removeprefix("::")
        return ("::" not in name and name in stdlib.STANDARD_MODULES) or any(
            qname in getattr(p, "fixed", lambda: ())() for p in self.providers)

    def check(self, mt: ModuleText, register: bool = True) -> CheckedModule:
        from mdl.checker import check_module

        if mt.kind == "file" and mt.path is not None and self.reserved(mt.qname):
            src = Source(mt.filename, mt.text)
            stem = mt.qname.removeprefix("::")
            owner = ("a standard module" if stem in stdlib.STANDARD_MODULES
                     else "the renderer's")
            raise MdlError([src.diagnostic(
                "error", f"this file would be the module {mt.qname}, which is "
                f"{owner} and cannot be replaced", 0, min(len(mt.text), 1) or None,
                f"rename the file (my_{stem}.mdl) and import it by that name")])
        self._loading.append(mt.qname)
        try:
            module = check_module(self, mt, cacheable=register)
        except MdlError as e:
            if register:
                self._failed[mt.qname] = e
            raise
        finally:
            self._loading.pop()
        if register:
            self.modules[mt.qname] = module
        return module

    def content_key(self, mt: ModuleText, imports: Iterable[CheckedModule]) -> str:
        """A hash of a module's text, name and file, and the keys of everything it
        imports: equal keys mean equal checked modules."""
        h = hashlib.sha256(mt.text.encode())
        h.update(mt.qname.encode())
        h.update(str(mt.path).encode())
        h.update(mt.kind.encode())
        for m in sorted(imports, key=lambda m: m.qname):
            h.update(m.key.encode())
        return h.hexdigest()[:20]


class _NotFound(Exception):
    def __init__(self, qname: str):
        super().__init__(qname)
        self.qname = qname


class _CycleError(Exception):
    def __init__(self, chain: str):
        super().__init__(chain)
        self.chain = chain


def search_path_from_env() -> list[Path]:
    """The folders of :data:`MDL_PATH_ENV`."""
    raw = os.environ.get(MDL_PATH_ENV, "")
    return [Path(p) for p in raw.split(os.pathsep) if p]


def not_found_fix(loader: Loader, qname: str) -> str:
    """How to fix an import that names no known module."""
    hint = did_you_mean(qname, loader.known_names())
    where = ", ".join(str(d) for d in loader.search_path) or "(no search folders)"
    return ((hint + " or " if hint else "")
            + f"put {module_file(qname)} beside the importing module or in a search folder "
              f"({where}); add folders with --mdl-path DIR or ${MDL_PATH_ENV}")
