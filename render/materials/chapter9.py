"""Chapter 9 of the Handbook, "Function calls as arguments": diffuse materials whose tint is
a function of the rendering state (Listings 9.4-9.27).

Texture coordinates as colour (``uv_as_color_material``, ``uv_as_color``), an image
mapped by them (``tex2d_diffuse``, ``tex2d_diffuse_scaled``), the coordinate spaces as
colour (``uvw_space_as_color``, ``space_as_color``), stripes and checkerboards
(``horizontal_stripes``, ``horizontal_stripes_component``, ``red_stripes_on_yellow``,
``checkerboard``), all through ``generic_diffuse_material`` (Listing 9.8) or its
let-expression twin.  The functions are in :mod:`render.library.patterns`,
:mod:`render.library.space` and :mod:`displacement.textures`.

Reading notes:

* ``uv_as_color`` names both a function (Listing 9.5) and a material (Listing 9.6); the
  registry's ``uv_as_color`` is the material, the function is
  :func:`render.library.patterns.uv_as_color`.
* ``uv.png`` (Figure 9.3) is not shipped with the Handbook; ``gallery/textures/uv.png``
  is made by ``gallery/textures/make_uv_texture.py``.  ``texture_2d("uv.png")`` has
  MDL's default gamma: an 8-bit PNG is sRGB-encoded colour.
* ``space_as_color(mode: "world", ...)`` (Figure 9.8) uses the state's
  ``object_to_world``, which the integrator sets to each object's transform
  (:func:`render.library.space.world_position`).
"""

from __future__ import annotations

from displacement import textures as tex
from render.library.patterns import (
    check_interval,
    check_mapping_mode,
    checkerboard_pattern,
    horizontal_stripe_pattern,
)
from render.library.patterns import uv_as_color as uv_as_color_function
from render.library.resources import load_texture
from render.library.space import position, position_to_color, texture_coordinate
from render.material import (
    Color,
    Float,
    MappingMode,
    Varying,
    df,
    evaluate,
    material,
    material_surface,
)
from render.materials._common import color, diffuse_surface

__all__ = [
    "uv_as_color_material",
    "uv_as_color",
    "generic_diffuse_material",
    "tex2d_diffuse",
    "tex2d_diffuse_scaled",
    "uvw_space_as_color",
    "space_as_color",
    "horizontal_stripes",
    "horizontal_stripes_component",
    "red_stripes_on_yellow",
    "checkerboard",
    "UV_TEXTURE",
]

#: Figure 9.3's image (``gallery/textures/uv.png``), read as MDL's ``gamma_default``.
UV_TEXTURE = "uv.png"


def uv_as_color_material() -> material:
    """Listing 9.4: ``tint: color(state::texture_coordinate(0))`` in a let-expression.

    Examples
    --------
    >>> uv_as_color_material().surface.scattering.name
    'diffuse_reflection_bsdf'
    """
    diffuse_color = Varying(lambda s: texture_coordinate(s, 0), "color",
                            {"value": "state::texture_coordinate(0)"})
    diffuse_bsdf = df.diffuse_reflection_bsdf(tint=diffuse_color)
    return material(surface=material_surface(scattering=diffuse_bsdf))


def uv_as_color() -> material:
    """Listing 9.6: the tint is the user-defined function ``uv_as_color()`` (Listing 9.5)."""
    diffuse_color = Varying(uv_as_color_function, "uv_as_color")
    diffuse_bsdf = df.diffuse_reflection_bsdf(tint=diffuse_color)
    return material(surface=material_surface(scattering=diffuse_bsdf))


def generic_diffuse_material(diffuse_color: Color = (1.0, 1.0, 1.0)) -> material:
    """Listing 9.8: ``df::diffuse_reflection_bsdf(tint: diffuse_color)``.

    Examples
    --------
    >>> generic_diffuse_material((0.2, 0.4, 0.6)).surface.scattering
    df::diffuse_reflection_bsdf(tint: (0.2, 0.4, 0.6))
    """
    return material(surface=diffuse_surface(color(diffuse_color, "diffuse_color")))


def tex2d_diffuse() -> material:
    """Listing 9.9: ``texture_2d_lookup(texture_2d("uv.png"))`` as the diffuse colour."""
    texture = load_texture(UV_TEXTURE, "default")
    return generic_diffuse_material(Varying(
        lambda s: tex.texture_2d_lookup(s, texture), "texture_2d_lookup",
        {"texture": texture.name}))


