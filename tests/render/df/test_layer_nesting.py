"""Combiners nested to depth 5: the Handbook's five_layers (Figure 6.36) and a deeper tree with
its own normals, through the df checklist and through MDL df nodes bound by ``material.shade``."""

from __future__ import annotations

import numpy as np
import pytest
from render_combiner_cases import (
    COMBINED_ALBEDO_TOL,
    JUMP_ALBEDO_TOL,
    CombinerCase,
    check_chi2_combined,
    check_integrals_combined,
    check_no_nan_combined,
    two_wos,
)
from render_df_cases import (
    case_ids,
    check_consistency,
    pair_ids,
    random_dirs,
)

from displacement.surfaces import UnitSquare
from render import df
from render.bsdf import Lobe
from render.df import _kernel_common as kc
from render.frame import Frame
from render.material import df as mdf
from render.material import material, material_emission, material_surface
from render.testing import direction, tile

WHITE, BLUE, GREEN = 0.7, (0.2, 0.3, 0.7), (0.1, 0.3, 0.05)
ORANGE, YELLOW = (0.3, 0.15, 0.0), (0.5, 0.4, 0.1)


def five_layers():
    """Figure 6.36: fresnel_layer(mirror) over weighted_layer(narrow blue glossy) over
    custom_curve_layer(clamped_mix of orange and yellow glossy) over diffuse green."""
    two_layers = df.clamped_mix([
        df.bsdf_component(0.5, df.simple_glossy_bsdf(roughness_u=0.6, tint=ORANGE)),
        df.bsdf_component(0.5, df.simple_glossy_bsdf(roughness_u=0.3, tint=YELLOW)),
    ])
    three_layers = df.custom_curve_layer(0.0, 1.0, 0.5, 1.0, two_layers,
                                         df.diffuse_reflection_bsdf(tint=GREEN))
    four_layers = df.weighted_layer(0.3, df.simple_glossy_bsdf(roughness_u=0.2, tint=BLUE),
                                    three_layers)
    return df.fresnel_layer(1.6, 1.0, df.specular_bsdf(tint=WHITE), four_layers)


N1 = np.array([0.2, -0.1, 0.97]) / np.linalg.norm([0.2, -0.1, 0.97])
N2 = np.array([-0.3, 0.25, 0.92]) / np.linalg.norm([-0.3, 0.25, 0.92])


def deep():
    """Five combiner levels, two of them with their own normals, reflection and transmission."""
    leaf = df.tint((0.9, 0.8, 0.7), df.directional_factor((0.9, 0.6, 0.2), 1.0, 1.0, 5.0,
                                                          df.simple_glossy_bsdf(roughness_u=0.4)))
    mix = df.clamped_mix([df.bsdf_component(0.7, leaf),
                          df.bsdf_component(0.5, df.diffuse_reflection_bsdf())])
    curve = df.custom_curve_layer(0.1, 1.0, 5.0, 1.0, mix, df.diffuse_reflection_bsdf(tint=GREEN),
                                  normal=N2)
    weighted = df.weighted_layer(0.4, curve, df.diffuse_transmission_bsdf(tint=0.8))
    return df.fresnel_layer(1.5, 1.0, df.specular_bsdf(), weighted, normal=N1)


CASES = [
    CombinerCase("five-layers", five_layers, "glossy", albedo_tol=COMBINED_ALBEDO_TOL),
    CombinerCase("deep-own-normals", deep, "glossy", transmits=True, reciprocal=False,
                 albedo_tol=JUMP_ALBEDO_TOL, quad_tol=3e-3),
]
INTEGRALS = two_wos(CASES)
CHI2 = [(CASES[0], (45.0, 30.0)), (CASES[1], (60.0, 200.0))]


@pytest.mark.parametrize("case", CASES, ids=case_ids(CASES))
def test_consistency(case, rng):
    check_consistency(case, rng)


