"""The compiled interpreter of df programs (:mod:`render.program`): one lane at a time.

Every entry point takes the program's arrays (``code``, ``kids``, ``frames``, ``P``,
``tables``), the lane's parameter ``row``, local directions (``+z`` the shading normal)
and a scratch array ``ws`` of :func:`work_size` floats (allocate it once per thread and
batch, never per lane).  Nothing here recurses (numba's cache cannot hold recursive
functions): a program is walked in passes over its postorder nodes.

* :func:`prepare` (at ``wo``): each node's cheap albedo and each combiner's selection
  probabilities (the defensive mixture of :func:`render.df._workspace.selection`);
* :func:`evaluate` (at ``wi``): every node's value and pdf, bottom-up, as each combiner
  sums its children (a child's term in the pdf counts only where it contributes);
* :func:`sample`: prepare, descend from the root to one leaf (choices rescale ``u1``),
  sample the leaf, evaluate once at the drawn direction, and settle the choices on the
  path: ``eval / pdf`` of the whole tree, or for a delta leaf the product of the factors
  over the selection probabilities.

The interpreter only walks: which kernel serves a node is decided in one place, the
dispatch that :mod:`render.df._registry` generates from the df modules' declarations
(:data:`leaf_eval_pdf`, :data:`leaf_sample`, ...), and what a combiner does in each
phase is written once in its role's module (:mod:`render.df._layer`,
:mod:`render.df._mix`, :mod:`render.df._modifier`), compiled here with that dispatch
bound.  Nothing here names a df or holds a combiner's formula.
"""

from __future__ import annotations

import sys

import numpy as np

from render.df import _layer, _mix, _modifier
from render.df._registry import registry
from render.df._signature import MODE_MASK, REFLECT
from render.df._workspace import (
    AL,
    CH,
    FR,
    FWI,
    FWO,
    KON,
    KR,
    MAX_DEPTH,
    NO_KID,
    ON,
    PDF,
    F,
    R,
    any_pos,
    set_bases,
    set_dirs,
    to_frame0,
    work_size,
)
from render.jit import instantiate, njit
from render.program import (
    BASE,
    CHAT_NONE,
    FLAGS,
    FRAME,
    KID0,
    OP,
    SIZE,
    SPECULAR_LOBES,
    TABLE,
)

__all__ = [
    "work_size",
    "prepare",
    "evaluate",
    "eval_pdf",
    "sample",
    "albedo",
    "cheap_albedo",
    "edf_eval_pdf",
    "edf_sample",
]

# ------------------------------------------------------------------ dispatch
# Every call of a node's kernel goes through the dispatch that the registry generates
# from the df modules' declarations (render.df._registry): a function per phase, of the
# opcode, and the nodes' facts as arrays indexed by opcode.
_DISPATCH = registry().dispatch()
_ROLE, _EDF, _MIRROR = _DISPATCH.ROLE, _DISPATCH.EDF, _DISPATCH.MIRROR
#: ``(f0, f1, f2, pdf)`` of leaf ``op`` (local frame; its node table at ``tables[t:]``)
leaf_eval_pdf = _DISPATCH.eval_pdf
#: ``(wi xyz, pdf, weight rgb, lobe)`` of leaf ``op`` (lobe 0: failed)
leaf_sample = _DISPATCH.sample
#: directional albedo ``(a0, a1, a2)`` of leaf ``op``
leaf_albedo = _DISPATCH.albedo
#: whether a layer's (or modifier's) curve takes one value at every cosine (then Ĉ never
#: matters)
curve_constant = _DISPATCH.curve_constant
_LEAF, _LAYER, _MIX, _MODIFIER = range(4)  # render.df._registry.ROLES


@njit(inline="always")
def _is_leaf(op):
    return _ROLE[op] == _LEAF


@njit
def is_mirror(code, c):
    """Node ``c`` is a mirror (``specular_bsdf`` reflecting): it scatters to the mirror
    direction alone."""
    return c >= 0 and _MIRROR[code[c, OP]] and (code[c, FLAGS] & MODE_MASK) == REFLECT


# ------------------------------------------------------------------ combiners
# What each combiner does in each phase is written once, in its role's module
# (render.df._layer, render.df._mix, render.df._modifier), as templates compiled here
# with the dispatch and this module (the walker they call back) bound.
_ME = sys.modules[__name__]


