"""Render the gallery's reference images and measure the noise thresholds of its test.

Run explicitly (never from the test suite)::

    python gallery/make_references.py                 # every scene in gallery/scenes
    python gallery/make_references.py fig_12_06 ...   # some of them

For each ``gallery/scenes/NAME.toml`` it writes

* ``gallery/reference/NAME.exr``: linear RGBA, 16-bit half floats, rendered with
  ``REFERENCE_SPP`` samples per pixel;
* ``gallery/reference/NAME.png``: its sRGB preview;

and records in ``gallery/reference/thresholds.json`` what the regression test
(``tests/gallery/test_gallery.py``) needs: the RMSE and mean FLIP (LDR, on the sRGB
images) of ``TEST_SPP`` renders against the reference for ``CALIBRATION_SEEDS`` seeds
(not the test's seed), and the spread of their image means.  The test allows
``MARGIN`` times the largest error measured here: a change that only reshuffles the
noise stays inside, a change of the image (a wrong material, light or geometry) does not.
"""

from __future__ import annotations

import json
import sys
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
SCENES = ROOT / "gallery" / "scenes"
REFERENCE = ROOT / "gallery" / "reference"

REFERENCE_SPP = 512
TEST_SPP = 16
TEST_SEED = 7
CALIBRATION_SEEDS = (101, 102, 103, 104)
MARGIN = 1.5


def srgb(img: np.ndarray) -> np.ndarray:
    """sRGB-encoded float32 image in [0, 1] (what LDR-FLIP compares)."""
    from render.film import linear_to_srgb

    return linear_to_srgb(img).astype(np.float32)


def errors(test: np.ndarray, ref: np.ndarray) -> tuple[float, float]:
    """(RMSE of the linear images, mean LDR-FLIP of their sRGB encodings)."""
    import flip_evaluator

    rmse = float(np.sqrt(np.mean((test - ref) ** 2)))
    _, flip, _ = flip_evaluator.evaluate(srgb(ref), srgb(test), "LDR", applyMagma=False)
    return rmse, float(flip)


def read_reference(name: str) -> np.ndarray:
    """(h, w, 3) float64 linear reference image of a scene."""
    from render.film import read_exr

    return read_exr(REFERENCE / f"{name}.exr")["RGBA"][..., :3]


def render_scene(name: str, spp: int, seed: int, progress: bool = False):
    from render.integrator import render

    return render(SCENES / f"{name}.toml", spp=spp, seed=seed, progress=progress)


def main(argv: list[str]) -> int:
    import argparse

    parser = argparse.ArgumentParser(
        description="Render the gallery's reference images (slow) and calibrate the "
                    "regression thresholds from renders at other seeds.")
    parser.add_argument("names", nargs="*", metavar="SCENE",
                        help="scene names such as fig_14_28 (default: every scene)")
    names = parser.parse_args(argv).names or sorted(p.stem for p in SCENES.glob("*.toml"))
    REFERENCE.mkdir(parents=True, exist_ok=True)
    table_path = REFERENCE / "thresholds.json"
    table = json.loads(table_path.read_text()) if table_path.exists() else {}
    for name in names:
        t0 = time.perf_counter()
        film = render_scene(name, REFERENCE_SPP, 0, progress=True)
        film.write_exr(REFERENCE / f"{name}.exr", aovs=[], half=True)
        film.write_png(REFERENCE / f"{name}.png")
        ref = read_reference(name)  # as stored (half floats)
        rmse, flip, means = [], [], []
        for seed in CALIBRATION_SEEDS:
            img = render_scene(name, TEST_SPP, seed).rgb()
            r, f = errors(img, ref)
            rmse.append(r)
            flip.append(f)
            means.append(img.mean(axis=(0, 1)).tolist())
        table[name] = {
            "reference_spp": REFERENCE_SPP,
            "test_spp": TEST_SPP,
            "rmse": rmse,
            "flip": flip,
            "rmse_max": MARGIN * max(rmse),
            "flip_max": MARGIN * max(flip),
            "mean_std": np.std(np.array(means), axis=0, ddof=1).tolist(),
            "render_s": round(time.perf_counter() - t0, 1),
        }
        print(
            f"{name}: {film.stats['spp']} spp in {film.stats['time_s']:.1f} s; "
            f"{TEST_SPP}-spp RMSE {np.mean(rmse):.4f} (max {max(rmse):.4f}), "
            f"FLIP {np.mean(flip):.4f} (max {max(flip):.4f})",
            flush=True,
        )
        table_path.write_text(json.dumps(table, indent=1, sort_keys=True) + "\n")
    return 0


if __name__ == "__main__":
    sys.path.insert(0, str(ROOT))
    sys.exit(main(sys.argv[1:]))
