"""Measure a scene's speed/accuracy trade: a reference, a sweep of the knobs, a search
for the cheapest combination that meets the target, the Pareto front.

1. **Reference**: the scene converged (:func:`trade.knobs.reference_patch`), rendered
   once and kept in the report folder (``reference.exr`` and ``reference.json``, keyed
   to the scene text, its settings and the render code), so a rerun reuses it.
2. **Baseline**: the scene as written (at the report's resolution).
3. **Sweep**: every option of every knob, one knob at a time from the baseline.
4. **Combination**: the cheapest option of each knob that meets the target on its own;
   starting from the one that saves most, each next one joins the combination if the
   whole still meets the target (at most :data:`COMBINE_ROUNDS` renders).
5. **Recommendation**: the fastest measured run that meets the target (never an
   unmeasured guess), written out as a scene file.

With a Dask ``client`` the runs are tasks on its cluster (one run each,
:func:`render.distributed.map_on_cluster`): the sweep's runs all at once, then the
combination's one by one; the reference's chunks spread over the cluster
(:func:`render.distributed.render_on_cluster`).  The images, errors and choices are
the in-process ones; the times are measured on the workers (:mod:`trade.measure`).

Every run renders with the scene's own seed, and the reference with another
(:data:`REFERENCE_SEED_OFFSET` added), so runs that differ in one knob share their random
numbers: their differences are the knob's, not the noise's; and the recommended scene
file renders exactly the image that was measured.  Same scene, same options, same
numbers (times aside).
"""

from __future__ import annotations

import hashlib
import json
import time
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from trade.knobs import describe, knobs_for, merge, patch_key, reference_patch
from trade.measure import measure, measure_shipped, ship
from trade.metrics import METRICS, geometric_error, image_errors

__all__ = ["Run", "Trade", "COSTS", "REFERENCE_SEED_OFFSET", "pareto_front", "run_trade"]

#: what a run's cost is measured in: wall time, or the CPU time of the process (which
#: other programs' load on a shared machine changes much less)
COSTS = {"wall": "wall_s", "cpu": "cpu_s"}
#: the reference's seed is the scene's plus this (its noise shared with no run)
REFERENCE_SEED_OFFSET = 1_000_003
COMBINE_ROUNDS = 6
#: an option joins the combination only if it alone saves this share of the time
#: (smaller savings are within the timing noise of a shared machine)
MIN_GAIN = 0.05


@dataclass
class Run:
    """One measured render."""

    index: int
    label: str
    family: str
    patch: dict
    record: dict = field(default_factory=dict)
    errors: dict = field(default_factory=dict)
    geometric_px: float | None = None
    meets: bool = False
    pareto: bool = False
    image: str = ""  # its sRGB preview, relative to the report folder

    def error(self, metric: str) -> float:
        return self.errors[metric]

    def cost(self, cost: str) -> float:
        """Seconds of ``"wall"`` time or of ``"cpu"`` time."""
        return self.record[COSTS[cost]]


@dataclass
class Trade:
    """The result of :func:`run_trade` (what the report shows)."""

    scene_path: Path
    text: str
    names: list[str]
    resolution: tuple[int, int]
    metric: str
    target: float
    cost: str
    reference: dict
    runs: list[Run]
    skipped: list[str]
    recommended: Run | None
    recommended_text: str
    modelled: list[dict]
    lights: list[str]
    loads: dict
    budget: float | None
    size: str
    elapsed_s: float


def pareto_front(points: list[tuple[float, float]]) -> list[bool]:
    """Which (cost, error) points no other point beats in both (ties kept).

    Examples
    --------
    >>> pareto_front([(1, 5), (2, 3), (3, 4), (4, 1), (2, 3)])
    [True, True, False, True, True]
    """
    out = []
    for i, (c, e) in enumerate(points):
        dominated = any((c2 <= c and e2 <= e) and (c2 < c or e2 < e)
                        for j, (c2, e2) in enumerate(points) if j != i)
        out.append(not dominated)
    return out


def _code_key() -> str:
    from render.jit import SOURCE_KEY

    return SOURCE_KEY


def _resolution_patch(resolution) -> dict:
    return {"render": {"resolution": [int(resolution[0]), int(resolution[1])]}}


def _save_png(path: Path, image: np.ndarray) -> None:
    from PIL import Image

    from render.film import linear_to_srgb

    srgb = np.round(linear_to_srgb(image) * 255.0).astype(np.uint8)
    path.parent.mkdir(parents=True, exist_ok=True)
    Image.fromarray(srgb, "RGB").save(path)


