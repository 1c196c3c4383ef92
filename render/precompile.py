"""The first render on a machine, on both cores: the df kernels compile in a second process.

numba compiles one kernel at a time, under one lock, so a cold start runs on one core:
83 s of CPU for the render kernels, about 31 s of it the distribution functions' own
kernels (each ``render/df`` module's ``eval_pdf``, ``sample``, ``albedo``, curves and
factors).  Those kernels do not depend on the path kernel, and the interpreter calls
every one of them with the same kinds of arguments, so a second process can compile
them into the shared kernel cache (:func:`render.jit.cache_dir`) while the first
compiles the path kernel: when the first reaches a df kernel the second has finished,
it loads it from the cache instead of compiling it (numba looks in the cache before it
compiles a callee).  The second process starts from the end of the dispatch, the first
reaches the kernels from its start, and they meet in between.

The arguments follow one convention, by parameter name (:data:`KERNEL_ARGS`); a test
checks that every df kernel the path kernel calls is the one compiled here.  Whatever
the second process has not finished, the first compiles itself: it is never waited for.
"""

from __future__ import annotations

import inspect
import os
import subprocess
import sys
from pathlib import Path

from numba import types

__all__ = ["KERNEL_ARGS", "df_kernels", "kernel_signature", "compile_df_kernels",
           "compile_df_kernels_aside", "before_first_render", "cores"]

_INT = types.int64
#: the types the interpreter passes a df kernel, by parameter name; every other
#: parameter is a float64 (directions, variates, IORs, colours)
KERNEL_ARGS = {
    "P": types.Array(types.float64, 2, "C"),      # the program's parameter rows
    "T": types.Array(types.float64, 1, "C"),      # the program's tables
    "tables": types.Array(types.float64, 1, "C"),
    "row": _INT, "b": _INT, "flags": _INT, "t": _INT, "k": _INT, "i": _INT,
}


def df_kernels() -> list:
    """The kernels of :mod:`render.df` the interpreter calls, in its dispatch order."""
    from numba.core.dispatcher import Dispatcher

    from render import interpreter

    return [v for v in vars(interpreter).values()
            if isinstance(v, Dispatcher) and v.py_func.__module__.startswith("render.df.")]


def kernel_signature(kernel) -> tuple:
    """The argument types the interpreter calls ``kernel`` with (:data:`KERNEL_ARGS`)."""
    return tuple(KERNEL_ARGS.get(p, types.float64)
                 for p in inspect.signature(kernel.py_func).parameters)


def compile_df_kernels() -> None:
    """Compile (or load from the cache) every df kernel, from the end of the dispatch."""
    for kernel in reversed(df_kernels()):
        kernel.compile(kernel_signature(kernel))


def cores() -> int:
    """The cores this process may run on (all the machine's where that is not known)."""
    try:
        return len(os.sched_getaffinity(0))
    except AttributeError:  # not Linux
        return os.cpu_count() or 1


def compile_df_kernels_aside() -> subprocess.Popen | None:
    """Start :func:`compile_df_kernels` in a second process (None on one core).  It runs
    to its end whatever this process does; its output is discarded."""
    if cores() < 2:
        return None
    here = str(Path(__file__).resolve().parents[1])  # this checkout's render package
    path = os.pathsep.join(p for p in (here, os.environ.get("PYTHONPATH")) if p)
    return subprocess.Popen(
        [sys.executable, "-c", "from render.precompile import compile_df_kernels as c; c()"],
        env={**os.environ, "PYTHONPATH": path}, stdin=subprocess.DEVNULL,
        stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)


def before_first_render(prog: str, quiet: bool = False) -> None:
    """What a command does before it renders: on a cold kernel cache, say so (unless
    ``quiet``, :func:`render.jit.notice_first_compile`) and compile the df kernels aside."""
    from render.jit import notice_first_compile

    if notice_first_compile(prog, quiet):
        compile_df_kernels_aside()
