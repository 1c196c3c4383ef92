"""df::weighted_layer and df::color_weighted_layer: the checklist, extreme weights, own normal."""

from __future__ import annotations

import numpy as np
import pytest
from render_combiner_cases import (
    JUMP_ALBEDO_TOL,
    CombinerCase,
    check_chi2_combined,
    check_integrals_combined,
    check_no_nan_combined,
    two_wos,
)
from render_df_cases import (
    CHI2_WOS,
    case_ids,
    check_consistency,
    check_reciprocity,
    pair_ids,
    per_wo,
    random_dirs,
)

from render.bsdf import Lobe
from render.df import _kernel_common as kc
from render.df import (
    color_weighted_layer,
    diffuse_reflection_bsdf,
    diffuse_transmission_bsdf,
    simple_glossy_bsdf,
    specular_bsdf,
    weighted_layer,
)
from render.testing import direction, sample_lanes, tile

D, T, G, S = diffuse_reflection_bsdf, diffuse_transmission_bsdf, simple_glossy_bsdf, specular_bsdf
TAB = 3e-3  # the glossy children's tabulated albedo
TILT = np.array([0.3, 0.2, 0.93]) / np.linalg.norm([0.3, 0.2, 0.93])


def _reflect(k, m):
    """Rows of ``k`` mirrored about the unit rows ``m`` (``kc.reflect``, a row at a time)."""
    return np.array([kc.reflect(*a, *b) for a, b in zip(k, m, strict=True)])


def shiny_red(weight=0.5):
    """Handbook Listing 6.1 (shiny_red)."""
    return weighted_layer(
        weight=weight,
        layer=G(roughness_u=0.08, tint=0.15),
        base=D(tint=(0.3, 0.03, 0.05)),
    )


CASES = [
    CombinerCase("shiny-red", shiny_red, "glossy", albedo_tol=TAB),
    CombinerCase(
        "white-r-over-t",
        lambda: weighted_layer(0.3, T(), D()),
        "glossy",
        lossless=True,
        transmits=True,
        reciprocal=False,
    ),
    CombinerCase("w0", lambda: weighted_layer(0.0, G(roughness_u=0.3), D(tint=0.5)), "glossy"),
    CombinerCase(
        "w1", lambda: weighted_layer(1.0, G(roughness_u=0.3), D()), "glossy", albedo_tol=TAB
    ),
    CombinerCase("mirror-over-lambert", lambda: weighted_layer(0.3, S(), D()), "glossy",
                 lossless=True),
    CombinerCase(
        "own-normal",
        lambda: weighted_layer(0.5, G(roughness_u=0.4), D(), normal=TILT),
        "glossy",
        reciprocal=False,
        albedo_tol=JUMP_ALBEDO_TOL,
        quad_tol=3e-3,
    ),
    CombinerCase(
        "own-normal-mirror",
        lambda: weighted_layer(0.6, S(), D(tint=0.5), normal=TILT),
        "glossy",
        reciprocal=False,
        albedo_tol=JUMP_ALBEDO_TOL,
    ),
    CombinerCase(
        "color",
        lambda: color_weighted_layer((1.0, 0.5, 0.0), G(roughness_u=0.3), D(tint=(0.2, 0.9, 0.4))),
        "glossy",
        albedo_tol=TAB,
    ),
    CombinerCase("no-children", lambda: weighted_layer(0.5), "glossy"),
]
CHI2 = per_wo(CASES, CHI2_WOS[1:2], only=lambda c: c.id == "shiny-red")
CHI2 += per_wo(CASES, CHI2_WOS[2:3], only=lambda c: c.id == "own-normal")
INTEGRALS = two_wos(CASES)


@pytest.mark.parametrize("case", CASES, ids=case_ids(CASES))
def test_consistency(case, rng):
    check_consistency(case, rng)


@pytest.mark.parametrize("case", CASES, ids=case_ids(CASES))
def test_no_nan_or_negative(case, rng):
    check_no_nan_combined(case, rng)


@pytest.mark.parametrize("case", [c for c in CASES if c.reciprocal], ids=case_ids(
    [c for c in CASES if c.reciprocal]))
def test_reciprocity(case, rng):
    check_reciprocity(case, rng)


@pytest.mark.parametrize(("case", "wo"), CHI2, ids=pair_ids(CHI2))
def test_chi2(case, wo):
    check_chi2_combined(case, wo, test_count=len(CHI2))


@pytest.mark.parametrize(("case", "wo"), INTEGRALS, ids=pair_ids(INTEGRALS))
def test_pdf_furnace_and_albedo(case, wo):
    check_integrals_combined(case, wo)


# --- values worked out by hand ----------------------------------------------------------------


def _pairs(rng, n=4000):
    wo = random_dirs(rng, n)
    wi = random_dirs(rng, n)
    return wo, wi


