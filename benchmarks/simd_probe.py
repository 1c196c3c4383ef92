"""What SIMD shading would buy in numba: one diffuse vertex's shading math, per lane as
the megakernel runs it, against lanes in a loop that LLVM vectorizes.

Run ``python benchmarks/simd_probe.py`` (``--quick`` for a smoke run).  The math is a
diffuse path vertex's: the shading frame from a normal and a tangent, next-event
estimation toward a light point (distance, cosines, pdfs, the power heuristic) and a
cosine-weighted direction (Shirley's concentric map, so a sine and a cosine).  It is
written once (branch-free, in selects: :func:`_make_shade`), and run three ways over
lanes held as structure of arrays, a block of 4096 lanes that stays in the caches:

* ``per-lane call``: a loop calling a kernel per lane, as the path kernel calls its
  helpers (one lane at a time, arguments and results through numba's calling
  convention);
* ``lane loop``: the same code inlined into the loop over lanes, which LLVM's loop
  vectorizer turns into AVX-512 (or AVX2) instructions where it can; libm's ``sin`` and
  ``cos`` stay calls, one lane at a time (pip's llvmlite has no SVML);
* ``lane loop, polynomial sincos``: the same with a polynomial sine and cosine, which
  vectorize (as Dr.Jit's own do in Mitsuba's LLVM variant).

All in float64 (the kernels' type; numba would promote float32 lanes to float64 at the
first Python constant).

Printed: nanoseconds a lane (the best of five), the speed-up over the per-lane call,
the largest difference from the per-lane float64 results (the accuracy paid), and
whether the loop holds packed square roots (``vsqrtpd``/``vsqrtps``: vectorized).
This is a probe of code shape, not of the renderer: gathers of hit data, divergent
materials and Embree's calls are what a real lane-parallel core adds.
"""

from __future__ import annotations

import argparse
import math
import sys
import time

import numpy as np
from numba import njit

INV_PI = 1.0 / math.pi
QUARTER_PI = 0.25 * math.pi


@njit(inline="always", fastmath=True)
def _poly_sincos(p):
    """sin and cos of p in [-pi/4, pi/4] by their Taylor series to degree 13 / 12
    (error below 1e-12 there)."""
    x2 = p * p
    s = p * (1.0 + x2 * (-1.0 / 6.0 + x2 * (1.0 / 120.0 + x2 * (-1.0 / 5040.0 + x2 * (
        1.0 / 362880.0 + x2 * (-1.0 / 39916800.0 + x2 / 6227020800.0))))))
    c = 1.0 + x2 * (-0.5 + x2 * (1.0 / 24.0 + x2 * (-1.0 / 720.0 + x2 * (
        1.0 / 40320.0 + x2 * (-1.0 / 3628800.0 + x2 / 479001600.0)))))
    return s, c


@njit(inline="always")
def _libm_sincos(p):
    return math.sin(p), math.cos(p)


def _make_shade(sincos):
    """The vertex's math with ``sincos`` of an angle in [-pi/4, pi/4]."""

    @njit(inline="always", error_model="numpy")
    def shade(nx, ny, nz, tx, ty, tz, dx, dy, dz, u1, u2, lx, ly, lz, lnx, lny, lnz):
        """(next-event contribution, sampled direction xyz, its pdf)."""
        d = tx * nx + ty * ny + tz * nz
        sx, sy, sz = tx - d * nx, ty - d * ny, tz - d * nz
        inv = 1.0 / math.sqrt(sx * sx + sy * sy + sz * sz)
        sx, sy, sz = sx * inv, sy * inv, sz * inv
        qx, qy, qz = ny * sz - nz * sy, nz * sx - nx * sz, nx * sy - ny * sx
        woz = -(dx * nx + dy * ny + dz * nz)
        d2 = lx * lx + ly * ly + lz * lz
        il = 1.0 / math.sqrt(d2)
        cos_i = (lx * nx + ly * ny + lz * nz) * il
        cos_l = -(lx * lnx + ly * lny + lz * lnz) * il
        pl = d2 / max(cos_l, 1e-8)
        pb = max(cos_i, 0.0) * INV_PI
        mis = pl * pl / (pl * pl + pb * pb)
        lit = (cos_i > 0.0) & (woz > 0.0) & (cos_l > 0.0)
        contrib = INV_PI * cos_i * mis / pl if lit else 0.0
        # concentric map: phi = pi/4 t where |a| > |b|, else pi/2 - pi/4 t, so the
        # angle p = +-pi/4 t stays in [-pi/4, pi/4] and the second case is turned by pi/2
        a, b = 2.0 * u1 - 1.0, 2.0 * u2 - 1.0
        wide = abs(a) > abs(b)
        r = a if wide else b
        t = (b if wide else a) / r if r != 0.0 else 0.0
        sn, cs = sincos(QUARTER_PI * t if wide else -QUARTER_PI * t)
        x = r * (cs if wide else -sn)
        y = r * (sn if wide else cs)
        z = math.sqrt(max(1.0 - x * x - y * y, 0.0))
        return (contrib, x * sx + y * qx + z * nx, x * sy + y * qy + z * ny,
                x * sz + y * qz + z * nz, z * INV_PI)

    return shade


