"""The one set of tolerances the compiler uses (no stray epsilons elsewhere)."""

from __future__ import annotations

from dataclasses import dataclass

__all__ = ["TOL"]


@dataclass(frozen=True)
class Tolerances:
    #: |angle| below this many degrees is a straight segment (spec: 1e-6 degrees).
    angle_deg: float = 1e-6
    #: relative distance (to the chord) under which a flare's end is on its tangent line.
    flare_rel: float = 1e-12
    #: relative distance (to the curve's extent) under which two points are identical.
    same_point_rel: float = 1e-12
    #: an arc whose sagitta is below this fraction of its chord is compiled as a segment:
    #: its radius would exceed 1e7 chords, where ``center + radius * (cos, sin)`` loses
    #: more precision (~radius * 1e-16) than the straight chord deviates from the arc.
    flat_arc_rel: float = 1e-8
    #: the largest |coordinate| of a list must lie in [coordinate_min, coordinate_max]:
    #: normalizing divides by it, so its reciprocal must be a finite, normal double, with
    #: room for the sums and chords of the constructions (outside: a clear error).
    coordinate_min: float = 1e-305
    coordinate_max: float = 1e305


TOL = Tolerances()
