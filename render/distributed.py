"""Rendering on a Dask cluster: the chunks of :mod:`render.passes` run on
``dask.distributed`` workers, and the client merges their patches into one film.

The image is bit-identical to the in-process render with the same seed, whatever the
number of workers: a sample's values depend only on its pixel, its index and the seed
(:mod:`render.sampler`), and the client merges the
chunks' :class:`~render.film.FilmPatch` results in (pass, chunk) order, whole passes
at a time, as :meth:`render.integrator.Integrator.render` does.

How the work travels:

* **The scene, once per worker.**  A loaded :class:`~render.scene.Scene` holds what
  its files gave it (compiled profiles, texture pixels, meshes, materials parsed from
  MDL calls), so the workers never read the scene's files.  It is pickled once
  (cloudpickle) into a worker plugin; the scheduler hands the plugin to every worker,
  including workers that join or are restarted during the render, and removes it at
  the end.
* **Dicing on each worker.**  Each worker builds the geometry (dicing, Embree BVH) and
  the integrator once, in a first task, before the time budget starts.  Dicing there
  costs every worker the same wall time as dicing on the client, and ships a scene
  that is far smaller than its diced mesh (``benchmarks/cluster_speed.py`` measures
  both; ``docs/distributed.md``).
* **Chunks as tasks.**  A task renders consecutive chunks of a pass (one per 6 threads
  of the cluster, at least one) and returns their patches.  The client keeps a window
  of tasks in flight (twice the cluster's threads, at least one pass) so every worker
  stays busy across passes.  A worker that dies takes its running
  chunks with it; the scheduler runs them again elsewhere, and since a chunk's result
  depends only on its samples' pixels, indices and the seed, the image is unchanged.
* **The time budget** holds across workers: once it is spent (and one pass is merged)
  the client cancels the chunks in flight and keeps the whole passes merged so far.

**Whole tasks** (:func:`map_on_cluster`): work that is whole on its own (a gallery
figure, a ``pwc trade`` run) goes as one task per item, the loaded scene in the task's
arguments: it reaches only the worker that runs it, and stays with the scheduler, which
runs the task again elsewhere if that worker dies.  Such tasks return their results
and write nothing; the client writes the files.

Workers must run the same render code (:data:`render.jit.SOURCE_KEY`) and the same
numpy, numba and embreex as the client, or the bits could differ: the client checks
every worker, and a worker that joins with other code fails its chunks with a message.
"""

from __future__ import annotations

import functools
import hashlib
import os
import threading
import time as _time
import uuid
from collections.abc import Iterator
from contextlib import contextmanager

from render import checkout_pythonpath
from render.film import Film
from render.passes import PassPlan, render_chunk

__all__ = [
    "ClusterError",
    "cluster",
    "render_on_cluster",
    "map_on_cluster",
    "add_cluster_options",
    "worker_identity",
]

#: seconds to wait for a scheduler to answer, and for its first worker
CONNECT_TIMEOUT = 30.0
#: tasks in flight per thread of the cluster (enough to hide a task's round trip)
IN_FLIGHT_PER_THREAD = 2
#: by default a task holds one chunk per this many threads of the cluster: the scheduler
#: and the client spend ~5 ms per task, so 100 threads of a fast scene need tasks of ~15
#: chunks to stay above 90 % (docs/distributed.md)
THREADS_PER_CHUNK_IN_TASK = 6


class ClusterError(RuntimeError):
    """The cluster cannot render: unreachable scheduler, no workers, workers running
    other code, or a chunk that keeps killing workers.  The message names the fix."""


# --------------------------------------------------------------------------- cluster
def add_cluster_options(parser, work: str = "render") -> None:
    """Add ``--scheduler ADDRESS`` and ``--workers N`` (mutually exclusive) to a command
    that can spread its work over a Dask cluster; ``work`` says what in their help
    (``"render"``, ``"render the figures"``...)."""
    g = parser.add_mutually_exclusive_group()
    g.add_argument(
        "--scheduler",
        metavar="ADDRESS",
        help=f"{work} on a running Dask cluster (`dask scheduler`, then `dask worker "
        "ADDRESS` on each machine), e.g. tcp://scheduler-host:8786",
    )
    g.add_argument(
        "--workers",
        type=_worker_count,
        metavar="N",
        help=f"{work} on a local cluster of N worker processes on this machine",
    )


