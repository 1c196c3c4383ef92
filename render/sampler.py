"""The path tracer's sample values: Owen-scrambled Sobol points, padded in pairs.

A path's random numbers are not drawn from a stream.  Sample ``index`` of pixel
``pixel`` takes dimension pair ``pair`` (the pixel position, the light sample of a
vertex, its bsdf sample, ...) from the 2D Sobol sequence, as Burley's hash-based Owen
scrambling does it ("Practical Hash-based Owen Scrambling", JCGT 9(4), 2020; the same
scheme as Blender Cycles' Sobol-Burley pattern and pbrt-v4's ``PaddedSobolSampler``):

* the sample index is shuffled by a nested uniform (Owen) scramble seeded by
  ``(seed, pixel, pair)``, so that each pair is an independent permutation of the
  sequence (*padding*: pairs are not correlated with each other);
* the first two Sobol dimensions of the shuffled index form a (0, 2)-sequence: any
  first ``2^k`` samples of a pixel are stratified in every dyadic box of area
  ``2^-k``;
* each coordinate is Owen-scrambled with its own seed, so every sample is uniform on
  ``[0, 1)^2`` and pixels are independent estimates (tests may take the spread of
  pixels as the noise, as with independent random numbers).

Every value depends only on ``(seed, pixel, index, pair)``: the image does not depend
on how the samples are cut into chunks or passes.  Stratification lowers the noise of
the integrals that a few pairs decide (the pixel footprint, direct light, the first
bounce) well below independent sampling's at the same sample count (measured in
``docs/render.md``, "Sample values").

Examples
--------
>>> import numpy as np
>>> u = pair_values(np.zeros(16, np.int64), np.arange(16), 0, 7)
>>> bool(u.min() >= 0.0 and u.max() < 1.0)
True
>>> # 16 samples: one in each of the 4 x 4 strata (a (0, 4, 2)-net)
>>> sorted(np.unique((u * 4).astype(int) @ [4, 1]).tolist()) == list(range(16))
True
"""

from __future__ import annotations

import llvmlite.ir as llvm_ir
import numpy as np
from numba import types
from numba.core import cgutils
from numba.extending import intrinsic

from render.jit import njit

__all__ = ["CAMERA_PAIR", "FIRST_SEGMENT_PAIR", "HERO_PAIR", "PAIRS_PER_SEGMENT", "P_LIGHT",
           "P_BSDF", "P_CHOICE", "P_FLIGHT", "P_CUTOUT", "SHADOW_PAIRS", "SAMPLERS",
           "SOBOL_TABLE", "pair_values", "pixel_hash", "sample_pair"]

_M32 = 0xFFFFFFFF


def _direction_numbers() -> np.ndarray:
    """(32,) the generator matrix columns of Sobol's second dimension (primitive
    polynomial x + 1, m_1 = 1): m_k = m_{k-1} xor 2 m_{k-1}, v_k = m_k 2^(32 - k)."""
    v = np.zeros(32, dtype=np.int64)
    m = 1
    for k in range(1, 33):
        v[k - 1] = (m << (32 - k)) & _M32
        m ^= m << 1
    return v


def _byte_tables(v: np.ndarray) -> np.ndarray:
    """(4, 256) the xor of the columns ``v`` selected by each byte value at each of the
    four byte positions of an index (four lookups instead of a loop over 32 bits)."""
    t = np.zeros((4, 256), dtype=np.int64)
    for pos in range(4):
        for b in range(256):
            for k in range(8):
                if (b >> k) & 1:
                    t[pos, b] ^= v[8 * pos + k]
    return t


#: the Sobol second dimension's byte tables (the kernels' ``v1``)
SOBOL_TABLE = _byte_tables(_direction_numbers())

#: the pairs of a path: the position in the pixel, the hero channel (media), then
#: :data:`PAIRS_PER_SEGMENT` per path segment; shadow rays' cutout decisions take theirs
#: from ``SHADOW_PAIRS`` on (by segment and crossing), apart from the paths'
CAMERA_PAIR, HERO_PAIR, FIRST_SEGMENT_PAIR = 0, 1, 2
#: ``[render] sampler``: Owen-scrambled Sobol points, or independent uniforms (a hash of
#: the same pixel, index and pair: for comparison, and for checks that want them)
SOBOL, INDEPENDENT = 0, 1
SAMPLERS = {"sobol": SOBOL, "independent": INDEPENDENT}
SHADOW_PAIRS = 1 << 40

