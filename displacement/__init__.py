"""Displacement: base surfaces, displacement fields, tessellation, bump maps and solids.

Knows curves (``pwc``) and surfaces, nothing of light.
"""

from displacement.state import ShadingState

__all__ = ["ShadingState"]
