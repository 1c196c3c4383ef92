"""Benchmark: this path tracer against Mitsuba 3 (``llvm_ad_rgb``) on the Handbook stage.

Run ``python benchmarks/render_vs_mitsuba.py`` (``--quick`` for a tiny run,
``--markdown`` for a Markdown table).  The scene is the Handbook's stage (Figure 11.6: a
square and a sphere on a floor, two area lights above left and right, a dim constant
environment), built identically for both renderers, once with diffuse and once with
glossy objects.  For each it measures

* samples per second of both renderers (ours with 2 threads; Mitsuba's LLVM backend
  uses both cores too), from a timed render after a warm-up (Mitsuba's JIT compile and
  our BVH build are excluded);
* the share of our render time spent inside Embree (``scene.run``);
* equal-time error: both render for the same wall time, and their RMSE against a
  converged Mitsuba reference (``--ref-spp``) is compared.

Requires ``pip install mitsuba`` and Debian's ``libllvm19`` (``DRJIT_LIBLLVM_PATH``).
"""

from __future__ import annotations

import argparse
import os
import sys
import time
from pathlib import Path

os.environ.setdefault("DRJIT_LIBLLVM_PATH", "/usr/lib/x86_64-linux-gnu/libLLVM-19.so")

import numpy as np  # noqa: E402

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from displacement.surfaces import Plane, UVSphere  # noqa: E402
from render import material as M  # noqa: E402
from render.camera import Camera  # noqa: E402
from render.integrator import Integrator  # noqa: E402
from render.lights import ConstantEnvironment  # noqa: E402
from render.scene import RenderSettings, Scene, SceneObject, emissive_material, make_transform  # noqa: E402


def _rect(center, axis_u, axis_v, size):
    au, av = np.asarray(axis_u, float), np.asarray(axis_v, float)
    au, av = au / np.linalg.norm(au), av / np.linalg.norm(av)
    c = np.asarray(center, float)
    n = np.cross(au, av)
    m = np.eye(4)
    m[:3, 0], m[:3, 1], m[:3, 2], m[:3, 3] = 0.5 * size[0] * au, 0.5 * size[1] * av, n, c
    origin = c - 0.5 * (size[0] * au + size[1] * av)
    return Plane(size=size, origin=tuple(origin), axis_u=tuple(au), axis_v=tuple(av)), m


def _light_axes(normal):
    n = np.asarray(normal, float) / np.linalg.norm(normal)
    au = np.cross([0.0, 0.0, -1.0], n)
    au /= np.linalg.norm(au)
    return au, np.cross(n, au)


def stage(kind: str, width: int, height: int):
    """(our Scene, Mitsuba scene dict, camera dict) of the stage with diffuse or glossy objects."""
    cam = dict(origin=(0.0, 1.1, 3.6), target=(0.0, 0.45, 0.0), fov=30.0)
    floor, floor_m = _rect((0, 0, 0), (1, 0, 0), (0, 0, -1), (8.0, 8.0))
    c, s = np.cos(np.radians(15)), np.sin(np.radians(15))
    square, square_m = _rect(
        (-0.65 + 0.5 * c - 0.5, 0.5, -0.5 * s), (c, 0, -s), (0, 1, 0), (1.0, 1.0)
    )
    lights = []
    for center, normal, radiance in (
        ((-2.2, 3.2, 2.2), (0.55, -0.7, -0.45), 5.0),
        ((2.2, 3.2, 2.2), (-0.55, -0.7, -0.45), 4.0),
    ):
        au, av = _light_axes(normal)
        lights.append((*_rect(center, au, av, (1.2, 1.2)), radiance))
    if kind == "diffuse":
        tint = (0.6, 0.4, 0.1)
        ours_obj = M.material(surface=M.material_surface(M.df.diffuse_reflection_bsdf(tint=tint)))
        mi_obj = {
            "type": "twosided",
            "b": {"type": "diffuse", "reflectance": {"type": "rgb", "value": list(tint)}},
        }
    else:
        tint, r = (0.6, 0.4, 0.0), 0.3
        ours_obj = M.material(
            surface=M.material_surface(M.df.simple_glossy_bsdf(tint=tint, roughness_u=r))
        )
        mi_obj = {
            "type": "twosided",
            "b": {
                "type": "roughconductor",
                "material": "none",
                "distribution": "beckmann",
                "alpha": r,
                "specular_reflectance": {"type": "rgb", "value": list(tint)},
            },
        }
    grey = M.material(surface=M.material_surface(M.df.diffuse_reflection_bsdf(tint=0.45)))
    objects = [
        SceneObject(floor, grey, name="floor"),
        SceneObject(square, ours_obj, name="square"),
        SceneObject(
            UVSphere(0.5),
            ours_obj,
            make_transform(translate=(0.65, 0.5, 0.0)),
            name="sphere",
            resolution=(192, 96),
        ),
    ]
    objects += [
        SceneObject(p, emissive_material(np.full(3, np.pi * L)), name=f"light{i}")
        for i, (p, _, L) in enumerate(lights)
    ]
    ours = Scene(
        Camera(
            position=cam["origin"],
            look_at=cam["target"],
            fov_y_deg=cam["fov"],
            width=width,
            height=height,
        ),
        objects,
        [ConstantEnvironment(0.12)],
        RenderSettings(width, height, spp=1, max_depth=8),
    )
    md = {
        "type": "scene",
        "integrator": {"type": "path", "max_depth": 8, "rr_depth": 5},
        "sensor": {
            "type": "perspective",
            "fov": cam["fov"],
            "fov_axis": "y",
            "film": {
                "type": "hdrfilm",
                "width": width,
                "height": height,
                "rfilter": {"type": "box"},
                "pixel_format": "rgb",
            },
            "sampler": {"type": "independent"},
        },
        "floor": {
            "type": "rectangle",
            "to_world": floor_m,
            "bsdf": {
                "type": "twosided",
                "b": {"type": "diffuse", "reflectance": {"type": "rgb", "value": [0.45] * 3}},
            },
        },
        "square": {"type": "rectangle", "to_world": square_m, "bsdf": mi_obj},
        "sphere": {"type": "sphere", "center": [0.65, 0.5, 0.0], "radius": 0.5, "bsdf": mi_obj},
        "env": {"type": "constant", "radiance": {"type": "rgb", "value": [0.12] * 3}},
    }
    for i, (_, m, L) in enumerate(lights):
        md[f"light{i}"] = {
            "type": "rectangle",
            "to_world": m,
            "bsdf": {"type": "diffuse", "reflectance": {"type": "rgb", "value": [0.0] * 3}},
            "emitter": {"type": "area", "radiance": {"type": "rgb", "value": [L] * 3}},
        }
    return ours, md, cam


