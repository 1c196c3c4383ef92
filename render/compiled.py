"""The integrator's compiled path: the path tracer's bounce in numba loops.

The general integrator (:mod:`render.integrator`) shades a wavefront with numpy passes
per object; :class:`CompiledTrace` runs each bounce as one compiled loop over the lanes
instead, where the scene allows it (:func:`compiled_reason`): no volume, cutout,
thin-walled backface or null interface; emission a constant ``diffuse_edf``; lights
that are emissive objects, point, spot and directional lights and an environment
(constant or a latitude-longitude map).  Every bsdf qualifies: each object's df tree is
a program (:mod:`render.program`) that :mod:`render.interpreter` runs per lane, the
same kernels the general path calls in batches.  Objects whose arguments vary over the
surface (textures, noise, a bumped normal, an explicit ``tangent_u`` or layer
``normal``) are bound per segment by ``material.shade`` (numpy) and their programs'
parameter rows go to the kernel per lane; AOVs are written from the general path's own
shading of the camera rays' hits.

It is the same algorithm, lane for lane: the same random numbers drawn in the same
order, the same light choice, MIS weights, Russian roulette, ray offsets and shadow-ray
aims, and Embree (embreex) still traces every ray in batches.  The tests hold its images
and AOVs equal to the general path's with the same seed.  Displaced objects qualify
(their triangles are diced before rendering).
"""

from __future__ import annotations

from collections import namedtuple

import numpy as np

from render import interpreter
from render.camera import primary_rays
from render.film import empty_aovs
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
from render.numerics import dot
from render.program import SPECULAR_LOBES, ProgramTable

__all__ = ["CompiledTrace", "compiled_reason"]

INV_PI = 1.0 / np.pi

#: ``Tables.light_kind``: the lights the kernels sample
AREA, ENVIRONMENT, POINT, SPOT, DIRECTIONAL, ENVIRONMENT_MAP = 0, 1, 2, 3, 4, 5
_KINDS = {
    ConstantEnvironment: ENVIRONMENT,
    PointLight: POINT,
    SpotLight: SPOT,
    DirectionalLight: DIRECTIONAL,
    LatLongEnvironment: ENVIRONMENT_MAP,
}

#: Scene tables of the kernels (float64 unless noted).
Tables = namedtuple(
    "Tables",
    [
        "packed",  # (v, 14) positions, normals, tangent_u, tangent_v, uv per vertex
        "faces",  # (f, 3) int64
        "face_normal",  # (f, 3)
        "face_object",  # (f,) int64
        "code",  # the objects' bsdf programs (render.program.ProgramTable)
        "kids",
        "frames",
        "chat",  # their Ĉ tables
        "roots",  # (k,) root node of object k's program, -1: black
        "frame_lo",  # (k,) its frames
        "frame_hi",
        "emit_hit",  # (k, 3) radiance seen when a path hits object k (front side)
        "emit_light",  # (k, 3) radiance of object k's light samples (front side)
        "area_pdf",  # (k,) light-selection probability / area
        "light_kind",  # (l,) int64 AREA, ENVIRONMENT, POINT, SPOT or DIRECTIONAL
        "light_object",  # (l,) int64 object of each area light, -1 for the others
        "light_params",  # (l, 11) position, direction, intensity, cos cutoff, cos width
        "light_first",  # (l + 1,) int64 range of each light's triangles in light_faces
        "light_faces",  # (t,) int64 emissive triangles
        "light_cdf",  # (t,) area cdf within each light
        "light_corners",  # (t, 3, 3) their corners
        "light_pdf_area",  # (l,) 1 / area
        "env",  # (3,) constant environment radiance (0: none)
        "env_image",  # (h, w, 3) environment map radiance ((1, 1, 3) zeros: none)
        "env_p",  # (h * w,) its texels' probabilities
        "env_cdf",  # (h * w,) their cdf
        "scalars",  # (7,) select_pdf, eps, max_depth, rr_depth, the environment's kind,
        # cos and sin of the map's rotation
    ],
)


def compiled_reason(integ) -> str | None:
    """Why the scene of ``integ`` cannot take the compiled path (None: it can)."""
    if integ.media or integ.cutout.any() or integ.two_faced.any() or integ.null_candidate.any():
        return "volumes, cutouts, thin-walled backfaces and null interfaces need the general path"
    if integ.encloses.sum() > 1 and any(_may_transmit(o.material.surface.scattering)
                                        for o in integ.objects):
        return ("light transmitted into nested closed objects needs the general path's "
                "stack of media and IORs")
    for light in integ.lights.lights:
        if isinstance(light, AreaLight):
            if _constant_emission(integ, light.object_id) is None:
                return "emission that is not a constant diffuse_edf needs the general path"
        elif type(light) not in _KINDS:
            return f"{type(light).__name__} needs the general path"
    return None


