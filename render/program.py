"""Materials as programs: a df tree flattened to nodes that one compiled interpreter runs.

A bound distribution function (one df, or a tree of layers, mixes and modifiers over
elemental dfs) is a :class:`Program`, as Blender Cycles' shader virtual machine runs a
node graph compiled to a linear program, and the MDL SDK compiles a material instance
to target code:

* ``code`` (N, NCOL) int64: the nodes in **postorder** (children before their parent,
  the root last, every subtree a contiguous range).  Columns: :data:`OP` (the opcode:
  which df), :data:`BASE` (its first parameter slot), :data:`FRAME` (the frame its
  directions are expressed in), :data:`NKIDS` and :data:`KID0` (its children, a range
  of ``kids``; -1 is MDL's black ``bsdf()``), :data:`FLAGS` (uniform enums:
  :mod:`render.df._signature`), :data:`LFRAME` (a layer's frame for its ``layer``
  child), :data:`TABLE` (a curve layer's Ĉ table: offset in ``tables``, or
  :data:`CHAT_NONE`), :data:`SIZE` (nodes in its subtree).
* ``P`` (rows, S) float64: every node's parameters packed by its df's
  :class:`~render.df._signature.Signature` (clamped), one row per lane (or one row for
  all lanes).
* ``frames`` (F, 3) int64: ``[parent, normal slot, tangent slot]``: frame 0 is the
  shading frame (parent -1); a layer with its own ``normal`` has a frame whose normal
  and ``tangent_u`` (in the parent frame) sit at ``P[row, slot:slot + 3]``.  Frames
  are listed parents first.
* ``tables``: the curve layers' curve-weighted albedos Ĉ (:mod:`render.df._layer`),
  tabulated once per distinct layer by the interpreter itself.

The interpreter (:func:`~render.interpreter.eval_pdf`, :func:`~render.interpreter.sample`,
:func:`~render.interpreter.albedo`, :func:`~render.interpreter.edf_eval_pdf`,
:func:`~render.interpreter.edf_sample`) takes one lane (``row``) and local directions and
walks the program without recursion: a pass over the nodes at ``wo`` (cheap albedos,
selection probabilities), a descent for sampling, and one pass at ``wi`` that evaluates
every node once (the numbers each combiner sums).  A node's opcode is its place in the
registry of declared dfs (:mod:`render.df._registry`), which also generates the dispatch
from opcodes to kernels; the layering semantics are documented in
:mod:`render.df._layer`, the mixes' in :mod:`render.df._mix`; each df's math lives once,
in its module's kernels.

:class:`ProgramBsdf` and :class:`ProgramEdf` run programs over lanes for the Python API
(``bsdf.eval(wo, wi)``, ``bsdf.sample(wo, u1, u2)``, ...): the df checklist of the tests
runs on the very kernels that render.
"""

from __future__ import annotations

import threading
from collections import OrderedDict
from dataclasses import dataclass
from functools import cached_property, lru_cache

import numpy as np

from render.bsdf import Bsdf, BsdfSample, Edf, EdfSample, Lobe, check_dirs, check_samples
from render.df._signature import ARRAYS, MODE_FLAGS, REQUIRED, THIN_WALLED, Signature
from render.df._signature import WIDTH as TYPE_WIDTH

__all__ = [
    "Program",
    "ProgramBsdf",
    "ProgramEdf",
    "ProgramTable",
    "leaf_program",
    "layer_program",
    "mix_program",
    "combine",
    "pack",
]

# ----------------------------------------------------------------------------- layout
OP, BASE, FRAME, NKIDS, KID0, FLAGS, LFRAME, TABLE, SIZE, WIDTH = range(10)
NCOL = 10
#: ``code[k, TABLE]``: no Ĉ (a constant curve, a mirror or missing layer, or per-lane
#: parameters: libbsdf's base factor alone)
CHAT_NONE = -2
#: Ĉ table: nodes over the layer-frame polar angle, azimuths kept (largest), Sobol
#: points per direction (render.df._layer's CURVE_ALBEDO_* values)
CHAT_THETA, CHAT_PHI, CHAT_POINTS, CHAT_MU_MIN = 17, 4, 512, 1e-3
#: quadrature points of a combiner's albedo correction (through a child's sampler; a
#: Fibonacci number: the u2 points form a Fibonacci lattice).  Measured accuracy
#: (tests/render/df): about 5e-3 where the factors are smooth, 2e-2 where they jump
#: (total internal reflection in a Fresnel coat, the horizon of a tilted layer normal).
ALBEDO_POINTS = 89

COS_ZERO = 1e-10  # render.numerics.TOL.cos_zero
DEFENSIVE = 0.05  # share of a combiner's selection spread evenly (render.df._combine)
ONE_MINUS_EPS = float(np.nextafter(1.0, 0.0))
LUM_R, LUM_G, LUM_B = 0.212671, 0.715160, 0.072169  # MDL's math::luminance
SPECULAR_LOBES = int(Lobe.SPECULAR)


