"""MDL ``df::microfacet_ggx_smith_bsdf``: GGX (Trowbridge–Reitz) microfacets with Smith masking.

MDL signature (1.6)::

    bsdf microfacet_ggx_smith_bsdf(float roughness_u, float roughness_v = roughness_u,
        color tint = color(1.0), color multiscatter_tint = color(0.0),
        float3 tangent_u = state::texture_tangent_u(0),
        uniform scatter_mode mode = scatter_reflect, uniform string handle = "");

Model (libbsdf, ``reference/mdl-distribution-functions.md`` §2.4, §2.6): the GGX
normal distribution with ``alpha_u = roughness_u`` along ``tangent_u`` and ``alpha_v =
roughness_v`` across it (clamped at 1e-7: roughness 0 is a near-mirror, not a delta)::

    D(h) = 1 / (pi alpha_u alpha_v (h_t^2/alpha_u^2 + h_b^2/alpha_v^2 + h_n^2)^2)

Smith masking, uncorrelated: ``G2 = G1(wo) G1(wi)`` for reflection and refraction, ``G1
= 1 / (1 + Lambda)``; sampled through the distribution of visible normals (Heitz 2018),
so the sample weight is ``tint G1(wi)``.  Scatter modes as every glossy lobe: **no
Fresnel** in ``scatter_reflect`` and ``scatter_transmit`` (weight ``tint``; transmit
reflects only on total internal reflection), dielectric Fresnel on the renderer's IOR
pair in ``scatter_reflect_transmit``; thin-walled transmission mirrors the reflection.
``multiscatter_tint`` adds the energy-compensation lobe of :mod:`render.df._microfacet`
(reflect and reflect_transmit modes; lossless for a white lobe with ``multiscatter_tint
= 1`` to the albedo table's accuracy).

Compiled kernels (the render core): :data:`SIGNATURE`, :func:`eval_pdf`, :func:`sample`
and :func:`albedo` are the glossy-lobe kernels of :mod:`render.df._glossy_lobe` over the
microfacet lobe of :mod:`render.df._microfacet` with this df's distribution and masking;
``eval_pdf``, ``sample`` and ``albedo`` read the node's albedo table (``T``, ``t``:
:func:`albedo_table`), which holds ``E`` and ``E_avg`` for the compensation.

Departures from libbsdf: the refraction pdf includes the ``eta2^2``
Jacobian (see ``_microfacet``).

References: Walter et al., "Microfacet models for refraction through rough surfaces"
(2007); Heitz, "Sampling the GGX distribution of visible normals" (JCGT 2018)."""

from __future__ import annotations

from render.df import _glossy_lobe
from render.df._albedo import glossy_albedo_table
from render.df._microfacet import (
    GGX,
    MICROFACET_LOBES,
    SMITH,
    mf_ms_lobe,
    mf_setup,
    mf_single_sample,
    mf_value,
    microfacet_signature,
)
from render.df._registry import Df, Node
from render.jit import njit

__all__ = [
    "MicrofacetGgxSmithBsdf",
    "microfacet_ggx_smith_bsdf",
    "SIGNATURE",
    "eval_pdf",
    "sample",
    "albedo",
    "albedo_table",
]

# --- signature and kernels (the compiled render core) ---------------------------------------
SIGNATURE = microfacet_signature()
_TINT = SIGNATURE.offset("tint")


@njit
def _setup(P, row, b, flags, flip):
    """The lane's setup (:func:`render.df._microfacet.mf_setup`) with this df's
    distribution and masking."""
    return mf_setup(GGX, SMITH, P, row, b, flags, flip)


# the lobe the kernels of render.df._glossy_lobe read
_value, _single_sample, _ms_lobe = mf_value, mf_single_sample, mf_ms_lobe
eval_pdf, sample, albedo, sample_weights = _glossy_lobe.kernels(__name__)


def albedo_table(row, flags: int):
    """The node table :func:`albedo` reads (:func:`render.df._albedo.glossy_albedo_table`)."""
    return glossy_albedo_table(MicrofacetGgxSmithBsdf, row, flags)


# --- the Python class ------------------------------------------------------------------

NODE = Node("microfacet_ggx_smith_bsdf", "bsdf", "leaf", SIGNATURE, eval_pdf=eval_pdf,
            sample=sample, albedo=albedo)
DF = Df("microfacet_ggx_smith_bsdf", SIGNATURE, (NODE,), lobes=MICROFACET_LOBES,
        albedo_table=albedo_table)
MicrofacetGgxSmithBsdf = DF.cls
microfacet_ggx_smith_bsdf = MicrofacetGgxSmithBsdf
