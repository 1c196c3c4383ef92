"""Compile a parsed pwc-list into a :class:`~pwc.curve.Curve` (spec/pwc-list.md §1-2).

Stages: resolve relative/absolute coordinates, construct each piece (segment, or an arc
from its angle, sagitta, cyma or flare), normalize by the largest coordinate, and
parametrize by arc length.
"""

from __future__ import annotations

import math

import numpy as np

from pwc.curve import Curve, PwType
from pwc.diagnostics import Diagnostic, PwcGeometryError
from pwc.tolerance import TOL
from pwc.tree import PwcList, PwPoint

__all__ = ["compile_list", "arc_through", "resolve_points"]

_BULGE_60 = math.tan(math.pi / 12)  # a cyma's arcs each sweep 60 degrees


def resolve_points(tree: PwcList) -> np.ndarray:
    """(n, 2) absolute coordinates of the points: offsets summed in a ``:relative`` list,
    ``a``-prefixed coordinates taken as they are."""
    out = np.empty((len(tree.points), 2))
    x = y = 0.0
    for i, p in enumerate(tree.points):
        x = p.x.value if (p.x.absolute or not tree.relative) else x + p.x.value
        y = p.y.value if (p.y.absolute or not tree.relative) else y + p.y.value
        out[i] = x, y
    return out


def arc_through(a, b, bulge: float) -> tuple[tuple[float, float], float, float, float]:
    """The circular arc from ``a`` to ``b`` with the given bulge ``tan(sweep / 4)``.

    A positive bulge turns counter-clockwise (for a minor arc the centre lies left of
    the chord a→b).  The bulge, not the sweep, is the argument because it keeps full
    precision for nearly flat and nearly closed arcs alike: ``|bulge|`` is twice the
    sagitta over the chord.  Returns ``(center, radius, start_angle, end_angle)`` with
    ``start_angle`` in (-pi, pi] and ``end_angle = start_angle + sweep``.

    Examples
    --------
    >>> c, r, a0, a1 = arc_through((1.0, 0.0), (0.0, 1.0), math.tan(math.pi / 8))
    >>> [round(v, 9) + 0.0 for v in (*c, r, a0, a1)]
    [0.0, 0.0, 1.0, 0.0, 1.570796327]
    """
    ax, ay = a
    bx, by = b
    wx, wy = bx - ax, by - ay
    chord = math.hypot(wx, wy)
    h = (1.0 - bulge * bulge) / (4.0 * bulge)  # centre offset along the left normal / chord
    cx = 0.5 * (ax + bx) - wy * h
    cy = 0.5 * (ay + by) + wx * h
    radius = chord * (1.0 + bulge * bulge) / (4.0 * abs(bulge))
    start = math.atan2(ay - cy, ax - cx)
    if start <= -math.pi:
        start = math.pi
    return (cx, cy), radius, start, start + 4.0 * math.atan(bulge)


def _end_direction(row: dict) -> tuple[float, float]:
    """Unit direction in which a constructed piece arrives at its end point."""
    if row["type"] == PwType.SEGMENT:
        dx, dy = row["pt"][0] - row["from"][0], row["pt"][1] - row["from"][1]
        n = math.hypot(dx, dy)
        return dx / n, dy / n
    phi = row["end"]
    sign = 1.0 if row["end"] > row["start"] else -1.0
    return -sign * math.sin(phi), sign * math.cos(phi)


