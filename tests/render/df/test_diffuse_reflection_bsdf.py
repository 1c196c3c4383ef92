"""df::diffuse_reflection_bsdf: Lambert and Fujii's Oren–Nayar, with the full df checklist."""

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
    check_reciprocity,
    pair_ids,
    per_wo,
)

from render.df import diffuse_reflection_bsdf
from render.df.diffuse_reflection_bsdf import oren_nayar_albedo
from render.testing import direction

# the Oren–Nayar lobe's retro-reflection peak at grazing limits the quadrature to ~3e-4
CASES = [
    DfCase("lambert-white", lambda: diffuse_reflection_bsdf(), "diffuse", lossless=True),
    DfCase("lambert-black", lambda: diffuse_reflection_bsdf(tint=0.0), "diffuse"),
    DfCase("lambert-color", lambda: diffuse_reflection_bsdf(tint=[0.2, 0.5, 0.9]), "diffuse"),
    DfCase("on-tiny", lambda: diffuse_reflection_bsdf(roughness=1e-7), "diffuse", albedo_tol=1e-6),
    DfCase("on-0.3", lambda: diffuse_reflection_bsdf(roughness=0.3), "diffuse", albedo_tol=3e-4),
    DfCase("on-1", lambda: diffuse_reflection_bsdf(roughness=1.0), "diffuse", albedo_tol=3e-4),
    DfCase(
        "on-1-multiscatter",
        lambda: diffuse_reflection_bsdf(roughness=1.0, multiscatter_tint=1.0),
        "diffuse",
        lossless=True,
        albedo_tol=3e-4,
    ),
]
# every case samples the cosine lobe: Lambert at all four directions, Oren–Nayar at two
CHI2 = per_wo(CASES, CHI2_WOS, only=lambda c: c.id == "lambert-white")
CHI2 += per_wo(CASES, CHI2_WOS[2:], only=lambda c: c.id in ("on-1", "on-1-multiscatter"))


@pytest.mark.parametrize("case", CASES, ids=case_ids(CASES))
def test_consistency(case, rng):
    check_consistency(case, rng)


@pytest.mark.parametrize("case", CASES, ids=case_ids(CASES))
def test_no_nan_or_negative(case, rng):
    check_no_nan(case, rng)


@pytest.mark.parametrize("case", CASES, ids=case_ids(CASES))
def test_reciprocity(case, rng):
    check_reciprocity(case, rng)


@pytest.mark.parametrize(("case", "wo"), CHI2, ids=pair_ids(CHI2))
def test_chi2(case, wo):
    check_chi2(case, wo, test_count=len(CHI2))


@pytest.mark.parametrize(("case", "wo"), per_wo(CASES), ids=pair_ids(per_wo(CASES)))
def test_pdf_furnace_and_albedo(case, wo):
    check_integrals(case, wo)


# --- closed forms worked out by hand --------------------------------------------------------


def test_lambert_value():
    b = diffuse_reflection_bsdf(tint=[1.0, 0.5, 0.25])
    wo = np.array([[0.0, 0.0, 1.0]])
    wi = np.array([[0.8, 0.0, 0.6]])
    # f cos = tint / pi * 0.6
    assert np.allclose(b.eval(wo, wi), np.array([[0.6, 0.3, 0.15]]) / np.pi, rtol=1e-15)
    assert np.isclose(b.pdf(wo, wi)[0], 0.6 / np.pi, rtol=1e-15)


def test_oren_nayar_value_by_hand():
    # sigma = 1: A = 1/(1 + 1/2 - 2/(3 pi)) = 0.7765220670..., B = A.  wo at 60 deg and wi at
    # 30 deg in the same azimuth: s = cos 30 - cos 60 cos 30 = 0.4330127, divided by
    # max(cos 60, cos 30) = 0.8660254 -> s = 0.5;  eval = (A + B/2)/pi * cos 30.
    b = diffuse_reflection_bsdf(roughness=1.0)
    e = b.eval(direction(60.0)[None], direction(30.0)[None])[0, 0]
    assert e == pytest.approx(0.7765220670 * 1.5 / np.pi * np.cos(np.pi / 6), rel=1e-9)
    # opposite azimuths: s = -sin 60 sin 30 = -0.4330127 (not divided): A (1 - 0.4330127)
    e = b.eval(direction(60.0)[None], direction(30.0, 180.0)[None])[0, 0]
    assert e == pytest.approx(
        0.7765220670 * (1 - 0.4330127019) / np.pi * np.cos(np.pi / 6), rel=1e-9
    )


