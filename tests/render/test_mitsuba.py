"""Side-by-side renders against Mitsuba 3 (``llvm_ad_rgb``) of equivalent scenes.

Each scene is described once (spheres, rectangles, materials, an area light and a
constant environment) and built both for this renderer and as a Mitsuba dict: emitters
get a black BSDF, one-sided diffuse is wrapped in ``twosided``, pixel samples are
box-filtered (``rfilter = box``), and Mitsuba's ``max_depth`` means what ours does.

Tolerances are measured, not guessed (docs/render.md, "Agreement with Mitsuba").  At
64x64 with 1024 spp (ours) and 4096 spp (Mitsuba) the relative differences of the means
were, over the whole image and over the sphere's pixels:

* diffuse sphere, area light + environment: 0.02 % and 0.04 % (both within noise);
* smooth dielectric sphere (specular_bsdf reflect_transmit vs ``dielectric``, ior 1.5):
  0.01 % and 0.08 % (within noise);
* glossy: MDL's simple_glossy_bsdf (Ashikhmin-Shirley with v-cavities masking, no
  Fresnel) has no exact Mitsuba twin; against ``roughconductor`` (Beckmann, alpha =
  roughness, F = 1) the sphere differs by 0.3 % at roughness 0.3 (0.26 % at 0.1, 4.3 %
  at 0.6, where the distributions and masking models part).

The tests render at low spp (two seeds each, whose difference gives the noise) and
allow 4 standard errors plus a systematic 0.1 % (diffuse), 0.2 % (glass) and 0.6 %
(glossy at roughness 0.3).
"""

from __future__ import annotations

import os

os.environ.setdefault("DRJIT_LIBLLVM_PATH", "/usr/lib/x86_64-linux-gnu/libLLVM-19.so")

import numpy as np  # noqa: E402
import pytest  # noqa: E402

from displacement.surfaces import Plane, UVSphere  # noqa: E402
from render import material as M  # noqa: E402
from render.camera import Camera  # noqa: E402
from render.integrator import render  # noqa: E402
from render.lights import ConstantEnvironment  # noqa: E402
from render.scene import RenderSettings, Scene, SceneObject, emissive_material, make_transform  # noqa: E402

RES = 64


@pytest.fixture(scope="module")
def mi():
    import mitsuba

    mitsuba.set_variant("llvm_ad_rgb")
    return mitsuba


def _rect(center, axis_u, axis_v, size):
    """Our Plane and Mitsuba's to_world matrix for a rectangle (normal axis_u x axis_v)."""
    au, av = np.asarray(axis_u, float), np.asarray(axis_v, float)
    c = np.asarray(center, float)
    n = np.cross(au, av)
    origin = c - 0.5 * (size[0] * au + size[1] * av)
    m = np.eye(4)
    m[:3, 0], m[:3, 1], m[:3, 2], m[:3, 3] = 0.5 * size[0] * au, 0.5 * size[1] * av, n, c
    return Plane(size=size, origin=tuple(origin), axis_u=tuple(au), axis_v=tuple(av)), m


def _ours_material(kind, params):
    if kind == "diffuse":
        return M.material(surface=M.material_surface(M.df.diffuse_reflection_bsdf(tint=params)))
    if kind == "glass":
        return M.material(
            ior=(params,) * 3,
            surface=M.material_surface(M.df.specular_bsdf(mode="scatter_reflect_transmit")),
        )
    if kind == "glossy":
        tint, r = params
        return M.material(
            surface=M.material_surface(M.df.simple_glossy_bsdf(tint=tint, roughness_u=r))
        )
    raise ValueError(kind)


def _mi_bsdf(kind, params):
    if kind == "diffuse":
        return {
            "type": "twosided",
            "b": {"type": "diffuse", "reflectance": {"type": "rgb", "value": list(params)}},
        }
    if kind == "glass":
        return {"type": "dielectric", "int_ior": float(params), "ext_ior": 1.0}
    if kind == "glossy":
        tint, r = params
        return {
            "type": "twosided",
            "b": {
                "type": "roughconductor",
                "material": "none",
                "distribution": "beckmann",
                "alpha": float(r),
                "specular_reflectance": {"type": "rgb", "value": list(tint)},
                "sample_visible": True,
            },
        }
    raise ValueError(kind)


