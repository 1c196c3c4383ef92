"""Stability of displacement at the extremes (docs/stability.md, "Displacement"):
amplitudes far beyond the surface's size, folded and self-intersecting displacement,
zero-area triangles, and grazing cameras.  The dicer returns finite vertices and unit
normals within its triangle cap, and the renders are finite, non-negative and create
no energy in a white furnace; a surface displaced to nothing is refused clearly."""

from __future__ import annotations

import warnings

import numpy as np
import pytest
import trimesh
from stability import assert_no_energy_gain, furnace

from displacement.camera import Camera
from displacement.dice import DicingCapWarning, dice
from displacement.fields import Field
from displacement.surfaces import MeshSurface, UnitSquare, UVSphere
from displacement.waves import waves_as_displacement
from render import material as M
from render.scene import SceneObject, make_transform

#: the unit square turned to lie in the xz-plane, facing +y
FLAT = make_transform(rotate=(-90.0, 0.0, 0.0))
CAMERA = Camera(position=(0.5, 1.5, 2.0), look_at=(0.5, 0.0, -0.5), fov_y_deg=40,
                width=24, height=24)


def white(field=None) -> M.material:
    """A lossless white diffuse material, displaced by ``field``."""
    return M.material(surface=M.material_surface(M.df.diffuse_reflection_bsdf(tint=1.0)),
                      geometry=M.material_geometry(displacement=field))


def assert_sound_mesh(mesh, cap: int | None = None) -> None:
    assert np.all(np.isfinite(mesh.vertices)) and np.all(np.isfinite(mesh.normals))
    np.testing.assert_allclose(np.linalg.norm(mesh.normals, axis=1), 1.0, atol=1e-9)
    np.testing.assert_allclose(np.linalg.norm(mesh.tangents, axis=1), 1.0, atol=1e-9)
    assert mesh.faces.min() >= 0 and mesh.faces.max() < len(mesh.vertices)
    if cap is not None:
        assert mesh.triangle_count <= cap


def object_pixels(film) -> np.ndarray:
    return film.rgb()[film.alpha() > 0.999]


# -- amplitudes far beyond the surface ---------------------------------------------------
@pytest.mark.parametrize("distance", [1e3, 1e12])
def test_amplitudes_far_beyond_the_surface_dice_within_the_cap(distance):
    cap = 20_000
    field = waves_as_displacement(frequency=4.0, distance=distance)
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        mesh = dice(UnitSquare(), field, CAMERA, FLAT, max_triangles=cap)
    assert_sound_mesh(mesh, cap)
    # the relief spans +-(distance_u + distance_v): the mesh does too (nothing clamped)
    assert np.ptp(mesh.vertices[:, 1]) == pytest.approx(4 * distance, rel=0.05)
    if mesh.stats["cap_reached"]:
        assert any(issubclass(w.category, DicingCapWarning) for w in caught)
    assert np.isfinite(mesh.stats["max_error_px"])


def test_an_amplitude_of_a_thousand_surfaces_renders_without_energy_gain():
    # the relief is 4000 units tall on a unit square, the camera amid its walls.  A
    # lossless path may bounce thousands of times between them before it escapes (the
    # roulette keeps a throughput of 1 alive), so the depth is capped: energy only drops
    field = waves_as_displacement(frequency=2.0, distance=1e3)
    film = furnace([SceneObject(UnitSquare(), white(field), FLAT)], CAMERA, max_depth=64)
    assert (film.alpha() > 0).sum() >= 16
    assert_no_energy_gain(object_pixels(film))


# -- folded and self-intersecting displacement --------------------------------------------
def _fold(state):
    """The square's left half folded back over its right half, with a ripple."""
    u = state.uv[:, 0]
    x = np.where(u < 0.5, 1.0 - 2.0 * u, 0.0)  # u in [0, .5] lands on [1, .5]... reversed
    return np.stack([x, np.zeros_like(u), 0.2 * np.sin(8.0 * u)], axis=1)


def _spiral(state):
    """Every v line wound twice around a circle: the surface passes through itself."""
    u = state.uv[:, 0]
    target = np.stack([0.5 + 0.4 * np.cos(4 * np.pi * u), state.position[:, 1],
                       0.3 * np.sin(4 * np.pi * u) + 0.1 * u], axis=1)
    return target - state.position


FOLDS = {"fold": Field(_fold, ([0.5], None)), "spiral": Field(_spiral)}


