"""Drawings of a compiled curve like the Handbook's Figures 15.9-15.20, as SVG or PNG.

Shows the curve, its pw-points, each arc's centre (with dashed radii to the arc's ends),
the sagitta of every ``:sag`` arc, and the unit square that the curve displaces.
SVG is written directly; PNG uses matplotlib (imported only when asked for).
"""

from __future__ import annotations

import io
from dataclasses import dataclass

import numpy as np

from pwc.curve import Curve, PwType

__all__ = ["Drawing", "drawing", "to_svg", "to_png"]

_BLUE, _CURVE, _POINT, _CENTER, _SAG = "#3b6fd4", "#111111", "#d62728", "#7f7f7f", "#2ca02c"


@dataclass(frozen=True)
class Drawing:
    """What a curve drawing shows, in curve coordinates (x right, y up)."""

    curve: np.ndarray  # (m, 2) polyline of the exact curve
    points: np.ndarray  # (N, 2) pw-points
    centers: np.ndarray  # (k, 2) arc centres
    radii: list[np.ndarray]  # (3, 2) polylines: start -> centre -> end, one per arc
    sagittas: list[np.ndarray]  # (2, 2) chord midpoint -> arc midpoint, one per :sag arc
    frame: np.ndarray  # (2, 2) [[xmin, ymin], [xmax, ymax]] of everything to show
    wall: np.ndarray  # (k, 2) the undisplaced surface x = 0 (none for closed sweep curves)


def drawing(curve: Curve) -> Drawing:
    """Collect the drawing's elements from a curve."""
    bbox = curve.bbox
    size = float(np.max(bbox[1] - bbox[0])) or 1.0
    _, poly = curve.polyline(size * 2e-4)
    arcs = np.flatnonzero(curve.is_arc)
    prev = curve.pt[arcs - 1]
    ends = zip(prev, curve.center[arcs], curve.pt[arcs], strict=True)
    radii = [np.stack([a, c, b]) for a, c, b in ends]
    sag = arcs[curve.type[arcs] == PwType.SAGITTA]
    mid_phi = 0.5 * (curve.start_angle[sag] + curve.end_angle[sag])
    arc_mid = curve.center[sag] + curve.radius[sag, None] * np.stack(
        [np.cos(mid_phi), np.sin(mid_phi)], -1)
    chord_mid = 0.5 * (curve.pt[sag - 1] + curve.pt[sag])
    sagittas = [np.stack([c, m]) for c, m in zip(chord_mid, arc_mid, strict=True)]
    # the displaced unit square spans [0, 1] in y (the run) and x from 0 to the curve
    wall = np.zeros((0, 2)) if curve.is_closed else np.array([[0.0, 0.0], [0.0, 1.0]])
    everything = np.concatenate([poly, curve.center[arcs], wall])
    # centres of huge, nearly flat arcs would shrink the picture to a dot: keep them only
    # when they are near the curve
    near = np.all(np.abs(everything - poly.mean(0)) <= 4 * size, axis=1)
    frame = np.stack([everything[near].min(0), everything[near].max(0)])
    return Drawing(poly, curve.pt.copy(), curve.center[arcs], radii, sagittas, frame, wall)


def _svg_path(pts: np.ndarray, tx) -> str:
    q = tx(pts)
    return "M" + " L".join(f"{x:.2f},{y:.2f}" for x, y in q)


