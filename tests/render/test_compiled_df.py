"""render.compiled_df: the compiled per-lane dfs equal the numpy classes they port.

The numpy classes (bound from the same DfNode, as ``material.shade`` binds them) are the
reference.  eval and pdf agree to 1e-12 relative (atol 1e-300); samples: validity and the
delta flag exactly, directions to 1e-12 of their length (a component that nearly cancels
has no meaningful relative error of its own), pdf and weight to 1e-12 (see
:func:`assert_sample_equal`).
"""

from __future__ import annotations

import threading

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from displacement.state import ShadingState
from render import compiled_df as C
from render.df import DiffuseReflectionBsdf, SimpleGlossyBsdf, SpecularBsdf
from render.material import df
from render.numerics import ONE_MINUS_EPS, TOL, strict

RTOL, ATOL = 1e-12, 1e-300
COLOR = (0.8, 0.3, 0.05)
ROUGH = (0.0, 1e-7, 1e-3, 0.3, 1.0)


@pytest.fixture(autouse=True)
def _strict_float():
    """The numpy reference runs strict, as in tests/render/df (underflow to 0 allowed)."""
    with strict(), np.errstate(divide="raise", invalid="raise", over="raise", under="ignore"):
        yield


def _state() -> ShadingState:
    """One lane, local frame = object frame (normal +z, tangent_u +x)."""
    return ShadingState(np.zeros((1, 3)), np.array([[0.0, 0.0, 1.0]]), np.full((1, 2), 0.5),
                        np.array([[1.0, 0.0, 0.0]]), np.array([[0.0, 1.0, 0.0]]))


def reference(node):
    """The numpy class ``material.shade`` would use for ``node``."""
    return node.bind(_state())


# --- cases -----------------------------------------------------------------------------------

CASES = {
    "lambert": df.diffuse_reflection_bsdf(),
    "lambert-color": df.diffuse_reflection_bsdf(tint=COLOR),
    "lambert-saturated": df.diffuse_reflection_bsdf(tint=(1.5, -0.5, 0.5)),
    "lambert-tint0-ms1": df.diffuse_reflection_bsdf(tint=0.0, multiscatter_tint=1.0),
    "on-tint0-ms1": df.diffuse_reflection_bsdf(tint=0.0, roughness=0.5, multiscatter_tint=1.0),
    "on-r2-saturated": df.diffuse_reflection_bsdf(tint=COLOR, roughness=2.0,
                                                  multiscatter_tint=(2.0, 0.5, -1.0)),
    **{f"on-r{r}-ms{ms}": df.diffuse_reflection_bsdf(tint=t, roughness=r, multiscatter_tint=ms)
       for r in ROUGH[1:] for t, ms in ((1.0, 0.0), (COLOR, 1.0), (1.0, (0.2, 0.7, 1.0)))},
    **{f"glossy-r{r}": df.simple_glossy_bsdf(roughness_u=r) for r in (*ROUGH, 3.0)},
    "glossy-color": df.simple_glossy_bsdf(roughness_u=0.3, tint=COLOR),
    "glossy-one-channel": df.simple_glossy_bsdf(roughness_u=0.1, tint=(0.0, 0.0, 0.5)),
    "glossy-saturated": df.simple_glossy_bsdf(roughness_u=0.2, tint=(1.5, -1.0, 0.2)),
    "glossy-aniso": df.simple_glossy_bsdf(roughness_u=0.05, roughness_v=0.4, tint=COLOR),
    "glossy-aniso-v": df.simple_glossy_bsdf(roughness_u=0.4, roughness_v=0.05),
    "glossy-aniso-0": df.simple_glossy_bsdf(roughness_u=0.0, roughness_v=0.3),
    "glossy-aniso-1e-3": df.simple_glossy_bsdf(roughness_u=1.0, roughness_v=1e-3,
                                               mode="df::scatter_reflect", handle="coat"),
    "specular": df.specular_bsdf(),
    "specular-color": df.specular_bsdf(tint=COLOR, mode="scatter_reflect"),
    "specular-saturated": df.specular_bsdf(tint=(0.0, 2.0, 0.5)),
}
BLACK_CASES = {
    "diffuse": df.diffuse_reflection_bsdf(tint=0.0, roughness=0.3),
    "glossy": df.simple_glossy_bsdf(roughness_u=0.3, tint=(0.0, 0.0, 0.0)),
    "specular": df.specular_bsdf(tint=-1.0),
}


def unit(v):
    v = np.asarray(v, dtype=np.float64)
    return np.ascontiguousarray(v / np.linalg.norm(v, axis=-1, keepdims=True))


