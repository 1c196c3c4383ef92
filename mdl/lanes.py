"""MDL values over lanes, and the semantics of MDL's operators on them.

A value of an MDL type is held for many shading points (*lanes*) at once, as numpy
arrays whose first axis is the lane (length ``L``, or 1 for a *uniform* value, which
broadcasts against any ``L``):

============================  ==============================================
MDL type                      representation
============================  ==============================================
bool, int, enum               ``(L,)`` bool / int32
float, double                 ``(L,)`` float64 (MDL's 32-bit float is held in 64 bits)
``floatN``, ``intN``...       ``(L, N)``
color                         ``(L, 3)`` linear RGB
``floatCxR``                  ``(L, C, R)``: ``m[:, c]`` is column ``c``
``T[N]`` of a value type      ``(L, N, ...)``
struct                        a tuple of its fields' values
``S[N]`` of a struct          a tuple of the fields, each with the ``N`` axis added
string, texture, ...          the Python object itself (always uniform)
============================  ==============================================

The same functions evaluate constants in the front end (one lane) and run in the code
the back end generates, so an operator has one implementation.  Integer arithmetic
wraps at 32 bits and divides toward zero, as in C; float division by zero gives
infinities (IEEE); out-of-range indices are clamped.

Examples
--------
>>> import numpy as np
>>> a = np.array([[1.0, 2.0, 3.0]]); s = np.array([2.0, 3.0])
>>> mul(a, s).tolist()                            # float3 * float, uniform * varying
[[2.0, 4.0, 6.0], [3.0, 6.0, 9.0]]
>>> div(np.array([-7], np.int32), np.array([2], np.int32)).tolist()
[-3]
"""

from __future__ import annotations

import numpy as np

from mdl import types as T

__all__ = [
    "dtype", "suffix", "zeros", "const", "lanes_of", "sel", "gather", "scatter", "take",
    "add", "sub", "mul", "div", "mod", "neg", "pos", "lnot", "bnot", "band", "bor", "bxor",
    "shl", "shr", "ushr", "land", "lor", "eq", "ne", "lt", "le", "gt", "ge",
    "matmul", "convert", "construct_vector", "construct_matrix", "splat", "component",
    "swizzle", "set_component", "set_swizzle", "index", "set_index", "set_field",
    "uniform_value", "to_python", "from_python", "broadcast_lanes", "as_bool",
]


def dtype(t: T.Type):
    """numpy dtype of a scalar, vector, matrix, color or enum type."""
    k = T.elem_kind(t)
    if isinstance(t, T.EnumType) or k == "int":
        return np.int32
    if k == "bool":
        return np.bool_
    return np.float64


def suffix(t: T.Type) -> tuple[int, ...]:
    """The per-lane shape of a value of type ``t`` (not for structs)."""
    if isinstance(t, T.Vector):
        return (t.size,)
    if isinstance(t, T.Color):
        return (3,)
    if isinstance(t, T.Matrix):
        return (t.cols, t.rows)
    if isinstance(t, T.ArrayT):
        return (t.size or 0,) + suffix(t.elem)
    return ()


def zeros(t: T.Type, n: int = 1, size: int | None = None):
    """The zero value of ``t`` on ``n`` lanes (structs: zero fields; arrays need their
    ``size`` when ``t`` does not fix it)."""
    if isinstance(t, T.StructType):
        return tuple(zeros(f.type, n) for f in t.fields)
    if isinstance(t, T.ArrayT):
        count = t.size if t.size is not None else (size or 0)
        if isinstance(t.elem, T.StructType):
            return tuple(_stack_axis(zeros(f.type, n), count) for f in t.elem.fields)
        if _is_object(t.elem):
            return [None] * count
        return np.zeros((n, count) + suffix(t.elem), dtype=dtype(t.elem))
    if _is_object(t):
        return None
    if isinstance(t, T.EnumType):
        first = t.values[0][1] if t.values else 0
        return np.full(n, first, dtype=np.int32)
    return np.zeros((n,) + suffix(t), dtype=dtype(t))


