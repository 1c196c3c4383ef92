"""Base surfaces: analytic positions and frames, poles, seams, uv outside [0, 1], meshes."""

from __future__ import annotations

import math

import numpy as np
import pytest
import trimesh
from hypothesis import given, settings
from hypothesis import strategies as st
from hypothesis.extra.numpy import arrays

from displacement.surfaces import (
    Cube,
    Cylinder,
    MeshSurface,
    Plane,
    Torus,
    UnitSquare,
    UVSphere,
)

PARAMETRIC = [Plane(), Plane((2.0, 0.5)), UVSphere(1.5), Cylinder(0.5, 2.0), Torus(1.0, 0.3)]
IDS = ["plane", "plane2x05", "sphere", "cylinder", "torus"]


def dot(a, b):
    return np.einsum("ij,ij->i", a, b)


def assert_frame(state, atol=1e-12):
    """Unit, mutually orthogonal, right-handed (tu x tv = n), finite."""
    for a in (state.position, state.normal, state.tangent_u, state.tangent_v, state.uv):
        assert np.all(np.isfinite(a))
    for a in (state.normal, state.tangent_u, state.tangent_v):
        np.testing.assert_allclose(np.linalg.norm(a, axis=1), 1.0, atol=atol)
    np.testing.assert_allclose(dot(state.normal, state.tangent_u), 0.0, atol=atol)
    np.testing.assert_allclose(dot(state.normal, state.tangent_v), 0.0, atol=atol)
    np.testing.assert_allclose(dot(state.tangent_u, state.tangent_v), 0.0, atol=atol)
    np.testing.assert_allclose(np.cross(state.tangent_u, state.tangent_v), state.normal, atol=atol)


# ---------------------------------------------------------------- parametric surfaces


def test_default_plane_is_the_unit_square():
    uv = np.array([[0.0, 0.0], [1.0, 1.0], [0.25, 0.75], [-0.5, 2.0]])
    a, b = Plane().state_at_uv(uv), UnitSquare().state_at_uv(uv)
    for name in ("position", "normal", "uv", "tangent_u", "tangent_v"):
        np.testing.assert_array_equal(getattr(a, name), getattr(b, name))
    assert not Plane().periodic_u and not Plane().periodic_v


def test_plane_size_origin_axes():
    p = Plane((2.0, 3.0), origin=(1.0, 0.0, 0.0), axis_u=(0, 0, -1), axis_v=(0, 1, 0))
    s = p.state_at_uv(np.array([[0.5, 1.0]]))
    np.testing.assert_allclose(s.position, [[1.0, 3.0, -1.0]])
    np.testing.assert_allclose(s.normal, [[1.0, 0.0, 0.0]])   # (-z) x y = +x
    assert_frame(s)


@pytest.mark.parametrize("kwargs", [
    {"size": (0.0, 1.0)}, {"size": (1.0, -2.0)}, {"axis_u": (1, 1, 0)},
    {"axis_v": (1, 0, 0)}, {"resolution": (0, 1)}, {"origin": (np.nan, 0, 0)},
])
def test_plane_bad_arguments(kwargs):
    with pytest.raises(ValueError):
        Plane(**kwargs)


@pytest.mark.parametrize("factory", [
    lambda: UVSphere(0.0), lambda: UVSphere(-1.0), lambda: Cylinder(1.0, 0.0),
    lambda: Cylinder(np.inf, 1.0), lambda: Torus(0.0, 0.1), lambda: Torus(1.0, -0.1),
])
def test_bad_radii(factory):
    with pytest.raises(ValueError, match="> 0"):
        factory()


@pytest.mark.parametrize("uv", [np.array([[np.nan, 0.0]]), np.zeros((3, 3)), np.zeros(5)])
def test_bad_uv(uv):
    with pytest.raises(ValueError):
        UVSphere().state_at_uv(uv)


