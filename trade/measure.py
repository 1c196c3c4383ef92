"""One measured render: wall time, peak memory, triangles, rays and the image.

The timed span is what ``pwc render`` does with the scene file: read it (materials,
profiles, textures, baked normal maps), dice and build the Embree scene, trace, and
denoise where the scene asks.  Peak memory is the process's peak resident set above
what it held when the run started: Linux lets a process reset its peak
(``/proc/self/clear_refs``, then ``VmHWM``), which counts Embree's and numba's memory
too; elsewhere :mod:`tracemalloc` counts numpy's allocations only.
"""

from __future__ import annotations

import time
import tracemalloc
from pathlib import Path

import numpy as np

__all__ = ["PeakMemory", "measure"]


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


def measure(text: str, path: str | Path, threads: int = 2,
            seed: int | None = None) -> tuple[dict, np.ndarray]:
    """Render the scene file ``text`` (read as if it were at ``path``) once, with its own
    seed or ``seed``.

    Returns
    -------
    record : dict
        ``wall_s`` (read + build + render + denoise) and ``cpu_s`` (the CPU time of all
        the process's threads over it), ``render_s``, ``build_s``,
        ``peak_mb``, ``memory_method``, ``triangles``, ``rays``, ``spp``,
        ``numpy_shaded`` (objects whose varying arguments numpy shades per hit),
        ``objects`` (per object: triangles, diced, dicer error).
    image : (h, w, 3) float64
        Linear RGB.
    """
    from render.integrator import render
    from render.scene import parse_scene

    path = Path(path)
    with PeakMemory() as memory:
        t0, c0 = time.perf_counter(), time.process_time()
        scene = parse_scene(text, str(path), overrides={"seed": seed},
                            base_dir=path.parent)  # an override of None keeps the scene's
        film = render(scene, progress=False, threads=threads, denoise=scene.settings.denoise)
        image = film.rgb()
        wall, cpu = time.perf_counter() - t0, time.process_time() - c0
    st = film.stats
    record = {
        "wall_s": wall,
        "cpu_s": cpu,
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
    return record, image