#: a path segment's pairs, from ``FIRST_SEGMENT_PAIR + segment * PAIRS_PER_SEGMENT`` on:
#: (light position), (bsdf direction), (light choice, bsdf lobe), (free flight, roulette),
#: (cutout, unused); the pairs that decide 2D integrals are Sobol's (0, 2).  The path
#: kernel draws each only where the vertex needs it.
P_LIGHT, P_BSDF, P_CHOICE, P_FLIGHT, P_CUTOUT = 0, 1, 2, 3, 4
PAIRS_PER_SEGMENT = 5


@intrinsic
def _reverse(typingctx, x):
    """The 32 low bits of the integer ``x`` in reverse order (LLVM's ``bitreverse``: a
    few instructions, one on CPUs with GFNI), as int64."""
    def codegen(context, builder, signature, args):
        i32, i64 = llvm_ir.IntType(32), llvm_ir.IntType(64)
        fn = cgutils.get_or_insert_function(builder.module, llvm_ir.FunctionType(i32, [i32]),
                                            "llvm.bitreverse.i32")
        return builder.zext(builder.call(fn, [builder.trunc(args[0], i32)]), i64)

    return types.int64(x), codegen


@njit(inline="always")
def _laine_karras(x, seed):
    """Burley's Laine-Karras-style hash of the 32-bit ``x``: each bit flipped by a hash
    of the bits below it (of the bits above it, on reversed input)."""
    x = (x + seed) & _M32
    x ^= (x * 0x6C50B47C) & _M32
    x ^= (x * 0xB82F1E52) & _M32
    x ^= (x * 0xC7AFE638) & _M32
    x ^= (x * 0x8D22F6E6) & _M32
    return x


@njit(inline="always")
def _owen(x, seed):
    """Nested uniform (Owen) scramble of the 32-bit ``x``: the hash on the reversed bits
    (each bit flipped by a hash of the bits above it)."""
    return _reverse(_laine_karras(_reverse(x), seed))


@njit(inline="always")
def _mix(h):
    """splitmix64's finalizer: 64 well-mixed bits of ``h``."""
    h = (h ^ (h >> np.uint64(30))) * np.uint64(0xBF58476D1CE4E5B9)
    h = (h ^ (h >> np.uint64(27))) * np.uint64(0x94D049BB133111EB)
    return h ^ (h >> np.uint64(31))


@njit(inline="always")
def pixel_hash(seed, pixel):
    """64 bits that name ``pixel`` of the render seeded ``seed``."""
    return _mix(np.uint64(seed) * np.uint64(0x9E3779B97F4A7C15) + np.uint64(pixel))


@njit
def sample_pair(v1, ph, index, pair, kind):
    """Sample ``index`` of the pixel hashed ``ph`` (:func:`pixel_hash`) in dimension
    pair ``pair``: two uniforms in [0, 1) (``kind`` SOBOL or INDEPENDENT)."""
    h = _mix(ph ^ np.uint64(pair))
    m = np.uint64(_M32)
    scale = 1.0 / 4294967296.0
    if kind == INDEPENDENT:
        h = _mix(h ^ (np.uint64(index) * np.uint64(0x9E3779B97F4A7C15)))
        return float(h >> np.uint64(32)) * scale, float(h & m) * scale
    s_i, s_x = np.int64(h & m), np.int64(h >> np.uint64(32))
    s_y = np.int64((h * np.uint64(0xD6E8FEB86659FD93)) >> np.uint64(32))
    x = _laine_karras(_reverse(index), s_i)  # Sobol's first dimension of the shuffled
    i = _reverse(x)  # index i = _owen(index): its radical inverse
    # the second: the xor of the generator columns of i's set bits, a byte at a time
    y = v1[0, i & 255] ^ v1[1, (i >> 8) & 255] ^ v1[2, (i >> 16) & 255] ^ v1[3, i >> 24]
    return float(_owen(x, s_x)) * scale, float(_owen(y, s_y)) * scale


@njit(allocates=True)
def _pair_values(v1, pixel, index, pair, seed, kind):
    n = len(pixel)
    out = np.empty((n, 2))
    for i in range(n):
        out[i, 0], out[i, 1] = sample_pair(v1, pixel_hash(seed, pixel[i]), index[i], pair, kind)
    return out


def pair_values(pixel: np.ndarray, index: np.ndarray, pair: int, seed: int,
                kind: int = SOBOL) -> np.ndarray:
    """(n, 2) the values of dimension pair ``pair`` for samples ``index`` (n,) of
    pixels ``pixel`` (n,) (both int64)."""
    return _pair_values(SOBOL_TABLE, np.asarray(pixel, dtype=np.int64),
                        np.asarray(index, dtype=np.int64), int(pair), int(seed), int(kind))
