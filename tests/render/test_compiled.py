"""The compiled path (render.compiled) against the general integrator: which scenes take
it, and that it renders the same image from the same seed."""

from __future__ import annotations

import numpy as np
import pytest

from displacement.surfaces import Plane, UVSphere
from render import material as M
from render.camera import Camera
from render.compiled import compiled_reason
from render.integrator import Integrator, render
from render.lights import (
    ConstantEnvironment,
    DirectionalLight,
    LatLongEnvironment,
    PointLight,
    SpotLight,
)
from render.scene import RenderSettings, Scene, SceneObject, emissive_material, make_transform
from render.sky import SunAndSky

D = M.df


def surface(node, **kw):
    return M.material(surface=M.material_surface(node), **kw)


def stage(bsdf, *, env=0.15, lights=((-1.5, 2.5, 1.5, 6.0), (1.8, 2.2, 1.2, 4.0)), power=False,
          size=(48, 36), spp=4, max_depth=8, rr_depth=3, extra=()):
    """A floor, a sphere with ``bsdf`` and square area lights facing down."""
    floor = Plane(size=(6.0, 6.0), origin=(-3.0, 0.0, 3.0), axis_u=(1, 0, 0), axis_v=(0, 0, -1))
    objects = [
        SceneObject(floor, surface(D.diffuse_reflection_bsdf(tint=0.5)), name="floor"),
        SceneObject(UVSphere(0.5), surface(bsdf), make_transform(translate=(0.0, 0.5, 0.0)),
                    name="sphere", resolution=(64, 32)),
    ]
    for i, (x, y, z, radiance) in enumerate(lights):
        quad = Plane(size=(0.8, 0.8), origin=(x - 0.4, y, z - 0.4), axis_u=(1, 0, 0),
                     axis_v=(0, 0, 1))  # normal -y: lights the floor
        mat = emissive_material(np.full(3, radiance))
        if power:  # the same radiance given as the power of the 0.8 x 0.8 quad
            mat = M.material(surface=M.material_surface(emission=M.material_emission(
                D.diffuse_edf(), intensity=(0.64 * radiance,) * 3, mode="intensity_power")))
        objects.append(SceneObject(quad, mat, name=f"light{i}"))
    objects += list(extra)
    w, h = size
    cam = Camera(position=(0.0, 1.2, 3.5), look_at=(0.0, 0.4, 0.0), fov_y_deg=35, width=w,
                 height=h)
    envs = [ConstantEnvironment(env)] if env else []
    return Scene(cam, objects, envs, RenderSettings(w, h, spp=spp, max_depth=max_depth,
                                                     rr_depth=rr_depth, seed=7))


def both(scene, **kw):
    """(general film, compiled film) of the same scene and seed."""
    geo = scene.build()
    general = Integrator(scene, geo, path="general").render(progress=False, **kw)
    compiled = Integrator(scene, geo, path="compiled").render(progress=False, **kw)
    assert general.stats["path"] == "general" and compiled.stats["path"] == "compiled"
    return general, compiled


def assert_same_image(general, compiled):
    """Same pixels up to rounding: the kernels follow the general path's arithmetic, so
    paths only part where a last-bit difference flips a comparison."""
    a, b = general.rgb(), compiled.rgb()
    assert np.all(np.isfinite(b)) and b.min() >= 0.0
    assert np.array_equal(general.alpha(), compiled.alpha())
    close = np.isclose(a, b, rtol=1e-9, atol=1e-12).all(axis=-1)
    assert close.mean() >= 0.999, f"{(~close).sum()} of {close.size} pixels differ"
    assert abs(a.mean() - b.mean()) <= 1e-4 * a.mean()


CASES = {
    "lambert": D.diffuse_reflection_bsdf(tint=(0.6, 0.4, 0.1)),
    "oren-nayar+multiscatter": D.diffuse_reflection_bsdf(tint=0.8, roughness=1.0,
                                                         multiscatter_tint=1.0),
    "glossy": D.simple_glossy_bsdf(tint=(0.6, 0.4, 0.0), roughness_u=0.3),
    "glossy-anisotropic": D.simple_glossy_bsdf(roughness_u=0.05, roughness_v=0.6),
    "glossy-roughness-0": D.simple_glossy_bsdf(roughness_u=0.0),
    "glossy-roughness-1": D.simple_glossy_bsdf(roughness_u=1.0, tint=0.9),
    "mirror": D.specular_bsdf(tint=0.9),
    "black": D.diffuse_reflection_bsdf(tint=0.0),
}


