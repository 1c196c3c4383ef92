"""The sun-and-sky environment: Preetham's formulas by hand, the pdf integrates to 1,
sampling follows the pdf (chi-square), the sun's irradiance is E cos(zenith), no NaN at
the zenith / horizon / below it, the scalar kernels called one direction at a time are the
methods, and a rendered diffuse plane gets the analytic irradiance."""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from scipy.stats import chi2 as chi2_dist
from scipy.stats import kstest

from render.frame import Frame
from render.integrator import render
from render.scene import SceneError, parse_scene
from render.sky import (
    PARAMS_SIZE,
    RGB_UNIT_CONVERSION,
    SunAndSky,
    preetham_xyY,
    relative_air_mass,
    sun_and_sky_eval,
    sun_and_sky_pdf,
    sun_and_sky_sample,
    sun_color,
    sun_direction_from_angles,
    sun_normal_illuminance,
    xyY_to_linear_srgb,
)
from render.testing import light_samples

# sun at the zenith, high, low, a hair above the horizon, on it, below it (twilight), night
ELEVATIONS = (90.0, 60.0, 20.0, 0.5, 0.0, -3.0, -30.0)


def _sun_centred(sky: SunAndSky, n_theta: int, n_phi: int, lo: float, hi: float):
    """Midpoint nodes uniform in (cos theta', phi') about the sun between the cosines
    ``lo < hi``, and their (equal) solid angle."""
    c = hi - (np.arange(n_theta) + 0.5) * (hi - lo) / n_theta
    phi = (np.arange(n_phi) + 0.5) * 2 * np.pi / n_phi
    cc, pp = np.meshgrid(c, phi, indexing="ij")
    r = np.sqrt(np.maximum(0.0, 1.0 - cc * cc))
    local = np.stack([r * np.cos(pp), r * np.sin(pp), cc], axis=-1).reshape(-1, 3)
    f = Frame.from_normal(sky.sun_direction[None])
    d = local[:, :1] * f.s + local[:, 1:2] * f.t + local[:, 2:3] * f.n
    return d, (hi - lo) * 2 * np.pi / (n_theta * n_phi)


def _sphere_integral(sky: SunAndSky, fn, n_cone=64, n_theta=2048, n_phi=1024):
    """∫ fn(d) dω over the sphere: a fine grid inside the sun disk, a grid outside."""
    inside, w_in = _sun_centred(sky, n_cone, 64, sky.cos_sun_radius, 1.0)
    outside, w_out = _sun_centred(sky, n_theta, n_phi, -1.0, sky.cos_sun_radius)
    return fn(inside).sum(axis=0) * w_in + fn(outside).sum(axis=0) * w_out


# ----------------------------------------------------------------------------- formulas
def test_preetham_by_hand():
    # T = 4, sun zenith angle 40 degrees; the zenith direction: F(0, ts) / F(0, ts) = 1
    t, ts = 4.0, math.radians(40.0)
    chi = (4 / 9 - t / 120) * (math.pi - 2 * ts)
    yz = (4.0453 * t - 4.9710) * math.tan(chi) - 0.2155 * t + 2.4192
    xz = (0.00166 * ts**3 - 0.00375 * ts**2 + 0.00209 * ts) * t * t + (
        -0.02903 * ts**3 + 0.06377 * ts**2 - 0.03202 * ts + 0.00394
    ) * t + (0.11693 * ts**3 - 0.21196 * ts**2 + 0.06052 * ts + 0.25886)
    big_y, x, _ = preetham_xyY([1.0], [math.cos(ts)], ts, t)
    assert big_y[0] == pytest.approx(yz, rel=1e-12) and x[0] == pytest.approx(xz, rel=1e-12)
    # at the horizon, 90 degrees from the sun: (1 + 0) (1 + C + 0) / F(0, ts) for Y
    a, b, c, d, e = 0.1787 * t - 1.4630, -0.3554 * t + 0.4275, -0.0227 * t + 5.3251, (
        0.1206 * t - 2.5771), -0.0670 * t + 0.3703
    f0 = (1 + a * math.exp(b)) * (1 + c * math.exp(d * ts) + e * math.cos(ts) ** 2)
    fh = 1 + c * math.exp(d * math.pi / 2)
    big_y, _, _ = preetham_xyY([0.0], [0.0], ts, t)
    assert big_y[0] == pytest.approx(yz * fh / f0, rel=1e-12)
    # below the horizon reads the horizon; the result is finite everywhere
    assert np.array_equal(preetham_xyY([-0.5], [0.0], ts, t)[0], big_y)


