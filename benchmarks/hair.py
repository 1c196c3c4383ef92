"""Benchmark: hair strands — Embree's round curves at thin radii, the split that fixes them,
and what hair costs a render, on one machine in one run.

Run ``python benchmarks/hair.py`` (``--quick`` for a tiny smoke run).

* **precision**: a straight round curve (linear and Bézier) of radius ``r`` and length 1,
  rays shot straight at it at offsets 0 to 30 r from its axis: the largest offset Embree
  still reports a hit at ("reach", in radii; exact is 1) and the rays within 0.99 r it
  misses, for r / length from 1e-2 to 1e-5, as given to Embree and after
  :func:`render.hair.Strands.world` splits segments longer than
  :data:`render.hair.MAX_SEGMENT_RADII` radii; with the rays per second of each;
* **render**: CPU time per sample of the page's fringe scene
  (``gallery/dfs/scenes/df_chiang_hair_bsdf.toml``), with and without its fringes, and
  with shadow rays traced by occlusion instead of intersection (wrong for hair: they
  would not pass a fibre's wall from inside; the cost of doing it right).  Best of
  ``--repeats`` runs, alternating.
"""

from __future__ import annotations

import argparse
import dataclasses
import sys
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from render import embree  # noqa: E402
from render.hair import MAX_SEGMENT_RADII, Strands  # noqa: E402


def precision(kind: str, r: float, split: bool, n: int, rng) -> tuple[float, int, float]:
    """(reach in radii, misses within 0.99 r, rays per second) of a unit-length strand."""
    a, b = np.array([-0.5, 0.3, 0.0]), np.array([0.5, 0.3, 0.0])
    s = (Strands.polylines([[a, b]], radius=r) if kind == "linear" else
         Strands.bezier([[a, a + (b - a) / 3, a + 2 * (b - a) / 3, b]], radius=r))
    if split:
        p, segs, _ = s.world(np.eye(4))
    else:
        p, segs = s.points, s.segments
    off = np.linspace(0.0, 30 * r, n)
    o = np.column_stack([rng.uniform(-0.45, 0.45, n), 0.3 + off, np.full(n, 2.0)])
    d = np.tile([0.0, 0.0, -1.0], (n, 1))
    with embree.EmbreeScene([embree.Curves(p, segs, kind)]) as scene:
        scene.intersect(o[:8], d[:8])  # build
        t0 = time.perf_counter()
        h = scene.intersect(o, d)
        dt = time.perf_counter() - t0
    hit = h.geom_id >= 0
    reach = float(off[hit].max() / r) if hit.any() else 0.0
    return reach, int((~hit & (off < 0.99 * r)).sum()), n / dt


def render_costs(spp: int, repeats: int, resolution) -> dict:
    from render import path as kern
    from render.integrator import Integrator
    from render.scene import load_scene

    scene = load_scene(ROOT / "gallery/dfs/scenes/df_chiang_hair_bsdf.toml",
                       {"render": {"resolution": list(resolution)}})
    bare = dataclasses.replace(scene, objects=[o for o in scene.objects
                                               if not o.name.startswith("fringe")])
    runs = {"fringes": Integrator(scene, scene.build()),
            "no fringes": Integrator(bare, bare.build())}
    occluded = Integrator(scene, scene.build())
    occluded.tables.scalars[kern.SC_PASS] = 0.0
    runs["fringes, shadow rays by occlusion (wrong)"] = occluded
    best = dict.fromkeys(runs, np.inf)
    for rep in range(repeats):
        for name, integ in runs.items():
            t0 = time.process_time()
            film = integ.render(spp=spp, seed=rep, progress=False)
            ns = (time.process_time() - t0) / (film.width * film.height * spp) * 1e9
            best[name] = min(best[name], ns)
    return best


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--quick", action="store_true", help="tiny sizes (a smoke run)")
    ap.add_argument("--rays", type=int, default=20000)
    ap.add_argument("--spp", type=int, default=16)
    ap.add_argument("--repeats", type=int, default=3)
    args = ap.parse_args(argv)
    rays, spp, repeats, res = args.rays, args.spp, args.repeats, (384, 144)
    if args.quick:
        rays, spp, repeats, res = 600, 1, 1, (48, 18)
    rng = np.random.default_rng(0)
    print(f"Embree's round curves, radius r on a segment of length 1 (split: segments of at "
          f"most {MAX_SEGMENT_RADII:g} radii); reach in radii (exact: 1), misses within "
          f"0.99 r, of {rays} rays")
    print("| curve | r / length | reach | misses | Mrays/s | reach split | misses split | "
          "Mrays/s split |")
    print("|---|---|---|---|---|---|---|---|")
    for kind in ("linear", "bezier"):
        for r in (1e-2, 1e-3, 1e-4, 1e-5):
            a = precision(kind, r, False, rays, rng)
            b = precision(kind, r, True, rays, rng)
            print(f"| {kind} | {r:g} | {a[0]:.2f} | {a[1]} | {a[2] / 1e6:.2f} | {b[0]:.2f} | "
                  f"{b[1]} | {b[2] / 1e6:.2f} |")
    print(f"\nThe fringe scene, {res[0]} x {res[1]}, {spp} spp, CPU ns per sample (best of "
          f"{repeats}):")
    for name, ns in render_costs(spp, repeats, res).items():
        print(f"  {name}: {ns:.0f}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
