"""Hair strands rendered by the path kernel, against exact answers: white furnaces (a
lossless fibre in a uniform environment, or inside a box of area lights, reflects the
radiance around it: 1, within Monte Carlo error) for polylines and Bézier strands at the
extremes (radius 1e-5, radius larger than the strand, views grazing along the fibre,
strands inside each other), black hair (material.hair = None), and the shadow a strand
casts from an area light (the unoccluded part of the light, integrated exactly)."""

from __future__ import annotations

import math

import numpy as np
import pytest

from displacement.surfaces import Plane
from render import material as M
from render.camera import Camera
from render.hair import Strands, fringe
from render.integrator import render
from render.lights import ConstantEnvironment
from render.scene import RenderSettings, Scene, SceneObject, emissive_material, make_transform

#: a lossless fibre (absorption 0): its albedo is 1 for every wo and h (the df's tests)
WHITE = M.material(hair=M.df.chiang_hair_bsdf(roughness_R=(0.3, 0.3)))
#: MDL's default hair_bsdf(): black
BLACK = M.material()


def _camera(position, look_at, res=24, fov=30.0, ortho=None, up=(0, 1, 0)):
    return Camera(position=position, look_at=look_at, up=up, width=res, height=res,
                  fov_y_deg=fov, ortho_height=ortho)


def _render(objects, camera, spp=16, lights=None, max_depth=-1, aovs=()):
    scene = Scene(camera, objects, [ConstantEnvironment(1.0)] if lights is None else lights,
                  RenderSettings(camera.width, camera.height, spp=spp, max_depth=max_depth))
    return render(scene, progress=False, aovs=aovs)