class _Builder:
    """Turns resolved points into pw_point rows, collecting diagnostics."""

    def __init__(self, tree: PwcList, pts: np.ndarray):
        self.tree, self.pts = tree, pts
        self.extent = float(np.abs(pts).max()) if len(pts) else 0.0
        self.rows: list[dict] = []
        self.diags: list[Diagnostic] = []

    def diag(self, severity: str, p: PwPoint, msg: str, fix: str) -> None:
        self.diags.append(Diagnostic(severity, msg, p.loc, fix))

    def row(self, kind: PwType, p: PwPoint, a, b, arc=None) -> None:
        row = {"type": kind, "pt": (float(b[0]), float(b[1])), "from": a, "line": p.loc.line,
               "text": p.text, "center": (0.0, 0.0), "radius": 0.0, "start": 0.0, "end": 0.0,
               "length": math.hypot(b[0] - a[0], b[1] - a[1])}
        if arc is not None:
            center, radius, start, end = arc
            row.update(center=center, radius=radius, start=start, end=end,
                       length=radius * abs(end - start))
        self.rows.append(row)

    def arc(self, kind: PwType, p: PwPoint, a, b, bulge: float) -> None:
        """Emit an arc, or a segment (with a warning) when it is flatter than precision."""
        if abs(bulge) / 2.0 < TOL.flat_arc_rel:  # sagitta / chord
            sag = math.hypot(b[0] - a[0], b[1] - a[1]) * abs(bulge) / 2.0
            self.diag("warning", p, "this arc is so flat that it is compiled as a straight "
                      f"segment (it deviates from its chord by {sag:.3g})",
                      "use a larger angle or sagitta, or drop the property")
            self.row(PwType.SEGMENT, p, a, b)
        else:
            self.row(kind, p, a, b, arc_through(a, b, bulge))

    def in_range(self) -> bool:
        """Whether the coordinates can be compiled in double precision (else an error)."""
        pts, tree = self.pts, self.tree
        bad = np.flatnonzero(~np.all(np.isfinite(pts), axis=1))
        if len(bad):
            self.diag("error", tree.points[bad[0]], "this point's coordinates overflow double "
                      "precision (beyond 1.8e308, after adding up the offsets)",
                      "scale the whole list down")
            return False
        if self.extent == 0.0:
            return True  # every point at the origin: reported by build()
        if not TOL.coordinate_min <= self.extent <= TOL.coordinate_max:
            i = int(np.argmax(np.abs(pts).max(axis=1)))
            self.diag("error", tree.points[i], f"the largest coordinate, {self.extent:.3g}, "
                      f"is outside [{TOL.coordinate_min:g}, {TOL.coordinate_max:g}]: the "
                      "curve cannot be normalized in double precision",
                      "scale the whole list (every coordinate) into that range")
            return False
        return True

    def build(self) -> None:
        pts, tree = self.pts, self.tree
        if not self.in_range():
            return
        self.row(PwType.SEGMENT, tree.points[0], pts[0], pts[0])  # the start: no piece
        same_tol = TOL.same_point_rel * self.extent
        for i in range(1, len(pts)):
            p = tree.points[i]
            a, b = self.rows[-1]["pt"], (float(pts[i, 0]), float(pts[i, 1]))
            same = math.hypot(b[0] - a[0], b[1] - a[1]) <= same_tol
            if p.prop is None:
                if same:
                    self.diag("warning", p, "segment between two identical points; it is "
                              "dropped", "delete this line, or move the point")
                else:
                    self.row(PwType.SEGMENT, p, a, b)
                continue
            if same:
                self.diag("error", p, f"':{p.prop}' joins two identical points: an arc needs "
                          "two distinct end points", "move this point or delete the line")
                continue
            n = len(self.rows)
            getattr(self, "_" + p.prop)(p, a, b)
            if not all(math.isfinite(r[k]) for r in self.rows[n:]
                       for k in ("radius", "length", "start", "end")) or not all(
                    math.isfinite(x) for r in self.rows[n:] for x in r["center"]):
                del self.rows[n:]
                self.diag("error", p, f"':{p.prop}': this arc's centre or radius overflows "
                          "double precision (its sagitta is far larger than its chord)",
                          "use a smaller angle or sagitta, or scale the list down")
        if len(self.rows) < 2 and not any(d.severity == "error" for d in self.diags):
            self.diag("error", tree.points[-1], "every point is at the same place: the curve "
                      "has no length", "give the points different coordinates")

    def _angle(self, p: PwPoint, a, b) -> None:
        if abs(p.arg) >= 360.0:
            self.diag("error", p, f"':angle {p.arg:g}' turns a full circle or more; an arc "
                      "between two distinct points turns less than 360 degrees",
                      "use an angle between -360 and 360 (exclusive)")
        elif abs(p.arg) < TOL.angle_deg:
            self.diag("warning", p, f"':angle {p.arg:g}' is below {TOL.angle_deg:g} degrees; "
                      "compiled as a straight segment", "drop ':angle', or use a larger angle")
            self.row(PwType.SEGMENT, p, a, b)
        else:
            self.arc(PwType.ANGLE, p, a, b, math.tan(math.radians(p.arg) / 4.0))

    def _sag(self, p: PwPoint, a, b) -> None:
        if p.arg == 0.0:
            self.diag("warning", p, "':sag 0' is a straight segment", "drop ':sag 0'")
            self.row(PwType.SEGMENT, p, a, b)
            return
        chord = math.hypot(b[0] - a[0], b[1] - a[1])
        self.arc(PwType.SAGITTA, p, a, b, 2.0 * p.arg / chord)

    def _cyma(self, p: PwPoint, a, b, first_bulge: float, kind: PwType) -> None:
        m = (0.5 * (a[0] + b[0]), 0.5 * (a[1] + b[1]))
        self.row(kind, p, a, m, arc_through(a, m, first_bulge))
        self.row(kind, p, m, b, arc_through(m, b, -first_bulge))

    def _cyma_recta(self, p: PwPoint, a, b) -> None:
        self._cyma(p, a, b, _BULGE_60, PwType.CYMA_RECTA)  # convex (ccw) first

    def _cyma_reversa(self, p: PwPoint, a, b) -> None:
        self._cyma(p, a, b, -_BULGE_60, PwType.CYMA_REVERSA)  # concave (cw) first

    def _flare(self, p: PwPoint, a, b) -> None:
        if len(self.rows) < 2:
            self.diag("error", p, "':flare' needs a previous piece to be tangent to, and this "
                      "point has none", "put a segment or arc before the flare, or use "
                      "':angle' / ':sag' here")
            return
        tx, ty = _end_direction(self.rows[-1])
        wx, wy = b[0] - a[0], b[1] - a[1]
        cross, dot = tx * wy - ty * wx, tx * wx + ty * wy
        if abs(cross) <= TOL.flare_rel * math.hypot(wx, wy):
            if dot > 0:
                self.diag("warning", p, "the flare's end lies on the tangent line of the "
                          "previous piece; compiled as a straight segment", "drop ':flare'")
                self.row(PwType.SEGMENT, p, a, b)
            else:
                self.diag("error", p, "the flare's end lies straight behind its start on the "
                          "tangent line: no circle tangent there passes through it",
                          "move the point off the line of the previous piece")
            return
        # the sweep is twice the tangent-chord angle alpha; bulge = tan(alpha / 2)
        w = math.hypot(wx, wy)
        bulge = cross / (w + dot) if dot >= 0 else (w - dot) / cross
        self.arc(PwType.FLARE, p, a, b, bulge)


