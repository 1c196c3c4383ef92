"""MBSDF files (MDL 1.10 spec, Appendix B): read, write, and the tables ``measured_bsdf`` samples.

The format, version 1: a text header, then one or two binary data blocks::

    NVIDIA ARC MBSDF V1\\n                      magic identifier (20 bytes)
    key="value"\\n ...                          meta-data (zero or more lines)
    MBSDF_DATA_REFLECTION=\\n (or MBSDF_DATA=\\n) a BRDF block, and/or
    MBSDF_DATA_TRANSMISSION=\\n                 a BTDF block (after the BRDF block):
        uint32 T        0: one float per measurement (scalar), 1: three (sRGB)
        uint32 n_theta  > 0, equi-spaced steps of theta_i and theta_o over [0, pi/2]
        uint32 n_phi    > 0, equi-spaced steps of phi (the azimuth difference) over [0, pi]
        float32 data[n_theta * n_theta * n_phi * (1 or 3)],
            offset(i, o, p) = i * n_phi * n_theta + o * n_phi + p

all little-endian.  Each value is the BSDF ``f`` (without the cosine) for the incoming
(light) direction at ``theta_i`` and the outgoing (view) direction at ``theta_o``,
``phi`` apart in azimuth; transmission measures ``theta_i`` from the far side.

**Reading the grid** (the spec names the ranges and step counts, not where the steps
sit): here ``n`` steps include both ends, ``theta_k = k (pi/2) / (n_theta - 1)``,
``phi_k = k pi / (n_phi - 1)`` (one step: constant along that axis); ``f`` is trilinear
between them.

:class:`Measurement` holds the data; :func:`read_mbsdf` and :func:`write_mbsdf` convert
files; :func:`measurement_table` builds the flat table the ``measured_bsdf`` kernels read
(the data of each part, its cell CDFs for sampling per ``theta_o`` node, and its albedo
per ``theta_o`` node by quadrature of the interpolant).  A malformed file raises
:class:`MbsdfError` naming the file, the byte offset and what to fix.
"""

from __future__ import annotations

import struct
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

__all__ = ["Measurement", "MbsdfError", "read_mbsdf", "write_mbsdf", "measurement_table",
           "MAGIC", "TABLE_HEADER"]

MAGIC = b"NVIDIA ARC MBSDF V1\n"
_BLOCKS = {b"MBSDF_DATA_REFLECTION=\n": "reflection", b"MBSDF_DATA=\n": "reflection",
           b"MBSDF_DATA_TRANSMISSION=\n": "transmission"}
#: the largest resolution read (the data of one part is n_theta^2 n_phi values)
MAX_STEPS = 1024


class MbsdfError(ValueError):
    """A file that is not a valid MBSDF measurement (the message names the file)."""


@dataclass(frozen=True, eq=False)
class Measurement:
    """A measured BSDF: per part, ``(n_theta, n_theta, n_phi, 3)`` float64 values of ``f``
    (index order theta_i, theta_o, phi; scalar data repeated over the channels), or None.

    Parameters
    ----------
    reflection, transmission : (n_theta, n_theta, n_phi, 3) float64 or None
    name : str
        Where it came from (for messages).
    metadata : dict
    """

    reflection: np.ndarray | None = field(repr=False)
    transmission: np.ndarray | None = field(repr=False)
    name: str = "measurement"
    metadata: dict = field(default_factory=dict)

    def __post_init__(self) -> None:
        for part in ("reflection", "transmission"):
            a = getattr(self, part)
            if a is None:
                continue
            a = np.asarray(a, dtype=np.float64)
            if a.ndim == 3:
                a = np.repeat(a[..., None], 3, axis=3)
            if a.ndim != 4 or a.shape[0] != a.shape[1] or a.shape[3] != 3 or 0 in a.shape:
                raise MbsdfError(f"{self.name}: the {part} data must have shape (n_theta, "
                                 f"n_theta, n_phi[, 3]), got {np.shape(getattr(self, part))}")
            if not np.all(np.isfinite(a)) or np.any(a < 0.0):
                raise MbsdfError(f"{self.name}: the {part} data must be finite and >= 0 (a "
                                 "BSDF value); fix the measurement")
            object.__setattr__(self, part, a)
        if self.reflection is None and self.transmission is None:
            raise MbsdfError(f"{self.name}: the file holds no data block; it needs "
                             "MBSDF_DATA_REFLECTION= and/or MBSDF_DATA_TRANSMISSION=")


def read_mbsdf(path) -> Measurement:
    """Read an MBSDF file (:class:`MbsdfError` on anything malformed)."""
    path = Path(path)
    try:
        raw = path.read_bytes()
    except OSError as e:
        raise MbsdfError(f"{path}: cannot read the measurement ({e.strerror or e})") from None
    return parse_mbsdf(raw, str(path))


