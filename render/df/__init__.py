"""MDL's ``::df`` module: one distribution function per module, named as in MDL.

Each df is a class (``DiffuseReflectionBsdf``) with an alias of its MDL name
(``diffuse_reflection_bsdf``), so a material reads like MDL::

    from render import df
    glass = df.specular_bsdf(mode="scatter_reflect_transmit", ior_inside=1.5)

Every df is declared once, in its module (:mod:`render.df._registry`); the names
below are derived from those declarations: each df's MDL name (its class, or for a
name with overloads the function that picks one) and its module's classes.

Conventions (directions, sides, IORs): :mod:`render.frame`; interfaces:
:mod:`render.bsdf`.
"""

import sys

from render.df._combine import albedo_estimate
from render.df._common import ScatterMode
from render.df._ies import IesError, LightProfile, read_ies, write_ies
from render.df._mbsdf import MbsdfError, Measurement, read_mbsdf, write_mbsdf
from render.df._mix import (
    BsdfComponent,
    ColorBsdfComponent,
    ColorEdfComponent,
    ColorVdfComponent,
    EdfComponent,
    VdfComponent,
    bsdf_component,
    color_bsdf_component,
    color_edf_component,
    color_vdf_component,
    edf_component,
    vdf_component,
)
from render.df._registry import registry

#: MDL's ``df::scatter_mode`` enumerators
scatter_reflect = ScatterMode.scatter_reflect
scatter_transmit = ScatterMode.scatter_transmit
scatter_reflect_transmit = ScatterMode.scatter_reflect_transmit


def _declared() -> dict:
    """Each declared df's MDL name (its constructor in its module, else its class) and
    the classes its module exports."""
    out = {}
    for key, declaration in registry().dfs.items():
        if declaration.struct:
            continue
        module = sys.modules[declaration.module]
        out[key] = getattr(module, key, declaration.cls)
        for name in getattr(module, "__all__", ()):
            value = getattr(module, name, None)
            if isinstance(value, type) and value.__module__ == module.__name__:
                out[name] = value
    return out


_DECLARED = _declared()
globals().update(_DECLARED)

__all__ = [
    "ScatterMode", "scatter_reflect", "scatter_transmit", "scatter_reflect_transmit",
    "BsdfComponent", "bsdf_component", "ColorBsdfComponent", "color_bsdf_component",
    "EdfComponent", "edf_component", "ColorEdfComponent", "color_edf_component",
    "VdfComponent", "vdf_component", "ColorVdfComponent", "color_vdf_component",
    "Measurement", "MbsdfError", "read_mbsdf", "write_mbsdf",
    "IesError", "LightProfile", "read_ies", "write_ies", "albedo_estimate",
    *sorted(_DECLARED),
]