def test_sphere_analytic_points():
    r = 1.5
    uv = np.array([[0.0, 0.5], [0.25, 0.5], [0.5, 0.5], [0.1, 0.0], [0.1, 1.0]])
    s = UVSphere(r).state_at_uv(uv)
    np.testing.assert_allclose(
        s.position,
        [[r, 0, 0], [0, 0, -r], [-r, 0, 0], [0, -r, 0], [0, r, 0]], atol=1e-15,
    )
    # equator at u = 0: tangent_u = -z, tangent_v = +y, normal = +x
    np.testing.assert_allclose(s.tangent_u[0], [0, 0, -1], atol=1e-15)
    np.testing.assert_allclose(s.tangent_v[0], [0, 1, 0], atol=1e-15)


def _finite_difference_frame(surface, uv, h=1e-6):
    du = surface.state_at_uv(uv + [h, 0]).position - surface.state_at_uv(uv - [h, 0]).position
    dv = surface.state_at_uv(uv + [0, h]).position - surface.state_at_uv(uv - [0, h]).position
    return (du / np.linalg.norm(du, axis=1)[:, None], dv / np.linalg.norm(dv, axis=1)[:, None])


@pytest.mark.parametrize("surface", PARAMETRIC, ids=IDS)
def test_tangents_are_normalized_derivatives(surface):
    rng = np.random.default_rng(1)
    uv = rng.uniform(0.05, 0.95, (50, 2))
    s = surface.state_at_uv(uv)
    tu, tv = _finite_difference_frame(surface, uv)
    np.testing.assert_allclose(s.tangent_u, tu, atol=1e-8)
    np.testing.assert_allclose(s.tangent_v, tv, atol=1e-8)
    assert_frame(s)


@pytest.mark.parametrize("surface", PARAMETRIC[2:], ids=IDS[2:])
def test_normal_is_outward(surface):
    rng = np.random.default_rng(2)
    s = surface.state_at_uv(rng.uniform(0, 1, (100, 2)))
    if isinstance(surface, Torus):
        radial = s.position.copy()
        radial[:, 1] = 0
        ring = surface.major * radial / np.linalg.norm(radial, axis=1)[:, None]
        outward = s.position - ring
    else:
        outward = s.position.copy()
        if isinstance(surface, Cylinder):
            outward[:, 1] = 0
    assert np.all(dot(outward, s.normal) > 0)


def test_sphere_poles_frames_are_limits():
    sphere = UVSphere(2.0)
    u = np.linspace(-1.0, 2.0, 61)
    for v_pole, sign in ((0.0, -1.0), (1.0, 1.0)):
        s = sphere.state_at_uv(np.stack([u, np.full_like(u, v_pole)], 1))
        assert_frame(s)
        np.testing.assert_array_equal(s.position, np.tile([0.0, 2.0 * sign, 0.0], (len(u), 1)))
        np.testing.assert_array_equal(s.normal, np.tile([0.0, sign, 0.0], (len(u), 1)))
        # the limit along the meridian of each u
        eps = 1e-9
        near = sphere.state_at_uv(np.stack([u, np.full_like(u, abs(v_pole - eps))], 1))
        np.testing.assert_allclose(s.tangent_u, near.tangent_u, atol=1e-8)
        np.testing.assert_allclose(s.tangent_v, near.tangent_v, atol=1e-8)
        np.testing.assert_allclose(s.normal, near.normal, atol=1e-8)


def test_sphere_v_outside_is_clamped():
    sphere = UVSphere()
    s = sphere.state_at_uv(np.array([[0.3, -0.5], [0.3, 1.7], [0.3, -1e300]]))
    ref = sphere.state_at_uv(np.array([[0.3, 0.0], [0.3, 1.0], [0.3, 0.0]]))
    np.testing.assert_array_equal(s.position, ref.position)
    np.testing.assert_array_equal(s.tangent_v, ref.tangent_v)
    np.testing.assert_array_equal(s.uv, [[0.3, -0.5], [0.3, 1.7], [0.3, -1e300]])  # as asked


def test_cylinder_v_extrapolates():
    s = Cylinder(1.0, 2.0).state_at_uv(np.array([[0.0, 1.5], [0.0, -1.0]]))
    np.testing.assert_allclose(s.position, [[1.0, 2.0, 0.0], [1.0, -3.0, 0.0]], atol=1e-15)


