"""MDL ``df::diffuse_transmission_bsdf``: Lambertian transmission to the far side, no refraction.

MDL signature::

    bsdf diffuse_transmission_bsdf(color tint = color(1.0), uniform string handle = "");

Model (libbsdf, ``reference/mdl-distribution-functions.md`` §2.2): the Lambert lobe
mirrored to the side opposite ``wo``, ``eval = saturate(tint) |wi.z| / pi`` for
``wi.z wo.z < 0``; cosine-weighted sampling, weight ``tint``; the IOR plays no part.
Departure: the bump renormalisation ``1/(pi/2 (1 + n.ng))`` is left to the integrator.
"""

from __future__ import annotations

from render.bsdf import Lobe
from render.df import _kernel_common as kc
from render.df._registry import Df, Node
from render.df._signature import Param, Signature
from render.jit import njit

__all__ = [
    "DiffuseTransmissionBsdf",
    "diffuse_transmission_bsdf",
    "SIGNATURE",
    "eval_pdf",
    "sample",
    "albedo",
]


# --- signature and kernels (the compiled render core) ---------------------------------

SIGNATURE = Signature("bsdf", (
    Param("tint", "color", (1.0, 1.0, 1.0), clamp=(0.0, 1.0)),
    Param("handle", "string", "", uniform=True),
))
_TINT = SIGNATURE.offset("tint")


@njit
def eval_pdf(P, row, b, flags, wox, woy, woz, wix, wiy, wiz):
    """``eval`` (with ``|cos theta_i|``) and ``pdf`` of one lane -> ``(f0, f1, f2, pdf)``:
    the Lambert lobe on the side opposite ``wo``."""
    t0, t1, t2 = P[row, b + _TINT], P[row, b + _TINT + 1], P[row, b + _TINT + 2]
    flip, woz = kc.orient(woz)
    wiz = kc.mirror_z(wiz, flip)
    if not (woz > kc.COS_ZERO and wiz < -kc.COS_ZERO) or (t0 == 0.0 and t1 == 0.0 and t2 == 0.0):
        return 0.0, 0.0, 0.0, 0.0
    pdf = -wiz * kc.INV_PI
    return t0 * pdf, t1 * pdf, t2 * pdf, pdf


@njit
def sample(P, row, b, flags, wox, woy, woz, u1, u2x, u2y):
    """Cosine-weighted sample of the far side -> ``(wix, wiy, wiz, pdf, w0, w1, w2, lobe)``."""
    t0, t1, t2 = P[row, b + _TINT], P[row, b + _TINT + 1], P[row, b + _TINT + 2]
    flip, woz = kc.orient(woz)
    wix, wiy, wiz = kc.cosine_hemisphere(kc.clamp_u(u2x), kc.clamp_u(u2y))
    wiz = -wiz
    if not (woz > kc.COS_ZERO and wiz < -kc.COS_ZERO) or (t0 == 0.0 and t1 == 0.0 and t2 == 0.0):
        return 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0
    return (wix, wiy, kc.mirror_z(wiz, flip), -wiz * kc.INV_PI, t0, t1, t2,
            kc.LOBE_DIFFUSE_TRANSMISSION)


@njit
def albedo(P, row, b, flags, wox, woy, woz):
    """Directional albedo of one lane: ``tint`` -> ``(a0, a1, a2)``."""
    if not abs(woz) > kc.COS_ZERO:
        return 0.0, 0.0, 0.0
    return P[row, b + _TINT], P[row, b + _TINT + 1], P[row, b + _TINT + 2]


# --- the Python class ------------------------------------------------------------------

NODE = Node("diffuse_transmission_bsdf", "bsdf", "leaf", SIGNATURE, eval_pdf=eval_pdf,
            sample=sample, albedo=albedo)
DF = Df("diffuse_transmission_bsdf", SIGNATURE, (NODE,), lobes=Lobe.DIFFUSE_TRANSMISSION)
DiffuseTransmissionBsdf = DF.cls
diffuse_transmission_bsdf = DiffuseTransmissionBsdf
