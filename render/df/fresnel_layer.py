"""MDL ``df::fresnel_layer`` and ``df::color_fresnel_layer``: a layer weighted by exact Fresnel.

MDL signatures::

    bsdf fresnel_layer(float ior, float weight = 1.0, bsdf layer = bsdf(),
                       bsdf base = bsdf(), float3 normal = state::normal());
    bsdf color_fresnel_layer(color ior, color weight = color(1.0), bsdf layer = bsdf(),
                             bsdf base = bsdf(), float3 normal = state::normal());   // 1.4

``ior`` was a ``color`` before MDL 1.4 and the Handbook passes ``ior: color(1.6)``
(Listing 6.11, Figure 6.36), so both take a colour (a float means grey) and evaluate
Fresnel **per channel**.

Model (libbsdf, ``reference/mdl-distribution-functions.md`` §3.2): the directional
layering of :mod:`render.df._layer` with the exact unpolarised dielectric
Fresnel curve ``C(c) = F(eta, c)`` (libbsdf's ``ior_fresnel``, not Schlick).  The layer's
``ior`` replaces the material's on the side the ray comes from: with ``(eta1, eta2)``
the renderer's IOR pair on ``wo``'s side and the far side, a ray from outside
(``wo.z >= 0``, or any thin-walled hit) uses ``eta = ior / eta1``, a ray from inside
``eta = eta2 / ior``.  Then::

    eval = w F(|wo.h|) layer.eval(wo_L, wi_L) + (1 - w max(F(nk1), F(nk2r))) base.eval(wo, wi)

with the refraction half vector (material IOR pair) for transmitted ``wi`` on
non-thin-walled surfaces.  ``color_fresnel_layer`` folds ``saturate(weight)`` into
``C`` per channel.  The layer's own lobe carries no Fresnel of its own
(``specular_bsdf(scatter_reflect)``), so the node applies exactly one.

Energy: the node never gains energy (the bound and how ``Ĉ`` is computed:
:mod:`render.df._layer`).  The base's factor is libbsdf's ``1 - w max(F(nk1), F(nk2r))``
lowered, only where needed, to ``1 - w Ĉ`` with ``Ĉ`` the coat's Fresnel-weighted albedo
(libbsdf's rule alone gains 0.2 % with a rough coat over a mirror at 45 degrees).  A
smooth (specular) coat keeps libbsdf's factors exactly and is lossless where the base
is, except for the part of the base's lobe that leaves at grazing angles
(``F(nk2) > F(nk1)``), which is lost.  Measured in ``tests/render/df/test_fresnel_layer.py``.

Under ``thin_film`` the curve is the film's reflectance over the layer's IOR
(:mod:`render.df.thin_film`; the film slots are not MDL parameters of this df).
"""

from __future__ import annotations

from render.df import _curve_layer
from render.df._layer import (
    curve_geometry,
    fresnel_curve,
    fresnel_eta,
)
from render.df._registry import Df, Node
from render.df._signature import REQUIRED, THIN_WALLED, Param, Signature
from render.df.thin_film import FILM_PARAMS, film_rgb
from render.jit import njit
from render.program import check_ior

__all__ = [
    "FresnelLayer",
    "fresnel_layer",
    "ColorFresnelLayer",
    "color_fresnel_layer",
    "SIGNATURE",
    "COLOR_SIGNATURE",
    "layer_factors",
    "layer_estimates",
    "layer_possible",
    "curve_h",
    "curve_nk",
    "curve_constant",
    "curve_is_one",
]


# --- signature and kernels (the compiled render core) ---------------------------------
# The per-node factors of CurveLayer with the Fresnel curve (the interpreter,
# render.program, walks the tree, maps directions into the layer frame, looks up the
# curve-weighted albedo Ĉ, applies the frame-agreement mask and sums).  One set of
# kernels serves both forms: the float ior and weight are packed as grey colours.
# ``ior`` must be > 0 (the earlier numpy class raises; the packer should too): the kernels
# treat an ior <= 0 as an infinitely dense coat (F = 1), never NaN.


def _params(ior: Param, weight: Param) -> tuple:
    return (ior, weight, Param("layer", "bsdf", None), Param("base", "bsdf", None),
            Param("normal", "float3", "state::normal()"), *FILM_PARAMS)


#: ``df::fresnel_layer`` plus the renderer's IORs on the ``+z`` and ``-z`` sides
SIGNATURE = Signature("bsdf", _params(
    Param("ior", "float", REQUIRED, packed="color"),
    Param("weight", "float", 1.0, clamp=(0.0, 1.0), packed="color"),
), context=("ior_outside", "ior_inside"))
#: ``df::color_fresnel_layer`` (MDL 1.4)
COLOR_SIGNATURE = Signature("bsdf", _params(
    Param("ior", "color", REQUIRED),
    Param("weight", "color", (1.0, 1.0, 1.0), clamp=(0.0, 1.0)),
), context=("ior_outside", "ior_inside"))
#: ``df::fresnel_layer`` of MDL before 1.4 (the Handbook's): a colour ior; it packs as
#: the colour form, whose kernels it runs
BEFORE_1_4_SIGNATURE = Signature("bsdf", _params(
    Param("ior", "color", REQUIRED),
    Param("weight", "float", 1.0, clamp=(0.0, 1.0), packed="color"),
), context=("ior_outside", "ior_inside"))
_IOR = COLOR_SIGNATURE.offset("ior")
_WEIGHT = COLOR_SIGNATURE.offset("weight")
_IOR_OUTSIDE = COLOR_SIGNATURE.offset("ior_outside")
_IOR_INSIDE = COLOR_SIGNATURE.offset("ior_inside")
_FILM_D = COLOR_SIGNATURE.offset("thin_film_thickness")
_FILM_N = COLOR_SIGNATURE.offset("thin_film_ior")


