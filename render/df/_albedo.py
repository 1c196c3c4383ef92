"""Directional-albedo tables of the glossy lobes, built lazily by quasi-Monte Carlo.

A glossy lobe's albedo ``E`` (white tint) has no closed form.  Like libbsdf's
multiscatter tables it is tabulated, per df class, scatter mode and (for refracting
modes) relative IOR ``eta = eta2 / eta1`` (rounded to 4 decimals), over:

* ``mu = |cos theta_o|`` at 65 nodes uniform in ``sqrt(mu)`` (dense at grazing, where
  ``E`` changes fastest; the node ``mu = 0`` is evaluated at ``MU_MIN``);
* roughness at the nodes :data:`ROUGHNESS_NODES` (uniform in ``sqrt(r)`` plus extra
  nodes below 1e-3), interpolated linearly in ``sqrt(r)``; roughness above 1 reads 1;
* for anisotropic lanes (``roughness_u != roughness_v``), ``(roughness_u, roughness_v)``
  on the same nodes (bilinear in their square roots), ``mu`` on 25 nodes, and the
  azimuth ``phi`` of ``wo`` from ``tangent_u``: the distributions are symmetric under
  ``t -> -t`` and ``b -> -b``, so ``E`` is even and pi-periodic in ``phi`` and is
  interpolated as ``sum_k c_k cos(2 k phi)`` through nodes at 0, 30, 60, 90 degrees.

Each table column is the mean sample weight over the points of a 3-D Kronecker (R3)
sequence pushed through the lobe's compiled ``sample`` kernel (the df module's
``sample``, bit for bit the earlier numpy class's), built on first use and cached for the
process, so only the roughness nodes a scene uses are ever computed.  Measured accuracy
against quadrature and Monte Carlo: ``tests/render/df``.

For the compiled render core, :func:`node_table` bakes one df node's roughness (and IOR)
into a short table (the columns above, interpolated in roughness, for ``wo`` on either
side) and the kernel :func:`table_albedo` interpolates it in ``mu`` (and ``phi``), as
the numpy tables did; the dfs' ``albedo`` kernels read it.  A node whose roughness or
IOR differs per lane (textures) gets a :func:`lanes_table` instead: the columns its lanes
need on the roughness grid, found from each lane's own values by
:func:`lane_table_albedo` (bit for bit what a single-lane node table gives that lane).
Tables are not built at
import and frozen into the kernels: one isotropic column costs about 0.3 s of sampling
and one anisotropic corner 0.35 s (2 busy cores), so a full grid is ~10 s per (mode,
IOR) isotropic and ~7 min anisotropic, and a refracting mode needs it per IOR; a node
needs at most four columns (``benchmarks/glossy_kernels.py``).
"""

from __future__ import annotations

import math
import os
import sys
import threading
from functools import lru_cache

import numpy as np

from render._typing import Arr
from render.jit import njit

__all__ = [
    "iso_column",
    "aniso_column",
    "node_table",
    "lanes_table",
    "table_albedo",
    "lane_table_albedo",
    "lane_table_average",
    "iso_average",
    "aniso_average",
    "glossy_albedo_table",
    "ROUGHNESS_NODES",
    "MU_MIN",
]

#: roughness nodes of every table
ROUGHNESS_NODES = np.concatenate([[1e-7, 1e-5, 1e-4, 3e-4], (np.arange(1, 33) / 32.0) ** 2])
_Y = np.sqrt(ROUGHNESS_NODES)
#: the grazing node (mu = 0) is evaluated at this cosine
MU_MIN = 1e-6
N_MU, N_POINTS = 65, 4096  # isotropic columns
N_MU_A, N_PHI, N_POINTS_A = 25, 4, 4096  # anisotropic corners
#: azimuth nodes k pi/6 of the anisotropic tables; E(phi) is even and pi-periodic in
#: phi, interpolated as sum_k c_k cos(2 k phi) through the four nodes
_PHI = np.arange(N_PHI) * (np.pi / (2 * (N_PHI - 1)))
_COS_INV = np.linalg.inv(np.cos(2.0 * np.outer(_PHI, np.arange(N_PHI))))


