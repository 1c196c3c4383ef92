"""Render-time adaptive tessellation ("dicing") of displaced surfaces for a camera.

:func:`dice` turns a base surface, a displacement field and the camera that will render
it into world-space triangles (:class:`DicedMesh`), only as finely as the camera needs:

* **Adaptive**: the surface is sampled every ``dicing_rate`` pixels on screen, and only
  the vertices needed to keep the screen-space distance between the diced surface and
  the true displaced surface within ``tolerance`` pixels are kept (tested at the edge and
  face midpoints of every cell).  Outside the view frustum both are coarser by
  ``offscreen_rate / dicing_rate``.  A triangle cap bounds memory: when it is reached a
  :class:`DicingCapWarning` is issued and the surface is diced coarser to fit.
* **Crack-free**: neighbouring triangles share their vertices; seam and pole vertices
  are bit-identical copies, so a watertight base surface stays watertight.
* **Knot-aligned**: a field with ``uv_knots = (knots_u, knots_v)`` (the u or v values of
  its creases, e.g. a profile's breakpoints) gets grid lines exactly there, and shading
  normals are split along them.

The ``dicing_rate`` is the finest scale the dicer looks at and dices to (the spacing of
its samples, as in Cycles or RenderMan), not the length of every edge: where the
displaced surface is flat on screen to within the tolerance, edges are much longer.
"""

from __future__ import annotations

import time

import numpy as np

from displacement.camera import Camera
from displacement.dice.evaluator import DisplacedSurface, check_transform
from displacement.dice.mesh import DicedMesh, DicingCapWarning, DicingWarning
from displacement.dice.parametric import dice_parametric

__all__ = ["DicedMesh", "DicingCapWarning", "DicingWarning", "dice", "screen_error",
           "locate_uv", "is_mesh_surface", "displacement_on_screen"]


def is_mesh_surface(surface) -> bool:
    """Whether ``surface`` is diced per base triangle (``base_mesh`` and ``state_at``;
    :class:`~displacement.surfaces.MeshSurface` says so with ``is_mesh = True``) rather
    than over its uv domain (``state_at_uv``)."""
    if getattr(surface, "is_mesh", False):
        return True
    return (hasattr(surface, "base_mesh") and hasattr(surface, "state_at")
            and not hasattr(surface, "state_at_uv"))


def _check_positive(name: str, value: float) -> float:
    try:
        value = float(value)
    except (TypeError, ValueError):
        raise ValueError(f"dice: {name} must be a number, got {value!r}") from None
    if not (np.isfinite(value) and value > 0.0):
        raise ValueError(f"dice: {name} must be a finite number > 0, got {value}")
    return value


