"""Lights: the sampling kernel that renders (render.path.sample_light) against each
light's density and radiance, at the extremes, and clear errors."""

from __future__ import annotations

import numpy as np
import pytest

from displacement.surfaces import UnitSquare
from render.lights import (
    INFINITE_DISTANCE,
    AreaLight,
    ConstantEnvironment,
    DirectionalLight,
    LatLongEnvironment,
    LightSet,
    PointLight,
    SpotLight,
)
from render.path import escaped, sample_lights
from render.scene import SceneObject, emissive_material, make_transform
from render.testing import light_samples, light_tables

_tables = light_tables
_sample = light_samples


def test_point_light_inverse_square_and_coincident_point():
    p = np.array([[2.0, 0, 0], [0, 1e-150, 0], [0, 0, 0], [1e150, 0, 0]])
    wi, dist, li, pdf, delta = _sample([PointLight((0, 0, 0), (1.0, 2.0, 4.0))], p,
                                       np.zeros((4, 2)))
    assert np.allclose(li[0], [0.25, 0.5, 1.0]) and dist[0] == 2.0
    # at the light itself: no direction, no radiance, no NaN
    assert pdf[2] == 0 and np.all(li[2] == 0) and np.all(np.isfinite(li))
    assert np.all(np.isfinite(wi)) and delta.all()


def test_spot_falloff_is_smoothstep_monotone_and_bounded():
    angles = np.radians(np.linspace(0, 60, 61))
    p = np.column_stack([np.tan(angles), np.zeros(61), -np.ones(61)])  # z = -1, below
    spot = SpotLight((0, 0, 0), (0, 0, -1), 1.0, cutoff_angle=40.0, beam_width=10.0)
    _, dist, li, _, _ = _sample([spot], p, np.zeros((61, 2)))
    f = li[:, 0] * dist**2
    assert f[0] == pytest.approx(1.0) and np.all(np.diff(f) <= 1e-12)
    assert np.all(f[angles > np.radians(40)] == 0)
    c = np.cos(angles[20])  # 20 degrees: between the beam width and the cutoff
    t = (c - np.cos(np.radians(40))) / (np.cos(np.radians(10)) - np.cos(np.radians(40)))
    assert f[20] == pytest.approx(t * t * (3 - 2 * t), rel=1e-9)
    hard = SpotLight((0, 0, 0), (0, 0, -1), 1.0, cutoff_angle=20.0, beam_width=20.0)
    q = np.array([[np.tan(np.radians(a)), 0.0, -1.0] for a in (19.9, 20.1)])
    _, dist, li, _, _ = _sample([hard], q, np.zeros((2, 2)))
    assert (li[:, 0] * dist**2).round(12).tolist() == [1.0, 0.0]
    for bad in (
        {"cutoff_angle": 0.0},
        {"cutoff_angle": 10.0, "beam_width": 20.0},
        {"cutoff_angle": 200.0},
    ):
        with pytest.raises(ValueError, match="spot light"):
            SpotLight((0, 0, 0), (0, 0, -1), 1.0, **bad)
    with pytest.raises(ValueError, match="zero vector"):
        SpotLight((0, 0, 0), (0, 0, 0), 1.0)


def test_directional_light_and_bad_values():
    wi, dist, li, pdf, delta = _sample([DirectionalLight((1, -1, 0), 3.0)], np.zeros((2, 3)),
                                       np.zeros((2, 2)))
    assert np.allclose(wi, [[-1 / np.sqrt(2), 1 / np.sqrt(2), 0]] * 2) and delta.all()
    assert np.all(dist == INFINITE_DISTANCE) and np.all(li == 3.0) and np.all(pdf == 1.0)
    with pytest.raises(ValueError, match="irradiance"):
        DirectionalLight((0, -1, 0), -1.0)
    with pytest.raises(ValueError, match="position"):
        PointLight((0, np.nan, 0), 1.0)


def test_constant_environment_pdf_integrates_to_one(rng):
    env = ConstantEnvironment((0.5, 1.0, 2.0))
    wi, _, li, pdf, _ = _sample([env], np.zeros((1000, 3)), rng.random((1000, 2)))
    assert np.allclose(np.linalg.norm(wi, axis=1), 1.0)
    assert np.allclose(pdf, 1 / (4 * np.pi)) and np.allclose(li, [0.5, 1.0, 2.0])
    # directions ending on the environment: the same radiance and density
    pe, le = escaped(_tables([env]), wi)
    assert np.allclose(pe, pdf) and np.allclose(le, li)


