"""The declarations of MDL's standard modules, as MDL text the front end reads.

``::math``, ``::state``, ``::tex``, ``::debug``, ``::limits``, ``::anno`` and
``::scene`` (MDL 1.7), and the built-in material structs.  Functions are prototypes
(no body): a back end implements them (``::math`` is :mod:`mdl.mathlib`; the rest are
the renderer's).  ``::df`` and ``::base`` depend on the renderer's distribution
functions and library, so the renderer provides them (as a provider of
:class:`mdl.loader.Loader`).

Overload families are written once with placeholders and expanded: ``F`` float and
double scalars and vectors, ``I`` int scalars and vectors, ``V``/``S`` a vector and
its scalar.

Examples
--------
>>> "export float3 cross(float3 a, float3 b);" in source("math")
True
>>> sorted(STANDARD_MODULES)[:3]
['anno', 'builtins', 'debug']
"""

from __future__ import annotations

from functools import cache

__all__ = ["source", "STANDARD_MODULES"]

_F = ["float", "float2", "float3", "float4", "double", "double2", "double3", "double4"]
_I = ["int", "int2", "int3", "int4"]
_B = ["bool", "bool2", "bool3", "bool4"]
_VS = [(f"{e}{n}", e) for e in ("float", "double") for n in (2, 3, 4)]
_IVS = [(f"int{n}", "int") for n in (2, 3, 4)]


def _scalar_of(t: str) -> str:
    return t.rstrip("234") if t[-1] in "234" and not t.startswith("bool") else t.rstrip("234")


