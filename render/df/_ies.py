"""IES light profiles (ANSI/IES LM-63): read, write, and the table ``measured_edf`` samples.

The format (LM-63-1995, -2002 and -2019; text, numbers separated by blanks, commas or
line ends, free to wrap)::

    IESNA:LM-63-2002                        version line (optional: LM-63-1986 has none)
    [KEYWORD] value                         keywords (any number)
    TILT=NONE                               or TILT=INCLUDE, then the tilt block:
                                              lamp-to-luminaire geometry, N tilt angles,
                                              N angles, N multiplying factors
    lamps lumens_per_lamp candela_multiplier n_vertical n_horizontal
        photometric_type units width length height
    ballast_factor ballast_lamp_factor input_watts
    n_vertical vertical angles (degrees, increasing)
    n_horizontal horizontal angles (degrees, increasing)
    n_horizontal x n_vertical candela values (one vertical set per horizontal angle)

Photometric type C (1) is read: vertical angles ``gamma`` from the luminaire's nadir (its
downward axis: 0 to 90, 0 to 180, or 90 to 180 for an up-light), horizontal angles ``C``
about it starting at 0 and ending at 0 (rotationally symmetric), 90 (symmetric in each
quadrant), 180 (symmetric about the 0-180 plane) or 360 (no symmetry).  Candela values are
multiplied by the candela multiplier and the ballast factors.  A tilt block is read and
its factors ignored (they matter only for a lamp tilted from the orientation it was
measured in).  Types A and B, tilt files (``TILT=<file>``) and other angle ranges are
errors that say so.

:class:`LightProfile` holds a profile; :func:`read_ies` reads a file (an
:class:`IesError` names the file, the line and what to fix), :func:`write_ies` writes
one; :func:`profile_table` builds the flat table the ``measured_edf`` kernels read
(angles in radians over the full circle, the intensities, the front hemisphere's flux
of the bilinear interpolant in closed form, and a cell table for sampling).
"""

from __future__ import annotations

import math
import re
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

__all__ = ["LightProfile", "IesError", "read_ies", "write_ies", "profile_table",
           "SAMPLE_MU", "SAMPLE_PHI", "TABLE_HEADER"]

#: intervals of the sampling density's grid: in cos(gamma) over the front hemisphere, in C
SAMPLE_MU, SAMPLE_PHI = 48, 72
#: table header: n_vertical, n_horizontal, sample cells in mu and C, 1 / front flux
TABLE_HEADER = 5
#: the largest number of angles read per axis
MAX_ANGLES = 10_000


class IesError(ValueError):
    """A file that is not a readable IES LM-63 profile (``path:line: message; fix``)."""


@dataclass(frozen=True, eq=False)
class LightProfile:
    """A type C photometric profile.

    Parameters
    ----------
    vertical : (nv,) float64
        Vertical angles gamma in degrees from the nadir, increasing.
    horizontal : (nh,) float64
        Horizontal angles C in degrees, increasing, from 0.
    candela : (nh, nv) float64
        Intensities (candela multiplier and ballast factors applied), >= 0.
    name : str
        Where it came from (for messages).
    """

    vertical: np.ndarray = field(repr=False)
    horizontal: np.ndarray = field(repr=False)
    candela: np.ndarray = field(repr=False)
    name: str = "<profile>"

    def __post_init__(self) -> None:
        v = np.asarray(self.vertical, dtype=np.float64)
        h = np.asarray(self.horizontal, dtype=np.float64)
        c = np.asarray(self.candela, dtype=np.float64)
        problem = _check_angles(v, h) or _check_values(c, len(v), len(h))
        if problem:
            raise IesError(f"{self.name}: {problem[0]}; {problem[1]}")
        object.__setattr__(self, "vertical", v)
        object.__setattr__(self, "horizontal", h)
        object.__setattr__(self, "candela", c)

    def intensity(self, gamma_deg, c_deg) -> np.ndarray:
        """The profile's intensity (candela) at vertical angles ``gamma`` and horizontal
        angles ``C`` (degrees; broadcast), bilinear between the grid's angles (the
        kernels' interpolation), 0 outside the vertical range."""
        t = profile_table(self, 1.0)
        g = np.radians(np.asarray(gamma_deg, dtype=np.float64))
        p = np.radians(np.asarray(c_deg, dtype=np.float64))
        g, p = np.broadcast_arrays(g, p)
        out = np.empty(g.shape)
        flat_g, flat_p, flat_o = g.ravel(), p.ravel(), out.reshape(-1)
        from render.df.measured_edf import table_intensity

        for i in range(len(flat_g)):
            flat_o[i] = table_intensity(t, 0, flat_g[i], flat_p[i])
        return out

    @property
    def power(self) -> float:
        """``∫ I dw`` over the whole sphere (candela sr: lumens for a photometric
        profile), of the bilinear interpolant the kernels evaluate: MDL's
        ``df::light_profile_power``."""
        h, c = _full_circle(self.horizontal, self.candela)
        return profile_flux(self.vertical, h, c)

    @property
    def maximum(self) -> float:
        """The largest intensity (candela): MDL's ``df::light_profile_maximum``."""
        return float(self.candela.max())


