"""MDL's ``::math`` module over lanes (the whole function set of MDL 1.7).

Each function takes and returns lane values (:mod:`mdl.lanes`): a scalar is ``(L,)``,
a vector or color ``(L, n)``, a matrix ``(L, C, R)``; overloads that differ only in
type share one implementation.  The front end folds constant calls with these
functions and the generated code of the back end calls them, so each exists once.

Numerics.  IEEE-754 double arithmetic throughout (MDL's ``float`` is held in 64
bits).  Where MDL (or mathematics) defines a finite value that the naive formula
loses, the value is kept: ``length``, ``distance`` and ``normalize`` scale by the
largest component, so ``length(float3(1e200))`` is ``1.7e200`` (not infinity) and
``normalize`` of a vector of length ``1e-200`` is unit; ``smoothstep(a, a, x)`` is the
step at ``a``; ``atan2(0, 0)`` is 0; ``pow(0, 0)`` is 1; ``round`` rounds halves away
from zero (C's ``round``, not numpy's half-to-even).  Outside a function's domain the
result is IEEE's (``sqrt(-1)``, ``log(-1)`` and ``fmod(x, 0)`` are NaN, ``log(0)`` is
``-inf``), except ``acos``/``asin``, which clamp their argument to [-1, 1] (so rounding
just past 1 does not give NaN), and ``normalize(0)``, which is the zero vector.

Spectral functions work on the workbench's linear RGB colour: ``blackbody`` integrates
Planck's law against Wyman, Sloan and Shirley's (2013) analytic fit of the CIE 1931
colour-matching functions (within about 1 % of the tabulated functions), converted to
linear sRGB and scaled to luminance 1; ``eval_at_wavelength`` and
``emission_color(wavelengths, amplitudes)`` use a box basis (blue below 490 nm, green
to 580 nm, red above); ``max_value_wavelength``/``min_value_wavelength`` return the
centre of the largest/smallest channel's band (465, 535, 680 nm).  ``DX``/``DY`` (screen
derivatives, experimental in MDL) are 0: the path tracer has no ray differentials.

Examples
--------
>>> import numpy as np
>>> big = 2.0 ** 600  # its square overflows
>>> length(np.array([[3 * big, 4 * big, 0.0]])).tolist() == [5 * big]
True
>>> round_(np.array([0.5, -0.5, 2.5, 0.49999999999999994])).tolist()
[1.0, -1.0, 3.0, 0.0]
>>> smoothstep(np.array([1.0, 1.0]), np.array([1.0, 1.0]), np.array([0.5, 1.0])).tolist()
[0.0, 1.0]
"""

from __future__ import annotations

import math

import numpy as np

__all__ = [
    "PI", "TWO_PI", "HALF_PI", "FUNCTIONS",
    "abs_", "acos", "all_", "any_", "asin", "atan", "atan2", "average", "ceil", "clamp", "cos",
    "cross", "degrees", "distance", "dot", "eval_at_wavelength", "exp", "exp2", "floor",
    "fmod", "frac", "isnan", "isfinite", "length", "lerp", "log", "log2", "log10",
    "luminance", "max_", "max_value", "max_value_wavelength", "min_", "min_value",
    "min_value_wavelength", "modf", "normalize", "pow_", "radians", "round_", "rsqrt",
    "saturate", "sign", "sin", "sincos", "smoothstep", "sqrt", "step", "tan", "transpose",
    "blackbody", "emission_color", "cosh", "sinh", "tanh", "float_bits_to_int",
    "int_bits_to_float", "DX", "DY",
]

PI = math.pi
TWO_PI = 2.0 * math.pi
HALF_PI = 0.5 * math.pi
#: math::luminance of linear RGB (Rec. 709 primaries; the render core's LUM_*)
LUMINANCE = np.array([0.212671, 0.715160, 0.072169])


def _pair(a, b):
    a, b = np.asarray(a), np.asarray(b)
    if a.ndim < b.ndim:
        a = a.reshape(a.shape + (1,) * (b.ndim - a.ndim))
    elif b.ndim < a.ndim:
        b = b.reshape(b.shape + (1,) * (a.ndim - b.ndim))
    return a, b


def _quiet(f):
    def g(*args):
        with np.errstate(all="ignore"):
            return f(*args)
    g.__name__ = f.__name__
    g.__doc__ = f.__doc__
    return g


