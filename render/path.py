"""The path tracer's compiled core: every ray through Embree, every vertex in numba.

:func:`trace` is a megakernel: it carries each path lane of a chunk of samples from the
camera to its end in one compiled loop, with no Python in between.  Per segment: the
ray through Embree (``rtcIntersect1`` from :mod:`render.embree`), free-flight sampling
in the lane's medium (spectral MIS over a hero channel), the environment on escape, and
at a surface the cutout decision, emission (MIS against light sampling), alpha and
AOVs, next-event estimation (the light :func:`select_light` picks, and each delta light
when they are sampled at every vertex; each shadow ray traced at once by
:func:`_walk_shadow`, through cutouts and null interfaces, attenuated by every medium on
the way), the bsdf's sampled continuation, null crossings (index-matched or thin-walled
straight transmission: no vertex), the stack of closed objects the path is inside
(their media and IORs), and Russian roulette.  A scattering event in a medium is a
vertex with next-event estimation through the phase function and a phase-sampled
continuation.  Bsdfs are material programs run by :mod:`render.interpreter`; every
sample value is drawn where it is needed (:func:`render.sampler.sample_pair`).

A hit on a hair strand (:mod:`render.hair`, object flag ``HAIR``) is a vertex like a
surface's, in the fibre's frame (:func:`render.hair.hair_hit`: the tangent along the
strand, the tube's normal where the ray enters it) and shaded by the material's hair
bsdf, with next-event estimation and MIS as at a surface; lights are weighed for it as
for a point in a medium (the bsdf scatters all around).  A ray that meets a tube from
inside (leaving a fibre it scattered into) passes through the wall without a vertex,
path and shadow rays alike.

Where an object's material varies over the surface (textures, noise, bump, a varying
cutout or emission), a lane that hits it is *parked*: its state and hit are written to
the parked arrays (``lf`` floats, ``li`` integers, the column constants below; its
stack of closed objects in ``so``/``sior``) and the kernel moves on.  The integrator
shades the parked lanes with numpy (``material.shade``), hands the kernel a parameter
row, a shading frame, an opacity, an IOR and an emitted radiance per lane
("bindings"), and resumes them.  Shadow records park likewise (in ``sf``/``si``) at such
surfaces and where a light's emission varies, and :func:`resolve_shadows` finishes
them.  A scene of constant materials renders a chunk in one call.
"""

from __future__ import annotations

import math
from collections import namedtuple

import numpy as np

from render import embree, interpreter
from render import light_sampling as ls
from render.bsdf import Lobe
from render.camera import camera_ray
from render.df._kernel_common import frame_from_normal_tangent, unitize
from render.df._registry import registry
from render.hair import hair_hit
from render.jit import njit
from render.light_sampling import (
    EVERY_DELTA,
    L_KIND,
    L_PDF_AREA,
    environment_radiance,
    is_delta,
    next_delta,
    sample_light,
    select_light,
    selection_pdf,
)
from render.lights import INFINITE_DISTANCE
from render.program import BASE, OP, SIZE
from render.sampler import (
    CAMERA_PAIR,
    FIRST_SEGMENT_PAIR,
    HERO_PAIR,
    P_BSDF,
    P_CHOICE,
    P_CUTOUT,
    P_FLIGHT,
    P_LIGHT,
    PAIRS_PER_SEGMENT,
    SHADOW_PAIRS,
    pixel_hash,
    sample_pair,
)
from render.volume import (
    emitted,
    free_flight,
    stack_outside_ior,
    stack_pop,
    stack_push,
    transmittance,
)

__all__ = [
    "Tables",
    "trace",
    "resolve_shadows",
    "outside_ior",
    "sample_lights",
    "selection",
    "escaped",
]

#: a lane may pass through at most this many cutout or null surfaces in a row
MAX_CROSSINGS = 64
#: a transmission counts as straight through (a null event) within this 1 - cos
STRAIGHT_TOL = 1e-9
ONE_MINUS_EPS = float(np.nextafter(1.0, 0.0))
SPECULAR = int(Lobe.SPECULAR)
SPECULAR_TRANSMISSION = int(Lobe.SPECULAR_TRANSMISSION)

# parked lanes' columns (:func:`trace`): lf (float64)
ORG, D, BETA, R, PREV_PDF, SEG, SHIFT = 0, 3, 6, 9, 12, 13, 14
# the previous vertex's position, normal (0 in a medium) and total light importance: the
# light-selection probability of an emitter a bsdf-sampled path hits (MIS)
PREV_P, PREV_N, PREV_SUM = 15, 18, 21
HIT_T, HIT_B1, HIT_B2 = 22, 23, 24  # the pending hit
NF = 25
# li (int64): SEGMENT counts the path's segments (its sample pairs), HIT the pending
# hit's triangle (-1: none, the ray escaped)
ID, DEPTH, DELTA, FIRST, CROSS, HERO, NSTK, SEGMENT, HIT = 0, 1, 2, 3, 4, 5, 6, 7, 8
NI = 9
# shadow records: sf (float64), si (int64); S_FACE: the light's triangle where its
# emission varies (-1: constant), S_HIT: a pending hit's triangle (-1: not traced yet)
S_O, S_D, S_FAR, S_LEAD, S_TAIL, S_C, S_BARY = 0, 3, 6, 7, 8, 9, 12
S_HIT_T, S_HIT_B1, S_HIT_B2 = 15, 16, 17
S_L = 18  # the sampled direction to the light from the vertex itself (a light's wo)
NSF = 21
S_ID, S_FACE, S_NSTK, S_CROSS, S_SEGMENT, S_HIT = 0, 1, 2, 3, 4, 5
NSI = 6
# AOV columns
A_ALBEDO, A_NORMAL, A_DEPTH, A_UV, A_OBJECT = 0, 3, 6, 7, 9
NA = 10

#: object flags; BOUND: shaded with numpy per hit, IOR_SENSITIVE: its program reads the
#: IOR outside it (bound again inside other objects); EMIT_CONST: a constant diffuse
#: emitter (``emit_hit``), EMIT_PROG: a constant edf program (its slots), EMIT_GLOBAL: one
#: whose edfs read the rotation from object space (a global spot or measured edf)
CUTOUT, NULL, ENCLOSES, TWO_FACED, EMIT_CONST, BOUND, IOR_SENSITIVE = 1, 2, 4, 8, 16, 32, 64
EMIT_PROG, EMIT_GLOBAL = 128, 256
#: hair strands (:mod:`render.hair`): the object's primitives are curve segments (rows of
#: ``curves``), its program (slot 2k) its material's hair bsdf
HAIR = 512
#: each opcode's slot of ``object_to_local_00`` (-1: none): the edfs whose lobe may be
#: fixed in object space (``object_to_local_ij`` context slots)
OBJECT_TO_LOCAL = registry().dispatch().OBJECT_TO_LOCAL
#: one Embree call in this many is timed (the share of time inside Embree)
TIMED_EVERY = 16

