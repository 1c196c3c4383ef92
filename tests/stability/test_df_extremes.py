"""Stability of every distribution function at the extremes (docs/stability.md,
"Distribution functions"): roughness 0, 1e-7 and 1; ior 1, 1e-3 and 1e3 (both sides,
thin-walled too); tints 0 and 1; directions within 1e-7 of the horizon.

Two levels.  The kernels (as the renderer runs them, strict: internal finiteness checks
on and every floating-point exception raised): ``eval``, ``pdf``, ``sample`` and
``albedo`` are finite and non-negative, ``albedo() <= 1``, and the Monte-Carlo white
furnace of ``sample`` stays at or below 1.  The renders: a sphere of each df in a white
environment is finite, non-negative and
no brighter than 1 (within noise)."""

from __future__ import annotations

import numpy as np
import pytest
from stability import FURNACE_SIGMAS, FURNACE_TOL, assert_no_energy_gain, furnace

from displacement.surfaces import UVSphere
from render import df
from render import material as M
from render.camera import Camera
from render.numerics import strict
from render.scene import SceneObject
from render.testing import sample_lanes

RT, TR = "scatter_reflect_transmit", "scatter_transmit"
ROUGHNESS = (0.0, 1e-7, 1.0)
IOR = (1.0, 1e-3, 1e3)
TINT = (0.0, 1.0)


def _kernel_cases() -> dict:
    """Every df (bsdfs, layers, mixes, modifiers) at every listed extreme."""
    cases = {}
    for t in TINT:
        cases[f"diffuse_transmission t{t:g}"] = lambda t=t: df.diffuse_transmission_bsdf(tint=t)
        cases[f"specular reflect t{t:g}"] = lambda t=t: df.specular_bsdf(tint=t)
        cases[f"tint t{t:g}"] = lambda t=t: df.tint(t, df.diffuse_reflection_bsdf())
        cases[f"directional_factor t{t:g}"] = lambda t=t: df.directional_factor(
            t, t, base=df.simple_glossy_bsdf(roughness_u=0.3))
        for r in ROUGHNESS:
            cases[f"diffuse_reflection r{r:g} t{t:g}"] = lambda r=r, t=t: (
                df.diffuse_reflection_bsdf(tint=t, roughness=r))
            cases[f"backscattering r{r:g} t{t:g}"] = lambda r=r, t=t: (
                df.backscattering_glossy_reflection_bsdf(roughness_u=r, tint=t))
            cases[f"simple_glossy reflect r{r:g} t{t:g}"] = lambda r=r, t=t: (
                df.simple_glossy_bsdf(roughness_u=r, tint=t))
            cases[f"custom_curve_layer r{r:g} t{t:g}"] = lambda r=r, t=t: df.custom_curve_layer(
                t, 1.0, 5.0, 1.0, df.simple_glossy_bsdf(roughness_u=r, tint=t),
                df.diffuse_reflection_bsdf(tint=t))
            cases[f"weighted_layer r{r:g} t{t:g}"] = lambda r=r, t=t: df.weighted_layer(
                0.5, df.simple_glossy_bsdf(roughness_u=r, tint=t),
                df.diffuse_reflection_bsdf(tint=t))
            cases[f"normalized_mix r{r:g} t{t:g}"] = lambda r=r, t=t: df.normalized_mix([
                df.bsdf_component(0.7, df.simple_glossy_bsdf(roughness_u=r, tint=t)),
                df.bsdf_component(0.7, df.diffuse_reflection_bsdf(tint=t))])
            cases[f"clamped_mix r{r:g} t{t:g}"] = lambda r=r, t=t: df.clamped_mix([
                df.bsdf_component(0.7, df.simple_glossy_bsdf(roughness_u=r, tint=t)),
                df.bsdf_component(0.7, df.diffuse_reflection_bsdf(tint=t))])
        for ior in IOR:
            for thin in (False, True):
                for mode in (RT, TR):
                    side = f"{mode[8:]} ior{ior:g}{' thin' if thin else ''} t{t:g}"
                    cases[f"specular {side}"] = lambda t=t, ior=ior, thin=thin, mode=mode: (
                        df.specular_bsdf(tint=t, mode=mode, ior_inside=ior, thin_walled=thin))
                    for r in ROUGHNESS:
                        cases[f"simple_glossy {side} r{r:g}"] = (
                            lambda t=t, ior=ior, thin=thin, mode=mode, r=r: df.simple_glossy_bsdf(
                                roughness_u=r, tint=t, mode=mode, ior_inside=ior,
                                thin_walled=thin))
            for r in ROUGHNESS:
                cases[f"fresnel_layer ior{ior:g} r{r:g} t{t:g}"] = lambda t=t, ior=ior, r=r: (
                    df.fresnel_layer(ior, 1.0, df.simple_glossy_bsdf(roughness_u=r, tint=t),
                                     df.diffuse_reflection_bsdf(tint=t)))
    return cases