def mitsuba_scene(mi, md, cam):
    d = {k: (dict(v) if isinstance(v, dict) else v) for k, v in md.items()}
    d["sensor"]["to_world"] = mi.ScalarTransform4f().look_at(
        origin=list(cam["origin"]), target=list(cam["target"]), up=[0, 1, 0]
    )
    for v in d.values():
        if isinstance(v, dict) and isinstance(v.get("to_world"), np.ndarray):
            v["to_world"] = mi.ScalarTransform4f(v["to_world"].tolist())
    return mi.load_dict(d)


def mitsuba_render(mi, scene, spp, seed):
    t0 = time.perf_counter()
    img = np.array(mi.render(scene, spp=spp, seed=seed), dtype=np.float64)
    return img, time.perf_counter() - t0


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--quick", action="store_true", help="tiny sizes (a smoke run)")
    ap.add_argument("--size", type=int, nargs=2, default=(256, 192), metavar=("W", "H"))
    ap.add_argument("--spp", type=int, default=32, help="spp of the timed render of ours")
    ap.add_argument("--ref-spp", type=int, default=4096, help="spp of the Mitsuba reference")
    ap.add_argument("--seconds", type=float, default=4.0, help="equal-time budget")
    ap.add_argument("--markdown", action="store_true")
    args = ap.parse_args(argv)
    if args.quick:
        args.size, args.spp, args.ref_spp, args.seconds = (48, 32), 4, 64, 0.5
    import mitsuba as mi

    mi.set_variant("llvm_ad_rgb")
    w, h = args.size
    rows = []
    for kind in ("diffuse", "glossy"):
        ours, md, cam = stage(kind, w, h)
        integ = Integrator(ours, ours.build())
        misc = mitsuba_scene(mi, md, cam)
        mitsuba_render(mi, misc, 4, 0)  # JIT warm-up
        integ.render(spp=1, progress=False)  # warm-up
        film = integ.render(spp=args.spp, progress=False)
        ours_rate = film.stats["samples_per_s"]
        embree_share = film.stats["embree_time_s"] / film.stats["time_s"]
        mi_spp = max(4, args.spp * 4)
        _, t_mi = mitsuba_render(mi, misc, mi_spp, 1)
        mi_rate = w * h * mi_spp / t_mi
        ref, _ = mitsuba_render(mi, misc, args.ref_spp, 2)
        # equal time: each renders for the same budget
        eq_ours = integ.render(time_budget=args.seconds, seed=3, progress=False)
        spp_mi_eq = max(1, int(round(mi_rate * args.seconds / (w * h))))
        eq_mi, t_eq_mi = mitsuba_render(mi, misc, spp_mi_eq, 4)
        rmse_ours = float(np.sqrt(np.mean((eq_ours.rgb() - ref) ** 2)))
        rmse_mi = float(np.sqrt(np.mean((eq_mi - ref) ** 2)))
        bias = float((eq_ours.rgb().mean() - ref.mean()) / ref.mean())
        rows.append(
            (
                kind,
                ours_rate,
                mi_rate,
                embree_share,
                eq_ours.stats["spp"],
                eq_ours.stats["time_s"],
                rmse_ours,
                spp_mi_eq,
                t_eq_mi,
                rmse_mi,
                bias,
            )
        )
    head = (
        "scene",
        "ours Msamples/s",
        "Mitsuba Msamples/s",
        "ratio",
        "in Embree",
        "equal time: ours spp (s)",
        "ours RMSE",
        "Mitsuba spp (s)",
        "Mitsuba RMSE",
        "mean vs ref",
    )
    lines = []
    for r in rows:
        lines.append(
            (
                r[0],
                f"{r[1] / 1e6:.3f}",
                f"{r[2] / 1e6:.3f}",
                f"{r[1] / r[2]:.3f}",
                f"{r[3]:.0%}",
                f"{r[4]} ({r[5]:.1f})",
                f"{r[6]:.4f}",
                f"{r[7]} ({r[8]:.1f})",
                f"{r[9]:.4f}",
                f"{r[10]:+.2%}",
            )
        )
    print(
        f"# {w}x{h}, Mitsuba reference {args.ref_spp} spp, equal time {args.seconds} s, max depth 8"
    )
    if args.markdown:
        print("| " + " | ".join(head) + " |")
        print("|" + "---|" * len(head))
        for ln in lines:
            print("| " + " | ".join(ln) + " |")
    else:
        for ln in lines:
            print(", ".join(f"{k}: {v}" for k, v in zip(head, ln, strict=True)))
    return 0


if __name__ == "__main__":
    sys.exit(main())
