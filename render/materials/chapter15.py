"""Chapter 15 of the Handbook: architectural details from pw-curves (Listings 15.9-15.22).

Curves are the compiled ``profiles/*.pwc`` files (``ornament_1``, ``ornament_2``,
``corinthian``, ``doric_flutes``, ``ionic_flutes``; :func:`render.library.resources.load_profile`),
the Handbook's MDL arrays ``ornament_1::ornament_1`` etc.; ``NAME_length`` is
``curve.length``.  Displacements are :data:`displacement.fields.FIELDS`'
``displace_with_pwc``, ``pwc_angular_displace`` and ``double_pwc``.

Reading of Listing 15.10 (``travertine``): as printed, the tint is
``tex::lookup_color(texture_2d("travertine.png"), float2(texture_u_scale,
texture_v_scale))``, a lookup at the *constant* coordinate (u_scale, v_scale), which
would paint one flat colour; Figure 15.22 shows the stone texture following the
surface, and Listing 15.11 passes ``ornament_2_length`` as the v scale to keep the
texture's proportions.  So the lookup is taken at the scaled texture coordinate,
``texture_2d_lookup_scaled(texture, texture_u_scale, texture_v_scale)`` (Listing 9.10),
the evident intent.  ``travertine.png`` is a colour image, decoded from sRGB.
"""

from __future__ import annotations

from displacement.fields import FIELDS
from displacement.textures import texture_2d_lookup_scaled
from render.library.noise import check_level_count, marbloid_tint
from render.library.resources import load_profile, load_texture
from render.material import (
    DisplacementDirection,
    Float,
    Int,
    MappingMode,
    Material,
    PwCurve,
    UniformFloat,
    Varying,
    evaluate,
    material,
)
from render.materials._common import diffuse_surface
from render.materials.chapter12 import _check_material
from render.materials.chapter14 import grid, vector_displacement
from render.materials.earlier import PINK_STONE, diffuse_reflection

__all__ = [
    "grid_ornament_1",
    "travertine",
    "stone_ornament_2",
    "radial_pwc",
    "corinthian_capital_grid",
    "marbloid",
    "corinthian_capital_stone",
    "double_pwc",
    "doric_matte_stone",
    "ionic_matte_stone",
    "TRAVERTINE",
]

#: Listing 15.10's texture (``gallery/textures/travertine.png``, sRGB).
TRAVERTINE = "travertine.png"


def grid_ornament_1(grid_count: UniformFloat = 50.0) -> material:
    """Listing 15.9: ornament 1 along v, on ``grid(float2(grid_count, grid_count *
    ornament_1_length))`` (``grid_count`` must be a constant here)."""
    curve = load_profile("ornament_1")
    count = float(grid_count)
    return vector_displacement(FIELDS["displace_with_pwc"](curve, "along_v"),
                               grid((count, count * float(curve.length))))


def travertine(texture_u_scale: Float = 1.0, texture_v_scale: Float = 1.0) -> material:
    """Listing 15.10 (read as the scaled lookup; see the module notes): diffuse stone."""
    texture = load_texture(TRAVERTINE, "srgb")

    def tint(s):
        return texture_2d_lookup_scaled(s, texture,
                                        evaluate(texture_u_scale, s, "float", "texture_u_scale"),
                                        evaluate(texture_v_scale, s, "float", "texture_v_scale"))

    return material(surface=diffuse_surface(Varying(tint, "texture_2d_lookup_scaled", {
        "texture": TRAVERTINE, "u_scale": texture_u_scale, "v_scale": texture_v_scale})))


def stone_ornament_2() -> material:
    """Listing 15.11: ornament 2 along v with ``travertine(1.0, ornament_2_length)``."""
    curve = load_profile("ornament_2")
    return vector_displacement(FIELDS["displace_with_pwc"](curve, "along_v"),
                               travertine(1.0, float(curve.length)))


def radial_pwc(pwc: PwCurve, surface_material: Material,
               displace_dir: DisplacementDirection = "along_v") -> material:
    """Listing 15.15: ``vector_displacement(pwc_angular_displace(pwc, displace_dir),
    surface_material)``, a solid of revolution about +y."""
    _check_material(surface_material, "surface_material")
    return vector_displacement(FIELDS["pwc_angular_displace"](pwc, displace_dir), surface_material)


def corinthian_capital_grid() -> material:
    """Listing 15.16: the Corinthian impost revolved, on ``grid(float2(50.0))``."""
    return radial_pwc(load_profile("corinthian"), grid((50.0, 50.0)))


def marbloid(scale: Float = 1.0, level_count: Int = 5, space: MappingMode = "object") -> material:
    """Listing 15.17: diffuse marble veins from turbulent Perlin noise in 3D
    (:func:`render.library.noise.marbloid_tint`)."""
    args = {"scale": scale, "level_count": check_level_count(level_count),
            "space": str(space).split("::")[-1]}
    if args["space"] not in ("uvw", "object", "world"):
        raise ValueError(f"space must be uvw, object or world, got {space!r}")
    return material(surface=diffuse_surface(
        Varying(lambda s: marbloid_tint(s, **args), "marbloid_tint", args)))


def corinthian_capital_stone() -> material:
    """Listing 15.18: ``radial_pwc(corinthian::corinthian, marbloid(scale: 12))``."""
    return radial_pwc(load_profile("corinthian"), marbloid(scale=12.0))


def double_pwc(pwc_profile: PwCurve, pwc_sweep: PwCurve, surface_material: Material,
               radius_offset: UniformFloat = 0.0) -> material:
    """Listing 15.20: the profile (along v) swept around +y at a distance that follows the
    sweep curve (along u).  ``radius_offset`` must be constant here."""
    _check_material(surface_material, "surface_material")
    return vector_displacement(FIELDS["double_pwc"](pwc_profile, pwc_sweep, float(radius_offset)),
                               surface_material)


def doric_matte_stone() -> material:
    """Listing 15.21: the Corinthian profile swept along Doric flutes, in ``pink_stone``."""
    return double_pwc(load_profile("corinthian"), load_profile("doric_flutes"),
                      diffuse_reflection(tint=PINK_STONE), radius_offset=0.25)


def ionic_matte_stone() -> material:
    """Listing 15.22: as :func:`doric_matte_stone` with Ionic flutes."""
    return double_pwc(load_profile("corinthian"), load_profile("ionic_flutes"),
                      diffuse_reflection(tint=PINK_STONE), radius_offset=0.25)
