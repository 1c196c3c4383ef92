"""Optional system libraries some tests need, found without crashing the test run.

Mitsuba 3's LLVM back end (the reference renderer of ``tests/render/test_mitsuba.py`` and
``benchmarks/render_vs_mitsuba.py``) loads ``libLLVM`` through Dr.Jit at run time.  It
needs LLVM 16 or later (Debian's ``libllvm19``, which ``.ci/run`` installs); the LLVM 14
and 15 of the base system crash its JIT with a fatal error that kills pytest, so they
are never used: such tests skip with the reason instead.
"""

from __future__ import annotations

import os
import re
from importlib.util import find_spec
from pathlib import Path

#: where Debian's libllvm19 puts the library
LLVM19 = Path("/usr/lib/x86_64-linux-gnu/libLLVM-19.so")
#: oldest LLVM whose JIT runs Mitsuba here
MIN_LLVM = 16
ENV = "DRJIT_LIBLLVM_PATH"


def llvm_major(path: str | os.PathLike) -> int | None:
    """The LLVM major version in a library's file name, if it shows one.

    Examples
    --------
    >>> llvm_major("/usr/lib/libLLVM-15.so"), llvm_major("libLLVM.so.19.1")
    (15, 19)
    >>> llvm_major("llvm-19/lib/libLLVM.so") is None  # the folder does not count
    True
    """
    m = re.search(r"libLLVM(?:-(\d+)|\.so\.(\d+))", Path(path).name)
    return int(m.group(1) or m.group(2)) if m else None


def mitsuba_llvm(env=None, default: Path = LLVM19) -> tuple[str | None, str | None]:
    """``(library, None)`` to run Mitsuba's LLVM back end with, or ``(None, reason)``.

    ``$DRJIT_LIBLLVM_PATH`` wins when set (and is refused if it names an LLVM older than
    :data:`MIN_LLVM`); else ``default`` when it exists.
    """
    env = os.environ if env is None else env
    fix = ("install Debian's libllvm19 (apt-get install libllvm19, as .ci/run does) or set "
           f"{ENV} to an LLVM >= {MIN_LLVM} library")
    if find_spec("mitsuba") is None:
        return None, "mitsuba is not installed (pip install -e '.[test]')"
    given = env.get(ENV)
    path = Path(given) if given else default
    if not path.is_file():
        where = f"{ENV}={given} does not exist" if given else f"{default} is absent"
        return None, f"Mitsuba's LLVM back end needs LLVM >= {MIN_LLVM}: {where}; {fix}"
    major = llvm_major(path)
    if major is not None and major < MIN_LLVM:
        return None, (f"{path} is LLVM {major}, which crashes Mitsuba's JIT; {fix}")
    return str(path), None


def use_mitsuba_llvm() -> str | None:
    """Point Dr.Jit at the LLVM to use (before mitsuba is imported); returns the reason
    to skip Mitsuba's tests, or None when they can run."""
    library, reason = mitsuba_llvm()
    if library is not None:
        os.environ[ENV] = library
    return reason