def _check_angles(v, h):
    """``(problem, fix)`` or None for type C angle grids."""
    if len(v) < 1 or len(h) < 1:
        return "there must be at least one vertical and one horizontal angle", \
            "give the angles the candela values are measured at"
    if not (np.all(np.isfinite(v)) and np.all(np.isfinite(h))):
        return "angles must be finite numbers", "write the angles in degrees"
    if np.any(np.diff(v) <= 0) or np.any(np.diff(h) <= 0):
        return "angles must increase", "list vertical and horizontal angles in increasing order"
    if v[0] not in (0.0, 90.0) or v[-1] not in (90.0, 180.0) or len(v) < 2:
        return (f"type C vertical angles must run from 0 or 90 to 90 or 180 degrees, got "
                f"{v[0]:g} to {v[-1]:g} ({len(v)} angles)",
                "use a type C profile (vertical 0 = nadir) with at least two vertical angles")
    if h[0] != 0.0 or h[-1] not in (0.0, 90.0, 180.0, 360.0):
        return (f"type C horizontal angles must start at 0 and end at 0, 90, 180 or 360 "
                f"degrees, got {h[0]:g} to {h[-1]:g}",
                "give one angle (0) for a rotationally symmetric profile, or 0..90, "
                "0..180, 0..360")
    return None


def _check_values(c, nv, nh):
    if c.shape != (nh, nv):
        return (f"the candela table has shape {c.shape}, not (horizontal, vertical) = "
                f"({nh}, {nv})", "give one vertical set of values per horizontal angle")
    if not np.all(np.isfinite(c)) or np.any(c < 0.0):
        return "candela values must be finite and >= 0", "fix the negative or missing values"
    return None


# ------------------------------------------------------------------------ reading
_NUMBER = re.compile(r"[^\s,]+")


