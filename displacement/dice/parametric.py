"""Dicing a parametric (uv) surface: a knot-aligned, adaptively spaced tensor-product grid.

The grid is one set of u lines times one set of v lines over the whole uv domain, so
every edge is shared by construction (crack-free without stitching), the field's knots
are grid lines exactly, and seams and poles weld by copying positions.  The lines are
chosen by three passes:

1. a pilot grid measures how long each part of the domain is on screen;
2. :mod:`displacement.dice.select` samples each direction every ``dicing_rate`` pixels
   and keeps only the lines needed for the 1-D interpolation error along the other
   direction's pilot lines to stay within the tolerance (split between u and v when both
   are curved, given wholly to one when the other is flat);
3. a 2-D check measures the error at every cell's edge midpoints, centre (choosing the
   diagonal that fits better) and triangle centroids, and halves the offending u or v
   intervals until every test point is within tolerance or the cell is already at the
   dicing rate.
"""

from __future__ import annotations

import warnings

import numpy as np

from displacement.dice.evaluator import DICE_TOL, DisplacedSurface
from displacement.dice.mesh import DicedMesh, DicingCapWarning
from displacement.dice.select import dense_candidates, segment_lengths_px, select_lines

__all__ = ["dice_parametric", "grid_uv"]

_PILOT = 64            # pilot intervals per direction (plus the knots)
_MAX_DENSE = 16384     # dense candidates per direction
_MAX_CROSS = 160       # cross lines sampled by the 1-D selection
_MAX_ROUNDS = 10       # 2-D refinement rounds
_SHARE = 0.7           # tolerance share of each direction when both are curved


def grid_uv(u: np.ndarray, v: np.ndarray) -> np.ndarray:
    """All (u, v) pairs of a tensor grid, v-major: row j, column i at ``j * len(u) + i``.

    Parameters
    ----------
    u : (nu,) float64
    v : (nv,) float64

    Returns
    -------
    (nv * nu, 2) float64

    Examples
    --------
    >>> grid_uv(np.array([0.0, 1.0]), np.array([0.0, 0.5])).tolist()
    [[0.0, 0.0], [1.0, 0.0], [0.0, 0.5], [1.0, 0.5]]
    """
    uu, vv = np.meshgrid(u, v)
    return np.stack([uu.ravel(), vv.ravel()], axis=1)


def _eval_grid(ds: DisplacedSurface, u: np.ndarray, v: np.ndarray) -> np.ndarray:
    return ds.eval_uv(grid_uv(u, v)).reshape(len(v), len(u), 3)


def _knots(values, periodic: bool) -> np.ndarray:
    """Crease lines in [0, 1] (sorted, unique), always with the domain ends."""
    k = np.asarray([] if values is None else values, dtype=np.float64).reshape(-1)
    k = k[np.isfinite(k)]
    if periodic:
        k = np.where((k < 0.0) | (k > 1.0), k - np.floor(k), k)
    k = k[(k >= 0.0) & (k <= 1.0)]
    return np.unique(np.concatenate([[0.0, 1.0], k]))


