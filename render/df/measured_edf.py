"""MDL ``df::measured_edf``: emission shaped by a measured light profile (an IES file).

MDL signature (1.1; ``tangent_u`` 1.2)::

    edf measured_edf(uniform light_profile profile, uniform float multiplier = 1.0,
                     uniform bool global_distribution = true,
                     uniform float3x3 global_frame = float3x3(1.0),
                     float3 tangent_u = state::texture_tangent_u(0),
                     uniform string handle = "");

Model.  The profile (:mod:`render.df._ies`, type C photometry) gives an intensity
``I(gamma, C)`` per direction: ``gamma`` the angle from the luminaire's nadir, which is the
emitting side's normal (local ``+z``), ``C`` the azimuth about it counter-clockwise from
``tangent_u`` (its part in the tangent plane).  With ``global_distribution = true``
(MDL's default) the profile's frame is fixed in object space instead: ``global_frame``
maps the profile's axes to object space (its column 2 is the nadir, column 0 ``C = 0``),
as ``spot_edf``'s.  The edf keeps the profile's shape and MDL's normalisation of the
other edfs (``∫ edf cos = multiplier`` over the front hemisphere), so
``material_emission.intensity`` stays the exitance::

    edf(wo) = multiplier I(gamma, C) / (Phi cos theta_o),   Phi = ∫_{gamma <= 90} I dw

and a small emitter of area ``A`` and intensity ``E`` sends ``E A multiplier I / Phi`` (W/sr)
toward each direction: the profile's distribution, scaled to its power.  ``Phi`` is the
closed-form flux of the bilinear interpolant over the front hemisphere; light the profile
sends above 90 degrees (behind the surface) is not emitted (MDL emits from the front only).
``I`` is bilinear in ``gamma`` and ``C`` between the file's angles.

Sampling draws from a continuous density bilinear in ``cos gamma`` and ``C`` between
nodes of a 48 x 72 grid (the intensity at the nodes, plus a floor): ``cos gamma`` from its
piecewise-linear marginal, then ``C`` from the piecewise-linear row at it, each by the
inverse of a quadratic; ``pdf`` is that density exactly, the weight ``eval cos / pdf``
(near ``multiplier``).

Departures from libbsdf: libbsdf evaluates the profile (no ``1/cos``, its own scale) and
emits nothing with ``global_distribution`` true (an unimplemented mode, as for
``spot_edf``); here the global mode is implemented as the spec describes, and the scale is
the material's intensity.
"""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np

from render.bsdf import Lobe
from render.df import _kernel_common as kc
from render.df._ies import IesError, LightProfile, profile_table, read_ies
from render.df._registry import Df, Node
from render.df._signature import REQUIRED, Param, Signature
from render.jit import njit
from render.program import TABLE, Program, ProgramEdf, leaf_program

__all__ = ["MeasuredEdf", "measured_edf", "SIGNATURE", "edf_eval_pdf", "edf_sample",
           "table_intensity", "IesError", "LightProfile", "read_ies"]

_IDENTITY = ((1.0, 0.0, 0.0), (0.0, 1.0, 0.0), (0.0, 0.0, 1.0))
SIGNATURE = Signature("edf", (
    Param("profile", "light_profile", REQUIRED, uniform=True),
    Param("multiplier", "float", 1.0, clamp=(0.0, None), uniform=True),
    Param("global_distribution", "bool", True, uniform=True),
    Param("global_frame", "float3x3", _IDENTITY, uniform=True),
    Param("tangent_u", "float3", "state::texture_tangent_u(0)"),
    Param("handle", "string", "", uniform=True),
), context=tuple(f"object_to_local_{i}{j}" for i in range(3) for j in range(3)))
"""``object_to_local_ij``: as :mod:`render.df.spot_edf` (the rotation from object space into
the lane's local frame, for the global mode)."""
_GLOBAL = SIGNATURE.offset("global_distribution")
_FRAME = SIGNATURE.offset("global_frame")
_TANGENT = SIGNATURE.offset("tangent_u")
O2L = SIGNATURE.offset("object_to_local_00")
_HEAD = 5
_TWO_PI = 2.0 * math.pi