def _worker_count(text: str) -> int:
    """``--workers N``: a whole number >= 1 (argparse reports the message, status 2)."""
    import argparse

    try:
        n = int(text)
    except ValueError:
        n = 0
    if n < 1:
        raise argparse.ArgumentTypeError(f"--workers must be >= 1, got {text}")
    return n


@contextmanager
def cluster(
    scheduler: str | None = None,
    workers: int | None = None,
    threads_per_worker: int = 1,
    timeout: float | None = None,
) -> Iterator:
    """A ``distributed.Client`` of a running scheduler or of a new local cluster.

    Parameters
    ----------
    scheduler : str, optional
        Address of a running ``dask scheduler`` (``tcp://host:8786``).
    workers : int, optional
        Start a local cluster of this many worker processes instead (closed on exit).
        They import the render package the client runs, whatever their working folder.
    threads_per_worker : int
        Threads of each local worker.
    timeout : float, optional
        Seconds to wait for the scheduler to answer (default :data:`CONNECT_TIMEOUT`).

    Raises
    ------
    ClusterError
        The scheduler does not answer within ``timeout`` seconds.
    """
    import logging

    from distributed import Client, LocalCluster

    if (scheduler is None) == (workers is None):
        raise ValueError("give a scheduler address or a number of workers, not both or neither")
    if workers is not None:
        if workers < 1 or threads_per_worker < 1:
            raise ValueError(
                f"a local cluster needs >= 1 worker of >= 1 thread, got {workers} x "
                f"{threads_per_worker}"
            )
        with (
            LocalCluster(
                n_workers=workers,
                threads_per_worker=threads_per_worker,
                processes=True,
                host="127.0.0.1",
                dashboard_address=None,
                # no dashboard; the scheduler's HTTP routes on any free loopback port
                scheduler_kwargs={"dashboard": False, "dashboard_address": "127.0.0.1:0"},
                # the shutdown chatter of workers losing their scheduler is not news
                silence_logs=logging.CRITICAL,
                env={"PYTHONPATH": checkout_pythonpath()},
            ) as local,
            Client(local) as client,
        ):
            yield client
        return
    try:
        client = Client(scheduler, timeout=CONNECT_TIMEOUT if timeout is None else timeout)
    except (OSError, TimeoutError, ValueError) as e:
        raise ClusterError(
            f"cannot reach the Dask scheduler at {scheduler!r} ({e}); start one with "
            "`dask scheduler` and give the address it prints"
        ) from None
    with client:
        yield client


def worker_identity() -> dict:
    """What must match between client and workers for the same bits: the render
    sources' key and the versions of numpy, numba and embreex."""
    import embreex
    import numba
    import numpy

    from render.jit import SOURCE_KEY

    return {
        "render sources": SOURCE_KEY,
        "numpy": numpy.__version__,
        "numba": numba.__version__,
        "embreex": getattr(embreex, "__version__", "?"),
    }


def _identity_mismatch(theirs: dict, ours: dict) -> str | None:
    diff = [f"{k} {theirs.get(k)!r} (client: {v!r})" for k, v in ours.items() if theirs.get(k) != v]
    return ", ".join(diff) or None


def _wait_for_workers(client) -> None:
    from distributed.utils import TimeoutError as DaskTimeout

    try:
        client.wait_for_workers(1, timeout=CONNECT_TIMEOUT)
    except (TimeoutError, DaskTimeout):
        address = getattr(client.scheduler, "address", "the scheduler")
        raise ClusterError(
            f"no worker joined the scheduler at {address} within {CONNECT_TIMEOUT:.0f} s; "
            f"start one on each machine with `dask worker {address}`"
        ) from None


def _check_workers(client) -> None:
    ours = worker_identity()
    for address, theirs in client.run(worker_identity).items():
        diff = _identity_mismatch(theirs, ours)
        if diff:
            raise ClusterError(
                f"worker {address} runs other code: {diff}; install the same revision of "
                "pwc-workbench (and the same numpy, numba, embreex) on every worker, or the "
                "image would not be the same"
            )


