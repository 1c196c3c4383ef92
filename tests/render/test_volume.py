"""Homogeneous media: free-flight sampling, the medium stack, and whole-image checks
(Beer–Lambert through a slab, a white furnace with an optically thick scattering
sphere, light reaching a floor inside an absorbing box, media that must be ignored)."""

from __future__ import annotations

import math

import numpy as np
import pytest
import trimesh
from numba import njit
from scipy import stats

from displacement.surfaces import Cube, Plane, UnitSquare, UVSphere
from render import material as M
from render import path
from render.camera import Camera
from render.integrator import Integrator, render
from render.lights import ConstantEnvironment, DirectionalLight, PointLight
from render.scene import RenderSettings, Scene, SceneObject, make_transform
from render.volume import (
    MAX_NESTING,
    HomogeneousMedium,
    is_closed,
    medium_of,
    stack_outside_ior,
    stack_pop,
    stack_push,
)


def medium_material(sigma_a=0.0, sigma_s=0.0, g=0.0, ior=1.0, mode="scatter_transmit",
                    thin_walled=False):
    """Listing 5.2's anisotropic_volume: a clear specular boundary around a medium."""
    return M.material(
        thin_walled=thin_walled,
        ior=(ior,) * 3,
        surface=M.material_surface(M.df.specular_bsdf(mode=mode)),
        volume=M.material_volume(
            scattering=M.df.anisotropic_vdf(directional_bias=g),
            absorption_coefficient=sigma_a,
            scattering_coefficient=sigma_s,
        ),
    )


def diffuse(tint):
    return M.material(surface=M.material_surface(M.df.diffuse_reflection_bsdf(tint=tint)))


def down_camera(res=16, ortho=1.0, height=3.0):
    """Orthographic, looking straight down -y at the origin."""
    return Camera(position=(0, height, 0), look_at=(0, 0, 0), up=(0, 0, -1), width=res,
                  height=res, ortho_height=ortho)


def mean_and_error(px: np.ndarray):
    px = px.reshape(-1, 3)
    return px.mean(axis=0), px.std(axis=0, ddof=1) / math.sqrt(len(px))


# ----------------------------------------------------------------------- the medium
def test_medium_coefficients_and_transmittance():
    m = HomogeneousMedium((1.0, 0.5, 0.0), (0.0, 0.5, 0.0), directional_bias=-0.3)
    assert np.allclose(m.sigma_t, [1.0, 1.0, 0.0]) and m.scatters and not m.is_vacuum
    tr = m.transmittance(np.array([0.0, 2.0, np.inf]))
    assert np.allclose(tr, [[1, 1, 1], [math.exp(-2), math.exp(-2), 1], [0, 0, 1]])
    assert float(m.phase.directional_bias) == -0.3
    # MDL's vdf() default is isotropic; an all-zero volume is no medium at all
    assert medium_of(medium_material(sigma_a=0.0)) is None
    assert medium_of(medium_material(sigma_a=1.0, thin_walled=True)) is None
    assert medium_of(M.material(volume=M.material_volume(absorption_coefficient=0.2))) is not None


@pytest.mark.parametrize(
    ("kwargs", "match"),
    [
        ({"absorption_coefficient": -1.0}, "absorption_coefficient"),
        ({"scattering_coefficient": (1.0, np.inf, 0.0)}, "scattering_coefficient"),
        ({"scattering_coefficient": lambda s: s.uv}, "homogeneous"),
        ({"directional_bias": 2.0}, "directional_bias"),
        ({"directional_bias": lambda s: s.uv[:, 0]}, "constant"),
    ],
)
def test_medium_rejects_bad_coefficients(kwargs, match):
    with pytest.raises(ValueError, match=match):
        HomogeneousMedium(**kwargs)