def test_colour_conversion_and_sun_model():
    # D65 white point -> (1, 1, 1); y = 0 -> black instead of a division by zero
    assert np.allclose(xyY_to_linear_srgb([0.3127, 0.2], [0.3290, 0.0], [2.0, 1.0]),
                       [[2.0, 2.0, 2.0], [0.0, 0.0, 0.0]], rtol=5e-4)
    # Kasten-Young: m(0) ~ 1, m(60) ~ 2, m(90) = 37.92, and no blow-up past 90
    m = relative_air_mass(np.radians([0.0, 60.0, 90.0, 120.0]))
    # m(60) = 1 / (0.5 + 0.50572 * 36.07995^-1.6364) by hand
    assert m[0] == pytest.approx(0.99971, abs=1e-5) and m[1] == pytest.approx(1.99429, abs=1e-5)
    assert m[2] == pytest.approx(37.92, abs=0.01) and m[3] == m[2]
    # E_vn = 133.8 klx exp(-T m / (9.9 + 0.043 m)) by hand at 60 degrees, T = 3
    mm = float(relative_air_mass(math.radians(60.0)))
    assert sun_normal_illuminance(math.radians(60.0), 3.0) == pytest.approx(
        133_800 * math.exp(-3.0 * mm / (9.9 + 0.043 * mm)), rel=1e-12)
    # the sun reddens toward the horizon, with luminance 1
    noon, dusk = sun_color(0.0, 3.0), sun_color(math.radians(89.0), 3.0)
    lum = np.array([0.212671, 0.715160, 0.072169])
    assert lum @ noon == pytest.approx(1.0) and lum @ dusk == pytest.approx(1.0)
    assert dusk[0] / dusk[2] > 10 * noon[0] / noon[2] > 10


def test_units_and_plausible_ratios():
    lum = np.array([0.212671, 0.715160, 0.072169])
    zenith_horizon = np.array([[0.0, 1.0, 0.0], [1.0, 0.0, 0.0]])  # horizon 90 deg from the sun
    # a clear sky (low sun) is blue at the zenith and brighter at the horizon; a hazy
    # one is brighter at the zenith (toward the CIE overcast sky)
    for t, lo, hi in ((2.0, 3.0, 8.0), (3.0, 1.2, 3.0), (8.0, 0.3, 1.0)):
        z, h = SunAndSky(sun_direction_from_angles(20.0, 0.0), turbidity=t).eval(zenith_horizon)
        assert z[2] > z[1] > z[0] and lo < (lum @ h) / (lum @ z) < hi, (t, z, h)
    sky = SunAndSky(sun_direction_from_angles(60.0, 0.0), turbidity=3.0)
    z = sky.eval(zenith_horizon)[0]
    # zenith luminance = Preetham's Y_z (kcd/m^2) * 1000 * 1e-4
    big_y, _, _ = preetham_xyY([1.0], [math.cos(math.radians(30))], math.radians(30), 3.0)
    assert lum @ z == pytest.approx(big_y[0] * 1000 * RGB_UNIT_CONVERSION, rel=2e-3)
    # clear-sky magnitudes: sun ~ 80-110 klx normal, sky 10-40 klx on the ground
    assert 80_000 < sky.sun_illuminance < 110_000
    assert 1.0 < lum @ sky.sky_irradiance < 4.0
    # intensity scales everything; sun_scale/sky_scale one part
    twice = SunAndSky(sky.sun_direction, turbidity=3.0, intensity=2.0)
    d = np.array([[0.3, 0.5, -0.2], list(sky.sun_direction)])
    d /= np.linalg.norm(d, axis=1, keepdims=True)
    assert np.allclose(twice.eval(d), 2 * sky.eval(d), rtol=1e-12)
    no_sky = SunAndSky(sky.sun_direction, turbidity=3.0, sky_scale=0.0, ground_albedo=0.0)
    assert np.allclose(no_sky.eval(d)[1] - sky.sun_radiance, 0.0) and no_sky.p_sun == 1.0


