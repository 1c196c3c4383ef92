"""Chapter 14 of the Handbook: geometric profiles by vector displacement (Listings 14.6-14.30).

``grid`` (14.6) is the surface of most of the chapter's materials, and
``vector_displacement`` (14.7) the template: a displacement vector (a
:class:`~displacement.fields.Field` from :data:`displacement.fields.FIELDS`, whose uv
knots reach the dicer) plus the surface of another material, on a thin-walled material.
"""

from __future__ import annotations

import numpy as np

from displacement.bubble import get_bubble_args
from displacement.bubble import normalize_grid as _normalize_grid
from displacement.fields import FIELDS, Field
from displacement.profile import TEE, profile_lengths, scale_component
from render.library.grid import grid_color
from render.material import (
    Color,
    Float,
    Float2,
    Float3,
    Int,
    Material,
    UniformBool,
    UniformFloat,
    UniformFloat2,
    UniformInt,
    Varying,
    material,
    material_geometry,
)
from render.materials._common import color, diffuse_surface
from render.materials.chapter12 import _check_material

__all__ = [
    "grid",
    "vector_displacement",
    "raise_",
    "triangle",
    "circle_linear",
    "circle_nonlinear",
    "bubble",
    "tee_displacement",
]


def grid(cell_count: Float2 = (4.0, 4.0), line_color: Color = (0.0, 0.0, 0.0),
         bg_color: Color = (0.7, 0.7, 0.7), thickness: Float2 = (0.0, 0.0),
         texture_space: Int = 0) -> material:
    """Listing 14.6: diffuse ``grid_color(cell_count, line_color, bg_color, thickness)``.

    Examples
    --------
    >>> import numpy as np
    >>> from displacement.surfaces import UnitSquare
    >>> s = UnitSquare().state_at_uv(np.array([[0.25, 0.6], [0.6, 0.6]]))
    >>> grid().surface.scattering.kwargs["tint"](s).tolist()
    [[0.0, 0.0, 0.0], [0.7, 0.7, 0.7]]
    """
    if not callable(cell_count) and np.any(np.asarray(cell_count, dtype=np.float64) == 0.0):
        raise ValueError(
            f"grid cell_count must not be 0 (there would be no cells), got {cell_count!r}")
    args = {"cell_count": cell_count, "line_color": color(line_color, "line_color"),
            "bg_color": color(bg_color, "bg_color"), "thickness": thickness,
            "texture_space": int(texture_space)}
    return material(surface=diffuse_surface(
        Varying(lambda s: grid_color(s, **args), "grid_color", args)))


_GRID = grid()


def vector_displacement(displacement: Float3 = (0.0, 0.0, 0.0),
                        material_for_surface: Material = _GRID) -> material:
    """Listing 14.7: ``material(thin_walled: true, surface: material_for_surface.surface,
    geometry: material_geometry(displacement))``.

    ``displacement`` is a Field (kept as is), another callable of the state (wrapped in
    a Field without knots), or a constant vector (zero: no displacement).
    """
    _check_material(material_for_surface, "material_for_surface")
    if callable(displacement) and not isinstance(displacement, Field):
        displacement = Field(displacement, (None, None), getattr(displacement, "name", "") or
                             "displacement")
    return material(thin_walled=True, surface=material_for_surface.surface,
                    geometry=material_geometry(displacement=displacement))


def raise_(scale: Float = 0.0, grid_count: Float2 = (4.0, 4.0)) -> material:
    """Listing 14.9, material ``raise`` (a Python keyword; ``MATERIALS["raise"]``):
    ``vector_displacement(move_up(scale), grid(grid_count))``."""
    return vector_displacement(FIELDS["raise"](scale), grid(grid_count))


def triangle(height: Float = 0.5) -> material:
    """Listing 14.11: ``vector_displacement(triangle_displacement(u(), height))`` on ``grid()``."""
    return vector_displacement(FIELDS["triangle"](height))


def circle_linear(height: Float = 0.5) -> material:
    """Listing 14.13: ``circle_linear_vector(u(), height)`` on ``grid(float2(20, 20))``."""
    return vector_displacement(FIELDS["circle_linear"](height), grid((20.0, 20.0)))


def circle_nonlinear(height: Float = 0.5, count: Float2 = (20.0, 20.0)) -> material:
    """Listing 14.15: ``circle_nonlinear_vector(u(), height)`` on ``grid(count)``."""
    return vector_displacement(FIELDS["circle_nonlinear"](height), grid(count))


def bubble(radius: UniformFloat = 0.25, height: UniformFloat = 0.25,
           repeat: UniformFloat2 = (1.0, 1.0), grid_count: UniformFloat2 = (4.0, 4.0),
           normalize_grid: UniformBool = False) -> material:
    """Listing 14.21: ``vector_displacement(displace_with_bubble(repeat, ba), grid(grid_point))``.

    ``ba = get_bubble_args(radius, height)`` is computed once; ``grid_point`` scales the
    grid counts by ``ba.total_length`` where ``normalize_grid`` and ``repeat != 1``
    (:func:`displacement.bubble.normalize_grid`).  ``repeat``, ``grid_count`` and
    ``normalize_grid`` are varying in the Handbook but must be constants here (the
    bubble arguments are computed once from them).
    """
    ba = get_bubble_args(float(radius), float(height))
    grid_point = _normalize_grid(grid_count, repeat, ba, bool(normalize_grid))
    return vector_displacement(FIELDS["displace_with_bubble"](repeat, ba),
                               grid(tuple(float(x) for x in grid_point)))


def tee_displacement(uv_index: UniformInt = 0, repeat: UniformFloat = 1.0,
                     grid_count: UniformFloat2 = (4.0, 4.0)) -> material:
    """Listing 14.30: the tee profile (Listing 14.22) along u (``uv_index`` 0) or v, with
    the grid count in that direction scaled by the profile's total length (3)."""
    scaled_grid_count = scale_component(grid_count, profile_lengths(TEE), uv_index)
    return vector_displacement(FIELDS["tee_displacement"](uv_index, repeat),
                               grid(tuple(float(x) for x in scaled_grid_count)))

