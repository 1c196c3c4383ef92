"""The registry of distribution functions: every fact about a df declared once, in its module.

A df module declares, beside its kernels:

* :class:`Node`: a kind of node of df programs (:mod:`render.program`): its role (a
  ``leaf``, a ``layer``, a ``mix`` or a ``modifier``), its kind (``bsdf``, ``edf``,
  ``vdf``), the slots it packs (a :class:`~render.df._signature.Signature`) and its
  kernels, one per phase the interpreter runs (:data:`PHASES`);
* :class:`Df`: an MDL distribution function (or one overload of its name, or the
  struct of a mix's component): its key, its MDL signature, the nodes its programs are
  made of, and what its Python class needs.

:func:`registry` discovers the modules of :mod:`render.df` (and of the folders
``$PWC_DF_PATH`` lists) and derives from the declarations everything that used to be
written by hand beside them: the opcodes (a node's place in the registry, never a
number written down), the MDL signatures (:data:`render.material.DF_SIGNATURES`, from
which the ``::df`` module's declarations are written), the Python classes
(:attr:`Df.cls`), the interpreter's dispatch (:meth:`Registry.dispatch`: generated
code, one branch per node and phase) and the capabilities the integrator and the tests
ask about (:attr:`Df.reads_outside_ior`, :attr:`Df.refracts`, ...), each derived from
the signature or the lobes where they already say it.

Adding a df is one new module: its kernels, a :class:`Node`, a :class:`Df`.
"""

from __future__ import annotations

import functools
import importlib
import importlib.util
import inspect
import pkgutil
import sys
import threading
import traceback
from dataclasses import dataclass, field
from types import MappingProxyType, ModuleType

import numpy as np

from pwc.cli import EXIT_USAGE, CliError
from render.df._signature import Signature

__all__ = ["Node", "Df", "Registry", "registry", "DfPathError", "PHASES", "ROLES"]

#: what a node is in a program: a leaf scatters or emits; a layer has a ``layer`` and a
#: ``base`` child; a mix has weighted components; a modifier scales its one child
ROLES = ("leaf", "layer", "mix", "modifier")

#: the phases a node's kernels serve: phase -> (roles, the kernel's parameters after
#: ``P, row, b, flags``, its result when a node has no kernel for it).  A kernel whose
#: Python signature has two more parameters than listed reads its node's table
#: (``tables, t``).
PHASES = MappingProxyType({
    # leaves: bsdfs and vdfs
    "eval_pdf": ("leaf", "ox, oy, oz, ix, iy, iz", "0.0, 0.0, 0.0, 0.0"),
    "sample": ("leaf", "ox, oy, oz, u1, u2x, u2y", "0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0"),
    "albedo": ("leaf", "ox, oy, oz", "0.0, 0.0, 0.0"),
    # the white albedo E(w) of a sheen lobe (a sheen layer's Ĉ)
    "white_albedo": ("leaf", "ox, oy, oz", "0.0"),
    # leaves: edfs
    "edf_eval_pdf": ("leaf", "ox, oy, oz", "0.0, 0.0, 0.0, 0.0"),
    "edf_sample": ("leaf", "u1, u2x, u2y", "0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0"),
    # layers: the factors of the layer and the base, their estimates at wo, whether each
    # child may be chosen, and a curve layer's curve
    "layer_factors": ("layer", "o0, o1, o2, i0, i1, i2, ol0, ol1, ol2, il0, il1, il2, "
                               "co0, co1, co2, ci0, ci1, ci2",
                      "0.0, 0.0, 0.0, 0.0, 0.0, 0.0"),
    "layer_estimates": ("layer", "o0, o1, o2, ol0, ol1, ol2, co0, co1, co2",
                        "0.0, 0.0, 0.0, 0.0, 0.0, 0.0"),
    "layer_possible": ("layer", "", "False, False"),
    "curve_h": ("layer", "vx, vy, vz, xx, xy, xz", "0.0, 0.0, 0.0"),
    "curve_nk": ("layer", "vx, vy, vz", "0.0, 0.0, 0.0"),
    # layers and modifiers: whether the curve takes one value at every cosine (a node
    # without the kernel is taken as varying: a Ĉ table, an albedo correction)
    "curve_constant": ("layer modifier", "", "False"),
    # modifiers: the factor at (wo, wi) (an edf modifier's at wo)
    "scale": ("modifier", "o0, o1, o2, i0, i1, i2", "0.0, 0.0, 0.0"),
    # mixes: component i's effective weight among k
    "mix_weights": ("mix", "k, i", "0.0, 0.0, 0.0"),
})

