"""The gallery's page of distribution functions (``gallery/dfs``): one scene of three
spheres per df, its reference at the stated noise, and the gallery's regression rule
(:mod:`gallery.compare`) on each."""

from __future__ import annotations

import numpy as np
import pytest
from PIL import Image

from gallery import compare, dfs
from render.film import write_exr_channels

FIGURES = dfs.figures()
FOLDER = dfs.reference_dir()
TABLE = compare.read_table(FOLDER)


def test_scenes_are_the_page_list(tmp_path):
    # the committed scenes are what write_scenes makes from DFS (one list of truth), and
    # every df of the list has one
    written = {p.name: p.read_text() for p in dfs.write_scenes(tmp_path)}
    committed = {p.name: p.read_text() for p in dfs.scenes_dir().glob("df_*.toml")}
    assert written == committed
    assert {f.name for f in FIGURES} == {f"df_{n}" for n in dfs.DFS}


def test_every_scene_has_a_reference_at_the_stated_noise():
    for fig in FIGURES:
        assert fig.name in TABLE, f"run: python -m gallery.dfs {fig.name}"
        ref, test = TABLE[fig.name]["reference"], TABLE[fig.name]["test"]
        w, h = fig.resolution
        assert ref["resolution"] == [w, h]
        assert compare.read_reference(fig.name, FOLDER).shape == (h, w, 3)
        with Image.open(FOLDER / f"{fig.name}.png") as png:
            assert png.size == (w, h)
        assert ref["batches"] >= 4 and 0 < ref["noise"] <= ref["noise_target"], fig.name
        assert test["resolution"] == list(fig.test_resolution)
        assert test["rmse_max"] == pytest.approx(compare.MARGIN * max(test["rmse"]), abs=1e-6)


@pytest.mark.parametrize("fig", FIGURES, ids=[f.name for f in FIGURES])
def test_scene_matches_its_reference(fig, tmp_path):
    outcome = compare.check(fig, TABLE, FOLDER)
    img = outcome.image
    assert img.shape == (*fig.test_resolution[::-1], 3)
    assert np.all(np.isfinite(img)) and img.min() >= 0
    # three spheres that differ: the roughness shows (left and right thirds differ)
    third = img.shape[1] // 3
    assert np.abs(img[:, :third].mean() - img[:, -third:].mean()) > 1e-4
    if not outcome.passed:
        for tag, data in (("img", img), ("ref", outcome.reference)):
            write_exr_channels(tmp_path / f"{fig.name}_{tag}.exr",
                               {c: data[..., i].astype(np.float32) for i, c in enumerate("RGB")})
    assert outcome.passed, f"{fig.name}: {'; '.join(outcome.reasons())}; images in {tmp_path}"


def test_the_page_shows_every_scene():
    page = (dfs.HERE / "index.html").read_text(encoding="utf-8")
    for fig in FIGURES:
        assert f"id='{fig.name}'" in page
        assert (FOLDER / f"{fig.name}.png").is_file()
