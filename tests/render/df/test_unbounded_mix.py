"""df::unbounded_mix and color_unbounded_mix (bsdf and edf): the checklist, and weights
summing above 1 that gain energy exactly as the model says."""

from __future__ import annotations

import numpy as np
import pytest
from render_combiner_cases import (
    CombinerCase,
    check_chi2_combined,
    check_integrals_combined,
    check_no_nan_combined,
    two_wos,
)
from render_df_cases import CHI2_WOS, case_ids, check_consistency, pair_ids, per_wo

from render import df
from render.testing import direction, sample_lanes

D, G, S, T = (df.diffuse_reflection_bsdf, df.microfacet_beckmann_vcavities_bsdf,
              df.specular_bsdf, df.diffuse_transmission_bsdf)
C = df.bsdf_component

CASES = [
    CombinerCase("diffuse-glossy", lambda: df.unbounded_mix([C(0.5, D(tint=0.8)),
                                                             C(0.4, G(roughness_u=0.3))]),
                 "diffuse", albedo_tol=3e-3, chi2_wos=((45.0, 30.0), (130.0, 250.0))),
    CombinerCase("white-sum-1", lambda: df.unbounded_mix([C(0.3, D()), C(0.7, D(roughness=0.5,
                                                                                   multiscatter_tint=1.0))]),
                 "diffuse", lossless=True),
    CombinerCase("mirror-diffuse", lambda: df.unbounded_mix([C(0.6, S()), C(0.3, D())]),
                 "diffuse"),
    CombinerCase("color", lambda: df.color_unbounded_mix([
        df.color_bsdf_component((0.9, 0.2, 0.0), D()),
        df.color_bsdf_component((0.0, 0.5, 0.9), G(roughness_u=0.5))]), "diffuse",
        albedo_tol=3e-3, chi2_wos=((0.0, 0.0),)),
    CombinerCase("negative-weight", lambda: df.unbounded_mix([C(-2.0, D()), C(0.5, D())]),
                 "diffuse"),
]
CHI2 = per_wo(CASES, CHI2_WOS, only=lambda c: c.chi2_wos is not None)
INTEGRALS = two_wos(CASES)


@pytest.mark.parametrize("case", CASES, ids=case_ids(CASES))
def test_consistency(case, rng):
    check_consistency(case, rng)


@pytest.mark.parametrize("case", CASES, ids=case_ids(CASES))
def test_no_nan_or_negative(case, rng):
    check_no_nan_combined(case, rng)


@pytest.mark.parametrize(("case", "wo"), CHI2, ids=pair_ids(CHI2))
def test_chi2(case, wo):
    check_chi2_combined(case, wo, test_count=len(CHI2))


@pytest.mark.parametrize(("case", "wo"), INTEGRALS, ids=pair_ids(INTEGRALS))
def test_pdf_furnace_and_albedo(case, wo):
    check_integrals_combined(case, wo)


def test_weights_are_not_normalised():
    # 1.5 + 0.75: the albedo is the weighted sum, 2.25 white; normalized_mix would give 1
    m = df.unbounded_mix([C(1.5, D()), C(0.75, D())])
    wo = direction(30.0)
    assert np.allclose(m.albedo(wo[None]), 2.25)
    assert np.allclose(df.normalized_mix([C(1.5, D()), C(0.75, D())]).albedo(wo[None]), 1.0)
    s = sample_lanes(m, wo, 20_000)
    assert np.allclose(s.weight.mean(axis=0), 2.25, rtol=1e-12)  # both lobes are Lambert
    assert np.allclose(m.weights(1)[0, :, 0], [1.5, 0.75])


def test_edf_form():
    e = df.unbounded_mix([df.edf_component(1.2, df.diffuse_edf()),
                          df.edf_component(0.3, df.diffuse_edf())])
    assert isinstance(e, df.UnboundedMixEdf)
    wo = np.array([[0.0, 0.0, 1.0]])
    assert np.allclose(e.eval(wo), 1.5 / np.pi)
