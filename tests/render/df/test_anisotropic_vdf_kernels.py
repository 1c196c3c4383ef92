"""df::anisotropic_vdf kernels: equal to the numpy class, chi-square, normalised, KS, weight 1."""

from __future__ import annotations

import importlib

import numpy as np
import pytest
from df_kernel_adapter import KernelBsdf, compare_bsdf, lane_dirs, lane_us, pack
from scipy import stats

from render.bsdf import Lobe
from render.df import anisotropic_vdf
from render.df.anisotropic_vdf import G_MAX
from render.testing import chi2_test, consistency_error, direction, sample_lanes, sphere_integral

mod = importlib.import_module("render.df.anisotropic_vdf")
BIASES = (0.0, 0.3, -0.3, 0.99, -0.99, 0.9999, -0.9999, 1.0, -1.0)


def _kernel(g, n=1):
    return KernelBsdf(mod, Lobe.DIFFUSE, n=n, directional_bias=g)


def test_signature_clamps_to_g_max():
    assert mod.SIGNATURE.kind == "vdf" and mod.SIGNATURE.width == 1
    assert pack(mod.SIGNATURE, directional_bias=1.0).tolist() == [[G_MAX]]


@pytest.mark.parametrize("g", ["random", *BIASES])
def test_kernels_equal_numpy_over_random_lanes(g, rng):
    wo = lane_dirs(rng, 5000)
    wi = lane_dirs(rng, 5000)[rng.permutation(len(wo))]
    n = len(wo)
    u1, u2 = lane_us(rng, n)
    bias = rng.uniform(-1.0, 1.0, n) if g == "random" else g
    compare_bsdf(anisotropic_vdf(bias), _kernel(bias, n), wo, wi, u1, u2, rtol=0.0)


_CHI2 = [(g, wo) for g in (0.0, 0.7, -0.7, 0.99) for wo in ((30.0, 20.0), (120.0, 300.0))]


@pytest.mark.parametrize(("g", "wo"), _CHI2, ids=[f"g{g}-wo{w[0]:.0f}" for g, w in _CHI2])
def test_chi2(g, wo):
    res = chi2_test(_kernel(g), direction(*wo), sample_count=100_000, test_count=len(_CHI2))
    assert res.passed, str(res)


@pytest.mark.parametrize("g", [0.0, 0.5, -0.5, 0.9999, -0.9999])
def test_pdf_integrates_to_one_and_furnace(g, rng):
    vdf = _kernel(g)
    wo = direction(60.0, 200.0)
    peak = -wo if g >= 0 else wo
    total = sum(sphere_integral(lambda w: vdf.pdf(np.tile(wo, (len(w), 1)), w), peak, side)
                for side in (+1, -1))
    assert total == pytest.approx(1.0, abs=1e-6)
    s = sample_lanes(vdf, wo, 50_000, seed=5)
    assert np.all(s.valid) and np.all(s.weight == 1.0)  # furnace: lossless, weight 1
    pdf_err, weight_err = consistency_error(vdf, np.tile(wo, (len(s.wi), 1)), s)
    assert pdf_err.max() < 1e-9 and weight_err.max() < 1e-9
    assert np.all(vdf.albedo(wo[None]) == 1.0)


@pytest.mark.parametrize("g", [0.5, -0.5, 0.99])
def test_cos_theta_follows_hg(g):
    wo = direction(40.0, 75.0)
    s = sample_lanes(_kernel(g), wo, 40_000, seed=3)
    mu = np.clip(-(s.wi @ wo), -1.0, 1.0)
    cdf = lambda x: (1 - g * g) / (2 * g) * (1 / np.sqrt(1 + g * g - 2 * g * x) - 1 / (1 + g))  # noqa: E731
    assert stats.kstest(mu, cdf).pvalue > 1e-3
    back = (s.wi @ wo) > 0
    assert np.all(s.lobe[back] == Lobe.DIFFUSE_REFLECTION)
    assert np.all(s.lobe[~back] == Lobe.DIFFUSE_TRANSMISSION)


def test_degenerate_directions_stay_finite_as_numpy(rng):
    # a zero wo: finite, and the same as the numpy class (which fails only the lanes whose
    # sin theta <= 0.5, despite its comment)
    wo = np.zeros((200, 3))
    u1, u2 = lane_us(rng, 200)
    compare_bsdf(anisotropic_vdf(0.5), _kernel(0.5), wo, -wo, u1, u2, rtol=0.0)
    s = _kernel(0.5).sample(wo, u1, u2)
    assert np.all(np.isfinite(s.wi)) and np.all(np.isfinite(s.pdf))
