"""Chapter 14.3 of the MDL Handbook: the bubble profile, a circle cut by a unit base line.

:func:`get_bubble_args` computes the uniform struct of Listing 14.17 once (in the
factory, never per point); :func:`bubble_point` (14.18) maps a fraction to the profile;
:func:`displace_with_bubble` (14.20) builds the field; :func:`bubble` is the displacement
of Listing 14.21's material and :func:`normalize_grid` its texture compensation.

The profile's x is the run along the base (along the tangent) and its y the height
(along the normal), as :func:`~displacement.vector.modify_normal` reads it.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from displacement.fields import Field, float2, frac, repeat_knots
from displacement.state import ShadingState
from displacement.vector import modify_normal

__all__ = [
    "BubbleArgs",
    "get_bubble_args",
    "bubble_point",
    "displace_with_bubble",
    "bubble",
    "normalize_grid",
]


@dataclass(frozen=True)
class BubbleArgs:
    """Listing 14.16's ``bubble_args`` struct (uniform: computed once per material).

    Attributes
    ----------
    radius, height : float
        The circle's radius and the height of its center above the base's midpoint.
    angle_start, angle_end : float
        Angles (radians) where the arc leaves and rejoins the base; the arc is traced
        from ``angle_end`` down to ``angle_start`` as the fraction grows.
    bubble_start, bubble_end : float
        Fractions of the whole profile where the arc starts and ends.
    total_length : float
        Length of the profile: arc plus the two base pieces (>= 1).
    """

    radius: float
    height: float
    angle_start: float
    angle_end: float
    bubble_start: float
    bubble_end: float
    total_length: float


def get_bubble_args(radius: float, height: float) -> BubbleArgs:
    """Listing 14.17: the angles and lengths of a bubble, computed once.

    Parameters
    ----------
    radius : float > 0
    height : float with ``|height| <= radius``
        ``height = radius`` is a full circle standing on the base; ``height = -radius``
        is no bubble at all (a flat base); both are finite.

    Returns
    -------
    BubbleArgs

    Raises
    ------
    ValueError
        If ``radius <= 0``, ``|height| > radius`` (the circle does not reach the base:
        ``acos(height / radius)`` is undefined), or the chord the circle cuts from the
        base is longer than the base (1.0), so the bubble would overhang its own ends.

    Examples
    --------
    >>> ba = get_bubble_args(0.5, 0.0)          # a semicircle on the whole base
    >>> round(ba.total_length, 12), round(ba.bubble_start, 12), ba.bubble_end
    (1.570796326795, 0.0, 1.0)
    >>> get_bubble_args(0.25, 0.3)  # doctest: +ELLIPSIS
    Traceback (most recent call last):
    ...
    ValueError: bubble height 0.3 is outside [-radius, radius] = [-0.25, 0.25]: ...
    """
    radius = float(radius)
    height = float(height)
    if not (math.isfinite(radius) and radius > 0.0):
        raise ValueError(f"bubble radius must be a finite number > 0, got {radius}")
    if not (math.isfinite(height) and abs(height) <= radius):
        raise ValueError(
            f"bubble height {height} is outside [-radius, radius] = [{-radius}, {radius}]: "
            "the circle does not meet the base; use |height| <= radius"
        )
    base_angle = math.pi * 3 / 2
    half_angle = math.acos(height / radius)   # |height / radius| <= 1 checked above
    angle_start = base_angle + half_angle
    angle_end = base_angle - half_angle + 2 * math.pi

    bubble_circumference = (2 * math.pi - 2 * half_angle) * radius
    chord_length = 2 * radius * math.sin(half_angle)
    if chord_length > 1.0:
        raise ValueError(
            f"bubble chord 2*radius*sin(acos(height/radius)) = {chord_length:.6g} is longer "
            "than the base (1.0): reduce the radius or raise the height"
        )
    total_length = bubble_circumference + (1 - chord_length)

    circumference_fraction = bubble_circumference / total_length
    base_length = (1.0 - chord_length) / 2
    bubble_start = base_length / total_length
    bubble_end = bubble_start + circumference_fraction
    return BubbleArgs(
        radius, height, angle_start, angle_end, bubble_start, bubble_end, total_length
    )


def bubble_point(fraction, repeat, ba: BubbleArgs) -> np.ndarray:
    """Listing 14.18: the point of the bubble profile at ``fraction`` (0 to 1).

    ``f = frac(fraction * repeat)`` selects the left base (``f <= bubble_start``), the arc
    (``f <= bubble_end``) or the right base.  When ``repeat != 1`` the point is scaled by
    ``1 / repeat`` and offset in x by ``floor(fraction * repeat) / repeat``.

    Parameters
    ----------
    fraction : (n,) float64
    repeat : float or (n,) float64, nonzero
    ba : BubbleArgs

    Returns
    -------
    (n, 2) float64
        (x = run along the base, y = height).

    Examples
    --------
    >>> ba = get_bubble_args(0.5, 0.0)
    >>> bubble_point(np.array([0.0, 0.5, 1.0]), 1.0, ba).round(12).tolist()
    [[0.0, 0.0], [0.5, 0.5], [0.0, 0.0]]
    >>> bubble_point(np.array([0.75]), 2.0, ba).round(12).tolist()
    [[0.75, 0.25]]
    """
    fraction = np.asarray(fraction, dtype=np.float64)
    repeat = np.broadcast_to(np.asarray(repeat, dtype=np.float64), fraction.shape)
    if np.any(repeat == 0.0):
        raise ValueError("bubble_point: repeat must be nonzero")
    f = frac(fraction * repeat)

    left = f <= ba.bubble_start
    arc = ~left & (f <= ba.bubble_end)
    # the arc's fraction range is empty when height = -radius: no point is on it then
    span = ba.bubble_end - ba.bubble_start
    along = np.where(arc, f - ba.bubble_start, 0.0) / (span if span > 0.0 else 1.0)
    pt_angle = ba.angle_end + along * (ba.angle_start - ba.angle_end)   # fit(...)

    x = np.where(
        left,
        f * ba.total_length,
        np.where(arc, np.cos(pt_angle) * ba.radius + 0.5, 1.0 - (1.0 - f) * ba.total_length),
    )
    y = np.where(arc, np.sin(pt_angle) * ba.radius + ba.height, 0.0)

    scaled = repeat != 1.0
    offset = np.floor(fraction * repeat) / repeat
    x = np.where(scaled, x / repeat + offset, x)
    y = np.where(scaled, y / repeat, y)
    return np.stack([x, y], axis=-1)




def displace_with_bubble(repeat, ba: BubbleArgs) -> Field:
    """Listing 14.20: the bubble displacement in u (if ``repeat.u > 0``), else in v
    (if ``repeat.v > 0``), else the zero vector.

    ``f = frac(texture_coordinate)``, so uv outside [0, 1] and negative uv repeat the
    profile, and uv = 1 is the same point of the profile as uv = 0 (no displacement at
    either end: the base ends at x = 0 and x = 1).

    Parameters
    ----------
    repeat : float or (2,) float64, constant
        Repetitions in u and v (a scalar means ``float2(x)``); the first positive one
        chooses the direction.
    ba : BubbleArgs
        From :func:`get_bubble_args`, computed once.

    Returns
    -------
    Field
        Knots at the joins of arc and base (``bubble_start``, ``bubble_end``) and at
        every repetition boundary, in the chosen direction.

    Examples
    --------
    >>> from displacement.surfaces import UnitSquare
    >>> s = UnitSquare().state_at_uv(np.array([[0.5, 0.3]]))
    >>> displace_with_bubble((1.0, 0.0), get_bubble_args(0.5, 0.0))(s).round(12).tolist()
    [[0.0, 0.0, 0.5]]
    """
    if not isinstance(ba, BubbleArgs):
        raise ValueError("ba must be a BubbleArgs from get_bubble_args(radius, height)")
    repeat = float2(repeat, "repeat")
    if repeat[0] > 0:
        index = 0
    elif repeat[1] > 0:
        index = 1
    else:
        index = None

    if index is None:
        def function(state: ShadingState) -> np.ndarray:
            return np.zeros((len(state), 3))   # the default value is a null vector
        knots = (None, None)
    else:
        r = float(repeat[index])

        def function(state: ShadingState) -> np.ndarray:
            f = frac(state.uv[:, index])
            tangent = state.tangent_u if index == 0 else state.tangent_v
            return modify_normal(f, bubble_point(f, r, ba), tangent, state.normal)

        k = repeat_knots(np.array([0.0, ba.bubble_start, ba.bubble_end, 1.0]), r)
        knots = (k, None) if index == 0 else (None, k)
    return Field(function, knots, "displace_with_bubble", {"repeat": tuple(repeat), "ba": ba})


def bubble(radius=0.25, height=0.25, repeat=1.0) -> Field:
    """Listing 14.21's displacement: ``displace_with_bubble(repeat,
    get_bubble_args(radius, height))`` with the material's defaults.

    Examples
    --------
    >>> bubble(0.35, 0.0, (1.0, 0.0)).uv_knots[0].round(6).tolist()
    [0.0, 0.107177, 0.892823, 1.0]
    """
    field = displace_with_bubble(repeat, get_bubble_args(radius, height))
    return Field(
        field.function, field.uv_knots, "bubble",
        {"radius": radius, "height": height, "repeat": repeat},
    )


def normalize_grid(grid_count, repeat, ba: BubbleArgs, normalize_grid: bool = True) -> np.ndarray:
    """Listing 14.21's ``grid_point``: grid counts scaled by ``ba.total_length``.

    Component i is ``grid_count[i] * total_length`` when ``normalize_grid`` and
    ``repeat[i] != 1.0``, else ``grid_count[i]``, exactly as printed.  Note that the
    Handbook's condition also scales a direction whose repeat is 0 (not displaced).

    Parameters
    ----------
    grid_count, repeat : float or (2,) float64
    ba : BubbleArgs
    normalize_grid : bool

    Returns
    -------
    (2,) float64

    Examples
    --------
    >>> ba = get_bubble_args(0.5, 0.0)
    >>> normalize_grid((4.0, 4.0), (1.0, 2.0), ba).round(6).tolist()
    [4.0, 6.283185]
    """
    grid_count = float2(grid_count, "grid_count")
    repeat = float2(repeat, "repeat")
    scale = np.where(bool(normalize_grid) & (repeat != 1.0), ba.total_length, 1.0)
    return grid_count * scale
