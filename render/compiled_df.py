"""Compiled (numba) per-lane twins of three elemental BSDFs, for the integrator's fast path.

The numpy classes in :mod:`render.df` stay the reference: they vectorise over lanes and
handle every argument form (callables, per-lane arrays, nested nodes, every scatter mode).
A compiled integrator loop cannot call them per lane, so this module ports, formula by
formula and guard by guard, the common constant-argument cases to scalar ``@njit`` code:

* ``df::diffuse_reflection_bsdf`` (Lambert / Fujii's Oren–Nayar with EON's multiscatter
  compensation), :mod:`render.df.diffuse_reflection_bsdf`;
* ``df::simple_glossy_bsdf`` in ``scatter_reflect`` mode with the default ``tangent_u``
  (Ashikhmin–Shirley with v-cavities), :mod:`render.df.simple_glossy_bsdf` and
  :mod:`render.df._microfacet`;
* ``df::specular_bsdf`` in ``scatter_reflect`` mode (a tinted mirror),
  :mod:`render.df.specular_bsdf`.

A material's df is flattened once, by :func:`params_of`, into one float64 row of
:data:`PARAM_WIDTH` values (``None``: not covered, use the numpy path)::

    [kind, tint_r, tint_g, tint_b, roughness_u, roughness_v, ms_r, ms_g, ms_b, 0]

``kind`` is :data:`BLACK`, :data:`DIFFUSE_REFLECTION`, :data:`SIMPLE_GLOSSY` or
:data:`SPECULAR`; the diffuse roughness sits in ``roughness_u``; every value is stored as
the numpy class stores it after its own clamping (saturated tints, the diffuse
roughness saturated, glossy roughness clamped below at ``TOL.roughness_min``).

:func:`eval_pdf` and :func:`sample` then evaluate one lane (local frame, ``+z`` the
shading normal, ``x`` along ``tangent_u``; conventions in :mod:`render.frame`), with the
numpy classes' orientation (two-sidedness), tolerances and special cases.  They agree
with the numpy classes to rounding: numpy evaluates ``exp``, ``log``, ``log1p``,
``expm1`` and ``arctan2`` with its own SIMD kernels, which differ from the C library's
(used here) in the last bit on some arguments; everything else is the same sequence of
IEEE operations.  ``tests/render/test_compiled_df.py`` holds the two equal.

Every kernel is compiled with ``nogil=True`` (two threads shade at once) and
``cache=True`` (compiled once per machine, in ``__pycache__``).  The tolerances are
literals here, checked against :data:`render.numerics.TOL` at import: numba freezes
globals into the cached machine code, and the cache is keyed on this file only.

Examples
--------
>>> from render.material import df
>>> p = params_of(df.diffuse_reflection_bsdf(tint=0.5))
>>> f_r, f_g, f_b, pdf = eval_pdf(p[None], 0, 0.0, 0.0, 1.0, 0.0, 0.6, 0.8)
>>> round(f_r * np.pi, 12), round(pdf * np.pi, 12)
(0.4, 0.8)
>>> eval_pdf(p[None], 0, 0.0, 0.0, 1.0, 0.0, 0.6, -0.8)  # below the surface
(0.0, 0.0, 0.0, 0.0)
>>> sample(params_of(df.specular_bsdf())[None], 0, 0.6, 0.0, 0.8, 0.5, 0.5, 0.5)
(-0.6, -0.0, 0.8, 1.0, 1.0, 1.0, 1.0, True, True)
"""

from __future__ import annotations

import math

import numpy as np

from render.jit import njit
from render.numerics import ONE_MINUS_EPS, TOL

__all__ = [
    "PARAM_WIDTH",
    "BLACK",
    "DIFFUSE_REFLECTION",
    "SIMPLE_GLOSSY",
    "SPECULAR",
    "covers",
    "params_of",
    "rows_of",
    "eval_pdf",
    "sample",
    "eval_pdf_batch",
    "sample_batch",
]

