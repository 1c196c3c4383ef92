"""How far a render is from its reference: image errors, and the geometric error of the
displaced objects on screen.

Image errors compare linear RGB images of the same size:

* ``rmse``: root mean square difference of the linear values;
* ``rel_rmse``: ``rmse`` over the reference's mean (scale-free: 0.01 is "1 %");
* ``flip``: mean LDR-FLIP (``flip_evaluator``, the perceptual metric of the gallery's
  regression test) of the sRGB encodings;
* ``rel_mean``: the relative difference of the image means (bias, not noise).

The geometric error is the screen-space distance, in pixels, between the triangles an
object was traced with and its true displaced surface
(:func:`displacement.dice.screen_error`): the dicer's tolerance for diced objects, the
whole displacement for bumped ones (their triangles are the base surface).
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

__all__ = ["METRICS", "image_errors", "geometric_error"]

#: the image error metrics, with what they measure (for reports)
METRICS = {
    "flip": "mean FLIP (perceptual, sRGB)",
    "rel_rmse": "RMSE / reference mean",
    "rmse": "RMSE (linear)",
    "rel_mean": "relative error of the mean",
}


def _flip_on_one_thread() -> None:
    """Run FLIP's OpenMP loops on the calling thread only.  Beside a renderer (Embree's
    worker threads, on a busy machine) its team of threads waits on descheduled members:
    a 32 x 24 image took 0.13 s instead of 1 ms (measured); one thread is as fast as two
    up to 512 x 384."""
    import ctypes
    from importlib.util import find_spec

    spec = find_spec("flip_evaluator")
    if spec is None or not spec.origin:
        return
    for lib in (Path(spec.origin).parents[1] / "flip_evaluator.libs").glob("libgomp*.so*"):
        try:
            ctypes.CDLL(str(lib)).omp_set_num_threads(1)
        except (OSError, AttributeError):
            pass


def image_errors(test: np.ndarray, ref: np.ndarray) -> dict[str, float]:
    """Errors of ``test`` against ``ref``, both (h, w, 3) linear RGB.

    Examples
    --------
    >>> ref = np.full((4, 4, 3), 0.5)
    >>> e = image_errors(ref * 1.02, ref)
    >>> round(e["rmse"], 6), round(e["rel_rmse"], 6), round(e["rel_mean"], 6)
    (0.01, 0.02, 0.02)
    >>> image_errors(ref, ref)["flip"]
    0.0
    """
    import flip_evaluator

    from render.film import linear_to_srgb

    # aligned and contiguous: numpy sums misaligned data (as an array can arrive from a
    # cluster's worker) in another order, and the mean would differ in its last bits
    test = np.require(test, np.float64, ["C", "A"])
    ref = np.require(ref, np.float64, ["C", "A"])
    if test.shape != ref.shape:
        raise ValueError(f"image of shape {test.shape} against a reference of {ref.shape}")
    rmse = float(np.sqrt(np.mean((test - ref) ** 2)))
    mean_ref = float(ref.mean())
    scale = mean_ref if mean_ref > 0 else 1.0
    a = np.ascontiguousarray(linear_to_srgb(ref), dtype=np.float32)
    b = np.ascontiguousarray(linear_to_srgb(test), dtype=np.float32)
    _flip_on_one_thread()
    _, flip, _ = flip_evaluator.evaluate(a, b, "LDR", applyMagma=False)
    return {"rmse": rmse, "rel_rmse": rmse / scale, "flip": float(flip),
            "rel_mean": abs(float(test.mean()) - mean_ref) / scale}


def geometric_error(scene, geometry, samples: int = 20_000, seed: int = 0) -> float | None:
    """The largest screen-space distance (pixels), over the scene's displaced parametric
    objects, between their traced triangles and their true displaced surface, from
    ``samples`` random points per object in view; None without such objects.

    Parameters
    ----------
    scene : render.scene.Scene
        The scene as written, with exact curves: it defines the true surfaces.
    geometry : render.scene.Geometry
        The triangles a run traced (its objects in the same order as ``scene``'s).

    Objects whose displacement was modelled as bump or a normal map count: their
    triangles are the flat base surface, so their error is the displacement itself.
    """
    from types import SimpleNamespace

    from displacement.dice import is_mesh_surface, screen_error

    worst = None
    rng = np.random.default_rng(seed)
    for k, obj in enumerate(scene.objects):
        field = obj.original_displacement or obj.displacement
        if field is None or is_mesh_surface(obj.surface):
            continue
        first, last = geometry.face_offset[k], geometry.face_offset[k + 1]
        if last == first:
            continue
        faces = geometry.faces[first:last]
        used = np.unique(faces)
        remap = np.zeros(len(geometry.vertices), dtype=np.int64)
        remap[used] = np.arange(len(used))
        mesh = SimpleNamespace(vertices=geometry.vertices[used], uv=geometry.uv[used],
                               faces=remap[faces])
        err = screen_error(mesh, obj.surface, field, scene.camera, obj.transform,
                           max_samples=samples, rng=rng)
        if len(err):
            worst = max(worst or 0.0, float(err.max()))
    return worst
