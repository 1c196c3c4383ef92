"""Benchmark: a cached start, for this tree and another.

Run ``python benchmarks/start_up.py [--other PATH] [--runs N]``.  With the kernels
already compiled (a warm-up run of each tree first), it times ``pwc render fig_14_28`` at
64 x 48 and 1 spp (the README's scene) from process start to its first sample and to
its end, and the same start from Python, step by step in one process: imports, the
scene file with its MDL check, building the objects, the integrator with its cached
kernels, the first image.  With ``--other`` (for example an earlier commit in a ``git
worktree``) the two trees run alternately, so load on the machine hits both alike, and
the ratio is printed.  Both run with bytecode caching on, as an installed package does.
The image's mean tells that each rendered the same scene.  ``--quick``: one run each.
"""

from __future__ import annotations

import argparse
import json
import os
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]

# the command as the console script runs it (pwc.cli.entry), noting when it starts
# tracing; the collector set up before the renderer's import, as entry does it first
_COMMAND = r"""
import sys, time
from pwc import cli
getattr(cli, "space_out_full_collections", lambda: None)()
from render import integrator
render = integrator.Integrator.render


def first_sample(self, *args, **kwargs):
    print("first sample at", time.time(), file=sys.stderr, flush=True)
    return render(self, *args, **kwargs)


integrator.Integrator.render = first_sample
sys.argv = ["pwc", "render", "fig_14_28", "-o", sys.argv[1], "--resolution", "64", "48",
            "--spp", "1", "--quiet"]
sys.exit(getattr(cli, "entry", cli.main)())
"""

_STEPS = r"""
import json, time
try:  # as the pwc command's process
    from pwc.cli import space_out_full_collections
    space_out_full_collections()
except ImportError:  # a tree from before it
    pass
t = [time.perf_counter()]
from render.precompile import compiled_integrator
from render.scene import load_scene
from render.library.resources import bundled_scenes
t.append(time.perf_counter())
scene = load_scene(bundled_scenes() / "fig_14_28.toml")
scene.settings.width, scene.settings.height = 64, 48
import dataclasses
scene.camera = dataclasses.replace(scene.camera, width=64, height=48)
t.append(time.perf_counter())
geo = scene.build()
t.append(time.perf_counter())
integ = compiled_integrator(scene, geo)
t.append(time.perf_counter())
film = integ.render(spp=1, progress=False)
t.append(time.perf_counter())
steps = ["imports", "scene file", "objects", "integrator", "first image"]
print(json.dumps({**{s: b - a for s, a, b in zip(steps, t, t[1:])},
                  "mean": float(film.rgb().mean())}))
"""

STEPS = ["imports", "scene file", "objects", "integrator", "first image"]


def _env(tree: Path) -> dict:
    env = dict(os.environ, PYTHONPATH=str(tree))
    env.pop("PYTHONDONTWRITEBYTECODE", None)  # as an installed package: bytecode cached
    return env


def command_time(tree: Path, out: Path) -> tuple[float, float]:
    """Wall seconds of ``pwc render fig_14_28`` (64 x 48, 1 spp) from process start to its
    first sample and to its end (the clock read by both processes)."""
    start, t = time.time(), time.perf_counter()
    r = subprocess.run([sys.executable, "-c", _COMMAND, str(out)], cwd=tree, env=_env(tree),
                       capture_output=True, text=True, timeout=1800)
    end = time.perf_counter() - t
    if r.returncode:
        raise SystemExit(f"{tree}: pwc render failed: {r.stderr.strip()}")
    first = float(r.stderr.split("first sample at")[1].split()[0])
    return first - start, end


def steps(tree: Path) -> dict:
    """The start from Python, step by step (seconds), and the image's mean."""
    r = subprocess.run([sys.executable, "-c", _STEPS], cwd=tree, env=_env(tree),
                       capture_output=True, text=True, timeout=1800)
    if r.returncode:
        raise SystemExit(f"{tree}: {r.stderr.strip()}")
    return json.loads(r.stdout.strip().splitlines()[-1])


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--other", type=Path, help="another checkout to compare with")
    ap.add_argument("--runs", type=int, default=5, help="alternated runs of each tree")
    ap.add_argument("--quick", action="store_true", help="one run each")
    args = ap.parse_args(argv)
    trees = {"this": ROOT} | ({"other": args.other.resolve()} if args.other else {})
    runs = 1 if args.quick else args.runs
    got = {k: {"command": [], "steps": []} for k in trees}
    with tempfile.TemporaryDirectory() as tmp:
        for name, tree in trees.items():  # compile, or load the cache, once
            command_time(tree, Path(tmp) / f"{name}.exr")
        for _ in range(runs):
            for name, tree in trees.items():
                got[name]["command"].append(command_time(tree, Path(tmp) / f"{name}.exr"))
                got[name]["steps"].append(steps(tree))
    print(f"cached start, median of {runs} (wall s; Python {sys.version.split()[0]}, "
          f"{os.cpu_count()} cpus)")
    print(f"{'':26}" + "".join(f"{k:>10}" for k in trees) + ("     ratio" if args.other else ""))
    rows = [(label, {k: statistics.median(c[i] for c in v["command"])
                     for k, v in got.items()})
            for i, label in enumerate(["pwc render: first sample", "pwc render: end"])]
    rows.append(("from Python", {k: statistics.median(sum(x[s] for s in STEPS)
                                                      for x in v["steps"])
                                 for k, v in got.items()}))
    for s in [*STEPS, "mean"]:
        rows.append((s, {k: statistics.median(x[s] for x in v["steps"])
                         for k, v in got.items()}))
    for label, vals in rows:
        line = f"{label:26}" + "".join(f"{vals[k]:10.3f}" for k in trees)
        if args.other and label != "mean" and vals["other"] > 0:
            line += f"{vals['this'] / vals['other']:10.2f}"
        print(line)
    return 0


if __name__ == "__main__":
    sys.exit(main())
