"""Benchmark: bump mapping versus true displacement of the same look on the Handbook stage.

Run ``python benchmarks/bump_vs_displacement.py`` (``--quick`` for a tiny smoke run;
``--doc PATH`` writes the Markdown table, by default to ``docs/bump_vs_displacement.md``
unless ``--quick``).  The scene is the gallery's Figure 12.5
(``gallery/scenes/fig_12_05.toml``: the Handbook's stage, Figure 11.6, with a square and
a sphere wearing ``waves_as_displacement(frequency: float2(4.0, 4.0), distance:
float2(0.075, 0.075))``).  The same look is rendered, at the same samples per pixel, as

* **displaced**: the Handbook's material; the renderer dices both objects for the camera
  (``displacement.dice``) and traces the displaced triangles;
* **bump, baked normal map**: the displacement baked per object into a 16-bit
  tangent-space normal map (``displacement.bake``, ``--map-size`` texels square, quantized
  as the file stores it) and applied with the Handbook's ``normal_map_bump`` (Listing
  13.19) over the same surface; the objects stay flat (the base mesh).  This is the scene
  files' ``displacement_method = "normal_map"`` (:mod:`render.displacement_method`);
* **bump, procedural normal**: the exact normal of the displaced surface computed at
  every shading point (``displacement.bake.displaced_normal``), no map: what bump can
  do at best, so the map's own error is seen apart from bump's (``displacement_method =
  "bump"``);
* **shading only**: ``waves_as_grayscale(frequency: float2(4.0, 4.0))`` (Listing 12.4),
  the version that the Handbook timed at 57 % of ``waves_as_displacement`` (section
  12.2): a different look, timed for comparison;
* **displaced, another seed**: the noise floor of the error columns.

Times are wall-clock seconds of ``Scene.build`` (dicing and the Embree BVH) plus the
render, two threads, after one untimed warm-up render; each is the fastest of
``--repeats`` runs (the machine may be shared).  Image errors are against the
displaced render (seed 1; every other render uses seed 2, so no two share their noise):
RMSE of the linear images and mean LDR-FLIP (``flip_evaluator``) of their sRGB encodings.
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

from render.displacement_method import apply  # noqa: E402
from render.film import linear_to_srgb  # noqa: E402
from render.integrator import Integrator  # noqa: E402
from render.material import material  # noqa: E402
from render.materials import MATERIALS  # noqa: E402
from render.scene import load_scene  # noqa: E402

SCENE = ROOT / "gallery" / "scenes" / "fig_12_05.toml"
DOC = ROOT / "docs" / "bump_vs_displacement.md"
#: section 12.2: "the rendering of the waves_as_grayscale version only took 57% of the
#: time required by wave_as_displacement"
HANDBOOK_RATIO = 0.57


def errors(test: np.ndarray, ref: np.ndarray) -> tuple[float, float]:
    """(RMSE of the linear images, mean LDR-FLIP of their sRGB encodings)."""
    import flip_evaluator

    rmse = float(np.sqrt(np.mean((test - ref) ** 2)))
    a = linear_to_srgb(ref).astype(np.float32)
    b = linear_to_srgb(test).astype(np.float32)
    _, flip, _ = flip_evaluator.evaluate(a, b, "LDR", applyMagma=False)
    return rmse, float(flip)


def timed_render(scene, spp: int, seed: int, repeats: int = 1) -> dict:
    """Build (dice) and render ``repeats`` times; the fastest build and render (seconds),
    the image, the triangle count and the rays traced."""
    build, render = [], []
    for _ in range(repeats):
        t0 = time.perf_counter()
        geometry = scene.build()
        build.append(time.perf_counter() - t0)
        film = Integrator(scene, geometry).render(spp=spp, seed=seed, progress=False)
        render.append(film.stats["time_s"])
    return {"build_s": min(build), "render_s": min(render), "total_s": min(build) + min(render),
            "image": film.rgb(), "triangles": geometry.triangle_count,
            "rays": film.stats["rays"]}


def with_method(scene, method: str, map_size: int = 512, bake_times: list | None = None):
    """A copy of ``scene`` whose displaced objects are modelled by ``method``
    (:mod:`render.displacement_method`: ``"bump"`` or a 16-bit ``"normal_map"``)."""
    objects = []
    for o in scene.objects:
        if o.displacement is not None:
            t0 = time.perf_counter()
            o = dataclasses.replace(o, material=apply(o.material, o.surface, method, map_size, 16),
                                    displacement_method=method)
            if bake_times is not None:
                bake_times.append(time.perf_counter() - t0)
        objects.append(o)
    return dataclasses.replace(scene, objects=objects)


def with_materials(scene, make):
    """A copy of ``scene`` whose displaced objects get ``make(obj)`` as their material."""
    objects = [dataclasses.replace(o, material=make(o)) if o.displacement is not None else o
               for o in scene.objects]
    return dataclasses.replace(scene, objects=objects)


def shading_only(obj) -> material:
    """Listing 12.4's ``waves_as_grayscale(frequency: float2(4.0, 4.0))``."""
    return MATERIALS["waves_as_grayscale"](frequency=(4.0, 4.0))


