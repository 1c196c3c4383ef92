"""Whole-image checks against answers the renderer did not produce (issue 17).

Each scene has a closed form or an exact twin: power-mode emitters (a sphere and a quad of
known power), spot emitters (``df::spot_edf``'s lobe and the spot light's smoothstep
profile, integrated here over the emitter), layered materials in the white furnace, a
constant texture against the constant, a zero bump against no bump, and a displaced
square's depth against its height field.  Tolerances are four standard errors (pixels
are independent samples) plus, where named, a deterministic bias bound.  Where Mitsuba 3
has an equivalent (a power-mode quad, weighted layers of diffuse lobes, a hard-edged spot
light), ``test_mitsuba_twins.py`` renders it beside ours.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from displacement.surfaces import Plane, UnitSquare, UVSphere
from displacement.textures import read_texture, write_texture
from render import material as M
from render.camera import Camera
from render.integrator import render
from render.library.functions import (
    modify_normal_from_texture,
    state_normal,
    texture_2d_lookup,
)
from render.lights import ConstantEnvironment, SpotLight
from render.scene import RenderSettings, Scene, SceneObject, make_transform

D = M.df


def diffuse(tint=1.0, **kw):
    return M.material(surface=M.material_surface(D.diffuse_reflection_bsdf(tint=tint)), **kw)


def emitter(edf, intensity, mode="intensity_radiant_exitance"):
    return M.material(surface=M.material_surface(
        scattering=None,
        emission=M.material_emission(emission=edf, intensity=(intensity,) * 3, mode=mode)))


def floor(size=40.0):
    """A square in the y = 0 plane facing +y, centred on the origin."""
    return Plane(size=(size, size), origin=(-size / 2, 0.0, size / 2), axis_u=(1, 0, 0),
                 axis_v=(0, 0, -1))


def down_quad(half, height):
    """A square of side 2 half at ``height``, centred over the origin, facing -y."""
    return Plane(size=(2 * half, 2 * half), origin=(-half, height, -half), axis_u=(1, 0, 0),
                 axis_v=(0, 0, 1))


def top_camera(res, height, ortho):
    """Orthographic, looking straight down at the origin: pixel (row, col) sees
    x = (col + 0.5) / res - 0.5 and z = (row + 0.5) / res - 0.5 (times ortho)."""
    return Camera(position=(0.0, height, 0.0), look_at=(0.0, 0.0, 0.0), up=(0, 0, -1),
                  width=res, height=res, ortho_height=ortho)


def pixel_grid(res, ortho, sub=4):
    """x, z of ``sub`` x ``sub`` points in every pixel of :func:`top_camera` (res*sub)^2."""
    c = ((np.arange(res * sub) + 0.5) / (res * sub) - 0.5) * ortho
    return np.meshgrid(c, c)


def pixel_mean(values, res, sub=4):
    return values.reshape(res, sub, res, sub).mean(axis=(1, 3))


def mean_and_error(img):
    px = img.reshape(-1, img.shape[-1])
    return px.mean(axis=0), px.std(axis=0, ddof=1) / math.sqrt(len(px))


# ---------------------------------------------------------------- power-mode emitters
def test_power_mode_sphere_is_a_point_source_of_power_over_4pi():
    """A diffusely emitting sphere of total power P (``intensity_power``) irradiates a
    plane facing it, wherever the sphere is above the plane's horizon, exactly as a point
    source of intensity P / (4 pi) at its centre: E = P cos(theta) / (4 pi d^2)."""
    power, rho, h, r = 20.0, 0.5, 1.5, 0.3
    sphere = SceneObject(UVSphere(r), emitter(D.diffuse_edf(), power, "intensity_power"),
                         make_transform(translate=(0.0, h, 0.0)), name="light")
    res, ortho = 12, 1.6
    scene = Scene(top_camera(res, 0.5, ortho), [SceneObject(floor(), diffuse(rho)), sphere], [],
                  RenderSettings(res, res, spp=32, max_depth=2, seed=1))
    img = render(scene, progress=False).rgb()
    x, z = pixel_grid(res, ortho)
    d2 = x * x + z * z + h * h
    expected = pixel_mean(rho / math.pi * power * h / (4 * math.pi * d2**1.5), res)
    ratio = img / expected[..., None]
    mean, err = mean_and_error(ratio)
    # the sphere is a 128 x 64 polyhedron of the same power: its far field differs from
    # the sphere's by far less than 0.2 % (checked: the ratio's mean is within 4 errors)
    assert np.all(np.abs(mean - 1.0) < 4 * err + 2e-3), (mean, err)
    assert err.max() < 0.05  # measured 0.024: a halved power would be over 10 errors away


def test_power_mode_quad_irradiance():
    """A square emitter of side 2a and power P: radiance P / (pi A); below its centre at
    distance h, E = (P / A) * 4 F(a/h, a/h) (the rectangle form factor)."""
    power, rho, h, a = 6.0, 0.5, 1.0, 0.5
    light = SceneObject(down_quad(a, h), emitter(D.diffuse_edf(), power, "intensity_power"),
                        name="light")
    scene = Scene(top_camera(16, 0.5, 0.01), [SceneObject(floor(), diffuse(rho)), light], [],
                  RenderSettings(16, 16, spp=16, max_depth=2, seed=2))
    img = render(scene, progress=False).rgb()
    x = a / h
    f = 2 * (x / math.sqrt(1 + x * x) * math.atan(x / math.sqrt(1 + x * x))) / (2 * math.pi)
    expected = rho / math.pi * power / (4 * a * a) * 4 * f
    mean, err = mean_and_error(img)
    assert np.all(np.abs(mean - expected) < 4 * err + 1e-4 * expected), (mean, err, expected)


# ---------------------------------------------------------------------- spot emitters
def _spot_edf_eval(cos_axis, exponent, spread):
    """df::spot_edf's radiance per unit exitance (the MDL spec / libbsdf lobe)."""
    s, k = math.cos(spread / 2), max(exponent, 0.0)
    t = np.clip((cos_axis - s) / (1 - s), 0.0, None)
    norm = (k + 1) * (k + 2) / (2 * math.pi * (1 - s) * (k + 1 + s))
    return np.where(cos_axis > s, t**k * norm, 0.0)


