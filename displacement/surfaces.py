"""Base surfaces: where a displacement field is applied, with uv and unit tangent frames.

Every surface maps texture coordinates to a :class:`~displacement.state.ShadingState`
(position, normal, uv, tangent_u, tangent_v), as MDL's ``state::`` functions would
report them on the undisplaced surface.

Conventions (``spec/displacement.md`` section 2): right-handed, y up; every frame has
unit ``tangent_u`` along increasing u, unit ``tangent_v`` along increasing v, and the
outward unit ``normal``, with ``tangent_u x tangent_v = normal`` wherever the
parametrisation is orthogonal (all parametric surfaces here).  Surfaces of revolution
turn about +y with u, starting on +x and going towards -z (a right-handed turn seen from
+y), the direction of Listing 15.12's ``y_rotation_3``.

* Parametric surfaces (:class:`Plane`, :class:`UVSphere`, :class:`Cylinder`,
  :class:`Torus`) implement ``state_at_uv(uv)`` and ``base_mesh(nu, nv)``, and say with
  ``periodic_u`` / ``periodic_v`` where u = 0 meets u = 1.  In a periodic direction the
  geometry is computed from ``frac(uv)``, so u and u + k (k whole; u = 0 and u = 1)
  give bit-identical positions, normals and tangents; ``state.uv`` always reports the
  uv asked for, unwrapped, as the seam vertices of a mesh carry u = 1.
* Mesh surfaces (:class:`MeshSurface`, :class:`Cube`) implement ``base_mesh()`` and
  ``state_at(face_index, barycentric)`` with per-face tangent frames derived from uv.

Nothing returns NaN: poles, seams and degenerate uv triangles have defined frames.
"""

from __future__ import annotations

import math
from typing import TYPE_CHECKING, Protocol

import numpy as np

from displacement.state import ShadingState

if TYPE_CHECKING:  # imported where a mesh is made: trimesh costs 0.45 s to import
    import trimesh

__all__ = [
    "Surface",
    "UnitSquare",
    "ParametricSurface",
    "Plane",
    "UVSphere",
    "Cylinder",
    "Torus",
    "MeshSurface",
    "Cube",
]


class Surface(Protocol):
    """A parametric base surface."""

    def state_at_uv(self, uv: np.ndarray) -> ShadingState:
        """Shading state at texture coordinates ``uv`` of shape (n, 2)."""
        ...


#: |det| of a triangle's uv edge matrix, relative to the product of its uv edge
#: lengths, below which the triangle's uv mapping is degenerate (no dP/du).
_UV_DEGENERATE_REL = 1e-12


def _as_uv(uv) -> np.ndarray:
    """``uv`` as a fresh (n, 2) float64 array of finite numbers."""
    uv = np.array(uv, dtype=np.float64)
    if uv.ndim == 1 and uv.shape == (2,):
        uv = uv[None, :]
    if uv.ndim != 2 or uv.shape[1] != 2:
        raise ValueError(f"uv must have shape (n, 2), got {uv.shape}")
    if not np.all(np.isfinite(uv)):
        raise ValueError("uv must be finite (no NaN or infinity)")
    return uv


def _wrap(x: np.ndarray) -> np.ndarray:
    """``frac(x)``, the periodic coordinate, with 1.0 from rounding mapped back to 0."""
    w = x - np.floor(x)
    return np.where(w >= 1.0, 0.0, w)


