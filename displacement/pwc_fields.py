"""Chapter 15 of the MDL Handbook: displacement fields driven by compiled pw-curves.

A pw-curve (a :class:`pwc.Curve`, or a path to a ``.pwc`` file) gives points with
x = depth and y = run (the opposite of chapter 14's profiles).

* :func:`displace_with_pwc` (Listings 15.6-15.8): a molding along u or v.
* :func:`pwc_angular_displace` (15.12-15.14): a solid of revolution about +y.
* :func:`double_pwc` (15.19-15.20): a profile revolved with a radius that follows a
  second curve (column fluting).
* :func:`normalized_grid_count`, :func:`texture_scale` (15.9, 15.11): texture-length
  compensation by the curve's length (the compiler's ``NAME_length``).

Rotation direction.  Listing 15.12 builds ``float3x3(cos, 0, sin, 0, 1, 0, -sin, 0,
cos)``; MDL's matrix constructor lists elements column by column, and ``p *= M`` is
the row vector ``p`` times ``M`` (component j is ``p . column_j``).  So
``p * y_rotation_3(a) = (x cos a + z sin a, y, -x sin a + z cos a)``: the right-handed
rotation by ``+a`` about +y (x turns towards -z), the direction in which the parametric
surfaces of :mod:`displacement.surfaces` turn with u.  :func:`y_rotation_3` returns the
numpy matrix ``A`` with ``p @ A`` equal to MDL's ``p * y_rotation_3(a)``.

Listings 15.13 and 15.19 subtract ``state::position()``, so the displaced point
(position + displacement) is the absolute rotated point, whatever the base surface.
"""

from __future__ import annotations

import math
from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np

from displacement.fields import Field, displacement_direction, frac, repeat_knots
from displacement.state import ShadingState

if TYPE_CHECKING:  # pragma: no cover
    import pwc

__all__ = [
    "displace_to_point",
    "displace_with_pwc",
    "y_rotation_3",
    "displace_to_angular_point",
    "pwc_angular_displace",
    "displace_to_pwc_point",
    "double_pwc",
    "normalized_grid_count",
    "texture_scale",
]


def _as_curve(curve) -> pwc.Curve:
    """A compiled curve: a :class:`pwc.Curve` as is, a path to a ``.pwc`` file loaded."""
    if isinstance(curve, str | Path):
        import pwc

        return pwc.load(curve)
    for attribute in ("evaluate", "t", "length"):
        if not hasattr(curve, attribute):
            raise ValueError(
                f"expected a pwc.Curve (or a path to a .pwc file), got {type(curve).__name__}"
            )
    return curve


def _direction_knots(index: int, knots: np.ndarray) -> tuple:
    return (knots, None) if index == 0 else (None, knots)


def displace_to_point(pw_point, uv_position, tangent, normal) -> np.ndarray:
    """Listing 15.6: ``pw_point.x * normal + (pw_point.y - uv_position) * tangent``.

    The curve's x (depth) moves the point along the normal; the offset of its y (run)
    from the point's own texture coordinate moves it along the tangent, so the
    displaced point lands on the curve point itself (on the unit square).

    Parameters
    ----------
    pw_point : (n, 2) float64
    uv_position : (n,) float64
    tangent, normal : (n, 3) float64

    Returns
    -------
    (n, 3) float64

    Examples
    --------
    >>> displace_to_point(np.array([[0.2, 0.7]]), np.array([0.5]),
    ...                   np.array([[0.0, 1, 0]]), np.array([[0.0, 0, 1]])).round(12).tolist()
    [[0.0, 0.2, 0.2]]
    """
    pw_point = np.asarray(pw_point, dtype=np.float64)
    uv_position = np.asarray(uv_position, dtype=np.float64)
    result = pw_point[:, 0][:, None] * normal
    result = result + (pw_point[:, 1] - uv_position)[:, None] * tangent
    return result