# --------------------------------------------------------------------- lines
def _select(ds: DisplacedSurface, knots_u, knots_v, rate: float, tol: float):
    """Adaptive u and v lines (pilot, dense sampling, 1-D selection)."""
    pu = np.unique(np.concatenate([np.linspace(0.0, 1.0, _PILOT + 1), knots_u]))
    pv = np.unique(np.concatenate([np.linspace(0.0, 1.0, _PILOT + 1), knots_v]))
    w0 = _eval_grid(ds, pu, pv)                       # (nv, nu, 3)
    s0 = ds.px_scale(w0).reshape(w0.shape[:2])
    du, fu = dense_candidates(pu, segment_lengths_px(w0.transpose(1, 0, 2), s0.T), rate,
                              knots_u, _MAX_DENSE)
    dv, fv = dense_candidates(pv, segment_lengths_px(w0, s0), rate, knots_v, _MAX_DENSE)
    cross_u = pu if len(pu) <= _MAX_CROSS else np.unique(np.concatenate(
        [pu[np.linspace(0, len(pu) - 1, _MAX_CROSS).round().astype(int)], knots_u]))
    cross_v = pv if len(pv) <= _MAX_CROSS else np.unique(np.concatenate(
        [pv[np.linspace(0, len(pv) - 1, _MAX_CROSS).round().astype(int)], knots_v]))
    wv = _eval_grid(ds, cross_u, dv)                  # (mv, ku, 3): lines of constant v
    sv = ds.px_scale(wv).reshape(wv.shape[:2])
    wu = _eval_grid(ds, du, cross_v).transpose(1, 0, 2)  # (mu, kv, 3)
    su = ds.px_scale(wu).reshape(wu.shape[:2])

    # share the tolerance: a direction that needs no lines beyond its knots leaves the
    # rest of the budget to the other; two curved directions get _SHARE each (their
    # errors rarely peak at the same point; the 2-D check below catches where they do)
    keep_u, err_u, split_u = select_lines(du, fu, wu, su, _SHARE * tol)
    keep_v, err_v, split_v = select_lines(dv, fv, wv, sv,
                                          _SHARE * tol if split_u else tol - err_u)
    if split_u and not split_v:
        keep_u, _, _ = select_lines(du, fu, wu, su, tol - err_v)
    return du[keep_u], dv[keep_v]


# ------------------------------------------------------------- welding grid
def _weld_grid(w: np.ndarray, periodic_u: bool, periodic_v: bool):
    """Copy seam columns/rows and collapse poles in place; return pole flags."""
    if periodic_u:
        w[:, -1] = w[:, 0]
    if periodic_v:
        w[-1, :] = w[0, :]
    extent = float(np.ptp(w.reshape(-1, 3), axis=0).max()) if w.size else 0.0
    eps = DICE_TOL.pole_rel * max(extent, 1e-300)
    # a pole is a line whose points (not counting a seam copy) all coincide
    rows = w[:, :-1] if periodic_u else w
    cols = w[:-1] if periodic_v else w
    pole_rows = np.zeros(w.shape[0], bool)
    pole_cols = np.zeros(w.shape[1], bool)
    if rows.shape[1] >= 2:
        pole_rows = np.linalg.norm(rows - rows.mean(axis=1, keepdims=True),
                                   axis=2).max(axis=1) <= eps
        w[pole_rows] = rows[pole_rows].mean(axis=1, keepdims=True)
    if cols.shape[0] >= 2:
        pole_cols = np.linalg.norm(cols - cols.mean(axis=0, keepdims=True),
                                   axis=2).max(axis=0) <= eps
        w[:, pole_cols] = cols[:, pole_cols].mean(axis=0, keepdims=True)
    return pole_rows, pole_cols