#: Scene tables of the kernels (float64 unless noted).
Tables = namedtuple(
    "Tables",
    [
        "packed",  # (v, 14) positions, normals, tangent_u, tangent_v, uv per vertex
        "faces",  # (f, 3) int64
        "face_normal",  # (f, 3) unit, on the side of the vertex normals
        "face_object",  # (f,) int64
        "face_offset",  # (k + 1,) int64 first triangle of each object (Embree geomID)
        # the programs (render.program.ProgramTable): slot 2k is object k's bsdf on its
        # front, 2k + 1 its back; 2K + 2k and 2K + 2k + 1 its edfs (K objects); then the
        # media's phase functions; per-lane bindings after SC_NCONST
        "code",
        "kids",
        "frames",
        "chat",
        "roots",  # (2k,) root node of each slot's program, -1: black
        "frame_lo",
        "frame_hi",
        "obj_flags",  # (k,) int64 the object flags above
        "obj_opacity",  # (k,) constant cutout opacity
        "obj_ior",  # (k,) constant IOR (mean over channels)
        "obj_medium",  # (k,) int64 medium of the inside, -1: none
        # (k, 6) EMIT_CONST: radiance seen on the front of a constant diffuse emitter;
        # EMIT_PROG: the intensity of the front and back edfs (per area in power mode)
        "emit_hit",
        "obj_linear",  # (k, 9) each object's linear map to world, row-major
        "curves",  # (s, 16) hair segments' Bézier control points and radii (render.hair)
        "curve_first",  # (k,) int64 each hair object's first row of curves, -1: none
        "face_light",  # (f,) int64 the area light (group) of each emissive triangle, -1: none
        "medium",  # (m, 12) sigma_a, sigma_s, sigma_t, emission per channel
        # the lights (render.light_sampling.light_table): a row per light and per node of
        # the light tree, a row per emissive triangle, an environment map and its texels'
        # (probabilities, cdf), the sun and sky's parameters and (probabilities, cdf)
        "lights",
        "light_tri",
        "env_image",
        "env_dist",
        "sky",
        "sky_dist",
        "camera",  # (2, 3, 3) the camera's ray map (displacement.camera.Camera.ray_map)
        "scalars",  # (N_SCALARS,) see SC_* below
    ],
)
SC_SELECT, SC_EPS, SC_MAX_DEPTH, SC_RR_DEPTH, SC_LIGHTS, SC_ROT_C, SC_ROT_S = 0, 1, 2, 3, 4, 5, 6
SC_MEDIA, SC_AOV, SC_CAM = 7, 8, 9  # media present, AOVs asked for, camera position (9..11)
SC_FWD = 12  # camera forward (12..14)
SC_ENV_LIGHT = 15  # index of the environment light, -1: none
SC_BIND = 16  # some objects are shaded with numpy (lanes may park)
SC_PASS = 17  # some objects are cutouts or null surfaces (shadow rays may pass)
SC_WIDTH = 18  # the image's width in pixels
SC_NCONST = 19  # program slots of the scene (bindings' rows follow)
N_SCALARS = 20


# ---------------------------------------------------------------- small kernels
@njit(inline="always")
def _power(a, b):
    a2 = a * a
    b2 = b * b
    s = a2 + b2
    return a2 / s if s > 0.0 else 0.0


@njit(inline="always")
def _dot(ax, ay, az, bx, by, bz):
    return ax * bx + ay * by + az * bz


# ------------------------------------------------- the lights, for tests and set-up
def sample_lights(tb, p, u):
    """:func:`render.light_sampling.sample_lights` of the lights of tables ``tb``
    (points ``p`` (n, 3) in a medium, uniforms ``u`` (n, 3))."""
    sc = tb.scalars
    return ls.sample_lights(tb.lights, tb.light_tri, tb.env_image, tb.env_dist, tb.sky,
                            tb.sky_dist, int(sc[SC_LIGHTS]), int(sc[SC_SELECT]), sc[SC_ROT_C],
                            sc[SC_ROT_S], np.asarray(p, dtype=np.float64),
                            np.asarray(u, dtype=np.float64))


def selection(tb, p, nrm):
    """(n, lights) the probability that next-event estimation at points ``p`` with
    normals ``nrm`` (0: in a medium) picks each light of tables ``tb``."""
    sc = tb.scalars
    return ls.selection(tb.lights, int(sc[SC_LIGHTS]), int(sc[SC_SELECT]),
                        np.asarray(p, dtype=np.float64), np.asarray(nrm, dtype=np.float64))


def escaped(tb, d):
    """What rays along unit directions ``d`` (n, 3) that leave the scene of tables
    ``tb`` see: the environment's sampling pdf (n,) and radiance (n, 3)."""
    sc = tb.scalars
    return ls.escaped(tb.lights, int(sc[SC_ENV_LIGHT]), tb.env_image, tb.env_dist, tb.sky,
                      tb.sky_dist, sc[SC_ROT_C], sc[SC_ROT_S], np.asarray(d, dtype=np.float64))


# ------------------------------------------------------- the stack of closed objects
@njit(allocates=True)
def outside_ior(so, sior, nstk, objs):
    """(n,) the IOR around object ``objs[i]`` for stack rows ``i`` (for the bindings)."""
    out = np.ones(len(objs))
    for i in range(len(objs)):
        out[i] = stack_outside_ior(so, sior, i, nstk[i], objs[i])
    return out


@njit(inline="always")
def _roulette(b0, b1, b2, mis, u):
    """Russian roulette on a throughput (spectral-MIS normalised): (survives, b0, b1, b2)
    with survival probability min(max channel, 0.95)."""
    q = min(max(max(b0, b1), b2) / mis, 0.95)
    if not u < q:
        return False, b0, b1, b2
    q = max(q, 1e-300)
    return True, b0 / q, b1 / q, b2 / q


@njit(inline="always")
def _attributes(packed, faces, face_normal, f, w1, w2):
    """Position, unit shading normal (the face's where it degenerates), unit tangents u
    and v, and uv at barycentrics (w1, w2) of triangle ``f``."""
    tp = packed
    v0, v1, v2 = faces[f, 0], faces[f, 1], faces[f, 2]
    w0 = 1.0 - w1 - w2
    px = w0 * tp[v0, 0] + w1 * tp[v1, 0] + w2 * tp[v2, 0]
    py = w0 * tp[v0, 1] + w1 * tp[v1, 1] + w2 * tp[v2, 1]
    pz = w0 * tp[v0, 2] + w1 * tp[v1, 2] + w2 * tp[v2, 2]
    nx, ny, nz, ok = unitize(
        w0 * tp[v0, 3] + w1 * tp[v1, 3] + w2 * tp[v2, 3],
        w0 * tp[v0, 4] + w1 * tp[v1, 4] + w2 * tp[v2, 4],
        w0 * tp[v0, 5] + w1 * tp[v1, 5] + w2 * tp[v2, 5],
    )
    if not ok:
        nx, ny, nz = face_normal[f, 0], face_normal[f, 1], face_normal[f, 2]
    tx, ty, tz, _ = unitize(
        w0 * tp[v0, 6] + w1 * tp[v1, 6] + w2 * tp[v2, 6],
        w0 * tp[v0, 7] + w1 * tp[v1, 7] + w2 * tp[v2, 7],
        w0 * tp[v0, 8] + w1 * tp[v1, 8] + w2 * tp[v2, 8],
    )
    bx, by, bz, _ = unitize(
        w0 * tp[v0, 9] + w1 * tp[v1, 9] + w2 * tp[v2, 9],
        w0 * tp[v0, 10] + w1 * tp[v1, 10] + w2 * tp[v2, 10],
        w0 * tp[v0, 11] + w1 * tp[v1, 11] + w2 * tp[v2, 11],
    )
    u = w0 * tp[v0, 12] + w1 * tp[v1, 12] + w2 * tp[v2, 12]
    v = w0 * tp[v0, 13] + w1 * tp[v1, 13] + w2 * tp[v2, 13]
    return px, py, pz, nx, ny, nz, tx, ty, tz, bx, by, bz, u, v


