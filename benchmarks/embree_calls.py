"""Benchmark: the ways of calling Embree, in rays per second, on one machine in one run.

Run ``python benchmarks/embree_calls.py`` (``--quick`` for a tiny smoke run).  The scene
is a trimesh icosphere (``--subdivisions``, 327,680 triangles at 7) resting on a ground
quad, a second mesh.  Three kinds of rays, all float32:

* **camera**: a pinhole camera's rays (``--size`` pixels square) ordered by 4 x 2 pixel
  tiles, so the 8 rays of a packet are neighbours (coherent);
* **shadow**: from every camera hit (offset along the normal) to random points of a
  small square light (side 0.1 at distance ~5), occlusion queries (coherent directions,
  scattered origins);
* **bounce**: from the same points in random directions of the hemisphere (incoherent).

Each is traced by embreex's ``EmbreeScene.run`` (one Python call per batch, one thread),
by :func:`render.embree.intersect_rays` / ``occluded_rays`` (``rtcIntersect1`` /
``rtcOccluded1`` from numba) on 1 and 2 threads, and by ``intersect_packets`` /
``occluded_packets`` (``rtcIntersect8`` / ``rtcOccluded8``).  It also prints the BVH
build time of every build quality, with and without ``RTC_SCENE_FLAG_ROBUST``, and the
rays that slip through a closed sphere when aimed exactly at its vertices and edges.
Every figure is the best of ``--repeats`` runs (the machine may be shared), and the
machine's SIMD flags (``lscpu``) are printed first: Embree picks its code path by them.
"""

from __future__ import annotations

import argparse
import subprocess
import sys
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

import numba  # noqa: E402
import trimesh  # noqa: E402
from embreex import rtcore_scene  # noqa: E402
from embreex.mesh_construction import TriangleMesh  # noqa: E402

from render import embree  # noqa: E402


def simd_flags() -> str:
    """The SIMD flags Embree cares about, from ``lscpu``."""
    try:
        out = subprocess.run(["lscpu"], capture_output=True, text=True, check=True).stdout
    except (OSError, subprocess.CalledProcessError):
        return "unknown (lscpu failed)"
    flags = set()
    for line in out.splitlines():
        if line.startswith("Flags:"):
            flags = set(line.split()[1:])
    model = next((line.split(":", 1)[1].strip() for line in out.splitlines()
                  if line.startswith("Model name:")), "?")
    have = [f for f in ("sse4_2", "avx", "avx2", "avx512f") if f in flags]
    return f"{model}; {' '.join(have) or 'no avx'}; avx512f {'yes' if 'avx512f' in flags else 'no'}"


def scene_meshes(subdivisions: int):
    m = trimesh.creation.icosphere(subdivisions=subdivisions)
    sphere = (np.asarray(m.vertices, np.float32), np.asarray(m.faces, np.uint32))
    ground = (np.float32([[-5, -1, -5], [5, -1, -5], [5, -1, 5], [-5, -1, 5]]),
              np.uint32([[0, 2, 1], [0, 3, 2]]))
    return [sphere, ground]


def unit(v):
    return (v / np.linalg.norm(v, axis=1, keepdims=True)).astype(np.float32)


