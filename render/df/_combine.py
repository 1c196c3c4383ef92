"""Machinery shared by the layers, mixes and modifiers: child checks, selection, frames, QMC albedo.

Every combiner in :mod:`render.df` is a :class:`~render.bsdf.Bsdf` built from child
Bsdfs and evaluates them over the **same lanes** (children hold per-lane parameters,
so a combiner never subsets lanes: it evaluates every child on every lane and selects
per lane with masks).

Selection probabilities (which child :meth:`~render.bsdf.Bsdf.sample` draws from) are a
*defensive mixture*: ``p_i = (1 - DEFENSIVE) e_i / sum(e) + DEFENSIVE / k``, where
``e_i`` is the luminance of the child's expected contribution at ``wo`` (its factor
times a cheap estimate of its albedo) and ``k`` the number of children that can
contribute on that lane.  The floor keeps the pdf positive wherever a child
contributes, even where the estimate is poor (a custom curve that is 0 at normal
incidence but not at the tilted half vectors of a rough layer), which libbsdf's
``P = weight * curve(n.k1)`` does not (it never samples such a layer).  Children that
cannot contribute on a lane (no df, zero weight) get probability exactly 0.

Sampling a nest of combiners in two passes.  A combiner's sample is the mixture pdf
and ``eval / pdf`` of the **whole node** at the drawn direction, so the chosen child's
own pdf and weight are discarded (only its validity, and its weight for delta
events, are kept).  Had every level evaluated its subtree at the drawn direction, a
nest of depth ``d`` would cost ``O(d^2)`` subtree evaluations.  Instead a combiner's
``_draw`` only descends (choices, rescaled ``u1``, the leaf's direction) and returns a
:class:`Draw`; its ``_settle`` then evaluates its subtree once at that direction,
settling the children's draws on the way (each child's validity, pdf and weight come
out of the same evaluation its parent sums), so :func:`sample_by_draw` costs one
evaluation of the tree.  The numbers are the ones each level's own evaluation would
give, because every level sees the same direction (frames that are not the identity
excepted: see :meth:`render.df._layer.LayerBsdf._draw`).
"""

from __future__ import annotations

from dataclasses import dataclass
from functools import lru_cache

import numpy as np

from render._typing import Arr, Arr2, ArrayLike, Rgb, Vec3
from render.bsdf import Bsdf, BsdfSample, check_dirs, check_samples, lane_vector
from render.frame import Frame
from render.numerics import ONE_MINUS_EPS, TOL, luminance, unitize

__all__ = [
    "DEFENSIVE",
    "ALBEDO_POINTS",
    "check_child",
    "union_lobes",
    "selection",
    "pick",
    "cheap_albedo",
    "albedo_estimate",
    "albedo_points",
    "albedo_correction",
    "is_mirror",
    "LayerFrame",
    "Memo",
    "any_positive",
    "lum",
    "child_eval_pdf",
    "child_sample",
    "Draw",
    "child_draw",
    "child_settle",
    "drawn",
    "sample_by_draw",
]

#: share of the selection probability spread uniformly over the children that can
#: contribute (a floor against poor estimates, see the module docstring).
DEFENSIVE = 0.05
#: quadrature points with which a combiner whose factors vary with ``wi`` integrates the
#: deviation of its albedo from ``factor(wo) * child.albedo(wo)`` through each child's own
#: sampler (a Fibonacci number: the ``u2`` points form a Fibonacci lattice).  Measured
#: accuracy (``tests/render/df``): about 5e-3 where the factors are smooth, 2e-2 where they
#: jump (total internal reflection inside a Fresnel coat, the horizon of a tilted layer
#: normal); the cost is ``2 * ALBEDO_POINTS`` child samples per lane.
ALBEDO_POINTS = 89


def check_child(child, name: str, kind: type = Bsdf):
    """``child`` if it is a ``kind`` (Bsdf or Edf) or None (MDL's ``bsdf()``), else ValueError."""
    if child is None or isinstance(child, kind):
        return child
    article = "an" if kind.__name__[0] in "AEIOU" else "a"
    raise ValueError(
        f"{name} must be {article} {kind.__name__} (a bound render.df distribution function) "
        f"or None for MDL's black {'bsdf' if kind is Bsdf else 'edf'}(), got {type(child).__name__}"
    )


