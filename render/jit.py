"""The render package's numba decorator, and its kernel cache keyed to every source file.

numba's own cache (``cache=True``) is keyed on the file that defines a kernel, so a
kernel that calls a kernel of another file keeps running the old machine code after
that other file changes.  Every compiled kernel of :mod:`render` is declared with
:func:`njit` from this module instead, and is cached in a per-user folder whose name
is a hash of *all* the package's Python sources: any edit to any of them starts a fresh
cache (old ones stay until the user deletes them).

Distribution functions may also come from modules outside the package, in the folders
that ``$PWC_DF_PATH`` lists (:mod:`render.df._registry`); their sources are part of the
key and their kernels are cached like the package's.  Code that the package generates
(:func:`generated`: the interpreter's df dispatch) is written to the cache folder and
cached there too.

The folder is ``$PWC_CACHE_DIR`` if set, else ``$XDG_CACHE_HOME/pwc-workbench`` (by
default ``~/.cache/pwc-workbench``), never the source tree, so a non-editable install
caches too.  Tests point ``PWC_CACHE_DIR`` at a fresh folder to prove they compile.

Examples
--------
>>> from render.jit import njit
>>> @njit
... def twice(x):
...     return 2.0 * x
>>> twice(1.5)
3.0
"""

from __future__ import annotations

import functools
import hashlib
import importlib.util
import os
import sys
import tempfile
from collections import Counter
from pathlib import Path
from types import FunctionType, ModuleType

import numba
from numba.core import types
from numba.core.caching import CacheImpl, _CacheLocator
from numba.core.registry import CPUDispatcher

__all__ = ["njit", "is_kernel", "instantiate", "generated", "cache_dir", "df_path",
           "SOURCE_KEY"]

_PACKAGE = Path(__file__).resolve().parent


def df_path() -> list[Path]:
    """The ``.py`` files of the df modules in the folders ``$PWC_DF_PATH`` lists
    (separated by ``os.pathsep``), sorted by folder, then name."""
    files = []
    for folder in filter(None, os.environ.get("PWC_DF_PATH", "").split(os.pathsep)):
        files += sorted(p.resolve() for p in Path(folder).glob("*.py"))
    return files


def _source_key() -> str:
    """sha256 (16 hex digits) of every ``.py`` file of the package and of
    :func:`df_path`, path and content."""
    h = hashlib.sha256()
    named = [(p, p.relative_to(_PACKAGE)) for p in sorted(_PACKAGE.rglob("*.py"))]
    for path, name in named + [(p, Path("ext") / p.name) for p in df_path()]:
        h.update(str(name).encode())
        h.update(b"\0")
        h.update(path.read_bytes())
        h.update(b"\0")
    return h.hexdigest()[:16]


#: files outside the package whose kernels are cached as its own: resolved path ->
#: a name relative to the cache (the df path's modules, generated modules)
_OUTSIDE: dict[str, Path] = {str(p): Path("ext") / p.name for p in df_path()}
#: the key of this tree's sources (part of the cache folder's name)
SOURCE_KEY = _source_key()


def cache_dir() -> Path:
    """The folder that holds this tree's compiled kernels."""
    root = os.environ.get("PWC_CACHE_DIR")
    if root:
        base = Path(root)
    else:
        xdg = os.environ.get("XDG_CACHE_HOME")
        base = (Path(xdg) if xdg else Path.home() / ".cache") / "pwc-workbench"
    return base / f"numba-{numba.__version__}-{SOURCE_KEY}"


class _RenderCacheLocator(_CacheLocator):
    """numba cache locator for kernels defined in this package (others: numba's own)."""

    def __init__(self, py_func, py_file):
        self._lineno = py_func.__code__.co_firstlineno
        self._module = py_func.__module__
        self._instance = getattr(py_func, "_instance", 0)
        self._cache_path = str(cache_dir() / _package_path(py_file).with_suffix(""))

    def get_cache_path(self):
        return self._cache_path

    def get_source_stamp(self):
        return SOURCE_KEY

    def get_disambiguator(self):
        # the module and the instance's number in it tell apart the instances of one
        # template (:func:`instantiate`), which share its file and line
        return f"{self._lineno}-{self._module}-{self._instance}"

    @classmethod
    def from_function(cls, py_func, py_file):
        if not _in_package(py_func):
            return None
        self = cls(py_func, py_file)
        return self if _writable(self._cache_path) else None


if _RenderCacheLocator not in CacheImpl._locator_classes:
    CacheImpl._locator_classes.insert(0, _RenderCacheLocator)


