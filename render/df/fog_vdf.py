"""MDL ``df::fog_vdf``: an approximate Mie phase function for fog and clouds, by droplet size.

MDL signature (1.8)::

    vdf fog_vdf(float particle_size = 8.0, uniform string handle = "");

``particle_size`` is the diameter ``d`` of the water droplets in micrometres.  The phase
function is the fit of Jendersie and d'Eon ("An Approximate Mie Scattering Function for
Fog and Cloud Rendering", SIGGRAPH 2023 Talks) to Lorenz–Mie theory for water droplets
(averaged over the visible spectrum and over a size distribution about ``d``): a blend of
Henyey–Greenstein and Draine's phase function, with ``mu = cos theta`` the cosine
between the old propagation direction ``-wo`` and the new one ``wi``::

    p(mu) = (1 - w_D) HG(mu; g_HG) + w_D D(mu; g_D, alpha)
    D(mu; g, alpha) = HG(mu; g) (1 + alpha mu^2) / (1 + alpha (1 + 2 g^2) / 3)

where ``g_HG``, ``g_D``, ``alpha`` and ``w_D`` are the paper's fitted functions of ``d``
in its three ranges (``0.1 <= d < 1.5``, ``1.5 <= d < 5``, ``5 <= d <= 50``; ``d`` is
clamped to ``[0.1, 50]``, the range of the fit).  It is normalised over the sphere.

Sampling is exact (sample weight 1, ``pdf = eval``): the lobe is picked with probability
``1 - w_D`` or ``w_D``, Henyey–Greenstein by its inverse CDF (:mod:`anisotropic_vdf`'s
form) and Draine by solving ``F(mu) = u`` with Newton's method bracketed by bisection on
its closed-form CDF (the antiderivative of ``(1 + alpha mu^2) s^(-3/2)``,
``s = 1 + g^2 - 2 g mu``; below ``|g| = 0.05``, where that form loses digits, 16-point
Gauss–Legendre quadrature, exact to rounding there).  As a vdf, ``eval`` is ``p`` in
every channel and the albedo is 1 (the interpreter reads every vdf's from
:func:`render.df.anisotropic_vdf.albedo`); directions in any orthonormal frame (world space in
the integrator).  The lobe flag is DIFFUSE_REFLECTION when ``wi`` returns to the
viewer's side, else DIFFUSE_TRANSMISSION (as ``anisotropic_vdf``).

Not in libbsdf's reference text (``reference/mdl-distribution-functions.md`` §6 names
it "approx. Mie"); this module follows the published fit.  Checks:
``tests/render/df/test_fog_vdf.py``.
"""

from __future__ import annotations

import math

import numpy as np

from render.bsdf import Lobe
from render.df import _kernel_common as kc
from render.df._registry import Df, Node
from render.df._signature import Param, Signature
from render.df.anisotropic_vdf import albedo as _vdf_albedo
from render.jit import njit

__all__ = ["FogVdf", "fog_vdf", "SIGNATURE", "eval_pdf", "sample", "fog_parameters", "D_MIN",
           "D_MAX"]

#: the droplet diameters (micrometres) the fit covers; ``particle_size`` is clamped to them
D_MIN, D_MAX = 0.1, 50.0
_G_MAX = 1.0 - 1e-4
_INV_4PI = 1.0 / (4.0 * math.pi)
_TWO_PI = 2.0 * math.pi
#: below this |g| the Draine CDF is integrated numerically (its closed form cancels)
_G_SMALL = 0.05
# 16-point Gauss–Legendre nodes and weights on [-1, 1]
_GL_X, _GL_W = np.polynomial.legendre.leggauss(16)

SIGNATURE = Signature("vdf", (
    Param("particle_size", "float", 8.0, clamp=(D_MIN, D_MAX)),
    Param("handle", "string", "", uniform=True),
))
_D = SIGNATURE.offset("particle_size")


