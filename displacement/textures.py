"""Image textures: read and write PNG/OpenEXR, and sample them bilinearly as MDL's ``tex::`` does.

Origin and orientation
----------------------
A :class:`Texture` holds a float64 array of shape ``(H, W, C)`` whose row 0 is the *top*
row of the image as stored in the file (the order every image viewer shows). MDL puts the
texture-space origin ``uv = (0, 0)`` at the **lower-left** corner of the image (Handbook
section 9.3, Figure 9.2), u to the right and v upwards, both spanning [0, 1] whatever the
aspect ratio.  So ``uv`` maps to the continuous pixel position ``x = u * W - 0.5``,
``y = (1 - v) * H - 0.5`` (row index counted from the top), with texel ``(row, col)``
centred at ``uv = ((col + 0.5) / W, 1 - (row + 0.5) / H)``.

Linear versus sRGB
------------------
MDL's ``texture_2d(name, gamma = tex::gamma_default)`` decides by the file: with
``gamma_default`` integer images (8- and 16-bit PNG) are taken as sRGB-encoded colour and
floating-point images (EXR) as linear; ``tex::gamma_linear`` and ``tex::gamma_srgb``
force either.  Here :func:`read_texture` takes ``gamma="linear"`` by default, because the
textures of chapters 12 and 13 are *data* (heights, normals) whose values must not be
re-encoded; pass ``gamma="srgb"`` (or ``"default"`` for MDL's rule) for colour images such
as ``travertine.png``.  sRGB uses the exact piecewise IEC 61966-2-1 curve, not a 2.2
power.  Normal and height maps must always be read linear.

Formats
-------
* PNG, 8-bit: Pillow, any colour type.
* PNG, 16-bit: Pillow writes 16-bit *grey* only and truncates 16-bit RGB to 8 bits when
  reading, so 16-bit PNG (grey, grey+alpha, RGB, RGBA) is read and written by a small
  numpy codec in this module (:func:`_write_png16`, :func:`_read_png16`) built on
  ``zlib``: non-interlaced images, all five PNG row filters on reading.
* OpenEXR (``.exr``), half or float, scanline, ZIP-compressed, any number of channels and
  named layers (``N.X``, ``N.Y``, ``N.Z``) through the OpenEXR 3.x Python API.
"""

from __future__ import annotations

import os
import struct
import zlib
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from displacement.state import ShadingState

__all__ = [
    "Texture",
    "read_texture",
    "write_texture",
    "srgb_to_linear",
    "linear_to_srgb",
    "width",
    "height",
    "lookup_float",
    "lookup_float3",
    "lookup_color",
    "texture_2d_lookup",
    "texture_2d_lookup_scaled",
    "texture_2d_sample",
    "WRAP_MODES",
]

#: texture filters, cheapest first
FILTERS = ("nearest", "bilinear")

#: MDL ``tex::wrap_mode`` values supported by :meth:`Texture.lookup`.
WRAP_MODES = ("repeat", "clamp", "mirrored_repeat")

_PNG_SIGNATURE = b"\x89PNG\r\n\x1a\n"
_EXR_MAGIC = b"\x76\x2f\x31\x01"
_BITS = (8, 16, "half", "float")
# component order inside an EXR layer: the first family that names every channel wins
_COMPONENT_ORDERS = (("R", "G", "B", "A"), ("X", "Y", "Z", "W"), ("U", "V"), ("Y", "A"))


# ---------------------------------------------------------------------------
# transfer functions


def srgb_to_linear(c: np.ndarray) -> np.ndarray:
    """Decode sRGB-encoded values in [0, 1] to linear (IEC 61966-2-1).

    Examples
    --------
    >>> srgb_to_linear(np.array([0.0, 0.5, 1.0])).round(6).tolist()
    [0.0, 0.214041, 1.0]
    """
    c = np.asarray(c, dtype=np.float64)
    return np.where(c <= 0.04045, c / 12.92, ((np.maximum(c, 0.04045) + 0.055) / 1.055) ** 2.4)


