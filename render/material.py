"""MDL's material model: the material structs, df expression nodes, and ``shade``.

A material is the frozen struct tree MDL defines (spec 1.10, Handbook Listing 11.1)::

    material(thin_walled=False, surface=material_surface(), backface=material_surface(),
             ior=(1, 1, 1), volume=material_volume(), geometry=material_geometry())

Every *varying* field or df parameter is a constant or a callable ``f(state) -> array``
of a :class:`~displacement.state.ShadingState` with ``n`` lanes (``(n,)`` for floats,
``(n, 2)`` for float2, ``(n, 3)`` for float3 and color), exactly as the Handbook passes
function calls as arguments (chapter 9).  Distribution functions are unbound expression
nodes (:class:`DfNode`): ``df.simple_glossy_bsdf(tint=..., roughness_u=0.3)`` records the
MDL name and arguments; :meth:`DfNode.bind` evaluates the arguments over the lanes of a
state and instantiates the :mod:`render.df` class of the same name.

The integrator uses one entry point, :meth:`material.shade`, which applies the geometry
fields in MDL's order (spec; Handbook section 11.2):

1. ``displacement`` is realized by dicing (``displacement.dice``) before shading, so the
   state passed in already describes the displaced surface;
2. ``cutout_opacity`` is evaluated on that state and clamped to [0, 1];
3. ``normal`` replaces the shading normal (normalized; zero or non-finite rows fall back
   to ``state.normal``; bent back above the horizon by ``displacement.bump``'s rule,
   :func:`displacement.bump.clamp_to_horizon`), and every later expression, every df
   argument included, is evaluated on the state whose ``normal`` is the replaced one.

Additions to the render contract above:

* :class:`Shading` also carries ``frame`` (``Frame.from_normal_tangent(normal,
  state.tangent_u)``), the local frame in which the bound dfs expect ``wo``/``wi``
  (``tangent_u`` arguments are converted into it), ``state`` (the state with the
  replaced normal), ``ior`` and ``thin_walled``.
* :meth:`DfNode.bind` takes renderer context as keywords (``ior_outside``,
  ``ior_inside``, ``thin_walled``, ``object_to_local``), passed to the df classes that
  accept them; :meth:`material.shade` supplies them from the material.
* MDL types of parameters are Python annotations (``Float``, ``Color``, ``Float2``,
  ``Material``..., :class:`MdlType` in :data:`typing.Annotated` metadata);
  :func:`mdl_signature` reads them for :mod:`render.expr`.
"""

from __future__ import annotations

import difflib
import functools
import inspect
import typing
from collections.abc import Callable, Mapping
from dataclasses import dataclass, field
from types import MappingProxyType, SimpleNamespace
from typing import Annotated, Any

import numpy as np

from displacement.bump import HORIZON_MIN_COS, clamp_to_horizon
from displacement.fields import Field
from displacement.fields import constant as constant_field
from displacement.state import ShadingState
from render.bsdf import Bsdf, Edf
from render.df._registry import registry
from render.frame import Frame

__all__ = [
    "MdlType",
    "MdlParam",
    "mdl_signature",
    "Float",
    "UniformFloat",
    "Float2",
    "UniformFloat2",
    "Float3",
    "Color",
    "UniformColor",
    "Bool",
    "UniformBool",
    "Int",
    "UniformInt",
    "String",
    "Texture2D",
    "PwCurve",
    "Material",
    "BsdfArg",
    "EdfArg",
    "VdfArg",
    "MappingMode",
    "DisplacementDirection",
    "ScatterModeArg",
    "IntensityMode",
    "Gamma",
    "Varying",
    "evaluate",
    "DfNode",
    "df",
    "DF_SIGNATURES",
    "OVERLOADS",
    "MDL_NAMES",
    "COMPONENT_KINDS",
    "material_emission",
    "material_surface",
    "material_volume",
    "material_geometry",
    "material",
    "Shading",
]


# ---------------------------------------------------------------------------
# MDL types as annotations


@dataclass(frozen=True)
class MdlType:
    """The MDL type of a parameter or a value.

    Parameters
    ----------
    name : str
        ``"float"``, ``"float2"``, ``"float3"``, ``"color"``, ``"bool"``, ``"int"``,
        ``"string"``, ``"texture_2d"``, ``"pw_curve"``, ``"material"``, ``"bsdf"``,
        ``"edf"``, ``"vdf"``, or an enum type name.
    uniform : bool
        MDL ``uniform``: the argument must be a constant (not a function of state).
    values : tuple of str
        The enumerators, for enum types.

    Examples
    --------
    >>> str(MdlType("float2", uniform=True))
    'uniform float2'
    """

    name: str
    uniform: bool = False
    values: tuple[str, ...] = ()

    def __str__(self) -> str:
        return ("uniform " if self.uniform else "") + self.name

    @property
    def is_enum(self) -> bool:
        """True for enum types (``values`` lists the enumerators)."""
        return bool(self.values)


_MAPPING_MODES = ("uvw", "object", "world")
_DIRECTIONS = ("along_u", "along_v")
_SCATTER_MODES = ("scatter_reflect", "scatter_transmit", "scatter_reflect_transmit")
_INTENSITY_MODES = ("intensity_radiant_exitance", "intensity_power")
_GAMMAS = ("gamma_default", "gamma_linear", "gamma_srgb")

