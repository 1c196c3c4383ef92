"""The path tracer's compiled stages: every ray through Embree, every vertex in numba.

:class:`render.integrator.Integrator` runs a wavefront of path lanes per chunk of
samples through three kernels, with no Python between them unless a material's
arguments vary over the surface:

1. :func:`intersect`: each lane's next segment through Embree (``rtcIntersect1`` from
   :mod:`render.embree`).
2. :func:`bounce`: what happens on the segment and at its end, per lane: free-flight
   sampling in the lane's medium (spectral MIS over a hero channel), the environment on
   escape, and at a surface the cutout decision, emission (MIS against light
   sampling), alpha and AOVs, next-event estimation (a shadow record per lane and
   light sampled: the one :func:`select_light` picks, and each delta light when they
   are sampled at every vertex), the
   bsdf's sampled continuation, null crossings (index-matched or thin-walled straight
   transmission: no vertex), the stack of closed objects the path is inside (their
   media and IORs), and Russian roulette.  A scattering event in a medium is a vertex
   with next-event estimation through the phase function and a phase-sampled
   continuation.  Bsdfs are material programs run by :mod:`render.interpreter`.
3. :func:`shadow_trace` and :func:`shadow_resolve`: the shadow records' segments, to
   the light or through cutouts and null interfaces (entering and leaving media), each
   attenuated by the media it runs through; what reaches the light is added to the
   image.

Where an object's material varies over the surface (textures, noise, bump, a varying
cutout or emission), the integrator shades the lanes that hit it with numpy between
stages 1 and 2 (``material.shade``) and hands the kernels a parameter row, a shading
frame, an opacity, an IOR and an emitted radiance per lane ("bindings").  Lanes on
objects whose arguments are constant never leave the kernels.

Lane state lives in two arrays per lane (``lf`` floats, ``li`` integers; the column
constants below) and the stack of closed objects in ``so`` (object ids) and ``sior``
(their IORs).  Kernels return the lanes that go on, compacted in order.
"""

from __future__ import annotations

import math
from collections import namedtuple

import numpy as np

from render import embree, interpreter
from render.bsdf import Lobe
from render.df.anisotropic_vdf import eval_pdf as _phase_eval_pdf
from render.df.anisotropic_vdf import sample as _phase_sample
from render.jit import njit
from render.lights import INFINITE_DISTANCE
from render.program import LUM_B, LUM_G, LUM_R
from render.sky import sun_and_sky_eval, sun_and_sky_pdf, sun_and_sky_sample
from render.volume import (
    free_flight,
    stack_outside_ior,
    stack_pop,
    stack_push,
    transmittance,
)

__all__ = [
    "Tables",
    "intersect",
    "bounce",
    "shadow_trace",
    "shadow_resolve",
    "outside_ior",
    "sample_light",
    "select_light",
    "selection_pdf",
    "sample_lights",
    "selection",
    "escaped",
    "lane_count_columns",
]

INV_PI = 1.0 / np.pi
#: a lane may pass through at most this many cutout or null surfaces in a row
MAX_CROSSINGS = 64
#: a transmission counts as straight through (a null event) within this 1 - cos
STRAIGHT_TOL = 1e-9
ONE_MINUS_EPS = float(np.nextafter(1.0, 0.0))
SPECULAR = int(Lobe.SPECULAR)
SPECULAR_TRANSMISSION = int(Lobe.SPECULAR_TRANSMISSION)

# lane columns: lf (float64)
ORG, D, BETA, R, PREV_PDF, SEG, SHIFT = 0, 3, 6, 9, 12, 13, 14
# the previous vertex's position, normal (0 in a medium) and total light importance: the
# light-selection probability of an emitter a bsdf-sampled path hits (MIS)
PREV_P, PREV_N, PREV_SUM = 15, 18, 21
NF = 22
# li (int64)
ID, DEPTH, DELTA, FIRST, CROSS, HERO, NSTK = 0, 1, 2, 3, 4, 5, 6
NI = 7
# shadow records: sf (float64), si (int64)
S_O, S_D, S_FAR, S_LEAD, S_TAIL, S_C, S_BARY = 0, 3, 6, 7, 8, 9, 12
NSF = 15
S_ID, S_FACE, S_NSTK, S_CROSS = 0, 1, 2, 3
NSI = 4
# AOV columns
A_ALBEDO, A_NORMAL, A_DEPTH, A_UV, A_OBJECT = 0, 3, 6, 7, 9
NA = 10

#: object flags
CUTOUT, NULL, ENCLOSES, TWO_FACED, EMIT_CONST = 1, 2, 4, 8, 16

#: ``light_kind``
AREA, ENVIRONMENT, POINT, SPOT, DIRECTIONAL, ENVIRONMENT_MAP, SUN_AND_SKY = 0, 1, 2, 3, 4, 5, 6
#: ``[render] light_selection`` (``scalars[SC_SELECT]``)
UNIFORM, POWER, CONTRIBUTION = 0, 1, 2
SELECTIONS = {"uniform": UNIFORM, "power": POWER, "contribution": CONTRIBUTION}
#: added to the mode: every delta light is sampled at every vertex, outside the selection
EVERY_DELTA = 4
#: at most this many delta lights are sampled at every vertex (more: selected)
MAX_EVERY_DELTA = 4
#: ``light_bounds`` columns: bounding-sphere centre and radius, emission cone axis and
#: cos of its half-angle (area lights; -1: no cone), intensity (the importance's
#: numerator, see :func:`_importance`), power (pbrt's ``PowerLightSampler``), and the
#: number of lights below (1 for a light, more for a node of the light tree)
LB_C, LB_R, LB_AXIS, LB_COS, LB_I, LB_PHI, LB_N = 0, 3, 4, 7, 8, 9, 10
NLB = 11
#: the cosine at the receiver never counts less than this in a light's importance: the
#: shading normal is not the geometric one, so "perpendicular" is no proof of "black"
COS_FLOOR = 0.02
#: an importance is clamped here so that a sum of many never overflows
MAX_IMPORTANCE = 1e250

#: Scene tables of the kernels (float64 unless noted).
Tables = namedtuple(
    "Tables",
    [
        "packed",  # (v, 14) positions, normals, tangent_u, tangent_v, uv per vertex
        "faces",  # (f, 3) int64
        "face_normal",  # (f, 3) unit, on the side of the vertex normals
        "face_object",  # (f,) int64
        "face_offset",  # (k + 1,) int64 first triangle of each object (Embree geomID)
        "code",  # the bsdf programs of the shading slots (render.program.ProgramTable):
        "kids",  # slot 2k is object k's front, 2k + 1 its back
        "frames",
        "chat",
        "roots",  # (2k,) root node of each slot's program, -1: black
        "frame_lo",
        "frame_hi",
        "obj_flags",  # (k,) int64 CUTOUT | NULL | ENCLOSES | TWO_FACED | EMIT_CONST
        "obj_opacity",  # (k,) constant cutout opacity
        "obj_ior",  # (k,) constant IOR (mean over channels)
        "obj_medium",  # (k,) int64 medium of the inside, -1: none
        "emit_hit",  # (k, 3) radiance seen on the front of a constant diffuse emitter
        "emit_light",  # (k, 3) radiance of its light samples
        "face_light",  # (f,) int64 the area light (group) of each emissive triangle, -1: none
        "medium",  # (m, 9) sigma_a, sigma_s, sigma_t per channel
        "phase",  # (m, w) anisotropic_vdf rows of the media's phase functions
        "light_kind",  # (l,) int64
        "light_object",  # (l,) int64 object of each area light, -1 for the others
        "light_params",  # (l, 11) position, direction, intensity, cos cutoff, cos width
        "light_first",  # (l + 1,) int64 range of each light's triangles in light_faces
        "light_faces",  # (t,) int64 emissive triangles
        "light_cdf",  # (t,) area cdf within each light
        "light_corners",  # (t, 3, 3) their corners
        "light_pdf_area",  # (l,) 1 / area
        "light_bounds",  # (l + nodes, NLB) what a light (or a node of the light tree) can
        # contribute (LB_* columns)
        "light_tree",  # (l + nodes, 3) int64 parent, child a, child b (-1: none)
        "env",  # (3,) constant environment radiance
        "env_image",  # (h, w, 3) environment map radiance
        "env_p",  # (h * w,) its texels' probabilities
        "env_cdf",  # (h * w,)
        "sky",  # sun-and-sky parameters (render.sky.SunAndSky.kernel_params)
        "sky_p",
        "sky_cdf",
        "scalars",  # (12,) see SC_* below
    ],
)
SC_SELECT, SC_EPS, SC_MAX_DEPTH, SC_RR_DEPTH, SC_ENV, SC_ROT_C, SC_ROT_S = 0, 1, 2, 3, 4, 5, 6
SC_MEDIA, SC_AOV, SC_CAM = 7, 8, 9  # media present, AOVs asked for, camera position (9..11)
SC_FWD = 12  # camera forward (12..14)
SC_ENV_LIGHT = 15  # index of the environment light, -1: none
N_SCALARS = 16


