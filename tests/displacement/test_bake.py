"""displacement.bake and ``pwc bake``: maps against analytic normals, encodings, round trips."""

from __future__ import annotations

import argparse

import numpy as np
import pytest
from repo import ROOT, run_pwc

from displacement.bake import (
    angle_between,
    bake,
    displaced_normal,
    map_size,
    quantize,
    roundtrip_errors,
    texel_uv,
    to_tangent_frame,
    write_height_map,
    write_normal_map,
    write_vector_map,
)
from displacement.bump import HORIZON_MIN_COS, bump_normal
from displacement.fields import constant
from displacement.state import ShadingState
from displacement.surfaces import UnitSquare
from displacement.textures import read_texture

A, K, M = 0.02, 3, 2


def sinusoid(state):
    u, v = state.uv[:, 0], state.uv[:, 1]
    return state.normal * (A * np.sin(2 * np.pi * K * u) * np.sin(2 * np.pi * M * v))[:, None]


def sinusoid_height(uv):
    return A * np.sin(2 * np.pi * K * uv[..., 0]) * np.sin(2 * np.pi * M * uv[..., 1])


def sinusoid_normal(uv):
    u, v = uv[:, 0], uv[:, 1]
    hu = A * 2 * np.pi * K * np.cos(2 * np.pi * K * u) * np.sin(2 * np.pi * M * v)
    hv = A * 2 * np.pi * M * np.sin(2 * np.pi * K * u) * np.cos(2 * np.pi * M * v)
    n = np.stack([-hu, -hv, np.ones_like(hu)], axis=1)
    return n / np.linalg.norm(n, axis=1, keepdims=True)


class Transformed:
    """The unit square under a linear map ``mat`` (p -> p @ mat.T), frames as MDL reports them.

    With a rotation the frame stays orthonormal; with a shear, tangent_v is not
    perpendicular to tangent_u (the normal is their normalized cross product).
    ``flip_v`` makes the chart left-handed (v runs downwards).
    """

    def __init__(self, mat, flip_v=False):
        self.mat = np.asarray(mat, float)
        self.flip_v = flip_v

    def state_at_uv(self, uv):
        uv = np.asarray(uv, float).reshape(-1, 2)
        p = np.zeros((len(uv), 3))
        p[:, 0] = uv[:, 0]
        p[:, 1] = 1.0 - uv[:, 1] if self.flip_v else uv[:, 1]
        dpdu = np.broadcast_to(self.mat @ [1.0, 0, 0], p.shape)
        dpdv = np.broadcast_to(self.mat @ [0, -1.0 if self.flip_v else 1.0, 0], p.shape)
        n = np.broadcast_to(self.mat @ [1.0, 0, 0], p.shape)
        n = np.cross(self.mat @ [1.0, 0, 0], self.mat @ [0, 1.0, 0])
        n = np.broadcast_to(n / np.linalg.norm(n), p.shape)
        tu = dpdu / np.linalg.norm(dpdu, axis=1, keepdims=True)
        tv = dpdv / np.linalg.norm(dpdv, axis=1, keepdims=True)
        return ShadingState(p @ self.mat.T, n.copy(), uv.copy(), tu.copy(), tv.copy())


def _rotation(rng):
    q, r = np.linalg.qr(rng.normal(size=(3, 3)))
    q = q * np.sign(np.diag(r))
    if np.linalg.det(q) < 0:
        q[:, 0] = -q[:, 0]
    return q


# ---------------------------------------------------------------------------
# layout and simple fields


def test_texel_uv_layout_row_zero_is_the_top():
    uv = texel_uv((4, 2))
    assert uv.shape == (2, 4, 2)
    assert uv[0, 0].tolist() == [0.125, 0.75]
    assert uv[1, 3].tolist() == [0.875, 0.25]
    with pytest.raises(ValueError, match="between 1 and 16384"):
        map_size(0)
    with pytest.raises(ValueError, match="whole numbers"):
        map_size(2.5)


