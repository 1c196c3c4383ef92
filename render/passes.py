"""How an image's samples are cut into passes and chunks, so that the image does not
depend on who renders which chunk.

A render is a sequence of *passes*; pass ``k`` draws ``pass_spp(k)`` samples for every
pixel.  Its ``npix * pass_spp(k)`` samples are numbered pixel-major (sample ``s`` is in
pixel ``s // pass_spp(k)``, the pixel's sample ``k * per_pass + s % pass_spp(k)``) and
cut into chunks of :data:`CHUNK` samples.  A sample's values depend only on its pixel,
its index and the seed (:mod:`render.sampler`); a chunk's result is a
:class:`~render.film.FilmPatch`.  Merging the patches in (pass, chunk) order gives the
same bits whichever thread, process or machine traced them: the in-process loop
(:meth:`render.integrator.Integrator.render`) and the Dask driver
(:mod:`render.distributed`) both call :func:`render_chunk`.

A pass holds at least :data:`PASS_SAMPLES` samples (small images draw several samples
per pixel in one pass); a time budget is spent in whole passes (at least one).
"""

from __future__ import annotations

import functools
from dataclasses import dataclass

import numpy as np

from render.film import FilmPatch

__all__ = ["CHUNK", "PASS_SAMPLES", "PassPlan", "render_chunk"]

#: samples per work item
CHUNK = 1 << 16
#: fewest samples in one pass (the unit of the time budget and of the progress bar)
PASS_SAMPLES = 1 << 19


@dataclass(frozen=True)
class PassPlan:
    """The passes and chunks of one image.

    Attributes
    ----------
    npix : int
        Pixels of the image.
    per_pass : int
        Samples per pixel of a full pass.
    passes : int or None
        Number of passes; None with a time budget (passes until it is spent).
    spp : int
        Samples per pixel asked for (without a time budget).
    time_budget : float or None
        Seconds.
    seed : int

    Examples
    --------
    >>> from render.scene import RenderSettings
    >>> plan = PassPlan.of(RenderSettings(1024, 1024, spp=3), 1024 * 1024)
    >>> plan.per_pass, plan.passes, [len(plan.chunks(k)) for k in range(plan.passes)]
    (1, 3, [16, 16, 16])
    >>> plan = PassPlan.of(RenderSettings(64, 64, spp=300), 64 * 64)
    >>> plan.per_pass, plan.passes, plan.pass_spp(2), plan.chunk_count
    (128, 3, 44, 19)
    """

    npix: int
    per_pass: int
    passes: int | None
    spp: int
    time_budget: float | None
    seed: int

    @classmethod
    def of(cls, settings, npix: int, spp=None, time_budget=None, seed=None) -> PassPlan:
        """The plan for ``npix`` pixels: ``spp``, ``time_budget`` and ``seed`` override the
        scene's :class:`~render.scene.RenderSettings` (without either budget, the scene's
        ``time`` if set, else its ``spp``)."""
        if spp is None and time_budget is None:
            time_budget = settings.time
        spp = settings.spp if spp is None else int(spp)
        seed = settings.seed if seed is None else int(seed)
        # a pass holds at least PASS_SAMPLES samples (small images: several spp per pass);
        # independent of the thread count, so the image is too
        per_pass = max(1, settings.spp_per_pass, -(-PASS_SAMPLES // npix))
        if not time_budget:
            per_pass = min(per_pass, spp)
        passes = None if time_budget else -(-spp // per_pass)
        return cls(int(npix), per_pass, passes, spp, time_budget or None, seed)

    def pass_spp(self, k: int) -> int:
        """Samples per pixel of pass ``k`` (the last pass of an spp budget may be short)."""
        if self.passes is None:
            return self.per_pass
        return min(self.per_pass, self.spp - k * self.per_pass)

    def chunks(self, k: int) -> list[tuple[int, int, tuple[int, int]]]:
        """The work items of pass ``k``: ``(k, pass_spp, (a, b))`` for samples ``[a, b)``."""
        k_spp = self.pass_spp(k)
        per = self.npix * k_spp
        return [(k, k_spp, (a, min(a + CHUNK, per))) for a in range(0, per, CHUNK)]

    @property
    def chunk_count(self) -> int | None:
        """Chunks of the whole image (None with a time budget)."""
        if self.passes is None:
            return None
        return sum(-(-self.npix * self.pass_spp(k) // CHUNK) for k in range(self.passes))


def render_chunk(integrator, plan: PassPlan, item) -> FilmPatch:
    """Trace one work item of ``plan`` (:meth:`PassPlan.chunks`) with ``integrator``
    (:class:`render.integrator.Integrator`) and sum it into a patch."""
    k, k_spp, (a, b) = item
    keep_freed_memory()
    pixel, within = np.divmod(np.arange(a, b, dtype=np.int64), k_spp)
    rgb, alpha, aovs = integrator.trace(pixel, k * plan.per_pass + within, plan.seed)
    return FilmPatch.of_samples(pixel, rgb, alpha, aovs, integrator.aovs)


@functools.cache
def keep_freed_memory() -> None:
    """Let glibc keep freed memory for reuse in this process (once per process).

    A chunk allocates its lanes' arrays afresh (tens of MB).  With glibc's default
    limits, memory freed at the end of a chunk is returned to the kernel and mapped
    again, page by page, by the next: 16 % of a render's time was the kernel clearing
    pages, 5 % with these limits (glibc's own dynamic limits at their largest: 32 MB
    mmap threshold, 64 MB trim).  Dask's nannies start workers with
    ``MALLOC_TRIM_THRESHOLD_=65536``, which also pins the mmap threshold at 128 kB:
    there, chunks took 2-2.5 times as long without this."""
    import ctypes
    import sys

    if not sys.platform.startswith("linux"):
        return
    try:
        libc = ctypes.CDLL("libc.so.6")
    except OSError:  # not glibc (musl): no such limits to set
        return
    m_trim_threshold, m_mmap_threshold = -1, -3
    libc.mallopt(m_mmap_threshold, 32 << 20)
    libc.mallopt(m_trim_threshold, 64 << 20)