# ------------------------------------------------------------------------- the sun disk
@pytest.mark.parametrize("elevation", [90.0, 60.0, 30.0, 1.0, 0.28])
def test_sun_irradiance_on_a_horizontal_plane_is_e_cos_zenith(elevation):
    sky = SunAndSky(sun_direction_from_angles(elevation, 40.0), turbidity=2.5, sky_scale=0.0)
    e = sky.sun_irradiance
    assert np.all(e > 0)
    # a surface facing the sun gets E; a horizontal one E cos(zenith) = E sin(elevation)
    d, w = _sun_centred(sky, 400, 256, sky.cos_sun_radius, 1.0)
    facing = (sky.eval(d) * (d @ sky.sun_direction)[:, None]).sum(axis=0) * w
    horizontal = (sky.eval(d) * d[:, 1:2]).sum(axis=0) * w
    assert np.allclose(facing, e, rtol=1e-9)
    assert np.allclose(horizontal, e * math.sin(math.radians(elevation)), rtol=1e-9)
    # the radiance is E / (pi sin^2 alpha), uniform over the disk
    assert np.allclose(sky.sun_radiance, e / (math.pi * math.sin(math.radians(0.27)) ** 2))


def test_sun_on_and_below_the_horizon():
    # half the disk below the horizon: that half is ground, and gets no sun
    half = SunAndSky([1.0, 0.0, 0.0], turbidity=3.0, sky_scale=0.0, ground_albedo=0.0)
    d, w = _sun_centred(half, 200, 256, half.cos_sun_radius, 1.0)
    lit = half.sun(d)[:, 0] > 0
    assert np.array_equal(lit, d[:, 1] >= 0) and 0.45 < lit.mean() < 0.55
    # the sun is dim and red there, but on
    assert 0 < half.sun_irradiance[2] < half.sun_irradiance[0] < 0.01
    # disk entirely below the horizon: no sun; sky fades out by -6 degrees
    assert np.all(SunAndSky(sun_direction_from_angles(-0.3, 0.0)).sun_irradiance == 0)
    dusk = SunAndSky(sun_direction_from_angles(-3.0, 0.0))
    night = SunAndSky(sun_direction_from_angles(-6.0, 0.0))
    assert dusk.p_sun == 0.0 and np.all(dusk.sky_irradiance > 0)
    assert np.all(night.sky_irradiance == 0) and np.all(night.ground_radiance == 0)


@pytest.mark.parametrize("elevation", ELEVATIONS)
def test_no_nan_at_zenith_horizon_and_below(elevation, rng):
    sky = SunAndSky(sun_direction_from_angles(elevation, 0.0), turbidity=2.0)
    special = np.array([
        [0, 1.0, 0], [0, -1.0, 0], [1.0, 0, 0], [0, 0, -1.0], [0, 0, 1.0], [-1.0, 0, 0],
        list(sky.sun_direction), list(-sky.sun_direction), [1e-300, 1.0, 0], [0, 1e-300, 1.0],
    ])
    special /= np.linalg.norm(special, axis=1, keepdims=True)
    u = np.concatenate([rng.random((2000, 2)), [[0.0, 0.0], [1 - 2**-53] * 2, [0.0, 1 - 2**-53]]])
    with np.errstate(all="raise", under="ignore"):
        values = sky.eval(special), sky.pdf(special)
        wi, _, li, pdf, _ = light_samples([sky], np.zeros((len(u), 3)), u)
    for v in (*values, li, pdf, wi):
        assert np.all(np.isfinite(v))
    assert np.all(values[0] >= 0) and np.all(values[1] > 0)
    assert np.all(li >= 0) and np.all(pdf > 0)
    assert np.allclose(np.linalg.norm(wi, axis=1), 1.0)
    assert np.allclose(sky.eval(wi), li) and np.allclose(sky.pdf(wi), pdf)