def reference_image(text: str, path: Path, out: Path, spp: int, given: Path | None,
                    fresh: bool, resolution, threads: int, log, client=None,
                    progress: bool = False) -> tuple[np.ndarray, dict]:
    """The converged reference: ``given``, or the one kept in ``out`` for the same scene
    and settings, or a new render (kept for the next run; with a Dask ``client``, its
    chunks on the cluster: the same image)."""
    from displacement.textures import read_texture, write_texture
    from render.scene import parse_scene, patch_scene_text

    scene = parse_scene(text, str(path), base_dir=path.parent)
    patch = merge(_resolution_patch(resolution), reference_patch(scene, spp))
    ref_text = patch_scene_text(text, patch["render"], patch["objects"])
    seed = scene.settings.seed + REFERENCE_SEED_OFFSET
    key = hashlib.sha256("\0".join([ref_text, str(seed), _code_key()]).encode())
    key = key.hexdigest()[:20]
    exr, meta = out / "reference.exr", out / "reference.json"
    if given is not None:
        image = read_texture(given).data[..., :3]
        if image.shape[:2] != (resolution[1], resolution[0]):
            raise ValueError(f"{given}: the reference is {image.shape[1]} x {image.shape[0]} "
                             f"pixels, the runs {resolution[0]} x {resolution[1]}: render "
                             "them at its size (--resolution)")
        return image, {"source": str(given), "spp": None, "wall_s": None, "reused": True,
                       "patch": patch}
    if not fresh and exr.is_file() and meta.is_file():
        info = json.loads(meta.read_text())
        if info.get("key") == key:
            log(f"reusing the reference {exr} ({info['spp']} spp, rendered in "
                f"{info['wall_s']:.1f} s)")
            return read_texture(exr).data[..., :3], {**info, "reused": True, "patch": patch}
    log(f"rendering the reference: {spp} spp at {resolution[0]} x {resolution[1]}")
    if client is None:
        record, image = measure(ref_text, path, threads, seed)
    else:
        from render.distributed import render_on_cluster

        t0 = time.perf_counter()
        film = render_on_cluster(parse_scene(ref_text, str(path), overrides={"seed": seed},
                                             base_dir=path.parent), client, progress=progress)
        image = film.rgb()
        record = {"wall_s": time.perf_counter() - t0, "triangles": film.stats["triangles"]}
    image = image.astype(np.float32).astype(np.float64)  # as kept, so reruns compare alike
    write_texture(exr, image, bits="float")
    _save_png(out / "images" / "reference.png", image)
    info = {"key": key, "spp": int(spp), "wall_s": record["wall_s"],
            "triangles": record["triangles"], "settings": describe(patch, [
                o.name for o in scene.objects]), "source": "rendered"}
    meta.write_text(json.dumps(info, indent=1))
    return image, {**info, "reused": False, "patch": patch}


def as_written(text: str, path: Path, resolution):
    """The scene as written, at ``resolution``, built: ``(scene, loads, summary, lights)``
    (what its materials loaded, :func:`render.scene.modelling_summary`, its lights)."""
    from render.library.resources import track_loads
    from render.scene import modelling_summary, parse_scene, patch_scene_text

    with track_loads() as loads:
        scene = parse_scene(patch_scene_text(text, _resolution_patch(resolution)["render"]),
                            str(path), base_dir=path.parent)
    summary = modelling_summary(scene, scene.build().stats)
    lights = [type(light).__name__ for light in scene.lights]
    lights += [f"area light {m['name']}" for m in summary if m["emits"]]
    return scene, {k: sorted(v) for k, v in loads.items()}, summary, lights


