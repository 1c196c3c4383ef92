"""Source text, spans and diagnostics of MDL modules, formatted as the pwc-list's are.

Every message names ``file:line:col``, quotes the line with a caret under the culprit,
and says how to fix it (:class:`pwc.diagnostics.Diagnostic` formats them, so a user sees
one style across pwc-lists, scenes and MDL)::

    stone.mdl:4:12: error: unknown function 'math::sine'
        4 |     return math::sine(x);
          |            ^^^^^^^^^^
      fix: did you mean 'math::sin'?

Examples
--------
>>> src = Source("a.mdl", "mdl 1.6;\\nconst float x = ;\\n")
>>> print(src.diagnostic("error", "expected an expression", 25, 26, "write a value"))
a.mdl:2:17: error: expected an expression
    2 | const float x = ;
      |                 ^
  fix: write a value
"""

from __future__ import annotations

import bisect
import difflib
from collections.abc import Iterable, Sequence
from dataclasses import dataclass

from pwc.diagnostics import Diagnostic, Loc

__all__ = ["Source", "Span", "Diagnostic", "Loc", "MdlError", "suggest", "did_you_mean",
           "MAX_ERRORS"]

#: a module that is not MDL at all should not print thousands of errors
MAX_ERRORS = 25


@dataclass(frozen=True, slots=True)
class Span:
    """Character offsets ``[start, end)`` into a :class:`Source`'s text."""

    start: int
    end: int

    def __or__(self, other: Span) -> Span:
        return Span(min(self.start, other.start), max(self.end, other.end))


class Source:
    """One MDL text with its name, and the offset -> (line, column) map.

    Parameters
    ----------
    name : str
        What diagnostics call the file (a path, or ``<scene.toml:12>``).
    text : str
    line_offset, col_offset : int
        Added to reported positions: text embedded in another file (a material call in a
        TOML scene) is reported at its place in that file.
    """

    def __init__(self, name: str, text: str, line_offset: int = 0, col_offset: int = 0):
        self.name = name
        self.text = text
        self.line_offset = line_offset
        self.col_offset = col_offset
        self._starts = [0]
        i = text.find("\n")
        while i >= 0:
            self._starts.append(i + 1)
            i = text.find("\n", i + 1)

    def __repr__(self) -> str:
        return f"Source({self.name!r})"

    def line_col(self, offset: int) -> tuple[int, int]:
        """1-based line and column of ``offset`` (clamped into the text)."""
        offset = max(0, min(offset, len(self.text)))
        line = bisect.bisect_right(self._starts, offset) - 1
        col = offset - self._starts[line] + 1
        if line == 0:
            col += self.col_offset
        return line + 1 + self.line_offset, col

    def line_text(self, line: int) -> str:
        """The text of 1-based ``line`` (as numbered by :meth:`line_col`)."""
        i = line - 1 - self.line_offset
        if not 0 <= i < len(self._starts):
            return ""
        end = self.text.find("\n", self._starts[i])
        text = self.text[self._starts[i]:] if end < 0 else self.text[self._starts[i]:end]
        return (" " * self.col_offset + text) if i == 0 else text

    def loc(self, start: int, end: int | None = None) -> Loc:
        """A :class:`pwc.diagnostics.Loc` for the span (width limited to its first line)."""
        line, col = self.line_col(start)
        text = self.line_text(line)
        end = start + 1 if end is None else end
        width = max(1, min(end - start, len(text) - col + 1))
        return Loc(self.name, line, col, width, text)

    def diagnostic(self, severity: str, message: str, start: int, end: int | None = None,
                   fix: str = "") -> Diagnostic:
        """A located diagnostic."""
        return Diagnostic(severity, message, self.loc(start, end), fix)


class MdlError(Exception):
    """An MDL module (or expression) has errors; ``diagnostics`` holds every one found.

    ``str(error)`` is the formatted report, ready to print (never a traceback).
    """

    def __init__(self, diagnostics: Sequence[Diagnostic]):
        self.diagnostics = list(diagnostics)
        super().__init__(str(self))

    def __str__(self) -> str:
        return "\n".join(d.format() for d in self.diagnostics)

    def __reduce__(self):
        return (type(self), (self.diagnostics,))

    @property
    def first(self) -> Diagnostic:
        """The first error (the one a user fixes first)."""
        errors = [d for d in self.diagnostics if d.severity == "error"]
        return (errors or self.diagnostics)[0]


def suggest(word: str, candidates: Iterable[str], cutoff: float = 0.6) -> str | None:
    """The closest candidate to ``word`` (difflib), or None."""
    pool = sorted(set(candidates))
    hit = difflib.get_close_matches(word, pool, 1, cutoff)
    if hit:
        return hit[0]
    # qualified names: compare the last part too (math::sine -> math::sin)
    if "::" in word:
        tail = word.rsplit("::", 1)[1]
        tails = {c.rsplit("::", 1)[-1]: c for c in pool}
        hit = difflib.get_close_matches(tail, list(tails), 1, cutoff)
        if hit:
            return tails[hit[0]]
    return None


def did_you_mean(word: str, candidates: Iterable[str], cutoff: float = 0.6) -> str:
    """``"did you mean 'x'?"`` for the closest candidate, or ``""``."""
    hit = suggest(word, candidates, cutoff)
    return f"did you mean '{hit}'?" if hit else ""
