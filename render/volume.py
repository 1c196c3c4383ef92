"""Homogeneous participating media: transmittance, free-flight sampling, and the medium stack.

MDL's ``material_volume(scattering, absorption_coefficient, scattering_coefficient)``
describes the medium enclosed by a closed, non-thin-walled object
(``reference/mdl-distribution-functions.md`` §1.2, §6; Handbook chapters 4 and 5):
per colour channel ``sigma_a`` and ``sigma_s`` (per meter; a scene unit is a meter,
:data:`METERS_PER_SCENE_UNIT`), ``sigma_t = sigma_a + sigma_s``, transmittance
``T(d) = exp(-sigma_t d)``, and the phase function ``anisotropic_vdf``
(Henyey–Greenstein, :mod:`render.df.anisotropic_vdf`; MDL's default ``vdf()`` is
isotropic).

Free-flight sampling: path-space spectral MIS
---------------------------------------------
The coefficients differ per channel, so one distance cannot be drawn from all three
exponentials.  Each path picks one *hero* channel ``h`` (uniformly, once) and draws
every free-flight distance in every medium with ``sigma_t[h]``.  The estimate in
channel ``i`` is the one-sample MIS (balance heuristic) over the three channels for the
whole path (Wilkie et al. 2014; pbrt-v4's ``VolPathIntegrator``)::

    f_i(path) / (1/3 sum_j p_j(path))

with ``p_j(path)`` the product over the path's medium segments of
``sigma_t[j] T_j(t)`` (a scattering event at ``t``) or ``T_j(t_max)`` (no event before
the surface), and ``f_i`` the product of ``sigma_s[i] T_i(t)`` or ``T_i(t_max)``.
:meth:`HomogeneousMedium.sample_distance` returns both per segment; the integrator
keeps ``beta *= f / p[h]`` and ``r *= p / p[h]`` (``r[h] = 1``) and divides every
contribution by ``mean(r)``.  The weight is bounded for the whole path
(``f_i / mean_j p_j <= 3 f_i / p_i <= 3``), where per-segment channel MIS lets the
non-hero channels' weights multiply into heavy tails in dense chromatic media; a grey
medium has ``r = 1`` and weight ``sigma_s / sigma_t`` exactly.  A medium without
scattering (``sigma_s = 0``) is not sampled at all: the segment is attenuated by
``T(t)`` exactly (Beer–Lambert, ``p = 1``), which is noise-free.  Tracking with the
largest coefficient as a majorant (delta tracking) would need null collisions in the
other channels; it is not used.

The medium stack
----------------
Each path lane keeps a small stack of the closed objects it is inside
(:class:`MediumStack`): entering one pushes it with its IOR, leaving pops it.  The
medium a segment travels through is the top of the stack; the IOR on the outside of
an interface of object ``k`` is the IOR of the topmost entry that is not ``k`` (1 for
air), so objects nested inside volumes (Handbook §5.8) see the right pair.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from render._typing import Arr, Rgb

__all__ = [
    "METERS_PER_SCENE_UNIT",
    "MAX_NESTING",
    "HomogeneousMedium",
    "DistanceSample",
    "MediumStack",
    "medium_of",
    "is_closed",
]

#: MDL's ``state::meters_per_scene_unit()``: scene units are meters.
METERS_PER_SCENE_UNIT = 1.0
#: deepest nesting of closed objects tracked per path (deeper entries are not pushed)
MAX_NESTING = 8


def _coefficient(value, name: str) -> np.ndarray:
    if callable(value):
        raise ValueError(
            f"material_volume.{name} must be a constant color: only homogeneous media are "
            "rendered (a varying coefficient would describe a heterogeneous medium)"
        )
    a = np.asarray(value, dtype=np.float64)
    if a.ndim == 0:
        a = np.full(3, float(a))
    if a.shape != (3,) or not np.all(np.isfinite(a)) or np.any(a < 0.0):
        raise ValueError(
            f"material_volume.{name} must be a color of finite values >= 0 (per meter), "
            f"got {value!r}"
        )
    return a


@dataclass(frozen=True)
class DistanceSample:
    """Result of :meth:`HomogeneousMedium.sample_distance`, one row per lane.

    Parameters
    ----------
    t : (n,) float64
        Distance of the scattering event; ``t_max`` where none happened.
    scattered : (n,) bool
        A scattering event lies before ``t_max``.
    value : (n, 3) float64
        Per channel: ``sigma_s T(t)`` for a scattering event, ``T(t_max)`` otherwise.
    pdf : (n, 3) float64
        Per channel: the density (or probability) with which that channel's sampling
        would have produced this outcome, ``sigma_t T(t)`` or ``T(t_max)``; ones for a
        medium that does not scatter (its segments are not sampled).
    """

    t: Arr
    scattered: np.ndarray
    value: Rgb
    pdf: Rgb

    def weight(self, hero: np.ndarray) -> tuple[Rgb, Rgb]:
        """``(value / pdf[hero], pdf / pdf[hero])``: the throughput factor and the MIS
        ratios of the segment for hero channels ``hero`` (n,); 0 where ``pdf[hero]`` is 0
        (the hero channel could not have produced the outcome)."""
        rows = np.arange(len(self.t))
        ph = self.pdf[rows, hero]
        ok = ph > 0.0
        inv = np.where(ok, 1.0 / np.where(ok, ph, 1.0), 0.0)[:, None]
        return self.value * inv, np.where(ok[:, None], self.pdf * inv, 1.0)


class HomogeneousMedium:
    """A homogeneous medium with per-channel coefficients and a Henyey–Greenstein phase.

    Parameters
    ----------
    absorption_coefficient, scattering_coefficient : float or (3,)
        ``sigma_a``, ``sigma_s`` per meter, >= 0 (stored per scene unit in
        :attr:`sigma_a`, :attr:`sigma_s`, :attr:`sigma_t`).
    directional_bias : float
        The ``anisotropic_vdf``'s ``g`` in [-1, 1].

    Examples
    --------
    >>> m = HomogeneousMedium((1.0, 2.0, 0.0), 0.0)
    >>> np.round(m.transmittance(np.array([0.5])), 6).tolist()
    [[0.606531, 0.367879, 1.0]]
    >>> m.scatters, HomogeneousMedium(0.0, 0.5).scatters
    (False, True)
    """

    def __init__(self, absorption_coefficient=0.0, scattering_coefficient=0.0,
                 directional_bias: float = 0.0):
        from render.df.anisotropic_vdf import AnisotropicVdf

        # MDL gives coefficients per meter; paths are measured in scene units
        self.sigma_a = _coefficient(absorption_coefficient, "absorption_coefficient") * (
            METERS_PER_SCENE_UNIT)
        self.sigma_s = _coefficient(scattering_coefficient, "scattering_coefficient") * (
            METERS_PER_SCENE_UNIT)
        self.sigma_t = self.sigma_a + self.sigma_s
        if np.ndim(directional_bias) != 0 or callable(directional_bias):
            raise ValueError(
                "anisotropic_vdf(directional_bias) must be a constant for a homogeneous "
                f"medium, got {directional_bias!r}"
            )
        self.phase = AnisotropicVdf(float(directional_bias))
        #: whether any channel scatters (else the segment is attenuated, never sampled)
        self.scatters = bool(np.any(self.sigma_s > 0.0))
        #: whether the medium does anything at all
        self.is_vacuum = bool(np.all(self.sigma_t == 0.0))

    @classmethod
    def from_material_volume(cls, volume) -> HomogeneousMedium | None:
        """The medium of a ``material_volume`` (None for a vacuum: all coefficients 0).

        Raises
        ------
        ValueError
            A varying coefficient or bias, or a vdf other than ``anisotropic_vdf``.
        """
        g = 0.0
        vdf = getattr(volume, "scattering", None)
        if vdf is not None:
            if vdf.name != "anisotropic_vdf":
                raise ValueError(
                    f"material_volume.scattering: df::{vdf.name} is not supported; use "
                    "df::anisotropic_vdf"
                )
            g = vdf.kwargs.get("directional_bias", 0.0)
        medium = cls(volume.absorption_coefficient, volume.scattering_coefficient, g)
        return None if medium.is_vacuum else medium

    def __repr__(self) -> str:
        return (
            f"HomogeneousMedium(sigma_a={self.sigma_a.tolist()}, "
            f"sigma_s={self.sigma_s.tolist()}, g={float(self.phase.directional_bias)})"
        )

    def transmittance(self, distance: Arr) -> Rgb:
        """``exp(-sigma_t d)`` per channel, (n, 3); ``d = inf`` gives 0 (or 1 where
        ``sigma_t = 0``)."""
        d = np.asarray(distance, dtype=np.float64)[:, None]
        tau = np.where(self.sigma_t > 0.0, self.sigma_t * np.minimum(d, 1e300), 0.0)
        return np.exp(-tau)

    def sample_distance(self, t_max: Arr, hero: np.ndarray, u: Arr) -> DistanceSample:
        """Sample a free-flight distance with the hero channel's extinction.

        Parameters
        ----------
        t_max : (n,) float64
            Distance to the next surface (``inf`` when the ray leaves the scene).
        hero : (n,) int
            The path's hero channel (0, 1, 2).
        u : (n,) float64
            Uniform variates in [0, 1).

        Returns
        -------
        DistanceSample

        Examples
        --------
        A grey, lossless medium: every scattering event has weight exactly 1.

        >>> m = HomogeneousMedium(0.0, 2.0)
        >>> s = m.sample_distance(np.array([10.0, 0.01]), np.array([0, 2]), np.array([0.5, 0.5]))
        >>> s.scattered.tolist(), np.round(s.t, 6).tolist()
        ([True, False], [0.346574, 0.01])
        >>> w, r = s.weight(np.array([0, 2]))
        >>> np.allclose(w, [[1, 1, 1], [1, 1, 1]]) and np.allclose(r, 1.0)
        True
        """
        t_max = np.asarray(t_max, dtype=np.float64)
        n = len(t_max)
        if not self.scatters:
            return DistanceSample(t_max.copy(), np.zeros(n, dtype=bool),
                                  self.transmittance(t_max), np.ones((n, 3)))
        sig = self.sigma_t[np.asarray(hero, dtype=np.int64)]
        # -log(1 - u) / sigma: u < 1, so the log is finite; sigma 0 never scatters
        t = np.where(sig > 0.0, -np.log1p(-np.asarray(u)) / np.where(sig > 0.0, sig, 1.0),
                     np.inf)
        scattered = t < t_max
        t = np.where(scattered, t, t_max)
        tr = self.transmittance(t)
        value = np.where(scattered[:, None], self.sigma_s * tr, tr)
        pdf = np.where(scattered[:, None], self.sigma_t * tr, tr)
        return DistanceSample(t, scattered, value, pdf)


def medium_of(material) -> HomogeneousMedium | None:
    """The homogeneous medium a material encloses, or None.

    Thin-walled materials enclose nothing (MDL: their ``volume`` is ignored).
    """
    if getattr(material, "thin_walled", False):
        return None
    volume = getattr(material, "volume", None)
    if volume is None:
        return None
    return HomogeneousMedium.from_material_volume(volume)


def is_closed(vertices: np.ndarray, faces: np.ndarray, tolerance: float = 1e-7) -> bool:
    """Whether a triangle mesh encloses a volume: every edge shared by exactly two faces.

    Vertices closer than ``tolerance`` times the mesh's size are welded first (uv seams
    and per-face vertices duplicate positions); faces that collapse to a line or point
    after welding (a sphere's poles) are ignored.

    Parameters
    ----------
    vertices : (v, 3) float64
    faces : (f, 3) int

    Examples
    --------
    >>> import trimesh
    >>> box = trimesh.creation.box()
    >>> is_closed(box.vertices, box.faces), is_closed(box.vertices, box.faces[:-1])
    (True, False)
    """
    v = np.asarray(vertices, dtype=np.float64)
    f = np.asarray(faces, dtype=np.int64)
    if len(f) == 0:
        return False
    size = float(np.ptp(v, axis=0).max()) or 1.0
    # offsets from the mesh's corner, so the keys stay below 1 / tolerance however far
    # the mesh is from the origin (1e12 away, v / size alone overflows int64)
    key = np.round((v - v.min(axis=0)) / (tolerance * size)).astype(np.int64)
    _, weld = np.unique(key, axis=0, return_inverse=True)
    g = weld.ravel()[f]
    good = (g[:, 0] != g[:, 1]) & (g[:, 1] != g[:, 2]) & (g[:, 0] != g[:, 2])
    g = g[good]
    if len(g) == 0:
        return False
    edges = np.sort(np.concatenate([g[:, [0, 1]], g[:, [1, 2]], g[:, [2, 0]]]), axis=1)
    _, counts = np.unique(edges, axis=0, return_counts=True)
    return bool(np.all(counts == 2))


class MediumStack:
    """Per-lane stacks of the closed objects a path is inside, with their IORs.

    Parameters
    ----------
    n : int
        Lanes (all start outside every object: the camera must be in air).
    depth : int
        Entries per lane (:data:`MAX_NESTING`; the integrator uses fewer when the scene
        has fewer closed objects, none at all in a scene without any).

    Attributes
    ----------
    objects : (n, depth) int32
        Object indices, bottom first; -1 in unused slots.
    ior : (n, depth) float64
        The IOR of each entry (the material's ``ior`` averaged over channels, as
        libbsdf does, at the point where the path entered).
    size : (n,) int32
        Entries in use.

    Examples
    --------
    >>> s = MediumStack(2)
    >>> s.push(np.array([True, True]), np.array([4, 4]), np.array([1.33, 1.33]))
    >>> s.push(np.array([True, False]), np.array([7, 7]), np.array([1.5, 1.5]))
    >>> s.top().tolist(), s.outside_ior(np.array([7, 4])).tolist()
    ([7, 4], [1.33, 1.0])
    >>> s.pop(np.array([True, True]), np.array([4, 4]))     # leave the outer one first
    >>> s.top().tolist(), s.size.tolist()
    ([7, -1], [1, 0])
    """

    def __init__(self, n: int, depth: int = MAX_NESTING):
        self.objects = np.full((n, depth), -1, dtype=np.int32)
        self.ior = np.ones((n, depth))
        self.size = np.zeros(n, dtype=np.int32)

    def __len__(self) -> int:
        return len(self.size)

    def take(self, index: np.ndarray) -> MediumStack:
        """The stacks of lanes ``index`` (a copy)."""
        out = MediumStack.__new__(MediumStack)
        out.objects = self.objects[index]
        out.ior = self.ior[index]
        out.size = self.size[index]
        return out

    @staticmethod
    def concatenate(stacks: list) -> MediumStack:
        """The lanes of several stacks, in order (all of the same depth)."""
        out = MediumStack.__new__(MediumStack)
        out.objects = np.concatenate([s.objects for s in stacks])
        out.ior = np.concatenate([s.ior for s in stacks])
        out.size = np.concatenate([s.size for s in stacks])
        return out

    def copy(self) -> MediumStack:
        """An independent copy."""
        return self.take(np.arange(len(self)))

    def top(self) -> np.ndarray:
        """(n,) int: the innermost object of each lane (-1 outside every object)."""
        if self.objects.shape[1] == 0:
            return np.full(len(self), -1, dtype=np.int32)
        rows = np.arange(len(self))
        return np.where(self.size > 0, self.objects[rows, np.maximum(self.size - 1, 0)], -1)

    def outside_ior(self, obj: np.ndarray) -> np.ndarray:
        """(n,): the IOR around object ``obj[i]``: its topmost entry that is not that
        object (1 when there is none)."""
        depth = self.objects.shape[1]
        if depth == 0:
            return np.ones(len(self))
        col = np.arange(depth)[None, :]
        other = (self.objects != np.asarray(obj)[:, None]) & (col < self.size[:, None])
        last = depth - 1 - np.argmax(other[:, ::-1], axis=1)
        found = other.any(axis=1)
        return np.where(found, self.ior[np.arange(len(self)), last], 1.0)

    def push(self, mask: np.ndarray, obj: np.ndarray, ior: np.ndarray) -> None:
        """Enter ``obj`` on lanes ``mask`` (lanes whose stack is full are left as they are)."""
        depth = self.objects.shape[1]
        lanes = np.flatnonzero(np.asarray(mask) & (self.size < depth))
        if len(lanes) == 0:
            return
        slot = self.size[lanes]
        self.objects[lanes, slot] = np.asarray(obj)[lanes]
        self.ior[lanes, slot] = np.broadcast_to(np.asarray(ior, dtype=np.float64),
                                                (len(self),))[lanes]
        self.size[lanes] += 1

    def pop(self, mask: np.ndarray, obj: np.ndarray) -> None:
        """Leave ``obj`` on lanes ``mask``: remove its topmost entry (if any), keeping the
        order of the others."""
        lanes = np.flatnonzero(mask)
        if len(lanes) == 0:
            return
        depth = self.objects.shape[1]
        o = self.objects[lanes]
        col = np.arange(depth)[None, :]
        hit = (o == np.asarray(obj)[lanes, None]) & (col < self.size[lanes, None])
        found = hit.any(axis=1)
        if not found.any():
            return
        lanes, o, hit = lanes[found], o[found], hit[found]
        last = depth - 1 - np.argmax(hit[:, ::-1], axis=1)
        keep = (col < self.size[lanes, None]) & (col != last[:, None])
        order = np.argsort(~keep, axis=1, kind="stable")
        size = self.size[lanes] - 1
        new_o = np.take_along_axis(o, order, axis=1)
        new_i = np.take_along_axis(self.ior[lanes], order, axis=1)
        unused = col >= size[:, None]
        self.objects[lanes] = np.where(unused, -1, new_o)
        self.ior[lanes] = np.where(unused, 1.0, new_i)
        self.size[lanes] = size
