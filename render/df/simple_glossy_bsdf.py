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
* ``multiscatter_tint`` is not implemented yet (``albedo()`` gives the single-scattering
  table that the compensation would need).

References: Ashikhmin & Shirley, "An anisotropic Phong BRDF model" (2000); Heitz &
d'Eon, "Importance sampling microfacet-based BSDFs using the distribution of visible
normals" (2014).
"""

from __future__ import annotations

import numpy as np

from render._typing import Arr, Arr2
from render.df._microfacet import MicrofacetBsdf

__all__ = ["SimpleGlossyBsdf", "simple_glossy_bsdf", "AshikhminShirley"]


class AshikhminShirley:
    """Anisotropic Ashikhmin–Shirley half-vector density ``D(h) (n.h)`` over lanes.

    Parameters
    ----------
    roughness_u, roughness_v : (n,) float64
        Already clamped to ``>= TOL.roughness_min``; exponents ``e = 2 / r^2``.

    Examples
    --------
    >>> d = AshikhminShirley(np.array([0.5]), np.array([0.5]))
    >>> round(float(d.d_cos(np.zeros(1), np.zeros(1), np.ones(1))[0] * 2 * np.pi), 12)
    9.0
    """

    def __init__(self, roughness_u: Arr, roughness_v: Arr):
        self.e_u = 2.0 / (roughness_u * roughness_u)
        self.e_v = 2.0 / (roughness_v * roughness_v)
        self.norm = np.sqrt((self.e_u + 1.0) * (self.e_v + 1.0)) / (2.0 * np.pi)

    def d_cos(self, ht: Arr, hb: Arr, hn: Arr) -> Arr:
        """``D(h) (n.h)`` for unit half vectors given in the anisotropy frame."""
        s2 = ht * ht + hb * hb
        valid = (hn > 0.0) & (s2 < 1.0)
        s2c = np.where(valid, s2, 0.5)
        # (n.h)^(x) = exp(x/2 * log(1 - s2)); x s2 = e_u ht^2 + e_v hb^2 stays finite as s2 -> 0
        ratio = np.where(s2c > 0.0, np.log1p(-s2c) / np.where(s2c > 0.0, s2c, 1.0), -1.0)
        expo = 0.5 * (self.e_u * ht * ht + self.e_v * hb * hb) * ratio
        return np.where(valid, self.norm * np.exp(expo), 0.0)

    def sample(self, u: Arr2) -> tuple[Arr, Arr, Arr]:
        """Half vectors ``(ht, hb, hn)`` with density ``D(h) (n.h)``, from ``u`` (n, 2)."""
        # azimuth: quadrant from u0, then tan(phi) = sqrt((e_u+1)/(e_v+1)) tan(pi u'/2)
        q = np.floor(4.0 * u[:, 0])
        up = 4.0 * u[:, 0] - q
        half = 0.5 * np.pi * up
        phi0 = np.arctan2(
            np.sqrt(self.e_u + 1.0) * np.sin(half), np.sqrt(self.e_v + 1.0) * np.cos(half)
        )
        phi = np.select(
            [q == 0, q == 1, q == 2], [phi0, np.pi - phi0, np.pi + phi0], 2.0 * np.pi - phi0
        )
        cp, sp = np.cos(phi), np.sin(phi)
        e = self.e_u * cp * cp + self.e_v * sp * sp
        # cos theta = (1 - u1)^(1/(e+1)); keep 1 - cos accurate for huge exponents
        one_minus_cos = -np.expm1(np.log1p(-u[:, 1]) / (e + 1.0))
        cos_t = 1.0 - one_minus_cos
        sin_t = np.sqrt(np.maximum(one_minus_cos * (2.0 - one_minus_cos), 0.0))
        return sin_t * cp, sin_t * sp, cos_t


class SimpleGlossyBsdf(MicrofacetBsdf):
    """``df::simple_glossy_bsdf`` over lanes (parameters: :class:`MicrofacetBsdf`).

    Examples
    --------
    >>> g = simple_glossy_bsdf(roughness_u=0.3)
    >>> wo = np.array([[0.0, 0.0, 1.0]])
    >>> s = g.sample(wo, np.array([0.3]), np.array([[0.2, 0.7]]))
    >>> bool(np.allclose(g.eval(wo, s.wi) / g.pdf(wo, s.wi)[:, None], s.weight))
    True
    """

    _mdl_name = "simple_glossy_bsdf"

    def _distribution(self, ru: Arr, rv: Arr) -> AshikhminShirley:
        return AshikhminShirley(ru, rv)


simple_glossy_bsdf = SimpleGlossyBsdf
