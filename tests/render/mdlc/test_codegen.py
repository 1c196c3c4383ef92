"""MDL function bodies run over lanes: control flow where lanes disagree (masks), early
returns, loops with per-lane exits, switch fallthrough, value semantics of structs,
arrays, vectors and matrices, 32-bit ints, and calls that see only their active lanes.

Each expectation is the same computation written per lane in plain Python."""

from __future__ import annotations

import math

import numpy as np
import pytest

from displacement.surfaces import UnitSquare
from mdl.diagnostics import MdlError
from render.mdlc import make_loader, run_function
from render.mdlc.rt import MdlRuntimeError

MODULE = """
mdl 1.6;
import ::math::*;
import ::state::*;
import ::debug::*;

export float branches(float x) {
    float y = 0.0;
    if (x > 0.5)
        y = x * 2.0;
    else if (x > 0.2)
        y = -x;
    else {
        y = 1.0;
    }
    return y;
}

export int loop_exits(float x) {
    int n = 0;
    for (int i = 0; i < 20; i++) {
        if (i % 3 == 0)
            continue;
        if (float(i) * x > 4.0)
            break;
        n += i;
    }
    return n;
}

export int doubling(float x) {
    int k = 0;
    float v = x;
    while (v < 10.0) {
        v = v * 2.0 + 1.0;
        k++;
    }
    do { k += 100; } while (k < 150 && x > 0.5);
    return k;
}

export int fallthrough(int v) {
    int r = 0;
    switch (v) {
        case 0: r += 1;
        case 1: r += 10; break;
        case 2: r = 100;
        default: r += 1000;
    }
    return r;
}

export float returns(float x) {
    if (x < 0.3)
        return 1.0;
    for (int i = 0; i < 4; ++i) {
        if (x < 0.4 + 0.1 * float(i))
            return 2.0 + float(i);
    }
    return 9.0;
}

struct pair { float2 p = float2(1.0, 2.0); int[3] k; };

export float structs(float x) {
    pair a;
    pair b = a;
    b.p.y = x;
    b.k[1] = int(x * 10.0);
    float3 v = float3(1.0, 2.0, 3.0);
    v.zx = float2(x, 7.0);
    return a.p.y + b.p.y * 100.0 + float(b.k[1]) * 1000.0 + v.x * 10000.0 + v.z;
}

export float3 rotate(float a, float3 p) {
    float3x3 m = float3x3(math::cos(a), 0.0, math::sin(a), 0.0, 1.0, 0.0,
                          -math::sin(a), 0.0, math::cos(a));
    return p * m;
}

export float total(float[<N>] xs) {
    float s = 0.0;
    for (int i = 0; i < N; i++)
        s += xs[i] * float(i + 1);
    return s;
}

export int ints(int a, int b) {
    return (a + 2147483647) * 3 + a / b * 7 + a % b;
}

export float guarded(float x) {
    float r = -1.0;
    if (x > 0.5) {
        debug::assert(x > 0.5, "the lanes of the branch only");
        r = math::sqrt(x - 0.5);
    }
    return x > 0.25 ? math::log(x) : r;
}

export float uv_here() {
    float3 uvw = state::texture_coordinate(0);
    return let { float s = uvw.x + uvw.y; } in s * 2.0;
}

export float failing(float x) {
    debug::assert(x < 0.9, "x too large");
    return x;
}
"""


@pytest.fixture(scope="module")
def module():
    return make_loader().load_text(MODULE, "lanes.mdl", "::lanes_test")


def _state(n: int, seed: int = 7):
    uv = np.random.default_rng(seed).uniform(0.0, 1.0, (n, 2))
    return UnitSquare().state_at_uv(uv)


X = np.concatenate([np.linspace(0.0, 1.0, 41), [0.2, 0.5, 0.3, 0.4]])
S = _state(len(X))


def test_if_else_chains_per_lane(module):
    def ref(x):
        return x * 2.0 if x > 0.5 else (-x if x > 0.2 else 1.0)
    assert run_function(module, "branches", S, X).tolist() == [ref(x) for x in X]
    # one uniform lane takes one branch
    assert run_function(module, "branches", _state(1), 0.3).tolist() == [-0.3]


def test_continue_and_break_per_lane(module):
    def ref(x):
        n = 0
        for i in range(20):
            if i % 3 == 0:
                continue
            if i * x > 4.0:
                break
            n += i
        return n
    assert run_function(module, "loop_exits", S, X).tolist() == [ref(x) for x in X]


