"""Next-event estimation's lights in compiled form: one table of them, the choice of a
light by what it can contribute at a vertex, and the sampling of the light chosen.

The table (:func:`light_table`) has a row per light and, after them, a row per node of
the light tree; the ``L_*`` and ``LB_*`` constants name its columns.  A light's row holds
what sampling it needs (its kind; an area light's triangles, area and constant
radiance; a point or spot light's position, axis, intensity and cone; a directional
light's direction and irradiance; an environment's radiance and its irradiance as
spherical harmonics) and what choosing it needs (its bounds: a bounding sphere, an
emission cone, an intensity and a power, as pbrt-v4's ``LightBounds``).  A node's row
holds the merged bounds of the lights below it and the tree's links.  The emissive
triangles are rows of a second table (``T_*`` columns): their area cdf, index, corners
and normal.  So the kernels take two arrays, not twenty: every kernel call hands numba
its arguments one machine word at a time, and twenty arrays cost more than the work.

* :func:`select_light` picks a light in proportion to :func:`_importance` at the vertex
  (``[render] light_selection``: the contribution bound, the power, or uniformly),
  flat over up to :data:`FLAT_LIGHTS` lights, else down the light tree; its
  probability again (for MIS) is :func:`selection_pdf`;
* :func:`sample_light` samples the chosen light from a point: a direction, the
  radiance arriving along it and its solid-angle density;
* :func:`environment_radiance`: what a ray that leaves the scene sees.

:func:`sample_lights`, :func:`selection` and :func:`escaped` are their batch forms, for
the tests and for the integrator's set-up.
"""

from __future__ import annotations

import math
from collections import namedtuple

import numpy as np

from render.df._kernel_common import unitize
from render.jit import njit
from render.lights import (
    INFINITE_DISTANCE,
    AreaLight,
    ConstantEnvironment,
    DirectionalLight,
    LatLongEnvironment,
    PointLight,
    SpotLight,
)
from render.program import LUM_B, LUM_G, LUM_R
from render.sampler import pair_values
from render.sky import SunAndSky, sun_and_sky_eval, sun_and_sky_pdf, sun_and_sky_sample

__all__ = ["LightTable", "light_table", "select_light", "selection_pdf", "sample_light",
           "environment_radiance", "sample_lights", "selection", "escaped", "FLAT_LIGHTS"]

#: light kinds (``L_KIND``; -1: a node of the light tree)
AREA, ENVIRONMENT, POINT, SPOT, DIRECTIONAL, ENVIRONMENT_MAP, SUN_AND_SKY = 0, 1, 2, 3, 4, 5, 6
KINDS = {AreaLight: AREA, ConstantEnvironment: ENVIRONMENT, PointLight: POINT, SpotLight: SPOT,
         DirectionalLight: DIRECTIONAL, LatLongEnvironment: ENVIRONMENT_MAP,
         SunAndSky: SUN_AND_SKY}
#: ``[render] light_selection``
UNIFORM, POWER, CONTRIBUTION = 0, 1, 2
SELECTIONS = {"uniform": UNIFORM, "power": POWER, "contribution": CONTRIBUTION}
#: added to the mode: every delta light is sampled at every vertex, outside the selection
EVERY_DELTA = 4
#: at most this many delta lights are sampled at every vertex (more: selected)
MAX_EVERY_DELTA = 4
#: up to this many lights are weighed one by one at every vertex (as cheap as walking a
#: tree of them, and each light's own bound is the sharper); more go into a light tree
FLAT_LIGHTS = 8

# ``lights`` columns.  A light's: its kind; an area light's object, first and last
# triangle (rows of ``light_tri``), 1 / area, whether its emission is constant, and
# then its samples' radiance (L_RAD; also an environment's constant radiance); a point
# or spot light's position, a spot's or directional light's axis (the direction the
# light travels), intensity or irradiance, a spot's cosines of cutoff and beam width;
# an environment's irradiance harmonics.
L_KIND, L_OBJECT, L_TRI, L_TRI_END, L_PDF_AREA, L_CONST = 0, 1, 2, 3, 4, 5
L_RAD, L_POS, L_DIR, L_INT, L_CUT, L_WIDTH, L_SH = 6, 9, 12, 15, 18, 19, 20
# bounds (lights and nodes): bounding-sphere centre and radius, emission cone axis and
# cos of its half-angle (-1: no cone), intensity (the importance's numerator, see
# :func:`_importance`), power (pbrt's ``PowerLightSampler``), number of lights below
LB_C, LB_R, LB_AXIS, LB_COS, LB_I, LB_PHI, LB_N = 29, 32, 33, 36, 37, 38, 39
# the light tree: parent, children (-1: none)
L_PARENT, L_A, L_B = 40, 41, 42
NL = 43
# ``light_tri`` columns: the area cdf within its light, the triangle, its corners
# (three xyz), its unit normal
T_CDF, T_FACE, T_CORNERS, T_NORMAL = 0, 1, 2, 11
NT = 14
#: the cosine at the receiver never counts less than this in a light's importance: the
#: shading normal is not the geometric one, so "perpendicular" is no proof of "black"
COS_FLOOR = 0.02
#: an importance is clamped here so that a sum of many never overflows
MAX_IMPORTANCE = 1e250
ONE_MINUS_EPS = float(np.nextafter(1.0, 0.0))