def _stack_axis(v, count: int):
    if isinstance(v, tuple):
        return tuple(_stack_axis(x, count) for x in v)
    if v is None:
        return [None] * count
    return np.repeat(v[:, None], count, axis=1)


def _is_object(t: T.Type) -> bool:
    return isinstance(t, (T.String, T.Resource, T.DF, T.ErrorType)) or (
        isinstance(t, T.StructType) and t.builtin)


def const(t: T.Type, value) -> object:
    """A uniform (one-lane) value of type ``t`` from a Python number or sequence."""
    if _is_object(t):
        return value
    return np.asarray(value, dtype=dtype(t)).reshape((1,) + suffix(t))


def lanes_of(v) -> int:
    """Lane count of a value (1 for uniform values and objects)."""
    if isinstance(v, tuple):
        return max((lanes_of(x) for x in v), default=1)
    if isinstance(v, np.ndarray):
        return v.shape[0]
    return 1


def broadcast_lanes(v, n: int):
    """``v`` materialised on ``n`` lanes (a copy; structs field by field)."""
    if isinstance(v, tuple):
        return tuple(broadcast_lanes(x, n) for x in v)
    if isinstance(v, np.ndarray):
        return np.array(np.broadcast_to(v, (n,) + v.shape[1:]))
    return v


def _expand(m: np.ndarray, ndim: int) -> np.ndarray:
    """A lane mask or lane scalar shaped to broadcast over ``ndim`` dimensions."""
    return m.reshape(m.shape + (1,) * (ndim - m.ndim)) if ndim > m.ndim else m


def sel(mask, a, b):
    """``mask ? a : b`` lane by lane (structs and arrays of structs field by field)."""
    if isinstance(a, tuple):
        return tuple(sel(mask, x, y) for x, y in zip(a, b, strict=True))
    if not isinstance(a, np.ndarray):
        return a if bool(np.all(mask)) else b
    nd = max(a.ndim, b.ndim)
    return np.where(_expand(mask, nd), a, b)


def gather(v, idx: np.ndarray, n: int):
    """The lanes ``idx`` of a value that has ``n`` lanes (uniform values unchanged)."""
    if isinstance(v, tuple):
        return tuple(gather(x, idx, n) for x in v)
    if isinstance(v, np.ndarray) and v.shape[0] == n and n != 1:
        return v[idx]
    if isinstance(v, np.ndarray) and n == 1 and v.shape[0] == 1:
        return v
    return v


def scatter(out, idx: np.ndarray, v):
    """Write ``v`` (the lanes ``idx``) into ``out`` in place; returns ``out``."""
    if isinstance(out, tuple):
        return tuple(scatter(o, idx, x) for o, x in zip(out, v, strict=True))
    if isinstance(out, np.ndarray):
        out[idx] = v
        return out
    return v


def take(v, n: int):
    """A fresh lane array of ``n`` lanes holding ``v`` (for scatter targets)."""
    return broadcast_lanes(v, n)


def as_bool(x) -> bool:
    """A uniform bool value as a Python bool."""
    return bool(np.asarray(x).reshape(-1)[0])


def uniform_value(x):
    """The single value of a uniform array as a Python scalar."""
    return np.asarray(x).reshape(-1)[0].item()


# ----------------------------------------------------------------------------- operators
def _align(a: np.ndarray, b: np.ndarray):
    """Give the lower-rank operand trailing axes (a scalar against a vector)."""
    if a.ndim < b.ndim:
        a = _expand(a, b.ndim)
    elif b.ndim < a.ndim:
        b = _expand(b, a.ndim)
    return a, b


def _wrap(x: np.ndarray) -> np.ndarray:
    """int64 intermediate to int32 with two's-complement wrap-around."""
    return x.astype(np.int64).astype(np.int32) if x.dtype != np.int32 else x


def _is_int(x) -> bool:
    return isinstance(x, np.ndarray) and x.dtype.kind in "iu"


def add(a, b):
    a, b = _align(a, b)
    if _is_int(a) and _is_int(b):
        return _wrap(a.astype(np.int64) + b)
    return a + b


