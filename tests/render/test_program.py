"""Building programs (render.program): the parameter table of lanes, and when a curve
layer gets its Ĉ table."""

from __future__ import annotations

import numpy as np
from hypothesis import given
from hypothesis import strategies as st

from render import df
from render.program import CHAT_NONE, TABLE, _stack


@given(st.integers(1, 40), st.lists(st.tuples(st.booleans(), st.integers(0, 9)),
                                    min_size=1, max_size=8), st.integers(0, 2**32 - 1))
def test_stack_is_the_broadcast_columns_side_by_side(n, blocks, seed):
    """One-row blocks broadcast to every lane, per-lane blocks as they are."""
    rng = np.random.default_rng(seed)
    arrays = [rng.normal(size=(n if lanes else 1, w)) for lanes, w in blocks]
    got = _stack(arrays)
    rows = max(a.shape[0] for a in arrays)
    want = np.concatenate([np.broadcast_to(a, (rows, a.shape[1])) for a in arrays], axis=1)
    np.testing.assert_array_equal(got, want)
    assert got.dtype == np.float64


def test_a_layer_gets_its_chat_table_unless_what_it_depends_on_varies_per_lane():
    """Ĉ is tabulated where the layer child and the curve are the same on every lane,
    whatever varies elsewhere (the base, the weight); not where the layer's roughness
    or the curve's ior varies per lane, even if only one lane differs."""
    n = 50
    coat = df.simple_glossy_bsdf(roughness_u=0.2)
    tint = np.tile([0.6, 0.4, 0.1], (n, 1))
    tint[7] = 0.9
    base = df.diffuse_reflection_bsdf(tint=tint)
    rough = np.full(n, 0.2)
    ior = np.full(n, 1.5)

    def table(layer, weight=1.0, ior=1.5):
        program = df.fresnel_layer(ior=ior, weight=weight, layer=layer, base=base).program
        return program.code[program.root, TABLE]

    assert table(coat) != CHAT_NONE
    assert table(coat, weight=np.linspace(0.0, 1.0, n)) != CHAT_NONE
    assert table(df.simple_glossy_bsdf(roughness_u=rough)) != CHAT_NONE  # equal lanes
    rough[3] = 0.5
    assert table(df.simple_glossy_bsdf(roughness_u=rough)) == CHAT_NONE
    ior[-1] = 1.4
    assert table(coat, ior=ior) == CHAT_NONE
