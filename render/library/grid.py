"""The grid pattern of Handbook section 14.1.2: grid lines in texture space (Listings 14.3-14.5).

:func:`near_grid_value` is the one-dimensional test, :func:`in_grid_line` combines u and
v, and :func:`grid_color` picks the line or background colour; material ``grid``
(Listing 14.6, :mod:`render.materials.chapter14`) uses it as its diffuse tint.
"""

from __future__ import annotations

import numpy as np

from displacement.state import ShadingState
from render.library.space import u, v
from render.material import evaluate

__all__ = ["near_grid_value", "in_grid_line", "grid_color"]


def near_grid_value(f, cell_count, thickness, edge=1.0) -> np.ndarray:
    """Listing 14.3: is ``f`` within ``thickness * edge`` of a multiple of ``1 / cell_count``?

    ``thick = 0.05 / cell_count`` when ``thickness == 0`` (the default line width),
    else ``thickness``; ``thick *= edge``; ``nearest = floor((f + thick) cell_count) /
    cell_count``; the result is ``nearest - thick <= f <= nearest + thick``.

    Parameters
    ----------
    f : (n,) float64
    cell_count, thickness, edge : float or (n,) float64, broadcastable

    Returns
    -------
    (n,) bool

    Raises
    ------
    ValueError
        If ``cell_count`` is 0 anywhere (there are no cells; the Handbook divides by it).

    Examples
    --------
    >>> near_grid_value(np.array([0.0, 0.01, 0.1, 0.24, 0.26, 1.0]), 4.0, 0.0).tolist()
    [True, True, False, True, True, True]
    """
    f = np.asarray(f, dtype=np.float64)
    cell_count = np.asarray(cell_count, dtype=np.float64)
    thickness = np.asarray(thickness, dtype=np.float64)
    if np.any(cell_count == 0.0):
        raise ValueError("grid cell_count must not be 0 (there would be no cells); use e.g. 4.0")
    thick = np.where(thickness == 0.0, 0.05 / cell_count, thickness)
    thick = thick * np.asarray(edge, dtype=np.float64)
    nearest_value = np.floor((f + thick) * cell_count) / cell_count
    return (f >= nearest_value - thick) & (f <= nearest_value + thick)


def in_grid_line(state: ShadingState, cell_count=(4.0, 4.0), thickness=(0.0, 0.0),
                 texture_space: int = 0, edge=1.0) -> np.ndarray:
    """Listing 14.4: near a grid value in u or in v.

    Parameters
    ----------
    state : ShadingState
    cell_count, thickness : float2 or callable(state) -> (n, 2)
    texture_space : int
        0 (the only texture space of the state; others read as uv = 0, MDL's rule).
    edge : float

    Returns
    -------
    (n,) bool
    """
    count = evaluate(cell_count, state, "float2", "cell_count")
    thick = evaluate(thickness, state, "float2", "thickness")
    return (near_grid_value(u(state, texture_space), count[:, 0], thick[:, 0], edge)
            | near_grid_value(v(state, texture_space), count[:, 1], thick[:, 1], edge))


def grid_color(state: ShadingState, cell_count=(4.0, 4.0), line_color=0.0, bg_color=1.0,
               thickness=(0.0, 0.0), texture_space: int = 0) -> np.ndarray:
    """Listing 14.5: ``line_color`` on the grid lines, ``bg_color`` elsewhere.

    Parameters
    ----------
    state : ShadingState
    cell_count : float2 or callable
        Cells per unit of u and v (default ``float2(4.0, 4.0)``).
    line_color, bg_color : color or callable(state) -> (n, 3)
        Defaults ``color(0.0)`` and ``color(1.0)``.
    thickness : float2 or callable
        Half-width of the lines in texture units; 0 means ``0.05 / cell_count``.
    texture_space : int

    Returns
    -------
    (n, 3) float64

    Examples
    --------
    >>> from displacement.surfaces import UnitSquare
    >>> s = UnitSquare().state_at_uv(np.array([[0.25, 0.6], [0.6, 0.6], [0.6, 1.0]]))
    >>> grid_color(s, (4.0, 4.0), 0.0, 0.7)[:, 0].tolist()
    [0.0, 0.7, 0.0]
    """
    line = in_grid_line(state, cell_count, thickness, texture_space)
    return np.where(line[:, None], evaluate(line_color, state, "color", "line_color"),
                    evaluate(bg_color, state, "color", "bg_color"))
