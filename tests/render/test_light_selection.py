"""Light selection for next-event estimation (render.path.select_light): probabilities
that sum to 1 at any point, 0 only where a light gives nothing, defined at the extremes."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from displacement.surfaces import UnitSquare
from render import light_sampling as LS
from render.lights import ConstantEnvironment, DirectionalLight, PointLight, SpotLight
from render.path import SC_LIGHTS, sample_lights, selection
from render.scene import RenderSettings, SceneObject, emissive_material, make_transform
from render.testing import light_tables

MODES = ("contribution", "power", "uniform")


def _quad(x, z=0.0, size=0.2, radiance=1.0):
    """A one-sided emissive square in the plane ``z`` facing +z, corner at (x, 0)."""
    return SceneObject(UnitSquare(), emissive_material((np.pi * radiance,) * 3),
                       make_transform(translate=(x, 0.0, z), scale=(size, size, 1.0)))


def _mixed(mode):
    lights = [PointLight((0.0, 0.0, 2.0), 5.0),
              SpotLight((1.0, 1.0, 3.0), (0.0, 0.0, -1.0), 20.0, cutoff_angle=30.0),
              DirectionalLight((0.3, -1.0, 0.2), 3.0), ConstantEnvironment(0.1)]
    return light_tables(lights, [_quad(-1.0), _quad(1.5, z=1.0)], selection=mode)


_TABLES = {mode: _mixed(mode) for mode in MODES}
coord = st.floats(-1e6, 1e6, allow_nan=False)
unit = st.floats(-1.0, 1.0, allow_nan=False)


@settings(max_examples=60)
@given(p=st.tuples(coord, coord, coord), n=st.tuples(unit, unit, unit),
       mode=st.sampled_from(MODES))
def test_probabilities_sum_to_one_anywhere(p, n, mode):
    """At most one: a walk down the light tree ends without a light where a node's
    bound allows light but both its children are black there (pbrt-v4's sampler
    loses those samples too); the environment and directional light stay possible."""
    pr = selection(_TABLES[mode], np.array([p]), np.array([n]))
    assert np.all(np.isfinite(pr)) and np.all(pr >= 0) and np.all(pr[0, 2:4] > 0)
    assert pr.sum() <= 1.0 + 1e-12
    if mode != "contribution":  # no light is ever black: nothing is lost
        assert pr.sum() == pytest.approx(1.0, rel=1e-12)


def test_uniform_and_power_ignore_the_point():
    p = np.array([[0.0, 0.0, 0.0], [5.0, -3.0, 100.0]])
    assert np.allclose(selection(_TABLES["uniform"], p, np.zeros_like(p)), 1 / 6)
    pw = selection(_TABLES["power"], p, np.zeros_like(p))
    assert np.allclose(pw[0], pw[1])
    # pbrt's powers: point 4 pi I, directional pi r^2 E, environment pi L pi r^2
    assert pw[0, 2] / pw[0, 3] == pytest.approx(3.0 / (np.pi * 0.1))


def test_zero_only_behind_a_one_sided_emitter_where_it_gives_nothing(rng):
    objs = [_quad(0.0, size=1.0)]
    contribution = light_tables([], objs, selection="contribution")
    uniform = light_tables([], objs)  # samples the square from any point
    n = 400
    p = np.column_stack([rng.uniform(-3, 4, n), rng.uniform(-3, 4, n),
                         np.concatenate([rng.uniform(-3, -1e-3, n // 2),
                                         rng.uniform(1e-3, 3, n // 2)])])
    pr = selection(contribution, p, np.zeros_like(p))[:, 0]
    assert np.all(pr[p[:, 2] > 0] == 1)
    # right behind it: 0 (near its plane the bounding sphere keeps it possible)
    below = (p[:, 2] < -1) & (p[:, 0] > 0) & (p[:, 0] < 1) & (p[:, 1] > 0) & (p[:, 1] < 1)
    assert below.any() and np.all(pr[below] == 0)
    # wherever it is 0, the square really gives nothing: 64 samples from each point
    q = np.repeat(p[pr == 0], 64, axis=0)
    u = np.column_stack([np.zeros(len(q)), rng.random((len(q), 2))])
    _, _, li, _, _, _ = sample_lights(uniform, q, u)
    assert np.all(li == 0)
    # a spot outside its cutoff: 0, inside: 1, the sampled radiance agrees
    spot = [SpotLight((0.0, 0.0, 0.0), (0.0, 0.0, -1.0), 1.0, cutoff_angle=30.0)]
    tb = light_tables(spot, selection="contribution")
    d = np.radians([10.0, 29.0, 31.0, 90.0, 170.0])
    p = np.column_stack([np.sin(d), np.zeros(5), -np.cos(d)])
    pr = selection(tb, p, np.zeros_like(p))[:, 0]
    _, _, li, _, _, _ = sample_lights(light_tables(spot), p, np.zeros((5, 3)))
    assert pr.tolist() == [1.0, 1.0, 0.0, 0.0, 0.0] and np.all((li[:, 0] > 0) == (pr > 0))


def test_extremes_of_distance_power_and_count():
    lights = [PointLight((1e-6, 0.0, 0.0), 1.0), PointLight((1e6, 0.0, 0.0), 1.0),
              PointLight((0.0, 1.0, 0.0), 0.0)]
    tb = light_tables(lights, selection="contribution")
    pr = selection(tb, np.zeros((1, 3)), np.array([[0.0, 1.0, 0.0]]))[0]
    assert np.all(np.isfinite(pr)) and pr.sum() == pytest.approx(1.0)
    assert pr[0] >= 1 - 1e-12 and pr[2] == 0  # the zero-power light is never picked
    assert pr[1] > 0  # 1e-24 of the near one, but not lost
    one = light_tables([PointLight((1e6, 1e6, 1e6), 1e-30)], selection="contribution")
    assert selection(one, np.zeros((1, 3)), np.zeros((1, 3)))[0, 0] == 1.0
    dark = light_tables([PointLight((0.0, 1.0, 0.0), 0.0)], selection="contribution")
    assert selection(dark, np.zeros((1, 3)), np.zeros((1, 3)))[0, 0] == 0.0
    u = np.array([[0.5, 0.5, 0.5]])
    _, _, li, pdf, _, _ = sample_lights(dark, np.zeros((1, 3)), u)
    assert pdf[0] == 0 and np.all(li == 0)  # nothing to sample: no shadow ray


def test_a_hundred_lights_nearest_first(rng):
    pos = np.column_stack([np.arange(100.0), np.full(100, 1.0), np.zeros(100)])
    tb = light_tables([PointLight(x, 1.0) for x in pos], selection="contribution")
    p = np.array([[37.0, 0.0, 0.0], [-1e6, 0.0, 0.0]])
    pr = selection(tb, p, np.array([[0.0, 1.0, 0.0], [0.0, 0.0, 0.0]]))
    assert np.allclose(pr.sum(axis=1), 1.0) and pr[0].argmax() == 37
    # down the light tree the shares follow its nodes' bounds, not each light's exactly
    # (a point inside a node's sphere cannot tell where its lights are): the 9 nearest
    # take 65 % (87 % by each light's own bound), those over 16 away 18 % (2.5 %)
    off = np.abs(np.arange(100) - 37)
    assert pr[0, off <= 4].sum() > 0.6 and pr[0, off > 16].sum() < 0.2 and np.all(pr[0] > 0)
    # choices follow the probabilities (chi-square-free check: frequencies within 5 sigma)
    n = 20_000
    u = np.column_stack([rng.random(n), np.full((n, 2), 0.5)])
    at = np.tile(p[:1], (n, 1))
    wi, dist, _, pdf, _, _ = sample_lights(tb, at, u)
    chosen = np.rint((at + wi * dist[:, None])[:, 0]).astype(int)
    q = selection(tb, p[:1], np.zeros((1, 3)))[0]
    assert np.allclose(pdf, q[chosen], rtol=1e-12)  # delta lights: pdf = the probability
    freq = np.bincount(chosen, minlength=100) / n
    assert np.all(np.abs(freq - q) <= 5 * np.sqrt(q * (1 - q) / n) + 1e-12)


def test_every_delta_light_leaves_the_others_to_the_selection():
    tb = light_tables([PointLight((0.0, 0.0, 2.0), 5.0), DirectionalLight((0, -1, 0), 3.0),
                       ConstantEnvironment(0.1)], [_quad(-1.0)], selection="contribution",
                      every_delta=True)
    p = np.array([[0.0, 0.0, 0.0], [3.0, 1.0, -2.0]])
    pr = selection(tb, p, np.array([[0.0, 1.0, 0.0], [0.0, 0.0, 0.0]]))
    assert np.all(pr[:, :2] == 0) and np.allclose(pr.sum(axis=1), 1.0)


def test_setting_is_checked():
    with pytest.raises(ValueError, match="light_selection"):
        RenderSettings(light_selection="nearest").validate()


def _render(selection, every_delta, seed):
    from render import material as M
    from render.camera import Camera
    from render.integrator import Integrator
    from render.scene import Scene

    grey = M.material(surface=M.material_surface(M.df.diffuse_reflection_bsdf(tint=0.6)))
    floor = SceneObject(UnitSquare(), grey, make_transform(translate=(-2.0, 0.0, 2.0),
                                                           rotate=(-90.0, 0.0, 0.0),
                                                           scale=(4.0, 4.0, 1.0)))
    lamp = SceneObject(UnitSquare(), emissive_material((np.pi * 8.0,) * 3),
                       make_transform(translate=(-0.6, 1.0, -0.2), rotate=(90.0, 0.0, 0.0),
                                      scale=(0.3, 0.3, 1.0)))
    lights = [PointLight((0.8, 0.7, 0.3), 0.5), DirectionalLight((0.3, -1.0, -0.4), 1.0),
              ConstantEnvironment(0.2)]
    cam = Camera(position=(0.0, 2.0, 3.0), look_at=(0.0, 0.0, 0.0), fov_y_deg=50.0, width=24,
                 height=24)
    scene = Scene(cam, [floor, lamp], lights,
                  RenderSettings(24, 24, spp=48, light_selection=selection,
                                 every_delta_light=every_delta))
    return Integrator(scene, scene.build()).render(seed=seed, progress=False, threads=1).rgb()


def test_every_selection_renders_the_same_image_in_expectation():
    """Unbiased whatever the selection: MIS weights use the probability the selection
    had at the vertex the path left.  Pixels are independent: the difference of two
    images' means is within 5 standard errors of 0."""
    base = _render("uniform", False, 1)
    for k, (kind, every) in enumerate([("contribution", False), ("contribution", True),
                                       ("power", True)]):
        other = _render(kind, every, 2 + k)
        diff = (other - base).mean(axis=2).ravel()
        assert abs(diff.mean()) < 5 * diff.std() / np.sqrt(diff.size), (kind, every)
        assert diff.std() > 0


