"""A sun-and-sky environment: ``base::sun_and_sky`` as a Preetham sky plus a sun disk.

:class:`SunAndSky` is one environment light (:attr:`Light.infinite`) made of

* **the sun**: a disk of angular radius ``sun_radius`` (default 0.27 degrees) around
  ``sun_direction`` (the direction *toward* the sun, as ``base::sun_and_sky``'s
  argument), of uniform radiance ``L_sun = E / (pi sin^2 alpha)``, so a surface facing
  the sun receives exactly the irradiance ``E`` and a surface of normal ``n`` receives
  ``E cos(angle(n, sun))`` while the whole disk is above its horizon;
* **the sky**: Preetham, Shirley and Smits' analytic daylight model ("A Practical
  Analytic Model for Daylight", SIGGRAPH 1999): the Perez luminance distribution
  ``F(theta, gamma) = (1 + A e^(B / cos theta)) (1 + C e^(D gamma) + E cos^2 gamma)``
  for ``Y``, ``x`` and ``y`` with coefficients linear in the turbidity ``T``, scaled by
  the zenith luminance ``Y_z`` (kcd/m^2) and chromaticity of the paper's appendix,
  converted from CIE xyY to linear sRGB (Rec. 709 primaries, D65);
* **the ground**: below the horizon a uniform Lambertian ground of ``ground_albedo``
  lit by the sun and the sky, radiance ``albedo (E_sun,h + E_sky,h) / pi``.

Units follow mental ray's physical sky (the ancestor of ``base::sun_and_sky``):
radiance in RGB = luminance in cd/m^2 times ``rgb_unit_conversion`` = 1e-4, times
``intensity``.  A clear noon sky (``Y_z`` about 10 kcd/m^2) is then about 1 and the sun's
normal irradiance about 10 (100 klx).  The sun's normal illuminance is the CIE
luminous-turbidity formula ``E_vn = 133.8 klx exp(-a_v m T)`` with the luminous
extinction coefficient ``a_v = 1 / (9.9 + 0.043 m)`` (Navvab et al. 1984; the luminous
solar constant of Darula, Kittler and Gueymard 2005) and Kasten and Young's (1989)
relative air mass ``m`` (38 at the horizon); Preetham's turbidity is used as the
luminous turbidity.  Its colour is the same attenuation per channel, with Rayleigh
(``lambda^-4``) and aerosol (Angstrom exponent 1.3) optical depths in the ratio
``1 : T - 1`` at 610, 550 and 465 nm, normalised to the luminance ``E_vn``: white-yellow
at noon, red at the horizon.

Preetham's model holds for a sun above the horizon and ``2 <= T <= 10``.  With the sun
below the horizon the sky keeps its sunset shape (sun zenith angle clamped to 90
degrees) and fades linearly to black at a sun elevation of -6 degrees (the end of civil
twilight); the sun shines while any of its disk is above the horizon, and directions of
the disk below the horizon (the ground) get no sun.

Sampling (next-event estimation): the sun's cone, uniformly, with probability
``P_sun`` (its share of the emitted power, kept in [0.05, 0.95] when both parts
shine), else a piecewise-constant table of the sky and ground over cells of equal
solid angle (uniform in ``cos theta`` and ``phi``, 128 x 256), proportional to each
cell's mean luminance plus 1 % of the average (so every direction has a positive
density).  :meth:`SunAndSky.pdf` is exactly the density of :meth:`SunAndSky.sample_li`,
and :meth:`SunAndSky.eval` the analytic radiance, so estimates are unbiased whatever
the table's resolution.

Examples
--------
>>> sky = SunAndSky(sun_direction_from_angles(45.0, 0.0), turbidity=3.0)
>>> s = sky.sample_li(np.zeros((4, 3)), np.random.default_rng(0).random((4, 2)))
>>> bool(np.all(s.pdf > 0)), bool(np.all(np.isfinite(s.radiance)))
(True, True)
>>> round(float(sky.sun_illuminance), -2)        # lux at 45 degrees, T = 3
87400.0
"""

from __future__ import annotations

import math

import numpy as np

from render._typing import Arr, ArrayLike, Rgb, Vec3
from render.frame import Frame
from render.lights import INFINITE_DISTANCE, Light, LightSample
from render.numerics import luminance, safe_sqrt
from render.warp import square_to_uniform_cone

