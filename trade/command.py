"""The ``pwc trade`` subcommand: measure a scene's speed/accuracy trade and recommend the
cheapest settings that meet a target error.

Registered through the ``pwc.commands`` entry point (``trade = "trade.command:register"``).
With ``--workers N`` or ``--scheduler ADDRESS`` every measured run is one task on a Dask
cluster (:mod:`render.distributed`), timed on its worker.  Exit status: 0 done (a
recommendation, or a report saying no run met the target); 1 the scene has errors; 2
bad command line; 3 a file could not be read or written, or the cluster cannot work.
"""

from __future__ import annotations

import argparse
import shlex
import sys
from pathlib import Path

from pwc.cli import add_profiles_option
from pwc.files import OutputError, prepare_output
from render.distributed import add_cluster_options

__all__ = ["register", "run", "FAMILIES"]

EXIT_OK, EXIT_ERRORS, EXIT_USAGE, EXIT_IO = 0, 1, 2, 3
#: the knob families (``--knobs``)
FAMILIES = ("samples", "dicing", "displacement", "curves", "textures", "paths")

_DESCRIPTION = """\
Measure what a scene costs at each accuracy.  A converged reference of the scene is
rendered (or read back from REPORT/, where an earlier run kept it); then every knob that
trades speed for accuracy and can change this scene is swept, one at a time from the
scene as written: samples per pixel with and without denoising; dicing tolerance and
rate, and true displacement against bump and baked normal maps, per displaced object;
pwc curves exact, float32 or as polylines; texture filtering; path and roulette depth.
Each run is measured for wall time, peak memory, triangles and rays, and its error
against the reference (RMSE, mean FLIP, relative mean, and the geometric error in
pixels of displaced objects).  The cheapest options that meet the target are then
combined and measured.  REPORT/ gets report.md and report.html (plots of error against
time and memory with the Pareto front, the table of every run), runs.json, the images,
and recommended.toml: the fastest measured run that meets --target-error, as a scene
file for pwc render.  With --workers or --scheduler each run is one task on a Dask
cluster, timed on its worker (runs sharing a machine share its cores: docs/trade.md);
the images and errors are the in-process ones."""

_EPILOG = """\
examples:
  pwc trade gallery/scenes/fig_15_21.toml -o trade_report/
  pwc trade scene.toml -o out/ --metric rel_rmse --target-error 0.01 --budget 600
  pwc trade scene.toml -o out/ --knobs samples,dicing --ci
  pwc trade scene.toml -o out/ --cost cpu --workers 2"""


def _families(text: str) -> set[str]:
    names = {k.strip() for k in text.split(",") if k.strip()}
    bad = names - set(FAMILIES)
    if bad or not names:
        raise argparse.ArgumentTypeError(
            f"unknown knob family {sorted(bad)[0] if bad else text!r}: choose from "
            f"{', '.join(FAMILIES)}")
    return names