def _lights(tb) -> int:
    """The number of lights of tables ``tb`` (the light tree's nodes follow them)."""
    return int(tb.scalars[SC_LIGHTS])


# ---------------------------------------------------------------- environments
def _sh_irradiance(tb, j, nrm):
    """The harmonics' irradiance of environment ``j`` at unit normals ``nrm`` (n, 3)."""
    from render.light_sampling import SH_Y00

    x, y, z = nrm.T
    c = tb.lights[j, LS.L_SH:LS.L_SH + 9]
    y1, y2 = np.sqrt(3 / (4 * np.pi)), np.sqrt(15 / (4 * np.pi))
    basis = [np.full_like(x, SH_Y00), y1 * y, y1 * z, y1 * x, y2 * x * y, y2 * y * z,
             np.sqrt(5 / (16 * np.pi)) * (3 * z * z - 1), y2 * x * z,
             np.sqrt(15 / (16 * np.pi)) * (x * x - y * y)]
    return sum(ck * bk for ck, bk in zip(c, basis, strict=True))


def _normals(n, rng):
    v = rng.normal(size=(n, 3))
    return v / np.linalg.norm(v, axis=1, keepdims=True)


def test_a_constant_environment_gives_pi_l_from_every_side(rng):
    tb = light_tables([ConstantEnvironment(0.1)], [_quad(0.0)], selection="contribution")
    j = 0
    c = tb.lights[j, LS.L_SH:LS.L_SH + 9]
    assert c[0] * np.sqrt(0.25 / np.pi) == pytest.approx(np.pi * 0.1, rel=1e-9)
    assert np.abs(c[1:]).max() < 1e-3 * c[0]
    e = _sh_irradiance(tb, j, _normals(200, rng))
    np.testing.assert_allclose(e, np.pi * 0.1, rtol=2e-3)


