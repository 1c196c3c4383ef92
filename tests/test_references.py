"""The prose names what exists: every reference to the project's own Python objects and
files, in the docstrings (and ``#:`` comments) of its packages and in its Markdown pages,
resolves, so a rename cannot leave ``render.df._scaled`` or ``render/df/_gone.py`` behind.

What counts as a reference:

* a Sphinx role, ``:func:`render.path.trace``` (also ``:mod:``, ``:class:``, ``:data:``,
  ``:meth:``, ``:attr:``, ``:exc:``, ``:obj:``; ``~`` and ``title <target>`` forms).  In
  a docstring a bare or partial target (``:func:`prepare```, ``:meth:`Scene.build```)
  resolves as the code around it would: the enclosing classes, the module's globals and
  the names it imports anywhere (in functions, under ``TYPE_CHECKING``), the names the
  enclosing functions define, modules of its package, builtins;
* code in backticks (single or double) that is a dotted name starting with a project
  package: ``render.df.tint``, ``render.df.tint(...)``, ``render.commands.render:register``;
* code in backticks that is a path under a top-level folder of the repository:
  ``render/df/_layer.py``, ``tests/render/``.  Globs and placeholders (``NAME``,
  ``fig_CC_NN``, ``<df>``, ``...``) must match a file; an installed package's folder
  (``render/gallery/scenes``) is its source folder (pyproject's package-dir);
* in Markdown, the target of a relative link;
* code in backticks that is a path of one machine, outside the repository: a temporary
  file (``/tmp/notes.md``), a home folder, the folder the checkout sits in.  Such a file
  is no part of the project (system paths such as ``/proc/self/clear_refs`` are fine).

Not references: doctest and ``::`` literal blocks in docstrings, fenced code blocks in
Markdown, URLs, shell commands (they start with a command, not a package), the
entry-point groups pyproject declares (``pwc.commands``) and file names (``scene.toml``).

A dotted name imports its longest importable module prefix and takes the rest as
attributes.  An attribute of a class may also be an instance attribute the class
declares: an annotation (dataclass and NamedTuple fields), a ``__slots__`` entry, or an
assignment to ``self.NAME`` in the source of the class or of a base class.
"""

from __future__ import annotations

import ast
import builtins
import dataclasses
import importlib
import importlib.util
import inspect
import re
import tomllib
from functools import cache
from pathlib import Path

import pytest
from repo import ROOT

_PYPROJECT = tomllib.loads((ROOT / "pyproject.toml").read_text(encoding="utf-8"))
_SETUPTOOLS = _PYPROJECT["tool"]["setuptools"]

#: the project's top-level packages (pyproject's package list)
PACKAGES = frozenset(name.split(".")[0] for name in _SETUPTOOLS["packages"])
#: packages installed from another folder: render.gallery.scenes is gallery/scenes
PACKAGE_DIRS = dict(_SETUPTOOLS.get("package-dir", {}))
#: entry-point groups (``pwc.commands``): dotted names, but not Python objects
ENTRY_POINT_GROUPS = frozenset(_PYPROJECT["project"].get("entry-points", {}))
#: the folders a path in backticks may start with
TOP_FOLDERS = frozenset(p.name for p in ROOT.iterdir() if p.is_dir()
                        and not p.name.startswith(".") and not p.name.endswith(".egg-info"))
#: a dotted name ending in one of these is a file's name, not an object
FILE_SUFFIXES = frozenset("py toml md png exr json mdl pwc html txt csv stl obj 3mf mbsdf svg "
                          "ies npz npy yaml yml cfg".split())

SOURCES = sorted(p.relative_to(ROOT).as_posix() for package in PACKAGES
                 for p in (ROOT / package).rglob("*.py") if "__pycache__" not in p.parts)
PAGES = sorted([p.relative_to(ROOT).as_posix() for p in (ROOT / "docs").rglob("*.md")]
               + [page for page in ("README.md", "gallery/README.md", "profiles/README.md")
                  if (ROOT / page).is_file()])