def union_lobes(*children):
    """Union of the lobe flags of the children that are not None."""
    from render.bsdf import Lobe

    out = Lobe.NONE
    for c in children:
        if c is not None:
            out |= c.lobes
    return out


def selection(estimates: np.ndarray, possible: np.ndarray) -> np.ndarray:
    """Per-lane selection probabilities of ``k`` children (a defensive mixture).

    Parameters
    ----------
    estimates : (n, k) float64
        Non-negative expected contribution of each child (luminance).
    possible : (n, k) bool
        Which children can contribute on each lane; the others get probability 0.

    Returns
    -------
    (n, k) float64
        Rows sum to 1 where any child is possible, else 0.

    Examples
    --------
    >>> selection(np.array([[3.0, 1.0], [1.0, 0.0], [0.0, 0.0]]),
    ...           np.array([[True, True], [True, False], [False, False]])).round(4).tolist()
    [[0.7375, 0.2625], [1.0, 0.0], [0.0, 0.0]]
    """
    e = np.where(possible, np.maximum(estimates, 0.0), 0.0)
    count = possible.sum(axis=1, keepdims=True)
    total = e.sum(axis=1, keepdims=True)
    share = np.where(possible, 1.0, 0.0) / np.maximum(count, 1)
    prop = np.where(total > 0, e / np.where(total > 0, total, 1.0), share)
    p = (1.0 - DEFENSIVE) * prop + DEFENSIVE * share
    return np.where(possible, p, 0.0)


def pick(u1: Arr, probs: np.ndarray) -> tuple[np.ndarray, Arr, Arr]:
    """Choose a child per lane from ``u1`` and rescale ``u1`` for reuse.

    Parameters
    ----------
    u1 : (n,) float64 in [0, 1)
    probs : (n, k) float64
        Rows summing to 1 (or all 0: the lane picks nothing).

    Returns
    -------
    index : (n,) int
        The chosen child, ``-1`` where every probability is 0.
    u1 : (n,) float64
        ``(u1 - cdf_before) / p_chosen`` in [0, 1).
    p : (n,) float64
        Probability of the chosen child (0 where none).

    Examples
    --------
    >>> i, u, p = pick(np.array([0.1, 0.7, 0.5]), np.array([[0.4, 0.6], [0.4, 0.6], [0.0, 0.0]]))
    >>> i.tolist(), np.round(u, 6).tolist(), p.tolist()
    ([0, 1, -1], [0.25, 0.5, 0.0], [0.4, 0.6, 0.0])
    """
    n, k = probs.shape
    cdf = np.cumsum(probs, axis=1)
    any_p = cdf[:, -1] > 0
    # the first child whose cdf exceeds u1 (the last possible one if rounding leaves u1 above)
    idx = np.sum(cdf <= u1[:, None], axis=1)
    last = k - 1 - np.argmax(probs[:, ::-1] > 0, axis=1)
    idx = np.minimum(idx, last)
    # never land on a zero-probability child (cdf plateaus)
    rows = np.arange(n)
    p = probs[rows, idx]
    before = cdf[rows, idx] - p
    u = np.where(p > 0, (u1 - before) / np.where(p > 0, p, 1.0), 0.0)
    u = np.clip(u, 0.0, ONE_MINUS_EPS)
    return np.where(any_p, idx, -1), np.where(any_p, u, 0.0), np.where(any_p, p, 0.0)


