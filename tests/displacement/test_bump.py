"""displacement.bump: chapter 13, the accurate height-map normal, conventions, the horizon."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import example, given, settings
from hypothesis import strategies as st

from displacement.bake import angle_between
from displacement.bump import (
    HORIZON_MIN_COS,
    bend_normal,
    bump_normal,
    clamp_to_horizon,
    color_from_normal,
    decode_normal_colors,
    encode_normal_colors,
    fractional_uv,
    height_map_normal,
    modify_normal_from_texture,
    nearby_texture_differences,
    normal_as_color,
    normal_to_tangent_space,
    round_bump_normal,
    texture_2d_lookup_float3,
)
from displacement.state import ShadingState
from displacement.surfaces import UnitSquare
from displacement.textures import Texture

SQ = UnitSquare()
EXTREME_UV = np.array(
    [[0.0, 0.0], [1.0, 1.0], [0.0, 1.0], [-0.3, -2.7], [1e9 + 0.25, -1e9], [0.5, 0.5],
     [1 - 1e-16, 1e-300]]
)


def _unit(v):
    v = np.asarray(v, dtype=float)
    return v / np.linalg.norm(v, axis=-1, keepdims=True)


def _rotated_state(uv, rot: np.ndarray) -> ShadingState:
    """The unit square's state with its frame rotated by ``rot`` (rows: p @ rot.T)."""
    s = SQ.state_at_uv(uv)
    return ShadingState(
        s.position @ rot.T, s.normal @ rot.T, s.uv, s.tangent_u @ rot.T, s.tangent_v @ rot.T
    )


def _random_rotation(rng) -> np.ndarray:
    q, r = np.linalg.qr(rng.normal(size=(3, 3)))
    q = q * np.sign(np.diag(r))
    if np.linalg.det(q) < 0:
        q[:, 0] = -q[:, 0]
    return q


def _assert_good_normals(n, reference, min_cos=HORIZON_MIN_COS):
    assert np.all(np.isfinite(n))
    assert np.allclose(np.linalg.norm(n, axis=1), 1.0, atol=1e-12)
    assert np.all(np.einsum("ij,ij->i", n, reference) >= min_cos - 1e-12)


# ---------------------------------------------------------------------------
# fractional_uv and round bumps (Listings 13.1, 13.5)


def test_fractional_uv_at_the_extremes():
    s = SQ.state_at_uv(np.array([[0.0, 1.0], [1.0, 0.0], [-0.3, -2.7], [0.26, 0.55]]))
    got = fractional_uv(s, 8, 4)
    assert got.round(12).tolist() == [[0.0, 0.0], [0.0, 0.0], [0.6, 0.2], [0.08, 0.2]]
    assert np.all((got >= 0) & (got <= 1))


def test_round_bump_normal_by_hand():
    # tile centre: unchanged; (0.75, 0.5): N + s (0.25, 0) ; on the circle (0.5, 1.0): inside (<=)
    s = SQ.state_at_uv(np.array([[0.5, 0.5], [0.75, 0.5], [0.5, 1.0 - 1e-12], [0.05, 0.05]]))
    got = round_bump_normal(s, bump_scale=2.0)
    assert np.allclose(got[0], [0, 0, 1])
    assert np.allclose(got[1], _unit([0.5, 0, 1]))
    assert np.allclose(got[2], _unit([0, 1.0, 1]), atol=1e-9)
    assert np.allclose(got[3], [0, 0, 1])  # corner: outside the circle


@pytest.mark.parametrize("bump_scale", [0.0, 1.0, -1.0, 100.0, -100.0, 1e6, -1e300])
def test_round_bump_normal_extreme_scales_stay_unit_and_above_horizon(rng, bump_scale):
    uv = np.concatenate([rng.random((500, 2)) * 3 - 1, EXTREME_UV])
    s = SQ.state_at_uv(uv)
    n = round_bump_normal(s, bump_scale=bump_scale, u_scale=8, v_scale=4)
    _assert_good_normals(n, s.normal)
    if bump_scale == 0.0:
        assert np.array_equal(n, s.normal)