#: ``float`` (varying): a number or ``f(state) -> (n,)``.
Float = Annotated[Any, MdlType("float")]
UniformFloat = Annotated[Any, MdlType("float", True)]
#: ``float2``: two numbers or ``f(state) -> (n, 2)``.
Float2 = Annotated[Any, MdlType("float2")]
UniformFloat2 = Annotated[Any, MdlType("float2", True)]
#: ``float3``: three numbers or ``f(state) -> (n, 3)`` (a displacement Field is one).
Float3 = Annotated[Any, MdlType("float3")]
#: ``color`` (linear RGB): three numbers or ``f(state) -> (n, 3)``.
Color = Annotated[Any, MdlType("color")]
UniformColor = Annotated[Any, MdlType("color", True)]
Bool = Annotated[bool, MdlType("bool")]
UniformBool = Annotated[bool, MdlType("bool", True)]
Int = Annotated[int, MdlType("int")]
UniformInt = Annotated[int, MdlType("int", True)]
String = Annotated[str, MdlType("string", True)]
#: ``uniform texture_2d``: a :class:`displacement.textures.Texture` (None = ``texture_2d()``).
Texture2D = Annotated[Any, MdlType("texture_2d", True)]
#: ``uniform pw_curve::pw_point[<N>]``: a compiled :class:`pwc.Curve`.
PwCurve = Annotated[Any, MdlType("pw_curve", True)]
#: a :class:`material` instance.
Material = Annotated[Any, MdlType("material")]
BsdfArg = Annotated[Any, MdlType("bsdf")]
EdfArg = Annotated[Any, MdlType("edf")]
VdfArg = Annotated[Any, MdlType("vdf")]
#: Handbook Listing 9.15's ``mapping_mode`` enum.
MappingMode = Annotated[str, MdlType("mapping_mode", True, _MAPPING_MODES)]
#: Handbook Listing 15.7's ``displacement_direction`` enum.
DisplacementDirection = Annotated[str, MdlType("displacement_direction", True, _DIRECTIONS)]
ScatterModeArg = Annotated[str, MdlType("scatter_mode", True, _SCATTER_MODES)]
IntensityMode = Annotated[str, MdlType("intensity_mode", True, _INTENSITY_MODES)]
Gamma = Annotated[str, MdlType("gamma_mode", True, _GAMMAS)]


@dataclass(frozen=True)
class MdlParam:
    """One parameter of an MDL-callable Python function.

    Parameters
    ----------
    name : str
    type : MdlType
    required : bool
        No default (the Handbook gives none).
    default : object
        The default value (``inspect.Parameter.empty`` when required).
    """

    name: str
    type: MdlType
    required: bool
    default: Any = inspect.Parameter.empty


def _mdl_type_of(hint: Any) -> MdlType | None:
    if typing.get_origin(hint) is Annotated:
        for meta in hint.__metadata__:
            if isinstance(meta, MdlType):
                return meta
    if hint is material:
        return MdlType("material")
    return None


def mdl_signature(function: Callable) -> tuple[list[MdlParam], MdlType | None]:
    """The MDL parameters and return type of a function annotated with this module's types.

    Parameters
    ----------
    function : callable
        A material (``render.materials.MATERIALS``), a library function or a df
        constructor; every parameter must carry an MDL type annotation.

    Returns
    -------
    params : list of MdlParam
        In declaration order.
    returns : MdlType or None
        ``MdlType("material")`` for materials; None if unannotated.

    Examples
    --------
    >>> params, returns = mdl_signature(df.diffuse_reflection_bsdf)
    >>> [(p.name, str(p.type)) for p in params][:2], str(returns)
    ([('tint', 'color'), ('roughness', 'float')], 'bsdf')
    """
    hints = typing.get_type_hints(function, include_extras=True)
    params = []
    for p in inspect.signature(function).parameters.values():
        if p.kind in (p.VAR_POSITIONAL, p.VAR_KEYWORD):
            continue
        t = _mdl_type_of(hints.get(p.name))
        if t is None:
            raise TypeError(
                f"{getattr(function, '__name__', function)}: parameter {p.name!r} has no MDL "
                "type annotation (use render.material.Float, Color, Float2, ...)"
            )
        params.append(MdlParam(p.name, t, p.default is p.empty, p.default))
    return params, _mdl_type_of(hints.get("return"))


# ---------------------------------------------------------------------------
# varying values


class Varying:
    """A varying expression: ``f(state) -> array`` with a name for display.

    Parameters
    ----------
    function : callable ShadingState -> array
    name : str
        The MDL function it stands for (``"uv_wave"``).
    parameters : dict
        Its arguments, for ``repr``.

    Examples
    --------
    >>> from displacement.surfaces import UnitSquare
    >>> u = Varying(lambda s: s.uv[:, 0], "u")
    >>> u(UnitSquare().state_at_uv(np.array([[0.25, 0.5]]))).tolist(), repr(u)
    ([0.25], 'u()')
    """

    __slots__ = ("function", "name", "parameters")

    def __init__(self, function: Callable[[ShadingState], np.ndarray], name: str = "",
                 parameters: Mapping[str, Any] | None = None):
        self.function = function
        self.name = name
        self.parameters = dict(parameters or {})

    def __call__(self, state: ShadingState) -> np.ndarray:
        return self.function(state)

    def __repr__(self) -> str:
        args = ", ".join(f"{k}: {_short(v)}" for k, v in self.parameters.items())
        return f"{self.name or 'varying'}({args})"


def _short(value: Any) -> str:
    if isinstance(value, np.ndarray):
        return repr(value.tolist())
    return repr(value)


_WIDTH = {"float": None, "float2": 2, "float3": 3, "color": 3}


def evaluate(value: Any, state: ShadingState, kind: str, name: str = "value") -> np.ndarray:
    """A varying argument over the lanes of ``state``.

    Parameters
    ----------
    value : number, array_like or callable(state) -> array
        A constant (a scalar means ``float2(x)``, ``color(x)``...; a ``(2,)``/``(3,)``
        vector is one constant vector) or a function of the state returning ``(n,)``,
        ``(n, 2)`` or ``(n, 3)`` (or a constant of those shapes).
    state : ShadingState with n lanes
    kind : {"float", "float2", "float3", "color"}
    name : str
        Parameter name for error messages.

    Returns
    -------
    (n,), (n, 2) or (n, 3) float64, finite

    Raises
    ------
    ValueError
        Wrong shape, or non-finite values.

    Examples
    --------
    >>> from displacement.surfaces import UnitSquare
    >>> s = UnitSquare().state_at_uv(np.array([[0.25, 0.5], [0.75, 0.0]]))
    >>> evaluate(0.5, s, "color").tolist()
    [[0.5, 0.5, 0.5], [0.5, 0.5, 0.5]]
    >>> evaluate(lambda st: st.uv[:, 0], s, "float").tolist()
    [0.25, 0.75]
    """
    if kind not in _WIDTH:
        raise ValueError(f"kind must be one of {sorted(_WIDTH)}, got {kind!r}")
    n = len(state)
    raw = value(state) if callable(value) else value
    try:
        a = np.asarray(raw, dtype=np.float64)
    except (TypeError, ValueError):
        raise ValueError(
            f"{name} must be a number, a vector or a function of the state returning "
            f"numbers; got {type(raw).__name__}"
        ) from None
    width = _WIDTH[kind]
    if width is None:
        if a.ndim == 0 or a.shape == (n,):
            out = np.broadcast_to(a, (n,))
        else:
            raise ValueError(
                f"{name} (a {kind}) must be a number or have shape ({n},), got {a.shape}")
    elif a.ndim == 0 or a.shape == (width,) or a.shape == (n, width):
        out = np.broadcast_to(a if a.ndim != 0 else np.full(width, float(a)), (n, width))
    else:
        raise ValueError(
            f"{name} (a {kind}) must be a number, {width} numbers or have shape "
            f"({n}, {width}), got {a.shape}"
        )
    if not np.all(np.isfinite(out)):
        raise ValueError(f"{name} (a {kind}) has non-finite values (NaN or inf)")
    return out


