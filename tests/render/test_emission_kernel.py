"""Constant edfs in the path kernel: an emitter whose edf and intensity are constant
(spot_edf, local or global, edf tint and directional_factor, edf mixes, thin-walled
backfaces, power mode) is evaluated by the interpreter's edf entry points at hits and at
light samples, and never goes back to numpy; it renders as the numpy shading of the same
material (Integrator._emitted), with the same samples."""

from __future__ import annotations

import math

import numpy as np
import pytest

from displacement.surfaces import Plane, UVSphere
from render import material as M
from render.camera import Camera
from render.integrator import Integrator
from render.scene import RenderSettings, Scene, SceneObject, load_scene, make_transform

RES = 32
df = M.df


def _varying(intensity):
    """The same intensity as a function of the state: the object is shaded by numpy."""
    c = np.broadcast_to(np.asarray(intensity, dtype=np.float64), (3,))
    return lambda state: np.tile(c, (len(state), 1))


def _emitter_material(front, back=None, intensity=(6.0, 5.0, 4.0), back_intensity=(3.0, 4.0, 6.0),
                      mode="intensity_radiant_exitance", varying=False):
    wrap = _varying if varying else (lambda c: c)
    surface = M.material_surface(emission=M.material_emission(front, wrap(intensity), mode))
    if back is None:
        return M.material(surface=surface)
    backface = M.material_surface(
        scattering=df.diffuse_reflection_bsdf(tint=(0.3, 0.3, 0.3)),
        emission=M.material_emission(back, wrap(back_intensity), mode))
    return M.material(thin_walled=True, surface=surface, backface=backface)


def _scene(mat, rotate=(70.0, 20.0, 0.0), scale=1.0):
    floor = SceneObject(Plane(size=(6.0, 6.0), origin=(-3.0, -3.0, 0.0)),
                        M.material(surface=M.material_surface(
                            df.diffuse_reflection_bsdf(tint=(0.6, 0.5, 0.4)))),
                        make_transform(rotate=(-90.0, 0.0, 0.0), translate=(0.0, 0.0, 3.0)),
                        name="floor")
    ball = SceneObject(UVSphere(radius=0.4),
                       M.material(surface=M.material_surface(df.diffuse_reflection_bsdf())),
                       make_transform(translate=(0.5, 0.4, 0.0)), name="ball")
    lamp = SceneObject(Plane(size=(0.8, 0.8), origin=(-0.4, -0.4, 0.0)), mat,
                       make_transform(rotate=rotate, translate=(-0.4, 1.2, 0.2), scale=scale),
                       name="lamp")
    cam = Camera(position=(0.0, 1.4, 3.4), look_at=(0.0, 0.5, 0.0), width=RES, height=RES,
                 fov_y_deg=45.0)
    return Scene(cam, [floor, ball, lamp], [], RenderSettings(RES, RES, spp=8, max_depth=4))


def _render(mat, spp=8, **kw):
    scene = _scene(mat, **kw)
    integ = Integrator(scene, scene.build())
    film = integ.render(spp=spp, progress=False, seed=3)
    return film.rgb(), film.stats["bound_objects"]


CASES = {
    "local spot": lambda: (df.spot_edf(exponent=3.0, spread=0.6 * math.pi,
                                       global_distribution=False), None),
    "global spot": lambda: (df.spot_edf(exponent=2.0, spread=0.8 * math.pi,
                                        global_frame=((1.0, 0.0, 0.0), (0.0, 0.8, -0.6),
                                                      (0.0, 0.6, 0.8))), None),
    "edf tint": lambda: (df.tint(tint=(0.2, 0.9, 0.5), base=df.diffuse_edf()), None),
    "edf directional_factor": lambda: (df.directional_factor(
        normal_tint=(1.0, 0.3, 0.2), grazing_tint=(0.1, 0.4, 1.0), exponent=3.0,
        base=df.diffuse_edf()), None),
    "edf mix": lambda: (df.normalized_mix(components=[
        df.edf_component(weight=0.4, component=df.diffuse_edf()),
        df.edf_component(weight=0.5, component=df.spot_edf(exponent=8.0,
                                                           global_distribution=False))]),
        None),
    "thin-walled backface": lambda: (
        df.spot_edf(exponent=1.0, spread=0.7 * math.pi, global_distribution=False),
        # its lobe about the object's -z: the back's side
        df.spot_edf(exponent=4.0, global_distribution=True,
                    global_frame=((1.0, 0.0, 0.0), (0.0, -1.0, 0.0), (0.0, 0.0, -1.0)))),
}


