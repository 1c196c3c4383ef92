"""The references' noise is measured right: the batches' standard error, its sRGB scale,
and a reference's stated noise against its real error from a converged render."""

from __future__ import annotations

import re

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from hypothesis.extra.numpy import arrays

from gallery import compare, references
from gallery.figures import read_figure, scenes_dir
from render.film import linear_to_srgb

KNEE = 0.0031308  # where the sRGB encoding turns from linear to a power


@given(st.floats(1e-4, 0.999).filter(lambda x: abs(x - KNEE) > 1e-5))
def test_srgb_slope_is_the_derivative_of_the_encoding(x):
    h = 1e-7 * max(x, 1e-3)
    numeric = (linear_to_srgb(np.array(x + h)) - linear_to_srgb(np.array(x - h))) / (2 * h)
    assert references.srgb_slope(np.array(x)) == pytest.approx(float(numeric), rel=1e-5)


def test_srgb_slope_at_the_extremes():
    x = np.array([-np.inf, -1e-300, 0.0, KNEE, 1.0, 1.0 + 1e-12, np.inf, np.nan])
    slope = references.srgb_slope(x)
    assert slope.tolist()[:5] == [0.0, 0.0, 12.92, 12.92, pytest.approx(1.055 / 2.4)]
    assert slope.tolist()[5:] == [0.0, 0.0, 0.0]  # clamped, or not a number: no grain


@settings(max_examples=50)
@given(arrays(np.float64, (5, 2, 3, 1), elements=st.floats(0, 10)))
def test_batches_give_the_mean_and_its_standard_error(images):
    batches = references.Batches((2, 3, 1))
    for img in images:
        batches.add(img, np.ones((2, 3)))
    assert np.allclose(batches.mean(), images.mean(axis=0))
    expected = images.std(axis=0, ddof=1) / np.sqrt(len(images))
    assert np.allclose(batches.stderr(), expected, atol=1e-6)
    assert np.all(np.isfinite(batches.stderr()))


def test_one_batch_has_no_standard_error_yet():
    batches = references.Batches((1, 1, 3))
    batches.add(np.ones((1, 1, 3)), np.ones((1, 1)))
    assert np.all(np.isinf(batches.stderr()))


@given(st.floats(0.0, 1.0), st.floats(0.0, 1.0), st.floats(0.1, 100.0))
def test_display_noise_scales_with_the_standard_error(value, stderr, k):
    mean = np.full((3, 4, 3), value)
    one = references.display_noise(mean, np.full_like(mean, stderr))
    assert references.display_noise(mean, np.full_like(mean, k * stderr)) == pytest.approx(k * one)
    assert one == pytest.approx(255 * references.srgb_slope(np.array(value)) * stderr)


def test_a_references_stated_noise_is_its_error_against_a_converged_render(tmp_path):
    """A 16-spp reference states its noise from its batches; its error against a render
    with 8 times the samples, seen in 8-bit sRGB, is that noise (the converged render's
    own noise adds in quadrature)."""
    path = tmp_path / "fig_13_03.toml"  # the gallery's Figure 13.3, at 128 x 96
    scene = (scenes_dir() / path.name).read_text(encoding="utf-8")
    path.write_text(re.sub(r"resolution = \[\d+, \d+\]", "resolution = [128, 96]", scene))
    fig = read_figure(path)
    facts = references.make_reference(fig, target=0.0, max_spp=16, folder=tmp_path,
                                      progress=False)
    assert facts["spp"] == 16 and facts["batches"] == 4 and facts["resolution"] == [128, 96]
    assert (tmp_path / "fig_13_03.png").is_file()
    ref = compare.read_reference("fig_13_03", tmp_path)
    converged = compare.render_figure(fig, 128, 99, resolution=(128, 96)).rgb()
    diff = 255 * (linear_to_srgb(ref) - linear_to_srgb(converged))
    measured = float(np.sqrt(np.mean(diff**2)))
    expected = facts["noise"] * np.sqrt(1 + 1 / 8)
    assert measured == pytest.approx(expected, rel=0.15), (measured, facts["noise"])
    # and the thresholds calibrate against it
    test = references.calibrate(fig, tmp_path)
    assert test["rmse_max"] == pytest.approx(compare.MARGIN * max(test["rmse"]), abs=1e-6)
    assert len(test["flip"]) == len(compare.CALIBRATION_SEEDS)
