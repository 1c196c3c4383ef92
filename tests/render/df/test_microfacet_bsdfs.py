"""df::microfacet_{ggx,beckmann}_{smith,vcavities}_bsdf in all scatter modes, with
anisotropy and energy compensation (multiscatter_tint): the df checklist on the kernels."""

from __future__ import annotations

import math

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
from render.bsdf import Lobe
from render.df._microfacet import (
    BECKMANN,
    GGX,
    _erfinv,
    mf_d,
    mf_sample_visible,
    mf_smith_g1,
)
from render.testing import direction, sample_lanes, sphere_integral

RT, TR = "scatter_reflect_transmit", "scatter_transmit"
#: measured accuracy of the tabulated albedo (render.df._albedo), as for simple_glossy
TAB, TAB_ANISO, TAB_NARROW = 3e-3, 1e-2, 1e-2
DFS = {
    "ggx_smith": df.microfacet_ggx_smith_bsdf,
    "beckmann_smith": df.microfacet_beckmann_smith_bsdf,
    "ggx_vc": df.microfacet_ggx_vcavities_bsdf,
    "beckmann_vc": df.microfacet_beckmann_vcavities_bsdf,
}


def _cases(key: str) -> list[DfCase]:
    cls = DFS[key]

    def G(**kw):
        return lambda: cls(**kw)

    return [
        DfCase(f"{key}-r0.3", G(roughness_u=0.3), "glossy", albedo_tol=TAB),
        DfCase(f"{key}-r1", G(roughness_u=1.0), "glossy", albedo_tol=TAB),
        DfCase(f"{key}-r0", G(roughness_u=0.0), "glossy", chi2=False, narrow=True,
               albedo_tol=TAB),
        DfCase(f"{key}-aniso", G(roughness_u=0.1, roughness_v=0.5, tangent_u=(0.6, 0.8, 0.0)),
               "glossy", albedo_tol=TAB_ANISO,
               chi2_wos=((0.0, 0.0), (45.0, 30.0), (80.0, 120.0), (130.0, 250.0))),
        DfCase(f"{key}-rt-1.5", G(roughness_u=0.3, mode=RT, ior_inside=1.5), "glossy",
               transmits=True, ior=(1.0, 1.5), albedo_tol=TAB),
        DfCase(f"{key}-transmit-1.5", G(roughness_u=0.3, mode=TR, ior_inside=1.5), "glossy",
               transmits=True, ior=(1.0, 1.5), albedo_tol=TAB),
        DfCase(f"{key}-rt-1.0", G(roughness_u=0.3, mode=RT, ior_inside=1.0), "glossy",
               chi2=False, narrow_t=True, transmits=True, ior=(1.0, 1.0), albedo_tol=TAB),
        DfCase(f"{key}-rt-thin", G(roughness_u=0.3, mode=RT, ior_inside=1.5, thin_walled=True),
               "glossy", transmits=True, thin=True, ior=(1.0, 1.5), albedo_tol=TAB),
        # energy compensation: white lobes lossless to the table's accuracy
        DfCase(f"{key}-ms", G(roughness_u=0.6, multiscatter_tint=1.0), "glossy", lossless=True,
               lossless_tol=TAB, albedo_tol=TAB),
        DfCase(f"{key}-ms-rt", G(roughness_u=0.5, multiscatter_tint=1.0, mode=RT, ior_inside=1.5),
               "glossy", transmits=True, ior=(1.0, 1.5), lossless=True, lossless_tol=TAB,
               albedo_tol=TAB, reciprocal=False),
        DfCase(f"{key}-ms-black", G(roughness_u=0.4, tint=0.0, multiscatter_tint=(0.2, 0.5, 1.0)),
               "glossy", albedo_tol=TAB),
    ]


