"""Warps from the unit square to disks, hemispheres, spheres and cones, with pdfs and inverses.

Named as in Mitsuba's ``warp``: ``square_to_<domain>(u)`` maps ``(n, 2)`` uniform
variates in [0, 1)^2 to points of the domain, ``square_to_<domain>_pdf(p)`` is the density
of the result (per unit area for disks, per steradian for directions; 0 outside the
domain) and ``<domain>_to_square(p)`` inverts the warp (a round trip returns ``u``).
"""

from __future__ import annotations

import numpy as np

from render._typing import Arr, Arr2, ArrayLike, Vec3
from render.numerics import safe_sqrt

__all__ = [
    "square_to_uniform_disk_concentric",
    "square_to_uniform_disk_concentric_pdf",
    "uniform_disk_concentric_to_square",
    "square_to_cosine_hemisphere",
    "square_to_cosine_hemisphere_pdf",
    "cosine_hemisphere_to_square",
    "square_to_uniform_hemisphere",
    "square_to_uniform_hemisphere_pdf",
    "uniform_hemisphere_to_square",
    "square_to_uniform_sphere",
    "square_to_uniform_sphere_pdf",
    "uniform_sphere_to_square",
    "square_to_uniform_cone",
    "square_to_uniform_cone_pdf",
    "uniform_cone_to_square",
]

_QUARTER_PI = np.pi / 4.0


def _as_u(u: ArrayLike) -> Arr2:
    u = np.asarray(u, dtype=np.float64)
    if u.ndim != 2 or u.shape[1] != 2:
        raise ValueError(f"u must have shape (n, 2) (two uniform variates per lane), got {u.shape}")
    return u


def _as_dirs(w: ArrayLike, name: str = "w") -> Vec3:
    w = np.asarray(w, dtype=np.float64)
    if w.ndim != 2 or w.shape[1] != 3:
        raise ValueError(f"{name} must have shape (n, 3), got {w.shape}")
    return w


def square_to_uniform_disk_concentric(u: ArrayLike) -> Arr2:
    """Shirley–Chiu concentric map of [0, 1)^2 onto the unit disk (area-preserving).

    Parameters
    ----------
    u : (n, 2) float64

    Returns
    -------
    (n, 2) float64

    Examples
    --------
    >>> square_to_uniform_disk_concentric(np.array([[0.5, 0.5], [1.0, 0.5]])).tolist()
    [[0.0, 0.0], [1.0, 0.0]]
    """
    u = _as_u(u)
    a = 2.0 * u[:, 0] - 1.0
    b = 2.0 * u[:, 1] - 1.0
    first = np.abs(a) > np.abs(b)
    r = np.where(first, a, b)
    safe_a = np.where(a != 0, a, 1.0)
    safe_b = np.where(b != 0, b, 1.0)
    phi = np.where(first, _QUARTER_PI * (b / safe_a), 2 * _QUARTER_PI - _QUARTER_PI * (a / safe_b))
    return np.stack([r * np.cos(phi), r * np.sin(phi)], axis=1)


def square_to_uniform_disk_concentric_pdf(p: ArrayLike) -> Arr:
    """``1/pi`` inside the unit disk, 0 outside."""
    p = np.asarray(p, dtype=np.float64)
    return np.where(p[:, 0] ** 2 + p[:, 1] ** 2 <= 1.0, 1.0 / np.pi, 0.0)


def uniform_disk_concentric_to_square(p: ArrayLike) -> Arr2:
    """Inverse of :func:`square_to_uniform_disk_concentric`.

    Examples
    --------
    >>> uniform_disk_concentric_to_square(np.array([[0.0, 0.0], [0.0, -1.0]])).tolist()
    [[0.5, 0.5], [0.5, 0.0]]
    """
    p = np.asarray(p, dtype=np.float64)
    x, y = p[:, 0], p[:, 1]
    r = np.hypot(x, y)
    first = np.abs(x) >= np.abs(y)
    # region |a| > |b|: p = a (cos phi, sin phi), phi = (pi/4) b/a in (-pi/4, pi/4]
    a1 = np.where(x >= 0, r, -r)
    phi1 = np.arctan2(y * np.sign(a1), np.abs(x))
    b1 = a1 * phi1 / _QUARTER_PI
    # region |b| >= |a|: p = b (cos phi, sin phi), phi = pi/2 - (pi/4) a/b
    b2 = np.where(y >= 0, r, -r)
    phi2 = np.arctan2(y * np.sign(b2), x * np.sign(b2))
    a2 = b2 * (2 * _QUARTER_PI - phi2) / _QUARTER_PI
    a = np.where(first, a1, a2)
    b = np.where(first, b1, b2)
    a = np.where(r > 0, a, 0.0)
    b = np.where(r > 0, b, 0.0)
    return np.stack([(a + 1.0) * 0.5, (b + 1.0) * 0.5], axis=1)


def square_to_cosine_hemisphere(u: ArrayLike) -> Vec3:
    """Cosine-weighted directions on the ``+z`` hemisphere (Malley's method).

    Examples
    --------
    >>> square_to_cosine_hemisphere(np.array([[0.5, 0.5]])).tolist()
    [[0.0, 0.0, 1.0]]
    """
    p = square_to_uniform_disk_concentric(u)
    z = safe_sqrt(1.0 - p[:, 0] ** 2 - p[:, 1] ** 2)
    return np.stack([p[:, 0], p[:, 1], z], axis=1)


