"""df::diffuse_edf: 1/pi radiance per unit exitance, cosine sampling, front side only."""

from __future__ import annotations

import numpy as np
import pytest
from render_edf_adapter import EdfAsBsdf

from render.df import diffuse_edf
from render.testing import chi2_test, direction, sphere_integral


def test_normalised_to_unit_exitance():
    e = diffuse_edf()
    # ∫ eval cos theta = 1 over the hemisphere, so intensity I shows as radiance I/pi
    total = sphere_integral(lambda w: e.eval(w)[:, 0] * w[:, 2], [0.0, 0.0, 1.0], +1)
    assert total == pytest.approx(1.0, abs=1e-12)
    assert np.allclose(e.eval(direction(40.0)[None]), 1 / np.pi)


def test_front_side_only():
    e = diffuse_edf()
    w = np.stack([direction(100.0), direction(180.0), direction(90.0)])
    assert not np.any(e.eval(w)) and not np.any(e.pdf(w))


def test_sample_weight_is_one(rng):
    e = diffuse_edf()
    s = e.sample(rng.random(10_000), rng.random((10_000, 2)))
    ok = s.valid
    assert ok.mean() > 0.9999 and np.all(s.wo[ok, 2] > 0)
    assert np.allclose(s.weight[ok], 1.0) and np.allclose(s.pdf[ok], e.pdf(s.wo[ok]))
    assert np.allclose(s.weight[ok], e.eval(s.wo[ok]) * s.wo[ok, 2:3] / s.pdf[ok, None])


def test_chi2():
    res = chi2_test(EdfAsBsdf(diffuse_edf()), direction(0.0))
    assert res.passed, str(res)


def test_degenerate_samples_are_finite():
    e = diffuse_edf()
    u2 = np.array([[0.0, 0.0], [np.nextafter(1, 0), 0.5], [0.5, 0.5], [0.0, np.nextafter(1, 0)]])
    s = e.sample(np.zeros(4), u2)
    assert np.all(np.isfinite(s.wo)) and np.all(np.isfinite(s.weight)) and np.all(s.pdf >= 0)
