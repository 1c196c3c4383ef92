"""How an image's samples are cut into passes and chunks (render.passes), and the film
patches chunks send back (render.film.FilmPatch): merged in order they give the bits
of adding the samples themselves, at the extremes of float64 too."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from hypothesis.extra import numpy as hnp

from render.film import AOVS, Film, FilmPatch
from render.passes import CHUNK, PASS_SAMPLES, PassPlan
from render.scene import RenderSettings

#: every float64 worth a test: huge (sums overflow), subnormal, signed zeros, inf, nan
EXTREME = st.floats(allow_nan=True, allow_infinity=True, width=64) | st.sampled_from(
    [1.7976931348623157e308, -1.7976931348623157e308, 5e-324, -5e-324, 0.0, -0.0, 1.0]
)


@st.composite
def batches(draw):
    """A film size and batches of samples (pixel, rgb, alpha, every AOV)."""
    npix = draw(st.integers(1, 40))
    out = []
    for _ in range(draw(st.integers(1, 4))):
        n = draw(st.integers(0, 60))
        pixel = draw(hnp.arrays(np.int64, n, elements=st.integers(0, npix - 1)))
        f = lambda shape: draw(hnp.arrays(np.float64, shape, elements=EXTREME))  # noqa: E731
        aovs = {name: f((n, len(ch))) for name, ch in AOVS.items() if name != "object_id"}
        aovs["object_id"] = draw(hnp.arrays(np.int32, n, elements=st.integers(-1, 5)))
        out.append((pixel, f((n, 3)), f(n), aovs))
    return npix, out


@settings(max_examples=150)
@given(batches())
def test_merged_patches_are_the_samples_summed_in_order(case):
    """The film's sums are the samples' sums in the order they were added, per pixel
    (np.bincount of each batch over the whole image, added batch after batch), bit for
    bit: a patch covers only its pixel range, and the pixels outside it are untouched."""
    npix, data = case
    film = Film(npix, 1, aovs=list(AOVS))
    rgb = np.zeros((npix, 3))
    alpha = np.zeros(npix)
    count = np.zeros(npix, dtype=np.int64)
    aov = {n: np.zeros((npix, len(c))) for n, c in AOVS.items() if n != "object_id"}
    first_id = np.full(npix, -1, dtype=np.int32)
    seen = np.zeros(npix, dtype=bool)
    nonfinite = 0
    # sums of +-1.8e308 overflow to inf, and inf - inf is nan: IEEE's answer, the same
    # on both sides (compared bit for bit below), not an error here
    with np.errstate(over="ignore", invalid="ignore"):
        for pixel, c, a, aovs in data:
            patch = FilmPatch.of_samples(pixel, c, a, aovs, film.aov_names)
            if len(pixel):
                assert patch.start == pixel.min()
                assert len(patch.count) == pixel.max() - pixel.min() + 1
            film.merge(patch)
            bad = ~np.all(np.isfinite(c), axis=1)
            nonfinite += int(bad.sum())
            c = np.where(bad[:, None], 0.0, c)
            for k in range(3):
                rgb[:, k] += np.bincount(pixel, c[:, k], minlength=npix)
            alpha += np.bincount(pixel, a, minlength=npix)
            count += np.bincount(pixel, minlength=npix)
            for name, acc in aov.items():
                for k in range(acc.shape[1]):
                    acc[:, k] += np.bincount(pixel, aovs[name][:, k], minlength=npix)
            for p, i in zip(pixel, aovs["object_id"], strict=True):
                if not seen[p]:
                    first_id[p], seen[p] = i, True
    mean = np.maximum(count, 1).astype(np.float64)
    same = lambda x, y: np.array_equal(x, y, equal_nan=True)  # noqa: E731
    assert np.array_equal(film.spp.ravel(), count)
    assert same(film.rgb().reshape(-1, 3), rgb / mean[:, None])
    assert same(film.alpha().ravel(), alpha / mean)
    for name, acc in aov.items():
        assert same(film.aov(name).reshape(npix, -1), acc / mean[:, None]), name
    assert np.array_equal(film.aov("object_id").ravel(), first_id)
    assert film.stats.get("nonfinite_samples", 0) == nonfinite


def test_a_patch_outside_the_film_is_refused():
    patch = FilmPatch.of_samples(np.array([5, 6]), np.ones((2, 3)), np.ones(2), None, ())
    with pytest.raises(ValueError, match="covers pixels 5..6, the film has 6"):
        Film(3, 2).merge(patch)
    assert patch.nbytes == 2 * (3 * 8 + 8 + 8)


@settings(max_examples=200)
@given(
    st.integers(1, 4096),
    st.integers(1, 2048),
    st.integers(1, 5000),
    st.integers(1, 64),
)
def test_chunks_tile_every_pass_and_the_passes_sum_to_spp(width, height, spp, per_pass):
    npix = width * height
    plan = PassPlan.of(RenderSettings(width, height, spp=spp, spp_per_pass=per_pass), npix)
    assert plan.per_pass >= min(spp, per_pass, -(-PASS_SAMPLES // npix))
    assert sum(plan.pass_spp(k) for k in range(plan.passes)) == spp
    assert all(plan.pass_spp(k) >= 1 for k in range(plan.passes))
    chunks = 0
    for k in range(plan.passes):
        items = plan.chunks(k)
        chunks += len(items)
        # consecutive, disjoint, at most CHUNK samples: each pixel gets pass_spp samples
        starts = [a for _, _, (a, _) in items]
        ends = [b for _, _, (_, b) in items]
        assert starts[0] == 0 and ends[-1] == npix * plan.pass_spp(k)
        assert starts[1:] == ends[:-1]
        assert all(0 < b - a <= CHUNK for a, b in zip(starts, ends, strict=True))
        assert all(i[0] == k and i[1] == plan.pass_spp(k) for i in items)
    assert chunks == plan.chunk_count


def test_time_budget_plan_and_overrides():
    s = RenderSettings(100, 100, spp=7, time=3.0, spp_per_pass=2, seed=4)
    plan = PassPlan.of(s, 10_000)
    assert (plan.passes, plan.time_budget, plan.seed, plan.chunk_count) == (None, 3.0, 4, None)
    assert plan.per_pass == -(-PASS_SAMPLES // 10_000) and plan.pass_spp(1000) == plan.per_pass
    # an spp given overrides the scene's time budget; a seed given, the scene's seed
    plan = PassPlan.of(s, 10_000, spp=5, seed=9)
    assert (plan.passes, plan.per_pass, plan.time_budget, plan.seed) == (1, 5, None, 9)


