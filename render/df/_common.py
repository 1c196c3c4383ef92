"""MDL's ``df::scatter_mode`` for the distribution functions' Python side.

The per-lane helpers of the kernels (orientation, the IOR pair, tangent axes, Fresnel)
are in :mod:`render.df._kernel_common`.
"""

from __future__ import annotations

from enum import Enum

__all__ = ["ScatterMode"]


class ScatterMode(str, Enum):
    """MDL's ``df::scatter_mode``."""

    scatter_reflect = "scatter_reflect"
    scatter_transmit = "scatter_transmit"
    scatter_reflect_transmit = "scatter_reflect_transmit"

    @classmethod
    def parse(cls, mode) -> ScatterMode:
        """A :class:`ScatterMode` from itself or its MDL name (with or without ``df::``).

        Examples
        --------
        >>> ScatterMode.parse("df::scatter_transmit").name
        'scatter_transmit'
        >>> ScatterMode.parse("reflect")
        Traceback (most recent call last):
        ...
        ValueError: mode must be one of scatter_reflect, scatter_transmit, ...
        """
        if isinstance(mode, cls):
            return mode
        name = str(mode).removeprefix("::").removeprefix("df::")
        try:
            return cls(name)
        except ValueError:
            raise ValueError(
                f"mode must be one of {', '.join(m.value for m in cls)}; got {mode!r}"
            ) from None

