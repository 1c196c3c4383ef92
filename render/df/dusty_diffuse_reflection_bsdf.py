"""MDL ``df::dusty_diffuse_reflection_bsdf``: d'Eon's BRDF of a half-space of Lambertian spheres.

MDL signature (1.8)::

    bsdf dusty_diffuse_reflection_bsdf(color tint = color(1.0), uniform string handle = "");

Model: the reflectance of a semi-infinite, sparse medium of spherical particles whose
surfaces are Lambertian (dust, regolith, powders), as d'Eon derived it and fitted it in
closed form (E. d'Eon, "An analytic BRDF for materials with spherical Lambertian
scatterers", Computer Graphics Forum 40(4), EGSR 2021).  It is the model of NVIDIA's
libbsdf (MDL SDK, ``src/mdl/jit/libbsdf/libbsdf_utilities.h``: ``lambert_sphere_brdf``,
selected by ``diffuse_sample``/``diffuse_evaluate`` in ``libbsdf.cpp``) and of d'Eon's own
Mitsuba 0.6 plugin (``eugenedeon/mitsuba``, ``src/bsdfs/lambert_sphere.cpp``); the two
agree term by term, and the equation numbers below are the paper's as that plugin cites
them.  With ``mu1 = wo.z``, ``mu2 = wi.z`` (both > 0) and per colour channel:

* the tint ``a = saturate(tint)`` is turned into the particles' single-scattering albedo
  by the paper's fitted inversion, Eq. (46),
  ``c = (1 - (1 - a)^2.73556) / (1 - 0.184096 (1 - a)^2.48423)``;
* the Lambertian sphere's phase function, ``u`` the cosine of the scattering angle,
  ``p(u) = 2 (sqrt(1 - u^2) - u acos(u)) / (3 pi^2)``, normalised over the sphere;
* the BRDF (``f``, without the cosine) is the exact single scattering plus fitted
  azimuthal Fourier modes of the rest::

      f = c (p(-wo.wi) / (mu1 + mu2) - F0s(mu1, mu2)) + f0(mu1, mu2; c)
          + f1(mu1, mu2; c) (wo.wi - mu1 mu2)

  where ``F0s = (207 + 256 mu1 mu2 - 45 (mu1^2 + mu2^2) + 135 mu1^2 mu2^2) / (768 pi (mu1 +
  mu2))`` is a polynomial fit of the azimuthal mean of single scattering,
  ``f0 = H0(mu1) H0(mu2) Q(mu1, mu2; c) / (2 pi (mu1 + mu2))`` the zeroth mode, with the
  fitted H-function ``H0`` of Eq. (37) and a symmetric quadratic-over-linear ``Q``
  whose coefficients are rational functions of ``sqrt(1 - c)``, and ``f1`` the first
  mode (divided by ``sin theta_1 sin theta_2``), built on the fitted ``H1`` of Eq. (28).
  The coefficients are the published ones (:func:`_f0`, :func:`_f1`).

``eval = f mu2``, sampled cosine-weighted (``pdf = mu2 / pi``, weight ``pi f``), as
libbsdf does.  ``f`` is symmetric in ``(wo, wi)``: the lobe is reciprocal.

Departures, each for a defined result where the fit alone gives none:

* ``c`` is capped at 1: Eq. (46) overshoots 1 by up to 3e-10 for ``a`` in (0.9988, 1),
  where ``sqrt(1 - c)`` would be NaN (libbsdf computes it unguarded);
* a channel with ``a = 0`` reflects nothing: the fit leaves a residue of ``1e-4`` at
  ``c = 0``, where the physical BRDF is 0;
* libbsdf's ``max(f, 0)`` is kept, though it never acts for ``c`` in [0, 1] (tested).

Energy: the fit is not lossless.  Its white albedo (``tint = 1``, a conservative
medium that physically reflects everything) is 0.979 at normal incidence, 0.991 at
60 degrees and 0.985-0.994 toward grazing: it never exceeds 1.

``albedo`` has no closed form; it is the table :func:`albedo_table` (built once per
process from these kernels by quadrature, 65 x 65 nodes over ``sqrt(mu)`` and
``sqrt(1 - c)``, bilinear, accurate to about 2e-4).  Because ``max(f, 0)`` never acts
and the first mode integrates to zero over the azimuth, the albedo is
``c S(mu) + G(mu, c)`` with ``S`` the (``c``-free) azimuth-integrated single-scattering
remainder and ``G`` one integral of ``f0`` over ``mu2``.

``handle`` only tags lobes and is not taken.
"""