def test_latlong_environment_sampling_matches_its_pdf(rng):
    h, w = 16, 32
    img = rng.random((h, w, 3)) ** 4 * 10
    img[0, :] = 0.0  # a black row: never sampled
    env = LatLongEnvironment(img, scale=2.0, rotation=30.0)
    tables = _tables([env])
    n = 200_000
    u = np.column_stack([np.zeros(n), rng.random((n, 2))])
    wi, _, li, pdf, _, _ = sample_lights(tables, np.zeros((n, 3)), u)
    assert np.all(pdf > 0) and np.all(np.isfinite(pdf))
    # E[L / pdf] over the sphere = integral of L = sum over texels of L * solid angle
    rows = np.arange(h)
    solid = (2 * np.pi / w) * (np.cos(np.pi * rows / h) - np.cos(np.pi * (rows + 1) / h))
    integral = (img * 2.0 * solid[:, None, None]).sum(axis=(0, 1))
    est = (li / pdf[:, None]).mean(axis=0)
    assert np.allclose(est, integral, rtol=0.02)
    # a path escaping along a sampled direction sees that radiance at that density
    pe, le = escaped(tables, wi)
    assert np.allclose(le, li) and np.allclose(pe, pdf)
    # poles and the seam are defined
    d = np.array([[0, 1.0, 0], [0, -1.0, 0], [0, 0, 1.0], [0, 0, -1.0]])
    pe, le = escaped(tables, d)
    assert np.all(np.isfinite(le)) and np.all(np.isfinite(pe))
    # an all-black map still samples (uniformly by solid angle) and gives 0
    _, _, lb, pb, _ = _sample([LatLongEnvironment(np.zeros((4, 8, 3)))], np.zeros((10, 3)),
                              rng.random((10, 2)))
    assert np.all(lb == 0) and np.all(pb > 0)
    _, le = escaped(_tables([LatLongEnvironment(np.full((4, 8, 1), 0.5))]),
                    np.array([[0.0, 0.0, 1.0]]))
    assert np.allclose(le, 0.5)
    with pytest.raises(ValueError, match=r"\(h, w, 3\)"):
        LatLongEnvironment(np.zeros((4, 8, 3, 1)))


def test_area_light_uniform_by_area_and_its_solid_angle_pdf(rng):
    # a 1 x 3 emissive rectangle in the plane z = 0 facing +z, radiance 2 (intensity 2 pi)
    quad = SceneObject(UnitSquare(), emissive_material((2.0 * np.pi,) * 3),
                       make_transform(scale=(1.0, 3.0, 1.0)))
    n = 40_000
    p = np.tile([[0.3, 0.3, 2.0]], (n, 1))
    wi, dist, li, pdf, delta = _sample([], p, rng.random((n, 2)), objects=[quad])
    x = p + wi * dist[:, None]  # the sampled points
    assert np.allclose(x[:, 2], 0.0, atol=1e-12) and not delta.any()
    assert x[:, 0].min() > -1e-12 and x[:, 0].max() < 1 + 1e-12
    assert abs((x[:, 1] > 1.5).mean() - 0.5) < 0.01  # uniform by area
    cos = np.abs(wi[:, 2])
    assert np.allclose(pdf, dist**2 / (3.0 * cos)) and np.allclose(li, 2.0)
    with pytest.raises(ValueError, match="zero area"):
        AreaLight(0, np.array([0]), np.zeros((1, 3, 3)), np.zeros((1, 3)), lambda f, b, wo: None)


def test_light_selection_and_no_lights():
    lights = [PointLight((0, 1, 0), 1.0), ConstantEnvironment(1.0)]
    assert LightSet(lights).environment is not None and LightSet(lights).select_pdf == 0.5
    u = np.column_stack([[0.1, 0.4, 0.6, 0.99], np.full((4, 2), 0.5)])
    _, _, _, pdf, delta, _ = sample_lights(_tables(lights), np.zeros((4, 3)), u)
    assert delta.tolist() == [True, True, False, False]
    assert np.allclose(pdf[:2], 0.5) and np.allclose(pdf[2:], 0.5 / (4 * np.pi))
    assert len(LightSet([])) == 0
    _, _, li, pdf, _, _ = sample_lights(_tables([]), np.zeros((2, 3)), np.zeros((2, 3)))
    assert np.all(pdf == 0) and np.all(li == 0)
    with pytest.raises(ValueError, match="at most one environment"):
        LightSet([ConstantEnvironment(1.0), ConstantEnvironment(2.0)])