# --------------------------------------------------------------- 2-D check
def _cell_errors(ds: DisplacedSurface, u, v, w, poles: bool = True):
    """Screen errors of every grid cell at its edge midpoints, centre and centroids.

    Returns
    -------
    cell_err : (nv-1, nu-1)   largest error of the cell's test points
    e_u, e_v : (nv-1, nu-1)   largest error at the cell's u-edge / v-edge midpoints
    diag : (nv-1, nu-1) bool  True: split along (u1, v0)-(u0, v1), else (u0, v0)-(u1, v1)
    len_u, len_v : (nv-1, nu-1)  longest u / v edge of the cell on screen (pixels)
    all_errors : (k,)         every tested error (for statistics)
    """
    um, vm = 0.5 * (u[:-1] + u[1:]), 0.5 * (v[:-1] + v[1:])
    s = ds.px_scale(w).reshape(w.shape[:2])
    w00, w10, w01, w11 = w[:-1, :-1], w[:-1, 1:], w[1:, :-1], w[1:, 1:]

    def err(true, approx):
        d = true - approx
        scale = ds.px_scale(true).reshape(true.shape[:-1])
        return np.sqrt(np.einsum("...k,...k->...", d, d)) * scale

    pu_true = _eval_grid(ds, um, v)                   # u-edge midpoints (nv, nu-1)
    e_uedge = err(pu_true, 0.5 * (w[:, :-1] + w[:, 1:]))
    pv_true = _eval_grid(ds, u, vm)                   # v-edge midpoints (nv-1, nu)
    e_vedge = err(pv_true, 0.5 * (w[:-1] + w[1:]))
    centre = _eval_grid(ds, um, vm)
    e_d0 = err(centre, 0.5 * (w00 + w11))
    e_d1 = err(centre, 0.5 * (w10 + w01))
    diag = e_d1 < e_d0
    # triangle centroids for the chosen diagonal
    u0, u1 = u[None, :-1], u[None, 1:]
    v0, v1 = v[:-1, None], v[1:, None]
    shape = diag.shape
    ua = np.where(diag, (2 * u0 + u1) / 3, (u0 + 2 * u1) / 3)
    va = np.where(diag, (2 * v0 + v1) / 3, (2 * v0 + v1) / 3)
    ub = np.where(diag, (u0 + 2 * u1) / 3, (2 * u0 + u1) / 3)
    vb = np.where(diag, (v0 + 2 * v1) / 3, (v0 + 2 * v1) / 3)
    uv = np.concatenate([np.stack([ua.ravel(), va.ravel()], 1),
                         np.stack([ub.ravel(), vb.ravel()], 1)])
    cen = ds.eval_uv(uv).reshape(2, *shape, 3)
    d = diag[..., None]
    tri_a = np.where(d, (w00 + w10 + w01) / 3, (w00 + w10 + w11) / 3)
    tri_b = np.where(d, (w10 + w11 + w01) / 3, (w00 + w11 + w01) / 3)
    e_ca, e_cb = err(cen[0], tri_a), err(cen[1], tri_b)
    # triangles that collapse at a pole are dropped from the mesh: not measured
    if poles:
        same = lambda a, b: np.all(a == b, axis=-1)  # noqa: E731
        deg_a = np.where(diag, same(w00, w10) | same(w00, w01) | same(w10, w01),
                         same(w00, w10) | same(w10, w11) | same(w00, w11))
        deg_b = np.where(diag, same(w10, w11) | same(w11, w01) | same(w10, w01),
                         same(w00, w11) | same(w11, w01) | same(w00, w01))
        e_ca = np.where(deg_a, 0.0, e_ca)
        e_cb = np.where(deg_b, 0.0, e_cb)
    else:
        deg_a = deg_b = np.zeros(diag.shape, bool)
    e_c = np.minimum(e_d0, e_d1)
    e_u = np.maximum(e_uedge[:-1], e_uedge[1:])
    e_v = np.maximum(e_vedge[:, :-1], e_vedge[:, 1:])
    cell_err = np.maximum.reduce([e_u, e_v, e_c, e_ca, e_cb])
    len_u = np.maximum(np.linalg.norm(w10 - w00, axis=-1) * np.maximum(s[:-1, :-1], s[:-1, 1:]),
                       np.linalg.norm(w11 - w01, axis=-1) * np.maximum(s[1:, :-1], s[1:, 1:]))
    len_v = np.maximum(np.linalg.norm(w01 - w00, axis=-1) * np.maximum(s[:-1, :-1], s[1:, :-1]),
                       np.linalg.norm(w11 - w10, axis=-1) * np.maximum(s[:-1, 1:], s[1:, 1:]))
    all_errors = np.concatenate([e_uedge.ravel(), e_vedge.ravel(), e_c.ravel(),
                                 e_ca[~deg_a], e_cb[~deg_b]])
    return cell_err, e_u, e_v, diag, len_u, len_v, all_errors


def _tri_count(u, v) -> int:
    return 2 * (len(u) - 1) * (len(v) - 1)


