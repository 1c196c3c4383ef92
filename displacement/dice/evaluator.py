"""Batched evaluation of a displaced surface in world space, and the camera's error scale.

Everything the dicer measures goes through :class:`DisplacedSurface`: base state at uv (or
at a face and barycentric point), displacement by the field, the object-to-world
transform, and :meth:`DisplacedSurface.px_scale`: how many pixels one world unit of
error is worth at a point, already divided by the off-screen coarsening.
"""

from __future__ import annotations

import warnings
from dataclasses import dataclass

import numpy as np

from displacement.camera import Camera
from displacement.dice.mesh import DicingWarning
from displacement.state import ShadingState

__all__ = ["DICE_TOL", "DisplacedSurface", "check_transform"]


@dataclass(frozen=True)
class _DiceTolerances:
    #: points per field call (bounds the memory of temporaries).
    batch: int = 1 << 20
    #: finite-difference step in uv (or barycentric) for shading normals, at most a
    #: quarter of the adjacent grid spacing (so it never crosses a crease).
    fd_step: float = 1e-6
    #: relative to the diced extent: rows/columns whose displaced points all lie within
    #: this distance of each other are a pole (collapsed to one vertex).
    pole_rel: float = 1e-9
    #: |dP/du x dP/dv| below this times the diced extent squared is a degenerate normal
    #: (finite-difference noise at a pole is ~1e-16 / fd_step = 1e-10 of the extent).
    degenerate_normal: float = 1e-7


DICE_TOL = _DiceTolerances()


def check_transform(transform) -> np.ndarray:
    """Validate an object-to-world 4x4 affine transform.

    Parameters
    ----------
    transform : (4, 4) array_like

    Returns
    -------
    (4, 4) float64

    Examples
    --------
    >>> check_transform(np.eye(4)).shape
    (4, 4)
    >>> check_transform(np.zeros((4, 4)))
    Traceback (most recent call last):
    ...
    ValueError: transform is singular: its 3x3 linear part must be invertible
    """
    m = np.asarray(transform, dtype=np.float64)
    if m.shape != (4, 4):
        raise ValueError(f"transform must be a 4x4 matrix, got shape {m.shape}")
    if not np.all(np.isfinite(m)):
        raise ValueError("transform has non-finite entries")
    if abs(np.linalg.det(m[:3, :3])) < 1e-300:
        raise ValueError("transform is singular: its 3x3 linear part must be invertible")
    if not np.allclose(m[3], [0.0, 0.0, 0.0, 1.0]):
        raise ValueError(f"transform must be affine (last row 0 0 0 1), got {m[3].tolist()}")
    return m