def _mean_err(px: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    px = px.reshape(-1, px.shape[-1])
    return px.mean(axis=0), px.std(axis=0, ddof=1) / math.sqrt(len(px))


def _zigzag(kind, radius):
    pts = [[-1.0, -0.4, 0.0], [-0.4, 0.5, 0.2], [0.3, -0.5, -0.2], [1.0, 0.4, 0.0]]
    if kind == "linear":
        return Strands.polylines([pts], radius=radius)
    return Strands.bezier([pts], radii=[[radius, 1.5 * radius, 0.7 * radius, 0.3 * radius]])


FURNACES = {
    # name: (objects, camera, minimum covered pixels)
    "polyline": ([SceneObject(_zigzag("linear", 0.08), WHITE)],
                 _camera((0, 0, 4), (0, 0, 0)), 40),
    "bezier": ([SceneObject(_zigzag("bezier", 0.1), WHITE)], _camera((0, 0, 4), (0, 0, 0)), 40),
    # radius 1e-5, seen through a 2e-4-wide orthographic window
    "radius 1e-5": ([SceneObject(Strands.polylines([[[-0.5, 0.3, 0.0], [0.5, 0.3, 0.0]],
                                                     [[0.3, -0.5, 0.0], [0.3, 0.5, 0.001]]],
                                                    radius=1e-5), WHITE)],
                    _camera((0.3, 0.3, 2.0), (0.3, 0.3, 0.0), ortho=2e-4), 100),
    # radius far beyond the length: a ball of a polyline, a stub of a Bézier tube
    "radius >> length": ([SceneObject(Strands.polylines([[[-0.01, 0, 0], [0.01, 0, 0]]],
                                                        radius=0.5), WHITE),
                          SceneObject(Strands.bezier([[[0, -0.05, 0], [0.01, 0, 0],
                                                       [0.02, 0.02, 0], [0, 0.06, 0]]],
                                                     radius=0.3), WHITE,
                                      make_transform(translate=(0.0, -1.0, 0.5)))],
                         _camera((0, -0.4, 4), (0, -0.4, 0), fov=40), 60),
    # looking along a straight strand: rays 0.5 to 3 degrees off the fibre's axis (rays
    # into its open end meet it from inside only, and pass)
    "grazing": ([SceneObject(Strands.bezier([[[0, 0, -1], [0, 0, -0.3], [0, 0, 0.3],
                                              [0, 0, 1]]], radius=0.05), WHITE)],
                _camera((0.0, 0.15, 5.0), (0.0, -0.016, 0.0), fov=2.5), 60),
    # a tassel: strands gathered through each other (rays leave one inside another)
    "tassel": ([SceneObject(fringe(start=(-0.4, 0.4, 0), end=(0.4, 0.4, 0), count=40,
                                   length=0.8, radius=0.02, tassel=1.0, seed=1), WHITE)],
               _camera((0, 0, 2.5), (0, 0, 0)), 60),
}


@pytest.mark.parametrize("name", list(FURNACES))
def test_white_furnace(name):
    objects, cam, min_covered = FURNACES[name]
    film = _render(objects, cam, spp=16)
    img, alpha = film.rgb(), film.alpha()
    assert np.all(np.isfinite(img)) and img.min() >= 0.0
    covered = alpha > 0.0
    assert covered.sum() >= min_covered, covered.sum()
    # every pixel is 1 in expectation, on the strands as off them
    mean, err = _mean_err(img[covered])
    assert np.all(np.abs(mean - 1.0) < 4 * err + 2e-3), (mean, err)
    assert np.allclose(img[alpha == 0.0], 1.0)


def test_radius_1e5_covers_its_exact_area():
    # the cross of two strands of radius 1e-5 seen through a 2e-4 window: each covers a
    # 2e-5-wide band (their segments are split for Embree: unsplit, Embree traces such a
    # tube up to 20 radii thick); alpha's mean is the covered fraction of the window
    objects, cam, _ = FURNACES["radius 1e-5"]
    alpha = _render(objects, cam, spp=16).alpha()
    w, d = 2e-4, 2e-5
    exact = (2 * w * d - d * d) / (w * w)
    se = math.sqrt(exact * (1 - exact) / (alpha.size * 16))
    assert abs(alpha.mean() - exact) < 4 * se + 2e-3, (alpha.mean(), exact)


def test_black_hair_is_black_whatever_the_surface():
    # material.hair = None is hair_bsdf(), black; MDL: nothing but the hair field applies
    # to hair, so a surface bsdf, emission, displacement and cutout change nothing
    lit = M.material(surface=M.material_surface(
        M.df.diffuse_reflection_bsdf(tint=0.8),
        M.material_emission(M.df.diffuse_edf(), intensity=(5.0, 5.0, 5.0))),
        geometry=M.material_geometry(displacement=lambda st: 0.1 * st.normal,
                                     cutout_opacity=0.3))
    strand = Strands.polylines([[[-1, 0, 0], [1, 0, 0]]], radius=0.15)
    cam = _camera((0, 0, 3), (0, 0, 0))
    for material in (BLACK, lit):
        film = _render([SceneObject(strand, material)], cam, spp=8, aovs=("normal", "albedo"))
        img, alpha = film.rgb(), film.alpha()
        assert (alpha == 1.0).sum() >= 24
        # each sample sees the black strand or the environment (1)
        assert np.allclose(img, (1.0 - alpha)[..., None], atol=1e-12)
        nrm = film.aov("normal")[alpha == 1.0]
        assert np.allclose(np.abs(nrm[:, 0]), 0.0, atol=1e-9)  # perpendicular to the fibre
        assert np.allclose(film.aov("albedo")[alpha == 1.0], 0.0)


def _box(half=2.0, radiance=1.0):
    """Six inward-facing emissive squares closing a cube: uniform radiance inside."""
    mat = emissive_material(np.full(3, np.pi * radiance))
    s = 2 * half
    faces = [((-half, -half, -half), (1, 0, 0), (0, 1, 0)),   # back, normal +z
             ((-half, -half, half), (0, 1, 0), (1, 0, 0)),    # front, normal -z
             ((-half, -half, -half), (0, 0, 1), (1, 0, 0)),   # floor, normal +y
             ((-half, half, -half), (1, 0, 0), (0, 0, 1)),    # ceiling, normal -y
             ((-half, -half, -half), (0, 1, 0), (0, 0, 1)),   # left, normal +x
             ((half, -half, -half), (0, 0, 1), (0, 1, 0))]    # right, normal -x
    return [SceneObject(Plane(size=(s, s), origin=o, axis_u=u, axis_v=v), mat, name=f"wall{i}")
            for i, (o, u, v) in enumerate(faces)]


def test_furnace_of_area_lights():
    # inside a closed box of area lights of radiance 1: next-event estimation toward the
    # walls (shadow rays that leave a fibre through its far wall) and MIS against the
    # walls found by the fibres' sampled directions; every pixel is 1
    strands = [SceneObject(fringe(start=(-0.5, 0.5, 0), end=(0.5, 0.5, 0), count=12,
                                  length=1.0, radius=0.04, seed=2), WHITE, name="fringe"),
               SceneObject(_zigzag("linear", 0.1), WHITE,
                           make_transform(translate=(0, 0, -0.6)), name="zigzag")]
    cam = _camera((0, 0, 1.9), (0, 0, 0), fov=60)
    film = _render(_box() + strands, cam, spp=16, lights=[], aovs=("object_id",))
    img = film.rgb()
    assert np.all(np.isfinite(img))
    on_strands = film.aov("object_id") >= 6
    assert on_strands.sum() >= 60
    mean, err = _mean_err(img[on_strands])
    assert np.all(np.abs(mean - 1.0) < 4 * err + 2e-3), (mean, err)
    mean, err = _mean_err(img)
    assert np.all(np.abs(mean - 1.0) < 4 * err + 2e-3), (mean, err)


# -------------------------------------------------------------------- shadows
H, ZL, SIDE = 2.0, -1.0, 1.0  # the light: a square of SIDE at height H, centred on z = ZL
HC, R, RHO, LE = 1.0, 0.25, 0.5, 3.0  # the strand along x at height HC, z = 0; the floor


def _blocked(z: float) -> tuple[float, float]:
    """The light's z' interval hidden from the floor point (x, 0, z) by the infinite
    cylinder of radius R about the line y = HC, z = 0 (where the segment from (0, z) to
    (H, z') in the y-z plane passes within R of (HC, 0))."""
    # |z_mid| cos(slope) < R, z_mid = z + (z' - z) HC / H: a quadratic in z'
    k = HC / H
    # z_mid = (1 - k) z + k z'; squared distance = z_mid^2 H^2 / (H^2 + (z' - z)^2)
    a = (k * H) ** 2 - R * R
    b = 2 * (1 - k) * z * k * H * H + 2 * R * R * z
    c = ((1 - k) * z * H) ** 2 - R * R * (H * H + z * z)
    disc = b * b - 4 * a * c
    if disc <= 0:
        return 0.0, 0.0
    r1, r2 = (-b - math.sqrt(disc)) / (2 * a), (-b + math.sqrt(disc)) / (2 * a)
    return min(r1, r2), max(r1, r2)


def _floor_radiance(x: float, z: float, n: int = 48) -> float:
    """rho / pi times the irradiance at (x, 0, z) from the unblocked part of the light
    (Gauss-Legendre on each unblocked z' piece: the integrand H^2 / d^4 is smooth)."""
    g, w = np.polynomial.legendre.leggauss(n)
    z0, z1 = ZL - SIDE / 2, ZL + SIDE / 2
    b0, b1 = _blocked(z)
    pieces = [(z0, min(z1, b0)), (max(z0, b1), z1)] if b1 > b0 else [(z0, z1)]
    xs = 0.5 * SIDE * g
    wx = 0.5 * SIDE * w
    e = 0.0
    for lo, hi in pieces:
        if hi <= lo:
            continue
        zs = 0.5 * (hi - lo) * g + 0.5 * (hi + lo)
        wz = 0.5 * (hi - lo) * w
        d2 = (xs[:, None] - x) ** 2 + H * H + (zs[None, :] - z) ** 2
        e += float(np.sum(wx[:, None] * wz[None, :] * H * H / d2 ** 2))
    return RHO / math.pi * LE * e


@pytest.mark.parametrize("kind", ["linear", "bezier"])
def test_strand_casts_the_exact_shadow_of_an_area_light(kind):
    a, b = np.array([-8.0, HC, 0.0]), np.array([8.0, HC, 0.0])
    strand = (Strands.polylines([[a, b]], radius=R) if kind == "linear" else
              Strands.bezier([[a, a + (b - a) / 3, a + 2 * (b - a) / 3, b]], radius=R))
    light = SceneObject(Plane(size=(SIDE, SIDE), origin=(-SIDE / 2, H, ZL - SIDE / 2),
                              axis_u=(1, 0, 0), axis_v=(0, 0, 1)),
                        emissive_material(np.full(3, np.pi * LE)), name="light")
    floor = SceneObject(Plane(size=(40, 40), origin=(-20, 0, 20), axis_u=(1, 0, 0),
                              axis_v=(0, 0, -1)),
                        M.material(surface=M.material_surface(
                            M.df.diffuse_reflection_bsdf(tint=RHO))), name="floor")
    # looking down at the floor behind the strand (z in [0.5, 1.5]: the shadow's middle is
    # at z = 1), from above the light: neither the light nor the strand is in view
    w, h = 16, 32
    cam = Camera(position=(0, 3, 1.0), look_at=(0, 0, 1.0), up=(0, 0, -1), width=w, height=h,
                 ortho_height=1.0)
    film = _render([floor, light, SceneObject(strand, BLACK, name="strand")], cam, spp=64,
                   lights=[], max_depth=2)
    img = film.rgb()[..., 0]
    # the expected image, averaged over each pixel's footprint (x right, z down)
    sub = (np.arange(4) + 0.5) / 4
    exp = np.zeros((h, w))
    for i in range(h):
        for j in range(w):
            exp[i, j] = np.mean([_floor_radiance((j + sx) / w * 0.5 - 0.25, 0.5 + (i + sz) / h)
                                 for sx in sub for sz in sub])
    assert exp.min() < 0.2 * exp.max()  # an umbra, a penumbra and light
    resid = img - exp
    row_mean = resid.mean(axis=1)
    row_err = resid.std(axis=1, ddof=1) / math.sqrt(w) + 1e-4 * exp.max()
    assert np.all(np.abs(row_mean) < 4.5 * row_err), np.column_stack([row_mean, row_err,
                                                                      exp.mean(axis=1)])
    # and without the strand, no shadow: the full light everywhere
    film = _render([floor, light], cam, spp=8, lights=[], max_depth=2)
    assert film.rgb()[..., 0].mean() > img.mean() * 1.2
