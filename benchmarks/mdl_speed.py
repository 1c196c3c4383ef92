"""Benchmark: MDL modules - compile time (first and cached) and render speed of a material
written in MDL against the same material built in.

Run ``python benchmarks/mdl_speed.py [--spp N] [--repeat R] [--quick]``.

* **Compile**: in a fresh process, the first ``material_from_call`` of a module (reading,
  parsing and checking it and the modules it imports -- ``::df``, ``::state``,
  ``::materials``... -- generating and compiling its Python, instantiating) and the same
  call again (the module is cached by content: only the instantiation is left); and
  ``pwc mdl check`` of ``::base`` as a command.
* **Render**: samples per second of two gallery scenes with the material written in an
  MDL module beside the scene, and as built in (the string form), alternately in fresh
  processes, ``--repeat`` times each (the best is kept: load on the machine only slows a
  run down).  The MDL and built-in materials make the same df program; what differs is
  who computes the varying arguments at each hit (generated lane code or the Python
  library), and for the moulding, the MDL displacement's dicing.  Same seed, so the
  images are compared too.

``--quick`` renders at 1 spp, once.
"""

from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys
import tempfile
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]

CHECKS = """\
// fig_09_12's checkerboard, written in MDL for this benchmark (the pattern of the
// workbench's checkerboard_pattern: squares interval / 2 wide, mirrored at 0)
mdl 1.6;
import ::df::*;
import ::state::*;
import ::math::*;

bool in_stripe(float f, float interval, float thickness)
{
    float position = math::abs(f);
    float lower = math::floor(position / interval) * interval;
    return position < lower + thickness / 2.0 || position > lower + interval - thickness / 2.0;
}

export material checks(color color_1 = color(0.0), color color_2 = color(1.0),
                       float interval = 0.2) = let {
    float3 p = state::texture_coordinate(0);
    bool a = in_stripe(p.x, interval, interval / 2.0);
    bool b = in_stripe(p.y, interval, interval / 2.0);
    color tint = a != b ? color_1 : color_2;
} in material(surface: material_surface(
    scattering: df::diffuse_reflection_bsdf(tint: tint)));
"""

MOULDINGS = """\
// ornament_2 swept along v, written in MDL (the closed loop's module)
mdl 1.6;
import ::df::*;
import ::state::*;
import ::pw_curve::*;
import ::ornament_2::*;
import ::materials::travertine;

float3 sweep(uniform pw_curve::pw_point[<N>] pwc)
{
    float v = state::texture_coordinate(0).y;
    float2 p = pw_curve::point_along_pwc(v, pwc);
    return p.x * state::normal() + (p.y - v) * state::texture_tangent_v(0);
}

export material stone_molding() = let {
    material stone = materials::travertine(1.0, ornament_2::ornament_2_length);
} in material(surface: stone.surface,
              geometry: material_geometry(displacement: sweep(ornament_2::ornament_2)));
"""

#: (name, gallery scene, built-in call, module file, module text, MDL call)
CASES = [
    ("checkerboard (fig_09_12)", "fig_09_12",
     "checkerboard(color_1: color(.3, .4, .5), color_2: color(.8, .7, .1))",
     "checks.mdl", CHECKS, "checks(color_1: color(.3, .4, .5), color_2: color(.8, .7, .1))"),
    ("moulding (fig_15_22)", "fig_15_22", "stone_ornament_2()",
     "mouldings.mdl", MOULDINGS, "stone_molding()"),
]

_COMPILE = r"""
import json, sys, time
t0 = time.perf_counter()
from render.mdlc import material_from_call
t1 = time.perf_counter()
material_from_call(sys.argv[2], sys.argv[1], base_dir=sys.argv[3])
t2 = time.perf_counter()
material_from_call(sys.argv[2], sys.argv[1], base_dir=sys.argv[3])
t3 = time.perf_counter()
print(json.dumps({"import": t1 - t0, "first": t2 - t1, "cached": t3 - t2}))
"""

_RENDER = r"""
import json, sys, time
import numpy as np
from render.integrator import Integrator
from render.scene import load_scene
scene = load_scene(sys.argv[1]); spp = int(sys.argv[2])
t0 = time.perf_counter()
geo = scene.build()
build = time.perf_counter() - t0
integ = Integrator(scene, geo)
integ.render(spp=1, progress=False)  # compile (cached) and warm up
film = integ.render(spp=spp, progress=False)
np.save(sys.argv[3], film.rgb())
print(json.dumps({"rate": film.stats["samples_per_s"], "build": build}))
"""


