"""Writers: MDL parsed back and compared with JSON, JSON/NPZ round trips, drawings."""

from __future__ import annotations

import json
import math
import re

import numpy as np
import pytest
from repo import PROFILES

import pwc
from mdl.entities import TypeEntity
from mdl.loader import Loader, ModuleText
from pwc.draw import to_png, to_svg
from pwc.emit import (
    from_json,
    from_npz,
    mdl_float,
    mdl_identifier,
    runtime_mdl,
    to_json,
    to_mdl,
    to_npz,
)


class _Runtime:
    """``::pw_curve`` as ``pwc compile`` writes it, for the MDL front end."""

    def find(self, qname):
        if qname == "::pw_curve":
            return ModuleText(qname, runtime_mdl(), "pw_curve.mdl", None, "generated")
        return None


def _check(text: str, name: str):
    """The emitted text, checked by the MDL front end (:mod:`mdl`)."""
    return Loader(providers=[_Runtime()]).load_text(text, name)


def _type(module, name):
    return next(e for e in module.scope[name] if isinstance(e, TypeEntity)).type


def test_runtime_module_is_valid_mdl_with_the_handbook_types():
    m = Loader(providers=[_Runtime()]).load("::pw_curve")
    assert _type(m, "pw_type").values == [(k.mdl_name, int(k)) for k in pwc.PwType]
    assert _type(m, "displacement_direction").values == [("along_u", 0), ("along_v", 1)]
    assert [f.name for f in _type(m, "pw_point").fields] == [
        "type", "t", "pt", "center", "radius", "start_angle", "end_angle"]
    for name in ("point_along_pwc", "displace_to_point", "displace_with_pwc",
                 "y_rotation_3", "displace_to_angular_point", "pwc_angular_displace",
                 "displace_to_pwc_point", "double_pwc_displacement", "point_along_pwc_repeat"):
        assert m.functions(name) and m.functions(name)[0].exported
    assert not m.diagnostics


@pytest.mark.parametrize("path", PROFILES, ids=lambda p: p.stem)
def test_emitted_mdl_parses_back_to_the_json_values(path):
    curve = pwc.load(path)
    doc = json.loads(to_json(curve))
    text = to_mdl(curve)
    m = _check(text, f"{curve.name}.mdl")
    assert {x.qname for x in m.imports.values()} == {"::pw_curve"} and not m.diagnostics
    assert m.constant(f"{curve.name}_length") == pytest.approx(doc["length"], rel=1e-8)
    arr = m.constant(curve.name)
    entity = m.scope[curve.name][0]
    assert str(entity.type) == f"pw_curve::pw_point[{len(doc['points'])}]" and entity.exported
    comments = re.findall(r"pw_curve::pw_point\( // (.*)", text)
    assert len(comments) == len(arr) == len(doc["points"])
    for point, p, comment in zip(arr, doc["points"], comments, strict=True):
        assert point["type"] == p["type"]
        assert point["t"] == pytest.approx(p["t"], rel=1e-8, abs=1e-12)
        np.testing.assert_allclose(point["pt"], p["pt"], rtol=1e-8, atol=1e-12)
        if p["type"] == "segment":
            assert point["center"] == (0.0, 0.0) and point["radius"] == 0.0
        else:
            np.testing.assert_allclose(point["center"], p["center"], rtol=1e-8, atol=1e-12)
            assert [point["radius"], point["start_angle"], point["end_angle"]] == pytest.approx(
                [p["radius"], p["start_angle"], p["end_angle"]], rel=1e-8, abs=1e-12)
        assert comment.rstrip().endswith(p["text"]) or "of 2)" in comment
        assert comment.startswith(f"line {p['line']}: ")


def test_relative_lists_carry_the_property_as_a_comment():
    text = to_mdl(pwc.compile_text(":relative\n0 0\n1 1\n", name="r"))
    assert "pw_curve::pw_point[2] r( // :relative\n" in text


def test_nine_significant_digits():
    assert mdl_float(1 / 3) == "0.333333333" and mdl_float(math.pi) == "3.14159265"
    assert mdl_float(-1e-20) == "-1.0e-20" and mdl_float(123456789012.0) == "1.23456789e+11"


@pytest.mark.parametrize(("stem", "ok"), [
    ("ornament_2", "ornament_2"), ("Cyma-Recta 2", "Cyma_Recta_2"), ("_x", None),
    ("2profile", None), ("let", None), ("material", None), ("", None),
])
def test_mdl_identifiers(stem, ok):
    if ok:
        assert mdl_identifier(stem) == ok
    else:
        with pytest.raises(ValueError, match="rename the file"):
            mdl_identifier(stem)


@pytest.mark.parametrize("path", PROFILES, ids=lambda p: p.stem)
def test_json_and_npz_round_trips_are_exact(path):
    c = pwc.load(path)
    for back in (from_json(to_json(c)), from_npz(to_npz(c))):
        for name in ("type", "t", "pt", "center", "radius", "start_angle", "end_angle", "line"):
            np.testing.assert_array_equal(getattr(back, name), getattr(c, name))
        assert (back.length, back.scale, back.relative, back.text) == (
            c.length, c.scale, c.relative, c.text)


def test_json_rejects_other_documents():
    with pytest.raises(ValueError, match="pwc-json/1"):
        from_json('{"format": "other"}')


def test_drawings_show_points_centres_and_sagittas():
    c = pwc.compile_text("0 0\n1 0\n1 1 :sag .2\n0 2 :angle 90\n0 3\n")
    svg = to_svg(c)
    assert svg.count("<circle") == c.n
    assert svg.count('stroke-dasharray') == 2  # dashed radii of the two arcs
    assert svg.count('stroke="#2ca02c"') == 1  # one sagitta mark
    png = to_png(c, 300)
    assert png.startswith(b"\x89PNG") and len(png) > 2000


def test_drawing_of_a_nearly_flat_huge_arc_stays_readable():
    c = pwc.compile_text("0 0\n1 0 :sag 1e-6\n", normalize=False)
    svg = to_svg(c)
    width = float(svg.split('width="')[1].split('"')[0])
    assert width == 640  # the far-away centre does not shrink the drawing to a dot
