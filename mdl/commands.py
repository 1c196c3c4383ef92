"""``pwc mdl check`` and ``pwc mdl info``: MDL modules for their authors.

Registered through the ``pwc.commands`` entry point (``mdl = "mdl.commands:register"``).
A renderer that implements modules (``::df``, its function library) plugs into the
``pwc.mdl`` entry point group: an object with ``providers(args)`` (the front end's module
providers), and optionally ``compile(module)`` (generate the code of the module's
functions, raising :class:`~mdl.diagnostics.MdlError` for what it cannot compile) and
``python(module)`` (the generated code, for ``info --python``).

Exit status: 0 no errors; 1 errors (or warnings, with ``--strict``); 2 bad command line;
3 a file could not be read.
"""

from __future__ import annotations

import argparse
import sys
from importlib.metadata import entry_points
from pathlib import Path

from mdl.diagnostics import MdlError
from mdl.entities import ConstEntity, Overload, TypeEntity
from mdl.lanes import to_python
from mdl.loader import MDL_PATH_ENV, Loader, module_file, search_path_from_env
from mdl.types import EnumType, StructType

__all__ = ["register", "backends", "EXIT_OK", "EXIT_ERRORS", "EXIT_USAGE", "EXIT_IO"]

EXIT_OK, EXIT_ERRORS, EXIT_USAGE, EXIT_IO, EXIT_INTERNAL = 0, 1, 2, 3, 70

_EPILOG = """\
examples:
  pwc mdl check mouldings.mdl
  pwc mdl check lib/*.mdl --mdl-path lib --strict
  pwc mdl info mouldings.mdl
  pwc mdl info ::pw_curve --python"""


def register(subparsers) -> argparse.ArgumentParser:
    """Add ``mdl`` (``check``, ``info``) to the ``pwc`` command's subparsers."""
    p = subparsers.add_parser(
        "mdl", help="check MDL modules and show what they export",
        description="Check MDL modules (.mdl) as the workbench reads them, and describe "
                    "their exports.  Modules they import are found beside them, then in "
                    f"--mdl-path folders, then ${MDL_PATH_ENV}, then the workbench's own "
                    "modules.", epilog=_EPILOG,
        formatter_class=argparse.RawDescriptionHelpFormatter)
    sub = p.add_subparsers(dest="mdl_command", metavar="{check,info}")
    sub.required = True
    c = sub.add_parser("check", help="report errors and warnings, file:line:col",
                       description="Parse and check each module (and what it imports), "
                                   "then generate the code of its functions; print every "
                                   "error and warning with its location and a fix.",
                       epilog=_EPILOG, formatter_class=argparse.RawDescriptionHelpFormatter)
    c.add_argument("files", nargs="+", metavar="FILE.mdl", help="modules to check")
    c.add_argument("--strict", action="store_true", help="warnings fail the check too")
    _common(c)
    c.set_defaults(func=cmd_check)
    i = sub.add_parser("info", help="exports: materials, functions, types, constants",
                       description="Describe a module: its imports and every export with "
                                   "its signature, defaults and annotations.",
                       epilog=_EPILOG, formatter_class=argparse.RawDescriptionHelpFormatter)
    i.add_argument("module", metavar="FILE.mdl|::NAME", help="a file or a module name")
    i.add_argument("--python", action="store_true",
                   help="also print the Python the workbench generates for its functions")
    _common(i)
    i.set_defaults(func=cmd_info)
    return p


def _common(p) -> None:
    p.add_argument("--mdl-path", action="append", default=[], metavar="DIR",
                   help=f"also look for imported modules in DIR (before ${MDL_PATH_ENV}); "
                        "repeatable")


def backends() -> list:
    """The renderers plugged into the ``pwc.mdl`` entry point group."""
    out = []
    for ep in entry_points(group="pwc.mdl"):
        try:
            out.append(ep.load()())
        except Exception as e:  # noqa: BLE001 - a renderer that is not installed
            print(f"pwc mdl: note: the MDL back end {ep.name!r} is unavailable "
                  f"({type(e).__name__}: {e}); renderer modules such as ::df will not be found",
                  file=sys.stderr)
    return out


def _loader(args, first: Path | None, found: list) -> Loader:
    folders = ([first.parent] if first is not None else []) + [Path(d) for d in args.mdl_path]
    folders += search_path_from_env()
    providers = [p for b in found for p in b.providers()]
    return Loader(folders, providers)


