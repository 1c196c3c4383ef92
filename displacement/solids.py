"""Solids for fabrication: a pwc profile extruded, revolved, swept or mitred into a frame.

The Handbook ends chapter 13 noting that fabrication needs real geometry; this module
turns any compiled profile (:class:`pwc.Curve`) into a watertight, verified
:class:`manifold3d.Manifold`, so solids combine with ``a + b`` (union), ``a - b``
(difference) and ``a ^ b`` (intersection) and export to STL, 3MF and OBJ.

Conventions
-----------
* **Axes** are the Handbook's: right-handed, y up.  A profile's x is the depth out
  from the wall and its y the run up the wall, in the curve's normalized units
  (object units).
* **The cross-section** of a profile is the region between the curve and the wall
  ``x = 0``: an open profile is closed back to the wall by straight segments -- from
  its last point horizontally to ``(0, y_last)``, down (or up) the wall to
  ``(0, y_first)``, and horizontally back to its first point (segments of zero length
  are skipped, so a profile that starts and ends on the wall adds only the wall).  A
  closed profile (last point equal to the first) is its own cross-section and is not
  joined to the wall.  A loop that crosses itself is filled by the non-zero rule
  (see :func:`section_polygons`).
* **Tolerance**: every arc is sampled with ``curve.polyline(tolerance)``, whose chords
  lie within ``tolerance`` of the exact arcs and whose vertices lie *on* the exact
  curve.  Every solid here deviates from the exact shape by at most ``tolerance``
  (a two-sided, Hausdorff bound on the surface).  Where a second discretization is
  needed (the circle of a revolution, the ring of a sweep) the budget is split in two
  halves, each bounding one of the two errors.  Two caveats: ``revolve(...,
  segments=n)`` honours ``n`` instead of the tolerance on the circle, and the sweep's
  ring is refined until 7 probes per interval are within tolerance (measured, not
  proved, for the ring between probes).

Listings 15.12-15.14 and 15.19 fix the rotation: a profile point ``(x, y)`` at angle
``theta = 2 pi u`` goes to ``((x + radius_offset) cos theta, y,
-(x + radius_offset) sin theta)``, i.e. ``float3(x, y, 0) * y_rotation_3(theta)`` in
MDL's row-vector convention, so the solids coincide with the displaced surfaces of
``pwc_angular_displace`` and ``double_pwc``.
"""

from __future__ import annotations

from pathlib import Path

import manifold3d
import numpy as np
import trimesh

import pwc

__all__ = [
    "EXPORT_FORMATS",
    "MAX_TRIANGLES",
    "profile_area",
    "profile_centroid",
    "section_polygons",
    "extrude",
    "revolve",
    "sweep",
    "frame",
    "frame_pieces",
    "to_trimesh",
    "export",
    "solid_info",
]

#: File suffixes :func:`export` writes (through trimesh).
EXPORT_FORMATS = (".stl", ".3mf", ".obj")

#: Largest mesh a builder will make; a finer request raises ValueError (memory bound).
MAX_TRIANGLES = 20_000_000

# Points closer than this (relative to the curve's extent) are one point, and |x| below
# it is on the wall / axis; far below any useful tolerance, far above float64 rounding.
_SAME_POINT_REL = 1e-12

# Refinement of the sweep ring: interior probes per interval and a cap on passes.
_RING_PROBES = 7
_RING_MAX_PASSES = 40


# --------------------------------------------------------------------------- checks
def _check_tolerance(tolerance: float) -> float:
    tolerance = float(tolerance)
    if not (np.isfinite(tolerance) and tolerance > 0):
        raise ValueError(
            f"tolerance must be a positive finite distance (object units), got {tolerance}"
        )
    return tolerance


def _check_positive(name: str, value: float) -> float:
    value = float(value)
    if not (np.isfinite(value) and value > 0):
        raise ValueError(f"{name} must be a positive finite number, got {value}")
    return value


def _check_curve(curve) -> None:
    if not isinstance(curve, pwc.Curve):
        raise ValueError(
            f"expected a compiled profile (pwc.Curve), got {type(curve).__name__}; "
            "compile it with pwc.load(path) or pwc.compile_text(text)"
        )


def _extent(curve: pwc.Curve) -> float:
    """Characteristic size of the curve (largest |coordinate|, at least 1e-300)."""
    return max(float(np.abs(curve.bbox).max()), 1e-300)


