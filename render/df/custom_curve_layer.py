"""MDL ``df::custom_curve_layer`` and its colour variant: a layer weighted by a Schlick curve.

MDL signatures::

    bsdf custom_curve_layer(float normal_reflectivity, float grazing_reflectivity = 1.0,
                            float exponent = 5.0, float weight = 1.0, bsdf layer = bsdf(),
                            bsdf base = bsdf(), float3 normal = state::normal());
    bsdf color_custom_curve_layer(color normal_reflectivity,
                                  color grazing_reflectivity = color(1.0),
                                  color f82_factor = color(1.0),              // 1.10
                                  float exponent = 5.0, color weight = color(1.0),
                                  bsdf layer = bsdf(), bsdf base = bsdf(),
                                  float3 normal = state::normal());            // 1.4

Model (libbsdf, ``reference/mdl-distribution-functions.md`` §3.2): the directional
layering of :mod:`render.df._layer` with the curve::

    C(c) = R0 + (R90 - R0) (1 - saturate(c))^p,
    R0 = saturate(normal_reflectivity), R90 = saturate(grazing_reflectivity), p = max(exponent, 0)

and, for the colour variant, Hoffman's F82 tint
``C = saturate(C - a c (1 - c)^6)``, ``a = (R0 + (R90 - R0)(6/7)^p) 7^7/6^6 (1 - saturate(f82))``
and ``saturate(weight)`` folded into ``C`` per channel::

    eval = w C(|wo.h|) layer.eval(wo_L, wi_L) + (1 - w max(C(nk1), C(nk2))) base.eval(wo, wi)

Transmitted ``wi`` use the half vector of ``wi`` mirrored through the layer's tangent
plane (no refraction half vector: libbsdf uses it only for the Fresnel layers).

Energy: the node never gains energy (the bound and how ``Ĉ`` is computed:
:mod:`render.df._layer`).  libbsdf's rule alone does, by up to 6.5 %: with a rough coat
over a mirror or narrow glossy base, ``C(|wo.h|)`` at tilted half vectors exceeds
``C(nk1)`` while the base keeps ``1 - w C(nk1)``, which matters where the curve rises
steeply from normal incidence (``custom_curve_layer(0, 1, 1, glossy r 0.5, mirror)``:
1.0647 at normal incidence).  Here the base keeps ``1 - w max(C(nk1), C(nk2), Ĉ(wo),
Ĉ(wi))`` with ``Ĉ`` the coat's curve-weighted albedo, so that node is at most 1; the
coat's own lobe is libbsdf's.  Over diffuse bases ``C(nk2)`` dominates and libbsdf's
factors are kept almost everywhere (measured in
``tests/render/df/test_custom_curve_layer.py``).

Under ``thin_film`` (MDL 1.8) the curve takes the film's change of the reflectance of a
dielectric whose normal reflectance is ``R0``, ``C' = saturate(C + shift)``
(:mod:`render.df.thin_film`; the film slots and the IOR context are not MDL parameters of
this df).
"""

from __future__ import annotations

from render.df import _curve_layer
from render.df._layer import curve_geometry, f82_curve1
from render.df._registry import Df, Node
from render.df._signature import REQUIRED, THIN_WALLED, Param, Signature
from render.df.thin_film import FILM_PARAMS, film_shift, schlick_ior
from render.jit import njit

