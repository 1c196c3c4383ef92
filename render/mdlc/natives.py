"""The workbench's own MDL modules: what the renderer implements, declared in MDL.

:class:`WorkbenchModules` is the front end's provider (:class:`mdl.loader.Loader`) of

* ``::df`` -- the distribution functions the render core has, declared from the
  signatures each df module writes beside its kernels (:data:`render.material.DF_SIGNATURES`);
* ``::materials`` -- the Handbook's materials translated in :mod:`render.materials`
  (and its named colours, ``pink_stone``...);
* ``::functions`` -- the Handbook's function library :data:`render.library.FUNCTIONS`
  (``uv_wave``, ``grid_color``, ``perlin_noise``, ``displace_with_pwc``...) and the
  ``mapping_mode`` enum (Listing 9.15);
* ``::pw_curve`` -- the runtime ``pwc compile`` writes (:func:`pwc.emit.runtime_mdl`);
* ``::profile_arrays`` -- Listing 14.22's ``tee``;
* ``::sky`` -- the render core's sun and sky (:class:`render.sky.SunAndSky`) as the
  environment function ``sun_and_sky`` that ``::base`` re-exports;
* one module per profile on the profile search path: ``::ornament_2`` holds
  ``ornament_2`` (a ``pw_curve::pw_point[N]``) and ``ornament_2_length``, the module
  ``pwc compile`` would write for it;
* the MDL library written for the workbench in ``render/library/mdl`` (``::base``,
  ``::geometry``, ``::perlin_noise``, ``::diffuse_reflection``, ``::pwc_examples``).

The Python functions are *natives*: their MDL declarations are prototypes generated
from the Python signatures (parameter names, MDL types and defaults, as
:func:`render.material.mdl_signature` reads them), and a call runs the Python function
(:func:`bind_native`).  Library functions are declared ``varying``: they read the
state.  A parameter whose Python default has no MDL spelling (a material instance) is
declared with ``material()`` and left out of the call when the MDL call leaves it out,
so the Python default applies.
"""

from __future__ import annotations

import inspect
from functools import cache
from pathlib import Path

import numpy as np

from mdl import lanes as LN
from mdl import types as T
from mdl.loader import ModuleText

__all__ = ["WorkbenchModules", "bind_native", "LIBRARY_DIR", "native_value", "curve_from_lanes",
           "df_key", "df_module_text", "NATIVE_MODULES", "PROFILE_VALUES", "register_profiles",
           "SkyFunction", "sun_and_sky_light"]

#: the workbench's MDL library (modules written in MDL for the workbench)
LIBRARY_DIR = Path(__file__).resolve().parent.parent / "library" / "mdl"
#: modules implemented in Python
NATIVE_MODULES = ("::df", "::materials", "::functions", "::sky")


def _mdl_number(x: float) -> str:
    r = repr(float(x))
    if "e" in r and "." not in r.split("e")[0]:
        m, e = r.split("e")
        r = f"{m}.0e{e}"
    return r


def _default_text(value, mdl_type, kinds: dict) -> str | None:
    """MDL text of a Python default of a parameter of ``mdl_type`` (None: required)."""
    from render.material import _StateDefault

    if value is inspect.Parameter.empty:
        return None
    name = mdl_type.name
    if isinstance(value, _StateDefault):
        return value.text
    if name in kinds:  # an enum: its value name
        return f"{kinds[name]}{str(value).split('::')[-1]}"
    if name == "float":
        return _mdl_number(value)
    if name == "int":
        return str(int(value))
    if name == "bool":
        return "true" if value else "false"
    if name == "string":
        return '"' + str(value).replace("\\", "\\\\").replace('"', '\\"') + '"'
    if name in ("float2", "float3", "color"):
        a = np.asarray(value, dtype=np.float64).reshape(-1)
        if a.size == 1:
            return f"{name}({_mdl_number(a[0])})"
        return f"{name}({', '.join(_mdl_number(x) for x in a)})"
    if name == "texture_2d":
        return "texture_2d()"
    if name == "float3x3":
        m = np.asarray(value, dtype=np.float64)
        if np.array_equal(m, np.eye(3)):
            return "float3x3(1.0)"
        return "float3x3(" + ", ".join(_mdl_number(x) for x in m.T.reshape(-1)) + ")"
    if name == "material":
        return "material()"
    if name in ("bsdf", "edf", "vdf"):
        return f"{name}()"
    return None