def _stage(sphere_kind, sphere_params, env=0.3, light=6.0):
    """Floor, a sphere, a rectangular area light above-left; camera looking down a little."""
    cam = dict(origin=(0.0, 1.2, 3.5), target=(0.0, 0.4, 0.0), fov=35.0)
    floor, floor_m = _rect((0, 0, 0), (1, 0, 0), (0, 0, -1), (6.0, 6.0))
    lamp, lamp_m = _rect((-1.2, 2.5, 0.8), (1, 0, 0), (0, 0, 1), (1.0, 1.0))
    sphere = dict(center=(0.0, 0.5, 0.0), radius=0.5)
    ours = Scene(
        Camera(
            position=cam["origin"],
            look_at=cam["target"],
            fov_y_deg=cam["fov"],
            width=RES,
            height=RES,
        ),
        [
            SceneObject(floor, _ours_material("diffuse", (0.5, 0.5, 0.5)), name="floor"),
            SceneObject(
                UVSphere(sphere["radius"]),
                _ours_material(sphere_kind, sphere_params),
                make_transform(translate=sphere["center"]),
                name="sphere",
                resolution=(192, 96),
            ),
            SceneObject(lamp, emissive_material(np.full(3, np.pi * light)), name="lamp"),
        ],
        [ConstantEnvironment(env)],
        RenderSettings(RES, RES, spp=1, max_depth=8, rr_depth=5),
    )
    mdict = {
        "type": "scene",
        "integrator": {"type": "path", "max_depth": 8, "rr_depth": 5},
        "sensor": {
            "type": "perspective",
            "fov": cam["fov"],
            "fov_axis": "y",
            "to_world": None,
            "film": {
                "type": "hdrfilm",
                "width": RES,
                "height": RES,
                "rfilter": {"type": "box"},
                "pixel_format": "rgb",
            },
            "sampler": {"type": "independent"},
        },
        "floor": {
            "type": "rectangle",
            "to_world": floor_m,
            "bsdf": _mi_bsdf("diffuse", (0.5, 0.5, 0.5)),
        },
        "sphere": {
            "type": "sphere",
            "center": list(sphere["center"]),
            "radius": sphere["radius"],
            "bsdf": _mi_bsdf(sphere_kind, sphere_params),
        },
        "lamp": {
            "type": "rectangle",
            "to_world": lamp_m,
            "bsdf": {"type": "diffuse", "reflectance": {"type": "rgb", "value": [0.0, 0.0, 0.0]}},
            "emitter": {"type": "area", "radiance": {"type": "rgb", "value": [light] * 3}},
        },
        "env": {"type": "constant", "radiance": {"type": "rgb", "value": [env] * 3}},
    }
    return ours, mdict, cam


def _mitsuba_image(mi, mdict, cam, spp, seed=0):
    d = dict(mdict)
    d["sensor"] = dict(d["sensor"])
    d["sensor"]["to_world"] = mi.ScalarTransform4f().look_at(
        origin=list(cam["origin"]), target=list(cam["target"]), up=[0, 1, 0]
    )
    for key in ("floor", "lamp"):
        d[key] = dict(d[key])
        d[key]["to_world"] = mi.ScalarTransform4f(d[key]["to_world"].tolist())
    scene = mi.load_dict(d)
    return np.array(mi.render(scene, spp=spp, seed=seed), dtype=np.float64)


def _two(render_fn):
    """Mean of two renders with different seeds, and the standard deviation of one
    pixel's noise in it (from their difference)."""
    x, y = render_fn(1), render_fn(2)
    # one render's pixel noise is std(x - y) / sqrt(2); their mean has 1/sqrt(2) of it
    return 0.5 * (x + y), 0.5 * (x - y).reshape(-1, 3).std(axis=0)


def _compare(mi, kind, params, spp_ours, spp_mi, systematic):
    ours, mdict, cam = _stage(kind, params)
    sphere = render(ours, spp=1, progress=False, aovs=["object_id"]).aov("object_id") == 1
    a, na = _two(lambda seed: render(ours, spp=spp_ours, seed=seed, progress=False).rgb())
    b, nb = _two(lambda seed: _mitsuba_image(mi, mdict, cam, spp_mi, seed=seed))
    assert np.all(np.isfinite(a)) and a.min() >= 0
    for region in (np.ones_like(sphere), sphere):
        ma, mb = a[region].mean(axis=0), b[region].mean(axis=0)
        # 4 standard errors of the difference of the two means, plus the measured
        # systematic difference of the models
        noise = 4.0 * np.hypot(na, nb) / np.sqrt(region.sum())
        assert np.all(np.abs(ma - mb) <= noise + systematic * mb), (
            ma,
            mb,
            (ma - mb) / mb,
            noise / mb,
        )
    # the images also agree region by region (8x8 blocks): same orientation, same layout
    ba = a.reshape(8, RES // 8, 8, RES // 8, 3).mean(axis=(1, 3))
    bb = b.reshape(8, RES // 8, 8, RES // 8, 3).mean(axis=(1, 3))
    assert np.corrcoef(ba.ravel(), bb.ravel())[0, 1] > 0.99


def test_diffuse_sphere_area_light_environment(mi):
    _compare(mi, "diffuse", (0.8, 0.3, 0.2), 32, 128, 0.001)


def test_smooth_dielectric_sphere(mi):
    _compare(mi, "glass", 1.5, 32, 128, 0.002)


def test_glossy_sphere(mi):
    _compare(mi, "glossy", ((0.9, 0.6, 0.2), 0.3), 32, 128, 0.006)