def linear_to_srgb(c: np.ndarray) -> np.ndarray:
    """Encode linear values in [0, 1] as sRGB (inverse of :func:`srgb_to_linear`).

    Examples
    --------
    >>> linear_to_srgb(np.array([0.0, 0.214041, 1.0])).round(4).tolist()
    [0.0, 0.5, 1.0]
    """
    c = np.asarray(c, dtype=np.float64)
    # the decoder's break point mapped through its linear piece, so the two are inverse
    knee = 0.04045 / 12.92
    return np.where(c <= knee, 12.92 * c, 1.055 * np.maximum(c, knee) ** (1.0 / 2.4) - 0.055)


# ---------------------------------------------------------------------------
# the texture


@dataclass(frozen=True, eq=False)
class Texture:
    """A sampled image, MDL's ``texture_2d``: float64 pixels, row 0 at the top.

    Parameters
    ----------
    data : (H, W, C) float64
        Linear pixel values (an ``(H, W)`` array is taken as one channel).  Integer files
        are normalized to [0, 1] by their maximum code value (255 or 65535), as MDL's
        lookup functions do.
    name : str
        Where it came from (a path), for messages.
    channel_names : tuple of str
        One name per channel (``("R", "G", "B")``, ``("N.X", "N.Y", "N.Z")``, ``("Y",)``).
    filter : {"bilinear", "nearest"}
        How :meth:`lookup` filters when not told (a speed/accuracy choice of the scene:
        ``[render] texture_filter``).

    Examples
    --------
    >>> t = Texture(np.array([[0.0, 1.0], [2.0, 3.0]]))
    >>> (t.width, t.height, t.channels)
    (2, 2, 1)
    >>> t.lookup(np.array([[0.25, 0.75], [0.5, 0.5]]))[:, 0].tolist()
    [0.0, 1.5]
    """

    data: np.ndarray
    name: str = "<array>"
    channel_names: tuple[str, ...] = field(default=())
    filter: str = "bilinear"

    def __post_init__(self) -> None:
        if self.filter not in FILTERS:
            raise ValueError(f"texture {self.name}: filter must be one of {', '.join(FILTERS)}, "
                             f"not {self.filter!r}")
        a = np.asarray(self.data, dtype=np.float64)
        if a.ndim == 2:
            a = a[:, :, None]
        if a.ndim != 3 or a.shape[0] < 1 or a.shape[1] < 1 or a.shape[2] < 1:
            raise ValueError(
                f"texture {self.name}: pixel array has shape {np.shape(self.data)}, "
                "expected (H, W) or (H, W, C) with H, W, C >= 1"
            )
        if not np.all(np.isfinite(a)):
            raise ValueError(f"texture {self.name}: pixel array contains NaN or inf")
        a = np.ascontiguousarray(a)
        a.flags.writeable = False
        object.__setattr__(self, "data", a)
        names = tuple(self.channel_names) or _default_channel_names(a.shape[2])
        if len(names) != a.shape[2]:
            raise ValueError(
                f"texture {self.name}: {len(names)} channel names for {a.shape[2]} channels"
            )
        object.__setattr__(self, "channel_names", names)

    @property
    def width(self) -> int:
        """``tex::width``: pixels across (u)."""
        return int(self.data.shape[1])

    @property
    def height(self) -> int:
        """``tex::height``: pixels up (v)."""
        return int(self.data.shape[0])

    @property
    def channels(self) -> int:
        """Number of channels C."""
        return int(self.data.shape[2])

    def lookup(
        self,
        uv: np.ndarray,
        wrap_u: str = "repeat",
        wrap_v: str = "repeat",
        filter: str | None = None,
    ) -> np.ndarray:
        """Filtered value at texture coordinates ``uv`` (MDL ``tex::lookup_*``).

        Parameters
        ----------
        uv : (n, 2) float64
            Texture coordinates, origin at the lower-left of the image.  Any finite
            values: ``"repeat"`` wraps them with ``frac`` semantics (so -0.25 samples
            like 0.75), ``"clamp"`` holds the edge texels, ``"mirrored_repeat"`` reflects
            at every integer.
        wrap_u, wrap_v : {"repeat", "clamp", "mirrored_repeat"}
            MDL ``tex::wrap_repeat`` (the default), ``wrap_clamp``,
            ``wrap_mirrored_repeat``.
        filter : {"bilinear", "nearest"} or None
            Bilinear interpolation between the four nearest texel centres, or the
            nearest texel; None: the texture's own :attr:`filter`.

        Returns
        -------
        (n, C) float64
        """
        filter = self.filter if filter is None else filter
        uv = _as_uv(uv, self.name)
        x = self._axis(uv[:, 0], self.width, wrap_u, flip=False)
        y = self._axis(uv[:, 1], self.height, wrap_v, flip=True)
        if filter == "nearest":
            i = self._index(np.floor(x + 0.5).astype(np.int64), self.width, wrap_u)
            j = self._index(np.floor(y + 0.5).astype(np.int64), self.height, wrap_v)
            return self.data[j, i].copy()
        if filter != "bilinear":
            raise ValueError(f"filter must be 'bilinear' or 'nearest', not {filter!r}")
        x0 = np.floor(x)
        y0 = np.floor(y)
        fx = (x - x0)[:, None]
        fy = (y - y0)[:, None]
        x0 = x0.astype(np.int64)
        y0 = y0.astype(np.int64)
        i0 = self._index(x0, self.width, wrap_u)
        i1 = self._index(x0 + 1, self.width, wrap_u)
        j0 = self._index(y0, self.height, wrap_v)
        j1 = self._index(y0 + 1, self.height, wrap_v)
        d = self.data
        top = d[j0, i0] * (1.0 - fx) + d[j0, i1] * fx
        bottom = d[j1, i0] * (1.0 - fx) + d[j1, i1] * fx
        return top * (1.0 - fy) + bottom * fy

    # continuous texel coordinate along one axis (before index wrapping)
    @staticmethod
    def _axis(t: np.ndarray, n: int, wrap: str, flip: bool) -> np.ndarray:
        if wrap == "repeat":
            t = t - np.floor(t)  # math::frac; lands in [0, 1]
        elif wrap == "mirrored_repeat":
            t = np.abs(t - 2.0 * np.floor(0.5 * t) - 1.0)  # triangle wave, 1 - |frac2 - 1|
            t = 1.0 - t
        elif wrap == "clamp":
            t = np.clip(t, 0.0, 1.0)
        else:
            raise ValueError(f"wrap mode must be one of {WRAP_MODES}, not {wrap!r}")
        if flip:
            t = 1.0 - t
        return t * n - 0.5

    @staticmethod
    def _index(i: np.ndarray, n: int, wrap: str) -> np.ndarray:
        if wrap == "repeat":
            return np.mod(i, n)
        return np.clip(i, 0, n - 1)  # clamp; mirrored repeat holds the edge texel too

    def lookup_float(self, uv: np.ndarray, **kw) -> np.ndarray:
        """``tex::lookup_float``: the first channel, shape (n,)."""
        return self.lookup(uv, **kw)[:, 0]

    def lookup_float3(self, uv: np.ndarray, **kw) -> np.ndarray:
        """``tex::lookup_float3``: (n, 3); one channel is repeated, alpha is dropped."""
        return _as_three(self.lookup(uv, **kw))

    lookup_color = lookup_float3
    """``tex::lookup_color``: linear RGB (n, 3), as :meth:`lookup_float3`."""