#: real spherical harmonics of bands 0-2 at unit (x, y, z), and the cosine lobe's band
#: factors pi, 2 pi / 3, pi / 4 (Ramamoorthi and Hanrahan 2001, "An efficient
#: representation for irradiance environment maps")
SH_BANDS = np.array([np.pi] + [2.0 * np.pi / 3.0] * 3 + [np.pi / 4.0] * 5)
SH_Y00 = 0.5 / math.sqrt(math.pi)
_SH_Y1 = math.sqrt(3.0 / (4.0 * math.pi))
_SH_Y2 = math.sqrt(15.0 / (4.0 * math.pi))
_SH_Y20 = math.sqrt(5.0 / (16.0 * math.pi))
_SH_Y22 = math.sqrt(15.0 / (16.0 * math.pi))


# ------------------------------------------------------------------ small kernels
@njit(inline="always")
def _dot(ax, ay, az, bx, by, bz):
    return ax * bx + ay * by + az * bz


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


@njit(inline="always")
def is_delta(kind):
    """Point, spot and directional lights: one direction each, never hit by a ray."""
    return kind == POINT or kind == SPOT or kind == DIRECTIONAL


@njit
def next_delta(lights, n_lights, j):
    """The first delta light after light ``j`` (-1: none)."""
    for k in range(j + 1, n_lights):
        if is_delta(int(lights[k, L_KIND])):
            return k
    return -1


@njit(inline="always")
def _spot_falloff(lights, j, c):
    """Spot ``j``'s falloff at cosine ``c`` from its axis: smoothstep between the cosines
    of the cutoff and the beam width, 0 outside the cutoff."""
    cut = lights[j, L_CUT]
    span = lights[j, L_WIDTH] - cut
    if span <= 0.0:
        return 1.0 if c >= cut else 0.0
    t = min(max((c - cut) / span, 0.0), 1.0)
    return t * t * (3.0 - 2.0 * t)


@njit(inline="always")
def _sh_basis(x, y, z):
    """The nine real spherical harmonics of bands 0-2 at the unit vector (x, y, z)."""
    return (SH_Y00, _SH_Y1 * y, _SH_Y1 * z, _SH_Y1 * x, _SH_Y2 * x * y, _SH_Y2 * y * z,
            _SH_Y20 * (3.0 * z * z - 1.0), _SH_Y2 * x * z, _SH_Y22 * (x * x - y * y))


@njit(inline="always")
def _sh9(lights, j, x, y, z):
    """Light ``j``'s harmonics (``L_SH``) summed at the unit vector (x, y, z)."""
    b = _sh_basis(x, y, z)
    s = 0.0
    for k in range(9):
        s += lights[j, L_SH + k] * b[k]
    return s


# ------------------------------------------------------------------- environments
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
def environment_radiance(lights, env_light, env_image, env_dist, sky, sky_dist, rot_c, rot_s,
                         dx, dy, dz):
    """Radiance along the unit direction ``d`` of a ray that leaves the scene, and the
    pdf with which sampling environment light ``env_light`` (-1: none) gives ``d``:
    ``(pdf, r, g, b)``."""
    if env_light < 0:
        return 0.0, 0.0, 0.0, 0.0
    kind = int(lights[env_light, L_KIND])
    if kind == ENVIRONMENT:
        return (0.25 / np.pi, lights[env_light, L_RAD], lights[env_light, L_RAD + 1],
                lights[env_light, L_RAD + 2])
    if kind == ENVIRONMENT_MAP:
        return _environment_map(env_image, env_dist[0], rot_c, rot_s, dx, dy, dz)
    e0, e1, e2 = sun_and_sky_eval(sky, dx, dy, dz)
    return sun_and_sky_pdf(sky, sky_dist[0], dx, dy, dz), e0, e1, e2


