"""Lights: sampling densities against their pdfs, radiance at the extremes, and clear errors."""

from __future__ import annotations

import numpy as np
import pytest

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


def test_point_light_inverse_square_and_coincident_point():
    light = PointLight((0, 0, 0), (1.0, 2.0, 4.0))
    p = np.array([[2.0, 0, 0], [0, 1e-150, 0], [0, 0, 0], [1e150, 0, 0]])
    s = light.sample_li(p, np.zeros((4, 2)))
    assert np.allclose(s.radiance[0], [0.25, 0.5, 1.0])
    # at the light itself: no direction, no radiance, no NaN
    assert s.pdf[2] == 0 and np.all(s.radiance[2] == 0) and np.all(np.isfinite(s.radiance))
    assert np.all(np.isfinite(s.wi)) and s.delta


def test_spot_falloff_is_monotone_and_bounded():
    spot = SpotLight((0, 0, 0), (0, 0, -1), 1.0, cutoff_angle=40.0, beam_width=10.0)
    angles = np.radians(np.linspace(0, 60, 61))
    f = spot.falloff(np.cos(angles))
    assert f[0] == 1.0 and np.all(np.diff(f) <= 1e-15) and np.all(f[angles > np.radians(40)] == 0)
    hard = SpotLight((0, 0, 0), (0, 0, -1), 1.0, cutoff_angle=20.0, beam_width=20.0)
    assert hard.falloff(np.cos(np.radians([19.9, 20.1]))).tolist() == [1.0, 0.0]
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
    s = DirectionalLight((1, -1, 0), 3.0).sample_li(np.zeros((2, 3)), np.zeros((2, 2)))
    assert np.allclose(s.wi, [[-1 / np.sqrt(2), 1 / np.sqrt(2), 0]] * 2)
    assert np.all(s.distance == INFINITE_DISTANCE) and np.all(s.radiance == 3.0)
    with pytest.raises(ValueError, match="irradiance"):
        DirectionalLight((0, -1, 0), -1.0)
    with pytest.raises(ValueError, match="position"):
        PointLight((0, np.nan, 0), 1.0)


def test_constant_environment_pdf_integrates_to_one(rng):
    env = ConstantEnvironment((0.5, 1.0, 2.0))
    s = env.sample_li(np.zeros((1000, 3)), rng.random((1000, 2)))
    assert np.allclose(np.linalg.norm(s.wi, axis=1), 1.0)
    assert np.allclose(s.pdf, 1 / (4 * np.pi)) and np.allclose(s.radiance, [0.5, 1.0, 2.0])


def test_latlong_environment_sampling_matches_its_pdf(rng):
    h, w = 16, 32
    img = rng.random((h, w, 3)) ** 4 * 10
    img[0, :] = 0.0  # a black row: never sampled
    env = LatLongEnvironment(img, scale=2.0, rotation=30.0)
    n = 200_000
    s = env.sample_li(np.zeros((n, 3)), rng.random((n, 2)))
    assert np.all(s.pdf > 0) and np.all(np.isfinite(s.pdf))
    # E[L / pdf] over the sphere = integral of L = sum over texels of L * solid angle
    rows = np.arange(h)
    solid = (2 * np.pi / w) * (np.cos(np.pi * rows / h) - np.cos(np.pi * (rows + 1) / h))
    integral = (img * 2.0 * solid[:, None, None]).sum(axis=(0, 1))
    est = (s.radiance / s.pdf[:, None]).mean(axis=0)
    assert np.allclose(est, integral, rtol=0.02)
    # eval and pdf agree with what sample returned
    assert np.allclose(env.eval(s.wi), s.radiance) and np.allclose(env.pdf(s.wi), s.pdf)
    # poles and the seam are defined
    d = np.array([[0, 1.0, 0], [0, -1.0, 0], [0, 0, 1.0], [0, 0, -1.0]])
    assert np.all(np.isfinite(env.eval(d))) and np.all(np.isfinite(env.pdf(d)))
    # an all-black map still samples (uniformly by solid angle) and gives 0
    black = LatLongEnvironment(np.zeros((4, 8, 3)))
    sb = black.sample_li(np.zeros((10, 3)), rng.random((10, 2)))
    assert np.all(sb.radiance == 0) and np.all(sb.pdf > 0)
    grey = LatLongEnvironment(np.full((4, 8, 1), 0.5))
    assert np.allclose(grey.eval(np.array([[0.0, 0.0, 1.0]])), 0.5)
    with pytest.raises(ValueError, match=r"\(h, w, 3\)"):
        LatLongEnvironment(np.zeros((4, 8, 3, 1)))


def test_area_light_uniform_by_area(rng):
    # two triangles of areas 1 and 3 (a 1x1 and a 1x3 right triangle pair)
    corners = np.array(
        [
            [[0, 0, 0], [np.sqrt(2), 0, 0], [0, np.sqrt(2), 0]],
            [[5, 0, 0], [5 + np.sqrt(6), 0, 0], [5, np.sqrt(6), 0]],
        ],
        float,
    )
    normals = np.array([[0, 0, 1.0], [0, 0, 1.0]])
    light = AreaLight(
        0, np.array([10, 11]), corners, normals, lambda f, b, wo: np.ones((len(f), 3))
    )
    assert light.area == pytest.approx(4.0)
    k, bary, pos = light.sample_points(rng.random((40000, 2)))
    assert abs((k == 1).mean() - 0.75) < 0.01
    assert np.all(bary >= -1e-12) and np.allclose(bary.sum(axis=1), 1)
    assert np.all(pos[k == 0, 0] <= np.sqrt(2) + 1e-12)
    # solid-angle pdf from a point above: d^2 / (A cos)
    p = np.array([[0.3, 0.3, 2.0]])
    s = light.sample_li(p, np.array([[0.1, 0.5]]))
    cos = abs(s.wi[0, 2])
    assert s.pdf[0] == pytest.approx(s.distance[0] ** 2 / (4.0 * cos))
    with pytest.raises(ValueError, match="zero area"):
        AreaLight(0, np.array([0]), np.zeros((1, 3, 3)), normals[:1], lambda f, b, wo: None)


def test_light_set_selection():
    lights = LightSet([PointLight((0, 1, 0), 1.0), ConstantEnvironment(1.0)])
    assert lights.environment is not None and lights.select_pdf == 0.5
    wi, dist, li, pdf, delta = lights.sample_li(
        np.zeros((4, 3)), np.array([0.1, 0.4, 0.6, 0.99]), np.full((4, 2), 0.5)
    )
    assert delta.tolist() == [True, True, False, False]
    assert np.allclose(pdf[:2], 0.5) and np.allclose(pdf[2:], 0.5 / (4 * np.pi))
    empty = LightSet([])
    assert len(empty) == 0 and np.all(
        empty.sample_li(np.zeros((2, 3)), np.zeros(2), np.zeros((2, 2)))[3] == 0
    )
    with pytest.raises(ValueError, match="at most one environment"):
        LightSet([ConstantEnvironment(1.0), ConstantEnvironment(2.0)])
