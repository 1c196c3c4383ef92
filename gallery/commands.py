"""The ``pwc gallery`` subcommand: render the Handbook's figures, check them, show them.

Registered through the ``pwc.commands`` entry point (``gallery =
"gallery.commands:register"``):

* ``pwc gallery render [FIGURE...] -o DIR`` renders figures (all, or those selected by
  chapter, number, name or glob) at their reference size, or as told;
* ``pwc gallery check [FIGURE...]`` renders each by the regression rule
  (:mod:`gallery.compare`, the rule of ``tests/gallery``), prints a table and exits 1
  when any fails;
* ``pwc gallery sheet [FIGURE...] [-o gallery/index.html]`` checks them and writes the
  contact sheet (:mod:`gallery.sheet`).

Exit status: 0 ok; 1 a figure failed its check or a scene has errors; 2 bad command
line; 3 a file could not be read or written.
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

from pwc.files import OutputError, prepare_output

__all__ = ["register", "run_render", "run_check", "run_sheet"]

EXIT_OK, EXIT_FAILED, EXIT_USAGE, EXIT_IO = 0, 1, 2, 3

_DESCRIPTION = """\
The gallery: the MDL Handbook's figures as scenes (gallery/scenes), their converged
reference images (gallery/reference) and a contact sheet (gallery/index.html).  Select
figures by chapter (13), number (13.14), scene name (fig_13_14) or glob ('fig_12_*');
none selects every figure."""

_EPILOG = """\
examples:
  pwc gallery render 14.28 -o out/ --resolution 512 384 --spp 64 --denoise
  pwc gallery check 13            # every figure of chapter 13, by the test's rule
  pwc gallery sheet -o gallery/index.html"""


def register(subparsers) -> argparse.ArgumentParser:
    """Add ``gallery`` (with ``render``, ``check``, ``sheet``) to ``pwc``'s subparsers."""
    p = subparsers.add_parser("gallery", help="render, check and show the Handbook's figures",
                              description=_DESCRIPTION, epilog=_EPILOG,
                              formatter_class=argparse.RawDescriptionHelpFormatter)
    sub = p.add_subparsers(dest="gallery_command", metavar="{render,check,sheet}",
                           required=True)

    def figures_arg(q):
        q.add_argument("figures", nargs="*", metavar="FIGURE",
                       help="chapter, figure number, scene name or glob (default: all)")
        q.add_argument("--quiet", action="store_true", help="no progress bar or table")

    r = sub.add_parser("render", help="render figures to a folder (EXR and PNG)",
                       description="Render gallery figures to DIR/NAME.exr (linear RGBA) and "
                                   "DIR/NAME.png (sRGB), at their reference size unless told.",
                       epilog="example: pwc gallery render 13.14 13.33 -o out/ --spp 128")
    figures_arg(r)
    r.add_argument("-o", "--output", required=True, metavar="DIR", help="folder to write")
    budget = r.add_mutually_exclusive_group()
    budget.add_argument("--spp", type=int, metavar="N", help="samples per pixel")
    budget.add_argument("--time", type=float, metavar="S", help="time budget per figure (s)")
    r.add_argument("--resolution", type=int, nargs=2, metavar=("W", "H"),
                   help="image size (default: the figure's reference size)")
    r.add_argument("--denoise", action="store_true",
                   help="denoise with Open Image Denoise (pyoidn)")
    r.add_argument("--seed", type=int, default=0, metavar="N", help="random seed (default 0)")
    r.set_defaults(func=run_render)

    c = sub.add_parser("check", help="render figures by the regression rule and compare",
                       description="Render each figure as the regression test does (small, "
                                   "few samples, a fixed seed), compare it with its reference "
                                   "by RMSE, FLIP and image mean against the measured "
                                   "thresholds, print a table, and exit 1 if any fails.",
                       epilog="example: pwc gallery check 12.12 12.13 --save out/check")
    figures_arg(c)
    c.add_argument("--save", metavar="DIR",
                   help="also write each render, its reference and FLIP map as EXR there")
    c.add_argument("--references", metavar="DIR",
                   help="the reference folder (default: the gallery's own)")
    c.set_defaults(func=run_check)

    s = sub.add_parser("sheet", help="check figures and write the HTML contact sheet",
                       description="Check the figures (as `pwc gallery check`) and write the "
                                   "contact sheet: per figure its number, caption, our render, "
                                   "the reference, the FLIP error map, samples, time and "
                                   "error, grouped by chapter.  Images go to sheet/ beside "
                                   "the page.",
                       epilog="example: pwc gallery sheet 13 -o /tmp/sheet/index.html")
    figures_arg(s)
    s.add_argument("-o", "--output", default="gallery/index.html", metavar="PAGE.html",
                   help="the page to write (default: gallery/index.html)")
    s.add_argument("--references", metavar="DIR",
                   help="the reference folder (default: the gallery's own)")
    s.set_defaults(func=run_sheet)
    return p


def _error(message: str, status: int) -> int:
    print(f"pwc gallery: error: {message}", file=sys.stderr)
    return status


def _select(args):
    from gallery.figures import FigureError, figures

    try:
        return figures(args.figures), None
    except FigureError as e:
        return None, _error(str(e), EXIT_USAGE)


def _bar(items, args, unit: str):
    if args.quiet or not sys.stderr.isatty():
        return items
    from tqdm import tqdm

    return tqdm(items, unit=unit, leave=False)


