"""df::backscattering_glossy_reflection_bsdf's compiled kernels: equal to the numpy class
(eval, pdf, samples, albedo) over random lanes and the extremes; chi-square and furnace
on the kernels themselves."""

from __future__ import annotations

import importlib

import numpy as np
import pytest
from glossy_kernel_lanes import KernelLanes, albedo_lanes, eval_lanes, pack, sample_lanes
from render_df_cases import (
    WOS,
    DfCase,
    case_ids,
    check_consistency,
    check_integrals,
    check_no_nan,
    check_reciprocity,
    edge_dirs,
    pair_ids,
    per_wo,
    random_dirs,
)

from render.bsdf import Lobe
from render.df import backscattering_glossy_reflection_bsdf
from render.testing import chi2_test, direction, furnace

K = importlib.import_module("render.df.backscattering_glossy_reflection_bsdf")
TAB, TAB_ANISO = 3e-3, 1e-2

CASES = {
    "r0": dict(roughness_u=0.0),
    "r1e-7": dict(roughness_u=1e-7),
    "r1e-3": dict(roughness_u=1e-3),
    "r0.3-color": dict(roughness_u=0.3, tint=(0.2, 0.5, 0.9)),
    "r1": dict(roughness_u=1.0),
    "black": dict(roughness_u=0.3, tint=0.0),
    "aniso-0.01-1": dict(roughness_u=0.01, roughness_v=1.0, tangent_u=(0.6, 0.8, 0.0)),
    "aniso-0.1-0.5": dict(roughness_u=0.1, roughness_v=0.5, tangent_u=(0.0, 1.0, 0.0)),
    "aniso-tilted-tangent": dict(roughness_u=0.4, roughness_v=0.1, tangent_u=(0.3, -0.2, 0.9)),
    "tangent-along-n": dict(roughness_u=0.3, tangent_u=(0.0, 0.0, 1.0)),
}


def lanes_of(kw):
    row, flags = pack(K.SIGNATURE, **kw)
    return (backscattering_glossy_reflection_bsdf(**kw),
            KernelLanes(K, row, flags, Lobe.GLOSSY_REFLECTION))


def _unit(v):
    return v / np.linalg.norm(v, axis=1, keepdims=True)


def direction_pairs(rng, n=3000):
    """Random pairs, the edge directions, and wi near wo (the retro peak) and the mirror
    direction at several scales."""
    e = edge_dirs()
    wo = [random_dirs(rng, n), np.repeat(e, len(e), axis=0)]
    wi = [random_dirs(rng, n), np.tile(e, (len(e), 1))]
    base = random_dirs(rng, n)
    for target in (base, base * [-1, -1, 1]):
        for s in (1e-9, 1e-6, 1e-3, 3e-2, 0.3):
            wo.append(base)
            wi.append(_unit(target + s * rng.normal(size=(n, 3))))
    return np.concatenate(wo), np.concatenate(wi)


def assert_equal(a, b, rtol=1e-12, what=""):
    a, b = np.asarray(a, dtype=np.float64), np.asarray(b, dtype=np.float64)
    err = np.abs(a - b) / np.maximum(np.abs(b), 1e-300)
    assert np.all((a == b) | (err <= rtol)), f"{what}: max rel err {err.max():.3g}"


@pytest.mark.parametrize("name", list(CASES))
def test_eval_pdf_equal_numpy(name, rng):
    ref, ker = lanes_of(CASES[name])
    wo, wi = direction_pairs(rng)
    f, p = ker.eval_pdf(wo, wi)
    fn, pn = ref.eval_pdf(wo, wi)
    assert_equal(f, fn, what="eval")
    assert_equal(p, pn, what="pdf")
    assert np.all(np.isfinite(f)) and np.all(f >= 0) and np.all(p >= 0)
    if name not in ("black", "tangent-along-n"):
        assert np.count_nonzero(p) > 100


@pytest.mark.parametrize("name", list(CASES))
def test_samples_equal_numpy(name, rng):
    ref, ker = lanes_of(CASES[name])
    e = edge_dirs()
    wo = np.concatenate([random_dirs(rng, 20_000), np.repeat(e, 20, axis=0)])
    u1, u2 = rng.random(len(wo)), rng.random((len(wo), 2))
    u2[:4] = [[0, 0], [1, 1], [1 - 1e-17, 0.5], [0.25, 1.0]]  # the ends
    s, sn = ker.sample(wo, u1, u2), ref.sample(wo, u1, u2)
    assert np.array_equal(s.lobe, sn.lobe)
    assert_equal(s.wi, sn.wi, what="wi")
    assert_equal(s.pdf, sn.pdf, what="pdf")
    assert_equal(s.weight, sn.weight, what="weight")
    if name not in ("black", "tangent-along-n"):
        assert s.valid.mean() > 0.5


@pytest.mark.parametrize("name", ["r1e-7", "r0.3-color", "r1", "aniso-0.1-0.5",
                                  "aniso-tilted-tangent", "black", "tangent-along-n"])
def test_albedo_equal_numpy(name, rng):
    # same tables (built through the kernels); roughness interpolated before mu: rounding
    ref, ker = lanes_of(CASES[name])
    wo = np.concatenate([random_dirs(rng, 2000), edge_dirs()])
    a, an = ker.albedo(wo), ref.albedo(wo)
    assert np.allclose(a, an, rtol=1e-13, atol=1e-15)
    assert np.all(a >= 0)