KERNELS = _kernel_cases()


def horizon_directions() -> np.ndarray:
    """Unit directions with cos(theta) = 0, +-1e-12 ... +-1e-7, at three azimuths."""
    out = []
    for c in (0.0, 1e-12, 1e-9, 1e-8, 1e-7, -1e-12, -1e-8, -1e-7):
        s = np.sqrt(1.0 - c * c)
        out += [[s * np.cos(p), s * np.sin(p), c] for p in (0.0, 1.0, 2.5)]
    return np.asarray(out)


@pytest.fixture(autouse=True)
def _strict():
    with strict(), np.errstate(divide="raise", invalid="raise", over="raise", under="ignore"):
        yield


def test_the_grid_covers_every_extreme():
    names = " ".join(KERNELS)
    for word in ("r0 ", "r1e-07", "r1 ", "ior1 ", "ior0.001", "ior1000", "t0", "t1", "thin"):
        assert word in names + " ", word
    assert len(KERNELS) >= 150


@pytest.mark.parametrize("name", KERNELS)
def test_kernels_are_finite_and_lose_energy_at_the_horizon(name, rng):
    bsdf = KERNELS[name]()
    h = horizon_directions()
    v = rng.normal(size=(len(h) * 60, 3))
    v /= np.linalg.norm(v, axis=1, keepdims=True)
    wo = np.concatenate([np.repeat(h, len(h), axis=0), np.repeat(h, 60, axis=0), v])
    wi = np.concatenate([np.tile(h, (len(h), 1)), v, np.repeat(h, 60, axis=0)])
    e, p = bsdf.eval_pdf(wo, wi)
    assert np.all(np.isfinite(e)) and e.min() >= 0 and np.all(np.isfinite(p)) and p.min() >= 0
    u1 = rng.random(len(wo))
    u1[::5] = 0.0
    u1[1::5] = np.nextafter(1.0, 0.0)
    s = bsdf.sample(wo, u1, rng.random((len(wo), 2)))
    for a in (s.wi, s.pdf, s.weight):
        assert np.all(np.isfinite(a))
    assert s.pdf.min() >= 0 and s.weight.min() >= 0
    np.testing.assert_allclose(np.linalg.norm(s.wi[s.valid], axis=1), 1.0, atol=1e-12)
    a = bsdf.albedo(np.concatenate([h, v[:100]]))
    assert np.all(np.isfinite(a)) and a.min() >= 0 and a.max() <= 1.0 + 1e-12
    # the white furnace of the sampler, at normal, oblique and grazing incidence
    n = 20_000
    for w in (np.array([0.0, 0.0, 1.0]), np.array([0.6, 0.0, 0.8]), h[12], h[3], h[-1]):
        weight = sample_lanes(bsdf, w, n, seed=1).weight
        mean, err = weight.mean(axis=0), weight.std(axis=0) / np.sqrt(n)
        assert np.all(mean <= 1.0 + FURNACE_SIGMAS * err + FURNACE_TOL), (w, mean, err)


