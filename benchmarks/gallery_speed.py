"""Benchmark: samples per second of every gallery scene, for this tree and another.

Run ``python benchmarks/gallery_speed.py [--other PATH] [--spp N] [--threads N]
[--markdown] [--scenes NAME ...]``.  Each scene is rendered (after a warm-up render that
compiles and builds) by this checkout's ``render`` and, with ``--other``, by the ``render`` of another
checkout (for example an earlier commit in a ``git worktree``), alternately scene by
scene in fresh processes, so load on the machine hits both alike.  Prints samples/s, how
each was rendered (objects shaded per hit in numpy are named), and the ratio.  With
``--threads 1`` the rate is per second of the process's CPU time, which other work on a
shared machine hardly moves.  ``--quick`` renders three scenes at 1 spp.
"""

from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]

_CHILD = r"""
import json, sys, time
from render.integrator import Integrator
from render.scene import load_scene
scene = load_scene(sys.argv[1]); spp = int(sys.argv[2]); threads = int(sys.argv[3])
geo = scene.build(); integ = Integrator(scene, geo)
integ.render(spp=1, progress=False, threads=threads)  # compile (cached) and warm up
cpu = time.process_time()
film = integ.render(spp=spp, progress=False, threads=threads)
cpu = time.process_time() - cpu
st = film.stats  # "path": trees before the one core; "bound_objects": after it
rate = st["samples_per_s"] if threads > 1 else st["samples_per_s"] * st["time_s"] / cpu
bound = st.get("bound_objects") or []
how = st.get("path") or ("core, numpy-shaded: " + ", ".join(bound) if bound else "core")
print(json.dumps({"rate": rate, "path": how}))
"""


def measure(tree: Path, scene: Path, spp: int, threads: int) -> dict:
    env = dict(os.environ, PYTHONPATH=str(tree))
    out = subprocess.run([sys.executable, "-c", _CHILD, str(scene), str(spp), str(threads)],
                         cwd=tree,
                         env=env, capture_output=True, text=True, timeout=1800)
    if out.returncode:
        return {"rate": float("nan"), "path": "error: " + out.stderr.strip().splitlines()[-1]}
    return json.loads(out.stdout.strip().splitlines()[-1])


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--other", type=Path, help="another checkout to compare with")
    ap.add_argument("--spp", type=int, default=16)
    ap.add_argument("--threads", type=int, default=2,
                    help="render threads (1: samples per second of CPU time)")
    ap.add_argument("--quick", action="store_true")
    ap.add_argument("--markdown", action="store_true")
    ap.add_argument("--scenes", nargs="+", metavar="NAME",
                    help="only these gallery scenes (file names without .toml)")
    args = ap.parse_args(argv)
    scenes = sorted((ROOT / "gallery" / "scenes").glob("*.toml"))
    if args.scenes:
        missing = sorted(set(args.scenes) - {s.stem for s in scenes})
        if missing:
            ap.error(f"no gallery scene {', '.join(missing)} (see gallery/scenes/)")
        scenes = [s for s in scenes if s.stem in args.scenes]
    if args.quick:
        scenes, args.spp = scenes[:3], 1
    rows = []
    for s in scenes:
        new = measure(ROOT, s, args.spp, args.threads)
        old = measure(args.other, s, args.spp, args.threads) if args.other else None
        rows.append((s.stem, new, old))
        ratio = new["rate"] / old["rate"] if old else float("nan")
        if not args.markdown:
            print(f"{s.stem}: {new['rate'] / 1e6:.3f} M/s ({new['path']})"
                  + (f", other {old['rate'] / 1e6:.3f} M/s ({old['path']}), x{ratio:.2f}"
                     if old else ""), flush=True)
    if args.markdown:
        print("| scene | before: Msamples/s (path) | after: Msamples/s (path) | after / before |")
        print("|---|---|---|---|")
        for name, new, old in rows:
            b = f"{old['rate'] / 1e6:.3f} ({old['path']})" if old else ""
            r = f"{new['rate'] / old['rate']:.2f}" if old else ""
            print(f"| {name} | {b} | {new['rate'] / 1e6:.3f} ({new['path']}) | {r} |")
    return 0


if __name__ == "__main__":
    sys.exit(main())