from __future__ import annotations

import math
from functools import lru_cache

import numpy as np

from render.bsdf import Lobe
from render.df import _kernel_common as kc
from render.df._registry import Df, Node
from render.df._signature import Param, Signature
from render.jit import njit

__all__ = [
    "DustyDiffuseReflectionBsdf",
    "dusty_diffuse_reflection_bsdf",
    "SIGNATURE",
    "eval_pdf",
    "sample",
    "albedo",
    "albedo_table",
    "single_scattering_albedo",
    "lambert_sphere_brdf",
]

SIGNATURE = Signature("bsdf", (
    Param("tint", "color", (1.0, 1.0, 1.0), clamp=(0.0, 1.0)),
    Param("handle", "string", "", uniform=True),
))
_TINT = SIGNATURE.offset("tint")
_PI = float(np.pi)
_TWO_PI = 2.0 * _PI
_INV_PI = 1.0 / _PI
#: the albedo table: nodes over sqrt(mu) and over sqrt(1 - c)
N_MU, N_C = 65, 65


# --- the fit (d'Eon 2021) ----------------------------------------------------------------


@njit
def single_scattering_albedo(a):
    """The particles' albedo ``c`` for a tint ``a`` in [0, 1] (Eq. 46), capped at 1."""
    if not a > 0.0:
        return 0.0
    if a >= 1.0:
        return 1.0
    e = 1.0 - a
    c = (1.0 - math.pow(e, 2.73556)) / (1.0 - 0.184096 * math.pow(e, 2.48423))
    return min(c, 1.0)


@njit
def _phase(u):
    """The Lambertian sphere's phase function at scattering cosine ``u`` (per steradian)."""
    u = min(max(u, -1.0), 1.0)
    return (2.0 / (3.0 * _PI * _PI)) * (math.sqrt(max(1.0 - u * u, 0.0)) - u * math.acos(u))


@njit
def _f0_single(m1, m2):
    """The polynomial fit of single scattering's azimuthal mean (times ``c``)."""
    q = 207.0 + 256.0 * m1 * m2 - 45.0 * (m1 * m1 + m2 * m2) + 135.0 * m1 * m1 * m2 * m2
    return q / (768.0 * _PI * (m1 + m2))


@njit
def _h0(u, c, s):
    """The fitted zeroth-order H-function (Eq. 37); ``s = sqrt(1 - c)``."""
    a = (8.216443463470172 + 1.501116252342486 * math.pow(s, 6.054351911707695)) / (
        4.175932557866179 - 1.2122216865199813 * s)
    d = (7.773097842804312 - 0.5658108102188075 * math.pow(s, 0.9615460393324836)) / (
        8.659120811349371 - 0.15997430541238322 * math.pow(s, 7.0))
    # sqrt(1 - 2 (89 c / 288 + 59 c^2 / 288 - c^3 / 72)): 0 for c = 1
    root = math.sqrt(max(1.0 - c * (89.0 + c * (59.0 - 4.0 * c)) / 144.0, 0.0))
    ud = a * math.pow(u, d)
    return (1.0 + ud) / (1.0 + root * ud)


@njit
def _h1(u, c):
    """The fitted first-order H-function (Eq. 28)."""
    k = c * (-0.14483935877260054 + 0.024285125615255733 * c)
    e = 0.45944184025347456 + u * (-1.0787917226917565 + u * (1.8572804924335546
                                                             - 1.1283119660147671 * u))
    return math.exp(k * math.pow(u, e))