def _kronecker(n: int, d: int = 3) -> np.ndarray:
    """``n`` points of the R_d low-discrepancy sequence (Roberts 2018) in [0, 1)^d."""
    phi = 2.0
    for _ in range(64):  # the root of x^(d+1) = x + 1
        phi = (1.0 + phi) ** (1.0 / (d + 1))
    alpha = (1.0 / phi) ** np.arange(1, d + 1)
    i = np.arange(1, n + 1, dtype=np.float64)[:, None]
    return np.mod(0.5 + i * alpha, 1.0)


def _mu_nodes(m: int) -> Arr:
    return np.maximum(np.linspace(0.0, 1.0, m) ** 2, MU_MIN)


def _kernels(cls):
    """The df's kernels: the module of the first class in the MRO that has them (a
    subclass of a df class defined elsewhere samples through its parent's kernels)."""
    return next(m for m in (sys.modules.get(c.__module__) for c in cls.__mro__)
                if hasattr(m, "sample_weights"))


def _mean_weight(cls, mode, eta, ru, rv, wo: np.ndarray, points: int) -> Arr:
    """Mean white sample weight for each row of ``wo`` (m, 3), through the df's kernels."""
    from render.df._common import ScatterMode
    from render.df._signature import MODE_FLAGS

    module = _kernels(cls)
    sig = module.SIGNATURE
    P = np.zeros((1, sig.width))
    names = [p.name for p in sig.params]
    if "roughness_u" in names:
        P[0, sig.offset("roughness_u")] = max(ru, ROUGHNESS_NODES[0])
        P[0, sig.offset("roughness_v")] = max(rv, ROUGHNESS_NODES[0])
    else:  # an isotropic lobe (sheen_bsdf): one roughness
        P[0, sig.offset("roughness")] = max(ru, ROUGHNESS_NODES[0])
    P[0, sig.offset("tint") : sig.offset("tint") + 3] = 1.0
    if "tangent_u" in names:
        P[0, sig.offset("tangent_u")] = 1.0
    flags = 0
    if mode is not None:
        flags = MODE_FLAGS[ScatterMode.parse(mode).value]
        P[0, sig.offset("ior_outside")] = 1.0
        P[0, sig.offset("ior_inside")] = eta
    w = module.sample_weights(P, flags, np.ascontiguousarray(wo), _kronecker(points))
    return w.mean(axis=1)


def _stored(name: str, compute) -> Arr:
    """``compute()``, kept on disk as ``albedo/<name>.npy`` in the kernels' cache folder
    (:func:`render.jit.cache_dir`: per user, per source tree).  A column is a mean over
    4096 samples through the df's kernels, 50-80 ms, and the same in every process of one
    tree; a glossy scene's start computed two to six of them (0.1-0.3 s, 32 of the 83
    gallery scenes).  A file that cannot be read is computed again; one that cannot be
    written is not kept."""
    from render.jit import cache_dir

    path = cache_dir() / "albedo" / f"{name}.npy"
    try:
        return np.load(path)
    except (OSError, ValueError, EOFError):
        pass
    value = compute()
    try:  # written whole, then renamed: a reader never sees half a file
        path.parent.mkdir(parents=True, exist_ok=True)
        part = path.with_name(f"{path.name}.{os.getpid()}-{threading.get_ident()}")
        with open(part, "wb") as f:
            np.save(f, value)
        os.replace(part, path)
    except OSError:
        pass
    return value


def _column_name(cls: type, mode, eta: float, *nodes: int) -> str:
    """What a column depends on: the kernels' module, the mode, eta, the roughness nodes."""
    return "-".join([_kernels(cls).__name__, str(getattr(mode, "name", mode)),
                     repr(float(eta)), *map(str, nodes)])


@lru_cache(maxsize=None)
def iso_column(cls: type, mode, eta: float, ir: int) -> Arr:
    """``E`` at the ``N_MU`` cosine nodes for roughness node ``ir`` (isotropic)."""
    def compute():
        mu = _mu_nodes(N_MU)
        wo = np.stack([np.sqrt(1.0 - mu * mu), np.zeros_like(mu), mu], axis=1)
        r = float(ROUGHNESS_NODES[ir])
        return _mean_weight(cls, mode, eta, r, r, wo, N_POINTS)

    return _stored(_column_name(cls, mode, eta, ir), compute)