@pytest.mark.parametrize("name", sorted(CASES))
def test_same_image_as_the_general_path(name):
    scene = stage(CASES[name])
    assert compiled_reason(Integrator(scene, scene.build())) is None
    assert_same_image(*both(scene))


@pytest.mark.parametrize(
    "light",
    [
        PointLight(position=(0.3, 1.8, 0.9), intensity=2.0),
        SpotLight(position=(-0.5, 2.0, 1.0), direction=(0.3, -1.0, -0.5), intensity=4.0,
                  cutoff_angle=25.0, beam_width=15.0),
        SpotLight(position=(0.5, 2.0, 1.0), direction=(0.0, -1.0, 0.0), intensity=4.0,
                  cutoff_angle=20.0, beam_width=20.0),  # hard edge: no falloff band
        DirectionalLight(direction=(0.4, -1.0, -0.3), irradiance=1.5),
    ],
    ids=["point", "spot", "spot-hard-edge", "directional"],
)
def test_same_image_with_delta_lights(light):
    # delta lights take no MIS (their pdf is the selection probability alone)
    scene = stage(D.simple_glossy_bsdf(roughness_u=0.25, tint=(0.7, 0.5, 0.2)))
    scene.lights.append(light)
    assert_same_image(*both(scene))
    alone = stage(D.diffuse_reflection_bsdf(tint=0.8), env=0.0, lights=())
    alone.lights.append(light)
    general, compiled = both(alone)
    assert_same_image(general, compiled)
    assert compiled.rgb().max() > 0.0


def sky_image(h=16, w=32):
    """A latitude-longitude map: a bright warm spot above a dim blue gradient, one black
    texel row at the bottom (zero-probability texels)."""
    v = (np.arange(h)[:, None] + 0.5) / h
    u = (np.arange(w)[None, :] + 0.5) / w
    img = np.stack([0.2 + 0 * u + 0.1 * v, 0.3 + 0.1 * v + 0 * u, 0.6 - 0.3 * v + 0 * u], -1)
    img[2:4, 5:8] = (40.0, 30.0, 20.0)
    img[-1] = 0.0
    return img


@pytest.mark.parametrize("rotation", [0.0, 117.0])
def test_same_image_with_an_environment_map(rotation):
    # importance-sampled texels, MIS on escaped rays, a rotated map
    scene = stage(D.simple_glossy_bsdf(roughness_u=0.2, tint=(0.8, 0.6, 0.3)), env=0.0)
    scene.lights.append(LatLongEnvironment(sky_image(), scale=1.5, rotation=rotation))
    assert_same_image(*both(scene))
    alone = stage(D.diffuse_reflection_bsdf(tint=0.7), env=0.0, lights=())
    alone.lights.append(LatLongEnvironment(sky_image(), rotation=rotation))
    general, compiled = both(alone)
    assert_same_image(general, compiled)
    sky = compiled.rgb()[compiled.alpha() == 0]  # the map itself, behind the stage
    assert len(sky) > 0 and sky.min() > 0.0


@pytest.mark.parametrize(
    "kw",
    [
        dict(max_depth=1),  # emission and the environment only
        dict(max_depth=2, rr_depth=1),  # roulette from the first bounce
        dict(env=0.0),  # no environment light
        dict(lights=()),  # the environment alone
        dict(power=True),  # intensity_power emitters
        dict(env=0.0, lights=()),  # no light at all: black
    ],
    ids=["depth-1", "roulette", "no-env", "env-only", "power", "dark"],
)
def test_same_image_at_the_edges(kw):
    general, compiled = both(stage(D.diffuse_reflection_bsdf(tint=0.7), **kw))
    assert_same_image(general, compiled)
    if kw.get("env") == 0.0 and kw.get("lights") == ():
        assert not compiled.rgb().any()


def test_same_image_with_two_threads_and_many_passes():
    scene = stage(D.simple_glossy_bsdf(roughness_u=0.2), size=(32, 24))
    geo = scene.build()
    one = Integrator(scene, geo, path="compiled").render(spp=40, threads=1, progress=False)
    two = Integrator(scene, geo, path="compiled").render(spp=40, threads=2, progress=False)
    assert np.array_equal(one.rgb(), two.rgb())


