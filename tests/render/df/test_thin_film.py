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
from render.df.fresnel_factor import fresnel_conductor
from render.df.thin_film import film_reflectance, film_rgb
from render.numerics import fresnel_dielectric
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
        bare = float(fresnel_dielectric(np.array([c]), n2)[0][0])
        assert film_reflectance(c, 1.0, 1.4, n2, 0.0, 0.0, 550.0) == pytest.approx(bare, abs=1e-12)
        top = float(fresnel_dielectric(np.array([c]), 1.7)[0][0])
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
    assert np.allclose(rgb, float(fresnel_dielectric(np.array([0.9]), 1.5)[0][0]), atol=1e-9)
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
