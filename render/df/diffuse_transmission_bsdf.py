"""MDL ``df::diffuse_transmission_bsdf``: Lambertian transmission to the far side, no refraction.

MDL signature::

    bsdf diffuse_transmission_bsdf(color tint = color(1.0), uniform string handle = "");

Model (libbsdf, ``reference/mdl-distribution-functions.md`` §2.2): the Lambert lobe
mirrored to the side opposite ``wo``, ``eval = saturate(tint) |wi.z| / pi`` for
``wi.z wo.z < 0``; cosine-weighted sampling, weight ``tint``; the IOR plays no part.
Departure: the bump renormalisation ``1/(pi/2 (1 + n.ng))`` is left to the integrator.
"""

from __future__ import annotations

import numpy as np

from render._typing import Arr, Arr2, ArrayLike, Rgb, Vec3
from render.bsdf import Bsdf, BsdfSample, Lobe, check_dirs, check_samples, lane_color, lanes
from render.df import _kernel_common as kc
from render.df._common import INV_PI, orient
from render.df._signature import Param, Signature
from render.frame import mirror_z
from render.jit import njit
from render.numerics import TOL, saturate
from render.warp import square_to_cosine_hemisphere

__all__ = ["DiffuseTransmissionBsdf", "diffuse_transmission_bsdf"]


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
    pdf = -wiz * INV_PI
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
    return (wix, wiy, kc.mirror_z(wiz, flip), -wiz * INV_PI, t0, t1, t2,
            kc.LOBE_DIFFUSE_TRANSMISSION)


@njit
def albedo(P, row, b, flags, wox, woy, woz):
    """Directional albedo of one lane: ``tint`` -> ``(a0, a1, a2)``."""
    if not abs(woz) > kc.COS_ZERO:
        return 0.0, 0.0, 0.0
    return P[row, b + _TINT], P[row, b + _TINT + 1], P[row, b + _TINT + 2]


# --- the numpy reference (deleted once the program adapters replace it) ----------------


class DiffuseTransmissionBsdf(Bsdf):
    """``df::diffuse_transmission_bsdf`` over lanes.

    Parameters
    ----------
    tint : float, (3,) or (n, 3)
        Saturated to [0, 1].

    Examples
    --------
    >>> bsdf = diffuse_transmission_bsdf(tint=[1.0, 0.5, 0.0])
    >>> wo = np.array([[0.0, 0.0, 1.0], [0.0, 0.0, 1.0]])
    >>> wi = np.array([[0.0, 0.0, -1.0], [0.0, 0.0, 1.0]])
    >>> (bsdf.eval(wo, wi) * np.pi).tolist()
    [[1.0, 0.5, 0.0], [0.0, 0.0, 0.0]]
    """

    lobes = Lobe.DIFFUSE_TRANSMISSION

    def __init__(self, tint: ArrayLike = 1.0):
        self.tint = saturate(lane_color(tint, "tint"))
        self._black = np.all(self.tint == 0, axis=1)

    def __repr__(self) -> str:
        return f"diffuse_transmission_bsdf(tint={self.tint.tolist()})"

    def _valid(self, wo: Vec3, wi: Vec3) -> np.ndarray:
        n = len(wo)
        black = np.broadcast_to(lanes(self._black, n, "tint"), (n,))
        return (wo[:, 2] > TOL.cos_zero) & (wi[:, 2] < -TOL.cos_zero) & ~black

    def eval(self, wo: Vec3, wi: Vec3) -> Rgb:
        wo, wi = check_dirs(wo, wi)
        _, wo, wi = orient(wo, wi)
        valid = self._valid(wo, wi)
        return np.where(
            valid[:, None], lanes(self.tint, len(wo), "tint") * (-wi[:, 2] * INV_PI)[:, None], 0.0
        )

    def pdf(self, wo: Vec3, wi: Vec3) -> Arr:
        wo, wi = check_dirs(wo, wi)
        _, wo, wi = orient(wo, wi)
        return np.where(self._valid(wo, wi), -wi[:, 2] * INV_PI, 0.0)

    def sample(self, wo: Vec3, u1: Arr, u2: Arr2) -> BsdfSample:
        (wo,) = check_dirs(wo, names=("wo",))
        u1, u2 = check_samples(len(wo), u1, u2)
        flip, wo = orient(wo)
        wi = mirror_z(square_to_cosine_hemisphere(u2))
        valid = self._valid(wo, wi)
        pdf = np.where(valid, -wi[:, 2] * INV_PI, 0.0)
        weight = np.where(valid[:, None], lanes(self.tint, len(wo), "tint"), 0.0)
        wi = np.where(valid[:, None], mirror_z(wi, flip), 0.0)
        lobe = np.where(valid, int(Lobe.DIFFUSE_TRANSMISSION), 0).astype(np.int32)
        return BsdfSample(wi, pdf, weight, lobe).checked()

    def albedo(self, wo: Vec3) -> Rgb:
        (wo,) = check_dirs(wo, names=("wo",))
        ok = np.abs(wo[:, 2]) > TOL.cos_zero
        return np.where(
            ok[:, None], np.broadcast_to(lanes(self.tint, len(wo), "tint"), (len(wo), 3)), 0.0
        )


diffuse_transmission_bsdf = DiffuseTransmissionBsdf