@dataclass(frozen=True, eq=False)
class Program:
    """A bound df tree (see the module docstring for the arrays).

    Parameters
    ----------
    kind : {"bsdf", "edf"}
    code : (N, NCOL) int64
    kids : (K,) int64
    frames : (F, 3) int64
    blocks : tuple of (rows or 1, w) float64
        The columns of ``P`` side by side, each with one row per lane or one for all:
        ``P`` is stacked from them when it is first read, so that a tree whose lanes
        differ in one leaf is not copied to every lane at each of its levels (Figure
        8.9: 0.5 s of 2 s at 4 spp before).
    tables : (T,) float64
    lobes : Lobe
    """

    kind: str
    code: np.ndarray
    kids: np.ndarray
    frames: np.ndarray
    blocks: tuple
    tables: np.ndarray
    lobes: Lobe

    @cached_property
    def P(self) -> np.ndarray:
        """(rows, S) float64: the parameters, one row per lane or one for all."""
        out = np.empty((self.rows, self.width))
        self.write_params(out)
        return out

    def write_params(self, out: np.ndarray, rows=slice(None)) -> None:
        """The blocks side by side into ``out[rows]`` from column 0, each broadcast over
        the rows (a bind writes a lane's program straight into the scene's table)."""
        at = 0
        for b in self.blocks:
            out[rows, at:at + b.shape[1]] = b
            at += b.shape[1]

    @property
    def rows(self) -> int:
        """Lanes of parameters (1: the same for every lane)."""
        return _rows(list(self.blocks))

    @property
    def width(self) -> int:
        """Parameter slots (``P``'s columns)."""
        return sum(b.shape[1] for b in self.blocks)

    def first_row(self) -> np.ndarray:
        """(1, S): ``P``'s first row, without stacking the lanes."""
        return np.concatenate([b[:1] for b in self.blocks], axis=1) if self.blocks else \
            np.zeros((1, 0))

    @property
    def root(self) -> int:
        return self.code.shape[0] - 1


def _as_rows(value, width: int, name: str) -> np.ndarray:
    """An argument as (rows, width) float64: a number, a ``width`` vector, ``(n,)`` per
    lane (width 1), ``(n, width)`` per lane, or a number per lane broadcast over a colour."""
    a = np.asarray(value, dtype=np.float64)
    shapes = ("a number or one number per lane (n,)" if width == 1 else
              f"a number, {width} numbers or one row of {width} per lane (n, {width})")
    if a.ndim == 0:
        a = np.full((1, width), float(a))
    elif a.ndim == 1:
        if width == 1:
            a = a[:, None]
        elif a.shape[0] == width:
            a = a[None, :]
        else:
            raise ValueError(f"{name} must be {shapes}, got shape {a.shape}")
    elif width == 1:  # a float: (n, 1) or more dimensions is a shape mistake
        raise ValueError(f"{name} must be {shapes}, got shape {a.shape}")
    elif a.ndim == 2 and a.shape[1] == 1:
        a = np.repeat(a, width, axis=1)
    if a.ndim != 2 or a.shape[1] != width:
        raise ValueError(f"{name} must be {shapes}, got shape {a.shape}")
    if not np.all(np.isfinite(a)):
        raise ValueError(f"{name} must be finite, got {value!r}")
    return a


def _rows(arrays: list) -> int:
    n = max((a.shape[0] for a in arrays), default=1)
    for a in arrays:
        if a.shape[0] not in (1, n):
            raise ValueError(f"arguments have {a.shape[0]} and {n} rows: give one value per "
                             "lane or one for all lanes")
    return n


def _stack(arrays: list) -> np.ndarray:
    """Columns side by side, broadcast to a common number of rows."""
    if not arrays:
        return np.zeros((1, 0))
    n = _rows(arrays)
    return np.concatenate([np.broadcast_to(a, (n, a.shape[1])) for a in arrays], axis=1)


def _same_rows(a: np.ndarray) -> bool:
    """Whether every row of ``a`` equals its first (one row: trivially)."""
    return a.shape[0] == 1 or bool(np.all(a == a[0]))


def pack(signature: Signature, values: dict, name: str) -> tuple[np.ndarray, int]:
    """The slot columns of one node and its flags, from MDL arguments and context.

    ``values`` maps parameter (and context) names to constants or per-lane arrays;
    missing parameters take MDL's defaults (a missing required one is an error), missing
    context values 1 (``ior_*``).  ``mode`` and ``thin_walled`` become flags.
    """
    cols, flags, tail = [], 0, []
    for p in signature.params:
        if p.type in ARRAYS:  # its length here, its elements after the fixed slots
            value = values.get(p.name, p.default)
            if value is REQUIRED or value is None:
                raise ValueError(f"{name} needs the argument {p.name!r} (it has no default)")
            if callable(value):
                raise ValueError(f"{name}: {p.name} must be constant (one array for all "
                                 "lanes), not a function of the state")
            a = np.asarray(value, dtype=np.float64)
            k = ARRAYS[p.type]
            a = a.reshape(-1, k) if (a.ndim == 2 and a.shape[1] == k) or k == 1 else None
            if a is None or a.shape[0] < 1:
                raise ValueError(f"{name}: {p.name} must be a non-empty array of "
                                 f"{p.type[:-2]} values (shape (N, {k})), got shape "
                                 f"{np.shape(value)}")
            if not np.all(np.isfinite(a)):
                raise ValueError(f"{name}: {p.name} must be finite")
            cols.append(np.full((1, 1), float(a.shape[0])))
            tail.append(a.reshape(1, -1))
            continue
        if p.type == "scatter_mode":
            mode = values.get(p.name, p.default)
            mode = getattr(mode, "value", mode)
            key = str(mode).removeprefix("::").removeprefix("df::")
            if key not in MODE_FLAGS:
                raise ValueError(f"{name}: mode must be one of {', '.join(MODE_FLAGS)}; "
                                 f"got {mode!r}")
            flags |= MODE_FLAGS[key]
            continue
        if not p.width:
            continue
        value = values.get(p.name, p.default)
        if value is REQUIRED or isinstance(value, str) or value is None:
            raise ValueError(f"{name} needs the argument {p.name!r} (it has no default)")
        if p.type == "float3x3":  # row-major, M[i][j] at slot 3 i + j
            value = np.asarray(value, dtype=np.float64)
            if value.shape[-2:] != (3, 3) or value.ndim not in (2, 3):
                raise ValueError(f"{name}: {p.name} must be a 3x3 matrix or one per lane "
                                 f"(n, 3, 3), got shape {value.shape}")
            value = value.reshape(-1, 9)
        a = _as_rows(value, TYPE_WIDTH.get(p.type, p.width), f"{name}: {p.name}")
        if a.shape[1] != p.width:  # a float packed as a grey colour
            a = np.repeat(a, p.width, axis=1)
        if p.clamp is not None:
            a = np.clip(a, p.clamp[0], p.clamp[1])
        cols.append(a)
    for c in signature.context:
        a = _as_rows(values.get(c, _CONTEXT_DEFAULTS.get(c, 1.0)), 1, f"{name}: {c}")
        if c.startswith("ior") and np.any(a <= 0.0):
            raise ValueError(f"{name}: {c} must be > 0 (an index of refraction), got {a.min()}")
        cols.append(a)
    if values.get("thin_walled", False):
        flags |= THIN_WALLED
    return _stack(cols + tail), flags


