"""Make ``uv.png``, the texture-space test image of the Handbook's section 9.3 (Figure 9.3).

Run ``python gallery/textures/make_uv_texture.py`` (well under a second); it writes
``uv.png`` (8-bit sRGB, ``SIZE`` x ``SIZE``) next to itself, the image that
``tex2d_diffuse`` and ``tex2d_diffuse_scaled`` (Listings 9.9 and 9.11) map onto objects.

The Handbook does not ship the file.  Like its Figure 9.3, the image shows where
texture space is: ``CELLS`` x ``CELLS`` cells whose colour grows in red with u and in
green with v (the origin at the lower left, as MDL puts it), alternate cells darker
(a checkerboard, so the cells stay countable where u and v scale), thin dark lines
between cells, and a white corner mark in the cell at the origin.  The colour is a
plain function of (u, v) (:func:`uv_color`), so tests can check a lookup against it.
"""

from __future__ import annotations

import sys
from pathlib import Path

import numpy as np

from displacement.textures import write_texture

HERE = Path(__file__).resolve().parent

SIZE = 256
CELLS = 8
LINE = 1.0 / SIZE  # half-width of the dark lines between cells, in uv
LINE_COLOR = np.array([0.02, 0.02, 0.02])
MARK_COLOR = np.array([1.0, 1.0, 1.0])
MARK = (0.25, 0.75)  # the origin cell's mark: an L, 1/4 cell thick, 3/4 cell long


def uv_color(u: np.ndarray, v: np.ndarray) -> np.ndarray:
    """Linear RGB of the uv test image at (u, v) in [0, 1], shape (..., 3).

    Cell ``(i, j) = (floor(CELLS u), floor(CELLS v))`` (clamped to the image) has colour
    ``(0.02 + 0.9 (i + 0.5) / CELLS, 0.02 + 0.9 (j + 0.5) / CELLS, 0.1)``, times 0.4 when
    ``i + j`` is odd; within ``LINE`` of a cell edge the colour is ``LINE_COLOR``; an L
    along the lower and left edges of cell (0, 0) is white.
    """
    u = np.asarray(u, dtype=np.float64)
    v = np.asarray(v, dtype=np.float64)
    i = np.clip(np.floor(u * CELLS), 0, CELLS - 1)
    j = np.clip(np.floor(v * CELLS), 0, CELLS - 1)
    rgb = np.stack([0.02 + 0.9 * (i + 0.5) / CELLS, 0.02 + 0.9 * (j + 0.5) / CELLS,
                    np.full(i.shape, 0.1)], axis=-1)
    rgb = np.where(((i + j) % 2 == 1)[..., None], 0.4 * rgb, rgb)
    fu = u * CELLS - i  # position in the cell, [0, 1)
    fv = v * CELLS - j
    edge = (np.minimum(fu, 1.0 - fu) < LINE * CELLS) | (np.minimum(fv, 1.0 - fv) < LINE * CELLS)
    rgb = np.where(edge[..., None], LINE_COLOR, rgb)
    thick, long = MARK
    in_l = (i == 0) & (j == 0) & (((fu < thick) & (fv < long)) | ((fv < thick) & (fu < long)))
    in_l &= ~edge
    return np.where(in_l[..., None], MARK_COLOR, rgb)


def main(out_dir: Path = HERE, size: int = SIZE) -> Path:
    """Write ``uv.png`` into ``out_dir`` and return its path."""
    c = (np.arange(size) + 0.5) / size
    u, v = np.meshgrid(c, c[::-1])  # row 0 at the top: v decreases down the image
    path = write_texture(out_dir / "uv.png", uv_color(u, v), bits=8, gamma="srgb")
    print(f"{path.name}: {size} x {size}, {path.stat().st_size / 1024:.1f} KiB")
    return path


if __name__ == "__main__":
    sys.exit(0 if main() else 1)
