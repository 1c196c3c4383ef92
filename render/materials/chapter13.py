"""Chapter 13 of the Handbook: bump mapping (Listings 13.2-13.20).

Normals come from :mod:`displacement.bump` (``round_bump_normal``,
``modify_normal_from_texture``, ``bump_normal``, ``color_from_normal``), which apply the
horizon rule; ``material.shade`` applies it again to whatever ``geometry.normal`` gives.

Textures: ``weave_depth.png`` (height, read linear) and ``weave_normal_map.png`` (the
Handbook's ``weave_normal_map.tif``, 16-bit OpenGL normal map, read linear), made by
``gallery/textures/make_textures.py``.  ``texture_2d()`` (an invalid texture, passed as
None) reads 0 everywhere, as MDL specifies.
"""

from __future__ import annotations

from displacement import bump
from render.library.resources import INVALID_TEXTURE, load_texture
from render.library.space import world_normal
from render.library.uv import scaled_uv_circle_color, scaled_uv_color
from render.material import (
    Bool,
    Color,
    Float,
    Float2,
    Float3,
    Material,
    Texture2D,
    UniformBool,
    UniformFloat,
    Varying,
    df,
    evaluate,
    material,
    material_emission,
    material_geometry,
    material_surface,
)
from render.materials._common import color, diffuse_surface
from render.materials.chapter12 import WEAVE_DEPTH, _check_material, glossy

__all__ = [
    "scaled_uv",
    "scaled_uv_circle",
    "round_bumps",
    "glossy_round_bumps",
    "texture_bump",
    "glossy_texture_weave_bump",
    "normal_as_color",
    "normal_map_bump",
    "glossy_normal_map_weave",
    "glossy_yellow",
    "WEAVE_NORMAL_MAP",
]

#: Listing 13.20's normal map (the Handbook's ``weave_normal_map.tif``).
WEAVE_NORMAL_MAP = "weave_normal_map.png"


def scaled_uv(u_scale: Float = 1.0, v_scale: Float = 1.0) -> material:
    """Listing 13.2: ``tint = color(uv[0], uv[1], 0.0)`` of ``fractional_uv(u_scale, v_scale)``."""
    return material(surface=diffuse_surface(Varying(
        lambda s: scaled_uv_color(s, u_scale, v_scale), "scaled_uv_color",
        {"u_scale": u_scale, "v_scale": v_scale})))


def scaled_uv_circle(u_scale: Float = 1.0, v_scale: Float = 1.0,
                     outside_color: Color = (0.7, 0.7, 0.7)) -> material:
    """Listing 13.4: the uv colour inside each tile's circle, ``outside_color`` outside."""
    outside_color = color(outside_color, "outside_color")
    return material(surface=diffuse_surface(Varying(
        lambda s: scaled_uv_circle_color(s, u_scale, v_scale, outside_color),
        "scaled_uv_circle_color", {"u_scale": u_scale, "v_scale": v_scale})))


def round_bumps(surface_material: Material, bump_scale: Float = 1.0, u_scale: Float = 1.0,
                v_scale: Float = 1.0) -> material:
    """Listing 13.6: ``surface_material.surface`` with ``normal: round_bump_normal(...)``."""
    _check_material(surface_material, "surface_material")
    normal = Varying(lambda s: bump.round_bump_normal(s, bump_scale, u_scale, v_scale),
                     "round_bump_normal",
                     {"bump_scale": bump_scale, "u_scale": u_scale, "v_scale": v_scale})
    return material(surface=surface_material.surface, geometry=material_geometry(normal=normal))


def glossy_round_bumps(bump_scale: Float = 1.0, u_scale: Float = 1.0,
                       v_scale: Float = 1.0) -> material:
    """Listing 13.7: ``round_bumps(glossy(color(0.6, 0.4, 0.0)), bump_scale, u_scale, v_scale)``."""
    return round_bumps(glossy((0.6, 0.4, 0.0)), bump_scale, u_scale, v_scale)


def _texture(texture):
    return INVALID_TEXTURE if texture is None else texture


def texture_bump(surface_material: Material, texture: Texture2D,
                 pixel_distance: Float2 = (1.0, 1.0),
                 texture_scale: Float2 = (1.0, 1.0)) -> material:
    """Listing 13.12: ``normal: modify_normal_from_texture(texture, pixel_distance,
    texture_scale)``."""
    _check_material(surface_material, "surface_material")
    tex = _texture(texture)

    def normal(s):
        return bump.modify_normal_from_texture(
            s, tex, evaluate(pixel_distance, s, "float2", "pixel_distance"),
            evaluate(texture_scale, s, "float2", "texture_scale"))

    return material(surface=surface_material.surface, geometry=material_geometry(normal=Varying(
        normal, "modify_normal_from_texture",
        {"texture": tex.name, "pixel_distance": pixel_distance, "texture_scale": texture_scale})))