# ------------------------------------------------------------------------ pdf, sampling
@pytest.mark.parametrize(
    "elevation, kwargs",
    [(45.0, {}), (90.0, {}), (0.0, {}), (-3.0, {}), (30.0, {"sky_scale": 0.0}),
     (30.0, {"sun_scale": 0.0}), (20.0, {"sun_radius": 5.0, "turbidity": 8.0}),
     (-30.0, {"ground_albedo": 0.0})],
)
def test_pdf_integrates_to_one(elevation, kwargs):
    sky = SunAndSky(sun_direction_from_angles(elevation, 25.0), **kwargs)
    total = _sphere_integral(sky, sky.pdf)
    assert total == pytest.approx(1.0, abs=2e-3)


def _chi2(sky: SunAndSky, n: int, rng, nz=16, nphi=32):
    """Pearson's chi-square of ``n`` samples against the pdf over (y, phi) bins plus one
    bin for the sun disk; expected counts by quadrature of the pdf."""
    def bins(d):
        j = np.clip(((1 - d[:, 1]) / 2 * nz).astype(int), 0, nz - 1)
        i = np.clip(((0.5 + np.arctan2(d[:, 0], -d[:, 2]) / (2 * np.pi)) * nphi).astype(int),
                    0, nphi - 1)
        k = j * nphi + i
        return np.where(d @ sky.sun_direction >= sky.cos_sun_radius, nz * nphi, k)

    expected = np.zeros(nz * nphi + 1)
    inside, w_in = _sun_centred(sky, 64, 64, sky.cos_sun_radius, 1.0)
    np.add.at(expected, bins(inside), sky.pdf(inside) * w_in)
    outside, w_out = _sun_centred(sky, 2048, 1024, -1.0, sky.cos_sun_radius)
    np.add.at(expected, bins(outside), sky.pdf(outside) * w_out)
    wi = light_samples([sky], np.zeros((n, 3)), rng.random((n, 2)))[0]
    observed = np.bincount(bins(wi), minlength=len(expected)).astype(float)
    expected *= n / expected.sum()
    keep = expected >= 5
    # pool the sparse cells into one
    obs = np.append(observed[keep], observed[~keep].sum())
    exp = np.append(expected[keep], expected[~keep].sum())
    if exp[-1] < 5:
        obs, exp = obs[:-1], exp[:-1]
    stat = float(((obs - exp) ** 2 / exp).sum())
    return float(chi2_dist.sf(stat, len(exp) - 1)), observed[-1] / n


@pytest.mark.parametrize(
    "elevation, kwargs",
    [(45.0, {}), (90.0, {"turbidity": 2.0}), (0.0, {}), (-3.0, {}),
     (20.0, {"sun_radius": 5.0, "turbidity": 8.0}), (30.0, {"sky_scale": 0.0}),
     (60.0, {"sun_scale": 0.0})],
)
def test_sampling_matches_pdf_chi2(elevation, kwargs, rng):
    sky = SunAndSky(sun_direction_from_angles(elevation, 130.0), **kwargs)
    p, sun_share = _chi2(sky, 400_000, rng)
    assert p > 1e-3, p
    if "sun_radius" not in kwargs and sky.p_sun > 0:
        # a 0.27 degree disk holds (almost) only sun samples
        assert abs(sun_share - sky.p_sun) < 5 * math.sqrt(sky.p_sun * (1 - sky.p_sun) / 400_000)


