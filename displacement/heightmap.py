"""Image height-map displacement (Handbook 12.5): grey values move the surface along its normal.

Listing 12.16's ``diffuse_weave`` reads ``weave_depth.png`` with
``texture_2d_lookup_scaled`` and displaces by ``state::normal() * displace *
math::average(texture_color)``.  :func:`image_height_displacement` is that field for any
:class:`~displacement.textures.Texture`; :func:`diffuse_weave` is the Handbook's material
parameters (``scale``, ``displace``) on the field alone (the tint belongs to rendering).
"""

from __future__ import annotations

import os

import numpy as np

from displacement.fields import Field
from displacement.state import ShadingState
from displacement.textures import Texture, read_texture, texture_2d_lookup_scaled

__all__ = ["image_height_displacement", "diffuse_weave", "weave"]


def _as_texture(texture) -> Texture:
    if isinstance(texture, Texture):
        return texture
    if isinstance(texture, (str, os.PathLike)):
        return read_texture(texture, gamma="linear")
    raise ValueError(
        f"texture must be a Texture or a path to an image file, got {type(texture).__name__}"
    )


def _scale2(scale) -> tuple[float, float]:
    s = np.broadcast_to(np.asarray(scale, dtype=np.float64), (2,))
    if not np.all(np.isfinite(s)):
        raise ValueError(f"scale must be finite, got {scale!r}")
    return float(s[0]), float(s[1])


def image_height_displacement(texture, displace: float = 0.0, scale=(1.0, 1.0)) -> Field:
    """The field ``state::normal() * displace * average(texture_2d_lookup_scaled(...))``.

    Parameters
    ----------
    texture : Texture or path
        The height map; its channels are averaged (``math::average``).  A path is read
        linear (no sRGB decoding: grey values are distances).
    displace : float
        Object-space distance for a grey value of 1.
    scale : float or (2,) float
        Repetitions of the image in u and v (Listing 9.10's ``u_scale``, ``v_scale``).

    Returns
    -------
    Field
        ``field(state) -> (n, 3)``; no uv knots (bilinear filtering is continuous).

    Examples
    --------
    >>> from displacement.surfaces import UnitSquare
    >>> t = Texture(np.array([[0.0, 1.0]]))
    >>> f = image_height_displacement(t, displace=0.1, scale=(2.0, 1.0))
    >>> f(UnitSquare().state_at_uv(np.array([[0.375, 0.5]]))).round(12).tolist()
    [[0.0, 0.0, 0.1]]
    """
    tex = _as_texture(texture)
    displace = float(displace)
    if not np.isfinite(displace):
        raise ValueError(f"displace must be finite, got {displace}")
    u_scale, v_scale = _scale2(scale)

    def function(state: ShadingState) -> np.ndarray:
        texture_color = texture_2d_lookup_scaled(state, tex, u_scale, v_scale)
        scaled_displace = displace * texture_color.mean(axis=1)
        return state.normal * scaled_displace[:, None]

    return Field(
        function,
        (None, None),
        "image_height_displacement",
        {"texture": tex.name, "displace": displace, "scale": (u_scale, v_scale)},
    )


def diffuse_weave(texture, scale=(1.0, 1.0), displace: float = 0.0) -> Field:
    """Listing 12.16 ``diffuse_weave``'s geometry: the weave height map as displacement.

    Parameters
    ----------
    texture : Texture or path
        ``weave_depth.png`` (``gallery/textures/weave_depth.png`` here).
    scale : (2,) float
        ``float2(8, 4)`` tiles the weave 8 times in u and 4 in v (Figure 12.20).
    displace : float
        0.1 in Figure 12.19, 0.05 in Figure 12.20.
    """
    field = image_height_displacement(texture, displace=displace, scale=scale)
    return Field(field.function, field.uv_knots, "diffuse_weave", field.parameters)


#: Listing 12.17 ``weave`` has the same geometry as ``diffuse_weave``.
weave = diffuse_weave
