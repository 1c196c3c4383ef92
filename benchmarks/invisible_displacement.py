"""Benchmark: what not dicing invisible displacement saves on the gallery.

Run ``python benchmarks/invisible_displacement.py`` (``--quick`` for one scene at one
size; ``--doc PATH`` writes the Markdown table into that page between its markers, by
default ``docs/trade.md`` unless ``--quick``).

``Scene.build`` does not dice a displaced object whose displacement the camera cannot
see: zero length, under the dicing tolerance on screen (shaded as bump from the same
field), or on an object out of view (:func:`displacement.dice.displacement_on_screen`).
For every gallery scene with a displaced object, at its own size and at smaller ones
(thumbnails are where displacement falls under a pixel), this builds the scene both ways
(``dice_invisible = false``, the default, and ``true``) and reports the triangles and
the build time (dicing and the Embree scene; fastest of ``--repeats``).  Where an object
was not diced, both are rendered with the same seed, and their RMSE is printed next to
the noise floor (the diced render against another seed): modelling less must not show.
"""

from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))
sys.path.insert(0, str(ROOT / "benchmarks"))

from bump_vs_displacement import write_doc  # noqa: E402

from render.integrator import render  # noqa: E402
from render.library.resources import bundled_scenes  # noqa: E402
from render.scene import load_scene  # noqa: E402
from trade.metrics import image_errors  # noqa: E402

DOC = ROOT / "docs" / "trade.md"


def build(path: Path, size, dice_invisible: bool, repeats: int):
    """(scene, geometry, fastest build seconds) at ``size``."""
    best = None
    for _ in range(repeats):
        scene = load_scene(path, overrides={"width": size[0], "height": size[1],
                                            "dice_invisible": dice_invisible})
        t0 = time.perf_counter()
        geometry = scene.build()
        dt = time.perf_counter() - t0
        best = dt if best is None else min(best, dt)
    return scene, geometry, best


def displaced(path: Path) -> bool:
    return any(o.displacement is not None for o in load_scene(path).objects)


def run(args) -> list[dict]:
    rows = []
    for path in args.scenes:
        native = load_scene(path).settings
        for scale in args.scales:
            size = (max(1, native.width // scale), max(1, native.height // scale))
            culled, g1, t1 = build(path, size, False, args.repeats)
            _, g2, t2 = build(path, size, True, args.repeats)
            skipped = [st for st in g1.stats if st.get("not_diced")]
            row = {"scene": path.stem, "size": size, "skipped": skipped,
                   "triangles": (g1.triangle_count, g2.triangle_count), "build_s": (t1, t2)}
            if skipped:
                kw = {"width": size[0], "height": size[1], "spp": args.spp}
                a = render(load_scene(path, overrides=kw), progress=False).rgb()
                b = render(load_scene(path, overrides={**kw, "dice_invisible": True}),
                           progress=False).rgb()
                c = render(load_scene(path, overrides={**kw, "dice_invisible": True,
                                                       "seed": 99}), progress=False).rgb()
                row["rmse"] = image_errors(a, b)["rmse"]
                row["noise"] = image_errors(c, b)["rmse"]
            rows.append(row)
            print(f"{path.stem} {size[0]}x{size[1]}: {len(skipped)} not diced, triangles "
                  f"{row['triangles'][0]:,} vs {row['triangles'][1]:,}, build "
                  f"{t1 * 1e3:.0f} vs {t2 * 1e3:.0f} ms"
                  + (f", RMSE {row['rmse']:.2g} (noise {row['noise']:.2g})" if skipped
                     else ""), flush=True)
    return rows


def markdown(rows: list[dict], args) -> str:
    fractions = ", ".join(f"1/{k}" for k in args.scales[1:])
    lines = [f"Gallery scenes with displacement, at their size and at {fractions} of it "
             f"(fastest of {args.repeats} builds; renders at {args.spp} spp):", "",
             "| scene | size | not diced (why) | triangles: as built / all diced | "
             "build ms: as built / all diced | RMSE vs diced (noise) |",
             "|---|---|---|---|---|---|"]
    total = [0, 0, 0.0, 0.0]
    for r in rows:
        total[0] += r["triangles"][0]
        total[1] += r["triangles"][1]
        total[2] += r["build_s"][0]
        total[3] += r["build_s"][1]
        if not r["skipped"]:
            continue
        why = "; ".join(f"{st['name']}: {st['not_diced']}" for st in r["skipped"])
        lines.append(f"| {r['scene']} | {r['size'][0]} x {r['size'][1]} | {why} | "
                     f"{r['triangles'][0]:,} / {r['triangles'][1]:,} | "
                     f"{r['build_s'][0] * 1e3:.0f} / {r['build_s'][1] * 1e3:.0f} | "
                     f"{r['rmse']:.2g} ({r['noise']:.2g}) |")
    n_skip = sum(len(r["skipped"]) for r in rows)
    lines.append(f"| **all {len(rows)} builds** | | {n_skip} objects not diced | "
                 f"{total[0]:,} / {total[1]:,} | {total[2] * 1e3:.0f} / "
                 f"{total[3] * 1e3:.0f} | |")
    return "\n".join(lines) + "\n"


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--quick", action="store_true", help="one scene, one size (no doc)")
    ap.add_argument("--spp", type=int, default=16, help="samples per pixel of the renders")
    ap.add_argument("--repeats", type=int, default=None, help="builds to time (default 3)")
    ap.add_argument("--doc", default=None, help=f"write the table into this page "
                    f"(default {DOC.relative_to(ROOT)}, not with --quick)")
    args = ap.parse_args(argv)
    scenes = [p for p in sorted(bundled_scenes().glob("*.toml")) if displaced(p)]
    if args.quick:
        args.scenes, args.scales, args.repeats = [bundled_scenes() / "fig_14_03.toml"], [1], 1
        args.spp = 2
    else:
        args.scenes, args.scales = scenes, [1, 4, 16]
        args.repeats = args.repeats or 3
    rows = run(args)
    table = markdown(rows, args)
    print(table)
    doc = Path(args.doc) if args.doc else (None if args.quick else DOC)
    if doc is not None:
        write_doc(doc, table, "invisible")
        print(f"wrote {doc}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
