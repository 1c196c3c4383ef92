"""pwc: the MDL Handbook's pwc-list language (chapter 15) — parse, compile, evaluate, emit.

>>> import pwc
>>> curve = pwc.compile_text("0 0\\n.7 0\\n.7 .4\\n3/7 .4\\n3/7 4/3\\n4/7 1", name="segments")
>>> round(curve.length, 5), curve.t.round(5).tolist()
(2.00056, [0.0, 0.26243, 0.41238, 0.51414, 0.86404, 1.0])
"""

from __future__ import annotations

from pathlib import Path

from pwc.compiler import compile_list
from pwc.curve import Curve, PwType, point_along_pwc
from pwc.diagnostics import Diagnostic, Loc, PwcError, PwcGeometryError, PwcSyntaxError
from pwc.parser import decode_source, parse
from pwc.tree import PwcList

__all__ = [
    "Curve", "PwType", "PwcList", "Diagnostic", "Loc", "PwcError", "PwcSyntaxError",
    "PwcGeometryError", "parse", "compile_text", "compile_source", "load", "point_along_pwc",
]


def compile_source(text: str, name: str = "curve", file: str = "<string>",
                   normalize: bool = True) -> tuple[Curve, list[Diagnostic]]:
    """Parse and compile pwc-list text; returns the curve and its warnings.

    Raises :class:`PwcError` (a syntax or geometry error) with every diagnostic found.
    """
    tree, warnings = parse(text, file)
    try:
        curve, more = compile_list(tree, name, normalize)
    except PwcError as e:
        raise type(e)(warnings + e.diagnostics) from None
    return curve, warnings + more


def compile_text(text: str, name: str = "curve", file: str = "<string>",
                 normalize: bool = True) -> Curve:
    """Compile pwc-list text to a :class:`Curve`, ignoring warnings."""
    return compile_source(text, name, file, normalize)[0]


def load(path, normalize: bool = True) -> Curve:
    """Compile a ``.pwc`` file; the curve is named after the file's stem."""
    path = Path(path)
    text = decode_source(path.read_bytes(), str(path))
    return compile_source(text, path.stem, str(path), normalize)[0]
