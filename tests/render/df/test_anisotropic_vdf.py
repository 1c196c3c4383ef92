"""df::anisotropic_vdf: the Henyey–Greenstein phase function (sampling, pdf, extremes)."""

from __future__ import annotations

import numpy as np
import pytest
from scipy import stats

from displacement.surfaces import UnitSquare
from render import material as M
from render.df import AnisotropicVdf, anisotropic_vdf
from render.df.anisotropic_vdf import G_MAX, hg_phase
from render.testing import (
    chi2_test,
    consistency_error,
    direction,
    sample_lanes,
    sphere_integral,
    tile,
)

BIASES = (0.0, 0.3, -0.3, 0.7, -0.7, 0.99, -0.99)
WOS = ((30.0, 20.0), (120.0, 300.0))
CHI2 = [(g, wo) for g in BIASES for wo in WOS]


def hg_cdf(mu: np.ndarray, g: float) -> np.ndarray:
    """P(cos theta <= mu) for Henyey–Greenstein (theta from the forward direction)."""
    if g == 0.0:
        return 0.5 * (mu + 1.0)
    return (1 - g * g) / (2 * g) * (1 / np.sqrt(1 + g * g - 2 * g * mu) - 1 / (1 + g))


@pytest.mark.parametrize(("g", "wo"), CHI2, ids=[f"g{g}-wo{w[0]:.0f}" for g, w in CHI2])
def test_chi2_sample_against_pdf(g, wo):
    res = chi2_test(anisotropic_vdf(g), direction(*wo), sample_count=100_000, test_count=len(CHI2))
    assert res.passed, str(res)


@pytest.mark.parametrize("g", [0.0, 0.5, -0.5, 0.99, -0.99, 0.9999, -0.9999, 1.0, -1.0])
def test_cos_theta_distribution_ks(g):
    # the angle to the propagation direction -wo follows HG's CDF, to the clamp at +-G_MAX
    wo = direction(40.0, 75.0)
    s = sample_lanes(anisotropic_vdf(g), wo, 40_000, seed=3)
    mu = np.clip(-(s.wi @ wo), -1.0, 1.0)
    geff = float(np.clip(g, -G_MAX, G_MAX))
    res = stats.kstest(mu, lambda x: hg_cdf(x, geff))
    assert res.pvalue > 1e-3, res
    # HG's mean cosine is g, its variance (1 - g^2) / 3 (E[P2(cos)] = g^2); the sample
    # variance is no guide for the heavy tails at |g| -> 1
    assert abs(mu.mean() - geff) < 5 * np.sqrt((1 - geff * geff) / 3 / len(mu))


@pytest.mark.parametrize("g", [0.0, 0.5, -0.5, 0.99, -0.99, 0.9999, -0.9999])
def test_pdf_integrates_to_one(g):
    vdf = anisotropic_vdf(g)
    wo = direction(60.0, 200.0)
    # rings about the peak (forward for g > 0, backward for g < 0): the lobe is constant
    # on each ring, and the rings are log-spaced near their centre
    peak = -wo if g >= 0 else wo
    total = sum(
        sphere_integral(lambda w: vdf.pdf(tile(wo, len(w)), w), peak, side) for side in (+1, -1)
    )
    assert abs(total - 1.0) < 1e-7, total


@pytest.mark.parametrize("g", [0.0, 0.6, -0.6, 0.99, -0.99])
def test_sample_consistency_and_unit_weight(g, rng):
    vdf = anisotropic_vdf(g)
    wo = tile(direction(25.0, 10.0), 5000)
    s = vdf.sample(wo, rng.random(5000), rng.random((5000, 2)))
    assert np.all(s.valid) and np.allclose(s.weight, 1.0)
    assert np.allclose(np.linalg.norm(s.wi, axis=1), 1.0)
    pdf_err, w_err = consistency_error(vdf, wo, s)
    assert pdf_err.max() < 1e-9 and w_err.max() < 1e-9
    # back-scattered samples are flagged as reflection, forward ones as transmission
    back = np.einsum("ij,ij->i", s.wi, wo) > 0
    assert np.array_equal(s.lobe == 1, back)