CASES = [c for k in DFS for c in _cases(k)]
MAIN = tuple(f"{k}-{c}" for k in DFS for c in ("r0.3", "rt-1.5", "transmit-1.5"))
CHI2 = per_wo(CASES, CHI2_WOS, only=lambda c: c.id.endswith("-r0.3"))
CHI2 += per_wo(CASES, CHI2_WOS[1:2] + CHI2_WOS[3:],
               only=lambda c: c.id.endswith(("-rt-1.5", "-transmit-1.5", "-ms", "-ms-rt")))
CHI2 += per_wo(CASES, ((0.0, 0.0), (80.0, 120.0)), only=lambda c: c.id.endswith("-aniso"))
CHI2 += per_wo(CASES, CHI2_WOS[2:3], only=lambda c: c.id.endswith(("-r1", "-rt-thin")))
INTEGRALS = per_wo([c for c in CASES if c.id in MAIN or c.id.endswith(("-aniso", "-ms"))])
INTEGRALS += per_wo([c for c in CASES if c.id.endswith(("-r1", "-r0", "-rt-thin", "-ms-rt",
                                                        "-ms-black"))], WOS[2:])


@pytest.mark.parametrize("case", CASES, ids=case_ids(CASES))
def test_consistency(case, rng):
    check_consistency(case, rng)


@pytest.mark.parametrize("case", CASES, ids=case_ids(CASES))
def test_no_nan_or_negative(case, rng):
    check_no_nan(case, rng)


@pytest.mark.parametrize("case", [c for c in CASES if c.reciprocal], ids=case_ids(
    [c for c in CASES if c.reciprocal]))
def test_reciprocity(case, rng):
    check_reciprocity(case, rng)


@pytest.mark.parametrize(("case", "wo"), CHI2, ids=pair_ids(CHI2))
def test_chi2(case, wo):
    check_chi2(case, wo, test_count=len(CHI2))


@pytest.mark.parametrize(("case", "wo"), INTEGRALS, ids=pair_ids(INTEGRALS))
def test_pdf_furnace_and_albedo(case, wo):
    check_integrals(case, wo)


# --- the model's pieces, worked out by hand --------------------------------------------------


@pytest.mark.parametrize("dist", [GGX, BECKMANN])
@pytest.mark.parametrize(("au", "av"), [(0.3, 0.3), (1.0, 1.0), (0.05, 0.6), (1e-3, 3e-3)])
def test_distribution_is_normalised(dist, au, av):
    # ∫ D(h) (n.h) dh = 1 (GGX and Beckmann, isotropic and anisotropic, narrow)
    d = np.vectorize(lambda t, b, n: mf_d(dist, au, av, t, b, n))

    def f(h):
        z = np.maximum(h[:, 2], 0.0)
        return d(h[:, 0], h[:, 1], z) * z

    total = sphere_integral(f, [0.0, 0.0, 1.0], +1, n_beta=96 if au == av else 256, order=16)
    # GGX's tail is heavy: at 1e-3 the rings resolve it less finely
    assert total == pytest.approx(1.0, abs=2e-6 if dist == BECKMANN else 5e-5), (au, av)


@pytest.mark.parametrize("dist", [GGX, BECKMANN])
@pytest.mark.parametrize("theta", [0.0, 30.0, 70.0, 89.0])
def test_smith_g1_normalises_the_visible_normals(dist, theta):
    # ∫ G1(v) max(0, v.h) D(h) / v.z dh = 1: G1 is the exact Smith term of D
    au, av = 0.4, 0.15
    v = direction(theta, 35.0)
    g1 = mf_smith_g1(dist, au, av, v[0], v[1], v[2])
    d = np.vectorize(lambda t, b, n: mf_d(dist, au, av, t, b, n))

    def f(h):
        z = np.maximum(h[:, 2], 0.0)
        return g1 * np.maximum(h @ v, 0.0) * d(h[:, 0], h[:, 1], z) / v[2]

    assert sphere_integral(f, [0.0, 0.0, 1.0], +1, n_beta=256, order=16) == pytest.approx(
        1.0, abs=1e-5)