def _fit_cap(u, v, fixed_u, fixed_v, cap):
    """Drop lines (non-fixed first, every other one) until the grid fits the cap."""
    while _tri_count(u, v) > cap:
        axis_u = len(u) >= len(v)
        lines, fixed = (u, fixed_u) if axis_u else (v, fixed_v)
        if len(lines) <= 2:
            axis_u = not axis_u
            lines, fixed = (u, fixed_u) if axis_u else (v, fixed_v)
            if len(lines) <= 2:
                break
        free = np.flatnonzero(~np.isin(lines, fixed))
        if len(free):
            drop = free[::2]
        else:  # only knots left: give up knot alignment, keep the ends
            drop = np.arange(1, len(lines) - 1)[::2]
        lines = np.delete(lines, drop)
        if axis_u:
            u = lines
        else:
            v = lines
    return u, v


# --------------------------------------------------------------------- mesh
def _copies(lines: np.ndarray, knots: np.ndarray):
    """Duplicate lines at knots so each band between knots has its own copies.

    Returns line index per copy (c,), finite-difference direction per copy (+1 into the
    band above, -1 for a band's last line), and whether copy c and c+1 bound a cell.
    """
    kidx = np.flatnonzero(np.isin(lines, knots))
    if kidx[0] != 0:
        kidx = np.concatenate([[0], kidx])
    if kidx[-1] != len(lines) - 1:
        kidx = np.concatenate([kidx, [len(lines) - 1]])
    a, b = kidx[:-1], kidx[1:]
    n = b - a + 1
    band = np.repeat(np.arange(len(a)), n)
    line = a[band] + (np.arange(n.sum()) - np.repeat(np.cumsum(n) - n, n))
    fd = np.ones(len(line), dtype=np.int64)
    fd[np.cumsum(n) - 1] = -1
    cell = band[:-1] == band[1:]
    return line, fd, cell


def _fd_uv(lines: np.ndarray, line: np.ndarray, fd: np.ndarray) -> np.ndarray:
    """Signed finite-difference step per copy (towards the neighbour inside its band)."""
    nb = np.clip(line + fd, 0, len(lines) - 1)
    gap = np.abs(lines[nb] - lines[line])
    gap = np.where(gap > 0, gap, 1.0)
    return fd * np.minimum(DICE_TOL.fd_step, 0.25 * gap)


