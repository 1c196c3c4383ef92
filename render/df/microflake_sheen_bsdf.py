"""MDL ``df::microflake_sheen_bsdf``: Zeltner et al.'s LTC sheen over a multiscatter bsdf.

MDL signature (1.10)::

    bsdf microflake_sheen_bsdf(float roughness [[hard_range(0.0, 1.0)]],
                               color tint = color(1.0),
                               color multiscatter_tint = color(0.0),
                               bsdf multiscatter = diffuse_reflection_bsdf(
                                   color(1.0), 0.0, color(0.0), ""),
                               uniform string handle = "");

Model: T. Zeltner, B. Burley and M. J.-Y. Chiang, "Practical Multiple-Scattering Sheen
Using Linearly Transformed Cosines" (SIGGRAPH 2022 talk): the reflectance of a thin
volumetric layer of fibre-like SGGX microflakes (multiple scattering included) fitted,
per viewing elevation ``mu_o = wo.z`` and roughness ``alpha``, by a linearly transformed
cosine (Heitz et al. 2016).  The fitted table is the authors' "volume" fit as the MDL
SDK ships it (:mod:`render.df._microflake_sheen_table`, with its provenance and
licence).  As in libbsdf (``microflake_sheen_bsdf_*`` in ``libbsdf.cpp``) and the
authors' reference code:

* ``(a, b, c)`` bilinear in the 32 x 32 table at ``alpha = saturate(roughness)`` and
  ``mu_o`` (nodes ``i / 31``); ``c`` is the lobe's directional albedo;
* in the frame turned about the normal so that ``wo`` lies in the x-z plane
  (``x`` toward ``wo``), ``wi = (x, y, z)`` is mapped back to the cosine lobe by
  ``M^-1 = [[a, 0, b], [0, a, 0], [0, 0, 1]]``, and the lobe's density is the cosine
  density there times the Jacobian::

      D(wi) = z a^2 / (pi |(a x + b z, a y, z)|^4),     eval = tint c D(wi)

  (``eval`` with the cosine; the lobe is zero below the horizon);
* sampled exactly: a cosine-distributed direction pushed through ``M``, so ``pdf = D``
  and the weight is ``tint c``.  ``M`` keeps the sign of ``z``, so ``D`` integrates to 1
  over the upper hemisphere and the lobe's albedo is ``c`` exactly.

``multiscatter_tint`` hands what the sheen does not reflect to the ``multiscatter``
bsdf, which is weighted ``multiscatter_tint (1 - max(E(wo), E(wi)))``, with ``E`` the
sheen's white albedo (the sheen layer node of :mod:`render.df.sheen_bsdf`, shared); the
sheen lobe is chosen with the interpreter's defensive selection (libbsdf: with
probability ``E(wo)``).  Unlike ``sheen_bsdf``, MDL's default white Lambertian
``multiscatter`` is layered the same way (libbsdf has no table lobe for this df).  With
``multiscatter_tint = 0`` (the default) or ``bsdf()`` the node is the sheen lobe alone.

Departures: ``E`` is the lobe's own albedo ``c`` from the same table (libbsdf reads a
separate 64 x 64 albedo table of the same model); table nodes at ``i / 31`` (the authors'
lookup; libbsdf's texture lookup places them at texel centres); a lobe whose
interpolated ``a`` or ``c`` is 0 (the fit's empty corner at small roughness and high
``mu_o``, where ``c < 1e-5``) reflects nothing and samples nothing.  The lobe is not
reciprocal (an LTC per ``wo``), as in libbsdf.  ``handle`` only tags lobes.
"""

from __future__ import annotations

import math

import numpy as np

from render.bsdf import Lobe
from render.df import _kernel_common as kc
from render.df._microflake_sheen_table import LTC, N_ALPHA, N_MU
from render.df._registry import Df, Node
from render.df._signature import REQUIRED, Param, Signature
from render.jit import njit
from render.program import ProgramBsdf, combine, df_class, pack

__all__ = ["MicroflakeSheenBsdf", "microflake_sheen_bsdf", "SIGNATURE", "LOBE_SIGNATURE",
           "eval_pdf", "sample", "albedo", "white_albedo", "ltc_coefficients", "albedo_table"]

