"""Chapter 9's state functions as colours: stripes, checkerboards, uv and height tests.

The user-defined functions of the Handbook's chapter 9 (Listings 9.1-9.5, 9.20-9.26),
vectorized over the lanes of a :class:`~displacement.state.ShadingState`:

* :func:`white_above_value` (Listings 9.1-9.3): white where the object-space y is above
  a value, black elsewhere;
* :func:`uv_as_color` (Listing 9.5): ``color(state::texture_coordinate(0))``;
* :func:`stripe` (Listing 9.20): is a coordinate inside a stripe of width ``thickness``
  centred on every multiple of ``interval`` (of ``|f|``: the stripes mirror at 0);
* :func:`horizontal_stripe_pattern` (Listing 9.21): two colours by ``stripe`` of the
  y coordinate of ``position(mode)``;
* :func:`exclusive_or` (Listing 9.25) and :func:`checkerboard_pattern` (Listing 9.26):
  stripes of half the interval in x and in y, one colour where exactly one holds.

The texture lookups of section 9.3 are :func:`displacement.textures.texture_2d_lookup`
and :func:`~displacement.textures.texture_2d_lookup_scaled`; the coordinate spaces of
section 9.4 are in :mod:`render.library.space`.

Degenerate arguments: a lane whose ``interval`` is 0 is inside a stripe exactly when its
``thickness`` is positive (the limit of ever denser stripes of that thickness), so no
division by zero reaches the result.  Constant intervals are checked by
:func:`check_interval` (the materials and :data:`~render.library.FUNCTIONS` call it):
they must be finite and positive.
"""

from __future__ import annotations

import numpy as np

from displacement.state import ShadingState
from render.library.space import MAPPING_MODES, object_position, position, texture_coordinate
from render.material import evaluate

__all__ = [
    "white_above_value",
    "uv_as_color",
    "stripe",
    "horizontal_stripe_pattern",
    "exclusive_or",
    "checkerboard_pattern",
    "check_interval",
    "check_mapping_mode",
]


def check_interval(interval, name: str = "interval"):
    """A constant stripe interval must be finite and > 0; a function of the state passes.

    Raises
    ------
    ValueError
        For zero, negative or non-finite constants (or a non-number).

    Examples
    --------
    >>> check_interval(0.2)
    0.2
    >>> check_interval(0.0)
    Traceback (most recent call last):
    ...
    ValueError: interval must be a finite number > 0 (the distance between stripe centres), got 0.0
    """
    if callable(interval):
        return interval
    try:
        value = float(interval)
    except (TypeError, ValueError):
        raise ValueError(f"{name} must be a number (the distance between stripe centres), "
                         f"got {interval!r}") from None
    if not (np.isfinite(value) and value > 0.0):
        raise ValueError(f"{name} must be a finite number > 0 (the distance between stripe "
                         f"centres), got {interval!r}")
    return value


def check_mapping_mode(mode) -> str:
    """Listing 9.15's ``mapping_mode`` as its enumerator (``functions::object`` is ``object``).

    Raises
    ------
    ValueError
        For anything but ``uvw``, ``object`` or ``world``.

    Examples
    --------
    >>> check_mapping_mode("functions::world")
    'world'
    """
    value = str(mode).split("::")[-1]
    if value not in MAPPING_MODES:
        raise ValueError(f"mode must be one of {', '.join(MAPPING_MODES)} (a mapping_mode), "
                         f"got {mode!r}")
    return value


def white_above_value(state: ShadingState, y_value=0.0) -> np.ndarray:
    """Listings 9.1-9.3: ``object_position.y > y_value ? color(1.0) : color(0.0)``.

    Parameters
    ----------
    state : ShadingState with n lanes
    y_value : float or callable(state) -> (n,)

    Returns
    -------
    (n, 3) float64, each row all 0 or all 1

    Examples
    --------
    >>> from displacement.surfaces import UnitSquare
    >>> s = UnitSquare().state_at_uv(np.array([[0.5, 0.25], [0.5, 0.75]]))
    >>> white_above_value(s, 0.5).tolist()
    [[0.0, 0.0, 0.0], [1.0, 1.0, 1.0]]
    """
    y = object_position(state)[:, 1]
    above = y > evaluate(y_value, state, "float", "y_value")
    return np.repeat(above.astype(np.float64)[:, None], 3, axis=1)


def uv_as_color(state: ShadingState) -> np.ndarray:
    """Listing 9.5: ``color(state::texture_coordinate(0))``, that is ``(u, v, 0)``.

    Not clamped, as in MDL: a tint outside [0, 1] is saturated by the distribution
    function that takes it.

    Returns
    -------
    (n, 3) float64

    Examples
    --------
    >>> from displacement.surfaces import UnitSquare
    >>> uv_as_color(UnitSquare().state_at_uv(np.array([[0.25, 0.5]]))).tolist()
    [[0.25, 0.5, 0.0]]
    """
    return texture_coordinate(state, 0)