def _build_mesh(ds: DisplacedSurface, u, v, w, diag, knots_u, knots_v, periodic_u,
                periodic_v, pole_rows, pole_cols, seam_crease_u, seam_crease_v):
    cu, fdu, cellu = _copies(u, knots_u)
    cv, fdv, cellv = _copies(v, knots_v)
    nc, nr = len(cu), len(cv)
    # vertex (r, c) is number r * nc + c
    rr, cc = np.meshgrid(np.arange(nr), np.arange(nc), indexing="ij")
    li, lj = cu[cc].ravel(), cv[rr].ravel()              # line index in u, in v
    pos = w[lj, li]
    uv = np.stack([u[li], v[lj]], axis=1)

    # shading normals from one-sided differences inside each band
    hu = _fd_uv(u, cu, fdu)[cc].ravel()
    hv = _fd_uv(v, cv, fdv)[rr].ravel()
    p_u = ds.eval_uv(np.stack([uv[:, 0] + hu, uv[:, 1]], 1))
    p_v = ds.eval_uv(np.stack([uv[:, 0], uv[:, 1] + hv], 1))
    # the grid positions are the true ones except where seams and poles were welded
    p_c = pos.copy()
    redo = np.zeros(len(pos), bool)
    if periodic_u:
        redo |= li == len(u) - 1
    if periodic_v:
        redo |= lj == len(v) - 1
    redo |= pole_rows[lj] | pole_cols[li]
    if redo.any():
        p_c[redo] = ds.eval_uv(uv[redo])
    # orientation: faces counter-clockwise in uv face along dP/du x dP/dv; flip them if
    # the base normal points the other way (left-handed charts) or the transform mirrors
    probe = np.linspace(0, len(uv) - 1, min(len(uv), 257)).astype(np.int64)
    st = ds.surface.state_at_uv(uv[probe])
    handed = np.einsum("ij,ij->i", np.cross(st.tangent_u, st.tangent_v), st.normal)
    orient = -1.0 if (np.sum(handed) < 0) != ds.flips else 1.0
    dpdu = ((p_u - p_c) / hu[:, None]).reshape(nr, nc, 3)
    dpdv = ((p_v - p_c) / hv[:, None]).reshape(nr, nc, 3)
    if periodic_u and not seam_crease_u and nc > 1:   # smooth across the seam
        avg = 0.5 * (dpdu[:, 0] + dpdu[:, -1])
        dpdu[:, 0] = dpdu[:, -1] = avg
    if periodic_v and not seam_crease_v and nr > 1:
        avg = 0.5 * (dpdv[0] + dpdv[-1])
        dpdv[0] = dpdv[-1] = avg
    dpdu, dpdv = dpdu.reshape(-1, 3), dpdv.reshape(-1, 3)
    extent = max(float(np.ptp(pos, axis=0).max()), 1e-300)
    normal = np.cross(dpdu, dpdv)
    normal *= orient
    length = np.sqrt(np.einsum("ij,ij->i", normal, normal))
    bad = length <= DICE_TOL.degenerate_normal * extent ** 2
    normal /= np.where(bad, 1.0, length)[:, None]
    if bad.any():       # degenerate parametrization: the base surface's normal
        sb = ds.surface.state_at_uv(uv[bad])
        bn = (ds.normal_matrix @ sb.normal.T).T
        normal[bad] = bn / np.maximum(np.linalg.norm(bn, axis=1, keepdims=True), 1e-300)

    # poles: one normal, the mean of the normals just off the pole
    for axis, poles in ((0, pole_rows), (1, pole_cols)):
        for line_idx in np.flatnonzero(poles):
            sel = (lj == line_idx) if axis == 0 else (li == line_idx)
            if not sel.any():
                continue
            q = uv[sel].copy()
            lines = v if axis == 0 else u
            step = 1.0 if line_idx == 0 else -1.0
            other = lines[min(max(line_idx + int(step), 0), len(lines) - 1)]
            delta = step * min(1e-3, 0.25 * abs(other - lines[line_idx]) or 1e-3)
            q[:, 1 - axis] += delta
            e = DICE_TOL.fd_step * step
            q0 = ds.eval_uv(q)
            qa = ds.eval_uv(q + [abs(e), 0.0] if axis == 0 else q + [0.0, e])
            qb = ds.eval_uv(q + [0.0, e] if axis == 0 else q + [abs(e), 0.0])
            if axis == 0:
                n = orient * np.cross((qa - q0) / abs(e), (qb - q0) / e)
            else:
                n = orient * np.cross((qb - q0) / abs(e), (qa - q0) / e)
            n /= np.maximum(np.linalg.norm(n, axis=1, keepdims=True), 1e-300)
            mean = n.mean(axis=0)
            if np.linalg.norm(mean) > 1e-12:
                normal[sel] = mean / np.linalg.norm(mean)

    tangent = dpdu - normal * np.einsum("ij,ij->i", dpdu, normal)[:, None]
    length = np.sqrt(np.einsum("ij,ij->i", tangent, tangent))
    bad = length <= DICE_TOL.degenerate_normal * extent
    tangent /= np.where(bad, 1.0, length)[:, None]
    if bad.any():       # no u direction (poles): the base tangent, else any perpendicular
        nb = normal[bad]
        bt = (ds.linear @ ds.surface.state_at_uv(uv[bad]).tangent_u.T).T
        bt -= nb * np.einsum("ij,ij->i", bt, nb)[:, None]
        bl = np.linalg.norm(bt, axis=1, keepdims=True)
        tangent[bad] = np.where(bl > 1e-12 * extent, bt / np.maximum(bl, 1e-300),
                                _any_perpendicular(nb))

    # weld keys: seams identify the last line with the first, poles collapse a line
    nu, nv = len(u), len(v)
    ku = np.where(periodic_u & (li == nu - 1), 0, li)
    kv = np.where(periodic_v & (lj == nv - 1), 0, lj)
    ku = np.where(pole_rows[lj], 0, ku)
    kv = np.where(pole_cols[li], 0, kv)
    _, weld = np.unique(kv * nu + ku, return_inverse=True)

    # two triangles per cell, with the diagonal the error test chose
    r0 = np.flatnonzero(cellv)
    c0 = np.flatnonzero(cellu)
    R, C = np.meshgrid(r0, c0, indexing="ij")
    R, C = R.ravel(), C.ravel()
    v00, v10 = R * nc + C, R * nc + C + 1
    v01, v11 = (R + 1) * nc + C, (R + 1) * nc + C + 1
    dg = diag[cv[R], cu[C]]
    ta = np.where(dg[:, None], np.stack([v00, v10, v01], 1), np.stack([v00, v10, v11], 1))
    tb = np.where(dg[:, None], np.stack([v10, v11, v01], 1), np.stack([v00, v11, v01], 1))
    faces = np.concatenate([ta, tb])
    if orient < 0:
        faces = faces[:, [0, 2, 1]]
    wf = weld[faces]
    good = (wf[:, 0] != wf[:, 1]) & (wf[:, 1] != wf[:, 2]) & (wf[:, 0] != wf[:, 2])
    faces = faces[good]
    new_index = np.where(good, np.cumsum(good) - 1, -1)
    cell_faces = np.full((len(v) - 1, len(u) - 1, 2), -1, dtype=np.int64)
    cell_faces[cv[R], cu[C], 0] = new_index[: len(R)]
    cell_faces[cv[R], cu[C], 1] = new_index[len(R):]

    # keep only referenced vertices
    used = np.zeros(len(pos), bool)
    used[faces.ravel()] = True
    remap = np.cumsum(used) - 1
    faces = remap[faces]
    _, weld = np.unique(weld[used], return_inverse=True)
    return DicedMesh(vertices=pos[used], faces=faces.astype(np.int64), uv=uv[used],
                     normals=normal[used], tangents=tangent[used],
                     weld=weld.astype(np.int64), grid=(u.copy(), v.copy(), cell_faces))


