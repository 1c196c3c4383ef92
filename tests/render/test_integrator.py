"""Whole-image checks of the path tracer against analytic answers (furnace, point,
directional, environment and area lights), determinism, cutouts, AOVs and energy."""

from __future__ import annotations

import math

import numpy as np
import pytest

from displacement.surfaces import Plane, UnitSquare, UVSphere
from render import material as M
from render.camera import Camera
from render.integrator import Integrator, render
from render.lights import ConstantEnvironment, DirectionalLight, PointLight, SpotLight
from render.scene import RenderSettings, Scene, SceneObject, emissive_material, make_transform


def diffuse(tint=1.0, **kw):
    return M.material(surface=M.material_surface(M.df.diffuse_reflection_bsdf(tint=tint)), **kw)


def floor(size=40.0):
    """A large square in the y = 0 plane facing +y, centred on the origin."""
    return Plane(
        size=(size, size), origin=(-size / 2, 0.0, size / 2), axis_u=(1, 0, 0), axis_v=(0, 0, -1)
    )


def top_camera(res=32, height=1.0, ortho=0.2):
    """An orthographic camera looking straight down at the origin."""
    return Camera(
        position=(0.0, height, 0.0),
        look_at=(0.0, 0.0, 0.0),
        up=(0, 0, -1),
        width=res,
        height=res,
        ortho_height=ortho,
    )