def leaf_program(kind: str, op: int, signature: Signature, values: dict, lobes: Lobe,
                 name: str, albedo_table=None) -> Program:
    """The program of one elemental df; ``albedo_table(row, flags)``, for dfs whose
    albedo kernel reads a node table (the glossy lobes), builds it from row 0."""
    P, flags = pack(signature, values, name)
    code = np.zeros((1, NCOL), dtype=np.int64)
    code[0, OP], code[0, FLAGS], code[0, SIZE], code[0, WIDTH] = op, flags, 1, P.shape[1]
    code[0, TABLE] = CHAT_NONE
    tables = np.zeros(0)
    if albedo_table is not None:
        tables = np.asarray(albedo_table(P[0], flags), dtype=np.float64)
        code[0, TABLE] = 0
    return Program(kind, code, np.zeros(0, dtype=np.int64),
                   np.array([[-1, 0, 0]], dtype=np.int64), (P,), tables, lobes)


def combine(kind: str, op: int, columns: np.ndarray, flags: int, children: list,
            frame: tuple | None = None, curve_columns: np.ndarray | None = None) -> Program:
    """The program of a combiner over ``children`` (Programs, or None for ``bsdf()``).

    Parameters
    ----------
    columns : (rows, w) float64
        The node's own packed parameters (:func:`pack`, or a mix's weights).
    frame : (int, (rows, 3) float64), optional
        A layer's own frame: the offset of its ``normal`` (inherited frame) in
        ``columns``, and ``tangent_u`` in the inherited frame (None: the layer child
        shares the node's frame).  Only for layers; ``children[0]`` is the layer.
    curve_columns : (w,) bool, optional
        Which of ``columns`` the layer's curve depends on (for its Ĉ table).
    """
    codes, kid_lists, frame_rows, blocks, tabs = [], [], [[-1, 0, 0]], [], []
    roots, lobes = [], Lobe.NONE
    n_nodes = n_slots = n_tab = 0
    layer_frame = 0
    for i, child in enumerate(children):
        if child is None:
            roots.append(-1)
            continue
        lobes |= child.lobes
        c = child.code.copy()
        # the child's frames: its frame 0 is the node's (or the layer frame)
        fmap = np.zeros(len(child.frames), dtype=np.int64)
        if i == 0 and frame is not None:
            layer_frame = len(frame_rows)
            frame_rows.append([0, -1, -1])  # the layer frame; slots set below
            fmap[0] = layer_frame
        for f in range(1, len(child.frames)):
            fmap[f] = len(frame_rows)
            parent, ns, ts = child.frames[f]
            frame_rows.append([fmap[parent] if parent >= 0 else fmap[0], ns + n_slots,
                               ts + n_slots])
        c[:, FRAME] = fmap[c[:, FRAME]]
        c[:, LFRAME] = fmap[c[:, LFRAME]]
        c[:, BASE] += n_slots
        c[:, KID0] += len(np.concatenate(kid_lists)) if kid_lists else 0
        c[:, TABLE] = np.where(c[:, TABLE] >= 0, c[:, TABLE] + n_tab, c[:, TABLE])
        k = child.kids.copy()
        kid_lists.append(np.where(k >= 0, k + n_nodes, k))
        codes.append(c)
        blocks.extend(child.blocks)
        tabs.append(child.tables)
        roots.append(n_nodes + child.root)
        n_nodes += len(c)
        n_slots += child.width
        n_tab += len(child.tables)
    own = [columns] + ([frame[1]] if frame is not None else [])
    _rows(blocks + own)  # one row or one per lane, alike
    if frame is not None:
        frame_rows[layer_frame][1:] = [n_slots + frame[0], n_slots + columns.shape[1]]
    kids = np.concatenate(kid_lists + [np.array(roots, dtype=np.int64)]) if kid_lists else \
        np.array(roots, dtype=np.int64)
    node = np.zeros((1, NCOL), dtype=np.int64)
    node[0, OP], node[0, BASE], node[0, FLAGS] = op, n_slots, flags
    node[0, NKIDS], node[0, KID0] = len(children), len(kids) - len(children)
    node[0, LFRAME] = layer_frame
    node[0, TABLE] = CHAT_NONE
    node[0, SIZE] = n_nodes + 1
    node[0, WIDTH] = sum(b.shape[1] for b in own)
    code = np.concatenate(codes + [node]) if codes else node
    program = Program(kind, np.ascontiguousarray(code), kids,
                      np.array(frame_rows, dtype=np.int64).reshape(-1, 3),
                      (*blocks, *own), np.concatenate(tabs) if tabs else np.zeros(0), lobes)
    if curve_columns is not None:
        # Ĉ depends on the layer child's parameters and the curve's own: checked here,
        # on the parts, rather than on the stacked lanes
        constant = (all(_same_rows(b) for b in (() if children[0] is None
                                                 else children[0].blocks))
                    and _same_rows(columns[:, curve_columns]))
        program = _with_chat_table(program, curve_columns, constant)
    return program


