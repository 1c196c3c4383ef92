"""Benchmark: render-time adaptive dicing (ours) against the uniform tessellation a Mitsuba 3
user makes beforehand, on the Handbook's displaced figures, to the same image error.

Run ``python benchmarks/displaced_vs_mitsuba.py`` (``--quick`` for a tiny smoke run;
``--doc PATH`` writes the Markdown table into that page between its markers, by default
``docs/trade.md`` unless ``--quick``).

Mitsuba 3 has no render-time displacement: its users tessellate the displaced surface
uniformly and load the mesh.  For each figure (chapters 14 and 15: the gallery's scenes,
every material made a grey diffuse ``0.5`` so that both renderers evaluate the same
model; the displacement fields kept):

1. **ours**: the scene as ``pwc render`` builds it: displaced objects diced adaptively
   for the camera (0.5 px tolerance, 1 px rate); their measured screen error (random
   points and knot lines, ``benchmarks/dicing.py``'s ``measure``) is the geometric
   target;
2. **Mitsuba**: each displaced object tessellated uniformly at the smallest grid whose
   measured error reaches the same target (``dicing.py``'s ``equal_error_search``), the
   other objects with our triangles; ``llvm_ad_rgb``, ``path`` integrator, the same
   depth;
3. **one converged reference**: ours with the displaced objects diced at 0.1 px and
   ``--ref-spp`` samples; Mitsuba's own floor (its mesh at ``--ref-spp``) against it is
   printed, and the image target is ``--target`` relative RMSE, raised to 1.5 x that
   floor where the floor is higher (so that both can reach it);
4. **time to that error**: each renders at 1, 2, 4 ... spp (seed 1) until its relative
   RMSE against the reference is at most the target; the time of that render counts
   (ours: dicing, Embree build and trace; Mitsuba: loading the mesh and building its BVH,
   and rendering; its uniform tessellation, done once beforehand, is printed apart),
   with the peak memory above the process's at its start (``trade.measure.PeakMemory``:
   the resident set, Embree's, Dr.Jit's and LLVM's memory included).

Both run on the same two cores, after an untimed warm-up each (JIT kernels compiled).
The goal is to win on time and memory; the ratios are printed as they come.
Requires ``mitsuba`` and Debian's ``libllvm19`` (``DRJIT_LIBLLVM_PATH``).
"""

from __future__ import annotations

import argparse
import dataclasses
import os
import sys
import time
from pathlib import Path

os.environ.setdefault("DRJIT_LIBLLVM_PATH", "/usr/lib/x86_64-linux-gnu/libLLVM-19.so")

import numpy as np  # noqa: E402

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))
sys.path.insert(0, str(ROOT / "benchmarks"))

from bump_vs_displacement import write_doc  # noqa: E402
from dicing import equal_error_search, measure, worst  # noqa: E402
from render_vs_mitsuba import mitsuba_mesh  # noqa: E402

from displacement.dice import dice  # noqa: E402
from render import material as M  # noqa: E402
from render.integrator import render  # noqa: E402
from render.library.resources import bundled_scenes  # noqa: E402
from render.lights import ConstantEnvironment  # noqa: E402
from render.scene import load_scene  # noqa: E402
from trade.measure import PeakMemory  # noqa: E402
from trade.metrics import image_errors  # noqa: E402

DOC = ROOT / "docs" / "trade.md"
SCENES = ("fig_14_28", "fig_14_04", "fig_15_21")
GREY = 0.5


def grey_scene(name: str, size, spp: int, tolerance: float = 0.5):
    """The gallery scene ``name`` with every non-emitting material a grey diffuse (the
    displacement kept), at ``size``."""
    scene = load_scene(bundled_scenes() / f"{name}.toml", overrides={
        "width": size[0], "height": size[1], "spp": spp, "dicing_tolerance": tolerance,
        "dice_invisible": True})
    objects = []
    for o in scene.objects:
        emission = o.material.surface.emission
        if emission.emission is None:
            o = dataclasses.replace(o, material=M.material(
                surface=M.material_surface(M.df.diffuse_reflection_bsdf(tint=GREY)),
                geometry=M.material_geometry(displacement=o.displacement)))
        objects.append(o)
    return dataclasses.replace(scene, objects=objects)


