"""df::spot_edf kernels: equal to the numpy class (local and global axes), normalised, chi2."""

from __future__ import annotations

import importlib

import numpy as np
import pytest
from df_kernel_adapter import KernelEdf, compare_edf, lane_dirs, lane_us, pack
from render_edf_adapter import EdfAsBsdf

from render.df import spot_edf
from render.testing import chi2_test, sphere_integral

mod = importlib.import_module("render.df.spot_edf")
PARAMS = [(0.0, np.pi), (1.0, np.pi), (2.0, np.pi / 2), (0.5, 1.0), (10.0, np.pi / 2),
          (100.0, 0.3), (0.0, 1e-3), (3.0, 2 * np.pi), (-1.0, 0.0), (1e4, 1e-6)]


def _rotations(rng, n):
    q, r = np.linalg.qr(rng.normal(size=(n, 3, 3)))
    return q * np.sign(np.diagonal(r, axis1=1, axis2=2))[:, None, :]


def test_signature_and_packing():
    sig = mod.SIGNATURE
    assert [p.name for p in sig.params] == [
        "exponent", "spread", "global_distribution", "global_frame", "handle"]
    assert sig.width == 1 + 1 + 1 + 9 + 9 and sig.offset("object_to_local_00") == 12
    m = np.arange(9.0).reshape(3, 3)
    row = pack(sig, exponent=-2.0, spread=7.0, global_frame=m, object_to_local=m + 10)
    assert row[0, :3].tolist() == [0.0, np.pi, 1.0]
    assert row[0, 3:12].tolist() == m.ravel().tolist()
    assert row[0, 12:].tolist() == (m + 10).ravel().tolist()


@pytest.mark.parametrize(("k", "spread"), PARAMS)
def test_local_kernels_equal_numpy(k, spread, rng):
    wo = lane_dirs(rng, 4000)
    u1, u2 = lane_us(rng, len(wo))
    ref = spot_edf(exponent=k, spread=spread, global_distribution=False)
    ker = KernelEdf(mod, exponent=k, spread=spread, global_distribution=False)
    compare_edf(ref, ker, wo, u1, u2, rtol=0.0)


def _signed_permutations(rng, n):
    p = np.stack([np.eye(3)[rng.permutation(3)] for _ in range(n)])
    return p * rng.choice([-1.0, 1.0], size=(n, 3, 1))


@pytest.mark.parametrize(("k", "spread"), PARAMS[:6])
def test_global_kernels_equal_numpy_per_lane_frames(k, spread, rng):
    n = 3000
    wo = lane_dirs(rng, n)[:n]
    u1, u2 = lane_us(rng, n)
    gf = _rotations(rng, 1)[0]
    # signed permutations: object_to_local @ axis is exact in numpy's matmul and in the
    # kernel alike, so everything after it must agree bit for bit
    o2l = _signed_permutations(rng, n)
    ref = spot_edf(exponent=k, spread=spread, global_frame=gf, object_to_local=o2l)
    ker = KernelEdf(mod, n=n, exponent=k, spread=spread, global_frame=gf, object_to_local=o2l)
    compare_edf(ref, ker, wo, u1, u2, rtol=0.0)
    # general rotations: numpy's matmul (BLAS) sums the three products in its own order,
    # the kernel left to right; the axes differ in the last bit, which only the cone's
    # edge (t = (c - s)/(1 - s) -> 0, cancellation) amplifies
    o2l = _rotations(rng, n)
    ref = spot_edf(exponent=k, spread=spread, global_frame=gf, object_to_local=o2l)
    ker = KernelEdf(mod, n=n, exponent=k, spread=spread, global_frame=gf, object_to_local=o2l)
    e0, (e1, p1) = ref.eval(wo), ker.eval_pdf(wo)
    inner = e0[:, 0] > 1e-6 * e0[:, 0].max()
    assert np.allclose(e1[inner], e0[inner], rtol=1e-12, atol=0)
    assert np.allclose(p1[inner], ref.pdf(wo)[inner], rtol=1e-12, atol=0)
    s0, s1 = ref.sample(u1, u2), ker.sample(u1, u2)
    both = s0.valid & s1.valid
    # samples may pass or fail differently only when drawn at the cone's edge (u = 1 - ulp:
    # t = 1e-16) or on the horizon
    odd = s0.valid != s1.valid
    z = np.maximum(np.abs(s0.wo[odd, 2]), np.abs(s1.wo[odd, 2]))
    assert np.all((u2[odd, 1] > 1.0 - 1e-9) | (z < 1e-9)), (u2[odd], z)
    assert np.allclose(s1.wo[both], s0.wo[both], rtol=0, atol=1e-14)


