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

from render._typing import Arr, Arr2, ArrayLike, Rgb, Vec3
from render.bsdf import Bsdf, BsdfSample, Lobe, check_dirs, check_samples, lane_color, lanes
from render.df import _kernel_common as kc
from render.df._common import ScatterMode, ior_pair, lane_ior, orient
from render.df._signature import MODE_MASK, REFLECT, THIN_WALLED, TRANSMIT, Param, Signature
from render.frame import mirror_z
from render.jit import njit
from render.numerics import TOL, fresnel_dielectric, refract, saturate

__all__ = ["SpecularBsdf", "specular_bsdf"]

_Z = np.array([0.0, 0.0, 1.0])

# --- signature and kernels (the compiled render core) ---------------------------------

SIGNATURE = Signature("bsdf", (
    Param("tint", "color", (1.0, 1.0, 1.0), clamp=(0.0, 1.0)),
    Param("mode", "scatter_mode", "scatter_reflect", uniform=True),
    Param("handle", "string", "", uniform=True),
), context=("ior_outside", "ior_inside"))
_TINT = SIGNATURE.offset("tint")
_IOR_OUTSIDE = SIGNATURE.offset("ior_outside")
_IOR_INSIDE = SIGNATURE.offset("ior_inside")


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
    return wix, wiy, kc.mirror_z(wiz, flip), prob, t0, t1, t2, lobe


@njit
def albedo(P, row, b, flags, wox, woy, woz):
    """Directional albedo of one lane: ``tint`` in every mode -> ``(a0, a1, a2)``."""
    if not abs(woz) > kc.COS_ZERO:
        return 0.0, 0.0, 0.0
    return P[row, b + _TINT], P[row, b + _TINT + 1], P[row, b + _TINT + 2]


# --- the numpy reference (deleted once the program adapters replace it) ----------------



class SpecularBsdf(Bsdf):
    """``df::specular_bsdf`` over lanes.

    Parameters
    ----------
    tint : float, (3,) or (n, 3)
        Saturated to [0, 1].
    mode : ScatterMode or str
        ``"scatter_reflect"`` (default), ``"scatter_transmit"`` or
        ``"scatter_reflect_transmit"``.
    ior_outside, ior_inside : float or (n,)
        IORs on the ``+z`` and ``-z`` sides (from the renderer, not from MDL arguments).
    thin_walled : bool
        ``material.thin_walled``: transmission without refraction.

    Examples
    --------
    >>> glass = specular_bsdf(mode="scatter_reflect_transmit", ior_inside=1.5)
    >>> s = glass.sample(np.array([[0.0, 0.0, 1.0]] * 2), np.array([0.01, 0.9]), np.zeros((2, 2)))
    >>> (np.round(s.wi, 6) + 0.0).tolist(), np.round(s.pdf, 6).tolist()
    ([[0.0, 0.0, 1.0], [0.0, 0.0, -1.0]], [0.04, 0.96])
    >>> [Lobe(v).name for v in s.lobe]
    ['SPECULAR_REFLECTION', 'SPECULAR_TRANSMISSION']
    """

    def __init__(
        self,
        tint: ArrayLike = 1.0,
        mode: ScatterMode | str = ScatterMode.scatter_reflect,
        ior_outside: ArrayLike = 1.0,
        ior_inside: ArrayLike = 1.0,
        thin_walled: bool = False,
    ):
        self.tint = saturate(lane_color(tint, "tint"))
        self.mode = ScatterMode.parse(mode)
        self.ior_outside = lane_ior(ior_outside, "ior_outside")
        self.ior_inside = lane_ior(ior_inside, "ior_inside")
        self.thin_walled = bool(thin_walled)
        self._black = np.all(self.tint == 0, axis=1)
        self.lobes = {
            ScatterMode.scatter_reflect: Lobe.SPECULAR_REFLECTION,
            ScatterMode.scatter_transmit: Lobe.SPECULAR,
            ScatterMode.scatter_reflect_transmit: Lobe.SPECULAR,
        }[self.mode]

    def __repr__(self) -> str:
        return (
            f"specular_bsdf(tint={self.tint.tolist()}, mode={self.mode.value}, "
            f"ior_outside={self.ior_outside.tolist()}, ior_inside={self.ior_inside.tolist()}, "
            f"thin_walled={self.thin_walled})"
        )

    def eval(self, wo: Vec3, wi: Vec3) -> Rgb:
        wo, wi = check_dirs(wo, wi)
        return np.zeros((len(wo), 3))

    def pdf(self, wo: Vec3, wi: Vec3) -> Arr:
        wo, wi = check_dirs(wo, wi)
        return np.zeros(len(wo))

    def sample(self, wo: Vec3, u1: Arr, u2: Arr2) -> BsdfSample:
        (wo,) = check_dirs(wo, names=("wo",))
        n = len(wo)
        u1, u2 = check_samples(n, u1, u2)
        flip, wo = orient(wo)
        c = wo[:, 2]
        black = np.broadcast_to(lanes(self._black, n, "tint"), (n,))
        ok = (c > TOL.cos_zero) & ~black
        eta1, eta2 = ior_pair(
            lanes(self.ior_outside, n, "ior_outside"),
            lanes(self.ior_inside, n, "ior_inside"),
            flip,
            self.thin_walled,
            glossy=False,
        )
        F, _ = fresnel_dielectric(c, eta2 / eta1)
        # choose the event: probability of reflection per mode
        if self.mode is ScatterMode.scatter_reflect:
            p_refl = np.ones(n)
        elif self.mode is ScatterMode.scatter_transmit:
            b = eta1 / eta2
            tir = b * b * (1.0 - c * c) > 1.0
            p_refl = np.where(tir & ~np.bool_(self.thin_walled), 1.0, 0.0)  # only TIR reflects
        else:
            p_refl = F
        refl = u1 < p_refl
        prob = np.where(refl, p_refl, 1.0 - p_refl)
        # directions: mirror; refraction about +z, or straight through on a thin wall
        wi_refl = wo * np.array([-1.0, -1.0, 1.0])
        if self.thin_walled:
            wi_tr = -wo
        else:
            wi_tr, _ = refract(wo, np.broadcast_to(_Z, wo.shape), eta1 / eta2)
        wi = np.where(refl[:, None], wi_refl, wi_tr)
        ok &= (prob > 0) & np.where(refl, wi[:, 2] > TOL.cos_zero, wi[:, 2] < -TOL.cos_zero)
        lobe = np.where(refl, int(Lobe.SPECULAR_REFLECTION), int(Lobe.SPECULAR_TRANSMISSION))
        weight = np.broadcast_to(lanes(self.tint, n, "tint"), (n, 3))
        return BsdfSample(
            np.where(ok[:, None], mirror_z(wi, flip), 0.0),
            np.where(ok, prob, 0.0),
            np.where(ok[:, None], weight, 0.0),
            np.where(ok, lobe, 0).astype(np.int32),
        ).checked()

    def albedo(self, wo: Vec3) -> Rgb:
        (wo,) = check_dirs(wo, names=("wo",))
        n = len(wo)
        ok = np.abs(wo[:, 2]) > TOL.cos_zero
        return np.where(ok[:, None], np.broadcast_to(lanes(self.tint, n, "tint"), (n, 3)), 0.0)


specular_bsdf = SpecularBsdf