def test_constant_field_bakes_flat_normals_and_its_vector():
    maps = bake(constant((0.1, -0.2, 0.3)), size=(3, 2))
    assert np.allclose(maps.normal, [0, 0, 1])
    assert np.allclose(maps.height, 0.3)
    assert np.allclose(maps.vector_tangent, [0.1, -0.2, 0.3])
    assert np.allclose(maps.vector_object, [0.1, -0.2, 0.3])
    assert (maps.width, maps.height_px) == (3, 2)


def test_sinusoid_bake_matches_the_analytic_surface_at_texel_centres():
    maps = bake(sinusoid, size=128)
    uv = maps.uv.reshape(-1, 2)
    assert np.allclose(maps.height.ravel(), sinusoid_height(uv), atol=1e-15)
    assert np.allclose(maps.vector_tangent[..., :2], 0.0, atol=1e-15)
    # central differences with a quarter-texel step: measured 4.3e-3 degrees at 128
    err = angle_between(maps.normal_object.reshape(-1, 3), sinusoid_normal(uv))
    assert err.max() < 5e-3
    # on the unit square tangent space is object space
    assert np.allclose(maps.normal, maps.normal_object)


@pytest.mark.parametrize(
    "bits, mean, p99, worst",
    # measured at 128 px, 20000 samples: 8-bit 0.113 / 0.240 / 0.294,
    # 16-bit 0.033 / 0.071 / 0.078 (interpolation-limited), float the same as 16-bit
    [(8, 0.13, 0.27, 0.33), (16, 0.037, 0.08, 0.09), ("float", 0.037, 0.08, 0.09)],
)
def test_roundtrip_bake_decode_error_bounds(bits, mean, p99, worst):
    angles, _ = roundtrip_errors(sinusoid, sinusoid_normal, 128, bits, samples=20000)
    assert angles.mean() < mean
    assert np.percentile(angles, 99) < p99
    assert angles.max() < worst


def test_roundtrip_error_falls_with_resolution_until_8_bit_quantization_dominates():
    maps = {n: bake(sinusoid, size=n) for n in (64, 256)}
    e = {
        (n, b): roundtrip_errors(
            sinusoid, sinusoid_normal, n, b, samples=5000, maps=maps[n]
        )[0].mean()
        for n in (64, 256)
        for b in (8, "float")
    }
    assert e[(256, "float")] < e[(64, "float")] / 10  # second order: 0.133 -> 0.0083
    assert e[(256, 8)] > 10 * e[(256, "float")]  # 8-bit floor ~0.11 degrees


def test_rotated_surface_gives_the_same_tangent_maps(rng):
    rot = _rotation(rng)
    flat = bake(sinusoid, UnitSquare(), 32)
    turned = bake(sinusoid, Transformed(rot), 32)
    assert np.allclose(turned.normal, flat.normal, atol=1e-9)
    assert np.allclose(turned.vector_tangent, flat.vector_tangent, atol=1e-12)
    assert np.allclose(turned.normal_object, flat.normal_object @ rot.T, atol=1e-9)
    assert np.allclose(turned.vector_object, flat.vector_object @ rot.T, atol=1e-12)


def test_skewed_frame_decodes_back_to_the_displaced_normal():
    shear = np.array([[1.0, 0.5, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]])
    surface = Transformed(shear)
    maps = bake(sinusoid, surface, 16)
    state = surface.state_at_uv(maps.uv.reshape(-1, 2))
    # decode each texel at its centre: a 16x16 map looked up at texel centres
    from displacement.textures import Texture

    tex = Texture(0.5 + 0.5 * maps.normal)
    decoded = bump_normal(state, tex)
    err = angle_between(decoded, maps.normal_object.reshape(-1, 3))
    assert err.max() < 1e-9
    vec = to_tangent_frame(state, maps.vector_object.reshape(-1, 3))
    rebuilt = (
        vec[:, :1] * state.tangent_u + vec[:, 1:2] * state.tangent_v + vec[:, 2:] * state.normal
    )
    assert np.allclose(rebuilt, maps.vector_object.reshape(-1, 3))


