"""The ``pwc`` command: compile, check and describe pwc-lists.

Downstream packages add subcommands (``solid``, ``bake``, ``view``, ``render``) through
the ``pwc.commands`` entry-point group, so this package never imports them.

Exit status: 0 success; 1 the input has errors (or warnings, with ``--strict``);
2 bad command line; 3 a file could not be read or written, or a plugin is unavailable.
"""

from __future__ import annotations

import argparse
import gc
import sys
from importlib.metadata import entry_points
from pathlib import Path

import numpy as np

from pwc import compile_source
from pwc.curve import Curve, PwType
from pwc.diagnostics import Diagnostic, PwcError
from pwc.files import OutputError, ProfileNotFound, prepare_output, resolve_profile
from pwc.parser import decode_source

__all__ = ["main", "version", "add_profiles_option", "EXIT_OK", "EXIT_ERRORS", "EXIT_USAGE",
           "EXIT_IO"]

EXIT_OK, EXIT_ERRORS, EXIT_USAGE, EXIT_IO = 0, 1, 2, 3
FORMATS = ("mdl", "json", "npz", "svg", "png")


class CliError(Exception):
    """A failure to report in one line, with an exit status."""

    def __init__(self, message: str, status: int = EXIT_IO):
        super().__init__(message)
        self.status = status


def version() -> str:
    """The installed distribution's version (``pwc --version``)."""
    from importlib.metadata import PackageNotFoundError
    from importlib.metadata import version as dist_version

    try:
        return dist_version("pwc-workbench")
    except PackageNotFoundError:
        return "unknown (not installed: run pip install .)"


def add_profiles_option(parser: argparse.ArgumentParser) -> None:
    """Add ``--profiles DIR`` (repeatable) to a command that takes profiles by name."""
    parser.add_argument(
        "--profiles", action="append", default=[], metavar="DIR",
        help="also look for profiles given by name (NAME for NAME.pwc) in DIR, after the "
             "current folder and before $PWC_PROFILE_PATH and the bundled library; "
             "repeatable")


def find_profile_arg(arg: str, extra=()) -> Path:
    """A PROFILE argument as a file: the path given, or a profile name on the search path
    (:mod:`pwc.files`); raises :class:`CliError` (exit 3) when there is neither."""
    try:
        return resolve_profile(arg, (".",), extra)
    except (ProfileNotFound, IsADirectoryError) as e:
        raise CliError(str(e)) from None


def _load(path: str, normalize: bool, extra=()) -> tuple[Curve | None, list[Diagnostic]]:
    """Compile one file; returns (curve or None, diagnostics) and prints nothing."""
    p = find_profile_arg(path, extra)
    path = str(p)
    try:
        data = p.read_bytes()
    except OSError as e:
        raise CliError(f"{path}: cannot read: {e.strerror}") from None
    try:
        text = decode_source(data, path)
        return compile_source(text, p.stem, path, normalize)
    except PwcError as e:
        return None, e.diagnostics


def _report(diags: list[Diagnostic], strict: bool) -> bool:
    """Print diagnostics to stderr; True when the file counts as failed."""
    for d in diags:
        print(d.format(), file=sys.stderr)
    errors = sum(d.severity == "error" for d in diags)
    warnings = len(diags) - errors
    return errors > 0 or (strict and warnings > 0)


def _encode(curve: Curve, fmt: str) -> bytes:
    from pwc import emit

    if fmt == "mdl":
        try:
            return emit.to_mdl(curve).encode()
        except ValueError as e:
            raise CliError(f"{curve.source}: {e}", EXIT_ERRORS) from None
    if fmt == "json":
        return emit.to_json(curve).encode()
    if fmt == "npz":
        return emit.to_npz(curve)
    from pwc import draw

    if fmt == "svg":
        return draw.to_svg(curve).encode()
    try:
        return draw.to_png(curve)
    except ImportError:
        raise CliError("PNG drawings need matplotlib: pip install 'pwc-workbench[geometry]' "
                       "(or use --format svg)") from None


def _write(path: Path, data: bytes) -> None:
    try:
        prepare_output(path).write_bytes(data)
    except OSError as e:
        raise CliError(str(e) if isinstance(e, OutputError) else
                       f"cannot write {path}: {e.strerror or e}") from None