_ENUM_TYPES = {
    "mapping_mode": "functions::mapping_mode",
    "displacement_direction": "pw_curve::displacement_direction",
    "scatter_mode": "df::scatter_mode",
    "intensity_mode": "intensity_mode",
    "gamma_mode": "tex::gamma_mode",
}
_ENUM_PREFIX = {
    "mapping_mode": "functions::",
    "displacement_direction": "pw_curve::",
    "scatter_mode": "df::",
    "intensity_mode": "",
    "gamma_mode": "tex::",
}


def _type_text(t, module: str, size: str = "N") -> str:
    """MDL spelling of a :class:`render.material.MdlType` inside ``module``."""
    name = t.name
    q = "uniform " if t.uniform else ""
    if name == "pw_curve":
        return f"uniform pw_curve::pw_point[<{size}>]"
    if name in _ENUM_TYPES:
        spelled = _ENUM_TYPES[name]
        if module == "::functions" and name == "mapping_mode":
            spelled = "mapping_mode"
        if module == "::df" and name == "scatter_mode":
            spelled = "scatter_mode"
        return q + spelled
    if name.endswith("[]"):
        return f"{q}{name[:-2]}[<{size}>]"
    if name == "float3x3":
        return q + "float3x3"
    return q + name


def _prefixes(module: str) -> dict:
    out = dict(_ENUM_PREFIX)
    if module == "::functions":
        out["mapping_mode"] = ""
    if module == "::df":
        out["scatter_mode"] = ""
    return out


def _declare(name: str, function, module: str, qualifier: str = "") -> str:
    from render.material import mdl_signature

    params, returns = mdl_signature(function)
    kinds = _prefixes(module)
    ps = []
    sizes = iter("NMKPQRSTUVW")
    for p in params:
        size = next(sizes) if p.type.name in ("pw_curve",) or p.type.name.endswith("[]") else "N"
        text = f"{_type_text(p.type, module, size)} {p.name}"
        d = _default_text(p.default, p.type, kinds)
        if d is not None:
            text += f" = {d}"
        elif not p.required:
            text += f" = {_default_text(inspect.Parameter.empty, p.type, kinds) or ''}"
        ps.append(text)
    ret = "float" if returns is None else returns.name
    q = f" {qualifier}" if qualifier else ""
    return f"export {ret} {name}({', '.join(ps)}){q};"


