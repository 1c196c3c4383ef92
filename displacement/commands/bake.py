"""The ``pwc bake`` subcommand: bake a profile's displacement into normal, height and vector maps.

Registered through the ``pwc.commands`` entry point (``bake =
"displacement.commands.bake:register"``); ``pwc`` calls :func:`register` with its
subparsers and then ``args.func(args)``.
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

import numpy as np

from pwc.cli import add_profiles_option
from pwc.files import prepare_output, resolve_profile

__all__ = ["register", "undercut_runs"]

EXIT_ERRORS, EXIT_USAGE, EXIT_IO = 1, 2, 3

_DESCRIPTION = """\
Bake the vector displacement of a molding profile (Handbook Listing 15.8,
displace_with_pwc, on the unit square) into image maps, so the molding can be
rendered cheaply as a bump or normal map or re-applied as vector displacement.

  normal map  tangent-space normal of the displaced surface, stored as 0.5 + 0.5 n
              (red = u tangent, green = v tangent (OpenGL), blue = normal); decode
              with bump_normal (Listing 13.16) at its defaults
  height map  the displacement's component along the surface normal; EXR keeps the
              heights, PNG stores them rescaled to [0, 1] (the range is printed)
  vector map  the displacement vector, OpenEXR only (signed); tangent space
              (R = u tangent, G = v tangent, B = normal) or object space

Bit depths: 8 or 16 for .png, half or float for .exr; default 16 for PNG and float
for EXR.  Maps are square, --size pixels a side; row 0 is the top (v = 1)."""

_EPILOG = """\
examples:
  pwc bake profiles/ornament_2.pwc --normal-map out/ornament_2_n.png --size 512
  pwc bake profiles/torus.pwc --along u --repeat 4 --height-map h.exr --vector-map d.exr
  pwc bake profiles/bead.pwc --normal-map n.exr --bits half --convention directx"""


def register(subparsers) -> argparse.ArgumentParser:
    """Add ``bake`` to the ``pwc`` command's subparsers and return its parser."""
    p = subparsers.add_parser(
        "bake",
        help="bake a profile's displacement into normal, height and vector maps",
        description=_DESCRIPTION,
        epilog=_EPILOG,
        formatter_class=argparse.RawDescriptionHelpFormatter,
    )
    p.add_argument("profile", metavar="PROFILE.pwc",
                   help="the pwc-list to bake: a file, or a name (ornament_2)")
    p.add_argument(
        "--along", choices=("u", "v"), default="v",
        help="texture direction the profile runs along (Listing 15.7 along_u / along_v; "
             "default: v)",
    )
    p.add_argument(
        "--repeat", type=float, default=None, metavar="R",
        help="copies of the profile across the map, wrapping (Listing 14.27's repeat); "
             "default: one copy, not wrapped (Listing 15.8)",
    )
    p.add_argument("--normal-map", metavar="OUT", help="tangent-space normal map (.png or .exr)")
    p.add_argument("--height-map", metavar="OUT", help="height map (.png or .exr)")
    p.add_argument("--vector-map", metavar="OUT.exr", help="vector displacement map (.exr)")
    p.add_argument(
        "--size", type=int, default=1024, metavar="PX",
        help="map width and height in pixels (default 1024)",
    )
    p.add_argument(
        "--bits", choices=("8", "16", "half", "float"), default=None,
        help="bit depth: 8 or 16 for PNG, half or float for EXR "
             "(default: 16 for PNG, float for EXR)",
    )
    p.add_argument(
        "--space", choices=("tangent", "object"), default="tangent",
        help="space of the vector map (default: tangent)",
    )
    p.add_argument(
        "--convention", choices=("opengl", "directx"), default="opengl",
        help="normal-map green channel: +v (opengl, default) or -v (directx)",
    )
    p.add_argument(
        "--step", type=float, default=0.25, metavar="TEXELS",
        help="finite-difference step for the displaced normal, in texels (default 0.25)",
    )
    add_profiles_option(p)
    p.set_defaults(func=_run)
    return p


def _fail(message: str, status: int) -> SystemExit:
    print(f"pwc bake: error: {message}", file=sys.stderr)
    return SystemExit(status)


def _bits_for(path: Path, bits: str | None, what: str):
    ext = path.suffix.lower()
    if ext not in (".png", ".exr"):
        raise _fail(f"{what} {path}: unsupported format {ext or '(none)'}; use .png or .exr",
                    EXIT_USAGE)
    if bits is None:
        return 16 if ext == ".png" else "float"
    value = int(bits) if bits in ("8", "16") else bits
    if ext == ".png" and value not in (8, 16):
        raise _fail(f"{what} {path}: PNG stores 8 or 16 bits, not {bits}; use .exr", EXIT_USAGE)
    if ext == ".exr" and value not in ("half", "float"):
        raise _fail(f"{what} {path}: OpenEXR stores half or float, not {bits}; use .png",
                    EXIT_USAGE)
    return value


