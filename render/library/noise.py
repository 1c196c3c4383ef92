"""Perlin noise as the Handbook writes it (chapter 10, Listings 10.1-10.5) and marbloid's tint.

The Handbook translates Ken Perlin's Java reference implementation of "improved noise"
(2002) to MDL; this is that listing, vectorized over points: the same permutation table
(printed in the listing, duplicated to 512 entries), ``fade`` (10.2), ``grad`` (10.3),
``plerp`` (10.1), the lattice hashing ``A = p[X] + Y, AA = p[A] + Z, ...`` and the
trilinear blend of the eight corner gradients.  Properties:

* ``perlin_noise`` is 0 at every integer lattice point (every corner gradient is dotted
  with a zero offset there);
* it is C2-continuous (the quintic ``fade``) and periodic with period 256 in x, y and z;
* it is bounded: each corner term ``(+-a) + (+-b)`` uses two offset components in
  [-1, 1], so ``|noise| <= 2``; in practice the range is about [-1, 1].

:func:`summed_perlin_noise` is Listing 10.5 (octaves, ``turbulence`` = absolute value),
and :func:`marbloid_tint` the let-block of Listing 15.17 (material ``marbloid``).

Departures, for robustness: the lattice cell ``int(floor(x)) & 255`` is computed as
``floor(x) mod 256`` in floating point, which is the same for every x where the
integer conversion is defined and stays defined for huge x; non-finite points raise
ValueError.
"""

from __future__ import annotations

import numpy as np

from displacement.state import ShadingState
from render.library.space import position
from render.material import evaluate

__all__ = [
    "PERMUTATION",
    "plerp",
    "fade",
    "grad",
    "perlin_noise",
    "summed_perlin_noise",
    "MAX_LEVELS",
    "check_level_count",
    "perlin_noise_color",
    "summed_noise_color",
    "marbloid_tint",
]

# Listing 10.4's table (the first 256 values; the listing repeats them)
_TABLE = (
    151, 160, 137, 91, 90, 15,
    131, 13, 201, 95, 96, 53, 194, 233, 7, 225, 140, 36, 103, 30, 69, 142, 8, 99, 37, 240, 21, 10,
    23,
    190, 6, 148, 247, 120, 234, 75, 0, 26, 197, 62, 94, 252, 219, 203, 117, 35, 11, 32, 57, 177, 33,
    88, 237, 149, 56, 87, 174, 20, 125, 136, 171, 168, 68, 175, 74, 165, 71, 134, 139, 48, 27, 166,
    77, 146, 158, 231, 83, 111, 229, 122, 60, 211, 133, 230, 220, 105, 92, 41, 55, 46, 245, 40, 244,
    102, 143, 54, 65, 25, 63, 161, 1, 216, 80, 73, 209, 76, 132, 187, 208, 89, 18, 169, 200, 196,
    135, 130, 116, 188, 159, 86, 164, 100, 109, 198, 173, 186, 3, 64, 52, 217, 226, 250, 124, 123,
    5, 202, 38, 147, 118, 126, 255, 82, 85, 212, 207, 206, 59, 227, 47, 16, 58, 17, 182, 189, 28,
    42,
    223, 183, 170, 213, 119, 248, 152, 2, 44, 154, 163, 70, 221, 153, 101, 155, 167, 43, 172, 9,
    129, 22, 39, 253, 19, 98, 108, 110, 79, 113, 224, 232, 178, 185, 112, 104, 218, 246, 97, 228,
    251, 34, 242, 193, 238, 210, 144, 12, 191, 179, 162, 241, 81, 51, 145, 235, 249, 14, 239, 107,
    49, 192, 214, 31, 181, 199, 106, 157, 184, 84, 204, 176, 115, 121, 50, 45, 127, 4, 150, 254,
    138, 236, 205, 93, 222, 114, 67, 29, 24, 72, 243, 141, 128, 195, 78, 66, 215, 61, 156, 180,
)

#: ``int[512] p``: the permutation of 0..255, twice (so ``p[i + 1]`` needs no modulus).
PERMUTATION = np.array(_TABLE + _TABLE, dtype=np.int64)
PERMUTATION.flags.writeable = False

#: Largest ``level_count`` of :func:`summed_perlin_noise`: the point doubles per level,
#: and beyond 64 octaves the detail is below float64 resolution.
MAX_LEVELS = 64


def plerp(t, a, b):
    """Listing 10.1: ``a + t (b - a)`` (Perlin's argument order).

    Examples
    --------
    >>> float(plerp(0.25, 2.0, 4.0))
    2.5
    """
    return a + t * (b - a)


def fade(t):
    """Listing 10.2: ``6 t^5 - 15 t^4 + 10 t^3``, the quintic with zero first and second
    derivatives at 0 and 1.

    Examples
    --------
    >>> fade(np.array([0.0, 0.5, 1.0])).tolist()
    [0.0, 0.5, 1.0]
    """
    return t * t * t * (t * (t * 6.0 - 15.0) + 10.0)