def _make_loop(shade):
    @njit(error_model="numpy")
    def loop(A, out, reps):
        for _ in range(reps):
            for i in range(A.shape[1]):
                c, ox, oy, oz, p = shade(A[0, i], A[1, i], A[2, i], A[3, i], A[4, i],
                                         A[5, i], A[6, i], A[7, i], A[8, i], A[9, i],
                                         A[10, i], A[11, i], A[12, i], A[13, i], A[14, i],
                                         A[15, i], A[16, i])
                out[0, i], out[1, i], out[2, i], out[3, i], out[4, i] = c, ox, oy, oz, p

    return loop


def lanes(n: int) -> np.ndarray:
    """(17, n) lanes: unit normals, tangents, view directions, two uniforms, the light
    point relative to the vertex and the light's normal."""
    rng = np.random.default_rng(1)
    a = rng.normal(size=(17, n))
    a[0:3] /= np.linalg.norm(a[0:3], axis=0)
    a[6:9] /= np.linalg.norm(a[6:9], axis=0)
    a[9:11] = rng.random((2, n))
    a[11:14] *= 3.0
    a[14:17] /= np.linalg.norm(a[14:17], axis=0)
    return a


def timed(loop, a, reps: int) -> tuple[float, np.ndarray]:
    """(ns a lane, the results)."""
    out = np.zeros((5, a.shape[1]))
    loop(a, out, 1)
    best = math.inf
    for _ in range(5):
        t = time.perf_counter()
        loop(a, out, reps)
        best = min(best, time.perf_counter() - t)
    return best / (reps * a.shape[1]) * 1e9, out


def packed_sqrt(loop) -> bool:
    asm = "".join(loop.inspect_asm().values())
    return "vsqrtpd" in asm or "vsqrtps" in asm


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--lanes", type=int, default=4096, help="lanes in the block")
    ap.add_argument("--reps", type=int, default=200, help="passes over the block per timing")
    ap.add_argument("--quick", action="store_true", help="a smoke run")
    args = ap.parse_args(argv)
    if args.quick:
        args.lanes, args.reps = 256, 2
    libm = _make_shade(_libm_sincos)
    per_lane = njit(inline="never", error_model="numpy")(libm.py_func)
    variants = [
        ("per-lane call (as the megakernel)", _make_loop(per_lane)),
        ("lane loop", _make_loop(libm)),
        ("lane loop, polynomial sincos", _make_loop(_make_shade(_poly_sincos))),
    ]
    a = lanes(args.lanes)
    base, ref = None, None
    print(f"# one diffuse vertex's shading math, {args.lanes} lanes x {args.reps} passes, "
          f"best of 5; error: largest |difference| from the per-lane float64 results")
    print("| variant | ns a lane | speed-up | error | packed sqrt |")
    print("|---|---|---|---|---|")
    for name, loop in variants:
        ns, out = timed(loop, a, args.reps)
        if base is None:
            base, ref = ns, out
        err = float(np.max(np.abs(out - ref)))
        if not np.isfinite(out).all():
            raise SystemExit(f"{name}: non-finite results")
        print(f"| {name} | {ns:.2f} | {base / ns:.1f}x | {err:.1e} | "
              f"{'yes' if packed_sqrt(loop) else 'no'} |")
    return 0


if __name__ == "__main__":
    sys.exit(main())