def _phase(template, allocates: bool = False):
    return instantiate(template, __name__, allocates=allocates, dispatch=_DISPATCH, walker=_ME)


layer_chat = _phase(_layer.chat)
layer_factors = _phase(_layer.factors)
layer_factor_at = _phase(_layer.factor_at)
lobe_white_albedo = _phase(_layer.lobe_white_albedo)
_layer_prepare = _phase(_layer.prepare)
_layer_evaluate = _phase(_layer.evaluate)
_layer_choose = _phase(_layer.choose)
_layer_settle = _phase(_layer.settle)
_mix_prepare = _phase(_mix.prepare)
_mix_evaluate = _phase(_mix.evaluate)
_mix_choose = _phase(_mix.choose)
_mix_settle = _phase(_mix.settle)
_mix_albedo = _phase(_mix.albedo)
_modifier_prepare = _phase(_modifier.prepare)
_modifier_evaluate = _phase(_modifier.evaluate)
_modifier_settle = _phase(_modifier.settle)
modifier_varies = _phase(_modifier.varies)
modifier_factor_at = _phase(_modifier.factor_at)


# ------------------------------------------------------------------ passes
@njit
def prepare(code, kids, frames, P, tables, row, ws, lo, hi, f0, f1, x, y, z):
    """Directions at ``wo = (x, y, z)`` (frame ``f0``) in the frames ``f0 .. f1 - 1``,
    then nodes ``lo..hi``: cheap albedos, and each combiner's choice among its
    children."""
    n = code.shape[0]
    ko = n * R
    fo = ko + kids.shape[0] * KR
    set_bases(frames, P, row, ws, fo, f0, f1)
    set_dirs(frames, ws, fo, f0, f1, FWO, x, y, z)
    for k in range(lo, hi + 1):
        op = code[k, OP]
        role = _ROLE[op]
        fr = fo + code[k, FRAME] * FR
        wo = ws[fr + FWO:fr + FWO + 3]
        if role == _LEAF:
            r = k * R + CH
            if _EDF[op]:
                ws[r], ws[r + 1], ws[r + 2] = 1.0, 1.0, 1.0
            else:
                ws[r], ws[r + 1], ws[r + 2] = leaf_albedo(
                    op, P, row, code[k, BASE], code[k, FLAGS], wo[0], wo[1], wo[2], tables,
                    code[k, TABLE])
        elif role == _LAYER:
            _layer_prepare(code, kids, frames, P, tables, row, ws, k, ko, fo, wo)
        elif role == _MIX:
            _mix_prepare(code, kids, P, tables, row, ws, k, ko)
        else:
            _modifier_prepare(code, kids, P, tables, row, ws, k, wo)


@njit
def evaluate(code, kids, frames, P, tables, row, ws, lo, hi, f0, f1, x, y, z):
    """Every node ``lo..hi`` at ``wi = (x, y, z)`` (frame ``f0``), after :func:`prepare`:
    its value and pdf (0 both where either is), children first.  An emission program is
    evaluated with ``wi = wo`` (its edfs and modifiers read ``wo`` alone)."""
    n = code.shape[0]
    ko = n * R
    fo = ko + kids.shape[0] * KR
    set_dirs(frames, ws, fo, f0, f1, FWI, x, y, z)
    for k in range(lo, hi + 1):
        op = code[k, OP]
        role = _ROLE[op]
        fr = fo + code[k, FRAME] * FR
        wo = ws[fr + FWO:fr + FWO + 3]
        wi = ws[fr + FWI:fr + FWI + 3]
        if role == _LEAF and _EDF[op]:  # an emission program: at wo (= wi)
            v0, v1, v2, pdf = _DISPATCH.edf_eval_pdf(op, P, row, code[k, BASE],
                                                     code[k, FLAGS], wo[0], wo[1], wo[2],
                                                     tables, code[k, TABLE])
        elif role == _LEAF:
            v0, v1, v2, pdf = leaf_eval_pdf(op, P, row, code[k, BASE], code[k, FLAGS], wo[0],
                                            wo[1], wo[2], wi[0], wi[1], wi[2], tables,
                                            code[k, TABLE])
        elif role == _LAYER:
            v0, v1, v2, pdf = _layer_evaluate(code, kids, frames, P, tables, row, ws, k, ko,
                                              fo, wo, wi)
        elif role == _MIX:
            v0, v1, v2, pdf = _mix_evaluate(code, kids, ws, k, ko)
        else:
            v0, v1, v2, pdf = _modifier_evaluate(code, kids, P, tables, row, ws, k, ko, wo, wi)
        if role != _LEAF and not pdf > 0.0:
            v0 = v1 = v2 = pdf = 0.0
        r = k * R
        ws[r + F], ws[r + F + 1], ws[r + F + 2] = v0, v1, v2
        ws[r + PDF] = pdf
        ws[r + ON] = 1.0 if any_pos(v0, v1, v2) else 0.0


