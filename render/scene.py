"""Scenes: TOML scene files, objects with MDL materials, and the one Embree scene built from them.

A scene file has a ``[camera]``, a ``[render]`` table of settings, ``[[lights]]`` and
``[[objects]]``; every material is an MDL call expression as the Handbook prints it in
its figure captions, parsed by :mod:`render.expr`.  Example (the Handbook's stage)::

    [camera]
    type = "pinhole"                # or "orthographic" (then ortho_height = ...)
    position = [0.5, 1.2, 3.2]
    look_at = [0.5, 0.45, 0.0]
    fov = 35.0                      # vertical, degrees

    [render]
    resolution = [256, 192]
    spp = 64                        # or time = 30.0 (seconds)
    max_depth = 8
    seed = 0

    [[lights]]
    type = "quad"                   # an emissive quad: an area light (diffuse_edf)
    center = [-1.5, 3.0, 1.5]
    normal = [0.5, -1.0, -0.3]      # the direction it faces
    size = [1.0, 1.0]
    radiance = [6.0, 6.0, 6.0]      # or intensity = MDL radiant exitance (= pi radiance)

    [[objects]]
    name = "square"
    surface = "square"              # or { type = "sphere", radius = 0.5 }, or mesh = "x.obj"
    translate = [-0.6, 0.0, 0.0]
    rotate = [0.0, 20.0, 0.0]       # degrees about x, then y, then z
    scale = 1.0
    material = "waves(distance: float2(0.02, 0.02), frequency: float2(10.0, 10.0))"

    [[objects]]                     # a material written in MDL: a call into a module
    surface = "square"
    material = { module = "mouldings.mdl", call = "stone_molding(scale: 2.0)" }

A material is an MDL call: as a string, a call of the workbench's materials and functions
by name (:mod:`render.expr`); as a table, ``call`` into the exports of ``module`` (an
``.mdl`` file, or a qualified name ``::a::b``), found beside the scene, then in the
``--mdl-path`` folders, then ``$PWC_MDL_PATH``, then the workbench's own MDL library
(:mod:`render.mdlc`).

Light types: ``point`` (position, intensity), ``spot`` (position, direction or look_at,
intensity, cutoff_angle, beam_width), ``directional`` (direction, irradiance),
``environment`` (radiance, or file = lat-long EXR with scale and rotation, or function =
an MDL call of a colour function of ``state::direction()`` such as
``base::sun_and_sky(...)``, optionally into ``module``, baked at ``resolution``:
:mod:`render.mdlc.environment`),
``sun_and_sky`` (sun_direction, or elevation and azimuth in degrees; turbidity,
intensity, sun_radius, sun_scale, sky_scale, ground_albedo: :class:`render.sky.SunAndSky`),
``quad`` (center, normal, size, up, radiance or intensity) and ``sphere`` (center,
radius, radiance or intensity).  Units: :mod:`render.lights`.

Surfaces by name (:func:`displacement.view.make_surface`: ``square``, ``plane``,
``sphere``, ``cylinder``, ``torus``, ``cube``), or as a table ``{ type = NAME, ... }``
whose other keys are the constructor's parameters (``square`` -> UnitSquare, ``plane``
-> Plane, ``sphere`` -> UVSphere, ``cylinder``, ``torus``, ``cube``).  ``mesh = PATH``
loads a file with trimesh (relative to the scene file; without texture coordinates its
uv is 0 everywhere).

Errors raise :class:`SceneError`, whose message starts with ``file:line:col:``; a bad
material expression is reported at the column of the expression inside the TOML file.

Geometry (:meth:`Scene.build`): only objects whose material has a displacement are
diced, by :func:`displacement.dice.dice` for this scene's camera; the others use their
base surface's ``base_mesh``.  All triangles go into ONE Embree scene (float32), one
geometry per object (Embree's ``geomID`` is the object id), with float64 attribute
tables (positions, shading normals, uv, tangents) interpolated at hits.
"""

from __future__ import annotations

import math
import re
import tomllib
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from render.camera import Camera
from render.lights import (
    ConstantEnvironment,
    DirectionalLight,
    LatLongEnvironment,
    Light,
    PointLight,
    SpotLight,
)

__all__ = [
    "SceneError",
    "SceneReadError",
    "RenderSettings",
    "SceneObject",
    "Scene",
    "Geometry",
    "load_scene",
    "parse_scene",
    "patch_scene_text",
    "modelling_summary",
    "make_transform",
    "SURFACE_TYPES",
]

#: surface names accepted in ``surface = { type = NAME, ... }`` -> displacement.surfaces class
SURFACE_TYPES = {
    "square": "UnitSquare",
    "plane": "Plane",
    "sphere": "UVSphere",
    "cylinder": "Cylinder",
    "torus": "Torus",
    "cube": "Cube",
}

#: base-mesh resolution (cells in u, v) of curved parametric surfaces that are not diced
_BASE_RESOLUTION = {"UVSphere": (128, 64), "Cylinder": (128, 1), "Torus": (128, 48)}


class SceneError(ValueError):
    """A scene file (or scene description) is wrong; ``str()`` is ``file:line:col: message``.

    Attributes
    ----------
    path : str
    line, column : int
        1-based; 0 when unknown.
    message : str
    """

    def __init__(self, message: str, path: str = "<scene>", line: int = 0, column: int = 0):
        self.path, self.line, self.column, self.message = str(path), int(line), int(column), message
        loc = self.path
        if self.line:
            loc += f":{self.line}"
            if self.column:
                loc += f":{self.column}"
        super().__init__(f"{loc}: {message}")


class SceneReadError(SceneError):
    """The scene file itself cannot be read (missing, a folder, no permission)."""


@dataclass
class RenderSettings:
    """The ``[render]`` table.

    Parameters
    ----------
    width, height : int
        Image size in pixels (``resolution = [w, h]``).
    spp : int
        Samples per pixel (ignored when ``time`` is given).
    time : float or None
        Time budget in seconds: render passes of ``spp_per_pass`` samples until it is
        spent (at least one pass).
    max_depth : int
        Longest path, in vertices after the camera (Mitsuba's ``max_depth``: 1 shows
        emitters only, 2 is direct lighting); -1 for unlimited (Russian roulette ends
        the paths).
    rr_depth : int
        Depth from which Russian roulette may end paths.
    seed : int
        Same seed, same image.
    dicing_rate, dicing_tolerance : float
        Pixels; passed to :func:`displacement.dice.dice`.
    spp_per_pass : int
        Samples per pixel per pass (the unit of progress and of the time budget).
    curves : {"exact", "float32", "polyline"}
        How pwc profiles are evaluated (:func:`render.library.resources.evaluation`):
        exact arcs in float64, the same in float32, or polylines within
        ``curve_tolerance`` (normalized units).
    curve_tolerance : float
    texture_filter : {"bilinear", "nearest"}
        How image textures are filtered.
    denoise : bool
        Denoise the image (Open Image Denoise) after rendering (``pwc render`` honours
        it, as ``--denoise``).
    dice_invisible : bool
        Dice every displaced object.  By default (False) a displacement the camera
        cannot see is not diced (:meth:`Scene.build`).
    light_selection : {"contribution", "power", "uniform"}
        How next-event estimation picks a light at a vertex
        (:func:`render.light_sampling.select_light`): by a bound on what each light can contribute
        there (distance, orientation, power), by power alone, or uniformly.
    every_delta_light : bool
        Sample each point, spot and directional light at every vertex (when a scene
        has at most four), besides the light selected among the others.
    sampler : {"sobol", "independent"}
        Where a path's sample values come from (:mod:`render.sampler`): Owen-scrambled
        Sobol points of its pixel, or independent uniforms.
    """

    width: int = 256
    height: int = 256
    spp: int = 16
    time: float | None = None
    max_depth: int = 8
    rr_depth: int = 5
    seed: int = 0
    dicing_rate: float = 1.0
    dicing_tolerance: float = 0.5
    spp_per_pass: int = 1
    curves: str = "exact"
    curve_tolerance: float = 1e-4
    texture_filter: str = "bilinear"
    denoise: bool = False
    dice_invisible: bool = False
    light_selection: str = "contribution"
    every_delta_light: bool = True
    sampler: str = "sobol"

    def validate(self) -> RenderSettings:
        for name in ("width", "height", "spp", "spp_per_pass"):
            v = getattr(self, name)
            if not isinstance(v, (int, np.integer)) or isinstance(v, bool) or v < 1:
                raise ValueError(f"{name} must be a whole number >= 1, got {v!r}")
        if self.time is not None and not (isinstance(self.time, (int, float)) and self.time > 0):
            raise ValueError(f"time must be a number of seconds > 0, got {self.time!r}")
        if not isinstance(self.max_depth, (int, np.integer)) or (
            self.max_depth < 1 and self.max_depth != -1
        ):
            raise ValueError(
                f"max_depth must be >= 1 (or -1 for unlimited), got {self.max_depth!r}"
            )
        if not isinstance(self.rr_depth, (int, np.integer)) or self.rr_depth < 1:
            raise ValueError(f"rr_depth must be >= 1, got {self.rr_depth!r}")
        if not isinstance(self.seed, (int, np.integer)) or self.seed < 0:
            raise ValueError(f"seed must be a whole number >= 0, got {self.seed!r}")
        for name in ("dicing_rate", "dicing_tolerance"):
            v = getattr(self, name)
            if not (isinstance(v, (int, float)) and math.isfinite(v) and v > 0):
                raise ValueError(f"{name} must be a number of pixels > 0, got {v!r}")
        from displacement.textures import FILTERS
        from render.library.resources import CURVE_MODES

        if self.curves not in CURVE_MODES:
            raise ValueError(f"curves must be one of {', '.join(map(repr, CURVE_MODES))}, got "
                             f"{self.curves!r}")
        v = self.curve_tolerance
        if not (isinstance(v, (int, float)) and not isinstance(v, bool) and math.isfinite(v)
                and v > 0):
            raise ValueError(f"curve_tolerance must be a number > 0, got {v!r}")
        if self.texture_filter not in FILTERS:
            raise ValueError(f"texture_filter must be one of {', '.join(map(repr, FILTERS))}, "
                             f"got {self.texture_filter!r}")
        if self.light_selection not in ("contribution", "power", "uniform"):
            raise ValueError("light_selection must be one of 'contribution', 'power', "
                             f"'uniform', got {self.light_selection!r}")
        if self.sampler not in ("sobol", "independent"):
            raise ValueError(f"sampler must be 'sobol' or 'independent', got {self.sampler!r}")
        for name in ("denoise", "dice_invisible", "every_delta_light"):
            if not isinstance(getattr(self, name), bool):
                raise ValueError(f"{name} must be true or false, got {getattr(self, name)!r}")
        return self