@pytest.mark.parametrize("dist", [GGX, BECKMANN])
@pytest.mark.parametrize("theta", [0.0, 50.0, 85.0])
def test_visible_normal_sampler_matches_its_density(dist, theta):
    # the sampled half vectors' mean cosine with v and their mean h against quadrature of
    # the density G1 max(0, v.h) D / v.z
    au, av = 0.5, 0.2
    v = direction(theta, 60.0)
    rng = np.random.default_rng(3)
    u = rng.random((100_000, 2))
    h = np.array([mf_sample_visible(dist, au, av, v[0], v[1], v[2], a, b) for a, b in u])
    assert np.allclose(np.linalg.norm(h, axis=1), 1.0) and np.all(h[:, 2] >= 0.0)
    g1 = mf_smith_g1(dist, au, av, v[0], v[1], v[2])
    d = np.vectorize(lambda t, b, n: mf_d(dist, au, av, t, b, n))

    def f(x):
        z = np.maximum(x[:, 2], 0.0)
        p = g1 * np.maximum(x @ v, 0.0) * d(x[:, 0], x[:, 1], z) / v[2]
        return p[:, None] * x

    mean = sphere_integral(f, [0.0, 0.0, 1.0], +1, n_beta=256, order=16)
    se = h.std(axis=0) / math.sqrt(len(h))
    assert np.all(np.abs(h.mean(axis=0) - mean) <= 5 * se + 1e-6), (h.mean(axis=0), mean)


def test_erfinv_inverts_erf():
    x = np.concatenate([np.linspace(-0.999999, 0.999999, 2001), [0.0, 1e-12, -1e-12]])
    y = np.array([_erfinv(v) for v in x])
    assert np.max(np.abs(np.array([math.erf(v) for v in y]) - x)) < 2e-15


@settings(max_examples=60)
@given(st.sampled_from(list(DFS)), st.floats(0.0, 2.0), st.floats(0.0, 2.0),
       st.floats(0.0, 180.0), st.floats(0.0, 360.0), st.floats(0.0, 1.0),
       st.sampled_from(["scatter_reflect", RT, TR]), st.floats(1.0, 3.0))
def test_weight_is_eval_over_pdf_everywhere(key, ru, rv, th, ph, ms, mode, ior):
    # property: any roughness (beyond the tables' 1), angle, mode, IOR and compensation:
    # the sample's pdf and weight are pdf() and eval()/pdf() at the sampled wi, finite
    b = DFS[key](roughness_u=ru, roughness_v=rv, multiscatter_tint=ms, mode=mode,
                 ior_inside=ior, tangent_u=(0.3, -0.9, 0.2))
    rng = np.random.default_rng(0)
    wo = np.tile(direction(th, ph), (400, 1))
    s = b.sample(wo, rng.random(400), rng.random((400, 2)))
    assert np.all(np.isfinite(s.weight)) and np.all(s.weight >= 0)
    ok = s.valid
    e, p = b.eval_pdf(wo[ok], s.wi[ok])
    assert np.allclose(p, s.pdf[ok], rtol=1e-9)
    assert np.allclose(e / p[:, None], s.weight[ok], rtol=1e-9)


def test_smith_weight_is_tint_times_g1_of_wi():
    # reflect mode, Smith masking, visible-normal sampling: weight = tint G1(wi) <= tint
    for cls in (df.microfacet_ggx_smith_bsdf, df.microfacet_beckmann_smith_bsdf):
        b = cls(roughness_u=0.5, tint=(0.2, 0.5, 0.9))
        s = sample_lanes(b, direction(70.0, 10.0), 5000)
        w = s.weight[s.valid]
        dist = GGX if cls is df.microfacet_ggx_smith_bsdf else BECKMANN
        g1 = np.array([mf_smith_g1(dist, 0.5, 0.5, *x) for x in s.wi[s.valid]])
        assert np.allclose(w, g1[:, None] * [0.2, 0.5, 0.9], rtol=1e-12)