class DisplacedSurface:
    """A base surface moved by a displacement field, placed in the world, seen by a camera.

    Parameters
    ----------
    surface
        A parametric surface (``state_at_uv``) or a mesh surface (``state_at``).
    field : callable or None
        ``field(state) -> (n, 3)`` object-space displacement vectors; None = zero.
    transform : (4, 4) float64
        Object to world.
    camera : Camera
    dicing_rate, tolerance, offscreen_rate : float
        Pixels (see :func:`displacement.dice.dice`).
    """

    def __init__(self, surface, field, transform, camera: Camera, dicing_rate: float,
                 tolerance: float, offscreen_rate: float) -> None:
        self.surface = surface
        self.field = field
        self.matrix = check_transform(transform)
        self.linear = self.matrix[:3, :3]
        self.normal_matrix = np.linalg.inv(self.linear).T
        self.flips = bool(np.linalg.det(self.linear) < 0.0)
        self.identity = bool(np.array_equal(self.matrix, np.eye(4)))
        self.camera = camera
        self.dicing_rate = float(dicing_rate)
        self.tolerance = float(tolerance)
        self.offscreen_factor = max(1.0, float(offscreen_rate) / float(dicing_rate))
        self.margin_px = float(offscreen_rate)
        self.evaluations = 0
        self.nonfinite = 0

    # ----------------------------------------------------------------- states
    def _displace(self, state: ShadingState) -> np.ndarray:
        """Object-space displaced positions (n, 3) of a state batch."""
        p = state.position
        if self.field is None or len(state) == 0:
            return p.copy()
        d = np.asarray(self.field(state), dtype=np.float64)
        if d.shape == (3,):
            d = np.broadcast_to(d, p.shape)
        if d.shape != p.shape:
            raise ValueError(f"displacement field returned shape {d.shape}, expected "
                             f"{p.shape}: a field maps a state of n points to (n, 3) vectors")
        bad = ~np.all(np.isfinite(d), axis=1)
        if bad.any():
            # as Cycles does: a non-finite offset is replaced by no offset
            d = np.where(bad[:, None], 0.0, d)
            self.nonfinite += int(bad.sum())
            warnings.warn(f"displacement field returned non-finite vectors at {int(bad.sum())} "
                          "points; they were not displaced", DicingWarning, stacklevel=4)
        return p + d

    def to_world(self, p: np.ndarray) -> np.ndarray:
        """World positions of object-space points (n, 3)."""
        if self.identity:
            return p
        return (self.linear @ p.T).T + self.matrix[:3, 3]

    def eval_uv(self, uv: np.ndarray, with_state: bool = False):
        """World-space displaced positions at parametric ``uv`` (n, 2).

        Returns
        -------
        world : (n, 3) float64
        state : ShadingState, only if ``with_state``
        """
        uv = np.asarray(uv, dtype=np.float64).reshape(-1, 2)
        out = np.empty((len(uv), 3))
        states = []
        for s in range(0, len(uv), DICE_TOL.batch):
            st = self.surface.state_at_uv(uv[s:s + DICE_TOL.batch])
            out[s:s + DICE_TOL.batch] = self.to_world(self._displace(st))
            if with_state:
                states.append(st)
        self.evaluations += len(uv)
        if with_state:
            return out, _concat_states(states, len(uv))
        return out

    def eval_bary(self, face: np.ndarray, bary: np.ndarray, with_state: bool = False):
        """World-space displaced positions at ``(face (n,), barycentric (n, 3))``."""
        face = np.asarray(face, dtype=np.int64).reshape(-1)
        bary = np.asarray(bary, dtype=np.float64).reshape(-1, 3)
        out = np.empty((len(face), 3))
        states = []
        for s in range(0, len(face), DICE_TOL.batch):
            st = self.surface.state_at(face[s:s + DICE_TOL.batch], bary[s:s + DICE_TOL.batch])
            out[s:s + DICE_TOL.batch] = self.to_world(self._displace(st))
            if with_state:
                states.append(st)
        self.evaluations += len(face)
        if with_state:
            return out, _concat_states(states, len(face))
        return out

    # ------------------------------------------------------------ screen scale
    def px_scale(self, world: np.ndarray) -> np.ndarray:
        """Effective pixels per world unit at points (n, 3), for length and error tests.

        Inside the frustum (with a margin of ``offscreen_rate`` pixels) this is
        :meth:`Camera.raster_scale`; outside it is divided by
        ``offscreen_rate / dicing_rate``, so both the sampling rate and the tolerance
        there are that much coarser.
        """
        scale, inside = self.camera.dicing_footprint(world.reshape(-1, 3), self.margin_px)
        if self.offscreen_factor > 1.0:
            scale = np.where(inside, scale, scale / self.offscreen_factor)
        return scale


def _concat_states(states: list[ShadingState], n: int) -> ShadingState:
    if len(states) == 1:
        return states[0]
    if not states:
        z3 = np.zeros((0, 3))
        return ShadingState(z3, z3.copy(), np.zeros((0, 2)), z3.copy(), z3.copy())
    return ShadingState(*(np.concatenate([getattr(s, k) for s in states]) for k in
                          ("position", "normal", "uv", "tangent_u", "tangent_v")))
