"""The combiners' per-node kernels (layer factors, modifier scales, mix weights) against
the numpy classes they port, over random lanes and at the extremes.

Each kernel runs over every lane through a small njit loop; the numpy reference is the
class's own private method (``_factors``, ``_estimates``, ``_possible``, ``_curves``,
``_curve``, ``_scale``, ``weights``) on nodes built from elemental children.
"""

from __future__ import annotations

import importlib
import inspect

import numpy as np
import pytest
from render_df_cases import edge_dirs, random_dirs

from render.df import (
    color_bsdf_component,
    color_custom_curve_layer,
    color_fresnel_layer,
    color_weighted_layer,
    custom_curve_layer,
    diffuse_reflection_bsdf,
    directional_factor,
    fresnel_layer,
    simple_glossy_bsdf,
    specular_bsdf,
    tint,
    weighted_layer,
)
from render.df._mix import COMPONENT_WIDTH, bsdf_component, component_signature
from render.df._signature import REQUIRED, THIN_WALLED
from render.jit import njit
from render.material import DF_SIGNATURES

WL = importlib.import_module("render.df.weighted_layer")
FL = importlib.import_module("render.df.fresnel_layer")
CL = importlib.import_module("render.df.custom_curve_layer")
TI = importlib.import_module("render.df.tint")
DFAC = importlib.import_module("render.df.directional_factor")
NM = importlib.import_module("render.df.normalized_mix")
CM = importlib.import_module("render.df.clamped_mix")

#: relative agreement with numpy (the kernels repeat numpy's operations in its order; the
#: custom curves' pow is libm's in both on this machine, so most lanes agree bit for bit)
RTOL, ATOL = 1e-12, 1e-15
TILT = np.array([0.3, -0.2, 0.9]) / np.linalg.norm([0.3, -0.2, 0.9])


# --- the test's packer (the lead's render.program replaces it) -----------------------------


def pack(sig, n: int, **values) -> np.ndarray:
    """(n, sig.width) slot rows: each packed parameter from ``values`` or its default
    (a float: scalar or (n,); a colour: scalar, (3,) or (n, 3)), broadcast to its slots
    (a float packed as a colour), clamped; then the context values (scalar or (n,))."""
    cols = []
    for p in sig.params:
        if not p.width:
            continue
        v = values.get(p.name, p.default)
        if isinstance(v, str):  # "state::normal()"
            v = (0.0, 0.0, 1.0)  # the inherited normal, in the local frame
        v = np.asarray(v, dtype=np.float64)
        if v.ndim == 1 and p.type == "float":
            v = v[:, None]  # per lane
        v = np.broadcast_to(v, (n, p.width))
        if p.clamp is not None:
            v = np.clip(v, p.clamp[0], p.clamp[1])
        cols.append(v)
    for name in sig.context:
        cols.append(np.broadcast_to(np.asarray(values[name], dtype=np.float64), (n,))[:, None])
    return np.ascontiguousarray(np.concatenate(cols, axis=1))


# --- vectorising loops over the kernels -------------------------------------------------


@njit
def run_factors(kern, P, flags, wo, wi, wo_l, wi_l, co, ci):
    out = np.empty((len(P), 6))
    for r in range(len(P)):
        out[r] = kern(P, r, 0, flags, wo[r, 0], wo[r, 1], wo[r, 2], wi[r, 0], wi[r, 1],
                      wi[r, 2], wo_l[r, 0], wo_l[r, 1], wo_l[r, 2], wi_l[r, 0], wi_l[r, 1],
                      wi_l[r, 2], co[r, 0], co[r, 1], co[r, 2], ci[r, 0], ci[r, 1], ci[r, 2])
    return out


@njit
def run_estimates(kern, P, flags, wo, wo_l, co):
    out = np.empty((len(P), 6))
    for r in range(len(P)):
        out[r] = kern(P, r, 0, flags, wo[r, 0], wo[r, 1], wo[r, 2], wo_l[r, 0], wo_l[r, 1],
                      wo_l[r, 2], co[r, 0], co[r, 1], co[r, 2])
    return out


