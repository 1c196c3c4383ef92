"""Hair geometry: strands as Embree's round curves, and the hits on them.

A scene object whose ``curves`` is a :class:`Strands` is traced as Embree curve
primitives (:mod:`render.embree`): polylines as ``RTC_GEOMETRY_TYPE_ROUND_LINEAR_CURVE``
(cones with spheres at the joints), cubic Bézier strands as
``RTC_GEOMETRY_TYPE_ROUND_BEZIER_CURVE`` (tubes swept along the curve), each control point
with its radius.  Its material's ``hair`` field (a ``hair_bsdf``, e.g.
``df::chiang_hair_bsdf``) shades it (MDL: ior, volume and geometry do not affect hair).

Every segment is one primitive; the kernel keeps its four Bézier control points and radii
(world space, a linear segment written as the Bézier of the same line) in a row of the
curve table, and at a hit with curve parameter ``u`` (Embree's ``u``) rebuilds the hit's
frame (:func:`curve_frame`): the axis point ``c(u)``, the unit tangent ``c'(u)`` along the
strand (the hair bsdf's local ``x``), and the normal ``n``: the hit point's offset from the
axis, perpendicular to the tangent (its local ``z``).  The offset across the fibre that
the hair bsdf calls ``h`` follows from ``wo`` and ``n`` (:mod:`render.df.chiang_hair_bsdf`).

A ray that leaves a fibre into it (the transmitted lobes ``TT``, ``TRT``: the bsdf models the
whole passage through the fibre) starts where it leaves the tube on the far side
(:func:`exit_point`), not on the surface it entered, so it does not hit the same fibre
again.

Scene files (``[[objects]] curves = {...}``, :func:`from_table`): ``type = "polylines"``
(``points``: a list of strands, each a list of [x, y, z] points), ``type = "bezier"``
(each strand ``3 m + 1`` control points: ``m`` cubic segments sharing their ends), or
``type = "fringe"`` (:func:`fringe`: a row of strands hanging from a line, a fringe or a
tassel); ``radius`` a number or one per point (``radii``).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from render.df._kernel_common import unitize
from render.jit import njit

__all__ = ["Strands", "StrandsError", "fringe", "from_table", "curve_point", "curve_frame",
           "exit_point", "CURVE_COLUMNS", "LINEAR", "BEZIER"]

LINEAR, BEZIER = "linear", "bezier"
#: columns of a row of the curve table: four control points (x, y, z, radius)
CURVE_COLUMNS = 16


class StrandsError(ValueError):
    """Strands that cannot be traced; the message says which strand and point, and the fix."""


@dataclass(frozen=True, eq=False)
class Strands:
    """Hair strands in object space: control points with radii, and the segments.

    Parameters
    ----------
    points : (n, 4) float64
        ``x, y, z, radius`` of every control point.
    segments : (m,) int64
        The first control point of each segment (2 points for ``linear``, 4 for
        ``bezier``).
    kind : {"linear", "bezier"}
    strand : (m,) int64
        The strand each segment belongs to.
    """

    points: np.ndarray
    segments: np.ndarray
    kind: str
    strand: np.ndarray

    @property
    def segment_count(self) -> int:
        return len(self.segments)

    @classmethod
    def polylines(cls, strands, radius=0.001, radii=None) -> Strands:
        """Strands as polylines: ``strands`` a list of (k, 3) arrays (k >= 2), ``radius`` a
        number, or ``radii`` a matching list of (k,) radii."""
        return cls._build(strands, radius, radii, LINEAR)

    @classmethod
    def bezier(cls, strands, radius=0.001, radii=None) -> Strands:
        """Strands as cubic Bézier curves: each (3 m + 1, 3) control points, segment ``j``
        the points ``3 j .. 3 j + 3`` (neighbours share their end point)."""
        return cls._build(strands, radius, radii, BEZIER)

    @classmethod
    def _build(cls, strands, radius, radii, kind) -> Strands:
        if isinstance(strands, np.ndarray) and strands.ndim == 2:
            strands = [strands]
        try:
            strands = list(strands)
        except TypeError:
            raise StrandsError("strands must be a list of strands, each a list of [x, y, z] "
                               "points") from None
        if not strands:
            raise StrandsError("no strands: give at least one strand of points")
        if radii is not None and len(radii) != len(strands):
            raise StrandsError(f"radii has {len(radii)} entries for {len(strands)} strands; "
                               "give one list of radii per strand")
        pts, segs, owner = [], [], []
        base = 0
        for i, s in enumerate(strands):
            try:
                p = np.asarray(s, dtype=np.float64)
            except (TypeError, ValueError):
                raise StrandsError(f"strand {i + 1}: points must be numbers [x, y, z]") from None
            if p.ndim != 2 or p.shape[1] != 3:
                raise StrandsError(f"strand {i + 1}: points must be [x, y, z] triples, got "
                                   f"shape {p.shape}")
            k = len(p)
            if kind == LINEAR and k < 2:
                raise StrandsError(f"strand {i + 1}: a polyline needs at least 2 points, got "
                                   f"{k}")
            if kind == BEZIER and (k < 4 or (k - 1) % 3):
                raise StrandsError(f"strand {i + 1}: a cubic Bézier strand has 3 m + 1 control "
                                   f"points (4, 7, 10, ...), got {k}; add or remove points")
            bad = ~np.all(np.isfinite(p), axis=1)
            if bad.any():
                raise StrandsError(f"strand {i + 1}, point {int(np.flatnonzero(bad)[0]) + 1}: "
                                   "coordinates must be finite")
            r = np.full(k, radius, dtype=np.float64) if radii is None else np.asarray(
                radii[i], dtype=np.float64).reshape(-1)
            if r.shape != (k,):
                raise StrandsError(f"strand {i + 1}: {len(r)} radii for {k} points; give one "
                                   "radius per point")
            if not np.all(np.isfinite(r)) or np.any(r <= 0.0):
                j = int(np.flatnonzero(~(np.isfinite(r) & (r > 0)))[0])
                raise StrandsError(f"strand {i + 1}, point {j + 1}: radius must be > 0, got "
                                   f"{r[j]!r}")
            step = 1 if kind == LINEAR else 3
            n_seg = (k - 1) // step
            lengths = np.linalg.norm(np.diff(p, axis=0), axis=1)
            if not np.any(lengths > 0):
                raise StrandsError(f"strand {i + 1}: all its points coincide (a strand needs a "
                                   "length)")
            pts.append(np.column_stack([p, r]))
            segs.append(base + step * np.arange(n_seg))
            owner.append(np.full(n_seg, i))
            base += k
        return cls(np.ascontiguousarray(np.vstack(pts)), np.concatenate(segs).astype(np.int64),
                   kind, np.concatenate(owner).astype(np.int64))

    def world(self, transform: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """(control points (n, 4) in world space, curve table (m, 16)): positions by the
        object's transform, radii by its mean scale (the cube root of the determinant)."""
        lin, t = transform[:3, :3], transform[:3, 3]
        scale = abs(float(np.linalg.det(lin))) ** (1.0 / 3.0)
        p = np.column_stack([self.points[:, :3] @ lin.T + t, self.points[:, 3] * scale])
        rows = np.empty((self.segment_count, CURVE_COLUMNS))
        s = self.segments
        if self.kind == BEZIER:
            for c in range(4):
                rows[:, 4 * c:4 * c + 4] = p[s + c]
        else:  # the line as the Bézier curve of the same points and radii
            a, b = p[s], p[s + 1]
            for c in range(4):
                rows[:, 4 * c:4 * c + 4] = a + (b - a) * (c / 3.0)
        return np.ascontiguousarray(p), rows

    def bounds(self, transform: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """World-space bounding box (lo, hi) of the strands, radii included."""
        p, _ = self.world(transform)
        r = p[:, 3:4]
        return (p[:, :3] - r).min(axis=0), (p[:, :3] + r).max(axis=0)


def fringe(start=(-0.5, 0.0, 0.0), end=(0.5, 0.0, 0.0), count: int = 64,
           length: float = 0.4, radius: float = 0.003, sway: float = 0.08,
           curl: float = 0.02, tassel: float = 0.0, segments: int = 3,
           seed: int = 0) -> Strands:
    """A fringe: ``count`` strands hanging (along ``-y``) from the line ``start``-``end``,
    cubic Bézier curves of ``segments`` segments, each swaying sideways and forward by up
    to ``sway``, curling by ``curl``, tapering to half the radius at its tip;
    ``tassel`` > 0 gathers the strands' middles toward the line's centre (a tassel's
    waist) by that fraction.  Deterministic for a ``seed``."""
    if not (isinstance(count, int) and count >= 1):
        raise StrandsError(f"fringe: count must be a whole number >= 1, got {count!r}")
    if not (isinstance(segments, int) and segments >= 1):
        raise StrandsError(f"fringe: segments must be a whole number >= 1, got {segments!r}")
    for name, v in (("length", length), ("radius", radius)):
        if not (isinstance(v, int | float) and math.isfinite(v) and v > 0):
            raise StrandsError(f"fringe: {name} must be > 0, got {v!r}")
    rng = np.random.default_rng(seed)
    a, b = np.asarray(start, dtype=np.float64), np.asarray(end, dtype=np.float64)
    centre = 0.5 * (a + b)
    k = 3 * segments + 1
    t = np.linspace(0.0, 1.0, k)
    strands, radii = [], []
    for i in range(count):
        top = a + (b - a) * ((i + rng.uniform(0.2, 0.8)) / count)
        side = rng.uniform(-sway, sway) * t ** 1.5
        fwd = rng.uniform(-sway, sway) * t ** 2
        phase = rng.uniform(0, 2 * np.pi)
        wiggle = curl * np.sin(phase + 3 * np.pi * t) * t
        p = np.empty((k, 3))
        p[:, 0] = top[0] + side + wiggle
        p[:, 1] = top[1] - length * rng.uniform(0.9, 1.0) * t
        p[:, 2] = top[2] + fwd + curl * np.cos(phase + 3 * np.pi * t) * t
        if tassel > 0:
            pull = tassel * np.sin(np.pi * np.clip(t / 0.6, 0, 1)) ** 2 * (t < 0.6)
            p[:, 0] += (centre[0] - top[0]) * pull
            p[:, 2] += (centre[2] - top[2]) * pull
        strands.append(p)
        radii.append(radius * (1.0 - 0.5 * t))
    return Strands.bezier(strands, radii=radii)


def from_table(spec: dict) -> Strands:
    """:class:`Strands` from a scene file's ``curves = { type = ..., ... }`` table.

    Raises :class:`StrandsError` (the scene reader adds the file, line and column)."""
    spec = dict(spec)
    kind = spec.pop("type", None)
    kinds = ("polylines", "bezier", "fringe")
    if kind not in kinds:
        raise StrandsError(f"curves type must be one of {', '.join(kinds)}, got {kind!r}")
    if kind == "fringe":
        allowed = {"start", "end", "count", "length", "radius", "sway", "curl", "tassel",
                   "segments", "seed"}
        unknown = sorted(set(spec) - allowed)
        if unknown:
            raise StrandsError(f"curves (fringe) has no key {unknown[0]!r}; keys: "
                               f"{', '.join(sorted(allowed))}")
        return fringe(**spec)
    unknown = sorted(set(spec) - {"points", "radius", "radii"})
    if unknown:
        raise StrandsError(f"curves ({kind}) has no key {unknown[0]!r}; keys: points, radius, "
                           "radii")
    if "points" not in spec:
        raise StrandsError(f"curves ({kind}) needs points: a list of strands, each a list of "
                           "[x, y, z] points")
    radius = spec.get("radius", 0.001)
    if not (isinstance(radius, int | float) and not isinstance(radius, bool)):
        raise StrandsError(f"curves radius must be a number, got {radius!r}")
    build = Strands.polylines if kind == "polylines" else Strands.bezier
    return build(spec["points"], float(radius), spec.get("radii"))


# ------------------------------------------------------------------------ kernels
@njit(inline="always")
def curve_point(C, s, u):
    """Point ``(x, y, z)``, radius, and derivative ``(dx, dy, dz)`` of row ``s`` of the
    curve table at parameter ``u`` (cubic Bézier)."""
    v = 1.0 - u
    b0, b1, b2, b3 = v * v * v, 3.0 * u * v * v, 3.0 * u * u * v, u * u * u
    d0, d1, d2 = 3.0 * v * v, 6.0 * u * v, 3.0 * u * u  # of the differences
    x = b0 * C[s, 0] + b1 * C[s, 4] + b2 * C[s, 8] + b3 * C[s, 12]
    y = b0 * C[s, 1] + b1 * C[s, 5] + b2 * C[s, 9] + b3 * C[s, 13]
    z = b0 * C[s, 2] + b1 * C[s, 6] + b2 * C[s, 10] + b3 * C[s, 14]
    r = b0 * C[s, 3] + b1 * C[s, 7] + b2 * C[s, 11] + b3 * C[s, 15]
    dx = d0 * (C[s, 4] - C[s, 0]) + d1 * (C[s, 8] - C[s, 4]) + d2 * (C[s, 12] - C[s, 8])
    dy = d0 * (C[s, 5] - C[s, 1]) + d1 * (C[s, 9] - C[s, 5]) + d2 * (C[s, 13] - C[s, 9])
    dz = d0 * (C[s, 6] - C[s, 2]) + d1 * (C[s, 10] - C[s, 6]) + d2 * (C[s, 14] - C[s, 10])
    return x, y, z, r, dx, dy, dz


@njit
def curve_frame(C, s, u, px, py, pz):
    """The frame of a hit at ``p`` on row ``s`` at parameter ``u``: unit normal ``n`` (from
    the axis to ``p``, perpendicular to the strand), unit tangent ``t`` and the radius."""
    cx, cy, cz, r, dx, dy, dz = curve_point(C, s, min(max(u, 0.0), 1.0))
    tx, ty, tz, ok = unitize(dx, dy, dz)
    if not ok:  # a degenerate (cusp) derivative: the chord of the segment
        tx, ty, tz, ok = unitize(C[s, 12] - C[s, 0], C[s, 13] - C[s, 1], C[s, 14] - C[s, 2])
        if not ok:
            tx, ty, tz = 1.0, 0.0, 0.0
    ox, oy, oz = px - cx, py - cy, pz - cz
    a = ox * tx + oy * ty + oz * tz
    nx, ny, nz, ok = unitize(ox - a * tx, oy - a * ty, oz - a * tz)
    if not ok:  # on the axis: any normal perpendicular to the tangent
        sign = 1.0 if tz >= 0.0 else -1.0
        b = -1.0 / (sign + tz)
        nx, ny, nz = 1.0 + sign * tx * tx * b, sign * tx * ty * b, -sign * tx
    return nx, ny, nz, tx, ty, tz, r


@njit
def exit_point(px, py, pz, nx, ny, nz, tx, ty, tz, r, wx, wy, wz):
    """Where a ray from ``p`` on a fibre (unit outward normal ``n``, tangent ``t``, radius
    ``r``) along ``w`` leaves the tube, and the outward normal there: ``p`` itself for a ray
    leaving outward (``w.n >= 0``), else the far side of the chord through a straight
    cylinder of radius ``r`` (the segment's curvature neglected)."""
    wn = wx * nx + wy * ny + wz * nz
    if wn >= 0.0:
        return px, py, pz, nx, ny, nz
    wt = wx * tx + wy * ty + wz * tz
    perp = max(1.0 - wt * wt, 1e-12)
    s = min(-2.0 * r * wn / perp, 4.0 * r / math.sqrt(perp))
    qx, qy, qz = px + s * wx, py + s * wy, pz + s * wz
    # the exit normal: the offset from the axis at q, perpendicular to the tangent
    ax, ay, az = px - r * nx, py - r * ny, pz - r * nz
    ox, oy, oz = qx - ax, qy - ay, qz - az
    a = ox * tx + oy * ty + oz * tz
    ex, ey, ez, ok = unitize(ox - a * tx, oy - a * ty, oz - a * tz)
    if not ok:
        ex, ey, ez = wx, wy, wz
    return qx, qy, qz, ex, ey, ez
