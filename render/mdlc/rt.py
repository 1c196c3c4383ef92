"""What code generated from MDL calls at run time: masked calls, ``::state``, ``::tex``,
``::debug`` and ``::scene`` over lanes, and native (Python) functions of the workbench.

Generated code (:mod:`render.mdlc.codegen`) runs on ``L`` lanes of a
:class:`~displacement.state.ShadingState` ``S`` at once.  A call made where only some
lanes are active (inside a branch whose condition varies) runs the callee on those
lanes alone (:func:`mcall`): their arguments and state are gathered, the result
scattered back; the other lanes get the type's zero.  So a texture lookup or a library
function never sees the garbage values of lanes that do not take the branch.

``::state``: internal space is object space; world space is the state's
``object_to_world`` (identity when there is none).  ``geometry_normal`` is the state's
if it has one, else the shading normal; ``direction`` likewise (else zero);
``texture_space_max`` is 1 (one uv set); ``animation_time`` 0; ``wavelength_*`` the
visible range (380, 780) nm; ``rounded_corner_normal`` the shading normal (not
rounded).

``::tex``: 2D textures only (:class:`displacement.textures.Texture`, bilinear or
nearest as the scene says); ``texture_3d``/``cube``/``ptex`` lookups raise a located
error.  An invalid texture (``texture_2d()``, or a file that is not there) looks up 0.
"""

from __future__ import annotations

import sys

import numpy as np

from mdl import lanes as LN
from mdl import mathlib as MATH  # noqa: F401 - used by generated code
from mdl import types as T
from mdl.construct import construct  # noqa: F401 - used by generated code

__all__ = ["mcall", "ncall", "MdlRuntimeError", "size_of", "array_of", "cv", "STATE", "TEX",
           "DEBUG", "SCENE", "lane_count", "zero_of", "transform_matrix"]


class MdlRuntimeError(ValueError):
    """An MDL function failed while running (``debug::assert``, a missing feature),
    located at its MDL source; ``str()`` is ``file:line:col: message``."""


def lane_count(S) -> int:
    return len(S)


def mcall(f, mask, S, L, zero, *args):
    """``f(S, L, *args)`` on the lanes of ``mask`` only (all lanes when None)."""
    if mask is None:
        return f(S, L, *args)
    m = np.broadcast_to(np.asarray(mask), (L,))
    idx = np.flatnonzero(m)
    if idx.size == L:
        return f(S, L, *args)
    out = zero(L)
    if idx.size == 0:
        return out
    sub = S.subset(idx) if S is not None and len(S) == L else S
    res = f(sub, idx.size, *[LN.gather(a, idx, L) for a in args])
    res = LN.broadcast_lanes(res, idx.size) if LN.lanes_of(res) == 1 and idx.size != 1 else res
    return LN.scatter(out, idx, res)


def ncall(binding, mask, S, L, zero, *args):
    """A native function on the lanes of ``mask``; ``binding(S, n, *args)``."""
    return mcall(binding, mask, S, L, zero, *args)


def zero_of(t: T.Type):
    """A factory ``L -> zero value of t on L lanes``."""
    def make(n):
        return LN.zeros(t, n)
    return make


def size_of(a) -> np.ndarray:
    """The element count of an array value, as a uniform int."""
    while isinstance(a, tuple):
        a = a[0]
    n = len(a) if isinstance(a, list) else a.shape[1]
    return np.array([n], dtype=np.int32)


def array_of(elems: list, struct: bool):
    """An array value from its element values (each on 1 or L lanes)."""
    if not elems:
        return np.zeros((1, 0))
    if struct:
        return _stack_struct(elems)
    if not isinstance(elems[0], np.ndarray):
        return list(elems)
    parts = np.broadcast_arrays(*elems)
    return np.stack(parts, axis=1)


def _stack_struct(elems):
    first = elems[0]
    if isinstance(first, tuple):
        return tuple(_stack_struct([e[k] for e in elems]) for k in range(len(first)))
    if isinstance(first, np.ndarray):
        return np.stack(np.broadcast_arrays(*elems), axis=1)
    return list(elems)


def cv(x, dtype):
    """An implicit conversion to ``dtype`` (int to float...)."""
    if isinstance(x, np.ndarray) and x.dtype != dtype:
        if dtype == np.int32 and x.dtype.kind == "f":
            return LN.convert(x, T.FLOAT, T.INT)
        return x.astype(dtype)
    return x


# ----------------------------------------------------------------------------- ::state
def _rows(a, L):
    a = np.asarray(a, dtype=np.float64)
    return a if a.shape[0] == L else np.broadcast_to(a, (L,) + a.shape[1:])


_COORD_INTERNAL, _COORD_OBJECT, _COORD_WORLD = 0, 1, 2


