"""Safe maths and unitize over lane arrays at the extremes, the tolerances, strict mode.

Fresnel, refraction and reflection are the kernels' own (``render/df/_kernel_common.py``),
tested in ``tests/render/df/test_kernel_common.py``."""

from __future__ import annotations

import numpy as np

from render.numerics import TOL, luminance, safe_div, safe_sqrt, unitize


def test_safe_functions_at_their_edges():
    assert safe_sqrt(np.array([-1e-300, -1.0, 0.0, 4.0])).tolist() == [0.0, 0.0, 0.0, 2.0]
    assert safe_div(np.array([1.0, 0.0]), np.array([0.0, 0.0]), default=7.0).tolist() == [7.0, 7.0]
    assert luminance(np.array([[1.0, 0.0, 0.0], [0.0, 1.0, 0.0]])).tolist() == [0.212671, 0.71516]


def test_unitize_tiny_huge_and_zero():
    v = np.array([[3e-200, 0, 4e-200], [3e200, 0, 4e200], [0.0, 0.0, 0.0], [1e-320, 0, 0]])
    u, ok = unitize(v)
    # below TOL.unit_min (1e-300, i.e. subnormal) a vector has no usable direction
    assert ok.tolist() == [True, True, False, False]
    assert np.allclose(u[:2], [[0.6, 0, 0.8]] * 2) and u[2].tolist() == [0, 0, 0] == u[3].tolist()
    assert np.all(np.isfinite(u))


def test_the_suite_runs_strict():
    # tests/render/conftest.py: floating-point errors raise and internal checks are on
    from render.numerics import is_strict

    assert is_strict() and np.geterr()["divide"] == "raise" and np.geterr()["invalid"] == "raise"


def test_tolerances_are_documented_values():
    assert TOL.roughness_min == 1e-7 and TOL.ior_delta_min == 1e-4 and TOL.cos_zero == 1e-10