def _check_constant(value: Any, t: MdlType, where: str) -> Any:
    """Validate a constant argument of type ``t`` (callables are checked when bound)."""
    if t.name in _WIDTH:
        if callable(value):
            if t.uniform:
                raise ValueError(f"{where} is uniform: pass a constant, not a function of state")
            return value
        width = _WIDTH[t.name]
        try:
            a = np.asarray(value, dtype=np.float64)
        except (TypeError, ValueError):
            raise ValueError(f"{where} must be a {t.name}, got {value!r}") from None
        ok_shape = a.ndim == 0 if width is None else (a.ndim == 0 or a.shape == (width,))
        if not ok_shape:
            raise ValueError(f"{where} must be a {t.name}, got shape {a.shape}")
        if not np.all(np.isfinite(a)):
            raise ValueError(f"{where} must be finite, got {value!r}")
        return value
    if t.is_enum:
        name = str(value).split("::")[-1]
        if name not in t.values:
            hint = difflib.get_close_matches(name, t.values, 1)
            raise ValueError(
                f"{where} must be one of {', '.join(t.values)}, got {value!r}"
                + (f" (did you mean {hint[0]!r}?)" if hint else "")
            )
        return name
    if t.name == "bsdf_measurement":
        from render.df._mbsdf import Measurement

        if not isinstance(value, Measurement):
            raise ValueError(f"{where} must be a bsdf_measurement, e.g. "
                             f"bsdf_measurement(\"paint.mbsdf\"), got {value!r}")
        return value
    if t.name == "light_profile":
        from render.df._ies import LightProfile

        if not isinstance(value, LightProfile):
            raise ValueError(f"{where} must be a light_profile, e.g. "
                             f"light_profile(\"lamp.ies\"), got {value!r}")
        return value
    if t.name in ("color[]", "float[]"):
        if callable(value) or any(callable(v) for v in np.atleast_1d(
                np.asarray(value, dtype=object)).ravel()):
            raise ValueError(f"{where} is uniform: give constant values, not functions of "
                             "the state")
        width = 3 if t.name == "color[]" else 1
        try:
            a = np.asarray(value, dtype=np.float64)
        except (TypeError, ValueError):
            raise ValueError(f"{where} must be an array of {t.name[:-2]} values, e.g. "
                             f"{t.name[:-2]}[]({t.name[:-2]}(0.9), {t.name[:-2]}(0.2)), got "
                             f"{value!r}") from None
        if a.size == 0 or (width == 3 and (a.ndim != 2 or a.shape[1] != 3)) or (
                width == 1 and a.ndim != 1):
            raise ValueError(f"{where} must be a non-empty array of {t.name[:-2]} values "
                             f"(shape (N, {width})), got shape {a.shape}")
        if not np.all(np.isfinite(a)):
            raise ValueError(f"{where} must be finite, got {value!r}")
        return a
    if t.name.endswith("[]"):
        return _check_components(value, t.name[:-2], where)
    if t.name in ("bsdf", "edf", "vdf"):
        if value is not None and not (isinstance(value, DfNode) and value.kind == t.name):
            raise ValueError(f"{where} must be a {t.name} (a df node), got {value!r}")
    if t.name == "bool" and not isinstance(value, bool | np.bool_):
        raise ValueError(f"{where} must be a bool, got {value!r}")
    if t.name == "string" and not isinstance(value, str):
        raise ValueError(f"{where} must be a string, got {value!r}")
    return value


# ---------------------------------------------------------------------------
# df expression nodes


class _StateDefault:
    """A default that MDL takes from the renderer state (``state::texture_tangent_u(0)``)."""

    def __init__(self, text: str):
        self.text = text

    def __repr__(self) -> str:
        return self.text


_REQ = inspect.Parameter.empty
_TANGENT_U = _StateDefault("state::texture_tangent_u(0)")
_SAME_AS_U = _StateDefault("roughness_u")
_NORMAL = _StateDefault("state::normal()")
_DIFFUSE_DEFAULT = _StateDefault("df::diffuse_reflection_bsdf()")
_SAME_AS_R = _StateDefault("roughness_R")
_SAME_AS_TT = _StateDefault("roughness_TT")
#: ``bsdf_component[<N>]`` / ``color_bsdf_component[<N>]`` (the mixers' edf and vdf overloads
#: take ``edf_component`` / ``vdf_component`` arrays, and their colour forms, through the same
#: parameter)
BsdfComponents = Annotated[Any, MdlType("bsdf_component[]")]
ColorBsdfComponents = Annotated[Any, MdlType("color_bsdf_component[]")]
#: the component kinds an array parameter of each element type takes (the first: its own)
COMPONENT_KINDS = {"bsdf_component": ("bsdf_component", "edf_component", "vdf_component"),
                "color_bsdf_component": ("color_bsdf_component", "color_edf_component",
                                         "color_vdf_component")}


def _check_components(value: Any, element: str, where: str) -> tuple:
    """An array argument: a list or tuple of component nodes of one kind."""
    kinds = COMPONENT_KINDS.get(element, (element,))
    if not isinstance(value, list | tuple) or not all(
            isinstance(v, DfNode) and v.kind in kinds for v in value):
        raise ValueError(
            f"{where} must be an array (a list) of {' or '.join(kinds)} nodes, e.g. "
            f"[df.{element}(weight=0.5, component=...)], got {value!r}")
    if len({v.kind for v in value}) > 1:
        raise ValueError(f"{where} mixes {' and '.join(sorted({v.kind for v in value}))} "
                         "components; use one kind")
    return tuple(value)


