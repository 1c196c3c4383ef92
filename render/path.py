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
from render.bsdf import Lobe
from render.df.anisotropic_vdf import eval_pdf as _phase_eval_pdf
from render.df.anisotropic_vdf import sample as _phase_sample
from render.jit import njit
from render.lights import INFINITE_DISTANCE
from render.program import LUM_B, LUM_G, LUM_R
from render.sampler import (
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
    "trace",
    "resolve_shadows",
    "outside_ior",
    "sample_light",
    "select_light",
    "selection_pdf",
    "sample_lights",
    "selection",
    "escaped",
]

INV_PI = 1.0 / np.pi
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
NSF = 18
S_ID, S_FACE, S_NSTK, S_CROSS, S_SEGMENT, S_HIT = 0, 1, 2, 3, 4, 5
NSI = 6
# AOV columns
A_ALBEDO, A_NORMAL, A_DEPTH, A_UV, A_OBJECT = 0, 3, 6, 7, 9
NA = 10

#: object flags; BOUND: shaded with numpy per hit, IOR_SENSITIVE: its program reads the
#: IOR outside it (bound again inside other objects)
CUTOUT, NULL, ENCLOSES, TWO_FACED, EMIT_CONST, BOUND, IOR_SENSITIVE = 1, 2, 4, 8, 16, 32, 64
#: one Embree call in this many is timed (the share of time inside Embree)
TIMED_EVERY = 16

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
SC_BIND = 16  # some objects are shaded with numpy (lanes may park)
SC_PASS = 17  # some objects are cutouts or null surfaces (shadow rays may pass)
N_SCALARS = 18


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


@njit(inline="always")
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


@njit(inline="always")
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


@njit(inline="always")
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


@njit(inline="always")
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


@njit(inline="always")
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


@njit(inline="always")
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