def grad(hash_value, x, y, z):
    """Listing 10.3: the dot product of an offset with one of 12 gradient directions.

    ``h = hash & 15``; ``u = h < 8 ? x : y``; ``v = h < 4 ? y : (h == 12 || h == 14 ?
    x : z)``; the result is ``(h & 1 ? -u : u) + (h & 2 ? -v : v)``.

    Parameters
    ----------
    hash_value : int or (...) int64
    x, y, z : float or (...) float64

    Examples
    --------
    >>> grad(np.array([0, 1, 13, 14]), 0.5, 0.25, 1.0).tolist()
    [0.75, -0.25, 0.75, -0.25]
    """
    h = np.asarray(hash_value) & 15
    u = np.where(h < 8, x, y)
    v = np.where(h < 4, y, np.where((h == 12) | (h == 14), x, z))
    return np.where((h & 1) == 0, u, -u) + np.where((h & 2) == 0, v, -v)


def perlin_noise(point) -> np.ndarray:
    """Listing 10.4's ``perlin_noise(double3 pt)``, vectorized.

    Parameters
    ----------
    point : (..., 3) float64
        Points in noise space (finite).

    Returns
    -------
    (...) float64
        Noise values, 0 at integer lattice points, ``|value| <= 2`` (about [-1, 1]).

    Raises
    ------
    ValueError
        On a non-finite coordinate or a last axis other than 3.

    Examples
    --------
    >>> perlin_noise(np.array([[0.0, 0.0, 0.0], [3.0, -7.0, 12.0]])).tolist()
    [0.0, 0.0]
    >>> round(float(perlin_noise(np.array([0.5, 0.5, 0.5]))), 6)
    -0.25
    """
    pt = np.asarray(point, dtype=np.float64)
    if pt.shape[-1:] != (3,):
        raise ValueError(
            f"perlin_noise needs points with 3 coordinates (..., 3), got shape {pt.shape}")
    if not np.all(np.isfinite(pt)):
        raise ValueError("perlin_noise: the point has a NaN or infinite coordinate")
    p = PERMUTATION
    floor = np.floor(pt)
    # find the unit cube that contains the point: int(floor(pt)) & 255
    cell = np.mod(floor, 256.0).astype(np.intp)
    X, Y, Z = cell[..., 0], cell[..., 1], cell[..., 2]
    # relative x, y, z of the point in the cube, and the fade curves
    rel = pt - floor
    x, y, z = rel[..., 0], rel[..., 1], rel[..., 2]
    x1, y1, z1 = x - 1.0, y - 1.0, z - 1.0
    u, v, w = fade(x), fade(y), fade(z)
    # hash coordinates of the eight cube corners
    A = p[X] + Y
    AA = p[A] + Z
    AB = p[A + 1] + Z
    B = p[X + 1] + Y
    BA = p[B] + Z
    BB = p[B + 1] + Z
    # blended results from the eight corners of the cube
    return plerp(
        w,
        plerp(v,
              plerp(u, _grad(p[AA], x, y, z), _grad(p[BA], x1, y, z)),
              plerp(u, _grad(p[AB], x, y1, z), _grad(p[BB], x1, y1, z))),
        plerp(v,
              plerp(u, _grad(p[AA + 1], x, y, z1), _grad(p[BA + 1], x1, y, z1)),
              plerp(u, _grad(p[AB + 1], x, y1, z1), _grad(p[BB + 1], x1, y1, z1))),
    )


#: ``grad(h, x, y, z)`` is linear in (x, y, z): row ``h`` holds its coefficients, taken
#: from :func:`grad` itself.  Each row has two entries +-1 on different axes and one 0, so
#: ``g . (x, y, z)`` is bit-identical to ``grad`` (the zero term adds exactly 0).
_GRADIENTS = np.array([[grad(h, *e) for e in np.eye(3)] for h in range(16)])
_GRADIENTS.flags.writeable = False


def _grad(hash_value: np.ndarray, x: np.ndarray, y: np.ndarray, z: np.ndarray) -> np.ndarray:
    """:func:`grad` by table lookup (the same values, fewer temporaries)."""
    g = _GRADIENTS[hash_value & 15]
    return g[..., 0] * x + g[..., 1] * y + g[..., 2] * z


