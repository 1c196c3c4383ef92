"""Bake a displacement field into a tangent-space normal map, a height map and a vector map.

A displacement field (any callable ``state -> (n, 3)``) on a parametric surface (any
object with ``state_at_uv``) is sampled at the texel centres of a W x H map:

* **normal map**: the unit normal of the *displaced* surface, ``normalize(dP'/du x
  dP'/dv)`` with ``P' = P + D``, by central differences of the displaced position in uv
  with a step of ``step`` texels (default 0.25: small enough that the difference error,
  O(step^2), is far below the map's own interpolation error, and still a finite
  footprint so a crease inside a texel gives a blended normal, not a random one side).
  It is expressed in the base frame ``(texture_tangent_u, texture_tangent_v, normal)``
  as the exact inverse of :func:`displacement.bump.bump_normal`
  (:func:`~displacement.bump.normal_to_tangent_space`), so decoding with ``bump_normal``
  (bump_scale 1, scale_vector_z true) gives back the baked normal wherever the map is
  sampled at a texel centre.  Orientation: the side of ``state.normal`` (flipped for a
  left-handed uv chart); a degenerate displaced surface (zero cross product) bakes the
  base normal ``(0, 0, 1)``.
* **height map**: ``D . N``, the displacement's component along the base normal.
* **vector displacement map**: ``D`` itself in object space, or its components in the
  base frame in tangent space (again the exact inverse: ``x T_u + y T_v + z N = D``).

Map layout: row 0 is the top of the image, texel ``(row, col)`` is centred at ``uv =
((col + 0.5) / W, 1 - (row + 0.5) / H)`` (MDL's lower-left origin, see
:mod:`displacement.textures`).

File encodings (what :func:`write_normal_map`, :func:`write_height_map` and
:func:`write_vector_map` store):

* normal maps, PNG 8/16-bit or EXR half/float: colour ``0.5 + 0.5 n`` (OpenGL green =
  +v unless ``convention="directx"``), so Listing 13.16's defaults (``sample_min = 0``,
  ``sample_max = 1``) decode every one of them;
* height maps: EXR stores the heights themselves (channel ``Y``); PNG stores
  ``(h - low) / (high - low)`` and the function returns ``(low, high)`` to undo it
  (the range is also in the EXR header as ``heightLow``/``heightHigh`` for EXR);
* vector maps: EXR only (signed values), RGB = ``(tangent_u, tangent_v, normal)``
  components by default; ``order="unv"`` writes Maya/Blender/Mudbox's
  (tangent, normal, bitangent) order.  The header records ``space`` and ``channelOrder``.
"""

from __future__ import annotations

import time
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from displacement.bump import (
    bump_normal,
    encode_normal_colors,
    normal_to_tangent_space,
)
from displacement.state import ShadingState
from displacement.surfaces import UnitSquare
from displacement.textures import Texture, read_texture, write_texture

__all__ = [
    "BakedMaps",
    "texel_uv",
    "map_size",
    "displaced_position",
    "displaced_normal",
    "to_tangent_frame",
    "bake",
    "write_normal_map",
    "write_height_map",
    "write_vector_map",
    "read_normal_map",
    "quantize",
    "angle_between",
    "roundtrip_errors",
]

_CHUNK = 1 << 17  # texels per evaluation batch: bounds memory for 1024^2 and beyond


@dataclass(frozen=True)
class BakedMaps:
    """The maps of one bake, each (H, W, ...) with row 0 at the top.

    Attributes
    ----------
    uv : (H, W, 2) float64
        Texel-centre texture coordinates.
    normal : (H, W, 3) float64
        Tangent-space unit normals of the displaced surface (x: tangent_u, y: tangent_v,
        z: normal).
    normal_object : (H, W, 3) float64
        The same normals in object space.
    height : (H, W) float64
        ``D . N``.
    vector_tangent : (H, W, 3) float64
        ``D`` in the base frame (components along tangent_u, tangent_v, normal).
    vector_object : (H, W, 3) float64
        ``D`` in object space.
    step : float
        Finite-difference step in texels.
    seconds : float
        Time the bake took.
    """

    uv: np.ndarray
    normal: np.ndarray
    normal_object: np.ndarray
    height: np.ndarray
    vector_tangent: np.ndarray
    vector_object: np.ndarray
    step: float
    seconds: float

    @property
    def width(self) -> int:
        return int(self.uv.shape[1])

    @property
    def height_px(self) -> int:
        return int(self.uv.shape[0])