def _math() -> str:
    out = ["mdl 1.7;", "",
           "export const float PI = 3.14159265358979323846;",
           "export const float TWO_PI = 6.28318530717958647692;",
           "export const float HALF_PI = 1.57079632679489661923;", ""]

    def emit(line: str) -> None:
        out.append("export " + line + ";")

    unary_f = ["acos", "asin", "atan", "cos", "sin", "tan", "ceil", "floor", "frac", "round",
               "degrees", "radians", "normalize", "cosh", "sinh", "tanh"]
    unary_fc = ["exp", "exp2", "log", "log2", "log10", "sqrt", "rsqrt", "saturate"]
    for t in _F:
        s = _scalar_of(t)
        for f in unary_f:
            emit(f"{t} {f}({t} a)")
        for f in unary_fc:
            emit(f"{t} {f}({t} a)")
        emit(f"{t} abs({t} a)")
        emit(f"{t} sign({t} a)")
        emit(f"{t} atan2({t} y, {t} x)")
        emit(f"{s} average({t} a)")
        emit(f"{t} clamp({t} a, {t} min, {t} max)")
        emit(f"{s} distance({t} a, {t} b)")
        emit(f"{s} dot({t} a, {t} b)")
        emit(f"{t} fmod({t} a, {t} b)")
        b = "bool" + t[-1] if t[-1] in "234" else "bool"
        emit(f"{b} isnan({t} a)")
        emit(f"{b} isfinite({t} a)")
        emit(f"{s} length({t} a)")
        emit(f"{t} lerp({t} a, {t} b, {t} l)")
        emit(f"{t} max({t} a, {t} b)")
        emit(f"{t} min({t} a, {t} b)")
        emit(f"{s} max_value({t} a)")
        emit(f"{s} min_value({t} a)")
        emit(f"{t}[2] modf({t} a)")
        emit(f"{t} pow({t} a, {t} b)")
        emit(f"{t}[2] sincos({t} a)")
        emit(f"{t} smoothstep({t} a, {t} b, {t} l)")
        emit(f"{t} step({t} a, {t} b)")
        if s == "float":
            emit(f"{t} DX({t} a)")
            emit(f"{t} DY({t} a)")
        else:
            emit(f"{t} DX({t} a)")
            emit(f"{t} DY({t} a)")
    for v, s in _VS:
        emit(f"{v} clamp({v} a, {v} min, {s} max)")
        emit(f"{v} clamp({v} a, {s} min, {v} max)")
        emit(f"{v} clamp({v} a, {s} min, {s} max)")
        emit(f"{v} fmod({v} a, {s} b)")
        emit(f"{v} lerp({v} a, {v} b, {s} l)")
        emit(f"{v} max({v} a, {s} b)")
        emit(f"{v} max({s} a, {v} b)")
        emit(f"{v} min({v} a, {s} b)")
        emit(f"{v} min({s} a, {v} b)")
        emit(f"{v} pow({v} a, {s} b)")
        emit(f"{v} smoothstep({v} a, {v} b, {s} l)")
    for t in _I:
        emit(f"{t} abs({t} a)")
        emit(f"{t} clamp({t} a, {t} min, {t} max)")
        emit(f"{t} max({t} a, {t} b)")
        emit(f"{t} min({t} a, {t} b)")
        emit(f"{t} pow({t} a, {t} b)")
        emit(f"{t} sign({t} a)")
    for v, s in _IVS:
        emit(f"{v} clamp({v} a, {v} min, {s} max)")
        emit(f"{v} clamp({v} a, {s} min, {v} max)")
        emit(f"{v} clamp({v} a, {s} min, {s} max)")
        emit(f"{v} max({v} a, {s} b)")
        emit(f"{v} max({s} a, {v} b)")
        emit(f"{v} min({v} a, {s} b)")
        emit(f"{v} min({s} a, {v} b)")
        emit(f"{v} pow({v} a, {s} b)")
    for t in _B:
        emit(f"bool all({t} a)")
        emit(f"bool any({t} a)")
    for f in ("abs", "exp", "exp2", "log", "log2", "log10", "sqrt", "rsqrt", "saturate"):
        emit(f"color {f}(color a)")
    emit("float average(color a)")
    emit("color clamp(color a, color min, color max)")
    emit("color clamp(color a, color min, float max)")
    emit("color clamp(color a, float min, color max)")
    emit("color clamp(color a, float min, float max)")
    emit("color lerp(color a, color b, color l)")
    emit("color lerp(color a, color b, float l)")
    emit("float luminance(float3 a)")
    emit("float luminance(color a)")
    for f in ("max", "min"):
        emit(f"color {f}(color a, color b)")
        emit(f"color {f}(float a, color b)")
        emit(f"color {f}(color a, float b)")
    emit("float max_value(color a)")
    emit("float min_value(color a)")
    emit("float max_value_wavelength(color a)")
    emit("float min_value_wavelength(color a)")
    emit("color pow(color a, color b)")
    emit("color pow(color a, float b)")
    emit("float3 cross(float3 a, float3 b)")
    emit("double3 cross(double3 a, double3 b)")
    emit("float eval_at_wavelength(color a, float wavelength)")
    for e in ("float", "double"):
        for c in (2, 3, 4):
            for r in (2, 3, 4):
                emit(f"{e}{r}x{c} transpose({e}{c}x{r} a)")
    emit("color blackbody(float temperature)")
    emit("color emission_color(float[<N>] wavelengths, float[N] amplitudes) uniform")
    emit("color emission_color(color value) uniform")
    emit("int float_bits_to_int(float a)")
    emit("float int_bits_to_float(int a)")
    return "\n".join(out) + "\n"


_STATE = """\
mdl 1.7;

export enum coordinate_space {
    coordinate_internal,
    coordinate_object,
    coordinate_world
};

export float3 position() varying;
export float3 normal() varying;
export float3 geometry_normal() varying;
export float3 motion() varying;
export int texture_space_max() varying;
export float3 texture_coordinate(int index) varying;
export float3 texture_tangent_u(int index) varying;
export float3 texture_tangent_v(int index) varying;
export float3x3 tangent_space(int index) varying;
export float3 geometry_tangent_u(int index) varying;
export float3 geometry_tangent_v(int index) varying;
export float3 direction() varying;
export float animation_time() varying;
export float[3] wavelength_base() uniform;
export float4x4 transform(coordinate_space from, coordinate_space to) uniform;
export float3 transform_point(coordinate_space from, coordinate_space to, float3 point) uniform;
export float3 transform_vector(coordinate_space from, coordinate_space to, float3 vector) uniform;
export float3 transform_normal(coordinate_space from, coordinate_space to, float3 normal) uniform;
export float transform_scale(coordinate_space from, coordinate_space to, float scale) uniform;
export float3 rounded_corner_normal(uniform float radius = 0.0,
    uniform bool across_materials = false, uniform float roundness = 1.0) varying;
export float meters_per_scene_unit() uniform;
export float scene_units_per_meter() uniform;
export int object_id() uniform;
export float wavelength_min() uniform;
export float wavelength_max() uniform;
"""