ROLE = re.compile(r":(?:py:)?(mod|func|class|data|meth|attr|exc|obj|const):`([^`]+)`")
# inline code, ``...`` or `...`: across line breaks, never across a blank line
_SPAN = r"(?:[^`\n]|\n(?![ \t]*\n))"
CODE = re.compile(rf"``({_SPAN}+?)``|`({_SPAN}+)`")
DOTTED = re.compile(r"~?([A-Za-z_]\w*(?:\.[A-Za-z_]\w*)+)(?::([A-Za-z_]\w*))?(?:\(.*\))?",
                    re.S)
PATH = re.compile(r"([\w.-]+(?:/[\w.*?<>\[\] -]*)+?)/?(?::\d+(?:-\d+)?)?")
# what a path writes for "any": a glob, <df>, ..., or an upper-case NAME / fig_CC_NN
PLACEHOLDER = re.compile(r"<[^>/]*>|\.\.\.|(?<![A-Za-z])[A-Z][A-Z0-9]*(?![A-Za-z])")
# a temporary file, a home folder, or the folder this checkout sits in
LOCAL = re.compile("(?:/tmp|/var/tmp|/home|/Users|/root|" + re.escape(str(ROOT.parent))
                   + r")/\S*")
LINK = re.compile(r"\]\(([^)\s]+)\)")
FENCE = re.compile(r"^[ \t]*(```|~~~)")

FIX = "rename it to the object's current name, or reword the sentence if the object is gone"
FIX_PATH = "write the file's current path, or reword the sentence if the file is gone"
FIX_LOCAL = ("a file of one machine, not of the project: cite a file in the repository, or "
             "say what it holds")


# -- where the references are ---------------------------------------------------------------

def docstring_text(text: str) -> str:
    """``text`` with its doctest blocks and ``::`` literal blocks blanked, lines kept."""
    lines = text.split("\n")
    i = 0
    while i < len(lines):
        line = lines[i]
        if line.lstrip().startswith(">>>"):  # a doctest: up to the next blank line
            while i < len(lines) and lines[i].strip():
                lines[i] = ""
                i += 1
        elif line.rstrip().endswith("::"):  # a literal block: the lines indented deeper
            indent = len(line) - len(line.lstrip())
            i += 1
            while i < len(lines) and (not lines[i].strip()
                                      or len(lines[i]) - len(lines[i].lstrip()) > indent):
                lines[i] = ""
                i += 1
        else:
            i += 1
    return "\n".join(lines)


def markdown_text(text: str) -> str:
    """``text`` with its fenced code blocks blanked, lines kept."""
    lines = text.split("\n")
    fence = None
    for i, line in enumerate(lines):
        match = FENCE.match(line)
        if fence is None and match:
            fence = match.group(1)
        elif fence is not None and line.strip().startswith(fence):
            fence = None
        elif fence is None:
            continue
        lines[i] = ""
    return "\n".join(lines)


def references(text: str):
    """``(offset, kind, as written, target)`` of each reference in ``text``; ``kind`` is a
    role (``func``...), ``code`` (a dotted name in backticks), ``path`` or ``local``."""
    for match in ROLE.finditer(text):
        target = match.group(2)
        if target.rstrip().endswith(">") and "<" in target:
            target = target[target.rindex("<") + 1:-1]
        target = re.sub(r"\s+", "", target).lstrip("~!.").removesuffix("()")
        yield match.start(), match.group(1), match.group(0), target
    text = ROLE.sub(lambda m: " " * len(m.group(0)), text)
    for match in CODE.finditer(text):
        code = (match.group(1) or match.group(2)).strip()
        if "://" in code:
            continue
        if (dotted := DOTTED.fullmatch(code)) and dotted.group(1).split(".")[0] in PACKAGES:
            name = dotted.group(1) + (f".{dotted.group(2)}" if dotted.group(2) else "")
            if name not in ENTRY_POINT_GROUPS and name.rsplit(".")[-1] not in FILE_SUFFIXES:
                yield match.start(), "code", match.group(0), name
        elif (path := PATH.fullmatch(code)) and path.group(1).split("/")[0] in TOP_FOLDERS:
            yield match.start(), "path", match.group(0), path.group(1)
        elif LOCAL.fullmatch(code):
            yield match.start(), "local", match.group(0), code


