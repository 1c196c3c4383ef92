"""The film: box-filtered accumulation, AOV averaging, EXR layers round trip, sRGB PNG,
OIDN denoising, and defined output for pixels without samples or with bad samples."""

from __future__ import annotations

import numpy as np
import pytest

from render.film import AOVS, Film, linear_to_srgb, read_exr


def test_accumulation_is_a_box_filter_mean():
    f = Film(3, 2, aovs=["depth"])
    pixel = np.array([0, 0, 0, 5, 2])
    rgb = np.array([[1.0, 2, 3], [3, 2, 1], [2, 2, 2], [9, 9, 9], [0, 0, 0]])
    f.add(
        pixel,
        rgb,
        np.array([1.0, 0.0, 1.0, 1.0, 0.0]),
        {"depth": np.array([1.0, 2.0, 3.0, 4.0, 5.0])},
    )
    assert f.rgb()[0, 0].tolist() == [2.0, 2.0, 2.0]
    assert f.alpha()[0, 0] == pytest.approx(2 / 3)
    assert f.aov("depth")[0, 0, 0] == pytest.approx(2.0) and f.aov("depth")[1, 2, 0] == 4.0
    # pixels without samples are 0, not NaN
    assert f.rgb()[0, 1].tolist() == [0.0, 0.0, 0.0] and f.spp[0, 1] == 0


def test_nonfinite_samples_are_dropped_and_counted():
    f = Film(1, 1)
    f.add(np.array([0, 0]), np.array([[np.nan, 0, 0], [1.0, 1.0, 1.0]]), np.ones(2))
    assert f.rgb()[0, 0].tolist() == [0.5, 0.5, 0.5] and f.stats["nonfinite_samples"] == 1


def test_object_id_keeps_the_first_sample():
    f = Film(2, 1, aovs=["object_id"])
    f.add(np.array([1, 1, 0]), np.zeros((3, 3)), np.ones(3), {"object_id": np.array([4, 7, -1])})
    f.add(np.array([0]), np.zeros((1, 3)), np.ones(1), {"object_id": np.array([9])})
    assert f.aov("object_id").tolist() == [[-1, 4]]


def test_unknown_aov_is_an_error():
    with pytest.raises(ValueError, match="unknown AOV 'colour'"):
        Film(2, 2, aovs=["colour"])
    with pytest.raises(ValueError, match="does not keep"):
        Film(2, 2).aov("albedo")


@pytest.mark.parametrize("half", [False, True])
def test_exr_round_trip_with_layers(tmp_path, half, rng):
    f = Film(5, 4, aovs=list(AOVS))
    n = 20
    vals = {
        "albedo": rng.random((n, 3)),
        "normal": rng.normal(size=(n, 3)),
        "depth": rng.random(n) * 100,
        "uv": rng.random((n, 2)),
        "object_id": rng.integers(-1, 5, n),
    }
    f.add(np.arange(n), rng.random((n, 3)) * 50, rng.random(n), vals)
    f.write_exr(tmp_path / "a.exr", half=half)
    ch = read_exr(tmp_path / "a.exr")
    tol = 1e-3 if half else 1e-6
    assert np.allclose(ch["RGBA"][..., :3], f.rgb(), rtol=tol)
    assert np.allclose(ch["RGBA"][..., 3], f.alpha(), rtol=tol, atol=tol)
    for name, chans in AOVS.items():
        for c, chan in enumerate(chans):
            got = ch[f"{name}.{chan}"]
            want = f.aov(name) if name == "object_id" else f.aov(name)[..., c]
            assert np.allclose(got, want, rtol=tol, atol=tol), name
    # only the layers asked for
    f.write_exr(tmp_path / "b.exr", aovs=["depth"])
    assert set(read_exr(tmp_path / "b.exr")) == {"R", "G", "B", "A", "RGBA", "depth.Z"}


def test_png_is_srgb_and_clamped(tmp_path):
    from PIL import Image

    f = Film(3, 1)
    f.add(np.arange(3), np.array([[0.0, 0.0, 0.0], [0.5, 0.5, 0.5], [20.0, -1.0, 0.0]]), np.ones(3))
    f.write_png(tmp_path / "p.png")
    px = np.asarray(Image.open(tmp_path / "p.png"))
    assert px[0].tolist() == [[0, 0, 0], [188, 188, 188], [255, 0, 0]]
    assert linear_to_srgb(np.array([np.nan]))[0] == 0.0


def test_oidn_denoising_reduces_error():
    # a smooth ramp plus noise: the denoiser must bring it closer to the ramp
    rng = np.random.default_rng(0)
    h, w = 64, 64
    truth = np.repeat(np.linspace(0.1, 0.9, w)[None, :, None], h, axis=0).repeat(3, axis=2)
    f = Film(w, h, aovs=["albedo", "normal"])
    pix = np.arange(h * w)
    noisy = truth.reshape(-1, 3) * rng.exponential(1.0, (h * w, 1))
    f.add(
        pix,
        noisy,
        np.ones(h * w),
        {"albedo": np.full((h * w, 3), 0.8), "normal": np.tile([0, 0, 1.0], (h * w, 1))},
    )
    before = np.sqrt(np.mean((f.rgb() - truth) ** 2))
    out = f.denoise()
    after = np.sqrt(np.mean((out - truth) ** 2))
    assert np.all(np.isfinite(out)) and after < 0.5 * before
    assert np.array_equal(f.rgb(), out)