def test_values_and_symmetries(rng):
    wo = np.array([[0.0, 0.0, 1.0]] * 3)
    wi = np.array([[0.0, 0.0, -1.0], [0.0, 0.0, 1.0], [1.0, 0.0, 0.0]])
    g = 0.5
    p = anisotropic_vdf(g).pdf(wo, wi) * 4 * np.pi
    assert np.allclose(p, [(1 - g * g) / (1 - g) ** 3, (1 - g * g) / (1 + g) ** 3,
                           (1 - g * g) / (1 + g * g) ** 1.5], rtol=1e-13)
    # reciprocity p(wo, wi) = p(wi, wo); negative bias mirrors positive: p(-g, wi) = p(g, -wi)
    a = rng.normal(size=(500, 3))
    a /= np.linalg.norm(a, axis=1)[:, None]
    b = rng.normal(size=(500, 3))
    b /= np.linalg.norm(b, axis=1)[:, None]
    for gg in (0.3, -0.8, 0.99):
        v = anisotropic_vdf(gg)
        assert np.allclose(v.pdf(a, b), v.pdf(b, a), rtol=1e-12)
        assert np.allclose(v.pdf(a, b), anisotropic_vdf(-gg).pdf(a, -b), rtol=1e-12)
    # eval is the pdf in every channel, the albedo is 1
    v = anisotropic_vdf(0.4)
    assert np.array_equal(v.eval(a, b), np.repeat(v.pdf(a, b)[:, None], 3, axis=1))
    assert np.array_equal(v.albedo(a), np.ones((500, 3)))


def test_peak_is_accurate_near_one():
    # exactly forward at g = 0.9999: (1 + g) / (4 pi (1 - g)^2), no cancellation
    g = G_MAX
    wo = np.array([[0.0, 0.6, 0.8]])
    p = hg_phase(g, wo, -wo)[0]
    assert p == pytest.approx((1 + g) / (4 * np.pi * (1 - g) ** 2), rel=1e-12)
    p_back = hg_phase(-g, wo, wo)[0]
    assert p_back == pytest.approx(p, rel=1e-12)


def test_per_lane_bias_and_extremes(rng):
    g = np.array([-1.0, -0.5, 0.0, 0.5, 1.0])
    v = anisotropic_vdf(g)
    assert np.allclose(v.directional_bias, [-G_MAX, -0.5, 0.0, 0.5, G_MAX])
    wo = tile([0.0, 0.0, 1.0], 5)
    s = v.sample(wo, np.full(5, 0.5), np.full((5, 2), 0.5))
    assert np.all(np.isfinite(s.wi)) and np.all(s.valid)
    assert s.wi[0, 2] > 0.999 and s.wi[4, 2] < -0.999  # backward and forward
    # degenerate directions: no NaN, a zero wo fails cleanly
    wz = np.zeros((2, 3))
    out = v.eval(wz[:1].repeat(5, 0), tile([1.0, 0.0, 0.0], 5))
    assert np.all(np.isfinite(out))
    s = anisotropic_vdf(0.3).sample(wz, np.zeros(2), np.zeros((2, 2)))
    assert np.all(np.isfinite(s.wi)) and np.all(np.isfinite(s.weight))
    # u at the ends of [0, 1)
    ends = np.array([[0.0, 0.0], [1.0, 1.0]])
    s = anisotropic_vdf(-0.99).sample(tile([0, 0, 1.0], 2), np.zeros(2), ends)
    assert np.all(s.valid) and np.all(np.isfinite(s.pdf))


@pytest.mark.parametrize("bad", [1.5, -1.01, np.nan, [[0.1]]])
def test_bad_bias_raises(bad):
    with pytest.raises(ValueError, match="directional_bias"):
        AnisotropicVdf(bad)


def test_bound_from_a_material_node():
    state = UnitSquare().state_at_uv(np.array([[0.5, 0.5], [0.25, 0.75]]))
    node = M.df.anisotropic_vdf(directional_bias=lambda s: s.uv[:, 0] - 0.5)
    vdf = node.bind(state)
    assert isinstance(vdf, AnisotropicVdf)
    assert np.allclose(vdf.directional_bias, [0.0, -0.25])