@cache
def _df_declarations() -> tuple[str, dict]:
    """``::df``'s text and which render core constructor each declaration is:
    ``{(MDL name, overload index): DF_SIGNATURES key}`` (:func:`df_key`).

    Everything comes from :data:`render.material.DF_SIGNATURES` (the ``SIGNATURE`` each
    df module declares beside its kernels): the component structs from the
    ``*_component`` signatures, a function per signature under its MDL name
    (:data:`render.material.MDL_NAMES`: ``tint_rt`` is MDL's two-tint ``tint``), and the
    mixers' edf and vdf overloads from the component kinds their array parameter takes
    (:data:`render.material.COMPONENT_KINDS`)."""
    from render.df._registry import registry
    from render.material import COMPONENT_KINDS, DF_SIGNATURES, MDL_NAMES, _mdl_type_of

    out = ["mdl 1.9;", "", "import ::state::*;", "import ::anno::*;", "",
           "// the distribution functions of the render core (render.df)",
           "export enum scatter_mode { scatter_reflect, scatter_transmit, "
           "scatter_reflect_transmit };", ""]
    keys: dict = {}
    count: dict = {}

    def declare(name: str, key: str, text: str) -> None:
        out.append(text)
        keys[name, count.get(name, 0)] = key
        count[name] = count.get(name, 0) + 1

    for name, (kind, params) in DF_SIGNATURES.items():
        if kind != name:  # a struct: its signature's kind is its name
            continue
        fields = []
        for p, t, d in params:
            mt = _mdl_type_of(t)
            dt = f"{mt.name}()" if d is None else _default_text(d, mt, _prefixes("::df"))
            fields.append(f"{_type_text(mt, '::df')} {p} = {dt};")
        out.append(f"export struct {name} {{ {' '.join(fields)} }};")
    out.append("")
    for key, (kind, params) in DF_SIGNATURES.items():
        if kind == key:
            continue
        name = MDL_NAMES.get(key, key)
        ps = []
        names = [x for x, _, _ in params]
        for p, t, d in params:
            mt = _mdl_type_of(t)
            text = f"{_type_text(mt, '::df')} {p}"
            if isinstance(d, str) and d in names:
                dt = d
            elif d is None and mt.name in ("bsdf", "edf", "vdf"):
                dt = f"{mt.name}()"
            else:
                dt = _default_text(d, mt, _prefixes("::df"))
            if dt is not None:
                text += f" = {dt.removeprefix('df::')}"  # ::df's own names, unqualified
            ps.append(text)
        why = registry().df(key).deprecated
        annotation = f' [[ anno::deprecated("{why}") ]]' if why else ""
        declare(name, key, f"export {kind} {name}({', '.join(ps)}){annotation};")
        arrays = [(p, _mdl_type_of(t).name[:-2]) for p, t, _ in params
                  if _mdl_type_of(t).name[:-2] in COMPONENT_KINDS]
        if len(params) == 1 and arrays:  # a mixer: its edf and vdf overloads
            p, element = arrays[0]
            for comp in COMPONENT_KINDS[element][1:]:
                fields = {f: _mdl_type_of(t).name for f, t, _ in DF_SIGNATURES[comp][1]}
                declare(name, key, f"export {fields['component']} {name}({comp}[<N>] {p});")
    out.append("")
    for name, (ret, param, _) in RESOURCE_QUERIES.items():
        out.append(f"export {ret} {name}(uniform {param}) uniform;")
    return "\n".join(out) + "\n", keys


#: ``::df``'s queries of a resource (MDL 1.0; ``*_isvalid`` 1.2): name -> (return type,
#: parameter, the value for the loaded resource or None, an invalid one).  Power is
#: ``∫ I dw`` over the sphere of the profile's interpolant, maximum its largest candela.
RESOURCE_QUERIES = {
    "light_profile_power": ("float", "light_profile profile",
                            lambda profile=None: 0.0 if profile is None else profile.power),
    "light_profile_maximum": ("float", "light_profile profile",
                              lambda profile=None: 0.0 if profile is None else profile.maximum),
    "light_profile_isvalid": ("bool", "light_profile profile",
                              lambda profile=None: profile is not None),
    "bsdf_measurement_isvalid": ("bool", "bsdf_measurement measurement",
                                 lambda measurement=None: measurement is not None),
}


def df_module_text() -> str:
    """The MDL text of ``::df`` (see :func:`_df_declarations`)."""
    return _df_declarations()[0]


def df_key(overload) -> str:
    """The :data:`render.material.DF_SIGNATURES` key (the constructor in
    :data:`render.material.df`) of an overload of ``::df`` the front end chose (a
    component struct's constructor: the struct's name)."""
    if overload.kind == "struct":
        return overload.name
    return _df_declarations()[1][overload.name, overload.index]


@cache
def materials_module_text() -> str:
    from render.materials import CONSTANTS, MATERIALS

    out = ["mdl 1.6;", "", "import ::tex::*;", "import ::pw_curve::*;", "import ::functions::*;",
           "", "// the Handbook's materials translated in render.materials (native)"]
    for name, c in CONSTANTS.items():
        a = np.asarray(c, dtype=np.float64)
        out.append(f"export const color {name} = color({', '.join(_mdl_number(x) for x in a)});")
    for name, f in MATERIALS.items():
        out.append(_declare(name, f, "::materials"))
    return "\n".join(out) + "\n"


#: declarations that differ from what the Python annotations say: chapter 10's noise
#: works in double (Listings 10.1-10.5), so a double3 point passes without a cast
_DECLARED = {
    "perlin_noise": "export double perlin_noise(double3 point) varying;",
    "summed_perlin_noise": "export double summed_perlin_noise(double3 point, uniform int "
                           "level_count = 4, uniform double level_scale = 0.5, uniform double "
                           "point_scale = 2.0, uniform bool turbulence = false) varying;",
}