def _default_channel_names(c: int) -> tuple[str, ...]:
    return {1: ("Y",), 2: ("Y", "A"), 3: ("R", "G", "B"), 4: ("R", "G", "B", "A")}.get(
        c, tuple(f"C{k}" for k in range(c))
    )


def _as_three(v: np.ndarray) -> np.ndarray:
    c = v.shape[1]
    if c == 1:
        return np.repeat(v, 3, axis=1)
    if c == 2:  # grey + alpha
        return np.repeat(v[:, :1], 3, axis=1)
    return v[:, :3].copy()


def _as_uv(uv: np.ndarray, name: str) -> np.ndarray:
    uv = np.asarray(uv, dtype=np.float64)
    if uv.ndim == 1 and uv.shape[0] == 2:
        uv = uv[None, :]
    if uv.ndim != 2 or uv.shape[1] != 2:
        raise ValueError(f"texture {name}: uv must have shape (n, 2), got {uv.shape}")
    if not np.all(np.isfinite(uv)):
        raise ValueError(f"texture {name}: uv contains NaN or inf; pass finite coordinates")
    return uv


# ---------------------------------------------------------------------------
# MDL tex:: functions and the Handbook's lookup functions


def width(texture: Texture) -> int:
    """``tex::width(texture)``."""
    return texture.width


