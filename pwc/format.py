"""Canonical text of a parsed pwc-list (the inverse of :func:`pwc.parser.parse`).

Numbers are written with ``repr`` so they parse back to the identical float.
"""

from __future__ import annotations

from pwc.tree import Coord, PwcList

__all__ = ["format_list"]


def _num(v: float) -> str:
    s = repr(float(v) + 0.0)
    return s[:-2] if s.endswith(".0") else s


def _coord(c: Coord) -> str:
    return ("a" if c.absolute else "") + _num(c.value)


def format_list(tree: PwcList) -> str:
    """The list as pwc text, one point per line.

    Examples
    --------
    >>> from pwc.parser import parse
    >>> print(format_list(parse(":relative\\n0 0   # start\\n1/4 a.5 :sag -1e-3")[0]), end="")
    :relative
    0 0
    0.25 a0.5 :sag -0.001
    """
    lines = [":relative"] if tree.relative else []
    for p in tree.points:
        item = f"{_coord(p.x)} {_coord(p.y)}"
        if p.prop:
            item += f" :{p.prop}" + (f" {_num(p.arg)}" if p.arg is not None else "")
        lines.append(item)
    return "\n".join(lines) + "\n"
