"""df::measured_factor: the checklist over a table, the lookup by hand, and the texture
read from a file through scene expressions."""

from __future__ import annotations

import numpy as np
import pytest
from render_combiner_cases import (
    COMBINED_ALBEDO_TOL,
    CombinerCase,
    check_chi2_combined,
    check_integrals_combined,
    check_no_nan_combined,
    two_wos,
)
from render_df_cases import case_ids, check_consistency, check_reciprocity, pair_ids, per_wo

from render import df
from render.testing import direction

G, D, S = df.microfacet_ggx_smith_bsdf, df.diffuse_reflection_bsdf, df.specular_bsdf


def table(h=8, w=16):
    """A smooth table over (u, v): row 0 at the top, as images are stored."""
    v = (np.arange(h)[::-1, None] + 0.5) / h
    u = (np.arange(w)[None, :] + 0.5) / w
    base = 0.9 - 0.5 * u * u - 0.3 * v
    return np.stack([base, base * 0.8, base * 0.5], axis=-1)


CASES = [
    CombinerCase("glossy", lambda: df.measured_factor(table(), G(roughness_u=0.3)), "glossy",
                 albedo_tol=COMBINED_ALBEDO_TOL, chi2_wos=((45.0, 30.0),)),
    CombinerCase("diffuse", lambda: df.measured_factor(table(), D()), "diffuse",
                 albedo_tol=COMBINED_ALBEDO_TOL),
    CombinerCase("mirror", lambda: df.measured_factor(table(4, 4), S()), "delta"),
]
INTEGRALS = two_wos(CASES)
CHI2 = per_wo(CASES, ((45.0, 30.0),), only=lambda c: c.chi2_wos is not None)


@pytest.mark.parametrize("case", CASES, ids=case_ids(CASES))
def test_consistency(case, rng):
    check_consistency(case, rng)


@pytest.mark.parametrize("case", CASES, ids=case_ids(CASES))
def test_no_nan_or_negative(case, rng):
    check_no_nan_combined(case, rng)


@pytest.mark.parametrize("case", CASES, ids=case_ids(CASES))
def test_reciprocity(case, rng):
    check_reciprocity(case, rng)


@pytest.mark.parametrize(("case", "wo"), CHI2, ids=pair_ids(CHI2))
def test_chi2(case, wo):
    check_chi2_combined(case, wo, test_count=len(CHI2))


@pytest.mark.parametrize(("case", "wo"), INTEGRALS, ids=pair_ids(INTEGRALS))
def test_pdf_furnace_and_albedo(case, wo):
    check_integrals_combined(case, wo)


def test_lookup_by_hand():
    # over a mirror, h = n: v = 0 (the bottom row), u = theta_o / 90 degrees
    t = table(6, 10)
    m = df.measured_factor(t, S())
    for th in (0.0, 20.0, 45.0, 80.0):
        s = m.sample(direction(th)[None], np.array([0.5]), np.array([[0.5, 0.5]]))
        x = np.clip(th / 90.0 * 10 - 0.5, 0, 9)
        i = min(int(x), 8)
        f = x - i
        bottom = t[-1]
        want = (1 - f) * bottom[i] + f * bottom[i + 1]
        assert np.allclose(s.weight[0], want, rtol=1e-12), th
    # a factor above 1 is allowed (the spec's table may exceed 1)
    big = df.measured_factor(np.full((2, 2), 1.5), S())
    s = big.sample(direction(30.0)[None], np.array([0.5]), np.array([[0.5, 0.5]]))
    assert np.allclose(s.weight, 1.5)


def test_from_a_texture_file(tmp_path):
    import OpenEXR

    from displacement.surfaces import UnitSquare
    from render.expr import parse_material

    t = table().astype(np.float32)
    with OpenEXR.File({"compression": OpenEXR.ZIP_COMPRESSION, "type": OpenEXR.scanlineimage},
                      {"RGB": t}) as f:
        f.write(str(tmp_path / "factor.exr"))
    m = parse_material('material(surface: material_surface(scattering: df::measured_factor('
                       'texture_2d("factor.exr"), df::specular_bsdf())))', base_dir=tmp_path)
    b = m.surface.scattering.bind(UnitSquare().state_at_uv(np.array([[0.5, 0.5]])))
    direct = df.measured_factor(t, S())
    w = direction(35.0)[None]
    u, uu = np.array([0.5]), np.array([[0.5, 0.5]])
    assert np.allclose(b.sample(w, u, uu).weight, direct.sample(w, u, uu).weight, rtol=1e-6)


def test_bad_tables():
    with pytest.raises(ValueError, match="must be a 2-D texture"):
        df.measured_factor(np.zeros(5), S())
    with pytest.raises(ValueError, match="finite"):
        df.measured_factor(np.full((2, 2), np.nan), S())