# ------------------------------------------------------------------ exact region maths
def _piece_integrals(curve: pwc.Curve) -> np.ndarray:
    """Green's-theorem integrals of every piece of the cross-section loop.

    Returns
    -------
    (3,) float64
        ``[A, Mx, My]`` with ``A = 1/2 ∮ (x dy - y dx)`` (signed area),
        ``Mx = ∮ x²/2 dy`` (= ∬ x dA) and ``My = -∮ y²/2 dx`` (= ∬ y dA), summed over
        the curve's pieces (segments and exact arcs) and the closing wall segments.
    """
    pt = curve.pt
    arc = curve.is_arc.copy()
    arc[0] = False
    total = np.zeros(3)

    # straight pieces: the curve's segments, then the closure to the wall
    a, b = pt[:-1][~arc[1:]], pt[1:][~arc[1:]]
    closing = _closure_points(curve)
    if len(closing):
        chain = np.vstack([pt[-1:], closing, pt[:1]])
        a = np.vstack([a, chain[:-1]])
        b = np.vstack([b, chain[1:]])
    xa, ya, xb, yb = a[:, 0], a[:, 1], b[:, 0], b[:, 1]
    total[0] += 0.5 * np.sum(xa * yb - xb * ya)
    total[1] += np.sum((yb - ya) * (xa * xa + xa * xb + xb * xb)) / 6.0
    total[2] -= np.sum((xb - xa) * (ya * ya + ya * yb + yb * yb)) / 6.0

    # arcs: x = cx + r cos(phi), y = cy + r sin(phi), phi from start to end angle
    i = np.flatnonzero(arc)
    cx, cy, r = curve.center[i, 0], curve.center[i, 1], curve.radius[i]
    p0, p1 = curve.start_angle[i], curve.end_angle[i]
    s0, s1, c0, c1 = np.sin(p0), np.sin(p1), np.cos(p0), np.cos(p1)
    total[0] += 0.5 * np.sum(r * cx * (s1 - s0) - r * cy * (c1 - c0) + r * r * (p1 - p0))
    # ∫ (cx + r cos)^2 / 2 * r cos dphi
    int_cos = s1 - s0
    int_cos2 = 0.5 * (p1 - p0) + 0.25 * (np.sin(2 * p1) - np.sin(2 * p0))
    int_cos3 = (s1 - s1**3 / 3.0) - (s0 - s0**3 / 3.0)
    total[1] += np.sum(0.5 * r * (cx * cx * int_cos + 2 * cx * r * int_cos2 + r * r * int_cos3))
    # -∫ (cy + r sin)^2 / 2 * (-r sin) dphi
    int_sin = -(c1 - c0)
    int_sin2 = 0.5 * (p1 - p0) - 0.25 * (np.sin(2 * p1) - np.sin(2 * p0))
    int_sin3 = (-c1 + c1**3 / 3.0) - (-c0 + c0**3 / 3.0)
    total[2] += np.sum(0.5 * r * (cy * cy * int_sin + 2 * cy * r * int_sin2 + r * r * int_sin3))
    return total


def _closure_points(curve: pwc.Curve) -> np.ndarray:
    """(k, 2) points that close an open profile back to the wall (empty if closed)."""
    if curve.is_closed:
        return np.zeros((0, 2))
    first, last = curve.pt[0], curve.pt[-1]
    return np.array([[0.0, last[1]], [0.0, first[1]]])


def _exact_integrals(curve: pwc.Curve) -> np.ndarray:
    """:func:`_piece_integrals`, after checking that the loop does not cross itself.

    The check samples the loop at 1e-4 of the curve's extent; a crossing lobe
    thinner than that may pass unseen.
    """
    try:
        loop = _raw_loop(curve, 1e-4 * _extent(curve))
    except ValueError:
        return np.zeros(3)  # no area: nothing can cross
    if not _is_simple(loop):
        raise ValueError(
            f"the cross-section of profile '{curve.name}' crosses itself (closed back to "
            "the wall x = 0 its loop is not simple), so its exact area is not defined by "
            "the pieces alone; use section_polygons(curve, tolerance) for its sampled "
            "region"
        )
    return _piece_integrals(curve)


def profile_area(curve: pwc.Curve) -> float:
    """Exact area of a profile's cross-section (the region between curve and wall).

    Straight pieces contribute their shoelace term; each arc contributes its chord
    term plus its circular segment (sector minus triangle), evaluated in closed form
    from the arc's centre, radius and angles -- no sampling.  The loop is the one
    :func:`section_polygons` samples (closed back to the wall ``x = 0`` if open).

    Parameters
    ----------
    curve : pwc.Curve

    Returns
    -------
    float
        The area (non-negative, whichever way the loop runs).

    Raises
    ------
    ValueError
        If the closed loop crosses itself (then the region is not bounded by the
        exact pieces alone; :func:`section_polygons` gives its sampled polygons).

    Examples
    --------
    A quarter disc of radius 1 against the wall:

    >>> import pwc
    >>> c = pwc.compile_text("0 0\\n1 0\\n0 1 :angle 90")
    >>> round(profile_area(c), 12) == round(np.pi / 4, 12)
    True

    A profile lying along the wall encloses nothing:

    >>> profile_area(pwc.compile_text("0 0\\n0 1"))
    0.0
    """
    _check_curve(curve)
    return float(abs(_exact_integrals(curve)[0]))


def profile_centroid(curve: pwc.Curve) -> np.ndarray:
    """Exact centroid ``(x̄, ȳ)`` of a profile's cross-section (see :func:`profile_area`).

    With it Pappus' theorem gives the volume of a revolution,
    ``2 pi (x̄ + radius_offset) * area``.

    Returns
    -------
    (2,) float64

    Raises
    ------
    ValueError
        If the cross-section has zero area (no centroid).

    Examples
    --------
    >>> import pwc
    >>> profile_centroid(pwc.compile_text("0 0\\n1 0\\n1 1\\n0 1")).tolist()
    [0.5, 0.5]
    """
    _check_curve(curve)
    a, mx, my = _exact_integrals(curve)
    if abs(a) <= (_SAME_POINT_REL * _extent(curve)) ** 2:
        raise ValueError(
            f"profile '{curve.name}' encloses no area, so it has no centroid; "
            "a profile needs depth (x != 0) somewhere"
        )
    return np.array([mx / a, my / a])


# ------------------------------------------------------------------ the sampled section
def _dedupe_loop(loop: np.ndarray, eps: float) -> np.ndarray:
    """Drop consecutive (cyclically) repeated points."""
    step = np.linalg.norm(np.diff(loop, axis=0, append=loop[:1]), axis=1)
    keep = step > eps
    if not keep.any():
        return loop[:1]
    return loop[keep]


