"""Bump and normal mapping (Handbook chapter 13): normals perturbed by uv, height or normal maps.

Every function takes a :class:`~displacement.state.ShadingState` of n points and returns
(n, 3) unit normals in object space, as MDL's ``material_geometry.normal`` expects.

The Handbook's functions are here under their own names and do what its listings do:

* :func:`fractional_uv` (Listing 13.1) and :func:`round_bump_normal` (Listing 13.5);
* the height-map normal of section 13.5: :func:`nearby_texture_differences`
  (Listing 13.9), :func:`bend_normal` (13.10), :func:`modify_normal_from_texture`
  (13.11);
* normal maps: :func:`texture_2d_lookup_float3` (13.15), :func:`bump_normal` (13.16),
  :func:`color_from_normal` (13.17), :func:`normal_as_color` (13.18).

Two additions:

* :func:`height_map_normal`, a more accurate height-map normal: central differences one
  texel either side with the texel-correct scale, giving the normal of the surface whose
  height is ``height_scale * texture value``.  The Handbook's
  :func:`modify_normal_from_texture` uses a forward difference and averages the u- and
  v-bent normals; for a height field that varies along u only, that average tilts the
  normal by exactly *half* the angle of the forward-difference slope (the sum of two unit
  vectors bisects them), so its bumps look half as steep as the same height would be
  when displaced.
* the **horizon rule**.  A perturbed normal ``n`` must stay in the upper hemisphere of
  the unperturbed normal ``N = state.normal`` (the geometric horizon of the surface as
  far as displacement knows it), or light arriving from above would shade it black.
  Where ``n . N < min_cos`` (:data:`HORIZON_MIN_COS` = 0.01, about 0.57 degrees above the
  horizon), ``n`` is rotated towards ``N`` in the plane of ``N`` and ``n`` until
  ``n . N = min_cos``: ``n' = min_cos N + sqrt(1 - min_cos^2) t`` with ``t`` the unit
  tangential part of ``n``.  This is the view-independent form of Cycles'
  ``ensure_valid_reflection`` (which rotates in the same plane but stops where the mirror
  direction clears the horizon, something only the renderer knows) and the same idea as
  Arnold's and Cycles' bending back of normals.  If ``n`` has no tangential part (it is
  ``-N``) or is the zero vector, the result is ``N`` itself.  Every function takes
  ``horizon=`` to change ``min_cos`` or, with ``None``, to switch the rule off (results
  are then the Handbook's exactly, still never NaN: a zero vector normalizes to ``N``).

Normal-map encoding: colour ``c`` in [0, 1] stores ``n = 2 c - 1`` (red = x along
``texture_tangent_u``, green = y along ``texture_tangent_v``, blue = z along the normal).
The OpenGL convention (green = +v, the Handbook's, Blender's, glTF's) is the default;
DirectX maps (Unreal) store -y: pass ``convention="directx"``.
"""

from __future__ import annotations

from typing import NamedTuple

import numpy as np

from displacement.fields import frac, varying
from displacement.state import ShadingState
from displacement.textures import Texture, texture_2d_sample

__all__ = [
    "HORIZON_MIN_COS",
    "CONVENTIONS",
    "clamp_to_horizon",
    "fractional_uv",
    "round_bump_normal",
    "nearby_texture_differences",
    "bend_normal",
    "modify_normal_from_texture",
    "height_map_normal",
    "texture_2d_lookup_float3",
    "bump_normal",
    "encode_normal_colors",
    "decode_normal_colors",
    "normal_to_tangent_space",
    "color_from_normal",
    "normal_as_color",
    "NormalAsColor",
]

#: Smallest cosine between a perturbed normal and ``state.normal`` (see module docstring).
HORIZON_MIN_COS = 0.01

#: Green-channel conventions of normal maps: OpenGL stores +y (up = +v), DirectX -y.
CONVENTIONS = ("opengl", "directx")

_Horizon = float | None


# ---------------------------------------------------------------------------
# vector helpers