def lane_count_columns():
    """``(NF, NI, NSF, NSI, NA)``: columns of the lane, shadow-record and AOV arrays."""
    return NF, NI, NSF, NSI, NA


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


@njit
def _fast_unit(x, y, z):
    """(ux, uy, uz, valid); vectors shorter than 1e-150 are left as they are."""
    length = math.sqrt(x * x + y * y + z * z)
    if length > 1e-150:
        return x / length, y / length, z / length, True
    return x, y, z, False


@njit
def _unitize(x, y, z):
    """A unit vector robust to under- and overflow: (ux, uy, uz, valid)."""
    scale = max(max(abs(x), abs(y)), abs(z))
    if not scale > 1e-300:
        return 0.0, 0.0, 0.0, False
    wx, wy, wz = x / scale, y / scale, z / scale
    length = math.sqrt(wx * wx + wy * wy + wz * wz)
    return wx / length, wy / length, wz / length, True


@njit
def _frame(nx, ny, nz, tx, ty, tz):
    """The shading frame's (s, t) from a unit normal and a tangent (Gram–Schmidt; Duff
    et al.'s frame where the tangent is missing or parallel)."""
    c = _dot(tx, ty, tz, nx, ny, nz)
    px, py, pz = tx - c * nx, ty - c * ny, tz - c * nz
    sx, sy, sz, ok = _unitize(px, py, pz)
    ok = ok and math.sqrt(px * px + py * py + pz * pz) > 1e-8 * math.sqrt(
        tx * tx + ty * ty + tz * tz)
    if not ok:
        sign = 1.0 if nz >= 0.0 else -1.0
        a = -1.0 / (sign + nz)
        b = nx * ny * a
        sx, sy, sz = 1.0 + sign * nx * nx * a, sign * b, -sign * nx
    return sx, sy, sz, ny * sz - nz * sy, nz * sx - nx * sz, nx * sy - ny * sx


@njit
def _search_right(cdf, a, b, u):
    """``a + searchsorted(cdf[a:b], u, side="right")``, clipped to ``b - 1``."""
    lo, hi = a, b
    while lo < hi:
        mid = (lo + hi) // 2
        if cdf[mid] <= u:
            lo = mid + 1
        else:
            hi = mid
    return min(lo, b - 1)


@njit
def _environment_map(image, p, rot_c, rot_s, dx, dy, dz):
    """A latitude-longitude map's (solid-angle pdf, radiance rgb) along ``d``."""
    h, w = image.shape[0], image.shape[1]
    x = rot_c * dx - rot_s * dz
    z = rot_s * dx + rot_c * dz
    u = 0.5 + math.atan2(x, -z) / (2.0 * np.pi)
    v = math.acos(min(max(dy, -1.0), 1.0)) / np.pi
    i = min(max(int(u * w), 0), w - 1)
    j = min(max(int(v * h), 0), h - 1)
    sin_t = math.sin(np.pi * v)
    pdf = p[j * w + i] * h * w / (2.0 * np.pi * np.pi * sin_t) if sin_t > 1e-12 else 0.0
    return pdf, image[j, i, 0], image[j, i, 1], image[j, i, 2]


@njit
def _environment(sc, env, env_image, env_p, sky, sky_p, dx, dy, dz):
    """Radiance along an escaping direction and the pdf of sampling it once the
    environment is selected: (pdf, r, g, b)."""
    kind = sc[SC_ENV]
    if kind == ENVIRONMENT:
        return 0.25 / np.pi, env[0], env[1], env[2]
    if kind == ENVIRONMENT_MAP:
        pe, e0, e1, e2 = _environment_map(env_image, env_p, sc[SC_ROT_C], sc[SC_ROT_S],
                                          dx, dy, dz)
        return pe, e0, e1, e2
    if kind == SUN_AND_SKY:
        e0, e1, e2 = sun_and_sky_eval(sky, dx, dy, dz)
        return sun_and_sky_pdf(sky, sky_p, dx, dy, dz), e0, e1, e2
    return 0.0, 0.0, 0.0, 0.0


@njit(inline="always")
def _is_delta(kind):
    return kind == POINT or kind == SPOT or kind == DIRECTIONAL


@njit(inline="always")
def _next_delta(light_kind, j):
    """The first delta light after light ``j`` (-1: none)."""
    for k in range(j + 1, len(light_kind)):
        if _is_delta(light_kind[k]):
            return k
    return -1


@njit(inline="always")
def _spot_falloff(lp, j, c):
    """Spot ``j``'s falloff at cosine ``c`` from its axis: smoothstep between the cosines
    of the cutoff and the beam width, 0 outside the cutoff."""
    span = lp[j, 10] - lp[j, 9]
    if span <= 0.0:
        return 1.0 if c >= lp[j, 9] else 0.0
    t = min(max((c - lp[j, 9]) / span, 0.0), 1.0)
    return t * t * (3.0 - 2.0 * t)


#: real spherical harmonics of bands 0-2 at unit (x, y, z), and the cosine lobe's band
#: factors pi, 2 pi / 3, pi / 4 (Ramamoorthi and Hanrahan 2001, "An efficient
#: representation for irradiance environment maps")
SH_BANDS = np.array([np.pi] + [2.0 * np.pi / 3.0] * 3 + [np.pi / 4.0] * 5)
SH_Y00 = 0.5 / math.sqrt(math.pi)
_SH_Y1 = math.sqrt(3.0 / (4.0 * math.pi))
_SH_Y2 = math.sqrt(15.0 / (4.0 * math.pi))
_SH_Y20 = math.sqrt(5.0 / (16.0 * math.pi))
_SH_Y22 = math.sqrt(15.0 / (16.0 * math.pi))


@njit(inline="always")
def _sh_basis(x, y, z):
    """The nine real spherical harmonics of bands 0-2 at the unit vector (x, y, z)."""
    return (SH_Y00, _SH_Y1 * y, _SH_Y1 * z, _SH_Y1 * x, _SH_Y2 * x * y, _SH_Y2 * y * z,
            _SH_Y20 * (3.0 * z * z - 1.0), _SH_Y2 * x * z, _SH_Y22 * (x * x - y * y))


@njit(inline="always")
def _sh9(x, y, z, c, s):
    """sum_k c[s, k] Y_k(x, y, z) over the nine harmonics of :func:`_sh_basis`."""
    b = _sh_basis(x, y, z)
    return (c[s, 0] * b[0] + c[s, 1] * b[1] + c[s, 2] * b[2] + c[s, 3] * b[3]
            + c[s, 4] * b[4] + c[s, 5] * b[5] + c[s, 6] * b[6] + c[s, 7] * b[7]
            + c[s, 8] * b[8])


@njit(allocates=True)
def environment_sh(tb, j, u):
    """(9,) the irradiance of environment light ``j`` as harmonics of bands 0-2: its
    luminance projected by the light's own importance samples (``u`` (n, 2) uniforms),
    times :data:`SH_BANDS`; :func:`_sh9` of them at a normal n is the cosine-weighted
    radiance over the hemisphere around n, smoothed to three bands."""
    out = np.zeros(9)
    n = len(u)
    for i in range(n):
        wx, wy, wz, _, l0, l1, l2, pdf, _, _, _, _, _ = sample_light(
            tb.light_kind, tb.light_params, tb.light_first, tb.light_cdf, tb.light_corners,
            tb.light_faces, tb.light_pdf_area, tb.light_object, tb.obj_flags, tb.emit_light,
            tb.face_normal, tb.env, tb.env_image, tb.env_p, tb.env_cdf, tb.sky, tb.sky_p,
            tb.sky_cdf, tb.scalars, j, 0.0, 0.0, 0.0, u[i, 0], u[i, 1])
        if not pdf > 0.0:
            continue
        lum = (LUM_R * l0 + LUM_G * l1 + LUM_B * l2) / (pdf * n)
        b = _sh_basis(wx, wy, wz)
        for k in range(9):
            out[k] += lum * b[k]
    for k in range(9):
        out[k] *= SH_BANDS[k]
    return out


