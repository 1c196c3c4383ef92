"""A distribution function's MDL signature, declared once beside its kernels.

Each df module declares ``SIGNATURE = Signature(kind, params, context)``.  From it:

* the expression parser (:mod:`render.expr`) and :mod:`render.material` know the
  parameter names, MDL types and defaults;
* :mod:`render.program` packs bound arguments into a row of float64 *slots*, in the
  declared order (``float`` 1 slot, ``float2`` 2, ``float3``/``color`` 3, ``bool``/``int``
  1, ``float3x3`` 9: the (3, 3) array row-major, ``M[i][j]`` at slot ``3 i + j``), clamped
  as declared, followed by the renderer context values (``ior_outside``, ``ior_inside``:
  1 slot each); uniform enum arguments (``mode``) go to the node's
  integer ``flags`` instead (:data:`MODE_FLAGS`, :data:`THIN_WALLED`), and ``handle``
  is not packed;
* the kernels read parameter ``name`` at ``P[row, b + SIGNATURE.offset(name)]``;
* an array parameter (``color[<N>] curve_values``, :data:`ARRAYS`) packs its length
  ``N`` at its offset and its elements after the fixed slots, from
  ``b + SIGNATURE.width`` (uniform: one row for all lanes).

Examples
--------
>>> sig = Signature("bsdf", (Param("tint", "color", (1.0, 1.0, 1.0), clamp=(0.0, 1.0)),
...                          Param("roughness", "float", 0.0, clamp=(0.0, 1.0)),
...                          Param("handle", "string", "")), context=("ior_inside",))
>>> sig.offset("roughness"), sig.offset("ior_inside"), sig.width
(3, 4, 5)
"""

from __future__ import annotations

from dataclasses import dataclass

__all__ = [
    "Param",
    "Signature",
    "REQUIRED",
    "WIDTH",
    "MODE_FLAGS",
    "MODE_MASK",
    "THIN_WALLED",
    "REFLECT",
    "TRANSMIT",
    "REFLECT_TRANSMIT",
    "ARRAYS",
]


class _Required:
    def __repr__(self) -> str:
        return "REQUIRED"


#: the default of a parameter that has none in MDL
REQUIRED = _Required()

#: slots per MDL type (types not listed are not packed: strings, enums, dfs)
WIDTH = {"float": 1, "float2": 2, "float3": 3, "color": 3, "bool": 1, "int": 1,
         "float3x3": 9}
#: array types packed as a count slot in place and their elements after the node's
#: fixed slots (``b + signature.width``); element widths
ARRAYS = {"color[]": 3, "float[]": 1}

#: ``flags & MODE_MASK``: ``df::scatter_mode``
REFLECT, TRANSMIT, REFLECT_TRANSMIT = 0, 1, 2
MODE_MASK = 3
MODE_FLAGS = {"scatter_reflect": REFLECT, "scatter_transmit": TRANSMIT,
              "scatter_reflect_transmit": REFLECT_TRANSMIT}
#: ``flags & THIN_WALLED``: ``material.thin_walled`` (transmission without refraction)
THIN_WALLED = 4


@dataclass(frozen=True)
class Param:
    """One MDL parameter.

    Parameters
    ----------
    name : str
        MDL's name, verbatim.
    type : str
        MDL type: ``float``, ``float2``, ``float3``, ``color``, ``bool``, ``int``,
        ``string``, ``scatter_mode``, ``bsdf``, ``edf``, ``vdf``, ...
    default : object
        MDL's default (:data:`REQUIRED` where MDL has none; a string naming a state
        function such as ``"state::texture_tangent_u(0)"`` where the default is one).
    clamp : (lo, hi) or None
        Applied per component when packing (``None`` bounds are open).
    uniform : bool
        MDL ``uniform``.
    packed : str or None
        The type the packer writes when it differs from ``type``: ``"color"`` for a
        ``float`` broadcast to three slots, so one kernel serves a df's float and colour
        forms (``weighted_layer`` and ``color_weighted_layer``).
    mdl : bool
        False for a slot that is not an MDL parameter of this form (the parser never
        offers it; the packer writes its default): it keeps the float form's slot layout
        equal to the colour form's (``f82_factor`` of ``custom_curve_layer``).
    """

    name: str
    type: str
    default: object = REQUIRED
    clamp: tuple | None = None
    uniform: bool = False
    packed: str | None = None
    mdl: bool = True

    @property
    def width(self) -> int:
        """Slots taken when packed (0: not packed); an array takes one (its length), its
        elements follow the node's fixed slots."""
        if self.type in ARRAYS:
            return 1
        return 0 if self.name == "handle" else WIDTH.get(self.packed or self.type, 0)


@dataclass(frozen=True)
class Signature:
    """A df's MDL signature plus the renderer context its kernels read.

    Parameters
    ----------
    kind : {"bsdf", "edf", "vdf"}
    params : tuple of Param
        In MDL's order.
    context : tuple of str
        Renderer values packed after the parameters (one slot each).
    """

    kind: str
    params: tuple
    context: tuple = ()

    def offset(self, name: str) -> int:
        """First slot of parameter or context value ``name`` (KeyError if not packed)."""
        at = 0
        for p in self.params:
            if p.name == name and p.width:
                return at
            at += p.width
        if name in self.context:
            return at + self.context.index(name)
        raise KeyError(f"{name!r} is not a packed parameter of this signature")

    @property
    def width(self) -> int:
        """Slots of one packed node."""
        return sum(p.width for p in self.params) + len(self.context)

    def param(self, name: str) -> Param:
        """The parameter called ``name``."""
        for p in self.params:
            if p.name == name:
                return p
        raise KeyError(name)
