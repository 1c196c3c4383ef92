"""MDL ``df::measured_bsdf``: a bsdf tabulated from a measurement (an MBSDF file).

MDL signature (1.1)::

    bsdf measured_bsdf(uniform bsdf_measurement measurement, uniform float multiplier = 1.0,
                       uniform scatter_mode mode = scatter_reflect, uniform string handle = "");

Model (libbsdf, ``reference/mdl-distribution-functions.md`` §2.9): the isotropic
measured BSDF ``f(theta_i, theta_o, phi)`` of the file's reflection (BRDF) and
transmission (BTDF) blocks (:mod:`render.df._mbsdf`: trilinear between the grid's
steps), with ``theta_o`` the angle of ``wo``, ``theta_i`` that of ``wi`` (from the far side
for transmission) and ``phi`` their azimuth difference folded into [0, pi]::

    eval = scale f |wi.z|,    scale = min(max(multiplier, 0), 1 / max_albedo)

``max_albedo`` is the largest albedo (over ``theta_o`` and channels) of each part the mode
uses, so a measurement never reflects more than it receives whatever the multiplier
(libbsdf).  ``scatter_reflect`` uses the BRDF only, ``scatter_transmit`` the BTDF only,
``scatter_reflect_transmit`` both.  Reflection is not assumed reciprocal (measurements
need not be).

Sampling (as libbsdf, CDF sampling; the details are ours): the part in proportion to
its albedo at ``theta_o``, a ``theta_o`` grid node by its linear-interpolation weight, a
cell of the ``(theta_i, phi)`` grid from that node's CDF of ``f cos`` (the interpolant
integrated per cell), then a direction uniform in solid angle within the cell, either
sign of ``phi``.  ``pdf`` is that mixture's density exactly; the weight is ``eval / pdf``.
``albedo`` is the tabulated albedo (exact for the interpolant, to its quadrature).

Compiled kernels (the render core): :data:`SIGNATURE`, :func:`eval_pdf`, :func:`sample`,
:func:`albedo`, reading the node's table (``T``, ``t``:
:func:`render.df._mbsdf.measurement_table`).
"""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np

from render.bsdf import Lobe
from render.df import _kernel_common as kc
from render.df._mbsdf import MbsdfError, Measurement, measurement_table, read_mbsdf
from render.df._registry import Df, Node
from render.df._signature import (
    MODE_FLAGS,
    MODE_MASK,
    REFLECT,
    REQUIRED,
    TRANSMIT,
    Param,
    Signature,
)
from render.jit import njit
from render.program import FLAGS, TABLE, Program, ProgramBsdf, leaf_program

__all__ = ["MeasuredBsdf", "measured_bsdf", "SIGNATURE", "eval_pdf", "sample", "albedo"]

SIGNATURE = Signature("bsdf", (
    Param("measurement", "bsdf_measurement", REQUIRED, uniform=True),
    Param("multiplier", "float", 1.0, clamp=(0.0, None), uniform=True),
    Param("mode", "scatter_mode", "scatter_reflect", uniform=True),
    Param("handle", "string", "", uniform=True),
))
_HALF_PI = 0.5 * math.pi
_GLOSSY_R = int(Lobe.GLOSSY_REFLECTION)
_GLOSSY_T = int(Lobe.GLOSSY_TRANSMISSION)


@njit
def _axis(n, hi, x):
    """``(j0, j1, f)`` of ``x`` on the step grid of ``n`` nodes over [0, hi]."""
    if n == 1:
        return 0, 0, 0.0
    s = min(max(x / hi * (n - 1), 0.0), n - 1.0)
    j = min(int(math.floor(s)), n - 2)
    return j, j + 1, s - j


@njit
def _cells_axis(n, hi, x):
    """The cell of ``x`` on the grid (``max(n - 1, 1)`` cells over [0, hi]) and its edges."""
    m = max(n - 1, 1)
    c = min(max(int(math.floor(x / hi * m)), 0), m - 1)
    return c, c * hi / m, (c + 1) * hi / m, m


