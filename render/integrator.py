"""The wavefront path tracer: batches of rays through Embree, shading vectorized per object.

Scenes whose materials the compiled kernels model (:func:`render.compiled.compiled_reason`)
run the same algorithm, with the same random numbers and the same image, in
:class:`render.compiled.CompiledTrace` (numba), about three times faster; this module is
the general path for every material, and the reference.

Algorithm (unidirectional path tracing, as Mitsuba 3's ``path``/``volpath`` integrators):

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

Interfaces, thin walls and volumes (``reference/mdl-distribution-functions.md`` §1.2,
§1.3, §6; :mod:`render.volume`):

* every path lane carries a :class:`~render.volume.MediumStack` of the closed,
  non-thin-walled objects it is inside.  At a hit on object ``k`` the bound BSDF gets
  ``ior_inside`` = the material's ``ior`` and ``ior_outside`` = the IOR of the
  innermost *other* object the lane is in (1 in air), so an object inside a liquid
  refracts against the liquid (Handbook §5.8); total internal reflection follows from
  that pair (the dfs handle it).  A transmission through such an object pushes it
  (entering from the front) or pops it (leaving from the back);
* ``thin_walled`` materials never enter the stack: no volume, and their transmission
  does not refract (the dfs are bound with ``thin_walled=True``); ``surface`` shades the
  front and ``backface`` the back when it is not the default; emission only where MDL
  allows it (front; back only through a thin-walled ``backface`` edf);
* the medium of the innermost object (``material.volume``) attenuates every segment
  and, where it scatters, a free-flight distance is sampled (spectral MIS); a
  scattering event is a path vertex with next-event estimation through the phase
  function (``anisotropic_vdf``) and a phase-sampled continuation;
* index-matched and thin-walled ``specular_bsdf`` transmissions that keep the direction
  are *null* events (as Mitsuba's ``null``/``thindielectric``): they add no vertex
  (depth, MIS state and Russian roulette are untouched), and shadow rays pass through
  them, weighted by the straight-through transmission and by the transmittance of
  every medium on the way.  A refracting boundary blocks shadow rays (no next-event
  estimation through it; paths find lights behind it by sampling);
* only objects whose triangles close up (every edge shared by two faces, after
  welding) enclose a medium; an open surface (a square) is an interface without an
  inside.  The camera must be outside every closed object.

Parallelism: the image's samples are cut into fixed chunks; each chunk has its own
random stream (``SeedSequence([seed, pass, chunk])``), so the image does not depend on
how many threads run, and two threads trace their own chunks at once (Embree releases
the GIL).  Same seed, same image.
"""

from __future__ import annotations

import time as _time
from concurrent.futures import ThreadPoolExecutor
from dataclasses import dataclass
from functools import partial

import numpy as np

from render.bsdf import Lobe
from render.camera import primary_rays
from render.compiled import CompiledTrace, compiled_reason
from render.df import albedo_estimate
from render.film import Film, empty_aovs
from render.frame import Frame, mirror_z
from render.lights import INFINITE_DISTANCE, AreaLight, LightSet
from render.numerics import ONE_MINUS_EPS, dot, norm, row_any, row_max, unitize
from render.passes import CHUNK, PASS_SAMPLES, PassPlan, render_chunk  # noqa: F401 (re-export)
from render.volume import MAX_NESTING, MediumStack, is_closed, medium_of

__all__ = ["render", "Integrator", "RAY_EPS", "CHUNK"]

#: ray-origin offset relative to the scene's bounding-box diagonal
RAY_EPS = 1e-5
#: a lane may pass through at most this many cutout surfaces per segment
MAX_CUTOUT_CROSSINGS = 64
#: a sampled transmission counts as straight through (a null event) when its direction
#: differs from the incoming one by less than this (1 - cos)
STRAIGHT_TOL = 1e-9


