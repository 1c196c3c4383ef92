"""The render camera: :class:`displacement.camera.Camera` (the dicer's camera) plus pixel sampling.

The renderer and the dicer must agree on what a pixel sees, so the camera is the
displacement package's own (pinhole or orthographic, y up, raster y down), taken by the
kernels as its :attr:`~displacement.camera.Camera.ray_map`; this module adds
box-filtered primary rays: :func:`camera_ray` for one sample (the path kernel's), and
:func:`primary_rays` for arrays of them.
"""

from __future__ import annotations

import numpy as np

from displacement.camera import Camera
from render.df._kernel_common import unitize
from render.jit import njit

__all__ = ["Camera", "camera_ray", "primary_rays"]


@njit(inline="always")
def camera_ray(ray_map, width, pixel, jx, jy):
    """The ray through the point ``(jx, jy)`` (in [0, 1)^2) of pixel ``pixel`` (``y *
    width + x``): ``(ox, oy, oz, dx, dy, dz)``, ``d`` unit (a box filter, as Mitsuba's
    ``box``)."""
    px = pixel % width + jx
    py = pixel // width + jy
    o, m = ray_map[0], ray_map[1]
    dx, dy, dz, _ = unitize(m[0, 0] * px + m[0, 1] * py + m[0, 2],
                            m[1, 0] * px + m[1, 1] * py + m[1, 2],
                            m[2, 0] * px + m[2, 1] * py + m[2, 2])
    return (o[0, 0] * px + o[0, 1] * py + o[0, 2], o[1, 0] * px + o[1, 1] * py + o[1, 2],
            o[2, 0] * px + o[2, 1] * py + o[2, 2], dx, dy, dz)


@njit(allocates=True)
def _primary_rays(ray_map, width, pixel, jitter):
    n = len(pixel)
    o, d = np.empty((n, 3)), np.empty((n, 3))
    for i in range(n):
        o[i, 0], o[i, 1], o[i, 2], d[i, 0], d[i, 1], d[i, 2] = camera_ray(
            ray_map, width, pixel[i], jitter[i, 0], jitter[i, 1])
    return o, d


def primary_rays(
    camera: Camera, pixel: np.ndarray, jitter: np.ndarray
) -> tuple[np.ndarray, np.ndarray]:
    """Camera rays through points of pixels (:func:`camera_ray` for arrays).

    Parameters
    ----------
    camera : Camera
    pixel : (n,) int64
        Pixel indices ``y * width + x``.
    jitter : (n, 2) float64
        Uniform in [0, 1)^2: the position inside the pixel.

    Returns
    -------
    origins, directions : (n, 3) float64
        Directions are unit.

    Examples
    --------
    >>> cam = Camera(position=(0, 0, 5), look_at=(0, 0, 0), width=2, height=2)
    >>> o, d = primary_rays(cam, np.array([0, 3]), np.full((2, 2), 0.5))
    >>> bool(d[0, 0] < 0 < d[1, 0]), bool(d[0, 1] > 0 > d[1, 1])   # top-left, bottom-right
    (True, True)
    """
    return _primary_rays(camera.ray_map, int(camera.width),
                         np.asarray(pixel, dtype=np.int64),
                         np.asarray(jitter, dtype=np.float64))