def test_rows_and_offsets_are_read(rng):
    _, ker = lanes_of(CASES["aniso-tilted-tangent"])
    w = K.SIGNATURE.width
    P = rng.random((3, w + 9))
    P[2, 4 : 4 + w] = ker.P[0]
    wo, wi = direction_pairs(rng, 500)
    u1, u2 = rng.random(len(wo)), rng.random((len(wo), 2))
    f, p = eval_lanes(K.eval_pdf, P, 2, 4, 0, wo, wi)
    f0, p0 = ker.eval_pdf(wo, wi)
    assert np.array_equal(f, f0) and np.array_equal(p, p0)
    s = sample_lanes(K.sample, P, 2, 4, 0, wo, u1, u2)
    s0 = ker.sample(wo, u1, u2)
    assert np.array_equal(s[0], s0.wi) and np.array_equal(s[3], s0.lobe)
    T = np.concatenate([np.full(3, -5.0), ker.table])
    assert np.array_equal(albedo_lanes(K.albedo, P, 2, 4, 0, wo, T, 3), ker.albedo(wo))


def test_any_finite_input_is_safe(rng):
    wo, wi = direction_pairs(rng, 300)
    u1, u2 = rng.uniform(-2, 3, len(wo)), rng.uniform(-2, 3, (len(wo), 2))
    for ru, tangent in [(-1.0, (1, 0, 0)), (0.0, (0, 0, 0)), (1e300, (1e300, 1e-300, 0)),
                        (1e-300, (0, 0, -3.0))]:
        P = np.zeros((1, K.SIGNATURE.width))
        P[0, :2] = ru
        P[0, 2:5] = (1.0, 0.5, 0.0)
        P[0, 8:11] = tangent
        f, p = eval_lanes(K.eval_pdf, P, 0, 0, 0, wo, wi)
        s = sample_lanes(K.sample, P, 0, 0, 0, wo, u1, u2)
        for x in (f, p, *s[:3]):
            assert np.all(np.isfinite(x))


def test_signature_matches_mdl():
    from render.material import DF_SIGNATURES

    names = [p[0] for p in DF_SIGNATURES["backscattering_glossy_reflection_bsdf"][1]]
    assert [p.name for p in K.SIGNATURE.params] == names
    assert K.SIGNATURE.context == ()


# at 89.9 degrees the retro lobe is a sliver inside one row of the 101-cell grid (see
# test_backscattering_glossy_reflection_bsdf): 88 degrees is the grazing direction here
CHI2 = [("r0.3-color", (45.0, 30.0)), ("r0.3-color", (130.0, 250.0)), ("r1", (88.0, 120.0)),
        ("aniso-0.1-0.5", (0.0, 0.0)), ("aniso-tilted-tangent", (60.0, 200.0))]


@pytest.mark.parametrize(("name", "wo"), CHI2, ids=[f"{c}-{w[0]:g}" for c, w in CHI2])
def test_chi2_on_kernels(name, wo):
    _, ker = lanes_of(CASES[name])
    res = chi2_test(ker, direction(*wo), sample_count=200_000, test_count=len(CHI2))
    assert res.passed, f"{name} wo={wo}: {res}"


FURNACE = [("r1e-7", (60.0, 0.0), TAB), ("r0.3-color", (0.0, 0.0), TAB),
           ("r1", (89.9, 45.0), TAB), ("aniso-0.1-0.5", (60.0, 200.0), TAB_ANISO),
           ("r0.3-color", (120.0, 300.0), TAB)]


@pytest.mark.parametrize(
    ("name", "wo", "tol"), FURNACE, ids=[f"{c}-{w[0]:g}" for c, w, _ in FURNACE]
)
def test_furnace_on_kernels(name, wo, tol):
    # mean sample weight = directional albedo: equal to the tables, never above the tint
    _, ker = lanes_of(CASES[name])
    w = direction(*wo)
    mean, se = furnace(ker, w, n=200_000, seed=3)
    a = ker.albedo(w[None])[0]
    tint = np.asarray(CASES[name].get("tint", 1.0)) * np.ones(3)
    assert np.all(mean <= tint + 4 * se)
    assert np.all(np.abs(mean - a) <= tol + 4 * se), (mean, a, se)


# --- the df checklist on the kernels (consistency, no NaN, reciprocity, integrals) --------


def _kernel_case(cid, name, **kw):
    return DfCase(cid, lambda: lanes_of(CASES[name])[1], "backscatter", **kw)


CHECKLIST = [
    _kernel_case("r0.3", "r0.3-color", albedo_tol=TAB),
    _kernel_case("r1", "r1", albedo_tol=TAB),
    _kernel_case("r0", "r0", chi2=False, narrow=True, albedo_tol=TAB),
    _kernel_case("r1e-3", "r1e-3", chi2=False, narrow=True, albedo_tol=TAB),
    _kernel_case("aniso", "aniso-0.1-0.5", albedo_tol=TAB_ANISO),
]
INTEGRALS = per_wo([c for c in CHECKLIST if c.id != "r0.3"]) + per_wo(CHECKLIST[:1], WOS[2:])


@pytest.mark.parametrize("case", CHECKLIST, ids=case_ids(CHECKLIST))
def test_checklist_pointwise_on_kernels(case, rng):
    check_consistency(case, rng)
    check_no_nan(case, rng)
    check_reciprocity(case, rng)


@pytest.mark.parametrize(("case", "wo"), INTEGRALS, ids=pair_ids(INTEGRALS))
def test_pdf_integral_furnace_and_albedo_on_kernels(case, wo):
    check_integrals(case, wo)