def _unitize(v: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Rows of ``v`` scaled to unit length, and a mask of the rows that had a length.

    Rows of zero (or non-finite) length are returned as zeros with ``valid = False``.
    """
    length = np.linalg.norm(v, axis=-1)
    valid = np.isfinite(length) & (length > 0.0)
    safe = np.where(valid, length, 1.0)
    return np.where(valid[..., None], v / safe[..., None], 0.0), valid


def _any_perpendicular(n: np.ndarray) -> np.ndarray:
    """A unit vector perpendicular to each unit row of ``n`` (deterministic)."""
    axis = np.where((np.abs(n[:, 0]) < 0.9)[:, None], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0])
    t = np.cross(axis, n)
    t, _ = _unitize(t)
    return t


def _texture_mesh(vertices, faces, uv, normals) -> trimesh.Trimesh:
    """A trimesh with vertex uv and normals, vertices kept as given (no merging)."""
    import trimesh

    return trimesh.Trimesh(
        vertices=vertices,
        faces=faces,
        vertex_normals=normals,
        visual=trimesh.visual.TextureVisuals(uv=uv),
        process=False,
    )


def _grid_faces(nu: int, nv: int) -> np.ndarray:
    """Triangles of an (nu + 1) x (nv + 1) vertex grid (index j * (nu + 1) + i), each
    cell split along its (i, j)-(i+1, j+1) diagonal, counter-clockwise in uv."""
    i, j = np.meshgrid(np.arange(nu), np.arange(nv), indexing="xy")
    a = (j * (nu + 1) + i).ravel()
    b = a + 1
    c = a + nu + 2
    d = a + nu + 1
    return np.concatenate([np.stack([a, b, c], 1), np.stack([a, c, d], 1)]).astype(np.int64)


def _check_resolution(nu, nv, min_u: int, min_v: int, name: str) -> tuple[int, int]:
    if int(nu) != nu or int(nv) != nv or nu < min_u or nv < min_v:
        raise ValueError(
            f"{name}.base_mesh needs whole nu >= {min_u} and nv >= {min_v}, got ({nu}, {nv})"
        )
    return int(nu), int(nv)


def _positive(value, name: str) -> float:
    value = float(value)
    if not (math.isfinite(value) and value > 0.0):
        raise ValueError(f"{name} must be a finite number > 0, got {value}")
    return value


class ParametricSurface:
    """Base of the surfaces given by a map from uv to 3D.

    Subclasses implement ``state_at_uv``; ``base_mesh`` here tessellates a regular uv
    grid, seam vertices duplicated (u = 1 beside u = 0) so uv is continuous per face.

    Attributes
    ----------
    periodic_u, periodic_v : bool
        Whether u = 0 and u = 1 (v = 0 and v = 1) are the same points.
    is_mesh : bool
        False: a tessellator samples ``state_at_uv`` (mesh surfaces say True).
    """

    periodic_u: bool = False
    periodic_v: bool = False
    #: diced over its uv domain (``state_at_uv``), not per base triangle
    is_mesh: bool = False
    #: fewest grid cells in u and v for a mesh that is not degenerate
    _min_resolution: tuple[int, int] = (1, 1)
    #: grid cells in u and v of a base mesh when none are given
    resolution: tuple[int, int] = (1, 1)

    def state_at_uv(self, uv: np.ndarray) -> ShadingState:  # pragma: no cover - abstract
        raise NotImplementedError

    def base_grid(self, nu: int | None = None, nv: int | None = None):
        """The uv points and triangles of :meth:`base_mesh`, without evaluating the surface
        or making a mesh (the renderer's path: trimesh alone takes 0.45 s to import).

        Parameters
        ----------
        nu, nv : int, optional
            Cells in u and v (default: ``resolution``).

        Returns
        -------
        uv : (n, 2) float64
        faces : (m, 3) int64
            Triangles wound counter-clockwise seen from the normal side.
        """
        nu, nv = self._cells(nu, nv)
        u, v = np.meshgrid(np.arange(nu + 1) / nu, np.arange(nv + 1) / nv, indexing="xy")
        return np.stack([u.ravel(), v.ravel()], axis=1), _grid_faces(nu, nv)

    def _cells(self, nu, nv) -> tuple[int, int]:
        """``(nu, nv)`` checked, ``resolution`` where not given."""
        return _check_resolution(self.resolution[0] if nu is None else nu,
                                 self.resolution[1] if nv is None else nv,
                                 *self._min_resolution, type(self).__name__)

    def base_mesh(self, nu: int | None = None, nv: int | None = None) -> trimesh.Trimesh:
        """A triangle mesh of the surface on an nu x nv uv grid (default: ``resolution``).

        Returns
        -------
        trimesh.Trimesh
            The :meth:`base_grid` (on a plain grid ``(nu + 1) (nv + 1)`` vertices and
            ``2 nu nv`` triangles) with uv in ``mesh.visual.uv`` and the analytic normals
            as vertex normals.  Not processed: seam vertices stay duplicated.
        """
        uv, faces = self.base_grid(nu, nv)
        state = self.state_at_uv(uv)
        return _texture_mesh(state.position, faces, uv, state.normal)


class Plane(ParametricSurface):
    """A flat rectangle, the unit square generalised.

    ``position = origin + u * size[0] * axis_u + v * size[1] * axis_v``, normal
    ``axis_u x axis_v``.  The default is the Handbook's unit square (u along +x, v along
    +y, normal +z, corner at the origin), identical to :class:`UnitSquare`.  uv outside
    [0, 1] extrapolates: the plane goes on.

    Parameters
    ----------
    size : (2,) float
        Lengths along u and v (object units), > 0.
    resolution : (2,) int
        Default cells of :meth:`base_mesh` (it only matters for a base mesh).
    origin : (3,) float
        The point at uv = (0, 0).
    axis_u, axis_v : (3,) float
        Orthonormal directions of increasing u and v.

    Examples
    --------
    >>> s = Plane(size=(2.0, 1.0)).state_at_uv(np.array([[0.5, 1.0]]))
    >>> s.position.tolist(), s.normal.tolist()
    ([[1.0, 1.0, 0.0]], [[0.0, 0.0, 1.0]])
    """

    def __init__(
        self,
        size=(1.0, 1.0),
        resolution=(1, 1),
        origin=(0.0, 0.0, 0.0),
        axis_u=(1.0, 0.0, 0.0),
        axis_v=(0.0, 1.0, 0.0),
    ):
        size = np.broadcast_to(np.asarray(size, dtype=np.float64), (2,))
        self.size = (_positive(size[0], "Plane size[0]"), _positive(size[1], "Plane size[1]"))
        res = np.broadcast_to(np.asarray(resolution), (2,))
        self.resolution = _check_resolution(res[0], res[1], 1, 1, "Plane")
        self.origin = np.asarray(origin, dtype=np.float64).reshape(3)
        au = np.asarray(axis_u, dtype=np.float64).reshape(3)
        av = np.asarray(axis_v, dtype=np.float64).reshape(3)
        if not (
            np.all(np.isfinite(self.origin))
            and abs(np.linalg.norm(au) - 1.0) < 1e-9
            and abs(np.linalg.norm(av) - 1.0) < 1e-9
            and abs(np.dot(au, av)) < 1e-9
        ):
            raise ValueError(
                "Plane axis_u and axis_v must be orthonormal (unit length, perpendicular) "
                "and origin finite"
            )
        self.axis_u, self.axis_v = au, av
        self.normal = np.cross(au, av)

    def state_at_uv(self, uv: np.ndarray) -> ShadingState:
        """Shading state at ``uv`` (n, 2); uv outside [0, 1] extrapolates linearly."""
        uv = _as_uv(uv)
        n = len(uv)
        position = (
            self.origin
            + (uv[:, 0] * self.size[0])[:, None] * self.axis_u
            + (uv[:, 1] * self.size[1])[:, None] * self.axis_v
        )
        return ShadingState(
            position=position,
            normal=np.broadcast_to(self.normal, (n, 3)).copy(),
            uv=uv,
            tangent_u=np.broadcast_to(self.axis_u, (n, 3)).copy(),
            tangent_v=np.broadcast_to(self.axis_v, (n, 3)).copy(),
        )


class UVSphere(ParametricSurface):
    """A sphere about the origin: u around +y (longitude), v from pole to pole.

    ``theta = 2 pi frac(u)``, latitude ``phi = pi (v - 1/2)`` with v clamped to [0, 1];
    ``position = r (cos phi cos theta, sin phi, -cos phi sin theta)``: v = 0 is the
    south pole (y = -r), v = 1 the north pole, u = 0 the meridian through +x.

    Frame: outward normal ``position / r``; ``tangent_u = (-sin theta, 0, -cos theta)``,
    ``tangent_v = (-sin phi cos theta, cos phi, sin phi sin theta)``, the normalised
    dP/du and dP/dv.  At a pole dP/du = 0; ``tangent_u`` there is its limit along the
    meridian of that u (the same expression), and ``tangent_v`` points along that
    meridian, so the frame stays unit, orthogonal and right-handed.  Pole positions are
    exactly (0, +-r, 0) for every u.  v outside [0, 1] is clamped (there is no surface
    beyond a pole); u outside [0, 1] wraps.

    Parameters
    ----------
    radius : float > 0

    Examples
    --------
    >>> s = UVSphere(2.0).state_at_uv(np.array([[0.0, 0.5], [0.25, 0.5], [0.3, 1.0]]))
    >>> (s.position.round(12) + 0.0).tolist()
    [[2.0, 0.0, 0.0], [0.0, 0.0, -2.0], [0.0, 2.0, 0.0]]
    """

    periodic_u = True
    periodic_v = False
    _min_resolution = (3, 2)
    resolution = (32, 16)

    def __init__(self, radius: float = 1.0):
        self.radius = _positive(radius, "UVSphere radius")

    def state_at_uv(self, uv: np.ndarray) -> ShadingState:
        """Shading state at ``uv`` (n, 2): u wraps, v is clamped to [0, 1]."""
        uv = _as_uv(uv)
        theta = 2.0 * math.pi * _wrap(uv[:, 0])
        v = np.clip(uv[:, 1], 0.0, 1.0)
        phi = math.pi * (v - 0.5)
        pole = (v == 0.0) | (v == 1.0)
        cos_phi = np.where(pole, 0.0, np.cos(phi))   # exact poles
        sin_phi = np.where(pole, np.sign(v - 0.5), np.sin(phi))
        cos_t, sin_t = np.cos(theta), np.sin(theta)
        # + 0.0: no signed zeros, so pole positions are the same bytes for every u
        normal = np.stack([cos_phi * cos_t, sin_phi, -cos_phi * sin_t], axis=1) + 0.0
        zeros = np.zeros_like(cos_t)
        tangent_u = np.stack([-sin_t, zeros, -cos_t], axis=1)
        tangent_v = np.stack([-sin_phi * cos_t, cos_phi, sin_phi * sin_t], axis=1)
        return ShadingState(self.radius * normal, normal, uv, tangent_u, tangent_v)

    def base_grid(self, nu: int | None = None, nv: int | None = None):
        """The sphere as nu segments and nv rings of cells, the poles as triangle fans
        (:meth:`ParametricSurface.base_grid`; default 32 x 16).

        Each pole is ``nu`` vertices at the same position, the i-th with
        u = (i + 1/2) / nu, so every fan triangle has continuous uv (and no triangle is
        degenerate); the seam column u = 1 duplicates u = 0: ``2 nu + (nv - 1)(nu + 1)``
        vertices, ``2 nu (nv - 1)`` triangles.
        """
        nu, nv = self._cells(nu, nv)
        pole_u = (np.arange(nu) + 0.5) / nu
        ring_u, ring_v = np.meshgrid(
            np.arange(nu + 1) / nu, np.arange(1, nv) / nv, indexing="xy"
        )
        uv = np.concatenate([
            np.stack([pole_u, np.zeros(nu)], 1),
            np.stack([ring_u.ravel(), ring_v.ravel()], 1),
            np.stack([pole_u, np.ones(nu)], 1),
        ])
        i = np.arange(nu)
        ring0 = nu                                   # first vertex of ring j = 1
        last = nu + (nv - 2) * (nu + 1)              # first vertex of ring j = nv - 1
        north = nu + (nv - 1) * (nu + 1)
        south_fan = np.stack([i, ring0 + i + 1, ring0 + i], 1)
        north_fan = np.stack([last + i, last + i + 1, north + i], 1)
        body = _grid_faces(nu, nv - 2) + ring0
        return uv, np.concatenate([south_fan, body, north_fan]).astype(np.int64)


class Cylinder(ParametricSurface):
    """An open cylinder about the y axis, centred on the origin (no caps).

    ``position = (r cos theta, (v - 1/2) h, -r sin theta)`` with ``theta = 2 pi
    frac(u)``; outward normal ``(cos theta, 0, -sin theta)``, ``tangent_u = (-sin theta,
    0, -cos theta)``, ``tangent_v = +y``.  u wraps; v outside [0, 1] extrapolates along
    the axis (the cylinder goes on).

    Parameters
    ----------
    radius, height : float > 0

    Examples
    --------
    >>> s = Cylinder(1.0, 2.0).state_at_uv(np.array([[0.0, 1.0], [1.0, 0.0]]))
    >>> (s.position + 0.0).tolist()
    [[1.0, 1.0, 0.0], [1.0, -1.0, 0.0]]
    """

    periodic_u = True
    periodic_v = False
    _min_resolution = (3, 1)
    resolution = (32, 1)

    def __init__(self, radius: float = 1.0, height: float = 1.0):
        self.radius = _positive(radius, "Cylinder radius")
        self.height = _positive(height, "Cylinder height")

    def state_at_uv(self, uv: np.ndarray) -> ShadingState:
        """Shading state at ``uv`` (n, 2): u wraps, v extrapolates along y."""
        uv = _as_uv(uv)
        theta = 2.0 * math.pi * _wrap(uv[:, 0])
        cos_t, sin_t = np.cos(theta), np.sin(theta)
        zeros = np.zeros_like(cos_t)
        normal = np.stack([cos_t, zeros, -sin_t], axis=1)
        position = self.radius * normal
        position[:, 1] = (uv[:, 1] - 0.5) * self.height
        tangent_u = np.stack([-sin_t, zeros, -cos_t], axis=1)
        tangent_v = np.broadcast_to([0.0, 1.0, 0.0], (len(uv), 3)).copy()
        return ShadingState(position, normal, uv, tangent_u, tangent_v)



class Torus(ParametricSurface):
    """A torus about the y axis: u around the axis, v around the tube.

    With ``theta = 2 pi frac(u)``, ``psi = 2 pi frac(v)`` and the radial direction
    ``e = (cos theta, 0, -sin theta)``: ``position = (R + r cos psi) e + r sin psi y``;
    outward normal ``cos psi e + sin psi y``; ``tangent_u = (-sin theta, 0, -cos theta)``;
    ``tangent_v = -sin psi e + cos psi y``.  v = 0 is the outer equator and v grows
    upwards first.  Both directions wrap.  The frame is defined for any radii (even a
    self-intersecting spindle torus, ``minor >= major``).

    Parameters
    ----------
    major : float > 0
        Distance from the axis to the tube's centre line.
    minor : float > 0
        Tube radius.

    Examples
    --------
    >>> s = Torus(1.0, 0.25).state_at_uv(np.array([[0.0, 0.0], [0.0, 0.25]]))
    >>> (s.position.round(12) + 0.0).tolist()
    [[1.25, 0.0, 0.0], [1.0, 0.25, 0.0]]
    """

    periodic_u = True
    periodic_v = True
    _min_resolution = (3, 3)
    resolution = (48, 16)

    def __init__(self, major: float = 1.0, minor: float = 0.25):
        self.major = _positive(major, "Torus major radius")
        self.minor = _positive(minor, "Torus minor radius")

    def state_at_uv(self, uv: np.ndarray) -> ShadingState:
        """Shading state at ``uv`` (n, 2): both u and v wrap."""
        uv = _as_uv(uv)
        theta = 2.0 * math.pi * _wrap(uv[:, 0])
        psi = 2.0 * math.pi * _wrap(uv[:, 1])
        cos_t, sin_t = np.cos(theta), np.sin(theta)
        cos_p, sin_p = np.cos(psi), np.sin(psi)
        zeros = np.zeros_like(cos_t)
        radial = np.stack([cos_t, zeros, -sin_t], axis=1)
        up = np.array([0.0, 1.0, 0.0])
        normal = cos_p[:, None] * radial + sin_p[:, None] * up
        position = (self.major + self.minor * cos_p)[:, None] * radial
        position[:, 1] = self.minor * sin_p
        tangent_u = np.stack([-sin_t, zeros, -cos_t], axis=1)
        tangent_v = -sin_p[:, None] * radial + cos_p[:, None] * up
        return ShadingState(position, normal, uv, tangent_u, tangent_v)



class MeshSurface:
    """Any triangle mesh with per-vertex uv, as a base surface.

    A point is a face index and barycentric coordinates ``(b0, b1, b2)`` of that face's
    vertices: ``p = b0 v0 + b1 v1 + b2 v2`` (from an Embree hit ``(u, v)``:
    ``(1 - u - v, u, v)``).  Position and uv interpolate linearly.

    Normal: per ``normals`` (below), interpolated and normalised; where that is zero,
    the face normal; for a zero-area face, +z.

    Tangent frame (MikkTSpace-like, per face): dP/du and dP/dv solve
    ``[e1 e2] = [dP/du dP/dv] [[du1 du2], [dv1 dv2]]`` for the face's edges e1, e2 and
    their uv differences.  ``tangent_u`` is dP/du orthonormalised against the point's
    normal (Gram-Schmidt), and ``tangent_v = sign * normal x tangent_u`` with ``sign``
    the handedness ``sign((normal x dP/du) . dP/dv)`` (negative on mirrored uv), so the
    frame is orthonormal.  A face whose uv triangle is degenerate (zero area) takes its
    first edge as dP/du; if that is along the normal, any vector perpendicular to it.

    Parameters
    ----------
    mesh : trimesh.Trimesh
        With ``mesh.visual.uv`` of shape (len(vertices), 2).
    normals : {"vertex", "smooth", "face"}
        "vertex": the mesh's vertex normals (its own, or trimesh's average of the faces
        at each vertex); "smooth": those averaged over vertices at the same position, so
        vertices duplicated along uv seams agree and displacement along the normal does
        not crack the seam; "face": flat faces (hard edges; displacement cracks there).

    ``state_at_uv`` is not available: uv charts of a mesh may overlap or leave gaps, so
    uv does not name one point (it raises TypeError).
    """

    periodic_u = False
    periodic_v = False
    #: diced per base triangle (``state_at``), not over a uv domain
    is_mesh = True

    def __init__(self, mesh: trimesh.Trimesh, normals: str = "vertex"):
        uv = getattr(mesh.visual, "uv", None)
        if uv is None:
            raise ValueError(
                "MeshSurface needs per-vertex texture coordinates in mesh.visual.uv "
                "(a trimesh.visual.TextureVisuals); the mesh has none"
            )
        uv = np.asarray(uv, dtype=np.float64)
        vertices = np.asarray(mesh.vertices, dtype=np.float64)
        faces = np.asarray(mesh.faces, dtype=np.int64)
        if uv.shape != (len(vertices), 2):
            raise ValueError(
                f"mesh.visual.uv has shape {uv.shape}, expected ({len(vertices)}, 2)"
            )
        if len(faces) == 0:
            raise ValueError("MeshSurface needs a mesh with at least one face")
        if normals not in ("vertex", "smooth", "face"):
            raise ValueError(f"normals must be 'vertex', 'smooth' or 'face', got {normals!r}")
        self.mesh = mesh
        self.normals = normals
        self._vertices, self._faces, self._uv = vertices, faces, uv

        tri = vertices[faces]                           # (m, 3, 3)
        tuv = uv[faces]                                 # (m, 3, 2)
        e1, e2 = tri[:, 1] - tri[:, 0], tri[:, 2] - tri[:, 0]
        d1, d2 = tuv[:, 1] - tuv[:, 0], tuv[:, 2] - tuv[:, 0]

        face_normal, area_ok = _unitize(np.cross(e1, e2))
        self._face_normal = np.where(area_ok[:, None], face_normal, [0.0, 0.0, 1.0])

        det = d1[:, 0] * d2[:, 1] - d2[:, 0] * d1[:, 1]
        scale = np.linalg.norm(d1, axis=1) * np.linalg.norm(d2, axis=1)
        uv_ok = np.abs(det) > _UV_DEGENERATE_REL * scale
        inv = np.where(uv_ok, 1.0 / np.where(uv_ok, det, 1.0), 0.0)[:, None]
        dpdu = (e1 * d2[:, 1:2] - e2 * d1[:, 1:2]) * inv
        dpdv = (e2 * d1[:, 0:1] - e1 * d2[:, 0:1]) * inv
        self._dpdu = np.where(uv_ok[:, None], dpdu, e1)
        self._uv_ok = uv_ok
        handed = np.einsum("ij,ij->i", np.cross(self._face_normal, dpdu), dpdv)
        self._sign = np.where(uv_ok & (handed < 0.0), -1.0, 1.0)

        if normals == "face":
            self._vertex_normal = None
        else:
            vn = np.asarray(mesh.vertex_normals, dtype=np.float64)
            if normals == "smooth":
                # + 0.0 makes -0.0 and 0.0 one key (np.unique compares rows bytewise)
                _, group = np.unique(vertices + 0.0, axis=0, return_inverse=True)
                group = group.ravel()
                summed = np.zeros((group.max() + 1, 3))
                np.add.at(summed, group, vn)
                welded, ok = _unitize(summed[group])
                vn = np.where(ok[:, None], welded, vn)
            self._vertex_normal = vn

    def base_mesh(self) -> trimesh.Trimesh:
        """The mesh itself (shared, not a copy: do not modify it)."""
        return self.mesh

    def state_at_uv(self, uv):
        """Not available on a mesh: raises TypeError (use :meth:`state_at`)."""
        raise TypeError(
            f"{type(self).__name__} has no state_at_uv: a mesh's uv charts may overlap, so uv "
            "does not name one point; use state_at(face_index, barycentric)"
        )

    def state_at(self, face_index, barycentric) -> ShadingState:
        """Shading state at points given by face and barycentric coordinates.

        Parameters
        ----------
        face_index : (n,) int
        barycentric : (n, 3) float64
            Weights of the face's vertices 0, 1, 2 (usually summing to 1).

        Returns
        -------
        ShadingState
        """
        face_index = np.asarray(face_index)
        barycentric = np.asarray(barycentric, dtype=np.float64)
        if barycentric.ndim == 1 and barycentric.shape == (3,):
            barycentric = barycentric[None, :]
        face_index = face_index.reshape(-1)
        if barycentric.shape != (len(face_index), 3):
            raise ValueError(
                f"barycentric must have shape ({len(face_index)}, 3), got {barycentric.shape}"
            )
        if not np.issubdtype(face_index.dtype, np.integer):
            raise ValueError(f"face_index must be integers, got dtype {face_index.dtype}")
        if len(face_index) and (face_index.min() < 0 or face_index.max() >= len(self._faces)):
            raise ValueError(
                f"face_index out of range [0, {len(self._faces)}): "
                f"{face_index.min()}..{face_index.max()}"
            )
        if not np.all(np.isfinite(barycentric)):
            raise ValueError("barycentric coordinates must be finite")

        corners = self._faces[face_index]                               # (n, 3)
        position = np.einsum("nk,nkj->nj", barycentric, self._vertices[corners])
        uv = np.einsum("nk,nkj->nj", barycentric, self._uv[corners])
        face_normal = self._face_normal[face_index]
        if self._vertex_normal is None:
            normal = face_normal
        else:
            normal = np.einsum("nk,nkj->nj", barycentric, self._vertex_normal[corners])
            normal, ok = _unitize(normal)
            if not ok.all():
                normal[~ok] = face_normal[~ok]

        dpdu = self._dpdu[face_index]
        tangent_u = dpdu - np.einsum("ij,ij->i", dpdu, normal)[:, None] * normal
        tangent_u, ok = _unitize(tangent_u)
        if not ok.all():
            tangent_u[~ok] = _any_perpendicular(normal[~ok])
        tangent_v = self._sign[face_index][:, None] * np.cross(normal, tangent_u)
        return ShadingState(position, normal, uv, tangent_u, tangent_v)


class Cube(MeshSurface):
    """An axis-aligned cube about the origin with six uv charts, each face [0, 1]².

    Every face is a :class:`Plane` (in :attr:`charts`, order +x, -x, +y, -y, +z, -z)
    with its own full uv square, so a profile field applies to each face alike.  On the
    four sides v runs up (+y); u runs around the cube counter-clockwise seen from +y
    (+x face: u along -z; +z face: u along +x).  Top: u along +x, v along -z; bottom:
    u along +x, v along +z.  Every chart is right-handed with an outward normal.

    Normals are flat ("face"): the cube has hard edges, and its faces share no
    vertices (each chart has its own), so displacing along the normal opens its edges.

    Parameters
    ----------
    size : float > 0
        Edge length.
    resolution : int >= 1
        Cells per face edge in :meth:`base_mesh`.

    Attributes
    ----------
    charts : tuple of six Plane
    chart_of_face : (n_faces,) int
        Which chart each triangle belongs to.

    Examples
    --------
    >>> c = Cube(2.0)
    >>> s = c.state_at(np.array([0]), np.array([[1/3, 1/3, 1/3]]))
    >>> s.normal.tolist(), round(float(s.position[0, 0]), 12)
    ([[1.0, 0.0, 0.0]], 1.0)
    """

    CHART_NAMES = ("+x", "-x", "+y", "-y", "+z", "-z")
    _FRAMES = (  # (normal, tangent_u, tangent_v) per chart
        ((1, 0, 0), (0, 0, -1), (0, 1, 0)),
        ((-1, 0, 0), (0, 0, 1), (0, 1, 0)),
        ((0, 1, 0), (1, 0, 0), (0, 0, -1)),
        ((0, -1, 0), (1, 0, 0), (0, 0, 1)),
        ((0, 0, 1), (1, 0, 0), (0, 1, 0)),
        ((0, 0, -1), (-1, 0, 0), (0, 1, 0)),
    )

    def __init__(self, size: float = 1.0, resolution: int = 1):
        self.size = _positive(size, "Cube size")
        if int(resolution) != resolution or resolution < 1:
            raise ValueError(f"Cube resolution must be a whole number >= 1, got {resolution}")
        self.resolution = int(resolution)
        half = self.size / 2.0
        charts = []
        for normal, tu, tv in self._FRAMES:
            n, a, b = (np.asarray(x, dtype=np.float64) for x in (normal, tu, tv))
            charts.append(Plane(
                (self.size, self.size), (self.resolution, self.resolution),
                origin=half * (n - a - b), axis_u=a, axis_v=b,
            ))
        self.charts = tuple(charts)
        meshes = [c.base_mesh() for c in charts]
        offsets = np.cumsum([0] + [len(m.vertices) for m in meshes[:-1]])
        vertices = np.concatenate([m.vertices for m in meshes])
        faces = np.concatenate([m.faces + o for m, o in zip(meshes, offsets, strict=True)])
        uv = np.concatenate([m.visual.uv for m in meshes])
        normals = np.concatenate([m.vertex_normals for m in meshes])
        self.chart_of_face = np.repeat(np.arange(6), [len(m.faces) for m in meshes])
        super().__init__(_texture_mesh(vertices, faces, uv, normals), normals="face")


class UnitSquare(Plane):
    """The Handbook's unit square: u along +x, v along +y, normal +z, uv in [0, 1]².

    One object unit a side, lower-left corner at the origin: the default :class:`Plane`.

    Examples
    --------
    >>> s = UnitSquare().state_at_uv(np.array([[0.0, 0.0], [1.0, 0.5]]))
    >>> s.position.tolist()
    [[0.0, 0.0, 0.0], [1.0, 0.5, 0.0]]
    """

    def __init__(self, resolution=(1, 1)):
        super().__init__(resolution=resolution)
