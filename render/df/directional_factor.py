"""MDL ``df::directional_factor``: a Bsdf scaled by a Schlick-like curve of the half-vector angle.

MDL signature::

    bsdf directional_factor(color normal_tint = color(1.0), color grazing_tint = color(1.0),
                            color f82_factor = color(1.0),                          // 1.10
                            float exponent = 5.0, bsdf base = bsdf());

Model (libbsdf, ``reference/mdl-distribution-functions.md`` §4): the factor is the
custom curve of ``custom_curve_layer`` with Hoffman's F82 tint,
``C(c) = saturate(R0 + (R90 - R0)(1 - c)^p - a c (1 - c)^6)`` with ``R0 =
saturate(normal_tint)``, ``R90 = saturate(grazing_tint)``, ``p = max(exponent, 0)``,
evaluated at ``c = wo.h`` for the reflection half vector ``h`` (a transmitted ``wi`` is
mirrored through the tangent plane first; :func:`render.df._layer.scale_cosine`)::

    eval = C(wo.h) base.eval(wo, wi),    pdf = base.pdf (0 where the product is)

The sample weight is scaled by ``C`` at the sampled direction.  Energy: never more
than the base (``C <= 1``).  ``albedo`` is exact for a constant curve and otherwise
integrated through the base's sampler (:data:`render.program.ALBEDO_POINTS` QMC
points).

Under ``thin_film`` (MDL 1.8) the factor takes the film's change of the reflectance of
the conductor with normal reflectance ``R0`` and edge tint ``R90 f82`` (Gulbrandsen's
fit), ``C' = saturate(C + shift)`` (:mod:`render.df.thin_film`; the film slots and the
IOR context are not MDL parameters of this df).

The EDF overload (MDL 1.7, no ``f82_factor``)::

    edf directional_factor(color normal_tint = color(1.0), color grazing_tint = color(1.0),
                           float exponent = 5.0, edf base = edf());

scales the emission toward ``wo`` by the curve at ``c = wo.n``
(:class:`DirectionalFactorEdf`); :func:`directional_factor` picks the overload from
the ``base``.
"""

from __future__ import annotations

from render.df._layer import f82_curve1, scale_cosine
from render.df._registry import Df, Node
from render.df._signature import THIN_WALLED, Param, Signature
from render.df.thin_film import FILM_PARAMS, edge_tint_ior, film_shift
from render.jit import njit

__all__ = [
    "DirectionalFactor",
    "DirectionalFactorEdf",
    "directional_factor",
    "directional_factor_edf",
    "SIGNATURE",
    "EDF_SIGNATURE",
    "scale",
    "edf_scale",
    "curve_constant",
]


# --- signature and kernels (the compiled render core) ---------------------------------
# The factor of ScaledBsdf (the interpreter, render.program, evaluates the base and
# scales its value and sample weight; the pdf is the base's where the product is > 0).

#: ``df::directional_factor`` (the bsdf overload; ``base`` None: MDL's ``bsdf()``), plus
#: the film slots and the renderer's IORs on the ``+z`` and ``-z`` sides (what a
#: ``thin_film`` over the factor reads)
SIGNATURE = Signature("bsdf", (
    Param("normal_tint", "color", (1.0, 1.0, 1.0), clamp=(0.0, 1.0)),
    Param("grazing_tint", "color", (1.0, 1.0, 1.0), clamp=(0.0, 1.0)),
    Param("f82_factor", "color", (1.0, 1.0, 1.0), clamp=(0.0, 1.0)),
    Param("exponent", "float", 5.0, clamp=(0.0, None)),
    Param("base", "bsdf", None),
    *FILM_PARAMS,
), context=("ior_outside", "ior_inside"))
#: the edf overload (MDL 1.7)
EDF_SIGNATURE = Signature("edf", (
    Param("normal_tint", "color", (1.0, 1.0, 1.0), clamp=(0.0, 1.0)),
    Param("grazing_tint", "color", (1.0, 1.0, 1.0), clamp=(0.0, 1.0)),
    Param("exponent", "float", 5.0, clamp=(0.0, None)),
    Param("base", "edf", None),
))
_E_R0 = EDF_SIGNATURE.offset("normal_tint")
_E_R90 = EDF_SIGNATURE.offset("grazing_tint")
_E_EXPONENT = EDF_SIGNATURE.offset("exponent")
_R0 = SIGNATURE.offset("normal_tint")
_R90 = SIGNATURE.offset("grazing_tint")
_F82 = SIGNATURE.offset("f82_factor")
_EXPONENT = SIGNATURE.offset("exponent")
_FILM_D = SIGNATURE.offset("thin_film_thickness")
_FILM_N = SIGNATURE.offset("thin_film_ior")
_OUT = SIGNATURE.offset("ior_outside")
_IN = SIGNATURE.offset("ior_inside")