def height(texture: Texture) -> int:
    """``tex::height(texture)``."""
    return texture.height


def lookup_float(texture: Texture, uv: np.ndarray, **kw) -> np.ndarray:
    """``tex::lookup_float(texture, uv)``: (n,) float64, the first channel."""
    return texture.lookup_float(uv, **kw)


def lookup_float3(texture: Texture, uv: np.ndarray, **kw) -> np.ndarray:
    """``tex::lookup_float3(texture, uv)``: (n, 3) float64."""
    return texture.lookup_float3(uv, **kw)


def lookup_color(texture: Texture, uv: np.ndarray, **kw) -> np.ndarray:
    """``tex::lookup_color(texture, uv)``: (n, 3) float64 linear RGB."""
    return texture.lookup_float3(uv, **kw)


def _frac(x: np.ndarray) -> np.ndarray:
    return x - np.floor(x)


def texture_2d_lookup(state: ShadingState, texture: Texture) -> np.ndarray:
    """Handbook Listing 9.7: the colour at ``state::texture_coordinate(0)``.

    Returns
    -------
    (n, 3) float64
    """
    return texture.lookup_float3(state.uv)


def texture_2d_lookup_scaled(
    state: ShadingState, texture: Texture, u_scale: float = 1.0, v_scale: float = 1.0
) -> np.ndarray:
    """Handbook Listing 9.10: colour at ``frac(u * u_scale), frac(v * v_scale)``.

    Parameters
    ----------
    state : ShadingState
        Supplies ``state::texture_coordinate(0)`` (``state.uv``).
    texture : Texture
    u_scale, v_scale : float
        Repetitions of the image across the unit of texture space.

    Returns
    -------
    (n, 3) float64

    Examples
    --------
    >>> from displacement.surfaces import UnitSquare
    >>> t = Texture(np.array([[0.0, 1.0]]))            # one row: left 0, right 1
    >>> s = UnitSquare().state_at_uv(np.array([[0.125, 0.5], [0.375, 0.5]]))
    >>> texture_2d_lookup_scaled(s, t, 2.0, 1.0)[:, 0].tolist()   # frac(0.25), frac(0.75)
    [0.0, 1.0]
    """
    uv = np.asarray(state.uv, dtype=np.float64)
    scaled = np.stack([_frac(uv[:, 0] * u_scale), _frac(uv[:, 1] * v_scale)], axis=1)
    return texture.lookup_float3(scaled)


def texture_2d_sample(
    texture: Texture, texture_scale=(1.0, 1.0), uv: np.ndarray = (0.0, 0.0)
) -> np.ndarray:
    """Handbook Listing 13.8: colour at explicit coordinates, ``frac(uv * texture_scale)``.

    Parameters
    ----------
    texture : Texture
    texture_scale : float or (2,) or (n, 2) float64
        Repetitions of the image in u and v.
    uv : (n, 2) or (2,) float64
        Texture-space coordinates (not read from the state).

    Returns
    -------
    (n, 3) float64

    Examples
    --------
    >>> t = Texture(np.array([[0.0, 1.0]]))
    >>> texture_2d_sample(t, (1.0, 1.0), np.array([[-0.25, 0.0], [1.75, 3.0]]))[:, 0].tolist()
    [1.0, 1.0]
    """
    uv = _as_uv(uv, texture.name)
    scale = np.broadcast_to(np.asarray(texture_scale, dtype=np.float64), uv.shape)
    return texture.lookup_float3(_frac(uv * scale))


# ---------------------------------------------------------------------------
# reading


