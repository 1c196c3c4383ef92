"""Coordinate spaces of the Handbook's section 9.4: texture, object and world positions.

``state::texture_coordinate(i)``, ``u()``/``v()`` (Listings 14.1-14.2), the
``mapping_mode`` enum (Listing 9.15), ``position(mode)`` (9.16) and
``position_to_color`` (9.18), vectorized over the lanes of a
:class:`~displacement.state.ShadingState`.

World space.  A :class:`ShadingState` is in object space (MDL's internal space here).
Its ``object_to_world``, a (4, 4) or (3, 3) matrix or an (n, 4, 4)/(n, 3, 3) stack
acting on column vectors (``M @ p``), takes positions and normals to world space; the
integrator sets it to each object's transform.  Without one (a surface outside a scene),
world space is object space.
"""

from __future__ import annotations

import numpy as np

from displacement.fields import frac
from displacement.state import ShadingState
from render.material import evaluate

__all__ = [
    "MAPPING_MODES",
    "texture_coordinate",
    "u",
    "v",
    "uvw_position",
    "object_position",
    "world_position",
    "position",
    "position_to_color",
    "world_normal",
]

#: Listing 9.15's ``mapping_mode`` enumerators.
MAPPING_MODES = ("uvw", "object", "world")


def texture_coordinate(state: ShadingState, index: int = 0) -> np.ndarray:
    """``state::texture_coordinate(index)``: (u, v, 0) for index 0.

    The state holds one texture space; as MDL specifies for an index out of range,
    any other index gives the zero vector.

    Parameters
    ----------
    state : ShadingState
    index : int

    Returns
    -------
    (n, 3) float64

    Examples
    --------
    >>> from displacement.surfaces import UnitSquare
    >>> s = UnitSquare().state_at_uv(np.array([[0.25, 0.75]]))
    >>> texture_coordinate(s).tolist(), texture_coordinate(s, 1).tolist()
    ([[0.25, 0.75, 0.0]], [[0.0, 0.0, 0.0]])
    """
    n = len(state)
    out = np.zeros((n, 3))
    if int(index) == 0:
        out[:, :2] = state.uv
    return out


def u(state: ShadingState, texture_space: int = 0) -> np.ndarray:
    """Listing 14.1: ``state::texture_coordinate(texture_space).x``, shape (n,)."""
    return texture_coordinate(state, texture_space)[:, 0]


def v(state: ShadingState, texture_space: int = 0) -> np.ndarray:
    """Listing 14.2: ``state::texture_coordinate(texture_space).y``, shape (n,)."""
    return texture_coordinate(state, texture_space)[:, 1]


def uvw_position(state: ShadingState) -> np.ndarray:
    """Listing 9.14: ``state::texture_coordinate(0)``, shape (n, 3)."""
    return texture_coordinate(state, 0)


def object_position(state: ShadingState) -> np.ndarray:
    """Listing 9.12: the position in object space, shape (n, 3)."""
    return np.asarray(state.position, dtype=np.float64)


def _object_to_world(state: ShadingState) -> np.ndarray | None:
    m = getattr(state, "object_to_world", None)
    if m is None:
        return None
    m = np.asarray(m, dtype=np.float64)
    if m.shape[-2:] not in ((4, 4), (3, 3)) or m.ndim not in (2, 3):
        raise ValueError(
            f"state.object_to_world must be (4, 4), (3, 3) or a stack of them, got {m.shape}")
    return m


def world_position(state: ShadingState) -> np.ndarray:
    """Listing 9.13: the position in world space (object space without ``object_to_world``).

    Examples
    --------
    >>> from displacement.surfaces import UnitSquare
    >>> world_position(UnitSquare().state_at_uv(np.array([[0.5, 0.5]]))).tolist()
    [[0.5, 0.5, 0.0]]
    """
    p = object_position(state)
    m = _object_to_world(state)
    if m is None:
        return p.copy()
    linear = m[..., :3, :3]
    out = p @ linear.T if linear.ndim == 2 else np.einsum("nij,nj->ni", linear, p)
    if m.shape[-1] == 4:
        out = out + m[..., :3, 3]
    return out


def world_normal(state: ShadingState, normal: np.ndarray) -> np.ndarray:
    """``state::transform_normal(internal, world, normal)``: by the inverse transpose.

    Parameters
    ----------
    state : ShadingState
    normal : (n, 3) float64

    Returns
    -------
    (n, 3) float64 (not renormalized, as MDL)
    """
    normal = np.asarray(normal, dtype=np.float64)
    m = _object_to_world(state)
    if m is None:
        return normal.copy()
    linear = m[..., :3, :3]
    det = np.linalg.det(linear)
    if np.any(np.abs(det) < 1e-300):
        raise ValueError("state.object_to_world is singular; normals cannot be transformed")
    inverse = np.linalg.inv(linear)
    # (M^-T n) per row: n^T M^-1
    if inverse.ndim == 2:
        return normal @ inverse
    return np.einsum("ni,nij->nj", normal, inverse)


def position(state: ShadingState, mode: str = "uvw") -> np.ndarray:
    """Listing 9.16: the position in texture (``uvw``), ``object`` or ``world`` space.

    Parameters
    ----------
    state : ShadingState
    mode : {"uvw", "object", "world"}

    Returns
    -------
    (n, 3) float64

    Examples
    --------
    >>> from displacement.surfaces import UnitSquare
    >>> s = UnitSquare().state_at_uv(np.array([[0.25, 0.75]]))
    >>> position(s, "uvw").tolist(), position(s, "object").tolist()
    ([[0.25, 0.75, 0.0]], [[0.25, 0.75, 0.0]])
    >>> position(s, "texture")
    Traceback (most recent call last):
    ...
    ValueError: mapping mode must be one of uvw, object, world; got 'texture'
    """
    mode = str(mode).split("::")[-1]
    if mode == "uvw":
        return uvw_position(state)
    if mode == "object":
        return object_position(state).copy()
    if mode == "world":
        return world_position(state)
    raise ValueError(f"mapping mode must be one of {', '.join(MAPPING_MODES)}; got {mode!r}")


def position_to_color(state: ShadingState, mode: str = "uvw", scale=1.0) -> np.ndarray:
    """Listing 9.18: ``color(frac(scale * position(mode)))``.

    Parameters
    ----------
    state : ShadingState
    mode : {"uvw", "object", "world"}
    scale : float or callable(state) -> (n,)

    Returns
    -------
    (n, 3) float64 in [0, 1]

    Examples
    --------
    >>> from displacement.surfaces import UnitSquare
    >>> s = UnitSquare().state_at_uv(np.array([[0.25, -0.75]]))
    >>> position_to_color(s, "uvw", 2.0).tolist()
    [[0.5, 0.5, 0.0]]
    """
    k = evaluate(scale, state, "float", "scale")
    return frac(k[:, None] * position(state, mode))
