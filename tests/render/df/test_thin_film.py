"""df::thin_film: Airy's film reflectance by hand (its limits), the propagation rules,
and the coated layers through the combiner checklist."""

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
from render.df.thin_film import film_reflectance, film_rgb
from render.testing import direction

D, G, S = df.diffuse_reflection_bsdf, df.microfacet_ggx_smith_bsdf, df.specular_bsdf


def coat(ior=1.5, r=0.2):
    return df.fresnel_layer(ior, layer=G(roughness_u=r), base=D(tint=0.4))


CASES = [
    CombinerCase("soap-on-coat", lambda: df.thin_film(380.0, 1.33, coat()), "diffuse",
                 albedo_tol=COMBINED_ALBEDO_TOL, chi2_wos=((45.0, 30.0),)),
    CombinerCase("mirror-coat", lambda: df.thin_film(250.0, (1.2, 1.4, 1.6),
                                                     df.fresnel_layer(1.6, layer=S(),
                                                                      base=D())), "diffuse",
                 albedo_tol=COMBINED_ALBEDO_TOL),
    CombinerCase("on-gold", lambda: df.thin_film(300.0, 1.45, df.fresnel_factor(
        (0.18, 0.42, 1.37), (3.42, 2.35, 1.77), G(roughness_u=0.3))), "glossy",
        albedo_tol=COMBINED_ALBEDO_TOL, chi2_wos=((0.0, 0.0),)),
]
CHI2 = per_wo(CASES, ((45.0, 30.0),), only=lambda c: c.chi2_wos is not None)
INTEGRALS = two_wos(CASES)


@pytest.mark.parametrize("case", CASES, ids=case_ids(CASES))
def test_consistency(case, rng):
    check_consistency(case, rng)


@pytest.mark.parametrize("case", CASES, ids=case_ids(CASES))
def test_no_nan_or_negative(case, rng):
    check_no_nan_combined(case, rng)


@pytest.mark.parametrize("case", CASES, ids=case_ids(CASES))
def test_reciprocity(case, rng):
    check_reciprocity(case, rng)


@pytest.mark.parametrize(("case", "wo"), CHI2, ids=pair_ids(CHI2))
def test_chi2(case, wo):
    check_chi2_combined(case, wo, test_count=len(CHI2))


@pytest.mark.parametrize(("case", "wo"), INTEGRALS, ids=pair_ids(INTEGRALS))
def test_pdf_furnace_and_albedo(case, wo):
    check_integrals_combined(case, wo)


@pytest.mark.parametrize("c", [1.0, 0.8, 0.4, 0.05])
def test_airy_limits(c):
    # no film: the bare interface; a film of the substrate's index: the top interface;
    # a conductor substrate without film: the conductor's reflectance
    for n2 in (1.33, 1.5, 2.4):
        bare = fresnel_dielectric(c, n2)[0]
        assert film_reflectance(c, 1.0, 1.4, n2, 0.0, 0.0, 550.0) == pytest.approx(bare, abs=1e-12)
        top = fresnel_dielectric(c, 1.7)[0]
        assert film_reflectance(c, 1.0, 1.7, 1.7, 0.0, 321.0, 550.0) == pytest.approx(top,
                                                                                    abs=1e-12)
    assert film_reflectance(c, 1.0, 1.3, 0.18, 3.42, 0.0, 600.0) == pytest.approx(
        fresnel_conductor(c, 0.18, 3.42), abs=1e-12)


def test_quarter_wave_antireflection():
    # n_film = sqrt(n0 n2), d = lambda / (4 n_film): no reflection at normal incidence
    n2, lam = 1.9, 550.0
    nf = np.sqrt(n2)
    assert film_reflectance(1.0, 1.0, nf, n2, 0.0, lam / (4 * nf), lam) < 1e-12
    # a half-wave film is absent at normal incidence
    bare = ((n2 - 1) / (n2 + 1)) ** 2
    assert film_reflectance(1.0, 1.0, 1.4, n2, 0.0, lam / (2 * 1.4), lam) == pytest.approx(bare)


def test_colours():
    # a vanishing film gives the bare Fresnel term in every channel (white balance), a
    # 400 nm soap film over water is coloured
    rgb = np.array(film_rgb(0.9, 1.0, 1.33, 1.33, 1.33, 1.5, 1.5, 1.5, 0.0, 0.0, 0.0, 1e-9))
    assert np.allclose(rgb, fresnel_dielectric(0.9, 1.5)[0], atol=1e-9)
    rgb = np.array(film_rgb(1.0, 1.0, 1.33, 1.33, 1.33, 1.0, 1.0, 1.0, 0.0, 0.0, 0.0, 400.0))
    assert rgb.max() - rgb.min() > 0.02