@njit
def hit_attributes(packed, faces, face_normal, f, b1, b2, out):
    """:func:`_attributes` of hits ``f``, ``b1``, ``b2`` (n,) into ``out`` (n, 14):
    position, unit normal, unit tangents u and v, uv (for the lanes shaded with numpy)."""
    for i in range(len(f)):
        a = _attributes(packed, faces, face_normal, f[i], b1[i], b2[i])
        for c in range(14):
            out[i, c] = a[c]


def scratch(tb) -> np.ndarray:
    """The interpreter's scratch for the programs of ``tb`` (one per thread and kernel
    call: the kernels own no memory, so they count no references)."""
    return np.empty(interpreter.work_size(len(tb.code), len(tb.kids), len(tb.frames)))


# ------------------------------------------------------------- the path walker
@njit(inline="always")
def _needs_binding(flags, cso, csior, nstk, k):
    """Whether a hit on object ``k`` must first be shaded with numpy
    (:meth:`render.integrator.Integrator._bind`): its arguments vary, or its program
    reads the IOR outside it and the lane is inside another object whose IOR is not 1."""
    if flags & BOUND:
        return True
    return (flags & IOR_SENSITIVE) != 0 and nstk > 0 and \
        stack_outside_ior(cso, csior, 0, nstk, k) != 1.0


@njit(inline="always")
def _traced(counts, t0, rays):
    """Count one Embree call; every TIMED_EVERY-th is timed (``counts``: rays, timed
    rays, their cycles)."""
    if rays % TIMED_EVERY == 0:
        counts[1] += 1
        counts[2] += embree.cycles() - t0