@njit
def _rational(s, n0, n1, n2, n3, d0, d1, d2):
    """``(n0 + n1 s + n2 s^2 + n3 s^3) / (d0 + d1 s + d2 s^2)``."""
    return (n0 + s * (n1 + s * (n2 + s * n3))) / (d0 + s * (d1 + s * d2))


@njit
def _f0(m1, m2, c, s, h01, h02):
    """The zeroth azimuthal mode; ``h0k = H0(mu_k)``."""
    s2 = s * s
    qa = 69.0 * c / 128.0
    qb = _rational(s, -0.08446297239646791, 0.5153566145541554, -0.77757371002123,
                   0.34668869623791543, 0.9648932738041012, -0.6655015709030936,
                   0.1826019462608555)
    qc = _rational(s, 682.8479477533338, -2567.7368047535556, 7487.987105705168,
                   -5602.448801045478, 5850.602606063662, -4008.3309624647227,
                   1480.250743805733)
    qd = _rational(s, 0.2855294320307508, 160.39651500649123, -327.42799697993706,
                   166.88327184107732, 674.1908010450103, -412.9837444306491,
                   596.4232294419696)
    qe = 15.0 * s2 * c * (3.0 + 4.0 * c / 3.0) / 128.0
    qf = _rational(s, -1.9208967199948512, -242.16001167844007, -21.914139454773085,
                   266.06342182761813, 1499.904420175135, 457.4200839912641,
                   215.77342164754094)
    p, t = m1 * m2, m1 + m2
    q = qa + qb * t + qc * p + qd * p * t + qe * p * p + qf * (m1 * m1 + m2 * m2)
    return h01 * h02 * q / (_TWO_PI * t)


@njit
def _f1(m1, m2, c, h11, h12):
    """The first azimuthal mode divided by ``sin theta_1 sin theta_2``; ``h1k = H1(mu_k)``."""
    ell = -c * (0.05890107167021953 + 0.004740543453386809 * c)
    p = m1 * m2
    hh = h11 * h12
    v = (15.0 / 16.0) * (1.0 + 0.44 * c) * c * p * hh + (4.0 / 3.0) * c * (
        1.0 + ell * m1) * (1.0 + ell * m2) * hh - c * (64.0 + 45.0 * p) / 48.0
    return v / (4.0 * _PI * (m1 + m2))


@njit
def _channel(a, m1, m2, single, f0s, cross):
    """``f`` of one channel: tint ``a``, ``single = p(-wo.wi) / (mu1 + mu2)``, ``f0s`` the
    single-scattering mean's fit, ``cross = wo.wi - mu1 mu2``."""
    c = single_scattering_albedo(a)
    if not c > 0.0:
        return 0.0
    s = math.sqrt(1.0 - c)
    f = (c * (single - f0s) + _f0(m1, m2, c, s, _h0(m1, c, s), _h0(m2, c, s))
         + _f1(m1, m2, c, _h1(m1, c), _h1(m2, c)) * cross)
    return max(f, 0.0)


@njit
def lambert_sphere_brdf(a0, a1, a2, wox, woy, woz, wix, wiy, wiz):
    """The BRDF ``f`` (no cosine) per channel for tints ``a`` and local directions with
    ``wo.z, wi.z > 0`` -> ``(f0, f1, f2)``."""
    m1, m2 = woz, wiz
    k = kc.dot3(wox, woy, woz, wix, wiy, wiz)
    single = _phase(-k) / (m1 + m2)
    f0s = _f0_single(m1, m2)
    cross = k - m1 * m2
    v0 = _channel(a0, m1, m2, single, f0s, cross)
    v1 = v0 if a1 == a0 else _channel(a1, m1, m2, single, f0s, cross)
    if a2 == a0:
        v2 = v0
    elif a2 == a1:
        v2 = v1
    else:
        v2 = _channel(a2, m1, m2, single, f0s, cross)
    return v0, v1, v2


# --- kernels (the compiled render core) -----------------------------------------------------