@dataclass
class SceneObject:
    """One object: a base surface (or mesh), a transform and a material.

    Parameters
    ----------
    surface
        A :mod:`displacement.surfaces` surface (parametric with ``state_at_uv``, or a
        mesh surface).
    material
        A material with ``shade(state)`` and ``geometry.displacement`` (see
        :mod:`render.material`).
    transform : (4, 4) float64
        Object to world.
    name : str
    resolution : (int, int) or None
        Cells of the base mesh of an undiced parametric surface (None: a default that
        keeps curved silhouettes smooth at the usual image sizes).
    material_text : str
        The MDL expression the material came from (for messages and the gallery).
    dicing_rate, dicing_tolerance : float or None
        Pixels: this object's own dicing settings (None: the scene's).
    displacement_method : {"displacement", "bump", "normal_map"}
        How the material's displacement was modelled (:mod:`render.displacement_method`;
        applied to ``material`` when the scene is read).
    original_displacement : Field or None
        The displacement the material was written with, when ``displacement_method``
        modelled it as bump or a normal map (``material`` then has none).
    not_diced : str or None
        Why :meth:`Scene.build` did not dice this displaced object (the camera cannot see
        its displacement), or None.
    """

    surface: Any
    material: Any
    transform: np.ndarray = field(default_factory=lambda: np.eye(4))
    name: str = "object"
    resolution: tuple[int, int] | None = None
    material_text: str = ""
    dicing_rate: float | None = None
    dicing_tolerance: float | None = None
    displacement_method: str = "displacement"
    original_displacement: Any = None
    not_diced: str | None = None

    def __post_init__(self) -> None:
        from displacement.dice.evaluator import check_transform

        self.transform = check_transform(self.transform)
        self.linear = self.transform[:3, :3]
        self.inv_linear = np.linalg.inv(self.linear)
        self.translation = self.transform[:3, 3]

    @property
    def displacement(self):
        """The material's displacement field, or None (always for hair strands: MDL's
        material geometry does not apply to hair)."""
        from render.hair import Strands

        if isinstance(self.surface, Strands):
            return None
        geometry = getattr(self.material, "geometry", None)
        return getattr(geometry, "displacement", None)

    # object <-> world (row vectors)
    def to_object_points(self, p: np.ndarray) -> np.ndarray:
        """World points (n, 3) in object space."""
        return (p - self.translation) @ self.inv_linear.T

    def to_object_normals(self, n: np.ndarray) -> np.ndarray:
        """World normals (n, 3) in object space (unit; normals transform by L^T)."""
        return _unit_rows(n @ self.linear)

    def to_object_vectors(self, v: np.ndarray) -> np.ndarray:
        """World tangent vectors (n, 3) in object space (unit)."""
        return _unit_rows(v @ self.inv_linear.T)

    def to_world_normals(self, n: np.ndarray) -> np.ndarray:
        """Object-space normals (n, 3) in world space (unit)."""
        return _unit_rows(n @ self.inv_linear)


def _unit_rows(v: np.ndarray) -> np.ndarray:
    from render.numerics import unitize

    u, ok = unitize(v)
    return np.where(ok[:, None], u, np.array([0.0, 0.0, 1.0]))


@dataclass
class Scene:
    """A camera, lights, objects and render settings.

    Parameters
    ----------
    camera : Camera
        Its ``width``/``height`` are the image size.
    objects : list of SceneObject
    lights : list of Light
        Non-geometric lights (point, spot, directional, environment); emissive objects
        are area lights automatically.
    settings : RenderSettings
    path : str
        Where the scene came from (for messages).
    """

    camera: Camera
    objects: list[SceneObject]
    lights: list[Light] = field(default_factory=list)
    settings: RenderSettings = field(default_factory=RenderSettings)
    path: str = "<scene>"

    def build(self, progress: bool = False) -> Geometry:
        """Tessellate (dice displaced objects) and build the Embree scene.

        Raises :class:`render.film.FilmTooLarge` first, before any dicing, when the image
        would not fit in memory.
        """
        from render.film import check_film_memory

        check_film_memory(self.camera.width, self.camera.height)
        if not self.settings.dice_invisible:
            self.objects = [_model_what_is_seen(o, self.camera, self.settings)
                            for o in self.objects]
        return Geometry.build(self, progress=progress)


def _model_what_is_seen(obj: SceneObject, camera: Camera, settings: RenderSettings):
    """``obj``, or, where the camera cannot see its displacement, a copy that is not diced:
    a displacement of zero length here is dropped; one under the dicing tolerance, or on
    an object out of view, is shaded as bump from the same field (its normals still
    show).  Its triangles are then the undisplaced surface as coarse as the tolerance
    allows.  Mesh surfaces, and objects already modelled otherwise, are kept."""
    import dataclasses

    from displacement.dice import displacement_on_screen, is_mesh_surface
    from render.displacement_method import apply, without_displacement

    field_ = obj.displacement
    if field_ is None or obj.displacement_method != "displacement" or is_mesh_surface(
            obj.surface):
        return obj
    tolerance = obj.dicing_tolerance or settings.dicing_tolerance
    pixels, in_view = displacement_on_screen(obj.surface, field_, camera, obj.transform,
                                             stop_above=tolerance)
    if pixels == 0.0:
        why, material, method = "its displacement is zero", without_displacement(
            obj.material), "none"
    elif in_view and pixels > tolerance:
        return obj
    else:
        why = ("out of view" if not in_view else
               f"its displacement is {pixels:.2g} px here, under the {tolerance:g} px "
               "tolerance")
        material, method = apply(obj.material, obj.surface, "bump"), "bump"
    return dataclasses.replace(obj, material=material, displacement_method=method,
                               original_displacement=field_,
                               not_diced=f"{why}: shaded as {method}" if method == "bump"
                               else why)