def _average_iso(col: Arr) -> float:
    """``E_avg = 2 ∫ E(mu) mu dmu`` of an isotropic column, exactly for its interpolant
    (linear in ``y = sqrt(mu)`` between the nodes ``y_j = j / (N_MU - 1)``):
    ``4 ∫ E(y) y^3 dy``."""
    y = np.linspace(0.0, 1.0, len(col))
    a, b = y[:-1], y[1:]
    h = b - a
    # ∫_a^b ((b - y) E_a + (y - a) E_b) / h * y^3 dy, each term in closed form
    i4 = (b**4 - a**4) / 4.0
    i5 = (b**5 - a**5) / 5.0
    ea, eb = col[:-1], col[1:]
    return float(4.0 * np.sum((ea * (b * i4 - i5) + eb * (i5 - a * i4)) / h))


@lru_cache(maxsize=None)
def iso_average(cls: type, mode, eta: float, ir: int) -> float:
    """The cosine-weighted average ``E_avg`` of :func:`iso_column` (the energy the
    multiple-scattering lobe of ``multiscatter_tint`` must hand back is ``1 - E_avg``)."""
    return _average_iso(iso_column(cls, mode, eta, ir))


@lru_cache(maxsize=None)
def aniso_average(cls: type, mode, eta: float, iu: int, iv: int) -> float:
    """``E_avg`` of :func:`aniso_column`: the azimuthal mean of the trigonometric
    interpolant (its constant coefficient) averaged over ``mu`` as :func:`iso_average`
    does, on the anisotropic nodes (linear in ``sqrt(mu)``)."""
    col = aniso_column(cls, mode, eta, iu, iv)  # (N_PHI, N_MU_A)
    mean = _COS_INV[:, 0] @ col
    return _average_iso(mean)


@lru_cache(maxsize=None)
def aniso_column(cls: type, mode, eta: float, iu: int, iv: int) -> Arr:
    """``E`` at ``N_PHI x N_MU_A`` (azimuth, cosine) nodes for roughness nodes ``(iu, iv)``."""
    def compute():
        mu = _mu_nodes(N_MU_A)
        P, M = np.meshgrid(_PHI, mu, indexing="ij")
        s = np.sqrt(1.0 - M * M)
        wo = np.stack([s * np.cos(P), s * np.sin(P), M], axis=-1).reshape(-1, 3)
        E = _mean_weight(cls, mode, eta, float(ROUGHNESS_NODES[iu]),
                         float(ROUGHNESS_NODES[iv]), wo, N_POINTS_A)
        return E.reshape(N_PHI, N_MU_A)

    return _stored(_column_name(cls, mode, eta, iu, iv), compute)


def _locate(y: Arr, nodes: Arr) -> tuple[np.ndarray, Arr]:
    """Interval index and fraction of ``y`` in the sorted ``nodes`` (clamped)."""
    i = np.clip(np.searchsorted(nodes, y, side="right") - 1, 0, len(nodes) - 2)
    f = np.clip((y - nodes[i]) / (nodes[i + 1] - nodes[i]), 0.0, 1.0)
    return i, f


_MU_NODES_A = np.linspace(0.0, 1.0, N_MU_A)
_ISO, _ANISO, _LANES = 0.0, 1.0, 2.0
_NR = len(ROUGHNESS_NODES)
_R_LO = float(ROUGHNESS_NODES[0])
_HEADER = 2


def _iso_node(cls, mode, eta: float, ru: float) -> Arr:
    """``E`` at the ``N_MU`` nodes, interpolated in ``sqrt(r)`` (linear in ``sqrt(r)``)."""
    i, fy = _locate(np.sqrt(np.array([ru])), _Y)
    i, fy = int(i[0]), float(fy[0])
    if fy >= 1.0:
        i, fy = i + 1, 0.0
    col = np.append(iso_column(cls, mode, eta, i), iso_average(cls, mode, eta, i))
    if fy > 0.0:
        nxt = np.append(iso_column(cls, mode, eta, i + 1), iso_average(cls, mode, eta, i + 1))
        col = (1.0 - fy) * col + fy * nxt
    return col