# --------------------------------------------------------------------------- element-wise
def abs_(a):
    if a.dtype == np.int32:
        return np.abs(a.astype(np.int64)).astype(np.int32)  # abs(INT_MIN) wraps, as in C
    return np.abs(a)


@_quiet
def acos(a):
    return np.arccos(np.clip(a, -1.0, 1.0))


@_quiet
def asin(a):
    return np.arcsin(np.clip(a, -1.0, 1.0))


@_quiet
def atan(a):
    return np.arctan(a)


@_quiet
def atan2(y, x):
    y, x = _pair(y, x)
    return np.arctan2(y, x)


@_quiet
def cos(a):
    return np.cos(a)


@_quiet
def sin(a):
    return np.sin(a)


@_quiet
def tan(a):
    return np.tan(a)


@_quiet
def cosh(a):
    return np.cosh(a)


@_quiet
def sinh(a):
    return np.sinh(a)


@_quiet
def tanh(a):
    return np.tanh(a)


@_quiet
def exp(a):
    return np.exp(a)


@_quiet
def exp2(a):
    return np.exp2(a)


@_quiet
def log(a):
    return np.log(a)


@_quiet
def log2(a):
    return np.log2(a)


@_quiet
def log10(a):
    return np.log10(a)


@_quiet
def sqrt(a):
    return np.sqrt(a)


@_quiet
def rsqrt(a):
    return 1.0 / np.sqrt(a)


def ceil(a):
    return np.ceil(a)


def floor(a):
    return np.floor(a)


@_quiet
def frac(a):
    """``a - floor(a)``, in [0, 1] (a negative ``a`` within half an ULP of an integer
    rounds to 1.0)."""
    return a - np.floor(a)


@_quiet
def fmod(a, b):
    a, b = _pair(a, b)
    return np.fmod(a, b)


def round_(a):
    """Round to the nearest integer, halves away from zero (C's ``round``)."""
    t = np.trunc(a)
    with np.errstate(invalid="ignore"):
        up = np.abs(a - t) >= 0.5
    return np.where(up, t + np.sign(a), t)


def degrees(a):
    return a * (180.0 / math.pi)


def radians(a):
    return a * (math.pi / 180.0)


def saturate(a):
    return np.minimum(np.maximum(a, 0.0), 1.0)


def sign(a):
    if a.dtype == np.int32:
        return np.sign(a).astype(np.int32)
    return np.sign(a)


def step(a, b):
    """0 where ``b < a``, else 1 (MDL's edge first)."""
    a, b = _pair(a, b)
    return np.where(b < a, 0.0, 1.0)


def min_(a, b):
    a, b = _pair(a, b)
    return np.minimum(a, b)


def max_(a, b):
    a, b = _pair(a, b)
    return np.maximum(a, b)


def clamp(a, lo, hi):
    """``min(max(a, lo), hi)`` (so ``hi`` wins when ``lo > hi``)."""
    return min_(max_(a, lo), hi)


@_quiet
def pow_(a, b):
    a, b = _pair(a, b)
    if a.dtype == np.int32 and np.asarray(b).dtype == np.int32:
        out = np.zeros(np.broadcast(a, b).shape, dtype=np.int64)
        aa, bb = np.broadcast_arrays(a.astype(np.int64), b.astype(np.int64))
        pos = bb >= 0
        out[pos] = np.power(aa[pos], bb[pos])
        # negative exponents: 1 / a^-b truncated (1 for a = 1, +-1 for a = -1, else 0)
        neg = ~pos
        out[neg] = np.where(aa[neg] == 1, 1, np.where(aa[neg] == -1,
                                                      np.where(bb[neg] % 2 == 0, 1, -1), 0))
        return out.astype(np.int32)
    return np.power(np.asarray(a, dtype=np.float64), b)


def lerp(a, b, t):
    a, ta = _pair(a, t)
    b, tb = _pair(b, t)
    return a * (1.0 - ta) + b * tb


@_quiet
def smoothstep(a, b, x):
    """Hermite step from ``a`` to ``b`` (the step at ``a`` when ``a == b``)."""
    a, x = _pair(a, x)
    b, x = _pair(b, x)
    width = b - a
    safe = np.where(width == 0.0, 1.0, width)
    t = np.clip((x - a) / safe, 0.0, 1.0)
    t = np.where(width == 0.0, np.where(x < a, 0.0, 1.0), t)
    return t * t * (3.0 - 2.0 * t)


