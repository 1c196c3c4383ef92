"""The film: accumulates samples per pixel and writes linear EXR (RGBA + AOVs) and sRGB PNG.

Pixel samples are box-filtered (each sample counts for the pixel it was drawn in, as
Mitsuba's ``box`` filter).  Besides colour and alpha the film keeps arbitrary output
variables (AOVs) averaged over a pixel's samples: ``albedo`` (RGB, the BSDF's
directional albedo at the first visible surface), ``normal`` (world-space shading
normal), ``depth`` (distance along the camera's viewing axis; 0 where nothing was hit),
``uv`` (texture coordinates) and ``object_id`` (the index of the object seen by the
pixel's first sample, -1 for none; not averaged).

EXR layout (OpenEXR 3.x API): channels ``R, G, B, A`` and one layer per AOV:
``albedo.R/G/B``, ``normal.X/Y/Z``, ``depth.Z``, ``uv.U/V``, ``object_id.id``.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

__all__ = ["Film", "FilmPatch", "AOVS", "FilmTooLarge", "available_memory",
           "check_film_memory", "empty_aovs", "film_bytes", "linear_to_srgb", "read_exr",
           "write_exr_channels", "write_png_rgb"]

#: the AOVs a film can keep, and their channel names in the EXR.
AOVS = {
    "albedo": ("R", "G", "B"),
    "normal": ("X", "Y", "Z"),
    "depth": ("Z",),
    "uv": ("U", "V"),
    "object_id": ("id",),
}


def linear_to_srgb(x: np.ndarray) -> np.ndarray:
    """The sRGB transfer function (IEC 61966-2-1) of linear values clamped to [0, 1].

    Examples
    --------
    >>> np.round(linear_to_srgb(np.array([0.0, 0.0031308, 0.5, 1.0, 7.0])), 6).tolist()
    [0.0, 0.04045, 0.735357, 1.0, 1.0]
    """
    x = np.clip(np.nan_to_num(np.asarray(x, dtype=np.float64)), 0.0, 1.0)
    return np.where(x <= 0.0031308, 12.92 * x, 1.055 * np.power(x, 1.0 / 2.4) - 0.055)


#: bytes per pixel a render holds at its peak, measured with tracemalloc (1024^2): the
#: film's sums (colour 24, alpha 8, count 8, object id 5) plus the largest transient, the
#: sRGB preview made from them (100); each AOV channel adds its sum (8), its float32
#: EXR copy and read-out (8), and its sum in the patch a chunk is merged from (8, since
#: Film.add merges a FilmPatch); denoising adds its float32 colour, guides and output (48)
FILM_BYTES = 45 + 100
AOV_CHANNEL_BYTES = 24
DENOISE_BYTES = 48


class FilmTooLarge(ValueError):
    """An image too large for this machine's memory (raised before any work starts)."""


def film_bytes(width: int, height: int, aovs=(), denoise: bool = False) -> int:
    """Peak bytes a ``width`` x ``height`` render and its outputs need (besides the scene).

    Examples
    --------
    >>> film_bytes(1, 1), film_bytes(16384, 16384) / 2**30
    (145, 36.25)
    """
    per_pixel = FILM_BYTES + AOV_CHANNEL_BYTES * sum(len(AOVS[a]) for a in aovs if a in AOVS)
    return int(width) * int(height) * (per_pixel + (DENOISE_BYTES if denoise else 0))


def available_memory() -> int | None:
    """Bytes this process may still allocate: the kernel's ``MemAvailable``, capped by a
    cgroup (container) limit; None where neither can be read (then nothing is refused)."""
    found = []
    try:
        with open("/proc/meminfo") as f:
            for line in f:
                if line.startswith("MemAvailable:"):
                    found.append(int(line.split()[1]) * 1024)
    except (OSError, ValueError, IndexError):
        pass
    try:
        limit = Path("/sys/fs/cgroup/memory.max").read_text().strip()
        used = Path("/sys/fs/cgroup/memory.current").read_text().strip()
        if limit != "max":
            found.append(int(limit) - int(used))
    except (OSError, ValueError):
        pass
    return min(found) if found else None


def check_film_memory(width: int, height: int, aovs=(), denoise: bool = False,
                      available: int | None = None) -> int:
    """Refuse, with :class:`FilmTooLarge`, an image whose film would not fit in memory.

    ``available`` defaults to :func:`available_memory`.  Returns the bytes needed.
    """
    need = film_bytes(width, height, aovs, denoise)
    available = available_memory() if available is None else available
    if available is not None and need > available:
        gb = 2.0**30
        raise FilmTooLarge(
            f"a {width} x {height} image needs about {need / gb:.1f} GB for its film and "
            f"outputs, but only {available / gb:.1f} GB of memory is available; render it "
            f"smaller (--resolution W H, or resolution = [w, h] in [render]), with fewer AOVs, "
            f"or on a machine with more memory")
    return need


