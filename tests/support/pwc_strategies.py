"""Hypothesis strategies for valid pwc-lists (shared by the pwc tests)."""

from __future__ import annotations

import math

from hypothesis import strategies as st

PROPS = [None, "angle", "sag", "cyma_recta", "cyma_reversa", "flare"]


@st.composite
def valid_lists(draw, max_points: int = 12) -> str:
    """Text of a geometrically valid pwc-list: distinct consecutive points, arcs of
    reasonable sweep, no flare without a previous piece."""
    n = draw(st.integers(2, max_points))
    relative = draw(st.booleans())
    coord = st.floats(-10, 10, allow_nan=False).map(lambda v: round(v, 3))
    lines = [":relative"] if relative else []
    pts = [(draw(coord), draw(coord))]
    lines.append(f"{pts[0][0]!r} {pts[0][1]!r}")
    for i in range(1, n):
        while True:
            p = (draw(coord), draw(coord))
            chord = math.dist(p, pts[-1])
            if chord > 0.05:
                break
            pts_shift = (pts[-1][0] + 1.0, pts[-1][1])
            p, chord = pts_shift, 1.0
            break
        prop = draw(st.sampled_from(PROPS if i > 1 else PROPS[:-1]))
        item = ""
        if prop == "angle":
            deg = draw(st.floats(1.0, 300.0)) * draw(st.sampled_from([-1, 1]))
            item = f" :angle {deg!r}"
        elif prop == "sag":
            sag = chord * draw(st.floats(0.01, 3.0)) * draw(st.sampled_from([-1, 1]))
            item = f" :sag {sag!r}"
        elif prop:
            item = f" :{prop}"
        if relative:
            dx, dy = p[0] - pts[-1][0], p[1] - pts[-1][1]
            lines.append(f"{dx!r} {dy!r}{item}")
        else:
            lines.append(f"{p[0]!r} {p[1]!r}{item}")
        pts.append(p)
    return "\n".join(lines) + "\n"


def compile_valid(text: str):
    """Compile a generated list; discards the example (``assume``) when a flare ends
    straight behind its start, the one invalid case the generator cannot rule out
    without knowing the previous piece's tangent."""
    from hypothesis import assume

    from pwc import PwcGeometryError, compile_source

    try:
        return compile_source(text)
    except PwcGeometryError as e:
        assume("straight behind its start" not in str(e))
        raise
