"""The scratch of one lane's interpretation of a df program: registers and frames.

:mod:`render.interpreter` walks a program (:mod:`render.program`) over a scratch array
``ws`` of :func:`work_size` floats; the phases of the combiners (:mod:`render.df._layer`,
:mod:`render.df._mix`, :mod:`render.df._modifier`) read and write the same registers.
This module is their one description:

* per node (``R`` floats at ``k * R``): its value (``F``, 3), ``PDF``, whether it
  contributes (``ON``), its cheap albedo (``CH``, 3), a layer's probability of choosing
  its layer child (``SEL``), a layer's Ĉ at ``wo`` (``CO``, 3), whether ``wo`` agrees
  with its layer frame (``AGO``), its Ĉ at ``wi`` (``CW``, 3), a scratch direction
  (``TMP``, 3) and the full albedo (``AL``, 3; untouched by prepare and evaluate);
* per child slot (``KR`` floats at ``ko + j * KR``, ``ko = nodes * R``): the factor its
  parent applies (``KF``, 3), its selection probability (``KSEL``), whether it
  contributes (``KON``), a mix's weight (``KW``, 3);
* per frame (``FR`` floats at ``fo + f * FR``, ``fo = ko + kids * KR``): its basis
  ``s, t, n`` in its parent frame (``FS``, ``FT``, ``FN``) and ``wo``, ``wi`` in it
  (``FWO``, ``FWI``);
* then the descent's path (``2 * MAX_DEPTH``).
"""

from __future__ import annotations

import math

from render.df import _kernel_common as kc
from render.jit import njit
from render.program import CHAT_THETA, COS_ZERO, DEFENSIVE, LUM_B, LUM_G, LUM_R, ONE_MINUS_EPS

__all__ = ["work_size", "any_pos", "lum", "clamp_u", "agree", "set_bases", "set_dirs",
           "to_frame0", "selection", "chat_lookup", "MAX_DEPTH", "NO_KID"]

# per-node registers (R floats per node): value, pdf, contributes, cheap albedo,
# selection probability of the layer child, Ĉ(wo), wo agrees with the layer frame,
# Ĉ(wi), a scratch direction, the full albedo (untouched by prepare and evaluate)
F, PDF, ON, CH, SEL, CO, AGO, CW, TMP, AL = 0, 3, 4, 5, 8, 9, 12, 13, 16, 19
R = 22
# per-child registers: factor (3), selection probability, contributes, mix weight (3)
KF, KSEL, KON, KW = 0, 3, 4, 5
KR = 8
# per-frame registers: basis s, t, n (9), wo (3), wi (3)
FS, FT, FN, FWO, FWI = 0, 3, 6, 9, 12
FR = 15
#: deepest nesting of combiners a program may have (the descent's path is kept in ws)
MAX_DEPTH = 64
NO_KID = -1


@njit
def work_size(n_nodes, n_kids, n_frames):
    """Floats of scratch one lane's interpretation needs."""
    return n_nodes * R + n_kids * KR + n_frames * FR + 2 * MAX_DEPTH


@njit(inline="always")
def any_pos(a, b, c):
    return a > 0.0 or b > 0.0 or c > 0.0


@njit(inline="always")
def lum(a, b, c):
    return LUM_R * a + LUM_G * b + LUM_B * c


@njit(inline="always")
def clamp_u(u):
    return min(max(u, 0.0), ONE_MINUS_EPS)


@njit
def agree(identity, w, wl):
    """the layer frame's side test: ``w`` strictly on one side of both tangent planes."""
    if identity:
        return abs(w[2]) > COS_ZERO
    return w[2] * wl[2] > 0.0 and abs(wl[2]) > COS_ZERO and abs(w[2]) > COS_ZERO