def mitsuba_dict(mi, scene, geometry, uniform: dict):
    """Mitsuba's scene: our camera and lights, our triangles for undisplaced objects, the
    uniform meshes ``uniform[k]`` for displaced ones."""
    cam = scene.camera
    st = scene.settings
    d = {"type": "scene",
         "integrator": {"type": "path", "max_depth": st.max_depth, "rr_depth": st.rr_depth},
         "sensor": {"type": "perspective", "fov": cam.fov_y_deg, "fov_axis": "y",
                    "to_world": mi.ScalarTransform4f().look_at(
                        origin=list(map(float, cam.position)),
                        target=list(map(float, cam.look_at)), up=list(map(float, cam.up))),
                    "film": {"type": "hdrfilm", "width": cam.width, "height": cam.height,
                             "rfilter": {"type": "box"}, "pixel_format": "rgb"},
                    "sampler": {"type": "independent"}}}
    for light in scene.lights:
        if not isinstance(light, ConstantEnvironment):
            raise ValueError(f"{type(light).__name__} has no twin here")
        d["env"] = {"type": "constant", "radiance": {
            "type": "rgb", "value": np.broadcast_to(light.radiance, (3,)).tolist()}}
    grey = {"type": "twosided", "b": {"type": "diffuse", "reflectance": {
        "type": "rgb", "value": [GREY] * 3}}}
    for k, o in enumerate(scene.objects):
        emission = o.material.surface.emission
        if emission.emission is not None:
            radiance = np.broadcast_to(emission.intensity, (3,)) / np.pi
            shape = {"bsdf": {"type": "diffuse", "reflectance": {"type": "rgb",
                                                                  "value": [0.0] * 3}},
                     "emitter": {"type": "area", "radiance": {"type": "rgb",
                                                              "value": radiance.tolist()}}}
        else:
            shape = {"bsdf": grey}
        if k in uniform:
            mesh = uniform[k]
            d[o.name] = mitsuba_mesh(mi, o.name, mesh.vertices, mesh.normals, mesh.faces, shape)
        else:
            f = geometry.faces[geometry.face_offset[k]: geometry.face_offset[k + 1]]
            d[o.name] = mitsuba_mesh(mi, o.name, geometry.vertices, geometry.normals, f, shape)
    return d


def ours_run(name, size, spp, seed, reference):
    """Build and render ours once: (seconds, peak MB, triangles, errors)."""
    scene = grey_scene(name, size, spp)
    scene = dataclasses.replace(scene, settings=dataclasses.replace(scene.settings,
                                                                    seed=seed))
    with PeakMemory() as memory:
        t0 = time.perf_counter()
        film = render(scene, progress=False)
        seconds = time.perf_counter() - t0
    return seconds, memory.peak_bytes / 2**20, film.stats["triangles"], image_errors(
        film.rgb(), reference)


def mitsuba_run(mi, d, spp, seed, reference):
    """Load (BVH) and render Mitsuba's scene once: (seconds, peak MB, errors)."""
    with PeakMemory() as memory:
        t0 = time.perf_counter()
        scene = mi.load_dict(d)
        image = np.array(mi.render(scene, spp=spp, seed=seed), dtype=np.float64)
        seconds = time.perf_counter() - t0
    return seconds, memory.peak_bytes / 2**20, image_errors(image, reference)


def time_to_error(run, target: float, max_spp: int):
    """Render at 1, 2, 4 ... spp until the relative RMSE is at most ``target``."""
    spp = 1
    while True:
        out = run(spp)
        if out[-1]["rel_rmse"] <= target or spp >= max_spp:
            return spp, out
        spp *= 2


def benchmark(mi, name: str, args) -> dict:
    size = args.size
    ref_scene = grey_scene(name, size, args.ref_spp, tolerance=0.1)
    reference = render(ref_scene, progress=False).rgb()
    ours_scene = grey_scene(name, size, 1)
    geometry = ours_scene.build()
    uniform, n_eq, tess_s, adaptive_err = {}, {}, 0.0, 0.0
    rng = np.random.default_rng(1)
    for k, o in enumerate(ours_scene.objects):
        if o.displacement is None:
            continue
        mesh = dice(o.surface, o.displacement, ours_scene.camera, o.transform)
        err = worst(measure(mesh, o.surface, o.displacement, ours_scene.camera, args.samples,
                            rng, o.transform))
        adaptive_err = max(adaptive_err, err)
        n, _ = equal_error_search(o.surface, o.displacement, ours_scene.camera,
                                  max(0.5, err), args.samples, rng, args.n_max, None,
                                  o.transform)
        n = n or args.n_max
        t0 = time.perf_counter()
        uniform[k] = dice(o.surface, o.displacement, ours_scene.camera, o.transform,
                          uniform=n, max_triangles=2 * n * n + 2)
        tess_s += time.perf_counter() - t0
        n_eq[o.name] = n
    d = mitsuba_dict(mi, ours_scene, geometry, uniform)
    mi_triangles = sum(len(m.faces) for m in uniform.values()) + sum(
        int(geometry.face_offset[k + 1] - geometry.face_offset[k])
        for k in range(len(ours_scene.objects)) if k not in uniform)
    # Mitsuba's floor: its mesh converged, against our reference
    floor = mitsuba_run(mi, d, args.ref_spp, 7, reference)[2]["rel_rmse"]
    target = max(args.target, 1.5 * floor)
    render(grey_scene(name, size, 1), progress=False)  # warm-ups
    mitsuba_run(mi, d, 1, 0, reference)
    ours_spp, (ours_s, ours_mb, ours_tris, ours_err) = time_to_error(
        lambda spp: ours_run(name, size, spp, 1, reference), target, args.max_spp)
    mi_spp, (mi_s, mi_mb, mi_err) = time_to_error(
        lambda spp: mitsuba_run(mi, d, spp, 1, reference), target, args.max_spp)
    row = {"scene": name, "target": target, "floor": floor, "adaptive_px": adaptive_err,
           "n_eq": n_eq, "tess_s": tess_s,
           "ours": (ours_spp, ours_s, ours_mb, ours_tris, ours_err["rel_rmse"]),
           "mitsuba": (mi_spp, mi_s, mi_mb, mi_triangles, mi_err["rel_rmse"])}
    print(f"{name}: target rel RMSE {target:.3g} (Mitsuba's floor {floor:.3g}); ours "
          f"{ours_spp} spp {ours_s:.2f} s {ours_mb:.0f} MB {ours_tris:,} triangles; Mitsuba "
          f"{mi_spp} spp {mi_s:.2f} s {mi_mb:.0f} MB {mi_triangles:,} triangles (uniform "
          f"{n_eq}, tessellated in {tess_s:.2f} s); time ratio ours/Mitsuba "
          f"{ours_s / mi_s:.2f}, memory {ours_mb / max(mi_mb, 1e-9):.2f}", flush=True)
    return row