class Memo:
    """The last value a per-``wo`` computation gave, reused while ``wo`` is unchanged.

    A combiner's selection probabilities and albedo estimate depend on ``wo`` only, and
    nested combiners ask for them several times per call with the same directions
    (``sample`` then ``eval_pdf`` at the sampled ``wi``, parents estimating their
    children).  The key is a copy of ``wo`` compared by value (``np.array_equal``), so an
    array changed in place is never mistaken for the old one; key and value are stored
    as one tuple, so a reader never pairs a new key with an old value.
    """

    __slots__ = ("_entry",)

    def __init__(self):
        self._entry = None

    def get(self, wo: np.ndarray, compute):
        entry = self._entry
        if entry is not None and entry[0].shape == wo.shape and np.array_equal(entry[0], wo):
            return entry[1]
        value = compute()
        self._entry = (wo.copy(), value)
        return value


def cheap_albedo(child, wo: Vec3) -> Rgb:
    """A fast albedo estimate of ``child`` at ``wo`` for selection probabilities.

    Combiners provide ``_cheap_albedo`` (exact for mixes and weighted layers, an
    estimate for directional layers); elemental dfs their ``albedo``.  None -> 0.
    """
    if child is None:
        return np.zeros((len(wo), 3))
    f = getattr(child, "_cheap_albedo", None)
    return f(wo) if f is not None else child.albedo(wo)


def albedo_estimate(bsdf, wo: ArrayLike) -> Rgb:
    """A fast directional-albedo estimate of any Bsdf (None: 0), e.g. for an albedo AOV.

    Exact for the elemental dfs (their ``albedo``), mixes, weighted layers and ``tint``;
    the directional layers and ``directional_factor`` use their factors at ``wo`` times
    their children's estimates (no quadrature), so it costs one ``albedo`` per leaf
    instead of :data:`ALBEDO_POINTS` child samples per combiner.

    Parameters
    ----------
    bsdf : Bsdf or None
    wo : (n, 3) float64

    Returns
    -------
    (n, 3) float64

    Examples
    --------
    >>> from render.df import fresnel_layer, specular_bsdf, diffuse_reflection_bsdf
    >>> coat = fresnel_layer(1.5, layer=specular_bsdf(), base=diffuse_reflection_bsdf(tint=0.5))
    >>> albedo_estimate(coat, np.array([[0.0, 0.0, 1.0]])).round(6).tolist()   # 0.04 + 0.96 / 2
    [[0.52, 0.52, 0.52]]
    """
    wo = np.asarray(wo, dtype=np.float64)
    return np.clip(cheap_albedo(bsdf, wo), 0.0, None)


@lru_cache(maxsize=8)
def albedo_points(m: int = ALBEDO_POINTS) -> np.ndarray:
    """``m`` quadrature points in [0, 1)^3: columns ``u1, u2x, u2y``, shape (m', 3).

    ``u2`` is the Fibonacci lattice ``((i + 1/2)/m', frac((i g + 1/2)/m'))`` with ``m'``
    the first Fibonacci number ``>= m`` and ``g`` its predecessor (the best 2-D rank-1
    lattice); ``u1 = frac(1/2 + i (sqrt 2 - 1))``.

    Examples
    --------
    >>> p = albedo_points(8)
    >>> p.shape, bool(np.all((p >= 0) & (p < 1)))
    ((8, 3), True)
    """
    fib = [1, 2]
    while fib[-1] < m:
        fib.append(fib[-1] + fib[-2])
    m, g = fib[-1], fib[-2]
    i = np.arange(m)
    u2x = (i + 0.5) / m
    u2y = np.mod((i * g + 0.5) / m, 1.0)
    u1 = np.mod(0.5 + i * (np.sqrt(2.0) - 1.0), 1.0)
    pts = np.stack([u1, u2x, u2y], axis=1)
    pts.setflags(write=False)
    return pts


def is_mirror(child) -> bool:
    """True if ``child`` only mirrors about the inherited normal (``specular_bsdf`` reflect)."""
    from render.df._common import ScatterMode
    from render.df.specular_bsdf import SpecularBsdf

    return isinstance(child, SpecularBsdf) and child.mode is ScatterMode.scatter_reflect