@njit
def fog_parameters(d):
    """``(g_HG, g_D, alpha, w_D)`` of Jendersie and d'Eon's fit at droplet diameter ``d``
    (micrometres, clamped to ``[D_MIN, D_MAX]``)."""
    d = min(max(d, D_MIN), D_MAX)
    if d < 1.5:
        ld = math.log(d)
        inner = (ld - 0.238604) * (ld + 1.00667) / (0.507522 - 0.15677 * ld)
        g_hg = 0.862 - 0.143 * ld * ld
        g_d = 0.379685 * math.cos(1.19692 * math.cos(inner) + 1.37932 * ld + 0.0625835) + 0.344213
        alpha = 250.0
        w_d = 0.146209 * math.cos(3.38707 * ld + 2.11193) + 0.316072 + 0.0778917 * ld
    elif d < 5.0:
        ld = math.log(d)
        g_hg = 0.0604931 * math.log(ld) + 0.940256
        g_d = 0.500411 - 0.081287 / (-2.0 * ld + math.tan(ld) + 1.27551)
        alpha = 7.30354 * ld + 6.31675
        w_d = 0.026914 * (ld - math.cos(5.68947 * (math.log(ld) - 0.0292149))) + 0.376475
    else:
        g_hg = math.exp(-0.0990567 / (d - 1.67154))
        g_d = math.exp(-2.20679 / (d + 3.91029) - 0.428934)
        alpha = math.exp(3.62489 - 8.29288 / (d + 5.52825))
        w_d = math.exp(-0.599085 / (d - 0.641583) - 0.665888)
    g_hg = min(max(g_hg, -_G_MAX), _G_MAX)
    g_d = min(max(g_d, -_G_MAX), _G_MAX)
    return g_hg, g_d, max(alpha, 0.0), min(max(w_d, 0.0), 1.0)


@njit
def _s(g, mu):
    """``1 + g^2 - 2 g mu`` without cancellation at the peak (``mu`` -> sign g)."""
    if g >= 0.0:
        return (1.0 - g) * (1.0 - g) + 2.0 * g * (1.0 - mu)
    return (1.0 + g) * (1.0 + g) - 2.0 * g * (-1.0 - mu)


@njit
def _hg(g, mu):
    s = _s(g, mu)
    return (1.0 - g * g) * _INV_4PI / (s * math.sqrt(s))


@njit
def _draine(g, alpha, mu):
    return _hg(g, mu) * (1.0 + alpha * mu * mu) / (1.0 + alpha * (1.0 + 2.0 * g * g) / 3.0)


@njit
def _phase(P, row, b, mu):
    g_hg, g_d, alpha, w_d = fog_parameters(P[row, b + _D])
    return (1.0 - w_d) * _hg(g_hg, mu) + w_d * _draine(g_d, alpha, mu)


@njit
def _antiderivative(g, alpha, mu):
    """An antiderivative in ``mu`` of ``(1 + alpha mu^2) s^(-3/2)``, ``s = 1 + g^2 - 2 g mu``
    (``|g| >= _G_SMALL``)."""
    a = 1.0 + g * g
    b = 2.0 * g
    s = _s(g, mu)
    r = math.sqrt(s)
    return (2.0 / r + alpha / (b * b) * (2.0 * a * a / r + 4.0 * a * r - 2.0 / 3.0 * s * r)) / b


@njit
def _draine_mass(g, alpha, mu):
    """``∫_{-1}^{mu} (1 + alpha t^2) s(t)^(-3/2) dt`` (the Draine CDF up to its total)."""
    if abs(g) >= _G_SMALL:
        return _antiderivative(g, alpha, mu) - _antiderivative(g, alpha, -1.0)
    half = 0.5 * (mu + 1.0)
    total = 0.0
    for i in range(16):
        t = -1.0 + half * (_GL_X[i] + 1.0)
        s = _s(g, t)
        total += _GL_W[i] * (1.0 + alpha * t * t) / (s * math.sqrt(s))
    return total * half


