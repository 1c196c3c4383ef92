"""Dicing a mesh surface: each base triangle is split into a barycentric grid.

Crack-free by edge-based levels (Reyes / Cycles): every base edge gets one power-of-two
level from its own samples (displaced through one canonical face, in a canonical
direction), so both neighbours agree; a face is diced at the largest level its edges and
its interior need, and the grid points on an edge whose level is lower are snapped onto
that edge's points (the triangles this collapses are dropped).  Base vertices are welded
by position, so charts that merely touch (a cube's six faces) share their edges too, and
every shared point is displaced once: positions are identical by construction.
"""

from __future__ import annotations

import warnings

import numpy as np

from displacement.dice.evaluator import DICE_TOL, DisplacedSurface
from displacement.dice.mesh import DicedMesh, DicingCapWarning

__all__ = ["dice_triangles"]

_MAX_LEVEL_LOG2 = 10      # at most 1024 segments per base edge
_PILOT = 8                # pilot segments per edge


def _tri_grid(n: int):
    """Barycentric grid of a triangle at level n: points (i, j) and sub-triangles."""
    i, j = np.meshgrid(np.arange(n + 1), np.arange(n + 1), indexing="ij")
    keep = i + j <= n
    i, j = i[keep], j[keep]
    index = -np.ones((n + 1, n + 1), dtype=np.int64)
    index[i, j] = np.arange(len(i))
    ii, jj = np.meshgrid(np.arange(n), np.arange(n), indexing="ij")
    up = ii + jj <= n - 1
    a, b = ii[up], jj[up]
    tris = [np.stack([index[a, b], index[a + 1, b], index[a, b + 1]], 1)]
    down = ii + jj <= n - 2
    a, b = ii[down], jj[down]
    tris.append(np.stack([index[a + 1, b], index[a + 1, b + 1], index[a, b + 1]], 1))
    return i, j, np.concatenate(tris)


def _edge_structure(vertices: np.ndarray, faces: np.ndarray):
    """Welded vertex ids, unique edges, and each face edge's edge id and direction."""
    _, vid = np.unique(vertices, axis=0, return_inverse=True)
    vid = vid.reshape(-1)
    fv = vid[faces]                                           # (m, 3)
    # face edge k goes from corner k to corner (k + 1) % 3
    a = fv
    b = np.roll(fv, -1, axis=1)
    lo, hi = np.minimum(a, b), np.maximum(a, b)
    key = lo.astype(np.int64) * (vid.max() + 1) + hi
    edges, edge_id = np.unique(key.ravel(), return_inverse=True)
    edge_id = edge_id.reshape(-1, 3)
    forward = a < b                                           # face edge runs lo -> hi
    # canonical (face, local edge) of every edge: its first occurrence
    first = np.full(len(edges), -1, dtype=np.int64)
    flat = edge_id.ravel()
    order = np.arange(len(flat))[::-1]
    first[flat[order]] = order
    return vid, edge_id, forward, first // 3, first % 3


def _edge_bary(local: np.ndarray, t: np.ndarray, forward: np.ndarray) -> np.ndarray:
    """Barycentric coordinates of the point at canonical parameter t on face edge
    ``local`` (corner local -> corner local+1, reversed if not ``forward``)."""
    s = np.where(forward, t, 1.0 - t)
    bary = np.zeros((len(t), 3))
    rows = np.arange(len(t))
    bary[rows, local] = 1.0 - s
    bary[rows, (local + 1) % 3] = s
    return bary


