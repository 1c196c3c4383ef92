"""MDL ``df::measured_factor``: a Bsdf scaled by a 2-D table of the half-vector angles.

MDL signature (1.5)::

    bsdf measured_factor(uniform texture_2d values, bsdf base = bsdf());

Model (libbsdf, ``reference/mdl-distribution-functions.md`` §4): with ``h`` the
reflection half vector (a transmitted ``wi`` mirrored through the tangent plane first),
the factor is the texture at ``u = acos(|wi.h|) 2/pi``, ``v = acos(|n.h|) 2/pi``
(bilinear between texel centres, clamped at the edges, negative values read as 0; MDL's
texture space: ``v = 0`` is the image's bottom row).  The table may exceed 1: a factor
above 1 gains energy, as the spec allows.  ``eval = factor base.eval``, the pdf the
base's.  The texture is uniform: its texels go to the program's table (not to every
lane's parameter row).
"""

from __future__ import annotations

import math

import numpy as np

from render.df._layer import scale_half_vector
from render.df._registry import Df, Node
from render.df._signature import REQUIRED, Param, Signature
from render.jit import njit
from render.program import TABLE, Program, ProgramBsdf, combine

__all__ = ["MeasuredFactor", "measured_factor", "SIGNATURE", "scale", "texture_table"]

SIGNATURE = Signature("bsdf", (
    Param("values", "texture_2d", REQUIRED, uniform=True),
    Param("base", "bsdf", None),
))
_TWO_OVER_PI = 2.0 / math.pi


@njit
def _texel(T, t, u, v):
    """Bilinear lookup ``(r, g, b)`` at ``(u, v)`` in [0, 1]^2 (texel centres, clamped; at
    least 0); the table: ``[width, height, rows from v = 0 up...]`` of RGB texels."""
    w, h = int(T[t]), int(T[t + 1])
    x = min(max(u * w - 0.5, 0.0), w - 1.0)
    y = min(max(v * h - 0.5, 0.0), h - 1.0)
    i0 = min(int(math.floor(x)), max(w - 2, 0))
    j0 = min(int(math.floor(y)), max(h - 2, 0))
    i1, j1 = min(i0 + 1, w - 1), min(j0 + 1, h - 1)
    fx, fy = x - i0, y - j0
    base = t + 2
    a = base + (j0 * w + i0) * 3
    b = base + (j0 * w + i1) * 3
    c = base + (j1 * w + i0) * 3
    d = base + (j1 * w + i1) * 3
    wa, wb = (1.0 - fy) * (1.0 - fx), (1.0 - fy) * fx
    wc, wd = fy * (1.0 - fx), fy * fx
    return (max(wa * T[a] + wb * T[b] + wc * T[c] + wd * T[d], 0.0),
            max(wa * T[a + 1] + wb * T[b + 1] + wc * T[c + 1] + wd * T[d + 1], 0.0),
            max(wa * T[a + 2] + wb * T[b + 2] + wc * T[c + 2] + wd * T[d + 2], 0.0))


@njit
def scale(P, row, b, flags, wox, woy, woz, wix, wiy, wiz, T, t):
    """the table's factor per channel at the half vector's angles (0 where ``wo.h < 0``)."""
    kh, nh = scale_half_vector(wox, woy, woz, wix, wiy, wiz)
    if kh < 0.0:
        return 0.0, 0.0, 0.0
    u = math.acos(kh) * _TWO_OVER_PI  # |wi.h| = |wo.h| for the reflection half vector
    v = math.acos(nh) * _TWO_OVER_PI
    return _texel(T, t, u, v)


def texture_table(texture) -> np.ndarray:
    """The table :func:`scale` reads from a :class:`displacement.textures.Texture` (or an
    ``(H, W[, C])`` array, row 0 at the top as images are stored): one or three channels
    (one is grey), rows flipped so that row 0 is ``v = 0``."""
    data = np.asarray(getattr(texture, "data", texture), dtype=np.float64)
    if data.ndim == 2:
        data = data[:, :, None]
    if data.ndim != 3 or data.shape[0] < 1 or data.shape[1] < 1:
        raise ValueError(f"df::measured_factor(values) must be a 2-D texture, got shape "
                         f"{data.shape}")
    if data.shape[2] == 1:
        data = np.repeat(data, 3, axis=2)
    data = data[:, :, :3]
    if not np.all(np.isfinite(data)):
        raise ValueError("df::measured_factor(values) must hold finite values")
    h, w = data.shape[:2]
    return np.concatenate([[w, h], data[::-1].reshape(-1)])


class MeasuredFactor(ProgramBsdf):
    """``df::measured_factor`` over lanes: its kernel, run by :mod:`render.interpreter`.

    Parameters
    ----------
    values : Texture or (H, W[, C]) array
        MDL's ``texture_2d`` (uniform).
    base : bound bsdf or None
    """

    mdl_name = "measured_factor"
    signature = SIGNATURE

    def __init__(self, values, base=None):
        title = "df::measured_factor"
        if values is None:
            raise ValueError(f"{title} needs the argument 'values' (a texture_2d)")
        table = texture_table(values)
        if base is not None and not isinstance(base, ProgramBsdf):
            raise ValueError(f"{title}(base) must be a bound bsdf or None for MDL's black "
                             f"bsdf(), got {type(base).__name__}")
        prog = combine("bsdf", NODE.op, np.zeros((1, 0)), 0,
                       [None if base is None else base.program])
        code = prog.code.copy()
        code[prog.root, TABLE] = len(prog.tables)
        ProgramBsdf.__init__(self, Program("bsdf", code, prog.kids, prog.frames, prog.blocks,
                                           np.concatenate([prog.tables, table]), prog.lobes))
        self.base = base


measured_factor = MeasuredFactor
NODE = Node("measured_factor", "bsdf", "modifier", SIGNATURE, passes_film=True, scale=scale)
DF = Df("measured_factor", SIGNATURE, (NODE,), constructor=MeasuredFactor)