def stripe(f, interval, thickness) -> np.ndarray:
    """Listing 9.20: is ``f`` inside a stripe?

    ``position = |f|``; with ``lower_center = int(position / interval) * interval`` and
    ``upper_center = lower_center + interval``, the point is in a stripe when
    ``position < lower_center + thickness/2`` or ``position > upper_center -
    thickness/2``: stripes of width ``thickness`` centred on the multiples of
    ``interval``.  ``int()`` truncates toward zero (``np.trunc``, which also stays
    defined beyond the range of MDL's int).

    Parameters
    ----------
    f, interval, thickness : float or array_like, broadcast together
        A lane with ``interval == 0`` is in a stripe exactly when ``thickness > 0``.

    Returns
    -------
    bool ndarray of the broadcast shape

    Examples
    --------
    >>> stripe(np.array([0.0, 0.04, 0.06, 0.1, 0.14, 0.16, -0.18]), 0.2, 0.1).tolist()
    [True, True, False, False, False, True, True]
    """
    f, interval, thickness = np.broadcast_arrays(
        *(np.asarray(a, dtype=np.float64) for a in (f, interval, thickness)))
    position = np.abs(f)
    radius = thickness / 2.0
    zero = interval == 0.0
    step = np.where(zero, 1.0, interval)
    with np.errstate(over="ignore", invalid="ignore"):
        lower_center = np.trunc(position / step) * step
        upper_center = lower_center + step
        lower_bound = lower_center + radius
        upper_bound = upper_center - radius
        inside = (position < lower_bound) | (position > upper_bound)
    return np.where(zero, radius > 0.0, inside)


def horizontal_stripe_pattern(state: ShadingState, mode: str = "uvw", interval=0.2,
                              thickness=0.1, stripe_color=0.0, bg_color=1.0) -> np.ndarray:
    """Listing 9.21: ``stripe(position(mode).y, interval, thickness) ? stripe_color :
    bg_color``.

    Parameters
    ----------
    state : ShadingState with n lanes
    mode : {"uvw", "object", "world"}
    interval, thickness : float or callable(state) -> (n,)
    stripe_color, bg_color : color or callable(state) -> (n, 3)

    Returns
    -------
    (n, 3) float64

    Examples
    --------
    >>> from displacement.surfaces import UnitSquare
    >>> s = UnitSquare().state_at_uv(np.array([[0.3, 0.02], [0.3, 0.1], [0.9, 0.41]]))
    >>> horizontal_stripe_pattern(s).tolist()
    [[0.0, 0.0, 0.0], [1.0, 1.0, 1.0], [0.0, 0.0, 0.0]]
    """
    y = position(state, mode)[:, 1]
    inside = stripe(y, evaluate(interval, state, "float", "interval"),
                    evaluate(thickness, state, "float", "thickness"))
    return np.where(inside[:, None], evaluate(stripe_color, state, "color", "stripe_color"),
                    evaluate(bg_color, state, "color", "bg_color"))


def exclusive_or(a, b) -> np.ndarray:
    """Listing 9.25: ``(a || b) && !(a && b)``, elementwise.

    Examples
    --------
    >>> exclusive_or(np.array([False, False, True, True]),
    ...              np.array([False, True, False, True])).tolist()
    [False, True, True, False]
    """
    a = np.asarray(a, dtype=bool)
    b = np.asarray(b, dtype=bool)
    return (a | b) & ~(a & b)


def checkerboard_pattern(state: ShadingState, interval=0.2, mode: str = "uvw", color_1=1.0,
                         color_2=0.0) -> np.ndarray:
    """Listing 9.26: two colours in a checkerboard of squares ``interval / 2`` wide.

    With ``thickness = interval / 2``, ``color_1`` where exactly one of
    ``stripe(point.x, interval, thickness)`` and ``stripe(point.y, ...)`` holds
    (:func:`exclusive_or`), ``color_2`` elsewhere; ``point = position(mode)``.  The
    squares' edges lie at odd multiples of ``interval / 4``, and the pattern mirrors at
    x = 0 and y = 0 (``stripe`` takes ``|f|``).

    Parameters
    ----------
    state : ShadingState with n lanes
    interval : float or callable(state) -> (n,)
    mode : {"uvw", "object", "world"}
    color_1, color_2 : color or callable(state) -> (n, 3)

    Returns
    -------
    (n, 3) float64

    Examples
    --------
    >>> from displacement.surfaces import UnitSquare
    >>> s = UnitSquare().state_at_uv(np.array([[0.0, 0.0], [0.1, 0.0], [0.1, 0.1]]))
    >>> checkerboard_pattern(s).tolist()
    [[0.0, 0.0, 0.0], [1.0, 1.0, 1.0], [0.0, 0.0, 0.0]]
    """
    point = position(state, mode)
    step = evaluate(interval, state, "float", "interval")
    thickness = step / 2.0
    vertical_stripe = stripe(point[:, 0], step, thickness)
    horizontal_stripe = stripe(point[:, 1], step, thickness)
    return np.where(exclusive_or(horizontal_stripe, vertical_stripe)[:, None],
                    evaluate(color_1, state, "color", "color_1"),
                    evaluate(color_2, state, "color", "color_2"))
