"""df::measured_curve_layer and color_measured_curve_layer: the checklist, and a curve
sampled from a known function that renders as the custom curve it was sampled from."""

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

from render import df
from render.testing import direction

D, G, S = df.diffuse_reflection_bsdf, df.microfacet_ggx_smith_bsdf, df.specular_bsdf


def schlick(n: int, r0, r90=1.0, p=5.0) -> np.ndarray:
    """``custom_curve_layer``'s curve sampled at ``n`` angles equally spaced in [0, pi/2]."""
    c = np.cos(np.linspace(0.0, np.pi / 2, n))[:, None]
    r0 = np.broadcast_to(np.asarray(r0, float), (3,))
    return r0 + (r90 - r0) * (1 - c) ** p


CASES = [
    CombinerCase("glossy-over-diffuse", lambda: df.measured_curve_layer(
        schlick(9, 0.04), layer=G(roughness_u=0.2), base=D(tint=0.6)), "diffuse",
        albedo_tol=COMBINED_ALBEDO_TOL, chi2_wos=((45.0, 30.0), (130.0, 250.0))),
    CombinerCase("mirror-over-glossy", lambda: df.measured_curve_layer(
        schlick(5, 0.1), 0.8, layer=S(), base=G(roughness_u=0.4)), "glossy",
        albedo_tol=COMBINED_ALBEDO_TOL),
    CombinerCase("color", lambda: df.color_measured_curve_layer(
        schlick(17, (0.9, 0.5, 0.1), 1.0, 3.0), (1.0, 0.7, 0.4), layer=G(roughness_u=0.5),
        base=D()), "diffuse", albedo_tol=COMBINED_ALBEDO_TOL, chi2_wos=((0.0, 0.0),)),
    CombinerCase("one-value", lambda: df.measured_curve_layer(
        np.array([[0.3, 0.3, 0.3]]), layer=D(tint=(1, 0, 0)), base=D(tint=(0, 0, 1))),
        "diffuse"),
    CombinerCase("tilted-normal", lambda: df.measured_curve_layer(
        schlick(7, 0.05), layer=G(roughness_u=0.3), base=D(),
        normal=np.array([0.3, 0.0, 0.95]) / np.linalg.norm([0.3, 0.0, 0.95])), "diffuse",
        albedo_tol=2.5e-2),
]
CHI2 = per_wo(CASES, CHI2_WOS, only=lambda c: c.chi2_wos is not None)
INTEGRALS = two_wos(CASES)


@pytest.mark.parametrize("case", CASES, ids=case_ids(CASES))
def test_consistency(case, rng):
    check_consistency(case, rng)


@pytest.mark.parametrize("case", CASES, ids=case_ids(CASES))
def test_no_nan_or_negative(case, rng):
    check_no_nan_combined(case, rng)


@pytest.mark.parametrize("case", CASES[:4], ids=case_ids(CASES[:4]))
def test_reciprocity(case, rng):
    check_reciprocity(case, rng)


@pytest.mark.parametrize(("case", "wo"), CHI2, ids=pair_ids(CHI2))
def test_chi2(case, wo):
    check_chi2_combined(case, wo, test_count=len(CHI2))


@pytest.mark.parametrize(("case", "wo"), INTEGRALS, ids=pair_ids(INTEGRALS))
def test_pdf_furnace_and_albedo(case, wo):
    check_integrals_combined(case, wo)


def test_a_finely_sampled_curve_is_the_custom_curve(rng):
    # 181 samples (half a degree) of Schlick's curve: the layer evaluates as
    # custom_curve_layer of the same curve, to the linear interpolation's error
    layer, base = G(roughness_u=0.3), D(tint=0.5)
    m = df.measured_curve_layer(schlick(181, 0.05), layer=layer, base=base)
    c = df.custom_curve_layer(0.05, 1.0, 5.0, layer=layer, base=base)
    wo, wi = random_dirs(rng, 5000), random_dirs(rng, 5000)
    wi[:, 2] = np.abs(wi[:, 2]) * np.sign(wo[:, 2])
    em, ec = m.eval(wo, wi), c.eval(wo, wi)
    # the factors differ by the curve's interpolation (at most 2e-4 where (1 - c)^5 bends
    # at grazing angles) and by the two Ĉ tables' own accuracy (1e-3): so the values
    # differ by at most 2e-3 of the two lobes' sum, and mostly far less
    scale = layer.eval(wo, wi) + base.eval(wo, wi)
    assert np.all(np.abs(em - ec) <= 2e-3 * scale + 1e-15)
    assert np.median(np.abs(em - ec) / np.maximum(ec, 1e-300)) < 1e-4
    assert np.allclose(m.albedo(direction(40.0)[None]), c.albedo(direction(40.0)[None]),
                       atol=3e-3)


def test_colour_form_folds_the_weight_per_channel(rng):
    curve = schlick(9, (0.2, 0.4, 0.8))
    layer, base = G(roughness_u=0.3), D()
    a = df.color_measured_curve_layer(curve, (1.0, 0.5, 0.0), layer=layer, base=base)
    wo, wi = random_dirs(rng, 2000), random_dirs(rng, 2000)
    e = a.eval(wo, wi)
    # weight 0 in blue: blue is the base alone
    b = df.color_measured_curve_layer(curve, (1.0, 0.5, 0.0), layer=None, base=base)
    assert np.allclose(e[:, 2], b.eval(wo, wi)[:, 2] * 0 + base.eval(wo, wi)[:, 2])


def test_bad_curves():
    with pytest.raises(ValueError, match="curve_values must be a non-empty array"):
        df.measured_curve_layer(np.zeros((0, 3)), layer=S(), base=D())
    with pytest.raises(ValueError, match=r"shape \(N, 3\)"):
        df.measured_curve_layer(np.zeros((4, 2)), layer=S(), base=D())
