"""The Field base, the FIELDS registry, and the small helpers of displacement.fields."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from repo import ROOT

import pwc
from displacement.fields import (
    FIELDS,
    Field,
    constant,
    displacement_direction,
    frac,
    repeat_knots,
    varying,
)
from displacement.surfaces import Cube, Plane, Torus, UnitSquare, UVSphere

PROFILES = Path(__file__).resolve().parents[2] / "profiles"


def test_frac_is_x_minus_floor():
    x = np.array([0.0, 0.25, 1.0, 1.75, -0.25, -1.0, -2.5, 1e300, -1e-300])
    np.testing.assert_array_equal(frac(x), [0.0, 0.25, 0.0, 0.75, 0.75, 0.0, 0.5, 0.0, 1.0])


def test_constant_field_is_a_translation():
    vector = (0.1, -0.2, 0.3)
    field = constant(vector)
    for surface in (UnitSquare(), UVSphere(), Torus()):
        state = surface.state_at_uv(np.random.default_rng(18).uniform(-2, 2, (25, 2)))
        moved = state.position + field(state)
        np.testing.assert_allclose(moved - state.position, np.tile(vector, (25, 1)), atol=1e-15)
    assert field.uv_knots == (None, None)
    with pytest.raises(ValueError, match="3 finite numbers"):
        constant((0.0, 1.0))
    np.testing.assert_array_equal(FIELDS["vector_displacement"]()(state), np.zeros((25, 3)))


def test_field_broadcasts_and_reports():
    field = Field(lambda s: np.array([0.0, 0.0, 1.0]), name="up", parameters={"a": 1})
    state = UnitSquare().state_at_uv(np.zeros((4, 2)))
    out = field(state)
    assert out.shape == (4, 3) and out.flags.writeable
    assert repr(field) == "Field(up(a=1))"


def test_varying():
    state = UnitSquare().state_at_uv(np.array([[0.1, 0.2], [0.3, 0.4]]))
    np.testing.assert_array_equal(varying(2.0, state), [2.0, 2.0])
    np.testing.assert_array_equal(varying([1.0, 3.0], state), [1.0, 3.0])
    np.testing.assert_array_equal(varying(lambda s: s.uv[:, 1], state), [0.2, 0.4])
    with pytest.raises(ValueError, match="varying"):
        varying([1.0, 2.0, 3.0], state)


def test_repeat_knots():
    t = np.array([0.0, 0.3, 1.0])
    np.testing.assert_array_equal(repeat_knots(t, 1.0), t)
    np.testing.assert_allclose(repeat_knots(t, 2.0), [0.0, 0.15, 0.5, 0.65, 1.0])
    np.testing.assert_allclose(repeat_knots(t, 0.5), [0.0, 0.6])  # half a copy
    assert len(repeat_knots(t, 1000.0)) == 2001
    with pytest.raises(ValueError, match="repeat"):
        repeat_knots(t, 0.0)


@settings(max_examples=50)
@given(st.lists(st.floats(0, 1), min_size=1, max_size=6), st.floats(0.01, 50))
def test_property_repeat_knots_are_where_frac_restarts_a_knot(t, repeat):
    t = np.unique(np.concatenate([[0.0], t, [1.0]]))
    knots = repeat_knots(t, repeat)
    assert np.all(np.diff(knots) > 0) and knots[0] == 0.0 and knots[-1] <= 1.0
    # every knot maps to a profile knot through frac(s * repeat) (or a wrap to 0)
    local = frac(knots * repeat)
    distance = np.min(np.abs(local[:, None] - t[None, :]), axis=1)
    assert np.all((distance < 1e-9) | (np.abs(local - 1) < 1e-9))


def test_displacement_direction():
    assert displacement_direction("along_u") == 0 and displacement_direction(1) == 1
    for bad in ("u", 2, True, 0.0, None):
        with pytest.raises(ValueError, match="along_u"):
            displacement_direction(bad)


SEGMENTS = pwc.load(PROFILES / "segments.pwc")
DORIC = pwc.load(PROFILES / "doric_flutes.pwc")
ARGUMENTS = {  # the Handbook parameters without defaults
    "move_up": (0.1,),
    "triangle_displacement": (lambda s: s.uv[:, 0], 0.2),
    "circle_linear_vector": (lambda s: s.uv[:, 1],),
    "circle_nonlinear_vector": (lambda s: s.uv[:, 0], 0.3),
    "displace_with_bubble": ((2.0, 0.0), None),
    "displace_with_profile": ([[0, 0], [0.5, 0.2], [1, 0]],),
    "displace_with_pwc": (SEGMENTS,),
    "pwc_angular_displace": (SEGMENTS,),
    "radial_pwc": (SEGMENTS,),
    "double_pwc": (SEGMENTS, DORIC),
    "diffuse_weave": (ROOT / "gallery" / "textures" / "weave_depth.png", (8.0, 4.0), 0.05),
    "weave": (ROOT / "gallery" / "textures" / "weave_depth.png", (8.0, 4.0), 0.05),
}


@pytest.mark.parametrize("name", sorted(FIELDS))
def test_every_registered_factory(name):
    from displacement.bubble import get_bubble_args

    args = ARGUMENTS.get(name, ())
    if name == "displace_with_bubble":
        args = (args[0], get_bubble_args(0.3, 0.1))
    field = FIELDS[name](*args)
    assert isinstance(field, Field)
    rng = np.random.default_rng(19)
    surfaces = (Plane(), UVSphere(), Torus())
    states = [s.state_at_uv(rng.uniform(-1.5, 2.5, (64, 2))) for s in surfaces]
    cube = Cube()
    states.append(cube.state_at(rng.integers(0, 12, 64), rng.dirichlet([1, 1, 1], 64)))
    for state in states:
        d = field(state)
        assert d.shape == (64, 3) and d.dtype == np.float64 and np.all(np.isfinite(d))
    assert len(field.uv_knots) == 2
    for knots in field.uv_knots:
        if knots is not None:
            assert knots.ndim == 1 and np.all(np.diff(knots) > 0)
            assert knots[0] >= 0.0 and knots[-1] <= 1.0
