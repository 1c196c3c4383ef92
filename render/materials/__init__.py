"""The Handbook's Part 5 materials by name (chapters 12-15), plus the few they build on.

:data:`MATERIALS` maps each Handbook name to a function that takes the Handbook's
parameters (same names, order and defaults, annotated with MDL types) and returns a
:class:`render.material.material`::

    from render.materials import MATERIALS
    m = MATERIALS["glossy_waves"](distance=(0.02, 0.02), frequency=(10.0, 10.0),
                                  tint=(0.6, 0.4, 0.0), use_displacement=True)

Materials taking other materials (``waver``, ``shaper``, ``weave``, ``round_bumps``,
``texture_bump``, ``normal_map_bump``, ``vector_displacement``, ``radial_pwc``,
``double_pwc``) compose them as the Handbook does (``surface_material.surface``...).
:data:`CONSTANTS` holds named constants the listings use (``pink_stone``).

Modules: :mod:`~render.materials.chapter12` (displacement mapping),
:mod:`~render.materials.chapter13` (bump and normal maps),
:mod:`~render.materials.chapter14` (vector displacement, profiles),
:mod:`~render.materials.chapter15` (pw-curves), :mod:`~render.materials.chapter10`
(noise) and :mod:`~render.materials.earlier` (``diffuse``, ``subsurface_scattering``).
"""

from __future__ import annotations

from collections.abc import Callable
from types import MappingProxyType

from render.material import material
from render.materials import chapter10, chapter12, chapter13, chapter14, chapter15, earlier

__all__ = ["MATERIALS", "CONSTANTS", "PART5"]

#: The Part 5 materials (chapters 12-15) by their Handbook names.
PART5: tuple[str, ...] = (
    # chapter 12
    "waves_as_grayscale", "waves_as_displacement", "waves", "glossy", "glossy_waves", "waver",
    "glossy_yellow_waves", "glass_waves", "shaper", "green_glass_waves", "diffuse_weave",
    "weave", "gold_weave",
    # chapter 13
    "scaled_uv", "scaled_uv_circle", "round_bumps", "glossy_round_bumps", "texture_bump",
    "glossy_texture_weave_bump", "normal_as_color", "normal_map_bump",
    "glossy_normal_map_weave",
    # chapter 14
    "grid", "vector_displacement", "raise", "triangle", "circle_linear", "circle_nonlinear",
    "bubble", "tee_displacement",
    # chapter 15
    "grid_ornament_1", "travertine", "stone_ornament_2", "radial_pwc",
    "corinthian_capital_grid", "marbloid", "corinthian_capital_stone", "double_pwc",
    "doric_matte_stone", "ionic_matte_stone",
)

_EXTRA = {
    "glossy_yellow": chapter13.glossy_yellow,
    "diffuse": earlier.diffuse,
    "diffuse_reflection": earlier.diffuse_reflection,
    "subsurface_scattering": earlier.subsurface_scattering,
    "perlin_noise_material": chapter10.perlin_noise_material,
    "summed_noise_material": chapter10.summed_noise_material,
}


def _lookup(name: str) -> Callable[..., material]:
    if name == "raise":
        return chapter14.raise_
    for module in (chapter12, chapter13, chapter14, chapter15):
        if hasattr(module, name):
            return getattr(module, name)
    raise LookupError(name)


#: Handbook name -> material function (read-only).
MATERIALS: MappingProxyType[str, Callable[..., material]] = MappingProxyType(
    {name: _lookup(name) for name in PART5} | _EXTRA
)

#: Named constants of the listings: ``pink_stone`` (Listing 15.21).
CONSTANTS: MappingProxyType = MappingProxyType({"pink_stone": earlier.PINK_STONE})