def test_sun_disk_samples_are_uniform_ks(rng):
    sky = SunAndSky(sun_direction_from_angles(35.0, -60.0), sky_scale=0.0, ground_albedo=0.0)
    assert sky.p_sun == 1.0
    wi = sky.sample_direction(rng.random((20_000, 2)))
    f = Frame.from_normal(sky.sun_direction[None])
    local = np.stack([wi @ f.s[0], wi @ f.t[0], wi @ f.n[0]], axis=1)
    # uniform over the cap: 1 - cos theta' uniform in [0, 1 - cos alpha], phi' uniform
    one_minus = 2 * math.sin(math.radians(0.27) / 2) ** 2
    assert kstest((1 - local[:, 2]) / one_minus, "uniform").pvalue > 1e-3
    assert kstest((np.arctan2(local[:, 1], local[:, 0]) + np.pi) / (2 * np.pi),
                  "uniform").pvalue > 1e-3


@pytest.mark.parametrize("elevation", [60.0, 10.0])
def test_estimator_gives_the_horizontal_irradiance(elevation, rng):
    # E[L cos / pdf] over the upper hemisphere = E_sun sin(elevation) + E_sky
    sky = SunAndSky(sun_direction_from_angles(elevation, 0.0), turbidity=3.0)
    n = 400_000
    wi, _, li, pdf, _ = light_samples([sky], np.zeros((n, 3)), rng.random((n, 2)))
    contrib = li * (np.maximum(wi[:, 1], 0.0) / pdf)[:, None]
    mean, err = contrib.mean(axis=0), contrib.std(axis=0) / math.sqrt(n)
    want = sky.sun_irradiance * math.sin(math.radians(elevation)) + sky.sky_irradiance
    assert np.all(np.abs(mean - want) < 4 * err + 1e-9), (mean, want, err)
    # and the quadrature of the sky alone agrees with a finer, independent one
    fine = _sphere_integral(sky, lambda d: sky.sky(d) * np.maximum(d[:, 1:2], 0.0),
                            n_theta=1024, n_phi=2048)
    assert np.allclose(sky.sky_irradiance, fine, rtol=2e-3)


# ------------------------------------------------------------------------------ kernels
# sun high, on the horizon, below it (twilight, night), and each part alone
KERNEL_SKIES = [(60.0, {}), (0.0, {}), (-3.0, {}), (-30.0, {}), (30.0, {"sky_scale": 0.0}),
                (30.0, {"sun_scale": 0.0}), (30.0, {"sky_scale": 0.0, "ground_albedo": 0.0})]
ONE_MINUS_EPS = 1 - 2**-53


def _kernels(sky: SunAndSky, d, u):
    """The three kernels called from Python one direction (one u) at a time."""
    params, p, cdf = sky.kernel_params(), sky._p, sky._cdf
    radiance = np.array([sun_and_sky_eval(params, *row) for row in d])
    pdf = np.array([sun_and_sky_pdf(params, p, *row) for row in d])
    wi = np.array([sun_and_sky_sample(params, p, cdf, *row) for row in u])
    return radiance, pdf, wi


@pytest.mark.parametrize("elevation, kwargs", KERNEL_SKIES)
def test_kernels_one_direction_at_a_time_are_the_methods(elevation, kwargs, rng):
    sky = SunAndSky(sun_direction_from_angles(elevation, 70.0), **kwargs)
    params = sky.kernel_params()
    assert params.shape == (PARAMS_SIZE,) and params.dtype == np.float64
    assert np.array_equal(params[:3], sky.sun_direction) and params[15] == sky.p_sun
    # on the horizon exactly (both signs of zero), the poles, at and around the sun, random
    ring = np.linspace(0.0, 2 * np.pi, 9)
    horizon = np.stack([np.sin(ring), np.zeros(9), -np.cos(ring)], axis=1)
    edge = math.acos(sky.cos_sun_radius) * np.array([0.999, 1.001])
    f = Frame.from_normal(sky.sun_direction[None])
    rim = np.cos(edge)[:, None] * sky.sun_direction + np.sin(edge)[:, None] * f.s[0]
    d = np.concatenate([horizon, [[0, -0.0, 1.0], [0, 1.0, 0], [0, -1.0, 0]],
                        [sky.sun_direction, -sky.sun_direction], rim, rng.normal(size=(40, 3))])
    d /= np.linalg.norm(d, axis=1, keepdims=True)
    edges = [0.0, ONE_MINUS_EPS, 1.0, sky.p_sun, np.nextafter(sky.p_sun, 0.0)]
    u = np.concatenate([[[a, b] for a in edges for b in (0.0, ONE_MINUS_EPS)], rng.random((40, 2))])
    radiance, pdf, wi = _kernels(sky, d, u)
    assert np.allclose(radiance, sky.eval(d), rtol=1e-13, atol=0)
    assert np.allclose(radiance, sky.sky(d) + sky.sun(d), rtol=1e-13, atol=0)
    assert np.allclose(pdf, sky.pdf(d), rtol=1e-13, atol=0)
    assert np.allclose(wi, sky.sample_direction(u), rtol=1e-13, atol=1e-15)
    for v in (radiance, pdf, wi):
        assert np.all(np.isfinite(v))
    # a density wherever there is light (only a sun with no sky and a black ground: p_sun
    # = 1, and nothing outside the disk)
    assert np.all(radiance >= 0) and np.all(pdf[radiance.max(axis=1) > 0] > 0)
    assert np.all(pdf > 0) or sky.p_sun == 1.0
    assert np.allclose(np.linalg.norm(wi, axis=1), 1.0)
    # the sampled directions have a density: the pdf there is that of the methods
    assert np.all(sky.pdf(wi) > 0)