def test_free_flight_distances_are_exponential(rng):
    m = HomogeneousMedium(0.5, 1.5)  # sigma_t = 2
    n = 40_000
    s = m.sample_distance(np.full(n, 1.0), np.zeros(n, dtype=np.int64), rng.random(n))
    assert abs(s.scattered.mean() - (1 - math.exp(-2.0))) < 4 * math.sqrt(0.14 / n)
    # conditioned on t < 1, t follows the truncated exponential
    t = s.t[s.scattered]
    res = stats.kstest(t, lambda x: (1 - np.exp(-2 * x)) / (1 - math.exp(-2.0)))
    assert res.pvalue > 1e-3
    assert np.all(s.t[~s.scattered] == 1.0)
    # a grey medium: scattering weight sigma_s / sigma_t, passing weight 1, ratios 1
    w, r = s.weight(np.zeros(n, dtype=np.int64))
    assert np.allclose(w[s.scattered], 0.75) and np.allclose(w[~s.scattered], 1.0)
    assert np.allclose(r, 1.0)


def test_spectral_mis_single_segment_is_unbiased(rng):
    # one segment of length 0.7 through a chromatic medium: E[value / mean_j pdf_j]
    # over uniform hero channels is T_i(0.7) for the passing part and
    # int_0^0.7 sigma_s_i T_i(t) t dt for a test function g(t) = t of the scattering part
    sa, ss, d = np.array([0.2, 1.0, 0.0]), np.array([0.5, 3.0, 8.0]), 0.7
    m = HomogeneousMedium(sa, ss)
    n = 400_000
    hero = rng.integers(0, 3, n)
    s = m.sample_distance(np.full(n, d), hero, rng.random(n))
    w, r = s.weight(hero)
    est = w / r.mean(axis=1)[:, None]
    st = sa + ss
    passing = np.where(~s.scattered[:, None], est, 0.0)
    scat = np.where(s.scattered[:, None], est * s.t[:, None], 0.0)
    exact_scat = ss / st**2 * (1 - np.exp(-st * d) * (1 + st * d))
    for got, want in ((passing, np.exp(-st * d)), (scat, exact_scat)):
        mean, err = got.mean(axis=0), got.std(axis=0) / math.sqrt(n)
        assert np.all(np.abs(mean - want) < 4 * err + 1e-12), (mean, want, err)
    # the estimate is bounded: <= 3 sigma_s / sigma_t per channel when scattering
    assert np.all(est[s.scattered] <= 3 * ss / st + 1e-12)


def test_absorbing_only_medium_is_not_sampled():
    m = HomogeneousMedium((1.0, 2.0, 3.0), 0.0)
    s = m.sample_distance(np.array([0.5, np.inf]), np.array([0, 2]), np.array([0.1, 0.9]))
    assert not s.scattered.any() and np.array_equal(s.pdf, np.ones((2, 3)))
    assert np.allclose(s.value, [np.exp(-0.5 * np.array([1.0, 2.0, 3.0])), [0, 0, 0]])


# ------------------------------------------------------------------ the medium stack
def _stack_ops(ops, depth):
    return _stack_run(np.array(ops, dtype=np.float64), depth)


@njit
def _stack_run(ops, depth):
    """Run (kind, obj, ior) operations on one stack row: kind 0 push, 1 pop, 2 query the
    IOR outside obj; returns the queries' answers and the final row."""
    so = np.full((1, depth), -1, dtype=np.int64)
    sior = np.ones((1, depth))
    n = 0
    out = []
    for j in range(len(ops)):
        kind, obj, ior = ops[j, 0], ops[j, 1], ops[j, 2]
        if kind == 0:
            n = stack_push(so, sior, 0, n, int(obj), ior)
        elif kind == 1:
            n = stack_pop(so, sior, 0, n, int(obj))
        else:
            out.append(stack_outside_ior(so, sior, 0, n, int(obj)))
    return out, so[0, :n].copy(), sior[0, :n].copy()