def isnan(a):
    return np.isnan(a)


def isfinite(a):
    return np.isfinite(a)


def all_(a):
    return np.all(a, axis=-1) if a.ndim > 1 else a.astype(bool)


def any_(a):
    return np.any(a, axis=-1) if a.ndim > 1 else a.astype(bool)


# --------------------------------------------------------------------------- vectors
def average(a):
    return a.mean(axis=-1) if a.ndim > 1 else a


def max_value(a):
    return a.max(axis=-1) if a.ndim > 1 else a


def min_value(a):
    return a.min(axis=-1) if a.ndim > 1 else a


def dot(a, b):
    a, b = _pair(a, b)
    return (a * b).sum(axis=-1) if a.ndim > 1 else a * b


def cross(a, b):
    a, b = np.broadcast_arrays(a, b)
    return np.cross(a, b)


@_quiet
def length(a):
    """Euclidean length, without overflow or underflow in between."""
    if a.ndim == 1:
        return np.abs(a)
    big = np.max(np.abs(a), axis=-1)
    scale = np.where((big > 0) & np.isfinite(big), big, 1.0)
    return scale * np.sqrt(np.sum((a / scale[..., None]) ** 2, axis=-1))


def distance(a, b):
    a, b = np.broadcast_arrays(*_pair(a, b))
    return length(a - b)


@_quiet
def normalize(a):
    """``a / length(a)`` (scaled first: tiny and huge vectors are fine); 0 for 0."""
    if a.ndim == 1:
        return np.where(a == 0, 0.0, np.sign(a))
    big = np.max(np.abs(a), axis=-1, keepdims=True)
    scale = np.where(big > 0, big, 1.0)
    s = a / scale
    n = np.sqrt(np.sum(s * s, axis=-1, keepdims=True))
    return np.where(n > 0, s / np.where(n > 0, n, 1.0), 0.0)


def luminance(a):
    return a @ LUMINANCE


def transpose(m):
    return np.swapaxes(m, -1, -2)


def modf(a):
    """``[integral part, fractional part]``, both with the sign of ``a``."""
    with np.errstate(invalid="ignore"):
        frac_part, int_part = np.modf(a)
    return np.stack([int_part, frac_part], axis=1)


@_quiet
def sincos(a):
    """``[sin(a), cos(a)]``."""
    return np.stack([np.sin(a), np.cos(a)], axis=1)


def float_bits_to_int(a):
    """The bits of ``a`` as a 32-bit float, read as an int."""
    return a.astype(np.float32).view(np.int32)


def int_bits_to_float(a):
    """The bits of the int ``a`` read as a 32-bit float."""
    return a.astype(np.int32).view(np.float32).astype(np.float64)


def DX(a):  # noqa: N802 - MDL's name
    return np.zeros_like(a)


def DY(a):  # noqa: N802
    return np.zeros_like(a)


# --------------------------------------------------------------------------- spectra
_BANDS = np.array([[580.0, 780.0], [490.0, 580.0], [380.0, 490.0]])  # r, g, b (nm)
_BAND_CENTRES = np.array([680.0, 535.0, 465.0])


def eval_at_wavelength(c, wavelength):
    """The RGB colour's value at ``wavelength`` (nm) on a box basis: its red, green or
    blue component; 0 outside 380-780 nm."""
    w = np.asarray(wavelength, dtype=np.float64)
    out = np.zeros(np.broadcast(c[..., 0], w).shape)
    for k in range(3):
        lo, hi = _BANDS[k]
        inside = (w >= lo) & ((w < hi) | ((k == 0) & (w <= hi)))
        out = np.where(inside, c[..., k], out)
    return out


def max_value_wavelength(c):
    return _BAND_CENTRES[np.argmax(c, axis=-1)]


def min_value_wavelength(c):
    return _BAND_CENTRES[np.argmin(c, axis=-1)]


def _g(x, mu, s1, s2):
    s = np.where(x < mu, s1, s2)
    return np.exp(-0.5 * ((x - mu) / s) ** 2)


