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

import numpy as np
import pytest

from displacement.surfaces import Plane, UVSphere
from render import material as M
from render.camera import Camera
from render.integrator import render
from render.lights import ConstantEnvironment
from render.scene import RenderSettings, Scene, SceneObject, emissive_material, make_transform

# Mitsuba's LLVM (DRJIT_LIBLLVM_PATH) is chosen by tests/conftest.py, which skips these
# tests with the reason where none is usable
pytestmark = pytest.mark.mitsuba

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
    """Mean of two renders with different seeds, and half their difference, whose spread
    over a set of pixels is the standard deviation of one pixel's noise in the mean (one
    render's pixel noise is std(x - y) / sqrt(2); their mean has 1/sqrt(2) of it).  The
    spread is taken over the pixels compared (:func:`_noise`): the noise of a glass
    sphere is not the floor's."""
    x, y = render_fn(1), render_fn(2)
    return 0.5 * (x + y), 0.5 * (x - y)


def _noise(half_a, half_b, mask):
    """4 standard errors of the difference of two images' means over ``mask``."""
    na, nb = half_a[mask].reshape(-1, 3).std(axis=0), half_b[mask].reshape(-1, 3).std(axis=0)
    return 4.0 * np.hypot(na, nb) / np.sqrt(mask.sum())


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
        noise = _noise(na, nb, region)
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


# --------------------------------------------------------------------------------------
# Volumes, thin walls and interfaces (docs/render.md, "Volumes, thin walls and
# interfaces").  Mitsuba renders these with ``volpath``: media bound to the sphere's
# interior, ``null`` for an index-matched boundary (our clear specular_bsdf
# scatter_transmit with ior 1 passes shadow rays the same way), ``twosided`` with two
# BSDFs for a thin-walled material with a backface.  Measured at 64 x 64 with 2 x 1024
# spp (ours) and 2 x 8192 spp (Mitsuba), relative difference of the means, whole image /
# object (1 sigma of the difference in brackets):
#
# * dielectric sphere (ior 1.5) holding an absorbing medium sigma_a = (0.5, 1, 2):
#   <= 0.008 % (0.02 %) / <= 0.12 % (0.07-0.16 %);
# * dielectric sphere holding a scattering medium of grey extinction 4 and albedo
#   (0.95, 0.7, 0.4), Henyey-Greenstein g = 0.5: <= 0.007 % (0.02-0.03 %) / <= 0.18 %
#   (0.12-0.2 %);
# * an index-matched ("null") sphere of fog (sigma_s = 3, sigma_a = 0.5, g = -0.3):
#   -0.01 % (0.011 %) / -0.05 % (0.03 %);
# * a thin-walled pair of squares, diffuse red in front and blue behind, vs twosided:
#   <= 0.022 % (0.012 %) / <= 0.13 % (0.03-0.2 %);
# * a thin-walled pane met at 45 degrees by every camera ray (orthographic) vs
#   thindielectric with the IOR whose slab reflectance equals the single interface's:
#   0.025 % (0.016 %);
# * normalized_mix of a tinted mirror (0.4) and a dielectric (0.6) over an absorbing
#   interior vs blendbsdf: <= 0.008 % (0.02 %) / <= 0.2 % (0.07-0.11 %).
#
# All within noise.  Strongly chromatic extinction (e.g. sigma_a = (0.5, 2, 6)) agrees
# too, but Mitsuba tracks one channel per path without spectral MIS, so its estimate
# there has heavy tails (6-20 times our noise in the weakest channel): the tests keep
# the extinction grey or mildly chromatic so that two low-spp renders bound the noise.
# The tests allow 4 standard errors plus VOLUME_TOLERANCES.


def _medium_dicts(sigma_a, sigma_s, g):
    sa, ss = np.broadcast_to(np.asarray(sigma_a, float), (3,)), np.broadcast_to(
        np.asarray(sigma_s, float), (3,))
    st = sa + ss
    albedo = np.where(st > 0, ss / np.where(st > 0, st, 1.0), 0.0)
    scale = float(st.max()) or 1.0  # Mitsuba's RGB values must lie in [0, 1]
    mi_medium = {
        "type": "homogeneous",
        "sigma_t": {"type": "rgb", "value": (st / scale).tolist()},
        "scale": scale,
        "albedo": {"type": "rgb", "value": albedo.tolist()},
        "phase": {"type": "hg", "g": float(g)},
    }
    return sa, ss, mi_medium


