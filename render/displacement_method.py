"""How a displaced object is modelled: its true displacement (diced), bump from the same
field, or a baked normal map; chosen per object (a scene's ``displacement_method``).

This is Cycles' per-material "displacement method", and the trade the Handbook measures
in section 12.2: bump keeps the base mesh (no dicing, no silhouettes or self-shadowing
of the relief) and shades with the displaced surface's normal.

* ``"displacement"``: the material as written; the renderer dices the object.
* ``"bump"``: the exact normal of the displaced surface at each shading point (central
  differences of the field in uv, :func:`displacement.bake.displaced_normal`); no map.
* ``"normal_map"``: the field baked into a tangent-space normal map of ``size`` texels
  at ``bits`` (8, 16, "half", "float"), quantized as the file would store it, applied
  with the Handbook's ``normal_map_bump`` (Listing 13.19).
"""

from __future__ import annotations

import dataclasses

import numpy as np

__all__ = ["METHODS", "NORMAL_MAP_BITS", "apply", "without_displacement"]

#: the methods, most faithful first
METHODS = ("displacement", "bump", "normal_map")
#: the bit depths a baked normal map may have
NORMAL_MAP_BITS = (8, 16, "half", "float")
#: finite-difference step of ``"bump"``, in uv (the field's own scale: 1e-4 of the surface)
BUMP_STEP = 1e-4


def without_displacement(material):
    """``material`` with its displacement removed (everything else kept)."""
    geometry = dataclasses.replace(material.geometry, displacement=None)
    return dataclasses.replace(material, geometry=geometry)


def _with_normal(material, normal):
    """``material`` without displacement, shading with ``normal`` (a Varying)."""
    geometry = dataclasses.replace(material.geometry, displacement=None, normal=normal)
    return dataclasses.replace(material, geometry=geometry)


def apply(material, surface, method: str, size: int = 512, bits=16):
    """``material`` on ``surface`` with its displacement modelled by ``method``.

    Parameters
    ----------
    material : render.material.material
    surface
        The object's base surface; ``"bump"`` and ``"normal_map"`` need a parametric one
        (``state_at_uv``).
    method : {"displacement", "bump", "normal_map"}
    size : int
        Texels across the normal map (``"normal_map"``).
    bits : {8, 16, "half", "float"}
        Bit depth of the normal map.

    Raises
    ------
    ValueError
        An unknown method or bit depth, or a method that needs a parametric surface.
    """
    from displacement.bake import bake, displaced_normal, quantize
    from displacement.bump import encode_normal_colors
    from displacement.dice import is_mesh_surface
    from displacement.textures import Texture
    from render.library.resources import with_filter
    from render.material import Varying
    from render.materials import MATERIALS

    if method not in METHODS:
        raise ValueError(f"displacement_method must be one of {', '.join(METHODS)}, got "
                         f"{method!r}")
    field = material.geometry.displacement
    if method == "displacement" or field is None:
        return material
    if is_mesh_surface(surface):
        raise ValueError(f"displacement_method {method!r} needs a parametric surface (a mesh "
                         "has no uv chart to take the field's derivatives in); use "
                         "'displacement'")
    if method == "bump":
        def normal(state):
            return displaced_normal(field, surface, state.uv, BUMP_STEP)[0]

        return _with_normal(material, Varying(normal, "displaced_normal"))
    if bits not in NORMAL_MAP_BITS:
        raise ValueError(f"normal_map_bits must be one of 8, 16, 'half', 'float', got {bits!r}")
    if not (isinstance(size, int | np.integer) and size >= 2):
        raise ValueError(f"normal_map_size must be a whole number >= 2, got {size!r}")
    maps = bake(field, surface, size=int(size))
    colors = quantize(encode_normal_colors(maps.normal), bits)
    texture = with_filter(Texture(colors, name=f"baked normal map {size}x{size} {bits}-bit"))
    bumped = MATERIALS["normal_map_bump"](surface_material=material, texture=texture)
    return _with_normal(material, bumped.geometry.normal)