def dice(surface, field, camera: Camera, transform=None, dicing_rate: float = 1.0,
         tolerance: float = 0.5, max_triangles: int = 2_000_000, offscreen_rate: float = 8.0,
         uniform=None) -> DicedMesh:
    """Tessellate a displaced surface for a camera.

    Parameters
    ----------
    surface
        A parametric surface with ``state_at_uv(uv)`` (optional attributes
        ``periodic_u`` / ``periodic_v``, missing = False), or a mesh surface with
        ``base_mesh()`` and ``state_at(face_index, barycentric)``.
    field : callable or None
        ``field(state) -> (n, 3)`` displacement vectors in object space; the displaced
        position is ``state.position + field(state)``, then ``transform`` applies.  An
        optional attribute ``uv_knots = (knots_u or None, knots_v or None)`` lists the u
        and v values of the field's creases.  None: the object is not displaced and is
        not diced (its base surface is returned, as coarse as the tolerance allows).
    camera : Camera
        The camera the mesh is diced for.
    transform : (4, 4) float64 or None
        Object-to-world affine transform (None: the identity).
    dicing_rate : float
        Pixels: the surface is sampled this finely on screen, and no edge is split below
        this length.
    tolerance : float
        Pixels: the largest allowed screen-space distance between the diced and the true
        displaced surface at the tested edge and face midpoints.
    max_triangles : int
        Cap on the triangle count; reaching it warns (:class:`DicingCapWarning`) and
        dices coarser, never exceeding it.
    offscreen_rate : float
        Pixels: the dicing rate outside the view frustum (the tolerance there is scaled by
        the same ``offscreen_rate / dicing_rate``).
    uniform : None, int or (int, int)
        Dice a uniform grid of this many intervals in u and v instead (a baseline; no
        adaptivity and no knot insertion).  For a mesh surface the first number is the
        number of segments of every base edge.

    Returns
    -------
    DicedMesh

    Examples
    --------
    The unit square, not displaced, is not diced: two triangles.

    >>> from displacement.surfaces import UnitSquare
    >>> cam = Camera(position=(0.5, 0.5, 2.0), look_at=(0.5, 0.5, 0.0), width=64, height=64)
    >>> dice(UnitSquare(), None, cam).triangle_count
    2

    A constant displacement is a translation: still flat, still two triangles.

    >>> m = dice(UnitSquare(), lambda s: np.tile([0.0, 0.0, 0.25], (len(s), 1)), cam)
    >>> m.triangle_count, m.vertices[:, 2].tolist()
    (2, [0.25, 0.25, 0.25, 0.25])
    """
    start = time.perf_counter()
    if not isinstance(camera, Camera):
        raise ValueError(f"dice: camera must be a displacement.camera.Camera, got "
                         f"{type(camera).__name__}")
    dicing_rate = _check_positive("dicing_rate", dicing_rate)
    tolerance = _check_positive("tolerance", tolerance)
    offscreen_rate = _check_positive("offscreen_rate", offscreen_rate)
    if int(max_triangles) != max_triangles or max_triangles < 2:
        raise ValueError(f"dice: max_triangles must be an integer >= 2, got {max_triangles}")
    max_triangles = int(max_triangles)
    if uniform is not None:
        nu, nv = (uniform, uniform) if np.ndim(uniform) == 0 else tuple(uniform)
        if int(nu) != nu or int(nv) != nv or nu < 1 or nv < 1:
            raise ValueError(f"dice: uniform must be a positive integer or a pair of them, "
                             f"got {uniform!r}")
        uniform = (int(nu), int(nv))
    if field is not None and not callable(field):
        raise ValueError(f"dice: field must be callable (state -> (n, 3)) or None, got "
                         f"{type(field).__name__}")
    transform = check_transform(np.eye(4) if transform is None else transform)
    ds = DisplacedSurface(surface, field, transform, camera, dicing_rate, tolerance,
                          offscreen_rate)
    knots = getattr(field, "uv_knots", None) or (None, None)
    if len(knots) != 2:
        raise ValueError(f"dice: field.uv_knots must be a pair (knots_u, knots_v), got "
                         f"{knots!r}")

    if is_mesh_surface(surface):
        from displacement.dice.triangles import dice_triangles
        mesh = dice_triangles(ds, max_triangles, uniform=uniform, coarse=field is None)
    elif hasattr(surface, "state_at_uv"):
        mesh = dice_parametric(ds, knots, bool(getattr(surface, "periodic_u", False)),
                               bool(getattr(surface, "periodic_v", False)), max_triangles,
                               uniform=uniform, coarse=field is None)
    else:
        raise ValueError(f"dice: {type(surface).__name__} is not a surface: it needs "
                         "state_at_uv(uv), or base_mesh() and state_at(face, barycentric)")
    stats = dict(mesh.stats)
    stats.update(triangles=mesh.triangle_count, vertices=len(mesh.vertices),
                 time_s=time.perf_counter() - start, evaluations=ds.evaluations,
                 diced=field is not None, nonfinite_displacements=ds.nonfinite)
    object.__setattr__(mesh, "stats", stats)
    return mesh


