"""Render the gallery's references to a stated noise level and measure the test's thresholds.

Run explicitly, never from the tests (slow: minutes per figure)::

    python -m gallery.references                   # every figure
    python -m gallery.references 13.14 fig_12_*    # some (chapters, numbers, names, globs)
    python -m gallery.references 12.12 --max-spp 4096 --noise 1.0

A reference is the mean of independent *batches* (each ``batch_spp`` samples per pixel
with its own seed), rendered at the scene's resolution until the noise of the mean is
at most the target, or the sample cap is reached.  The noise is measured, not assumed:
the batches' spread gives each pixel's standard error, which the sRGB encoding maps
to 8-bit levels of the PNG (:func:`display_noise`, the root mean square over pixels and
channels).  Noise 1.0 means the preview's grain is about one 8-bit level.

For each figure it writes ``NAME.exr`` (linear RGBA, half floats), ``NAME.png`` (the sRGB
preview) and the figure's entry in ``references.json``: how the reference was made
(samples, batches, measured noise, time, CPU time) and the thresholds of the
regression rule (:mod:`gallery.compare`), calibrated against the new reference.
"""

from __future__ import annotations

import json
import sys
import time
from pathlib import Path

import numpy as np

from gallery import compare
from gallery.figures import Figure, figures

__all__ = [
    "NOISE_TARGET",
    "MAX_SPP",
    "MAX_SPP_OF",
    "MIN_BATCHES",
    "SEED_BASE",
    "srgb_slope",
    "display_noise",
    "Batches",
    "make_reference",
    "calibrate",
    "main",
]

#: the stated noise level of a reference: RMS standard error, in 8-bit sRGB levels
NOISE_TARGET = 1.5
#: most samples per pixel a reference gets unless told otherwise
MAX_SPP = 2048
#: figures whose light arrives mostly through glass (caustics: paths that find the lights
#: only by sampling a refraction) converge slowly; they may take more samples
MAX_SPP_OF = {"fig_12_12": 4096, "fig_12_13": 4096}
#: fewest batches (the spread of fewer says little about the noise)
MIN_BATCHES = 4
#: the batches' seeds are SEED_BASE, SEED_BASE + 1, ... (the test uses 7 and 101-104)
SEED_BASE = 1000
#: most samples in one batch, across the image (fewer where MIN_BATCHES would pass max_spp)
BATCH_SAMPLES = 1 << 21


def srgb_slope(x: np.ndarray) -> np.ndarray:
    """Derivative of the sRGB encoding (:func:`render.film.linear_to_srgb`) at linear ``x``;
    0 where the encoding clamps (below 0, above 1).

    Examples
    --------
    >>> srgb_slope(np.array([-1.0, 0.001, 0.5, 1.0, 2.0])).round(4).tolist()
    [0.0, 12.92, 0.6586, 0.4396, 0.0]
    """
    x = np.asarray(x, dtype=np.float64)
    inside = (x >= 0.0) & (x <= 1.0)
    power = 1.055 / 2.4 * np.power(np.maximum(x, 0.0031308), 1.0 / 2.4 - 1.0)
    return np.where(inside, np.where(x <= 0.0031308, 12.92, power), 0.0)


def display_noise(mean: np.ndarray, stderr: np.ndarray) -> float:
    """RMS over pixels and channels of the standard error ``stderr`` of a linear image
    ``mean``, as it shows in its 8-bit sRGB preview (levels of 255).

    Examples
    --------
    >>> round(display_noise(np.full((2, 2, 3), 0.5), np.full((2, 2, 3), 0.01)), 3)
    1.68
    >>> display_noise(np.full((1, 1, 3), 2.0), np.ones((1, 1, 3)))   # saturated: no grain
    0.0
    """
    return float(np.sqrt(np.mean((255.0 * srgb_slope(mean) * stderr) ** 2)))


class Batches:
    """Running sums of independent batch images: their mean and its standard error."""

    def __init__(self, shape: tuple[int, ...]):
        self.k = 0
        self._sum = np.zeros(shape)
        self._sq = np.zeros(shape)
        self._alpha = np.zeros(shape[:2])

    def add(self, rgb: np.ndarray, alpha: np.ndarray) -> None:
        self.k += 1
        self._sum += rgb
        self._sq += rgb * rgb
        self._alpha += alpha

    def mean(self) -> np.ndarray:
        return self._sum / max(self.k, 1)

    def alpha(self) -> np.ndarray:
        return self._alpha / max(self.k, 1)

    def stderr(self) -> np.ndarray:
        """Standard error of the mean per pixel, from the batches' sample variance.

        Examples
        --------
        >>> b = Batches((1, 1, 1))
        >>> for x in (1.0, 2.0, 3.0, 4.0):
        ...     b.add(np.full((1, 1, 1), x), np.ones((1, 1)))
        >>> float(b.mean()[0, 0, 0]), round(float(b.stderr()[0, 0, 0]), 6)
        (2.5, 0.645497)
        """
        if self.k < 2:
            return np.full(self._sum.shape, np.inf)
        m = self.mean()
        var = np.maximum(self._sq - self.k * m * m, 0.0) / (self.k - 1)
        return np.sqrt(var / self.k)

    def noise(self) -> float:
        """:func:`display_noise` of the mean."""
        return display_noise(self.mean(), self.stderr())