def _raw_loop(curve: pwc.Curve, tolerance: float) -> np.ndarray:
    """The profile's polyline closed to the wall, counter-clockwise, possibly crossing."""
    eps = _SAME_POINT_REL * _extent(curve)
    _, pts = curve.polyline(tolerance)
    loop = np.vstack([pts, _closure_points(curve)])
    loop[np.abs(loop[:, 0]) <= eps, 0] = 0.0
    loop = _dedupe_loop(loop, eps)
    signed = _shoelace(loop) if len(loop) >= 3 else 0.0
    if abs(signed) <= eps * eps:
        raise ValueError(
            f"profile '{curve.name}' encloses no area at tolerance {tolerance:g} "
            "(it lies along the wall x = 0, or its arcs collapse to chords); "
            "give the profile depth or lower the tolerance"
        )
    return loop[::-1].copy() if signed < 0 else loop


def section_polygons(curve: pwc.Curve, tolerance: float) -> list[np.ndarray]:
    """The sampled cross-section of a profile, as polygons.

    The profile's polyline (arcs within ``tolerance``) is closed back to the wall as
    the module docstring describes.  When that loop is simple it is the one polygon
    returned.  When it crosses itself -- Listing 15.3's stepped block
    (``profiles/segments.pwc``) ends at ``(4/7, 1)`` inside its own outline, so its
    closing segment cuts the last step -- the cross-section is every point the loop
    winds around (non-zero rule): the lobes are separated at the crossings, and the
    crossing points are recomputed exactly from the two edges that meet there.

    Parameters
    ----------
    curve : pwc.Curve
    tolerance : float
        Largest distance between the chords and the exact arcs (object units).

    Returns
    -------
    list of (m_i, 2) float64
        Outer boundaries counter-clockwise, holes clockwise, first point not
        repeated.  Every vertex lies on the exact profile, on the wall ``x = 0``
        (coordinates within 1e-12 of the wall are snapped onto it), or at a crossing
        of two chords.

    Raises
    ------
    ValueError
        If the cross-section encloses no area at this tolerance.

    Examples
    --------
    >>> import pwc
    >>> [p.tolist() for p in section_polygons(pwc.compile_text("0 0\\n1 0\\n1 1"), 1e-3)]
    [[[0.0, 0.0], [1.0, 0.0], [1.0, 1.0], [0.0, 1.0]]]

    A profile that returns along the wall is empty:

    >>> section_polygons(pwc.compile_text("0 0\\n0 1"), 1e-3)  # doctest: +ELLIPSIS
    Traceback (most recent call last):
    ...
    ValueError: profile 'curve' encloses no area at tolerance 0.001 (it lies along ...
    """
    _check_curve(curve)
    tolerance = _check_tolerance(tolerance)
    loop = _raw_loop(curve, tolerance)
    if _is_simple(loop):
        return [loop]
    return _resolve_crossings(loop, curve.name)


def _shoelace(loop: np.ndarray) -> float:
    x, y = loop[:, 0], loop[:, 1]
    return 0.5 * float(np.sum(x * np.roll(y, -1) - np.roll(x, -1) * y))


def _nonzero_union(loop: np.ndarray) -> tuple[manifold3d.CrossSection, float]:
    """manifold3d's non-zero fill of the loop (coordinates rounded to ~1e-8 of scale)."""
    scale = float(np.abs(loop).max())
    return manifold3d.CrossSection([loop / scale], manifold3d.FillRule.NonZero), scale


def _is_simple(loop: np.ndarray) -> bool:
    """True if the counter-clockwise polygon does not cross itself.

    A simple polygon's non-zero fill is one region whose area equals its signed
    area; a figure-eight or a doubled lobe changes one or the other.
    """
    cs, scale = _nonzero_union(loop)
    union = cs.area() * scale * scale
    area = _shoelace(loop)
    perimeter = float(np.sum(np.linalg.norm(np.diff(loop, axis=0, append=loop[:1]), axis=1)))
    # the fill rounds coordinates to ~1e-8 of the scale: allow that along the perimeter
    slack = 1e-7 * perimeter * scale + 1e-9 * area
    return abs(union - area) <= slack and cs.num_contour() == 1


def _resolve_crossings(loop: np.ndarray, name: str) -> list[np.ndarray]:
    """Split a self-crossing loop into the polygons of its non-zero region, exactly.

    manifold3d's fill finds the regions but rounds coordinates; every vertex it
    returns is moved back onto the loop vertex it came from, or, for a crossing, onto
    the exact intersection of the two loop edges that cross there.
    """
    cs, scale = _nonzero_union(loop)
    polygons = [np.asarray(p, dtype=np.float64) * scale for p in cs.to_polygons()]
    if not polygons:
        raise ValueError(f"the cross-section of profile '{name}' encloses no area")
    snap = 1e-6 * scale
    q = np.vstack(polygons)
    # nearest loop vertex within `snap`, found among the vertices sorted by x
    order = np.argsort(loop[:, 0], kind="stable")
    xs = loop[order, 0]
    lo = np.searchsorted(xs, q[:, 0] - snap, side="left")
    hi = np.searchsorted(xs, q[:, 0] + snap, side="right")
    count = hi - lo
    owner = np.repeat(np.arange(len(q)), count)
    within = np.arange(count.sum()) - np.repeat(np.cumsum(count) - count, count)
    cand = order[np.repeat(lo, count) + within]
    dist = np.linalg.norm(loop[cand] - q[owner], axis=1)
    best = np.full(len(q), np.inf)
    np.minimum.at(best, owner, dist)
    hit = np.zeros(len(q), dtype=np.int64)
    chosen = dist <= best[owner]
    hit[owner[chosen]] = cand[chosen]
    exact = q.copy()
    matched = best <= snap
    exact[matched] = loop[hit[matched]]
    # crossings: intersect the pairs of loop edges passing within `snap` of the vertex
    a, d = loop, np.roll(loop, -1, axis=0) - loop
    for k in np.flatnonzero(~matched):
        dd = np.maximum(np.einsum("ij,ij->i", d, d), 1e-300)
        t = np.clip(np.einsum("ij,ij->i", q[k] - a, d) / dd, 0.0, 1.0)
        near = np.flatnonzero(np.linalg.norm(a + t[:, None] * d - q[k], axis=1) <= snap)
        best_point, best_dist = q[k], np.inf
        for i in near:
            for j in near:
                cross = d[i, 0] * d[j, 1] - d[i, 1] * d[j, 0]
                if j <= i or cross == 0.0:
                    continue
                s = ((a[j, 0] - a[i, 0]) * d[j, 1] - (a[j, 1] - a[i, 1]) * d[j, 0]) / cross
                p = a[i] + s * d[i]
                if np.linalg.norm(p - q[k]) < best_dist:
                    best_point, best_dist = p, np.linalg.norm(p - q[k])
        exact[k] = best_point
    sizes = np.cumsum([len(p) for p in polygons])[:-1]
    return [p for p in np.split(exact, sizes) if len(p) >= 3]


