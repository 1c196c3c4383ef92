"""MDL ``df::specular_bsdf``: a delta lobe that mirrors, refracts, or splits by dielectric Fresnel.

MDL signature::

    bsdf specular_bsdf(color tint = color(1.0), uniform scatter_mode mode = scatter_reflect,
                       uniform string handle = "");

Model (libbsdf, ``reference/mdl-distribution-functions.md`` §2, §2.3).  ``eval`` and
``pdf`` are 0 (a delta is reached only by sampling).  With ``c = |wo.z|``:

* ``scatter_reflect``: mirror ``wi = (-wo.x, -wo.y, wo.z)``, weight ``saturate(tint)``,
  **no Fresnel** (a layerer such as ``fresnel_layer`` supplies it);
* ``scatter_transmit``: always transmit, weight ``tint``; total internal reflection
  turns the event into a mirror reflection with full weight;
* ``scatter_reflect_transmit``: dielectric Fresnel ``F = F(eta2/eta1, c)`` picks the
  reflection with probability ``F`` (sample ``pdf = F``) and the transmission with
  ``1 - F``; the weight stays ``tint``.

Transmission refracts with ``eta1 / eta2`` (``eta1`` on ``wo``'s side; ``+z`` is the
outside, so lanes viewed from below swap ``ior_outside`` and ``ior_inside``); on a
thin-walled surface it passes straight through, ``wi = -wo``, and Fresnel still uses the
IOR pair.  ``albedo = saturate(tint)`` in every mode.

The renderer passes the IORs (``reference`` §1.3): ``ior_outside`` is the medium on the
``+z`` side (1 for air), ``ior_inside`` is ``material.ior`` averaged over its channels.

Departure from libbsdf: an exact index match (``ior_inside == ior_outside``) is handled
exactly (``F = 0``, ``wi = -wo``) instead of pushing the IORs 1e-4 apart.
"""

from __future__ import annotations

import numpy as np

from render.bsdf import Lobe
from render.df import _kernel_common as kc
from render.df._registry import Df, Node
from render.df._signature import (
    MODE_MASK,
    REFLECT,
    REFLECT_TRANSMIT,
    THIN_WALLED,
    TRANSMIT,
    Param,
    Signature,
)
from render.df.thin_film import FILM_PARAMS, film_rgb
from render.jit import njit

__all__ = [
    "SpecularBsdf",
    "specular_bsdf",
    "SIGNATURE",
    "eval_pdf",
    "sample",
    "albedo",
]

_Z = np.array([0.0, 0.0, 1.0])

# --- signature and kernels (the compiled render core) ---------------------------------

SIGNATURE = Signature("bsdf", (
    Param("tint", "color", (1.0, 1.0, 1.0), clamp=(0.0, 1.0)),
    Param("mode", "scatter_mode", "scatter_reflect", uniform=True),
    Param("handle", "string", "", uniform=True),
    *FILM_PARAMS,
), context=("ior_outside", "ior_inside"))
_TINT = SIGNATURE.offset("tint")
_IOR_OUTSIDE = SIGNATURE.offset("ior_outside")
_IOR_INSIDE = SIGNATURE.offset("ior_inside")
_FILM_D = SIGNATURE.offset("thin_film_thickness")
_FILM_N = SIGNATURE.offset("thin_film_ior")


@njit
def eval_pdf(P, row, b, flags, wox, woy, woz, wix, wiy, wiz):
    """A delta lobe: ``(0, 0, 0, 0)`` (reached only by :func:`sample`)."""
    return 0.0, 0.0, 0.0, 0.0