def _may_transmit(node) -> bool:
    """Whether a df tree has a lobe that transmits (then the IOR outside an object
    depends on the objects a path is inside)."""
    stack = [] if node is None else [node]
    while stack:
        n = stack.pop()
        mode = str(n.kwargs.get("mode", "scatter_reflect")).split("::")[-1]
        if n.name == "diffuse_transmission_bsdf" or mode != "scatter_reflect":
            return True
        for value in n.kwargs.values():
            if isinstance(value, list | tuple):
                stack.extend(v for v in value if hasattr(v, "kwargs"))
            elif hasattr(value, "kwargs"):
                stack.append(value)
    return False


def _varying(material) -> bool:
    """Whether an object's bsdf must be bound per lane: an argument that is a function
    of the state, a bumped normal, a varying IOR, or a ``tangent_u``/layer ``normal``
    given explicitly (bound in the local frame of each hit)."""
    if material.geometry.normal is not None or callable(material.ior):
        return True
    node = material.surface.scattering
    stack = [] if node is None else [node]
    while stack:
        n = stack.pop()
        for key, value in n.kwargs.items():
            if key in ("tangent_u", "normal") or callable(value):
                return True
            if isinstance(value, list | tuple):
                stack.extend(v for v in value if hasattr(v, "kwargs"))
            elif hasattr(value, "kwargs"):
                stack.append(value)
    return False


def _constant_program(integ, k: int):
    """Object ``k``'s bsdf program with one parameter row (None: black)."""
    mat = integ.objects[k].material
    node = mat.surface.scattering
    if node is None or node.is_black:
        return None
    from displacement.state import ShadingState

    one = np.array([[0.0, 0.0, 1.0]])
    state = ShadingState(np.zeros((1, 3)), one, np.zeros((1, 2)), np.array([[1.0, 0.0, 0.0]]),
                         np.array([[0.0, 1.0, 0.0]]), integ.objects[k].transform)
    bsdf = node.bind(state, ior_outside=1.0, ior_inside=float(np.mean(mat.ior)),
                     thin_walled=bool(mat.thin_walled))
    return bsdf.program


def _constant_emission(integ, k: int):
    from render.integrator import _constant_diffuse_emission

    return _constant_diffuse_emission(integ.objects[k].material)


