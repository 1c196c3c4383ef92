"""The gallery's scenes as the Handbook's figures: number, chapter, title, captions, sizes.

A scene ``gallery/scenes/fig_CC_NN.toml`` reproduces Figure CC.NN of the *MDL Handbook*.
Its opening comment says what the figure shows: the first line is ``# Figure CC.NN of
the MDL Handbook: TITLE``, the following comment lines note how the scene reads the
figure and any departure.  The figure's *captions* are the material calls the Handbook
prints under it: the materials of every object but the stage's own (the floor, the
enclosure and the emissive panels that light it, :data:`STAGE_OBJECTS`).

The scene's ``[render] resolution`` is the size of its reference image.  The regression
test and ``pwc gallery check`` render the figure smaller, at :attr:`Figure.test_resolution`
(a whole fraction of it, :data:`TEST_WIDTH` pixels wide), and compare with the reference
averaged down to that size: a box-filtered pixel is the mean of the pixels it covers,
so both estimate the same image.
"""

from __future__ import annotations

import fnmatch
import re
import tomllib
from dataclasses import dataclass
from pathlib import Path

__all__ = [
    "CHAPTERS",
    "PARTS",
    "STAGE_OBJECTS",
    "TEST_WIDTH",
    "Figure",
    "FigureError",
    "read_figure",
    "figures",
    "scenes_dir",
]

#: width of the images the regression test renders (the reference is a whole multiple)
TEST_WIDTH = 128

#: objects that set the stage rather than show the figure's material
STAGE_OBJECTS = frozenset({"floor", "enclosure", "spotlight", "light_left", "light_right"})

#: the Handbook's chapters that the gallery illustrates
CHAPTERS = {
    3: "Light at a surface",
    4: "Glass",
    5: "Light in a volume",
    6: "Combining distribution functions",
    7: "Plastic",
    8: "Fabric",
    9: "Function calls as arguments",
    10: "Noise",
    12: "Displacement mapping: moving a surface point",
    13: "Bump mapping: perturbing a surface normal",
    14: "Geometric profiles",
    15: "Architectural details",
}

#: the Handbook's parts, by their chapters
PARTS = {
    "Part 2 Light interaction": range(3, 6),
    "Part 3 Material combinations": range(6, 9),
    "Part 4 Defining functions": range(9, 11),
    "Part 5 Modifying geometry": range(11, 16),
}

_NAME = re.compile(r"fig_(\d{2})_(\d{2})")
_TITLE = re.compile(r"Figure\s+\d+\.\d+\s+of the MDL Handbook:\s*")


class FigureError(ValueError):
    """A scene that does not describe a figure, or a filter that matches none."""