# ------------------------------------------------------------- the scene on a worker
@functools.cache
def _scene_plugin_class():
    from distributed.diagnostics.plugin import WorkerPlugin

    class ScenePlugin(WorkerPlugin):
        """The pickled scene on one worker, and its integrator once built."""

        def __init__(self, payload: bytes, aovs: tuple, identity: dict, numba_threads: dict):
            self.payload = payload
            self.aovs = aovs
            self.identity = identity
            self.numba_threads = numba_threads

        def setup(self, worker) -> None:
            self.lock = threading.Lock()
            self.integrator = None
            self.build_s = self.geometry_s = None
            self.geometry_stats = None
            self.builds = 0

        def teardown(self, worker) -> None:
            self.integrator = None

        def prepared(self):
            """The integrator, built by the first task that asks (dicing included)."""
            with self.lock:
                if self.integrator is None:
                    diff = _identity_mismatch(worker_identity(), self.identity)
                    if diff:
                        raise ClusterError(
                            f"this worker runs other code than the client: {diff}; install "
                            "the same revision of pwc-workbench on every worker"
                        )
                    import pickle

                    from render.precompile import compiled_integrator

                    t0 = _time.perf_counter()
                    scene = pickle.loads(self.payload)
                    t1 = _time.perf_counter()
                    geometry = scene.build()
                    self.geometry_s = _time.perf_counter() - t1
                    # on a cold cache one worker of a host at a time
                    self.integrator = compiled_integrator(scene, geometry, self.aovs)
                    self.build_s = _time.perf_counter() - t0
                    self.builds += 1
                    self.geometry_stats = geometry.stats
                return self.integrator

    return ScenePlugin


def _plugin(name: str):
    """This worker and its scene plugin; the calling task thread's numba parallel regions
    set to this host's share of cores (numba would start one thread per core in every
    task thread of every worker, and spinning OpenMP threads on busy cores slow each
    chunk several times)."""
    from distributed import get_worker

    worker = get_worker()
    plugin = worker.plugins.get(name)
    if plugin is None:
        raise ClusterError(f"worker {worker.address} has no scene {name!r} (was it unregistered?)")
    _numba_share(worker, plugin.numba_threads)
    return worker, plugin


def _numba_share(worker, shares: dict) -> None:
    """Set the calling task thread's numba threads to its host's share (``shares``, from
    :func:`_numba_threads`)."""
    import numba

    share = shares.get(_host(worker.address))
    if share is not None:
        numba.set_num_threads(min(share, numba.config.NUMBA_NUM_THREADS))


def _host(address: str) -> str:
    """The host of a worker address (``tcp://127.0.0.1:4567`` -> ``127.0.0.1``)."""
    return address.split("://")[-1].rsplit(":", 1)[0]