def test_left_handed_chart_still_faces_the_base_normal():
    maps = bake(sinusoid, Transformed(np.eye(3), flip_v=True), 16)
    assert np.all(maps.normal_object[..., 2] > 0.5)
    assert np.all(maps.normal[..., 2] > 0.5)


def test_tangential_and_degenerate_fields_stay_finite():
    along_u = bake(lambda s: 0.3 * s.tangent_u, size=8)
    assert np.allclose(along_u.normal, [0, 0, 1])
    assert np.allclose(along_u.vector_tangent, [0.3, 0, 0])
    collapse = bake(lambda s: -s.position, size=8)  # every point to the origin
    assert np.allclose(collapse.normal, [0, 0, 1])
    with pytest.raises(ValueError, match="NaN or inf"):
        bake(lambda s: s.normal * np.nan, size=4)
    with pytest.raises(ValueError, match="expected"):
        bake(lambda s: s.uv, size=4)
    with pytest.raises(ValueError, match="step"):
        bake(sinusoid, size=4, step=0.0)
    with pytest.raises(ValueError, match="step must be > 0"):
        displaced_normal(sinusoid, UnitSquare(), np.zeros((1, 2)), -1.0)


# ---------------------------------------------------------------------------
# files


@pytest.mark.parametrize(
    "name, bits, step",
    # rounding moves each colour by at most half a step q, so each component of n by at
    # most q and the normal by at most sqrt(3) q radians (first order): q = 1/255,
    # 1/65535, 2^-11 (half, colours in [0.5, 1)), 2^-23 (float).  Measured worst at
    # 32-128 px: 0.31, 0.0012, 0.041, 5.0e-6 degrees against bounds 0.39, 0.0015, 0.048, 1.2e-5
    [("n.png", 8, 1 / 255), ("n.png", 16, 1 / 65535), ("n.exr", "half", 2.0**-11),
     ("n.exr", "float", 2.0**-23)],
)
def test_normal_map_files_decode_at_texel_centres(tmp_path, name, bits, step):
    bound = 1.05 * np.degrees(np.sqrt(3.0) * step)
    maps = bake(sinusoid, size=32)
    path = write_normal_map(tmp_path / name, maps.normal, bits)
    tex = read_texture(path)
    state = UnitSquare().state_at_uv(maps.uv.reshape(-1, 2))
    err = angle_between(bump_normal(state, tex), maps.normal_object.reshape(-1, 3))
    assert err.max() < bound
    # quantization as quantize() models it is what the file stored
    assert np.allclose(tex.data, quantize(0.5 + 0.5 * maps.normal, bits), atol=1e-12)


def test_directx_normal_map_decodes_with_directx(tmp_path):
    maps = bake(sinusoid, size=16)
    tex = read_texture(write_normal_map(tmp_path / "dx.exr", maps.normal, convention="directx"))
    state = UnitSquare().state_at_uv(maps.uv.reshape(-1, 2))
    good = bump_normal(state, tex, convention="directx")
    assert angle_between(good, maps.normal_object.reshape(-1, 3)).max() < 1e-5
    wrong = bump_normal(state, tex)
    assert angle_between(wrong, maps.normal_object.reshape(-1, 3)).max() > 1.0


def test_height_map_files(tmp_path):
    maps = bake(sinusoid, size=16)
    path, low, high = write_height_map(tmp_path / "h.png", maps.height, 16)
    grey = read_texture(path).data[..., 0]
    assert np.allclose(low + grey * (high - low), maps.height, atol=(high - low) / 65535)
    path, low, high = write_height_map(tmp_path / "h.exr", maps.height)
    assert np.array_equal(read_texture(path).data[..., 0], maps.height.astype(np.float32))
    flat_path, lo, hi = write_height_map(tmp_path / "flat.png", np.zeros((2, 2)), 8)
    assert lo == hi == 0.0 and np.all(read_texture(flat_path).data == 0)