@pytest.mark.parametrize("elevation", [60.0, 10.0, -5.0])
def test_sun_and_sky_irradiance_from_three_bands(elevation, rng):
    """The harmonics' irradiance against the cosine-weighted radiance of the sun and sky
    by 2^16 of its own importance samples, at 64 normals: within the error of three bands
    (9 % of the largest irradiance: the clamped cosine's band-limit error is 0.07 of its
    peak, Ramamoorthi and Hanrahan), and the importance is positive everywhere."""
    from render.sky import SunAndSky, sun_direction_from_angles
    from render.testing import light_samples

    sky = SunAndSky(sun_direction_from_angles(elevation, 120.0), turbidity=3.0)
    tb = light_tables([sky], [_quad(0.0)], selection="contribution")
    nrm = _normals(64, rng)
    u = rng.random((1 << 16, 2))
    wi, _, li, pdf, _ = light_samples([sky], np.zeros((len(u), 3)), u, [_quad(0.0)])
    lum = li @ np.array([0.212671, 0.715160, 0.072169])
    w = np.where(pdf > 0, lum / np.where(pdf > 0, pdf, 1.0), 0.0)
    truth = (w[None, :] * np.maximum(nrm @ wi.T, 0.0)).mean(axis=1)
    e = _sh_irradiance(tb, 0, nrm)
    assert np.abs(e - truth).max() <= 0.09 * truth.max()
    p = np.zeros((64, 3))
    pr = selection(tb, p, nrm)
    assert np.all(pr[:, 0] > 0) and np.allclose(pr.sum(axis=1), 1.0)