#: length of a parameter row (one float64 row per material)
PARAM_WIDTH = 10
#: ``row[0]``: the df scatters nothing (eval, pdf 0; samples fail)
BLACK = 0
#: ``row[0]``: ``df::diffuse_reflection_bsdf``
DIFFUSE_REFLECTION = 1
#: ``row[0]``: ``df::simple_glossy_bsdf`` (``scatter_reflect``, default ``tangent_u``)
SIMPLE_GLOSSY = 2
#: ``row[0]``: ``df::specular_bsdf`` (``scatter_reflect``)
SPECULAR = 3

# --- constants frozen into the compiled code ---------------------------------------------
# TOL values as literals: numba bakes globals into its cache, which only this file's
# timestamp invalidates; the import-time check below keeps them equal to TOL.
_COS_ZERO = 1e-10
_ROUGHNESS_MIN = 1e-7
_UNIT_MIN = 1e-300
if (_COS_ZERO, _ROUGHNESS_MIN, _UNIT_MIN) != (TOL.cos_zero, TOL.roughness_min, TOL.unit_min):
    raise RuntimeError(
        "render.compiled_df: its tolerance literals differ from render.numerics.TOL; "
        "update _COS_ZERO, _ROUGHNESS_MIN and _UNIT_MIN (editing this file also "
        "invalidates numba's cache)"
    )
_ONE_MINUS_EPS = ONE_MINUS_EPS
_PI = np.pi
_INV_PI = 1.0 / np.pi  # render.df._common.INV_PI
_QUARTER_PI = np.pi / 4.0  # render.warp._QUARTER_PI
# Oren–Nayar constants of render.df.diffuse_reflection_bsdf: 1 - A = C_A sigma A,
# rho_avg = A + C_AVG B
_C_A = 0.5 - 2.0 / (3.0 * np.pi)
_C_AVG = 2.0 / 3.0 - 28.0 / (15.0 * np.pi)



# --- parameter rows ------------------------------------------------------------------------


def covers(node) -> bool:
    """True if the kernels model the df node ``node`` once bound: a bsdf
    :class:`render.material.DfNode` of ``diffuse_reflection_bsdf``, ``simple_glossy_bsdf``
    in ``scatter_reflect`` mode with ``tangent_u`` left at its default and no
    ``multiscatter_tint`` (the numpy class does not take it yet), or ``specular_bsdf`` in
    ``scatter_reflect`` mode, whose arguments are constants or functions of the state
    (not nested dfs); or any node with ``node.is_black`` (``material.shade`` skips it).

    Examples
    --------
    >>> from render.material import df
    >>> covers(df.diffuse_reflection_bsdf(tint=lambda state: state.uv[:, :1]))
    True
    >>> covers(df.simple_glossy_bsdf(roughness_u=0.2, mode="scatter_transmit"))
    False
    """
    from render.material import DfNode

    if not isinstance(node, DfNode) or node.kind != "bsdf":
        return False
    if node.is_black:
        return True
    kw = node.kwargs
    if node.name not in ("diffuse_reflection_bsdf", "simple_glossy_bsdf", "specular_bsdf"):
        return False
    if any(isinstance(v, DfNode) for v in kw.values()):
        return False
    if node.name != "diffuse_reflection_bsdf" and kw.get("mode", "scatter_reflect") != (
        "scatter_reflect"
    ):
        return False
    if node.name == "simple_glossy_bsdf":
        ms = kw.get("multiscatter_tint", 0.0)
        if "tangent_u" in kw or callable(ms) or np.any(np.asarray(ms, dtype=np.float64) != 0):
            return False
    return True


