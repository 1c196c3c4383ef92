"""Benchmark: adaptive versus uniform dicing of the Handbook's displaced scenes.

Run ``python benchmarks/dicing.py`` (``--quick`` for a smaller image, ``--markdown`` to
print the table as Markdown).  For each scene at 1024 x 1024 it dices adaptively
(dicing rate 1 px, tolerance 0.5 px) and uniformly, and measures the screen-space error
of every mesh against the analytic displaced surface: random points in every triangle
(or a random subset of at most ``--samples`` points), and, for fields with creases,
points on the knot lines.  The uniform grid is searched for the smallest size whose
measured error is within the target (equal error), and the one with about the adaptive
triangle count (equal triangles) is measured too.
"""

from __future__ import annotations

import argparse
import math
import sys
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from displacement.camera import Camera  # noqa: E402
from displacement.dice import dice, screen_error  # noqa: E402
from displacement.surfaces import UnitSquare, UVSphere  # noqa: E402

TARGET_PX = 0.5


def _pwc(name):
    import pwc
    return pwc.load(str(ROOT / "profiles" / f"{name}.pwc"))


def scene_ornament(size):
    from displacement.pwc_fields import displace_with_pwc
    cam = Camera(position=(1.45, 0.75, 1.75), look_at=(0.5, 0.5, 0.15), fov_y_deg=38.0,
                 width=size, height=size)
    return "ornament 2 along v (unit square)", UnitSquare(), \
        displace_with_pwc(_pwc("ornament_2"), "along_v"), cam


def scene_corinthian(size):
    from displacement.pwc_fields import pwc_angular_displace
    cam = Camera(position=(0.0, 1.25, 2.3), look_at=(0.0, 0.45, 0.0), fov_y_deg=40.0,
                 width=size, height=size)
    return "Corinthian impost revolved", UnitSquare(), \
        pwc_angular_displace(_pwc("corinthian"), "along_v"), cam


def scene_tee(size):
    from displacement.profile import tee_displacement
    cam = Camera(position=(1.3, 0.6, 1.7), look_at=(0.5, 0.5, 0.1), fov_y_deg=40.0,
                 width=size, height=size)
    return "tee repeated 3x along v", UnitSquare(), tee_displacement(1, 3.0), cam


def scene_waves(size):
    from displacement.waves import waves_as_displacement
    cam = Camera(position=(0.0, 0.6, 3.1), look_at=(0.0, 0.0, 0.0), fov_y_deg=45.0,
                 width=size, height=size)
    return "waves (4, 4) x 0.075 on the sphere", UVSphere(1.0), \
        waves_as_displacement((4.0, 4.0), (0.075, 0.075)), cam


SCENES = [scene_ornament, scene_corinthian, scene_tee, scene_waves]


def knot_uv(field, per_line, rng):
    """Points on the field's knot lines (u or v fixed at a knot, the other random)."""
    knots = getattr(field, "uv_knots", (None, None))
    pts = []
    for axis, k in enumerate(knots):
        if k is None:
            continue
        k = np.asarray(k, dtype=np.float64)
        k = k[(k > 0.0) & (k < 1.0)]
        if not len(k):
            continue
        other = rng.random((len(k), per_line))
        fixed = np.repeat(k[:, None], per_line, axis=1)
        uv = np.stack([fixed, other] if axis == 0 else [other, fixed], axis=-1)
        pts.append(uv.reshape(-1, 2))
    return np.concatenate(pts) if pts else np.zeros((0, 2))