@njit(inline="always")
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
def trace(scene, tb, n, resume, o, d, pixel, index, seed, kind, v1, lf, li, so, sior,
          lane_row, params, bf, bslot, L, alpha, aov, plf, pli, pso, psior, sf, si, sso,
          ssior, ws, es, cso, csior, counts):
    """Trace the paths of lanes ``0 .. n-1`` to their end, or until a path hits an object
    that numpy must shade first (:func:`_needs_binding`): such a lane is *parked*, its
    state and hit written to row ``p`` of ``plf``, ``pli``, ``pso``, ``psior``.

    Fresh lanes (``resume`` False) start at the camera: lane ``i`` is sample
    ``index[i]`` of pixel ``pixel[i]``, its ray ``o[i]``, ``d[i]``.  Resumed lanes are
    the rows of ``lf``, ``li``, ``so``, ``sior`` (a previous call's parked lanes), each
    with its hit, bound by row ``lane_row[i]`` (-1: none) of ``bf``, ``bslot`` and
    ``params`` (:func:`bounce_binding`).  Shadow records that cannot be resolved here
    (an area light whose emission varies, or a cutout or null surface that numpy must
    shade) are parked in ``sf``, ``si``, ``sso``, ``ssior`` for :func:`resolve_shadows`.

    What each path sees is added to ``L[lane]``, its alpha and AOVs (first hits) to
    ``alpha`` and ``aov``.  Scratch: ``ws`` (the interpreter's), ``es`` (Embree's ray
    record), ``cso``/``csior`` (a lane's stack of closed objects, one row).  Returns
    ``(parked lanes, parked shadow records)``."""
    sc = tb.scalars
    eps = sc[SC_EPS]
    max_depth, rr_depth = sc[SC_MAX_DEPTH], sc[SC_RR_DEPTH]
    has_media = sc[SC_MEDIA] != 0.0
    want_aov = sc[SC_AOV] != 0.0
    may_bind = sc[SC_BIND] != 0.0
    mode, env_light = int(sc[SC_SELECT]), int(sc[SC_ENV_LIGHT])
    n_every = 0  # delta lights sampled at every vertex
    if mode >= EVERY_DELTA:
        for j in range(len(tb.light_kind)):
            n_every += 1 if _is_delta(tb.light_kind[j]) else 0
    n_const = 2 * len(tb.obj_flags)
    nest = cso.shape[1]
    code, kids, frames, chat = tb.code, tb.kids, tb.frames, tb.chat
    face_light, emit_hit, face_normal = tb.face_light, tb.emit_hit, tb.face_normal
    light_bounds, light_tree = tb.light_bounds, tb.light_tree
    face_object, frame_lo, frame_hi, roots = tb.face_object, tb.frame_lo, tb.frame_hi, tb.roots
    medium, phase, face_offset = tb.medium, tb.phase, tb.face_offset
    obj_flags, obj_ior, obj_medium = tb.obj_flags, tb.obj_ior, tb.obj_medium
    obj_opacity, packed, faces = tb.obj_opacity, tb.packed, tb.faces
    light_kind, light_params, light_first = tb.light_kind, tb.light_params, tb.light_first
    light_cdf, light_corners, light_faces = tb.light_cdf, tb.light_corners, tb.light_faces
    light_pdf_area, light_object, emit_light = tb.light_pdf_area, tb.light_object, tb.emit_light
    env, env_image, env_p, env_cdf = tb.env, tb.env_image, tb.env_p, tb.env_cdf
    sky, sky_p, sky_cdf = tb.sky, tb.sky_p, tb.sky_cdf
    n_park = 0
    n_shadow = 0
    rays = 0
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
            ox, oy, oz = o[i, 0], o[i, 1], o[i, 2]
            dx, dy, dz = d[i, 0], d[i, 1], d[i, 2]
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
                    hb1, hb2, t_hit = h[1], h[2], h[0]
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
            t_event = 0.0
            med = -1
            u_flight, u_roulette = 0.0, 0.0
            if has_media and nstk > 0:
                med = obj_medium[cso[0, nstk - 1]]
            if med >= 0:
                u_flight, u_roulette = sample_pair(v1, ph, idx, pair0 + P_FLIGHT, kind)
                length = t_hit + shift
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
                k, row, root, f_lo, f_hi, entry_ior, g_wo, dist_v = -1, 0, -1, 0, 0, 1.0, 0.0, 0.0
                can_continue, is_null, encloses, front = True, False, False, True
            elif f < 0:
                # ---- escaped: the environment, weighted against light sampling
                pe, e0, e1, e2 = _environment(sc, env, env_image, env_p, sky, sky_p, dx, dy, dz)
                if e0 != 0.0 or e1 != 0.0 or e2 != 0.0:
                    if not prev_delta:
                        pe *= selection_pdf(light_kind, light_bounds, light_params, light_tree,
                                            mode, env_light, prev_sum, vx, vy, vz, vnx, vny, vnz)
                    w = (1.0 if prev_delta else _power(prev_pdf, pe)) / mis
                    L[lane, 0] += b0 * e0 * w
                    L[lane, 1] += b1 * e1 * w
                    L[lane, 2] += b2 * e2 * w
                break
            else:
                # ---- a surface
                k = face_object[f]
                flags = obj_flags[k]
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
                            light_kind, light_bounds, light_params, light_tree, mode, jl,
                            prev_sum, vx, vy, vz, vnx, vny, vnz)
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
            for pick in range(1 + n_every if can_continue else 0):
                if pick == 0:
                    j, sel, total = select_light(light_kind, light_bounds, light_params,
                                                 light_tree, mode, px, py, pz, nx, ny, nz,
                                                 u_choice)  # -1: none
                else:
                    jd = _next_delta(light_kind, jd)
                    j, sel = jd, 1.0
                (lx, ly, lz, ldist, l0, l1, l2, lpdf, ldelta, lface, q0, q1, q2) = sample_light(
                    light_kind, light_params, light_first, light_cdf, light_corners, light_faces,
                    light_pdf_area, light_object, obj_flags, emit_light, face_normal, env,
                    env_image, env_p, env_cdf, sky, sky_p, sky_cdf, sc, j, px, py, pz, ul1, ul2)
                lpdf *= sel
                if not lpdf > 0.0:
                    continue
                across = False
                if scattered:
                    f0, f1, f2, pb = _phase_eval_pdf(phase, med, 0, 0, wox, woy, woz, lx, ly, lz)
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
                nx2, ny2, nz2, pdf, w0, w1, w2, lobe = _phase_sample(
                    phase, med, 0, 0, wox, woy, woz, u_lobe, ub1, ub2)
                if lobe == 0:
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
                vx, vy, vz, vnx, vny, vnz, prev_sum = px, py, pz, nx, ny, nz, total
                depth, crossings = depth + 1, 0
                prev_delta = (not scattered) and (lobe & SPECULAR) != 0
    counts[0] += rays
    return n_park, n_shadow


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
        ux, uy, uz, ok = _unitize(ex, ey, ez)
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
    through cutouts and null surfaces (:func:`_cross_shadow`); what arrives is added to
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
                if not (flags & (CUTOUT | NULL)) or si[r, S_CROSS] >= MAX_CROSSINGS:
                    return False
                if sc[SC_BIND] != 0.0 and _needs_binding(flags, sso[r:r + 1], ssior[r:r + 1],
                                                         nstk, k):
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
        slot, row = bslot[v], 2 * len(tb.obj_flags) + v
    else:
        opacity, entry_ior = tb.obj_opacity[k], tb.obj_ior[k]
    c0, c1, c2 = sf[r, S_C], sf[r, S_C + 1], sf[r, S_C + 2]
    cross = si[r, S_CROSS]
    crossing = False
    if (flags & CUTOUT) and sample_pair(
            v1, ph, idx, SHADOW_PAIRS + (si[r, S_SEGMENT] << 8) + cross, kind)[0] >= opacity:
        pass  # cut: passes unchanged
    elif flags & NULL and roots[slot] >= 0:
        sx, sy, sz, qx, qy, qz = _frame(nx, ny, nz, tx, ty, tz)
        wox = -_dot(dx, dy, dz, sx, sy, sz)
        woy = -_dot(dx, dy, dz, qx, qy, qz)
        woz = -_dot(dx, dy, dz, nx, ny, nz)
        wix, wiy, wiz, pdf, w0, w1, w2, lobe = interpreter.sample(
            tb.code, tb.kids, tb.frames, params, tb.chat, row, ws, roots[slot],
            tb.frame_lo[slot], tb.frame_hi[slot], wox, woy, woz, ONE_MINUS_EPS, 0.0, 0.0)
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