def displace_with_pwc(
    curve, direction: str | int = "along_v", repeat: float | None = None
) -> Field:
    """Listing 15.8: a pw-curve as a vector displacement along u or v.

    ``uv_pos = texture_coordinate[direction]``, ``p = point_along_pwc(uv_pos)`` and the
    vector is ``displace_to_point(p, uv_pos, tangent)``.  As in the Handbook, uv_pos is
    not wrapped: below 0 the first point and from 1 on the last point of the curve are
    used (uv = 0 and uv = 1 land exactly on the curve's ends).

    Parameters
    ----------
    curve : pwc.Curve or path
    direction : "along_u" | "along_v" (or 0 | 1)
    repeat : float > 0, optional
        Repeat the curve ``repeat`` times across [0, 1] with ``curve.evaluate(s,
        repeat)`` (Listing 14.27's rule: ``frac(s r)``, shrunk by ``1/r``, run offset
        ``floor(s r)/r``).  This wraps, so with ``repeat=1`` the point at uv = 1 is the
        curve's first point (unlike ``repeat=None``); uv outside [0, 1] repeats.

    Returns
    -------
    Field
        Knots ``curve.t`` (through ``repeat``) in the chosen direction.

    Examples
    --------
    >>> import pwc
    >>> from displacement.surfaces import UnitSquare
    >>> c = pwc.compile_text("0 0\\n.5 0 \\n.5 1")       # normalized: (0,0) (.5,0) (.5,1)
    >>> s = UnitSquare().state_at_uv(np.array([[0.3, 1.0]]))
    >>> (s.position + displace_with_pwc(c, "along_v")(s)).round(12).tolist()
    [[0.3, 1.0, 0.5]]
    """
    curve = _as_curve(curve)
    index = displacement_direction(direction)
    if repeat is not None:
        repeat = float(repeat)
        if not (math.isfinite(repeat) and repeat > 0.0):
            raise ValueError(f"repeat must be a finite number > 0 (or None), got {repeat}")

    def function(state: ShadingState) -> np.ndarray:
        uv_pos = state.uv[:, index]
        tangent = state.tangent_u if index == 0 else state.tangent_v
        pw_point = curve.evaluate(uv_pos) if repeat is None else curve.evaluate(uv_pos, repeat)
        return displace_to_point(pw_point, uv_pos, tangent, state.normal)

    t = np.asarray(curve.t, dtype=np.float64)
    knots = t.copy() if repeat is None else repeat_knots(t, repeat)
    return Field(
        function, _direction_knots(index, knots), "displace_with_pwc",
        {"curve": getattr(curve, "name", ""), "direction": ("along_u", "along_v")[index],
         "repeat": repeat},
    )


def y_rotation_3(angle) -> np.ndarray:
    """Listing 15.12: rotation about +y, as the matrix ``A`` with ``p @ A`` equal to
    MDL's ``p * y_rotation_3(angle)`` (see the module docstring).

    ``A = [[cos, 0, -sin], [0, 1, 0], [sin, 0, cos]]``: the Handbook's nine arguments
    are its columns.  ``p @ A`` rotates ``p`` by ``+angle``, right-handed about +y.

    Parameters
    ----------
    angle : float or (...) float64
        Radians.

    Returns
    -------
    (..., 3, 3) float64

    Examples
    --------
    >>> (np.array([1.0, 2.0, 0.0]) @ y_rotation_3(math.pi / 2)).round(12).tolist()
    [0.0, 2.0, -1.0]
    """
    angle = np.asarray(angle, dtype=np.float64)
    c, s = np.cos(angle), np.sin(angle)
    zero, one = np.zeros_like(c), np.ones_like(c)
    columns = [
        np.stack([c, zero, s], axis=-1),     # math::cos(angle), 0.0, math::sin(angle)
        np.stack([zero, one, zero], axis=-1),
        np.stack([-s, zero, c], axis=-1),    # -math::sin(angle), 0.0, math::cos(angle)
    ]
    return np.stack(columns, axis=-1)