def sub(a, b):
    a, b = _align(a, b)
    if _is_int(a) and _is_int(b):
        return _wrap(a.astype(np.int64) - b)
    return a - b


def mul(a, b):
    """Component-wise product (scalars, vectors, colors; a matrix times a scalar)."""
    a, b = _align(a, b)
    if _is_int(a) and _is_int(b):
        return _wrap(a.astype(np.int64) * b)
    return a * b


def div(a, b):
    a, b = _align(a, b)
    if _is_int(a) and _is_int(b):
        # C: truncate toward zero; division by zero gives 0 (MDL leaves it undefined)
        a64, b64 = a.astype(np.int64), b.astype(np.int64)
        safe = np.where(b64 == 0, 1, b64)
        q = np.abs(a64) // np.abs(safe) * np.sign(a64) * np.sign(safe)
        return _wrap(np.where(b64 == 0, 0, q))
    with np.errstate(divide="ignore", invalid="ignore"):
        return a / b


def mod(a, b):
    a, b = _align(a, b)
    if _is_int(a) and _is_int(b):
        a64, b64 = a.astype(np.int64), b.astype(np.int64)
        safe = np.where(b64 == 0, 1, b64)
        r = np.fmod(a64, safe)  # C: the sign of the dividend
        return _wrap(np.where(b64 == 0, 0, r))
    with np.errstate(divide="ignore", invalid="ignore"):
        return np.fmod(a, b)


def neg(a):
    if _is_int(a):
        return _wrap(-a.astype(np.int64))
    return -a


def pos(a):
    return a


def lnot(a):
    return np.logical_not(a)


def bnot(a):
    return np.invert(a)


def _int_pair(a, b):
    a, b = _align(a, b)
    if a.dtype == np.bool_ and b.dtype == np.bool_:
        return a, b
    return a.astype(np.int32), b.astype(np.int32)


def band(a, b):
    a, b = _int_pair(a, b)
    return a & b


def bor(a, b):
    a, b = _int_pair(a, b)
    return a | b


def bxor(a, b):
    a, b = _int_pair(a, b)
    return a ^ b


def shl(a, b):
    a, b = _align(a, b)
    return _wrap(a.astype(np.int64) << (b.astype(np.int64) & 31))


def shr(a, b):
    a, b = _align(a, b)
    return (a.astype(np.int32) >> (b.astype(np.int32) & 31)).astype(np.int32)


def ushr(a, b):
    a, b = _align(a, b)
    u = a.astype(np.int32).view(np.uint32)
    return (u >> (b.astype(np.uint32) & 31)).view(np.int32)


def land(a, b):
    return np.logical_and(a, b)


def lor(a, b):
    return np.logical_or(a, b)


def _cmp_axes(a, b):
    a, b = _align(a, b)
    return a, b, tuple(range(1, max(a.ndim, b.ndim)))


def eq(a, b):
    """``==``: vectors, colors, matrices compare whole (one bool per lane)."""
    if isinstance(a, tuple):
        out = np.ones(1, dtype=bool)
        for x, y in zip(a, b, strict=True):
            out = out & eq(x, y)
        return out
    if not isinstance(a, np.ndarray):
        return np.array([a == b])
    a, b, axes = _cmp_axes(a, b)
    r = a == b
    return np.all(r, axis=axes) if axes else r


def ne(a, b):
    return np.logical_not(eq(a, b))


def lt(a, b):
    return a < b


def le(a, b):
    return a <= b


def gt(a, b):
    return a > b


def ge(a, b):
    return a >= b


def matmul(a, b, kinds: tuple[str, str]):
    """Products involving matrices; ``kinds`` are ``"m"`` (matrix) or ``"v"`` (vector).

    ``m * v``: ``r[r] = sum_c m[c][r] v[c]``; ``v * m``: ``r[c] = dot(v, m[c])`` (row
    vector); ``m1 * m2``: the matrix product (columns of ``m2`` transformed by ``m1``).
    """
    if kinds == ("m", "v"):
        return np.einsum("...cr,...c->...r", a, b)
    if kinds == ("v", "m"):
        return np.einsum("...r,...cr->...c", a, b)
    if kinds == ("m", "m"):
        return np.einsum("...kr,...ck->...cr", a, b)
    raise ValueError(f"matmul of {kinds}")


