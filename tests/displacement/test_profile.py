"""Chapter 14.4-14.5: segmented profiles, the tee (Listings 14.22-14.30)."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from hypothesis.extra.numpy import arrays

from displacement.fields import FIELDS
from displacement.profile import (
    TEE,
    displace_with_profile,
    normalized_lengths,
    point_along_profile,
    profile_lengths,
    scale_component,
    tee_displacement,
)
from displacement.surfaces import Cylinder, UnitSquare, UVSphere

SQUARE = UnitSquare()
TEE_LENGTHS = [0.0, 0.375, 0.625, 0.875, 1.125, 1.875, 2.125, 2.375, 2.625, 3.0]
TEE_T = np.array(TEE_LENGTHS) / 3.0


def row(values, index=0, other=0.5):
    values = np.asarray(values, dtype=np.float64)
    uv = np.stack([values, np.full_like(values, other)], 1)
    return SQUARE.state_at_uv(uv if index == 0 else uv[:, ::-1])


def point_on_polyline(p, polyline, atol=1e-12):
    """Whether each 2D point of p lies on the polyline."""
    a, b = polyline[:-1], polyline[1:]
    keep = np.any(a != b, axis=1)                       # joined copies repeat a point
    a, b = a[keep], b[keep]
    ab = b - a
    along = np.einsum("nkj,kj->nk", p[:, None, :] - a, ab)
    t = np.clip(along / np.einsum("kj,kj->k", ab, ab), 0, 1)
    closest = a + t[..., None] * ab
    return np.min(np.linalg.norm(p[:, None, :] - closest, axis=-1), axis=1) <= atol


def test_tee_is_listing_14_22():
    assert TEE.shape == (10, 2) and not TEE.flags.writeable
    assert TEE[4].tolist() == [0.125, 0.5] and TEE[-1].tolist() == [1.0, 0.0]


def test_lengths_hand_values():
    np.testing.assert_allclose(profile_lengths(TEE), TEE_LENGTHS)
    np.testing.assert_allclose(normalized_lengths(profile_lengths(TEE)), TEE_T)
    np.testing.assert_allclose(profile_lengths([[0, 0], [3, 4], [3, 4.5]]), [0, 5, 5.5])
    with pytest.raises(ValueError, match="total length"):
        normalized_lengths([0.0, 0.0])
    with pytest.raises(ValueError, match="N >= 2"):
        profile_lengths([[0.0, 0.0]])


def test_point_along_profile_hits_every_point_at_its_knot():
    np.testing.assert_allclose(point_along_profile(TEE_T[:-1], TEE, TEE_T), TEE[:-1], atol=1e-15)
    # frac(1) = 0: distance 1 is the start again (as in MDL)
    np.testing.assert_allclose(point_along_profile(np.array([1.0]), TEE, TEE_T), [[0.0, 0.0]])


def test_tee_hand_values_on_the_unit_square():
    # u = 0.25: t[2] = 0.2083 <= 0.25 <= t[3] = 0.2917, halfway from (.375,.25) to (.125,.25):
    # the profile point is (0.25, 0.25), the displacement (0.25 - 0.25) x + 0.25 z.
    # u = 0.1: 0.8 of the first segment: (0.3, 0); the point moves 0.2 along +x.
    # u = 0.5: halfway along the top: (0.5, 0.5).
    s = row([0.25, 0.1, 0.5, 0.0])
    d = tee_displacement()(s)
    np.testing.assert_allclose(d, [[0, 0, 0.25], [0.2, 0, 0], [0, 0, 0.5], [0, 0, 0]], atol=1e-15)
    np.testing.assert_allclose((s.position + d)[0], [0.25, 0.5, 0.25], atol=1e-15)


def test_displaced_points_lie_on_the_tee():
    u = np.random.default_rng(12).uniform(0, 1, 500)
    s = row(u)
    p = s.position + tee_displacement()(s)
    np.testing.assert_allclose(p[:, 1], 0.5)
    assert np.all(point_on_polyline(p[:, [0, 2]], TEE))
    # linear texture space: the distance along the profile is 3 u (total length 3)
    order = np.argsort(u)
    steps = np.linalg.norm(np.diff(p[order][:, [0, 2]], axis=0), axis=1)
    assert np.all(steps <= 3 * np.diff(u[order]) + 1e-12)


def test_along_v_uses_tangent_v():
    s = row([0.25], index=1, other=0.7)                        # uv = (0.7, 0.25)
    np.testing.assert_allclose(tee_displacement(uv_index=1)(s), [[0, 0, 0.25]], atol=1e-15)
    s = row([0.1], index=1, other=0.7)
    np.testing.assert_allclose(displace_with_profile(TEE, uv_index="along_v")(s), [[0, 0.2, 0]],
                               atol=1e-15)
    field = tee_displacement(1)
    assert field.uv_knots[0] is None
    np.testing.assert_allclose(field.uv_knots[1], TEE_T)


def test_uv_outside_and_negative_wrap():
    field = tee_displacement()
    base = field(row([0.25]))
    for u in (1.25, -0.75, 7.25, -100.75):
        np.testing.assert_allclose(field(row([u])), base, atol=1e-12)
    np.testing.assert_allclose(field(row([1.0])), field(row([0.0])))


def test_repeat_three_and_its_offset():
    f = np.linspace(0, 1, 31)[:-1]
    once = point_along_profile(f, TEE, TEE_T)
    for k in range(3):
        thrice = point_along_profile((f + k) / 3, TEE, TEE_T, 3.0)
        np.testing.assert_allclose(thrice, once / 3 + [k / 3, 0.0], atol=1e-14)
    knots = tee_displacement(repeat=3).uv_knots[0]
    copies = np.concatenate([(TEE_T + k) / 3 for k in range(3)])
    np.testing.assert_allclose(knots, np.unique(copies))
    # on the surface: three tees of a third the size, side by side
    u = np.random.default_rng(13).uniform(0, 1, 300)
    s = row(u)
    p = s.position + tee_displacement(repeat=3)(s)
    copies = np.concatenate([TEE / 3 + [k / 3, 0] for k in range(3)])
    assert np.all(point_on_polyline(p[:, [0, 2]], copies))


def test_repeat_one_is_the_default_and_thousand_is_finite():
    s = row(np.linspace(-1, 2, 61))
    np.testing.assert_array_equal(tee_displacement(repeat=1)(s), tee_displacement()(s))
    field = tee_displacement(repeat=1000)
    u = np.linspace(0, 1, 100003)
    d = field(row(u))
    assert np.all(np.isfinite(d))
    assert np.max(np.abs(d)) <= 0.5 / 1000 + 1e-12
    assert len(field.uv_knots[0]) == 9 * 1000 + 1
    np.testing.assert_allclose(field(row([0.0123])), field(row([0.0123 + 0.017])), atol=1e-12)


def test_zero_length_segment_raises_at_factory_time():
    with pytest.raises(ValueError, match="segment 2 -> 3 has zero length"):
        displace_with_profile([[0, 0], [0.2, 0], [0.2, 0.3], [0.2, 0.3], [1, 0]])
    with pytest.raises(ValueError, match="zero length"):
        point_along_profile(np.array([0.5]), [[0, 0], [1, 0], [1, 0]], [0.0, 1.0, 1.0])
    with pytest.raises(ValueError, match="total length"):
        displace_with_profile([[0.5, 0.5], [0.5, 0.5]])


@pytest.mark.parametrize("kwargs,match", [
    ({"repeat": 0.0}, "repeat"), ({"repeat": -2.0}, "repeat"), ({"repeat": np.nan}, "repeat"),
    ({"uv_index": 2}, "along_u"), ({"uv_index": "along_w"}, "along_u"),
    ({"t": [0.0, 1.0]}, "shape"),
])
def test_bad_arguments(kwargs, match):
    with pytest.raises(ValueError, match=match):
        displace_with_profile(TEE, **kwargs)


def test_single_segment_profile():
    field = displace_with_profile([[0.0, 0.0], [1.0, 0.5]])
    s = row([0.0, 0.5, 0.999])
    np.testing.assert_allclose(field(s), [[0, 0, 0], [0, 0, 0.25], [0, 0, 0.4995]], atol=1e-15)
    np.testing.assert_array_equal(field.uv_knots[0], [0.0, 1.0])


def test_explicit_t_is_used():
    # a non-arc-length parametrisation: first half of the run covers the first point pair
    field = displace_with_profile([[0, 0], [0.1, 0], [1, 0]], t=[0.0, 0.5, 1.0])
    np.testing.assert_allclose(field(row([0.25]))[:, 0], 0.05 - 0.25)


def test_scale_component_and_registry():
    np.testing.assert_allclose(scale_component((4.0, 4.0), profile_lengths(TEE), 0), [12.0, 4.0])
    np.testing.assert_allclose(scale_component(24.0, profile_lengths(TEE), "along_v"), [24.0, 72.0])
    assert FIELDS["tee_displacement"] is tee_displacement
    assert FIELDS["displace_with_profile"] is displace_with_profile


@settings(max_examples=50)
@given(
    arrays(np.float64, st.integers(2, 8).map(lambda n: (n, 2)), elements=st.floats(-10, 10)),
    st.floats(0.001, 1000.0),
    arrays(np.float64, (10, 2), elements=st.floats(-1e6, 1e6)),
)
def test_property_finite(profile, repeat, uv):
    try:
        field = displace_with_profile(profile, repeat=repeat, uv_index=0)
    except ValueError as error:
        assert "zero length" in str(error) or "total length" in str(error)
        return
    for surface in (SQUARE, UVSphere(), Cylinder()):
        d = field(surface.state_at_uv(uv))
        assert np.all(np.isfinite(d))
    knots = field.uv_knots[0]
    assert np.all(np.diff(knots) > 0) and knots[0] >= 0 and knots[-1] <= 1
