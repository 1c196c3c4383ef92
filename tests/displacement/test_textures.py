"""displacement.textures: file round trips, uv origin, filtering, wrap, errors, gallery tiling."""

from __future__ import annotations

import importlib.util
import struct
import zlib
from pathlib import Path

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from PIL import Image

from displacement import textures as T
from displacement.surfaces import UnitSquare
from displacement.textures import (
    Texture,
    linear_to_srgb,
    read_texture,
    srgb_to_linear,
    texture_2d_lookup_scaled,
    texture_2d_sample,
    write_texture,
)

ROOT = Path(__file__).resolve().parents[2]
GALLERY = ROOT / "gallery" / "textures"


def _load_make_textures():
    spec = importlib.util.spec_from_file_location(
        "make_textures", GALLERY / "make_textures.py"
    )
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


# ---------------------------------------------------------------------------
# PNG


@pytest.mark.parametrize("channels", [1, 2, 3, 4])
@pytest.mark.parametrize("bits, maxval", [(8, 255), (16, 65535)])
def test_png_round_trip_is_exact_at_the_code_values(tmp_path, rng, channels, bits, maxval):
    a = rng.random((13, 17, channels))
    path = write_texture(tmp_path / "a.png", a, bits=bits)
    t = read_texture(path)
    expected = np.round(a * maxval) / maxval
    assert t.data.shape == (13, 17, channels)
    assert np.array_equal(t.data, expected)
    assert t.channel_names == T._default_channel_names(channels)


def test_16_bit_grey_png_agrees_with_pillow_both_ways(tmp_path, rng):
    codes = rng.integers(0, 65536, size=(9, 11)).astype(np.uint16)
    write_texture(tmp_path / "ours.png", codes / 65535.0, bits=16)
    with Image.open(tmp_path / "ours.png") as im:
        assert np.array_equal(np.asarray(im).astype(np.uint16), codes)
    Image.fromarray(codes).save(tmp_path / "pillow.png")
    assert np.array_equal(read_texture(tmp_path / "pillow.png").data[:, :, 0] * 65535, codes)


def test_16_bit_rgb_png_keeps_all_16_bits(tmp_path):
    # Pillow reads 16-bit RGB as 8-bit; our codec must keep the low byte
    a = np.zeros((1, 2, 3))
    a[0, 0] = [1 / 65535, 2 / 65535, 3 / 65535]
    a[0, 1] = [65534 / 65535, 0.5, 1.0]
    t = read_texture(write_texture(tmp_path / "rgb16.png", a, bits=16))
    assert np.round(t.data * 65535).tolist() == [[[1, 2, 3], [65534, 32768, 65535]]]


def _encode_with_filters(codes: np.ndarray, filters: list[int]) -> bytes:
    """A slow reference PNG filter encoder (per byte), for decoding tests."""
    h, w, c = codes.shape
    raw = codes.astype(">u2").view(np.uint8).reshape(h, w * c * 2).astype(int)
    bpp = 2 * c
    prev = np.zeros(raw.shape[1], int)
    rows = []
    for r in range(h):
        x, f = raw[r], filters[r]
        out = []
        for i in range(len(x)):
            a = x[i - bpp] if i >= bpp else 0
            b = prev[i]
            cc = prev[i - bpp] if i >= bpp else 0
            if f == 0:
                pred = 0
            elif f == 1:
                pred = a
            elif f == 2:
                pred = b
            elif f == 3:
                pred = (a + b) // 2
            else:
                p = a + b - cc
                pa, pb, pc = abs(p - a), abs(p - b), abs(p - cc)
                pred = a if pa <= pb and pa <= pc else (b if pb <= pc else cc)
            out.append((x[i] - pred) % 256)
        rows.append(bytes([f] + out))
        prev = x
    return b"".join(rows)