def run_trade(scene_path: Path, out: Path, *, metric: str = "flip", target: float = 0.05,
              cost: str = "wall",
              knobs: set[str] | None = None, budget: float | None = None,
              size: str = "full", resolution=None, reference_spp: int | None = None,
              reference: Path | None = None, fresh_reference: bool = False,
              threads: int = 2, repeats: int = 1, progress: bool = False,
              log=print, client=None) -> Trade:
    """Measure the trade of the scene file ``scene_path``; images go to ``out/images``.

    Parameters
    ----------
    metric : one of :data:`trade.metrics.METRICS`
        The error the target is stated in.
    target : float
        The largest acceptable error of a recommendation.
    cost : {"wall", "cpu"}
        What "cheapest" means: wall-clock seconds, or the process's CPU seconds (steadier
        where other programs share the machine).
    knobs : set of str, optional
        Families to sweep (``samples``, ``dicing``, ``displacement``, ``curves``,
        ``textures``, ``paths``); default all that apply.
    budget : float, optional
        Seconds for the whole sweep (reference excluded): runs past it are skipped.
    size : {"full", "ci"}
        The full sweep, or the CI-sized one (fewer options; the caller keeps images
        small).
    resolution : (w, h), optional
        Default: the scene's.
    reference_spp : int, optional
        Default: 16 x the scene's samples per pixel, at least 256 (64 for ``"ci"``).
    reference : Path, optional
        A converged reference EXR to use instead of rendering one.
    repeats : int
        Time each run this many times and keep the fastest.
    threads : int
        Threads of each render.
    client : distributed.Client, optional
        Measure the runs as tasks on its Dask cluster (one run each; the tasks write
        nothing), and render the reference's chunks there.
    """
    from render.scene import parse_scene, patch_scene_text

    if metric not in METRICS:
        raise ValueError(f"metric must be one of {', '.join(METRICS)}, got {metric!r}")
    if cost not in COSTS:
        raise ValueError(f"cost must be one of {', '.join(COSTS)}, got {cost!r}")
    started = time.perf_counter()
    scene_path = Path(scene_path)
    text = scene_path.read_text(encoding="utf-8")
    written = parse_scene(text, str(scene_path), base_dir=scene_path.parent).settings
    res = tuple(resolution) if resolution else (written.width, written.height)
    scene, loads, modelled, lights = as_written(text, scene_path, res)
    names = [o.name for o in scene.objects]
    ref_spp = reference_spp or (64 if size == "ci" else max(256, 16 * scene.settings.spp))
    ref_image, ref_info = reference_image(text, scene_path, out, ref_spp, reference,
                                          fresh_reference, res, threads, log, client,
                                          progress)
    try:
        import pyoidn  # noqa: F401
        denoiser = True
    except ImportError:
        denoiser = False
    all_knobs = knobs_for(scene, loads, size, denoiser)
    exact = parse_scene(patch_scene_text(text, {**_resolution_patch(res)["render"],
                                                "curves": "exact"}),
                        str(scene_path), base_dir=scene_path.parent)
    if client is None:
        _warm_up(text, scene_path, denoiser, threads)  # on a cluster: each worker, once
    else:
        _note_shared_workers(client, log)
    chosen = [k for k in all_knobs if knobs is None or k.family in knobs]
    base = _resolution_patch(res)
    runs: list[Run] = []
    seen: dict[str, Run] = {}
    geometric: dict[str, float | None] = {}
    skipped: list[str] = []
    sweep_start = time.perf_counter()
    planned = 1 + sum(len(k.options) for k in chosen) + COMBINE_ROUNDS
    bar = None
    if progress:
        from tqdm import tqdm

        bar = tqdm(total=planned, unit="run", desc="trade", leave=False)

    warm_key = hashlib.sha256(f"{text}\0{res}".encode()).hexdigest()

    def measured(texts: list[str], over):
        """``(i, (record, image))`` of the run texts, in order: in-process one after
        another until ``over()``; on the cluster all at once, the unfinished ones
        cancelled once ``over()``."""
        if client is None:
            for i, run_text in enumerate(texts):
                if over():
                    return
                yield i, measure(run_text, scene_path, threads, repeats=repeats)
            return
        from render.distributed import map_on_cluster

        jobs = (ship(t, scene_path, threads, repeats, warm_key) for t in texts)
        yield from map_on_cluster(client, measure_shipped, jobs, unit="run", stop=over,
                                  progress=bar if bar is not None else False)

    def batch(specs: list[tuple[str, str, dict]]) -> list[Run | None]:
        """Measure the runs ``(label, family, patch)``; their Runs in order (a run of
        settings measured before is that Run; None: skipped by the budget)."""
        todo = []  # (spec index, full patch, key, scene text)
        first: set[str] = set()  # the keys in todo
        same: dict[int, str] = {}  # spec index -> the key of an earlier spec in the batch
        for i, (_, _, patch) in enumerate(specs):
            full = merge(base, patch)
            key = patch_key(full)
            if key in seen or key in first:
                same[i] = key
            else:
                first.add(key)
                todo.append((i, full, key, patch_scene_text(text, full["render"],
                                                            full["objects"])))

        def over() -> bool:
            return budget is not None and bool(runs) and (
                time.perf_counter() - sweep_start > budget)

        got: list[Run | None] = [None] * len(specs)
        for j, (record, image) in measured([t for *_, t in todo], over):
            i, full, key, run_text = todo[j]
            label, family, patch = specs[i]
            r = Run(len(runs), label, family, merge(patch), record,
                    image_errors(image, ref_image))
            gkey = patch_key(_geometry_patch(full))
            if gkey not in geometric:  # measured only where the geometry changes
                geometric[gkey] = _geometric(run_text, scene_path, exact)
            r.geometric_px = geometric[gkey]
            r.meets = r.error(metric) <= target
            r.image = f"images/run_{r.index:03d}.png"
            _save_png(out / r.image, image)  # files are written here, never by a task
            runs.append(r)
            seen[key] = r
            got[i] = r
            if bar is not None and client is None:  # on a cluster: as its tasks finish
                bar.update(1)
        for i, key in same.items():
            got[i] = seen.get(key)
        skipped.extend(specs[i][0] for i, r in enumerate(got) if r is None)
        return got

    sweep = [(option.label, knob.family, option.patch, knob.name)
             for knob in chosen for option in knob.options]
    baseline, *swept = batch([("the scene as written", "baseline",
                               {"render": {}, "objects": {}})] + [s[:3] for s in sweep])
    for r, (*_, knob_name) in zip(swept, sweep, strict=True):
        if r is not None:
            r.record["knob"] = knob_name
    # the combination: per knob, its cheapest option that meets the target on its own;
    # from the one that saves most, each next one joins if the whole still meets it
    picks = []
    for knob in chosen:
        ok = [r for r in runs if r.record.get("knob") == knob.name and r.meets
              and r.cost(cost) < (1.0 - MIN_GAIN) * baseline.cost(cost)]
        if ok:
            picks.append(min(ok, key=lambda r: r.cost(cost)))
    picks.sort(key=lambda r: r.cost(cost))
    together = picks[:1]
    for p in picks[1:1 + COMBINE_ROUNDS]:
        combo, = batch([("combined: " + " + ".join(q.label for q in together + [p]),
                         "combined", merge(*(q.patch for q in together + [p])))])
        if combo is not None and combo.meets:
            together.append(p)
    if bar is not None:
        bar.close()
    front = pareto_front([(r.cost(cost), r.error(metric)) for r in runs])
    for r, on_front in zip(runs, front, strict=True):
        r.pareto = on_front
    meeting = [r for r in runs if r.meets]
    recommended = (min(meeting, key=lambda r: (r.cost(cost), r.error(metric)))
                   if meeting else None)
    # the recommendation keeps the scene's own resolution unless the user chose another
    rec_patch = merge(base if resolution else {}, recommended.patch if recommended else {})
    recommended_text = patch_scene_text(text, rec_patch["render"], rec_patch["objects"])
    return Trade(scene_path, text, names, res, metric, target, cost, ref_info, runs, skipped,
                 recommended, recommended_text, modelled, lights, loads, budget, size,
                 time.perf_counter() - started)


