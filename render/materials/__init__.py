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

:data:`PARTS_2_3` lists the example materials of chapters 3-8 (Parts 2 and 3: surfaces,
glass, volumes, layering and mixing, plastic, fabric), in
:mod:`~render.materials.chapter3` ... :mod:`~render.materials.chapter8`; where a name is
used twice in the Handbook, the registry keeps one meaning (see those modules' notes).

:data:`PART4` lists the example materials of chapters 9 and 10 (Part 4, defining
functions: state functions, stripes and checkerboards, Perlin noise), in
:mod:`~render.materials.chapter9` and :mod:`~render.materials.chapter10`.
"""

from __future__ import annotations

from collections.abc import Callable
from types import MappingProxyType

from render.material import material
from render.materials import (
    chapter3,
    chapter4,
    chapter5,
    chapter6,
    chapter7,
    chapter8,
    chapter9,
    chapter10,
    chapter12,
    chapter13,
    chapter14,
    chapter15,
    earlier,
)

__all__ = ["MATERIALS", "CONSTANTS", "PART5", "PARTS_2_3", "PART4"]

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


#: The example materials of chapters 3-8 (Parts 2 and 3) by their Handbook names.
PARTS_2_3: tuple[str, ...] = (
    # chapter 3
    "plaster", "diffuse_transmission", "emission", "emission_with_diffuse_backface",
    "specular", "mirror", "specular_transmission", "specular_reflection_transmission",
    "glossy_reflection", "glossy_transmission", "glossy_reflection_transmission",
    # chapter 4
    "specular_reflect_transmit", "specular_reflect_transmit_thin_walled",
    "glossy_reflect_transmit", "glossy_reflect_transmit_layers",
    "glossy_reflect_transmit_absorb", "glossy_reflect_transmit_absorb_falloff",
    "subsurface_scattering",
    # chapter 5
    "isotropic_volume", "anisotropic_volume", "red_light", "green_light", "blue_light",
    "blue_scattering", "blue_absorption", "spotlight_emission",
    # chapter 6 (its glossy and mirror keep Listing 12.8's and Listing 3.5's names)
    "red", "shiny", "shiny_red", "shiny_red_with_let", "shiny_red_extract", "diffuse",
    "glossy_over_diffuse", "shiny_red_specialized", "light_blue_ceramic", "shiny_tint",
    "fresnel_glossy_over_diffuse", "two_glossy_lobes", "diffuse_green_base",
    "wide_blue_glossy", "narrow_blue_glossy", "two_layers", "three_layers", "four_layers",
    "two_layers_v1", "three_layers_v1", "four_layers_v1", "five_layers",
    # chapter 7
    "phonglike_plastic", "phonglike_plastic_layered", "dielectric_plastic",
    "dielectric_plastic_two_lobe", "translucency", "translucent_plastic",
    # chapter 8 (translucency: Listing 8.5 = Listing 7.5)
    "anisotropic_glossy", "anisotropic_glossy_three_lobes", "warp_and_weft", "iridescent_silk",
)

#: names of PARTS_2_3 already registered from the Part 5 modules (the same listings)
_SHARED = {"diffuse": earlier.diffuse, "subsurface_scattering": earlier.subsurface_scattering}


def _lookup_parts_2_3(name: str) -> Callable[..., material]:
    if name in _SHARED:
        return _SHARED[name]
    for module in (chapter3, chapter4, chapter5, chapter6, chapter7, chapter8):
        if name in module.__all__:
            return getattr(module, name)
    raise LookupError(name)


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
    | {name: _lookup_parts_2_3(name) for name in PARTS_2_3}
)

#: Named constants of the listings: ``pink_stone`` (Listing 15.21); ``white``, ``blue``,
#: ``orange``, ``yellow`` (section 6.5), ``magenta`` (section 8.6).  (``green`` is left out:
#: sections 6.5 and 8.6 give it different values.)
CONSTANTS: MappingProxyType = MappingProxyType({
    "pink_stone": earlier.PINK_STONE,
    "white": chapter6.WHITE, "blue": chapter6.BLUE, "orange": chapter6.ORANGE,
    "yellow": chapter6.YELLOW, "magenta": chapter8.MAGENTA,
})

#: The example materials of chapters 9 and 10 (Part 4) by their Handbook names.
PART4: tuple[str, ...] = (
    # chapter 9
    "uv_as_color_material", "uv_as_color", "generic_diffuse_material", "tex2d_diffuse",
    "tex2d_diffuse_scaled", "uvw_space_as_color", "space_as_color", "horizontal_stripes",
    "horizontal_stripes_component", "red_stripes_on_yellow", "checkerboard",
    # chapter 10
    "perlin_noise_material", "summed_noise_material",
)


def _lookup_part_4(name: str) -> Callable[..., material]:
    for module in (chapter9, chapter10):
        if name in module.__all__:
            return getattr(module, name)
    raise LookupError(name)


_PART4 = {name: _lookup_part_4(name) for name in PART4}
_TAKEN = sorted(name for name, f in _PART4.items() if MATERIALS.get(name, f) is not f)
if _TAKEN:
    raise ImportError(f"Part 4 material names already registered otherwise: {_TAKEN}")
#: Handbook name -> material function (read-only), Parts 2-5.
MATERIALS = MappingProxyType(dict(MATERIALS) | _PART4)
