"""One measured render: wall time, peak memory, triangles, rays and the image.

The timed span is what ``pwc render`` does with the scene file: read it (materials,
profiles, textures, baked normal maps), dice and build the Embree scene, trace, and
denoise where the scene asks.  Peak memory is the process's peak resident set above
what it held when the run started: Linux lets a process reset its peak
(``/proc/self/clear_refs``, then ``VmHWM``), which counts Embree's and numba's memory
too; elsewhere :mod:`tracemalloc` counts numpy's allocations only.

On a Dask cluster (``pwc trade --workers``) a run is one task: the client reads the
scene file (timed, :func:`ship`), and the worker renders the scene it is sent
(:func:`measure_shipped`), timed there around the render alone, not the task's
scheduling, transfer or unpickling; the run's times are the sum of the two spans.
"""

from __future__ import annotations

import hashlib
import time
import tracemalloc
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

__all__ = ["PeakMemory", "measure", "ShippedRun", "ship", "measure_shipped"]


def _status_kb(field: str) -> int | None:
    try:
        with open("/proc/self/status") as f:
            for line in f:
                if line.startswith(field + ":"):
                    return int(line.split()[1])
    except (OSError, ValueError, IndexError):
        return None
    return None


def _trim_heap() -> None:
    """Give the memory freed by earlier work back to the system (glibc's ``malloc_trim``),
    so that what a run allocates shows in its resident set; a no-op elsewhere."""
    try:
        import ctypes

        ctypes.CDLL("libc.so.6").malloc_trim(0)
    except (OSError, AttributeError):
        pass


class PeakMemory:
    """``with PeakMemory() as m: ...`` then ``m.peak_bytes``: the block's peak memory above
    what the process held when it started, and ``m.method`` (``"rss"`` or
    ``"tracemalloc"``)."""

    def __enter__(self) -> PeakMemory:
        _trim_heap()
        self.start = _status_kb("VmRSS")
        try:
            with open("/proc/self/clear_refs", "w") as f:
                f.write("5")  # reset the peak resident set to the current one
            self.method = "rss" if self.start is not None else "tracemalloc"
        except OSError:
            self.method = "tracemalloc"
        if self.method == "tracemalloc":
            self._tracing = tracemalloc.is_tracing()
            if not self._tracing:
                tracemalloc.start()
            tracemalloc.reset_peak()
            self._base = tracemalloc.get_traced_memory()[0]
        return self

    def __exit__(self, *exc) -> None:
        if self.method == "rss":
            peak = _status_kb("VmHWM")
            self.peak_bytes = max(0, (peak or 0) - self.start) * 1024
        else:
            self.peak_bytes = max(0, tracemalloc.get_traced_memory()[1] - self._base)
            if not self._tracing:
                tracemalloc.stop()


def measure(text: str, path: str | Path, threads: int = 2, seed: int | None = None,
            repeats: int = 1) -> tuple[dict, np.ndarray]:
    """Render the scene file ``text`` (read as if it were at ``path``) with its own seed
    or ``seed``, ``repeats`` times; the fastest times are kept.

    Returns
    -------
    record : dict
        ``wall_s`` (read + build + render + denoise) and ``cpu_s`` (the CPU time of all
        the process's threads over it), ``read_s`` (reading the scene file),
        ``render_s``, ``build_s``, ``peak_mb``, ``memory_method``, ``triangles``,
        ``rays``, ``spp``, ``numpy_shaded`` (objects whose varying arguments numpy
        shades per hit), ``objects`` (per object: triangles, diced, dicer error).
    image : (h, w, 3) float64
        Linear RGB.
    """
    from render.scene import parse_scene

    path = Path(path)
    best = None
    for _ in range(repeats):
        with PeakMemory() as memory:
            t0, c0 = time.perf_counter(), time.process_time()
            scene = parse_scene(text, str(path), overrides={"seed": seed},
                                base_dir=path.parent)  # an override of None keeps the scene's
            read_s = time.perf_counter() - t0
            film, image = _render(scene, threads)
            wall, cpu = time.perf_counter() - t0, time.process_time() - c0
        best = _fastest(best, _record(film, wall, cpu, read_s, memory))
    return best, image