def map_size(size) -> tuple[int, int]:
    """``(W, H)`` from an int (square) or a pair; each in 1..16384.

    Examples
    --------
    >>> map_size(64), map_size((128, 32))
    ((64, 64), (128, 32))
    """
    w, h = (size, size) if np.ndim(size) == 0 else tuple(size)
    if not all(isinstance(x, (int, np.integer)) and not isinstance(x, bool) for x in (w, h)):
        raise ValueError(f"map size must be whole numbers of pixels, got {size!r}")
    if not (1 <= w <= 16384 and 1 <= h <= 16384):
        raise ValueError(f"map size must be between 1 and 16384 pixels a side, got {size!r}")
    return int(w), int(h)


def texel_uv(size) -> np.ndarray:
    """Texel-centre uv of a map, shape (H, W, 2), row 0 at the top (v = 1 - (row + 0.5) / H).

    Examples
    --------
    >>> texel_uv((2, 1)).tolist()
    [[[0.25, 0.5], [0.75, 0.5]]]
    """
    w, h = map_size(size)
    u = (np.arange(w) + 0.5) / w
    v = 1.0 - (np.arange(h) + 0.5) / h
    uu, vv = np.meshgrid(u, v)
    return np.stack([uu, vv], axis=-1)


def _evaluate(field, state: ShadingState) -> np.ndarray:
    d = np.asarray(field(state), dtype=np.float64)
    if d.shape != (len(state), 3):
        raise ValueError(
            f"the displacement field returned shape {d.shape}, expected ({len(state)}, 3)"
        )
    if not np.all(np.isfinite(d)):
        bad = state.uv[~np.all(np.isfinite(d), axis=1)][0]
        raise ValueError(f"the displacement field returned NaN or inf (first at uv = {bad})")
    return d


def displaced_position(
    field, surface, uv: np.ndarray
) -> tuple[np.ndarray, ShadingState, np.ndarray]:
    """``P + D`` at ``uv``: displaced positions, the base state, and the displacement.

    Parameters
    ----------
    field : callable ShadingState -> (n, 3)
    surface : object with ``state_at_uv((n, 2)) -> ShadingState``
    uv : (n, 2) float64

    Returns
    -------
    position : (n, 3) float64
    state : ShadingState
    displacement : (n, 3) float64
    """
    state = surface.state_at_uv(np.asarray(uv, dtype=np.float64).reshape(-1, 2))
    d = _evaluate(field, state)
    return state.position + d, state, d


