"""MDL ``df::simple_glossy_bsdf``: an anisotropic Ashikhmin–Shirley lobe with v-cavities masking.

MDL signature::

    bsdf simple_glossy_bsdf(float roughness_u, float roughness_v = roughness_u,
                            color tint = color(1.0), color multiscatter_tint = color(0.0),
                            float3 tangent_u = state::texture_tangent_u(0),
                            uniform scatter_mode mode = scatter_reflect,
                            uniform string handle = "");

What libbsdf really computes (``reference/mdl-distribution-functions.md`` §2.5): neither
GGX nor Beckmann, but the Ashikhmin–Shirley (Phong) half-vector distribution with
exponents ``e_u = 2 / roughness_u^2``, ``e_v = 2 / roughness_v^2`` (roughness clamped at
``1e-7``, so roughness 0 is a near-mirror lobe, not a delta)::

    D(h) (n.h) = sqrt((e_u + 1)(e_v + 1)) / (2 pi) * (n.h)^((e_u h_t^2 + e_v h_b^2) / (1 - (n.h)^2))

with v-cavities masking and libbsdf's scatter modes: **no Fresnel** in
``scatter_reflect`` and ``scatter_transmit`` (weight ``tint``; transmit reflects only on
total internal reflection), dielectric Fresnel on the renderer's IOR pair in
``scatter_reflect_transmit``.  The framework (half vectors, masking, pdfs, sampling) is
:mod:`render.df._microfacet`; half vectors are sampled in closed form (``phi`` from the
quadrant formula, ``cos theta_h = (1 - u)^(1 / (e_u cos^2 phi + e_v sin^2 phi + 1))``).

Departures from libbsdf:

* the exponent is evaluated as ``exp(x/2 * log1p(-s2))`` with ``s2 = h_t^2 + h_b^2``
  taken from the tangential components, exact down to roughness 1e-7; libbsdf instead
  sets the exponential factor to 1 whenever ``n.h > 0.99999``, which for narrow lobes
  (roughness below ~0.01) makes ``D`` integrate to far more than 1;
* the refraction pdf includes the ``eta2^2`` Jacobian (see ``_microfacet``);
* ``multiscatter_tint`` adds libbsdf's energy-compensation lobe
  (:mod:`render.df._microfacet`), from this lobe's own albedo table.

Compiled kernels (the render core): :data:`SIGNATURE`, :func:`eval_pdf`, :func:`sample`
and :func:`albedo`, one lane at a time: the glossy-lobe kernels of
:mod:`render.df._glossy_lobe` over the microfacet lobe of :mod:`render.df._microfacet`
with Ashikhmin–Shirley's distribution (:func:`~render.df._microfacet.as_d_cos`,
:func:`~render.df._microfacet.as_sample`) and v-cavities masking.  All three take two
arguments beyond the kernel contract, the program's table array ``T`` and this node's
offset ``t`` in it, filled by :func:`albedo_table` (see :mod:`render.df._albedo` for why
the tables are not frozen into the kernel): the albedo and the compensation lobe read it.

References: Ashikhmin & Shirley, "An anisotropic Phong BRDF model" (2000); Heitz &
d'Eon, "Importance sampling microfacet-based BSDFs using the distribution of visible
normals" (2014).
"""

from __future__ import annotations

import numpy as np

from render.df import _glossy_lobe
from render.df._albedo import glossy_albedo_table
from render.df._microfacet import (
    ASHIKHMIN_SHIRLEY,
    MICROFACET_LOBES,
    VCAVITIES,
    mf_ms_lobe,
    mf_setup,
    mf_single_sample,
    mf_value,
    microfacet_signature,
)
from render.df._registry import Df, Node
from render.jit import njit

__all__ = [
    "SimpleGlossyBsdf",
    "simple_glossy_bsdf",
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
    """The lane's setup (:func:`render.df._microfacet.mf_setup`): Ashikhmin–Shirley's
    distribution, v-cavities masking."""
    return mf_setup(ASHIKHMIN_SHIRLEY, VCAVITIES, P, row, b, flags, flip)


# the lobe the kernels of render.df._glossy_lobe read
_value, _single_sample, _ms_lobe = mf_value, mf_single_sample, mf_ms_lobe
eval_pdf, sample, albedo, sample_weights = _glossy_lobe.kernels(__name__)


def albedo_table(row, flags: int) -> np.ndarray:
    """The node table :func:`albedo` reads (:func:`render.df._albedo.glossy_albedo_table`:
    a node table for one packed row, a lanes table for per-lane roughness or IOR)."""
    return glossy_albedo_table(SimpleGlossyBsdf, row, flags)

# --- the Python class ------------------------------------------------------------------

NODE = Node("simple_glossy_bsdf", "bsdf", "leaf", SIGNATURE, eval_pdf=eval_pdf, sample=sample,
            albedo=albedo)
DF = Df("simple_glossy_bsdf", SIGNATURE, (NODE,), lobes=MICROFACET_LOBES, albedo_table=albedo_table)
SimpleGlossyBsdf = DF.cls
simple_glossy_bsdf = SimpleGlossyBsdf