def _rotate(p: np.ndarray, t: np.ndarray) -> np.ndarray:
    """``p * y_rotation_3(2 pi t)`` per row.

    The angle is taken of ``frac(t)``: the same rotation, but t = 0 and t = 1 give
    bit-identical points, so the seam of a solid of revolution closes exactly.  The
    product is written out (``p @ y_rotation_3(a)`` without building n matrices).
    """
    angle = 2.0 * math.pi * frac(t)
    c, s = np.cos(angle), np.sin(angle)
    out = np.empty_like(p)
    out[:, 0] = p[:, 0] * c + p[:, 2] * s       # p . column 0 = (cos, 0, sin)
    out[:, 1] = p[:, 1]
    out[:, 2] = -p[:, 0] * s + p[:, 2] * c      # p . column 2 = (-sin, 0, cos)
    return out


def displace_to_angular_point(pw_point, t, position, radius=0.0) -> np.ndarray:
    """Listing 15.13: the curve point at distance ``x + radius`` from the y axis,
    turned by ``2 pi t`` about +y, minus the point's own position.

    Parameters
    ----------
    pw_point : (n, 2) float64
        (x = distance from the axis, y = height).
    t : (n,) float64
        Turn fraction, usually a texture coordinate in [0, 1].
    position : (n, 3) float64
        ``state::position()``.
    radius : float or (n,) float64
        Added to x (Listing 15.13's ``radius``, 0 in Listing 15.14).

    Returns
    -------
    (n, 3) float64

    Examples
    --------
    >>> displace_to_angular_point(np.array([[0.5, 0.25]]), np.array([0.25]),
    ...                           np.zeros((1, 3))).round(12).tolist()
    [[0.0, 0.25, -0.5]]
    """
    pw_point = np.asarray(pw_point, dtype=np.float64)
    n = len(pw_point)
    p = np.zeros((n, 3))
    p[:, 0] = pw_point[:, 0] + radius
    p[:, 1] = pw_point[:, 1]
    p = _rotate(p, np.asarray(t, dtype=np.float64))
    return p - position


def pwc_angular_displace(curve, direction: str | int = "along_v", radius: float = 0.0) -> Field:
    """Listing 15.14: a solid of revolution from a pw-curve (``radial_pwc``).

    The texture coordinate in ``direction`` picks the curve point; the other one turns
    it about +y by ``2 pi`` times its value.  On the unit square along v, the point
    (u, v) goes to ``R_y(2 pi u) (x(v) + radius, y(v), 0)``, at distance
    ``|x(v) + radius|`` from the y axis.

    Parameters
    ----------
    curve : pwc.Curve or path
    direction : "along_u" | "along_v" (or 0 | 1)
        Which texture coordinate runs along the curve (Listing 15.15's default: v).
    radius : float
        Added to every point's distance from the axis (Listing 15.13's ``radius``; the
        Handbook's ``pwc_angular_displace`` uses 0).

    Returns
    -------
    Field
        Knots ``curve.t`` in the curve direction, none in the turn direction.

    Examples
    --------
    >>> import pwc
    >>> from displacement.surfaces import UnitSquare
    >>> c = pwc.compile_text("1 0\\n1 1")                 # normalized: (1, 0) (1, 1)
    >>> s = UnitSquare().state_at_uv(np.array([[0.5, 0.5]]))
    >>> (s.position + pwc_angular_displace(c)(s)).round(12).tolist()
    [[-1.0, 0.5, -0.0]]
    """
    curve = _as_curve(curve)
    position_index = displacement_direction(direction)
    rotation_index = 1 - position_index
    radius = float(radius)
    if not math.isfinite(radius):
        raise ValueError(f"radius must be finite, got {radius}")

    def function(state: ShadingState) -> np.ndarray:
        position = state.uv[:, position_index]
        rotation = state.uv[:, rotation_index]
        pw_point = curve.evaluate(position)
        return displace_to_angular_point(pw_point, rotation, state.position, radius)

    t = np.asarray(curve.t, dtype=np.float64).copy()
    return Field(
        function, _direction_knots(position_index, t), "pwc_angular_displace",
        {"curve": getattr(curve, "name", ""),
         "direction": ("along_u", "along_v")[position_index], "radius": radius},
    )


