"""The ``pwc view`` subcommand: inspect a profile's displacement in a PyVista window.

Registered through the ``pwc.commands`` entry point (``view =
"displacement.commands.view:register"``); ``pwc`` calls :func:`register` with its
subparsers and then ``args.func(args)``.  PyVista is imported only when the command runs.
"""

from __future__ import annotations

import argparse
import math
import os
import sys
import time
from pathlib import Path

from pwc.cli import add_profiles_option
from pwc.files import prepare_output, resolve_profile

__all__ = ["register"]

EXIT_OK, EXIT_ERRORS, EXIT_USAGE, EXIT_IO = 0, 1, 2, 3

_SURFACES = ("square", "plane", "sphere", "cylinder", "torus", "cube")
_IMAGE_TYPES = (".png", ".jpg", ".jpeg", ".bmp", ".tif", ".tiff")

_DESCRIPTION = """\
Show a molding profile as the vector displacement of a base surface, diced for the
view (render-time tessellation) and textured with the Handbook's grid material
(Listing 14.6), whose cells are scaled by the curve's length (NAME_length, Listing
15.9) so that they stay square where the displacement stretches texture space.

  --along u|v          displace_with_pwc along u or v (Listing 15.8)
  --along radial       pwc_angular_displace (Listing 15.14): a solid of revolution
                       about +y (on the unit square: Figure 15.23)
  --along double SWEEP double_pwc (Listing 15.20): the profile revolved at a distance
                       that follows the SWEEP curve

The window shows the profile itself (red) beside the surface, displacement vectors
(blue arrows, base point to displaced point) and, on request, the shading normals of
the diced mesh (orange).  Sliders change the dicing rate and the repeat count; both
re-dice the surface for the current view, as does the key 'd' after the view
has moved.  Check boxes toggle vectors, normals and the triangles' edges.

--screenshot OUT.png renders off-screen (no display needed) and exits."""

_EPILOG = """\
examples:
  pwc view profiles/ornament_2.pwc
  pwc view profiles/tee.pwc --along u --repeat 3 --grid-count 8
  pwc view profiles/corinthian.pwc --along radial --screenshot capital.png --size 800 800
  pwc view profiles/torus.pwc --along double profiles/doric_flutes.pwc --radius-offset 0.5"""


def register(subparsers) -> argparse.ArgumentParser:
    """Add ``view`` to the ``pwc`` command's subparsers and return its parser."""
    p = subparsers.add_parser(
        "view",
        help="inspect a profile's displacement interactively (PyVista)",
        description=_DESCRIPTION,
        epilog=_EPILOG,
        formatter_class=argparse.RawDescriptionHelpFormatter,
    )
    p.add_argument("profile", metavar="PROFILE.pwc", nargs="?",
                   help="the pwc-list to show: a file, or a name (ornament_2)")
    p.add_argument("--surface", choices=_SURFACES, default="square",
                   help="base surface (default: square, the Handbook's unit square)")
    p.add_argument("--along", nargs="+", default=["v"],
                   metavar=("{u,v,radial,double}", "SWEEP.pwc"),
                   help="how the profile displaces the surface (default: v); 'double' "
                        "takes the sweep curve's file as a second argument")
    p.add_argument("--repeat", type=float, default=None, metavar="R",
                   help="copies of the profile across the surface, along u or v only "
                        "(Listing 14.27's repeat); default: one copy (Listing 15.8)")
    p.add_argument("--grid-count", type=float, default=4.0, metavar="N",
                   help="grid cells per uv unit before the length compensation "
                        "(default 4)")
    p.add_argument("--no-normalize-grid", action="store_true",
                   help="do not scale the grid by the curve's length (Listing 15.16 draws "
                        "the Corinthian capital with a plain grid(float2(50.0)))")
    p.add_argument("--dicing-rate", type=float, default=1.0, metavar="PX",
                   help="dicing rate: pixels between the dicer's samples on screen "
                        "(default 1)")
    p.add_argument("--tolerance", type=float, default=0.5, metavar="PX",
                   help="screen-space tolerance of the diced surface (default 0.5)")
    p.add_argument("--radius-offset", type=float, default=0.0, metavar="R",
                   help="added to the distance from the axis (radial: Listing 15.13's "
                        "radius; double: Listing 15.20's radius_offset); default 0")
    p.add_argument("--normals", action="store_true", help="show the normals at first")
    vectors = p.add_mutually_exclusive_group()
    vectors.add_argument("--vectors", dest="vectors", action="store_const", const=True,
                         default=None, help="show the displacement vectors at first "
                         "(default: along u or v only)")
    vectors.add_argument("--no-vectors", dest="vectors", action="store_const", const=False,
                         help="hide the displacement vectors at first")
    p.add_argument("--screenshot", metavar="OUT.png",
                   help="render off-screen to this image and exit (no window)")
    p.add_argument("--size", type=int, nargs=2, default=(1024, 768), metavar=("W", "H"),
                   help="window or image size in pixels (default 1024 768)")
    add_profiles_option(p)
    p.set_defaults(func=_run)
    return p


def _error(message: str, status: int) -> int:
    print(f"pwc view: error: {message}", file=sys.stderr)
    return status


def _has_display() -> bool:
    if not sys.platform.startswith("linux"):
        return True
    return bool(os.environ.get("DISPLAY") or os.environ.get("WAYLAND_DISPLAY"))


