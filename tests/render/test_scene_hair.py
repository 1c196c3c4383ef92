"""Hair strands in scene files (``[[objects]] curves = {...}``): what they build, and every
error located at the file, line and column of the strand or point at fault, with the fix."""

from __future__ import annotations

import numpy as np
import pytest

from render.hair import Strands
from render.scene import SceneError, load_scene, modelling_summary, parse_scene

HEAD = """[camera]
position = [0.0, 0.0, 4.0]
look_at = [0.0, 0.0, 0.0]

[render]
resolution = [16, 16]
spp = 1

[[lights]]
type = "environment"
radiance = [1.0, 1.0, 1.0]

"""
HAIR = 'material = "material(hair: df::chiang_hair_bsdf(roughness_R: float2(0.2, 0.3)))"\n'


def _scene(body: str):
    return parse_scene(HEAD + body, "hair.toml")


def _error(body: str) -> tuple[SceneError, str]:
    """The error of a scene and the text at its column."""
    with pytest.raises(SceneError) as info:
        _scene(body)
    e = info.value
    line = (HEAD + body).splitlines()[e.line - 1] if e.line else ""
    return e, line[e.column - 1:] if e.column else ""


def test_polylines_bezier_and_fringe_objects():
    sc = _scene(f"""[[objects]]
name = "tuft"
{HAIR}curves = {{ type = "polylines", radius = 0.01, points = [
    [[0, 0, 0], [0, 1, 0]],
    [[1, 0, 0], [1, 1, 0], [1.2, 2, 0]],
] }}

[[objects]]
name = "curl"
{HAIR}translate = [0.0, 1.0, 0.0]

[objects.curves]
type = "bezier"
radii = [[0.02, 0.015, 0.01, 0.005]]
points = [[[0, 0, 0], [0.5, 0.5, 0], [1, -0.5, 0], [1.5, 0, 0]]]

[[objects]]
name = "fringe"
{HAIR}curves = {{ type = "fringe", start = [-1.0, 0.0, 0.0], end = [1.0, 0.0, 0.0], count = 20 }}
""")
    kinds = [(o.name, o.surface.kind, o.surface.segment_count) for o in sc.objects]
    assert kinds == [("tuft", "linear", 3), ("curl", "bezier", 1), ("fringe", "bezier", 60)]
    assert all(isinstance(o.surface, Strands) for o in sc.objects)
    assert sc.objects[0].material.hair.name == "chiang_hair_bsdf"
    assert np.allclose(sc.objects[1].surface.points[:, 3], [0.02, 0.015, 0.01, 0.005])
    assert np.allclose(sc.objects[1].transform[:3, 3], [0, 1, 0])