@njit
def _film3(P, row, b, flags, woz, c):
    """The shift a ``thin_film`` makes at cosine ``c``
    (:func:`render.df.thin_film.film_shift`) on the conductor of the curve's normal and
    edge tints (:func:`~render.df.thin_film.edge_tint_ior` of ``R0`` and ``R90 f82``, per
    channel), seen from the medium on ``wo``'s side."""
    inside = woz < 0.0 and (flags & THIN_WALLED) == 0
    e1 = P[row, b + _IN] if inside else P[row, b + _OUT]
    n0, k0 = edge_tint_ior(P[row, b + _R0], P[row, b + _R90] * P[row, b + _F82])
    n1, k1 = edge_tint_ior(P[row, b + _R0 + 1], P[row, b + _R90 + 1] * P[row, b + _F82 + 1])
    n2, k2 = edge_tint_ior(P[row, b + _R0 + 2], P[row, b + _R90 + 2] * P[row, b + _F82 + 2])
    return film_shift(c, e1, P[row, b + _FILM_N], P[row, b + _FILM_N + 1],
                      P[row, b + _FILM_N + 2], n0, n1, n2, k0, k1, k2, P[row, b + _FILM_D])


@njit
def scale(P, row, b, flags, wox, woy, woz, wix, wiy, wiz):
    """the directional factor: ``C(wo.h)`` per channel, ``h`` the reflection half
    vector (both directions mirrored to ``wo``'s side, then a transmitted ``wi`` through
    the tangent plane); 0 where ``wo.h < 0``.  Under a ``thin_film``,
    ``saturate(C + shift)``."""
    kh = scale_cosine(wox, woy, woz, wix, wiy, wiz)
    if kh < 0.0:
        return 0.0, 0.0, 0.0
    p = P[row, b + _EXPONENT]
    c0 = f82_curve1(kh, P[row, b + _R0], P[row, b + _R90], P[row, b + _F82], p)
    c1 = f82_curve1(kh, P[row, b + _R0 + 1], P[row, b + _R90 + 1], P[row, b + _F82 + 1], p)
    c2 = f82_curve1(kh, P[row, b + _R0 + 2], P[row, b + _R90 + 2], P[row, b + _F82 + 2], p)
    if P[row, b + _FILM_D] > 0.0:
        s0, s1, s2 = _film3(P, row, b, flags, woz, kh)
        c0 = min(max(c0 + s0, 0.0), 1.0)
        c1 = min(max(c1 + s1, 0.0), 1.0)
        c2 = min(max(c2 + s2, 0.0), 1.0)
    return c0, c1, c2


@njit
def edf_scale(P, row, b, flags, wox, woy, woz, wix, wiy, wiz):
    """the edf overload's factor: the curve (no F82 tint) at ``c = wo.z`` (``wi`` unused)."""
    p = P[row, b + _E_EXPONENT]
    c = min(max(woz, 0.0), 1.0)
    return (f82_curve1(c, P[row, b + _E_R0], P[row, b + _E_R90], 1.0, p),
            f82_curve1(c, P[row, b + _E_R0 + 1], P[row, b + _E_R90 + 1], 1.0, p),
            f82_curve1(c, P[row, b + _E_R0 + 2], P[row, b + _E_R90 + 2], 1.0, p))


@njit
def curve_constant(P, row, b, flags):
    """Whether the curve takes one value at every cosine (no F82 tint, and ``R0 = R90``
    or exponent 0, and no film): then the albedo is exact without quadrature."""
    if P[row, b + _FILM_D] > 0.0:
        return False
    for c in range(3):
        if P[row, b + _F82 + c] != 1.0:
            return False
    if P[row, b + _EXPONENT] == 0.0:
        return True
    for c in range(3):
        if P[row, b + _R0 + c] != P[row, b + _R90 + c]:
            return False
    return True


# --- the Python class ------------------------------------------------------------------

NODE = Node("directional_factor", "bsdf", "modifier", SIGNATURE, scale=scale,
            curve_constant=curve_constant)
EDF_NODE = Node("directional_factor_edf", "edf", "modifier", EDF_SIGNATURE, directional=False,
                scale=edf_scale)
DF = Df("directional_factor", SIGNATURE, (NODE,))
EDF_DF = Df("directional_factor_edf", EDF_SIGNATURE, (EDF_NODE,), mdl_name="directional_factor")
DirectionalFactor, DirectionalFactorEdf = DF.cls, EDF_DF.cls
directional_factor_edf = DirectionalFactorEdf


def directional_factor(*args, **kwargs):
    """``df::directional_factor``: the edf overload for an edf ``base``
    (:class:`DirectionalFactorEdf`), else the bsdf one (:class:`DirectionalFactor`)."""
    from render.program import ProgramEdf

    base = kwargs.get("base", args[-1] if args else None)
    if isinstance(base, ProgramEdf):  # (the edf overload reads no IOR context)
        for key in ("ior_outside", "ior_inside", "thin_walled"):
            kwargs.pop(key, None)
        return DirectionalFactorEdf(*args, **kwargs)
    return DirectionalFactor(*args, **kwargs)


directional_factor.mdl_name = "directional_factor"
directional_factor.__signature__ = DirectionalFactor.__signature__
