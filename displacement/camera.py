"""A pinhole or orthographic camera: projection, frustum tests and pixel footprints.

The dicer asks the camera how large a piece of the displaced surface is on screen; the
renderer reuses the same camera to generate its primary rays.

Conventions
-----------
World space is right-handed with y up.  Camera space has x to the right, y up and the
camera looking down -z, so a point in front of the camera has ``depth = -z_camera > 0``.
Raster space has (0, 0) at the top-left corner of the top-left pixel, x to the right and
y down; pixel ``(i, j)`` covers ``[i, i+1) x [j, j+1)`` and its centre is
``(i + 0.5, j + 0.5)``.  Pixels are square.

Points behind a pinhole camera (``depth <= 0``) have no image.  :meth:`Camera.project`
still returns finite raster coordinates for them (the direction's image pushed out to
:data:`RASTER_LIMIT` pixels, clamped), and :meth:`Camera.in_frustum` reports them outside,
so nothing downstream sees NaN or infinity.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

__all__ = ["Camera", "RASTER_LIMIT"]

#: Raster coordinates are clamped to +-RASTER_LIMIT pixels (points near or behind the
#: camera plane project arbitrarily far away; a finite clamp keeps arithmetic defined).
RASTER_LIMIT = 1.0e12

# relative to the distance look_at - position: depths below this are "at the eye"
_NEAR_REL = 1.0e-12


def _unit(v: np.ndarray, what: str) -> np.ndarray:
    n = float(np.linalg.norm(v))
    if not np.isfinite(n) or n <= 0.0:
        raise ValueError(f"Camera: {what} has zero length or is not finite ({v.tolist()}); "
                         "give distinct, finite points")
    return v / n


def _norm(v: np.ndarray) -> np.ndarray:
    """Row lengths of (n, 3) vectors without overflow for huge coordinates."""
    big = np.abs(v).max(axis=1)
    safe = np.where(big > 0, big, 1.0)
    w = v / safe[:, None]
    return big * np.sqrt(np.einsum("ij,ij->i", w, w))


@dataclass(frozen=True)
class Camera:
    """A pinhole (perspective) or orthographic camera.

    Parameters
    ----------
    position : (3,) float64
        Eye point in world space.
    look_at : (3,) float64
        A point on the viewing axis (the image centre).
    up : (3,) float64
        Approximate up direction; it is orthogonalized against the viewing axis.
    fov_y_deg : float
        Full vertical field of view of the pinhole camera, in degrees, in (0, 180).
    width, height : int
        Image size in pixels.
    ortho_height : float or None
        If given, the camera is orthographic and the image spans ``ortho_height`` world
        units vertically (``ortho_height * width / height`` horizontally).

    Examples
    --------
    >>> cam = Camera(position=(0, 0, 5), look_at=(0, 0, 0), width=100, height=100,
    ...              fov_y_deg=90.0)
    >>> xy, depth = cam.project(np.array([[0.0, 0.0, 0.0], [5.0, 0.0, 0.0], [0, 0, 9.0]]))
    >>> xy[:2].round(6).tolist(), depth.tolist()
    ([[50.0, 50.0], [100.0, 50.0]], [5.0, 5.0, -4.0])
    >>> cam.in_frustum(np.array([[0.0, 0.0, 0.0], [0, 0, 9.0]])).tolist()
    [True, False]
    >>> round(float(cam.pixel_size_at(np.array([[0.0, 0.0, 0.0]]))[0]), 12)  # 2*5*tan(45)/100
    0.1
    """

    position: tuple = (0.0, 0.0, 1.0)
    look_at: tuple = (0.0, 0.0, 0.0)
    up: tuple = (0.0, 1.0, 0.0)
    fov_y_deg: float = 45.0
    width: int = 1024
    height: int = 1024
    ortho_height: float | None = None
    # derived (camera-to-world rotation rows and scale), filled in __post_init__
    _right: np.ndarray = field(init=False, repr=False, compare=False)
    _up: np.ndarray = field(init=False, repr=False, compare=False)
    _forward: np.ndarray = field(init=False, repr=False, compare=False)
    _eye: np.ndarray = field(init=False, repr=False, compare=False)
    _focal: float = field(init=False, repr=False, compare=False)
    _near: float = field(init=False, repr=False, compare=False)
    _rotation: np.ndarray = field(init=False, repr=False, compare=False)

    def __post_init__(self) -> None:
        eye = np.asarray(self.position, dtype=np.float64).reshape(3)
        target = np.asarray(self.look_at, dtype=np.float64).reshape(3)
        up = np.asarray(self.up, dtype=np.float64).reshape(3)
        if not (np.all(np.isfinite(eye)) and np.all(np.isfinite(target))):
            raise ValueError("Camera: position and look_at must be finite")
        if int(self.width) != self.width or int(self.height) != self.height \
                or self.width < 1 or self.height < 1:
            raise ValueError(f"Camera: width and height must be positive integers, got "
                             f"{self.width} x {self.height}")
        forward = _unit(target - eye, "look_at - position")
        up = _unit(up, "up")
        right = np.cross(forward, up)
        if np.linalg.norm(right) < 1e-9:
            raise ValueError("Camera: up is parallel to the viewing direction; "
                             "choose an up vector that is not along look_at - position")
        right = right / np.linalg.norm(right)
        true_up = np.cross(right, forward)
        if self.ortho_height is None:
            if not (0.0 < self.fov_y_deg < 180.0):
                raise ValueError(f"Camera: fov_y_deg must be in (0, 180), got {self.fov_y_deg}")
            focal = 0.5 * self.height / math.tan(math.radians(self.fov_y_deg) / 2.0)
        else:
            if not (self.ortho_height > 0.0 and math.isfinite(self.ortho_height)):
                raise ValueError(f"Camera: ortho_height must be > 0, got {self.ortho_height}")
            focal = self.height / float(self.ortho_height)  # pixels per world unit
        set_ = object.__setattr__
        set_(self, "_right", right)
        set_(self, "_up", true_up)
        set_(self, "_forward", forward)
        set_(self, "_eye", eye)
        set_(self, "_focal", float(focal))
        set_(self, "_near", _NEAR_REL * float(np.linalg.norm(target - eye)))
        # world offset (row) @ _rotation = camera coordinates (x right, y up, -forward)
        set_(self, "_rotation", np.stack([right, true_up, -forward], axis=1))

    # ------------------------------------------------------------------ basics
    @property
    def is_orthographic(self) -> bool:
        """True for an orthographic camera (``ortho_height`` given)."""
        return self.ortho_height is not None

    @property
    def focal_px(self) -> float:
        """Pixels per unit of ``x/depth`` (pinhole) or per world unit (orthographic)."""
        return self._focal

    @property
    def forward(self) -> np.ndarray:
        """(3,) unit viewing direction in world space (camera -z)."""
        return self._forward.copy()

    def world_to_camera(self, points: np.ndarray) -> np.ndarray:
        """Camera-space coordinates (x right, y up, -z forward) of world points.

        Parameters
        ----------
        points : (n, 3) float64

        Returns
        -------
        (n, 3) float64
        """
        d = np.asarray(points, dtype=np.float64).reshape(-1, 3) - self._eye
        # (R^T d^T)^T: numpy's matmul of an (n, 3) by a (3, 3) is ~20x slower
        return (self._rotation.T @ d.T).T

    # ------------------------------------------------------------- projection
    def project(self, points_world: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Raster position and depth of world points.

        Parameters
        ----------
        points_world : (n, 3) float64

        Returns
        -------
        raster_xy : (n, 2) float64
            Raster coordinates, (0, 0) at the top-left pixel corner, y down.  For points
            with ``depth <= 0`` in a pinhole camera (behind the eye) the image of the
            direction is pushed out and clamped to +-:data:`RASTER_LIMIT`: finite, but
            meaningless; use :meth:`in_frustum`.
        depth : (n,) float64
            Distance in front of the camera along the viewing axis (negative behind it).
        """
        c = self.world_to_camera(points_world)
        depth = -c[:, 2]
        if self.is_orthographic:
            sx, sy = c[:, 0] * self._focal, c[:, 1] * self._focal
        else:
            # behind or at the eye: divide by a tiny positive depth (huge, then clamped)
            d = np.maximum(depth, self._near)
            sx, sy = self._focal * c[:, 0] / d, self._focal * c[:, 1] / d
        raster = np.stack([0.5 * self.width + sx, 0.5 * self.height - sy], axis=1)
        return np.clip(raster, -RASTER_LIMIT, RASTER_LIMIT), depth

    def in_frustum(self, points: np.ndarray, margin_px: float = 0.0) -> np.ndarray:
        """Whether points are in front of the camera and inside the image (plus a margin).

        Parameters
        ----------
        points : (n, 3) float64
            World-space points.
        margin_px : float
            Grow the image rectangle by this many pixels on every side.

        Returns
        -------
        (n,) bool
        """
        xy, depth = self.project(points)
        m = float(margin_px)
        inside = ((xy[:, 0] >= -m) & (xy[:, 0] <= self.width + m)
                  & (xy[:, 1] >= -m) & (xy[:, 1] <= self.height + m))
        return inside & (depth > self._near)

    def pixel_size_at(self, points: np.ndarray) -> np.ndarray:
        """World-space size of one pixel at each point's depth.

        Pinhole: ``2 * depth * tan(fov_y / 2) / height``; orthographic: the constant
        ``ortho_height / height``.  For points at or behind a pinhole camera's eye the
        Euclidean distance to the eye replaces the depth (so the size stays positive and
        grows with distance, as Cycles' off-screen footprint does).

        Parameters
        ----------
        points : (n, 3) float64

        Returns
        -------
        (n,) float64, > 0
        """
        p = np.asarray(points, dtype=np.float64).reshape(-1, 3)
        if self.is_orthographic:
            return np.full(len(p), 1.0 / self._focal)
        c = self.world_to_camera(p)
        depth = -c[:, 2]
        d = np.where(depth > self._near, depth, _norm(c))
        return np.maximum(d, self._near) / self._focal

    def raster_scale(self, points: np.ndarray) -> np.ndarray:
        """Upper bound, in pixels per world unit, of the image of a short world segment.

        The largest singular value of the projection's Jacobian at each point: for a
        pinhole ``focal * distance / depth**2`` (``1 / pixel_size_at`` on the axis,
        larger off-axis, where the image plane is oblique), for an orthographic camera the
        constant ``height / ortho_height``.  A world-space error ``e`` at the point is at
        most ``e * raster_scale`` pixels on screen (to first order).  Points at or behind
        a pinhole eye get ``1 / pixel_size_at`` (their distance-based footprint).

        Parameters
        ----------
        points : (n, 3) float64

        Returns
        -------
        (n,) float64, > 0
        """
        p = np.asarray(points, dtype=np.float64).reshape(-1, 3)
        if self.is_orthographic:
            return np.full(len(p), self._focal)
        c = self.world_to_camera(p)
        depth = -c[:, 2]
        dist = np.maximum(_norm(c), self._near)
        front = depth > self._near
        safe = np.where(front, depth, 1.0)
        return np.where(front, self._focal * (dist / safe) / safe, self._focal / dist)

    def dicing_footprint(self, points: np.ndarray, margin_px: float = 0.0
                         ) -> tuple[np.ndarray, np.ndarray]:
        """Pixels per world unit for dicing, and :meth:`in_frustum`, in one pass.

        Inside the frustum (grown by ``margin_px``) the scale is :meth:`raster_scale`;
        outside it is ``1 / pixel_size`` at the point's distance from the eye, as if the
        point were on the viewing axis (Cycles' off-screen footprint): the projection of
        an off-screen point near the eye plane is unbounded and meaningless.

        Parameters
        ----------
        points : (n, 3) float64
        margin_px : float

        Returns
        -------
        scale : (n,) float64
        inside : (n,) bool
        """
        p = np.asarray(points, dtype=np.float64).reshape(-1, 3)
        c = self.world_to_camera(p)
        depth = -c[:, 2]
        m = float(margin_px)
        if self.is_orthographic:
            sx, sy = c[:, 0] * self._focal, c[:, 1] * self._focal
            front = depth > self._near
            scale = np.full(len(p), self._focal)
        else:
            front = depth > self._near
            safe = np.where(front, depth, 1.0)
            sx, sy = self._focal * c[:, 0] / safe, self._focal * c[:, 1] / safe
            dist = np.maximum(_norm(c), self._near)
            scale = np.where(front, self._focal * (dist / safe) / safe, self._focal / dist)
        hw, hh = 0.5 * self.width + m, 0.5 * self.height + m
        inside = front & (np.abs(sx) <= hw) & (np.abs(sy) <= hh)
        if not self.is_orthographic:
            scale = np.where(inside, scale, self._focal / dist)
        return scale, inside

    # -------------------------------------------------------------------- rays
    @property
    def ray_map(self) -> np.ndarray:
        """(2, 3, 3) the camera as two linear maps of raster coordinates ``(px, py, 1)``:
        ``ray_map[0] @ (px, py, 1)`` is a ray's origin and ``ray_map[1] @ (px, py, 1)``
        its direction, before it is made unit length (pinhole: the eye, and
        ``x right + y up + forward`` with ``x = (px - w / 2) / f``, ``y = (h / 2 - py) /
        f``; orthographic: the point ``eye + x right + y up`` on the image plane, and
        ``forward``).  :meth:`generate_rays` applies it; the renderer's kernels take it as
        it is."""
        f = self._focal
        c = -0.5 * self.width / f * self._right + 0.5 * self.height / f * self._up
        m = np.zeros((2, 3, 3))
        plane = np.stack([self._right / f, -self._up / f, c], axis=1)
        if self.is_orthographic:
            m[0] = plane
            m[0][:, 2] += self._eye
            m[1][:, 2] = self._forward
        else:
            m[0][:, 2] = self._eye
            m[1] = plane
            m[1][:, 2] += self._forward
        return m

    def generate_rays(self, px: np.ndarray, py: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Primary rays through raster positions (:attr:`ray_map`).

        Parameters
        ----------
        px, py : (n,) float64
            Raster coordinates (pixel centres are at ``i + 0.5``).

        Returns
        -------
        origins : (n, 3) float64
            The eye (pinhole) or a point on the image plane through the eye
            (orthographic).
        directions : (n, 3) float64
            Unit world-space directions.

        Examples
        --------
        >>> cam = Camera(position=(0, 0, 5), look_at=(0, 0, 0), width=2, height=2)
        >>> o, d = cam.generate_rays(np.array([1.0]), np.array([1.0]))
        >>> d.round(12).tolist()
        [[0.0, 0.0, -1.0]]
        """
        px = np.asarray(px, dtype=np.float64).reshape(-1)
        py = np.asarray(py, dtype=np.float64).reshape(-1)
        if px.shape != py.shape:
            raise ValueError(f"generate_rays: px and py must have the same shape, got "
                             f"{px.shape} and {py.shape}")
        q = np.stack([px, py, np.ones_like(px)], axis=1)
        m = self.ray_map
        d = q @ m[1].T
        d /= np.linalg.norm(d, axis=1, keepdims=True)
        return q @ m[0].T, d
