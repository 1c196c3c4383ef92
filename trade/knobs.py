"""The knobs that trade speed for accuracy, and the settings of a converged reference.

A run's settings are a *patch* of the scene file (:func:`render.scene.patch_scene_text`):
``{"render": {key: value}, "objects": {index: {key: value}}}``, so every run, and the
recommendation, is a scene file the user can render with ``pwc render``.

Each :class:`Knob` changes one thing and offers options from more accurate to cheaper:

* ``samples``: samples per pixel, with and without denoising (Open Image Denoise);
* per displaced object: ``dicing_tolerance`` and ``dicing_rate`` (pixels), and the
  ``displacement_method``: true displacement, bump from the same field, or a baked
  normal map of a size and bit depth (:mod:`render.displacement_method`);
* ``curves``: pwc profiles evaluated exactly in float64, in float32, or as polylines
  within a tolerance (only where the scene's materials load profiles);
* ``texture_filter``: bilinear or nearest (only where they load image textures);
* ``max_depth`` and ``rr_depth``: the longest path and where Russian roulette starts.

Knobs that cannot change a scene (no displaced object, no profile, no texture) are not
offered: only what the scene models is measured.
"""

from __future__ import annotations

import json
from dataclasses import dataclass, field

__all__ = ["Knob", "Option", "knobs_for", "reference_patch", "merge", "patch_key", "describe",
           "ci_resolution", "CI_WIDTH"]

#: the CI-sized sweep's image width (the height keeps the scene's aspect)
CI_WIDTH = 32


def ci_resolution(width: int, height: int) -> tuple[int, int]:
    """The CI-sized image of a ``width`` x ``height`` scene.

    Examples
    --------
    >>> ci_resolution(128, 96), ci_resolution(1, 1000)
    ((32, 24), (32, 32000))
    """
    return CI_WIDTH, max(1, round(CI_WIDTH * height / width))

#: values of each knob: the full sweep and the CI-sized one
SPP = {"full": (1, 2, 4, 8, 16, 32, 64, 128, 256), "ci": (1, 4)}
DICING_TOLERANCE = {"full": (0.25, 1.0, 2.0, 4.0, 8.0), "ci": (4.0,)}
DICING_RATE = {"full": (0.5, 2.0, 4.0, 8.0), "ci": (4.0,)}
NORMAL_MAPS = {"full": ((1024, 16), (1024, 8), (256, 16), (256, 8)), "ci": ((32, 8),)}
POLYLINE = {"full": (1e-4, 1e-3, 1e-2), "ci": (1e-2,)}
MAX_DEPTH = {"full": (2, 3, 4, 6, 12), "ci": (2,)}
RR_DEPTH = {"full": (1, 2, 3, 8), "ci": (1,)}
#: the reference dices finer than any option (pixels)
REFERENCE_DICING = {"dicing_tolerance": 0.25, "dicing_rate": 0.5}
#: and traces paths at least this long
REFERENCE_DEPTH = 16


@dataclass(frozen=True)
class Option:
    """One value of a knob: a label and the scene patch that sets it."""

    label: str
    patch: dict


@dataclass
class Knob:
    """A setting traded for speed, with its options (the scene's own value excluded)."""

    name: str
    family: str
    options: list[Option] = field(default_factory=list)
    #: what the scene as written has
    baseline: str = ""


def patch_key(patch: dict) -> str:
    """A canonical string of a patch (runs with equal keys render the same scene)."""
    return json.dumps(patch, sort_keys=True, default=str)


def merge(*patches: dict) -> dict:
    """Patches applied one after another (later keys win)."""
    out: dict = {"render": {}, "objects": {}}
    for p in patches:
        out["render"].update(p.get("render", {}))
        for i, keys in p.get("objects", {}).items():
            out["objects"].setdefault(i, {}).update(keys)
    return out


def describe(patch: dict, names: list[str]) -> str:
    """A patch in words: ``spp 4, denoise; ornament: bump``."""
    parts = [f"{k} {_short(v)}" for k, v in sorted(patch.get("render", {}).items())
             if k != "resolution"]
    for i, keys in sorted(patch.get("objects", {}).items()):
        parts.append(f"{names[i]}: " + ", ".join(f"{k} {_short(v)}" for k, v in keys.items()))
    return "; ".join(parts) or "the scene as written"


def _short(v) -> str:
    if isinstance(v, bool):
        return "on" if v else "off"
    if isinstance(v, float):
        return f"{v:g}"
    return str(v)


def _obj(i: int, **keys) -> dict:
    return {"objects": {i: keys}}