# ----------------------------------------------------------------------------- conversions
def convert(v, src: T.Type, dst: T.Type):
    """An implicit or explicit conversion between numeric types of equal shape (and
    enum to int)."""
    if src == dst or isinstance(dst, T.ErrorType):
        return v
    if isinstance(dst, T.ArrayT):
        return v
    if not isinstance(v, np.ndarray):
        return v
    dt = dtype(dst)
    if dt == np.int32 and v.dtype.kind == "f":
        # C: truncation toward zero; NaN and out-of-range become INT_MIN-like values
        with np.errstate(invalid="ignore"):
            t = np.trunc(np.nan_to_num(v, nan=0.0, posinf=2**31 - 1, neginf=-2**31))
        return np.clip(t, -2**31, 2**31 - 1).astype(np.int32)
    if dt == np.bool_:
        return v != 0
    return v.astype(dt)


def splat(x: np.ndarray, n: int) -> np.ndarray:
    """A vector of ``n`` equal components from a scalar per lane."""
    return np.repeat(x[:, None], n, axis=1)


def construct_vector(parts: list, t: T.Type) -> np.ndarray:
    """``floatN(a, b, ...)`` from one scalar per component (each ``(L,)`` or ``(1,)``)."""
    arrays = np.broadcast_arrays(*[np.asarray(p) for p in parts])
    return np.stack(arrays, axis=1).astype(dtype(t))


def construct_matrix(parts: list, t: T.Matrix) -> np.ndarray:
    """``floatCxR(...)`` from C*R scalars (column by column), from C column vectors,
    or from one scalar (that value on the diagonal)."""
    dt = dtype(t)
    if len(parts) == 1 and parts[0].ndim == 1:
        d = parts[0]
        out = np.zeros((d.shape[0], t.cols, t.rows), dtype=dt)
        for k in range(min(t.cols, t.rows)):
            out[:, k, k] = d
        return out
    if len(parts) == t.cols and all(p.ndim == 2 for p in parts):
        cols = np.broadcast_arrays(*parts)
        return np.stack(cols, axis=1).astype(dt)
    flat = np.broadcast_arrays(*parts)
    m = np.stack(flat, axis=1).astype(dt)
    return m.reshape(m.shape[0], t.cols, t.rows)


# ----------------------------------------------------------------------------- access
_COMPONENTS = {"x": 0, "y": 1, "z": 2, "w": 3}


def component(v: np.ndarray, k: int) -> np.ndarray:
    return v[:, k]


def swizzle(v: np.ndarray, ks: tuple[int, ...]) -> np.ndarray:
    return v[:, list(ks)]


def _lane_index(i: np.ndarray, n: int) -> np.ndarray:
    return np.clip(i.astype(np.int64), 0, max(n - 1, 0))


def index(a, i: np.ndarray):
    """``a[i]`` along the axis after the lanes (arrays, vectors, matrix columns);
    out-of-range indices are clamped to the nearest element."""
    if isinstance(a, tuple):
        return tuple(index(x, i) for x in a)
    if isinstance(a, list):
        return a[int(_lane_index(np.asarray(i), len(a)).reshape(-1)[0])]
    n = a.shape[1]
    i = _lane_index(np.asarray(i), n)
    if i.shape[0] == 1:
        return a[:, int(i[0])]
    rows = np.arange(i.shape[0]) if a.shape[0] != 1 else np.zeros(i.shape[0], dtype=np.int64)
    return a[rows, i]


def _writable(a: np.ndarray, lanes: int) -> np.ndarray:
    n = max(a.shape[0], lanes)
    return np.array(np.broadcast_to(a, (n,) + a.shape[1:]))