@njit
def run_pair(kern, P, flags):
    out = np.empty((len(P), 2), dtype=np.bool_)
    for r in range(len(P)):
        a, b = kern(P, r, 0, flags)
        out[r, 0] = a
        out[r, 1] = b
    return out


@njit
def run_flag(kern, P, flags):
    out = np.empty(len(P), dtype=np.bool_)
    for r in range(len(P)):
        out[r] = kern(P, r, 0, flags)
    return out


@njit
def run_two_dirs(kern, P, flags, v, x):
    out = np.empty((len(P), 3))
    for r in range(len(P)):
        out[r] = kern(P, r, 0, flags, v[r, 0], v[r, 1], v[r, 2], x[r, 0], x[r, 1], x[r, 2])
    return out


@njit
def run_one_dir(kern, P, flags, v):
    out = np.empty((len(P), 3))
    for r in range(len(P)):
        out[r] = kern(P, r, 0, flags, v[r, 0], v[r, 1], v[r, 2])
    return out


@njit
def run_mix(kern, P, k):
    out = np.empty((len(P), k, 3))
    for r in range(len(P)):
        for i in range(k):
            out[r, i] = kern(P, r, 0, 0, k, i)
    return out


def close(kernel_out, numpy_out) -> None:
    np.testing.assert_allclose(kernel_out, numpy_out, rtol=RTOL, atol=ATOL)
    assert np.all(np.isfinite(kernel_out))


# --- lanes ---------------------------------------------------------------------------------


def lanes_wo_wi(rng, n: int) -> tuple[np.ndarray, np.ndarray]:
    """Direction pairs: random, the edge directions (poles, horizon, 89.9 degrees, both
    sides) against random and edge partners, mirror pairs, opposite pairs, equal pairs."""
    e = edge_dirs()
    wo = [random_dirs(rng, n), np.repeat(e, len(e), axis=0), e, e, e, random_dirs(rng, 200)]
    wi = [random_dirs(rng, n), np.tile(e, (len(e), 1)), e * [-1.0, -1.0, 1.0], -e, e,
          random_dirs(rng, 200) * [1.0, 1.0, -1.0]]
    return np.concatenate(wo), np.concatenate(wi)


def pick(rng, m: int, extremes, lo: float, hi: float) -> np.ndarray:
    """``m`` values: a third the extremes (cycled), the rest uniform in [lo, hi]."""
    v = rng.uniform(lo, hi, m)
    k = m // 3
    v[:k] = np.resize(np.asarray(extremes, dtype=np.float64), k)
    return rng.permutation(v)


def pick3(rng, m, extremes, lo, hi) -> np.ndarray:
    """(m, 3) per-channel values (grey on a third of the lanes)."""
    v = np.stack([pick(rng, m, extremes, lo, hi) for _ in range(3)], axis=1)
    grey = rng.random(m) < 1.0 / 3.0
    v[grey] = v[grey, :1]
    return v


def frames(node, wo, wi):
    lf = node.layer_frame
    return lf.to_layer(wo), lf.to_layer(wi)


# --- the layers ----------------------------------------------------------------------------


LAYERS = {
    "weighted": WL,
    "fresnel": FL,
    "custom_curve": CL,
}


def weighted_case(rng, n, color, normal):
    w = pick3(rng, n, (0.0, 1.0), 0.0, 1.0) if color else pick(rng, n, (0.0, 1.0), 0.0, 1.0)
    ctor = color_weighted_layer if color else weighted_layer
    node = ctor(weight=w, layer=simple_glossy_bsdf(roughness_u=0.3),
                base=diffuse_reflection_bsdf(), normal=normal)
    sig = WL.COLOR_SIGNATURE if color else WL.SIGNATURE
    return node, pack(sig, n, weight=w), 0