@njit
def _find(T, lo, n, x):
    """The cell ``i`` with ``T[lo + i] <= x < T[lo + i + 1]`` (clamped to ``0 .. n - 2``)."""
    a, b = 0, n - 1
    while b - a > 1:
        m = (a + b) // 2
        if T[lo + m] <= x:
            a = m
        else:
            b = m
    return a


@njit
def table_intensity(T, t, gamma, phi):
    """The profile's intensity at vertical angle ``gamma`` and azimuth ``phi`` (radians),
    bilinear; 0 outside its vertical range."""
    nv, nh = int(T[t]), int(T[t + 1])
    v0 = t + _HEAD
    h0 = v0 + nv
    c0 = h0 + nh
    if gamma < T[v0] or gamma > T[v0 + nv - 1]:
        return 0.0
    phi = phi - _TWO_PI * math.floor(phi / _TWO_PI)
    i = _find(T, v0, nv, gamma)
    j = _find(T, h0, nh, phi)
    fv = min(max((gamma - T[v0 + i]) / (T[v0 + i + 1] - T[v0 + i]), 0.0), 1.0)
    fh = min(max((phi - T[h0 + j]) / (T[h0 + j + 1] - T[h0 + j]), 0.0), 1.0)
    a = T[c0 + i * nh + j] * (1.0 - fh) + T[c0 + i * nh + j + 1] * fh
    b = T[c0 + (i + 1) * nh + j] * (1.0 - fh) + T[c0 + (i + 1) * nh + j + 1] * fh
    return a * (1.0 - fv) + b * fv


@njit
def _frame(P, row, b):
    """The profile's axes in the local frame: ``(x, y, z)`` rows, ``z`` the nadir, ``x``
    toward ``C = 0``; ``valid`` False for a degenerate frame."""
    if P[row, b + _GLOBAL] == 0.0:
        zx, zy, zz = 0.0, 0.0, 1.0
        # tangent_u's part in the tangent plane
        xx, xy, xz, ok = kc.unitize(P[row, b + _TANGENT], P[row, b + _TANGENT + 1], 0.0)
        if not ok:
            xx, xy, xz = 1.0, 0.0, 0.0
    else:
        o = b + O2L
        f = b + _FRAME
        # A = object_to_local @ global_frame: column k is the profile's axis k
        zx = (P[row, o] * P[row, f + 2] + P[row, o + 1] * P[row, f + 5]
              + P[row, o + 2] * P[row, f + 8])
        zy = (P[row, o + 3] * P[row, f + 2] + P[row, o + 4] * P[row, f + 5]
              + P[row, o + 5] * P[row, f + 8])
        zz = (P[row, o + 6] * P[row, f + 2] + P[row, o + 7] * P[row, f + 5]
              + P[row, o + 8] * P[row, f + 8])
        xx = (P[row, o] * P[row, f] + P[row, o + 1] * P[row, f + 3]
              + P[row, o + 2] * P[row, f + 6])
        xy = (P[row, o + 3] * P[row, f] + P[row, o + 4] * P[row, f + 3]
              + P[row, o + 5] * P[row, f + 6])
        xz = (P[row, o + 6] * P[row, f] + P[row, o + 7] * P[row, f + 3]
              + P[row, o + 8] * P[row, f + 6])
        zx, zy, zz, ok = kc.unitize(zx, zy, zz)
        if not ok:
            return 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, False
        c = xx * zx + xy * zy + xz * zz
        xx, xy, xz, ok = kc.unitize(xx - c * zx, xy - c * zy, xz - c * zz)
        if not ok:
            return 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, False
    yx, yy, yz = zy * xz - zz * xy, zz * xx - zx * xz, zx * xy - zy * xx
    return xx, xy, xz, yx, yy, yz, zx, zy, zz, True


@njit
def _sampling(T, t):
    """``(m, q, offset of the node values)`` of the sampling density."""
    nv, nh = int(T[t]), int(T[t + 1])
    return int(T[t + 2]), int(T[t + 3]), t + _HEAD + nv + nh + nv * nh