def params_of(node) -> np.ndarray | None:
    """The parameter row of a df node with constant arguments, or ``None`` if the kernels
    do not cover it (:func:`covers`) or an argument is a function of the state.

    Parameters
    ----------
    node : DfNode
        The df, as given to ``material_surface(scattering=...)``.

    Returns
    -------
    (PARAM_WIDTH,) float64 or None
        ``[kind, tint_r, tint_g, tint_b, roughness_u, roughness_v, ms_r, ms_g, ms_b, 0]``
        with the values the numpy class stores (saturated, clamped); a :data:`BLACK` row
        (all 0) for ``node.is_black``.

    Examples
    --------
    >>> from render.material import df
    >>> params_of(df.diffuse_reflection_bsdf(tint=(1.5, 0.5, 0.0), roughness=0.3)).tolist()
    [1.0, 1.0, 0.5, 0.0, 0.3, 0.0, 0.0, 0.0, 0.0, 0.0]
    >>> params_of(df.simple_glossy_bsdf(roughness_u=0.0, roughness_v=0.2))[4:6].tolist()
    [1e-07, 0.2]
    >>> params_of(df.specular_bsdf(tint=0.0, mode="scatter_transmit")).tolist()[0]  # black
    0.0
    >>> params_of(df.diffuse_reflection_bsdf(tint=lambda state: state.uv[:, :1])) is None
    True
    """
    from render.df import DiffuseReflectionBsdf, SimpleGlossyBsdf, SpecularBsdf

    if not covers(node):
        return None
    if node.is_black:
        return np.zeros(PARAM_WIDTH)
    kw = {k: v for k, v in node.kwargs.items() if k != "handle"}
    if any(callable(v) for v in kw.values()):
        return None
    cls = {
        "diffuse_reflection_bsdf": DiffuseReflectionBsdf,
        "simple_glossy_bsdf": SimpleGlossyBsdf,
        "specular_bsdf": SpecularBsdf,
    }[node.name]
    return rows_of(cls(**kw), 1)[0]


def rows_of(bsdf, n: int) -> np.ndarray:
    """(n, PARAM_WIDTH) parameter rows of a bound numpy df over ``n`` lanes (``None``:
    black), as :func:`params_of` lays them out.  The df must be one :func:`covers`
    accepts (bound from such a node by ``material.shade``).

    Examples
    --------
    >>> from render.df import DiffuseReflectionBsdf
    >>> rows_of(DiffuseReflectionBsdf(tint=np.array([[0.2, 0.4, 0.6], [1, 1, 1]])), 2)[:, :4]
    array([[1. , 0.2, 0.4, 0.6],
           [1. , 1. , 1. , 1. ]])
    """
    from render.df import DiffuseReflectionBsdf, SimpleGlossyBsdf, SpecularBsdf

    rows = np.zeros((n, PARAM_WIDTH))
    if bsdf is None:
        return rows
    rows[:, 1:4] = bsdf.tint
    if isinstance(bsdf, DiffuseReflectionBsdf):
        rows[:, 0] = DIFFUSE_REFLECTION
        rows[:, 4] = bsdf.roughness
        rows[:, 6:9] = bsdf.multiscatter_tint
    elif isinstance(bsdf, SimpleGlossyBsdf):
        rows[:, 0] = SIMPLE_GLOSSY
        rows[:, 4] = bsdf.roughness_u
        rows[:, 5] = bsdf.roughness_v
    elif isinstance(bsdf, SpecularBsdf):
        rows[:, 0] = SPECULAR
    else:
        raise TypeError(f"the compiled kernels do not model {type(bsdf).__name__}")
    return rows


# --- scalar helpers (ports of render.numerics / render.warp) ----------------------------------


@njit(inline="always")
def _clamp_u(u):
    """``np.clip(u, 0, ONE_MINUS_EPS)`` (``render.bsdf.check_samples``)."""
    if u < 0.0:
        return 0.0
    if u > _ONE_MINUS_EPS:
        return _ONE_MINUS_EPS
    return u


@njit(inline="always")
def _dot(ax, ay, az, bx, by, bz):
    """``render.numerics.dot``: summed as ``(x + z) + y``."""
    return ax * bx + az * bz + ay * by


@njit(inline="always")
def _unitize(x, y, z):
    """``render.numerics.unitize`` of one vector -> ``(ux, uy, uz, valid)``."""
    scale = max(max(abs(x), abs(y)), abs(z))
    if not scale > _UNIT_MIN:
        return 0.0, 0.0, 0.0, False
    wx = x / scale
    wy = y / scale
    wz = z / scale
    length = math.sqrt(_dot(wx, wy, wz, wx, wy, wz))
    return wx / length, wy / length, wz / length, True


