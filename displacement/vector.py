"""Chapter 14.1-14.2 of the MDL Handbook: vector displacement by scaling and tilting the normal.

MDL functions such as ``move_up(float scale)`` read ``state::normal()`` and are called
per point with arguments that are themselves expressions of the state (``u()``).  Here
each such function is a factory: its varying arguments are constants or callables of
the state (:func:`u`, :func:`v`, any ``state -> (n,)``), and it returns a
:class:`~displacement.fields.Field`.  The material-named factories (:func:`raise_`,
:func:`triangle`, :func:`circle_linear`, :func:`circle_nonlinear`) are the displacement
arguments of Listings 14.9, 14.11, 14.13 and 14.15.

Chapter 14 profiles use x as the run along the tangent and y as the height along the
normal (:func:`modify_normal`); chapter 15's pw-curves swap them (x = depth).
"""

from __future__ import annotations

import math

import numpy as np

from displacement.fields import Field, varying
from displacement.state import ShadingState
from displacement.waves import fit

__all__ = [
    "u",
    "v",
    "modify_normal",
    "move_up",
    "raise_",
    "triangle_displacement",
    "triangle",
    "circle_linear_vector",
    "circle_linear",
    "circle_nonlinear_vector",
    "circle_nonlinear",
]


def u(state: ShadingState) -> np.ndarray:
    """Listing 14.1: ``state::texture_coordinate(0).x``, shape (n,)."""
    return state.uv[:, 0]


def v(state: ShadingState) -> np.ndarray:
    """Listing 14.2: ``state::texture_coordinate(0).y``, shape (n,)."""
    return state.uv[:, 1]


def _uv_direction(f) -> int | None:
    """0 or 1 when ``f`` is :func:`u` or :func:`v` (so knots are known), else None."""
    if f is u:
        return 0
    if f is v:
        return 1
    return None


def _knots_in(direction: int | None, knots) -> tuple:
    knots = np.unique(np.asarray(knots, dtype=np.float64))
    knots = knots[(knots >= 0.0) & (knots <= 1.0)]
    if direction is None or len(knots) == 0:
        return (None, None)
    return (knots, None) if direction == 0 else (None, knots)


def modify_normal(f, target, tangent, normal) -> np.ndarray:
    """Listing 14.19: ``tangent * (target.x - f) + normal * target.y``.

    The profile point ``target`` is (run, height): its x is compared with the current
    texture coordinate ``f`` and the difference moves the point along ``tangent``; its y
    moves it along the normal.

    Parameters
    ----------
    f : (n,) float64
        Texture coordinate along ``tangent``.
    target : (n, 2) float64
        Profile point (x = run, y = height).
    tangent, normal : (n, 3) float64
        ``state::texture_tangent_u(0)`` or ``_v(0)``, and ``state::normal()``.

    Returns
    -------
    (n, 3) float64

    Examples
    --------
    >>> modify_normal(np.array([0.25]), np.array([[0.5, 0.1]]),
    ...               np.array([[1.0, 0, 0]]), np.array([[0, 0, 1.0]])).tolist()
    [[0.25, 0.0, 0.1]]
    """
    f = np.asarray(f, dtype=np.float64)
    target = np.asarray(target, dtype=np.float64)
    return tangent * (target[:, 0] - f)[:, None] + normal * target[:, 1][:, None]


def move_up(scale) -> Field:
    """Listing 14.8: ``scale * state::normal()``.

    Parameters
    ----------
    scale : float or callable state -> (n,)

    Examples
    --------
    >>> from displacement.surfaces import UnitSquare
    >>> s = UnitSquare().state_at_uv(np.array([[0.5, 0.5]]))
    >>> move_up(0.2)(s).tolist()
    [[0.0, 0.0, 0.2]]
    """
    def function(state: ShadingState) -> np.ndarray:
        return varying(scale, state)[:, None] * state.normal

    return Field(function, (None, None), "move_up", {"scale": scale})


def raise_(scale=0.0) -> Field:
    """Listing 14.9's displacement, material ``raise`` (a Python keyword, hence the
    underscore; ``FIELDS["raise"]`` is this function): ``move_up(scale)``.

    Parameters
    ----------
    scale : float or callable state -> (n,), default 0.0
    """
    field = move_up(scale)
    return Field(field.function, field.uv_knots, "raise", {"scale": scale})


