"""Benchmark: rendering on a local Dask cluster against in-process, and what a chunk costs.

Run ``python benchmarks/cluster_speed.py [--scene NAME] [--resolution W H] [--spp N]``
(``--quick`` for a tiny smoke run).  It prints:

* **samples/s** in-process (1 and 2 threads) and on local clusters of processes
  (1 worker x 1 thread, 1 x 2, 2 x 1), each next to its largest difference from the
  in-process image (0: the same bits);
* **CPU seconds per million samples** of each, split into the client process (which
  holds the scheduler of a local cluster) and the worker processes, and the cluster's
  **overhead per chunk** in CPU time: what it spends beyond the in-process render of the
  same samples.  CPU time is what the cluster costs whatever else runs on the machine;
  wall-clock rates on a shared machine are not (the load average is printed);
* **per chunk**, wall clock: a task's round trip, the throughput of no-op tasks, the
  transfer of a chunk's patch beyond a no-op task, and the client's merge;
* **chunks per task**: the overhead per task and per million samples for tasks of 1 to
  8 chunks (2 workers; the same image);
* **dicing on each worker or on the client** (``--dice-scene``, a displaced scene at
  print size): the pickled scene and the dicing on the workers, against the diced
  geometry's bytes and its transfer to one worker;
* **a projection** to 10 and 100 workers from these figures (``docs/distributed.md``).

Every figure is the best of ``--repeats`` runs.
"""

from __future__ import annotations

import argparse
import dataclasses
import os
import pickle
import sys
import time
from pathlib import Path

import numpy as np
import psutil

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from render.distributed import cluster, render_on_cluster  # noqa: E402
from render.film import FilmPatch  # noqa: E402
from render.integrator import Integrator  # noqa: E402
from render.library.resources import bundled_scenes  # noqa: E402
from render.passes import CHUNK, PassPlan  # noqa: E402
from render.scene import load_scene  # noqa: E402

#: networks of the projection, bytes/s: 1 and 10 Gb/s
NETWORKS = {"1 Gb/s": 125e6, "10 Gb/s": 1.25e9}


def sized_scene(name: str, w: int, h: int):
    """A gallery scene (or scene file) at ``w`` x ``h``."""
    path = Path(name)
    if not path.is_file():
        path = bundled_scenes() / f"{name}.toml"
    scene = load_scene(path)
    scene.settings.width, scene.settings.height = w, h
    scene.camera = dataclasses.replace(scene.camera, width=w, height=h)
    return path.stem, scene


def cpu_s(pids) -> float:
    """User + system CPU seconds of these processes (all their threads).  This process is
    read from its own CPU clock (nanoseconds): psutil reads others from /proc in 10 ms
    ticks, too coarse for a ``--quick`` render, whose reference CPU would read 0."""
    total = 0.0
    for pid in pids:
        if pid == os.getpid():
            total += time.process_time()
            continue
        t = psutil.Process(pid).cpu_times()
        total += t.user + t.system
    return total


def measured(run, pids, workers, repeats: int):
    """Run ``run()`` ``repeats`` times; the run of least total CPU, as (its result, wall
    seconds, CPU of ``pids`` (this process, with a local cluster's scheduler), CPU of
    ``workers``)."""
    best = None
    for _ in range(repeats):
        c0, w0, t0 = cpu_s(pids), cpu_s(workers), time.perf_counter()
        out = run()
        wall = time.perf_counter() - t0
        row = (out, wall, cpu_s(pids) - c0, cpu_s(workers) - w0)
        if best is None or row[2] + row[3] < best[2] + best[3]:
            best = row
    return best


def _noop(i):
    return i


def _patch_of(rows: int):
    """A patch of ``rows`` pixels, as a chunk sends it (made on the worker)."""
    rng = np.random.default_rng(rows)
    return FilmPatch(0, rng.random((rows, 3)), rng.random(rows), np.ones(rows, np.int64))


