"""Stability of lights at the extremes (docs/stability.md, "Lights"): lights of zero
size (refused at their line) and of the smallest size that still has an area, and
lights 1e12 away.  A white floor seen from above must show the analytic irradiance
over pi, exactly for point-like lights and within noise for sampled ones."""

from __future__ import annotations

import math

import numpy as np
import pytest
from stability import assert_valid_radiance, mean_and_error

from render.integrator import render
from render.scene import SceneError, parse_scene

SCENE = """
[camera]
type = "orthographic"
position = [0.0, 1.0, 0.0]
look_at = [0.0, 0.0, 0.0]
up = [0.0, 0.0, -1.0]
ortho_height = 0.02

[render]
resolution = [8, 8]
spp = {spp}
max_depth = 2

[[objects]]
name = "floor"
surface = "square"
scale = 4.0
rotate = [-90.0, 0.0, 0.0]
translate = [-2.0, 0.0, 2.0]
material = "diffuse(tint: color(1.0))"

[[lights]]
"""
#: the line of the light's table in SCENE (its first key is on the next line)
LIGHT_LINE = SCENE.count("\n") + 1


def floor_radiance(light: str, spp: int = 4) -> np.ndarray:
    """The white floor's pixels (n, 3) under one light (max_depth 2: direct light only)."""
    scene = parse_scene(SCENE.format(spp=spp) + light + "\n", "lights.toml")
    film = render(scene, progress=False)
    return assert_valid_radiance(film).reshape(-1, 3)


def tessellated_sphere_fraction(light: str) -> float:
    """The area that the light's tessellated sphere shows the floor (its triangles
    projected along y, half the sum over the closed mesh), over pi r^2: the irradiance
    of the sphere that is rendered relative to the round one's (0.997 at 48 x 24)."""
    scene = parse_scene(SCENE.format(spp=1) + light + "\n", "lights.toml")
    g = scene.build()
    k = len(scene.objects) - 1  # the light's object comes after the floor
    v = g.vertices[g.faces[g.face_offset[k]:g.face_offset[k + 1]]]
    centre = v.reshape(-1, 3).mean(axis=0)
    v = v - centre  # 1e12 from the origin: areas from coordinates relative to the centre
    area = 0.5 * np.cross(v[:, 1] - v[:, 0], v[:, 2] - v[:, 0])
    r = np.linalg.norm(v, axis=-1).max()
    return 0.5 * np.abs(area[:, 1]).sum() / (math.pi * r * r)


# -- zero size ---------------------------------------------------------------------------
@pytest.mark.parametrize(("light", "key", "words"), [
    ('type = "quad"\ncenter = [0, 2, 0]\nnormal = [0, -1, 0]\nsize = [0.0, 0.0]\n'
     'radiance = [1, 1, 1]', "center", "size[0] must be a finite number > 0, got 0.0"),
    ('type = "sphere"\ncenter = [0, 2, 0]\nradius = 0.0\nradiance = [1, 1, 1]', "radius",
     "radius must be a number > 0, got 0.0"),
    ('type = "quad"\ncenter = [0, 2, 0]\nnormal = [0, -1, 0]\nsize = [1e-300, 1e-300]\n'
     'radiance = [1, 1, 1]', "size", "this quad light has no area in double precision"),
    ('type = "quad"\ncenter = [1, 2, 1]\nnormal = [0, -1, 0]\nsize = [1e-17, 1e-17]\n'
     'radiance = [1, 1, 1]', "size", "the corners round to the same points"),
    ('type = "sphere"\ncenter = [0, 2, 0]\nradius = 1e-300\nradiance = [1, 1, 1]', "radius",
     "this sphere light has no area in double precision"),
    ('type = "spot"\nposition = [0, 1, 0]\ndirection = [0, -1, 0]\ncutoff_angle = 0.0',
     "type", "spot light needs 0 < cutoff_angle"),
], ids=["quad-0", "sphere-0", "quad-1e-300", "quad-1e-17-at-1", "sphere-1e-300", "spot-0"])
def test_lights_of_zero_size_are_refused_at_their_line(light, key, words):
    with pytest.raises(SceneError) as e:
        parse_scene(SCENE.format(spp=1) + light + "\n", "lights.toml")
    lines = light.splitlines()
    line = LIGHT_LINE + next((i for i, ln in enumerate(lines) if ln.startswith(key)), -1)
    assert e.value.path == "lights.toml" and words in e.value.message
    assert e.value.line in (line, LIGHT_LINE - 1)  # the key's line, or the table's