class _Dispatcher(CPUDispatcher):
    """numba's dispatcher, but a call from another kernel is compiled for its arguments'
    types, never for their values: numba types a literal argument (``f(x, 0)``,
    ``f(x, False)``) as a type of its own and compiles ``f`` again for each value, which
    cost the cold compile dozens of specialisations (measured: 355 where 301 kernels
    suffice)."""

    def get_call_template(self, args, kws):
        return super().get_call_template([types.unliteral(a) for a in args],
                                         {k: types.unliteral(v) for k, v in kws.items()})


def is_kernel(obj) -> bool:
    """Whether ``obj`` is a kernel of the workbench's (made by :func:`njit`)."""
    return isinstance(obj, _Dispatcher)


def njit(function=None, allocates: bool = False, **options):
    """``numba.njit`` with the package's defaults: ``nogil=True`` (both cores shade at
    once), ``cache=True`` (in :func:`cache_dir`) for functions defined in the package,
    numpy's error model (IEEE division: the kernels guard their own divisions, and
    Python's zero-division checks cost a branch per division), no reference counting
    unless ``allocates``, and one compilation per argument types (:class:`_Dispatcher`).
    Use bare or with options.

    A kernel that only reads and writes arrays it is given needs no reference counts;
    numba's would cost an atomic increment and decrement per array argument per call
    (measured: 22 % of a render's time).  A kernel that creates an array (``np.empty``
    ...) or returns one says ``allocates=True``."""
    def decorate(f):
        opts = {"nopython": True, "boundscheck": None, "nogil": True, "_nrt": allocates,
                "error_model": "numpy", **options}
        disp = _Dispatcher(py_func=f, locals={}, targetoptions=opts)
        if _in_package(f):
            disp.enable_caching()
        return disp

    return decorate if function is None else decorate(function)


def instantiate(template, module: str, allocates: bool = False, **names):
    """The plain function ``template`` compiled as a kernel of the module named ``module``,
    with ``names`` of its globals bound anew: one body of code that serves several dfs,
    each instance compiled for its own.

    numba caches neither a closure nor a kernel that takes another as an argument (both
    keys hold an object's per-process id, so every run compiles them again); an instance
    is a copy of the template's code over its globals and ``names``, keyed in the cache
    by ``module`` and by its number among the template's instances in that module
    (:class:`_RenderCacheLocator`), which the module's code fixes."""
    scope = {**template.__globals__, **names, "__name__": module}
    f = FunctionType(template.__code__, scope, template.__name__, template.__defaults__)
    f.__doc__, f.__qualname__ = template.__doc__, template.__qualname__
    f._instance = _INSTANCES[template.__code__, module]
    _INSTANCES[template.__code__, module] += 1
    return njit(f, allocates=allocates)


#: instances made so far of each (template code, module)
_INSTANCES: Counter = Counter()


def generated(name: str, source: str) -> ModuleType:
    """The module ``name`` made of ``source``, Python that the package generated: written
    to the cache folder (a temporary one where that is not writable) and imported from
    there, so that a person can read it and its kernels are cached like the package's
    (the source is a function of the package's, which :data:`SOURCE_KEY` covers)."""
    folder = cache_dir() / "generated"
    if not _writable(str(folder)):
        folder = Path(tempfile.mkdtemp(prefix="pwc-generated-"))
    path = folder / f"{name}.py"
    if not path.exists() or path.read_text() != source:
        tmp = path.with_suffix(f".{os.getpid()}.tmp")  # atomic for other processes
        tmp.write_text(source)
        os.replace(tmp, path)
    _OUTSIDE[str(path.resolve())] = Path("generated") / path.name
    spec = importlib.util.spec_from_file_location(name, path)
    module = importlib.util.module_from_spec(spec)
    sys.modules[name] = module
    spec.loader.exec_module(module)
    return module


def _in_package(function) -> bool:
    """Whether ``function`` is defined in a file of this package (doctests and
    interactive code are compiled, not cached)."""
    return _package_path(function.__code__.co_filename) is not None


# Once per file and folder, not per kernel: resolving a path and numba's check that a
# folder is writable (a temporary file) took 0.1 s of a cached start for ~400 kernels.
@functools.lru_cache(maxsize=None)
def _package_path(filename: str) -> Path | None:
    """``filename`` relative to the package (or its name under the cache for the df
    path's and generated modules), None outside them."""
    outside = _OUTSIDE.get(str(Path(filename).resolve()))
    if outside is not None:
        return outside
    try:
        return Path(filename).resolve().relative_to(_PACKAGE)
    except (ValueError, OSError):
        return None


@functools.lru_cache(maxsize=None)
def _writable(folder: str) -> bool:
    """Whether the cache folder ``folder`` exists or can be made, and takes files."""
    try:
        os.makedirs(folder, exist_ok=True)
        tempfile.TemporaryFile(dir=folder).close()
    except OSError:
        return False
    return True