def displacement_on_screen(surface, field, camera: Camera, transform=None,
                           samples: int = 65, margin_px: float = 8.0,
                           stop_above: float | None = None) -> tuple[float, bool]:
    """How far a displacement moves a parametric surface on screen, and whether the
    displaced surface can be in view: what decides if dicing it can show anything.

    The field is sampled on a 17 x 17 grid of uv, then on a ``samples`` x ``samples`` one
    (the dicer's pilot grid), both with the field's knot lines.  With ``stop_above``, a
    grid that already shows a displacement longer than that, in view, ends the search:
    the common case (a visible relief) costs one small grid.

    Returns
    -------
    pixels : float
        The largest screen length of a sampled displacement vector (world length times
        :meth:`Camera.raster_scale`, the larger of its two ends).  Where it is under the
        dicing tolerance, the undisplaced surface is already within the tolerance of the
        displaced one.
    in_view : bool
        False only when every sample, displaced or not, lies behind the camera, or in
        front of it and beyond one edge of the image (grown by ``margin_px``): then the
        convex hull of the samples, and the surface, is out of the frustum.

    Examples
    --------
    >>> from displacement.surfaces import UnitSquare
    >>> cam = Camera(position=(0.5, 0.5, 2.0), look_at=(0.5, 0.5, 0.0), width=64, height=64,
    ...              ortho_height=2.0)
    >>> up = lambda s: np.tile([0.0, 0.0, 0.01], (len(s), 1))  # 0.01 units = 0.32 px
    >>> px, seen = displacement_on_screen(UnitSquare(), up, cam)
    >>> round(px, 6), seen
    (0.32, True)
    >>> aside = np.eye(4)
    >>> aside[0, 3] = 40.0                                     # moved 40 units aside
    >>> displacement_on_screen(UnitSquare(), up, cam, aside)[1]
    False
    """
    knots_u, knots_v = getattr(field, "uv_knots", (None, None))
    transform = np.eye(4) if transform is None else transform
    ds = DisplacedSurface(surface, field, transform, camera, 1.0, 1.0, 1.0)
    w, h, m = camera.width, camera.height, float(margin_px)
    pixels, in_view = 0.0, True
    for n in (17, max(17, int(samples))):
        grid = np.linspace(0.0, 1.0, n)
        u = np.unique(np.concatenate([grid, np.asarray(knots_u if knots_u is not None else [])]))
        v = np.unique(np.concatenate([grid, np.asarray(knots_v if knots_v is not None else [])]))
        state = surface.state_at_uv(np.stack(np.meshgrid(u, v), axis=-1).reshape(-1, 2))
        base = ds.to_world(state.position)
        moved = ds.to_world(ds._displace(state))
        scale = np.maximum(camera.raster_scale(base), camera.raster_scale(moved))
        pixels = max(pixels, float(np.max(np.linalg.norm(moved - base, axis=1) * scale)))
        if stop_above is not None and pixels > stop_above and np.any(
                camera.in_frustum(moved, m)):
            return pixels, True
        both = np.concatenate([base, moved])
        xy, depth = camera.project(both)
        out = bool(np.all(depth <= 0.0)) or (bool(np.all(depth > 0.0)) and any(
            np.all(test) for test in (xy[:, 0] < -m, xy[:, 0] > w + m, xy[:, 1] < -m,
                                      xy[:, 1] > h + m)))
        in_view = not out
    return pixels, in_view


def screen_error(mesh: DicedMesh, surface, field, camera: Camera, transform=None,
                 samples_per_triangle: int = 4, max_samples: int | None = None,
                 rng: np.random.Generator | None = None, uv: np.ndarray | None = None,
                 visible_only: bool = True) -> np.ndarray:
    """Screen-space distances (pixels) between a diced mesh and the true displaced surface.

    Points are drawn uniformly in random triangles (or given as ``uv``, located in the
    mesh's uv triangulation); the diced point (barycentric interpolation of the world
    vertices) and the true displaced point at the same uv are both projected, and their
    raster distance is returned.

    Parameters
    ----------
    mesh : DicedMesh
        Diced from a parametric ``surface``.
    surface, field, camera, transform
        As given to :func:`dice`.
    samples_per_triangle : int
        Random points per triangle.
    max_samples : int or None
        Draw at most this many points in total (random triangles, with repetition).
    rng : numpy.random.Generator
    uv : (k, 2) float64 or None
        Measure at these texture coordinates instead of random points (points outside
        the mesh's uv triangulation are dropped).
    visible_only : bool
        Keep only points whose true position is in front of the camera and in the image.

    Returns
    -------
    (k,) float64
    """
    rng = np.random.default_rng(0) if rng is None else rng
    if uv is None:
        n = len(mesh.faces) * int(samples_per_triangle)
        if max_samples is not None and n > max_samples:
            tri = rng.integers(0, len(mesh.faces), int(max_samples))
        else:
            tri = np.repeat(np.arange(len(mesh.faces)), int(samples_per_triangle))
        r = rng.random((len(tri), 2))
        flip = r.sum(axis=1) > 1.0
        r[flip] = 1.0 - r[flip]
        bary = np.stack([1.0 - r[:, 0] - r[:, 1], r[:, 0], r[:, 1]], axis=1)
        corners = mesh.faces[tri]
        at = np.einsum("ij,ijk->ik", bary, mesh.uv[corners])
    else:
        at = np.asarray(uv, dtype=np.float64).reshape(-1, 2)
        corners, bary, kept = locate_uv(mesh, at)
        at = at[kept]
    diced = np.einsum("ij,ijk->ik", bary, mesh.vertices[corners])
    ds = DisplacedSurface(surface, field, np.eye(4) if transform is None else transform,
                          camera, 1.0, 1.0, 1.0)
    true = ds.eval_uv(at)
    xy_true, depth = camera.project(true)
    xy_diced, _ = camera.project(diced)
    err = np.linalg.norm(xy_true - xy_diced, axis=1)
    if visible_only:
        err = err[camera.in_frustum(true)]
    return err


