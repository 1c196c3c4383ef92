"""Benchmark: this path tracer against Mitsuba 3 (``llvm_ad_rgb``) on the Handbook stage.

Run ``python benchmarks/render_vs_mitsuba.py`` (``--quick`` for a tiny run,
``--markdown`` for a Markdown table).  The scene is the Handbook's stage (Figure 11.6: a
square and a sphere on a floor, two area lights above left and right, a dim constant
environment), built identically for both renderers, with diffuse, glossy, layered
(``fresnel_layer`` of a glossy coat over diffuse, against Mitsuba's ``roughplastic``)
and mixed (``normalized_mix`` of diffuse and glossy, against ``blendbsdf``) objects.
For each it measures

* samples per second of both renderers (ours with 2 threads; Mitsuba's LLVM backend
  uses both cores too), from a timed render after a warm-up (Mitsuba's JIT compile and
  our BVH build are excluded).  Mitsuba renders the very triangles we trace (our
  tessellation, vertex normals included), and, for scale, its analytic sphere and
  rectangles.  Mitsuba's ``scalar_rgb`` variant (C++, one lane and one ray at a time,
  as our kernels) renders the same triangles too: the peer of our scalar design,
  where ``llvm_ad_rgb`` traces and shades 16 lanes per instruction with AVX-512;
* the share of our threads' time spent inside Embree (``rtcIntersect1``/``rtcOccluded1``
  called from the path kernel; every 16th call timed by the CPU's time-stamp counter,
  :data:`render.path.TIMED_EVERY`), and rays per sample;
* equal-time error: both render for the same wall time, and their RMSE against a
  converged reference (``--ref-spp``) is compared (Mitsuba with its ``independent``
  sampler and with its ``ldsampler``, whose padded (0, 2)-sequences are the peer of
  ours, :mod:`render.sampler`): Mitsuba's reference for the diffuse and glossy
  stages (the same model); for the layered and mixed stages, whose models differ in
  detail (libbsdf's Ashikhmin–Shirley lobe and layering against Beckmann
  ``roughplastic``), each renderer against its own reference, and the means side by
  side.

The machine's SIMD flags (``lscpu``: avx2, avx512f) are printed with the ratios:
Mitsuba's speed depends on its vector width.

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
    elif kind == "layered":
        tint, r = (0.6, 0.4, 0.1), 0.2
        ours_obj = M.material(surface=M.material_surface(M.df.fresnel_layer(
            ior=1.5, layer=M.df.simple_glossy_bsdf(roughness_u=r),
            base=M.df.diffuse_reflection_bsdf(tint=tint))))
        mi_obj = {
            "type": "twosided",
            "b": {"type": "roughplastic", "distribution": "beckmann", "alpha": r,
                  "int_ior": 1.5, "ext_ior": 1.0,
                  "diffuse_reflectance": {"type": "rgb", "value": list(tint)}},
        }
    elif kind == "mixed":
        tint, gloss, r = (0.6, 0.4, 0.1), (0.8, 0.8, 0.8), 0.3
        ours_obj = M.material(surface=M.material_surface(M.df.normalized_mix([
            M.df.bsdf_component(0.6, M.df.diffuse_reflection_bsdf(tint=tint)),
            M.df.bsdf_component(0.4, M.df.simple_glossy_bsdf(tint=gloss, roughness_u=r))])))
        mi_obj = {
            "type": "twosided",
            "b": {"type": "blendbsdf", "weight": 0.4,
                  "bsdf_0": {"type": "diffuse",
                             "reflectance": {"type": "rgb", "value": list(tint)}},
                  "bsdf_1": {"type": "roughconductor", "material": "none",
                             "distribution": "beckmann", "alpha": r,
                             "specular_reflectance": {"type": "rgb", "value": list(gloss)}}},
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


def with_sampler(md, sampler):
    """The scene dict ``md`` with the sensor's sampler plugin ``sampler``."""
    return {**md, "sensor": {**md["sensor"], "sampler": {"type": sampler}}}


def mitsuba_mesh(mi, name, vertices, normals, faces, shape: dict):
    """A Mitsuba mesh of triangles (positions, vertex normals) with the ``bsdf`` and
    ``emitter`` of the shape dict ``shape``."""
    used, local = np.unique(faces, return_inverse=True)
    props = mi.Properties()
    for key in ("bsdf", "emitter"):
        if key in shape:
            props[key] = mi.load_dict(shape[key])
    mesh = mi.Mesh(name, len(used), len(faces), props, has_vertex_normals=True)
    params = mi.traverse(mesh)
    # each buffer in its own type: a Dr.Jit array in the LLVM variant, a dynamic array
    # in the scalar one
    for key, data in (("vertex_positions", vertices[used].astype(np.float32)),
                      ("vertex_normals", normals[used].astype(np.float32)),
                      ("faces", local.astype(np.uint32))):
        params[key] = type(params[key])(data.ravel())
    params.update()
    return mesh


