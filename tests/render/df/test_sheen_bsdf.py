"""df::sheen_bsdf: the Charlie sheen lobe with v-cavities, its table-based compensation
(the default multiscatter) and its layer over another multiscatter bsdf."""

from __future__ import annotations

import numpy as np
import pytest
from render_combiner_cases import (
    COMBINED_ALBEDO_TOL,
    CombinerCase,
    check_chi2_combined,
    check_integrals_combined,
    check_no_nan_combined,
)
from render_df_cases import (
    CHI2_WOS,
    WOS,
    DfCase,
    case_ids,
    check_chi2,
    check_consistency,
    check_integrals,
    check_no_nan,
    check_reciprocity,
    pair_ids,
    per_wo,
)

from render import df
from render.df.sheen_bsdf import _d
from render.testing import direction, sample_lanes, sphere_integral

TAB = 3e-3
S = df.sheen_bsdf

CASES = [
    DfCase("r0.4", lambda: S(0.4, multiscatter=None), "diffuse", albedo_tol=TAB),
    DfCase("r1", lambda: S(1.0, multiscatter=None), "diffuse", albedo_tol=TAB),
    DfCase("r0.05", lambda: S(0.05, multiscatter=None), "diffuse", albedo_tol=TAB),
    DfCase("default-ms", lambda: S(0.5, multiscatter_tint=1.0), "diffuse", lossless=True,
           lossless_tol=TAB, albedo_tol=TAB),
    DfCase("default-ms-color", lambda: S(0.3, tint=(1.0, 0.4, 0.1),
                                         multiscatter_tint=(0.2, 0.8, 0.5)), "diffuse",
           albedo_tol=TAB),
]
LAYERED = [
    CombinerCase("over-glossy", lambda: S(0.4, tint=(1.0, 0.6, 0.3), multiscatter_tint=1.0,
                                          multiscatter=df.microfacet_ggx_smith_bsdf(
                                              roughness_u=0.3)),
                 "diffuse", albedo_tol=COMBINED_ALBEDO_TOL, chi2_wos=((45.0, 30.0),)),
    CombinerCase("over-tinted-diffuse", lambda: S(0.6, multiscatter_tint=0.8, multiscatter=
                                                   df.diffuse_reflection_bsdf(tint=0.5)),
                 "diffuse", albedo_tol=COMBINED_ALBEDO_TOL, chi2_wos=((0.0, 0.0),)),
]
CHI2 = per_wo(CASES, CHI2_WOS, only=lambda c: c.id in ("r0.4", "default-ms"))
CHI2 += per_wo(CASES, CHI2_WOS[1:2], only=lambda c: c.id in ("r1", "r0.05"))
INTEGRALS = per_wo([c for c in CASES if c.id in ("r0.4", "default-ms")])
INTEGRALS += per_wo([c for c in CASES if c.id not in ("r0.4", "default-ms")], WOS[1:3])
L_CHI2 = per_wo(LAYERED, CHI2_WOS)
L_INTEGRALS = per_wo(LAYERED, WOS[:3])


@pytest.mark.parametrize("case", CASES + LAYERED, ids=case_ids(CASES + LAYERED))
def test_consistency(case, rng):
    check_consistency(case, rng)


@pytest.mark.parametrize("case", CASES, ids=case_ids(CASES))
def test_no_nan_or_negative(case, rng):
    check_no_nan(case, rng)


@pytest.mark.parametrize("case", LAYERED, ids=case_ids(LAYERED))
def test_no_nan_or_negative_layered(case, rng):
    check_no_nan_combined(case, rng)


@pytest.mark.parametrize("case", CASES + LAYERED, ids=case_ids(CASES + LAYERED))
def test_reciprocity(case, rng):
    check_reciprocity(case, rng)


@pytest.mark.parametrize(("case", "wo"), CHI2, ids=pair_ids(CHI2))
def test_chi2(case, wo):
    check_chi2(case, wo, test_count=len(CHI2) + len(L_CHI2))


@pytest.mark.parametrize(("case", "wo"), L_CHI2, ids=pair_ids(L_CHI2))
def test_chi2_layered(case, wo):
    check_chi2_combined(case, wo, test_count=len(CHI2) + len(L_CHI2))


@pytest.mark.parametrize(("case", "wo"), INTEGRALS, ids=pair_ids(INTEGRALS))
def test_pdf_furnace_and_albedo(case, wo):
    check_integrals(case, wo)


@pytest.mark.parametrize(("case", "wo"), L_INTEGRALS, ids=pair_ids(L_INTEGRALS))
def test_pdf_furnace_and_albedo_layered(case, wo):
    check_integrals_combined(case, wo)


@pytest.mark.parametrize("r", [0.05, 0.3, 1.0])
def test_distribution_is_normalised(r):
    q = 1.0 / r

    def f(h):
        z = np.maximum(h[:, 2], 0.0)
        return np.array([_d(q, v) for v in z]) * z

    assert sphere_integral(f, [0.0, 0.0, 1.0], +1, n_beta=64, order=16) == pytest.approx(
        1.0, abs=1e-6)


def test_sheen_is_strongest_at_grazing():
    # the retro-reflective sheen: far more at 80 degrees than at normal incidence
    b = S(0.4, multiscatter=None)
    a = b.albedo(np.array([direction(0.0), direction(80.0)]))[:, 0]
    assert a[1] > 3 * a[0]


def test_default_multiscatter_explicit_or_implicit_is_the_same(rng):
    a = S(0.5, multiscatter_tint=0.7)
    b = S(0.5, multiscatter_tint=0.7, multiscatter=df.diffuse_reflection_bsdf())
    assert a.program.code.shape == b.program.code.shape == (1, a.program.code.shape[1])
    wo = rng.normal(size=(100, 3))
    wo /= np.linalg.norm(wo, axis=1, keepdims=True)
    assert np.array_equal(a.eval(wo, wo * [-1, -1, 1]), b.eval(wo, wo * [-1, -1, 1]))
    # a non-default diffuse is a layer: it loses what max(E(wo), E(wi)) holds back
    c = S(0.5, multiscatter_tint=1.0, multiscatter=df.diffuse_reflection_bsdf(tint=0.999))
    assert c.program.code.shape[0] == 3
    s = sample_lanes(c, direction(60.0), 40_000)
    assert s.weight.mean(axis=0)[0] < 0.995


def test_bad_arguments():
    with pytest.raises(ValueError, match="multiscatter"):
        S(0.3, multiscatter=df.diffuse_edf())
    with pytest.raises(ValueError, match="roughness must be finite"):
        S(np.nan)
