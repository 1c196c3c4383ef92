"""Media whose phase function is any vdf program (fog_vdf, mixes of vdfs, tint(vdf)) run
by the interpreter in the path kernel, and ``material_volume.emission_intensity``:
emission along every segment inside a medium, attenuated by it, with spectral MIS."""

from __future__ import annotations

import math

import numpy as np
import pytest

from displacement.surfaces import Cube, UVSphere
from render import material as M
from render.camera import Camera
from render.integrator import Integrator, render
from render.lights import ConstantEnvironment
from render.scene import RenderSettings, Scene, SceneObject, make_transform
from render.volume import HomogeneousMedium

df = M.df


def medium(vdf=None, sigma_a=0.0, sigma_s=0.0, emission=0.0):
    """An index-matched clear boundary (a null interface) around a medium."""
    return M.material(surface=M.material_surface(df.specular_bsdf(mode="scatter_transmit")),
                      volume=M.material_volume(scattering=vdf, absorption_coefficient=sigma_a,
                                               scattering_coefficient=sigma_s,
                                               emission_intensity=emission))


def sphere_scene(mat, env=1.0, res=24, spp=8):
    sphere = SceneObject(UVSphere(1.0), mat, name="ball")
    cam = Camera(position=(0, 0, 4), look_at=(0, 0, 0), fov_y_deg=30, width=res, height=res)
    return Scene(cam, [sphere], [ConstantEnvironment(env)] if env else [],
                 RenderSettings(res, res, spp=spp, max_depth=-1, rr_depth=100_000))


def mean_and_error(px):
    px = px.reshape(-1, 3)
    return px.mean(axis=0), px.std(axis=0, ddof=1) / math.sqrt(len(px))


VDFS = {
    "fog": lambda: df.fog_vdf(particle_size=10.0),
    "small fog": lambda: df.fog_vdf(particle_size=0.8),
    "mix": lambda: df.normalized_mix(components=[
        df.vdf_component(weight=0.5, component=df.fog_vdf(particle_size=4.0)),
        df.vdf_component(weight=0.5, component=df.anisotropic_vdf(directional_bias=-0.6))]),
    "color mix": lambda: df.color_normalized_mix(components=[
        df.color_vdf_component(weight=(0.8, 0.5, 0.3), component=df.anisotropic_vdf(0.8)),
        df.color_vdf_component(weight=(0.2, 0.5, 0.7), component=df.fog_vdf())]),
    "white tint": lambda: df.tint(tint=(1.0, 1.0, 1.0), base=df.fog_vdf(particle_size=2.0)),
}


@pytest.mark.parametrize("name", list(VDFS))
def test_white_furnace_with_any_vdf_program(name):
    """A lossless, optically thick medium (sigma_s 6) behind an index-matched boundary in
    a white environment disappears, whatever its (normalised) phase function."""
    film = render(sphere_scene(medium(VDFS[name](), sigma_s=6.0)), progress=False)
    assert film.stats["bound_objects"] == []
    img = film.rgb()
    assert np.all(np.isfinite(img)) and img.min() >= 0
    inside = film.alpha() > 0.999
    mean, err = mean_and_error(img[inside])
    assert np.all(np.abs(mean - 1.0) < 4 * err + 1e-3), (mean, err)
    assert np.all(err < 0.03)


def test_a_tinted_phase_function_is_a_lower_albedo():
    """tint(c, vdf) scales every scattering event by c: the same medium as sigma_s' =
    c sigma_s, sigma_a' = sigma_a + (1 - c) sigma_s (the same extinction)."""
    c = np.array([0.9, 0.6, 0.3])
    sa, ss = 0.5, 4.0
    tinted = medium(df.tint(tint=tuple(c), base=df.anisotropic_vdf(0.4)), sigma_a=sa,
                    sigma_s=ss)
    plain = medium(df.anisotropic_vdf(0.4), sigma_a=tuple(sa + (1 - c) * ss),
                   sigma_s=tuple(c * ss))
    means = []
    for mat in (tinted, plain):
        means.append([])
        for seed in range(4):
            film = render(sphere_scene(mat, res=20, spp=16), progress=False, seed=seed)
            means[-1].append(film.rgb()[film.alpha() > 0.999].mean(axis=0))
    a, b = np.array(means[0]), np.array(means[1])
    err = np.sqrt(a.var(axis=0, ddof=1) / 4 + b.var(axis=0, ddof=1) / 4)
    assert np.all(np.abs(a.mean(axis=0) - b.mean(axis=0)) < 4 * err + 2e-3), (a, b, err)
    assert np.all(a.mean(axis=0) < 1.0)