def test_propagation_rules(rng):
    wo, wi = random_dirs(rng, 3000), random_dirs(rng, 3000)
    wi[:, 2] = np.abs(wi[:, 2]) * np.sign(wo[:, 2])
    # a no-op on a df without Fresnel
    d = D(tint=0.6, roughness=0.3)
    assert np.array_equal(df.thin_film(400.0, 1.4, d).eval(wo, wi), d.eval(wo, wi))
    # through tint and a mix, onto the coat only
    c = coat()
    filmed = df.thin_film(400.0, 1.33, df.tint(0.8, df.normalized_mix([(0.5, c), (0.5, d)])))
    by_hand = df.tint(0.8, df.normalized_mix([(0.5, df.thin_film(400.0, 1.33, c)), (0.5, d)]))
    assert np.allclose(filmed.eval(wo, wi), by_hand.eval(wo, wi), rtol=1e-12, atol=0)
    assert not np.allclose(filmed.eval(wo, wi), df.tint(0.8, df.normalized_mix(
        [(0.5, c), (0.5, d)])).eval(wo, wi))
    # thickness 0: the film is absent
    assert np.allclose(df.thin_film(0.0, 1.33, c).eval(wo, wi), c.eval(wo, wi), rtol=1e-12)
    assert df.thin_film(400.0, 1.33, None) is None


def test_parses_and_binds():
    from displacement.surfaces import UnitSquare
    from render.expr import parse_material

    m = parse_material("material(surface: material_surface(scattering: df::thin_film("
                       "thickness: 380.0, ior: color(1.33), base: df::fresnel_layer(ior: 1.5, "
                       "layer: df::specular_bsdf(), base: df::diffuse_reflection_bsdf()))))")
    b = m.surface.scattering.bind(UnitSquare().state_at_uv(np.array([[0.5, 0.5]])))
    assert isinstance(b, df.FresnelLayer)
    a = b.albedo(direction(20.0)[None])[0]
    assert np.all(np.isfinite(a)) and a.max() - a.min() > 1e-3


def test_bad_arguments():
    with pytest.raises(ValueError, match="ior must be > 0"):
        df.thin_film(300.0, 0.0, coat())
    with pytest.raises(ValueError, match="must be a bound bsdf"):
        df.thin_film(300.0, 1.3, "coat")


# --- films on the lobes' own Fresnel split (scatter_reflect_transmit) ----------------------
RT = "scatter_reflect_transmit"
LOBES = [
    # a soap bubble: a water film in air (the material's IOR 1: air on both sides)
    CombinerCase("soap-bubble", lambda: df.thin_film(420.0, 1.33, S(mode=RT, ior_inside=1.0,
                                                                     thin_walled=True)),
                 "delta", transmits=True, thin=True, lossless=True, reciprocal=False),
    CombinerCase("glass-film", lambda: df.thin_film(300.0, 1.38, S(mode=RT, ior_inside=1.5)),
                 "delta", transmits=True, ior=(1.0, 1.5), lossless=True, reciprocal=False),
    CombinerCase("rough-glass-film", lambda: df.thin_film(300.0, 1.38, G(
        roughness_u=0.3, mode=RT, ior_inside=1.5)), "glossy", transmits=True, ior=(1.0, 1.5),
        albedo_tol=2e-2, reciprocal=False, chi2_wos=((45.0, 30.0),)),
]


@pytest.mark.parametrize("case", LOBES, ids=case_ids(LOBES))
def test_lobe_consistency_and_no_nan(case, rng):
    check_consistency(case, rng)
    check_no_nan_combined(case, rng)


@pytest.mark.parametrize(("case", "wo"), two_wos(LOBES), ids=pair_ids(two_wos(LOBES)))
def test_lobe_furnace(case, wo):
    check_integrals_combined(case, wo)


def test_lobe_chi2():
    check_chi2_combined(LOBES[2], (45.0, 30.0), test_count=1)


