"""df::microflake_sheen_bsdf: Zeltner et al.'s LTC sheen (the fitted table), its exact
sampling and albedo, and its layer over a multiscatter bsdf, through the df checklist."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
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
    pair_ids,
    per_wo,
)

from render import df
from render.df._microflake_sheen_table import LTC
from render.df.microflake_sheen_bsdf import albedo_table, ltc_coefficients
from render.testing import direction, sample_lanes, sphere_integral, tile

M = df.microflake_sheen_bsdf

# the lobe alone (multiscatter_tint 0, MDL's default): its albedo is the table's c, exact
CASES = [
    DfCase("r0.6", lambda: M(0.6), "diffuse", reciprocal=False),
    DfCase("r0.3", lambda: M(0.3), "diffuse", reciprocal=False),
    DfCase("r1", lambda: M(1.0), "diffuse", reciprocal=False),
    DfCase("r0.12-grazing", lambda: M(0.12), "diffuse", reciprocal=False),
    DfCase("r0", lambda: M(0.0), "diffuse", reciprocal=False),
    DfCase("tint", lambda: M(0.5, tint=(1.0, 0.4, 0.1)), "diffuse", reciprocal=False),
    DfCase("black", lambda: M(0.5, tint=0.0), "diffuse", reciprocal=False),
]
LAYERED = [
    CombinerCase("default-ms", lambda: M(0.5, multiscatter_tint=1.0), "diffuse",
                 reciprocal=False, albedo_tol=COMBINED_ALBEDO_TOL),
    CombinerCase("over-glossy", lambda: M(0.4, tint=(1.0, 0.6, 0.3), multiscatter_tint=1.0,
                                          multiscatter=df.microfacet_ggx_smith_bsdf(
                                              roughness_u=0.3)),
                 "diffuse", reciprocal=False, albedo_tol=COMBINED_ALBEDO_TOL,
                 chi2_wos=((45.0, 30.0),)),
    CombinerCase("color-ms", lambda: M(0.8, tint=(0.9, 0.9, 1.0), multiscatter_tint=(
        0.4, 0.1, 0.05)), "diffuse", reciprocal=False, albedo_tol=COMBINED_ALBEDO_TOL,
        chi2_wos=((0.0, 0.0),)),
]
CHI2 = per_wo(CASES, CHI2_WOS, only=lambda c: c.id == "r0.6")
CHI2 += per_wo(CASES, CHI2_WOS[1:3], only=lambda c: c.id in ("r0.3", "r1"))
CHI2 += per_wo(CASES, CHI2_WOS[2:3], only=lambda c: c.id == "r0.12-grazing")
L_CHI2 = per_wo(LAYERED, CHI2_WOS, only=lambda c: c.chi2_wos is not None)
INTEGRALS = per_wo([c for c in CASES if c.id in ("r0.6", "r1")])
INTEGRALS += per_wo([c for c in CASES if c.id not in ("r0.6", "r1")], WOS[1:3])
L_INTEGRALS = per_wo(LAYERED, WOS[:3])
N_CHI2 = len(CHI2) + len(L_CHI2)


@pytest.mark.parametrize("case", CASES + LAYERED, ids=case_ids(CASES + LAYERED))
def test_consistency(case, rng):
    check_consistency(case, rng)


@pytest.mark.parametrize("case", CASES, ids=case_ids(CASES))
def test_no_nan_or_negative(case, rng):
    check_no_nan(case, rng)


@pytest.mark.parametrize("case", LAYERED, ids=case_ids(LAYERED))
def test_no_nan_or_negative_layered(case, rng):
    check_no_nan_combined(case, rng)


@pytest.mark.parametrize(("case", "wo"), CHI2, ids=pair_ids(CHI2))
def test_chi2(case, wo):
    check_chi2(case, wo, test_count=N_CHI2)


@pytest.mark.parametrize(("case", "wo"), L_CHI2, ids=pair_ids(L_CHI2))
def test_chi2_layered(case, wo):
    check_chi2_combined(case, wo, test_count=N_CHI2)


@pytest.mark.parametrize(("case", "wo"), INTEGRALS, ids=pair_ids(INTEGRALS))
def test_pdf_furnace_and_albedo(case, wo):
    check_integrals(case, wo)


@pytest.mark.parametrize(("case", "wo"), L_INTEGRALS, ids=pair_ids(L_INTEGRALS))
def test_pdf_furnace_and_albedo_layered(case, wo):
    check_integrals_combined(case, wo)


# --- the fitted table and the LTC ----------------------------------------------------------


def test_table_is_the_published_fit():
    # spot values of the authors' "volume" table (rows: roughness i/31, columns:
    # cos theta j/31), read at the nodes by the kernel's bilinear lookup
    assert LTC.shape == (32, 32, 3)
    for (i, j), want in {(0, 0): (0.01415, 0.00060, 0.00001),
                         (3, 0): (0.03084, -0.04909, 0.55348),
                         (4, 1): (0.05152, -0.02772, 0.42999),
                         (31, 31): (0.87958, 0.00003, 0.34187)}.items():
        got = ltc_coefficients(albedo_table(None), 0, i / 31, j / 31)
        assert np.allclose(got, want, atol=1e-12), (i, j)
    assert np.all(LTC[..., 0] >= 0.0) and np.all(LTC[..., 2] <= 0.75)
    assert np.all((LTC[..., 0] > 0) | (LTC[..., 2] == 0))  # an empty LTC reflects 0


@pytest.mark.parametrize(("alpha", "mu"), [(0.3, 0.2), (0.5, 0.9), (0.97, 0.05), (1.0, 1.0),
                                           (0.12, 0.0)])
def test_ltc_integrates_to_one_over_the_hemisphere(alpha, mu):
    # M^-1 keeps z: the whole lobe is above the horizon, so pdf integrates to 1 and the
    # albedo is exactly c
    b = M(alpha)
    wo = np.array([np.sqrt(1 - mu * mu), 0.0, max(mu, 1e-3)])

    def f(w):
        return b.pdf(tile(wo, len(w)), w)

    q = sphere_integral(f, np.array([0.0, 0.0, 1.0]), 1, n_beta=256, order=16)
    assert q == pytest.approx(1.0, abs=2e-3)


def test_albedo_is_exact_and_sheen_rises_toward_grazing():
    b = M(0.5, tint=(1.0, 0.5, 0.25))
    wo = direction(70.0)[None]
    s = sample_lanes(b, wo[0], 2000)
    assert np.allclose(s.weight[s.valid], b.albedo(wo)[0], rtol=1e-14, atol=0)
    a = M(0.5).albedo(np.stack([direction(0.0), direction(80.0)]))[:, 0]
    assert a[1] > 2 * a[0]


def test_normal_incidence_is_round():
    # at cos theta_o = 1 the fitted skew b is ~3e-5: the lobe is symmetric about n
    b = M(0.9)
    wo = np.array([[0.0, 0.0, 1.0]])
    phi = np.linspace(0.0, 2 * np.pi, 13)
    wi = np.stack([0.6 * np.cos(phi), 0.6 * np.sin(phi), np.full_like(phi, 0.8)], axis=1)
    e = b.eval(np.repeat(wo, len(wi), axis=0), wi)[:, 0]
    assert np.ptp(e) <= 1e-3 * e.max()


def test_multiscatter_defaults():
    # multiscatter_tint 0 (the default) or bsdf(): the lobe alone; otherwise a layer over
    # MDL's default white Lambertian lobe, which never gains energy
    assert M(0.5).program.code.shape[0] == 1
    assert M(0.5, multiscatter_tint=1.0, multiscatter=None).program.code.shape[0] == 1
    layered = M(0.5, multiscatter_tint=1.0)
    assert layered.program.code.shape[0] == 3
    for th in (0.0, 45.0, 85.0):
        s = sample_lanes(layered, direction(th), 40_000)
        m, se = s.weight.mean(axis=0), s.weight.std(axis=0) / np.sqrt(40_000)
        assert np.all(m <= 1.0 + 4 * se) and np.all(m >= 0.85)


@settings(max_examples=60)
@given(st.floats(0.0, 1.0), st.floats(0.0, 1.0), st.floats(0.0, 1.0), st.floats(0.0, 180.0),
       st.floats(0.0, 360.0), st.floats(0.0, 1.0), st.floats(0.0, 1.0), st.floats(0.0, 1.0))
def test_properties(r, t, ms, th, ph, u0, u1, u2):
    # property: any roughness, tints and direction: a finite sample whose pdf and weight
    # are pdf() and eval()/pdf() there, on wo's side; an albedo in [0, 1]
    b = M(r, tint=t, multiscatter_tint=ms)
    wo = direction(th, ph)[None]
    s = b.sample(wo, np.array([u0]), np.array([[u1, u2]]))
    assert np.all(np.isfinite(s.wi)) and np.all(np.isfinite(s.weight))
    if s.valid[0]:
        e, p = b.eval_pdf(wo, s.wi)
        assert s.pdf[0] == pytest.approx(p[0], rel=1e-9)
        assert np.allclose(s.weight[0], e[0] / p[0], rtol=1e-9, atol=1e-15)
        assert s.wi[0, 2] * wo[0, 2] > 0.0
    a = b.albedo(wo)[0]
    assert np.all(np.isfinite(a)) and np.all(a >= 0.0) and np.all(a <= 1.0 + 1e-12)


def test_parses_and_binds():
    from displacement.surfaces import UnitSquare
    from render.expr import parse_material

    state = UnitSquare().state_at_uv(np.array([[0.5, 0.5]]))
    m = parse_material("material(surface: material_surface(scattering: "
                       "df::microflake_sheen_bsdf(roughness: 0.5, tint: color(1.0, 0.8, 0.8), "
                       "multiscatter_tint: color(0.3, 0.05, 0.05))))")
    b = m.surface.scattering.bind(state)
    assert isinstance(b, df.MicroflakeSheenBsdf)
    want = M(0.5, tint=(1.0, 0.8, 0.8), multiscatter_tint=(0.3, 0.05, 0.05))
    wo = direction(40.0)[None]
    assert np.allclose(b.albedo(wo), want.albedo(wo), rtol=1e-12)


def test_bad_arguments():
    with pytest.raises(ValueError, match="multiscatter"):
        M(0.3, multiscatter_tint=1.0, multiscatter=df.diffuse_edf())
    with pytest.raises(ValueError, match="roughness must be finite"):
        M(np.nan)