@pytest.mark.parametrize("elevation, kwargs", KERNEL_SKIES[:4])
def test_kernel_pdf_is_the_table_cell_by_cell_and_integrates_to_one(elevation, kwargs):
    sky = SunAndSky(sun_direction_from_angles(elevation, -40.0), **kwargs)
    params, p = sky.kernel_params(), sky._p
    # at the centre of table cell k (row k // 256 from the zenith down, uniform in cos
    # theta; column k % 256 from azimuth -180): (1 - p_sun) p_k over the cell's solid angle
    h, w = 128, 256
    y = 1 - 2 * (np.arange(h) + 0.5) / h
    phi = ((np.arange(w) + 0.5) / w - 0.5) * 2 * np.pi
    yy, pp = np.meshgrid(y, phi, indexing="ij")
    r = np.sqrt(1 - yy * yy)
    d = np.stack([r * np.sin(pp), yy, -r * np.cos(pp)], axis=-1).reshape(-1, 3)
    outside = d @ sky.sun_direction < sky.cos_sun_radius
    pdf = np.array([sun_and_sky_pdf(params, p, *row) for row in d[outside]])
    want = (1 - sky.p_sun) * p[outside] * (h * w) / (4 * np.pi)
    assert np.allclose(pdf, want, rtol=1e-12, atol=0)
    # the whole sphere, the sun disk resolved
    assert _sphere_integral(sky, sky.pdf) == pytest.approx(1.0, abs=2e-3)


_SKIES = {}


@settings(max_examples=150)
@given(
    st.sampled_from(range(len(KERNEL_SKIES))),
    st.floats(-1.0, 1.0), st.floats(-np.pi, np.pi),
    st.floats(0.0, 1.0), st.floats(0.0, 1.0),
)
def test_kernels_are_total(which, cos_theta, phi, u1, u2):
    """Any direction (the horizon and the poles included) and any u in [0, 1]: finite,
    radiance >= 0, pdf > 0 where there is light, a unit sample whose pdf is > 0."""
    if which not in _SKIES:
        elevation, kwargs = KERNEL_SKIES[which]
        _SKIES[which] = SunAndSky(sun_direction_from_angles(elevation, 10.0), **kwargs)
    sky = _SKIES[which]
    params, p, cdf = sky.kernel_params(), sky._p, sky._cdf
    r = math.sqrt(max(0.0, 1 - cos_theta * cos_theta))
    d = (r * math.sin(phi), cos_theta, -r * math.cos(phi))
    radiance = sun_and_sky_eval(params, *d)
    pdf = sun_and_sky_pdf(params, p, *d)
    assert all(math.isfinite(c) and c >= 0 for c in radiance) and math.isfinite(pdf)
    assert pdf > 0 or (max(radiance) == 0 and sky.p_sun == 1.0)
    wi = sun_and_sky_sample(params, p, cdf, u1, u2)
    assert all(math.isfinite(c) for c in wi) and math.isclose(math.hypot(*wi), 1.0, rel_tol=1e-12)
    assert sun_and_sky_pdf(params, p, *wi) > 0