# ------------------------------------------------------------------- mesh -> manifold
def _to_manifold(vertices: np.ndarray, faces: np.ndarray, what: str) -> manifold3d.Manifold:
    """Verify a triangle mesh as a manifold3d solid, outward-oriented.

    The builders orient their triangles consistently but not necessarily outward;
    the signed volume (divergence theorem, in numpy) decides, so the mesh is handed
    to manifold3d -- which checks that it is a closed oriented 2-manifold -- once.
    """
    tri = vertices[faces]
    signed = np.einsum("ij,ij->i", tri[:, 0], np.cross(tri[:, 1], tri[:, 2])).sum()
    if signed < 0:
        faces = faces[:, ::-1]
    solid = manifold3d.Manifold(
        manifold3d.Mesh64(
            vert_properties=np.ascontiguousarray(vertices, dtype=np.float64),
            tri_verts=np.ascontiguousarray(faces, dtype=np.uint64),
        )
    )
    if solid.status() != manifold3d.Error.NoError or solid.is_empty():
        raise ValueError(f"the {what} is not a valid closed manifold ({solid.status().name})")
    return solid


def _check_budget(n_triangles: int) -> None:
    if n_triangles > MAX_TRIANGLES:
        raise ValueError(
            f"the solid would need {n_triangles:,} triangles (limit {MAX_TRIANGLES:,}); "
            "raise the tolerance"
        )


def _successors(polygons: list[np.ndarray]) -> tuple[np.ndarray, np.ndarray]:
    """All polygon vertices stacked, and the index of each one's successor."""
    points = np.vstack(polygons)
    sizes = np.array([len(p) for p in polygons])
    first = np.repeat(np.cumsum(sizes) - sizes, sizes)
    local = np.arange(len(points)) - first
    return points, first + (local + 1) % np.repeat(sizes, sizes)


def _prism_mesh(polygons: list[np.ndarray], length: float) -> tuple[np.ndarray, np.ndarray]:
    """Polygons in the x-y plane (outer CCW, holes CW) extruded from z = 0 to z = length."""
    points, nxt = _successors(polygons)
    m = len(points)
    caps = np.asarray(manifold3d.triangulate(polygons), dtype=np.int64).reshape(-1, 3)
    _check_budget(2 * len(caps) + 2 * m)
    vertices = np.zeros((2 * m, 3))
    vertices[:m, :2] = points
    vertices[m:, :2] = points
    vertices[m:, 2] = length
    i = np.arange(m)
    j = nxt
    sides = np.concatenate([np.c_[i, j, j + m], np.c_[i, j + m, i + m]])
    faces = np.concatenate([caps[:, ::-1], caps + m, sides])
    return vertices, faces


def _ring_mesh(
    polygons: list[np.ndarray],
    origins: np.ndarray,
    u_axes: np.ndarray,
    v_axes: np.ndarray,
    collapse: float | None = None,
) -> tuple[np.ndarray, np.ndarray]:
    """Carry planar polygons round a closed ring of frames and skin them.

    Polygon point ``(a, b)`` at station ``j`` goes to
    ``origins[j] + a * u_axes[j] + b * v_axes[j]``; the ring closes from station
    ``k - 1`` back to station 0.  For a revolution ``origins`` is 0, ``u_axes`` the
    rotated (and scaled) x direction and ``v_axes`` the y axis; for a frame the
    stations are the four corners.

    Parameters
    ----------
    polygons : list of (m_i, 2) float64
    origins, u_axes, v_axes : (k, 3) float64
    collapse : float, optional
        Points with ``a <= collapse`` are on the axis: one vertex for all stations
        (the stations must then agree there: ``origins`` and ``v_axes`` constant).

    Returns
    -------
    vertices : (v, 3) float64
    faces : (f, 3) int64
        Consistently oriented triangles (outward or inward, see ``_to_manifold``).
        Each quad between neighbouring stations is a planar trapezoid when its two
        rows are parallel, as they are for every ring built here.
    """
    points, nxt = _successors(polygons)
    m, k = len(points), len(origins)
    on_axis = points[:, 0] <= collapse if collapse is not None else np.zeros(m, dtype=bool)
    count = np.where(on_axis, 1, k)
    start = np.concatenate([[0], np.cumsum(count)[:-1]])
    _check_budget(2 * m * k)

    # vertices: one per axis point, a ring of k per other point
    off = ~on_axis
    rings = (
        origins[None, :, :]
        + points[off, 0][:, None, None] * u_axes[None, :, :]
        + points[off, 1][:, None, None] * v_axes[None, :, :]
    )
    vertices = np.zeros((int(count.sum()), 3))
    vertices[start[on_axis]] = origins[0] + points[on_axis, 1][:, None] * v_axes[0]
    vertices[(start[off][:, None] + np.arange(k)[None, :]).ravel()] = rings.reshape(-1, 3)

    def index(i: np.ndarray, j: np.ndarray) -> np.ndarray:  # point i at station j
        return start[i] + np.where(on_axis[i], 0, j)

    i = np.repeat(np.arange(m), k)
    j = np.tile(np.arange(k), m)
    i1, j1 = nxt[i], (j + 1) % k
    a, a1, b, b1 = index(i, j), index(i, j1), index(i1, j), index(i1, j1)
    faces = np.concatenate([np.c_[a, b, b1], np.c_[a, b1, a1]])
    # triangles with two corners on the axis collapse; edges along the axis vanish
    f0, f1, f2 = faces.T
    good = (f0 != f1) & (f1 != f2) & (f0 != f2)
    return vertices, faces[good]


