"""thin_walled materials in the path tracer: transmission without refraction, the
backface on the back side, emission only where MDL allows it, no volume inside."""

from __future__ import annotations

import math

import numpy as np
import pytest

from displacement.surfaces import Plane
from render import material as M
from render.camera import Camera
from render.df._kernel_common import fresnel_dielectric
from render.integrator import render
from render.lights import DirectionalLight
from render.scene import RenderSettings, Scene, SceneObject, emissive_material, make_transform

RES = 24


def specular(mode="scatter_transmit", tint=1.0):
    return M.material_surface(M.df.specular_bsdf(tint=tint, mode=mode))


def backdrop(z=-1.0, varying=True):
    """A 4 x 4 emitter in the plane z facing +z, with a smooth pattern of radiance."""
    plane = Plane(size=(4.0, 4.0), origin=(-2.0, -2.0, z))
    if not varying:
        return SceneObject(plane, emissive_material(np.full(3, np.pi)), name="backdrop")

    def intensity(state):
        u, v = state.uv[:, 0], state.uv[:, 1]
        r = 1.0 + 0.5 * np.sin(6 * u) * np.cos(5 * v)
        return np.pi * np.stack([r, 0.5 * r + 0.3, 1.5 - 0.4 * r], axis=1)

    mat = M.material(surface=M.material_surface(
        emission=M.material_emission(M.df.diffuse_edf(), intensity=intensity)))
    return SceneObject(plane, mat, name="backdrop")


def pane(material, rotate=(0.0, 35.0, 0.0), z=0.0):
    """A 2 x 2 square at z, turned about y (its front faces +z before turning)."""
    return SceneObject(Plane(size=(2.0, 2.0), origin=(-1.0, -1.0, 0.0)), material,
                       make_transform(translate=(0, 0, z), rotate=rotate), name="pane")


def camera(z=3.0, ortho=None):
    return Camera(position=(0, 0, z), look_at=(0, 0, 0), width=RES, height=RES, fov_y_deg=25,
                  ortho_height=ortho)


def image(objects, cam=None, spp=2, lights=(), max_depth=8, seed=0):
    scene = Scene(cam or camera(), objects, list(lights), RenderSettings(RES, RES, spp=spp,
                                                                        max_depth=max_depth))
    return render(scene, progress=False, seed=seed).rgb()


def test_thin_walled_transmission_leaves_the_background_undistorted():
    plain = image([backdrop()])
    thin = M.material(thin_walled=True, ior=(1.5,) * 3, surface=specular())
    through = image([backdrop(), pane(thin)])
    # the same samples, the same directions: the pane is invisible (up to the ray
    # offset, 1e-5 of the scene's size, which moves the ray on the smooth pattern)
    assert np.allclose(through, plain, rtol=1e-4, atol=0), np.abs(through / plain - 1).max()
    # the same pane as an interface (not thin-walled) refracts: the background shifts
    solid = M.material(ior=(1.5,) * 3, surface=specular())
    bent = image([backdrop(), pane(solid)])
    assert np.abs(bent - plain).max() > 0.1


def test_thin_walled_fresnel_without_refraction():
    # reflect_transmit at a fixed angle (orthographic view, pane turned 35 degrees):
    # the background arrives times 1 - F(35 degrees, 1.5), the pattern unshifted
    thin = M.material(thin_walled=True, ior=(1.5,) * 3,
                      surface=specular("scatter_reflect_transmit"))
    cam = camera(ortho=1.0)
    plain = image([backdrop(varying=False)], cam)
    through = image([backdrop(varying=False), pane(thin)], cam, spp=16)
    F = fresnel_dielectric(math.cos(math.radians(35.0)), 1.5)[0]
    ratio = through / plain
    assert np.all(np.isfinite(ratio))
    mean = ratio.mean()
    err = ratio.std() / math.sqrt(ratio.size / 3)
    assert abs(mean - (1 - F)) < 4 * err, (mean, 1 - F, err)
    # every sample either passed (weight 1) or reflected into the black sky
    assert set(np.unique(np.round(ratio * 16)).tolist()) <= set(range(17))


