"""Safe maths, unitize, dielectric Fresnel and refraction at the extremes."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from render.numerics import (
    TOL,
    fresnel_dielectric,
    luminance,
    reflect,
    refract,
    safe_acos,
    safe_div,
    safe_sqrt,
    saturate,
    unitize,
)


def test_safe_functions_at_their_edges():
    assert safe_sqrt(np.array([-1e-300, -1.0, 0.0, 4.0])).tolist() == [0.0, 0.0, 0.0, 2.0]
    assert safe_acos(np.array([1 + 1e-12, -1 - 1e-12])).tolist() == [0.0, np.pi]
    assert safe_div(np.array([1.0, 0.0]), np.array([0.0, 0.0]), default=7.0).tolist() == [7.0, 7.0]
    assert saturate(np.array([np.inf, -np.inf])).tolist() == [1.0, 0.0]
    assert luminance(np.array([[1.0, 0.0, 0.0], [0.0, 1.0, 0.0]])).tolist() == [0.212671, 0.71516]


def test_unitize_tiny_huge_and_zero():
    v = np.array([[3e-200, 0, 4e-200], [3e200, 0, 4e200], [0.0, 0.0, 0.0], [1e-320, 0, 0]])
    u, ok = unitize(v)
    # below TOL.unit_min (1e-300, i.e. subnormal) a vector has no usable direction
    assert ok.tolist() == [True, True, False, False]
    assert np.allclose(u[:2], [[0.6, 0, 0.8]] * 2) and u[2].tolist() == [0, 0, 0] == u[3].tolist()
    assert np.all(np.isfinite(u))


@pytest.mark.parametrize("eta", [1.0001, 1.5, 3.0])
def test_fresnel_normal_incidence(eta):
    F, ct = fresnel_dielectric(np.array([1.0, -1.0]), eta)
    assert F == pytest.approx(((eta - 1) / (eta + 1)) ** 2, rel=1e-12)
    assert ct.tolist() == [-1.0, 1.0]


def test_fresnel_index_matched_is_exactly_zero_even_at_grazing():
    c = np.array([1.0, 0.3, 1e-12, 0.0, -0.5, -0.0])
    F, ct = fresnel_dielectric(c, 1.0)
    assert np.all(F == 0.0)
    assert np.allclose(ct, [-1.0, -0.3, -1e-12, 0.0, 0.5, 0.0])


def test_fresnel_grazing_and_total_internal_reflection():
    F, ct = fresnel_dielectric(np.array([0.0, 1e-10]), 1.5)
    assert F[0] == 1.0 and F[1] == pytest.approx(1.0, abs=1e-9)
    # from inside glass (cos < 0): critical angle asin(1/1.5) = 41.81 degrees
    c_crit = np.cos(np.arcsin(1 / 1.5))
    F, ct = fresnel_dielectric(np.array([-(c_crit - 1e-9), -(c_crit + 1e-9), -0.01]), 1.5)
    assert F[0] == 1.0 and F[2] == 1.0 and ct[0] == 0.0
    assert F[1] < 1.0 and ct[1] > 0


def test_fresnel_value_by_hand():
    # cos 0.3, eta 1.5: cos_t = sqrt(1 - 0.91/2.25) = 0.771723;
    # rs = (0.3 - 1.5 cos_t)/(0.3 + 1.5 cos_t) = -0.588360,
    # rp = (0.45 - cos_t)/(0.45 + cos_t) = -0.263336
    F, ct = fresnel_dielectric(np.array([0.3]), 1.5)
    assert ct[0] == pytest.approx(-0.771723, abs=1e-6)
    assert F[0] == pytest.approx(0.5 * (0.588360**2 + 0.263336**2), abs=2e-6)


@settings(max_examples=300)
@given(st.floats(1e-4, 1.0), st.floats(0.2, 5.0))
def test_fresnel_is_symmetric_across_the_interface(c, eta):
    # Stokes: the reflectance seen from inside at the transmitted angle is the same.
    # (Below c ~ 1e-4 the round trip through cos_t is ill-conditioned: cos_i^2 is
    # recovered as 1 - (1 - cos_t^2) eta^2 with an absolute error ~1e-16 eta^2.)
    F1, ct = fresnel_dielectric(np.array([c]), eta)
    F2, ci = fresnel_dielectric(ct, eta)
    assert 0.0 <= F1[0] <= 1.0
    if F1[0] < 1.0:
        assert F2[0] == pytest.approx(F1[0], abs=1e-9)
        assert ci[0] == pytest.approx(c, abs=1e-8)


def test_refract_snell_and_tir():
    n = np.array([[0.0, 0.0, 1.0]] * 3)
    k = np.array([[np.sin(0.5), 0, np.cos(0.5)], [np.sin(1.2), 0, np.cos(1.2)], [0, 0, 1.0]])
    k2, tir = refract(k, n, np.array([1 / 1.5, 1.5, 1.0]))
    assert tir.tolist() == [False, True, False]
    assert np.sin(0.5) == pytest.approx(1.5 * np.hypot(*k2[0, :2]), rel=1e-14)
    assert k2[0, 2] < 0 and k2[0, 0] < 0
    assert np.allclose(k2[1], reflect(k[1:2], n[1:2])[0])
    assert np.allclose(k2[2], [0, 0, -1.0])
    assert np.allclose(np.linalg.norm(k2, axis=1), 1.0)


def test_the_suite_runs_strict():
    # tests/render/conftest.py: floating-point errors raise and internal checks are on
    from render.numerics import is_strict

    assert is_strict() and np.geterr()["divide"] == "raise" and np.geterr()["invalid"] == "raise"


def test_tolerances_are_documented_values():
    assert TOL.roughness_min == 1e-7 and TOL.ior_delta_min == 1e-4 and TOL.cos_zero == 1e-10
