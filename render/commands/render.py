"""The ``pwc render`` subcommand: render a TOML scene to a linear EXR and an sRGB PNG.

Registered through the ``pwc.commands`` entry point (``render =
"render.commands.render:register"``); ``pwc`` calls :func:`register` with its
subparsers and then ``args.func(args)``.  Errors in the scene are printed as
``file:line:col: message`` and exit with status 1; no traceback.  With
``--scheduler`` or ``--workers`` the chunks run on a Dask cluster
(:mod:`render.distributed`); a cluster that cannot render exits with status 3.
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

from pwc.cli import add_profiles_option
from pwc.files import OutputError, prepare_output
from render.distributed import add_cluster_options
from render.mdlc.options import add_mdl_path_option

__all__ = ["register", "run"]

EXIT_OK, EXIT_ERRORS, EXIT_USAGE, EXIT_IO = 0, 1, 2, 3

_DESCRIPTION = """\
Render a scene file with the Embree path tracer.  The scene (TOML) gives the camera,
lights, objects with MDL material expressions as the Handbook prints them, and render
settings; the options below override its [render] table.  Output: linear float RGBA
OpenEXR with optional AOV layers, and an optional sRGB PNG preview.  With --scheduler or
--workers the image's chunks run on a Dask cluster: the same image, bit for bit."""

_EPILOG = """\
examples:
  pwc render gallery/scenes/fig_12_06.toml -o out.exr --png out.png
  pwc render scene.toml -o out.exr --time 30 --aov albedo,normal --denoise
  pwc render scene.toml -o out.exr --spp 256 --seed 7 --threads 2
  pwc render scene.toml -o out.exr --spp 1024 --workers 2
  pwc render scene.toml -o out.exr --time 60 --scheduler tcp://scheduler-host:8786"""


def register(subparsers) -> argparse.ArgumentParser:
    """Add ``render`` to the ``pwc`` command's subparsers and return its parser."""
    p = subparsers.add_parser(
        "render",
        help="render a TOML scene to EXR/PNG (Embree path tracer)",
        description=_DESCRIPTION,
        epilog=_EPILOG,
        formatter_class=argparse.RawDescriptionHelpFormatter,
    )
    p.add_argument("scene", metavar="SCENE.toml",
                   help="the scene file, or the name of a bundled gallery scene (fig_14_28)")
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
    p.add_argument(
        "--threads",
        type=int,
        metavar="N",
        help="threads: in-process (default 2), or per --workers process (default 1)",
    )
    add_cluster_options(p)
    p.add_argument(
        "--chunks-per-task",
        type=int,
        metavar="N",
        help="on a cluster: chunks of 65536 samples in one task (default: one per 6 threads "
        "of the cluster); the same image",
    )
    p.add_argument("--half", action="store_true", help="write 16-bit half floats")
    p.add_argument("--quiet", action="store_true", help="no progress bar or summary")
    add_profiles_option(p)
    add_mdl_path_option(p)
    p.set_defaults(func=run)
    return p


def _error(message: str, status: int) -> int:
    print(f"pwc render: error: {message}", file=sys.stderr)
    return status