@cache
def functions_module_text() -> str:
    from render.library.functions import FUNCTIONS

    out = ["mdl 1.6;", "", "import ::tex::*;", "import ::pw_curve::*;", "",
           "// the Handbook's function library, render.library (native)",
           "export enum mapping_mode { uvw, object, world };", ""]
    for name, f in FUNCTIONS.items():
        if "::" in name:
            continue  # state:: is the standard module
        out.append(_DECLARED.get(name) or _declare(name, f, "::functions", "varying"))
    return "\n".join(out) + "\n"


@cache
def profile_arrays_text() -> str:
    from displacement.profile import TEE

    rows = ",\n    ".join(f"float2({_mdl_number(x)}, {_mdl_number(y)})" for x, y in TEE)
    return ("mdl 1.6;\n\n// Listing 14.22's tee profile (displacement.profile.TEE)\n"
            f"export const float2[{len(TEE)}] tee(\n    {rows});\n")


#: ``::sky``: base::sun_and_sky's parameters (the names of MDL's ``::base``; the defaults
#: are the workbench's: its sky's units and size).  What the render core's sky models:
#: on, multiplier, rgb_unit_conversion, haze, ground_color, sun_direction,
#: sun_disk_intensity, sun_disk_scale, y_is_up; the rest are accepted and have no effect
#: (docs/mdl.md, "base::sun_and_sky").
SKY_MODULE = """\
mdl 1.6;

// the render core's sun and sky, render.sky.SunAndSky (native): the radiance arriving
// from state::direction() (an environment function), RGB = cd/m^2 x rgb_unit_conversion
// x multiplier.  haze is Preetham's turbidity minus 2; sun_disk_scale is the sun's
// radius in multiples of the real sun's (0.2666 degrees).
export color sun_and_sky(
    uniform bool on = true,
    uniform float multiplier = 1.0,
    uniform color rgb_unit_conversion = color(0.0001),
    uniform float haze = 1.0,
    uniform float redblueshift = 0.0,
    uniform float saturation = 1.0,
    uniform float horizon_height = 0.0,
    uniform float horizon_blur = 0.1,
    uniform color ground_color = color(0.2),
    uniform color night_color = color(0.0),
    uniform float3 sun_direction = float3(0.0, 1.0, 0.0),
    uniform float sun_disk_intensity = 1.0,
    uniform float sun_disk_scale = 1.0,
    uniform float sun_glow_intensity = 1.0,
    uniform bool y_is_up = true
) varying;
"""

#: the real sun's angular radius, degrees
SUN_RADIUS = 0.2666


class SkyFunction:
    """``sun_and_sky(...)`` as a value: the core's light (:attr:`sky`) and, called on a
    state, its radiance toward ``-state.direction``... that is, arriving along
    ``state::direction()`` looked up from the scene (MDL's environment convention)."""

    def __init__(self, sky):
        self.sky = sky

    def __call__(self, S):
        d = getattr(S, "direction", None)
        if d is None:
            return np.zeros((len(S), 3))
        return self.sky.eval(np.asarray(d, dtype=np.float64))


def sun_and_sky_light(on=True, multiplier=1.0, rgb_unit_conversion=(1e-4,) * 3, haze=1.0,
                      redblueshift=0.0, saturation=1.0, horizon_height=0.0, horizon_blur=0.1,
                      ground_color=(0.2,) * 3, night_color=(0.0,) * 3,
                      sun_direction=(0.0, 1.0, 0.0), sun_disk_intensity=1.0,
                      sun_disk_scale=1.0, sun_glow_intensity=1.0, y_is_up=True):
    """The :class:`render.sky.SunAndSky` of a ``base::sun_and_sky`` call (cached).

    Raises
    ------
    ValueError
        A value the sky refuses (a zero sun direction, haze outside [0, 8]...).
    """
    key = tuple(np.asarray(v, dtype=np.float64).round(12).tobytes() for v in (
        on, multiplier, rgb_unit_conversion, haze, ground_color, sun_direction,
        sun_disk_intensity, sun_disk_scale, y_is_up))
    if key not in _SKIES:
        _SKIES[key] = _make_sky(on, multiplier, rgb_unit_conversion, haze, ground_color,
                                sun_direction, sun_disk_intensity, sun_disk_scale, y_is_up)
    return _SKIES[key]