@pytest.mark.parametrize(
    "surface", [s for s in PARAMETRIC if s.periodic_u], ids=["sphere", "cylinder", "torus"]
)
def test_seams_are_bit_identical(surface):
    v = np.linspace(0.0, 1.0, 17)
    a = surface.state_at_uv(np.stack([np.zeros_like(v), v], 1))
    for shift in (1.0, -1.0, 3.0, -7.0):
        b = surface.state_at_uv(np.stack([np.full_like(v, shift), v], 1))
        for name in ("position", "normal", "tangent_u", "tangent_v"):
            np.testing.assert_array_equal(getattr(a, name), getattr(b, name))
        np.testing.assert_array_equal(b.uv[:, 0], shift)          # uv reported unwrapped
    # a negative u is the same point as its fractional part
    c = surface.state_at_uv(np.array([[-0.25, 0.4]]))
    d = surface.state_at_uv(np.array([[0.75, 0.4]]))
    np.testing.assert_allclose(c.position, d.position, atol=1e-15)


def test_torus_v_seam():
    t = Torus(1.0, 0.3)
    u = np.linspace(0, 1, 9)
    a = t.state_at_uv(np.stack([u, np.zeros_like(u)], 1))
    b = t.state_at_uv(np.stack([u, np.ones_like(u)], 1))
    np.testing.assert_array_equal(a.position, b.position)
    np.testing.assert_array_equal(a.normal, b.normal)
    assert t.periodic_u and t.periodic_v


def test_spindle_torus_frame_is_defined():
    s = Torus(0.2, 0.5).state_at_uv(np.random.default_rng(3).uniform(0, 1, (200, 2)))
    assert_frame(s)


@settings(max_examples=60)
@given(arrays(np.float64, (16, 2), elements=st.floats(-1e6, 1e6)))
def test_property_frames_everywhere(uv):
    for surface in PARAMETRIC:
        assert_frame(surface.state_at_uv(uv), atol=1e-9)


@settings(max_examples=30)
@given(st.sampled_from([0.0, 1.0, 0.5, 1e-300, -1e-300, 1 - 1e-16, 1e-16]),
       st.sampled_from([0.0, 1.0, 0.5, 1e-300, 1 - 1e-16, 1e-16, -0.0]))
def test_property_extreme_uv(u, v):
    for surface in PARAMETRIC:
        assert_frame(surface.state_at_uv(np.array([[u, v]])), atol=1e-12)


# ---------------------------------------------------------------- base meshes


@pytest.mark.parametrize("surface,nu,nv", [
    (Plane(), 4, 3), (UVSphere(1.5), 12, 6), (Cylinder(0.5, 2.0), 10, 2), (Torus(1.0, 0.3), 12, 6),
])
def test_base_mesh_matches_surface(surface, nu, nv):
    mesh = surface.base_mesh(nu, nv)
    uv = mesh.visual.uv
    state = surface.state_at_uv(uv)
    np.testing.assert_array_equal(mesh.vertices, state.position)
    np.testing.assert_allclose(mesh.vertex_normals, state.normal, atol=1e-12)
    # counter-clockwise seen from the normal side
    assert np.all(dot(mesh.face_normals, mesh.vertex_normals[mesh.faces].mean(axis=1)) > 0)
    # no face straddles a seam: uv is continuous inside every face
    span = np.ptp(uv[mesh.faces], axis=1)
    assert np.all(span[:, 0] <= 1.0 / nu + 1e-12)
    assert np.all(span[:, 1] <= 1.0 / nv + 1e-12)
    assert np.all(mesh.area_faces > 0)


@pytest.mark.parametrize("surface,default", [
    (Plane(resolution=(3, 2)), (3, 2)), (UVSphere(), (32, 16)), (Cylinder(), (32, 1)),
    (Torus(), (48, 16)),
])
def test_base_grid_is_the_base_mesh_without_trimesh(surface, default):
    """The renderer's path (``base_grid``, then ``state_at_uv``) makes the base mesh's
    triangles, at the given resolution and at the surface's default."""
    for res in ((6, 4), (None, None)):
        uv, faces = surface.base_grid(*res)
        mesh = surface.base_mesh(*res)
        np.testing.assert_array_equal(uv, mesh.visual.uv)
        np.testing.assert_array_equal(faces, mesh.faces)
        assert faces.dtype == np.int64
    assert surface.base_grid()[0].shape == surface.base_grid(*default)[0].shape


