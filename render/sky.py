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
density).  :meth:`SunAndSky.pdf` is exactly the density of :meth:`SunAndSky.sample_direction`,
and :meth:`SunAndSky.eval` the analytic radiance, so estimates are unbiased whatever
the table's resolution.

Kernels: the per-direction math is written once, as numba scalar kernels that the
path kernel calls: :func:`sun_and_sky_eval` (radiance),
:func:`sun_and_sky_pdf` and :func:`sun_and_sky_sample`, on the constants of
:meth:`SunAndSky.kernel_params` (everything fixed per sky, the Perez coefficients and
zenith values included) and the table ``SunAndSky._p``, ``._cdf``.  The numpy methods
(:meth:`SunAndSky.eval`, ``sky``, ``sun``, ``pdf``, ``sample_direction``)
and :func:`preetham_xyY` / :func:`xyY_to_linear_srgb` run these kernels over rows.

Examples
--------
>>> sky = SunAndSky(sun_direction_from_angles(45.0, 0.0), turbidity=3.0)
>>> wi = sky.sample_direction(np.random.default_rng(0).random((4, 2)))
>>> bool(np.all(sky.pdf(wi) > 0)), bool(np.all(np.isfinite(sky.eval(wi))))
(True, True)
>>> round(float(sky.sun_illuminance), -2)        # lux at 45 degrees, T = 3
87400.0
"""

from __future__ import annotations

import math

import numpy as np

from render._typing import Arr, ArrayLike, Rgb, Vec3
from render.df import _kernel_common as kc
from render.frame import Frame
from render.jit import njit
from render.lights import Light
from render.numerics import luminance, safe_sqrt

__all__ = [
    "SunAndSky",
    "sun_and_sky_eval",
    "sun_and_sky_pdf",
    "sun_and_sky_sample",
    "PARAMS_SIZE",
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


# --- the kernels' constants ----------------------------------------------------------------
# SunAndSky.kernel_params() -> float64 vector of PARAMS_SIZE, read by the kernels below:
#   0:3    sun direction (unit, toward the sun)
#   3      cos alpha, alpha the sun's angular radius
#   4      1 - cos alpha (without cancellation)
#   5:8    sun radiance rgb (0 while the whole disk is below the horizon, or sun_scale = 0)
#   8:11   the sun direction the sky is computed for (on the horizon during twilight)
#   11     sky factor: RGB per kcd/m^2 (scale, sky_scale and twilight fade; 0: no sky)
#   12:15  ground radiance rgb
#   15     p_sun, the probability that sampling picks the sun's cone
#   16:19  s, 19:22 t: the sun's frame (Frame.from_normal; its n is the sun direction)
#   22:40  Preetham's sky, 6 per quantity Y, x, y: Perez A, B, C, D, E, then the zenith
#          value over F(0, theta_sun)  (see _preetham_constants)
# The table (p, cdf) is SunAndSky._p, ._cdf: 128 x 256 cells, row 0 at the zenith.
_SUN, _COS_ALPHA, _ONE_MINUS_COS, _SUN_RADIANCE, _SKY_SUN = 0, 3, 4, 5, 8
_SKY_FACTOR, _GROUND, _P_SUN, _FRAME_S, _FRAME_T, _PREETHAM = 11, 12, 15, 16, 19, 22
PARAMS_SIZE = 40
# which radiance _radiance_rows computes
_PART_ALL, _PART_SKY, _PART_SUN = 0, 1, 2


def _preetham_constants(theta_sun: float, turbidity: float) -> np.ndarray:
    """The 18 constants of Preetham's sky for one sun zenith angle and turbidity: for
    ``Y``, ``x``, ``y`` the Perez coefficients ``A..E`` (linear in ``T``) and the zenith
    value (appendix of the paper) divided by ``F(0, theta_sun)``."""
    t = float(turbidity)
    ts = float(theta_sun)
    chi = (4.0 / 9.0 - t / 120.0) * (math.pi - 2.0 * ts)
    y_zenith = (4.0453 * t - 4.9710) * math.tan(chi) - 0.2155 * t + 2.4192
    tv = np.array([t * t, t, 1.0])
    sv = np.array([ts**3, ts**2, ts, 1.0])
    zenith = {"Y": y_zenith, "x": float(tv @ _ZENITH_X @ sv), "y": float(tv @ _ZENITH_Y @ sv)}
    q = np.empty(18)
    for k, key in enumerate(("Y", "x", "y")):
        coef = _PEREZ[key] @ np.array([t, 1.0])
        q[6 * k : 6 * k + 5] = coef
        q[6 * k + 5] = zenith[key] / _perez(*coef, 1.0, ts, math.cos(ts))
    return q


@njit
def _perez(a, b, c, d, e, cos_theta, gamma, cos_gamma):
    """Perez et al.'s ``F(theta, gamma)``; the first factor is 1 at the horizon (its
    limit: ``b < 0`` for every valid turbidity, so ``exp(b / cos theta) -> 0``)."""
    grad = a * math.exp(b / cos_theta) if cos_theta > 0.0 else 0.0
    return (1.0 + grad) * (1.0 + c * math.exp(d * gamma) + e * cos_gamma * cos_gamma)


@njit
def _preetham(q, k, cos_theta, cos_gamma):
    """Preetham's ``(Y, x, y)`` of one direction from the constants ``q[k:k + 18]``;
    ``cos_theta`` below 0 reads 0 (the horizon)."""
    ct = min(max(cos_theta, 0.0), 1.0)
    cg = min(max(cos_gamma, -1.0), 1.0)
    gamma = math.acos(cg)
    big_y = q[k + 5] * _perez(q[k], q[k + 1], q[k + 2], q[k + 3], q[k + 4], ct, gamma, cg)
    x = q[k + 11] * _perez(q[k + 6], q[k + 7], q[k + 8], q[k + 9], q[k + 10], ct, gamma, cg)
    y = q[k + 17] * _perez(q[k + 12], q[k + 13], q[k + 14], q[k + 15], q[k + 16], ct, gamma, cg)
    return big_y, x, y


@njit
def _xyY_to_rgb(x, y, big_y):  # noqa: N802
    """CIE xyY to linear sRGB, negative components clipped to 0 (``y = 0``: black)."""
    if not y > 1e-12:
        return 0.0, 0.0, 0.0
    k = big_y / y
    cx = x * k
    cz = (1.0 - x - y) * k
    m = _XYZ_TO_RGB
    r = m[0, 0] * cx + m[0, 1] * big_y + m[0, 2] * cz
    g = m[1, 0] * cx + m[1, 1] * big_y + m[1, 2] * cz
    b = m[2, 0] * cx + m[2, 1] * big_y + m[2, 2] * cz
    return max(r, 0.0), max(g, 0.0), max(b, 0.0)


@njit(allocates=True)
def _preetham_rows(q, cos_theta, cos_gamma):
    """:func:`_preetham` of each row -> (3, n): Y, x, y."""
    out = np.empty((3, len(cos_theta)))
    for i in range(len(cos_theta)):
        out[0, i], out[1, i], out[2, i] = _preetham(q, 0, cos_theta[i], cos_gamma[i])
    return out


@njit(allocates=True)
def _xyY_rows(x, y, big_y):  # noqa: N802
    """:func:`_xyY_to_rgb` of each row -> (n, 3)."""
    out = np.empty((len(x), 3))
    for i in range(len(x)):
        out[i, 0], out[i, 1], out[i, 2] = _xyY_to_rgb(x[i], y[i], big_y[i])
    return out


def _flat(*arrays) -> tuple[tuple[int, ...], list[np.ndarray]]:
    """The broadcast shape of ``arrays`` and each as a contiguous float64 vector."""
    b = np.broadcast_arrays(*(np.asarray(a, dtype=np.float64) for a in arrays))
    return b[0].shape, [np.ascontiguousarray(a.ravel()) for a in b]


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
    shape, (ct, cg) = _flat(cos_theta, cos_gamma)
    out = _preetham_rows(_preetham_constants(theta_sun, turbidity), ct, cg)
    return out[0].reshape(shape), out[1].reshape(shape), out[2].reshape(shape)


def xyY_to_linear_srgb(x: ArrayLike, y: ArrayLike, Y: ArrayLike) -> Rgb:  # noqa: N802, N803
    """CIE xyY to linear sRGB (n, 3), negative components clipped to 0 (``y = 0``: black).

    Examples
    --------
    >>> np.round(xyY_to_linear_srgb([0.3127], [0.3290], [1.0]), 3).tolist()   # D65 white
    [[1.0, 1.0, 1.0]]
    """
    shape, (x, y, big_y) = _flat(x, y, Y)
    return _xyY_rows(x, y, big_y).reshape(*shape, 3)


# --- the sun and sky, one direction at a time ------------------------------------------------


@njit
def _sky(params, dx, dy, dz):
    """Radiance of the sky (``dy >= 0``) or the ground (``dy < 0``) along ``d`` -> rgb."""
    if dy < 0.0:
        return params[_GROUND], params[_GROUND + 1], params[_GROUND + 2]
    f = params[_SKY_FACTOR]
    if not f > 0.0:
        return 0.0, 0.0, 0.0
    cos_gamma = dx * params[_SKY_SUN] + dy * params[_SKY_SUN + 1] + dz * params[_SKY_SUN + 2]
    big_y, x, y = _preetham(params, _PREETHAM, dy, cos_gamma)
    return _xyY_to_rgb(x, y, max(big_y, 0.0) * f)


@njit
def _in_sun_cone(params, dx, dy, dz):
    """Whether ``d`` is within the sun's angular radius (above the horizon or not)."""
    c = dx * params[_SUN] + dy * params[_SUN + 1] + dz * params[_SUN + 2]
    return c >= params[_COS_ALPHA]


