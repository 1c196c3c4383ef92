"""df::simple_glossy_bsdf (Ashikhmin–Shirley, v-cavities) in all scatter modes, checklist."""

from __future__ import annotations

import numpy as np
import pytest
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

from render.bsdf import Lobe
from render.df import simple_glossy_bsdf
from render.df._microfacet import as_d_cos, as_exponents
from render.testing import direction, sample_lanes, sphere_integral

RT, TR = "scatter_reflect_transmit", "scatter_transmit"
#: measured accuracy of the tabulated albedo (render.df._albedo): isotropic, anisotropic,
#: and narrow lobes at grazing incidence (E changes on the scale mu ~ roughness there)
TAB, TAB_ANISO, TAB_NARROW = 3e-3, 1e-2, 1e-2


def G(**kw):
    return lambda: simple_glossy_bsdf(**kw)


CASES = [
    DfCase("r0.3", G(roughness_u=0.3), "glossy", albedo_tol=TAB),
    DfCase("r1", G(roughness_u=1.0), "glossy", albedo_tol=TAB),
    DfCase("r0", G(roughness_u=0.0), "glossy", chi2=False, narrow=True, albedo_tol=TAB),
    DfCase("r1e-3", G(roughness_u=1e-3), "glossy", chi2=False, narrow=True, albedo_tol=TAB_NARROW),
    # at 89.9 degrees this lobe is a ~0.02 rad sliver the 101-cell grid cannot integrate
    DfCase(
        "aniso",
        G(roughness_u=0.1, roughness_v=0.5, tangent_u=(0.6, 0.8, 0.0)),
        "glossy",
        albedo_tol=TAB_ANISO,
        chi2_wos=((0.0, 0.0), (45.0, 30.0), (80.0, 120.0), (130.0, 250.0)),
    ),
    DfCase("color", G(roughness_u=0.3, tint=[0.2, 0.5, 0.9]), "glossy", albedo_tol=TAB),
    DfCase(
        "black",
        G(roughness_u=0.3, tint=0.0, mode=RT, ior_inside=1.5),
        "glossy",
        chi2=False,
        transmits=True,
        ior=(1.0, 1.5),
    ),
    DfCase(
        "rt-1.5",
        G(roughness_u=0.3, mode=RT, ior_inside=1.5),
        "glossy",
        transmits=True,
        ior=(1.0, 1.5),
        albedo_tol=TAB,
    ),
    DfCase(
        "rt-1.5-r1",
        G(roughness_u=1.0, mode=RT, ior_inside=1.5),
        "glossy",
        transmits=True,
        ior=(1.0, 1.5),
        albedo_tol=TAB,
    ),
    DfCase(
        "rt-3",
        G(roughness_u=0.3, mode=RT, ior_inside=3.0),
        "glossy",
        transmits=True,
        ior=(1.0, 3.0),
        albedo_tol=TAB,
    ),
    DfCase(
        "rt-1.0",
        G(roughness_u=0.3, mode=RT, ior_inside=1.0),
        "glossy",
        chi2=False,
        narrow_t=True,
        transmits=True,
        ior=(1.0, 1.0),
        albedo_tol=TAB,
    ),
    DfCase(
        "rt-1.0001",
        G(roughness_u=0.3, mode=RT, ior_inside=1.0001),
        "glossy",
        chi2=False,
        narrow_t=True,
        transmits=True,
        ior=(1.0, 1.0001),
        albedo_tol=TAB,
    ),
    DfCase(
        "transmit-1.5",
        G(roughness_u=0.3, mode=TR, ior_inside=1.5),
        "glossy",
        transmits=True,
        ior=(1.0, 1.5),
        albedo_tol=TAB,
    ),
    DfCase(
        "transmit-3-r0.1",
        G(roughness_u=0.1, mode=TR, ior_inside=3.0),
        "glossy",
        transmits=True,
        narrow_t=True,
        ior=(1.0, 3.0),
        albedo_tol=TAB,
    ),
    DfCase(
        "rt-1.5-thin",
        G(roughness_u=0.3, mode=RT, ior_inside=1.5, thin_walled=True),
        "glossy",
        transmits=True,
        thin=True,
        ior=(1.0, 1.5),
        albedo_tol=TAB,
    ),
    DfCase(
        "transmit-thin-r0.5",
        G(roughness_u=0.5, mode=TR, ior_inside=1.5, thin_walled=True),
        "glossy",
        transmits=True,
        thin=True,
        ior=(1.0, 1.5),
        albedo_tol=TAB,
    ),
]
# every mode at the four CHI2_WOS (normal, oblique, grazing, below); the variants at one or two
MAIN = ("r0.3", "rt-1.5", "transmit-1.5")
CHI2 = per_wo(CASES, CHI2_WOS, only=lambda c: c.id in MAIN)
CHI2 += per_wo(CASES, ((0.0, 0.0), (80.0, 120.0)), only=lambda c: c.id == "aniso")
CHI2 += per_wo(CASES, CHI2_WOS[1:2], only=lambda c: c.id in ("r1", "rt-3", "rt-1.5-thin"))
CHI2 += per_wo(
    CASES,
    CHI2_WOS[3:],
    only=lambda c: c.id in ("rt-1.5-r1", "transmit-3-r0.1", "transmit-thin-r0.5"),
)
# tint scales eval and weights linearly (checked by consistency); ior 1.0 is clamped to
# 1.0001 exactly as libbsdf does (test_index_match_is_pushed_apart): no need to integrate them.
# The main modes at all four WOS, the variants at the extremes (grazing, from below).
INTEGRALS = per_wo([c for c in CASES if c.id in MAIN + ("aniso",)])
INTEGRALS += per_wo(
    [c for c in CASES if c.id not in MAIN + ("aniso", "color", "black", "rt-1.0")], WOS[2:]
)


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


