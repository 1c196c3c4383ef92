"""The golden compiles checked against something other than the compiler that wrote them.

``test_profiles.py`` compares today's compile with the golden JSON; this module checks
the golden JSON itself, so a golden file rewritten from a broken compiler fails here:

* every row is re-derived from its own source ``text`` by the construction rules of
  spec/pwc-list.md §2 (sign conventions fixed by Listing 15.4), with a number reader and
  geometry written here, not imported from ``pwc``;
* the Handbook's printed arrays (Listings 15.3 and 15.4) are read from the golden files;
* the golden files are written only by an explicit command: importing the writer (as
  pytest's ``--doctest-modules`` collection would) writes nothing.
"""

from __future__ import annotations

import hashlib
import importlib.util
import json
import math
import re
from fractions import Fraction

import numpy as np
import pytest
from repo import PROFILES, ROOT

GOLDEN = ROOT / "tests" / "pwc" / "golden"
GOLDENS = sorted(GOLDEN.glob("*.json"))
_MIXED = re.compile(r"^(-?)(\d+)-(\d+)/(\d+)$")


def _number(token: str) -> tuple[float, bool]:
    """A pwc number and whether it carries the absolute prefix ``a`` (spec §1)."""
    absolute = token.startswith("a")
    token = token[1:] if absolute else token
    mixed = _MIXED.match(token)
    if mixed:
        sign = -1 if mixed.group(1) else 1
        value = sign * (int(mixed.group(2)) + Fraction(int(mixed.group(3)),
                                                       int(mixed.group(4))))
    else:
        value = Fraction(token)
    return float(value), absolute


def _left(v: np.ndarray) -> np.ndarray:
    return np.array([-v[1], v[0]])


def _cross(u: np.ndarray, v: np.ndarray) -> float:
    return float(u[0] * v[1] - u[1] * v[0])


def _arc_point(row: dict, phi: float) -> np.ndarray:
    return np.asarray(row["center"]) + row["radius"] * np.array([math.cos(phi), math.sin(phi)])


def _expected_points(gold: dict) -> np.ndarray:
    """Resolve each distinct source line's coordinates (relative sums, ``a`` prefixes)."""
    out, x, y, seen = [], 0.0, 0.0, set()
    for row in gold["points"]:
        if row["line"] in seen:  # a cyma's midpoint row shares its line with its end
            continue
        seen.add(row["line"])
        (vx, ax), (vy, ay) = map(_number, row["text"].split()[:2])
        x = vx if (ax or not gold["relative"]) else x + vx
        y = vy if (ay or not gold["relative"]) else y + vy
        out.append((x, y))
    return np.array(out)


def _check_piece(row: dict, a: np.ndarray, b: np.ndarray, prev_dir, scale: float) -> None:
    """One row against the spec's construction from A (previous point) to B (this one)."""
    words = row["text"].split()
    prop = words[2] if len(words) > 2 else None
    chord = b - a
    if row["type"] == "segment":
        assert row["radius"] == 0.0 and row["center"] == [0.0, 0.0]
        assert row["start_angle"] == 0.0 and row["end_angle"] == 0.0
        return
    # every arc runs from A to B around its centre
    np.testing.assert_allclose(_arc_point(row, row["start_angle"]), a, atol=1e-12)
    np.testing.assert_allclose(_arc_point(row, row["end_angle"]), b, atol=1e-12)
    assert -math.pi < row["start_angle"] <= math.pi
    sweep = row["end_angle"] - row["start_angle"]
    mid = _arc_point(row, 0.5 * (row["start_angle"] + row["end_angle"]))
    if prop == ":angle":
        theta = math.radians(_number(words[3])[0])
        assert sweep == pytest.approx(theta, rel=1e-12)
        assert row["radius"] == pytest.approx(
            np.linalg.norm(chord) / (2 * math.sin(abs(theta) / 2)), rel=1e-12)
    elif prop == ":sag":
        s = _number(words[3])[0] * scale
        # sagitta: chord midpoint to arc midpoint is |s|; positive s is counter-clockwise,
        # so the arc bulges to the right of A->B (its centre, for a minor arc, on the left)
        assert np.linalg.norm(mid - 0.5 * (a + b)) == pytest.approx(abs(s), rel=1e-12)
        assert math.copysign(1.0, sweep) == math.copysign(1.0, s)
        assert math.copysign(1.0, _cross(chord, mid - a)) == -math.copysign(1.0, s)
    elif prop in (":cyma_recta", ":cyma_reversa"):
        # each half sweeps 60 degrees on a circle of radius |AM|; the recta's first arc is
        # counter-clockwise (convex), the reversa's clockwise
        assert abs(sweep) == pytest.approx(math.pi / 3, rel=1e-12)
        assert row["radius"] == pytest.approx(np.linalg.norm(chord), rel=1e-12)
    elif prop == ":flare":
        # tangent at A to the direction in which the previous piece arrives there
        start_dir = np.sign(sweep) * _left(a - np.asarray(row["center"])) / row["radius"]
        np.testing.assert_allclose(start_dir, prev_dir, atol=1e-12)
    else:
        pytest.fail(f"row {row} is an arc but its text has no arc property")