@njit
def _importance(light_kind, light_bounds, light_params, mode, j, px, py, pz, nx, ny, nz):
    """How much light ``j`` may contribute at p with normal n (n = 0: a point in a
    medium), up to a common factor: the weight by which :func:`select_light` picks it.

    ``mode`` UNIFORM: 1; POWER: the light's power (pbrt-v4's ``PowerLightSampler``);
    CONTRIBUTION: a bound on the irradiance at p (pbrt-v4's ``LightBounds::Importance``
    for one light): intensity / d^2 (d from the light's bounding sphere, at least its
    radius) times the cosine at the emitter bounded over its emission cone and bounding
    sphere (0 only where p is behind every triangle of a one-sided emitter, or outside a
    spot's cutoff: where the light gives nothing) times the bounded cosine at the
    receiver (at least COS_FLOOR).  Directional lights: irradiance times that cosine;
    environments: their irradiance at the normal from three bands of spherical harmonics
    (:func:`environment_sh`, kept in ``light_params[j, 0:9]``), at least COS_FLOOR of pi
    times their mean radiance (4 pi times it in a medium).

    ``mode + EVERY_DELTA``: the same, delta lights 0 (each is sampled at every vertex,
    outside the selection)."""
    lb = light_bounds
    kind = light_kind[j]
    if mode >= EVERY_DELTA:
        if _is_delta(kind):
            return 0.0
        mode -= EVERY_DELTA
    if mode == UNIFORM:
        return 1.0
    if mode == POWER:
        return min(lb[j, LB_PHI], MAX_IMPORTANCE)
    intensity = lb[j, LB_I]
    if not intensity > 0.0:
        return 0.0
    surface = nx != 0.0 or ny != 0.0 or nz != 0.0
    if kind == ENVIRONMENT or kind == ENVIRONMENT_MAP or kind == SUN_AND_SKY:
        if not surface:
            return 4.0 * intensity
        return max(_sh9(nx, ny, nz, light_params, j), COS_FLOOR * intensity)
    if kind == DIRECTIONAL:
        cos_i = abs(_dot(nx, ny, nz, light_params[j, 3], light_params[j, 4],
                         light_params[j, 5])) if surface else 1.0
        return intensity * max(cos_i, COS_FLOOR)
    if kind == SPOT:  # a point: its falloff exactly
        wx, wy, wz, ok = _unitize(px - lb[j, LB_C], py - lb[j, LB_C + 1], pz - lb[j, LB_C + 2])
        falloff = _spot_falloff(light_params, j, _dot(wx, wy, wz, light_params[j, 3],
                                                      light_params[j, 4], light_params[j, 5]))
        if not falloff > 0.0:
            return 0.0
        return falloff * _bound_importance(lb, j, intensity, px, py, pz, nx, ny, nz, False)
    return _bound_importance(lb, j, intensity, px, py, pz, nx, ny, nz, kind == AREA)


@njit
def _bound_importance(lb, j, intensity, px, py, pz, nx, ny, nz, cone):
    """The contribution bound of :func:`_importance` for row ``j`` of ``lb`` (a light or
    a node of the light tree): ``intensity`` / d^2 from its bounding sphere, times the
    emitter's cosine bounded by its emission cone (``cone`` and the row has one) and
    sphere, times the receiver's cosine bounded the same way."""
    vx, vy, vz = px - lb[j, LB_C], py - lb[j, LB_C + 1], pz - lb[j, LB_C + 2]
    r = lb[j, LB_R]
    d2 = vx * vx + vy * vy + vz * vz
    wx, wy, wz, ok = _unitize(vx, vy, vz)
    inside = d2 <= r * r or not ok
    surface = nx != 0.0 or ny != 0.0 or nz != 0.0
    # sin and cos of the half-angle the bounding sphere subtends at p
    sin_b = 1.0 if inside else min(r / math.sqrt(d2), 1.0)
    cos_b = math.sqrt(max(1.0 - sin_b * sin_b, 0.0))
    cos_e = 1.0
    if cone and not inside and lb[j, LB_COS] > -1.0:
        # cos theta', theta' = max(0, theta_w - theta_o - theta_b): 0 (p behind) below
        # -1e-6, a margin for rounding
        cw = min(max(_dot(wx, wy, wz, lb[j, LB_AXIS], lb[j, LB_AXIS + 1], lb[j, LB_AXIS + 2]),
                     -1.0), 1.0)
        co = lb[j, LB_COS]
        c = 1.0
        if cw < co:  # theta_w > theta_o: cos and sin of theta_w - theta_o
            sw, so = math.sqrt(max(1.0 - cw * cw, 0.0)), math.sqrt(max(1.0 - co * co, 0.0))
            cx, sx = cw * co + sw * so, sw * co - cw * so
            if cx < cos_b:  # beyond theta_b too
                c = cx * cos_b + sx * sin_b
        if c < -1e-6:
            return 0.0
        cos_e = max(c, COS_FLOOR)
    cos_i = 1.0
    if surface and not inside:
        c = abs(_dot(wx, wy, wz, nx, ny, nz))  # cos(theta_i), theta_i - theta_b bounded
        s = math.sqrt(max(1.0 - c * c, 0.0))
        cos_i = 1.0 if c >= cos_b else c * cos_b + s * sin_b
        cos_i = max(cos_i, COS_FLOOR)
    d2 = max(d2, r * r, 1e-300)
    return min(intensity * cos_e * cos_i / d2, MAX_IMPORTANCE)


@njit
def _node_importance(lb, mode, r, px, py, pz, nx, ny, nz):
    """:func:`_importance` for node ``r`` of the light tree (a row of ``lb`` after the
    lights'): the number of its lights, their power, or the bound of their merged
    bounding sphere and emission cone on the sum of their intensities (pbrt-v4's
    ``LightBounds`` of a ``BVHLightSampler`` node)."""
    if mode >= EVERY_DELTA:
        mode -= EVERY_DELTA
    if mode == UNIFORM:
        return lb[r, LB_N]
    if mode == POWER:
        return min(lb[r, LB_PHI], MAX_IMPORTANCE)
    if not lb[r, LB_I] > 0.0:
        return 0.0
    return _bound_importance(lb, r, lb[r, LB_I], px, py, pz, nx, ny, nz, True)


@njit(inline="always")
def _weight(light_kind, light_bounds, light_params, mode, x, px, py, pz, nx, ny, nz):
    """The importance of light ``x``, or of node ``x`` of the light tree (x >= lights)."""
    if x < len(light_kind):
        return _importance(light_kind, light_bounds, light_params, mode, x, px, py, pz, nx,
                           ny, nz)
    return _node_importance(light_bounds, mode, x, px, py, pz, nx, ny, nz)


@njit
def select_light(light_kind, light_bounds, light_params, light_tree, mode, px, py, pz, nx, ny,
                 nz, u):
    """One light for next-event estimation at p (normal n, 0 in a medium), in proportion
    to :func:`_importance`: (light, its probability, the total importance at the top),
    light -1 (probability 0) where no light can contribute.

    The top is every light outside the light tree (environments, directional lights,
    a lone area light) and the tree's root (row ``lights`` of ``light_bounds``, if the
    scene has one): one pass over them, last to first (a reservoir of one, the uniform
    ``u`` rescaled at each: with two lights ``u < p_0`` picks the first).  From the
    root the walk goes down ``light_tree`` (parent, child a, child b per row), picking
    a child in proportion to its importance, as pbrt-v4's ``BVHLightSampler`` does:
    O(log lights) per vertex."""
    n_lights = len(light_kind)
    top = n_lights + 1 if light_bounds.shape[0] > n_lights else n_lights
    total = 0.0
    chosen, w = -1, 0.0
    for x in range(top - 1, -1, -1):  # keep x with probability w_x / total so far
        if x < n_lights and light_tree[x, 0] >= 0:
            continue  # under the root
        wx = _weight(light_kind, light_bounds, light_params, mode, x, px, py, pz, nx, ny, nz)
        if not wx > 0.0:
            continue
        total += wx
        q = wx / total
        if u < q:
            chosen, w = x, wx
            u = min(u / q, ONE_MINUS_EPS)
        else:
            u = min((u - q) / (1.0 - q), ONE_MINUS_EPS) if q < 1.0 else 0.0
    if not (total > 0.0 and total < np.inf):
        return -1, 0.0, 0.0
    pr = w / total
    x = chosen
    while x >= n_lights:  # down the tree
        a, b = light_tree[x, 1], light_tree[x, 2]
        wa = _weight(light_kind, light_bounds, light_params, mode, a, px, py, pz, nx, ny, nz)
        wb = _weight(light_kind, light_bounds, light_params, mode, b, px, py, pz, nx, ny, nz)
        s = wa + wb
        if not (s > 0.0 and s < np.inf):
            return -1, 0.0, total
        q = wa / s
        if u < q:
            x, pr = a, pr * q
            u = min(u / q, ONE_MINUS_EPS)
        else:
            x, pr = b, pr * (wb / s)
            u = min((u - q) / (1.0 - q), ONE_MINUS_EPS) if q < 1.0 else 0.0
    return x, pr, total