def _aniso_node(cls, mode, eta: float, ru: float, rv: float) -> Arr:
    """``E`` at the ``N_PHI x N_MU_A`` nodes, bilinear in ``(sqrt(ru), sqrt(rv))``."""
    iu, fu = (float(a[0]) for a in _locate(np.sqrt(np.array([ru])), _Y))
    iv, fv = (float(a[0]) for a in _locate(np.sqrt(np.array([rv])), _Y))
    acc = np.zeros((N_PHI, N_MU_A))
    avg = 0.0
    for du in (0, 1):
        for dv in (0, 1):
            w = (fu if du else 1 - fu) * (fv if dv else 1 - fv)
            if w > 0.0:
                acc += w * aniso_column(cls, mode, eta, int(iu) + du, int(iv) + dv)
                avg += w * aniso_average(cls, mode, eta, int(iu) + du, int(iv) + dv)
    return np.append(acc.ravel(), avg)


def node_table(cls: type, mode, roughness_u: float, roughness_v: float,
               eta_outside: float = 1.0, eta_inside: float = 1.0) -> np.ndarray:
    """One df node's albedo table for :func:`table_albedo` (constant roughness and IOR).

    Parameters
    ----------
    cls : type
        The df class (its module holds ``SIGNATURE`` and ``sample``).
    mode : ScatterMode or None
        The key mode: ``scatter_reflect`` for reflection and thin-walled surfaces (the
        Fresnel split cancels), ``None`` for lobes without modes.
    roughness_u, roughness_v : float
    eta_outside, eta_inside : float
        ``eta2 / eta1`` seen from the outside (``wo.z > 0``) and from the inside
        (refracting modes only; after ``ior_pair``'s glossy push-apart).

    Returns
    -------
    (k,) float64
        ``[kind, inside_offset, E outside..., E_avg, (E inside..., E_avg)]``: ``kind`` 0
        isotropic (``E`` at the ``N_MU`` cosine nodes) or 1 anisotropic (``N_PHI x N_MU_A``
        nodes), each side followed by its cosine-weighted average ``E_avg``
        (:func:`lane_table_average`); ``inside_offset`` is where the inside table starts
        (0: the same table).
    """
    from render.df._common import ScatterMode

    ru = float(np.clip(roughness_u, ROUGHNESS_NODES[0], 1.0))
    rv = float(np.clip(roughness_v, ROUGHNESS_NODES[0], 1.0))
    refracting = mode is not None and ScatterMode.parse(mode) is not ScatterMode.scatter_reflect
    etas = (eta_outside, eta_inside) if refracting else (1.0,)

    def one(eta):
        eta = float(np.round(eta, 4))
        if ru == rv:
            return _iso_node(cls, mode, eta, ru)
        return _aniso_node(cls, mode, eta, ru, rv)

    parts = [one(e) for e in etas]
    kind = _ISO if ru == rv else _ANISO
    inside = _HEADER + len(parts[0]) if len(parts) > 1 else 0
    return np.concatenate([[kind, float(inside)], *parts])


@njit
def _aniso_mu(y):
    """Interval and fraction of ``y = sqrt(mu)`` among the anisotropic tables' nodes."""
    j = 0
    while j < N_MU_A - 2 and _MU_NODES_A[j + 1] <= y:
        j += 1
    return j, min(max((y - _MU_NODES_A[j]) / (_MU_NODES_A[j + 1] - _MU_NODES_A[j]), 0.0), 1.0)


@njit
def _phi_weight(phi, k):
    """Weight of azimuth node ``k`` at ``phi`` (``E`` as ``sum_c a_c cos(2 c phi)``)."""
    w = 0.0
    for c in range(N_PHI):
        w += math.cos(2.0 * (phi * c)) * _COS_INV[k, c]
    return w