@njit
def _value(P, row, b, wox, woy, woz, wix, wiy, wiz):
    """``f`` for an oriented ``wo`` -> ``(f0, f1, f2, valid)``."""
    a0, a1, a2 = P[row, b + _TINT], P[row, b + _TINT + 1], P[row, b + _TINT + 2]
    if not (woz > kc.COS_ZERO and wiz > kc.COS_ZERO) or (a0 == 0.0 and a1 == 0.0
                                                         and a2 == 0.0):
        return 0.0, 0.0, 0.0, False
    f0, f1, f2 = lambert_sphere_brdf(a0, a1, a2, wox, woy, woz, wix, wiy, wiz)
    return f0, f1, f2, True


@njit
def eval_pdf(P, row, b, flags, wox, woy, woz, wix, wiy, wiz):
    """``f |cos theta_i|`` and the cosine pdf of one lane -> ``(f0, f1, f2, pdf)``."""
    flip, woz = kc.orient(woz)
    wiz = kc.mirror_z(wiz, flip)
    f0, f1, f2, valid = _value(P, row, b, wox, woy, woz, wix, wiy, wiz)
    if not valid:
        return 0.0, 0.0, 0.0, 0.0
    return f0 * wiz, f1 * wiz, f2 * wiz, wiz * _INV_PI


@njit
def sample(P, row, b, flags, wox, woy, woz, u1, u2x, u2y):
    """Cosine-weighted sample of one lane -> ``(wix, wiy, wiz, pdf, w0, w1, w2, lobe)``."""
    flip, woz = kc.orient(woz)
    wix, wiy, wiz = kc.cosine_hemisphere(kc.clamp_u(u2x), kc.clamp_u(u2y))
    f0, f1, f2, valid = _value(P, row, b, wox, woy, woz, wix, wiy, wiz)
    if not valid:
        return 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0
    return (wix, wiy, kc.mirror_z(wiz, flip), wiz * _INV_PI, _PI * f0, _PI * f1, _PI * f2,
            kc.LOBE_DIFFUSE_REFLECTION)


@njit
def _table_channel(tables, t, a, x, i, fx):
    """The albedo of one channel from the table: ``x`` = sqrt(mu) (N_MU - 1) split as
    node ``i`` plus ``fx``."""
    c = single_scattering_albedo(a)
    if not c > 0.0:
        return 0.0
    y = math.sqrt(1.0 - c) * (N_C - 1)
    j = min(int(y), N_C - 2)
    fy = y - j
    g = t + i * N_C + j
    lo = (1.0 - fy) * tables[g] + fy * tables[g + 1]
    hi = (1.0 - fy) * tables[g + N_C] + fy * tables[g + N_C + 1]
    sv = t + N_MU * N_C + i
    single = (1.0 - fx) * tables[sv] + fx * tables[sv + 1]
    return min(max((1.0 - fx) * lo + fx * hi + c * single, 0.0), 1.0)


@njit
def albedo(P, row, b, flags, wox, woy, woz, tables, t):
    """Directional albedo of one lane from the node's table -> ``(a0, a1, a2)``."""
    a0, a1, a2 = P[row, b + _TINT], P[row, b + _TINT + 1], P[row, b + _TINT + 2]
    mu = min(abs(woz), 1.0)
    if not mu > kc.COS_ZERO or (a0 == 0.0 and a1 == 0.0 and a2 == 0.0):
        return 0.0, 0.0, 0.0
    x = math.sqrt(mu) * (N_MU - 1)
    i = min(int(x), N_MU - 2)
    fx = x - i
    v0 = _table_channel(tables, t, a0, x, i, fx)
    v1 = v0 if a1 == a0 else _table_channel(tables, t, a1, x, i, fx)
    v2 = v0 if a2 == a0 else _table_channel(tables, t, a2, x, i, fx)
    return v0, v1, v2


# --- the albedo table ----------------------------------------------------------------------


