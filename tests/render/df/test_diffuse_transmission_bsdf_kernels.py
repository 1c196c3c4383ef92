"""df::diffuse_transmission_bsdf kernels: equal to the numpy class, and the df checklist on them."""

from __future__ import annotations

import importlib

import pytest
from df_kernel_adapter import KernelBsdf, compare_bsdf, lane_dirs, lane_us, pack
from render_df_cases import (
    CHI2_WOS,
    WOS,
    DfCase,
    case_ids,
    check_chi2,
    check_consistency,
    check_integrals,
    check_no_nan,
    pair_ids,
    per_wo,
)

from render.bsdf import Lobe
from render.df import diffuse_transmission_bsdf

mod = importlib.import_module("render.df.diffuse_transmission_bsdf")


def _kernel(**kw):
    return lambda: KernelBsdf(mod, Lobe.DIFFUSE_TRANSMISSION, **kw)


CASES = [
    DfCase("white", _kernel(), "diffuse", lossless=True, transmits=True, reciprocal=False),
    DfCase("color", _kernel(tint=[0.9, 0.5, 0.0]), "diffuse", transmits=True, reciprocal=False),
    DfCase("black", _kernel(tint=0.0), "diffuse", transmits=True, reciprocal=False),
    # the mode and thin_walled flags do not change a diffuse transmission
    DfCase("thin-rt", _kernel(mode="scatter_reflect_transmit", thin_walled=True), "diffuse",
           lossless=True, transmits=True, reciprocal=False),
]


def test_signature():
    assert [p.name for p in mod.SIGNATURE.params] == ["tint", "handle"]
    assert mod.SIGNATURE.width == 3
    assert pack(mod.SIGNATURE, tint=[2.0, -1.0, 0.25]).tolist() == [[1.0, 0.0, 0.25]]


@pytest.mark.parametrize("tint", ["random", 0.0, 1.0])
def test_kernels_equal_numpy_over_random_lanes(tint, rng):
    wo = lane_dirs(rng, 6000)
    wi = lane_dirs(rng, 6000)[rng.permutation(len(wo))]
    n = len(wo)
    u1, u2 = lane_us(rng, n)
    t = rng.uniform(-0.2, 1.2, (n, 3)) if tint == "random" else tint
    ref = diffuse_transmission_bsdf(tint=t)
    ker = KernelBsdf(mod, Lobe.DIFFUSE_TRANSMISSION, n=n, tint=t)
    compare_bsdf(ref, ker, wo, wi, u1, u2, rtol=0.0)


@pytest.mark.parametrize("case", CASES, ids=case_ids(CASES))
def test_consistency(case, rng):
    check_consistency(case, rng)


@pytest.mark.parametrize("case", CASES, ids=case_ids(CASES))
def test_no_nan_or_negative(case, rng):
    check_no_nan(case, rng)


_CHI2 = per_wo(CASES, CHI2_WOS, only=lambda c: c.id == "color")


@pytest.mark.parametrize(("case", "wo"), _CHI2, ids=pair_ids(_CHI2))
def test_chi2(case, wo):
    check_chi2(case, wo, test_count=len(_CHI2))


_INT = per_wo(CASES, WOS)


@pytest.mark.parametrize(("case", "wo"), _INT, ids=pair_ids(_INT))
def test_furnace_albedo_and_pdf_integral(case, wo):
    check_integrals(case, wo)