def run(args) -> list[dict]:
    scene = load_scene(args.scene, overrides={"width": args.size[0], "height": args.size[1],
                                              "spp": args.spp})
    timed_render(scene, 1, 0)  # warm-up: imports, Embree, caches (not timed)
    rows = []
    bake_times: list[float] = []
    variants = [
        ("displaced", scene, 1),
        ("bump, baked normal map", with_method(scene, "normal_map", args.map_size,
                                               bake_times), 2),
        ("bump, procedural normal", with_method(scene, "bump"), 2),
        ("shading only (waves_as_grayscale)", with_materials(scene, shading_only), 2),
        ("displaced, another seed", scene, 2),
    ]
    reference = None
    for name, sc, seed in variants:
        r = timed_render(sc, args.spp, seed, args.repeats)
        r["name"] = name
        if reference is None:
            reference = r
        else:
            r["rmse"], r["flip"] = errors(r["image"], reference["image"])
        r["ratio"] = r["total_s"] / reference["total_s"]
        if name.startswith("bump, baked"):
            r["bake_s"] = sum(bake_times)
        rows.append(r)
        print(f"{name}: {r['total_s']:.2f} s ({r['ratio']:.0%} of displaced), "
              f"{r['triangles']} triangles"
              + (f", RMSE {r['rmse']:.4f}, FLIP {r['flip']:.4f}" if "rmse" in r else ""),
              flush=True)
    return rows


def markdown(rows: list[dict], args) -> str:
    w, h = rows[0]["image"].shape[1], rows[0]["image"].shape[0]
    lines = [
        "| render | triangles | rays | build s | render s | total s | time vs displaced | "
        "RMSE vs displaced | FLIP vs displaced |",
        "|---|---|---|---|---|---|---|---|---|",
    ]
    for r in rows:
        err = (f"{r['rmse']:.4f} | {r['flip']:.4f}" if "rmse" in r else "— | —")
        extra = f" (+ {r['bake_s']:.2f} s bake, once)" if "bake_s" in r else ""
        lines.append(f"| {r['name']} | {r['triangles']:,} | {r['rays'] / 1e6:.2f} M | "
                     f"{r['build_s']:.2f} | "
                     f"{r['render_s']:.2f}{extra} | {r['total_s']:.2f} | {r['ratio']:.0%} | "
                     f"{err} |")
    lines.append(f"| *Handbook, section 12.2: waves_as_grayscale vs waves_as_displacement* | "
                 f"| | | | | *{HANDBOOK_RATIO:.0%}* | | |")
    scene = Path(args.scene).resolve()
    scene = scene.relative_to(ROOT) if scene.is_relative_to(ROOT) else scene
    head = (f"{w} x {h} px, {args.spp} spp, normal maps {args.map_size} x {args.map_size} "
            f"16-bit, fastest of {args.repeats} runs, scene `{scene}`")
    return head + "\n\n" + "\n".join(lines) + "\n"


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--quick", action="store_true", help="tiny sizes (a smoke run; no doc)")
    ap.add_argument("--size", type=int, nargs=2, default=None, metavar=("W", "H"),
                    help="image size (default: 256 192; --quick 48 36)")
    ap.add_argument("--spp", type=int, default=None, help="samples per pixel (default 64)")
    ap.add_argument("--map-size", type=int, default=None, help="normal map texels (default 512)")
    ap.add_argument("--repeats", type=int, default=None,
                    help="time each render this many times, keep the fastest (default 3)")
    ap.add_argument("--scene", default=str(SCENE), help="a TOML scene with displaced objects")
    ap.add_argument("--doc", default=None,
                    help=f"write the Markdown table here (default {DOC.relative_to(ROOT)}, "
                         "not with --quick)")
    args = ap.parse_args(argv)
    quick = args.quick
    args.size = tuple(args.size) if args.size else ((48, 36) if quick else (256, 192))
    args.spp = args.spp or (2 if quick else 64)
    args.map_size = args.map_size or (32 if quick else 512)
    args.repeats = args.repeats or (1 if quick else 3)
    if min(args.size) < 1 or args.spp < 1 or args.repeats < 1 or args.map_size < 2:
        ap.error("--size, --spp and --repeats must be >= 1 and --map-size >= 2")
    rows = run(args)
    table = markdown(rows, args)
    print(table)
    doc = Path(args.doc) if args.doc else (None if quick else DOC)
    if doc is not None:
        write_doc(doc, table)
        print(f"wrote {doc}")
    return 0


def write_doc(path: Path, table: str, name: str = "table",
              title: str = "# Bump versus true displacement") -> None:
    """Replace the table between the ``<!-- NAME: start/end -->`` markers of ``path``
    (append them, or write a page with ``title``, where they are missing)."""
    start, end = f"<!-- {name}: start -->", f"<!-- {name}: end -->"
    block = f"{start}\n{table}{end}"
    text = path.read_text() if path.exists() else f"{title}\n"
    if start in text and end in text:
        before, rest = text.split(start, 1)
        path.write_text(before + block + rest.split(end, 1)[1])
    else:
        path.write_text(f"{text}\n{block}\n")


if __name__ == "__main__":
    sys.exit(main())
