"""One-dimensional line selection: which u (or v) values a tensor-product dicing keeps.

Two steps, both vectorized over all lines and samples at once:

1. :func:`dense_candidates` samples a parameter range finely enough that consecutive
   samples are at most ``dicing_rate`` pixels apart on screen (measured on a coarse pilot
   grid), always including the fixed values (domain ends and the field's knots).
2. :func:`select_lines` keeps a subset of those candidates, top-down as Douglas and
   Peucker simplify a polyline: a span between kept candidates is split at its worst
   candidate while linear interpolation across it misses any candidate, on any sampled
   cross line, by more than the tolerance (in pixels).
"""

from __future__ import annotations

import numpy as np

__all__ = ["dense_candidates", "select_lines", "segment_lengths_px"]


def segment_lengths_px(world: np.ndarray, scale: np.ndarray) -> np.ndarray:
    """Largest on-screen length of each interval between consecutive lines.

    Parameters
    ----------
    world : (m, k, 3) float64
        Positions on m lines (first axis) at k cross samples.
    scale : (m, k) float64
        Pixels per world unit at those points.

    Returns
    -------
    (m - 1,) float64
        For each interval, the maximum over the cross samples of
        ``|world[i+1] - world[i]| * max(scale[i], scale[i+1])``.

    Examples
    --------
    >>> w = np.zeros((3, 1, 3)); w[:, 0, 0] = [0.0, 1.0, 3.0]
    >>> segment_lengths_px(w, np.full((3, 1), 2.0)).tolist()
    [2.0, 4.0]
    """
    d = np.linalg.norm(np.diff(world, axis=0), axis=2)
    s = np.maximum(scale[1:], scale[:-1])
    return (d * s).max(axis=1) if d.shape[1] else np.zeros(len(d))


def dense_candidates(pilot: np.ndarray, lengths_px: np.ndarray, rate: float,
                     fixed: np.ndarray, max_count: int) -> tuple[np.ndarray, np.ndarray]:
    """Sample each pilot interval so that consecutive samples are ``rate`` pixels apart.

    Parameters
    ----------
    pilot : (p,) float64
        Sorted pilot parameter values (include every fixed value).
    lengths_px : (p - 1,) float64
        On-screen length of each pilot interval.
    rate : float
        Target spacing in pixels.
    fixed : (f,) float64
        Values that must be kept exactly (a subset of ``pilot``).
    max_count : int
        Upper bound on the number of candidates (the counts are scaled down to fit).

    Returns
    -------
    values : (m,) float64
        Sorted candidates; the pilot values are among them, bit-exact.
    is_fixed : (m,) bool

    Examples
    --------
    >>> v, f = dense_candidates(np.array([0.0, 0.5, 1.0]), np.array([2.0, 0.1]), 1.0,
    ...                         np.array([0.0, 1.0]), 100)
    >>> v.tolist(), f.tolist()
    ([0.0, 0.25, 0.5, 1.0], [True, False, False, True])
    """
    n = np.maximum(np.ceil(np.nan_to_num(lengths_px / rate, nan=1.0, posinf=1e9)), 1.0)
    total = n.sum() + 1
    if total > max_count:
        n = np.maximum(np.floor(n * (max_count - len(pilot)) / total), 1.0)
    n = n.astype(np.int64)
    seg = np.repeat(np.arange(len(n)), n)
    k = np.arange(n.sum()) - np.repeat(np.cumsum(n) - n, n)
    a, b = pilot[:-1][seg], pilot[1:][seg]
    values = a + (b - a) * (k / n[seg])
    values[k == 0] = a[k == 0]          # pilot values exactly
    values = np.concatenate([values, pilot[-1:]])
    is_fixed = np.isin(values, fixed)
    return values, is_fixed


def select_lines(values: np.ndarray, is_fixed: np.ndarray, world: np.ndarray,
                 scale: np.ndarray, tolerance: float) -> tuple[np.ndarray, float, bool]:
    """Keep the fewest candidate lines (top-down) so interpolation stays within tolerance.

    Parameters
    ----------
    values : (m,) float64
        Sorted candidate parameter values (a line each).
    is_fixed : (m,) bool
        Candidates always kept (at least the first and the last).
    world : (m, k, 3) float64
        True displaced world positions on each candidate line at k cross samples.
    scale : (m, k) float64
        Pixels per world unit at those points.
    tolerance : float
        Pixels.

    Returns
    -------
    keep : (m,) bool
    max_error : float
        Largest remaining interpolation error (pixels) over all candidates.
    split : bool
        Whether any span had to be split (False: the fixed lines alone suffice).

    Examples
    --------
    A parabola sampled at 9 lines, one cross sample: its vertex is kept.

    >>> v = np.linspace(0.0, 1.0, 9)
    >>> w = np.zeros((9, 1, 3)); w[:, 0, 0] = v; w[:, 0, 1] = (v - 0.5) ** 2
    >>> fixed = np.zeros(9, bool); fixed[[0, -1]] = True
    >>> keep, err, split = select_lines(v, fixed, w, np.full((9, 1), 100.0), 5.0)
    >>> v[keep].tolist(), split
    ([0.0, 0.25, 0.5, 0.75, 1.0], True)
    """
    keep = is_fixed.copy()
    keep[0] = keep[-1] = True
    kept = np.flatnonzero(keep)
    a, b = kept[:-1], kept[1:]
    max_error, split = 0.0, False
    while len(a):
        length = b - a - 1
        act = length > 0
        a, b, length = a[act], b[act], length[act]
        if not len(a):
            break
        seg = np.repeat(np.arange(len(a)), length)
        start = np.cumsum(length) - length
        idx = a[seg] + 1 + (np.arange(length.sum()) - start[seg])
        t = (values[idx] - values[a[seg]]) / (values[b[seg]] - values[a[seg]])
        wa, wb = world[a[seg]], world[b[seg]]
        lerp = wa + t[:, None, None] * (wb - wa)
        diff = lerp - world[idx]
        err = (np.sqrt(np.einsum("ijk,ijk->ij", diff, diff)) * scale[idx]).max(axis=1)
        emax = np.maximum.reduceat(err, start)
        fail = emax > tolerance
        if (~fail).any():
            max_error = max(max_error, float(emax[~fail].max()))
        if not fail.any():
            break
        split = True
        # the first worst candidate of each failing span
        worst = np.flatnonzero((err == emax[seg]) & fail[seg])
        seg_of, first = np.unique(seg[worst], return_index=True)
        s = idx[worst[first]]
        keep[s] = True
        a = np.concatenate([a[seg_of], s])
        b = np.concatenate([s, b[seg_of]])
    return keep, max_error, split