def _dot(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    return np.einsum("ij,ij->i", a, b)


def _normalize(v: np.ndarray, fallback: np.ndarray) -> np.ndarray:
    """Unit vectors along rows of ``v``; rows that are zero (or not finite) get ``fallback``.

    Rows are first divided by their largest component so that huge inputs (a bump scale
    of 1e300) do not overflow the length.
    """
    v = np.asarray(v, dtype=np.float64)
    m = np.max(np.abs(v), axis=1)
    ok = np.isfinite(m) & (m > 0.0)
    safe_m = np.where(ok, m, 1.0)
    w = v / safe_m[:, None]
    length = np.sqrt(_dot(w, w))
    out = w / np.where(ok, length, 1.0)[:, None]
    return np.where(ok[:, None], out, fallback)


def _perpendicular(reference: np.ndarray, hint: np.ndarray) -> np.ndarray:
    """Unit vectors perpendicular to ``reference``: ``hint`` made orthogonal, or any."""
    t = hint - _dot(hint, reference)[:, None] * reference
    # an axis least aligned with the reference, for rows where the hint is parallel
    axis = np.eye(3)[np.argmin(np.abs(reference), axis=1)]
    other = np.cross(reference, axis)
    return _normalize(t, _normalize(other, np.broadcast_to([1.0, 0.0, 0.0], t.shape)))


def clamp_to_horizon(
    normal: np.ndarray, reference: np.ndarray, min_cos: float = HORIZON_MIN_COS
) -> np.ndarray:
    """Bend unit normals that fall below the horizon of ``reference`` back above it.

    Parameters
    ----------
    normal : (n, 3) float64
        Perturbed unit normals (zero rows are replaced by ``reference``).
    reference : (n, 3) float64
        Unit normals of the unperturbed surface.
    min_cos : float in [0, 1)
        Rows with ``normal . reference < min_cos`` are rotated towards ``reference``
        in their common plane until the cosine equals ``min_cos``.

    Returns
    -------
    (n, 3) float64 unit vectors with ``. reference >= min_cos`` (up to rounding).

    Examples
    --------
    >>> r = np.array([[0.0, 0.0, 1.0]] * 3)
    >>> n = np.array([[0.6, 0.0, -0.8], [0.0, 0.0, -1.0], [0.0, 0.6, 0.8]])
    >>> clamp_to_horizon(n, r, 0.0).round(12).tolist()
    [[1.0, 0.0, 0.0], [0.0, 0.0, 1.0], [0.0, 0.6, 0.8]]
    """
    if not (0.0 <= min_cos < 1.0):
        raise ValueError(f"horizon min_cos must be in [0, 1), got {min_cos}")
    reference = np.asarray(reference, dtype=np.float64)
    n = _normalize(normal, reference)
    c = _dot(n, reference)
    tangential = n - c[:, None] * reference
    t_len = np.sqrt(_dot(tangential, tangential))
    has_t = t_len > 1e-12
    t = tangential / np.where(has_t, t_len, 1.0)[:, None]
    # project once more: for n nearly opposite to reference, n - c reference cancels and
    # keeps a component along reference of the order of rounding over t_len (Gram-Schmidt:
    # twice is enough)
    t = t - _dot(t, reference)[:, None] * reference
    t = t / np.where(has_t, np.sqrt(_dot(t, t)), 1.0)[:, None]
    bent = min_cos * reference + np.sqrt(1.0 - min_cos * min_cos) * t
    bent = np.where(has_t[:, None], bent, reference)
    return np.where((c < min_cos)[:, None], bent, n)


def _finish(v: np.ndarray, state: ShadingState, horizon: _Horizon) -> np.ndarray:
    """Normalize (zero -> state.normal) and apply the horizon rule unless disabled."""
    n = _normalize(v, state.normal)
    if horizon is None:
        return n
    return clamp_to_horizon(n, state.normal, horizon)


def _float2(value, name: str, n: int, positive: bool = False) -> np.ndarray:
    a = np.asarray(value, dtype=np.float64)
    try:
        a = np.broadcast_to(a, (n, 2))
    except ValueError:
        raise ValueError(
            f"{name} must be a number, a float2 or (n, 2), got shape {a.shape}"
        ) from None
    if not np.all(np.isfinite(a)):
        raise ValueError(f"{name} must be finite, got {value!r}")
    if positive and np.any(a <= 0.0):
        raise ValueError(f"{name} must be > 0 in u and v, got {value!r}")
    return a


def _check_convention(convention: str) -> None:
    if convention not in CONVENTIONS:
        raise ValueError(
            f"convention must be 'opengl' (green = +v) or 'directx' (green = -v), "
            f"not {convention!r}"
        )


# ---------------------------------------------------------------------------
# 13.2-13.4: tiles and round bumps


def fractional_uv(state: ShadingState, u_scale=1.0, v_scale=1.0) -> np.ndarray:
    """Listing 13.1: ``float2(frac(u * u_scale), frac(v * v_scale))``.

    Parameters
    ----------
    state : ShadingState
    u_scale, v_scale : float or callable(state) -> (n,)

    Returns
    -------
    (n, 2) float64 in [0, 1]

    Examples
    --------
    >>> from displacement.surfaces import UnitSquare
    >>> s = UnitSquare().state_at_uv(np.array([[0.3, -0.1], [1.0, 0.55]]))
    >>> fractional_uv(s, 8, 4).round(12).tolist()
    [[0.4, 0.6], [0.0, 0.2]]
    """
    us = varying(u_scale, state)
    vs = varying(v_scale, state)
    return np.stack([frac(state.uv[:, 0] * us), frac(state.uv[:, 1] * vs)], axis=1)


def round_bump_normal(
    state: ShadingState,
    bump_scale=1.0,
    u_scale=1.0,
    v_scale=1.0,
    horizon: _Horizon = HORIZON_MIN_COS,
) -> np.ndarray:
    """Listing 13.5: spherical-cap bumps, one in each tile of ``fractional_uv``.

    Inside the circle of radius 0.5 about the tile centre (``distance <= 0.5``) the
    normal is ``normalize(N + bump_scale * (tangent_u * du + tangent_v * dv))`` with
    ``(du, dv) = uv - (0.5, 0.5)``; outside it is ``state::normal()``.  A negative
    ``bump_scale`` turns the bumps into dimples (Figure 13.16).

    Parameters
    ----------
    state : ShadingState
    bump_scale, u_scale, v_scale : float or callable(state) -> (n,)
    horizon : float or None
        See :func:`clamp_to_horizon`; only extreme bump scales (|bump_scale| > ~140 on
        an orthonormal frame) reach it.

    Returns
    -------
    (n, 3) float64 unit normals

    Examples
    --------
    >>> from displacement.surfaces import UnitSquare
    >>> s = UnitSquare().state_at_uv(np.array([[0.75, 0.5], [0.02, 0.02]]))
    >>> round_bump_normal(s, bump_scale=4.0).round(6).tolist()   # (1, 0, 1)/sqrt(2); outside
    [[0.707107, 0.0, 0.707107], [0.0, 0.0, 1.0]]
    """
    uv = fractional_uv(state, u_scale, v_scale)
    center_offset = uv - 0.5
    inside = np.hypot(center_offset[:, 0], center_offset[:, 1]) <= 0.5
    tangent_sum = (
        state.tangent_u * center_offset[:, :1] + state.tangent_v * center_offset[:, 1:]
    )
    bent_normal = state.normal + tangent_sum * varying(bump_scale, state)[:, None]
    result = _finish(bent_normal, state, horizon)
    return np.where(inside[:, None], result, state.normal)


# ---------------------------------------------------------------------------
# 13.5: normals from a height map


def nearby_texture_differences(
    state: ShadingState, texture: Texture, distance, texture_scale=(1.0, 1.0)
) -> np.ndarray:
    """Listing 13.9: forward differences of the averaged texture value in u and in v.

    Samples ``texture_2d_sample`` at the current uv, at ``uv + (distance[0], 0)`` and at
    ``uv + (0, distance[1])``.

    Parameters
    ----------
    state : ShadingState
    texture : Texture
    distance : float2 or (n, 2) float64
        Offsets in uv (texture-coordinate) units.
    texture_scale : float2
        Repetitions of the texture.

    Returns
    -------
    (n, 2) float64
        ``(u_value - center_value, v_value - center_value)``.
    """
    n = len(state)
    distance = _float2(distance, "distance", n)
    center_point = state.uv
    u_point = center_point + np.stack([distance[:, 0], np.zeros(n)], axis=1)
    v_point = center_point + np.stack([np.zeros(n), distance[:, 1]], axis=1)
    stacked = np.concatenate([center_point, u_point, v_point])
    scale = np.concatenate([_float2(texture_scale, "texture_scale", n)] * 3)
    values = texture_2d_sample(texture, scale, stacked).mean(axis=1)
    center_value, u_value, v_value = values[:n], values[n : 2 * n], values[2 * n :]
    return np.stack([u_value - center_value, v_value - center_value], axis=1)


def bend_normal(
    state: ShadingState,
    tangent: np.ndarray,
    distance,
    difference,
    horizon: _Horizon = HORIZON_MIN_COS,
) -> np.ndarray:
    """Listing 13.10: ``normalize(state::normal() * distance + tangent * -difference)``.

    Parameters
    ----------
    state : ShadingState
    tangent : (n, 3) float64
        ``texture_tangent_u`` or ``texture_tangent_v``.
    distance : float or (n,) float64
        Distance between the sample points (the run).
    difference : float or (n,) float64
        Difference of the sampled values (the rise).

    Returns
    -------
    (n, 3) float64 unit normals; ``distance = difference = 0`` gives ``state.normal``.

    Examples
    --------
    >>> from displacement.surfaces import UnitSquare
    >>> s = UnitSquare().state_at_uv(np.array([[0.5, 0.5]]))
    >>> bend_normal(s, s.tangent_u, 0.01, 0.01).round(6).tolist()     # a 45 degree rise
    [[-0.707107, 0.0, 0.707107]]
    """
    n = len(state)
    distance = np.broadcast_to(np.asarray(distance, dtype=np.float64), (n,))
    difference = np.broadcast_to(np.asarray(difference, dtype=np.float64), (n,))
    scaled_normal = state.normal * distance[:, None]
    bend_direction = np.asarray(tangent, dtype=np.float64) * -difference[:, None]
    return _finish(scaled_normal + bend_direction, state, horizon)


def modify_normal_from_texture(
    state: ShadingState,
    texture: Texture,
    pixel_distance=(1.0, 1.0),
    texture_scale=(1.0, 1.0),
    horizon: _Horizon = HORIZON_MIN_COS,
) -> np.ndarray:
    """Listing 13.11: the Handbook's height-map normal.

    ``texture_distance = pixel_distance / (float2(width, height) * texture_scale)``;
    the forward differences of :func:`nearby_texture_differences` bend the normal along
    u and along v (:func:`bend_normal`), and the result is ``normalize(u_bend +
    v_bend)``.  Texture values are heights in uv units (a value step of 1 over a uv
    distance of 1 is a 45 degree slope).  For a height varying in u only the result is
    tilted by exactly half the forward-difference slope angle (see the module notes);
    :func:`height_map_normal` gives the full slope.

    Parameters
    ----------
    state : ShadingState
    texture : Texture
    pixel_distance : float2 > 0
        Sample spacing in texels (1 = the neighbouring texel).
    texture_scale : float2 > 0
        Repetitions of the texture in u and v.
    horizon : float or None

    Returns
    -------
    (n, 3) float64 unit normals
    """
    n = len(state)
    pixel_distance = _float2(pixel_distance, "pixel_distance", n, positive=True)
    texture_scale = _float2(texture_scale, "texture_scale", n, positive=True)
    dimensions = np.array([texture.width, texture.height], dtype=np.float64)
    texture_distance = pixel_distance / (dimensions * texture_scale)
    difference = nearby_texture_differences(state, texture, texture_distance, texture_scale)
    u_bend = bend_normal(state, state.tangent_u, texture_distance[:, 0], difference[:, 0], None)
    v_bend = bend_normal(state, state.tangent_v, texture_distance[:, 1], difference[:, 1], None)
    return _finish(u_bend + v_bend, state, horizon)


def height_map_normal(
    state: ShadingState,
    texture: Texture,
    height_scale=1.0,
    texture_scale=(1.0, 1.0),
    uv_length=(1.0, 1.0),
    wrap: str = "repeat",
    horizon: _Horizon = HORIZON_MIN_COS,
) -> np.ndarray:
    """Normal of the surface ``P + height_scale * h(uv * texture_scale) * N``, from a height map.

    The more accurate variant of :func:`modify_normal_from_texture`: the slope of the
    averaged texture value ``h`` is a central difference one texel either side,
    ``dh/ds = (h(s + 1/W) - h(s - 1/W)) * W / 2`` (and likewise in t with H), which on
    the bilinearly filtered image is exact for linear ramps and second-order accurate for
    smooth heights.  The object-space gradient along ``tangent_u`` is ``g_u =
    height_scale * texture_scale_u * dh/ds / uv_length_u`` and the normal is
    ``normalize(N - g_u tangent_u - g_v tangent_v)`` (exact on an orthonormal frame,
    first order in the angle between the tangents otherwise).

    Parameters
    ----------
    state : ShadingState
    texture : Texture
        Channels are averaged, as the Handbook does.
    height_scale : float or callable(state) -> (n,)
        Object-space height of a texture value of 1 (may be negative: dents).
    texture_scale : float2 > 0
        Repetitions of the texture over the unit of uv.
    uv_length : float2 > 0
        Object-space length of a unit step in u and in v (``|dP/du|``, ``|dP/dv|``):
        1 on the unit square.
    wrap : {"repeat", "clamp", "mirrored_repeat"}
        Texture wrap mode; "repeat" for tiling maps.
    horizon : float or None

    Returns
    -------
    (n, 3) float64 unit normals

    Examples
    --------
    >>> from displacement.surfaces import UnitSquare
    >>> ramp = Texture(np.tile(np.linspace(0.0, 1.0, 9), (4, 1)))   # h rises 1 over 8/9 of u
    >>> s = UnitSquare().state_at_uv(np.array([[0.5, 0.5]]))
    >>> height_map_normal(s, ramp, height_scale=8 / 9, wrap="clamp").round(6).tolist()
    [[-0.707107, 0.0, 0.707107]]
    """
    n = len(state)
    texture_scale = _float2(texture_scale, "texture_scale", n, positive=True)
    uv_length = _float2(uv_length, "uv_length", n, positive=True)
    st = state.uv * texture_scale
    du = np.array([1.0 / texture.width, 0.0])
    dv = np.array([0.0, 1.0 / texture.height])
    pts = np.concatenate([st + du, st - du, st + dv, st - dv])
    h = texture.lookup(pts, wrap_u=wrap, wrap_v=wrap).mean(axis=1).reshape(4, n)
    dh_ds = (h[0] - h[1]) * (0.5 * texture.width)
    dh_dt = (h[2] - h[3]) * (0.5 * texture.height)
    scale = varying(height_scale, state)
    g_u = scale * texture_scale[:, 0] * dh_ds / uv_length[:, 0]
    g_v = scale * texture_scale[:, 1] * dh_dt / uv_length[:, 1]
    bent = state.normal - g_u[:, None] * state.tangent_u - g_v[:, None] * state.tangent_v
    return _finish(bent, state, horizon)


# ---------------------------------------------------------------------------
# 13.6: normal maps


def _fit(v, old_min, old_max, new_min, new_max):
    """Listing 13.14 ``fit``: map [old_min, old_max] linearly onto [new_min, new_max]."""
    if old_max == old_min:
        raise ValueError(
            f"sample_min and sample_max must differ (both {old_min}); they give the range "
            "of values stored in the texture"
        )
    scale = (v - old_min) / (old_max - old_min)
    return new_min + scale * (new_max - new_min)


def texture_2d_lookup_float3(
    state: ShadingState,
    texture: Texture,
    texture_scale=(1.0, 1.0),
    sample_min: float = 0.0,
    sample_max: float = 1.0,
    new_min: float = 0.0,
    new_max: float = 1.0,
) -> np.ndarray:
    """Listing 13.15: ``fit(tex::lookup_float3(texture, uv * texture_scale), ...)``.

    Parameters
    ----------
    state : ShadingState
    texture : Texture
    texture_scale : float2
        Multiplies ``state::texture_coordinate(0)``; the lookup repeats the image.
    sample_min, sample_max : float
        Range of the values stored in the texture (0 and 1 for 8/16-bit maps).
    new_min, new_max : float
        Range of the result.

    Returns
    -------
    (n, 3) float64

    Examples
    --------
    >>> from displacement.surfaces import UnitSquare
    >>> t = Texture(np.full((2, 2, 3), [0.5, 0.75, 1.0]))
    >>> s = UnitSquare().state_at_uv(np.array([[0.3, 0.3]]))
    >>> texture_2d_lookup_float3(s, t, 1.0, 0.0, 1.0, -1.0, 1.0).tolist()
    [[0.0, 0.5, 1.0]]
    """
    n = len(state)
    uv = state.uv * _float2(texture_scale, "texture_scale", n)
    sample = texture.lookup_float3(uv)
    return _fit(sample, sample_min, sample_max, new_min, new_max)


def bump_normal(
    state: ShadingState,
    texture: Texture,
    bump_scale=1.0,
    scale_vector_z: bool = True,
    texture_scale=(1.0, 1.0),
    sample_min: float = 0.0,
    sample_max: float = 1.0,
    convention: str = "opengl",
    horizon: _Horizon = HORIZON_MIN_COS,
) -> np.ndarray:
    """Listing 13.16: the normal from a tangent-space normal map.

    ``sample = texture_2d_lookup_float3(texture, texture_scale, sample_min, sample_max,
    -1, 1)``; the result is ``normalize(N * (scale_vector_z ? sample.z : 1) +
    tangent_u * sample.x * bump_scale + tangent_v * sample.y * bump_scale)``.

    Parameters
    ----------
    state : ShadingState
    texture : Texture
        The normal map (read linear, never sRGB-decoded).
    bump_scale : float or callable(state) -> (n,)
        0 flattens, 1 is the map as baked, negative inverts the relief.
    scale_vector_z : bool
        Scale the normal by the blue channel (Figure 13.35).
    texture_scale : float2
    sample_min, sample_max : float
        Stored value range; (0, 1) for the usual ``0.5 + 0.5 n`` encoding, (-1, 1) for
        float maps that store ``n`` itself.
    convention : {"opengl", "directx"}
        Green channel +v (OpenGL, the default) or -v (DirectX: y is negated).
    horizon : float or None

    Returns
    -------
    (n, 3) float64 unit normals

    Examples
    --------
    >>> from displacement.surfaces import UnitSquare
    >>> s = UnitSquare().state_at_uv(np.array([[0.5, 0.5]]))
    >>> t = Texture(np.full((1, 1, 3), [0.5 + 0.3, 0.5, 0.5 + 0.4]))   # n = (0.6, 0, 0.8)
    >>> bump_normal(s, t).round(6).tolist()
    [[0.6, 0.0, 0.8]]
    >>> bump_normal(s, t, bump_scale=0.0).round(6).tolist()
    [[0.0, 0.0, 1.0]]
    """
    _check_convention(convention)
    sample = texture_2d_lookup_float3(
        state, texture, texture_scale, sample_min, sample_max, -1.0, 1.0
    )
    if convention == "directx":
        sample[:, 1] = -sample[:, 1]
    scale = varying(bump_scale, state)[:, None]
    z = sample[:, 2:] if scale_vector_z else 1.0
    normal = state.normal * z
    tangent_u = state.tangent_u * sample[:, :1] * scale
    tangent_v = state.tangent_v * sample[:, 1:2] * scale
    return _finish(normal + tangent_u + tangent_v, state, horizon)


def encode_normal_colors(normal: np.ndarray, convention: str = "opengl") -> np.ndarray:
    """Colours ``0.5 + 0.5 n`` in [0, 1] for tangent-space unit normals (y negated for DirectX).

    Parameters
    ----------
    normal : (..., 3) float64
    convention : {"opengl", "directx"}

    Returns
    -------
    (..., 3) float64 in [0, 1]

    Examples
    --------
    >>> encode_normal_colors(np.array([0.6, 0.0, 0.8])).tolist()
    [0.8, 0.5, 0.9]
    >>> encode_normal_colors(np.array([0.0, 0.6, 0.8]), "directx").tolist()
    [0.5, 0.2, 0.9]
    """
    _check_convention(convention)
    n = np.array(normal, dtype=np.float64)
    if convention == "directx":
        n[..., 1] = -n[..., 1]
    return np.clip(0.5 + 0.5 * n, 0.0, 1.0)


def decode_normal_colors(colors: np.ndarray, convention: str = "opengl") -> np.ndarray:
    """Inverse of :func:`encode_normal_colors`: ``2 c - 1`` (y negated for DirectX), unnormalized.

    Examples
    --------
    >>> decode_normal_colors(np.array([0.5, 0.2, 0.9]), "directx").round(12).tolist()
    [0.0, 0.6, 0.8]
    """
    _check_convention(convention)
    n = 2.0 * np.asarray(colors, dtype=np.float64) - 1.0
    if convention == "directx":
        n[..., 1] = -n[..., 1]
    return n


def normal_to_tangent_space(state: ShadingState, normal: np.ndarray) -> np.ndarray:
    """Tangent-space components ``(x, y, z)`` of object-space normals (inverts ``bump_normal``).

    Solves ``x tangent_u + y tangent_v + z N = normal`` per point (the exact inverse of
    the decoding for ``bump_scale = 1`` and ``scale_vector_z = True``, whatever the
    angle between the tangents) and returns the unit vector ``(x, y, z)``; on an
    orthonormal frame these are the dot products.  A singular frame (parallel tangents)
    falls back to the dot products.

    Parameters
    ----------
    state : ShadingState
    normal : (n, 3) float64

    Returns
    -------
    (n, 3) float64 unit vectors

    Examples
    --------
    >>> from displacement.surfaces import UnitSquare
    >>> s = UnitSquare().state_at_uv(np.array([[0.5, 0.5]]))
    >>> normal_to_tangent_space(s, np.array([[0.0, -0.6, 0.8]])).round(12).tolist()
    [[0.0, -0.6, 0.8]]
    """
    normal = np.asarray(normal, dtype=np.float64)
    frame = np.stack([state.tangent_u, state.tangent_v, state.normal], axis=2)  # columns
    det = np.linalg.det(frame)
    ok = np.abs(det) > 1e-9
    dots = np.stack(
        [_dot(normal, state.tangent_u), _dot(normal, state.tangent_v), _dot(normal, state.normal)],
        axis=1,
    )
    coeffs = dots.copy()
    if np.any(ok):
        coeffs[ok] = np.linalg.solve(frame[ok], normal[ok][:, :, None])[:, :, 0]
    return _normalize(coeffs, np.broadcast_to([0.0, 0.0, 1.0], coeffs.shape))


# ---------------------------------------------------------------------------
# visualizing normals


def color_from_normal(
    normal: np.ndarray,
    normal_color_as_emission: bool = True,
    object_to_world: np.ndarray | None = None,
) -> np.ndarray:
    """Listing 13.17: a normal as a colour, ``0.5 + 0.5 n`` (divided by pi as emission).

    Parameters
    ----------
    normal : (n, 3) float64
        Normals in object (MDL internal) space.
    normal_color_as_emission : bool
        Divide by pi so the colour is a radiant exitance for ``diffuse_edf``.
    object_to_world : (3, 3) float64, optional
        The object's linear transform; normals are mapped by its inverse transpose, as
        ``state::transform_normal(coordinate_internal, coordinate_world, n)`` does.
        Default: the identity (object space is world space).

    Returns
    -------
    (n, 3) float64

    Examples
    --------
    >>> color_from_normal(np.array([[0.0, 0.0, 1.0]]), False).tolist()
    [[0.5, 0.5, 1.0]]
    """
    n = np.asarray(normal, dtype=np.float64)
    if object_to_world is not None:
        m = np.asarray(object_to_world, dtype=np.float64)
        if m.shape != (3, 3):
            raise ValueError(f"object_to_world must be a (3, 3) matrix, got {m.shape}")
        if abs(np.linalg.det(m)) < 1e-300:
            raise ValueError("object_to_world is singular; normals cannot be transformed")
        n = n @ np.linalg.inv(m)  # rows: (M^-T n)^T = n^T M^-1
    result = 0.5 + 0.5 * n
    if normal_color_as_emission:
        result = result / np.pi
    return result


class NormalAsColor(NamedTuple):
    """The parts of Listing 13.18's material: a diffuse tint and an emission intensity."""

    tint: np.ndarray
    """(n, 3) diffuse_reflection_bsdf tint (zero when the colour is emitted)."""
    intensity: np.ndarray
    """(n, 3) material_emission intensity for diffuse_edf (zero when reflected)."""


def normal_as_color(
    normal: np.ndarray, normal_color_as_emission: bool = True, object_to_world=None
) -> NormalAsColor:
    """Listing 13.18 ``normal_as_color``: show a normal as reflected or emitted colour.

    The material itself belongs to rendering; this returns the two values it plugs into
    ``df::diffuse_reflection_bsdf(tint)`` and ``material_emission(intensity)``.

    Examples
    --------
    >>> c = normal_as_color(np.array([[0.0, 0.0, 1.0]]), normal_color_as_emission=False)
    >>> c.tint.tolist(), c.intensity.tolist()
    ([[0.5, 0.5, 1.0]], [[0.0, 0.0, 0.0]])
    """
    color = color_from_normal(normal, normal_color_as_emission, object_to_world)
    zero = np.zeros_like(color)
    if normal_color_as_emission:
        return NormalAsColor(tint=zero, intensity=color)
    return NormalAsColor(tint=color, intensity=zero)
