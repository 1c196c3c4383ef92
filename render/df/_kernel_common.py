"""Scalar numba helpers shared by the df kernels: orientation, Fresnel, refraction, warps.

One lane at a time: the kernels call these, and Python code that needs the same maths
(the tests included) calls them directly, a lane at a time.  Every helper is total: any
finite input gives a finite output, never NaN, never an exception (each special case is
guarded explicitly).

Conventions (:mod:`render.frame`): the local frame has ``+z`` along the shading normal,
``+z`` is the outside; ``wo`` points toward the viewer, ``wi`` toward the light.  The
tolerances are :data:`render.numerics.TOL`'s, read at import (numba freezes module
globals; :mod:`render.jit` keys its cache to every source file, so an edit of ``TOL``
recompiles).

Examples
--------
>>> F, ct = fresnel_dielectric(1.0, 1.5)
>>> round(F, 6), ct
(0.04, -1.0)
>>> [round(fresnel_dielectric(c, 1.5)[0], 4) for c in (0.3, -0.3)]  # oblique, TIR inside
[0.2078, 1.0]
>>> cosine_hemisphere(0.5, 0.5)
(0.0, 0.0, 1.0)
>>> flip, z = orient(-0.5)
>>> flip, z, mirror_z(0.8, flip)
(True, 0.5, -0.8)
"""

from __future__ import annotations

import math

import numpy as np

from render.bsdf import Lobe
from render.jit import njit
from render.numerics import ONE_MINUS_EPS as _ONE_MINUS_EPS
from render.numerics import TOL

__all__ = [
    "COS_ZERO",
    "ROUGHNESS_MIN",
    "IOR_DELTA_MIN",
    "SPREAD_MIN",
    "UNIT_MIN",
    "ONE_MINUS_EPS",
    "PI",
    "INV_PI",
    "LOBE_DIFFUSE_REFLECTION",
    "LOBE_DIFFUSE_TRANSMISSION",
    "LOBE_GLOSSY_REFLECTION",
    "LOBE_GLOSSY_TRANSMISSION",
    "LOBE_SPECULAR_REFLECTION",
    "LOBE_SPECULAR_TRANSMISSION",
    "clamp_u",
    "safe_sqrt",
    "dot3",
    "unitize",
    "orient",
    "mirror_z",
    "reflect_z",
    "reflect",
    "refract",
    "fresnel_dielectric",
    "fresnel_dielectric3",
    "ior_pair",
    "cosine_hemisphere",
    "frame_from_normal",
    "frame_from_normal_tangent",
    "frames_from_normal_tangent",
    "tangent_axes",
]

# --- constants (module floats: numba freezes them into the machine code) ------------------
COS_ZERO = float(TOL.cos_zero)
ROUGHNESS_MIN = float(TOL.roughness_min)
IOR_DELTA_MIN = float(TOL.ior_delta_min)
SPREAD_MIN = float(TOL.spread_min)
UNIT_MIN = float(TOL.unit_min)
ONE_MINUS_EPS = float(_ONE_MINUS_EPS)
PI = float(np.pi)
#: ``1 / pi``
INV_PI = 1.0 / PI
_QUARTER_PI = PI / 4.0

#: :class:`render.bsdf.Lobe` flag values as ints (a sample kernel's ``lobe``)
LOBE_DIFFUSE_REFLECTION = int(Lobe.DIFFUSE_REFLECTION)
LOBE_DIFFUSE_TRANSMISSION = int(Lobe.DIFFUSE_TRANSMISSION)
LOBE_GLOSSY_REFLECTION = int(Lobe.GLOSSY_REFLECTION)
LOBE_GLOSSY_TRANSMISSION = int(Lobe.GLOSSY_TRANSMISSION)
LOBE_SPECULAR_REFLECTION = int(Lobe.SPECULAR_REFLECTION)
LOBE_SPECULAR_TRANSMISSION = int(Lobe.SPECULAR_TRANSMISSION)