@njit
def selection_pdf(light_kind, light_bounds, light_params, light_tree, mode, j, total, px, py,
                  pz, nx, ny, nz):
    """The probability that :func:`select_light` at p (normal n), whose top importances
    sum to ``total``, picks light ``j`` (0 for ``j < 0``): up the tree from ``j``, the
    product of each step's share, times the top's share."""
    if j < 0 or not total > 0.0:
        return 0.0
    pr = 1.0
    x = j
    parent = light_tree[x, 0]
    while parent >= 0:
        a, b = light_tree[parent, 1], light_tree[parent, 2]
        wa = _weight(light_kind, light_bounds, light_params, mode, a, px, py, pz, nx, ny, nz)
        wb = _weight(light_kind, light_bounds, light_params, mode, b, px, py, pz, nx, ny, nz)
        s = wa + wb
        if not s > 0.0:
            return 0.0
        pr *= (wa if x == a else wb) / s
        x, parent = parent, light_tree[parent, 0]
    return pr * _weight(light_kind, light_bounds, light_params, mode, x, px, py, pz, nx, ny,
                        nz) / total


@njit
def sample_light(light_kind, light_params, light_first, light_cdf, light_corners, light_faces,
                  light_pdf_area, light_object, obj_flags, emit_light, face_normal, env,
                  env_image, env_p, env_cdf, sky, sky_p, sky_cdf, scalars, j, px, py, pz, u1,
                  u2):
    """Light ``j`` sampled from p: (wi xyz, distance, radiance rgb, pdf, delta, face,
    b0, b1, b2).  ``pdf`` is the density once ``j`` is selected (delta lights: 1; the
    caller multiplies by the selection probability, :func:`select_light`);
    ``face >= 0`` marks an area light whose radiance varies over it (radiance returned
    as 1: the integrator evaluates it at ``face`` and the barycentrics ``b``).

    Takes the scene's arrays one by one (:data:`Tables`): an array taken out of a tuple
    costs numba two atomic reference counts, which per lane cost more than the work."""
    if j < 0:  # a scene without lights, or none that can contribute
        return 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 0.0, 0.0, False, -1, 0.0, 0.0, 0.0
    kind = light_kind[j]
    if kind == ENVIRONMENT:  # uniform sphere
        z = 1.0 - 2.0 * u1
        r = 2.0 * math.sqrt(max(u1 * (1.0 - u1), 0.0))
        phi = 2.0 * np.pi * u2
        e = env
        return (r * math.cos(phi), r * math.sin(phi), z, INFINITE_DISTANCE, e[0], e[1], e[2],
                0.25 / np.pi, False, -1, 0.0, 0.0, 0.0)
    if kind == ENVIRONMENT_MAP:  # a texel by its cdf
        image, cdf = env_image, env_cdf
        rot_c, rot_s = scalars[SC_ROT_C], scalars[SC_ROT_S]
        h, w = image.shape[0], image.shape[1]
        k = _search_right(cdf, 0, len(cdf), u1)
        lo = cdf[k - 1] if k > 0 else 0.0
        pk = env_p[k]
        du = min(max((u1 - lo) / pk if pk > 0 else 0.5, 0.0), 1.0)
        row, col = k // w, k % w
        phi = ((col + du) / w - 0.5) * 2.0 * np.pi
        theta = (row + u2) / h * np.pi
        st = math.sin(theta)
        x, z = st * math.sin(phi), -st * math.cos(phi)
        wx, wy, wz = rot_c * x + rot_s * z, math.cos(theta), -rot_s * x + rot_c * z
        pdf, e0, e1, e2 = _environment_map(image, env_p, rot_c, rot_s, wx, wy, wz)
        if not pdf > 0.0:
            e0 = e1 = e2 = 0.0
        return wx, wy, wz, INFINITE_DISTANCE, e0, e1, e2, pdf, False, -1, 0.0, 0.0, 0.0
    if kind == SUN_AND_SKY:
        wx, wy, wz = sun_and_sky_sample(sky, sky_p, sky_cdf, u1, u2)
        pdf = sun_and_sky_pdf(sky, sky_p, wx, wy, wz)
        e0 = e1 = e2 = 0.0
        if pdf > 0.0:
            e0, e1, e2 = sun_and_sky_eval(sky, wx, wy, wz)
        return wx, wy, wz, INFINITE_DISTANCE, e0, e1, e2, pdf, False, -1, 0.0, 0.0, 0.0
    lp = light_params
    if kind == DIRECTIONAL:
        return (-lp[j, 3], -lp[j, 4], -lp[j, 5], INFINITE_DISTANCE, lp[j, 6], lp[j, 7],
                lp[j, 8], 1.0, True, -1, 0.0, 0.0, 0.0)
    if kind != AREA:  # point, or spot with a smoothstep falloff in the cosine
        dx, dy, dz = lp[j, 0] - px, lp[j, 1] - py, lp[j, 2] - pz
        dist = math.sqrt(dx * dx + dy * dy + dz * dz)
        wx, wy, wz, ok = _unitize(dx, dy, dz)
        if not (ok and dist > 0.0):
            return wx, wy, wz, dist, 0.0, 0.0, 0.0, 0.0, True, -1, 0.0, 0.0, 0.0
        scale = 1.0 / (dist * dist)
        if kind == SPOT:
            scale = scale * _spot_falloff(lp, j, _dot(-wx, -wy, -wz, lp[j, 3], lp[j, 4],
                                                      lp[j, 5]))
        return (wx, wy, wz, dist, scale * lp[j, 6], scale * lp[j, 7], scale * lp[j, 8], 1.0,
                True, -1, 0.0, 0.0, 0.0)
    # an emissive object: a triangle by area, a uniform point on it
    a, b = light_first[j], light_first[j + 1]
    cdf = light_cdf
    t = _search_right(cdf, a, b, u1)
    lo = cdf[t - 1] if t > a else 0.0
    width = cdf[t] - lo
    u0 = min(max((u1 - lo) / width if width > 0 else 0.5, 0.0), 1.0)
    su = math.sqrt(max(u0, 0.0))
    b1 = 1.0 - su
    b2 = u2 * su
    b0 = 1.0 - b1 - b2
    c = light_corners
    xx = b0 * c[t, 0, 0] + b1 * c[t, 1, 0] + b2 * c[t, 2, 0]
    xy = b0 * c[t, 0, 1] + b1 * c[t, 1, 1] + b2 * c[t, 2, 1]
    xz = b0 * c[t, 0, 2] + b1 * c[t, 1, 2] + b2 * c[t, 2, 2]
    dx, dy, dz = xx - px, xy - py, xz - pz
    dist = math.sqrt(dx * dx + dy * dy + dz * dz)
    wx, wy, wz, ok = _unitize(dx, dy, dz)
    f = light_faces[t]
    fn = face_normal
    gx, gy, gz = fn[f, 0], fn[f, 1], fn[f, 2]
    cos_l = abs(_dot(wx, wy, wz, gx, gy, gz))
    if not (ok and dist > 0.0 and cos_l > 1e-12):
        return wx, wy, wz, dist, 0.0, 0.0, 0.0, 0.0, False, -1, 0.0, 0.0, 0.0
    pdf = dist * dist / cos_l * light_pdf_area[j]
    obj = light_object[j]
    if not (obj_flags[obj] & EMIT_CONST):
        return wx, wy, wz, dist, 1.0, 1.0, 1.0, pdf, False, f, b0, b1, b2
    if _dot(-wx, -wy, -wz, gx, gy, gz) > 0.0:  # emitters light their front side
        e = emit_light
        return wx, wy, wz, dist, e[obj, 0], e[obj, 1], e[obj, 2], pdf, False, -1, 0.0, 0.0, 0.0
    return wx, wy, wz, dist, 0.0, 0.0, 0.0, pdf, False, -1, 0.0, 0.0, 0.0


@njit(allocates=True)
def sample_lights(tb, p, u):
    """:func:`sample_light` for points ``p`` (n, 3) in a medium (no normal) with
    uniforms ``u`` (n, 3): the light chosen by ``u[:, 0]`` as :func:`bounce` chooses it,
    sampled with ``u[:, 1:]``.

    Returns ``wi`` (n, 3), distance (n,), radiance (n, 3), pdf (n,) (selection
    included), delta (n,) bool and the varying-emission face (n,) (-1: none)."""
    n = len(p)
    wi, dist, li, pdf = np.empty((n, 3)), np.empty(n), np.empty((n, 3)), np.empty(n)
    delta, face = np.empty(n, dtype=np.bool_), np.empty(n, dtype=np.int64)
    mode = int(tb.scalars[SC_SELECT])
    for i in range(n):
        j, sel, _ = select_light(tb.light_kind, tb.light_bounds, tb.light_params, tb.light_tree,
                                 mode, p[i, 0], p[i, 1], p[i, 2], 0.0, 0.0, 0.0, u[i, 0])
        (wi[i, 0], wi[i, 1], wi[i, 2], dist[i], li[i, 0], li[i, 1], li[i, 2], pdf[i], delta[i],
         face[i], _, _, _) = sample_light(
            tb.light_kind, tb.light_params, tb.light_first, tb.light_cdf, tb.light_corners,
            tb.light_faces, tb.light_pdf_area, tb.light_object, tb.obj_flags, tb.emit_light,
            tb.face_normal, tb.env, tb.env_image, tb.env_p, tb.env_cdf, tb.sky, tb.sky_p,
            tb.sky_cdf, tb.scalars, j, p[i, 0], p[i, 1], p[i, 2], u[i, 1], u[i, 2])
        pdf[i] *= sel
    return wi, dist, li, pdf, delta, face


