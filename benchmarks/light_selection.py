"""Benchmark: how next-event estimation picks a light (``[render] light_selection``).

Run ``python benchmarks/light_selection.py`` (``--quick`` for a smoke run).  Every
figure compares the selections in the same run (the machine is shared and noisy: read
the ratios, not the absolute times).

* **frieze**: a diffuse cylinder (a molding along x) on a floor under a row of 100
  small one-sided area lights; each selection renders for the same wall time and its
  RMSE against a converged reference (``contribution``, 10x the time; scaled by
  sqrt(time taken / budget), passes being whole) is printed next to its time per sample.
* **sun and sky**: the same molding lit by a ``directional`` sun (irradiance 3) and a
  constant environment (radiance 0.1), 512 x 384 at 16 spp (issue 18: Cycles 2.1 %):
  the row noise, the spread of the pixels along an image row of the molding relative
  to their mean (a Lambertian cylinder along x seen by a camera without roll is the
  same along every row: the spread is pure noise), the median over its rows, next to
  the time per sample; the three selections, then ``contribution`` with the sun sampled
  at every vertex besides the selected light (``every_delta_light``), each with
  independent sample values and with the Sobol sampler (``[render] sampler``);
* **sky and lamps**: the molding under a low sun and sky and 8 of the frieze's lamps,
  equal-time RMSE against a reference 10x as long (the environment's importance at a
  vertex follows the normal: compare with the tree before that change in the same run,
  ``--only sky``);
* **tube**: the molding under a 12-unit emissive cylinder (4096 triangles) and a dim
  sky, equal-time RMSE (an emitter of many triangles in groups, or, in the tree before,
  one light: ``--only tube`` in each).
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from displacement.surfaces import Cylinder, Plane, UnitSquare  # noqa: E402
from render import material as M  # noqa: E402
from render.camera import Camera  # noqa: E402
from render.integrator import Integrator  # noqa: E402
from render.lights import ConstantEnvironment, DirectionalLight  # noqa: E402
from render.scene import (  # noqa: E402
    RenderSettings,
    Scene,
    SceneObject,
    emissive_material,
    make_transform,
)

SELECTIONS = ("uniform", "power", "contribution")
THREADS = 2


def _diffuse(tint):
    return M.material(surface=M.material_surface(M.df.diffuse_reflection_bsdf(tint=tint)))


def molding_scene(width, height, lights, extra=(), selection="contribution", spp=16,
                  every_delta=False, sampler="sobol"):
    """A cylinder of radius 0.3 along x on a 14 x 6 floor, seen from the front."""
    floor = Plane(size=(14.0, 6.0), origin=(-7.0, 0.0, 3.0), axis_u=(1, 0, 0),
                  axis_v=(0, 0, -1))
    objects = [SceneObject(floor, _diffuse(0.5), name="floor"),
               SceneObject(Cylinder(0.3, 14.0), _diffuse(0.7),
                           make_transform(translate=(0.0, 0.3, 0.0), rotate=(0.0, 0.0, 90.0)),
                           name="molding", resolution=(256, 1)),
               *extra]
    cam = Camera(position=(0.0, 1.2, 4.0), look_at=(0.0, 0.3, 0.0), fov_y_deg=30.0,
                 width=width, height=height)
    return Scene(cam, objects, list(lights),
                 RenderSettings(width, height, spp=spp, max_depth=8,
                                light_selection=selection, every_delta_light=every_delta,
                                sampler=sampler))


def frieze_lights(n=100):
    """``n`` one-sided 5 cm squares facing down at height 1.2 in a row along x."""
    xs = np.linspace(-6.0, 6.0, n)
    return [SceneObject(UnitSquare(), emissive_material((np.pi * 150.0,) * 3),
                        make_transform(translate=(x - 0.025, 1.2, -0.2 + 0.4 * (i % 2)),
                                       rotate=(90.0, 0.0, 0.0), scale=(0.05, 0.05, 1.0)),
                        name=f"lamp{i}") for i, x in enumerate(xs)]


def equal_time(scene, seconds, reference=None):
    """Render ``scene`` for ``seconds`` (after a warm-up): ``(integrator, film, RMSE
    against reference, reference)``, the reference rendered for 10x the time when not
    given.  Passes are whole: the RMSE is scaled to exactly the budget (error ~
    1 / sqrt(time))."""
    integ = Integrator(scene, scene.build())
    integ.render(spp=1, progress=False)  # warm-up
    if reference is None:
        reference = integ.render(time_budget=10 * seconds, seed=100, progress=False,
                                 threads=THREADS).rgb()
    film = integ.render(time_budget=seconds, seed=1, progress=False, threads=THREADS)
    rmse = float(np.sqrt(np.mean((film.rgb() - reference) ** 2)))
    return integ, film, rmse * np.sqrt(film.stats["time_s"] / seconds), reference


def frieze(args):
    w, h = args.size
    rows = []
    lamps = frieze_lights(args.lights)
    *_, reference = equal_time(molding_scene(w, h, [], lamps, "contribution"), args.seconds)
    for sel in SELECTIONS:
        _, film, rmse, _ = equal_time(molding_scene(w, h, [], lamps, sel), args.seconds,
                                      reference)
        rows.append((sel, film.stats["spp"], film.stats["time_s"], rmse))
    base = rows[0][3]
    print(f"# frieze: {args.lights} area lights, {w}x{h}, equal time {args.seconds} s, "
          f"{THREADS} threads; reference: contribution, {10 * args.seconds} s")
    for sel, spp, t, rmse in rows:
        print(f"frieze  {sel:>12}: {spp:4d} spp in {t:.1f} s "
              f"({t / (w * h * spp) * 1e9:.0f} ns per sample), equal-time RMSE {rmse:.5f} "
              f"({rmse / base:.2f}x uniform's)")


def row_noise(img, mask):
    """Median over the rows wholly on ``mask`` (central half of the columns) of the
    relative spread (std / mean of the luminance) along the row."""
    h, w = mask.shape
    cols = slice(w // 4, 3 * w // 4)
    lum = img @ np.array([0.212671, 0.715160, 0.072169])
    out = [lum[r, cols].std() / lum[r, cols].mean() for r in range(h)
           if mask[r, cols].all() and lum[r, cols].mean() > 0]
    return float(np.median(out)), len(out)


def sun_and_sky(args):
    w, h = args.sun_size
    lights = [DirectionalLight((0.5, -1.0, -0.6), 3.0), ConstantEnvironment(0.1)]
    print(f"# sun and sky: directional irradiance 3 + constant environment 0.1, {w}x{h}, "
          f"{args.spp} spp, {THREADS} threads; row noise on the molding (Cycles 5.0: 2.1%)")
    rows = [(s, False) for s in SELECTIONS] + [("contribution", True)]
    for sampler, sel, every in [(m, s, e) for m in ("independent", "sobol") for s, e in rows]:
        scene = molding_scene(w, h, lights, selection=sel, spp=args.spp, every_delta=every,
                              sampler=sampler)
        integ = Integrator(scene, scene.build(), aovs=("object_id",))
        integ.render(spp=1, progress=False)  # warm-up
        film = integ.render(spp=args.spp, seed=1, progress=False, threads=THREADS)
        noise, n_rows = row_noise(film.rgb(), film.aov("object_id") == 1)
        per = film.stats["time_s"] / (w * h * args.spp) * 1e9
        name = f"{sampler}, {sel}" + (" + every delta light" if every else "")
        print(f"sun+sky {name:>45}: row noise {noise:6.2%} over {n_rows} rows, "
              f"{per:.0f} ns per sample ({film.stats['time_s']:.1f} s)")


def sky_and_lamps(args):
    """The frieze's molding under a low sun and sky and a row of 8 lamps: how much each
    choice of light is worth depends on which way the surface faces."""
    from render.sky import SunAndSky, sun_direction_from_angles

    w, h = args.size
    sky = SunAndSky(sun_direction_from_angles(20.0, 200.0), turbidity=3.0, intensity=0.5)
    _, film, rmse, reference = equal_time(
        molding_scene(w, h, [sky], frieze_lights(8), "contribution"), args.seconds)
    t, spp = film.stats["time_s"], film.stats["spp"]
    print(f"sky+lamps contribution: {spp} spp in {t:.1f} s ({t / (w * h * spp) * 1e9:.0f} ns "
          f"per sample), equal-time RMSE {rmse:.5f} (reference {10 * args.seconds} s), "
          f"mean {reference.mean():.4f}")


def tube(args):
    """The molding under a 12-unit neon tube (an emissive cylinder of 4096 triangles)
    and a dim sky: equal-time RMSE against a reference 10x as long.  Compare trees (the
    tube as one light, or in groups) in the same run with ``--only tube``."""
    w, h = args.size
    lamp = SceneObject(Cylinder(0.03, 12.0), emissive_material((np.pi * 20.0,) * 3),
                       make_transform(translate=(0.0, 1.0, 0.3), rotate=(0.0, 0.0, 90.0)),
                       name="tube", resolution=(256, 8))
    integ, film, rmse, reference = equal_time(
        molding_scene(w, h, [ConstantEnvironment(0.05)], [lamp], "contribution"), args.seconds)
    t, spp = film.stats["time_s"], film.stats["spp"]
    print(f"tube contribution, {len(integ.lights)} lights: {spp} spp in {t:.1f} s "
          f"({t / (w * h * spp) * 1e9:.0f} ns per sample), equal-time RMSE {rmse:.5f} "
          f"(reference {10 * args.seconds} s), mean {reference.mean():.4f}")


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--quick", action="store_true", help="tiny sizes (a smoke run)")
    ap.add_argument("--size", type=int, nargs=2, default=(256, 192), metavar=("W", "H"),
                    help="frieze image size")
    ap.add_argument("--seconds", type=float, default=4.0, help="frieze equal-time budget")
    ap.add_argument("--lights", type=int, default=100, help="frieze area lights")
    ap.add_argument("--sun-size", type=int, nargs=2, default=(512, 384), metavar=("W", "H"))
    ap.add_argument("--spp", type=int, default=16, help="sun-and-sky samples per pixel")
    ap.add_argument("--only", choices=("frieze", "sun", "sky", "tube"),
                    help="one of the scenes")
    args = ap.parse_args(argv)
    if args.quick:
        args.size, args.seconds, args.sun_size, args.spp = (48, 32), 0.5, (64, 48), 4
    if args.only in (None, "frieze"):
        frieze(args)
    if args.only in (None, "sun"):
        sun_and_sky(args)
    if args.only in (None, "sky"):
        sky_and_lamps(args)
    if args.only in (None, "tube"):
        tube(args)
    return 0


if __name__ == "__main__":
    sys.exit(main())