def test_round_bump_negative_scale_mirrors_the_tangential_part(rng):
    s = SQ.state_at_uv(rng.random((200, 2)))
    up = round_bump_normal(s, 1.0, 4, 4)
    down = round_bump_normal(s, -1.0, 4, 4)
    assert np.allclose(down[:, :2], -up[:, :2])
    assert np.allclose(down[:, 2], up[:, 2])


def test_round_bump_normal_follows_a_rotated_frame(rng):
    rot = _random_rotation(rng)
    uv = rng.random((100, 2))
    flat = round_bump_normal(SQ.state_at_uv(uv), 3.0, 2, 2)
    turned = round_bump_normal(_rotated_state(uv, rot), 3.0, 2, 2)
    assert np.allclose(turned, flat @ rot.T, atol=1e-12)


def test_round_bump_scale_can_vary_with_state():
    s = SQ.state_at_uv(np.array([[0.75, 0.5], [0.75, 0.5]]))
    uv = np.array([[0.75, 0.5], [0.25, 0.5]])
    s = ShadingState(s.position, s.normal, uv, s.tangent_u, s.tangent_v)
    got = round_bump_normal(s, bump_scale=lambda st: np.array([4.0, -4.0]))
    assert np.allclose(got, [_unit([1, 0, 1]), _unit([1, 0, 1])])


# ---------------------------------------------------------------------------
# section 13.5: the Handbook's height-map normal


def _ramp_texture(w=16, h=4, slope_per_texel=0.01):
    return Texture(np.tile(np.arange(w) * slope_per_texel, (h, 1)))


def test_nearby_texture_differences_are_forward_differences():
    tex = _ramp_texture(w=16)
    s = SQ.state_at_uv(np.array([[0.25 + 1 / 32, 0.5]]))  # a texel centre (index 4)
    d = nearby_texture_differences(s, tex, (1 / 16, 1 / 4), (1.0, 1.0))
    assert d.round(12).tolist() == [[0.01, 0.0]]


def test_bend_normal_by_hand_and_degenerate():
    s = SQ.state_at_uv(np.array([[0.5, 0.5], [0.1, 0.1]]))
    got = bend_normal(s, s.tangent_v, np.array([0.02, 0.0]), np.array([-0.01, 0.0]))
    assert np.allclose(got[0], _unit([0, 0.01, 0.02]))
    assert np.array_equal(got[1], [0.0, 0.0, 1.0])  # zero vector -> the normal


def test_modify_normal_from_texture_on_a_linear_ramp_by_hand():
    # slope: value rises 0.01 per texel; texel = 1/16 uv -> forward difference slope 0.16
    tex = _ramp_texture(w=16, slope_per_texel=0.01)
    s = SQ.state_at_uv(np.array([[0.25 + 1 / 32, 0.5]]))
    got = modify_normal_from_texture(s, tex)
    d = 1 / 16
    u_bend = _unit([-0.01, 0, d])
    expected = _unit(u_bend + [0, 0, 1])
    assert np.allclose(got[0], expected, atol=1e-12)
    # the Handbook's normal tilts by exactly half the slope angle
    tilt = np.degrees(np.arctan2(-got[0, 0], got[0, 2]))
    assert tilt == pytest.approx(0.5 * np.degrees(np.arctan(0.16)), abs=1e-9)


def test_modify_normal_pixel_distance_and_texture_scale():
    tex = _ramp_texture(w=16, slope_per_texel=0.01)
    s = SQ.state_at_uv(np.array([[0.125 + 1 / 64, 0.5]]))
    # tiled twice: the uv distance halves, the value step stays one texel: slope doubles
    got = modify_normal_from_texture(s, tex, pixel_distance=(2.0, 2.0), texture_scale=(2.0, 2.0))
    d = 2 / (16 * 2)
    assert np.allclose(got[0], _unit(_unit([-0.02, 0, d]) + [0, 0, 1]), atol=1e-12)
    with pytest.raises(ValueError, match="texture_scale must be > 0"):
        modify_normal_from_texture(s, tex, texture_scale=(0.0, 1.0))
    with pytest.raises(ValueError, match="pixel_distance must be > 0"):
        modify_normal_from_texture(s, tex, pixel_distance=-1.0)