def test_the_smallest_quad_light_that_has_an_area_lights_the_floor_exactly():
    # 1e-10 x 1e-10 at height 2, radiance 1e20: L A = 1, E = L A / d^2 = 1/4 below it
    px = floor_radiance('type = "quad"\ncenter = [0, 2, 0]\nnormal = [0, -1, 0]\n'
                        'size = [1e-10, 1e-10]\nradiance = [1e20, 1e20, 1e20]')
    # points up to 0.01 off axis: E = L A h^2 / d^4, within 2.5e-5 of 1/4
    np.testing.assert_allclose(px, 0.25 / math.pi, rtol=1e-4)


def test_a_sphere_light_of_radius_1e_minus_6_lights_the_floor_within_noise():
    # E = L pi r^2 / d^2 = 1e12 pi 1e-12 / 4: the floor shows 1/4, times the tessellated
    # sphere's share of the round one's area (0.3 % less: 3 standard errors at 64 spp)
    light = 'type = "sphere"\ncenter = [0, 2, 0]\nradius = 1e-6\nradiance = [1e12, 1e12, 1e12]'
    px = floor_radiance(light, spp=64)
    mean, err = mean_and_error(px)
    want = 0.25 * tessellated_sphere_fraction(light)
    assert 0.99 < want / 0.25 < 1.0
    assert np.all(np.abs(mean - want) <= 4 * err + 1e-6), (mean, err, want)


# -- 1e12 away ---------------------------------------------------------------------------
FAR = {
    "point": 'type = "point"\nposition = [0, 1e12, 0]\nintensity = [1e24, 1e24, 1e24]',
    "spot": 'type = "spot"\nposition = [0, 1e12, 0]\ndirection = [0, -1, 0]\n'
            'intensity = [1e24, 1e24, 1e24]',
    "quad 1 unit": 'type = "quad"\ncenter = [0, 1e12, 0]\nnormal = [0, -1, 0]\nsize = [1, 1]\n'
                   'radiance = [1e24, 1e24, 1e24]',
    "quad 1e6 units": 'type = "quad"\ncenter = [0, 1e12, 0]\nnormal = [0, -1, 0]\n'
                      'size = [1e6, 1e6]\nradiance = [1e12, 1e12, 1e12]',
    "directional": 'type = "directional"\ndirection = [0, -1, 0]\nirradiance = [1, 1, 1]',
}


@pytest.mark.parametrize("name", FAR)
def test_lights_1e12_away_give_the_analytic_irradiance(name):
    # each gives an irradiance of 1 on the floor: radiance 1 / pi everywhere
    np.testing.assert_allclose(floor_radiance(FAR[name]), 1.0 / math.pi, rtol=1e-9)


def test_a_dim_light_1e12_away_stays_finite_and_exact():
    px = floor_radiance('type = "point"\nposition = [0, 1e12, 0]\nintensity = [1, 1, 1]')
    np.testing.assert_allclose(px, 1e-24 / math.pi, rtol=1e-9)


def test_a_closed_sphere_light_1e12_away_is_welded_and_lights_within_noise():
    # radius 1e6 at 1e12: E = L pi (r/d)^2 = pi, so the floor shows 1 (its mesh is closed:
    # welding 1e12 from the origin used to overflow int64)
    light = ('type = "sphere"\ncenter = [0, 1e12, 0]\nradius = 1e6\n'
             'radiance = [1e12, 1e12, 1e12]')
    px = floor_radiance(light, spp=64)
    mean, err = mean_and_error(px)
    want = tessellated_sphere_fraction(light)
    assert 0.99 < want < 1.0
    assert np.all(np.abs(mean - want) <= 4 * err + 1e-3), (mean, err, want)