@njit
def _f(T, off, nt, nphi, ti, to, ph):
    """The part's trilinear value ``(r, g, b)`` at ``(theta_i, theta_o, phi)``."""
    i0, i1, fi = _axis(nt, _HALF_PI, ti)
    o0, o1, fo = _axis(nt, _HALF_PI, to)
    p0, p1, fp = _axis(nphi, math.pi, ph)
    r = g = b = 0.0
    for ii in range(2):
        wi = fi if ii else 1.0 - fi
        i = i1 if ii else i0
        for oo in range(2):
            wo = fo if oo else 1.0 - fo
            o = o1 if oo else o0
            for pp in range(2):
                wp = fp if pp else 1.0 - fp
                p = p1 if pp else p0
                w = wi * wo * wp
                if w > 0.0:
                    k = off + ((i * nt + o) * nphi + p) * 3
                    r += w * T[k]
                    g += w * T[k + 1]
                    b += w * T[k + 2]
    return r, g, b


@njit
def _part_albedo(T, off, nt, nphi, to):
    """A part's albedo ``(r, g, b)`` at ``theta_o`` (0 for a part the file lacks)."""
    if off < 0:
        return 0.0, 0.0, 0.0
    cells = max(nt - 1, 1) * max(nphi - 1, 1)
    base = off + nt * nt * nphi * 3 + nt * cells
    o0, o1, fo = _axis(nt, _HALF_PI, to)
    a, b = base + o0 * 3, base + o1 * 3
    return ((1.0 - fo) * T[a] + fo * T[b], (1.0 - fo) * T[a + 1] + fo * T[b + 1],
            (1.0 - fo) * T[a + 2] + fo * T[b + 2])


@njit
def _part_mean_albedo(T, off, nt, nphi, to):
    """A part's albedo at ``theta_o``, the mean of its channels."""
    r, g, b = _part_albedo(T, off, nt, nphi, to)
    return (r + g + b) / 3.0


@njit
def _offsets(T, t, flags):
    """``(off_R, off_T)`` of the parts the mode uses (-1: none)."""
    mode = flags & MODE_MASK
    r = int(T[t + 2]) if mode != TRANSMIT else -1
    tr = int(T[t + 3]) if mode != REFLECT else -1
    return (t + r if r >= 0 else -1), (t + tr if tr >= 0 else -1)


@njit
def _cell_prob(T, off, nt, nphi, o, c):
    cells = max(nt - 1, 1) * max(nphi - 1, 1)
    cdf = off + nt * nt * nphi * 3 + o * cells
    return T[cdf + c] - (T[cdf + c - 1] if c > 0 else 0.0)


@njit
def _dphi(wox, woy, wix, wiy):
    so = math.hypot(wox, woy)
    si = math.hypot(wix, wiy)
    if not (so > 1e-12 and si > 1e-12):
        return 0.0
    return math.acos(min(max((wox * wix + woy * wiy) / (so * si), -1.0), 1.0))


@njit
def _eval(T, t, flags, wox, woy, woz, wix, wiy, wiz):
    """The value and pdf at an oriented pair -> ``(f0, f1, f2, pdf)``."""
    if not (woz > kc.COS_ZERO and abs(wiz) > kc.COS_ZERO):
        return 0.0, 0.0, 0.0, 0.0
    nt, nphi = int(T[t]), int(T[t + 1])
    offr, offt = _offsets(T, t, flags)
    tr = wiz < 0.0
    off = offt if tr else offr
    if off < 0:
        return 0.0, 0.0, 0.0, 0.0
    to = math.acos(min(woz, 1.0))
    ti = math.acos(min(abs(wiz), 1.0))
    ph = _dphi(wox, woy, wix, wiy)
    scale = T[t + 4]
    c = abs(wiz) * scale
    f0, f1, f2 = _f(T, off, nt, nphi, ti, to, ph)
    f0, f1, f2 = f0 * c, f1 * c, f2 * c
    # pdf: the part, the theta_o node mixture, the cell's probability over its solid angle
    ar = _part_mean_albedo(T, offr, nt, nphi, to)
    at = _part_mean_albedo(T, offt, nt, nphi, to)
    if not ar + at > 0.0:
        return 0.0, 0.0, 0.0, 0.0
    prob = (at if tr else ar) / (ar + at)
    a, t0, t1, ma = _cells_axis(nt, _HALF_PI, ti)
    bq, p0, p1, mp = _cells_axis(nphi, math.pi, ph)
    cell = a * mp + bq
    solid = (math.cos(t0) - math.cos(t1)) * (p1 - p0) * 2.0
    o0, o1, fo = _axis(nt, _HALF_PI, to)
    p = (1.0 - fo) * _cell_prob(T, off, nt, nphi, o0, cell)
    if fo > 0.0:
        p += fo * _cell_prob(T, off, nt, nphi, o1, cell)
    pdf = prob * p / solid
    if not (max(max(f0, f1), f2) > 0.0 and pdf > 0.0):
        return 0.0, 0.0, 0.0, 0.0
    return f0, f1, f2, pdf