def test_vector_map_files(tmp_path):
    import OpenEXR

    d = np.random.default_rng(4).normal(size=(4, 5, 3))
    p = write_vector_map(tmp_path / "v.exr", d)
    assert np.array_equal(read_texture(p).data, d.astype(np.float32))
    p = write_vector_map(tmp_path / "v2.exr", d, order="unv", bits="half")
    assert np.array_equal(read_texture(p).data, d[..., [0, 2, 1]].astype(np.float16))
    with OpenEXR.File(str(p)) as f:
        assert f.header()["space"] == "tangent" and f.header()["channelOrder"] == "unv"
    with pytest.raises(ValueError, match="signed"):
        write_vector_map(tmp_path / "v.png", d)
    with pytest.raises(ValueError, match="space"):
        write_vector_map(tmp_path / "v.exr", d, space="world")


# ---------------------------------------------------------------------------
# a real profile: ornament_2 along v (creases and walls)


def _ornament():
    import pwc
    from displacement.pwc_fields import displace_with_pwc

    curve = pwc.load(ROOT / "profiles" / "ornament_2.pwc")

    def exact(uv):
        d = curve.derivative(uv[:, 1])
        n = np.stack([np.zeros(len(uv)), -d[:, 0], d[:, 1]], axis=1)
        return n / np.linalg.norm(n, axis=1, keepdims=True)

    return displace_with_pwc(curve, "along_v"), exact, np.asarray(curve.t)


def test_ornament_2_round_trip_away_from_creases():
    field, exact, knots = _ornament()
    size = 256
    angles, uv = roundtrip_errors(field, exact, size, 16, samples=20000)
    assert np.all(np.isfinite(angles))
    near = np.min(np.abs(uv[:, 1:2] - knots[None, :]), axis=1) < 2.0 / size
    z = exact(uv)[:, 2]
    wall = np.abs(z) < HORIZON_MIN_COS  # depth changes at constant run
    undercut = z <= -HORIZON_MIN_COS  # arcs turning back: no bump normal can show them
    smooth = angles[~near & ~wall & ~undercut]
    # measured at 256 px, 16-bit: mean 0.0023, p99 0.049, max 0.072 degrees
    assert smooth.mean() < 0.005 and np.percentile(smooth, 99) < 0.06 and smooth.max() < 0.09
    # walls (normal at the horizon) come back held by the horizon rule: asin(0.01) = 0.573
    assert np.allclose(angles[~near & wall], np.degrees(np.arcsin(HORIZON_MIN_COS)), atol=1e-3)


# ---------------------------------------------------------------------------
# the command


def _pwc(*args, cwd):
    return run_pwc("bake", *args, cwd=cwd)


def test_pwc_bake_writes_readable_maps(tmp_path):
    profile = str(ROOT / "profiles" / "ornament_2.pwc")
    r = _pwc(profile, "--normal-map", "n.png", "--height-map", "h.exr", "--vector-map", "v.exr",
             "--size", "32", cwd=tmp_path)
    assert r.returncode == 0, r.stderr
    assert "normal map" in r.stdout and "vector map" in r.stdout
    n = read_texture(tmp_path / "n.png")
    assert n.data.shape == (32, 32, 3)
    assert read_texture(tmp_path / "h.exr").data.shape == (32, 32, 1)
    assert read_texture(tmp_path / "v.exr").data.shape == (32, 32, 3)
    r = _pwc(profile, "--along", "u", "--repeat", "3", "--normal-map", "n8.png", "--bits", "8",
             "--size", "16", "--convention", "directx", cwd=tmp_path)
    assert r.returncode == 0, r.stderr
    # along u: the map varies across columns only
    d = read_texture(tmp_path / "n8.png").data
    assert np.allclose(d, d[:1], atol=1e-12)