@pytest.mark.parametrize("name", FOLDS)
def test_folded_and_self_intersecting_surfaces_dice_soundly(name):
    mesh = dice(UnitSquare(), FOLDS[name], CAMERA, FLAT)
    assert_sound_mesh(mesh)
    assert mesh.stats["max_error_px"] <= 0.5 + 1e-9


@pytest.mark.parametrize("name", FOLDS)
def test_folded_and_self_intersecting_surfaces_render_without_energy_gain(name):
    film = furnace([SceneObject(UnitSquare(), white(FOLDS[name]), FLAT)], CAMERA)
    assert_no_energy_gain(object_pixels(film))


# -- zero-area triangles -----------------------------------------------------------------
def _degenerate_mesh() -> MeshSurface:
    """Two good triangles, a sliver of zero area, a repeated vertex and a point."""
    v = np.array([[0, 0, 0], [1, 0, 0], [0, 0, -1], [1, 0, -1], [0.5, 0, -0.5],
                  [0.5, 0, -0.5], [2, 0, 0]], dtype=float)
    f = np.array([[0, 1, 2], [1, 3, 2], [4, 5, 4], [0, 1, 6], [4, 4, 4]])
    m = trimesh.Trimesh(v, f, process=False)
    m.visual = trimesh.visual.TextureVisuals(uv=np.zeros((len(v), 2)))
    return MeshSurface(m)


def _pinch(state):
    """The left half of the square squeezed onto the line u = 0.5: zero-area triangles."""
    u = state.uv[:, 0]
    return np.stack([np.maximum(0.5 - u, 0.0), np.zeros_like(u), np.zeros_like(u)], axis=1)


@pytest.mark.parametrize("case", ["mesh", "mesh displaced", "pinched"])
def test_zero_area_triangles_render_without_energy_gain(case):
    if case == "pinched":
        obj = SceneObject(UnitSquare(), white(Field(_pinch, ([0.5], None))), FLAT)
    else:
        field = Field(lambda s: 0.1 * s.normal) if case == "mesh displaced" else None
        obj = SceneObject(_degenerate_mesh(), white(field))
    film = furnace([obj], CAMERA)
    assert_no_energy_gain(object_pixels(film))


def test_zero_area_triangles_dice_to_unit_normals():
    mesh = dice(_degenerate_mesh(), Field(lambda s: 0.1 * s.normal), CAMERA)
    assert_sound_mesh(mesh)
    pinched = dice(UnitSquare(), Field(_pinch, ([0.5], None)), CAMERA, FLAT)
    assert_sound_mesh(pinched)


def test_a_surface_displaced_to_a_point_is_refused_clearly():
    to_point = Field(lambda s: 0.5 - s.position)
    with pytest.raises(ValueError, match=r"nothing to trace: every object \('object0'\) has "
                                         r"zero area"):
        furnace([SceneObject(UnitSquare(), white(to_point), FLAT, name="object0")], CAMERA)


# -- grazing cameras ---------------------------------------------------------------------
def grazing_camera(height: float) -> Camera:
    """A camera ``height`` above the square's plane, looking along it."""
    return Camera(position=(-1.0, height, -0.5), look_at=(2.0, height, -0.5), fov_y_deg=40,
                  width=24, height=24)


@pytest.mark.parametrize("height", [0.0, 1e-7, 1e-3])
def test_grazing_cameras_dice_soundly(height):
    cam = grazing_camera(height)
    field = waves_as_displacement(frequency=4.0, distance=0.05)
    mesh = dice(UnitSquare(), field, cam, FLAT)
    assert_sound_mesh(mesh)
    sphere = dice(UVSphere(0.3), field, cam, make_transform(translate=(0.5, 0.0, -0.5)))
    assert_sound_mesh(sphere)


@pytest.mark.parametrize("height", [0.0, 1e-7, 1e-3])
def test_grazing_cameras_render_without_energy_gain(height):
    cam = grazing_camera(height)
    field = waves_as_displacement(frequency=4.0, distance=0.05)
    objects = [SceneObject(UnitSquare(), white(field), FLAT),
               SceneObject(UnitSquare(), white(), make_transform(translate=(0.0, -0.2, 0.0),
                                                                 rotate=(-90.0, 0.0, 0.0)))]
    film = furnace(objects, cam)
    assert_no_energy_gain(object_pixels(film))