#: the phases the interpreter dispatches on an array argument: phase -> (dispatch
#: parameters, how they unpack into the kernel's)
_ARRAYS = {
    "layer_factors": ("o, i, ol, il, co, ci", "o[0], o[1], o[2], i[0], i[1], i[2], ol[0], "
                      "ol[1], ol[2], il[0], il[1], il[2], co[0], co[1], co[2], ci[0], "
                      "ci[1], ci[2]"),
    "layer_estimates": ("o, ol, co", "o[0], o[1], o[2], ol[0], ol[1], ol[2], co[0], co[1], "
                        "co[2]"),
    "scale": ("o, i", "o[0], o[1], o[2], i[0], i[1], i[2]"),
}


class Node:
    """A kind of node of df programs, declared once in its df's module.

    Parameters
    ----------
    name : str
        Unique among the registry's nodes (the df's MDL name, or a name of its own
        for a part of one: ``sheen_layer``).
    kind : {"bsdf", "edf", "vdf"}
    role : {"leaf", "layer", "mix", "modifier"}
    signature : Signature
        The slots one node packs (its kernels read them).
    mirror : bool
        In ``scatter_reflect`` mode the node reflects to the mirror direction alone
        (``specular_bsdf``): a layer over it needs no Ĉ table, an albedo no quadrature.
    directional : bool
        A layer's factors depend on the directions (every layer but
        ``weighted_layer``); a modifier's factor depends on ``wi`` (unless its
        ``curve_constant`` kernel says the curve is flat, or it is an edf's).
    chat_from_lobe : bool
        A layer whose Ĉ is its layer child's white albedo (the sheen layer's
        ``1 - max(E(wo), E(wi))``), read through the child's ``white_albedo``.
    passes_film : bool
        A combiner that a ``thin_film`` over it reaches through, to the dfs under it
        (:mod:`render.df.thin_film`); a node that packs the film's slots takes it.
    **kernels
        One compiled kernel per phase of :data:`PHASES` that the node implements.
    """

    def __init__(self, name: str, kind: str, role: str, signature: Signature, *,
                 mirror: bool = False, directional: bool = True, chat_from_lobe: bool = False,
                 passes_film: bool = False, **kernels):
        if role not in ROLES:
            raise ValueError(f"node {name}: role must be one of {', '.join(ROLES)}, got "
                             f"{role!r}")
        if kind not in ("bsdf", "edf", "vdf"):
            raise ValueError(f"node {name}: kind must be bsdf, edf or vdf, got {kind!r}")
        for phase in kernels:
            if phase not in PHASES or role not in PHASES[phase][0].split():
                raise ValueError(f"node {name}: a {role} has no phase {phase!r} (phases: "
                                 f"{', '.join(p for p, v in PHASES.items() if role in v[0])})")
        self.name, self.kind, self.role, self.signature = name, kind, role, signature
        self.mirror, self.directional, self.chat_from_lobe = mirror, directional, chat_from_lobe
        self.passes_film = passes_film
        self.kernels = MappingProxyType(dict(kernels))

    def __repr__(self) -> str:
        return f"Node({self.name!r}, {self.kind!r}, {self.role!r})"

    @property
    def op(self) -> int:
        """The node's opcode: its place in the registry (1, 2, ...)."""
        return registry().op(self)

    @property
    def reads_outside_ior(self) -> bool:
        """Whether the node's kernels read the IOR outside the object (its signature's
        context packs ``ior_outside``)."""
        return "ior_outside" in self.signature.context

    @property
    def object_to_local(self) -> int:
        """The slot of ``object_to_local_00`` in a packed node (a lobe fixed in object
        space: the kernel writes each hit's rotation there), -1 if it has none."""
        try:
            return self.signature.offset("object_to_local_00")
        except KeyError:
            return -1

    @property
    def film(self) -> int:
        """The slot of ``thin_film_thickness`` (the film a ``thin_film`` writes into the
        node's Fresnel terms), -1 if it has none."""
        try:
            return self.signature.offset("thin_film_thickness")
        except KeyError:
            return -1

    @property
    def film_always(self) -> bool:
        """Whether the node's film applies whatever its mode (a node with no scatter
        mode: a Fresnel layer or factor), not only in ``scatter_reflect_transmit``."""
        return all(p.type != "scatter_mode" for p in self.signature.params)

    def takes_table(self, phase: str) -> bool:
        """Whether the node's kernel for ``phase`` reads its node table (``tables, t``)."""
        f = self.kernels[phase]
        params = inspect.signature(getattr(f, "py_func", f)).parameters
        listed = [a for a in PHASES[phase][1].split(", ") if a]
        return len(params) == 4 + len(listed) + 2