@njit
def trace(scene, tb, n, resume, pixel, index, seed, kind, v1, lf, li, so, sior,
          lane_row, params, bf, bslot, L, alpha, aov, plf, pli, pso, psior, sf, si, sso,
          ssior, ws, es, cso, csior, lw, ep, counts):
    """Trace the paths of lanes ``0 .. n-1`` to their end, or until a path hits an object
    that numpy must shade first (:func:`_needs_binding`): such a lane is *parked*, its
    state and hit written to row ``p`` of ``plf``, ``pli``, ``pso``, ``psior``.

    Fresh lanes (``resume`` False) start at the camera: lane ``i`` is sample
    ``index[i]`` of pixel ``pixel[i]``, through a point of the pixel drawn from its
    camera pair.  Resumed lanes are
    the rows of ``lf``, ``li``, ``so``, ``sior`` (a previous call's parked lanes), each
    with its hit, bound by row ``lane_row[i]`` (-1: none) of ``bf``, ``bslot`` and
    ``params`` (:meth:`render.integrator.Integrator._bind`).  Shadow records that cannot
    be resolved here (an area light whose emission varies, or a cutout or null surface
    that numpy must shade) are parked in ``sf``, ``si``, ``sso``, ``ssior`` for
    :func:`resolve_shadows`.

    What each path sees is added to ``L[lane]``, its alpha and AOVs (first hits) to
    ``alpha`` and ``aov``.  Scratch: ``ws`` (the interpreter's), ``es`` (Embree's ray
    record), ``cso``/``csior`` (a lane's stack of closed objects, one row), ``lw`` (the
    lights' weights, a row of ``tb.lights`` long), ``ep`` (one parameter row: an edf
    program's row with the hit's rotation from object space).  Returns
    ``(parked lanes, parked shadow records)``."""
    sc = tb.scalars
    eps = sc[SC_EPS]
    max_depth, rr_depth = sc[SC_MAX_DEPTH], sc[SC_RR_DEPTH]
    has_media = sc[SC_MEDIA] != 0.0
    want_aov = sc[SC_AOV] != 0.0
    may_bind = sc[SC_BIND] != 0.0
    mode, env_light = int(sc[SC_SELECT]), int(sc[SC_ENV_LIGHT])
    n_lights, rot_c, rot_s = int(sc[SC_LIGHTS]), sc[SC_ROT_C], sc[SC_ROT_S]
    width = int(sc[SC_WIDTH])
    lights, light_tri, env_image, env_dist = tb.lights, tb.light_tri, tb.env_image, tb.env_dist
    sky, sky_dist = tb.sky, tb.sky_dist
    n_every = 0  # delta lights sampled at every vertex
    if mode >= EVERY_DELTA:
        for j in range(n_lights):
            n_every += 1 if is_delta(int(lights[j, L_KIND])) else 0
    n_const = int(sc[SC_NCONST])
    nest = cso.shape[1]
    code, kids, frames, chat = tb.code, tb.kids, tb.frames, tb.chat
    face_light, emit_hit, face_normal = tb.face_light, tb.emit_hit, tb.face_normal
    face_object, frame_lo, frame_hi, roots = tb.face_object, tb.frame_lo, tb.frame_hi, tb.roots
    medium, face_offset = tb.medium, tb.face_offset
    phase0 = 4 * len(tb.obj_flags)  # the media's phase functions' slots
    obj_flags, obj_ior, obj_medium = tb.obj_flags, tb.obj_ior, tb.obj_medium
    obj_opacity, packed, faces = tb.obj_opacity, tb.packed, tb.faces
    n_park = n_shadow = rays = 0
    for i in range(n):
        if resume:
            lane = li[i, ID]
            ox, oy, oz = lf[i, ORG], lf[i, ORG + 1], lf[i, ORG + 2]
            dx, dy, dz = lf[i, D], lf[i, D + 1], lf[i, D + 2]
            b0, b1, b2 = lf[i, BETA], lf[i, BETA + 1], lf[i, BETA + 2]
            r0, r1, r2 = lf[i, R], lf[i, R + 1], lf[i, R + 2]
            prev_pdf, seg, shift = lf[i, PREV_PDF], lf[i, SEG], lf[i, SHIFT]
            vx, vy, vz = lf[i, PREV_P], lf[i, PREV_P + 1], lf[i, PREV_P + 2]
            vnx, vny, vnz = lf[i, PREV_N], lf[i, PREV_N + 1], lf[i, PREV_N + 2]
            prev_sum = lf[i, PREV_SUM]
            depth, prev_delta, first = li[i, DEPTH], li[i, DELTA] != 0, li[i, FIRST] != 0
            crossings, hero, nstk, segment = li[i, CROSS], li[i, HERO], li[i, NSTK], li[i, SEGMENT]
            for s in range(nest):
                cso[0, s], csior[0, s] = so[i, s], sior[i, s]
            f = li[i, HIT]
            hb1, hb2, t_hit = lf[i, HIT_B1], lf[i, HIT_B2], lf[i, HIT_T]
            v = lane_row[i]
        else:
            lane = i
            jx, jy = sample_pair(v1, pixel_hash(seed, pixel[i]), index[i], CAMERA_PAIR, kind)
            ox, oy, oz, dx, dy, dz = camera_ray(tb.camera, width, pixel[i], jx, jy)
            b0 = b1 = b2 = r0 = r1 = r2 = 1.0
            prev_pdf = seg = shift = prev_sum = 0.0
            vx = vy = vz = vnx = vny = vnz = 0.0
            depth, prev_delta, first = 1, True, True  # camera rays count as specular
            crossings, hero, nstk, segment = 0, 0, 0, 0
            for s in range(nest):
                cso[0, s], csior[0, s] = -1, 1.0
            f, hb1, hb2, t_hit = -1, 0.0, 0.0, 0.0
            v = -1
        ph = pixel_hash(seed, pixel[lane])
        idx = index[lane]
        if has_media and not resume:  # one hero channel per path
            hero = min(int(sample_pair(v1, ph, idx, HERO_PAIR, kind)[0] * 3.0), 2)
        have_hit = resume
        while True:
            # ---- the segment's first hit
            if not have_hit:
                rays += 1
                t0 = embree.cycles() if rays % TIMED_EVERY == 0 else np.uint64(0)
                h = embree.intersect1(scene, ox, oy, oz, dx, dy, dz, 0.0, np.inf, es)
                _traced(counts, t0, rays)
                f = -1
                if h[4] != embree.MISS:
                    f = face_offset[h[4]] + h[3]
                    hb1, hb2, t_hit = np.float64(h[1]), np.float64(h[2]), np.float64(h[0])
                    if obj_flags[face_object[f]] & HAIR:  # hb2: the tube met from inside
                        hb2 = 1.0 if h[5] * dx + h[6] * dy + h[7] * dz > 0.0 else 0.0
                    if may_bind and _needs_binding(obj_flags[face_object[f]], cso, csior, nstk,
                                                   face_object[f]):
                        _park(plf, pli, pso, psior, n_park, cso, csior, lane, ox, oy, oz, dx,
                              dy, dz, b0, b1, b2, r0, r1, r2, prev_pdf, seg, shift, vx, vy, vz,
                              vnx, vny, vnz, prev_sum, depth, prev_delta, first, crossings,
                              hero, nstk, segment, f, hb1, hb2, t_hit)
                        n_park += 1
                        break
                v = -1
            if n_shadow + 1 + n_every > len(sf):  # no room for this vertex's shadow records
                _park(plf, pli, pso, psior, n_park, cso, csior, lane, ox, oy, oz, dx, dy, dz, b0,
                      b1, b2, r0, r1, r2, prev_pdf, seg, shift, vx, vy, vz, vnx, vny, vnz,
                      prev_sum, depth, prev_delta, first, crossings, hero, nstk, segment, f,
                      hb1, hb2, t_hit)
                n_park += 1
                break
            have_hit = False
            pair0 = FIRST_SEGMENT_PAIR + segment * PAIRS_PER_SEGMENT
            segment += 1
            if f < 0:
                t_hit = np.inf
            # ---- the medium of the segment: attenuate, or scatter inside it
            scattered = False
            hair = False
            t_event = 0.0
            med = -1
            u_flight, u_roulette = 0.0, 0.0
            if has_media and nstk > 0:
                med = obj_medium[cso[0, nstk - 1]]
            if med >= 0:
                u_flight, u_roulette = sample_pair(v1, ph, idx, pair0 + P_FLIGHT, kind)
                length = t_hit + shift
                if medium[med, 9] > 0.0 or medium[med, 10] > 0.0 or medium[med, 11] > 0.0:
                    # the medium's emission along the whole segment, in closed form
                    w = 1.0 / ((r0 + r1 + r2) / 3.0)
                    L[lane, 0] += b0 * emitted(medium, med, 0, length) * w
                    L[lane, 1] += b1 * emitted(medium, med, 1, length) * w
                    L[lane, 2] += b2 * emitted(medium, med, 2, length) * w
                scattered, tt, w0, w1, w2, p0, p1, p2 = free_flight(medium, med, hero, u_flight,
                                                                    length)
                if scattered:
                    t_event = tt - shift
                pw = p0 if hero == 0 else (p1 if hero == 1 else p2)
                if pw > 0.0:  # spectral MIS: r = p / p[hero], beta *= value / p[hero]
                    b0, b1, b2 = b0 * w0 / pw, b1 * w1 / pw, b2 * w2 / pw
                    r0, r1, r2 = r0 * p0 / pw, r1 * p1 / pw, r2 * p2 / pw
                else:
                    b0 = b1 = b2 = 0.0
            mis = (r0 + r1 + r2) / 3.0
            if scattered:
                # ---- a scattering vertex in the medium: the phase function, no normal
                px, py, pz = ox + t_event * dx, oy + t_event * dy, oz + t_event * dz
                if not depth < max_depth:
                    break
                nx = ny = nz = gx = gy = gz = sx = sy = sz = qx = qy = qz = 0.0
                wox, woy, woz = -dx, -dy, -dz  # world directions at a medium vertex
                k, entry_ior, g_wo, dist_v = -1, 1.0, 0.0, 0.0
                row = phase0 + med  # the phase function's program
                root, f_lo, f_hi = roots[row], frame_lo[row], frame_hi[row]
                can_continue, is_null, encloses, front = True, False, False, True
            elif f < 0:
                # ---- escaped: the environment, weighted against light sampling
                pe, e0, e1, e2 = environment_radiance(lights, env_light, env_image, env_dist,
                                                      sky, sky_dist, rot_c, rot_s, dx, dy, dz)
                if e0 != 0.0 or e1 != 0.0 or e2 != 0.0:
                    if not prev_delta:
                        pe *= selection_pdf(lights, n_lights, mode, env_light, prev_sum, vx, vy,
                                            vz, vnx, vny, vnz)
                    w = (1.0 if prev_delta else _power(prev_pdf, pe)) / mis
                    L[lane, 0] += b0 * e0 * w
                    L[lane, 1] += b1 * e1 * w
                    L[lane, 2] += b2 * e2 * w
                break
            else:
                # ---- a surface
                k = face_object[f]
                flags = obj_flags[k]
                if flags & HAIR:
                    if hb2 != 0.0:  # a tube met from inside: on through its wall, no vertex
                        if crossings >= MAX_CROSSINGS:
                            break
                        ox, oy, oz = (ox + (t_hit + eps) * dx, oy + (t_hit + eps) * dy,
                                      oz + (t_hit + eps) * dz)
                        seg += t_hit + eps
                        shift = eps
                        crossings += 1
                        continue
                    # the fibre's frame: tangent along it, the tube's normal at the entry
                    hair = True
                    px, py, pz, nx, ny, nz, tx, ty, tz = hair_hit(
                        tb.curves, tb.curve_first[k] + f - face_offset[k], hb1, ox, oy, oz,
                        dx, dy, dz, t_hit)
                    gx, gy, gz, uu, uv = nx, ny, nz, hb1, 0.0
                else:
                    px, py, pz, nx, ny, nz, tx, ty, tz, _, _, _, uu, uv = _attributes(
                        packed, faces, face_normal, f, hb1, hb2)
                    gx, gy, gz = face_normal[f, 0], face_normal[f, 1], face_normal[f, 2]
                g_wo = -_dot(dx, dy, dz, gx, gy, gz)
                front = g_wo > 0.0
                slot = 2 * k + (1 if (flags & TWO_FACED) and not front else 0)
                row = slot
                if v >= 0:
                    nx, ny, nz = bf[v, 0], bf[v, 1], bf[v, 2]
                    tx, ty, tz = bf[v, 3], bf[v, 4], bf[v, 5]
                    opacity, entry_ior = bf[v, 6], bf[v, 7]
                    e0, e1, e2 = bf[v, 8], bf[v, 9], bf[v, 10]
                    slot, row = bslot[v], n_const + v
                else:
                    opacity, entry_ior = obj_opacity[k], obj_ior[k]
                    e0 = e1 = e2 = 0.0
                dist_v = seg + t_hit
                # cutouts: pass straight through with probability 1 - opacity
                if (flags & CUTOUT) and crossings < MAX_CROSSINGS and \
                        sample_pair(v1, ph, idx, pair0 + P_CUTOUT, kind)[0] >= opacity:
                    side = 1.0 if _dot(dx, dy, dz, gx, gy, gz) >= 0.0 else -1.0
                    ox, oy, oz = px + side * eps * gx, py + side * eps * gy, pz + side * eps * gz
                    seg = dist_v
                    shift = _parallel_shift(eps, gx, gy, gz, dx, dy, dz)
                    crossings += 1
                    continue
                sx, sy, sz, qx, qy, qz = frame_from_normal_tangent(nx, ny, nz, tx, ty, tz)
                wox = -_dot(dx, dy, dz, sx, sy, sz)
                woy = -_dot(dx, dy, dz, qx, qy, qz)
                woz = -_dot(dx, dy, dz, nx, ny, nz)
                # emission, weighted against light sampling
                if flags & EMIT_CONST and front and woz > 1e-10:
                    e0, e1, e2 = emit_hit[k, 0], emit_hit[k, 1], emit_hit[k, 2]
                elif flags & EMIT_PROG and v < 0 and (front or (flags & TWO_FACED) != 0):
                    e0, e1, e2 = _emission(tb, params, ws, ep, k, not front, sx, sy, sz, qx,
                                           qy, qz, nx, ny, nz, wox, woy, woz)
                if e0 != 0.0 or e1 != 0.0 or e2 != 0.0:
                    w = 1.0 / mis
                    jl = face_light[f]
                    cos_l = abs(g_wo)
                    if not prev_delta and jl >= 0 and cos_l > 0.0:
                        pl = lights[jl, L_PDF_AREA] * dist_v * dist_v / cos_l * selection_pdf(
                            lights, n_lights, mode, jl, prev_sum, vx, vy, vz, vnx, vny, vnz)
                        w = _power(prev_pdf, pl) / mis
                    L[lane, 0] += b0 * e0 * w
                    L[lane, 1] += b1 * e1 * w
                    L[lane, 2] += b2 * e2 * w
                root, f_lo, f_hi = roots[slot], frame_lo[slot], frame_hi[slot]
                if first:
                    first = False
                    alpha[lane] = 1.0
                    if want_aov:
                        if root >= 0:
                            a0, a1, a2 = interpreter.cheap_albedo(code, kids, frames, params,
                                                                  chat, row, ws, root, f_lo,
                                                                  f_hi, wox, woy, woz)
                            aov[lane, A_ALBEDO], aov[lane, A_ALBEDO + 1] = a0, a1
                            aov[lane, A_ALBEDO + 2] = a2
                        aov[lane, A_NORMAL], aov[lane, A_NORMAL + 1] = nx, ny
                        aov[lane, A_NORMAL + 2] = nz
                        aov[lane, A_DEPTH] = _dot(px - sc[SC_CAM], py - sc[SC_CAM + 1],
                                                  pz - sc[SC_CAM + 2], sc[SC_FWD],
                                                  sc[SC_FWD + 1], sc[SC_FWD + 2])
                        aov[lane, A_UV], aov[lane, A_UV + 1] = uu, uv
                        aov[lane, A_OBJECT] = k
                if root < 0:
                    break
                can_continue = depth < max_depth
                is_null = (flags & NULL) != 0
                if not (can_continue or is_null):
                    break
                encloses = (flags & ENCLOSES) != 0
            # ---- next-event estimation: the selected light, then every delta light
            u_choice, u_lobe = sample_pair(v1, ph, idx, pair0 + P_CHOICE, kind)
            prepared = False
            total = 0.0
            jd = -1
            ul1 = ul2 = 0.0
            if can_continue:
                ul1, ul2 = sample_pair(v1, ph, idx, pair0 + P_LIGHT, kind)
            # the normal lights are weighed by (0: all around, in a medium or on a fibre)
            snx, sny, snz = (0.0, 0.0, 0.0) if hair else (nx, ny, nz)
            for pick in range(1 + n_every if can_continue else 0):
                if pick == 0:
                    j, sel, total = select_light(lights, n_lights, mode, px, py, pz, snx, sny,
                                                 snz, u_choice, lw)  # -1: none
                else:
                    jd = next_delta(lights, n_lights, jd)
                    j, sel = jd, 1.0
                (lx, ly, lz, ldist, l0, l1, l2, lpdf, ldelta, lface, q0, q1, q2) = sample_light(
                    lights, light_tri, env_image, env_dist, sky, sky_dist, rot_c, rot_s, j, px,
                    py, pz, ul1, ul2)
                lpdf *= sel
                if not lpdf > 0.0:
                    continue
                if lface >= 0 and obj_flags[face_object[lface]] & EMIT_PROG:
                    le0, le1, le2 = _emission_at(tb, params, ws, ep, lface, q1, q2, -lx, -ly,
                                                 -lz)
                    l0, l1, l2, lface = l0 * le0, l1 * le1, l2 * le2, -1
                across = False
                if scattered:
                    f0, f1, f2, pb = interpreter.eval_pdf(
                        code, kids, frames, params, chat, row, ws, root, f_lo, f_hi, wox, woy,
                        woz, lx, ly, lz)
                    prepared = True
                else:
                    wlz = _dot(lx, ly, lz, nx, ny, nz)
                    g_wi = _dot(lx, ly, lz, gx, gy, gz)
                    if g_wi == 0.0 or (g_wi * g_wo > 0.0) != (wlz * woz > 0.0):
                        continue
                    f0, f1, f2, pb = interpreter.eval_pdf(
                        code, kids, frames, params, chat, row, ws, root, f_lo, f_hi, wox, woy,
                        woz, _dot(lx, ly, lz, sx, sy, sz), _dot(lx, ly, lz, qx, qy, qz), wlz)
                    prepared = True
                    across = encloses and g_wi * g_wo < 0.0  # the light is across the surface
                w = (1.0 if ldelta else _power(lpdf, pb)) / lpdf / mis
                c0, c1, c2 = b0 * f0 * l0 * w, b1 * f1 * l1 * w, b2 * f2 * l2 * w
                if not (c0 > 0.0 or c1 > 0.0 or c2 > 0.0):
                    continue
                _shadow_record(eps, sf, si, sso, ssior, n_shadow, cso, csior, nstk, lane,
                               segment - 1, px, py, pz, gx, gy, gz, lx, ly, lz, ldist, c0, c1,
                               c2, lface, q0, q1, q2, not scattered,
                               0.0 if scattered else _parallel_shift(eps, gx, gy, gz, lx, ly, lz))
                if across:
                    sn = si[n_shadow, S_NSTK]
                    if front:
                        sn = stack_push(sso, ssior, n_shadow, sn, k, entry_ior)
                    else:
                        sn = stack_pop(sso, ssior, n_shadow, sn, k)
                    si[n_shadow, S_NSTK] = sn
                if lface >= 0 or _walk_shadow(scene, tb, sf, si, sso, ssior, n_shadow, -1, params,
                                              bf, bslot, L, ws, es, v1, ph, idx, kind, counts):
                    n_shadow += 1
            # ---- the bsdf's (or the phase function's) sample continues the path
            ub1, ub2 = sample_pair(v1, ph, idx, pair0 + P_BSDF, kind)
            straight = False
            if scattered:
                nx2, ny2, nz2, pdf, w0, w1, w2, lobe = interpreter.sample(
                    code, kids, frames, params, chat, row, ws, root, f_lo, f_hi, wox, woy, woz,
                    u_lobe, ub1, ub2, prepared)
                if lobe == 0 or not (w0 > 0.0 or w1 > 0.0 or w2 > 0.0):
                    break
                g_new = 0.0
            else:
                wix, wiy, wiz, pdf, w0, w1, w2, lobe = interpreter.sample(
                    code, kids, frames, params, chat, row, ws, root, f_lo, f_hi, wox, woy, woz,
                    u_lobe, ub1, ub2, prepared)
                if lobe == 0 or not (w0 > 0.0 or w1 > 0.0 or w2 > 0.0):
                    break
                nx2 = wix * sx + wiy * qx + wiz * nx
                ny2 = wix * sy + wiy * qy + wiz * ny
                nz2 = wix * sz + wiy * qz + wiz * nz
                g_new = _dot(nx2, ny2, nz2, gx, gy, gz)
                if g_new == 0.0 or (g_new * g_wo > 0.0) != (wiz * woz > 0.0):
                    break
                straight = (is_null and lobe == SPECULAR_TRANSMISSION
                            and _dot(nx2, ny2, nz2, dx, dy, dz) > 1.0 - STRAIGHT_TOL
                            and crossings < MAX_CROSSINGS)
                if not (can_continue or straight):
                    break
            b0, b1, b2 = b0 * w0, b1 * w1, b2 * w2
            if not straight and depth >= rr_depth:
                if med < 0:
                    u_roulette = sample_pair(v1, ph, idx, pair0 + P_FLIGHT, kind)[1]
                survives, b0, b1, b2 = _roulette(b0, b1, b2, mis, u_roulette)
                if not survives:
                    break
            if not (b0 > 0.0 or b1 > 0.0 or b2 > 0.0):
                break
            if scattered:
                ox, oy, oz = px, py, pz
                shift = 0.0
            else:
                if straight:
                    nx2, ny2, nz2 = dx, dy, dz
                # a transmission through a closed object enters or leaves it
                if encloses and g_new * g_wo < 0.0:
                    if front:
                        nstk = stack_push(cso, csior, 0, nstk, k, entry_ior)
                    else:
                        nstk = stack_pop(cso, csior, 0, nstk, k)
                side = 1.0 if g_new >= 0.0 else -1.0
                ox, oy, oz = px + side * eps * gx, py + side * eps * gy, pz + side * eps * gz
                shift = _parallel_shift(eps, gx, gy, gz, nx2, ny2, nz2)
            dx, dy, dz = nx2, ny2, nz2
            if straight:
                seg = dist_v
                crossings += 1
            else:
                prev_pdf, seg = pdf, 0.0
                vx, vy, vz, vnx, vny, vnz, prev_sum = px, py, pz, snx, sny, snz, total
                depth, crossings = depth + 1, 0
                prev_delta = (not scattered) and (lobe & SPECULAR) != 0
    counts[0] += rays
    return n_park, n_shadow