def _layer_params(weight_type, weight_default) -> tuple:
    return (("weight", weight_type, weight_default), ("layer", BsdfArg, None),
            ("base", BsdfArg, None), ("normal", Float3, _NORMAL))


_PI = float(np.pi)

UniformFloat3x3 = Annotated[Any, MdlType("float3x3", True)]
UniformColorArray = Annotated[Any, MdlType("color[]", True)]
UniformBsdfMeasurement = Annotated[Any, MdlType("bsdf_measurement", True)]

#: MDL types of the parameters a df SIGNATURE declares (type name, uniform) -> annotation
_PARAM_TYPES = {
    ("float", False): Float, ("float", True): UniformFloat,
    ("color", False): Color, ("color", True): UniformColor,
    ("float3", False): Float3, ("float3x3", True): UniformFloat3x3,
    ("bool", False): Bool, ("bool", True): UniformBool,
    ("string", False): String, ("string", True): String,
    ("scatter_mode", True): ScatterModeArg,
    ("bsdf", False): BsdfArg, ("edf", False): EdfArg, ("vdf", False): VdfArg,
    ("color[]", True): UniformColorArray,
    ("bsdf_measurement", True): UniformBsdfMeasurement,
    ("light_profile", True): Annotated[Any, MdlType("light_profile", True)],
    ("texture_2d", True): Texture2D,
    ("float2", False): Float2,
    ("bsdf_component[]", False): BsdfComponents,
    ("color_bsdf_component[]", False): ColorBsdfComponents,
}
#: defaults that MDL takes from the state or from another parameter
_STATE_DEFAULTS = {d.text: d for d in (_TANGENT_U, _SAME_AS_U, _NORMAL, _DIFFUSE_DEFAULT,
                                        _SAME_AS_R, _SAME_AS_TT)}
def _df_signatures() -> Mapping[str, tuple[str, tuple[tuple[str, Any, Any], ...]]]:
    """The dfs' MDL signatures, from the declarations of the df modules
    (:mod:`render.df._registry`): the one place they are written."""
    from render.df._signature import REQUIRED

    out = {}
    for name, declaration in registry().dfs.items():
        params = []
        for p in declaration.signature.params:
            if not p.mdl:
                continue
            d = p.default
            if d is REQUIRED:
                d = _REQ
            elif isinstance(d, str) and d in _STATE_DEFAULTS:
                d = _STATE_DEFAULTS[d]
            params.append((p.name, _PARAM_TYPES[p.type, p.uniform], d))
        out[name] = (declaration.signature.kind, tuple(params))
    return MappingProxyType(out)


#: MDL signatures of the distribution functions: name -> (kind, ((param, type, default),...)).
#: Defaults are MDL's (spec 1.10); ``_REQ`` marks parameters without one.
DF_SIGNATURES = _df_signatures()
#: MDL names with several overloads: name -> the DF_SIGNATURES keys of its overloads, in
#: the order a call tries them (the first whose parameters take the arguments)
OVERLOADS = MappingProxyType(registry().overloads())
#: the MDL name of each key that is not MDL's name (another overload of that name)
MDL_NAMES = MappingProxyType({k: d.mdl_name for k, d in registry().dfs.items()
                              if d.mdl_name != k})

_KIND_TYPES = {"bsdf": BsdfArg, "edf": EdfArg, "vdf": VdfArg,
               "hair_bsdf": Annotated[Any, MdlType("hair_bsdf")]}
_KIND_TYPES.update({k: Annotated[Any, MdlType(k)] for k in (
    "bsdf_component", "color_bsdf_component", "edf_component", "color_edf_component",
    "vdf_component", "color_vdf_component")})
#: renderer context a df class may take (not MDL arguments)
_CONTEXT = ("ior_outside", "ior_inside", "thin_walled", "object_to_local")


@functools.lru_cache(maxsize=None)
def _df_params(name: str) -> Mapping[str, tuple[MdlType, Any]]:
    """``{param: (MdlType, default)}`` of a df, built once per name (read-only)."""
    _, params = DF_SIGNATURES[name]
    return MappingProxyType({p: (_mdl_type_of(t), d) for p, t, d in params})


@functools.lru_cache(maxsize=None)
def _accepted_parameters(cls: Callable) -> frozenset[str]:
    """Parameter names of a :mod:`render.df` class, once per class (``inspect.signature``
    on every bind cost 3-5 % of render time)."""
    return frozenset(inspect.signature(cls).parameters)


# what DfNode.bind does with each argument (the per-node plan, see DfNode._bind_plan)
_BIND_NODE, _BIND_ARRAY, _BIND_TANGENT, _BIND_VARYING, _BIND_CONSTANT, _BIND_REJECT = range(6)