def layer_program(op: int, signature: Signature, values: dict, layer, base, normal,
                  tangent_u, name: str) -> Program:
    """The program of a layer node over bound children (Program or None).

    ``normal`` and ``tangent_u`` are the layer's normal and the texture tangent in the
    inherited local frame (``(3,)`` or ``(rows, 3)``); a frame equal to the inherited
    one (within 1e-12) adds no frame.  The layer's curve depends on every packed value
    but ``weight`` and ``normal`` (its Ĉ table's key).
    """
    from render.frame import Frame
    from render.numerics import unitize

    nrm, ok = unitize(_as_rows(normal, 3, f"{name}(normal)"))
    if not np.all(ok):
        raise ValueError(f"{name}: normal must be a non-zero vector (the layer's surface "
                         "normal)")
    tu = _as_rows(tangent_u, 3, f"{name}(tangent_u)")
    n = _rows([nrm, tu])
    frame = Frame.from_normal_tangent(np.broadcast_to(nrm, (n, 3)), np.broadcast_to(tu, (n, 3)))
    eye = np.eye(3)
    identity = all(np.all(np.abs(a - e) <= 1e-12) for a, e in
                   zip((frame.s, frame.t, frame.n), eye, strict=True))
    columns, flags = pack(signature, dict(values, normal=nrm), name)
    curve = np.ones(columns.shape[1], dtype=bool)  # (an array's elements follow the slots)
    for p in ("weight", "normal"):
        at = signature.offset(p)
        curve[at:at + signature.param(p).width] = False
    children = [None if c is None else c.program for c in (layer, base)]
    return combine("bsdf", op, columns, flags, children,
                   frame=None if identity else (signature.offset("normal"), tu),
                   curve_columns=curve)


def mix_program(kind: str, op: int, components: list, color: bool) -> Program:
    """The program of a mix of ``components`` (``render.df._mix`` component structs):
    each component's weight packed as a colour (3 slots, in order), its df a child."""
    from render.df._mix import component_signature

    del color
    sig_c = component_signature(True, kind == "edf")  # the structs hold colour weights
    cols = [pack(sig_c, {"weight": c.weight}, f"{kind} component")[0] for c in components]
    children = [None if c.component is None else c.component.program for c in components]
    return combine(kind, op, _stack(cols), 0, children)


# ----------------------------------------------------------------------------- Ĉ tables
_TABLES: OrderedDict = OrderedDict()
_TABLES_MAX = 256
_TABLES_LOCK = threading.Lock()


def _with_chat_table(program: Program, curve_columns: np.ndarray, constant: bool) -> Program:
    """``program`` (a curve layer at its root) with its Ĉ table, where one applies.

    Ĉ is tabulated from parameter row 0 when every parameter it depends on (the layer
    child's subtree, its frames, the curve's own parameters) is the same on every lane
    (``constant``); otherwise (textured layers) the layer keeps libbsdf's base factor
    (``CHAT_NONE``).  A table is built once per distinct layer and curve (cached by
    value).
    """
    from render.df._registry import registry
    from render.df._signature import MODE_MASK, REFLECT

    code, root = program.code, program.root
    lay = program.kids[code[root, KID0]]
    if lay < 0 or not constant:
        return program
    # a mirror layer (specular_bsdf reflecting) never exceeds libbsdf's factor
    if registry().nodes[code[lay, OP] - 1].mirror and (code[lay, FLAGS] & MODE_MASK) == REFLECT:
        return program
    lo = lay - code[lay, SIZE] + 1
    cols = [np.arange(code[k, BASE], code[k, BASE] + code[k, WIDTH]) for k in range(lo, lay + 1)]
    cols.append(code[root, BASE] + np.flatnonzero(curve_columns))
    cols = np.concatenate(cols)
    P = program.first_row()  # what Ĉ depends on is the same on every lane
    from render import interpreter

    if interpreter.curve_constant(code[root, OP], P, 0, code[root, BASE], code[root, FLAGS],
                                  program.tables, code[root, TABLE]):
        return program
    key = (code[lo:].tobytes(), program.kids.tobytes(), program.frames.tobytes(),
           P[0, cols].tobytes())
    with _TABLES_LOCK:
        table = _TABLES.get(key)
        if table is not None:
            _TABLES.move_to_end(key)
    if table is None:
        out = np.zeros((2, 2, CHAT_THETA, 3))
        interpreter.build_chat_table(code, program.kids, program.frames, P[:1], program.tables,
                                     0, root, _chat_directions(), sobol_points(CHAT_POINTS), out)
        table = out.ravel()
        table.setflags(write=False)
        with _TABLES_LOCK:
            _TABLES[key] = table
            while len(_TABLES) > _TABLES_MAX:
                _TABLES.popitem(last=False)
    code = code.copy()
    code[root, TABLE] = len(program.tables)
    return Program(program.kind, code, program.kids, program.frames, program.blocks,
                   np.concatenate([program.tables, table]), program.lobes)