# --- the model, worked out by hand ------------------------------------------------------------


def test_distribution_is_normalised():
    # ∫ D(h) (n.h) dh = 1 for the Ashikhmin–Shirley density, isotropic and anisotropic,
    # down to roughness 1e-7 (libbsdf's n.h > 0.99999 shortcut would give ~1e9 there)
    for ru, rv in [(0.3, 0.3), (1.0, 1.0), (0.05, 0.6), (1e-7, 1e-7), (1e-3, 3e-3)]:
        e_u, e_v, norm = as_exponents(ru, rv)
        d_cos = np.vectorize(lambda t, b, n, e_u=e_u, e_v=e_v, norm=norm:
                             as_d_cos(e_u, e_v, norm, t, b, n))  # the kernel, over arrays

        def f(h, d_cos=d_cos):
            z = np.maximum(h[:, 2], 0.0)
            return d_cos(h[:, 0], h[:, 1], np.where(z > 0, z, 1.0)) * (z > 0)

        total = sphere_integral(f, [0.0, 0.0, 1.0], +1, n_beta=96 if ru == rv else 256, order=16)
        assert total == pytest.approx(1.0, abs=2e-6), (ru, rv)


def test_peak_value_at_normal_incidence():
    # wo = wi = n: h = n, D = (e + 1)/(2 pi) with e = 2/r^2, G = 1, eval = D / (4 nk1) = D/4
    r = 0.5
    e = 2.0 / r**2
    b = simple_glossy_bsdf(roughness_u=r, tint=0.5)
    n = np.array([[0.0, 0.0, 1.0]])
    assert b.eval(n, n)[0, 0] == pytest.approx(0.5 * (e + 1) / (2 * np.pi) / 4, rel=1e-14)
    assert b.pdf(n, n)[0] == pytest.approx((e + 1) / (2 * np.pi) / 4, rel=1e-14)