@njit
def table_albedo(T, t, mu, phi, inside):
    """White albedo ``E`` from the node table at ``T[t:]`` (:func:`node_table`).

    ``mu = |cos theta_o|``, ``phi`` the azimuth of ``wo`` from ``tangent_u`` folded into
    [0, pi/2], ``inside``: ``wo`` below the surface.  Linear in ``sqrt(mu)``; anisotropic
    tables are trigonometric in ``phi`` (``sum_k c_k cos(2 k phi)`` through the nodes).
    """
    base = t + _HEADER
    if inside and T[t + 1] > 0.0:
        base = t + int(T[t + 1])
    y = math.sqrt(mu)
    if T[t] == _ISO:
        j = min(max(int(math.floor(y * (N_MU - 1))), 0), N_MU - 2)
        fx = min(max((y - j / (N_MU - 1)) / (1.0 / (N_MU - 1)), 0.0), 1.0)
        return (1.0 - fx) * T[base + j] + fx * T[base + j + 1]
    j, fx = _aniso_mu(y)
    E = 0.0
    for k in range(N_PHI):
        w = _phi_weight(phi, k)
        at = base + k * N_MU_A + j
        E += w * ((1.0 - fx) * T[at] + fx * T[at + 1])
    return E


def _grid(cls, mode, eta: float, ru: np.ndarray, rv: np.ndarray) -> np.ndarray:
    """The roughness-grid part of a :func:`lanes_table` for lanes ``(ru, rv)`` (clipped):
    ``[iso map (_NR), aniso map (_NR^2), columns...]``; a map entry is the offset of
    column ``i`` (``(iu, iv)``) from the grid's start, or -1 where no lane needs it; each
    column ends with its ``E_avg``."""
    maps = np.full(_NR + _NR * _NR, -1.0)
    cols, at = [], len(maps)
    iso = ru == rv
    i, f = _locate(np.sqrt(ru[iso]), _Y)
    shift = f >= 1.0
    i, f = np.where(shift, i + 1, i), np.where(shift, 0.0, f)
    for k in sorted(set(i.tolist()) | set((i[f > 0.0] + 1).tolist())):
        maps[k] = at
        cols.append(np.append(iso_column(cls, mode, eta, k), iso_average(cls, mode, eta, k)))
        at += N_MU + 1
    iu, fu = _locate(np.sqrt(ru[~iso]), _Y)
    iv, fv = _locate(np.sqrt(rv[~iso]), _Y)
    corners = set()
    for du in (0, 1):
        for dv in (0, 1):
            w = (fu if du else 1 - fu) * (fv if dv else 1 - fv)
            corners |= set(zip((iu + du)[w > 0.0].tolist(), (iv + dv)[w > 0.0].tolist(),
                               strict=True))
    for a, b in sorted(corners):
        maps[_NR + a * _NR + b] = at
        cols.append(np.append(aniso_column(cls, mode, eta, a, b).ravel(),
                              aniso_average(cls, mode, eta, a, b)))
        at += N_PHI * N_MU_A + 1
    return np.concatenate([maps, *cols])


def lanes_table(cls: type, mode, roughness_u, roughness_v, iors=None, etas=None) -> np.ndarray:
    """The albedo table of a node whose roughness (or IOR) differs per lane.

    Parameters
    ----------
    cls, mode : as :func:`node_table`
    roughness_u, roughness_v : (n,) float64
    iors : (n, 2) float64, optional
        Each lane's packed ``(ior_outside, ior_inside)`` (refracting modes only): the key
        :func:`lane_table_albedo` finds the lane's IOR group by.
    etas : (n, 2) float64, optional
        Each lane's ``(eta_outside, eta_inside)`` as :func:`node_table` takes them.

    Returns
    -------
    (k,) float64
        ``[2, groups, (ior_outside, ior_inside, outside grid, inside grid) per group,
        grids...]`` (offsets from the table's start; one group without refraction).
    """
    from render.df._common import ScatterMode

    ru = np.clip(np.asarray(roughness_u, dtype=np.float64), _R_LO, 1.0)
    rv = np.clip(np.asarray(roughness_v, dtype=np.float64), _R_LO, 1.0)
    refracting = mode is not None and ScatterMode.parse(mode) is not ScatterMode.scatter_reflect
    if refracting:
        keys, first, group = np.unique(np.asarray(iors, dtype=np.float64), axis=0,
                                       return_index=True, return_inverse=True)
        group = group.ravel()
    else:
        keys, first, group = np.full((1, 2), np.nan), np.zeros(1, dtype=int), np.zeros(len(ru),
                                                                                        dtype=int)
    head = np.zeros(2 + 4 * len(keys))
    head[0], head[1] = _LANES, len(keys)
    parts, at = [head], len(head)
    for g in range(len(keys)):
        lanes = group == g
        sides = [float(np.round(e, 4)) for e in (etas[first[g]] if refracting else (1.0,))]
        offs = []
        for eta in sides:
            parts.append(_grid(cls, mode, eta, ru[lanes], rv[lanes]))
            offs.append(at)
            at += len(parts[-1])
        head[2 + 4 * g: 6 + 4 * g] = (*keys[g], offs[0], offs[-1])
    return np.concatenate(parts)


