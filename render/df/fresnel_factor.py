"""MDL ``df::fresnel_factor``: a Bsdf scaled by the Fresnel reflectance of a conductor.

MDL signature (1.4)::

    bsdf fresnel_factor(color ior, color extinction_coefficient, bsdf base = bsdf());

Model (libbsdf, ``reference/mdl-distribution-functions.md`` §4): the unpolarised
Fresnel reflectance of a conducting interface, per channel, with the complex index
``eta + i kappa``, ``eta = ior / eta1`` and ``kappa = extinction_coefficient / eta1``
relative to the medium on ``wo``'s side (``eta1``: ``ior_outside`` from outside or on
thin walls, ``ior_inside`` from inside), at ``c = wo.h`` for the reflection half vector
(a transmitted ``wi`` mirrored first; 0 where ``wo.h < 0``)::

    s2 = 1 - c^2;  t0 = eta^2 - kappa^2 - s2;  a2b2 = sqrt(t0^2 + 4 eta^2 kappa^2)
    a = sqrt((a2b2 + t0) / 2);  Rs = (a2b2 + c^2 - 2 a c) / (a2b2 + c^2 + 2 a c)
    Rp = Rs (c^2 a2b2 + s2^2 - 2 a c s2) / (c^2 a2b2 + s2^2 + 2 a c s2);  F = (Rs + Rp) / 2

With ``kappa = 0`` this is the dielectric Fresnel term of ``fresnel_layer``.  Under
``thin_film`` the factor is the film's reflectance on the conductor
(:mod:`render.df.thin_film`).  ``eval =
F(wo.h) base.eval``, the pdf the base's; the factor never exceeds 1.
"""

from __future__ import annotations

import math

import numpy as np

from render.df._layer import scale_cosine
from render.df._registry import Df, Node
from render.df._signature import REQUIRED, THIN_WALLED, Param, Signature
from render.df.thin_film import FILM_PARAMS, film_rgb
from render.jit import njit

__all__ = ["FresnelFactor", "fresnel_factor", "SIGNATURE", "scale", "fresnel_conductor"]

#: ``df::fresnel_factor`` plus the renderer's IORs on the ``+z`` and ``-z`` sides
SIGNATURE = Signature("bsdf", (
    Param("ior", "color", REQUIRED),
    Param("extinction_coefficient", "color", REQUIRED, clamp=(0.0, None)),
    Param("base", "bsdf", None),
    *FILM_PARAMS,
), context=("ior_outside", "ior_inside"))
_IOR = SIGNATURE.offset("ior")
_FILM_D = SIGNATURE.offset("thin_film_thickness")
_FILM_N = SIGNATURE.offset("thin_film_ior")
_K = SIGNATURE.offset("extinction_coefficient")
_OUT = SIGNATURE.offset("ior_outside")
_IN = SIGNATURE.offset("ior_inside")


@njit
def fresnel_conductor(c, eta, kappa):
    """Unpolarised reflectance of a conductor ``eta + i kappa`` at cosine ``c`` (in [0, 1],
    saturated; 1 at grazing incidence and for a non-positive ``eta``).

    Examples
    --------
    >>> round(fresnel_conductor(1.0, 1.5, 0.0), 12)
    0.04
    """
    c = min(max(c, 0.0), 1.0)
    if not (eta > 0.0) or not c > 0.0:
        return 1.0
    c2 = c * c
    s2 = 1.0 - c2
    e2 = eta * eta
    k2 = kappa * kappa
    t0 = e2 - k2 - s2
    a2b2 = math.sqrt(t0 * t0 + 4.0 * e2 * k2)
    a = math.sqrt(max(0.5 * (a2b2 + t0), 0.0))
    t1 = a2b2 + c2
    t2 = 2.0 * a * c
    rs = (t1 - t2) / (t1 + t2) if t1 + t2 > 0.0 else 1.0
    t3 = c2 * a2b2 + s2 * s2
    t4 = t2 * s2
    rp = rs * (t3 - t4) / (t3 + t4) if t3 + t4 > 0.0 else rs
    return min(max(0.5 * (rs + rp), 0.0), 1.0)


@njit
def scale(P, row, b, flags, wox, woy, woz, wix, wiy, wiz):
    """the conductor Fresnel factor per channel at ``wo.h``, relative to ``wo``'s side."""
    c = scale_cosine(wox, woy, woz, wix, wiy, wiz)
    if c < 0.0:
        return 0.0, 0.0, 0.0
    inside = woz < 0.0 and (flags & THIN_WALLED) == 0
    e1 = P[row, b + _IN] if inside else P[row, b + _OUT]
    if not e1 > 0.0:
        return 1.0, 1.0, 1.0
    if P[row, b + _FILM_D] > 0.0:  # under a thin_film: the film on the conductor
        return film_rgb(c, e1, P[row, b + _FILM_N], P[row, b + _FILM_N + 1],
                        P[row, b + _FILM_N + 2], P[row, b + _IOR], P[row, b + _IOR + 1],
                        P[row, b + _IOR + 2], P[row, b + _K], P[row, b + _K + 1],
                        P[row, b + _K + 2], P[row, b + _FILM_D])
    return (fresnel_conductor(c, P[row, b + _IOR] / e1, P[row, b + _K] / e1),
            fresnel_conductor(c, P[row, b + _IOR + 1] / e1, P[row, b + _K + 1] / e1),
            fresnel_conductor(c, P[row, b + _IOR + 2] / e1, P[row, b + _K + 2] / e1))


def _check(values: dict) -> None:
    ior = np.asarray(values["ior"], dtype=np.float64)
    if not np.all(np.isfinite(ior)) or np.any(ior <= 0.0):
        raise ValueError(f"df::fresnel_factor: ior must be > 0 (the real part of a "
                         f"conductor's index of refraction), got {values['ior']!r}")


NODE = Node("fresnel_factor", "bsdf", "modifier", SIGNATURE, scale=scale)
DF = Df("fresnel_factor", SIGNATURE, (NODE,), check=_check)
FresnelFactor = DF.cls
fresnel_factor = FresnelFactor
