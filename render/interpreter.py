"""The compiled interpreter of df programs (:mod:`render.program`): one lane at a time.

Every entry point takes the program's arrays (``code``, ``kids``, ``frames``, ``P``,
``tables``), the lane's parameter ``row``, local directions (``+z`` the shading normal)
and a scratch array ``ws`` of :func:`work_size` floats (allocate it once per thread and
batch, never per lane).  Nothing here recurses (numba's cache cannot hold recursive
functions): a program is walked in passes over its postorder nodes.

* :func:`prepare` (at ``wo``): each node's cheap albedo and each combiner's selection
  probabilities (the defensive mixture of :func:`_selection`);
* :func:`evaluate` (at ``wi``): every node's value and pdf, bottom-up, as each combiner
  sums its children (a child's term in the pdf counts only where it contributes);
* :func:`sample`: prepare, descend from the root to one leaf (choices rescale ``u1``),
  sample the leaf, evaluate once at the drawn direction, and settle the choices on the
  path: ``eval / pdf`` of the whole tree, or for a delta leaf the product of the factors
  over the selection probabilities.

Which kernel serves a node is decided in one place, the dispatch that
:mod:`render.df._registry` generates from the df modules' declarations
(:data:`leaf_eval_pdf`, :data:`leaf_sample`, ...); nothing here names a df.
"""

from __future__ import annotations

import math

import numpy as np