def _revolution_frames(theta: np.ndarray, scale: np.ndarray) -> tuple[np.ndarray, ...]:
    """Stations of a revolution: x rotated by Listing 15.12's ``y_rotation_3(theta)``.

    ``float3(1, 0, 0) * y_rotation_3(theta) = (cos theta, 0, -sin theta)`` in MDL's
    row-vector convention; ``scale`` multiplies it (Listing 15.19's ``p.x *= scale``).
    """
    k = len(theta)
    u_axes = np.stack([scale * np.cos(theta), np.zeros(k), -scale * np.sin(theta)], -1)
    v_axes = np.broadcast_to([0.0, 1.0, 0.0], (k, 3))
    return np.zeros((k, 3)), u_axes, v_axes


def _meridian(curve: pwc.Curve, tolerance: float, radius_offset: float, what: str):
    """The section shifted to ``rho = x + radius_offset``, checked to be >= 0."""
    radius_offset = float(radius_offset)
    if not np.isfinite(radius_offset):
        raise ValueError(f"radius_offset must be finite, got {radius_offset}")
    eps = _SAME_POINT_REL * (_extent(curve) + abs(radius_offset))
    xmin = float(curve.bbox[0, 0]) if curve.is_closed else min(float(curve.bbox[0, 0]), 0.0)
    if xmin + radius_offset < -eps:
        raise ValueError(
            f"profile '{curve.name}' reaches x = {xmin:.6g}, behind the axis of the "
            f"{what} (x + radius_offset = {xmin + radius_offset:.6g} < 0), so the solid "
            f"would cross itself; give radius_offset >= {-xmin:.6g} or keep x >= 0"
        )
    polygons = []
    for p in section_polygons(curve, tolerance):
        p = p.copy()
        p[:, 0] += radius_offset
        p[p[:, 0] <= eps, 0] = 0.0
        polygons.append(p)
    return polygons, eps


def _segments_for(radius: float, tolerance: float) -> int:
    """Fewest equal segments of a full circle whose sagitta is <= tolerance."""
    if radius <= tolerance:
        return 3
    half_step = np.arccos(1.0 - tolerance / radius)
    return max(3, int(np.ceil(np.pi / half_step)))


# ---------------------------------------------------------------------- the builders
def extrude(curve: pwc.Curve, length: float, tolerance: float = 1e-3) -> manifold3d.Manifold:
    """A straight molding: the profile's cross-section extruded along z.

    The cross-section (see :func:`section_polygons`) lies in the x-y plane -- x the depth
    out from the wall, y the run up the wall, y up as in the Handbook -- and the solid
    spans ``0 <= z <= length``, the wall being the plane ``x = 0``.  Its volume is
    ``area * length`` with the area of the sampled section, within
    ``tolerance * perimeter * length`` of ``profile_area(curve) * length``.

    Parameters
    ----------
    curve : pwc.Curve
    length : float
        Length of the molding along z (object units), > 0.
    tolerance : float
        Largest distance between the solid's surface and the exact profile's.

    Returns
    -------
    manifold3d.Manifold

    Examples
    --------
    >>> import pwc
    >>> solid = extrude(pwc.compile_text("0 0\\n1 0\\n1 1\\n0 1"), 2.0)
    >>> round(solid.volume(), 12), solid.num_tri()
    (2.0, 12)
    """
    _check_curve(curve)
    length = _check_positive("length", length)
    polygons = section_polygons(curve, tolerance)
    return _to_manifold(*_prism_mesh(polygons, length), what=f"extrusion of '{curve.name}'")


