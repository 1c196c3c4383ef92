"""The wavefront path tracer: batches of rays through Embree, shading vectorized per object.

Algorithm (unidirectional path tracing, as Mitsuba 3's ``path`` integrator):

* primary rays through random points of each pixel (box filter);
* per bounce, ONE Embree call for all live paths; hits are grouped by object and each
  group is shaded at once by its material (``material.shade(state)`` on a
  :class:`~displacement.state.ShadingState` of that group's lanes, in object space);
* emission found by a ray is weighted by multiple importance sampling (power
  heuristic) against next-event estimation; next-event estimation picks one light
  uniformly (area, point, spot, directional or environment), evaluates the BSDF
  toward it and traces one shadow ray per lane (one Embree occlusion call);
* the BSDF's own sample continues the path (specular lobes too); Russian roulette from
  ``rr_depth``; ``max_depth`` counts path vertices after the camera, as Mitsuba does;
* cutout opacity is stochastic: a lane passes through a surface with probability
  ``1 - cutout_opacity`` without a bounce (shadow rays too); alpha is 1 where a path's
  first opaque hit exists;
* ray origins are offset along the geometric normal by ``RAY_EPS`` times the scene's
  size (plus float32 rounding of the coordinates), because Embree's tnear is 0.

The path state keeps a per-lane ``medium`` index (-1 = outside every object) ready for
homogeneous volumes, thin walls and layers, which come later.

Parallelism: the image's samples are cut into fixed chunks; each chunk has its own
random stream (``SeedSequence([seed, pass, chunk])``), so the image does not depend on
how many threads run, and two threads trace their own chunks at once (Embree releases
the GIL).  Same seed, same image.
"""

from __future__ import annotations

import time as _time
from concurrent.futures import ThreadPoolExecutor
from dataclasses import dataclass

import numpy as np

from render.camera import primary_rays
from render.film import Film
from render.frame import Frame
from render.lights import INFINITE_DISTANCE, AreaLight, LightSet
from render.numerics import dot, unitize

__all__ = ["render", "Integrator", "RAY_EPS", "CHUNK"]

#: ray-origin offset relative to the scene's bounding-box diagonal
RAY_EPS = 1e-5
#: samples per work item (each has its own random stream)
CHUNK = 1 << 16
#: fewest samples in one pass (the unit of the time budget and of the progress bar)
PASS_SAMPLES = 1 << 19
#: a lane may pass through at most this many cutout surfaces per segment
MAX_CUTOUT_CROSSINGS = 64