def test_white_furnace():
    # a white Lambertian sphere in a white environment disappears (every pixel is 1)
    cam = Camera(position=(0, 0, 4), look_at=(0, 0, 0), fov_y_deg=30, width=48, height=48)
    scene = Scene(cam, [SceneObject(UVSphere(1.0), surface(D.diffuse_reflection_bsdf()))],
                  [ConstantEnvironment(1.0)],
                  RenderSettings(48, 48, spp=16, max_depth=-1, rr_depth=5))
    film = render(scene, progress=False, path="compiled")
    px = film.rgb()[film.alpha() > 0.999].reshape(-1, 3)
    mean, err = px.mean(axis=0), px.std(axis=0, ddof=1) / np.sqrt(len(px))
    assert len(px) > 500 and np.all(np.abs(mean - 1.0) < 4 * err + 1e-3), (mean, err)


def tinted_by_uv(state):
    return np.repeat(state.uv[:, :1], 3, axis=1)


def rough_by_position(state):
    return 0.05 + 0.5 * np.abs(np.sin(8.0 * state.position[:, 0]))


def bumped(state):
    n = state.normal + 0.3 * np.sin(20.0 * state.position[:, [1, 2, 0]])
    return n / np.linalg.norm(n, axis=1, keepdims=True)


@pytest.mark.parametrize(
    "material",
    [
        surface(D.diffuse_reflection_bsdf(tint=tinted_by_uv, roughness=0.5)),
        surface(D.simple_glossy_bsdf(roughness_u=rough_by_position, tint=tinted_by_uv)),
        surface(D.diffuse_reflection_bsdf(tint=0.7), geometry=M.material_geometry(normal=bumped)),
        surface(D.specular_bsdf(tint=tinted_by_uv),
                geometry=M.material_geometry(normal=(0.0, 0.0, 1.0))),
    ],
    ids=["textured-diffuse", "textured-glossy", "bumped", "constant-normal-mirror"],
)
def test_same_image_with_arguments_that_vary_over_the_surface(material):
    # such objects are shaded per lane by material.shade (numpy); the kernels take the rows
    scene = stage(D.diffuse_reflection_bsdf())
    scene.objects[1] = SceneObject(UVSphere(0.5), material, make_transform(translate=(0, 0.5, 0)),
                                   name="sphere", resolution=(64, 32))
    integ = Integrator(scene, scene.build())
    assert integ.general_reason is None and integ.compiled.varying.tolist() == [
        False, True, False, False]
    assert_same_image(*both(scene))


def test_auto_takes_the_compiled_path_only_where_it_can():
    scene = stage(D.diffuse_reflection_bsdf(tint=0.5), size=(16, 12), spp=1)
    assert render(scene, progress=False).stats["path"] == "compiled"
    scene.lights[0] = SunAndSky((0.3, 0.8, 0.2))
    film = render(scene, progress=False)
    assert film.stats["path"] == "general"
    assert "SunAndSky" in film.stats["general_reason"]


@pytest.mark.parametrize("bsdf", [CASES["glossy-anisotropic"], CASES["oren-nayar+multiscatter"]],
                         ids=["glossy", "diffuse"])
def test_same_aovs_as_the_general_path(bsdf):
    # the first hits are shaded by the general path's numpy code: every AOV is equal
    aovs = ["albedo", "normal", "depth", "uv", "object_id"]
    scene = stage(bsdf)
    geo = scene.build()
    general = Integrator(scene, geo, aovs, path="general").render(progress=False)
    compiled = Integrator(scene, geo, aovs, path="compiled").render(progress=False)
    assert_same_image(general, compiled)
    for name in aovs:
        assert np.array_equal(general.aov(name), compiled.aov(name)), name
    assert set(np.unique(compiled.aov("object_id"))) == {-1, 0, 1}  # sky, floor, sphere
    assert compiled.aov("albedo").max() > 0.1