def summed_perlin_noise(point, level_count: int = 4, level_scale: float = 0.5,
                        point_scale: float = 2.0, turbulence: bool = False) -> np.ndarray:
    """Listing 10.5: ``level_count`` octaves of :func:`perlin_noise`.

    ``sum_i perlin_noise(point * point_scale^i) * level_scale^i``; with ``turbulence``
    the result is ``|sum|``, otherwise ``0.5 + 0.5 sum``.

    Parameters
    ----------
    point : (..., 3) float64
    level_count : int in [0, MAX_LEVELS]
    level_scale, point_scale : float
        Finite; the amplitude and frequency factors between levels.
    turbulence : bool

    Returns
    -------
    (...) float64

    Examples
    --------
    >>> summed_perlin_noise(np.zeros((1, 3))).tolist()
    [0.5]
    >>> summed_perlin_noise(np.zeros((1, 3)), turbulence=True).tolist()
    [0.0]
    """
    level_count = check_level_count(level_count)
    level_scale = float(level_scale)
    point_scale = float(point_scale)
    if not (np.isfinite(level_scale) and np.isfinite(point_scale)):
        raise ValueError(
            f"level_scale and point_scale must be finite, got {level_scale}, {point_scale}")
    level_point = np.asarray(point, dtype=np.float64)
    scale = 1.0
    noise_sum = np.zeros(level_point.shape[:-1])
    for _ in range(level_count):
        noise_sum = noise_sum + perlin_noise(level_point) * scale
        scale *= level_scale
        level_point = level_point * point_scale
    if turbulence:
        return np.abs(noise_sum)
    return 0.5 + 0.5 * noise_sum


def check_level_count(level_count) -> int:
    """``level_count`` as an int in [0, MAX_LEVELS], or ValueError."""
    if isinstance(level_count, bool) or not isinstance(level_count, int | np.integer):
        raise ValueError(f"level_count must be an int, got {level_count!r}")
    if not 0 <= level_count <= MAX_LEVELS:
        raise ValueError(f"level_count must be in [0, {MAX_LEVELS}], got {level_count}")
    return int(level_count)


def _scaled_point(state: ShadingState, scale, space: str) -> np.ndarray:
    return evaluate(scale, state, "float", "scale")[:, None] * position(state, space)


def perlin_noise_color(state: ShadingState, color_1=0.0, color_2=1.0, scale=1.0,
                       space: str = "object") -> np.ndarray:
    """Listing 10.4's tint: ``lerp(color_1, color_2, 0.5 + 0.5 n)``, with
    ``n = perlin_noise(scale * position(space))``.

    Returns
    -------
    (n, 3) float64
    """
    t = 0.5 + 0.5 * perlin_noise(_scaled_point(state, scale, space))
    c1 = evaluate(color_1, state, "color", "color_1")
    c2 = evaluate(color_2, state, "color", "color_2")
    return c1 + t[:, None] * (c2 - c1)


def summed_noise_color(state: ShadingState, color_1=0.0, color_2=1.0, scale=1.0,
                       level_count: int = 4, turbulence: bool = False,
                       space: str = "object") -> np.ndarray:
    """Listing 10.6's tint: ``lerp(color_1, color_2, summed_perlin_noise(scale * position(space),
    level_count, turbulence))``.

    Returns
    -------
    (n, 3) float64
    """
    t = summed_perlin_noise(_scaled_point(state, scale, space), level_count,
                            turbulence=turbulence)
    c1 = evaluate(color_1, state, "color", "color_1")
    c2 = evaluate(color_2, state, "color", "color_2")
    return c1 + t[:, None] * (c2 - c1)


def marbloid_tint(state: ShadingState, scale=1.0, level_count: int = 5,
                  space: str = "object") -> np.ndarray:
    """Listing 15.17's tint: marble veins from turbulent noise in 3D space.

    ``p = scale * position(space)``; ``noise = summed_perlin_noise(p, level_count,
    level_scale: 0.8, turbulence: true)``; ``veins = 0.03 + 0.3 (1 + sin(2 p.z + 8
    noise))`` in [0.03, 0.63]; the tint is ``(veins^(1/1.8), veins^(1/1.4), 0.9
    veins^(1/1.1))``.

    Parameters
    ----------
    state : ShadingState
    scale : float or callable(state) -> (n,)
    level_count : int
    space : {"uvw", "object", "world"}

    Returns
    -------
    (n, 3) float64 in [0.03^(1/1.1) * 0.9, 1)

    Examples
    --------
    >>> from displacement.surfaces import UnitSquare
    >>> s = UnitSquare().state_at_uv(np.array([[0.0, 0.0]]))      # noise 0, z 0: veins 0.33
    >>> marbloid_tint(s).round(6).tolist()
    [[0.540142, 0.452982, 0.328494]]
    """
    scaled_point = _scaled_point(state, scale, space)
    noise_value = summed_perlin_noise(scaled_point, level_count, level_scale=0.8,
                                      turbulence=True)
    z = 2.0 * scaled_point[:, 2]
    veins = 0.03 + 0.3 * (1.0 + np.sin(z + 8.0 * noise_value))
    return np.stack([veins ** (1.0 / 1.8), veins ** (1.0 / 1.4), veins ** (1.0 / 1.1) * 0.9],
                    axis=1)