@lru_cache(maxsize=1)
def _chat_directions() -> np.ndarray:  # noqa: D401
    """(2, THETA * PHI, 3): the layer-frame directions of each side of a Ĉ table
    (uniform in the polar angle from the pole to ``acos(CHAT_MU_MIN)``; azimuths 0, 45,
    90, 135 degrees)."""
    step = float(np.arccos(CHAT_MU_MIN)) / (CHAT_THETA - 1)
    theta = np.arange(CHAT_THETA) * step
    phi = np.arange(CHAT_PHI) * (np.pi / CHAT_PHI)
    t, p = np.meshgrid(theta, phi, indexing="ij")
    out = np.empty((2, CHAT_THETA * CHAT_PHI, 3))
    for side in (0, 1):
        z = np.cos(t) * (-1.0 if side else 1.0)
        out[side] = np.stack([np.sin(t) * np.cos(p), np.sin(t) * np.sin(p), z],
                             axis=-1).reshape(-1, 3)
    out.setflags(write=False)
    return out


@lru_cache(maxsize=1)
def albedo_points(m: int = ALBEDO_POINTS) -> np.ndarray:
    """``m`` quadrature points in [0, 1)^3 (columns ``u1, u2x, u2y``), shape (m', 3):
    ``u2`` the Fibonacci lattice ``((i + 1/2)/m', frac((i g + 1/2)/m'))`` with ``m'`` the
    first Fibonacci number ``>= m`` and ``g`` its predecessor, ``u1 = frac(1/2 + i (sqrt 2
    - 1))``.

    Examples
    --------
    >>> p = albedo_points(8)
    >>> p.shape, bool(np.all((p >= 0) & (p < 1)))
    ((8, 3), True)
    """
    fib = [1, 2]
    while fib[-1] < m:
        fib.append(fib[-1] + fib[-2])
    m, g = fib[-1], fib[-2]
    i = np.arange(m)
    pts = np.stack([np.mod(0.5 + i * (np.sqrt(2.0) - 1.0), 1.0), (i + 0.5) / m,
                    np.mod((i * g + 0.5) / m, 1.0)], axis=1)
    pts.setflags(write=False)
    return pts


@lru_cache(maxsize=8)
def sobol_points(m: int) -> np.ndarray:
    """The first ``m`` (a power of 2) points of Sobol's sequence in [0, 1)^3, shifted by
    ``1/(2m)`` (no point on a cell edge); columns ``u1, u2x, u2y``.

    Unscrambled, Gray-code order, Joe and Kuo's direction numbers for dimensions 2
    and 3.

    Examples
    --------
    >>> (sobol_points(4) - 1 / 8).tolist()
    [[0.0, 0.0, 0.0], [0.5, 0.5, 0.5], [0.75, 0.25, 0.25], [0.25, 0.75, 0.75]]
    """
    if m < 1 or m & (m - 1):
        raise ValueError(f"m must be a power of 2 (the Sobol points form a net), got {m}")
    bits = 32
    dims = [[1] * bits, [1], [1, 3]]
    for d, (s, a) in ((1, (1, ())), (2, (2, (1,)))):
        mk = dims[d]
        for k in range(s, bits):
            new = mk[k - s] ^ (mk[k - s] << s)
            for j, aj in enumerate(a, start=1):
                new ^= (mk[k - j] << j) if aj else 0
            mk.append(new)
    v = np.array([[mk[k] << (bits - 1 - k) for k in range(bits)] for mk in dims], dtype=np.uint64)
    i = np.arange(m, dtype=np.uint64)
    gray = i ^ (i >> np.uint64(1))
    x = np.zeros((m, 3), dtype=np.uint64)
    for k in range(bits):
        on = ((gray >> np.uint64(k)) & np.uint64(1)).astype(bool)
        x ^= np.where(on[:, None], v[:, k][None, :], np.uint64(0))
    pts = x.astype(np.float64) / 2.0**bits + 0.5 / m
    pts.setflags(write=False)
    return pts


