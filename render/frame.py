"""The local shading frame, world <-> local transforms and spherical-coordinate helpers.

Direction conventions (stated once, here; every df in :mod:`render.df` follows them)
-------------------------------------------------------------------------------------
* All distribution functions work in the **local shading frame**: ``+z`` is the shading
  normal (``state::normal()`` or a layer's ``normal``), ``x`` and ``y`` span the tangent
  plane, with ``x`` along ``state::texture_tangent_u(0)`` when the frame is built by
  :meth:`Frame.from_normal_tangent`.  A direction in world space carries a suffix
  (``wi_world``), as in pbrt.
* ``wo`` points **toward the viewer** (the previous path vertex, MDL/libbsdf's ``k1``);
  ``wi`` points **toward the light** (the next vertex, ``k2``).  Both point away from the
  surface and are unit vectors, stored as ``(n, 3)`` float64 rows, one row per lane.
* ``cos theta = w.z``.  ``wi.z * wo.z > 0`` is reflection, ``< 0`` transmission.
* BSDFs are two-sided, as in libbsdf (which flips the normal toward ``k1`` before any
  lobe is evaluated): a lane with ``wo.z < 0`` is evaluated as the mirror image through
  the tangent plane.  The ``+z`` side is the "outside" of an interface: IORs are passed
  as ``ior_outside`` (``+z`` side) and ``ior_inside`` (``-z`` side).
* ``eval(wo, wi)`` returns ``f(wo, wi) * |cos theta_i|`` (Mitsuba's convention), ``pdf``
  is a solid-angle density over ``wi``, and ``sample`` returns ``wi``, ``pdf`` and
  ``weight = eval / pdf``; a zero weight (lobe flag 0) means the sample failed.
* A direction with ``|cos theta| <= TOL.cos_zero`` lies in the tangent plane: nothing
  scatters from or into it (eval, pdf and weight are 0 there).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from render._typing import Arr, ArrayLike, Vec3
from render.numerics import TOL, dot, safe_div, safe_sqrt

__all__ = [
    "Frame",
    "cos_theta",
    "cos2_theta",
    "sin_theta",
    "sin2_theta",
    "tan_theta",
    "cos_phi",
    "sin_phi",
    "same_hemisphere",
    "mirror_z",
]


@dataclass(frozen=True, slots=True)
class Frame:
    """An orthonormal frame per lane: tangent ``s``, bitangent ``t``, normal ``n``.

    Parameters
    ----------
    s, t, n : (n, 3) float64
        Unit, mutually orthogonal, right-handed (``s x t = n``).
    """

    s: Vec3
    t: Vec3
    n: Vec3

    @classmethod
    def from_normal(cls, n: ArrayLike) -> Frame:
        """A frame around unit normals ``n``, branch-free (Duff et al. 2017).

        Parameters
        ----------
        n : (n, 3) float64
            Unit normals.

        Examples
        --------
        >>> f = Frame.from_normal(np.array([[0.0, 0.0, 1.0], [0.0, 0.0, -1.0]]))
        >>> np.allclose(f.to_local(f.n), [[0, 0, 1], [0, 0, 1]])
        True
        """
        n = np.asarray(n, dtype=np.float64)
        sign = np.where(n[:, 2] >= 0.0, 1.0, -1.0)
        a = -1.0 / (sign + n[:, 2])
        b = n[:, 0] * n[:, 1] * a
        s = np.stack([1.0 + sign * n[:, 0] ** 2 * a, sign * b, -sign * n[:, 0]], axis=1)
        t = np.stack([b, sign + n[:, 1] ** 2 * a, -n[:, 1]], axis=1)
        return cls(s, t, n)

    @classmethod
    def from_normal_tangent(cls, n: ArrayLike, tangent_u: ArrayLike) -> Frame:
        """A frame with ``s`` along ``tangent_u`` projected into the tangent plane.

        Where ``tangent_u`` is (nearly) parallel to ``n`` or zero, the frame falls back to
        :meth:`from_normal`.

        Parameters
        ----------
        n : (n, 3) float64
            Unit normals.
        tangent_u : (n, 3) float64
            Tangent directions (need not be unit or orthogonal to ``n``).

        Examples
        --------
        >>> f = Frame.from_normal_tangent(np.array([[0.0, 0.0, 1.0]] * 2),
        ...                               np.array([[1.0, 0.0, 0.5], [0.0, 0.0, 1.0]]))
        >>> f.s[0].tolist(), bool(np.allclose(np.cross(f.s, f.t), f.n))
        ([1.0, 0.0, 0.0], True)
        """
        from render.df._kernel_common import frames_from_normal_tangent

        n = np.ascontiguousarray(n, dtype=np.float64)
        tu = np.ascontiguousarray(np.broadcast_to(np.asarray(tangent_u, dtype=np.float64),
                                                  n.shape))
        s, t = np.empty(n.shape), np.empty(n.shape)
        frames_from_normal_tangent(n, tu, s, t)  # one compiled pass
        return cls(s, t, n)

    def to_local(self, v: ArrayLike) -> Vec3:
        """World rows ``v`` (n, 3) expressed in this frame."""
        v = np.asarray(v, dtype=np.float64)
        return np.stack([dot(v, self.s), dot(v, self.t), dot(v, self.n)], axis=-1)

    def to_world(self, v: ArrayLike) -> Vec3:
        """Local rows ``v`` (n, 3) expressed in world space."""
        v = np.asarray(v, dtype=np.float64)
        return v[:, 0:1] * self.s + v[:, 1:2] * self.t + v[:, 2:3] * self.n


def cos_theta(w: Vec3) -> Arr:
    """``w.z``: cosine between local direction ``w`` and the shading normal."""
    return w[..., 2]


def cos2_theta(w: Vec3) -> Arr:
    """``w.z ** 2``."""
    return w[..., 2] ** 2


def sin2_theta(w: Vec3) -> Arr:
    """``x^2 + y^2`` of a unit direction (exact near the pole, unlike ``1 - z^2``)."""
    return w[..., 0] ** 2 + w[..., 1] ** 2


def sin_theta(w: Vec3) -> Arr:
    """``sqrt(x^2 + y^2)``."""
    return safe_sqrt(sin2_theta(w))


def tan_theta(w: Vec3) -> Arr:
    """``sin theta / cos theta``; 0 where ``|cos theta| <= TOL.cos_zero`` (defined, not inf).

    Examples
    --------
    >>> np.round(tan_theta(np.array([[0.6, 0.0, 0.8], [1.0, 0.0, 0.0]])), 12).tolist()
    [0.75, 0.0]
    """
    c = w[..., 2]
    return safe_div(sin_theta(w), np.where(np.abs(c) > TOL.cos_zero, c, 0.0))


def cos_phi(w: Vec3) -> Arr:
    """``x / sin theta``; 1 at the poles.

    Examples
    --------
    >>> cos_phi(np.array([[0.0, 0.6, 0.8], [0.0, 0.0, 1.0]])).tolist()
    [0.0, 1.0]
    """
    st = sin_theta(w)
    return np.where(st > 0, w[..., 0] / np.where(st > 0, st, 1.0), 1.0)


def sin_phi(w: Vec3) -> Arr:
    """``y / sin theta``; 0 at the poles."""
    st = sin_theta(w)
    return np.where(st > 0, w[..., 1] / np.where(st > 0, st, 1.0), 0.0)


def same_hemisphere(a: Vec3, b: Vec3) -> np.ndarray:
    """``a.z * b.z > 0`` (both strictly on the same side of the tangent plane)."""
    return a[..., 2] * b[..., 2] > 0


def mirror_z(w: Vec3, mask: np.ndarray | None = None) -> Vec3:
    """``w`` mirrored through the tangent plane (``z -> -z``), on lanes ``mask`` only.

    Examples
    --------
    >>> mirror_z(np.array([[1.0, 2.0, 3.0], [1.0, 2.0, 3.0]]), np.array([True, False])).tolist()
    [[1.0, 2.0, -3.0], [1.0, 2.0, 3.0]]
    """
    if mask is None:
        return w * np.array([1.0, 1.0, -1.0])
    return np.where(mask[..., None], w * np.array([1.0, 1.0, -1.0]), w)