# -- edfs and the vdf ------------------------------------------------------------------
@pytest.mark.parametrize("exponent", [0.0, 1e-7, 1.0, 1e7])
@pytest.mark.parametrize("spread", [1e-7, 1.0, np.pi])
def test_spot_edf_is_finite_and_emits_at_most_its_power(exponent, spread, rng):
    edf = df.spot_edf(exponent=exponent, spread=spread, global_distribution=False)
    w = np.concatenate([horizon_directions(), rng.normal(size=(4000, 3))])
    w /= np.linalg.norm(w, axis=1, keepdims=True)
    e, p = edf.eval(w), edf.pdf(w)
    assert np.all(np.isfinite(e)) and e.min() >= 0 and np.all(np.isfinite(p)) and p.min() >= 0
    s = edf.sample(rng.random(20_000), rng.random((20_000, 2)))
    assert np.all(np.isfinite(s.weight)) and s.weight.min() >= 0 and np.all(np.isfinite(s.wo))
    # the weight is eval * cos / pdf: its mean is the emitted fraction of the power
    mean = s.weight.mean(axis=0)
    assert np.all(mean <= 1.0 + FURNACE_SIGMAS * s.weight.std(axis=0) / np.sqrt(20_000)
                  + FURNACE_TOL)


@pytest.mark.parametrize("bias", [-1.0, -(1 - 1e-7), 0.0, 1 - 1e-7, 1.0])
def test_anisotropic_vdf_at_full_bias_is_finite_and_lossless(bias, rng):
    vdf = df.anisotropic_vdf(bias)
    wo = np.concatenate([horizon_directions(), [[0.0, 0.0, 1.0], [0.0, 0.0, -1.0]]])
    for w in wo:
        s = sample_lanes(vdf, w, 5000, seed=2)
        assert np.all(np.isfinite(s.wi)) and np.all(np.isfinite(s.weight))
        assert np.all(np.isfinite(s.pdf)) and s.pdf.min() > 0
        np.testing.assert_allclose(s.weight, 1.0, rtol=1e-9)  # a phase function: lossless
    e, p = vdf.eval_pdf(np.repeat(wo, len(wo), 0), np.tile(wo, (len(wo), 1)))
    assert np.all(np.isfinite(e)) and e.min() >= 0 and np.all(np.isfinite(p))


# -- whole renders -----------------------------------------------------------------------
def _render_cases() -> dict:
    """A material for a sphere of each df at the extremes."""
    d = M.df
    out = {}

    def add(name, bsdf, ior=1.0, thin=False):
        out[name] = M.material(thin_walled=thin, ior=(ior,) * 3, surface=M.material_surface(bsdf))

    for t in TINT:
        add(f"diffuse_transmission t{t:g}", d.diffuse_transmission_bsdf(tint=t))
        for r in ROUGHNESS:
            add(f"diffuse r{r:g} t{t:g}", d.diffuse_reflection_bsdf(tint=t, roughness=r))
            add(f"glossy r{r:g} t{t:g}", d.simple_glossy_bsdf(roughness_u=r, tint=t))
            add(f"backscattering r{r:g} t{t:g}",
                d.backscattering_glossy_reflection_bsdf(roughness_u=r, tint=t))
        for ior in IOR:
            for thin in (False, True):
                for r in ROUGHNESS:
                    add(f"glossy rt ior{ior:g}{' thin' if thin else ''} r{r:g} t{t:g}",
                        d.simple_glossy_bsdf(roughness_u=r, tint=t, mode=RT), ior, thin)
                for mode in (RT, TR):
                    # index-matched and thin specular transmission are null interfaces
                    add(f"specular {mode[8:]} ior{ior:g}{' thin' if thin else ''} t{t:g}",
                        d.specular_bsdf(tint=t, mode=mode), ior, thin)
            add(f"fresnel_layer ior{ior:g} t{t:g}", d.fresnel_layer(
                ior=ior, layer=d.simple_glossy_bsdf(roughness_u=1e-7, tint=t),
                base=d.diffuse_reflection_bsdf(tint=t)))
    return out


RENDERS = _render_cases()
SPHERE_CAMERA = Camera(position=(0, 0, 4), look_at=(0, 0, 0), fov_y_deg=30, width=12,
                       height=12)


@pytest.mark.parametrize("name", RENDERS)
def test_a_sphere_of_each_df_at_the_extremes_renders_without_energy_gain(name):
    material = RENDERS[name]
    with np.errstate(divide="ignore", invalid="ignore", over="ignore"):  # numpy's own rules
        film = furnace([SceneObject(UVSphere(1.0), material)], SPHERE_CAMERA, spp=32)
    sphere = film.alpha() > 0.999
    assert sphere.sum() > 20
    assert_no_energy_gain(film.rgb()[sphere])