@njit
def _emission(tb, params, ws, ep, k, back, sx, sy, sz, qx, qy, qz, nx, ny, nz, wox, woy, woz):
    """Radiance emitted toward ``wo`` (in the frame ``s, q, n`` of the point) by the
    edf program of object ``k`` (EMIT_PROG): its front edf, or with ``back`` its thin-walled
    backface's, whose frame is turned over (``wo`` mirrored through the tangent plane);
    times the intensity of that side (``emit_hit``; per area in power mode), as
    :meth:`render.integrator.Integrator._emitted` has it.  An edf whose lobe is fixed
    in object space reads the rotation from object space into the (turned) frame: the
    program's row is copied to ``ep`` with it."""
    slot = 2 * len(tb.obj_flags) + 2 * k + (1 if back else 0)
    root = tb.roots[slot]
    if root < 0:
        return 0.0, 0.0, 0.0
    side = 1.0
    if back:
        woz, side = -woz, -1.0
    P, row = params, slot
    if tb.obj_flags[k] & EMIT_GLOBAL:
        code, lin = tb.code, tb.obj_linear
        for c in range(params.shape[1]):
            ep[0, c] = params[slot, c]
        for node in range(root - code[root, SIZE] + 1, root + 1):
            o = OBJECT_TO_LOCAL[code[node, OP]]
            if o < 0:
                continue
            o += code[node, BASE]
            for i in range(3):
                if i == 0:
                    rx, ry, rz = sx, sy, sz
                elif i == 1:
                    rx, ry, rz = qx, qy, qz
                else:
                    rx, ry, rz = side * nx, side * ny, side * nz
                for j in range(3):
                    ep[0, o + 3 * i + j] = rx * lin[k, j] + ry * lin[k, 3 + j] + rz * lin[k, 6 + j]
        P, row = ep, 0
    e0, e1, e2, _ = interpreter.edf_eval_pdf(tb.code, tb.kids, tb.frames, P, tb.chat, row, ws,
                                             root, tb.frame_lo[slot], tb.frame_hi[slot], wox,
                                             woy, woz)
    o = 3 if back else 0
    eh = tb.emit_hit
    return e0 * eh[k, o], e1 * eh[k, o + 1], e2 * eh[k, o + 2]