@njit
def _sample_pdf(T, t, mu, phi):
    """The sampler's density (per solid angle) at ``mu = cos gamma`` and azimuth ``phi``:
    bilinear between its nodes, over its integral."""
    m, q, off = _sampling(T, t)
    phi = phi - _TWO_PI * math.floor(phi / _TWO_PI)
    x = min(max(mu, 0.0), 1.0) * m
    y = phi / _TWO_PI * q
    i = min(int(x), m - 1)
    j = min(int(y), q - 1)
    fx, fy = x - i, y - j
    a = T[off + i * (q + 1) + j] * (1.0 - fy) + T[off + i * (q + 1) + j + 1] * fy
    b = T[off + (i + 1) * (q + 1) + j] * (1.0 - fy) + T[off + (i + 1) * (q + 1) + j + 1] * fy
    return (a * (1.0 - fx) + b * fx) / T[off + (m + 1) * (q + 1) + m]


@njit
def _row(T, off, q, k, tm, j):
    """The density's node value at C node ``j`` on the row ``tm`` of band ``k``."""
    return T[off + k * (q + 1) + j] * (1.0 - tm) + T[off + (k + 1) * (q + 1) + j] * tm


@njit
def _linear(a, b, u):
    """``t`` in [0, 1] with ``F(t) = u`` for the density ``a (1 - t) + b t`` (a, b >= 0)."""
    s = a + b
    if not s > 0.0:
        return u
    return min(max(u * s / (a + math.sqrt(max(a * a + u * (b * b - a * a), 0.0))), 0.0), 1.0)


@njit
def edf_eval_pdf(P, row, b, flags, wox, woy, woz, T, t):
    """Emission per unit intensity toward ``wo`` and its density -> ``(e, e, e, pdf)``."""
    if not woz > kc.COS_ZERO:
        return 0.0, 0.0, 0.0, 0.0
    xx, xy, xz, yx, yy, yz, zx, zy, zz, ok = _frame(P, row, b)
    if not ok:
        return 0.0, 0.0, 0.0, 0.0
    dz = wox * zx + woy * zy + woz * zz
    if not dz > 0.0:
        return 0.0, 0.0, 0.0, 0.0
    dx = wox * xx + woy * xy + woz * xz
    dy = wox * yx + woy * yy + woz * yz
    gamma = math.acos(min(dz, 1.0))
    phi = math.atan2(dy, dx)
    e = T[t + 4] * table_intensity(T, t, gamma, phi) / woz
    if not e > 0.0:
        return 0.0, 0.0, 0.0, 0.0
    return e, e, e, _sample_pdf(T, t, min(dz, 1.0), phi)


@njit
def edf_sample(P, row, b, flags, u1, u2x, u2y, T, t):
    """A direction from the sampling density -> ``(wox, woy, woz, pdf, w, w, w)``
    (``u2y`` is not needed: the within-cell inverses reuse ``u1`` and ``u2x``)."""
    xx, xy, xz, yx, yy, yz, zx, zy, zz, ok = _frame(P, row, b)
    if not ok:
        return 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0
    m, q, off = _sampling(T, t)
    c0 = off + (m + 1) * (q + 1)
    u = kc.clamp_u(u1)
    # a band of mu by its running sum, then mu within it (the density is linear there)
    a, c = 0, m - 1
    while a < c:
        mid = (a + c) // 2
        if T[c0 + mid] <= u:
            a = mid + 1
        else:
            c = mid
    k = a
    lo = T[c0 + k - 1] if k > 0 else 0.0
    width = T[c0 + k] - lo
    u = min(max((u - lo) / width, 0.0), 1.0) if width > 0.0 else 0.5
    ra = rb = 0.0
    for j in range(q):
        ra += 0.5 * (T[off + k * (q + 1) + j] + T[off + k * (q + 1) + j + 1])
        rb += 0.5 * (T[off + (k + 1) * (q + 1) + j] + T[off + (k + 1) * (q + 1) + j + 1])
    tm = _linear(ra, rb, u)
    mu = (k + tm) / m
    # C: the row at mu, linear between its nodes; a cell by its share, then within it
    total = 0.0
    for j in range(q):
        total += 0.5 * (_row(T, off, q, k, tm, j) + _row(T, off, q, k, tm, j + 1))
    target = kc.clamp_u(u2x) * total
    acc = 0.0
    j = q - 1
    for jj in range(q):
        cell = 0.5 * (_row(T, off, q, k, tm, jj) + _row(T, off, q, k, tm, jj + 1))
        if target < acc + cell:
            j = jj
            break
        acc += cell
    wa, wb = _row(T, off, q, k, tm, j), _row(T, off, q, k, tm, j + 1)
    cell = 0.5 * (wa + wb)
    uc = min(max((target - acc) / cell, 0.0), 1.0) if cell > 0.0 else kc.clamp_u(u2y)
    phi = _TWO_PI * (j + _linear(wa, wb, uc)) / q
    s = math.sqrt(max(1.0 - mu * mu, 0.0))
    dx, dy, dz = s * math.cos(phi), s * math.sin(phi), mu
    wox = dx * xx + dy * yx + dz * zx
    woy = dx * xy + dy * yy + dz * zy
    woz = dx * xz + dy * yz + dz * zz
    e0, e1, e2, pdf = edf_eval_pdf(P, row, b, flags, wox, woy, woz, T, t)
    if not (pdf > 0.0 and e0 > 0.0):
        return 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0
    w = e0 * woz / pdf
    return wox, woy, woz, pdf, w, w, w


