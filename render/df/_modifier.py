"""The modifiers' framework: a factor times one child, shared by ``tint``, the directional
factors and their edf forms (``reference/mdl-distribution-functions.md`` §3.4)::

    eval = s(wo, wi) base.eval(wo, wi),    pdf = base.pdf (0 where the product is)

A modifier samples its child and weights the sample by ``s`` at the drawn direction
(delta events: the child's weight times ``s``).  An edf modifier's factor depends on
``wo`` alone.  The albedo is ``s`` at the mirror direction times the child's albedo,
plus, where ``s`` varies over ``wi`` (every modifier but ``tint`` and a flat curve:
the node's ``directional`` declaration and its ``curve_constant`` kernel), the integral
of its deviation through the child's sampler (:func:`render.interpreter.correction`).

The phases below are templates that :mod:`render.interpreter` compiles with ``dispatch``
bound (:func:`render.jit.instantiate`); registers: :mod:`render.df._workspace`.
"""

from __future__ import annotations

from render.df._workspace import (
    AL,
    CH,
    FR,
    FWI,
    FWO,
    KF,
    KON,
    KR,
    NO_KID,
    PDF,
    TMP,
    R,
    any_pos,
    set_dirs,
)
from render.program import BASE, FLAGS, FRAME, KID0, OP, TABLE

#: bound by render.interpreter: the generated dispatch (render.df._registry)
dispatch = None
#: bound by render.interpreter: the interpreter, whose passes a modifier calls back
walker = None


def prepare(code, kids, P, tables, row, ws, k, wo):
    """Modifier ``k`` at ``wo``: its cheap albedo, the factor at the mirror direction
    times the child's."""
    r = k * R
    ws[r + TMP], ws[r + TMP + 1], ws[r + TMP + 2] = -wo[0], -wo[1], wo[2]
    f0, f1, f2 = dispatch.scale(code[k, OP], P, row, code[k, BASE], code[k, FLAGS], wo,
                                ws[r + TMP:r + TMP + 3], tables, code[k, TABLE])
    c = kids[code[k, KID0]]
    a0 = a1 = a2 = 0.0
    if c != NO_KID:
        q = c * R + CH
        a0, a1, a2 = ws[q], ws[q + 1], ws[q + 2]
    ws[r + CH], ws[r + CH + 1], ws[r + CH + 2] = f0 * a0, f1 * a1, f2 * a2


def evaluate(code, kids, P, tables, row, ws, k, ko, wo, wi):
    """Modifier ``k`` at ``wi`` after its child: ``s(wo, wi) child`` with the child's
    pdf -> ``(v0, v1, v2, pdf)``; the factor and whether the child contributes in its
    registers.  An edf modifier is evaluated with ``wi = wo``."""
    f0, f1, f2 = dispatch.scale(code[k, OP], P, row, code[k, BASE], code[k, FLAGS], wo, wi,
                                tables, code[k, TABLE])
    o = ko + code[k, KID0] * KR
    ws[o + KF], ws[o + KF + 1], ws[o + KF + 2] = f0, f1, f2
    c = kids[code[k, KID0]]
    v0 = v1 = v2 = pdf = 0.0
    if c != NO_KID:
        q = c * R
        v0, v1, v2 = f0 * ws[q], f1 * ws[q + 1], f2 * ws[q + 2]
        if any_pos(v0, v1, v2):
            pdf = ws[q + PDF]
    ws[o + KON] = 1.0 if pdf > 0.0 else 0.0
    return v0, v1, v2, pdf


def settle(code, ws, k, ko, j):
    """A delta sample through the child: ``(1, factor)``."""
    o = ko + j * KR
    return 1.0, ws[o + KF], ws[o + KF + 1], ws[o + KF + 2]


def varies(code, P, tables, row, k):
    """Whether the factor depends on ``wi`` (then the albedo needs the quadrature): a
    directional bsdf modifier whose curve is not flat."""
    op = code[k, OP]
    if not dispatch.DIRECTIONAL[op] or dispatch.EDF[op]:
        return False
    return not dispatch.curve_constant(op, P, row, code[k, BASE], code[k, FLAGS], tables,
                                       code[k, TABLE])


def factor_at(code, kids, frames, P, tables, row, ws, k, f0, f1, x, y, z):
    """Modifier ``k``'s factor at ``wi = (x, y, z)`` (frame ``f0``), after the
    interpreter's prepare at ``wo``."""
    fo = code.shape[0] * R + kids.shape[0] * KR
    set_dirs(frames, ws, fo, f0, f1, FWI, x, y, z)
    fr = fo + code[k, FRAME] * FR
    return dispatch.scale(code[k, OP], P, row, code[k, BASE], code[k, FLAGS],
                          ws[fr + FWO:fr + FWO + 3], ws[fr + FWI:fr + FWI + 3], tables,
                          code[k, TABLE])


def albedo(code, kids, frames, P, tables, row, ws, k, f0, f1, points, ox, oy, oz, wo):
    """Modifier ``k``'s directional albedo from its child's (``AL``): the factor at the
    mirror direction times it, corrected where the factor varies (but not for a mirror
    child, which sees only that direction); never below 0."""
    r = k * R
    c = kids[code[k, KID0]]
    if c == NO_KID:
        return 0.0, 0.0, 0.0
    ws[r + TMP], ws[r + TMP + 1], ws[r + TMP + 2] = -wo[0], -wo[1], wo[2]
    e0, e1, e2 = dispatch.scale(code[k, OP], P, row, code[k, BASE], code[k, FLAGS], wo,
                                ws[r + TMP:r + TMP + 3], tables, code[k, TABLE])
    q = c * R + AL
    a0, a1, a2 = e0 * ws[q], e1 * ws[q + 1], e2 * ws[q + 2]
    if walker.modifier_varies(code, P, tables, row, k) and not walker.is_mirror(code, c):
        d0, d1, d2 = walker.correction(code, kids, frames, P, tables, row, ws, k, c, 0, e0,
                                       e1, e2, f0, f1, ox, oy, oz, points)
        a0, a1, a2 = max(a0 + d0, 0.0), max(a1 + d1, 0.0), max(a2 + d2, 0.0)
    return a0, a1, a2