@njit
def _emission_at(tb, params, ws, ep, f, b1, b2, wx, wy, wz):
    """:func:`_emission` of a light sample: at barycentrics ``(b1, b2)`` of triangle
    ``f`` of an EMIT_PROG object, toward the unit world direction ``w``; 0 from the back
    unless the object is two-faced."""
    k = tb.face_object[f]
    face_normal = tb.face_normal
    front = _dot(wx, wy, wz, face_normal[f, 0], face_normal[f, 1], face_normal[f, 2]) > 0.0
    if not front and not (tb.obj_flags[k] & TWO_FACED):
        return 0.0, 0.0, 0.0
    _, _, _, nx, ny, nz, tx, ty, tz, _, _, _, _, _ = _attributes(tb.packed, tb.faces,
                                                                 face_normal, f, b1, b2)
    sx, sy, sz, qx, qy, qz = frame_from_normal_tangent(nx, ny, nz, tx, ty, tz)
    return _emission(tb, params, ws, ep, k, not front, sx, sy, sz, qx, qy, qz, nx, ny, nz,
                     _dot(wx, wy, wz, sx, sy, sz), _dot(wx, wy, wz, qx, qy, qz),
                     _dot(wx, wy, wz, nx, ny, nz))


@njit
def _park(plf, pli, pso, psior, p, cso, csior, lane, ox, oy, oz, dx, dy, dz, b0, b1, b2, r0,
          r1, r2, prev_pdf, seg, shift, vx, vy, vz, vnx, vny, vnz, prev_sum, depth, prev_delta,
          first, crossings, hero, nstk, segment, f, hb1, hb2, t_hit):
    """A lane's state and pending hit to row ``p`` of the parked lanes."""
    plf[p, ORG], plf[p, ORG + 1], plf[p, ORG + 2] = ox, oy, oz
    plf[p, D], plf[p, D + 1], plf[p, D + 2] = dx, dy, dz
    plf[p, BETA], plf[p, BETA + 1], plf[p, BETA + 2] = b0, b1, b2
    plf[p, R], plf[p, R + 1], plf[p, R + 2] = r0, r1, r2
    plf[p, PREV_PDF], plf[p, SEG], plf[p, SHIFT] = prev_pdf, seg, shift
    plf[p, PREV_P], plf[p, PREV_P + 1], plf[p, PREV_P + 2] = vx, vy, vz
    plf[p, PREV_N], plf[p, PREV_N + 1], plf[p, PREV_N + 2] = vnx, vny, vnz
    plf[p, PREV_SUM] = prev_sum
    plf[p, HIT_T], plf[p, HIT_B1], plf[p, HIT_B2] = t_hit, hb1, hb2
    pli[p, ID], pli[p, DEPTH], pli[p, DELTA], pli[p, FIRST] = lane, depth, prev_delta, first
    pli[p, CROSS], pli[p, HERO], pli[p, NSTK] = crossings, hero, nstk
    pli[p, SEGMENT], pli[p, HIT] = segment, f
    for s in range(pso.shape[1]):
        pso[p, s], psior[p, s] = cso[0, s], csior[0, s]


