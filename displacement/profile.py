"""Chapter 14.4-14.5 of the MDL Handbook: vector displacement by a segmented profile.

A profile is an (N, 2) array of points joined by straight segments, x = run along the
tangent and y = height along the normal (chapter 14's convention).  The uniform tables
(:func:`profile_lengths`, :func:`normalized_lengths`) are computed once in the factory
:func:`displace_with_profile`; :func:`point_along_profile` (Listing 14.27) is the
per-point lookup, vectorized.
"""

from __future__ import annotations

import numpy as np

from displacement.fields import Field, displacement_direction, frac, repeat_knots
from displacement.state import ShadingState
from displacement.vector import modify_normal

__all__ = [
    "TEE",
    "profile_lengths",
    "normalized_lengths",
    "point_along_profile",
    "displace_with_profile",
    "tee_displacement",
    "scale_component",
]

#: Listing 14.22: the tee profile (``profile_arrays::tee``), shape (10, 2), read-only.
TEE = np.array(
    [
        [0.000, 0.000],
        [0.375, 0.000],
        [0.375, 0.250],
        [0.125, 0.250],
        [0.125, 0.500],
        [0.875, 0.500],
        [0.875, 0.250],
        [0.625, 0.250],
        [0.625, 0.000],
        [1.000, 0.000],
    ]
)
TEE.flags.writeable = False


def _as_profile(pts) -> np.ndarray:
    pts = np.asarray(pts, dtype=np.float64)
    if pts.ndim != 2 or pts.shape[1] != 2 or len(pts) < 2:
        raise ValueError(
            f"a profile is an (N, 2) array of N >= 2 points, got shape {pts.shape}"
        )
    if not np.all(np.isfinite(pts)):
        raise ValueError("profile points must be finite")
    return pts


def profile_lengths(pts) -> np.ndarray:
    """Listing 14.25: the accumulated length from the first point to each point.

    Parameters
    ----------
    pts : (N, 2) float64

    Returns
    -------
    (N,) float64
        ``result[0] = 0``, ``result[i] = result[i-1] + |pts[i] - pts[i-1]|``.

    Examples
    --------
    >>> profile_lengths(TEE).tolist()
    [0.0, 0.375, 0.625, 0.875, 1.125, 1.875, 2.125, 2.375, 2.625, 3.0]
    """
    pts = _as_profile(pts)
    steps = np.linalg.norm(np.diff(pts, axis=0), axis=1)
    return np.concatenate([[0.0], np.cumsum(steps)])


def normalized_lengths(lengths) -> np.ndarray:
    """Listing 14.26: lengths divided by the total (the last element), so 0 to 1.

    Parameters
    ----------
    lengths : (N,) float64, nondecreasing, last element > 0

    Returns
    -------
    (N,) float64

    Raises
    ------
    ValueError
        If the total length is not > 0 (every point of the profile is the same).

    Examples
    --------
    >>> normalized_lengths([0.0, 1.0, 4.0]).tolist()
    [0.0, 0.25, 1.0]
    """
    lengths = np.asarray(lengths, dtype=np.float64)
    if lengths.ndim != 1 or len(lengths) < 2:
        raise ValueError(f"lengths must be an (N,) array with N >= 2, got {lengths.shape}")
    total_length = lengths[-1]
    if not (np.isfinite(total_length) and total_length > 0.0):
        raise ValueError(
            f"the profile's total length is {total_length}: it must be > 0 "
            "(a profile needs at least two distinct points)"
        )
    result = lengths / total_length
    result[0] = 0.0
    return result


def _check_knots(t: np.ndarray) -> None:
    steps = np.diff(t)
    bad = np.flatnonzero(~(steps > 0.0))
    if len(bad):
        i = int(bad[0])
        raise ValueError(
            f"profile segment {i} -> {i + 1} has zero length (t[{i}] = t[{i + 1}] = {t[i]}): "
            "remove the repeated point (the Handbook asserts on a duplicated t value)"
        )


def point_along_profile(distance, profile, t, repeat=1.0) -> np.ndarray:
    """Listing 14.27: the point at fraction ``distance`` along a segmented profile.

    ``dist = frac(distance * repeat)``; the segment i is the first with
    ``t[i-1] <= dist <= t[i]``, the point is ``lerp(profile[i-1], profile[i],
    (dist - t[i-1]) / (t[i] - t[i-1]))``, and when ``repeat != 1`` it is divided by
    ``repeat`` and its x offset by ``floor(distance * repeat) / repeat``.

    Parameters
    ----------
    distance : (n,) float64
    profile : (N, 2) float64
    t : (N,) float64
        Strictly increasing from 0 to 1 (:func:`normalized_lengths`).
    repeat : float > 0

    Returns
    -------
    (n, 2) float64

    Raises
    ------
    ValueError
        If ``t`` repeats a value (a zero-length segment) or ``repeat <= 0``.

    Examples
    --------
    >>> t = normalized_lengths(profile_lengths(TEE))
    >>> point_along_profile(np.array([0.25, 0.5, 1.0]), TEE, t).round(12).tolist()
    [[0.25, 0.25], [0.5, 0.5], [0.0, 0.0]]
    >>> point_along_profile(np.array([0.75]), TEE, t, repeat=2.0).tolist()
    [[0.75, 0.25]]
    """
    profile = _as_profile(profile)
    t = np.asarray(t, dtype=np.float64)
    if t.shape != (len(profile),):
        raise ValueError(f"t has shape {t.shape}, expected ({len(profile)},) like the profile")
    _check_knots(t)
    repeat = float(repeat)
    if not (np.isfinite(repeat) and repeat > 0.0):
        raise ValueError(f"repeat must be a finite number > 0, got {repeat}")
    distance = np.asarray(distance, dtype=np.float64)

    dist = frac(distance * repeat)
    # first i >= 1 with t[i-1] <= dist <= t[i] (the Handbook's linear search)
    i = np.clip(np.searchsorted(t, dist, side="left"), 1, len(t) - 1)
    segment_fraction = (dist - t[i - 1]) / (t[i] - t[i - 1])
    result = profile[i - 1] + segment_fraction[..., None] * (profile[i] - profile[i - 1])

    if repeat != 1.0:
        offset = np.floor(distance * repeat) / repeat
        result = result / repeat
        result[..., 0] += offset
    return result


