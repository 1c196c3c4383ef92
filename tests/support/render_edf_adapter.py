"""Adapters so the BSDF statistics of ``render.testing`` apply to EDFs."""

from __future__ import annotations

import numpy as np

from render.bsdf import BsdfSample, Edf, Lobe


class EdfAsBsdf:
    """An EDF seen as a 'BSDF' whose ``wi`` is the emitted direction (``wo`` ignored)."""

    lobes = Lobe.DIFFUSE_REFLECTION

    def __init__(self, edf: Edf):
        self.edf = edf

    def sample(self, wo, u1, u2):
        s = self.edf.sample(u1, u2)
        lobe = np.where(s.valid, int(Lobe.DIFFUSE_REFLECTION), 0).astype(np.int32)
        return BsdfSample(s.wo, s.pdf, s.weight, lobe)

    def pdf(self, wo, wi):
        return self.edf.pdf(wi)
