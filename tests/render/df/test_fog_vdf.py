"""df::fog_vdf: Jendersie and d'Eon's approximate Mie phase function (HG + Draine) on the
kernels that render: χ², normalisation, exact sampling (weight 1, the mean cosine in
closed form), reciprocity, the fit's ranges and their joins, extremes, bad input."""

from __future__ import annotations

import numpy as np
import pytest
from scipy import stats

from render import df
from render.df.fog_vdf import D_MAX, D_MIN, fog_parameters
from render.testing import (
    chi2_test,
    consistency_error,
    direction,
    sample_lanes,
    sphere_integral,
    tile,
)

#: droplet diameters across the three ranges of the fit, their joins and the clamps
SIZES = (D_MIN, 0.5, 1.4999, 1.5, 3.0, 4.9999, 5.0, 8.0, 20.0, D_MAX)
WOS = ((30.0, 20.0), (120.0, 300.0))
CHI2 = [(d, wo) for d in (0.1, 0.7, 2.0, 8.0, 50.0) for wo in WOS]


def fog_pdf(d: float, mu: np.ndarray) -> np.ndarray:
    """The published blend in closed form (the test's own evaluation)."""
    g_hg, g_d, a, w = fog_parameters(d)

    def hg(g):
        return (1 - g * g) / (4 * np.pi * (1 + g * g - 2 * g * mu) ** 1.5)

    draine = hg(g_d) * (1 + a * mu * mu) / (1 + a * (1 + 2 * g_d * g_d) / 3)
    return (1 - w) * hg(g_hg) + w * draine


def mean_cosine(d: float) -> float:
    """E[mu] of the blend: g for HG; for Draine's function (E[mu] + a E[mu^3]) / (1 + a
    E[mu^2]) with HG's moments E[P_l(mu)] = g^l: g (1 + a (3 + 2 g^2) / 5) / (1 + a (1 +
    2 g^2) / 3)."""
    g_hg, g_d, a, w = fog_parameters(d)
    e_d = g_d * (1 + a * (3 + 2 * g_d * g_d) / 5) / (1 + a * (1 + 2 * g_d * g_d) / 3)
    return (1 - w) * g_hg + w * e_d


@pytest.mark.parametrize(("d", "wo"), CHI2, ids=[f"d{d}-wo{w[0]:.0f}" for d, w in CHI2])
def test_chi2_sample_against_pdf(d, wo):
    res = chi2_test(df.fog_vdf(d), direction(*wo), sample_count=100_000, test_count=len(CHI2))
    assert res.passed, str(res)


@pytest.mark.parametrize("d", SIZES)
def test_pdf_integrates_to_one_and_is_the_published_blend(d, rng):
    v = df.fog_vdf(d)
    wo = direction(60.0, 200.0)
    total = sum(sphere_integral(lambda w: v.pdf(tile(wo, len(w)), w), -wo, side, n_beta=128,
                                order=16) for side in (+1, -1))
    assert abs(total - 1.0) < 1e-7, total
    wi = rng.normal(size=(400, 3))
    wi /= np.linalg.norm(wi, axis=1, keepdims=True)
    mu = -(wi @ wo)
    np.testing.assert_allclose(v.pdf(tile(wo, 400), wi), fog_pdf(d, mu), rtol=1e-12)