# ----------------------------------------------------------------------------- geometry
@dataclass
class Geometry:
    """Every triangle of a scene in one Embree scene, with float64 attribute tables.

    Vertex tables are global (all objects concatenated); ``faces`` index them.  Embree's
    ``geomID`` is the object index and ``primID`` the triangle within the object:
    the global triangle is ``face_offset[geomID] + primID``.

    Attributes
    ----------
    vertices, normals, tangent_u, tangent_v : (v, 3) float64
        World positions, unit shading normals and unit tangents.
    uv : (v, 2) float64
    faces : (f, 3) int64
    face_object : (f,) int32
    face_normal : (f, 3) float64
        Unit geometric normals, flipped to the side of the vertex normals.
    face_offset : (k + 1,) int64
        First triangle of each object.
    extent : float
        Diagonal of the scene's bounding box (ray offsets scale with it).
    center : (3,) float64
    stats : list of dict
        Per object: triangle count, whether it was diced, and the dicer's statistics
        (hair: ``curve_segments``, ``strands``, ``curve_kind``).
    curves : (s, 16) float64
        The hair segments' curve table (:mod:`render.hair`); a hair object's segments
        also have placeholder rows in ``faces`` (never traced), so that every
        primitive is ``face_offset[geomID] + primID``.
    curve_first : (k,) int64
        Each hair object's first row of ``curves`` (-1: a triangle mesh).
    coord_max : float
        The largest absolute world coordinate (ray offsets cover its float32 rounding).
    """

    embree: Any
    vertices: np.ndarray
    normals: np.ndarray
    tangent_u: np.ndarray
    tangent_v: np.ndarray
    uv: np.ndarray
    faces: np.ndarray
    face_object: np.ndarray
    face_normal: np.ndarray
    face_offset: np.ndarray
    extent: float
    center: np.ndarray
    stats: list

    #: (s, 16) the hair segments' Bézier control points and radii in world space
    #: (:func:`render.hair.Strands.world`; one row of zeros when there are none)
    curves: np.ndarray = field(default_factory=lambda: np.zeros((1, 16)))
    #: (k,) int64 each hair object's first row of ``curves`` (-1: a triangle mesh)
    curve_first: np.ndarray = field(default_factory=lambda: np.zeros(0, dtype=np.int64))
    #: the largest absolute world coordinate of any vertex or control point
    coord_max: float = 0.0

    @classmethod
    def build(cls, scene: Scene, progress: bool = False) -> Geometry:
        from render.embree import Curves, EmbreeScene
        from render.hair import Strands, StrandsError

        parts = []
        stats = []
        strands = {}  # object -> (world control points, curve table rows)
        for k, obj in enumerate(scene.objects):
            if isinstance(obj.surface, Strands):
                try:
                    pts, segs, rows = obj.surface.world(obj.transform)
                except StrandsError as e:
                    raise ValueError(f"object {obj.name!r} (hair strands): {e}") from None
                strands[k] = (pts, segs, rows)
                z3 = np.zeros((0, 3))
                # a placeholder triangle per curve segment (never traced: Embree gets the
                # curves): the kernels find every primitive's object by its global number
                part = (z3, np.zeros((len(rows), 3), dtype=np.int64), np.zeros((0, 2)), z3, z3,
                        z3)
                st = {"diced": False, "triangles": 0, "curve_segments": len(rows),
                      "strand_segments": obj.surface.segment_count,
                      "strands": obj.surface.strand_count, "curve_kind": obj.surface.kind}
            else:
                part, st = _object_triangles(obj, scene.camera, scene.settings)
            st["name"] = obj.name
            parts.append(part)
            stats.append(st)
        if not parts:
            raise ValueError("the scene has no objects")
        if not any(len(p[1]) for p in parts):
            names = ", ".join(repr(st["name"]) for st in stats)
            raise ValueError(f"nothing to trace: every object ({names}) has zero area (a "
                             "displacement that collapses a surface to a line or a point "
                             "leaves no triangles)")
        if not any(len(p[0]) for i, p in enumerate(parts) if i not in strands):
            # hair only: one vertex for the placeholders to index
            i = min(strands)
            parts[i] = (np.zeros((1, 3)), parts[i][1], np.zeros((1, 2)),
                        np.array([[0.0, 0.0, 1.0]]), np.array([[1.0, 0.0, 0.0]]),
                        np.array([[0.0, 1.0, 0.0]]))
        v_off = np.cumsum([0] + [len(p[0]) for p in parts])
        f_off = np.cumsum([0] + [len(p[1]) for p in parts]).astype(np.int64)
        vertices = np.concatenate([p[0] for p in parts])
        faces = np.concatenate([p[1] + (0 if i in strands else v_off[i])
                                for i, p in enumerate(parts)]).astype(np.int64)
        uv = np.concatenate([p[2] for p in parts])
        normals = np.concatenate([p[3] for p in parts])
        tu = np.concatenate([p[4] for p in parts])
        tv = np.concatenate([p[5] for p in parts])
        face_object = np.repeat(np.arange(len(parts), dtype=np.int32), np.diff(f_off))
        # geometric normals, oriented like the interpolated shading normals
        c = vertices[faces]
        ng = np.cross(c[:, 1] - c[:, 0], c[:, 2] - c[:, 0])
        nsum = normals[faces].sum(axis=1)
        ng = np.where((np.einsum("ij,ij->i", ng, nsum) < 0)[:, None], -ng, ng)
        from render.numerics import unitize

        ng_u, ok = unitize(ng)
        ns_u, ok2 = unitize(nsum)
        face_normal = np.where(ok[:, None], ng_u, np.where(ok2[:, None], ns_u, [0.0, 0.0, 1.0]))
        boxes = [(p[0].min(axis=0), p[0].max(axis=0)) for i, p in enumerate(parts)
                 if len(p[0]) and i not in strands]
        for pts, _, _ in strands.values():
            r = pts[:, 3:4]
            boxes.append(((pts[:, :3] - r).min(axis=0), (pts[:, :3] + r).max(axis=0)))
        lo = np.min([b[0] for b in boxes], axis=0)
        hi = np.max([b[1] for b in boxes], axis=0)
        extent = float(np.linalg.norm(hi - lo)) or 1.0
        coord_max = max(float(np.abs(b).max()) for box in boxes for b in box)

        embree = EmbreeScene([Curves(strands[i][0], strands[i][1], scene.objects[i].surface.kind)
                              if i in strands else (p[0], p[1]) for i, p in enumerate(parts)])
        # the curve table: one row per segment, each hair object's rows together
        curve_first = np.full(len(parts), -1, dtype=np.int64)
        rows = [np.zeros((1, 16))]
        count = 0
        for k in sorted(strands):
            curve_first[k] = count
            rows.append(strands[k][2])
            count += len(strands[k][2])
        curves = np.ascontiguousarray(np.vstack(rows[1:] if strands else rows))
        return cls(embree, vertices, normals, tu, tv, uv, faces, face_object, face_normal,
                   f_off, extent, 0.5 * (lo + hi), stats, curves=curves,
                   curve_first=curve_first, coord_max=coord_max)

    @property
    def triangle_count(self) -> int:
        """Triangles traced (the placeholders of hair segments not counted)."""
        return len(self.faces) - self.curve_segment_count

    @property
    def curve_segment_count(self) -> int:
        """Hair curve segments traced (:mod:`render.hair`)."""
        return sum(int(st.get("curve_segments", 0)) for st in self.stats)

    @property
    def packed(self) -> np.ndarray:
        """(v, 14) float64: positions, normals, tangent_u, tangent_v, uv side by side."""
        if getattr(self, "_packed", None) is None:
            self._packed = np.ascontiguousarray(
                np.concatenate(
                    [self.vertices, self.normals, self.tangent_u, self.tangent_v, self.uv], axis=1
                )
            )
        return self._packed


def _object_triangles(obj: SceneObject, camera: Camera, settings: RenderSettings):
    """World-space triangles and per-vertex attributes of one object.

    Returns
    -------
    (vertices, faces, uv, normals, tangent_u, tangent_v), stats
    """
    from displacement.dice import dice, is_mesh_surface

    field_ = obj.displacement
    surface = obj.surface
    # a displacement not diced because the camera cannot see it: the base surface as
    # coarse as the tolerance allows for this camera (the dicer without a field)
    if field_ is not None or obj.not_diced:
        mesh = dice(
            surface,
            field_,
            camera,
            obj.transform,
            dicing_rate=obj.dicing_rate or settings.dicing_rate,
            tolerance=obj.dicing_tolerance or settings.dicing_tolerance,
        )
        n = _unit_rows(mesh.normals)
        tu = _unit_rows(mesh.tangents)
        tv = _unit_rows(np.cross(n, tu))
        st = {
            "diced": field_ is not None,
            "triangles": mesh.triangle_count,
            "dice_time_s": mesh.stats.get("time_s"),
            "max_error_px": mesh.stats.get("max_error_px"),
        }
        if obj.not_diced:
            st["not_diced"] = obj.not_diced
        return (mesh.vertices, mesh.faces.astype(np.int64), mesh.uv, n, tu, tv), st
    if is_mesh_surface(surface):
        base = surface.base_mesh()
        faces = np.asarray(base.faces, dtype=np.int64)
        nf = len(faces)
        # per-corner attributes from the surface (per-face frames of a mesh surface)
        face_index = np.repeat(np.arange(nf), 3)
        bary = np.tile(np.eye(3), (nf, 1))
        state = surface.state_at(face_index, bary)
        pos = state.position
        new_faces = np.arange(3 * nf, dtype=np.int64).reshape(nf, 3)
    else:
        res = obj.resolution or _BASE_RESOLUTION.get(type(surface).__name__, (None, None))
        uv, new_faces = surface.base_grid(*res)
        state = surface.state_at_uv(uv)
        pos = state.position
    verts = pos @ obj.linear.T + obj.translation
    n = obj.to_world_normals(state.normal)
    tu = _unit_rows(state.tangent_u @ obj.linear.T)
    tv = _unit_rows(state.tangent_v @ obj.linear.T)
    st = {"diced": False, "triangles": len(new_faces)}
    return (verts, new_faces, state.uv, n, tu, tv), st


def _triangle_area(obj: SceneObject) -> float:
    """Total area of an undisplaced object's triangles, as the renderer builds them."""
    (v, f, *_), _ = _object_triangles(obj, None, RenderSettings())
    c = v[f]
    return float(0.5 * np.linalg.norm(np.cross(c[:, 1] - c[:, 0], c[:, 2] - c[:, 0]),
                                      axis=1).sum())


def _df_names(node) -> set[str]:
    """MDL names of a df node and every df inside it (layers, mixes, components)."""
    from render.material import DfNode

    if not isinstance(node, DfNode):
        return set()
    names = {node.name}
    for value in node.kwargs.values():
        for item in value if isinstance(value, tuple | list) else (value,):
            names |= _df_names(item)
    return names


