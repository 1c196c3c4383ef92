"""The compiled pw-curve and its vectorized evaluation (Listing 15.5's ``point_along_pwc``).

A :class:`Curve` holds the MDL array of Listing 15.2 as numpy columns, one row per
pw_point.  Evaluation is exact on arcs: the angle, not a polyline, is interpolated.

Within each piece the parameter ``s`` is proportional to arc length (segments are
linear in ``s``; arcs are linear in angle, hence in length), so ``s * length`` *is*
the arc length from the start and the inverse mapping is exact.
"""

from __future__ import annotations

from dataclasses import dataclass, field, replace
from enum import IntEnum
from functools import cached_property
from typing import NamedTuple

import numpy as np

__all__ = ["PwType", "Curve", "point_along_pwc"]


class _Tables(NamedTuple):
    """Per-row evaluation tables of a curve (see ``Curve._tables64``)."""

    t: np.ndarray  # knots, with +inf appended
    lut: np.ndarray
    steps: int
    t0: np.ndarray
    inv_dt: np.ndarray
    ax: np.ndarray
    ay: np.ndarray
    bx: np.ndarray
    by: np.ndarray
    r: np.ndarray
    phi0: np.ndarray
    dphi: np.ndarray

    _floats = ("t", "t0", "inv_dt", "ax", "ay", "bx", "by", "r", "phi0", "dphi")


class PwType(IntEnum):
    """Listing 15.1's ``pw_type``, in enum order (the NPZ ``type`` column uses these ints)."""

    SEGMENT = 0
    ANGLE = 1
    SAGITTA = 2
    CYMA_RECTA = 3
    CYMA_REVERSA = 4
    FLARE = 5

    @property
    def mdl_name(self) -> str:
        return ("segment", "angle", "sagitta", "cyma_recta", "cyma_reversa", "flare")[self]


