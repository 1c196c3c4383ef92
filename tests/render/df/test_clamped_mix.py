"""df::clamped_mix / color_clamped_mix: the checklist, clamping in order, edf overload."""

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

from render.df import (
    ClampedMixEdf,
    bsdf_component,
    clamped_mix,
    color_bsdf_component,
    color_clamped_mix,
    diffuse_edf,
    diffuse_reflection_bsdf,
    diffuse_transmission_bsdf,
    edf_component,
    simple_glossy_bsdf,
    specular_bsdf,
)
from render.testing import direction

D, T, G, S = diffuse_reflection_bsdf, diffuse_transmission_bsdf, simple_glossy_bsdf, specular_bsdf
TAB = 3e-3


def two_glossy_lobes(weight_1=0.5, weight_2=0.5):
    """Handbook Listing 6.13 with Figure 6.21's gold parameters."""
    return clamped_mix([
        bsdf_component(weight_1, G(roughness_u=0.6, tint=(0.3, 0.15, 0.0))),
        bsdf_component(weight_2, G(roughness_u=0.3, tint=(0.5, 0.4, 0.1))),
    ])


CASES = [
    CombinerCase("two-glossy-lobes", two_glossy_lobes, "glossy", albedo_tol=TAB,
                 chi2_wos=((89.9, 120.0),)),
    CombinerCase("first-only", lambda: two_glossy_lobes(1.0, 0.0), "glossy", albedo_tol=TAB),
    CombinerCase(
        "sum-above-1",
        lambda: clamped_mix([bsdf_component(0.7, D()), bsdf_component(0.7, G(roughness_u=0.3)),
                             bsdf_component(0.7, T())]),
        "glossy",
        albedo_tol=TAB,
    ),
    CombinerCase(
        "lossless-sum-above-1",
        lambda: clamped_mix([bsdf_component(0.6, T()), bsdf_component(0.9, S())]),
        "glossy",
        transmits=True,
        reciprocal=False,
        lossless=True,
    ),
    CombinerCase(
        "color",
        lambda: color_clamped_mix([
            color_bsdf_component((0.8, 0.2, 1.0), D()),
            color_bsdf_component((0.8, 0.2, 0.5), G(roughness_u=0.3)),
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


# --- clamping by hand -------------------------------------------------------------------------


def test_clamping_in_order(rng):
    a, b, c = D(tint=1.0), D(tint=0.5), D(tint=0.0)
    m = clamped_mix([bsdf_component(0.7, a), bsdf_component(0.7, b), bsdf_component(0.7, c)])
    # running sums 0.7, 1.4 -> the second gets 0.3, the third nothing
    assert np.allclose(m.weights(1)[0, :, 0], [0.7, 0.3, 0.0], rtol=1e-15)
    # weights saturate first: 1.5 -> 1, and everything after it is cut
    m = clamped_mix([bsdf_component(1.5, a), bsdf_component(0.5, b)])
    assert m.weights(1)[0, :, 0].tolist() == [1.0, 0.0]
    # below 1 nothing changes; negative weights count 0
    m = clamped_mix([bsdf_component(0.3, a), bsdf_component(-0.2, b), bsdf_component(0.4, c)])
    assert np.allclose(m.weights(1)[0, :, 0], [0.3, 0.0, 0.4], rtol=1e-15)
    wo, wi = random_dirs(rng, 1000), random_dirs(rng, 1000)
    assert np.allclose(m.eval(wo, wi), 0.3 * a.eval(wo, wi) + 0.4 * c.eval(wo, wi), rtol=1e-14,
                       atol=0)


def test_color_clamping_per_channel():
    m = color_clamped_mix([color_bsdf_component((0.8, 0.2, 1.0), D()),
                           color_bsdf_component((0.8, 0.2, 0.5), D())])
    assert np.allclose(m.weights(1)[0], [[0.8, 0.2, 1.0], [0.2, 0.2, 0.0]], rtol=1e-15)
    assert np.allclose(m.albedo(direction(20.0)[None]), [[1.0, 0.4, 1.0]], rtol=1e-14)


def test_gold_albedo_is_the_clamped_sum_of_the_lobes():
    wo = np.stack([direction(0.0), direction(50.0)])
    m = two_glossy_lobes()
    expect = sum(0.5 * c.component.albedo(wo) for c in m.components)
    assert np.allclose(m.albedo(wo), expect, rtol=1e-14)


def test_edf_overload():
    m = clamped_mix([edf_component(0.8, diffuse_edf()), edf_component(0.8, diffuse_edf())])
    assert isinstance(m, ClampedMixEdf)
    assert np.allclose(m.eval(direction(30.0)[None]) * np.pi, 1.0, rtol=1e-14)


# --- properties -------------------------------------------------------------------------------

WEIGHTS = st.lists(st.floats(-2.0, 3.0, allow_nan=False), min_size=1, max_size=5)


@settings(max_examples=60)
@given(WEIGHTS)
def test_clamped_weights_properties(weights):
    m = clamped_mix([bsdf_component(w, D()) for w in weights])
    eff = m.weights(1)[0, :, 0]
    sat = np.clip(weights, 0.0, 1.0)
    assert np.all(eff >= 0.0) and np.all(eff <= sat + 1e-15)
    assert eff.sum() <= 1.0 + 1e-12
    # a prefix whose saturated sum stays at most 1 is kept unchanged
    keep = np.cumsum(sat) <= 1.0
    assert np.allclose(eff[keep], sat[keep], rtol=0, atol=1e-15)
    # the white furnace of white Lambert components is the weight sum, never above 1
    assert m.albedo(direction(30.0)[None])[0, 0] == pytest.approx(eff.sum(), abs=1e-12)