@pytest.mark.parametrize("case", CASES, ids=case_ids(CASES))
def test_no_nan_or_negative(case, rng):
    check_no_nan_combined(case, rng)


def test_five_layers_reciprocity(rng):
    from render_df_cases import check_reciprocity

    check_reciprocity(CASES[0], rng)


@pytest.mark.parametrize(("case", "wo"), CHI2, ids=pair_ids(CHI2))
def test_chi2(case, wo):
    check_chi2_combined(case, wo, test_count=len(CHI2))


@pytest.mark.parametrize(("case", "wo"), INTEGRALS, ids=pair_ids(INTEGRALS))
def test_pdf_furnace_and_albedo(case, wo):
    check_integrals_combined(case, wo)


def test_five_layers_by_hand_at_normal_incidence():
    # the mirror coat reflects F(1.6, 1) = (0.6/2.6)^2 of 0.7 straight back
    f = (0.6 / 2.6) ** 2
    b = five_layers()
    wo = tile(direction(0.0), 4)
    s = b.sample(wo, np.zeros(4), np.full((4, 2), 0.5))  # u1 = 0 picks the coat
    assert np.all(s.lobe == int(Lobe.SPECULAR_REFLECTION))
    assert np.allclose(s.wi, [0.0, 0.0, 1.0], atol=1e-15)
    # the delta's probability is the coat's selection probability P; weight = 0.7 F / P
    assert np.allclose(s.weight * s.pdf[:, None], WHITE * f, rtol=1e-12)
    # the lobes of all five levels are declared
    assert b.lobes == Lobe.SPECULAR_REFLECTION | Lobe.GLOSSY_REFLECTION | Lobe.DIFFUSE_REFLECTION


# --- the same trees as MDL df nodes, bound by material.shade ------------------------------------


def five_layers_node():
    two_layers = mdf.clamped_mix(components=[
        mdf.bsdf_component(weight=0.5, component=mdf.simple_glossy_bsdf(
            roughness_u=0.6, tint=ORANGE)),
        mdf.bsdf_component(weight=0.5, component=mdf.simple_glossy_bsdf(
            roughness_u=0.3, tint=YELLOW)),
    ])
    three_layers = mdf.custom_curve_layer(normal_reflectivity=0.0, grazing_reflectivity=1.0,
                                          exponent=0.5, weight=1.0, layer=two_layers,
                                          base=mdf.diffuse_reflection_bsdf(tint=GREEN))
    four_layers = mdf.weighted_layer(weight=0.3, layer=mdf.simple_glossy_bsdf(
        roughness_u=0.2, tint=BLUE), base=three_layers)
    return mdf.fresnel_layer(ior=1.6, weight=1.0, layer=mdf.specular_bsdf(tint=(WHITE,) * 3),
                             base=four_layers)


def _reflect(k, m):
    """Rows of ``k`` mirrored about the unit rows ``m`` (``kc.reflect``, a row at a time)."""
    return np.array([kc.reflect(*a, *b) for a, b in zip(k, m, strict=True)])


def _state(n=64, seed=1):
    rng = np.random.default_rng(seed)
    return UnitSquare().state_at_uv(rng.random((n, 2)))


def test_five_layer_nodes_bind_to_the_same_bsdf(rng):
    state = _state()
    shading = material(surface=material_surface(five_layers_node())).shade(state)
    bound, direct = shading.bsdf, five_layers()
    assert type(bound).__name__ == "FresnelLayer"
    wo, wi = random_dirs(rng, len(state)), random_dirs(rng, len(state))
    e1, p1 = bound.eval_pdf(wo, wi)
    e2, p2 = direct.eval_pdf(wo, wi)
    assert np.allclose(e1, e2, rtol=1e-12, atol=0) and np.allclose(p1, p2, rtol=1e-12, atol=0)