def fresnel_case(rng, n, color, normal, thin=False):
    if color:
        ior = pick3(rng, n, (1.0, 1.0001, 3.0, 0.5), 0.8, 3.0)
        w = pick3(rng, n, (0.0, 1.0), 0.0, 1.0)
        ctor = color_fresnel_layer
    else:
        ior = pick(rng, n, (1.0, 1.0001, 3.0, 0.5), 0.8, 3.0)
        w = pick(rng, n, (0.0, 1.0), 0.0, 1.0)
        ctor = fresnel_layer
    i_out = pick(rng, n, (1.0, 1.0001, 1.5), 1.0, 2.0)
    i_in = pick(rng, n, (1.0, 1.0001, 3.0), 1.0, 3.0)
    grey = ior if color else np.repeat(ior[:, None], 3, axis=1)  # numpy takes colour iors
    node = ctor(ior=grey, weight=w, layer=simple_glossy_bsdf(roughness_u=0.3),
                base=diffuse_reflection_bsdf(), normal=normal, ior_outside=i_out,
                ior_inside=i_in, thin_walled=thin)
    sig = FL.COLOR_SIGNATURE if color else FL.SIGNATURE
    P = pack(sig, n, ior=ior, weight=w, ior_outside=i_out, ior_inside=i_in)
    return node, P, THIN_WALLED if thin else 0


def custom_case(rng, n, color, normal):
    p = pick(rng, n, (0.0, 1.0, 5.0, 200.0), 0.0, 10.0)
    if color:
        r0 = pick3(rng, n, (0.0, 1.0), 0.0, 1.0)
        r90 = pick3(rng, n, (0.0, 1.0), 0.0, 1.0)
        f82 = pick3(rng, n, (0.0, 1.0), 0.0, 1.0)
        w = pick3(rng, n, (0.0, 1.0), 0.0, 1.0)
        node = color_custom_curve_layer(r0, r90, f82, p, w, simple_glossy_bsdf(roughness_u=0.4),
                                        diffuse_reflection_bsdf(), normal=normal)
        P = pack(CL.COLOR_SIGNATURE, n, normal_reflectivity=r0, grazing_reflectivity=r90,
                 f82_factor=f82, exponent=p, weight=w)
    else:
        r0 = pick(rng, n, (0.0, 1.0), 0.0, 1.0)
        r90 = pick(rng, n, (0.0, 1.0), 0.0, 1.0)
        w = pick(rng, n, (0.0, 1.0), 0.0, 1.0)
        node = custom_curve_layer(r0, r90, p, w, simple_glossy_bsdf(roughness_u=0.4),
                                  diffuse_reflection_bsdf(), normal=normal)
        P = pack(CL.SIGNATURE, n, normal_reflectivity=r0, grazing_reflectivity=r90,
                 exponent=p, weight=w)
    return node, P, 0


CASES = {"weighted": weighted_case, "fresnel": fresnel_case, "custom_curve": custom_case}
LAYER_IDS = [(k, c, t) for k in CASES for c in (False, True) for t in (False, True)]


def build(rng, kind, color, tilted, n, thin=False):
    normal = TILT if tilted else (0.0, 0.0, 1.0)
    if kind == "fresnel":
        return fresnel_case(rng, n, color, normal, thin)
    return CASES[kind](rng, n, color, normal)


def chat(node, w, w_l, role):
    """``Ĉ`` as the node's own CurveAlbedo gives it (masked by the frames' agreement)."""
    if not hasattr(node, "_curve_albedo"):
        return np.zeros((len(w), 3))
    return node._curve_albedo.at(w, w_l, role)


@pytest.mark.parametrize(("kind", "color", "tilted"), LAYER_IDS,
                         ids=[f"{k}-{'color' if c else 'float'}-{'tilted' if t else 'flat'}"
                              for k, c, t in LAYER_IDS])