@pytest.mark.parametrize("channels, colour_type", [(1, 0), (3, 2), (4, 6)])
def test_16_bit_png_decodes_all_five_row_filters(tmp_path, rng, channels, colour_type):
    h, w = 12, 7
    codes = rng.integers(0, 65536, size=(h, w, channels)).astype(np.uint16)
    body = _encode_with_filters(codes, [r % 5 for r in range(h)])
    path = tmp_path / "filters.png"
    with open(path, "wb") as fh:
        fh.write(T._PNG_SIGNATURE)
        fh.write(T._chunk(b"IHDR", struct.pack(">IIBBBBB", w, h, 16, colour_type, 0, 0, 0)))
        fh.write(T._chunk(b"IDAT", zlib.compress(body)))
        fh.write(T._chunk(b"IEND", b""))
    assert np.array_equal(np.round(read_texture(path).data * 65535), codes)


def test_png_writer_rejects_values_it_cannot_store(tmp_path):
    with pytest.raises(ValueError, match=r"\[0, 1\]"):
        write_texture(tmp_path / "n.png", np.array([[-0.5, 0.5]]))
    with pytest.raises(ValueError, match="NaN"):
        write_texture(tmp_path / "n.png", np.array([[np.nan, 0.5]]))
    with pytest.raises(ValueError, match="1 to 4 channels"):
        write_texture(tmp_path / "n.png", np.zeros((2, 2, 5)))
    with pytest.raises(ValueError, match="use a .exr file"):
        write_texture(tmp_path / "n.png", np.zeros((2, 2)), bits="half")
    with pytest.raises(ValueError, match="use a .png file"):
        write_texture(tmp_path / "n.exr", np.zeros((2, 2)), bits=16)
    with pytest.raises(ValueError, match="unsupported texture format"):
        write_texture(tmp_path / "n.tif", np.zeros((2, 2)))
    with pytest.raises(FileNotFoundError, match="does not exist"):
        write_texture(tmp_path / "missing" / "n.png", np.zeros((2, 2)))


# ---------------------------------------------------------------------------
# OpenEXR


@pytest.mark.parametrize("bits, dtype", [("half", np.float16), ("float", np.float32)])
def test_exr_round_trip_half_and_float(tmp_path, rng, bits, dtype):
    a = (rng.random((6, 5, 3)) - 0.5) * 100.0
    t = read_texture(write_texture(tmp_path / "a.exr", a, bits=bits))
    assert t.channel_names == ("R", "G", "B")
    assert np.array_equal(t.data, a.astype(dtype).astype(np.float64))


def test_exr_named_layers_and_attributes(tmp_path, rng):
    import OpenEXR

    n = rng.random((4, 3, 3)) * 2 - 1
    path = write_texture(tmp_path / "n.exr", n, layer="N", attributes={"space": "tangent"})
    t = read_texture(path)  # the only layer
    assert t.channel_names == ("N.X", "N.Y", "N.Z")
    assert np.array_equal(t.data, n.astype(np.float32).astype(np.float64))
    with OpenEXR.File(str(path)) as f:
        assert f.header()["space"] == "tangent"
    assert read_texture(path, layer="N").channel_names == ("N.X", "N.Y", "N.Z")
    with pytest.raises(ValueError, match="no layer 'P'"):
        read_texture(path, layer="P")


def test_exr_with_several_layers_needs_a_layer_choice(tmp_path, rng):
    import OpenEXR

    x = rng.random((2, 2)).astype(np.float32)
    chans = {"N.X": x, "N.Y": x, "N.Z": x, "P.X": 2 * x, "P.Y": 2 * x, "P.Z": 2 * x}
    with OpenEXR.File({"compression": OpenEXR.ZIP_COMPRESSION}, chans) as f:
        f.write(str(tmp_path / "two.exr"))
    with pytest.raises(ValueError, match="several layers"):
        read_texture(tmp_path / "two.exr")
    p = read_texture(tmp_path / "two.exr", layer="P")
    assert p.channel_names == ("P.X", "P.Y", "P.Z")
    assert np.allclose(p.data[..., 0], 2 * x)