def read_texture(path, gamma: str = "linear", layer: str | None = None) -> Texture:
    """Read a PNG (8/16-bit) or OpenEXR (half/float) image as a :class:`Texture`.

    Parameters
    ----------
    path : str or os.PathLike
    gamma : {"linear", "srgb", "default"}
        How integer values are decoded: ``"linear"`` keeps code/max (right for height
        and normal maps), ``"srgb"`` applies the sRGB decoding curve, ``"default"``
        follows MDL's ``tex::gamma_default`` (sRGB for PNG, linear for EXR).  EXR data
        is always linear except with ``"srgb"``.  Alpha is never decoded.
    layer : str, optional
        EXR only: the layer to read (``"N"`` reads ``N.X, N.Y, N.Z``).  By default the
        unprefixed channels (``R, G, B[, A]`` or ``Y``), or the only layer there is.

    Returns
    -------
    Texture

    Raises
    ------
    FileNotFoundError
        The file does not exist (the message names the path).
    ValueError
        Unsupported format, bit depth or layout, unknown layer, or bad ``gamma``.
    """
    path = Path(os.fspath(path))
    if gamma not in ("linear", "srgb", "default"):
        raise ValueError(f"gamma must be 'linear', 'srgb' or 'default', not {gamma!r}")
    if not path.is_file():
        raise FileNotFoundError(f"texture file not found: {path}")
    with open(path, "rb") as fh:
        magic = fh.read(8)
    if magic.startswith(_PNG_SIGNATURE):
        data, names = _read_png(path)
        srgb = gamma in ("srgb", "default")
    elif magic.startswith(_EXR_MAGIC):
        data, names = _read_exr(path, layer)
        srgb = gamma == "srgb"
    else:
        raise ValueError(
            f"unsupported texture format: {path} (supported: PNG 8/16-bit, OpenEXR)"
        )
    if layer is not None and not magic.startswith(_EXR_MAGIC):
        raise ValueError(f"{path}: layer={layer!r} applies to OpenEXR files only")
    if srgb:
        colour = [k for k, n in enumerate(names) if not n.split(".")[-1] == "A"]
        data[..., colour] = srgb_to_linear(data[..., colour])
    return Texture(data, name=str(path), channel_names=names)


def _read_png(path: Path) -> tuple[np.ndarray, tuple[str, ...]]:
    with open(path, "rb") as fh:
        head = fh.read(33)
    if len(head) < 33 or head[12:16] != b"IHDR":
        raise ValueError(f"{path}: not a valid PNG file (missing IHDR)")
    bit_depth = head[24]
    if bit_depth == 16:
        a = _read_png16(path)
        return a / 65535.0, _default_channel_names(a.shape[2])
    from PIL import Image

    with Image.open(path) as im:
        mode = im.mode
        if mode == "P":
            im = im.convert("RGBA" if "transparency" in im.info else "RGB")
        elif mode in ("1",):
            im = im.convert("L")
        elif mode not in ("L", "LA", "RGB", "RGBA"):
            raise ValueError(f"{path}: unsupported PNG pixel mode {mode!r}")
        a = np.asarray(im, dtype=np.float64) / 255.0
    if a.ndim == 2:
        a = a[:, :, None]
    return a, _default_channel_names(a.shape[2])


def _read_exr(path: Path, layer: str | None) -> tuple[np.ndarray, tuple[str, ...]]:
    import OpenEXR

    try:
        with OpenEXR.File(str(path), separate_channels=True) as f:
            channels = {k: np.asarray(v.pixels) for k, v in f.channels().items()}
    except RuntimeError as exc:  # OpenEXR reports every failure as RuntimeError
        raise ValueError(f"{path}: cannot read OpenEXR file ({exc})") from None
    groups: dict[str, list[str]] = {}
    for full in channels:
        prefix, _, comp = full.rpartition(".")
        groups.setdefault(prefix, []).append(comp)
    if layer is None:
        if "" in groups:
            layer = ""
        elif len(groups) == 1:
            layer = next(iter(groups))
        else:
            raise ValueError(
                f"{path}: several layers {sorted(groups)}; pass layer= to choose one"
            )
    if layer not in groups:
        shown = sorted(k or "<unprefixed>" for k in groups)
        raise ValueError(f"{path}: no layer {layer!r}; the file has {shown}")
    comps = groups[layer]
    for order in _COMPONENT_ORDERS:
        if set(comps) <= set(order):
            comps = [c for c in order if c in comps]
            break
    else:
        comps = sorted(comps)
    names = tuple(f"{layer}.{c}" if layer else c for c in comps)
    data = np.stack([channels[n].astype(np.float64) for n in names], axis=-1)
    if not np.all(np.isfinite(data)):
        raise ValueError(f"{path}: EXR channels {names} contain NaN or inf")
    return data, names


