"""df::diffuse_edf kernels: equal to the numpy class; normalised, chi-square, unit weight."""

from __future__ import annotations

import importlib

import numpy as np
import pytest
from df_kernel_adapter import KernelEdf, compare_edf, lane_dirs, lane_us
from render_edf_adapter import EdfAsBsdf

from render.df import diffuse_edf
from render.testing import chi2_test, sphere_integral

mod = importlib.import_module("render.df.diffuse_edf")


def test_signature_packs_nothing():
    assert mod.SIGNATURE.kind == "edf" and mod.SIGNATURE.width == 0


def test_kernels_equal_numpy(rng):
    wo = lane_dirs(rng, 5000)
    u1, u2 = lane_us(rng, len(wo))
    compare_edf(diffuse_edf(), KernelEdf(mod), wo, u1, u2, rtol=0.0)


def test_normalised_front_side_only_and_unit_weight(rng):
    e = KernelEdf(mod)
    rule = dict(n_beta=32, order=16)
    total = sphere_integral(lambda w: e.eval(w)[:, 0] * w[:, 2], [0.0, 0.0, 1.0], +1, **rule)
    pdf = sphere_integral(e.pdf, [0.0, 0.0, 1.0], +1, **rule)
    assert total == pytest.approx(1.0, abs=1e-9) and pdf == pytest.approx(1.0, abs=1e-9)
    below = lane_dirs(rng, 100)
    below[:, 2] = -np.abs(below[:, 2])
    assert not np.any(e.eval_pdf(below)[0]) and not np.any(e.pdf(below))
    s = e.sample(rng.random(100_000), rng.random((100_000, 2)))
    assert s.valid.mean() > 0.9999 and np.all(s.weight[s.valid] == 1.0)
    assert np.all(np.isfinite(s.wo)) and np.all(s.wo[s.valid, 2] > 0)
    assert s.weight.mean() == pytest.approx(1.0, abs=1e-3)  # the furnace: ∫ eval cos = 1


def test_chi2():
    res = chi2_test(EdfAsBsdf(KernelEdf(mod)), [0.0, 0.0, 1.0], sample_count=200_000)
    assert res.passed, str(res)
