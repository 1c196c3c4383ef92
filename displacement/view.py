"""Interactive inspection of a displaced surface with PyVista: grid texture, profile, glyphs.

A profile (a :class:`pwc.Curve`) displaces a base surface (Listing 15.8 along u or v,
Listing 15.14 as a solid of revolution, Listing 15.20 swept along a second curve); the
surface is diced for the camera that looks at it (:func:`displacement.dice.dice`) and
shown with the Handbook's ``grid`` material (Listings 14.3-14.6) so that the stretching
of texture space by the displacement is visible, as in Figures 14.6-14.33 and 15.21.

Layers:

* :func:`build_scene` is pure data: a dict of PyVista objects (the diced, textured
  surface; the profile polyline; displacement-vector and normal glyphs; the grid
  texture).  It needs no window and is what the tests inspect.
* :func:`build_plotter` puts a scene in a :class:`pyvista.Plotter` with the camera set
  exactly from a :class:`~displacement.camera.Camera` (the one the mesh was diced for),
  optionally with slider widgets for ``repeat`` and the dicing rate that re-dice the
  surface for the current view, and a check box for the normals.
* :func:`screenshot` renders off-screen to an image file; :func:`show` opens a window.

Grid texture.  ``grid_color`` draws a line where a texture coordinate is within
``thickness`` (default ``0.05 / cell_count``) of a multiple of ``1 / cell_count``.  With
the default thickness every grid cell looks the same, so the texture is one cell
(:func:`grid_tile`) repeated, and the mesh's texture coordinates are ``uv * cell_count``:
lines are exact at any count.  ``cell_count`` is ``grid_count`` times the curve's
``length`` (the compiler's ``NAME_length``) in the curve's direction (Listing 15.9's
``float2(grid_count, grid_count * ornament_1_length)``; Listing 14.30's
``scale_component``), so the cells of the displaced surface stay square.

PyVista is imported inside the functions that need it: ``import displacement.view``
works without it.  Off-screen rendering needs no display: with no ``DISPLAY`` set,
:func:`build_plotter` selects VTK's EGL render window (Mesa's ``libEGL``), which the VTK
wheel falls back to anyway, minus its warning about the missing X server.
"""

from __future__ import annotations

import math
import os
import sys
import time
from pathlib import Path

import numpy as np

from displacement.camera import Camera

__all__ = [
    "SURFACES",
    "ALONG",
    "make_surface",
    "make_field",
    "cell_counts",
    "near_grid_value",
    "in_grid_line",
    "grid_color",
    "grid_tile",
    "default_camera",
    "dice_surface",
    "build_scene",
    "build_plotter",
    "apply_camera",
    "camera_from_plotter",
    "screenshot",
    "show",
    "Viewer",
]

#: Names of the base surfaces :func:`make_surface` builds.
SURFACES = ("square", "plane", "sphere", "cylinder", "torus", "cube")
#: How the profile displaces the surface: Listing 15.8 along u or v, Listing 15.14
#: ("radial", a solid of revolution) or Listing 15.20 ("double", swept along a curve).
ALONG = ("u", "v", "radial", "double")

#: The grid material's colours (Listing 14.6: line_color = color(0.0), bg_color = 0.7).
LINE_COLOR = 0.0
BG_COLOR = 0.7
#: Texels a side of the default grid tile: the default line (5% of a cell on each side
#: of the cell's edge) is then exactly 4 texels wide, so its edges fall on texel edges.
TILE_SIZE = 80

_CURVE_COLOR = "crimson"
_VECTOR_COLOR = "royalblue"
_NORMAL_COLOR = "darkorange"


# --------------------------------------------------------------------------- inputs
def make_surface(name: str):
    """The base surface called ``name`` (one of :data:`SURFACES`).

    ``square``: the Handbook's unit square (u along +x, v along +y, normal +z).
    ``plane``: a unit square lying on the ground (y up): centred on the origin, u along
    +x, v along -z, normal +y.  ``sphere``: radius 0.5; ``cylinder``: radius 0.5,
    height 1 (open); ``torus``: radii 0.5 and 0.2; ``cube``: edge 1, six charts.

    Parameters
    ----------
    name : str

    Returns
    -------
    surface
        A :mod:`displacement.surfaces` surface.

    Examples
    --------
    >>> type(make_surface("square")).__name__
    'UnitSquare'
    >>> make_surface("cone")
    Traceback (most recent call last):
    ...
    ValueError: unknown surface 'cone': choose one of square, plane, sphere, cylinder, torus, cube
    """
    from displacement import surfaces

    builders = {
        "square": surfaces.UnitSquare,
        "plane": lambda: surfaces.Plane(origin=(-0.5, 0.0, 0.5), axis_u=(1.0, 0.0, 0.0),
                                        axis_v=(0.0, 0.0, -1.0)),
        "sphere": lambda: surfaces.UVSphere(0.5),
        "cylinder": lambda: surfaces.Cylinder(0.5, 1.0),
        "torus": lambda: surfaces.Torus(0.5, 0.2),
        "cube": lambda: surfaces.Cube(1.0),
    }
    if name not in builders:
        raise ValueError(f"unknown surface {name!r}: choose one of {', '.join(SURFACES)}")
    return builders[name]()


