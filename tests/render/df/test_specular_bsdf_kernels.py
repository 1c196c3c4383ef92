"""df::specular_bsdf kernels: equal to the numpy class in every mode, and the checklist on them."""

from __future__ import annotations

import importlib

import numpy as np
import pytest
from df_kernel_adapter import KernelBsdf, compare_bsdf, lane_dirs, lane_us, pack
from render_df_cases import (
    WOS,
    DfCase,
    case_ids,
    check_consistency,
    check_integrals,
    check_no_nan,
    pair_ids,
    per_wo,
)

from render.bsdf import Lobe
from render.df import specular_bsdf
from render.numerics import fresnel_dielectric
from render.testing import direction, sample_lanes

mod = importlib.import_module("render.df.specular_bsdf")
MODES = ("scatter_reflect", "scatter_transmit", "scatter_reflect_transmit")
_LOBES = {"scatter_reflect": Lobe.SPECULAR_REFLECTION, "scatter_transmit": Lobe.SPECULAR,
          "scatter_reflect_transmit": Lobe.SPECULAR}


def _kernel(mode, ior=1.0, thin=False, **kw):
    return lambda: KernelBsdf(mod, _LOBES[mode], mode=mode, thin_walled=thin, ior_inside=ior,
                              **kw)


CASES = [
    DfCase("reflect", _kernel("scatter_reflect"), "delta", lossless=True),
    DfCase("reflect-color", _kernel("scatter_reflect", tint=[0.9, 0.5, 0.1]), "delta"),
    DfCase("reflect-black", _kernel("scatter_reflect", tint=0.0), "delta"),
    *(DfCase(f"{m[8:]}-{ior:g}{'-thin' if thin else ''}", _kernel(m, ior, thin), "delta",
             lossless=True)
      for m in MODES[1:] for ior in (1.0, 1.0001, 1.5, 3.0) for thin in (False, True)),
]


def test_signature():
    sig = mod.SIGNATURE
    assert [p.name for p in sig.params] == ["tint", "mode", "handle"]
    assert sig.context == ("ior_outside", "ior_inside") and sig.width == 5
    assert pack(sig, tint=0.5, ior_inside=1.5).tolist() == [[0.5, 0.5, 0.5, 1.0, 1.5]]


@pytest.mark.parametrize("thin", [False, True], ids=["solid", "thin"])
@pytest.mark.parametrize("mode", MODES)
@pytest.mark.parametrize("iors", ["random", (1.0, 1.0), (1.0, 1.0001), (1.0, 3.0), (1.5, 1.0),
                                  (1.33, 1.33)])
def test_kernels_equal_numpy_over_random_lanes(iors, mode, thin, rng):
    wo = lane_dirs(rng, 5000)
    n = len(wo)
    wi = -wo
    u1, u2 = lane_us(rng, n)
    if iors == "random":
        ior_o = np.where(rng.random(n) < 0.5, 1.0, rng.uniform(0.5, 3.0, n))
        ior_i = np.where(rng.random(n) < 0.2, ior_o, rng.uniform(0.5, 3.0, n))
    else:
        ior_o, ior_i = iors
    tint = np.where(rng.random((n, 1)) < 0.1, 0.0, rng.uniform(-0.2, 1.2, (n, 3)))
    ref = specular_bsdf(tint=tint, mode=mode, ior_outside=ior_o, ior_inside=ior_i,
                        thin_walled=thin)
    ker = KernelBsdf(mod, _LOBES[mode], mode=mode, thin_walled=thin, n=n, tint=tint,
                     ior_outside=ior_o, ior_inside=ior_i)
    compare_bsdf(ref, ker, wo, wi, u1, u2, rtol=0.0)


@pytest.mark.parametrize("case", CASES, ids=case_ids(CASES))
def test_consistency(case, rng):
    check_consistency(case, rng)


@pytest.mark.parametrize("case", CASES, ids=case_ids(CASES))
def test_no_nan_or_negative(case, rng):
    check_no_nan(case, rng)


_INT = per_wo(CASES, WOS)


@pytest.mark.parametrize(("case", "wo"), _INT, ids=pair_ids(_INT))
def test_furnace_and_albedo(case, wo):
    check_integrals(case, wo)


@pytest.mark.parametrize("eta", [1.0001, 1.5, 3.0])
@pytest.mark.parametrize("theta", [0.0, 30.0, 75.0, 89.9])
def test_refraction_obeys_snell(eta, theta):
    wo = direction(theta, 40.0)
    s = sample_lanes(_kernel("scatter_transmit", eta)(), wo, 10)
    assert np.all(s.lobe == Lobe.SPECULAR_TRANSMISSION) and np.all(s.pdf == 1.0)
    sin_i, sin_t = np.hypot(*wo[:2]), np.hypot(*s.wi[0, :2])
    assert sin_i == pytest.approx(eta * sin_t, abs=1e-14) and s.wi[0, 2] < 0
    assert np.dot(wo[:2], s.wi[0, :2]) <= 0


def test_total_internal_reflection_and_exact_index_match():
    wo = direction(120.0, 10.0)  # inside glass: sin 60 * 1.5 > 1
    for mode in MODES[1:]:
        s = sample_lanes(_kernel(mode, 1.5)(), wo, 1000)
        assert np.all(s.lobe == Lobe.SPECULAR_REFLECTION) and np.all(s.pdf == 1.0)
        assert np.allclose(s.wi, [-wo[0], -wo[1], wo[2]])
    s = sample_lanes(_kernel("scatter_reflect_transmit", 1.0)(), direction(0.0), 1000)
    assert np.all(s.lobe == Lobe.SPECULAR_TRANSMISSION) and np.all(s.wi == [0.0, 0.0, -1.0])


@pytest.mark.parametrize("theta", [0.0, 70.0, 89.9])
def test_reflect_transmit_splits_by_fresnel(theta):
    n = 200_000
    wo = direction(theta, 20.0)
    F = float(fresnel_dielectric(np.array([wo[2]]), 1.5)[0][0])
    s = sample_lanes(_kernel("scatter_reflect_transmit", 1.5)(), wo, n, seed=3)
    refl = s.lobe == Lobe.SPECULAR_REFLECTION
    assert abs(refl.mean() - F) <= 4 * np.sqrt(F * (1 - F) / n)
    assert np.allclose(s.pdf[refl], F) and np.allclose(s.pdf[~refl], 1 - F)
    assert np.all(s.weight == 1.0)


def test_non_positive_ior_scatters_nothing(rng):
    wo = lane_dirs(rng, 100)
    u1, u2 = lane_us(rng, len(wo))
    for ior in (0.0, -1.5):
        s = KernelBsdf(mod, Lobe.SPECULAR, mode="scatter_transmit", ior_inside=ior).sample(
            wo, u1, u2)
        assert not np.any(s.lobe) and not np.any(s.wi) and not np.any(s.pdf)