def read_ies(path) -> LightProfile:
    """Read an IES LM-63 file (type C photometry).

    Raises
    ------
    IesError
        ``path:line: what is wrong; how to fix it``.
    """
    path = Path(path)
    name = str(path)
    try:
        raw = path.read_bytes()
    except OSError as e:
        raise IesError(f"{name}: cannot read the file ({e.strerror}); give the path of an "
                       ".ies file") from None
    text = raw.decode("latin-1")
    lines = text.splitlines()

    def fail(line: int, message: str, fix: str):
        raise IesError(f"{name}:{line}: {message}; {fix}")

    if not text.strip():
        fail(1, "the file is empty", "give an IES LM-63 light profile")
    # the version line and keywords, up to TILT=
    k = 0
    while k < len(lines) and not lines[k].strip().upper().startswith("TILT"):
        s = lines[k].strip()
        if k == 0 and (s.upper().startswith("IESNA") or s.upper().startswith("IES:")
                       or not s or s.startswith("[")):
            k += 1
            continue
        if s and not s.startswith("["):
            fail(k + 1, f"expected a [KEYWORD] line or TILT=, got {s[:40]!r}",
                 "an LM-63 header is a version line, [KEYWORD] lines, then TILT=NONE")
        k += 1
    if k == len(lines):
        fail(len(lines), "no TILT= line", "add the line TILT=NONE after the keywords")
    tilt = lines[k].strip()
    m = re.match(r"TILT\s*=\s*(.*)$", tilt, re.IGNORECASE)
    value = (m.group(1).strip() if m else "").upper()
    if value not in ("NONE", "INCLUDE"):
        fail(k + 1, f"TILT={value or '?'} is not read here (a separate tilt file)",
             "use TILT=NONE, or TILT=INCLUDE with the tilt block in the file")
    # the numbers that follow, each with its line
    tokens = []
    for i in range(k + 1, len(lines)):
        tokens.extend((t, i + 1) for t in _NUMBER.findall(lines[i]))
    pos = [0]

    def number(what: str, integer: bool = False):
        if pos[0] >= len(tokens):
            fail(len(lines), f"the file ends before {what}",
                 "the file is cut short: give every value LM-63 lists")
        t, line = tokens[pos[0]]
        pos[0] += 1
        try:
            x = float(t)
        except ValueError:
            fail(line, f"{what}: {t!r} is not a number", "write a decimal number")
        if not math.isfinite(x):
            fail(line, f"{what} is {t}", "write a finite number")
        if integer:
            if x != int(x):
                fail(line, f"{what} must be a whole number, got {t}", "write an integer")
            return int(x), line
        return x, line

    if value == "INCLUDE":
        number("the lamp-to-luminaire geometry", integer=True)
        n_tilt, line = number("the number of tilt angles", integer=True)
        if not 0 <= n_tilt <= MAX_ANGLES:
            fail(line, f"{n_tilt} tilt angles", "give a count from 0 to 10000")
        for j in range(2 * n_tilt):
            number(f"tilt {'angle' if j < n_tilt else 'factor'} {j % max(n_tilt, 1) + 1}")
    number("the number of lamps")
    number("the lumens per lamp")
    multiplier, line = number("the candela multiplier")
    if multiplier < 0:
        fail(line, f"the candela multiplier is {multiplier:g}", "it must be >= 0")
    nv, line_v = number("the number of vertical angles", integer=True)
    nh, line_h = number("the number of horizontal angles", integer=True)
    for n, line, what in ((nv, line_v, "vertical"), (nh, line_h, "horizontal")):
        if not 1 <= n <= MAX_ANGLES:
            fail(line, f"{n} {what} angles", f"give 1 to {MAX_ANGLES} {what} angles")
    ptype, line = number("the photometric type", integer=True)
    if ptype != 1:
        kind = {2: "B", 3: "A"}.get(ptype)
        fail(line, f"photometric type {ptype}" + (f" ({kind})" if kind else "")
             + " is not read here", "use type C photometry (1), the usual for luminaires")
    units, line = number("the units type", integer=True)
    if units not in (1, 2):
        fail(line, f"units type {units}", "1 for feet or 2 for meters")
    for what in ("the luminous opening's width", "its length", "its height"):
        number(what)
    ballast, _ = number("the ballast factor")
    lamp_factor, _ = number("the ballast-lamp photometric factor")
    number("the input watts")
    vertical, v_lines = np.empty(nv), []
    horizontal, h_lines = np.empty(nh), []
    for i in range(nv):
        vertical[i], line = number(f"vertical angle {i + 1} of {nv}")
        v_lines.append(line)
    for i in range(nh):
        horizontal[i], line = number(f"horizontal angle {i + 1} of {nh}")
        h_lines.append(line)
    for values, at, what in ((vertical, v_lines, "vertical"),
                             (horizontal, h_lines, "horizontal")):
        down = np.flatnonzero(np.diff(values) <= 0)
        if len(down):
            i = int(down[0]) + 1
            fail(at[i], f"{what} angles must increase: angle {i + 1} ({values[i]:g}) "
                 f"follows {values[i - 1]:g}", f"list the {what} angles in increasing order")
    problem = _check_angles(vertical, horizontal)
    if problem:
        fail(v_lines[0] if "vertical" in problem[0] else h_lines[0], *problem)
    candela = np.empty((nh, nv))
    for a in range(nh):
        for i in range(nv):
            candela[a, i], line = number(
                f"candela value {a * nv + i + 1} of {nh * nv} (horizontal angle "
                f"{horizontal[a]:g}, vertical {vertical[i]:g})")
            if candela[a, i] < 0:
                fail(line, f"candela value {a * nv + i + 1} is {candela[a, i]:g}",
                     "intensities must be >= 0")
    if pos[0] < len(tokens):
        t, line = tokens[pos[0]]
        fail(line, f"unexpected value {t!r} after the {nh * nv} candela values",
             "check the counts of vertical and horizontal angles on the line after TILT")
    scale = multiplier * ballast * (lamp_factor if lamp_factor > 0 else 1.0)
    return LightProfile(vertical, horizontal, candela * scale, name)


