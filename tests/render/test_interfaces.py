"""The IOR on each side of an interface: total internal reflection, objects nested in
other objects (Handbook §5.8) and in volumes, and the medium stack along paths."""

from __future__ import annotations

import math

import numpy as np
import pytest
import trimesh

from displacement.surfaces import Cube, MeshSurface, Plane, UVSphere
from render import material as M
from render.camera import Camera
from render.df._kernel_common import fresnel_dielectric
from render.integrator import Integrator, render
from render.lights import ConstantEnvironment, PointLight
from render.scene import RenderSettings, Scene, SceneObject, emissive_material, make_transform


def dielectric(ior, mode="scatter_reflect_transmit", sigma_a=0.0, sigma_s=0.0):
    return M.material(
        ior=(ior,) * 3,
        surface=M.material_surface(M.df.specular_bsdf(mode=mode)),
        volume=M.material_volume(absorption_coefficient=sigma_a, scattering_coefficient=sigma_s),
    )


def prism(length=4.0) -> MeshSurface:
    """A right isosceles prism along z: top face y = 0.5 (normal +y), side x = 0.5
    (normal +x), hypotenuse x + y = 0 (normal (-1, -1, 0) / sqrt 2); flat faces."""
    a, b, c = (-0.5, 0.5), (0.5, 0.5), (0.5, -0.5)  # the right angle at b
    z0, z1 = -length / 2, length / 2

    def p(xy, z):
        return [xy[0], xy[1], z]

    tris = [[p(a, z1), p(c, z1), p(b, z1)], [p(a, z0), p(b, z0), p(c, z0)]]
    for s, e in ((a, b), (b, c), (c, a)):
        tris += [[p(s, z0), p(e, z1), p(e, z0)], [p(s, z0), p(s, z1), p(e, z1)]]
    v = np.array(tris, dtype=float).reshape(-1, 3)
    mesh = trimesh.Trimesh(v, np.arange(len(v)).reshape(-1, 3), process=False)
    mesh.visual = trimesh.visual.TextureVisuals(uv=np.zeros((len(v), 2)))
    return MeshSurface(mesh, normals="face")


def lamp(le, x=3.0):
    """A large emitter in the plane x facing -x."""
    plane = Plane(size=(8, 8), origin=(x, -4.0, 4.0), axis_u=(0, 1, 0), axis_v=(0, 0, -1))
    return SceneObject(plane, emissive_material(np.full(3, np.pi * le)), name="lamp")


def down_camera(res=16, ortho=0.5):
    return Camera(position=(0, 3, 0), look_at=(0, 0, 0), up=(0, 0, -1), width=res, height=res,
                  ortho_height=ortho)


def fresnel(cos, eta):
    return fresnel_dielectric(float(cos), float(eta))[0]


def mean_err(img):
    px = img[..., 0].ravel()
    return px.mean(), px.std(ddof=1) / math.sqrt(len(px))


def test_prism_geometry():
    m = prism().mesh
    n = np.round(m.face_normals, 6)
    assert {tuple(x) for x in n} == {(0, 0, 1), (0, 0, -1), (0, 1, 0), (1, 0, 0),
                                     (-0.707107, -0.707107, 0)}
    welded = m.copy()
    welded.merge_vertices()
    assert welded.is_watertight and welded.volume > 0  # closed, normals outward


def test_total_internal_reflection_in_a_prism():
    # looking down into the prism: the hypotenuse at 45 degrees exceeds glass's critical
    # angle (41.8 degrees) and reflects everything toward the lamp on +x; the two faces at
    # normal incidence pass 1 - F0 each, and light going back and forth between them
    # sums to Le (1 - F0) / (1 + F0), F0 = 0.04
    le = 2.0
    scene = Scene(down_camera(), [SceneObject(prism(), dielectric(1.5)), lamp(le)], [],
                  RenderSettings(16, 16, spp=16, max_depth=-1, rr_depth=1000))
    img = render(scene, progress=False).rgb() / le
    mean, err = mean_err(img)
    want = 0.96 / 1.04
    assert abs(mean - want) < 4 * err, (mean, want, err)
    assert np.all(np.isfinite(img))


