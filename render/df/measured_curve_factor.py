"""MDL ``df::measured_curve_factor``: a Bsdf scaled by a measured curve of the half-vector angle.

MDL signature (1.1)::

    bsdf measured_curve_factor(color[<N>] curve_values, bsdf base = bsdf());

Model (libbsdf, ``reference/mdl-distribution-functions.md`` §4): the factor is the
measured curve of ``measured_curve_layer`` (``N`` colours equally spaced in angle over
``[0, pi/2]``, linear in between, saturated) at ``c = wo.h`` for the reflection half
vector ``h`` (a transmitted ``wi`` mirrored through the tangent plane first; 0 where
``wo.h < 0``)::

    eval = C(wo.h) base.eval(wo, wi),     pdf = base.pdf (0 where the product is)

Energy: never more than the base (``C <= 1``).  ``albedo`` is integrated through the
base's sampler (the interpreter's control variate), exact for a constant curve.
"""

from __future__ import annotations

from render.df._layer import measured_curve3, measured_curve_constant, scale_cosine
from render.df._registry import Df, Node
from render.df._signature import REQUIRED, Param, Signature
from render.jit import njit

__all__ = ["MeasuredCurveFactor", "measured_curve_factor", "SIGNATURE", "scale",
           "curve_constant"]

#: ``df::measured_curve_factor`` (``base`` None: MDL's ``bsdf()``)
SIGNATURE = Signature("bsdf", (
    Param("curve_values", "color[]", REQUIRED, uniform=True),
    Param("base", "bsdf", None),
))
_N = SIGNATURE.offset("curve_values")
_AT = SIGNATURE.width


@njit
def scale(P, row, b, flags, wox, woy, woz, wix, wiy, wiz):
    """the factor ``C(wo.h)`` per channel (0 where ``wo.h < 0``)."""
    c = scale_cosine(wox, woy, woz, wix, wiy, wiz)
    if c < 0.0:
        return 0.0, 0.0, 0.0
    return measured_curve3(P, row, b + _AT, int(P[row, b + _N]), c)


@njit
def curve_constant(P, row, b, flags):
    """The curve takes one value at every cosine: the albedo needs no quadrature."""
    return measured_curve_constant(P, row, b + _AT, int(P[row, b + _N]))


NODE = Node("measured_curve_factor", "bsdf", "modifier", SIGNATURE, passes_film=True,
            scale=scale, curve_constant=curve_constant)
DF = Df("measured_curve_factor", SIGNATURE, (NODE,))
MeasuredCurveFactor = DF.cls
measured_curve_factor = MeasuredCurveFactor