# ---------------------------------------------------------------------------
# writing


def write_texture(
    path,
    array: np.ndarray,
    bits=None,
    gamma: str = "linear",
    channel_names=None,
    layer: str | None = None,
    attributes: dict | None = None,
) -> Path:
    """Write an image: PNG 8/16-bit or OpenEXR half/float, chosen by extension and bits.

    Parameters
    ----------
    path : str or os.PathLike
        ``.png`` or ``.exr``.
    array : (H, W) or (H, W, C) float64
        Row 0 is the top of the image.  PNG takes C in 1..4 (grey, grey+alpha, RGB,
        RGBA) with values in [0, 1]; EXR takes any C and any finite value (half: up to
        65504 in magnitude).
    bits : {8, 16, "half", "float"}, optional
        Default 8 for PNG and "float" for EXR.
    gamma : {"linear", "srgb"}
        ``"srgb"`` encodes colour channels with the sRGB curve before quantizing (for
        colour images); data maps stay ``"linear"``.
    channel_names : sequence of str, optional
        EXR channel names, one per channel (default Y / Y,A / R,G,B / R,G,B,A).
    layer : str, optional
        EXR layer prefix: ``layer="N"`` on 3 channels writes ``N.X, N.Y, N.Z``.
    attributes : dict, optional
        Extra EXR header attributes (str, int or float values), e.g. ``{"space":
        "tangent"}``.

    Returns
    -------
    Path
        The path written.

    Raises
    ------
    ValueError
        Unsupported extension or bit depth for it, wrong channel count, values that the
        format cannot store (outside [0, 1] for PNG, NaN/inf, beyond half range).
    """
    path = Path(os.fspath(path))
    if not path.parent.is_dir():
        raise FileNotFoundError(f"cannot write {path}: directory {path.parent} does not exist")
    a = np.asarray(array, dtype=np.float64)
    if a.ndim == 2:
        a = a[:, :, None]
    if a.ndim != 3 or a.shape[0] < 1 or a.shape[1] < 1 or a.shape[2] < 1:
        raise ValueError(f"{path}: image must have shape (H, W) or (H, W, C), got {a.shape}")
    if not np.all(np.isfinite(a)):
        raise ValueError(f"{path}: image contains NaN or inf; these cannot be stored")
    if gamma not in ("linear", "srgb"):
        raise ValueError(f"gamma must be 'linear' or 'srgb', not {gamma!r}")
    ext = path.suffix.lower()
    if ext == ".png":
        bits = 8 if bits is None else bits
        if bits not in (8, 16):
            raise ValueError(
                f"{path}: PNG stores 8 or 16 bits per channel, not {bits!r}; "
                "use a .exr file for 'half' or 'float'"
            )
        if a.shape[2] > 4:
            raise ValueError(
                f"{path}: PNG holds 1 to 4 channels (grey, grey+alpha, RGB, RGBA), got "
                f"{a.shape[2]}; use a .exr file"
            )
        if channel_names is not None or layer is not None or attributes:
            raise ValueError(f"{path}: channel names, layers and attributes need OpenEXR")
        lo, hi = float(a.min()), float(a.max())
        if lo < 0.0 or hi > 1.0:
            raise ValueError(
                f"{path}: values span [{lo:.6g}, {hi:.6g}] but an integer PNG stores [0, 1]; "
                "rescale (e.g. 0.5 + 0.5 * n for normals) or write OpenEXR"
            )
        if gamma == "srgb":
            a = a.copy()
            colour = slice(0, 3) if a.shape[2] >= 3 else slice(0, 1)
            a[..., colour] = linear_to_srgb(a[..., colour])
        if bits == 16:
            _write_png16(path, np.round(a * 65535.0).astype(np.uint16))
        else:
            from PIL import Image

            q = np.round(a * 255.0).astype(np.uint8)
            mode = {1: "L", 2: "LA", 3: "RGB", 4: "RGBA"}[q.shape[2]]
            Image.fromarray(q[:, :, 0] if q.shape[2] == 1 else q, mode=mode).save(path)
        return path
    if ext == ".exr":
        bits = "float" if bits is None else bits
        if bits not in ("half", "float"):
            raise ValueError(
                f"{path}: OpenEXR stores 'half' or 'float', not {bits!r}; "
                "use a .png file for 8 or 16 bits"
            )
        _write_exr(path, a, bits, gamma, channel_names, layer, attributes or {})
        return path
    raise ValueError(f"unsupported texture format for writing: {path} (use .png or .exr)")