class Film:
    """Sums of samples per pixel.

    Parameters
    ----------
    width, height : int
    aovs : iterable of str
        Names from :data:`AOVS` to keep.

    Examples
    --------
    >>> f = Film(2, 1)
    >>> f.add(np.array([0, 0, 1]), np.array([[1.0, 0, 0], [3.0, 0, 0], [0, 0, 2.0]]), np.ones(3))
    >>> f.rgb()[0].tolist(), f.spp.tolist()
    ([[2.0, 0.0, 0.0], [0.0, 0.0, 2.0]], [[2, 1]])
    """

    def __init__(self, width: int, height: int, aovs=()):
        self.width, self.height = int(width), int(height)
        unknown = set(aovs) - set(AOVS)
        if unknown:
            raise ValueError(f"unknown AOV {sorted(unknown)[0]!r}: choose from {', '.join(AOVS)}")
        self.aov_names = [a for a in AOVS if a in set(aovs)]
        check_film_memory(self.width, self.height, self.aov_names)
        n = self.width * self.height
        self._rgb = np.zeros((n, 3))
        self._alpha = np.zeros(n)
        self._count = np.zeros(n, dtype=np.int64)
        self._aov = {a: np.zeros((n, len(AOVS[a]))) for a in self.aov_names if a != "object_id"}
        self._object_id = np.full(n, -1, dtype=np.int32)
        self._object_id_set = np.zeros(n, dtype=bool)
        #: render statistics (filled by the integrator)
        self.stats: dict = {}
        self._denoised: np.ndarray | None = None

    @property
    def pixel_count(self) -> int:
        return self.width * self.height

    @property
    def spp(self) -> np.ndarray:
        """(h, w) int64: samples accumulated per pixel."""
        return self._count.reshape(self.height, self.width).copy()

    def add(
        self, pixel: np.ndarray, rgb: np.ndarray, alpha: np.ndarray, aovs: dict | None = None
    ) -> None:
        """Accumulate samples.

        Parameters
        ----------
        pixel : (n,) int64
            Pixel indices ``y * width + x``.
        rgb : (n, 3) float64
            Radiance; non-finite values are counted as 0 (and reported in ``stats``).
        alpha : (n,) float64
        aovs : dict, optional
            Name -> (n, k) values; ``object_id`` -> (n,) ints (kept from the pixel's
            first added sample).
        """
        self.merge(FilmPatch.of_samples(pixel, rgb, alpha, aovs, self.aov_names))

    def merge(self, patch: FilmPatch) -> None:
        """Add a :class:`FilmPatch` (the sums of a batch of samples over its pixel range).

        Merging the patches of batches in the order they were drawn gives the same bits
        as adding the batches' samples in that order: a patch holds each pixel's sum of
        the batch, summed in the batch's order, and the film adds it once.
        """
        start, stop = patch.start, patch.start + len(patch.count)
        if stop > self.pixel_count or start < 0:
            raise ValueError(
                f"the patch covers pixels {start}..{stop - 1}, the film has {self.pixel_count}"
            )
        if patch.nonfinite:
            self.stats["nonfinite_samples"] = (
                self.stats.get("nonfinite_samples", 0) + patch.nonfinite
            )
        span = slice(start, stop)
        self._rgb[span] += patch.rgb
        self._alpha[span] += patch.alpha
        self._count[span] += patch.count
        for name, acc in self._aov.items():
            if name in patch.aov:
                acc[span] += patch.aov[name]
        if "object_id" in self.aov_names and patch.object_id is not None:
            new = (patch.object_id_set & ~self._object_id_set[span]).nonzero()[0] + start
            self._object_id[new] = patch.object_id[new - start]
            self._object_id_set[new] = True
        self._denoised = None

    def _mean(self, acc: np.ndarray) -> np.ndarray:
        c = np.maximum(self._count, 1).astype(np.float64)
        return acc / (c[:, None] if acc.ndim == 2 else c)

    def rgb(self) -> np.ndarray:
        """(h, w, 3) float64: mean radiance per pixel (the denoised one after :meth:`denoise`)."""
        if self._denoised is not None:
            return self._denoised.copy()
        return self._mean(self._rgb).reshape(self.height, self.width, 3)

    def alpha(self) -> np.ndarray:
        """(h, w) float64: mean coverage (1 where a surface was hit, 0 for the background)."""
        return self._mean(self._alpha).reshape(self.height, self.width)

    def aov(self, name: str) -> np.ndarray:
        """(h, w, k) float64 (``object_id``: (h, w) int32) of an AOV this film keeps."""
        if name not in self.aov_names:
            raise ValueError(
                f"this film does not keep the AOV {name!r} (it keeps {self.aov_names})"
            )
        if name == "object_id":
            return self._object_id.reshape(self.height, self.width).copy()
        return self._mean(self._aov[name]).reshape(self.height, self.width, -1)

    def denoise(self) -> np.ndarray:
        """Denoise the colour with Open Image Denoise (``pyoidn``), guided by the albedo and
        normal AOVs when the film keeps them; afterwards :meth:`rgb` returns the result.

        Raises
        ------
        ImportError
            ``pyoidn`` is not installed (``pip install pyoidn``).
        """
        try:
            import pyoidn
        except ImportError:
            raise ImportError("denoising needs Open Image Denoise: pip install pyoidn") from None
        self._denoised = None
        color = np.ascontiguousarray(self.rgb(), dtype=np.float32)
        kw = {}
        if "albedo" in self.aov_names:
            kw["albedo"] = np.ascontiguousarray(np.clip(self.aov("albedo"), 0, 1), dtype=np.float32)
            if "normal" in self.aov_names:
                kw["normal"] = np.ascontiguousarray(self.aov("normal"), dtype=np.float32)
        out = pyoidn.denoise(color, hdr=True, quality="high", **kw)
        self._denoised = np.nan_to_num(np.asarray(out, dtype=np.float64)).reshape(
            self.height, self.width, 3
        )
        return self._denoised.copy()

    # ------------------------------------------------------------------------- output
    def write_exr(self, path, aovs=None, half: bool = False) -> None:
        """Write linear RGBA and AOV layers to an OpenEXR file (ZIP compression).

        Parameters
        ----------
        path : str or Path
        aovs : list of str or None
            Which kept AOVs to write (None: all kept).
        half : bool
            Store colour and AOVs as 16-bit half floats (object ids stay 32-bit floats).
        """
        names = self.aov_names if aovs is None else list(aovs)
        dt = np.float16 if half else np.float32
        rgb = self.rgb()
        channels = {
            "R": rgb[..., 0].astype(dt),
            "G": rgb[..., 1].astype(dt),
            "B": rgb[..., 2].astype(dt),
            "A": self.alpha().astype(dt),
        }
        for name in names:
            val = self.aov(name)
            if name == "object_id":
                channels["object_id.id"] = val.astype(np.float32)
                continue
            for c, ch in enumerate(AOVS[name]):
                channels[f"{name}.{ch}"] = np.ascontiguousarray(val[..., c]).astype(dt)
        write_exr_channels(path, channels)

    def write_png(self, path, exposure: float = 0.0) -> None:
        """Write an 8-bit sRGB preview (colour times ``2**exposure``, clamped)."""
        write_png_rgb(path, self.rgb(), exposure)


