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

Processes of one machine that render at once on a cold cache (the workers of a local
Dask cluster, ``pwc gallery`` on Dask) take turns at the first compile
(:func:`first_compile`, a lock file in the cache): one compiles, with its second
process, and the others load what it compiled instead of compiling it again each.
"""

from __future__ import annotations

import contextlib
import inspect
import os
import subprocess
import sys
import threading

from numba import types
from numba.core import event

__all__ = ["KERNEL_ARGS", "df_kernels", "kernel_signature", "compile_df_kernels",
           "compile_df_kernels_aside", "cores", "kernels_ready", "notice_first_compile",
           "first_compile", "compiled_integrator", "READY"]

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
    """The kernels of the declared dfs (:mod:`render.df._registry`) that the interpreter
    calls, in its dispatch's order (by opcode, then phase)."""
    from render.df._registry import registry

    out = []
    for node in registry().nodes:
        out += [k for k in node.kernels.values() if k not in out]
    return out


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
    from render import checkout_pythonpath

    return subprocess.Popen(
        [sys.executable, "-c", "from render.precompile import compile_df_kernels as c; c()"],
        env={**os.environ, "PYTHONPATH": checkout_pythonpath()}, stdin=subprocess.DEVNULL,
        stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)


#: the file in the cache folder that says a render has traced samples with its kernels
READY = "ready"


def kernels_ready() -> bool:
    """Whether this tree's kernels are compiled on this machine: a render has traced its
    first samples with them (:func:`render.jit.cache_dir` holds :data:`READY`).  A
    kernel that only some scenes call may still compile on its first use."""
    from render.jit import cache_dir

    return (cache_dir() / READY).is_file()


_said: set = set()  # the cache folders this process has said it compiles into
_said_lock = threading.Lock()


def notice_first_compile(prog: str, quiet: bool = False) -> bool:
    """Before a render on a cold cache (not :func:`kernels_ready`), say on stderr, once
    per process and unless ``quiet``, that the kernels compile now.  On a ready cache,
    say so only if the render compiles a kernel after all: one that only some scenes
    call (a varying emission's, a curve layer's Ĉ table's: 0.4-7 s each, once per
    machine; docs/render.md, "Start-up").  Returns whether the cache is cold."""
    from render.jit import cache_dir

    if quiet:
        return not kernels_ready()
    if kernels_ready():
        _compile_notice.prog = prog
        with _said_lock:
            if not _compile_notice.registered:
                event.register("numba:compile", _compile_notice)
                _compile_notice.registered = True
        return False
    _say(f"{prog}: compiling render kernels, once per machine (about a minute; cached in "
         f"{cache_dir()})")
    return True


def _say(message: str) -> None:
    """``message`` on stderr, unless this process has said it compiles into this cache."""
    from render.jit import cache_dir

    folder = cache_dir()
    with _said_lock:
        if folder in _said:
            return
        _said.add(folder)
    print(message, file=sys.stderr)


class _CompileNotice(event.Listener):
    """Says, at the first kernel of the workbench's that a render compiles on a ready
    cache, that it does (numba's ``numba:compile`` event: a compile, not a cache load)."""

    def __init__(self):
        self.prog, self.registered = "pwc", False

    def on_start(self, ev):
        from render.jit import is_kernel

        if is_kernel(ev.data["dispatcher"]):
            _say(f"{self.prog}: compiling the render kernels this scene needs, once per "
                 f"machine (seconds)")

    def on_end(self, ev):
        pass


_compile_notice = _CompileNotice()


@contextlib.contextmanager
def first_compile():
    """Around the first kernel calls of a render (:func:`compiled_integrator`): on a
    cold cache, take this machine's turn to compile (a lock on ``compile.lock`` in the
    cache folder; others wait for it, then load what it compiled), start
    :func:`compile_df_kernels_aside`, and when the block ends without an error write
    :data:`READY`.  Yields whether this block compiles; on a ready cache it neither
    waits nor compiles, nor where the cache folder cannot be written (numba then caches
    elsewhere, or not at all).  Without ``fcntl`` (not POSIX) there is no lock, and
    processes compile alike."""
    if kernels_ready():
        yield False
        return
    from render.jit import cache_dir

    folder = cache_dir()
    try:
        folder.mkdir(parents=True, exist_ok=True)
        lock = open(folder / "compile.lock", "a")  # noqa: SIM115 - closed below
    except OSError:
        yield False
        return
    with lock:  # closing the file releases the lock
        try:
            import fcntl

            fcntl.flock(lock, fcntl.LOCK_EX)
        except ImportError:  # not POSIX
            pass
        if kernels_ready():  # compiled by the process this one waited for
            yield False
            return
        compile_df_kernels_aside()
        yield True
        with contextlib.suppress(OSError):
            (folder / READY).touch()


def compiled_integrator(scene, geometry, aovs=()):
    """The scene's :class:`~render.integrator.Integrator` with the kernels its render
    calls compiled: on a cold cache in this machine's turn (:func:`first_compile`), by
    tracing a few samples, so the turn ends before the render does."""
    import numpy as np

    from render.integrator import Integrator

    with first_compile() as compiling:
        integ = Integrator(scene, geometry, aovs)
        if compiling:
            n = min(64, integ.camera.width * integ.camera.height)
            integ.trace(np.arange(n), np.zeros(n, np.int64), 0)
    return integ