def modelling_summary(scene: Scene, geometry_stats: list) -> list[dict]:
    """What was modelled for each object of a built scene, and why.

    Parameters
    ----------
    scene : Scene
    geometry_stats : list of dict
        :attr:`Geometry.stats` (``film.stats["geometry"]``).

    Returns
    -------
    list of dict
        Per object: ``name``; ``geometry`` (diced, or the base mesh, with its triangle
        count and why); ``displacement`` (its method, or none); ``normal`` (whether a
        bumped normal is evaluated at each shading point); ``dfs`` (the distribution
        functions its material's programs use); ``emits``, ``volume``, ``thin_walled``,
        ``cutout``.
    """
    out = []
    for obj, st in zip(scene.objects, geometry_stats, strict=True):
        m = obj.material
        field_ = obj.original_displacement or obj.displacement
        if "curve_segments" in st:  # hair (render.hair): the material's hair field only
            out.append({
                "name": obj.name,
                "geometry": (f"hair: {st['strands']:,} strands, {st['strand_segments']:,} "
                             f"{st['curve_kind']} curve segments"
                             + (f" (traced as {st['curve_segments']:,}: long thin ones split)"
                                if st["curve_segments"] != st["strand_segments"] else "")
                             + " (Embree round curves)"),
                "triangles": 0, "diced": False, "displacement": "none",
                "normal": "the fibre's (tangent and tube normal)",
                "dfs": sorted(_df_names(m.hair)) or ["none (black)"],
                "emits": False, "volume": False, "thin_walled": False, "cutout": False,
            })
            continue
        if st.get("diced"):
            err = st.get("max_error_px")
            geometry = (f"diced: {st['triangles']:,} triangles"
                        + (f", within {err:.2g} px" if err is not None else ""))
        elif field_ is not None:
            geometry = (f"base mesh: {st['triangles']:,} triangles (displacement as "
                        f"{obj.displacement_method.replace('_', ' ')})")
        else:
            geometry = f"base mesh: {st['triangles']:,} triangles (not displaced)"
        if st.get("not_diced"):
            geometry = (f"base mesh: {st['triangles']:,} triangles (not diced: "
                        f"{st['not_diced']})")
        dfs = _df_names(getattr(m.surface, "scattering", None))
        if not m.backface.is_default:
            dfs |= _df_names(m.backface.scattering)
        emission = getattr(m.surface.emission, "emission", None)
        dfs |= _df_names(emission)
        volume = m.volume
        has_volume = volume.scattering is not None or any(
            callable(c) or np.any(np.asarray(c, dtype=float) > 0)
            for c in (volume.absorption_coefficient, volume.scattering_coefficient))
        cutout = m.geometry.cutout_opacity
        out.append({
            "name": obj.name,
            "geometry": geometry,
            "triangles": int(st["triangles"]),
            "diced": bool(st.get("diced")),
            "displacement": (obj.displacement_method if field_ is not None else "none"),
            "normal": ("evaluated (bump)" if m.geometry.normal is not None else
                       "interpolated (no bump)"),
            "dfs": sorted(dfs) or ["none (black)"],
            "emits": emission is not None,
            "volume": bool(has_volume),
            "thin_walled": bool(m.thin_walled),
            "cutout": bool(callable(cutout) or np.any(np.asarray(cutout, dtype=float) < 1)),
        })
    return out


# ------------------------------------------------------------------------------ parsing
def make_transform(translate=(0.0, 0.0, 0.0), rotate=(0.0, 0.0, 0.0), scale=1.0) -> np.ndarray:
    """Object-to-world matrix: scale, then rotate about x, y, z (degrees), then translate.

    Examples
    --------
    >>> m = make_transform(translate=[1, 0, 0], rotate=[0, 90, 0], scale=2)
    >>> np.round(m @ [1.0, 0.0, 0.0, 1.0], 12).tolist()    # +x turns to -z, scaled, moved
    [1.0, 0.0, -2.0, 1.0]
    >>> make_transform(scale=0)
    Traceback (most recent call last):
    ...
    ValueError: scale must be non-zero numbers, got 0
    """
    t = np.asarray(translate, dtype=np.float64)
    r = np.radians(np.asarray(rotate, dtype=np.float64))
    s = np.asarray(scale, dtype=np.float64)
    if t.shape != (3,) or not np.all(np.isfinite(t)):
        raise ValueError(f"translate must be [x, y, z], got {translate!r}")
    if r.shape != (3,) or not np.all(np.isfinite(r)):
        raise ValueError(f"rotate must be [x, y, z] degrees, got {rotate!r}")
    s = np.broadcast_to(s, (3,)) if s.ndim == 0 else s
    if s.shape != (3,) or not np.all(np.isfinite(s)) or np.any(s == 0):
        raise ValueError(f"scale must be non-zero numbers, got {scale!r}")
    cx, cy, cz = np.cos(r)
    sx, sy, sz = np.sin(r)
    rx = np.array([[1, 0, 0], [0, cx, -sx], [0, sx, cx]])
    ry = np.array([[cy, 0, sy], [0, 1, 0], [-sy, 0, cy]])
    rz = np.array([[cz, -sz, 0], [sz, cz, 0], [0, 0, 1]])
    m = np.eye(4)
    m[:3, :3] = rz @ ry @ rx @ np.diag(s)
    m[:3, 3] = t
    return m


class _Locator:
    """Line and column of tables and keys in TOML text (tomllib keeps no positions)."""

    _HEADER = re.compile(r"^\s*(\[\[?)\s*([A-Za-z0-9_.\-]+)\s*\]\]?")

    def __init__(self, text: str):
        self.text = text
        self.lines = text.splitlines()
        self.line_start = [0]
        for ln in text.splitlines(keepends=True):
            self.line_start.append(self.line_start[-1] + len(ln))
        # sections: (name, index or None, first line (1-based), last line)
        self.sections: list[list] = [["", None, 1, len(self.lines)]]
        counts: dict[str, int] = {}
        for i, ln in enumerate(self.lines, start=1):
            m = self._HEADER.match(ln)
            if not m or _in_multiline_string(text, self.line_start[i - 1]):
                continue
            name = m.group(2)
            if m.group(1) == "[[":
                idx = counts.get(name, -1) + 1
                counts[name] = idx
            else:
                head = name.split(".")[0]
                idx = counts.get(head) if head != name else None
            self.sections[-1][3] = i - 1
            self.sections.append([name, idx, i, len(self.lines)])

    def section(self, name: str, index: int | None = None) -> tuple[int, int]:
        """(first, last) line of a table (or of the index-th array table)."""
        for s in self.sections:
            if s[0] == name and (index is None or s[1] == index):
                return s[2], s[3]
        return 0, 0

    def key(self, name: str, index: int | None, key: str) -> tuple[int, int]:
        """(line, column) of ``key =`` in a table, or of the table header, or (0, 0)."""
        pat = re.compile(r"^\s*" + re.escape(key) + r"\s*=")
        for s in self.sections:
            if not (s[0] == name or s[0].startswith(name + ".")) or (
                index is not None and s[1] != index
            ):
                continue
            for ln in range(s[2], s[3] + 1):
                if pat.match(self.lines[ln - 1]):
                    return ln, len(self.lines[ln - 1]) - len(self.lines[ln - 1].lstrip()) + 1
        first, _ = self.section(name, index)
        return first, 1 if first else 0

    def find_key(self, name: str, index: int | None, key: str,
                 after: tuple[int, int] = (0, 0)) -> tuple[int, int]:
        """(line, column) of ``key =`` anywhere in a table's lines (inside an inline
        table too), at or after ``after``; (0, 0) if absent."""
        pat = re.compile(r"(?:^|[\s{,])(" + re.escape(key) + r")\s*=")
        for s in self.sections:
            if not (s[0] == name or s[0].startswith(name + ".")) or (
                index is not None and s[1] != index
            ):
                continue
            for ln in range(max(s[2], after[0]), s[3] + 1):
                text = self.lines[ln - 1].split("#", 1)[0]
                start = after[1] if ln == after[0] else 0
                m = pat.search(text, max(start - 1, 0))
                if m:
                    return ln, m.start(1) + 1
        return 0, 0

    def array_item(self, line: int, column: int, path) -> tuple[int, int]:
        """(line, column) of the element at index ``path`` (a tuple: ``(i,)`` or
        ``(i, j)`` for nested arrays) of the array assigned by the ``key =`` at
        ``line``:``column``; the deepest element found if the path runs out."""
        text = self.text
        if not line:
            return 0, 0
        i = text.find("=", self.line_start[line - 1] + column - 1)
        if i < 0:
            return line, column
        i = _skip_blank(text, i + 1)
        found = i
        for want in path:
            if i >= len(text) or text[i] != "[":
                break
            i = _skip_blank(text, i + 1, newlines=True)
            k = 0
            while i < len(text) and text[i] != "]" and k < want:
                i = _skip_blank(text, _skip_value(text, i), newlines=True)
                if i < len(text) and text[i] == ",":
                    i = _skip_blank(text, i + 1, newlines=True)
                    k += 1
                else:
                    break
            if k != want or i >= len(text) or text[i] == "]":
                break
            found = i
        ln = text.count("\n", 0, found) + 1
        return ln, found - self.line_start[ln - 1] + 1

    def value_position(self, line: int, offset: int) -> tuple[int, int]:
        """(line, column) of the character ``offset`` characters into the string value
        on ``line`` (after the opening quotes), when the string has no escapes."""
        if not line:
            return 0, 0
        start = self.line_start[line - 1]
        m = re.search(r"=\s*('''|\"\"\"|'|\")", self.text[start:])
        if not m:
            return line, 0
        quote = m.group(1)
        pos = start + m.end()
        if len(quote) == 3 and self.text[pos : pos + 1] == "\n":
            pos += 1  # a newline right after the opening quotes is trimmed
        end = self.text.find(quote, pos)
        raw = self.text[pos : end if end >= 0 else len(self.text)]
        if quote.startswith('"') and "\\" in raw[:offset]:
            return line, 0
        at = pos + min(offset, len(raw))
        ln = self.text.count("\n", 0, at) + 1
        return ln, at - self.line_start[ln - 1] + 1


def _skip_blank(text: str, i: int, newlines: bool = False) -> int:
    """The first position at or after ``i`` that is not blank (nor a comment, nor with
    ``newlines`` a line break)."""
    while i < len(text):
        ch = text[i]
        if ch == "#":
            j = text.find("\n", i)
            i = len(text) if j < 0 else j
        elif ch in " \t\r" or (newlines and ch == "\n"):
            i += 1
        else:
            break
    return i