def write_exr_channels(path, channels: dict) -> None:
    """Write named (h, w) channels (``R``, ``G``, ``B``, ``A``, ``layer.X``...) to an
    OpenEXR file, ZIP-compressed, in the dtype each array has (float16 or float32)."""
    import OpenEXR

    channels = {k: np.ascontiguousarray(v) for k, v in channels.items()}
    hdr = {"compression": OpenEXR.ZIP_COMPRESSION, "type": OpenEXR.scanlineimage}
    Path(path).parent.mkdir(parents=True, exist_ok=True)
    with OpenEXR.File(hdr, channels) as f:
        f.write(str(path))


def write_png_rgb(path, rgb: np.ndarray, exposure: float = 0.0) -> None:
    """Write linear (h, w, 3) colour as an 8-bit sRGB PNG (times ``2**exposure``, clamped)."""
    from PIL import Image

    img = linear_to_srgb(np.asarray(rgb) * 2.0**exposure)
    Path(path).parent.mkdir(parents=True, exist_ok=True)
    Image.fromarray(np.round(img * 255.0).astype(np.uint8), "RGB").save(str(path))



@dataclass(frozen=True)
class FilmPatch:
    """The per-pixel sums of one batch of samples over the pixel range it touches.

    What a chunk of the image sends back (:mod:`render.passes`): ``count`` pixels from
    ``start`` on, not one row per sample, so a chunk of ``k`` samples per pixel ships
    ``k`` times less than its samples, and merging it into a :class:`Film` touches only
    its range.

    Attributes
    ----------
    start : int
        First pixel (index ``y * width + x``).
    rgb : (m, 3) float64
        Sums of finite radiance samples (non-finite ones count as 0).
    alpha : (m,) float64
    count : (m,) int64
        Samples per pixel.
    aov : dict
        Name -> (m, k) float64 sums, for the averaged AOVs kept.
    object_id : (m,) int32 or None
        The id of each pixel's first sample in the batch (``object_id`` kept).
    object_id_set : (m,) bool or None
        Which pixels had a sample with an id.
    nonfinite : int
        Samples whose radiance was not finite.
    """

    start: int
    rgb: np.ndarray
    alpha: np.ndarray
    count: np.ndarray
    aov: dict = field(default_factory=dict)
    object_id: np.ndarray | None = None
    object_id_set: np.ndarray | None = None
    nonfinite: int = 0

    @classmethod
    def of_samples(
        cls, pixel: np.ndarray, rgb: np.ndarray, alpha: np.ndarray, aovs: dict | None, keep
    ) -> FilmPatch:
        """The patch of a batch of samples (:meth:`Film.add` takes the same arguments),
        keeping the AOVs named in ``keep``.

        Examples
        --------
        >>> p = FilmPatch.of_samples(np.array([3, 3, 4]), np.ones((3, 3)), np.ones(3), None, ())
        >>> p.start, p.count.tolist(), p.rgb[:, 0].tolist()
        (3, [2, 1], [2.0, 1.0])
        """
        pixel = np.asarray(pixel, dtype=np.int64)
        rgb = np.asarray(rgb, dtype=np.float64)
        start = int(pixel.min()) if len(pixel) else 0
        local = pixel - start
        m = int(local.max()) + 1 if len(pixel) else 0
        bad = ~np.all(np.isfinite(rgb), axis=1)
        nonfinite = int(bad.sum())
        if nonfinite:
            rgb = np.where(bad[:, None], 0.0, rgb)
        sums = np.stack([np.bincount(local, rgb[:, c], minlength=m) for c in range(3)], axis=1)
        aovs = aovs or {}
        aov = {}
        for name in keep:
            if name != "object_id" and name in aovs:
                k = len(AOVS[name])
                val = np.asarray(aovs[name], dtype=np.float64).reshape(len(pixel), k)
                aov[name] = np.stack(
                    [np.bincount(local, val[:, c], minlength=m) for c in range(k)], axis=1
                ).reshape(m, k)
        object_id = object_id_set = None
        if "object_id" in keep and "object_id" in aovs:
            ids = np.asarray(aovs["object_id"], dtype=np.int32)
            # the first sample of each pixel in this batch
            first = np.unique(local, return_index=True)[1]
            object_id = np.full(m, -1, dtype=np.int32)
            object_id_set = np.zeros(m, dtype=bool)
            object_id[local[first]] = ids[first]
            object_id_set[local[first]] = True
        return cls(
            start,
            sums,
            np.bincount(local, np.asarray(alpha, dtype=np.float64), minlength=m),
            np.bincount(local, minlength=m).astype(np.int64),
            aov,
            object_id,
            object_id_set,
            nonfinite,
        )

    @property
    def nbytes(self) -> int:
        """Bytes of its arrays (what a chunk's result weighs on the wire)."""
        arrays = [self.rgb, self.alpha, self.count, *self.aov.values()]
        arrays += [a for a in (self.object_id, self.object_id_set) if a is not None]
        return sum(a.nbytes for a in arrays)