__all__ = [
    "CustomCurveLayer",
    "custom_curve_layer",
    "ColorCustomCurveLayer",
    "color_custom_curve_layer",
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
# The per-node factors of CurveLayer with the custom curve (the interpreter,
# render.program, walks the tree, maps directions into the layer frame, looks up the
# curve-weighted albedo Ĉ, applies the frame-agreement mask and sums).  One set of
# kernels serves both forms: the float form's reflectivities and weight are packed as
# grey colours, and it carries the colour form's f82_factor slot at its default 1 (not an
# MDL parameter of custom_curve_layer: ``mdl=False``).


def _params(r0: Param, r90: Param, f82: Param, weight: Param) -> tuple:
    return (r0, r90, f82, Param("exponent", "float", 5.0, clamp=(0.0, None)), weight,
            Param("layer", "bsdf", None), Param("base", "bsdf", None),
            Param("normal", "float3", "state::normal()"), *FILM_PARAMS)


#: ``df::custom_curve_layer``, plus the film slots and the renderer's IORs on the ``+z``
#: and ``-z`` sides (what a ``thin_film`` over the curve reads)
SIGNATURE = Signature("bsdf", _params(
    Param("normal_reflectivity", "float", REQUIRED, clamp=(0.0, 1.0), packed="color"),
    Param("grazing_reflectivity", "float", 1.0, clamp=(0.0, 1.0), packed="color"),
    Param("f82_factor", "color", (1.0, 1.0, 1.0), clamp=(0.0, 1.0), mdl=False),
    Param("weight", "float", 1.0, clamp=(0.0, 1.0), packed="color"),
), context=("ior_outside", "ior_inside"))
#: ``df::color_custom_curve_layer`` (MDL 1.4; ``f82_factor`` 1.10)
COLOR_SIGNATURE = Signature("bsdf", _params(
    Param("normal_reflectivity", "color", REQUIRED, clamp=(0.0, 1.0)),
    Param("grazing_reflectivity", "color", (1.0, 1.0, 1.0), clamp=(0.0, 1.0)),
    Param("f82_factor", "color", (1.0, 1.0, 1.0), clamp=(0.0, 1.0)),
    Param("weight", "color", (1.0, 1.0, 1.0), clamp=(0.0, 1.0)),
), context=("ior_outside", "ior_inside"))
_R0 = COLOR_SIGNATURE.offset("normal_reflectivity")
_R90 = COLOR_SIGNATURE.offset("grazing_reflectivity")
_F82 = COLOR_SIGNATURE.offset("f82_factor")
_EXPONENT = COLOR_SIGNATURE.offset("exponent")
_WEIGHT = COLOR_SIGNATURE.offset("weight")
_FILM_D = COLOR_SIGNATURE.offset("thin_film_thickness")
_FILM_N = COLOR_SIGNATURE.offset("thin_film_ior")
_IOR_OUTSIDE = COLOR_SIGNATURE.offset("ior_outside")


@njit
def _film3(P, row, b, flags, woz, c):
    """The shift a ``thin_film`` makes at cosine ``c``
    (:func:`render.df.thin_film.film_shift`), on the dielectric whose normal reflectance
    is ``R0`` (:func:`~render.df.thin_film.schlick_ior`, per channel): from outside (or
    on a thin wall) a film over that IOR, from inside a film over the outside medium
    seen from it (its channels' mean), as ``fresnel_layer``'s film."""
    o = P[row, b + _IOR_OUTSIDE]
    i0 = schlick_ior(P[row, b + _R0])
    i1 = schlick_ior(P[row, b + _R0 + 1])
    i2 = schlick_ior(P[row, b + _R0 + 2])
    f0, f1, f2 = P[row, b + _FILM_N], P[row, b + _FILM_N + 1], P[row, b + _FILM_N + 2]
    d = P[row, b + _FILM_D]
    if woz < 0.0 and (flags & THIN_WALLED) == 0:
        return film_shift(c, (i0 + i1 + i2) / 3.0, f0, f1, f2, o, o, o, 0.0, 0.0, 0.0, d)
    return film_shift(c, o, f0, f1, f2, i0, i1, i2, 0.0, 0.0, 0.0, d)


@njit
def _curve3(P, row, b, flags, woz, c):
    """``C(c)`` per channel (the F82-tinted custom curve; under a ``thin_film`` shifted
    by the film, ``saturate(C + shift)``, with the IOR context of ``wo``'s side)."""
    p = P[row, b + _EXPONENT]
    c0 = f82_curve1(c, P[row, b + _R0], P[row, b + _R90], P[row, b + _F82], p)
    c1 = f82_curve1(c, P[row, b + _R0 + 1], P[row, b + _R90 + 1], P[row, b + _F82 + 1], p)
    c2 = f82_curve1(c, P[row, b + _R0 + 2], P[row, b + _R90 + 2], P[row, b + _F82 + 2], p)
    if P[row, b + _FILM_D] > 0.0:
        s0, s1, s2 = _film3(P, row, b, flags, woz, c)
        c0 = min(max(c0 + s0, 0.0), 1.0)
        c1 = min(max(c1 + s1, 0.0), 1.0)
        c2 = min(max(c2 + s2, 0.0), 1.0)
    return c0, c1, c2


@njit
def _geometry(P, row, b, flags, woz, wiz, ox, oy, oz, ix, iy, iz):
    """The curve's cosines (transmitted ``wi`` mirrored, no refraction half vector)."""
    return curve_geometry(False, flags, 1.0, 1.0, woz, wiz, ox, oy, oz, ix, iy, iz)


layer_factors, layer_estimates, curve_h, curve_nk = _curve_layer.kernels(__name__)


@njit
def layer_possible(P, row, b, flags):
    """``(layer, base)`` can contribute: some channel of ``w max(R0, R90)`` positive; not
    ``w == 1`` with ``C == 1`` in every channel.  The interpreter ANDs in whether each
    child exists and the frames agree."""
    pos_l = False
    white = True
    film = P[row, b + _FILM_D] > 0.0  # a film reflects even where the curve is 0
    for k in range(3):
        w = P[row, b + _WEIGHT + k]
        pos_l = pos_l or w * max(P[row, b + _R0 + k], P[row, b + _R90 + k]) > 0.0 or (
            film and w > 0.0)
        white = white and w == 1.0
    return pos_l, not (white and curve_is_one(P, row, b, flags))


@njit
def curve_constant(P, row, b, flags):
    """``C`` takes one value at every cosine: no F82 tint and ``R0 == R90`` or ``p == 0``
    (every channel), and no film."""
    if P[row, b + _FILM_D] > 0.0:
        return False
    p0 = max(P[row, b + _EXPONENT], 0.0) == 0.0  # as f82_curve1 reads p
    for k in range(3):
        if not (P[row, b + _F82 + k] == 1.0
                and (P[row, b + _R0 + k] == P[row, b + _R90 + k] or p0)):
            return False
    return True


@njit
def curve_is_one(P, row, b, flags):
    """``C == 1`` at every cosine: ``R0 == R90 == 1`` and no F82 tint (every channel),
    and no film."""
    if P[row, b + _FILM_D] > 0.0:
        return False
    for k in range(3):
        if not (P[row, b + _R0 + k] == 1.0 and P[row, b + _R90 + k] == 1.0
                and P[row, b + _F82 + k] == 1.0):
            return False
    return True


# --- the Python classes ----------------------------------------------------------------

NODE = Node("custom_curve_layer", "bsdf", "layer", COLOR_SIGNATURE,
            layer_factors=layer_factors, layer_estimates=layer_estimates,
            layer_possible=layer_possible, curve_h=curve_h, curve_nk=curve_nk,
            curve_constant=curve_constant)
DF = Df("custom_curve_layer", SIGNATURE, (NODE,))
COLOR_DF = Df("color_custom_curve_layer", COLOR_SIGNATURE, (NODE,))
CustomCurveLayer = DF.cls
custom_curve_layer = CustomCurveLayer
ColorCustomCurveLayer = COLOR_DF.cls
color_custom_curve_layer = ColorCustomCurveLayer