def test_backface_shades_the_back_side():
    front_tint, back_tint = (0.9, 0.5, 0.2), (0.1, 0.6, 0.8)
    two = M.material(thin_walled=True, surface=specular(tint=front_tint),
                     backface=specular(tint=back_tint))
    one = M.material(thin_walled=True, surface=specular(tint=front_tint))
    plain_front = image([backdrop()])
    # from the back: the camera at -z looks through the pane's back at a backdrop facing -z
    back_drop = SceneObject(Plane(size=(4.0, 4.0), origin=(-2.0, -2.0, 1.0), axis_u=(0, 1, 0),
                                  axis_v=(1, 0, 0)), emissive_material(np.full(3, np.pi)))
    cam_back = Camera(position=(0, 0, -3), look_at=(0, 0, 0), width=RES, height=RES,
                      fov_y_deg=25)
    plain_back = image([back_drop], cam_back)
    for mat, want_front, want_back in ((two, front_tint, back_tint),
                                       (one, front_tint, front_tint)):
        got_front = image([backdrop(), pane(mat)])
        got_back = image([back_drop, pane(mat)], cam_back)
        seen = np.abs(got_front - plain_front).max(axis=2) > 0  # pixels through the pane
        assert seen.mean() > 0.3
        assert np.allclose(got_front[seen], plain_front[seen] * want_front, rtol=1e-4)
        seen_b = np.abs(got_back - plain_back).max(axis=2) > 0
        assert seen_b.mean() > 0.3
        assert np.allclose(got_back[seen_b], plain_back[seen_b] * want_back, rtol=1e-4)


@pytest.mark.parametrize(
    ("thin_walled", "backface_edf", "want_front", "want_back"),
    [
        (False, False, 2.0, 0.0),  # an interface emits on its front only
        (True, False, 2.0, 0.0),  # thin, default backface: surface.emission front only
        (True, True, 2.0, 0.5),  # thin with a backface edf: each side its own
    ],
)
def test_emission_only_where_mdl_allows(thin_walled, backface_edf, want_front, want_back):
    edf = M.df.diffuse_edf()
    surface = M.material_surface(emission=M.material_emission(edf, intensity=2.0 * math.pi))
    backface = (M.material_surface(emission=M.material_emission(edf, intensity=0.5 * math.pi))
                if backface_edf else M.material_surface())
    mat = M.material(thin_walled=thin_walled, surface=surface, backface=backface)
    square = SceneObject(Plane(size=(4, 4), origin=(-2, -2, 0)), mat)
    for z, want in ((2.0, want_front), (-2.0, want_back)):
        cam = Camera(position=(0, 0, z), look_at=(0, 0, 0), width=8, height=8, fov_y_deg=20)
        img = image([square], cam)
        assert np.allclose(img, want, rtol=1e-12), (z, img.mean(), want)


def test_thin_walled_diffuse_transmission_is_lit_from_behind():
    # a lampshade: thin-walled diffuse_transmission_bsdf(tint) lit by a sun behind it;
    # seen from the front, L = tint / pi * E cos(theta_sun), by next-event estimation
    # through the sheet (no medium, no refraction)
    tint, E, theta = 0.7, 3.0, math.radians(40.0)
    shade = M.material(thin_walled=True, ior=(1.5,) * 3, surface=M.material_surface(
        M.df.diffuse_transmission_bsdf(tint=tint)))
    sheet = SceneObject(Plane(size=(4, 4), origin=(-2, -2, 0)), shade)
    sun = DirectionalLight((0.0, -math.sin(theta), -math.cos(theta)), E)  # from +z, behind
    cam = Camera(position=(0, 0, -2), look_at=(0, 0, 0), width=8, height=8, fov_y_deg=20)
    img = image([sheet], cam, lights=[sun], max_depth=2)
    assert np.allclose(img, tint / math.pi * E * math.cos(theta), rtol=1e-12)
