"""Chapter 12 of the MDL Handbook: sine waves in uv as displacement along the normal.

The small functions :func:`fit` (Listing 12.1), :func:`sinusoid` (12.2) and
:func:`uv_wave` (12.3) are pure vectorized functions of arrays, reused by the renderer's
function library.  :func:`waves_as_displacement` (12.5) and :func:`waves` (12.7) build
the displacement fields of those materials; :func:`waves_tint` is the tint that
:func:`waves` shows instead when ``use_displacement`` is false.
"""

from __future__ import annotations

import math

import numpy as np

from displacement.fields import Field, float2, frac
from displacement.state import ShadingState

__all__ = [
    "fit",
    "sinusoid",
    "sinusoid2",
    "uv_wave",
    "waves_as_displacement",
    "waves",
    "waves_tint",
]


def fit(v, old_min, old_max, new_min, new_max):
    """Listing 12.1: map ``v`` from [old_min, old_max] to [new_min, new_max] linearly.

    Values outside the old range extrapolate (no clamping), as in the Handbook.

    Parameters
    ----------
    v, old_min, old_max, new_min, new_max : float or (...) float64, broadcastable

    Returns
    -------
    float or (...) float64

    Raises
    ------
    ValueError
        If ``old_min == old_max`` anywhere (the source range is empty, the Handbook's
        division would be by zero).

    Examples
    --------
    >>> float(fit(0.25, 0.0, 1.0, -1.0, 1.0))
    -0.5
    >>> fit(np.array([0.0, 0.5, 2.0]), 0.0, 0.5, 0.0, 10.0).tolist()
    [0.0, 10.0, 40.0]
    >>> fit(1.0, 2.0, 2.0, 0.0, 1.0)
    Traceback (most recent call last):
    ...
    ValueError: fit: old_min == old_max (2.0); the original range must not be empty
    """
    v = np.asarray(v, dtype=np.float64)
    old_min = np.asarray(old_min, dtype=np.float64)
    old_max = np.asarray(old_max, dtype=np.float64)
    span = old_max - old_min
    if np.any(span == 0.0):
        bad = np.broadcast_to(old_min, span.shape)[span == 0.0]
        raise ValueError(
            f"fit: old_min == old_max ({float(np.ravel(bad)[0])}); "
            "the original range must not be empty"
        )
    scale = (v - old_min) / span
    return new_min + scale * (np.asarray(new_max, dtype=np.float64) - new_min)


def sinusoid(f, frequency=1.0, minval=-1.0, maxval=1.0):
    """Listing 12.2: one sine period per unit of ``frac(f)``, times ``frequency``,
    fitted from [-1, 1] to [minval, maxval].

    Parameters
    ----------
    f : float or (...) float64
        Input; only its fractional part counts (so negative values wrap).
    frequency, minval, maxval : float or (...) float64, broadcastable to ``f``

    Returns
    -------
    float or (...) float64

    Examples
    --------
    >>> sinusoid(np.array([0.0, 0.25, 0.75, 1.25, -0.75]), 1.0, 0.0, 1.0).round(12).tolist()
    [0.5, 1.0, 0.0, 1.0, 1.0]
    """
    fraction = frac(f)                     # fractional component
    angle = fraction * (2.0 * math.pi)     # scale input to a single period
    scaled = angle * np.asarray(frequency, dtype=np.float64)  # multiple periods
    sine_value = np.sin(scaled)
    return fit(sine_value, -1.0, 1.0, minval, maxval)


def sinusoid2(f, frequency=1.0, minval=-1.0, maxval=1.0):
    """Listing 12.6: :func:`sinusoid` that returns 0.0 where ``frequency == 0``.

    Note that the Handbook returns 0.0, not ``fit(0, -1, 1, minval, maxval)``, so this
    differs from :func:`sinusoid` at zero frequency unless ``minval = -maxval``.

    Examples
    --------
    >>> sinusoid2(np.array([0.3, 0.3]), np.array([0.0, 1.0]), 0.0, 1.0).round(6).tolist()
    [0.0, 0.975528]
    """
    frequency = np.asarray(frequency, dtype=np.float64)
    return np.where(frequency == 0.0, 0.0, sinusoid(f, frequency, minval, maxval))