_SKIES: dict = {}


def _make_sky(on, multiplier, unit, haze, ground, direction, disk_intensity, disk_scale,
              y_is_up):
    from render.sky import SunAndSky

    d = np.asarray(direction, dtype=np.float64)
    if not y_is_up:
        d = np.array([d[0], d[2], -d[1]])  # z up -> the workbench's y up
    unit = np.asarray(unit, dtype=np.float64)
    if not np.allclose(unit, unit[0]):
        raise ValueError(f"rgb_unit_conversion must be grey here, got {tuple(unit)} (the "
                         "sky's colour is the model's)")
    if not 0.0 <= float(haze) <= 8.0:
        raise ValueError(f"haze must be in [0, 8] (Preetham's turbidity 2..10), got {haze}")
    intensity = float(multiplier) * float(unit[0]) / 1e-4 if on else 0.0
    return SunAndSky(d, turbidity=2.0 + float(haze), intensity=intensity,
                     sun_radius=SUN_RADIUS * float(disk_scale),
                     sun_scale=float(disk_intensity),
                     ground_albedo=np.clip(np.asarray(ground, dtype=np.float64), 0.0, 1.0))


class WorkbenchModules:
    """The front end's provider of the workbench's modules (see the module docstring)."""

    def fixed(self) -> tuple[str, ...]:
        """Modules a file of the same name does not shadow (the renderer's ``::df``)."""
        return ("::df", "::sky")

    def find(self, qname: str) -> ModuleText | None:
        name = qname.removeprefix("::")
        if name == "df":
            return ModuleText(qname, df_module_text(), "<workbench module ::df>", None, "native",
                              {"kind": "df"})
        if name == "materials":
            return ModuleText(qname, materials_module_text(), "<workbench module ::materials>",
                              None, "native", {"kind": "materials"})
        if name == "functions":
            return ModuleText(qname, functions_module_text(), "<workbench module ::functions>",
                              None, "native", {"kind": "functions"})
        if name == "sky":
            return ModuleText(qname, SKY_MODULE, "<workbench module ::sky>", None, "native",
                              {"kind": "sky"})
        if name == "pw_curve":
            from pwc.emit import runtime_mdl

            return ModuleText(qname, runtime_mdl(), "<workbench module ::pw_curve "
                              "(pwc/mdl/pw_curve.mdl)>", None, "file")
        if name == "profile_arrays":
            return ModuleText(qname, profile_arrays_text(), "<workbench module "
                              "::profile_arrays>", None, "generated")
        if "::" in name:
            return None
        f = LIBRARY_DIR / f"{name}.mdl"
        if f.is_file():
            return ModuleText(qname, f.read_text(encoding="utf-8"), str(f), f, "file")
        return self.profile(qname, name)

    def profile(self, qname: str, name: str) -> ModuleText | None:
        from render.library.resources import find_profile

        path = find_profile(name)
        if path is None:
            return None
        try:
            import pwc
            from pwc.emit import to_mdl

            text = to_mdl(pwc.load(path))  # the scene's curve is loaded where it is used
        except Exception as e:  # noqa: BLE001 - a profile that does not compile
            text = (f"mdl 1.6;\n// profile {path} does not compile:\n// "
                    + str(e).replace("\n", "\n// ") + "\n")
            return ModuleText(qname, text + f"export const int {name} = __error__;\n",
                              str(path), path, "generated")
        return ModuleText(qname, text, f"<module ::{name} compiled from {path}>", path,
                          "generated", {"kind": "profile", "name": name})

    def hint(self, qname: str) -> str:
        """Where a missing profile module would be looked for."""
        from render.library.resources import profile_dirs

        name = qname.removeprefix("::")
        if "::" in name:
            return ""
        dirs = ", ".join(str(d) for d in profile_dirs())
        return (f"no profile '{name}': there is no {name}.pwc in {dirs} (put it beside the "
                "scene, or add its folder with --profiles DIR or $PWC_PROFILE_PATH)")

    def names(self) -> list[str]:
        from render.library.resources import profile_names

        out = ["::df", "::materials", "::functions", "::sky", "::pw_curve", "::profile_arrays"]
        out += ["::" + f.stem for f in LIBRARY_DIR.glob("*.mdl")]
        out += ["::" + n for n in profile_names()]
        return out


