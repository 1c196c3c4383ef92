"""Kernels over lanes for the glossy dfs' kernel tests: a tiny slot packer that follows a
df's SIGNATURE (the lead's packer replaces it) and vectorising njit loops, wrapped as a
:class:`render.bsdf.Bsdf` so that :mod:`render.testing`'s chi-square and furnace run on
the compiled kernels."""

from __future__ import annotations

import numba
import numpy as np

from render.bsdf import Bsdf, BsdfSample, Lobe
from render.df._signature import MODE_FLAGS, THIN_WALLED


def pack(sig, flags_mode: str | None = None, thin_walled: bool = False, **kw):
    """``(row, flags)``: one row of slots in SIGNATURE order, clamped as declared;
    a default naming another parameter (``roughness_v``) copies it, ``tangent_u``
    defaults to ``+x`` (the local frame's tangent)."""
    row = np.zeros(sig.width)
    for p in sig.params:
        if not p.width:
            continue
        v = kw.get(p.name, p.default)
        if isinstance(v, str):
            v = kw.get(v, (1.0, 0.0, 0.0))
        v = np.broadcast_to(np.asarray(v, dtype=np.float64), (p.width,)).copy()
        if p.clamp is not None:
            v = np.clip(v, p.clamp[0], p.clamp[1])
        at = sig.offset(p.name)
        row[at : at + p.width] = v
    for c in sig.context:
        row[sig.offset(c)] = kw.get(c, 1.0)
    flags = MODE_FLAGS[flags_mode or "scatter_reflect"] | (THIN_WALLED if thin_walled else 0)
    return row, flags


@numba.njit
def eval_lanes(kernel, P, row, b, flags, wo, wi):
    n = wo.shape[0]
    f = np.zeros((n, 3))
    pdf = np.zeros(n)
    for k in range(n):
        f[k, 0], f[k, 1], f[k, 2], pdf[k] = kernel(
            P, row, b, flags, wo[k, 0], wo[k, 1], wo[k, 2], wi[k, 0], wi[k, 1], wi[k, 2])
    return f, pdf


@numba.njit
def sample_lanes(kernel, P, row, b, flags, wo, u1, u2):
    n = wo.shape[0]
    wi = np.zeros((n, 3))
    pdf = np.zeros(n)
    w = np.zeros((n, 3))
    lobe = np.zeros(n, np.int32)
    for k in range(n):
        r = kernel(P, row, b, flags, wo[k, 0], wo[k, 1], wo[k, 2], u1[k], u2[k, 0], u2[k, 1])
        wi[k, 0], wi[k, 1], wi[k, 2], pdf[k], w[k, 0], w[k, 1], w[k, 2], lobe[k] = r
    return wi, pdf, w, lobe


@numba.njit
def albedo_lanes(kernel, P, row, b, flags, wo, T, t):
    n = wo.shape[0]
    a = np.zeros((n, 3))
    for k in range(n):
        a[k, 0], a[k, 1], a[k, 2] = kernel(P, row, b, flags, wo[k, 0], wo[k, 1], wo[k, 2], T, t)
    return a


class KernelLanes(Bsdf):
    """A df module's kernels on one packed row, as a numpy-style :class:`Bsdf`."""

    def __init__(self, module, row, flags, lobes=Lobe.GLOSSY):
        self.module = module
        self.P = np.asarray(row, dtype=np.float64).reshape(1, -1)
        self.flags = int(flags)
        self.lobes = lobes
        self.table = module.albedo_table(self.P[0], self.flags)

    def eval_pdf(self, wo, wi):
        return eval_lanes(self.module.eval_pdf, self.P, 0, 0, self.flags,
                          np.ascontiguousarray(wo), np.ascontiguousarray(wi))

    def eval(self, wo, wi):
        return self.eval_pdf(wo, wi)[0]

    def pdf(self, wo, wi):
        return self.eval_pdf(wo, wi)[1]

    def sample(self, wo, u1, u2):
        return BsdfSample(*sample_lanes(self.module.sample, self.P, 0, 0, self.flags,
                                        np.ascontiguousarray(wo), np.asarray(u1, np.float64),
                                        np.ascontiguousarray(u2, np.float64)))

    def albedo(self, wo):
        return albedo_lanes(self.module.albedo, self.P, 0, 0, self.flags,
                            np.ascontiguousarray(wo), self.table, 0)
