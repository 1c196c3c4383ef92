"""df::custom_curve_layer and its colour variant: the checklist, the curve by hand, no gain."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from render_combiner_cases import (
    COMBINED_ALBEDO_TOL,
    SWEEP_BASES,
    SWEEP_LAYERS,
    SWEEP_ROUGHNESS,
    CombinerCase,
    assert_no_gain,
    check_chi2_combined,
    check_integrals_combined,
    check_no_nan_combined,
    sweep_base,
    sweep_furnace,
    sweep_layer,
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
from render.df._layer import f82_curve1
from render.program import CHAT_NONE, TABLE
from render.testing import direction, furnace


def f82_curve(c, r0, r90, f82, p):
    """The kernel's curve per channel over cosines ``c`` (n,) -> (n, 3)."""
    f = np.vectorize(f82_curve1)
    r0, r90, f82 = (np.broadcast_to(x, (1, 3))[0] for x in (r0, r90, f82))
    return np.stack([f(c, r0[k], r90[k], f82[k], p) for k in range(3)], axis=1)

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
    # libbsdf's rule gained 6.5 % here: see test_rough_layer_over_a_mirror_does_not_gain
    CombinerCase("rough-over-mirror",
                 lambda: custom_curve_layer(0.0, 1.0, 1.0, 1.0, G(roughness_u=0.5), S()),
                 "glossy", albedo_tol=TOL),
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


def test_rough_layer_over_a_mirror_does_not_gain():
    """libbsdf's rule (reference §3.2) gains energy here; the node does not.

    C(c) = 1 - c (R0 0, R90 1, exponent 1) is 0 at normal incidence, so libbsdf's mirror
    base keeps everything while a rough layer sees tilted half vectors with C(|wo.h|) > 0:
    measured 1.0647 ± 0.0008 at normal incidence with libbsdf's factors.  The base now
    keeps 1 - Ĉ(wo), so the node is lossless up to Ĉ's accuracy and never above 1.  The
    Handbook's own curve (exponent 0.5, Figure 6.34) over a diffuse base loses energy.
    """
    node = custom_curve_layer(0.0, 1.0, 1.0, 1.0, G(roughness_u=0.5), S())
    for theta in (0.0, 15.0):
        m, se = furnace(node, direction(theta), 100_000, seed=5)
        assert_no_gain(m, se)
        assert np.all(m >= 1.0 - 4 * se - 3e-3) and se[0] < 0.002
    assert node.albedo(direction(15.0)[None])[0, 0] == pytest.approx(m[0], abs=6e-3)
    hb, _ = furnace(three_layers(), direction(0.0), 100_000, seed=5)
    assert np.all(hb < 1.0)


def test_base_keeps_one_minus_the_layer_curve_albedo():
    # a white Lambertian layer under C(c) = 1 - c: at normal incidence h bisects n and wi,
    # |wo.h| = cos(theta/2), and Ĉ(n) = 2 ∫ (1 - cos(theta/2)) cos(theta) sin(theta) dtheta
    # = 1 - (8/15)(1 + 1/sqrt 2) = 0.0895 > C(1) = 0; at wi = wo = n the layer's term is
    # C(1) = 0, so eval is the base's times 1 - w Ĉ(n) (libbsdf: times 1); the node's
    # tabulated Ĉ is accurate to 1e-3 (render.df._layer.CURVE_ALBEDO_POINTS)
    c_hat = 1.0 - 8.0 / 15.0 * (1.0 + 1.0 / np.sqrt(2.0))
    base = G(roughness_u=0.2, tint=(0.9, 0.5, 0.2))
    node = custom_curve_layer(0.0, 1.0, 1.0, 0.7, D(), base)
    n = direction(0.0)[None]
    kept = node.eval(n, n) / base.eval(n, n)
    assert np.all(np.abs(kept - (1.0 - 0.7 * c_hat)) <= 0.7 * 1e-3)
    # libbsdf's factor where C(nk2) exceeds Ĉ: wi at 60 degrees, C = 1 - 1/2 on the base
    wi = direction(60.0, 180.0)[None]
    h = (n + wi) / np.linalg.norm(n + wi)
    layer_term = 0.7 * (1.0 - float(n[0] @ h[0])) * D().eval(n, wi)
    expect = layer_term + (1.0 - 0.7 * 0.5) * base.eval(n, wi)
    assert np.allclose(node.eval(n, wi), expect, rtol=1e-12)


def test_the_layer_lobe_is_libbsdfs(rng):
    # without a base the node is exactly w C(|wo.h|) layer.eval (reflection half vector)
    layer = G(roughness_u=0.4, tint=(0.8, 0.6, 0.4))
    node = custom_curve_layer(0.1, 0.9, 2.0, 0.6, layer, None)
    wo, wi = random_dirs(rng, 3000), random_dirs(rng, 3000)
    wi[:, 2] = np.abs(wi[:, 2]) * np.sign(wo[:, 2])
    h = wo + wi
    h /= np.linalg.norm(h, axis=1, keepdims=True)
    c = np.abs(np.einsum("ij,ij->i", wo, h))
    expect = 0.6 * (0.1 + 0.8 * (1 - c) ** 2)[:, None] * layer.eval(wo, wi)
    assert np.allclose(node.eval(wo, wi), expect, rtol=1e-12, atol=1e-300)