def _end_direction(row: dict, a: np.ndarray, b: np.ndarray) -> np.ndarray:
    if row["type"] == "segment":
        return (b - a) / np.linalg.norm(b - a)
    sweep = row["end_angle"] - row["start_angle"]
    return np.sign(sweep) * _left(b - np.asarray(row["center"])) / row["radius"]


@pytest.mark.parametrize("path", GOLDENS, ids=lambda p: p.stem)
def test_golden_rows_follow_the_spec_constructions(path):
    gold = json.loads(path.read_text())
    rows = gold["points"]
    points = _expected_points(gold)
    scale = 1.0 / np.abs(points).max()
    assert gold["scale"] == pytest.approx(scale, rel=1e-15)
    # the curve's points are the source's points, normalized by the largest coordinate
    ends = [i for i, r in enumerate(rows) if i + 1 == len(rows) or rows[i + 1]["line"] != r["line"]]
    np.testing.assert_allclose([rows[i]["pt"] for i in ends], points * scale, atol=1e-14)
    # each piece is the spec's construction; its length is the chord or r * |sweep|
    lengths, prev_dir = [], None
    for i in range(1, len(rows)):
        row, a, b = rows[i], np.asarray(rows[i - 1]["pt"]), np.asarray(rows[i]["pt"])
        first_half = i + 1 < len(rows) and rows[i + 1]["line"] == row["line"]
        if row["type"].startswith("cyma") and first_half:
            # a cyma's midpoint M is the midpoint of AB, B being the next row's point
            np.testing.assert_allclose(b, 0.5 * (a + np.asarray(rows[i + 1]["pt"])),
                                       atol=1e-14)
            clockwise = row["type"] == "cyma_reversa"
            assert (row["end_angle"] < row["start_angle"]) == clockwise
        elif row["type"].startswith("cyma"):
            # second half turns the other way and joins the first smoothly at M
            first = rows[i - 1]
            assert np.sign(row["end_angle"] - row["start_angle"]) == \
                -np.sign(first["end_angle"] - first["start_angle"])
            np.testing.assert_allclose(
                np.sign(row["end_angle"] - row["start_angle"])
                * _left(a - np.asarray(row["center"])) / row["radius"],
                prev_dir, atol=1e-12)
        _check_piece(row, a, b, prev_dir, scale)
        lengths.append(np.linalg.norm(b - a) if row["type"] == "segment" else
                       row["radius"] * abs(row["end_angle"] - row["start_angle"]))
        prev_dir = _end_direction(row, a, b)
    total = math.fsum(lengths)
    assert gold["length"] == pytest.approx(total, rel=1e-12)
    np.testing.assert_allclose([r["t"] for r in rows],
                               np.concatenate([[0.0], np.cumsum(lengths) / total]), atol=1e-12)


def test_every_profile_has_a_golden_and_every_golden_a_profile():
    assert [p.stem for p in PROFILES] == [g.stem for g in GOLDENS]


def test_goldens_reproduce_the_handbook_printed_arrays():
    """Listing 15.3's t values and Listing 15.4's first arc, as printed (spec §2)."""
    seg = json.loads((GOLDEN / "segments.json").read_text())
    assert seg["length"] == pytest.approx(2.00056, abs=5e-6)
    np.testing.assert_allclose([p["t"] for p in seg["points"]],
                               [0, 0.26243, 0.41238, 0.51414, 0.86404, 1.0], atol=5e-6)
    arc = json.loads((GOLDEN / "right_angle_arc.json").read_text())
    assert arc["length"] == pytest.approx(2.23678, abs=5e-6)
    first = next(p for p in arc["points"] if p["radius"] > 0)
    np.testing.assert_allclose(first["center"], [0.18292683, 0.26829268], atol=5e-9)
    assert first["radius"] == pytest.approx(0.06098, abs=5e-6)
    assert [first["start_angle"], first["end_angle"]] == pytest.approx([math.pi, math.pi / 2])


def test_importing_the_golden_writer_writes_nothing():
    """Only ``python tests/pwc/golden/regenerate.py`` writes goldens; an import (pytest's
    doctest collection, an IDE) must leave every file as it is."""
    before = {p: hashlib.sha256(p.read_bytes()).hexdigest() for p in GOLDENS}
    mtimes = {p: p.stat().st_mtime_ns for p in GOLDENS}
    spec = importlib.util.spec_from_file_location("_regenerate", GOLDEN / "regenerate.py")
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    assert callable(module.main)
    assert {p: p.stat().st_mtime_ns for p in GOLDENS} == mtimes
    assert {p: hashlib.sha256(p.read_bytes()).hexdigest() for p in GOLDENS} == before
