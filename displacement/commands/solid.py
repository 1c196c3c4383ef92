"""``pwc solid``: build a watertight solid from a profile and write it as STL, 3MF or OBJ."""

from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path

from pwc.cli import add_profiles_option
from pwc.files import prepare_output, resolve_profile

__all__ = ["register"]

EXIT_ERRORS, EXIT_USAGE, EXIT_IO = 1, 2, 3

_DESCRIPTION = """\
Build a watertight solid for fabrication from a pwc profile and write it as STL, 3MF
or OBJ.  The profile's x is the depth out from the wall and its y the run up the
wall (normalized units = object units, y up).  An open profile is closed back to the
wall x = 0 by straight segments.

Exactly one shape:
  --extrude L      a straight molding: the cross-section extruded along z from 0 to L
  --revolve        a solid of revolution about the y axis (Listing 15.14's shape)
  --sweep PATH     the profile swept round the closed curve PATH.pwc (Listing 15.20's
                   double_pwc: radius scaled by |path(u)| at angle 2*pi*u)
  --frame W H      a mitred frame of four pieces, outer size W x H, in the x-y plane

The surface deviates from the exact curved shape by at most --tolerance.
"""

_EPILOG = """\
examples:
  pwc solid profiles/torus.pwc --revolve -o torus.stl
  pwc solid profiles/corinthian.pwc --sweep profiles/doric_flutes.pwc \\
      --radius-offset 0.25 -o capital.3mf
  pwc solid profiles/ornament_2.pwc --frame 6 8 --tolerance 1e-4 -o frame.obj
"""


def register(subparsers) -> argparse.ArgumentParser:
    """Add the ``solid`` subcommand to the ``pwc`` command's subparsers."""
    parser = subparsers.add_parser(
        "solid",
        help="build a watertight solid (extrude, revolve, sweep, frame) and export it",
        description=_DESCRIPTION,
        epilog=_EPILOG,
        formatter_class=argparse.RawDescriptionHelpFormatter,
    )
    parser.add_argument("profile", metavar="PROFILE.pwc",
                        help="the profile to build from: a file, or a name (ornament_2)")
    shape = parser.add_mutually_exclusive_group(required=True)
    shape.add_argument("--extrude", type=float, metavar="L",
                       help="extrude the cross-section along z over length L")
    shape.add_argument("--revolve", action="store_true",
                       help="revolve the profile about the y axis")
    shape.add_argument("--sweep", metavar="PATH.pwc",
                       help="sweep the profile round this closed curve (double_pwc)")
    shape.add_argument("--frame", type=float, nargs=2, metavar=("W", "H"),
                       help="a mitred frame of outer width W and height H")
    parser.add_argument("-o", "--output", required=True, metavar="OUT",
                        help="output file: .stl (binary), .3mf or .obj")
    parser.add_argument("--tolerance", type=float, default=1e-3,
                        help="largest deviation from the exact shape (default 1e-3)")
    parser.add_argument("--radius-offset", type=float, default=0.0, metavar="R",
                        help="added to x before revolving or sweeping (default 0)")
    parser.add_argument("--segments", type=int, default=None, metavar="N",
                        help="circular segments of a --revolve (default: from tolerance)")
    add_profiles_option(parser)
    parser.set_defaults(func=_run)
    return parser


def _fail(message: str, status: int = EXIT_ERRORS) -> int:
    print(f"pwc solid: error: {message}", file=sys.stderr)
    return status


def _run(args: argparse.Namespace) -> int:
    """Build, export and report; returns the exit status (0 ok, 1 error in the input or a
    solid that is not watertight, 2 bad command line, 3 unreadable or unwritable file)."""
    import pwc
    from displacement import solids

    out = Path(args.output)
    if out.suffix.lower() not in solids.EXPORT_FORMATS:
        return _fail(
            f"unsupported output type '{out.suffix or '(none)'}' for '{out}'; "
            f"use one of {', '.join(solids.EXPORT_FORMATS)}", EXIT_USAGE
        )
    if args.radius_offset and not (args.revolve or args.sweep):
        return _fail("--radius-offset applies only to --revolve and --sweep", EXIT_USAGE)
    if args.segments is not None and not args.revolve:
        return _fail("--segments applies only to --revolve", EXIT_USAGE)
    try:
        profile = resolve_profile(args.profile, (".",), args.profiles)
        sweep = resolve_profile(args.sweep, (".",), args.profiles) if args.sweep else None
        prepare_output(out)
    except OSError as e:  # not found, a folder, or an output that cannot be written
        return _fail(str(e), EXIT_IO)

    try:
        curve = pwc.load(profile)
        start = time.perf_counter()
        if args.extrude is not None:
            what = f"extrusion of length {args.extrude:g}"
            solid = solids.extrude(curve, args.extrude, args.tolerance)
        elif args.revolve:
            what = "revolution"
            solid = solids.revolve(curve, args.tolerance, args.radius_offset, args.segments)
        elif args.sweep:
            path = pwc.load(sweep)
            what = f"sweep along '{path.name}'"
            solid = solids.sweep(curve, path, args.tolerance, args.radius_offset)
        else:
            width, height = args.frame
            what = f"frame {width:g} x {height:g}"
            solid = solids.frame(curve, width, height, args.tolerance)
        elapsed = time.perf_counter() - start
        info = solids.solid_info(solid)
        solids.export(solid, out)
    except pwc.PwcError as e:  # the compiler's own report: file:line:col, caret, fix
        print(str(e), file=sys.stderr)
        return 1
    except OSError as e:
        return _fail(f"cannot read or write '{e.filename}': {e.strerror}", EXIT_IO)
    except (ValueError, UnicodeDecodeError) as e:
        return _fail(str(e))

    print(f"wrote {out}: {what} of '{curve.name}', tolerance {args.tolerance:g}")
    print(f"  volume      {info['volume']:.9g}")
    print(f"  triangles   {info['triangles']}")
    print(f"  watertight  {'yes' if info['watertight'] else 'NO'} (genus {info['genus']})")
    print(f"  built in    {elapsed:.3f} s")
    return 0 if info["watertight"] else 1