def knobs_for(scene, loads: dict, size: str = "full", denoiser: bool = True) -> list[Knob]:
    """The knobs that can change ``scene`` (read as written), with their options.

    Parameters
    ----------
    scene : render.scene.Scene
        Built (:meth:`render.scene.Scene.build`): an object whose displacement the camera
        cannot see was not diced, and offers no displacement knob.
    loads : dict
        The profiles and textures its materials loaded
        (:func:`render.library.resources.track_loads`).
    size : {"full", "ci"}
        The full sweep, or the CI-sized one (one or two options per knob).
    denoiser : bool
        Whether Open Image Denoise is available (offer denoised options).
    """
    from displacement.dice import is_mesh_surface

    st = scene.settings
    knobs = []
    samples = Knob("samples", "samples", baseline=f"spp {st.spp}" +
                   (", denoise" if st.denoise else ""))
    spp_values = sorted({v for v in SPP[size] if v <= max(2 * st.spp, 4)} | {st.spp})
    for n in spp_values:
        for d in ((False, True) if denoiser else (False,)):
            if (n, d) != (st.spp, st.denoise):
                label = f"spp {n}" + (", denoised" if d else "")
                samples.options.append(Option(label, {"render": {"spp": n, "denoise": d}}))
    knobs.append(samples)
    for i, obj in enumerate(scene.objects):
        field_ = obj.original_displacement or obj.displacement
        if field_ is None or obj.not_diced:  # no relief, or none the camera can see
            continue
        if obj.displacement_method == "displacement":  # diced: its dicing is a knob
            tol = obj.dicing_tolerance or st.dicing_tolerance
            rate = obj.dicing_rate or st.dicing_rate
            knobs.append(Knob(f"dicing_tolerance ({obj.name})", "dicing", [
                Option(f"{obj.name}: tolerance {v:g} px", _obj(i, dicing_tolerance=v))
                for v in DICING_TOLERANCE[size] if v != tol], f"{tol:g} px"))
            knobs.append(Knob(f"dicing_rate ({obj.name})", "dicing", [
                Option(f"{obj.name}: rate {v:g} px", _obj(i, dicing_rate=v))
                for v in DICING_RATE[size] if v != rate], f"{rate:g} px"))
        if not is_mesh_surface(obj.surface):
            method = Knob(f"displacement_method ({obj.name})", "displacement",
                          baseline=obj.displacement_method)
            method.options.append(Option(f"{obj.name}: bump", _obj(
                i, displacement_method="bump")))
            for px, bits in NORMAL_MAPS[size]:
                method.options.append(Option(
                    f"{obj.name}: normal map {px} px {bits}-bit", _obj(
                        i, displacement_method="normal_map", normal_map_size=px,
                        normal_map_bits=bits)))
            if obj.displacement_method != "displacement":
                method.options.insert(0, Option(f"{obj.name}: displacement", _obj(
                    i, displacement_method="displacement")))
            knobs.append(method)
    if loads.get("profiles"):
        curves = Knob("curves", "curves", baseline=st.curves)
        curves.options.append(Option("curves float32", {"render": {"curves": "float32"}}))
        for tol in POLYLINE[size]:
            curves.options.append(Option(f"curves polyline {tol:g}", {"render": {
                "curves": "polyline", "curve_tolerance": tol}}))
        knobs.append(curves)
    if loads.get("textures"):
        other = "nearest" if st.texture_filter == "bilinear" else "bilinear"
        knobs.append(Knob("texture_filter", "textures", [
            Option(f"textures {other}", {"render": {"texture_filter": other}})],
            st.texture_filter))
    knobs.append(Knob("max_depth", "paths", [
        Option(f"max_depth {v}", {"render": {"max_depth": v}})
        for v in MAX_DEPTH[size] if v != st.max_depth], str(st.max_depth)))
    knobs.append(Knob("rr_depth", "paths", [
        Option(f"rr_depth {v}", {"render": {"rr_depth": v}})
        for v in RR_DEPTH[size] if v != st.rr_depth], str(st.rr_depth)))
    return [k for k in knobs if k.options]


def reference_patch(scene, spp: int) -> dict:
    """Settings of the converged reference: ``spp`` samples, no denoising, paths at least
    :data:`REFERENCE_DEPTH` long (or unlimited as written), exact curves, bilinear
    textures, true displacement diced finer than any option, even where the camera
    cannot see it."""
    st = scene.settings
    depth = -1 if st.max_depth == -1 else max(st.max_depth, REFERENCE_DEPTH)
    patch = {"render": {"spp": int(spp), "denoise": False, "max_depth": depth,
                        "curves": "exact", "texture_filter": "bilinear",
                        "dice_invisible": True, **REFERENCE_DICING},
             "objects": {}}
    for i, obj in enumerate(scene.objects):
        if (obj.original_displacement or obj.displacement) is not None:
            patch["objects"][i] = {"displacement_method": "displacement", **REFERENCE_DICING}
    return patch