@njit
def _sun(params, dx, dy, dz):
    """Radiance of the sun disk along ``d`` -> rgb (0 below the horizon)."""
    if dy >= 0.0 and _in_sun_cone(params, dx, dy, dz):
        return params[_SUN_RADIANCE], params[_SUN_RADIANCE + 1], params[_SUN_RADIANCE + 2]
    return 0.0, 0.0, 0.0


@njit
def sun_and_sky_eval(params, dx, dy, dz):
    """Radiance along the unit direction ``d``: sky or ground plus sun -> ``(r, g, b)``."""
    r, g, b = _sky(params, dx, dy, dz)
    sr, sg, sb = _sun(params, dx, dy, dz)
    return r + sr, g + sg, b + sb


@njit
def _cell(dx, dy, dz):
    """Index of the table cell (uniform in ``cos theta`` and ``phi``) holding ``d``."""
    row = min(max((1.0 - dy) * 0.5 * _TABLE_H, 0.0), _TABLE_H - 1.0)
    u = 0.5 + math.atan2(dx, -dz) / (2.0 * math.pi)
    col = min(max(u * _TABLE_W, 0.0), _TABLE_W - 1.0)
    return int(row) * _TABLE_W + int(col)


@njit
def sun_and_sky_pdf(params, p, dx, dy, dz):
    """Solid-angle density with which :func:`sun_and_sky_sample` picks the unit direction
    ``d``: ``p_sun`` times the sun cone's uniform density plus ``1 - p_sun`` times the
    table ``p``'s (a cell's probability over its solid angle ``4 pi / (128 256)``)."""
    p_sun = params[_P_SUN]
    sky = p[_cell(dx, dy, dz)] * (_TABLE_H * _TABLE_W / (4.0 * math.pi))
    omc = params[_ONE_MINUS_COS]
    cone = 0.0
    if omc > 0.0 and _in_sun_cone(params, dx, dy, dz):
        cone = 1.0 / (2.0 * math.pi * omc)
    return p_sun * cone + (1.0 - p_sun) * sky