# ---------------------------------------------------------------- choosing a light
@njit(inline="always")
def _importance(lights, mode, j, px, py, pz, nx, ny, nz):
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
    (``L_SH``), at least COS_FLOOR of pi times their mean radiance (4 pi times it in a
    medium).

    ``mode + EVERY_DELTA``: the same, delta lights 0 (each is sampled at every vertex,
    outside the selection)."""
    kind = int(lights[j, L_KIND])
    if mode >= EVERY_DELTA:
        if is_delta(kind):
            return 0.0
        mode -= EVERY_DELTA
    if mode == UNIFORM:
        return 1.0
    if mode == POWER:
        return min(lights[j, LB_PHI], MAX_IMPORTANCE)
    intensity = lights[j, LB_I]
    if not intensity > 0.0:
        return 0.0
    surface = nx != 0.0 or ny != 0.0 or nz != 0.0
    if kind == ENVIRONMENT or kind == ENVIRONMENT_MAP or kind == SUN_AND_SKY:
        if not surface:
            return 4.0 * intensity
        return max(_sh9(lights, j, nx, ny, nz), COS_FLOOR * intensity)
    if kind == DIRECTIONAL:
        cos_i = abs(_dot(nx, ny, nz, lights[j, L_DIR], lights[j, L_DIR + 1],
                         lights[j, L_DIR + 2])) if surface else 1.0
        return intensity * max(cos_i, COS_FLOOR)
    if kind == SPOT:  # a point: its falloff exactly
        wx, wy, wz, ok = unitize(px - lights[j, L_POS], py - lights[j, L_POS + 1],
                                  pz - lights[j, L_POS + 2])
        falloff = _spot_falloff(lights, j, _dot(wx, wy, wz, lights[j, L_DIR],
                                                lights[j, L_DIR + 1], lights[j, L_DIR + 2]))
        if not falloff > 0.0:
            return 0.0
        return falloff * _bound_importance(lights, j, intensity, px, py, pz, nx, ny, nz)
    return _bound_importance(lights, j, intensity, px, py, pz, nx, ny, nz)


@njit
def _bound_importance(lb, j, intensity, px, py, pz, nx, ny, nz):
    """The contribution bound of :func:`_importance` for row ``j`` of ``lb`` (a light or
    a node of the light tree): ``intensity`` / d^2 from its bounding sphere, times the
    emitter's cosine bounded by its emission cone (where the row has one: area lights of
    constant emission and the tree's nodes over them) and sphere, times the receiver's
    cosine bounded the same way."""
    vx, vy, vz = px - lb[j, LB_C], py - lb[j, LB_C + 1], pz - lb[j, LB_C + 2]
    r = lb[j, LB_R]
    d2 = vx * vx + vy * vy + vz * vz
    wx, wy, wz, ok = unitize(vx, vy, vz)
    inside = d2 <= r * r or not ok
    surface = nx != 0.0 or ny != 0.0 or nz != 0.0
    # sin and cos of the half-angle the bounding sphere subtends at p
    sin_b = 1.0 if inside else min(r / math.sqrt(d2), 1.0)
    cos_b = math.sqrt(max(1.0 - sin_b * sin_b, 0.0))
    cos_e = 1.0
    if not inside and lb[j, LB_COS] > -1.0:
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
def _weight(lights, n_lights, mode, x, px, py, pz, nx, ny, nz):
    """The importance of light ``x``, or of node ``x`` of the light tree (x >= n_lights):
    the number of its lights, their power, or the bound of their merged bounding sphere
    and emission cone on the sum of their intensities (pbrt-v4's ``LightBounds`` of a
    ``BVHLightSampler`` node)."""
    if x < n_lights:
        return _importance(lights, mode, x, px, py, pz, nx, ny, nz)
    if mode >= EVERY_DELTA:
        mode -= EVERY_DELTA
    if mode == UNIFORM:
        return lights[x, LB_N]
    if mode == POWER:
        return min(lights[x, LB_PHI], MAX_IMPORTANCE)
    if not lights[x, LB_I] > 0.0:
        return 0.0
    return _bound_importance(lights, x, lights[x, LB_I], px, py, pz, nx, ny, nz)


@njit(inline="always")
def select_light(lights, n_lights, mode, px, py, pz, nx, ny, nz, u, lw):
    """One light for next-event estimation at p (normal n, 0 in a medium), in proportion
    to :func:`_importance`: (light, its probability, the total importance at the top),
    light -1 (probability 0) where no light can contribute.

    The top is every light outside the light tree and the tree's root (row
    ``n_lights``, if the scene has a tree): their weights (kept in the scratch ``lw``,
    at least ``n_lights + 1`` long) are summed, and ``u`` times the sum picks one by
    their running sum (so ``u < p_0`` picks the first).  From the root the walk goes
    down the tree, picking a child in proportion to its importance with ``u`` rescaled,
    as pbrt-v4's ``BVHLightSampler`` does: O(log lights) per vertex."""
    top = n_lights + 1 if lights.shape[0] > n_lights else n_lights
    total = 0.0
    for x in range(top):
        w = 0.0
        if x >= n_lights or lights[x, L_PARENT] < 0.0:  # not under the root
            w = _weight(lights, n_lights, mode, x, px, py, pz, nx, ny, nz)
            if not w > 0.0:
                w = 0.0
        lw[x] = w
        total += w
    if not (total > 0.0 and total < np.inf):
        return -1, 0.0, 0.0
    target = u * total
    chosen, below = -1, 0.0
    for x in range(top):
        if lw[x] > 0.0:
            chosen = x
            if target < below + lw[x]:
                break
            below += lw[x]
    w = lw[chosen]
    pr = w / total
    u = min(max((target - below) / w, 0.0), ONE_MINUS_EPS)
    x = chosen
    while x >= n_lights:  # down the tree
        a, b = int(lights[x, L_A]), int(lights[x, L_B])
        wa = _weight(lights, n_lights, mode, a, px, py, pz, nx, ny, nz)
        wb = _weight(lights, n_lights, mode, b, px, py, pz, nx, ny, nz)
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
def selection_pdf(lights, n_lights, mode, j, total, px, py, pz, nx, ny, nz):
    """The probability that :func:`select_light` at p (normal n), whose top importances
    sum to ``total``, picks light ``j`` (0 for ``j < 0``): up the tree from ``j``, the
    product of each step's share, times the top's share."""
    if j < 0 or not total > 0.0:
        return 0.0
    pr = 1.0
    x = j
    parent = int(lights[x, L_PARENT])
    while parent >= 0:
        a, b = int(lights[parent, L_A]), int(lights[parent, L_B])
        wa = _weight(lights, n_lights, mode, a, px, py, pz, nx, ny, nz)
        wb = _weight(lights, n_lights, mode, b, px, py, pz, nx, ny, nz)
        s = wa + wb
        if not s > 0.0:
            return 0.0
        pr *= (wa if x == a else wb) / s
        x, parent = parent, int(lights[parent, L_PARENT])
    return pr * _weight(lights, n_lights, mode, x, px, py, pz, nx, ny, nz) / total