__all__ = [
    "SunAndSky",
    "sun_direction_from_angles",
    "preetham_xyY",
    "xyY_to_linear_srgb",
    "relative_air_mass",
    "sun_normal_illuminance",
    "sun_color",
    "RGB_UNIT_CONVERSION",
    "LUMINOUS_SOLAR_CONSTANT",
    "TURBIDITY_RANGE",
]

#: RGB radiance per cd/m^2 (mental ray's ``rgb_unit_conversion`` default).
RGB_UNIT_CONVERSION = 1.0e-4
#: extraterrestrial luminous solar constant, lux (Darula, Kittler and Gueymard 2005).
LUMINOUS_SOLAR_CONSTANT = 133_800.0
#: turbidities for which Preetham's fit is valid.
TURBIDITY_RANGE = (2.0, 10.0)
#: sun elevation (degrees) at which the twilight sky has faded to black.
TWILIGHT_END_DEG = -6.0

# Preetham et al. 1999, appendix: Perez coefficients (A..E) = M @ [T, 1]
_PEREZ = {
    "Y": np.array([[0.1787, -1.4630], [-0.3554, 0.4275], [-0.0227, 5.3251],
                   [0.1206, -2.5771], [-0.0670, 0.3703]]),
    "x": np.array([[-0.0193, -0.2592], [-0.0665, 0.0008], [-0.0004, 0.2125],
                   [-0.0641, -0.8989], [-0.0033, 0.0452]]),
    "y": np.array([[-0.0167, -0.2608], [-0.0950, 0.0092], [-0.0079, 0.2102],
                   [-0.0441, -1.6537], [-0.0109, 0.0529]]),
}
# zenith chromaticity = [T^2, T, 1] @ M @ [theta_s^3, theta_s^2, theta_s, 1]
_ZENITH_X = np.array([[0.00166, -0.00375, 0.00209, 0.0],
                      [-0.02903, 0.06377, -0.03202, 0.00394],
                      [0.11693, -0.21196, 0.06052, 0.25886]])
_ZENITH_Y = np.array([[0.00275, -0.00610, 0.00317, 0.0],
                      [-0.04214, 0.08970, -0.04153, 0.00516],
                      [0.15346, -0.26756, 0.06670, 0.26688]])
# CIE XYZ -> linear sRGB (IEC 61966-2-1, D65)
_XYZ_TO_RGB = np.array([[3.2404542, -1.5371385, -0.4985314],
                        [-0.9692660, 1.8760108, 0.0415560],
                        [0.0556434, -0.2040259, 1.0572252]])
# effective wavelengths (nm) of the R, G, B channels for the sun's colour
_SUN_WAVELENGTHS = np.array([610.0, 550.0, 465.0])
_ANGSTROM = 1.3
_TABLE_H, _TABLE_W = 128, 256


def sun_direction_from_angles(elevation: float, azimuth: float) -> np.ndarray:
    """Unit direction toward the sun from ``elevation`` and ``azimuth`` (degrees).

    World space is y up; azimuth 0 looks toward ``-z`` (the centre column of a lat-long
    environment), 90 toward ``+x``.

    Examples
    --------
    >>> np.round(sun_direction_from_angles(0.0, 90.0), 12).tolist()
    [1.0, 0.0, -0.0]
    >>> float(sun_direction_from_angles(90.0, 0.0)[1])
    1.0
    """
    e, a = math.radians(float(elevation)), math.radians(float(azimuth))
    if not (math.isfinite(e) and math.isfinite(a)) or abs(float(elevation)) > 90.0:
        raise ValueError(
            f"sun elevation must be in [-90, 90] degrees and azimuth finite, got "
            f"{elevation!r}, {azimuth!r}")
    return np.array([math.cos(e) * math.sin(a), math.sin(e), -math.cos(e) * math.cos(a)])


def _perez(coef: np.ndarray, cos_theta: Arr, gamma: Arr, cos_gamma: Arr) -> Arr:
    """Perez et al.'s ``F(theta, gamma)``; the first factor is 1 at the horizon (its limit)."""
    a, b, c, d, e = coef
    up = cos_theta > 0.0
    # b < 0 for every valid turbidity: exp(b / cos) -> 0 at the horizon
    grad = np.where(up, a * np.exp(b / np.where(up, cos_theta, 1.0)), 0.0)
    return (1.0 + grad) * (1.0 + c * np.exp(d * gamma) + e * cos_gamma * cos_gamma)