def test_no_total_internal_reflection_in_water():
    # the same prism inside a box of water (1.33): its critical angle is 62.5 degrees,
    # so the hypotenuse now reflects only F(45 deg, 1.33 / 1.5) ~ 1 %: the lamp nearly
    # vanishes (the outside IOR of the prism is the water's, from the medium stack)
    le = 2.0
    water = SceneObject(Cube(1.0), dielectric(1.33), make_transform(scale=(2.0, 2.0, 5.0)),
                        name="water")
    scene = Scene(down_camera(), [SceneObject(prism(), dielectric(1.5)), water, lamp(le)], [],
                  RenderSettings(16, 16, spp=32, max_depth=-1, rr_depth=1000))
    img = render(scene, progress=False).rgb() / le
    mean, err = mean_err(img)
    # the main path: into the water and the glass at normal incidence, reflected by the
    # hypotenuse, out through glass and water at normal incidence
    f_aw = fresnel(1.0, 1.33)
    f_wg = fresnel(1.0, 1.5 / 1.33)
    r45 = fresnel(math.cos(math.pi / 4), 1.33 / 1.5)
    main = (1 - f_aw) ** 2 * (1 - f_wg) ** 2 * r45
    assert 0.005 < r45 < 0.02
    assert abs(mean - main) < 4 * err + 0.15 * main, (mean, main, err)


def _stack_transmittance(layers):
    """Incoherent transmittance of stacked layers (reflectance, transmittance), each
    the same from both sides: the adding formula."""
    r, t = layers[0]
    for r2, t2 in layers[1:]:
        t, r = t * t2 / (1 - r * r2), r + t * t * r2 / (1 - r * r2)
    return t


@pytest.mark.parametrize("nested", [True, False])
def test_nested_slabs_use_the_outside_ior(nested):
    # a glass slab (1.5) inside a water box (1.33), seen at normal incidence against a
    # lamp below: every interface transmits 1 - F with F from the IORs on its two
    # sides (water/glass inside the box, not air/glass), and reflections between the
    # four interfaces add up incoherently
    le = 1.0
    objs = [
        SceneObject(Cube(1.0), dielectric(1.5), make_transform(scale=(3.0, 0.3, 3.0)),
                    name="glass"),
        SceneObject(Plane(size=(10, 10), origin=(-5, -2, 5), axis_u=(1, 0, 0), axis_v=(0, 0, -1)),
                    emissive_material(np.full(3, np.pi * le)), name="lamp"),
    ]
    if nested:
        objs.append(SceneObject(Cube(1.0), dielectric(1.33), make_transform(scale=(4.0, 1.0, 4.0)),
                                name="water"))
    scene = Scene(down_camera(), objs, [], RenderSettings(16, 16, spp=32, max_depth=-1,
                                                          rr_depth=1000))
    img = render(scene, progress=False).rgb() / le
    mean, err = mean_err(img)
    if nested:
        fa, fg = fresnel(1.0, 1.33), fresnel(1.0, 1.5 / 1.33)
        want = _stack_transmittance([(fa, 1 - fa), (fg, 1 - fg), (fg, 1 - fg), (fa, 1 - fa)])
        wrong = _stack_transmittance([(fa, 1 - fa)] + [(0.04, 0.96)] * 2 + [(fa, 1 - fa)])
        assert abs(want - wrong) > 10 * err  # the test can tell air/glass from water/glass
    else:
        want = 0.96 / 1.04
    assert abs(mean - want) < 4 * err, (mean, want, err)