def test_layer_factors_estimates_possible(kind, color, tilted, rng):
    wo, wi = lanes_wo_wi(rng, 600)
    n = len(wo)
    node, P, flags = build(rng, kind, color, tilted, n)
    m = LAYERS[kind]
    wo_l, wi_l = frames(node, wo, wi)
    co, ci = chat(node, wo, wo_l, "wo"), chat(node, wi, wi_l, "wi")
    if kind != "weighted":
        assert np.any(co > 0.0) and np.any(ci > 0.0)  # Ĉ takes part
    f_l, f_b = node._factors(wo, wi, wo_l, wi_l)
    got = run_factors(m.layer_factors, P, flags, wo, wi, wo_l, wi_l, co, ci)
    close(got, np.concatenate([f_l, f_b], axis=1))
    e_l, e_b = node._estimates(wo, wo_l)
    got = run_estimates(m.layer_estimates, P, flags, wo, wo_l, co)
    close(got, np.concatenate([e_l, e_b], axis=1))
    pos_l, pos_b = node._possible(n)
    got = run_pair(m.layer_possible, P, flags)
    np.testing.assert_array_equal(got, np.stack([pos_l, pos_b], axis=1))


@pytest.mark.parametrize("color", [False, True], ids=["float", "color"])
def test_fresnel_thin_walled(color, rng):
    """Thin-walled: the outside's eta on both sides, no refraction half vector."""
    wo, wi = lanes_wo_wi(rng, 400)
    n = len(wo)
    node, P, flags = build(rng, "fresnel", color, True, n, thin=True)
    assert flags == THIN_WALLED
    wo_l, wi_l = frames(node, wo, wi)
    co, ci = chat(node, wo, wo_l, "wo"), chat(node, wi, wi_l, "wi")
    f_l, f_b = node._factors(wo, wi, wo_l, wi_l)
    got = run_factors(FL.layer_factors, P, flags, wo, wi, wo_l, wi_l, co, ci)
    close(got, np.concatenate([f_l, f_b], axis=1))
    e_l, e_b = node._estimates(wo, wo_l)
    close(run_estimates(FL.layer_estimates, P, flags, wo, wo_l, co),
          np.concatenate([e_l, e_b], axis=1))
    v, x = random_dirs(rng, n), random_dirs(rng, n)
    close(run_two_dirs(FL.curve_h, P, flags, v, x), node._curves(v, x, v, x, node._context(v))[0])


@pytest.mark.parametrize(("kind", "color"), [(k, c) for k in CASES for c in (False, True)])
def test_curves(kind, color, rng):
    """``curve_h`` and ``curve_nk``: what CurveAlbedo integrates, in the layer frame."""
    e = edge_dirs()
    v = np.concatenate([random_dirs(rng, 800), np.repeat(e, len(e), axis=0), e, e])
    x = np.concatenate([random_dirs(rng, 800), np.tile(e, (len(e), 1)), -e,
                        e * [-1.0, -1.0, 1.0]])
    n = len(v)
    node, P, flags = build(rng, kind, color, False, n)
    m = LAYERS[kind]
    got_h = run_two_dirs(m.curve_h, P, flags, v, x)
    got_nk = run_one_dir(m.curve_nk, P, flags, v)
    if kind == "weighted":
        assert np.all(got_h == 1.0) and np.all(got_nk == 1.0)
        return
    ctx = node._context(v)
    close(got_h, node._curves(v, x, v, x, ctx)[0])
    close(got_nk, node._curve(np.abs(v[:, 2]), ctx))


