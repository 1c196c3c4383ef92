"""Safe maths over lane arrays: guarded sqrt/acos, unitize, dielectric Fresnel, refraction.

Every function here maps arrays to arrays without producing NaN or raising floating-point
errors for any finite input (the tests run under ``np.errstate(all="raise")``): special
cases are selected with masks and ``np.where``, and divisions only ever see safe
denominators.  The one set of tolerances the renderer uses lives in :data:`TOL`.
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
    "safe_acos",
    "safe_asin",
    "safe_div",
    "saturate",
    "dot",
    "norm",
    "cross",
    "row_max",
    "unitize",
    "luminance",
    "reflect",
    "refract",
    "fresnel_dielectric",
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


def safe_acos(x: ArrayLike) -> np.ndarray:
    """``acos`` of ``x`` clamped to [-1, 1] (dot products of unit vectors may exceed 1).

    Examples
    --------
    >>> safe_acos(np.array([1.0 + 1e-15, -2.0])).tolist() == [0.0, np.pi]
    True
    """
    return np.arccos(np.clip(x, -1.0, 1.0))


def safe_asin(x: ArrayLike) -> np.ndarray:
    """``asin`` of ``x`` clamped to [-1, 1].

    Examples
    --------
    >>> float(safe_asin(np.array(1.5)))  == np.pi / 2
    True
    """
    return np.arcsin(np.clip(x, -1.0, 1.0))


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


def saturate(x: ArrayLike) -> np.ndarray:
    """MDL's ``math::saturate``: clamp to [0, 1].

    Examples
    --------
    >>> saturate(np.array([-0.5, 0.25, 7.0])).tolist()
    [0.0, 0.25, 1.0]
    """
    return np.clip(np.asarray(x, dtype=np.float64), 0.0, 1.0)


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


def norm(v: Vec3) -> Arr:
    """Row-wise Euclidean length of (n, 3) rows -> (n,) (``np.linalg.norm(v, axis=-1)``,
    same bits, without the generic reduction).

    Examples
    --------
    >>> norm(np.array([[3.0, 0.0, 4.0], [0.0, 0.0, 0.0]])).tolist()
    [5.0, 0.0]
    """
    v = np.asarray(v)
    x, y, z = v[..., 0], v[..., 1], v[..., 2]
    return np.sqrt(x * x + y * y + z * z)


def cross(a: Vec3, b: Vec3) -> Vec3:
    """Row-wise cross product of (n, 3) arrays (``np.cross``, same bits, faster).

    Examples
    --------
    >>> cross(np.array([[1.0, 0.0, 0.0]]), np.array([[0.0, 1.0, 0.0]])).tolist()
    [[0.0, 0.0, 1.0]]
    """
    a = np.asarray(a)
    b = np.asarray(b)
    ax, ay, az = a[..., 0], a[..., 1], a[..., 2]
    bx, by, bz = b[..., 0], b[..., 1], b[..., 2]
    return np.stack([ay * bz - az * by, az * bx - ax * bz, ax * by - ay * bx], axis=-1)


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


def reflect(k: Vec3, m: Vec3) -> Vec3:
    """Mirror ``k`` about the unit normal ``m``: ``2 (k.m) m - k`` (both point away).

    Examples
    --------
    >>> reflect(np.array([[1.0, 0.0, 1.0]]), np.array([[0.0, 0.0, 1.0]])).tolist()
    [[-1.0, 0.0, 1.0]]
    """
    return 2.0 * dot(k, m)[..., None] * m - k


def refract(k: Vec3, m: Vec3, b: ArrayLike) -> tuple[Vec3, np.ndarray]:
    """Refract ``k`` through the interface with unit normal ``m`` on ``k``'s side.

    Parameters
    ----------
    k : (n, 3) float64
        Unit direction pointing away from the surface, ``k . m >= 0``.
    m : (n, 3) float64
        Unit (micro)normal on ``k``'s side.
    b : float or (n,) float64
        ``ior on k's side / ior on the far side``.

    Returns
    -------
    k2 : (n, 3) float64
        The refracted direction (pointing away on the far side); under total internal
        reflection the mirror direction ``2 c m - k`` instead.
    tir : (n,) bool
        Total internal reflection.

    Examples
    --------
    >>> k2, tir = refract(np.array([[0.0, 0.0, 1.0]]), np.array([[0.0, 0.0, 1.0]]), 1 / 1.5)
    >>> (k2 + 0.0).tolist(), tir.tolist()
    ([[0.0, 0.0, -1.0]], [False])
    >>> k = np.array([[np.sin(1.2), 0.0, np.cos(1.2)]])
    >>> refract(k, np.array([[0.0, 0.0, 1.0]]), 1.5)[1].tolist()
    [True]
    """
    b = np.asarray(b, dtype=np.float64)
    c = dot(k, m)
    s2 = b * b * np.maximum(1.0 - c * c, 0.0)
    tir = s2 > 1.0
    ct = safe_sqrt(1.0 - s2)
    k2 = -b[..., None] * k + (b * c - ct)[..., None] * m
    mirror = 2.0 * c[..., None] * m - k
    return np.where(tir[..., None], mirror, k2), tir


def fresnel_dielectric(cos_theta_i: ArrayLike, eta: ArrayLike) -> tuple[np.ndarray, np.ndarray]:
    """Unpolarised dielectric Fresnel reflectance and the transmitted cosine.

    libbsdf's ``ior_fresnel`` with the special cases made explicit.

    Parameters
    ----------
    cos_theta_i : (n,) float64
        Cosine between the incident direction and the normal; negative means the light
        arrives from the lower (``-z``) side.
    eta : float or (n,) float64
        Relative IOR ``ior(-z side) / ior(+z side)`` (inside over outside).  It is
        inverted for lanes with ``cos_theta_i < 0``.

    Returns
    -------
    F : (n,) float64
        Reflectance in [0, 1].  Index-matched (``eta == 1``): exactly 0, even at grazing
        incidence (where any ``eta != 1`` gives 1).  Total internal reflection: 1.
    cos_theta_t : (n,) float64
        Cosine of the transmitted direction, with the sign opposite to ``cos_theta_i``
        (0 under total internal reflection).

    Examples
    --------
    >>> F, ct = fresnel_dielectric(np.array([1.0, 0.3, -0.3, 1.0]), np.array([1.5, 1.5, 1.5, 1.0]))
    >>> np.round(F, 4).tolist()
    [0.04, 0.2078, 1.0, 0.0]
    >>> np.round(ct, 4).tolist()
    [-1.0, -0.7717, 0.0, -1.0]
    """
    ci = np.asarray(cos_theta_i, dtype=np.float64)
    eta = np.broadcast_to(np.asarray(eta, dtype=np.float64), ci.shape)
    outside = ci >= 0.0
    # e = ior(transmitted side) / ior(incident side)
    e = np.where(outside, eta, 1.0 / eta)
    c = np.minimum(np.abs(ci), 1.0)
    ct2 = 1.0 - (1.0 - c * c) / (e * e)
    tir = ct2 <= 0.0
    ct = safe_sqrt(ct2)
    den_s = c + e * ct
    den_p = e * c + ct
    ok = (den_s > 0) & (den_p > 0)
    rs = (c - e * ct) / np.where(ok, den_s, 1.0)
    rp = (e * c - ct) / np.where(ok, den_p, 1.0)
    F = np.where(ok, 0.5 * (rs * rs + rp * rp), 1.0)
    matched = e == 1.0
    F = np.where(tir & ~matched, 1.0, F)
    F = np.where(matched, 0.0, F)
    ct = np.where(matched, c, np.where(tir, 0.0, ct))
    return np.clip(F, 0.0, 1.0), np.where(outside, -ct, ct)
