"""MDL ``df::anisotropic_vdf``: the Henyey–Greenstein phase function of a homogeneous medium.

MDL signature::

    vdf anisotropic_vdf(float directional_bias = 0.0, uniform string handle = "");

Model (``reference/mdl-distribution-functions.md`` §6; Handbook §5.4): with
``g = directional_bias`` in [-1, 1] (0 isotropic, > 0 forward, < 0 backward) and
``theta`` the angle between the old propagation direction ``-wo`` and the new one
``wi``::

    p(wo, wi) = (1 - g^2) / (4 pi (1 + g^2 - 2 g cos theta)^(3/2)),   cos theta = -wo . wi

normalised over the whole sphere.  As a :class:`~render.bsdf.Bsdf`, ``eval`` is ``p``
in every channel (a phase function has no cosine factor), ``pdf`` is ``p`` (sampling is
exact), the sample weight is 1 and ``albedo`` is 1 (the medium's single-scattering
albedo ``sigma_s / sigma_t`` is applied by :mod:`render.volume`).

Directions need no shading frame: the lobe is symmetric about ``-wo``, so ``wo``/``wi``
may be given in any orthonormal frame (the integrator uses world space).  A sample's
lobe flag is ``DIFFUSE_REFLECTION`` when it scatters back toward the viewer's side
(``wi . wo > 0``) and ``DIFFUSE_TRANSMISSION`` otherwise (there is no volume flag in
:class:`~render.bsdf.Lobe`).

Numerics
--------
* ``1 + g^2 - 2 g cos theta`` is computed as ``(1 - g)^2 + g |wo + wi|^2`` for
  ``g >= 0`` and ``(1 + g)^2 - g |wo - wi|^2`` for ``g < 0``: no cancellation at the
  peak, for positive and negative bias alike (the MDL SDK example's fallback to
  isotropic below ``g = 0.001`` mishandles negative bias; this has no fallback);
* the inverse CDF ``cos theta = (1 + g^2 - ((1 - g^2) / (1 + g a))^2) / (2 g)`` with
  ``a = 2 xi - 1`` is used in the equivalent form
  ``(a + g (a^2 + 3) / 2 + g^2 a + g^3 (a^2 - 1) / 2) / (1 + g a)^2``, exact for every
  ``g`` including 0 (no special case, no division by ``g``);
* ``|g|`` is clamped to :data:`G_MAX` (``g = +-1`` would be a delta: straight through
  or straight back); at ``g = 0.9999`` the lobe is about 1e-4 rad wide.
"""

from __future__ import annotations

import math

import numpy as np

from render._typing import Arr, ArrayLike, Vec3
from render.bsdf import Lobe
from render.df import _kernel_common as kc
from render.df._registry import Df, Node
from render.df._signature import Param, Signature
from render.jit import njit

__all__ = [
    "AnisotropicVdf",
    "anisotropic_vdf",
    "G_MAX",
    "hg_phase",
    "SIGNATURE",
    "eval_pdf",
    "sample",
    "albedo",
]

#: largest ``|directional_bias|`` used (values up to 1 are accepted and clamped to it)
G_MAX = 1.0 - 1e-4
_INV_4PI = 1.0 / (4.0 * np.pi)


# --- signature and kernels (the compiled render core) ---------------------------------

SIGNATURE = Signature("vdf", (
    Param("directional_bias", "float", 0.0, clamp=(-G_MAX, G_MAX)),
    Param("handle", "string", "", uniform=True),
))
_BIAS = SIGNATURE.offset("directional_bias")
_K_INV_4PI = float(_INV_4PI)
_TWO_PI = 2.0 * float(np.pi)


@njit
def _hg(g, wox, woy, woz, wix, wiy, wiz):
    """:func:`hg_phase` of one lane (``g`` in ``[-G_MAX, G_MAX]``)."""
    if g >= 0.0:
        sx, sy, sz = wox + wix, woy + wiy, woz + wiz
        gp = g
        denom = (1.0 - gp) * (1.0 - gp) + gp * kc.dot3(sx, sy, sz, sx, sy, sz)
    else:
        sx, sy, sz = wox - wix, woy - wiy, woz - wiz
        gn = g
        denom = (1.0 + gn) * (1.0 + gn) - gn * kc.dot3(sx, sy, sz, sx, sy, sz)
    if not denom > 0.0:  # only for non-unit directions
        return 0.0
    return (1.0 - g * g) * _K_INV_4PI / (denom * math.sqrt(denom))


