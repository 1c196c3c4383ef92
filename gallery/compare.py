"""The regression rule: a quick render of a figure against its reference.

One rule, used by ``tests/gallery`` and by ``pwc gallery check``:

* render the figure at its test resolution (:attr:`gallery.figures.Figure.test_resolution`)
  with :data:`TEST_SPP` samples per pixel and seed :data:`TEST_SEED`, its displaced
  objects diced as for the reference (:func:`render_figure`);
* average the reference down to that size (:func:`downsample`: each test pixel is the mean
  of the reference pixels it covers, which a box-filtered render estimates too);
* the render passes when its RMSE (linear) and mean FLIP (LDR, on the sRGB encodings) are
  at most ``rmse_max`` and ``flip_max``, and each channel's image mean lies within
  :data:`MEAN_SIGMAS` seed-to-seed standard deviations of the reference's (plus
  :data:`HALF_TOLERANCE` of it, for the half-float reference).

The thresholds are not guessed: :mod:`gallery.references` renders the test image at
:data:`CALIBRATION_SEEDS` (not the test's seed) when it makes a reference, measures both
errors and the spread of the means, and allows :data:`MARGIN` times the largest error.
A change that only reshuffles the noise stays inside; a change of the image (a wrong
material, light or geometry) does not.
"""

from __future__ import annotations

import json
import time as _time
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from gallery.figures import Figure

__all__ = [
    "TEST_SPP",
    "TEST_SEED",
    "CALIBRATION_SEEDS",
    "MARGIN",
    "MEAN_SIGMAS",
    "HALF_TOLERANCE",
    "Outcome",
    "reference_dir",
    "read_table",
    "read_reference",
    "downsample",
    "srgb",
    "errors",
    "flip_map",
    "figure_scene",
    "render_figure",
    "judge",
    "CheckJob",
    "check_job",
    "render_and_judge",
    "check",
]

TEST_SPP = 16
TEST_SEED = 7
CALIBRATION_SEEDS = (101, 102, 103, 104)
MARGIN = 1.5
MEAN_SIGMAS = 6.0
HALF_TOLERANCE = 0.005
#: the table of reference facts and test thresholds, in the reference folder
TABLE = "references.json"


def reference_dir() -> Path:
    """The reference images and their table (package data when installed)."""
    from render.library.resources import bundled_references

    return bundled_references()


def read_table(folder: Path | None = None) -> dict:
    """``references.json``: per figure, how its reference was made and its thresholds."""
    path = (folder or reference_dir()) / TABLE
    return json.loads(path.read_text(encoding="utf-8")) if path.is_file() else {}


def read_reference(name: str, folder: Path | None = None) -> np.ndarray:
    """(h, w, 3) float64 linear reference image of a figure, at its full size."""
    from render.film import read_exr

    return read_exr((folder or reference_dir()) / f"{name}.exr")["RGBA"][..., :3]