def _numba_threads(client) -> dict:
    """Per host: its cores over the task threads of its workers (at least 1)."""
    threads: dict = {}
    for address, n in client.nthreads().items():
        threads[_host(address)] = threads.get(_host(address), 0) + n
    cores = {_host(a): n for a, n in client.run(os.cpu_count).items()}
    return {h: max(1, (cores.get(h) or 1) // n) for h, n in threads.items()}


def _prepare_task(name: str) -> dict:
    """Build the scene's integrator on this worker; its build time and geometry."""
    worker, plugin = _plugin(name)
    integ = plugin.prepared()
    return {
        "worker": worker.address,
        "pid": os.getpid(),
        "build_s": plugin.build_s,
        "geometry_s": plugin.geometry_s,
        "triangles": integ.geo.triangle_count,
        "geometry": plugin.geometry_stats,
        "bound_objects": [o.name for o, b in zip(integ.objects, integ.bound, strict=True)
                          if b],
    }


def _chunks_task(name: str, plan: PassPlan, items) -> tuple:
    """Render consecutive chunks on this worker: their patches, in order (each chunk's
    own, not their sum: the client adds them one by one, as in-process), and the cost."""
    worker, plugin = _plugin(name)
    integ = plugin.prepared()
    rays, embree = integ.rays, integ.embree_time
    t0 = _time.perf_counter()
    patches = [render_chunk(integ, plan, item) for item in items]
    info = {
        "worker": worker.address,
        "pid": os.getpid(),
        "trace_s": _time.perf_counter() - t0,
        "builds": plugin.builds,
        # per worker, not per thread: approximate when a worker runs chunks in threads
        "rays": integ.rays - rays,
        "embree_s": integ.embree_time - embree,
    }
    return patches, info


# --------------------------------------------------------------------------- render
def render_on_cluster(
    scene,
    client,
    spp: int | None = None,
    time: float | None = None,
    seed: int | None = None,
    aovs=(),
    progress: bool = True,
    denoise: bool = False,
    chunks_per_task: int | None = None,
) -> Film:
    """Render a scene on a Dask cluster; the arguments are those of
    :func:`render.integrator.render`, with the cluster's ``client`` for ``threads``.

    ``chunks_per_task`` (default: one per 6 threads of the cluster, at least one) sets
    how many consecutive chunks of a pass one task renders: the scheduler and the client
    pay per task, so a large cluster needs longer tasks (``docs/distributed.md``); the
    chunks, their sample values and the image stay the same.

    Returns
    -------
    Film
        Bit-identical to the in-process render with the same seed and samples.
        ``film.stats`` has the in-process keys, plus ``workers`` (per worker address:
        ``chunks``, ``trace_s``, ``build_s`` (unpickle, geometry, integrator),
        ``geometry_s`` (dicing and BVH), ``builds`` (times it built the scene: 1),
        ``pid``), ``merge_s`` (the client merging patches), ``tasks`` and
        ``chunks_per_task``, ``scene_bytes`` (the pickled
        scene), ``patch_bytes`` (all results) and ``prepare_s`` (until every worker had
        built the scene).

    Raises
    ------
    ClusterError
        No workers, workers with other code, or a chunk that kept killing workers.
    """
    import cloudpickle

    from render.scene import Scene, load_scene

    if not isinstance(scene, Scene):
        scene = load_scene(scene)
    aov_list = list(aovs)
    if denoise:
        aov_list = list(dict.fromkeys(aov_list + ["albedo", "normal"]))
    film = Film(scene.camera.width, scene.camera.height, aov_list)
    plan = PassPlan.of(scene.settings, film.pixel_count, spp, time, seed)
    if chunks_per_task is not None and chunks_per_task < 1:
        raise ValueError(f"chunks_per_task must be >= 1, got {chunks_per_task}")

    _wait_for_workers(client)
    _check_workers(client)
    t0 = _time.perf_counter()
    payload = cloudpickle.dumps(scene)
    token = hashlib.sha256(payload).hexdigest()[:12]
    name = f"pwc-scene-{token}-{uuid.uuid4().hex[:8]}"
    plugin = _scene_plugin_class()(payload, tuple(film.aov_names), worker_identity(),
                                   _numba_threads(client))
    client.register_plugin(plugin, name=name)
    try:
        prepared = _prepare(client, name, progress)
        prepare_s = _time.perf_counter() - t0
        stats = _render_passes(client, name, plan, film, progress, chunks_per_task)
    finally:
        try:
            client.unregister_worker_plugin(name)
        except Exception:  # noqa: BLE001 - the scheduler may be gone; nothing to free then
            pass
    first = next(iter(prepared.values()))
    workers = stats["workers"]
    for address, info in prepared.items():
        workers.setdefault(address, {"chunks": 0, "trace_s": 0.0, "pid": info["pid"]})
        workers[address]["build_s"] = info["build_s"]
        workers[address]["geometry_s"] = info["geometry_s"]
    elapsed = stats["time_s"]
    film.stats.update(
        passes=stats["passes"],
        spp=stats["spp"],
        time_s=elapsed,
        rays=stats["rays"],
        embree_time_s=stats["embree_s"],
        samples_per_s=film.pixel_count * stats["spp"] / elapsed if elapsed > 0 else 0.0,
        triangles=first["triangles"],
        bound_objects=first["bound_objects"],
        build_s=max(info["build_s"] for info in prepared.values()),
        geometry_s=max(info["geometry_s"] for info in prepared.values()),
        geometry=first["geometry"],
        workers=workers,
        scene_bytes=len(payload),
        patch_bytes=stats["patch_bytes"],
        merge_s=stats["merge_s"],
        tasks=stats["tasks"],
        chunks_per_task=stats["chunks_per_task"],
        prepare_s=prepare_s,
    )
    if denoise:
        film.denoise()
    return film


def _prepare(client, name: str, progress: bool) -> dict:
    """Build the scene on every worker now (one task each), so the time budget and the
    chunks' times count rendering only; a worker that joins later builds in its first
    chunk.  Returns each worker's :func:`_prepare_task` answer."""
    futures = [
        client.submit(
            _prepare_task,
            name,
            key=f"{name}-prepare-{i}",
            workers=[address],
            allow_other_workers=True,
            pure=False,
        )
        for i, address in enumerate(client.nthreads())
    ]
    from distributed import as_completed

    bar = None
    if progress:
        from tqdm import tqdm

        bar = tqdm(total=len(futures), unit="worker", desc="build scene on workers", leave=False)
    answers = {}
    try:
        for fut in as_completed(futures):
            a = fut.result()
            answers[a["worker"]] = a
            if bar is not None:
                bar.update(1)
    except Exception as e:
        raise _explain(e, "preparing the scene") from None
    finally:
        if bar is not None:
            bar.close()
    return answers


def _explain(error: Exception, doing: str) -> Exception:
    """A chunk's failure as the exception to raise: the task's own error (a scene
    error, a ClusterError from the worker), or a ClusterError for a killed worker."""
    from distributed.scheduler import KilledWorker

    if isinstance(error, KilledWorker):
        return ClusterError(
            f"{doing}: the task killed {error.allowed_failures + 1} workers in turn (the "
            f"last {getattr(error.last_worker, 'address', '?')}): out of memory, or a crash "
            "in a native library? See the workers' logs"
        )
    return error


def _render_passes(
    client, name: str, plan: PassPlan, film: Film, progress: bool, per_task: int | None
) -> dict:
    """Submit the chunks in (pass, chunk) order, ``per_task`` consecutive chunks of a
    pass in a task, keep a window of tasks in flight, and merge whole passes in order
    as they complete."""
    from distributed import as_completed

    threads = sum(client.nthreads().values()) or 1
    per_task = per_task or max(1, threads // THREADS_PER_CHUNK_IN_TASK)
    window = max(IN_FLIGHT_PER_THREAD * threads, -(-len(plan.chunks(0)) // per_task))
    bar = None
    if progress:
        from tqdm import tqdm

        desc = f"render on {len(client.nthreads())} workers"
        bar = tqdm(total=plan.chunk_count, unit="chunk", desc=desc, leave=False)
    stats = {"workers": {}, "rays": 0, "embree_s": 0.0, "patch_bytes": 0, "merge_s": 0.0,
             "chunks_per_task": per_task, "tasks": 0}
    todo = _tasks(plan, per_task, threads)
    in_flight: dict = {}  # future -> its items
    done: dict = {}  # pass -> {first sample of a chunk: patch}
    size: dict = {}  # pass -> its number of chunks
    merged = spp = 0
    start = _time.perf_counter()
    ac = as_completed()

    def over() -> bool:
        return plan.passes is None and _time.perf_counter() - start >= plan.time_budget

    def submit(count: int) -> None:
        for _ in range(count):
            items = next(todo, None)
            if items is None:
                return
            k, _, (a, _) = items[0]
            if k not in size:
                size[k] = len(plan.chunks(k))
            fut = client.submit(
                _chunks_task, name, plan, items, key=f"{name}-chunks-{k}-{a}", pure=False
            )
            in_flight[fut] = items
            ac.add(fut)

    try:
        submit(window)  # the first pass whole, whatever the budget
        for fut in ac:
            items = in_flight.pop(fut)
            try:
                patches, info = fut.result()
            except Exception as e:
                k, _, (a, _) = items[0]
                raise _explain(e, f"chunk {a} of pass {k}") from None
            for (k, _, (a, _)), patch in zip(items, patches, strict=True):
                done.setdefault(k, {})[a] = patch
                stats["patch_bytes"] += patch.nbytes
            w = stats["workers"].setdefault(
                info["worker"], {"chunks": 0, "trace_s": 0.0, "pid": info["pid"]}
            )
            w["chunks"] += len(items)
            w["builds"] = max(w.get("builds", 0), info["builds"])
            w["trace_s"] += info["trace_s"]
            stats["rays"] += info["rays"]
            stats["embree_s"] += info["embree_s"]
            stats["tasks"] += 1
            if bar is not None:
                bar.update(len(items))
            # whole passes, in order, chunks in order: the in-process sums, bit for bit
            t_merge = _time.perf_counter()
            while len(done.get(merged, ())) == size.get(merged, -1):
                for _, p in sorted(done.pop(merged).items()):
                    film.merge(p)
                spp += plan.pass_spp(merged)
                merged += 1
            stats["merge_s"] += _time.perf_counter() - t_merge
            if merged == plan.passes or (merged > 0 and over()):
                break
            if not over():
                submit(window - len(in_flight))
    finally:
        if in_flight:
            client.cancel(list(in_flight))
        if bar is not None:
            bar.close()
    stats.update(passes=merged, spp=spp, time_s=_time.perf_counter() - start)
    return stats


def _tasks(plan: PassPlan, per_task: int, threads: int):
    """The work items of every pass in order, up to ``per_task`` consecutive ones of a
    pass at a time (endless with a time budget).  Near the end of an spp budget the
    tasks shrink as OpenMP's *guided* schedule does, to the chunks left over twice the
    threads, down to a quarter of ``per_task``: the last tasks leave workers idle for
    less, without multiplying the tasks."""
    left = plan.chunk_count
    floor = max(1, per_task // 4)
    k = 0
    while plan.passes is None or k < plan.passes:
        items = plan.chunks(k)
        i = 0
        while i < len(items):
            n = per_task if left is None else max(floor, min(per_task, left // (2 * threads)))
            group = items[i:i + n]
            yield group
            i += len(group)
            if left is not None:
                left -= len(group)
        k += 1


# ---------------------------------------------------------------------- whole tasks
def map_on_cluster(
    client,
    function,
    jobs,
    progress: bool = True,
    desc: str = "tasks",
    unit: str = "task",
    stop=None,
) -> Iterator[tuple[int, object]]:
    """Run ``function(job)`` for every job, one task each, on the cluster of ``client``,
    and yield ``(index, result)`` in the jobs' order as the results arrive.

    For work that is whole on its own: a gallery figure, a ``pwc trade`` run.  The job
    travels in the task's arguments (pickled by Dask with cloudpickle, so a loaded
    :class:`~render.scene.Scene` goes with what its files gave it) to the one worker
    that runs it; the scheduler keeps it, and runs the task again elsewhere if that
    worker dies.  So ``function`` must be pure: it returns what it made and writes no
    file (the client writes them), and it must be importable on the workers (a
    module-level function, or a ``functools.partial`` of one).  Each task runs with the
    worker settings of :func:`render_on_cluster` (glibc keeps freed memory; numba's
    threads are the host's cores over its task threads).

    Parameters
    ----------
    client : distributed.Client
    function : callable
    jobs : iterable
        Consumed whole before the first result is yielded (each is submitted as soon as
        it is made, so workers start while the client makes the next).
    progress : bool or bar
        One bar on the client, counting the tasks as they finish, in any order; or the
        caller's own bar (anything with ``update(n)``), which it keeps.
    desc, unit : str
        The bar's label and unit.
    stop : callable, optional
        Called after each finished task; when it returns True, the tasks not finished
        are cancelled, and the finished ones are yielded, in order, with gaps.

    Raises
    ------
    ClusterError
        No workers, workers with other code, or a task that kept killing workers.
    Exception
        The first task error, as the task raised it.
    """
    from distributed import as_completed

    _wait_for_workers(client)
    _check_workers(client)
    shares = _numba_threads(client)
    tag = uuid.uuid4().hex[:8]
    index: dict = {}
    results: dict = {}
    ac = as_completed()
    bar, own = None, False
    try:
        for i, job in enumerate(jobs):
            fut = client.submit(_whole_task, function, job, shares, pure=False,
                                key=f"pwc-{unit}-{tag}-{i}")
            index[fut] = i
            ac.add(fut)
        total = len(index)
        if hasattr(progress, "update"):
            bar, own = progress, False
        elif progress:
            from tqdm import tqdm

            desc = f"{desc} on {len(client.nthreads())} workers"
            bar, own = tqdm(total=total, unit=unit, desc=desc, leave=False), True
        done = 0
        for fut in ac:
            i = index.pop(fut)
            try:
                results[i] = fut.result()
            except Exception as e:
                raise _explain(e, f"{unit} {i + 1} of {total}") from None
            if bar is not None:
                bar.update(1)
            while done in results:
                yield done, results.pop(done)
                done += 1
            if stop is not None and stop():
                break
        # stopped: what finished meanwhile is kept; the rest is cancelled below
        for fut, i in list(index.items()):
            if fut.status == "finished":
                results[i] = fut.result()
                del index[fut]
        for i in sorted(results):
            yield i, results[i]
    finally:
        if index:
            client.cancel(list(index))
        if own:
            bar.close()


def _whole_task(function, job, shares: dict):
    """A whole task on a worker: the worker settings of the chunks, then the job."""
    from distributed import get_worker

    from render.passes import keep_freed_memory

    keep_freed_memory()
    _numba_share(get_worker(), shares)
    return function(job)