def albedo_correction(child, wo: Vec3, factor, estimate: Rgb) -> Rgb:
    """``∫ (factor(wi) - estimate) child.eval(wo, wi) dwi`` through the child's sampler.

    The combiners' albedo is ``estimate * child.albedo(wo)`` plus this correction (a
    control variate: only the deviation of the factor from its value at ``wo`` is
    integrated numerically, over :func:`albedo_points`).

    Parameters
    ----------
    child : Bsdf
    wo : (n, 3) float64
        Viewing directions in the child's frame.
    factor : callable
        ``wi (n, 3) in the child's frame -> (n, 3)``: the combiner's factor at ``wi``
        (0 where the combiner drops the direction).
    estimate : (n, 3) float64
    """
    n = len(wo)
    acc = np.zeros((n, 3))
    pts = albedo_points(ALBEDO_POINTS)
    for u in pts:
        s = child.sample(wo, np.full(n, u[0]), np.broadcast_to(u[1:], (n, 2)))
        wi = np.where(s.valid[:, None], s.wi, np.array([0.0, 0.0, 1.0]))
        acc += np.where(s.valid[:, None], (factor(wi) - estimate) * s.weight, 0.0)
    return acc / len(pts)


class LayerFrame:
    """The frame of a layer's own ``normal``, expressed in the inherited local frame.

    Parameters
    ----------
    normal : (3,) or (n, 3)
        The layer's normal in the inherited local frame (``+z`` = inherited normal);
        normalised here.
    tangent_u : (3,) or (n, 3)
        ``state::texture_tangent_u(0)`` in the inherited local frame: the layer frame's
        ``x`` axis is its projection (so anisotropic children keep their orientation).

    Raises
    ------
    ValueError
        A zero or non-finite normal.

    Examples
    --------
    >>> f = LayerFrame((0.0, 0.0, 2.0), (1.0, 0.0, 0.0))
    >>> f.identity
    True
    >>> g = LayerFrame((0.6, 0.0, 0.8), (1.0, 0.0, 0.0))
    >>> np.round(g.to_layer(np.array([[0.6, 0.0, 0.8]])), 12).tolist()
    [[0.0, 0.0, 1.0]]
    """

    def __init__(self, normal: ArrayLike = (0.0, 0.0, 1.0), tangent_u: ArrayLike = (1.0, 0.0, 0.0)):
        nrm = lane_vector(normal, "normal")
        nrm, ok = unitize(nrm)
        if not np.all(ok):
            raise ValueError("normal must be a non-zero vector (the layer's surface normal)")
        tu = lane_vector(tangent_u, "tangent_u")
        m = max(len(nrm), len(tu))
        if len(nrm) not in (1, m) or len(tu) not in (1, m):
            raise ValueError(
                f"normal has {len(nrm)} rows and tangent_u {len(tu)}: give one per lane or one"
            )
        nrm = np.broadcast_to(nrm, (m, 3))
        tu = np.broadcast_to(tu, (m, 3))
        self.frame = Frame.from_normal_tangent(nrm, tu)
        eye = np.eye(3)
        self.identity = bool(
            np.all(np.abs(self.frame.s - eye[0]) <= 1e-12)
            and np.all(np.abs(self.frame.t - eye[1]) <= 1e-12)
            and np.all(np.abs(self.frame.n - eye[2]) <= 1e-12)
        )
        self.lanes = m

    def _check(self, n: int) -> None:
        if self.lanes not in (1, n):
            raise ValueError(f"normal has {self.lanes} per-lane values but the call has {n} lanes")

    def to_layer(self, w: Vec3) -> Vec3:
        """Directions (n, 3) of the inherited frame in the layer frame."""
        if self.identity:
            return w
        self._check(len(w))
        return self.frame.to_local(w)

    def to_inherited(self, w: Vec3) -> Vec3:
        """Directions (n, 3) of the layer frame in the inherited frame."""
        if self.identity:
            return w
        self._check(len(w))
        return self.frame.to_world(w)

    def agree(self, w: Vec3, w_layer: Vec3) -> np.ndarray:
        """(n,) bool: ``w`` lies strictly on the same side of both tangent planes."""
        if self.identity:
            return np.abs(w[:, 2]) > TOL.cos_zero
        return (w[:, 2] * w_layer[:, 2] > 0.0) & (np.abs(w_layer[:, 2]) > TOL.cos_zero) & (
            np.abs(w[:, 2]) > TOL.cos_zero
        )


