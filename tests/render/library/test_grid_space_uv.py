"""Grid lines (Listings 14.3-14.5), coordinate spaces (9.12-9.18), uv tiles (13.1-13.3)."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from displacement.state import ShadingState
from displacement.surfaces import UnitSquare
from render.library import (
    fractional_uv,
    grid_color,
    in_grid_line,
    near_grid_value,
    position,
    position_to_color,
    scaled_uv_circle_color,
    scaled_uv_color,
    texture_coordinate,
    u,
    v,
    world_normal,
    world_position,
)


def square(uv) -> ShadingState:
    return UnitSquare().state_at_uv(np.asarray(uv, dtype=np.float64).reshape(-1, 2))


def in_world(state, matrix):
    """``state`` with its ``object_to_world`` set (as the integrator sets it)."""
    return dataclasses.replace(state, object_to_world=matrix)


# --- grid --------------------------------------------------------------------------


def test_near_grid_value_line_edges_by_hand():
    # 4 cells, default thickness 0.05 / 4 = 0.0125 either side of 0, 0.25, 0.5, 0.75, 1
    thick = 0.0125
    f = np.array([0.0, thick, 0.25 - thick, 0.25 + thick, 0.5, 0.75, 1.0, 1.0 - thick,
                  0.125, 0.25 + 0.013, 0.25 - 0.013, 0.6])
    expected = [True] * 8 + [False] * 4
    assert near_grid_value(f, 4.0, 0.0).tolist() == expected


def test_near_grid_value_explicit_thickness_and_edge():
    f = np.array([0.093, 0.106, 0.185, 0.15, 0.097])       # lines at 0.1, 0.2
    assert near_grid_value(f, 10.0, 0.01).tolist() == [True, True, False, False, True]
    assert near_grid_value(f, 10.0, 0.01, edge=0.5).tolist() == [False, False, False, False, True]
    assert near_grid_value(np.array([-0.26, -0.3]), 4.0, 0.0).tolist() == [True, False]
    with pytest.raises(ValueError, match="cell_count must not be 0"):
        near_grid_value(f, 0.0, 0.0)


def test_grid_color_line_positions():
    # lines at multiples of 1/4 in u or v; background elsewhere
    uv = [[0.25, 0.6], [0.6, 0.6], [0.6, 1.0], [0.0, 0.33], [0.5 + 0.012, 0.1], [0.5 + 0.014, 0.1]]
    c = grid_color(square(uv), (4.0, 4.0), (1.0, 0.0, 0.0), (0.0, 0.0, 0.7))
    assert c.tolist() == [[1.0, 0.0, 0.0], [0.0, 0.0, 0.7], [1.0, 0.0, 0.0], [1.0, 0.0, 0.0],
                          [1.0, 0.0, 0.0], [0.0, 0.0, 0.7]]


def test_grid_color_varying_arguments_and_other_texture_space():
    s = square([[0.6, 0.6], [0.25, 0.6]])
    c = grid_color(s, lambda st: np.tile([4.0, 4.0], (len(st), 1)),
                   line_color=lambda st: np.stack([st.uv[:, 0]] * 3, axis=1), bg_color=0.5)
    assert c.tolist() == [[0.5] * 3, [0.25] * 3]
    # texture space 1 does not exist: uv reads as 0, which is on a line (MDL's rule)
    assert np.all(in_grid_line(s, (4.0, 4.0), (0.0, 0.0), texture_space=1))


@settings(max_examples=100)
@given(st.floats(-1e6, 1e6), st.floats(0.5, 500.0))
def test_grid_lines_contain_every_multiple(k, count):
    f = np.array([np.floor(k) / count])
    assert near_grid_value(f, count, 0.0)[0]


# --- spaces --------------------------------------------------------------------------


def test_texture_coordinate_and_u_v():
    s = square([[0.25, 0.75], [-1.5, 2.0]])
    assert texture_coordinate(s).tolist() == [[0.25, 0.75, 0.0], [-1.5, 2.0, 0.0]]
    assert texture_coordinate(s, 3).tolist() == [[0.0] * 3] * 2
    assert u(s).tolist() == [0.25, -1.5] and v(s).tolist() == [0.75, 2.0]
    assert u(s, 1).tolist() == [0.0, 0.0]


def test_positions_in_three_spaces():
    s = square([[0.25, 0.75]])
    assert position(s, "uvw").tolist() == [[0.25, 0.75, 0.0]]
    assert position(s, "object").tolist() == [[0.25, 0.75, 0.0]]
    assert position(s, "functions::world").tolist() == [[0.25, 0.75, 0.0]]
    m = np.array([[2.0, 0.0, 0.0, 1.0], [0.0, 1.0, 0.0, 2.0], [0.0, 0.0, 1.0, 3.0], [0, 0, 0, 1.0]])
    w = in_world(s, m)
    assert world_position(w).tolist() == [[1.5, 2.75, 3.0]]
    assert position(w, "world").tolist() == [[1.5, 2.75, 3.0]]
    assert position(w, "object").tolist() == [[0.25, 0.75, 0.0]]
    # normals by the inverse transpose: the x component halves
    assert world_normal(w, np.array([[1.0, 0.0, 0.0]])).tolist() == [[0.5, 0.0, 0.0]]
    per_lane = in_world(s, m[None, :3, :3])
    assert world_position(per_lane).tolist() == [[0.5, 0.75, 0.0]]
    with pytest.raises(ValueError, match="singular"):
        world_normal(in_world(s, np.zeros((3, 3))), np.array([[1.0, 0.0, 0.0]]))
    with pytest.raises(ValueError, match="object_to_world must be"):
        world_position(in_world(s, np.eye(2)))


def test_position_to_color_wraps_negative_coordinates():
    s = square([[0.25, -0.75], [1.0, 0.0]])
    assert position_to_color(s, "uvw", 2.0).tolist() == [[0.5, 0.5, 0.0], [0.0, 0.0, 0.0]]
    assert position_to_color(s, "object", 0.5).tolist() == [[0.125, 0.625, 0.0], [0.5, 0.0, 0.0]]


# --- uv tiles ---------------------------------------------------------------------------


def test_scaled_uv_colors():
    s = square([[0.3, 0.55], [1.0, 1.0], [-0.1, -0.3]])
    assert np.allclose(scaled_uv_color(s, 2.0, 4.0), [[0.6, 0.2, 0.0], [0.0, 0.0, 0.0],
                                                      [0.8, 0.8, 0.0]])
    assert np.allclose(fractional_uv(s, 2.0, 4.0), scaled_uv_color(s, 2.0, 4.0)[:, :2])


def test_scaled_uv_circle_color_boundary_is_strict():
    # distance exactly 0.5 (tile edge midpoint) is outside in Listing 13.3
    s = square([[0.5, 0.5], [0.0, 0.5], [0.5, 0.999], [0.9, 0.5], [0.05, 0.05]])
    c = scaled_uv_circle_color(s, 1.0, 1.0, (0.1, 0.2, 0.3))
    assert np.allclose(c, [[0.5, 0.5, 0.0], [0.1, 0.2, 0.3], [0.5, 0.999, 0.0], [0.9, 0.5, 0.0],
                           [0.1, 0.2, 0.3]])