def _write_exr(path, a, bits, gamma, channel_names, layer, attributes) -> None:
    import OpenEXR

    c = a.shape[2]
    if channel_names is not None and layer is not None:
        raise ValueError(f"{path}: pass channel_names or layer, not both")
    if layer is not None:
        comps = ("X", "Y", "Z", "W") if c <= 4 else tuple(f"C{k}" for k in range(c))
        names = tuple(f"{layer}.{comps[k]}" for k in range(c))
    elif channel_names is not None:
        names = tuple(channel_names)
    else:
        names = _default_channel_names(c)
    if len(names) != c or len(set(names)) != c:
        raise ValueError(f"{path}: need {c} distinct channel names, got {names}")
    if gamma == "srgb":
        a = a.copy()
        colour = [k for k, n in enumerate(names) if n.split(".")[-1] != "A"]
        a[..., colour] = linear_to_srgb(a[..., colour])
    dtype = np.float16 if bits == "half" else np.float32
    if bits == "half" and float(np.abs(a).max()) > 65504.0:
        raise ValueError(f"{path}: values beyond +-65504 overflow half floats; use 'float'")
    header = {"compression": OpenEXR.ZIP_COMPRESSION, "type": OpenEXR.scanlineimage}
    for key, value in attributes.items():
        if not isinstance(value, (str, int, float)):
            raise ValueError(f"{path}: EXR attribute {key!r} must be str, int or float")
        header[key] = value
    chans = {n: np.ascontiguousarray(a[:, :, k].astype(dtype)) for k, n in enumerate(names)}
    try:
        with OpenEXR.File(header, chans) as f:
            f.write(str(path))
    except RuntimeError as exc:  # OpenEXR reports I/O failures as RuntimeError
        raise OSError(f"cannot write {path}: {exc}") from None


# ---------------------------------------------------------------------------
# 16-bit PNG codec (Pillow cannot write 16-bit colour PNG nor read it losslessly)

_COLOR_TYPE = {1: 0, 2: 4, 3: 2, 4: 6}  # channels -> PNG colour type
_CHANNELS = {0: 1, 4: 2, 2: 3, 6: 4}


def _chunk(kind: bytes, payload: bytes) -> bytes:
    return (
        struct.pack(">I", len(payload))
        + kind
        + payload
        + struct.pack(">I", zlib.crc32(kind + payload) & 0xFFFFFFFF)
    )


def _write_png16(path: Path, q: np.ndarray) -> None:
    """Write a (H, W, C) uint16 array as a 16-bit PNG (C in 1..4), rows filtered Sub or Up.

    Each row gets the filter (None, Sub or Up) with the smallest sum of absolute signed
    residuals, the usual PNG heuristic, computed for all rows at once.
    """
    h, w, c = q.shape
    raw = q.astype(">u2").view(np.uint8).reshape(h, w * c * 2).astype(np.int16)
    bpp = 2 * c
    sub = raw.copy()
    sub[:, bpp:] -= raw[:, :-bpp]
    up = raw.copy()
    up[1:] -= raw[:-1]
    cands = np.stack([raw, sub, up]) & 0xFF  # (3, H, stride) filtered bytes
    cost = np.abs(cands.astype(np.int8).astype(np.int32)).sum(axis=2)  # (3, H)
    choice = np.argmin(cost, axis=0)
    rows = cands[choice, np.arange(h)].astype(np.uint8)
    body = np.concatenate([choice.astype(np.uint8)[:, None], rows], axis=1)
    ihdr = struct.pack(">IIBBBBB", w, h, 16, _COLOR_TYPE[c], 0, 0, 0)
    with open(path, "wb") as fh:
        fh.write(_PNG_SIGNATURE)
        fh.write(_chunk(b"IHDR", ihdr))
        fh.write(_chunk(b"IDAT", zlib.compress(body.tobytes(), 9)))
        fh.write(_chunk(b"IEND", b""))


