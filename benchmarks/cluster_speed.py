"""Benchmark: rendering on a local Dask cluster against in-process, and what a chunk costs.

Run ``python benchmarks/cluster_speed.py [--scene NAME] [--resolution W H] [--spp N]``
(``--quick`` for a tiny smoke run).  On this machine it prints:

* **samples/s** in-process (1 and 2 threads) and on local clusters of processes
  (1 worker x 1 thread, 1 x 2, 2 x 1), each next to its largest difference from the
  in-process image (0: the same bits) and its efficiency against in-process with as
  many threads;
* **per chunk** (2 workers): its render time on a worker, the scheduling cost of a
  task (no-op tasks, one at a time and many at once), the transfer of a chunk's patch
  from a worker to the client, and the client's merge;
* **chunk size**: samples/s on 2 workers for chunks of 4096 to 262144 samples;
* **dicing on each worker or on the client** (``--dice-scene``, a displaced scene at
  print size): the pickled scene, the build on the workers, against dicing on the
  client and shipping the diced geometry (its bytes and its transfer to one worker);
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
from render.passes import CHUNK, PassPlan, render_chunk  # noqa: E402
from render.scene import load_scene  # noqa: E402

#: networks of the projection, bytes/s: 1 and 10 Gb/s
NETWORKS = {"1 Gb/s": 125e6, "10 Gb/s": 1.25e9}


def best(f, repeats: int):
    """(smallest seconds, last result) of ``repeats`` calls of ``f``."""
    times, out = [], None
    for _ in range(repeats):
        t0 = time.perf_counter()
        out = f()
        times.append(time.perf_counter() - t0)
    return min(times), out


def sized_scene(name: str, w: int, h: int):
    """A gallery scene (or scene file) at ``w`` x ``h``."""
    path = Path(name)
    if not path.is_file():
        path = bundled_scenes() / f"{name}.toml"
    scene = load_scene(path)
    scene.settings.width, scene.settings.height = w, h
    scene.camera = dataclasses.replace(scene.camera, width=w, height=h)
    return path.stem, scene


def _noop(i):
    return i


def _patch_of(rows: int):
    """A patch of ``rows`` pixels, as a chunk sends it (made on the worker)."""
    rng = np.random.default_rng(rows)
    return FilmPatch(0, rng.random((rows, 3)), rng.random(rows), np.ones(rows, np.int64))


def cluster_film(client, scene, spp: int, repeats: int, chunk=None):
    """The best of ``repeats`` renders on the cluster, after one that loads the kernels."""
    render_on_cluster(scene, client, spp=1, progress=False)
    return best(lambda: render_on_cluster(scene, client, spp=spp, progress=False,
                                          chunk=chunk), repeats)[1]


def chunk_costs(client, st: dict, samples: int, rows: int, quick: bool, repeats: int) -> dict:
    """Per chunk: render on a worker, scheduling (serial round trip and throughput of
    no-op tasks), the transfer of a patch beyond a no-op, and the client's merge."""
    chunks = sum(v["chunks"] for v in st["workers"].values())
    n = 40 if quick else 400
    t0 = time.perf_counter()
    for i in range(n // 10):
        client.submit(_noop, i, pure=False).result()
    latency = (time.perf_counter() - t0) / (n // 10)
    t0 = time.perf_counter()
    client.gather([client.submit(_noop, i, pure=False) for i in range(n)])
    per_task = (time.perf_counter() - t0) / n
    reps = max(3, 3 * repeats)
    t_fetch = best(lambda: client.submit(_patch_of, rows, pure=False).result(), reps)[0]
    t_noop = best(lambda: client.submit(_noop, 0, pure=False).result(), reps)[0]
    render_s = sum(v["trace_s"] for v in st["workers"].values()) / chunks
    return {
        "render_s": render_s,
        # one worker thread's own pace, without the cluster's costs
        "rate1": samples / chunks / render_s,
        "latency_s": latency,
        "task_s": per_task,
        "transfer_s": max(t_fetch - t_noop, 0.0),
        "transfer_bytes": _patch_of(rows).nbytes,
        "patch_bytes": st["patch_bytes"] / chunks,
        "merge_s": st["merge_s"] / chunks,
    }


def chunk_sizes(client, scene, integ, spp: int, repeats: int, sizes, rate2: float) -> None:
    """samples/s on the cluster for other chunk sizes, each against the in-process image
    of the same chunks (other sizes draw other random streams)."""
    for size in sizes:
        film = cluster_film(client, scene, spp, repeats, chunk=size)
        plan = PassPlan.of(scene.settings, film.pixel_count, spp, chunk=size)
        own = Film(film.width, film.height)
        for k in range(plan.passes):
            for item in plan.chunks(k):
                own.merge(render_chunk(integ, plan.seed, item))
        diff = float(np.max(np.abs(film.rgb() - own.rgb())))
        r = film.stats["samples_per_s"]
        print(f"  {size:>7} samples per chunk   {r / 1e6:7.3f} M/s  (difference {diff:g}; "
              f"efficiency {r / rate2:.0%})")


def dicing(client, name: str, scene, repeats: int) -> dict:
    """Dicing on each worker (what render_on_cluster does) against dicing on the client
    and shipping the geometry; returns the figures for the projection."""
    t_client, geo = best(scene.build, repeats)
    names = ("vertices", "normals", "tangent_u", "tangent_v", "uv", "faces", "face_object",
             "face_normal", "face_offset")
    arrays = {n: getattr(geo, n) for n in names}
    geo_bytes = len(pickle.dumps(arrays, protocol=5))
    address = next(iter(client.nthreads()))
    t_geo = best(lambda: client.cancel(client.scatter(arrays, workers=[address], hash=False)),
                 max(2, repeats))[0]
    st = render_on_cluster(scene, client, spp=1, progress=False).stats
    w, h = scene.camera.width, scene.camera.height
    print(f"\ndicing: {name} at {w}x{h}, {geo.triangle_count} triangles")
    print(f"  pickled scene, to each worker   {st['scene_bytes'] / 1e3:9.1f} kB")
    print(f"  ship and build on 2 workers     {st['prepare_s']:9.2f} s (the build "
          f"{st['build_s']:.2f} s: unpickle, dice and BVH, integrator)")
    print(f"  dice and BVH on each worker     {st['geometry_s']:9.2f} s (2 at once on 2 cores)")
    print(f"  dice and BVH on the client      {t_client:9.2f} s")
    print(f"  the diced geometry instead      {geo_bytes / 1e6:9.2f} MB per worker, "
          f"{t_geo:.3f} s to one worker here")
    for workers in (2, 10, 100):
        cells = []
        for net, bw in NETWORKS.items():
            cells.append(f"{net}: on the client {t_client + workers * geo_bytes / bw:6.2f} s, "
                         f"on each {t_client + workers * st['scene_bytes'] / bw:5.2f} s")
        print(f"  {workers:>3} workers, diced geometry on every worker: " + "; ".join(cells))
    return {"scene_bytes": st["scene_bytes"], "build_s": st["build_s"], "geo_bytes": geo_bytes}


def projection(rate1: float, c: dict, per_pass: int, dice: dict) -> None:
    """Efficiency of W workers, each tracing ``rate1`` samples/s (a worker here): the
    scheduler and client pay ``serial`` seconds per task whatever its size, and receive
    the patches (bytes per sample: 40 / spp per pass, without AOVs)."""
    serial = c["task_s"] + c["transfer_s"] + c["merge_s"]
    print(f"  one worker thread traces {rate1 / 1e6:.3f} M samples/s; the scheduler and the "
          f"client spend {serial * 1e3:.2f} ms per task")
    for workers in (10, 100):
        for size in (CHUNK, 4 * CHUNK, 16 * CHUNK):
            t_c = size / rate1
            sched = min(1.0, t_c / (workers * serial))
            print(f"  {workers:>3} workers, {size:>7}-sample chunks ({t_c * 1e3:5.0f} ms): "
                  f"the scheduler keeps {sched:4.0%} of them busy")
        for k_spp in (1, per_pass):
            inflow = workers * rate1 * 40.0 / k_spp
            cells = [f"{min(1.0, bw / inflow):4.0%} on {net}" for net, bw in NETWORKS.items()]
            print(f"  {workers:>3} workers, {k_spp:>3} spp per pass: results "
                  f"{inflow / 1e6:7.1f} MB/s into the client: " + ", ".join(cells))
    need = 100 * serial * rate1 / 0.9
    print(f"  chunks for 90% on 100 workers: >= {need:,.0f} samples "
          f"(>= {-(-need // CHUNK):.0f} x {CHUNK})")


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
    plan = PassPlan.of(scene.settings, npix, spp)
    print(f"{name} at {scene.camera.width}x{scene.camera.height}, {spp} spp: "
          f"{npix * spp / 1e6:.2f} M samples in {plan.chunk_count} chunks of {CHUNK} samples "
          f"({plan.per_pass} spp per pass); {os.cpu_count()} cores, load average "
          f"{os.getloadavg()[0]:.1f}")

    integ = Integrator(scene, scene.build())
    integ.render(spp=1, progress=False)  # compile (cached) and warm up
    rates = {}
    print("\nsamples/s (largest difference from the in-process image; efficiency against "
          "in-process with as many threads)")
    for threads in (1, 2):
        _, film = best(lambda t=threads: integ.render(spp=spp, progress=False, threads=t),
                       args.repeats)
        rates[threads] = film.stats["samples_per_s"]
        print(f"  in-process, {threads} thread(s)      {rates[threads] / 1e6:7.3f} M/s")
    ref = film.rgb()
    for workers, threads in ((1, 1), (1, 2), (2, 1)):
        with cluster(workers=workers, threads_per_worker=threads) as client:
            film = cluster_film(client, scene, spp, args.repeats)
            st = film.stats
            r = rates[(workers, threads)] = st["samples_per_s"]
            diff = float(np.max(np.abs(film.rgb() - ref)))
            print(f"  cluster, {workers} x {threads} thread(s)  {r / 1e6:7.3f} M/s  "
                  f"(difference {diff:g}; efficiency {r / rates[min(2, workers * threads)]:.0%})")
            if (workers, threads) != (2, 1):
                continue
            rows = min(-(-CHUNK // plan.per_pass), npix)
            c = chunk_costs(client, st, npix * spp, rows, args.quick, args.repeats)
            print(f"\nper chunk ({CHUNK} samples, a patch of {rows} pixels, "
                  f"{c['patch_bytes'] / 1e3:.0f} kB), 2 workers:")
            print(f"  render on a worker            {c['render_s'] * 1e3:8.2f} ms")
            print(f"  scheduling, one task          {c['latency_s'] * 1e3:8.2f} ms (round trip)")
            print(f"  scheduling, many tasks        {c['task_s'] * 1e3:8.2f} ms per task")
            print(f"  transfer of a patch           {c['transfer_s'] * 1e3:8.2f} ms "
                  f"({c['transfer_bytes'] / 1e3:.0f} kB, beyond a no-op task)")
            print(f"  merge on the client           {c['merge_s'] * 1e3:8.2f} ms")
            print("\nchunk size, 2 workers:")
            sizes = (4096, CHUNK) if args.quick else (4096, 16384, CHUNK, 4 * CHUNK)
            chunk_sizes(client, scene, integ, spp, args.repeats, sizes, rates[2])
            dice = dicing(client, *sized_scene(args.dice_scene, *args.dice_resolution),
                          args.repeats)
    print("\nprojection (docs/distributed.md): W workers, each as fast as a worker here")
    projection(c["rate1"], c, plan.per_pass, dice)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