@njit
def _bias_of(P, row, b):
    """The lane's ``g``, clamped to ``[-G_MAX, G_MAX]`` (kernels stay safe on any input)."""
    return min(max(P[row, b + _BIAS], -G_MAX), G_MAX)


@njit
def eval_pdf(P, row, b, flags, wox, woy, woz, wix, wiy, wiz):
    """The phase function ``p`` in every channel and as the pdf -> ``(p, p, p, p)``
    (no cosine factor; directions in any orthonormal frame)."""
    p = _hg(_bias_of(P, row, b), wox, woy, woz, wix, wiy, wiz)
    return p, p, p, p


@njit
def sample(P, row, b, flags, wox, woy, woz, u1, u2x, u2y):
    """Exact Henyey–Greenstein sample about ``-wo`` -> ``(wix, wiy, wiz, pdf, 1, 1, 1,
    lobe)``; ``lobe`` DIFFUSE_REFLECTION toward the viewer's side, else
    DIFFUSE_TRANSMISSION."""
    g = _bias_of(P, row, b)
    a = 2.0 * kc.clamp_u(u2x) - 1.0
    den = 1.0 + g * a  # >= 1 - G_MAX > 0
    cos_t = (a + 0.5 * g * (a * a + 3.0) + g * g * a + 0.5 * math.pow(g, 3.0) * (a * a - 1.0)) / (
        den * den)
    cos_t = min(max(cos_t, -1.0), 1.0)
    sin_t = math.sqrt(max(1.0 - cos_t * cos_t, 0.0))
    phi = _TWO_PI * kc.clamp_u(u2y)
    cp = sin_t * math.cos(phi)
    sp = sin_t * math.sin(phi)
    nx, ny, nz = -wox, -woy, -woz
    sx, sy, sz, tx, ty, tz = kc.frame_from_normal(nx, ny, nz)
    wix = cp * sx + sp * tx + cos_t * nx
    wiy = cp * sy + sp * ty + cos_t * ny
    wiz = cp * sz + sp * tz + cos_t * nz
    length = math.sqrt(wix * wix + wiy * wiy + wiz * wiz)
    if not length > 0.5:  # a unit wo gives a unit wi; a zero wo fails
        return 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0
    wix = wix / length
    wiy = wiy / length
    wiz = wiz / length
    pdf = _hg(g, wox, woy, woz, wix, wiy, wiz)
    back = kc.dot3(wix, wiy, wiz, wox, woy, woz) > 0.0
    lobe = kc.LOBE_DIFFUSE_REFLECTION if back else kc.LOBE_DIFFUSE_TRANSMISSION
    return wix, wiy, wiz, pdf, 1.0, 1.0, 1.0, lobe


@njit
def albedo(P, row, b, flags, wox, woy, woz):
    """1 (the medium's single-scattering albedo is applied by :mod:`render.volume`)."""
    return 1.0, 1.0, 1.0


# --- the Python class ------------------------------------------------------------------


def _check(values: dict) -> None:
    g = np.asarray(values["directional_bias"], dtype=np.float64)
    if not np.all(np.isfinite(g)) or np.any(np.abs(g) > 1.0):
        raise ValueError(f"directional_bias must be in [-1, 1], got {values['directional_bias']!r}")


NODE = Node("anisotropic_vdf", "vdf", "leaf", SIGNATURE, eval_pdf=eval_pdf, sample=sample,
            albedo=albedo)
DF = Df("anisotropic_vdf", SIGNATURE, (NODE,), lobes=Lobe.DIFFUSE, check=_check)
AnisotropicVdf = DF.cls
anisotropic_vdf = AnisotropicVdf


def hg_phase(g: ArrayLike, wo: Vec3, wi: Vec3) -> Arr:
    """The Henyey–Greenstein phase function ``p(wo, wi)`` (per steradian), (n,): the
    :func:`eval_pdf` kernel's pdf.

    Examples
    --------
    >>> wo = np.array([[0.0, 0.0, 1.0]] * 2)
    >>> wi = np.array([[0.0, 0.0, -1.0], [0.0, 0.0, 1.0]])   # forward, backward
    >>> p = hg_phase(0.5, wo, wi) * 4 * np.pi
    >>> np.round(p, 12).tolist()                  # (1 - g^2) / (1 -+ g)^3
    [6.0, 0.222222222222]
    """
    return AnisotropicVdf(g).pdf(wo, wi)
