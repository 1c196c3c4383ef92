"""df::specular_bsdf in its three scatter modes: directions, Fresnel split, checklist."""

from __future__ import annotations

import numpy as np
import pytest
from render_df_cases import (
    WOS,
    DfCase,
    case_ids,
    check_consistency,
    check_integrals,
    check_no_nan,
    pair_ids,
    per_wo,
    random_dirs,
)

from render.bsdf import Lobe
from render.df import specular_bsdf
from render.df._kernel_common import fresnel_dielectric
from render.testing import direction, sample_lanes, tile


def _spec(mode, ior=1.0, **kw):
    return lambda: specular_bsdf(mode=mode, ior_inside=ior, **kw)


CASES = [
    DfCase("reflect", _spec("scatter_reflect"), "delta", lossless=True),
    DfCase("reflect-color", _spec("scatter_reflect", tint=[0.9, 0.5, 0.1]), "delta"),
    DfCase("reflect-black", _spec("scatter_reflect", tint=0.0), "delta"),
    DfCase("transmit-1.5", _spec("scatter_transmit", 1.5), "delta", lossless=True),
    DfCase("transmit-1.0", _spec("scatter_transmit", 1.0), "delta", lossless=True),
    DfCase("transmit-1.0001", _spec("scatter_transmit", 1.0001), "delta", lossless=True),
    DfCase("transmit-3", _spec("scatter_transmit", 3.0), "delta", lossless=True),
    DfCase("rt-1.5", _spec("scatter_reflect_transmit", 1.5), "delta", lossless=True),
    DfCase("rt-1.0", _spec("scatter_reflect_transmit", 1.0), "delta", lossless=True),
    DfCase("rt-1.0001", _spec("scatter_reflect_transmit", 1.0001), "delta", lossless=True),
    DfCase("rt-3", _spec("scatter_reflect_transmit", 3.0), "delta", lossless=True),
    DfCase(
        "rt-1.5-thin",
        _spec("scatter_reflect_transmit", 1.5, thin_walled=True),
        "delta",
        lossless=True,
    ),
    DfCase(
        "transmit-thin", _spec("scatter_transmit", 1.5, thin_walled=True), "delta", lossless=True
    ),
]


@pytest.mark.parametrize("case", CASES, ids=case_ids(CASES))
def test_consistency(case, rng):
    check_consistency(case, rng)


@pytest.mark.parametrize("case", CASES, ids=case_ids(CASES))
def test_no_nan_or_negative(case, rng):
    check_no_nan(case, rng)


@pytest.mark.parametrize(("case", "wo"), per_wo(CASES), ids=pair_ids(per_wo(CASES)))
def test_pdf_furnace_and_albedo(case, wo):
    check_integrals(case, wo)


@pytest.mark.parametrize("theta_phi", WOS)
def test_reflect_is_the_mirror_direction(theta_phi, rng):
    wo = direction(*theta_phi)
    s = sample_lanes(specular_bsdf(tint=[0.2, 0.4, 0.8]), wo, 100)
    assert np.all(s.lobe == Lobe.SPECULAR_REFLECTION) and np.all(s.pdf == 1.0)
    assert np.allclose(s.wi, [-wo[0], -wo[1], wo[2]], atol=1e-15)
    assert np.allclose(s.weight, [0.2, 0.4, 0.8])


@pytest.mark.parametrize("eta", [1.0001, 1.5, 3.0])
@pytest.mark.parametrize("theta", [0.0, 30.0, 75.0, 89.9])
def test_refraction_obeys_snell(eta, theta):
    wo = direction(theta, 40.0)
    s = sample_lanes(specular_bsdf(mode="scatter_transmit", ior_inside=eta), wo, 10)
    assert np.all(s.lobe == Lobe.SPECULAR_TRANSMISSION) and np.all(s.pdf == 1.0)
    wi = s.wi[0]
    sin_i, sin_t = np.hypot(*wo[:2]), np.hypot(*wi[:2])
    assert sin_i == pytest.approx(eta * sin_t, abs=1e-14)
    assert wi[2] < 0 and np.allclose(
        np.cross(wo[:2].tolist() + [0], wi[:2].tolist() + [0]), 0, atol=1e-15
    )
    assert np.dot(wo[:2], wi[:2]) <= 0  # the transmitted ray continues across the normal


