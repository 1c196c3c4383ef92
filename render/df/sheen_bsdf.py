"""MDL ``df::sheen_bsdf``: a sheen lobe (Conty & Kulla's "Charlie") over a multiscatter bsdf.

MDL signature (1.10)::

    bsdf sheen_bsdf(float roughness, color tint = color(1.0),
                    color multiscatter_tint = color(0.0),
                    bsdf multiscatter = diffuse_reflection_bsdf(color(1.0), 0.0, color(0.0), ""),
                    uniform string handle = "");

Model (libbsdf, ``reference/mdl-distribution-functions.md`` §2.8): a reflection-only
microfacet lobe, no Fresnel, with v-cavities masking and the "Charlie" distribution of
``q = 1 / roughness`` (roughness clamped at 1e-7)::

    D(h) = (2 + q) sin(theta_h)^q / (2 pi),     sampled as sin(theta_h) = (1 - u)^(1/(q+2))

then the v-cavities flip (:mod:`render.df._microfacet`).  ``multiscatter_tint`` hands
the energy the lobe does not reflect to the ``multiscatter`` bsdf:

* with MDL's default ``multiscatter`` (the white Lambertian lobe; also when given
  explicitly with its default arguments), libbsdf's table-based compensation lobe of
  the glossy dfs, ``multiscatter_tint (1 - E(wo)) (1 - E(wi)) |wi.z| / (pi (1 - E_avg))``:
  one leaf node (``O_SHEEN``), lossless for white tints to the table's accuracy;
* with another bsdf, a layer node (``O_SHEEN_LAYER``): the sheen lobe over the bsdf
  weighted by ``multiscatter_tint (1 - max(E(wo), E(wi)))``, ``E`` the sheen lobe's white
  albedo read from its table (reciprocal where the bsdf is; never more than 1, as
  ``E(wo) + (1 - E(wo)) albedo_base <= 1``).  Sampling picks the sheen lobe with the
  interpreter's defensive selection (libbsdf: with probability ``E(wo)``).

``bsdf()`` (None) as ``multiscatter`` gives the sheen lobe alone.
"""

from __future__ import annotations

import math

import numpy as np

from render.bsdf import Lobe
from render.df import _glossy_lobe
from render.df import _kernel_common as kc
from render.df._albedo import glossy_albedo_table
from render.df._microfacet import (
    mf_finish,
    mf_geometry,
    mf_sample_dir,
    ms_albedo,
    ms_lobe,
    ms_on,
)
from render.df._registry import Df, Node
from render.df._signature import REQUIRED, Param, Signature
from render.jit import njit
from render.program import ProgramBsdf, combine, df_class, pack

__all__ = ["SheenBsdf", "sheen_bsdf", "SIGNATURE", "LAYER_SIGNATURE", "eval_pdf", "sample",
           "albedo", "albedo_table", "white_albedo", "layer_factors", "layer_estimates",
           "layer_possible"]

#: ``df::sheen_bsdf`` (MDL 1.10); ``multiscatter`` is a child, not packed
SIGNATURE = Signature("bsdf", (
    Param("roughness", "float", REQUIRED, clamp=(kc.ROUGHNESS_MIN, None)),
    Param("tint", "color", (1.0, 1.0, 1.0), clamp=(0.0, 1.0)),
    Param("multiscatter_tint", "color", (0.0, 0.0, 0.0), clamp=(0.0, 1.0)),
    Param("multiscatter", "bsdf", "df::diffuse_reflection_bsdf()"),
    Param("handle", "string", "", uniform=True),
))
#: the sheen lobe's own node (the same slots, no child)
LOBE_SIGNATURE = Signature("bsdf", tuple(p for p in SIGNATURE.params
                                         if p.name != "multiscatter"))
#: the layer node over a ``multiscatter`` bsdf that is not the default one
LAYER_SIGNATURE = Signature("bsdf", (
    Param("multiscatter_tint", "color", (0.0, 0.0, 0.0), clamp=(0.0, 1.0)),))
_R = SIGNATURE.offset("roughness")
_TINT = SIGNATURE.offset("tint")
_MS = SIGNATURE.offset("multiscatter_tint")
_GLOSSY_R = int(Lobe.GLOSSY_REFLECTION)
_TWO_PI = 2.0 * math.pi