@njit(inline="always")
def _cosine_hemisphere(u0, u1):
    """``render.warp.square_to_cosine_hemisphere`` (concentric disk, then lift)."""
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


# --- diffuse_reflection_bsdf --------------------------------------------------------------


@njit(inline="always")
def _on_g(mu):
    """``G(theta)`` of the closed-form Oren–Nayar albedo (``diffuse_reflection_bsdf._g``)."""
    if mu < 0.0:
        mu = 0.0
    elif mu > 1.0:
        mu = 1.0
    s = math.sqrt(max(1.0 - mu * mu, 0.0))
    theta = math.atan2(s, mu)
    return s * (theta - s * mu) + (2.0 / 3.0) * s * (mu * (1.0 + s + s * s) / (1.0 + s) - 1.0)


@njit
def _diffuse_value(P, k, wox, woy, woz, wix, wiy, wiz):
    """``DiffuseReflectionBsdf._value`` for oriented ``wo`` -> ``(v_r, v_g, v_b, valid)``."""
    tr, tg, tb = P[k, 1], P[k, 2], P[k, 3]
    sigma = P[k, 4]
    mr, mg, mb = P[k, 6], P[k, 7], P[k, 8]
    black = tr == 0.0 and tg == 0.0 and tb == 0.0 and mr == 0.0 and mg == 0.0 and mb == 0.0
    mu1 = woz
    mu2 = wiz
    if not (mu1 > _COS_ZERO and mu2 > _COS_ZERO and not black):
        return 0.0, 0.0, 0.0, False
    if not sigma > 0.0:
        return tr, tg, tb, True  # Lambert
    # Fujii's Oren–Nayar: s / t with t = max(mu1, mu2) where s > 0
    a = 1.0 / (1.0 + _C_A * sigma)
    b = sigma * a
    s = max(_dot(wox, woy, woz, wix, wiy, wiz) - mu1 * mu2, -1.0)  # as the numpy class
    tmax = max(max(mu1, mu2), _COS_ZERO)
    if s > 0.0:
        s = s / tmax
    single = a + b * s
    vr = single * tr
    vg = single * tg
    vb = single * tb
    if mr > 0.0 or mg > 0.0 or mb > 0.0:
        # energy compensation: 1 - rho(mu) = B (C_A - G(mu)/pi)
        e1 = _C_A - _on_g(mu1) / _PI
        e2 = _C_A - _on_g(mu2) / _PI
        multi = b * max(e1, 0.0) * max(e2, 0.0) / (_C_A - _C_AVG)
        vr = vr + multi * mr
        vg = vg + multi * mg
        vb = vb + multi * mb
    return vr, vg, vb, True


@njit
def _diffuse_eval_pdf(P, k, wox, woy, woz, wix, wiy, wiz):
    if woz < 0.0:  # orient: mirror both through the tangent plane
        woz = -woz
        wiz = -wiz
    vr, vg, vb, valid = _diffuse_value(P, k, wox, woy, woz, wix, wiy, wiz)
    if not valid:
        return 0.0, 0.0, 0.0, 0.0
    pdf = wiz * _INV_PI
    return vr * pdf, vg * pdf, vb * pdf, pdf


@njit
def _diffuse_sample(P, k, wox, woy, woz, u2x, u2y):
    flip = woz < 0.0
    if flip:
        woz = -woz
    wix, wiy, wiz = _cosine_hemisphere(u2x, u2y)
    vr, vg, vb, valid = _diffuse_value(P, k, wox, woy, woz, wix, wiy, wiz)
    if not valid:
        return 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, False, False
    # the numpy class computes the pdf from the un-mirrored wi times -1: the same bits
    pdf = wiz * _INV_PI
    if flip:
        wiz = -wiz
    return wix, wiy, wiz, pdf, vr, vg, vb, False, True


# --- simple_glossy_bsdf (scatter_reflect, tangent_u = +x) -------------------------------------


@njit(inline="always")
def _as_exponents(P, k):
    """Ashikhmin–Shirley exponents and normalisation (``AshikhminShirley.__init__``)."""
    ru = P[k, 4]
    rv = P[k, 5]
    e_u = 2.0 / (ru * ru)
    e_v = 2.0 / (rv * rv)
    return e_u, e_v, math.sqrt((e_u + 1.0) * (e_v + 1.0)) / (2.0 * _PI)