def glossy_texture_weave_bump(tint: Color = (0.7, 0.7, 0.7), roughness: Float = 0.5,
                              pixel_distance: Float2 = (1.0, 1.0),
                              texture_scale: Float2 = (1.0, 1.0)) -> material:
    """Listing 13.13: ``texture_bump(glossy(tint, roughness), texture_2d("weave_depth.png"),
    pixel_distance, texture_scale)``."""
    return texture_bump(glossy(tint, roughness), load_texture(WEAVE_DEPTH, "linear"),
                        pixel_distance, texture_scale)


def normal_as_color(normal: Float3 = (1.0, 1.0, 1.0),
                    normal_color_as_emission: UniformBool = True) -> material:
    """Listing 13.18: a normal shown as diffuse colour, or (default) as emission.

    ``normal_color = color_from_normal(normal, normal_color_as_emission)`` (Listing
    13.17: world space by the state's ``object_to_world``, ``0.5 + 0.5
    n``, divided by pi as emission); the other of tint and intensity is ``color(0.0)``.

    Examples
    --------
    >>> m = normal_as_color()
    >>> m.surface.scattering.is_black, m.surface.emission.emission is not None
    (True, True)
    """
    as_emission = bool(normal_color_as_emission)

    def normal_color(s):
        world = world_normal(s, evaluate(normal, s, "float3", "normal"))
        return bump.color_from_normal(world, as_emission)

    normal_color = Varying(normal_color, "color_from_normal",
                           {"normal": normal, "normal_color_as_emission": as_emission})
    black = (0.0, 0.0, 0.0)
    return material(surface=material_surface(
        scattering=df.diffuse_reflection_bsdf(tint=black if as_emission else normal_color),
        emission=material_emission(emission=df.diffuse_edf(),
                                   intensity=normal_color if as_emission else black),
    ))


_DEFAULT_MATERIAL = material()


def normal_map_bump(bump_scale: Float = 1.0, texture_scale: Float2 = (1.0, 1.0),
                    scale_vector_z: Bool = True, surface_material: Material = _DEFAULT_MATERIAL,
                    texture: Texture2D = None, sample_min: UniformFloat = 0.0,
                    sample_max: UniformFloat = 1.0,
                    use_normal_for_color: UniformBool = False,
                    normal_color_is_emission: UniformBool = True) -> material:
    """Listing 13.19: a normal map's normal (``bump_normal``), or that normal shown as colour.

    ``texture`` None is ``texture_2d()`` (the Handbook's default): it reads 0, so the
    decoded normal is ``(-1, -1, -1)`` in tangent space, below the horizon; the horizon
    rule bends it back.  ``sample_min``/``sample_max`` must be constants here.
    """
    _check_material(surface_material, "surface_material")
    tex = _texture(texture)
    scale_vector_z = bool(scale_vector_z)

    def normal(s):
        return bump.bump_normal(s, tex, bump_scale, scale_vector_z,
                                evaluate(texture_scale, s, "float2", "texture_scale"),
                                float(sample_min), float(sample_max))

    modified_normal = Varying(normal, "bump_normal", {
        "texture": tex.name, "bump_scale": bump_scale, "scale_vector_z": scale_vector_z,
        "texture_scale": texture_scale, "sample_min": sample_min, "sample_max": sample_max})
    if use_normal_for_color:
        return material(surface=normal_as_color(modified_normal, normal_color_is_emission).surface)
    return material(surface=surface_material.surface,
                    geometry=material_geometry(normal=modified_normal))


def glossy_yellow() -> material:
    """``glossy_yellow()`` of Listing 13.20, never listed in the Handbook: read as
    ``glossy(tint: color(0.6, 0.4, 0.0))``, the yellow glossy of the chapter's other
    figures (``glossy_round_bumps``, ``glossy_yellow_waves``), roughness 0.3."""
    return glossy((0.6, 0.4, 0.0), 0.3)


def glossy_normal_map_weave(bump_scale: Float = 1.0, texture_scale: Float2 = (1.0, 1.0),
                            scale_vector_z: Bool = True, use_normal_for_color: UniformBool = False,
                            normal_color_is_emission: UniformBool = True) -> material:
    """Listing 13.20: ``normal_map_bump`` with ``glossy_yellow()`` and the weave normal map."""
    return normal_map_bump(
        bump_scale=bump_scale, texture_scale=texture_scale, scale_vector_z=scale_vector_z,
        surface_material=glossy_yellow(), texture=load_texture(WEAVE_NORMAL_MAP, "linear"),
        sample_min=0.0, sample_max=1.0, use_normal_for_color=use_normal_for_color,
        normal_color_is_emission=normal_color_is_emission)