class ProgramTable:
    """Several programs in one set of arrays, for kernels that shade many materials
    (the integrator): node, child, frame and table indices made absolute.

    Each program keeps its own parameter columns (``BASE`` relative to its row): the
    caller keeps a parameter array of :attr:`width` columns whose rows it chooses per
    lane.  Program ``i`` is run with ``root = roots[i]`` and frames
    ``frame_lo[i] .. frame_hi[i] - 1``.

    Parameters
    ----------
    programs : list of Program or None
        None (a black bsdf or no edf) gets root -1.
    """

    def __init__(self, programs: list):
        codes, kids, frames, tables = [], [], [], []
        self.roots = np.full(len(programs), -1, dtype=np.int64)
        self.frame_lo = np.zeros(len(programs), dtype=np.int64)
        self.frame_hi = np.zeros(len(programs), dtype=np.int64)
        n = k = f = t = 0
        width = 0
        for i, p in enumerate(programs):
            if p is None:
                continue
            c = p.code.copy()
            c[:, KID0] += k
            c[:, FRAME] += f
            c[:, LFRAME] += f
            c[:, TABLE] = np.where(c[:, TABLE] >= 0, c[:, TABLE] + t, c[:, TABLE])
            codes.append(c)
            kids.append(np.where(p.kids >= 0, p.kids + n, p.kids))
            fr = p.frames.copy()
            fr[:, 0] = np.where(fr[:, 0] >= 0, fr[:, 0] + f, -1)
            frames.append(fr)
            tables.append(p.tables)
            self.roots[i] = n + p.root
            self.frame_lo[i], self.frame_hi[i] = f, f + len(p.frames)
            n, k, f, t = n + len(c), k + len(p.kids), f + len(fr), t + len(p.tables)
            width = max(width, p.width)
        self.code = np.concatenate(codes) if codes else np.zeros((1, NCOL), dtype=np.int64)
        self.kids = np.concatenate(kids) if kids else np.zeros(0, dtype=np.int64)
        self.frames = (np.concatenate(frames) if frames
                       else np.array([[-1, 0, 0]], dtype=np.int64))
        self.tables = np.concatenate(tables) if tables else np.zeros(0)
        #: columns of a parameter row that holds any of the programs
        self.width = max(width, 1)


# ----------------------------------------------------------------------------- adapters
def _lane_program(program: Program, n: int) -> None:
    if program.rows not in (1, n):
        raise ValueError(f"the df holds {program.rows} per-lane values but the call has "
                         f"{n} lanes")


class ProgramBsdf(Bsdf):
    """A bsdf program over lanes: the :class:`~render.bsdf.Bsdf` interface on the
    kernels that render (every call runs the compiled interpreter per lane).

    Parameters
    ----------
    program : Program
    """

    def __init__(self, program: Program):
        self.program = program
        self.lobes = program.lobes

    def __repr__(self) -> str:
        return f"{type(self).__name__}({self.program.code.shape[0]} nodes)"

    def _args(self):
        p = self.program
        return p.code, p.kids, p.frames, p.P, p.tables

    def eval_pdf(self, wo, wi):
        from render import interpreter

        wo, wi = check_dirs(wo, wi)
        n = len(wo)
        _lane_program(self.program, n)
        f, pdf = np.empty((n, 3)), np.empty(n)
        interpreter.eval_pdf_batch(*self._args(), wo, wi, f, pdf)
        return f, pdf

    def eval(self, wo, wi):
        return self.eval_pdf(wo, wi)[0]

    def pdf(self, wo, wi):
        return self.eval_pdf(wo, wi)[1]

    def sample(self, wo, u1, u2) -> BsdfSample:
        from render import interpreter

        (wo,) = check_dirs(wo, names=("wo",))
        n = len(wo)
        u1, u2 = check_samples(n, u1, u2)
        _lane_program(self.program, n)
        wi, pdf, w = np.empty((n, 3)), np.empty(n), np.empty((n, 3))
        lobe = np.empty(n, dtype=np.int64)
        interpreter.sample_batch(*self._args(), wo, np.ascontiguousarray(u1),
                                 np.ascontiguousarray(u2), wi, pdf, w, lobe)
        return BsdfSample(wi, pdf, w, lobe.astype(np.int32)).checked()

    def albedo(self, wo):
        from render import interpreter

        (wo,) = check_dirs(wo, names=("wo",))
        _lane_program(self.program, len(wo))
        out = np.empty((len(wo), 3))
        interpreter.albedo_batch(*self._args(), wo, albedo_points(), out)
        return out

    def cheap_albedo(self, wo):
        """The fast albedo estimate (``render.df.albedo_estimate``)."""
        from render import interpreter

        (wo,) = check_dirs(wo, names=("wo",))
        _lane_program(self.program, len(wo))
        out = np.empty((len(wo), 3))
        interpreter.cheap_albedo_batch(*self._args(), wo, out)
        return out


class ProgramEdf(Edf):
    """An edf program over lanes (the :class:`~render.bsdf.Edf` interface)."""

    def __init__(self, program: Program):
        self.program = program

    def __repr__(self) -> str:
        return f"{type(self).__name__}({self.program.code.shape[0]} nodes)"

    def _args(self):
        p = self.program
        return p.code, p.kids, p.frames, p.P, p.tables

    def _eval_pdf(self, wo):
        from render import interpreter

        (wo,) = check_dirs(wo, names=("wo",))
        n = len(wo)
        _lane_program(self.program, n)
        e, pdf = np.empty((n, 3)), np.empty(n)
        interpreter.edf_eval_pdf_batch(*self._args(), wo, e, pdf)
        return e, pdf

    def eval(self, wo):
        return self._eval_pdf(wo)[0]

    def pdf(self, wo):
        return self._eval_pdf(wo)[1]

    def sample(self, u1, u2) -> EdfSample:
        from render import interpreter

        n = len(np.asarray(u2))
        u1, u2 = check_samples(n, u1, u2)
        _lane_program(self.program, n)
        wo, pdf, w = np.empty((n, 3)), np.empty(n), np.empty((n, 3))
        interpreter.edf_sample_batch(*self._args(), np.ascontiguousarray(u1),
                                     np.ascontiguousarray(u2), wo, pdf, w)
        return EdfSample(wo, pdf, w)