def test_eval_is_the_weighted_sum(rng):
    wo, wi = _pairs(rng)
    layer, base = G(roughness_u=0.3, tint=(0.9, 0.6, 0.3)), D(tint=(0.2, 0.4, 0.8))
    for w in (0.0, 0.25, 1.0):
        wl = weighted_layer(w, layer, base)
        expect = w * layer.eval(wo, wi) + (1 - w) * base.eval(wo, wi)
        assert np.allclose(wl.eval(wo, wi), expect, rtol=1e-14, atol=0)
    # weights outside [0, 1] saturate: the cases w0 and w1 cover them
    assert np.array_equal(weighted_layer(7.0, layer, base).eval(wo, wi), layer.eval(wo, wi))
    assert np.array_equal(weighted_layer(-2.0, layer, base).eval(wo, wi), base.eval(wo, wi))
    # colour weights act per channel
    cl = color_weighted_layer((1.0, 0.5, 0.0), layer, base)
    e = cl.eval(wo, wi)
    assert np.allclose(e[:, 0], layer.eval(wo, wi)[:, 0], rtol=1e-14)
    assert np.allclose(e[:, 2], base.eval(wo, wi)[:, 2], rtol=1e-14)


def test_extreme_weights_sample_only_the_live_child(rng):
    wo = tile(direction(40.0, 10.0), 5000)
    u1, u2 = rng.random(5000), rng.random((5000, 2))
    # weight 0: every sample is the base's (diffuse), weight 1: every sample the mirror's
    s0 = weighted_layer(0.0, S(), D()).sample(wo, u1, u2)
    assert np.all(s0.lobe[s0.valid] == int(Lobe.DIFFUSE_REFLECTION)) and s0.valid.mean() > 0.99
    s1 = weighted_layer(1.0, S(), D()).sample(wo, u1, u2)
    assert np.all(s1.lobe == int(Lobe.SPECULAR_REFLECTION))
    assert np.allclose(s1.weight, 1.0, rtol=1e-15) and np.allclose(s1.pdf, 1.0)


def test_per_lane_weights():
    wo = np.stack([direction(0.0), direction(60.0)])
    wl = weighted_layer(np.array([0.2, 0.9]), S(tint=1.0), D(tint=0.0))
    assert np.allclose(wl.albedo(wo), [[0.2] * 3, [0.9] * 3], rtol=1e-14)
    with pytest.raises(ValueError, match="2 per-lane values but the call has 3 lanes"):
        wl.albedo(np.stack([direction(0.0)] * 3))


def test_own_normal_mirror_reflects_about_that_normal(rng):
    # a mirror layer with its own normal n reflects wo about n; the base keeps +z
    wl = weighted_layer(1.0, S(), None, normal=TILT)
    wo = tile(direction(20.0, 30.0), 100)
    s = wl.sample(wo, rng.random(100), rng.random((100, 2)))
    expect = _reflect(wo, tile(TILT, 100))
    assert np.all(s.valid)
    assert np.allclose(s.wi, expect, atol=1e-12)
    # where wo lies below the layer's tangent plane (but above the inherited one) the layer
    # contributes nothing
    below = np.cross(TILT, [0.0, 1.0, 0.0])
    below = below / np.linalg.norm(below)
    below = below * np.sign(below[2]) if below[2] != 0 else below
    wo_b = np.array([[-0.99, 0.0, 0.141]])
    assert (wo_b @ TILT)[0] < 0 < wo_b[0, 2]
    sb = wl.sample(wo_b / np.linalg.norm(wo_b), np.array([0.3]), np.array([[0.5, 0.5]]))
    assert not sb.valid[0]
    assert np.all(wl.albedo(wo_b / np.linalg.norm(wo_b)) == 0.0)


def test_own_normal_glossy_peaks_at_the_tilted_mirror_direction():
    wl = weighted_layer(1.0, G(roughness_u=0.05), None, normal=TILT)
    wo = direction(25.0, 200.0)
    s = sample_lanes(wl, wo, 20_000, seed=3)
    peak = _reflect(wo[None], TILT[None])[0]
    cos = s.wi[s.valid] @ peak
    assert np.median(cos) > 0.995


def test_errors():
    with pytest.raises(ValueError, match=r"\(layer\) must be a bound bsdf"):
        weighted_layer(0.5, layer="diffuse")
    with pytest.raises(ValueError, match="normal must be a non-zero vector"):
        weighted_layer(0.5, D(), normal=(0.0, 0.0, 0.0))
    with pytest.raises(ValueError, match="weight must be finite"):
        weighted_layer(np.nan, D())
    with pytest.raises(ValueError, match="weight must be a number or one number per lane"):
        weighted_layer([[0.5]], D())