def test_bad_arguments():
    for kwargs, match in (
        ({"turbidity": 1.0}, "turbidity"),
        ({"turbidity": 11.0}, "turbidity"),
        ({"sun_radius": 0.0}, "sun_radius"),
        ({"sun_radius": 60.0}, "sun_radius"),
        ({"intensity": -1.0}, "intensity"),
        ({"intensity": math.nan}, "intensity"),
        ({"sky_scale": -0.1}, "sky_scale"),
        ({"ground_albedo": 1.5}, "ground_albedo"),
        ({"ground_albedo": [0.2, 0.2]}, "ground_albedo"),
    ):
        with pytest.raises(ValueError, match=match):
            SunAndSky([0, 1, 0], **kwargs)
    with pytest.raises(ValueError, match="sun_direction"):
        SunAndSky([0, 0, 0])
    with pytest.raises(ValueError, match="elevation"):
        sun_direction_from_angles(91.0, 0.0)


# ------------------------------------------------------------------------------- scenes
SCENE = """
[camera]
type = "orthographic"
position = [0.0, 1.0, 0.0]
look_at = [0.0, 0.0, 0.0]
up = [0.0, 0.0, -1.0]
ortho_height = 0.2

[render]
resolution = [24, 24]
spp = {spp}
max_depth = 3

[[lights]]
type = "sun_and_sky"
{light}

[[objects]]
surface = {{ type = "plane", size = [40.0, 40.0], origin = [-20.0, 0.0, 20.0], \
axis_u = [1.0, 0.0, 0.0], axis_v = [0.0, 0.0, -1.0] }}
material = "diffuse(tint: color(0.5))"
"""


@pytest.mark.parametrize(
    "light",
    ['elevation = 35.0\nazimuth = 120.0\nturbidity = 2.5\nsky_scale = 0.0',
     'sun_direction = [-1.0, 1.0, -1.0]\nturbidity = 4.0'],
)
def test_rendered_diffuse_plane_gets_the_analytic_irradiance(light):
    scene = parse_scene(SCENE.format(spp=16, light=light), "sun.toml")
    sky = scene.lights[0]
    assert isinstance(sky, SunAndSky)
    film = render(scene, progress=False)
    img = film.rgb().reshape(-1, 3)
    assert np.all(np.isfinite(img)) and img.min() >= 0
    mean, err = img.mean(axis=0), img.std(axis=0, ddof=1) / math.sqrt(len(img))
    elevation = math.asin(sky.sun_direction[1])
    want = 0.5 / math.pi * (sky.sun_irradiance * math.sin(elevation) + sky.sky_irradiance)
    assert np.all(np.abs(mean - want) < 4 * err + 1e-3 * want), (mean, want, err)


def test_scene_file_errors():
    base = SCENE.format(spp=1, light="{}")
    for light, key, match in (
        ("elevation = 30.0\nsun_direction = [0.0, 1.0, 0.0]", "sun_direction", "not both"),
        ("elevation = 120.0", "elevation", "elevation"),
        ("sun_direction = [0.0, 0.0, 0.0]", "sun_direction", "must not be"),
        ("turbidity = 20.0", "turbidity", "turbidity"),
        ("turbidty = 3.0", "turbidty", "did you mean 'turbidity'"),
    ):
        text = base.replace("{}", light)
        with pytest.raises(SceneError, match=match) as e:
            parse_scene(text, "s.toml")
        line = 1 + next(i for i, ln in enumerate(text.splitlines()) if ln.startswith(key))
        assert (e.value.line, e.value.column) == (line, 1), str(e.value)
    two = base.replace("{}", "") + '\n[[lights]]\ntype = "environment"\n'
    with pytest.raises(SceneError, match="at most one environment"):
        parse_scene(two, "s.toml")