@njit
def eval_pdf(code, kids, frames, P, tables, row, ws, root, f0, f1, ox, oy, oz, ix, iy, iz):
    """``(f0, f1, f2, pdf)`` of the program rooted at node ``root`` (its frames
    ``f0 .. f1 - 1``) at ``(wo, wi)`` in its shading frame."""
    if code[root, SIZE] == 1 and code[root, FRAME] == f0:  # one df in the shading frame
        return leaf_eval_pdf(code[root, OP], P, row, code[root, BASE], code[root, FLAGS],
                             ox, oy, oz, ix, iy, iz, tables, code[root, TABLE])
    lo = root - code[root, SIZE] + 1
    prepare(code, kids, frames, P, tables, row, ws, lo, root, f0, f1, ox, oy, oz)
    evaluate(code, kids, frames, P, tables, row, ws, lo, root, f0, f1, ix, iy, iz)
    r = root * R
    return ws[r + F], ws[r + F + 1], ws[r + F + 2], ws[r + PDF]


@njit
def sample(code, kids, frames, P, tables, row, ws, root, f0, f1, ox, oy, oz, u1, u2x, u2y,
           prepared):
    """``(wi xyz, pdf, weight rgb, lobe)`` of the program rooted at ``root`` (lobe 0:
    failed); directions in its shading frame.  ``prepared``: :func:`eval_pdf` has just
    run on ``ws`` at the same ``wo`` (its :func:`prepare` holds: evaluate changes none
    of the registers prepare sets).

    Prepare, descend from the root to one leaf (each combiner chooses a child and
    rescales ``u1``), sample the leaf, evaluate once at the drawn direction, and settle
    the choices on the path: ``eval / pdf`` of the whole tree, or for a delta leaf the
    product of the factors over the choices' probabilities."""
    if code[root, SIZE] == 1 and code[root, FRAME] == f0:  # one df: its kernel alone
        return leaf_sample(code[root, OP], P, row, code[root, BASE], code[root, FLAGS],
                           ox, oy, oz, u1, u2x, u2y, tables, code[root, TABLE])
    n = code.shape[0]
    ko = n * R
    fo = ko + kids.shape[0] * KR
    lo = root - code[root, SIZE] + 1
    if not prepared:
        prepare(code, kids, frames, P, tables, row, ws, lo, root, f0, f1, ox, oy, oz)
    # descend: remember the chosen child (kid slot) and its parent at every combiner
    po = fo + frames.shape[0] * FR
    depth = 0
    k = root
    while not _is_leaf(code[k, OP]):
        role = _ROLE[code[k, OP]]
        if role == _LAYER:
            j, u1 = _layer_choose(code, ws, k, ko, u1)
        elif role == _MIX:
            j, u1 = _mix_choose(code, ws, k, ko, u1)
        else:
            j = code[k, KID0]
        if j < 0 or kids[j] == NO_KID or depth >= MAX_DEPTH:
            return 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0
        ws[po + depth] = j
        ws[po + MAX_DEPTH + depth] = k
        depth += 1
        k = kids[j]
    f = code[k, FRAME]
    fr = fo + f * FR
    wx, wy, wz, pdf, w0, w1, w2, lobe = leaf_sample(
        code[k, OP], P, row, code[k, BASE], code[k, FLAGS], ws[fr + FWO], ws[fr + FWO + 1],
        ws[fr + FWO + 2], u1, u2x, u2y, tables, code[k, TABLE])
    if lobe == 0:
        return 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0
    wx, wy, wz = to_frame0(frames, ws, fo, f, wx, wy, wz)
    if depth == 0:
        return wx, wy, wz, pdf, w0, w1, w2, lobe
    evaluate(code, kids, frames, P, tables, row, ws, lo, root, f0, f1, wx, wy, wz)
    delta = (lobe & SPECULAR_LOBES) != 0
    # settle the choices from the leaf up
    for d in range(depth - 1, -1, -1):
        j = int(ws[po + d])
        k = int(ws[po + MAX_DEPTH + d])
        if delta:
            role = _ROLE[code[k, OP]]
            if role == _LAYER:
                psel, g0, g1, g2 = _layer_settle(code, ws, k, ko, j)
            elif role == _MIX:
                psel, g0, g1, g2 = _mix_settle(code, ws, k, ko, j)
            else:
                psel, g0, g1, g2 = _modifier_settle(code, ws, k, ko, j)
            if not psel > 0.0:
                return 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0
            w0, w1, w2 = g0 * w0 / psel, g1 * w1 / psel, g2 * w2 / psel
            pdf = psel * pdf
            if not (any_pos(w0, w1, w2) and pdf > 0.0):
                return 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0
        elif not (ws[ko + j * KR + KON] > 0.0 and ws[k * R + PDF] > 0.0):
            return 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0
    if not delta:
        r = root * R
        pdf = ws[r + PDF]
        w0, w1, w2 = ws[r + F] / pdf, ws[r + F + 1] / pdf, ws[r + F + 2] / pdf
    return wx, wy, wz, pdf, w0, w1, w2, lobe