def compile_list(tree: PwcList, name: str = "curve",
                 normalize: bool = True) -> tuple[Curve, list[Diagnostic]]:
    """Compile a parsed list; returns the curve and the warnings.

    Raises :class:`PwcGeometryError` (holding all errors and warnings) when the list
    describes impossible geometry.
    """
    b = _Builder(tree, resolve_points(tree))
    b.build()
    if any(d.severity == "error" for d in b.diags):
        raise PwcGeometryError(b.diags)
    rows = b.rows
    scale = 1.0 / b.extent if normalize else 1.0
    col = lambda key: np.array([r[key] for r in rows], dtype=np.float64)  # noqa: E731
    lengths = col("length") * scale
    cum = np.cumsum(lengths)
    total = float(cum[-1])
    t = cum / total
    t[0], t[-1] = 0.0, 1.0
    short = np.flatnonzero(np.diff(t) <= 0)
    if len(short):
        bad = [p for p in tree.points if p.loc.line == rows[short[0] + 1]["line"]][0]
        raise PwcGeometryError(b.diags + [Diagnostic(
            "error", "this piece is too short, relative to the whole curve, to be told "
            "apart from its neighbour", bad.loc, "remove the point or lengthen the piece")])
    curve = Curve(
        name=name,
        type=np.array([r["type"] for r in rows], dtype=np.int8),
        t=t,
        pt=col("pt") * scale,
        center=col("center") * scale,
        radius=col("radius") * scale,
        start_angle=col("start"),
        end_angle=col("end"),
        length=total,
        scale=scale,
        relative=tree.relative,
        source=tree.file,
        line=np.array([r["line"] for r in rows], dtype=np.int64),
        text=tuple(r["text"] for r in rows),
    )
    return curve, b.diags
