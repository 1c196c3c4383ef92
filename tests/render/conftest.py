"""The distribution-function tests run strict: internal finiteness checks on, and any
floating-point division by zero, invalid operation or overflow raises (underflow to 0 is
allowed).  Scoped to the df test files (other render tests opt in by listing theirs)."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from render.numerics import strict

_HERE = Path(__file__).resolve().parent
STRICT_PATHS = (
    _HERE / "df",
    _HERE / "test_warp.py",
    _HERE / "test_numerics.py",
    _HERE / "test_frame.py",
)


@pytest.fixture(autouse=True)
def _strict_float(request):
    path = Path(str(request.node.path)).resolve()
    if not any(path == p or p in path.parents for p in STRICT_PATHS):
        yield
        return
    with strict(), np.errstate(divide="raise", invalid="raise", over="raise", under="ignore"):
        yield
