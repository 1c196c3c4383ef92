"""MDL's ``::df`` module: one distribution function per module, named as in MDL.

Each df is a class (``DiffuseReflectionBsdf``) with an alias of its MDL name
(``diffuse_reflection_bsdf``), so a material reads like MDL::

    from render import df
    glass = df.specular_bsdf(mode="scatter_reflect_transmit", ior_inside=1.5)

Conventions (directions, sides, IORs): :mod:`render.frame`; interfaces:
:mod:`render.bsdf`.
"""

from render.df._common import ScatterMode
from render.df.backscattering_glossy_reflection_bsdf import (
    BackscatteringGlossyReflectionBsdf,
    backscattering_glossy_reflection_bsdf,
)
from render.df.diffuse_edf import DiffuseEdf, diffuse_edf
from render.df.diffuse_reflection_bsdf import DiffuseReflectionBsdf, diffuse_reflection_bsdf
from render.df.diffuse_transmission_bsdf import DiffuseTransmissionBsdf, diffuse_transmission_bsdf
from render.df.simple_glossy_bsdf import SimpleGlossyBsdf, simple_glossy_bsdf
from render.df.specular_bsdf import SpecularBsdf, specular_bsdf
from render.df.spot_edf import SpotEdf, spot_edf

#: MDL's ``df::scatter_mode`` enumerators
scatter_reflect = ScatterMode.scatter_reflect
scatter_transmit = ScatterMode.scatter_transmit
scatter_reflect_transmit = ScatterMode.scatter_reflect_transmit

__all__ = [
    "ScatterMode",
    "scatter_reflect",
    "scatter_transmit",
    "scatter_reflect_transmit",
    "DiffuseReflectionBsdf",
    "diffuse_reflection_bsdf",
    "DiffuseTransmissionBsdf",
    "diffuse_transmission_bsdf",
    "SpecularBsdf",
    "specular_bsdf",
    "SimpleGlossyBsdf",
    "simple_glossy_bsdf",
    "BackscatteringGlossyReflectionBsdf",
    "backscattering_glossy_reflection_bsdf",
    "DiffuseEdf",
    "diffuse_edf",
    "SpotEdf",
    "spot_edf",
]