@njit
def eval_pdf(P, row, b, flags, wox, woy, woz, wix, wiy, wiz, T, t):
    """``f |cos theta_i|`` and the pdf of :func:`sample` -> ``(f0, f1, f2, pdf)``."""
    if woz < 0.0:
        woz = -woz
        wiz = -wiz
    return _eval(T, t, flags, wox, woy, woz, wix, wiy, wiz)


@njit
def sample(P, row, b, flags, wox, woy, woz, u1, u2x, u2y, T, t):
    """-> ``(wix, wiy, wiz, pdf, w0, w1, w2, lobe)`` (all 0 where the sample fails)."""
    u1 = kc.clamp_u(u1)
    u2x = kc.clamp_u(u2x)
    u2y = kc.clamp_u(u2y)
    flip = woz < 0.0
    if flip:
        woz = -woz
    if not woz > kc.COS_ZERO:
        return 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0
    nt, nphi = int(T[t]), int(T[t + 1])
    offr, offt = _offsets(T, t, flags)
    to = math.acos(min(woz, 1.0))
    ar = _part_mean_albedo(T, offr, nt, nphi, to)
    at = _part_mean_albedo(T, offt, nt, nphi, to)
    if not ar + at > 0.0:
        return 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0
    pr = ar / (ar + at)
    tr = not (u1 < pr)
    u1 = (u1 - pr) / (1.0 - pr) if tr else u1 / pr
    off = offt if tr else offr
    o0, o1, fo = _axis(nt, _HALF_PI, to)
    o = o0
    if u1 < 1.0 - fo:
        u1 = u1 / (1.0 - fo)
    else:
        o = o1
        u1 = (u1 - (1.0 - fo)) / fo
    sign = 1.0 if u1 < 0.5 else -1.0
    # the cell from the node's CDF (binary search), u2x rescaled within it
    cells = max(nt - 1, 1) * max(nphi - 1, 1)
    cdf = off + nt * nt * nphi * 3 + o * cells
    lo, hi = 0, cells - 1
    while lo < hi:
        mid = (lo + hi) // 2
        if T[cdf + mid] > u2x:
            hi = mid
        else:
            lo = mid + 1
    c = lo
    before = T[cdf + c - 1] if c > 0 else 0.0
    width = T[cdf + c] - before
    if not width > 0.0:
        return 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0
    v = min(max((u2x - before) / width, 0.0), 1.0)
    mp = max(nphi - 1, 1)
    ma = max(nt - 1, 1)
    a, bq = c // mp, c % mp
    t0, t1 = a * _HALF_PI / ma, (a + 1) * _HALF_PI / ma
    p0, p1 = bq * math.pi / mp, (bq + 1) * math.pi / mp
    cos_t = math.cos(t0) - (math.cos(t0) - math.cos(t1)) * u2y
    sin_t = math.sqrt(max(1.0 - cos_t * cos_t, 0.0))
    dphi = p0 + (p1 - p0) * v
    phi_o = math.atan2(woy, wox) if math.hypot(wox, woy) > 1e-12 else 0.0
    phi = phi_o + sign * dphi
    wix, wiy = sin_t * math.cos(phi), sin_t * math.sin(phi)
    wiz = -cos_t if tr else cos_t
    f0, f1, f2, pdf = _eval(T, t, flags, wox, woy, woz, wix, wiy, wiz)
    if not pdf > 0.0:
        return 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0
    lobe = _GLOSSY_T if tr else _GLOSSY_R
    if flip:
        wiz = -wiz
    return wix, wiy, wiz, pdf, f0 / pdf, f1 / pdf, f2 / pdf, lobe