def test_film_colours_the_split_and_spares_plain_modes(rng):
    w = direction(0.0)[None]
    s = df.thin_film(420.0, 1.33, S(mode=RT, ior_inside=1.0, thin_walled=True)).sample(
        np.repeat(w, 4000, axis=0), rng.random(4000), rng.random((4000, 2)))
    refl = s.wi[:, 2] > 0
    # the reflected colour is the film's reflectance over its mean: not grey; reflection
    # and transmission together lose nothing (F + (1 - F) = 1 per channel)
    rgb = s.weight[refl].mean(axis=0)
    assert rgb.max() - rgb.min() > 0.1
    assert np.allclose(s.weight.mean(axis=0), 1.0, atol=0.05)
    # a reflect-only lobe has no Fresnel: the film leaves it alone
    g = G(roughness_u=0.3)
    wo, wi = random_dirs(rng, 500), random_dirs(rng, 500)
    assert np.array_equal(df.thin_film(420.0, 1.33, g).eval(wo, wi), g.eval(wo, wi))


# --- films over the custom curves (MDL 1.8) --------------------------------------------------
from hypothesis import given, settings  # noqa: E402
from hypothesis import strategies as st  # noqa: E402

from render.df.thin_film import edge_tint_ior, schlick_ior  # noqa: E402

CC, CCC, DF = df.custom_curve_layer, df.color_custom_curve_layer, df.directional_factor


def schlick(c, r0, r90=1.0, p=5.0):
    return r0 + (r90 - r0) * (1.0 - c) ** p


CURVES = [
    CombinerCase("on-custom-curve", lambda: df.thin_film(380.0, 1.33, CC(
        0.04, 1.0, 5.0, 0.9, layer=G(roughness_u=0.2), base=D(tint=0.4))), "diffuse",
        albedo_tol=COMBINED_ALBEDO_TOL, chi2_wos=((45.0, 30.0),)),
    CombinerCase("on-color-curve-mirror", lambda: df.thin_film(300.0, (1.2, 1.4, 1.6), CCC(
        (0.04, 0.1, 0.5), (1.0, 1.0, 1.0), (0.8, 0.9, 1.0), layer=S(), base=D())), "diffuse",
        albedo_tol=COMBINED_ALBEDO_TOL),
    CombinerCase("on-constant-curve", lambda: df.thin_film(420.0, 1.33, CC(
        0.2, 0.2, layer=G(roughness_u=0.3), base=D())), "diffuse",
        albedo_tol=COMBINED_ALBEDO_TOL),
    CombinerCase("on-directional-factor", lambda: df.thin_film(250.0, 1.45, DF(
        (0.9, 0.6, 0.3), (1.0, 1.0, 1.0), base=G(roughness_u=0.3))), "glossy",
        albedo_tol=COMBINED_ALBEDO_TOL, chi2_wos=((0.0, 0.0),)),
]
CURVE_CHI2 = [(c, w) for c in CURVES if c.chi2_wos for w in c.chi2_wos]


@pytest.mark.parametrize("case", CURVES, ids=case_ids(CURVES))
def test_curve_consistency_no_nan_and_reciprocity(case, rng):
    check_consistency(case, rng)
    check_no_nan_combined(case, rng)
    check_reciprocity(case, rng)


@pytest.mark.parametrize(("case", "wo"), CURVE_CHI2, ids=pair_ids(CURVE_CHI2))
def test_curve_chi2(case, wo):
    check_chi2_combined(case, wo, test_count=len(CURVE_CHI2))


@pytest.mark.parametrize(("case", "wo"), two_wos(CURVES), ids=pair_ids(two_wos(CURVES)))
def test_curve_furnace_and_albedo(case, wo):
    check_integrals_combined(case, wo)


def test_zero_thickness_leaves_the_curves_unchanged(rng):
    wo, wi = random_dirs(rng, 3000), random_dirs(rng, 3000)
    u1, u2 = rng.random(3000), rng.random((3000, 2))
    for base in (CC(0.04, 1.0, 5.0, 0.8, layer=G(roughness_u=0.2), base=D(tint=0.4)),
                 CCC((0.04, 0.3, 0.9), (1.0, 0.5, 1.0), (0.7, 1.0, 1.0), layer=S(), base=D()),
                 CC(0.3, 0.3, layer=G(roughness_u=0.3), base=D()),
                 DF((0.9, 0.6, 0.3), (1.0, 0.8, 1.0), (0.9, 1.0, 1.0), base=G(roughness_u=0.3))):
        film = df.thin_film(0.0, 1.33, base)
        assert np.array_equal(film.eval(wo, wi), base.eval(wo, wi))
        assert np.array_equal(film.pdf(wo, wi), base.pdf(wo, wi))
        assert np.array_equal(film.albedo(wo), base.albedo(wo))
        a, b = film.sample(wo, u1, u2), base.sample(wo, u1, u2)
        assert np.array_equal(a.wi, b.wi) and np.array_equal(a.weight, b.weight)
        assert np.array_equal(film.program.tables, base.program.tables)


