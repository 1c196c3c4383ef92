"""Chapter 10 of the Handbook: the noise materials (Listings 10.4 and 10.6).

Not Part 5, but ``marbloid`` (Listing 15.17) is built on the same noise and these two
show it directly.
"""

from __future__ import annotations

from render.library.noise import check_level_count, perlin_noise_color, summed_noise_color
from render.material import Bool, Color, Float, Int, MappingMode, Varying, material
from render.materials._common import color, diffuse_surface

__all__ = ["perlin_noise_material", "summed_noise_material"]


def perlin_noise_material(color_1: Color = (0.0, 0.0, 0.0), color_2: Color = (1.0, 1.0, 1.0),
                          scale: Float = 1.0, space: MappingMode = "object") -> material:
    """Listing 10.4: ``lerp(color_1, color_2, 0.5 + 0.5 perlin_noise(scale * position(space)))``."""
    args = {"color_1": color(color_1, "color_1"), "color_2": color(color_2, "color_2"),
            "scale": scale, "space": str(space).split("::")[-1]}
    return material(surface=diffuse_surface(
        Varying(lambda s: perlin_noise_color(s, **args), "perlin_noise_color", args)))


def summed_noise_material(color_1: Color = (0.0, 0.0, 0.0), color_2: Color = (1.0, 1.0, 1.0),
                          scale: Float = 1.0, level_count: Int = 4, turbulence: Bool = False,
                          space: MappingMode = "object") -> material:
    """Listing 10.6: ``summed_perlin_noise`` between two colours."""
    args = {"color_1": color(color_1, "color_1"), "color_2": color(color_2, "color_2"),
            "scale": scale, "level_count": check_level_count(level_count),
            "turbulence": bool(turbulence), "space": str(space).split("::")[-1]}
    return material(surface=diffuse_surface(
        Varying(lambda s: summed_noise_color(s, **args), "summed_noise_color", args)))