@njit(inline="always")
def _shadow_record(eps, sf, si, sso, ssior, r, cso, csior, nstk, lane, segment, px, py, pz,
                   gx, gy, gz, lx, ly, lz, ldist, c0, c1, c2, face, bary0, bary1, bary2,
                   offset, shift_in):
    """Write shadow record ``r``: a ray from p toward the light sample; ``offset``: push
    the origin off the surface (normal ``g``) on the light's side, else start at p (in a
    medium).  The record starts untraced (``S_HIT`` -1) with the lane's stack."""
    qx, qy, qz = px, py, pz
    if offset:
        side = 1.0 if _dot(lx, ly, lz, gx, gy, gz) >= 0.0 else -1.0
        qx, qy, qz = px + side * eps * gx, py + side * eps * gy, pz + side * eps * gz
    finite = ldist < INFINITE_DISTANCE
    if finite:  # aim from the offset origin at the light point itself
        tx, ty, tz = px + lx * ldist, py + ly * ldist, pz + lz * ldist
        ex, ey, ez = tx - qx, ty - qy, tz - qz
        ux, uy, uz, ok = unitize(ex, ey, ez)
        if not ok:
            ux, uy, uz = lx, ly, lz
        sdist = math.sqrt(ex * ex + ey * ey + ez * ez)
        lead = ldist - sdist
    else:
        ux, uy, uz, sdist = lx, ly, lz, ldist
        lead = shift_in
    far = sdist * (1.0 - 1e-6) - eps if finite else sdist
    sf[r, S_O], sf[r, S_O + 1], sf[r, S_O + 2] = qx, qy, qz
    sf[r, S_D], sf[r, S_D + 1], sf[r, S_D + 2] = ux, uy, uz
    sf[r, S_FAR] = max(far, 0.0)
    sf[r, S_LEAD] = lead
    sf[r, S_TAIL] = sdist - far if finite else 0.0
    sf[r, S_C], sf[r, S_C + 1], sf[r, S_C + 2] = c0, c1, c2
    sf[r, S_BARY], sf[r, S_BARY + 1], sf[r, S_BARY + 2] = bary0, bary1, bary2
    sf[r, S_L], sf[r, S_L + 1], sf[r, S_L + 2] = lx, ly, lz
    si[r, S_ID], si[r, S_FACE], si[r, S_NSTK], si[r, S_CROSS] = lane, face, nstk, 0
    si[r, S_SEGMENT], si[r, S_HIT] = segment, -1
    for s in range(sso.shape[1]):
        sso[r, s] = cso[0, s]
        ssior[r, s] = csior[0, s]


@njit
def _parallel_shift(eps, gx, gy, gz, dx, dy, dz):
    """How much shorter an offset ray is than the same ray from the surface point,
    through a medium bounded by a parallel surface (|cos| clamped at 0.1)."""
    return eps / max(abs(_dot(gx, gy, gz, dx, dy, dz)), 0.1)


# ---------------------------------------------------------------- shadow rays
@njit(inline="always")
def _walk_shadow(scene, tb, sf, si, sso, ssior, r, v, params, bf, bslot, L, ws, es, v1, ph,
                 idx, kind, counts):
    """Carry shadow record ``r`` to its light: attenuated by the medium of each segment,
    through cutouts and null surfaces (:func:`_cross_shadow`) and hair tubes it meets
    from inside (from a fibre's vertex into the fibre); what arrives is added to
    ``L``, what is blocked dropped.  A pending hit (``S_HIT >= 0``) is taken first, with
    binding row ``v`` (-1: none).  Returns True where the record stops at a surface that
    numpy must shade first: it is then left in row ``r`` with that hit pending, else
    False.  (Inlined: the common case, a ray to the light, runs without a call.)"""
    sc = tb.scalars
    medium, face_object, obj_flags = tb.medium, tb.face_object, tb.obj_flags
    while True:
        f = si[r, S_HIT]
        far = sf[r, S_FAR]
        nstk = si[r, S_NSTK]
        inside = False  # a hair tube met from inside: passed, as in trace
        if f >= 0:  # the pending hit
            si[r, S_HIT] = -1
            hb1, hb2, t = sf[r, S_HIT_B1], sf[r, S_HIT_B2], sf[r, S_HIT_T]
        else:
            counts[0] += 1
            timed = counts[0] % TIMED_EVERY == 0
            t0 = embree.cycles() if timed else np.uint64(0)
            if sc[SC_PASS] != 0.0:
                h = embree.intersect1(scene, sf[r, S_O], sf[r, S_O + 1], sf[r, S_O + 2],
                                      sf[r, S_D], sf[r, S_D + 1], sf[r, S_D + 2], 0.0, far, es)
                f = -1 if h[4] == embree.MISS else tb.face_offset[h[4]] + h[3]
                hb1, hb2, t = h[1], h[2], h[0]
                inside = h[5] * sf[r, S_D] + h[6] * sf[r, S_D + 1] + h[7] * sf[r, S_D + 2] > 0.0
            else:
                blocked = embree.occluded1(scene, sf[r, S_O], sf[r, S_O + 1], sf[r, S_O + 2],
                                           sf[r, S_D], sf[r, S_D + 1], sf[r, S_D + 2], 0.0, far,
                                           es)
                f, hb1, hb2, t = -2 if blocked else -1, 0.0, 0.0, far
            if timed:
                counts[1] += 1
                counts[2] += embree.cycles() - t0
            v = -1
            if f == -2:
                return False
            if f >= 0:
                k = face_object[f]
                flags = obj_flags[k]
                if flags & HAIR:  # blocks, unless met from inside
                    if not inside or si[r, S_CROSS] >= MAX_CROSSINGS:
                        return False
                elif not (flags & (CUTOUT | NULL)) or si[r, S_CROSS] >= MAX_CROSSINGS:
                    return False
                else:
                    inside = False
                    if sc[SC_BIND] != 0.0 and _needs_binding(flags, sso[r:r + 1],
                                                             ssior[r:r + 1], nstk, k):
                        si[r, S_HIT] = f
                        sf[r, S_HIT_T], sf[r, S_HIT_B1], sf[r, S_HIT_B2] = t, hb1, hb2
                        return True
        if f < 0:
            t = far
        if sc[SC_MEDIA] != 0.0 and nstk > 0:
            med = tb.obj_medium[sso[r, nstk - 1]]
            if med >= 0:
                length = t + sf[r, S_LEAD] + (0.0 if f >= 0 else sf[r, S_TAIL])
                for c in range(3):
                    sf[r, S_C + c] *= transmittance(medium, med, c, length)
        if f < 0:
            lane = si[r, S_ID]
            for c in range(3):
                L[lane, c] += sf[r, S_C + c]
            return False
        if inside:  # on through the tube's wall, along the ray
            step = t + sc[SC_EPS]
            for c in range(3):
                sf[r, S_O + c] += step * sf[r, S_D + c]
            sf[r, S_FAR] = max(far - step, 0.0)
            sf[r, S_LEAD] = sc[SC_EPS]
            si[r, S_CROSS] += 1
            continue
        if not _cross_shadow(tb, sf, si, sso, ssior, r, f, hb1, hb2, t, v, params, bf, bslot,
                             ws, v1, ph, idx, kind):
            return False