class CompiledTrace:
    """``Integrator.trace`` for scenes :func:`compiled_reason` accepts.

    Parameters
    ----------
    integ : render.integrator.Integrator
    """

    def __init__(self, integ):
        geo = integ.geo
        n_obj = len(integ.objects)
        emit_hit = np.zeros((n_obj, 3))
        emit_light = np.zeros((n_obj, 3))
        #: objects shaded per lane by numpy first (arguments that vary over the surface,
        #: a bumped normal); the kernels take their programs' rows and normals per lane
        self.varying = np.zeros(n_obj, dtype=bool)
        #: each object's bsdf program (None: black, or varying: bound per segment)
        self.programs = [None] * n_obj
        for k, obj in enumerate(integ.objects):
            self.varying[k] = _varying(obj.material)
            if not self.varying[k]:
                self.programs[k] = _constant_program(integ, k)
            const = _constant_emission(integ, k)
            if const is not None:
                intensity = np.broadcast_to(
                    np.asarray(obj.material.surface.emission.intensity, dtype=np.float64), (3,)
                )
                radiance, power = const
                light = integ.lights.area_by_object[k]
                # as the general path computes them: edf.eval (1/pi) times the intensity
                # (per area in power mode) on a hit, intensity / pi (per area) when sampled
                emit_hit[k] = INV_PI * (intensity / light.area if power else intensity)
                emit_light[k] = radiance / integ._object_area(k) if power else radiance
        lights = integ.lights.lights
        light_kind = np.array([_KINDS.get(type(light), AREA) for light in lights], dtype=np.int64)
        light_object = np.full(len(lights), -1, dtype=np.int64)
        light_params = np.zeros((len(lights), 11))
        light_first = np.zeros(len(lights) + 1, dtype=np.int64)
        faces, cdf, corners, pdf_area = [], [], [], np.zeros(len(lights))
        env = np.zeros(3)
        env_kind, env_map = 0, None
        for j, light in enumerate(lights):
            kind = light_kind[j]
            if kind == AREA:
                light_object[j] = light.object_id
                faces.append(light.faces)
                cdf.append(light._cdf)
                corners.append(light.corners)
                pdf_area[j] = light.pdf_area
            elif kind == ENVIRONMENT:
                env = np.asarray(light.radiance, dtype=np.float64)
                env_kind = ENVIRONMENT
            elif kind == ENVIRONMENT_MAP:
                env_kind, env_map = ENVIRONMENT_MAP, light
            elif kind == DIRECTIONAL:
                light_params[j, 3:6] = light.direction
                light_params[j, 6:9] = light.irradiance
            else:
                light_params[j, 0:3] = light.position
                light_params[j, 6:9] = light.intensity
                if kind == SPOT:
                    light_params[j, 3:6] = light.direction
                    light_params[j, 9:11] = light.cos_cutoff, light.cos_width
            light_first[j + 1] = light_first[j] + (len(light.faces) if kind == AREA else 0)
        self.integ = integ
        table = ProgramTable(self.programs)
        #: parameter rows of the constant objects (row k: object k)
        self.params = np.zeros((n_obj, table.width))
        for k, prog in enumerate(self.programs):
            if prog is not None:
                self.params[k, : prog.P.shape[1]] = prog.P[0]
        self.tables = Tables(
            geo.packed,
            geo.faces,
            geo.face_normal,
            geo.face_object.astype(np.int64),
            table.code,
            table.kids,
            table.frames,
            table.tables,
            table.roots,
            table.frame_lo,
            table.frame_hi,
            emit_hit,
            emit_light,
            np.asarray(integ.area_pdf, dtype=np.float64),
            light_kind,
            light_object,
            light_params,
            light_first,
            np.concatenate(faces) if faces else np.zeros(0, dtype=np.int64),
            np.concatenate(cdf) if cdf else np.zeros(0),
            np.concatenate(corners) if corners else np.zeros((0, 3, 3)),
            pdf_area,
            env,
            np.zeros((1, 1, 3)) if env_map is None else env_map.image,
            np.zeros(1) if env_map is None else env_map._p,
            np.ones(1) if env_map is None else env_map._cdf,
            np.array(
                [
                    integ.lights.select_pdf,
                    integ.eps,
                    float(integ.max_depth),
                    float(integ.settings.rr_depth),
                    float(env_kind),
                    1.0 if env_map is None else np.cos(env_map.rotation),
                    0.0 if env_map is None else np.sin(env_map.rotation),
                ]
            ),
        )
        # compile (or load from numba's cache) before worker threads start
        self.trace(np.zeros(1, dtype=np.int64), np.random.default_rng(0))

    def trace(self, pixel: np.ndarray, rng: np.random.Generator) -> tuple:
        """Trace one path per entry of ``pixel`` (see :meth:`Integrator.trace`)."""
        integ = self.integ
        n = len(pixel)
        o, d = primary_rays(integ.camera, pixel, rng.random((n, 2)))
        L = np.zeros((n, 3))
        alpha = np.zeros(n)
        ids = np.arange(n)
        beta = np.ones((n, 3))
        depth = np.ones(n, dtype=np.int64)
        prev_pdf = np.zeros(n)
        prev_delta = np.ones(n, dtype=bool)
        offset = integ.geo.face_offset
        aov = empty_aovs(n) if integ.aovs else None
        camera_rays = True
        while len(ids):
            hit = integ._intersect(o, d)
            prim = hit["primID"]
            face = np.where(prim >= 0, offset[np.maximum(hit["geomID"], 0)] + prim, -1)
            m = int(np.count_nonzero(prim >= 0))
            lane_row, params, lane_normal, tables = self._numpy_shading(
                face, hit, d, aov if camera_rays else None
            )
            camera_rays = False
            # the general path's draws, in its order, for the lanes that hit a surface
            rng.random(m)  # cutout decisions (no cutouts here)
            u_light = rng.random((m, 3))
            u_bsdf = rng.random((m, 3))
            u_rr = rng.random(m)
            out = _bounce(
                tables,
                face,
                hit["u"].astype(np.float64),
                hit["v"].astype(np.float64),
                hit["tfar"].astype(np.float64),
                o,
                d,
                ids,
                beta,
                depth,
                prev_pdf,
                prev_delta,
                u_light,
                u_bsdf,
                u_rr,
                lane_row,
                params,
                lane_normal,
                L,
                alpha,
            )
            n_shadow, s_org, s_dir, s_dist, s_c, s_id, n_next, nxt = out
            if n_shadow:
                blocked = integ._occluded(
                    s_org[:n_shadow], s_dir[:n_shadow], s_dist[:n_shadow], rng
                )
                _add_unblocked(L, s_id[:n_shadow], s_c[:n_shadow], blocked)
            o, d, ids, beta, depth, prev_pdf, prev_delta = (a[:n_next] for a in nxt)
        return L, alpha, {} if aov is None else {a: aov[a] for a in integ.aovs}

    def _numpy_shading(self, face, hit, d, aov):
        """The numpy part of a segment: ``material.shade``, as the general path shades
        them and once per object, of the hits on varying objects (their rows and normals
        for the kernels) and, given ``aov`` (camera rays, AOVs asked for), of every hit
        (its AOVs).

        Returns ``lane_row`` (m,), ``params`` (k + q, width): the objects' rows, then
        one per varying lane, ``normals`` (q, 3): lane ``i`` takes row ``k + lane_row[i]``
        and normal ``lane_row[i]``, or its object's row where ``lane_row[i] = -1``; and
        the kernel tables with this segment's programs of the varying objects.
        """
        integ = self.integ
        hit_objects = integ.geo.face_object[np.maximum(face, 0)]
        varying = (face >= 0) & self.varying[hit_objects]
        q = int(np.count_nonzero(varying))
        lane_row = np.full(len(face), -1, dtype=np.int64)
        lane_row[varying] = np.arange(q)
        programs = list(self.programs)
        rows = []
        normals = np.empty((q, 3))
        lanes = np.flatnonzero(face >= 0 if aov is not None else varying)
        objs = hit_objects[lanes]
        for k in np.unique(objs):
            sel = lanes[objs == k]
            f = face[sel]
            p, ns, tu, tv, uv = integ._attributes(
                f, hit["u"][sel].astype(np.float64), hit["v"][sel].astype(np.float64)
            )
            front = dot(-d[sel], integ.geo.face_normal[f]) > 0
            sh = integ._shade(k, integ._object_state(k, p, ns, tu, tv, uv), front)
            nw = ns if sh.normal_world is None else sh.normal_world
            if aov is not None:
                wo = integ._frame(k, sh, ns, tu).to_local(-d[sel])
                integ.write_aovs(aov, sel, k, sh.bsdf, wo, nw, p, uv)
            if self.varying[k]:
                if sh.bsdf is not None:
                    programs[k] = sh.bsdf.program
                    rows.append((lane_row[sel], sh.bsdf.program.P))
                normals[lane_row[sel]] = nw
        if not rows:
            return lane_row, self.params, normals, self.tables
        table = ProgramTable(programs)
        params = np.zeros((len(self.params) + q, table.width))
        params[: len(self.params), : self.params.shape[1]] = self.params
        for at, P in rows:
            params[len(self.params) + at, : P.shape[1]] = P
        tables = self.tables._replace(
            code=table.code, kids=table.kids, frames=table.frames, chat=table.tables,
            roots=table.roots, frame_lo=table.frame_lo, frame_hi=table.frame_hi)
        return lane_row, params, normals, tables