# ----------------------------------------------------------------------------- df classes
_CONTEXT_DEFAULTS = {"ior_outside": 1.0, "ior_inside": 1.0, "thin_walled": False}


def df_class(declaration) -> type:
    """The Python class of a df (a :class:`render.df._registry.Df` of one node): MDL's
    parameters (from its signature) as keywords or in MDL's order, plus the renderer
    context the kernels read; instances are :class:`ProgramBsdf` (or
    :class:`ProgramEdf`) whose program is the df.

    Children (``bsdf``/``edf`` parameters) are bound dfs or None (MDL's black df).  A
    layer (children ``layer`` and ``base`` and a ``normal``) also takes ``tangent_u``,
    both in the inherited local frame.  The declaration's ``lobes``: a :class:`Lobe` or
    a dict from the scatter mode's name to the lobes of an elemental df;
    ``unsupported``: parameters that must stay at their defaults;
    ``albedo_table(P, flags)``: the node table the leaf's albedo kernel reads, from its
    packed row, or from all its rows (2-D) when the arguments are per lane;
    ``check(values)`` raises ValueError for arguments MDL does not allow (it sees the
    arguments as given: a 3x3 context left out is None).  A 3x3 context
    (``object_to_local``, packed as 9 slots ``object_to_local_ij``; the identity when
    left out) is taken as one ``(3, 3)`` or ``(rows, 3, 3)`` argument.
    """
    import inspect

    py_name, mdl_name, signature = (declaration.py_name, declaration.mdl_name,
                                    declaration.signature)
    (node,) = declaration.nodes
    lobes, unsupported = declaration.lobes, declaration.unsupported
    albedo_table, check, module = declaration.albedo_table, declaration.check, declaration.module
    params = [p for p in signature.params if p.name != "handle" and p.mdl]
    names = [p.name for p in params]
    children = [p.name for p in params if p.type in ("bsdf", "edf", "vdf")]
    is_layer = children == ["layer", "base"] and "normal" in names
    extra = []
    if is_layer:
        extra.append(("tangent_u", (1.0, 0.0, 0.0)))
    matrices = sorted({c[:-3] for c in signature.context if c[-3:-2] == "_" and c[-2:].isdigit()})
    if signature.context:
        extra += [(c, _CONTEXT_DEFAULTS.get(c)) for c in signature.context
                  if c[:-3] not in matrices]
        extra += [(m, None) for m in matrices]  # None: the identity (check sees None)
        extra.append(("thin_walled", False))
    defaults = {}
    for p in params:
        d = p.default
        if p.name == "normal" and is_layer:
            d = (0.0, 0.0, 1.0)
        elif p.name == "tangent_u":
            d = (1.0, 0.0, 0.0)
        elif isinstance(d, str) and d in names:
            d = None  # the value of another parameter (roughness_v = roughness_u)
        defaults[p.name] = d
    pysig = inspect.Signature(
        [inspect.Parameter(p.name, inspect.Parameter.POSITIONAL_OR_KEYWORD,
                           default=(inspect.Parameter.empty if defaults[p.name] is REQUIRED
                                    else defaults[p.name])) for p in params]
        + [inspect.Parameter(n, inspect.Parameter.KEYWORD_ONLY, default=d) for n, d in extra])
    base_cls = ProgramEdf if signature.kind == "edf" else ProgramBsdf
    title = f"df::{mdl_name}"

    def __init__(self, *args, **kwargs):  # noqa: N807
        try:
            bound = pysig.bind(*args, **kwargs)
        except TypeError as e:
            raise ValueError(f"{title}: {e}") from None
        bound.apply_defaults()
        values = dict(bound.arguments)
        for p in params:
            if isinstance(p.default, str) and p.default in names and values[p.name] is None:
                values[p.name] = values[p.default]
        if check is not None:
            check(values)
        for m in matrices:
            a = values.pop(m)
            a = np.eye(3) if a is None else np.asarray(a, dtype=np.float64)
            if a.shape[-2:] != (3, 3) or a.ndim not in (2, 3):
                raise ValueError(f"{title}: {m} must be a 3x3 matrix or one per lane "
                                 f"(n, 3, 3), got shape {a.shape}")
            a = a.reshape(-1, 3, 3)
            for i in range(3):
                for j in range(3):
                    values[f"{m}_{i}{j}"] = a[:, i, j]
        for u in unsupported:
            if np.any(np.asarray(values[u], dtype=np.float64) != np.asarray(
                    defaults[u], dtype=np.float64)):
                raise ValueError(f"{title}({u}) is not implemented yet; leave it at its "
                                 f"default {defaults[u]!r}")
        kids = []
        for c in children:
            child = values.pop(c)
            if child is not None and not isinstance(child, base_cls):
                raise ValueError(f"{title}({c}) must be a bound {signature.kind} (a "
                                 f"render.df distribution function) or None for MDL's black "
                                 f"{signature.kind}(), got {type(child).__name__}")
            kids.append(child)
        op = node.op
        if is_layer:
            program = layer_program(op, signature, values, kids[0], kids[1],
                                    values.pop("normal"), values.pop("tangent_u"), title)
        elif kids:
            columns, flags = pack(signature, values, title)
            program = combine(signature.kind, op, columns, flags,
                              [None if c is None else c.program for c in kids])
        else:
            program = leaf_program(signature.kind, op, signature, values, Lobe.NONE, title)
            tables = program.tables
            code = program.code
            if albedo_table is not None:  # from every row: per-lane roughness has its own
                code = code.copy()
                code[0, TABLE] = 0
                P = program.P
                tables = np.asarray(albedo_table(P if len(P) > 1 else P[0],
                                                 int(code[0, FLAGS])), dtype=np.float64)
            if isinstance(lobes, dict):
                mode = str(getattr(values.get("mode"), "value", values.get("mode")))
                mode = mode.removeprefix("::").removeprefix("df::")
                leaf_lobes = lobes[mode]
            else:
                leaf_lobes = Lobe.NONE if lobes is None else lobes
            program = Program(program.kind, code, program.kids, program.frames,
                              program.blocks, tables, leaf_lobes)
        base_cls.__init__(self, program)
        for c, child in zip(children, kids, strict=True):
            self.__dict__[c] = child

    doc = (f"``{title}`` over lanes: its kernels, run by :mod:`render.interpreter`.\n\n"
           f"Parameters (MDL's, constants or one value per lane): "
           f"{', '.join(names)}" + (f"; renderer context: {', '.join(n for n, _ in extra)}"
                                     if extra else "") + ".")
    def __getattr__(self, key):  # noqa: N807
        """A packed parameter of the root node as stored (clamped): a float as a number
        (0-d) when one row serves every lane, else ``(rows,)``; ``(rows, w)`` otherwise;
        ``mode`` as its MDL name."""
        prog = self.__dict__.get("program")
        if prog is None or key.startswith("__"):
            raise AttributeError(key)
        root = prog.code[prog.root]
        if key == "mode" and "mode" in names:
            flags = int(root[FLAGS]) & 3
            return next(m for m, f in MODE_FLAGS.items() if f == flags)
        if key == "thin_walled" and signature.context:
            return bool(int(root[FLAGS]) & THIN_WALLED)
        try:
            at = signature.offset(key)
        except KeyError:
            raise AttributeError(f"{py_name} has no attribute {key!r}") from None
        width = 1 if key in signature.context else signature.param(key).width
        cols = prog.P[:, root[BASE] + at:root[BASE] + at + width]
        if width == 1:
            return cols[0, 0] if prog.rows == 1 else cols[:, 0]
        return cols

    cls = type(py_name, (base_cls,), {"__init__": __init__, "__doc__": doc,
                                      "__getattr__": __getattr__, "__module__": module,
                                      "mdl_name": mdl_name, "signature": signature})
    cls.__signature__ = pysig
    return cls