def test_anisotropic_layer_does_not_gain_at_any_azimuth():
    # the tabulated Ĉ keeps the largest of four azimuths of the layer's tangent frame, so it
    # bounds an anisotropic coat seen from every azimuth (tangent rotated off the nodes)
    layer = G(roughness_u=0.5625, roughness_v=0.140625, tangent_u=(0.6, 0.8, 0.0))
    node = custom_curve_layer(0.0, 1.0, 1.0, 1.0, layer, S())
    for theta, phi in ((0.0, 0.0), (20.0, 0.0), (20.0, 53.1), (20.0, 98.0), (35.0, 143.1)):
        sweep_furnace(node, theta, phi)


def test_per_lane_parameters_alike_share_the_table():
    # per-lane rows that are all alike (constants bound per lane) get the Ĉ table of the
    # same node with single-row parameters: the same values, hence the same factors
    n = 600
    alike = custom_curve_layer(np.full(n, 0.01), 1.0, 1.7, 1.0,
                               G(roughness_u=np.full(n, 0.43)), S())
    shared = custom_curve_layer(0.01, 1.0, 1.7, 1.0, G(roughness_u=0.43), S())
    pa, ps = alike.program, shared.program
    assert pa.rows == n and ps.rows == 1
    assert pa.code[pa.root, TABLE] >= 0 and ps.code[ps.root, TABLE] >= 0
    ta, ts = pa.tables[pa.code[pa.root, TABLE]:], ps.tables[ps.code[ps.root, TABLE]:]
    assert np.array_equal(ta, ts)
    wo = np.stack([direction(t, 30.0) for t in np.linspace(0.0, 89.0, n)])
    wi = np.stack([direction(t, 200.0) for t in np.linspace(0.0, 89.0, n)])
    assert np.array_equal(alike.eval_pdf(wo, wi)[0], shared.eval_pdf(wo, wi)[0])


def test_per_lane_parameters_that_differ_keep_libbsdfs_factor(rng):
    # rows that differ (textures) cannot share a table: the node keeps libbsdf's base
    # factor 1 - w max(C(nk1), C(nk2r)) (no Ĉ, render.program.CHAT_NONE) on every lane,
    # and stays consistent, reciprocal and without gain here
    n = 200
    node = custom_curve_layer(np.linspace(0.0, 0.01, n), 1.0, 1.0, 1.0,
                              G(roughness_u=np.linspace(0.4, 0.6, n)), G(roughness_u=0.05))
    assert node.program.code[node.program.root, TABLE] == CHAT_NONE
    wo = random_dirs(rng, n)
    wo[:, 2] = np.abs(wo[:, 2])
    # the base factor at wi = wo: libbsdf's, lane by lane (C(nk1) = C(nk2r) there)
    r0 = np.linspace(0.0, 0.01, n)
    lone = custom_curve_layer(r0, 1.0, 1.0, 1.0, None, G(roughness_u=0.05))
    c = r0 + (1.0 - r0) * (1.0 - wo[:, 2])
    base = G(roughness_u=0.05).eval(wo, wo)
    assert np.allclose(lone.eval(wo, wo), (1.0 - c)[:, None] * base, rtol=1e-12, atol=1e-300)
    # consistency at the sampled directions (on every lane: the parameters are per lane)
    s = node.sample(wo, rng.random(n), rng.random((n, 2)))
    e, p = node.eval_pdf(wo, s.wi)
    ok = s.valid
    assert np.allclose(p[ok], s.pdf[ok], rtol=1e-9)
    assert np.allclose(e[ok] / p[ok, None], s.weight[ok], rtol=1e-9)
    # reciprocity
    wi = random_dirs(rng, n)
    wi[:, 2] = np.abs(wi[:, 2])
    assert np.allclose(node.eval(wo, wi) / wi[:, 2:], node.eval(wi, wo) / wo[:, 2:],
                       rtol=1e-9, atol=1e-300)
    m, se = furnace(node, direction(10.0), n, seed=4)
    assert_no_gain(m, se)


CURVE_SWEEP = dict(
    r0=st.sampled_from([0.0, 1.0]) | st.floats(0.0, 1.0),
    r90=st.sampled_from([0.0, 1.0]) | st.floats(0.0, 1.0),
    f82=st.sampled_from([0.0, 1.0]) | st.floats(0.0, 1.0),
    exponent=st.sampled_from([0.0, 0.5, 1.0, 5.0]) | st.floats(0.0, 20.0),
    weight=st.floats(0.0, 1.0),
    roughness=st.sampled_from(SWEEP_ROUGHNESS),
    layer=st.sampled_from(SWEEP_LAYERS),
    base=st.sampled_from(SWEEP_BASES),
    base_roughness=st.sampled_from(SWEEP_ROUGHNESS[:4]),
    theta=st.sampled_from([0.0, 89.9, 150.0]) | st.floats(0.0, 89.9),
)


@settings(max_examples=12, derandomize=True)
@given(**CURVE_SWEEP)
def test_no_gain_sweep(r0, r90, f82, exponent, weight, roughness, layer, base, base_roughness,
                       theta):
    """White furnace <= 1 for any curve (F82 tint included), weight, coat and base."""
    node = color_custom_curve_layer(r0, r90, f82, exponent, weight, sweep_layer(layer, roughness),
                                    sweep_base(base, base_roughness))
    sweep_furnace(node, theta)


def test_errors():
    with pytest.raises(ValueError, match="normal_reflectivity must be finite"):
        custom_curve_layer(np.inf)
    with pytest.raises(ValueError, match=r"\(base\) must be a bound bsdf"):
        custom_curve_layer(0.1, base=3.0)