@njit(allocates=True)
def selection(tb, p, nrm):
    """(n, lights) the probability that next-event estimation at points ``p`` (n, 3)
    with normals ``nrm`` (n, 3; 0: in a medium) picks each light (:func:`select_light`)."""
    n, n_lights = len(p), len(tb.light_kind)
    out = np.zeros((n, n_lights))
    mode = int(tb.scalars[SC_SELECT])
    for i in range(n):
        _, _, total = select_light(tb.light_kind, tb.light_bounds, tb.light_params, tb.light_tree,
                                   mode, p[i, 0], p[i, 1], p[i, 2], nrm[i, 0], nrm[i, 1],
                                   nrm[i, 2], 0.5)
        for j in range(n_lights):
            out[i, j] = selection_pdf(tb.light_kind, tb.light_bounds, tb.light_params,
                                      tb.light_tree, mode, j, total, p[i, 0], p[i, 1], p[i, 2],
                                      nrm[i, 0], nrm[i, 1], nrm[i, 2])
    return out


@njit(allocates=True)
def escaped(tb, d):
    """What a path sees along unit directions ``d`` (n, 3) that leave the scene: the
    pdf with which the environment, once selected, samples them (n,) and the radiance
    (n, 3)."""
    n = len(d)
    pdf, li = np.empty(n), np.empty((n, 3))
    sc, env, env_image, env_p, sky, sky_p = (tb.scalars, tb.env, tb.env_image, tb.env_p, tb.sky,
                                             tb.sky_p)
    for i in range(n):
        pdf[i], li[i, 0], li[i, 1], li[i, 2] = _environment(sc, env, env_image, env_p, sky, sky_p,
                                                            d[i, 0], d[i, 1], d[i, 2])
    return pdf, li


# ------------------------------------------------------- the stack of closed objects
@njit(allocates=True)
def outside_ior(so, sior, nstk, objs):
    """(n,) the IOR around object ``objs[i]`` for stack rows ``i`` (for the bindings)."""
    out = np.ones(len(objs))
    for i in range(len(objs)):
        out[i] = stack_outside_ior(so, sior, i, nstk[i], objs[i])
    return out


@njit(inline="always")
def _copy_row(src, i, dst, j):
    for c in range(src.shape[1]):
        dst[j, c] = src[i, c]


@njit(inline="always")
def _copy_lane(a, b, c, d, i, na, nb, nc, nd, j):
    """Row ``i`` of four per-lane arrays to row ``j`` of four others."""
    _copy_row(a, i, na, j)
    _copy_row(b, i, nb, j)
    _copy_row(c, i, nc, j)
    _copy_row(d, i, nd, j)


