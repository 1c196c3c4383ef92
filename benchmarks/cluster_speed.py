"""Benchmark: rendering on a local Dask cluster against in-process, and what a chunk costs.

Run ``python benchmarks/cluster_speed.py [--scene NAME] [--resolution W H] [--spp N]``
(``--quick`` for a tiny smoke run).  On this machine (``nproc`` cores) it prints:

* **samples/s** in-process (1 and 2 threads) and on local clusters of processes
  (1 worker x 1 thread, 1 x 2, 2 x 1), each next to its largest difference from the
  in-process image (0: the same bits), and its efficiency against in-process with as
  many threads;
* **per chunk**: its render time on a worker, the scheduling cost of a task (no-op
  tasks, one at a time and many at once), the transfer of a chunk's patch from a
  worker to the client, and the client's merge;
* **scene shipping and dicing**: the pickled scene's bytes and the time to hand it to
  every worker and build it there, against dicing on the client and shipping the
  diced geometry (its bytes and transfer time to one worker);
* **chunk size**: samples/s on 2 workers for chunks of 4096 to 262144 samples;
* **a projection** to 10 and 100 workers from these figures (the model is in
  ``docs/distributed.md``).

Every time is the best of ``--repeats`` runs (the machine may be shared).
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

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from render.distributed import cluster, render_on_cluster  # noqa: E402
from render.film import Film, FilmPatch  # noqa: E402
from render.integrator import Integrator  # noqa: E402
from render.library.resources import bundled_scenes  # noqa: E402
from render.passes import CHUNK, PassPlan  # noqa: E402
from render.scene import load_scene  # noqa: E402


def best(f, repeats: int):
    """(smallest seconds, last result) of ``repeats`` calls of ``f``."""
    times, out = [], None
    for _ in range(repeats):
        t0 = time.perf_counter()
        out = f()
        times.append(time.perf_counter() - t0)
    return min(times), out


def _noop(i):
    return i


def _patch_of(rows: int, aovs: int):
    """A patch of ``rows`` pixels as a chunk sends it (made on the worker)."""
    rng = np.random.default_rng(rows)
    return FilmPatch(0, rng.random((rows, 3)), rng.random(rows), np.ones(rows, np.int64),
                     {f"a{i}": rng.random((rows, 3)) for i in range(aovs)})


def _geometry_arrays(geo) -> dict:
    """What shipping the diced geometry would send (all but the Embree scene)."""
    names = ("vertices", "normals", "tangent_u", "tangent_v", "uv", "faces", "face_object",
             "face_normal", "face_offset")
    return {n: getattr(geo, n) for n in names}


def scheduling(client, n: int) -> tuple[float, float]:
    """Seconds per no-op task: one at a time (latency) and ``n`` at once (throughput)."""
    t0 = time.perf_counter()
    for i in range(max(5, n // 20)):
        client.submit(_noop, i, pure=False).result()
    latency = (time.perf_counter() - t0) / max(5, n // 20)
    t0 = time.perf_counter()
    client.gather([client.submit(_noop, i, pure=False) for i in range(n)])
    return latency, (time.perf_counter() - t0) / n


def transfer(client, rows: int, repeats: int) -> tuple[float, int]:
    """Seconds to bring a patch of ``rows`` pixels from a worker, beyond a no-op task."""
    nbytes = _patch_of(rows, 0).nbytes

    def fetch():
        return client.submit(_patch_of, rows, 0, pure=False).result()

    def noop():
        return client.submit(_noop, 0, pure=False).result()

    t_fetch, _ = best(fetch, repeats)
    t_noop, _ = best(noop, repeats)
    return max(t_fetch - t_noop, 0.0), nbytes


def cluster_film(client, scene, spp: int, repeats: int):
    """The best of ``repeats`` renders on the cluster, after one that loads the kernels."""
    render_on_cluster(scene, client, spp=1, progress=False)
    return best(lambda: render_on_cluster(scene, client, spp=spp, progress=False), repeats)[1]


def chunk_costs(client, st: dict, rows: int, quick: bool, repeats: int) -> dict:
    """The per-chunk figures: render, scheduling, transfer and merge."""
    chunks = sum(v["chunks"] for v in st["workers"].values())
    latency, per_task = scheduling(client, 40 if quick else 400)
    t_x, nbytes = transfer(client, rows, max(3, 3 * repeats))
    return {
        "render_s": sum(v["trace_s"] for v in st["workers"].values()) / chunks,
        "latency_s": latency,
        "task_s": per_task,
        "transfer_s": t_x,
        "transfer_bytes": nbytes,
        "patch_bytes": st["patch_bytes"] / chunks,
        "merge_s": st["merge_s"] / chunks,
    }


def shipping(client, geo, repeats: int) -> tuple[int, float]:
    """Bytes of the diced geometry and seconds to send them to one worker."""
    arrays = _geometry_arrays(geo)
    nbytes = len(pickle.dumps(arrays, protocol=5))
    address = next(iter(client.nthreads()))

    def send():
        client.cancel(client.scatter(arrays, workers=[address], hash=False))

    return nbytes, best(send, max(2, repeats))[0]


def chunk_sizes(client, scene, integ, spp: int, repeats: int, sizes, rate2: float) -> None:
    """samples/s on the cluster for other chunk sizes, each against the in-process image
    of the same chunks (other sizes draw other random streams)."""
    from render.passes import render_chunk

    npix = scene.camera.width * scene.camera.height
    for size in sizes:
        _, film = best(lambda s=size: render_on_cluster(scene, client, spp=spp,
                                                        progress=False, chunk=s), repeats)
        plan = PassPlan.of(scene.settings, npix, spp, chunk=size)
        own = Film(scene.camera.width, scene.camera.height)
        for k in range(plan.passes):
            for item in plan.chunks(k):
                own.merge(render_chunk(integ, plan.seed, item))
        diff = float(np.max(np.abs(film.rgb() - own.rgb())))
        r = film.stats["samples_per_s"]
        print(f"  {size:>7} samples per chunk  {r / 1e6:7.3f} M/s  (difference {diff:g}; "
              f"efficiency {r / rate2:.0%})")


def projection(rate1: float, c: dict, scene_bytes: int, build_s: float) -> None:
    """Efficiency of W workers, each rendering ``rate1`` samples/s, from the measured
    per-task serial cost (scheduler, transfer, merge), the patch bytes and the scene."""
    serial = c["task_s"] + c["transfer_s"] + c["merge_s"]
    bytes_per_sample = c["patch_bytes"] / CHUNK
    print(f"  per task, serial at the scheduler and client: {serial * 1e3:.2f} ms; "
          f"{bytes_per_sample:.1f} result bytes per sample")
    for workers in (10, 100):
        for size in (CHUNK, 4 * CHUNK, 16 * CHUNK):
            t_c = size / rate1
            busy = min(1.0, t_c / (workers * serial))
            inflow = workers * rate1 * bytes_per_sample
            print(f"  {workers:>3} workers, {size:>7}-sample chunks ({t_c * 1e3:6.0f} ms): "
                  f"scheduler/client keep {busy:4.0%} busy; results {inflow / 1e6:6.1f} MB/s "
                  f"into the client")
        ship = workers * scene_bytes / 125e6
        print(f"  {workers:>3} workers: the scene to every worker {ship:.2f} s at 1 Gb/s "
              f"(plus {build_s:.2f} s to build, in parallel)")
    need = 100 * serial * rate1 / 0.9
    print(f"  chunk size for 90% on 100 workers: >= {need:,.0f} samples")


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--scene", default="fig_14_28", help="a gallery scene or a scene file")
    ap.add_argument("--resolution", type=int, nargs=2, metavar=("W", "H"), default=(256, 192))
    ap.add_argument("--spp", type=int, default=64)
    ap.add_argument("--repeats", type=int, default=2)
    ap.add_argument("--quick", action="store_true", help="a tiny smoke run")
    args = ap.parse_args(argv)
    if args.quick:
        args.resolution, args.spp, args.repeats = (32, 24), 4, 1
    path = Path(args.scene)
    if not path.is_file():
        path = bundled_scenes() / f"{args.scene}.toml"
    scene = load_scene(path)
    w, h = args.resolution
    scene.settings.width, scene.settings.height = w, h
    scene.camera = dataclasses.replace(scene.camera, width=w, height=h)
    npix, spp = w * h, args.spp
    plan = PassPlan.of(scene.settings, npix, spp)
    print(f"{path.stem} at {w}x{h}, {spp} spp: {npix * spp / 1e6:.2f} M samples in "
          f"{plan.chunk_count} chunks of {CHUNK} samples ({plan.per_pass} spp per pass); "
          f"{os.cpu_count()} cores")

    t0 = time.perf_counter()
    geo = scene.build()
    dice_s = time.perf_counter() - t0
    integ = Integrator(scene, geo)
    integ.render(spp=1, progress=False)  # compile (cached) and warm up
    rates = {}
    print("\nsamples/s (largest difference from the in-process image; efficiency against "
          "in-process with as many threads)")
    for threads in (1, 2):
        _, film = best(lambda t=threads: integ.render(spp=spp, progress=False, threads=t),
                       args.repeats)
        rates[threads] = film.stats["samples_per_s"]
        print(f"  in-process, {threads} thread(s)    {rates[threads] / 1e6:7.3f} M/s")
    ref = film.rgb()
    for workers, threads in ((1, 1), (1, 2), (2, 1)):
        with cluster(workers=workers, threads_per_worker=threads) as client:
            film = cluster_film(client, scene, spp, args.repeats)
            diff = float(np.max(np.abs(film.rgb() - ref)))
            st = film.stats
            r = st["samples_per_s"]
            rates[(workers, threads)] = r
            print(f"  cluster {workers} x {threads} thread(s) {r / 1e6:7.3f} M/s  "
                  f"(difference {diff:g}; efficiency {r / rates[min(2, workers * threads)]:.0%})")
            if (workers, threads) != (2, 1):
                continue
            rows = min(-(-CHUNK // plan.per_pass), npix)
            c = chunk_costs(client, st, rows, args.quick, args.repeats)
            print(f"\nper chunk ({CHUNK} samples; a patch of {rows} pixels, "
                  f"{c['patch_bytes'] / 1e3:.0f} kB), 2 workers:")
            print(f"  render on a worker          {c['render_s'] * 1e3:8.2f} ms")
            print(f"  scheduling, one task        {c['latency_s'] * 1e3:8.2f} ms (round trip)")
            print(f"  scheduling, many tasks      {c['task_s'] * 1e3:8.2f} ms per task")
            print(f"  transfer of a patch         {c['transfer_s'] * 1e3:8.2f} ms "
                  f"({c['transfer_bytes'] / 1e3:.0f} kB)")
            print(f"  merge on the client         {c['merge_s'] * 1e3:8.2f} ms")
            gbytes, t_geo = shipping(client, geo, args.repeats)
            print("\nthe scene to the workers (pwc render dices on each worker):")
            print(f"  pickled scene               {st['scene_bytes'] / 1e6:8.2f} MB")
            print(f"  ship and build, 2 workers   {st['prepare_s']:8.2f} s "
                  f"(the build alone {st['build_s']:.2f} s)")
            print(f"  dice and BVH on the client  {dice_s:8.2f} s ({geo.triangle_count} "
                  "triangles)")
            print(f"  diced geometry instead      {gbytes / 1e6:8.2f} MB, {t_geo:.3f} s to one "
                  "worker")
            print("\nchunk size, 2 workers:")
            sizes = (4096, CHUNK) if args.quick else (4096, 16384, CHUNK, 4 * CHUNK)
            chunk_sizes(client, scene, integ, spp, args.repeats, sizes, rates[2])
    print("\nprojection (docs/distributed.md): W workers as fast as one worker here")
    projection(rates[(1, 1)], c, st["scene_bytes"], st["build_s"])
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