@njit
def set_bases(frames, P, row, ws, fo, f0, f1):
    """The basis of every frame ``f0 .. f1 - 1`` in its parent frame
    (``Frame.from_normal_tangent`` of the layer's unit normal and ``tangent_u``); frame
    ``f0``, the program's shading frame, is the identity."""
    for f in range(f0, f1):
        o = fo + f * FR
        if f == f0:
            for j in range(9):
                ws[o + j] = 0.0
            ws[o + FS] = 1.0
            ws[o + FT + 1] = 1.0
            ws[o + FN + 2] = 1.0
            continue
        s, t = frames[f, 1], frames[f, 2]
        nx, ny, nz, ok = kc.unitize(P[row, s], P[row, s + 1], P[row, s + 2])
        if not ok:
            nx, ny, nz = 0.0, 0.0, 1.0
        sx, sy, sz, tx, ty, tz = kc.frame_from_normal_tangent(nx, ny, nz, P[row, t],
                                                              P[row, t + 1], P[row, t + 2])
        ws[o + FS], ws[o + FS + 1], ws[o + FS + 2] = sx, sy, sz
        ws[o + FT], ws[o + FT + 1], ws[o + FT + 2] = tx, ty, tz
        ws[o + FN], ws[o + FN + 1], ws[o + FN + 2] = nx, ny, nz


@njit
def set_dirs(frames, ws, fo, f0, f1, which, x, y, z):
    """Direction ``(x, y, z)`` of frame ``f0`` expressed in every frame ``f0 .. f1 - 1``
    (``which``: the wo or wi registers)."""
    o = fo + f0 * FR
    ws[o + which], ws[o + which + 1], ws[o + which + 2] = x, y, z
    for f in range(f0 + 1, f1):
        o = fo + f * FR
        p = fo + frames[f, 0] * FR
        vx, vy, vz = ws[p + which], ws[p + which + 1], ws[p + which + 2]
        ws[o + which] = vx * ws[o + FS] + vy * ws[o + FS + 1] + vz * ws[o + FS + 2]
        ws[o + which + 1] = vx * ws[o + FT] + vy * ws[o + FT + 1] + vz * ws[o + FT + 2]
        ws[o + which + 2] = vx * ws[o + FN] + vy * ws[o + FN + 1] + vz * ws[o + FN + 2]


@njit
def to_frame0(frames, ws, fo, f, x, y, z):
    """Direction ``(x, y, z)`` of frame ``f`` in its program's shading frame (the one
    whose parent is -1): ``to_inherited`` up the chain."""
    while frames[f, 0] >= 0:
        o = fo + f * FR
        x, y, z = (x * ws[o + FS] + y * ws[o + FT] + z * ws[o + FN],
                   x * ws[o + FS + 1] + y * ws[o + FT + 1] + z * ws[o + FN + 1],
                   x * ws[o + FS + 2] + y * ws[o + FT + 2] + z * ws[o + FN + 2])
        f = frames[f, 0]
    return x, y, z


@njit
def selection(ws, ko, first, k):
    """Defensive-mixture selection over kids ``first .. first + k`` whose estimate is in
    their KSEL register and whose possibility (1/0) in KON; probabilities replace the
    estimates."""
    count = 0
    total = 0.0
    for j in range(first, first + k):
        o = ko + j * KR
        if ws[o + KON] > 0.0:
            count += 1
            total += max(ws[o + KSEL], 0.0)
    for j in range(first, first + k):
        o = ko + j * KR
        if ws[o + KON] > 0.0:
            share = 1.0 / count
            prop = max(ws[o + KSEL], 0.0) / total if total > 0.0 else share
            ws[o + KSEL] = (1.0 - DEFENSIVE) * prop + DEFENSIVE * share
        else:
            ws[o + KSEL] = 0.0


@njit
def chat_lookup(tables, t, wl0, wl1, wl2):
    """Ĉ from a table at offset ``t`` (made by :func:`render.df._layer.build_chat_table`):
    linear in the polar angle between nodes, plus the concave pad."""
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
