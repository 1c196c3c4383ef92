"""MDL ``df::diffuse_edf``: uniform (Lambertian) emission, radiance = intensity / pi.

MDL signature::

    edf diffuse_edf(uniform string handle = "");

Model (libbsdf, ``reference/mdl-distribution-functions.md`` §5): ``eval = 1/pi`` toward
every direction of the ``+z`` hemisphere, normalised so that ``∫ eval cos theta = 1``;
the renderer multiplies by ``material_emission.intensity`` (radiant exitance, or power
over area in ``intensity_power`` mode).  **So an intensity ``I`` is seen as radiance
``I / pi``: to display a color ``c``, set ``intensity = pi c``** (as NVIDIA's
``core_definitions.mdl`` does).  Cosine-weighted sampling, ``pdf = cos theta / pi``,
weight 1.  Only ``+z`` emits (the integrator orients the frame toward the emitting face).
"""

from __future__ import annotations

from render.df import _kernel_common as kc
from render.df._registry import Df, Node
from render.df._signature import Param, Signature
from render.jit import njit

__all__ = [
    "DiffuseEdf",
    "diffuse_edf",
    "SIGNATURE",
    "edf_eval_pdf",
    "edf_sample",
]


# --- signature and kernels (the compiled render core) ---------------------------------

SIGNATURE = Signature("edf", (Param("handle", "string", "", uniform=True),))


@njit
def edf_eval_pdf(P, row, b, flags, wox, woy, woz):
    """Emission per unit intensity toward ``wo`` and its density -> ``(e0, e1, e2, pdf)``:
    ``1/pi`` and ``cos theta / pi`` on the ``+z`` side."""
    if not woz > kc.COS_ZERO:
        return 0.0, 0.0, 0.0, 0.0
    return kc.INV_PI, kc.INV_PI, kc.INV_PI, woz * kc.INV_PI


@njit
def edf_sample(P, row, b, flags, u1, u2x, u2y):
    """A cosine-weighted emission direction -> ``(wox, woy, woz, pdf, w0, w1, w2)``
    (weight ``eval cos / pdf = 1``)."""
    x, y, z = kc.cosine_hemisphere(kc.clamp_u(u2x), kc.clamp_u(u2y))
    if not z > kc.COS_ZERO:
        return 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0
    return x, y, z, z * kc.INV_PI, 1.0, 1.0, 1.0


# --- the Python class ------------------------------------------------------------------

NODE = Node("diffuse_edf", "edf", "leaf", SIGNATURE, edf_eval_pdf=edf_eval_pdf,
            edf_sample=edf_sample)
DF = Df("diffuse_edf", SIGNATURE, (NODE,), lambertian=True)
DiffuseEdf = DF.cls
diffuse_edf = DiffuseEdf