@dataclass(frozen=True, eq=False)
class DfNode:
    """An unbound distribution function: MDL name plus arguments (an expression node).

    Build with the constructors in :data:`df` (``df.diffuse_reflection_bsdf(tint=0.5)``).

    Parameters
    ----------
    name : str
        MDL df name (a key of :data:`DF_SIGNATURES`).
    kwargs : mapping
        The arguments given (constants, callables of state, or nested DfNodes);
        parameters left out take MDL's defaults.

    Examples
    --------
    >>> node = df.simple_glossy_bsdf(roughness_u=0.3, tint=(0.6, 0.4, 0.0))
    >>> node.kind, sorted(node.kwargs)
    ('bsdf', ['roughness_u', 'tint'])
    >>> df.diffuse_reflection_bsdf(tnt=0.5)
    Traceback (most recent call last):
    ...
    ValueError: df::diffuse_reflection_bsdf has no parameter 'tnt' (did you mean 'tint'?)
    """

    name: str
    kwargs: Mapping[str, Any] = field(default_factory=dict)

    def __post_init__(self) -> None:
        if self.name not in DF_SIGNATURES:
            hint = difflib.get_close_matches(self.name, DF_SIGNATURES, 1)
            raise ValueError(
                f"unknown distribution function {self.name!r}"
                + (f" (did you mean {hint[0]!r}?)" if hint else "")
            )
        params = _df_params(self.name)
        checked = {}
        for key, value in dict(self.kwargs).items():
            if key not in params:
                hint = difflib.get_close_matches(key, params, 1)
                raise ValueError(
                    f"df::{self.name} has no parameter {key!r}"
                    + (f" (did you mean {hint[0]!r}?)" if hint else "")
                )
            checked[key] = _check_constant(value, params[key][0], f"df::{self.name}({key})")
        missing = [p for p, (_, d) in params.items() if d is _REQ and p not in checked]
        if missing:
            raise ValueError(
                f"df::{self.name} needs the argument {missing[0]!r} (it has no default)")
        object.__setattr__(self, "kwargs", MappingProxyType(checked))

    @property
    def kind(self) -> str:
        """``"bsdf"``, ``"edf"`` or ``"vdf"``."""
        components = self.kwargs.get("components")
        if components and components[0].kind in ("edf_component", "color_edf_component"):
            return "edf"  # the mixers' edf overloads
        if components and components[0].kind in ("vdf_component", "color_vdf_component"):
            return "vdf"  # and their vdf overloads
        return DF_SIGNATURES[self.name][0]

    @property
    def is_black(self) -> bool:
        """True when the node trivially scatters nothing: a constant zero ``tint`` (and
        no multiscatter tint).  Such lobes are skipped (``shade`` returns ``bsdf=None``)."""
        tint = self.kwargs.get("tint", 1.0)
        if callable(tint) or isinstance(tint, DfNode):
            return False
        ms = self.kwargs.get("multiscatter_tint", 0.0)
        if callable(ms):
            return False
        return bool(np.all(np.asarray(tint, dtype=np.float64) <= 0.0)
                    and np.all(np.asarray(ms, dtype=np.float64) <= 0.0))

    def bind(self, state: ShadingState, **context) -> Bsdf | Edf:
        """Evaluate the arguments over the lanes of ``state`` and build the :mod:`render.df` df.

        Parameters
        ----------
        state : ShadingState
            The shading state (with the material's replaced normal).
        **context
            Renderer values passed to df classes that take them: ``ior_outside``,
            ``ior_inside`` ((n,) or float), ``thin_walled`` (bool), ``object_to_local``
            ((n, 3, 3), for ``spot_edf``).  Nested dfs (a layer's ``layer`` and ``base``,
            mix components) are bound with the same context plus ``frame_normal``, the
            (n, 3) object-space normal of the frame they are evaluated in: a layer's
            ``normal`` for its ``layer``, the inherited one for everything else.

        Returns
        -------
        Bsdf or Edf
            A ``tangent_u`` argument (object space) is expressed in the local frame
            ``Frame.from_normal_tangent(state.normal, state.tangent_u)`` (the
            ``frame_normal`` instead of ``state.normal`` inside a layer with its own
            normal); a layer's ``normal`` (default ``state::normal()``) is expressed in
            that frame too, with ``tangent_u`` orienting the layer's frame.

        Raises
        ------
        ValueError
            A callable argument returned a wrong shape or non-finite values; the df has
            no implementation in :mod:`render.df`; or a parameter that the implementation
            does not support yet was given a non-default value.
        """
        frame_normal = context.pop("frame_normal", None)
        unknown = set(context) - set(_CONTEXT)
        if unknown:
            raise ValueError(f"unknown bind context {sorted(unknown)}; allowed: {_CONTEXT}")
        cls, accepted, is_layer, steps = self._bind_plan()
        kw: dict[str, Any] = {}
        # the frame this df is evaluated in: the material's, or an enclosing layer's
        frame_n = state.normal if frame_normal is None else frame_normal
        inner = context if frame_normal is None else dict(context, frame_normal=frame_normal)
        layer_context = inner
        if is_layer and ("normal" in self.kwargs or frame_normal is not None):
            kw["normal"], kw["tangent_u"], own = _layer_normal(
                self.kwargs.get("normal"), state, frame_n, self.name)
            layer_context = dict(context, frame_normal=own)
        for key, action, value, known, default, type_name in steps:
            if action == _BIND_NODE:
                value = value.bind(state, **(layer_context if key == "layer" else inner))
            elif action == _BIND_ARRAY:
                value = [v.bind(state, **inner) for v in value]
            elif action == _BIND_TANGENT:
                tangent = evaluate(value, state, "float3", f"df::{self.name}(tangent_u)")
                value = Frame.from_normal_tangent(frame_n, state.tangent_u).to_local(tangent)
            elif action == _BIND_VARYING:
                value = evaluate(value, state, type_name, f"df::{self.name}({key})")
            if not known:
                # (constants equal to their defaults are already out of the plan)
                if action != _BIND_REJECT and not callable(value) and _equal(value, default):
                    continue
                raise ValueError(
                    f"df::{self.name}({key}) is not implemented by render.df.{self.name} yet; "
                    f"leave it at its default {default!r}"
                )
            kw[key] = value
        for key, value in context.items():
            if key in accepted:
                kw[key] = value
        return cls(**kw)

    def _bind_plan(self) -> tuple[Callable, frozenset, bool, tuple]:
        """The per-node constant part of :meth:`bind`, worked out on the first bind.

        Returns ``(cls, accepted, is_layer, steps)``: the :mod:`render.df` class, its
        parameter names, whether the df is a layer with a ``normal``, and per argument
        ``(key, action, value, accepted, default, MDL type name)`` in argument order
        (handles, a layer's ``normal`` and unsupported constants equal to their defaults
        are left out).  The node is immutable, so the plan is kept on it (``__dict__``;
        the dataclass is frozen); a node that cannot be bound raises on every bind, as
        before.
        """
        plan = self.__dict__.get("_plan")
        if plan is not None:
            return plan
        import render.df as df_module

        cls = getattr(df_module, self.name, None)
        if cls is None:
            raise ValueError(
                f"df::{self.name} has no implementation in render.df yet; it cannot be shaded"
            )
        accepted = _accepted_parameters(cls)
        params = _df_params(self.name)
        is_layer = "normal" in params and params["normal"][1] is _NORMAL
        steps = []
        for key, value in self.kwargs.items():
            t, default = params[key]
            if key == "handle" or (is_layer and key == "normal"):
                continue  # handles only tag lobes for light-path expressions
            if isinstance(value, DfNode):
                action = _BIND_NODE
            elif t.name.endswith("[]") and t.name not in ("color[]", "float[]"):
                action = _BIND_ARRAY  # (component arrays; a curve's values are constants)
            elif key == "tangent_u":
                action = _BIND_TANGENT
            elif callable(value) and t.name in _WIDTH:
                action = _BIND_VARYING
            else:
                action = _BIND_CONSTANT
            known = key in accepted
            if not known and action == _BIND_CONSTANT:
                if not callable(value) and _equal(value, default):
                    continue
                action = _BIND_REJECT
            steps.append((key, action, value, known, default, t.name))
        plan = (cls, accepted, is_layer, tuple(steps))
        self.__dict__["_plan"] = plan
        return plan

    def __repr__(self) -> str:
        args = ", ".join(f"{k}: {_short(v)}" for k, v in self.kwargs.items())
        return f"df::{MDL_NAMES.get(self.name, self.name)}({args})"