def _line(text: str, offset: int) -> int:
    return text.count("\n", 0, offset) + 1


def _docstrings(code: str):
    """``(first line, text, classes, local names)`` of each docstring of the module
    ``code`` (its own, its classes' and its functions') and of each block of its ``#:``
    comments: the classes around it (outermost first, as reached from the module) and
    the names the functions around it define."""
    def visit(node, classes, local_names):
        if isinstance(node, ast.Module | ast.ClassDef | ast.FunctionDef | ast.AsyncFunctionDef) \
                and ast.get_docstring(node, clean=False) is not None:
            yield node.body[0].lineno, ast.get_docstring(node, clean=False), classes, local_names
        if isinstance(node, ast.ClassDef | ast.Module) and not local_names:
            scopes.append((node.lineno if classes else 0, getattr(node, "end_lineno", 1e9),
                           classes))
        for child in ast.iter_child_nodes(node):
            if isinstance(child, ast.ClassDef):
                # a class made in a function cannot be reached from the module
                yield from visit(child, classes if local_names else [*classes, child.name],
                                 local_names)
            elif isinstance(child, ast.FunctionDef | ast.AsyncFunctionDef):
                defined = {n.name for n in ast.walk(child) if isinstance(
                    n, ast.FunctionDef | ast.AsyncFunctionDef | ast.ClassDef)}
                yield from visit(child, classes, local_names | defined)
            elif not isinstance(child, ast.expr):
                yield from visit(child, classes, local_names)

    scopes: list = []  # (first line, last line, classes) of the module and its classes
    yield from visit(ast.parse(code), [], frozenset())
    yield from _doc_comments(code.split("\n"), scopes)


def _doc_comments(lines: list[str], scopes: list):
    """``(first line, text, classes, no local names)`` of each block of ``#:`` comments
    in ``lines``, with the classes of the innermost of ``scopes`` that holds it."""
    start = None
    for number, line in enumerate([*lines, ""], 1):
        if line.lstrip().startswith("#:"):
            start = start or number
            continue
        if start:
            text = "\n".join(row.lstrip()[2:] for row in lines[start - 1:number - 1])
            classes = max((s for s in scopes if s[0] <= start <= s[1]), key=lambda s: s[0])[2]
            yield start, text, classes, frozenset()
            start = None


# -- what they name -------------------------------------------------------------------------

_BROKEN: dict[str, str] = {}  # modules that exist but fail to import, with the error


@cache
def _find_module(name: str):
    try:
        if importlib.util.find_spec(name) is None:
            return None
    except (ModuleNotFoundError, ValueError):
        return None
    try:
        return importlib.import_module(name)
    except Exception as e:  # noqa: BLE001 - reported as what it is, below
        _BROKEN[name] = f"{type(e).__name__}: {e}"
        return None


def _module(name: str):
    """The module ``name``, or None where there is none (``__main__`` modules, which run
    a command, are never imported); a module that fails to import fails the test (its
    references cannot be checked) without a long traceback."""
    if name.rpartition(".")[2] == "__main__":
        return None
    module = _find_module(name)
    if name in _BROKEN:
        pytest.fail(f"importing {name} fails ({_BROKEN[name]}): fix that first, then its "
                    "references can be checked", pytrace=False)
    return module


@pytest.fixture(scope="module", autouse=True)
def project_modules():
    """Every module of the project imported once, in one order (the files' sorted paths: a
    package before its modules), before anything is resolved, so that what resolves does
    not depend on which tests ran first.  (``import render.program`` on its own is a
    circular import; after ``render.df`` it is not.)"""
    for source in SOURCES:
        if not source.endswith("__main__.py"):
            _find_module(_module_name(ROOT / source))


def _module_name(path: Path) -> str:
    parts = path.relative_to(ROOT).with_suffix("").parts
    return ".".join(parts[:-1] if parts[-1] == "__init__" else parts)