def _check_along(along: str, sweep) -> None:
    if along not in ALONG:
        raise ValueError(f"unknown displacement {along!r}: choose one of {', '.join(ALONG)}")
    if along == "double" and sweep is None:
        raise ValueError("along='double' needs a sweep curve (Listing 15.20's second pw-curve)")
    if along != "double" and sweep is not None:
        raise ValueError(f"a sweep curve is only used with along='double', not {along!r}")


def make_field(curve, along: str = "v", repeat: float | None = None, sweep=None,
               radius_offset: float = 0.0):
    """The displacement field of a profile.

    Parameters
    ----------
    curve : pwc.Curve
        The profile (x = depth, y = run).
    along : {"u", "v", "radial", "double"}
        "u"/"v": :func:`~displacement.pwc_fields.displace_with_pwc` (Listing 15.8);
        "radial": :func:`~displacement.pwc_fields.pwc_angular_displace` along v
        (Listing 15.14); "double": :func:`~displacement.pwc_fields.double_pwc`
        (Listing 15.20) with ``sweep`` as the sweep curve.
    repeat : float > 0 or None
        Copies of the profile across [0, 1] (along u or v only).
    sweep : pwc.Curve or None
        The sweep curve (``along="double"`` only).
    radius_offset : float
        Added to the distance from the axis ("radial": Listing 15.13's ``radius``;
        "double": Listing 15.20's ``radius_offset``).

    Returns
    -------
    displacement.fields.Field
    """
    from displacement import pwc_fields

    _check_along(along, sweep)
    if repeat is not None and along not in ("u", "v"):
        raise ValueError(f"repeat applies to along='u' or 'v' (Listing 15.8), not {along!r}")
    if radius_offset != 0.0 and along in ("u", "v"):
        raise ValueError("radius_offset applies to along='radial' or 'double', not "
                         f"{along!r}")
    if along in ("u", "v"):
        return pwc_fields.displace_with_pwc(curve, f"along_{along}", repeat)
    if along == "radial":
        return pwc_fields.pwc_angular_displace(curve, "along_v", radius_offset)
    return pwc_fields.double_pwc(curve, sweep, radius_offset)


def cell_counts(curve, along: str = "v", grid_count=4.0, normalize: bool = True) -> np.ndarray:
    """Grid cells per uv unit: ``grid_count`` times ``curve.length`` in the curve's
    direction (Listing 15.9), so the displaced surface's cells stay square.

    The curve runs along u for ``along="u"``, along v otherwise (Listings 15.14 and
    15.20 put the profile along v).  A curve's ``length`` is the total arc length of the
    normalized curve, the texture stretch of one uv unit displaced by it (also with
    ``repeat``: r copies each 1/r as long).

    Parameters
    ----------
    curve : pwc.Curve
    along : {"u", "v", "radial", "double"}
    grid_count : float or (2,) float
        Cells per uv unit before compensation, > 0.
    normalize : bool
        False: no compensation (Listing 15.16 draws the Corinthian capital with a plain
        ``grid(float2(50.0))``).

    Returns
    -------
    (2,) float64

    Examples
    --------
    >>> import pwc
    >>> c = pwc.compile_text("0 0\\n1 0\\n1 1")             # length 2
    >>> cell_counts(c, "v", 4).tolist(), cell_counts(c, "u", 4).tolist()
    ([4.0, 8.0], [8.0, 4.0])
    >>> cell_counts(c, "radial", (3, 5), normalize=False).tolist()
    [3.0, 5.0]
    """
    if along not in ALONG:
        raise ValueError(f"unknown displacement {along!r}: choose one of {', '.join(ALONG)}")
    counts = np.broadcast_to(np.asarray(grid_count, dtype=np.float64), (2,)).copy()
    if not (np.all(np.isfinite(counts)) and np.all(counts > 0.0)):
        raise ValueError(f"grid_count must be finite and > 0, got {counts.tolist()}")
    if normalize:
        counts[0 if along == "u" else 1] *= float(curve.length)
    return counts


# ------------------------------------------------------------------ grid material
def near_grid_value(f, cell_count, thickness=0.0, edge: float = 1.0) -> np.ndarray:
    """Listing 14.3: whether ``f`` lies within ``thickness`` of a multiple of
    ``1 / cell_count``.

    ``thick = thickness`` or, for 0, ``0.05 / cell_count``; times ``edge``; the nearest
    grid value is ``floor((f + thick) cell_count) / cell_count`` and ``f`` is on the line
    when ``nearest - thick <= f <= nearest + thick``.

    Parameters
    ----------
    f : (...) float64
    cell_count : float > 0
    thickness : float >= 0
    edge : float

    Returns
    -------
    (...) bool

    Examples
    --------
    >>> near_grid_value(np.array([0.0, 0.01, 0.0125, 0.02, 0.24, 0.5, 1.0]), 4.0).tolist()
    [True, True, True, False, True, True, True]
    """
    f = np.asarray(f, dtype=np.float64)
    cell_count = float(cell_count)
    if not (math.isfinite(cell_count) and cell_count > 0.0):
        raise ValueError(f"cell_count must be finite and > 0, got {cell_count}")
    thick = (0.05 / cell_count if thickness == 0.0 else float(thickness)) * edge
    nearest = np.floor((f + thick) * cell_count) / cell_count
    return (f >= nearest - thick) & (f <= nearest + thick)