def revolve(
    curve: pwc.Curve,
    tolerance: float = 1e-3,
    radius_offset: float = 0.0,
    segments: int | None = None,
) -> manifold3d.Manifold:
    """The profile revolved about the y axis (Listing 15.14's shape as a solid).

    A profile point ``(x, y)`` sweeps the circle ``((x + r) cos θ, y, -(x + r) sin θ)``
    with ``r = radius_offset``, exactly the displaced point of
    ``pwc_angular_displace`` (Listings 15.13-15.14) for ``r = 0``.  Points with
    ``x + r = 0`` stay on the axis, so a profile touching the axis closes there.

    Without ``segments`` the profile is sampled at ``tolerance / 2`` and the circle
    divided into the fewest equal segments whose sagitta at the largest radius is at
    most ``tolerance / 2``, so the surface is within ``tolerance`` of the exact solid
    of revolution.  With ``segments`` the profile is sampled at ``tolerance`` and the
    circle has exactly that many segments (its own sagitta is then
    ``rho_max (1 - cos(pi / segments))``).

    Parameters
    ----------
    curve : pwc.Curve
    tolerance : float
    radius_offset : float
        Added to every x before revolving (a hollow core of that radius if > 0).
    segments : int, optional
        Number of circular segments, >= 3.

    Returns
    -------
    manifold3d.Manifold
        Volume within the polygonal error of Pappus' value
        ``2 pi (x̄ + r) profile_area(curve)``.

    Raises
    ------
    ValueError
        If some ``x + radius_offset < 0`` (the solid would cross itself), or the
        cross-section is degenerate.

    Examples
    --------
    A unit square against the axis is a cylinder (here a 4-sided prism):

    >>> import pwc
    >>> round(revolve(pwc.compile_text("0 0\\n1 0\\n1 1\\n0 1"), segments=4).volume(), 12)
    2.0
    """
    _check_curve(curve)
    tolerance = _check_tolerance(tolerance)
    if segments is None:
        polygons, eps = _meridian(curve, tolerance / 2, radius_offset, "revolution")
        segments = _segments_for(max(float(p[:, 0].max()) for p in polygons), tolerance / 2)
    else:
        if isinstance(segments, bool) or int(segments) != segments or segments < 3:
            raise ValueError(f"segments must be an integer >= 3, got {segments!r}")
        polygons, eps = _meridian(curve, tolerance, radius_offset, "revolution")
        segments = int(segments)
    theta = 2 * np.pi * np.arange(segments) / segments
    stations = _revolution_frames(theta, np.ones(segments))
    vertices, faces = _ring_mesh(polygons, *stations, collapse=eps)
    return _to_manifold(vertices, faces, what=f"revolution of '{curve.name}'")


def _radial_range(curve: pwc.Curve) -> tuple[float, float]:
    """Exact smallest and largest distance of the curve from the origin."""
    pt = curve.pt
    arc = curve.is_arc[1:]
    a, b = pt[:-1], pt[1:]
    # segments: the closest point is the clamped projection of the origin
    d = b - a
    dd = np.maximum(np.einsum("ij,ij->i", d, d), 1e-300)
    f = np.clip(-np.einsum("ij,ij->i", a, d) / dd, 0.0, 1.0)
    seg_min = np.linalg.norm(a + f[:, None] * d, axis=1)
    ends = np.linalg.norm(pt, axis=1)
    lo = np.where(arc, np.inf, seg_min)
    hi = np.maximum(ends[:-1], ends[1:])
    # arcs: the nearest / farthest circle point lies along the centre's ray
    c, r = curve.center[1:], curve.radius[1:]
    p0, p1 = curve.start_angle[1:], curve.end_angle[1:]
    lo_angle = np.minimum(p0, p1)
    span = np.abs(p1 - p0)
    norm_c = np.linalg.norm(c, axis=1)
    toward = np.arctan2(-c[:, 1], -c[:, 0])  # direction from the centre to the origin

    def within(phi):
        return np.mod(phi - lo_angle, 2 * np.pi) <= span

    near = arc & within(toward)
    far = arc & within(toward + np.pi)
    lo = np.where(near, np.abs(norm_c - r), lo)
    lo = np.where(arc & ~near, np.minimum(ends[:-1], ends[1:]), lo)
    hi = np.where(far, norm_c + r, hi)
    return float(lo.min()), float(hi.max())


def _ring_samples(path: pwc.Curve, radius: float, tolerance: float) -> np.ndarray:
    """Sweep positions u in [0, 1) whose ring polygon is within tolerance of the ring.

    The ring at meridian radius ``radius`` is ``C(u) = radius |path(u)|
    (cos 2πu, -sin 2πu)``; starting from the path's knots and a uniform division,
    every interval whose chord misses ``C`` by more than ``tolerance`` at any of
    7 interior probes is halved, until none does.
    """
    smax = _radial_range(path)[1]
    n0 = max(_segments_for(radius * smax, tolerance), 4)
    u = np.unique(np.concatenate([path.t[:-1], np.arange(n0) / n0]))

    def ring(s):
        return radius * np.linalg.norm(path.evaluate(s), axis=-1)[..., None] * np.stack(
            [np.cos(2 * np.pi * s), -np.sin(2 * np.pi * s)], -1
        )

    probes = np.arange(1, _RING_PROBES + 1) / (_RING_PROBES + 1)
    for _ in range(_RING_MAX_PASSES):
        ua = u
        ub = np.append(u[1:], 1.0)
        pa, pb = ring(ua), ring(ub)
        uq = ua[:, None] + (ub - ua)[:, None] * probes[None, :]
        q = ring(uq)  # (k, p, 2)
        chord = (pb - pa)[:, None, :]
        t = np.einsum("kpi,kpi->kp", q - pa[:, None, :], chord) / np.maximum(
            np.einsum("kpi,kpi->kp", chord, chord), 1e-300
        )
        nearest = pa[:, None, :] + np.clip(t, 0, 1)[..., None] * chord
        miss = np.linalg.norm(q - nearest, axis=-1).max(axis=1)
        bad = miss > tolerance
        if not bad.any():
            return u
        _check_budget(len(u) + int(bad.sum()))
        u = np.sort(np.concatenate([u, 0.5 * (ua[bad] + ub[bad])]))
    raise ValueError(  # pragma: no cover - a ring that keeps failing would need a kink
        f"could not sample the sweep path '{path.name}' within tolerance {tolerance:g}"
    )