def write_ies(path, vertical, horizontal, candela, *, lumens: float = -1.0,
              keywords: dict | None = None) -> Path:
    """Write a type C profile as an LM-63-2002 file (``candela`` (nh, nv), angles in
    degrees); returns the path."""
    profile = LightProfile(vertical, horizontal, candela, str(path))
    kw = {"TEST": "render.df._ies", "MANUFAC": "pwc-workbench"} | (keywords or {})
    out = ["IESNA:LM-63-2002"] + [f"[{k}] {v}" for k, v in kw.items()] + ["TILT=NONE"]
    nv, nh = len(profile.vertical), len(profile.horizontal)
    out.append(f"1 {lumens:g} 1 {nv} {nh} 1 2 0 0 0")
    out.append("1 1 0")

    def rows(values):
        values = [repr(float(x)) for x in values]
        return [" ".join(values[i:i + 8]) for i in range(0, len(values), 8)]

    out += rows(profile.vertical) + rows(profile.horizontal)
    for a in range(nh):
        out += rows(profile.candela[a])
    path = Path(path)
    path.write_text("\n".join(out) + "\n", encoding="latin-1")
    return path


# ------------------------------------------------------------------------ the table
def _full_circle(h: np.ndarray, c: np.ndarray):
    """Horizontal angles over [0, 360] and their values, by the profile's symmetry."""
    last = h[-1]
    if len(h) == 1:
        return np.array([0.0, 360.0]), np.vstack([c, c])
    if last == 90.0:  # each quadrant mirrors the first
        h2 = np.concatenate([h, 180.0 - h[-2::-1]])
        c2 = np.vstack([c, c[-2::-1]])
        h, c = h2, c2
        last = 180.0
    if last == 180.0:  # mirror about the 0-180 plane
        h = np.concatenate([h, 360.0 - h[-2::-1]])
        c = np.vstack([c, c[-2::-1]])
    return h, c


def _front(v: np.ndarray, c: np.ndarray):
    """The vertical grid cut at 90 degrees (the front hemisphere), a node inserted there."""
    if v[0] >= 90.0:
        return v[:1], c[:, :1]
    if v[-1] <= 90.0:
        return v, c
    j = int(np.searchsorted(v, 90.0))
    if v[j] == 90.0:
        return v[:j + 1], c[:, :j + 1]
    t = (90.0 - v[j - 1]) / (v[j] - v[j - 1])
    mid = c[:, j - 1] * (1 - t) + c[:, j] * t
    return np.concatenate([v[:j], [90.0]]), np.hstack([c[:, :j], mid[:, None]])


def front_flux(v_deg: np.ndarray, h_deg: np.ndarray, c: np.ndarray) -> float:
    """``∫ I dw`` of the bilinear interpolant over gamma <= 90 degrees (:func:`profile_flux`)."""
    v, cc = _front(v_deg, c)
    return profile_flux(v, h_deg, cc)