@njit(inline="always")
def _as_d_cos(e_u, e_v, norm, ht, hb, hn):
    """``AshikhminShirley.d_cos``: ``D(h) (n.h)`` in the anisotropy frame."""
    s2 = ht * ht + hb * hb
    if not (hn > 0.0 and s2 < 1.0):
        return 0.0
    # (n.h)^(x) = exp(x/2 * log(1 - s2)); x s2 = e_u ht^2 + e_v hb^2 stays finite as s2 -> 0
    ratio = math.log1p(-s2) / s2 if s2 > 0.0 else -1.0
    expo = 0.5 * (e_u * ht * ht + e_v * hb * hb) * ratio
    return norm * math.exp(expo)


@njit
def _glossy_kernel(P, k, wox, woy, woz, wix, wiy, wiz):
    """``MicrofacetBsdf._kernel`` in ``scatter_reflect`` mode for oriented ``wo``.

    Returns ``(weight_r, weight_g, weight_b, pdf, ok)``.
    """
    tr, tg, tb = P[k, 1], P[k, 2], P[k, 3]
    # tangent_axes((1, 0, 0)): the anisotropy frame is the local frame
    tx = 1.0
    ty = 0.0
    black = tr == 0.0 and tg == 0.0 and tb == 0.0
    nk1 = woz
    # scatter_reflect: nothing below the surface (wi.z < 0)
    if black or not (nk1 > _COS_ZERO and abs(wiz) > _COS_ZERO) or wiz < 0.0:
        return 0.0, 0.0, 0.0, 0.0, False
    hx, hy, hz, v1 = _unitize(wox + wix, woy + wiy, woz + wiz)
    if not v1:
        return 0.0, 0.0, 0.0, 0.0, False
    kh1 = _dot(wox, woy, woz, hx, hy, hz)
    kh2 = _dot(wix, wiy, wiz, hx, hy, hz)
    if not (hz > _COS_ZERO and kh1 > 0.0 and kh2 > 0.0):
        return 0.0, 0.0, 0.0, 0.0, False
    # v-cavities masking
    hn = hz
    g1_1 = min(1.0, 2.0 * hn * nk1 / kh1)
    g1_2 = min(1.0, 2.0 * hn * abs(wiz) / abs(kh2))
    g2 = min(g1_1, g1_2)
    if not g2 > 0.0:
        return 0.0, 0.0, 0.0, 0.0, False
    # distribution in the anisotropy frame (t = (tx, ty, 0), b = (ty, -tx, 0))
    ht = hx * tx + hy * ty
    hb = hx * ty - hy * tx
    e_u, e_v, norm = _as_exponents(P, k)
    d = _as_d_cos(e_u, e_v, norm, ht, hb, hn) / hn
    pdf0 = d / (4.0 * nk1)
    pdf = 1.0 * g1_1 * pdf0  # P = 1 in scatter_reflect
    r = g2 / g1_1
    wr = tr * r
    wg = tg * r
    wb = tb * r
    # pdf > 0 exactly where eval = weight * pdf > 0 (also where the product underflows)
    if not max(max(wr * pdf, wg * pdf), wb * pdf) > 0.0:
        return 0.0, 0.0, 0.0, 0.0, False
    return wr, wg, wb, pdf, True


@njit
def _glossy_eval_pdf(P, k, wox, woy, woz, wix, wiy, wiz):
    if woz < 0.0:
        woz = -woz
        wiz = -wiz
    wr, wg, wb, pdf, ok = _glossy_kernel(P, k, wox, woy, woz, wix, wiy, wiz)
    if not ok:
        return 0.0, 0.0, 0.0, 0.0
    return wr * pdf, wg * pdf, wb * pdf, pdf