@dataclass(frozen=True)
class ShippedRun:
    """A run for a cluster's worker (:func:`ship`): the scene read on the client and
    pickled with what its files gave it, so the worker needs none of them."""

    payload: bytes = field(repr=False)
    read_s: float  # reading the scene file on the client, wall
    read_cpu_s: float  # and the client thread's CPU time
    threads: int = 1
    repeats: int = 1
    #: runs of one trade share it: each worker warms up once for them
    warm_up: str = ""


def ship(text: str, path: str | Path, threads: int = 1, repeats: int = 1,
         warm_up: str = "", seed: int | None = None) -> ShippedRun:
    """Read the scene file ``text`` as :func:`measure` does, timed (the client's thread
    alone: on a local cluster the scheduler shares this process), and pickle it."""
    import cloudpickle

    from render.scene import parse_scene

    path = Path(path)
    t0, c0 = time.perf_counter(), time.thread_time()
    scene = parse_scene(text, str(path), overrides={"seed": seed}, base_dir=path.parent)
    read_s, read_cpu = time.perf_counter() - t0, time.thread_time() - c0
    return ShippedRun(cloudpickle.dumps(scene), read_s, read_cpu, threads, repeats,
                      warm_up or hashlib.sha256(text.encode()).hexdigest())


#: the trades this worker process has warmed up for
_WARM: set = set()


def measure_shipped(run: ShippedRun) -> tuple[dict, np.ndarray]:
    """:func:`measure` of a :class:`ShippedRun`, on the worker that runs its task: the
    span timed is unpickling the scene (so its memory counts, as reading does in
    :func:`measure`; not in the times), building, tracing and denoising; the client's
    reading time is added.  Pure: writes nothing, so the scheduler may run it again."""
    import pickle

    if run.warm_up not in _WARM:
        _warm_up(pickle.loads(run.payload))
        _WARM.add(run.warm_up)
    best = None
    for _ in range(run.repeats):
        with PeakMemory() as memory:
            scene = pickle.loads(run.payload)
            t0, c0 = time.perf_counter(), time.process_time()
            film, image = _render(scene, run.threads)
            wall, cpu = time.perf_counter() - t0, time.process_time() - c0
        record = _record(film, run.read_s + wall, run.read_cpu_s + cpu, run.read_s, memory)
        best = _fastest(best, record)
    return best, image


def _warm_up(scene) -> None:
    """Render ``scene`` once, 8 x 8 at 1 spp, untimed: this process's kernels loaded,
    Embree and Open Image Denoise started (where it is installed)."""
    import dataclasses

    from render.integrator import render

    try:
        import pyoidn  # noqa: F401
        denoise = True
    except ImportError:
        denoise = False
    scene.settings.width = scene.settings.height = 8
    scene.camera = dataclasses.replace(scene.camera, width=8, height=8)
    render(scene, spp=1, progress=False, threads=1, denoise=denoise)


def _render(scene, threads: int):
    from render.integrator import render

    film = render(scene, progress=False, threads=threads, denoise=scene.settings.denoise)
    return film, film.rgb()


def _fastest(best: dict | None, record: dict) -> dict:
    """The first record, with the fastest times of all (a shared machine's noise)."""
    if best is None:
        return record
    for key in ("wall_s", "cpu_s", "render_s", "read_s"):
        best[key] = min(best[key], record[key])
    return best


def _record(film, wall: float, cpu: float, read_s: float, memory: PeakMemory) -> dict:
    st = film.stats
    return {
        "wall_s": wall,
        "cpu_s": cpu,
        "read_s": read_s,
        "render_s": st["time_s"],
        "build_s": st["build_s"],
        "peak_mb": memory.peak_bytes / 2**20,
        "memory_method": memory.method,
        "triangles": int(st["triangles"]),
        "rays": int(st["rays"]),
        "spp": int(st["spp"]),
        "numpy_shaded": list(st.get("bound_objects") or []),
        "objects": [{k: v for k, v in g.items() if k in ("name", "triangles", "diced",
                                                           "max_error_px")}
                    for g in st["geometry"]],
    }