# ----------------------------------------------------------------------------- values
class _ProfileValues(dict):
    """id(lane value of a profile module's curve constant) -> (value, profile name): a
    native taking a ``pw_point[N]`` gets the profile's :class:`pwc.Curve` as
    :func:`render.library.resources.load_profile` gives it (in the scene's curve mode)."""

    def curve(self, value):
        hit = self.get(id(value))
        if hit is None or hit[0] is not value:
            return None
        from render.library.resources import load_profile

        return load_profile(hit[1])


PROFILE_VALUES = _ProfileValues()


def register_profiles(modules) -> None:
    """Record the curve constants of the profile modules among ``modules``."""
    from mdl.entities import ConstEntity

    for m in modules:
        data = m.native if isinstance(m.native, dict) else {}
        if data.get("kind") != "profile":
            continue
        for e in m.scope.get(data["name"], []):
            if isinstance(e, ConstEntity) and e.value is not None:
                PROFILE_VALUES[id(e.value)] = (e.value, data["name"])


def curve_from_lanes(value, name: str = "mdl_array"):
    """A :class:`pwc.Curve` from a ``pw_curve::pw_point[N]`` lane value (uniform)."""
    import pwc

    kind, t, pt, center, radius, start, end = (np.asarray(v)[0] for v in value)
    seg = kind == 0
    d = np.zeros(len(t))
    d[1:] = np.where(seg[1:], np.hypot(*(pt[1:] - pt[:-1]).T),
                     np.abs(radius[1:] * (end[1:] - start[1:])))
    return pwc.Curve(name=name, type=kind.astype(np.int64), t=t.astype(np.float64),
                     pt=pt.astype(np.float64), center=center.astype(np.float64),
                     radius=radius.astype(np.float64), start_angle=start.astype(np.float64),
                     end_angle=end.astype(np.float64), length=float(d.sum()))


def _is_pw_points(t: T.Type) -> bool:
    return isinstance(t, T.ArrayT) and isinstance(t.elem, T.StructType) and \
        t.elem.name.endswith("pw_point")


def native_value(value, t: T.Type, curves: dict | None = None):
    """A uniform lane value as the Python value the workbench's functions take (a
    matrix as a numpy ``M[row, column]``, a pw_point array as a :class:`pwc.Curve`)."""
    if isinstance(t, T.Matrix):
        return np.asarray(value, dtype=np.float64)[0].T.copy()
    if _is_pw_points(t):
        curve = PROFILE_VALUES.curve(value)
        return curve if curve is not None else curve_from_lanes(value)
    return LN.to_python(value, t)


def bind_native(overload, curves: dict | None = None):
    """A lane binding ``(S, n, *args) -> lane value`` of a native library function."""
    data = overload.module.native if isinstance(overload.module.native, dict) else {}
    if data.get("kind") == "sky":
        def fn(**kwargs):
            return SkyFunction(sun_and_sky_light(**kwargs))
    elif data.get("kind") == "df":
        fn = RESOURCE_QUERIES[overload.name][2]
    else:
        from render.library.functions import FUNCTIONS

        fn = FUNCTIONS[overload.name]
    params = overload.params
    ret = overload.ret

    def call(S, n, *args):
        kwargs = {}
        for p, a in zip(params, args, strict=False):
            if a is None:
                continue
            if isinstance(a, np.ndarray) and a.shape[0] == n and n != 1 and \
                    not isinstance(p.type, T.ArrayT):
                v = a.astype(np.float64) if a.dtype != np.bool_ else a
            else:
                v = native_value(a, p.type, curves)
            kwargs[p.name] = v
        result = fn(**kwargs)
        if callable(result):
            result = result(S)
        out = np.asarray(result)
        if out.ndim == 0 or (out.shape[0] != n and LN.suffix(ret) == out.shape):
            return LN.const(ret, out)
        return out.astype(LN.dtype(ret))

    call.__name__ = f"native_{overload.name}"
    return call