def _layer_normal(value: Any, state: ShadingState, frame_normal: np.ndarray,
                  name: str) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """A layer's ``normal`` argument (None: ``state::normal()``) for its df class.

    Returns the normal and ``state.tangent_u`` in the local frame of ``frame_normal``,
    and the normalised object-space normal (zero rows fall back to ``frame_normal``).
    """
    from render.numerics import unitize

    raw = state.normal if value is None else evaluate(value, state, "float3",
                                                      f"df::{name}(normal)")
    own, ok = unitize(np.asarray(raw, dtype=np.float64))
    own = np.where(ok[:, None], own, frame_normal)
    frame = Frame.from_normal_tangent(frame_normal, state.tangent_u)
    return frame.to_local(own), frame.to_local(state.tangent_u), own


def _equal(a: Any, b: Any) -> bool:
    try:
        return bool(np.all(np.asarray(a, dtype=np.float64) == np.asarray(b, dtype=np.float64)))
    except (TypeError, ValueError):
        return a == b


def _make_df_constructor(name: str) -> Callable[..., DfNode]:
    kind, params = DF_SIGNATURES[name]
    signature = inspect.Signature(
        [inspect.Parameter(p, inspect.Parameter.POSITIONAL_OR_KEYWORD, default=d, annotation=t)
         for p, t, d in params],
        return_annotation=_KIND_TYPES[kind],
    )

    def constructor(*args, **kwargs) -> DfNode:
        if len(args) > len(params):
            raise ValueError(f"df::{name} takes at most {len(params)} arguments, got {len(args)}")
        given = dict(zip((p for p, _, _ in params), args, strict=False))
        for key, value in kwargs.items():
            if key in given:
                raise ValueError(f"df::{name} got two values for {key!r}")
            given[key] = value
        return DfNode(name, given)

    constructor.__name__ = constructor.__qualname__ = name
    constructor.__signature__ = signature
    constructor.__annotations__ = {p: t for p, t, _ in params} | {"return": _KIND_TYPES[kind]}
    text = ", ".join(
        f"{_mdl_type_of(t)} {p}" + ("" if d is _REQ else f" = {d!r}") for p, t, d in params
    )
    constructor.__doc__ = f"``df::{name}``: an unbound {kind} node.\n\n``{kind} {name}({text})``"
    return constructor


def _make_overloaded(name: str) -> Callable[..., DfNode]:
    """A constructor of an MDL name with overloads (:data:`OVERLOADS`) for Python
    callers: the first overload whose parameters take the arguments and whose df
    arguments are of the kinds it declares.  (MDL text does not come here: ``::df``
    declares each overload, the front end chooses one by MDL's rules and calls its own
    constructor, :func:`render.mdlc.natives.df_key`.)"""
    constructors = [_make_df_constructor(k) for k in OVERLOADS[name]]

    def constructor(*args, **kwargs) -> DfNode:
        first = None
        for c, key in zip(constructors, OVERLOADS[name], strict=True):
            try:
                bound = c.__signature__.bind(*args, **kwargs)
            except TypeError as e:
                first = first or ValueError(f"df::{name}: {e}")
                continue
            kinds = {p: t for p, t, _ in DF_SIGNATURES[key][1]}
            bad = [p for p, v in bound.arguments.items() if isinstance(v, DfNode)
                   and _mdl_type_of(kinds[p]).name in ("bsdf", "edf", "vdf")
                   and v.kind != _mdl_type_of(kinds[p]).name]
            if bad:
                first = first or ValueError(
                    f"df::{name}({bad[0]}) must be a {_mdl_type_of(kinds[bad[0]]).name}")
                continue
            return c(*args, **kwargs)
        raise first

    constructor.__name__ = constructor.__qualname__ = name
    constructor.__signature__ = constructors[0].__signature__
    constructor.__annotations__ = constructors[0].__annotations__
    constructor.__doc__ = "\n\n".join(c.__doc__ for c in constructors)
    return constructor


#: MDL's ``df`` module as expression constructors: ``df.diffuse_reflection_bsdf(tint=...)``
#: returns an unbound :class:`DfNode`; enum values ``df.scatter_reflect`` ... are strings.
df = SimpleNamespace(
    **{name: _make_df_constructor(name) for name in DF_SIGNATURES if name not in OVERLOADS},
    **{name: _make_overloaded(name) for name in OVERLOADS},
    **{mode: mode for mode in _SCATTER_MODES},
)


# ---------------------------------------------------------------------------
# the material structs


def _check_color_field(value: Any, where: str) -> Any:
    return _check_constant(value, MdlType("color"), where)


@dataclass(frozen=True)
class material_emission:  # noqa: N801 - MDL's name
    """``material_emission(edf emission = edf(), color intensity = color(0.0),
    uniform intensity_mode mode = intensity_radiant_exitance)``.

    Parameters
    ----------
    emission : DfNode (an edf) or None
        None is MDL's ``edf()``: no emission.
    intensity : color
        Constant or ``f(state) -> (n, 3)``.
    mode : {"intensity_radiant_exitance", "intensity_power"}
    """

    emission: DfNode | None = None
    intensity: Any = (0.0, 0.0, 0.0)
    mode: str = "intensity_radiant_exitance"

    def __post_init__(self) -> None:
        if self.emission is not None and not (isinstance(self.emission, DfNode)
                                              and self.emission.kind == "edf"):
            raise ValueError(
                f"material_emission.emission must be an edf node or None, got {self.emission!r}")
        _check_color_field(self.intensity, "material_emission.intensity")
        object.__setattr__(self, "mode", _check_constant(self.mode, _mdl_type_of(IntensityMode),
                                                         "material_emission.mode"))

    @property
    def is_black(self) -> bool:
        """No edf, or a constant zero intensity."""
        if self.emission is None:
            return True
        if callable(self.intensity):
            return False
        return bool(np.all(np.asarray(self.intensity, dtype=np.float64) == 0.0))