from render.df import _kernel_common as kc
from render.df._registry import registry
from render.df._signature import MODE_MASK, REFLECT
from render.jit import njit
from render.program import (
    BASE,
    CHAT_NONE,
    CHAT_THETA,
    COS_ZERO,
    DEFENSIVE,
    FLAGS,
    FRAME,
    KID0,
    LFRAME,
    LUM_B,
    LUM_G,
    LUM_R,
    NKIDS,
    ONE_MINUS_EPS,
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

# per-node registers (R floats per node): value, pdf, contributes, cheap albedo,
# selection probability of the layer child, Ĉ(wo), wo agrees with the layer frame,
# Ĉ(wi), a scratch direction, the full albedo (untouched by prepare and evaluate)
_F, _PDF, _ON, _CH, _SEL, _CO, _AGO, _CW, _TMP, _AL = 0, 3, 4, 5, 8, 9, 12, 13, 16, 19
_R = 22
# per-child registers: factor (3), selection probability, contributes, mix weight (3)
_KF, _KSEL, _KON, _KW = 0, 3, 4, 5
_KR = 8
# per-frame registers: basis s, t, n (9), wo (3), wi (3)
_FS, _FT, _FN, _FWO, _FWI = 0, 3, 6, 9, 12
_FR = 15
#: deepest nesting of combiners a program may have (the descent's path is kept in ws)
MAX_DEPTH = 64
_NO_KID = -1


@njit
def work_size(n_nodes, n_kids, n_frames):
    """Floats of scratch one lane's interpretation needs."""
    return n_nodes * _R + n_kids * _KR + n_frames * _FR + 2 * MAX_DEPTH


# ------------------------------------------------------------------ dispatch
# Every call of a node's kernel goes through the dispatch that the registry generates
# from the df modules' declarations (render.df._registry): a function per phase, of the
# opcode, and the nodes' facts as arrays indexed by opcode.
_DISPATCH = registry().dispatch()
_ROLE, _EDF, _MIRROR = _DISPATCH.ROLE, _DISPATCH.EDF, _DISPATCH.MIRROR
_DIRECTIONAL, _CHAT_FROM_LOBE = _DISPATCH.DIRECTIONAL, _DISPATCH.CHAT_FROM_LOBE
#: ``(f0, f1, f2, pdf)`` of leaf ``op`` (local frame; its node table at ``tables[t:]``)
leaf_eval_pdf = _DISPATCH.eval_pdf
#: ``(wi xyz, pdf, weight rgb, lobe)`` of leaf ``op`` (lobe 0: failed)
leaf_sample = _DISPATCH.sample
#: directional albedo ``(a0, a1, a2)`` of leaf ``op``
leaf_albedo = _DISPATCH.albedo
#: a curve layer's ``C(|v.h|)`` at layer-frame directions ``v``, ``x``
curve_h = _DISPATCH.curve_h
#: a curve layer's ``C(|v.z|)`` (the control variate's curve)
curve_nk = _DISPATCH.curve_nk
#: whether a layer's (or modifier's) curve takes one value at every cosine (then Ĉ never
#: matters)
curve_constant = _DISPATCH.curve_constant
_layer_factors = _DISPATCH.layer_factors
_layer_estimates = _DISPATCH.layer_estimates
_layer_possible = _DISPATCH.layer_possible
#: a modifier's factor at ``(wo, wi)`` (an edf modifier's at ``wo``)
_scale = _DISPATCH.scale
_mix_weight = _DISPATCH.mix_weights
_edf_leaf_eval_pdf = _DISPATCH.edf_eval_pdf
_edf_leaf_sample = _DISPATCH.edf_sample
_white_albedo = _DISPATCH.white_albedo
_LEAF, _LAYER, _MIX, _MODIFIER = range(4)  # render.df._registry.ROLES


@njit(inline="always")
def _is_leaf(op):
    return _ROLE[op] == _LEAF


@njit(inline="always")
def _is_layer(op):
    return _ROLE[op] == _LAYER


@njit(inline="always")
def _is_mix(op):
    return _ROLE[op] == _MIX


@njit(inline="always")
def _is_edf_mix(op):
    return _ROLE[op] == _MIX and _EDF[op]


@njit(inline="always")
def _is_edf_scale(op):
    """An edf modifier: a factor of ``wo`` alone times its child's emission."""
    return _ROLE[op] == _MODIFIER and _EDF[op]


@njit
def _scale_varies(op, P, row, b, fl, tables, t):
    """Whether a modifier's factor depends on ``wi`` (then its albedo needs the
    quadrature correction): a directional one whose curve is not flat."""
    if not _DIRECTIONAL[op] or _EDF[op]:
        return False
    return not curve_constant(op, P, row, b, fl, tables, t)


@njit
def _sheen_e(code, kids, P, row, tables, k, w):
    """The white albedo ``E(w)`` of a layer's lobe (its layer child, e.g. a
    ``sheen_bsdf`` leaf) from the lobe's own table: what a sheen layer's
    ``(1 - max(E(wo), E(wi)))`` reads."""
    lay = kids[code[k, KID0]]
    if lay < 0:
        return 0.0
    e = _white_albedo(code[lay, OP], P, row, code[lay, BASE], code[lay, FLAGS], w[0], w[1],
                      w[2], tables, code[lay, TABLE])
    return min(max(e, 0.0), 1.0)


# ------------------------------------------------------------------ small helpers
@njit(inline="always")
def _any_pos(a, b, c):
    return a > 0.0 or b > 0.0 or c > 0.0


@njit(inline="always")
def _lum(a, b, c):
    return LUM_R * a + LUM_G * b + LUM_B * c


@njit(inline="always")
def _clamp_u(u):
    return min(max(u, 0.0), ONE_MINUS_EPS)


@njit
def _agree(identity, w, wl):
    """the layer frame's side test: ``w`` strictly on one side of both tangent planes."""
    if identity:
        return abs(w[2]) > COS_ZERO
    return w[2] * wl[2] > 0.0 and abs(wl[2]) > COS_ZERO and abs(w[2]) > COS_ZERO


@njit
def _set_bases(frames, P, row, ws, fo, f0, f1):
    """The basis of every frame ``f0 .. f1 - 1`` in its parent frame
    (``Frame.from_normal_tangent`` of the layer's unit normal and ``tangent_u``); frame
    ``f0``, the program's shading frame, is the identity."""
    for f in range(f0, f1):
        o = fo + f * _FR
        if f == f0:
            for j in range(9):
                ws[o + j] = 0.0
            ws[o + _FS] = 1.0
            ws[o + _FT + 1] = 1.0
            ws[o + _FN + 2] = 1.0
            continue
        s, t = frames[f, 1], frames[f, 2]
        nx, ny, nz, ok = kc.unitize(P[row, s], P[row, s + 1], P[row, s + 2])
        if not ok:
            nx, ny, nz = 0.0, 0.0, 1.0
        sx, sy, sz, tx, ty, tz = kc.frame_from_normal_tangent(nx, ny, nz, P[row, t],
                                                              P[row, t + 1], P[row, t + 2])
        ws[o + _FS], ws[o + _FS + 1], ws[o + _FS + 2] = sx, sy, sz
        ws[o + _FT], ws[o + _FT + 1], ws[o + _FT + 2] = tx, ty, tz
        ws[o + _FN], ws[o + _FN + 1], ws[o + _FN + 2] = nx, ny, nz


@njit
def _set_dirs(frames, ws, fo, f0, f1, which, x, y, z):
    """Direction ``(x, y, z)`` of frame ``f0`` expressed in every frame ``f0 .. f1 - 1``
    (``which``: the wo or wi registers)."""
    o = fo + f0 * _FR
    ws[o + which], ws[o + which + 1], ws[o + which + 2] = x, y, z
    for f in range(f0 + 1, f1):
        o = fo + f * _FR
        p = fo + frames[f, 0] * _FR
        vx, vy, vz = ws[p + which], ws[p + which + 1], ws[p + which + 2]
        ws[o + which] = vx * ws[o + _FS] + vy * ws[o + _FS + 1] + vz * ws[o + _FS + 2]
        ws[o + which + 1] = vx * ws[o + _FT] + vy * ws[o + _FT + 1] + vz * ws[o + _FT + 2]
        ws[o + which + 2] = vx * ws[o + _FN] + vy * ws[o + _FN + 1] + vz * ws[o + _FN + 2]


@njit
def _to_frame0(frames, ws, fo, f, x, y, z):
    """Direction ``(x, y, z)`` of frame ``f`` in its program's shading frame (the one
    whose parent is -1): ``to_inherited`` up the chain."""
    while frames[f, 0] >= 0:
        o = fo + f * _FR
        x, y, z = (x * ws[o + _FS] + y * ws[o + _FT] + z * ws[o + _FN],
                   x * ws[o + _FS + 1] + y * ws[o + _FT + 1] + z * ws[o + _FN + 1],
                   x * ws[o + _FS + 2] + y * ws[o + _FT + 2] + z * ws[o + _FN + 2])
        f = frames[f, 0]
    return x, y, z


@njit
def _selection(ws, ko, first, k):
    """Defensive-mixture selection over kids ``first .. first + k`` whose estimate is in
    their KSEL register and whose possibility (1/0) in KON; probabilities replace the
    estimates."""
    count = 0
    total = 0.0
    for j in range(first, first + k):
        o = ko + j * _KR
        if ws[o + _KON] > 0.0:
            count += 1
            total += max(ws[o + _KSEL], 0.0)
    for j in range(first, first + k):
        o = ko + j * _KR
        if ws[o + _KON] > 0.0:
            share = 1.0 / count
            prop = max(ws[o + _KSEL], 0.0) / total if total > 0.0 else share
            ws[o + _KSEL] = (1.0 - DEFENSIVE) * prop + DEFENSIVE * share
        else:
            ws[o + _KSEL] = 0.0


@njit
def chat_lookup(tables, t, wl0, wl1, wl2):
    """Ĉ from a table at offset ``t`` (made by :func:`build_chat_table`): linear in the
    polar angle between nodes, plus the concave pad."""
    mu = wl2
    side = 1 if mu < 0.0 else 0
    theta = CHAT_THETA
    step = math.acos(1e-3) / (theta - 1)
    tt = math.acos(min(abs(mu), 1.0)) / step
    j = min(int(math.floor(tt)), theta - 2)
    f = min(max(tt - j, 0.0), 1.0)
    base = t + side * 2 * theta * 3
    a = base + j * 3
    pad = base + theta * 3 + j * 3
    out0 = tables[a] * (1.0 - f) + tables[a + 3] * f + tables[pad] * f * (1.0 - f)
    out1 = tables[a + 1] * (1.0 - f) + tables[a + 4] * f + tables[pad + 1] * f * (1.0 - f)
    out2 = tables[a + 2] * (1.0 - f) + tables[a + 5] * f + tables[pad + 2] * f * (1.0 - f)
    return out0, out1, out2


# ------------------------------------------------------------------ passes
@njit
def prepare(code, kids, frames, P, tables, row, ws, lo, hi, f0, f1, x, y, z):
    """Directions at ``wo = (x, y, z)`` (frame ``f0``) in the frames ``f0 .. f1 - 1``,
    then nodes ``lo..hi``: cheap albedos, layer selection probabilities and Ĉ(wo), mix
    weights and probabilities."""
    n = code.shape[0]
    ko = n * _R
    fo = ko + kids.shape[0] * _KR
    _set_bases(frames, P, row, ws, fo, f0, f1)
    _set_dirs(frames, ws, fo, f0, f1, _FWO, x, y, z)
    for k in range(lo, hi + 1):
        op = code[k, OP]
        b = code[k, BASE]
        fl = code[k, FLAGS]
        r = k * _R
        fr = fo + code[k, FRAME] * _FR
        wo = ws[fr + _FWO:fr + _FWO + 3]
        if _is_leaf(op):
            if _EDF[op]:
                ws[r + _CH], ws[r + _CH + 1], ws[r + _CH + 2] = 1.0, 1.0, 1.0
            else:
                a0, a1, a2 = leaf_albedo(op, P, row, b, fl, wo[0], wo[1], wo[2], tables,
                                         code[k, TABLE])
                ws[r + _CH], ws[r + _CH + 1], ws[r + _CH + 2] = a0, a1, a2
            continue
        k0 = code[k, KID0]
        nk = code[k, NKIDS]
        if _is_layer(op):
            lf = fo + code[k, LFRAME] * _FR
            wol = ws[lf + _FWO:lf + _FWO + 3]
            ago = _agree(code[k, LFRAME] == code[k, FRAME], wo, wol)
            c0 = c1 = c2 = 0.0
            t = code[k, TABLE]
            if t != CHAT_NONE and ago:
                c0, c1, c2 = chat_lookup(tables, t, wol[0], wol[1], wol[2])
            elif _CHAT_FROM_LOBE[op] and ago:
                c0 = c1 = c2 = _sheen_e(code, kids, P, row, tables, k, wol)
            ws[r + _CO], ws[r + _CO + 1], ws[r + _CO + 2] = c0, c1, c2
            ws[r + _AGO] = 1.0 if ago else 0.0
            el0, el1, el2, eb0, eb1, eb2 = _layer_estimates(op, P, row, b, fl, wo, wol,
                                                            ws[r + _CO:r + _CO + 3], tables,
                                                            code[k, TABLE])
            pos_l, pos_b = _layer_possible(op, P, row, b, fl, tables, code[k, TABLE])
            lay, bas = kids[k0], kids[k0 + 1]
            al0 = al1 = al2 = ab0 = ab1 = ab2 = 0.0
            if lay != _NO_KID:
                q = lay * _R + _CH
                al0, al1, al2 = ws[q], ws[q + 1], ws[q + 2]
            else:
                pos_l = False
            if bas != _NO_KID:
                q = bas * _R + _CH
                ab0, ab1, ab2 = ws[q], ws[q + 1], ws[q + 2]
            else:
                pos_b = False
            pos_l = pos_l and ago
            ka, kb = ko + k0 * _KR, ko + (k0 + 1) * _KR
            ws[ka + _KSEL] = _lum(el0 * al0, el1 * al1, el2 * al2)
            ws[kb + _KSEL] = _lum(eb0 * ab0, eb1 * ab1, eb2 * ab2)
            ws[ka + _KON] = 1.0 if pos_l else 0.0
            ws[kb + _KON] = 1.0 if pos_b else 0.0
            _selection(ws, ko, k0, 2)
            ws[r + _SEL] = ws[ka + _KSEL]
            g = 1.0 if ago else 0.0
            ws[r + _CH] = el0 * al0 * g + eb0 * ab0
            ws[r + _CH + 1] = el1 * al1 * g + eb1 * ab1
            ws[r + _CH + 2] = el2 * al2 * g + eb2 * ab2
        elif _is_mix(op):
            edf = _is_edf_mix(op)
            s0 = s1 = s2 = 0.0
            for j in range(nk):
                o = ko + (k0 + j) * _KR
                w0, w1, w2 = _mix_weight(op, P, row, b, fl, nk, j, tables, code[k, TABLE])
                ws[o + _KW], ws[o + _KW + 1], ws[o + _KW + 2] = w0, w1, w2
                c = kids[k0 + j]
                a0 = a1 = a2 = 0.0
                if c != _NO_KID:
                    q = c * _R + _CH
                    a0, a1, a2 = ws[q], ws[q + 1], ws[q + 2]
                # edf mixes select by the weights' luminance (every edf has unit exitance)
                ws[o + _KSEL] = _lum(w0, w1, w2) if edf else _lum(w0 * a0, w1 * a1, w2 * a2)
                ws[o + _KON] = 1.0 if (c != _NO_KID and _any_pos(w0, w1, w2)) else 0.0
                s0 += w0 * a0
                s1 += w1 * a1
                s2 += w2 * a2
            _selection(ws, ko, k0, nk)
            ws[r + _CH], ws[r + _CH + 1], ws[r + _CH + 2] = s0, s1, s2
        else:  # tint, directional_factor: the factor at the mirror direction
            ws[r + _TMP], ws[r + _TMP + 1], ws[r + _TMP + 2] = -wo[0], -wo[1], wo[2]
            f0, f1, f2 = _scale(op, P, row, b, fl, wo, ws[r + _TMP:r + _TMP + 3], tables,
                                code[k, TABLE])
            c = kids[k0]
            a0 = a1 = a2 = 0.0
            if c != _NO_KID:
                q = c * _R + _CH
                a0, a1, a2 = ws[q], ws[q + 1], ws[q + 2]
            ws[r + _CH], ws[r + _CH + 1], ws[r + _CH + 2] = f0 * a0, f1 * a1, f2 * a2


@njit
def evaluate(code, kids, frames, P, tables, row, ws, lo, hi, f0, f1, x, y, z):
    """Every node ``lo..hi`` at ``wi = (x, y, z)`` (frame ``f0``), after :func:`prepare`."""
    n = code.shape[0]
    ko = n * _R
    fo = ko + kids.shape[0] * _KR
    _set_dirs(frames, ws, fo, f0, f1, _FWI, x, y, z)
    for k in range(lo, hi + 1):
        op = code[k, OP]
        b = code[k, BASE]
        fl = code[k, FLAGS]
        r = k * _R
        fr = fo + code[k, FRAME] * _FR
        wo = ws[fr + _FWO:fr + _FWO + 3]
        wi = ws[fr + _FWI:fr + _FWI + 3]
        v0 = v1 = v2 = pdf = 0.0
        if _is_leaf(op):
            v0, v1, v2, pdf = leaf_eval_pdf(op, P, row, b, fl, wo[0], wo[1], wo[2],
                                            wi[0], wi[1], wi[2], tables, code[k, TABLE])
        else:
            k0 = code[k, KID0]
            nk = code[k, NKIDS]
            if _is_layer(op):
                lf = fo + code[k, LFRAME] * _FR
                wol = ws[lf + _FWO:lf + _FWO + 3]
                wil = ws[lf + _FWI:lf + _FWI + 3]
                agi = _agree(code[k, LFRAME] == code[k, FRAME], wi, wil)
                c0 = c1 = c2 = 0.0
                t = code[k, TABLE]
                if t != CHAT_NONE and agi:
                    c0, c1, c2 = chat_lookup(tables, t, wil[0], wil[1], wil[2])
                elif _CHAT_FROM_LOBE[op] and agi:
                    c0 = c1 = c2 = _sheen_e(code, kids, P, row, tables, k, wil)
                ws[r + _CW], ws[r + _CW + 1], ws[r + _CW + 2] = c0, c1, c2
                fl0, fl1, fl2, fb0, fb1, fb2 = _layer_factors(
                    op, P, row, b, fl, wo, wi, wol, wil, ws[r + _CO:r + _CO + 3],
                    ws[r + _CW:r + _CW + 3], tables, t)
                if not (ws[r + _AGO] > 0.0 and agi):
                    fl0 = fl1 = fl2 = 0.0
                P_l = ws[r + _SEL]
                ka, kb = ko + k0 * _KR, ko + (k0 + 1) * _KR
                ws[ka + _KF], ws[ka + _KF + 1], ws[ka + _KF + 2] = fl0, fl1, fl2
                ws[kb + _KF], ws[kb + _KF + 1], ws[kb + _KF + 2] = fb0, fb1, fb2
                lay, bas = kids[k0], kids[k0 + 1]
                cl0 = cl1 = cl2 = cb0 = cb1 = cb2 = pl = pb = 0.0
                if lay != _NO_KID:
                    q = lay * _R
                    cl0, cl1, cl2 = fl0 * ws[q], fl1 * ws[q + 1], fl2 * ws[q + 2]
                    pl = ws[q + _PDF]
                if bas != _NO_KID:
                    q = bas * _R
                    cb0, cb1, cb2 = fb0 * ws[q], fb1 * ws[q + 1], fb2 * ws[q + 2]
                    pb = ws[q + _PDF]
                on_l = _any_pos(cl0, cl1, cl2)
                on_b = _any_pos(cb0, cb1, cb2)
                ws[ka + _KON] = 1.0 if on_l else 0.0
                ws[kb + _KON] = 1.0 if on_b else 0.0
                pdf = (P_l * pl if on_l else 0.0) + ((1.0 - P_l) * pb if on_b else 0.0)
                v0, v1, v2 = cl0 + cb0, cl1 + cb1, cl2 + cb2
            elif _is_mix(op):
                for j in range(nk):
                    o = ko + (k0 + j) * _KR
                    c = kids[k0 + j]
                    if c == _NO_KID:
                        ws[o + _KON] = 0.0
                        continue
                    q = c * _R
                    c0 = ws[o + _KW] * ws[q]
                    c1 = ws[o + _KW + 1] * ws[q + 1]
                    c2 = ws[o + _KW + 2] * ws[q + 2]
                    on = _any_pos(c0, c1, c2)
                    ws[o + _KON] = 1.0 if on else 0.0
                    v0 += c0
                    v1 += c1
                    v2 += c2
                    if on:
                        pdf += ws[o + _KSEL] * ws[q + _PDF]
            else:
                f0, f1, f2 = _scale(op, P, row, b, fl, wo, wi, tables, code[k, TABLE])
                o = ko + k0 * _KR
                ws[o + _KF], ws[o + _KF + 1], ws[o + _KF + 2] = f0, f1, f2
                c = kids[k0]
                if c != _NO_KID:
                    q = c * _R
                    v0, v1, v2 = f0 * ws[q], f1 * ws[q + 1], f2 * ws[q + 2]
                    if _any_pos(v0, v1, v2):
                        pdf = ws[q + _PDF]
                ws[o + _KON] = 1.0 if pdf > 0.0 else 0.0
            if not pdf > 0.0:
                v0 = v1 = v2 = pdf = 0.0
        ws[r + _F], ws[r + _F + 1], ws[r + _F + 2] = v0, v1, v2
        ws[r + _PDF] = pdf
        ws[r + _ON] = 1.0 if _any_pos(v0, v1, v2) else 0.0


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
    r = root * _R
    return ws[r + _F], ws[r + _F + 1], ws[r + _F + 2], ws[r + _PDF]


@njit
def sample(code, kids, frames, P, tables, row, ws, root, f0, f1, ox, oy, oz, u1, u2x, u2y,
           prepared):
    """``(wi xyz, pdf, weight rgb, lobe)`` of the program rooted at ``root`` (lobe 0:
    failed); directions in its shading frame.  ``prepared``: :func:`eval_pdf` has just
    run on ``ws`` at the same ``wo`` (its :func:`prepare` holds: evaluate changes none
    of the registers prepare sets)."""
    if code[root, SIZE] == 1 and code[root, FRAME] == f0:  # one df: its kernel alone
        return leaf_sample(code[root, OP], P, row, code[root, BASE], code[root, FLAGS],
                           ox, oy, oz, u1, u2x, u2y, tables, code[root, TABLE])
    n = code.shape[0]
    ko = n * _R
    fo = ko + kids.shape[0] * _KR
    lo = root - code[root, SIZE] + 1
    if not prepared:
        prepare(code, kids, frames, P, tables, row, ws, lo, root, f0, f1, ox, oy, oz)
    # descend: remember the chosen child (kid slot) and its parent at every combiner
    po = fo + frames.shape[0] * _FR
    depth = 0
    k = root
    while not _is_leaf(code[k, OP]):
        op = code[k, OP]
        k0 = code[k, KID0]
        nk = code[k, NKIDS]
        j = -1
        if _is_layer(op):
            p = ws[k * _R + _SEL]
            if u1 < p:
                j = k0
                u1 = _clamp_u(u1 / p if p > 0.0 else 0.0)
            else:
                j = k0 + 1
                u1 = _clamp_u((u1 - p) / (1.0 - p) if p < 1.0 else 0.0)
        elif _is_mix(op):
            cdf = 0.0
            last = -1
            for jj in range(k0, k0 + nk):
                if ws[ko + jj * _KR + _KSEL] > 0.0:
                    last = jj
            if last < 0:
                return 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0
            j = last
            for jj in range(k0, last + 1):
                p = ws[ko + jj * _KR + _KSEL]
                if u1 < cdf + p and p > 0.0:
                    j = jj
                    break
                cdf += p
            p = ws[ko + j * _KR + _KSEL]
            before = 0.0
            for jj in range(k0, j):
                before += ws[ko + jj * _KR + _KSEL]
            u1 = _clamp_u((u1 - before) / p)
        else:
            j = k0
        if kids[j] == _NO_KID or depth >= MAX_DEPTH:
            return 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0
        ws[po + depth] = j
        ws[po + MAX_DEPTH + depth] = k
        depth += 1
        k = kids[j]
    f = code[k, FRAME]
    fr = fo + f * _FR
    wx, wy, wz, pdf, w0, w1, w2, lobe = leaf_sample(
        code[k, OP], P, row, code[k, BASE], code[k, FLAGS], ws[fr + _FWO], ws[fr + _FWO + 1],
        ws[fr + _FWO + 2], u1, u2x, u2y, tables, code[k, TABLE])
    if lobe == 0:
        return 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0
    wx, wy, wz = _to_frame0(frames, ws, fo, f, wx, wy, wz)
    if depth == 0:
        return wx, wy, wz, pdf, w0, w1, w2, lobe
    evaluate(code, kids, frames, P, tables, row, ws, lo, root, f0, f1, wx, wy, wz)
    delta = (lobe & SPECULAR_LOBES) != 0
    # settle the choices from the leaf up (render.df._combine: Draw/_settle)
    for d in range(depth - 1, -1, -1):
        j = int(ws[po + d])
        k = int(ws[po + MAX_DEPTH + d])
        o = ko + j * _KR
        op = code[k, OP]
        if delta:
            if _is_layer(op):
                p = ws[k * _R + _SEL]
                psel = p if j == code[k, KID0] else 1.0 - p
                g0, g1, g2 = ws[o + _KF], ws[o + _KF + 1], ws[o + _KF + 2]
            elif _is_mix(op):
                psel = ws[o + _KSEL]
                g0, g1, g2 = ws[o + _KW], ws[o + _KW + 1], ws[o + _KW + 2]
            else:
                psel = 1.0
                g0, g1, g2 = ws[o + _KF], ws[o + _KF + 1], ws[o + _KF + 2]
            if not psel > 0.0:
                return 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0
            w0, w1, w2 = g0 * w0 / psel, g1 * w1 / psel, g2 * w2 / psel
            pdf = psel * pdf
            if not (_any_pos(w0, w1, w2) and pdf > 0.0):
                return 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0
        elif not (ws[o + _KON] > 0.0 and ws[k * _R + _PDF] > 0.0):
            return 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0
    if not delta:
        r = root * _R
        pdf = ws[r + _PDF]
        w0, w1, w2 = ws[r + _F] / pdf, ws[r + _F + 1] / pdf, ws[r + _F + 2] / pdf
    return wx, wy, wz, pdf, w0, w1, w2, lobe


@njit
def cheap_albedo(code, kids, frames, P, tables, row, ws, root, f0, f1, ox, oy, oz):
    """The fast albedo estimate (``render.df.albedo_estimate``): exact for elemental
    dfs, mixes, weighted layers and tint; factors at ``wo`` times the children's
    estimates for the directional combiners."""
    lo = root - code[root, SIZE] + 1
    prepare(code, kids, frames, P, tables, row, ws, lo, root, f0, f1, ox, oy, oz)
    r = root * _R + _CH
    return max(ws[r], 0.0), max(ws[r + 1], 0.0), max(ws[r + 2], 0.0)


@njit
def _layer_factors_at(code, kids, frames, P, tables, row, ws, k, f0, f1, x, y, z):
    """Layer ``k``'s factors ``(f_layer, f_base)`` at ``wi = (x, y, z)`` (frame ``f0``),
    the layer factor masked where a direction leaves the two tangent planes' common
    side; after :func:`prepare` at ``wo``."""
    n = code.shape[0]
    fo = n * _R + kids.shape[0] * _KR
    _set_dirs(frames, ws, fo, f0, f1, _FWI, x, y, z)
    r = k * _R
    fr = fo + code[k, FRAME] * _FR
    lf = fo + code[k, LFRAME] * _FR
    wo = ws[fr + _FWO:fr + _FWO + 3]
    wi = ws[fr + _FWI:fr + _FWI + 3]
    wol = ws[lf + _FWO:lf + _FWO + 3]
    wil = ws[lf + _FWI:lf + _FWI + 3]
    agi = _agree(code[k, LFRAME] == code[k, FRAME], wi, wil)
    c0 = c1 = c2 = 0.0
    t = code[k, TABLE]
    if t != CHAT_NONE and agi:
        c0, c1, c2 = chat_lookup(tables, t, wil[0], wil[1], wil[2])
    elif _CHAT_FROM_LOBE[code[k, OP]] and agi:
        c0 = c1 = c2 = _sheen_e(code, kids, P, row, tables, k, wil)
    ws[r + _CW], ws[r + _CW + 1], ws[r + _CW + 2] = c0, c1, c2
    fl0, fl1, fl2, fb0, fb1, fb2 = _layer_factors(
        code[k, OP], P, row, code[k, BASE], code[k, FLAGS], wo, wi, wol, wil,
        ws[r + _CO:r + _CO + 3], ws[r + _CW:r + _CW + 3], tables, t)
    if not (ws[r + _AGO] > 0.0 and agi):
        fl0 = fl1 = fl2 = 0.0
    return fl0, fl1, fl2, fb0, fb1, fb2


@njit
def _is_mirror(code, c):
    """Node ``c`` is ``specular_bsdf`` reflecting: it scatters to the mirror direction."""
    return c >= 0 and _MIRROR[code[c, OP]] and (code[c, FLAGS] & MODE_MASK) == REFLECT


@njit
def _correction(code, kids, frames, P, tables, row, ws, k, child, which, e0, e1, e2, f0, f1,
                ox, oy, oz, points):
    """``∫ (factor(wi) - e) child.eval(wo, wi) dwi`` through the child's own sampler over
    ``points`` (a control variate: the factor's value ``e`` at ``wo`` is exact, the
    integral adds its deviation): ``which`` picks the factor
    (0 the layer's, 1 the base's, 2 a scaled node's)."""
    s0 = s1 = s2 = 0.0
    m = points.shape[0]
    for i in range(m):
        s = sample(code, kids, frames, P, tables, row, ws, child, f0, f1, ox, oy, oz,
                   points[i, 0], points[i, 1], points[i, 2], False)
        if s[7] == 0:
            continue
        # the node's own registers at wo again (the child's pass rewrote shared frames)
        prepare(code, kids, frames, P, tables, row, ws, k, k, f0, f1, ox, oy, oz)
        if which == 2:
            n = code.shape[0]
            fo = n * _R + kids.shape[0] * _KR
            _set_dirs(frames, ws, fo, f0, f1, _FWI, s[0], s[1], s[2])
            fr = fo + code[k, FRAME] * _FR
            g0, g1, g2 = _scale(code[k, OP], P, row, code[k, BASE], code[k, FLAGS],
                                ws[fr + _FWO:fr + _FWO + 3], ws[fr + _FWI:fr + _FWI + 3],
                                tables, code[k, TABLE])
        else:
            a = _layer_factors_at(code, kids, frames, P, tables, row, ws, k, f0, f1,
                                  s[0], s[1], s[2])
            g0, g1, g2 = (a[0], a[1], a[2]) if which == 0 else (a[3], a[4], a[5])
        s0 += (g0 - e0) * s[4]
        s1 += (g1 - e1) * s[5]
        s2 += (g2 - e2) * s[6]
    return s0 / m, s1 / m, s2 / m


@njit
def albedo(code, kids, frames, P, tables, row, ws, root, f0, f1, points, ox, oy, oz):
    """Directional albedo of the program at ``wo`` (``Bsdf.albedo``): exact for the
    elemental dfs, mixes, weighted layers in their own frame and ``tint``; the
    directional combiners add the integral of their factors' deviation from their value
    at ``wo`` through each child's sampler over ``points`` (``render.df._combine``'s
    control variate).  Clipped to [0, 1] for layers (they never gain energy)."""
    n = code.shape[0]
    ko = n * _R
    fo = ko + kids.shape[0] * _KR
    lo = root - code[root, SIZE] + 1
    for k in range(lo, root + 1):
        op = code[k, OP]
        b = code[k, BASE]
        fl = code[k, FLAGS]
        r = k * _R
        prepare(code, kids, frames, P, tables, row, ws, k, k, f0, f1, ox, oy, oz)
        fr = fo + code[k, FRAME] * _FR
        wo = ws[fr + _FWO:fr + _FWO + 3]
        a0 = a1 = a2 = 0.0
        if _is_leaf(op):
            a0, a1, a2 = leaf_albedo(op, P, row, b, fl, wo[0], wo[1], wo[2], tables,
                                     code[k, TABLE])
        elif _is_mix(op):
            k0 = code[k, KID0]
            for j in range(code[k, NKIDS]):
                c = kids[k0 + j]
                if c != _NO_KID:
                    o = ko + (k0 + j) * _KR
                    a0 += ws[o + _KW] * ws[c * _R + _AL]
                    a1 += ws[o + _KW + 1] * ws[c * _R + _AL + 1]
                    a2 += ws[o + _KW + 2] * ws[c * _R + _AL + 2]
        elif _is_layer(op):
            k0 = code[k, KID0]
            lay, bas = kids[k0], kids[k0 + 1]
            lf = fo + code[k, LFRAME] * _FR
            wol = ws[lf + _FWO:lf + _FWO + 3]
            el0, el1, el2, eb0, eb1, eb2 = _layer_estimates(op, P, row, b, fl, wo, wol,
                                                            ws[r + _CO:r + _CO + 3], tables,
                                                            code[k, TABLE])
            if not ws[r + _AGO] > 0.0:
                el0 = el1 = el2 = 0.0
            identity = code[k, LFRAME] == code[k, FRAME]
            directional = _DIRECTIONAL[op]
            if lay != _NO_KID:
                q = lay * _R + _AL
                a0, a1, a2 = el0 * ws[q], el1 * ws[q + 1], el2 * ws[q + 2]
                if not (identity and (not directional or _is_mirror(code, lay))):
                    d0, d1, d2 = _correction(code, kids, frames, P, tables, row, ws, k, lay,
                                             0, el0, el1, el2, f0, f1, ox, oy, oz, points)
                    a0, a1, a2 = a0 + d0, a1 + d1, a2 + d2
            if bas != _NO_KID:
                q = bas * _R + _AL
                if directional and _is_mirror(code, bas):
                    prepare(code, kids, frames, P, tables, row, ws, k, k, f0, f1, ox, oy, oz)
                    m = _layer_factors_at(code, kids, frames, P, tables, row, ws, k, f0, f1,
                                          -ox, -oy, oz)
                    a0, a1, a2 = a0 + m[3] * ws[q], a1 + m[4] * ws[q + 1], a2 + m[5] * ws[q + 2]
                else:
                    a0, a1, a2 = a0 + eb0 * ws[q], a1 + eb1 * ws[q + 1], a2 + eb2 * ws[q + 2]
                    if directional:
                        d0, d1, d2 = _correction(code, kids, frames, P, tables, row, ws, k,
                                                 bas, 1, eb0, eb1, eb2, f0, f1, ox, oy, oz,
                                                 points)
                        a0, a1, a2 = a0 + d0, a1 + d1, a2 + d2
            a0, a1, a2 = min(max(a0, 0.0), 1.0), min(max(a1, 0.0), 1.0), min(max(a2, 0.0), 1.0)
        else:  # tint, directional_factor: the factor at the mirror direction, corrected
            c = kids[code[k, KID0]]
            if c != _NO_KID:
                ws[r + _TMP], ws[r + _TMP + 1], ws[r + _TMP + 2] = -wo[0], -wo[1], wo[2]
                e0, e1, e2 = _scale(op, P, row, b, fl, wo, ws[r + _TMP:r + _TMP + 3], tables,
                                    code[k, TABLE])
                q = c * _R + _AL
                a0, a1, a2 = e0 * ws[q], e1 * ws[q + 1], e2 * ws[q + 2]
                varies = _scale_varies(op, P, row, b, fl, tables, code[k, TABLE])
                if varies and not _is_mirror(code, c):
                    d0, d1, d2 = _correction(code, kids, frames, P, tables, row, ws, k, c, 2,
                                             e0, e1, e2, f0, f1, ox, oy, oz, points)
                    a0, a1, a2 = max(a0 + d0, 0.0), max(a1 + d1, 0.0), max(a2 + d2, 0.0)
        ws[r + _AL], ws[r + _AL + 1], ws[r + _AL + 2] = a0, a1, a2
    q = root * _R + _AL
    return ws[q], ws[q + 1], ws[q + 2]


# ------------------------------------------------------------------ EDF programs
@njit
def edf_eval_pdf(code, kids, frames, P, tables, row, ws, root, f0, f1, ox, oy, oz):
    """``(e0, e1, e2, pdf)`` of the edf program rooted at ``root`` toward ``wo``
    (``Edf.eval``, ``Edf.pdf``)."""
    n = code.shape[0]
    ko = n * _R
    fo = ko + kids.shape[0] * _KR
    lo = root - code[root, SIZE] + 1
    prepare(code, kids, frames, P, tables, row, ws, lo, root, f0, f1, ox, oy, oz)
    for k in range(lo, root + 1):
        op = code[k, OP]
        r = k * _R
        v0 = v1 = v2 = pdf = 0.0
        if _is_leaf(op):
            v0, v1, v2, pdf = _edf_leaf_eval_pdf(op, P, row, code[k, BASE], code[k, FLAGS],
                                                 ox, oy, oz, tables, code[k, TABLE])
        elif _is_edf_scale(op):
            c = kids[code[k, KID0]]
            if c != _NO_KID:
                fr = fo + code[k, FRAME] * _FR
                wo = ws[fr + _FWO:fr + _FWO + 3]
                f0, f1, f2 = _scale(op, P, row, code[k, BASE], code[k, FLAGS], wo, wo, tables,
                                    code[k, TABLE])
                q = c * _R
                v0, v1, v2 = f0 * ws[q], f1 * ws[q + 1], f2 * ws[q + 2]
                if _any_pos(v0, v1, v2):
                    pdf = ws[q + _PDF]
            if not pdf > 0.0:
                v0 = v1 = v2 = pdf = 0.0
        else:
            k0 = code[k, KID0]
            for j in range(code[k, NKIDS]):
                o = ko + (k0 + j) * _KR
                c = kids[k0 + j]
                if c == _NO_KID:
                    continue
                q = c * _R
                c0 = ws[o + _KW] * ws[q]
                c1 = ws[o + _KW + 1] * ws[q + 1]
                c2 = ws[o + _KW + 2] * ws[q + 2]
                v0 += c0
                v1 += c1
                v2 += c2
                if _any_pos(c0, c1, c2):
                    pdf += ws[o + _KSEL] * ws[q + _PDF]
            if not pdf > 0.0:
                v0 = v1 = v2 = pdf = 0.0
        ws[r + _F], ws[r + _F + 1], ws[r + _F + 2] = v0, v1, v2
        ws[r + _PDF] = pdf
    r = root * _R
    return ws[r + _F], ws[r + _F + 1], ws[r + _F + 2], ws[r + _PDF]


@njit
def edf_sample(code, kids, frames, P, tables, row, ws, root, f0, f1, u1, u2x, u2y):
    """``(wo xyz, pdf, weight rgb)`` of the edf program rooted at ``root`` (``EdfSample``;
    pdf 0: failed)."""
    n = code.shape[0]
    ko = n * _R
    k = root
    if not _is_leaf(code[k, OP]):
        prepare(code, kids, frames, P, tables, row, ws, root - code[root, SIZE] + 1, root,
                f0, f1, 0.0, 0.0, 1.0)
    while not _is_leaf(code[k, OP]):
        k0 = code[k, KID0]
        nk = code[k, NKIDS]
        if _is_edf_scale(code[k, OP]):  # a modifier: its one child
            k = kids[k0]
            if k == _NO_KID:
                return 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0
            continue
        last = -1
        for jj in range(k0, k0 + nk):
            if ws[ko + jj * _KR + _KSEL] > 0.0:
                last = jj
        if last < 0:
            return 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0
        j = last
        cdf = 0.0
        for jj in range(k0, last + 1):
            p = ws[ko + jj * _KR + _KSEL]
            if u1 < cdf + p and p > 0.0:
                j = jj
                break
            cdf += p
        p = ws[ko + j * _KR + _KSEL]
        before = 0.0
        for jj in range(k0, j):
            before += ws[ko + jj * _KR + _KSEL]
        u1 = _clamp_u((u1 - before) / p)
        k = kids[j]
        if k == _NO_KID:
            return 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0
    wx, wy, wz, pdf, w0, w1, w2 = _edf_leaf_sample(code[k, OP], P, row, code[k, BASE],
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
            out[i, j, 0], out[i, j, 1], out[i, j, 2] = _mix_weight(op, P, _row(P, i), b, 0,
                                                                   k, j, tables, CHAT_NONE)


# ------------------------------------------------------------------ Ĉ tables
@njit(allocates=True)
def build_chat_table(code, kids, frames, P, tables, row, k, dirs, points, out):
    """The Ĉ table of curve layer ``k`` (both sides): ``out`` (2, 2, THETA, 3) gets per
    side the node values (largest over the azimuths of ``dirs``) and the concave pad.

    ``dirs`` (2, THETA * PHI, 3): the layer-frame table directions of each side;
    ``points`` (m, 3) the Sobol points.  The layer child is sampled in its own frame;
    with an elemental layer ``C(nk) albedo_L`` is the control variate.
    """
    ws = _ws(code, kids, frames)
    n = code.shape[0]
    ko = n * _R
    fo = ko + kids.shape[0] * _KR
    nf = frames.shape[0]
    op = code[k, OP]
    b = code[k, BASE]
    fl = code[k, FLAGS]
    lay = kids[code[k, KID0]]
    lframe = code[k, LFRAME]
    controlled = _is_leaf(code[lay, OP])
    theta = CHAT_THETA
    nd = dirs.shape[1]
    phi = nd // theta
    m = points.shape[0]
    _set_bases(frames, P, row, ws, fo, 0, nf)
    for side in range(2):
        for t in range(theta):
            for c in range(3):
                out[side, 0, t, c] = 0.0
        for d in range(nd):
            vx, vy, vz = dirs[side, d, 0], dirs[side, d, 1], dirs[side, d, 2]
            # the direction in frame 0, for the subtree's own frames
            gx, gy, gz = _to_frame0(frames, ws, fo, lframe, vx, vy, vz)
            n0, n1, n2 = curve_nk(op, P, row, b, fl, vx, vy, vz, tables, code[k, TABLE])
            s0 = s1 = s2 = 0.0
            for i in range(m):
                s = sample(code, kids, frames, P, tables, row, ws, lay, 0, nf, gx, gy, gz,
                           points[i, 0], points[i, 1], points[i, 2], False)
                if s[7] == 0:
                    continue
                fx, fy, fz = s[0], s[1], s[2]
                # back into the layer frame
                lf = fo + lframe * _FR
                if lframe > 0:
                    _set_dirs(frames, ws, fo, 0, nf, _FWI, fx, fy, fz)
                    fx, fy, fz = ws[lf + _FWI], ws[lf + _FWI + 1], ws[lf + _FWI + 2]
                h0, h1, h2 = curve_h(op, P, row, b, fl, vx, vy, vz, fx, fy, fz, tables,
                                     code[k, TABLE])
                if controlled:
                    h0, h1, h2 = h0 - n0, h1 - n1, h2 - n2
                s0 += h0 * s[4]
                s1 += h1 * s[5]
                s2 += h2 * s[6]
            c0, c1, c2 = s0 / m, s1 / m, s2 / m
            if controlled:
                a0, a1, a2 = leaf_albedo(code[lay, OP], P, row, code[lay, BASE],
                                         code[lay, FLAGS], vx, vy, vz, tables,
                                         code[lay, TABLE])
                c0, c1, c2 = c0 + n0 * a0, c1 + n1 * a1, c2 + n2 * a2
            if not abs(vz) > 0.0:
                c0 = c1 = c2 = 0.0
            t = d // phi
            out[side, 0, t, 0] = max(out[side, 0, t, 0], min(max(c0, 0.0), 1.0))
            out[side, 0, t, 1] = max(out[side, 0, t, 1], min(max(c1, 0.0), 1.0))
            out[side, 0, t, 2] = max(out[side, 0, t, 2], min(max(c2, 0.0), 1.0))
        # the concave correction of each interval (second differences, pole mirrored)
        for c in range(3):
            for t in range(theta):
                out[side, 1, t, c] = 0.0
            for t in range(theta - 1):
                d2a = _second_difference(out, side, c, t, theta)
                d2b = _second_difference(out, side, c, t + 1, theta)
                out[side, 1, t, c] = 0.5 * max(0.0, -min(d2a, d2b))


@njit
def _second_difference(out, side, c, t, theta):
    """``v[t-1] - 2 v[t] + v[t+1]`` with the pole mirrored (``v[-1] = v[1]``) and the last
    node taking its neighbour's value."""
    if t == theta - 1:
        t = theta - 2
    prev = out[side, 0, 1, c] if t == 0 else out[side, 0, t - 1, c]
    return prev - 2.0 * out[side, 0, t, c] + out[side, 0, t + 1, c]