@pytest.mark.parametrize("theta", [0.0, 30.0, 60.0, 80.0])
def test_film_changes_the_curve_layer_weight_as_its_fresnel_predicts(theta):
    # a mirror coat under a Schlick curve of glass (R0 = 0.04 is IOR 1.5): the layer's
    # weight w C(c) becomes w (C(c) + F_film(c) - F(c)), F the bare glass's Fresnel
    # and F_film that glass under the film (Airy), c = cos theta
    w, d, nf = 0.8, 380.0, 1.33
    assert schlick_ior(0.04) == pytest.approx(1.5, rel=1e-15)
    wo = direction(theta)[None]
    c = float(wo[0, 2])
    bare = CC(0.04, 1.0, 5.0, w, layer=S())
    filmed = df.thin_film(d, nf, bare)
    u2 = np.array([[0.5, 0.5]])
    s0, s1 = bare.sample(wo, np.array([0.3]), u2), filmed.sample(wo, np.array([0.3]), u2)
    assert s0.weight[0] == pytest.approx(w * schlick(c, 0.04), rel=1e-12)
    fresnel = fresnel_dielectric(c, 1.5)[0]
    film_f = np.array(film_rgb(c, 1.0, nf, nf, nf, 1.5, 1.5, 1.5, 0.0, 0.0, 0.0, d))
    assert np.allclose(s1.weight[0], w * np.clip(schlick(c, 0.04) + film_f - fresnel, 0, 1),
                       rtol=1e-9, atol=1e-12)
    # where the curve is the Fresnel term itself, the film's Fresnel replaces it
    assert np.allclose(s1.weight[0] - w * (schlick(c, 0.04) - fresnel), w * film_f,
                       rtol=1e-9, atol=1e-12)
    assert np.ptp(s1.weight[0]) > 1e-3  # a coloured film


@pytest.mark.parametrize("theta", [0.0, 45.0, 75.0])
def test_film_changes_the_directional_factor_as_its_conductor_predicts(theta):
    # the factor over a mirror is C(c); under the film C(c) + F_film(c) - F(c) for the
    # conductor of Gulbrandsen's fit (normal reflectance R0, edge tint R90 f82)
    d, nf = 250.0, 1.45
    wo = direction(theta)[None]
    c = float(wo[0, 2])
    u1, u2 = np.array([0.3]), np.array([[0.5, 0.5]])
    # a grey conductor: F is the conductor's Fresnel term exactly
    bare = DF(0.9, 0.8, 1.0, 3.0, base=S())
    w0 = bare.sample(wo, u1, u2).weight[0]
    w1 = df.thin_film(d, nf, bare).sample(wo, u1, u2).weight[0]
    n, k = edge_tint_ior(0.9, 0.8)
    film_f = np.array(film_rgb(c, 1.0, nf, nf, nf, n, n, n, k, k, k, d))
    assert np.allclose(w1, np.clip(w0 + film_f - fresnel_conductor(c, n, k), 0, 1), rtol=1e-9,
                       atol=1e-12)
    assert np.ptp(w1) > 1e-3 and np.ptp(w0) == 0.0  # the film colours a grey factor
    # a coloured one: F is the bare conductor through the film's own spectral weighting
    # (film_rgb at thickness 0), within 4e-2 of the per-channel Fresnel term (the
    # round trip from three channels to 16 wavelengths and back)
    r0, r90, f82 = (0.9, 0.6, 0.3), (1.0, 0.9, 0.8), (1.0, 0.9, 1.0)
    bare = DF(r0, r90, f82, 3.0, base=S())
    w0 = bare.sample(wo, u1, u2).weight[0]
    w1 = df.thin_film(d, nf, bare).sample(wo, u1, u2).weight[0]
    nk = [edge_tint_ior(r0[i], r90[i] * f82[i]) for i in range(3)]
    sub = (*(n for n, _ in nk), *(k for _, k in nk))
    film_f = np.array(film_rgb(c, 1.0, nf, nf, nf, *sub, d))
    bare_f = np.array(film_rgb(c, 1.0, nf, nf, nf, *sub, 0.0))
    assert np.allclose(w1, np.clip(w0 + film_f - bare_f, 0, 1), rtol=1e-9, atol=1e-12)
    assert np.allclose(bare_f, [fresnel_conductor(c, n, k) for n, k in nk], atol=4e-2)
    assert not np.allclose(w1, w0, atol=1e-3)


