"""df::custom_curve_layer and df::color_custom_curve_layer: the checklist, the curve by hand."""

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
    bsdf_component,
    clamped_mix,
    color_custom_curve_layer,
    custom_curve_layer,
    diffuse_reflection_bsdf,
    diffuse_transmission_bsdf,
    simple_glossy_bsdf,
    specular_bsdf,
    weighted_layer,
)
from render.df._layer import f82_curve
from render.testing import direction, furnace

D, T, G, S = diffuse_reflection_bsdf, diffuse_transmission_bsdf, simple_glossy_bsdf, specular_bsdf
TOL = COMBINED_ALBEDO_TOL
ORANGE, YELLOW, GREEN = (0.3, 0.15, 0.0), (0.5, 0.4, 0.1), (0.1, 0.3, 0.05)


def three_layers():
    """Handbook Figure 6.34: two_glossy_lobes (a clamped mix) over diffuse green."""
    lobes = clamped_mix([
        bsdf_component(0.5, G(roughness_u=0.6, tint=ORANGE)),
        bsdf_component(0.5, G(roughness_u=0.3, tint=YELLOW)),
    ])
    return custom_curve_layer(0.0, 1.0, 0.5, 1.0, lobes, D(tint=GREEN))


CASES = [
    CombinerCase("three-layers", three_layers, "glossy", albedo_tol=TOL,
                 chi2_wos=((45.0, 30.0),)),
    CombinerCase("mirror-over-lambert", lambda: custom_curve_layer(0.2, 1.0, 5.0, 1.0, S(), D()),
                 "glossy", albedo_tol=TOL),
    CombinerCase("exponent-0", lambda: custom_curve_layer(0.3, 0.6, 0.0, 1.0, G(roughness_u=0.3),
                                                          D()), "glossy", albedo_tol=TOL),
    CombinerCase("w0", lambda: custom_curve_layer(0.5, 1.0, 5.0, 0.0, G(roughness_u=0.3),
                                                  D(tint=0.5)), "glossy"),
    CombinerCase("always-layer", lambda: custom_curve_layer(1.0, 1.0, 5.0, 1.0, G(roughness_u=0.3),
                                                            D()), "glossy", albedo_tol=TOL),
    CombinerCase(
        "color-f82",
        lambda: color_custom_curve_layer((0.9, 0.5, 0.1), 1.0, (0.3, 0.7, 1.0), 5.0,
                                         (1.0, 1.0, 0.5), G(roughness_u=0.2), D(tint=0.5)),
        "glossy",
        albedo_tol=TOL,
        chi2_wos=((130.0, 250.0),),
    ),
    CombinerCase(
        "transmitting-base",
        lambda: custom_curve_layer(0.1, 1.0, 5.0, 1.0, G(roughness_u=0.3), T()),
        "glossy",
        transmits=True,
        reciprocal=False,
        albedo_tol=TOL,
    ),
    # libbsdf's heuristic gains energy here: see test_rough_layer_over_a_mirror_gains_energy
    CombinerCase("gain", lambda: custom_curve_layer(0.0, 1.0, 1.0, 1.0, G(roughness_u=0.5), S()),
                 "glossy", albedo_tol=TOL, gain=1.07),
]
CHI2 = per_wo(CASES, CHI2_WOS, only=lambda c: c.chi2_wos is not None)
INTEGRALS = two_wos(CASES)


@pytest.mark.parametrize("case", CASES, ids=case_ids(CASES))
def test_consistency(case, rng):
    check_consistency(case, rng)


NO_GAIN = [c for c in CASES if c.gain <= 1.0]


@pytest.mark.parametrize("case", NO_GAIN, ids=case_ids(NO_GAIN))
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


# --- values worked out by hand ----------------------------------------------------------------