@njit
def sun_and_sky_sample(params, p, cdf, u1, u2):
    """A unit direction of density :func:`sun_and_sky_pdf` from ``u1, u2`` in [0, 1) ->
    ``(wx, wy, wz)``: ``u1 < p_sun`` picks the sun's cone (uniformly, ``u1`` rescaled),
    else a table cell by ``cdf`` (``u1`` rescaled again for the azimuth in the cell)."""
    u1 = kc.clamp_u(u1)
    u2 = kc.clamp_u(u2)
    p_sun = params[_P_SUN]
    if u1 < p_sun or p_sun >= 1.0:  # a uniform point of the sun's cone, in the sun's frame
        u0 = u1 / p_sun
        omc = params[_ONE_MINUS_COS]
        z = 1.0 - u0 * omc
        r = kc.safe_sqrt(u0 * omc * (1.0 + z))  # 1 - z^2 = (1 - z)(1 + z)
        phi = 2.0 * math.pi * u2
        lx = r * math.cos(phi)
        ly = r * math.sin(phi)
        s, t = _FRAME_S, _FRAME_T
        return (lx * params[s] + ly * params[t] + z * params[_SUN],
                lx * params[s + 1] + ly * params[t + 1] + z * params[_SUN + 1],
                lx * params[s + 2] + ly * params[t + 2] + z * params[_SUN + 2])
    uk = min(max((u1 - p_sun) / (1.0 - p_sun), 0.0), 1.0)
    k = min(np.searchsorted(cdf, uk, side="right"), len(p) - 1)
    lo = cdf[k - 1] if k > 0 else 0.0
    pk = p[k]
    du = min(max((uk - lo) / pk if pk > 0.0 else 0.5, 0.0), 1.0)
    j, i = k // _TABLE_W, k % _TABLE_W
    y = 1.0 - 2.0 * (j + u2) / _TABLE_H
    phi = ((i + du) / _TABLE_W - 0.5) * 2.0 * math.pi
    r = kc.safe_sqrt(1.0 - y * y)
    return r * math.sin(phi), y, -r * math.cos(phi)


# --- batch wrappers: the kernels over rows (the numpy API of SunAndSky) -----------------------


@njit(allocates=True)
def _radiance_rows(params, d, part):
    """Sky + sun, sky or sun (``part``) radiance of each row of ``d`` -> (n, 3)."""
    out = np.empty((d.shape[0], 3))
    for k in range(d.shape[0]):
        dx, dy, dz = d[k, 0], d[k, 1], d[k, 2]
        if part == _PART_SKY:
            r, g, b = _sky(params, dx, dy, dz)
        elif part == _PART_SUN:
            r, g, b = _sun(params, dx, dy, dz)
        else:
            r, g, b = sun_and_sky_eval(params, dx, dy, dz)
        out[k, 0], out[k, 1], out[k, 2] = r, g, b
    return out