def test_a_sun_is_chosen_more_where_the_normal_faces_it():
    """Sun and sky and an area light: facing the sun the environment is picked more often
    than facing away (in a medium, with no normal, both are possible)."""
    from render.sky import SunAndSky

    sky = SunAndSky([0.0, 1.0, 0.0], turbidity=3.0)  # the sun at the zenith (+y)
    # a square facing +z in front of the point: alike from both normals (grazing)
    tb = light_tables([sky], [_quad(-0.1, z=-2.0, size=0.2, radiance=50.0)],
                      selection="contribution")
    p = np.zeros((3, 3))
    nrm = np.array([[0.0, 1.0, 0.0], [0.0, -1.0, 0.0], [0.0, 0.0, 0.0]])
    pr = selection(tb, p, nrm)
    assert np.all(pr > 0) and np.allclose(pr.sum(axis=1), 1.0)
    # the square weighs the same from both normals: the odds are the irradiance's ratio,
    # the sun and sky above against the ground below (about 1 / its albedo; before the
    # harmonics, 1)
    odds = pr[:, 0] / pr[:, 1]
    assert odds[0] > 2.0 * odds[1]


# ---------------------------------------------------------------- the light tree
def _row(c, r, axis, cos, i):
    from render import light_sampling as K

    row = np.zeros(K.NL)
    row[K.LB_C:K.LB_C + 3], row[K.LB_R] = c, r
    row[K.LB_AXIS:K.LB_AXIS + 3] = axis / np.linalg.norm(axis)
    row[K.LB_COS], row[K.LB_I], row[K.LB_PHI], row[K.LB_N] = cos, i, 2 * i, 1
    return row


vec = st.tuples(*[st.floats(-10, 10, allow_nan=False)] * 3)


@settings(max_examples=200)
@given(ca=vec, cb=vec, ra=st.floats(0, 5), rb=st.floats(0, 5), xa=vec, xb=vec,
       cos_a=st.floats(-1, 1), cos_b=st.floats(-1, 1))
def test_a_node_bounds_both_children(ca, cb, ra, rb, xa, xb, cos_a, cos_b):
    """The merged sphere holds both spheres; the merged cone holds both cones (or is
    none, -1, when it would cover the sphere or a child has none); sums add up."""
    from render import light_sampling as K
    from render.light_sampling import _merge_bounds

    xa, xb = np.array(xa) + [0, 0, 1e-3], np.array(xb) + [0, 1e-3, 0]
    a = _row(np.array(ca), ra, xa, cos_a, 1.0)
    b = _row(np.array(cb), rb, xb, cos_b, 2.0)
    m = _merge_bounds(a, b)
    c, r = m[K.LB_C:K.LB_C + 3], m[K.LB_R]
    for child in (a, b):
        dist = np.linalg.norm(child[K.LB_C:K.LB_C + 3] - c) + child[K.LB_R]
        assert dist <= r * (1 + 1e-9) + 1e-9
        if m[K.LB_COS] > -1.0 and child[K.LB_COS] > -1.0:
            t = np.arccos(np.clip(m[K.LB_AXIS:K.LB_AXIS + 3] @ child[K.LB_AXIS:K.LB_AXIS + 3],
                                  -1, 1)) + np.arccos(child[K.LB_COS])
            assert t <= np.arccos(m[K.LB_COS]) + 1e-6
    if cos_a == -1.0 or cos_b == -1.0:
        assert m[K.LB_COS] == -1.0
    assert (m[K.LB_I], m[K.LB_PHI], m[K.LB_N]) == (3.0, 6.0, 2.0)