# ---------------------------------------------------------------- sampling a light
@njit
def sample_light(lights, light_tri, env_image, env_dist, sky, sky_dist, rot_c, rot_s, j, px,
                 py, pz, u1, u2):
    """Light ``j`` sampled from p: (wi xyz, distance, radiance rgb, pdf, delta, face,
    b0, b1, b2).  ``pdf`` is the density once ``j`` is selected (delta lights: 1; the
    caller multiplies by the selection probability, :func:`select_light`);
    ``face >= 0`` marks an area light whose radiance varies over it (radiance returned
    as 1: the integrator evaluates it at ``face`` and the barycentrics ``b``)."""
    if j < 0:  # a scene without lights, or none that can contribute
        return 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 0.0, 0.0, False, -1, 0.0, 0.0, 0.0
    kind = int(lights[j, L_KIND])
    if kind == ENVIRONMENT:  # uniform sphere
        z = 1.0 - 2.0 * u1
        r = 2.0 * math.sqrt(max(u1 * (1.0 - u1), 0.0))
        phi = 2.0 * np.pi * u2
        return (r * math.cos(phi), r * math.sin(phi), z, INFINITE_DISTANCE, lights[j, L_RAD],
                lights[j, L_RAD + 1], lights[j, L_RAD + 2], 0.25 / np.pi, False, -1, 0.0, 0.0,
                0.0)
    if kind == ENVIRONMENT_MAP:  # a texel by its cdf
        h, w = env_image.shape[0], env_image.shape[1]
        k = _search_right(env_dist[1], 0, env_dist.shape[1], u1)
        lo = env_dist[1, k - 1] if k > 0 else 0.0
        pk = env_dist[0, k]
        du = min(max((u1 - lo) / pk if pk > 0 else 0.5, 0.0), 1.0)
        row, col = k // w, k % w
        phi = ((col + du) / w - 0.5) * 2.0 * np.pi
        theta = (row + u2) / h * np.pi
        st = math.sin(theta)
        x, z = st * math.sin(phi), -st * math.cos(phi)
        wx, wy, wz = rot_c * x + rot_s * z, math.cos(theta), -rot_s * x + rot_c * z
        pdf, e0, e1, e2 = _environment_map(env_image, env_dist[0], rot_c, rot_s, wx, wy, wz)
        if not pdf > 0.0:
            e0 = e1 = e2 = 0.0
        return wx, wy, wz, INFINITE_DISTANCE, e0, e1, e2, pdf, False, -1, 0.0, 0.0, 0.0
    if kind == SUN_AND_SKY:
        wx, wy, wz = sun_and_sky_sample(sky, sky_dist[0], sky_dist[1], u1, u2)
        pdf = sun_and_sky_pdf(sky, sky_dist[0], wx, wy, wz)
        e0 = e1 = e2 = 0.0
        if pdf > 0.0:
            e0, e1, e2 = sun_and_sky_eval(sky, wx, wy, wz)
        return wx, wy, wz, INFINITE_DISTANCE, e0, e1, e2, pdf, False, -1, 0.0, 0.0, 0.0
    if kind == DIRECTIONAL:
        return (-lights[j, L_DIR], -lights[j, L_DIR + 1], -lights[j, L_DIR + 2],
                INFINITE_DISTANCE, lights[j, L_INT], lights[j, L_INT + 1], lights[j, L_INT + 2],
                1.0, True, -1, 0.0, 0.0, 0.0)
    if kind != AREA:  # point, or spot with a smoothstep falloff in the cosine
        dx, dy, dz = lights[j, L_POS] - px, lights[j, L_POS + 1] - py, lights[j, L_POS + 2] - pz
        dist = math.sqrt(dx * dx + dy * dy + dz * dz)
        wx, wy, wz, ok = unitize(dx, dy, dz)
        if not (ok and dist > 0.0):
            return wx, wy, wz, dist, 0.0, 0.0, 0.0, 0.0, True, -1, 0.0, 0.0, 0.0
        scale = 1.0 / (dist * dist)
        if kind == SPOT:
            scale = scale * _spot_falloff(lights, j, _dot(-wx, -wy, -wz, lights[j, L_DIR],
                                                          lights[j, L_DIR + 1],
                                                          lights[j, L_DIR + 2]))
        return (wx, wy, wz, dist, scale * lights[j, L_INT], scale * lights[j, L_INT + 1],
                scale * lights[j, L_INT + 2], 1.0, True, -1, 0.0, 0.0, 0.0)
    # an emissive object: a triangle by area, a uniform point on it
    a, b = int(lights[j, L_TRI]), int(lights[j, L_TRI_END])
    t = _search_right(light_tri[:, T_CDF], a, b, u1)
    lo = light_tri[t - 1, T_CDF] if t > a else 0.0
    width = light_tri[t, T_CDF] - lo
    u0 = min(max((u1 - lo) / width if width > 0 else 0.5, 0.0), 1.0)
    su = math.sqrt(max(u0, 0.0))
    b1 = 1.0 - su
    b2 = u2 * su
    b0 = 1.0 - b1 - b2
    c = T_CORNERS
    xx = b0 * light_tri[t, c] + b1 * light_tri[t, c + 3] + b2 * light_tri[t, c + 6]
    xy = b0 * light_tri[t, c + 1] + b1 * light_tri[t, c + 4] + b2 * light_tri[t, c + 7]
    xz = b0 * light_tri[t, c + 2] + b1 * light_tri[t, c + 5] + b2 * light_tri[t, c + 8]
    dx, dy, dz = xx - px, xy - py, xz - pz
    dist = math.sqrt(dx * dx + dy * dy + dz * dz)
    wx, wy, wz, ok = unitize(dx, dy, dz)
    gx, gy, gz = light_tri[t, T_NORMAL], light_tri[t, T_NORMAL + 1], light_tri[t, T_NORMAL + 2]
    cos_l = abs(_dot(wx, wy, wz, gx, gy, gz))
    if not (ok and dist > 0.0 and cos_l > 1e-12):
        return wx, wy, wz, dist, 0.0, 0.0, 0.0, 0.0, False, -1, 0.0, 0.0, 0.0
    pdf = dist * dist / cos_l * lights[j, L_PDF_AREA]
    if lights[j, L_CONST] == 0.0:
        return wx, wy, wz, dist, 1.0, 1.0, 1.0, pdf, False, int(light_tri[t, T_FACE]), b0, b1, b2
    if _dot(-wx, -wy, -wz, gx, gy, gz) > 0.0:  # emitters light their front side
        return (wx, wy, wz, dist, lights[j, L_RAD], lights[j, L_RAD + 1], lights[j, L_RAD + 2],
                pdf, False, -1, 0.0, 0.0, 0.0)
    return wx, wy, wz, dist, 0.0, 0.0, 0.0, pdf, False, -1, 0.0, 0.0, 0.0