def cmd_check(args) -> int:
    found = backends()
    failed = False
    for f in args.files:
        path = Path(f)
        if not path.is_file():
            print(f"pwc mdl: error: {f}: no such file", file=sys.stderr)
            return EXIT_IO
        loader = _loader(args, path, found)
        try:
            module = loader.load_file(path)
            for b in found:
                if hasattr(b, "compile"):
                    b.compile(module)
        except MdlError as e:
            for d in e.diagnostics:
                print(d.format(), file=sys.stderr)
            failed = True
            continue
        except Exception as e:  # noqa: BLE001 - a bug: say so, in one line
            print(internal_error(f, e), file=sys.stderr)
            return EXIT_INTERNAL
        for d in module.diagnostics:
            print(d.format(), file=sys.stderr)
        if args.strict and module.diagnostics:
            failed = True
        n = len(module.diagnostics)
        print(f"{f}: ok ({len(module.materials())} materials, "
              f"{sum(1 for o in module.overloads if not o.is_material and o.kind == 'mdl')} "
              f"functions{f', {n} warning' + ('s' if n != 1 else '') if n else ''})",
              file=sys.stderr)
    return EXIT_ERRORS if failed else EXIT_OK


def cmd_info(args) -> int:
    found = backends()
    name = args.module
    try:
        if name.endswith(".mdl") or Path(name).is_file():
            path = Path(name)
            if not path.is_file():
                print(f"pwc mdl: error: {name}: no such file", file=sys.stderr)
                return EXIT_IO
            loader = _loader(args, path, found)
            module = loader.load_file(path)
        else:
            loader = _loader(args, None, found)
            qname = name if name.startswith("::") else "::" + name
            if loader.find(qname) is None:
                print(f"pwc mdl: error: no module {qname} (no {module_file(qname)} on the "
                      "search path)", file=sys.stderr)
                return EXIT_IO
            module = loader.load(qname)
    except MdlError as e:
        for d in e.diagnostics:
            print(d.format(), file=sys.stderr)
        return EXIT_ERRORS
    except Exception as e:  # noqa: BLE001 - a bug: say so, in one line
        print(internal_error(name, e), file=sys.stderr)
        return EXIT_INTERNAL
    print(describe(module))
    if args.python:
        for b in found:
            if hasattr(b, "python"):
                print(b.python(module))
    return EXIT_OK


def internal_error(what: str, e: Exception) -> str:
    """One line for an unexpected exception (a bug in the front end or a back end): where
    it was raised, and what to do."""
    import traceback

    frames = traceback.extract_tb(e.__traceback__)
    where = f" at {Path(frames[-1].filename).name}:{frames[-1].lineno}" if frames else ""
    return (f"pwc mdl: internal error while reading {what}: {type(e).__name__}: {e}{where} "
            "(a bug of the workbench, not of the module: please report it with the module)")


def _annos(annos, indent: str) -> list[str]:
    return [f"{indent}[[ {a} ]]" for a in annos]


def describe(module) -> str:
    """A module's exports as text (what ``pwc mdl info`` prints)."""
    v = module.version
    out = [f"module {module.qname}" + (f"  (mdl {v[0]}.{v[1]})" if v else ""),
           f"  from {module.source.name}"]
    out += _annos(module.annotations, "  ")
    imports = sorted({m.qname for m in module.imports.values()})
    if imports:
        out.append("  imports: " + ", ".join(imports))
    exports = module.exports()
    mats, funcs, types, consts, values, again = [], [], [], [], [], []
    for n in sorted(exports):
        for e in exports[n]:
            if e.module is not module:
                again.append((n, e))
                continue
            if isinstance(e, Overload):
                if e.kind == "struct":
                    continue
                (mats if e.is_material else funcs).append(e)
            elif isinstance(e, TypeEntity):
                types.append(e)
            elif isinstance(e, ConstEntity):
                consts.append(e)
            else:
                values.append(e)
    for title, items in (("materials", mats), ("functions", funcs)):
        if not items:
            continue
        out.append(f"  {title}:")
        for o in items:
            out.append(f"    {o.signature()}")
            out += _annos(o.annotations, "        ")
            for p in o.params:
                if p.annotations:
                    out.append(f"        {p.name}: " + ", ".join(str(a) for a in p.annotations))
    if again:
        out.append("  re-exported:")
        for n, e in again:
            what = e.signature() if isinstance(e, Overload) else (
                f"{e.type} {n}" if isinstance(e, ConstEntity) else n)
            out.append(f"    {what}  (from {e.module.qname})")
    if types:
        out.append("  types:")
        for e in types:
            t = e.type
            if isinstance(t, StructType):
                fields = "; ".join(f"{f.type} {f.name}" for f in t.fields)
                out.append(f"    struct {e.name} {{ {fields} }}")
            elif isinstance(t, EnumType):
                vals = ", ".join(f"{n} = {k}" for n, k in t.values)
                out.append(f"    enum {e.name} {{ {vals} }}")
            else:
                out.append(f"    typedef {t} {e.name}")
    if consts:
        out.append("  constants:")
        for e in consts:
            value = to_python(e.value, e.type) if e.value is not None else "?"
            text = repr(value)
            if len(text) > 70:
                text = text[:67] + "..."
            out.append(f"    {e.type} {e.name} = {text}")
    return "\n".join(out)
