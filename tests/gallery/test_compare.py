"""The regression rule: block averages, errors, and the verdict with its reasons."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from hypothesis.extra.numpy import arrays

from gallery import compare
from gallery.figures import figures


@settings(max_examples=50)
@given(st.integers(1, 4), st.integers(1, 5), st.integers(1, 5),
       st.data())
def test_downsample_is_the_mean_of_each_block(factor, bh, bw, data):
    img = data.draw(arrays(np.float64, (bh * factor, bw * factor, 3),
                           elements=st.floats(0, 1e6)))
    small = compare.downsample(img, factor)
    assert small.shape == (bh, bw, 3)
    assert np.allclose(small.mean(axis=(0, 1)), img.mean(axis=(0, 1)), rtol=1e-12, atol=1e-9)
    assert np.allclose(small[0, 0], img[:factor, :factor].mean(axis=(0, 1)))


def test_downsample_refuses_a_partial_block():
    with pytest.raises(ValueError, match="not a whole number of 2-pixel blocks"):
        compare.downsample(np.zeros((3, 4, 3)), 2)


def test_a_render_at_a_quarter_of_the_pixels_estimates_the_averaged_larger_one():
    """The test's premise: a box-filtered pixel 4 times larger is the mean of the 2 x 2
    pixels it covers, so a 128 x 96 render and a 256 x 192 one averaged down agree within
    their noise (same sample count per test pixel)."""
    fig = figures(["13.3"])[0]
    small = compare.render_figure(fig, 64, 1, resolution=(128, 96)).rgb()
    large = compare.render_figure(fig, 16, 2, resolution=(256, 192)).rgb()
    averaged = compare.downsample(large, 2)
    other = compare.render_figure(fig, 64, 3, resolution=(128, 96)).rgb()
    # the difference is what two independent renders of the same size differ by
    rms = np.sqrt(np.mean((small - averaged) ** 2))
    noise = np.sqrt(np.mean((small - other) ** 2))
    assert rms == pytest.approx(noise, rel=0.1)
    assert np.allclose(small.mean(axis=(0, 1)), averaged.mean(axis=(0, 1)), rtol=0.01)


ENTRY = {"test": {"rmse_max": 0.02, "flip_max": 0.05, "mean_std": [0.001, 0.001, 0.001]}}


def test_identical_images_pass_with_no_error(rng):
    ref = rng.uniform(0.0, 1.0, (24, 32, 3))
    outcome = compare.judge("x", ref.copy(), ref, ENTRY)
    assert outcome.rmse == 0.0 and outcome.flip == 0.0 and outcome.passed
    assert outcome.reasons() == [] and outcome.error_map.shape == (24, 32)


def test_a_changed_image_fails_and_says_why(rng):
    ref = rng.uniform(0.2, 0.6, (24, 32, 3))
    darker = ref * np.array([1.0, 1.0, 0.7])  # the blue of a wrong material
    outcome = compare.judge("x", darker, ref, ENTRY)
    assert not outcome.passed
    reasons = "; ".join(outcome.reasons())
    assert "RMSE" in reasons and "FLIP" in reasons and "mean of B off by" in reasons
    assert "mean of R" not in reasons


def test_noise_within_the_thresholds_passes_and_nan_fails(rng):
    ref = np.full((24, 32, 3), 0.3)
    noisy = ref + rng.normal(0.0, 0.005, ref.shape)
    assert compare.judge("x", noisy, ref, ENTRY).passed
    broken = noisy.copy()
    broken[0, 0, 0] = np.nan
    assert not compare.judge("x", broken, ref, ENTRY).passed


def test_shapes_must_agree():
    with pytest.raises(ValueError, match="the render is 4 x 2, the reference 8 x 4"):
        compare.judge("x", np.zeros((2, 4, 3)), np.zeros((4, 8, 3)), ENTRY)


def test_a_figure_without_a_reference_says_how_to_make_one():
    fig = figures(["13.3"])[0]
    with pytest.raises(KeyError, match="python -m gallery.references fig_13_03"):
        compare.check(fig, table={})
