"""Array type aliases shared by the render package (shapes are given in docstrings)."""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike, NDArray

__all__ = ["Arr", "Vec3", "Rgb", "Arr2", "ArrayLike"]

#: (n,) float64: one scalar per lane.
Arr = NDArray[np.float64]
#: (n, 3) float64: one direction per lane, in the local shading frame unless suffixed.
Vec3 = NDArray[np.float64]
#: (n, 3) float64: linear RGB per lane.
Rgb = NDArray[np.float64]
#: (n, 2) float64: two uniform variates per lane, each in [0, 1).
Arr2 = NDArray[np.float64]
