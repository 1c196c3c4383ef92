"""df::simple_glossy_bsdf's compiled kernels: equal to the numpy class (eval, pdf,
samples and albedo) over random lanes and the extremes, and chi-square and furnace
checks run on the kernels themselves."""

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

from render.df import simple_glossy_bsdf
from render.numerics import TOL
from render.testing import chi2_test, direction, furnace

K = importlib.import_module("render.df.simple_glossy_bsdf")
RT, TR = "scatter_reflect_transmit", "scatter_transmit"
#: the tabulated albedo's documented accuracy (render.df._albedo; test_simple_glossy_bsdf)
TAB, TAB_ANISO = 3e-3, 1e-2

CASES = {
    "r0": dict(roughness_u=0.0),
    "r1e-7": dict(roughness_u=1e-7),
    "r1e-3": dict(roughness_u=1e-3),
    "r0.3-color": dict(roughness_u=0.3, tint=(0.2, 0.5, 0.9)),
    "r1": dict(roughness_u=1.0),
    "black": dict(roughness_u=0.3, tint=0.0, mode=RT, ior_inside=1.5),
    "aniso-0.01-1": dict(roughness_u=0.01, roughness_v=1.0, tangent_u=(0.6, 0.8, 0.0)),
    "aniso-0.1-0.5": dict(roughness_u=0.1, roughness_v=0.5, tangent_u=(0.6, 0.8, 0.0)),
    "aniso-tilted-tangent": dict(roughness_u=0.4, roughness_v=0.1, tangent_u=(0.3, -0.2, 0.9)),
    "tangent-along-n": dict(roughness_u=0.3, tangent_u=(0.0, 0.0, 1.0)),
    "rt-1.5": dict(roughness_u=0.3, mode=RT, ior_inside=1.5),
    "rt-1": dict(roughness_u=0.3, mode=RT, ior_inside=1.0),
    "rt-1.0001": dict(roughness_u=0.3, mode=RT, ior_inside=1.0001),
    "rt-3-r0": dict(roughness_u=0.0, mode=RT, ior_inside=3.0),
    "rt-3-r1": dict(roughness_u=1.0, mode=RT, ior_inside=3.0),
    "rt-inside-denser": dict(roughness_u=0.2, mode=RT, ior_outside=1.5, ior_inside=1.2),
    "rt-aniso": dict(roughness_u=0.05, roughness_v=0.5, tangent_u=(0.0, 1.0, 0.0), mode=RT,
                     ior_inside=1.33),
    "transmit-1.5": dict(roughness_u=0.3, mode=TR, ior_inside=1.5),
    "transmit-3-r0.1": dict(roughness_u=0.1, mode=TR, ior_inside=3.0),
    "transmit-1": dict(roughness_u=0.5, mode=TR, ior_inside=1.0),
    "rt-thin": dict(roughness_u=0.3, mode=RT, ior_inside=1.5, thin_walled=True),
    "transmit-thin": dict(roughness_u=0.5, mode=TR, ior_inside=1.5, thin_walled=True),
    "reflect-thin": dict(roughness_u=0.2, thin_walled=True, ior_inside=1.5),
}


def lanes_of(kw):
    """The numpy class and the kernels on the same arguments."""
    kw = dict(kw)
    mode, thin = kw.pop("mode", None), kw.pop("thin_walled", False)
    row, flags = pack(K.SIGNATURE, mode, thin, **kw)
    extra = {"mode": mode} if mode else {}
    return simple_glossy_bsdf(thin_walled=thin, **extra, **kw), KernelLanes(K, row, flags)


def _unit(v):
    return v / np.linalg.norm(v, axis=1, keepdims=True)


def direction_pairs(rng, n=3000):
    """Random pairs, the edge directions, and wi near the mirror, -wo and refracted
    directions at several scales (so that the narrowest lobes are hit)."""
    e = edge_dirs()
    wo = [random_dirs(rng, n), np.repeat(e, len(e), axis=0)]
    wi = [random_dirs(rng, n), np.tile(e, (len(e), 1))]
    base = random_dirs(rng, n)
    for target in (base * [-1, -1, 1], -base, -_unit(base * [1, 1, 3.0])):
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
        assert np.count_nonzero(p) > 100  # the lanes exercise the lobe


@pytest.mark.parametrize("name", list(CASES))
def test_samples_equal_numpy(name, rng):
    ref, ker = lanes_of(CASES[name])
    n = 20_000
    e = edge_dirs()
    wo = np.concatenate([random_dirs(rng, n), np.repeat(e, 20, axis=0)])
    u1, u2 = rng.random(len(wo)), rng.random((len(wo), 2))
    u1[:8], u2[:8] = [0.0, 1.0, 0.5, 1 - 1e-17, 0, 0, 1, 1], [[0, 0], [1, 1]] * 4  # the ends
    s, sn = ker.sample(wo, u1, u2), ref.sample(wo, u1, u2)
    assert np.array_equal(s.lobe, sn.lobe)
    assert_equal(s.wi, sn.wi, what="wi")
    assert_equal(s.pdf, sn.pdf, what="pdf")
    assert_equal(s.weight, sn.weight, what="weight")
    if name not in ("black", "tangent-along-n"):
        assert s.valid.mean() > 0.5


