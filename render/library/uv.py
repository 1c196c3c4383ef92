"""Texture-space tiles as colours (Handbook sections 13.2-13.3, Listings 13.2-13.3).

:func:`fractional_uv` (Listing 13.1) is :func:`displacement.bump.fractional_uv`; the
colours here show it: ``color(uv.x, uv.y, 0)`` over the tiles, and the same inside the
circle of radius 0.5 centred in each tile.
"""

from __future__ import annotations

import numpy as np

from displacement.bump import fractional_uv
from displacement.state import ShadingState
from render.material import evaluate

__all__ = ["fractional_uv", "scaled_uv_color", "scaled_uv_circle_color"]


def scaled_uv_color(state: ShadingState, u_scale=1.0, v_scale=1.0) -> np.ndarray:
    """Listing 13.2's tint: ``color(uv[0], uv[1], 0.0)`` with ``uv = fractional_uv(...)``.

    Returns
    -------
    (n, 3) float64

    Examples
    --------
    >>> from displacement.surfaces import UnitSquare
    >>> s = UnitSquare().state_at_uv(np.array([[0.3, 0.55]]))
    >>> scaled_uv_color(s, 2.0, 4.0).round(12).tolist()
    [[0.6, 0.2, 0.0]]
    """
    uv = fractional_uv(state, u_scale, v_scale)
    return np.concatenate([uv, np.zeros((len(uv), 1))], axis=1)


def scaled_uv_circle_color(state: ShadingState, u_scale=1.0, v_scale=1.0,
                           outside_color=0.7) -> np.ndarray:
    """Listing 13.3: the tile's uv colour inside the circle, ``outside_color`` outside.

    Inside means ``distance(uv, (0.5, 0.5)) < 0.5`` (strictly, as printed; Listing
    13.5's bump uses ``<=``).

    Parameters
    ----------
    state : ShadingState
    u_scale, v_scale : float or callable(state) -> (n,)
    outside_color : color or callable(state) -> (n, 3)

    Returns
    -------
    (n, 3) float64

    Examples
    --------
    >>> from displacement.surfaces import UnitSquare
    >>> s = UnitSquare().state_at_uv(np.array([[0.5, 0.5], [0.0, 0.0], [1.75, 0.5]]))
    >>> scaled_uv_circle_color(s, 1.0, 1.0, 0.7).tolist()
    [[0.5, 0.5, 0.0], [0.7, 0.7, 0.7], [0.75, 0.5, 0.0]]
    """
    uv = fractional_uv(state, u_scale, v_scale)
    inside = np.hypot(uv[:, 0] - 0.5, uv[:, 1] - 0.5) < 0.5
    inner = np.concatenate([uv, np.zeros((len(uv), 1))], axis=1)
    outside = evaluate(outside_color, state, "color", "outside_color")
    return np.where(inside[:, None], inner, outside)