def displaced_normal(
    field, surface, uv: np.ndarray, step
) -> tuple[np.ndarray, ShadingState, np.ndarray]:
    """Object-space unit normals of the displaced surface by central differences in uv.

    Parameters
    ----------
    field : callable ShadingState -> (n, 3)
    surface : object with ``state_at_uv``
    uv : (n, 2) float64
    step : float or (2,) float64
        Difference steps in u and v (uv units, > 0).

    Returns
    -------
    normal : (n, 3) float64
        ``normalize(dP'/du x dP'/dv)``, on the side of the base normal for a
        right-handed chart; the base normal where the cross product vanishes.
    state : ShadingState
        The base state at ``uv``.
    displacement : (n, 3) float64
        ``D`` at ``uv``.
    """
    uv = np.asarray(uv, dtype=np.float64).reshape(-1, 2)
    hu, hv = np.broadcast_to(np.asarray(step, dtype=np.float64), (2,))
    if not (hu > 0 and hv > 0 and np.isfinite(hu) and np.isfinite(hv)):
        raise ValueError(f"finite-difference step must be > 0, got {step!r}")
    n = len(uv)
    offsets = np.array([[0.0, 0.0], [hu, 0.0], [-hu, 0.0], [0.0, hv], [0.0, -hv]])
    all_uv = (uv[None, :, :] + offsets[:, None, :]).reshape(-1, 2)
    p, state_all, d_all = displaced_position(field, surface, all_uv)
    p = p.reshape(5, n, 3)
    dpdu = (p[1] - p[2]) / (2.0 * hu)
    dpdv = (p[3] - p[4]) / (2.0 * hv)
    state = state_all.subset(slice(0, n))
    cross = np.cross(dpdu, dpdv)
    # left-handed charts (tangent_u x tangent_v against the normal) flip the cross product
    handed = np.einsum("ij,ij->i", np.cross(state.tangent_u, state.tangent_v), state.normal)
    cross = np.where((handed < 0.0)[:, None], -cross, cross)
    length = np.linalg.norm(cross, axis=1)
    scale = np.maximum(np.linalg.norm(dpdu, axis=1) * np.linalg.norm(dpdv, axis=1), 1e-300)
    ok = length > 1e-12 * scale
    normal = np.where(ok[:, None], cross / np.where(ok, length, 1.0)[:, None], state.normal)
    return normal, state, d_all[:n]


def to_tangent_frame(state: ShadingState, vectors: np.ndarray) -> np.ndarray:
    """Components ``c`` with ``c_u tangent_u + c_v tangent_v + c_n normal = vectors``.

    Not normalized: the exact coordinates of ``vectors`` in the base frame.

    A singular frame (parallel tangents) falls back to the dot products.

    Examples
    --------
    >>> s = UnitSquare().state_at_uv(np.array([[0.5, 0.5]]))
    >>> to_tangent_frame(s, np.array([[0.1, -0.2, 0.3]])).tolist()
    [[0.1, -0.2, 0.3]]
    """
    vectors = np.asarray(vectors, dtype=np.float64)
    frame = np.stack([state.tangent_u, state.tangent_v, state.normal], axis=2)
    ok = np.abs(np.linalg.det(frame)) > 1e-9
    out = np.stack(
        [
            np.einsum("ij,ij->i", vectors, a)
            for a in (state.tangent_u, state.tangent_v, state.normal)
        ],
        axis=1,
    )
    if np.any(ok):
        out[ok] = np.linalg.solve(frame[ok], vectors[ok][:, :, None])[:, :, 0]
    return out


def bake(field, surface=None, size=256, step: float = 0.25, progress: bool = False) -> BakedMaps:
    """Bake ``field`` on ``surface`` into normal, height and vector maps of ``size``.

    Parameters
    ----------
    field : callable ShadingState -> (n, 3)
        The displacement (a :class:`~displacement.fields.Field` or any function).
    surface : Surface, optional
        Default: the unit square.
    size : int or (W, H)
        Map resolution in pixels.
    step : float
        Finite-difference step in texels (> 0, at most 1).
    progress : bool
        Show a tqdm progress bar over the evaluation batches.

    Returns
    -------
    BakedMaps

    Examples
    --------
    >>> from displacement.fields import constant
    >>> maps = bake(constant((0.0, 0.0, 0.25)), size=2)
    >>> maps.height.tolist(), maps.normal[0, 0].tolist()
    ([[0.25, 0.25], [0.25, 0.25]], [0.0, 0.0, 1.0])
    """
    t0 = time.perf_counter()
    surface = UnitSquare() if surface is None else surface
    step = float(step)
    if not (0.0 < step <= 1.0):
        raise ValueError(f"step must be in (0, 1] texels, got {step}")
    w, h = map_size(size)
    uv = texel_uv((w, h)).reshape(-1, 2)
    total = len(uv)
    normal_obj = np.empty((total, 3))
    normal_tan = np.empty((total, 3))
    vec_obj = np.empty((total, 3))
    vec_tan = np.empty((total, 3))
    height = np.empty(total)
    starts = range(0, total, _CHUNK)
    if progress:
        from tqdm import tqdm

        starts = tqdm(starts, desc="bake", unit="batch")
    for s in starts:
        e = min(s + _CHUNK, total)
        n_obj, state, d = displaced_normal(field, surface, uv[s:e], (step / w, step / h))
        normal_obj[s:e] = n_obj
        normal_tan[s:e] = normal_to_tangent_space(state, n_obj)
        vec_obj[s:e] = d
        vec_tan[s:e] = to_tangent_frame(state, d)
        height[s:e] = np.einsum("ij,ij->i", d, state.normal)
    return BakedMaps(
        uv=uv.reshape(h, w, 2),
        normal=normal_tan.reshape(h, w, 3),
        normal_object=normal_obj.reshape(h, w, 3),
        height=height.reshape(h, w),
        vector_tangent=vec_tan.reshape(h, w, 3),
        vector_object=vec_obj.reshape(h, w, 3),
        step=step,
        seconds=time.perf_counter() - t0,
    )


