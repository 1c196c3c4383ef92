"""What SIMD shading would buy in numba: one diffuse vertex's shading, per lane as the
megakernel runs it, against lanes in a loop that LLVM vectorizes.

Run ``python benchmarks/simd_probe.py`` (``--quick`` for a smoke run).  A diffuse path
vertex's shading, from the render core's own kernels: the shading frame
(:func:`render.df._kernel_common.frame_from_normal_tangent`), next-event estimation
toward a light point (distance, cosines, pdfs, the power heuristic
:func:`render.path._power`) and a cosine-weighted direction
(:func:`render.df._kernel_common.cosine_hemisphere`: Shirley's concentric map, so a
sine and a cosine).  It runs three ways over lanes held as structure of arrays, a
block of 4096 lanes that stays in the caches:

* ``per-lane call``: a loop calling a kernel per lane, which calls the core's kernels as
  the path kernel does (one lane at a time, arguments and results through numba's
  calling convention);
* ``lane loop``: the same kernels' code inlined into the loop over lanes, which LLVM's
  loop vectorizer turns into AVX-512 (or AVX2) instructions where it can; libm's
  ``sin`` and ``cos`` stay calls, one lane at a time (pip's llvmlite has no SVML);
* ``lane loop, polynomial sincos``: the same with a polynomial sine and cosine, which
  vectorize (as Dr.Jit's own do in Mitsuba's LLVM variant).

All in float64, the kernels' type.  Printed: nanoseconds a lane (the best of five), the
speed-up over the per-lane call, the largest difference from the per-lane results (the
accuracy paid), and whether the loop holds packed square roots (``vsqrtpd``:
vectorized).  This is a probe of code shape, not of the renderer: gathers of hit data,
divergent materials and Embree's calls are what a real lane-parallel core adds.
"""

from __future__ import annotations

import argparse
import math
import sys
import time
from pathlib import Path
from types import FunctionType, ModuleType

import numpy as np
from numba import njit

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

from render.df import _kernel_common as kc  # noqa: E402
from render.path import _power  # noqa: E402

INV_PI = 1.0 / math.pi
_SQRT_HALF = math.sqrt(0.5)


def _inlined(kernel, **names):
    """``kernel``'s own code compiled to be inlined into its caller (so that a loop over
    lanes can vectorize it), with ``names`` of its globals bound anew."""
    f = kernel.py_func
    g = FunctionType(f.__code__, {**f.__globals__, **names}, f.__name__, f.__defaults__)
    return njit(inline="always", error_model="numpy")(g)


@njit(inline="always")
def _poly_sincos(d):
    """sin and cos of d in [-pi/2, pi/2] by their Taylor series to degree 19 / 18
    (the next terms are below 4e-15 there)."""
    x2 = d * d
    s, c = 1.0, 1.0
    for k in range(9, 0, -1):  # Horner, unrolled by LLVM
        s = 1.0 - x2 / ((2 * k + 1) * (2 * k)) * s
        c = 1.0 - x2 / ((2 * k) * (2 * k - 1)) * c
    return d * s, c


@njit(inline="always")
def _poly_cos(x):
    """cos of x in [-pi/4, 3 pi/4] (the concentric map's angles): about pi/4."""
    s, c = _poly_sincos(x - 0.25 * math.pi)
    return _SQRT_HALF * (c - s)


@njit(inline="always")
def _poly_sin(x):
    """sin of x in [-pi/4, 3 pi/4]."""
    s, c = _poly_sincos(x - 0.25 * math.pi)
    return _SQRT_HALF * (s + c)


#: ``math`` for :func:`_inlined`, with the polynomial sine and cosine
POLY_MATH = ModuleType("poly_math")
POLY_MATH.sin, POLY_MATH.cos, POLY_MATH.sqrt = _poly_sin, _poly_cos, math.sqrt


def _make_shade(frame, cosine_hemisphere):
    """The vertex's shading with these frame and direction kernels."""

    @njit(inline="always", error_model="numpy")
    def shade(nx, ny, nz, tx, ty, tz, dx, dy, dz, u1, u2, lx, ly, lz, lnx, lny, lnz):
        """(next-event contribution, sampled direction xyz, its pdf)."""
        sx, sy, sz, qx, qy, qz = frame(nx, ny, nz, tx, ty, tz)
        woz = -(dx * nx + dy * ny + dz * nz)
        d2 = lx * lx + ly * ly + lz * lz
        il = 1.0 / math.sqrt(d2)
        cos_i = (lx * nx + ly * ny + lz * nz) * il
        cos_l = -(lx * lnx + ly * lny + lz * lnz) * il
        pl = d2 / max(cos_l, 1e-8)
        mis = _power(pl, max(cos_i, 0.0) * INV_PI)
        lit = (cos_i > 0.0) & (woz > 0.0) & (cos_l > 0.0)
        contrib = INV_PI * cos_i * mis / pl if lit else 0.0
        x, y, z = cosine_hemisphere(u1, u2)
        return (contrib, x * sx + y * qx + z * nx, x * sy + y * qy + z * ny,
                x * sz + y * qz + z * nz, z * INV_PI)

    return shade


def _inlined_kernels(math_module):
    """The frame and direction kernels inlined all the way down, over ``math_module``."""
    dot3 = _inlined(kc.dot3)
    unitize = _inlined(kc.unitize, dot3=dot3, math=math_module)
    frame = _inlined(kc.frame_from_normal_tangent, dot3=dot3, unitize=unitize,
                     frame_from_normal=_inlined(kc.frame_from_normal))
    return frame, _inlined(kc.cosine_hemisphere, math=math_module)


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
    return "vsqrtpd" in asm


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--lanes", type=int, default=4096, help="lanes in the block")
    ap.add_argument("--reps", type=int, default=200, help="passes over the block per timing")
    ap.add_argument("--quick", action="store_true", help="a smoke run")
    args = ap.parse_args(argv)
    if args.quick:
        args.lanes, args.reps = 256, 2
    as_is = _make_shade(kc.frame_from_normal_tangent, kc.cosine_hemisphere)
    variants = [
        ("per-lane call (as the megakernel)",
         _make_loop(njit(inline="never", error_model="numpy")(as_is.py_func))),
        ("lane loop", _make_loop(_make_shade(*_inlined_kernels(math)))),
        ("lane loop, polynomial sincos", _make_loop(_make_shade(*_inlined_kernels(POLY_MATH)))),
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
