"""The displacement-field base: a callable of shading state with the uv knots a dicer needs.

A displacement field is MDL's ``material_geometry.displacement``: a function of the
shading state that returns an object-space vector per point, never normalized (its
direction is the direction of motion and its length the distance).  Here every field is
a :class:`Field`: ``field(state) -> (n, 3) float64`` plus ``uv_knots``, the texture
coordinates in [0, 1] where the field has breakpoints (creases) so the tessellator can
put vertices exactly there.

The registry :data:`FIELDS` maps the Handbook's names to the factories that build
fields from the Handbook's parameters (``FIELDS["raise"](scale=0.2)``); it is filled
lazily, on first access, so that the field modules can import :class:`Field` from here.

Parameters that MDL declares varying (not ``uniform``) are accepted as a constant or a
callable of the state (``DESIGN.md``: "parameters are constants or functions of state");
:func:`varying` evaluates either.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from displacement.state import ShadingState

__all__ = [
    "Field",
    "FIELDS",
    "frac",
    "float2",
    "varying",
    "repeat_knots",
    "displacement_direction",
    "constant",
]

Knots = tuple[np.ndarray | None, np.ndarray | None]


def frac(x):
    """MDL's ``math::frac``: the positive fractional part ``x - floor(x)``.

    Negative inputs wrap into [0, 1) (``frac(-0.25) = 0.75``), so a texture coordinate
    outside [0, 1] repeats the pattern.  A tiny negative ``x`` (|x| below half an ULP of
    1) rounds to exactly 1.0; every user in this package accepts 1.0.

    Parameters
    ----------
    x : float or (...) float64

    Returns
    -------
    float or (...) float64, in [0, 1]

    Examples
    --------
    >>> frac(np.array([2.75, -0.25, 1.0, -3.0])).tolist()
    [0.75, 0.75, 0.0, 0.0]
    """
    x = np.asarray(x, dtype=np.float64)
    return x - np.floor(x)


def float2(value, name: str) -> np.ndarray:
    """A uniform ``float2`` argument: a scalar (MDL's ``float2(x)``) or two finite numbers.

    Examples
    --------
    >>> float2(3, "repeat").tolist(), float2((1, 2), "scale").tolist()
    ([3.0, 3.0], [1.0, 2.0])
    """
    arr = np.asarray(value, dtype=np.float64)
    if arr.ndim == 0:
        arr = np.full(2, float(arr))
    if arr.shape != (2,) or not np.all(np.isfinite(arr)):
        raise ValueError(f"{name} must be a float2: one or two finite numbers, got {value!r}")
    return arr


def varying(value: Any, state: ShadingState) -> np.ndarray:
    """Evaluate a varying parameter: a constant, an array of one value per point, or a
    callable ``state -> (n,)``.

    Parameters
    ----------
    value : float, (n,) array_like or callable
    state : ShadingState with n points

    Returns
    -------
    (n,) float64

    Examples
    --------
    >>> from displacement.surfaces import UnitSquare
    >>> s = UnitSquare().state_at_uv(np.array([[0.2, 0.0], [0.6, 1.0]]))
    >>> varying(0.5, s).tolist(), varying(lambda st: st.uv[:, 0], s).tolist()
    ([0.5, 0.5], [0.2, 0.6])
    """
    n = len(state)
    out = value(state) if callable(value) else value
    out = np.asarray(out, dtype=np.float64)
    if out.ndim > 1 or (out.ndim == 1 and out.shape != (n,)):
        raise ValueError(
            f"a varying parameter must be a scalar or have shape ({n},), got {out.shape}"
        )
    return np.broadcast_to(out, (n,))


def repeat_knots(t: np.ndarray, repeat: float) -> np.ndarray:
    """Knots ``t`` of a profile on [0, 1] mapped through ``frac(s * repeat)``.

    With ``repeat = r`` the profile parameter is ``frac(s r)``, so each knot ``t`` of
    the profile appears at ``s = (t + k) / r`` for every whole ``k``; the values in
    [0, 1] are returned sorted and without duplicates (``t = 1`` of copy ``k`` is ``t = 0``
    of copy ``k + 1``).

    Parameters
    ----------
    t : (N,) float64 in [0, 1]
    repeat : float > 0

    Returns
    -------
    (m,) float64, strictly increasing, in [0, 1]

    Examples
    --------
    >>> repeat_knots(np.array([0.0, 0.5, 1.0]), 2).tolist()
    [0.0, 0.25, 0.5, 0.75, 1.0]
    >>> repeat_knots(np.array([0.0, 1.0]), 1.5).tolist()
    [0.0, 0.6666666666666666]
    """
    t = np.asarray(t, dtype=np.float64)
    repeat = float(repeat)
    if not (np.isfinite(repeat) and repeat > 0):
        raise ValueError(f"repeat must be a finite number > 0, got {repeat}")
    if repeat == 1.0:
        s = t
    else:
        k = np.arange(int(np.ceil(repeat)) + 1, dtype=np.float64)
        s = ((t[None, :] + k[:, None]) / repeat).ravel()
    s = np.unique(s[(s >= 0.0) & (s <= 1.0)])
    # the repeat boundaries s = k / r are creases too (frac restarts there)
    if repeat != 1.0:
        s = np.unique(np.concatenate([s, np.arange(int(np.floor(repeat)) + 1) / repeat]))
        s = s[s <= 1.0]
    return s


def displacement_direction(direction: str | int) -> int:
    """Listing 15.7's ``displacement_direction`` enum as a uv index (0 = u, 1 = v).

    Parameters
    ----------
    direction : "along_u", "along_v", 0 or 1

    Examples
    --------
    >>> displacement_direction("along_u"), displacement_direction("along_v")
    (0, 1)
    """
    if isinstance(direction, str):
        index = {"along_u": 0, "along_v": 1}.get(direction)
    elif isinstance(direction, int | np.integer) and not isinstance(direction, bool):
        index = int(direction) if direction in (0, 1) else None
    else:
        index = None
    if index is None:
        raise ValueError(
            f"direction must be 'along_u' or 'along_v' (or uv index 0 or 1), got {direction!r}"
        )
    return index


@dataclass(frozen=True, eq=False)
class Field:
    """A displacement field: ``field(state) -> (n, 3) float64`` object-space vectors.

    Parameters
    ----------
    function : callable ShadingState -> (n, 3) float64
        The per-point displacement (MDL's ``material_geometry.displacement``).
    uv_knots : (u_knots, v_knots)
        Sorted texture coordinates in [0, 1] where the field has breakpoints in u and
        in v, or None in a direction without any.  The dicer places vertices there.
    name : str
        The Handbook's name of the function or material the field comes from.
    parameters : dict
        The arguments the factory was called with (for display and scene files).
    """

    function: Callable[[ShadingState], np.ndarray]
    uv_knots: Knots = (None, None)
    name: str = ""
    parameters: dict = field(default_factory=dict)

    def __call__(self, state: ShadingState) -> np.ndarray:
        """Displacement vectors, shape (n, 3), one row per point of ``state``."""
        result = np.asarray(self.function(state), dtype=np.float64)
        n = len(state)
        if result.shape != (n, 3):
            result = np.broadcast_to(result, (n, 3)).copy()
        return result

    def __repr__(self) -> str:
        args = ", ".join(f"{k}={v!r}" for k, v in self.parameters.items())
        return f"Field({self.name}({args}))"


def constant(displacement=(0.0, 0.0, 0.0)) -> Field:
    """The constant field: every point moves by the same vector (a translation).

    Listing 14.7's ``vector_displacement`` default, ``float3(0.0)``, is the zero field.

    Parameters
    ----------
    displacement : (3,) array_like
        Object-space vector.

    Examples
    --------
    >>> from displacement.surfaces import UnitSquare
    >>> s = UnitSquare().state_at_uv(np.array([[0.5, 0.5]]))
    >>> constant((0.0, 0.0, 0.25))(s).tolist()
    [[0.0, 0.0, 0.25]]
    """
    vector = np.asarray(displacement, dtype=np.float64)
    if vector.shape != (3,) or not np.all(np.isfinite(vector)):
        raise ValueError(f"displacement must be 3 finite numbers, got {displacement!r}")
    vector = vector.copy()
    vector.flags.writeable = False

    def function(state: ShadingState) -> np.ndarray:
        return np.broadcast_to(vector, (len(state), 3)).copy()

    return Field(function, (None, None), "constant", {"displacement": tuple(vector)})


def _build_registry() -> dict[str, Callable[..., Field]]:
    from displacement import bubble, heightmap, profile, pwc_fields, vector, waves

    return {
        "constant": constant,
        "vector_displacement": constant,
        # chapter 12
        "waves_as_displacement": waves.waves_as_displacement,
        "waver": waves.waves_as_displacement,
        "waves": waves.waves,
        "glossy_waves": waves.waves,
        "diffuse_weave": heightmap.diffuse_weave,
        "weave": heightmap.diffuse_weave,
        # chapter 14.1-14.2
        "move_up": vector.move_up,
        "raise": vector.raise_,
        "triangle_displacement": vector.triangle_displacement,
        "triangle": vector.triangle,
        "circle_linear_vector": vector.circle_linear_vector,
        "circle_linear": vector.circle_linear,
        "circle_nonlinear_vector": vector.circle_nonlinear_vector,
        "circle_nonlinear": vector.circle_nonlinear,
        # chapter 14.3
        "displace_with_bubble": bubble.displace_with_bubble,
        "bubble": bubble.bubble,
        # chapter 14.4-14.5
        "displace_with_profile": profile.displace_with_profile,
        "tee_displacement": profile.tee_displacement,
        # chapter 15
        "displace_with_pwc": pwc_fields.displace_with_pwc,
        "pwc_angular_displace": pwc_fields.pwc_angular_displace,
        "radial_pwc": pwc_fields.pwc_angular_displace,
        "double_pwc": pwc_fields.double_pwc,
    }


_REGISTRY: dict[str, Callable[..., Field]] | None = None

#: Handbook name -> field factory (``FIELDS["raise"] is vector.raise_``), built on
#: first access by the module ``__getattr__`` below.
FIELDS: dict[str, Callable[..., Field]]


def __getattr__(name: str):
    # FIELDS is built on first access: the field modules import Field from this module.
    global _REGISTRY
    if name == "FIELDS":
        if _REGISTRY is None:
            _REGISTRY = _build_registry()
        return _REGISTRY
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
