"""df::normalized_mix / color_normalized_mix over bsdf and edf components: checklist and weights."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from render_combiner_cases import (
    CombinerCase,
    check_chi2_combined,
    check_integrals_combined,
    two_wos,
)
from render_df_cases import (
    CHI2_WOS,
    case_ids,
    check_consistency,
    check_no_nan,
    check_reciprocity,
    pair_ids,
    per_wo,
    random_dirs,
)
from render_edf_adapter import EdfAsBsdf

from render.df import (
    ColorNormalizedMixEdf,
    NormalizedMix,
    NormalizedMixEdf,
    bsdf_component,
    color_bsdf_component,
    color_edf_component,
    color_normalized_mix,
    diffuse_edf,
    diffuse_reflection_bsdf,
    diffuse_transmission_bsdf,
    edf_component,
    normalized_mix,
    simple_glossy_bsdf,
    specular_bsdf,
    spot_edf,
)
from render.testing import chi2_test, direction, sphere_integral

D, T, G, S = diffuse_reflection_bsdf, diffuse_transmission_bsdf, simple_glossy_bsdf, specular_bsdf
TAB = 3e-3


def listing_6_12():
    """Handbook Listing 6.12: red, green and blue diffuse components, weights 0.3, 0.2, 0.5."""
    return normalized_mix([
        bsdf_component(0.3, D(tint=(1.0, 0.0, 0.0))),
        bsdf_component(0.2, D(tint=(0.0, 1.0, 0.0))),
        bsdf_component(0.5, D(tint=(0.0, 0.0, 1.0))),
    ])


CASES = [
    CombinerCase("listing-6.12", listing_6_12, "diffuse"),
    CombinerCase(
        "sum-above-1",
        lambda: normalized_mix([bsdf_component(2.0, G(roughness_u=0.3)),
                                bsdf_component(2.0, D()), bsdf_component(1.0, T())]),
        "glossy",
        transmits=True,
        reciprocal=False,
        albedo_tol=TAB,
        chi2_wos=((130.0, 250.0),),
    ),
    CombinerCase(
        "lossless-sum-above-1",
        lambda: normalized_mix([bsdf_component(3.0, D()), bsdf_component(1.0, T())]),
        "glossy",
        transmits=True,
        reciprocal=False,
        lossless=True,
    ),
    CombinerCase("negative-weight",
                 lambda: normalized_mix([bsdf_component(-1.0, S()), bsdf_component(0.5, D())]),
                 "diffuse"),
    CombinerCase("all-zero",
                 lambda: normalized_mix([bsdf_component(0.0, D()), bsdf_component(0.0, S())]),
                 "diffuse"),
    CombinerCase("empty", lambda: normalized_mix([]), "diffuse"),
    CombinerCase("mirror-and-lambert",
                 lambda: normalized_mix([bsdf_component(1.0, S()), bsdf_component(1.0, D())]),
                 "glossy", lossless=True, chi2_wos=((45.0, 30.0),)),
    CombinerCase(
        "color",
        lambda: color_normalized_mix([
            color_bsdf_component((1.5, 0.2, 0.5), D()),
            color_bsdf_component((1.0, 0.2, 0.6), G(roughness_u=0.3)),
        ]),
        "glossy",
        albedo_tol=TAB,
    ),
]
CHI2 = per_wo(CASES, CHI2_WOS, only=lambda c: c.chi2_wos is not None)
INTEGRALS = two_wos(CASES)


@pytest.mark.parametrize("case", CASES, ids=case_ids(CASES))
def test_consistency(case, rng):
    check_consistency(case, rng)


@pytest.mark.parametrize("case", CASES, ids=case_ids(CASES))
def test_no_nan_or_negative(case, rng):
    check_no_nan(case, rng)


RECIPROCAL = [c for c in CASES if c.reciprocal]


@pytest.mark.parametrize("case", RECIPROCAL, ids=case_ids(RECIPROCAL))
def test_reciprocity(case, rng):
    check_reciprocity(case, rng)


@pytest.mark.parametrize(("case", "wo"), CHI2, ids=pair_ids(CHI2))
def test_chi2(case, wo):
    check_chi2_combined(case, wo, test_count=len(CHI2))


@pytest.mark.parametrize(("case", "wo"), INTEGRALS, ids=pair_ids(INTEGRALS))
def test_pdf_furnace_and_albedo(case, wo):
    check_integrals_combined(case, wo)


# --- weights by hand --------------------------------------------------------------------------


def test_weights_sum_below_one_are_kept_above_one_normalised(rng):
    wo, wi = random_dirs(rng, 2000), random_dirs(rng, 2000)
    a, b = G(roughness_u=0.3), D(tint=0.5)
    below = normalized_mix([bsdf_component(0.3, a), bsdf_component(0.2, b)])
    assert np.allclose(below.eval(wo, wi), 0.3 * a.eval(wo, wi) + 0.2 * b.eval(wo, wi),
                       rtol=1e-14, atol=0)
    above = normalized_mix([bsdf_component(3.0, a), bsdf_component(1.0, b)])
    assert np.allclose(above.eval(wo, wi), 0.75 * a.eval(wo, wi) + 0.25 * b.eval(wo, wi),
                       rtol=1e-14, atol=0)
    assert np.allclose(above.weights(1)[0, :, 0], [0.75, 0.25], rtol=1e-15)
    # negative weights count as 0
    neg = normalized_mix([bsdf_component(-1.0, a), bsdf_component(0.5, b)])
    assert neg.weights(1)[0, :, 0].tolist() == [0.0, 0.5]


def test_listing_6_12_albedo():
    # Lambert components: albedo = sum of weight * tint = (0.3, 0.2, 0.5)
    assert np.allclose(listing_6_12().albedo(direction(30.0)[None]), [[0.3, 0.2, 0.5]],
                       rtol=1e-14)


def test_color_weights_normalise_each_channel_by_its_own_sum():
    m = color_normalized_mix([color_bsdf_component((1.5, 0.2, 0.5), D()),
                              color_bsdf_component((1.0, 0.2, 0.6), D())])
    w = m.weights(1)[0]
    # red sums to 2.5 (divided), green to 0.4 (kept), blue to 1.1 (divided)
    assert np.allclose(w, [[0.6, 0.2, 0.5 / 1.1], [0.4, 0.2, 0.6 / 1.1]], rtol=1e-15)


def test_per_lane_weights():
    m = normalized_mix([bsdf_component(np.array([0.2, 3.0]), S(tint=1.0)),
                        bsdf_component(np.array([0.5, 1.0]), S(tint=0.0))])
    wo = np.stack([direction(10.0), direction(70.0)])
    assert np.allclose(m.albedo(wo)[:, 0], [0.2, 0.75], rtol=1e-14)


def test_components_as_pairs_and_errors():
    m = normalized_mix([(0.5, D()), (0.5, S())])
    assert isinstance(m, NormalizedMix) and len(m.components) == 2
    with pytest.raises(ValueError, match="must be a list of bsdf_component"):
        normalized_mix(bsdf_component(0.5, D()))
    with pytest.raises(ValueError, match=r"components\[1\] must be a component struct"):
        normalized_mix([(0.5, D()), D()])
    with pytest.raises(ValueError, match="mix bsdf and edf components"):
        normalized_mix([bsdf_component(0.5, D()), edf_component(0.5, diffuse_edf())])
    with pytest.raises(ValueError, match="takes color_bsdf_component"):
        color_normalized_mix([bsdf_component(0.5, D())])
    with pytest.raises(ValueError, match="component must be a Bsdf"):
        bsdf_component(0.5, diffuse_edf())
    with pytest.raises(ValueError, match="component must be an Edf"):
        edf_component(0.5, D())


# --- edf mixes ---------------------------------------------------------------------------------


def _edf_mix():
    return normalized_mix([
        edf_component(2.0, diffuse_edf()),
        edf_component(2.0, spot_edf(exponent=20.0, spread=1.0, global_distribution=False)),
    ])


def test_edf_mix_is_an_edf_normalised_to_the_weight_sum():
    m = _edf_mix()
    assert isinstance(m, NormalizedMixEdf)
    edge = (0.5,)
    rule = dict(n_beta=32, order=16, breaks=edge)
    total = sphere_integral(lambda w: m.eval(w)[:, 0] * w[:, 2], [0.0, 0.0, 1.0], +1, **rule)
    assert total == pytest.approx(1.0, abs=1e-7)  # weights 2 + 2 normalised to 1/2 + 1/2
    assert sphere_integral(m.pdf, [0.0, 0.0, 1.0], +1, **rule) == pytest.approx(1.0, abs=1e-7)
    w = direction(20.0)[None]
    expect = 0.5 * diffuse_edf().eval(w) + 0.5 * spot_edf(20.0, 1.0, False).eval(w)
    assert np.allclose(m.eval(w), expect, rtol=1e-14)


def test_edf_mix_sampling(rng):
    m = _edf_mix()
    s = m.sample(rng.random(20_000), rng.random((20_000, 2)))
    ok = s.valid
    assert ok.mean() > 0.999
    assert np.allclose(s.pdf[ok], m.pdf(s.wo[ok]), rtol=1e-12)
    assert np.allclose(s.weight[ok], m.eval(s.wo[ok]) * (s.wo[ok, 2] / s.pdf[ok])[:, None],
                       rtol=1e-12)
    res = chi2_test(EdfAsBsdf(m), direction(0.0), sample_count=100_000)
    assert res.passed, str(res)


def test_color_edf_mix():
    m = color_normalized_mix([color_edf_component((1.0, 0.0, 3.0), diffuse_edf()),
                              color_edf_component((0.0, 0.5, 1.0), diffuse_edf())])
    assert isinstance(m, ColorNormalizedMixEdf)
    # per channel: (1, 0.5, 3/4 + 1/4) of the diffuse radiance 1/pi
    assert np.allclose(m.eval(direction(10.0)[None]) * np.pi, [[1.0, 0.5, 1.0]], rtol=1e-14)
    assert np.all(m.eval(direction(100.0)[None]) == 0.0)


# --- properties -------------------------------------------------------------------------------


@settings(max_examples=60)
@given(st.lists(st.floats(-2.0, 5.0, allow_nan=False), min_size=1, max_size=5))
def test_normalized_weights_properties(weights):
    m = normalized_mix([bsdf_component(w, D()) for w in weights])
    eff = m.weights(1)[0, :, 0]
    pos = np.maximum(weights, 0.0)
    total = pos.sum()
    assert eff.sum() <= 1.0 + 1e-12
    expect = pos / total if total > 1.0 else pos
    assert np.allclose(eff, expect, rtol=1e-14, atol=0)
    assert m.albedo(direction(30.0)[None])[0, 0] == pytest.approx(eff.sum(), abs=1e-12)