# ---------------------------------------------------------------------------
# files


def _suffix(path: Path) -> str:
    ext = path.suffix.lower()
    if ext not in (".png", ".exr"):
        raise ValueError(f"unsupported map format: {path} (use .png or .exr)")
    return ext


def _default_bits(path: Path, bits):
    if bits is not None:
        return bits
    return 16 if _suffix(path) == ".png" else "float"


def write_normal_map(path, normal: np.ndarray, bits=None, convention: str = "opengl") -> Path:
    """Write tangent-space unit normals (H, W, 3) as colours ``0.5 + 0.5 n``.

    Parameters
    ----------
    path : str or Path
        ``.png`` (bits 8 or 16, default 16) or ``.exr`` (bits "half" or "float",
        default "float").
    normal : (H, W, 3) float64
        E.g. ``BakedMaps.normal``.
    bits : {8, 16, "half", "float"}, optional
    convention : {"opengl", "directx"}

    Returns
    -------
    Path
    """
    path = Path(path)
    bits = _default_bits(path, bits)
    colors = encode_normal_colors(normal, convention)
    attrs = None
    if _suffix(path) == ".exr":
        attrs = {"normalEncoding": "0.5 + 0.5 n", "convention": convention, "space": "tangent"}
    return write_texture(path, colors, bits=bits, attributes=attrs)


def write_height_map(path, height: np.ndarray, bits=None) -> tuple[Path, float, float]:
    """Write a height map; return ``(path, low, high)``, the heights of grey 0 and 1.

    EXR stores the heights as they are (``low, high`` = their range, for reference);
    PNG stores ``(h - low) / (high - low)`` (a flat map stores 0 with ``high = low``).
    """
    path = Path(path)
    bits = _default_bits(path, bits)
    height = np.asarray(height, dtype=np.float64)
    low, high = float(height.min()), float(height.max())
    if _suffix(path) == ".exr":
        attrs = {"heightLow": low, "heightHigh": high}
        return write_texture(path, height, bits=bits, attributes=attrs), low, high
    span = high - low
    grey = (height - low) / span if span > 0 else np.zeros_like(height)
    return write_texture(path, np.clip(grey, 0.0, 1.0), bits=bits), low, high


def write_vector_map(
    path, vectors: np.ndarray, space: str = "tangent", bits="float", order: str = "uvn"
) -> Path:
    """Write a vector displacement map (signed, OpenEXR only).

    Parameters
    ----------
    path : str or Path
        ``.exr``.
    vectors : (H, W, 3) float64
        ``BakedMaps.vector_tangent`` or ``vector_object``.
    space : {"tangent", "object"}
        Recorded in the header.
    bits : {"half", "float"}
    order : {"uvn", "unv"}
        Tangent space only: RGB = (tangent_u, tangent_v, normal), or (tangent_u,
        normal, tangent_v) as Maya, Blender and Mudbox read them.
    """
    path = Path(path)
    if _suffix(path) != ".exr":
        raise ValueError(
            f"{path}: vector displacement maps hold signed values; write them as .exr"
        )
    if space not in ("tangent", "object"):
        raise ValueError(f"space must be 'tangent' or 'object', not {space!r}")
    if order not in ("uvn", "unv"):
        raise ValueError(f"order must be 'uvn' or 'unv', not {order!r}")
    v = np.asarray(vectors, dtype=np.float64)
    if space == "tangent" and order == "unv":
        v = v[..., [0, 2, 1]]
    attrs = {"space": space, "channelOrder": order if space == "tangent" else "xyz"}
    return write_texture(path, v, bits=bits, attributes=attrs)