def assert_rings_match(img, expected, res):
    """Compare an image with its expected values ring by ring about the image centre
    (one pixel wide): each ring's mean difference within 4 of its standard errors (the
    pixels' jitter and light-sampling noise are independent), plus 0.2 % of the peak for
    the expected values' own pixel quadrature."""
    yy, xx = np.indices(img.shape)
    ring = np.hypot(xx + 0.5 - res / 2, yy + 0.5 - res / 2).astype(int)
    checked = 0
    for k in range(ring.max() + 1):
        d = (img - expected)[ring == k]
        if len(d) < 8:
            continue
        se = d.std(ddof=1) / math.sqrt(len(d))
        assert abs(d.mean()) < 4 * se + 2e-3 * expected.max(), (k, d.mean(), se)
        checked += 1
    assert checked >= res // 3


@pytest.mark.parametrize(("exponent", "spread_deg"), [(0.0, 60.0), (8.0, 90.0)])
def test_spot_edf_profile_on_a_plane(exponent, spread_deg):
    """A small square emitting with ``df::spot_edf`` (axis: its normal, straight down):
    the irradiance of the floor is the lobe integrated over the emitter, here by a
    midpoint rule (8 x 8 points, far finer than the lobe varies across 4 cm at 1 m)."""
    I0, rho, h, a = 40.0, 0.8, 1.0, 0.02
    spread = math.radians(spread_deg)
    edf = D.spot_edf(exponent=exponent, spread=spread, global_distribution=False)
    light = SceneObject(down_quad(a, h), emitter(edf, I0), name="spot")
    res, ortho = 32, 2 * h * math.tan(spread / 2) * 1.25
    scene = Scene(top_camera(res, 0.5, ortho), [SceneObject(floor(), diffuse(rho)), light], [],
                  RenderSettings(res, res, spp=16, max_depth=2, seed=3))
    img = render(scene, progress=False).rgb()[..., 0]
    x, z = pixel_grid(res, ortho, sub=8)
    q = ((np.arange(8) + 0.5) / 8 - 0.5) * 2 * a
    e = np.zeros_like(x)
    for qx in q:
        for qz in q:
            dx, dz = x - qx, z - qz
            d2 = dx * dx + dz * dz + h * h
            cos = h / np.sqrt(d2)  # at the emitter (to its axis) and at the floor alike
            e += I0 * _spot_edf_eval(cos, exponent, spread) * cos * cos / d2
    expected = pixel_mean(rho / math.pi * e * (2 * a) ** 2 / 64, res, sub=8)
    assert_rings_match(img, expected, res)
    # nothing beyond the cone (widened by the emitter's angular size)
    outside = pixel_mean((h / np.sqrt(x * x + z * z + h * h) <
                          math.cos(spread / 2 + 2 * a / h)).astype(float), res, sub=8) == 1.0
    assert outside.sum() > 20 and np.all(img[outside] == 0.0)