# --- scalars ----------------------------------------------------------------------------


@njit
def clamp_u(u):
    """A uniform variate clamped into ``[0, ONE_MINUS_EPS]`` (``render.bsdf.check_samples``).

    Sample kernels clamp their variates so that any finite input stays safe
    (``log1p(-u)`` needs ``u < 1``).
    """
    if u < 0.0:
        return 0.0
    if u > ONE_MINUS_EPS:
        return ONE_MINUS_EPS
    return u


@njit
def safe_sqrt(x):
    """``sqrt(max(x, 0))``: a square that rounding pushed slightly below 0 gives 0."""
    return math.sqrt(max(x, 0.0))


@njit
def dot3(ax, ay, az, bx, by, bz):
    """``a . b``, summed as ``(x + z) + y`` (numpy einsum's order, kept since the kernels
    were ported from numpy)."""
    return ax * bx + az * bz + ay * by


@njit
def unitize(x, y, z):
    """One vector normalised -> ``(ux, uy, uz, valid)``.

    A vector of ordinary length is divided by its length at once; a tiny or huge one is
    scaled by its largest component first (no overflow or underflow of the squared
    length); a vector whose largest component is ``<= UNIT_MIN`` gives ``(0, 0, 0, False)``.
    """
    s = x * x + y * y + z * z
    if s > 1e-280 and s < 1e280:  # no under- or overflow: one root, one division
        inv = 1.0 / math.sqrt(s)
        return x * inv, y * inv, z * inv, True
    scale = max(max(abs(x), abs(y)), abs(z))
    if not scale > UNIT_MIN:
        return 0.0, 0.0, 0.0, False
    wx = x / scale
    wy = y / scale
    wz = z / scale
    length = math.sqrt(dot3(wx, wy, wz, wx, wy, wz))
    return wx / length, wy / length, wz / length, True


# --- two-sidedness and mirrors ------------------------------------------------------------


@njit
def orient(woz):
    """libbsdf's normal flip for one lane -> ``(flip, |woz|)``.

    ``flip`` is ``woz < 0``: the lane is mirrored through the tangent plane so that
    ``wo.z >= 0``.  Mirror the other directions of the lane with :func:`mirror_z`
    (``wi`` before evaluating, a sampled ``wi`` after sampling).
    """
    if woz < 0.0:
        return True, -woz
    return False, woz


@njit
def mirror_z(z, flip):
    """``-z`` where ``flip``, else ``z`` (:func:`render.frame.mirror_z` of one component)."""
    return -z if flip else z


@njit
def reflect_z(x, y, z):
    """The mirror direction about the normal ``+z``: ``(-x, -y, z)``."""
    return -x, -y, z


@njit
def reflect(kx, ky, kz, mx, my, mz):
    """``2 (k.m) m - k``: ``k`` mirrored about the unit normal ``m`` (both point away)."""
    c2 = 2.0 * dot3(kx, ky, kz, mx, my, mz)
    return c2 * mx - kx, c2 * my - ky, c2 * mz - kz


@njit
def refract(kx, ky, kz, mx, my, mz, b):
    """``k`` refracted through the interface with unit normal ``m`` -> ``(x, y, z, tir)``.

    Parameters
    ----------
    kx, ky, kz : float
        Unit direction pointing away from the surface, ``k . m >= 0``.
    mx, my, mz : float
        Unit (micro)normal on ``k``'s side.
    b : float
        ``ior on k's side / ior on the far side``.

    Returns
    -------
    x, y, z : float
        The refracted direction (pointing away on the far side); under total internal
        reflection the mirror direction ``2 c m - k`` instead.
    tir : bool
    """
    c = dot3(kx, ky, kz, mx, my, mz)
    s2 = b * b * max(1.0 - c * c, 0.0)
    if s2 > 1.0:
        c2 = 2.0 * c
        return c2 * mx - kx, c2 * my - ky, c2 * mz - kz, True
    ct = math.sqrt(max(1.0 - s2, 0.0))
    d = b * c - ct
    return -b * kx + d * mx, -b * ky + d * my, -b * kz + d * mz, False