def tex2d_diffuse_scaled(u_scale: Float = 1.0, v_scale: Float = 1.0) -> material:
    """Listing 9.11: ``texture_2d_lookup_scaled(texture_2d("uv.png"), u_scale, v_scale)``
    (Listing 9.10: the lookup at ``frac(u * u_scale), frac(v * v_scale)``)."""
    texture = load_texture(UV_TEXTURE, "default")

    def diffuse_color(s):
        return tex.texture_2d_lookup_scaled(s, texture, evaluate(u_scale, s, "float", "u_scale"),
                                            evaluate(v_scale, s, "float", "v_scale"))

    return generic_diffuse_material(Varying(
        diffuse_color, "texture_2d_lookup_scaled",
        {"texture": texture.name, "u_scale": u_scale, "v_scale": v_scale}))


def uvw_space_as_color() -> material:
    """Listing 9.17: ``diffuse_color: color(position(uvw))``."""
    return generic_diffuse_material(Varying(lambda s: position(s, "uvw"), "color",
                                            {"value": "position(uvw)"}))


def space_as_color(mode: MappingMode = "uvw", scale: Float = 1.0) -> material:
    """Listing 9.19: ``diffuse_color: position_to_color(mode, scale)`` (Listing 9.18:
    ``color(frac(scale * position(mode)))``).

    Examples
    --------
    >>> space_as_color("object", 4.0).surface.scattering.kwargs["tint"]
    position_to_color(mode: 'object', scale: 4.0)
    """
    mode = check_mapping_mode(mode)
    return generic_diffuse_material(Varying(
        lambda s: position_to_color(s, mode, scale), "position_to_color",
        {"mode": mode, "scale": scale}))


def horizontal_stripes_component(stripe_color: Color = (0.0, 0.0, 0.0),
                                 bg_color: Color = (1.0, 1.0, 1.0), mode: MappingMode = "uvw",
                                 interval: Float = 0.2, thickness: Float = 0.1) -> material:
    """Listing 9.23: every parameter of ``horizontal_stripe_pattern`` (Listing 9.21) exposed.

    Raises
    ------
    ValueError
        A constant ``interval`` that is not > 0, or an unknown ``mode``.
    """
    args = {"mode": check_mapping_mode(mode), "interval": check_interval(interval),
            "thickness": thickness, "stripe_color": color(stripe_color, "stripe_color"),
            "bg_color": color(bg_color, "bg_color")}
    return generic_diffuse_material(Varying(
        lambda s: horizontal_stripe_pattern(s, **args), "horizontal_stripe_pattern", args))


def horizontal_stripes(stripe_color: Color = (0.0, 0.0, 0.0),
                       bg_color: Color = (1.0, 1.0, 1.0)) -> material:
    """Listing 9.22: ``horizontal_stripe_pattern(stripe_color: ..., bg_color: ...)`` with
    the pattern's defaults (uvw space, interval 0.2, thickness 0.1)."""
    return horizontal_stripes_component(stripe_color, bg_color)


def red_stripes_on_yellow() -> material:
    """Listing 9.24: thin red-brown stripes (interval 0.05, thickness 0.0075) on yellow."""
    return horizontal_stripes_component(stripe_color=(0.5, 0.2, 0.0), bg_color=(0.8, 0.7, 0.1),
                                        interval=0.05, thickness=0.0075)


def checkerboard(color_1: Color = (0.0, 0.0, 0.0), color_2: Color = (1.0, 1.0, 1.0),
                 mode: MappingMode = "uvw") -> material:
    """Listing 9.27: ``checkerboard_pattern(color_1: ..., color_2: ..., mode: ...)`` with
    the pattern's interval 0.2 (squares 0.1 wide).

    Note the material's defaults swap the pattern's: ``color_1`` is black here.
    """
    args = {"interval": 0.2, "mode": check_mapping_mode(mode),
            "color_1": color(color_1, "color_1"), "color_2": color(color_2, "color_2")}
    return generic_diffuse_material(Varying(
        lambda s: checkerboard_pattern(s, **args), "checkerboard_pattern", args))