ALBEDO_CASES = ["r1e-7", "r0.3-color", "r1", "aniso-0.01-1", "aniso-tilted-tangent", "rt-1.5",
                "rt-inside-denser", "rt-1", "transmit-3-r0.1", "rt-thin", "transmit-thin",
                "tangent-along-n", "black"]


@pytest.mark.parametrize("name", ALBEDO_CASES)
def test_albedo_equal_numpy(name, rng):
    # the same tables (built through the kernels), interpolated in roughness before mu
    # instead of after, and the trigonometric phi weights summed in order instead of by
    # BLAS: equal to rounding
    ref, ker = lanes_of(CASES[name])
    wo = np.concatenate([random_dirs(rng, 2000), edge_dirs()])
    a, an = ker.albedo(wo), ref.albedo(wo)
    assert np.allclose(a, an, rtol=1e-13, atol=1e-15)
    # (not <= 1: the anisotropic tables' phi interpolation overshoots to 1.04 at grazing
    # incidence for roughness 0.01 x 1, in numpy as here; reported, left to the tables)
    assert np.all(a >= 0)


def test_rows_and_offsets_are_read(rng):
    # a node at slot offset b of row 1 of a wider table reads its own slots only
    kw = CASES["rt-aniso"]
    _, ker = lanes_of(kw)
    w = K.SIGNATURE.width
    P = rng.random((3, w + 9))
    P[1, 5 : 5 + w] = ker.P[0]
    wo, wi = direction_pairs(rng, 500)
    u1, u2 = rng.random(len(wo)), rng.random((len(wo), 2))
    f, p = eval_lanes(K.eval_pdf, P, 1, 5, ker.flags, wo, wi)
    f0, p0 = ker.eval_pdf(wo, wi)
    assert np.array_equal(f, f0) and np.array_equal(p, p0)
    s = sample_lanes(K.sample, P, 1, 5, ker.flags, wo, u1, u2)
    s0 = ker.sample(wo, u1, u2)
    assert np.array_equal(s[0], s0.wi) and np.array_equal(s[3], s0.lobe)
    T = np.concatenate([np.full(7, -5.0), ker.table])
    a = albedo_lanes(K.albedo, P, 1, 5, ker.flags, wo, T, 7)
    assert np.array_equal(a, ker.albedo(wo))


def test_any_finite_input_is_safe(rng):
    # out-of-range slots (the packer clamps them, the kernels must still not produce NaN)
    wo, wi = direction_pairs(rng, 300)
    u1, u2 = rng.uniform(-2, 3, len(wo)), rng.uniform(-2, 3, (len(wo), 2))
    for ru, ior_o, ior_i, tangent in [(-1.0, 1.0, 1.5, (1, 0, 0)), (0.0, 0.0, 1.5, (0, 0, 0)),
                                      (1e300, -1.0, 1e-300, (1e300, 1e-300, 0)),
                                      (1e-300, 1e300, 1e300, (0, 0, -3.0))]:
        for flags in (0, 1, 2, 5, 6):
            P = np.zeros((1, K.SIGNATURE.width))
            P[0, :2] = ru
            P[0, 2:5] = (1.0, 0.5, 0.0)
            P[0, 8:11] = tangent
            P[0, 11:13] = ior_o, ior_i
            f, p = eval_lanes(K.eval_pdf, P, 0, 0, flags, wo, wi)
            wi_s, ps, ws, lobe = sample_lanes(K.sample, P, 0, 0, flags, wo, u1, u2)
            for x in (f, p, wi_s, ps, ws):
                assert np.all(np.isfinite(x))


def test_signature_matches_mdl():
    from render.material import DF_SIGNATURES

    names = [p[0] for p in DF_SIGNATURES["simple_glossy_bsdf"][1]]
    assert [p.name for p in K.SIGNATURE.params] == names
    assert K.SIGNATURE.context == ("ior_outside", "ior_inside")
    assert K.SIGNATURE.param("roughness_u").clamp == (TOL.roughness_min, None)
    assert K.SIGNATURE.param("multiscatter_tint").default == (0.0, 0.0, 0.0)


# --- statistics on the kernels themselves -------------------------------------------------

# (roughness 0.01 x 1 is a sliver the 101 x 202 cell grid cannot integrate: equality above)
CHI2 = [("r0.3-color", (45.0, 30.0)), ("r1", (89.9, 120.0)), ("aniso-0.1-0.5", (0.0, 0.0)),
        ("aniso-tilted-tangent", (80.0, 120.0)), ("rt-1.5", (45.0, 30.0)),
        ("rt-1.5", (130.0, 250.0)), ("rt-inside-denser", (60.0, 10.0)),
        ("rt-3-r1", (130.0, 250.0)), ("transmit-1.5", (45.0, 30.0)),
        ("transmit-1.5", (130.0, 250.0)), ("transmit-thin", (45.0, 30.0)),
        ("rt-thin", (130.0, 250.0))]