def profile_flux(v: np.ndarray, h_deg: np.ndarray, cc: np.ndarray) -> float:
    """``∫ I dw`` of the bilinear interpolant (in gamma and C) over the vertical angles
    ``v`` (degrees) and the horizontal angles ``h_deg`` (``cc``: ``(nh, nv)``), in closed
    form per cell (``∫ w(gamma) sin(gamma) dgamma`` of the linear weights)."""
    if len(v) < 2:
        return 0.0
    g = np.radians(v)
    p = np.radians(h_deg)
    ga, gb = g[:-1], g[1:]
    d = gb - ga
    # weights of the lower and upper vertical node: ∫ (gb - x) sin x / d, ∫ (x - ga) sin x / d
    wa = (d * np.cos(ga) - (np.sin(gb) - np.sin(ga))) / d
    wb = (-d * np.cos(gb) + (np.sin(gb) - np.sin(ga))) / d
    dp = np.diff(p)
    # C is linear between its nodes: each contributes half the interval
    per_c = 0.5 * (cc[:-1] + cc[1:]) * dp[:, None]  # (nh - 1, nv) ∫ dC per vertical node
    lower = per_c[:, :-1] * wa[None, :]
    upper = per_c[:, 1:] * wb[None, :]
    return float(np.sum(lower) + np.sum(upper))


def profile_table(profile: LightProfile, multiplier: float = 1.0) -> np.ndarray:
    """The flat table the ``measured_edf`` kernels read.

    Layout: ``[nv, nh, SAMPLE_MU, SAMPLE_PHI, multiplier / flux]``, then the vertical
    angles (radians, ``nv``), the horizontal angles over the full circle (radians,
    ``nh``), the intensities (``nv x nh``, vertical-major), the sampling density's node
    values (``(SAMPLE_MU + 1) x (SAMPLE_PHI + 1)``, bilinear between them in
    ``cos gamma`` and ``C``), the running sums of its ``SAMPLE_MU`` bands, and its
    integral.

    ``flux`` is the profile's front-hemisphere flux (gamma <= 90): the edf
    ``multiplier I / (flux cos)`` emits ``multiplier`` per unit intensity of the
    material.  A profile with no light below 90 degrees is an error.
    """
    h, c = _full_circle(profile.horizontal, profile.candela)
    v = profile.vertical
    flux = front_flux(v, h, c)
    if not flux > 0.0:
        raise IesError(f"{profile.name}: the profile sends no light below the horizontal "
                       "(vertical angles 0 to 90 degrees, the emitting side); an up-light "
                       "emits from a surface's back: turn the emitter over")
    nv, nh = len(v), len(h)
    m, q = SAMPLE_MU, SAMPLE_PHI
    head = np.array([nv, nh, m, q, multiplier / flux], dtype=np.float64)
    body = np.concatenate([np.radians(v), np.radians(h), c.T.ravel()])
    size = (m + 1) * (q + 1) + m + 1
    table = np.concatenate([head, body, np.zeros(size)])
    # sampling: a density bilinear between nodes uniform in mu = cos(gamma) over [0, 1]
    # and C over [0, 2 pi] (continuous), the intensity at the nodes plus a floor (no
    # direction that may emit has density 0)
    from render.df.measured_edf import table_intensity

    nodes = np.empty((m + 1, q + 1))
    for i in range(m + 1):
        gamma = math.acos(i / m)
        for j in range(q):
            nodes[i, j] = table_intensity(table, 0, gamma, 2 * math.pi * j / q)
    nodes[:, q] = nodes[:, 0]
    nodes += 1e-3 * max(float(nodes.mean()), 1e-300)
    row = 0.5 * (nodes[:, :-1] + nodes[:, 1:]).sum(axis=1)  # ∫ dC per mu node / dC
    band = 0.5 * (row[:-1] + row[1:])
    off = TABLE_HEADER + nv + nh + nv * nh
    table[off:off + (m + 1) * (q + 1)] = nodes.ravel()
    cdf = np.cumsum(band) / band.sum()
    cdf[-1] = 1.0
    table[off + (m + 1) * (q + 1):off + (m + 1) * (q + 1) + m] = cdf
    # the density's normaliser: ∫ bilinear dmu dC
    table[off + (m + 1) * (q + 1) + m] = float(band.sum()) * (1.0 / m) * (2 * math.pi / q)
    return table