def test_medium_stack_nesting_and_removal():
    push, pop, ask = 0, 1, 2
    out, objs, iors = _stack_ops([(push, 5, 1.33), (push, 8, 1.5), (push, 2, 1.2),
                                  (ask, 2, 0.0), (ask, 8, 0.0), (ask, 7, 0.0)], 3)
    # the IOR around object k: the innermost entry that is not k
    assert out == [1.5, 1.2, 1.2] and objs.tolist() == [5, 8, 2]
    # leaving the middle object keeps the order of the others; popping an object the
    # lane is not in changes nothing
    out, objs, iors = _stack_ops([(push, 5, 1.33), (push, 8, 1.5), (push, 2, 1.2),
                                  (pop, 8, 0.0), (pop, 9, 0.0), (ask, 2, 0.0)], 3)
    assert objs.tolist() == [5, 2] and iors.tolist() == [1.33, 1.2] and out == [1.33]
    out, objs, _ = _stack_ops([(push, 5, 1.33), (pop, 5, 0.0), (ask, 0, 0.0)], 3)
    assert objs.tolist() == [] and out == [1.0]
    # deeper than the row: further pushes are ignored, nothing overflows
    _, objs, _ = _stack_ops([(push, k, 1.0 + k) for k in range(MAX_NESTING + 3)], MAX_NESTING)
    assert objs.tolist() == list(range(MAX_NESTING))


def test_is_closed():
    box = trimesh.creation.box()
    assert is_closed(box.vertices, box.faces)
    assert not is_closed(box.vertices, box.faces[:-1])
    assert not is_closed(box.vertices, box.faces[:0])
    sphere = UVSphere(1.0).base_mesh(16, 8)  # seam duplicates and collapsed poles
    assert is_closed(sphere.vertices, sphere.faces)
    cube = Cube(2.0).base_mesh()  # six charts, no shared vertices
    assert is_closed(cube.vertices, cube.faces)
    square = UnitSquare().base_mesh()
    assert not is_closed(square.vertices, square.faces)


# ---------------------------------------------------------------- whole images
def test_beer_lambert_slab_per_channel():
    # an index-matched slab of thickness d seen straight through: exp(-sigma_a d) exactly
    sigma_a, d = np.array([1.0, 3.0, 7.0]), 0.3
    slab = SceneObject(Cube(1.0), medium_material(sigma_a=tuple(sigma_a)),
                       make_transform(scale=(2.0, d, 2.0)))
    scene = Scene(down_camera(16), [slab], [ConstantEnvironment(1.0)],
                  RenderSettings(16, 16, spp=2, max_depth=-1))
    film = render(scene, progress=False)
    img = film.rgb().reshape(-1, 3)
    want = np.exp(-sigma_a * d)
    assert np.allclose(img, want, rtol=1e-6, atol=0), np.abs(img / want - 1).max()
    assert np.all(film.alpha() == 1.0)


def test_beer_lambert_depends_on_thickness_and_scale():
    # a tilted view through a thicker slab: the path length is d / cos(theta)
    sigma_a, d, theta = 2.0, 0.5, math.radians(30.0)
    slab = SceneObject(Cube(1.0), medium_material(sigma_a=sigma_a),
                       make_transform(scale=(8.0, d, 8.0)))
    cam = Camera(position=(0, 3 * math.cos(theta), 3 * math.sin(theta)), look_at=(0, 0, 0),
                 width=8, height=8, ortho_height=0.5)
    scene = Scene(cam, [slab], [ConstantEnvironment(1.0)], RenderSettings(8, 8, spp=1))
    img = render(scene, progress=False).rgb()
    assert np.allclose(img, math.exp(-sigma_a * d / math.cos(theta)), rtol=1e-6)