def markdown(rows, args) -> str:
    lines = [f"{args.size[0]} x {args.size[1]} px, grey diffuse materials, reference "
             f"{args.ref_spp} spp (ours, 0.1 px dicing); each renderer at 1, 2, 4 ... spp "
             f"until its relative RMSE reaches the target:", "",
             "| figure | target rel RMSE (Mitsuba floor) | renderer | geometry | triangles | "
             "spp | time s | peak MB | rel RMSE | ours / Mitsuba time, memory, triangles |",
             "|---|---|---|---|---|---|---|---|---|---|"]
    for r in rows:
        o, m = r["ours"], r["mitsuba"]
        grids = ", ".join(f"{k}: {n} x {n}" for k, n in r["n_eq"].items())
        lines.append(f"| {r['scene']} | {r['target']:.3g} ({r['floor']:.3g}) | ours | "
                     f"adaptive, {r['adaptive_px']:.2f} px | {o[3]:,} | {o[0]} | {o[1]:.2f} | "
                     f"{o[2]:.0f} | {o[4]:.3g} | {o[1] / m[1]:.2f}x, "
                     f"{o[2] / max(m[2], 1e-9):.2f}x, {o[3] / m[3]:.2g}x |")
        lines.append(f"| | | Mitsuba 3 | uniform ({grids}; {r['tess_s']:.2f} s beforehand) | "
                     f"{m[3]:,} | {m[0]} | {m[1]:.2f} | {m[2]:.0f} | {m[4]:.3g} | |")
    return "\n".join(lines) + "\n"


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--quick", action="store_true", help="one figure, tiny (no doc)")
    ap.add_argument("--size", type=int, nargs=2, default=(256, 192), metavar=("W", "H"))
    ap.add_argument("--ref-spp", type=int, default=1024)
    ap.add_argument("--target", type=float, default=0.05, help="relative RMSE to reach")
    ap.add_argument("--max-spp", type=int, default=1024)
    ap.add_argument("--samples", type=int, default=100_000, help="geometric error samples")
    ap.add_argument("--n-max", type=int, default=1024, help="largest uniform grid searched")
    ap.add_argument("--scenes", nargs="+", default=list(SCENES))
    ap.add_argument("--doc", default=None, help="write the table into this page")
    args = ap.parse_args(argv)
    if args.quick:
        args.size, args.ref_spp, args.samples, args.n_max = (32, 24), 32, 5000, 64
        args.scenes, args.target, args.max_spp = ["fig_14_28"], 0.3, 64
    sys.path.insert(0, str(ROOT / "tests" / "support"))
    from optional_libs import use_mitsuba_llvm

    reason = use_mitsuba_llvm()
    if reason is not None:
        print(f"skipped: {reason}")
        return 0
    import mitsuba as mi

    mi.set_variant("llvm_ad_rgb")
    rows = [benchmark(mi, name, args) for name in args.scenes]
    table = markdown(rows, args)
    print(table)
    doc = Path(args.doc) if args.doc else (None if args.quick else DOC)
    if doc is not None:
        write_doc(doc, table, "mitsuba")
        print(f"wrote {doc}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