@pytest.mark.parametrize("case", list(CASES))
def test_a_constant_edf_renders_in_the_kernel_as_numpy_shades_it(case):
    front, back = CASES[case]()
    kernel, bound = _render(_emitter_material(front, back))
    assert bound == []  # nothing shaded with numpy
    numpy_, bound_numpy = _render(_emitter_material(front, back, varying=True))
    assert bound_numpy == ["lamp"]
    assert np.all(np.isfinite(kernel)) and kernel.max() > 0.0
    # the same sample values and paths: the images agree up to rounding and the
    # shadow rays' offset origins (numpy takes wo from the offset origin), not noise
    np.testing.assert_allclose(kernel, numpy_, rtol=2e-4, atol=1e-6 * kernel.max())


def test_power_mode_and_a_scaled_emitter():
    front = df.spot_edf(exponent=2.0, spread=0.9 * math.pi, global_distribution=False)
    back = df.diffuse_edf()
    mat = _emitter_material(front, back, intensity=(20.0, 10.0, 5.0),
                            back_intensity=(2.0, 2.0, 8.0), mode="intensity_power")
    kernel, bound = _render(mat, scale=(1.5, 0.5, 1.0))
    numpy_, _ = _render(_emitter_material(front, back, intensity=(20.0, 10.0, 5.0),
                                          back_intensity=(2.0, 2.0, 8.0),
                                          mode="intensity_power", varying=True),
                        scale=(1.5, 0.5, 1.0))
    assert bound == []
    np.testing.assert_allclose(kernel, numpy_, rtol=2e-4, atol=1e-6 * kernel.max())


def test_a_global_spot_follows_the_object_and_lights_only_its_cone():
    """Directly below a downward global spot (+z of the object turned to -y) the floor
    receives the spot's on-axis intensity; outside its narrow cone it is dark but for
    the floor's own bounce."""
    spot = df.spot_edf(exponent=1.0, spread=0.2 * math.pi, global_distribution=True)
    mat = M.material(thin_walled=True, surface=M.material_surface(
        emission=M.material_emission(spot, (50.0, 50.0, 50.0))))
    floor = SceneObject(Plane(size=(6.0, 6.0), origin=(-3.0, -3.0, 0.0)),
                        M.material(surface=M.material_surface(df.diffuse_reflection_bsdf())),
                        make_transform(rotate=(-90.0, 0.0, 0.0)),
                        name="floor")
    lamp = SceneObject(Plane(size=(0.2, 0.2), origin=(-0.1, -0.1, 0.0)), mat,
                       make_transform(rotate=(90.0, 0.0, 0.0), translate=(0.0, 2.0, 0.0)),
                       name="lamp")

    def render(fov):
        # from the side, past the lamp, at the floor below it
        cam = Camera(position=(1.0, 3.0, 0.0), look_at=(0.0, 0.0, 0.0), width=RES,
                     height=RES, fov_y_deg=fov)
        scene = Scene(cam, [floor, lamp], [], RenderSettings(RES, RES, spp=16, max_depth=3))
        film = Integrator(scene, scene.build()).render(progress=False, seed=1)
        assert film.stats["bound_objects"] == []
        return film.rgb()[..., 1]

    c = RES // 2
    centre = render(4.0)[c - 1:c + 1, c - 1:c + 1].mean()
    # E = ∫ I edf(theta) cos theta cos theta' / r^2 dA over the lamp (2 above the point;
    # edf = t^k (k + 1)(k + 2) / (2 pi (1 - s)(k + 1 + s)), k = 1), reflected by a white
    # floor (1 / pi); midpoint rule
    s = math.cos(0.1 * math.pi)
    x = (np.arange(400) + 0.5) / 400 * 0.2 - 0.1
    r2 = x[:, None] ** 2 + x[None, :] ** 2 + 4.0
    cos = 2.0 / np.sqrt(r2)
    edf = (cos - s) / (1.0 - s) * 6.0 / (2.0 * math.pi * (1.0 - s) * (2.0 + s))
    e = float(np.mean(50.0 * edf * cos * cos / r2)) * 0.04
    assert centre == pytest.approx(e / math.pi, rel=0.01)
    wide = render(70.0)
    # the cone's rim on the floor is 2 tan(18 deg) = 0.65 from the axis; the image's
    # left columns look 1.2 and more beyond it
    assert wide[:, :3].max() < 0.01 * centre