def _volume_stage(kind, sigma_a=0.0, sigma_s=0.0, g=0.0):
    """The stage of _stage with the sphere's material replaced (and the path tracer of
    Mitsuba replaced by volpath)."""
    ours, mdict, cam = _stage("diffuse", (0.5, 0.5, 0.5))
    mdict = dict(mdict)
    mdict["integrator"] = {"type": "volpath", "max_depth": 8, "rr_depth": 5}
    sphere = dict(mdict["sphere"])
    sa, ss, mi_medium = _medium_dicts(sigma_a, sigma_s, g)
    volume = M.material_volume(
        scattering=M.df.anisotropic_vdf(directional_bias=g),
        absorption_coefficient=tuple(sa),
        scattering_coefficient=tuple(ss),
    )
    if kind == "glass":
        mat = M.material(
            ior=(1.5,) * 3,
            surface=M.material_surface(M.df.specular_bsdf(mode="scatter_reflect_transmit")),
            volume=volume,
        )
        sphere["bsdf"] = {"type": "dielectric", "int_ior": 1.5, "ext_ior": 1.0}
    elif kind == "null":
        mat = M.material(
            surface=M.material_surface(M.df.specular_bsdf(mode="scatter_transmit")),
            volume=volume,
        )
        sphere["bsdf"] = {"type": "null"}
    else:
        raise ValueError(kind)
    sphere["interior"] = mi_medium
    mdict["sphere"] = sphere
    objects = list(ours.objects)
    objects[1] = SceneObject(objects[1].surface, mat, objects[1].transform, name="sphere",
                             resolution=(192, 96))
    ours = Scene(ours.camera, objects, ours.lights, ours.settings)
    return ours, mdict, cam