def _skip_value(text: str, i: int) -> int:
    """The position just after the TOML value (array, inline table, string or bare
    value) that starts at ``i``."""
    if i >= len(text):
        return i
    ch = text[i]
    if ch in "\"'":
        quote = text[i:i + 3] if text[i:i + 3] in ('"""', "'''") else ch
        j = i + len(quote)
        while j < len(text):
            if ch == '"' and text[j] == "\\":
                j += 2
                continue
            if text.startswith(quote, j):
                return j + len(quote)
            j += 1
        return j
    if ch in "[{":
        close = "]" if ch == "[" else "}"
        j = _skip_blank(text, i + 1, newlines=True)
        while j < len(text) and text[j] != close:
            j = _skip_blank(text, _skip_value(text, j), newlines=True)
            if j < len(text) and text[j] in ",=":
                j = _skip_blank(text, j + 1, newlines=True)
        return j + 1
    j = i
    while j < len(text) and text[j] not in ",]}\n#=":
        j += 1
    return j


def _in_multiline_string(text: str, pos: int) -> bool:
    """Whether ``pos`` is inside a ''' or \"\"\" string (counts delimiters before it)."""
    before = text[:pos]
    return (before.count('"""') % 2 == 1) or (before.count("'''") % 2 == 1)


def _toml_value(v) -> str:
    """A TOML literal for a bool, number, string or list of them."""
    import json

    if isinstance(v, bool):
        return "true" if v else "false"
    if isinstance(v, int | np.integer):
        return str(int(v))
    if isinstance(v, float | np.floating):
        if not math.isfinite(v):
            raise ValueError(f"a scene value must be finite, got {v!r}")
        return repr(float(v))
    if isinstance(v, str):
        return json.dumps(v)
    if isinstance(v, list | tuple):
        return "[" + ", ".join(_toml_value(x) for x in v) + "]"
    raise ValueError(f"cannot write {v!r} into a scene file")


def patch_scene_text(text: str, render: dict | None = None,
                     objects: dict[int, dict] | None = None) -> str:
    """The scene file ``text`` with keys of its ``[render]`` table and of its
    ``[[objects]]`` tables (by index) set: a key already there is replaced, a new one
    added below the table's header; everything else (comments, materials) is kept.

    Examples
    --------
    >>> text = "[render]\\nspp = 64 # converged\\n\\n[[objects]]\\nmaterial = 'x()'\\n"
    >>> print(patch_scene_text(text, {"spp": 4}, {0: {"dicing_tolerance": 2.0}}), end="")
    [render]
    spp = 4
    <BLANKLINE>
    [[objects]]
    dicing_tolerance = 2.0
    material = 'x()'
    """
    lines = text.splitlines(keepends=True)
    if lines and not lines[-1].endswith("\n"):
        lines[-1] += "\n"
    loc = _Locator(text)
    edits = [("render", None, render or {})]
    edits += [("objects", i, keys) for i, keys in sorted((objects or {}).items())]
    missing = []
    for name, index, keys in sorted(edits, key=lambda e: -loc.section(e[0], e[1])[0]):
        if not keys:
            continue
        first, last = loc.section(name, index)
        if not first:
            if name != "render":
                raise ValueError(f"the scene has no [[objects]] table number {index}")
            missing.append(keys)
            continue
        pats = [re.compile(r"^\s*" + re.escape(k) + r"\s*=") for k in keys]
        start = sum(len(ln) for ln in lines[:first])
        body = []
        pos = start
        for ln in lines[first:last]:
            if not (any(p.match(ln) for p in pats) and not _in_multiline_string(text, pos)):
                body.append(ln)
            pos += len(ln)
        new = [f"{k} = {_toml_value(v)}\n" for k, v in keys.items()]
        lines[first:last] = new + body
    for keys in missing:
        lines += ["\n[render]\n"] + [f"{k} = {_toml_value(v)}\n" for k, v in keys.items()]
    return "".join(lines)


def load_scene(path, overrides: dict | None = None, profile_dirs=(), mdl_paths=()) -> Scene:
    """Read a TOML scene file.

    Parameters
    ----------
    path : str or Path
    overrides : dict, optional
        ``[render]`` settings to replace (``spp``, ``time``, ``seed``...).
    profile_dirs : paths, optional
        Folders of profiles named in materials (``myprof::myprof``), searched after the
        scene's own folder and before ``$PWC_PROFILE_PATH`` and the bundled library.
    mdl_paths : paths, optional
        Folders of MDL modules (``--mdl-path``), searched after the scene's own folder and
        before ``$PWC_MDL_PATH`` and the workbench's library.

    Returns
    -------
    Scene

    Raises
    ------
    SceneError
        With ``file:line:col`` of the problem.
    """
    path = Path(path)
    try:
        text = path.read_text(encoding="utf-8")
    except OSError as e:
        raise SceneReadError(f"cannot read the scene file: {e.strerror or e}", str(path)) from None
    return parse_scene(text, str(path), overrides=overrides, base_dir=path.parent,
                       profile_dirs=profile_dirs, mdl_paths=mdl_paths)


def parse_scene(
    text: str, path: str = "<scene>", overrides: dict | None = None, base_dir: Path | None = None,
    profile_dirs=(), mdl_paths=(),
) -> Scene:
    """Parse scene text (see the module docstring for the format).

    Files named in the scene (meshes, textures, profiles) are looked up in ``base_dir``
    first (the scene file's folder; default: the current folder); profiles then in
    ``profile_dirs``, ``$PWC_PROFILE_PATH`` and the bundled library.

    Examples
    --------
    >>> parse_scene('[camera]\\nfov = 400\\n', "s.toml")
    Traceback (most recent call last):
    ...
    render.scene.SceneError: s.toml:2:1: camera: fov must be in (0, 180) degrees, got 400
    """
    base_dir = Path(".") if base_dir is None else Path(base_dir)
    try:
        data = tomllib.loads(text)
    except tomllib.TOMLDecodeError as e:
        msg = str(e)
        m = re.search(r"\(at line (\d+), column (\d+)\)", msg)
        line, col = (int(m.group(1)), int(m.group(2))) if m else (0, 0)
        msg = re.sub(r"\s*\(at line \d+, column \d+\)", "", msg)
        raise SceneError(f"TOML syntax error: {msg}", path, line, col) from None
    loc = _Locator(text)
    return _Parser(data, loc, path, base_dir, profile_dirs, mdl_paths).scene(overrides or {})


def _key_re(key: str):
    """``key =`` in a TOML line."""
    return re.compile(rf"\b{key}\s*=")


def _value_re(key: str):
    """``key = `` up to the opening quote of its string value (group 1: the quote)."""
    return re.compile(rf"""\b{key}\s*=\s*('''|\"\"\"|'|")""")