@pytest.mark.parametrize("name", ["fig_05_35", "fig_03_02"])
def test_gallery_emitters_are_no_longer_numpy_shaded(name):
    scene = load_scene(f"gallery/scenes/{name}.toml", overrides={"resolution": [16, 12]})
    film = Integrator(scene, scene.build()).render(spp=1, progress=False)
    assert film.stats["bound_objects"] == []


def _lambertian_ies(path):
    from render.df import write_ies

    deg = np.arange(0.0, 90.5, 1.0)
    return write_ies(path, deg, [0.0], 100.0 * np.cos(np.radians(deg))[None, :])


def test_a_measured_edf_renders_in_the_kernel_as_numpy_shades_it(tmp_path):
    from render.df import read_ies

    profile = read_ies(_lambertian_ies(tmp_path / "lamp.ies"))
    for global_distribution in (False, True):
        front = df.measured_edf(profile=profile, multiplier=1.5,
                                global_distribution=global_distribution)
        kernel, bound = _render(_emitter_material(front))
        numpy_, bound_numpy = _render(_emitter_material(front, varying=True))
        assert bound == [] and bound_numpy == ["lamp"]
        np.testing.assert_allclose(kernel, numpy_, rtol=2e-4, atol=1e-6 * kernel.max())


def test_an_ies_file_of_a_lambertian_lamp_renders_as_diffuse_edf(tmp_path):
    """I(gamma) = I0 cos(gamma) is a Lambertian emitter: with the measured edf's
    normalisation it emits what diffuse_edf emits at the same intensity (the same
    samples: up to the profile's interpolation, 4e-5 of cos at 1-degree steps)."""
    from render.df import read_ies

    profile = read_ies(_lambertian_ies(tmp_path / "lamp.ies"))
    measured, _ = _render(_emitter_material(
        df.measured_edf(profile=profile, global_distribution=False)), spp=16)
    diffuse, _ = _render(_emitter_material(df.diffuse_edf()), spp=16)
    np.testing.assert_allclose(measured, diffuse, rtol=2e-4, atol=1e-6 * diffuse.max())


SCENE = """[camera]
position = [0.0, 1.0, 3.0]
look_at = [0.0, 0.0, 0.0]
[render]
resolution = [16, 12]
spp = 1
[[objects]]
name = "floor"
surface = { type = "plane", size = [4.0, 4.0], origin = [-2.0, -2.0, 0.0] }
rotate = [-90.0, 0.0, 0.0]
material = "diffuse(tint: color(0.5))"
[[objects]]
name = "lamp"
surface = { type = "plane", size = [0.4, 0.4], origin = [-0.2, -0.2, 0.0] }
rotate = [90.0, 0.0, 0.0]
translate = [0.0, 1.5, 0.0]
material = '''material(thin_walled: true, surface: material_surface(
    emission: material_emission(intensity: color(20.0),
        emission: df::measured_edf(profile: light_profile("LAMP"),
                                   global_frame: float3x3(1.0)))))'''
"""


def test_an_ies_lamp_in_a_scene_file(tmp_path):
    """A light_profile named relative to the scene file renders in the kernel; a malformed
    one is a located scene error (file, line, column of the string), not a traceback."""
    from render.scene import SceneError, parse_scene

    _lambertian_ies(tmp_path / "lamp.ies")
    scene = parse_scene(SCENE.replace("LAMP", "lamp.ies"), str(tmp_path / "s.toml"),
                        base_dir=tmp_path)
    film = Integrator(scene, scene.build()).render(progress=False)
    assert film.stats["bound_objects"] == [] and film.rgb().max() > 0
    (tmp_path / "bad.ies").write_text("IESNA:LM-63-2002\nTILT=NONE\n1 -1 1 2 1 1 2 0 0 0\n"
                                      "1 1 0\n0 90\n0\n100 x\n")
    with pytest.raises(SceneError) as err:
        parse_scene(SCENE.replace("LAMP", "bad.ies"), str(tmp_path / "s.toml"),
                    base_dir=tmp_path)
    msg = str(err.value)
    assert msg.startswith(str(tmp_path / "s.toml") + ":19:") and "bad.ies:7: candela value 2" \
        in msg, msg