# ------------------------------------------------------------------ batch forms
@njit(allocates=True)
def sample_lights(lights, light_tri, env_image, env_dist, sky, sky_dist, n_lights, mode, rot_c,
                  rot_s, p, u):
    """:func:`sample_light` for points ``p`` (n, 3) in a medium (no normal) with
    uniforms ``u`` (n, 3): the light chosen by ``u[:, 0]`` as the path kernel chooses
    it, sampled with ``u[:, 1:]``.

    Returns ``wi`` (n, 3), distance (n,), radiance (n, 3), pdf (n,) (selection
    included), delta (n,) bool and the varying-emission face (n,) (-1: none)."""
    n = len(p)
    wi, dist, li, pdf = np.empty((n, 3)), np.empty(n), np.empty((n, 3)), np.empty(n)
    delta, face = np.empty(n, dtype=np.bool_), np.empty(n, dtype=np.int64)
    lw = np.empty(len(lights))
    for i in range(n):
        j, sel, _ = select_light(lights, n_lights, mode, p[i, 0], p[i, 1], p[i, 2], 0.0, 0.0,
                                 0.0, u[i, 0], lw)
        (wi[i, 0], wi[i, 1], wi[i, 2], dist[i], li[i, 0], li[i, 1], li[i, 2], pdf[i], delta[i],
         face[i], _, _, _) = sample_light(lights, light_tri, env_image, env_dist, sky, sky_dist,
                                          rot_c, rot_s, j, p[i, 0], p[i, 1], p[i, 2], u[i, 1],
                                          u[i, 2])
        pdf[i] *= sel
    return wi, dist, li, pdf, delta, face