@njit
def _glossy_sample(P, k, wox, woy, woz, u1, u2x, u2y):
    flip = woz < 0.0
    if flip:
        woz = -woz
    if P[k, 1] == 0.0 and P[k, 2] == 0.0 and P[k, 3] == 0.0:
        return 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, False, False
    tx = 1.0
    ty = 0.0
    e_u, e_v, _ = _as_exponents(P, k)
    # AshikhminShirley.sample: azimuth from the quadrant formula
    q = np.floor(4.0 * u2x)
    up = 4.0 * u2x - q
    half = 0.5 * _PI * up
    phi0 = math.atan2(math.sqrt(e_u + 1.0) * math.sin(half), math.sqrt(e_v + 1.0) * math.cos(half))
    if q == 0.0:
        phi = phi0
    elif q == 1.0:
        phi = _PI - phi0
    elif q == 2.0:
        phi = _PI + phi0
    else:
        phi = 2.0 * _PI - phi0
    cp = math.cos(phi)
    sp = math.sin(phi)
    e = e_u * cp * cp + e_v * sp * sp
    # cos theta = (1 - u)^(1/(e+1)), with 1 - cos kept accurate for huge exponents
    one_minus_cos = -math.expm1(math.log1p(-u2y) / (e + 1.0))
    cos_t = 1.0 - one_minus_cos
    sin_t = math.sqrt(max(one_minus_cos * (2.0 - one_minus_cos), 0.0))
    ht = sin_t * cp
    hb = sin_t * sp
    hx = ht * tx + hb * ty
    hy = ht * ty - hb * tx
    hz = cos_t
    # v-cavities: the facet rotated by pi about n, chosen with prob. ~ max(0, wo.h')
    a = max(_dot(wox, woy, woz, hx, hy, hz), 0.0)
    a_alt = max(_dot(wox, woy, woz, -hx, -hy, hz), 0.0)
    tot = a + a_alt
    if not tot > 0.0:
        return 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, False, False
    q = a_alt / tot
    if u1 < q:
        hx = -hx
        hy = -hy
    c = _dot(wox, woy, woz, hx, hy, hz)
    # (u1 is rescaled and reused for the event choice, which scatter_reflect does not need)
    if not c > 0.0:
        return 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, False, False
    two_c = 2.0 * c
    wix = two_c * hx - wox
    wiy = two_c * hy - woy
    wiz = two_c * hz - woz
    if not wiz > 0.0:
        return 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, False, False
    wr, wg, wb, pdf, ok = _glossy_kernel(P, k, wox, woy, woz, wix, wiy, wiz)
    if not ok:
        return 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, False, False
    if flip:
        wiz = -wiz
    return wix, wiy, wiz, pdf, wr, wg, wb, False, True


# --- specular_bsdf (scatter_reflect) ----------------------------------------------------------


@njit
def _specular_sample(P, k, wox, woy, woz):
    tr, tg, tb = P[k, 1], P[k, 2], P[k, 3]
    flip = woz < 0.0
    if flip:
        woz = -woz
    black = tr == 0.0 and tg == 0.0 and tb == 0.0
    # the mirror direction has wi.z = wo.z: one test covers both of the class's
    if black or not woz > _COS_ZERO:
        return 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, False, False
    wiz = -woz if flip else woz
    return -wox, -woy, wiz, 1.0, tr, tg, tb, True, True


# --- the interface ------------------------------------------------------------------------


@njit
def eval_pdf(P, k, wox, woy, woz, wix, wiy, wiz):
    """``Bsdf.eval`` and ``Bsdf.pdf`` of the numpy class, for one lane.

    Parameters
    ----------
    P : (m, PARAM_WIDTH) float64
        Rows from :func:`params_of` or :func:`rows_of`.
    k : int
        The lane's row of ``P`` (a table and an index rather than a row view: a view
        per lane costs two atomic reference-count updates in numba).
    wox, woy, woz, wix, wiy, wiz : float
        Unit directions ``wo`` (toward the viewer) and ``wi`` (toward the light) in the
        local frame (``z`` the shading normal, ``x`` along ``tangent_u``).

    Returns
    -------
    f_r, f_g, f_b : float
        ``f(wo, wi) |cos theta_i|``.
    pdf : float
        Solid-angle density of :func:`sample` choosing ``wi``; 0 for :data:`SPECULAR`
        and :data:`BLACK` (delta lobes are reached only by sampling).
    """
    kind = P[k, 0]
    if kind == DIFFUSE_REFLECTION:
        return _diffuse_eval_pdf(P, k, wox, woy, woz, wix, wiy, wiz)
    if kind == SIMPLE_GLOSSY:
        return _glossy_eval_pdf(P, k, wox, woy, woz, wix, wiy, wiz)
    return 0.0, 0.0, 0.0, 0.0


