"""Stability of images at the extremes (docs/stability.md, "Images"): 1 x 1 renders with
every AOV, denoised; 16k x 16k (and larger) refused with a clear error, before any
dicing, when the film would not fit in memory; the film's memory estimate is measured."""

from __future__ import annotations

import dataclasses
import re
import tracemalloc

import numpy as np
import pytest
from repo import run_pwc
from stability import assert_valid_radiance

from render.film import (
    AOVS,
    Film,
    FilmTooLarge,
    available_memory,
    check_film_memory,
    film_bytes,
    read_exr,
)
from render.integrator import render
from render.library.resources import bundled_scenes
from render.scene import load_scene

SCENE = bundled_scenes() / "fig_14_28.toml"  # a displaced square: dicing follows the image
ALL_AOVS = ",".join(AOVS)


# -- 1 x 1 -------------------------------------------------------------------------------
def test_a_one_pixel_image_renders():
    scene = load_scene(SCENE, overrides={"width": 1, "height": 1, "spp": 8})
    scene.camera = dataclasses.replace(scene.camera, width=1, height=1)
    film = render(scene, aovs=list(AOVS), progress=False)
    img = assert_valid_radiance(film)
    assert img.shape == (1, 1, 3) and film.spp.tolist() == [[8]]
    assert 0.0 <= film.alpha()[0, 0] <= 1.0
    for name in AOVS:
        assert np.all(np.isfinite(film.aov(name)))
    assert film.stats["geometry"][1]["triangles"] >= 2  # diced for one pixel: a few triangles


def test_a_one_pixel_image_from_the_command_with_every_output(tmp_path):
    exr, png = tmp_path / "one.exr", tmp_path / "one.png"
    r = run_pwc("render", SCENE, "-o", exr, "--png", png, "--resolution", 1, 1, "--spp", 4,
                "--aov", ALL_AOVS, "--denoise", "--quiet")
    assert r.returncode == 0, r.stderr
    channels = read_exr(exr)
    assert channels["RGBA"].shape == (1, 1, 4) and np.all(np.isfinite(channels["RGBA"]))
    assert all(np.all(np.isfinite(v)) for v in channels.values())
    from PIL import Image

    assert Image.open(png).size == (1, 1)


# -- 16k x 16k and beyond ------------------------------------------------------------------
def test_the_film_estimate_bounds_what_a_film_and_its_outputs_allocate(tmp_path, rng):
    w, h = 256, 192
    n = w * h
    tracemalloc.start()
    try:
        before = tracemalloc.get_traced_memory()[0]
        tracemalloc.reset_peak()
        film = Film(w, h, list(AOVS))
        film.add(np.arange(n), rng.random((n, 3)), np.ones(n),
                 {"albedo": rng.random((n, 3)), "normal": rng.random((n, 3)),
                  "depth": rng.random(n), "uv": rng.random((n, 2)),
                  "object_id": np.zeros(n, np.int32)})
        film.denoise()
        film.write_exr(tmp_path / "f.exr")
        film.write_png(tmp_path / "f.png")
        peak = tracemalloc.get_traced_memory()[1] - before
    finally:
        tracemalloc.stop()
    estimate = film_bytes(w, h, list(AOVS), denoise=True)
    assert peak <= estimate, (peak / n, estimate / n)
    assert peak >= 0.5 * estimate, (peak / n, estimate / n)  # and not wildly pessimistic


def test_a_16k_image_is_refused_exactly_when_it_does_not_fit():
    need = film_bytes(16384, 16384)
    available = available_memory()
    assert need == 16384 * 16384 * 145  # 36 GB
    if available is not None and need > available:
        with pytest.raises(FilmTooLarge, match=r"a 16384 x 16384 image needs about 36\.2 GB"):
            check_film_memory(16384, 16384)
    else:
        assert check_film_memory(16384, 16384) == need
    # the same rule against any stated amount of memory
    with pytest.raises(FilmTooLarge, match=r"render it smaller \(--resolution W H"):
        check_film_memory(16384, 16384, available=need - 1)
    assert check_film_memory(16384, 16384, available=need) == need


def test_a_16k_image_from_the_command_is_refused_before_any_work(tmp_path):
    need = film_bytes(16384, 16384)
    available = available_memory()
    if available is None or need <= available:
        pytest.skip(f"this machine has {available} bytes free: a 16k image fits (rendering "
                    "it is not a test)")
    out = tmp_path / "big.exr"
    r = run_pwc("render", SCENE, "-o", out, "--resolution", 16384, 16384)
    assert r.returncode == 1 and "Traceback" not in r.stderr
    assert "a 16384 x 16384 image needs about 36.2 GB" in r.stderr and "--resolution" in r.stderr
    assert not out.exists()
    # refused up front: the one line of the error, nothing diced, compiled or rendered
    assert r.stderr.strip().count("\n") == 0 and "dic" not in r.stderr.lower()


def test_an_image_no_machine_can_hold_is_refused_by_the_api_before_dicing(tmp_path):
    text = re.sub(r"(?m)^resolution = .*$", "resolution = [65536, 65536]", SCENE.read_text())
    assert "65536" in text
    scene_file = tmp_path / "huge.toml"
    scene_file.write_text(text)
    scene = load_scene(scene_file)
    if (available_memory() or 0) >= film_bytes(65536, 65536):
        pytest.skip("this machine has more than 580 GB free")
    with pytest.raises(FilmTooLarge, match="65536 x 65536"):
        scene.build()
    r = run_pwc("render", scene_file, "-o", tmp_path / "huge.exr", "--aov", ALL_AOVS)
    assert r.returncode == 1 and "65536 x 65536 image needs about" in r.stderr
    assert "Traceback" not in r.stderr
