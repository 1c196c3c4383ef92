"""Bake-then-decode accuracy of normal maps against map resolution and bit depth, with time.

For each field, resolution (64 .. 1024) and bit depth (8, 16, half, float) this bakes the
field's tangent-space normal map (:func:`displacement.bake.bake`), writes it to a real
file (PNG 8/16-bit, EXR half/float) and reads it back, decodes it with Listing 13.16's
``bump_normal`` at random uv points (bilinear lookups, so between texel centres too) and
prints the angle to the exact displaced normal: mean, 99th percentile and maximum in
degrees, with the bake, write+read and decode times.

Fields (on the unit square):

* ``sinusoid``: ``D = a sin(2 pi k u) sin(2 pi m v) N`` with a = 0.02, k = 3, m = 2
  (slopes up to 21 degrees); exact normal ``normalize(-h_u, -h_v, 1)``.
* ``ornament_2`` (when ``displacement.pwc_fields`` and ``pwc`` are importable):
  ``displace_with_pwc(profiles/ornament_2.pwc, "along_v")``, the displaced point is
  ``(u, y(v), x(v))`` and its exact normal ``normalize(0, -x'(v), y'(v))`` from the
  curve's derivative.  The profile has creases (normals jump at the knots), so samples
  are split: *creases* = within 2 texels of a knot; of the others, *walls* = where the
  exact normal lies in the base surface's horizon (``|normal.z| < HORIZON_MIN_COS``: a
  depth change at constant run, ``y' = 0``; the horizon rule returns it 0.57 degrees
  above the horizon), *undercuts* = where it points below the horizon (``y' < 0``,
  arcs turning back), which no bump normal can represent, and *smooth* = the rest.

Run: ``python benchmarks/bake_roundtrip.py [--sizes 64 128 256 512 1024] [--samples N]``.
"""

from __future__ import annotations

import argparse
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

from displacement.bake import angle_between, bake, write_normal_map
from displacement.bump import HORIZON_MIN_COS, bump_normal
from displacement.surfaces import UnitSquare
from displacement.textures import read_texture

ROOT = Path(__file__).resolve().parent.parent
BITS = (8, 16, "half", "float")

A, K, M = 0.02, 3, 2


def sinusoid_field(state):
    """``a sin(2 pi k u) sin(2 pi m v)`` along the normal."""
    u, v = state.uv[:, 0], state.uv[:, 1]
    h = A * np.sin(2 * np.pi * K * u) * np.sin(2 * np.pi * M * v)
    return state.normal * h[:, None]


def sinusoid_normal(uv):
    u, v = uv[:, 0], uv[:, 1]
    hu = A * 2 * np.pi * K * np.cos(2 * np.pi * K * u) * np.sin(2 * np.pi * M * v)
    hv = A * 2 * np.pi * M * np.sin(2 * np.pi * K * u) * np.cos(2 * np.pi * M * v)
    n = np.stack([-hu, -hv, np.ones_like(hu)], axis=1)
    return n / np.linalg.norm(n, axis=1, keepdims=True)


def ornament_case():
    """(field, exact normal, knots) for ornament_2 along v, or None if unavailable."""
    try:
        import pwc
        from displacement.pwc_fields import displace_with_pwc
    except ImportError as e:  # the profile field is optional for this benchmark
        print(f"(ornament_2 skipped: {e})", file=sys.stderr)
        return None
    curve = pwc.load(ROOT / "profiles" / "ornament_2.pwc")
    field = displace_with_pwc(curve, "along_v")

    def normal(uv):
        d = curve.derivative(uv[:, 1])
        n = np.stack([np.zeros(len(uv)), -d[:, 0], d[:, 1]], axis=1)
        return n / np.linalg.norm(n, axis=1, keepdims=True)

    return field, normal, np.asarray(curve.t)


def stats(angles: np.ndarray) -> str:
    if len(angles) == 0:
        return f"{'-':>8} {'-':>8} {'-':>8}"
    return f"{angles.mean():8.4f} {np.percentile(angles, 99):8.4f} {angles.max():8.4f}"


def run(sizes, samples: int, seed: int = 1) -> list[str]:
    rng = np.random.default_rng(seed)
    uv = rng.random((samples, 2))
    state = UnitSquare().state_at_uv(uv)
    cases = [("sinusoid", sinusoid_field, sinusoid_normal, None)]
    orn = ornament_case()
    if orn is not None:
        cases.append(("ornament_2", *orn))
    lines = [
        "| field | size | bits | samples | mean deg | p99 deg | max deg | bake s | write+read s "
        "| decode s |",
        "|---|---|---|---|---|---|---|---|---|---|",
    ]
    with tempfile.TemporaryDirectory() as tmp:
        for name, field, reference, knots in cases:
            exact = reference(uv)
            groups = {"": np.ones(samples, bool)}
            if knots is not None:
                wall = np.abs(exact[:, 2]) < HORIZON_MIN_COS
                undercut = exact[:, 2] <= -HORIZON_MIN_COS
            for size in sizes:
                maps = bake(field, None, size)
                if knots is not None:
                    near = np.min(np.abs(uv[:, 1:2] - knots[None, :]), axis=1) < 2.0 / size
                    groups = {
                        " smooth": ~near & ~wall & ~undercut,
                        " walls": ~near & wall,
                        " undercuts": ~near & undercut,
                        " creases": near,
                    }
                for bits in BITS:
                    ext = ".png" if bits in (8, 16) else ".exr"
                    path = Path(tmp) / f"{name}_{size}_{bits}{ext}"
                    t0 = time.perf_counter()
                    write_normal_map(path, maps.normal, bits)
                    texture = read_texture(path)
                    t1 = time.perf_counter()
                    decoded = bump_normal(state, texture)
                    t2 = time.perf_counter()
                    angles = angle_between(decoded, exact)
                    for label, mask in groups.items():
                        line = (
                            f"| {name}{label} | {size} | {bits} | {int(mask.sum())} | "
                            + " | ".join(stats(angles[mask]).split())
                            + f" | {maps.seconds:.2f} | {t1 - t0:.2f} | {t2 - t1:.3f} |"
                        )
                        lines.append(line)
                        print(line, flush=True)
    return lines


def main(argv=None) -> int:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--sizes", type=int, nargs="+", default=[64, 128, 256, 512, 1024])
    p.add_argument("--samples", type=int, default=100_000)
    args = p.parse_args(argv)
    print(
        "| field | size | bits | samples | mean deg | p99 deg | max deg | bake s "
        "| write+read s | decode s |"
    )
    print("|---|---|---|---|---|---|---|---|---|---|")
    run(args.sizes, args.samples)
    return 0


if __name__ == "__main__":
    sys.exit(main())