def test_curve_values():
    r0, r90 = np.array([[0.2, 0.2, 0.2]]), np.array([[1.0, 1.0, 1.0]])
    c = np.array([1.0, 0.5, 0.0, -0.3, 1.7])
    # R0 + (R90 - R0)(1 - saturate(c))^5
    expect = 0.2 + 0.8 * (1 - np.clip(c, 0, 1)) ** 5
    assert np.allclose(f82_curve(c, r0, r90, np.ones((1, 3)), 5.0)[:, 0], expect, rtol=1e-15)
    # F82 with f82 = 0 at c = 1/7: a = (R0 + (R90 - R0)(6/7)^5) 7^7/6^6 and the subtracted
    # term a c (1 - c)^6 = R0 + (R90 - R0)(6/7)^5 is the whole curve there: C = 0
    assert f82_curve(np.array([1 / 7]), r0, r90, np.zeros((1, 3)), 5.0)[0, 0] == pytest.approx(
        0.0, abs=1e-14)


def test_mirror_layer_albedo_is_the_curve():
    layer = custom_curve_layer(0.2, 0.9, 3.0, 0.5, S(), None)
    wo = np.stack([direction(0.0), direction(45.0), direction(80.0)])
    c = np.cos(np.radians([0.0, 45.0, 80.0]))
    expect = 0.5 * (0.2 + 0.7 * (1 - c) ** 3)
    assert np.allclose(layer.albedo(wo)[:, 0], expect, rtol=1e-12)


def test_exponent_zero_is_a_weighted_layer(rng):
    # C = R90 everywhere: f_layer = w R90 and f_base = 1 - w R90
    wo, wi = random_dirs(rng, 3000), random_dirs(rng, 3000)
    layer, base = G(roughness_u=0.3), D(tint=(0.9, 0.5, 0.1))
    cc = custom_curve_layer(0.3, 0.6, 0.0, 0.5, layer, base)
    wl = weighted_layer(0.3, layer, base)
    e1, p1 = cc.eval_pdf(wo, wi)
    e2, p2 = wl.eval_pdf(wo, wi)
    assert np.allclose(e1, e2, rtol=1e-12, atol=0) and np.allclose(p1, p2, rtol=1e-12, atol=0)


def test_transmission_uses_the_mirrored_half_vector():
    # straight through (wi = -wo): mirrored, wi is the mirror direction, so h = n and the
    # base keeps 1 - w C(nk1)
    base = T()
    cc = custom_curve_layer(0.1, 1.0, 5.0, 0.8, None, base)
    wo = direction(50.0, 30.0)[None]
    wi = -wo
    c = np.cos(np.radians(50.0))
    expect = (1 - 0.8 * (0.1 + 0.9 * (1 - c) ** 5)) * base.eval(wo, wi)
    assert np.allclose(cc.eval(wo, wi), expect, rtol=1e-12)


def test_rough_layer_over_a_mirror_gains_energy():
    """libbsdf's heuristic (reference §3.2) is not energy conserving for steep curves.

    C(c) = 1 - c (R0 0, R90 1, exponent 1) is 0 at normal incidence, so the mirror base
    keeps everything, while a rough layer sees tilted half vectors with C(|wo.h|) > 0:
    measured albedo 1.064 ± 0.001 at normal incidence (roughness 0.5).  The Handbook's
    own curve (exponent 0.5, Figure 6.34) over a diffuse base loses energy instead.
    """
    gain = custom_curve_layer(0.0, 1.0, 1.0, 1.0, G(roughness_u=0.5), S())
    m, se = furnace(gain, direction(0.0), 100_000, seed=5)
    assert 1.05 < m[0] < 1.075 and se[0] < 0.002
    assert gain.albedo(direction(0.0)[None])[0, 0] == pytest.approx(m[0], abs=6e-3)
    hb, _ = furnace(three_layers(), direction(0.0), 100_000, seed=5)
    assert np.all(hb < 1.0)


def test_errors():
    with pytest.raises(ValueError, match="normal_reflectivity must be finite"):
        custom_curve_layer(np.inf)
    with pytest.raises(ValueError, match="base must be a Bsdf"):
        custom_curve_layer(0.1, base=3.0)
