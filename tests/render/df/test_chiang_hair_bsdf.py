"""df::chiang_hair_bsdf: the fibre model's checks (pbrt's hair tests as a guide): sampling
weights of exactly 1 in a white lossless fibre, the white furnace, chi-square of the
sampler over the whole sphere, the pdf's normalisation, and extremes."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from render_df_cases import DfCase, check_consistency, check_no_nan

from render import df
from render.testing import chi2_test, direction, sample_lanes, sphere_integral

H = df.chiang_hair_bsdf
WOS = ((10.0, 30.0), (60.0, 200.0), (95.0, 80.0), (170.0, 300.0))


def _white(v=0.2, s=0.3, alpha=0.0, ior=1.55):
    return H(roughness_R=(v, s), cuticle_angle=alpha, ior=ior)


CASES = [
    DfCase("white", lambda: _white(), "hair", reciprocal=False),
    DfCase("rough", lambda: _white(0.8, 0.9), "hair", reciprocal=False),
    DfCase("tilted", lambda: _white(0.3, 0.4, alpha=0.05), "hair", reciprocal=False),
    DfCase("brown", lambda: H(roughness_R=(0.1, 0.3), roughness_TT=(0.05, 0.2),
                              roughness_TRT=(0.2, 0.5), absorption_coefficient=(0.4, 0.8, 1.6),
                              cuticle_angle=0.03), "hair", reciprocal=False),
    DfCase("diffuse-mix", lambda: H(diffuse_reflection_weight=0.3,
                                    diffuse_reflection_tint=(0.9, 0.6, 0.3),
                                    roughness_R=(0.3, 0.4)), "hair", reciprocal=False),
    DfCase("smooth", lambda: H(roughness_R=(0.0, 0.0)), "hair", reciprocal=False, chi2=False),
]


@pytest.mark.parametrize("case", CASES, ids=[c.id for c in CASES])
def test_consistency(case, rng):
    check_consistency(case, rng)


@pytest.mark.parametrize("case", CASES, ids=[c.id for c in CASES])
def test_no_nan_or_negative(case, rng):
    check_no_nan(case, rng, surface=False)


CHI2 = [(c, w) for c in CASES if c.chi2 for w in WOS[1:3]]


@pytest.mark.parametrize(("case", "wo"), CHI2, ids=[f"{c.id}-{w[0]:g}" for c, w in CHI2])
def test_chi2(case, wo):
    res = chi2_test(case.make(), direction(*wo), sample_count=200_000, test_count=len(CHI2))
    assert res.passed, f"{case.id} {wo}: {res}"


def _sphere(bsdf, wo):
    def f(w):
        e, p = bsdf.eval_pdf(np.tile(wo, (len(w), 1)), w)
        return np.concatenate([e, p[:, None]], axis=1)

    # rings about the fibre axis: M_p's cones are rings of constant theta about it
    return sum(sphere_integral(f, [1.0, 0.0, 0.0], side, n_beta=256, order=16)
               for side in (+1, -1))


@pytest.mark.parametrize("case", [c for c in CASES if c.id != "smooth"],
                         ids=[c.id for c in CASES if c.id != "smooth"])
@pytest.mark.parametrize("wo", WOS[:3])
def test_pdf_normalised_and_furnace(case, wo):
    b = case.make()
    w = direction(*wo)
    q = _sphere(b, w)
    assert q[3] == pytest.approx(1.0, abs=3e-3), q  # the sampler never fails
    s = sample_lanes(b, w, 100_000)
    assert s.valid.all()
    mean, se = s.weight.mean(axis=0), s.weight.std(axis=0) / np.sqrt(100_000)
    # ∫ eval by quadrature and by Monte Carlo agree
    assert np.allclose(q[:3], mean, atol=4 * se.max() + 3e-3)
    # never more than 1 (pbrt's hair furnace: within [0.95, 1.05]; lossless fibres
    # with an untilted cuticle are exactly 1 but for M_p's tails at the poles)
    assert np.all(mean <= 1.0 + 4 * se + 1e-3)
    if case.id in ("white", "rough"):
        assert np.all(np.abs(mean - 1.0) <= 0.02), mean


@settings(max_examples=40)
@given(st.floats(0.01, 1.0), st.floats(0.01, 1.0), st.floats(-0.2, 0.2), st.floats(1.2, 2.0),
       st.floats(0.0, 180.0), st.floats(0.0, 360.0))
def test_white_fibre_sampling_weights_are_one(v, s, alpha, ior, th, ph):
    # lobes picked by A_p and sampled exactly: f / pdf = sum_p A_p = 1 in a white,
    # non-absorbing fibre, for any roughness, tilt, IOR and direction (pbrt's test)
    b = H(roughness_R=(v, s), cuticle_angle=alpha, ior=ior)
    wo = direction(th, ph)
    smp = sample_lanes(b, wo, 500)
    assert smp.valid.all()
    assert np.allclose(smp.weight, 1.0, rtol=1e-9)
    assert np.allclose(b.albedo(wo[None]), 1.0)


def test_absorption_darkens_the_long_lobes():
    w = direction(60.0, 80.0)
    clear = sample_lanes(_white(), w, 50_000).weight.mean(axis=0)
    dark = sample_lanes(H(roughness_R=(0.2, 0.3), absorption_coefficient=(0.2, 1.0, 4.0)), w,
                        50_000).weight.mean(axis=0)
    assert np.all(dark < clear) and dark[0] > dark[1] > dark[2]


def test_parses_as_a_hair_bsdf():
    from displacement.surfaces import UnitSquare
    from render.expr import evaluate_expression

    v = evaluate_expression("df::chiang_hair_bsdf(roughness_R: float2(0.2, 0.3), "
                            "absorption_coefficient: color(0.2, 0.5, 1.0))")
    assert v.type.name == "hair_bsdf"
    b = v.value.bind(UnitSquare().state_at_uv(np.array([[0.5, 0.5]])))
    assert isinstance(b, df.ChiangHairBsdf)
    assert np.allclose(b.roughness_TRT, [[0.2, 0.3]])  # TRT = TT = R by default


def test_bad_arguments():
    with pytest.raises(ValueError, match="ior must be > 0"):
        H(ior=0.0)
    with pytest.raises(ValueError, match="cuticle_angle must be in"):
        H(cuticle_angle=2.0)
