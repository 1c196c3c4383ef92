"""The path tracer: every path of a chunk of samples carried to its end by one compiled
kernel, :func:`render.path.trace`.

Algorithm (unidirectional path tracing, as Mitsuba 3's ``path``/``volpath`` integrators):

* primary rays through random points of each pixel (box filter); every sample value
  of a path is an Owen-scrambled Sobol point of its pixel (:mod:`render.sampler`);
* per segment, the ray through Embree, then at its end: emission found by a ray is
  weighted by multiple importance sampling (power heuristic) against next-event
  estimation; next-event estimation picks one light (area, point, spot, directional,
  environment map or sun and sky) by what it can contribute at the vertex
  (:func:`render.light_sampling.select_light`, ``[render] light_selection``), samples
  each delta light at every vertex too (``every_delta_light``), and traces a shadow
  ray to each light sampled;
  the bsdf's own sample continues the path (specular lobes too); Russian roulette from
  ``rr_depth``; ``max_depth`` counts path vertices after the camera, as Mitsuba does;
* cutout opacity is stochastic: a lane passes through a surface with probability
  ``1 - cutout_opacity`` without a bounce (shadow rays too); alpha is 1 where a path's
  first opaque hit exists;
* ray origins are offset along the geometric normal by ``RAY_EPS`` times the scene's
  size (plus float32 rounding of the coordinates), because Embree's tnear is 0.

Materials are programs (:mod:`render.program`) run by :mod:`render.interpreter` inside
the kernel.  An object whose material's arguments vary over the surface (textures,
noise, a bumped normal, a varying cutout, IOR or emission, an explicit ``tangent_u``
or layer ``normal``) is shaded by ``material.shade`` (numpy) for the lanes that hit it:
the kernel parks them, :meth:`Integrator._bind` shades them in a batch, and the kernel
resumes them with that lane's parameter row and frame.  So is an object whose IOR
context changes because the path is inside another object.

Interfaces, thin walls and volumes (``reference/mdl-distribution-functions.md`` §1.2,
§1.3, §6; :mod:`render.volume`):

* every path lane carries a stack of the closed, non-thin-walled objects it is inside.
  At a hit on object ``k`` the bsdf gets ``ior_inside`` = the material's ``ior`` and
  ``ior_outside`` = the IOR of the innermost *other* object the lane is in (1 in air),
  so an object inside a liquid refracts against the liquid (Handbook §5.8); total
  internal reflection follows from that pair (the dfs handle it).  A transmission
  through such an object pushes it (entering from the front) or pops it (leaving from
  the back);
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

Parallelism: the image's samples are cut into fixed chunks, and two threads trace their
own chunks at once (the kernels and Embree release the GIL).  A sample's values depend
only on its pixel, its index in the pixel and the seed, so the image does not depend on
how many threads run or how the samples are cut.  Same seed, same image.
"""

from __future__ import annotations

import threading
import time as _time
from concurrent.futures import ThreadPoolExecutor
from functools import partial
from types import SimpleNamespace

import numpy as np

from render import embree
from render import material as M
from render import path as kern
from render.df._registry import registry
from render.film import Film
from render.frame import Frame, mirror_z
from render.hair import check_hair_bsdf
from render.light_sampling import KINDS, MAX_EVERY_DELTA, light_table
from render.lights import AreaLight, LightSet
from render.numerics import dot
from render.passes import CHUNK, PASS_SAMPLES, PassPlan, render_chunk  # noqa: F401 (re-export)
from render.program import OP, ProgramTable
from render.sampler import SAMPLERS, SOBOL_TABLE
from render.volume import MAX_NESTING, is_closed, medium_of

__all__ = ["render", "Integrator", "RAY_EPS", "CHUNK"]

#: ray-origin offset relative to the scene's bounding-box diagonal
RAY_EPS = 1e-5
#: up to this many lights next-event estimation weighs each light at every vertex (as
#: cheap as walking a tree of them, and each light's own bound is the sharper); more
#: are put in a light tree
FLAT_LIGHTS = 8


def _straight_through_candidate(material, two_faced: bool) -> bool:
    """Whether a material's surface(s) may pass light straight through without a vertex:
    one df whose lobes in its mode are deltas that transmit (``specular_bsdf``
    transmitting: straight when index-matched or thin)."""
    surfaces = [material.surface] + ([material.backface] if two_faced else [])
    for surface in surfaces:
        node = getattr(surface, "scattering", None)
        declared = registry().dfs.get(getattr(node, "name", None))
        if declared is None:
            return False
        mode = str(node.kwargs.get("mode", "scatter_reflect")).split("::")[-1]
        if not (declared.delta_in(mode) and declared.transmits_in(mode)):
            return False
    return True


def _is_strands(surface) -> bool:
    from render.hair import Strands

    return isinstance(surface, Strands)


