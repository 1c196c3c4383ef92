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

With ``--workers N`` or ``--scheduler ADDRESS`` each figure (a whole render, a whole
check) is one task on a Dask cluster (:func:`render.distributed.map_on_cluster`): the
client loads the scenes, the workers render (and judge), and the client writes the
files and prints the table in the figures' order; the same images, bit for bit.  A
cluster that cannot work exits with status 3.

Exit status: 0 ok; 1 a figure failed its check or a scene has errors; 2 bad command
line; 3 a file could not be read or written.
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

from pwc.files import OutputError, prepare_output
from render.distributed import add_cluster_options

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
  pwc gallery check --workers 2   # every figure, one task each on 2 local processes
  pwc gallery sheet -o gallery/index.html"""


def register(subparsers) -> argparse.ArgumentParser:
    """Add ``gallery`` (with ``render``, ``check``, ``sheet``) to ``pwc``'s subparsers."""
    p = subparsers.add_parser("gallery", help="render, check and show the Handbook's figures",
                              description=_DESCRIPTION, epilog=_EPILOG,
                              formatter_class=argparse.RawDescriptionHelpFormatter)
    sub = p.add_subparsers(dest="gallery_command", metavar="{render,check,sheet}",
                           required=True)

    def figures_arg(q, work: str):
        q.add_argument("figures", nargs="*", metavar="FIGURE",
                       help="chapter, figure number, scene name or glob (default: all)")
        q.add_argument("--quiet", action="store_true", help="no progress bar or table")
        add_cluster_options(q, f"{work} the figures, one task each,")

    r = sub.add_parser("render", help="render figures to a folder (EXR and PNG)",
                       description="Render gallery figures to DIR/NAME.exr (linear RGBA) and "
                                   "DIR/NAME.png (sRGB), at their reference size unless told.",
                       epilog="examples:\n  pwc gallery render 13.14 13.33 -o out/ --spp 128\n"
                              "  pwc gallery render 14 -o out/ --scheduler tcp://host:8786",
                       formatter_class=argparse.RawDescriptionHelpFormatter)
    figures_arg(r, "render")
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
                       epilog="examples:\n  pwc gallery check 12.12 12.13 --save out/check\n"
                              "  pwc gallery check --workers 2",
                       formatter_class=argparse.RawDescriptionHelpFormatter)
    figures_arg(c, "check")
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
    figures_arg(s, "check")
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
    if not _progress(args):
        return items
    from tqdm import tqdm

    return tqdm(items, unit=unit, leave=False)


def _on_cluster(args) -> bool:
    return bool(args.scheduler or args.workers)


def _progress(args) -> bool:
    """A bar redrawn with carriage returns only on a terminal, not into a log."""
    return not args.quiet and sys.stderr.isatty()


def _rendered(args, figs):
    """``(figure, film)`` in the figures' order: rendered in-process, or one task per
    figure on a cluster (the scenes loaded here, the films brought back)."""
    from gallery.compare import figure_scene, render_figure

    def size(fig):
        return args.resolution or fig.resolution

    from render.precompile import notice_first_compile

    notice_first_compile("pwc gallery", args.quiet)
    if not _on_cluster(args):
        for fig in figs:
            yield fig, render_figure(fig, args.spp, args.seed, resolution=size(fig),
                                     progress=_progress(args), denoise=args.denoise,
                                     time=args.time)
        return
    from functools import partial

    from render.distributed import cluster, map_on_cluster
    from render.integrator import render

    task = partial(render, progress=False, threads=1, denoise=args.denoise)
    with cluster(args.scheduler, args.workers) as client:
        scenes = (figure_scene(fig, size(fig), args.spp, args.seed, args.time) for fig in figs)
        for i, film in map_on_cluster(client, task, scenes, progress=_progress(args),
                                      desc="render figures", unit="figure"):
            yield figs[i], film


def run_render(args) -> int:
    """``pwc gallery render``."""
    from render.distributed import ClusterError
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
    try:
        for fig, film in _rendered(args, figs):
            try:
                film.write_exr(out / f"{fig.name}.exr", aovs=[])
                film.write_png(out / f"{fig.name}.png")
            except OSError as e:
                return _error(f"cannot write {out / fig.name}: {e.strerror or e}", EXIT_IO)
            if not args.quiet:
                st = film.stats
                print(f"Figure {fig.number:>6}  {fig.name}: {film.width} x {film.height}, "
                      f"{st['spp']} spp{', denoised' if args.denoise else ''}, "
                      f"{st['time_s'] + st.get('build_s', 0.0):.1f} s -> {out / fig.name}.png",
                      file=sys.stderr)
    except SceneError as e:
        print(str(e), file=sys.stderr)
        return EXIT_FAILED
    except ClusterError as e:
        return _error(str(e), EXIT_IO)
    except OSError as e:
        return _error(f"{e.filename or 'a scene'}: {e.strerror or e}", EXIT_IO)
    return EXIT_OK


def _checked(args, figs):
    """(figure, Outcome or None) for each figure, and the references table: checked
    in-process, or one task per figure on a cluster."""
    from gallery.compare import check, check_job, read_table, render_and_judge

    folder = Path(args.references) if args.references else None
    table = read_table(folder)
    known = [fig for fig in figs if fig.name in table]
    if _on_cluster(args):
        from functools import partial

        from render.distributed import cluster, map_on_cluster

        with cluster(args.scheduler, args.workers) as client:
            jobs = (check_job(fig, table, folder) for fig in known)
            done = dict(map_on_cluster(client, partial(render_and_judge, threads=1), jobs,
                                       progress=_progress(args), desc="check figures",
                                       unit="figure"))
        outcomes = {known[i].name: o for i, o in done.items()}
    else:
        outcomes = {fig.name: check(fig, table, folder) for fig in _bar(known, args, "figure")}
    return [(fig, outcomes.get(fig.name)) for fig in figs], table


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
    from render.distributed import ClusterError

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
    try:
        results, _ = _checked(args, figs)
    except ClusterError as e:
        return _error(str(e), EXIT_IO)
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
    from render.distributed import ClusterError

    figs, status = _select(args)
    if figs is None:
        return status
    try:
        prepare_output(args.output, "the page")
    except OutputError as e:
        return _error(str(e), EXIT_IO)
    try:
        results, table = _checked(args, figs)
    except ClusterError as e:
        return _error(str(e), EXIT_IO)
    try:
        page = write_sheet(args.output, results, table,
                           Path(args.references) if args.references else None)
    except OSError as e:
        return _error(f"cannot write the page: {e.strerror or e}", EXIT_IO)
    if not args.quiet:
        print(_table(results))
        print(f"wrote {page} ({len(results)} figures; images in {page.parent / 'sheet'})")
    return EXIT_OK