def test_the_tree_holds_every_area_light_once():
    """100 lamps: 99 nodes, the root first after the lights, every lamp a leaf reached
    from the root, every node's count the number of lamps below it."""
    from render import light_sampling as K

    lamps = [_quad(float(x), size=0.05) for x in np.linspace(-5, 5, 100)]
    tb = light_tables([ConstantEnvironment(0.1)], lamps, selection="contribution")
    n = _lights(tb)
    lb = tb.lights
    tree = lb[:, K.L_PARENT:K.L_B + 1].astype(np.int64)
    assert len(tree) == n + 99 and tree[n, 0] == -1 and tree[0, 0] == -1  # env at the top
    seen, stack = [], [n]
    while stack:
        x = stack.pop()
        if x < n:
            seen.append(x)
            continue
        a, b = tree[x, 1], tree[x, 2]
        assert tree[a, 0] == x and tree[b, 0] == x
        assert lb[x, K.LB_N] == lb[a, K.LB_N] + lb[b, K.LB_N]
        stack += [a, b]
    assert sorted(seen) == list(range(1, n))


# ---------------------------------------------------------------- emitter groups
def _tube(length=12.0, radius=0.03, height=1.0):
    """An emissive cylinder along x (a neon tube) of 256 x 8 quads."""
    from displacement.surfaces import Cylinder

    return SceneObject(Cylinder(radius, length), emissive_material((np.pi * 20.0,) * 3),
                       make_transform(translate=(0.0, height, 0.0),
                                      rotate=(0.0, 0.0, 90.0)),
                       resolution=(256, 8))


def test_an_emitter_of_many_triangles_is_sampled_in_groups():
    """The tube's triangles become 32 lights that partition them (each triangle in the
    group ``face_light`` names, areas summing to the tube's), and from a point near
    one end the nearest group is the likeliest."""
    from render.lights import GROUP_FACES, GROUPS

    tb = light_tables([], [_tube()], selection="contribution")
    n = _lights(tb)
    assert n == GROUPS
    tube = np.flatnonzero(tb.face_object == 0)
    groups = tb.face_light[tube]
    assert np.all(groups >= 0) and sorted(np.unique(groups)) == list(range(n))
    tri = tb.light_tri
    for j in range(n):
        faces = tri[int(tb.lights[j, LS.L_TRI]):int(tb.lights[j, LS.L_TRI_END]), LS.T_FACE]
        faces = faces.astype(np.int64)
        assert len(faces) >= GROUP_FACES and np.all(tb.face_light[faces] == j)
    c = tri[:, LS.T_CORNERS:LS.T_CORNERS + 9].reshape(-1, 3, 3)
    area = 0.5 * np.linalg.norm(np.cross(c[:, 1] - c[:, 0], c[:, 2] - c[:, 0]), axis=1).sum()
    assert np.sum(1.0 / tb.lights[:n, LS.L_PDF_AREA]) == pytest.approx(area, rel=1e-12)
    p = np.array([[-5.5, 0.0, 0.0]])
    pr = selection(tb, p, np.array([[0.0, 1.0, 0.0]]))[0]
    centre = tb.lights[:n, LS.LB_C]  # the lights (the tree's nodes follow)
    assert abs(centre[np.argmax(pr)] + 5.5) < 1.5  # the tube is cut into 1.5 lengths
    assert np.all(pr[centre > 3.0] < pr.max() / 20)
    assert pr.sum() == pytest.approx(1.0, rel=1e-12)


def test_a_small_emitter_stays_one_light():
    tb = light_tables([], [_quad(0.0)], selection="contribution")
    assert _lights(tb) == 1