def _fast_unit(v: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Unit rows of interpolated attribute vectors (bounded, finite): ``(u, valid)``;
    rows shorter than 1e-150 give 0 and ``valid = False``."""
    length = np.sqrt(dot(v, v))
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
    ior: np.ndarray | None = None


class _Paths:
    """The state of the live path lanes (compacted every segment).

    Attributes
    ----------
    ids : (n,) int64
        Sample index of each lane (row of the chunk's output).
    o, d : (n, 3) float64
        Ray origin and unit direction of the next segment.
    beta : (n, 3) float64
        Throughput.
    depth : (n,) int64
        Depth of the vertex the ray will find (1 for camera rays).
    prev_pdf : (n,) float64
        Solid-angle pdf of the last scattering vertex's sampled direction (MIS).
    prev_delta : (n,) bool
        The last vertex was specular (or the camera): no MIS.
    first : (n,) bool
        No opaque surface seen yet (alpha and AOVs).
    crossings : (n,) int64
        Cutout and null crossings since the last vertex (capped).
    seg : (n,) float64
        Distance from the last scattering vertex to this segment's origin (cutout and
        null crossings keep the direction, so the light pdf of an emitter hit is
        measured from that vertex).
    shift : (n,) float64
        How far the offset origin lies ahead of the true surface point along ``d``
        (media attenuate the true length ``t + shift``).
    hero : (n,) int64
        The path's hero channel for free-flight sampling (:mod:`render.volume`).
    r : (n, 3) float64
        Spectral-MIS ratios ``p_j / p_hero`` of the path's free-flight decisions;
        contributions are divided by ``mean(r)`` (1 without media).
    stack : MediumStack
    """

    FIELDS = ("ids", "o", "d", "beta", "depth", "prev_pdf", "prev_delta", "first",
              "crossings", "seg", "shift", "hero", "r")

    def __init__(self, **kw):
        for name in self.FIELDS:
            setattr(self, name, kw[name])
        self.stack = kw["stack"]

    def __len__(self) -> int:
        return len(self.ids)

    def take(self, index: np.ndarray) -> _Paths:
        """The lanes ``index`` (a bool mask or indices), copied."""
        index = np.asarray(index)
        if index.dtype == bool:
            index = np.flatnonzero(index)
        # np.take with indices: faster than boolean or fancy indexing
        kw = {name: getattr(self, name).take(index, axis=0) for name in self.FIELDS}
        return _Paths(stack=self.stack.take(index), **kw)

    @staticmethod
    def concatenate(parts: list) -> _Paths:
        """One set of lanes from several (in order)."""
        if len(parts) == 1:
            return parts[0]
        kw = {name: np.concatenate([getattr(p, name) for p in parts]) for name in _Paths.FIELDS}
        return _Paths(stack=MediumStack.concatenate([p.stack for p in parts]), **kw)


def _straight_through_candidate(material, two_faced: bool) -> bool:
    """Whether a material's surface(s) may pass light straight through without a vertex:
    ``specular_bsdf`` with a transmitting mode (straight when index-matched or thin)."""
    surfaces = [material.surface] + ([material.backface] if two_faced else [])
    for surface in surfaces:
        node = getattr(surface, "scattering", None)
        if node is None or getattr(node, "name", None) != "specular_bsdf":
            return False
        mode = str(node.kwargs.get("mode", "scatter_reflect")).split("::")[-1]
        if mode not in ("scatter_transmit", "scatter_reflect_transmit"):
            return False
    return True


def _surface_is_closed(surface) -> bool:
    """Whether an object's base surface encloses a volume (tested on a coarse base mesh:
    displacement and adaptive dicing keep a closed surface closed, but their T-junctions
    would fail a topological test of the diced triangles)."""
    from displacement.dice import is_mesh_surface

    if is_mesh_surface(surface):
        mesh = surface.base_mesh()
    else:
        try:
            mesh = surface.base_mesh(8, 6)
        except TypeError:
            mesh = surface.base_mesh()
    return is_closed(np.asarray(mesh.vertices), np.asarray(mesh.faces))


def _may_enclose(material) -> bool:
    """Non-thin-walled: a closed object of this material has an inside (a medium, which
    may be a vacuum, with the material's IOR)."""
    return not getattr(material, "thin_walled", False)


class Integrator:
    """A path tracer for one built scene.

    Parameters
    ----------
    scene : render.scene.Scene
    geometry : render.scene.Geometry
        ``scene.build()``.
    aovs : iterable of str
        AOVs for the film (:data:`render.film.AOVS`).
    path : {"auto", "general", "compiled"}
        ``"auto"`` traces with the compiled kernels of :mod:`render.compiled` where the
        scene allows it (same image, several times faster) and with the general numpy
        path elsewhere; ``"compiled"`` raises ValueError where the scene does not allow it.
    """

    def __init__(self, scene, geometry, aovs=(), path: str = "auto"):
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
        # interfaces and media: closed non-thin-walled objects enter the medium stack
        n_obj = len(self.objects)
        self.encloses = np.zeros(n_obj, dtype=bool)
        for k, obj in enumerate(self.objects):
            if _may_enclose(obj.material):
                self.encloses[k] = _surface_is_closed(obj.surface)
        self.media = []
        self.medium_index = np.full(n_obj, -1, dtype=np.int64)
        for k, obj in enumerate(self.objects):
            medium = medium_of(obj.material) if self.encloses[k] else None
            if medium is not None:
                self.medium_index[k] = len(self.media)
                self.media.append(medium)
        #: medium-stack depth: no deeper than the number of closed objects
        self.nesting = int(min(MAX_NESTING, int(self.encloses.sum())))
        self.null_candidate = np.array(
            [_straight_through_candidate(o.material, bool(self.two_faced[k]))
             for k, o in enumerate(self.objects)],
            dtype=bool,
        )
        # objects whose transform has no rotation or scale: object frames are world frames
        self.rigid_identity = np.array([np.array_equal(o.linear, np.eye(3)) for o in self.objects])
        self.embree_time = 0.0
        self.rays = 0
        if path not in ("auto", "general", "compiled"):
            raise ValueError(f"path must be 'auto', 'general' or 'compiled', got {path!r}")
        #: why the general path traces this scene (None: the compiled one does)
        self.general_reason = "asked for" if path == "general" else compiled_reason(self)
        if path == "compiled" and self.general_reason is not None:
            raise ValueError(f"the compiled path cannot render this scene: {self.general_reason}")
        self.compiled = CompiledTrace(self) if self.general_reason is None else None

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
            return ShadingState(p - obj.translation, ns, uv, tu, tv, obj.transform)
        return ShadingState(
            obj.to_object_points(p),
            obj.to_object_normals(ns),
            uv,
            obj.to_object_vectors(tu),
            obj.to_object_vectors(tv),
            obj.transform,
        )

    def _state(self, k: int, face: np.ndarray, b1: np.ndarray, b2: np.ndarray):
        """World attributes and the object-space ShadingState at points of object ``k``."""
        p, ns, tu, tv, uv = self._attributes(face, b1, b2)
        return p, ns, tu, uv, self._object_state(k, p, ns, tu, tv, uv)

    def _shade(
        self, k: int, state, front: np.ndarray | None = None, ior_outside=None
    ) -> _Shaded:
        """Shade lanes of object ``k``; ``ior_outside`` (n,) is the IOR around them
        (None or 1: air, as ``material.shade`` assumes)."""
        obj = self.objects[k]
        sh = obj.material.shade(state, front)
        n = len(state)
        bsdf = getattr(sh, "bsdf", None)
        if ior_outside is not None and bsdf is not None and np.any(ior_outside != 1.0):
            bsdf = self._rebind(k, sh, front, np.asarray(ior_outside, dtype=np.float64))
        shade_ior = getattr(sh, "ior", None)
        ior = None
        if shade_ior is not None:
            # the mean of the RGB IORs (as .mean(axis=1), without the slow short-axis reduction)
            ior3 = np.asarray(shade_ior, dtype=np.float64)
            ior = (ior3[:, 0] + ior3[:, 1] + ior3[:, 2]) / 3.0
        nrm = getattr(sh, "normal", None)
        if nrm is None or np.array_equal(nrm, state.normal):
            normal_world = None  # unperturbed: the world normal as interpolated, bit for bit
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
            bsdf,
            getattr(sh, "edf", None),
            intensity,
            str(getattr(sh, "mode", "intensity_radiant_exitance")),
            normal_world,
            op,
            getattr(sh, "frame", None),
            ior,
        )

    def _rebind(self, k: int, sh, front, ior_outside: np.ndarray):
        """The surface bsdf of object ``k`` bound again with the real outside IOR.

        ``material.shade`` binds with ``ior_outside = 1`` (air); lanes inside another
        object (a medium stack that is not empty) need that object's IOR instead.  Uses
        the same surface choice as ``shade`` (``backface`` for back lanes of thin-walled
        materials with one) and the shading state it returned.
        """
        mat = self.objects[k].material
        back = front is not None and len(front) > 0 and not np.any(front)
        surface = mat.backface if (self.two_faced[k] and back) else mat.surface
        node = surface.scattering
        ior_inside = sh.ior.mean(axis=1) if callable(mat.ior) else float(np.mean(mat.ior))
        return node.bind(
            sh.state,
            ior_outside=ior_outside,
            ior_inside=ior_inside,
            thin_walled=bool(mat.thin_walled),
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

    def write_aovs(self, aov: dict, lanes, k: int, bsdf, wo, normal, p, uv) -> None:
        """Fill the AOVs of first opaque hits on object ``k``.

        ``lanes`` (q,) are the rows of ``aov``; ``wo`` (q, 3) the local view directions,
        ``normal`` (q, 3) the world shading normals, ``p`` (q, 3) the hit points and
        ``uv`` (q, 2) their texture coordinates; ``bsdf`` is the bound bsdf (or None).
        """
        if "albedo" in self.aovs and bsdf is not None:
            aov["albedo"][lanes] = albedo_estimate(bsdf, wo)
        aov["normal"][lanes] = normal
        aov["depth"][lanes] = dot(
            p - np.asarray(self.camera.position, dtype=np.float64),
            np.broadcast_to(self.camera.forward, (len(p), 3)),
        )
        aov["uv"][lanes] = uv
        aov["object_id"][lanes] = k

    def _emitted(
        self, k: int, sh: _Shaded, frame: Frame, wo_world: np.ndarray, front=None
    ) -> np.ndarray:
        """Radiance (n, 3) emitted toward ``wo_world`` by object ``k`` (0 without an edf).

        Edfs emit toward their frame's ``+z``: on the back lanes (``front`` False) of a
        thin-walled material with its own ``backface``, whose edf emits from the back,
        the frame is turned over (``wo`` mirrored through the tangent plane).
        """
        n = len(wo_world)
        if sh.edf is None:
            return np.zeros((n, 3))
        intensity = sh.intensity
        if "power" in sh.mode:
            light = self.lights.area_by_object.get(k)
            intensity = intensity / (light.area if light is not None else 1.0)
        wo = frame.to_local(wo_world)
        if self.two_faced[k] and front is not None:
            wo = mirror_z(wo, ~np.asarray(front))
        return sh.edf.eval(wo) * intensity

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
                    k, sh, Frame.from_normal_tangent(nw, tu[side]), wo_world[side], front[side]
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

    def _mis_norm(self, r: np.ndarray):
        """(n,) ``mean(r)`` of the spectral-MIS ratios of paths (1 in scenes without media)."""
        return r.mean(axis=1) if self.media else 1.0

    def _mis_norm_col(self, r: np.ndarray):
        """:meth:`_mis_norm` as an (n, 1) column (or 1)."""
        return r.mean(axis=1, keepdims=True) if self.media else 1.0

    def _parallel_shift(self, ng: np.ndarray, d: np.ndarray) -> np.ndarray:
        """(n,) How much shorter a ray offset by :meth:`_offset` is than the same ray from
        the surface point, through a medium bounded by a parallel surface:
        ``eps / |cos|`` (``|cos|`` clamped at 0.1: grazing rays are ill-conditioned)."""
        return self.eps / np.maximum(np.abs(dot(ng, d)), 0.1)

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

    # ------------------------------------------------------------- media
    def _medium_transmittance(self, top: np.ndarray, dist: np.ndarray) -> np.ndarray:
        """(n, 3) transmittance of segments of length ``dist`` (n,) through the media of
        objects ``top`` (n,) (-1 or an object without a medium: 1)."""
        out = np.ones((len(top), 3))
        if not self.media:
            return out
        med = np.where(top >= 0, self.medium_index[np.maximum(top, 0)], -1)
        for j, medium in enumerate(self.media):
            sel = np.flatnonzero(med == j)
            if len(sel):
                out[sel] = medium.transmittance(dist[sel])
        return out

    def _frame(self, k: int, sh: _Shaded, ns: np.ndarray, tu: np.ndarray) -> Frame:
        nw = sh.normal_world if sh.normal_world is not None else ns
        if self.rigid_identity[k] and sh.frame is not None:
            return sh.frame
        return Frame.from_normal_tangent(nw, tu)

    def _shadow(self, o, d, dist, stack: MediumStack, rng, lead=None, tail=None) -> np.ndarray:
        """Transmittance (n, 3) along shadow segments ``o + s d``, ``0 <= s < dist``.

        Opaque surfaces give 0; cutouts pass stochastically; straight-through
        (index-matched or thin-walled) ``specular_bsdf`` transmissions pass with their
        transmission weight, entering and leaving media on the way (``stack``: the
        media at the origins, not modified); every segment is attenuated by the medium
        it runs through.  ``lead`` (n,) and ``tail`` (n,) are the lengths by which the
        offset segment falls short of the true one at its start and end (media attenuate
        the true length).
        """
        n = len(o)
        if n == 0:
            return np.zeros((0, 3))
        dist = np.maximum(dist, 0.0)
        lead = np.zeros(n) if lead is None else np.asarray(lead, dtype=np.float64).copy()
        tail = np.zeros(n) if tail is None else np.asarray(tail, dtype=np.float64)
        if not self.null_candidate.any():
            # no surface lets a shadow ray through into another medium: the origin's
            # medium is the only one on the segment
            occ = self._occluded(o, d, dist, rng)
            T = np.where(occ[:, None], 0.0, np.ones((n, 3)))
            if self.media and np.any(stack.size):
                T *= self._medium_transmittance(stack.top(), dist + lead + tail)
            return T
        T = np.ones((n, 3))
        stack = stack.copy()
        o = o.copy()
        dist = dist.copy()
        live = np.arange(n)
        for _ in range(MAX_CUTOUT_CROSSINGS):
            if len(live) == 0:
                break
            hit = self._intersect(o[live], d[live], dist[live])
            prim = hit["primID"]
            got = prim >= 0
            t = np.where(got, hit["tfar"].astype(np.float64), dist[live])
            if self.media:
                length = t + lead[live] + np.where(got, 0.0, tail[live])
                T[live] *= self._medium_transmittance(stack.top()[live], length)
            live, t = live[got], t[got]
            if len(live) == 0:
                break
            face = self.geo.face_offset[hit["geomID"][got]] + prim[got]
            objs = self.geo.face_object[face]
            b1 = hit["u"][got].astype(np.float64)
            b2 = hit["v"][got].astype(np.float64)
            ng = self.geo.face_normal[face]
            dl = d[live]
            front = dot(dl, ng) < 0
            factor = np.zeros((len(live), 3))
            crossing = np.zeros(len(live), dtype=bool)
            cross_ior = np.ones(len(live))
            u = rng.random(len(live))
            for k in np.unique(objs):
                if not (self.cutout[k] or self.null_candidate[k]):
                    continue
                sel = np.flatnonzero(objs == k)
                _, ns, tu, _, state = self._state(k, face[sel], b1[sel], b2[sel])
                sides = (
                    (front[sel], ~front[sel]) if self.two_faced[k] else (np.ones(len(sel), bool),)
                )
                for side in sides:
                    if not np.any(side):
                        continue
                    ss = sel[side]
                    st = state if side.all() else state.subset(side)
                    ior_out = stack.take(live[ss]).outside_ior(np.full(len(ss), k))
                    sh = self._shade(k, st, front[ss], ior_outside=ior_out)
                    cut = u[ss] >= sh.opacity if self.cutout[k] else np.zeros(len(ss), bool)
                    f = np.zeros((len(ss), 3))
                    if self.null_candidate[k] and sh.bsdf is not None:
                        frame = self._frame(k, sh, ns[side], tu[side])
                        wo = frame.to_local(-dl[ss])
                        s = sh.bsdf.sample(
                            wo, np.full(len(ss), ONE_MINUS_EPS), np.zeros((len(ss), 2))
                        )
                        straight = (s.lobe == int(Lobe.SPECULAR_TRANSMISSION)) & (
                            dot(frame.to_world(s.wi), dl[ss]) > 1.0 - STRAIGHT_TOL
                        )
                        f = np.where(straight[:, None], s.pdf[:, None] * s.weight, 0.0)
                        crossing[ss] = straight & ~cut
                        if sh.ior is not None:
                            cross_ior[ss] = sh.ior
                    factor[ss] = np.where(cut[:, None], 1.0, f)
            passes = row_any(factor > 0.0)
            T[live] *= factor
            enc = crossing & self.encloses[objs]
            if np.any(enc):
                obj_full = np.full(n, -1, dtype=np.int64)
                obj_full[live] = objs
                ior_full = np.ones(n)
                ior_full[live] = cross_ior
                enter = np.zeros(n, dtype=bool)
                leave = np.zeros(n, dtype=bool)
                enter[live] = enc & front
                leave[live] = enc & ~front
                stack.push(enter, obj_full, ior_full)
                stack.pop(leave, obj_full)
            if not np.any(passes):
                live = live[:0]
                break
            lp = live[passes]
            p = self.geo.interpolate(face[passes], b1[passes], b2[passes])[0]
            o[lp] = self._offset(p, ng[passes], d[lp])
            cos = np.abs(dot(ng[passes], d[lp]))
            dist[lp] = np.maximum(dist[lp] - t[passes] - self.eps * cos, 0.0)
            lead[lp] = self._parallel_shift(ng[passes], d[lp])
            live = lp
        T[live] = 0.0  # still crossing surfaces after the cap: call it blocked
        return T

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
        o, d = primary_rays(self.camera, pixel, rng.random((n, 2)))
        L = np.zeros((n, 3))
        alpha = np.zeros(n)
        aov = empty_aovs(n)
        paths = _Paths(
            ids=np.arange(n),
            o=o,
            d=d,
            beta=np.ones((n, 3)),
            depth=np.ones(n, dtype=np.int64),
            prev_pdf=np.zeros(n),
            prev_delta=np.ones(n, dtype=bool),  # camera rays count as specular (no MIS)
            first=np.ones(n, dtype=bool),
            crossings=np.zeros(n, dtype=np.int64),
            seg=np.zeros(n),
            shift=np.zeros(n),
            # one hero channel per path, drawn only in scenes with media
            hero=(
                np.minimum((rng.random(n) * 3).astype(np.int64), 2)
                if self.media
                else np.zeros(n, dtype=np.int64)
            ),
            r=np.ones((n, 3)),
            stack=MediumStack(n, self.nesting),
        )
        env = self.lights.environment

        while len(paths):
            hit = self._intersect(paths.o, paths.d)
            prim = hit["primID"]
            miss = prim < 0
            t_hit = np.where(miss, np.inf, hit["tfar"].astype(np.float64))
            # the medium of each lane attenuates the segment or scatters inside it
            scat, t_event = self._sample_media(paths, t_hit, rng)
            escaped = miss & ~scat
            if env is not None and np.any(escaped):
                dm = paths.d[escaped]
                le = env.eval(dm)
                w = np.where(
                    paths.prev_delta[escaped],
                    1.0,
                    _power(paths.prev_pdf[escaped], env.pdf(dm) * self.lights.select_pdf),
                )
                L[paths.ids[escaped]] += (
                    paths.beta[escaped] * le * (w / self._mis_norm(paths.r[escaped]))[:, None]
                )
            nxt = []
            surf = ~miss & ~scat
            if np.any(surf):
                nxt.append(
                    self._surface_events(
                        paths if surf.all() else paths.take(surf),
                        self.geo.face_offset[hit["geomID"][surf]] + prim[surf],
                        hit["u"][surf].astype(np.float64),
                        hit["v"][surf].astype(np.float64),
                        t_hit[surf],
                        L,
                        alpha,
                        aov,
                        rng,
                    )
                )
            if np.any(scat):
                nxt.append(self._medium_events(paths.take(scat), t_event[scat], L, rng))
            nxt = [p for p in nxt if len(p)]
            if not nxt:
                break
            paths = _Paths.concatenate(nxt)

        aovs = {a: aov[a] for a in self.aovs}
        return L, alpha, aovs

    def _sample_media(self, paths: _Paths, t_hit: np.ndarray, rng):
        """Free-flight sampling in each lane's medium (throughput updated in place).

        Returns
        -------
        scattered : (n,) bool
            A scattering event lies before the surface.
        t : (n,) float64
            Its distance (the surface's where there is none).
        """
        m = len(paths)
        scattered = np.zeros(m, dtype=bool)
        t = t_hit.copy()
        if not self.media or not np.any(paths.stack.size):
            return scattered, t
        u = rng.random(m)
        top = paths.stack.top()
        med = np.where(top >= 0, self.medium_index[np.maximum(top, 0)], -1)
        for j, medium in enumerate(self.media):
            sel = np.flatnonzero(med == j)
            if len(sel) == 0:
                continue
            shift = paths.shift[sel]
            ds = medium.sample_distance(t_hit[sel] + shift, paths.hero[sel], u[sel])
            w, ratio = ds.weight(paths.hero[sel])
            paths.beta[sel] *= w
            paths.r[sel] *= ratio
            scattered[sel] = ds.scattered
            t[sel] = np.where(ds.scattered, ds.t - shift, t_hit[sel])
        return scattered, t

    def _medium_events(self, P: _Paths, t: np.ndarray, L: np.ndarray, rng) -> _Paths:
        """Scattering events inside media: next-event estimation through the phase
        function and a phase-sampled continuation (a path vertex each)."""
        m = len(P)
        p = P.o + t[:, None] * P.d
        wo = -P.d
        u_light = rng.random((m, 3))
        u_phase = rng.random((m, 3))
        u_rr = rng.random(m)
        live = P.depth < self.max_depth
        top = P.stack.top()
        med = self.medium_index[np.maximum(top, 0)]
        lw, ldist, lli, lpdf, ldelta = self.lights.sample_li(p, u_light[:, 0], u_light[:, 1:])
        new_d = np.zeros((m, 3))
        new_pdf = np.zeros(m)
        new_w = np.zeros((m, 3))
        ok_s = np.zeros(m, dtype=bool)
        nee_c = np.zeros((m, 3))
        for j, medium in enumerate(self.media):
            sel = np.flatnonzero((med == j) & live)
            if len(sel) == 0:
                continue
            f, pp = medium.phase.eval_pdf(wo[sel], lw[sel])
            w = np.where(ldelta[sel], 1.0, _power(lpdf[sel], pp))
            ok = lpdf[sel] > 0
            nee_c[sel] = np.where(
                ok[:, None],
                P.beta[sel]
                * f
                * lli[sel]
                * (w / np.where(ok, lpdf[sel], 1.0) / self._mis_norm(P.r[sel]))[:, None],
                0.0,
            )
            s = medium.phase.sample(wo[sel], u_phase[sel, 0], u_phase[sel, 1:])
            new_d[sel] = s.wi
            new_pdf[sel] = s.pdf
            new_w[sel] = s.weight
            ok_s[sel] = s.valid
        q = np.flatnonzero(row_any(nee_c > 0))
        if len(q):
            finite = ldist[q] < INFINITE_DISTANCE
            far = np.where(finite, ldist[q] * (1.0 - 1e-6) - self.eps, ldist[q])
            T = self._shadow(p[q], lw[q], far, P.stack.take(q), rng, tail=ldist[q] - far)
            L[P.ids[q]] += nee_c[q] * T
        beta = P.beta * new_w
        rr = P.depth >= self.settings.rr_depth
        qrr = np.minimum(row_max(beta / self._mis_norm_col(P.r)), 0.95)
        survive = ~rr | (u_rr < qrr)
        scale = np.where(rr, np.maximum(qrr, 1e-300), 1.0)
        beta = np.where(rr[:, None], beta / scale[:, None], beta)
        go = live & ok_s & survive & row_any(beta > 0)
        out = P.take(go)
        out.o = p[go]
        out.d = new_d[go]
        out.beta = beta[go]
        out.depth = P.depth[go] + 1
        out.prev_pdf = new_pdf[go]
        out.prev_delta = np.zeros(int(go.sum()), dtype=bool)
        out.crossings = np.zeros(int(go.sum()), dtype=np.int64)
        out.seg = np.zeros(int(go.sum()))
        out.shift = np.zeros(int(go.sum()))
        return out

    def _surface_events(self, P: _Paths, face, b1, b2, t, L, alpha, aov, rng) -> _Paths:
        """Surface hits: emission (MIS), alpha and AOVs, next-event estimation, the
        BSDF-sampled continuation (or a cutout / null crossing), Russian roulette."""
        geo = self.geo
        m = len(P)
        ids, beta, depth = P.ids, P.beta, P.depth
        objs = geo.face_object[face]
        ng = geo.face_normal[face]
        wo_world = -P.d
        want = set(self.aovs)

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
        null_pass = np.zeros(m, dtype=bool)
        entry_ior = np.ones(m)
        nee_c = np.zeros((m, 3))
        nee_ok = np.zeros(m, dtype=bool)
        can_continue = depth < self.max_depth
        # distance from the last scattering vertex (emitter pdfs are measured from it)
        dist_v = P.seg + t

        # spectral-MIS normalisation (1 without media)
        mis = self._mis_norm(P.r)
        # light samples for every lane (one light each)
        front_all = dot(wo_world, ng) > 0
        groups = []
        for k in np.unique(objs):
            sel = np.flatnonzero(objs == k)
            if self.two_faced[k]:
                groups += [(k, g) for g in (sel[front_all[sel]], sel[~front_all[sel]]) if len(g)]
            else:
                groups.append((k, sel))
        p_all, ns_all, tu_all, tv_all, uv_all = self._attributes(face, b1, b2)
        lw, ldist, lli, lpdf, ldelta = self.lights.sample_li(p_all, u_light[:, 0], u_light[:, 1:])
        # the IOR around each hit object (air unless the lane is inside other objects)
        ior_out_all = P.stack.outside_ior(objs) if np.any(P.stack.size) else None

        for k, sel in groups:
            whole = len(groups) == 1
            p, ns, tu, uv = (
                (p_all, ns_all, tu_all, uv_all)
                if whole
                else (p_all[sel], ns_all[sel], tu_all[sel], uv_all[sel])
            )
            state = self._object_state(k, p, ns, tu, tv_all if whole else tv_all[sel], uv)
            sh = self._shade(
                k, state, front_all[sel], None if ior_out_all is None else ior_out_all[sel]
            )
            if self.cutout[k]:
                ps = u_cut[sel] >= sh.opacity
                passes[sel] = ps & (P.crossings[sel] < MAX_CUTOUT_CROSSINGS)
            opaque = ~passes[sel]
            nw = sh.normal_world if sh.normal_world is not None else ns
            frame = self._frame(k, sh, ns, tu)
            wo_w, ng_s = wo_world[sel], ng[sel]
            mis_s = mis[sel] if self.media else mis
            wo = frame.to_local(wo_w)
            g_wo = dot(wo_w, ng_s)
            if sh.ior is not None:
                entry_ior[sel] = sh.ior
            # emission, weighted against light sampling
            if sh.edf is not None:
                le = self._emitted(k, sh, frame, wo_w, front_all[sel])
                cos_l = np.abs(g_wo)
                pl = np.where(
                    cos_l > 0,
                    self.area_pdf[k] * dist_v[sel] ** 2 / np.where(cos_l > 0, cos_l, 1.0),
                    0.0,
                )
                w = np.where(P.prev_delta[sel], 1.0, _power(P.prev_pdf[sel], pl))
                w = w / mis_s
                L[ids[sel]] += np.where(opaque[:, None], beta[sel] * le * w[:, None], 0.0)
            # first opaque hit: alpha and AOVs
            fo = P.first[sel] & opaque
            if np.any(fo):
                lanes = ids[sel][fo]
                alpha[lanes] = 1.0
                if want:
                    self.write_aovs(aov, lanes, k, sh.bsdf, wo[fo], nw[fo], p[fo], uv[fo])
            bsdf = sh.bsdf
            live = opaque & can_continue[sel]
            # a null crossing adds no vertex: it is allowed at the maximum depth too
            trial = opaque if self.null_candidate[k] else live
            if bsdf is None or not np.any(trial):
                continue
            # next-event estimation
            lw_s, lpdf_s = lw[sel], lpdf[sel]
            wl = frame.to_local(lw_s)
            f, pb = bsdf.eval_pdf(wo, wl)
            g_wi = dot(lw_s, ng_s)
            consistent = (g_wi * g_wo > 0) == (wl[:, 2] * wo[:, 2] > 0)
            w = np.where(ldelta[sel], 1.0, _power(lpdf_s, pb)) / mis_s
            ok = live & (lpdf_s > 0) & consistent & (g_wi != 0)
            contrib = beta[sel] * f * lli[sel] * (w / np.where(ok, lpdf_s, 1.0))[:, None]
            ok &= row_any(contrib > 0)
            nee_c[sel] = np.where(ok[:, None], contrib, 0.0)
            nee_ok[sel] = ok
            # continue the path with the BSDF's sample
            s = bsdf.sample(wo, u_bsdf[sel, 0], u_bsdf[sel, 1:])
            wi_world = frame.to_world(s.wi)
            g_new = dot(wi_world, ng_s)
            consistent = (g_new * g_wo > 0) == (s.wi[:, 2] * wo[:, 2] > 0)
            sc = trial & s.valid & consistent & (g_new != 0) & row_any(s.weight > 0)
            new_d[sel] = wi_world
            new_w[sel] = s.weight
            new_pdf[sel] = s.pdf
            new_delta[sel] = s.is_delta
            if self.null_candidate[k]:
                # a transmission that keeps the direction: no vertex (Mitsuba's null)
                straight = (s.lobe == int(Lobe.SPECULAR_TRANSMISSION)) & (
                    dot(wi_world, P.d[sel]) > 1.0 - STRAIGHT_TOL
                )
                null_pass[sel] = sc & straight & (P.crossings[sel] < MAX_CUTOUT_CROSSINGS)
                sc &= can_continue[sel] | null_pass[sel]
            scatter[sel] = sc

        # shadow rays
        if np.any(nee_ok):
            q = np.flatnonzero(nee_ok)
            pq, ngq, lwq, ldq = p_all[q], ng[q], lw[q], ldist[q]
            org = self._offset(pq, ngq, lwq)
            # aim from the offset origin at the light point itself (lights at a
            # finite distance), and stop short of it
            finite = ldq < INFINITE_DISTANCE
            target = pq + lwq * np.where(finite, ldq, 0.0)[:, None]
            sd, sok = unitize(target - org)
            sdir = np.where((finite & sok)[:, None], sd, lwq)
            sdist = np.where(finite, norm(target - org), ldq)
            far = sdist * (1.0 - 1e-6) - self.eps
            stack = P.stack.take(q)
            # a shadow ray on the transmitted side starts inside (or outside) the object
            if np.any(self.encloses[objs[q]]):
                cross = (dot(lwq, ngq) * dot(wo_world[q], ngq) < 0) & self.encloses[objs[q]]
                if np.any(cross):
                    stack.push(cross & front_all[q], objs[q], entry_ior[q])
                    stack.pop(cross & ~front_all[q], objs[q])
            # the true segment starts at the surface point: for a light at a finite
            # distance the aim was moved to the offset origin, for one at infinity the
            # ray was shifted parallel to itself
            lead = np.where(
                finite,
                norm(target - pq) - sdist,
                self._parallel_shift(ngq, sdir),
            )
            T = self._shadow(org, sdir, far, stack, rng, lead=lead, tail=sdist - far)
            L[ids[q]] += nee_c[q] * T

        # lanes that pass through a cutout keep going straight on
        first = P.first & passes
        straight = passes | null_pass
        crossings = np.where(straight, P.crossings + 1, 0)
        beta = np.where(scatter[:, None], beta * new_w, beta)
        # Russian roulette (at real vertices only)
        rr = scatter & ~null_pass & (depth >= self.settings.rr_depth)
        qrr = np.minimum(row_max(beta / self._mis_norm_col(P.r)), 0.95)
        survive = ~rr | (u_rr < qrr)
        beta = np.where(
            (rr & survive)[:, None],
            beta / np.where(rr, np.maximum(qrr, 1e-300), 1.0)[:, None],
            beta,
        )
        go = passes | (scatter & survive)
        nd = np.where(straight[:, None], P.d, new_d)
        # transmissions through closed objects enter or leave their media
        if np.any(self.encloses[objs]):
            cross = scatter & (dot(nd, ng) * dot(wo_world, ng) < 0) & self.encloses[objs]
            if np.any(cross):
                P.stack.push(cross & front_all, objs, entry_ior)
                P.stack.pop(cross & ~front_all, objs)
        return _Paths(
            ids=ids,
            o=self._offset(p_all, ng, nd),
            d=nd,
            beta=beta,
            depth=np.where(straight, depth, depth + 1),
            prev_pdf=np.where(straight, P.prev_pdf, new_pdf),
            prev_delta=np.where(straight, P.prev_delta, new_delta),
            first=first,
            crossings=crossings,
            seg=np.where(straight, dist_v, 0.0),
            shift=self._parallel_shift(ng, nd),
            hero=P.hero,
            r=P.r,
            stack=P.stack,
        ).take(go)

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
        film = Film(self.camera.width, self.camera.height, self.aovs)
        npix = film.pixel_count
        # the passes and chunks (render.passes): the same in-process and on a cluster
        plan = PassPlan.of(self.settings, npix, spp, time_budget, seed)
        passes, time_budget = plan.passes, plan.time_budget
        bar = None
        if progress:
            from tqdm import tqdm

            bar = tqdm(total=plan.chunk_count, unit="chunk", desc="render", leave=False)
        start = _time.perf_counter()
        self.embree_time = 0.0
        self.rays = 0
        work = partial(render_chunk, self, plan.seed)

        pool = ThreadPoolExecutor(max_workers=threads) if threads > 1 else None
        done = 0
        k = 0
        try:
            while True:
                if passes is not None and k >= passes:
                    break
                if passes is None and k > 0 and _time.perf_counter() - start >= time_budget:
                    break
                items = plan.chunks(k)
                results = pool.map(work, items) if pool else map(work, items)
                for patch in results:
                    film.merge(patch)
                    if bar is not None:
                        bar.update(1)
                done += plan.pass_spp(k)
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
            path="general" if self.compiled is None else "compiled",
            general_reason=self.general_reason,
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
    path: str = "auto",
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
    path : {"auto", "general", "compiled"}
        Which implementation traces (:class:`Integrator`).

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
    integ = Integrator(scene, geometry, aov_list, path=path)
    film = integ.render(spp=spp, time_budget=time, seed=seed, progress=progress, threads=threads)
    film.stats["build_s"] = build_s
    film.stats["geometry"] = geometry.stats
    if denoise:
        film.denoise()
    return film