def make_reference(figure: Figure, target: float = NOISE_TARGET, max_spp: int = MAX_SPP,
                   folder: Path | None = None, progress: bool = True) -> dict:
    """Render ``figure``'s reference in batches until its noise is at most ``target`` (or
    ``max_spp`` samples per pixel), write ``NAME.exr`` and ``NAME.png``, and return the
    facts for the table's ``"reference"`` entry."""
    from render.film import write_exr_channels, write_png_rgb
    from render.integrator import Integrator

    folder = folder or compare.reference_dir()
    w, h = figure.resolution
    # a power of two, so that a power-of-two max_spp is a whole number of batches
    batch_spp = 1 << max(0, min(BATCH_SAMPLES // (w * h), max_spp // MIN_BATCHES).bit_length() - 1)
    t0, c0 = time.perf_counter(), time.process_time()
    scene = compare.figure_scene(figure, figure.resolution)
    integrator = Integrator(scene, scene.build())
    batches = Batches((h, w, 3))
    bar = None
    if progress:
        from tqdm import tqdm

        bar = tqdm(total=max_spp, unit="spp", desc=figure.name, leave=False)
    noise = float("inf")
    while batches.k < MIN_BATCHES or (batches.k + 1) * batch_spp <= max_spp:
        film = integrator.render(spp=batch_spp, seed=SEED_BASE + batches.k, progress=False)
        batches.add(film.rgb(), film.alpha())
        if bar is not None:
            bar.update(batch_spp)
        if batches.k >= MIN_BATCHES:
            noise = batches.noise()
            if bar is not None:
                bar.set_postfix(noise=f"{noise:.2f}")
            if noise <= target:
                break
    if bar is not None:
        bar.close()
    mean, alpha = batches.mean(), batches.alpha()
    half = np.float16
    write_exr_channels(folder / f"{figure.name}.exr",
                       {"R": mean[..., 0].astype(half), "G": mean[..., 1].astype(half),
                        "B": mean[..., 2].astype(half), "A": alpha.astype(half)})
    write_png_rgb(folder / f"{figure.name}.png", mean)
    return {
        "resolution": [w, h],
        "spp": batches.k * batch_spp,
        "batches": batches.k,
        "batch_spp": batch_spp,
        "seeds": [SEED_BASE, SEED_BASE + batches.k - 1],
        "noise": round(noise, 3),
        "noise_target": target,
        "time_s": round(time.perf_counter() - t0, 1),
        "cpu_s": round(time.process_time() - c0, 1),
    }


def calibrate(figure: Figure, folder: Path | None = None) -> dict:
    """Measure the regression rule's errors at :data:`gallery.compare.CALIBRATION_SEEDS`
    against the stored reference; return the table's ``"test"`` entry."""
    from render.integrator import Integrator

    ref = compare.downsample(compare.read_reference(figure.name, folder), figure.factor)
    scene = compare.figure_scene(figure)  # as the test renders it, built once
    integrator = Integrator(scene, scene.build())
    rmse, flip, means = [], [], []
    for seed in compare.CALIBRATION_SEEDS:
        img = integrator.render(spp=compare.TEST_SPP, seed=seed, progress=False).rgb()
        r, f = compare.errors(img, ref)
        rmse.append(round(r, 6))
        flip.append(round(f, 6))
        means.append(img.mean(axis=(0, 1)))
    return {
        "resolution": list(figure.test_resolution),
        "spp": compare.TEST_SPP,
        "seed": compare.TEST_SEED,
        "calibration_seeds": list(compare.CALIBRATION_SEEDS),
        "rmse": rmse,
        "flip": flip,
        "rmse_max": round(compare.MARGIN * max(rmse), 6),
        "flip_max": round(compare.MARGIN * max(flip), 6),
        "mean_std": np.std(np.array(means), axis=0, ddof=1).round(8).tolist(),
    }


def main(argv: list[str] | None = None) -> int:
    import argparse

    parser = argparse.ArgumentParser(
        prog="python -m gallery.references",
        description="Render the gallery's reference images to a stated noise level (slow) "
                    "and calibrate the regression thresholds from test renders at other "
                    "seeds.  Writes gallery/reference/NAME.exr, NAME.png, references.json.")
    parser.add_argument("patterns", nargs="*", metavar="FIGURE",
                        help="chapters (13), figures (13.14), names (fig_13_14) or globs "
                             "(default: every figure)")
    parser.add_argument("--noise", type=float, default=NOISE_TARGET, metavar="LEVELS",
                        help=f"noise target, RMS 8-bit sRGB levels (default {NOISE_TARGET})")
    parser.add_argument("--max-spp", type=int, metavar="N",
                        help=f"most samples per pixel (default {MAX_SPP}; caustic figures "
                             f"{max(MAX_SPP_OF.values())})")
    parser.add_argument("--calibrate-only", action="store_true",
                        help="keep the reference images, only measure the thresholds again")
    args = parser.parse_args(argv)
    folder = compare.reference_dir()
    folder.mkdir(parents=True, exist_ok=True)
    path = folder / compare.TABLE
    for figure in figures(args.patterns):
        table = compare.read_table(folder)
        entry = table.get(figure.name, {})
        if not args.calibrate_only or "reference" not in entry:
            max_spp = args.max_spp or MAX_SPP_OF.get(figure.name, MAX_SPP)
            entry["reference"] = make_reference(figure, args.noise, max_spp, folder,
                                                progress=sys.stderr.isatty())
        entry["test"] = calibrate(figure, folder)
        table[figure.name] = entry
        path.write_text(json.dumps(table, indent=1, sort_keys=True) + "\n", encoding="utf-8")
        r, t = entry["reference"], entry["test"]
        print(f"{figure.name}: {r['resolution'][0]}x{r['resolution'][1]}, {r['spp']} spp, "
              f"noise {r['noise']:.2f} levels, {r['time_s']:.0f} s ({r['cpu_s']:.0f} CPU s); "
              f"test RMSE max {max(t['rmse']):.4f}, FLIP max {max(t['flip']):.4f}", flush=True)
    return 0


if __name__ == "__main__":
    sys.exit(main())