@njit
def _locate1(y, nodes):
    """:func:`_locate` of one value."""
    i = 0
    while i < len(nodes) - 2 and nodes[i + 1] <= y:
        i += 1
    f = min(max((y - nodes[i]) / (nodes[i + 1] - nodes[i]), 0.0), 1.0)
    return i, f


@njit
def lane_table_albedo(T, t, mu, phi, inside, ru, rv, ior_outside, ior_inside):
    """White albedo ``E`` of one lane from its node's table at ``T[t:]``: a
    :func:`node_table` (:func:`table_albedo`), or a :func:`lanes_table` read at the lane's
    own roughness ``(ru, rv)`` and IOR pair (the values its node packs)."""
    if T[t] != _LANES:
        return table_albedo(T, t, mu, phi, inside)
    e = t + 2
    if T[t + 1] > 1.0:
        for g in range(int(T[t + 1])):
            if T[t + 2 + 4 * g] == ior_outside and T[t + 3 + 4 * g] == ior_inside:
                e = t + 2 + 4 * g
                break
    gb = t + int(T[e + 3] if inside else T[e + 2])
    ru = min(max(ru, _R_LO), 1.0)
    rv = min(max(rv, _R_LO), 1.0)
    y = math.sqrt(mu)
    if ru == rv:
        i, f = _locate1(math.sqrt(ru), _Y)
        if f >= 1.0:
            i, f = i + 1, 0.0
        a = gb + int(T[gb + i])
        c = gb + int(T[gb + i + 1]) if f > 0.0 else a
        j = min(max(int(math.floor(y * (N_MU - 1))), 0), N_MU - 2)
        fx = min(max((y - j / (N_MU - 1)) / (1.0 / (N_MU - 1)), 0.0), 1.0)
        v0, v1 = T[a + j], T[a + j + 1]
        if f > 0.0:
            v0 = (1.0 - f) * v0 + f * T[c + j]
            v1 = (1.0 - f) * v1 + f * T[c + j + 1]
        return (1.0 - fx) * v0 + fx * v1
    iu, fu = _locate1(math.sqrt(ru), _Y)
    iv, fv = _locate1(math.sqrt(rv), _Y)
    j, fx = _aniso_mu(y)
    E = 0.0
    for k in range(N_PHI):
        w = _phi_weight(phi, k)
        v0 = v1 = 0.0
        for du in range(2):
            for dv in range(2):
                wc = (fu if du else 1.0 - fu) * (fv if dv else 1.0 - fv)
                if wc > 0.0:
                    at = gb + int(T[gb + _NR + (iu + du) * _NR + iv + dv]) + k * N_MU_A + j
                    v0 += wc * T[at]
                    v1 += wc * T[at + 1]
        E += w * ((1.0 - fx) * v0 + fx * v1)
    return E


