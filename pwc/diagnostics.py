"""Diagnostics: source locations, warnings and errors, formatted like a compiler's.

Every message names ``file:line:col``, quotes the line with a caret under the culprit,
and says how to fix it::

    molding.pwc:3:5: error: unknown property ':sagg'
        3 | 0 1 :sagg .3
          |     ^^^^^
      fix: did you mean ':sag'?
"""

from __future__ import annotations

from dataclasses import dataclass, field

__all__ = ["Loc", "Diagnostic", "PwcError", "PwcSyntaxError", "PwcGeometryError"]


@dataclass(frozen=True, slots=True)
class Loc:
    """A span in a source file: 1-based line, 1-based column, width in characters."""

    file: str
    line: int
    col: int = 1
    width: int = 1
    text: str = ""  # the whole source line, for quoting

    def __str__(self) -> str:
        return f"{self.file}:{self.line}:{self.col}"


@dataclass(frozen=True, slots=True)
class Diagnostic:
    """One error or warning at a location, with a suggested fix."""

    severity: str  # "error" | "warning"
    message: str
    loc: Loc
    fix: str = ""

    def format(self) -> str:
        """The message as a compiler prints it (several lines)."""
        out = [f"{self.loc}: {self.severity}: {self.message}"]
        if self.loc.text:
            text = self.loc.text.rstrip("\n").expandtabs(1)
            gutter = f"{self.loc.line:>5} | "
            out.append(gutter + text)
            caret = " " * (self.loc.col - 1) + "^" * max(1, self.loc.width)
            out.append(" " * (len(gutter) - 2) + "| " + caret)
        if self.fix:
            out.append(f"  fix: {self.fix}")
        return "\n".join(out)

    __str__ = format


@dataclass
class PwcError(Exception):
    """A pwc-list could not be compiled; ``diagnostics`` holds every error found.

    ``str(error)`` is the formatted report, ready to print.
    """

    diagnostics: list[Diagnostic] = field(default_factory=list)

    def __post_init__(self) -> None:
        super().__init__(self.__str__())

    def __str__(self) -> str:
        return "\n".join(d.format() for d in self.diagnostics)

    @property
    def first(self) -> Diagnostic:
        return self.diagnostics[0]


class PwcSyntaxError(PwcError):
    """The text is not a well-formed pwc-list (bad token, number, property, arguments)."""


class PwcGeometryError(PwcError):
    """The list is well formed but describes impossible geometry (arc between equal points)."""