def _tex() -> str:
    out = ["mdl 1.7;", "",
           "export enum gamma_mode { gamma_default, gamma_linear, gamma_srgb };",
           "export enum wrap_mode { wrap_clamp, wrap_repeat, wrap_mirrored_repeat, wrap_clip };",
           ""]
    for f in ("width", "height"):
        out.append(f"export int {f}(uniform texture_2d tex, int2 uv_tile = int2(0), "
                   "float frame = 0.0) uniform;")
        out.append(f"export int {f}(uniform texture_3d tex, float frame = 0.0) uniform;")
        out.append(f"export int {f}(uniform texture_cube tex) uniform;")
    out.append("export int depth(uniform texture_3d tex, float frame = 0.0) uniform;")
    for ret, suffix in (("float", "float"), ("float2", "float2"), ("float3", "float3"),
                        ("float4", "float4"), ("color", "color")):
        out.append(
            f"export {ret} lookup_{suffix}(uniform texture_2d tex, float2 coord, "
            "uniform wrap_mode wrap_u = wrap_repeat, uniform wrap_mode wrap_v = wrap_repeat, "
            "uniform float2 crop_u = float2(0.0, 1.0), uniform float2 crop_v = "
            "float2(0.0, 1.0), float frame = 0.0) uniform;")
        out.append(
            f"export {ret} lookup_{suffix}(uniform texture_3d tex, float3 coord, "
            "uniform wrap_mode wrap_u = wrap_repeat, uniform wrap_mode wrap_v = wrap_repeat, "
            "uniform wrap_mode wrap_w = wrap_repeat, uniform float2 crop_u = float2(0.0, 1.0), "
            "uniform float2 crop_v = float2(0.0, 1.0), uniform float2 crop_w = "
            "float2(0.0, 1.0), float frame = 0.0) uniform;")
        out.append(f"export {ret} lookup_{suffix}(uniform texture_cube tex, float3 coord) "
                   "uniform;")
        out.append(f"export {ret} lookup_{suffix}(uniform texture_ptex tex, int channel = 0) "
                   "varying;")
        out.append(f"export {ret} texel_{suffix}(uniform texture_2d tex, int2 coord, "
                   "int2 uv_tile = int2(0), float frame = 0.0) uniform;")
        out.append(f"export {ret} texel_{suffix}(uniform texture_3d tex, int3 coord, "
                   "float frame = 0.0) uniform;")
    for r in ("texture_2d", "texture_3d", "texture_cube", "texture_ptex", "light_profile",
              "bsdf_measurement"):
        out.append(f"export bool texture_isvalid(uniform {r} tex) uniform;")
    return "\n".join(out) + "\n"


def _debug() -> str:
    out = ["mdl 1.7;", "",
           "export bool assert(bool condition, string reason, string funcname = \"\", "
           "string filename = \"\", int line = 0);",
           "export bool breakpoint();"]
    for t in ["bool", "int", "float", "double", "string", "color"] + _B[1:] + _I[1:] + [
            "float2", "float3", "float4", "double2", "double3", "double4"]:
        out.append(f"export bool print({t} v);")
    return "\n".join(out) + "\n"


_LIMITS = """\
mdl 1.7;

export const int INT_MIN = -2147483648;
export const int INT_MAX = 2147483647;
export const float FLOAT_MIN = 1.17549435e-38;
export const float FLOAT_MAX = 3.40282347e+38;
export const double DOUBLE_MIN = 2.2250738585072014e-308d;
export const double DOUBLE_MAX = 1.7976931348623157e+308d;
"""