def transform_matrix(S, frm: int, to: int) -> np.ndarray:
    """``state::transform(from, to)``: (4, 4), column vectors (``M @ p``); internal
    space is object space."""
    m = getattr(S, "object_to_world", None)
    if m is None:
        o2w = np.eye(4)
    else:
        m = np.asarray(m, dtype=np.float64)
        if m.ndim != 2:
            raise MdlRuntimeError("state::transform needs one transform for every lane")
        o2w = m if m.shape == (4, 4) else np.block([[m, np.zeros((3, 1))],
                                                    [np.zeros((1, 3)), np.ones((1, 1))]])
    world = lambda s: s == _COORD_WORLD  # noqa: E731
    if world(frm) == world(to):
        return np.eye(4)
    return o2w if world(to) else np.linalg.inv(o2w)


def _space(x) -> int:
    return int(LN.uniform_value(x))


class STATE:
    """``::state`` over lanes (called as ``STATE.name(S, L, *args)``)."""

    @staticmethod
    def position(S, L):
        return _rows(S.position, L)

    @staticmethod
    def normal(S, L):
        return _rows(S.normal, L)

    @staticmethod
    def geometry_normal(S, L):
        g = getattr(S, "geometry_normal", None)
        return _rows(S.normal if g is None else g, L)

    @staticmethod
    def motion(S, L):
        return np.zeros((L, 3))

    @staticmethod
    def texture_space_max(S, L):
        return np.ones(1, dtype=np.int32)

    @staticmethod
    def texture_coordinate(S, L, index):
        out = np.zeros((L, 3))
        i = np.broadcast_to(index, (L,))
        out[:, :2] = np.where((i == 0)[:, None], _rows(S.uv, L), 0.0)
        return out

    @staticmethod
    def texture_tangent_u(S, L, index):
        i = np.broadcast_to(index, (L,))
        return np.where((i == 0)[:, None], _rows(S.tangent_u, L), 0.0)

    @staticmethod
    def texture_tangent_v(S, L, index):
        i = np.broadcast_to(index, (L,))
        return np.where((i == 0)[:, None], _rows(S.tangent_v, L), 0.0)

    geometry_tangent_u = texture_tangent_u
    geometry_tangent_v = texture_tangent_v

    @staticmethod
    def tangent_space(S, L, index):
        cols = [STATE.texture_tangent_u(S, L, index), STATE.texture_tangent_v(S, L, index),
                _rows(S.normal, L)]
        return np.stack(cols, axis=1)

    @staticmethod
    def direction(S, L):
        d = getattr(S, "direction", None)
        return np.zeros((L, 3)) if d is None else _rows(d, L)

    @staticmethod
    def animation_time(S, L):
        return np.zeros(1)

    @staticmethod
    def wavelength_base(S, L):
        return np.array([[680.0, 535.0, 465.0]])

    @staticmethod
    def transform(S, L, frm, to):
        return transform_matrix(S, _space(frm), _space(to)).T[None]  # columns

    @staticmethod
    def transform_point(S, L, frm, to, p):
        m = transform_matrix(S, _space(frm), _space(to))
        return p @ m[:3, :3].T + m[:3, 3]

    @staticmethod
    def transform_vector(S, L, frm, to, v):
        m = transform_matrix(S, _space(frm), _space(to))
        return v @ m[:3, :3].T

    @staticmethod
    def transform_normal(S, L, frm, to, n):
        m = transform_matrix(S, _space(frm), _space(to))
        return n @ np.linalg.inv(m[:3, :3])

    @staticmethod
    def transform_scale(S, L, frm, to, s):
        m = transform_matrix(S, _space(frm), _space(to))
        return s * abs(np.linalg.det(m[:3, :3])) ** (1.0 / 3.0)

    @staticmethod
    def rounded_corner_normal(S, L, radius, across_materials, roundness):
        return _rows(S.normal, L)

    @staticmethod
    def meters_per_scene_unit(S, L):
        return np.ones(1)

    @staticmethod
    def scene_units_per_meter(S, L):
        return np.ones(1)

    @staticmethod
    def object_id(S, L):
        return np.array([int(getattr(S, "object_id", 0) or 0)], dtype=np.int32)

    @staticmethod
    def wavelength_min(S, L):
        return np.array([380.0])

    @staticmethod
    def wavelength_max(S, L):
        return np.array([780.0])


# ----------------------------------------------------------------------------- ::tex
_WRAP = {0: "clamp", 1: "repeat", 2: "mirrored_repeat", 3: "clip"}


def _wrap01(t: np.ndarray, mode: str) -> np.ndarray:
    if mode == "repeat":
        return t - np.floor(t)
    if mode == "mirrored_repeat":
        return 1.0 - np.abs(t - 2.0 * np.floor(0.5 * t) - 1.0)
    return np.clip(t, 0.0, 1.0)