@dataclass(frozen=True, eq=False)
class Df:
    """An MDL distribution function (one overload of a name, or a mix component's
    struct), declared once in its module.

    Parameters
    ----------
    key : str
        The name the material layer knows it by (:data:`render.material.DF_SIGNATURES`):
        MDL's name, or MDL's name with a suffix for another overload (``tint_rt``).
    signature : Signature
        Its MDL parameters (and the renderer context its kernels read).
    nodes : tuple of Node
        The nodes its programs are made of (none for a struct).
    mdl_name : str
        MDL's name (default: ``key``).
    py_name : str
        The Python class's name (default: ``key`` in CamelCase).
    lobes : Lobe or dict
        An elemental df's lobes, or a dict from the scatter mode's name to them.
    albedo_table, check, unsupported :
        What :func:`render.program.df_class` takes for the class.
    lambertian : bool
        An edf that emits the same radiance in every direction of its hemisphere
        (``diffuse_edf``: a constant one is the integrator's plain area light).
    struct : bool
        A mix component's struct (``bsdf_component``): a signature, no program.
    deprecated : str
        Why MDL deprecates this overload and what to call instead (an overload that an
        earlier MDL version declared, kept for modules of that version; ``::df``
        declares it with ``anno::deprecated``).
    constructor : type or callable
        The Python constructor, where it is not the class that
        :func:`render.program.df_class` derives (a df built of several nodes, a mix's
        overloads).

    The module that declares it is recorded as the class's module (as
    :func:`collections.namedtuple` does).
    """

    key: str
    signature: Signature
    nodes: tuple = ()
    mdl_name: str = ""
    py_name: str = ""
    lobes: object = None
    albedo_table: object = None
    check: object = None
    unsupported: tuple = ()
    lambertian: bool = False
    struct: bool = False
    deprecated: str = ""
    constructor: object = field(default=None, repr=False)
    module: str = field(default="", repr=False)

    def __post_init__(self):
        if not self.module:
            object.__setattr__(self, "module", sys._getframe(2).f_globals.get("__name__", ""))
        if not self.mdl_name:
            object.__setattr__(self, "mdl_name", self.key)
        if not self.py_name:
            object.__setattr__(self, "py_name",
                               "".join(w.capitalize() for w in self.key.split("_")))

    @functools.cached_property
    def cls(self):
        """The Python class (or constructor) of the df: MDL's parameters as keywords."""
        if self.constructor is not None:
            return self.constructor
        from render.program import df_class

        return df_class(self)

    def lobes_in(self, mode: str | None = None):
        """Its lobes in scatter mode ``mode`` (None: in any mode)."""
        from render.bsdf import Lobe

        if not isinstance(self.lobes, dict):
            return Lobe.NONE if self.lobes is None else self.lobes
        if mode is not None:
            return self.lobes.get(mode, Lobe.NONE)
        out = Lobe.NONE
        for v in self.lobes.values():
            out |= v
        return out

    @property
    def reads_outside_ior(self) -> bool:
        """Whether its programs change with the IOR outside the object (its signature's
        renderer context packs ``ior_outside``)."""
        return "ior_outside" in self.signature.context

    @property
    def transmits(self) -> bool:
        """Whether it may scatter to the other side (a transmitting lobe)."""
        return self.transmits_in(None)

    @property
    def refracts(self) -> bool:
        """A dielectric interface: glossy or specular transmission that bends by the
        IOR pair (index-matched, it passes light straight through)."""
        from render.bsdf import Lobe

        return self.reads_outside_ior and bool(
            self.lobes_in() & (Lobe.GLOSSY_TRANSMISSION | Lobe.SPECULAR_TRANSMISSION))

    def delta_in(self, mode: str) -> bool:
        """Whether every lobe in scatter mode ``mode`` is a delta (specular)."""
        from render.bsdf import Lobe

        lobes = self.lobes_in(mode)
        return bool(lobes) and not (lobes & ~Lobe.SPECULAR)

    def transmits_in(self, mode: str | None) -> bool:
        """Whether it may transmit in scatter mode ``mode`` (None: in any mode)."""
        from render.bsdf import Lobe

        return bool(self.lobes_in(mode) & Lobe.TRANSMISSION)