def cmd_compile(args) -> int:
    out = args.output
    to_dir = out is None or out.endswith(("/", "\\")) or Path(out).is_dir()
    if out and out != "-" and len(args.files) > 1 and not to_dir:
        raise CliError(f"-o {out}: with several input files, -o must be an existing "
                       "directory (or '-')", EXIT_USAGE)
    failed = False
    for path in args.files:
        curve, diags = _load(path, not args.no_normalize, args.profiles)
        if _report(diags, args.strict) or curve is None:
            failed = True
            continue
        data = _encode(curve, args.format)
        if out == "-":
            sys.stdout.buffer.write(data)
            sys.stdout.flush()
            continue
        stem = curve.name
        if args.format == "mdl":
            from pwc.emit import mdl_identifier

            stem = mdl_identifier(stem)
        target = Path(out or ".") / f"{stem}.{args.format}" if to_dir else Path(out)
        _write(target, data)
        if args.format == "mdl":
            from pwc.emit import runtime_mdl

            _write(target.parent / "pw_curve.mdl", runtime_mdl().encode())
        print(f"{path} -> {target}  ({curve.n} pw_points, length {curve.length:.6g})",
              file=sys.stderr)
    return EXIT_ERRORS if failed else EXIT_OK


def cmd_check(args) -> int:
    failed = False
    for path in args.files:
        curve, diags = _load(path, True, args.profiles)
        bad = _report(diags, args.strict)
        failed |= bad
        if not bad and curve is not None:
            warn = f", {len(diags)} warning(s)" if diags else ""
            print(f"{path}: ok ({curve.n} pw_points, length {curve.length:.6g}{warn})")
    return EXIT_ERRORS if failed else EXIT_OK


def describe(curve: Curve) -> str:
    """A human-readable summary of a compiled curve (``pwc info``)."""
    # a piece is named by the type of the point it ends at; the first point ends none
    kinds = {k.mdl_name: int(np.sum(curve.type[1:] == k)) for k in PwType}
    kinds = ", ".join(f"{v} {k}" for k, v in kinds.items() if v) or "none"
    (x0, y0), (x1, y1) = curve.bbox
    pieces = curve.n - 1
    lines = [
        f"name        {curve.name}",
        f"source      {curve.source}",
        f"list        {':relative' if curve.relative else 'absolute'}",
        f"pw_points   {curve.n} ({pieces} pieces: {kinds} ending at them)",
        f"length      {curve.length:.9g}   (MDL: {curve.name}_length)",
        f"scale       {curve.scale:.9g}   (source units -> normalized)",
        f"bbox        x [{x0:.6g}, {x1:.6g}]  y [{y0:.6g}, {y1:.6g}]",
        f"closed      {'yes' if curve.is_closed else 'no'}",
        "",
        f"{'#':>4} {'line':>5} {'type':<13} {'t':>10} {'x':>11} {'y':>11} {'radius':>10}  source",
    ]
    for i in range(curve.n):
        r = f"{curve.radius[i]:10.5g}" if curve.is_arc[i] else " " * 10
        lines.append(f"{i:>4} {curve.line[i]:>5} {PwType(int(curve.type[i])).mdl_name:<13} "
                     f"{curve.t[i]:10.6f} {curve.pt[i, 0]:11.6g} {curve.pt[i, 1]:11.6g} {r}  "
                     f"{curve.text[i] if curve.text else ''}")
    return "\n".join(lines)


def cmd_info(args) -> int:
    failed = False
    for path in args.files:
        curve, diags = _load(path, not args.no_normalize, args.profiles)
        failed |= _report(diags, False) or curve is None
        if curve is not None:
            print(describe(curve))
    return EXIT_ERRORS if failed else EXIT_OK


def cmd_catalogue(args) -> int:
    from pwc.catalogue import write_catalogue

    try:
        out = write_catalogue(Path(args.folder), force=args.force)
    except (FileNotFoundError, FileExistsError) as e:
        raise CliError(str(e)) from None
    except OSError as e:
        raise CliError(f"cannot write the catalogue: {e.strerror or e}") from None
    except PwcError as e:
        print(e, file=sys.stderr)
        return EXIT_ERRORS
    print(f"wrote {out}")
    return EXIT_OK