def test_layer_normal_argument_and_nested_default_normal():
    state = _state(8)  # UnitSquare: normal +z, tangent_u +x, so the shading frame is identity
    n1 = (0.3, 0.0, 0.9)
    n1_unit = np.array(n1) / np.linalg.norm(n1)
    wo = tile(direction(20.0, 150.0), 8)
    u1, u2 = np.full(8, 0.5), np.full((8, 2), 0.5)
    # a mirror layer with its own normal reflects about it
    own = mdf.weighted_layer(weight=1.0, layer=mdf.specular_bsdf(), normal=n1).bind(state)
    assert np.allclose(own.sample(wo, u1, u2).wi, _reflect(wo, tile(n1_unit, 8)), atol=1e-12)
    # a layer nested in it with the default normal state::normal() uses the material's
    # normal, not the enclosing layer's (MDL evaluates state::normal() in the material)
    nested = mdf.weighted_layer(
        weight=1.0, normal=n1,
        layer=mdf.weighted_layer(weight=1.0, layer=mdf.specular_bsdf())).bind(state)
    assert np.allclose(nested.sample(wo, u1, u2).wi, wo * [-1.0, -1.0, 1.0], atol=1e-12)
    # a varying normal: one per lane
    tilt = mdf.weighted_layer(weight=1.0, layer=mdf.specular_bsdf(),
                              normal=lambda s: np.column_stack([s.uv[:, 0] - 0.5,
                                                                np.zeros(len(s)), np.ones(len(s))]))
    normals = np.column_stack([state.uv[:, 0] - 0.5, np.zeros(8), np.ones(8)])
    normals /= np.linalg.norm(normals, axis=1, keepdims=True)
    assert np.allclose(tilt.bind(state).sample(wo, u1, u2).wi, _reflect(wo, normals), atol=1e-12)


def test_child_tangent_is_expressed_in_the_layer_frame():
    state = _state(4)
    n1 = np.array([0.0, 0.4, 0.9]) / np.linalg.norm([0.0, 0.4, 0.9])
    t = (1.0, 1.0, 0.0)
    node = mdf.weighted_layer(weight=1.0, normal=tuple(n1), layer=mdf.simple_glossy_bsdf(
        roughness_u=0.1, roughness_v=0.5, tangent_u=t))
    bound = node.bind(state)
    expect = Frame.from_normal_tangent(tile(n1, 4), state.tangent_u).to_local(tile(t, 4))
    assert np.allclose(bound.layer.tangent_u, expect, atol=1e-12)


def test_handbook_three_lobes_weave_highlights():
    """Listing 8.3: three glossy lobes about state::normal() and normals bent along +-u."""
    state = _state(1)
    bend = 1.5

    def bent(sign):
        def normal(s):
            v = s.normal + sign * bend * s.tangent_u
            return v / np.linalg.norm(v, axis=1, keepdims=True)
        return normal

    glossy = mdf.simple_glossy_bsdf(roughness_u=0.05)
    node = mdf.weighted_layer(weight=0.5, normal=lambda s: s.normal, layer=glossy,
                              base=mdf.weighted_layer(weight=0.5, normal=bent(1.0), layer=glossy,
                                                      base=mdf.weighted_layer(
                                                          weight=1.0, normal=bent(-1.0),
                                                          layer=glossy)))
    bsdf = material(surface=material_surface(node)).shade(state).bsdf
    wo = direction(10.0, 0.0)
    # each of the three mirror directions carries a narrow peak
    for sign in (0.0, 1.0, -1.0):
        n = np.array([sign * bend, 0.0, 1.0]) / np.linalg.norm([sign * bend, 0.0, 1.0])
        peak = _reflect(wo[None], n[None])
        if peak[0, 2] <= 0:
            continue
        assert bsdf.eval(wo[None], peak)[0, 0] > 10.0