@njit
def _film3(P, row, b, flags, woz, c):
    """The Fresnel curve under a ``thin_film`` (:func:`render.df.thin_film.film_rgb`): from
    outside (or on a thin wall) a film over the layer's IOR, from inside a film over the
    outside medium seen from the layer (its channels' mean)."""
    ior_o = P[row, b + _IOR_OUTSIDE]
    i0, i1, i2 = P[row, b + _IOR], P[row, b + _IOR + 1], P[row, b + _IOR + 2]
    f0, f1, f2 = P[row, b + _FILM_N], P[row, b + _FILM_N + 1], P[row, b + _FILM_N + 2]
    d = P[row, b + _FILM_D]
    if woz < 0.0 and (flags & THIN_WALLED) == 0:
        return film_rgb(c, (i0 + i1 + i2) / 3.0, f0, f1, f2, ior_o, ior_o, ior_o, 0.0, 0.0,
                        0.0, d)
    return film_rgb(c, ior_o, f0, f1, f2, i0, i1, i2, 0.0, 0.0, 0.0, d)


@njit
def _curve3(P, row, b, flags, woz, c):
    """``F(c)`` per channel, with the IOR context of ``wo``'s side (``woz``)."""
    if P[row, b + _FILM_D] > 0.0:
        return _film3(P, row, b, flags, woz, c)
    ior_o = P[row, b + _IOR_OUTSIDE]
    i0, i1, i2 = P[row, b + _IOR], P[row, b + _IOR + 1], P[row, b + _IOR + 2]
    f0 = fresnel_curve(c, fresnel_eta(i0, ior_o, woz, flags))
    # a grey ior (the float form, the common case) evaluates Fresnel once
    f1 = f0 if i1 == i0 else fresnel_curve(c, fresnel_eta(i1, ior_o, woz, flags))
    f2 = f0 if i2 == i0 else fresnel_curve(c, fresnel_eta(i2, ior_o, woz, flags))
    return f0, f1, f2


@njit
def _geometry(P, row, b, flags, woz, wiz, ox, oy, oz, ix, iy, iz):
    """The curve's cosines, transmission through the refraction half vector."""
    return curve_geometry(True, flags, P[row, b + _IOR_OUTSIDE], P[row, b + _IOR_INSIDE],
                          woz, wiz, ox, oy, oz, ix, iy, iz)


layer_factors, layer_estimates, curve_h, curve_nk = _curve_layer.kernels(__name__)


@njit
def layer_possible(P, row, b, flags):
    """``(layer, base)`` can contribute: some channel of ``w`` positive (``F <= 1``); the
    base always (``F`` is never 1 at every cosine).  The interpreter ANDs in whether each
    child exists and the frames agree."""
    w0, w1, w2 = P[row, b + _WEIGHT], P[row, b + _WEIGHT + 1], P[row, b + _WEIGHT + 2]
    return (w0 > 0.0 or w1 > 0.0 or w2 > 0.0), True


@njit
def curve_constant(P, row, b, flags):
    """``F`` is constant (0 at every cosine): ``ior == ior_outside`` in every channel."""
    o = P[row, b + _IOR_OUTSIDE]
    if P[row, b + _FILM_D] > 0.0:
        return False
    return P[row, b + _IOR] == o and P[row, b + _IOR + 1] == o and P[row, b + _IOR + 2] == o


@njit
def curve_is_one(P, row, b, flags):
    """``F == 1`` at every cosine: never."""
    return False


# --- the Python classes ----------------------------------------------------------------

NODE = Node("fresnel_layer", "bsdf", "layer", COLOR_SIGNATURE,
            layer_factors=layer_factors, layer_estimates=layer_estimates,
            layer_possible=layer_possible, curve_h=curve_h, curve_nk=curve_nk,
            curve_constant=curve_constant)
DF = Df("fresnel_layer", SIGNATURE, (NODE,), check=check_ior)
COLOR_DF = Df("color_fresnel_layer", COLOR_SIGNATURE, (NODE,), check=check_ior)
BEFORE_1_4_DF = Df("fresnel_layer_before_1_4", BEFORE_1_4_SIGNATURE, (NODE,),
                   mdl_name="fresnel_layer", py_name="FresnelLayerBefore14", check=check_ior,
                   deprecated="MDL before 1.4: fresnel_layer's ior is a float since; for a "
                              "colour ior call df::color_fresnel_layer")
FresnelLayer = DF.cls
fresnel_layer = FresnelLayer
ColorFresnelLayer = COLOR_DF.cls
color_fresnel_layer = ColorFresnelLayer