# --- the Python class ------------------------------------------------------------------

_TABLES: dict = {}


class MeasuredEdf(ProgramEdf):
    """``df::measured_edf`` over lanes: its kernels, run by :mod:`render.interpreter`.

    Parameters
    ----------
    profile : LightProfile, str or Path
        The light profile, or an IES file to read.
    multiplier : float
        Uniform, >= 0.
    global_distribution : bool
    global_frame : (3, 3)
        Row-major ``M[i][j]``; the profile's nadir is column 2.
    tangent_u : (3,) or (n, 3)
        In the local frame (``C = 0``; used by the local mode).
    object_to_local : (3, 3) or (n, 3, 3), optional
        The rotation from object space into the local frame (the global mode needs it).
    """

    mdl_name = "measured_edf"
    signature = SIGNATURE

    def __init__(self, profile, multiplier=1.0, global_distribution=True,
                 global_frame=_IDENTITY, tangent_u=(1.0, 0.0, 0.0), *, object_to_local=None):
        title = "df::measured_edf"
        if isinstance(profile, str | Path):
            profile = read_ies(profile)
        if not isinstance(profile, LightProfile):
            raise ValueError(f"{title}(profile) must be a light_profile (an IES file), got "
                             f"{type(profile).__name__}")
        mult = np.asarray(multiplier, dtype=np.float64)
        if mult.ndim != 0 or not np.isfinite(mult) or mult < 0:
            raise ValueError(f"{title}(multiplier) is uniform: one finite number >= 0, got "
                             f"{multiplier!r}")
        frame = np.asarray(global_frame, dtype=np.float64)
        if frame.shape != (3, 3) or not np.all(np.isfinite(frame)):
            raise ValueError(f"{title}: global_frame must be a finite 3x3 matrix (uniform), "
                             f"got shape {frame.shape}")
        if global_distribution:
            if object_to_local is None:
                raise ValueError(f"{title} with global_distribution = true needs "
                                 "object_to_local (material.shade passes it), or set "
                                 "global_distribution = false")
            if not np.any(frame[:, 2]):
                raise ValueError(f"{title}: global_frame maps +z to a zero vector (the "
                                 "profile's nadir); give a rotation")
        o2l = np.eye(3)[None] if object_to_local is None else np.asarray(
            object_to_local, dtype=np.float64).reshape(-1, 3, 3)
        values = {"multiplier": float(mult), "global_distribution": bool(global_distribution),
                  "global_frame": frame, "tangent_u": tangent_u}
        for i in range(3):
            for j in range(3):
                values[f"object_to_local_{i}{j}"] = o2l[:, i, j]
        key = id(profile)
        if key not in _TABLES or _TABLES[key][0] is not profile:
            _TABLES[key] = (profile, profile_table(profile, 1.0))
        table = _TABLES[key][1].copy()
        table[4] *= float(mult)
        prog = leaf_program("edf", NODE.op, SIGNATURE, values, Lobe.NONE, title)
        code = prog.code.copy()
        code[0, TABLE] = 0
        ProgramEdf.__init__(self, Program("edf", code, prog.kids, prog.frames, prog.blocks, table,
                                          prog.lobes))
        self.profile = profile


measured_edf = MeasuredEdf
NODE = Node("measured_edf", "edf", "leaf", SIGNATURE, edf_eval_pdf=edf_eval_pdf,
            edf_sample=edf_sample)
DF = Df("measured_edf", SIGNATURE, (NODE,), constructor=MeasuredEdf)