#: ``df::microflake_sheen_bsdf`` (MDL 1.10); ``multiscatter`` is a child, not packed
SIGNATURE = Signature("bsdf", (
    Param("roughness", "float", REQUIRED, clamp=(0.0, 1.0)),
    Param("tint", "color", (1.0, 1.0, 1.0), clamp=(0.0, 1.0)),
    Param("multiscatter_tint", "color", (0.0, 0.0, 0.0), clamp=(0.0, 1.0)),
    Param("multiscatter", "bsdf", "df::diffuse_reflection_bsdf()"),
    Param("handle", "string", "", uniform=True),
))
#: the sheen lobe's own node
LOBE_SIGNATURE = Signature("bsdf", (
    Param("roughness", "float", REQUIRED, clamp=(0.0, 1.0)),
    Param("tint", "color", (1.0, 1.0, 1.0), clamp=(0.0, 1.0)),
))
_R = LOBE_SIGNATURE.offset("roughness")
_TINT = LOBE_SIGNATURE.offset("tint")
_GLOSSY_R = int(Lobe.GLOSSY_REFLECTION)
#: an LTC whose ``a`` is below this is the fit's empty corner (there ``c`` is 0 too)
_A_MIN = 1e-7
#: the node table: the LTC table, row-major (alpha, mu, 3)
_TABLE = np.ascontiguousarray(LTC.ravel())
_TABLE.setflags(write=False)


@njit
def ltc_coefficients(tables, t, alpha, mu):
    """``(a, b, c)`` bilinear in the table at ``tables[t:]`` (roughness ``alpha`` and
    ``mu = cos theta_o``, both clamped to [0, 1))."""
    x = min(max(alpha, 0.0), kc.ONE_MINUS_EPS) * (N_ALPHA - 1)
    y = min(max(mu, 0.0), kc.ONE_MINUS_EPS) * (N_MU - 1)
    i = int(x)
    j = int(y)
    fx = x - i
    fy = y - j
    g = t + (i * N_MU + j) * 3
    h = g + N_MU * 3
    w00, w01, w10, w11 = (1.0 - fx) * (1.0 - fy), (1.0 - fx) * fy, fx * (1.0 - fy), fx * fy
    a = w00 * tables[g] + w01 * tables[g + 3] + w10 * tables[h] + w11 * tables[h + 3]
    b = (w00 * tables[g + 1] + w01 * tables[g + 4] + w10 * tables[h + 1]
         + w11 * tables[h + 4])
    c = (w00 * tables[g + 2] + w01 * tables[g + 5] + w10 * tables[h + 2]
         + w11 * tables[h + 5])
    return a, b, c


@njit
def _frame(wox, woy):
    """The tangent axis toward ``wo`` (``x``) and the one across it (``y``)."""
    s = math.sqrt(wox * wox + woy * woy)
    if not s > 1e-12:
        return 1.0, 0.0, 0.0, 1.0  # normal incidence: the lobe is round (b = 0)
    return wox / s, woy / s, -woy / s, wox / s


@njit
def _density(a, b, x, y, z):
    """The LTC's density at the unit direction ``(x, y, z)`` of the aligned frame."""
    if not z > kc.COS_ZERO:
        return 0.0
    ox = a * x + b * z
    oy = a * y
    ll = ox * ox + oy * oy + z * z
    return z * a * a / (kc.PI * ll * ll)


@njit
def _setup(P, row, b, woz, tables, t):
    """``(ok, a, b, c)``: the lane's LTC at ``|wo.z|``."""
    t0, t1, t2 = P[row, b + _TINT], P[row, b + _TINT + 1], P[row, b + _TINT + 2]
    if (t0 == 0.0 and t1 == 0.0 and t2 == 0.0) or not woz > kc.COS_ZERO:
        return False, 0.0, 0.0, 0.0
    la, lb, lc = ltc_coefficients(tables, t, P[row, b + _R], woz)
    return la > _A_MIN and lc > 0.0, la, lb, lc


@njit
def eval_pdf(P, row, b, flags, wox, woy, woz, wix, wiy, wiz, tables, t):
    """``f |cos theta_i|`` and the pdf of :func:`sample` -> ``(f0, f1, f2, pdf)``."""
    if woz < 0.0:
        woz = -woz
        wiz = -wiz
    ok, la, lb, lc = _setup(P, row, b, woz, tables, t)
    if not ok:
        return 0.0, 0.0, 0.0, 0.0
    xx, xy, yx, yy = _frame(wox, woy)
    pdf = _density(la, lb, wix * xx + wiy * xy, wix * yx + wiy * yy, wiz)
    if not pdf > 0.0:
        return 0.0, 0.0, 0.0, 0.0
    f = lc * pdf
    return P[row, b + _TINT] * f, P[row, b + _TINT + 1] * f, P[row, b + _TINT + 2] * f, pdf