def _surface_is_closed(surface) -> bool:
    """Whether an object's base surface encloses a volume (tested on a coarse base mesh:
    displacement and adaptive dicing keep a closed surface closed, but their T-junctions
    would fail a topological test of the diced triangles)."""
    from displacement.dice import is_mesh_surface

    if _is_strands(surface):
        return False

    if is_mesh_surface(surface):
        mesh = surface.base_mesh()
        return is_closed(np.asarray(mesh.vertices), np.asarray(mesh.faces))
    uv, faces = surface.base_grid(8, 6)
    return is_closed(surface.state_at_uv(uv).position, faces)


def _may_enclose(material) -> bool:
    """Non-thin-walled: a closed object of this material has an inside (a medium, which
    may be a vacuum, with the material's IOR)."""
    return not getattr(material, "thin_walled", False)


def _df_nodes(node):
    """Every node of a df tree (children in arguments, lists of components too)."""
    stack = [] if node is None else [node]
    while stack:
        n = stack.pop()
        yield n
        for value in n.kwargs.values():
            if isinstance(value, list | tuple):
                stack.extend(v for v in value if hasattr(v, "kwargs"))
            elif hasattr(value, "kwargs"):
                stack.append(value)


def _varying(material) -> bool:
    """Whether an object's material must be shaded per lane: an argument that is a
    function of the state, a bumped normal, a varying IOR or cutout, or a
    ``tangent_u``/layer ``normal`` given explicitly (bound in the frame of each hit)."""
    if material.geometry.normal is not None or callable(material.ior):
        return True
    if callable(getattr(material.geometry, "cutout_opacity", 1.0)):
        return True
    surfaces = [material.surface, getattr(material, "backface", None)]
    for surface in surfaces:
        for n in _df_nodes(getattr(surface, "scattering", None)):
            if any(key in ("tangent_u", "normal") or callable(value)
                   for key, value in n.kwargs.items()):
                return True
    return False


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
        n_obj = len(self.objects)
        # scene-relative, plus the float32 rounding of the largest coordinate
        self.eps = RAY_EPS * geometry.extent + 4e-7 * geometry.coord_max
        #: hair strands (render.hair), shaded by their material's hair bsdf in the kernel
        self.hair = np.array([_is_strands(o.surface) for o in self.objects], dtype=bool)
        for k in np.flatnonzero(self.hair):
            try:
                check_hair_bsdf(self.objects[k].material.hair)
            except ValueError as e:
                raise ValueError(f"object {self.objects[k].name!r} (hair strands): {e}") from None
        #: the materials of the objects' surfaces: MDL shades hair by the material's hair
        #: field alone (surface, backface, ior, volume and geometry do not apply), so a
        #: hair object's surface is the default material's (no emission, no cutout)
        self.surface_materials = [M.material() if self.hair[k] else o.material
                                  for k, o in enumerate(self.objects)]
        lights = list(scene.lights)
        #: each emissive object's triangles as one light (its emission and total area);
        #: next-event estimation samples them in groups (AreaLight.groups)
        self.emitters = {}
        for k, mat in enumerate(self.surface_materials):
            if _is_emissive(mat):
                first, last = geometry.face_offset[k], geometry.face_offset[k + 1]
                faces = np.arange(first, last)
                corners = geometry.vertices[geometry.faces[faces]]
                self.emitters[k] = AreaLight(k, faces, corners, geometry.face_normal[faces],
                                             self._emission_fn(k))
                lights.extend(self.emitters[k].groups())
        self.lights = LightSet(lights)
        n_delta = sum(light.delta for light in self.lights.lights)
        #: delta lights sampled at every vertex besides the selected light (their shadow
        #: records: up to 1 + n_delta per lane)
        self.every_delta = bool(self.settings.every_delta_light and
                                0 < n_delta <= MAX_EVERY_DELTA)
        self.shadow_rows = 1 + (n_delta if self.every_delta else 0)
        for light in self.lights.lights:
            if type(light) not in KINDS:
                raise ValueError(f"{type(light).__name__} is not a light the renderer samples")
        mats = self.surface_materials
        self.cutout = np.array([_has_cutout(m) for m in mats], dtype=bool)
        # thin-walled materials with their own backface are shaded per side
        self.two_faced = np.array(
            [bool(getattr(m, "thin_walled", False))
             and not getattr(getattr(m, "backface", None), "is_default", True) for m in mats],
            dtype=bool)
        self.max_depth = self.settings.max_depth if self.settings.max_depth > 0 else 1 << 30
        # interfaces and media: closed non-thin-walled objects enter the medium stack
        self.encloses = np.array([_may_enclose(m) and _surface_is_closed(o.surface)
                                  for m, o in zip(mats, self.objects, strict=True)], dtype=bool)
        self.media = []
        obj_medium = np.full(n_obj, -1, dtype=np.int64)
        for k, mat in enumerate(mats):
            medium = medium_of(mat) if self.encloses[k] else None
            if medium is not None:
                obj_medium[k] = len(self.media)
                self.media.append(medium)
        #: medium-stack depth: no deeper than the number of closed objects (at least 1,
        #: an unused column, so the kernels' arrays are never empty)
        self.nesting = max(1, int(min(MAX_NESTING, int(self.encloses.sum()))))
        self.null_candidate = np.array(
            [_straight_through_candidate(m, bool(self.two_faced[k])) for k, m in enumerate(mats)],
            dtype=bool)
        # objects whose transform has no rotation or scale: object frames are world frames
        self.rigid_identity = np.array([np.array_equal(o.linear, np.eye(3))
                                        for o in self.objects])
        const_emit = [_constant_diffuse_emission(m) for m in mats]
        #: emitters whose edf and intensity are constant: their edf programs run in the
        #: kernel (the constant diffuse ones by the shortcut EMIT_CONST)
        self.emit_program = np.array([const_emit[k] is None and _constant_edf(m)
                                      for k, m in enumerate(mats)], dtype=bool)
        #: objects shaded per lane with numpy (varying arguments or emission)
        self.bound = np.array([_varying(m) or (_is_emissive(m) and const_emit[k] is None
                                               and not self.emit_program[k])
                               for k, m in enumerate(mats)], dtype=bool)
        self.emit_program &= ~self.bound
        # the program slots: bsdfs (2k front, 2k + 1 back), then edfs (EDF_SLOTS + 2k,
        # + 1), then the media's phase functions (after both)
        self.programs = [None] * (4 * n_obj)
        for k in range(n_obj):
            if self.hair[k]:
                self.programs[2 * k] = self._hair_program(k)
            elif not self.bound[k]:
                self.programs[2 * k] = self._constant_program(k, back=False)
                if self.two_faced[k]:  # slot 2k + 1 is read for two-faced objects only
                    self.programs[2 * k + 1] = self._constant_program(k, back=True)
            if self.emit_program[k]:
                self.programs[2 * n_obj + 2 * k] = self._edf_program(k, back=False)
                if self.two_faced[k]:
                    self.programs[2 * n_obj + 2 * k + 1] = self._edf_program(k, back=True)
        self.programs += [m.phase.program for m in self.media]  # slot 4K + j: medium j's
        #: objects whose programs read the IOR outside them (rebound per lane inside
        #: other objects)
        self.ior_sensitive = np.array(
            [self.bound[k] or self._reads_outside_ior(k) for k in range(n_obj)],
            dtype=bool) & ~self.hair
        self.passable = self.cutout | self.null_candidate
        #: whether any lane may need per-hit bindings (:meth:`_bind`)
        self.may_bind = bool(self.bound.any() or (self.encloses.any() and self.ior_sensitive.any()))
        self.tables, self.params = self._tables(const_emit, obj_medium)
        self.embree_time = 0.0
        self.rays = 0
        self._count_lock = threading.Lock()  # two threads trace chunks at once
        self._local = threading.local()  # each thread's buffers (:meth:`_buffers`)
        # compile (or load from numba's cache) before worker threads start
        self.trace(np.zeros(1, dtype=np.int64), np.zeros(1, dtype=np.int64), 0)

    # ------------------------------------------------------------------ setup
    def _constant_program(self, k: int, back: bool):
        """Object ``k``'s bsdf program (front or back surface), one parameter row, in
        air (None: black)."""
        from displacement.state import ShadingState

        mat = self.objects[k].material
        surface = mat.backface if back else mat.surface
        node = surface.scattering
        if node is None or node.is_black:
            return None
        one = np.array([[0.0, 0.0, 1.0]])
        state = ShadingState(np.zeros((1, 3)), one, np.zeros((1, 2)), np.array([[1.0, 0.0, 0.0]]),
                             np.array([[0.0, 1.0, 0.0]]), self.objects[k].transform)
        return node.bind(state, ior_outside=1.0, ior_inside=float(np.mean(mat.ior)),
                         thin_walled=bool(mat.thin_walled)).program

    def _hair_program(self, k: int):
        """Object ``k``'s hair bsdf program (its material's ``hair``; None: black)."""
        from displacement.state import ShadingState

        node = self.objects[k].material.hair
        if node is None:
            return None
        one = np.array([[0.0, 0.0, 1.0]])
        state = ShadingState(np.zeros((1, 3)), one, np.zeros((1, 2)), np.array([[1.0, 0.0, 0.0]]),
                             np.array([[0.0, 1.0, 0.0]]), self.objects[k].transform)
        return node.bind(state).program

    def _edf_program(self, k: int, back: bool):
        """Object ``k``'s edf program (front surface, or a thin-walled backface), one
        parameter row (None: no emission).  A global ``spot_edf`` or ``measured_edf``
        is bound with the identity for ``object_to_local``: the kernel writes each
        hit's rotation into a copy of the row (:func:`render.path._emission`)."""
        from displacement.state import ShadingState

        mat = self.objects[k].material
        emission = (mat.backface if back else mat.surface).emission
        if emission.is_black:
            return None
        one = np.array([[0.0, 0.0, 1.0]])
        state = ShadingState(np.zeros((1, 3)), one, np.zeros((1, 2)), np.array([[1.0, 0.0, 0.0]]),
                             np.array([[0.0, 1.0, 0.0]]), self.objects[k].transform)
        return emission.emission.bind(state, ior_outside=1.0, ior_inside=float(np.mean(mat.ior)),
                                      thin_walled=bool(mat.thin_walled),
                                      object_to_local=np.eye(3)[None]).program

    def _reads_outside_ior(self, k: int) -> bool:
        """Whether object ``k``'s constant programs change with the IOR outside it."""
        if not self.encloses.any():
            return False
        mat = self.objects[k].material
        for surface in (mat.surface, mat.backface if self.two_faced[k] else None):
            node = getattr(surface, "scattering", None)
            if node is None or node.is_black:
                continue
            if any(getattr(registry().dfs.get(n.name), "reads_outside_ior", False)
                   for n in _df_nodes(node)):
                return True
        return False

    def _tables(self, const_emit, obj_medium):
        geo = self.geo
        n_obj = len(self.objects)
        emit_hit = np.zeros((n_obj, 6))
        #: each emitter's radiance of its light samples (None: it varies over it)
        emission = dict.fromkeys(self.emitters)
        #: the mean radiance of an edf-program emitter, for its light's bounds
        exitance = {}
        flags = np.zeros(n_obj, dtype=np.int64)
        flags[self.cutout] |= kern.CUTOUT
        flags[self.null_candidate] |= kern.NULL
        flags[self.encloses] |= kern.ENCLOSES
        flags[self.two_faced] |= kern.TWO_FACED
        flags[self.bound] |= kern.BOUND
        flags[self.hair] |= kern.HAIR
        if self.encloses.any():
            flags[self.ior_sensitive] |= kern.IOR_SENSITIVE
        opacity = np.ones(n_obj)
        ior = np.ones(n_obj)
        for k, mat in enumerate(self.surface_materials):
            if not callable(mat.ior):
                ior[k] = float(np.mean(mat.ior))
            op = getattr(mat.geometry, "cutout_opacity", 1.0)
            if not callable(op):
                opacity[k] = float(np.clip(np.mean(op), 0.0, 1.0))
            if const_emit[k] is not None:
                flags[k] |= kern.EMIT_CONST
                intensity = np.broadcast_to(
                    np.asarray(mat.surface.emission.intensity, dtype=np.float64), (3,))
                radiance, power = const_emit[k]
                light = self.emitters[k]
                # edf.eval (1/pi) times the intensity (per area in power mode) on a hit,
                # intensity / pi (per area) when sampled
                emit_hit[k, :3] = (intensity / light.area if power else intensity) / np.pi
                emission[k] = radiance / light.area if power else radiance
            elif self.emit_program[k]:
                flags[k] |= kern.EMIT_PROG
                slots = self.programs[2 * n_obj + 2 * k:2 * n_obj + 2 * k + 2]
                if any(p is not None and (kern.OBJECT_TO_LOCAL[p.code[:, OP]] >= 0).any()
                       for p in slots):
                    flags[k] |= kern.EMIT_GLOBAL
                area = self.emitters[k].area
                sides = (mat.surface, mat.backface) if self.two_faced[k] else (mat.surface,)
                mean = 0.0
                for side, (surface, prog) in enumerate(zip(sides, slots, strict=False)):
                    e = surface.emission
                    if prog is None or e.is_black:
                        continue
                    i = np.broadcast_to(np.asarray(e.intensity, dtype=np.float64), (3,))
                    if "power" in str(e.mode):
                        i = i / area
                    emit_hit[k, 3 * side:3 * side + 3] = i
                    # intensity times the edf's hemispherical emission over pi: the
                    # radiance of a diffuse emitter of the same power
                    mean = max(mean, float(_luminance(i)) * _edf_albedo(prog) / np.pi)
                exitance[k] = mean
        media = np.zeros((max(len(self.media), 1), 12))
        for j, m in enumerate(self.media):
            media[j] = m.row
        lt = light_table(self.lights.lights, len(geo.faces), emission, self._scene_disk(),
                         self.every_delta, self.settings.light_selection, exitance)
        scalars = np.zeros(kern.N_SCALARS)
        scalars[kern.SC_SELECT] = float(lt.mode)
        scalars[kern.SC_LIGHTS] = float(lt.n_lights)
        scalars[kern.SC_ENV_LIGHT] = float(lt.env_light)
        scalars[kern.SC_ROT_C], scalars[kern.SC_ROT_S] = lt.rot_c, lt.rot_s
        scalars[kern.SC_EPS] = self.eps
        scalars[kern.SC_MAX_DEPTH] = float(self.max_depth)
        scalars[kern.SC_RR_DEPTH] = float(self.settings.rr_depth)
        scalars[kern.SC_MEDIA] = float(bool(self.media))
        scalars[kern.SC_AOV] = float(bool(self.aovs))
        scalars[kern.SC_BIND] = float(self.may_bind)
        # hair: shadow rays pass a tube they meet from inside (render.hair)
        scalars[kern.SC_PASS] = float(bool(self.passable.any() or self.hair.any()))
        scalars[kern.SC_CAM:kern.SC_CAM + 3] = self.camera.position
        scalars[kern.SC_FWD:kern.SC_FWD + 3] = self.camera.forward
        scalars[kern.SC_WIDTH] = float(self.camera.width)
        scalars[kern.SC_NCONST] = float(len(self.programs))
        table = ProgramTable(self.programs)
        params = np.zeros((len(self.programs), table.width))
        for s, prog in enumerate(self.programs):
            if prog is not None:
                params[s, : prog.P.shape[1]] = prog.P[0]
        tables = kern.Tables(
            geo.packed, geo.faces, geo.face_normal, geo.face_object.astype(np.int64),
            geo.face_offset.astype(np.int64),
            table.code, table.kids, table.frames, table.tables, table.roots, table.frame_lo,
            table.frame_hi,
            flags, opacity, ior, obj_medium, emit_hit,
            np.ascontiguousarray([o.linear.ravel() for o in self.objects]), geo.curves,
            geo.curve_first, lt.face_light,
            media,
            lt.lights, lt.light_tri, lt.env_image, lt.env_dist, lt.sky, lt.sky_dist,
            self.camera.ray_map, scalars)
        return tables, params

    def _scene_disk(self) -> float:
        """pi r^2 of the scene's bounding sphere (the cross-section a distant light
        covers, for its power)."""
        return np.pi * (0.5 * self.geo.extent) ** 2

    # ----------------------------------------------------------------- shading
    def _attributes(self, face: np.ndarray, b1: np.ndarray, b2: np.ndarray):
        """World position, unit shading normal, unit tangents and uv at hit points (the
        path kernel's own interpolation, :func:`render.path.hit_attributes`)."""
        a = np.empty((len(face), 14))
        kern.hit_attributes(self.geo.packed, self.geo.faces, self.geo.face_normal, face, b1, b2, a)
        return a[:, 0:3], a[:, 3:6], a[:, 6:9], a[:, 9:12], a[:, 12:14]

    def _object_state(self, k: int, p, ns, tu, tv, uv, face, d):
        """The object-space ShadingState of lanes of object ``k`` from world attributes.

        ``face`` (n,): the triangles hit, whose geometric normals (on the side of the
        shading normals, :attr:`render.scene.Geometry.face_normal`) are
        ``state::geometry_normal()``; ``d`` (n, 3): the world directions of the rays
        that arrived, toward the surface (``state::direction()``).  Both, like every
        field, in object space and unit; ``state::object_id()`` is ``k``."""
        from displacement.state import ShadingState

        obj = self.objects[k]
        ng = self.geo.face_normal[face]
        if self.rigid_identity[k]:  # the kernels' rays are unit
            return ShadingState(p - obj.translation, ns, uv, tu, tv, obj.transform,
                                geometry_normal=ng, direction=d, object_id=int(k))
        return ShadingState(obj.to_object_points(p), obj.to_object_normals(ns), uv,
                            obj.to_object_vectors(tu), obj.to_object_vectors(tv), obj.transform,
                            geometry_normal=obj.to_object_normals(ng),
                            direction=obj.to_object_vectors(d), object_id=int(k))

    def _shade(self, k: int, state, front: np.ndarray, ior_outside=None):
        """``material.shade`` of lanes of object ``k`` (all on one side for two-faced
        materials), the bsdf bound again where the IOR around them is not air.

        Returns ``(shading, bsdf, normal_world or None, opacity (n,), ior (n,))``."""
        obj = self.objects[k]
        mat = obj.material
        sh = mat.shade(state, front)
        n = len(state)
        bsdf = getattr(sh, "bsdf", None)
        if ior_outside is not None and bsdf is not None and np.any(ior_outside != 1.0):
            surface = mat.backface if (self.two_faced[k] and not np.any(front)) else mat.surface
            ior_inside = sh.ior.mean(axis=1) if callable(mat.ior) else float(np.mean(mat.ior))
            bsdf = surface.scattering.bind(sh.state, ior_outside=ior_outside,
                                           ior_inside=ior_inside,
                                           thin_walled=bool(mat.thin_walled))
        ior = np.asarray(sh.ior, dtype=np.float64).mean(axis=1)
        nrm = getattr(sh, "normal", None)
        if nrm is None or np.array_equal(nrm, state.normal):
            normal_world = None  # unperturbed: the world normal as interpolated
        elif self.rigid_identity[k]:
            normal_world = np.asarray(nrm, dtype=np.float64)
        else:
            normal_world = obj.to_world_normals(np.asarray(nrm, dtype=np.float64))
        opacity = np.broadcast_to(
            np.clip(np.asarray(sh.cutout_opacity, dtype=np.float64), 0.0, 1.0), (n,))
        return sh, bsdf, normal_world, opacity, ior

    def _frame(self, k: int, sh, normal_world, ns: np.ndarray, tu: np.ndarray) -> Frame:
        if self.rigid_identity[k] and getattr(sh, "frame", None) is not None:
            return sh.frame
        return Frame.from_normal_tangent(ns if normal_world is None else normal_world, tu)

    def _emitted(self, k: int, sh, frame: Frame, wo_world: np.ndarray, front) -> np.ndarray:
        """Radiance (n, 3) emitted toward ``wo_world`` by object ``k`` (0 without an edf).

        Edfs emit toward their frame's ``+z``: on the back lanes (``front`` False) of a
        thin-walled material with its own ``backface``, whose edf emits from the back,
        the frame is turned over (``wo`` mirrored through the tangent plane).
        """
        if sh.edf is None:
            return np.zeros((len(wo_world), 3))
        intensity = np.broadcast_to(np.asarray(sh.intensity, dtype=np.float64),
                                    (len(wo_world), 3))
        if "power" in str(sh.mode):
            light = self.emitters.get(k)
            intensity = intensity / (light.area if light is not None else 1.0)
        wo = frame.to_local(wo_world)
        if self.two_faced[k]:
            wo = mirror_z(wo, ~np.asarray(front))
        return sh.edf.eval(wo) * intensity

    def _emission_fn(self, k: int):
        """Object ``k``'s emitted radiance at points of its triangles, for light samples
        (``AreaLight.emission``)."""

        def emission(face, bary, wo_world):
            p, ns, tu, tv, uv = self._attributes(face, bary[:, 1], bary[:, 2])
            state = self._object_state(k, p, ns, tu, tv, uv, face, -wo_world)
            front = dot(wo_world, self.geo.face_normal[face]) > 0
            out = np.zeros((len(face), 3))
            sides = (front, ~front) if self.two_faced[k] else (np.ones(len(face), dtype=bool),)
            for side in sides:
                if np.any(side):
                    sub = state if side.all() else state.subset(side)
                    sh, _, nw, _, _ = self._shade(k, sub, front[side])
                    frame = self._frame(k, sh, nw, ns[side], tu[side])
                    out[side] = self._emitted(k, sh, frame, wo_world[side], front[side])
            return out

        return emission

    def _bind(self, face, b1, b2, d, so, sior, nstk, only=None):
        """The per-lane bindings of :func:`render.path.trace` for lanes parked at objects
        shaded with numpy (and objects whose IOR context is not air).

        ``only`` (k,) bool restricts binding to those objects (shadow rays need only
        cutout and null surfaces).  Returns ``(tables, params, lane_row, bf, bslot)``:
        ``bf`` (q, 11) normal, tangent, opacity, IOR and emitted radiance, ``bslot`` (q,)
        the program slot of each bound lane."""
        m = len(face)
        lane_row = np.full(m, -1, dtype=np.int64)
        if not self.may_bind:
            return self.tables, self.params, lane_row, np.zeros((1, 11)), np.zeros(1, np.int64)
        hit = face >= 0
        objs = np.full(m, -1, dtype=np.int64)
        objs[hit] = self.geo.face_object[face[hit]]
        need = hit & self.bound[np.maximum(objs, 0)]
        outside = None
        if self.encloses.any() and np.any(nstk[hit] > 0):
            sel = np.flatnonzero(hit & (nstk > 0) & self.ior_sensitive[np.maximum(objs, 0)])
            if len(sel):
                outside = np.ones(m)
                outside[sel] = kern.outside_ior(so[sel], sior[sel], nstk[sel], objs[sel])
                need |= outside != 1.0
        if only is not None:
            need &= only[np.maximum(objs, 0)]
        q = int(np.count_nonzero(need))
        if q == 0:
            return self.tables, self.params, lane_row, np.zeros((1, 11)), np.zeros(1, np.int64)
        lane_row[need] = np.arange(q)
        bf = np.zeros((q, 11))
        bslot = np.zeros(q, dtype=np.int64)
        programs = list(self.programs)
        rows = []
        for k in np.unique(objs[need]):
            sel = np.flatnonzero(need & (objs == k))
            f = face[sel]
            p, ns, tu, tv, uv = self._attributes(f, b1[sel], b2[sel])
            state = self._object_state(k, p, ns, tu, tv, uv, f, d[sel])
            front = dot(-d[sel], self.geo.face_normal[f]) > 0
            sides = (front, ~front) if self.two_faced[k] else (np.ones(len(sel), dtype=bool),)
            for side in sides:
                if not np.any(side):
                    continue
                ss = sel[side]
                st = state if side.all() else state.subset(side)
                sh, bsdf, nw, opacity, ior = self._shade(
                    k, st, front[side], None if outside is None else outside[ss])
                frame = self._frame(k, sh, nw, ns[side], tu[side])
                v = lane_row[ss]
                bf[v, 0:3] = frame.n
                bf[v, 3:6] = frame.s
                bf[v, 6] = opacity
                bf[v, 7] = ior
                bf[v, 8:11] = self._emitted(k, sh, frame, -d[ss], front[side])
                bslot[v] = len(programs)
                programs.append(None if bsdf is None else bsdf.program)
                if bsdf is not None:
                    rows.append((v, bsdf.program))
        table = ProgramTable(programs)
        n_const = len(self.programs)
        params = np.zeros((n_const + q, table.width))
        params[:n_const, : self.params.shape[1]] = self.params
        for v, program in rows:
            program.write_params(params, n_const + v)
        tables = self.tables._replace(code=table.code, kids=table.kids, frames=table.frames,
                                      chat=table.tables, roots=table.roots,
                                      frame_lo=table.frame_lo, frame_hi=table.frame_hi)
        return tables, params, lane_row, bf, bslot

    # --------------------------------------------------------------- one chunk
    def trace(self, pixel: np.ndarray, index: np.ndarray, seed: int) -> tuple:
        """Trace one path per entry of ``pixel``: sample ``index`` of that pixel, its
        sample values from :mod:`render.sampler` (seeded ``seed``).

        One call of :func:`render.path.trace` carries every path to its end; lanes
        parked at objects shaded with numpy are bound (:meth:`_bind`) and resumed, and
        parked shadow records finished (:meth:`_shadows`), until none is left.

        Returns
        -------
        rgb : (n, 3) float64
        alpha : (n,) float64
        aovs : dict of arrays
        """
        n = len(pixel)
        kind = SAMPLERS[self.settings.sampler]
        L = np.zeros((n, 3))
        alpha = np.zeros(n)
        aov = np.zeros((n if self.aovs else 1, kern.NA))
        aov[:, kern.A_OBJECT] = -1
        buf = self._buffers(n)
        lanes, parked = buf.lanes
        counts = np.zeros(3, dtype=np.uint64)
        tables, params = self.tables, self.params
        lane_row, bf = np.full(1, -1, dtype=np.int64), np.zeros((1, 11))
        bslot = np.zeros(1, dtype=np.int64)
        m, resume = n, False
        while True:
            m, ns = kern.trace(self.scene_handle, tables, m, resume, pixel, index, seed, kind,
                               SOBOL_TABLE, *lanes, lane_row, params, bf, bslot, L, alpha,
                               aov, *parked, *buf.shadows[0], kern.scratch(tables), buf.es,
                               buf.cso, buf.csior, buf.lw, np.empty((1, params.shape[1])),
                               counts)
            if ns:
                self._shadows(ns, buf, (pixel, index, seed, kind), L, counts)
            if not m:
                break
            lanes, parked = parked, lanes
            lf, li, so, sior = lanes
            tables, params, lane_row, bf, bslot = self._bind(
                li[:m, kern.HIT], lf[:m, kern.HIT_B1], lf[:m, kern.HIT_B2],
                lf[:m, kern.D:kern.D + 3], so, sior, li[:m, kern.NSTK])
            resume = True
        self._count(counts)
        aovs = {}
        if self.aovs:
            a = {"albedo": aov[:, 0:3], "normal": aov[:, 3:6], "depth": aov[:, 6],
                 "uv": aov[:, 7:9], "object_id": aov[:, 9].astype(np.int32)}
            aovs = {name: np.ascontiguousarray(a[name]) for name in self.aovs}
        return L, alpha, aovs

    def _buffers(self, n: int):
        """This thread's arrays for a chunk of ``n`` lanes, reused from chunk to chunk
        (fresh ones would cost page faults): two sets of parked-lane arrays (read one,
        write the other) and two of shadow records, with room for every lane where
        lanes may park (else one row: nothing parks), and Embree's ray record and a
        lane's stack of closed objects."""
        buf = getattr(self._local, "buffers", None)
        if buf is None or buf.n < n:
            rows = n if self.may_bind else 1
            srows = rows * self.shadow_rows
            nest = self.nesting

            def lane_set():
                return (np.empty((rows, kern.NF)), np.empty((rows, kern.NI), dtype=np.int64),
                        np.empty((rows, nest), dtype=np.int64), np.empty((rows, nest)))

            def shadow_set():
                return (np.empty((srows, kern.NSF)), np.empty((srows, kern.NSI), dtype=np.int64),
                        np.empty((srows, nest), dtype=np.int64), np.empty((srows, nest)))

            buf = SimpleNamespace(n=n, lanes=(lane_set(), lane_set()),
                                  shadows=(shadow_set(), shadow_set()),
                                  es=embree.new_scratch(),
                                  cso=np.full((1, nest), -1, dtype=np.int64),
                                  csior=np.ones((1, nest)), lw=np.empty(len(self.tables.lights)))
            self._local.buffers = buf
        return buf

    def _shadows(self, ns, buf, sample, L, counts):
        """Finish the ``ns`` shadow records parked in ``buf.shadows[0]``: multiply in the
        radiance of lights whose emission varies (numpy), bind the records waiting at a
        surface shaded with numpy, and carry them on (:func:`render.path.resolve_shadows`)
        until each reaches its light or is blocked, adding what arrives to ``L``.
        ``sample``: the chunk's ``(pixel, index, seed, sampler kind)``."""
        cur, nxt = buf.shadows
        while ns:
            sf, si, sso, ssior = cur
            deferred = np.flatnonzero(si[:ns, kern.S_FACE] >= 0)
            if len(deferred):  # area lights whose radiance varies: evaluate it now
                f = si[deferred, kern.S_FACE]
                objs = self.geo.face_object[f]
                for k in np.unique(objs):
                    sel = deferred[objs == k]
                    le = self.emitters[k].emission(
                        si[sel, kern.S_FACE], sf[sel, kern.S_BARY:kern.S_BARY + 3],
                        -sf[sel, kern.S_L:kern.S_L + 3])
                    sf[sel, kern.S_C:kern.S_C + 3] *= le
                si[deferred, kern.S_FACE] = -1
            tables, params, lane_row, bf, bslot = self._bind(
                si[:ns, kern.S_HIT], sf[:ns, kern.S_HIT_B1], sf[:ns, kern.S_HIT_B2],
                sf[:ns, kern.S_D:kern.S_D + 3], sso, ssior, si[:ns, kern.S_NSTK],
                only=self.passable)
            ns = kern.resolve_shadows(self.scene_handle, tables, ns, *cur, lane_row, params, bf,
                                      bslot, L, *nxt, *sample, SOBOL_TABLE, kern.scratch(tables),
                                      buf.es, counts)
            cur, nxt = nxt, cur

    def _count(self, counts) -> None:
        """Add a chunk's rays and its estimated time inside Embree (``counts``: rays,
        timed rays, their cycles; threads share the totals)."""
        rays, timed, cycles = (int(c) for c in counts)
        seconds = cycles * rays / timed / embree.cycle_rate() if timed else 0.0
        with self._count_lock:
            self.rays += rays
            self.embree_time += seconds

    @property
    def scene_handle(self) -> int:
        return self.geo.embree.handle

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
        work = partial(render_chunk, self, plan)

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
            bound_objects=[o.name for o, b in zip(self.objects, self.bound, strict=True) if b],
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
    declared = registry().dfs.get(getattr(edf, "name", None))
    if declared is None or not declared.lambertian or callable(emission.intensity):
        return None
    if getattr(material, "thin_walled", False) or _has_cutout(material):
        return None
    if material.geometry.normal is not None:
        return None
    intensity = np.broadcast_to(np.asarray(emission.intensity, dtype=np.float64), (3,))
    return intensity / np.pi, "power" in str(getattr(emission, "mode", ""))


