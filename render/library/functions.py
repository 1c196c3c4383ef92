"""The function library as MDL calls: typed wrappers that return values usable as arguments.

In MDL a material argument can be a function call (``tint: grid_color(...)``,
``displacement: move_up(0.2)``).  Each function here takes the Handbook's parameters
(annotated with MDL types from :mod:`render.material`, so :mod:`render.expr` can check
calls) and returns a varying value: a :class:`~render.material.Varying` (or a
:class:`~displacement.fields.Field` for displacement vectors), a callable of the
shading state.  Varying arguments (callables) are evaluated per lane.

:data:`FUNCTIONS` maps MDL names (``"uv_wave"``, ``"state::normal"``) to them.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

import numpy as np

from displacement import bump, vector, waves
from displacement import textures as tex
from displacement.fields import FIELDS
from displacement.state import ShadingState
from render.library import grid as _grid
from render.library import noise as _noise
from render.library import patterns as _patterns
from render.library import space as _space
from render.library import uv as _uv
from render.library.resources import INVALID_TEXTURE
from render.material import (
    Bool,
    Color,
    DisplacementDirection,
    Float,
    Float2,
    Float3,
    Int,
    MappingMode,
    PwCurve,
    Texture2D,
    UniformBool,
    UniformFloat,
    UniformInt,
    Varying,
    evaluate,
)

__all__ = ["FUNCTIONS"]


def _texture(texture):
    return INVALID_TEXTURE if texture is None else texture


def _f(value, state, kind, name):
    return evaluate(value, state, kind, name)


# --- state:: ------------------------------------------------------------------


def state_normal() -> Float3:
    """``state::normal()``."""
    return Varying(lambda s: s.normal, "state::normal")


def state_position() -> Float3:
    """``state::position()`` (object space)."""
    return Varying(lambda s: s.position, "state::position")


def state_texture_coordinate(index: UniformInt = 0) -> Float3:
    """``state::texture_coordinate(index)``."""
    return Varying(lambda s: _space.texture_coordinate(s, index), "state::texture_coordinate",
                   {"index": index})


def state_texture_tangent_u(index: UniformInt = 0) -> Float3:
    """``state::texture_tangent_u(index)`` (zero for an index out of range, as MDL)."""
    return Varying(lambda s: s.tangent_u if index == 0 else np.zeros((len(s), 3)),
                   "state::texture_tangent_u", {"index": index})


def state_texture_tangent_v(index: UniformInt = 0) -> Float3:
    """``state::texture_tangent_v(index)``."""
    return Varying(lambda s: s.tangent_v if index == 0 else np.zeros((len(s), 3)),
                   "state::texture_tangent_v", {"index": index})


# --- chapters 9, 12, 14: scalar functions ---------------------------------------


def u(texture_space: UniformInt = 0) -> Float:
    """Listing 14.1."""
    return Varying(lambda s: _space.u(s, texture_space), "u", {"texture_space": texture_space})


def v(texture_space: UniformInt = 0) -> Float:
    """Listing 14.2."""
    return Varying(lambda s: _space.v(s, texture_space), "v", {"texture_space": texture_space})


def fit(v: Float, old_min: Float, old_max: Float, new_min: Float, new_max: Float) -> Float:
    """Listing 12.1."""
    args = {"v": v, "old_min": old_min, "old_max": old_max, "new_min": new_min, "new_max": new_max}
    return Varying(lambda s: waves.fit(*(_f(a, s, "float", k) for k, a in args.items())),
                   "fit", args)


def sinusoid(f: Float, frequency: Float = 1.0, minval: Float = -1.0, maxval: Float = 1.0) -> Float:
    """Listing 12.2."""
    args = {"f": f, "frequency": frequency, "minval": minval, "maxval": maxval}
    return Varying(lambda s: waves.sinusoid(*(_f(a, s, "float", k) for k, a in args.items())),
                   "sinusoid", args)


def uv_wave(frequency: Float2 = (1.0, 1.0), minval: Float2 = (-1.0, -1.0),
            maxval: Float2 = (1.0, 1.0)) -> Float:
    """Listing 12.3 (float2 controls; varying controls are evaluated per lane)."""
    args = {"frequency": frequency, "minval": minval, "maxval": maxval}

    def function(s: ShadingState) -> np.ndarray:
        fr, lo, hi = (_f(a, s, "float2", k) for k, a in args.items())
        return (waves.sinusoid(s.uv[:, 0], fr[:, 0], lo[:, 0], hi[:, 0])
                + waves.sinusoid(s.uv[:, 1], fr[:, 1], lo[:, 1], hi[:, 1]))

    return Varying(function, "uv_wave", args)


def position(mode: MappingMode = "uvw") -> Float3:
    """Listing 9.16."""
    return Varying(lambda s: _space.position(s, mode), "position", {"mode": mode})


def position_to_color(mode: MappingMode = "uvw", scale: Float = 1.0) -> Color:
    """Listing 9.18."""
    return Varying(lambda s: _space.position_to_color(s, mode, scale), "position_to_color",
                   {"mode": mode, "scale": scale})


def grid_color(cell_count: Float2 = (4.0, 4.0), line_color: Color = (0.0, 0.0, 0.0),
               bg_color: Color = (1.0, 1.0, 1.0), thickness: Float2 = (0.0, 0.0),
               texture_space: Int = 0) -> Color:
    """Listing 14.5."""
    args = {"cell_count": cell_count, "line_color": line_color, "bg_color": bg_color,
            "thickness": thickness, "texture_space": texture_space}
    return Varying(lambda s: _grid.grid_color(s, **args), "grid_color", args)


# --- chapter 9: coordinate spaces, stripes and checkerboards ---------------------


def uvw_position() -> Float3:
    """Listing 9.14."""
    return Varying(_space.uvw_position, "uvw_position")


def object_position() -> Float3:
    """Listing 9.12."""
    return Varying(_space.object_position, "object_position")


def world_position() -> Float3:
    """Listing 9.13."""
    return Varying(_space.world_position, "world_position")


def white_above_value(y_value: Float = 0.0) -> Color:
    """Listings 9.1-9.3."""
    return Varying(lambda s: _patterns.white_above_value(s, y_value), "white_above_value",
                   {"y_value": y_value})


def horizontal_stripe_pattern(mode: MappingMode = "uvw", interval: Float = 0.2,
                              thickness: Float = 0.1, stripe_color: Color = (0.0, 0.0, 0.0),
                              bg_color: Color = (1.0, 1.0, 1.0)) -> Color:
    """Listing 9.21."""
    args = {"mode": _patterns.check_mapping_mode(mode),
            "interval": _patterns.check_interval(interval), "thickness": thickness,
            "stripe_color": stripe_color, "bg_color": bg_color}
    return Varying(lambda s: _patterns.horizontal_stripe_pattern(s, **args),
                   "horizontal_stripe_pattern", args)


def checkerboard_pattern(interval: Float = 0.2, mode: MappingMode = "uvw",
                         color_1: Color = (1.0, 1.0, 1.0),
                         color_2: Color = (0.0, 0.0, 0.0)) -> Color:
    """Listing 9.26."""
    args = {"interval": _patterns.check_interval(interval),
            "mode": _patterns.check_mapping_mode(mode), "color_1": color_1, "color_2": color_2}
    return Varying(lambda s: _patterns.checkerboard_pattern(s, **args), "checkerboard_pattern",
                   args)


# --- chapter 13: tiles, bumps, textures ------------------------------------------


def fractional_uv(u_scale: Float = 1.0, v_scale: Float = 1.0) -> Float2:
    """Listing 13.1."""
    return Varying(lambda s: bump.fractional_uv(s, u_scale, v_scale), "fractional_uv",
                   {"u_scale": u_scale, "v_scale": v_scale})


def scaled_uv_circle_color(u_scale: Float = 1.0, v_scale: Float = 1.0,
                           outside_color: Color = (0.7, 0.7, 0.7)) -> Color:
    """Listing 13.3."""
    args = {"u_scale": u_scale, "v_scale": v_scale, "outside_color": outside_color}
    return Varying(lambda s: _uv.scaled_uv_circle_color(s, **args), "scaled_uv_circle_color", args)


def round_bump_normal(bump_scale: Float = 1.0, u_scale: Float = 1.0,
                      v_scale: Float = 1.0) -> Float3:
    """Listing 13.5."""
    args = {"bump_scale": bump_scale, "u_scale": u_scale, "v_scale": v_scale}
    return Varying(lambda s: bump.round_bump_normal(s, **args), "round_bump_normal", args)


def modify_normal_from_texture(texture: Texture2D, pixel_distance: Float2 = (1.0, 1.0),
                               texture_scale: Float2 = (1.0, 1.0)) -> Float3:
    """Listing 13.11."""
    args = {"texture": texture, "pixel_distance": pixel_distance, "texture_scale": texture_scale}

    def function(s: ShadingState) -> np.ndarray:
        return bump.modify_normal_from_texture(
            s, _texture(texture), _f(pixel_distance, s, "float2", "pixel_distance"),
            _f(texture_scale, s, "float2", "texture_scale"))

    return Varying(function, "modify_normal_from_texture", args)


def bump_normal(texture: Texture2D, bump_scale: Float = 1.0, scale_vector_z: Bool = True,
                texture_scale: Float2 = (1.0, 1.0), sample_min: UniformFloat = 0.0,
                sample_max: UniformFloat = 1.0) -> Float3:
    """Listing 13.16."""
    args = {"texture": texture, "bump_scale": bump_scale, "scale_vector_z": scale_vector_z,
            "texture_scale": texture_scale, "sample_min": sample_min, "sample_max": sample_max}

    def function(s: ShadingState) -> np.ndarray:
        return bump.bump_normal(s, _texture(texture), bump_scale, scale_vector_z,
                                _f(texture_scale, s, "float2", "texture_scale"),
                                sample_min, sample_max)

    return Varying(function, "bump_normal", args)


def texture_2d_lookup(texture: Texture2D) -> Color:
    """Listing 9.7."""
    return Varying(lambda s: tex.texture_2d_lookup(s, _texture(texture)), "texture_2d_lookup",
                   {"texture": texture})


def texture_2d_lookup_scaled(texture: Texture2D, u_scale: Float = 1.0,
                             v_scale: Float = 1.0) -> Color:
    """Listing 9.10."""
    def function(s: ShadingState) -> np.ndarray:
        return tex.texture_2d_lookup_scaled(s, _texture(texture),
                                            _f(u_scale, s, "float", "u_scale"),
                                            _f(v_scale, s, "float", "v_scale"))

    return Varying(function, "texture_2d_lookup_scaled",
                   {"texture": texture, "u_scale": u_scale, "v_scale": v_scale})


def texture_2d_lookup_float3(texture: Texture2D, texture_scale: Float2 = (1.0, 1.0),
                             sample_min: UniformFloat = 0.0, sample_max: UniformFloat = 1.0,
                             new_min: UniformFloat = 0.0, new_max: UniformFloat = 1.0) -> Float3:
    """Listing 13.15."""
    def function(s: ShadingState) -> np.ndarray:
        return bump.texture_2d_lookup_float3(s, _texture(texture),
                                             _f(texture_scale, s, "float2", "texture_scale"),
                                             sample_min, sample_max, new_min, new_max)

    return Varying(function, "texture_2d_lookup_float3", {"texture": texture})


def color_from_normal(normal: Float3 = (1.0, 1.0, 1.0),
                      normal_color_as_emission: Bool = True) -> Color:
    """Listing 13.17 (normals to world space with the state's ``object_to_world``, if any)."""
    def function(s: ShadingState) -> np.ndarray:
        world = _space.world_normal(s, _f(normal, s, "float3", "normal"))
        return bump.color_from_normal(world, normal_color_as_emission)

    return Varying(function, "color_from_normal",
                   {"normal": normal, "normal_color_as_emission": normal_color_as_emission})


# --- chapter 10 and 15.8: noise ----------------------------------------------------


def perlin_noise(point: Float3) -> Float:
    """Listing 10.4's ``perlin_noise(double3 pt)``."""
    return Varying(lambda s: _noise.perlin_noise(_f(point, s, "float3", "point")), "perlin_noise",
                   {"point": point})


def summed_perlin_noise(point: Float3, level_count: UniformInt = 4, level_scale: UniformFloat = 0.5,
                        point_scale: UniformFloat = 2.0, turbulence: UniformBool = False) -> Float:
    """Listing 10.5."""
    _noise.check_level_count(level_count)
    args = {"level_count": level_count, "level_scale": level_scale, "point_scale": point_scale,
            "turbulence": turbulence}
    return Varying(lambda s: _noise.summed_perlin_noise(_f(point, s, "float3", "point"), **args),
                   "summed_perlin_noise", {"point": point, **args})


# --- chapters 14-15: displacement vectors (displacement.fields) -----------------------


def move_up(scale: Float) -> Float3:
    """Listing 14.8."""
    return vector.move_up(scale)


def triangle_displacement(f: Float, height: Float) -> Float3:
    """Listing 14.10."""
    return vector.triangle_displacement(f, height)


def circle_linear_vector(f: Float, radius: Float = 0.5) -> Float3:
    """Listing 14.12."""
    return vector.circle_linear_vector(f, radius)


def circle_nonlinear_vector(f: Float, height: Float) -> Float3:
    """Listing 14.14."""
    return vector.circle_nonlinear_vector(f, height)


def displace_with_pwc(pwc: PwCurve, displace_dir: DisplacementDirection = "along_v") -> Float3:
    """Listing 15.8."""
    return FIELDS["displace_with_pwc"](pwc, displace_dir)


def pwc_angular_displace(pwc: PwCurve, displace_dir: DisplacementDirection = "along_v") -> Float3:
    """Listing 15.14."""
    return FIELDS["pwc_angular_displace"](pwc, displace_dir)


#: MDL name -> typed function returning a varying value (a callable of the state).
FUNCTIONS: dict[str, Callable[..., Any]] = {
    "state::normal": state_normal,
    "state::position": state_position,
    "state::texture_coordinate": state_texture_coordinate,
    "state::texture_tangent_u": state_texture_tangent_u,
    "state::texture_tangent_v": state_texture_tangent_v,
    "u": u,
    "v": v,
    "fit": fit,
    "sinusoid": sinusoid,
    "uv_wave": uv_wave,
    "position": position,
    "position_to_color": position_to_color,
    "uvw_position": uvw_position,
    "object_position": object_position,
    "world_position": world_position,
    "white_above_value": white_above_value,
    "horizontal_stripe_pattern": horizontal_stripe_pattern,
    "checkerboard_pattern": checkerboard_pattern,
    "grid_color": grid_color,
    "fractional_uv": fractional_uv,
    "scaled_uv_circle_color": scaled_uv_circle_color,
    "round_bump_normal": round_bump_normal,
    "modify_normal_from_texture": modify_normal_from_texture,
    "bump_normal": bump_normal,
    "texture_2d_lookup": texture_2d_lookup,
    "texture_2d_lookup_scaled": texture_2d_lookup_scaled,
    "texture_2d_lookup_float3": texture_2d_lookup_float3,
    "color_from_normal": color_from_normal,
    "perlin_noise": perlin_noise,
    "summed_perlin_noise": summed_perlin_noise,
    "move_up": move_up,
    "triangle_displacement": triangle_displacement,
    "circle_linear_vector": circle_linear_vector,
    "circle_nonlinear_vector": circle_nonlinear_vector,
    "displace_with_pwc": displace_with_pwc,
    "pwc_angular_displace": pwc_angular_displace,
}
