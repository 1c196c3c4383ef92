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
:func:`free_flight` (and :meth:`HomogeneousMedium.sample_distance` over arrays) returns
both per segment; the integrator
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
Each path lane keeps a small stack of the closed objects it is inside (rows of two
arrays, object ids and IORs, with a size; :func:`stack_push`, :func:`stack_pop`,
:func:`stack_outside_ior`): entering one pushes it with its IOR, leaving pops it.  The
medium a segment travels through is the top of the stack; the IOR on the outside of
an interface of object ``k`` is the IOR of the topmost entry that is not ``k`` (1 for
air), so objects nested inside volumes (Handbook §5.8) see the right pair.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from render._typing import Arr, Rgb
from render.jit import njit

__all__ = [
    "METERS_PER_SCENE_UNIT",
    "MAX_NESTING",
    "HomogeneousMedium",
    "DistanceSample",
    "transmittance",
    "free_flight",
    "emitted",
    "stack_push",
    "stack_pop",
    "stack_outside_ior",
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
    """A homogeneous medium with per-channel coefficients, a phase function (any vdf
    program) and emission.

    Parameters
    ----------
    absorption_coefficient, scattering_coefficient : float or (3,)
        ``sigma_a``, ``sigma_s`` per meter, >= 0 (stored per scene unit in
        :attr:`sigma_a`, :attr:`sigma_s`, :attr:`sigma_t`).
    directional_bias : float
        The ``anisotropic_vdf``'s ``g`` in [-1, 1] (when ``phase`` is not given).
    phase : bound vdf, optional
        The phase function: a :mod:`render.df` vdf (``anisotropic_vdf``, ``fog_vdf``,
        their mixes and ``tint``) of one parameter row; its program runs in the path
        kernel.
    emission_intensity : float or (3,)
        MDL 1.7's ``material_volume.emission_intensity``: radiance added per unit
        distance, W / (m^3 sr), >= 0 (stored per scene unit in :attr:`emission`).

    Examples
    --------
    >>> m = HomogeneousMedium((1.0, 2.0, 0.0), 0.0)
    >>> np.round(m.transmittance(np.array([0.5])), 6).tolist()
    [[0.606531, 0.367879, 1.0]]
    >>> m.scatters, HomogeneousMedium(0.0, 0.5).scatters
    (False, True)
    """

    def __init__(self, absorption_coefficient=0.0, scattering_coefficient=0.0,
                 directional_bias: float = 0.0, phase=None, emission_intensity=0.0):
        from render.df.anisotropic_vdf import AnisotropicVdf

        # MDL gives coefficients per meter; paths are measured in scene units
        self.sigma_a = _coefficient(absorption_coefficient, "absorption_coefficient") * (
            METERS_PER_SCENE_UNIT)
        self.sigma_s = _coefficient(scattering_coefficient, "scattering_coefficient") * (
            METERS_PER_SCENE_UNIT)
        self.sigma_t = self.sigma_a + self.sigma_s
        #: radiance added per scene unit of path (W / (m^3 sr) times meters per unit)
        self.emission = _coefficient(emission_intensity, "emission_intensity") * (
            METERS_PER_SCENE_UNIT)
        if phase is None:
            if np.ndim(directional_bias) != 0 or callable(directional_bias):
                raise ValueError(
                    "anisotropic_vdf(directional_bias) must be a constant for a homogeneous "
                    f"medium, got {directional_bias!r}"
                )
            phase = AnisotropicVdf(float(directional_bias))
        program = getattr(phase, "program", None)
        if program is None or program.kind != "vdf" or program.rows != 1:
            raise ValueError("the phase function of a homogeneous medium must be a bound vdf "
                             f"of one parameter row (render.df), got {phase!r}")
        self.phase = phase
        #: whether any channel scatters (else the segment is attenuated, never sampled)
        self.scatters = bool(np.any(self.sigma_s > 0.0))
        #: whether the medium does anything at all
        self.is_vacuum = bool(np.all(self.sigma_t == 0.0) and np.all(self.emission == 0.0))

    @classmethod
    def from_material_volume(cls, volume) -> HomogeneousMedium | None:
        """The medium of a ``material_volume`` (None for a vacuum: all coefficients 0).

        Raises
        ------
        ValueError
            A varying coefficient, emission or vdf argument (a heterogeneous medium).
        """
        vdf = getattr(volume, "scattering", None)
        phase = None
        if vdf is not None:
            phase = _bind_vdf(vdf)
        medium = cls(volume.absorption_coefficient, volume.scattering_coefficient,
                     phase=phase, emission_intensity=getattr(volume, "emission_intensity", 0.0))
        return None if medium.is_vacuum else medium

    def __repr__(self) -> str:
        return (
            f"HomogeneousMedium(sigma_a={self.sigma_a.tolist()}, "
            f"sigma_s={self.sigma_s.tolist()}, phase={type(self.phase).__name__}, "
            f"emission={self.emission.tolist()})"
        )

    @property
    def row(self) -> np.ndarray:
        """(12,) ``sigma_a``, ``sigma_s``, ``sigma_t``, emission: the kernels' row of
        this medium."""
        return np.concatenate([self.sigma_a, self.sigma_s, self.sigma_t, self.emission])

    def transmittance(self, distance: Arr) -> Rgb:
        """``exp(-sigma_t d)`` per channel, (n, 3); ``d = inf`` gives 0 (or 1 where
        ``sigma_t = 0``)."""
        d = np.asarray(distance, dtype=np.float64)
        return _transmittance_batch(self.row[None], d)

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
        hero = np.broadcast_to(np.asarray(hero, dtype=np.int64), t_max.shape)
        u = np.broadcast_to(np.asarray(u, dtype=np.float64), t_max.shape)
        return DistanceSample(*_free_flight_batch(self.row[None], t_max, hero, u))


# ------------------------------------------------------------------------ kernels
@njit
def transmittance(medium, m, c, length):
    """``exp(-sigma_t length)`` in channel ``c`` of row ``m`` of a medium table
    (``sigma_a, sigma_s, sigma_t`` per row; see :attr:`HomogeneousMedium.row`): 1 where
    ``sigma_t`` is 0, also for an infinite length."""
    st = medium[m, 6 + c]
    return math.exp(-st * min(length, 1e300)) if st > 0.0 else 1.0


@njit
def free_flight(medium, m, hero, u, t_max):
    """A free-flight distance in medium ``m`` drawn with the hero channel's extinction.

    Returns ``(scattered, t, value rgb, pdf rgb)`` as :class:`DistanceSample` has them;
    a medium that does not scatter is not sampled (``t = t_max``, ``value = T(t_max)``,
    ``pdf = 1``)."""
    if not (medium[m, 3] > 0.0 or medium[m, 4] > 0.0 or medium[m, 5] > 0.0):
        return (False, t_max, transmittance(medium, m, 0, t_max),
                transmittance(medium, m, 1, t_max), transmittance(medium, m, 2, t_max),
                1.0, 1.0, 1.0)
    sig = medium[m, 6 + hero]
    # -log(1 - u) / sigma: u < 1, so the log is finite; sigma 0 never scatters
    t = -math.log1p(-u) / sig if sig > 0.0 else np.inf
    scattered = t < t_max
    if not scattered:
        t = t_max
    tr0 = transmittance(medium, m, 0, t)
    tr1 = transmittance(medium, m, 1, t)
    tr2 = transmittance(medium, m, 2, t)
    if scattered:
        return (True, t, medium[m, 3] * tr0, medium[m, 4] * tr1, medium[m, 5] * tr2,
                medium[m, 6] * tr0, medium[m, 7] * tr1, medium[m, 8] * tr2)
    return False, t, tr0, tr1, tr2, tr0, tr1, tr2


@njit(allocates=True)
def _transmittance_batch(medium, d):
    out = np.empty((len(d), 3))
    for i in range(len(d)):
        for c in range(3):
            out[i, c] = transmittance(medium, 0, c, d[i])
    return out


@njit(allocates=True)
def _free_flight_batch(medium, t_max, hero, u):
    n = len(t_max)
    t, scattered = np.empty(n), np.empty(n, dtype=np.bool_)
    value, pdf = np.empty((n, 3)), np.empty((n, 3))
    for i in range(n):
        (scattered[i], t[i], value[i, 0], value[i, 1], value[i, 2], pdf[i, 0], pdf[i, 1],
         pdf[i, 2]) = free_flight(medium, 0, hero[i], u[i], t_max[i])
    return t, scattered, value, pdf


@njit(inline="always")
def emitted(medium, m, c, length):
    """The radiance medium ``m`` emits along a segment of ``length``, seen from its
    start, in channel ``c``: ``e (1 - exp(-sigma_t length)) / sigma_t`` (``e length``
    without extinction; 0 for an infinite segment without extinction)."""
    e = medium[m, 9 + c]
    if e == 0.0:
        return 0.0
    st = medium[m, 6 + c]
    if st > 0.0:
        return e * -math.expm1(-st * min(length, 1e300)) / st
    return e * length if length < np.inf else 0.0


def _bind_vdf(vdf):
    """A ``material_volume.scattering`` node bound to its program (constant arguments
    only: a homogeneous medium)."""
    from displacement.state import ShadingState

    for node in _nodes(vdf):
        for key, value in node.kwargs.items():
            if callable(value):
                raise ValueError(
                    f"material_volume.scattering: df::{node.name}({key}) must be a constant: "
                    "only homogeneous media are rendered (a varying phase function would "
                    "describe a heterogeneous medium)")
    z = np.array([[0.0, 0.0, 1.0]])
    state = ShadingState(np.zeros((1, 3)), z, np.zeros((1, 2)), np.array([[1.0, 0.0, 0.0]]),
                         np.array([[0.0, 1.0, 0.0]]))
    return vdf.bind(state)


def _nodes(node):
    stack = [node]
    while stack:
        n = stack.pop()
        yield n
        for value in n.kwargs.values():
            for v in value if isinstance(value, list | tuple) else (value,):
                if hasattr(v, "kwargs"):
                    stack.append(v)


@njit
def stack_push(so, sior, i, n, obj, ior):
    """Enter ``obj`` (with its IOR) on stack row ``i`` of size ``n``; returns the new
    size (a full stack stays as it is)."""
    if n < so.shape[1]:
        so[i, n] = obj
        sior[i, n] = ior
        return n + 1
    return n


@njit
def stack_pop(so, sior, i, n, obj):
    """Leave ``obj``: remove its topmost entry from row ``i``, keeping the others'
    order; returns the new size (unchanged if the row does not hold ``obj``)."""
    for s in range(n - 1, -1, -1):
        if so[i, s] == obj:
            for q in range(s, n - 1):
                so[i, q] = so[i, q + 1]
                sior[i, q] = sior[i, q + 1]
            so[i, n - 1] = -1
            sior[i, n - 1] = 1.0
            return n - 1
    return n


@njit
def stack_outside_ior(so, sior, i, n, obj):
    """The IOR around ``obj`` for row ``i``: its topmost entry that is not ``obj`` (1:
    air)."""
    for s in range(n - 1, -1, -1):
        if so[i, s] != obj:
            return sior[i, s]
    return 1.0


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