@njit(allocates=True)
def _pdf_rows(params, p, d):
    """:func:`sun_and_sky_pdf` of each row of ``d`` -> (n,)."""
    out = np.empty(d.shape[0])
    for k in range(d.shape[0]):
        out[k] = sun_and_sky_pdf(params, p, d[k, 0], d[k, 1], d[k, 2])
    return out


@njit(allocates=True)
def _sample_rows(params, p, cdf, u):
    """:func:`sun_and_sky_sample` of each row of ``u`` -> (n, 3)."""
    out = np.empty((u.shape[0], 3))
    for k in range(u.shape[0]):
        out[k, 0], out[k, 1], out[k, 2] = sun_and_sky_sample(params, p, cdf, u[k, 0], u[k, 1])
    return out


def _rows(a, width: int) -> np.ndarray:
    """``a`` as a C-contiguous float64 (n, width) array (one compiled variant per kernel)."""
    return np.ascontiguousarray(np.asarray(a, dtype=np.float64).reshape(-1, width))


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
        Probability that :meth:`sample_direction` samples the sun.

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
        self._preetham = _preetham_constants(self._theta_sky, t)
        horizontal = np.array([self.sun_direction[0], 0.0, self.sun_direction[2]])
        hn = np.linalg.norm(horizontal)
        self._sky_sun = (self.sun_direction if elevation >= 0.0 or hn == 0.0
                         else horizontal / hn)
        fade = min(1.0, max(0.0, 1.0 - math.degrees(elevation) / TWILIGHT_END_DEG))
        # kcd/m^2 -> cd/m^2 -> RGB
        self._sky_factor = 1000.0 * scale * sky_scale * fade
        self._sun_frame = Frame.from_normal(self.sun_direction[None])
        self.ground_radiance = np.zeros(3)  # the quadrature below reads the upper hemisphere
        self.p_sun = 0.0  # set by _build_table (the sky alone does not read it)
        self.sky_irradiance = self._sky_horizontal_irradiance()
        sun_h = self.sun_irradiance * max(0.0, math.sin(elevation))
        self.ground_radiance = albedo * (sun_h + self.sky_irradiance) / math.pi
        self._build_table()

    # ------------------------------------------------------------------ kernels
    def kernel_params(self) -> np.ndarray:
        """The constants of this sky for :func:`sun_and_sky_eval`, :func:`sun_and_sky_pdf`
        and :func:`sun_and_sky_sample`: a float64 vector of :data:`PARAMS_SIZE` (layout in
        the comment above ``PARAMS_SIZE``); the kernels also take the table ``self._p`` and
        ``self._cdf``."""
        f = self._sun_frame
        params = np.concatenate([
            self.sun_direction, [self.cos_sun_radius, self._one_minus_cos], self.sun_radiance,
            self._sky_sun, [self._sky_factor], self.ground_radiance, [self.p_sun],
            f.s[0], f.t[0], self._preetham,
        ]).astype(np.float64)
        assert params.shape == (PARAMS_SIZE,)
        return params

    # ------------------------------------------------------------------ radiance
    def sky(self, d: Vec3) -> Rgb:
        """Radiance (n, 3) of the sky and the ground (no sun) along unit directions ``d``."""
        return _radiance_rows(self.kernel_params(), _rows(d, 3), _PART_SKY)

    def sun(self, d: Vec3) -> Rgb:
        """Radiance (n, 3) of the sun disk along unit directions ``d`` (0 below the horizon)."""
        return _radiance_rows(self.kernel_params(), _rows(d, 3), _PART_SUN)

    def eval(self, d: np.ndarray) -> np.ndarray:
        """Radiance (n, 3) seen along directions ``d`` (n, 3): sky or ground plus sun."""
        return _radiance_rows(self.kernel_params(), _rows(d, 3), _PART_ALL)

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
        """The sampling table ``_p``, ``_cdf`` (mean sky luminance of each cell plus 1 % of
        the average) and ``p_sun``."""
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

    def pdf(self, d: np.ndarray) -> np.ndarray:
        """Solid-angle density (n,) with which :meth:`sample_direction` picks unit
        directions ``d``."""
        return _pdf_rows(self.kernel_params(), self._p, _rows(d, 3))

    def sample_direction(self, u: np.ndarray) -> Vec3:
        """Directions (n, 3) distributed with density :meth:`pdf`, from ``u`` (n, 2) in [0, 1)."""
        return _sample_rows(self.kernel_params(), self._p, self._cdf, _rows(u, 2))
