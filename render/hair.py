"""Hair geometry: strands as Embree's round curves, and the shading frame of a hit on one.

A scene object whose surface is a :class:`Strands` is traced as Embree curve primitives
(:mod:`render.embree`): polylines as ``RTC_GEOMETRY_TYPE_ROUND_LINEAR_CURVE`` (cones
between the points, a sphere at every point), cubic Bézier strands as
``RTC_GEOMETRY_TYPE_ROUND_BEZIER_CURVE`` (a sphere of varying radius swept along the
curve; open at the strand's ends), each control point with its radius.  The object's
material's ``hair`` field (a ``hair_bsdf``, i.e. ``df::chiang_hair_bsdf``) shades it;
``hair = None`` is MDL's ``hair_bsdf()``, black.  MDL: a material's ``ior``, ``volume``
and ``geometry`` do not apply to hair.

Every segment is one Embree primitive.  The path kernel keeps, per segment, a row of the
*curve table*: its four Bézier control points and radii in world space (a linear segment
written as the Bézier of the same line), rounded to float32 as Embree stores them.  At a
hit with curve parameter ``u`` (Embree's ``u``), :func:`hair_hit` rebuilds the frame the
hair bsdf needs: the unit tangent ``c'(u)`` along the strand (the bsdf's local ``x``) and
the outward normal ``n`` of the tube where the ray enters it (its local ``z``).  ``n``
comes from the ray's closest approach to the strand's axis, not from the hit point: the
offset across the fibre, ``h = b / r`` (``b`` the ray's distance from the axis, ``r`` the
radius at ``u``), fixes ``n = h m - sqrt(1 - h^2) d_perp`` (``m`` the unit direction of
closest approach, ``d_perp`` the ray's unit direction across the fibre).  So ``h`` is
exact to float64 for the float32 geometry Embree traced, whatever the error of Embree's
``t`` along the ray, and ``|h| <= 1`` always (a hit on a joint's or an end's sphere, or on
a tube whose radius varies, clamps it).  The bsdf reads ``h`` back from ``wo`` and ``n``
(:mod:`render.df.chiang_hair_bsdf`).

The fibre is a tube, not a surface with two sides: the bsdf scatters into the whole
sphere, and a direction into the fibre (the transmitted lobes ``TT``, ``TRT``: the model
accounts for the passage through it) leaves from just inside the tube, whose far wall it
then meets *from inside*.  The kernel passes every hit on a tube from inside straight
through (Embree's geometric normal along the ray), for path and shadow rays alike, so a
ray never scatters twice at one fibre crossing and one strand lying inside another does
not trap rays.

Scene files (``[[objects]] curves = {...}``, :func:`from_table`): ``type = "polylines"``
(``points``: a list of strands, each a list of ``[x, y, z]`` points, at least 2),
``type = "bezier"`` (each strand ``3 m + 1`` control points: ``m`` cubic segments sharing
their ends), with ``radius`` (one number) or ``radii`` (one list per strand, a radius per
point); or ``type = "fringe"`` (:func:`fringe`: a row of strands hanging from a line, a
fringe or a tassel).  Errors name the strand and point (:class:`StrandsError`); the scene
reader adds the file, line and column.

Examples
--------
>>> s = Strands.polylines([[[0, 0, 0], [0, -1, 0], [0.1, -2, 0]]], radius=0.01)
>>> s.kind, s.segment_count, s.strand_count
('linear', 2, 1)
>>> try:
...     Strands.polylines([[[0, 0, 0], [0, 0, 0], [0, 1, 0]]])
... except StrandsError as e:
...     print(e)
strand 1, points 1 and 2: a zero-length segment (the points coincide); remove one of them
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from render.df._kernel_common import unitize
from render.jit import njit

__all__ = ["Strands", "StrandsError", "fringe", "from_table", "check_hair_bsdf", "curve_point",
           "hair_hit", "CURVE_COLUMNS", "LINEAR", "BEZIER", "MIN_RADIUS_ULPS",
           "MAX_SEGMENT_RADII", "MAX_PIECES"]

LINEAR, BEZIER = "linear", "bezier"
#: columns of a row of the curve table: four control points (x, y, z, radius)
CURVE_COLUMNS = 16
#: the smallest radius, in float32 steps (ulps) of the strand's largest coordinate: a
#: thinner tube is narrower than the precision of its own position in Embree's float32
MIN_RADIUS_ULPS = 16.0
_F32_EPS = float(np.finfo(np.float32).eps)  # 2^-23
#: a segment shorter than this many float32 steps of its coordinates is degenerate
_MIN_LENGTH_ULPS = 4.0
#: segments longer than this many of their (smallest) radii are split for Embree, whose
#: round curves are exact to a few per cent of the radius only where radius / length
#: >~ 1e-3 (measured, benchmarks/hair.py: at 1e-5 a linear segment is traced up to 24
#: radii from its axis and misses some rays through it, a Bézier one up to 1.5 radii);
#: the pieces are the same curve (de Casteljau), so the geometry does not change
MAX_SEGMENT_RADII = 250.0
#: at most this many pieces per input segment (beyond: a clear error, not a huge scene)
MAX_PIECES = 4096


class StrandsError(ValueError):
    """Strands that cannot be traced; the message says which strand and point, and the fix.

    Attributes
    ----------
    key : str or None
        The scene file's key at fault (``points``, ``radii``, ``radius``, ...).
    strand, point : int or None
        0-based strand and point (into that key's list) at fault, where known.
    """

    def __init__(self, message: str, key: str | None = None, strand: int | None = None,
                 point: int | None = None):
        super().__init__(message)
        self.key, self.strand, self.point = key, strand, point


@dataclass(frozen=True, eq=False)
class Strands:
    """Hair strands in object space: control points with radii, and the segments.

    Build with :meth:`polylines`, :meth:`bezier` or :func:`fringe`.

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

    @property
    def strand_count(self) -> int:
        return int(self.strand.max()) + 1 if len(self.strand) else 0

    @classmethod
    def polylines(cls, strands, radius=0.001, radii=None) -> Strands:
        """Strands as polylines: ``strands`` a list of (k, 3) point lists (k >= 2), with
        one ``radius`` or ``radii``, a (k,) list of radii per strand."""
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
        if isinstance(strands, str | bytes) or not hasattr(strands, "__len__"):
            raise StrandsError("points must be a list of strands, each a list of [x, y, z] "
                               f"points, got {strands!r}", "points")
        strands = list(strands)
        if not strands:
            raise StrandsError("points is empty: give at least one strand of [x, y, z] "
                               "points", "points")
        if radii is not None:
            if isinstance(radii, str | bytes) or not hasattr(radii, "__len__"):
                raise StrandsError(f"radii must be a list with one list of radii per strand, "
                                   f"got {radii!r}", "radii")
            if len(radii) != len(strands):
                raise StrandsError(f"radii has {len(radii)} lists for {len(strands)} strands; "
                                   "give one list of radii (one per point) per strand",
                                   "radii")
        elif not (isinstance(radius, int | float) and not isinstance(radius, bool)):
            raise StrandsError(f"radius must be a number, got {radius!r}", "radius")
        step = 1 if kind == LINEAR else 3
        pts, segs, owner = [], [], []
        base = 0
        for i, s in enumerate(strands):
            p = _points(s, i)
            k = len(p)
            if kind == LINEAR and k < 2:
                raise StrandsError(f"strand {i + 1}: a polyline needs at least 2 points, got "
                                   f"{k}; add a point", "points", i)
            if kind == BEZIER and (k < 4 or (k - 1) % 3):
                raise StrandsError(f"strand {i + 1}: a cubic Bézier strand has 3 m + 1 control "
                                   f"points (4, 7, 10, ...), got {k}; add or remove points",
                                   "points", i)
            r = _radii(radius if radii is None else radii[i], k, i, radii is not None)
            _check_segments(p, i, step)
            pts.append(np.column_stack([p, r]))
            segs.append(base + step * np.arange((k - 1) // step))
            owner.append(np.full((k - 1) // step, i))
            base += k
        return cls(np.ascontiguousarray(np.vstack(pts)), np.concatenate(segs).astype(np.int64),
                   kind, np.concatenate(owner).astype(np.int64))

    def world(self, transform: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """The strands in world space, as Embree and the kernel see them.

        Positions go by the object's transform, radii by its mean scale (the cube root of
        the determinant).  Segments longer than :data:`MAX_SEGMENT_RADII` radii are split
        into equal pieces of the same curve (Embree traces thin long round curves too
        thick).  Everything is rounded to float32 (Embree's precision), so the kernel
        rebuilds each hit on the very tube Embree traced.

        Returns
        -------
        points : (n, 4) float64
            World control points and radii (float32 values).
        segments : (m,) int64
            The first point of each traced segment (:attr:`segments` after splitting).
        table : (m, 16) float64
            The curve table: each traced segment's four Bézier control points and radii.

        Raises
        ------
        StrandsError
            A radius below :data:`MIN_RADIUS_ULPS` float32 steps of the strand's
            coordinates, a segment that float32 collapses to a point, or one that would
            need more than :data:`MAX_PIECES` pieces.
        """
        transform = np.asarray(transform, dtype=np.float64)
        lin, t = transform[:3, :3], transform[:3, 3]
        scale = abs(float(np.linalg.det(lin))) ** (1.0 / 3.0)
        p = np.column_stack([self.points[:, :3] @ lin.T + t, self.points[:, 3] * scale])
        with np.errstate(over="ignore"):
            p32 = p.astype(np.float32).astype(np.float64)
        if not np.all(np.isfinite(p32)):
            raise StrandsError("the strands' world coordinates overflow float32; scale the "
                               "object down", "points")
        step = 1 if self.kind == LINEAR else 3
        # per strand: radii resolvable at the strand's float32 coordinates
        first = np.concatenate([[0], np.flatnonzero(np.diff(self.strand)) + 1])
        for j, seg0 in enumerate(first):
            i = int(self.strand[seg0])
            lo = int(self.segments[seg0])
            hi = int(self.segments[first[j + 1] - 1] if j + 1 < len(first)
                     else self.segments[-1]) + step + 1
            q = p32[lo:hi]
            ulp = _F32_EPS * max(float(np.abs(q[:, :3]).max()), np.finfo(np.float32).tiny)
            small = q[:, 3] < MIN_RADIUS_ULPS * ulp
            if small.any():
                k = int(np.flatnonzero(small)[0])
                raise StrandsError(
                    f"strand {i + 1}, point {k + 1}: radius {p[lo + k, 3]:.3g} (in world space) "
                    f"is below float32's resolution of the strand's coordinates ({ulp:.2g} "
                    f"at |x| = {np.abs(q[:, :3]).max():.3g}; Embree needs at least "
                    f"{MIN_RADIUS_ULPS * ulp:.2g}); give a larger radius, or move the strand "
                    "nearer the origin", "radius" if np.ptp(self.points[lo:hi, 3]) == 0 else
                    "radii", i, k)
            _check_segments(q[:, :3], i, step)
        p, s = _split(p, self.segments, self.kind, self.strand)
        with np.errstate(over="ignore"):
            p32 = p.astype(np.float32).astype(np.float64)
        rows = np.empty((len(s), CURVE_COLUMNS))
        if self.kind == BEZIER:
            for c in range(4):
                rows[:, 4 * c:4 * c + 4] = p32[s + c]
        else:  # the line as the Bézier curve of the same points and radii
            a, b = p32[s], p32[s + 1]
            for c in range(4):
                rows[:, 4 * c:4 * c + 4] = a + (b - a) * (c / 3.0)
        return np.ascontiguousarray(p32), s, rows

    def bounds(self, transform: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """World-space bounding box ``(lo, hi)`` of the strands, radii included (a Bézier
        curve lies in the hull of its control points)."""
        p, _, _ = self.world(transform)
        r = p[:, 3:4]
        return (p[:, :3] - r).min(axis=0), (p[:, :3] + r).max(axis=0)


def _split(p: np.ndarray, segments: np.ndarray, kind: str, strand: np.ndarray):
    """Control points ``p`` (n, 4) and ``segments`` with every segment longer than
    :data:`MAX_SEGMENT_RADII` of its smallest radius cut into equal parameter pieces of
    the same curve; unchanged when none is.  Pieces get their own control points."""
    step = 1 if kind == LINEAR else 3
    ctrl = p[segments[:, None] + np.arange(step + 1)]  # (m, step + 1, 4)
    length = np.linalg.norm(np.diff(ctrl[:, :, :3], axis=1), axis=2).sum(axis=1)
    pieces = np.ceil(length / (MAX_SEGMENT_RADII * ctrl[:, :, 3].min(axis=1)))
    pieces = np.maximum(pieces, 1.0)
    if pieces.max() > MAX_PIECES:
        j = int(np.argmax(pieces))
        raise StrandsError(
            f"strand {int(strand[j]) + 1}: a segment {length[j]:.3g} long with radius "
            f"{ctrl[j, :, 3].min():.3g} is {length[j] / ctrl[j, :, 3].min():.3g} radii long; "
            f"Embree traces a round curve exactly only up to {MAX_SEGMENT_RADII:g} radii a "
            f"segment, and splitting it would take more than {MAX_PIECES} pieces: give a "
            "larger radius or more, shorter segments", "radius")
    if pieces.max() == 1.0:
        return p, segments
    k = pieces.astype(np.int64)
    seg = np.repeat(np.arange(len(segments)), k)
    j = np.arange(len(seg)) - np.repeat(np.cumsum(k) - k, k)
    u0, u1 = j / k[seg], (j + 1) / k[seg]
    c = ctrl[seg]
    if kind == LINEAR:
        out = np.stack([c[:, 0] + (c[:, 1] - c[:, 0]) * u0[:, None],
                        c[:, 0] + (c[:, 1] - c[:, 0]) * u1[:, None]], axis=1)
    else:  # the cubic on [u0, u1]: ends B(u) and B(u) +- (u1 - u0) / 3 B'(u)
        def at(u):
            v = (1.0 - u)[:, None]
            w = u[:, None]
            b = (v ** 3 * c[:, 0] + 3 * w * v * v * c[:, 1] + 3 * w * w * v * c[:, 2]
                 + w ** 3 * c[:, 3])
            d = 3 * (v * v * (c[:, 1] - c[:, 0]) + 2 * w * v * (c[:, 2] - c[:, 1])
                     + w * w * (c[:, 3] - c[:, 2]))
            return b, d

        (b0, d0), (b1, d1) = at(u0), at(u1)
        h = ((u1 - u0) / 3.0)[:, None]
        out = np.stack([b0, b0 + h * d0, b1 - h * d1, b1], axis=1)
    return (np.ascontiguousarray(out.reshape(-1, 4)),
            (step + 1) * np.arange(len(seg), dtype=np.int64))


def _points(s, i: int) -> np.ndarray:
    """Strand ``i``'s points as a checked (k, 3) float64 array."""
    if isinstance(s, str | bytes) or not hasattr(s, "__len__"):
        raise StrandsError(f"strand {i + 1}: must be a list of [x, y, z] points, got {s!r}",
                           "points", i)
    for j, q in enumerate(s):
        if isinstance(q, str | bytes) or not hasattr(q, "__len__") or len(q) != 3 or not all(
                isinstance(x, int | float | np.number) and not isinstance(x, bool) for x in q):
            raise StrandsError(f"strand {i + 1}, point {j + 1}: must be three numbers "
                               f"[x, y, z], got {q!r}", "points", i, j)
    p = np.asarray(s, dtype=np.float64).reshape(-1, 3)
    bad = ~np.all(np.isfinite(p), axis=1)
    if bad.any():
        j = int(np.flatnonzero(bad)[0])
        raise StrandsError(f"strand {i + 1}, point {j + 1}: coordinates must be finite, got "
                           f"{p[j].tolist()}", "points", i, j)
    return p


def _radii(r, k: int, i: int, per_point: bool) -> np.ndarray:
    """The (k,) radii of strand ``i`` from one radius or a list of them."""
    key = "radii" if per_point else "radius"
    if per_point:
        if isinstance(r, str | bytes) or not hasattr(r, "__len__") or not all(
                isinstance(x, int | float | np.number) and not isinstance(x, bool) for x in r):
            raise StrandsError(f"strand {i + 1}: radii must be a list of numbers, one per "
                               f"point, got {r!r}", key, i)
        out = np.asarray(r, dtype=np.float64).reshape(-1)
        if len(out) != k:
            raise StrandsError(f"strand {i + 1}: {len(out)} radii for {k} points; give one "
                               "radius per point", key, i)
    else:
        out = np.full(k, float(r))
    ok = np.isfinite(out) & (out > 0.0)
    if not ok.all():
        j = int(np.flatnonzero(~ok)[0])
        where = f"strand {i + 1}, point {j + 1}" if per_point else f"strand {i + 1}"
        raise StrandsError(f"{where}: radius must be a finite number > 0, got {float(out[j])!r}",
                           key, i, j if per_point else None)
    return out


def _check_segments(p: np.ndarray, i: int, step: int) -> None:
    """Reject segments of strand ``i`` (points ``p`` (k, 3)) that have no length: a
    polyline's repeated point, or a Bézier segment whose four control points coincide
    (to float32 steps of their coordinates)."""
    scale = _MIN_LENGTH_ULPS * _F32_EPS * max(float(np.abs(p).max()), 1e-30)
    edge = np.linalg.norm(np.diff(p, axis=0), axis=1)
    if step == 1:
        bad = np.flatnonzero(edge <= scale)
        if len(bad):
            j = int(bad[0])
            raise StrandsError(f"strand {i + 1}, points {j + 1} and {j + 2}: a zero-length "
                               "segment (the points coincide); remove one of them", "points",
                               i, j + 1)
        return
    polygon = edge.reshape(-1, 3).sum(axis=1)
    bad = np.flatnonzero(polygon <= scale)
    if len(bad):
        j = int(bad[0])
        raise StrandsError(f"strand {i + 1}, points {3 * j + 1} to {3 * j + 4}: a zero-length "
                           "Bézier segment (its four control points coincide); remove three "
                           "of them", "points", i, 3 * j)


def fringe(start=(-0.5, 0.0, 0.0), end=(0.5, 0.0, 0.0), count: int = 64,
           length: float = 0.4, radius: float = 0.003, sway: float = 0.08,
           curl: float = 0.02, tassel: float = 0.0, segments: int = 3,
           seed: int = 0) -> Strands:
    """A fringe: ``count`` strands hanging (along ``-y``) from the line ``start``-``end``.

    Each strand is a cubic Bézier curve of ``segments`` segments through points that
    sway sideways and forward by up to ``sway`` (growing toward the tip), curl by
    ``curl`` about the strand, and taper to half the radius at the tip; ``tassel`` in
    (0, 1] gathers the strands toward the line's middle (a tassel's waist, at 30 % of
    the length) by that fraction.  The same ``seed`` gives the same strands.

    Examples
    --------
    >>> f = fringe(count=3, segments=2)
    >>> f.kind, f.strand_count, f.segment_count
    ('bezier', 3, 6)
    """
    def number(name, v, lo=0.0, closed=False):
        if isinstance(v, bool) or not isinstance(v, int | float) or not math.isfinite(v) or (
                v < lo if closed else v <= lo):
            raise StrandsError(f"fringe: {name} must be a number {'>=' if closed else '>'} "
                               f"{lo:g}, got {v!r}", name)
        return float(v)

    for name, v, hi in (("count", count, 100_000), ("segments", segments, 64)):
        if isinstance(v, bool) or not isinstance(v, int) or not 1 <= v <= hi:
            raise StrandsError(f"fringe: {name} must be a whole number from 1 to {hi}, got "
                               f"{v!r}", name)
    length, radius = number("length", length), number("radius", radius)
    sway, curl = number("sway", sway, closed=True), number("curl", curl, closed=True)
    tassel = number("tassel", tassel, closed=True)
    if tassel > 1.0:
        raise StrandsError(f"fringe: tassel must be in [0, 1], got {tassel!r}", "tassel")
    if isinstance(seed, bool) or not isinstance(seed, int) or seed < 0:
        raise StrandsError(f"fringe: seed must be a whole number >= 0, got {seed!r}", "seed")
    ends = []
    for name, v in (("start", start), ("end", end)):
        try:
            a = np.asarray(v, dtype=np.float64)
        except (TypeError, ValueError):
            a = np.zeros(0)
        if a.shape != (3,) or not np.all(np.isfinite(a)):
            raise StrandsError(f"fringe: {name} must be a point [x, y, z], got {v!r}", name)
        ends.append(a)
    a, b = ends
    rng = np.random.default_rng(seed)
    centre = 0.5 * (a + b)
    k = 3 * segments + 1
    t = np.linspace(0.0, 1.0, k)
    strands, radii = [], []
    for i in range(count):
        top = a + (b - a) * ((i + rng.uniform(0.2, 0.8)) / count)
        side = rng.uniform(-sway, sway) * t ** 1.5
        fwd = rng.uniform(-sway, sway) * t ** 2
        phase = rng.uniform(0, 2 * np.pi)
        p = np.empty((k, 3))
        p[:, 0] = top[0] + side + curl * np.sin(phase + 3 * np.pi * t) * t
        p[:, 1] = top[1] - length * rng.uniform(0.9, 1.0) * t
        p[:, 2] = top[2] + fwd + curl * np.cos(phase + 3 * np.pi * t) * t
        if tassel > 0:
            pull = tassel * np.sin(0.5 * np.pi * np.clip(t / 0.3, 0.0, 1.0)) ** 2
            p[:, 0] += (centre[0] - top[0]) * pull
            p[:, 2] += (centre[2] - top[2]) * pull
        strands.append(p)
        radii.append(radius * (1.0 - 0.5 * t))
    return Strands.bezier(strands, radii=radii)


_FRINGE_KEYS = frozenset({"start", "end", "count", "length", "radius", "sway", "curl",
                          "tassel", "segments", "seed"})


def from_table(spec: dict) -> Strands:
    """:class:`Strands` from a scene file's ``curves = { type = ..., ... }`` table.

    Raises :class:`StrandsError` (the scene reader adds the file, line and column)."""
    spec = dict(spec)
    kind = spec.pop("type", None)
    kinds = ("polylines", "bezier", "fringe")
    if kind not in kinds:
        raise StrandsError(f"type must be one of {', '.join(map(repr, kinds))}, got {kind!r}",
                           "type")
    allowed = _FRINGE_KEYS if kind == "fringe" else frozenset({"points", "radius", "radii"})
    unknown = sorted(set(spec) - allowed)
    if unknown:
        import difflib

        close = difflib.get_close_matches(unknown[0], sorted(allowed), n=1)
        hint = f" (did you mean {close[0]!r}?)" if close else ""
        raise StrandsError(f"unknown key {unknown[0]!r}{hint} for type {kind!r}; keys: "
                           f"{', '.join(sorted(allowed))}", unknown[0])
    if kind == "fringe":
        return fringe(**spec)
    if "points" not in spec:
        raise StrandsError(f"type {kind!r} needs points: a list of strands, each a list of "
                           "[x, y, z] points", "type")
    if "radius" in spec and "radii" in spec:
        raise StrandsError("give radius (one for every point) or radii (a list per strand), "
                           "not both", "radii")
    build = Strands.polylines if kind == "polylines" else Strands.bezier
    return build(spec["points"], spec.get("radius", 0.001), spec.get("radii"))


def check_hair_bsdf(node) -> None:
    """Raise ValueError where a material's ``hair`` cannot be rendered: an argument that
    varies (a function of the state: the kernel binds a hair bsdf once, for every strand
    of the object).  ``None`` (MDL's black ``hair_bsdf()``) is fine."""
    if node is None:
        return
    for key, value in node.kwargs.items():
        if callable(value):
            raise ValueError(f"df::{node.name}: {key} must be a constant (one value for all "
                             "the object's strands); arguments that vary along a strand are "
                             "not rendered")


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
def _tangent(C, s, dx, dy, dz):
    """The unit tangent from the derivative ``d``; where it vanishes (a Bézier segment
    whose end control points coincide with their neighbours), the segment's chord, then
    its inner chord."""
    tx, ty, tz, ok = unitize(dx, dy, dz)
    if not ok:
        tx, ty, tz, ok = unitize(C[s, 12] - C[s, 0], C[s, 13] - C[s, 1], C[s, 14] - C[s, 2])
    if not ok:
        tx, ty, tz, ok = unitize(C[s, 8] - C[s, 4], C[s, 9] - C[s, 5], C[s, 10] - C[s, 6])
    if not ok:  # rejected when the strands are read; a defined frame all the same
        tx, ty, tz = 1.0, 0.0, 0.0
    return tx, ty, tz


@njit
def _perpendicular(tx, ty, tz):
    """A unit vector perpendicular to the unit ``t`` (Duff et al.'s frame)."""
    sign = 1.0 if tz >= 0.0 else -1.0
    a = -1.0 / (sign + tz)
    return 1.0 + sign * tx * tx * a, sign * tx * ty * a, -sign * tx


@njit
def hair_hit(C, s, u, ox, oy, oz, dx, dy, dz, t):
    """The frame of a ray's hit on row ``s`` of the curve table at Embree's ``u``.

    The ray is ``o + t d`` (unit ``d``; rounded to float32 here, as Embree traced it).
    Returns ``(px, py, pz, nx, ny, nz, tx, ty, tz)``: the entry point on the tube about
    the axis at ``u`` (radius ``r(u)``), the tube's unit outward normal there (from the
    ray's closest approach to the axis: exact ``h``, ``|h| <= 1``; see the module's
    docstring), and the unit tangent.  A ray along the axis (within 1e-7 rad) takes the
    hit point's offset from the axis for the normal; every case gives a unit ``n``
    perpendicular to ``t``.
    """
    ox, oy, oz = float(np.float32(ox)), float(np.float32(oy)), float(np.float32(oz))
    dx, dy, dz, _ = unitize(float(np.float32(dx)), float(np.float32(dy)),
                            float(np.float32(dz)))
    cx, cy, cz, r, ax, ay, az = curve_point(C, s, min(max(u, 0.0), 1.0))
    tx, ty, tz = _tangent(C, s, ax, ay, az)
    # the ray's origin relative to the axis point, and its direction, across the fibre
    wx, wy, wz = ox - cx, oy - cy, oz - cz
    wt = wx * tx + wy * ty + wz * tz
    wx, wy, wz = wx - wt * tx, wy - wt * ty, wz - wt * tz
    dt = dx * tx + dy * ty + dz * tz
    qx, qy, qz = dx - dt * tx, dy - dt * ty, dz - dt * tz
    q2 = qx * qx + qy * qy + qz * qz
    ok = False
    if q2 > 1e-14:
        # closest approach: m = w - (w.q / q.q) q, perpendicular to t and to q
        k = (wx * qx + wy * qy + wz * qz) / q2
        mx, my, mz = wx - k * qx, wy - k * qy, wz - k * qz
        mx, my, mz, ok = unitize(mx, my, mz)
        b = math.sqrt((wx - k * qx) ** 2 + (wy - k * qy) ** 2 + (wz - k * qz) ** 2)
        if not ok:  # through the axis: h = 0
            mx, my, mz, ok = unitize(ty * qz - tz * qy, tz * qx - tx * qz, tx * qy - ty * qx)
        h = min(b / r, 1.0) if r > 0.0 else 1.0
        c = math.sqrt(max(1.0 - h * h, 0.0))
        iq = 1.0 / math.sqrt(q2)
        nx, ny, nz = h * mx - c * qx * iq, h * my - c * qy * iq, h * mz - c * qz * iq
        nx, ny, nz, ok = unitize(nx, ny, nz)
    px, py, pz = ox + t * dx, oy + t * dy, oz + t * dz
    if not ok:  # along the fibre: the hit point's offset from the axis
        vx, vy, vz = px - cx, py - cy, pz - cz
        a = vx * tx + vy * ty + vz * tz
        nx, ny, nz, ok = unitize(vx - a * tx, vy - a * ty, vz - a * tz)
        if not ok:
            nx, ny, nz = _perpendicular(tx, ty, tz)
    # the point on the tube with that normal, level with the hit along the axis
    a = (px - cx) * tx + (py - cy) * ty + (pz - cz) * tz
    px, py, pz = cx + a * tx + r * nx, cy + a * ty + r * ny, cz + a * tz + r * nz
    return px, py, pz, nx, ny, nz, tx, ty, tz