def displace_with_profile(profile, t=None, uv_index=0, repeat=1.0) -> Field:
    """Listing 14.28: displacement by a segmented profile in u or v.

    ``f = frac(texture_coordinate[uv_index])``, ``p = point_along_profile(f, profile, t,
    repeat)`` and the vector is ``modify_normal(f, p, tangent)`` with the tangent in u
    or v.  uv outside [0, 1] and negative uv repeat the profile; uv = 1 is the profile's
    start, like uv = 0 (``frac(1) = 0``, as in MDL).

    Parameters
    ----------
    profile : (N, 2) float64, N >= 2
        x = run, y = height; no zero-length segments.
    t : (N,) float64, optional
        Normalized lengths; computed once here from the profile when omitted.
    uv_index : int or str
        0 / "along_u" or 1 / "along_v".
    repeat : float > 0

    Returns
    -------
    Field
        With the knots ``t`` (mapped through ``repeat``) in the chosen direction.

    Raises
    ------
    ValueError
        On a zero-length segment (the Handbook asserts), a bad shape or ``repeat <= 0``.

    Examples
    --------
    >>> from displacement.surfaces import UnitSquare
    >>> s = UnitSquare().state_at_uv(np.array([[0.25, 0.5]]))
    >>> displace_with_profile(TEE)(s).round(12).tolist()
    [[0.0, 0.0, 0.25]]
    >>> displace_with_profile([[0, 0], [0.5, 0], [0.5, 0], [1, 0]])  # doctest: +ELLIPSIS
    Traceback (most recent call last):
    ...
    ValueError: profile segment 1 -> 2 has zero length (t[1] = t[2] = 0.5): remove ...
    """
    profile = _as_profile(profile).copy()
    if t is None:
        t = normalized_lengths(profile_lengths(profile))
    t = np.array(t, dtype=np.float64)
    if t.shape != (len(profile),):
        raise ValueError(f"t has shape {t.shape}, expected ({len(profile)},) like the profile")
    _check_knots(t)
    index = displacement_direction(uv_index)
    repeat = float(repeat)
    if not (np.isfinite(repeat) and repeat > 0.0):
        raise ValueError(f"repeat must be a finite number > 0, got {repeat}")
    profile.flags.writeable = False
    t.flags.writeable = False

    def function(state: ShadingState) -> np.ndarray:
        f = frac(state.uv[:, index])
        tangent = state.tangent_u if index == 0 else state.tangent_v
        profile_point = point_along_profile(f, profile, t, repeat)
        return modify_normal(f, profile_point, tangent, state.normal)

    k = repeat_knots(t, repeat)
    knots = (k, None) if index == 0 else (None, k)
    return Field(
        function, knots, "displace_with_profile",
        {"profile": profile, "uv_index": index, "repeat": repeat},
    )


def tee_displacement(uv_index=0, repeat=1.0) -> Field:
    """Listing 14.30's displacement: ``displace_with_profile(tee, t, uv_index, repeat)``."""
    field = displace_with_profile(TEE, None, uv_index, repeat)
    return Field(
        field.function, field.uv_knots, "tee_displacement",
        {"uv_index": field.parameters["uv_index"], "repeat": float(repeat)},
    )


def scale_component(v, scale, index) -> np.ndarray:
    """Listing 14.29: ``v`` with component ``index`` multiplied by ``scale[N-1]``.

    Used to scale a grid count by a profile's total length so texture cells keep their
    proportions on the stretched surface.

    Parameters
    ----------
    v : float or (2,) float64
    scale : (N,) float64
        Accumulated lengths (:func:`profile_lengths`); the last is the total.
    index : int or str
        0 / "along_u" or 1 / "along_v".

    Returns
    -------
    (2,) float64

    Examples
    --------
    >>> scale_component((4.0, 4.0), profile_lengths(TEE), 0).tolist()
    [12.0, 4.0]
    """
    result = np.broadcast_to(np.asarray(v, dtype=np.float64), (2,)).copy()
    scale = np.asarray(scale, dtype=np.float64)
    result[displacement_direction(index)] *= scale[-1]
    return result