def _cie_xyz(w):
    """CIE 1931 colour matching functions, Wyman-Sloan-Shirley multi-lobe fit."""
    x = (1.056 * _g(w, 599.8, 37.9, 31.0) + 0.362 * _g(w, 442.0, 16.0, 26.7)
         - 0.065 * _g(w, 501.1, 20.4, 26.2))
    y = 0.821 * _g(w, 568.8, 46.9, 40.5) + 0.286 * _g(w, 530.9, 16.3, 31.1)
    z = 1.217 * _g(w, 437.0, 11.8, 36.0) + 0.681 * _g(w, 459.0, 26.0, 13.8)
    return np.stack([x, y, z], axis=-1)


_XYZ_TO_RGB = np.array([[3.2404542, -1.5371385, -0.4985314],
                        [-0.9692660, 1.8760108, 0.0415560],
                        [0.0556434, -0.2040259, 1.0572252]])
_WAVELENGTHS = np.linspace(380.0, 780.0, 401)
_CMF = _cie_xyz(_WAVELENGTHS)


def _spectrum_to_rgb(spd):
    """(..., 401) spectral values at :data:`_WAVELENGTHS` -> linear sRGB."""
    xyz = spd @ _CMF
    return xyz @ _XYZ_TO_RGB.T


@_quiet
def blackbody(temperature):
    """Linear sRGB colour of a black body at ``temperature`` kelvin, luminance 1
    (``color(0)`` at or below 0 K)."""
    t = np.asarray(temperature, dtype=np.float64)
    lam = _WAVELENGTHS * 1e-9
    c2 = 1.4387769e-2  # h c / k
    tt = np.where(t > 0, t, 1.0)[..., None]
    spd = 1.0 / (lam ** 5 * np.expm1(c2 / (lam * tt)))
    rgb = _spectrum_to_rgb(spd)
    lum = rgb @ LUMINANCE
    rgb = rgb / np.where(lum > 0, lum, 1.0)[..., None]
    return np.where((t > 0)[..., None], np.maximum(rgb, 0.0), 0.0)


def emission_color(wavelengths, amplitudes=None):
    """``emission_color(float[<N>] wavelengths, float[N] amplitudes)``: the spectrum
    (linear between samples) on the box basis; ``emission_color(color)`` is the colour."""
    if amplitudes is None:
        return wavelengths
    w = np.asarray(wavelengths, dtype=np.float64)
    a = np.asarray(amplitudes, dtype=np.float64)
    out = np.zeros(w.shape[:-1] + (3,))
    grid = np.linspace(380.0, 780.0, 401)
    for lane in np.ndindex(w.shape[:-1]):
        order = np.argsort(w[lane])
        spd = np.interp(grid, w[lane][order], a[lane][order], left=0.0, right=0.0)
        for k in range(3):
            lo, hi = _BANDS[k]
            inside = (grid >= lo) & (grid <= hi)
            out[lane + (k,)] = spd[inside].mean()
    return out


#: MDL name -> implementation (overloads share one)
FUNCTIONS = {
    "abs": abs_, "acos": acos, "all": all_, "any": any_, "asin": asin, "atan": atan,
    "atan2": atan2, "average": average, "ceil": ceil, "clamp": clamp, "cos": cos,
    "cross": cross, "degrees": degrees, "distance": distance, "dot": dot,
    "eval_at_wavelength": eval_at_wavelength, "exp": exp, "exp2": exp2, "floor": floor,
    "fmod": fmod, "frac": frac, "isnan": isnan, "isfinite": isfinite, "length": length,
    "lerp": lerp, "log": log, "log2": log2, "log10": log10, "luminance": luminance,
    "max": max_, "max_value": max_value, "max_value_wavelength": max_value_wavelength,
    "min": min_, "min_value": min_value, "min_value_wavelength": min_value_wavelength,
    "modf": modf, "normalize": normalize, "pow": pow_, "radians": radians, "round": round_,
    "rsqrt": rsqrt, "saturate": saturate, "sign": sign, "sin": sin, "sincos": sincos,
    "smoothstep": smoothstep, "sqrt": sqrt, "step": step, "tan": tan,
    "transpose": transpose, "blackbody": blackbody, "emission_color": emission_color,
    "cosh": cosh, "sinh": sinh, "tanh": tanh, "float_bits_to_int": float_bits_to_int,
    "int_bits_to_float": int_bits_to_float, "DX": DX, "DY": DY,
}