@cache
def _instance_attributes(cls: type) -> frozenset[str]:
    """What ``cls``'s instances have beyond its class attributes: annotated names (dataclass
    and NamedTuple fields), ``__slots__``, and ``self.NAME = ...`` in the source of the
    class or of a base class."""
    names: set[str] = set()
    for klass in cls.__mro__[:-1]:
        names |= set(vars(klass).get("__annotations__", {}))
        slots = vars(klass).get("__slots__", ())
        names |= {slots} if isinstance(slots, str) else set(slots)
        if dataclasses.is_dataclass(klass):
            names |= {field.name for field in dataclasses.fields(klass)}
        try:
            tree = ast.parse(inspect.cleandoc("\n" + inspect.getsource(klass)))
        except (OSError, TypeError, SyntaxError):
            continue
        names |= {node.attr for node in ast.walk(tree)
                  if isinstance(node, ast.Attribute) and isinstance(node.ctx, ast.Store)
                  and isinstance(node.value, ast.Name) and node.value.id == "self"}
    return frozenset(names)


def _follow(obj, parts: list[str], where: str) -> str | None:
    """Why ``obj`` (called ``where``) has no attribute chain ``parts``, or None."""
    for i, part in enumerate(parts):
        if inspect.ismodule(obj) and hasattr(obj, "__path__"):
            # a submodule before the package's attribute of the same name
            if (sub := _module(f"{obj.__name__}.{part}")) is not None:
                obj, where = sub, f"{obj.__name__}.{part}"
                continue
        try:
            obj = getattr(obj, part)
        except AttributeError:
            if inspect.isclass(obj) and part in _instance_attributes(obj):
                if i == len(parts) - 1:
                    return None
                return (f"`{where}.{part}` is an instance attribute; the test cannot follow "
                        f"it on to `{'.'.join(parts[i + 1:])}`")
            kind = ("module" if inspect.ismodule(obj) else "class" if inspect.isclass(obj)
                    else type(obj).__name__)
            return f"{kind} `{where}` has no attribute `{part}`"
        where = f"{where}.{part}"
    return None


def resolve(name: str) -> str | None:
    """Why the absolute dotted ``name`` names nothing, or None where it names something."""
    for package, folder in PACKAGE_DIRS.items():
        if name == package or name.startswith(package + "."):
            path = ROOT / folder / "/".join(name.split(".")[package.count(".") + 1:])
            if path.is_dir() or path.with_suffix(".py").is_file():
                return None
            return f"`{name}` would be {path.relative_to(ROOT)}, which is not there"
    parts = name.split(".")
    if (top := _module(parts[0])) is None:
        return f"there is no module `{parts[0]}`"
    return _follow(top, parts[1:], parts[0])


@cache
def _imports(path: Path) -> dict[str, str]:
    """The names ``path``'s module imports anywhere (in functions, under ``TYPE_CHECKING``),
    each with the absolute dotted name it stands for."""
    package = _module_name(path) if path.name == "__init__.py" else _module_name(
        path).rpartition(".")[0]
    names: dict[str, str] = {}
    for node in ast.walk(ast.parse(path.read_text(encoding="utf-8"))):
        if isinstance(node, ast.Import):
            for alias in node.names:
                top = alias.name.split(".")[0]
                names[alias.asname or top] = alias.name if alias.asname else top
        elif isinstance(node, ast.ImportFrom):
            base = node.module or ""
            if node.level:
                anchor = package.split(".")[:len(package.split(".")) - node.level + 1]
                base = ".".join([*anchor, base] if base else anchor)
            for alias in node.names:
                names[alias.asname or alias.name] = f"{base}.{alias.name}"
    return names