def measure(mesh, surface, field, cam, samples, rng, transform=None):
    """(max, mean) error in random points; (max, mean) on the knot lines (or None)."""
    # at least 4 points per triangle; small meshes get up to `samples` points in all
    per = int(min(2000, max(4, samples // max(1, mesh.triangle_count))))
    e = screen_error(mesh, surface, field, cam, transform, samples_per_triangle=per,
                     max_samples=samples, rng=rng)
    kuv = knot_uv(field, 400, rng)
    if len(kuv):
        ek = screen_error(mesh, surface, field, cam, transform, uv=kuv)
        knots = (float(ek.max(initial=0.0)), float(ek.mean()) if ek.size else 0.0)
    else:
        knots = None
    return (float(e.max(initial=0.0)), float(e.mean()) if e.size else 0.0), knots


def worst(err):
    (m, _), k = err
    return max(m, k[0]) if k else m


def run_uniform(surface, field, cam, n, samples, rng, transform=None):
    mesh = dice(surface, field, cam, transform, uniform=n, max_triangles=2 * n * n + 2)
    return mesh, measure(mesh, surface, field, cam, samples, rng, transform)


def equal_error_search(surface, field, cam, target, samples, rng, n_max, bar, transform=None):
    """Smallest uniform n (by bisection on a log scale) whose measured error <= target."""
    lo, hi = 4, None
    cache = {}

    def ok(n):
        if n not in cache:
            mesh, err = run_uniform(surface, field, cam, n, samples, rng, transform)
            cache[n] = (mesh.stats["triangles"], mesh.stats["time_s"], err)
            if bar is not None:
                bar.set_postfix_str(f"uniform n={n}: {worst(err):.3f} px")
        return worst(cache[n][2]) <= target

    n = 32
    while n <= n_max and not ok(n):
        lo, n = n, n * 2
    if n > n_max:
        return None, cache
    hi = n
    while hi - lo > max(1, hi // 32):
        mid = int(round(math.sqrt(lo * hi)))
        if mid in (lo, hi):
            break
        if ok(mid):
            hi = mid
        else:
            lo = mid
    return hi, cache


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--size", type=int, default=1024, help="image width = height (px)")
    ap.add_argument("--quick", action="store_true", help="256 x 256, fewer samples")
    ap.add_argument("--samples", type=int, default=400_000,
                    help="random error samples per mesh (at most)")
    ap.add_argument("--n-max", type=int, default=2048, help="largest uniform grid searched")
    ap.add_argument("--markdown", action="store_true", help="print a Markdown table")
    args = ap.parse_args(argv)
    size = 256 if args.quick else args.size
    samples = 50_000 if args.quick else args.samples
    try:
        from tqdm import tqdm
    except ImportError:  # pragma: no cover
        tqdm = None
    rows = []
    scenes = SCENES if tqdm is None else tqdm(SCENES, desc="scenes", leave=False)
    for make in scenes:
        name, surface, field, cam = make(size)
        rng = np.random.default_rng(1)
        # adaptive (best of 3 timings)
        times = []
        for _ in range(3):
            t0 = time.perf_counter()
            mesh = dice(surface, field, cam)
            times.append(time.perf_counter() - t0)
        a_err = measure(mesh, surface, field, cam, samples, rng)
        a_tris = mesh.stats["triangles"]
        bar = scenes if tqdm is not None else None
        n_eq, cache = equal_error_search(surface, field, cam, max(TARGET_PX, worst(a_err)),
                                         samples, rng, args.n_max, bar)
        # equal triangle count
        n_tri = max(1, int(round(math.sqrt(a_tris / 2))))
        mt, et = run_uniform(surface, field, cam, n_tri, samples, rng)
        if n_eq is not None:
            tris_eq, t_eq, err_eq = cache[n_eq]
            # time the equal-error uniform mesh once more (best of 2)
            t0 = time.perf_counter()
            dice(surface, field, cam, uniform=n_eq, max_triangles=2 * n_eq * n_eq + 2)
            t_eq = min(t_eq, time.perf_counter() - t0)
        # bulk throughput: a uniform grid of about 2M triangles, best of 2
        nb = 512 if args.quick else 1024
        bulk = []
        for _ in range(2):
            t0 = time.perf_counter()
            mb = dice(surface, field, cam, uniform=nb, max_triangles=2 * nb * nb + 2)
            bulk.append(time.perf_counter() - t0)
        rows.append(dict(
            bulk=(nb, mb.stats["triangles"], min(bulk)),
            scene=name, a_tris=a_tris, a_time=min(times), a_err=a_err,
            a_est=mesh.stats["max_error_px"],
            n_eq=n_eq, u_tris=None if n_eq is None else tris_eq,
            u_time=None if n_eq is None else t_eq, u_err=None if n_eq is None else err_eq,
            n_tri=n_tri, t_tris=mt.stats["triangles"], t_err=et,
            n_max=args.n_max,
        ))
    print_table(rows, size, args.markdown)
    return rows


def _fmt_err(err):
    (m, mean), k = err
    s = f"{m:.3f} / {mean:.3f}"
    if k:
        s += f"; knots {k[0]:.3f} / {k[1]:.3f}"
    return s


def print_table(rows, size, markdown):
    head = ["scene", "method", "triangles", "time s", "Mtri/s",
            "error px max / mean (random; on knot lines)"]
    lines = []
    for r in rows:
        lines.append([r["scene"], "adaptive", f"{r['a_tris']:,}", f"{r['a_time']:.3f}",
                      f"{r['a_tris'] / r['a_time'] / 1e6:.2f}", _fmt_err(r["a_err"])])
        if r["n_eq"] is None:
            lines.append(["", f"uniform equal error (n > {r['n_max']})",
                          f"> {2 * r['n_max'] ** 2:,}", "", "", "not reached"])
            ratio = f"> {2 * r['n_max'] ** 2 / r['a_tris']:.0f}x"
        else:
            lines.append(["", f"uniform equal error n={r['n_eq']}", f"{r['u_tris']:,}",
                          f"{r['u_time']:.3f}", f"{r['u_tris'] / r['u_time'] / 1e6:.2f}",
                          _fmt_err(r["u_err"])])
            ratio = f"{r['u_tris'] / r['a_tris']:.1f}x"
        lines.append(["", f"uniform equal triangles n={r['n_tri']}", f"{r['t_tris']:,}",
                      "", "", _fmt_err(r["t_err"])])
        lines.append(["", "uniform / adaptive triangles at equal error", ratio, "", "", ""])
    bulk = [[r["scene"], f"{r['bulk'][1]:,}", f"{r['bulk'][2]:.3f}",
             f"{r['bulk'][1] / r['bulk'][2] / 1e6:.2f}"] for r in rows]
    bulk_head = ["scene", "uniform triangles", "time s", "Mtri/s"]
    _print_rows(lines, head, markdown, f"Dicing at {size} x {size}, dicing rate 1 px, "
                f"tolerance {TARGET_PX} px (equal error: uniform max error <= "
                "max(target, adaptive's))")
    print()
    _print_rows(bulk, bulk_head, markdown, "Bulk dicing throughput (uniform grid: positions, "
                "normals, tangents, topology)")


def _print_rows(lines, head, markdown, title):
    print(title)
    if markdown:
        print("| " + " | ".join(head) + " |")
        print("|" + "---|" * len(head))
        for ln in lines:
            print("| " + " | ".join(ln) + " |")
    else:
        widths = [max(len(str(x)) for x in col) for col in zip(head, *lines, strict=False)]
        for ln in [head] + lines:
            print("  ".join(str(x).ljust(w) for x, w in zip(ln, widths, strict=False)))


if __name__ == "__main__":
    main()