@njit
def _setup(P, row, b, flags, flip):
    """The lane's setup (:mod:`render.df._glossy_lobe`): ``s = (q,)``."""
    q = 1.0 / max(P[row, b + _R], kc.ROUGHNESS_MIN)
    glossy = not (P[row, b + _TINT] == 0.0 and P[row, b + _TINT + 1] == 0.0
                  and P[row, b + _TINT + 2] == 0.0)
    ms = ms_on(0, P[row, b + _MS], P[row, b + _MS + 1], P[row, b + _MS + 2])
    return glossy or ms, glossy, ms, False, (q,)


@njit
def _d(q, hz):
    """The Charlie density ``(2 + q) sin(theta_h)^q / (2 pi)``."""
    s2 = max(1.0 - hz * hz, 0.0)
    if not s2 > 0.0:
        return 0.0
    return (2.0 + q) * math.exp(0.5 * q * math.log(s2)) / _TWO_PI


@njit
def _value(P, row, b, flags, wox, woy, woz, wix, wiy, wiz, s):
    """The sheen lobe at an oriented pair -> ``(w0, w1, w2, pdf)``."""
    q = s[0]
    ok, refr, hx, hy, hz, kh1, kh2, p_ev, g1_1, g2 = mf_geometry(
        0, 1.0, 1.0, wox, woy, woz, wix, wiy, wiz)
    if not ok:
        return 0.0, 0.0, 0.0, 0.0
    return mf_finish(_d(q, hz), refr, woz, kh1, kh2, 1.0, 1.0, p_ev, g1_1, g2,
                     P[row, b + _TINT], P[row, b + _TINT + 1], P[row, b + _TINT + 2])


@njit
def _single_sample(P, row, b, flags, wox, woy, woz, u1, u2x, u2y, s):
    """A half vector from ``D (n.h)`` (``sin theta_h = (1 - u)^(1/(q+2))``), then the
    v-cavities flip -> ``(ok, wix, wiy, wiz)``."""
    q = s[0]
    phi = _TWO_PI * u2x
    sin_t = math.exp(math.log1p(-u2y) / (q + 2.0))
    cos_t = math.sqrt(max(1.0 - sin_t * sin_t, 0.0))
    return mf_sample_dir(0, 1.0, 1.0, wox, woy, woz, sin_t * math.cos(phi),
                         sin_t * math.sin(phi), cos_t, u1, True, 0.0, 1.0, 1.0, 1.0)


@njit
def _ms_lobe(P, row, b, s, glossy):
    """:func:`ms_lobe` of a lane (isotropic: any tangent)."""
    r = P[row, b + _R]
    return ms_lobe(P, row, b + _MS, r, r, 1.0, 1.0, 1.0, 0.0, glossy)


eval_pdf, sample, albedo, sample_weights = _glossy_lobe.kernels(__name__)


@njit
def white_albedo(P, row, b, flags, ox, oy, oz, T, t):
    """The sheen lobe's white directional albedo ``E(wo)`` from its node table."""
    r = max(P[row, b + _R], kc.ROUGHNESS_MIN)
    if not abs(oz) > kc.COS_ZERO:
        return 0.0
    return ms_albedo(T, t, False, r, r, 1.0, 1.0, 1.0, 0.0, ox, oy, oz)


def albedo_table(row, flags: int = 0) -> np.ndarray:
    """The sheen lobe's node table (:func:`render.df._albedo.glossy_albedo_table`: per lane
    where the roughness differs)."""
    return glossy_albedo_table(_SheenLobe, row, flags)


# --- the layer over a multiscatter bsdf that is not the default --------------------------
_L_MS = LAYER_SIGNATURE.offset("multiscatter_tint")


@njit
def layer_factors(P, row, b, flags, wox, woy, woz, wix, wiy, wiz,
                  wolx, woly, wolz, wilx, wily, wilz, co0, co1, co2, ci0, ci1, ci2):
    """``(1, multiscatter_tint (1 - max(E(wo), E(wi))))`` per channel; the interpreter
    passes ``E(wo)``, ``E(wi)`` (the sheen lobe's white albedo) as ``co``, ``ci``."""
    e = 1.0 - max(co0, ci0)
    return (1.0, 1.0, 1.0, P[row, b + _L_MS] * e, P[row, b + _L_MS + 1] * e,
            P[row, b + _L_MS + 2] * e)