def _anno() -> str:
    out = ["mdl 1.7;", ""]
    simple = {
        "intrinsic": "", "throws": "", "since": "int major, int minor",
        "removed": "int major, int minor", "const_expr": "", "derivable": "",
        "native": "", "noinline": "", "experimental": "",
        "soft_range": None, "hard_range": None, "hidden": "", "unused": "",
        "deprecated": "", "display_name": "string name", "in_group": None,
        "description": "string description", "author": "string name",
        "contributor": "string name", "copyright_notice": "string copyright",
        "created": "int year, int month, int day, string notes",
        "modified": "int year, int month, int day, string notes",
        "version_number": "int major, int minor, int branch, int build",
        "version": "int major, int minor, int patch, string prerelease = \"\"",
        "key_words": "string[<N>] words", "ui_order": "int order", "usage": "string hint",
        "enable_if": "string condition", "thumbnail": "string name", "origin": "string name",
        "dependency": "string module_name, int major, int minor, int patch, "
                      "string prerelease = \"\"",
    }
    for name, params in simple.items():
        if name in ("soft_range", "hard_range"):
            for t in ["int", "float", "double"] + _I[1:] + _F[1:4] + _F[5:] + ["color"]:
                out.append(f"export annotation {name}({t} min, {t} max);")
        elif name == "in_group":
            out.append("export annotation in_group(string group, string subgroup = \"\", "
                       "string subsubgroup = \"\", bool collapsed = false);")
        elif name == "deprecated":
            out.append("export annotation deprecated();")
            out.append("export annotation deprecated(string description);")
        elif name == "unused":
            out.append("export annotation unused();")
            out.append("export annotation unused(string description);")
        else:
            out.append(f"export annotation {name}({params});")
    return "\n".join(out) + "\n"


def _scene() -> str:
    out = ["mdl 1.7;", "", "export bool data_isvalid(string name) varying;"]
    for t in ["int", "int2", "int3", "int4", "float", "float2", "float3", "float4", "color"]:
        for prefix in ("", "uniform_"):
            q = "varying" if not prefix else "uniform"
            out.append(f"export {t} data_lookup_{prefix}{t}(string name, {t} default_value = "
                       f"{t}()) {q};")
    return "\n".join(out) + "\n"


_BUILTINS = """\
mdl 1.7;

import ::state::*;

export enum intensity_mode {
    intensity_radiant_exitance,
    intensity_power
};

export struct material_emission {
    edf emission = edf();
    color intensity = color(0.0);
    uniform intensity_mode mode = intensity_radiant_exitance;
};

export struct material_surface {
    bsdf scattering = bsdf();
    material_emission emission = material_emission();
};

export struct material_volume {
    vdf scattering = vdf();
    color absorption_coefficient = color(0.0);
    color scattering_coefficient = color(0.0);
    color emission_intensity = color(0.0);
};

export struct material_geometry {
    float3 displacement = float3(0.0);
    float cutout_opacity = 1.0;
    float3 normal = state::normal();
};

export struct material {
    uniform bool thin_walled = false;
    material_surface surface = material_surface();
    material_surface backface = material_surface();
    uniform color ior = color(1.0);
    material_volume volume = material_volume();
    material_geometry geometry = material_geometry();
    hair_bsdf hair = hair_bsdf();
};
"""

_SOURCES = {
    "math": _math, "state": lambda: _STATE, "tex": _tex, "debug": _debug,
    "limits": lambda: _LIMITS, "anno": _anno, "scene": _scene, "builtins": lambda: _BUILTINS,
}

#: the names of the standard modules this front end declares (``builtins`` is imported
#: implicitly by every module)
STANDARD_MODULES = frozenset(_SOURCES)


@cache
def source(name: str) -> str:
    """The MDL text declaring standard module ``name``."""
    return _SOURCES[name]()