@dataclass(frozen=True)
class Figure:
    """One figure of the Handbook and the scene that reproduces it.

    Attributes
    ----------
    name : str
        The scene's stem, ``fig_13_14``.
    scene : Path
    number : str
        The Handbook's number, ``"13.14"``.
    chapter : int
    title : str
        The scene's first comment line after ``Figure N of the MDL Handbook:``.
    notes : str
        The scene's other opening comment lines, joined.
    captions : tuple of str
        The material calls the figure shows, whitespace normalized, each once.
    resolution : (int, int)
        Width and height of the reference image.
    """

    name: str
    scene: Path
    number: str
    chapter: int
    title: str
    notes: str
    captions: tuple[str, ...]
    resolution: tuple[int, int]

    @property
    def part(self) -> str:
        """The Handbook's part, ``"Part 5 Modifying geometry"``."""
        return next(p for p, chapters in PARTS.items() if self.chapter in chapters)

    @property
    def factor(self) -> int:
        """How many reference pixels a test pixel spans in each direction."""
        return max(1, self.resolution[0] // TEST_WIDTH)

    @property
    def test_resolution(self) -> tuple[int, int]:
        """Width and height of the regression test's image."""
        return self.resolution[0] // self.factor, self.resolution[1] // self.factor

    def sort_key(self) -> tuple[int, int]:
        chapter, figure = self.number.split(".")
        return int(chapter), int(figure)


def scenes_dir() -> Path:
    """The gallery's scene folder (package data when installed)."""
    from render.library.resources import bundled_scenes

    return bundled_scenes()


def read_figure(path: str | Path) -> Figure:
    """The figure a scene file reproduces.

    Raises
    ------
    FigureError
        The file name is not ``fig_CC_NN.toml``, the header does not name the figure,
        or the reference size is not a whole multiple of the test size.
    """
    path = Path(path)
    m = _NAME.fullmatch(path.stem)
    if not m:
        raise FigureError(f"{path}: a gallery scene is named fig_CC_NN.toml (chapter, figure)")
    chapter, index = int(m.group(1)), int(m.group(2))
    text = path.read_text(encoding="utf-8")
    header = []
    for line in text.splitlines():
        if not line.startswith("#"):
            break
        header.append(line[1:].strip())
    number = f"{chapter}.{index}"
    if not header or not _TITLE.match(header[0]) or not header[0].startswith(f"Figure {number} "):
        raise FigureError(f"{path}:1: the scene must open with '# Figure {number} of the MDL "
                          "Handbook: TITLE'")
    try:
        scene = tomllib.loads(text)
    except tomllib.TOMLDecodeError as e:
        raise FigureError(f"{path}: {e}") from None
    captions = tuple(dict.fromkeys(
        " ".join((obj["material"] if isinstance(obj["material"], str)
                  else str(obj["material"].get("call", ""))).split())
        for obj in scene.get("objects", [])
        if "material" in obj and obj.get("name") not in STAGE_OBJECTS))
    w, h = scene.get("render", {}).get("resolution", (256, 256))
    fig = Figure(name=path.stem, scene=path, number=number, chapter=chapter,
                 title=_TITLE.sub("", header[0]), notes=" ".join(header[1:]),
                 captions=captions, resolution=(int(w), int(h)))
    if fig.resolution[0] % TEST_WIDTH or fig.resolution[1] % fig.factor:
        raise FigureError(f"{path}: resolution {w} x {h} is not a whole multiple of a test "
                          f"image {TEST_WIDTH} pixels wide; make it {TEST_WIDTH} x n wide and "
                          f"as many times a whole height")
    return fig


def _matches(fig: Figure, pattern: str) -> bool:
    if re.fullmatch(r"\d+", pattern):
        return fig.chapter == int(pattern)
    if re.fullmatch(r"\d+\.\d+", pattern):
        return fig.number == f"{int(pattern.split('.')[0])}.{int(pattern.split('.')[1])}"
    return fnmatch.fnmatchcase(fig.name, pattern.removesuffix(".toml"))


def figures(patterns=(), folder: str | Path | None = None) -> list[Figure]:
    """The gallery's figures in the Handbook's order, or those any pattern selects.

    Parameters
    ----------
    patterns : iterable of str
        A chapter (``13``), a figure number (``13.14``), a scene name (``fig_13_14``) or
        a glob on scene names (``fig_12_*``).
    folder : path, optional
        The scene folder (default: :func:`scenes_dir`).

    Raises
    ------
    FigureError
        A pattern selects no figure (its message lists how to write one).

    Examples
    --------
    >>> [f.number for f in figures(["13.14", "fig_14_2?"])][:3]
    ['13.14', '14.20', '14.21']
    >>> figures(["99"])  # doctest: +ELLIPSIS
    Traceback (most recent call last):
    ...
    gallery.figures.FigureError: no gallery figure matches '99' (give a chapter such as 13, ...
    """
    folder = Path(folder) if folder is not None else scenes_dir()
    every = sorted((read_figure(p) for p in folder.glob("fig_*.toml")), key=Figure.sort_key)
    patterns = list(patterns)
    if not patterns:
        return every
    for pattern in patterns:
        if not any(_matches(f, pattern) for f in every):
            raise FigureError(
                f"no gallery figure matches {pattern!r} (give a chapter such as 13, a figure "
                "such as 13.14, a scene name such as fig_13_14 or a glob such as 'fig_12_*')")
    return [f for f in every if any(_matches(f, p) for p in patterns)]
