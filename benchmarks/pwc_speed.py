"""Benchmark the pwc translator: compile time and evaluation throughput, with accuracy.

Run:  python benchmarks/pwc_speed.py

Prints, next to each time, the error that goes with it:
* compile: a generated 10,000-point list (targets: < 0.5 s); the compiled length against
  an independent dense-sampling arc length;
* evaluate: positions per second on ornament 2 (target: >= 10 million/s) in float64 and
  float32 (MDL's float), the float32 position error against float64, and the speed-up of
  splitting the batch over both cores (numpy releases the GIL).
"""

from __future__ import annotations

import argparse
import time
from concurrent.futures import ThreadPoolExecutor
from pathlib import Path

import numpy as np

import pwc

ROOT = Path(__file__).resolve().parent.parent


def best_of(fn, repeat: int = 5) -> float:
    """Shortest wall time of several runs (the least disturbed by a noisy machine)."""
    times = []
    for _ in range(repeat):
        t0 = time.perf_counter()
        fn()
        times.append(time.perf_counter() - t0)
    return min(times)


def generated_list(n: int, seed: int = 0) -> str:
    """A relative list of n points mixing segments, arcs, cymas and flares."""
    rng = np.random.default_rng(seed)
    props = ["", " :angle 60", " :sag -.05", " :cyma_recta", " :cyma_reversa", " :flare"]
    lines = [":relative", "0 0"]
    for i in range(1, n):
        dx, dy = rng.uniform(0.1, 1.0, 2)
        lines.append(f"{dx:.4f} {dy:.4f}{props[i % len(props)] if i > 1 else ''}")
    return "\n".join(lines) + "\n"


def dense_length(curve: pwc.Curve, n: int = 1_000_001) -> float:
    """Arc length by summing chords of dense samples (knots included), Richardson-
    extrapolated from n and 2n samples: independent of the compiler's own lengths."""
    def chords(m: int) -> float:
        s = np.union1d(np.linspace(0, 1, m), curve.t)
        p = curve.evaluate(np.nextafter(s, 0))
        p[0] = curve.pt[0]
        return float(np.linalg.norm(np.diff(p, axis=0), axis=1).sum())
    return (4 * chords(2 * n) - chords(n)) / 3


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--points", type=int, default=10_000, help="size of the compiled list")
    ap.add_argument("--positions", type=int, default=4_000_000, help="evaluation batch")
    args = ap.parse_args()

    text = generated_list(args.points)
    t_compile = best_of(lambda: pwc.compile_text(text), 3)
    curve = pwc.compile_text(text)
    rel = abs(curve.length - dense_length(curve)) / curve.length
    print(f"compile  {args.points:>9,} points   {t_compile * 1e3:8.1f} ms  "
          f"(target < 500 ms)   length rel. error vs dense sampling {rel:.1e}")

    orn = pwc.load(ROOT / "profiles" / "ornament_2.pwc")
    s = np.random.default_rng(1).random(args.positions)
    s32 = s.astype(np.float32)
    t64 = best_of(lambda: orn.evaluate(s))
    t32 = best_of(lambda: orn.evaluate(s32))
    halves = np.array_split(s, 2)
    with ThreadPoolExecutor(2) as pool:
        t2 = best_of(lambda: list(pool.map(orn.evaluate, halves)))
    ref = orn.evaluate(s)
    err32 = np.abs(orn.evaluate(s32) - ref).max()
    # float32 error has two parts: s rounded to float32, and float32 tables/arithmetic
    err_pos = np.abs(orn.evaluate(s32.astype(np.float64)) - ref).max()
    n = args.positions
    print(f"evaluate ornament_2 ({orn.n} pw_points), {n:,} positions:")
    print(f"  float64 1 thread   {n / t64 / 1e6:6.1f} M/s  (target >= 10 M/s)")
    print(f"  float64 2 threads  {n / t2 / 1e6:6.1f} M/s  ({t64 / t2:.2f}x)")
    print(f"  float32 1 thread   {n / t32 / 1e6:6.1f} M/s  max position error vs float64 "
          f"{err32:.1e} (of which {err_pos:.1e} from rounding s itself; curve size 1)")


if __name__ == "__main__":
    main()
