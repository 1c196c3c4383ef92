"""Writers for a compiled curve: MDL module, ``pwc-json/1``, NPZ (spec/pwc-list.md §2).

All writers return ``bytes`` (or ``str`` for text) so the CLI decides where they go.
"""

from __future__ import annotations

import io
import json
import keyword
import re
from importlib import resources

import numpy as np

from pwc.curve import Curve, PwType

__all__ = [
    "JSON_FORMAT", "to_json", "from_json", "to_npz", "from_npz", "to_mdl", "runtime_mdl",
    "mdl_identifier", "mdl_float",
]

JSON_FORMAT = "pwc-json/1"
_FIELDS = ("t", "pt", "center", "radius", "start_angle", "end_angle")

# MDL reserved words (MDL 1.7 spec, keywords and reserved-for-future words)
_MDL_RESERVED = frozenset("""
annotation bool bool2 bool3 bool4 break bsdf bsdf_measurement case cast color const continue
default do double double2 double2x2 double2x3 double3 double3x2 double3x3 double3x4 double4
double4x3 double4x4 double4x2 double2x4 edf else enum export false float float2 float2x2
float2x3 float3 float3x2 float3x3 float3x4 float4 float4x3 float4x4 float4x2 float2x4 for hair_bsdf
if import in int int2 int3 int4 intensity_mode intensity_power intensity_radiant_exitance
let light_profile material material_emission material_geometry material_surface
material_volume mdl module package return string struct switch texture_2d texture_3d
texture_cube texture_ptex true typedef uniform using varying vdf while
auto catch char class const_cast delete dynamic_cast explicit extern external foreach friend
goto graph half half2 half2x2 half2x3 half3 half3x2 half3x3 half3x4 half4 half4x3 half4x4
half4x2 half2x4 inline inout lambda long mutable namespace native new operator out phenomenon
private protected public reinterpret_cast sampler shader short signed sizeof static
static_cast technique template this throw try typeid typename union unsigned virtual void
volatile wchar_t
""".split())


def mdl_identifier(stem: str) -> str:
    """The MDL identifier for a file stem, or ValueError saying how to rename the file.

    Examples
    --------
    >>> mdl_identifier("ornament-2")
    'ornament_2'
    >>> mdl_identifier("float")
    Traceback (most recent call last):
    ...
    ValueError: 'float' is a reserved word in MDL; rename the file (e.g. 'float_profile.pwc')
    """
    name = re.sub(r"[^A-Za-z0-9_]", "_", stem)
    if not name or not re.match(r"[A-Za-z]", name):
        raise ValueError(f"'{stem}' cannot become an MDL identifier (it must start with a "
                         f"letter); rename the file (e.g. 'profile_{name.strip('_')}.pwc')")
    if name in _MDL_RESERVED or keyword.iskeyword(name) and name in ("if", "for", "while"):
        raise ValueError(f"'{name}' is a reserved word in MDL; rename the file "
                         f"(e.g. '{name}_profile.pwc')")
    return name


def mdl_float(v: float) -> str:
    """An MDL float literal with 9 significant digits (always with a decimal point).

    Examples
    --------
    >>> [mdl_float(v) for v in (0.0, -0.0, 1.0, 0.123456789123, 2.5e-12, 3e20)]
    ['0.0', '0.0', '1.0', '0.123456789', '2.5e-12', '3.0e+20']
    """
    s = f"{float(v) + 0.0:.9g}"  # + 0.0 turns -0.0 into 0.0
    if "e" in s:
        mant, exp = s.split("e")
        return (mant if "." in mant else mant + ".0") + "e" + exp
    return s if "." in s else s + ".0"


def to_json(curve: Curve) -> str:
    """The ``pwc-json/1`` document of a curve."""
    doc = {
        "format": JSON_FORMAT, "name": curve.name, "source": curve.source,
        "relative": curve.relative, "scale": curve.scale, "length": curve.length,
        "points": [
            {"type": PwType(int(curve.type[i])).mdl_name, "t": float(curve.t[i]),
             "pt": curve.pt[i].tolist(), "center": curve.center[i].tolist(),
             "radius": float(curve.radius[i]), "start_angle": float(curve.start_angle[i]),
             "end_angle": float(curve.end_angle[i]), "line": int(curve.line[i]),
             "text": curve.text[i] if curve.text else ""}
            for i in range(curve.n)
        ],
    }
    return json.dumps(doc, indent=1) + "\n"