def build_parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(
        prog="pwc",
        description="Compile and inspect pwc-lists: the piece-wise curve language of the MDL "
                    "Handbook, chapter 15.",
        epilog="exit status: 0 ok; 1 errors in the input (or warnings with --strict); "
               "2 bad command line; 3 unreadable/unwritable file or unavailable command. "
               "Run 'pwc COMMAND --help' for each command.")
    parser.add_argument("--version", action="version", version=f"%(prog)s {version()}")
    sub = parser.add_subparsers(dest="command", metavar="COMMAND", required=True)

    p = sub.add_parser(
        "compile", help="compile pwc-lists to MDL, JSON, NPZ, SVG or PNG",
        description="Compile pwc-lists. MDL output writes NAME.mdl plus the runtime module "
                    "pw_curve.mdl beside it.",
        epilog="examples: pwc compile profiles/ornament_2.pwc -o out/  |  "
               "pwc compile a.pwc --format json -o -")
    p.add_argument("files", nargs="+", metavar="FILE",
                   help=".pwc files, or profile names (ornament_2) on the search path")
    p.add_argument("--format", "-f", choices=FORMATS, default="mdl",
                   help="output format (default: mdl)")
    p.add_argument("-o", "--output", metavar="PATH",
                   help="output file, or directory (an existing one, or a path ending in "
                        "'/'); default: NAME.FORMAT in the current directory; '-' writes "
                        "to stdout")
    p.add_argument("--no-normalize", action="store_true",
                   help="keep source units (scale 1) instead of scaling the largest "
                        "coordinate to 1")
    p.add_argument("--strict", action="store_true", help="treat warnings as errors")
    add_profiles_option(p)
    p.set_defaults(func=cmd_compile)

    p = sub.add_parser("check", help="report diagnostics only",
                       description="Parse and compile pwc-lists, print diagnostics, write "
                                   "nothing.")
    p.add_argument("files", nargs="+", metavar="FILE",
                   help=".pwc files, or profile names (ornament_2) on the search path")
    p.add_argument("--strict", action="store_true", help="treat warnings as errors")
    add_profiles_option(p)
    p.set_defaults(func=cmd_check)

    p = sub.add_parser("info", help="pieces, length, bounding box and scale of a curve",
                       description="Describe compiled curves: every pw_point with its type, "
                                   "t, position and radius.")
    p.add_argument("files", nargs="+", metavar="FILE",
                   help=".pwc files, or profile names (ornament_2) on the search path")
    p.add_argument("--no-normalize", action="store_true", help="show source units")
    add_profiles_option(p)
    p.set_defaults(func=cmd_info)

    p = sub.add_parser("catalogue", help="draw a folder of profiles and write its README.md",
                       description="Write FOLDER/drawings/NAME.svg for every FOLDER/*.pwc and "
                                   "the catalogue page FOLDER/README.md.")
    p.add_argument("folder", nargs="?", default="profiles", help="default: profiles")
    p.add_argument("--force", action="store_true",
                   help="overwrite FOLDER/README.md even if pwc catalogue did not write it")
    p.set_defaults(func=cmd_catalogue)

    for ep in sorted(entry_points(group="pwc.commands"), key=lambda e: e.name):
        try:
            ep.load()(sub)
        except Exception as e:  # a missing optional dependency must not break `pwc`
            p = sub.add_parser(ep.name, help=f"(unavailable: {type(e).__name__})")
            p.set_defaults(func=_unavailable(ep.name, e))
    return parser


def _unavailable(name: str, error: Exception):
    def run(args) -> int:
        raise CliError(f"pwc {name} is unavailable here ({type(error).__name__}: {error}); "
                       "install the full workbench: pip install 'pwc-workbench[geometry,viz]'")
    return run


def main(argv: list[str] | None = None) -> int:
    parser = build_parser()
    args = parser.parse_args(argv)
    try:
        return args.func(args)
    except CliError as e:
        print(f"pwc: error: {e}", file=sys.stderr)
        return e.status
    except KeyboardInterrupt:
        print("pwc: interrupted", file=sys.stderr)
        return 130
    except BrokenPipeError:
        return EXIT_OK


def space_out_full_collections() -> None:
    """Run the cycle collector's full pass a hundred times less often, for a process
    that runs one command.  A full pass walks every object alive, and a command's start
    makes many that live to its end (modules, numba's typing registries, the MDL
    modules' trees): with Python's default third threshold (10) a cached ``pwc render``
    ran three full passes, 0.10 s of its 1.0 s start; at 1000 it runs none (measured
    2026-11-28).  Young passes, which free the cycles a command makes as it goes, are
    unchanged: ``pwc gallery render 12 13`` peaks at the same memory (1.05 GB) either
    way."""
    young, middle, _ = gc.get_threshold()
    gc.set_threshold(young, middle, 1000)


def entry() -> int:
    """The ``pwc`` command's process: :func:`main` with the collector's full passes spaced
    out (:func:`space_out_full_collections`), then, after a render, an exit without its
    last pass.  Not in :func:`main`, which tests call in their own process.

    Python's finalisation collects every object still alive, 0.3 s once numba's typing
    registries are loaded (wall time minus the command's own, with and without); the
    process ends anyway, so they are frozen (``gc.freeze``) and left to the operating
    system.  Only after a render: a frozen object is never freed, and manifold3d (``pwc
    solid``) reports the objects it finds left at exit as leaks."""
    space_out_full_collections()
    status = main()
    if "render.integrator" in sys.modules:
        gc.freeze()
    return status


if __name__ == "__main__":
    sys.exit(entry())