def resolve_relative(target: str, kind: str, path: Path, classes: list[str],
                     local_names: frozenset[str]) -> str | None:
    """Why the role target ``target``, written in ``path``'s module inside the classes
    ``classes`` and functions defining ``local_names``, names nothing, or None."""
    parts = target.split(".")
    if (module := _module(_module_name(path))) is None:  # a __main__: its imports only
        imported = _imports(path).get(parts[0])
        if imported and resolve(".".join([imported, *parts[1:]])) is None:
            return None
        return f"`{target}` is not among the names `{_module_name(path)}` imports"
    scopes = [module]
    for cls in classes:
        if not inspect.isclass(scope := getattr(scopes[-1], cls, None)):
            break  # made conditionally, or replaced by a decorator
        scopes.append(scope)
    for scope in reversed(scopes[1:]):
        if _follow(scope, parts, scope.__qualname__) is None:
            return None
    if len(parts) == 1 and target in local_names:
        return None
    if parts[0] in vars(module) and _follow(vars(module)[parts[0]], parts[1:], parts[0]) is None:
        return None
    imported = _imports(path).get(parts[0])
    if imported and resolve(".".join([imported, *parts[1:]])) is None:
        return None
    package = module.__name__
    while package:  # a module of the package (:mod:`_layer` in render.df)
        if resolve(f"{package}.{target}") is None:
            return None
        package = package.rpartition(".")[0]
    if len(parts) == 1 and hasattr(builtins, target):
        return None
    if (kind == "mod" or len(parts) > 1) and parts[0] not in PACKAGES \
            and _module(parts[0]) is not None:
        return None  # another library's name (numpy.linalg.norm): not the project's to check
    where = f"class `{scopes[-1].__qualname__}`, " if len(scopes) > 1 else ""
    return (f"neither {where}module `{module.__name__}` (its names and imports) nor its "
            f"package has `{target}`")


def path_missing(path: str, beside: Path) -> bool:
    """Whether no file matches ``path`` (from the repository's root, or ``beside``)."""
    pattern = PLACEHOLDER.sub("*", path)
    for package, folder in PACKAGE_DIRS.items():
        installed = package.replace(".", "/")
        if pattern == installed or pattern.startswith(installed + "/"):
            pattern = folder + pattern[len(installed):]
        elif installed.startswith(pattern.rstrip("/*") + "/"):
            return False  # a folder holding installed packages (render/gallery/...)
    for base in (ROOT, beside):
        if any(c in pattern for c in "*?["):
            if next(base.glob(pattern), None) is not None:
                return False
        elif (base / pattern).exists():
            return False
    return True


# -- the tests ------------------------------------------------------------------------------

def _dead(text: str, where, folder: Path, resolve_name) -> list[str]:
    """The dead references of ``text``: ``where(offset)`` names the place,
    ``resolve_name(target, kind)`` says why a name does not resolve (None: it does)."""
    dead = []
    for offset, kind, written, target in references(text):
        at = f"{where(offset)}: {written}"
        if kind == "local":
            dead.append(f"{at}: {FIX_LOCAL}")
        elif kind == "path":
            if path_missing(target, folder):
                dead.append(f"{at}: there is no {target}; {FIX_PATH}")
        elif why := resolve_name(target, kind):
            dead.append(f"{at}: {why}; {FIX}")
    return dead


@pytest.mark.parametrize("source", SOURCES)
def test_docstring_references_resolve(source):
    path = ROOT / source
    dead = []
    for first_line, doc, classes, local_names in _docstrings(path.read_text(encoding="utf-8")):
        text = docstring_text(doc)
        dead += _dead(text, lambda o, t=text, f=first_line: f"{source}:{f + _line(t, o) - 1}",
                      path.parent,
                      lambda target, kind, c=classes, n=local_names: (
                          resolve(target) if target.split(".")[0] in PACKAGES else
                          resolve_relative(target, kind, path, c, n)))
    if dead:
        pytest.fail("dead references in docstrings:\n" + "\n".join(dead), pytrace=False)


@pytest.mark.parametrize("page", PAGES)
def test_page_references_resolve(page):
    path = ROOT / page
    text = markdown_text(path.read_text(encoding="utf-8"))
    dead = _dead(text, lambda o: f"{page}:{_line(text, o)}", path.parent,
                 lambda target, kind: resolve(target))
    prose = CODE.sub(lambda m: re.sub(r"[^\n]", " ", m.group(0)), text)
    for match in LINK.finditer(prose):
        target = match.group(1).split("#")[0]
        if target and not re.match(r"[a-z][a-z+.-]*:", target) \
                and not (path.parent / target).exists():  # not an anchor, nor a URL
            dead.append(f"{page}:{_line(text, match.start())}: link ({target}): there is no "
                        f"such file beside {page}; {FIX_PATH}")
    if dead:
        pytest.fail("dead references in Markdown:\n" + "\n".join(dead), pytrace=False)