# ------------------------------------------------------------------------- kernels
@njit
def _power(a, b):
    a2 = a * a
    b2 = b * b
    s = a2 + b2
    return a2 / s if s > 0.0 else 0.0


@njit
def _dot(ax, ay, az, bx, by, bz):
    # the general path's order: (x + z) + y
    return ax * bx + az * bz + ay * by


@njit
def _fast_unit(x, y, z):
    """The integrator's _fast_unit for one vector: (ux, uy, uz, valid); rows too short
    are left as they are."""
    length = np.sqrt(_dot(x, y, z, x, y, z))
    if length > 1e-150:
        return x / length, y / length, z / length, True
    return x, y, z, False


@njit
def _unitize(x, y, z):
    """render.numerics.unitize for one vector: (ux, uy, uz, valid)."""
    scale = max(max(abs(x), abs(y)), abs(z))
    if not scale > 1e-300:
        return 0.0, 0.0, 0.0, False
    wx, wy, wz = x / scale, y / scale, z / scale
    length = np.sqrt(_dot(wx, wy, wz, wx, wy, wz))
    return wx / length, wy / length, wz / length, True


@njit
def _frame(nx, ny, nz, tx, ty, tz):
    """Frame.from_normal_tangent for one lane: (s, t) as six floats."""
    c = _dot(tx, ty, tz, nx, ny, nz)
    px, py, pz = tx - c * nx, ty - c * ny, tz - c * nz
    sx, sy, sz, ok = _unitize(px, py, pz)
    ok = ok and np.sqrt(px * px + py * py + pz * pz) > 1e-8 * np.sqrt(tx * tx + ty * ty + tz * tz)
    if not ok:  # Frame.from_normal (Duff et al.)
        sign = 1.0 if nz >= 0.0 else -1.0
        a = -1.0 / (sign + nz)
        b = nx * ny * a
        sx, sy, sz = 1.0 + sign * nx * nx * a, sign * b, -sign * nx
    return sx, sy, sz, ny * sz - nz * sy, nz * sx - nx * sz, nx * sy - ny * sx