def parse_mbsdf(raw: bytes, name: str = "measurement") -> Measurement:
    """:func:`read_mbsdf` of the file's bytes."""
    if not raw.startswith(MAGIC):
        raise MbsdfError(f"{name}: not an MBSDF file: it must start with "
                         f"'NVIDIA ARC MBSDF V1' and a newline (the MDL spec, Appendix B)")
    at = len(MAGIC)
    metadata = {}
    parts = {}
    while at < len(raw):
        end = raw.find(b"\n", at)
        if end < 0:
            raise MbsdfError(f"{name}: byte {at}: a header line without its newline; the file "
                             "is truncated")
        line = raw[at:end + 1]
        if line in _BLOCKS:
            part = _BLOCKS[line]
            if part in parts:
                raise MbsdfError(f"{name}: byte {at}: a second {part} block")
            if part == "reflection" and "transmission" in parts:
                raise MbsdfError(f"{name}: byte {at}: the reflection block must come before "
                                 "the transmission block")
            parts[part], at = _block(raw, end + 1, name, part)
            continue
        if parts:
            raise MbsdfError(f"{name}: byte {at}: expected a data block "
                             "(MBSDF_DATA_REFLECTION= or MBSDF_DATA_TRANSMISSION=), got "
                             f"{line[:40]!r}")
        text = line[:-1].decode("ascii", errors="replace")
        key, eq, value = text.partition("=")
        if not eq or not (value.startswith('"') and value.endswith('"') and len(value) >= 2):
            raise MbsdfError(f"{name}: byte {at}: a header line must be key=\"value\" or a data "
                             f"block identifier, got {text[:60]!r}")
        metadata[key] = (value[1:-1].replace('\\"', '"').replace("\\n", "\n")
                         .replace("\\\\", "\\"))
        at = end + 1
    return Measurement(parts.get("reflection"), parts.get("transmission"), name, metadata)


def _block(raw: bytes, at: int, name: str, part: str) -> tuple[np.ndarray, int]:
    if len(raw) < at + 12:
        raise MbsdfError(f"{name}: byte {at}: the {part} block ends before its type and "
                         "resolution (3 uint32); the file is truncated")
    kind, n_theta, n_phi = struct.unpack_from("<3I", raw, at)
    if kind > 1:
        raise MbsdfError(f"{name}: byte {at}: the {part} block's type is {kind}; it must be 0 "
                         "(scalar) or 1 (RGB)")
    if not (0 < n_theta <= MAX_STEPS and 0 < n_phi <= MAX_STEPS):
        raise MbsdfError(f"{name}: byte {at + 4}: the {part} block's resolution is "
                         f"{n_theta} x {n_phi}; both must be in 1..{MAX_STEPS}")
    channels = 3 if kind == 1 else 1
    count = n_theta * n_theta * n_phi * channels
    start = at + 12
    if len(raw) < start + 4 * count:
        raise MbsdfError(f"{name}: byte {start}: the {part} block needs {count} float32 values "
                         f"({n_theta} x {n_theta} x {n_phi} x {channels}) but the file has "
                         f"{(len(raw) - start) // 4}; it is truncated")
    data = np.frombuffer(raw, dtype="<f4", count=count, offset=start).astype(np.float64)
    data = data.reshape(n_theta, n_theta, n_phi, channels)
    if channels == 1:
        data = np.repeat(data, 3, axis=3)
    if not np.all(np.isfinite(data)) or np.any(data < 0.0):
        raise MbsdfError(f"{name}: the {part} block holds negative or non-finite values; a "
                         "BSDF value is finite and >= 0")
    return data, start + 4 * count


def write_mbsdf(path, reflection=None, transmission=None, metadata=None, rgb=None) -> Path:
    """Write an MBSDF file from ``(n_theta, n_theta, n_phi)`` (scalar) or
    ``(n_theta, n_theta, n_phi, 3)`` (RGB) arrays of ``f`` (see the module docstring)."""
    path = Path(path)
    out = bytearray(MAGIC)
    for k, v in (metadata or {}).items():
        text = str(v).replace("\\", "\\\\").replace('"', '\\"').replace("\n", "\\n")
        out += f'{k}="{text}"\n'.encode("ascii")
    for ident, data in ((b"MBSDF_DATA_REFLECTION=\n", reflection),
                        (b"MBSDF_DATA_TRANSMISSION=\n", transmission)):
        if data is None:
            continue
        a = np.asarray(data, dtype=np.float64)
        colour = a.ndim == 4 if rgb is None else rgb
        if a.ndim == 3 and colour:
            a = np.repeat(a[..., None], 3, axis=3)
        out += ident + struct.pack("<3I", 1 if colour else 0, a.shape[0], a.shape[2])
        out += np.ascontiguousarray(a, dtype="<f4").tobytes()
    path.write_bytes(bytes(out))
    return path


# --- the kernels' table ---------------------------------------------------------------------
#: header slots: n_theta, n_phi, offset of each part (or -1), scale slot (set per node)
TABLE_HEADER = 5