def test_vcavity_weight_is_min_of_masking():
    # reflect mode: weight = G2/G1(wo) = min(1, G1(wi)/G1(wo)) <= tint, equal to tint at normal view
    b = simple_glossy_bsdf(roughness_u=0.4)
    s = sample_lanes(b, direction(0.0), 10_000)
    assert np.all(s.weight[s.valid] <= 1.0)
    s = sample_lanes(b, direction(80.0), 10_000)
    w = s.weight[s.valid, 0]
    assert np.all(w <= 1.0) and np.any(w < 1.0)


def test_anisotropy_follows_tangent_u():
    # a lobe narrow along tangent_u and wide across it: the spread of sampled wi is larger
    # across the tangent
    for t in ([1.0, 0.0, 0.0], [0.0, 1.0, 0.0]):
        b = simple_glossy_bsdf(roughness_u=0.05, roughness_v=0.4, tangent_u=t)
        s = sample_lanes(b, direction(0.0), 20_000)
        wi = s.wi[s.valid]
        along, across = np.std(wi @ np.array(t)), np.std(wi @ np.cross([0, 0, 1.0], t))
        assert across > 4 * along


def test_tangent_parallel_to_normal_absorbs():
    b = simple_glossy_bsdf(roughness_u=0.3, tangent_u=(0.0, 0.0, 1.0))
    wo = direction(30.0)[None]
    assert not np.any(b.eval(wo, direction(30.0, 180.0)[None]))
    assert not np.any(b.sample(wo, np.array([0.5]), np.array([[0.3, 0.3]])).valid)


def test_reflect_mode_has_no_fresnel_and_transmit_mode_only_tir_reflects(rng):
    wo = random_dirs(rng, 20_000)
    u1, u2 = rng.random(20_000), rng.random((20_000, 2))
    s = simple_glossy_bsdf(roughness_u=0.2).sample(wo, u1, u2)
    assert np.all(s.lobe[s.valid] == Lobe.GLOSSY_REFLECTION)
    # transmit from outside (eta2 > eta1) never reflects: no total internal reflection
    up = wo * np.array([1, 1, 1])[None]
    up[:, 2] = np.abs(up[:, 2])
    s = simple_glossy_bsdf(roughness_u=0.2, mode=TR, ior_inside=1.5).sample(up, u1, u2)
    assert np.all(s.lobe[s.valid] == Lobe.GLOSSY_TRANSMISSION)
    # from inside at 70 degrees (beyond the critical angle 41.8) most light reflects (TIR)
    s = sample_lanes(
        simple_glossy_bsdf(roughness_u=0.2, mode=TR, ior_inside=1.5), direction(110.0), 20_000
    )
    refl = s.lobe == Lobe.GLOSSY_REFLECTION
    assert refl.mean() > 0.9 and np.all(s.wi[refl, 2] < 0)


def test_roughness_zero_approaches_the_mirror():
    for th in (0.0, 45.0, 89.9):
        wo = direction(th, 30.0)
        s = sample_lanes(simple_glossy_bsdf(roughness_u=0.0), wo, 2000)
        assert s.valid.all()
        assert np.max(np.linalg.norm(s.wi - wo * [-1, -1, 1], axis=1)) < 1e-5
        assert np.allclose(s.weight, 1.0)


def test_index_match_is_pushed_apart(rng):
    # libbsdf: |ior2 - ior1| >= 1e-4 for glossy refraction; an exact match behaves as 1.0001
    wo = np.concatenate([random_dirs(rng, 2000)])
    wi = random_dirs(rng, 2000)
    a = simple_glossy_bsdf(roughness_u=0.3, mode=RT, ior_inside=1.0)
    b = simple_glossy_bsdf(roughness_u=0.3, mode=RT, ior_inside=1.0 + 1e-4)
    ea, pa = a.eval_pdf(wo, wi)
    eb, pb = b.eval_pdf(wo, wi)
    assert np.allclose(ea, eb, rtol=1e-9, atol=0) and np.allclose(pa, pb, rtol=1e-9, atol=0)
    s = sample_lanes(a, direction(30.0), 1000)
    t = s.lobe == Lobe.GLOSSY_TRANSMISSION
    # the transmitted lobe hugs -wo (it is a delta in the limit)
    assert t.mean() > 0.99 and np.max(np.linalg.norm(s.wi[t] + direction(30.0), axis=1)) < 1e-3