def _run(args: argparse.Namespace) -> int:
    """Carry out ``pwc bake``; returns the exit status (raises SystemExit on errors)."""
    outputs = [
        (args.normal_map, "normal map"),
        (args.height_map, "height map"),
        (args.vector_map, "vector map"),
    ]
    if not any(path for path, _ in outputs):
        raise _fail("nothing to write: give --normal-map, --height-map and/or --vector-map",
                    EXIT_USAGE)
    if not 1 <= args.size <= 16384:
        raise _fail(f"--size must be between 1 and 16384 pixels, got {args.size}", EXIT_USAGE)
    if args.repeat is not None and not (0 < args.repeat < float("inf")):
        raise _fail(f"--repeat must be a number > 0, got {args.repeat}", EXIT_USAGE)
    if not 0 < args.step <= 1:
        raise _fail(f"--step must be in (0, 1] texels, got {args.step}", EXIT_USAGE)
    bits = {}
    for path, what in outputs:
        if path:
            bits[what] = _bits_for(Path(path), args.bits, what)
    if args.vector_map and Path(args.vector_map).suffix.lower() != ".exr":
        raise _fail(f"vector map {args.vector_map}: signed vectors need OpenEXR (.exr)",
                    EXIT_USAGE)
    try:
        profile = resolve_profile(args.profile, (".",), args.profiles)
        for path, what in outputs:
            if path:
                prepare_output(path, what)
    except OSError as e:  # no such profile, or an output that cannot be written
        raise _fail(str(e), EXIT_IO) from None

    import pwc
    from displacement import bake as baking
    from displacement.pwc_fields import displace_with_pwc

    try:
        curve = pwc.load(profile)
    except pwc.PwcError as e:
        print(str(e), file=sys.stderr)
        raise _fail(f"{profile}: the pwc-list has errors", EXIT_ERRORS) from None
    try:
        field = displace_with_pwc(curve, direction=f"along_{args.along}", repeat=args.repeat)
        maps = baking.bake(field, None, args.size, step=args.step)
    except ValueError as e:
        raise _fail(f"{profile}: {e}", EXIT_ERRORS) from None
    repeat = "" if args.repeat is None else f", repeat {args.repeat:g}"
    print(f"baked {curve.name}: {args.size}x{args.size} along {args.along}{repeat} "
          f"in {maps.seconds:.2f} s")
    if args.normal_map or args.height_map:
        _warn_undercuts(maps.normal, args.along)
    try:
        if args.normal_map:
            path = baking.write_normal_map(args.normal_map, maps.normal, bits["normal map"],
                                           args.convention)
            print(f"  normal map  {path} ({bits['normal map']}, {args.convention})")
        if args.height_map:
            path, low, high = baking.write_height_map(args.height_map, maps.height,
                                                      bits["height map"])
            note = "" if path.suffix.lower() == ".exr" else f"; grey 0 = {low:.6g}, 1 = {high:.6g}"
            print(f"  height map  {path} ({bits['height map']}; heights {low:.6g} .. "
                  f"{high:.6g}{note})")
        if args.vector_map:
            vectors = maps.vector_tangent if args.space == "tangent" else maps.vector_object
            path = baking.write_vector_map(args.vector_map, vectors, args.space,
                                           bits["vector map"])
            print(f"  vector map  {path} ({bits['vector map']}, {args.space} space)")
    except OSError as e:
        raise _fail(str(e), EXIT_IO) from None
    except ValueError as e:
        raise _fail(str(e), EXIT_USAGE) from None
    return 0


def undercut_runs(normal: np.ndarray, along: str) -> list[tuple[int, int]]:
    """Runs ``(first, last)`` of map rows (``along`` v) or columns (u) where the displaced
    surface faces into the base surface (tangent-space normal z < 0): undercuts of the
    profile, which a normal or height map cannot show.

    Examples
    --------
    >>> n = np.zeros((5, 2, 3)); n[..., 2] = 1.0; n[1:3, 0, 2] = -0.5; n[4, 1, 2] = -1.0
    >>> undercut_runs(n, "v")
    [(1, 2), (4, 4)]
    """
    inward = normal[..., 2] < -1e-6  # below rounding: edge-on steps have z = 0 exactly
    hit = inward.any(axis=1 if along == "v" else 0)
    idx = np.flatnonzero(hit)
    if idx.size == 0:
        return []
    breaks = np.flatnonzero(np.diff(idx) > 1)
    firsts = np.concatenate([idx[:1], idx[breaks + 1]])
    lasts = np.concatenate([idx[breaks], idx[-1:]])
    return [(int(a), int(b)) for a, b in zip(firsts, lasts, strict=True)]


def _warn_undercuts(normal: np.ndarray, along: str) -> None:
    runs = undercut_runs(normal, along)
    if not runs:
        return
    size = normal.shape[0] if along == "v" else normal.shape[1]
    what = "rows" if along == "v" else "columns"

    def coord(i):  # row 0 is the top (v = 1); column 0 is u = 0
        c = (i + 0.5) / size
        return 1.0 - c if along == "v" else c

    parts = [f"{a}\u2013{b} ({along} {min(coord(a), coord(b)):.3f}\u2013"
             f"{max(coord(a), coord(b)):.3f})" if b > a else f"{a} ({along} {coord(a):.3f})"
             for a, b in runs]
    print(f"pwc bake: warning: the displaced surface faces into the base surface in {what} "
          f"{', '.join(parts)}: the profile has undercuts there, which a normal or height "
          "map cannot show (it can only tilt the surface); render them as true displacement, "
          "or bake --vector-map", file=sys.stderr)