def sweep(
    profile: pwc.Curve,
    path_curve: pwc.Curve,
    tolerance: float = 1e-3,
    radius_offset: float = 0.0,
) -> manifold3d.Manifold:
    """The profile swept round a second, closed curve (Listings 15.19-15.20, ``double_pwc``).

    At sweep position ``u`` (angle ``θ = 2πu``) a profile point ``(x, y)`` goes to
    ``((x + r) s cos θ, y, -(x + r) s sin θ)`` with ``r = radius_offset`` and
    ``s = |path(u)|``, the distance of the path's point from the origin -- the
    displaced point of Listing 15.19's ``displace_to_pwc_point``.  A circular path of
    radius 1 gives :func:`revolve`.  The mesh is rings of profile points, one ring per
    path sample, closing at ``u = 1`` (no caps: the cross-section is a closed loop and
    so is the ring), verified by manifold3d.

    The profile is sampled at ``tolerance / (2 max(1, s_max))`` and the path adaptively,
    so that every ring is within ``tolerance / 2`` of the exact ring; the surface is
    within ``tolerance`` of the exact swept surface.

    Parameters
    ----------
    profile : pwc.Curve
        The molding profile (x = depth, y = run up the axis).
    path_curve : pwc.Curve
        A closed curve around the origin (its last point equal to its first, or at
        least at the same distance from the origin), never passing through the origin.
    tolerance : float
    radius_offset : float
        Added to the profile's x before scaling (Listing 15.19's ``radius_offset``).

    Returns
    -------
    manifold3d.Manifold
        Volume ``2π A (x̄ + r) mean_u(s²)`` for the exact shape (A and x̄ from
        :func:`profile_area` and :func:`profile_centroid`).

    Raises
    ------
    ValueError
        If the path is open or passes through the origin, or some ``x + r < 0``: the
        solid would not close or would cross itself.
    """
    _check_curve(profile)
    _check_curve(path_curve)
    tolerance = _check_tolerance(tolerance)
    s_start, s_end = np.linalg.norm(path_curve.pt[[0, -1]], axis=1)
    path_eps = _SAME_POINT_REL * _extent(path_curve)
    if abs(s_start - s_end) > path_eps:
        raise ValueError(
            f"the sweep path '{path_curve.name}' must be closed: its first point "
            f"{path_curve.pt[0].tolist()} and last point {path_curve.pt[-1].tolist()} are "
            "at different distances from the origin, so the swept solid would not close "
            "at u = 1; end the path where it starts"
        )
    s_min, s_max = _radial_range(path_curve)
    if s_min <= path_eps:
        raise ValueError(
            f"the sweep path '{path_curve.name}' passes through the origin "
            f"(min |path(u)| = {s_min:.3g}), where the swept profile collapses onto the "
            "axis and the solid pinches; move the path away from the origin"
        )
    polygons, eps = _meridian(
        profile, tolerance / (2 * max(1.0, s_max)), radius_offset, "sweep"
    )
    rho_max = max(float(p[:, 0].max()) for p in polygons)
    u = _ring_samples(path_curve, rho_max, tolerance / 2)
    scale = np.linalg.norm(path_curve.evaluate(u), axis=-1)
    stations = _revolution_frames(2 * np.pi * u, scale)
    vertices, faces = _ring_mesh(polygons, *stations, collapse=eps)
    return _to_manifold(
        vertices, faces, what=f"sweep of '{profile.name}' along '{path_curve.name}'"
    )


def _frame_layout(curve: pwc.Curve, width: float, height: float, tolerance: float):
    """Section (d inward from the outer edge, depth) and the frame's corner stations."""
    _check_curve(curve)
    width = _check_positive("width", width)
    height = _check_positive("height", height)
    polygons = section_polygons(curve, tolerance)
    ys = np.concatenate([p[:, 1] for p in polygons])
    band = float(ys.max() - ys.min())
    if not (width > 2 * band and height > 2 * band):
        raise ValueError(
            f"a frame of profile '{curve.name}' (band {band:.6g} wide) needs width and "
            f"height above twice the band, {2 * band:.6g}; got {width:g} x {height:g}"
        )
    # (d, depth): d = y - y_min inward from the outer edge, depth = x out of the wall
    # (swapping the axes mirrors the polygons: reverse them to keep outer boundaries
    # counter-clockwise, as triangulation needs)
    sections = [np.c_[p[::-1, 1] - ys.min(), p[::-1, 0]] for p in polygons]
    # outer corners counter-clockwise, each with its inward 45-degree diagonal
    corners = np.array(
        [[0.0, 0.0, 0.0], [width, 0.0, 0.0], [width, height, 0.0], [0.0, height, 0.0]]
    )
    inward = np.array([[1.0, 1.0, 0.0], [-1.0, 1.0, 0.0], [-1.0, -1.0, 0.0], [1.0, -1.0, 0.0]])
    return sections, corners, inward


