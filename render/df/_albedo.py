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
sequence pushed through the lobe's own ``sample``, built on first use and cached for
the process, so only the roughness nodes a scene uses are ever computed (about 0.3 s
per isotropic column and 0.4 s per anisotropic corner).  Measured accuracy against
quadrature and Monte Carlo: ``tests/render/df``.
"""

from __future__ import annotations

from functools import lru_cache

import numpy as np

from render._typing import Arr

__all__ = ["glossy_albedo", "iso_column", "aniso_column", "ROUGHNESS_NODES", "MU_MIN"]

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


def _mean_weight(cls, mode, eta, ru, rv, wo: np.ndarray, points: int) -> Arr:
    """Mean white sample weight for each row of ``wo`` (m, 3)."""
    kwargs = {} if mode is None else {"mode": mode, "ior_inside": eta}
    pts = _kronecker(points)
    m = len(wo)
    bsdf = cls(roughness_u=ru, roughness_v=rv, **kwargs)
    s = bsdf.sample(
        np.repeat(wo, points, axis=0), np.tile(pts[:, 0], m), np.tile(pts[:, 1:], (m, 1))
    )
    return s.weight[:, 0].reshape(m, points).mean(axis=1)


@lru_cache(maxsize=None)
def iso_column(cls: type, mode, eta: float, ir: int) -> Arr:
    """``E`` at the ``N_MU`` cosine nodes for roughness node ``ir`` (isotropic)."""
    mu = _mu_nodes(N_MU)
    wo = np.stack([np.sqrt(1.0 - mu * mu), np.zeros_like(mu), mu], axis=1)
    r = float(ROUGHNESS_NODES[ir])
    return _mean_weight(cls, mode, eta, r, r, wo, N_POINTS)


@lru_cache(maxsize=None)
def aniso_column(cls: type, mode, eta: float, iu: int, iv: int) -> Arr:
    """``E`` at ``N_PHI x N_MU_A`` (azimuth, cosine) nodes for roughness nodes ``(iu, iv)``."""
    mu = _mu_nodes(N_MU_A)
    P, M = np.meshgrid(_PHI, mu, indexing="ij")
    s = np.sqrt(1.0 - M * M)
    wo = np.stack([s * np.cos(P), s * np.sin(P), M], axis=-1).reshape(-1, 3)
    E = _mean_weight(
        cls, mode, eta, float(ROUGHNESS_NODES[iu]), float(ROUGHNESS_NODES[iv]), wo, N_POINTS_A
    )
    return E.reshape(N_PHI, N_MU_A)


def _locate(y: Arr, nodes: Arr) -> tuple[np.ndarray, Arr]:
    """Interval index and fraction of ``y`` in the sorted ``nodes`` (clamped)."""
    i = np.clip(np.searchsorted(nodes, y, side="right") - 1, 0, len(nodes) - 2)
    f = np.clip((y - nodes[i]) / (nodes[i + 1] - nodes[i]), 0.0, 1.0)
    return i, f


def glossy_albedo(
    cls: type, mode, eta: Arr, roughness_u: Arr, roughness_v: Arr, mu: Arr, phi: Arr
) -> Arr:
    """Interpolated white albedo ``E`` per lane.

    Parameters
    ----------
    cls : type
        The df class (constructed as ``cls(roughness_u=, roughness_v=[, mode=, ior_inside=])``).
    mode : ScatterMode or None
        ``None`` for lobes without modes; reflect tables ignore ``eta``.
    eta : (n,) float64
        Relative IOR ``eta2 / eta1`` per lane.
    roughness_u, roughness_v : (n,) float64
    mu : (n,) float64
        ``|cos theta_o|``.
    phi : (n,) float64
        Azimuth of ``wo`` from ``tangent_u`` (only anisotropic lanes use it).

    Returns
    -------
    (n,) float64
    """
    n = len(mu)
    ru = np.clip(roughness_u, ROUGHNESS_NODES[0], 1.0)
    rv = np.clip(roughness_v, ROUGHNESS_NODES[0], 1.0)
    eta_key = np.round(np.broadcast_to(eta, (n,)), 4)
    out = np.zeros(n)
    aniso = ru != rv
    # isotropic lanes: 2 roughness columns, linear in sqrt(mu) and sqrt(r)
    iso = np.nonzero(~aniso)[0]
    if len(iso):
        j, fx = _locate(np.sqrt(mu[iso]), np.linspace(0.0, 1.0, N_MU))
        i, fy = _locate(np.sqrt(ru[iso]), _Y)
        etas, e_idx = np.unique(eta_key[iso], return_inverse=True)
        # a lane exactly on a node reads one column (the other's weight is 0)
        i = np.where(fy >= 1.0, i + 1, i)
        fy = np.where(fy >= 1.0, 0.0, fy)
        i1 = np.where(fy > 0.0, i + 1, i)
        codes = np.concatenate([e_idx * len(_Y) + i, e_idx * len(_Y) + i1])
        uniq, inv = np.unique(codes, return_inverse=True)
        table = np.stack(
            [iso_column(cls, mode, float(etas[c // len(_Y)]), int(c % len(_Y))) for c in uniq]
        )
        r0, r1 = inv[: len(iso)], inv[len(iso) :]

        def at(row):
            return (1.0 - fx) * table[row, j] + fx * table[row, j + 1]

        out[iso] = (1.0 - fy) * at(r0) + fy * at(r1)
    # anisotropic lanes: 4 roughness corners, bilinear in (phi, sqrt(mu))
    an = np.nonzero(aniso)[0]
    if len(an):
        j, fx = _locate(np.sqrt(mu[an]), np.linspace(0.0, 1.0, N_MU_A))
        # trigonometric interpolation weights in phi: E(phi) = sum_k w_k(phi) E(phi_k)
        wphi = np.cos(2.0 * np.outer(phi[an], np.arange(N_PHI))) @ _COS_INV.T  # (m, N_PHI)
        iu, fu = _locate(np.sqrt(ru[an]), _Y)
        iv, fv = _locate(np.sqrt(rv[an]), _Y)
        etas, e_idx = np.unique(eta_key[an], return_inverse=True)
        ny = len(_Y)
        corners = [(du, dv) for du in (0, 1) for dv in (0, 1)]
        codes = np.concatenate([(e_idx * ny + iu + du) * ny + iv + dv for du, dv in corners])
        uniq, inv = np.unique(codes, return_inverse=True)
        table = np.stack(
            [
                aniso_column(cls, mode, float(etas[c // (ny * ny)]), int(c // ny % ny), int(c % ny))
                for c in uniq
            ]
        )
        m = len(an)
        acc = np.zeros(m)
        for c, (du, dv) in enumerate(corners):
            row = inv[c * m : (c + 1) * m]
            at_nodes = (1 - fx)[:, None] * table[row, :, j] + fx[:, None] * table[row, :, j + 1]
            val = np.sum(wphi * at_nodes, axis=1)
            acc += (fu if du else 1 - fu) * (fv if dv else 1 - fv) * val
        out[an] = acc
    return out
