"""The sample values (render.sampler): Sobol's sequence, stratified, uniform, padded,
and an image that does not depend on how its samples are cut."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from scipy import stats
from scipy.stats import qmc

from render import sampler as S


def _unscrambled(i: int) -> tuple[float, float]:
    """Sobol's first two dimensions at index ``i`` from the module's tables."""
    x = int(f"{i:032b}"[::-1], 2)
    t = S.SOBOL_TABLE
    y = t[0, i & 255] ^ t[1, (i >> 8) & 255] ^ t[2, (i >> 16) & 255] ^ t[3, i >> 24]
    return x / 2**32, int(y) / 2**32


def test_the_tables_are_sobols_sequence():
    """The same 2^12 points as scipy's Sobol (Joe and Kuo's direction numbers), and the
    byte tables give the xor of the generator columns for any 32-bit index."""
    ours = np.array([_unscrambled(i) for i in range(1 << 12)])
    ref = qmc.Sobol(2, scramble=False).random_base2(12)
    assert np.array_equal(ours[np.lexsort(ours.T)], ref[np.lexsort(ref.T)])
    columns = S._direction_numbers()
    for i in np.random.default_rng(1).integers(0, 1 << 32, 200).tolist() + [(1 << 32) - 1]:
        y = 0
        for k in range(32):
            if (i >> k) & 1:
                y ^= int(columns[k])
        assert _unscrambled(i)[1] == y / 2**32


@settings(max_examples=60)
@given(pixel=st.integers(0, 1 << 40), pair=st.integers(0, 1 << 41),
       seed=st.integers(0, 1 << 62), m=st.integers(0, 10), block=st.integers(0, 3))
def test_every_aligned_power_of_two_block_is_a_net(pixel, pair, seed, m, block):
    """Samples [b 2^m, (b + 1) 2^m) of a pixel put one point in every elementary box of
    area 2^-m (every shape 2^-a x 2^-(m - a)): a (0, m, 2)-net, as Owen scrambling and
    the index shuffle keep it."""
    n = 1 << m
    idx = np.arange(block * n, (block + 1) * n)
    u = S.pair_values(np.full(n, pixel), idx, pair, seed)
    assert u.min() >= 0.0 and u.max() < 1.0
    for a in range(m + 1):
        box = np.floor(u[:, 0] * 2**a) * 2 ** (m - a) + np.floor(u[:, 1] * 2 ** (m - a))
        assert len(np.unique(box)) == n


def test_values_are_uniform_and_pairs_and_pixels_independent():
    """Over 4096 pixels x 16 samples: each coordinate passes a chi-square test of
    uniformity (64 bins), and values of different pairs, of x and y, and of neighbouring
    pixels are uncorrelated (|r| < 4 standard errors)."""
    pix = np.repeat(np.arange(4096), 16)
    idx = np.tile(np.arange(16), 4096)
    a, b = S.pair_values(pix, idx, 5, 1), S.pair_values(pix, idx, 6, 1)
    for col in (a[:, 0], a[:, 1], b[:, 0]):
        counts = np.bincount((col * 64).astype(int), minlength=64)
        assert stats.chisquare(counts).pvalue > 1e-4
    bound = 4 / np.sqrt(len(pix))
    c = S.pair_values(pix + 1, idx, 5, 1)
    for x, y in ((a[:, 0], b[:, 0]), (a[:, 1], b[:, 1]), (a[:, 0], a[:, 1]), (a[:, 0], c[:, 0])):
        assert abs(np.corrcoef(x, y)[0, 1]) < bound


def test_a_pixels_mean_converges_faster_than_independent_sampling():
    """The integral of a smooth 2D function (x y) over 4096 pixels at 64 samples: the
    spread of the pixel means is far below independent sampling's (1/sqrt(n)); that is
    the point of the sampler."""
    pix = np.repeat(np.arange(4096), 64)
    u = S.pair_values(pix, np.tile(np.arange(64), 4096), 9, 3)
    means = (u[:, 0] * u[:, 1]).reshape(4096, 64).mean(axis=1)
    independent = np.sqrt(7 / 144 / 64)  # var(xy) = 1/9 - 1/16
    assert abs(means.mean() - 0.25) < 4 * means.std() / 64
    assert means.std() < independent / 10


def test_the_kernels_draw_is_the_pair_value():
    """What the path kernel draws (``sample_pair`` at the pixel's hash) is
    ``pair_values``' value, for each pair of a path segment, and a segment's five pairs
    are distinct (each decides its own choice)."""
    pairs = (S.P_LIGHT, S.P_BSDF, S.P_CHOICE, S.P_FLIGHT, S.P_CUTOUT)
    assert sorted(pairs) == list(range(S.PAIRS_PER_SEGMENT))
    pixel, index = np.array([3, 7, 7, 11]), np.array([0, 5, 6, 1])
    for kind in S.SAMPLERS.values():
        for g in pairs:
            pair = S.FIRST_SEGMENT_PAIR + 3 * S.PAIRS_PER_SEGMENT + g
            want = S.pair_values(pixel, index, pair, 4, kind)
            got = [S.sample_pair(S.SOBOL_TABLE, np.uint64(S.pixel_hash(4, p)), i, pair, kind)
                   for p, i in zip(pixel, index, strict=True)]
            assert np.array_equal(np.array(got), want)


def test_extreme_indices_pixels_and_seeds():
    """Index 0 and 2^32 - 1, pixel and seed 0 and 2^63 - 1: in [0, 1), finite, and
    index 2^32 wraps to index 0 (the sequence has 2^32 points)."""
    big = (1 << 63) - 1
    for pixel, seed in ((0, 0), (big, big), (0, big)):
        u = S.pair_values(np.array([pixel] * 3), np.array([0, (1 << 32) - 1, 1 << 32]), 0, seed)
        assert np.isfinite(u).all() and u.min() >= 0.0 and u.max() < 1.0
        assert np.array_equal(u[0], u[2])


@pytest.mark.parametrize("cut", [1, 7, 100])
def test_the_image_does_not_depend_on_how_samples_are_cut(cut):
    """Tracing a pixel's samples in pieces gives each sample the same value as tracing
    them at once (values depend on pixel, index and seed only)."""
    from pathlib import Path

    from render.integrator import Integrator
    from render.scene import load_scene

    root = Path(__file__).resolve().parents[2]
    scene = load_scene(root / "gallery" / "scenes" / "fig_14_28.toml")
    integ = Integrator(scene, scene.build(), [])
    pixel = np.repeat(np.arange(0, 4000, 37), 3)
    index = np.tile(np.arange(3), len(pixel) // 3)
    whole, _, _ = integ.trace(pixel, index, 5)
    parts = [integ.trace(pixel[a:a + cut], index[a:a + cut], 5)[0]
             for a in range(0, len(pixel), cut)]
    assert whole.any() and np.array_equal(whole, np.concatenate(parts))
