"""The creases of a displacement written in MDL, for the dicer.

The workbench's built-in pw-curve fields carry ``uv_knots``
(:class:`displacement.fields.Field`): the texture coordinates of their profile's
breakpoints, where the dicer puts grid lines and splits shading normals.  MDL has no
such notion, so for a displacement written in MDL they are found in its code
(:func:`uv_knots`):

* **which profiles**: every ``pw_curve::pw_point[N]`` constant the displacement can
  reach -- passed to it as a material-level value, or named in the bodies of the
  functions it calls (transitively); their breakpoints ``t`` are the knots;
* **which direction**: the components of ``state::texture_coordinate(i)`` those bodies
  read -- only ``.x`` (or ``[0]``): knots in u; only ``.y`` (``[1]``): in v; anything
  else (a variable index, the whole vector): in both, which costs grid lines but never
  misses a crease.

A profile used through a repetition (``point_along_pwc_repeat``) has creases at
``(t + k) / repeat``, which this does not know: such a displacement is diced without
knots at the copies' seams (finer adaptive dicing still follows them; docs/mdl.md).
"""

from __future__ import annotations

import numpy as np

from mdl import ast as A
from mdl import types as T
from mdl.entities import ConstEntity, Overload

__all__ = ["uv_knots", "is_profile_type", "merge_knots"]


def is_profile_type(t) -> bool:
    """Whether ``t`` is an array of ``pw_curve::pw_point``."""
    return isinstance(t, T.ArrayT) and isinstance(t.elem, T.StructType) and \
        t.elem.name.endswith("pw_point")


def merge_knots(*pairs):
    """The union of ``(knots_u, knots_v)`` pairs (None: no knots in a direction)."""
    out = []
    for k in range(2):
        parts = [np.asarray(p[k], dtype=np.float64) for p in pairs if p and p[k] is not None]
        out.append(np.unique(np.concatenate(parts)) if parts else None)
    return tuple(out)


def _curve_t(value) -> np.ndarray | None:
    from render.mdlc.natives import PROFILE_VALUES, curve_from_lanes

    curve = PROFILE_VALUES.curve(value)
    if curve is None:
        try:
            curve = curve_from_lanes(value)
        except (ValueError, TypeError, IndexError):
            return None
    t = np.asarray(curve.t, dtype=np.float64)
    return t[(t >= 0.0) & (t <= 1.0)]


class _Scan:
    def __init__(self):
        self.curves: list = []       # lane values of pw_point arrays
        self.components: set = set()  # 0, 1 or "any"
        self.seen: set = set()

    def function(self, o: Overload):
        if id(o) in self.seen or o.kind != "mdl" or o.decl is None:
            return
        self.seen.add(id(o))
        m = o.module
        for p in o.decl.params or ():
            if p.default is not None:
                self.node(m, p.default, None)
        if o.decl.body is not None:
            self.node(m, o.decl.body, None)

    def node(self, m, x, parent):
        info = m.info.get(id(x)) if hasattr(m, "info") else None
        if info is not None:
            if isinstance(x, A.Ref) and isinstance(info.target, ConstEntity) and \
                    is_profile_type(info.type) and info.target.value is not None:
                self.curves.append(info.target.value)
            call = info.call
            if isinstance(x, A.Call) and call is not None and call.kind == "overload":
                o = call.target
                if o.name == "texture_coordinate" and o.module.qname == "::state":
                    self.components.add(_component(m, parent))
                self.function(o)
                for p, a in zip(o.params, call.args, strict=False):
                    if a is None and p.default is not None:
                        self.node(o.module, p.default, None)
        for y in A.children(x) if isinstance(x, A.Node) else ():
            self.node(m, y, x)


def _component(m, parent):
    """0 (u), 1 (v) or "any": what is read of a texture_coordinate call under
    ``parent``."""
    if isinstance(parent, A.Member):
        comps = set(parent.name)
        if comps <= set("xr"):
            return 0
        if comps <= set("yg"):
            return 1
        return "any"
    if isinstance(parent, A.Index):
        info = m.info.get(id(parent.index))
        const = getattr(info, "const", None)
        if const is not None:
            k = int(np.asarray(const).reshape(-1)[0])
            return k if k in (0, 1) else "any"
    return "any"


def uv_knots(m, e, inputs) -> tuple:
    """``(knots_u, knots_v)`` of the data expression ``e`` of module ``m`` whose
    material-level inputs are ``inputs`` (``[(type, value)]``: lane values of the
    constants; the knots of varying ones are merged by the caller)."""
    scan = _Scan()
    for t, value in inputs:
        if is_profile_type(t) and value is not None:
            scan.curves.append(value)
    scan.node(m, e, None)
    knots = [k for k in (_curve_t(c) for c in scan.curves) if k is not None and len(k)]
    if not knots:
        return (None, None)
    ks = np.unique(np.concatenate(knots))
    comps = scan.components
    if not comps:
        return (None, None)  # the profile does not follow the texture coordinates
    along_u = 0 in comps or "any" in comps
    along_v = 1 in comps or "any" in comps
    return (ks if along_u else None, ks if along_v else None)