def _run(code: str, *args, cwd=ROOT) -> dict:
    env = dict(os.environ, PYTHONPATH=str(ROOT))
    out = subprocess.run([sys.executable, "-c", code, *map(str, args)], cwd=cwd, env=env,
                         capture_output=True, text=True, timeout=3600)
    if out.returncode:
        raise SystemExit(f"benchmark child failed:\n{out.stderr}")
    return json.loads(out.stdout.strip().splitlines()[-1])


def scene_with(folder: Path, scene: str, material_line: str) -> Path:
    text = (ROOT / "gallery" / "scenes" / f"{scene}.toml").read_text(encoding="utf-8")
    lines = text.split("\n")
    # the figure's object is the last one; its material is the scene's last material line
    idx = max(i for i, x in enumerate(lines) if x.startswith("material ="))
    end = idx
    if '"""' in lines[idx] and lines[idx].count('"""') == 1:
        while '"""' not in lines[end + 1]:
            end += 1
        end += 1
    lines[idx:end + 1] = [f"material = {material_line}"]
    out = folder / f"{scene}_{abs(hash(material_line)) % 10**8}.toml"
    out.write_text("\n".join(lines), encoding="utf-8")
    return out


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--spp", type=int, default=16)
    ap.add_argument("--repeat", type=int, default=3)
    ap.add_argument("--quick", action="store_true")
    args = ap.parse_args(argv)
    if args.quick:
        args.spp, args.repeat = 1, 1
    import numpy as np

    with tempfile.TemporaryDirectory() as tmp:
        d = Path(tmp)
        subprocess.run([sys.executable, "-m", "pwc", "compile", "ornament_2", "-o", f"{d}/"],
                       cwd=ROOT, env=dict(os.environ, PYTHONPATH=str(ROOT)), check=True,
                       capture_output=True)
        print("compile (fresh process; ms):")
        for _, _, _, file, text, call in CASES:
            (d / file).write_text(text, encoding="utf-8")
            c = _run(_COMPILE, file, call, d)
            print(f"  {file}: first {c['first'] * 1e3:.0f} ms (after importing the renderer, "
                  f"{c['import'] * 1e3:.0f} ms), cached {c['cached'] * 1e3:.1f} ms", flush=True)
        t = _run("import json, subprocess, sys, time\nt = time.perf_counter()\n"
                 "r = subprocess.run([sys.executable, '-m', 'pwc', 'mdl', 'check', '::base'"
                 "], capture_output=True)\n"
                 "print(json.dumps({'s': time.perf_counter() - t}))")
        print(f"  pwc mdl check ::base (the whole command): {t['s'] * 1e3:.0f} ms")
        print(f"render ({args.spp} spp, best of {args.repeat}; Msamples/s):")
        for name, scene, builtin, file, _, call in CASES:
            mdl_scene = scene_with(d, scene, f'{{ module = "{file}", call = "{call}" }}')
            built_scene = scene_with(d, scene, f'"""{builtin}"""')
            best = {"mdl": 0.0, "built-in": 0.0}
            builds = {"mdl": [], "built-in": []}
            for _ in range(args.repeat):
                for key, path in (("mdl", mdl_scene), ("built-in", built_scene)):
                    r = _run(_RENDER, path, args.spp, d / f"{key}.npy")
                    best[key] = max(best[key], r["rate"])
                    builds[key].append(r["build"])
            a, b = np.load(d / "mdl.npy"), np.load(d / "built-in.npy")
            print(f"  {name}: MDL {best['mdl'] / 1e6:.3f}, built-in "
                  f"{best['built-in'] / 1e6:.3f}, MDL / built-in "
                  f"{best['mdl'] / best['built-in']:.3f}; scene build (dicing) "
                  f"{min(builds['mdl']):.2f} s vs {min(builds['built-in']):.2f} s; same seed: "
                  f"mean |difference| {np.abs(a - b).mean():.2e} (image mean "
                  f"{b.mean():.3f})", flush=True)
    return 0


if __name__ == "__main__":
    sys.exit(main())
