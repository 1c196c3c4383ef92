"""Helpers shared by the distribution functions: two-sided orientation, tangent axes, IORs."""

from __future__ import annotations

from enum import Enum

import numpy as np

from render._typing import Arr, Vec3
from render.frame import mirror_z
from render.numerics import TOL, norm

__all__ = ["orient", "tangent_axes", "ior_pair", "INV_PI", "ScatterMode", "lane_ior"]

INV_PI = 1.0 / np.pi


def orient(wo: Vec3, *others: Vec3) -> tuple:
    """Mirror lanes with ``wo.z < 0`` through the tangent plane (libbsdf's normal flip).

    Returns
    -------
    flip : (n,) bool
        Lanes that were mirrored (un-mirror sampled directions with the same mask).
    wo, *others : (n, 3) float64
        The oriented directions; afterwards ``wo.z >= 0`` on every lane.
    """
    flip = wo[:, 2] < 0.0
    if not np.any(flip):
        return (flip, wo, *others)
    return (flip, mirror_z(wo, flip), *(mirror_z(w, flip) for w in others))


def tangent_axes(tangent_u: np.ndarray, n: int) -> tuple[Arr, Arr, np.ndarray]:
    """The anisotropy axes in the local frame from ``tangent_u`` (libbsdf's convention).

    ``t_axis`` is ``tangent_u`` projected into the tangent plane and normalised, and
    ``b_axis = normalize(cross(tangent_u, n))``; with ``n = +z`` they are
    ``t = (tx, ty, 0)`` and ``b = (ty, -tx, 0)``.  ``roughness_u`` acts along ``t``.

    Parameters
    ----------
    tangent_u : (1, 3) or (n, 3) float64
    n : int
        Number of lanes.

    Returns
    -------
    tx, ty : (n,) float64
    valid : (n,) bool
        False where ``tangent_u`` is parallel to the normal (libbsdf: the lobe absorbs).
    """
    t = np.broadcast_to(tangent_u, (n, 3))
    tx, ty = t[:, 0], t[:, 1]
    length = np.hypot(tx, ty)
    full = norm(t)
    valid = length > 1e-8 * np.maximum(full, TOL.unit_min)
    safe = np.where(valid, length, 1.0)
    return np.where(valid, tx / safe, 1.0), np.where(valid, ty / safe, 0.0), valid


def ior_pair(
    ior_outside: np.ndarray,
    ior_inside: np.ndarray,
    flip: np.ndarray,
    thin_walled: bool,
    glossy: bool,
) -> tuple[Arr, Arr]:
    """``(eta1, eta2)``: the IOR on ``wo``'s side and on the far side, per lane.

    ``+z`` is the outside.  Lanes viewed from below (``flip``) swap the pair, except on
    thin-walled surfaces, where both sides see ``(ior_outside, ior_inside)`` (libbsdf is
    given ``ior1 = 1, ior2 = material.ior`` for every thin-walled hit).  For glossy
    refraction the pair is pushed apart to ``|eta2 - eta1| >= TOL.ior_delta_min``
    (libbsdf: at an exact match the transmitted lobe would be a delta); an exact match
    makes the inside the denser side.
    """
    n = len(flip)
    o = np.broadcast_to(ior_outside, (n,))
    i = np.broadcast_to(ior_inside, (n,))
    if glossy:
        # push the inside away from the outside (an exact match makes the inside denser),
        # before orienting, so both sides see the same interface
        d = i - o
        i = np.where(
            np.abs(d) < TOL.ior_delta_min,
            o + np.where(d < 0, -TOL.ior_delta_min, TOL.ior_delta_min),
            i,
        )
    swap = flip & (not thin_walled)
    return np.where(swap, i, o), np.where(swap, o, i)


class ScatterMode(str, Enum):
    """MDL's ``df::scatter_mode``."""

    scatter_reflect = "scatter_reflect"
    scatter_transmit = "scatter_transmit"
    scatter_reflect_transmit = "scatter_reflect_transmit"

    @classmethod
    def parse(cls, mode) -> ScatterMode:
        """A :class:`ScatterMode` from itself or its MDL name (with or without ``df::``).

        Examples
        --------
        >>> ScatterMode.parse("df::scatter_transmit").name
        'scatter_transmit'
        >>> ScatterMode.parse("reflect")
        Traceback (most recent call last):
        ...
        ValueError: mode must be one of scatter_reflect, scatter_transmit, ...
        """
        if isinstance(mode, cls):
            return mode
        name = str(mode).removeprefix("::").removeprefix("df::")
        try:
            return cls(name)
        except ValueError:
            raise ValueError(
                f"mode must be one of {', '.join(m.value for m in cls)}; got {mode!r}"
            ) from None


def lane_ior(x, name: str) -> np.ndarray:
    """An IOR: a positive float or ``(n,)`` array (average color IORs first, as libbsdf)."""
    from render.bsdf import lane_float

    a = lane_float(x, name)
    if np.any(a <= 0):
        raise ValueError(f"{name} must be > 0 (an index of refraction), got {x!r}")
    return a