@njit
def _fill_table(mu, xo, wo, phi_n, out):
    """``out[:N_MU N_C]`` the zeroth mode's albedo ``G(mu_i, c_j)`` (row-major over
    ``i, j``, ``c_j = 1 - (j / (N_C - 1))^2``) and ``out[N_MU N_C:]`` the azimuth-integrated
    single-scattering remainder ``S(mu_i)``, by quadrature: ``xo``, ``wo`` (N_MU, K) the
    nodes and weights over ``mu2`` for each ``mu_i``, midpoint rule over the azimuth."""
    k = xo.shape[1]
    for i in range(mu.shape[0]):
        m1 = mu[i]
        for j in range(N_C):
            s = j / (N_C - 1.0)
            c = 1.0 - s * s
            h1 = _h0(m1, c, s)
            acc = 0.0
            for q in range(k):
                m2 = xo[i, q]
                acc += wo[i, q] * m2 * _f0(m1, m2, c, s, h1, _h0(m2, c, s))
            out[i * N_C + j] = _TWO_PI * acc
        sin1 = math.sqrt(max(1.0 - m1 * m1, 0.0))
        acc = 0.0
        for q in range(k):
            m2 = xo[i, q]
            sin2 = math.sqrt(max(1.0 - m2 * m2, 0.0))
            ring = 0.0
            for r in range(phi_n):
                cphi = math.cos(_PI * (r + 0.5) / phi_n)
                ring += _phase(-(m1 * m2 + cphi * sin1 * sin2))
            ring = _TWO_PI * ring / phi_n / (m1 + m2)  # over the full circle
            acc += wo[i, q] * m2 * (ring - _TWO_PI * _f0_single(m1, m2))
        out[N_MU * N_C + i] = acc


def _nodes(mu: float) -> tuple[np.ndarray, np.ndarray]:
    """Gauss-Legendre panels over ``mu2`` in (0, 1), graded toward 0 and refined about
    ``mu`` (where ``1 / (mu + mu2)`` bends)."""
    edges = np.concatenate([[0.0, 1.0], np.geomspace(1e-9, 1.0, 36),
                            mu * np.array([0.25, 0.5, 1.0, 2.0, 4.0])])
    edges = np.unique(np.clip(edges, 0.0, 1.0))
    x, w = np.polynomial.legendre.leggauss(8)
    lo, hi = edges[:-1, None], edges[1:, None]
    return (lo + (hi - lo) * 0.5 * (x + 1.0)).ravel(), ((hi - lo) * 0.5 * w).ravel()


@lru_cache(maxsize=1)
def _table() -> np.ndarray:
    mu = np.maximum(np.linspace(0.0, 1.0, N_MU) ** 2, 1e-7)
    nodes = [_nodes(m) for m in mu]
    k = max(len(x) for x, _ in nodes)
    xo, wo = np.full((N_MU, k), 0.5), np.zeros((N_MU, k))  # padded with weight 0
    for i, (x, w) in enumerate(nodes):
        xo[i, :len(x)], wo[i, :len(w)] = x, w
    out = np.empty(N_MU * N_C + N_MU)
    _fill_table(mu, xo, wo, 256, out)
    out.setflags(write=False)
    return out


def albedo_table(row, flags: int = 0) -> np.ndarray:
    """The node table of :func:`albedo` (the same for every tint: built once per process,
    about 0.2 s; a writable copy, as every node table: numba compiles its kernels once
    more for a read-only array)."""
    return _table().copy()


# --- the Python class ----------------------------------------------------------------------

NODE = Node("dusty_diffuse_reflection_bsdf", "bsdf", "leaf", SIGNATURE, eval_pdf=eval_pdf,
            sample=sample, albedo=albedo)
DF = Df("dusty_diffuse_reflection_bsdf", SIGNATURE, (NODE,), lobes=Lobe.DIFFUSE_REFLECTION,
        albedo_table=albedo_table)
DustyDiffuseReflectionBsdf = DF.cls
dusty_diffuse_reflection_bsdf = DustyDiffuseReflectionBsdf
