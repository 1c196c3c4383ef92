"""The gallery's scenes read as the Handbook's figures, and they are the Handbook's."""

from __future__ import annotations

import re

import pytest
from repo import HANDBOOK, needs_handbook

from gallery.figures import (
    STAGE_OBJECTS,
    TEST_WIDTH,
    FigureError,
    figures,
    read_figure,
    scenes_dir,
)

FIGURES = figures()


def test_every_scene_is_a_figure_in_the_handbooks_order():
    names = sorted(p.stem for p in scenes_dir().glob("*.toml"))
    assert sorted(f.name for f in FIGURES) == names
    keys = [f.sort_key() for f in FIGURES]
    assert keys == sorted(keys) and len(set(keys)) == len(keys)
    for fig in FIGURES:
        chapter, index = fig.name.split("_")[1:]
        assert fig.number == f"{int(chapter)}.{int(index)}" and fig.chapter == int(chapter)
        assert fig.title and fig.captions, fig.name
        assert fig.part.startswith("Part ")
        w, h = fig.resolution
        tw, th = fig.test_resolution
        assert tw == TEST_WIDTH and (tw * fig.factor, th * fig.factor) == (w, h)


def test_captions_are_the_figures_materials_not_the_stages():
    by_name = {f.name: f for f in FIGURES}
    assert by_name["fig_13_14"].captions == ("glossy_round_bumps(u_scale: 80, v_scale: 40)",)
    # Figure 3.2's lights are emissive panels, and its floor is the stage's
    assert by_name["fig_03_02"].captions == ("plaster()",)
    assert {"floor", "light_left"} <= STAGE_OBJECTS
    assert by_name["fig_14_11"].captions[1].startswith("circle_nonlinear(")


@pytest.mark.parametrize("pattern, expected", [
    (["13"], lambda f: f.chapter == 13),
    (["13.14"], lambda f: f.number == "13.14"),
    (["13.04"], lambda f: f.number == "13.4"),
    (["fig_12_1?"], lambda f: f.name.startswith("fig_12_1")),
    (["fig_14_28.toml", "3"], lambda f: f.name == "fig_14_28" or f.chapter == 3),
])
def test_filters_select_by_chapter_number_name_or_glob(pattern, expected):
    chosen = figures(pattern)
    assert chosen == [f for f in FIGURES if expected(f)] and chosen


@pytest.mark.parametrize("pattern", ["99", "13.99", "fig_99_*", "glossy"])
def test_a_filter_that_selects_nothing_says_how_to_write_one(pattern):
    with pytest.raises(FigureError, match=rf"no gallery figure matches '{re.escape(pattern)}'"
                                          r".*chapter such as 13.*figure such as 13\.14"):
        figures([pattern])


SCENE = """# Figure 13.3 of the MDL Handbook: a test
# a note
[render]
resolution = [{w}, {h}]

[[objects]]
name = "floor"
surface = "square"
material = "diffuse()"

[[objects]]
name = "thing"
surface = "square"
material = '''scaled_uv(u_scale: 8,
    v_scale: 4)'''
"""


def test_a_scene_reads_as_a_figure(tmp_path):
    path = tmp_path / "fig_13_03.toml"
    path.write_text(SCENE.format(w=512, h=384))
    fig = read_figure(path)
    assert (fig.number, fig.chapter, fig.title, fig.notes) == ("13.3", 13, "a test", "a note")
    assert fig.captions == ("scaled_uv(u_scale: 8, v_scale: 4)",)
    assert fig.factor == 4 and fig.test_resolution == (128, 96)


@pytest.mark.parametrize("name, text, message", [
    ("figure_1.toml", SCENE.format(w=256, h=192), r"named fig_CC_NN\.toml"),
    ("fig_13_04.toml", SCENE.format(w=256, h=192),
     r"fig_13_04\.toml:1: the scene must open with '# Figure 13\.4 of the MDL Handbook"),
    ("fig_13_03.toml", SCENE.format(w=320, h=192), r"320 x 192 is not a whole multiple"),
    ("fig_13_03.toml", SCENE.format(w=256, h=191), r"256 x 191 is not a whole multiple"),
    ("fig_13_03.toml", SCENE.format(w=256, h=192) + "[render\n", r"fig_13_03\.toml: "),
])
def test_a_scene_that_is_not_a_figure_is_refused_with_the_reason(tmp_path, name, text, message):
    path = tmp_path / name
    path.write_text(text)
    with pytest.raises(FigureError, match=message):
        read_figure(path)


def _part_5() -> list[str]:
    text = HANDBOOK.read_text(encoding="utf-8")
    return text[text.index("\nPart 5 Modifying geometry\n"):
                text.index("\nPart 6 Reference\n")].splitlines()


def _code_blocks(lines: list[str]) -> list[tuple[int, str]]:
    """(line index of the opening fence, text) of every fenced block."""
    blocks, start = [], None
    for i, line in enumerate(lines):
        if line.strip().startswith("```"):
            if start is None:
                start = i
            else:
                blocks.append((start, "\n".join(lines[start + 1:i])))
                start = None
    return blocks


@needs_handbook
def test_every_rendered_figure_of_part_5_has_a_scene_with_the_handbooks_caption():
    """The rendered figures of chapters 12 and 13 stand alone as ``Figure N`` with the
    material call printed beside them (Figure 12.17 is described in a sentence); each
    has a scene whose material is that call, whitespace aside."""
    lines = _part_5()
    numbers = {f.number: f for f in FIGURES}
    blocks = _code_blocks(lines)
    squeeze = lambda s: re.sub(r"\s+", "", s)  # noqa: E731
    rendered = [(i, m.group(1)) for i, line in enumerate(lines)
                if (m := re.fullmatch(r"Figure (1[2-5]\.\d+)\s*", line))]
    assert len(rendered) > 30
    for i, number in rendered:
        assert number in numbers, f"Figure {number} of Part 5 has no scene"
        if number.startswith(("12.", "13.")):
            near = {squeeze(text) for start, text in blocks if abs(start - i) < 20}
            assert any(squeeze(c) in near for c in numbers[number].captions), (
                f"Figure {number}: {numbers[number].captions} is not the Handbook's caption")
    assert any("Figure 12.17" in line and "rendering in perspective" in line for line in lines)
    assert "12.17" in numbers
