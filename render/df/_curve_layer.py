"""The kernels of a curve layer, written once for ``fresnel_layer``, ``custom_curve_layer``
and ``measured_curve_layer`` (and their colour forms).

The three weigh a layer over a base by a curve of the cosine (``F`` or ``C``): the layer
by ``w C(|wo.h|)``, the base by ``max(0, 1 - w max(C(nk1), C(nk2), Ĉ(wo), Ĉ(wi))``
(:func:`render.df._layer.curve_factors`).  They differ only in the curve and in whether
transmission takes the refraction half vector; this module writes the rest once, as
templates that :func:`kernels` compiles for one df module (:func:`render.jit.instantiate`).
The df module defines, at module level:

``_curve3(P, row, b, flags, woz, c) -> (c0, c1, c2)``
    the curve per channel at cosine ``c``, with the IOR context of ``wo``'s side (``woz``);
``_geometry(P, row, b, flags, woz, wiz, ox, oy, oz, ix, iy, iz) -> (kh, nk1, nk2)``
    the cosines the curve is read at (:func:`render.df._layer.curve_geometry`);
``_WEIGHT``
    the column of ``weight`` (a colour).
"""

from __future__ import annotations

import sys

from render.df._layer import curve_estimates, curve_factors
from render.jit import instantiate

__all__ = ["kernels"]

#: the df module an instance reads its curve from (bound by :func:`kernels`)
lobe = None


def kernels(module: str) -> tuple:
    """``(layer_factors, layer_estimates, curve_h, curve_nk)`` compiled for the df module
    named ``module`` (being imported: it calls this after defining its curve)."""
    df = sys.modules[module]
    return tuple(instantiate(f, module, lobe=df)
                 for f in (layer_factors, layer_estimates, curve_h, curve_nk))


def layer_factors(P, row, b, flags, wox, woy, woz, wix, wiy, wiz,
                  wolx, woly, wolz, wilx, wily, wilz, co0, co1, co2, ci0, ci1, ci2):
    """The layer factors: ``f_layer = w C(|wo.h|)``, ``f_base = max(0, 1 - w
    max(C(nk1), C(nk2), Ĉ(wo), Ĉ(wi)))`` per channel.

    ``wo``, ``wi`` inherited frame; ``wo_l``, ``wi_l`` layer frame; ``co``, ``ci`` the
    curve-weighted albedos ``Ĉ(wo)``, ``Ĉ(wi)`` (already 0 where a direction's frames
    disagree, or where the node needs none).  Not applied here: ``f_layer = 0`` where
    ``wo`` or ``wi`` lies on different sides of the two tangent planes
    (the layer frame's side test, the interpreter's mask).
    """
    kh, nk1, nk2 = lobe._geometry(P, row, b, flags, woz, wiz, wolx, woly, wolz,
                                  wilx, wily, wilz)
    h0, h1, h2 = lobe._curve3(P, row, b, flags, woz, kh)
    a0, a1, a2 = lobe._curve3(P, row, b, flags, woz, nk1)
    r0, r1, r2 = lobe._curve3(P, row, b, flags, woz, nk2)
    w = b + lobe._WEIGHT
    return curve_factors(P[row, w], P[row, w + 1], P[row, w + 2], h0, h1, h2,
                         max(a0, r0), max(a1, r1), max(a2, r2), co0, co1, co2, ci0, ci1, ci2)


def layer_estimates(P, row, b, flags, wox, woy, woz, wolx, woly, wolz, co0, co1, co2):
    """The layer estimates: ``w C(nk1)`` and ``max(0, 1 - w max(C(nk1), Ĉ(wo)))``."""
    s = -1.0 if wolz < 0.0 else 1.0
    c0, c1, c2 = lobe._curve3(P, row, b, flags, woz, min(max(wolz * s, 0.0), 1.0))
    w = b + lobe._WEIGHT
    return curve_estimates(P[row, w], P[row, w + 1], P[row, w + 2], c0, c1, c2, co0, co1, co2)


def curve_h(P, row, b, flags, vx, vy, vz, xx, xy, xz):
    """``C(|v.h|)`` for layer-frame ``v`` (as ``wo`` and ``wo_L``) and ``x`` (as ``wi``
    and ``wi_L``): what the Ĉ quadrature integrates, the context of ``v``'s side."""
    kh, nk1, nk2 = lobe._geometry(P, row, b, flags, vz, xz, vx, vy, vz, xx, xy, xz)
    return lobe._curve3(P, row, b, flags, vz, kh)


def curve_nk(P, row, b, flags, vx, vy, vz):
    """``C(|v.z|)`` (the control variate's curve), the context of ``v``'s side."""
    return lobe._curve3(P, row, b, flags, vz, abs(vz))