@dataclass(frozen=True)
class material_surface:  # noqa: N801
    """``material_surface(bsdf scattering = bsdf(),
    material_emission emission = material_emission())``.

    Parameters
    ----------
    scattering : DfNode (a bsdf) or None
        None is MDL's ``bsdf()``: black, no scattering.
    emission : material_emission
    """

    scattering: DfNode | None = None
    emission: material_emission = field(default_factory=material_emission)

    def __post_init__(self) -> None:
        if self.scattering is not None and not (isinstance(self.scattering, DfNode)
                                                and self.scattering.kind == "bsdf"):
            raise ValueError(
                f"material_surface.scattering must be a bsdf node or None, got {self.scattering!r}")
        if not isinstance(self.emission, material_emission):
            raise ValueError(
                f"material_surface.emission must be a material_emission, got {self.emission!r}")

    @property
    def is_default(self) -> bool:
        """True for ``material_surface()`` (black bsdf, no edf)."""
        return self.scattering is None and self.emission.emission is None


@dataclass(frozen=True)
class material_volume:  # noqa: N801
    """``material_volume(vdf scattering = vdf(), color absorption_coefficient = color(),
    color scattering_coefficient = color(), color emission_intensity = color())``
    (coefficients per meter; ``emission_intensity``, MDL 1.7, in W / (m^3 sr)).

    Stored for the integrator's homogeneous media; ``shade`` does not evaluate it.
    """

    scattering: DfNode | None = None
    absorption_coefficient: Any = (0.0, 0.0, 0.0)
    scattering_coefficient: Any = (0.0, 0.0, 0.0)
    emission_intensity: Any = (0.0, 0.0, 0.0)

    def __post_init__(self) -> None:
        if self.scattering is not None and not (isinstance(self.scattering, DfNode)
                                                and self.scattering.kind == "vdf"):
            raise ValueError(
                f"material_volume.scattering must be a vdf node or None, got {self.scattering!r}")
        _check_color_field(self.absorption_coefficient, "material_volume.absorption_coefficient")
        _check_color_field(self.scattering_coefficient, "material_volume.scattering_coefficient")
        _check_color_field(self.emission_intensity, "material_volume.emission_intensity")


@dataclass(frozen=True)
class material_geometry:  # noqa: N801
    """``material_geometry(float3 displacement = float3(0.0), float cutout_opacity = 1.0,
    float3 normal = state::normal())``.

    Parameters
    ----------
    displacement : Field, callable(state) -> (n, 3), (3,) constant, or None
        None means no displacement (``float3(0.0)``); a constant zero vector is stored
        as None, another constant as :func:`displacement.fields.constant`.  The scene
        dices geometry only when this is not None.
    cutout_opacity : float or callable(state) -> (n,)
    normal : None, (3,) constant or callable(state) -> (n, 3)
        None is ``state::normal()`` (no bump).
    """

    displacement: Any = None
    cutout_opacity: Any = 1.0
    normal: Any = None

    def __post_init__(self) -> None:
        d = self.displacement
        if d is not None and not callable(d):
            vector = np.asarray(d, dtype=np.float64)
            if vector.shape != (3,) or not np.all(np.isfinite(vector)):
                raise ValueError(
                    f"material_geometry.displacement must be a Field, a function of state or "
                    f"three finite numbers, got {d!r}"
                )
            object.__setattr__(self, "displacement",
                               None if np.all(vector == 0.0) else constant_field(vector))
        _check_constant(self.cutout_opacity, MdlType("float"), "material_geometry.cutout_opacity")
        if self.normal is not None:
            _check_constant(self.normal, MdlType("float3"), "material_geometry.normal")


def _check_struct(value: Any, cls: type, where: str) -> None:
    if not isinstance(value, cls):
        raise ValueError(f"{where} must be a {cls.__name__}, got {value!r}")


