"""The diced mesh that render-time tessellation hands to the renderer, and its warnings."""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

__all__ = ["DicedMesh", "DicingCapWarning", "DicingWarning"]


class DicingWarning(UserWarning):
    """Something about the dicing input was repaired (e.g. a non-finite displacement)."""


class DicingCapWarning(DicingWarning):
    """The triangle cap was reached: the surface was diced coarser than asked to fit."""


@dataclass(frozen=True)
class DicedMesh:
    """Triangles of a displaced surface, in world space, with shading attributes.

    Vertices that share a position but need different attributes are kept apart: the
    copies on either side of a uv seam (different uv) and on either side of a crease (a
    knot line of the field: different normals).  Their positions are bit-identical by
    construction, so rays see a watertight surface; ``weld`` says which vertices are the
    same point, and :meth:`welded` / :meth:`to_trimesh` merge them for topology checks.

    Parameters
    ----------
    vertices : (n, 3) float64
        World-space displaced positions.
    faces : (m, 3) int64
        Counter-clockwise (seen from the side the shading normals point to) triangles.
    uv : (n, 2) float64
        Texture coordinates of the base surface at each vertex (kept through
        displacement, as chapter 14.2 requires).
    normals : (n, 3) float64
        Unit shading normals of the displaced surface, split at creases.
    tangents : (n, 3) float64
        Unit tangents of the displaced surface along increasing u, orthogonal to
        ``normals``.
    weld : (n,) int64
        Index of the distinct position each vertex belongs to (0 .. k-1).
    stats : dict
        ``triangles``, ``vertices``, ``time_s``, ``max_error_px``, ``mean_error_px``
        (estimated screen-space error at the edge and face midpoints tested; None where
        nothing was estimated: uniform or undisplaced dicing), ``cap_reached`` and
        method-specific entries.
    grid : (u_lines (nu,), v_lines (nv,), cell_faces (nv-1, nu-1, 2)) or None
        For a diced parametric surface: the grid lines and, per cell, its two triangles
        (indices into ``faces``, -1 where a triangle collapsed at a pole); used to find
        the triangle that holds a uv point.
    """

    vertices: np.ndarray
    faces: np.ndarray
    uv: np.ndarray
    normals: np.ndarray
    tangents: np.ndarray
    weld: np.ndarray
    stats: dict = field(default_factory=dict)
    grid: tuple | None = None

    def __post_init__(self) -> None:
        n = len(self.vertices)
        for name, width in (("vertices", 3), ("uv", 2), ("normals", 3), ("tangents", 3)):
            a = getattr(self, name)
            if a.shape != (n, width):
                raise ValueError(f"DicedMesh.{name} has shape {a.shape}, expected ({n}, {width})")
        if self.faces.ndim != 2 or self.faces.shape[1] != 3:
            raise ValueError(f"DicedMesh.faces has shape {self.faces.shape}, expected (m, 3)")
        if self.weld.shape != (n,):
            raise ValueError(f"DicedMesh.weld has shape {self.weld.shape}, expected ({n},)")

    @property
    def triangle_count(self) -> int:
        """Number of triangles."""
        return len(self.faces)

    def welded(self) -> tuple[np.ndarray, np.ndarray]:
        """Vertices and faces with coincident copies merged (seams, creases, poles).

        Returns
        -------
        vertices : (k, 3) float64
        faces : (m, 3) int64
        """
        k = int(self.weld.max()) + 1 if len(self.weld) else 0
        first = np.full(k, -1, dtype=np.int64)
        # the first copy of each welded vertex gives its position (all copies agree)
        order = np.arange(len(self.weld))[::-1]
        first[self.weld[order]] = order
        return self.vertices[first], self.weld[self.faces]

    def to_trimesh(self, weld: bool = True):
        """A :class:`trimesh.Trimesh` of the diced surface (``process=False``).

        Parameters
        ----------
        weld : bool
            Merge coincident copies (seams, creases, poles) so the mesh's topology shows
            whether it is watertight; without welding the vertex normals and uv are kept
            as vertex attributes.
        """
        import trimesh

        if weld:
            v, f = self.welded()
            return trimesh.Trimesh(v, f, process=False)
        mesh = trimesh.Trimesh(self.vertices, self.faces, vertex_normals=self.normals,
                               process=False)
        mesh.visual = trimesh.visual.TextureVisuals(uv=self.uv)
        return mesh