def sphere(rng, n):
    return unit(rng.normal(size=(n, 3)))


def grazing(rng, n, zs=(1e-9, -1e-9, 0.0, -0.0, 1e-10, -1e-10, 2e-10, 1.0, -1.0)):
    """Unit directions with the given exact ``z`` and a random azimuth."""
    z = np.resize(np.asarray(zs), n)
    phi = rng.uniform(0.0, 2.0 * np.pi, n)
    s = np.sqrt(1.0 - z * z)
    return np.ascontiguousarray(np.stack([s * np.cos(phi), s * np.sin(phi), z], axis=1))


def near_mirror(rng, wo, scales=(0.0, 1e-9, 1e-7, 1e-5, 1e-3, 0.1)):
    """``mirror(wo)`` (about +z, or its negative) perturbed on the scales of narrow lobes."""
    n = len(wo)
    m = wo * np.array([-1.0, -1.0, 1.0])
    s = np.resize(np.asarray(scales), n)[:, None]
    return unit(m + s * rng.normal(size=(n, 3)))


def direction_pairs(rng, n=400):
    """(wo, wi): random, near-mirror, grazing, wo = wi, wo = -wi, poles, both hemispheres."""
    wo, wi = sphere(rng, n), sphere(rng, n)
    wo_g, wi_g = grazing(rng, n), grazing(rng, n)
    rng.shuffle(wi_g)
    poles = np.array([[0.0, 0.0, 1.0], [0.0, 0.0, -1.0]])
    p_wo, p_wi = np.repeat(poles, 2, axis=0), np.tile(poles, (2, 1))
    wos = [wo, wo, wo_g, wo, wo_g, wo_g, wo, wo, p_wo, wo_g]
    wis = [wi, near_mirror(rng, wo), wi, wi_g, wi_g, near_mirror(rng, wo_g), wo, -wo, p_wi, wo_g]
    return np.ascontiguousarray(np.concatenate(wos)), np.ascontiguousarray(np.concatenate(wis))


EDGE_U = np.array([0.0, -0.0, 0.25, 0.5, 0.75, ONE_MINUS_EPS, 1.0, -0.5, 1.5, 1e-300])


