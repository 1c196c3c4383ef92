"""Make the Handbook's unshipped textures: a woven-fibre height map, its normal map, travertine.

Run ``python gallery/textures/make_textures.py`` (about 10 s); it writes, next to itself:

* ``weave_depth.png`` (16-bit grey) and ``weave_depth.exr`` (half, channel ``Y``): the
  height map of Figure 12.18 / Listing 12.16, grey value proportional to the height above
  the lowest point of the weave.  Made from an analytic fibre model rather than a
  rendering: a plain weave of ``THREADS`` warp threads (along v) and as many weft threads
  (along u) per tile, each thread's centre line undulating sinusoidally over and under
  the crossing threads, each thread a bundle of ``FIBRES`` twisted fibres (helices about
  the thread's axis) of circular section; the height is the maximum over every fibre of
  every thread.  Every term is periodic over the tile (an even number of threads, a
  whole number of twists, periodic lateral distances), so the map tiles without seams
  by construction, not by cropping.
* ``weave_normal_map.png`` (16-bit RGB, OpenGL convention, ``0.5 + 0.5 n``): the
  tangent-space normal of the same surface with the tile 1 x 1 and heights in tile units
  (the relief is ``RELIEF`` tiles), like the Handbook's ``weave_normal_map.tif``.
  Decode with ``bump.bump_normal``; it equals ``bump.height_map_normal`` of the height map
  with ``height_scale = RELIEF``.
* ``travertine.png`` (8-bit sRGB): a travertine-like stone for Listing 15.10: warm beige
  fractal noise, wavy sedimentary bands, and elongated dark pores along the bands, tiling
  too (periodic lattice noise).

The generators are plain functions of (u, v) (:func:`weave_height`,
:func:`travertine_color`), so tests can check periodicity exactly.
"""

from __future__ import annotations

import sys
import time
from pathlib import Path

import numpy as np

from displacement.bump import encode_normal_colors
from displacement.textures import write_texture

HERE = Path(__file__).resolve().parent

SIZE = 512
THREADS = 4  # warp (and weft) threads per tile; even, so the plain weave repeats
FIBRES = 5  # fibres per thread
TWISTS = 3  # whole helix turns of a fibre along one tile
PITCH = 1.0 / THREADS
HALF_WIDTH = 0.46 * PITCH  # thread half-width in the plane
FIBRE_RADIUS = 0.16 * PITCH
UNDULATION = 0.22 * PITCH  # amplitude of the over/under centre line
CORE = HALF_WIDTH - FIBRE_RADIUS  # radius of the helices the fibre centres follow
CORE_Z = 0.45 * CORE  # flattened yarn: vertical half-axis of the helices
LOW = -UNDULATION - CORE_Z - FIBRE_RADIUS  # lowest possible thread top: the floor
HIGH = UNDULATION + CORE_Z + FIBRE_RADIUS
RELIEF = HIGH - LOW  # tile units covered by grey values 0..1


def _wrap(d: np.ndarray) -> np.ndarray:
    """Periodic difference in [-0.5, 0.5)."""
    return d - np.floor(d + 0.5)


def _thread_top(lateral: np.ndarray, along: np.ndarray, sign: float, phase: float):
    """Top height of one thread: max over its fibres, -inf outside them."""
    centre_z = sign * UNDULATION * np.cos(np.pi * (THREADS * along - 0.5))
    top = np.full(lateral.shape, -np.inf)
    for k in range(FIBRES):
        phi = 2.0 * np.pi * (TWISTS * along + k / FIBRES + phase)
        x = lateral - CORE * np.sin(phi)
        inside = np.abs(x) < FIBRE_RADIUS
        cap = np.sqrt(np.where(inside, FIBRE_RADIUS**2 - x * x, 0.0))
        z = centre_z + CORE_Z * np.cos(phi) + cap
        top = np.where(inside, np.maximum(top, z), top)
    return top


def weave_height(u: np.ndarray, v: np.ndarray) -> np.ndarray:
    """Height of the plain weave at (u, v), normalized to [0, 1]; period 1 in u and v.

    Warp thread ``i`` lies along v at ``u = (i + 0.5) / THREADS`` and passes over weft
    thread ``j`` (along u at ``v = (j + 0.5) / THREADS``) when ``i + j`` is even.
    """
    u = np.asarray(u, dtype=np.float64)
    v = np.asarray(v, dtype=np.float64)
    h = np.full(np.broadcast(u, v).shape, LOW)
    for i in range(THREADS):
        sign = 1.0 if i % 2 == 0 else -1.0
        warp = _thread_top(_wrap(u - (i + 0.5) / THREADS), v, sign, 0.37 * i)
        weft = _thread_top(_wrap(v - (i + 0.5) / THREADS), u, -sign, 0.61 * i + 0.2)
        h = np.maximum(h, np.maximum(warp, weft))
    return np.clip((h - LOW) / RELIEF, 0.0, 1.0)