def from_json(text: str) -> Curve:
    """Read a ``pwc-json/1`` document back into a :class:`Curve`."""
    doc = json.loads(text)
    if doc.get("format") != JSON_FORMAT:
        raise ValueError(f"not a {JSON_FORMAT} document (format: {doc.get('format')!r})")
    pts = doc["points"]
    names = [t.mdl_name for t in PwType]
    col = lambda k: np.array([p[k] for p in pts], dtype=np.float64)  # noqa: E731
    return Curve(
        name=doc["name"], type=np.array([names.index(p["type"]) for p in pts], dtype=np.int8),
        **{k: col(k) for k in _FIELDS}, length=doc["length"], scale=doc["scale"],
        relative=doc["relative"], source=doc["source"],
        line=np.array([p["line"] for p in pts], dtype=np.int64),
        text=tuple(p["text"] for p in pts))


def to_npz(curve: Curve) -> bytes:
    """The curve as an ``.npz`` archive: the JSON fields as arrays (``type`` as ints in
    :class:`PwType` order)."""
    buf = io.BytesIO()
    np.savez(buf, format=JSON_FORMAT, name=curve.name, source=curve.source,
             relative=curve.relative, scale=curve.scale, length=curve.length,
             type=curve.type, line=curve.line, text=np.array(curve.text, dtype=str),
             **{k: getattr(curve, k) for k in _FIELDS})
    return buf.getvalue()


def from_npz(data: bytes) -> Curve:
    """Read :func:`to_npz` output back into a :class:`Curve`."""
    z = np.load(io.BytesIO(data), allow_pickle=False)
    return Curve(name=str(z["name"]), type=z["type"], **{k: z[k] for k in _FIELDS},
                 length=float(z["length"]), scale=float(z["scale"]),
                 relative=bool(z["relative"]), source=str(z["source"]), line=z["line"],
                 text=tuple(str(s) for s in z["text"]))


def _mdl_point(curve: Curve, i: int, comment: str) -> str:
    kind = PwType(int(curve.type[i]))
    args = [f"pw_curve::{kind.mdl_name}", mdl_float(curve.t[i]),
            f"float2({mdl_float(curve.pt[i, 0])}, {mdl_float(curve.pt[i, 1])})"]
    if kind != PwType.SEGMENT:
        args += [f"float2({mdl_float(curve.center[i, 0])}, {mdl_float(curve.center[i, 1])})",
                 mdl_float(curve.radius[i]), mdl_float(curve.start_angle[i]),
                 mdl_float(curve.end_angle[i])]
    return f"    pw_curve::pw_point( // {comment}\n        " + ", ".join(args) + ")"


def to_mdl(curve: Curve, name: str | None = None) -> str:
    """An MDL module holding ``NAME_length`` and the ``pw_point`` array (Listings 15.3-15.4).

    Each element carries its source line as a comment; list properties are a comment on
    the array.  Import it together with :func:`runtime_mdl`'s ``pw_curve.mdl``.
    """
    name = mdl_identifier(name or curve.name)
    cyma = np.isin(curve.type, (PwType.CYMA_RECTA, PwType.CYMA_REVERSA))
    comments = []
    for i in range(curve.n):
        text = curve.text[i] if curve.text else ""
        if cyma[i]:  # a cyma's two arcs come from one source line
            second = i > 0 and cyma[i - 1] and curve.line[i - 1] == curve.line[i]
            text += f"  (arc {2 if second else 1} of 2)"
        comments.append(f"line {curve.line[i]}: {text}" if curve.line[i] else text)
    props = " // :relative" if curve.relative else ""
    body = ",\n".join(_mdl_point(curve, i, comments[i]) for i in range(curve.n))
    return (
        f"// {name}: pw-curve compiled by `pwc compile` from {curve.source}\n"
        f"// normalized by scale {mdl_float(curve.scale)}; do not edit, edit the .pwc file.\n\n"
        "mdl 1.6;\n\nimport ::pw_curve::*;\n\n"
        "// Length of the pw-curve, for texture scaling\n"
        f"export const float {name}_length = {mdl_float(curve.length)};\n\n"
        f"export const pw_curve::pw_point[{curve.n}] {name}({props}\n{body});\n"
    )


def runtime_mdl() -> str:
    """The text of the ``pw_curve.mdl`` runtime module."""
    return resources.files("pwc").joinpath("mdl/pw_curve.mdl").read_text(encoding="utf-8")