def test_edf_mix_with_a_global_spot_through_shade():
    state = _state(16)
    emission = mdf.normalized_mix(components=[
        mdf.edf_component(weight=1.0, component=mdf.diffuse_edf()),
        mdf.edf_component(weight=1.0, component=mdf.spot_edf(exponent=4.0)),
    ])
    assert emission.kind == "edf"
    m = material(surface=material_surface(emission=material_emission(
        emission=emission, intensity=(1.0, 1.0, 1.0))))
    edf = m.shade(state).edf
    assert type(edf).__name__ == "NormalizedMixEdf"
    up = tile(direction(0.0), 16)
    # along the axis: half the diffuse 1/pi plus half the spot's peak (k + 2) / (2 pi)
    expect = 0.5 / np.pi + 0.5 * 6.0 / (2 * np.pi)
    assert np.allclose(edf.eval(up), expect, rtol=1e-12)


def test_component_arrays_and_their_errors():
    glossy = mdf.simple_glossy_bsdf(roughness_u=0.3)
    # a varying component weight is evaluated per lane when bound
    mix = mdf.normalized_mix(components=[
        mdf.bsdf_component(weight=lambda s: s.uv[:, 0], component=glossy),
        mdf.bsdf_component(weight=0.5, component=mdf.diffuse_reflection_bsdf()),
    ])
    assert mix.kind == "bsdf" and len(mix.kwargs["components"]) == 2
    state = _state(5)
    bound = mix.bind(state)
    u = state.uv[:, 0]
    expect = np.where(u + 0.5 > 1.0, u / (u + 0.5), u)  # normalised where the sum exceeds 1
    assert np.allclose(bound.weights(5)[:, 0, 0], expect, rtol=1e-15)
    # MDL's bsdf(): an omitted layer, or None, is black
    assert mdf.weighted_layer(weight=0.5, layer=None).bind(state).layer is None
    with pytest.raises(ValueError, match="must be an array"):
        mdf.normalized_mix(components=mdf.bsdf_component(weight=0.5, component=glossy))
    with pytest.raises(ValueError, match="must be an array"):
        mdf.clamped_mix(components=[glossy])
    with pytest.raises(ValueError, match="mixes bsdf_component and edf_component"):
        mdf.normalized_mix(components=[mdf.bsdf_component(weight=0.5, component=glossy),
                                       mdf.edf_component(weight=0.5, component=mdf.diffuse_edf())])
    with pytest.raises(ValueError, match="must be an array"):
        mdf.color_normalized_mix(components=[mdf.bsdf_component(weight=0.5, component=glossy)])
    with pytest.raises(ValueError, match="must be a bsdf"):
        mdf.weighted_layer(layer=mdf.diffuse_edf())
    with pytest.raises(ValueError, match="needs the argument 'ior'"):
        mdf.fresnel_layer(layer=glossy)
    # an edf mix is an edf: not a surface's scattering
    edf_mix = mdf.clamped_mix(components=[mdf.edf_component(weight=1.0,
                                                            component=mdf.diffuse_edf())])
    with pytest.raises(ValueError, match="scattering must be a bsdf node"):
        material_surface(scattering=edf_mix)


def test_layer_normal_errors():
    state = _state(3)
    node = mdf.weighted_layer(layer=mdf.specular_bsdf(),
                              normal=lambda s: np.full((len(s), 3), np.nan))
    with pytest.raises(ValueError, match="normal.*non-finite"):
        node.bind(state)
    # a zero normal falls back to the frame's normal (no NaN)
    zero = mdf.weighted_layer(layer=mdf.specular_bsdf(), normal=(0.0, 0.0, 0.0)).bind(state)
    assert len(zero.program.frames) == 1  # no layer frame of its own: the shading frame
    wo = tile(direction(20.0, 150.0), 3)
    s = zero.sample(wo, np.full(3, 0.5), np.full((3, 2), 0.5))
    assert np.allclose(s.wi, wo * [-1.0, -1.0, 1.0], atol=1e-12)