def displace_to_pwc_point(pw_point, t, pwc, position, radius_offset=0.0) -> np.ndarray:
    """Listing 15.19: a profile point revolved by ``2 pi t``, its distance from the axis
    scaled by ``|point_along_pwc(t, pwc)|``, minus the point's own position.

    ``p = (x + radius_offset, y, 0)``; ``p.x *= length(sweep(t))``; ``p *=
    y_rotation_3(2 pi t)``; ``p -= state::position()``.  Only the length of the sweep
    curve's point counts (its direction does not).

    Parameters
    ----------
    pw_point : (n, 2) float64
        Profile point (x = distance from the axis, y = height).
    t : (n,) float64
        Turn fraction (the u texture coordinate in :func:`double_pwc`).
    pwc : pwc.Curve
        The sweep curve.
    position : (n, 3) float64
        ``state::position()``.
    radius_offset : float or (n,) float64

    Returns
    -------
    (n, 3) float64
    """
    pw_point = np.asarray(pw_point, dtype=np.float64)
    t = np.asarray(t, dtype=np.float64)
    square_pt = np.asarray(pwc.evaluate(t), dtype=np.float64)
    scale = np.linalg.norm(square_pt, axis=-1)
    p = np.zeros((len(pw_point), 3))
    p[:, 0] = (pw_point[:, 0] + radius_offset) * scale
    p[:, 1] = pw_point[:, 1]
    p = _rotate(p, t)
    return p - position


def double_pwc(profile_curve, sweep_curve, radius_offset: float = 0.0) -> Field:
    """Listing 15.20's displacement: the profile (along v) swept around the y axis
    (along u) at a distance that follows the sweep curve.

    ``displace_to_pwc_point(point_along_pwc(v, profile), u, sweep, radius_offset)``.

    Parameters
    ----------
    profile_curve, sweep_curve : pwc.Curve or path
    radius_offset : float

    Returns
    -------
    Field
        Knots: the sweep's ``t`` in u and the profile's ``t`` in v.
    """
    profile_curve = _as_curve(profile_curve)
    sweep_curve = _as_curve(sweep_curve)
    radius_offset = float(radius_offset)
    if not math.isfinite(radius_offset):
        raise ValueError(f"radius_offset must be finite, got {radius_offset}")

    def function(state: ShadingState) -> np.ndarray:
        u = state.uv[:, 0]
        v = state.uv[:, 1]
        profile_point = profile_curve.evaluate(v)
        return displace_to_pwc_point(
            profile_point, u, sweep_curve, state.position, radius_offset
        )

    knots = (
        np.asarray(sweep_curve.t, dtype=np.float64).copy(),
        np.asarray(profile_curve.t, dtype=np.float64).copy(),
    )
    return Field(
        function, knots, "double_pwc",
        {"profile_curve": getattr(profile_curve, "name", ""),
         "sweep_curve": getattr(sweep_curve, "name", ""), "radius_offset": radius_offset},
    )


def normalized_grid_count(grid_count, curve, direction: str | int = "along_v") -> np.ndarray:
    """Listing 15.9: grid counts with the curve direction's count times ``curve.length``.

    A pw-curve stretches the texture of its direction by its length (the compiler's
    ``NAME_length``); multiplying that direction's grid count by it keeps grid cells
    square.  ``normalized_grid_count(50, ornament_1)`` is Listing 15.9's
    ``float2(50, 50 * ornament_1_length)``.

    Parameters
    ----------
    grid_count : float or (2,) float64
    curve : pwc.Curve or path
    direction : "along_u" | "along_v" (or 0 | 1)

    Returns
    -------
    (2,) float64
    """
    curve = _as_curve(curve)
    result = np.broadcast_to(np.asarray(grid_count, dtype=np.float64), (2,)).copy()
    result[displacement_direction(direction)] *= float(curve.length)
    return result


def texture_scale(curve, direction: str | int = "along_v", scale: float = 1.0) -> np.ndarray:
    """Listing 15.11: the texture scale ``(scale, scale * curve.length)`` for a curve
    along v (``travertine(1.0, ornament_2_length)``), or its mirror along u.

    Returns
    -------
    (2,) float64
    """
    return normalized_grid_count(scale, curve, direction)