def test_total_internal_reflection_from_inside():
    # inside glass (wo below, ior 1.5 inside): sin 60 * 1.5 > 1, so everything reflects
    wo = direction(180.0 - 60.0, 10.0)
    for mode in ("scatter_transmit", "scatter_reflect_transmit"):
        s = sample_lanes(specular_bsdf(mode=mode, ior_inside=1.5), wo, 1000)
        assert np.all(s.lobe == Lobe.SPECULAR_REFLECTION) and np.all(s.pdf == 1.0)
        assert np.allclose(s.wi, [-wo[0], -wo[1], wo[2]])
    # below the critical angle light leaves: sin 30 * 1.5 = 0.75 = sin(theta_t)
    s = sample_lanes(specular_bsdf(mode="scatter_transmit", ior_inside=1.5), direction(150.0), 10)
    assert np.hypot(*s.wi[0, :2]) == pytest.approx(0.75, abs=1e-14) and s.wi[0, 2] > 0


@pytest.mark.parametrize(("eta", "F0"), [(1.5, 0.04), (3.0, 0.25), (1.0, 0.0)])
def test_reflect_transmit_splits_by_fresnel(eta, F0):
    n = 200_000
    s = sample_lanes(
        specular_bsdf(mode="scatter_reflect_transmit", ior_inside=eta), direction(0.0), n
    )
    refl = s.lobe == Lobe.SPECULAR_REFLECTION
    # normal incidence: F = ((eta - 1)/(eta + 1))^2, the sample pdf is the event's probability
    assert np.allclose(s.pdf[refl], F0) and np.allclose(s.pdf[~refl], 1 - F0)
    assert abs(refl.mean() - F0) <= 4 * np.sqrt(F0 * (1 - F0) / n) + 1e-12
    assert np.all(s.weight == 1.0)
    if eta == 1.0:  # exact index match: straight through, no bend, no reflection
        assert np.array_equal(s.wi, tile([0.0, 0.0, -1.0], n))


def test_oblique_fresnel_fraction():
    n = 200_000
    wo = direction(70.0, 20.0)
    F = fresnel_dielectric(float(wo[2]), 1.5)[0]
    s = sample_lanes(specular_bsdf(mode="scatter_reflect_transmit", ior_inside=1.5), wo, n, seed=3)
    refl = s.lobe == Lobe.SPECULAR_REFLECTION
    assert abs(refl.mean() - F) <= 4 * np.sqrt(F * (1 - F) / n)
    assert np.allclose(s.pdf[refl], F)


def test_thin_walled_passes_straight_through(rng):
    wo = random_dirs(rng, 1000)
    s = specular_bsdf(mode="scatter_transmit", ior_inside=1.5, thin_walled=True).sample(
        wo, rng.random(1000), rng.random((1000, 2))
    )
    assert np.array_equal(s.wi[s.valid], -wo[s.valid])
    assert np.all(s.lobe[s.valid] == Lobe.SPECULAR_TRANSMISSION)


def test_eval_and_pdf_are_zero(rng):
    b = specular_bsdf(mode="scatter_reflect_transmit", ior_inside=1.5)
    wo = random_dirs(rng, 100)
    wi = wo * [-1, -1, 1]
    assert not np.any(b.eval(wo, wi)) and not np.any(b.pdf(wo, wi))
    assert b.is_delta


def test_bad_mode_and_ior():
    with pytest.raises(ValueError, match="mode must be one of"):
        specular_bsdf(mode="mirror")
    with pytest.raises(ValueError, match="ior_inside must be > 0"):
        specular_bsdf(ior_inside=0.0)
