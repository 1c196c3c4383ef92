"""The MDL material model: struct defaults, df nodes and binding, and material.shade."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from displacement.bump import HORIZON_MIN_COS, round_bump_normal
from displacement.fields import Field
from displacement.state import ShadingState
from displacement.surfaces import UnitSquare, UVSphere
from render.df import DiffuseEdf, DiffuseReflectionBsdf, SimpleGlossyBsdf, SpecularBsdf
from render.material import (
    DF_SIGNATURES,
    Color,
    Float,
    MdlType,
    Shading,
    Varying,
    df,
    evaluate,
    material,
    material_emission,
    material_geometry,
    material_surface,
    material_volume,
    mdl_signature,
)


def square(uv) -> ShadingState:
    return UnitSquare().state_at_uv(np.asarray(uv, dtype=np.float64).reshape(-1, 2))


def frame_state(normal, tangent_u, tangent_v, n=1) -> ShadingState:
    def rows(v):
        return np.tile(np.asarray(v, dtype=np.float64), (n, 1))
    return ShadingState(rows((0.0, 0.0, 0.0)), rows(normal), np.full((n, 2), 0.5),
                        rows(tangent_u), rows(tangent_v))


def bumped(bump_scale, u_scale=1.0, v_scale=1.0):
    return material(
        surface=material_surface(df.diffuse_reflection_bsdf(tint=0.5)),
        geometry=material_geometry(
            normal=lambda s: round_bump_normal(s, bump_scale, u_scale, v_scale, horizon=None)),
    )


def assert_shading_normal_ok(shading: Shading, state: ShadingState):
    n = shading.normal
    assert np.all(np.isfinite(n))
    assert np.allclose(np.linalg.norm(n, axis=1), 1.0, atol=1e-12)
    assert np.all(np.einsum("ij,ij->i", n, state.normal) >= HORIZON_MIN_COS - 1e-12)


# ---------------------------------------------------------------------------
# structs


def test_struct_defaults_are_mdl_defaults():
    m = material()
    assert m.thin_walled is False
    assert m.ior == (1.0, 1.0, 1.0)
    assert m.surface == material_surface() and m.backface == material_surface()
    assert m.surface.scattering is None and m.surface.is_default
    e = m.surface.emission
    assert (e.emission, e.intensity) == (None, (0.0, 0.0, 0.0))
    assert e.mode == "intensity_radiant_exitance"
    v = m.volume
    assert (v.scattering, v.absorption_coefficient, v.scattering_coefficient) == (
        None, (0.0, 0.0, 0.0), (0.0, 0.0, 0.0))
    g = m.geometry
    assert (g.displacement, g.cutout_opacity, g.normal) == (None, 1.0, None)
    assert m.displacement is None


def test_structs_are_frozen():
    m = material()
    with pytest.raises(AttributeError):
        m.thin_walled = True  # type: ignore[misc]


def test_constant_displacement_becomes_field_and_zero_becomes_none():
    assert material_geometry(displacement=(0.0, 0.0, 0.0)).displacement is None
    g = material_geometry(displacement=(0.0, 0.0, 0.25))
    assert isinstance(g.displacement, Field)
    assert g.displacement(square([[0.3, 0.7]])).tolist() == [[0.0, 0.0, 0.25]]


@pytest.mark.parametrize("make, match", [
    (lambda: material(thin_walled=1), "thin_walled must be a bool"),
    (lambda: material(surface=df.diffuse_reflection_bsdf()), "surface must be a material_surface"),
    (lambda: material(ior=(1.0, 0.0, 1.5)), "ior must be > 0"),
    (lambda: material_surface(scattering=df.diffuse_edf()), "scattering must be a bsdf node"),
    (lambda: material_emission(emission=df.diffuse_reflection_bsdf()), "must be an edf node"),
    (lambda: material_emission(mode="power"), "intensity_power"),
    (lambda: material_volume(scattering=df.diffuse_edf()), "must be a vdf node"),
    (lambda: material_geometry(displacement=(1.0, np.nan, 0.0)), "three finite numbers"),
    (lambda: material_geometry(cutout_opacity=(0.5, 0.5)), "cutout_opacity must be a float"),
])
def test_struct_validation(make, match):
    with pytest.raises(ValueError, match=match):
        make()


# ---------------------------------------------------------------------------
# df nodes


def test_every_df_has_a_constructor_with_its_mdl_signature():
    for name, (kind, params) in DF_SIGNATURES.items():
        constructor = getattr(df, name)
        sig_params, returns = mdl_signature(constructor)
        assert [p.name for p in sig_params] == [p for p, _, _ in params]
        assert returns == MdlType(kind)


def test_df_constructors_accept_positional_and_named_arguments():
    node = df.simple_glossy_bsdf(0.3, tint=(0.6, 0.4, 0.0))
    assert dict(node.kwargs) == {"roughness_u": 0.3, "tint": (0.6, 0.4, 0.0)}
    with pytest.raises(ValueError, match="got two values for 'roughness_u'"):
        df.simple_glossy_bsdf(0.3, roughness_u=0.2)
    with pytest.raises(ValueError, match="needs the argument 'roughness_u'"):
        df.simple_glossy_bsdf(tint=0.5)
    with pytest.raises(ValueError, match="did you mean 'roughness_u'"):
        df.simple_glossy_bsdf(roughnes_u=0.1)
    with pytest.raises(ValueError, match="must be one of scatter_reflect"):
        df.specular_bsdf(mode="reflect_transmit")
    with pytest.raises(ValueError, match="must be finite"):
        df.diffuse_reflection_bsdf(tint=(1.0, np.inf, 0.0))
    assert df.specular_bsdf(mode="df::scatter_transmit").kwargs["mode"] == "scatter_transmit"


def test_df_nodes_are_not_callable_so_they_never_pass_as_varying_values():
    assert not callable(df.diffuse_edf())


def test_bind_evaluates_callables_per_lane():
    s = square([[0.25, 0.5], [0.75, 0.5]])
    node = df.diffuse_reflection_bsdf(tint=lambda st: np.stack([st.uv[:, 0]] * 3, axis=1),
                                      roughness=lambda st: st.uv[:, 1])
    bsdf = node.bind(s)
    assert isinstance(bsdf, DiffuseReflectionBsdf)
    assert bsdf.tint.tolist() == [[0.25] * 3, [0.75] * 3]
    assert bsdf.roughness.tolist() == [0.5, 0.5]


def test_bind_rejects_bad_callable_results():
    s = square([[0.25, 0.5], [0.75, 0.5]])
    with pytest.raises(ValueError, match=r"tint\) \(a color\) must be"):
        df.diffuse_reflection_bsdf(tint=lambda st: st.uv).bind(s)
    with pytest.raises(ValueError, match="non-finite"):
        df.diffuse_reflection_bsdf(roughness=lambda st: st.uv[:, 0] * np.nan).bind(s)


def test_bind_expresses_tangent_u_in_the_local_frame():
    # tangent_v of the unit square is +y; in the frame built from (normal, tangent_u) it is +y local
    s = square([[0.5, 0.5]])
    bsdf = df.simple_glossy_bsdf(roughness_u=0.1, roughness_v=0.4,
                                 tangent_u=lambda st: st.tangent_v).bind(s)
    assert np.allclose(bsdf.tangent_u, [[0.0, 1.0, 0.0]])
    default = df.simple_glossy_bsdf(roughness_u=0.1).bind(s)
    assert np.allclose(default.tangent_u, [[1.0, 0.0, 0.0]])


def test_bind_passes_renderer_context_to_classes_that_take_it():
    s = square([[0.5, 0.5]])
    b = df.specular_bsdf(mode="scatter_reflect_transmit").bind(s, ior_inside=1.5, thin_walled=True)
    assert isinstance(b, SpecularBsdf) and b.ior_inside.tolist() == 1.5 and b.thin_walled
    d = df.diffuse_reflection_bsdf().bind(s, ior_inside=1.5)   # ignored by diffuse
    assert isinstance(d, DiffuseReflectionBsdf)
    with pytest.raises(ValueError, match="unknown bind context"):
        df.diffuse_reflection_bsdf().bind(s, eta=1.5)


def test_bind_passes_multiscatter_tint_and_other_dfs():
    s = square([[0.5, 0.5]])
    # multiscatter_tint binds (issue 16): the compensation lobe raises the albedo
    wo = np.array([[0.0, 0.6, 0.8]])
    single = df.simple_glossy_bsdf(roughness_u=0.8).bind(s).albedo(wo)
    comp = df.simple_glossy_bsdf(roughness_u=0.8, multiscatter_tint=0.5).bind(s).albedo(wo)
    assert np.allclose(comp, single + 0.5 * (1.0 - single))
    from render.df import AnisotropicVdf

    assert isinstance(df.anisotropic_vdf(directional_bias=-0.5).bind(s), AnisotropicVdf)


def test_is_black():
    assert df.diffuse_reflection_bsdf(tint=0.0).is_black
    assert df.diffuse_reflection_bsdf(tint=(0.0, 0.0, 0.0)).is_black
    assert not df.diffuse_reflection_bsdf(tint=(0.0, 0.0, 0.0), multiscatter_tint=0.5).is_black
    assert not df.diffuse_reflection_bsdf(tint=lambda s: np.zeros((len(s), 3))).is_black
    assert not df.diffuse_edf().is_black


# ---------------------------------------------------------------------------
# evaluate and signatures


def test_evaluate_shapes():
    s = square([[0.25, 0.5], [0.75, 0.0]])
    assert evaluate((0.1, 0.2), s, "float2").tolist() == [[0.1, 0.2], [0.1, 0.2]]
    assert evaluate(lambda st: st.uv, s, "float2").tolist() == [[0.25, 0.5], [0.75, 0.0]]
    assert evaluate((1.0, 2.0, 3.0), s, "float3").shape == (2, 3)
    with pytest.raises(ValueError, match=r"shape \(2,\)"):
        evaluate((1.0, 2.0, 3.0), s, "float")
    with pytest.raises(ValueError, match="kind must be"):
        evaluate(1.0, s, "float4")
    with pytest.raises(ValueError, match="must be a number"):
        evaluate("red", s, "color")


def test_evaluate_zero_lanes():
    s = square(np.zeros((0, 2)))
    assert evaluate(0.5, s, "color").shape == (0, 3)
    assert evaluate(lambda st: st.uv[:, 0], s, "float").shape == (0,)


def test_mdl_signature_reads_annotations():
    def f(tint: Color = 0.5, roughness: Float = 0.3) -> material:
        return material()

    params, returns = mdl_signature(f)
    assert [(p.name, p.type.name, p.required) for p in params] == [
        ("tint", "color", False), ("roughness", "float", False)]
    assert returns == MdlType("material")

    def g(x, y: Float = 1.0):
        return x

    with pytest.raises(TypeError, match="parameter 'x' has no MDL type annotation"):
        mdl_signature(g)


def test_varying_repr_and_call():
    v = Varying(lambda s: s.uv[:, 1], "v", {"texture_space": 0})
    assert repr(v) == "v(texture_space: 0)"
    assert v(square([[0.1, 0.9]])).tolist() == [0.9]


# ---------------------------------------------------------------------------
# shade


def test_shade_black_material_and_emission():
    s = square([[0.5, 0.5], [0.0, 1.0]])
    sh = material().shade(s)
    assert sh.bsdf is None and sh.edf is None
    assert sh.intensity.tolist() == [[0.0] * 3] * 2
    assert sh.cutout_opacity.tolist() == [1.0, 1.0]
    assert sh.normal is s.normal
    glow = material(surface=material_surface(emission=material_emission(
        emission=df.diffuse_edf(), intensity=(1.0, 2.0, 3.0))))
    sh = glow.shade(s)
    assert isinstance(sh.edf, DiffuseEdf) and sh.bsdf is None
    assert sh.intensity.tolist() == [[1.0, 2.0, 3.0]] * 2


def test_shade_skips_trivially_black_lobes_and_zero_emission():
    s = square([[0.5, 0.5]])
    m = material(surface=material_surface(
        df.diffuse_reflection_bsdf(tint=0.0),
        material_emission(emission=df.diffuse_edf(), intensity=0.0)))
    sh = m.shade(s)
    assert sh.bsdf is None and sh.edf is None


def test_emission_is_front_side_only():
    s = square([[0.5, 0.5], [0.5, 0.5]])
    glow = material(surface=material_surface(emission=material_emission(
        emission=df.diffuse_edf(), intensity=(1.0, 1.0, 1.0))))
    sh = glow.shade(s, front=np.array([True, False]))
    assert sh.intensity.tolist() == [[1.0] * 3, [0.0] * 3]
    assert glow.shade(s, front=np.array([False, False])).edf is None
    with pytest.raises(ValueError, match="bool array"):
        glow.shade(s, front=np.array([1, 0]))


def test_thin_walled_backface_is_used_on_back_lanes():
    s = square([[0.5, 0.5], [0.5, 0.5]])
    m = material(thin_walled=True, surface=material_surface(df.diffuse_reflection_bsdf(tint=0.2)),
                 backface=material_surface(df.diffuse_reflection_bsdf(tint=0.9)))
    assert m.shade(s).bsdf.tint.tolist() == [[0.2] * 3]
    assert m.shade(s, front=np.array([False, False])).bsdf.tint.tolist() == [[0.9] * 3]
    with pytest.raises(ValueError, match="separately for front lanes and back lanes"):
        m.shade(s, front=np.array([True, False]))
    # not thin-walled: the backface is ignored
    m2 = material(surface=m.surface, backface=m.backface)
    assert m2.shade(s, front=np.array([False, False])).bsdf.tint.tolist() == [[0.2] * 3]


def test_cutout_opacity_is_clamped_and_nan_is_an_error():
    s = square([[0.0, 0.0], [0.5, 0.0], [1.0, 0.0]])
    m = material(geometry=material_geometry(cutout_opacity=lambda st: 3.0 * st.uv[:, 0] - 1.0))
    assert m.shade(s).cutout_opacity.tolist() == [0.0, 0.5, 1.0]
    below = material(geometry=material_geometry(cutout_opacity=-2.0))
    assert below.shade(s).cutout_opacity.tolist() == [0.0] * 3
    bad = material(geometry=material_geometry(cutout_opacity=lambda st: st.uv[:, 0] * np.nan))
    with pytest.raises(ValueError, match="non-finite"):
        bad.shade(s)


def test_replaced_normal_is_seen_by_df_arguments():
    s = square([[0.5, 0.5]])
    tilted = np.array([[0.6, 0.0, 0.8]])
    seen = []

    def tint(st):
        seen.append(st.normal.copy())
        return np.full((len(st), 3), 0.5)

    m = material(surface=material_surface(df.diffuse_reflection_bsdf(tint=tint)),
                 geometry=material_geometry(normal=lambda st: tilted))
    sh = m.shade(s)
    assert np.allclose(seen[0], tilted) and np.allclose(sh.normal, tilted)
    assert np.allclose(sh.state.normal, tilted)
    assert np.allclose(sh.frame.n, tilted)
    # the frame's s axis is tangent_u projected into the new tangent plane
    assert np.allclose(sh.frame.s, [[0.8, 0.0, -0.6]])


def test_cutout_sees_the_normal_before_replacement():
    s = square([[0.5, 0.5]])
    m = material(geometry=material_geometry(
        cutout_opacity=lambda st: st.normal[:, 2], normal=(1.0, 0.0, 0.0)))
    sh = m.shade(s)
    assert sh.cutout_opacity.tolist() == [1.0]
    # (1, 0, 0) is on the horizon: bent up to the minimum cosine
    assert np.isclose(sh.normal[0, 2], HORIZON_MIN_COS)


@pytest.mark.parametrize("normal", [
    (0.0, 0.0, -1.0), (0.0, 0.0, 0.0), (np.nan, 0.0, 1.0), (np.inf, 0.0, 0.0), (1e300, 0.0, -1e300),
    (1e-300, 0.0, 0.0), (0.3, -0.4, -0.5),
])
def test_degenerate_normals_give_unit_normals_above_the_horizon(normal):
    s = square([[0.5, 0.5], [0.0, 1.0]])
    m = material(geometry=material_geometry(normal=lambda st: np.tile(normal, (len(st), 1))))
    sh = m.shade(s)
    assert_shading_normal_ok(sh, s)


@pytest.mark.parametrize("bump_scale", [0.0, 1.0, -1.0, 100.0, -100.0, 1e6])
@pytest.mark.parametrize("uv", [(0.0, 0.0), (1.0, 1.0), (0.5, 0.5), (-0.25, -3.75), (0.75, 0.5),
                                (1e6 + 0.3, -1e6 + 0.6)])
def test_round_bumps_at_extremes(bump_scale, uv):
    s = square([uv])
    sh = bumped(bump_scale, 8.0, 4.0).shade(s)
    assert_shading_normal_ok(sh, s)
    if bump_scale == 0.0:
        assert np.allclose(sh.normal, [[0.0, 0.0, 1.0]])


def test_bumps_on_grazing_and_skewed_frames():
    # a sphere near its poles and a frame whose tangents are nearly parallel to the normal
    sphere = UVSphere().state_at_uv(np.array([[0.3, 0.0], [0.3, 1.0], [0.0, 1e-9], [0.9, 0.5]]))
    skew = frame_state((0.0, 0.0, 1.0), (1e-3, 0.0, 1.0), (0.0, 1e-3, 1.0), n=3)
    for state in (sphere, skew):
        for scale in (-100.0, 1.0, 100.0):
            sh = bumped(scale, 3.0, 3.0).shade(state)
            assert_shading_normal_ok(sh, state)


def test_shade_ior_context_reaches_the_bsdf():
    s = square([[0.5, 0.5]])
    glass = material(ior=(1.4, 1.5, 1.6), thin_walled=True, surface=material_surface(
        df.simple_glossy_bsdf(roughness_u=0.1, mode="scatter_reflect_transmit")))
    sh = glass.shade(s)
    assert isinstance(sh.bsdf, SimpleGlossyBsdf)
    assert np.allclose(sh.bsdf.ior_inside, 1.5) and sh.bsdf.thin_walled
    assert sh.ior.tolist() == [[1.4, 1.5, 1.6]] and sh.thin_walled
    with pytest.raises(ValueError, match="ior must be > 0 on every lane"):
        material(ior=lambda st: np.zeros((len(st), 3))).shade(s)


def test_spot_edf_gets_object_to_local_from_the_frame():
    s = square([[0.5, 0.5]])
    m = material(surface=material_surface(emission=material_emission(
        emission=df.spot_edf(exponent=4.0), intensity=1.0)))
    edf = m.shade(s).edf
    assert np.allclose(edf.axis, [[0.0, 0.0, 1.0]])    # object +z is the local +z here


def test_shade_zero_lanes():
    s = square(np.zeros((0, 2)))
    sh = bumped(2.0).shade(s)
    assert sh.normal.shape == (0, 3) and sh.cutout_opacity.shape == (0,)


@settings(max_examples=60)
@given(st.lists(st.tuples(st.floats(-1e3, 1e3), st.floats(-1e3, 1e3)), min_size=1, max_size=20),
       st.floats(-1e4, 1e4), st.floats(0.01, 100.0))
def test_bumped_shading_is_always_unit_and_above_the_horizon(uvs, bump_scale, tiles):
    s = square(uvs)
    sh = bumped(bump_scale, tiles, tiles).shade(s)
    assert_shading_normal_ok(sh, s)