@dataclass(frozen=True, eq=False)
class Curve:
    """A compiled pwc-list: the ``pw_point`` array of Listing 15.2 as columns.

    Parameters
    ----------
    type : (N,) int8
        :class:`PwType` of the piece that *ends* at each point (the first is a segment).
    t : (N,) float64
        Cumulative arc length at each point over the total, 0 first, 1 last, strictly
        increasing.
    pt, center : (N, 2) float64
        Point, and the centre of the arc ending at it (zero for segments).
    radius, start_angle, end_angle : (N,) float64
        The arc's radius and angles in radians; the arc's point at angle φ is
        ``center + radius * (cos φ, sin φ)``, φ interpolated linearly in the piece.
    length : float
        Total length of the normalized curve (the Handbook's ``NAME_length``).
    scale : float
        The normalization factor applied to the source coordinates.
    line : (N,) int
        1-based source line of each point (a cyma's two points share one line).
    text : tuple of str
        Source line of each point, without its comment.
    precision : {"float64", "float32"}
        The float type :meth:`evaluate` computes in when given float64 positions:
        ``"float32"`` evaluates as MDL's ``float`` would (a renderer's choice, traded
        for speed; :meth:`in_float32`), and returns float64.
    """

    name: str
    type: np.ndarray
    t: np.ndarray
    pt: np.ndarray
    center: np.ndarray
    radius: np.ndarray
    start_angle: np.ndarray
    end_angle: np.ndarray
    length: float
    scale: float = 1.0
    relative: bool = False
    source: str = "<string>"
    line: np.ndarray = field(default=None)  # type: ignore[assignment]
    text: tuple[str, ...] = ()
    precision: str = "float64"

    def __post_init__(self) -> None:
        if self.precision not in ("float64", "float32"):
            raise ValueError(f"precision must be 'float64' or 'float32', got {self.precision!r}")
        n = len(self.t)
        if self.line is None:
            object.__setattr__(self, "line", np.zeros(n, dtype=np.int64))
        if n < 2:
            raise ValueError("a Curve needs at least two points")
        if not np.all(np.diff(self.t) > 0):
            raise ValueError("Curve.t must be strictly increasing")
        for name in ("t", "pt", "center", "radius", "start_angle", "end_angle"):
            a = getattr(self, name)
            a.setflags(write=False)
            if not np.all(np.isfinite(a)):
                raise ValueError(f"Curve.{name} holds a non-finite value")

    def __len__(self) -> int:
        return len(self.t)

    @property
    def n(self) -> int:
        """Number of pw_points (the MDL array size)."""
        return len(self.t)

    @property
    def is_arc(self) -> np.ndarray:
        """(N,) bool: the piece ending at each point is an arc."""
        return self.type != PwType.SEGMENT

    @property
    def is_closed(self) -> bool:
        """True when the last point equals the first (a sweep curve for ``double_pwc``)."""
        return bool(np.allclose(self.pt[0], self.pt[-1], rtol=0, atol=1e-12))

    @cached_property
    def bbox(self) -> np.ndarray:
        """(2, 2) [[xmin, ymin], [xmax, ymax]] of the exact curve, arcs included."""
        arc = np.flatnonzero(self.is_arc)
        lo0, hi0 = np.minimum(self.start_angle[arc], self.end_angle[arc]), \
            np.maximum(self.start_angle[arc], self.end_angle[arc])
        # an arc's extremes are its ends and the multiples of pi/2 inside its sweep
        # (start in (-pi, pi] and |sweep| < 2 pi keep angles within (-3 pi, 3 pi))
        quarter = np.arange(-6, 7) * (np.pi / 2)
        inside = (quarter >= lo0[:, None]) & (quarter <= hi0[:, None])
        k, q = np.nonzero(inside)
        extremes = self.center[arc[k]] + self.radius[arc[k], None] * np.stack(
            [np.cos(quarter[q]), np.sin(quarter[q])], -1)
        pts = np.concatenate([self.pt, extremes])
        return np.stack([pts.min(axis=0), pts.max(axis=0)])

    # -- the piece table: each piece as p(f) = a + b f + r (cos(phi0 + dphi f), sin(...)) --
    @cached_property
    def _tables64(self) -> _Tables:
        """Evaluation tables; rows 1..N-1 are the pieces, indexed by their end point.

        Segments have r = 0 and b = pt[i] - pt[i-1]; arcs have a = centre, b = 0, so one
        branch-free formula evaluates both exactly.  Row 0 is the constant first point
        (``s < 0``) and row N the constant last point (``s >= 1``), as Listing 15.5 returns.
        """
        arc = self.is_arc
        prev = np.roll(self.pt, 1, axis=0)
        a = np.concatenate([np.where(arc[:, None], self.center, prev), self.pt[-1:]])
        b = np.concatenate([np.where(arc[:, None], 0.0, self.pt - prev), [[0.0, 0.0]]])
        a[0], b[0] = self.pt[0], 0.0
        first_last = lambda x: np.append(np.where(arc, x, 0.0), 0.0)  # noqa: E731
        r = first_last(self.radius)
        phi0 = first_last(self.start_angle)
        dphi = first_last(self.end_angle - self.start_angle)
        r[0] = phi0[0] = dphi[0] = 0.0
        t0 = np.append(np.roll(self.t, 1), 1.0)
        inv_dt = np.append(1.0 / np.diff(self.t, prepend=-1.0), 0.0)
        t0[0] = inv_dt[0] = 0.0
        # a uniform lookup table over s replaces the binary search: lut[k] is the piece
        # of s = k / K, and at most `steps` knots lie inside any one bin
        k = min(len(self.t) * 64, 1 << 20)
        lut = np.searchsorted(self.t, np.arange(k) / k, side="right").astype(np.int32)
        ends = np.searchsorted(self.t, np.arange(1, k + 1) / k, side="right")
        steps = int(np.max(ends - lut))
        col = np.ascontiguousarray
        return _Tables(np.append(self.t, np.inf), lut, steps, t0, inv_dt, col(a[:, 0]),
                       col(a[:, 1]), col(b[:, 0]), col(b[:, 1]), r, phi0, dphi)

    @cached_property
    def _tables32(self) -> _Tables:
        """The tables rounded to float32, as an MDL renderer holds them."""
        t = self._tables64
        return t._replace(**{k: getattr(t, k).astype(np.float32) for k in _Tables._floats})

    def _locate(self, s: np.ndarray, tab: _Tables) -> tuple[np.ndarray, np.ndarray]:
        """Table row (the first point whose t exceeds s, as Listing 15.5 searches; N past
        the end, 0 before the start) and the fraction f in [0, 1] along that piece."""
        if not np.all(np.isfinite(s)):
            raise ValueError("curve position s must be finite (got NaN or infinity)")
        if tab.steps > 8:  # knots crowded into few bins: binary search is faster
            i = np.searchsorted(tab.t[:-1], s, side="right")
        else:
            k = len(tab.lut)
            i = np.take(tab.lut, np.clip(s * k, 0, k - 1).astype(np.intp))
            for _ in range(tab.steps):
                i += np.take(tab.t, i) <= s
            i[s < 0] = 0
        f = (s - np.take(tab.t0, i)) * np.take(tab.inv_dt, i)
        return i, np.clip(f, 0.0, 1.0, out=f)

    def evaluate(self, s, repeat: float | None = None) -> np.ndarray:
        """Points on the curve at positions ``s`` in [0, 1] (Listing 15.5).

        Parameters
        ----------
        s : array_like of any shape
            Curve position; ``s < 0`` gives the first point and ``s >= 1`` the last.
            A float32 array is evaluated in float32 throughout (tables included), as
            an MDL renderer would; anything else in float64.
        repeat : float, optional
            Listing 14.27's repetition: the curve is evaluated at ``frac(s * repeat)``
            and, when ``repeat != 1``, shrunk by ``repeat`` and offset along y (the run)
            by ``floor(s * repeat) / repeat``.  As in the Handbook, ``repeat=1`` wraps
            ``s = 1`` to the first point.

        Returns
        -------
        (*s.shape, 2) array of s's float type

        Examples
        --------
        >>> from pwc import compile_text
        >>> c = compile_text("0 0\\n1 0\\n1 1 :angle 90")
        >>> c.evaluate([-1.0, 0.0, 1.0, 2.0]).round(12).tolist()
        [[0.0, 0.0], [0.0, 0.0], [1.0, 1.0], [1.0, 1.0]]
        """
        s = np.asarray(s)
        if self.precision == "float32" and s.dtype != np.float32:
            return self.evaluate(s.astype(np.float32), repeat).astype(np.float64)
        s = s.astype(np.float32 if s.dtype == np.float32 else np.float64, copy=False)
        if repeat is not None:
            return self._evaluate_repeat(s, repeat)
        tab = self._tables32 if s.dtype == np.float32 else self._tables64
        flat = s.ravel()
        i, f = self._locate(flat, tab)
        take = np.take
        phi = take(tab.phi0, i) + take(tab.dphi, i) * f
        r = take(tab.r, i)
        out = np.empty((len(flat), 2), dtype=s.dtype)
        out[:, 0] = take(tab.ax, i) + take(tab.bx, i) * f + r * np.cos(phi)
        out[:, 1] = take(tab.ay, i) + take(tab.by, i) * f + r * np.sin(phi)
        return out.reshape(*s.shape, 2)

    def _evaluate_repeat(self, s: np.ndarray, repeat: float) -> np.ndarray:
        if not (np.isfinite(repeat) and repeat > 0):
            raise ValueError(f"repeat must be a positive finite number, got {repeat}")
        sr = s * repeat
        p = self.evaluate(sr - np.floor(sr))
        if repeat != 1.0:
            p /= repeat
            p[..., 1] += np.floor(sr) / repeat
        return p

    def derivative(self, s) -> np.ndarray:
        """d point / d s at ``s`` (magnitude ``length`` inside pieces; one-sided at knots).

        At a knot the derivative is that of the piece that *starts* there (the piece
        Listing 15.5 selects); before 0 and from 1 on, that of the first and last piece.
        """
        s = np.asarray(s, dtype=np.float64)
        tab = self._tables64
        i, f = self._locate(s.ravel(), tab)
        n = len(self.t)
        f = np.where(i == 0, 0.0, np.where(i == n, 1.0, f))
        i = np.clip(i, 1, n - 1)
        phi = tab.phi0[i] + tab.dphi[i] * f
        k = tab.r[i] * tab.dphi[i] * tab.inv_dt[i]
        d = np.stack([tab.bx[i] * tab.inv_dt[i] - k * np.sin(phi),
                      tab.by[i] * tab.inv_dt[i] + k * np.cos(phi)], -1)
        return d.reshape(*s.shape, 2)

    def tangent(self, s) -> np.ndarray:
        """Unit tangent at ``s`` (direction of increasing s)."""
        d = self.derivative(s)
        return d / np.linalg.norm(d, axis=-1, keepdims=True)

    def arc_length(self, s) -> np.ndarray:
        """Arc length from the start to position ``s`` (exact: ``s`` is arc-length linear)."""
        return np.clip(np.asarray(s, dtype=np.float64), 0.0, 1.0) * self.length

    def position_at_length(self, length) -> np.ndarray:
        """The curve position ``s`` at a given arc length from the start (inverse of
        :meth:`arc_length`)."""
        return np.clip(np.asarray(length, dtype=np.float64) / self.length, 0.0, 1.0)

    def polyline(self, tolerance: float) -> tuple[np.ndarray, np.ndarray]:
        """Sample the curve as a polyline whose chords deviate at most ``tolerance``.

        Every pw_point is included exactly; each arc is split into equal-angle steps
        whose sagitta ``r (1 - cos(step / 2))`` is at most ``tolerance``.

        Returns
        -------
        s : (m,) float64
            Curve positions of the samples (strictly increasing, first 0, last 1).
        points : (m, 2) float64
        """
        if not tolerance > 0:
            raise ValueError(f"tolerance must be positive, got {tolerance}")
        sweep = np.abs(self.end_angle - self.start_angle)
        ratio = np.clip(1.0 - tolerance / np.maximum(self.radius, 1e-300), -1.0, 1.0)
        step = 2.0 * np.arccos(ratio)  # largest angle step within tolerance
        counts = np.where(self.is_arc, np.ceil(sweep / np.maximum(step, 1e-12)), 1)
        counts = np.clip(counts, 1, 1 << 20).astype(np.int64)
        counts[0] = 0
        # s samples: each piece contributes counts[i] samples ending at t[i]
        piece = np.repeat(np.arange(len(self.t)), counts)
        k = np.arange(len(piece)) - np.repeat(np.cumsum(counts) - counts, counts) + 1
        t0 = np.roll(self.t, 1)
        s = t0[piece] + (self.t[piece] - t0[piece]) * k / counts[piece]
        s = np.concatenate([[0.0], s])
        knots = np.concatenate([[0], np.cumsum(counts[1:])])
        s[knots] = self.t
        pts = self.evaluate(s)
        pts[knots] = self.pt  # pw-points exactly, not recomputed from their arcs
        return s, pts

    def in_float32(self) -> Curve:
        """This curve, evaluated in float32 (MDL's ``float``) whatever it is given."""
        return replace(self, precision="float32")

    def as_polyline(self, tolerance: float) -> Curve:
        """The polyline of :meth:`polyline` as a curve of segments (what a renderer without
        arcs would trace), parametrized by its own arc length.

        Examples
        --------
        >>> from pwc import compile_text
        >>> c = compile_text("0 0\\n1 1 :angle 90")
        >>> p = c.as_polyline(1e-3)
        >>> p.n, bool(np.all(p.type == PwType.SEGMENT)), round(p.length / c.length, 4)
        (19, True, 0.9997)
        """
        _, pts = self.polyline(tolerance)
        keep = np.concatenate([[True], np.any(np.diff(pts, axis=0) != 0.0, axis=1)])
        pts = pts[keep]
        lengths = np.linalg.norm(np.diff(pts, axis=0), axis=1)
        cum = np.concatenate([[0.0], np.cumsum(lengths)])
        t = cum / cum[-1]
        t[-1] = 1.0
        zeros = np.zeros(len(pts))
        return Curve(name=self.name, type=np.zeros(len(pts), dtype=np.int8), t=t, pt=pts,
                     center=np.zeros((len(pts), 2)), radius=zeros, start_angle=zeros.copy(),
                     end_angle=zeros.copy(), length=float(cum[-1]), scale=self.scale,
                     relative=self.relative, source=self.source, precision=self.precision)


def point_along_pwc(curve_position, pwc: Curve, repeat: float | None = None) -> np.ndarray:
    """The Handbook's name for :meth:`Curve.evaluate` (Listing 15.5)."""
    return pwc.evaluate(curve_position, repeat)
