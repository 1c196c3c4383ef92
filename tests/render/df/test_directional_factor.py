"""df::directional_factor: the checklist, the curve at the half vector by hand."""

from __future__ import annotations

import numpy as np
import pytest
from render_combiner_cases import (
    COMBINED_ALBEDO_TOL,
    CombinerCase,
    check_chi2_combined,
    check_integrals_combined,
    check_no_nan_combined,
    two_wos,
)
from render_df_cases import (
    CHI2_WOS,
    case_ids,
    check_consistency,
    check_reciprocity,
    pair_ids,
    per_wo,
    random_dirs,
)

from render.df import (
    diffuse_reflection_bsdf,
    diffuse_transmission_bsdf,
    directional_factor,
    simple_glossy_bsdf,
    specular_bsdf,
)
from render.testing import direction

D, T, G, S = diffuse_reflection_bsdf, diffuse_transmission_bsdf, simple_glossy_bsdf, specular_bsdf
GOLD = (0.9, 0.6, 0.2)

CASES = [
    CombinerCase("gold-glossy", lambda: directional_factor(GOLD, 1.0, 1.0, 5.0, G(roughness_u=0.3)),
                 "glossy", albedo_tol=COMBINED_ALBEDO_TOL, chi2_wos=((89.9, 120.0),)),
    CombinerCase("gold-mirror", lambda: directional_factor(GOLD, 1.0, 1.0, 5.0, S()), "delta"),
    CombinerCase("f82-lambert",
                 lambda: directional_factor(GOLD, 1.0, (0.2, 0.5, 1.0), 5.0, D()), "diffuse",
                 albedo_tol=COMBINED_ALBEDO_TOL),
    CombinerCase("transmission", lambda: directional_factor(0.3, 0.9, 1.0, 2.0, T()), "diffuse",
                 transmits=True, reciprocal=False, albedo_tol=COMBINED_ALBEDO_TOL),
    CombinerCase("constant", lambda: directional_factor(0.5, 0.5, 1.0, 5.0, D()), "diffuse"),
]
CHI2 = per_wo(CASES, CHI2_WOS, only=lambda c: c.chi2_wos is not None)
INTEGRALS = two_wos(CASES)


@pytest.mark.parametrize("case", CASES, ids=case_ids(CASES))
def test_consistency(case, rng):
    check_consistency(case, rng)


@pytest.mark.parametrize("case", CASES, ids=case_ids(CASES))
def test_no_nan_or_negative(case, rng):
    check_no_nan_combined(case, rng)


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


def test_factor_at_the_half_vector():
    base = D()
    d = directional_factor(GOLD, 1.0, 1.0, 5.0, base)
    # wo at 60 degrees, wi at 0: h bisects them at 30 degrees from each, wo.h = cos 30
    wo, wi = direction(60.0)[None], direction(0.0)[None]
    c = np.cos(np.radians(30.0))
    expect = (np.array(GOLD) + (1 - np.array(GOLD)) * (1 - c) ** 5) * base.eval(wo, wi)
    assert np.allclose(d.eval(wo, wi), expect, rtol=1e-12)
    # a transmitted wi is mirrored first: -wi mirrored is the reflection direction (h = n)
    wi_t = -wo
    expect_t = (np.array(GOLD) + (1 - np.array(GOLD)) * (1 - 0.5) ** 5)
    t = directional_factor(GOLD, 1.0, 1.0, 5.0, T())
    assert np.allclose(t.eval(wo, wi_t), expect_t * T().eval(wo, wi_t), rtol=1e-12)


def test_mirror_albedo_is_the_curve_at_normal_incidence_angle():
    d = directional_factor(GOLD, 1.0, 1.0, 5.0, S())
    wo = np.stack([direction(0.0), direction(45.0), direction(80.0)])
    c = np.cos(np.radians([0.0, 45.0, 80.0]))[:, None]
    assert np.allclose(d.albedo(wo), np.array(GOLD) + (1 - np.array(GOLD)) * (1 - c) ** 5,
                       rtol=1e-12)


def test_pdf_is_the_base_pdf_where_the_factor_is_positive(rng):
    base = G(roughness_u=0.4)
    d = directional_factor(GOLD, 0.0, 1.0, 5.0, base)
    wo, wi = random_dirs(rng, 3000), random_dirs(rng, 3000)
    assert np.array_equal(d.pdf(wo, wi), base.pdf(wo, wi))