@njit
def layer_estimates(P, row, b, flags, wox, woy, woz, wolx, woly, wolz, co0, co1, co2):
    """``(1, multiscatter_tint (1 - E(wo)))``."""
    e = 1.0 - co0
    return (1.0, 1.0, 1.0, P[row, b + _L_MS] * e, P[row, b + _L_MS + 1] * e,
            P[row, b + _L_MS + 2] * e)


@njit
def layer_possible(P, row, b, flags):
    """The sheen lobe always; the base where ``multiscatter_tint`` is positive."""
    return True, (P[row, b + _L_MS] > 0.0 or P[row, b + _L_MS + 1] > 0.0
                  or P[row, b + _L_MS + 2] > 0.0)


# --- the Python class ------------------------------------------------------------------
#: the sheen lobe (a leaf), and the layer of it over another bsdf (Ĉ: the lobe's E)
NODE = Node("sheen_bsdf", "bsdf", "leaf", LOBE_SIGNATURE, eval_pdf=eval_pdf, sample=sample,
            albedo=albedo, white_albedo=white_albedo)
LAYER_NODE = Node("sheen_layer", "bsdf", "layer", LAYER_SIGNATURE, chat_from_lobe=True,
                  layer_factors=layer_factors, layer_estimates=layer_estimates,
                  layer_possible=layer_possible)
_SheenLobe = df_class(Df("sheen_bsdf", LOBE_SIGNATURE, (NODE,), py_name="SheenLobe",
                         lobes=Lobe.GLOSSY_REFLECTION, albedo_table=albedo_table))


class _DefaultDiffuse:
    def __repr__(self) -> str:
        return "df::diffuse_reflection_bsdf()"


#: MDL's default ``multiscatter``: the white Lambertian lobe
DEFAULT_MULTISCATTER = _DefaultDiffuse()


def _is_default_diffuse(bsdf) -> bool:
    from render.df.diffuse_reflection_bsdf import SIGNATURE as DSIG
    from render.df.diffuse_reflection_bsdf import DiffuseReflectionBsdf

    if not isinstance(bsdf, DiffuseReflectionBsdf) or bsdf.program.code.shape[0] != 1:
        return False
    want = np.array([1.0, 1.0, 1.0, 0.0, 0.0, 0.0, 0.0])[: DSIG.width]
    return bool(np.all(bsdf.program.P == want))


class SheenBsdf(ProgramBsdf):
    """``df::sheen_bsdf`` over lanes (see the module docstring): its kernels, run by
    :mod:`render.interpreter`.

    Parameters (MDL's, constants or one value per lane): roughness, tint,
    multiscatter_tint, multiscatter (a bound bsdf, None for ``bsdf()``, or MDL's
    default white Lambertian lobe).
    """

    mdl_name = "sheen_bsdf"
    signature = SIGNATURE

    def __init__(self, roughness, tint=(1.0, 1.0, 1.0), multiscatter_tint=(0.0, 0.0, 0.0),
                 multiscatter=DEFAULT_MULTISCATTER):
        title = "df::sheen_bsdf"
        if multiscatter is DEFAULT_MULTISCATTER or _is_default_diffuse(multiscatter):
            program = _SheenLobe(roughness, tint, multiscatter_tint).program
        else:
            if multiscatter is not None and not isinstance(multiscatter, ProgramBsdf):
                raise ValueError(f"{title}(multiscatter) must be a bound bsdf (a render.df "
                                 f"distribution function) or None for MDL's black bsdf(), got "
                                 f"{type(multiscatter).__name__}")
            lobe = _SheenLobe(roughness, tint, 0.0)
            if multiscatter is None:
                program = lobe.program
            else:
                cols, flags = pack(LAYER_SIGNATURE, {"multiscatter_tint": multiscatter_tint},
                                   title)
                program = combine("bsdf", LAYER_NODE.op, cols, flags,
                                  [lobe.program, multiscatter.program])
        ProgramBsdf.__init__(self, program)
        self.multiscatter = multiscatter


sheen_bsdf = SheenBsdf
DF = Df("sheen_bsdf", SIGNATURE, (NODE, LAYER_NODE), lobes=Lobe.GLOSSY_REFLECTION,
        constructor=SheenBsdf)