def test_peak_value_at_normal_incidence():
    # wo = wi = n: h = n; D(n) = 1/(pi a^2) for both; G = 1 (Smith at the pole, v-cavities)
    a = 0.4
    n = np.array([[0.0, 0.0, 1.0]])
    for cls in DFS.values():
        b = cls(roughness_u=a, tint=0.5)
        assert b.eval(n, n)[0, 0] == pytest.approx(0.5 / (np.pi * a * a) / 4, rel=1e-12)


def test_anisotropy_follows_tangent_u():
    for cls in DFS.values():
        for t in ([1.0, 0.0, 0.0], [0.0, 1.0, 0.0]):
            b = cls(roughness_u=0.05, roughness_v=0.4, tangent_u=t)
            s = sample_lanes(b, direction(0.0), 20_000)
            wi = s.wi[s.valid]
            along, across = np.std(wi @ np.array(t)), np.std(wi @ np.cross([0, 0, 1.0], t))
            assert across > 4 * along


def test_modes_and_total_internal_reflection(rng):
    for cls in DFS.values():
        s = cls(roughness_u=0.2).sample(random_dirs(rng, 5000), rng.random(5000),
                                        rng.random((5000, 2)))
        assert np.all(s.lobe[s.valid] == Lobe.GLOSSY_REFLECTION)
        s = sample_lanes(cls(roughness_u=0.2, mode=TR, ior_inside=1.5), direction(30.0), 5000)
        assert np.all(s.lobe[s.valid] == Lobe.GLOSSY_TRANSMISSION)
        s = sample_lanes(cls(roughness_u=0.2, mode=TR, ior_inside=1.5), direction(110.0), 5000)
        assert (s.lobe[s.valid] == Lobe.GLOSSY_REFLECTION).mean() > 0.9


def test_roughness_zero_approaches_the_mirror():
    for cls in DFS.values():
        for th in (0.0, 45.0, 89.0):
            wo = direction(th, 30.0)
            s = sample_lanes(cls(roughness_u=0.0), wo, 2000)
            assert s.valid.mean() > 0.99
            dev = np.linalg.norm(s.wi[s.valid] - wo * [-1, -1, 1], axis=1)
            # alpha = 1e-7: GGX's heavy tail (tan theta_h ~ alpha sqrt(u / (1 - u))) puts
            # the largest of 2000 deviations near 1e-5; the bulk is far tighter
            assert np.quantile(dev, 0.99) < 2e-6 and dev.max() < 1e-4


def test_multiscatter_compensation_adds_what_the_lobe_loses():
    # albedo with compensation = tint E + ms (1 - E); white: 1
    for cls in DFS.values():
        wo = direction(50.0, 0.0)[None]
        single = cls(roughness_u=0.8).albedo(wo)[0, 0]
        comp = cls(roughness_u=0.8, tint=0.5, multiscatter_tint=(1.0, 0.5, 0.0)).albedo(wo)[0]
        assert single < 0.97
        assert np.allclose(comp, 0.5 * single + np.array([1.0, 0.5, 0.0]) * (1 - single))
        # scatter_transmit takes no compensation (libbsdf)
        t = cls(roughness_u=0.8, mode=TR, ior_inside=1.5, multiscatter_tint=1.0)
        t0 = cls(roughness_u=0.8, mode=TR, ior_inside=1.5)
        w = random_dirs(np.random.default_rng(1), 200)
        v = random_dirs(np.random.default_rng(2), 200)
        assert np.array_equal(t.eval(w, v), t0.eval(w, v))


def test_bad_arguments():
    with pytest.raises(ValueError, match="roughness_u must be finite"):
        df.microfacet_ggx_smith_bsdf(roughness_u=np.nan)
    with pytest.raises(ValueError, match="mode must be one of"):
        df.microfacet_beckmann_vcavities_bsdf(roughness_u=0.3, mode="scatter_both")
    with pytest.raises(ValueError, match="missing a required argument: 'roughness_u'"):
        df.microfacet_ggx_vcavities_bsdf()