@njit(allocates=True)
def selection(lights, n_lights, mode, p, nrm):
    """(n, lights) the probability that next-event estimation at points ``p`` (n, 3)
    with normals ``nrm`` (n, 3; 0: in a medium) picks each light (:func:`select_light`)."""
    n = len(p)
    out = np.zeros((n, n_lights))
    lw = np.empty(len(lights))
    for i in range(n):
        _, _, total = select_light(lights, n_lights, mode, p[i, 0], p[i, 1], p[i, 2], nrm[i, 0],
                                   nrm[i, 1], nrm[i, 2], 0.5, lw)
        for j in range(n_lights):
            out[i, j] = selection_pdf(lights, n_lights, mode, j, total, p[i, 0], p[i, 1],
                                      p[i, 2], nrm[i, 0], nrm[i, 1], nrm[i, 2])
    return out


@njit(allocates=True)
def escaped(lights, env_light, env_image, env_dist, sky, sky_dist, rot_c, rot_s, d):
    """:func:`environment_radiance` along unit directions ``d`` (n, 3): the pdf (n,) and
    the radiance (n, 3)."""
    n = len(d)
    pdf, li = np.empty(n), np.empty((n, 3))
    for i in range(n):
        pdf[i], li[i, 0], li[i, 1], li[i, 2] = environment_radiance(
            lights, env_light, env_image, env_dist, sky, sky_dist, rot_c, rot_s, d[i, 0],
            d[i, 1], d[i, 2])
    return pdf, li


@njit(allocates=True)
def environment_sh(lights, light_tri, env_image, env_dist, sky, sky_dist, rot_c, rot_s, j, u):
    """(9,) the irradiance of environment light ``j`` as harmonics of bands 0-2: its
    luminance projected by the light's own importance samples (``u`` (n, 2) uniforms),
    times :data:`SH_BANDS`; :func:`_sh9` of them at a normal n is the cosine-weighted
    radiance over the hemisphere around n, smoothed to three bands."""
    out = np.zeros(9)
    n = len(u)
    for i in range(n):
        wx, wy, wz, _, l0, l1, l2, pdf, _, _, _, _, _ = sample_light(
            lights, light_tri, env_image, env_dist, sky, sky_dist, rot_c, rot_s, j, 0.0, 0.0,
            0.0, u[i, 0], u[i, 1])
        if not pdf > 0.0:
            continue
        lum = (LUM_R * l0 + LUM_G * l1 + LUM_B * l2) / (pdf * n)
        b = _sh_basis(wx, wy, wz)
        for k in range(9):
            out[k] += lum * b[k]
    for k in range(9):
        out[k] *= SH_BANDS[k]
    return out


# ------------------------------------------------------------------ the table
#: the tables of a scene's lights for the kernels (:func:`light_table`)
LightTable = namedtuple(
    "LightTable",
    ["lights", "light_tri", "face_light", "env_image", "env_dist", "sky", "sky_dist",
     "n_lights", "mode", "env_light", "rot_c", "rot_s"],
)


def _luminance(rgb):
    """Luminance of linear RGB (..., 3)."""
    return np.asarray(rgb, dtype=np.float64) @ np.array([LUM_R, LUM_G, LUM_B])