@njit(inline="always")
def _set_prev(lf, i, px, py, pz, nx, ny, nz, total):
    """Lane ``i`` leaves a vertex at p (normal n, 0 in a medium) whose light importances
    sum to ``total``."""
    lf[i, PREV_P], lf[i, PREV_P + 1], lf[i, PREV_P + 2] = px, py, pz
    lf[i, PREV_N], lf[i, PREV_N + 1], lf[i, PREV_N + 2] = nx, ny, nz
    lf[i, PREV_SUM] = total


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
    nx, ny, nz, ok = _fast_unit(
        w0 * tp[v0, 3] + w1 * tp[v1, 3] + w2 * tp[v2, 3],
        w0 * tp[v0, 4] + w1 * tp[v1, 4] + w2 * tp[v2, 4],
        w0 * tp[v0, 5] + w1 * tp[v1, 5] + w2 * tp[v2, 5],
    )
    if not ok:
        nx, ny, nz = face_normal[f, 0], face_normal[f, 1], face_normal[f, 2]
    tx, ty, tz, _ = _fast_unit(
        w0 * tp[v0, 6] + w1 * tp[v1, 6] + w2 * tp[v2, 6],
        w0 * tp[v0, 7] + w1 * tp[v1, 7] + w2 * tp[v2, 7],
        w0 * tp[v0, 8] + w1 * tp[v1, 8] + w2 * tp[v2, 8],
    )
    bx, by, bz, _ = _fast_unit(
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
    """The interpreter's scratch for the programs of ``tb`` (one per thread and stage
    call: the kernels own no memory, so they count no references)."""
    return np.empty(interpreter.work_size(len(tb.code), len(tb.kids), len(tb.frames)))


# -------------------------------------------------------------------- stage 1
@njit
def intersect(scene, tb, lf, n, face, b1, b2, t):
    """First hits of lanes ``0 .. n-1`` (origins ``lf[:, ORG]``, directions ``lf[:, D]``):
    global triangle (-1: none), barycentrics and distance."""
    scratch = embree.new_scratch()
    off = tb.face_offset
    for i in range(n):
        h = embree.intersect1(scene, lf[i, ORG], lf[i, ORG + 1], lf[i, ORG + 2], lf[i, D],
                              lf[i, D + 1], lf[i, D + 2], 0.0, np.inf, scratch)
        if h[4] == embree.MISS:
            face[i] = -1
        else:
            face[i] = off[h[4]] + h[3]
            b1[i], b2[i], t[i] = h[1], h[2], h[0]


# -------------------------------------------------------------------- stage 2
@njit(inline="always")
def _shadow_record(eps, sf, si, sso, ssior, ns, so, sior, i, nstk, lane, px, py, pz,
                   gx, gy, gz, lx, ly, lz, ldist, c0, c1, c2, face, bary0, bary1, bary2,
                   offset, shift_in):
    """Append a shadow ray from p toward the light sample; ``offset``: push the origin
    off the surface (normal ``g``) on the light's side, else start at p (in a medium).
    Returns the new count."""
    qx, qy, qz = px, py, pz
    if offset:
        side = 1.0 if _dot(lx, ly, lz, gx, gy, gz) >= 0.0 else -1.0
        qx, qy, qz = px + side * eps * gx, py + side * eps * gy, pz + side * eps * gz
    finite = ldist < INFINITE_DISTANCE
    if finite:  # aim from the offset origin at the light point itself
        tx, ty, tz = px + lx * ldist, py + ly * ldist, pz + lz * ldist
        ex, ey, ez = tx - qx, ty - qy, tz - qz
        ux, uy, uz, ok = _unitize(ex, ey, ez)
        if not ok:
            ux, uy, uz = lx, ly, lz
        sdist = math.sqrt(ex * ex + ey * ey + ez * ez)
        lead = ldist - sdist
    else:
        ux, uy, uz, sdist = lx, ly, lz, ldist
        lead = shift_in
    far = sdist * (1.0 - 1e-6) - eps if finite else sdist
    sf[ns, S_O], sf[ns, S_O + 1], sf[ns, S_O + 2] = qx, qy, qz
    sf[ns, S_D], sf[ns, S_D + 1], sf[ns, S_D + 2] = ux, uy, uz
    sf[ns, S_FAR] = max(far, 0.0)
    sf[ns, S_LEAD] = lead
    sf[ns, S_TAIL] = sdist - far if finite else 0.0
    sf[ns, S_C], sf[ns, S_C + 1], sf[ns, S_C + 2] = c0, c1, c2
    sf[ns, S_BARY], sf[ns, S_BARY + 1], sf[ns, S_BARY + 2] = bary0, bary1, bary2
    si[ns, S_ID], si[ns, S_FACE], si[ns, S_NSTK], si[ns, S_CROSS] = lane, face, nstk, 0
    for s in range(so.shape[1]):
        sso[ns, s] = so[i, s]
        ssior[ns, s] = sior[i, s]
    return ns + 1


@njit
def _parallel_shift(eps, gx, gy, gz, dx, dy, dz):
    """How much shorter an offset ray is than the same ray from the surface point,
    through a medium bounded by a parallel surface (|cos| clamped at 0.1)."""
    return eps / max(abs(_dot(gx, gy, gz, dx, dy, dz)), 0.1)


@njit
def bounce(tb, m, face, hb1, hb2, ht, lf, li, so, sior, u, lane_row, params, bf, bslot, L,
           alpha, aov, nlf, nli, nso, nsior, sf, si, sso, ssior, ws):
    """Stage 2 for every lane: see the module docstring.

    ``u`` (m, 9) uniforms per lane: free flight, cutout, light (3), bsdf or phase (3),
    roulette.  Bindings: lane ``i`` with ``lane_row[i] = v >= 0`` runs program slot
    ``bslot[v]`` with parameter row ``2k + v`` (k objects), and takes its shading
    normal, tangent, opacity, IOR and emitted radiance from ``bf[v]`` (columns 0-2,
    3-5, 6, 7, 8-10).

    Lanes ``0 .. m-1`` are read; the lanes that go on are written to ``nlf``, ``nli``,
    ``nso``, ``nsior`` and the shadow records to ``sf``, ``si``, ``sso``, ``ssior`` (all
    with at least ``m`` rows, reused from segment to segment: a fresh allocation per
    segment costs page faults).  ``ws``: the interpreter's scratch (:func:`scratch`).
    Returns their counts ``(nn, ns)``.
    """
    sc = tb.scalars
    eps = sc[SC_EPS]
    max_depth, rr_depth = sc[SC_MAX_DEPTH], sc[SC_RR_DEPTH]
    has_media = sc[SC_MEDIA] != 0.0
    want_aov = sc[SC_AOV] != 0.0
    mode, env_light = int(sc[SC_SELECT]), int(sc[SC_ENV_LIGHT])
    n_every = 0  # delta lights sampled at every vertex
    if mode >= EVERY_DELTA:
        for j in range(len(tb.light_kind)):
            n_every += 1 if _is_delta(tb.light_kind[j]) else 0
    n_const = 2 * len(tb.obj_flags)
    code, kids, frames, chat = tb.code, tb.kids, tb.frames, tb.chat
    # arrays out of the tuple once: each access costs numba two atomic reference counts
    face_light, emit_hit, face_normal = tb.face_light, tb.emit_hit, tb.face_normal
    light_bounds, light_tree = tb.light_bounds, tb.light_tree
    face_object, frame_lo, frame_hi, roots = tb.face_object, tb.frame_lo, tb.frame_hi, tb.roots
    medium, phase = tb.medium, tb.phase
    obj_flags, obj_ior, obj_medium = tb.obj_flags, tb.obj_ior, tb.obj_medium
    obj_opacity, packed, faces = tb.obj_opacity, tb.packed, tb.faces
    light_kind, light_params, light_first = tb.light_kind, tb.light_params, tb.light_first
    light_cdf, light_corners, light_faces = tb.light_cdf, tb.light_corners, tb.light_faces
    light_pdf_area, light_object, emit_light = tb.light_pdf_area, tb.light_object, tb.emit_light
    env, env_image, env_p, env_cdf = tb.env, tb.env_image, tb.env_p, tb.env_cdf
    sky, sky_p, sky_cdf = tb.sky, tb.sky_p, tb.sky_cdf
    nn = 0
    ns = 0
    for i in range(m):
        lane = li[i, ID]
        depth = li[i, DEPTH]
        nstk = li[i, NSTK]
        ox, oy, oz = lf[i, ORG], lf[i, ORG + 1], lf[i, ORG + 2]
        dx, dy, dz = lf[i, D], lf[i, D + 1], lf[i, D + 2]
        b0, b1, b2 = lf[i, BETA], lf[i, BETA + 1], lf[i, BETA + 2]
        r0, r1, r2 = lf[i, R], lf[i, R + 1], lf[i, R + 2]
        prev_pdf = lf[i, PREV_PDF]
        prev_delta = li[i, DELTA] != 0
        vx, vy, vz = lf[i, PREV_P], lf[i, PREV_P + 1], lf[i, PREV_P + 2]
        vnx, vny, vnz = lf[i, PREV_N], lf[i, PREV_N + 1], lf[i, PREV_N + 2]
        prev_sum = lf[i, PREV_SUM]
        f = face[i]
        t_hit = ht[i] if f >= 0 else np.inf
        # ---- the medium of the segment: attenuate, or scatter inside it
        scattered = False
        t_event = 0.0
        med = -1
        if has_media and nstk > 0:
            med = obj_medium[so[i, nstk - 1]]
        if med >= 0:
            length = t_hit + lf[i, SHIFT]
            hero = li[i, HERO]
            scattered, tt, v0, v1, v2, p0, p1, p2 = free_flight(medium, med, hero, u[i, 0],
                                                                length)
            if scattered:
                t_event = tt - lf[i, SHIFT]
            ph = p0 if hero == 0 else (p1 if hero == 1 else p2)
            if ph > 0.0:  # spectral MIS: r = p / p[hero], beta *= value / p[hero]
                b0, b1, b2 = b0 * v0 / ph, b1 * v1 / ph, b2 * v2 / ph
                r0, r1, r2 = r0 * p0 / ph, r1 * p1 / ph, r2 * p2 / ph
            else:
                b0 = b1 = b2 = 0.0
        mis = (r0 + r1 + r2) / 3.0
        if scattered:
            # ---- a scattering vertex in the medium
            px, py, pz = ox + t_event * dx, oy + t_event * dy, oz + t_event * dz
            if not depth < max_depth:
                continue
            wox, woy, woz = -dx, -dy, -dz
            total, jd = 0.0, -1
            for pick in range(1 + n_every):  # the selected light, then every delta light
                if pick == 0:
                    j, sel, total = select_light(light_kind, light_bounds, light_params,
                                                 light_tree, mode, px, py, pz, 0.0, 0.0, 0.0,
                                                 u[i, 2])  # -1: none
                else:
                    jd = _next_delta(light_kind, jd)
                    j, sel = jd, 1.0
                (lx, ly, lz, ldist, l0, l1, l2, lpdf, ldelta, lface, q0, q1, q2) = sample_light(
                    light_kind, light_params, light_first, light_cdf, light_corners, light_faces,
                    light_pdf_area, light_object, obj_flags, emit_light, face_normal, env,
                    env_image, env_p, env_cdf, sky, sky_p, sky_cdf, sc, j, px, py, pz, u[i, 3],
                    u[i, 4])
                lpdf *= sel
                ph0, ph1, ph2, pp = _phase_eval_pdf(phase, med, 0, 0, wox, woy, woz,
                                                              lx, ly, lz)
                if lpdf > 0.0:
                    w = (1.0 if ldelta else _power(lpdf, pp)) / lpdf / mis
                    c0, c1, c2 = b0 * ph0 * l0 * w, b1 * ph1 * l1 * w, b2 * ph2 * l2 * w
                    if c0 > 0.0 or c1 > 0.0 or c2 > 0.0:
                        ns = _shadow_record(eps, sf, si, sso, ssior, ns, so, sior, i, nstk, lane,
                                            px, py, pz, 0.0, 0.0, 0.0, lx, ly, lz, ldist, c0, c1,
                                            c2, lface, q0, q1, q2, False, 0.0)
            wix, wiy, wiz, pdf, w0, w1, w2, lobe = _phase_sample(
                phase, med, 0, 0, wox, woy, woz, u[i, 5], u[i, 6], u[i, 7])
            if lobe == 0:
                continue
            b0, b1, b2 = b0 * w0, b1 * w1, b2 * w2
            if depth >= rr_depth:
                survives, b0, b1, b2 = _roulette(b0, b1, b2, mis, u[i, 8])
                if not survives:
                    continue
            if not (b0 > 0.0 or b1 > 0.0 or b2 > 0.0):
                continue
            _copy_lane(lf, li, so, sior, i, nlf, nli, nso, nsior, nn)
            nlf[nn, ORG], nlf[nn, ORG + 1], nlf[nn, ORG + 2] = px, py, pz
            nlf[nn, D], nlf[nn, D + 1], nlf[nn, D + 2] = wix, wiy, wiz
            nlf[nn, BETA], nlf[nn, BETA + 1], nlf[nn, BETA + 2] = b0, b1, b2
            nlf[nn, R], nlf[nn, R + 1], nlf[nn, R + 2] = r0, r1, r2
            nlf[nn, PREV_PDF], nlf[nn, SEG], nlf[nn, SHIFT] = pdf, 0.0, 0.0
            _set_prev(nlf, nn, px, py, pz, 0.0, 0.0, 0.0, total)
            nli[nn, DEPTH], nli[nn, DELTA], nli[nn, CROSS] = depth + 1, 0, 0
            nn += 1
            continue
        if f < 0:
            # ---- escaped: the environment, weighted against light sampling
            pe, e0, e1, e2 = _environment(sc, env, env_image, env_p, sky, sky_p, dx, dy, dz)
            if e0 != 0.0 or e1 != 0.0 or e2 != 0.0:
                if not prev_delta:
                    pe *= selection_pdf(light_kind, light_bounds, light_params, light_tree, mode,
                                        env_light, prev_sum, vx, vy, vz, vnx, vny, vnz)
                w = (1.0 if prev_delta else _power(prev_pdf, pe)) / mis
                L[lane, 0] += b0 * e0 * w
                L[lane, 1] += b1 * e1 * w
                L[lane, 2] += b2 * e2 * w
            continue
        # ---- a surface
        k = face_object[f]
        flags = obj_flags[k]
        px, py, pz, nx, ny, nz, tx, ty, tz, _, _, _, uu, uv = _attributes(
            packed, faces, face_normal, f, hb1[i], hb2[i])
        gx, gy, gz = face_normal[f, 0], face_normal[f, 1], face_normal[f, 2]
        g_wo = -_dot(dx, dy, dz, gx, gy, gz)
        front = g_wo > 0.0
        slot = 2 * k + (1 if (flags & TWO_FACED) and not front else 0)
        row = slot
        v = lane_row[i]
        if v >= 0:
            nx, ny, nz = bf[v, 0], bf[v, 1], bf[v, 2]
            tx, ty, tz = bf[v, 3], bf[v, 4], bf[v, 5]
            opacity, entry_ior = bf[v, 6], bf[v, 7]
            e0, e1, e2 = bf[v, 8], bf[v, 9], bf[v, 10]
            slot, row = bslot[v], n_const + v
        else:
            opacity, entry_ior = obj_opacity[k], obj_ior[k]
            e0 = e1 = e2 = 0.0
        dist_v = lf[i, SEG] + t_hit
        crossings = li[i, CROSS]
        # cutouts: pass straight through with probability 1 - opacity
        if (flags & CUTOUT) and u[i, 1] >= opacity and crossings < MAX_CROSSINGS:
            side = 1.0 if _dot(dx, dy, dz, gx, gy, gz) >= 0.0 else -1.0
            _copy_lane(lf, li, so, sior, i, nlf, nli, nso, nsior, nn)
            nlf[nn, ORG], nlf[nn, ORG + 1], nlf[nn, ORG + 2] = (
                px + side * eps * gx, py + side * eps * gy, pz + side * eps * gz)
            nlf[nn, BETA], nlf[nn, BETA + 1], nlf[nn, BETA + 2] = b0, b1, b2
            nlf[nn, R], nlf[nn, R + 1], nlf[nn, R + 2] = r0, r1, r2
            nlf[nn, SEG] = dist_v
            nlf[nn, SHIFT] = _parallel_shift(eps, gx, gy, gz, dx, dy, dz)
            nli[nn, CROSS] = crossings + 1
            nn += 1
            continue
        sx, sy, sz, qx, qy, qz = _frame(nx, ny, nz, tx, ty, tz)
        wox = -_dot(dx, dy, dz, sx, sy, sz)
        woy = -_dot(dx, dy, dz, qx, qy, qz)
        woz = -_dot(dx, dy, dz, nx, ny, nz)
        # emission, weighted against light sampling
        if flags & EMIT_CONST and front and woz > 1e-10:
            e0, e1, e2 = emit_hit[k, 0], emit_hit[k, 1], emit_hit[k, 2]
        if e0 != 0.0 or e1 != 0.0 or e2 != 0.0:
            w = 1.0 / mis
            jl = face_light[f]
            cos_l = abs(g_wo)
            if not prev_delta and jl >= 0 and cos_l > 0.0:
                pl = light_pdf_area[jl] * dist_v * dist_v / cos_l * selection_pdf(
                    light_kind, light_bounds, light_params, light_tree, mode, jl, prev_sum, vx,
                    vy, vz, vnx, vny, vnz)
                w = _power(prev_pdf, pl) / mis
            L[lane, 0] += b0 * e0 * w
            L[lane, 1] += b1 * e1 * w
            L[lane, 2] += b2 * e2 * w
        root, f_lo, f_hi = roots[slot], frame_lo[slot], frame_hi[slot]
        if li[i, FIRST]:
            alpha[lane] = 1.0
            if want_aov:
                if root >= 0:
                    a0, a1, a2 = interpreter.cheap_albedo(code, kids, frames, params, chat, row,
                                                          ws, root, f_lo, f_hi, wox, woy, woz)
                    aov[lane, A_ALBEDO], aov[lane, A_ALBEDO + 1] = a0, a1
                    aov[lane, A_ALBEDO + 2] = a2
                aov[lane, A_NORMAL], aov[lane, A_NORMAL + 1] = nx, ny
                aov[lane, A_NORMAL + 2] = nz
                aov[lane, A_DEPTH] = _dot(px - sc[SC_CAM], py - sc[SC_CAM + 1],
                                          pz - sc[SC_CAM + 2], sc[SC_FWD], sc[SC_FWD + 1],
                                          sc[SC_FWD + 2])
                aov[lane, A_UV], aov[lane, A_UV + 1] = uu, uv
                aov[lane, A_OBJECT] = k
        if root < 0:
            continue
        can_continue = depth < max_depth
        is_null = (flags & NULL) != 0
        if not (can_continue or is_null):
            continue
        encloses = (flags & ENCLOSES) != 0
        # next-event estimation
        prepared = False
        total = 0.0
        jd = -1
        for pick in range(1 + n_every if can_continue else 0):  # selected, then every delta
            if pick == 0:
                j, sel, total = select_light(light_kind, light_bounds, light_params, light_tree,
                                             mode, px, py, pz, nx, ny, nz, u[i, 2])
            else:
                jd = _next_delta(light_kind, jd)
                j, sel = jd, 1.0
            (lx, ly, lz, ldist, l0, l1, l2, lpdf, ldelta, lface, q0, q1, q2) = sample_light(
                light_kind, light_params, light_first, light_cdf, light_corners, light_faces,
                light_pdf_area, light_object, obj_flags, emit_light, face_normal, env, env_image,
                env_p, env_cdf, sky, sky_p, sky_cdf, sc, j, px, py, pz, u[i, 3], u[i, 4])
            lpdf *= sel
            wlx = _dot(lx, ly, lz, sx, sy, sz)
            wly = _dot(lx, ly, lz, qx, qy, qz)
            wlz = _dot(lx, ly, lz, nx, ny, nz)
            g_wi = _dot(lx, ly, lz, gx, gy, gz)
            if lpdf > 0.0 and g_wi != 0.0 and ((g_wi * g_wo > 0.0) == (wlz * woz > 0.0)):
                f0, f1, f2, pb = interpreter.eval_pdf(code, kids, frames, params, chat, row, ws,
                                                      root, f_lo, f_hi, wox, woy, woz, wlx, wly,
                                                      wlz)
                prepared = True
                w = (1.0 if ldelta else _power(lpdf, pb)) / lpdf / mis
                c0, c1, c2 = b0 * f0 * l0 * w, b1 * f1 * l1 * w, b2 * f2 * l2 * w
                if c0 > 0.0 or c1 > 0.0 or c2 > 0.0:
                    shift = _parallel_shift(eps, gx, gy, gz, lx, ly, lz)
                    ns = _shadow_record(eps, sf, si, sso, ssior, ns, so, sior, i, nstk, lane,
                                        px, py, pz, gx, gy, gz, lx, ly, lz, ldist, c0, c1, c2,
                                        lface, q0, q1, q2, True, shift)
                    if encloses and g_wi * g_wo < 0.0:  # the light is across the surface
                        sn = si[ns - 1, S_NSTK]
                        if front:
                            sn = stack_push(sso, ssior, ns - 1, sn, k, entry_ior)
                        else:
                            sn = stack_pop(sso, ssior, ns - 1, sn, k)
                        si[ns - 1, S_NSTK] = sn
        # the bsdf's sample continues the path
        wix, wiy, wiz, pdf, w0, w1, w2, lobe = interpreter.sample(
            code, kids, frames, params, chat, row, ws, root, f_lo, f_hi, wox, woy, woz,
            u[i, 5], u[i, 6], u[i, 7], prepared)
        if lobe == 0 or not (w0 > 0.0 or w1 > 0.0 or w2 > 0.0):
            continue
        nx2 = wix * sx + wiy * qx + wiz * nx
        ny2 = wix * sy + wiy * qy + wiz * ny
        nz2 = wix * sz + wiy * qz + wiz * nz
        g_new = _dot(nx2, ny2, nz2, gx, gy, gz)
        if g_new == 0.0 or (g_new * g_wo > 0.0) != (wiz * woz > 0.0):
            continue
        straight = (is_null and lobe == SPECULAR_TRANSMISSION
                    and _dot(nx2, ny2, nz2, dx, dy, dz) > 1.0 - STRAIGHT_TOL
                    and crossings < MAX_CROSSINGS)
        if not (can_continue or straight):
            continue
        b0, b1, b2 = b0 * w0, b1 * w1, b2 * w2
        if not straight and depth >= rr_depth:
            survives, b0, b1, b2 = _roulette(b0, b1, b2, mis, u[i, 8])
            if not survives:
                continue
        if straight:
            nx2, ny2, nz2 = dx, dy, dz
        _copy_lane(lf, li, so, sior, i, nlf, nli, nso, nsior, nn)
        # a transmission through a closed object enters or leaves it
        if encloses and g_new * g_wo < 0.0:
            if front:
                nli[nn, NSTK] = stack_push(nso, nsior, nn, nstk, k, entry_ior)
            else:
                nli[nn, NSTK] = stack_pop(nso, nsior, nn, nstk, k)
        side = 1.0 if g_new >= 0.0 else -1.0
        nlf[nn, ORG], nlf[nn, ORG + 1], nlf[nn, ORG + 2] = (
            px + side * eps * gx, py + side * eps * gy, pz + side * eps * gz)
        nlf[nn, D], nlf[nn, D + 1], nlf[nn, D + 2] = nx2, ny2, nz2
        nlf[nn, BETA], nlf[nn, BETA + 1], nlf[nn, BETA + 2] = b0, b1, b2
        nlf[nn, R], nlf[nn, R + 1], nlf[nn, R + 2] = r0, r1, r2
        nlf[nn, SHIFT] = _parallel_shift(eps, gx, gy, gz, nx2, ny2, nz2)
        nli[nn, FIRST] = 0
        if straight:
            nlf[nn, SEG] = dist_v
            nli[nn, CROSS] = crossings + 1
        else:
            nlf[nn, PREV_PDF], nlf[nn, SEG] = pdf, 0.0
            _set_prev(nlf, nn, px, py, pz, nx, ny, nz, total)
            nli[nn, DEPTH], nli[nn, CROSS] = depth + 1, 0
            nli[nn, DELTA] = 1 if (lobe & SPECULAR) != 0 else 0
        nn += 1
    return nn, ns


# -------------------------------------------------------------------- stage 3
@njit
def shadow_trace(scene, tb, sf, n, any_pass, face, b1, b2, t):
    """The shadow records' segments: with ``any_pass`` (the scene has cutout or null
    surfaces) their first hits as :func:`intersect` gives them, else only whether they
    are blocked (``face`` -2) or free (-1)."""
    scratch = embree.new_scratch()
    off = tb.face_offset
    for i in range(n):
        ox, oy, oz = sf[i, S_O], sf[i, S_O + 1], sf[i, S_O + 2]
        dx, dy, dz = sf[i, S_D], sf[i, S_D + 1], sf[i, S_D + 2]
        far = sf[i, S_FAR]
        if any_pass:
            h = embree.intersect1(scene, ox, oy, oz, dx, dy, dz, 0.0, far, scratch)
            if h[4] == embree.MISS:
                face[i] = -1
            else:
                face[i] = off[h[4]] + h[3]
                b1[i], b2[i], t[i] = h[1], h[2], h[0]
        else:
            face[i] = -2 if embree.occluded1(scene, ox, oy, oz, dx, dy, dz, 0.0, far,
                                             scratch) else -1


@njit
def shadow_resolve(tb, m, sf, si, sso, ssior, face, hb1, hb2, ht, u, lane_row, params, bf,
                   bslot, L, nsf, nsi, nso, nsior, ws):
    """Attenuate each shadow segment by its medium; add what reaches the light to ``L``,
    drop what is blocked, and move records that cross a cutout or a null surface to
    their next segment (entering or leaving the object).  Bindings as in
    :func:`bounce` (for the cutout and null surfaces hit).  Records ``0 .. m-1`` are
    read; those still on their way are written to ``nsf``, ``nsi``, ``nso``, ``nsior``;
    returns their count.  ``ws``: the interpreter's scratch (:func:`scratch`)."""
    sc = tb.scalars
    eps = sc[SC_EPS]
    has_media = sc[SC_MEDIA] != 0.0
    n_const = 2 * len(tb.obj_flags)
    code, kids, frames, chat = tb.code, tb.kids, tb.frames, tb.chat
    face_normal, face_object, roots, medium = tb.face_normal, tb.face_object, tb.roots, tb.medium
    frame_lo, frame_hi, packed, faces = tb.frame_lo, tb.frame_hi, tb.packed, tb.faces
    obj_flags, obj_ior, obj_medium = tb.obj_flags, tb.obj_ior, tb.obj_medium
    obj_opacity = tb.obj_opacity
    nn = 0
    for i in range(m):
        f = face[i]
        if f == -2:
            continue
        c0, c1, c2 = sf[i, S_C], sf[i, S_C + 1], sf[i, S_C + 2]
        nstk = si[i, S_NSTK]
        t = ht[i] if f >= 0 else sf[i, S_FAR]
        if has_media and nstk > 0:
            med = obj_medium[sso[i, nstk - 1]]
            if med >= 0:
                length = t + sf[i, S_LEAD] + (0.0 if f >= 0 else sf[i, S_TAIL])
                c0 *= transmittance(medium, med, 0, length)
                c1 *= transmittance(medium, med, 1, length)
                c2 *= transmittance(medium, med, 2, length)
        if f < 0:
            lane = si[i, S_ID]
            L[lane, 0] += c0
            L[lane, 1] += c1
            L[lane, 2] += c2
            continue
        k = face_object[f]
        flags = obj_flags[k]
        if not (flags & (CUTOUT | NULL)) or si[i, S_CROSS] >= MAX_CROSSINGS:
            continue
        dx, dy, dz = sf[i, S_D], sf[i, S_D + 1], sf[i, S_D + 2]
        gx, gy, gz = face_normal[f, 0], face_normal[f, 1], face_normal[f, 2]
        front = _dot(dx, dy, dz, gx, gy, gz) < 0.0
        v = lane_row[i]
        slot = 2 * k + (1 if (flags & TWO_FACED) and not front else 0)
        px, py, pz, nx, ny, nz, tx, ty, tz, _, _, _, _, _ = _attributes(
            packed, faces, face_normal, f, hb1[i], hb2[i])
        row = slot
        if v >= 0:
            nx, ny, nz = bf[v, 0], bf[v, 1], bf[v, 2]
            tx, ty, tz = bf[v, 3], bf[v, 4], bf[v, 5]
            opacity, entry_ior = bf[v, 6], bf[v, 7]
            slot, row = bslot[v], n_const + v
        else:
            opacity, entry_ior = obj_opacity[k], obj_ior[k]
        crossing = False
        if (flags & CUTOUT) and u[i] >= opacity:
            pass  # cut: passes unchanged
        elif flags & NULL and roots[slot] >= 0:
            root = roots[slot]
            sx, sy, sz, qx, qy, qz = _frame(nx, ny, nz, tx, ty, tz)
            wox = -_dot(dx, dy, dz, sx, sy, sz)
            woy = -_dot(dx, dy, dz, qx, qy, qz)
            woz = -_dot(dx, dy, dz, nx, ny, nz)
            wix, wiy, wiz, pdf, w0, w1, w2, lobe = interpreter.sample(
                code, kids, frames, params, chat, row, ws, root, frame_lo[slot],
                frame_hi[slot], wox, woy, woz, ONE_MINUS_EPS, 0.0, 0.0)
            wx = wix * sx + wiy * qx + wiz * nx
            wy = wix * sy + wiy * qy + wiz * ny
            wz = wix * sz + wiy * qz + wiz * nz
            if not (lobe == SPECULAR_TRANSMISSION and _dot(wx, wy, wz, dx, dy, dz)
                    > 1.0 - STRAIGHT_TOL):
                continue
            c0, c1, c2 = c0 * pdf * w0, c1 * pdf * w1, c2 * pdf * w2
            crossing = True
        else:
            continue
        if not (c0 > 0.0 or c1 > 0.0 or c2 > 0.0):
            continue
        _copy_lane(sf, si, sso, ssior, i, nsf, nsi, nso, nsior, nn)
        if crossing and (flags & ENCLOSES):
            if front:
                nsi[nn, S_NSTK] = stack_push(nso, nsior, nn, nstk, k, entry_ior)
            else:
                nsi[nn, S_NSTK] = stack_pop(nso, nsior, nn, nstk, k)
        side = 1.0 if _dot(dx, dy, dz, gx, gy, gz) >= 0.0 else -1.0
        nsf[nn, S_O], nsf[nn, S_O + 1], nsf[nn, S_O + 2] = (
            px + side * eps * gx, py + side * eps * gy, pz + side * eps * gz)
        cos = abs(_dot(gx, gy, gz, dx, dy, dz))
        nsf[nn, S_FAR] = max(sf[i, S_FAR] - t - eps * cos, 0.0)
        nsf[nn, S_LEAD] = _parallel_shift(eps, gx, gy, gz, dx, dy, dz)
        nsf[nn, S_C], nsf[nn, S_C + 1], nsf[nn, S_C + 2] = c0, c1, c2
        nsi[nn, S_CROSS] = si[i, S_CROSS] + 1
        nn += 1
    return nn