def test_exr_half_overflow_and_names_are_checked(tmp_path):
    with pytest.raises(ValueError, match="65504"):
        write_texture(tmp_path / "h.exr", np.array([[1e5]]), bits="half")
    with pytest.raises(ValueError, match="distinct channel names"):
        write_texture(tmp_path / "h.exr", np.zeros((2, 2, 2)), channel_names=("A", "A"))


# ---------------------------------------------------------------------------
# reading errors and gamma


def test_missing_file_error_names_the_path(tmp_path):
    missing = tmp_path / "nowhere" / "weave_depth.png"
    with pytest.raises(FileNotFoundError, match="weave_depth.png"):
        read_texture(missing)


def test_unsupported_format_is_a_clear_error(tmp_path):
    (tmp_path / "x.tif").write_bytes(b"II*\x00not really a tiff")
    with pytest.raises(ValueError, match="unsupported texture format"):
        read_texture(tmp_path / "x.tif")
    with pytest.raises(ValueError, match="gamma"):
        read_texture(tmp_path / "x.tif", gamma="2.2")


def test_gamma_default_decodes_png_as_srgb_and_exr_as_linear(tmp_path):
    grey = np.full((1, 1, 3), 128 / 255)
    png = write_texture(tmp_path / "g.png", grey)
    exr = write_texture(tmp_path / "g.exr", grey)
    assert read_texture(png).data[0, 0, 0] == pytest.approx(128 / 255)
    assert read_texture(png, gamma="default").data[0, 0, 0] == pytest.approx(0.2158605, 1e-6)
    assert read_texture(exr, gamma="default").data[0, 0, 0] == pytest.approx(128 / 255, 1e-7)
    # alpha is never decoded
    rgba = write_texture(tmp_path / "a.png", np.full((1, 1, 4), 128 / 255))
    assert read_texture(rgba, gamma="srgb").data[0, 0, 3] == pytest.approx(128 / 255)


@given(st.floats(0.0, 1.0))
def test_srgb_curves_are_inverse(x):
    assert linear_to_srgb(srgb_to_linear(x)) == pytest.approx(x, abs=1e-12)


def test_srgb_png_write_read_round_trip(tmp_path):
    lin = np.array([[[0.0, 0.2140, 1.0]]])
    t = read_texture(write_texture(tmp_path / "s.png", lin, gamma="srgb"), gamma="srgb")
    assert np.allclose(t.data, lin, atol=2e-3)


# ---------------------------------------------------------------------------
# orientation, filtering and wrap


def _quad() -> Texture:
    # row 0 is the top of the image: top-left 1, top-right 2, bottom-left 3, bottom-right 4
    return Texture(np.array([[1.0, 2.0], [3.0, 4.0]]))


def test_uv_origin_is_the_lower_left_of_the_image():
    t = _quad()
    centres = np.array([[0.25, 0.75], [0.75, 0.75], [0.25, 0.25], [0.75, 0.25]])
    assert t.lookup(centres)[:, 0].tolist() == [1.0, 2.0, 3.0, 4.0]
    assert (t.width, t.height) == (2, 2)
    assert (T.width(t), T.height(t)) == (2, 2)


def test_bilinear_filtering_between_texel_centres():
    t = _quad()
    uv = np.array([[0.5, 0.75], [0.25, 0.5], [0.5, 0.5]])
    assert t.lookup(uv, wrap_u="clamp", wrap_v="clamp")[:, 0].tolist() == [1.5, 2.0, 2.5]
    assert t.lookup(np.array([[0.4, 0.6]]), filter="nearest")[0, 0] == 1.0


def test_bilinear_reproduces_a_linear_ramp_exactly():
    w = 16
    t = Texture(np.tile(np.arange(w, dtype=float), (3, 1)))
    u = np.linspace(0.5 / w, 1 - 0.5 / w, 101)
    got = t.lookup(np.stack([u, np.full_like(u, 0.5)], 1), wrap_u="clamp")[:, 0]
    assert np.allclose(got, u * w - 0.5, atol=1e-12)