@njit
def _cross_shadow(tb, sf, si, sso, ssior, r, f, hb1, hb2, t, v, params, bf, bslot, ws, v1, ph,
                  idx, kind):
    """Shadow record ``r`` at a hit on a cutout or null surface (triangle ``f``, binding
    row ``v``): a cutout lets it pass with probability ``1 - opacity``, a null surface
    with its straight-through transmission (entering or leaving the object).  Moves the
    record to its next segment and returns True, or False where it is blocked."""
    sc = tb.scalars
    eps = sc[SC_EPS]
    face_normal, roots = tb.face_normal, tb.roots
    k = tb.face_object[f]
    flags = tb.obj_flags[k]
    if not (flags & (CUTOUT | NULL)) or si[r, S_CROSS] >= MAX_CROSSINGS:
        return False
    dx, dy, dz = sf[r, S_D], sf[r, S_D + 1], sf[r, S_D + 2]
    gx, gy, gz = face_normal[f, 0], face_normal[f, 1], face_normal[f, 2]
    front = _dot(dx, dy, dz, gx, gy, gz) < 0.0
    slot = 2 * k + (1 if (flags & TWO_FACED) and not front else 0)
    px, py, pz, nx, ny, nz, tx, ty, tz, _, _, _, _, _ = _attributes(
        tb.packed, tb.faces, face_normal, f, hb1, hb2)
    row = slot
    if v >= 0:
        nx, ny, nz = bf[v, 0], bf[v, 1], bf[v, 2]
        tx, ty, tz = bf[v, 3], bf[v, 4], bf[v, 5]
        opacity, entry_ior = bf[v, 6], bf[v, 7]
        slot, row = bslot[v], int(sc[SC_NCONST]) + v
    else:
        opacity, entry_ior = tb.obj_opacity[k], tb.obj_ior[k]
    c0, c1, c2 = sf[r, S_C], sf[r, S_C + 1], sf[r, S_C + 2]
    cross = si[r, S_CROSS]
    crossing = False
    if (flags & CUTOUT) and sample_pair(
            v1, ph, idx, SHADOW_PAIRS + (si[r, S_SEGMENT] << 8) + cross, kind)[0] >= opacity:
        pass  # cut: passes unchanged
    elif flags & NULL and roots[slot] >= 0:
        sx, sy, sz, qx, qy, qz = frame_from_normal_tangent(nx, ny, nz, tx, ty, tz)
        wox = -_dot(dx, dy, dz, sx, sy, sz)
        woy = -_dot(dx, dy, dz, qx, qy, qz)
        woz = -_dot(dx, dy, dz, nx, ny, nz)
        wix, wiy, wiz, pdf, w0, w1, w2, lobe = interpreter.sample(
            tb.code, tb.kids, tb.frames, params, tb.chat, row, ws, roots[slot],
            tb.frame_lo[slot], tb.frame_hi[slot], wox, woy, woz, ONE_MINUS_EPS, 0.0, 0.0,
            False)
        wx = wix * sx + wiy * qx + wiz * nx
        wy = wix * sy + wiy * qy + wiz * ny
        wz = wix * sz + wiy * qz + wiz * nz
        if not (lobe == SPECULAR_TRANSMISSION and _dot(wx, wy, wz, dx, dy, dz)
                > 1.0 - STRAIGHT_TOL):
            return False
        c0, c1, c2 = c0 * pdf * w0, c1 * pdf * w1, c2 * pdf * w2
        crossing = True
    else:
        return False
    if not (c0 > 0.0 or c1 > 0.0 or c2 > 0.0):
        return False
    if crossing and (flags & ENCLOSES):
        nstk = si[r, S_NSTK]
        if front:
            si[r, S_NSTK] = stack_push(sso, ssior, r, nstk, k, entry_ior)
        else:
            si[r, S_NSTK] = stack_pop(sso, ssior, r, nstk, k)
    side = 1.0 if _dot(dx, dy, dz, gx, gy, gz) >= 0.0 else -1.0
    sf[r, S_O], sf[r, S_O + 1], sf[r, S_O + 2] = (
        px + side * eps * gx, py + side * eps * gy, pz + side * eps * gz)
    cos = abs(_dot(gx, gy, gz, dx, dy, dz))
    sf[r, S_FAR] = max(sf[r, S_FAR] - t - eps * cos, 0.0)
    sf[r, S_LEAD] = _parallel_shift(eps, gx, gy, gz, dx, dy, dz)
    sf[r, S_C], sf[r, S_C + 1], sf[r, S_C + 2] = c0, c1, c2
    si[r, S_CROSS] = cross + 1
    return True


@njit
def resolve_shadows(scene, tb, m, sf, si, sso, ssior, lane_row, params, bf, bslot, L, nsf, nsi,
                    nso, nsior, pixel, index, seed, kind, v1, ws, es, counts):
    """:func:`_walk_shadow` for parked records ``0 .. m-1`` (their varying emission
    already multiplied in, ``S_FACE`` -1), record ``r`` bound by ``lane_row[r]`` for its
    pending hit.  Records that park again are copied to ``nsf``, ``nsi``, ``nso``,
    ``nsior``; returns their count."""
    nn = 0
    for r in range(m):
        lane = si[r, S_ID]
        if _walk_shadow(scene, tb, sf, si, sso, ssior, r, lane_row[r], params, bf, bslot, L, ws,
                        es, v1, pixel_hash(seed, pixel[lane]), index[lane], kind, counts):
            for c in range(sf.shape[1]):
                nsf[nn, c] = sf[r, c]
            for c in range(si.shape[1]):
                nsi[nn, c] = si[r, c]
            for c in range(sso.shape[1]):
                nso[nn, c], nsior[nn, c] = sso[r, c], ssior[r, c]
            nn += 1
    return nn
