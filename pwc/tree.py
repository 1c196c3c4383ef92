"""The syntax tree of a pwc-list: frozen dataclasses, each point with its source location.

Locations and source text are carried for diagnostics but excluded from equality, so
``parse(format(tree)) == tree`` compares only what the list means.
"""

from __future__ import annotations

from dataclasses import dataclass, field

from pwc.diagnostics import Loc

__all__ = ["Coord", "PwPoint", "PwcList", "POINT_PROPERTIES", "LIST_PROPERTIES"]

#: point property -> number of arguments it takes
POINT_PROPERTIES: dict[str, int] = {
    "angle": 1,
    "sag": 1,
    "cyma_recta": 0,
    "cyma_reversa": 0,
    "flare": 0,
}
LIST_PROPERTIES: tuple[str, ...] = ("relative",)


@dataclass(frozen=True, slots=True)
class Coord:
    """One coordinate; ``absolute`` is the ``a`` prefix (meaningful in relative lists)."""

    value: float
    absolute: bool = False


@dataclass(frozen=True, slots=True)
class PwPoint:
    """A pw-point: ``X Y [:property [argument]]``."""

    x: Coord
    y: Coord
    prop: str | None = None  # a key of POINT_PROPERTIES
    arg: float | None = None
    loc: Loc = field(default=Loc("<string>", 1), compare=False)

    @property
    def text(self) -> str:
        """The source line without its comment."""
        return self.loc.text.split("#", 1)[0].strip()


@dataclass(frozen=True, slots=True)
class PwcList:
    """A parsed pwc-list: list properties and points, in file order."""

    points: tuple[PwPoint, ...]
    relative: bool = False
    file: str = field(default="<string>", compare=False)