def _constant_edf(material) -> bool:
    """Whether an emissive material's emission is the same everywhere on it: constant
    intensities and edf arguments, no bump, no varying cutout (its edf programs then
    run in the path kernel, at hits and at light samples)."""
    if not _is_emissive(material) or material.geometry.normal is not None:
        return False
    if callable(getattr(material.geometry, "cutout_opacity", 1.0)):
        return False
    for surface in (material.surface, material.backface):
        emission = surface.emission
        if emission.emission is None:
            continue
        if callable(emission.intensity):
            return False
        for n in _df_nodes(emission.emission):
            if any(callable(value) for value in n.kwargs.values()):
                return False
    return True


def _edf_albedo(program, samples: int = 4096) -> float:
    """The luminance of ``∫ edf cos`` over the hemisphere of an edf program (1 for a
    lone diffuse or spot edf), by its own sampling at Sobol points."""
    from render.program import ProgramEdf, sobol_points

    u = sobol_points(samples)
    s = ProgramEdf(program).sample(u[:, 0], u[:, 1:])
    return float(np.mean(_luminance(np.where(s.pdf[:, None] > 0.0, s.weight, 0.0))))


def _luminance(rgb) -> np.ndarray:
    from render.program import LUM_B, LUM_G, LUM_R

    return np.asarray(rgb, dtype=np.float64) @ np.array([LUM_R, LUM_G, LUM_B])


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
    from render.precompile import compiled_integrator, notice_first_compile
    from render.scene import Scene, load_scene

    if not isinstance(scene, Scene):
        scene = load_scene(scene)
    t0 = _time.perf_counter()
    geometry = scene.build()
    build_s = _time.perf_counter() - t0
    aov_list = list(aovs)
    denoise = denoise or bool(getattr(scene.settings, "denoise", False))  # or denoise = true
    if denoise:
        aov_list = list(dict.fromkeys(aov_list + ["albedo", "normal"]))
    notice_first_compile("pwc", quiet=not progress)
    integ = compiled_integrator(scene, geometry, aov_list)
    film = integ.render(spp=spp, time_budget=time, seed=seed, progress=progress, threads=threads)
    film.stats["build_s"] = build_s
    film.stats["geometry"] = geometry.stats
    if denoise:
        film.denoise()
    return film
