"""The vectorized shading state that displacement fields and bump functions read.

MDL evaluates a material's geometry field once per point with access to ``state::``
functions.  Here one :class:`ShadingState` holds many points as a struct of arrays, one
row per point, and every field is a function ``state -> (n, 3)``.
"""

from __future__ import annotations

from dataclasses import dataclass, replace

import numpy as np

__all__ = ["ShadingState"]


@dataclass(frozen=True, slots=True)
class ShadingState:
    """Per-point shading state, as MDL's ``state::`` functions return it.

    Parameters
    ----------
    position : (n, 3) float64
        ``state::position()``: object-space position of the (undisplaced) base surface.
    normal : (n, 3) float64
        ``state::normal()``: unit surface normal.
    uv : (n, 2) float64
        ``state::texture_coordinate(0).xy``.
    tangent_u, tangent_v : (n, 3) float64
        ``state::texture_tangent_u(0)`` / ``texture_tangent_v(0)``: unit vectors along
        the directions of increasing u and v.
    object_to_world : (4, 4) float64 or None
        The object's transform (column vectors, ``M @ p``), the same for every lane, for
        ``state::transform_point(..., coordinate_world, ...)`` and its kin; None (a
        surface outside a scene): world space is object space.
    geometry_normal : (n, 3) float64 or None
        ``state::geometry_normal()``: the unit normal of the triangle (flat), when the
        caller knows it; None: MDL code reading it gets ``normal`` (identical on flat
        shaded surfaces).
    direction : (n, 3) float64 or None
        ``state::direction()``: the direction of the ray, toward the surface, when the
        caller knows it (None: zero vectors).
    object_id : int
        ``state::object_id()`` (uniform).
    """

    position: np.ndarray
    normal: np.ndarray
    uv: np.ndarray
    tangent_u: np.ndarray
    tangent_v: np.ndarray
    object_to_world: np.ndarray | None = None
    geometry_normal: np.ndarray | None = None
    direction: np.ndarray | None = None
    object_id: int = 0

    def __post_init__(self) -> None:
        n = len(self.uv)
        for name in ("position", "normal", "tangent_u", "tangent_v"):
            a = getattr(self, name)
            if a.shape != (n, 3):
                raise ValueError(f"ShadingState.{name} has shape {a.shape}, expected ({n}, 3)")
        if self.uv.shape != (n, 2):
            raise ValueError(f"ShadingState.uv has shape {self.uv.shape}, expected ({n}, 2)")

    def __len__(self) -> int:
        return len(self.uv)

    def with_normal(self, normal: np.ndarray) -> ShadingState:
        """The same state with ``state::normal()`` replaced (after displacement or bump)."""
        return replace(self, normal=normal)

    def subset(self, index) -> ShadingState:
        """Rows ``index`` of every array (a mask or integer indices)."""
        return ShadingState(
            self.position[index], self.normal[index], self.uv[index],
            self.tangent_u[index], self.tangent_v[index], self.object_to_world,
            None if self.geometry_normal is None else self.geometry_normal[index],
            None if self.direction is None else self.direction[index], self.object_id,
        )
