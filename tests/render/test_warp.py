"""Warps: inverse round trips, densities that integrate to 1, chi-square against the pdfs."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from scipy import stats

from render import warp
from render.bsdf import BsdfSample, Lobe
from render.testing import chi2_test, sphere_integral

ONE = np.nextafter(1.0, 0.0)
EDGE_U = np.array(
    [
        [0, 0],
        [0, ONE],
        [ONE, 0],
        [ONE, ONE],
        [0.5, 0.5],
        [0.5, 0],
        [0, 0.5],
        [0.25, 0.75],
        [1e-300, 0.5],
        [0.5, 1e-17],
    ],
    dtype=float,
)


class WarpAsBsdf:
    """A direction warp seen as a BSDF (``wo`` ignored) for ``chi2_test``."""

    lobes = Lobe.DIFFUSE_REFLECTION

    def __init__(self, fwd, pdf):
        self.fwd, self._pdf = fwd, pdf

    def sample(self, wo, u1, u2):
        w = self.fwd(u2)
        p = self._pdf(w)
        return BsdfSample(w, p, np.ones((len(w), 3)), np.where(p > 0, 1, 0).astype(np.int32))

    def pdf(self, wo, wi):
        return self._pdf(wi)


CONE = 0.3
DIRECTION_WARPS = {
    "cosine_hemisphere": (
        warp.square_to_cosine_hemisphere,
        warp.square_to_cosine_hemisphere_pdf,
        warp.cosine_hemisphere_to_square,
    ),
    "uniform_hemisphere": (
        warp.square_to_uniform_hemisphere,
        warp.square_to_uniform_hemisphere_pdf,
        warp.uniform_hemisphere_to_square,
    ),
    "uniform_sphere": (
        warp.square_to_uniform_sphere,
        warp.square_to_uniform_sphere_pdf,
        warp.uniform_sphere_to_square,
    ),
    "uniform_cone": (
        lambda u: warp.square_to_uniform_cone(u, CONE),
        lambda w: warp.square_to_uniform_cone_pdf(w, CONE),
        lambda w: warp.uniform_cone_to_square(w, CONE),
    ),
}


@pytest.mark.parametrize("name", DIRECTION_WARPS)
def test_round_trip_and_unit_length(name, rng):
    fwd, pdf, inv = DIRECTION_WARPS[name]
    u = np.concatenate([rng.random((20_000, 2)), EDGE_U])
    w = fwd(u)
    assert np.allclose(np.linalg.norm(w, axis=1), 1.0, atol=1e-14)
    back = inv(w)
    # the azimuth of a pole is arbitrary: compare u1 only where the point is off the pole
    off_pole = np.hypot(w[:, 0], w[:, 1]) > 1e-7
    if name == "cosine_hemisphere":
        assert np.allclose(back, u, atol=1e-9)
    else:
        assert np.allclose(back[:, 0], u[:, 0], atol=1e-12)
        d = np.abs(back[off_pole, 1] - u[off_pole, 1])
        assert np.all(np.minimum(d, 1 - d) < 1e-9)
    # positive density everywhere except exactly on the horizon of the cosine warp
    assert np.all((pdf(w) > 0) | ((name == "cosine_hemisphere") & (w[:, 2] == 0)))


@pytest.mark.parametrize("name", DIRECTION_WARPS)
def test_pdf_integrates_to_one(name):
    _, pdf, _ = DIRECTION_WARPS[name]
    breaks = (np.arccos(CONE),) if name == "uniform_cone" else ()
    total = sum(sphere_integral(pdf, [0.0, 0.0, s], s, breaks=breaks) for s in (1, -1))
    assert total == pytest.approx(1.0, abs=1e-9)


@pytest.mark.parametrize("name", DIRECTION_WARPS)
def test_chi2(name):
    fwd, pdf, _ = DIRECTION_WARPS[name]
    res = chi2_test(WarpAsBsdf(fwd, pdf), [0.0, 0.0, 1.0], test_count=len(DIRECTION_WARPS))
    assert res.passed, str(res)


def test_concentric_disk_is_uniform(rng):
    p = warp.square_to_uniform_disk_concentric(rng.random((100_000, 2)))
    r2 = p[:, 0] ** 2 + p[:, 1] ** 2
    phi = np.arctan2(p[:, 1], p[:, 0])
    assert np.all(r2 <= 1.0 + 1e-15)
    # area-preserving: r^2 and phi are uniform (Kolmogorov–Smirnov)
    assert stats.kstest(r2, "uniform").pvalue > 1e-3
    assert stats.kstest(phi, stats.uniform(-np.pi, 2 * np.pi).cdf).pvalue > 1e-3
    assert np.all(warp.square_to_uniform_disk_concentric_pdf(p) == 1 / np.pi)


def test_concentric_disk_edges_by_hand():
    u = np.array([[0.5, 0.5], [1.0, 0.5], [0.0, 0.5], [0.5, 1.0], [0.5, 0.0], [1.0, 1.0]])
    p = warp.square_to_uniform_disk_concentric(u)
    s = np.sqrt(0.5)
    assert np.allclose(p, [[0, 0], [1, 0], [-1, 0], [0, 1], [0, -1], [s, s]], atol=1e-15)
    assert np.allclose(warp.uniform_disk_concentric_to_square(p), u, atol=1e-15)


def test_degenerate_cone_and_bad_shapes():
    w = warp.square_to_uniform_cone(np.array([[0.3, 0.7]]), 1.0)
    assert np.allclose(w, [[0.0, 0.0, 1.0]])
    assert warp.square_to_uniform_cone_pdf(w, 1.0)[0] == 0.0
    assert np.all(np.isfinite(warp.uniform_cone_to_square(w, 1.0)))
    with pytest.raises(ValueError, match=r"u must have shape \(n, 2\)"):
        warp.square_to_cosine_hemisphere(np.zeros(2))
    with pytest.raises(ValueError, match=r"w must have shape \(n, 3\)"):
        warp.square_to_uniform_sphere_pdf(np.zeros((2, 2)))


@settings(max_examples=200)
@given(st.floats(0.0, ONE), st.floats(0.0, ONE))
def test_concentric_round_trip_property(a, b):
    u = np.array([[a, b]])
    p = warp.square_to_uniform_disk_concentric(u)
    assert p[0, 0] ** 2 + p[0, 1] ** 2 <= 1.0 + 1e-15
    assert np.allclose(warp.uniform_disk_concentric_to_square(p), u, atol=1e-9)