def register(subparsers) -> argparse.ArgumentParser:
    """Add ``trade`` to the ``pwc`` command's subparsers and return its parser."""
    from trade.knobs import CI_WIDTH
    from trade.metrics import METRICS

    p = subparsers.add_parser(
        "trade", help="measure a scene's speed/accuracy trade; recommend settings",
        description=_DESCRIPTION, epilog=_EPILOG,
        formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("scene", metavar="SCENE.toml",
                   help="the scene file, or the name of a bundled gallery scene (fig_15_21)")
    p.add_argument("-o", "--output", required=True, metavar="REPORT/",
                   help="the report folder (created; an earlier run's reference is reused)")
    p.add_argument("--knobs", type=_families, metavar="LIST",
                   help=f"knob families to sweep, comma-separated: {', '.join(FAMILIES)} "
                        "(default: every one that can change the scene)")
    p.add_argument("--metric", choices=tuple(METRICS), default="flip",
                   help="the error the target is stated in: " + "; ".join(
                       f"{k}: {v}" for k, v in METRICS.items()) + " (default: flip)")
    p.add_argument("--target-error", type=float, default=0.05, metavar="E",
                   help="the largest acceptable error of the recommendation (default 0.05)")
    p.add_argument("--cost", choices=("wall", "cpu"), default="wall",
                   help="what cheapest means: wall-clock seconds (default), or the "
                        "process's CPU seconds, steadier where other programs share the "
                        "machine")
    p.add_argument("--budget", type=float, metavar="SECONDS",
                   help="stop starting runs after this long (the reference not counted)")
    p.add_argument("--resolution", type=int, nargs=2, metavar=("W", "H"),
                   help="measure at this image size (default: the scene's)")
    p.add_argument("--reference-spp", type=int, metavar="N",
                   help="samples per pixel of the reference (default: 16 x the scene's, "
                        "at least 256)")
    p.add_argument("--reference", metavar="REF.exr",
                   help="use this converged image as the reference instead of rendering one")
    p.add_argument("--fresh-reference", action="store_true",
                   help="render the reference even if REPORT/ holds one for this scene")
    p.add_argument("--ci", action="store_true",
                   help=f"CI-sized: images {CI_WIDTH} px wide, a 64-spp reference, one or "
                        "two options per knob")
    p.add_argument("--repeats", type=int, default=1, metavar="N",
                   help="time each run N times and keep the fastest (default 1)")
    p.add_argument("--threads", type=int, metavar="N",
                   help="threads per render (default 2; 1 on a cluster, where each worker "
                        "process renders one run at a time)")
    add_cluster_options(p, "measure the runs, one task each,")
    p.add_argument("--quiet", action="store_true", help="no progress bar or messages")
    add_profiles_option(p)
    p.set_defaults(func=run)
    return p


def _error(message: str, status: int) -> int:
    print(f"pwc trade: error: {message}", file=sys.stderr)
    return status


def _command_line(args) -> str:
    """The ``pwc trade`` command that reproduces this run (for the report)."""
    words = ["pwc", "trade", args.scene, "-o", args.output]
    if args.knobs:
        words += ["--knobs", ",".join(sorted(args.knobs))]
    words += ["--metric", args.metric, "--target-error", f"{args.target_error:g}"]
    if args.cost != "wall":
        words += ["--cost", args.cost]
    for flag, value in (("--budget", args.budget), ("--reference-spp", args.reference_spp),
                        ("--reference", args.reference)):
        if value is not None:
            words += [flag, str(value)]
    if args.resolution:
        words += ["--resolution", *map(str, args.resolution)]
    if args.repeats != 1:
        words += ["--repeats", str(args.repeats)]
    for flag, value in (("--threads", args.threads), ("--workers", args.workers),
                        ("--scheduler", args.scheduler)):
        if value is not None:
            words += [flag, str(value)]
    words += ["--ci"] if args.ci else []
    return " ".join(shlex.quote(str(w)) for w in words)


def run(args) -> int:
    """Execute ``pwc trade`` with parsed arguments; returns the exit status."""
    from contextlib import ExitStack

    from render.commands.render import _scene_file
    from render.distributed import ClusterError, cluster
    from render.library.resources import search_paths
    from render.scene import SceneError, parse_scene
    from trade.knobs import ci_resolution
    from trade.report import write_report
    from trade.sweep import run_trade

    if not args.target_error > 0:
        return _error(f"--target-error must be > 0, got {args.target_error}", EXIT_USAGE)
    if args.budget is not None and not args.budget > 0:
        return _error(f"--budget must be > 0 seconds, got {args.budget}", EXIT_USAGE)
    if args.reference_spp is not None and args.reference_spp < 1:
        return _error(f"--reference-spp must be >= 1, got {args.reference_spp}", EXIT_USAGE)
    if (args.threads is not None and args.threads < 1) or args.repeats < 1:
        return _error(f"--threads and --repeats must be >= 1, got {args.threads} and "
                      f"{args.repeats}", EXIT_USAGE)
    if args.resolution and min(args.resolution) < 1:
        return _error(f"--resolution must be positive, got {args.resolution}", EXIT_USAGE)
    scene_path = _scene_file(args.scene)
    out = Path(args.output)
    reference = Path(args.reference) if args.reference else None
    if reference is not None and not reference.is_file():
        return _error(f"--reference {reference}: no such file", EXIT_IO)
    try:
        prepare_output(out / "report.html", "the report")
    except OutputError as e:
        return _error(str(e), EXIT_IO)
    log = (lambda *a, **k: None) if args.quiet else (
        lambda msg: print(f"pwc trade: {msg}", file=sys.stderr))
    try:
        resolution = args.resolution
        if args.ci and not resolution:
            text = scene_path.read_text(encoding="utf-8")
            st = parse_scene(text, str(scene_path), base_dir=scene_path.parent).settings
            resolution = ci_resolution(st.width, st.height)
        with ExitStack() as stack:
            stack.enter_context(search_paths(profile_dirs=[scene_path.parent, *args.profiles]))
            client = None
            if args.scheduler or args.workers:
                client = stack.enter_context(cluster(args.scheduler, args.workers))
                log("measuring each run as a task on the cluster "
                    f"({len(client.nthreads())} workers now)")
            trade = run_trade(
                scene_path, out, metric=args.metric, target=args.target_error, cost=args.cost,
                knobs=args.knobs, budget=args.budget, size="ci" if args.ci else "full",
                resolution=resolution, reference_spp=args.reference_spp,
                reference=reference, fresh_reference=args.fresh_reference,
                threads=args.threads or (2 if client is None else 1), repeats=args.repeats,
                progress=not args.quiet and sys.stderr.isatty(), log=log, client=client)
        files = write_report(trade, out, _command_line(args))
    except ClusterError as e:
        return _error(str(e), EXIT_IO)
    except OSError as e:
        if isinstance(e, FileNotFoundError) and not scene_path.is_file():
            return _error(f"{scene_path}: cannot read the scene file: no such file", EXIT_IO)
        return _error(f"{getattr(e, 'filename', '') or scene_path}: {e.strerror or e}", EXIT_IO)
    except SceneError as e:
        print(str(e), file=sys.stderr)
        return EXIT_ERRORS
    except (ValueError, ImportError) as e:
        return _error(f"{args.scene}: {e}", EXIT_ERRORS)
    rec = trade.recommended
    base = trade.runs[0]
    if rec is None:
        log(f"no run met {trade.metric} <= {trade.target:g}; see {files['html']}")
    else:
        log(f"recommended: {rec.label}: {trade.metric} {rec.error(trade.metric):.4g}, "
            f"{base.cost(args.cost) / rec.cost(args.cost):.2f}x the speed of the scene as "
            f"written -> {files['scene']}")
    log(f"wrote {files['html']} and {files['markdown']} ({len(trade.runs)} runs)")
    return EXIT_OK