@pytest.mark.parametrize(
    ("sigma_s", "g"),
    [(8.0, 0.0), (6.0, -0.7), ((1.0, 4.0, 9.0), 0.6)],
    ids=["isotropic", "backward", "chromatic"],
)
def test_white_furnace_scattering_sphere_loses_nothing(sigma_s, g):
    # an optically thick (radius 1, sigma_s up to 9), lossless medium behind an
    # index-matched boundary, in a uniform white environment: every pixel is 1
    sphere = SceneObject(UVSphere(1.0), medium_material(sigma_s=sigma_s, g=g))
    cam = Camera(position=(0, 0, 4), look_at=(0, 0, 0), fov_y_deg=30, width=24, height=24)
    scene = Scene(cam, [sphere], [ConstantEnvironment(1.0)],
                  RenderSettings(24, 24, spp=8, max_depth=-1, rr_depth=100_000))
    film = render(scene, progress=False)
    img = film.rgb()
    assert np.all(np.isfinite(img)) and img.min() >= 0
    inside = film.alpha() > 0.999
    assert inside.sum() > 150
    mean, err = mean_and_error(img[inside])
    assert np.all(np.abs(mean - 1.0) < 4 * err + 1e-3), (mean, err)
    assert np.all(err < 0.03)
    assert np.allclose(img[film.alpha() == 0], 1.0)


def test_absorbing_furnace_matches_albedo_bound():
    # with absorption the sphere darkens, never brightens, and the darkening grows
    # with sigma_a (single-scattering albedo 0.5 vs 0.9)
    means = []
    for sa in (1.0, 9.0):
        sphere = SceneObject(UVSphere(1.0), medium_material(sigma_a=sa, sigma_s=9.0))
        cam = Camera(position=(0, 0, 4), look_at=(0, 0, 0), fov_y_deg=30, width=16, height=16)
        scene = Scene(cam, [sphere], [ConstantEnvironment(1.0)],
                      RenderSettings(16, 16, spp=4, max_depth=-1, rr_depth=100_000))
        film = render(scene, progress=False)
        means.append(film.rgb()[film.alpha() > 0.999].mean())
    assert 0.0 < means[1] < means[0] < 1.0


def test_floor_inside_absorbing_box_is_lit_through_the_medium():
    # a diffuse floor inside an index-matched box of absorbing medium, sun straight down,
    # camera straight down: L = rho / pi E exp(-sigma 2h) (in and out), exactly
    rho, E, h = 0.6, 2.0, 0.4
    sigma = np.array([0.5, 1.5, 3.0])
    box = SceneObject(Cube(1.0), medium_material(sigma_a=tuple(sigma)),
                      make_transform(translate=(0, h / 2, 0), scale=(3.0, h, 3.0)), name="box")
    floor = SceneObject(
        Plane(size=(2.0, 2.0), origin=(-1.0, 0.01, 1.0), axis_u=(1, 0, 0), axis_v=(0, 0, -1)),
        diffuse(rho), name="floor")
    scene = Scene(down_camera(8, ortho=0.5), [box, floor], [DirectionalLight((0, -1, 0), E)],
                  RenderSettings(8, 8, spp=2, max_depth=2))
    img = render(scene, progress=False).rgb().reshape(-1, 3)
    want = rho / np.pi * E * np.exp(-sigma * 2 * (h - 0.01))
    assert np.allclose(img, want, rtol=1e-6), (img[0], want)


def test_point_light_inside_a_medium():
    # the light inside the box too: the shadow ray never leaves the medium
    rho, intensity, h = 0.5, 3.0, 0.8
    sigma = 1.2
    box = SceneObject(Cube(1.0), medium_material(sigma_a=sigma),
                      make_transform(translate=(0, h / 2, 0), scale=(4.0, h, 4.0)))
    floor = SceneObject(
        Plane(size=(3.0, 3.0), origin=(-1.5, 0.01, 1.5), axis_u=(1, 0, 0), axis_v=(0, 0, -1)),
        diffuse(rho))
    y = 0.5 - 0.01  # light above the floor
    scene = Scene(down_camera(8, ortho=0.02), [box, floor],
                  [PointLight((0, y + 0.01, 0), intensity)],
                  RenderSettings(8, 8, spp=2, max_depth=2))
    img = render(scene, progress=False).rgb()
    want = rho / np.pi * intensity / y**2 * math.exp(-sigma * y) * math.exp(-sigma * (h - 0.01))
    assert np.allclose(img, want, rtol=2e-3), (img.mean(), want)