def run_render(args) -> int:
    """``pwc gallery render``."""
    from gallery.compare import render_figure
    from render.scene import SceneError

    figs, status = _select(args)
    if figs is None:
        return status
    if args.spp is not None and args.spp < 1:
        return _error(f"--spp must be >= 1, got {args.spp}", EXIT_USAGE)
    if args.time is not None and not args.time > 0:
        return _error(f"--time must be > 0 seconds, got {args.time}", EXIT_USAGE)
    if args.resolution and min(args.resolution) < 1:
        return _error(f"--resolution must be positive, got {args.resolution}", EXIT_USAGE)
    if args.denoise:
        try:
            import pyoidn  # noqa: F401
        except ImportError:
            return _error("--denoise needs Open Image Denoise: pip install pyoidn", EXIT_USAGE)
    out = Path(args.output)
    try:  # every output is checked before the first render starts
        for fig in figs:
            for ext in ("exr", "png"):
                prepare_output(out / f"{fig.name}.{ext}", "the image")
    except OutputError as e:
        return _error(str(e), EXIT_IO)
    for fig in figs:
        try:
            film = render_figure(fig, args.spp, args.seed,
                                 resolution=args.resolution or fig.resolution,
                                 progress=not args.quiet and sys.stderr.isatty(),
                                 denoise=args.denoise, time=args.time)
            film.write_exr(out / f"{fig.name}.exr", aovs=[])
            film.write_png(out / f"{fig.name}.png")
        except SceneError as e:
            print(str(e), file=sys.stderr)
            return EXIT_FAILED
        except OSError as e:
            return _error(f"cannot write {out / fig.name}: {e.strerror or e}", EXIT_IO)
        if not args.quiet:
            st = film.stats
            print(f"Figure {fig.number:>6}  {fig.name}: {film.width} x {film.height}, "
                  f"{st['spp']} spp{', denoised' if args.denoise else ''}, "
                  f"{st['time_s'] + st.get('build_s', 0.0):.1f} s -> {out / fig.name}.png",
                  file=sys.stderr)
    return EXIT_OK


def _checked(args, figs):
    """(figure, Outcome or None) for each figure, and the references table."""
    from gallery.compare import check, read_table

    folder = Path(args.references) if args.references else None
    table = read_table(folder)
    results = []
    for fig in _bar(figs, args, "figure"):
        results.append((fig, check(fig, table, folder) if fig.name in table else None))
    return results, table


def _table(results) -> str:
    head = (f"{'figure':>7}  {'scene':<10} {'RMSE':>7} {'max':>7} {'FLIP':>7} {'max':>7} "
            f"{'mean':>5} {'time':>6}  result")
    lines = [head, "-" * len(head)]
    for fig, o in results:
        if o is None:
            lines.append(f"{fig.number:>7}  {fig.name:<10} {'':>45}  no reference")
            continue
        mean_ok = "ok" if all(o.mean_diff <= o.mean_tol) else "off"
        verdict = "pass" if o.passed else "FAIL: " + "; ".join(o.reasons())
        lines.append(f"{fig.number:>7}  {fig.name:<10} {o.rmse:7.4f} {o.rmse_max:7.4f} "
                     f"{o.flip:7.4f} {o.flip_max:7.4f} {mean_ok:>5} {o.time_s:5.1f}s  {verdict}")
    failed = sum(1 for _, o in results if o is None or not o.passed)
    lines.append(f"{len(results) - failed} of {len(results)} figures pass"
                 + (f", {failed} fail" if failed else ""))
    return "\n".join(lines)


def _save(folder: Path, outcome) -> None:
    from render.film import write_exr_channels

    for tag, img in (("img", outcome.image), ("ref", outcome.reference),
                     ("err", outcome.error_map[..., None].repeat(3, axis=2))):
        write_exr_channels(folder / f"{outcome.name}_{tag}.exr",
                           {c: img[..., i].astype("float32") for i, c in enumerate("RGB")})


def run_check(args) -> int:
    """``pwc gallery check``."""
    figs, status = _select(args)
    if figs is None:
        return status
    if args.save:
        try:
            for fig in figs:
                for tag in ("img", "ref", "err"):
                    prepare_output(Path(args.save) / f"{fig.name}_{tag}.exr", "--save image")
        except OutputError as e:
            return _error(str(e), EXIT_IO)
    results, _ = _checked(args, figs)
    if args.save:
        for _, o in results:
            if o is not None:
                _save(Path(args.save), o)
    if not args.quiet:
        print(_table(results))
    return EXIT_OK if all(o is not None and o.passed for _, o in results) else EXIT_FAILED


def run_sheet(args) -> int:
    """``pwc gallery sheet``."""
    from gallery.sheet import write_sheet

    figs, status = _select(args)
    if figs is None:
        return status
    try:
        prepare_output(args.output, "the page")
    except OutputError as e:
        return _error(str(e), EXIT_IO)
    results, table = _checked(args, figs)
    try:
        page = write_sheet(args.output, results, table,
                           Path(args.references) if args.references else None)
    except OSError as e:
        return _error(f"cannot write the page: {e.strerror or e}", EXIT_IO)
    if not args.quiet:
        print(_table(results))
        print(f"wrote {page} ({len(results)} figures; images in {page.parent / 'sheet'})")
    return EXIT_OK
