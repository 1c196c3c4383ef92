"""Chapter 14.1-14.2: move_up / raise, triangle, circle_linear, circle_nonlinear."""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from hypothesis.extra.numpy import arrays

from displacement.fields import FIELDS
from displacement.surfaces import Cylinder, Plane, UnitSquare, UVSphere
from displacement.vector import (
    circle_linear,
    circle_linear_vector,
    circle_nonlinear,
    circle_nonlinear_vector,
    modify_normal,
    move_up,
    raise_,
    triangle,
    triangle_displacement,
    u,
    v,
)

SQUARE = UnitSquare()


def square_row(us, v_value=0.3):
    us = np.asarray(us, dtype=np.float64)
    return SQUARE.state_at_uv(np.stack([us, np.full_like(us, v_value)], 1))


def test_u_and_v():
    s = SQUARE.state_at_uv(np.array([[0.1, 0.9]]))
    assert u(s).tolist() == [0.1] and v(s).tolist() == [0.9]


def test_modify_normal_hand_value():
    # Listing 14.19: tangent * (target.x - f) + normal * target.y
    out = modify_normal(np.array([0.25, 1.0]), np.array([[0.5, 0.1], [0.0, -0.2]]),
                        np.array([[0.0, 1.0, 0.0]] * 2), np.array([[1.0, 0.0, 0.0]] * 2))
    np.testing.assert_allclose(out, [[0.1, 0.25, 0.0], [-0.2, -1.0, 0.0]])


def test_move_up_scales_the_normal():
    state = UVSphere(3.0).state_at_uv(np.random.default_rng(9).uniform(0, 1, (40, 2)))
    np.testing.assert_array_equal(move_up(0.2)(state), 0.2 * state.normal)
    # a varying scale: a function of state
    np.testing.assert_allclose(move_up(u)(state), state.uv[:, :1] * state.normal)
    # raise (Listing 14.9): default scale 0 is no displacement
    np.testing.assert_array_equal(raise_()(state), np.zeros((40, 3)))
    assert FIELDS["raise"] is raise_ and raise_(0.2).name == "raise"
    np.testing.assert_array_equal(FIELDS["raise"](scale=0.2)(state), move_up(0.2)(state))


def test_move_up_on_flat_plane_is_a_translation():
    plane = Plane((2.0, 3.0), origin=(1.0, 1.0, 1.0))
    state = plane.state_at_uv(np.random.default_rng(10).uniform(-1, 2, (30, 2)))
    np.testing.assert_array_equal(move_up(-0.4)(state), np.tile([0.0, 0.0, -0.4], (30, 1)))


def test_triangle_hand_values():
    # Listing 14.10 with height 0.25: fit(f, 0, 0.5, 0, h) then fit(f, 0.5, 1, h, 0)
    field = triangle_displacement(u, 0.25)
    d = field(square_row([0.0, 0.125, 0.5, 0.75, 1.0, -0.5, 1.5]))
    np.testing.assert_allclose(d[:, 2], [0.0, 0.0625, 0.25, 0.125, 0.0, -0.25, -0.25])
    np.testing.assert_array_equal(d[:, :2], 0.0)
    assert field.uv_knots[0].tolist() == [0.5] and field.uv_knots[1] is None
    # in v, with a constant f, and the material default height 0.5
    assert triangle_displacement(v, 1.0).uv_knots[1].tolist() == [0.5]
    np.testing.assert_allclose(triangle_displacement(0.25, 1.0)(square_row([0.9]))[:, 2], 0.5)
    assert triangle_displacement(lambda s: s.uv[:, 0], 1.0).uv_knots == (None, None)
    np.testing.assert_allclose(triangle()(square_row([0.5]))[:, 2], 0.5)