#: the settings that change the traced triangles
GEOMETRY_KEYS = {"resolution", "dicing_rate", "dicing_tolerance", "curves", "curve_tolerance",
                 "displacement_method"}


def _geometry_patch(patch: dict) -> dict:
    """The part of a patch that changes the traced triangles."""
    return {"render": {k: v for k, v in patch["render"].items() if k in GEOMETRY_KEYS},
            "objects": {i: {k: v for k, v in keys.items() if k in GEOMETRY_KEYS}
                        for i, keys in patch["objects"].items()}}


def _geometric(text: str, path: Path, exact) -> float | None:
    """:func:`trade.metrics.geometric_error` of the triangles of the scene file ``text``
    (rebuilt, untimed) against the true surfaces of ``exact`` (the scene as written,
    curves exact)."""
    from render.scene import parse_scene

    if not any((o.original_displacement or o.displacement) is not None for o in exact.objects):
        return None
    scene = parse_scene(text, str(path), base_dir=path.parent)
    return geometric_error(exact, scene.build())


def _note_shared_workers(client, log) -> None:
    """Say so when a worker runs several tasks at once: their runs then share its
    process, and each run's CPU time and peak memory include its neighbours'."""
    shared = {a: n for a, n in client.nthreads().items() if n > 1}
    if shared:
        address, n = next(iter(shared.items()))
        log(f"worker {address} runs {n} tasks at once: the CPU time and peak memory of a "
            "run there include the other runs'; start workers with `dask worker --nthreads "
            "1` (docs/trade.md)")


def _warm_up(text: str, path: Path, denoiser: bool, threads: int) -> None:
    """Render once, tiny and untimed: kernels loaded, Embree and Open Image Denoise
    started, so no run pays for what only the first pays."""
    from render.scene import patch_scene_text

    tiny = patch_scene_text(text, {"resolution": [8, 8], "spp": 1, "denoise": denoiser})
    measure(tiny, path, threads)
