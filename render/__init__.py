"""Render: a small path tracer that evaluates MDL's material model (distribution functions first).

Conventions for directions and frames: :mod:`render.frame`.  Interfaces: :mod:`render.bsdf`.
"""

from render import df
from render.bsdf import Bsdf, BsdfSample, Edf, EdfSample, Lobe
from render.frame import Frame

__all__ = ["df", "Bsdf", "BsdfSample", "Edf", "EdfSample", "Lobe", "Frame"]