@pytest.mark.parametrize("bsdf", [
    D.simple_glossy_bsdf(roughness_u=0.2, mode="scatter_reflect_transmit"),
    D.diffuse_transmission_bsdf(tint=0.7),
    D.weighted_layer(weight=0.5, layer=D.specular_bsdf(), base=D.diffuse_reflection_bsdf()),
    D.fresnel_layer(ior=1.5, layer=D.simple_glossy_bsdf(roughness_u=0.1),
                    base=D.normalized_mix([D.bsdf_component(0.6, D.diffuse_reflection_bsdf()),
                                           D.bsdf_component(0.4, D.tint(
                                               (1.0, 0.5, 0.2), D.specular_bsdf()))])),
], ids=["glossy-transmit", "translucent", "layer", "coat-over-mix"])
def test_every_bsdf_takes_the_compiled_path(bsdf):
    # a df tree is a program that both paths run with the same kernels: the same image
    scene = stage(bsdf, size=(12, 9), spp=2)
    scene.objects[1] = SceneObject(UVSphere(0.5), surface(bsdf), name="sphere",
                                   resolution=(16, 8))
    geo = scene.build()
    assert compiled_reason(Integrator(scene, geo)) is None
    general = Integrator(scene, geo, path="general").render(progress=False)
    compiled = Integrator(scene, geo, path="compiled").render(progress=False)
    assert_same_image(general, compiled)
    assert compiled.rgb().max() > 0.0


@pytest.mark.parametrize(
    "change, reason",
    [
        (dict(geometry=M.material_geometry(cutout_opacity=0.5)), "cutout"),
        (dict(sky=True), "SunAndSky"),
    ],
    ids=["cutout", "sky"],
)
def test_the_general_path_keeps_what_the_kernels_do_not_model(change, reason):
    bsdf = change.get("bsdf", D.diffuse_reflection_bsdf())
    mat = surface(bsdf, **({"geometry": change["geometry"]} if "geometry" in change else {}))
    scene = stage(bsdf, size=(8, 6), spp=1)
    scene.objects[1] = SceneObject(UVSphere(0.5), mat, name="sphere", resolution=(16, 8))
    if change.get("sky"):
        scene.lights[0] = SunAndSky((0.3, 0.8, 0.2))
    why = compiled_reason(Integrator(scene, scene.build()))
    assert why is not None and reason.lower() in why.lower(), why
    with pytest.raises(ValueError, match="compiled"):
        Integrator(scene, scene.build(), path="compiled")
    assert render(scene, progress=False).stats["path"] == "general"


def test_aovs_come_from_the_camera_rays_in_a_closed_room():
    # inside a white, glowing sphere every path goes on after its first hit, so the next
    # segment has as many lanes as the camera had: the AOVs are still the first hits'
    glow = M.material(surface=M.material_surface(
        D.diffuse_reflection_bsdf(tint=1.0),
        M.material_emission(D.diffuse_edf(), intensity=(1.0, 1.0, 1.0))))
    room = SceneObject(UVSphere(2.0), glow, name="room", resolution=(32, 16))
    cam = Camera(position=(0.3, 0.2, 0.5), look_at=(0.0, 0.0, -1.0), width=12, height=10,
                 fov_y_deg=60)
    scene = Scene(cam, [room], [], RenderSettings(12, 10, spp=2, max_depth=4, rr_depth=10))
    geo = scene.build()
    aovs = ["depth", "uv", "normal"]
    general = Integrator(scene, geo, aovs, path="general").render(progress=False)
    compiled = Integrator(scene, geo, aovs, path="compiled").render(progress=False)
    assert_same_image(general, compiled)
    for name in aovs:
        assert np.array_equal(general.aov(name), compiled.aov(name)), name
    assert compiled.aov("depth").min() > 0.5  # the wall, seen from inside


@pytest.mark.parametrize("material", [
    surface(D.simple_glossy_bsdf(roughness_u=0.05, roughness_v=0.5, tint=0.8)),
    surface(D.diffuse_reflection_bsdf(tint=tinted_by_uv),
            geometry=M.material_geometry(normal=bumped)),
], ids=["anisotropic", "textured-bumped"])
def test_same_image_with_a_rotated_stretched_object(material):
    # an ellipsoid (scale 0.6, 1.2, 0.9, turned about two axes): object and world frames
    # differ, so normals and tangents go through the object's transform and back
    scene = stage(D.diffuse_reflection_bsdf())
    scene.objects[1] = SceneObject(
        UVSphere(0.5), material,
        make_transform(translate=(0, 0.6, 0), rotate=(30, 50, 0), scale=(0.6, 1.2, 0.9)),
        name="ellipsoid", resolution=(64, 32))
    assert_same_image(*both(scene))
