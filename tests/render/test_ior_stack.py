"""The IOR stack for every df that refracts: a sphere of it inside a sphere of water.

The dfs under test come from the registry (:mod:`render.df._registry`): every declared
df that refracts (glossy or specular transmission bent by the IOR pair it reads), so a
df added later is checked without anyone listing it here.  Each is set up as a smooth
interface (its roughnesses, the parameters clamped at ``ROUGHNESS_MIN``, at 0.002) in
``scatter_transmit`` mode, and rendered as a small sphere inside a larger sphere of
water (``specular_bsdf``, IOR 1.33) against a lamp that covers half of the background:

* index-matched (IOR 1.33): the inner sphere vanishes: the image equals the scene's
  without it, within noise;
* an air bubble (IOR 1.0: total internal reflection on the way in) and a glass bead
  (IOR 1.5: total internal reflection on the way out): the image equals the one of
  ``specular_bsdf`` in its place, within noise.

Noise is measured, not assumed: the reference is rendered with two seeds, and a df's
image may differ from the reference by no more than 1.5 times the two references'
difference (plus 0.5 % of the lamp's radiance for the 0.002 roughness).
"""

from __future__ import annotations

import numpy as np
import pytest

from displacement.surfaces import Plane, UVSphere
from render import material as M
from render.camera import Camera
from render.df._kernel_common import ROUGHNESS_MIN
from render.df._registry import registry
from render.integrator import render
from render.scene import RenderSettings, Scene, SceneObject, emissive_material, make_transform

RES, SPP = 40, 64
WATER = 1.33
ROUGH = 0.002

REFRACTING = sorted(key for key, d in registry().dfs.items() if d.refracts)


def smooth(key: str, **kwargs):
    """The df ``key`` as a smooth interface in scatter_transmit mode."""
    rough = {p.name: ROUGH for p in registry().df(key).signature.params
             if p.clamp is not None and p.clamp[0] == ROUGHNESS_MIN}
    return getattr(M.df, key)(mode="scatter_transmit", **rough, **kwargs)


def sphere(bsdf, ior: float, radius: float, name: str) -> SceneObject:
    mat = M.material(ior=(ior,) * 3, surface=M.material_surface(bsdf))
    return SceneObject(UVSphere(radius=1.0), mat, make_transform(scale=radius), name=name)


def image(inner, seed: int = 1) -> np.ndarray:
    """The water sphere, with ``inner`` (a SceneObject or None) inside, in front of a
    lamp over the left half of the background."""
    water = sphere(M.df.specular_bsdf(mode="scatter_transmit"), WATER, 1.0, "water")
    lamp = SceneObject(Plane(size=(3.0, 6.0), origin=(-3.0, -3.0, -2.0), axis_u=(1, 0, 0),
                             axis_v=(0, 1, 0)), emissive_material(np.full(3, np.pi)),
                       name="lamp")
    cam = Camera(position=(0.0, 0.0, 4.0), look_at=(0.0, 0.0, 0.0), fov_y_deg=30.0,
                 width=RES, height=RES)
    objects = [water, lamp] + ([inner] if inner is not None else [])
    scene = Scene(cam, objects, [], RenderSettings(RES, RES, spp=SPP, max_depth=-1,
                                                   rr_depth=1000, seed=seed))
    img = render(scene, progress=False).rgb()
    assert np.all(np.isfinite(img))
    return img[..., 1]


def rms(a: np.ndarray, b: np.ndarray) -> float:
    return float(np.sqrt(np.mean((a - b) ** 2)))


def test_the_registry_finds_the_refracting_dfs():
    # the five glossy dfs with scatter modes and specular_bsdf read the IOR pair and
    # transmit by refraction; dfs that transmit without it (diffuse transmission, hair)
    # or read it without transmitting (Fresnel layers and factors) are not among them
    assert {"specular_bsdf", "simple_glossy_bsdf", "microfacet_ggx_smith_bsdf",
            "microfacet_beckmann_smith_bsdf", "microfacet_ggx_vcavities_bsdf",
            "microfacet_beckmann_vcavities_bsdf"} <= set(REFRACTING)
    for key in ("diffuse_transmission_bsdf", "chiang_hair_bsdf", "fresnel_layer",
                "fresnel_factor", "diffuse_reflection_bsdf"):
        assert key not in REFRACTING
    assert registry().df("diffuse_transmission_bsdf").transmits


@pytest.fixture(scope="module")
def references():
    """``{ior: (image, noise)}`` with specular_bsdf inside (None: no inner sphere)."""
    out = {}
    for ior in (None, 1.0, 1.5):
        if ior is None:
            a, b = image(None, seed=1), image(None, seed=2)
        else:
            inner = M.df.specular_bsdf(mode="scatter_transmit")
            a = image(sphere(inner, ior, 0.5, "inner"), seed=1)
            b = image(sphere(inner, ior, 0.5, "inner"), seed=2)
        out[ior] = (a, rms(a, b))
    return out


def tolerance(noise: float) -> float:
    """How far a df's image may be from its reference's."""
    return 1.5 * noise + 0.005


def test_the_scenes_tell_the_cases_apart(references):
    # the bubble and the bead bend light far beyond the tolerance: a df that vanished
    # (an air bubble taken as air in air, the bug of issue 32) or ignored the water
    # around it would fail the checks below
    empty, noise = references[None]
    for ior in (1.0, 1.5):
        img, n = references[ior]
        assert rms(img, empty) > 5 * tolerance(max(noise, n)), ior
    assert rms(references[1.0][0], references[1.5][0]) > 5 * tolerance(noise)


@pytest.mark.slow
@pytest.mark.parametrize("key", REFRACTING)
@pytest.mark.parametrize("ior", [WATER, 1.0, 1.5], ids=["matched", "bubble", "bead"])
def test_a_sphere_inside_water_refracts_by_the_ior_pair(key, ior, references):
    got = image(sphere(smooth(key), ior, 0.5, "inner"), seed=3)
    want, noise = references[None if ior == WATER else ior]
    assert rms(got, want) <= tolerance(noise), (key, ior, rms(got, want), noise)
