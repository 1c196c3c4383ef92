"""df::diffuse_transmission_bsdf: Lambertian transmission, with the full df checklist."""

from __future__ import annotations

import numpy as np
import pytest
from render_df_cases import (
    CHI2_WOS,
    DfCase,
    case_ids,
    check_chi2,
    check_consistency,
    check_integrals,
    check_no_nan,
    pair_ids,
    per_wo,
    random_dirs,
)

from render.df import diffuse_transmission_bsdf

CASES = [
    DfCase("white", lambda: diffuse_transmission_bsdf(), "diffuse", lossless=True, transmits=True),
    DfCase("black", lambda: diffuse_transmission_bsdf(tint=0.0), "diffuse", transmits=True),
    DfCase(
        "color", lambda: diffuse_transmission_bsdf(tint=[0.9, 0.4, 0.1]), "diffuse", transmits=True
    ),
]
CHI2 = per_wo(CASES[:1], CHI2_WOS)


@pytest.mark.parametrize("case", CASES, ids=case_ids(CASES))
def test_consistency(case, rng):
    check_consistency(case, rng)


@pytest.mark.parametrize("case", CASES, ids=case_ids(CASES))
def test_no_nan_or_negative(case, rng):
    check_no_nan(case, rng)


@pytest.mark.parametrize(("case", "wo"), CHI2, ids=pair_ids(CHI2))
def test_chi2(case, wo):
    check_chi2(case, wo, test_count=len(CHI2))


@pytest.mark.parametrize(("case", "wo"), per_wo(CASES), ids=pair_ids(per_wo(CASES)))
def test_pdf_furnace_and_albedo(case, wo):
    check_integrals(case, wo)


def test_value_and_sides():
    b = diffuse_transmission_bsdf(tint=0.5)
    wo = np.array([[0.0, 0.0, 1.0], [0.0, 0.0, -1.0], [0.0, 0.0, 1.0]])
    wi = np.array([[0.6, 0.0, -0.8], [0.6, 0.0, 0.8], [0.6, 0.0, 0.8]])
    assert np.allclose(b.eval(wo, wi)[:, 0], [0.5 * 0.8 / np.pi, 0.5 * 0.8 / np.pi, 0.0])
    assert np.allclose(b.pdf(wo, wi), [0.8 / np.pi, 0.8 / np.pi, 0.0])


def test_symmetric_under_swap(rng):
    # f(wo, wi) = tint/pi on opposite sides: the transmission lobe is reciprocal too
    b = diffuse_transmission_bsdf(tint=[0.3, 0.6, 0.9])
    wo = random_dirs(rng, 1000)
    wi = random_dirs(rng, 1000)
    wi[:, 2] = -np.abs(wi[:, 2]) * np.sign(wo[:, 2])
    f1 = b.eval(wo, wi) / np.abs(wi[:, 2:3])
    f2 = b.eval(wi, wo) / np.abs(wo[:, 2:3])
    assert np.allclose(f1, f2, rtol=1e-13) and np.allclose(f1, np.array([0.3, 0.6, 0.9]) / np.pi)


def test_sample_goes_to_the_far_side(rng):
    b = diffuse_transmission_bsdf()
    wo = random_dirs(rng, 1000)
    s = b.sample(wo, rng.random(1000), rng.random((1000, 2)))
    assert np.all(s.wi[s.valid, 2] * wo[s.valid, 2] < 0)
    assert s.valid.mean() > 0.999
