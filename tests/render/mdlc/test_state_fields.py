"""``state::direction()``, ``state::geometry_normal()`` and ``state::object_id()`` in a
render: the integrator fills them in the shading state of every hit (object space, unit).

An MDL material emits ``pi * value`` from a diffuse edf, so a pixel seen through it holds
``value`` (the edf's radiance is ``intensity / pi``).  The camera is orthographic, so every
ray of a render has the same direction, and the objects are flat, so every quantity is
constant on each object: the pixels an object covers entirely must hold the values
computed from the geometry alone, exactly.

* object 0: two triangles whose vertex normals are tilted 0.4 rad about y from the
  plane's normal, wound clockwise (their cross product points away from the camera):
  ``state::normal()`` is the tilted normal, ``state::geometry_normal()`` the plane's
  normal turned to the shading side (+z); moved by a translation only (the integrator's
  rigid path);
* object 1: the unit square rotated about y and x and scaled unevenly: in object space
  its geometric normal stays +z and the ray direction is ``L^-1 d`` made unit.
"""

from __future__ import annotations

import numpy as np
import pytest
import trimesh

from displacement.surfaces import MeshSurface, UnitSquare
from render.camera import Camera
from render.integrator import render
from render.mdlc import material_from_call
from render.scene import RenderSettings, Scene, SceneObject

MODULE = """\
mdl 1.8;
import ::df::*;
import ::state::*;
import ::math::*;

float3 half_up(float3 v) = v * 0.5 + float3(0.5);

// what: 0 state::direction(), 1 state::geometry_normal(), 2 state::normal(),
// 3 state::object_id()
export material probe(uniform int what = 0) = material(
    surface: material_surface(emission: material_emission(
        emission: df::diffuse_edf(),
        intensity: math::PI * (what == 0 ? color(half_up(state::direction()))
                   : what == 1 ? color(half_up(state::geometry_normal()))
                   : what == 2 ? color(half_up(state::normal()))
                   : color(float(state::object_id()) * 0.25 + 0.25)))));
"""

TILT = 0.4
WIDTH, HEIGHT = 40, 24


def _rotation(axis: int, angle: float) -> np.ndarray:
    c, s = np.cos(angle), np.sin(angle)
    i, j = [a for a in range(3) if a != axis]
    r = np.eye(3)
    r[i, i], r[i, j], r[j, i], r[j, j] = c, -s, s, c
    return r


def _tilted_quad() -> MeshSurface:
    vertices = np.array([[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [1.0, 1.0, 0.0], [0.0, 1.0, 0.0]])
    faces = np.array([[0, 2, 1], [0, 3, 2]])  # clockwise seen from +z: cross product -z
    normal = np.array([np.sin(TILT), 0.0, np.cos(TILT)])
    mesh = trimesh.Trimesh(vertices=vertices, faces=faces, vertex_normals=np.tile(normal, (4, 1)),
                           visual=trimesh.visual.TextureVisuals(uv=vertices[:, :2]),
                           process=False)
    return MeshSurface(mesh, normals="vertex")


def _transforms() -> list[np.ndarray]:
    rigid = np.eye(4)
    rigid[:3, 3] = (-1.3, -0.5, 0.0)
    other = np.eye(4)
    other[:3, :3] = _rotation(1, 0.5) @ _rotation(0, -0.3) @ np.diag([0.9, 0.8, 1.7])
    other[:3, 3] = (0.2, -0.4, 0.1)
    return [rigid, other]


CAMERA = dict(position=(0.4, 0.3, 5.0), look_at=(0.1, 0.0, 0.0), up=(0.1, 1.0, 0.0),
              width=WIDTH, height=HEIGHT, ortho_height=1.9)


@pytest.fixture(scope="module")
def module_dir(tmp_path_factory):
    d = tmp_path_factory.mktemp("state_fields")
    (d / "probe.mdl").write_text(MODULE, encoding="utf-8")
    return d


def _render(module_dir, what: int) -> np.ndarray:
    material, _ = material_from_call(f"probe(what: {what})", "probe.mdl", base_dir=module_dir)
    surfaces = [_tilted_quad(), UnitSquare()]
    objects = [SceneObject(s, material, t, name=f"object {k}")
               for k, (s, t) in enumerate(zip(surfaces, _transforms(), strict=True))]
    scene = Scene(Camera(**CAMERA), objects, [], RenderSettings(WIDTH, HEIGHT, spp=4,
                                                                max_depth=1))
    return render(scene, spp=4, seed=3, progress=False).rgb()


def _covered(camera: Camera, transform: np.ndarray) -> np.ndarray:
    """(HEIGHT, WIDTH) bool: pixels whose whole square lies on the object's unit square
    (the projection is affine: a parallelogram; all four pixel corners inside it)."""
    corners = np.array([[0.0, 0.0, 0.0, 1.0], [1.0, 0.0, 0.0, 1.0], [0.0, 1.0, 0.0, 1.0]])
    xy, _ = camera.project((corners @ transform.T)[:, :3])
    o, a, b = xy[0], xy[1] - xy[0], xy[2] - xy[0]
    inv = np.linalg.inv(np.stack([a, b], axis=1))
    px, py = np.meshgrid(np.arange(WIDTH + 1.0), np.arange(HEIGHT + 1.0))
    st = (np.stack([px, py], axis=-1) - o) @ inv.T
    inside = np.all((st > 1e-9) & (st < 1.0 - 1e-9), axis=-1)  # pixel corners
    return inside[:-1, :-1] & inside[1:, :-1] & inside[:-1, 1:] & inside[1:, 1:]


def test_state_fields_per_pixel(module_dir):
    camera = Camera(**CAMERA)
    transforms = _transforms()
    forward = np.asarray(camera.look_at) - np.asarray(camera.position)
    forward /= np.linalg.norm(forward)
    images = {what: _render(module_dir, what) for what in range(4)}
    tilted = np.array([np.sin(TILT), 0.0, np.cos(TILT)])
    for k, t in enumerate(transforms):
        mask = _covered(camera, t)
        assert mask.sum() >= 40, (k, int(mask.sum()))  # the check sees many pixels
        inv = np.linalg.inv(t[:3, :3])
        direction = inv @ forward
        direction /= np.linalg.norm(direction)
        expect = {
            0: 0.5 * direction + 0.5,                            # toward the surface, unit
            1: np.array([0.5, 0.5, 1.0]),                        # +z, the shading side
            2: 0.5 * (tilted if k == 0 else np.array([0.0, 0.0, 1.0])) + 0.5,
            3: np.full(3, 0.25 * k + 0.25),
        }
        for what, want in expect.items():
            got = images[what][mask]
            assert np.allclose(got, want, rtol=0.0, atol=1e-6), (k, what, got[:2], want)
    # the fields are not the stand-ins they replaced (zero, the shading normal, 0)
    quad = _covered(camera, transforms[0])
    assert np.abs(images[0][quad] - 0.5).max() > 0.2
    assert np.abs(images[1][quad] - images[2][quad]).max() > 0.1
    assert np.abs(images[3][quad] - images[3][_covered(camera, transforms[1])][0]).max() > 0.2