def sample_inputs(rng, n=400):
    """(wo, u1, u2): random and every edge combination of the random numbers."""
    wo = np.concatenate([sphere(rng, n), grazing(rng, n // 4)])
    u1, u2 = rng.random(len(wo)), rng.random((len(wo), 2))
    e = np.array(np.meshgrid(EDGE_U, EDGE_U, EDGE_U)).reshape(3, -1).T
    e_wo = np.concatenate([sphere(rng, len(e)), grazing(rng, len(e))])
    e = np.concatenate([e, e])
    return (np.ascontiguousarray(np.concatenate([wo, e_wo])),
            np.concatenate([u1, e[:, 0]]), np.ascontiguousarray(np.concatenate([u2, e[:, 1:]])))


# --- comparisons -------------------------------------------------------------------------------


def assert_eval_pdf_equal(node, wo, wi):
    p = C.params_of(node)
    bsdf = reference(node)
    f, pdf = C.eval_pdf_batch(p, wo, wi)
    # the classes' own strict-mode contract checks (eval >= 0) are not what is tested here;
    # see test_oren_nayar_eval_nonnegative_at_antipodal_grazing
    with strict(False):
        f_ref, pdf_ref = bsdf.eval(wo, wi), bsdf.pdf(wo, wi)
    assert np.all(np.isfinite(f)) and np.all(np.isfinite(pdf))
    np.testing.assert_allclose(f, f_ref, rtol=RTOL, atol=ATOL)
    np.testing.assert_allclose(pdf, pdf_ref, rtol=RTOL, atol=ATOL)
    assert np.all(pdf >= 0.0)
    return f, pdf


def assert_sample_equal(node, wo, u1, u2):
    """Validity, delta flag, wi, pdf and weight of the compiled sample equal the numpy one.

    Where the two sampled directions are the same bits (every diffuse and specular lane,
    most glossy ones), pdf and weight must agree to 1e-12.  Elsewhere the directions
    differ in the last bits (numpy's SIMD ``arctan2``/``log1p``/``expm1`` vs libm), and a
    glossy weight at a grazing ``wi`` amplifies that (G1(wi) ~ wi.z, which cancels): there
    pdf and weight * pdf must be the numpy class's eval_pdf at the compiled ``wi``.
    Returns ``(valid, same)``.
    """
    p = C.params_of(node)
    bsdf = reference(node)
    with strict(False):
        ref = bsdf.sample(wo, u1, u2)
    wi, pdf, weight, is_delta, valid = C.sample_batch(p, wo, u1, u2)
    for a in (wi, pdf, weight):
        assert np.all(np.isfinite(a)) and not np.any(a[~valid])
    assert np.all(pdf >= 0.0) and np.all(weight >= 0.0)
    np.testing.assert_array_equal(valid, ref.valid)
    np.testing.assert_array_equal(is_delta, ref.is_delta)
    err = np.linalg.norm(wi - ref.wi, axis=1)
    assert np.all(err <= RTOL * np.linalg.norm(ref.wi, axis=1)), err.max()
    same = valid & np.all(wi == ref.wi, axis=1)
    np.testing.assert_allclose(pdf[same], ref.pdf[same], rtol=RTOL, atol=ATOL)
    np.testing.assert_allclose(weight[same], ref.weight[same], rtol=RTOL, atol=ATOL)
    scatter = valid & ~is_delta
    with strict(False):
        f_at, pdf_at = bsdf.eval(wo, wi), bsdf.pdf(wo, wi)
    np.testing.assert_allclose(pdf[scatter], pdf_at[scatter], rtol=RTOL, atol=ATOL)
    np.testing.assert_allclose((weight * pdf[:, None])[scatter], f_at[scatter],
                               rtol=RTOL, atol=ATOL)
    return valid, same


# --- eval / pdf / sample against the numpy classes ------------------------------------------


@pytest.mark.parametrize("name", CASES)
def test_eval_pdf_equal_numpy(name, rng):
    node = CASES[name]
    wo, wi = direction_pairs(rng)
    f, pdf = assert_eval_pdf_equal(node, wo, wi)
    if C.params_of(node)[0] != C.SPECULAR:
        assert np.count_nonzero(pdf) > 50  # the comparison covered the lobe, not only zeros


@pytest.mark.parametrize("name", CASES)
def test_sample_equals_numpy(name, rng):
    node = CASES[name]
    wo, u1, u2 = sample_inputs(rng)
    valid, same = assert_sample_equal(node, wo, u1, u2)
    assert np.count_nonzero(valid) > 300  # most of the 500 random lanes
    kind = C.params_of(node)[0]
    # the direct comparison covers every diffuse and specular lane, most glossy ones
    assert np.count_nonzero(same) >= (0.75 if kind == C.SIMPLE_GLOSSY else 1.0) * valid.sum()


@pytest.mark.parametrize("name", BLACK_CASES)
def test_black_rows(name, rng):
    node = BLACK_CASES[name]
    p = C.params_of(node)
    np.testing.assert_array_equal(p, np.zeros(C.PARAM_WIDTH))
    wo, wi = direction_pairs(rng, 50)
    f, pdf = assert_eval_pdf_equal(node, wo, wi)
    assert not np.any(f) and not np.any(pdf)
    wo, u1, u2 = sample_inputs(rng, 50)
    assert not np.any(assert_sample_equal(node, wo, u1, u2)[0])


def test_oren_nayar_eval_nonnegative_at_antipodal_grazing():
    # s = wo.wi - mu1 mu2 rounds to -1 - ulp here; both implementations clamp it at -1
    # (at roughness 1, A = B and A + B s would be -1e-26)
    node = df.diffuse_reflection_bsdf(roughness=1.0)
    wo = grazing(np.random.default_rng(0), 2000, zs=(2e-10,))
    wi = np.ascontiguousarray(wo * np.array([-1.0, -1.0, 1.0]))
    f, _ = assert_eval_pdf_equal(node, wo, wi)
    assert np.all(f >= 0.0)


def test_scalar_interface():
    """The per-lane kernels, called as the integrator calls them."""
    p = C.params_of(df.diffuse_reflection_bsdf(tint=0.5))
    s = np.sqrt(0.5)
    f_r, f_g, f_b, pdf = C.eval_pdf(p[None], 0, 0.0, 0.0, 1.0, s, 0.0, s)
    assert (f_r, f_g, f_b) == (0.5 * pdf,) * 3 and pdf == s / np.pi
    mirror = C.params_of(df.specular_bsdf(tint=COLOR))[None]
    out = C.sample(mirror, 0, 0.6, 0.0, -0.8, 0.3, 0.1, 0.9)
    assert out == (-0.6, -0.0, -0.8, 1.0, *COLOR, True, True)
    black = np.zeros((1, C.PARAM_WIDTH))
    assert C.sample(black, 0, 0.0, 0.0, 1.0, 0.5, 0.5, 0.5)[-2:] == (False, False)


# --- hypothesis: parameters and directions -----------------------------------------------------

unit_float = st.one_of(st.sampled_from([0.0, 1.0, 0.5]), st.floats(-0.25, 1.25))
colors = st.one_of(unit_float, st.tuples(unit_float, unit_float, unit_float))
roughness = st.one_of(st.sampled_from(ROUGH), st.floats(0.0, 2.0))


@st.composite
def nodes(draw):
    kind = draw(st.sampled_from(["diffuse", "glossy", "specular"]))
    if kind == "diffuse":
        return df.diffuse_reflection_bsdf(tint=draw(colors), roughness=draw(roughness),
                                          multiscatter_tint=draw(colors))
    if kind == "glossy":
        return df.simple_glossy_bsdf(roughness_u=draw(roughness), roughness_v=draw(roughness),
                                     tint=draw(colors))
    return df.specular_bsdf(tint=draw(colors))


@st.composite
def directions(draw):
    z = draw(st.one_of(st.sampled_from([0.0, -0.0, 1e-9, -1e-9, 1e-10, 1.0, -1.0]),
                       st.floats(-1.0, 1.0)))
    phi = draw(st.floats(0.0, 2.0 * np.pi))
    s = np.sqrt(1.0 - z * z)
    return np.array([s * np.cos(phi), s * np.sin(phi), z])


@st.composite
def wi_for(draw, wo):
    how = draw(st.sampled_from(["free", "mirror", "same", "opposite"]))
    if how == "free":
        return draw(directions())
    if how == "same":
        return wo.copy()
    if how == "opposite":
        return -wo
    scale = draw(st.sampled_from([0.0, 1e-9, 1e-6, 1e-3, 0.1]))
    v = wo * np.array([-1.0, -1.0, 1.0]) + scale * np.array(
        draw(st.tuples(*[st.floats(-1.0, 1.0)] * 3)))
    norm = np.linalg.norm(v)
    return v / norm if norm > 0.5 else wo * np.array([-1.0, -1.0, 1.0])


u_float = st.one_of(st.sampled_from([0.0, 0.25, 0.5, 0.75, ONE_MINUS_EPS, 1.0]),
                    st.floats(0.0, 1.0))


@settings(max_examples=300, deadline=None)
@given(node=nodes(), data=st.data())
def test_property_eval_pdf(node, data):
    wo = data.draw(directions())
    wi = data.draw(wi_for(wo))
    assert_eval_pdf_equal(node, wo[None, :], np.ascontiguousarray(wi[None, :]))


@settings(max_examples=300, deadline=None)
@given(node=nodes(), wo=directions(), u=st.tuples(u_float, u_float, u_float))
def test_property_sample(node, wo, u):
    assert_sample_equal(node, wo[None, :], np.array([u[0]]), np.array([[u[1], u[2]]]))


# --- params_of -----------------------------------------------------------------------------------


def expected_row(bsdf) -> np.ndarray:
    """The row read off the bound numpy class (what ``material.shade`` evaluates)."""
    row = np.zeros(C.PARAM_WIDTH)
    row[1:4] = bsdf.tint[0]
    if isinstance(bsdf, DiffuseReflectionBsdf):
        row[0] = C.DIFFUSE_REFLECTION
        row[4] = bsdf.roughness
        row[6:9] = bsdf.multiscatter_tint[0]
    elif isinstance(bsdf, SimpleGlossyBsdf):
        assert bsdf.mode.value == "scatter_reflect"
        np.testing.assert_array_equal(bsdf.tangent_u, [[1.0, 0.0, 0.0]])
        row[0] = C.SIMPLE_GLOSSY
        row[4], row[5] = bsdf.roughness_u, bsdf.roughness_v
    else:
        assert isinstance(bsdf, SpecularBsdf) and bsdf.mode.value == "scatter_reflect"
        row[0] = C.SPECULAR
    return row


@pytest.mark.parametrize("name", CASES)
def test_params_of_rows(name):
    node = CASES[name]
    p = C.params_of(node)
    assert p.shape == (C.PARAM_WIDTH,) and p.dtype == np.float64
    np.testing.assert_array_equal(p, expected_row(reference(node)))


def test_params_of_clamps_as_the_classes():
    p = C.params_of(df.diffuse_reflection_bsdf(tint=(1.5, -0.5, 0.5), roughness=2.0,
                                               multiscatter_tint=(-1.0, 0.25, 9.0)))
    assert p.tolist() == [1.0, 1.0, 0.0, 0.5, 1.0, 0.0, 0.0, 0.25, 1.0, 0.0]
    p = C.params_of(df.simple_glossy_bsdf(roughness_u=0.0, tint=0.5))
    assert p.tolist() == [2.0, 0.5, 0.5, 0.5, TOL.roughness_min, TOL.roughness_min, 0, 0, 0, 0]
    assert C.params_of(df.simple_glossy_bsdf(roughness_u=3.0, roughness_v=-1.0))[4:6].tolist() \
        == [3.0, TOL.roughness_min]


def _varying(state):
    return np.full(len(state.uv), 0.5)


def _varying_color(state):
    return np.full((len(state.uv), 3), 0.5)


@pytest.mark.parametrize("node", [
    df.diffuse_reflection_bsdf(tint=_varying_color),
    df.diffuse_reflection_bsdf(roughness=_varying),
    df.diffuse_reflection_bsdf(multiscatter_tint=_varying_color),
    df.diffuse_reflection_bsdf(tint=0.0, multiscatter_tint=_varying_color),
    df.simple_glossy_bsdf(roughness_u=_varying),
    df.simple_glossy_bsdf(roughness_u=0.3, roughness_v=_varying),
    df.simple_glossy_bsdf(roughness_u=0.3, tint=_varying_color),
    df.simple_glossy_bsdf(roughness_u=0.3, tangent_u=(1.0, 0.0, 0.0)),
    df.simple_glossy_bsdf(roughness_u=0.3, tangent_u=lambda s: s.tangent_v),
    df.simple_glossy_bsdf(roughness_u=0.3, multiscatter_tint=0.5),
    df.simple_glossy_bsdf(roughness_u=0.3, mode="scatter_transmit"),
    df.simple_glossy_bsdf(roughness_u=0.3, mode="scatter_reflect_transmit"),
    df.specular_bsdf(mode="scatter_transmit"),
    df.specular_bsdf(mode="df::scatter_reflect_transmit"),
    df.specular_bsdf(tint=_varying_color),
    df.diffuse_transmission_bsdf(tint=0.5),
    df.backscattering_glossy_reflection_bsdf(roughness_u=0.3),
    df.weighted_layer(weight=0.5, layer=df.specular_bsdf(), base=df.diffuse_reflection_bsdf()),
    df.tint(tint=0.5, base=df.diffuse_reflection_bsdf()),
    df.normalized_mix(components=[df.bsdf_component(weight=1.0,
                                                    component=df.diffuse_reflection_bsdf())]),
    df.diffuse_edf(),
    None,
    "diffuse_reflection_bsdf",
], ids=repr)
def test_params_of_rejects(node):
    assert C.params_of(node) is None


@pytest.mark.parametrize("node", [
    df.diffuse_reflection_bsdf(tint=0.0, roughness=_varying),
    df.simple_glossy_bsdf(roughness_u=_varying, tint=(0.0, 0.0, 0.0)),
    df.specular_bsdf(tint=0.0, mode="scatter_transmit"),
    df.diffuse_transmission_bsdf(tint=-0.5),
], ids=repr)
def test_params_of_black_nodes(node):
    assert node.is_black
    np.testing.assert_array_equal(C.params_of(node), np.zeros(C.PARAM_WIDTH))


# --- compiled-kernel properties -----------------------------------------------------------------


def test_two_threads_at_once(rng):
    """nogil kernels run concurrently and give the same results as one thread."""
    p = C.params_of(CASES["glossy-aniso"])
    wo, u1, u2 = sphere(rng, 100_000), rng.random(100_000), rng.random((100_000, 2))
    expected = C.sample_batch(p, wo, u1, u2)
    out = [None, None]

    def run(k):
        out[k] = C.sample_batch(p, wo, u1, u2)

    threads = [threading.Thread(target=run, args=(k,)) for k in range(2)]
    for t in threads:
        t.start()
    for t in threads:
        t.join()
    for result in out:
        for a, b in zip(result, expected, strict=True):
            np.testing.assert_array_equal(a, b)
    for kernel in (C.eval_pdf, C.sample, C.eval_pdf_batch, C.sample_batch):
        assert kernel.targetoptions.get("nogil") is True


def test_tolerances_match_numerics():
    assert (C._COS_ZERO, C._ROUGHNESS_MIN, C._UNIT_MIN) == (
        TOL.cos_zero, TOL.roughness_min, TOL.unit_min)