def _read_png16(path: Path) -> np.ndarray:
    """Read a non-interlaced 16-bit PNG as (H, W, C) float64 codes in [0, 65535]."""
    blob = path.read_bytes()
    pos = len(_PNG_SIGNATURE)
    idat = []
    ihdr = None
    while pos + 8 <= len(blob):
        (length,) = struct.unpack(">I", blob[pos : pos + 4])
        kind = blob[pos + 4 : pos + 8]
        payload = blob[pos + 8 : pos + 8 + length]
        pos += 12 + length
        if kind == b"IHDR":
            ihdr = struct.unpack(">IIBBBBB", payload)
        elif kind == b"IDAT":
            idat.append(payload)
        elif kind == b"IEND":
            break
    if ihdr is None or not idat:
        raise ValueError(f"{path}: truncated PNG (no IHDR or IDAT)")
    w, h, depth, ctype, _, _, interlace = ihdr
    if ctype not in _CHANNELS:
        raise ValueError(f"{path}: unsupported 16-bit PNG colour type {ctype}")
    if interlace:
        raise ValueError(f"{path}: interlaced 16-bit PNG is not supported; re-save it plain")
    c = _CHANNELS[ctype]
    bpp = 2 * c
    stride = w * bpp
    try:
        raw = np.frombuffer(zlib.decompress(b"".join(idat)), dtype=np.uint8)
    except zlib.error as exc:
        raise ValueError(f"{path}: corrupt PNG data ({exc})") from None
    if raw.size < h * (stride + 1):
        raise ValueError(f"{path}: truncated PNG image data")
    rows = raw[: h * (stride + 1)].reshape(h, stride + 1)
    filters = rows[:, 0]
    if np.any(filters > 4):
        raise ValueError(f"{path}: invalid PNG row filter type")
    data = rows[:, 1:].astype(np.int32).reshape(h, w, bpp)
    out = _unfilter(data, filters)
    q = (out[..., 0::2] << 8) | out[..., 1::2]  # big-endian pairs
    return q.astype(np.float64)


def _unfilter(data: np.ndarray, filters: np.ndarray) -> np.ndarray:
    """Undo PNG row filters on (H, W, bpp) bytes; vectorized, no per-pixel Python loop.

    Rows filtered None/Sub/Up are undone row by row (Sub is a running sum mod 256).
    Average and Paeth depend on the left neighbour *and* the row above, so if any row
    uses them the whole image is undone along anti-diagonals r + c = t, every pixel of a
    diagonal at once (its left, upper and upper-left neighbours lie on earlier ones).
    """
    h, w, _ = data.shape
    out = np.zeros_like(data)
    if np.all(filters <= 2):
        prev = np.zeros_like(data[0])
        for r in range(h):
            f = filters[r]
            row = data[r]
            if f == 1:
                row = np.cumsum(row, axis=0)
            elif f == 2:
                row = row + prev
            out[r] = row & 0xFF
            prev = out[r]
        return out
    pad = np.zeros((h + 1, w + 1, data.shape[2]), dtype=np.int32)
    for t in range(h + w - 1):
        r = np.arange(max(0, t - w + 1), min(h, t + 1))
        c = t - r
        x = data[r, c]
        a = pad[r + 1, c]  # left
        b = pad[r, c + 1]  # up
        cc = pad[r, c]  # upper left
        f = filters[r][:, None]
        p = a + b - cc
        pa, pb, pc = np.abs(p - a), np.abs(p - b), np.abs(p - cc)
        paeth = np.where((pa <= pb) & (pa <= pc), a, np.where(pb <= pc, b, cc))
        pred = np.select([f == 1, f == 2, f == 3, f == 4], [a, b, (a + b) >> 1, paeth], 0)
        pad[r + 1, c + 1] = (x + pred) & 0xFF
    out[:] = pad[1:, 1:]
    return out