# --- Fresnel and the IOR pair ---------------------------------------------------------------


@njit
def fresnel_dielectric(cos_theta_i, eta):
    """Unpolarised dielectric Fresnel reflectance and the transmitted cosine -> ``(F,
    cos_theta_t)`` (libbsdf's ``ior_fresnel`` with the special cases made explicit).

    Parameters
    ----------
    cos_theta_i : float
        Cosine to the normal; negative: the light arrives from the ``-z`` side.
    eta : float
        ``ior(-z side) / ior(+z side)``, inverted for ``cos_theta_i < 0``.

    Returns
    -------
    F : float
        Unpolarised reflectance in [0, 1]; exactly 0 at an index match (``eta == 1``,
        even at grazing incidence), 1 under total internal reflection.
    cos_theta_t : float
        Transmitted cosine, sign opposite to ``cos_theta_i`` (0 under TIR).
    """
    outside = cos_theta_i >= 0.0
    e = eta if outside else 1.0 / eta
    c = min(abs(cos_theta_i), 1.0)
    ct2 = 1.0 - (1.0 - c * c) / (e * e)
    tir = ct2 <= 0.0
    ct = math.sqrt(max(ct2, 0.0))
    den_s = c + e * ct
    den_p = e * c + ct
    if den_s > 0.0 and den_p > 0.0:
        rs = (c - e * ct) / den_s
        rp = (e * c - ct) / den_p
        F = 0.5 * (rs * rs + rp * rp)
    else:
        F = 1.0
    if e == 1.0:
        F = 0.0
        ct = c
    elif tir:
        F = 1.0
        ct = 0.0
    F = min(max(F, 0.0), 1.0)
    return F, (-ct if outside else ct)


@njit
def fresnel_dielectric3(cos_theta_i, eta0, eta1, eta2):
    """:func:`fresnel_dielectric` per colour channel (a colour IOR) -> ``(F0, F1, F2)``."""
    f0, _ = fresnel_dielectric(cos_theta_i, eta0)
    f1, _ = fresnel_dielectric(cos_theta_i, eta1)
    f2, _ = fresnel_dielectric(cos_theta_i, eta2)
    return f0, f1, f2


@njit
def ior_pair(ior_outside, ior_inside, flip, thin_walled, glossy):
    """The IORs on ``wo``'s side and on the far side -> ``(eta1, eta2)``.

    ``+z`` is the outside.  Lanes viewed from below (``flip``) swap the pair, except on
    thin-walled surfaces, where both sides see ``(ior_outside, ior_inside)`` (libbsdf is
    given ``ior1 = 1, ior2 = material.ior`` for every thin-walled hit).  With ``glossy``
    the inside is first pushed ``IOR_DELTA_MIN`` away from the outside, before orienting,
    so both sides see the same interface (libbsdf: at an exact match the transmitted lobe
    would be a delta; an exact match makes the inside the denser side).
    """
    i = ior_inside
    if glossy:
        d = ior_inside - ior_outside
        if abs(d) < IOR_DELTA_MIN:
            i = ior_outside + (-IOR_DELTA_MIN if d < 0.0 else IOR_DELTA_MIN)
    if flip and not thin_walled:
        return i, ior_outside
    return ior_outside, i


# --- warps and frames --------------------------------------------------------------------