@pytest.mark.parametrize(("name", "wo"), CHI2, ids=[f"{c}-{w[0]:g}" for c, w in CHI2])
def test_chi2_on_kernels(name, wo):
    _, ker = lanes_of(CASES[name])
    res = chi2_test(ker, direction(*wo), sample_count=200_000, test_count=len(CHI2))
    assert res.passed, f"{name} wo={wo}: {res}"


FURNACE = [("r1e-7", (60.0, 0.0), TAB), ("r0.3-color", (0.0, 0.0), TAB),
           ("r1", (89.9, 45.0), TAB), ("aniso-0.01-1", (60.0, 200.0), TAB_ANISO),
           ("rt-1.5", (60.0, 200.0), TAB), ("rt-1.5", (120.0, 300.0), TAB),
           ("transmit-3-r0.1", (120.0, 300.0), TAB), ("transmit-thin", (60.0, 200.0), TAB)]


@pytest.mark.parametrize(
    ("name", "wo", "tol"), FURNACE, ids=[f"{c}-{w[0]:g}" for c, w, _ in FURNACE]
)
def test_furnace_on_kernels(name, wo, tol):
    # the mean sample weight is the directional albedo: it matches the tabulated albedo to
    # the tables' accuracy and never exceeds the tint (no energy gain)
    _, ker = lanes_of(CASES[name])
    w = direction(*wo)
    mean, se = furnace(ker, w, n=200_000, seed=3)
    a = ker.albedo(w[None])[0]
    tint = np.asarray(CASES[name].get("tint", 1.0)) * np.ones(3)
    assert np.all(mean <= tint + 4 * se)
    assert np.all(np.abs(mean - a) <= tol + 4 * se), (mean, a, se)


# --- the df checklist on the kernels (consistency, no NaN, reciprocity, integrals) --------


def _kernel_case(cid, name, **kw):
    return DfCase(cid, lambda: lanes_of(CASES[name])[1], "glossy", **kw)


CHECKLIST = [
    _kernel_case("r0.3", "r0.3-color", albedo_tol=TAB),
    _kernel_case("r1", "r1", albedo_tol=TAB),
    _kernel_case("r0", "r0", chi2=False, narrow=True, albedo_tol=TAB),
    _kernel_case("aniso", "aniso-0.1-0.5", albedo_tol=TAB_ANISO),
    _kernel_case("rt-1.5", "rt-1.5", transmits=True, ior=(1.0, 1.5), albedo_tol=TAB),
    _kernel_case("rt-3-r1", "rt-3-r1", transmits=True, ior=(1.0, 3.0), albedo_tol=TAB),
    _kernel_case("rt-1.0001", "rt-1.0001", narrow_t=True, transmits=True, ior=(1.0, 1.0001),
                 albedo_tol=TAB),
    _kernel_case("transmit-1.5", "transmit-1.5", transmits=True, ior=(1.0, 1.5), albedo_tol=TAB),
    _kernel_case("transmit-3-r0.1", "transmit-3-r0.1", transmits=True, narrow_t=True,
                 ior=(1.0, 3.0), albedo_tol=TAB),
    _kernel_case("rt-thin", "rt-thin", transmits=True, thin=True, ior=(1.0, 1.5),
                 albedo_tol=TAB),
    _kernel_case("transmit-thin", "transmit-thin", transmits=True, thin=True, ior=(1.0, 1.5),
                 albedo_tol=TAB),
]
INTEGRALS = per_wo([c for c in CHECKLIST if c.id in ("r0.3", "rt-1.5", "transmit-1.5")])
INTEGRALS += per_wo([c for c in CHECKLIST if c.id not in ("r0.3", "rt-1.5", "transmit-1.5")],
                    WOS[2:])


@pytest.mark.parametrize("case", CHECKLIST, ids=case_ids(CHECKLIST))
def test_checklist_pointwise_on_kernels(case, rng):
    check_consistency(case, rng)
    check_no_nan(case, rng)
    check_reciprocity(case, rng)


@pytest.mark.parametrize(("case", "wo"), INTEGRALS, ids=pair_ids(INTEGRALS))
def test_pdf_integral_furnace_and_albedo_on_kernels(case, wo):
    check_integrals(case, wo)


def test_albedo_tables_of_a_subclass_use_the_parents_kernels(rng):
    # the tables are built through the df module's kernels, also for subclasses defined
    # elsewhere (tests count calls on such subclasses)
    class Sub(simple_glossy_bsdf):
        pass

    wo = random_dirs(rng, 200)
    a = Sub(roughness_u=0.45, mode=RT, ior_inside=1.3).albedo(wo)
    b = simple_glossy_bsdf(roughness_u=0.45, mode=RT, ior_inside=1.3).albedo(wo)
    assert np.array_equal(a, b) and np.all(a[wo[:, 2] > 1e-3] > 0)