def test_sphere_mesh_counts_poles_and_volume():
    nu, nv = 64, 32
    mesh = UVSphere(1.3).base_mesh(nu, nv)
    assert len(mesh.vertices) == 2 * nu + (nv - 1) * (nu + 1)
    assert len(mesh.faces) == 2 * nu * (nv - 1)
    poles = mesh.visual.uv[:, 1] == 0.0
    np.testing.assert_allclose(mesh.visual.uv[poles, 0], (np.arange(nu) + 0.5) / nu)
    merged = mesh.copy()
    merged.merge_vertices(merge_tex=True, merge_norm=True)
    assert merged.is_watertight
    exact = 4 / 3 * math.pi * 1.3**3
    assert abs(merged.volume - exact) / exact < 0.005        # inscribed polyhedron
    assert merged.volume < exact


def test_torus_mesh_is_closed():
    merged = Torus(1.0, 0.3).base_mesh(48, 16)
    merged.merge_vertices(merge_tex=True, merge_norm=True)
    assert merged.is_watertight
    exact = 2 * math.pi**2 * 1.0 * 0.3**2
    assert abs(merged.volume - exact) / exact < 0.03


@pytest.mark.parametrize("surface,nu,nv", [
    (UVSphere(), 2, 4), (UVSphere(), 8, 1), (Torus(), 2, 3), (Cylinder(), 3, 0), (Plane(), 1.5, 2),
])
def test_base_mesh_bad_resolution(surface, nu, nv):
    with pytest.raises(ValueError, match="base_mesh needs"):
        surface.base_mesh(nu, nv)


# ---------------------------------------------------------------- mesh surfaces


def test_mesh_surface_reproduces_plane():
    plane = Plane((2.0, 1.0), resolution=(3, 2))
    ms = MeshSurface(plane.base_mesh())
    rng = np.random.default_rng(4)
    faces = rng.integers(0, len(ms.mesh.faces), 40)
    bary = rng.dirichlet([1, 1, 1], 40)
    s = ms.state_at(faces, bary)
    ref = plane.state_at_uv(s.uv)
    np.testing.assert_allclose(s.position, ref.position, atol=1e-14)
    np.testing.assert_allclose(s.normal, ref.normal, atol=1e-14)
    np.testing.assert_allclose(s.tangent_u, ref.tangent_u, atol=1e-14)
    np.testing.assert_allclose(s.tangent_v, ref.tangent_v, atol=1e-14)


def test_mesh_surface_on_sphere_mesh():
    sphere = UVSphere(1.0)
    ms = MeshSurface(sphere.base_mesh(64, 32), normals="smooth")
    rng = np.random.default_rng(5)
    faces = rng.integers(0, len(ms.mesh.faces), 500)
    s = ms.state_at(faces, rng.dirichlet([1, 1, 1], 500))
    assert_frame(s)
    ref = sphere.state_at_uv(s.uv)
    assert np.all(dot(s.normal, ref.normal) > 0.995)
    assert np.all(dot(s.tangent_u, ref.tangent_u) > 0.97)


def test_mesh_surface_smooth_normals_weld_seams():
    mesh = UVSphere().base_mesh(8, 4)
    # corrupt one copy of a seam vertex's normal: "smooth" averages it with its twin
    seam = np.flatnonzero(mesh.visual.uv[:, 0] == 1.0)[1]
    twin = np.flatnonzero(np.all(mesh.vertices == mesh.vertices[seam], axis=1))
    assert len(twin) == 2
    normals = mesh.vertex_normals.copy()
    normals[seam] = [0.0, 0.0, 1.0]
    bent = trimesh.Trimesh(mesh.vertices, mesh.faces, vertex_normals=normals,
                           visual=mesh.visual, process=False)
    welded = MeshSurface(bent, normals="smooth")._vertex_normal
    np.testing.assert_allclose(welded[twin[0]], welded[twin[1]])
    # the nu copies of each pole are one position, welded to one normal
    for v_pole in (0.0, 1.0):
        pole = mesh.visual.uv[:, 1] == v_pole
        assert len({row.tobytes() for row in mesh.vertices[pole]}) == 1     # no signed zeros
        assert np.all(welded[pole] == welded[pole][0])