@njit
def cheap_albedo(code, kids, frames, P, tables, row, ws, root, f0, f1, ox, oy, oz):
    """The fast albedo estimate (``render.df.albedo_estimate``): exact for elemental
    dfs, mixes, weighted layers and tint; factors at ``wo`` times the children's
    estimates for the directional combiners."""
    lo = root - code[root, SIZE] + 1
    prepare(code, kids, frames, P, tables, row, ws, lo, root, f0, f1, ox, oy, oz)
    r = root * R + CH
    return max(ws[r], 0.0), max(ws[r + 1], 0.0), max(ws[r + 2], 0.0)


@njit
def correction(code, kids, frames, P, tables, row, ws, k, child, which, e0, e1, e2, f0, f1,
               ox, oy, oz, points):
    """``∫ (factor(wi) - e) child.eval(wo, wi) dwi`` through the child's own sampler over
    ``points``, for combiner ``k``'s factor of its child ``which`` (a layer's 0 or 1, a
    modifier's 0): a control variate, the factor's value ``e`` at ``wo`` being exact."""
    s0 = s1 = s2 = 0.0
    m = points.shape[0]
    layer = _ROLE[code[k, OP]] == _LAYER
    for i in range(m):
        s = sample(code, kids, frames, P, tables, row, ws, child, f0, f1, ox, oy, oz,
                   points[i, 0], points[i, 1], points[i, 2], False)
        if s[7] == 0:
            continue
        # the node's own registers at wo again (the child's pass rewrote shared frames)
        prepare(code, kids, frames, P, tables, row, ws, k, k, f0, f1, ox, oy, oz)
        if layer:
            g0, g1, g2 = layer_factor_at(code, kids, frames, P, tables, row, ws, k, which,
                                         f0, f1, s[0], s[1], s[2])
        else:
            g0, g1, g2 = modifier_factor_at(code, kids, frames, P, tables, row, ws, k, f0,
                                            f1, s[0], s[1], s[2])
        s0 += (g0 - e0) * s[4]
        s1 += (g1 - e1) * s[5]
        s2 += (g2 - e2) * s[6]
    return s0 / m, s1 / m, s2 / m


_layer_albedo = _phase(_layer.albedo)
_modifier_albedo = _phase(_modifier.albedo)