def _fast_unit(v: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Unit rows of interpolated attribute vectors (bounded, finite): ``(u, valid)``;
    rows shorter than 1e-150 give 0 and ``valid = False``."""
    length = np.sqrt(np.einsum("ij,ij->i", v, v))
    ok = length > 1e-150
    return v / np.where(ok, length, 1.0)[:, None], ok


def _power(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Power-heuristic weight of ``a`` against ``b`` (0 where both are 0)."""
    a2, b2 = a * a, b * b
    s = a2 + b2
    return np.where(s > 0, a2 / np.where(s > 0, s, 1.0), 0.0)


@dataclass
class _Shaded:
    """One object's shading of its lanes (what ``material.shade`` returned, resolved)."""

    bsdf: object
    edf: object
    intensity: np.ndarray
    mode: str
    normal_world: np.ndarray
    opacity: np.ndarray
    frame: Frame | None = None


class Integrator:
    """A path tracer for one built scene.

    Parameters
    ----------
    scene : render.scene.Scene
    geometry : render.scene.Geometry
        ``scene.build()``.
    aovs : iterable of str
        AOVs for the film (:data:`render.film.AOVS`).
    """

    def __init__(self, scene, geometry, aovs=()):
        self.scene = scene
        self.geo = geometry
        self.camera = scene.camera
        self.settings = scene.settings
        self.objects = scene.objects
        self.aovs = tuple(aovs)
        # scene-relative, plus the float32 rounding of the largest coordinate
        geometry.packed  # noqa: B018 - build the packed attribute table before threads start
        self.eps = RAY_EPS * geometry.extent + 4e-7 * float(np.abs(geometry.vertices).max())
        self.area = {}
        lights = list(scene.lights)
        for k, obj in enumerate(self.objects):
            if _is_emissive(obj.material):
                first, last = geometry.face_offset[k], geometry.face_offset[k + 1]
                faces = np.arange(first, last)
                corners = geometry.vertices[geometry.faces[faces]]
                light = AreaLight(
                    k, faces, corners, geometry.face_normal[faces], self._emission_fn(k)
                )
                lights.append(light)
        self.lights = LightSet(lights)
        self.area_pdf = np.zeros(len(self.objects))
        for k, light in self.lights.area_by_object.items():
            self.area_pdf[k] = light.pdf_area * self.lights.select_pdf
        self.cutout = np.array([_has_cutout(o.material) for o in self.objects], dtype=bool)
        # thin-walled materials with their own backface are shaded per side
        self.two_faced = np.array(
            [
                bool(getattr(o.material, "thin_walled", False))
                and not getattr(getattr(o.material, "backface", None), "is_default", True)
                for o in self.objects
            ],
            dtype=bool,
        )
        self.max_depth = self.settings.max_depth if self.settings.max_depth > 0 else 1 << 30
        # objects whose transform has no rotation or scale: object frames are world frames
        self.rigid_identity = np.array([np.array_equal(o.linear, np.eye(3)) for o in self.objects])
        self.embree_time = 0.0
        self.rays = 0

    # ----------------------------------------------------------------- shading
    def _attributes(self, face: np.ndarray, b1: np.ndarray, b2: np.ndarray):
        """World position, unit shading normal, unit tangents and uv at hit points."""
        p, n, tu, tv, uv = self.geo.interpolate(face, b1, b2)
        ns, ok = _fast_unit(n)
        if not np.all(ok):
            ns = np.where(ok[:, None], ns, self.geo.face_normal[face])
        return p, ns, _fast_unit(tu)[0], _fast_unit(tv)[0], uv

    def _object_state(self, k: int, p, ns, tu, tv, uv):
        """The object-space ShadingState of lanes of object ``k`` from world attributes."""
        from displacement.state import ShadingState

        obj = self.objects[k]
        if self.rigid_identity[k]:
            return ShadingState(p - obj.translation, ns, uv, tu, tv)
        return ShadingState(
            obj.to_object_points(p),
            obj.to_object_normals(ns),
            uv,
            obj.to_object_vectors(tu),
            obj.to_object_vectors(tv),
        )

    def _state(self, k: int, face: np.ndarray, b1: np.ndarray, b2: np.ndarray):
        """World attributes and the object-space ShadingState at points of object ``k``."""
        p, ns, tu, tv, uv = self._attributes(face, b1, b2)
        return p, ns, tu, uv, self._object_state(k, p, ns, tu, tv, uv)

    def _shade(self, k: int, state, front: np.ndarray | None = None) -> _Shaded:
        obj = self.objects[k]
        sh = obj.material.shade(state, front)
        n = len(state)
        nrm = getattr(sh, "normal", None)
        if nrm is None:
            normal_world = None
        elif self.rigid_identity[k]:
            normal_world = np.asarray(nrm, dtype=np.float64)
        else:
            normal_world = obj.to_world_normals(np.asarray(nrm, dtype=np.float64))
        op = getattr(sh, "cutout_opacity", 1.0)
        op = np.broadcast_to(np.clip(np.asarray(op, dtype=np.float64), 0.0, 1.0), (n,))
        intensity = np.broadcast_to(
            np.asarray(getattr(sh, "intensity", 0.0), dtype=np.float64), (n, 3)
        )
        return _Shaded(
            getattr(sh, "bsdf", None),
            getattr(sh, "edf", None),
            intensity,
            str(getattr(sh, "mode", "intensity_radiant_exitance")),
            normal_world,
            op,
            getattr(sh, "frame", None),
        )

    def _shade_sides(self, k: int, state, front: np.ndarray) -> np.ndarray:
        """Cutout opacity (n,) of object ``k`` (shading front and back lanes apart when needed)."""
        if not self.two_faced[k]:
            return self._shade(k, state, front).opacity
        out = np.ones(len(state))
        for side in (front, ~front):
            if np.any(side):
                out[side] = self._shade(k, state.subset(side), front[side]).opacity
        return out

    def _emitted(self, k: int, sh: _Shaded, frame: Frame, wo_world: np.ndarray) -> np.ndarray:
        """Radiance (n, 3) emitted toward ``wo_world`` by object ``k`` (0 without an edf)."""
        n = len(wo_world)
        if sh.edf is None:
            return np.zeros((n, 3))
        intensity = sh.intensity
        if "power" in sh.mode:
            light = self.lights.area_by_object.get(k)
            intensity = intensity / (light.area if light is not None else 1.0)
        return sh.edf.eval(frame.to_local(wo_world)) * intensity

    def _emission_fn(self, k: int):
        const = _constant_diffuse_emission(self.objects[k].material)
        if const is not None:
            # a diffuse_edf of constant intensity: radiance I / pi on the front side, no shading
            radiance, power = const
            if power:
                radiance = radiance / self._object_area(k)
            face_normal = self.geo.face_normal

            def constant_emission(face, bary, wo_world):
                front = dot(wo_world, face_normal[face]) > 0
                return np.where(front[:, None], radiance, 0.0)

            return constant_emission

        def emission(face, bary, wo_world):
            _, ns, tu, _, state = self._state(k, face, bary[:, 1], bary[:, 2])
            front = dot(wo_world, self.geo.face_normal[face]) > 0
            out = np.zeros((len(face), 3))
            for side in (front, ~front) if self.two_faced[k] else (np.ones(len(face), dtype=bool),):
                if not np.any(side):
                    continue
                sub = state if side.all() else state.subset(side)
                sh = self._shade(k, sub, front[side])
                nw = sh.normal_world if sh.normal_world is not None else ns[side]
                out[side] = self._emitted(
                    k, sh, Frame.from_normal_tangent(nw, tu[side]), wo_world[side]
                )
            return out

        return emission

    def _object_area(self, k: int) -> float:
        first, last = self.geo.face_offset[k], self.geo.face_offset[k + 1]
        c = self.geo.vertices[self.geo.faces[first:last]]
        return float(
            0.5 * np.linalg.norm(np.cross(c[:, 1] - c[:, 0], c[:, 2] - c[:, 0]), axis=1).sum()
        )

    # ------------------------------------------------------------------ rays
    def _offset(self, p: np.ndarray, ng: np.ndarray, toward: np.ndarray) -> np.ndarray:
        """``p`` pushed off the surface along ``ng`` to the side ``toward`` points to."""
        side = np.where(dot(toward, ng) >= 0.0, 1.0, -1.0)
        return p + (side * self.eps)[:, None] * ng

    def _intersect(self, o: np.ndarray, d: np.ndarray, tfar: np.ndarray | None = None) -> dict:
        t0 = _time.perf_counter()
        o32 = np.ascontiguousarray(o, dtype=np.float32)
        d32 = np.ascontiguousarray(d, dtype=np.float32)
        if tfar is None:
            hit = self.geo.embree.run(o32, d32, output=1)
        else:
            hit = self.geo.embree.run(
                o32, d32, dists=np.ascontiguousarray(tfar, dtype=np.float32), output=1
            )
        self.embree_time += _time.perf_counter() - t0
        self.rays += len(o)
        return hit

    def _occluded(self, o: np.ndarray, d: np.ndarray, dist: np.ndarray, rng) -> np.ndarray:
        """(n,) bool: something opaque lies on the segments (cutouts pass stochastically)."""
        if len(o) == 0:
            return np.zeros(0, dtype=bool)
        dist = np.maximum(dist, 0.0)
        if not self.cutout.any():
            t0 = _time.perf_counter()
            res = self.geo.embree.run(
                np.ascontiguousarray(o, dtype=np.float32),
                np.ascontiguousarray(d, dtype=np.float32),
                dists=np.ascontiguousarray(dist, dtype=np.float32),
                query="OCCLUDED",
            )
            self.embree_time += _time.perf_counter() - t0
            self.rays += len(o)
            return np.asarray(res) != -1
        occluded = np.zeros(len(o), dtype=bool)
        live = np.arange(len(o))
        o = o.copy()
        dist = dist.copy()
        for _ in range(MAX_CUTOUT_CROSSINGS):
            if len(live) == 0:
                break
            hit = self._intersect(o[live], d[live], dist[live])
            prim = hit["primID"]
            got = prim >= 0
            live = live[got]
            if len(live) == 0:
                break
            face = self.geo.face_offset[hit["geomID"][got]] + prim[got]
            objs = self.geo.face_object[face]
            b1 = hit["u"][got].astype(np.float64)
            b2 = hit["v"][got].astype(np.float64)
            passes = np.zeros(len(live), dtype=bool)
            u = rng.random(len(live))
            for k in np.flatnonzero(self.cutout):
                sel = np.flatnonzero(objs == k)
                if len(sel) == 0:
                    continue
                _, _, _, _, state = self._state(k, face[sel], b1[sel], b2[sel])
                sh = self._shade_sides(
                    k, state, dot(d[live][sel], self.geo.face_normal[face[sel]]) < 0
                )
                passes[sel] = u[sel] >= sh
            occluded[live[~passes]] = True
            live = live[passes]
            if len(live):
                t = hit["tfar"][got][passes].astype(np.float64)
                fp = face[passes]
                p = self.geo.interpolate(fp, b1[passes], b2[passes])[0]
                ng = self.geo.face_normal[fp]
                o[live] = self._offset(p, ng, d[live])
                dist[live] = np.maximum(dist[live] - t - self.eps, 0.0)
        occluded[live] = True  # still crossing cutouts after the cap: call it blocked
        return occluded

    # --------------------------------------------------------------- one chunk
    def trace(self, pixel: np.ndarray, rng: np.random.Generator) -> tuple:
        """Trace one path per entry of ``pixel``.

        Parameters
        ----------
        pixel : (n,) int64
        rng : numpy.random.Generator

        Returns
        -------
        rgb : (n, 3) float64
        alpha : (n,) float64
        aovs : dict of arrays
        """
        n = len(pixel)
        geo = self.geo
        o, d = primary_rays(self.camera, pixel, rng.random((n, 2)))
        L = np.zeros((n, 3))
        alpha = np.zeros(n)
        want = set(self.aovs)
        aov = {
            "albedo": np.zeros((n, 3)),
            "normal": np.zeros((n, 3)),
            "depth": np.zeros(n),
            "uv": np.zeros((n, 2)),
            "object_id": np.full(n, -1, dtype=np.int32),
        }
        # path state of the live lanes (compacted every segment)
        ids = np.arange(n)
        beta = np.ones((n, 3))
        depth = np.ones(n, dtype=np.int64)  # depth of the vertex the ray will find
        prev_pdf = np.zeros(n)
        prev_delta = np.ones(n, dtype=bool)  # camera rays count as specular (no MIS)
        first = np.ones(n, dtype=bool)  # no opaque surface seen yet
        crossings = np.zeros(n, dtype=np.int64)
        medium = np.full(n, -1, dtype=np.int32)  # for volumes (later): -1 = outside
        env = self.lights.environment
        cam_fwd = self.camera.forward

        while len(ids):
            hit = self._intersect(o, d)
            prim = hit["primID"]
            miss = prim < 0
            if np.any(miss):
                if env is not None:
                    dm = d[miss]
                    le = env.eval(dm)
                    w = np.where(
                        prev_delta[miss],
                        1.0,
                        _power(prev_pdf[miss], env.pdf(dm) * self.lights.select_pdf),
                    )
                    L[ids[miss]] += beta[miss] * le * w[:, None]
            keep = ~miss
            if not np.any(keep):
                break
            (ids, o, d, beta, depth, prev_pdf, prev_delta, first, crossings, medium) = (
                a[keep]
                for a in (ids, o, d, beta, depth, prev_pdf, prev_delta, first, crossings, medium)
            )
            m = len(ids)
            face = geo.face_offset[hit["geomID"][keep]] + prim[keep]
            b1 = hit["u"][keep].astype(np.float64)
            b2 = hit["v"][keep].astype(np.float64)
            t = hit["tfar"][keep].astype(np.float64)
            objs = geo.face_object[face]
            ng = geo.face_normal[face]
            wo_world = -d

            # per-lane results of the shading groups
            passes = np.zeros(m, dtype=bool)
            u_cut = rng.random(m)
            u_light = rng.random((m, 3))
            u_bsdf = rng.random((m, 3))
            u_rr = rng.random(m)
            new_d = np.zeros((m, 3))
            new_w = np.zeros((m, 3))
            new_pdf = np.zeros(m)
            new_delta = np.zeros(m, dtype=bool)
            scatter = np.zeros(m, dtype=bool)
            nee_c = np.zeros((m, 3))
            nee_ok = np.zeros(m, dtype=bool)
            can_continue = depth < self.max_depth

            # light samples for every lane (one light each)
            front_all = dot(wo_world, ng) > 0
            groups = []
            for k in np.unique(objs):
                sel = np.flatnonzero(objs == k)
                if self.two_faced[k]:
                    groups += [
                        (k, g) for g in (sel[front_all[sel]], sel[~front_all[sel]]) if len(g)
                    ]
                else:
                    groups.append((k, sel))
            p_all, ns_all, tu_all, tv_all, uv_all = self._attributes(face, b1, b2)
            lw, ldist, lli, lpdf, ldelta = self.lights.sample_li(
                p_all, u_light[:, 0], u_light[:, 1:]
            )

            for k, sel in groups:
                whole = len(groups) == 1
                p, ns, tu, uv = (
                    (p_all, ns_all, tu_all, uv_all)
                    if whole
                    else (p_all[sel], ns_all[sel], tu_all[sel], uv_all[sel])
                )
                state = self._object_state(k, p, ns, tu, tv_all if whole else tv_all[sel], uv)
                sh = self._shade(k, state, front_all[sel])
                if self.cutout[k]:
                    ps = u_cut[sel] >= sh.opacity
                    passes[sel] = ps & (crossings[sel] < MAX_CUTOUT_CROSSINGS)
                opaque = ~passes[sel]
                nw = sh.normal_world if sh.normal_world is not None else ns
                frame = (
                    sh.frame
                    if (self.rigid_identity[k] and sh.frame is not None)
                    else Frame.from_normal_tangent(nw, tu)
                )
                wo = frame.to_local(wo_world[sel])
                g_wo = dot(wo_world[sel], ng[sel])
                # emission, weighted against light sampling
                if sh.edf is not None:
                    le = self._emitted(k, sh, frame, wo_world[sel])
                    cos_l = np.abs(g_wo)
                    pl = np.where(
                        cos_l > 0,
                        self.area_pdf[k] * t[sel] ** 2 / np.where(cos_l > 0, cos_l, 1.0),
                        0.0,
                    )
                    w = np.where(prev_delta[sel], 1.0, _power(prev_pdf[sel], pl))
                    L[ids[sel]] += np.where(opaque[:, None], beta[sel] * le * w[:, None], 0.0)
                # first opaque hit: alpha and AOVs
                fo = first[sel] & opaque
                if np.any(fo):
                    lanes = ids[sel][fo]
                    alpha[lanes] = 1.0
                    if want:
                        if "albedo" in want and sh.bsdf is not None:
                            aov["albedo"][lanes] = sh.bsdf.albedo(wo[fo])
                        aov["normal"][lanes] = nw[fo]
                        aov["depth"][lanes] = dot(
                            p[fo] - np.asarray(self.camera.position, dtype=np.float64),
                            np.broadcast_to(cam_fwd, (int(fo.sum()), 3)),
                        )
                        aov["uv"][lanes] = uv[fo]
                        aov["object_id"][lanes] = k
                bsdf = sh.bsdf
                live = opaque & can_continue[sel]
                if bsdf is None or not np.any(live):
                    continue
                # next-event estimation
                wl = frame.to_local(lw[sel])
                f, pb = bsdf.eval_pdf(wo, wl)
                g_wi = dot(lw[sel], ng[sel])
                consistent = (g_wi * g_wo > 0) == (wl[:, 2] * wo[:, 2] > 0)
                w = np.where(ldelta[sel], 1.0, _power(lpdf[sel], pb))
                ok = live & (lpdf[sel] > 0) & consistent & (g_wi != 0)
                contrib = beta[sel] * f * lli[sel] * (w / np.where(ok, lpdf[sel], 1.0))[:, None]
                ok &= np.any(contrib > 0, axis=1)
                nee_c[sel] = np.where(ok[:, None], contrib, 0.0)
                nee_ok[sel] = ok
                # continue the path with the BSDF's sample
                s = bsdf.sample(wo, u_bsdf[sel, 0], u_bsdf[sel, 1:])
                wi_world = frame.to_world(s.wi)
                g_new = dot(wi_world, ng[sel])
                consistent = (g_new * g_wo > 0) == (s.wi[:, 2] * wo[:, 2] > 0)
                sc = live & s.valid & consistent & (g_new != 0) & np.any(s.weight > 0, axis=1)
                scatter[sel] = sc
                new_d[sel] = wi_world
                new_w[sel] = s.weight
                new_pdf[sel] = s.pdf
                new_delta[sel] = s.is_delta

            # shadow rays
            if np.any(nee_ok):
                q = np.flatnonzero(nee_ok)
                org = self._offset(p_all[q], ng[q], lw[q])
                # aim from the offset origin at the light point itself (lights at a
                # finite distance), and stop short of it
                finite = ldist[q] < INFINITE_DISTANCE
                target = p_all[q] + lw[q] * np.where(finite, ldist[q], 0.0)[:, None]
                sd, sok = unitize(target - org)
                sdir = np.where((finite & sok)[:, None], sd, lw[q])
                sdist = np.where(finite, np.linalg.norm(target - org, axis=1), ldist[q])
                far = sdist * (1.0 - 1e-6) - self.eps
                occ = self._occluded(org, sdir, far, rng)
                vis = q[~occ]
                L[ids[vis]] += nee_c[vis]

            # lanes that pass through a cutout keep going straight on
            first &= passes
            crossings = np.where(passes, crossings + 1, 0)
            beta = np.where(scatter[:, None], beta * new_w, beta)
            # Russian roulette
            rr = scatter & (depth >= self.settings.rr_depth)
            qrr = np.minimum(beta.max(axis=1), 0.95)
            survive = ~rr | (u_rr < qrr)
            beta = np.where(
                (rr & survive)[:, None],
                beta / np.where(rr, np.maximum(qrr, 1e-300), 1.0)[:, None],
                beta,
            )
            go = passes | (scatter & survive)
            nd = np.where(passes[:, None], d, new_d)
            o = self._offset(p_all, ng, nd)[go]
            d = nd[go]
            prev_pdf = np.where(passes, prev_pdf, new_pdf)[go]
            prev_delta = np.where(passes, prev_delta, new_delta)[go]
            depth = np.where(passes, depth, depth + 1)[go]
            ids, beta, first, crossings, medium = (
                ids[go],
                beta[go],
                first[go],
                crossings[go],
                medium[go],
            )

        aovs = {a: aov[a] for a in self.aovs}
        return L, alpha, aovs

    # -------------------------------------------------------------- the image
    def render(
        self,
        spp: int | None = None,
        time_budget: float | None = None,
        seed: int | None = None,
        progress: bool = True,
        threads: int = 2,
    ) -> Film:
        """Render the scene into a :class:`~render.film.Film`.

        Parameters
        ----------
        spp : int, optional
            Samples per pixel (default: the scene's).
        time_budget : float, optional
            Seconds: render passes until the budget is spent (overrides ``spp``).
        seed : int, optional
        progress : bool
            Show a tqdm progress bar.
        threads : int
            Worker threads (each traces its own chunks).
        """
        st = self.settings
        if spp is None and time_budget is None:
            time_budget = st.time
        spp = st.spp if spp is None else int(spp)
        seed = st.seed if seed is None else int(seed)
        film = Film(self.camera.width, self.camera.height, self.aovs)
        npix = film.pixel_count
        # a pass holds at least PASS_SAMPLES samples (small images: several spp per pass);
        # independent of the thread count, so the image is too
        per_pass = max(1, st.spp_per_pass, -(-PASS_SAMPLES // npix))
        if not time_budget:
            per_pass = min(per_pass, spp)
        passes = None if time_budget else -(-spp // per_pass)
        bar = None
        if progress:
            from tqdm import tqdm

            total = passes * -(-npix * per_pass // CHUNK) if passes else None
            bar = tqdm(total=total, unit="chunk", desc="render", leave=False)
        start = _time.perf_counter()
        self.embree_time = 0.0
        self.rays = 0

        def work(args):
            pass_index, k_spp, (a, b) = args
            rng = np.random.Generator(
                np.random.PCG64(np.random.SeedSequence([seed, pass_index, a]))
            )
            pixel = np.arange(a, b, dtype=np.int64) // k_spp
            return pixel, self.trace(pixel, rng)

        pool = ThreadPoolExecutor(max_workers=threads) if threads > 1 else None
        done = 0
        k = 0
        try:
            while True:
                if passes is not None and k >= passes:
                    break
                if passes is None and k > 0 and _time.perf_counter() - start >= time_budget:
                    break
                k_spp = per_pass if passes is None else min(per_pass, spp - done)
                per = npix * k_spp
                items = [(k, k_spp, (a, min(a + CHUNK, per))) for a in range(0, per, CHUNK)]
                results = pool.map(work, items) if pool else map(work, items)
                for pixel, (rgb, alpha, aovs) in results:
                    film.add(pixel, rgb, alpha, aovs)
                    if bar is not None:
                        bar.update(1)
                done += k_spp
                k += 1
        finally:
            if pool:
                pool.shutdown()
            if bar is not None:
                bar.close()
        elapsed = _time.perf_counter() - start
        film.stats.update(
            passes=k,
            spp=done,
            time_s=elapsed,
            rays=self.rays,
            embree_time_s=self.embree_time,
            samples_per_s=npix * done / elapsed if elapsed > 0 else 0.0,
            triangles=self.geo.triangle_count,
        )
        return film


def _is_emissive(material) -> bool:
    surface = getattr(material, "surface", None)
    emission = getattr(surface, "emission", None)
    if emission is None or getattr(emission, "emission", None) is None:
        return False
    intensity = getattr(emission, "intensity", 0.0)
    if callable(intensity):
        return True
    return bool(np.any(np.asarray(intensity, dtype=np.float64) > 0))


def _constant_diffuse_emission(material):
    """``(intensity / pi (3,), power_mode)`` for a front-emitting diffuse_edf of constant
    intensity without bump or cutout (the usual area light), else None."""
    if not _is_emissive(material):
        return None
    emission = material.surface.emission
    edf = emission.emission
    if getattr(edf, "name", None) != "diffuse_edf" or callable(emission.intensity):
        return None
    if getattr(material, "thin_walled", False) or _has_cutout(material):
        return None
    intensity = np.broadcast_to(np.asarray(emission.intensity, dtype=np.float64), (3,))
    return intensity / np.pi, "power" in str(getattr(emission, "mode", ""))


def _has_cutout(material) -> bool:
    geometry = getattr(material, "geometry", None)
    op = getattr(geometry, "cutout_opacity", 1.0)
    if callable(op):
        return True
    return bool(np.any(np.asarray(op, dtype=np.float64) < 1.0))


def render(
    scene,
    spp: int | None = None,
    time: float | None = None,
    seed: int | None = None,
    aovs=(),
    progress: bool = True,
    threads: int = 2,
    denoise: bool = False,
) -> Film:
    """Render a scene (a :class:`~render.scene.Scene` or a TOML file path) to a film.

    Parameters
    ----------
    scene : Scene, str or Path
    spp, time, seed : optional
        Override the scene's ``[render]`` settings.
    aovs : iterable of str
        AOV layers to keep (:data:`render.film.AOVS`).
    progress : bool
    threads : int
    denoise : bool
        Denoise the colour with Open Image Denoise (``pyoidn``) afterwards.

    Returns
    -------
    Film
        ``film.stats`` holds time, samples per second, rays and time inside Embree.
    """
    from render.scene import Scene, load_scene

    if not isinstance(scene, Scene):
        scene = load_scene(scene)
    t0 = _time.perf_counter()
    geometry = scene.build()
    build_s = _time.perf_counter() - t0
    aov_list = list(aovs)
    if denoise:
        aov_list = list(dict.fromkeys(aov_list + ["albedo", "normal"]))
    integ = Integrator(scene, geometry, aov_list)
    film = integ.render(spp=spp, time_budget=time, seed=seed, progress=progress, threads=threads)
    film.stats["build_s"] = build_s
    film.stats["geometry"] = geometry.stats
    if denoise:
        film.denoise()
    return film