def test_wrap_modes_at_and_beyond_the_edges():
    t = Texture(np.array([[0.0, 1.0, 2.0, 3.0]]))  # texel centres at u = 1/8, 3/8, 5/8, 7/8
    u = np.array([0.0, 1.0, -0.25, 1.0 + 1 / 8, -7 / 8, 1e6 + 1 / 8, -1e-300])
    uv = np.stack([u, np.full_like(u, 0.5)], 1)
    rep = t.lookup(uv)[:, 0]
    # u = 0 and 1 sit halfway between the last and first texel: (3 + 0) / 2
    assert rep.tolist() == pytest.approx([1.5, 1.5, 2.5, 0.0, 0.0, 0.0, 1.5])
    clamp = t.lookup(uv, wrap_u="clamp")[:, 0]
    assert clamp.tolist() == [0.0, 3.0, 0.0, 3.0, 0.0, 3.0, 0.0]
    mirror = t.lookup(np.array([[1.125, 0.5], [-0.125, 0.5]]), wrap_u="mirrored_repeat")
    assert mirror[:, 0].tolist() == [3.0, 0.0]
    with pytest.raises(ValueError, match="wrap mode"):
        t.lookup(uv, wrap_u="border")


def test_lookup_rejects_non_finite_uv_and_bad_shapes():
    t = _quad()
    with pytest.raises(ValueError, match="NaN or inf"):
        t.lookup(np.array([[np.nan, 0.5]]))
    with pytest.raises(ValueError, match=r"\(n, 2\)"):
        t.lookup(np.zeros((3, 3)))
    with pytest.raises(ValueError, match="NaN or inf"):
        Texture(np.array([[np.inf]]))
    with pytest.raises(ValueError, match="shape"):
        Texture(np.zeros((2, 2, 2, 2)))


@settings(max_examples=50)
@given(
    st.lists(st.tuples(st.floats(-50, 50), st.floats(-50, 50)), min_size=1, max_size=20),
    st.integers(-5, 5),
    st.integers(-5, 5),
)
def test_repeat_lookup_is_periodic_and_a_convex_combination(points, ku, kv):
    data = np.random.default_rng(3).random((5, 7, 2))
    t = Texture(data)
    uv = np.array(points)
    a = t.lookup(uv)
    b = t.lookup(uv + [ku, kv])
    assert np.allclose(a, b, atol=1e-9)
    assert np.all(a >= data.min(axis=(0, 1)) - 1e-12)
    assert np.all(a <= data.max(axis=(0, 1)) + 1e-12)


def test_lookup_float_float3_and_color_channel_rules():
    rgba = Texture(np.array([[[0.1, 0.2, 0.3, 0.9]]]))
    grey = Texture(np.array([[0.4]]))
    uv = np.array([[0.5, 0.5]])
    assert T.lookup_float(rgba, uv).tolist() == [0.1]
    assert T.lookup_float3(rgba, uv).tolist() == [[0.1, 0.2, 0.3]]
    assert T.lookup_color(grey, uv).tolist() == [[0.4, 0.4, 0.4]]


# ---------------------------------------------------------------------------
# the Handbook's lookup functions


def test_texture_2d_lookup_scaled_uses_frac_of_scaled_uv():
    ramp = Texture(np.arange(8, dtype=float)[None, :])  # texel i centred at (i + .5) / 8
    s = UnitSquare().state_at_uv(np.array([[1 / 16, 0.5], [9 / 32, 0.5], [-3 / 32, 0.5]]))
    # u * 2 -> 1/8 (between texels 0 and 1), 9/16 (centre of texel 4), frac(-3/16) = 13/16
    got = texture_2d_lookup_scaled(s, ramp, 2.0, 1.0)[:, 0]
    assert got.tolist() == pytest.approx([0.5, 4.0, 6.0])
    assert texture_2d_lookup_scaled(s, ramp).shape == (3, 3)


def test_texture_2d_sample_scales_explicit_uv():
    ramp = Texture(np.arange(8, dtype=float)[None, :])
    uv = np.array([[9 / 32, 0.0], [1.0, 7.0], [-1 / 16, 0.0]])
    got = texture_2d_sample(ramp, (2.0, 1.0), uv)[:, 0]
    assert got.tolist() == pytest.approx([4.0, 3.5, 6.5])