def test_while_and_do_loops_per_lane(module):
    def ref(x):
        k, v = 0, x
        while v < 10.0:
            v, k = v * 2.0 + 1.0, k + 1
        while True:
            k += 100
            if not (k < 150 and x > 0.5):
                break
        return k
    assert run_function(module, "doubling", S, X).tolist() == [ref(x) for x in X]


@pytest.mark.parametrize("uniform", [True, False])
def test_switch_falls_through(module, uniform):
    def ref(v):
        return {0: 11, 1: 10, 2: 1100}.get(v, 1000)
    vs = np.array([0, 1, 2, 3, -5, 1, 0], dtype=np.int32)
    if uniform:
        for v in vs:
            assert run_function(module, "fallthrough", _state(1), int(v)).tolist() == [ref(v)]
    else:
        got = run_function(module, "fallthrough", _state(len(vs)), vs)
        assert got.tolist() == [ref(v) for v in vs]


def test_returns_in_branches_and_loops(module):
    def ref(x):
        if x < 0.3:
            return 1.0
        for i in range(4):
            if x < 0.4 + 0.1 * i:
                return 2.0 + i
        return 9.0
    assert run_function(module, "returns", S, X).tolist() == [ref(x) for x in X]


def test_structs_arrays_and_swizzles_are_values(module):
    def ref(x):
        return 2.0 + x * 100.0 + int(x * 10.0) * 1000.0 + 7.0 * 10000.0 + x
    assert run_function(module, "structs", S, X) == pytest.approx([ref(x) for x in X])


def test_row_vector_times_matrix(module):
    a = np.linspace(0.0, 2.0 * math.pi, 9)
    p = np.tile([1.0, 2.0, 0.5], (9, 1))
    got = run_function(module, "rotate", _state(9), a, p)
    want = [(x * math.cos(t) + z * math.sin(t), y, -x * math.sin(t) + z * math.cos(t))
            for t, (x, y, z) in zip(a, p, strict=True)]
    assert got == pytest.approx(np.array(want))


def test_size_deferred_arrays(module):
    assert run_function(module, "total", _state(1), [1.0, 2.0, 4.0]).tolist() == [17.0]
    xs = np.random.default_rng(3).uniform(size=(5, 4))
    got = run_function(module, "total", _state(5), xs)
    assert got == pytest.approx(xs @ np.arange(1.0, 5.0))


def test_ints_wrap_and_divide_toward_zero(module):
    a = np.array([-7, 7, 1, -2147483648, 5], dtype=np.int32)
    b = np.array([2, -2, 3, 1, -3], dtype=np.int32)

    def ref(x, y):
        wrap = lambda v: (v + 2**31) % 2**32 - 2**31  # noqa: E731
        q = abs(x) // abs(y) * (1 if (x >= 0) == (y > 0) else -1)
        r = int(math.fmod(x, y))
        return wrap(wrap(wrap(x + 2147483647) * 3) + wrap(q * 7) + r)
    got = run_function(module, "ints", _state(5), a, b)
    assert got.tolist() == [ref(int(x), int(y)) for x, y in zip(a, b, strict=True)]


def test_calls_see_only_their_active_lanes(module):
    """debug::assert in a branch sees the branch's lanes; the '?:' arms are evaluated on
    their own lanes, so log of the lanes <= 0.25 never reaches the result."""
    got = run_function(module, "guarded", S, X)
    want = [math.log(x) if x > 0.25 else (math.sqrt(x - 0.5) if x > 0.5 else -1.0) for x in X]
    assert got == pytest.approx(want)
    assert np.all(np.isfinite(got))


def test_state_reads_and_let(module):
    got = run_function(module, "uv_here", S)
    assert got == pytest.approx(2.0 * S.uv.sum(axis=1))


def test_a_failing_assert_is_located(module):
    with pytest.raises(MdlRuntimeError, match=r"lanes\.mdl:\d+:\d+: debug::assert failed on 5 "
                                              "of 45 lanes: x too large"):
        run_function(module, "failing", S, X)


def test_assignment_in_a_conditional_operand_is_refused():
    text = ("mdl 1.6;\nexport float f(float x) {\n    float y = 0.0;\n"
            "    return x > 0.5 ? (y = 1.0) : y;\n}\n")
    m = make_loader().load_text(text, "side.mdl", "::side_test")
    with pytest.raises(MdlError, match=r"side\.mdl:4:23: error: an assignment inside an "
                                       "operand of '\\?:', '&&' or '\\|\\|' is not supported"):
        from render.mdlc.backend import backend

        backend().compile(m)