def read_normal_map(path) -> Texture:
    """Read a normal map written by :func:`write_normal_map` (always linear)."""
    return read_texture(path, gamma="linear")


# ---------------------------------------------------------------------------
# measuring round trips


def quantize(values: np.ndarray, bits) -> np.ndarray:
    """What storing values in [0, 1] at ``bits`` keeps (8/16-bit codes, half, float32).

    Examples
    --------
    >>> quantize(np.array([0.5]), 8).tolist(), quantize(np.array([0.5]), "half").tolist()
    ([0.5019607843137255], [0.5])
    """
    v = np.asarray(values, dtype=np.float64)
    if bits == 8:
        return np.round(v * 255.0) / 255.0
    if bits == 16:
        return np.round(v * 65535.0) / 65535.0
    if bits == "half":
        return v.astype(np.float16).astype(np.float64)
    if bits == "float":
        return v.astype(np.float32).astype(np.float64)
    raise ValueError(f"bits must be 8, 16, 'half' or 'float', not {bits!r}")


def angle_between(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Angles in degrees between rows of ``a`` and ``b`` (unit or not), robust near 0.

    Uses ``atan2(|a x b|, a . b)``, accurate for tiny angles where ``acos`` is not.

    Examples
    --------
    >>> angle_between(np.array([[1.0, 0, 0]]), np.array([[2.0, 2e-9, 0]])) / np.degrees(1e-9)
    array([1.])
    """
    cross = np.linalg.norm(np.cross(a, b), axis=1)
    dot = np.einsum("ij,ij->i", a, b)
    return np.degrees(np.arctan2(cross, dot))


def roundtrip_errors(
    field,
    reference_normal,
    size,
    bits,
    surface=None,
    samples: int = 20000,
    rng: np.random.Generator | None = None,
    maps: BakedMaps | None = None,
) -> tuple[np.ndarray, np.ndarray]:
    """Bake, store at ``bits``, decode with ``bump_normal`` at random uv, and measure.

    Parameters
    ----------
    field : callable ShadingState -> (n, 3)
    reference_normal : callable (n, 2) uv -> (n, 3) object-space unit normals
        The exact displaced normal (analytic).
    size : int or (W, H)
    bits : {8, 16, "half", "float"}
        The encoded colours are quantized exactly as a file of that depth stores them
        (:func:`quantize`; ``write_texture``/``read_texture`` round trips are bit-exact).
    surface : Surface, optional
    samples : int
        Random uv points, uniform in [0, 1)^2.
    rng : numpy Generator, optional
    maps : BakedMaps, optional
        A bake to reuse (its size wins).

    Returns
    -------
    angles : (samples,) float64
        Degrees between decoded and reference normals.
    uv : (samples, 2) float64
        Where they were measured (to mask creases).
    """
    surface = UnitSquare() if surface is None else surface
    rng = np.random.default_rng(0) if rng is None else rng
    maps = bake(field, surface, size) if maps is None else maps
    colors = quantize(encode_normal_colors(maps.normal), bits)
    texture = Texture(colors, name=f"baked {maps.width}x{maps.height_px} {bits}")
    uv = rng.random((samples, 2))
    state = surface.state_at_uv(uv)
    decoded = bump_normal(state, texture)
    return angle_between(decoded, reference_normal(uv)), uv