class Registry:
    """The declared nodes and dfs, in discovery order (modules by name, then the
    order of their declarations)."""

    def __init__(self, modules: list[ModuleType]):
        nodes, dfs = [], {}
        seen = set()
        for m in modules:
            values = []
            for value in list(vars(m).values()):  # declarations, or tuples of them
                values += list(value) if isinstance(value, tuple) and value and all(
                    isinstance(v, Node | Df) for v in value) else [value]
            for value in values:
                if id(value) in seen:
                    continue
                if isinstance(value, Node):
                    seen.add(id(value))
                    nodes.append(value)
                elif isinstance(value, Df):
                    seen.add(id(value))
                    if value.key in dfs:
                        raise DfPathError(f"df {value.key!r} is declared twice (in "
                                          f"{dfs[value.key][1]} and {m.__name__}); give "
                                          "the new one a key of its own")
                    dfs[value.key] = (value, m.__name__)
        names = [n.name for n in nodes]
        twice = sorted({n for n in names if names.count(n) > 1})
        if twice:
            raise DfPathError(f"node names declared twice: {', '.join(twice)}; give each "
                              "node a name of its own")
        self.nodes = tuple(nodes)
        self._ops = {id(n): i + 1 for i, n in enumerate(nodes)}
        #: key -> Df
        self.dfs = MappingProxyType({k: v for k, (v, _) in dfs.items()})
        self._dispatch = None
        self._lock = threading.Lock()

    def op(self, node: Node) -> int:
        """The opcode of ``node`` (1, 2, ...)."""
        try:
            return self._ops[id(node)]
        except KeyError:
            raise ValueError(f"{node!r} is not in the registry: declare it at the top level "
                             "of a module of render.df or of $PWC_DF_PATH") from None

    def df(self, key: str) -> Df:
        """The df called ``key``."""
        return self.dfs[key]

    def overloads(self) -> dict[str, tuple[str, ...]]:
        """MDL names declared by several dfs that are not deprecated -> their keys, in
        declaration order (the order a Python call tries them; a deprecated overload is
        for MDL modules of its version, which the MDL front end resolves itself)."""
        by_name: dict[str, list[str]] = {}
        for key, d in self.dfs.items():
            if not d.deprecated:
                by_name.setdefault(d.mdl_name, []).append(key)
        return {n: tuple(keys) for n, keys in by_name.items() if len(keys) > 1}

    def table(self, fact) -> np.ndarray:
        """``fact(node)`` for every opcode, as an array indexed by opcode (slot 0, no
        node, holds ``fact`` of None)."""
        return np.array([fact(None)] + [fact(n) for n in self.nodes])

    def dispatch(self) -> ModuleType:
        """The interpreter's dispatch (:func:`dispatch_source`), generated and imported
        once per process."""
        with self._lock:
            if self._dispatch is None:
                from render.jit import generated

                self._dispatch = generated("render_df_dispatch", dispatch_source(self))
            return self._dispatch


