"""Regression renders of the Handbook's figures against committed references.

Each ``gallery/scenes/*.toml`` is rendered at ``TEST_SPP`` samples per pixel with a fixed
seed and compared with ``gallery/reference/NAME.exr`` (512 spp) by RMSE and mean FLIP.
The thresholds are not guessed: ``gallery/make_references.py`` measured both errors for
four other seeds at the same sample count, and the test allows 1.5 times the largest
(``thresholds.json``).  The image means must also agree within 6 standard deviations of
the seed-to-seed spread of the means (plus 0.5 % for the half-float reference).  On
failure the test render, the reference and the error map are written next to each other
in the test's temporary folder.
"""

from __future__ import annotations

import json
import sys
from pathlib import Path

import numpy as np
import pytest

ROOT = Path(__file__).resolve().parents[2]
sys.path.insert(0, str(ROOT / "gallery"))

import make_references as G  # noqa: E402

THRESHOLDS = json.loads((G.REFERENCE / "thresholds.json").read_text())
NAMES = sorted(p.stem for p in G.SCENES.glob("*.toml"))


def test_every_scene_has_a_reference():
    assert NAMES, "no gallery scenes"
    for name in NAMES:
        assert (G.REFERENCE / f"{name}.exr").exists() and (G.REFERENCE / f"{name}.png").exists(), (
            name
        )
        assert name in THRESHOLDS, f"{name}: run python gallery/make_references.py {name}"


@pytest.mark.parametrize("name", NAMES)
def test_gallery_scene_matches_reference(name, tmp_path):
    entry = THRESHOLDS[name]
    ref = G.read_reference(name)
    film = G.render_scene(name, entry["test_spp"], G.TEST_SEED)
    img = film.rgb()
    assert img.shape == ref.shape and np.all(np.isfinite(img)) and img.min() >= 0
    rmse, flip = G.errors(img, ref)
    mean_diff = np.abs(img.mean(axis=(0, 1)) - ref.mean(axis=(0, 1)))
    mean_tol = 6.0 * np.asarray(entry["mean_std"]) + 0.005 * ref.mean(axis=(0, 1))
    ok = rmse <= entry["rmse_max"] and flip <= entry["flip_max"] and np.all(mean_diff <= mean_tol)
    if not ok:
        import flip_evaluator

        from render.film import Film

        err, _, _ = flip_evaluator.evaluate(G.srgb(ref), G.srgb(img), "LDR")
        for tag, data in (("img", img), ("ref", ref), ("err", np.asarray(err, dtype=np.float64))):
            f = Film(img.shape[1], img.shape[0])
            f.add(
                np.arange(img.shape[0] * img.shape[1]),
                data.reshape(-1, 3),
                np.ones(img.shape[0] * img.shape[1]),
            )
            f.write_exr(tmp_path / f"{name}_{tag}.exr")
    assert ok, (
        f"{name}: RMSE {rmse:.4f} (max {entry['rmse_max']:.4f}), FLIP {flip:.4f} "
        f"(max {entry['flip_max']:.4f}), mean difference {mean_diff} (max {mean_tol}); "
        f"images in {tmp_path}"
    )


def test_contact_sheet_is_current():
    import runpy

    sheet = runpy.run_path(str(ROOT / "gallery" / "contact_sheet.py"))["contact_sheet"]()
    assert (ROOT / "gallery" / "README.md").read_text(encoding="utf-8") == sheet, \
        "run: python gallery/contact_sheet.py"