@njit
def _search_right(cdf, a, b, u):
    """``a + np.searchsorted(cdf[a:b], u, side="right")``, clipped to ``b - 1``."""
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
    """LatLongEnvironment.pdf and .eval along ``d``: (solid-angle pdf, radiance rgb)."""
    h, w = image.shape[0], image.shape[1]
    x = rot_c * dx - rot_s * dz
    z = rot_s * dx + rot_c * dz
    u = 0.5 + np.arctan2(x, -z) / (2.0 * np.pi)
    v = np.arccos(min(max(dy, -1.0), 1.0)) / np.pi
    i = min(max(int(u * w), 0), w - 1)
    j = min(max(int(v * h), 0), h - 1)
    sin_t = np.sin(np.pi * v)
    pdf = p[j * w + i] * h * w / (2.0 * np.pi * np.pi * sin_t) if sin_t > 1e-12 else 0.0
    return pdf, image[j, i, 0], image[j, i, 1], image[j, i, 2]


@njit(inline="always")
def _sample_light(
    light_first,
    light_cdf,
    light_corners,
    light_faces,
    light_pdf_area,
    light_kind,
    light_object,
    light_params,
    emit_light,
    face_normal,
    env,
    env_image,
    env_p,
    env_cdf,
    rot_c,
    rot_s,
    select,
    j,
    px,
    py,
    pz,
    u1,
    u2,
):
    """LightSet.sample_li of light ``j`` at p: (wi xyz, distance, radiance rgb, pdf,
    delta); ``pdf`` includes the selection probability (delta lights: it alone).

    Takes the arrays of :data:`Tables` one by one and indexes them in place: an array
    taken out of a tuple, or a row view, costs numba two atomic reference-count updates,
    which in a per-lane loop cost more than the shading."""
    kind = light_kind[j]
    if kind == ENVIRONMENT:  # constant environment: uniform sphere
        z = 1.0 - 2.0 * u1
        r = 2.0 * np.sqrt(max(u1 * (1.0 - u1), 0.0))
        phi = 2.0 * np.pi * u2
        return (
            r * np.cos(phi),
            r * np.sin(phi),
            z,
            INFINITE_DISTANCE,
            env[0],
            env[1],
            env[2],
            0.25 / np.pi * select,
            False,
        )
    if kind == ENVIRONMENT_MAP:  # LatLongEnvironment.sample_li: a texel by its cdf
        h, w = env_image.shape[0], env_image.shape[1]
        k = _search_right(env_cdf, 0, len(env_cdf), u1)
        lo = env_cdf[k - 1] if k > 0 else 0.0
        pk = env_p[k]
        du = min(max((u1 - lo) / pk if pk > 0 else 0.5, 0.0), 1.0)
        row, col = k // w, k % w
        phi = ((col + du) / w - 0.5) * 2.0 * np.pi
        theta = (row + u2) / h * np.pi
        st = np.sin(theta)
        x, z = st * np.sin(phi), -st * np.cos(phi)
        wx, wy, wz = rot_c * x + rot_s * z, np.cos(theta), -rot_s * x + rot_c * z
        pdf, e0, e1, e2 = _environment_map(env_image, env_p, rot_c, rot_s, wx, wy, wz)
        if not pdf > 0.0:
            e0 = e1 = e2 = 0.0
        return wx, wy, wz, INFINITE_DISTANCE, e0, e1, e2, pdf * select, False
    lp = light_params
    if kind == DIRECTIONAL:
        return (
            -lp[j, 3],
            -lp[j, 4],
            -lp[j, 5],
            INFINITE_DISTANCE,
            lp[j, 6],
            lp[j, 7],
            lp[j, 8],
            select,
            True,
        )
    if kind != AREA:  # PointLight._towards, then SpotLight's smoothstep falloff
        dx, dy, dz = lp[j, 0] - px, lp[j, 1] - py, lp[j, 2] - pz
        dist = np.sqrt(dx * dx + dy * dy + dz * dz)
        wx, wy, wz, ok = _unitize(dx, dy, dz)
        if not (ok and dist > 0.0):
            return wx, wy, wz, dist, 0.0, 0.0, 0.0, 0.0, True
        scale = 1.0 / (dist * dist)
        if kind == SPOT:
            c = _dot(-wx, -wy, -wz, lp[j, 3], lp[j, 4], lp[j, 5])
            span = lp[j, 10] - lp[j, 9]
            if span <= 0.0:
                falloff = 1.0 if c >= lp[j, 9] else 0.0
            else:
                t = min(max((c - lp[j, 9]) / span, 0.0), 1.0)
                falloff = t * t * (3.0 - 2.0 * t)
            scale = scale * falloff
        return (
            wx,
            wy,
            wz,
            dist,
            scale * lp[j, 6],
            scale * lp[j, 7],
            scale * lp[j, 8],
            select,
            True,
        )
    a, b = light_first[j], light_first[j + 1]
    t = _search_right(light_cdf, a, b, u1)
    lo = light_cdf[t - 1] if t > a else 0.0
    width = light_cdf[t] - lo
    u0 = min(max((u1 - lo) / width if width > 0 else 0.5, 0.0), 1.0)
    su = np.sqrt(max(u0, 0.0))
    b1 = 1.0 - su
    b2 = u2 * su
    b0 = 1.0 - b1 - b2
    c = light_corners
    xx = b0 * c[t, 0, 0] + b1 * c[t, 1, 0] + b2 * c[t, 2, 0]
    xy = b0 * c[t, 0, 1] + b1 * c[t, 1, 1] + b2 * c[t, 2, 1]
    xz = b0 * c[t, 0, 2] + b1 * c[t, 1, 2] + b2 * c[t, 2, 2]
    dx, dy, dz = xx - px, xy - py, xz - pz
    dist = np.sqrt(dx * dx + dy * dy + dz * dz)
    wx, wy, wz, ok = _unitize(dx, dy, dz)
    f = light_faces[t]
    gx, gy, gz = face_normal[f, 0], face_normal[f, 1], face_normal[f, 2]
    cos_l = abs(_dot(wx, wy, wz, gx, gy, gz))
    if not (ok and dist > 0.0 and cos_l > 1e-12):
        return wx, wy, wz, dist, 0.0, 0.0, 0.0, 0.0, False
    pdf = dist * dist / cos_l * light_pdf_area[j] * select
    obj = light_object[j]
    if _dot(-wx, -wy, -wz, gx, gy, gz) > 0.0:  # emitters light their front side
        e = emit_light
        return wx, wy, wz, dist, e[obj, 0], e[obj, 1], e[obj, 2], pdf, False
    return wx, wy, wz, dist, 0.0, 0.0, 0.0, pdf, False