# ---------------------------------------------------------------------------
# the gallery's textures


def test_gallery_textures_exist_small_and_readable():
    names = ["weave_depth.png", "weave_depth.exr", "weave_normal_map.png", "travertine.png"]
    sizes = [(GALLERY / n).stat().st_size for n in names]
    assert sum(sizes) < 3 * 1024 * 1024
    for n in names:
        t = read_texture(GALLERY / n)
        assert t.width <= 1024 and t.height <= 1024
    h_png = read_texture(GALLERY / "weave_depth.png").data[..., 0]
    h_exr = read_texture(GALLERY / "weave_depth.exr").data[..., 0]
    assert np.abs(h_png - h_exr).max() < 5e-4  # half precision near 1: 2^-11
    assert h_png.min() >= 0.0 and h_png.max() <= 1.0 and h_png.max() - h_png.min() > 0.8


def test_weave_and_travertine_generators_are_periodic_by_construction():
    mk = _load_make_textures()
    rng = np.random.default_rng(5)
    u, v = rng.random(2000), rng.random(2000)
    for f in (mk.weave_height, mk.travertine_color):
        base = f(u, v)
        for du, dv in [(1, 0), (0, 1), (-1, 2)]:
            assert np.allclose(f(u + du, v + dv), base, atol=1e-12)


def _seam_ratio(img: np.ndarray, axis: int) -> float:
    """Mean jump across the wrap over the mean jump between interior neighbours."""
    a = np.moveaxis(img, axis, 0)
    interior = np.abs(np.diff(a, axis=0)).mean()
    seam = np.abs(a[0] - a[-1]).mean()
    return seam / interior


@pytest.mark.parametrize("name", ["weave_depth.png", "weave_normal_map.png", "travertine.png"])
def test_written_textures_tile_without_seams(name):
    img = read_texture(GALLERY / name).data
    for axis in (0, 1):
        # measured 0.01-1.03 (the jump across the wrap is a typical neighbour step)
        assert _seam_ratio(img, axis) < 1.5
    # the check does see seams: cropped images give 4.2-23
    assert _seam_ratio(img[:, :400], 1) > 3.0
    assert _seam_ratio(img[:300], 0) > 3.0


def test_weave_normal_map_is_the_normal_of_the_height_map():
    from displacement.bake import angle_between
    from displacement.bump import bump_normal, height_map_normal

    mk = _load_make_textures()
    height = read_texture(GALLERY / "weave_depth.png")
    normals = read_texture(GALLERY / "weave_normal_map.png")
    rng = np.random.default_rng(9)
    s = UnitSquare().state_at_uv(rng.random((4000, 2)))
    from_map = bump_normal(s, normals)
    from_height = height_map_normal(s, height, height_scale=mk.RELIEF)
    assert np.all(from_map[:, 2] > 0.0)
    angles = angle_between(from_map, from_height)
    # the two differ at fibre creases (kinks of max()); measured median 0.12, mean 3.8 degrees
    assert np.median(angles) < 0.5
    assert angles.mean() < 5.0


def test_a_texture_filters_as_it_was_told():
    data = np.array([[0.0, 1.0], [2.0, 3.0]])
    uv = np.array([[0.3, 0.7], [0.6, 0.4]])
    bilinear = T.Texture(data)
    nearest = T.Texture(data, filter="nearest")
    assert bilinear.filter == "bilinear"  # MDL's default
    np.testing.assert_array_equal(nearest.lookup(uv), bilinear.lookup(uv, filter="nearest"))
    assert not np.array_equal(nearest.lookup(uv), bilinear.lookup(uv))
    np.testing.assert_array_equal(nearest.lookup(uv, filter="bilinear"), bilinear.lookup(uv))
    with pytest.raises(ValueError, match="filter must be one of nearest, bilinear"):
        T.Texture(data, filter="trilinear")