def test_spot_light_smoothstep_profile():
    """The spot light's intensity I smoothstep(cos cutoff, cos beam, cos theta) (pbrt),
    seen on a diffuse floor: E = I(theta) cos(theta)^3 / h^2."""
    I0, rho, h, cutoff, beam = 3.0, 0.8, 1.0, 30.0, 10.0
    spot = SpotLight((0.0, h, 0.0), (0.0, -1.0, 0.0), I0, cutoff_angle=cutoff, beam_width=beam)
    res, ortho = 32, 1.4
    scene = Scene(top_camera(res, 0.5, ortho), [SceneObject(floor(), diffuse(rho))], [spot],
                  RenderSettings(res, res, spp=16, max_depth=2, seed=4))
    img = render(scene, progress=False).rgb()[..., 1]
    x, z = pixel_grid(res, ortho, sub=8)
    cos = h / np.sqrt(x * x + z * z + h * h)
    c0, c1 = math.cos(math.radians(cutoff)), math.cos(math.radians(beam))
    t = np.clip((cos - c0) / (c1 - c0), 0.0, 1.0)
    expected = pixel_mean(rho / math.pi * I0 * t * t * (3 - 2 * t) * cos**3 / h**2, res, sub=8)
    assert_rings_match(img, expected, res)
    # inside the beam the light is full, and a point light is exact: only pixel jitter
    beam_px = pixel_mean((cos > c1).astype(float), res, sub=8) == 1.0
    np.testing.assert_allclose(img[beam_px], expected[beam_px], rtol=0.01)


# ------------------------------------------------------------ layered white furnace
LOSSLESS = {
    "weighted_layer": lambda: D.weighted_layer(weight=0.35, layer=D.diffuse_reflection_bsdf(),
                                               base=D.diffuse_reflection_bsdf()),
    "nested_weighted_layer": lambda: D.weighted_layer(
        weight=0.6, layer=D.diffuse_reflection_bsdf(),
        base=D.weighted_layer(weight=0.5, layer=D.diffuse_reflection_bsdf(),
                              base=D.diffuse_reflection_bsdf())),
}


@pytest.mark.parametrize("name", sorted(LOSSLESS))
def test_lossless_layers_vanish_in_the_white_furnace(name):
    """Layers of white, lossless dfs reflect everything: in a uniform white environment a
    convex object of such a material has radiance 1 everywhere (it disappears).
    (weighted_layer: eval = w layer + (1 - w) base, no directional loss; fresnel_layer
    loses energy by design, see reference/mdl-distribution-functions.md §3.2.)"""
    mat = M.material(surface=M.material_surface(LOSSLESS[name]()))
    cam = Camera(position=(0, 0, 4), look_at=(0, 0, 0), fov_y_deg=30, width=40, height=40)
    scene = Scene(cam, [SceneObject(UVSphere(1.0), mat)], [ConstantEnvironment(1.0)],
                  RenderSettings(40, 40, spp=8, max_depth=-1, rr_depth=5, seed=5))
    film = render(scene, progress=False)
    sphere = film.alpha() > 0.999
    assert sphere.sum() > 400
    mean, err = mean_and_error(film.rgb()[sphere])
    assert np.all(np.abs(mean - 1.0) < 4 * err + 1e-3), (mean, err)


# --------------------------------------------------------- textures and bumps, exactly
def _stage(material, res=24, spp=4, seed=6):
    cam = Camera(position=(0.5, 1.2, 2.0), look_at=(0.5, 0.3, 0.0), fov_y_deg=35,
                 width=res, height=res)
    obj = SceneObject(UnitSquare(), material, make_transform(rotate=(-60.0, 0.0, 0.0)))
    return Scene(cam, [obj, SceneObject(floor(), diffuse(0.4))],
                 [SpotLight((0.5, 2.0, 1.0), (0.0, -1.0, -0.3), 4.0, cutoff_angle=50.0),
                  ConstantEnvironment(0.3)],
                 RenderSettings(res, res, spp=spp, max_depth=3, seed=seed))