@pytest.mark.parametrize("d", SIZES)
def test_sampling_is_exact(d):
    """Weight 1 everywhere, pdf and eval consistent, and the cosine distributed as the
    blend: its mean in closed form, and a KS test against its CDF (quadrature)."""
    v = df.fog_vdf(d)
    wo = direction(40.0, 75.0)
    s = sample_lanes(v, wo, 40_000, seed=5)
    assert np.all(s.valid) and np.array_equal(s.weight, np.ones_like(s.weight))
    pdf_err, w_err = consistency_error(v, tile(wo, 40_000), s)
    assert pdf_err.max() < 1e-9 and w_err.max() < 1e-9
    mu = np.clip(-(s.wi @ wo), -1.0, 1.0)
    sd = np.sqrt(max(np.mean(mu * mu) - mu.mean() ** 2, 1e-12) / len(mu))
    assert abs(mu.mean() - mean_cosine(d)) < 5 * sd
    # the blend's CDF by the trapezoid rule, geometrically fine toward the forward peak
    grid = np.concatenate([[-1.0], 1.0 - np.geomspace(2.0, 1e-14, 400_001)[1:], [1.0]])
    cdf = np.concatenate([[0.0], np.cumsum(np.diff(grid) * 0.5 * (fog_pdf(d, grid[1:])
                                                                  + fog_pdf(d, grid[:-1])))])
    cdf *= 2 * np.pi
    assert cdf[-1] == pytest.approx(1.0, abs=1e-4)
    res = stats.kstest(mu, lambda x: np.interp(x, grid, cdf / cdf[-1]))
    assert res.pvalue > 1e-3, res


def test_reciprocity_and_forward_peak(rng):
    a = rng.normal(size=(500, 3))
    a /= np.linalg.norm(a, axis=1)[:, None]
    b = rng.normal(size=(500, 3))
    b /= np.linalg.norm(b, axis=1)[:, None]
    for d in (0.3, 2.0, 12.0):
        v = df.fog_vdf(d)
        assert np.allclose(v.pdf(a, b), v.pdf(b, a), rtol=1e-13)
        # eval is the pdf in every channel, the albedo 1
        assert np.array_equal(v.eval(a, b), np.repeat(v.pdf(a, b)[:, None], 3, axis=1))
        assert np.array_equal(v.albedo(a), np.ones((500, 3)))
    # larger droplets scatter further forward
    wo = np.array([[0.0, 0.0, 1.0]])
    peaks = [df.fog_vdf(d).pdf(wo, -wo)[0] for d in (5.0, 10.0, 20.0, 40.0)]
    assert np.all(np.diff(peaks) > 0)


def test_the_fit_is_clamped_to_its_range():
    wo = tile([0.0, 0.6, 0.8], 3)
    wi = tile([0.0, 0.0, -1.0], 3)
    big, small = df.fog_vdf([80.0, 0.01, 1e-9]), df.fog_vdf([D_MAX, D_MIN, D_MIN])
    assert np.array_equal(big.particle_size, [D_MAX, D_MIN, D_MIN])
    assert np.array_equal(big.pdf(wo, wi), small.pdf(wo, wi))


def test_extremes_give_no_nan():
    v = df.fog_vdf(np.array(SIZES))
    n = len(SIZES)
    for u in (0.0, 1.0 - 2**-53, 1.0):
        s = v.sample(tile([0.0, 0.0, 1.0], n), np.full(n, u), np.full((n, 2), u))
        assert np.all(s.valid) and np.all(np.isfinite(s.wi)) and np.all(np.isfinite(s.pdf))
    out = v.eval(np.zeros((n, 3)), tile([1.0, 0.0, 0.0], n))
    assert np.all(out == 0.0)
    s = v.sample(np.zeros((n, 3)), np.zeros(n), np.zeros((n, 2)))
    assert not np.any(s.valid)


@pytest.mark.parametrize("bad", [0.0, -2.0, np.nan, np.inf])
def test_bad_particle_size_is_a_clear_error(bad):
    with pytest.raises(ValueError, match="particle_size"):
        df.fog_vdf(bad)


def test_mixes_and_tint_of_fog():
    m = df.normalized_mix([df.vdf_component(0.6, df.fog_vdf(10.0)),
                           df.vdf_component(0.4, df.anisotropic_vdf(-0.3))])
    res = chi2_test(m, direction(50.0, 10.0), sample_count=100_000, test_count=1)
    assert res.passed, str(res)
    t = df.tint((0.9, 0.5, 0.2), df.fog_vdf(4.0))
    s = sample_lanes(t, direction(20.0), 2000)
    assert np.allclose(s.weight, [0.9, 0.5, 0.2], rtol=1e-12)