def test_substrates_reproduce_the_curve_at_normal_incidence():
    # the dielectric of schlick_ior and the conductor of edge_tint_ior reflect R0 at
    # normal incidence (the conductor: R0 pulled into [0.01, 0.99], as libbsdf)
    for r0 in (0.0, 0.02, 0.04, 0.3, 0.7, 0.98):
        n = schlick_ior(r0)
        assert fresnel_dielectric(1.0, float(n))[0] == pytest.approx(r0, abs=1e-12)
        for g in (0.0, 0.5, 1.0):
            n, k = edge_tint_ior(r0, g)
            assert fresnel_conductor(1.0, n, k) == pytest.approx(0.01 + 0.98 * r0, abs=1e-9)


def test_films_on_curves_parse_and_bind():
    from displacement.surfaces import UnitSquare
    from render.expr import parse_material

    state = UnitSquare().state_at_uv(np.array([[0.5, 0.5]]))
    for text, cls in (
            ("df::custom_curve_layer(normal_reflectivity: 0.04, layer: "
             "df::microfacet_ggx_smith_bsdf(0.2), base: df::diffuse_reflection_bsdf())",
             df.CustomCurveLayer),
            ("df::color_custom_curve_layer(normal_reflectivity: color(0.04, 0.1, 0.3), "
             "layer: df::specular_bsdf())", df.ColorCustomCurveLayer),
            ("df::directional_factor(normal_tint: color(0.9, 0.6, 0.3), base: "
             "df::microfacet_ggx_smith_bsdf(0.3))", df.DirectionalFactor)):
        m = parse_material("material(surface: material_surface(scattering: df::thin_film("
                           f"thickness: 380.0, ior: color(1.33), base: {text})))")
        b = m.surface.scattering.bind(state)
        assert isinstance(b, cls)
        plain = parse_material(f"material(surface: material_surface(scattering: {text}))")
        p = plain.surface.scattering.bind(state)
        wo = direction(20.0)[None]
        assert not np.allclose(b.albedo(wo), p.albedo(wo), atol=1e-4)


@settings(max_examples=40)
@given(st.floats(0.0, 1200.0), st.floats(1.0, 2.5), st.floats(0.0, 1.0), st.floats(0.0, 1.0),
       st.floats(0.0, 8.0), st.floats(0.0, 1.0), st.floats(0.0, 89.9), st.booleans())
def test_curve_film_properties(d, nf, r0, r90, p, w, theta, factor):
    # property: any film, curve and angle: the mirror coat's weight (custom curve) or
    # factor (directional_factor) stays in [0, w], the shift is the film's, and a film
    # of (almost) no thickness changes nothing
    wo = direction(theta, 30.0)[None]
    c = float(wo[0, 2])
    bare = DF(r0, r90, 1.0, p, base=S()) if factor else CC(r0, r90, p, w, layer=S())
    top = 1.0 if factor else w
    u1, u2 = np.array([0.3]), np.array([[0.5, 0.5]])
    w0 = bare.sample(wo, u1, u2).weight[0]
    s = df.thin_film(d, nf, bare).sample(wo, u1, u2)
    assert np.all(np.isfinite(s.weight)) and np.all(s.weight >= 0)
    assert np.all(s.weight[0] <= top + 1e-12)
    if factor:
        n, k = edge_tint_ior(r0, r90)
        sub = (n, n, n, k, k, k)
    else:
        n = schlick_ior(r0)
        sub = (n, n, n, 0.0, 0.0, 0.0)
    shift = (np.array(film_rgb(c, 1.0, nf, nf, nf, *sub, d))
             - np.array(film_rgb(c, 1.0, nf, nf, nf, *sub, 0.0)))
    curve = schlick(c, r0, r90, p)
    assert np.allclose(w0, top * curve, rtol=1e-12, atol=1e-15)
    assert np.allclose(s.weight[0], top * np.clip(curve + shift, 0, 1), rtol=1e-9, atol=1e-12)
    tiny = df.thin_film(1e-9, nf, bare).sample(wo, u1, u2).weight[0]
    assert np.allclose(tiny, w0, rtol=0, atol=1e-9)
