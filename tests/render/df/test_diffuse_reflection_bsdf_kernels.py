"""df::diffuse_reflection_bsdf kernels: equal to the numpy class, and the df checklist on them."""

from __future__ import annotations

import importlib

import numpy as np
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
    check_reciprocity,
    pair_ids,
    per_wo,
)

from render.bsdf import Lobe
from render.df import diffuse_reflection_bsdf

# the module (``render.df.diffuse_reflection_bsdf`` the attribute is the class alias)
mod = importlib.import_module("render.df.diffuse_reflection_bsdf")


def _kernel(**kw):
    return lambda: KernelBsdf(mod, Lobe.DIFFUSE_REFLECTION, **kw)


CASES = [
    DfCase("lambert", _kernel(), "diffuse", lossless=True),
    DfCase("lambert-color", _kernel(tint=[0.9, 0.5, 0.0]), "diffuse"),
    DfCase("black", _kernel(tint=0.0), "diffuse"),
    DfCase("on-1e-7", _kernel(roughness=1e-7), "diffuse"),
    DfCase("on-0.5", _kernel(roughness=0.5), "diffuse"),
    DfCase("on-1", _kernel(roughness=1.0), "diffuse"),
    DfCase("eon-1-white", _kernel(roughness=1.0, multiscatter_tint=1.0), "diffuse",
           lossless=True),
    DfCase("eon-0.3-color", _kernel(roughness=0.3, tint=[0.8, 0.2, 0.5],
                                    multiscatter_tint=[0.1, 0.9, 0.4]), "diffuse"),
    DfCase("ms-only", _kernel(roughness=0.7, tint=0.0, multiscatter_tint=1.0), "diffuse"),
]


def test_signature_matches_the_mdl_declaration():
    from render.material import DF_SIGNATURES

    kind, params = DF_SIGNATURES["diffuse_reflection_bsdf"]
    assert mod.SIGNATURE.kind == kind
    assert [p.name for p in mod.SIGNATURE.params] == [p[0] for p in params]
    assert [p.default for p in mod.SIGNATURE.params] == [p[2] for p in params]
    assert mod.SIGNATURE.width == 7
    row = pack(mod.SIGNATURE, tint=[1.5, -1.0, 0.5], roughness=3.0)
    assert row.tolist() == [[1.0, 0.0, 0.5, 1.0, 0.0, 0.0, 0.0]]


@pytest.mark.parametrize("fixed", [
    {},
    {"roughness": 0.0, "multiscatter_tint": 0.0},
    {"roughness": 1e-7},
    {"roughness": 1.0, "multiscatter_tint": 1.0, "tint": 1.0},
    {"tint": 0.0, "multiscatter_tint": 0.0},
    {"tint": 0.0, "roughness": 0.5},
], ids=["random", "lambert", "r1e-7", "eon-white", "black", "ms-only"])
def test_kernels_equal_numpy_over_random_lanes(fixed, rng):
    wo = lane_dirs(rng, 6000)
    wi = lane_dirs(rng, 6000)[rng.permutation(len(wo))]
    n = len(wo)
    u1, u2 = lane_us(rng, n)
    args = {
        "tint": rng.uniform(-0.2, 1.2, (n, 3)),
        "roughness": np.where(rng.random(n) < 0.2, 0.0, rng.uniform(-0.1, 1.1, n)),
        "multiscatter_tint": np.where(rng.random((n, 1)) < 0.3, 0.0,
                                      rng.uniform(-0.1, 1.1, (n, 3))),
    }
    args.update(fixed)
    ref = diffuse_reflection_bsdf(**args)
    ker = KernelBsdf(mod, Lobe.DIFFUSE_REFLECTION, n=n, **args)
    # bit for bit: the same IEEE operations in the same order (numpy's arctan2 in G(theta)
    # is libm's on this machine; a SIMD arctan2 elsewhere could differ in the last bit)
    compare_bsdf(ref, ker, wo, wi, u1, u2, rtol=0.0)


@pytest.mark.parametrize("case", CASES, ids=case_ids(CASES))
def test_consistency(case, rng):
    check_consistency(case, rng)


@pytest.mark.parametrize("case", CASES, ids=case_ids(CASES))
def test_no_nan_or_negative(case, rng):
    check_no_nan(case, rng)


@pytest.mark.parametrize("case", CASES, ids=case_ids(CASES))
def test_reciprocity(case, rng):
    check_reciprocity(case, rng)


_CHI2 = per_wo(CASES, CHI2_WOS, only=lambda c: c.id in ("lambert", "on-1", "eon-0.3-color"))


@pytest.mark.parametrize(("case", "wo"), _CHI2, ids=pair_ids(_CHI2))
def test_chi2(case, wo):
    check_chi2(case, wo, test_count=len(_CHI2))


_INT = per_wo(CASES, WOS)


@pytest.mark.parametrize(("case", "wo"), _INT, ids=pair_ids(_INT))
def test_furnace_albedo_and_pdf_integral(case, wo):
    check_integrals(case, wo)