def test_triangle_texture_space_is_linear():
    # Figure 14.6: equal steps in u give equal steps along each side of the triangle
    us = np.linspace(0.0, 0.5, 11)
    s = square_row(us)
    p = s.position + triangle(0.25)(s)
    steps = np.linalg.norm(np.diff(p, axis=0), axis=1)
    np.testing.assert_allclose(steps, steps[0])


def test_circle_linear_hand_values():
    # Listing 14.12: x = fit(f, 0, 1, -0.5, 0.5), y = sqrt(r^2 - x^2) or 0
    field = circle_linear_vector(u, 0.25)
    d = field(square_row([0.5, 0.6, 0.75, 0.8, 0.0, 1.0, 0.25]))
    np.testing.assert_allclose(d[:, 2], [0.25, math.sqrt(0.0625 - 0.01), 0.0, 0.0, 0.0, 0.0, 0.0],
                               atol=1e-15)
    np.testing.assert_allclose(field.uv_knots[0], [0.25, 0.75])
    # the default radius 0.5 touches the base at u = 0 and u = 1
    np.testing.assert_allclose(circle_linear_vector(u).uv_knots[0], [0.0, 1.0])
    assert circle_linear_vector(u, 2.0).uv_knots == (None, None)      # knots outside [0, 1]
    np.testing.assert_array_equal(circle_linear(0.25)(square_row([0.6])), d[1:2])


def test_circle_linear_points_lie_on_the_circle():
    s = square_row(np.linspace(0.1, 0.9, 33))
    p = s.position + circle_linear(0.4)(s)
    np.testing.assert_allclose((p[:, 0] - 0.5) ** 2 + p[:, 2] ** 2, 0.16, atol=1e-15)


def test_circle_nonlinear_maps_u_to_equal_arcs():
    # Listing 14.14 with height 0.5: u lands on the circle of radius 0.5 about
    # (0.5, v, 0) at angle pi (1 - u); equal steps in u are equal arcs.
    us = np.linspace(0.0, 1.0, 21)
    s = square_row(us)
    p = s.position + circle_nonlinear(0.5)(s)
    angle = math.pi * (1 - us)
    np.testing.assert_allclose(p[:, 0], 0.5 + 0.5 * np.cos(angle), atol=1e-15)
    np.testing.assert_allclose(p[:, 2], 0.5 * np.sin(angle), atol=1e-15)
    np.testing.assert_allclose(p[:, 1], 0.3)
    steps = np.linalg.norm(np.diff(p, axis=0), axis=1)
    np.testing.assert_allclose(steps, steps[0], atol=1e-15)
    assert circle_nonlinear().uv_knots == (None, None)


def test_circle_nonlinear_height_scales_the_vector():
    s = square_row([0.3, 0.7])
    np.testing.assert_allclose(circle_nonlinear_vector(u, 2.0)(s), 4.0 * circle_nonlinear(0.5)(s))


def test_registry_names():
    for name in ("move_up", "raise", "triangle_displacement", "triangle", "circle_linear_vector",
                 "circle_linear", "circle_nonlinear_vector", "circle_nonlinear"):
        assert name in FIELDS


FIELDS_UNDER_TEST = [
    move_up(0.3), raise_(u), triangle(0.25), triangle_displacement(v, 2.0), circle_linear(0.25),
    circle_linear_vector(u, lambda s: 0.1 + 0.2 * s.uv[:, 1]), circle_nonlinear(0.5),
]


@settings(max_examples=50)
@given(arrays(np.float64, (10, 2), elements=st.floats(-1e6, 1e6)))
def test_property_finite_on_any_uv(uv):
    for surface in (SQUARE, UVSphere(), Cylinder()):
        state = surface.state_at_uv(uv)
        for field in FIELDS_UNDER_TEST:
            d = field(state)
            assert d.shape == (10, 3) and np.all(np.isfinite(d))


def test_varying_parameter_shape_error():
    with pytest.raises(ValueError, match="varying parameter"):
        move_up(lambda s: np.zeros(3))(square_row([0.1, 0.2]))