def _load(path: str, extra=()):
    """Compile a .pwc file or named profile: (curve, None) or (None, exit status) after
    printing why."""
    import pwc

    try:
        p = resolve_profile(path, (".",), extra)
    except OSError as e:
        return None, _error(str(e), EXIT_IO)
    try:
        return pwc.load(p), None
    except pwc.PwcError as e:
        print(str(e), file=sys.stderr)
        return None, EXIT_ERRORS
    except OSError as e:
        return None, _error(f"{path}: cannot read: {e.strerror or e}", EXIT_IO)


def _check_arguments(args) -> tuple[str, str | None, int | None]:
    """Validate the flags; returns (along, sweep file, error status or None)."""
    mode, *rest = args.along
    if args.profile is None:
        # '--along double SWEEP.pwc PROFILE.pwc' and '--along v PROFILE.pwc': argparse
        # gives --along every file; the last one is the profile
        if len(rest) > (1 if mode == "double" else 0):
            args.profile = rest.pop()
        else:
            return mode, None, _error("give the profile to show: pwc view PROFILE.pwc",
                                      EXIT_USAGE)
    if mode not in ("u", "v", "radial", "double"):
        return mode, None, _error(f"--along {mode}: choose u, v, radial or double", EXIT_USAGE)
    if mode == "double" and len(rest) != 1:
        return mode, None, _error("--along double needs the sweep curve's file: "
                                  "--along double SWEEP.pwc", EXIT_USAGE)
    if mode != "double" and rest:
        return mode, None, _error(f"--along {mode} takes no file (only 'double' takes a "
                                  f"sweep curve), got {' '.join(rest)}", EXIT_USAGE)
    checks = [
        (args.repeat is not None and mode not in ("u", "v"),
         f"--repeat applies to --along u or v, not {mode}"),
        (args.repeat is not None and not (0 < args.repeat < math.inf),
         f"--repeat must be a number > 0, got {args.repeat}"),
        (args.radius_offset != 0.0 and mode in ("u", "v"),
         f"--radius-offset applies to --along radial or double, not {mode}"),
        (not math.isfinite(args.radius_offset),
         f"--radius-offset must be finite, got {args.radius_offset}"),
        (not (0 < args.grid_count < math.inf),
         f"--grid-count must be a number > 0, got {args.grid_count}"),
        (not (0 < args.dicing_rate < math.inf),
         f"--dicing-rate must be a number of pixels > 0, got {args.dicing_rate}"),
        (not (0 < args.tolerance < math.inf),
         f"--tolerance must be a number of pixels > 0, got {args.tolerance}"),
        (not all(16 <= s <= 8192 for s in args.size),
         f"--size must be between 16 and 8192 pixels, got {args.size[0]} {args.size[1]}"),
    ]
    for bad, message in checks:
        if bad:
            return mode, None, _error(message, EXIT_USAGE)
    return mode, (rest[0] if rest else None), None


def _run(args: argparse.Namespace) -> int:
    """Carry out ``pwc view``; returns the exit status."""
    along, sweep_path, status = _check_arguments(args)
    if status is not None:
        return status
    out = Path(args.screenshot) if args.screenshot else None
    if out is not None:
        if out.suffix.lower() not in _IMAGE_TYPES:
            return _error(f"--screenshot {out}: unsupported image type "
                          f"{out.suffix or '(none)'}; use .png (or .jpg, .bmp, .tif)",
                          EXIT_USAGE)
        try:
            prepare_output(out, "--screenshot")
        except OSError as e:
            return _error(str(e), EXIT_IO)
    elif not _has_display():
        return _error("no display to open a window on (DISPLAY is not set); use "
                      "--screenshot OUT.png to render off-screen", EXIT_IO)

    curve, status = _load(args.profile, args.profiles)
    if curve is None:
        return status
    sweep = None
    if sweep_path is not None:
        sweep, status = _load(sweep_path, args.profiles)
        if sweep is None:
            return status

    from displacement import view

    options = dict(surface=args.surface, along=along, sweep=sweep, repeat=args.repeat,
                   grid_count=args.grid_count, dicing_rate=args.dicing_rate,
                   radius_offset=args.radius_offset, tolerance=args.tolerance,
                   normalize_grid=not args.no_normalize_grid, show_normals=args.normals,
                   show_vectors=args.vectors)
    size = tuple(args.size)
    start = time.perf_counter()
    try:
        if out is None:
            view.show(curve, size=size, **options)
            return EXIT_OK
        view.screenshot(out, curve, size=size, **options)
    except ImportError as e:
        return _error(f"pwc view needs PyVista ({e}); install the viewer: "
                      "pip install 'pwc-workbench[viz]'", EXIT_IO)
    except ValueError as e:
        return _error(f"{args.profile}: {e}", EXIT_USAGE)
    except RuntimeError as e:
        return _error(f"rendering failed: {e}", EXIT_IO)
    except OSError as e:
        return _error(f"{out}: cannot write: {e.strerror or e}", EXIT_IO)
    print(f"wrote {out} ({size[0]}x{size[1]}, {curve.name} along {' '.join(args.along)}, "
          f"{time.perf_counter() - start:.2f} s)")
    return EXIT_OK