def preetham_xyY(cos_theta: ArrayLike, cos_gamma: ArrayLike, theta_sun: float,
                 turbidity: float) -> tuple[Arr, Arr, Arr]:
    """Preetham's sky: luminance (kcd/m^2) and CIE chromaticity of sky directions.

    Parameters
    ----------
    cos_theta : (n,) float
        Cosine of each direction's zenith angle, in [0, 1] (values below 0 read 0).
    cos_gamma : (n,) float
        Cosine of the angle between each direction and the sun.
    theta_sun : float
        Sun zenith angle, radians, in [0, pi/2].
    turbidity : float
        In :data:`TURBIDITY_RANGE`.

    Returns
    -------
    Y, x, y : (n,) float64

    Examples
    --------
    >>> Y, x, y = preetham_xyY([1.0], [1.0], 0.0, 2.0)      # the zenith under a zenith sun
    >>> round(float(Y[0]), 4), round(float(x[0]), 5), round(float(y[0]), 5)
    (15.5007, 0.26674, 0.2772)
    """
    t = float(turbidity)
    ct = np.clip(np.asarray(cos_theta, dtype=np.float64), 0.0, 1.0)
    cg = np.clip(np.asarray(cos_gamma, dtype=np.float64), -1.0, 1.0)
    gamma = np.arccos(cg)
    ts = float(theta_sun)
    chi = (4.0 / 9.0 - t / 120.0) * (math.pi - 2.0 * ts)
    y_zenith = (4.0453 * t - 4.9710) * math.tan(chi) - 0.2155 * t + 2.4192
    tv = np.array([t * t, t, 1.0])
    sv = np.array([ts**3, ts**2, ts, 1.0])
    zenith = {"Y": y_zenith, "x": float(tv @ _ZENITH_X @ sv), "y": float(tv @ _ZENITH_Y @ sv)}
    out = []
    for key in ("Y", "x", "y"):
        coef = _PEREZ[key] @ np.array([t, 1.0])
        norm = _perez(coef, np.ones(1), np.array([ts]), np.array([math.cos(ts)]))[0]
        out.append(zenith[key] * _perez(coef, ct, gamma, cg) / norm)
    return out[0], out[1], out[2]


def xyY_to_linear_srgb(x: ArrayLike, y: ArrayLike, Y: ArrayLike) -> Rgb:  # noqa: N802, N803
    """CIE xyY to linear sRGB (n, 3), negative components clipped to 0 (``y = 0``: black).

    Examples
    --------
    >>> np.round(xyY_to_linear_srgb([0.3127], [0.3290], [1.0]), 3).tolist()   # D65 white
    [[1.0, 1.0, 1.0]]
    """
    x = np.asarray(x, dtype=np.float64)
    y = np.asarray(y, dtype=np.float64)
    big_y = np.asarray(Y, dtype=np.float64)
    ok = y > 1e-12
    k = np.where(ok, big_y / np.where(ok, y, 1.0), 0.0)
    xyz = np.stack([x * k, np.where(ok, big_y, 0.0), (1.0 - x - y) * k], axis=-1)
    return np.maximum(xyz @ _XYZ_TO_RGB.T, 0.0)


def relative_air_mass(zenith: ArrayLike) -> np.ndarray:
    """Kasten and Young's (1989) relative optical air mass; zenith angle in radians.

    Angles beyond 90 degrees read 90 (m = 37.9).

    Examples
    --------
    >>> round(float(relative_air_mass(0.0)), 4), round(float(relative_air_mass(np.pi / 2)), 1)
    (0.9997, 37.9)
    """
    z = np.minimum(np.degrees(np.asarray(zenith, dtype=np.float64)), 90.0)
    return 1.0 / (np.cos(np.radians(z)) + 0.50572 * (96.07995 - z) ** -1.6364)


def sun_normal_illuminance(zenith: float, turbidity: float) -> float:
    """Direct normal illuminance of the sun (lux): ``133.8 klx exp(-a_v m T)``.

    Examples
    --------
    >>> round(sun_normal_illuminance(0.0, 2.0))
    109427
    """
    m = float(relative_air_mass(zenith))
    a_v = 1.0 / (9.9 + 0.043 * m)
    return LUMINOUS_SOLAR_CONSTANT * math.exp(-a_v * m * float(turbidity))


