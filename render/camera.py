"""The render camera: :class:`displacement.camera.Camera` (the dicer's camera) plus pixel sampling.

The renderer and the dicer must agree on what a pixel sees, so the camera is the
displacement package's own (pinhole or orthographic, y up, raster y down); this module
only adds box-filtered primary rays for sample indices.
"""

from __future__ import annotations

import numpy as np

from displacement.camera import Camera

__all__ = ["Camera", "primary_rays"]


def primary_rays(
    camera: Camera, pixel: np.ndarray, jitter: np.ndarray
) -> tuple[np.ndarray, np.ndarray]:
    """Camera rays through random points of pixels (a box filter, as Mitsuba's ``box``).

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
    pixel = np.asarray(pixel, dtype=np.int64)
    y, x = np.divmod(pixel, camera.width)
    return camera.generate_rays(x + jitter[:, 0], y + jitter[:, 1])