def locate_uv(mesh: DicedMesh, uv: np.ndarray):
    """Triangles of a diced mesh that contain texture coordinates.

    Parameters
    ----------
    mesh : DicedMesh
    uv : (k, 2) float64

    Returns
    -------
    corners : (j, 3) int64
        Vertex indices of the containing triangle of each located point.
    bary : (j, 3) float64
        Barycentric coordinates of the point in that triangle (in uv).
    kept : (j,) int64
        Which of the k points were located (points outside the uv domain, or in the
        gaps a pole's collapsed triangles leave in uv, are dropped).
    """
    uv = np.asarray(uv, dtype=np.float64).reshape(-1, 2)
    if mesh.grid is None:
        return _locate_uv_any(mesh, uv)
    u_lines, v_lines, cell_faces = mesh.grid
    inside = ((uv[:, 0] >= u_lines[0]) & (uv[:, 0] <= u_lines[-1])
              & (uv[:, 1] >= v_lines[0]) & (uv[:, 1] <= v_lines[-1]))
    i = np.clip(np.searchsorted(u_lines, uv[:, 0], "right") - 1, 0, len(u_lines) - 2)
    j = np.clip(np.searchsorted(v_lines, uv[:, 1], "right") - 1, 0, len(v_lines) - 2)
    cand = cell_faces[j, i]                                   # (k, 2)
    best_bary = np.zeros((len(uv), 3))
    best_face = np.full(len(uv), -1, dtype=np.int64)
    best_score = np.full(len(uv), -np.inf)
    for k in range(2):
        f = cand[:, k]
        ok = f >= 0
        corners = mesh.faces[np.where(ok, f, 0)]
        bary = _barycentric_2d(mesh.uv[corners], uv)
        score = np.where(ok, bary.min(axis=1), -np.inf)
        better = score > best_score
        best_score = np.where(better, score, best_score)
        best_face = np.where(better, f, best_face)
        best_bary = np.where(better[:, None], bary, best_bary)
    kept = np.flatnonzero(inside & (best_face >= 0) & (best_score >= -1e-9))
    return mesh.faces[best_face[kept]], best_bary[kept], kept


def _barycentric_2d(tri: np.ndarray, q: np.ndarray) -> np.ndarray:
    """Barycentric coordinates (k, 3) of points q (k, 2) in 2-D triangles tri (k, 3, 2);
    a degenerate triangle gives (1, 0, 0)-like weights with a very negative minimum."""
    p0 = tri[:, 0]
    e1, e2, eq = tri[:, 1] - p0, tri[:, 2] - p0, q - p0
    d = e1[:, 0] * e2[:, 1] - e1[:, 1] * e2[:, 0]
    ok = d != 0
    d = np.where(ok, d, 1.0)
    l1 = np.where(ok, (eq[:, 0] * e2[:, 1] - eq[:, 1] * e2[:, 0]) / d, -1.0)
    l2 = np.where(ok, (e1[:, 0] * eq[:, 1] - e1[:, 1] * eq[:, 0]) / d, -1.0)
    return np.stack([1.0 - l1 - l2, l1, l2], axis=1)


def _locate_uv_any(mesh: DicedMesh, uv: np.ndarray):
    """locate_uv for a mesh without a grid: a trapezoid map of its uv triangulation."""
    from matplotlib.tri import TrapezoidMapTriFinder, Triangulation

    # merge copies with the same uv (crease duplicates); drop triangles with no uv area
    key, inv = np.unique(mesh.uv, axis=0, return_inverse=True)
    f = inv.reshape(-1)[mesh.faces]
    a, b, c = key[f[:, 0]], key[f[:, 1]], key[f[:, 2]]
    area = (b[:, 0] - a[:, 0]) * (c[:, 1] - a[:, 1]) - (b[:, 1] - a[:, 1]) * (c[:, 0] - a[:, 0])
    good = np.flatnonzero(area != 0)
    swap = area[good] < 0
    fg = np.where(swap[:, None], f[good][:, [0, 2, 1]], f[good])
    orig = np.where(swap[:, None], mesh.faces[good][:, [0, 2, 1]], mesh.faces[good])
    found = TrapezoidMapTriFinder(Triangulation(key[:, 0], key[:, 1], fg))(uv[:, 0], uv[:, 1])
    kept = np.flatnonzero(found >= 0)
    bary = _barycentric_2d(key[fg[found[kept]]], uv[kept])
    return orig[found[kept]], bary, kept
