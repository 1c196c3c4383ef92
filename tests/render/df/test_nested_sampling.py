"""Sampling nested combiners costs one evaluation of the tree, not one per level.

A layer's or mix's sample returns ``eval / pdf`` of the whole node at the drawn
direction, so every level needs its subtree evaluated there.  ``_draw`` / ``_settle``
(:mod:`render.df._combine`) share one evaluation among all levels: each leaf's
``eval_pdf`` runs once per ``sample`` call however deep the nest.  Counted with leaves
that are real dfs recording their calls (no mock of the combiners).
"""

from __future__ import annotations

import numpy as np
import pytest
from render_df_cases import random_dirs

from render import df
from render.df.diffuse_reflection_bsdf import DiffuseReflectionBsdf
from render.df.simple_glossy_bsdf import SimpleGlossyBsdf
from render.df.specular_bsdf import SpecularBsdf

N = 512


class Counting:
    """Mixin: count ``eval_pdf`` calls (how every combiner evaluates its children)."""

    def __init__(self, *args, **kwargs):
        super().__init__(*args, **kwargs)
        self.calls = 0

    def eval_pdf(self, wo, wi):
        self.calls += 1
        return super().eval_pdf(wo, wi)


class CountingDiffuse(Counting, DiffuseReflectionBsdf):
    pass


class CountingGlossy(Counting, SimpleGlossyBsdf):
    pass


class CountingSpecular(Counting, SpecularBsdf):
    pass


def chain(depth: int, leaves: list):
    """``depth`` weighted layers, each a glossy leaf over the next; a diffuse leaf at the bottom."""
    bottom = CountingDiffuse(tint=0.8)
    leaves.append(bottom)
    node = bottom
    for k in range(depth):
        leaf = CountingGlossy(roughness_u=0.1 + 0.1 * k)
        leaves.append(leaf)
        node = df.weighted_layer(0.3, leaf, node)
    return node


def five_deep(leaves: list, normal=(0.0, 0.0, 1.0)):
    """Five combiner levels of every kind: weighted layer, Fresnel layer (specular coat),
    normalized mix (weights summing above 1), tint, weighted layer (the top one may tilt)."""
    a, b, c = CountingGlossy(roughness_u=0.3), CountingDiffuse(tint=0.5), CountingDiffuse()
    coat, d = CountingSpecular(tint=0.9), CountingGlossy(roughness_u=0.2)
    leaves += [a, b, c, coat, d]
    l5 = df.weighted_layer(0.5, a, b)
    l4 = df.tint((0.9, 0.7, 0.5), l5)
    l3 = df.normalized_mix([df.bsdf_component(0.8, c), df.bsdf_component(0.9, l4)])
    l2 = df.fresnel_layer(1.5, 1.0, coat, l3)
    return df.weighted_layer(0.3, d, l2, normal=normal)


def _inputs(rng):
    wo = random_dirs(rng, N)
    wo[:, 2] = np.abs(wo[:, 2])
    return wo, rng.random(N), rng.random((N, 2))


def test_each_leaf_is_evaluated_once_per_sample(rng):
    leaves = []
    bsdf = five_deep(leaves)
    wo, u1, u2 = _inputs(rng)
    s = bsdf.sample(wo, u1, u2)
    assert np.any(s.valid & ~s.is_delta) and np.any(s.is_delta)
    assert [leaf.calls for leaf in leaves] == [1] * len(leaves)


@pytest.mark.parametrize("depth", [1, 3, 6])
def test_evaluations_grow_linearly_with_depth(depth, rng):
    leaves = []
    bsdf = chain(depth, leaves)
    wo, u1, u2 = _inputs(rng)
    bsdf.sample(wo, u1, u2)
    # one evaluation of the tree: depth + 1 leaves, once each (one per level before)
    assert sum(leaf.calls for leaf in leaves) == depth + 1


def test_a_tilted_layer_settles_its_layer_child_on_its_own(rng):
    # a layer with its own normal evaluates its layer child at to_layer(to_inherited(wi_l)),
    # which rounding moves off the child's own direction: that child (a leaf here) is
    # evaluated once more, by its own sample, nothing else is
    leaves = []
    tilted = (0.2, -0.1, 0.97)
    bsdf = df.weighted_layer(0.6, five_deep(leaves), CountingDiffuse(), normal=tilted)
    wo, u1, u2 = _inputs(rng)
    bsdf.sample(wo, u1, u2)
    assert max(leaf.calls for leaf in leaves) <= 2
    assert sum(leaf.calls for leaf in leaves) == 2 * len(leaves)


@pytest.mark.parametrize("normal", [(0.0, 0.0, 1.0), (0.3, 0.1, 0.9)])
def test_sample_is_eval_over_pdf_of_the_whole_nest(normal, rng):
    leaves = []
    bsdf = five_deep(leaves, normal)
    wo, u1, u2 = _inputs(rng)
    s = bsdf.sample(wo, u1, u2)
    nd = s.valid & ~s.is_delta
    e, p = bsdf.eval_pdf(wo[nd], s.wi[nd])
    # the same evaluation at the same direction: equal to the last bit
    assert np.array_equal(s.pdf[nd], p)
    assert np.array_equal(s.weight[nd], e / p[:, None])