def test_zero_axis_emits_nothing(rng):
    e = KernelEdf(mod, exponent=1.0, global_frame=np.zeros((3, 3)), object_to_local=np.eye(3))
    u1, u2 = lane_us(rng, 100)
    assert not np.any(e.eval_pdf(lane_dirs(rng, 100))[0]) and not np.any(e.sample(u1, u2).pdf)


@pytest.mark.parametrize(("k", "spread"), [p for p in PARAMS[:7] if p[0] != 0.5])
def test_normalised_over_the_cone(k, spread):
    e = KernelEdf(mod, exponent=k, spread=spread, global_distribution=False)
    edge = (0.5 * min(spread, np.pi),)
    rule = dict(n_beta=32, order=16, breaks=edge)
    total = sphere_integral(lambda w: e.eval(w)[:, 0] * w[:, 2], [0.0, 0.0, 1.0], +1, **rule)
    assert total == pytest.approx(1.0, abs=1e-7)
    assert sphere_integral(e.pdf, [0.0, 0.0, 1.0], +1, **rule) == pytest.approx(1.0, abs=1e-7)


@pytest.mark.parametrize(("k", "spread"), PARAMS[:7])
def test_furnace_and_closed_form_weight(k, spread, rng):
    e = KernelEdf(mod, exponent=k, spread=spread, global_distribution=False)
    n = 100_000
    s = e.sample(rng.random(n), rng.random((n, 2)))
    assert s.valid.mean() > 0.999
    assert np.allclose(s.pdf[s.valid], e.pdf(s.wo[s.valid]), rtol=1e-9)
    sp = np.cos(0.5 * min(spread, np.pi))
    want = (k * k + 3 * k + 2) * s.wo[s.valid, 2] / (k * k + k * (2 + sp) + sp + 1)
    assert np.allclose(s.weight[s.valid, 0], want, rtol=1e-6)
    mean, se = s.weight[:, 0].mean(), s.weight[:, 0].std() / np.sqrt(n)
    assert abs(mean - 1.0) <= 4 * se + 1e-3  # ∫ eval cos = 1 over the cone


@pytest.mark.parametrize(("k", "spread"), [(0.0, np.pi), (2.0, np.pi / 2), (10.0, 1.5)])
def test_chi2(k, spread):
    e = KernelEdf(mod, exponent=k, spread=spread, global_distribution=False)
    res = chi2_test(EdfAsBsdf(e), [0.0, 0.0, 1.0], sample_count=200_000, test_count=3)
    assert res.passed, str(res)


def test_global_axis_chi2_and_horizon(rng):
    tilt = np.array([[1.0, 0.0, 0.0], [0.0, np.cos(1.0), -np.sin(1.0)],
                     [0.0, np.sin(1.0), np.cos(1.0)]])
    e = KernelEdf(mod, exponent=3.0, spread=2.0, global_frame=tilt, object_to_local=np.eye(3))
    s = e.sample(rng.random(50_000), rng.random((50_000, 2)))
    assert np.all(s.wo[s.valid, 2] > 0) and 0.5 < s.valid.mean() < 1.0  # horizon cuts it
    res = chi2_test(EdfAsBsdf(e), [0.0, 0.0, 1.0], sample_count=200_000, include_failures=True)
    assert res.passed, str(res)