@njit
def albedo(P, row, b, flags, wox, woy, woz, T, t):
    """``scale`` times the tabulated albedo of the parts the mode uses, at ``theta_o``."""
    mu = abs(woz)
    if not mu > kc.COS_ZERO:
        return 0.0, 0.0, 0.0
    nt, nphi = int(T[t]), int(T[t + 1])
    offr, offt = _offsets(T, t, flags)
    to = math.acos(min(mu, 1.0))
    s = T[t + 4]
    r0, g0, b0 = _part_albedo(T, offr, nt, nphi, to)
    r1, g1, b1 = _part_albedo(T, offt, nt, nphi, to)
    return s * (r0 + r1), s * (g0 + g1), s * (b0 + b1)


_TABLES: dict = {}


class MeasuredBsdf(ProgramBsdf):
    """``df::measured_bsdf`` over lanes: its kernels, run by :mod:`render.interpreter`.

    Parameters
    ----------
    measurement : Measurement, str or Path
        The measurement, or an MBSDF file to read.
    multiplier : float
        Uniform.
    mode : scatter_mode name
    """

    mdl_name = "measured_bsdf"
    signature = SIGNATURE

    def __init__(self, measurement, multiplier=1.0, mode="scatter_reflect"):
        title = "df::measured_bsdf"
        if isinstance(measurement, str | Path):
            measurement = read_mbsdf(measurement)
        if not isinstance(measurement, Measurement):
            raise ValueError(f"{title}(measurement) must be a bsdf_measurement (an MBSDF "
                             f"file), got {type(measurement).__name__}")
        mult = np.asarray(multiplier, dtype=np.float64)
        if mult.ndim != 0 or not np.isfinite(mult):
            raise ValueError(f"{title}(multiplier) is uniform: one finite number, got "
                             f"{multiplier!r}")
        key = id(measurement)
        if key not in _TABLES or _TABLES[key][0] is not measurement:
            _TABLES[key] = (measurement, *measurement_table(measurement))
        _, table, max_r, max_t = _TABLES[key]
        prog = leaf_program("bsdf", NODE.op, SIGNATURE,
                            {"multiplier": float(mult), "mode": mode}, Lobe.NONE, title)
        flags = int(prog.code[0, FLAGS])
        m = flags & MODE_MASK
        scale = max(float(mult), 0.0)
        for use, amax, part in ((m != TRANSMIT, max_r, measurement.reflection),
                                (m != REFLECT, max_t, measurement.transmission)):
            if use and part is not None and amax > 0.0:
                scale = min(scale, 1.0 / amax)
        table = table.copy()
        table[4] = scale
        code = prog.code.copy()
        code[0, TABLE] = 0
        lobes = {MODE_FLAGS["scatter_reflect"]: Lobe.GLOSSY_REFLECTION,
                 MODE_FLAGS["scatter_transmit"]: Lobe.GLOSSY_TRANSMISSION}.get(m, Lobe.GLOSSY)
        ProgramBsdf.__init__(self, Program("bsdf", code, prog.kids, prog.frames, prog.blocks,
                                           table, lobes))
        self.measurement = measurement
        self.scale = scale


measured_bsdf = MeasuredBsdf
NODE = Node("measured_bsdf", "bsdf", "leaf", SIGNATURE, eval_pdf=eval_pdf, sample=sample,
            albedo=albedo)
DF = Df("measured_bsdf", SIGNATURE, (NODE,), constructor=MeasuredBsdf,
        lobes={"scatter_reflect": Lobe.GLOSSY_REFLECTION,
               "scatter_transmit": Lobe.GLOSSY_TRANSMISSION,
               "scatter_reflect_transmit": Lobe.GLOSSY})

__all__ += ["MbsdfError", "Measurement", "read_mbsdf"]