def downsample(img: np.ndarray, factor: int) -> np.ndarray:
    """Mean of each ``factor`` x ``factor`` block of an (h, w, c) image.

    Examples
    --------
    >>> downsample(np.arange(16.0).reshape(4, 4, 1), 2)[..., 0].tolist()
    [[2.5, 4.5], [10.5, 12.5]]
    >>> downsample(np.ones((3, 2, 1)), 1).shape
    (3, 2, 1)
    """
    h, w, c = img.shape
    if h % factor or w % factor:
        raise ValueError(f"an image of {w} x {h} is not a whole number of {factor}-pixel blocks")
    return img.reshape(h // factor, factor, w // factor, factor, c).mean(axis=(1, 3))


def srgb(img: np.ndarray) -> np.ndarray:
    """sRGB-encoded float32 image in [0, 1] (what LDR-FLIP compares)."""
    from render.film import linear_to_srgb

    return linear_to_srgb(img).astype(np.float32)


def flip_map(test: np.ndarray, ref: np.ndarray) -> tuple[np.ndarray, float]:
    """(h, w) LDR-FLIP error of ``test`` against ``ref`` (both linear) and its mean."""
    import flip_evaluator

    err, mean, _ = flip_evaluator.evaluate(srgb(ref), srgb(test), "LDR", applyMagma=False)
    return np.asarray(err, dtype=np.float64).reshape(test.shape[:2]), float(mean)


def errors(test: np.ndarray, ref: np.ndarray) -> tuple[float, float]:
    """(RMSE of the linear images, mean LDR-FLIP of their sRGB encodings)."""
    rmse = float(np.sqrt(np.mean((test - ref) ** 2)))
    return rmse, flip_map(test, ref)[1]


def figure_scene(figure: Figure, resolution=None, spp: int | None = None,
                 seed: int | None = None, time: float | None = None):
    """A figure's :class:`~render.scene.Scene` at ``resolution`` (default: its test size),
    ``spp`` samples per pixel or ``time`` seconds (default: the scene's).

    The test image is diced as the reference is: displaced objects are tessellated for
    the reference's pixels (the scene's dicing rate and tolerance divided by
    :attr:`~gallery.figures.Figure.factor`), so the two images show the same triangles
    and differ by noise alone.  Other sizes are diced for their own pixels.
    """
    from render.scene import load_scene

    w, h = resolution or figure.test_resolution
    scene = load_scene(figure.scene, overrides={"width": w, "height": h, "spp": spp,
                                                "time": time, "seed": seed})
    if (w, h) == figure.test_resolution and figure.factor > 1:
        scene.settings.dicing_rate /= figure.factor
        scene.settings.dicing_tolerance /= figure.factor
    return scene


def render_figure(figure: Figure, spp: int | None, seed: int, resolution=None,
                  progress: bool = False, denoise: bool = False, time: float | None = None):
    """Render :func:`figure_scene` to a Film."""
    from render.integrator import render

    scene = figure_scene(figure, resolution, spp, seed, time)
    return render(scene, progress=progress, denoise=denoise)


@dataclass
class Outcome:
    """A figure's test render judged against its reference (:func:`judge`)."""

    name: str
    rmse: float
    flip: float
    rmse_max: float
    flip_max: float
    mean_diff: np.ndarray
    mean_tol: np.ndarray
    error_map: np.ndarray = field(repr=False)
    image: np.ndarray = field(repr=False)
    reference: np.ndarray = field(repr=False)
    spp: int = 0
    time_s: float = 0.0

    @property
    def passed(self) -> bool:
        return (self.rmse <= self.rmse_max and self.flip <= self.flip_max
                and bool(np.all(self.mean_diff <= self.mean_tol)))

    def reasons(self) -> list[str]:
        """What failed, in words (empty when the render passed)."""
        out = []
        if not self.rmse <= self.rmse_max:
            out.append(f"RMSE {self.rmse:.4f} > {self.rmse_max:.4f}")
        if not self.flip <= self.flip_max:
            out.append(f"FLIP {self.flip:.4f} > {self.flip_max:.4f}")
        bad = ~(self.mean_diff <= self.mean_tol)
        if np.any(bad):
            out.append("mean of " + ", ".join(
                f"{'RGB'[c]} off by {self.mean_diff[c]:.4f} > {self.mean_tol[c]:.4f}"
                for c in np.flatnonzero(bad)))
        return out


def judge(name: str, img: np.ndarray, ref: np.ndarray, entry: dict) -> Outcome:
    """Judge a test render ``img`` against the reference ``ref`` averaged to its size, by
    the thresholds ``entry["test"]`` of the references table."""
    t = entry["test"]
    # aligned: numpy sums misaligned data (as an array can arrive from a cluster's
    # worker) in another order, and the means would differ in their last bits
    img, ref = (np.require(a, np.float64, ["C", "A"]) for a in (img, ref))
    if img.shape != ref.shape:
        raise ValueError(f"{name}: the render is {img.shape[1]} x {img.shape[0]}, the "
                         f"reference {ref.shape[1]} x {ref.shape[0]}")
    err, flip = flip_map(img, ref)
    rmse = float(np.sqrt(np.mean((img - ref) ** 2)))
    ref_mean = ref.mean(axis=(0, 1))
    return Outcome(
        name=name, rmse=rmse, flip=flip, rmse_max=t["rmse_max"], flip_max=t["flip_max"],
        mean_diff=np.abs(img.mean(axis=(0, 1)) - ref_mean),
        mean_tol=MEAN_SIGMAS * np.asarray(t["mean_std"]) + HALF_TOLERANCE * ref_mean,
        error_map=err, image=img, reference=ref)


@dataclass(frozen=True)
class CheckJob:
    """What checking a figure needs, read where the files are (:func:`check_job`): its
    scene as the rule renders it, its reference averaged to the test size, and its
    entry of the references table.  Whole on its own, so a cluster's worker can check
    the figure in one task (``pwc gallery check --workers``) without the files."""

    name: str
    scene: object = field(repr=False)  # render.scene.Scene
    reference: np.ndarray = field(repr=False)
    entry: dict = field(repr=False)
    load_s: float = 0.0  # seconds reading the scene


def check_job(figure: Figure, table: dict | None = None,
              folder: Path | None = None) -> CheckJob:
    """Read what checking ``figure`` needs.

    Raises
    ------
    KeyError
        The figure has no reference (run ``python -m gallery.references NAME``).
    """
    table = read_table(folder) if table is None else table
    if figure.name not in table:
        raise KeyError(f"{figure.name} has no reference: run python -m gallery.references "
                       f"{figure.name}")
    entry = table[figure.name]
    ref = downsample(read_reference(figure.name, folder), figure.factor)
    t0 = _time.perf_counter()
    scene = figure_scene(figure, spp=entry["test"]["spp"], seed=TEST_SEED)
    return CheckJob(figure.name, scene, ref, entry, _time.perf_counter() - t0)


def render_and_judge(job: CheckJob, progress: bool = False, threads: int = 2) -> Outcome:
    """Render a :class:`CheckJob`'s scene and judge it; ``time_s`` counts reading the
    scene, rendering and judging.  Pure: writes nothing."""
    from render.integrator import render

    t0 = _time.perf_counter()
    film = render(job.scene, progress=progress, threads=threads)
    outcome = judge(job.name, film.rgb(), job.reference, job.entry)
    outcome.spp = int(film.stats["spp"])
    outcome.time_s = job.load_s + _time.perf_counter() - t0
    return outcome


def check(figure: Figure, table: dict | None = None, folder: Path | None = None,
          progress: bool = False) -> Outcome:
    """Render ``figure`` by the rule and judge it against its reference.

    Raises
    ------
    KeyError
        The figure has no reference (run ``python -m gallery.references NAME``).
    """
    return render_and_judge(check_job(figure, table, folder), progress)
