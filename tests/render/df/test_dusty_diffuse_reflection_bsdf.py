"""df::dusty_diffuse_reflection_bsdf: d'Eon's Lambertian-sphere BRDF through the df checklist,
its albedo table against quadrature, and the properties of the fit it rests on."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
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
    random_dirs,
)

from render import df
from render.df.dusty_diffuse_reflection_bsdf import (
    lambert_sphere_brdf,
    single_scattering_albedo,
)
from render.testing import direction, sphere_integral, tile

D = df.dusty_diffuse_reflection_bsdf
#: the albedo table's accuracy (65 x 65 bilinear nodes; measured below 2e-4)
TAB = 3e-4

CASES = [
    DfCase("white", lambda: D(), "diffuse", albedo_tol=TAB),
    DfCase("grey", lambda: D(tint=0.5), "diffuse", albedo_tol=TAB),
    DfCase("color", lambda: D(tint=(0.9, 0.35, 0.05)), "diffuse", albedo_tol=TAB),
    DfCase("black", lambda: D(tint=0.0), "diffuse"),
    DfCase("near-white", lambda: D(tint=0.9995), "diffuse", albedo_tol=TAB),
    DfCase("faint", lambda: D(tint=(1e-4, 0.0, 2e-3)), "diffuse", albedo_tol=TAB),
]
CHI2 = per_wo(CASES, CHI2_WOS, only=lambda c: c.id == "white")
CHI2 += per_wo(CASES, CHI2_WOS[1:3], only=lambda c: c.id == "color")
INTEGRALS = per_wo([c for c in CASES if c.id in ("white", "color")])
INTEGRALS += per_wo([c for c in CASES if c.id not in ("white", "color")], WOS[:2])


@pytest.mark.parametrize("case", CASES, ids=case_ids(CASES))
def test_consistency(case, rng):
    check_consistency(case, rng)


@pytest.mark.parametrize("case", CASES, ids=case_ids(CASES))
def test_no_nan_or_negative(case, rng):
    check_no_nan(case, rng)


@pytest.mark.parametrize("case", CASES, ids=case_ids(CASES))
def test_reciprocity(case, rng):
    check_reciprocity(case, rng)


@pytest.mark.parametrize(("case", "wo"), CHI2, ids=pair_ids(CHI2))
def test_chi2(case, wo):
    check_chi2(case, wo, test_count=len(CHI2))


@pytest.mark.parametrize(("case", "wo"), INTEGRALS, ids=pair_ids(INTEGRALS))
def test_pdf_furnace_and_albedo(case, wo):
    check_integrals(case, wo)


# --- the fit's properties ------------------------------------------------------------------


def test_white_albedo_is_below_one_and_close_to_it():
    # a conservative half-space reflects everything; the fit keeps 97.9-99.4 % of it and
    # never gains (the numbers the module docstring gives)
    mu = np.concatenate([np.linspace(1e-6, 1.0, 400), [1e-9, 1e-4]])
    wo = np.stack([np.sqrt(1 - mu**2), np.zeros_like(mu), mu], axis=1)
    a = D().albedo(wo)[:, 0]
    assert np.all(a <= 1.0) and np.all(a >= 0.978)
    assert a[-3] == pytest.approx(0.9789, abs=2e-4)  # normal incidence
    assert D().albedo(direction(60.0)[None])[0, 0] == pytest.approx(0.9907, abs=2e-4)


@pytest.mark.parametrize("tint", [1.0, 0.7, 0.3, 0.05, 1e-3])
def test_the_clamp_never_acts(tint):
    # libbsdf's max(f, 0) never acts for c in (0, 1]: f > 0 on a dense grid of (mu1, mu2,
    # phi); the albedo table's split into azimuthal modes rests on this
    m = np.concatenate([np.geomspace(1e-8, 0.05, 12), np.linspace(0.06, 1.0, 30)])
    phi = np.linspace(0.0, np.pi, 61)
    for m1 in m:
        for m2 in m:
            s1, s2 = np.sqrt(1 - m1 * m1), np.sqrt(1 - m2 * m2)
            for p in phi:
                f = lambert_sphere_brdf(tint, tint, tint, s1, 0.0, m1, s2 * np.cos(p),
                                        s2 * np.sin(p), m2)[0]
                assert f > 0.0 and np.isfinite(f), (m1, m2, p)


def test_backscatter_and_flattening():
    # dust reflects back toward the light (the retro direction beats the mirror
    # direction at 60 degrees), unlike Lambert's constant 1/pi
    b = D(tint=0.6)
    wo = direction(60.0)[None]
    retro = b.eval(wo, wo)[0, 0] / wo[0, 2]
    mirror = b.eval(wo, direction(60.0, 180.0)[None])[0, 0] / wo[0, 2]
    assert retro > 1.5 * mirror
    # a grey dusty surface is darker than Lambert at normal incidence and brighter
    # toward grazing (the albedo rises with the angle)
    a = b.albedo(np.stack([direction(0.0), direction(80.0)]))[:, 0]
    assert a[0] < 0.6 < a[1]


def test_single_scattering_albedo_mapping():
    # Eq. (46) maps [0, 1] onto [0, 1], monotonically, capped at 1 where the fit
    # overshoots (a in (0.9988, 1))
    a = np.concatenate([np.linspace(0.0, 1.0, 2001), 1.0 - np.geomspace(1e-12, 1e-2, 200)])
    c = np.array([single_scattering_albedo(x) for x in np.sort(a)])
    assert c[0] == 0.0 and c[-1] == 1.0
    assert np.all(np.diff(c) >= 0.0) and np.all((c >= 0.0) & (c <= 1.0))
    assert single_scattering_albedo(0.9995) == 1.0  # (the fit gives 1 + 2e-10)
    assert single_scattering_albedo(-0.5) == 0.0 and single_scattering_albedo(7.0) == 1.0


def test_black_channels_are_black(rng):
    # the fit leaves ~1e-4 at c = 0; a channel of tint 0 reflects nothing
    wo, wi = random_dirs(rng, 2000), random_dirs(rng, 2000)
    wi[:, 2] = np.abs(wi[:, 2]) * np.sign(wo[:, 2])
    e = D(tint=(0.0, 0.4, 0.0)).eval(wo, wi)
    assert not np.any(e[:, [0, 2]]) and np.all(e[np.abs(wo[:, 2]) > 1e-6, 1] > 0)
    assert not np.any(D(tint=0.0).albedo(wo))


def test_albedo_table_against_quadrature():
    # the table at off-node cosines and tints, against quadrature of eval
    for tint in (0.93, 0.41, 0.12):
        b = D(tint=tint)
        for th in (7.0, 51.0, 83.0):
            wo = direction(th, 20.0)

            def f(w, b=b, wo=wo):
                return b.eval(tile(wo, len(w)), w)[:, 0]

            q = sphere_integral(f, np.array([0.0, 0.0, 1.0]), 1, n_beta=128)
            assert b.albedo(wo[None])[0, 0] == pytest.approx(float(q), abs=TAB), (tint, th)


@settings(max_examples=60)
@given(st.floats(0.0, 1.0), st.floats(0.0, 1.0), st.floats(0.0, 1.0), st.floats(0.0, 180.0),
       st.floats(0.0, 360.0), st.floats(0.0, 1.0), st.floats(0.0, 1.0), st.floats(0.0, 1.0))
def test_properties(t0, t1, t2, th, ph, u0, u1, u2):
    # property: any tint and direction: a finite sample whose pdf and weight are pdf()
    # and eval()/pdf() there, reciprocal values, an albedo in [0, 1] no larger than the
    # same lobe's white albedo per channel
    b = D(tint=(t0, t1, t2))
    wo = direction(th, ph)[None]
    s = b.sample(wo, np.array([u0]), np.array([[u1, u2]]))
    assert np.all(np.isfinite(s.wi)) and np.all(np.isfinite(s.weight))
    if s.valid[0]:
        e, p = b.eval_pdf(wo, s.wi)
        assert s.pdf[0] == pytest.approx(p[0], rel=1e-12)
        assert np.allclose(s.weight[0], e[0] / p[0], rtol=1e-12, atol=0)
        assert np.allclose(b.eval(s.wi, wo)[0] / abs(wo[0, 2]), e[0] / abs(s.wi[0, 2]),
                           rtol=1e-12, atol=0)
    a = b.albedo(wo)[0]
    white = D().albedo(wo)[0, 0]
    assert np.all(np.isfinite(a)) and np.all(a >= 0.0) and np.all(a <= white + 1e-12)


def test_parses_and_binds():
    from displacement.surfaces import UnitSquare
    from render.expr import parse_material

    m = parse_material("material(surface: material_surface(scattering: "
                       "df::dusty_diffuse_reflection_bsdf(tint: color(0.8, 0.6, 0.4))))")
    b = m.surface.scattering.bind(UnitSquare().state_at_uv(np.array([[0.5, 0.5]])))
    assert isinstance(b, df.DustyDiffuseReflectionBsdf)
    assert np.allclose(b.albedo(direction(20.0)[None]),
                       D(tint=(0.8, 0.6, 0.4)).albedo(direction(20.0)[None]))


def test_tint_is_saturated_and_lanes_broadcast():
    wo = np.array([[0.0, 0.0, 1.0]] * 2)
    wi = np.array([[0.0, 0.6, 0.8]] * 2)
    e = D(tint=np.array([[2.0, -1.0, 0.5], [1.0, 0.0, 0.5]])).eval(wo, wi)
    assert np.array_equal(e[0], e[1])


def test_bad_arguments():
    with pytest.raises(ValueError, match="tint must be"):
        D(tint=[1.0, 0.5])
    with pytest.raises(ValueError, match="tint must be finite"):
        D(tint=np.nan)