@njit
def albedo(code, kids, frames, P, tables, row, ws, root, f0, f1, points, ox, oy, oz):
    """Directional albedo of the program at ``wo`` (``Bsdf.albedo``), children first:
    exact for the elemental dfs, mixes, weighted layers in their own frame and
    ``tint``; the directional combiners add the integral of their factors' deviation
    from their value at ``wo`` (:func:`correction`)."""
    n = code.shape[0]
    ko = n * R
    fo = ko + kids.shape[0] * KR
    lo = root - code[root, SIZE] + 1
    for k in range(lo, root + 1):
        op = code[k, OP]
        role = _ROLE[op]
        prepare(code, kids, frames, P, tables, row, ws, k, k, f0, f1, ox, oy, oz)
        fr = fo + code[k, FRAME] * FR
        wo = ws[fr + FWO:fr + FWO + 3]
        if role == _LEAF:
            a0, a1, a2 = leaf_albedo(op, P, row, code[k, BASE], code[k, FLAGS], wo[0], wo[1],
                                     wo[2], tables, code[k, TABLE])
        elif role == _MIX:
            a0, a1, a2 = _mix_albedo(code, kids, ws, k, ko)
        elif role == _LAYER:
            a0, a1, a2 = _layer_albedo(code, kids, frames, P, tables, row, ws, k, ko, fo, f0,
                                       f1, points, ox, oy, oz, wo)
        else:
            a0, a1, a2 = _modifier_albedo(code, kids, frames, P, tables, row, ws, k, f0, f1,
                                          points, ox, oy, oz, wo)
        r = k * R + AL
        ws[r], ws[r + 1], ws[r + 2] = a0, a1, a2
    q = root * R + AL
    return ws[q], ws[q + 1], ws[q + 2]


# ------------------------------------------------------------------ EDF programs
@njit
def edf_eval_pdf(code, kids, frames, P, tables, row, ws, root, f0, f1, ox, oy, oz):
    """``(e0, e1, e2, pdf)`` of the edf program rooted at ``root`` toward ``wo``
    (``Edf.eval``, ``Edf.pdf``)."""
    lo = root - code[root, SIZE] + 1
    prepare(code, kids, frames, P, tables, row, ws, lo, root, f0, f1, ox, oy, oz)
    evaluate(code, kids, frames, P, tables, row, ws, lo, root, f0, f1, ox, oy, oz)
    r = root * R
    return ws[r + F], ws[r + F + 1], ws[r + F + 2], ws[r + PDF]


@njit
def edf_sample(code, kids, frames, P, tables, row, ws, root, f0, f1, u1, u2x, u2y):
    """``(wo xyz, pdf, weight rgb)`` of the edf program rooted at ``root`` (``EdfSample``;
    pdf 0: failed): a descent through the mixes' choices and the modifiers to one leaf,
    its sample weighted by the whole program."""
    n = code.shape[0]
    ko = n * R
    k = root
    if not _is_leaf(code[k, OP]):
        prepare(code, kids, frames, P, tables, row, ws, root - code[root, SIZE] + 1, root,
                f0, f1, 0.0, 0.0, 1.0)
    while not _is_leaf(code[k, OP]):
        if _ROLE[code[k, OP]] == _MIX:
            j, u1 = _mix_choose(code, ws, k, ko, u1)
        else:  # a modifier: its one child
            j = code[k, KID0]
        if j < 0:
            return 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0
        k = kids[j]
        if k == NO_KID:
            return 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0
    wx, wy, wz, pdf, w0, w1, w2 = _DISPATCH.edf_sample(code[k, OP], P, row, code[k, BASE],
                                                       code[k, FLAGS], u1, u2x, u2y, tables,
                                                       code[k, TABLE])
    if k == root or not pdf > 0.0:
        return wx, wy, wz, pdf, w0, w1, w2
    e0, e1, e2, pdf = edf_eval_pdf(code, kids, frames, P, tables, row, ws, root, f0, f1,
                                   wx, wy, wz)
    if not pdf > 0.0:
        return 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0
    c = wz / pdf
    return wx, wy, wz, pdf, e0 * c, e1 * c, e2 * c


# ------------------------------------------------------------------ batches (lanes)
@njit
def _row(P, i):
    return i if P.shape[0] > 1 else 0


@njit(allocates=True)
def _ws(code, kids, frames):
    return np.empty(work_size(code.shape[0], kids.shape[0], frames.shape[0]))


