"""Small pieces shared by the Part 5 materials (not public)."""

from __future__ import annotations

import numpy as np

from render.material import Varying, df, evaluate, material_surface

__all__ = ["diffuse_surface", "float2", "color", "is_zero", "scaled"]


def diffuse_surface(tint) -> material_surface:
    """``material_surface(scattering: df::diffuse_reflection_bsdf(tint: tint))``."""
    return material_surface(scattering=df.diffuse_reflection_bsdf(tint=tint))


def float2(value, name: str) -> tuple[float, float]:
    """A uniform float2 argument as two floats (a scalar means ``float2(x)``)."""
    a = np.asarray(value, dtype=np.float64)
    if a.ndim == 0:
        a = np.full(2, float(a))
    if a.shape != (2,) or not np.all(np.isfinite(a)):
        raise ValueError(f"{name} must be a float2: one or two finite numbers, got {value!r}")
    return float(a[0]), float(a[1])


def color(value, name: str):
    """A color argument: a callable passes through, a constant becomes three floats."""
    if callable(value):
        return value
    a = np.asarray(value, dtype=np.float64)
    if a.ndim == 0:
        a = np.full(3, float(a))
    if a.shape != (3,) or not np.all(np.isfinite(a)):
        raise ValueError(f"{name} must be a color: one or three finite numbers, got {value!r}")
    return tuple(float(x) for x in a)


def is_zero(value) -> bool:
    """A constant that is exactly zero (so the feature it controls can be skipped)."""
    if callable(value):
        return False
    return bool(np.all(np.asarray(value, dtype=np.float64) == 0.0))


def scaled(tint, factor, name: str) -> Varying:
    """``tint * factor(state)`` for a color ``tint`` (constant or varying)."""
    def function(state):
        return evaluate(tint, state, "color", "tint") * factor(state)[:, None]
    return Varying(function, name, {"tint": tint})