def light_table(lights, face_count: int, emission: dict, scene_disk: float,
                every_delta: bool, selection: str, exitance: dict | None = None) -> LightTable:
    """The kernels' tables of ``lights`` (a list of :class:`render.lights.Light`).

    Parameters
    ----------
    face_count : int
        Triangles in the scene (``face_light`` maps each to its area light, -1: none).
    emission : dict
        Object id -> the radiance (3,) of a constant emitter's light samples, or None
        where the object's emission varies over it.
    scene_disk : float
        pi r^2 of the scene's bounding sphere (the cross-section a distant light covers,
        for its power).
    every_delta : bool
        Delta lights are sampled at every vertex, outside the selection.
    selection : {"uniform", "power", "contribution"}
    exitance : dict, optional
        Object id -> the mean radiance (luminance) of an emitter whose emission the
        path kernel evaluates (an edf program), for its bounds; other emitters whose
        emission varies are measured at their triangles' centroids.
    """
    n = len(lights)
    table = np.zeros((n, NL))
    table[:, L_OBJECT] = -1.0
    table[:, L_PARENT:L_B + 1] = -1.0
    face_light = np.full(face_count, -1, dtype=np.int64)
    tris = []
    env_image, env_dist = np.zeros((1, 1, 3)), np.array([[0.0], [1.0]])
    sky, sky_dist, rot, env_light = np.zeros(1), np.array([[0.0], [1.0]]), 0.0, -1
    n_tri = 0
    for j, light in enumerate(lights):
        kind = KINDS[type(light)]
        row = table[j]
        row[L_KIND] = kind
        if kind == AREA:
            row[L_OBJECT] = light.object_id
            row[L_TRI], row[L_TRI_END] = n_tri, n_tri + len(light.faces)
            n_tri += len(light.faces)
            row[L_PDF_AREA] = light.pdf_area
            radiance = emission.get(light.object_id)
            if radiance is not None:
                row[L_CONST] = 1.0
                row[L_RAD:L_RAD + 3] = radiance
            t = np.zeros((len(light.faces), NT))
            t[:, T_CDF] = light._cdf
            t[:, T_FACE] = light.faces
            t[:, T_CORNERS:T_CORNERS + 9] = light.corners.reshape(-1, 9)
            t[:, T_NORMAL:T_NORMAL + 3] = light.normals
            tris.append(t)
            face_light[light.faces] = j
        elif kind in (POINT, SPOT):
            row[L_POS:L_POS + 3] = light.position
            row[L_INT:L_INT + 3] = light.intensity
            if kind == SPOT:
                row[L_DIR:L_DIR + 3] = light.direction
                row[L_CUT], row[L_WIDTH] = light.cos_cutoff, light.cos_width
        elif kind == DIRECTIONAL:
            row[L_DIR:L_DIR + 3] = light.direction
            row[L_INT:L_INT + 3] = light.irradiance
        else:
            env_light = j
            if kind == ENVIRONMENT:
                row[L_RAD:L_RAD + 3] = light.radiance
            elif kind == ENVIRONMENT_MAP:
                env_image, env_dist = light.image, np.vstack([light._p, light._cdf])
                rot = light.rotation
            else:
                sky, sky_dist = light.kernel_params(), np.vstack([light._p, light._cdf])
    _bounds(table, lights, scene_disk, exitance or {})
    # an environment the only light to choose (the rest sampled at every vertex): its
    # importance is the same everywhere, so there is nothing to weigh per vertex
    chosen = [light for light in lights if not (every_delta and light.delta)]
    if len(chosen) == 1 and chosen[0].infinite:
        selection = "uniform"
    mode = SELECTIONS[selection] + (EVERY_DELTA if every_delta else 0)
    out = LightTable(_with_tree(table, every_delta),
                     np.vstack(tris) if tris else np.zeros((0, NT)), face_light, env_image,
                     env_dist, sky, sky_dist, n, mode, env_light, float(np.cos(rot)),
                     float(np.sin(rot)))
    if env_light >= 0:
        _environment_bounds(out, env_light, scene_disk)
    return out


def _bounds(table, lights, disk: float, exitance: dict) -> None:
    """Each light's bounds (``LB_*``; :func:`_importance`): bounding sphere, emission
    cone, intensity (area lights: mean radiance x area, directional: irradiance;
    luminance) and power (pbrt-v4's ``Light::Phi``: pi L A, 4 pi I, a spot's cone,
    pi r^2 E for a directional light; environments' are set by
    :func:`_environment_bounds`), and a count of 1."""
    table[:, LB_N] = 1.0
    table[:, LB_COS] = -1.0
    for j, light in enumerate(lights):
        row = table[j]
        kind = int(row[L_KIND])
        if kind == AREA:
            c = light.corners.reshape(-1, 3)
            a, b = c.min(axis=0), c.max(axis=0)
            row[LB_C:LB_C + 3] = 0.5 * (a + b)
            row[LB_R] = 0.5 * float(np.linalg.norm(b - a))
            area = light._tri_area
            axis = (area[:, None] * light.normals).sum(axis=0)
            length = float(np.linalg.norm(axis))
            const = row[L_CONST] != 0.0
            if const and length > 1e-9 * light.area:  # else two-sided or varying: no cone
                axis = axis / length
                row[LB_COS] = float(np.min(light.normals @ axis))
                row[LB_AXIS:LB_AXIS + 3] = axis
            if const:
                radiance = float(_luminance(row[L_RAD:L_RAD + 3]))
            elif light.object_id in exitance:
                radiance = exitance[light.object_id]
            else:  # varying: its radiance at the triangles' centroids toward their normals
                third = np.full((len(light.faces), 3), 1.0 / 3.0)
                rad = _luminance(light.emission(light.faces, third, light.normals))
                radiance = float((rad * area).sum() / light.area)
            row[LB_I] = radiance * light.area
            row[LB_PHI] = np.pi * radiance * light.area
        elif kind in (POINT, SPOT):
            intensity = _luminance(light.intensity)
            row[LB_C:LB_C + 3] = light.position
            row[LB_I] = intensity
            cone = 2.0 if kind == POINT else (
                (1.0 - light.cos_width) + 0.5 * (light.cos_width - light.cos_cutoff))
            row[LB_PHI] = 2.0 * np.pi * cone * intensity
        elif kind == DIRECTIONAL:
            row[LB_I] = _luminance(light.irradiance)
            row[LB_PHI] = disk * row[LB_I]