def same_triangles(mi, md, geometry, names):
    """``md`` with every shape replaced by a Mitsuba mesh of our triangles (positions and
    vertex normals of ``geometry``, object ``k`` being ``names[k]``)."""
    out = dict(md)
    for k, name in enumerate(names):
        faces = geometry.faces[geometry.face_offset[k] : geometry.face_offset[k + 1]]
        out[name] = mitsuba_mesh(mi, name, geometry.vertices, geometry.normals, faces,
                                 md[name])
    return out


THREADS = 2


def scalar_scene(mi, md, cam, geometry, names):
    """The stage ``md`` on our triangles in Mitsuba's ``scalar_rgb`` variant (C++, one
    ray and one lane at a time, Embree 3 underneath, a thread per core), rendered once
    to warm up: the peer of our scalar kernels, where ``llvm_ad_rgb`` traces and shades
    16 lanes at once.  Leaves the variant set to ``scalar_rgb``."""
    mi.set_variant("scalar_rgb")
    scene = mitsuba_scene(mi, same_triangles(mi, md, geometry, names), cam)
    mitsuba_render(mi, scene, 1, 0)
    return scene


def scalar_rate(mi, md, cam, geometry, names, spp: int) -> float:
    """Samples per second of :func:`scalar_scene`."""
    image, seconds = mitsuba_render(mi, scalar_scene(mi, md, cam, geometry, names), spp, 1)
    return image.shape[0] * image.shape[1] * spp / seconds