@njit
def sample(P, k, wox, woy, woz, u1, u2x, u2y):
    """``Bsdf.sample`` of the numpy class with the same random numbers, for one lane.

    Parameters
    ----------
    P : (m, PARAM_WIDTH) float64
        Rows from :func:`params_of` or :func:`rows_of`.
    k : int
        The lane's row of ``P`` (a table and an index rather than a row view: a view
        per lane costs two atomic reference-count updates in numba).
    wox, woy, woz : float
        Unit ``wo`` in the local frame.
    u1, u2x, u2y : float
        Uniform variates (the numpy class's ``u1`` and the two columns of ``u2``),
        clamped into ``[0, 1)`` as :func:`render.bsdf.check_samples` does.

    Returns
    -------
    wix, wiy, wiz : float
        The sampled direction (0 where the sample failed).
    pdf : float
        Its solid-angle density; for :data:`SPECULAR` the event probability 1.
    w_r, w_g, w_b : float
        ``eval / pdf`` (the tint for :data:`SPECULAR`).
    is_delta : bool
        A specular (delta) event.
    valid : bool
        False where the numpy sample fails (lobe 0; then every other output is 0).
    """
    u1 = _clamp_u(u1)
    u2x = _clamp_u(u2x)
    u2y = _clamp_u(u2y)
    kind = P[k, 0]
    if kind == DIFFUSE_REFLECTION:
        return _diffuse_sample(P, k, wox, woy, woz, u2x, u2y)
    if kind == SIMPLE_GLOSSY:
        return _glossy_sample(P, k, wox, woy, woz, u1, u2x, u2y)
    if kind == SPECULAR:
        return _specular_sample(P, k, wox, woy, woz)
    return 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, False, False


@njit
def eval_pdf_batch(p, wo, wi):
    """:func:`eval_pdf` over lanes (for tests and small batches).

    Parameters
    ----------
    p : (PARAM_WIDTH,) float64
    wo, wi : (n, 3) float64

    Returns
    -------
    f : (n, 3) float64
    pdf : (n,) float64
    """
    P = p.reshape((1, p.size))
    n = wo.shape[0]
    f = np.zeros((n, 3))
    pdf = np.zeros(n)
    for i in range(n):
        f[i, 0], f[i, 1], f[i, 2], pdf[i] = eval_pdf(
            P, 0, wo[i, 0], wo[i, 1], wo[i, 2], wi[i, 0], wi[i, 1], wi[i, 2]
        )
    return f, pdf


@njit
def sample_batch(p, wo, u1, u2):
    """:func:`sample` over lanes (for tests and small batches).

    Parameters
    ----------
    p : (PARAM_WIDTH,) float64
    wo : (n, 3) float64
    u1 : (n,) float64
    u2 : (n, 2) float64

    Returns
    -------
    wi : (n, 3) float64
    pdf : (n,) float64
    weight : (n, 3) float64
    is_delta, valid : (n,) bool
    """
    P = p.reshape((1, p.size))
    n = wo.shape[0]
    wi = np.zeros((n, 3))
    pdf = np.zeros(n)
    weight = np.zeros((n, 3))
    is_delta = np.zeros(n, np.bool_)
    valid = np.zeros(n, np.bool_)
    for i in range(n):
        (
            wi[i, 0],
            wi[i, 1],
            wi[i, 2],
            pdf[i],
            weight[i, 0],
            weight[i, 1],
            weight[i, 2],
            is_delta[i],
            valid[i],
        ) = sample(P, 0, wo[i, 0], wo[i, 1], wo[i, 2], u1[i], u2[i, 0], u2[i, 1])
    return wi, pdf, weight, is_delta, valid
