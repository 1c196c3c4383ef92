"""The profile library: every list compiles cleanly and matches its golden compile, the
Handbook's lists are exactly as printed, flutes follow their constructions, and the
catalogue page is current."""

from __future__ import annotations

import json
import math
import re

import numpy as np
import pytest
from repo import HANDBOOK, PROFILES, ROOT, needs_handbook

import pwc
from pwc.catalogue import catalogue_markdown, description
from pwc.parser import parse

GOLDEN = ROOT / "tests" / "pwc" / "golden"


@pytest.mark.parametrize("path", PROFILES, ids=lambda p: p.stem)
def test_profile_compiles_without_warnings_and_matches_golden(path):
    curve, warnings = pwc.compile_source(path.read_text(), path.stem, str(path))
    assert warnings == [], "\n".join(map(str, warnings))
    assert description(path), f"{path.name} needs a one-line '# description' first line"
    gold = json.loads((GOLDEN / f"{path.stem}.json").read_text())
    assert len(gold["points"]) == curve.n
    assert curve.length == pytest.approx(gold["length"], rel=1e-12)
    for i, p in enumerate(gold["points"]):
        assert pwc.PwType(int(curve.type[i])).mdl_name == p["type"]
        np.testing.assert_allclose(curve.pt[i], p["pt"], rtol=1e-12, atol=1e-14)
        np.testing.assert_allclose(curve.center[i], p["center"], rtol=1e-12, atol=1e-14)
        assert [curve.t[i], curve.radius[i], curve.start_angle[i], curve.end_angle[i]] == \
            pytest.approx([p["t"], p["radius"], p["start_angle"], p["end_angle"]],
                          rel=1e-12, abs=1e-14)


def _printed_list(after: str) -> str:
    """The first code block after a sentence of the Handbook."""
    text = HANDBOOK.read_text(encoding="utf-8")
    start = text.index(after)
    block = re.search(r"```\n(.*?)```", text[start:], re.S)
    return block.group(1)


@needs_handbook
@pytest.mark.parametrize(("name", "after"), [
    ("ornament_2", "encodes the second diagram from Plate XXIX"),
    ("corinthian", "the Corinthian impost also uses the `:flare` element"),
])
def test_handbook_lists_are_as_printed(name, after):
    printed, _ = parse(_printed_list(after))
    ours, _ = parse((ROOT / "profiles" / f"{name}.pwc").read_text())
    assert ours == printed


def test_listing_examples_reproduce_the_handbook_arrays():
    seg = pwc.load(ROOT / "profiles" / "segments.pwc")
    assert seg.length == pytest.approx(2.00056, abs=5e-6)
    arc = pwc.load(ROOT / "profiles" / "right_angle_arc.pwc")
    assert arc.length == pytest.approx(2.23678, abs=5e-6)
    np.testing.assert_allclose(arc.center[3], [0.18292683, 0.26829268], atol=5e-9)


def test_tee_is_listing_14_22():
    tee = pwc.load(ROOT / "profiles" / "tee.pwc", normalize=False)
    np.testing.assert_array_equal(tee.pt, [
        [0, 0], [.375, 0], [.375, .25], [.125, .25], [.125, .5], [.875, .5], [.875, .25],
        [.625, .25], [.625, 0], [1, 0]])


def test_doric_flutes_twenty_square_construction_arcs():
    c = pwc.load(ROOT / "profiles" / "doric_flutes.pwc")
    assert c.is_closed and c.n == 21 and np.all(c.type[1:] == pwc.PwType.SAGITTA)
    edges = np.linalg.norm(c.pt, axis=1)
    np.testing.assert_allclose(edges, edges[0], rtol=1e-9)  # flute edges on one circle
    chord = np.linalg.norm(np.diff(c.pt, axis=0), axis=1)
    np.testing.assert_allclose(chord, 2 * edges[0] * math.sin(math.pi / 20), rtol=1e-9)
    # the arc's centre is the centre of the square on the chord: radius chord/sqrt(2)
    np.testing.assert_allclose(c.radius[1:], chord / math.sqrt(2), rtol=1e-8)
    np.testing.assert_allclose(np.abs(c.end_angle[1:] - c.start_angle[1:]), math.pi / 2,
                               rtol=1e-8)
    # flutes are cut into the column: arc midpoints lie inside the edge circle
    mid = c.evaluate(0.5 * (c.t[1:] + c.t[:-1]))
    assert np.all(np.linalg.norm(mid, axis=1) < edges[0])


def test_ionic_flutes_semicircles_and_one_third_fillets():
    c = pwc.load(ROOT / "profiles" / "ionic_flutes.pwc")
    assert c.is_closed and c.n == 49
    arcs, fillets = np.arange(1, 49, 2), np.arange(2, 49, 2)
    assert np.all(c.is_arc[arcs]) and not np.any(c.is_arc[fillets])
    np.testing.assert_allclose(np.abs(c.end_angle[arcs] - c.start_angle[arcs]), math.pi,
                               rtol=1e-9)
    chord = np.linalg.norm(np.diff(c.pt, axis=0), axis=1)
    np.testing.assert_allclose(chord[fillets - 1], chord[arcs - 1] / 3, rtol=1e-9)
    mid = c.evaluate(0.5 * (c.t[arcs] + c.t[arcs - 1]))
    assert np.all(np.linalg.norm(mid, axis=1) < np.linalg.norm(c.pt[0]))


def test_at_least_twelve_classical_moldings_with_descriptions():
    names = {p.stem for p in PROFILES}
    classical = {"torus", "scotia", "ovolo", "cavetto", "astragal", "bead", "fillet",
                 "cyma_recta_molding", "cyma_reversa_molding", "bolection", "crown_molding",
                 "baseboard"}
    assert classical <= names
    for name in classical:
        assert description(ROOT / "profiles" / f"{name}.pwc")


def test_catalogue_is_current():
    page = (ROOT / "profiles" / "README.md").read_text()
    assert page == catalogue_markdown(PROFILES), "run: pwc catalogue profiles/"
    for p in PROFILES:
        assert (ROOT / "profiles" / "drawings" / f"{p.stem}.svg").exists()