def _any_perpendicular(n: np.ndarray) -> np.ndarray:
    a = np.where(np.abs(n[:, :1]) < 0.9, [[1.0, 0.0, 0.0]], [[0.0, 1.0, 0.0]])
    t = np.cross(n, a)
    return t / np.maximum(np.linalg.norm(t, axis=1, keepdims=True), 1e-300)


# ------------------------------------------------------------------- driver
def dice_parametric(ds: DisplacedSurface, knots, periodic_u: bool, periodic_v: bool,
                    max_triangles: int, uniform=None, coarse: bool = False) -> DicedMesh:
    """Dice a parametric surface (see :func:`displacement.dice.dice`).

    Parameters
    ----------
    ds : DisplacedSurface
    knots : (knots_u or None, knots_v or None)
    periodic_u, periodic_v : bool
    max_triangles : int
    uniform : None or (nu, nv)
        Intervals of a uniform grid (no adaptivity, no knot insertion).
    coarse : bool
        Not displaced: choose lines from the pilot grid only (no dicing-rate sampling,
        no refinement), enough for the base surface within tolerance.
    """
    field_knots_u = np.asarray([] if knots[0] is None else knots[0], dtype=np.float64)
    field_knots_v = np.asarray([] if knots[1] is None else knots[1], dtype=np.float64)
    knots_u = _knots(field_knots_u, periodic_u)
    knots_v = _knots(field_knots_v, periodic_v)
    seam_u = bool(np.any((field_knots_u == 0.0) | (field_knots_u == 1.0)))
    seam_v = bool(np.any((field_knots_v == 0.0) | (field_knots_v == 1.0)))
    tol, rate = ds.tolerance, ds.dicing_rate
    cap_reached = False
    rounds = 0
    if uniform is not None:
        u = np.linspace(0.0, 1.0, uniform[0] + 1)
        v = np.linspace(0.0, 1.0, uniform[1] + 1)
        if _tri_count(u, v) > max_triangles:
            cap_reached = True
            u, v = _fit_cap(u, v, u[[0, -1]], v[[0, -1]], max_triangles)
        w = _eval_grid(ds, u, v)
        poles = _weld_grid(w, periodic_u, periodic_v)
        diag = np.zeros((len(v) - 1, len(u) - 1), bool)   # one diagonal, no error tests
        errors = None
    else:
        scale = 1.0
        for _attempt in range(8):
            if coarse:
                u, v = _select_coarse(ds, knots_u, knots_v, tol * scale)
            else:
                u, v = _select(ds, knots_u, knots_v, rate * scale, tol * scale)
            over = False
            rounds = 0
            while True:
                if _tri_count(u, v) > max_triangles:
                    over = True
                    break
                w = _eval_grid(ds, u, v)
                poles = _weld_grid(w, periodic_u, periodic_v)
                cell_err, e_u, e_v, diag, len_u, len_v, errors = _cell_errors(
                    ds, u, v, w, poles[0].any() or poles[1].any())
                rounds += 1
                fail = cell_err > tol * scale
                if coarse or rounds >= _MAX_ROUNDS or not fail.any():
                    break
                half = 0.5 * tol * scale
                neither = fail & (e_u <= half) & (e_v <= half)
                split_u = (fail & (e_u > half)) | (neither & (len_u >= len_v))
                split_v = (fail & (e_v > half)) | (neither & (len_v > len_u))
                split_u &= len_u > rate * scale
                split_v &= len_v > rate * scale
                need_u, need_v = split_u.any(axis=0), split_v.any(axis=1)
                if not (need_u.any() or need_v.any()):
                    break
                u = np.sort(np.concatenate([u, 0.5 * (u[:-1] + u[1:])[need_u]]))
                v = np.sort(np.concatenate([v, 0.5 * (v[:-1] + v[1:])[need_v]]))
            if not over:
                break
            cap_reached = True
            scale *= max(2.0, _tri_count(u, v) / max_triangles)
        else:
            u, v = _fit_cap(u, v, knots_u, knots_v, max_triangles)
            w = _eval_grid(ds, u, v)
            poles = _weld_grid(w, periodic_u, periodic_v)
            cell_err, *_, diag, _, _, errors = _cell_errors(
                ds, u, v, w, poles[0].any() or poles[1].any())
    if cap_reached:
        warnings.warn(f"dice: the cap of {max_triangles} triangles was reached; the surface "
                      f"was diced coarser than dicing_rate={rate} px / tolerance={tol} px "
                      f"({_tri_count(u, v)} triangles)", DicingCapWarning, stacklevel=3)
    mesh = _build_mesh(ds, u, v, w, diag, knots_u, knots_v, periodic_u, periodic_v,
                       poles[0], poles[1], seam_u, seam_v)
    stats = dict(mesh.stats)
    stats.update(lines_u=len(u), lines_v=len(v), rounds=rounds, cap_reached=cap_reached,
                 max_error_px=None if errors is None else float(errors.max(initial=0.0)),
                 mean_error_px=None if errors is None else (float(errors.mean())
                                                            if errors.size else 0.0),
                 method="uniform" if uniform is not None else ("coarse" if coarse
                                                               else "adaptive"))
    object.__setattr__(mesh, "stats", stats)
    return mesh


def _select_coarse(ds, knots_u, knots_v, tol):
    """Lines for an undisplaced surface: a subset of the pilot grid within tolerance."""
    n = 32
    pu = np.unique(np.concatenate([np.linspace(0.0, 1.0, n + 1), knots_u]))
    pv = np.unique(np.concatenate([np.linspace(0.0, 1.0, n + 1), knots_v]))
    w = _eval_grid(ds, pu, pv)
    s = ds.px_scale(w).reshape(w.shape[:2])
    keep_u, _, _ = select_lines(pu, np.isin(pu, knots_u), w.transpose(1, 0, 2), s.T, 0.5 * tol)
    keep_v, _, _ = select_lines(pv, np.isin(pv, knots_v), w, s, 0.5 * tol)
    return pu[keep_u], pv[keep_v]
