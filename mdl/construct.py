"""MDL's built-in constructors over lanes: scalars, vectors, colors and matrices.

``float3(x)`` repeats ``x``; ``float3(x, y, z)`` takes components; ``float3(v)``
converts a vector of the same size (``color(v)`` and ``float3(c)`` alike); ``color(r, g,
b)``; matrices take one value (on the diagonal), their columns, or every element column
by column; ``color(wavelengths, amplitudes)`` is :func:`mdl.mathlib.emission_color`.
The front end folds constant constructors with :func:`construct` and generated code
calls it, so each constructor exists once.

Examples
--------
>>> import numpy as np
>>> from mdl import types as T
>>> construct("vector", T.Vector("float", 3), [np.array([0.5])], [T.FLOAT]).tolist()
[[0.5, 0.5, 0.5]]
>>> construct("matrix", T.Matrix("float", 2, 2), [np.array([2.0])], [T.FLOAT]).tolist()
[[[2.0, 0.0], [0.0, 2.0]]]
"""

from __future__ import annotations

import numpy as np

from mdl import lanes as LN
from mdl import mathlib
from mdl import types as T

__all__ = ["construct"]


def _scalar(v, src: T.Type, kind: str):
    return LN.convert(v, src, T.Scalar(kind))


def construct(kind: str, t: T.Type, vals: list, types: list, lanes: int = 1):
    """The value ``t(vals...)`` (``types`` are the arguments' types)."""
    if kind == "scalar":
        if not vals:
            return LN.zeros(t, lanes)
        if isinstance(t, T.String):
            return vals[0]
        src = types[0]
        if isinstance(src, T.EnumType):
            src = T.INT
        return LN.convert(vals[0], src, t)
    if kind in ("vector", "color"):
        n = T.width(t)
        ek = "float" if kind == "color" else t.elem
        if not vals:
            return LN.zeros(t, lanes)
        if len(vals) == 1:
            src = types[0]
            if isinstance(src, (T.Scalar, T.EnumType)):
                s = _scalar(vals[0], T.INT if isinstance(src, T.EnumType) else src, ek)
                return LN.splat(s, n).astype(LN.dtype(t))
            return np.asarray(vals[0]).astype(LN.dtype(t))
        parts = [_scalar(v, T.INT if isinstance(s, T.EnumType) else s, ek)
                 for v, s in zip(vals, types, strict=True)]
        return LN.construct_vector(parts, t)
    if kind == "matrix":
        if not vals:
            return LN.zeros(t, lanes)
        if len(vals) == 1 and isinstance(types[0], T.Matrix):
            return np.asarray(vals[0]).astype(LN.dtype(t))
        parts = []
        for v, s in zip(vals, types, strict=True):
            if isinstance(s, T.Vector):
                parts.append(LN.convert(v, s, T.Vector(t.elem, s.size)))
            else:
                parts.append(_scalar(v, s, t.elem))
        return LN.construct_matrix(parts, t)
    if kind == "color_spectrum":
        w, a = vals
        return mathlib.emission_color(np.asarray(w, dtype=np.float64),
                                      np.asarray(a, dtype=np.float64))
    raise ValueError(f"unknown constructor kind {kind!r}")