def test_mesh_surface_mirrored_and_degenerate_uv():
    vertices = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0], [1, 1, 0.0]])
    faces = np.array([[0, 1, 2], [1, 3, 2]])
    # mirrored u: u decreases along +x
    uv = np.array([[1, 0], [0, 0], [1, 1], [0, 1.0]])
    ms = MeshSurface(trimesh.Trimesh(vertices, faces, visual=trimesh.visual.TextureVisuals(uv=uv),
                                     process=False), normals="face")
    s = ms.state_at(np.array([0, 1]), np.full((2, 3), 1 / 3))
    np.testing.assert_allclose(s.tangent_u, [[-1, 0, 0]] * 2, atol=1e-15)
    np.testing.assert_allclose(s.tangent_v, [[0, 1, 0]] * 2, atol=1e-15)   # follows +v
    np.testing.assert_allclose(s.normal, [[0, 0, 1]] * 2)
    # all uv equal: degenerate uv, and a zero-area face
    flat_uv = np.zeros((4, 2))
    sliver = np.array([[0, 1, 1]])
    for fs, uvs in ((faces, flat_uv), (sliver, uv)):
        ms = MeshSurface(trimesh.Trimesh(vertices, fs, visual=trimesh.visual.TextureVisuals(uv=uvs),
                                         process=False))
        s = ms.state_at(np.zeros(3, dtype=int), np.array([[1, 0, 0], [0.2, 0.3, 0.5], [0, 0, 1.0]]))
        assert_frame(s)


def test_mesh_surface_errors():
    box = trimesh.creation.box()
    with pytest.raises(ValueError, match="mesh.visual.uv"):
        MeshSurface(box)
    cube = Cube()
    with pytest.raises(TypeError, match="state_at\\(face_index, barycentric\\)"):
        cube.state_at_uv(np.array([[0.5, 0.5]]))
    with pytest.raises(ValueError, match="out of range"):
        cube.state_at(np.array([12]), np.array([[1, 0, 0.0]]))
    with pytest.raises(ValueError, match="shape"):
        cube.state_at(np.array([0, 1]), np.array([[1, 0, 0.0]]))
    with pytest.raises(ValueError, match="normals"):
        MeshSurface(cube.mesh, normals="round")
    # a tessellator tells the kinds apart by is_mesh (a mesh surface still has state_at_uv)
    assert cube.is_mesh and not any(surface.is_mesh for surface in PARAMETRIC)


def test_cube_charts():
    cube = Cube(2.0, resolution=3)
    assert len(cube.charts) == 6 and len(cube.mesh.faces) == 6 * 2 * 9
    rng = np.random.default_rng(6)
    faces = np.arange(len(cube.mesh.faces))
    s = cube.state_at(faces, rng.dirichlet([1, 1, 1], len(faces)))
    assert_frame(s)
    assert np.all(s.uv >= 0) and np.all(s.uv <= 1)
    np.testing.assert_allclose(np.max(np.abs(s.position), axis=1), 1.0)
    np.testing.assert_allclose(dot(s.position, s.normal), 1.0)           # outward faces
    for chart_index, chart in enumerate(cube.charts):
        mask = cube.chart_of_face == chart_index
        ref = chart.state_at_uv(s.uv[mask])
        np.testing.assert_allclose(s.position[mask], ref.position, atol=1e-14)
        np.testing.assert_allclose(s.tangent_u[mask], ref.tangent_u, atol=1e-14)
        np.testing.assert_allclose(s.tangent_v[mask], ref.tangent_v, atol=1e-14)
    # sides have v up
    for name in ("+x", "-x", "+z", "-z"):
        assert cube.charts[Cube.CHART_NAMES.index(name)].axis_v.tolist() == [0, 1, 0]
    merged = cube.mesh.copy()
    merged.merge_vertices(merge_tex=True, merge_norm=True)
    assert merged.is_watertight
    assert merged.volume == pytest.approx(8.0)
