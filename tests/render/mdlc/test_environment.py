"""Environments written in MDL: ``base::sun_and_sky`` is the core's sun and sky, other
colour functions of ``state::direction()`` are baked into a lat-long map, and a scene
names them as ``[[lights]] type = "environment", function = "..."``."""

from __future__ import annotations

import numpy as np
import pytest

from mdl.diagnostics import MdlError
from render.lights import ConstantEnvironment, LatLongEnvironment
from render.mdlc.environment import direction_grid, environment_from_call
from render.mdlc.natives import SUN_RADIUS
from render.scene import SceneError, parse_scene
from render.sky import SunAndSky

HANDBOOK_SKY = ("base::sun_and_sky(sun_direction: float3(-1.0, 1.0, -1.0), horizon_blur: 0.5,"
                " sun_disk_intensity: 0.04, sun_disk_scale: 1.0)")


def test_the_handbooks_sun_and_sky_is_the_cores():
    """Section 3.8.2's arguments: the sun's direction, a dim disk of the real size."""
    light = environment_from_call(HANDBOOK_SKY)
    assert isinstance(light, SunAndSky)
    want = SunAndSky([-1.0, 1.0, -1.0], turbidity=3.0, sun_radius=SUN_RADIUS, sun_scale=0.04)
    d = np.random.default_rng(1).normal(size=(500, 3))
    d /= np.linalg.norm(d, axis=1, keepdims=True)
    d[0] = want.sun_direction  # inside the disk
    np.testing.assert_allclose(light.eval(d), want.eval(d), rtol=1e-12)
    np.testing.assert_allclose(light.sun_irradiance, want.sun_irradiance, rtol=1e-12)


def test_sun_and_sky_arguments_map_to_the_cores_parameters():
    light = environment_from_call(
        "base::sun_and_sky(multiplier: 2.0, rgb_unit_conversion: color(0.0002), haze: 4.0,"
        " ground_color: color(0.5), sun_direction: float3(0.0, 0.0, 1.0), y_is_up: false,"
        " sun_disk_scale: 3.0)")
    want = SunAndSky([0.0, 1.0, 0.0], turbidity=6.0, intensity=4.0,
                     sun_radius=3 * SUN_RADIUS, ground_albedo=0.5)
    np.testing.assert_allclose(light.sun_direction, want.sun_direction, atol=1e-15)
    np.testing.assert_allclose(light.sun_irradiance, want.sun_irradiance, rtol=1e-12)
    off = environment_from_call("base::sun_and_sky(on: false)")
    assert np.all(off.eval(np.array([[0.0, 1.0, 0.0], [1.0, 0.0, 0.0]])) == 0.0)


def test_sun_and_sky_as_a_colour_in_a_material_reads_state_direction():
    """Called in a material, it is the radiance arriving along state::direction()."""
    from displacement.state import ShadingState
    from render.mdlc import material_from_call

    value, info = material_from_call(HANDBOOK_SKY)
    d = np.array([[0.0, 1.0, 0.0], [0.6, 0.8, 0.0]])
    n = len(d)
    s = ShadingState(np.zeros((n, 3)), -d, np.zeros((n, 2)), np.tile([1.0, 0, 0], (n, 1)),
                     np.tile([0.0, 1.0, 0], (n, 1)), direction=d)
    np.testing.assert_allclose(value.lanes(s), environment_from_call(HANDBOOK_SKY).eval(d))


def test_constant_and_baked_environments():
    c = environment_from_call("color(0.2, 0.4, 0.6) * 0.5")
    assert isinstance(c, ConstantEnvironment) and c.radiance.tolist() == [0.1, 0.2, 0.3]
    f = ("math::lerp(color(0.1), color(0.3, 0.5, 1.0), "
         "math::max(state::direction().y, 0.0))")
    e = environment_from_call(f, resolution=(16, 32))
    assert isinstance(e, LatLongEnvironment) and e.image.shape == (16, 32, 3)
    y = direction_grid(16, 32)[..., 1]
    t = np.maximum(y, 0.0)[..., None]
    np.testing.assert_allclose(e.image, 0.1 * (1 - t) + np.array([0.3, 0.5, 1.0]) * t,
                               rtol=1e-12)


def test_the_lat_long_grid_is_the_lights_layout():
    d = direction_grid(4, 8)
    np.testing.assert_allclose(np.linalg.norm(d, axis=-1), 1.0)
    u = 0.5 + np.arctan2(d[..., 0], -d[..., 2]) / (2 * np.pi)
    v = np.arccos(d[..., 1]) / np.pi
    np.testing.assert_allclose(u, (np.arange(8) + 0.5)[None, :] / 8 * np.ones((4, 1)))
    np.testing.assert_allclose(v, (np.arange(4) + 0.5)[:, None] / 4 * np.ones((1, 8)))


def test_an_environment_must_be_a_colour():
    with pytest.raises(MdlError) as e:
        environment_from_call("float3(1.0)")
    assert "color function of state::direction()" in e.value.first.message


SCENE = """\
[camera]
position = [0.0, 0.0, 3.0]
look_at = [0.0, 0.0, 0.0]

[[objects]]
surface = "sphere"
material = "plaster()"

[[lights]]
type = "environment"
function = \"\"\"{call}\"\"\"
"""


def test_a_scene_names_an_environment_function(tmp_path):
    scene = parse_scene(SCENE.format(call=HANDBOOK_SKY), str(tmp_path / "s.toml"),
                        base_dir=tmp_path)
    assert any(isinstance(light, SunAndSky) for light in scene.lights)
    with pytest.raises(SceneError) as e:
        parse_scene(SCENE.format(call="base::sun_and_sky(sun_direction: float3(0.0, 1.0, 0.0),"
                                      " hazy: 2.0)"), str(tmp_path / "s.toml"),
                    base_dir=tmp_path)
    assert "s.toml:11:" in str(e.value) and "did you mean 'haze'" in str(e.value)
