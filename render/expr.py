"""Material calls as scene files write them (the Handbook's figure captions), through the
MDL front end.

>>> m = parse_material("glossy_waves(distance: float2(0.02, 0.02), frequency: "
...                    "float2(10.0, 10.0), tint: color(0.6, 0.4, 0.0), use_displacement: true)")
>>> m.geometry.displacement.name, m.surface.scattering.name
('waves', 'simple_glossy_bsdf')

A call is an MDL expression (:func:`mdl.parser.parse_expression`), checked by the MDL
front end (:mod:`mdl.checker`) in the scope of :data:`render.mdlc.CAPTION_CONTEXT` and
built by :mod:`render.mdlc.instance`; there is one parser and one checker of MDL in the
workbench, for modules and for these calls alike.  The scope:

* unqualified: the Handbook's materials of :mod:`render.materials` (``glossy``,
  ``stone_ornament_2``...) and their named colours (``pink_stone``), the function
  library (``uv_wave``, ``u()``, ``grid_color``...), the ``mapping_mode`` values
  (``object``...), ``along_u``/``along_v``, the material structs and ``intensity_mode``;
* qualified: the standard modules (``math::PI``, ``state::normal()``, ``tex::gamma_srgb``,
  ``df::diffuse_reflection_bsdf``...), the Handbook's modules (``geometry::grid``,
  ``perlin_noise::summed_perlin_noise``, ``diffuse_reflection::diffuse_reflection``,
  ``pwc_examples::doric_flutes``) and every profile on the profile search path as a
  module (``ornament_2::ornament_2`` and ``ornament_2::ornament_2_length``, or the bare
  names ``ornament_2``/``ornament_2_length``).

Everything MDL allows in an expression works: arithmetic (``spread_factor * math::PI``),
``let``, member access (``glossy().surface``), ``?:``, array constructors
(``df::bsdf_component[](...)``).  Enum values are written as names (``mode: object``), not
strings; ``texture_2d("f.png")`` decodes as MDL's ``tex::gamma_default`` says (8- and 16-bit
images as sRGB, EXR linear): write ``texture_2d("f.png", tex::gamma_linear)`` for data.
Textures, ``bsdf_measurement("f.mbsdf")`` and ``light_profile("f.ies")`` files are found in
``base_dir`` first.  ``float3x3(...)`` takes MDL's columns (``df::spot_edf``'s and
``df::measured_edf``'s ``global_frame``); the df receives its rows, ``M[i][j]``.  A df
name with several MDL overloads (``df::tint`` of a bsdf with one or two tints, of an edf,
of a vdf; the mixers of bsdf, edf or vdf components) takes the overload MDL's rules choose
from the arguments.

Every error -- syntax, an unknown name (with a suggestion), a type or uniformity
mismatch, a Python material refusing a value -- is a :class:`MaterialExprError` with the
line and column of the offending text and a fix.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

from mdl.diagnostics import MdlError, Source
from mdl.parser import MAX_DEPTH
from render.library.resources import search_paths

__all__ = ["MaterialExprError", "Value", "evaluate_expression", "parse_material", "MAX_DEPTH"]


class MaterialExprError(ValueError):
    """An error in a material call, with where it is and how to fix it.

    Parameters
    ----------
    message : str
    col : int
        1-based column on ``line``.
    fix : str, optional
        A suggestion.
    line : int
        1-based line within the call's text (captions span lines).
    offset : int
        0-based character offset into the text.

    Examples
    --------
    >>> str(MaterialExprError("unknown material 'glosy'", 1, "did you mean 'glossy'?"))
    "1:1: unknown material 'glosy' (did you mean 'glossy'?)"
    """

    def __init__(self, message: str, col: int, fix: str | None = None, *, line: int = 1,
                 offset: int = 0):
        self.message = message
        self.col = col
        self.fix = fix
        self.line = line
        self.offset = offset
        super().__init__(str(self))

    def __str__(self) -> str:
        return f"{self.line}:{self.col}: {self.message}" + (f" ({self.fix})" if self.fix else "")

    def __reduce__(self):
        return (_rebuild_error, (self.message, self.col, self.fix, self.line, self.offset))


def _rebuild_error(message, col, fix, line, offset):
    return MaterialExprError(message, col, fix, line=line, offset=offset)


@dataclass(frozen=True)
class Value:
    """An evaluated call: the value as the render core takes it (a material, a df node, a
    constant, or a function of the state), its MDL type, and whether it varies."""

    value: Any
    type: Any
    varying: bool = False


def _error_from(e: MdlError, text: str) -> MaterialExprError:
    d = e.first
    line, col = d.loc.line, d.loc.col
    starts = [0]
    for k, c in enumerate(text):
        if c == "\n":
            starts.append(k + 1)
    offset = starts[min(line, len(starts)) - 1] + col - 1 if line >= 1 else 0
    offset = max(0, min(offset, len(text)))
    return MaterialExprError(d.message, col, d.fix or None, line=line, offset=offset)


def evaluate_expression(text: str, *, base_dir=None, profile_dirs=None,
                        texture_dirs=None) -> Value:
    """Check and evaluate a call (a material, a color, a function of the state...).

    Parameters
    ----------
    text : str
    base_dir : path, optional
        The scene's folder: textures and modules are looked for there first.
    profile_dirs, texture_dirs : path or sequence of paths, optional
        Searched before ``profiles/`` and ``gallery/textures/``.

    Returns
    -------
    Value

    Raises
    ------
    MaterialExprError

    Examples
    --------
    >>> evaluate_expression("color(0.6, 0.4, 0.0)").value
    (0.6, 0.4, 0.0)
    >>> round(evaluate_expression("ornament_2::ornament_2_length").value, 5) > 1.0
    True
    """
    from render.mdlc import Session
    from render.mdlc.instance import Const, MaterialInstanceError, Vary, to_core

    if not isinstance(text, str):
        raise MaterialExprError(
            f"a material expression must be a string, got {type(text).__name__}", 1)
    with search_paths(profile_dirs=profile_dirs, texture_dirs=texture_dirs):
        try:
            session = Session(base_dir)
            value, info = session.material(text, Source("<material call>", text))
        except MdlError as e:
            raise _error_from(e, text) from None
        except MaterialInstanceError as e:
            raise _error_from(MdlError([e.diagnostic()]), text) from None
    t = info.type
    if isinstance(value, (Const, Vary)):
        return Value(to_core(value, value.type), t, isinstance(value, Vary))
    return Value(value, t, False)


def parse_material(text: str, *, base_dir=None, profile_dirs=None, texture_dirs=None):
    """Build the material a call describes (``glossy(tint: color(0.6))``).

    Parameters
    ----------
    text : str
        An expression whose value is a material (usually a call of a Handbook material).
    base_dir, profile_dirs, texture_dirs
        As :func:`evaluate_expression`.

    Returns
    -------
    render.material.material

    Raises
    ------
    MaterialExprError
        Syntax, unknown names (with suggestions), argument and type errors, and errors
        raised by the material functions, each with line and column.

    Examples
    --------
    >>> parse_material("triangle(height: 0.25)").geometry.displacement.name
    'triangle'
    >>> parse_material("glosy()")  # doctest: +ELLIPSIS
    Traceback (most recent call last):
    ...
    render.expr.MaterialExprError: 1:1: unknown function 'glosy' (did you mean 'glossy'?)
    """
    from render.material import material

    v = evaluate_expression(text, base_dir=base_dir, profile_dirs=profile_dirs,
                            texture_dirs=texture_dirs)
    if not isinstance(v.value, material):
        raise MaterialExprError(f"the expression is {_a(v.type)}, not a material", 1,
                                "write a material call such as glossy(tint: color(0.6, 0.4, "
                                "0.0))")
    return v.value


def _a(t) -> str:
    s = str(t)
    return ("an " if s[:1] in "aeiou" else "a ") + s