def simd_flags() -> str:
    """avx2 / avx512f as ``lscpu`` reports them (Mitsuba's vector width follows them)."""
    import subprocess

    try:
        out = subprocess.run(["lscpu"], capture_output=True, text=True, timeout=10).stdout
    except (OSError, subprocess.SubprocessError):
        return "unknown (no lscpu)"
    flags = next((ln.split(":", 1)[1].split() for ln in out.splitlines()
                  if ln.startswith("Flags")), [])
    return ", ".join(f"{f} {'yes' if f in flags else 'no'}" for f in ("avx2", "avx512f"))


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--quick", action="store_true", help="tiny sizes (a smoke run)")
    ap.add_argument("--size", type=int, nargs=2, default=(256, 192), metavar=("W", "H"))
    ap.add_argument("--spp", type=int, default=32, help="spp of the timed render of ours")
    ap.add_argument("--ref-spp", type=int, default=4096, help="spp of the Mitsuba reference")
    ap.add_argument("--seconds", type=float, default=4.0, help="equal-time budget")
    ap.add_argument("--markdown", action="store_true")
    ap.add_argument("--light-selection", default="contribution",
                    choices=["contribution", "power", "uniform"],
                    help="ours: [render] light_selection (how next-event estimation picks "
                         "a light)")
    ap.add_argument("--sampler", default="sobol", choices=["sobol", "independent"],
                    help="ours: [render] sampler (where sample values come from)")
    ap.add_argument("--kinds", nargs="+", default=["diffuse", "glossy", "layered", "mixed"],
                    choices=["diffuse", "glossy", "layered", "mixed"])
    args = ap.parse_args(argv)
    if args.quick:
        args.size, args.spp, args.ref_spp, args.seconds = (48, 32), 4, 64, 0.5
    import mitsuba as mi

    w, h = args.size
    pixels = w * h
    rows = []
    for kind in args.kinds:
        mi.set_variant("llvm_ad_rgb")
        ours, md, cam = stage(kind, w, h)
        ours.settings.light_selection = args.light_selection
        ours.settings.sampler = args.sampler
        geometry = ours.build()
        integ = Integrator(ours, geometry)
        names = [obj.name for obj in ours.objects]
        tri = same_triangles(mi, md, geometry, names)
        mi_tri = mitsuba_scene(mi, tri, cam)
        mi_ld = mitsuba_scene(mi, with_sampler(tri, "ldsampler"), cam)
        mi_analytic = mitsuba_scene(mi, md, cam)
        for sc in (mi_tri, mi_analytic):
            mitsuba_render(mi, sc, 4, 0)  # JIT warm-up
        integ.render(spp=1, progress=False)  # warm-up
        film = integ.render(spp=args.spp, progress=False, threads=THREADS)
        ours_rate = film.stats["samples_per_s"]
        rays_per_sample = film.stats["rays"] / (pixels * args.spp)
        embree_share = film.stats["embree_time_s"] / (THREADS * film.stats["time_s"])
        mi_spp = max(4, args.spp * 4)
        mi_rate = pixels * mi_spp / mitsuba_render(mi, mi_tri, mi_spp, 1)[1]
        mi_analytic_rate = pixels * mi_spp / mitsuba_render(mi, mi_analytic, mi_spp, 1)[1]
        mi_ref, _ = mitsuba_render(mi, mi_tri, args.ref_spp, 2)
        own = kind in ("layered", "mixed")  # models that differ in detail: own references
        ref = (integ.render(spp=max(args.ref_spp // 4, 1), seed=11, progress=False,
                            threads=THREADS).rgb() if own else mi_ref)
        # equal time: each renders for the same budget
        eq_ours = integ.render(time_budget=args.seconds, seed=3, progress=False, threads=THREADS)
        spp_mi_eq = max(1, int(round(mi_rate * args.seconds / pixels)))
        eq_mi, t_eq_mi = mitsuba_render(mi, mi_tri, spp_mi_eq, 4)
        # Mitsuba's low-discrepancy sampler (padded (0, 2)-sequences, as ours): its spp is
        # a power of four, the one nearest the equal-time count; its RMSE is scaled to the
        # budget as 1 / sqrt(time)
        spp_ld = 1 << 2 * max(0, int(round(np.log2(spp_mi_eq) / 2)))
        mitsuba_render(mi, mi_ld, spp_ld, 0)  # JIT warm-up of this sampler
        eq_ld, t_eq_ld = mitsuba_render(mi, mi_ld, spp_ld, 4)
        ours_rgb = eq_ours.rgb()
        mi_scalar_rate = scalar_rate(mi, md, cam, geometry, names, max(1, args.spp))
        rows.append(
            (
                kind,
                f"{rays_per_sample:.2f}",
                f"{ours_rate / 1e6:.3f}",
                f"{mi_rate / 1e6:.2f}",
                f"{mi_analytic_rate / 1e6:.2f}",
                f"{ours_rate / mi_rate:.3f}",
                f"{mi_scalar_rate / 1e6:.2f}",
                f"{ours_rate / mi_scalar_rate:.2f}",
                f"{embree_share:.0%}",
                f"{eq_ours.stats['spp']} ({eq_ours.stats['time_s']:.1f})",
                f"{np.sqrt(np.mean((ours_rgb - ref) ** 2)):.4f}",
                f"{spp_mi_eq} ({t_eq_mi:.1f})",
                f"{np.sqrt(np.mean((eq_mi - mi_ref) ** 2)):.4f}",
                f"{spp_ld} ({t_eq_ld:.1f})",
                f"{np.sqrt(np.mean((eq_ld - mi_ref) ** 2) * t_eq_ld / args.seconds):.4f}",
                f"{(ours_rgb.mean() - mi_ref.mean()) / mi_ref.mean():+.2%}",
            )
        )
    head = (
        "scene",
        "rays/sample",
        "ours Msamples/s",
        "Mitsuba, same triangles",
        "Mitsuba, analytic shapes",
        "ours / Mitsuba",
        "Mitsuba scalar_rgb, same triangles",
        "ours / Mitsuba scalar_rgb",
        "thread time in Embree",
        "equal time: ours spp (s)",
        "ours RMSE",
        "Mitsuba spp (s)",
        "Mitsuba RMSE",
        "Mitsuba ldsampler spp (s)",
        "Mitsuba ldsampler RMSE (scaled to the budget)",
        "our mean vs Mitsuba's reference",
    )
    print(
        f"# {w}x{h}, max depth 8, {THREADS} threads; Msamples/s; Mitsuba reference "
        f"{args.ref_spp} spp on the same triangles (layered, mixed: ours against our own "
        f"{max(args.ref_spp // 4, 1)}-spp reference); equal time {args.seconds} s; "
        f"light selection {args.light_selection}; sampler {args.sampler}; "
        f"CPU SIMD: {simd_flags()}"
    )
    if args.markdown:
        print("| " + " | ".join(head) + " |")
        print("|" + "---|" * len(head))
        for r in rows:
            print("| " + " | ".join(r) + " |")
    else:
        for r in rows:
            print(", ".join(f"{k}: {v}" for k, v in zip(head, r, strict=True)))
    return 0


if __name__ == "__main__":
    sys.exit(main())