def test_varying_vdf_arguments_are_a_clear_error():
    mat = medium(df.fog_vdf(particle_size=lambda s: 5.0 + s.position[:, 0]), sigma_s=1.0)
    scene = sphere_scene(mat, res=4, spp=1)
    with pytest.raises(ValueError, match="homogeneous"):
        Integrator(scene, scene.build())


def test_medium_rows_and_vacuum():
    m = HomogeneousMedium(0.0, 0.0, emission_intensity=(0.0, 2.0, 0.0))
    assert not m.is_vacuum and np.array_equal(m.row[9:], [0.0, 2.0, 0.0])
    assert HomogeneousMedium(0.0, 0.0).is_vacuum
    with pytest.raises(ValueError, match="emission_intensity"):
        HomogeneousMedium(1.0, 0.0, emission_intensity=(-1.0, 0.0, 0.0))


# ---------------------------------------------------------------- emission
def test_emitting_absorbing_slab_in_closed_form():
    """Straight through an index-matched slab of thickness d that absorbs and emits (no
    scattering, black surroundings): L = e (1 - exp(-sigma_a d)) / sigma_a per channel,
    noise-free."""
    sigma_a, e, d = np.array([0.5, 2.0, 6.0]), np.array([3.0, 1.0, 0.5]), 0.4
    slab = SceneObject(Cube(1.0), medium(sigma_a=tuple(sigma_a), emission=tuple(e)),
                       make_transform(scale=(2.0, d, 2.0)))
    cam = Camera(position=(0, 3, 0), look_at=(0, 0, 0), up=(0, 0, -1), width=16, height=16,
                 ortho_height=1.0)
    film = render(Scene(cam, [slab], [], RenderSettings(16, 16, spp=2, max_depth=-1)),
                  progress=False)
    want = e * -np.expm1(-sigma_a * d) / sigma_a
    img = film.rgb().reshape(-1, 3)
    assert np.allclose(img, want, rtol=1e-6, atol=0), np.abs(img / want - 1).max()
    # no absorption: e d
    slab = SceneObject(Cube(1.0), medium(emission=tuple(e)), make_transform(scale=(2.0, d, 2.0)))
    film = render(Scene(cam, [slab], [], RenderSettings(16, 16, spp=1, max_depth=-1)),
                  progress=False)
    assert np.allclose(film.rgb().reshape(-1, 3), e * d, rtol=1e-6)


def test_emitting_sphere_chords():
    """An absorbing, emitting sphere seen orthographically: each ray through it collects
    e (1 - exp(-sigma_a l)) / sigma_a over its chord l = 2 sqrt(R^2 - r^2)."""
    sigma_a, e, radius = 1.5, 2.0, 1.0
    ball = SceneObject(UVSphere(radius), medium(sigma_a=sigma_a, emission=e))
    res = 32
    cam = Camera(position=(0, 0, 4), look_at=(0, 0, 0), width=res, height=res,
                 ortho_height=2.4)
    film = render(Scene(cam, [ball], [], RenderSettings(res, res, spp=64, max_depth=-1)),
                  progress=False)
    img = film.rgb()[..., 0]
    # pixel centres; compare where the chord varies slowly across a pixel
    c = (np.arange(res) + 0.5) / res * 2.4 - 1.2
    r = np.hypot(c[None, :], c[:, None])
    inner = r < 0.8
    chord = 2 * np.sqrt(np.maximum(radius**2 - r**2, 0.0))
    want = e * -np.expm1(-sigma_a * chord) / sigma_a
    # the mesh's flat facets shorten chords slightly: 48 x 24 triangles about the sphere
    assert np.allclose(img[inner], want[inner], rtol=5e-3)
    assert np.all(img[r > 1.05] == 0.0)


@pytest.mark.parametrize(("sigma_a", "sigma_s", "g"), [
    (1.0, 3.0, 0.0),
    ((0.5, 1.5, 3.0), (4.0, 2.0, 1.0), 0.6),
    (2.0, 2.0, -0.5),
])
def test_kirchhoff_furnace(sigma_a, sigma_s, g):
    """A medium emitting e = sigma_a L0 in a uniform environment L0 is in equilibrium with
    it (Kirchhoff's law): every pixel is L0, whatever the scattering, its phase function
    and the chromatic extinction (spectral MIS)."""
    L0 = 0.7
    e = tuple(np.broadcast_to(np.asarray(sigma_a, dtype=float), (3,)) * L0)
    mat = medium(df.anisotropic_vdf(g), sigma_a=sigma_a, sigma_s=sigma_s, emission=e)
    film = render(sphere_scene(mat, env=L0, res=20, spp=16), progress=False)
    img = film.rgb()
    inside = film.alpha() > 0.999
    mean, err = mean_and_error(img[inside])
    assert np.all(np.abs(mean - L0) < 4 * err + 1e-3 * L0), (mean, err)