def set_index(a, i, v, mask=None):
    """A copy of ``a`` with ``a[i] = v`` on the lanes of ``mask`` (all if None)."""
    if isinstance(a, tuple):
        return tuple(set_index(x, i, y, mask) for x, y in zip(a, v, strict=True))
    if isinstance(a, list):
        out = list(a)
        out[int(_lane_index(np.asarray(i), len(a)).reshape(-1)[0])] = v
        return out
    i = np.asarray(i)
    lanes = max(a.shape[0], i.shape[0], lanes_of(v), 1 if mask is None else mask.shape[0])
    out = _writable(a, lanes)
    i = np.broadcast_to(_lane_index(i, a.shape[1]), (lanes,))
    v = np.broadcast_to(v, (lanes,) + a.shape[2:])
    rows = np.arange(lanes)
    if mask is not None:
        m = np.broadcast_to(mask, (lanes,))
        rows, i, v = rows[m], i[m], v[m]
    out[rows, i] = v
    return out


def set_component(v: np.ndarray, k: int, x, mask=None) -> np.ndarray:
    """A copy of vector ``v`` with component ``k`` replaced (on ``mask``)."""
    lanes = max(v.shape[0], lanes_of(x), 1 if mask is None else mask.shape[0])
    out = _writable(v, lanes)
    new = np.broadcast_to(x, (lanes,))
    out[:, k] = new if mask is None else np.where(mask, new, out[:, k])
    return out


def set_swizzle(v: np.ndarray, ks: tuple[int, ...], x, mask=None) -> np.ndarray:
    out = v
    for j, k in enumerate(ks):
        out = set_component(out, k, x[:, j], mask)
    return out


def set_field(s: tuple, k: int, x, mask=None) -> tuple:
    """A copy of struct ``s`` with field ``k`` replaced (on ``mask``)."""
    new = x if mask is None else sel(mask, x, s[k])
    return s[:k] + (new,) + s[k + 1:]


# ----------------------------------------------------------------------------- python
def to_python(v, t: T.Type):
    """A uniform value as Python data: numbers, tuples (vectors, colors; matrices as a
    tuple of columns), bools, enum names (str), dicts for structs, lists for arrays."""
    if isinstance(t, T.StructType) and not t.builtin:
        return {f.name: to_python(x, f.type) for f, x in zip(t.fields, v, strict=True)}
    if isinstance(t, T.ArrayT):
        if isinstance(t.elem, T.StructType):
            n = _array_len(v)
            return [to_python(index(v, np.array([k])), t.elem) for k in range(n)]
        if isinstance(v, list):
            return list(v)
        return [to_python(v[:, k], t.elem) for k in range(v.shape[1])]
    if not isinstance(v, np.ndarray):
        return v
    x = v[0]
    if isinstance(t, T.EnumType):
        name = t.name_of(int(x))
        return name if name is not None else int(x)
    if isinstance(t, T.Matrix):
        return tuple(tuple(float(c) for c in col) for col in x)
    if np.ndim(x) == 0:
        return x.item()
    return tuple(y.item() for y in x)


def _array_len(v) -> int:
    while isinstance(v, tuple):
        v = v[0]
    return len(v) if isinstance(v, list) else v.shape[1]


def from_python(x, t: T.Type):
    """The uniform lane value of Python data (the inverse of :func:`to_python`)."""
    if isinstance(t, T.StructType) and not t.builtin:
        if isinstance(x, dict):
            return tuple(from_python(x[f.name], f.type) for f in t.fields)
        return tuple(from_python(y, f.type) for f, y in zip(t.fields, x, strict=True))
    if isinstance(t, T.ArrayT):
        items = list(x)
        if isinstance(t.elem, T.StructType):
            parts = [from_python(y, t.elem) for y in items]
            return _stack_structs(parts)
        if _is_object(t.elem):
            return items
        return np.stack([from_python(y, t.elem) for y in items], axis=1) if items else \
            np.zeros((1, 0) + suffix(t.elem), dtype=dtype(t.elem))
    if isinstance(t, T.EnumType) and isinstance(x, str):
        x = t.value_of(x.split("::")[-1])
    return const(t, x)


def _stack_structs(parts: list):
    first = parts[0]
    if isinstance(first, tuple):
        return tuple(_stack_structs([p[k] for p in parts]) for k in range(len(first)))
    if isinstance(first, np.ndarray):
        return np.stack(parts, axis=1)
    return list(parts)