def _lookup(tex, coord, wrap_u, wrap_v, crop_u, crop_v, n):
    if tex is None:
        return None
    uv = np.array(np.broadcast_to(np.asarray(coord, dtype=np.float64), (n, 2)))
    bad = ~np.all(np.isfinite(uv), axis=1)
    uv[bad] = 0.0
    wu, wv = _WRAP[_space(wrap_u)], _WRAP[_space(wrap_v)]
    cu = np.asarray(crop_u, dtype=np.float64).reshape(-1)[:2]
    cvv = np.asarray(crop_v, dtype=np.float64).reshape(-1)[:2]
    clip = np.zeros(n, dtype=bool)
    if wu == "clip":
        clip |= (uv[:, 0] < 0.0) | (uv[:, 0] > 1.0)
    if wv == "clip":
        clip |= (uv[:, 1] < 0.0) | (uv[:, 1] > 1.0)
    cropped = not (np.array_equal(cu, [0.0, 1.0]) and np.array_equal(cvv, [0.0, 1.0]))
    if cropped or "clip" in (wu, wv):
        uv[:, 0] = cu[0] + _wrap01(uv[:, 0], wu if wu != "clip" else "clamp") * (cu[1] - cu[0])
        uv[:, 1] = cvv[0] + _wrap01(uv[:, 1], wv if wv != "clip" else "clamp") * (
            cvv[1] - cvv[0])
        out = tex.lookup(uv, "clamp", "clamp")
    else:
        out = tex.lookup(uv, wu, wv)
    out[clip | bad] = 0.0
    return out


def _channels(v: np.ndarray, k: int) -> np.ndarray:
    c = v.shape[1]
    if k == 1:
        return v[:, 0]
    if c >= k:
        return v[:, :k]
    if c == 1:
        return np.repeat(v, k, axis=1) if k != 4 else np.concatenate(
            [np.repeat(v, 3, axis=1), np.ones((len(v), 1))], axis=1)
    if c == 2 and k >= 3:  # grey + alpha
        g = np.repeat(v[:, :1], 3, axis=1)
        return g if k == 3 else np.concatenate([g, v[:, 1:2]], axis=1)
    pad = np.zeros((len(v), k - c))
    if k == 4:
        pad[:, -1] = 1.0
    return np.concatenate([v, pad], axis=1)


class TEX:
    """``::tex`` over lanes (``TEX.name(S, L, *args)``)."""

    @staticmethod
    def width(S, L, tex, *rest):
        return np.array([0 if tex is None else tex.width], dtype=np.int32)

    @staticmethod
    def height(S, L, tex, *rest):
        return np.array([0 if tex is None else tex.height], dtype=np.int32)

    @staticmethod
    def depth(S, L, tex, *rest):
        raise MdlRuntimeError("tex::depth: 3D textures are not supported by the workbench")

    @staticmethod
    def texture_isvalid(S, L, tex):
        return np.array([tex is not None])

    @staticmethod
    def lookup(k: int, S, L, tex, coord, wrap_u=1, wrap_v=1, crop_u=(0.0, 1.0),
               crop_v=(0.0, 1.0), frame=0.0):
        n = max(L, LN.lanes_of(coord))
        v = _lookup(tex, coord, wrap_u, wrap_v, crop_u, crop_v, n)
        if v is None:
            return np.zeros((n,) if k == 1 else (n, k))
        return _channels(v, k)

    @staticmethod
    def texel(k: int, S, L, tex, coord, uv_tile=None, frame=0.0):
        c = np.asarray(coord)
        n = max(L, c.shape[0])
        if tex is None:
            return np.zeros((n,) if k == 1 else (n, k))
        c = np.broadcast_to(c, (n, 2))
        i = np.clip(c[:, 0], 0, tex.width - 1)
        j = np.clip(c[:, 1], 0, tex.height - 1)
        v = tex.data[tex.height - 1 - j, i]  # texel (0, 0) is the lower-left
        return _channels(v, k)


# ----------------------------------------------------------------------------- ::debug
class DEBUG:
    """``::debug``: ``assert`` raises :class:`MdlRuntimeError` at its MDL location when
    it fails on any active lane; ``print`` writes the first lanes' values to stderr."""

    @staticmethod
    def assert_(where: str, S, L, condition, reason, funcname="", filename="", line=0):
        ok = np.asarray(condition, dtype=bool)
        if not np.all(ok):
            bad = int(np.count_nonzero(~ok))
            raise MdlRuntimeError(f"{where}: debug::assert failed on {bad} of {ok.size} "
                                  f"lanes: {reason}")
        return np.ones(1, dtype=bool)

    @staticmethod
    def print_(where: str, S, L, value):
        v = value if not isinstance(value, np.ndarray) else value[:4].tolist()
        print(f"{where}: debug::print {v}", file=sys.stderr)
        return np.ones(1, dtype=bool)

    @staticmethod
    def breakpoint_(where: str, S, L):
        return np.ones(1, dtype=bool)


class SCENE:
    """``::scene`` (MDL 1.7): the workbench's objects carry no scene data, so every
    lookup gives its default and ``data_isvalid`` is false."""

    @staticmethod
    def data_isvalid(S, L, name):
        return np.zeros(1, dtype=bool)

    @staticmethod
    def lookup(S, L, name, default):
        return default
