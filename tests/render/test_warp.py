"""The kernels' warps of the unit square: inverse round trips, densities that integrate to
1, chi-square against the densities.

* the cosine hemisphere, and the Shirley–Chiu concentric disk in it:
  :func:`render.df._kernel_common.cosine_hemisphere`;
* the uniform sphere: a constant environment sampled by
  :func:`render.light_sampling.sample_light`, its density from
  :func:`render.light_sampling.escaped`;
* the uniform cone: the sun's cone of :func:`render.sky.sun_and_sky_sample` and
  :func:`render.sky.sun_and_sky_pdf`, with ``p_sun = 1`` and the sun at ``+z``.

The inverses below are the tests' own: each undoes a warp with ``atan2``, so a round trip
checks the warp rather than repeating it.
"""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from scipy import stats

from render import sky
from render.bsdf import BsdfSample, Lobe
from render.df import _kernel_common as kc
from render.lights import ConstantEnvironment
from render.path import escaped, sample_lights
from render.testing import chi2_test, light_tables, sphere_integral

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
_QUARTER_PI = np.pi / 4.0


# --- the inverses (the tests' own) ----------------------------------------------------------


def _phi01(w):
    """Azimuth of ``w`` mapped to [0, 1)."""
    phi = np.arctan2(w[:, 1], w[:, 0])
    v = np.where(phi < 0, phi + 2.0 * np.pi, phi) / (2.0 * np.pi)
    return np.where(v >= 1.0, 0.0, v)


def disk_to_square(p):
    """Inverse of the concentric map: the square's point of a point of the unit disk."""
    x, y = p[:, 0], p[:, 1]
    r = np.hypot(x, y)
    first = np.abs(x) >= np.abs(y)
    # region |a| > |b|: p = a (cos phi, sin phi), phi = (pi/4) b/a in (-pi/4, pi/4]
    a1 = np.where(x >= 0, r, -r)
    phi1 = np.arctan2(y * np.sign(a1), np.abs(x))
    b1 = a1 * phi1 / _QUARTER_PI
    # region |b| >= |a|: p = b (cos phi, sin phi), phi = pi/2 - (pi/4) a/b
    b2 = np.where(y >= 0, r, -r)
    phi2 = np.arctan2(y * np.sign(b2), x * np.sign(b2))
    a2 = b2 * (2 * _QUARTER_PI - phi2) / _QUARTER_PI
    a = np.where(r > 0, np.where(first, a1, a2), 0.0)
    b = np.where(r > 0, np.where(first, b1, b2), 0.0)
    return np.stack([(a + 1.0) * 0.5, (b + 1.0) * 0.5], axis=1)


# --- the warps, a lane at a time --------------------------------------------------------------


def cosine_hemisphere(u):
    return np.array([kc.cosine_hemisphere(a, b) for a, b in u]).reshape(-1, 3)


def cosine_hemisphere_pdf(w):
    return np.maximum(w[:, 2], 0.0) / np.pi


_ENV = []


def _env_tables():
    if not _ENV:
        _ENV.append(light_tables([ConstantEnvironment((1.0, 1.0, 1.0))]))
    return _ENV[0]


def uniform_sphere(u):
    u = np.column_stack([np.zeros(len(u)), u])  # u[:, 0] picks the (only) light
    return sample_lights(_env_tables(), np.zeros((len(u), 3)), u)[0]


def uniform_sphere_pdf(w):
    return escaped(_env_tables(), w)[0]


def _cone(cos_cutoff):
    """Sun-and-sky kernel parameters whose sampling is the cone ``z >= cos_cutoff`` alone
    (the layout :meth:`render.sky.SunAndSky.kernel_params` documents), and an empty table."""
    params = np.zeros(sky.PARAMS_SIZE)
    params[sky._SUN + 2] = 1.0  # the sun (the cone's axis) at +z, its frame the identity
    params[sky._FRAME_S] = 1.0
    params[sky._FRAME_T + 1] = 1.0
    params[sky._COS_ALPHA] = cos_cutoff
    params[sky._ONE_MINUS_COS] = 1.0 - cos_cutoff
    params[sky._P_SUN] = 1.0
    table = np.zeros(sky._TABLE_H * sky._TABLE_W)
    return params, table


def uniform_cone(u, cos_cutoff):
    params, table = _cone(cos_cutoff)
    return np.array([sky.sun_and_sky_sample(params, table, table, a, b) for a, b in u])


def uniform_cone_pdf(w, cos_cutoff):
    params, table = _cone(cos_cutoff)
    return np.array([sky.sun_and_sky_pdf(params, table, *row) for row in w])


def uniform_cone_to_square(w, cos_cutoff):
    one_minus_c = 1.0 - cos_cutoff
    u0 = (1.0 - w[:, 2]) / one_minus_c if one_minus_c > 0 else np.zeros(len(w))
    return np.stack([u0, _phi01(w)], axis=1)


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
        cosine_hemisphere,
        cosine_hemisphere_pdf,
        lambda w: disk_to_square(w[:, :2]),
    ),
    "uniform_sphere": (
        uniform_sphere,
        uniform_sphere_pdf,
        lambda w: np.stack([(1.0 - w[:, 2]) * 0.5, _phi01(w)], axis=1),
    ),
    "uniform_cone": (
        lambda u: uniform_cone(u, CONE),
        lambda w: uniform_cone_pdf(w, CONE),
        lambda w: uniform_cone_to_square(w, CONE),
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
    p = cosine_hemisphere(rng.random((100_000, 2)))[:, :2]
    r2 = p[:, 0] ** 2 + p[:, 1] ** 2
    phi = np.arctan2(p[:, 1], p[:, 0])
    assert np.all(r2 <= 1.0 + 1e-15)
    # area-preserving: r^2 and phi are uniform (Kolmogorov–Smirnov)
    assert stats.kstest(r2, "uniform").pvalue > 1e-3
    assert stats.kstest(phi, stats.uniform(-np.pi, 2 * np.pi).cdf).pvalue > 1e-3


def test_concentric_disk_edges_by_hand():
    u = np.array([[0.5, 0.5], [1.0, 0.5], [0.0, 0.5], [0.5, 1.0], [0.5, 0.0], [1.0, 1.0]])
    p = cosine_hemisphere(u)[:, :2]
    s = np.sqrt(0.5)
    assert np.allclose(p, [[0, 0], [1, 0], [-1, 0], [0, 1], [0, -1], [s, s]], atol=1e-15)
    assert np.allclose(disk_to_square(p), u, atol=1e-15)


def test_degenerate_cone():
    w = uniform_cone(np.array([[0.3, 0.7]]), 1.0)
    assert np.allclose(w, [[0.0, 0.0, 1.0]])
    assert uniform_cone_pdf(w, 1.0)[0] == 0.0
    assert np.all(np.isfinite(uniform_cone_to_square(w, 1.0)))


@settings(max_examples=200)
@given(st.floats(0.0, ONE), st.floats(0.0, ONE))
def test_concentric_round_trip_property(a, b):
    u = np.array([[a, b]])
    p = cosine_hemisphere(u)[:, :2]
    assert p[0, 0] ** 2 + p[0, 1] ** 2 <= 1.0 + 1e-15
    assert np.allclose(disk_to_square(p), u, atol=1e-9)
