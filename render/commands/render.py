"""The ``pwc render`` subcommand: render a TOML scene to a linear EXR and an sRGB PNG.

Registered through the ``pwc.commands`` entry point (``render =
"render.commands.render:register"``); ``pwc`` calls :func:`register` with its
subparsers and then ``args.func(args)``.  Errors in the scene are printed as
``file:line:col: message`` and exit with status 1; no traceback.
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

__all__ = ["register", "run"]

EXIT_OK, EXIT_ERRORS, EXIT_USAGE, EXIT_IO = 0, 1, 2, 3

_DESCRIPTION = """\
Render a scene file with the Embree path tracer.  The scene (TOML) gives the camera,
lights, objects with MDL material expressions as the Handbook prints them, and render
settings; the options below override its [render] table.  Output: linear float RGBA
OpenEXR with optional AOV layers, and an optional sRGB PNG preview."""

_EPILOG = """\
examples:
  pwc render gallery/scenes/fig_12_06.toml -o out.exr --png out.png
  pwc render scene.toml -o out.exr --time 30 --aov albedo,normal --denoise
  pwc render scene.toml -o out.exr --spp 256 --seed 7 --threads 2"""


def register(subparsers) -> argparse.ArgumentParser:
    """Add ``render`` to the ``pwc`` command's subparsers and return its parser."""
    p = subparsers.add_parser(
        "render",
        help="render a TOML scene to EXR/PNG (Embree path tracer)",
        description=_DESCRIPTION,
        epilog=_EPILOG,
        formatter_class=argparse.RawDescriptionHelpFormatter,
    )
    p.add_argument("scene", metavar="SCENE.toml", help="the scene file")
    p.add_argument(
        "-o", "--output", required=True, metavar="OUT.exr", help="linear RGBA EXR to write"
    )
    budget = p.add_mutually_exclusive_group()
    budget.add_argument("--spp", type=int, metavar="N", help="samples per pixel")
    budget.add_argument("--time", type=float, metavar="S", help="time budget in seconds")
    p.add_argument("--png", metavar="OUT.png", help="also write an sRGB preview")
    p.add_argument(
        "--aov",
        default="",
        metavar="LIST",
        help="comma-separated AOV layers: albedo,normal,depth,uv,object_id",
    )
    p.add_argument(
        "--denoise", action="store_true", help="denoise with Open Image Denoise (pyoidn)"
    )
    p.add_argument("--seed", type=int, metavar="N", help="random seed (same seed, same image)")
    p.add_argument("--max-depth", type=int, metavar="N", help="longest path (-1: unlimited)")
    p.add_argument("--resolution", type=int, nargs=2, metavar=("W", "H"), help="image size")
    p.add_argument("--threads", type=int, default=2, metavar="N", help="worker threads (default 2)")
    p.add_argument(
        "--path",
        choices=("auto", "general", "compiled"),
        default="auto",
        help="auto (default): the compiled kernels where the scene allows them (same image), "
        "else the general numpy path; compiled fails where the scene does not allow them",
    )
    p.add_argument("--half", action="store_true", help="write 16-bit half floats")
    p.add_argument("--quiet", action="store_true", help="no progress bar or summary")
    p.set_defaults(func=run)
    return p


def _error(message: str, status: int) -> int:
    print(f"pwc render: error: {message}", file=sys.stderr)
    return status


def run(args) -> int:
    """Execute ``pwc render`` with parsed arguments; returns the exit status."""
    from render.film import AOVS
    from render.integrator import render
    from render.scene import SceneError, load_scene

    aovs = [a.strip() for a in args.aov.split(",") if a.strip()]
    for a in aovs:
        if a not in AOVS:
            return _error(f"unknown AOV {a!r}: choose from {', '.join(AOVS)}", EXIT_USAGE)
    if args.spp is not None and args.spp < 1:
        return _error(f"--spp must be >= 1, got {args.spp}", EXIT_USAGE)
    if args.time is not None and not args.time > 0:
        return _error(f"--time must be > 0 seconds, got {args.time}", EXIT_USAGE)
    if args.threads < 1:
        return _error(f"--threads must be >= 1, got {args.threads}", EXIT_USAGE)
    if not str(args.output).lower().endswith(".exr"):
        return _error(f"the output must be an .exr file, got {args.output!r}", EXIT_USAGE)
    if args.png and not str(args.png).lower().endswith(".png"):
        return _error(f"--png must name a .png file, got {args.png!r}", EXIT_USAGE)
    if args.denoise:
        try:
            import pyoidn  # noqa: F401
        except ImportError:
            return _error("--denoise needs Open Image Denoise: pip install pyoidn", EXIT_USAGE)
    overrides = {"spp": args.spp, "time": args.time, "seed": args.seed, "max_depth": args.max_depth}
    if args.resolution:
        w, h = args.resolution
        if w < 1 or h < 1:
            return _error(f"--resolution must be positive, got {w} {h}", EXIT_USAGE)
    try:
        scene = load_scene(args.scene, overrides=overrides)
        if args.resolution:
            import dataclasses

            scene.settings.width, scene.settings.height = args.resolution
            scene.camera = dataclasses.replace(
                scene.camera, width=args.resolution[0], height=args.resolution[1]
            )
        film = render(
            scene,
            aovs=aovs,
            progress=not args.quiet,
            threads=args.threads,
            denoise=args.denoise,
            path=args.path,
        )
    except SceneError as e:
        print(str(e), file=sys.stderr)
        return EXIT_ERRORS
    except (ValueError, ImportError) as e:
        return _error(f"{args.scene}: {e}", EXIT_ERRORS)
    except OSError as e:
        return _error(f"{args.scene}: {e.strerror or e}", EXIT_IO)
    try:
        film.write_exr(args.output, aovs=aovs, half=args.half)
        if args.png:
            film.write_png(args.png)
    except OSError as e:
        return _error(f"cannot write the output: {e.strerror or e}", EXIT_IO)
    if not args.quiet:
        st = film.stats
        share = st["embree_time_s"] / (args.threads * st["time_s"]) if st["time_s"] else 0.0
        path = st["path"] if st["path"] == "compiled" else f"general: {st['general_reason']}"
        print(
            f"{Path(args.output)}: {film.width}x{film.height}, {st['spp']} spp in "
            f"{st['time_s']:.2f} s "
            f"({st['samples_per_s'] / 1e6:.2f} M samples/s, {share:.0%} of thread time in "
            f"Embree, {st['triangles']} triangles; {path} path)",
            file=sys.stderr,
        )
    return EXIT_OK