def test_per_lane_parameters_match_scalar_ones(rng):
    # MDL varying arguments: one roughness, tint, tangent and IOR per lane
    n = 6
    ru = np.array([1e-7, 0.05, 0.3, 0.3, 0.7, 1.0])
    rv = np.array([1e-7, 0.2, 0.3, 0.6, 0.7, 0.4])
    tint = rng.random((n, 3))
    tu = np.concatenate([rng.normal(size=(n, 2)), np.zeros((n, 1))], axis=1)
    ior = np.array([1.0, 1.2, 1.5, 1.5, 2.0, 3.0])
    lanes = simple_glossy_bsdf(roughness_u=ru, roughness_v=rv, tint=tint, tangent_u=tu, mode=RT,
                               ior_inside=ior)
    wo = random_dirs(rng, n)
    wi = random_dirs(rng, n)
    u1, u2 = rng.random(n), rng.random((n, 2))
    e, p = lanes.eval_pdf(wo, wi)
    s = lanes.sample(wo, u1, u2)
    for i in range(n):
        one = simple_glossy_bsdf(roughness_u=ru[i], roughness_v=rv[i], tint=tint[i],
                                 tangent_u=tu[i], mode=RT, ior_inside=ior[i])
        ei, pi = one.eval_pdf(wo[i : i + 1], wi[i : i + 1])
        si = one.sample(wo[i : i + 1], u1[i : i + 1], u2[i : i + 1])
        assert np.allclose(e[i], ei[0], rtol=1e-12) and np.isclose(p[i], pi[0], rtol=1e-12)
        assert np.allclose(s.wi[i], si.wi[0]) and np.allclose(s.weight[i], si.weight[0])
    # albedo per lane (reflect tables at roughness 0.3 and 1, shared with the cases above)
    two = simple_glossy_bsdf(roughness_u=np.array([0.3, 1.0]), tint=tint[:2])
    a = two.albedo(wo[:2])
    for i, r in enumerate((0.3, 1.0)):
        one = simple_glossy_bsdf(roughness_u=r, tint=tint[i])
        assert np.allclose(a[i], one.albedo(wo[i : i + 1])[0])
    # anisotropic and isotropic lanes, refracting with an IOR per lane (both sides of the
    # surface): each lane reads the table a single-lane node of its values reads
    ru3, rv3 = np.array([0.3, 0.2, 0.2]), np.array([0.1, 0.2, 0.2])
    ior3 = np.array([1.5, 1.5, 1.33])
    w3 = np.concatenate([wo[:3, :2], np.abs(wo[:3, 2:]) * [[1.0], [-1.0], [1.0]]], axis=1)
    three = simple_glossy_bsdf(roughness_u=ru3, roughness_v=rv3, mode=RT, ior_inside=ior3)
    a = three.albedo(w3)
    for i in range(3):
        one = simple_glossy_bsdf(roughness_u=ru3[i], roughness_v=rv3[i], mode=RT,
                                 ior_inside=ior3[i])
        assert np.array_equal(a[i], one.albedo(w3[i : i + 1])[0])


def test_bad_arguments():
    with pytest.raises(ValueError, match="tangent_u must be a number, 3 numbers or one row of 3"):
        simple_glossy_bsdf(roughness_u=0.3, tangent_u=(1.0, 0.0))
    with pytest.raises(ValueError, match="roughness_u must be finite"):
        simple_glossy_bsdf(roughness_u=np.nan)
    with pytest.raises(ValueError, match="mode must be one of"):
        simple_glossy_bsdf(roughness_u=0.3, mode="scatter_both")