class _Parser:
    def __init__(self, data: dict, loc: _Locator, path: str, base_dir: Path, profile_dirs=(),
                 mdl_paths=()):
        self.data, self.loc, self.path, self.base_dir = data, loc, path, base_dir
        self.profile_dirs = (base_dir, *(Path(d) for d in profile_dirs))
        self.mdl_paths = tuple(Path(d) for d in mdl_paths)

    def error(self, msg: str, section: str, index: int | None = None, key: str | None = None):
        line, col = (
            self.loc.key(section, index, key) if key else (self.loc.section(section, index)[0], 1)
        )
        return SceneError(msg, self.path, line, col if line else 0)

    def _shape_error(self, section: str, msg: str) -> SceneError:
        line = self.loc.section(section, None)[0] or self.loc.key("scene", None, section)[0]
        return SceneError(msg, self.path, line, 1 if line else 0)

    def _check_keys(self, table: dict, allowed: set, section: str, index: int | None = None,
                    key: str | None = None, note: str = ""):
        for k in table:
            if k not in allowed:
                import difflib

                close = difflib.get_close_matches(k, sorted(allowed), n=1)
                hint = f" (did you mean {close[0]!r}?)" if close else ""
                where = section if index is None else f"{section}[{index}]"
                raise self.error(
                    f"{where}: unknown key {k!r}{hint}; allowed: {', '.join(sorted(allowed))}"
                    f"{note}", section, index, key or k)

    def _vec(self, table, key, section, index=None, default=None, size=3, what="numbers"):
        if key not in table:
            if default is None:
                where = section if index is None else f"{section}[{index}]"
                raise self.error(f"{where}: missing {key!r}", section, index)
            return np.asarray(default, dtype=np.float64)
        v = table[key]
        ok = (
            isinstance(v, list)
            and len(v) == size
            and all(
                isinstance(x, (int, float)) and not isinstance(x, bool) and math.isfinite(x)
                for x in v
            )
        )
        if not ok:
            raise self.error(
                f"{section}: {key} must be {size} {what}, got {v!r}", section, index, key
            )
        return np.asarray(v, dtype=np.float64)

    def _num(self, table, key, section, index=None, default=None, positive=False):
        if key not in table:
            return default
        v = table[key]
        if (
            not isinstance(v, (int, float))
            or isinstance(v, bool)
            or not math.isfinite(v)
            or (positive and v <= 0)
        ):
            what = "a number > 0" if positive else "a number"
            raise self.error(f"{section}: {key} must be {what}, got {v!r}", section, index, key)
        return float(v)

    def _color(self, table, key, section, index=None, default=None):
        if key not in table:
            return default
        v = table[key]
        if isinstance(v, (int, float)) and not isinstance(v, bool) and v >= 0:
            return np.full(3, float(v))
        c = self._vec(table, key, section, index, size=3, what="non-negative numbers [r, g, b]")
        if np.any(c < 0):
            raise self.error(
                f"{section}: {key} must be non-negative, got {v!r}", section, index, key
            )
        return c

    # ---------------------------------------------------------------- sections
    def scene(self, overrides: dict) -> Scene:
        top = {"camera", "render", "lights", "objects"}
        self._check_keys(self.data, top, "scene")
        for name in ("camera", "render"):
            if not isinstance(self.data.get(name, {}), dict):
                raise self._shape_error(name, f"[{name}] must be a table: write [{name}] on "
                                              "its own line, then its keys")
        for name in ("lights", "objects"):
            v = self.data.get(name, [])
            if not isinstance(v, list) or not all(isinstance(x, dict) for x in v):
                raise self._shape_error(name, f"{name} must be tables, each under a "
                                              f"[[{name}]] line (two brackets)")
        from render.library.resources import evaluation

        settings = self.settings(self.data.get("render", {}), overrides)
        camera = self.camera(self.data.get("camera", {}), settings)
        with evaluation(settings.curves, settings.curve_tolerance, settings.texture_filter):
            objects = [self.object(o, i) for i, o in enumerate(self.data.get("objects", []))]
        if not objects:
            raise SceneError("the scene has no [[objects]]", self.path, 1, 0)
        lights: list[Light] = []
        for i, spec in enumerate(self.data.get("lights", [])):
            light, obj = self.light(spec, i)
            if light is not None and light.infinite and any(x.infinite for x in lights):
                raise self.error(
                    f"lights[{i}]: a scene has at most one environment", "lights", i, "type"
                )
            if light is not None:
                lights.append(light)
            if obj is not None:
                objects.append(obj)
        return Scene(camera, objects, lights, settings, self.path)

    def settings(self, t: dict, overrides: dict) -> RenderSettings:
        allowed = {
            "resolution",
            "spp",
            "time",
            "max_depth",
            "rr_depth",
            "seed",
            "dicing_rate",
            "dicing_tolerance",
            "spp_per_pass",
            "curves",
            "curve_tolerance",
            "texture_filter",
            "denoise",
            "dice_invisible",
            "light_selection",
            "every_delta_light",
            "sampler",
        }
        self._check_keys(t, allowed, "render")
        s = RenderSettings()
        if "resolution" in t:
            r = t["resolution"]
            if not (
                isinstance(r, list)
                and len(r) == 2
                and all(isinstance(x, int) and x >= 1 for x in r)
            ):
                raise self.error(
                    f"render: resolution must be [width, height] in pixels, got {r!r}",
                    "render",
                    None,
                    "resolution",
                )
            s.width, s.height = r
        for key in (
            "spp",
            "max_depth",
            "rr_depth",
            "seed",
            "spp_per_pass",
            "time",
            "dicing_rate",
            "dicing_tolerance",
            "curves",
            "curve_tolerance",
            "texture_filter",
            "denoise",
            "dice_invisible",
            "light_selection",
            "every_delta_light",
            "sampler",
        ):
            if key in t:
                setattr(s, key, t[key])
        for key, value in overrides.items():
            if value is not None:
                setattr(s, key, value)
        if "spp" in overrides and overrides["spp"] is not None and overrides.get("time") is None:
            s.time = None
        try:
            s.validate()
        except ValueError as e:
            key = str(e).split()[0]
            raise self.error(f"render: {e}", "render", None, key if key in t else None) from None
        return s

    def camera(self, t: dict, s: RenderSettings) -> Camera:
        allowed = {"type", "position", "look_at", "up", "fov", "ortho_height"}
        self._check_keys(t, allowed, "camera")
        kind = t.get("type", "pinhole")
        if kind not in ("pinhole", "orthographic"):
            raise self.error(
                f"camera: type must be 'pinhole' or 'orthographic', got {kind!r}",
                "camera",
                None,
                "type",
            )
        pos = self._vec(t, "position", "camera", default=(0.0, 0.0, 3.0))
        look = self._vec(t, "look_at", "camera", default=(0.0, 0.0, 0.0))
        up = self._vec(t, "up", "camera", default=(0.0, 1.0, 0.0))
        fov = self._num(t, "fov", "camera", default=40.0)
        if not 0.0 < fov < 180.0:
            raise self.error(
                f"camera: fov must be in (0, 180) degrees, got {t['fov']!r}", "camera", None, "fov"
            )
        ortho = None
        if kind == "orthographic":
            ortho = self._num(t, "ortho_height", "camera", default=2.0, positive=True)
        elif "ortho_height" in t:
            raise self.error(
                "camera: ortho_height needs type = 'orthographic'", "camera", None, "ortho_height"
            )
        try:
            return Camera(
                position=tuple(pos),
                look_at=tuple(look),
                up=tuple(up),
                fov_y_deg=fov,
                width=s.width,
                height=s.height,
                ortho_height=ortho,
            )
        except ValueError as e:
            raise self.error(f"camera: {e}", "camera") from None

    def transform(self, t: dict, section: str, i: int) -> np.ndarray:
        tr = self._vec(t, "translate", section, i, default=(0.0, 0.0, 0.0))
        rot = self._vec(t, "rotate", section, i, default=(0.0, 0.0, 0.0), what="degrees")
        sc = t.get("scale", 1.0)
        if isinstance(sc, list):
            sc = self._vec(t, "scale", section, i)
        elif not isinstance(sc, (int, float)) or isinstance(sc, bool):
            raise self.error(
                f"{section}[{i}]: scale must be a number or [x, y, z]", section, i, "scale"
            )
        try:
            return make_transform(tr, rot, sc)
        except ValueError as e:
            raise self.error(f"{section}[{i}]: {e}", section, i, "scale") from None

    def curves(self, spec, i: int):
        """``curves = { type = "polylines" | "bezier" | "fringe", ... }``: hair strands
        (:func:`render.hair.from_table`)."""
        from render.hair import StrandsError, from_table

        if not isinstance(spec, dict):
            raise self.error(f"objects[{i}]: curves must be a table {{ type = \"polylines\", "
                             f"points = [...], radius = ... }}, got {spec!r}", "objects", i,
                             "curves")
        try:
            return from_table(spec)
        except StrandsError as e:
            raise self.strands_error(e, i) from None

    def strands_error(self, e, i: int) -> SceneError:
        """A :class:`render.hair.StrandsError` of ``objects[i]`` located in the file: at
        the strand (and point) it names, else at its key in the curves table."""
        where = self.loc.find_key("objects", i, "curves")
        if not where[0]:
            where = self.loc.section("objects.curves", i)[0], 1
        line, col = self.loc.find_key("objects", i, e.key, where) if e.key else (0, 0)
        if line and e.strand is not None and e.key in ("points", "radii"):
            path = (e.strand,) if e.point is None else (e.strand, e.point)
            line, col = self.loc.array_item(line, col, path)
        if not line:
            line, col = where
        return SceneError(f"objects[{i}]: curves: {e}", self.path, line, col if line else 0)

    def surface(self, spec, i: int):
        from displacement import surfaces
        from displacement.view import make_surface

        if isinstance(spec, str):
            try:
                return make_surface(spec)
            except ValueError as e:
                raise self.error(f"objects[{i}]: {e}", "objects", i, "surface") from None
        if isinstance(spec, dict):
            params = dict(spec)
            kind = params.pop("type", None)
            if not isinstance(kind, str) or kind not in SURFACE_TYPES:
                raise self.error(
                    f"objects[{i}]: surface type must be one of {', '.join(SURFACE_TYPES)}, "
                    f"got {kind!r}",
                    "objects",
                    i,
                    "surface",
                )
            cls = getattr(surfaces, SURFACE_TYPES[kind])
            self._surface_params(cls, kind, params, i)
            try:
                return cls(**params)
            except (TypeError, ValueError) as e:
                raise self.error(
                    f"objects[{i}]: surface {kind!r}: {e}", "objects", i, "surface"
                ) from None
        raise self.error(
            f"objects[{i}]: surface must be a name or a table, got {spec!r}",
            "objects",
            i,
            "surface",
        )

    def _surface_params(self, cls, kind: str, params: dict, i: int) -> None:
        """The keys of ``surface = { type = KIND, ... }`` are KIND's parameters, with values
        of their defaults' kinds (numbers, whole numbers, lists of n numbers)."""
        import inspect

        sig = inspect.signature(cls).parameters
        note = ""
        if "resolution" in params and "resolution" not in sig:
            note = (" (resolution belongs to the object: write resolution = [nu, nv] in its "
                    "[[objects]] table, beside surface)")
        self._check_keys(params, set(sig), "objects", i, "surface", note)
        where = f"objects[{i}]: surface {kind!r}"
        for k, v in params.items():
            default = sig[k].default
            if isinstance(default, tuple):
                whole = all(isinstance(x, int) for x in default)
                ok = isinstance(v, list) and len(v) == len(default) and all(
                    _is_number(x) and (not whole or isinstance(x, int)) for x in v)
                want = (f"a list of {len(default)} {'whole ' if whole else ''}numbers, "
                        f"e.g. {list(default)}")
            elif isinstance(default, int):
                ok, want = isinstance(v, int) and not isinstance(v, bool), "a whole number"
            else:
                ok, want = _is_number(v), "a number"
            if not ok:
                raise self.error(f"{where}: {k} must be {want}, got {v!r}", "objects", i,
                                 "surface")

    def mesh(self, rel: str, i: int):
        import trimesh

        from displacement.surfaces import MeshSurface

        p = Path(rel)
        if not p.is_absolute():
            p = self.base_dir / p
        try:
            m = trimesh.load(p, force="mesh", process=False)
        except Exception as e:  # trimesh raises many kinds
            raise self.error(
                f"objects[{i}]: cannot load mesh {str(p)!r}: {e}", "objects", i, "mesh"
            ) from None
        if len(m.faces) == 0:
            raise self.error(
                f"objects[{i}]: mesh {str(p)!r} has no triangles", "objects", i, "mesh"
            )
        uv = getattr(m.visual, "uv", None)
        if uv is None or len(uv) != len(m.vertices):
            # no texture coordinates in the file: uv = (0, 0) everywhere (frames from the
            # surface's fallback); textures and uv-driven fields are then constant
            m.visual = trimesh.visual.TextureVisuals(uv=np.zeros((len(m.vertices), 2)))
        try:
            return MeshSurface(m)
        except ValueError as e:
            raise self.error(f"objects[{i}]: mesh {str(p)!r}: {e}", "objects", i, "mesh") from None

    def material(self, text, i: int, section: str = "objects"):
        if isinstance(text, dict):
            return self.module_material(text, i, section)
        if not isinstance(text, str):
            raise self.error(
                f"{section}[{i}]: material must be an MDL call (a string), or a table "
                f'{{ module = "file.mdl", call = "name(...)" }}, got {text!r}',
                section,
                i,
                "material",
            )
        line, _ = self.loc.key(section, i, "material")
        try:
            return compile_material(text, base_dir=self.base_dir,
                                    profile_dirs=self.profile_dirs)
        except SceneError:
            raise
        except Exception as e:
            offset = getattr(e, "offset", None)
            if isinstance(offset, int) and offset >= 0 and hasattr(e, "col"):
                ln, c = self.loc.value_position(line, offset)
            else:
                ln, c = line, 0
            msg = getattr(e, "message", None) or str(e)
            fix = getattr(e, "fix", None)
            if fix:
                msg += f" ({fix})"
            raise SceneError(f"{section}[{i}]: material: {msg}", self.path, ln, c) from None

    def module_material(self, t: dict, i: int, section: str):
        """``material = { module = "file.mdl", call = "name(...)" }``: a call into an MDL
        module; errors are located in this file (the call) or in the module."""
        from mdl.diagnostics import MdlError
        from render.library.resources import search_paths
        from render.material import material as Material
        from render.mdlc import material_from_call

        form = ' (a material table is { module = "file.mdl", call = "name(...)" })'
        self._check_keys(t, {"module", "call"}, section, i, "material", note=form)
        for key in ("module", "call"):
            if not isinstance(t.get(key), str) or not t[key].strip():
                raise self.error(f"{section}[{i}]: material.{key} must be a non-empty string"
                                 + form, section, i, "material")
        line, col = self._call_position(section, i)
        try:
            with search_paths(profile_dirs=self.profile_dirs):
                value, info = material_from_call(
                    t["call"], t["module"], base_dir=self.base_dir, mdl_paths=self.mdl_paths,
                    source_name=self.path, line=line or 1, col=col or 1)
        except MdlError as e:
            d = e.first
            msg = d.message + (f" ({d.fix})" if d.fix else "")
            if d.loc.file == self.path:
                raise SceneError(f"{section}[{i}]: material: {msg}", self.path, d.loc.line,
                                 d.loc.col) from None
            raise SceneError(f"{section}[{i}]: material: in {d.loc}: {msg}", self.path,
                             line, col) from None
        except ValueError as e:
            raise self.error(f"{section}[{i}]: material: {e}", section, i, "material") from None
        if not isinstance(value, Material):
            raise SceneError(f"{section}[{i}]: material: the call gives {_a(info.type)}, not a "
                             "material", self.path, line, col)
        return value

    def _call_position(self, section: str, i: int, key: str = "call") -> tuple[int, int]:
        """(line, column) of the first character of the ``call`` (or ``key``) string's
        value."""
        key_re, value_re = _key_re(key), _value_re(key)
        line, _ = self.loc.key(section, i, key)
        if key == "call" and (not line or not key_re.search(self.loc.lines[line - 1])):
            line, _ = self.loc.key(section, i, "material")
        if not line:
            return 0, 0
        start = self.loc.line_start[line - 1]
        m = value_re.search(self.loc.text, start)
        if not m:
            return line, 0
        pos = m.end()
        if len(m.group(1)) == 3 and self.loc.text[pos:pos + 1] == "\n":
            pos += 1
        ln = self.loc.text.count("\n", 0, pos) + 1
        return ln, pos - self.loc.line_start[ln - 1] + 1

    def object(self, t: dict, i: int) -> SceneObject:
        if not isinstance(t, dict):
            raise self.error(f"objects[{i}] must be a table", "objects", i)
        allowed = {
            "name",
            "surface",
            "mesh",
            "curves",
            "material",
            "translate",
            "rotate",
            "scale",
            "resolution",
            "dicing_rate",
            "dicing_tolerance",
            "displacement_method",
            "normal_map_size",
            "normal_map_bits",
        }
        self._check_keys(t, allowed, "objects", i)
        if sum(k in t for k in ("surface", "mesh", "curves")) != 1:
            raise self.error(
                f"objects[{i}]: give exactly one of surface = NAME, mesh = PATH or curves = "
                "{ type = ... } (hair strands)", "objects", i
            )
        if "curves" in t:
            return self.hair_object(t, i)
        surface = self.surface(t["surface"], i) if "surface" in t else self.mesh(t["mesh"], i)
        if "material" not in t:
            raise self.error(
                f"objects[{i}]: missing material (an MDL call expression)", "objects", i
            )
        material = self.material(t["material"], i)
        res = t.get("resolution")
        if res is not None and not (
            isinstance(res, list)
            and len(res) == 2
            and all(isinstance(x, int) and x >= 1 for x in res)
        ):
            raise self.error(
                f"objects[{i}]: resolution must be [nu, nv] cells", "objects", i, "resolution"
            )
        name = t.get("name", f"object{i}")
        dicing = {k: self._num(t, k, "objects", i, positive=True)
                  for k in ("dicing_rate", "dicing_tolerance")}
        method = t.get("displacement_method", "displacement")
        written = material.geometry.displacement
        try:
            from render.displacement_method import apply

            material = apply(material, surface, method, t.get("normal_map_size", 512),
                             t.get("normal_map_bits", 16))
        except ValueError as e:
            key = next((k for k in ("normal_map_bits", "normal_map_size") if k in str(e)),
                       "displacement_method")
            raise self.error(f"objects[{i}]: {e}", "objects", i, key) from None
        return SceneObject(
            surface,
            material,
            self.transform(t, "objects", i),
            str(name),
            tuple(res) if res else None,
            t["material"] if isinstance(t["material"], str) else
            f"{t['material'].get('module')}: {t['material'].get('call')}",
            displacement_method=method,
            original_displacement=written if method != "displacement" else None,
            **dicing,
        )

    def hair_object(self, t: dict, i: int) -> SceneObject:
        """An object of hair strands (``curves = {...}``): its strands, checked in world
        space, and a material whose ``hair`` field shades them (MDL: nothing else of the
        material applies to hair)."""
        from render.hair import StrandsError, check_hair_bsdf

        for key in ("resolution", "dicing_rate", "dicing_tolerance", "displacement_method",
                    "normal_map_size", "normal_map_bits"):
            if key in t:
                raise self.error(f"objects[{i}]: {key} applies to surfaces, not to hair "
                                 "strands (curves); remove it", "objects", i, key)
        surface = self.curves(t["curves"], i)
        if "material" not in t:
            raise self.error(
                f"objects[{i}]: missing material, e.g. \"material(hair: "
                "df::chiang_hair_bsdf(roughness_R: float2(0.2, 0.3)))\"", "objects", i)
        material = self.material(t["material"], i)
        try:
            check_hair_bsdf(material.hair)
        except ValueError as e:
            raise self.error(f"objects[{i}]: material: {e}", "objects", i, "material") from None
        transform = self.transform(t, "objects", i)
        try:
            surface.world(transform)
        except StrandsError as e:
            raise self.strands_error(e, i) from None
        return SceneObject(surface, material, transform, str(t.get("name", f"object{i}")), None,
                           t["material"])

    def light(self, t: dict, i: int):
        kinds = {"point", "spot", "directional", "environment", "sun_and_sky", "quad", "sphere"}
        kind = t.get("type")
        if not isinstance(kind, str) or kind not in kinds:
            raise self.error(
                f"lights[{i}]: type must be one of {', '.join(sorted(kinds))}, got {kind!r}",
                "lights",
                i,
                "type",
            )
        sec = "lights"
        common = {"type", "name"}
        try:
            if kind == "point":
                self._check_keys(t, common | {"position", "intensity"}, sec, i)
                return PointLight(
                    self._vec(t, "position", sec, i),
                    self._color(t, "intensity", sec, i, np.ones(3)),
                ), None
            if kind == "spot":
                self._check_keys(
                    t,
                    common
                    | {
                        "position",
                        "direction",
                        "look_at",
                        "intensity",
                        "cutoff_angle",
                        "beam_width",
                    },
                    sec,
                    i,
                )
                pos = self._vec(t, "position", sec, i)
                if "look_at" in t:
                    direction = self._vec(t, "look_at", sec, i) - pos
                else:
                    direction = self._vec(t, "direction", sec, i, default=(0.0, -1.0, 0.0))
                return SpotLight(
                    pos,
                    direction,
                    self._color(t, "intensity", sec, i, np.ones(3)),
                    self._num(t, "cutoff_angle", sec, i, 20.0),
                    self._num(t, "beam_width", sec, i, None),
                ), None
            if kind == "directional":
                self._check_keys(t, common | {"direction", "irradiance"}, sec, i)
                return DirectionalLight(
                    self._vec(t, "direction", sec, i),
                    self._color(t, "irradiance", sec, i, np.ones(3)),
                ), None
            if kind == "environment":
                self._check_keys(t, common | {"radiance", "file", "scale", "rotation", "function",
                                              "module", "resolution"}, sec, i)
                given = [k for k in ("radiance", "file", "function") if k in t]
                if len(given) > 1:
                    raise self.error(f"lights[{i}]: give one of radiance, file or function, "
                                     f"not {' and '.join(given)}", sec, i, given[1])
                if "function" in t:
                    return self.environment_function(t, i), None
                if "file" in t:
                    from displacement.textures import read_texture

                    p = Path(t["file"])
                    p = p if p.is_absolute() else self.base_dir / p
                    try:
                        img = read_texture(p)
                    except Exception as e:
                        raise self.error(
                            f"lights[{i}]: cannot read environment {str(p)!r}: {e}", sec, i, "file"
                        ) from None
                    img = getattr(img, "data", img)
                    return LatLongEnvironment(
                        np.asarray(img),
                        self._num(t, "scale", sec, i, 1.0),
                        self._num(t, "rotation", sec, i, 0.0),
                    ), None
                return ConstantEnvironment(self._color(t, "radiance", sec, i, np.ones(3))), None
            if kind == "sun_and_sky":
                return self.sun_and_sky(t, i), None
            # emissive geometry
            self._check_keys(
                t,
                common | {"center", "normal", "size", "up", "radius", "radiance", "intensity"},
                sec,
                i,
            )
            if "radiance" in t and "intensity" in t:
                raise self.error(
                    f"lights[{i}]: give radiance or intensity, not both", sec, i, "intensity"
                )
            if "intensity" in t:
                intensity = self._color(t, "intensity", sec, i)
            else:
                intensity = np.pi * self._color(t, "radiance", sec, i, np.ones(3))
            center = self._vec(t, "center", sec, i)
            name = t.get("name", f"{kind}_light{i}")
            if kind == "quad":
                from displacement.surfaces import Plane

                nrm = self._vec(t, "normal", sec, i, default=(0.0, -1.0, 0.0))
                size = t.get("size", 1.0)
                size = (size, size) if isinstance(size, (int, float)) else size
                size = self._vec({"size": list(size)}, "size", sec, i, size=2)
                au, av, nrm = _plane_axes(nrm, self._vec(t, "up", sec, i, default=(0.0, 0.0, -1.0)))
                origin = center - 0.5 * (size[0] * au + size[1] * av)
                surface = Plane(
                    size=tuple(size), origin=tuple(origin), axis_u=tuple(au), axis_v=tuple(av)
                )
            else:
                from displacement.surfaces import UVSphere

                surface = UVSphere(self._num(t, "radius", sec, i, 0.25, positive=True))
            transform = make_transform(translate=center) if kind == "sphere" else np.eye(4)
            obj = SceneObject(
                surface,
                emissive_material(intensity),
                transform,
                str(name),
                (48, 24) if kind == "sphere" else None,
                f"emissive(intensity: {intensity.tolist()})",
            )
            if not _triangle_area(obj) > 0.0:
                key = "size" if kind == "quad" else "radius"
                raise self.error(
                    f"lights[{i}]: this {kind} light has no area in double precision: its "
                    f"{key} is so small that the area underflows to 0 or the corners round "
                    f"to the same points (below ~1e-15 of its distance from the origin); "
                    f"make it larger, or use a point light", sec, i, key)
            return None, obj
        except SceneError:
            raise
        except ValueError as e:
            raise self.error(f"lights[{i}]: {e}", sec, i) from None


    def environment_function(self, t: dict, i: int):
        """``type = "environment", function = "base::sun_and_sky(...)"``: an MDL colour
        function of ``state::direction()``
        (:func:`render.mdlc.environment.environment_from_call`)."""
        from mdl.diagnostics import MdlError
        from render.mdlc.environment import environment_from_call

        sec = "lights"
        for key in ("function", "module"):
            if key in t and (not isinstance(t[key], str) or not t[key].strip()):
                raise self.error(f"lights[{i}]: {key} must be a non-empty string", sec, i, key)
        resolution = t.get("resolution", [256, 512])
        if not (isinstance(resolution, list) and len(resolution) == 2 and all(
                isinstance(x, int) and not isinstance(x, bool) and 2 <= x <= 8192
                for x in resolution)):
            raise self.error(f"lights[{i}]: resolution must be [rows, columns], integers in "
                             f"[2, 8192], got {resolution!r}", sec, i, "resolution")
        line, col = self._call_position(sec, i, "function")
        try:
            light = environment_from_call(
                t["function"], t.get("module"), base_dir=self.base_dir,
                mdl_paths=self.mdl_paths, resolution=resolution, source_name=self.path,
                line=line or 1, col=col or 1)
        except MdlError as e:
            d = e.first
            msg = d.message + (f" ({d.fix})" if d.fix else "")
            if d.loc.file == self.path:
                raise SceneError(f"lights[{i}]: function: {msg}", self.path, d.loc.line,
                                 d.loc.col) from None
            raise SceneError(f"lights[{i}]: function: in {d.loc}: {msg}", self.path, line,
                             col) from None
        except ValueError as e:
            raise self.error(f"lights[{i}]: function: {e}", sec, i, "function") from None
        return light

    def sun_and_sky(self, t: dict, i: int):
        from render.sky import SunAndSky, sun_direction_from_angles

        sec = "lights"
        numbers = ("turbidity", "intensity", "sun_radius", "sun_scale", "sky_scale")
        self._check_keys(
            t,
            {"type", "name", "sun_direction", "elevation", "azimuth", "ground_albedo", *numbers},
            sec,
            i,
        )
        if "sun_direction" in t and ("elevation" in t or "azimuth" in t):
            raise self.error(
                f"lights[{i}]: give sun_direction or elevation/azimuth, not both",
                sec,
                i,
                "sun_direction",
            )
        if "sun_direction" in t:
            direction = self._vec(t, "sun_direction", sec, i)
            if not np.any(direction):
                raise self.error(
                    f"lights[{i}]: sun_direction must not be [0, 0, 0]", sec, i, "sun_direction"
                )
        else:
            elevation = self._num(t, "elevation", sec, i, 45.0)
            if not -90.0 <= elevation <= 90.0:
                raise self.error(
                    f"lights[{i}]: elevation must be in [-90, 90] degrees, got {elevation!r}",
                    sec,
                    i,
                    "elevation",
                )
            direction = sun_direction_from_angles(elevation, self._num(t, "azimuth", sec, i, 0.0))
        kwargs = {k: self._num(t, k, sec, i) for k in numbers if k in t}
        if "ground_albedo" in t:
            kwargs["ground_albedo"] = self._color(t, "ground_albedo", sec, i)
        try:
            return SunAndSky(direction, **kwargs)
        except ValueError as e:
            key = next((k for k in (*numbers, "ground_albedo") if k in str(e)), None)
            raise self.error(f"lights[{i}]: {e}", sec, i, key if key in t else None) from None