@dataclass(frozen=True)
class material:  # noqa: N801
    """MDL's ``material`` struct (Handbook Listing 11.1).

    Parameters
    ----------
    thin_walled : bool
        Stored (its semantics, with ``backface``, are applied by the integrator).
    surface, backface : material_surface
    ior : color
        Constant or ``f(state) -> (n, 3)``; averaged over channels for the dfs.
    volume : material_volume
    geometry : material_geometry
    hair : DfNode (a hair_bsdf) or None
        MDL 1.5's ``hair`` field: how hair geometry (strands, :mod:`render.hair`) of this
        material scatters; None is ``hair_bsdf()`` (black).  Surfaces ignore it.

    Examples
    --------
    >>> from displacement.surfaces import UnitSquare
    >>> m = material(surface=material_surface(df.diffuse_reflection_bsdf(tint=0.5)))
    >>> s = m.shade(UnitSquare().state_at_uv(np.array([[0.5, 0.5]])))
    >>> type(s.bsdf).__name__, s.normal.tolist(), s.cutout_opacity.tolist()
    ('DiffuseReflectionBsdf', [[0.0, 0.0, 1.0]], [1.0])
    >>> material().shade(UnitSquare().state_at_uv(np.array([[0.5, 0.5]]))).bsdf is None
    True
    """

    thin_walled: bool = False
    surface: material_surface = field(default_factory=material_surface)
    backface: material_surface = field(default_factory=material_surface)
    ior: Any = (1.0, 1.0, 1.0)
    volume: material_volume = field(default_factory=material_volume)
    geometry: material_geometry = field(default_factory=material_geometry)
    hair: DfNode | None = None

    def __post_init__(self) -> None:
        if self.hair is not None and not (isinstance(self.hair, DfNode)
                                          and self.hair.kind == "hair_bsdf"):
            raise ValueError(f"material.hair must be a hair_bsdf node (e.g. "
                             f"df::chiang_hair_bsdf(...)) or None, got {self.hair!r}")
        if not isinstance(self.thin_walled, bool | np.bool_):
            raise ValueError(f"material.thin_walled must be a bool, got {self.thin_walled!r}")
        object.__setattr__(self, "thin_walled", bool(self.thin_walled))
        _check_struct(self.surface, material_surface, "material.surface")
        _check_struct(self.backface, material_surface, "material.backface")
        _check_struct(self.volume, material_volume, "material.volume")
        _check_struct(self.geometry, material_geometry, "material.geometry")
        _check_color_field(self.ior, "material.ior")
        if not callable(self.ior) and np.any(np.asarray(self.ior, dtype=np.float64) <= 0.0):
            raise ValueError(f"material.ior must be > 0 (an index of refraction), got {self.ior!r}")

    @property
    def displacement(self) -> Field | Callable | None:
        """``geometry.displacement`` (None: no dicing needed)."""
        return self.geometry.displacement

    def shade(self, state: ShadingState, front: np.ndarray | None = None) -> Shading:
        """Evaluate the material at the lanes of ``state`` (the integrator's entry point).

        Parameters
        ----------
        state : ShadingState with n lanes
            The hit points on the (already displaced) surface, front-facing normals.
        front : (n,) bool, optional
            Which lanes were hit on the front side (default: all).  Emission is front
            side only (MDL), except a thin-walled material with a non-default
            ``backface`` emits on the back through that backface.  For thin-walled
            materials with a non-default ``backface``, lanes must be all front or all
            back (split them before calling).

        Returns
        -------
        Shading

        Raises
        ------
        ValueError
            A varying field produced a wrong shape or NaN; or mixed front/back lanes
            for a material whose backface differs.
        """
        n = len(state)
        front = _front_mask(front, n)

        # 1. displacement: already realized by dicing (the state is the displaced surface)
        # 2. cutout_opacity, on the state before the normal is replaced
        opacity = np.clip(evaluate(self.geometry.cutout_opacity, state, "float",
                                   "material_geometry.cutout_opacity"), 0.0, 1.0)
        # 3. normal: replaces state::normal() for every later expression
        normal = _shading_normal(self.geometry.normal, state)
        shading_state = state.with_normal(normal)

        # which surface: the backface only for thin-walled materials that set one
        surface = self.surface
        back_side = False
        use_backface = self.thin_walled and not self.backface.is_default
        if use_backface and n and not np.all(front):
            if np.any(front):
                raise ValueError(
                    "material.shade: this thin-walled material has a backface; call shade "
                    "separately for front lanes and back lanes"
                )
            surface = self.backface
            back_side = True

        ior = evaluate(self.ior, shading_state, "color", "material.ior")
        if np.any(ior <= 0.0):
            raise ValueError("material.ior must be > 0 on every lane")
        # libbsdf averages a colour IOR; a constant one stays a scalar for the dfs
        ior_inside = float(np.mean(self.ior)) if not callable(self.ior) else ior.mean(axis=1)
        frame = Frame.from_normal_tangent(normal, state.tangent_u)
        context = {"ior_outside": 1.0, "ior_inside": ior_inside, "thin_walled": self.thin_walled}

        bsdf = None
        if surface.scattering is not None and not surface.scattering.is_black:
            bsdf = surface.scattering.bind(shading_state, **context)

        emission = surface.emission
        edf = None
        intensity = np.zeros((n, 3))
        if not emission.is_black:
            intensity = evaluate(emission.intensity, shading_state, "color",
                                 "material_emission.intensity").copy()
            if not use_backface:
                intensity[~front] = 0.0  # surface.emission is front side only
            if np.any(intensity != 0.0):
                # object space -> local frame (spot_edf, also inside edf mixes); a
                # backface's edf emits from the back: its frame is turned over
                turn = -1.0 if back_side else 1.0
                context["object_to_local"] = np.stack([frame.s, frame.t, turn * frame.n],
                                                      axis=1)
                edf = emission.emission.bind(shading_state, **context)
        return Shading(bsdf=bsdf, edf=edf, intensity=intensity, mode=emission.mode,
                       normal=normal, cutout_opacity=opacity, frame=frame,
                       state=shading_state, ior=ior, thin_walled=self.thin_walled)


def _front_mask(front: np.ndarray | None, n: int) -> np.ndarray:
    if front is None:
        return np.ones(n, dtype=bool)
    mask = np.asarray(front)
    if mask.shape != (n,) or mask.dtype != bool:
        raise ValueError(f"front must be a ({n},) bool array (True = front side hit), got "
                         f"{mask.dtype} {mask.shape}")
    return mask


def _shading_normal(normal: Any, state: ShadingState) -> np.ndarray:
    """``material_geometry.normal`` over the lanes: unit, finite, above the horizon."""
    if normal is None:
        return state.normal
    raw = normal(state) if callable(normal) else normal
    a = np.asarray(raw, dtype=np.float64)
    n = len(state)
    if a.shape == (3,):
        a = np.broadcast_to(a, (n, 3))
    if a.shape != (n, 3):
        raise ValueError(f"material_geometry.normal must give ({n}, 3) vectors, got {a.shape}")
    finite = np.all(np.isfinite(a), axis=1)
    a = np.where(finite[:, None], a, state.normal)  # NaN/inf rows: the unperturbed normal
    # rows that are the unperturbed normal stay it bit for bit (a zero bump is no bump)
    same = np.all(a == state.normal, axis=1)
    return np.where(same[:, None], state.normal, clamp_to_horizon(a, state.normal,
                                                                  HORIZON_MIN_COS))


@dataclass(frozen=True, eq=False)
class Shading:
    """What the integrator needs at n hit lanes of one material.

    Parameters
    ----------
    bsdf : Bsdf or None
        Bound surface bsdf; None = black (MDL's ``bsdf()``, or a trivially zero tint).
    edf : Edf or None
        Bound edf; None = no emission.
    intensity : (n, 3) float64
        ``material_emission.intensity`` (zero on back-side lanes: front emission only).
    mode : str
        ``"intensity_radiant_exitance"`` or ``"intensity_power"``.
    normal : (n, 3) float64
        Shading normal after ``material_geometry.normal``: unit, finite, with
        ``normal . state.normal >= HORIZON_MIN_COS`` (up to rounding) where bumped.
    cutout_opacity : (n,) float64 in [0, 1]
    frame : Frame
        ``Frame.from_normal_tangent(normal, state.tangent_u)``: express ``wo``/``wi``
        in it for the bound dfs.
    state : ShadingState
        The input state with ``normal`` replaced.
    ior : (n, 3) float64
        ``material.ior`` per lane.
    thin_walled : bool
    """

    bsdf: Bsdf | None
    edf: Edf | None
    intensity: np.ndarray
    mode: str
    normal: np.ndarray
    cutout_opacity: np.ndarray
    frame: Frame
    state: ShadingState
    ior: np.ndarray
    thin_walled: bool