def _height_maps(rng):
    w = 32
    flat = Texture(np.full((w, w), 0.5))
    steep = Texture((np.arange(w)[None, :] >= w // 2).astype(float) * np.ones((w, 1)))
    checker = Texture(((np.arange(w)[None, :] + np.arange(w)[:, None]) % 2).astype(float))
    noise = Texture(rng.random((w, w, 3)))
    return {"flat": flat, "steep": steep, "checker": checker, "noise": noise}


@pytest.mark.parametrize("kind", ["flat", "steep", "checker", "noise"])
def test_height_map_normals_flat_steep_and_discontinuous(rng, kind):
    tex = _height_maps(rng)[kind]
    uv = np.concatenate([rng.random((400, 2)) * 4 - 2, EXTREME_UV])
    s = _rotated_state(uv, _random_rotation(rng))
    for scale in (1.0, 40.0):
        a = modify_normal_from_texture(s, tex, texture_scale=(scale, scale))
        b = height_map_normal(s, tex, height_scale=scale, texture_scale=(scale, scale))
        c = height_map_normal(s, tex, height_scale=-1e12)
        for n in (a, b, c):
            _assert_good_normals(n, s.normal)
        if kind == "flat":
            assert np.allclose(a, s.normal) and np.allclose(b, s.normal)


# ---------------------------------------------------------------------------
# the accurate height-map normal against an analytic oracle


@pytest.mark.parametrize(
    "width, bound_max, bound_mean",
    # measured max / mean: 64 -> 0.184 / 0.103, 256 -> 0.0115 / 0.0065 (second order)
    [(64, 0.2, 0.11), (256, 0.013, 0.007)],
)
def test_height_map_normal_matches_analytic_sinusoid(rng, width, bound_max, bound_mean):
    k, hs = 2, 0.05
    s_c = (np.arange(width) + 0.5) / width
    tex = Texture(np.tile(0.5 + 0.5 * np.sin(2 * np.pi * k * s_c), (4, 1)))
    uv = rng.random((20000, 2))
    st_ = SQ.state_at_uv(uv)
    got = height_map_normal(st_, tex, height_scale=hs)
    g = hs * 0.5 * 2 * np.pi * k * np.cos(2 * np.pi * k * uv[:, 0])
    exact = _unit(np.stack([-g, np.zeros_like(g), np.ones_like(g)], 1))
    angles = angle_between(got, exact)
    assert angles.max() < bound_max
    assert angles.mean() < bound_mean
    # the Handbook's version reads values as heights in uv units and tilts the normal by
    # exactly half the angle of the forward-difference slope, on any map
    hb = modify_normal_from_texture(st_, tex)
    d = 1.0 / width
    rise = tex.lookup(uv + [d, 0.0])[:, 0] - tex.lookup(uv)[:, 0]
    half = np.arctan2(-hb[:, 0], hb[:, 2])
    assert np.allclose(half, 0.5 * np.arctan2(rise, d), atol=1e-9)
    assert np.allclose(hb[:, 1], 0.0, atol=1e-12)


def test_height_map_normal_exact_on_ramps_and_scales():
    tex = Texture(np.tile(np.linspace(0.0, 1.0, 9), (9, 1)).T[::-1].copy())  # rises with v
    s = SQ.state_at_uv(np.array([[0.5, 0.5]]))
    # value rises 1/8 per texel of 1/9 uv: dh/dt = 9/8
    got = height_map_normal(s, tex, height_scale=1.0, wrap="clamp")
    assert np.allclose(got[0], _unit([0, -9 / 8, 1]))
    got = height_map_normal(s, tex, height_scale=1.0, uv_length=(1.0, 2.0), wrap="clamp")
    assert np.allclose(got[0], _unit([0, -9 / 16, 1]))
    got = height_map_normal(s, tex, height_scale=-2.0, wrap="clamp")
    assert np.allclose(got[0], _unit([0, 9 / 4, 1]))


# ---------------------------------------------------------------------------
# normal maps


def _constant_map(color) -> Texture:
    return Texture(np.broadcast_to(np.asarray(color, float), (2, 2, 3)).copy())


def test_texture_2d_lookup_float3_fit():
    s = SQ.state_at_uv(np.array([[0.1, 0.9]]))
    t = _constant_map([0.25, 0.5, 1.0])
    assert texture_2d_lookup_float3(s, t, 1.0, 0.0, 1.0, -1.0, 1.0).tolist() == [[-0.5, 0.0, 1.0]]
    assert texture_2d_lookup_float3(s, t, 1.0, 0.0, 0.5, 0.0, 1.0).tolist() == [[0.5, 1.0, 2.0]]
    with pytest.raises(ValueError, match="must differ"):
        texture_2d_lookup_float3(s, t, 1.0, 0.5, 0.5)


def test_bump_normal_by_hand_with_scales_and_conventions():
    s = SQ.state_at_uv(np.array([[0.3, 0.7]]))
    t = _constant_map(encode_normal_colors(np.array([0.0, 0.6, 0.8])))
    assert np.allclose(bump_normal(s, t), [[0.0, 0.6, 0.8]])
    assert np.allclose(bump_normal(s, t, convention="directx"), [[0.0, -0.6, 0.8]])
    assert np.allclose(bump_normal(s, t, bump_scale=0.5), _unit([[0, 0.3, 0.8]]))
    assert np.allclose(bump_normal(s, t, scale_vector_z=False), _unit([[0, 0.6, 1.0]]))
    # a float map storing n itself
    raw = _constant_map([0.0, 0.6, 0.8])
    assert np.allclose(bump_normal(s, raw, sample_min=-1.0, sample_max=1.0), [[0, 0.6, 0.8]])
    with pytest.raises(ValueError, match="opengl"):
        bump_normal(s, t, convention="vulkan")


@pytest.mark.parametrize("bump_scale", [0.0, 1.0, -1.0, 100.0, -100.0])
@pytest.mark.parametrize(
    "color", [[0.5, 0.5, 1.0], [1.0, 0.5, 0.5], [0.0, 0.0, 0.0], [0.5, 0.5, 0.0], [1.0, 1.0, 0.2]]
)
def test_bump_normal_extremes_never_black_or_nan(rng, bump_scale, color):
    uv = np.concatenate([rng.random((50, 2)), EXTREME_UV])
    s = _rotated_state(uv, _random_rotation(rng))
    n = bump_normal(s, _constant_map(color), bump_scale=bump_scale)
    _assert_good_normals(n, s.normal)
    if bump_scale == 0.0 and color[2] > 0.5:
        assert np.allclose(n, s.normal)


def test_bump_normal_below_horizon_is_bent_back_by_the_rule():
    s = SQ.state_at_uv(np.array([[0.5, 0.5]]))
    # decodes to (0.8, 0, -0.6): below the surface
    t = _constant_map(encode_normal_colors(np.array([0.8, 0.0, -0.6])))
    got = bump_normal(s, t)[0]
    assert got[2] == pytest.approx(HORIZON_MIN_COS)
    assert got[1] == pytest.approx(0.0)
    assert got[0] == pytest.approx(np.sqrt(1 - HORIZON_MIN_COS**2))
    assert np.allclose(bump_normal(s, t, horizon=None)[0], [0.8, 0, -0.6])


@settings(max_examples=60)
@given(
    st.tuples(st.floats(-1, 1), st.floats(-1, 1), st.floats(-1, 1)),
    st.tuples(st.floats(-1, 1), st.floats(-1, 1), st.floats(-1, 1)),
    st.floats(0.0, 0.9),
)
@example(n=(1.0, 0.0, 0.0), r=(-0.5, 0.0, 1e-08), min_cos=0.0)  # n - c r cancels
def test_clamp_to_horizon_properties(n, r, min_cos):
    n = np.array([n])
    r = np.array([r])
    if np.linalg.norm(r) < 1e-3:
        r = np.array([[0.0, 0.0, 1.0]])
    r = _unit(r)
    out = clamp_to_horizon(n, r, min_cos)
    assert np.all(np.isfinite(out))
    assert np.linalg.norm(out) == pytest.approx(1.0)
    assert (out @ r.T).item() >= min_cos - 1e-9
    if np.linalg.norm(n) > 1e-6:
        nu = _unit(n)
        if (nu @ r.T).item() >= min_cos:
            assert np.allclose(out, nu, atol=1e-9)
        else:
            # stays in the plane of n and r
            assert abs((np.cross(nu, r) @ out.T).item()) < 1e-6


def test_clamp_to_horizon_rejects_bad_min_cos():
    with pytest.raises(ValueError, match="min_cos"):
        clamp_to_horizon(np.array([[0, 0, 1.0]]), np.array([[0, 0, 1.0]]), 1.0)


@settings(max_examples=40)
@given(st.tuples(st.floats(-1, 1), st.floats(-1, 1), st.floats(0.05, 1)))
def test_encode_decode_round_trip(n):
    n = _unit(np.array(n))
    for conv in ("opengl", "directx"):
        c = encode_normal_colors(n, conv)
        assert np.all((c >= 0) & (c <= 1))
        assert np.allclose(decode_normal_colors(c, conv), n, atol=1e-12)


def test_directx_and_opengl_differ_only_in_green():
    n = _unit(np.array([0.3, -0.4, 0.8]))
    gl, dx = encode_normal_colors(n, "opengl"), encode_normal_colors(n, "directx")
    assert gl[0] == dx[0] and gl[2] == dx[2] and gl[1] == pytest.approx(1 - dx[1])


def test_normal_to_tangent_space_inverts_bump_normal_on_skewed_frames(rng):
    n_pts = 300
    tu = _unit(rng.normal(size=(n_pts, 3)))
    nrm = _unit(np.cross(tu, rng.normal(size=(n_pts, 3))))
    tv = _unit(np.cross(nrm, tu) + 0.6 * tu * rng.uniform(-1, 1, (n_pts, 1)))  # skewed
    s = ShadingState(np.zeros((n_pts, 3)), nrm, rng.random((n_pts, 2)), tu, tv)
    target = _unit(nrm + 0.7 * _unit(rng.normal(size=(n_pts, 3))))
    target = np.where((np.einsum("ij,ij->i", target, nrm) < 0.1)[:, None], nrm, target)
    c = normal_to_tangent_space(s, target)
    assert np.allclose(np.linalg.norm(c, axis=1), 1.0)
    decoded = _unit(c[:, :1] * tu + c[:, 1:2] * tv + c[:, 2:] * nrm)
    assert np.allclose(decoded, target, atol=1e-12)


# ---------------------------------------------------------------------------
# showing normals as colour (Listings 13.17, 13.18)


def test_color_from_normal_and_normal_as_color():
    n = np.array([[0.0, 0.0, 1.0], [-1.0, 0.0, 0.0]])
    assert color_from_normal(n, False).tolist() == [[0.5, 0.5, 1.0], [0.0, 0.5, 0.5]]
    expected = np.array([[0.5, 0.5, 1.0], [0, 0.5, 0.5]]) / np.pi
    assert np.allclose(color_from_normal(n, True), expected)
    quarter = np.array([[0.0, -1.0, 0.0], [1.0, 0.0, 0.0], [0.0, 0.0, 1.0]])  # +90 deg about z
    x_axis = np.array([[1.0, 0.0, 0.0]])
    assert np.allclose(color_from_normal(x_axis, False, quarter), [[0.5, 1.0, 0.5]])
    with pytest.raises(ValueError, match="singular"):
        color_from_normal(n, False, np.zeros((3, 3)))
    emit = normal_as_color(n)
    assert np.array_equal(emit.tint, np.zeros((2, 3)))
    assert np.allclose(emit.intensity, color_from_normal(n, True))
    refl = normal_as_color(n, normal_color_as_emission=False)
    assert np.array_equal(refl.intensity, np.zeros((2, 3)))