@pytest.mark.parametrize(("body", "message", "at"), [
    # a repeated point of strand 2: at that point
    ("""curves = { type = "polylines", radius = 0.01, points = [
    [[0, 0, 0], [0, 1, 0]],
    [[1, 0, 0], [1, 1, 0], [1, 1, 0]],
] }
""", r"objects\[0\]: curves: strand 2, points 2 and 3: a zero-length segment \(the points "
     r"coincide\); remove one of them", "[1, 1, 0]]"),
    # a degenerate Bézier segment of the second strand, in a sub-table
    ("""
[objects.curves]
type = "bezier"
points = [
  [[0, 0, 0], [0, 1, 0], [0, 2, 0], [0, 3, 0]],
  [[1, 0, 0], [1, 0, 0], [1, 0, 0], [1, 0, 0]],
]
""", r"strand 2, points 1 to 4: a zero-length Bézier segment .* remove three of them",
     "[1, 0, 0], [1, 0, 0], [1, 0, 0], [1, 0, 0]],"),
    ("""curves = { type = "bezier", points = [[[0, 0, 0], [0, 1, 0], [0, 2, 0]]] }
""", r"strand 1: a cubic Bézier strand has 3 m \+ 1 control points .* got 3; add or remove",
     "[[0, 0, 0], [0, 1, 0], [0, 2, 0]]"),
    ("""curves = { type = "polylines", radii = [[0.1, 0.1], [0.1, -0.2]], points = [
  [[0, 0, 0], [0, 1, 0]], [[1, 0, 0], [1, 1, 0]]] }
""", r"strand 2, point 2: radius must be a finite number > 0, got -0.2", "-0.2]]"),
    ("""curves = { type = "polylines", radii = [[0.1, 0.1]], points = [[[0, 0, 0], [0, 1, 0]],
  [[1, 0, 0], [1, 1, 0]]] }
""", r"radii has 1 lists for 2 strands; give one list of radii \(one per point\) per strand",
     "radii"),
    ("""curves = { type = "polylines", points = [[[0, 0, 0], [0, 1]]] }
""", r"strand 1, point 2: must be three numbers \[x, y, z\], got \[0, 1\]", "[0, 1]]]"),
    ("""curves = { type = "polyline", points = [] }
""", r"type must be one of 'polylines', 'bezier', 'fringe', got 'polyline'", "type"),
    ("""curves = { type = "fringe", count = 10, lenght = 0.3 }
""", r"unknown key 'lenght' \(did you mean 'length'\?\)", "lenght"),
    ("""curves = { type = "fringe", count = 0 }
""", r"fringe: count must be a whole number from 1 to 100000, got 0", "count"),
    # in world space: the radius below float32's resolution where the object was moved
    ("""translate = [1000.0, 0.0, 0.0]
curves = { type = "polylines", radius = 1e-5, points = [[[0, 0, 0], [0, 1, 0]]] }
""", r"strand 1, point 1: radius 1e-05 \(in world space\) is below float32's resolution "
     r".* give a larger radius, or move the strand nearer the origin", "radius"),
    ("""dicing_rate = 2.0
curves = { type = "fringe" }
""", r"dicing_rate applies to surfaces, not to hair strands \(curves\); remove it",
     "dicing_rate"),
    ("""surface = "square"
curves = { type = "fringe" }
""", r"give exactly one of surface = NAME, mesh = PATH or curves", ""),
])
def test_strand_errors_name_file_line_and_fix(body, message, at):
    e, text = _error("[[objects]]\n" + (HAIR if "material" not in body else "") + body)
    assert str(e).startswith("hair.toml:") and e.line > 0
    assert e.path == "hair.toml"
    import re

    assert re.search(message, e.message), e.message
    assert text.startswith(at), (text, at)


def test_varying_hair_arguments_are_refused_in_the_file():
    e, text = _error("""[[objects]]
material = "material(hair: df::chiang_hair_bsdf(absorption_coefficient: color(state::normal())))"
curves = { type = "fringe", count = 2 }
""")
    assert "absorption_coefficient must be a constant" in e.message
    assert text.startswith("material")


def test_geometry_of_hair_and_summary(tmp_path):
    path = tmp_path / "hair.toml"
    path.write_text(HEAD + f"""[[objects]]
name = "floor"
surface = "square"
material = "diffuse(tint: color(0.5))"

[[objects]]
name = "fringe"
{HAIR}translate = [0.0, 2.0, 0.0]
curves = {{ type = "fringe", count = 7, segments = 2 }}
""")
    sc = load_scene(path)
    geo = sc.build()
    assert geo.curve_segment_count == 14 and geo.triangle_count == len(geo.faces) - 14
    assert geo.curve_first.tolist() == [-1, 0] and geo.curves.shape == (14, 16)
    # the fringe's points reach y = 2 + radius: in the bounds and the largest coordinate
    assert geo.coord_max >= 2.0 and geo.center[1] > 0.5
    rows = modelling_summary(sc, geo.stats)
    assert rows[1]["geometry"] == ("hair: 7 strands, 14 bezier curve segments (Embree round "
                                   "curves)")
    assert rows[1]["dfs"] == ["chiang_hair_bsdf"] and rows[1]["triangles"] == 0


def test_hair_only_scene_builds():
    sc = _scene(f"""[[objects]]
{HAIR}curves = {{ type = "polylines", radius = 0.05, points = [[[0, 0, 0], [1, 0, 0]]] }}
""")
    geo = sc.build()
    assert geo.triangle_count == 0 and geo.curve_segment_count == 1
    assert geo.extent == pytest.approx(np.linalg.norm([1.1, 0.1, 0.1]), rel=1e-6)