def dispatch_source(reg: Registry) -> str:
    """Python source of the interpreter's dispatch: for each phase of :data:`PHASES`, a
    compiled function of the opcode that calls the node's kernel (one branch per node
    that has one), and arrays of the nodes' facts indexed by opcode."""
    lines = [
        '"""The interpreter\'s df dispatch, generated by render.df._registry from the',
        'declarations of the df modules: do not edit (it is written again wherever it',
        'differs from what the declarations give)."""',
        "",
        "from render.df._registry import registry",
        "from render.jit import njit",
        "",
        "_REG = registry()",
        "#: each opcode's role (render.df._registry.ROLES, by index; -1: no node)",
        "ROLE = _REG.table(lambda n: -1 if n is None else "
        "('leaf', 'layer', 'mix', 'modifier').index(n.role))",
        "#: an edf's node",
        "EDF = _REG.table(lambda n: n is not None and n.kind == 'edf')",
        "#: a mirror in scatter_reflect mode (Node.mirror)",
        "MIRROR = _REG.table(lambda n: n is not None and n.mirror)",
        "#: a layer or modifier whose factors depend on the directions (Node.directional)",
        "DIRECTIONAL = _REG.table(lambda n: n is not None and n.directional)",
        "#: a layer whose Ĉ is its layer child's white albedo (Node.chat_from_lobe)",
        "CHAT_FROM_LOBE = _REG.table(lambda n: n is not None and n.chat_from_lobe)",
        "#: the slot of object_to_local_00 in a node (-1: none; Node.object_to_local)",
        "OBJECT_TO_LOCAL = _REG.table(lambda n: -1 if n is None else n.object_to_local)",
        "",
    ]
    for op, node in enumerate(reg.nodes, start=1):
        for phase in node.kernels:
            lines.append(f"k{op}_{phase} = _REG.nodes[{op - 1}].kernels[{phase!r}]  "
                         f"# {node.name}")
    for phase, (_, params, default) in PHASES.items():
        head, unpack = _ARRAYS.get(phase, (params, params))
        head = ", ".join(filter(None, ["op", "P", "row", "b", "flags", head, "tables", "t"]))
        lines += ["", "", "@njit", f"def {phase}({head}):",
                  f'    """Phase {phase!r} of node ``op`` (``{default}`` where it has '
                  'none)."""']
        # nodes that share one kernel share a branch
        branches: dict[int, list[int]] = {}
        kernels = {}
        for op, node in enumerate(reg.nodes, start=1):
            if phase in node.kernels:
                k = node.kernels[phase]
                branches.setdefault(id(k), []).append(op)
                kernels[id(k)] = (op, node)
        for kid, ops in branches.items():
            op, node = kernels[kid]
            args = ", ".join(filter(None, ["P", "row", "b", "flags", unpack]))
            if node.takes_table(phase):
                args += ", tables, t"
            test = " or ".join(f"op == {o}" for o in ops)
            lines += [f"    if {test}:", f"        return k{op}_{phase}({args})"]
        lines.append(f"    return {default}")
    return "\n".join(lines) + "\n"


def _discover() -> list[ModuleType]:
    """The df modules: every module of :mod:`render.df` (by name), then those of
    ``$PWC_DF_PATH`` (:func:`render.jit.df_path`)."""
    import render.df as package
    from render.jit import df_path

    names = sorted(m.name for m in pkgutil.iter_modules(package.__path__))
    modules = [importlib.import_module(f"render.df.{n}") for n in names]
    for path in df_path():
        name = f"pwc_df_{path.stem}"
        module = sys.modules.get(name)
        if module is None:
            spec = importlib.util.spec_from_file_location(name, path)
            module = importlib.util.module_from_spec(spec)
            sys.modules[name] = module
            try:
                spec.loader.exec_module(module)
            except Exception as e:  # a user's module: say where, not a traceback
                del sys.modules[name]
                line = next((f.lineno for f in reversed(traceback.extract_tb(e.__traceback__))
                             if f.filename == str(path)), None)
                where = f"{path}, line {line}" if line else str(path)
                raise DfPathError(f"{where}: the df module on $PWC_DF_PATH does not load "
                                  f"({type(e).__name__}: {e}); fix it, or take its folder "
                                  "off $PWC_DF_PATH") from None
        modules.append(module)
    return modules


class DfPathError(CliError, ValueError):
    """A df module on ``$PWC_DF_PATH`` that does not load: every ``pwc`` command reports
    it in one line (a :class:`pwc.cli.CliError`), with the file and line to fix."""

    def __init__(self, message: str):
        super().__init__(message, EXIT_USAGE)


_REGISTRY: Registry | None = None
_DISCOVERY = threading.RLock()


def registry() -> Registry:
    """The registry of this process (discovered on first use)."""
    global _REGISTRY
    if _REGISTRY is None:
        with _DISCOVERY:
            if _REGISTRY is None:
                _REGISTRY = Registry(_discover())
    return _REGISTRY