def mean_and_error(img: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Per-channel image mean and its standard error (pixels are independent)."""
    px = img.reshape(-1, img.shape[-1])
    return px.mean(axis=0), px.std(axis=0, ddof=1) / math.sqrt(len(px))


def test_white_furnace_sphere_disappears():
    # a white diffuse sphere in a uniform white environment: every pixel is 1 in expectation
    cam = Camera(position=(0, 0, 4), look_at=(0, 0, 0), fov_y_deg=30, width=64, height=64)
    scene = Scene(
        cam,
        [SceneObject(UVSphere(1.0), diffuse(1.0))],
        [ConstantEnvironment(1.0)],
        RenderSettings(64, 64, spp=8, max_depth=-1, rr_depth=5),
    )
    film = render(scene, progress=False)
    img = film.rgb()
    assert np.all(np.isfinite(img)) and img.min() >= 0
    sphere = film.alpha() > 0.999
    assert sphere.sum() > 1000
    mean, err = mean_and_error(img[sphere])
    assert np.all(np.abs(mean - 1.0) < 4 * err + 1e-3), (mean, err)
    # the background is the environment itself, exactly
    assert np.allclose(img[film.alpha() == 0], 1.0)


def test_grey_furnace_matches_geometric_series():
    # tint 0.5, unlimited depth, uniform environment 1: the sphere is convex, so every
    # bounce leaves it: L = 0.5 * 1 exactly (one bounce, then the environment)
    cam = Camera(position=(0, 0, 4), look_at=(0, 0, 0), fov_y_deg=30, width=48, height=48)
    scene = Scene(
        cam,
        [SceneObject(UVSphere(1.0), diffuse(0.5))],
        [ConstantEnvironment(1.0)],
        RenderSettings(48, 48, spp=8, max_depth=-1),
    )
    film = render(scene, progress=False)
    sphere = film.alpha() > 0.999
    mean, err = mean_and_error(film.rgb()[sphere])
    assert np.all(np.abs(mean - 0.5) < 4 * err + 1e-3), (mean, err)


def test_point_light_on_diffuse_plane_is_analytic():
    # L = rho / pi * I cos(theta) / d^2 at every point of the plane (direct light only)
    rho, intensity, h = 0.6, 5.0, 1.5
    light = PointLight((0.3, h, 0.0), intensity)
    scene = Scene(
        top_camera(32, ortho=1.0),
        [SceneObject(floor(), diffuse(rho))],
        [light],
        RenderSettings(32, 32, spp=64, max_depth=2),
    )
    img = render(scene, progress=False).rgb()[..., 0]
    # the analytic value averaged over each pixel's footprint (x right, z down: up = -z)
    sub = (np.arange(32 * 16) + 0.5) / (32 * 16) - 0.5
    x, z = np.meshgrid(sub, sub)
    d2 = (x - 0.3) ** 2 + h * h + z * z
    expected = (rho / np.pi * intensity * h / d2**1.5).reshape(32, 16, 32, 16).mean(axis=(1, 3))
    # what remains is the jitter noise: the value varies < 3% across a pixel, so with
    # 64 samples its standard error is < 0.03 / sqrt(12 * 64) = 0.1%
    assert np.allclose(img, expected, rtol=0.005), np.abs(img / expected - 1).max()


def test_directional_and_spot_lights():
    rho = 0.8
    sun = DirectionalLight((0.0, -1.0, -1.0), 2.0)  # 45 degrees from the normal
    scene = Scene(
        top_camera(16),
        [SceneObject(floor(), diffuse(rho))],
        [sun],
        RenderSettings(16, 16, spp=2, max_depth=2),
    )
    img = render(scene, progress=False).rgb()
    assert np.allclose(img, rho / np.pi * 2.0 * math.cos(math.pi / 4), rtol=1e-9)
    # a spot straight down: full intensity inside the beam, nothing outside the cutoff
    spot = SpotLight((0.0, 1.0, 0.0), (0.0, -1.0, 0.0), 3.0, cutoff_angle=10.0, beam_width=5.0)
    scene = Scene(
        top_camera(32, ortho=1.0),
        [SceneObject(floor(), diffuse(rho))],
        [spot],
        RenderSettings(32, 32, spp=2, max_depth=2),
    )
    img = render(scene, progress=False).rgb()[..., 1]
    centre = img[15:17, 15:17]
    c = (np.arange(32) + 0.5) / 32 - 0.5
    x, z = np.meshgrid(c, c)
    d2 = x * x + 1.0 + z * z
    assert np.allclose(centre, (rho / np.pi * 3.0 / d2**1.5)[15:17, 15:17], rtol=0.01)
    outside = np.degrees(np.arctan(np.hypot(x, z))) > 12.0  # pixel half-diagonal: 1.3 degrees
    assert np.all(img[outside] == 0.0)


def test_constant_environment_on_a_plane_mis():
    # environment L over the upper hemisphere, diffuse rho: L_out = rho * L (direct only);
    # light sampling and BSDF sampling both contribute (MIS), so both weights are tested
    rho, le = 0.7, 1.3
    scene = Scene(
        top_camera(32),
        [SceneObject(floor(200.0), diffuse(rho))],
        [ConstantEnvironment(le)],
        RenderSettings(32, 32, spp=16, max_depth=2),
    )
    img = render(scene, progress=False).rgb()
    mean, err = mean_and_error(img)
    assert np.all(np.abs(mean - rho * le) < 4 * err), (mean, err)


def _rect_form_factor(x: float, y: float) -> float:
    """Form factor from a point to a parallel rectangle x*h by y*h with a corner above it."""
    a, b = x / math.sqrt(1 + x * x), y / math.sqrt(1 + y * y)
    return (a * math.atan(y / math.sqrt(1 + x * x)) + b * math.atan(x / math.sqrt(1 + y * y))) / (
        2 * math.pi
    )


@pytest.mark.parametrize("half_size", [0.25, 2.0])
def test_area_light_quad_irradiance(half_size):
    # a diffuse emitter of radiance le, a square of side 2a at height h facing down:
    # E = pi le * 4 F(a/h, a/h) below its centre; L_out = rho/pi * E
    rho, le, h = 0.5, 2.0, 1.0
    a = half_size
    light = SceneObject(
        Plane(size=(2 * a, 2 * a), origin=(-a, h, -a), axis_u=(1, 0, 0), axis_v=(0, 0, 1)),
        emissive_material(np.full(3, np.pi * le)),
        name="light",
    )
    cam = top_camera(16, height=0.5, ortho=0.01)  # between the light and the floor
    scene = Scene(
        cam,
        [SceneObject(floor(), diffuse(rho)), light],
        [],
        RenderSettings(16, 16, spp=64, max_depth=2),
    )
    img = render(scene, progress=False).rgb()
    expected = rho * le * 4 * _rect_form_factor(a / h, a / h)
    mean, err = mean_and_error(img)
    assert np.all(np.abs(mean - expected) < 4 * err + 1e-4 * expected), (mean, err, expected)


def test_emitter_seen_directly_and_from_behind():
    le = 3.0
    quad = SceneObject(
        Plane(size=(4, 4), origin=(-2, -2, 0)), emissive_material(np.full(3, np.pi * le))
    )
    front = Camera(position=(0, 0, 2), look_at=(0, 0, 0), width=8, height=8, fov_y_deg=20)
    back = Camera(position=(0, 0, -2), look_at=(0, 0, 0), width=8, height=8, fov_y_deg=20)
    for cam, value in ((front, le), (back, 0.0)):
        scene = Scene(cam, [quad], [], RenderSettings(8, 8, spp=2))
        img = render(scene, progress=False).rgb()
        assert np.allclose(img, value, rtol=1e-12)


def test_same_seed_same_image_any_thread_count():
    cam = Camera(position=(0, 0.5, 3), look_at=(0, 0, 0), width=40, height=30, fov_y_deg=40)
    objs = [
        SceneObject(floor(), diffuse(0.5)),
        SceneObject(UVSphere(0.5), diffuse((0.8, 0.3, 0.2)), make_transform(translate=(0, 0.5, 0))),
    ]
    scene = Scene(
        cam,
        objs,
        [PointLight((1, 2, 1), 3.0), ConstantEnvironment(0.2)],
        RenderSettings(40, 30, spp=4, seed=3),
    )
    a = render(scene, progress=False, threads=2).rgb()
    b = render(scene, progress=False, threads=1).rgb()
    c = render(scene, progress=False, threads=2, seed=4).rgb()
    assert np.array_equal(a, b)
    assert not np.array_equal(a, c)
    assert abs(a.mean() - c.mean()) < 0.05 * a.mean()


def test_cutout_opacity_alpha_and_blend():
    # a square with cutout 0.25 in front of a white environment, nothing behind: the
    # pixel is 0.25 * (square's colour) + 0.75 * environment, alpha 0.25
    op = 0.25
    mat = M.material(
        surface=M.material_surface(M.df.diffuse_reflection_bsdf(tint=0.0)),
        geometry=M.material_geometry(cutout_opacity=op),
    )
    square = SceneObject(Plane(size=(4, 4), origin=(-2, -2, 0)), mat)
    cam = Camera(position=(0, 0, 2), look_at=(0, 0, 0), width=16, height=16, fov_y_deg=20)
    scene = Scene(cam, [square], [ConstantEnvironment(1.0)], RenderSettings(16, 16, spp=64))
    film = render(scene, progress=False)
    for img, want in ((film.alpha(), op), (film.rgb()[..., 0], 1 - op)):
        mean, err = mean_and_error(img[..., None])
        # (64 stratified samples pass the cutout exactly 48 times in every pixel: err 0)
        assert abs(mean[0] - want) <= 4 * err[0] + 1e-12, (mean, err, want)
    # a varying cutout (the left half of the square removed) also stops shadow rays stochastically
    mat2 = M.material(
        surface=M.material_surface(M.df.diffuse_reflection_bsdf(tint=1.0)),
        geometry=M.material_geometry(cutout_opacity=lambda s: (s.uv[:, 0] > 0.5).astype(float)),
    )
    blocker = SceneObject(
        Plane(size=(40, 40), origin=(-20, 0.5, 20), axis_u=(1, 0, 0), axis_v=(0, 0, -1)), mat2
    )
    scene = Scene(
        top_camera(16, height=0.25, ortho=4.0),
        [SceneObject(floor(), diffuse(0.5)), blocker],
        [DirectionalLight((0, -1, 0), 1.0)],
        RenderSettings(16, 16, spp=2, max_depth=2),
    )
    img = render(scene, progress=False).rgb()[..., 0]
    assert np.allclose(img[:, :8], 0.5 / np.pi) and np.all(img[:, 8:] == 0)


def test_aovs_and_energy():
    cam = Camera(position=(0.5, 0.5, 2), look_at=(0.5, 0.5, 0), width=24, height=24, fov_y_deg=40)
    scene = Scene(
        cam,
        [SceneObject(UnitSquare(), diffuse((0.2, 0.4, 0.6)))],
        [ConstantEnvironment(1.0)],
        RenderSettings(24, 24, spp=4),
    )
    film = render(scene, progress=False, aovs=["albedo", "normal", "depth", "uv", "object_id"])
    hit = film.alpha() == 1.0
    assert hit[12, 12] and not hit[0, 0]
    assert np.allclose(film.aov("albedo")[hit], [0.2, 0.4, 0.6])
    assert np.allclose(film.aov("normal")[hit], [0, 0, 1])
    assert np.allclose(film.aov("depth")[hit], 2.0)
    uv = film.aov("uv")[12, 12]
    assert np.allclose(uv, 0.5, atol=0.05)
    assert film.aov("object_id")[12, 12] == 0 and film.aov("object_id")[0, 0] == -1
    img = film.rgb()
    assert np.all(np.isfinite(img)) and img.min() >= 0 and img.max() <= 1.0 + 1e-12
    st = film.stats
    assert st["spp"] == 4 and 0 < st["embree_time_s"] < st["time_s"] and st["rays"] > 24 * 24 * 4


def test_time_budget_and_progress():
    cam = Camera(position=(0, 0, 4), look_at=(0, 0, 0), width=16, height=16)
    scene = Scene(
        cam,
        [SceneObject(UVSphere(1.0), diffuse(0.5))],
        [ConstantEnvironment(1.0)],
        RenderSettings(16, 16, spp=1),
    )
    film = render(scene, time=0.3, progress=True)
    assert film.stats["spp"] >= 1 and film.stats["time_s"] < 5.0


def test_displaced_object_is_diced_and_rendered():
    # a raised unit square (constant displacement along the normal): it moves by 0.25
    mat = diffuse(0.5, geometry=M.material_geometry(displacement=(0.0, 0.0, 0.25)))
    cam = Camera(position=(0.5, 0.5, 2), look_at=(0.5, 0.5, 0), width=16, height=16, fov_y_deg=30)
    scene = Scene(
        cam,
        [SceneObject(UnitSquare(), mat)],
        [ConstantEnvironment(1.0)],
        RenderSettings(16, 16, spp=1),
    )
    geo = scene.build()
    assert geo.stats[0]["diced"] and np.allclose(geo.vertices[:, 2], 0.25)
    film = render(scene, progress=False, aovs=["depth"])
    assert np.allclose(film.aov("depth")[8, 8], 1.75)


def test_integrator_rejects_nothing_silently_on_empty_light_set():
    # no lights at all: a black image, not an error, and no NaN
    cam = Camera(position=(0, 0, 4), look_at=(0, 0, 0), width=8, height=8)
    scene = Scene(cam, [SceneObject(UVSphere(1.0), diffuse(0.5))], [], RenderSettings(8, 8, spp=2))
    integ = Integrator(scene, scene.build())
    film = integ.render(progress=False)
    assert np.all(film.rgb() == 0.0) and film.alpha().max() == 1.0


def test_world_space_is_the_objects_transform():
    # Figure 9.8: space_as_color in world space differs from object space by the object's
    # transform.  A sphere moved by t = (0.65, 0.5, 0): frac(4 (p + t)) = frac(4 p + (2.6,
    # 2, 0)), so red shifts by 0.6 (mod 1) and green and blue stay (mod 1).
    from render.materials.chapter9 import space_as_color

    cam = Camera(position=(0.65, 0.5, 4.0), look_at=(0.65, 0.5, 0.0), width=24, height=24,
                 fov_y_deg=16)

    def albedo(mode, transform):
        scene = Scene(cam, [SceneObject(UVSphere(0.5), space_as_color(mode, 4.0), transform)],
                      [ConstantEnvironment(1.0)], RenderSettings(24, 24, spp=1, max_depth=1))
        film = render(scene, progress=False, aovs=["albedo"])
        return film.aov("albedo")[film.alpha() > 0]

    moved = make_transform(translate=(0.65, 0.5, 0.0))
    obj, world = albedo("object", moved), albedo("world", moved)
    assert len(obj) > 200
    gap = np.abs(world - np.mod(obj + [0.6, 0.0, 0.0], 1.0))
    assert np.all(np.minimum(gap, 1.0 - gap) < 1e-9)  # on the circle: 0.9999... ~ 0
    assert np.abs(world[:, 0] - obj[:, 0]).max() > 0.5