def frame(
    curve: pwc.Curve, width: float, height: float, tolerance: float = 1e-3
) -> manifold3d.Manifold:
    """A mitred picture or door frame: four molding pieces meeting at 45° mitres.

    The frame lies in the x-y plane (y up) against the wall ``z = 0``, its outer edge
    the rectangle ``[0, width] x [0, height]``.  Each piece carries the profile's
    cross-section with the profile's x as the depth ``z`` out from the wall and the
    profile's y measured inward from the outer edge (the section's lowest y on the
    outer edge), so the band is ``w = y_max - y_min`` wide.  At each corner a
    section point at distance d from the outer edge lies on the mitre, at
    ``corner + d (±1, ±1)``.

    The assembled frame is built as one closed mesh -- the four pieces of
    :func:`frame_pieces` sharing their mitre faces -- rather than as a boolean union
    of the pieces.  Measured with manifold3d 3.5.4: the union of pieces that touch
    only along a mitre face is unreliable for non-convex sections (for
    ``profiles/right_angle_arc.pwc`` at tolerance 1e-4 it left zero-volume shells at
    two corners and added 3e-4 to the volume), while the single mesh is exact.  The
    solid is the same; its volume is the sum of the pieces' volumes.

    Parameters
    ----------
    curve : pwc.Curve
    width, height : float
        Outer size; each must exceed twice the band width ``w`` (leaving an opening).
    tolerance : float

    Returns
    -------
    manifold3d.Manifold
        Of genus 1 (for a simple cross-section), volume
        ``A (2 width + 2 height - 8 ȳ)``, with ``A`` the section's area and ``ȳ``
        its centroid's distance from the outer edge.

    Examples
    --------
    >>> import pwc
    >>> f = frame(pwc.compile_text("0 0\\n1 0\\n1 1\\n0 1"), 4.0, 3.0)
    >>> round(f.volume(), 9), f.genus()
    (10.0, 1)
    """
    sections, corners, inward = _frame_layout(curve, width, height, tolerance)
    v_axes = np.broadcast_to([0.0, 0.0, 1.0], (4, 3))
    vertices, faces = _ring_mesh(sections, corners, inward, v_axes)
    return _to_manifold(vertices, faces, what=f"frame of '{curve.name}'")


def frame_pieces(
    curve: pwc.Curve, width: float, height: float, tolerance: float = 1e-3
) -> list[manifold3d.Manifold]:
    """The four mitred pieces of :func:`frame`, each a separate solid, in place.

    Bottom, right, top, left: each is the profile extruded along its side and cut at
    both ends by the 45° mitre planes (its end vertices are placed on the mitres,
    which is exact, rather than found by a boolean cut).  For fabrication each piece
    is what a saw cuts; ``frame(...)`` is their assembly.

    Examples
    --------
    >>> import pwc
    >>> pieces = frame_pieces(pwc.compile_text("0 0\\n1 0\\n1 1\\n0 1"), 4.0, 3.0)
    >>> [round(p.volume(), 9) for p in pieces]
    [3.0, 2.0, 3.0, 2.0]
    """
    sections, corners, inward = _frame_layout(curve, width, height, tolerance)
    vertices, faces = _prism_mesh(sections, 1.0)  # z = 0 / 1: start / end of a piece
    d, depth, at_end = vertices[:, 0], vertices[:, 1], vertices[:, 2] > 0.5
    pieces = []
    for a in range(4):
        b = (a + 1) % 4
        start = corners[a, :2] + d[:, None] * inward[a, :2]
        end = corners[b, :2] + d[:, None] * inward[b, :2]
        placed = np.c_[np.where(at_end[:, None], end, start), depth]
        pieces.append(_to_manifold(placed, faces, what=f"frame piece of '{curve.name}'"))
    return pieces


# ------------------------------------------------------------------ output and checks
def to_trimesh(solid: manifold3d.Manifold) -> trimesh.Trimesh:
    """The solid as a :class:`trimesh.Trimesh` (float64 vertices, not re-processed).

    Examples
    --------
    >>> mesh = to_trimesh(manifold3d.Manifold.cube((1.0, 2.0, 3.0)))
    >>> mesh.is_watertight, round(float(mesh.volume), 12)
    (True, 6.0)
    """
    mesh = solid.to_mesh64()
    return trimesh.Trimesh(
        vertices=np.asarray(mesh.vert_properties)[:, :3],
        faces=np.asarray(mesh.tri_verts, dtype=np.int64),
        process=False,
    )


def export(solid: manifold3d.Manifold, path) -> Path:
    """Write the solid to ``path`` as STL (binary), 3MF or OBJ, chosen by its suffix.

    Parameters
    ----------
    solid : manifold3d.Manifold
    path : str or os.PathLike
        Ends in ``.stl``, ``.3mf`` or ``.obj`` (any case).

    Returns
    -------
    pathlib.Path
        The file written.

    Raises
    ------
    ValueError
        For any other suffix, or an empty solid.
    """
    path = Path(path)
    suffix = path.suffix.lower()
    if suffix not in EXPORT_FORMATS:
        raise ValueError(
            f"cannot write '{path}': unsupported file type '{path.suffix or '(none)'}'; "
            f"use one of {', '.join(EXPORT_FORMATS)}"
        )
    if solid.is_empty():
        raise ValueError(f"cannot write '{path}': the solid is empty")
    to_trimesh(solid).export(str(path), file_type=suffix[1:])
    return path


def solid_info(solid: manifold3d.Manifold) -> dict:
    """Volume, surface area, triangle count, genus and watertightness of a solid.

    ``watertight`` is trimesh's check on the in-memory mesh (every edge shared by
    exactly two consistently wound triangles) and manifold3d's status.

    Examples
    --------
    >>> info = solid_info(manifold3d.Manifold.cube((1.0, 1.0, 1.0)))
    >>> info["volume"], info["triangles"], info["watertight"], info["genus"]
    (1.0, 12, True, 0)
    """
    mesh = to_trimesh(solid)
    return {
        "volume": float(solid.volume()),
        "surface_area": float(solid.surface_area()),
        "triangles": int(solid.num_tri()),
        "vertices": int(solid.num_vert()),
        "genus": int(solid.genus()),
        "watertight": bool(
            solid.status() == manifold3d.Error.NoError
            and not solid.is_empty()
            and mesh.is_watertight
            and mesh.is_winding_consistent
        ),
    }