def _levels_from_samples(world, scale, counts, tol):
    """Smallest power-of-two level per ragged sample run whose interpolation is within tol.

    ``world`` (sum(counts + 1), 3) are points at t = k / counts (k = 0..counts) per run.
    """
    runs = len(counts)
    start = np.concatenate([[0], np.cumsum(counts + 1)[:-1]])
    level = np.ones(runs, dtype=np.int64)
    done = np.zeros(runs, bool)
    run_of = np.repeat(np.arange(runs), counts + 1)
    k = np.arange(len(run_of)) - start[run_of]
    while True:
        n = level[run_of]
        step = np.maximum(counts[run_of] // n, 1)
        seg = np.minimum(k // step, n - 1)
        t = (k - seg * step) / step
        a = world[start[run_of] + seg * step]
        b = world[start[run_of] + np.minimum((seg + 1) * step, counts[run_of])]
        d = a + t[:, None] * (b - a) - world
        err = np.sqrt(np.einsum("ij,ij->i", d, d)) * scale
        emax = np.zeros(runs)
        np.maximum.at(emax, run_of, err)
        done |= (emax <= tol) | (level >= counts)
        if done.all():
            return level
        level = np.where(done, level, level * 2)


def dice_triangles(ds: DisplacedSurface, max_triangles: int, uniform=None,
                   coarse: bool = False) -> DicedMesh:
    """Dice a mesh surface (see :func:`displacement.dice.dice`)."""
    base = ds.surface.base_mesh()
    vertices = np.asarray(base.vertices, dtype=np.float64)
    faces = np.asarray(base.faces, dtype=np.int64)
    m = len(faces)
    vid, edge_id, forward, canon_face, canon_local = _edge_structure(vertices, faces)
    n_edges = len(canon_face)
    tol, rate = ds.tolerance, ds.dicing_rate
    cap_reached = False

    def edge_world(counts):
        """Displaced points k / counts along every edge (canonical face and direction)."""
        e = np.repeat(np.arange(n_edges), counts + 1)
        start = np.concatenate([[0], np.cumsum(counts + 1)[:-1]])
        t = (np.arange(len(e)) - start[e]) / counts[e]
        f = canon_face[e]
        bary = _edge_bary(canon_local[e], t, forward[f, canon_local[e]])
        return ds.eval_bary(f, bary)

    if coarse:
        edge_level = np.ones(n_edges, dtype=np.int64)
        face_level = np.ones(m, dtype=np.int64)
    elif uniform is not None:
        edge_level = np.full(n_edges, int(uniform[0]), dtype=np.int64)
        face_level = np.full(m, int(uniform[0]), dtype=np.int64)
    else:
        # dense samples every `rate` pixels (length from a pilot polyline), then levels
        pilot = np.full(n_edges, _PILOT, dtype=np.int64)
        pw = edge_world(pilot).reshape(n_edges, _PILOT + 1, 3)
        ps = ds.px_scale(pw.reshape(-1, 3)).reshape(n_edges, _PILOT + 1)
        length = (np.linalg.norm(np.diff(pw, axis=1), axis=2)
                  * np.maximum(ps[:, 1:], ps[:, :-1])).sum(axis=1)
        dense = np.ceil(np.maximum(length / rate, 1.0))
        dense = (2 ** np.clip(np.ceil(np.log2(dense)), 0, _MAX_LEVEL_LOG2)).astype(np.int64)
        dw = edge_world(dense)
        edge_level = _levels_from_samples(dw, ds.px_scale(dw), dense, tol)
        face_level = edge_level[edge_id].max(axis=1)
        # interior: double the face level while a sub-triangle centroid misses
        for _ in range(_MAX_LEVEL_LOG2):
            err = _face_centroid_errors(ds, face_level)
            grow = (err > tol) & (face_level < 2 ** _MAX_LEVEL_LOG2)
            if not grow.any():
                break
            face_level = np.where(grow, face_level * 2, face_level)
    # the cap: halve every level above 1 until the estimate fits
    while (face_level.astype(np.float64) ** 2).sum() > max_triangles:
        cap_reached = True
        if face_level.max() == 1:
            break
        face_level = np.maximum(face_level // 2, 1)
        edge_level = np.maximum(edge_level // 2, 1)
    if (face_level.astype(np.float64) ** 2).sum() > max_triangles:
        raise ValueError(f"dice: max_triangles={max_triangles} is below the base mesh's "
                         f"{m} triangles; raise it")
    if cap_reached:
        warnings.warn(f"dice: the cap of {max_triangles} triangles was reached; the mesh "
                      "was diced coarser than asked", DicingCapWarning, stacklevel=3)
    face_level = np.maximum(face_level, edge_level[edge_id].max(axis=1))
    mesh = _build(ds, faces, vid, edge_id, forward, canon_face, canon_local, edge_level,
                  face_level, cap_reached)
    if uniform is None and not coarse:
        # estimated error: the sub-triangle centroids of the final levels
        err = _face_centroid_errors(ds, face_level)
        mesh.stats.update(max_error_px=float(err.max()), mean_error_px=float(err.mean()))
    return mesh


def _face_centroid_errors(ds: DisplacedSurface, face_level: np.ndarray) -> np.ndarray:
    """Largest screen error at sub-triangle centroids of each face at its level."""
    err = np.zeros(len(face_level))
    for n in np.unique(face_level):
        fs = np.flatnonzero(face_level == n)
        i, j, tris = _tri_grid(int(n))
        bary_pts = np.stack([n - i - j, i, j], 1) / n               # (p, 3)
        cen = bary_pts[tris].mean(axis=1)                           # (t, 3)
        f_pts = np.repeat(fs, len(bary_pts))
        f_cen = np.repeat(fs, len(cen))
        wp = ds.eval_bary(f_pts, np.tile(bary_pts, (len(fs), 1))).reshape(len(fs), -1, 3)
        wc = ds.eval_bary(f_cen, np.tile(cen, (len(fs), 1))).reshape(len(fs), -1, 3)
        approx = wp[:, tris].mean(axis=2)
        d = (wc - approx).reshape(-1, 3)
        e = np.sqrt(np.einsum("ij,ij->i", d, d)) * ds.px_scale(wc.reshape(-1, 3))
        err[fs] = e.reshape(len(fs), -1).max(axis=1)
    return err


def _build(ds, faces, vid, edge_id, forward, canon_face, canon_local, edge_level,
           face_level, cap_reached) -> DicedMesh:
    n_vid = int(vid.max()) + 1
    n_edges = len(edge_level)
    # unique position ids: base vertices, then edge points, then face interiors
    edge_base = n_vid + np.concatenate([[0], np.cumsum(edge_level - 1)[:-1]])
    n_edge_pts = int((edge_level - 1).sum())
    chunks = []
    next_id = n_vid + n_edge_pts
    for n in np.unique(face_level):
        fs = np.flatnonzero(face_level == n)
        n = int(n)
        i, j, tris = _tri_grid(n)
        p = len(i)
        bary = np.stack([n - i - j, i, j], 1) / n                   # (p, 3) local
        # which edge (if any) each grid point lies on; edge k: corner k -> k+1
        # corners: (i, j) = (0, 0) -> c0, (n, 0) -> c1, (0, n) -> c2
        on0 = (j == 0) & (i > 0) & (i < n)        # c0 -> c1, t = i / n
        on1 = (i + j == n) & (i > 0) & (j > 0)    # c1 -> c2, t = j / n
        on2 = (i == 0) & (j > 0) & (j < n)        # c2 -> c0, t = (n - j) / n
        corner = np.full(p, -1)
        corner[(i == 0) & (j == 0)] = 0
        corner[(i == n) & (j == 0)] = 1
        corner[(i == 0) & (j == n)] = 2
        F = len(fs)
        ids = np.empty((F, p), dtype=np.int64)
        interior = ~(on0 | on1 | on2 | (corner >= 0))
        n_int = int(interior.sum())
        ids[:, interior] = next_id + np.arange(F * n_int).reshape(F, n_int)
        next_id += F * n_int
        for k in range(3):
            sel = corner == k
            ids[:, sel] = vid[faces[fs, k]][:, None]
        for k, on, t_local in ((0, on0, i / n), (1, on1, j / n), (2, on2, (n - j) / n)):
            if not on.any():
                continue
            e = edge_id[fs, k]                                     # (F,)
            fwd = forward[fs, k]
            t = t_local[on][None, :]
            t_can = np.where(fwd[:, None], t, 1.0 - t)              # canonical parameter
            ne = edge_level[e][:, None]
            ke = np.floor(t_can * ne + 0.5).astype(np.int64)        # snapped edge index
            lo_v = np.minimum(vid[faces[fs, k]], vid[faces[fs, (k + 1) % 3]])[:, None]
            hi_v = np.maximum(vid[faces[fs, k]], vid[faces[fs, (k + 1) % 3]])[:, None]
            mid = edge_base[e][:, None] + ke - 1
            ids[:, on] = np.where(ke <= 0, lo_v, np.where(ke >= ne, hi_v, mid))
        chunks.append((fs, n, bary, tris, ids))

    # positions: every id displaced once, through one face
    total = next_id
    pos = np.zeros((total, 3))
    # base vertices through their first face corner
    fc_face = np.repeat(np.arange(len(faces)), 3)
    fc_vid = vid[faces].ravel()
    first = np.full(n_vid, -1, dtype=np.int64)
    first[fc_vid[::-1]] = np.arange(len(fc_vid))[::-1]
    cb = np.zeros((n_vid, 3))
    cb[np.arange(n_vid), first % 3] = 1.0
    pos[:n_vid] = ds.eval_bary(fc_face[first], cb)
    # edge points through the canonical face
    if n_edge_pts:
        e = np.repeat(np.arange(n_edges), edge_level - 1)
        k = np.arange(n_edge_pts) - (edge_base[e] - n_vid) + 1
        f = canon_face[e]
        bary = _edge_bary(canon_local[e], k / edge_level[e], forward[f, canon_local[e]])
        pos[n_vid:n_vid + n_edge_pts] = ds.eval_bary(f, bary)

    # copies: one vertex per (face, grid point); interiors evaluated here
    out_pos, out_uv, out_n, out_t, out_faces, out_basen = [], [], [], [], [], []
    offset = 0
    for fs, _n, bary, tris, ids in chunks:
        F, p = ids.shape
        fidx = np.repeat(fs, p)
        b = np.tile(bary, (F, 1))
        interior_ids = ids >= n_vid + n_edge_pts
        world, st = ds.eval_bary(fidx, b, with_state=True)
        flat_ids = ids.ravel()
        intr = interior_ids.ravel()
        pos[flat_ids[intr]] = world[intr]
        h = DICE_TOL.fd_step
        d1 = np.zeros(3)
        d1[[0, 1]] = [-h, h]
        d2 = np.zeros(3)
        d2[[0, 2]] = [-h, h]
        p1 = ds.eval_bary(fidx, b + d1)
        p2 = ds.eval_bary(fidx, b + d2)
        nrm = np.cross(p1 - world, p2 - world)
        if ds.flips:
            nrm = -nrm
        bn = (ds.normal_matrix @ st.normal.T).T
        bn /= np.maximum(np.linalg.norm(bn, axis=1, keepdims=True), 1e-300)
        ln = np.linalg.norm(nrm, axis=1, keepdims=True)
        nrm = np.where(ln > 1e-30, nrm / np.maximum(ln, 1e-300), bn)
        tu = (ds.linear @ st.tangent_u.T).T
        out_pos.append(flat_ids)
        out_uv.append(st.uv)
        out_n.append(nrm)
        out_t.append(tu)
        out_basen.append(bn)
        ft = (tris[None, :, :] + (np.arange(F) * p)[:, None, None]).reshape(-1, 3)
        if ds.flips:
            ft = ft[:, [0, 2, 1]]
        out_faces.append(ft + offset)
        offset += F * p
    weld_ids = np.concatenate(out_pos)
    vertices = pos[weld_ids]
    uv = np.concatenate(out_uv)
    normals = np.concatenate(out_n)
    base_n = np.concatenate(out_basen)
    tangents = np.concatenate(out_t)
    faces_out = np.concatenate(out_faces)

    # smooth normals over copies of a point whose base normals agree (hard base edges,
    # e.g. a cube's, stay split)
    key = np.concatenate([weld_ids[:, None].astype(np.float64), np.round(base_n, 9)], axis=1)
    _, group = np.unique(key, axis=0, return_inverse=True)
    group = group.reshape(-1)
    summed = np.zeros((group.max() + 1, 3))
    np.add.at(summed, group, normals)
    sl = np.linalg.norm(summed, axis=1, keepdims=True)
    smooth = np.where(sl > 1e-12, summed / np.maximum(sl, 1e-300), 0.0)[group]
    normals = np.where(np.linalg.norm(smooth, axis=1, keepdims=True) > 0, smooth, normals)
    tangents -= normals * np.einsum("ij,ij->i", tangents, normals)[:, None]
    tl = np.linalg.norm(tangents, axis=1, keepdims=True)
    alt = np.cross(normals, np.where(np.abs(normals[:, :1]) < 0.9, [[1.0, 0, 0]], [[0, 1.0, 0]]))
    tangents = np.where(tl > 1e-12, tangents / np.maximum(tl, 1e-300),
                        alt / np.linalg.norm(alt, axis=1, keepdims=True))

    # drop triangles collapsed by snapping, keep referenced vertices
    wf = weld_ids[faces_out]
    good = (wf[:, 0] != wf[:, 1]) & (wf[:, 1] != wf[:, 2]) & (wf[:, 0] != wf[:, 2])
    faces_out = faces_out[good]
    used = np.zeros(len(vertices), bool)
    used[faces_out.ravel()] = True
    remap = np.cumsum(used) - 1
    _, weld = np.unique(weld_ids[used], return_inverse=True)
    return DicedMesh(vertices=vertices[used], faces=remap[faces_out].astype(np.int64),
                     uv=uv[used], normals=normals[used], tangents=tangents[used],
                     weld=weld.reshape(-1).astype(np.int64),
                     stats=dict(cap_reached=cap_reached, method="triangles",
                                base_triangles=len(faces), max_error_px=None,
                                mean_error_px=None,
                                face_levels=np.bincount(face_level).nonzero()[0].tolist()))