def any_positive(c: Rgb) -> np.ndarray:
    """(n,) bool: rows of ``c`` (n, 3) with a positive channel (faster than ``max(axis=1)``)."""
    return (c[:, 0] > 0) | (c[:, 1] > 0) | (c[:, 2] > 0)


def lum(c: Rgb) -> Arr:
    """Luminance of (n, 3) rows (non-negative inputs give non-negative results)."""
    return luminance(c)


def zeros_like_child(n: int) -> tuple[Rgb, Arr]:
    """``(eval, pdf)`` of a missing child: zeros."""
    return np.zeros((n, 3)), np.zeros(n)


def child_eval_pdf(child, wo: Vec3, wi: Vec3) -> tuple[Rgb, Arr]:
    """``child.eval_pdf`` or zeros for None (MDL's ``bsdf()``)."""
    if child is None:
        return zeros_like_child(len(wo))
    return child.eval_pdf(wo, wi)


def child_sample(child, wo: Vec3, u1: Arr, u2: np.ndarray):
    """``child.sample`` or a failed sample for None."""
    if child is None:
        return BsdfSample.failed(len(wo))
    return child.sample(wo, u1, u2)


# --- sampling nests of combiners: one descent, one evaluation (module docstring) ------


@dataclass(frozen=True, slots=True)
class Draw:
    """A combiner's sample before the evaluation that settles it (``_draw``'s result).

    Parameters
    ----------
    wi : (n, 3) float64
        The drawn direction in the combiner's frame; zero rows where nothing was drawn.
    drawn : (n,) bool
        Lanes where the descent reached a direction (the chosen leaf's sample
        succeeded).  Not yet the sample's validity: that needs the evaluation at ``wi``.
    state : tuple
        What the combiner's ``_settle`` needs: its choices and its children's draws
        (a :class:`Draw`, a leaf's :class:`~render.bsdf.BsdfSample`, or None).
    """

    wi: Vec3
    drawn: np.ndarray
    state: tuple


def drawn(d) -> np.ndarray:
    """(n,) bool: lanes where ``d`` (a :class:`Draw` or a BsdfSample) has a direction."""
    return d.drawn if isinstance(d, Draw) else d.valid


def child_draw(child, wo: Vec3, u1: Arr, u2: Arr2):
    """Descend into ``child``: a combiner's :class:`Draw` (its evaluation deferred), a
    leaf's BsdfSample (leaves evaluate nothing below them), a failed sample for None."""
    if child is None:
        return BsdfSample.failed(len(wo))
    draw = getattr(child, "_draw", None)
    return draw(wo, u1, u2) if draw is not None else child.sample(wo, u1, u2)


def child_settle(child, wo: Vec3, wi: Vec3, d) -> tuple[Rgb, Arr, BsdfSample | None]:
    """``child.eval_pdf(wo, wi)`` and the child's sample ``d`` settled at ``wi``.

    A :class:`Draw` is settled by the same evaluation (``child._settle``); a BsdfSample
    (or None: the child was not sampled) is already final and returned as it is.
    """
    if isinstance(d, Draw):
        return child._settle(wo, wi, d)
    e, p = child_eval_pdf(child, wo, wi)
    return e, p, d


def sample_by_draw(node, wo: Vec3, u1: Arr, u2: Arr2) -> BsdfSample:
    """``node.sample``: descend once (``node._draw``), then evaluate once (``node._settle``).

    Where nothing was drawn the evaluation runs at ``+z`` (a valid direction: the
    lanes fail anyway).
    """
    (wo,) = check_dirs(wo, names=("wo",))
    u1, u2 = check_samples(len(wo), u1, u2)
    d = node._draw(wo, u1, u2)
    wi = np.where(d.drawn[:, None], d.wi, np.array([0.0, 0.0, 1.0]))
    return node._settle(wo, wi, d)[2]