def uv_wave(uv, frequency=1.0, minval=-1.0, maxval=1.0):
    """Listing 12.3: ``sinusoid(u, ...) + sinusoid(v, ...)`` with float2 controls.

    Parameters
    ----------
    uv : (n, 2) float64 or ShadingState
        ``state::texture_coordinate(0).xy`` (a state's ``uv`` is used).
    frequency, minval, maxval : float or (2,) float64
        Per-component controls of the u and v sinusoids (a scalar means ``float2(x)``).

    Returns
    -------
    (n,) float64

    Examples
    --------
    >>> uv = np.array([[0.25, 0.0], [0.0, 0.25]])
    >>> uv_wave(uv, (1.0, 4.0), 0.0, (1.0, 0.5)).round(12).tolist()
    [1.25, 0.75]
    """
    if isinstance(uv, ShadingState):
        uv = uv.uv
    uv = np.asarray(uv, dtype=np.float64).reshape(-1, 2)
    frequency = float2(frequency, "frequency")
    minval = float2(minval, "minval")
    maxval = float2(maxval, "maxval")
    u_component = sinusoid(uv[:, 0], frequency[0], minval[0], maxval[0])
    v_component = sinusoid(uv[:, 1], frequency[1], minval[1], maxval[1])
    return u_component + v_component


def waves_as_displacement(frequency=1.0, distance=0.1) -> Field:
    """Listing 12.5's displacement: ``state::normal() * uv_wave(frequency, -distance, distance)``.

    Parameters
    ----------
    frequency : float or (2,) float64, uniform
        Sine periods per uv unit in u and in v (default ``float2(1.0)``).
    distance : float or (2,) float64, uniform
        Amplitude of the u and v waves (default ``float2(0.1)``); the displacement
        ranges over ±(distance.u + distance.v).

    Returns
    -------
    Field

    Examples
    --------
    >>> from displacement.surfaces import UnitSquare
    >>> s = UnitSquare().state_at_uv(np.array([[0.3, 0.0625], [0.5, 0.1875]]))
    >>> (waves_as_displacement((0.0, 4.0), (0.0, 0.1))(s).round(12) + 0.0).tolist()
    [[0.0, 0.0, 0.1], [0.0, 0.0, -0.1]]
    """
    frequency = float2(frequency, "frequency")
    distance = float2(distance, "distance")

    def function(state: ShadingState) -> np.ndarray:
        displacement_distance = uv_wave(state.uv, frequency, -distance, distance)
        return state.normal * displacement_distance[:, None]

    return Field(
        function, (None, None), "waves_as_displacement",
        {"frequency": tuple(frequency), "distance": tuple(distance)},
    )


def waves(distance=0.1, frequency=1.0, use_displacement: bool = True) -> Field:
    """Listing 12.7's displacement: as :func:`waves_as_displacement`, or the zero field
    when ``use_displacement`` is false (the level-of-detail switch of section 12.2).

    Parameters
    ----------
    distance, frequency : float or (2,) float64, uniform
        As in :func:`waves_as_displacement` (note the Handbook's parameter order).
    use_displacement : bool
        False gives ``float3(0)`` everywhere; the look moves to :func:`waves_tint`.

    Examples
    --------
    >>> from displacement.surfaces import UnitSquare
    >>> s = UnitSquare().state_at_uv(np.array([[0.3, 0.0625]]))
    >>> waves((0.0, 0.1), (0.0, 4.0), use_displacement=False)(s).tolist()
    [[0.0, 0.0, 0.0]]
    """
    distance = float2(distance, "distance")
    frequency = float2(frequency, "frequency")
    use_displacement = bool(use_displacement)

    if use_displacement:
        def function(state: ShadingState) -> np.ndarray:
            displacement_distance = uv_wave(state.uv, frequency, -distance, distance)
            return state.normal * displacement_distance[:, None]
    else:
        def function(state: ShadingState) -> np.ndarray:
            return np.zeros((len(state), 3))

    return Field(
        function, (None, None), "waves",
        {"distance": tuple(distance), "frequency": tuple(frequency),
         "use_displacement": use_displacement},
    )


def waves_tint(uv, tint=0.7, frequency=1.0, use_displacement: bool = True) -> np.ndarray:
    """Listing 12.7's ``modified_tint``: ``tint`` when displacing, else
    ``tint * uv_wave(frequency, float2(0.1), float2(0.5))``.

    Parameters
    ----------
    uv : (n, 2) float64 or ShadingState
    tint : float or (3,) float64
        Linear RGB (a scalar means ``color(x)``).
    frequency : float or (2,) float64
    use_displacement : bool

    Returns
    -------
    (n, 3) float64

    Examples
    --------
    >>> waves_tint(np.array([[0.25, 0.25]]), 1.0, 1.0, False).round(12).tolist()
    [[1.0, 1.0, 1.0]]
    """
    if isinstance(uv, ShadingState):
        uv = uv.uv
    uv = np.asarray(uv, dtype=np.float64).reshape(-1, 2)
    tint = np.broadcast_to(np.asarray(tint, dtype=np.float64), (3,))
    if use_displacement:
        return np.broadcast_to(tint, (len(uv), 3)).copy()
    scale = uv_wave(uv, frequency, 0.1, 0.5)
    return tint[None, :] * scale[:, None]
