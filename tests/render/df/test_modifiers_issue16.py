"""The modifiers of issue 16 through the combiner checklist: the two-tint ``tint``,
``fresnel_factor``, ``coat_absorption_factor``, ``measured_curve_factor``; and the
edf overloads of ``tint`` and ``directional_factor``.  Worked-out values by hand."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from render_combiner_cases import (
    COMBINED_ALBEDO_TOL,
    JUMP_ALBEDO_TOL,
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
from render.df._kernel_common import fresnel_dielectric
from render.df.fresnel_factor import fresnel_conductor
from render.testing import direction

D, T, G, S = (df.diffuse_reflection_bsdf, df.diffuse_transmission_bsdf,
              df.microfacet_ggx_smith_bsdf, df.specular_bsdf)
RT = "scatter_reflect_transmit"
GOLD = ((0.18, 0.42, 1.37), (3.42, 2.35, 1.77))  # ior, extinction at R, G, B
CURVE = np.array([[0.9, 0.8, 0.7], [0.7, 0.5, 0.5], [0.4, 0.3, 0.1], [0.2, 0.1, 0.0]])


def _glass(r=0.3):
    return G(roughness_u=r, mode=RT, ior_inside=1.5)


CASES = [
    CombinerCase("tint-rt-glossy", lambda: df.tint((0.9, 0.5, 0.1), (0.1, 0.5, 0.9), _glass()),
                 # the factor jumps between reflection and transmission: JUMP accuracy
                 "glossy", transmits=True, ior=(1.0, 1.5), albedo_tol=JUMP_ALBEDO_TOL,
                 reciprocal=False, chi2_wos=((45.0, 30.0), (130.0, 250.0))),
    CombinerCase("tint-rt-specular", lambda: df.tint(0.3, (0.2, 0.9, 0.6),
                                                     S(mode=RT, ior_inside=1.5)),
                 "delta", transmits=True, ior=(1.0, 1.5), reciprocal=False,
                 albedo_tol=JUMP_ALBEDO_TOL),
    CombinerCase("tint-rt-white", lambda: df.tint(1.0, 1.0, T()), "diffuse", transmits=True,
                 lossless=True, reciprocal=False),
    CombinerCase("fresnel-factor-gold", lambda: df.fresnel_factor(*GOLD, G(roughness_u=0.3)),
                 "glossy", albedo_tol=COMBINED_ALBEDO_TOL, chi2_wos=((45.0, 30.0),)),
    CombinerCase("fresnel-factor-glass", lambda: df.fresnel_factor(1.5, 0.0, _glass(0.4)),
                 "glossy", transmits=True, ior=(1.0, 1.5), albedo_tol=JUMP_ALBEDO_TOL,
                 reciprocal=False),
    CombinerCase("fresnel-factor-mirror", lambda: df.fresnel_factor(*GOLD, S()), "delta"),
    CombinerCase("coat-absorption", lambda: df.coat_absorption_factor(
        1.5, (0.5, 2.0, 8.0), 0.4, D(tint=0.8)), "diffuse", albedo_tol=COMBINED_ALBEDO_TOL,
        chi2_wos=((45.0, 30.0),)),
    CombinerCase("coat-absorption-transmit", lambda: df.coat_absorption_factor(
        1.3, (1.0, 0.2, 3.0), 0.5, T()), "diffuse", transmits=True,
        albedo_tol=COMBINED_ALBEDO_TOL, reciprocal=False),
    CombinerCase("measured-curve-factor",
                 lambda: df.measured_curve_factor(CURVE, G(roughness_u=0.5)), "glossy",
                 albedo_tol=COMBINED_ALBEDO_TOL, chi2_wos=((0.0, 0.0),)),
    CombinerCase("measured-curve-factor-one", lambda: df.measured_curve_factor(
        np.array([[0.6, 0.3, 1.0]]), D()), "diffuse"),
]
CHI2 = per_wo(CASES, CHI2_WOS, only=lambda c: c.chi2_wos is not None)
INTEGRALS = two_wos(CASES)


@pytest.mark.parametrize("case", CASES, ids=case_ids(CASES))
def test_consistency(case, rng):
    check_consistency(case, rng)


@pytest.mark.parametrize("case", CASES, ids=case_ids(CASES))
def test_no_nan_or_negative(case, rng):
    check_no_nan_combined(case, rng)


@pytest.mark.parametrize("case", [c for c in CASES if c.reciprocal],
                         ids=case_ids([c for c in CASES if c.reciprocal]))
def test_reciprocity(case, rng):
    check_reciprocity(case, rng)


@pytest.mark.parametrize(("case", "wo"), CHI2, ids=pair_ids(CHI2))
def test_chi2(case, wo):
    check_chi2_combined(case, wo, test_count=len(CHI2))


@pytest.mark.parametrize(("case", "wo"), INTEGRALS, ids=pair_ids(INTEGRALS))
def test_pdf_furnace_and_albedo(case, wo):
    check_integrals_combined(case, wo)


# --- by hand --------------------------------------------------------------------------------


def test_two_tints_split_reflection_and_transmission(rng):
    base = _glass()
    t = df.tint((0.9, 0.5, 0.1), (0.1, 0.5, 0.9), base)
    wo, wi = random_dirs(rng, 4000), random_dirs(rng, 4000)
    refl = (wo[:, 2] * wi[:, 2] >= 0)[:, None]
    want = base.eval(wo, wi) * np.where(refl, [0.9, 0.5, 0.1], [0.1, 0.5, 0.9])
    assert np.allclose(t.eval(wo, wi), want, rtol=1e-15, atol=0)
    assert isinstance(t, df.TintRt) and isinstance(df.tint(0.5, base), df.Tint)


def test_conductor_fresnel_by_hand():
    # kappa = 0: the dielectric term; gold's normal reflectance from its complex index
    for c in (1.0, 0.7, 0.2, 0.01):
        assert fresnel_conductor(c, 1.5, 0.0) == pytest.approx(
            fresnel_dielectric(c, 1.5)[0], abs=1e-14)
    n, k = 0.18, 3.42
    r0 = ((n - 1) ** 2 + k * k) / ((n + 1) ** 2 + k * k)
    assert fresnel_conductor(1.0, n, k) == pytest.approx(r0, rel=1e-12)
    assert fresnel_conductor(0.0, n, k) == 1.0
    f = df.fresnel_factor(*GOLD, S())
    s = f.sample(direction(0.0)[None], np.array([0.5]), np.array([[0.5, 0.5]]))
    want = [((a - 1) ** 2 + b * b) / ((a + 1) ** 2 + b * b) for a, b in zip(*GOLD, strict=True)]
    assert np.allclose(s.weight[0], want, rtol=1e-12)


def test_fresnel_factor_is_relative_to_the_side_of_wo():
    # seen from inside a medium of IOR 1.5 (non-thin-walled), eta = ior / 1.5
    f = df.fresnel_factor(1.5, 0.0, S(), ior_inside=1.5)
    s = f.sample(direction(180.0)[None], np.array([0.5]), np.array([[0.5, 0.5]]))
    assert np.allclose(s.weight, 0.0)  # index-matched from inside: F = 0, the sample fails
    f = df.fresnel_factor(3.0, 0.0, S(), ior_inside=1.5)
    s = f.sample(direction(180.0)[None], np.array([0.5]), np.array([[0.5, 0.5]]))
    assert np.allclose(s.weight, ((2.0 - 1) / (2.0 + 1)) ** 2, rtol=1e-12)


def test_coat_absorption_by_hand():
    # normal incidence, reflection: exp(-2 sigma d); transmission: half of it
    f = df.coat_absorption_factor(1.5, (0.5, 2.0, 8.0), 0.4, S())
    s = f.sample(direction(0.0)[None], np.array([0.5]), np.array([[0.5, 0.5]]))
    assert np.allclose(s.weight[0], np.exp(-2 * 0.4 * np.array([0.5, 2.0, 8.0])), rtol=1e-12)
    f = df.coat_absorption_factor(1.5, (0.5, 2.0, 8.0), 0.4, S(mode="scatter_transmit",
                                                              ior_inside=1.0))
    s = f.sample(direction(0.0)[None], np.array([0.5]), np.array([[0.5, 0.5]]))
    assert np.allclose(s.weight[0], np.exp(-0.4 * np.array([0.5, 2.0, 8.0])), rtol=1e-12)
    # at 60 degrees the paths are along the refracted cosines
    wo = direction(60.0)
    ct = np.sqrt(1 - np.sin(np.radians(60.0)) ** 2 / 1.5**2)
    s = df.coat_absorption_factor(1.5, 1.0, 0.3, S()).sample(wo[None], np.array([0.5]),
                                                            np.array([[0.5, 0.5]]))
    assert np.allclose(s.weight[0], np.exp(-0.3 * 2 / ct), rtol=1e-12)
    # no absorption, no thickness, or a coat thinner than the medium: factor 1
    for args in ((1.5, 0.0, 1.0), (1.5, 1.0, 0.0)):
        s = df.coat_absorption_factor(*args, S()).sample(wo[None], np.array([0.5]),
                                                         np.array([[0.5, 0.5]]))
        assert np.allclose(s.weight, 1.0)


def test_measured_curve_factor_interpolates_in_angle():
    f = df.measured_curve_factor(CURVE, S())
    for th in (0.0, 15.0, 30.0, 45.0, 75.0, 89.0):
        s = f.sample(direction(th)[None], np.array([0.5]), np.array([[0.5, 0.5]]))
        x = th / 90.0 * (len(CURVE) - 1)
        j = min(int(x), len(CURVE) - 2)
        want = (1 - (x - j)) * CURVE[j] + (x - j) * CURVE[j + 1]
        assert np.allclose(s.weight[0], want, rtol=1e-12, atol=1e-15), th


def test_edf_overloads():
    wo = np.array([[0.0, 0.6, 0.8], [0.0, 0.0, 1.0], [0.3, 0.0, -0.95]])
    wo /= np.linalg.norm(wo, axis=1, keepdims=True)
    base = df.diffuse_edf()
    t = df.tint((0.5, 1.0, 0.2), base)
    assert isinstance(t, df.TintEdf)
    assert np.allclose(t.eval(wo), base.eval(wo) * [0.5, 1.0, 0.2], rtol=1e-15)
    assert np.array_equal(t.pdf(wo), base.pdf(wo))
    d = df.directional_factor(normal_tint=(0.2, 0.5, 1.0), grazing_tint=1.0, exponent=3.0,
                              base=base)
    assert isinstance(d, df.DirectionalFactorEdf)
    c = np.clip(wo[:, 2], 0.0, 1.0)[:, None]
    want = base.eval(wo) * (np.array([0.2, 0.5, 1.0]) + (1 - np.array([0.2, 0.5, 1.0]))
                            * (1 - c) ** 3)
    assert np.allclose(d.eval(wo), want, rtol=1e-13)
    # sampling: directions of the base, weights the factor over the base's
    rng = np.random.default_rng(4)
    s = d.sample(rng.random(20_000), rng.random((20_000, 2)))
    e, p = d._eval_pdf(s.wo)
    ok = s.pdf > 0
    assert ok.all() and np.allclose(s.pdf, p) and np.allclose(s.weight * p[:, None],
                                                              e * s.wo[:, 2:3])
    # a tinted spot in a mix: the mix's weights and the tint multiply
    m = df.normalized_mix([df.edf_component(0.5, df.tint(0.5, df.spot_edf(exponent=4.0,
                                                                          global_distribution=False))),
                           df.edf_component(0.5, base)])
    assert np.all(np.isfinite(m.eval(wo))) and np.all(m.eval(wo) >= 0)


@settings(max_examples=40)
@given(st.floats(0.0, 180.0), st.floats(0.0, 1.0), st.floats(0.0, 1.0), st.floats(0.0, 1.0),
       st.floats(1.0, 2.5), st.floats(0.0, 5.0))
def test_factors_never_gain_energy(theta, r, tr, g, ior, k):
    # property: every modifier over a white lossless base keeps the furnace <= 1
    wo = direction(theta, 30.0)
    base = G(roughness_u=max(r, 0.05), mode=RT, ior_inside=1.5, multiscatter_tint=1.0)
    rng = np.random.default_rng(7)
    for node in (df.tint(tr, g, base), df.fresnel_factor(ior, k, base),
                 df.coat_absorption_factor(ior, k, 0.2, base),
                 df.measured_curve_factor(np.array([[tr] * 3, [g] * 3, [1.0] * 3]), base)):
        s = node.sample(np.tile(wo, (4000, 1)), rng.random(4000), rng.random((4000, 2)))
        mean, se = s.weight.mean(axis=0), s.weight.std(axis=0) / np.sqrt(4000)
        assert np.all(mean <= 1.0 + 4 * se + 3e-3), (type(node).__name__, mean, se)


def test_bad_arguments():
    with pytest.raises(ValueError, match="ior must be > 0"):
        df.fresnel_factor(0.0, 1.0, S())
    with pytest.raises(ValueError, match="ior must be > 0"):
        df.coat_absorption_factor(-1.0, 1.0, 1.0, S())
    with pytest.raises(ValueError, match="curve_values must be a non-empty array"):
        df.measured_curve_factor(np.zeros((0, 3)), S())
    with pytest.raises(ValueError, match="curve_values must be finite"):
        df.measured_curve_factor(np.array([[np.nan, 0.0, 0.0]]), S())
