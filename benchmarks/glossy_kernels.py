"""Compile time and ns per call of the glossy dfs' kernels (simple_glossy_bsdf,
backscattering_glossy_reflection_bsdf, microfacet_ggx_smith_bsdf), and the cost of one
node's albedo table.

Run from the repository root: ``python benchmarks/glossy_kernels.py`` (``--quick``: fewer
calls).  Cold compile: ``PWC_CACHE_DIR=$(mktemp -d) python benchmarks/glossy_kernels.py``.
"""

from __future__ import annotations

import argparse
import importlib
import math
import sys
import time
from pathlib import Path

import numba
import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))
t0 = time.perf_counter()
G = importlib.import_module("render.df.simple_glossy_bsdf")
B = importlib.import_module("render.df.backscattering_glossy_reflection_bsdf")
M = importlib.import_module("render.df.microfacet_ggx_smith_bsdf")
t_import = time.perf_counter() - t0


@numba.njit
def _bench_sample(kernel, P, flags, n, wox, woy, woz, T):
    acc = 0.0
    for k in range(n):
        r = kernel(P, 0, 0, flags, wox, woy, woz, (k * 0.7548776662466927) % 1.0,
                   (k * 0.5698402909980532) % 1.0, (k * 0.3247179572447460) % 1.0, T, 0)
        acc += r[4]
    return acc


@numba.njit
def _bench_eval(kernel, P, flags, n, wox, woy, woz, T):
    acc = 0.0
    for k in range(n):
        z = 2.0 * ((k * 0.3247179572447460) % 1.0) - 1.0
        s = math.sqrt(1.0 - z * z)
        p = 6.283185307179586 * ((k * 0.5698402909980532) % 1.0)
        acc += kernel(P, 0, 0, flags, wox, woy, woz, s * math.cos(p), s * math.sin(p), z,
                      T, 0)[3]
    return acc


@numba.njit
def _bench_dirs(n):
    acc = 0.0
    for k in range(n):
        z = 2.0 * ((k * 0.3247179572447460) % 1.0) - 1.0
        s = math.sqrt(1.0 - z * z)
        p = 6.283185307179586 * ((k * 0.5698402909980532) % 1.0)
        acc += s * math.cos(p) + s * math.sin(p) + z
    return acc


@numba.njit
def _bench_albedo(kernel, P, flags, n, T):
    acc = 0.0
    for k in range(n):
        z = (k * 0.3247179572447460) % 1.0
        acc += kernel(P, 0, 0, flags, math.sqrt(1.0 - z * z), 0.0, z, T, 0)[0]
    return acc


def _row(mod, **kw):
    sig = mod.SIGNATURE
    P = np.zeros((1, sig.width))
    P[0, sig.offset("roughness_u")] = kw.get("ru", 0.3)
    P[0, sig.offset("roughness_v")] = kw.get("rv", 0.3)
    P[0, sig.offset("tint") : sig.offset("tint") + 3] = 1.0
    P[0, sig.offset("tangent_u")] = 1.0
    at = sig.offset("multiscatter_tint")
    P[0, at:at + 3] = kw.get("ms", 0.0)
    if sig.context:
        P[0, sig.offset("ior_outside")] = 1.0
        P[0, sig.offset("ior_inside")] = kw.get("ior", 1.5)
    return P


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--quick", action="store_true", help="20k calls per kernel, not 2M")
    n = 20_000 if ap.parse_args().quick else 2_000_000
    print(f"numba {numba.__version__}; import of both modules {t_import:.2f} s")
    # first calls compile (or load from the cache) the kernels themselves
    t = time.perf_counter()
    for mod in (G, B, M):
        P = _row(mod)
        T = mod.albedo_table(P[0], 0)
        mod.eval_pdf(P, 0, 0, 0, 0.6, 0.0, 0.8, -0.6, 0.0, 0.8, T, 0)
        mod.sample(P, 0, 0, 0, 0.6, 0.0, 0.8, 0.3, 0.4, 0.5, T, 0)
        mod.albedo(P, 0, 0, 0, 0.6, 0.0, 0.8, T, 0)
    print(f"eval_pdf + sample + albedo of the three dfs, first calls: "
          f"{time.perf_counter() - t:.2f} s")
    t = time.perf_counter()
    G.albedo_table(_row(G, ru=0.37, rv=0.37, ior=1.47)[0], 2)
    print(f"node table, isotropic, reflect_transmit (4 columns): {time.perf_counter() - t:.2f} s")
    t = time.perf_counter()
    G.albedo_table(_row(G, ru=0.13, rv=0.41)[0], 0)
    print(f"node table, anisotropic, reflect (4 corners): {time.perf_counter() - t:.2f} s")
    _bench_dirs(10)
    t = time.perf_counter()
    _bench_dirs(n)
    dirs = (time.perf_counter() - t) / n * 1e9
    for name, mod, flags, kw in [
        ("simple_glossy reflect", G, 0, {}),
        ("simple_glossy reflect aniso", G, 0, {"ru": 0.1, "rv": 0.5}),
        ("simple_glossy reflect_transmit", G, 2, {}),
        ("simple_glossy transmit", G, 1, {}),
        ("backscattering", B, 0, {}),
        ("ggx smith reflect", M, 0, {}),
        ("ggx smith reflect, multiscatter", M, 0, {"ms": 1.0}),
        ("ggx smith reflect_transmit", M, 2, {}),
    ]:
        P = _row(mod, **kw)
        T = mod.albedo_table(P[0], flags)
        out = []
        for bench, kernel in ((_bench_eval, mod.eval_pdf), (_bench_sample, mod.sample)):
            bench(kernel, P, flags, 10, 0.6, 0.0, 0.8, T)
            t = time.perf_counter()
            bench(kernel, P, flags, n, 0.6, 0.0, 0.8, T)
            out.append((time.perf_counter() - t) / n * 1e9)
        _bench_albedo(mod.albedo, P, flags, 10, T)
        t = time.perf_counter()
        _bench_albedo(mod.albedo, P, flags, n, T)
        alb = (time.perf_counter() - t) / n * 1e9
        print(f"{name:32s} eval_pdf {out[0] - dirs:6.1f} ns  sample {out[1]:6.1f} ns  "
              f"albedo {alb:6.1f} ns")


if __name__ == "__main__":
    main()