@njit
def cosine_hemisphere(u0, u1):
    """A cosine-weighted direction on the ``+z`` hemisphere from ``u0, u1`` in [0, 1)
    -> ``(x, y, z)`` (Malley's method).

    Shirley–Chiu concentric map of the square onto the unit disk (area-preserving:
    ``(x, y)`` is uniform on the disk), lifted to the hemisphere (density ``z / pi``).
    """
    a = 2.0 * u0 - 1.0
    b = 2.0 * u1 - 1.0
    if abs(a) > abs(b):
        r = a
        phi = _QUARTER_PI * (b / (a if a != 0.0 else 1.0))
    else:
        r = b
        phi = 2.0 * _QUARTER_PI - _QUARTER_PI * (a / (b if b != 0.0 else 1.0))
    x = r * math.cos(phi)
    y = r * math.sin(phi)
    return x, y, math.sqrt(max(1.0 - x * x - y * y, 0.0))


@njit
def frame_from_normal(nx, ny, nz):
    """:meth:`render.frame.Frame.from_normal` of one unit normal -> ``(sx, sy, sz, tx, ty, tz)``.

    Branch-free orthonormal basis (Duff et al. 2017); ``(s, t, n)`` is right-handed.
    A local vector ``v`` is ``(v0 s + v1 t) + v2 n`` in the frame's space.
    """
    sign = 1.0 if nz >= 0.0 else -1.0
    a = -1.0 / (sign + nz)
    b = nx * ny * a
    return (1.0 + sign * (nx * nx) * a, sign * b, -sign * nx,
            b, sign + (ny * ny) * a, -ny)


@njit
def frame_from_normal_tangent(nx, ny, nz, tx, ty, tz):
    """:meth:`render.frame.Frame.from_normal_tangent` of one unit normal and a tangent
    -> ``(sx, sy, sz, tx, ty, tz)``: ``s`` along the tangent projected into the tangent
    plane (Gram–Schmidt), ``t = n x s``; :func:`frame_from_normal`'s ``s`` where the
    tangent is zero or along ``n`` (its projection no longer than 1e-8 of it: rounding
    noise).  Only the tangent's direction counts: a huge one is scaled down first, so
    that its square does not overflow."""
    m = max(max(abs(tx), abs(ty)), abs(tz))
    if m > 1e150:
        tx, ty, tz = tx / m, ty / m, tz / m
    c = dot3(tx, ty, tz, nx, ny, nz)
    px, py, pz = tx - c * nx, ty - c * ny, tz - c * nz
    sx, sy, sz, ok = unitize(px, py, pz)
    if not (ok and px * px + py * py + pz * pz > 1e-16 * (tx * tx + ty * ty + tz * tz)):
        sx, sy, sz, _, _, _ = frame_from_normal(nx, ny, nz)
    return sx, sy, sz, ny * sz - nz * sy, nz * sx - nx * sz, nx * sy - ny * sx


@njit
def frames_from_normal_tangent(n, tu, s, t):
    """:func:`frame_from_normal_tangent` of rows ``n``, ``tu`` (n, 3) into ``s``, ``t``."""
    for i in range(n.shape[0]):
        s[i, 0], s[i, 1], s[i, 2], t[i, 0], t[i, 1], t[i, 2] = frame_from_normal_tangent(
            n[i, 0], n[i, 1], n[i, 2], tu[i, 0], tu[i, 1], tu[i, 2])


@njit
def tangent_axes(tx, ty, tz):
    """The anisotropy axes in the local frame from one ``tangent_u`` -> ``(tx, ty, valid)``
    (libbsdf's convention; ``roughness_u`` acts along ``t``).

    The anisotropy axis ``t = (tx, ty, 0)`` is ``tangent_u`` projected into the tangent
    plane and normalised (``b = (ty, -tx, 0)``); ``valid`` is False (and ``t = +x``)
    where ``tangent_u`` is parallel to the normal (libbsdf: the lobe absorbs).
    """
    length = math.hypot(tx, ty)
    full = math.hypot(length, tz)  # no overflow for huge tangents
    if length > 1e-8 * max(full, UNIT_MIN):
        return tx / length, ty / length, True
    return 1.0, 0.0, False