def in_grid_line(uv, cell_count=(4.0, 4.0), thickness=(0.0, 0.0), edge: float = 1.0
                 ) -> np.ndarray:
    """Listing 14.4: on a grid line in u or in v.

    Parameters
    ----------
    uv : (n, 2) float64
    cell_count, thickness : (2,) float

    Returns
    -------
    (n,) bool
    """
    uv = np.asarray(uv, dtype=np.float64).reshape(-1, 2)
    cell_count = np.broadcast_to(np.asarray(cell_count, dtype=np.float64), (2,))
    thickness = np.broadcast_to(np.asarray(thickness, dtype=np.float64), (2,))
    return (near_grid_value(uv[:, 0], cell_count[0], thickness[0], edge)
            | near_grid_value(uv[:, 1], cell_count[1], thickness[1], edge))


def grid_color(uv, cell_count=(4.0, 4.0), line_color=LINE_COLOR, bg_color=BG_COLOR,
               thickness=(0.0, 0.0)) -> np.ndarray:
    """Listing 14.5 with the ``grid`` material's defaults (Listing 14.6): ``line_color``
    on grid lines, ``bg_color`` elsewhere.

    Parameters
    ----------
    uv : (n, 2) float64
    cell_count, thickness : (2,) float
    line_color, bg_color : float or (3,) float
        Linear RGB in [0, 1].

    Returns
    -------
    (n, 3) float64

    Examples
    --------
    >>> grid_color(np.array([[0.0, 0.3], [0.3, 0.3]])).tolist()
    [[0.0, 0.0, 0.0], [0.7, 0.7, 0.7]]
    """
    line = np.broadcast_to(np.asarray(line_color, dtype=np.float64), (3,))
    bg = np.broadcast_to(np.asarray(bg_color, dtype=np.float64), (3,))
    return np.where(in_grid_line(uv, cell_count, thickness)[:, None], line, bg)


def grid_tile(cell_count=(4.0, 4.0), thickness=(0.0, 0.0), size: int = TILE_SIZE,
              line_color=LINE_COLOR, bg_color=BG_COLOR) -> np.ndarray:
    """One grid cell as an RGB image, to be repeated over texture coordinates
    ``uv * cell_count``.

    Texel (row j, column i) shows :func:`grid_color` at the texel centre of the first
    cell, ``uv = ((i + 1/2) / size / cell_count[0], (j + 1/2) / size / cell_count[1])``;
    rows run along v.  With the default thickness the line covers 5% of the cell on each
    side of every cell edge (4 texels of 80).

    Parameters
    ----------
    cell_count, thickness : (2,) float
        As for :func:`grid_color`; the thickness must leave part of the cell free
        (``thickness * cell_count < 0.5``).
    size : int >= 2
        Texels a side.

    Returns
    -------
    (size, size, 3) uint8
        sRGB-encoded (the display's) values of the linear grid colours.

    Examples
    --------
    >>> t = grid_tile(size=20)
    >>> t.shape, t[0, 0].tolist(), t[10, 10].tolist(), int((t[10, :, 0] == 0).sum())
    ((20, 20, 3), [0, 0, 0], [218, 218, 218], 2)
    """
    if int(size) != size or size < 2:
        raise ValueError(f"grid_tile size must be a whole number >= 2, got {size}")
    size = int(size)
    cell_count = np.broadcast_to(np.asarray(cell_count, dtype=np.float64), (2,))
    thickness = np.broadcast_to(np.asarray(thickness, dtype=np.float64), (2,))
    if np.any(thickness < 0.0) or np.any(thickness * cell_count >= 0.5):
        raise ValueError(f"grid thickness {thickness.tolist()} must be >= 0 and less than half "
                         f"a cell (1 / (2 cell_count) = {(0.5 / cell_count).tolist()})")
    centre = (np.arange(size) + 0.5) / size
    u, v = np.meshgrid(centre / cell_count[0], centre / cell_count[1], indexing="xy")
    rgb = grid_color(np.stack([u.ravel(), v.ravel()], 1), cell_count, line_color, bg_color,
                     thickness)
    from displacement.textures import linear_to_srgb

    encoded = np.clip(linear_to_srgb(rgb), 0.0, 1.0)
    return np.round(encoded * 255.0).astype(np.uint8).reshape(size, size, 3)


# ---------------------------------------------------------------------- geometry
def _charts(surface) -> list:
    """The parametric pieces of a surface: a cube's six planes, or the surface itself."""
    charts = getattr(surface, "charts", None)
    return list(charts) if charts is not None else [surface]


