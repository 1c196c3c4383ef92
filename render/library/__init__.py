"""The Handbook's function library (chapters 9, 10, 12-15), vectorized over shading lanes.

Functions take a :class:`~displacement.state.ShadingState` of n lanes (where MDL reads
``state::``) and return arrays, one row per lane.  What ``displacement`` already has is
re-exported, not reimplemented:

* chapter 12 (:mod:`displacement.waves`): :func:`fit`, :func:`sinusoid`,
  :func:`sinusoid2`, :func:`uv_wave`;
* chapter 13 (:mod:`displacement.bump`): :func:`fractional_uv`,
  :func:`round_bump_normal`, :func:`modify_normal_from_texture`, :func:`bump_normal`,
  :func:`texture_2d_lookup_float3`, :func:`color_from_normal`;
* texture lookups (:mod:`displacement.textures`): :func:`texture_2d_lookup`,
  :func:`texture_2d_lookup_scaled`, :func:`texture_2d_sample`.

New here: coordinate spaces (:mod:`render.library.space`), the grid of chapter 14
(:mod:`render.library.grid`), the uv tile colours of chapter 13
(:mod:`render.library.uv`), Perlin noise and marbloid (:mod:`render.library.noise`),
chapter 9's stripes and checkerboards (:mod:`render.library.patterns`).
:data:`FUNCTIONS` (:mod:`render.library.functions`) holds the same functions as MDL
calls for material expressions, and :mod:`render.library.resources` finds profiles and
textures.
"""

from displacement.bump import (
    bump_normal,
    color_from_normal,
    fractional_uv,
    modify_normal_from_texture,
    round_bump_normal,
    texture_2d_lookup_float3,
)
from displacement.textures import texture_2d_lookup, texture_2d_lookup_scaled, texture_2d_sample
from displacement.waves import fit, sinusoid, sinusoid2, uv_wave
from render.library.functions import FUNCTIONS
from render.library.grid import grid_color, in_grid_line, near_grid_value
from render.library.noise import (
    fade,
    grad,
    marbloid_tint,
    perlin_noise,
    perlin_noise_color,
    plerp,
    summed_noise_color,
    summed_perlin_noise,
)
from render.library.patterns import (
    checkerboard_pattern,
    exclusive_or,
    horizontal_stripe_pattern,
    stripe,
    uv_as_color,
    white_above_value,
)
from render.library.space import (
    MAPPING_MODES,
    object_position,
    position,
    position_to_color,
    texture_coordinate,
    u,
    uvw_position,
    v,
    world_normal,
    world_position,
)
from render.library.uv import scaled_uv_circle_color, scaled_uv_color

__all__ = [
    "fit", "sinusoid", "sinusoid2", "uv_wave",
    "fractional_uv", "round_bump_normal", "modify_normal_from_texture", "bump_normal",
    "texture_2d_lookup_float3", "color_from_normal",
    "texture_2d_lookup", "texture_2d_lookup_scaled", "texture_2d_sample",
    "MAPPING_MODES", "texture_coordinate", "u", "v", "uvw_position", "object_position",
    "world_position", "world_normal", "position", "position_to_color",
    "near_grid_value", "in_grid_line", "grid_color",
    "scaled_uv_color", "scaled_uv_circle_color",
    "white_above_value", "uv_as_color", "stripe", "horizontal_stripe_pattern", "exclusive_or",
    "checkerboard_pattern",
    "plerp", "fade", "grad", "perlin_noise", "summed_perlin_noise", "perlin_noise_color",
    "summed_noise_color", "marbloid_tint",
    "FUNCTIONS",
]