def test_albedo_closed_form_limits():
    mu = np.array([0.0, 1e-12, 0.5, 1.0])
    # rho(0) = 1 for every roughness (the grazing limit of the tan term is -2/3)
    assert oren_nayar_albedo(mu[:1], 0.7)[0] == pytest.approx(1.0, abs=1e-15)
    assert oren_nayar_albedo(mu[1:2], 0.7)[0] == pytest.approx(1.0, abs=1e-11)
    # rho(1) = A
    assert oren_nayar_albedo(mu[3:], 1.0)[0] == pytest.approx(
        1 / (1.5 - 2 / (3 * np.pi)), rel=1e-14
    )
    assert np.all(oren_nayar_albedo(mu, 0.0) == 1.0)
    # the cosine-weighted average is rho_avg = A + (2/3 - 28/(15 pi)) B
    x, w = np.polynomial.legendre.leggauss(200)
    m = 0.5 * (x + 1)
    avg = np.sum(w * 0.5 * 2 * m * oren_nayar_albedo(m, 1.0))
    a = 1 / (1.5 - 2 / (3 * np.pi))
    assert avg == pytest.approx(a + (2 / 3 - 28 / (15 * np.pi)) * a, rel=1e-10)


def test_multiscatter_makes_white_lossless():
    b = diffuse_reflection_bsdf(roughness=np.array([0.2, 0.6, 1.0]), multiscatter_tint=1.0)
    wo = np.stack([direction(0.0), direction(70.0), direction(89.9)])
    assert np.allclose(b.albedo(wo), 1.0, atol=1e-14)


def test_roughness_zero_is_lambert_and_multiscatter_vanishes(rng):
    wo, wi = rng.normal(size=(2, 500, 3))
    wo /= np.linalg.norm(wo, axis=1, keepdims=True)
    wi /= np.linalg.norm(wi, axis=1, keepdims=True)
    a = diffuse_reflection_bsdf(tint=0.7).eval(wo, wi)
    b = diffuse_reflection_bsdf(tint=0.7, roughness=0.0, multiscatter_tint=1.0).eval(wo, wi)
    assert np.array_equal(a, b)


def test_tint_is_saturated_and_lanes_broadcast():
    wo = np.array([[0.0, 0.0, 1.0]] * 3)
    wi = np.array([[0.0, 0.6, 0.8]] * 3)
    b = diffuse_reflection_bsdf(
        tint=np.array([[2.0, -1.0, 0.5], [1, 1, 1], [0, 0, 0]]), roughness=np.array([0.0, 0.5, 1.0])
    )
    e = b.eval(wo, wi)
    assert np.allclose(e[0], np.array([1.0, 0.0, 0.5]) * 0.8 / np.pi)
    single = diffuse_reflection_bsdf(roughness=0.5).eval(wo[:1], wi[:1])
    assert np.array_equal(e[1], single[0])
    assert not np.any(e[2])


def test_bad_arguments():
    with pytest.raises(ValueError, match="tint must be"):
        diffuse_reflection_bsdf(tint=[1.0, 0.5])
    with pytest.raises(ValueError, match="roughness must be a number or one number per lane"):
        diffuse_reflection_bsdf(roughness=np.zeros((2, 2)))
    with pytest.raises(
        ValueError, match="holds 2 per-lane values but the call has 3 lanes"
    ):
        diffuse_reflection_bsdf(roughness=np.zeros(2)).eval(np.ones((3, 3)), np.ones((3, 3)))
    with pytest.raises(ValueError, match=r"wi must have shape \(n, 3\)"):
        diffuse_reflection_bsdf().eval(np.ones((3, 3)), np.ones(3))
    with pytest.raises(ValueError, match=r"u2 must have shape \(2, 2\)"):
        diffuse_reflection_bsdf().sample(np.ones((2, 3)), np.zeros(2), np.zeros((2, 3)))
