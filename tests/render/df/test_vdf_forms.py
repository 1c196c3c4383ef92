"""The vdf forms of the mixers (normalized, clamped, unbounded, and their colour forms)
and of ``tint``: mixtures of Henyey–Greenstein phase functions on the kernels."""

from __future__ import annotations

import numpy as np
import pytest

from render import df
from render.expr import parse_material
from render.testing import chi2_test, consistency_error, direction, sample_lanes, sphere_integral

A = df.anisotropic_vdf
MIXES = {
    "normalized": lambda: df.normalized_mix([df.vdf_component(0.5, A(0.7)),
                                             df.vdf_component(0.9, A(-0.4))]),
    "clamped": lambda: df.clamped_mix([df.vdf_component(0.6, A(0.2)),
                                       df.vdf_component(0.9, A(-0.8))]),
    "unbounded": lambda: df.unbounded_mix([(0.3, A(0.5)), (0.4, A(0.0))]),
    "color": lambda: df.color_normalized_mix([df.color_vdf_component((1.0, 0.5, 0.0), A(0.8)),
                                              df.color_vdf_component((0.0, 0.5, 1.0),
                                                                     A(-0.5))]),
}
WO = ((30.0, 20.0), (120.0, 300.0))


@pytest.mark.parametrize("name", list(MIXES))
def test_mix_is_the_weighted_phase(name, rng):
    m = MIXES[name]()
    assert m.program.kind == "vdf" and type(m).__name__.endswith("Vdf")
    w = m.weights(1)[0]
    wo = rng.normal(size=(500, 3))
    wo /= np.linalg.norm(wo, axis=1, keepdims=True)
    wi = rng.normal(size=(500, 3))
    wi /= np.linalg.norm(wi, axis=1, keepdims=True)
    gs = [c.component.program.P[0, 0] for c in m.components]
    mu = -np.sum(wo * wi, axis=1)  # the angle between the propagation directions

    def hg(g):  # Henyey–Greenstein in closed form
        return (1 - g * g) / (4 * np.pi * (1 + g * g - 2 * g * mu) ** 1.5)

    want = sum(w[i][None, :] * hg(g)[:, None] for i, g in enumerate(gs))
    assert np.allclose(m.eval(wo, wi), want, rtol=1e-12)


@pytest.mark.parametrize("name", list(MIXES))
@pytest.mark.parametrize("wo", WO)
def test_chi2_and_consistency(name, wo):
    m = MIXES[name]()
    res = chi2_test(m, direction(*wo), sample_count=100_000, test_count=2 * len(MIXES))
    assert res.passed, str(res)
    s = sample_lanes(m, direction(*wo), 20_000)
    pdf_err, w_err = consistency_error(m, np.tile(direction(*wo), (20_000, 1)), s)
    assert pdf_err.max() < 1e-9 and w_err.max() < 1e-9


@pytest.mark.parametrize("name", list(MIXES))
def test_pdf_integrates_to_one_and_albedo_is_the_weight_sum(name):
    m = MIXES[name]()
    wo = direction(60.0, 200.0)

    def f(x):
        e, p = m.eval_pdf(np.tile(wo, (len(x), 1)), x)
        return np.concatenate([e, p[:, None]], axis=1)

    # both hemispheres, rings about the forward peak (the components peak forward or back)
    q = sum(sphere_integral(f, -wo, side, n_beta=128, order=16) for side in (+1, -1))
    assert q[3] == pytest.approx(1.0, abs=2e-3)
    total = m.weights(1)[0].sum(axis=0)
    assert np.allclose(q[:3], total, atol=2e-3)
    assert np.allclose(m.albedo(wo[None])[0], total, rtol=1e-12)


def test_tint_of_a_vdf():
    t = df.tint((0.5, 0.2, 0.1), A(0.3))
    assert isinstance(t, df.TintVdf) and t.program.kind == "vdf"
    wo = direction(20.0)
    s = sample_lanes(t, wo, 2000)
    assert np.allclose(s.weight, [0.5, 0.2, 0.1], rtol=1e-12)


def test_vdf_forms_parse():
    m = parse_material("material(volume: material_volume(scattering: df::normalized_mix("
                       "df::vdf_component[](df::vdf_component(0.5, df::anisotropic_vdf(0.7)), "
                       "df::vdf_component(0.5, df::anisotropic_vdf(-0.2))))))")
    assert m.volume.scattering.kind == "vdf"
    m = parse_material("material(volume: material_volume(scattering: df::tint(color(0.5), "
                       "df::anisotropic_vdf(0.3))))")
    assert m.volume.scattering.kind == "vdf" and m.volume.scattering.name == "tint_vdf"