@njit
def _bounce(
    tb,
    face,
    b1,
    b2,
    tfar,
    o,
    d,
    ids,
    beta,
    depth,
    prev_pdf,
    prev_delta,
    u_light,
    u_bsdf,
    u_rr,
    lane_row,
    params,
    lane_normal,
    L,
    alpha,
):
    """One segment of every lane: escapes, emission, NEE (shadow rays returned), the
    sampled continuation and Russian roulette.  Returns the shadow rays and the lanes
    that go on, compacted in order.  Bsdf rows come from ``params``
    (:meth:`CompiledTrace._numpy_shading`); lanes with ``lane_row >= 0`` also take their
    shading normal from ``lane_normal``."""
    (
        packed,
        faces,
        face_normal,
        face_object,
        code,
        kids,
        frames,
        chat,
        roots,
        frame_lo,
        frame_hi,
        emit_hit,
        emit_light,
        area_pdf,
        light_kind,
        light_object,
        light_params,
        light_first,
        light_faces,
        light_cdf,
        light_corners,
        light_pdf_area,
        env,
        env_image,
        env_p,
        env_cdf,
        scalars,
    ) = tb
    m = len(face)
    select, eps = scalars[0], scalars[1]
    max_depth, rr_depth = scalars[2], scalars[3]
    n_lights = len(light_object)
    n_objects = len(roots)
    ws = np.empty(interpreter.work_size(code.shape[0], kids.shape[0], frames.shape[0]))
    tp = packed
    s_org = np.empty((m, 3))
    s_dir = np.empty((m, 3))
    s_dist = np.empty(m)
    s_c = np.empty((m, 3))
    s_id = np.empty(m, dtype=np.int64)
    n_o = np.empty((m, 3))
    n_d = np.empty((m, 3))
    n_ids = np.empty(m, dtype=np.int64)
    n_beta = np.empty((m, 3))
    n_depth = np.empty(m, dtype=np.int64)
    n_pdf = np.empty(m)
    n_delta = np.empty(m, dtype=np.bool_)
    ns = 0
    nn = 0
    r = -1  # rank of the lane among the surface hits (its random numbers)
    env_kind, rot_c, rot_s = scalars[4], scalars[5], scalars[6]
    env_pdf = 0.25 / np.pi * select
    for i in range(m):
        lane = ids[i]
        if face[i] < 0:
            if env_kind == ENVIRONMENT:
                w = 1.0 if prev_delta[i] else _power(prev_pdf[i], env_pdf)
                for c in range(3):
                    L[lane, c] += beta[i, c] * env[c] * w
            elif env_kind == ENVIRONMENT_MAP:
                pe, e0, e1, e2 = _environment_map(
                    env_image, env_p, rot_c, rot_s, d[i, 0], d[i, 1], d[i, 2]
                )
                w = 1.0 if prev_delta[i] else _power(prev_pdf[i], pe * select)
                L[lane, 0] += beta[i, 0] * e0 * w
                L[lane, 1] += beta[i, 1] * e1 * w
                L[lane, 2] += beta[i, 2] * e2 * w
            continue
        r += 1
        f = face[i]
        k = face_object[f]
        # attributes: Geometry.interpolate, then unit normal and tangent
        v0, v1, v2 = faces[f, 0], faces[f, 1], faces[f, 2]
        w1, w2 = b1[i], b2[i]
        w0 = 1.0 - w1 - w2
        px = w0 * tp[v0, 0] + w1 * tp[v1, 0] + w2 * tp[v2, 0]
        py = w0 * tp[v0, 1] + w1 * tp[v1, 1] + w2 * tp[v2, 1]
        pz = w0 * tp[v0, 2] + w1 * tp[v1, 2] + w2 * tp[v2, 2]
        nx, ny, nz, ok = _fast_unit(
            w0 * tp[v0, 3] + w1 * tp[v1, 3] + w2 * tp[v2, 3],
            w0 * tp[v0, 4] + w1 * tp[v1, 4] + w2 * tp[v2, 4],
            w0 * tp[v0, 5] + w1 * tp[v1, 5] + w2 * tp[v2, 5],
        )
        gx, gy, gz = face_normal[f, 0], face_normal[f, 1], face_normal[f, 2]
        if not ok:
            nx, ny, nz = gx, gy, gz
        tx, ty, tz, _ = _fast_unit(
            w0 * tp[v0, 6] + w1 * tp[v1, 6] + w2 * tp[v2, 6],
            w0 * tp[v0, 7] + w1 * tp[v1, 7] + w2 * tp[v2, 7],
            w0 * tp[v0, 8] + w1 * tp[v1, 8] + w2 * tp[v2, 8],
        )
        row = k
        if lane_row[i] >= 0:
            v = lane_row[i]
            nx, ny, nz = lane_normal[v, 0], lane_normal[v, 1], lane_normal[v, 2]
            row = n_objects + v
        sx, sy, sz, qx, qy, qz = _frame(nx, ny, nz, tx, ty, tz)
        ox, oy, oz = -d[i, 0], -d[i, 1], -d[i, 2]
        wox = _dot(ox, oy, oz, sx, sy, sz)
        woy = _dot(ox, oy, oz, qx, qy, qz)
        woz = _dot(ox, oy, oz, nx, ny, nz)
        g_wo = _dot(ox, oy, oz, gx, gy, gz)
        if depth[i] == 1:
            alpha[lane] = 1.0
        # emission, weighted against light sampling
        e = emit_hit
        if (e[k, 0] != 0.0 or e[k, 1] != 0.0 or e[k, 2] != 0.0) and g_wo > 0.0 and woz > 1e-10:
            cos_l = abs(g_wo)
            pl = area_pdf[k] * tfar[i] ** 2 / cos_l
            w = 1.0 if prev_delta[i] else _power(prev_pdf[i], pl)
            for c in range(3):
                L[lane, c] += beta[i, c] * e[k, c] * w
        root = roots[k]
        if root < 0 or not depth[i] < max_depth:
            continue
        f_lo, f_hi = frame_lo[k], frame_hi[k]
        # next-event estimation
        j = min(int(u_light[r, 0] * n_lights), n_lights - 1)
        lx, ly, lz, ldist, l0, l1, l2, lpdf, ldelta = _sample_light(
            light_first,
            light_cdf,
            light_corners,
            light_faces,
            light_pdf_area,
            light_kind,
            light_object,
            light_params,
            emit_light,
            face_normal,
            env,
            env_image,
            env_p,
            env_cdf,
            rot_c,
            rot_s,
            select,
            j,
            px,
            py,
            pz,
            u_light[r, 1],
            u_light[r, 2],
        )
        wlx = _dot(lx, ly, lz, sx, sy, sz)
        wly = _dot(lx, ly, lz, qx, qy, qz)
        wlz = _dot(lx, ly, lz, nx, ny, nz)
        f0, f1, f2, pb = interpreter.eval_pdf(code, kids, frames, params, chat, row, ws, root,
                                              f_lo, f_hi, wox, woy, woz, wlx, wly, wlz)
        g_wi = _dot(lx, ly, lz, gx, gy, gz)
        if lpdf > 0.0 and g_wi != 0.0 and ((g_wi * g_wo > 0.0) == (wlz * woz > 0.0)):
            w = (1.0 if ldelta else _power(lpdf, pb)) / lpdf
            c0, c1, c2 = (
                beta[i, 0] * f0 * l0 * w,
                beta[i, 1] * f1 * l1 * w,
                beta[i, 2] * f2 * l2 * w,
            )
            if c0 > 0.0 or c1 > 0.0 or c2 > 0.0:
                side = 1.0 if g_wi >= 0.0 else -1.0
                qx0, qy0, qz0 = px + side * eps * gx, py + side * eps * gy, pz + side * eps * gz
                finite = ldist < INFINITE_DISTANCE
                if finite:
                    ex, ey, ez = px + lx * ldist - qx0, py + ly * ldist - qy0, pz + lz * ldist - qz0
                    ux, uy, uz, ok = _unitize(ex, ey, ez)
                    if not ok:
                        ux, uy, uz = lx, ly, lz
                    sdist = np.sqrt(ex * ex + ey * ey + ez * ez)
                else:
                    ux, uy, uz, sdist = lx, ly, lz, ldist
                s_org[ns, 0], s_org[ns, 1], s_org[ns, 2] = qx0, qy0, qz0
                s_dir[ns, 0], s_dir[ns, 1], s_dir[ns, 2] = ux, uy, uz
                s_dist[ns] = sdist * (1.0 - 1e-6) - eps
                s_c[ns, 0], s_c[ns, 1], s_c[ns, 2] = c0, c1, c2
                s_id[ns] = lane
                ns += 1
        # the bsdf's sample continues the path
        wix, wiy, wiz, pdf, w0, w1, w2, lobe = interpreter.sample(
            code, kids, frames, params, chat, row, ws, root, f_lo, f_hi, wox, woy, woz,
            u_bsdf[r, 0], u_bsdf[r, 1], u_bsdf[r, 2]
        )
        if lobe == 0 or not (w0 > 0.0 or w1 > 0.0 or w2 > 0.0):
            continue
        delta = (lobe & SPECULAR_LOBES) != 0
        dx = wix * sx + wiy * qx + wiz * nx
        dy = wix * sy + wiy * qy + wiz * ny
        dz = wix * sz + wiy * qz + wiz * nz
        g_new = _dot(dx, dy, dz, gx, gy, gz)
        if g_new == 0.0 or (g_new * g_wo > 0.0) != (wiz * woz > 0.0):
            continue
        t0, t1, t2 = beta[i, 0] * w0, beta[i, 1] * w1, beta[i, 2] * w2
        if depth[i] >= rr_depth:
            q = min(max(max(t0, t1), t2), 0.95)
            if not u_rr[r] < q:
                continue
            q = max(q, 1e-300)
            t0, t1, t2 = t0 / q, t1 / q, t2 / q
        side = 1.0 if g_new >= 0.0 else -1.0
        n_o[nn, 0], n_o[nn, 1], n_o[nn, 2] = (
            px + side * eps * gx,
            py + side * eps * gy,
            pz + side * eps * gz,
        )
        n_d[nn, 0], n_d[nn, 1], n_d[nn, 2] = dx, dy, dz
        n_ids[nn] = lane
        n_beta[nn, 0], n_beta[nn, 1], n_beta[nn, 2] = t0, t1, t2
        n_depth[nn] = depth[i] + 1
        n_pdf[nn] = pdf
        n_delta[nn] = delta
        nn += 1
    return (
        ns,
        s_org,
        s_dir,
        s_dist,
        s_c,
        s_id,
        nn,
        (n_o, n_d, n_ids, n_beta, n_depth, n_pdf, n_delta),
    )


@njit
def _add_unblocked(L, s_id, s_c, blocked):
    for i in range(len(s_id)):
        if not blocked[i]:
            for c in range(3):
                L[s_id[i], c] += s_c[i, c]