def test_constant_texture_equals_the_constant(tmp_path):
    """A texture file of one colour (float EXR: exact) as the tint gives the image of the
    same colour given as a constant: the same samples, so the same pixels."""
    colour = (0.75, 0.5, 0.25)
    write_texture(tmp_path / "flat.exr", np.broadcast_to(colour, (8, 8, 3)).astype(np.float32),
                  bits="float")
    tex = read_texture(tmp_path / "flat.exr")
    textured = diffuse(texture_2d_lookup(tex))
    constant = diffuse(colour)
    a = render(_stage(textured), progress=False).rgb()
    b = render(_stage(constant), progress=False).rgb()
    assert a.max() > 0.05
    np.testing.assert_allclose(a, b, rtol=1e-12, atol=1e-15)


def test_zero_bump_equals_no_bump(tmp_path):
    """MDL's default ``normal: state::normal()`` given explicitly, and a height map that is
    flat everywhere (Listing 13.11's normal from a constant texture), are zero bumps: the
    image equals the material's without a normal, bit for bit (same seed): rows equal to
    the state's normal skip ``clamp_to_horizon``'s re-normalization, and an unperturbed
    normal is not sent through the object's transform and back."""
    plain = render(_stage(diffuse(0.7)), progress=False).rgb()
    assert plain.max() > 0.05
    write_texture(tmp_path / "flat_height.exr", np.full((8, 8, 1), 0.5, np.float32),
                  bits="float")
    height = read_texture(tmp_path / "flat_height.exr")
    for normal in (state_normal(), modify_normal_from_texture(height)):
        bumped = diffuse(0.7, geometry=M.material_geometry(normal=normal))
        assert np.array_equal(render(_stage(bumped), progress=False).rgb(), plain)


# --------------------------------------------------------------- displaced surfaces
def test_displaced_square_depth_is_the_height_field():
    """A unit square displaced along its normal by h(u, v) = A sin(2 pi (2u + v)), seen
    straight down by an orthographic camera: the depth AOV is (camera height - h) at the
    pixel's position, with h evaluated here (u = x, v = y on the unit square)."""
    amp = 0.05

    def height(s):
        return amp * np.sin(2 * np.pi * (2 * s.uv[:, 0] + s.uv[:, 1]))

    mat = diffuse(0.5, geometry=M.material_geometry(
        displacement=lambda s: s.normal * height(s)[:, None]))
    res, cam_z = 32, 2.0
    cam = Camera(position=(0.5, 0.5, cam_z), look_at=(0.5, 0.5, 0.0), up=(0, 1, 0),
                 width=res, height=res, ortho_height=0.8)
    scene = Scene(cam, [SceneObject(UnitSquare(), mat)], [ConstantEnvironment(1.0)],
                  RenderSettings(res, res, spp=64, seed=7, dicing_tolerance=0.1))
    film = render(scene, progress=False, aovs=["depth"])
    depth = film.aov("depth")[..., 0]
    sub = 8
    c = ((np.arange(res * sub) + 0.5) / (res * sub) - 0.5) * 0.8 + 0.5
    x, y = np.meshgrid(c, c[::-1])  # image rows run down, y up
    h = (amp * np.sin(2 * np.pi * (2 * x + y))).reshape(res, sub, res, sub).mean(axis=(1, 3))
    seen = cam_z - depth
    # per pixel: the dicer's 0.1 px tolerance (0.1 * 0.8 / 32 = 0.0025 units, its bound
    # on the mesh's distance to the surface) plus 4 sigma of 64 jittered samples against
    # the pixel mean (h varies by at most 2 pi * 2.2 * amp * 0.025 = 0.017 across a
    # pixel: sigma = 0.017 / sqrt(12 * 64) = 0.0006)
    np.testing.assert_allclose(seen, h, atol=0.0025 + 4 * 0.017 / math.sqrt(12 * 64))
    # the amplitude, by least squares: chords cut inside the crests, so it is low by at
    # most the dicing tolerance over the amplitude (0.0025 / 0.05 = 5 %; measured 1.3 %)
    slope = float((seen * h).sum() / (h * h).sum())
    assert 0.95 <= slope <= 1.005, slope
