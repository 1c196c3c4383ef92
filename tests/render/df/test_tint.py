"""df::tint: the checklist and the scaling by hand."""

from __future__ import annotations

import numpy as np
import pytest
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
    diffuse_reflection_bsdf,
    diffuse_transmission_bsdf,
    simple_glossy_bsdf,
    specular_bsdf,
    tint,
)
from render.testing import direction

D, T, G, S = diffuse_reflection_bsdf, diffuse_transmission_bsdf, simple_glossy_bsdf, specular_bsdf

CASES = [
    CombinerCase("glossy", lambda: tint((0.5, 1.0, 2.0), G(roughness_u=0.3)), "glossy",
                 albedo_tol=3e-3, chi2_wos=((45.0, 30.0),)),
    CombinerCase("black", lambda: tint(0.0, D()), "diffuse"),
    CombinerCase("mirror", lambda: tint((0.2, 0.4, 0.8), S()), "delta"),
    CombinerCase("white-transmission", lambda: tint(1.0, T()), "diffuse", transmits=True,
                 lossless=True),
]
CHI2 = per_wo(CASES, CHI2_WOS, only=lambda c: c.chi2_wos is not None)
INTEGRALS = two_wos(CASES)


@pytest.mark.parametrize("case", CASES, ids=case_ids(CASES))
def test_consistency(case, rng):
    check_consistency(case, rng)


@pytest.mark.parametrize("case", CASES, ids=case_ids(CASES))
def test_no_nan_or_negative(case, rng):
    check_no_nan(case, rng)


@pytest.mark.parametrize("case", CASES[:3], ids=case_ids(CASES[:3]))
def test_reciprocity(case, rng):
    check_reciprocity(case, rng)


@pytest.mark.parametrize(("case", "wo"), CHI2, ids=pair_ids(CHI2))
def test_chi2(case, wo):
    check_chi2_combined(case, wo, test_count=len(CHI2))


@pytest.mark.parametrize(("case", "wo"), INTEGRALS, ids=pair_ids(INTEGRALS))
def test_pdf_furnace_and_albedo(case, wo):
    check_integrals_combined(case, wo)


def test_scales_eval_and_weight_not_pdf(rng):
    base = G(roughness_u=0.3)
    t = tint((0.5, 1.0, 2.0), base)  # saturated to (0.5, 1, 1)
    wo, wi = random_dirs(rng, 2000), random_dirs(rng, 2000)
    assert np.allclose(t.eval(wo, wi), base.eval(wo, wi) * [0.5, 1.0, 1.0], rtol=1e-15, atol=0)
    assert np.array_equal(t.pdf(wo, wi), base.pdf(wo, wi))
    s, sb = t.sample(wo, np.full(2000, 0.3), np.full((2000, 2), 0.6)), base.sample(
        wo, np.full(2000, 0.3), np.full((2000, 2), 0.6))
    assert np.allclose(s.weight, sb.weight * [0.5, 1.0, 1.0], rtol=1e-15, atol=0)
    assert np.allclose(t.albedo(direction(30.0)[None]), base.albedo(direction(30.0)[None])
                       * [0.5, 1.0, 1.0], rtol=1e-15)


def test_black_tint_samples_nothing(rng):
    t = tint(0.0, D())
    s = t.sample(random_dirs(rng, 100), rng.random(100), rng.random((100, 2)))
    assert not np.any(s.valid)
    with pytest.raises(ValueError, match="tint must be finite"):
        tint((np.nan, 0.0, 0.0), D())