def sun_color(zenith: float, turbidity: float) -> np.ndarray:
    """Relative RGB of the attenuated sun, of luminance 1 (see the module notes).

    Examples
    --------
    >>> c = sun_color(0.0, 3.0)
    >>> bool(c[0] > c[1] > c[2]), round(float(luminance(c[None])[0]), 12)
    (True, 1.0)
    """
    m = float(relative_air_mass(zenith))
    a_v = 1.0 / (9.9 + 0.043 * m)
    t = float(turbidity)
    rel = _SUN_WAVELENGTHS / 555.0
    k = rel**-4.0 + (t - 1.0) * rel**-_ANGSTROM
    c = np.exp(-a_v * m * (k - t))
    return c / float(luminance(c[None])[0])


def _nonneg(value, name: str) -> float:
    v = float(value)
    if not (math.isfinite(v) and v >= 0.0):
        raise ValueError(f"{name} must be a finite number >= 0, got {value!r}")
    return v


class SunAndSky(Light):
    """The sun (a uniform disk) plus Preetham's sky plus a Lambertian ground, one environment.

    Parameters
    ----------
    sun_direction : (3,) float
        Toward the sun (need not be unit; y is up); see :func:`sun_direction_from_angles`.
    turbidity : float
        Atmospheric turbidity in [2, 10] (2: very clear, 3: clear, 6+: hazy).
    intensity : float
        Multiplies everything (``base::sun_and_sky``'s ``multiplier``).
    sun_radius : float
        Angular radius of the sun disk, degrees, in (0, 45] (the real sun: 0.2666).
    sun_scale, sky_scale : float
        Multiply the sun and the sky separately (0 turns one off).
    ground_albedo : float or (3,)
        Reflectance in [0, 1] of the ground seen below the horizon.

    Attributes
    ----------
    sun_direction : (3,) float64
        Unit.
    sun_irradiance : (3,) float64
        RGB irradiance ``E`` on a surface facing the sun (0 when the sun is down).
    sun_radiance : (3,) float64
        ``E / (pi sin^2 alpha)``, the radiance inside the disk.
    sun_illuminance : float
        Direct normal illuminance (lux) before unit conversion and scaling.
    sky_irradiance : (3,) float64
        Irradiance of the sky alone on an upward-facing surface (quadrature).
    ground_radiance : (3,) float64
    p_sun : float
        Probability that :meth:`sample_li` samples the sun.

    Examples
    --------
    >>> sky = SunAndSky([0.0, 1.0, 0.0], turbidity=2.5, sky_scale=0.0)
    >>> d = np.array([[0.0, 1.0, 0.0], [1.0, 0.0, 0.0]])
    >>> bool(np.allclose(sky.eval(d)[0], sky.sun_radiance)), sky.eval(d)[1].tolist()
    (True, [0.0, 0.0, 0.0])
    """

    infinite = True

    def __init__(
        self,
        sun_direction,
        turbidity: float = 3.0,
        intensity: float = 1.0,
        sun_radius: float = 0.27,
        sun_scale: float = 1.0,
        sky_scale: float = 1.0,
        ground_albedo=0.2,
    ):
        s = np.asarray(sun_direction, dtype=np.float64)
        if s.shape != (3,) or not np.all(np.isfinite(s)) or not np.linalg.norm(s) > 0.0:
            raise ValueError(
                f"sun_direction must be three finite numbers, not all zero, got {sun_direction!r}")
        self.sun_direction = s / np.linalg.norm(s)
        t = float(turbidity)
        lo, hi = TURBIDITY_RANGE
        if not lo <= t <= hi:
            raise ValueError(
                f"turbidity must be in [{lo}, {hi}] (Preetham's fit; 2 is very clear, 10 hazy), "
                f"got {turbidity!r}")
        self.turbidity = t
        scale = _nonneg(intensity, "sun and sky intensity") * RGB_UNIT_CONVERSION
        radius = float(sun_radius)
        if not 0.0 < radius <= 45.0:
            raise ValueError(
                f"sun_radius must be in (0, 45] degrees, got {sun_radius!r} (for a point-like "
                "sun use a directional light)")
        alpha = math.radians(radius)
        self.cos_sun_radius = math.cos(alpha)
        self._one_minus_cos = 2.0 * math.sin(0.5 * alpha) ** 2  # 1 - cos, without cancellation
        albedo = np.asarray(ground_albedo, dtype=np.float64)
        albedo = np.full(3, float(albedo)) if albedo.ndim == 0 else albedo
        if albedo.shape != (3,) or not np.all((albedo >= 0) & (albedo <= 1)):
            raise ValueError(
                f"ground_albedo must be in [0, 1] (or [r, g, b]), got {albedo.tolist()!r}")
        sun_scale = _nonneg(sun_scale, "sun_scale")
        sky_scale = _nonneg(sky_scale, "sky_scale")

        elevation = math.asin(max(-1.0, min(1.0, float(self.sun_direction[1]))))
        zenith = 0.5 * math.pi - elevation
        # the sun: on while part of its disk is above the horizon
        if elevation > -alpha and sun_scale > 0.0 and scale > 0.0:
            self.sun_illuminance = sun_normal_illuminance(min(zenith, 0.5 * math.pi), t)
            color = sun_color(min(zenith, 0.5 * math.pi), t)
            self.sun_irradiance = self.sun_illuminance * scale * sun_scale * color
        else:
            self.sun_illuminance = 0.0
            self.sun_irradiance = np.zeros(3)
        self.sun_radiance = self.sun_irradiance / (math.pi * math.sin(alpha) ** 2)
        # the sky: Preetham's with the sun clamped to the horizon, faded in twilight
        self._theta_sky = min(zenith, 0.5 * math.pi)
        horizontal = np.array([self.sun_direction[0], 0.0, self.sun_direction[2]])
        hn = np.linalg.norm(horizontal)
        self._sky_sun = (self.sun_direction if elevation >= 0.0 or hn == 0.0
                         else horizontal / hn)
        fade = min(1.0, max(0.0, 1.0 - math.degrees(elevation) / TWILIGHT_END_DEG))
        # kcd/m^2 -> cd/m^2 -> RGB
        self._sky_factor = 1000.0 * scale * sky_scale * fade
        self.ground_radiance = np.zeros(3)  # the quadrature below reads the upper hemisphere
        self.sky_irradiance = self._sky_horizontal_irradiance()
        sun_h = self.sun_irradiance * max(0.0, math.sin(elevation))
        self.ground_radiance = albedo * (sun_h + self.sky_irradiance) / math.pi
        self._build_table()

    # ------------------------------------------------------------------ radiance
    def sky(self, d: Vec3) -> Rgb:
        """Radiance (n, 3) of the sky and the ground (no sun) along unit directions ``d``."""
        d = np.asarray(d, dtype=np.float64)
        n = len(d)
        if self._sky_factor <= 0.0:
            return np.broadcast_to(self.ground_radiance, (n, 3)) * (d[:, 1] < 0.0)[:, None]
        up = d[:, 1] >= 0.0
        big_y, x, y = preetham_xyY(d[:, 1], d @ self._sky_sun, self._theta_sky, self.turbidity)
        rgb = xyY_to_linear_srgb(x, y, np.maximum(big_y, 0.0) * self._sky_factor)
        return np.where(up[:, None], rgb, self.ground_radiance)

    def sun(self, d: Vec3) -> Rgb:
        """Radiance (n, 3) of the sun disk along unit directions ``d`` (0 below the horizon)."""
        d = np.asarray(d, dtype=np.float64)
        inside = (d @ self.sun_direction >= self.cos_sun_radius) & (d[:, 1] >= 0.0)
        return inside[:, None] * self.sun_radiance

    def eval(self, d: np.ndarray) -> np.ndarray:
        """Radiance (n, 3) seen along directions ``d`` (n, 3): sky or ground plus sun."""
        return self.sky(d) + self.sun(d)

    def _sky_horizontal_irradiance(self, nz: int = 256, nphi: int = 512) -> np.ndarray:
        """``∫ L_sky cos theta dω`` over the upper hemisphere (midpoint rule in cos theta, phi)."""
        if self._sky_factor <= 0.0:
            return np.zeros(3)
        z = (np.arange(nz) + 0.5) / nz
        phi = (np.arange(nphi) + 0.5) / nphi * 2.0 * math.pi
        zz, pp = np.meshgrid(z, phi, indexing="ij")
        r = safe_sqrt(1.0 - zz * zz)
        d = np.stack([r * np.sin(pp), zz, -r * np.cos(pp)], axis=-1).reshape(-1, 3)
        rad = self.sky(d) * d[:, 1:2]
        return rad.sum(axis=0) * (2.0 * math.pi / (nz * nphi))

    # ------------------------------------------------------------------ sampling
    def _build_table(self) -> None:
        h, w = _TABLE_H, _TABLE_W
        # 2 x 2 points per cell, cells uniform in y = cos theta (row 0 at the top) and phi
        sub = np.array([0.25, 0.75])
        rows = (np.arange(h)[:, None] + sub[None, :]).ravel() / h
        cols = (np.arange(w)[:, None] + sub[None, :]).ravel() / w
        yy, cc = np.meshgrid(1.0 - 2.0 * rows, cols, indexing="ij")
        phi = (cc - 0.5) * 2.0 * math.pi
        r = safe_sqrt(1.0 - yy * yy)
        d = np.stack([r * np.sin(phi), yy, -r * np.cos(phi)], axis=-1).reshape(-1, 3)
        lum = luminance(self.sky(d)).reshape(h, 2, w, 2).mean(axis=(1, 3))
        lum = np.maximum(lum, 0.0)
        cell = 4.0 * math.pi / (h * w)
        sky_power = float(lum.sum() * cell)
        weight = lum + 0.01 * float(lum.mean()) if sky_power > 0.0 else np.ones((h, w))
        self._p = (weight / weight.sum()).ravel()
        self._cdf = np.cumsum(self._p)
        self._cdf[-1] = 1.0
        sun_lum = float(luminance(self.sun_radiance[None])[0])
        sun_power = sun_lum * 2.0 * math.pi * self._one_minus_cos
        if sun_power <= 0.0:
            self.p_sun = 0.0
        elif sky_power <= 0.0:
            self.p_sun = 1.0
        else:
            self.p_sun = min(0.95, max(0.05, sun_power / (sun_power + sky_power)))
        self._sun_frame = Frame.from_normal(self.sun_direction[None])

    def _cells(self, d: Vec3) -> np.ndarray:
        h, w = _TABLE_H, _TABLE_W
        j = np.clip(((1.0 - d[:, 1]) * 0.5 * h).astype(np.int64), 0, h - 1)
        u = 0.5 + np.arctan2(d[:, 0], -d[:, 2]) / (2.0 * math.pi)
        i = np.clip((u * w).astype(np.int64), 0, w - 1)
        return j * w + i

    def pdf(self, d: np.ndarray) -> np.ndarray:
        """Solid-angle density (n,) with which :meth:`sample_li` picks unit directions ``d``."""
        d = np.asarray(d, dtype=np.float64)
        sky = self._p[self._cells(d)] * (_TABLE_H * _TABLE_W / (4.0 * math.pi))
        cone = (d @ self.sun_direction >= self.cos_sun_radius) / (
            2.0 * math.pi * self._one_minus_cos)
        return self.p_sun * cone + (1.0 - self.p_sun) * sky

    def sample_direction(self, u: np.ndarray) -> Vec3:
        """Directions (n, 3) distributed with density :meth:`pdf`, from ``u`` (n, 2) in [0, 1)."""
        u = np.asarray(u, dtype=np.float64)
        n = len(u)
        wi = np.zeros((n, 3))
        pick_sun = u[:, 0] < self.p_sun
        if np.any(pick_sun):
            us = u[pick_sun].copy()
            us[:, 0] = us[:, 0] / self.p_sun
            local = square_to_uniform_cone(us, self.cos_sun_radius)
            f = self._sun_frame
            wi[pick_sun] = local[:, :1] * f.s + local[:, 1:2] * f.t + local[:, 2:3] * f.n
        rest = ~pick_sun
        if np.any(rest):
            uk = np.clip((u[rest, 0] - self.p_sun) / (1.0 - self.p_sun), 0.0, 1.0)
            k = np.clip(np.searchsorted(self._cdf, uk, side="right"), 0, len(self._p) - 1)
            lo = np.where(k > 0, self._cdf[np.maximum(k - 1, 0)], 0.0)
            pk = self._p[k]
            du = np.clip(np.where(pk > 0, (uk - lo) / np.where(pk > 0, pk, 1.0), 0.5), 0.0, 1.0)
            j, i = np.divmod(k, _TABLE_W)
            y = 1.0 - 2.0 * (j + u[rest, 1]) / _TABLE_H
            phi = ((i + du) / _TABLE_W - 0.5) * 2.0 * math.pi
            r = safe_sqrt(1.0 - y * y)
            wi[rest] = np.stack([r * np.sin(phi), y, -r * np.cos(phi)], axis=1)
        return wi

    def sample_li(self, p, u):
        wi = self.sample_direction(u)
        pdf = self.pdf(wi)
        li = np.where((pdf > 0)[:, None], self.eval(wi), 0.0)
        return LightSample(wi, np.full(len(p), INFINITE_DISTANCE), li, pdf, False)