def triangle_displacement(f, height) -> Field:
    """Listing 14.10: the isosceles triangle profile along the normal.

    ``length = fit(f, 0, 0.5, 0, height)`` for ``f <= 0.5``, else
    ``fit(f, 0.5, 1, height, 0)``; the displacement is ``length * state::normal()``.
    As in the Handbook ``f`` is not wrapped: outside [0, 1] the two sides extrapolate
    linearly (finite, negative lengths).

    Parameters
    ----------
    f : float or callable state -> (n,)
        Position across the triangle, usually :func:`u`.
    height : float or callable state -> (n,)

    Returns
    -------
    Field
        With a u (or v) knot at 0.5, the apex, when ``f`` is :func:`u` (or :func:`v`).

    Examples
    --------
    >>> from displacement.surfaces import UnitSquare
    >>> s = UnitSquare().state_at_uv(np.array([[0.25, 0.0], [0.5, 0.0], [0.75, 0.0]]))
    >>> triangle_displacement(u, 0.25)(s)[:, 2].tolist()
    [0.125, 0.25, 0.125]
    """
    def function(state: ShadingState) -> np.ndarray:
        fs = varying(f, state)
        h = varying(height, state)
        length = np.where(fs <= 0.5, fit(fs, 0.0, 0.5, 0.0, h), fit(fs, 0.5, 1.0, h, 0.0))
        return length[:, None] * state.normal

    knots = _knots_in(_uv_direction(f), [0.5])
    return Field(function, knots, "triangle_displacement", {"f": f, "height": height})


def triangle(height=0.5) -> Field:
    """Listing 14.11's displacement: ``triangle_displacement(u(), height)``."""
    field = triangle_displacement(u, height)
    return Field(field.function, field.uv_knots, "triangle", {"height": height})


def circle_linear_vector(f, radius=0.5) -> Field:
    """Listing 14.12: a circular profile by scaling the normal (distorts texture space).

    ``x = fit(f, 0, 1, -0.5, 0.5)``, ``y = sqrt(radius² - x²)`` where that is real, else
    0; the displacement is ``y * state::normal()``.

    Parameters
    ----------
    f : float or callable state -> (n,)
    radius : float or callable state -> (n,), default 0.5

    Returns
    -------
    Field
        Knots where the circle meets the base (``f = 0.5 ± radius``, when in [0, 1],
        ``f`` is :func:`u` or :func:`v` and ``radius`` is a constant).

    Examples
    --------
    >>> from displacement.surfaces import UnitSquare
    >>> s = UnitSquare().state_at_uv(np.array([[0.5, 0.0], [0.9, 0.0], [0.0, 0.0]]))
    >>> circle_linear_vector(u, 0.5)(s)[:, 2].round(12).tolist()
    [0.5, 0.3, 0.0]
    """
    def function(state: ShadingState) -> np.ndarray:
        fs = varying(f, state)
        r = varying(radius, state)
        x = fit(fs, 0.0, 1.0, -0.5, 0.5)
        y_2 = r * r - x * x
        y = np.sqrt(np.maximum(y_2, 0.0))  # y clamped to a positive value
        return y[:, None] * state.normal

    if callable(radius):
        knots = (None, None)
    else:
        knots = _knots_in(_uv_direction(f), [0.5 - abs(radius), 0.5 + abs(radius)])
    return Field(function, knots, "circle_linear_vector", {"f": f, "radius": radius})


def circle_linear(height=0.5) -> Field:
    """Listing 14.13's displacement: ``circle_linear_vector(u(), height)``."""
    field = circle_linear_vector(u, height)
    return Field(field.function, field.uv_knots, "circle_linear", {"height": height})


def circle_nonlinear_vector(f, height) -> Field:
    """Listing 14.14: a semicircle with arc length proportional to ``f``.

    ``x1 = fit(f, 0, 1, -1, 1)``, ``angle = fit(f, 0, 1, pi, 0)``, and the displacement is
    ``height * (sin(angle) * normal + (cos(angle) - x1) * tangent_u)``: on the unit square
    with ``f = u`` and ``height = 0.5`` the point at u lands on the circle of radius 0.5
    about (0.5, v, 0) at the angle ``pi (1 - u)``.

    Parameters
    ----------
    f : float or callable state -> (n,)
    height : float or callable state -> (n,)

    Examples
    --------
    >>> from displacement.surfaces import UnitSquare
    >>> s = UnitSquare().state_at_uv(np.array([[0.0, 0.0], [0.5, 0.0], [1.0, 0.0]]))
    >>> (circle_nonlinear_vector(u, 0.5)(s).round(12) + 0.0).tolist()
    [[0.0, 0.0, 0.0], [0.0, 0.0, 0.5], [0.0, 0.0, 0.0]]
    """
    def function(state: ShadingState) -> np.ndarray:
        fs = varying(f, state)
        h = varying(height, state)
        x1 = fit(fs, 0.0, 1.0, -1.0, 1.0)
        angle = fit(fs, 0.0, 1.0, math.pi, 0.0)
        x2 = np.cos(angle)
        y2 = np.sin(angle)
        displacement_vector = y2[:, None] * state.normal + (x2 - x1)[:, None] * state.tangent_u
        return h[:, None] * displacement_vector

    return Field(function, (None, None), "circle_nonlinear_vector", {"f": f, "height": height})


def circle_nonlinear(height=0.5) -> Field:
    """Listing 14.15's displacement: ``circle_nonlinear_vector(u(), height)``."""
    field = circle_nonlinear_vector(u, height)
    return Field(field.function, field.uv_knots, "circle_nonlinear", {"height": height})
