"""df::spot_edf: the normalised cosine-power cone, local and global (object-space) axes."""

from __future__ import annotations

import numpy as np
import pytest
from render_edf_adapter import EdfAsBsdf

from render.df import spot_edf
from render.testing import chi2_test, direction, sample_lanes, sphere_integral

PARAMS = [
    (0.0, np.pi),
    (1.0, np.pi),
    (10.0, np.pi / 2),
    (100.0, 0.3),
    (0.0, 1e-3),
    (3.0, 2 * np.pi),
]


def _rot_x(angle):
    c, s = np.cos(angle), np.sin(angle)
    return np.array([[1.0, 0.0, 0.0], [0.0, c, -s], [0.0, s, c]])


@pytest.mark.parametrize(("k", "spread"), PARAMS)
def test_normalised_over_the_cone(k, spread):
    e = spot_edf(exponent=k, spread=spread, global_distribution=False)
    edge = (0.5 * min(spread, np.pi),)  # the cone's edge is a panel edge of the quadrature
    rule = dict(n_beta=32, order=16, breaks=edge)
    total = sphere_integral(lambda w: e.eval(w)[:, 0] * w[:, 2], [0.0, 0.0, 1.0], +1, **rule)
    assert total == pytest.approx(1.0, abs=1e-7)
    pdf = sphere_integral(e.pdf, [0.0, 0.0, 1.0], +1, **rule)
    assert pdf == pytest.approx(1.0, abs=1e-7)


def test_values_by_hand():
    # k = 2, spread = pi (s = 0): eval = c^2 * 12 / (2 pi * 3) = 2 c^2 / pi
    e = spot_edf(exponent=2.0, global_distribution=False)
    w = direction(60.0, 10.0)[None]
    assert e.eval(w)[0, 0] == pytest.approx(2 * 0.25 / np.pi, rel=1e-13)
    # outside the cone (spread = pi/2: s = cos 45) nothing is emitted
    e = spot_edf(exponent=2.0, spread=np.pi / 2, global_distribution=False)
    assert e.eval(direction(50.0)[None])[0, 0] == 0.0 and e.eval(direction(40.0)[None])[0, 0] > 0


@pytest.mark.parametrize(("k", "spread"), PARAMS)
def test_sample_consistency_and_closed_form_weight(k, spread, rng):
    e = spot_edf(exponent=k, spread=spread, global_distribution=False)
    s = e.sample(rng.random(20_000), rng.random((20_000, 2)))
    ok = s.valid
    assert ok.mean() > 0.999
    assert np.allclose(s.pdf[ok], e.pdf(s.wo[ok]), rtol=1e-9)
    # weight = (k^2 + 3k + 2) cos / (k^2 + k (2 + s) + s + 1) (libbsdf's closed form)
    sp = np.cos(0.5 * min(spread, np.pi))
    expected = (k * k + 3 * k + 2) * s.wo[ok, 2] / (k * k + k * (2 + sp) + sp + 1)
    assert np.allclose(s.weight[ok, 0], expected, rtol=1e-6)


@pytest.mark.parametrize(("k", "spread"), [(0.0, np.pi), (10.0, np.pi / 2), (2.0, 1.2)])
def test_chi2(k, spread):
    res = chi2_test(
        EdfAsBsdf(spot_edf(exponent=k, spread=spread, global_distribution=False)),
        direction(0.0),
        test_count=4,
    )
    assert res.passed, str(res)


def test_global_distribution_fixes_the_axis_in_object_space():
    # the object is tilted 30 degrees about x relative to the shading frame: the spot axis
    # (global_frame's +z) appears at theta = 30 in the local frame, whatever the normal
    o2l = _rot_x(np.radians(30.0))
    e = spot_edf(exponent=20.0, spread=np.pi, global_distribution=True, object_to_local=o2l)
    assert np.allclose(e.axis[0], o2l @ [0.0, 0.0, 1.0])
    peak = o2l @ [0.0, 0.0, 1.0]
    assert e.eval(peak[None])[0, 0] == pytest.approx(21 * 22 / (2 * np.pi * 21), rel=1e-12)
    # a global_frame rotation composes with object_to_local
    e2 = spot_edf(exponent=20.0, global_frame=_rot_x(np.radians(-30.0)), object_to_local=o2l)
    assert np.allclose(e2.axis[0], [0.0, 0.0, 1.0])


def test_global_spot_emits_only_above_the_surface():
    o2l = _rot_x(np.radians(80.0))  # axis 80 degrees from the normal: half the cone is below
    e = spot_edf(exponent=1.0, spread=np.pi / 2, object_to_local=o2l)
    s = sample_lanes(EdfAsBsdf(e), [0.0, 0.0, 1.0], 100_000)
    assert np.all(s.wi[s.valid, 2] > 0)
    # the pdf integrates to the fraction of the cone above the horizon = the success rate
    pdf_total = sphere_integral(e.pdf, e.axis[0], +1, n_beta=256)
    assert pdf_total == pytest.approx(s.valid.mean(), abs=4 * np.sqrt(0.25 / 100_000) + 1e-4)
    res = chi2_test(EdfAsBsdf(e), [0.0, 0.0, 1.0])
    assert res.passed, str(res)


def test_per_lane_object_frames():
    o2l = np.stack([np.eye(3), _rot_x(np.radians(45.0))])
    e = spot_edf(exponent=5.0, object_to_local=o2l)
    w = np.stack([direction(0.0), direction(45.0, -90.0)])  # each lane's own axis
    v = e.eval(w)[:, 0]
    assert v[0] == pytest.approx(v[1], rel=1e-12) and v[0] == pytest.approx(6 * 7 / (2 * np.pi * 6))


def test_extremes_stay_finite(rng):
    for k, spread in [(1e6, np.pi), (0.0, 0.0), (5.0, 1e-9), (-3.0, -1.0)]:
        e = spot_edf(exponent=k, spread=spread, global_distribution=False)
        s = e.sample(rng.random(1000), rng.random((1000, 2)))
        assert np.all(np.isfinite(s.wo)) and np.all(np.isfinite(s.weight)) and np.all(s.pdf >= 0)
        w = rng.normal(size=(1000, 3))
        w /= np.linalg.norm(w, axis=1, keepdims=True)
        assert np.all(np.isfinite(e.eval(w))) and np.all(e.eval(w) >= 0)


def test_bad_arguments():
    with pytest.raises(ValueError, match="needs object_to_local"):
        spot_edf(exponent=2.0)
    with pytest.raises(ValueError, match="finite exponent"):
        spot_edf(exponent=np.inf, global_distribution=False)
    with pytest.raises(ValueError, match="global_frame must be"):
        spot_edf(exponent=1.0, global_frame=np.eye(2), object_to_local=np.eye(3))
