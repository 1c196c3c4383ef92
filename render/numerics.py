"""Safe maths over lane arrays for the renderer's Python side, and its tolerances.

Guarded sqrt and division, row-wise dot product and normalisation, luminance: the numpy
helpers of the code that prepares scenes, frames and lights.  They map arrays to arrays
without producing NaN or raising floating-point errors for any finite input (the tests
run under ``np.errstate(all="raise")``): special cases are selected with masks and
``np.where``, and divisions only ever see safe denominators.  The kernels' per-lane maths
(Fresnel, refraction, reflection, warps) has its one implementation in
:mod:`render.df._kernel_common`.  The one set of tolerances the renderer uses lives in
:data:`TOL`.
"""

from __future__ import annotations

from contextlib import contextmanager
from dataclasses import dataclass

import numpy as np

from render._typing import Arr, ArrayLike, Vec3

__all__ = [
    "TOL",
    "Tolerances",
    "ONE_MINUS_EPS",
    "strict",
    "is_strict",
    "check_finite",
    "safe_sqrt",
    "safe_div",
    "dot",
    "row_max",
    "unitize",
    "luminance",
]


@dataclass(frozen=True)
class Tolerances:
    """The renderer's tolerances (one object, no stray epsilons elsewhere)."""

    #: a direction (or microfacet normal) with ``|cos theta| <= cos_zero`` lies in the
    #: tangent plane: no scattering, no emission (a set of measure ~1e-10 that keeps
    #: ``1/cos`` finite).
    cos_zero: float = 1e-10
    #: lower clamp of every roughness (libbsdf clamps at 1e-7): roughness 0 is a
    #: near-mirror lobe about 1e-7 rad wide, not a delta.
    roughness_min: float = 1e-7
    #: glossy refraction needs ``|ior_inside - ior_outside| >= ior_delta_min`` (libbsdf):
    #: at an exact index match every microfacet passes light straight through, so the
    #: transmitted lobe would be a delta.
    ior_delta_min: float = 1e-4
    #: smallest spot_edf spread (radians); spread 0 would be a delta beam.
    spread_min: float = 1e-6
    #: vectors shorter than this cannot be normalised (``unitize`` marks them invalid).
    unit_min: float = 1e-300


TOL = Tolerances()

#: largest float64 below 1: rescaled random numbers are clamped to it to stay in [0, 1).
ONE_MINUS_EPS = float(np.nextafter(1.0, 0.0))

_STRICT = [False]


@contextmanager
def strict(enabled: bool = True):
    """Enable costly internal checks (finite, non-negative outputs) inside the block.

    Examples
    --------
    >>> with strict():
    ...     is_strict()
    True
    >>> is_strict()
    False
    """
    old = _STRICT[0]
    _STRICT[0] = enabled
    try:
        yield
    finally:
        _STRICT[0] = old


def is_strict() -> bool:
    """Whether :func:`strict` checks are enabled."""
    return _STRICT[0]


def check_finite(name: str, a: np.ndarray, nonnegative: bool = False) -> np.ndarray:
    """In strict mode, raise ``AssertionError`` if ``a`` has NaN/inf (or negatives).

    Parameters
    ----------
    name : str
        What ``a`` is, for the message.
    a : array
    nonnegative : bool
        Also require ``a >= 0``.

    Returns
    -------
    array
        ``a`` itself.
    """
    if _STRICT[0]:
        if not np.all(np.isfinite(a)):
            raise AssertionError(f"{name}: {np.count_nonzero(~np.isfinite(a))} non-finite values")
        if nonnegative and np.any(a < 0):
            raise AssertionError(f"{name}: negative values (min {a.min()!r})")
    return a


def safe_sqrt(x: ArrayLike) -> np.ndarray:
    """``sqrt(max(x, 0))``: rounding that pushes a square slightly below 0 gives 0.

    Examples
    --------
    >>> safe_sqrt(np.array([4.0, 0.0, -1e-17])).tolist()
    [2.0, 0.0, 0.0]
    """
    return np.sqrt(np.maximum(x, 0.0))


def safe_div(a: ArrayLike, b: ArrayLike, default: float = 0.0) -> np.ndarray:
    """``a / b`` where ``b != 0``, else ``default`` (no division by zero is evaluated).

    Examples
    --------
    >>> safe_div(np.array([1.0, 1.0]), np.array([2.0, 0.0])).tolist()
    [0.5, 0.0]
    """
    a = np.asarray(a, dtype=np.float64)
    b = np.asarray(b, dtype=np.float64)
    ok = b != 0
    return np.where(ok, a / np.where(ok, b, 1.0), default)


def dot(a: Vec3, b: Vec3) -> Arr:
    """Row-wise dot product of (n, 3) arrays -> (n,).

    Examples
    --------
    >>> dot(np.array([[1.0, 2.0, 3.0]]), np.array([[0.0, 1.0, 1.0]])).tolist()
    [5.0]
    """
    a = np.asarray(a)
    b = np.asarray(b)
    return a[..., 0] * b[..., 0] + a[..., 1] * b[..., 1] + a[..., 2] * b[..., 2]


def row_max(a: Vec3) -> Arr:
    """Largest entry of each (n, 3) row (``a.max(axis=-1)``; a reduction over a short
    axis is several times slower).

    Examples
    --------
    >>> row_max(np.array([[1.0, 3.0, 2.0], [-1.0, -2.0, -3.0]])).tolist()
    [3.0, -1.0]
    """
    a = np.asarray(a)
    return np.maximum(np.maximum(a[..., 0], a[..., 1]), a[..., 2])


def unitize(v: ArrayLike) -> tuple[np.ndarray, np.ndarray]:
    """Normalise rows of ``v``; rows too short to normalise give 0 and ``valid = False``.

    Parameters
    ----------
    v : (n, 3) float64

    Returns
    -------
    u : (n, 3) float64
        Unit rows, or zero rows where ``valid`` is False.
    valid : (n,) bool

    Examples
    --------
    >>> u, ok = unitize(np.array([[3.0, 0.0, 4.0], [0.0, 0.0, 0.0]]))
    >>> u.tolist(), ok.tolist()
    ([[0.6, 0.0, 0.8], [0.0, 0.0, 0.0]], [True, False])
    """
    v = np.asarray(v, dtype=np.float64)
    # scale first so the squared length neither overflows nor underflows
    scale = row_max(np.abs(v))
    valid = scale > TOL.unit_min
    w = v / np.where(valid, scale, 1.0)[..., None]
    length = np.sqrt(dot(w, w))[..., None]
    if np.all(valid):
        return w / length, valid
    return np.where(valid[..., None], w / np.where(valid[..., None], length, 1.0), 0.0), valid


def luminance(c: ArrayLike) -> np.ndarray:
    """MDL's ``math::luminance`` of linear RGB rows: 0.212671 r + 0.715160 g + 0.072169 b.

    Examples
    --------
    >>> round(float(luminance(np.array([1.0, 1.0, 1.0]))), 6)
    1.0
    """
    c = np.asarray(c, dtype=np.float64)
    return c @ np.array([0.212671, 0.715160, 0.072169])