@njit
def sample(P, row, b, flags, wox, woy, woz, u1, u2x, u2y, tables, t):
    """-> ``(wix, wiy, wiz, pdf, w0, w1, w2, lobe)`` (all 0 where the sample fails)."""
    flip = woz < 0.0
    if flip:
        woz = -woz
    ok, la, lb, lc = _setup(P, row, b, woz, tables, t)
    if not ok:
        return 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0
    cx, cy, cz = kc.cosine_hemisphere(kc.clamp_u(u2x), kc.clamp_u(u2y))
    # through M = [[1/a, 0, -b/a], [0, 1/a, 0], [0, 0, 1]], then normalise
    x, y, z, good = kc.unitize((cx - lb * cz) / la, cy / la, cz)
    pdf = _density(la, lb, x, y, z) if good else 0.0
    if not pdf > 0.0:
        return 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0
    xx, xy, yx, yy = _frame(wox, woy)
    wix = x * xx + y * yx
    wiy = x * xy + y * yy
    # the rotation back is exact to rounding; re-evaluate the density at the rotated
    # direction so that eval_pdf returns the same pdf bit for bit
    pdf = _density(la, lb, wix * xx + wiy * xy, wix * yx + wiy * yy, z)
    if not pdf > 0.0:
        return 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0
    return (wix, wiy, -z if flip else z, pdf, P[row, b + _TINT] * lc,
            P[row, b + _TINT + 1] * lc, P[row, b + _TINT + 2] * lc, _GLOSSY_R)


@njit
def white_albedo(P, row, b, flags, ox, oy, oz, tables, t):
    """The sheen lobe's white directional albedo ``E(wo) = c(|wo.z|)`` (0 where the lobe
    is absent)."""
    mu = abs(oz)
    if not mu > kc.COS_ZERO:
        return 0.0
    la, lb, lc = ltc_coefficients(tables, t, P[row, b + _R], mu)
    return lc if la > _A_MIN and lc > 0.0 else 0.0


@njit
def albedo(P, row, b, flags, wox, woy, woz, tables, t):
    """``tint c(|wo.z|)``: exact for this lobe -> ``(a0, a1, a2)``."""
    e = white_albedo(P, row, b, flags, wox, woy, woz, tables, t)
    return P[row, b + _TINT] * e, P[row, b + _TINT + 1] * e, P[row, b + _TINT + 2] * e


def albedo_table(row, flags: int = 0) -> np.ndarray:
    """The node table: the LTC table (the same for every lane and roughness; a writable
    copy, as every node table: numba compiles its kernels once more for a read-only
    array)."""
    return _TABLE.copy()


# --- the Python class ------------------------------------------------------------------
#: the sheen lobe (a leaf; over another bsdf, the sheen layer of render.df.sheen_bsdf)
NODE = Node("microflake_sheen_bsdf", "bsdf", "leaf", LOBE_SIGNATURE, eval_pdf=eval_pdf,
            sample=sample, albedo=albedo, white_albedo=white_albedo)
_Lobe = df_class(Df("microflake_sheen_bsdf", LOBE_SIGNATURE, (NODE,),
                    py_name="MicroflakeSheenLobe", lobes=Lobe.GLOSSY_REFLECTION,
                    albedo_table=albedo_table))


class _DefaultDiffuse:
    def __repr__(self) -> str:
        return "df::diffuse_reflection_bsdf()"


#: MDL's default ``multiscatter``: the white Lambertian lobe
DEFAULT_MULTISCATTER = _DefaultDiffuse()


class MicroflakeSheenBsdf(ProgramBsdf):
    """``df::microflake_sheen_bsdf`` over lanes (see the module docstring): its kernels,
    run by :mod:`render.interpreter`.

    Parameters (MDL's, constants or one value per lane): roughness, tint,
    multiscatter_tint, multiscatter (a bound bsdf, None for ``bsdf()``, or MDL's
    default white Lambertian lobe).
    """

    mdl_name = "microflake_sheen_bsdf"
    signature = SIGNATURE

    def __init__(self, roughness, tint=(1.0, 1.0, 1.0), multiscatter_tint=(0.0, 0.0, 0.0),
                 multiscatter=DEFAULT_MULTISCATTER):
        from render.df.sheen_bsdf import LAYER_NODE, LAYER_SIGNATURE

        title = "df::microflake_sheen_bsdf"
        lobe = _Lobe(roughness, tint)
        cols, flags = pack(LAYER_SIGNATURE, {"multiscatter_tint": multiscatter_tint}, title)
        if multiscatter is DEFAULT_MULTISCATTER:
            from render.df.diffuse_reflection_bsdf import DiffuseReflectionBsdf

            multiscatter = DiffuseReflectionBsdf()
        elif multiscatter is not None and not isinstance(multiscatter, ProgramBsdf):
            raise ValueError(f"{title}(multiscatter) must be a bound bsdf (a render.df "
                             f"distribution function) or None for MDL's black bsdf(), got "
                             f"{type(multiscatter).__name__}")
        if multiscatter is None or not np.any(cols > 0.0):
            program = lobe.program  # nothing reaches the multiscatter bsdf
        else:
            program = combine("bsdf", LAYER_NODE.op, cols, flags,
                              [lobe.program, multiscatter.program])
        ProgramBsdf.__init__(self, program)
        self.multiscatter = multiscatter


microflake_sheen_bsdf = MicroflakeSheenBsdf
DF = Df("microflake_sheen_bsdf", SIGNATURE, (NODE,), lobes=Lobe.GLOSSY_REFLECTION,
        constructor=MicroflakeSheenBsdf)