def wall_costs(client, rows: int, quick: bool, repeats: int) -> dict:
    """Wall clock: a task's round trip, no-op throughput, a patch's transfer."""
    n = 40 if quick else 400
    t0 = time.perf_counter()
    for i in range(n // 10):
        client.submit(_noop, i, pure=False).result()
    latency = (time.perf_counter() - t0) / (n // 10)
    t0 = time.perf_counter()
    client.gather([client.submit(_noop, i, pure=False) for i in range(n)])
    per_task = (time.perf_counter() - t0) / n

    def best(f):
        return min(_timed(f) for _ in range(max(3, 3 * repeats)))

    t_x = best(lambda: client.submit(_patch_of, rows, pure=False).result())
    t_x -= best(lambda: client.submit(_noop, 0, pure=False).result())
    return {"latency_s": latency, "task_s": per_task, "transfer_s": max(t_x, 0.0),
            "transfer_bytes": _patch_of(rows).nbytes}


def _timed(f) -> float:
    t0 = time.perf_counter()
    f()
    return time.perf_counter() - t0


def dicing(client, name: str, scene, repeats: int) -> dict:
    """Dicing on each worker (what render_on_cluster does) against dicing on the client
    and shipping the geometry."""
    t_client = min(_timed(scene.build) for _ in range(repeats))
    geo = scene.build()
    names = ("vertices", "normals", "tangent_u", "tangent_v", "uv", "faces", "face_object",
             "face_normal", "face_offset")
    arrays = {n: getattr(geo, n) for n in names}
    geo_bytes = len(pickle.dumps(arrays, protocol=5))
    address = next(iter(client.nthreads()))
    t_geo = min(_timed(lambda: client.cancel(client.scatter(arrays, workers=[address],
                                                            hash=False)))
                for _ in range(max(2, repeats)))
    st = render_on_cluster(scene, client, spp=1, progress=False).stats
    w, h = scene.camera.width, scene.camera.height
    print(f"\ndicing: {name} at {w}x{h}, {geo.triangle_count} triangles")
    print(f"  pickled scene, to each worker   {st['scene_bytes'] / 1e3:9.1f} kB")
    print(f"  dice and BVH on the client      {t_client:9.2f} s")
    print(f"  dice and BVH on each worker     {st['geometry_s']:9.2f} s (2 at once; the whole "
          f"build {st['build_s']:.2f} s)")
    print(f"  the diced geometry instead      {geo_bytes / 1e6:9.2f} MB per worker, "
          f"{t_geo:.3f} s to one worker here")
    for workers in (2, 10, 100):
        cells = []
        for net, bw in NETWORKS.items():
            cells.append(f"{net}: {t_client + workers * geo_bytes / bw:6.2f} s diced on the "
                         f"client, {t_client + workers * st['scene_bytes'] / bw:5.2f} s on "
                         "each")
        print(f"  {workers:>3} workers, until every one has its geometry: " + "; ".join(cells))
    return {"scene_bytes": st["scene_bytes"], "geo_bytes": geo_bytes, "dice_s": t_client}


def projection(rate1: float, serial: float, worker_extra: float, per_pass: int,
               dice: dict) -> None:
    """Efficiency of W workers tracing ``rate1`` samples/s each, when the scheduler and
    client spend ``serial`` CPU seconds per task and a worker ``worker_extra`` beyond its
    chunk; results weigh 40 bytes per pixel of a patch (no AOVs)."""
    print(f"  a worker thread traces {rate1 / 1e6:.3f} M samples/s; per task the scheduler "
          f"and client spend {serial * 1e3:.2f} ms, a worker {worker_extra * 1e3:.2f} ms more")
    for workers in (10, 100):
        for per_task in (1, 4, 16):
            t_c = per_task * CHUNK / rate1
            eff = min(1.0, t_c / (workers * serial)) * t_c / (t_c + worker_extra)
            print(f"  {workers:>3} workers, tasks of {per_task:>2} chunks ({t_c * 1e3:5.0f} ms "
                  f"each): efficiency {eff:4.0%}")
        for k_spp in (1, per_pass):
            inflow = workers * rate1 * 40.0 / k_spp
            cells = [f"{min(1.0, bw / inflow):4.0%} on {net}" for net, bw in NETWORKS.items()]
            print(f"  {workers:>3} workers at {k_spp:>3} spp per pass: results "
                  f"{inflow / 1e6:7.1f} MB/s into the client, efficiency " + ", ".join(cells))
        ship = workers * dice["scene_bytes"] / NETWORKS["1 Gb/s"]
        print(f"  {workers:>3} workers: the scene to all {ship:.2f} s on 1 Gb/s, then "
              f"{dice['dice_s']:.2f} s of dicing on each, at once")
    for workers in (10, 100):
        need = workers * serial * rate1 / 0.9
        print(f"  tasks for 90% on {workers} workers: >= {need:,.0f} samples "
              f"({-(-need // CHUNK):.0f} chunks of {CHUNK})")


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--scene", default="fig_14_28", help="a gallery scene or a scene file")
    ap.add_argument("--resolution", type=int, nargs=2, metavar=("W", "H"), default=(256, 192))
    ap.add_argument("--spp", type=int, default=64)
    ap.add_argument("--dice-scene", default="fig_15_29", help="a displaced scene")
    ap.add_argument("--dice-resolution", type=int, nargs=2, metavar=("W", "H"),
                    default=(1536, 1152))
    ap.add_argument("--repeats", type=int, default=2)
    ap.add_argument("--quick", action="store_true", help="a tiny smoke run")
    args = ap.parse_args(argv)
    if args.quick:
        args.resolution, args.spp, args.repeats = (32, 24), 4, 1
        args.dice_resolution = (48, 36)
    name, scene = sized_scene(args.scene, *args.resolution)
    npix, spp = scene.camera.width * scene.camera.height, args.spp
    samples = npix * spp
    plan = PassPlan.of(scene.settings, npix, spp)
    print(f"{name} at {scene.camera.width}x{scene.camera.height}, {spp} spp: "
          f"{samples / 1e6:.2f} M samples in {plan.chunk_count} chunks of {CHUNK} samples "
          f"({plan.per_pass} spp per pass); {os.cpu_count()} cores, load average "
          f"{os.getloadavg()[0]:.1f}")

    me = [os.getpid()]
    integ = Integrator(scene, scene.build())
    integ.render(spp=1, progress=False)  # compile (cached) and warm up
    print("\n                          samples/s   CPU s per M samples: client  workers   "
          "total   overhead per chunk  (difference)")
    for threads in (1, 2):
        film, wall, cpu, _ = measured(
            lambda t=threads: integ.render(spp=spp, progress=False, threads=t), me, [],
            args.repeats)
        print(f"  in-process, {threads} thread(s)  {samples / wall / 1e6:7.3f} M/s"
              f"{'':22}{cpu * 1e6 / samples:8.2f}")
    ref = film.rgb()
    # the reference CPU: one thread, numba on one thread (no OpenMP threads spinning)
    _, wall, cpu_one, _ = measured(lambda: _in_process(integ, plan), me, [], args.repeats)
    print(f"  in-process, one core     {samples / wall / 1e6:7.3f} M/s"
          f"{'':22}{cpu_one * 1e6 / samples:8.2f}")
    cpu_ref = {1: cpu_one}
    for workers, threads in ((1, 1), (1, 2), (2, 1)):
        with cluster(workers=workers, threads_per_worker=threads) as client:
            pids = list(client.run(os.getpid).values())
            render_on_cluster(scene, client, spp=1, progress=False)  # workers load kernels

            def run(c=client, per_task=None):
                return render_on_cluster(scene, c, spp=spp, progress=False,
                                         chunks_per_task=per_task)

            film, wall, cpu, wcpu = measured(run, me, pids, args.repeats)
            chunks = plan.chunk_count
            extra = (cpu + wcpu - cpu_ref[1]) / chunks
            diff = float(np.max(np.abs(film.rgb() - ref)))
            print(f"  cluster, {workers} x {threads} thread(s) {samples / wall / 1e6:7.3f} M/s"
                  f"{'':12}{cpu * 1e6 / samples:8.2f} {wcpu * 1e6 / samples:8.2f} "
                  f"{(cpu + wcpu) * 1e6 / samples:7.2f} {extra * 1e3:10.2f} ms"
                  f"        ({diff:g})")
            if (workers, threads) != (2, 1):
                continue
            rows = min(-(-CHUNK // plan.per_pass), npix)
            st = film.stats
            serial = cpu / chunks  # the client and the scheduler
            worker_extra = (wcpu - cpu_ref[1]) / chunks
            rate1 = samples / cpu_ref[1]  # one core's samples per CPU second
            w = wall_costs(client, rows, args.quick, args.repeats)
            print(f"\nper chunk ({CHUNK} samples, a patch of {rows} pixels, "
                  f"{st['patch_bytes'] / chunks / 1e3:.0f} kB), 2 workers:")
            print(f"  render, CPU                   {cpu_ref[1] / chunks * 1e3:8.2f} ms")
            print(f"  client and scheduler, CPU     {serial * 1e3:8.2f} ms "
                  f"(of which the merge {st['merge_s'] / chunks * 1e3:.2f} ms)")
            print(f"  workers beyond the render, CPU {worker_extra * 1e3:7.2f} ms")
            print(f"  a task's round trip, wall     {w['latency_s'] * 1e3:8.2f} ms")
            print(f"  no-op tasks, wall per task    {w['task_s'] * 1e3:8.2f} ms")
            print(f"  a patch's transfer, wall      {w['transfer_s'] * 1e3:8.2f} ms "
                  f"({w['transfer_bytes'] / 1e3:.0f} kB, beyond a no-op task)")
            print("\nchunks per task, 2 workers (CPU beyond the in-process render):")
            for per_task in (1, 4) if args.quick else (1, 2, 4, 8):
                film, wall, cpu, wcpu = measured(lambda n=per_task: run(per_task=n), me,
                                                 pids, args.repeats)
                tasks = film.stats["tasks"]
                over = cpu + wcpu - cpu_ref[1]
                diff = float(np.max(np.abs(film.rgb() - ref)))
                print(f"  {per_task:>2} chunks per task: {tasks:4d} tasks, "
                      f"{over / tasks * 1e3:7.2f} ms per task, "
                      f"{over * 1e6 / samples:6.2f} CPU s per M samples "
                      f"({over / cpu_ref[1]:6.1%} of the render); "
                      f"{samples / wall / 1e6:.3f} M/s  ({diff:g})")
            dice = dicing(client, *sized_scene(args.dice_scene, *args.dice_resolution),
                          args.repeats)
    print("\nprojection (docs/distributed.md): W workers, each a core as fast as one here")
    projection(rate1, serial, max(worker_extra, 0.0), plan.per_pass, dice)
    return 0


def _in_process(integ, plan: PassPlan):
    """The in-process render of ``plan``'s chunks on one core: one thread, and numba's
    parallel regions on one thread (the reference CPU time)."""
    import numba

    from render.film import Film
    from render.passes import render_chunk

    before = numba.get_num_threads()
    numba.set_num_threads(1)
    try:
        film = Film(integ.camera.width, integ.camera.height)
        for k in range(plan.passes):
            for item in plan.chunks(k):
                film.merge(render_chunk(integ, plan, item))
    finally:
        numba.set_num_threads(before)
    return film


if __name__ == "__main__":
    raise SystemExit(main())