@pytest.mark.parametrize(
    "args, status, message",
    [
        (["missing.pwc", "--normal-map", "n.png"], 3, "no such file"),
        (["ornament2", "--normal-map", "n.png"], 3, "did you mean 'ornament_2'?"),
        (["{profile}"], 2, "nothing to write"),
        (["{profile}", "--normal-map", "n.png", "--bits", "half"], 2, "PNG stores 8 or 16"),
        (["{profile}", "--vector-map", "v.png"], 2, "OpenEXR"),
        (["{profile}", "--normal-map", "n.tif"], 2, "unsupported format"),
        (["{profile}", "--normal-map", "afile/n.png"], 3, "afile is a file, not a folder"),
        (["{profile}", "--normal-map", "/proc/n.png"], 3, "does not accept new files"),
        (["{profile}", "--normal-map", "n.png", "--size", "0"], 2, "--size"),
        (["{profile}", "--normal-map", "n.png", "--repeat", "-1"], 2, "--repeat"),
    ],
)
def test_pwc_bake_errors_are_one_line(tmp_path, args, status, message):
    profile = str(ROOT / "profiles" / "ornament_2.pwc")
    (tmp_path / "afile").write_text("")
    r = _pwc(*[a.format(profile=profile) for a in args], cwd=tmp_path)
    assert r.returncode == status
    assert message in r.stderr
    assert "Traceback" not in r.stderr
    assert len(r.stderr.strip().splitlines()) == 1


def test_pwc_bake_bad_profile_reports_diagnostics(tmp_path):
    (tmp_path / "bad.pwc").write_text("0 0\nnot a number\n")
    r = _pwc("bad.pwc", "--normal-map", "n.png", cwd=tmp_path)
    assert r.returncode == 1
    assert "Traceback" not in r.stderr and "bad.pwc" in r.stderr


def test_pwc_bake_help_and_run_function(tmp_path):
    r = run_pwc("bake", "--help")
    assert r.returncode == 0 and "--normal-map" in r.stdout and "OpenGL" in r.stdout
    from displacement.commands.bake import register

    parser = argparse.ArgumentParser()
    register(parser.add_subparsers())
    args = parser.parse_args(
        ["bake", str(ROOT / "profiles" / "segments.pwc"), "--height-map",
         str(tmp_path / "h.png"), "--size", "8"]
    )
    assert args.func(args) == 0
    assert read_texture(tmp_path / "h.png").data.shape == (8, 8, 1)


def test_pwc_bake_by_name_into_new_folders_warns_of_undercuts(tmp_path):
    """ornament 2's rows 215-220 (at 512 px) face into the surface: a normal map cannot
    show that, and bake says so; the torus has no undercut and bakes silently."""
    r = _pwc("ornament_2", "--normal-map", "maps/deep/n.png", "--size", "512", cwd=tmp_path)
    assert r.returncode == 0, r.stderr
    assert (tmp_path / "maps" / "deep" / "n.png").is_file()
    assert "warning" in r.stderr and "rows 215\u2013220 (v 0.569\u20130.579)" in r.stderr
    assert "undercuts" in r.stderr and "true displacement" in r.stderr
    r = _pwc("ornament_2", "--along", "u", "--height-map", "h.exr", "--size", "512",
             cwd=tmp_path)
    assert r.returncode == 0 and "columns 60 (u 0.118), 291\u2013296" in r.stderr
    r = _pwc("torus", "--normal-map", "t.png", "--size", "64", cwd=tmp_path)
    assert r.returncode == 0 and r.stderr == ""
    r = _pwc("ornament_2", "--vector-map", "v.exr", "--size", "64", cwd=tmp_path)
    assert r.returncode == 0 and r.stderr == ""  # a vector map shows undercuts


def test_undercut_runs_at_the_extremes():
    from displacement.commands.bake import undercut_runs

    flat = np.zeros((4, 4, 3))
    flat[..., 2] = 1.0
    assert undercut_runs(flat, "v") == [] and undercut_runs(flat, "u") == []
    edge_on = flat.copy()
    edge_on[..., 2] = 0.0  # a vertical step: seen edge-on, not an undercut
    assert undercut_runs(edge_on, "v") == []
    inward = -flat
    assert undercut_runs(inward, "v") == [(0, 3)] and undercut_runs(inward, "u") == [(0, 3)]