def _uv_grid(n_u: int, n_v: int, centres: bool) -> np.ndarray:
    """(n_u n_v, 2) texture coordinates: cell centres, or the grid's corners."""
    if centres:
        u, v = (np.arange(n_u) + 0.5) / n_u, (np.arange(n_v) + 0.5) / n_v
    else:
        u, v = np.linspace(0.0, 1.0, n_u), np.linspace(0.0, 1.0, n_v)
    uu, vv = np.meshgrid(u, v, indexing="xy")
    return np.stack([uu.ravel(), vv.ravel()], axis=1)


def _displaced_samples(surface, field, uv: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Base and displaced positions at ``uv`` on every chart, stacked: (k, 3) each."""
    base, moved = [], []
    for chart in _charts(surface):
        state = chart.state_at_uv(uv)
        d = field(state)
        base.append(state.position)
        moved.append(state.position + d)
    return np.concatenate(base), np.concatenate(moved)


def default_camera(points: np.ndarray, width: int = 1024, height: int = 768,
                   direction=(0.6, 0.7, 1.0), fov_y_deg: float = 30.0,
                   fill: float = 0.85) -> Camera:
    """A pinhole camera that frames ``points``: their image is centred and spans
    ``fill`` of the image's width or height.

    Starting from the bounding sphere, the view axis is moved to the centre of the
    points' image and the distance scaled to the wanted fill, a few times over.

    Parameters
    ----------
    points : (n, 3) float64
    width, height : int
        Image size in pixels.
    direction : (3,) float
        From the points towards the eye (default: front-right, above; y is up).
    fov_y_deg : float
    fill : float in (0, 1]

    Returns
    -------
    Camera

    Examples
    --------
    >>> p = np.array([[0.0, 0, 0], [1.0, 1, 0]])
    >>> cam = default_camera(p, 100, 100)
    >>> xy, _ = cam.project(p)
    >>> bool(np.all(cam.in_frustum(p))), round(float(np.ptp(xy, axis=0).max()), 1)
    (True, 85.0)
    """
    p = np.asarray(points, dtype=np.float64).reshape(-1, 3)
    p = p[np.all(np.isfinite(p), axis=1)]
    if len(p) == 0:
        raise ValueError("default_camera needs at least one finite point")
    if not 0.0 < fill <= 1.0:
        raise ValueError(f"fill must be in (0, 1], got {fill}")
    lo, hi = p.min(axis=0), p.max(axis=0)
    centre = 0.5 * (lo + hi)
    radius = max(0.5 * float(np.linalg.norm(hi - lo)), 1e-3)
    d = np.asarray(direction, dtype=np.float64)
    d = d / np.linalg.norm(d)
    right = np.cross(-d, [0.0, 1.0, 0.0])
    right /= np.linalg.norm(right)
    up = np.cross(right, -d)
    half_y = math.radians(fov_y_deg) / 2.0
    half_x = math.atan(math.tan(half_y) * width / height)
    distance = 1.05 * radius / math.sin(min(half_x, half_y))

    def camera(target, dist):
        return Camera(position=tuple(float(x) for x in target + dist * d),
                      look_at=tuple(float(x) for x in target),
                      up=(0.0, 1.0, 0.0), fov_y_deg=fov_y_deg, width=int(width),
                      height=int(height))

    cam = camera(centre, distance)
    for _ in range(6):
        xy, _ = cam.project(p)
        x0, x1 = xy.min(axis=0), xy.max(axis=0)
        offset = 0.5 * (x0 + x1) - (0.5 * width, 0.5 * height)
        pixel = float(cam.pixel_size_at(centre[None, :])[0])
        centre = centre + pixel * (offset[0] * right - offset[1] * up)
        used = max((x1[0] - x0[0]) / width, (x1[1] - x0[1]) / height)
        distance *= max(used / fill, 1e-3)
        distance = max(distance, 1.01 * radius)   # stay outside the points
        cam = camera(centre, distance)
    return cam


def dice_surface(surface, field, camera: Camera, dicing_rate: float = 1.0,
                 tolerance: float = 0.5):
    """Dice every chart of ``surface`` for ``camera`` and merge the pieces.

    A cube is diced as its six planes (each a parametric chart with the cube's frame),
    everything else in one piece by :func:`displacement.dice.dice`.

    Returns
    -------
    vertices : (n, 3) float64
    faces : (m, 3) int64
    uv : (n, 2) float64
    normals : (n, 3) float64
    stats : dict
        ``triangles``, ``vertices``, ``time_s`` (the dicing time, all charts).
    """
    from displacement.dice import dice

    start = time.perf_counter()
    pieces = [dice(chart, field, camera, dicing_rate=dicing_rate, tolerance=tolerance)
              for chart in _charts(surface)]
    offsets = np.cumsum([0] + [len(m.vertices) for m in pieces[:-1]])
    vertices = np.concatenate([m.vertices for m in pieces])
    faces = np.concatenate([m.faces + o for m, o in zip(pieces, offsets, strict=True)])
    uv = np.concatenate([m.uv for m in pieces])
    normals = np.concatenate([m.normals for m in pieces])
    stats = {"triangles": len(faces), "vertices": len(vertices),
             "time_s": time.perf_counter() - start}
    for key in ("max_error_px", "mean_error_px"):
        values = [m.stats[key] for m in pieces if key in m.stats]
        if values:
            stats[key] = float(max(values) if key.startswith("max") else np.mean(values))
    return vertices, faces, uv, normals, stats


def _curve_placement(curve, along: str, surface, moved: np.ndarray, gap: float,
                     tolerance: float) -> np.ndarray:
    """The profile as a 3D polyline beside the displaced surface, (m, 3).

    On a flat surface (square, plane) along u or v the profile is drawn in the plane of
    the surface's edge u = 0 (v = 0 along u), ``gap`` outside it: run along the curve's
    direction, depth along the normal, as the displaced edge itself lies.  A solid of
    revolution's profile (x = distance from the axis, y = height) is drawn in the xy
    plane beyond the solid's largest radius; on curved surfaces the profile stands
    beside the displaced surface's bounding box, in the xy plane.
    """
    _, points = curve.polyline(tolerance)
    x, y = points[:, 0], points[:, 1]
    charts = _charts(surface)
    flat = len(charts) == 1 and hasattr(charts[0], "state_at_uv") and (
        type(charts[0]).__name__ in ("UnitSquare", "Plane"))
    if along in ("u", "v") and flat:
        s = charts[0].state_at_uv(np.zeros((1, 2)))
        p0, n = s.position[0], s.normal[0]
        run, side = (s.tangent_v[0], s.tangent_u[0]) if along == "v" else (
            s.tangent_u[0], s.tangent_v[0])
        return p0 - gap * side + y[:, None] * run + x[:, None] * n
    lo, hi = moved.min(axis=0), moved.max(axis=0)
    if along in ("radial", "double"):
        reach = float(np.max(np.hypot(moved[:, 0], moved[:, 2])))
        return np.stack([reach + gap + x - x.min(), y, np.zeros_like(x)], axis=1)
    return np.stack([hi[0] + gap + x - x.min(), lo[1] + y, np.full_like(x, 0.5 * (lo[2] + hi[2]))],
                    axis=1)


def _polydata(vertices, faces):
    import pyvista as pv

    faces = np.asarray(faces, dtype=np.int64)
    cells = np.hstack([np.full((len(faces), 1), 3, dtype=np.int64), faces]).ravel()
    return pv.PolyData(np.asarray(vertices, dtype=np.float64), cells)


def _surface_mesh(vertices, faces, uv, normals, counts, stats):
    """The diced surface as PolyData with texture coordinates ``uv * counts``."""
    mesh = _polydata(vertices, faces)
    mesh.point_data["uv"] = uv
    mesh.point_data["Normals"] = normals
    mesh.point_data.active_normals_name = "Normals"
    mesh.active_texture_coordinates = uv * counts
    mesh.field_data["cell_count"] = np.asarray(counts, dtype=np.float64)
    for key, value in stats.items():
        mesh.field_data[key] = np.atleast_1d(np.asarray(value, dtype=np.float64))
    return mesh


def _vector_glyphs(base: np.ndarray, moved: np.ndarray):
    """Arrows from base to displaced points (the displacement vectors), and their data."""
    import pyvista as pv

    points = pv.PolyData(base)
    points.point_data["displacement"] = moved - base
    arrow = pv.Arrow(start=(0.0, 0.0, 0.0), direction=(1.0, 0.0, 0.0), tip_length=0.2,
                     tip_radius=0.07, shaft_radius=0.025)
    glyphs = points.glyph(orient="displacement", scale="displacement", factor=1.0,
                          geom=arrow)
    return points, glyphs


def _normal_glyphs(vertices: np.ndarray, normals: np.ndarray, count: int, length: float):
    """Arrows of fixed ``length`` along the shading normals at ``count`` vertices."""
    import pyvista as pv

    index = np.unique(np.linspace(0, len(vertices) - 1, min(count, len(vertices)))
                      .round().astype(np.int64))
    points = pv.PolyData(vertices[index])
    points.point_data["normal"] = normals[index]
    arrow = pv.Arrow(start=(0.0, 0.0, 0.0), direction=(1.0, 0.0, 0.0), tip_length=0.3,
                     tip_radius=0.12, shaft_radius=0.04)
    return points.glyph(orient="normal", scale=False, factor=length, geom=arrow)


def build_scene(curve, surface: str = "square", along: str = "v", sweep=None,
                repeat: float | None = None, grid_count=4.0, dicing_rate: float = 1.0,
                radius_offset: float = 0.0, camera: Camera | None = None,
                window_size=(1024, 768), tolerance: float = 0.5, vector_count: int = 12,
                normal_count: int = 400, normalize_grid: bool = True,
                thickness=(0.0, 0.0)) -> dict:
    """Everything the viewer shows, as PyVista data (no window).

    Parameters
    ----------
    curve : pwc.Curve
        The profile.
    surface : str or surface
        A name from :data:`SURFACES` or a :mod:`displacement.surfaces` surface with
        ``state_at_uv`` (or ``charts`` of such).
    along, sweep, repeat, radius_offset
        As for :func:`make_field`.
    grid_count : float or (2,) float
        Grid cells per uv unit before the curve-length compensation (:func:`cell_counts`).
    dicing_rate, tolerance : float
        Pixels, for :func:`displacement.dice.dice`.
    camera : Camera or None
        The camera to dice for; None: :func:`default_camera` framing the displaced
        surface and the profile, ``window_size`` pixels.
    window_size : (int, int)
        Width and height of the default camera's image.
    vector_count : int
        Displacement vectors per uv direction (per chart), at cell centres.
    normal_count : int
        Most normal glyphs (evenly spaced over the diced vertices).
    normalize_grid : bool
        Compensate the grid for the curve's length (:func:`cell_counts`).
    thickness : (2,) float
        Grid-line half-widths in uv (0: the Handbook's ``0.05 / cell_count``).

    Returns
    -------
    dict
        ``"surface"``: the diced displaced surface (``pyvista.PolyData``) with point
        arrays ``uv`` (the base uv, kept through displacement) and ``Normals``, active
        texture coordinates ``uv * cell_count`` and field data ``cell_count``,
        ``curve_length``, ``triangles``, ``vertices``, ``time_s``;
        ``"texture"``: the grid cell (``pyvista.Texture``, repeated);
        ``"curve"``: the profile polyline beside the surface;
        ``"vector_points"``: base points with the ``displacement`` vectors;
        ``"vectors"``: arrows from base to displaced points;
        ``"normals"``: arrows along the shading normals;
        and ``"camera"``: the :class:`Camera` the surface was diced for (not PyVista).
    """
    import pyvista as pv

    surface_obj = make_surface(surface) if isinstance(surface, str) else surface
    field = make_field(curve, along, repeat, sweep, radius_offset)
    counts = cell_counts(curve, along, grid_count, normalize_grid)
    if int(vector_count) != vector_count or vector_count < 1:
        raise ValueError(f"vector_count must be a whole number >= 1, got {vector_count}")
    vector_count = int(vector_count)

    # framing: the displaced surface sampled coarsely, and the profile beside it
    _, coarse = _displaced_samples(surface_obj, field, _uv_grid(65, 65, centres=False))
    extent = float(np.max(coarse.max(axis=0) - coarse.min(axis=0)))
    gap = 0.08 * max(extent, 1e-3)
    curve_points = _curve_placement(curve, along, surface_obj, coarse, gap, 1e-3)
    if camera is None:
        camera = default_camera(np.concatenate([coarse, curve_points]), *window_size)

    vertices, faces, uv, normals, stats = dice_surface(surface_obj, field, camera,
                                                       dicing_rate, tolerance)
    mesh = _surface_mesh(vertices, faces, uv, normals, counts, stats)
    mesh.field_data["curve_length"] = np.array([float(curve.length)])
    mesh.field_data["dicing_rate"] = np.array([float(dicing_rate)])

    texture = pv.Texture(grid_tile(counts, thickness))
    texture.repeat = True
    texture.interpolate = True
    texture.mipmap = True

    line = pv.PolyData(curve_points, lines=np.r_[len(curve_points), np.arange(len(curve_points))])
    base, moved = _displaced_samples(surface_obj, field, _uv_grid(vector_count, vector_count,
                                                                   centres=True))
    vector_points, vectors = _vector_glyphs(base, moved)
    normal_glyphs = _normal_glyphs(vertices, normals, int(normal_count), gap)
    return {"surface": mesh, "texture": texture, "curve": line,
            "vector_points": vector_points, "vectors": vectors, "normals": normal_glyphs,
            "camera": camera}


# ------------------------------------------------------------------------ camera
def apply_camera(plotter, camera: Camera) -> None:
    """Set a PyVista plotter's camera to ``camera`` exactly (position, look-at, up,
    field of view or orthographic height), with the clipping range fitted to the scene.

    VTK maps the view to pixels as :class:`Camera` does (pixel ``i`` covers
    ``[i, i + 1)``, row 0 at the top of a screenshot), so a point projected with
    :meth:`Camera.project` lands on the pixel VTK draws it in.
    """
    c = plotter.camera
    c.position = tuple(float(x) for x in camera.position)
    c.focal_point = tuple(float(x) for x in camera.look_at)
    c.up = tuple(float(x) for x in camera.up)
    if camera.is_orthographic:
        c.parallel_projection = True
        c.parallel_scale = 0.5 * float(camera.ortho_height)
    else:
        c.parallel_projection = False
        c.view_angle = float(camera.fov_y_deg)
    plotter.reset_camera_clipping_range()


def camera_from_plotter(plotter) -> Camera:
    """The :class:`Camera` a PyVista plotter currently looks through (its window size)."""
    c = plotter.camera
    width, height = (int(x) for x in plotter.window_size)
    ortho = 2.0 * float(c.parallel_scale) if c.parallel_projection else None
    return Camera(position=tuple(c.position), look_at=tuple(c.focal_point), up=tuple(c.up),
                  fov_y_deg=float(c.view_angle), width=width, height=height,
                  ortho_height=ortho)


# ------------------------------------------------------------------------ plotter
def _use_egl_without_display() -> None:
    """Select VTK's EGL window when there is no X display (silences VTK's warning about
    the missing X server; the EGL window is what VTK falls back to anyway)."""
    if sys.platform.startswith("linux") and not os.environ.get("DISPLAY") \
            and not os.environ.get("WAYLAND_DISPLAY"):
        os.environ.setdefault("VTK_DEFAULT_OPENGL_WINDOW", "vtkEGLRenderWindow")


class Viewer:
    """A scene in a PyVista plotter, re-diced when ``repeat`` or the dicing rate changes.

    Parameters
    ----------
    curve, surface, along, sweep, repeat, grid_count, dicing_rate, radius_offset,
    tolerance, vector_count, normalize_grid
        As for :func:`build_scene`.
    camera : Camera or None
        The view (its width and height are the window size); None: the default camera
        for ``window_size``.
    window_size : (int, int)
    off_screen : bool
        Render without a window (screenshots).
    widgets : bool
        Add sliders for repeat (along u or v only) and the dicing rate, check boxes for
        the vectors, the normals and the triangles' edges, and the key ``d`` that
        re-dices for the current view.
    show_vectors, show_normals, show_curve : bool
        Which glyphs and lines are visible at first (``show_vectors=None``: only along
        u or v; for a solid of revolution the vectors start on the flat square and
        hide the solid).
    lighting : bool
        False: the surface shows its texture's colours as they are (no shading), for
        measuring where the grid lines are.
    background : color
        The window's background.

    Attributes
    ----------
    plotter : pyvista.Plotter
    scene : dict
        The current :func:`build_scene` result.
    """

    def __init__(self, curve, surface="square", along="v", sweep=None, repeat=None,
                 grid_count=4.0, dicing_rate=1.0, radius_offset=0.0, camera=None,
                 window_size=(1024, 768), tolerance=0.5, vector_count=12,
                 normalize_grid=True, off_screen=False, widgets=True, show_vectors=None,
                 show_normals=False, show_curve=True, lighting=True, background="white"):
        if off_screen:
            _use_egl_without_display()
        import pyvista as pv

        if camera is not None:
            window_size = (camera.width, camera.height)
        self._options = dict(curve=curve, surface=surface, along=along, sweep=sweep,
                             grid_count=grid_count, radius_offset=radius_offset,
                             tolerance=tolerance, vector_count=vector_count,
                             normalize_grid=normalize_grid)
        self.repeat = repeat
        self.dicing_rate = float(dicing_rate)
        self.scene = build_scene(repeat=repeat, dicing_rate=dicing_rate, camera=camera,
                                 window_size=window_size, **self._options)
        self.plotter = pl = pv.Plotter(off_screen=off_screen,
                                       window_size=[int(x) for x in window_size])
        pl.set_background(background)
        s = self.scene
        self._surface_actor = pl.add_mesh(s["surface"], texture=s["texture"],
                                          lighting=lighting, smooth_shading=True,
                                          specular=0.0, name="surface")
        self._curve_actor = pl.add_mesh(s["curve"], color=_CURVE_COLOR, line_width=3,
                                        lighting=False, name="curve")
        self._vector_actor = pl.add_mesh(s["vectors"], color=_VECTOR_COLOR, lighting=False,
                                         name="vectors")
        self._normal_actor = pl.add_mesh(s["normals"], color=_NORMAL_COLOR, lighting=False,
                                         name="normals")
        if show_vectors is None:
            show_vectors = along in ("u", "v")
        self._curve_actor.SetVisibility(bool(show_curve))
        self._vector_actor.SetVisibility(bool(show_vectors))
        self._normal_actor.SetVisibility(bool(show_normals))
        self._text = self._add_caption() if widgets else None
        apply_camera(pl, s["camera"])
        if widgets:
            self._add_widgets(show_vectors, show_normals)
            pl.add_key_event("d", self.update)

    def _add_caption(self):
        return self.plotter.add_text(self._caption(), position="upper_left", font_size=9,
                                     color="black", name="caption")

    def _caption(self) -> str:
        o, m = self._options, self.scene["surface"]
        name = getattr(o["curve"], "name", "curve")
        mode = f"along {o['along']}" if o["along"] in ("u", "v") else o["along"]
        rep = "" if self.repeat is None else f", repeat {self.repeat:g}"
        return (f"{name}: {mode}{rep} on {o['surface'] if isinstance(o['surface'], str) else ''}"
                f"\n{int(m.field_data['triangles'][0])} triangles, diced in "
                f"{m.field_data['time_s'][0]:.2f} s at {self.dicing_rate:g} px")

    def _add_widgets(self, show_vectors: bool, show_normals: bool) -> None:
        pl = self.plotter
        slider = dict(style="modern", title_height=0.025, title_color="black",
                      color="black", interaction_event="end")
        pl.add_slider_widget(self.set_dicing_rate, rng=[0.5, 16.0], value=self.dicing_rate,
                             title="dicing rate (px)", pointa=(0.62, 0.12),
                             pointb=(0.95, 0.12), fmt="%.1f", **slider)
        if self._options["along"] in ("u", "v"):
            pl.add_slider_widget(self.set_repeat, rng=[1.0, 12.0],
                                 value=1.0 if self.repeat is None else self.repeat,
                                 title="repeat", pointa=(0.62, 0.27), pointb=(0.95, 0.27),
                                 fmt="%.0f", **slider)
        pl.add_checkbox_button_widget(lambda on: self._normal_actor.SetVisibility(bool(on)),
                                      value=show_normals, position=(10, 10), size=24,
                                      color_on=_NORMAL_COLOR)
        pl.add_text("normals", position=(40, 12), font_size=9, color="black")
        pl.add_checkbox_button_widget(lambda on: self._vector_actor.SetVisibility(bool(on)),
                                      value=show_vectors, position=(10, 44), size=24,
                                      color_on=_VECTOR_COLOR)
        pl.add_text("displacement vectors", position=(40, 46), font_size=9, color="black")
        pl.add_checkbox_button_widget(
            lambda on: self._surface_actor.GetProperty().SetEdgeVisibility(bool(on)),
            value=False, position=(10, 78), size=24, color_on="dimgray")
        pl.add_text("triangle edges", position=(40, 80), font_size=9, color="black")

    def set_repeat(self, value) -> None:
        """Re-dice with ``repeat`` rounded to a whole number of copies (1 keeps the
        Handbook's unrepeated Listing 15.8 when no repeat was asked for)."""
        value = max(1.0, float(round(float(value))))
        new = None if (value == 1.0 and self.repeat is None) else value
        if new != self.repeat:
            self.repeat = new
            self.update()

    def set_dicing_rate(self, value) -> None:
        """Re-dice at ``value`` pixels for the current view."""
        value = float(value)
        if value != self.dicing_rate:
            self.dicing_rate = value
            self.update()

    def update(self) -> None:
        """Re-dice for the plotter's current camera and replace the data in place."""
        camera = camera_from_plotter(self.plotter)
        scene = build_scene(repeat=self.repeat, dicing_rate=self.dicing_rate, camera=camera,
                            **self._options)
        for key in ("surface", "vectors", "normals", "curve"):
            self.scene[key].copy_from(scene[key])
        self.scene["camera"] = camera
        if self._text is not None:
            self._text = self._add_caption()
        self.plotter.render()

    def screenshot(self, path=None) -> np.ndarray:
        """Render and return the image, (height, width, 3) uint8; also write ``path``."""
        return self.plotter.screenshot(None if path is None else str(path), return_img=True)

    def close(self) -> None:
        """Release the render window."""
        self.plotter.close()


def build_plotter(curve, **options):
    """A :class:`Viewer` for ``curve`` (keyword options as :class:`Viewer`'s); returns its
    :class:`pyvista.Plotter`."""
    return Viewer(curve, **options).plotter


def screenshot(path, curve, size=(1024, 768), camera: Camera | None = None,
               **options) -> np.ndarray:
    """Render the scene off-screen and write it to ``path`` (PNG, JPEG, BMP or TIFF).

    Parameters
    ----------
    path : str or Path or None
        None: only return the image.
    curve : pwc.Curve
    size : (int, int)
        Width and height in pixels (ignored when ``camera`` is given: its size counts).
    camera : Camera or None
        The exact view (and the camera the surface is diced for); None: the default.
    **options
        :class:`Viewer`'s options (``surface``, ``along``, ``repeat``, ``show_vectors``,
        ``lighting``, ...); widgets are off unless ``widgets=True``.

    Returns
    -------
    (height, width, 3) uint8
    """
    if path is not None:
        path = Path(path)
        if path.suffix.lower() not in (".png", ".jpg", ".jpeg", ".bmp", ".tif", ".tiff"):
            raise ValueError(f"{path}: unsupported image format {path.suffix or '(none)'}; "
                             "use .png (or .jpg, .bmp, .tif)")
    options.setdefault("widgets", False)
    viewer = Viewer(curve, camera=camera, window_size=tuple(size), off_screen=True,
                    **options)
    try:
        return viewer.screenshot(path)
    finally:
        viewer.close()


def show(curve, size=(1024, 768), **options) -> None:
    """Open an interactive window (PyVista) on the displaced surface.

    Mouse: rotate, pan, zoom; the sliders re-dice for the current view.  Options as
    :class:`Viewer`'s.
    """
    viewer = Viewer(curve, window_size=tuple(size), off_screen=False, **options)
    viewer.plotter.show(title=f"pwc view: {getattr(curve, 'name', '')}")