def _environment_bounds(t: LightTable, j: int, disk: float, samples: int = 1 << 14) -> None:
    """Environment ``j``'s irradiance as three bands of spherical harmonics (``L_SH``,
    by ``samples`` of its own importance sampling at Sobol points), its intensity (pi
    times the mean radiance: the harmonics' constant band) and power."""
    u = pair_values(np.zeros(samples, dtype=np.int64), np.arange(samples), 0, 0)
    c = environment_sh(t.lights, t.light_tri, t.env_image, t.env_dist, t.sky, t.sky_dist,
                       t.rot_c, t.rot_s, j, u)
    t.lights[j, L_SH:L_SH + 9] = c
    e = max(float(c[0]) * SH_Y00, 0.0)
    t.lights[j, LB_I] = e
    t.lights[j, LB_PHI] = disk * e


def _union(d: float, ra: float, rb: float) -> tuple[float, float]:
    """The smallest ball (or cone) holding balls of radii ``ra`` and ``rb`` whose centres
    are ``d`` apart (cones: half-angles, and the angle between the axes): its radius,
    and how far its centre lies from a's toward b's."""
    if d + rb <= ra:
        return ra, 0.0
    if d + ra <= rb:
        return rb, d
    r = 0.5 * (d + ra + rb)
    return r, r - ra


def _merge_bounds(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """A node of the light tree over two rows: the sphere enclosing both spheres, the
    union of their emission cones (pbrt-v4's ``Union(DirectionCone, DirectionCone)``;
    none if either has none or it covers the sphere), and the sums of intensity, power
    and count; kind -1, links unset."""
    out = np.zeros_like(a)
    out[L_KIND] = -1.0
    out[L_OBJECT] = -1.0
    out[L_PARENT:L_B + 1] = -1.0
    ca, cb = a[LB_C:LB_C + 3], b[LB_C:LB_C + 3]
    d = float(np.linalg.norm(cb - ca))
    r, shift = _union(d, a[LB_R], b[LB_R])
    out[LB_C:LB_C + 3] = ca + (cb - ca) * (shift / d) if shift > 0.0 else ca
    out[LB_R] = r
    out[LB_COS] = -1.0
    if a[LB_COS] > -1.0 and b[LB_COS] > -1.0:
        xa, xb = a[LB_AXIS:LB_AXIS + 3], b[LB_AXIS:LB_AXIS + 3]
        ta, tb = np.arccos(np.clip([a[LB_COS], b[LB_COS]], -1.0, 1.0))
        to, turn = _union(float(np.arccos(np.clip(xa @ xb, -1.0, 1.0))), ta, tb)
        w = xb - (xa @ xb) * xa  # xa turned toward xb by ``turn``
        norm = float(np.linalg.norm(w))
        axis = xa if norm < 1e-12 else np.cos(turn) * xa + np.sin(turn) * w / norm
        if to < np.pi:
            out[LB_AXIS:LB_AXIS + 3] = axis / np.linalg.norm(axis)
            out[LB_COS] = np.cos(to)
    out[LB_I] = a[LB_I] + b[LB_I]
    out[LB_PHI] = a[LB_PHI] + b[LB_PHI]
    out[LB_N] = a[LB_N] + b[LB_N]
    return out


def _with_tree(table: np.ndarray, every_delta: bool) -> np.ndarray:
    """``table`` with the light tree's nodes appended (root first, at row ``n``) and
    linked, over the lights that next-event estimation selects and that have a place
    (area, point and spot lights; delta lights only when they are not sampled at every
    vertex), if there are more than :data:`FLAT_LIGHTS` of them.

    Built top down: the lights' bounding-sphere centres are cut at the median of the
    axis along which they spread most (pbrt-v4 builds its BVHLightSampler by the
    surface-area-orientation heuristic; the median cut is simpler and keeps the tree
    balanced).  A node's bounds merge its children's (:func:`_merge_bounds`)."""
    n = len(table)
    kinds = table[:, L_KIND]
    finite = (kinds == AREA) | (kinds == POINT) | (kinds == SPOT)
    delta = (kinds == POINT) | (kinds == SPOT)
    members = np.flatnonzero(finite & ~delta if every_delta else finite)
    if len(members) <= FLAT_LIGHTS:
        return table
    rows = []

    def row(x: int) -> np.ndarray:
        return table[x] if x < n else rows[x - n]

    def build(items: np.ndarray, parent: int) -> int:
        if len(items) == 1:
            table[items[0], L_PARENT] = parent
            return int(items[0])
        r = n + len(rows)
        rows.append(None)
        c = table[items, LB_C:LB_C + 3]
        order = items[np.argsort(c[:, int(np.argmax(np.ptp(c, axis=0)))], kind="stable")]
        half = len(order) // 2
        a, b = build(order[:half], r), build(order[half:], r)
        rows[r - n] = _merge_bounds(row(a), row(b))
        rows[r - n][L_PARENT], rows[r - n][L_A], rows[r - n][L_B] = parent, a, b
        return r

    build(members, -1)
    return np.vstack([table, np.array(rows)])