@njit
def lane_table_average(T, t, inside, ru, rv, ior_outside, ior_inside):
    """The cosine-weighted average ``E_avg = (1/pi) ∫ E(w) |cos| dw`` of one lane's white
    albedo, from its node's table at ``T[t:]`` (the value stored after each column and
    interpolated in roughness as the columns are; :func:`lane_table_albedo`'s lookups)."""
    if T[t] != _LANES:
        base = t + _HEADER
        if inside and T[t + 1] > 0.0:
            base = t + int(T[t + 1])
        return T[base + (N_MU if T[t] == _ISO else N_PHI * N_MU_A)]
    e = t + 2
    if T[t + 1] > 1.0:
        for g in range(int(T[t + 1])):
            if T[t + 2 + 4 * g] == ior_outside and T[t + 3 + 4 * g] == ior_inside:
                e = t + 2 + 4 * g
                break
    gb = t + int(T[e + 3] if inside else T[e + 2])
    ru = min(max(ru, _R_LO), 1.0)
    rv = min(max(rv, _R_LO), 1.0)
    if ru == rv:
        i, f = _locate1(math.sqrt(ru), _Y)
        if f >= 1.0:
            i, f = i + 1, 0.0
        v = T[gb + int(T[gb + i]) + N_MU]
        if f > 0.0:
            v = (1.0 - f) * v + f * T[gb + int(T[gb + i + 1]) + N_MU]
        return v
    iu, fu = _locate1(math.sqrt(ru), _Y)
    iv, fv = _locate1(math.sqrt(rv), _Y)
    v = 0.0
    for du in range(2):
        for dv in range(2):
            wc = (fu if du else 1.0 - fu) * (fv if dv else 1.0 - fv)
            if wc > 0.0:
                v += wc * T[gb + int(T[gb + _NR + (iu + du) * _NR + iv + dv]) + N_PHI * N_MU_A]
    return v


def glossy_albedo_table(cls: type, row, flags: int) -> np.ndarray:
    """The node table of a glossy lobe (:mod:`render.df._glossy_lobe`): a
    :func:`node_table` for one packed row (constant arguments), a :func:`lanes_table` for
    rows whose roughness or IOR differ (per-lane arguments).  The lobe has MDL's glossy
    signature (``roughness_u``, ``roughness_v``, ``mode`` and the IOR context:
    ``simple_glossy_bsdf`` and the ``microfacet_*`` dfs), or has no ``mode``: it reflects
    only and has no IOR (``roughness_u`` and ``roughness_v``, or one ``roughness``).

    Parameters
    ----------
    cls : type
        The df class (its module's ``SIGNATURE`` and ``sample_weights``).
    row : (SIGNATURE.width,) or (rows, SIGNATURE.width) float64
        The node's packed slots.
    flags : int
        Its mode and thin-walled flags.
    """
    from render.df import _kernel_common as kc
    from render.df._common import ScatterMode
    from render.df._signature import MODE_FLAGS, MODE_MASK, REFLECT, THIN_WALLED

    sig = sys.modules[cls.__module__].SIGNATURE
    names = {p.name for p in sig.params}
    if "roughness_u" in names:
        _ru, _rv = sig.offset("roughness_u"), sig.offset("roughness_v")
    else:
        _ru = _rv = sig.offset("roughness")
    rows = np.atleast_2d(np.asarray(row, dtype=np.float64))
    mode = flags & MODE_MASK
    if "mode" not in names:
        key = None
    elif mode == REFLECT or (flags & THIN_WALLED) != 0:
        key = ScatterMode.scatter_reflect
    else:
        key = ScatterMode({v: k for k, v in MODE_FLAGS.items()}[mode])
    refracts = key not in (None, ScatterMode.scatter_reflect)
    cols = [_ru, _rv]
    if refracts:
        _o, _i = sig.offset("ior_outside"), sig.offset("ior_inside")
        cols += [_o, _i]
    ru = np.maximum(rows[:, _ru], kc.ROUGHNESS_MIN)
    rv = np.maximum(rows[:, _rv], kc.ROUGHNESS_MIN)
    if np.all(rows[:, cols] == rows[0, cols]):
        if not refracts:
            return node_table(cls, key, ru[0], rv[0])
        o, i = kc.ior_pair(rows[0, _o], rows[0, _i], False, False, True)
        return node_table(cls, key, ru[0], rv[0], i / o, o / i)
    if not refracts:
        return lanes_table(cls, key, ru, rv)
    iors = rows[:, [_o, _i]]
    etas = np.empty_like(iors)
    for k, (ro, ri) in enumerate(iors):
        o, i = kc.ior_pair(ro, ri, False, False, True)
        etas[k] = i / o, o / i
    return lanes_table(cls, key, ru, rv, iors, etas)