def test_curve_flags(rng):
    """``curve_constant`` and ``curve_is_one`` per lane, against each one-lane node."""
    n = 1
    rows = []
    for r0, r90, f82, p in [(0.2, 0.2, 1.0, 5.0), (0.2, 0.7, 1.0, 0.0), (0.2, 0.7, 1.0, 5.0),
                            (1.0, 1.0, 1.0, 5.0), (1.0, 1.0, 0.0, 5.0), (0.3, 0.3, 0.5, 0.0),
                            ((1.0, 1.0, 0.9), 1.0, 1.0, 2.0), ((0.1, 0.5, 0.5), 0.5, 1.0, 3.0)]:
        node = color_custom_curve_layer(r0, r90, f82, p, 1.0, simple_glossy_bsdf(roughness_u=0.4),
                                        diffuse_reflection_bsdf())  # both children present
        P = pack(CL.COLOR_SIGNATURE, n, normal_reflectivity=np.broadcast_to(r0, 3),
                 grazing_reflectivity=np.broadcast_to(r90, 3), f82_factor=np.broadcast_to(f82, 3),
                 exponent=p)
        rows.append((bool(run_flag(CL.curve_constant, P, 0)[0]), node._curve_constant(),
                     bool(run_flag(CL.curve_is_one, P, 0)[0]), bool(node._curve_is_one(1)[0]),
                     tuple(run_pair(CL.layer_possible, P, 0)[0]),
                     tuple(np.concatenate(node._possible(1)))))
    for got_c, ref_c, got_1, ref_1, got_p, ref_p in rows:
        assert (got_c, got_1, got_p) == (ref_c, ref_1, ref_p)
    assert [r[0] for r in rows] == [True, True, False, True, False, False, False, False]
    for ior, out in [((1.5, 1.5, 1.5), 1.5), ((1.5, 1.5, 1.0), 1.5), ((1.0, 1.0, 1.0), 2.0)]:
        node = color_fresnel_layer(ior, 1.0, simple_glossy_bsdf(roughness_u=0.3),
                                   ior_outside=out)
        P = pack(FL.COLOR_SIGNATURE, 1, ior=ior, ior_outside=out, ior_inside=1.0)
        assert bool(run_flag(FL.curve_constant, P, 0)[0]) == node._curve_constant()
        assert not run_flag(FL.curve_is_one, P, 0)[0]
    P = pack(WL.SIGNATURE, 1, weight=0.5)
    assert run_flag(WL.curve_constant, P, 0)[0] and run_flag(WL.curve_is_one, P, 0)[0]


def test_fresnel_kernels_never_nan_on_bad_ior():
    """An ior of 0, or infinite etas, give F = 1 (the limit), never NaN."""
    wo = np.array([[0.0, 0.0, 1.0], [0.6, 0.0, -0.8], [0.0, 0.6, 0.8]])
    wi = np.array([[0.0, 0.0, 1.0], [-0.6, 0.0, 0.8], [0.0, -0.6, -0.8]])
    for ior, out in [(0.0, 1.0), (1e-320, 1.0), (1.5, 1e-320), (-1.0, 1.0)]:
        P = pack(FL.SIGNATURE, 3, ior=ior, weight=1.0, ior_outside=out, ior_inside=1.5)
        zero = np.zeros((3, 3))
        got = run_factors(FL.layer_factors, P, 0, wo, wi, wo, wi, zero, zero)
        assert np.all(np.isfinite(got))
        assert np.all((got >= 0.0) & (got <= 1.0))


# --- tint and directional_factor -----------------------------------------------------------


def test_tint_scale(rng):
    wo, wi = lanes_wo_wi(rng, 300)
    n = len(wo)
    t = pick3(rng, n, (0.0, 1.0), 0.0, 1.0)
    node = tint(t, diffuse_reflection_bsdf())
    close(run_two_dirs(TI.scale, pack(TI.SIGNATURE, n, tint=t), 0, wo, wi), node._scale(wo, wi))


def test_directional_factor_scale(rng):
    wo, wi = lanes_wo_wi(rng, 800)
    n = len(wo)
    r0 = pick3(rng, n, (0.0, 1.0), 0.0, 1.0)
    r90 = pick3(rng, n, (0.0, 1.0), 0.0, 1.0)
    f82 = pick3(rng, n, (0.0, 1.0), 0.0, 1.0)
    p = pick(rng, n, (0.0, 1.0, 5.0, 200.0), 0.0, 10.0)
    node = directional_factor(r0, r90, f82, p, base=specular_bsdf())
    P = pack(DFAC.SIGNATURE, n, normal_tint=r0, grazing_tint=r90, f82_factor=f82, exponent=p)
    got = run_two_dirs(DFAC.scale, P, 0, wo, wi)
    close(got, node._scale(wo, wi))
    assert np.any(got == 0.0) and np.any(got == 1.0)  # wo.h < 0 lanes, white curves


