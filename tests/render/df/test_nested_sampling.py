"""Sampling nested combiners: one descent, one evaluation of the whole tree.

A layer's or mix's sample returns ``eval / pdf`` of the whole node at the drawn
direction.  The interpreter (:func:`render.interpreter.sample`) descends once from the
root to a leaf, samples it, and evaluates the program once at the drawn direction: the
sample is the tree's own ``eval_pdf`` there, however deep the nest (delta leaves: their
weight times the factors over the selection probabilities on the path).
"""

from __future__ import annotations

import numpy as np
import pytest
from render_df_cases import random_dirs

from render import df

N = 512


def chain(depth: int):
    """``depth`` weighted layers, each a glossy leaf over the next; a diffuse leaf at the bottom."""
    node = df.diffuse_reflection_bsdf(tint=0.8)
    for k in range(depth):
        node = df.weighted_layer(0.3, df.simple_glossy_bsdf(roughness_u=0.1 + 0.1 * k), node)
    return node


def five_deep(normal=(0.0, 0.0, 1.0)):
    """Five combiner levels of every kind: weighted layer, Fresnel layer (specular coat),
    normalized mix (weights summing above 1), tint, weighted layer (the top one may tilt)."""
    a = df.simple_glossy_bsdf(roughness_u=0.3)
    b, c = df.diffuse_reflection_bsdf(tint=0.5), df.diffuse_reflection_bsdf()
    coat, d = df.specular_bsdf(tint=0.9), df.simple_glossy_bsdf(roughness_u=0.2)
    l5 = df.weighted_layer(0.5, a, b)
    l4 = df.tint((0.9, 0.7, 0.5), l5)
    l3 = df.normalized_mix([df.bsdf_component(0.8, c), df.bsdf_component(0.9, l4)])
    l2 = df.fresnel_layer(1.5, 1.0, coat, l3)
    return df.weighted_layer(0.3, d, l2, normal=normal)


def _inputs(rng):
    wo = random_dirs(rng, N)
    wo[:, 2] = np.abs(wo[:, 2])
    return wo, rng.random(N), rng.random((N, 2))


def _assert_sample_is_eval_over_pdf(bsdf, rng):
    wo, u1, u2 = _inputs(rng)
    s = bsdf.sample(wo, u1, u2)
    nd = s.valid & ~s.is_delta
    assert nd.mean() > 0.5
    e, p = bsdf.eval_pdf(wo[nd], s.wi[nd])
    # the same evaluation at the same direction: equal to the last bit
    assert np.array_equal(s.pdf[nd], p)
    assert np.array_equal(s.weight[nd], e / p[:, None])
    return s


@pytest.mark.parametrize("depth", [1, 3, 6, 40])
def test_a_chain_of_any_depth_samples_its_own_eval_pdf(depth, rng):
    bsdf = chain(depth)
    assert bsdf.program.code.shape[0] == 2 * depth + 1
    _assert_sample_is_eval_over_pdf(bsdf, rng)


@pytest.mark.parametrize("normal", [(0.0, 0.0, 1.0), (0.3, 0.1, 0.9)])
def test_sample_is_eval_over_pdf_of_the_whole_nest(normal, rng):
    s = _assert_sample_is_eval_over_pdf(five_deep(normal), rng)
    assert np.any(s.is_delta)  # the specular coat is drawn too


def test_a_tilted_layer_over_a_tilted_nest(rng):
    # a layer with its own normal over a nest whose top layer tilts too: two frames deep
    tilted = (0.2, -0.1, 0.97)
    bsdf = df.weighted_layer(0.6, five_deep((0.3, 0.1, 0.9)), df.diffuse_reflection_bsdf(),
                             normal=tilted)
    assert len(bsdf.program.frames) == 3
    _assert_sample_is_eval_over_pdf(bsdf, rng)


def test_delta_samples_carry_the_path_factors(rng):
    # a mirror under one weighted layer (weight w, selection P): weight = (1 - w) tint /
    # (1 - P) at the mirror direction, and the pdf the selection probability of the path
    w = 0.3
    bsdf = df.weighted_layer(w, df.diffuse_reflection_bsdf(), df.specular_bsdf(tint=0.9))
    wo, u1, u2 = _inputs(rng)
    s = bsdf.sample(wo, u1, u2)
    d = s.valid & s.is_delta
    assert d.any()
    assert np.allclose(s.wi[d], wo[d] * [-1.0, -1.0, 1.0], atol=1e-12)
    p_base = s.pdf[d]  # (1 - P) times the mirror's pdf (1 for a delta lobe)
    assert np.all((p_base > 0.0) & (p_base < 1.0))
    assert np.allclose(s.weight[d] * p_base[:, None], (1.0 - w) * 0.9, rtol=1e-12)