def _grid(n: int, hi: float) -> np.ndarray:
    return np.linspace(0.0, hi, n) if n > 1 else np.array([0.0, hi])


def _interp_axis(n: int, hi: float, x: np.ndarray):
    """Indices and weights of ``x`` on the step grid of ``n`` nodes over [0, hi]."""
    if n == 1:
        return np.zeros_like(x, dtype=int), np.zeros_like(x, dtype=int), np.zeros_like(x)
    t = np.clip(x / hi * (n - 1), 0.0, n - 1)
    j = np.minimum(np.floor(t).astype(int), n - 2)
    return j, j + 1, t - j


def _f(data: np.ndarray, ti, to, ph) -> np.ndarray:
    """Trilinear ``f`` at arrays of angles (the kernels' interpolation, in numpy)."""
    nt, _, nphi, _ = data.shape
    i0, i1, fi = _interp_axis(nt, np.pi / 2, ti)
    o0, o1, fo = _interp_axis(nt, np.pi / 2, to)
    p0, p1, fp = _interp_axis(nphi, np.pi, ph)
    out = 0.0
    for ii, wi in ((i0, 1 - fi), (i1, fi)):
        for oo, wo in ((o0, 1 - fo), (o1, fo)):
            for pp, wp in ((p0, 1 - fp), (p1, fp)):
                out = out + (wi * wo * wp)[..., None] * data[ii, oo, pp]
    return out


def _part_table(data: np.ndarray, order: int = 6) -> tuple[np.ndarray, float]:
    """One part's block: data, then per theta_o node the cell CDF (luminance-free channel
    mean) and the RGB albedo; returns the block and the part's largest albedo."""
    nt, _, nphi, _ = data.shape
    tg = _grid(nt, np.pi / 2)
    pg = _grid(nphi, np.pi)
    x, w = np.polynomial.legendre.leggauss(order)
    x, w = 0.5 * (x + 1.0), 0.5 * w
    cells = (len(tg) - 1) * (len(pg) - 1)
    cdfs = np.zeros((nt, cells))
    albedo = np.zeros((nt, 3))
    for o in range(nt):
        to = tg[o] if nt > 1 else 0.0
        masses = np.zeros((cells, 3))
        for a in range(len(tg) - 1):
            # cos theta_i uniform in the cell: integrate f cos over d(cos) d(phi), both signs
            c_hi, c_lo = np.cos(tg[a]), np.cos(tg[a + 1])
            cs = c_lo + (c_hi - c_lo) * x
            ti = np.arccos(np.clip(cs, -1.0, 1.0))
            for bb in range(len(pg) - 1):
                ph = pg[bb] + (pg[bb + 1] - pg[bb]) * x
                T, Pp = np.meshgrid(ti, ph, indexing="ij")
                C = np.cos(T)
                W = np.outer(w, w) * (c_hi - c_lo) * (pg[bb + 1] - pg[bb]) * 2.0
                fv = _f(data, T, np.full_like(T, to), Pp)
                masses[a * (len(pg) - 1) + bb] = np.einsum("ij,ijc->c", W * C, fv)
        albedo[o] = masses.sum(axis=0)
        m = masses.mean(axis=1)
        total = m.sum()
        cdfs[o] = np.cumsum(m) / total if total > 0 else np.linspace(1.0 / cells, 1.0, cells)
    block = np.concatenate([data.ravel(), cdfs.ravel(), albedo.ravel()])
    return block, float(albedo.max())


def measurement_table(m: Measurement) -> tuple[np.ndarray, float, float]:
    """The flat table of ``measured_bsdf``'s kernels and the parts' largest albedos.

    Layout: ``[n_theta, n_phi, reflection offset, transmission offset, scale]`` (offsets
    from the table's start, -1 for a missing part; ``scale`` is written per node by the
    df class), then per part: ``f`` ``(n_theta, n_theta, n_phi, 3)``, the cell CDFs
    ``(n_theta, cells)`` (cells ``max(n_theta - 1, 1) x max(n_phi - 1, 1)``, the
    interpolant's ``f cos`` integrated over each cell, both azimuth signs), and the RGB
    albedo per ``theta_o`` node ``(n_theta, 3)``.
    """
    shapes = {a.shape[:3] for a in (m.reflection, m.transmission) if a is not None}
    if len(shapes) > 1:
        raise MbsdfError(f"{m.name}: the reflection and transmission blocks have different "
                         f"resolutions {sorted(shapes)}; this reader needs one")
    nt, _, nphi = shapes.pop()
    head = np.array([nt, nphi, -1.0, -1.0, 1.0])
    parts, at, maxima = [head], TABLE_HEADER, [0.0, 0.0]
    for k, data in enumerate((m.reflection, m.transmission)):
        if data is None:
            continue
        block, amax = _part_table(data)
        head[2 + k] = at
        parts.append(block)
        at += len(block)
        maxima[k] = amax
    table = np.concatenate(parts)
    return table, maxima[0], maxima[1]