def _compare_scenes(mi, ours, mdict, cam, spp_ours, spp_mi, systematic, region_id=1):
    region = render(ours, spp=1, progress=False, aovs=["object_id"]).aov("object_id") == region_id
    a, na = _two(lambda seed: render(ours, spp=spp_ours, seed=seed, progress=False).rgb())
    b, nb = _two(lambda seed: _mitsuba_image(mi, mdict, cam, spp_mi, seed=seed))
    assert np.all(np.isfinite(a)) and a.min() >= 0
    out = []
    for mask in (np.ones_like(region), region):
        ma, mb = a[mask].mean(axis=0), b[mask].mean(axis=0)
        noise = _noise(na, nb, mask)
        out.append((ma - mb) / mb)
        assert np.all(np.abs(ma - mb) <= noise + systematic * mb), (
            ma, mb, (ma - mb) / mb, noise / mb)
    ba = a.reshape(8, RES // 8, 8, RES // 8, 3).mean(axis=(1, 3))
    bb = b.reshape(8, RES // 8, 8, RES // 8, 3).mean(axis=(1, 3))
    assert np.corrcoef(ba.ravel(), bb.ravel())[0, 1] > 0.99
    return out


#: measured systematic differences allowed on top of 4 standard errors
VOLUME_TOLERANCES = {"absorbing_glass": 0.002, "scattering_glass": 0.003, "null_fog": 0.001,
                     "twosided": 0.001, "thin_pane": 0.001, "blend": 0.002}


def test_dielectric_with_absorbing_medium(mi):
    ours, mdict, cam = _volume_stage("glass", sigma_a=(0.5, 1.0, 2.0))
    _compare_scenes(mi, ours, mdict, cam, 32, 128, VOLUME_TOLERANCES["absorbing_glass"])


def test_dielectric_with_scattering_medium(mi):
    ours, mdict, cam = _volume_stage("glass", sigma_a=(0.2, 1.2, 2.4), sigma_s=(3.8, 2.8, 1.6),
                                     g=0.5)
    _compare_scenes(mi, ours, mdict, cam, 32, 128, VOLUME_TOLERANCES["scattering_glass"])


def test_index_matched_fog_sphere(mi):
    ours, mdict, cam = _volume_stage("null", sigma_a=0.5, sigma_s=3.0, g=-0.3)
    _compare_scenes(mi, ours, mdict, cam, 32, 128, VOLUME_TOLERANCES["null_fog"])


def _twosided_stage():
    """Two upright squares in the stage: the left one shows its front, the right one its
    back; thin-walled diffuse red on the front and blue on the back."""
    ours, mdict, cam = _stage("diffuse", (0.5, 0.5, 0.5))
    front, back = (0.8, 0.25, 0.1), (0.1, 0.3, 0.85)
    mat = M.material(
        thin_walled=True,
        surface=M.material_surface(M.df.diffuse_reflection_bsdf(tint=front)),
        backface=M.material_surface(M.df.diffuse_reflection_bsdf(tint=back)),
    )
    mi_bsdf = {
        "type": "twosided",
        "front": {"type": "diffuse", "reflectance": {"type": "rgb", "value": list(front)}},
        "back": {"type": "diffuse", "reflectance": {"type": "rgb", "value": list(back)}},
    }
    left, left_m = _rect((-0.55, 0.45, 0.0), (1, 0, 0), (0, 1, 0), (0.8, 0.8))
    right, right_m = _rect((0.55, 0.45, 0.0), (-1, 0, 0), (0, 1, 0), (0.8, 0.8))
    objects = [ours.objects[0], SceneObject(left, mat, name="left"), ours.objects[2],
               SceneObject(right, mat, name="right")]
    ours = Scene(ours.camera, objects, ours.lights, ours.settings)
    mdict = dict(mdict)
    del mdict["sphere"]
    mdict["left"] = {"type": "rectangle", "to_world": left_m, "bsdf": mi_bsdf}
    mdict["right"] = {"type": "rectangle", "to_world": right_m, "bsdf": mi_bsdf}
    return ours, mdict, cam


def test_thin_walled_backface_vs_twosided(mi):
    ours, mdict, cam = _twosided_stage()

    def image(mi_, d, c, spp, seed=0):
        d = dict(d)
        for key in ("left", "right"):
            d[key] = dict(d[key])
            d[key]["to_world"] = mi_.ScalarTransform4f(d[key]["to_world"].tolist())
        return _mitsuba_image(mi_, d, c, spp, seed)

    region = render(ours, spp=1, progress=False, aovs=["object_id"]).aov("object_id")
    a, na = _two(lambda seed: render(ours, spp=32, seed=seed, progress=False).rgb())
    b, nb = _two(lambda seed: image(mi, mdict, cam, 128, seed=seed))
    for mask in (region >= 0, region == 1, region == 3):
        ma, mb = a[mask].mean(axis=0), b[mask].mean(axis=0)
        noise = _noise(na, nb, mask)
        assert np.all(np.abs(ma - mb) <= noise + VOLUME_TOLERANCES["twosided"] * mb), (
            ma, mb, (ma - mb) / mb, noise / mb)
    # the right square shows its back: blue, the left its front: red
    assert a[region == 3].mean(axis=0)[2] > a[region == 3].mean(axis=0)[0]
    assert a[region == 1].mean(axis=0)[0] > a[region == 1].mean(axis=0)[2]


def _thin_pane_stage():
    """The stage seen by an orthographic camera through a large thin pane turned 45
    degrees to the view (every camera ray meets it at 45 degrees, and its mirror image is
    the +x sky).  Ours: thin-walled specular_bsdf reflect_transmit, ior 1.5 (one
    interface, no refraction: reflects F, passes 1 - F).  Mitsuba's thindielectric sums
    the reflections inside a slab (R' = 2R / (1 + R)); with its IOR chosen so that
    R'(45 deg) = F(45 deg, 1.5) the two panes are the same for every camera ray."""
    from render.df._kernel_common import fresnel_dielectric

    ours, mdict, cam = _stage("diffuse", (0.8, 0.3, 0.2))
    cos45 = np.cos(np.pi / 4)
    r1 = fresnel_dielectric(float(cos45), 1.5)[0]
    r2 = r1 / (2.0 - r1)
    lo, hi = 1.0, 1.5  # bisection: F(45 deg, ior) = r2
    for _ in range(60):
        mid = 0.5 * (lo + hi)
        lo, hi = (mid, hi) if fresnel_dielectric(float(cos45), mid)[0] < r2 else (lo, mid)
    ior2 = 0.5 * (lo + hi)
    origin, target = np.array([0.0, 1.5, 3.5]), np.array([0.0, 0.4, 0.0])
    d = (target - origin) / np.linalg.norm(target - origin)
    x = np.array([1.0, 0.0, 0.0])
    n = cos45 * (-d) + cos45 * x
    v = np.cross(n, x)
    v /= np.linalg.norm(v)
    u = np.cross(v, n)
    center = origin + 1.0 * d
    pane, pane_m = _rect(center, u, v, (3.0, 3.0))
    height = 1.6
    cam_ours = Camera(position=tuple(origin), look_at=tuple(target), width=RES, height=RES,
                      ortho_height=height)
    mat = M.material(
        thin_walled=True,
        ior=(1.5,) * 3,
        surface=M.material_surface(M.df.specular_bsdf(mode="scatter_reflect_transmit")),
    )
    ours = Scene(cam_ours, list(ours.objects) + [SceneObject(pane, mat, name="pane")],
                 ours.lights, ours.settings)
    mdict = dict(mdict)
    mdict["integrator"] = {"type": "volpath", "max_depth": 8, "rr_depth": 5}
    mdict["pane"] = {"type": "rectangle", "to_world": pane_m,
                     "bsdf": {"type": "thindielectric", "int_ior": ior2, "ext_ior": 1.0}}
    mdict["sensor"] = dict(mdict["sensor"], type="orthographic")
    del mdict["sensor"]["fov"], mdict["sensor"]["fov_axis"]
    return ours, mdict, dict(origin=tuple(origin), target=tuple(target), height=height), ior2


def _mitsuba_ortho_image(mi, mdict, cam, spp, seed=0):
    d = dict(mdict)
    d["sensor"] = dict(d["sensor"])
    h = 0.5 * cam["height"]
    d["sensor"]["to_world"] = mi.ScalarTransform4f().look_at(
        origin=list(cam["origin"]), target=list(cam["target"]), up=[0, 1, 0]
    ) @ mi.ScalarTransform4f().scale([h, h, 1.0])
    for key in ("floor", "lamp", "pane"):
        d[key] = dict(d[key])
        d[key]["to_world"] = mi.ScalarTransform4f(d[key]["to_world"].tolist())
    return np.array(mi.render(mi.load_dict(d), spp=spp, seed=seed), dtype=np.float64)


def test_thin_walled_pane_vs_thindielectric(mi):
    ours, mdict, cam, ior2 = _thin_pane_stage()
    assert 1.2 < ior2 < 1.5
    a, na = _two(lambda seed: render(ours, spp=32, seed=seed, progress=False).rgb())
    b, nb = _two(lambda seed: _mitsuba_ortho_image(mi, mdict, cam, 128, seed=seed))
    ma, mb = a.reshape(-1, 3).mean(axis=0), b.reshape(-1, 3).mean(axis=0)
    noise = _noise(na, nb, np.ones((RES, RES), dtype=bool))
    assert np.all(np.abs(ma - mb) <= noise + VOLUME_TOLERANCES["thin_pane"] * mb), (
        ma, mb, (ma - mb) / mb, noise / mb)
    ba = a.reshape(8, RES // 8, 8, RES // 8, 3).mean(axis=(1, 3))
    bb = b.reshape(8, RES // 8, 8, RES // 8, 3).mean(axis=(1, 3))
    assert np.corrcoef(ba.ravel(), bb.ravel())[0, 1] > 0.99


def _blend_stage(weight=0.6, sigma_a=(0.5, 1.0, 2.0)):
    """The sphere as MDL's normalized_mix of a tinted mirror (weight 1 - w) and a
    dielectric (weight w) over an absorbing interior, against Mitsuba's blendbsdf of a
    twosided conductor (material "none": a perfect mirror) and a dielectric.

    Both components are deltas on purpose: Mitsuba 3.9's blendbsdf.sample returns the
    chosen component's pdf, not the mixture's, so its MIS weights are inconsistent when a
    delta is mixed with a smooth lobe (a diffuse + dielectric blend renders 6.7 % / 10 %
    darker in green / blue than its own linear combination at one bounce, where ours
    equals the linear combination)."""
    ours, mdict, cam = _volume_stage("glass", sigma_a=sigma_a)
    tint = (0.9, 0.6, 0.3)
    node = M.df.normalized_mix(components=[
        M.df.bsdf_component(weight=1.0 - weight,
                            component=M.df.specular_bsdf(tint=tint, mode="scatter_reflect")),
        M.df.bsdf_component(weight=weight,
                            component=M.df.specular_bsdf(mode="scatter_reflect_transmit")),
    ])
    mat = M.material(ior=(1.5,) * 3, surface=M.material_surface(node),
                     volume=ours.objects[1].material.volume)
    objects = list(ours.objects)
    objects[1] = SceneObject(objects[1].surface, mat, objects[1].transform, name="sphere",
                             resolution=(192, 96))
    ours = Scene(ours.camera, objects, ours.lights, ours.settings)
    sphere = dict(mdict["sphere"])
    sphere["bsdf"] = {
        "type": "blendbsdf",
        "weight": weight,
        "bsdf_0": {"type": "twosided", "b": {
            "type": "conductor", "material": "none",
            "specular_reflectance": {"type": "rgb", "value": list(tint)}}},
        "bsdf_1": {"type": "dielectric", "int_ior": 1.5, "ext_ior": 1.0},
    }
    mdict = dict(mdict, sphere=sphere)
    return ours, mdict, cam


def test_normalized_mix_vs_blendbsdf(mi):
    ours, mdict, cam = _blend_stage()
    _compare_scenes(mi, ours, mdict, cam, 32, 128, VOLUME_TOLERANCES["blend"])
