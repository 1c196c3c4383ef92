"""Regression renders of the Handbook's figures against the committed references.

Each figure is rendered by the rule of :mod:`gallery.compare` (the rule ``pwc gallery
check`` applies): small (128 pixels wide; the reference averaged down to that size), 16
samples per pixel, a fixed seed, and judged by RMSE, mean FLIP and the image mean against
thresholds that ``python -m gallery.references`` measured at four other seeds.  On
failure the render, the reference and the FLIP map are written next to each other in the
test's temporary folder.
"""

from __future__ import annotations

import re

import numpy as np
import pytest
from PIL import Image

from gallery import compare
from gallery.figures import figures
from render.film import write_exr_channels

FIGURES = figures()
TABLE = compare.read_table()
REFERENCES = compare.reference_dir()


def test_every_figure_has_a_reference_at_its_size_and_stated_noise():
    assert FIGURES, "no gallery scenes"
    for fig in FIGURES:
        assert fig.name in TABLE, f"run: python -m gallery.references {fig.name}"
        ref, test = TABLE[fig.name]["reference"], TABLE[fig.name]["test"]
        w, h = fig.resolution
        assert w >= 256 and h >= 192, f"{fig.name}: reference {w} x {h} is below 256 x 192"
        assert ref["resolution"] == [w, h], f"{fig.name}: the scene's size changed since"
        assert compare.read_reference(fig.name).shape == (h, w, 3)
        with Image.open(REFERENCES / f"{fig.name}.png") as png:
            assert png.size == (w, h)
        # the noise was measured from the batches, and met the target stated with it
        assert ref["batches"] >= 4 and ref["spp"] == ref["batches"] * ref["batch_spp"]
        assert 0 < ref["noise"] <= ref["noise_target"], fig.name
        assert test["resolution"] == list(fig.test_resolution)
        assert test["spp"] == compare.TEST_SPP and test["seed"] == compare.TEST_SEED
        assert compare.TEST_SEED not in test["calibration_seeds"]
        assert test["rmse_max"] == pytest.approx(compare.MARGIN * max(test["rmse"]), abs=1e-6)
        assert test["flip_max"] == pytest.approx(compare.MARGIN * max(test["flip"]), abs=1e-6)


# The weave height map (Figures 12.17, 12.19-12.21) has cliffs where threads cross, which
# keep the dicer refining until its triangle cap; it says so, and the reference was
# diced the same way (the test image is diced as the reference: gallery.compare).
@pytest.mark.filterwarnings("ignore::displacement.dice.mesh.DicingCapWarning")
@pytest.mark.parametrize("fig", FIGURES, ids=[f.name for f in FIGURES])
def test_figure_matches_its_reference(fig, tmp_path):
    outcome = compare.check(fig, TABLE)
    img = outcome.image
    assert img.shape == (*fig.test_resolution[::-1], 3)
    assert np.all(np.isfinite(img)) and img.min() >= 0
    if not outcome.passed:
        for tag, data in (("img", img), ("ref", outcome.reference),
                          ("err", np.repeat(outcome.error_map[..., None], 3, axis=2))):
            write_exr_channels(tmp_path / f"{fig.name}_{tag}.exr",
                               {c: data[..., i].astype(np.float32) for i, c in enumerate("RGB")})
    assert outcome.passed, f"{fig.name}: {'; '.join(outcome.reasons())}; images in {tmp_path}"


def test_the_committed_contact_sheet_shows_every_figure():
    """gallery/index.html is generated (pwc gallery sheet); it must list every figure and
    every image it links must exist."""
    page_path = REFERENCES.parent / "index.html"
    page = page_path.read_text(encoding="utf-8")
    for fig in FIGURES:
        assert f"id='{fig.name}'" in page, f"{fig.name} missing: run pwc gallery sheet"
    sources = re.findall(r"<img src='([^']+)'", page)
    assert len(sources) == 3 * len(FIGURES)
    for src in sources:
        assert (page_path.parent / src).is_file(), src