def square_to_cosine_hemisphere_pdf(w: ArrayLike) -> Arr:
    """``max(cos theta, 0) / pi``.

    Examples
    --------
    >>> p = square_to_cosine_hemisphere_pdf(np.array([[0.0, 0.0, 1.0], [0.0, 0.0, -1.0]]))
    >>> p.tolist() == [1 / np.pi, 0.0]
    True
    """
    w = _as_dirs(w)
    return np.maximum(w[:, 2], 0.0) / np.pi


def cosine_hemisphere_to_square(w: ArrayLike) -> Arr2:
    """Inverse of :func:`square_to_cosine_hemisphere` (uses only ``x, y``)."""
    w = _as_dirs(w)
    return uniform_disk_concentric_to_square(w[:, :2])


def square_to_uniform_hemisphere(u: ArrayLike) -> Vec3:
    """Uniform directions on the ``+z`` hemisphere (``z = 1 - u0``).

    Examples
    --------
    >>> square_to_uniform_hemisphere(np.array([[0.0, 0.25]])).round(12).tolist()
    [[0.0, 0.0, 1.0]]
    """
    u = _as_u(u)
    z = 1.0 - u[:, 0]
    r = safe_sqrt(u[:, 0] * (2.0 - u[:, 0]))  # sqrt(1 - z^2) without cancellation
    phi = 2.0 * np.pi * u[:, 1]
    return np.stack([r * np.cos(phi), r * np.sin(phi), z], axis=1)


def square_to_uniform_hemisphere_pdf(w: ArrayLike) -> Arr:
    """``1 / (2 pi)`` for ``z >= 0``, else 0."""
    w = _as_dirs(w)
    return np.where(w[:, 2] >= 0.0, 0.5 / np.pi, 0.0)


def uniform_hemisphere_to_square(w: ArrayLike) -> Arr2:
    """Inverse of :func:`square_to_uniform_hemisphere`."""
    w = _as_dirs(w)
    return np.stack([1.0 - w[:, 2], _phi01(w)], axis=1)


def square_to_uniform_sphere(u: ArrayLike) -> Vec3:
    """Uniform directions on the unit sphere (``z = 1 - 2 u0``).

    Examples
    --------
    >>> square_to_uniform_sphere(np.array([[0.5, 0.0]])).tolist()
    [[1.0, 0.0, 0.0]]
    """
    u = _as_u(u)
    z = 1.0 - 2.0 * u[:, 0]
    r = 2.0 * safe_sqrt(u[:, 0] * (1.0 - u[:, 0]))  # sqrt(1 - z^2)
    phi = 2.0 * np.pi * u[:, 1]
    return np.stack([r * np.cos(phi), r * np.sin(phi), z], axis=1)


def square_to_uniform_sphere_pdf(w: ArrayLike) -> Arr:
    """``1 / (4 pi)`` everywhere."""
    w = _as_dirs(w)
    return np.full(len(w), 0.25 / np.pi)


def uniform_sphere_to_square(w: ArrayLike) -> Arr2:
    """Inverse of :func:`square_to_uniform_sphere`."""
    w = _as_dirs(w)
    return np.stack([(1.0 - w[:, 2]) * 0.5, _phi01(w)], axis=1)


def square_to_uniform_cone(u: ArrayLike, cos_cutoff: ArrayLike) -> Vec3:
    """Uniform directions in the cone ``z >= cos_cutoff`` around ``+z``.

    Parameters
    ----------
    u : (n, 2) float64
    cos_cutoff : float or (n,) float64
        Cosine of the half angle, in [-1, 1] (-1 is the whole sphere).

    Examples
    --------
    >>> square_to_uniform_cone(np.array([[0.0, 0.0]]), 0.5).tolist()
    [[0.0, 0.0, 1.0]]
    """
    u = _as_u(u)
    c = np.asarray(cos_cutoff, dtype=np.float64)
    one_minus_c = 1.0 - c
    z = 1.0 - u[:, 0] * one_minus_c
    # 1 - z^2 = (1 - z)(1 + z)
    r = safe_sqrt(u[:, 0] * one_minus_c * (1.0 + z))
    phi = 2.0 * np.pi * u[:, 1]
    return np.stack([r * np.cos(phi), r * np.sin(phi), z], axis=1)


def square_to_uniform_cone_pdf(w: ArrayLike, cos_cutoff: ArrayLike) -> Arr:
    """``1 / (2 pi (1 - cos_cutoff))`` inside the cone, else 0 (0 for a degenerate cone)."""
    w = _as_dirs(w)
    c = np.asarray(cos_cutoff, dtype=np.float64)
    solid = 2.0 * np.pi * (1.0 - c)
    inside = (w[:, 2] >= c) & (solid > 0)
    return np.where(inside, 1.0 / np.where(solid > 0, solid, 1.0), 0.0)


def uniform_cone_to_square(w: ArrayLike, cos_cutoff: ArrayLike) -> Arr2:
    """Inverse of :func:`square_to_uniform_cone` (``u0 = 0`` for a degenerate cone)."""
    w = _as_dirs(w)
    c = np.asarray(cos_cutoff, dtype=np.float64)
    one_minus_c = np.broadcast_to(1.0 - c, (len(w),))
    u0 = np.where(
        one_minus_c > 0, (1.0 - w[:, 2]) / np.where(one_minus_c > 0, one_minus_c, 1.0), 0.0
    )
    return np.stack([u0, _phi01(w)], axis=1)


def _phi01(w: Vec3) -> Arr:
    """Azimuth of ``w`` mapped to [0, 1)."""
    phi = np.arctan2(w[:, 1], w[:, 0])
    v = np.where(phi < 0, phi + 2.0 * np.pi, phi) / (2.0 * np.pi)
    return np.where(v >= 1.0, 0.0, v)