def _a(t) -> str:
    s = str(t)
    return ("an " if s[:1] in "aeiou" else "a ") + s


def _is_number(v) -> bool:
    """A finite TOML number (not a boolean)."""
    return isinstance(v, (int, float)) and not isinstance(v, bool) and math.isfinite(v)


def _plane_axes(normal: np.ndarray, up: np.ndarray):
    """Orthonormal (axis_u, axis_v, normal) with axis_u x axis_v = normal."""
    n = normal / (np.linalg.norm(normal) or 1.0)
    if np.linalg.norm(normal) == 0:
        raise ValueError("quad light normal must not be zero")
    au = np.cross(up, n)
    if np.linalg.norm(au) < 1e-9:
        au = np.cross([1.0, 0.0, 0.0] if abs(n[0]) < 0.9 else [0.0, 1.0, 0.0], n)
    au /= np.linalg.norm(au)
    av = np.cross(n, au)
    return au, av, n


# ---------------------------------------------------------------------------- materials
def compile_material(text: str, base_dir=None, profile_dirs=None):
    """An MDL call expression (a Handbook material with arguments) as a material.

    Parsed by :func:`render.expr.parse_material` against :data:`render.materials.MATERIALS`;
    textures are looked up relative to ``base_dir`` (the scene file's folder) first, and
    profiles in ``profile_dirs`` first (:mod:`render.library.resources`).
    """
    from render import expr

    return expr.parse_material(text, base_dir=base_dir, profile_dirs=profile_dirs)


def emissive_material(intensity) -> Any:
    """A black, diffusely emitting material: MDL's
    ``material(surface: material_surface(emission: material_emission(df::diffuse_edf(),
    intensity)))``, the area light of a ``quad`` or ``sphere`` light."""
    from render import material as m

    return m.material(
        surface=m.material_surface(
            scattering=None,
            emission=m.material_emission(
                emission=m.df.diffuse_edf(), intensity=tuple(np.asarray(intensity, float))
            ),
        )
    )