@njit
def sample(P, row, b, flags, wox, woy, woz, u1, u2x, u2y):
    """The mirror or refracted direction of one lane -> ``(wix, wiy, wiz, pdf, w0, w1, w2,
    lobe)``; ``pdf`` is the event's probability (Fresnel's ``F`` or ``1 - F`` in
    ``scatter_reflect_transmit``, else 1), the weight ``tint``.

    ``flags & MODE_MASK`` is the scatter mode, ``flags & THIN_WALLED`` passes
    transmission straight through (``wi = -wo``).  IORs not both positive (the packer
    rejects them) scatter nothing.
    """
    t0, t1, t2 = P[row, b + _TINT], P[row, b + _TINT + 1], P[row, b + _TINT + 2]
    ior_o, ior_i = P[row, b + _IOR_OUTSIDE], P[row, b + _IOR_INSIDE]
    mode = flags & MODE_MASK
    thin = (flags & THIN_WALLED) != 0
    flip, c = kc.orient(woz)
    if not c > kc.COS_ZERO or (t0 == 0.0 and t1 == 0.0 and t2 == 0.0):
        return 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0
    if not (ior_o > 0.0 and ior_i > 0.0):
        return 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0
    eta1, eta2 = kc.ior_pair(ior_o, ior_i, flip, thin, False)
    # the probability of reflection per mode
    if mode == REFLECT:
        p_refl = 1.0
    elif mode == TRANSMIT:
        bb = eta1 / eta2
        p_refl = 1.0 if bb * bb * (1.0 - c * c) > 1.0 and not thin else 0.0  # only TIR
    else:
        p_refl, _ = kc.fresnel_dielectric(c, eta2 / eta1)
    d = P[row, b + _FILM_D]
    film = mode == REFLECT_TRANSMIT and d > 0.0
    if film:  # a thin_film's reflectance replaces Fresnel (render.df.thin_film)
        r0, r1, r2 = film_rgb(c, eta1, P[row, b + _FILM_N], P[row, b + _FILM_N + 1],
                              P[row, b + _FILM_N + 2], eta2, eta2, eta2, 0.0, 0.0, 0.0, d)
        p_refl = (r0 + r1 + r2) / 3.0
    refl = kc.clamp_u(u1) < p_refl
    if refl:
        prob = p_refl
        wix, wiy, wiz = -wox, -woy, c
        ok = wiz > kc.COS_ZERO
        lobe = kc.LOBE_SPECULAR_REFLECTION
    else:
        prob = 1.0 - p_refl
        if thin:
            wix, wiy, wiz = -wox, -woy, -c
        else:
            wix, wiy, wiz, _ = kc.refract(wox, woy, c, 0.0, 0.0, 1.0, eta1 / eta2)
        ok = wiz < -kc.COS_ZERO
        lobe = kc.LOBE_SPECULAR_TRANSMISSION
    if not (ok and prob > 0.0):
        return 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0
    if film:  # the film's colour: F_c / P reflected, (1 - F_c) / (1 - P) transmitted
        if refl:
            t0, t1, t2 = t0 * r0 / prob, t1 * r1 / prob, t2 * r2 / prob
        else:
            t0, t1, t2 = (t0 * (1.0 - r0) / prob, t1 * (1.0 - r1) / prob,
                          t2 * (1.0 - r2) / prob)
        if not (t0 > 0.0 or t1 > 0.0 or t2 > 0.0):
            return 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0
    return wix, wiy, kc.mirror_z(wiz, flip), prob, t0, t1, t2, lobe


@njit
def albedo(P, row, b, flags, wox, woy, woz):
    """Directional albedo of one lane: ``tint`` in every mode -> ``(a0, a1, a2)``."""
    if not abs(woz) > kc.COS_ZERO:
        return 0.0, 0.0, 0.0
    return P[row, b + _TINT], P[row, b + _TINT + 1], P[row, b + _TINT + 2]


# --- the Python class ------------------------------------------------------------------

NODE = Node("specular_bsdf", "bsdf", "leaf", SIGNATURE,
            mirror=True, eval_pdf=eval_pdf, sample=sample, albedo=albedo)
DF = Df("specular_bsdf", SIGNATURE, (NODE,), lobes={"scatter_reflect": Lobe.SPECULAR_REFLECTION,
                         "scatter_transmit": Lobe.SPECULAR,
                         "scatter_reflect_transmit": Lobe.SPECULAR})
SpecularBsdf = DF.cls
specular_bsdf = SpecularBsdf