def test_shadow_transmittance_inside_a_medium():
    # a shadow record inside a medium reaches its light with exp(-sigma d), d the whole
    # segment (offset included), whether the box's boundary lets shadow rays through
    # (a null interface: the records are traced hit by hit) or not (one occlusion query
    # times the origin's medium)
    sigma = (0.5, 1.0, 2.0)
    for mode in ("scatter_transmit", "scatter_reflect"):
        box = SceneObject(Cube(1.0), medium_material(sigma_a=sigma, mode=mode),
                          make_transform(scale=4.0))
        cam = Camera(position=(0, 0, 9), look_at=(0, 0, 0), width=4, height=4)
        scene = Scene(cam, [box], [], RenderSettings(4, 4, spp=1))
        integ = Integrator(scene, scene.build())
        assert integ.null_candidate[0] == (mode == "scatter_transmit")
        nest = integ.nesting
        records = (np.zeros((2, path.NSF)), np.zeros((2, path.NSI), dtype=np.int64),
                   np.zeros((2, nest), dtype=np.int64), np.ones((2, nest)))
        buf = integ._buffers(2)
        buf.shadows = (records, tuple(np.zeros_like(a) for a in records))
        sf, si, sso, ssior = records
        sf[:, path.S_D:path.S_D + 3] = [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0]]
        sf[:, path.S_FAR] = [0.5, 1.5]
        sf[:, path.S_TAIL] = [0.25, 0.0]
        sf[:, path.S_C:path.S_C + 3] = 1.0
        si[:, path.S_ID] = [0, 1]
        si[:, path.S_FACE] = -1  # constant emission
        si[:, path.S_HIT] = -1  # not traced yet
        si[:, path.S_NSTK] = 1
        sso[:] = 0  # inside object 0
        L = np.zeros((2, 3))
        sample = (np.zeros(2, dtype=np.int64), np.arange(2), 0, 0)  # pixel, index, seed, kind
        integ._shadows(2, buf, sample, L, np.zeros(3, dtype=np.uint64))
        assert np.allclose(L, np.exp(-np.outer([0.75, 1.5], sigma)), rtol=1e-9)


def test_thin_walled_and_open_objects_enclose_no_medium():
    # MDL ignores the volume of thin-walled materials; an open surface has no inside:
    # both leave the white environment behind them untouched
    dense = dict(sigma_a=5.0, sigma_s=5.0)
    objs = [
        SceneObject(UVSphere(0.5), medium_material(thin_walled=True, **dense),
                    make_transform(translate=(-0.6, 0, 0))),
        SceneObject(UnitSquare(), medium_material(**dense),
                    make_transform(translate=(0.1, -0.5, 0.5))),
    ]
    cam = Camera(position=(0, 0, 4), look_at=(0, 0, 0), width=24, height=16, fov_y_deg=30)
    scene = Scene(cam, objs, [ConstantEnvironment(1.0)], RenderSettings(24, 16, spp=2))
    integ = Integrator(scene, scene.build())
    assert not integ.encloses.any() and integ.media == []
    film = integ.render(progress=False)
    assert film.alpha().mean() > 0.2
    assert np.allclose(film.rgb(), 1.0, rtol=1e-12)


def test_heterogeneous_volume_is_a_clear_error():
    mat = M.material(volume=M.material_volume(absorption_coefficient=lambda s: s.position))
    scene = Scene(Camera(width=4, height=4), [SceneObject(UVSphere(1.0), mat)], [],
                  RenderSettings(4, 4, spp=1))
    with pytest.raises(ValueError, match="homogeneous"):
        Integrator(scene, scene.build())