@njit(allocates=True)
def eval_pdf_batch(code, kids, frames, P, tables, wo, wi, f, pdf):
    """:func:`eval_pdf` of a whole program over lanes (``f`` (n, 3), ``pdf`` (n,) written)."""
    ws = _ws(code, kids, frames)
    root, nf = code.shape[0] - 1, frames.shape[0]
    for i in range(wo.shape[0]):
        a, b, c, p = eval_pdf(code, kids, frames, P, tables, _row(P, i), ws, root, 0, nf,
                              wo[i, 0], wo[i, 1], wo[i, 2], wi[i, 0], wi[i, 1], wi[i, 2])
        f[i, 0], f[i, 1], f[i, 2], pdf[i] = a, b, c, p


@njit(allocates=True)
def sample_batch(code, kids, frames, P, tables, wo, u1, u2, wi, pdf, weight, lobe):
    """:func:`sample` of a whole program over lanes (outputs written in place)."""
    ws = _ws(code, kids, frames)
    root, nf = code.shape[0] - 1, frames.shape[0]
    for i in range(wo.shape[0]):
        s = sample(code, kids, frames, P, tables, _row(P, i), ws, root, 0, nf, wo[i, 0],
                   wo[i, 1], wo[i, 2], u1[i], u2[i, 0], u2[i, 1], False)
        wi[i, 0], wi[i, 1], wi[i, 2], pdf[i] = s[0], s[1], s[2], s[3]
        weight[i, 0], weight[i, 1], weight[i, 2], lobe[i] = s[4], s[5], s[6], s[7]


@njit(allocates=True)
def albedo_batch(code, kids, frames, P, tables, wo, points, out):
    """:func:`albedo` of a whole program over lanes."""
    ws = _ws(code, kids, frames)
    root, nf = code.shape[0] - 1, frames.shape[0]
    for i in range(wo.shape[0]):
        out[i, 0], out[i, 1], out[i, 2] = albedo(code, kids, frames, P, tables, _row(P, i),
                                                 ws, root, 0, nf, points, wo[i, 0],
                                                 wo[i, 1], wo[i, 2])


@njit(allocates=True)
def cheap_albedo_batch(code, kids, frames, P, tables, wo, out):
    """:func:`cheap_albedo` of a whole program over lanes."""
    ws = _ws(code, kids, frames)
    root, nf = code.shape[0] - 1, frames.shape[0]
    for i in range(wo.shape[0]):
        out[i, 0], out[i, 1], out[i, 2] = cheap_albedo(code, kids, frames, P, tables,
                                                       _row(P, i), ws, root, 0, nf,
                                                       wo[i, 0], wo[i, 1], wo[i, 2])


@njit(allocates=True)
def edf_eval_pdf_batch(code, kids, frames, P, tables, wo, e, pdf):
    """:func:`edf_eval_pdf` of a whole program over lanes."""
    ws = _ws(code, kids, frames)
    root, nf = code.shape[0] - 1, frames.shape[0]
    for i in range(wo.shape[0]):
        a, b, c, p = edf_eval_pdf(code, kids, frames, P, tables, _row(P, i), ws, root, 0, nf,
                                  wo[i, 0], wo[i, 1], wo[i, 2])
        e[i, 0], e[i, 1], e[i, 2], pdf[i] = a, b, c, p


@njit(allocates=True)
def edf_sample_batch(code, kids, frames, P, tables, u1, u2, wo, pdf, weight):
    """:func:`edf_sample` of a whole program over lanes."""
    ws = _ws(code, kids, frames)
    root, nf = code.shape[0] - 1, frames.shape[0]
    for i in range(u1.shape[0]):
        s = edf_sample(code, kids, frames, P, tables, _row(P, i), ws, root, 0, nf, u1[i],
                       u2[i, 0], u2[i, 1])
        wo[i, 0], wo[i, 1], wo[i, 2], pdf[i] = s[0], s[1], s[2], s[3]
        weight[i, 0], weight[i, 1], weight[i, 2] = s[4], s[5], s[6]


@njit
def mix_weights_batch(op, P, b, tables, out):
    """A mix's effective component weights over lanes: ``out`` (n, k, 3)."""
    k = out.shape[1]
    for i in range(out.shape[0]):
        for j in range(k):
            out[i, j, 0], out[i, j, 1], out[i, j, 2] = _DISPATCH.mix_weights(
                op, P, _row(P, i), b, 0, k, j, tables, CHAT_NONE)


#: the Ĉ table of a curve layer (render.df._layer.build_chat_table)
build_chat_table = _phase(_layer.build_chat_table, allocates=True)