# --- mixes ---------------------------------------------------------------------------------


def mix_lanes(rng, n: int, k: int, color: bool) -> np.ndarray:
    """(n, k) or (n, k, 3) MDL weights: negative, 0, 1, above 1, random; sums below,
    at and above 1."""
    shape = (n, k, 3) if color else (n, k)
    w = rng.uniform(-0.2, 1.2, shape)
    special = rng.choice(np.array([-1.0, 0.0, 1.0, 2.0, 1.0 / k]), size=shape)
    w = np.where(rng.random(shape) < 0.4, special, w)
    w[: n // 8] = 1.0 / k  # sums exactly (or within rounding of) 1
    w[n // 8: n // 4] = 0.0
    return w


@pytest.mark.parametrize("k", [1, 2, 3, 5])
@pytest.mark.parametrize("color", [False, True], ids=["float", "color"])
@pytest.mark.parametrize("module", [NM, CM], ids=["normalized", "clamped"])
def test_mix_weights(module, color, k, rng):
    n = 400
    w = mix_lanes(rng, n, k, color)
    comp = color_bsdf_component if color else bsdf_component
    comps = [comp(w[:, i], diffuse_reflection_bsdf()) for i in range(k)]
    mix = (module.color_normalized_mix if module is NM and color else
           module.normalized_mix if module is NM else
           module.color_clamped_mix if color else module.clamped_mix)(comps)
    sig = component_signature(color, edf=False)
    P = np.concatenate([pack(sig, n, weight=w[:, i]) for i in range(k)], axis=1)
    assert P.shape[1] == COMPONENT_WIDTH * k
    got = run_mix(module.mix_weights, P, k)
    close(got, mix.weights(n))


# --- signatures ----------------------------------------------------------------------------


SIGNED = {
    "weighted_layer": WL.SIGNATURE, "color_weighted_layer": WL.COLOR_SIGNATURE,
    "fresnel_layer": FL.SIGNATURE, "color_fresnel_layer": FL.COLOR_SIGNATURE,
    "custom_curve_layer": CL.SIGNATURE, "color_custom_curve_layer": CL.COLOR_SIGNATURE,
    "tint": TI.SIGNATURE, "directional_factor": DFAC.SIGNATURE,
    "normalized_mix": NM.SIGNATURE, "color_normalized_mix": NM.COLOR_SIGNATURE,
    "clamped_mix": CM.SIGNATURE, "color_clamped_mix": CM.COLOR_SIGNATURE,
    "bsdf_component": component_signature(False, False),
    "color_bsdf_component": component_signature(True, False),
    "edf_component": component_signature(False, True),
    "color_edf_component": component_signature(True, True),
}


@pytest.mark.parametrize("name", sorted(SIGNED))
def test_signature_is_mdl(name):
    """Names, order and defaults of the MDL parameters as DF_SIGNATURES has them."""
    sig = SIGNED[name]
    mdl = [p for p in sig.params if p.mdl]
    ref = DF_SIGNATURES[name][1]
    assert [p.name for p in mdl] == [r[0] for r in ref]
    for p, (_, _, default) in zip(mdl, ref, strict=True):
        if default is inspect.Parameter.empty:
            assert p.default is REQUIRED, p.name
        elif isinstance(default, (int, float, tuple)) or default is None:
            assert p.default == default, p.name
        else:
            assert p.default == repr(default), p.name  # a state function


@pytest.mark.parametrize("module", [WL, FL, CL])
def test_float_and_color_forms_share_slots(module):
    """One kernel serves both forms: every packed name at the same offset."""
    a, b = module.SIGNATURE, module.COLOR_SIGNATURE
    assert a.width == b.width
    for p in b.params:
        if p.width:
            assert a.offset(p.name) == b.offset(p.name), p.name
    for name in b.context:
        assert a.offset(name) == b.offset(name)