def check_ior(values: dict) -> None:
    """A layer's ``ior`` must be positive (an index of refraction)."""
    ior = np.asarray(values["ior"], dtype=np.float64)
    if not np.all(np.isfinite(ior)) or np.any(ior <= 0.0):
        raise ValueError(f"ior must be > 0 (an index of refraction), got {values['ior']!r}")


def mix_class(py_name: str, mdl_name: str, node, color: bool, edf: bool,
              module: str = "render.df", vdf: bool = False) -> type:
    """The Python class of a mix (``normalized_mix``, ``clamped_mix``, their colour, edf
    and vdf forms) over a list of component structs or ``(weight, df)`` pairs; ``node``
    the mix's :class:`render.df._registry.Node`."""
    from render.df._mix import as_components

    base_cls = ProgramEdf if edf else ProgramBsdf
    kind = "edf" if edf else ("vdf" if vdf else "bsdf")

    def __init__(self, components):  # noqa: N807
        comps = as_components(components, color, f"df::{mdl_name}")
        base_cls.__init__(self, mix_program(kind, node.op, comps, color))
        self.components = comps

    def weights(self, n: int) -> np.ndarray:
        """(n, k, 3): the effective (normalised or clamped) weights of the components,
        from the mix's weight kernel."""
        from render import interpreter

        p = self.program
        _lane_program(p, n)
        out = np.empty((n, len(self.components), 3))
        interpreter.mix_weights_batch(node.op, p.P, p.code[p.root, BASE], p.tables, out)
        return out

    doc = (f"``df::{mdl_name}`` over {kind} components: its weights (kernels in its module) "
           "and children, run by :mod:`render.interpreter`.")
    return type(py_name, (base_cls,), {"__init__": __init__, "weights": weights,
                                       "__doc__": doc, "__module__": module,
                                       "mdl_name": mdl_name})


def mix_dispatch(components, bsdf_cls: type, edf_cls: type, vdf_cls: type | None = None):
    """A mix of bsdf components, of edf components or of vdf components (MDL's
    overloads)."""
    from render.bsdf import Edf as _Edf
    from render.df._mix import as_components

    comps = as_components(components, bsdf_cls.__name__.startswith("Color"),
                          f"df::{bsdf_cls.mdl_name}")
    if comps and comps[0]._kind is _Edf:
        return edf_cls(comps)
    if vdf_cls is not None and comps and (comps[0]._vdf or getattr(
            getattr(comps[0].component, "program", None), "kind", None) == "vdf"):
        return vdf_cls(comps)
    return bsdf_cls(comps)