def rays(scene, size: int, rng):
    """Camera rays in 4 x 2 tiles; shadow and bounce rays from their hits."""
    ys, xs = np.mgrid[0:size, 0:size]
    order = np.lexsort(((xs % 4 + 4 * (ys % 2)).ravel(), (xs // 4).ravel(), (ys // 2).ravel()))
    px, py = xs.ravel()[order] + 0.5, ys.ravel()[order] + 0.5
    cam_d = unit(np.stack([(px / size - 0.5) * 1.2, (0.5 - py / size) * 1.2 - 0.3,
                           -np.ones(len(px))], axis=1))
    cam_o = np.tile(np.float32([0.0, 0.5, 3.5]), (len(cam_d), 1))
    h = scene.intersect(cam_o, cam_d)
    hit = h.geom_id >= 0
    n = unit(h.ng[hit])
    p = (cam_o[hit] + h.t[hit, None] * cam_d[hit] + 1e-4 * n).astype(np.float32)
    light = np.float32([2.0, 3.0, 3.0]) + rng.uniform(-0.05, 0.05, (len(p), 3)) * [1, 0, 1]
    shadow_d = (light - p).astype(np.float32)
    bounce_d = unit(rng.normal(size=(len(p), 3)))
    bounce_d = np.where((np.einsum("ij,ij->i", bounce_d, n) < 0)[:, None], -bounce_d, bounce_d)
    return {"camera": (cam_o, cam_d, np.inf),
            "shadow": (p, shadow_d, 0.999),
            "bounce": (p, np.ascontiguousarray(bounce_d, np.float32), np.inf)}


def best_rate(fn, n: int, repeats: int) -> float:
    """Rays per second (millions), the best of ``repeats`` timed calls after a warm-up."""
    fn()
    best = np.inf
    for _ in range(repeats):
        t0 = time.perf_counter()
        fn()
        best = min(best, time.perf_counter() - t0)
    return n / best / 1e6


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--subdivisions", type=int, default=7)
    ap.add_argument("--size", type=int, default=1024, help="camera pixels per side")
    ap.add_argument("--repeats", type=int, default=5)
    ap.add_argument("--quick", action="store_true", help="tiny sizes (a smoke run)")
    args = ap.parse_args(argv)
    if args.quick:
        args.subdivisions, args.size, args.repeats = 3, 64, 1

    print(f"SIMD: {simd_flags()}; numba threads available: {numba.config.NUMBA_NUM_THREADS}")
    meshes = scene_meshes(args.subdivisions)
    ntri = sum(len(f) for _, f in meshes)
    print(f"scene: icosphere {len(meshes[0][1])} triangles + ground quad ({ntri} in all)")

    scene = embree.EmbreeScene(meshes)  # the defaults: quality high, robust
    all_rays = rays(scene, args.size, np.random.default_rng(1))
    bo, bd, _ = all_rays["bounce"]
    blo, bhi = np.zeros(len(bo), np.float32), np.full(len(bo), np.inf, np.float32)

    print("\nBuild quality and robust mode: BVH build, bounce rays (rtcIntersect1, 1 thread),"
          "\nand rays slipping through the closed sphere aimed exactly at its vertices and edge"
          " midpoints:")
    closed = trimesh.creation.icosphere(subdivisions=min(args.subdivisions, 5))
    v = np.asarray(closed.vertices, np.float32)
    e = closed.edges_unique
    aim = np.concatenate([v, (v[e[:, 0]] + v[e[:, 1]]) / 2]).astype(np.float32)
    numba.set_num_threads(1)
    for robust in (False, True):
        for quality in ("low", "medium", "high"):
            t0 = time.perf_counter()
            s = embree.EmbreeScene(meshes, quality=quality, robust=robust)
            build = (time.perf_counter() - t0) * 1e3
            rate = best_rate(lambda s=s: embree.intersect_rays(s.handle, bo, bd, blo, bhi),
                             len(bo), args.repeats)
            s.close()
            with embree.EmbreeScene([(v, closed.faces)], quality=quality, robust=robust) as c:
                leaks = int((c.intersect(np.zeros_like(aim), aim).geom_id < 0).sum())
            print(f"  robust={robust!s:5}  {quality:6}  build {build:7.1f} ms  bounce "
                  f"{rate:5.2f} M rays/s  slipped {leaks} of {len(aim)}")
    numba.set_num_threads(numba.config.NUMBA_NUM_THREADS)

    ref = rtcore_scene.EmbreeScene()
    for vv, ff in meshes:
        TriangleMesh(ref, vv, ff.astype(np.int32))

    print("\nM rays/s (best of %d)" % args.repeats)
    print(f"{'rays':8} {'n':>9} {'embreex run':>12} {'rtc*1 x1':>9} {'rtc*1 x2':>9} "
          f"{'rtc*8 x1':>9} {'rtc*8 x2':>9}")
    for kind, (o, d, tfar) in all_rays.items():
        n = len(o)
        lo = np.zeros(n, np.float32)
        hi = np.full(n, tfar, np.float32)
        if kind == "shadow":
            single, packets = embree.occluded_rays, embree.occluded_packets
            ex = lambda o=o, d=d, hi=hi: ref.run(o, d, dists=hi.copy(), query="OCCLUDED")  # noqa: E731
        else:
            single, packets = embree.intersect_rays, embree.intersect_packets
            ex = lambda o=o, d=d: ref.run(o, d, output=1)  # noqa: E731
        row = [best_rate(ex, n, args.repeats)]
        for fn in (single, packets):
            for threads in (1, 2):
                numba.set_num_threads(min(threads, numba.config.NUMBA_NUM_THREADS))
                row.append(best_rate(lambda fn=fn, o=o, d=d, lo=lo, hi=hi:
                                     fn(scene.handle, o, d, lo, hi), n, args.repeats))
        numba.set_num_threads(numba.config.NUMBA_NUM_THREADS)
        print(f"{kind:8} {n:9d} " + " ".join(f"{r:9.2f}" for r in row[:1]) + "   "
              + " ".join(f"{r:9.2f}" for r in row[1:]))
    scene.close()
    return 0


if __name__ == "__main__":
    sys.exit(main())