@njit
def _sample_draine(g, alpha, u):
    """``mu`` with ``F_D(mu) = u``: Newton's method on the closed-form CDF, kept inside a
    bisection bracket."""
    total = _draine_mass(g, alpha, 1.0)
    target = u * total
    lo, hi = -1.0, 1.0
    # start from Henyey–Greenstein's inverse CDF (the same peak)
    a = 2.0 * u - 1.0
    den = 1.0 + g * a
    mu = (a + 0.5 * g * (a * a + 3.0) + g * g * a + 0.5 * g * g * g * (a * a - 1.0)) / (den * den)
    mu = min(max(mu, -1.0), 1.0)
    for _ in range(60):
        f = _draine_mass(g, alpha, mu) - target
        if f > 0.0:
            hi = mu
        else:
            lo = mu
        s = _s(g, mu)
        dens = (1.0 + alpha * mu * mu) / (s * math.sqrt(s))
        step = f / dens if dens > 0.0 else 0.0
        nxt = mu - step
        if not (nxt > lo and nxt < hi):
            nxt = 0.5 * (lo + hi)
        if abs(nxt - mu) <= 1e-15 * (1.0 + abs(mu)) or hi - lo <= 1e-15:
            mu = nxt
            break
        mu = nxt
    return min(max(mu, -1.0), 1.0)


@njit
def eval_pdf(P, row, b, flags, wox, woy, woz, wix, wiy, wiz):
    """The phase function ``p`` in every channel and as the pdf -> ``(p, p, p, p)`` (no
    cosine factor; unit directions in any orthonormal frame)."""
    lo = wox * wox + woy * woy + woz * woz
    li = wix * wix + wiy * wiy + wiz * wiz
    if not (lo > 0.25 and li > 0.25):
        return 0.0, 0.0, 0.0, 0.0
    mu = min(max(-kc.dot3(wox, woy, woz, wix, wiy, wiz) / math.sqrt(lo * li), -1.0), 1.0)
    p = _phase(P, row, b, mu)
    return p, p, p, p


@njit
def sample(P, row, b, flags, wox, woy, woz, u1, u2x, u2y):
    """An exact sample about ``-wo`` -> ``(wix, wiy, wiz, pdf, 1, 1, 1, lobe)``."""
    g_hg, g_d, alpha, w_d = fog_parameters(P[row, b + _D])
    u1 = kc.clamp_u(u1)
    u = kc.clamp_u(u2x)
    if u1 < w_d:
        mu = _sample_draine(g_d, alpha, u)
    else:
        a = 2.0 * u - 1.0
        g = g_hg
        den = 1.0 + g * a
        mu = (a + 0.5 * g * (a * a + 3.0) + g * g * a + 0.5 * g * g * g * (a * a - 1.0)) / (
            den * den)
        mu = min(max(mu, -1.0), 1.0)
    sin_t = math.sqrt(max(1.0 - mu * mu, 0.0))
    phi = _TWO_PI * kc.clamp_u(u2y)
    cp = sin_t * math.cos(phi)
    sp = sin_t * math.sin(phi)
    nx, ny, nz, ok = kc.unitize(-wox, -woy, -woz)
    if not ok:
        return 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0
    sx, sy, sz, tx, ty, tz = kc.frame_from_normal(nx, ny, nz)
    wix, wiy, wiz, ok = kc.unitize(cp * sx + sp * tx + mu * nx, cp * sy + sp * ty + mu * ny,
                                   cp * sz + sp * tz + mu * nz)
    if not ok:
        return 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0
    pdf = _phase(P, row, b, min(max(kc.dot3(nx, ny, nz, wix, wiy, wiz), -1.0), 1.0))
    if not pdf > 0.0:
        return 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0
    back = kc.dot3(wix, wiy, wiz, wox, woy, woz) > 0.0
    lobe = kc.LOBE_DIFFUSE_REFLECTION if back else kc.LOBE_DIFFUSE_TRANSMISSION
    return wix, wiy, wiz, pdf, 1.0, 1.0, 1.0, lobe


def _check(values: dict) -> None:
    d = np.asarray(values["particle_size"], dtype=np.float64)
    if not np.all(np.isfinite(d)) or np.any(d <= 0.0):
        raise ValueError("df::fog_vdf: particle_size must be a droplet diameter > 0 in "
                         f"micrometres (the fit covers {D_MIN} to {D_MAX}; 8 is MDL's "
                         f"default), got {values['particle_size']!r}")


NODE = Node("fog_vdf", "vdf", "leaf", SIGNATURE, eval_pdf=eval_pdf, sample=sample,
            albedo=_vdf_albedo)
DF = Df("fog_vdf", SIGNATURE, (NODE,), lobes=Lobe.DIFFUSE, check=_check)
FogVdf = DF.cls
fog_vdf = FogVdf