def weave_normals(u: np.ndarray, v: np.ndarray, step: float) -> np.ndarray:
    """Tangent-space unit normals of the weave (tile 1 x 1, height RELIEF * weave_height).

    Central differences of the analytic height ``step`` either side (half a texel when
    writing the map: a small prefilter of the creases where fibres meet).
    """
    hu = (weave_height(u + step, v) - weave_height(u - step, v)) * RELIEF / (2 * step)
    hv = (weave_height(u, v + step) - weave_height(u, v - step)) * RELIEF / (2 * step)
    n = np.stack([-hu, -hv, np.ones_like(hu)], axis=-1)
    return n / np.linalg.norm(n, axis=-1, keepdims=True)


def _lattice_noise(u, v, period_u: int, period_v: int, rng: np.random.Generator):
    """Value noise on a periodic lattice (quintic fade), in [0, 1]; period 1 in u and v."""
    grid = rng.random((period_v, period_u))
    x = np.asarray(u) * period_u
    y = np.asarray(v) * period_v
    x0 = np.floor(x)
    y0 = np.floor(y)
    fx = x - x0
    fy = y - y0
    fx = fx * fx * fx * (fx * (fx * 6 - 15) + 10)
    fy = fy * fy * fy * (fy * (fy * 6 - 15) + 10)
    i0 = np.mod(x0.astype(np.int64), period_u)
    j0 = np.mod(y0.astype(np.int64), period_v)
    i1 = np.mod(i0 + 1, period_u)
    j1 = np.mod(j0 + 1, period_v)
    a = grid[j0, i0] * (1 - fx) + grid[j0, i1] * fx
    b = grid[j1, i0] * (1 - fx) + grid[j1, i1] * fx
    return a * (1 - fy) + b * fy


def _fbm(u, v, base_u: int, base_v: int, octaves: int, seed: int) -> np.ndarray:
    rng = np.random.default_rng(seed)
    total = np.zeros(np.broadcast(u, v).shape)
    norm = 0.0
    amp = 1.0
    for o in range(octaves):
        total += amp * _lattice_noise(u, v, base_u << o, base_v << o, rng)
        norm += amp
        amp *= 0.5
    return total / norm


def travertine_color(u: np.ndarray, v: np.ndarray, seed: int = 12) -> np.ndarray:
    """Linear RGB of a travertine-like stone at (u, v), shape (..., 3); period 1 in u and v."""
    u = np.asarray(u, dtype=np.float64)
    v = np.asarray(v, dtype=np.float64)
    warp = _fbm(u, v, 2, 2, 4, seed)
    # sedimentary bands along u, bent by the warp noise; 7 whole bands per tile
    bands = 0.5 + 0.5 * np.sin(2 * np.pi * (7 * v + 0.9 * warp))
    fine = _fbm(u, v, 8, 8, 5, seed + 1)
    # pores: elongated along the bands (coarse lattice in u, fine in v), where noise peaks
    pore_noise = _fbm(u, v + 0.02 * warp, 24, 160, 2, seed + 2)
    pore_zone = 0.5 + 0.5 * np.sin(2 * np.pi * (7 * v + 0.9 * warp) + 1.3)
    pores = np.clip((pore_noise - 0.80 + 0.10 * pore_zone) / 0.05, 0.0, 1.0)
    light = np.array([0.82, 0.73, 0.57])
    dark = np.array([0.58, 0.45, 0.31])
    hole = np.array([0.33, 0.26, 0.18])
    t = np.clip(0.65 * bands + 0.35 * fine + 0.25 * (warp - 0.5), 0.0, 1.0)[..., None]
    t = t * t * (3.0 - 2.0 * t)
    stone = dark + (light - dark) * t
    stone = stone * (0.93 + 0.14 * fine[..., None])
    rgb = stone + (hole - stone) * pores[..., None]
    return np.clip(rgb, 0.0, 1.0)


def texel_grid(size: int) -> tuple[np.ndarray, np.ndarray]:
    """(u, v) of texel centres, row 0 at the top (v decreasing down the image)."""
    c = (np.arange(size) + 0.5) / size
    u, v = np.meshgrid(c, c[::-1])
    return u, v


def main(out_dir: Path = HERE, size: int = SIZE) -> list[Path]:
    """Write the textures into ``out_dir``; return the paths written."""
    t0 = time.perf_counter()
    u, v = texel_grid(size)
    height = weave_height(u, v)
    normals = weave_normals(u, v, step=0.5 / size)
    written = [
        write_texture(out_dir / "weave_depth.png", height, bits=16),
        write_texture(out_dir / "weave_depth.exr", height, bits="half"),
        write_texture(out_dir / "weave_normal_map.png", encode_normal_colors(normals), bits=16),
        write_texture(
            out_dir / "travertine.png", travertine_color(u, v), bits=8, gamma="srgb"
        ),
    ]
    total = sum(p.stat().st_size for p in written)
    for p in written:
        print(f"{p.name:24s} {p.stat().st_size / 1024:8.1f} KiB")
    print(f"{'total':24s} {total / 1024:8.1f} KiB  ({time.perf_counter() - t0:.1f} s)")
    return written


if __name__ == "__main__":
    sys.exit(0 if main() else 1)