def test_media_of_nested_objects_along_a_ray():
    # an index-matched box of absorbing "liquid" holding a smaller box of another
    # absorber and an empty bubble (a closed object without a medium): straight down,
    # each length is attenuated by the medium of the innermost object around it
    s_out, s_in = np.array([0.4, 1.0, 2.0]), np.array([3.0, 0.5, 0.0])
    outer = SceneObject(Cube(1.0), dielectric(1.0, "scatter_transmit", sigma_a=tuple(s_out)),
                        make_transform(scale=(3.0, 1.0, 3.0)), name="liquid")
    inner = SceneObject(Cube(1.0), dielectric(1.0, "scatter_transmit", sigma_a=tuple(s_in)),
                        make_transform(translate=(-0.5, 0.1, 0), scale=(0.6, 0.4, 2.0)),
                        name="inner")
    bubble = SceneObject(Cube(1.0), dielectric(1.0, "scatter_transmit"),
                         make_transform(translate=(0.5, -0.1, 0), scale=(0.6, 0.5, 2.0)),
                         name="bubble")
    cam = Camera(position=(0, 3, 0), look_at=(0, 0, 0), up=(0, 0, -1), width=20, height=4,
                 ortho_height=0.3)  # a strip across both inner boxes
    scene = Scene(cam, [outer, inner, bubble], [ConstantEnvironment(1.0)],
                  RenderSettings(20, 4, spp=1, max_depth=-1))
    integ = Integrator(scene, scene.build())
    assert integ.encloses.tolist() == [True, True, True]  # the bubble is a vacuum inside
    img = integ.render(progress=False).rgb()
    x = (np.arange(20) + 0.5) / 20 * 1.5 - 0.75
    want = np.where((np.abs(x + 0.5) < 0.3)[:, None], np.exp(-s_out * 0.6 - s_in * 0.4),
                    np.where((np.abs(x - 0.5) < 0.3)[:, None], np.exp(-s_out * 0.5),
                             np.exp(-s_out * 1.0)))
    inside = (np.abs(np.abs(x) - 0.5) < 0.25) | (np.abs(x) > 0.85) | (np.abs(x) < 0.15)
    assert np.allclose(img[1, inside], want[inside], rtol=1e-6), (img[1], want)


def test_objects_inside_volumes_can_be_lit_and_seen():
    # Handbook 5.8: a diffuse sphere inside a scattering fog box with a point light in the
    # fog; the image is finite, non-negative, and the sphere's shadow side is darker
    fog = SceneObject(Cube(1.0), dielectric(1.0, "scatter_transmit", sigma_a=0.2, sigma_s=1.5),
                      make_transform(scale=3.0), name="fog")
    ball = SceneObject(UVSphere(0.4), M.material(surface=M.material_surface(
        M.df.diffuse_reflection_bsdf(tint=0.8))), name="ball")
    cam = Camera(position=(0, 0, 4), look_at=(0, 0, 0), width=32, height=24, fov_y_deg=30)
    scene = Scene(cam, [fog, ball], [PointLight((-0.9, 0.6, 0.5), 4.0)],
                  RenderSettings(32, 24, spp=4, max_depth=6))
    film = render(scene, progress=False, aovs=["object_id"])
    img = film.rgb()
    assert np.all(np.isfinite(img)) and img.min() >= 0 and img.mean() > 0.01
    # the fog is lit too (single and multiple scattering around the light)
    assert img[2, 16].sum() > 0


def test_extreme_interfaces_make_no_nan():
    # dense chromatic media, grazing views, a TIR-heavy high IOR, nested glass in glass
    objs = [
        SceneObject(UVSphere(1.0),
                    dielectric(2.4, sigma_a=(0.0, 5.0, 50.0), sigma_s=(30.0, 0.0, 1.0))),
        SceneObject(UVSphere(0.4), dielectric(1.0001, sigma_s=(0.5, 0.5, 0.5))),
        SceneObject(Cube(1.0), dielectric(3.0, "scatter_transmit"),
                    make_transform(translate=(1.5, 0, 0), rotate=(30, 40, 0), scale=0.8)),
    ]
    cam = Camera(position=(0, 0.2, 3.5), look_at=(0, 0, 0), width=24, height=16, fov_y_deg=60)
    scene = Scene(cam, objs, [ConstantEnvironment(1.0), PointLight((2, 2, 2), 5.0)],
                  RenderSettings(24, 16, spp=4, max_depth=12))
    img = render(scene, progress=False).rgb()
    assert np.all(np.isfinite(img)) and img.min() >= 0
