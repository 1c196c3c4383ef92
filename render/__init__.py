"""Render: a small Embree path tracer that evaluates MDL's material model.

Conventions for directions and frames: :mod:`render.frame`.  Interfaces: :mod:`render.bsdf`.
``render.render(scene, spp=...)`` renders a scene file or :class:`render.scene.Scene`
(see :func:`render.integrator.render`).
"""

import importlib
import os
from pathlib import Path

from render.bsdf import Bsdf, BsdfSample, Edf, EdfSample, Lobe
from render.frame import Frame

__all__ = ["df", "Bsdf", "BsdfSample", "Edf", "EdfSample", "Lobe", "Frame", "render",
           "checkout_pythonpath"]


def __getattr__(name: str):
    """``render.df`` on first use: it imports numba and every kernel module (0.4 s), which
    commands that only register their options (``pwc compile``, ``pwc --help``) never
    need."""
    if name == "df":
        return importlib.import_module("render.df")
    raise AttributeError(f"module 'render' has no attribute {name!r}")


def render(scene, **options):
    """Render a scene (a TOML path or a Scene); returns the Film.  See
    :func:`render.integrator.render` for the options."""
    from render.integrator import render as _render

    return _render(scene, **options)


def checkout_pythonpath(rest: str | None = None) -> str:
    """``PYTHONPATH`` for a child process (a kernel compiler, a Dask worker, a test's
    ``pwc``) that must import this checkout's packages, whatever its working folder: this
    checkout first, then ``rest`` (default: this process's ``PYTHONPATH``)."""
    here = str(Path(__file__).resolve().parents[1])
    rest = os.environ.get("PYTHONPATH") if rest is None else rest
    return os.pathsep.join(p for p in (here, rest) if p)