def run(args) -> int:
    """Execute ``pwc render`` with parsed arguments; returns the exit status."""
    from render.distributed import ClusterError, cluster, render_on_cluster
    from render.film import AOVS, check_film_memory
    from render.integrator import render
    from render.scene import SceneError, SceneReadError, load_scene

    aovs = [a.strip() for a in args.aov.split(",") if a.strip()]
    for a in aovs:
        if a not in AOVS:
            return _error(f"unknown AOV {a!r}: choose from {', '.join(AOVS)}", EXIT_USAGE)
    if args.spp is not None and args.spp < 1:
        return _error(f"--spp must be >= 1, got {args.spp}", EXIT_USAGE)
    if args.time is not None and not args.time > 0:
        return _error(f"--time must be > 0 seconds, got {args.time}", EXIT_USAGE)
    if args.threads is not None and args.threads < 1:
        return _error(f"--threads must be >= 1, got {args.threads}", EXIT_USAGE)
    if args.chunks_per_task is not None and args.chunks_per_task < 1:
        return _error(f"--chunks-per-task must be >= 1, got {args.chunks_per_task}", EXIT_USAGE)
    if not str(args.output).lower().endswith(".exr"):
        return _error(f"the output must be an .exr file, got {args.output!r}", EXIT_USAGE)
    if args.png and not str(args.png).lower().endswith(".png"):
        return _error(f"--png must name a .png file, got {args.png!r}", EXIT_USAGE)
    denoise = args.denoise
    if denoise:
        try:
            import pyoidn  # noqa: F401
        except ImportError:
            return _error("--denoise needs Open Image Denoise: pip install pyoidn", EXIT_USAGE)
    overrides = {"spp": args.spp, "time": args.time, "seed": args.seed, "max_depth": args.max_depth}
    if args.resolution:
        w, h = args.resolution
        if w < 1 or h < 1:
            return _error(f"--resolution must be positive, got {w} {h}", EXIT_USAGE)
    try:  # every output is checked before the render starts
        prepare_output(args.output, "the image")
        if args.png:
            prepare_output(args.png, "the --png preview")
    except OutputError as e:
        return _error(str(e), EXIT_IO)
    try:
        scene = load_scene(_scene_file(args.scene), overrides=overrides,
                           profile_dirs=args.profiles, mdl_paths=args.mdl_path)
        if args.resolution:
            import dataclasses

            scene.settings.width, scene.settings.height = args.resolution
            scene.camera = dataclasses.replace(
                scene.camera, width=args.resolution[0], height=args.resolution[1]
            )
        denoise = denoise or scene.settings.denoise  # --denoise, or denoise = true
        if denoise:
            import pyoidn  # noqa: F401 - raises ImportError (reported below) when missing
        # an image too large for memory is refused before the scene is diced
        check_film_memory(scene.camera.width, scene.camera.height, aovs, denoise)
        from render.precompile import notice_first_compile

        notice_first_compile("pwc render", args.quiet)
        # a bar redrawn with carriage returns only on a terminal, not into a log
        progress = not args.quiet and sys.stderr.isatty()
        if args.scheduler or args.workers:
            with cluster(args.scheduler, args.workers, args.threads or 1) as client:
                film = render_on_cluster(scene, client, aovs=aovs, progress=progress,
                                         denoise=denoise,
                                         chunks_per_task=args.chunks_per_task)
        else:
            film = render(scene, aovs=aovs, progress=progress, threads=args.threads or 2,
                          denoise=denoise)
    except ClusterError as e:
        return _error(str(e), EXIT_IO)
    except SceneReadError as e:
        print(str(e), file=sys.stderr)
        return EXIT_IO
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
    except (OSError, RuntimeError) as e:  # OpenEXR reports a failed write as RuntimeError
        return _error(f"cannot write the output: {getattr(e, 'strerror', None) or e}", EXIT_IO)
    if not args.quiet:
        st = film.stats
        bound = st.get("bound_objects") or []
        shaded = f"; shaded per hit in numpy: {', '.join(bound)}" if bound else ""
        wrote = f"wrote {Path(args.output)}" + (f" and {Path(args.png)}" if args.png else "")
        if "workers" in st:
            where = (f"{len(st['workers'])} workers, scene {st['scene_bytes'] / 1e6:.1f} MB "
                     f"shipped to each, built in {st['build_s']:.1f} s")
        else:
            threads = args.threads or 2
            share = st["embree_time_s"] / (threads * st["time_s"]) if st["time_s"] else 0.0
            where = f"{share:.0%} of thread time in Embree"
        print(
            f"{wrote}: {film.width}x{film.height}, {st['spp']} spp in "
            f"{st['time_s']:.2f} s "
            f"({st['samples_per_s'] / 1e6:.2f} M samples/s, {where}, "
            f"{st['triangles']} triangles{shaded})",
            file=sys.stderr,
        )
        for line in modelling_lines(scene, st["geometry"], aovs):
            print(line, file=sys.stderr)
    return EXIT_OK


def modelling_lines(scene, geometry_stats, aovs) -> list[str]:
    """What was modelled, one line per object, then the lights, volumes and AOVs (the
    render summary of ``pwc render``)."""
    from render.scene import modelling_summary

    summary = modelling_summary(scene, geometry_stats)
    lines = []
    for m in summary:
        notes = [m["displacement"].replace("_", " ") if m["displacement"] not in (
            "none", "displacement") else "",
            "bumped normal" if m["normal"].startswith("evaluated") else "",
            "emits" if m["emits"] else "", "volume" if m["volume"] else "",
            "thin-walled" if m["thin_walled"] else "", "cutout" if m["cutout"] else ""]
        lines.append(f"  {m['name']}: {m['geometry']}; "
                     + ", ".join([x for x in notes if x] + m["dfs"]))
    lights = [type(light).__name__ for light in scene.lights]
    lights += [f"area ({m['name']})" for m in summary if m["emits"]]
    volumes = "on" if any(m["volume"] for m in summary) else "none"
    lines.append(f"  lights: {', '.join(lights) or 'none'}; volumes: {volumes}; "
                 f"AOVs: {', '.join(aovs) or 'none'}")
    return lines


def _scene_file(arg: str) -> Path:
    """The scene file: the path given, else a bundled gallery scene of that name."""
    from render.library.resources import bundled_scenes

    p = Path(arg)
    if p.exists() or any(c in arg for c in "/\\"):
        return p
    bundled = bundled_scenes() / (arg if arg.endswith(".toml") else f"{arg}.toml")
    return bundled if bundled.is_file() else p