def to_svg(curve: Curve, width: int = 640) -> str:
    """An SVG drawing of the curve (curve y up, drawn with y up)."""
    d = drawing(curve)
    lo, hi = d.frame
    span = np.maximum(hi - lo, 1e-12)
    pad = 0.08 * float(span.max())
    lo, hi = lo - pad, hi + pad
    span = hi - lo
    k = width / span[0]
    height = int(np.ceil(span[1] * k))
    if height > 4 * width:  # very tall profiles: bound the height instead
        k = 4 * width / span[1]
        height = 4 * width
        width = int(np.ceil(span[0] * k))

    def tx(p):
        p = np.atleast_2d(p)
        return np.stack([(p[:, 0] - lo[0]) * k, (hi[1] - p[:, 1]) * k], -1)

    stroke = max(1.0, width / 400)
    out = [f'<svg xmlns="http://www.w3.org/2000/svg" width="{width}" height="{height}" '
           f'viewBox="0 0 {width} {height}">',
           f"<title>{curve.name}: {curve.n} pw-points, length {curve.length:.5g}</title>",
           f'<rect width="{width}" height="{height}" fill="white"/>']
    if len(d.wall):  # the undisplaced square seen edge-on: x = 0
        out.append(f'<path d="{_svg_path(d.wall, tx)}" stroke="{_BLUE}" '
                   f'stroke-width="{3 * stroke}" fill="none" opacity="0.6"/>')
    for r in d.radii:
        out.append(f'<path d="{_svg_path(r, tx)}" stroke="{_CENTER}" stroke-width="{stroke}" '
                   f'stroke-dasharray="{4 * stroke},{3 * stroke}" fill="none"/>')
    for s in d.sagittas:
        out.append(f'<path d="{_svg_path(s, tx)}" stroke="{_SAG}" stroke-width="{1.5 * stroke}" '
                   'fill="none"/>')
    out.append(f'<path d="{_svg_path(d.curve, tx)}" stroke="{_CURVE}" '
               f'stroke-width="{2 * stroke}" fill="none" stroke-linejoin="round"/>')
    for x, y in tx(d.centers):
        c = 4 * stroke
        out.append(f'<path d="M{x - c:.2f},{y:.2f} L{x + c:.2f},{y:.2f} M{x:.2f},{y - c:.2f} '
                   f'L{x:.2f},{y + c:.2f}" stroke="{_CENTER}" stroke-width="{stroke}"/>')
    for x, y in tx(d.points):
        out.append(f'<circle cx="{x:.2f}" cy="{y:.2f}" r="{3 * stroke:.2f}" fill="{_POINT}"/>')
    out.append("</svg>")
    return "\n".join(out) + "\n"


def to_png(curve: Curve, size_px: int = 800) -> bytes:
    """A PNG drawing of the curve (needs matplotlib)."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    d = drawing(curve)
    lo, hi = d.frame
    span = np.maximum(hi - lo, 1e-12)
    aspect = float(np.clip(span[1] / span[0], 0.25, 4.0))
    fig, ax = plt.subplots(figsize=(6 / max(aspect, 1) * 1.0 + 1, 6 * min(aspect, 1) + 1),
                           dpi=size_px / 7)
    if len(d.wall):
        ax.plot(d.wall[:, 0], d.wall[:, 1], color=_BLUE, lw=4, alpha=0.6)
    for r in d.radii:
        ax.plot(r[:, 0], r[:, 1], color=_CENTER, lw=0.8, ls="--")
    for s in d.sagittas:
        ax.plot(s[:, 0], s[:, 1], color=_SAG, lw=1.5)
    ax.plot(d.curve[:, 0], d.curve[:, 1], color=_CURVE, lw=1.8)
    if len(d.centers):
        ax.plot(d.centers[:, 0], d.centers[:, 1], "+", color=_CENTER, ms=8)
    ax.plot(d.points[:, 0], d.points[:, 1], "o", color=_POINT, ms=3.5)
    pad = 0.08 * float(span.max())
    ax.set_xlim(lo[0] - pad, hi[0] + pad)
    ax.set_ylim(lo[1] - pad, hi[1] + pad)
    ax.set_aspect("equal")
    ax.grid(True, lw=0.3, alpha=0.5)
    ax.set_title(f"{curve.name}  ({curve.n} pw-points, length {curve.length:.5g})", fontsize=9)
    buf = io.BytesIO()
    fig.savefig(buf, format="png", bbox_inches="tight")
    plt.close(fig)
    return buf.getvalue()