def read_exr(path) -> dict[str, np.ndarray]:
    """Channels of an EXR file as float arrays: ``"RGBA"`` -> (h, w, 4) (or ``"RGB"``), and
    each other channel by its full name (``"albedo.R"``...) -> (h, w).

    Parameters
    ----------
    path : str or Path
    """
    import OpenEXR

    with OpenEXR.File(str(path), separate_channels=True) as f:
        ch = f.channels()
        out = {name: np.asarray(c.pixels, dtype=np.float64) for name, c in ch.items()}
    if all(k in out for k in "RGB"):
        keys = [k for k in "RGBA" if k in out]
        out["RGBA" if "A" in out else "RGB"] = np.stack([out[k] for k in keys], axis=-1)
    return out


def empty_aovs(n: int) -> dict:
    """Every AOV layer (:data:`AOVS`) for ``n`` samples before any hit; the tracer fills
    them at first hits (:func:`render.path.trace`'s ``aov`` rows, which
    :meth:`render.integrator.Integrator.trace` returns as these layers)."""
    return {
        "albedo": np.zeros((n, 3)),
        "normal": np.zeros((n, 3)),
        "depth": np.zeros(n),
        "uv": np.zeros((n, 2)),
        "object_id": np.full(n, -1, dtype=np.int32),
    }
