"""The mixing framework shared by the normalized, clamped and unbounded mixes, and the
component structs.

``reference/mdl-distribution-functions.md`` §3.3.  A mix holds components with
effective weights ``w_i`` (colours, per lane), computed by each mix's ``mix_weights``
kernel from the MDL weights (normalised, clamped or unbounded)::

    eval = sum_i w_i eval_i(wo, wi),      pdf = sum_i p_i pdf_i(wo, wi) [w_i eval_i > 0]

Sampling picks component ``i`` with probability ``p_i`` (a defensive mixture of the
expected contributions ``w_i albedo_i``, :func:`render.df._workspace.selection`; libbsdf
uses ``w_i / sum(w)``), reuses ``u1`` rescaled, and returns ``weight = eval / pdf``
(delta events: ``w_i weight_i / p_i``); nested combiners sample in one descent and one
evaluation of the whole tree (:func:`render.interpreter.sample`).
``albedo = sum_i w_i albedo_i`` exactly.

EDF mixes (``normalized_mix`` over ``edf_component``) weight the emission the same way;
the component is picked with probability proportional to ``luminance(w_i)`` (every
EDF is normalised to unit exitance).
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np

from render._typing import ArrayLike
from render.bsdf import (
    Bsdf,
    Edf,
    lane_color,
    lane_float,
)
from render.df._combine import (
    check_child,
)
from render.df._registry import Df
from render.df._signature import REQUIRED, Param, Signature
from render.df._workspace import (
    AL,
    CH,
    KON,
    KR,
    KSEL,
    KW,
    NO_KID,
    PDF,
    R,
    any_pos,
    clamp_u,
    lum,
    selection,
)
from render.program import BASE, FLAGS, KID0, NKIDS, OP, TABLE

__all__ = [
    "BSDF_COMPONENT_SIGNATURE",
    "COLOR_BSDF_COMPONENT_SIGNATURE",
    "EDF_COMPONENT_SIGNATURE",
    "COLOR_EDF_COMPONENT_SIGNATURE",
    "VDF_COMPONENT_SIGNATURE",
    "COLOR_VDF_COMPONENT_SIGNATURE",
    "VdfComponent",
    "vdf_component",
    "ColorVdfComponent",
    "color_vdf_component",
    "component_signature",
    "mix_signatures",
    "COMPONENT_WIDTH",
    "BsdfComponent",
    "bsdf_component",
    "ColorBsdfComponent",
    "color_bsdf_component",
    "EdfComponent",
    "edf_component",
    "ColorEdfComponent",
    "color_edf_component",
    "as_components",
]


# --- signatures of the component structs (the compiled render core) -------------------
# A mix node's slots are its k components' weights, each packed as a colour (a float
# weight broadcast to 3 slots), in component order: component i's weight at
# ``b + 3 i`` (3 k slots; the mix's own signature packs nothing).  The mixes' kernels
# (``mix_weights`` in normalized_mix.py and clamped_mix.py) clamp or normalise them, so
# the packer writes the weights as given (no clamp).

#: MDL's ``struct bsdf_component { float weight = 0.0; bsdf component = bsdf(); }``
BSDF_COMPONENT_SIGNATURE = Signature("bsdf_component", (
    Param("weight", "float", 0.0, packed="color"), Param("component", "bsdf", None)))
#: MDL's ``struct color_bsdf_component { color weight = color(0.0); bsdf component; }``
COLOR_BSDF_COMPONENT_SIGNATURE = Signature("color_bsdf_component", (
    Param("weight", "color", (0.0, 0.0, 0.0)), Param("component", "bsdf", None)))
#: MDL's ``struct edf_component { float weight = 0.0; edf component = edf(); }``
EDF_COMPONENT_SIGNATURE = Signature("edf_component", (
    Param("weight", "float", 0.0, packed="color"), Param("component", "edf", None)))
#: MDL's ``struct color_edf_component { color weight = color(0.0); edf component; }``
COLOR_EDF_COMPONENT_SIGNATURE = Signature("color_edf_component", (
    Param("weight", "color", (0.0, 0.0, 0.0)), Param("component", "edf", None)))
#: MDL's ``struct vdf_component { float weight = 0.0; vdf component = vdf(); }``
VDF_COMPONENT_SIGNATURE = Signature("vdf_component", (
    Param("weight", "float", 0.0, packed="color"), Param("component", "vdf", None)))
#: MDL's ``struct color_vdf_component { color weight = color(0.0); vdf component; }`` (1.7)
COLOR_VDF_COMPONENT_SIGNATURE = Signature("color_vdf_component", (
    Param("weight", "color", (0.0, 0.0, 0.0)), Param("component", "vdf", None)))
#: slots of one packed component (its weight as a colour)
COMPONENT_WIDTH = 3
#: the component structs, as the material layer knows them (render.df._registry)
STRUCTS = tuple(Df(sig.kind, sig, struct=True) for sig in (
    BSDF_COMPONENT_SIGNATURE, COLOR_BSDF_COMPONENT_SIGNATURE, EDF_COMPONENT_SIGNATURE,
    COLOR_EDF_COMPONENT_SIGNATURE, VDF_COMPONENT_SIGNATURE, COLOR_VDF_COMPONENT_SIGNATURE))


def component_signature(color: bool, edf: bool) -> Signature:
    """The signature of a mix's component struct (``color_``, ``edf_`` variants)."""
    return ((COLOR_EDF_COMPONENT_SIGNATURE if edf else COLOR_BSDF_COMPONENT_SIGNATURE)
            if color else (EDF_COMPONENT_SIGNATURE if edf else BSDF_COMPONENT_SIGNATURE))


def mix_signatures() -> tuple[Signature, Signature, Signature, Signature]:
    """A mix's overloads ``(bsdf, color bsdf, edf, color edf)``: one parameter, the
    component array (``bsdf_component[<N>]`` ...), no slots of its own."""
    return tuple(
        Signature(kind, (Param("components", f"{c}{kind}_component[]", REQUIRED),))
        for kind, c in (("bsdf", ""), ("bsdf", "color_"), ("edf", ""), ("edf", "color_")))


class BsdfComponent:
    """MDL's ``struct bsdf_component { float weight = 0.0; bsdf component = bsdf(); }``.

    Parameters
    ----------
    weight : float or (n,)
        The mixing weight (the mix clamps or normalises it).
    component : Bsdf or None
        None is MDL's black ``bsdf()``.

    Examples
    --------
    >>> from render.df import diffuse_reflection_bsdf
    >>> bsdf_component(0.5, diffuse_reflection_bsdf()).weight.tolist()
    [[0.5, 0.5, 0.5]]
    """

    _kind: type = Bsdf
    _color = False
    _vdf = False

    def __init__(self, weight: ArrayLike = 0.0, component=None):
        name = type(self).__name__
        if self._color:
            self.weight = lane_color(weight, f"{name}.weight")
        else:
            w = lane_float(weight, f"{name}.weight")
            self.weight = w[:, None] * np.ones(3) if w.ndim else np.full((1, 3), float(w))
        self.component = check_child(component, f"{name}.component", self._kind)
        if self._vdf and self.component is not None and getattr(
                getattr(self.component, "program", None), "kind", "vdf") != "vdf":
            raise ValueError(f"{name}.component must be a vdf (e.g. df.anisotropic_vdf), got "
                             f"{type(self.component).__name__}")

    def __repr__(self) -> str:
        return f"{type(self).__name__}(weight={self.weight.tolist()}, component={self.component!r})"


class ColorBsdfComponent(BsdfComponent):
    """MDL's ``color_bsdf_component { color weight = color(0.0); bsdf component; }`` (1.4)."""

    _color = True


class EdfComponent(BsdfComponent):
    """MDL's ``edf_component { float weight = 0.0; edf component = edf(); }``."""

    _kind = Edf


class ColorEdfComponent(BsdfComponent):
    """MDL's ``color_edf_component { color weight = color(0.0); edf component; }`` (1.4)."""

    _kind = Edf
    _color = True


class VdfComponent(BsdfComponent):
    """MDL's ``vdf_component { float weight = 0.0; vdf component = vdf(); }`` (a vdf is a
    :class:`~render.program.ProgramBsdf` whose program's kind is ``"vdf"``)."""

    _vdf = True


class ColorVdfComponent(BsdfComponent):
    """MDL's ``color_vdf_component { color weight = color(0.0); vdf component; }`` (1.7)."""

    _vdf = True
    _color = True


bsdf_component = BsdfComponent
color_bsdf_component = ColorBsdfComponent
vdf_component = VdfComponent
color_vdf_component = ColorVdfComponent
edf_component = EdfComponent
color_edf_component = ColorEdfComponent


def as_components(components, color: bool, mix: str) -> list[BsdfComponent]:
    """Validate a mix's ``components``: component structs or ``(weight, df)`` pairs.

    Returns
    -------
    list of BsdfComponent
        All Bsdf components or all Edf components.

    Raises
    ------
    ValueError
        Not a sequence, an element of the wrong kind, or Bsdf and Edf components mixed.
    """
    if isinstance(components, BsdfComponent) or not isinstance(components, Sequence):
        raise ValueError(
            f"{mix}: components must be a list of {'color_' if color else ''}bsdf_component "
            f"(or edf_component) values, got {type(components).__name__}"
        )
    out = []
    for i, c in enumerate(components):
        if isinstance(c, BsdfComponent):
            if c._color != color:
                want = "color_" if color else ""
                raise ValueError(
                    f"{mix}: components[{i}] is a {type(c).__name__}; this mix takes "
                    f"{want}bsdf_component / {want}edf_component values"
                )
            out.append(c)
        elif isinstance(c, tuple) and len(c) == 2:
            vdf = getattr(getattr(c[1], "program", None), "kind", None) == "vdf"
            kind = EdfComponent if isinstance(c[1], Edf) else (VdfComponent if vdf
                                                                else BsdfComponent)
            if color:
                kind = {EdfComponent: ColorEdfComponent, VdfComponent: ColorVdfComponent,
                        BsdfComponent: ColorBsdfComponent}[kind]
            out.append(kind(*c))
        else:
            raise ValueError(
                f"{mix}: components[{i}] must be a component struct or a (weight, df) pair, "
                f"got {type(c).__name__}"
            )
    edf = [c._kind is Edf for c in out]
    if any(edf) and not all(edf):
        raise ValueError(f"{mix}: components mix bsdf and edf components; use one kind")
    vdf = [c._vdf or getattr(getattr(c.component, "program", None), "kind", None) == "vdf"
           for c in out]
    if any(vdf) and not all(vdf):
        raise ValueError(f"{mix}: components mix vdf and bsdf components; use one kind")
    return out


# --- what a mix node does in each phase of the interpreter ---------------------------
# Templates that render.interpreter compiles with ``dispatch`` bound (render.jit.
# instantiate).  A mix's components are kid slots ``k0 .. k0 + nk - 1``; registers:
# render.df._workspace.

#: bound by render.interpreter: the generated dispatch (render.df._registry)
dispatch = None


def prepare(code, kids, P, tables, row, ws, k, ko):
    """Mix ``k`` at ``wo``: each component's effective weight (the mix's
    ``mix_weights`` kernel), the choice among them (a defensive mixture of ``w_i
    albedo_i``; for edf mixes of the weights' luminance, every edf having unit
    exitance) and the mix's cheap albedo ``sum w_i albedo_i``."""
    op, b, fl = code[k, OP], code[k, BASE], code[k, FLAGS]
    k0, nk = code[k, KID0], code[k, NKIDS]
    edf = dispatch.EDF[op]
    s0 = s1 = s2 = 0.0
    for j in range(nk):
        o = ko + (k0 + j) * KR
        w0, w1, w2 = dispatch.mix_weights(op, P, row, b, fl, nk, j, tables, code[k, TABLE])
        ws[o + KW], ws[o + KW + 1], ws[o + KW + 2] = w0, w1, w2
        c = kids[k0 + j]
        a0 = a1 = a2 = 0.0
        if c != NO_KID:
            q = c * R + CH
            a0, a1, a2 = ws[q], ws[q + 1], ws[q + 2]
        ws[o + KSEL] = lum(w0, w1, w2) if edf else lum(w0 * a0, w1 * a1, w2 * a2)
        ws[o + KON] = 1.0 if (c != NO_KID and any_pos(w0, w1, w2)) else 0.0
        s0 += w0 * a0
        s1 += w1 * a1
        s2 += w2 * a2
    selection(ws, ko, k0, nk)
    r = k * R + CH
    ws[r], ws[r + 1], ws[r + 2] = s0, s1, s2


def evaluate(code, kids, ws, k, ko):
    """Mix ``k`` after its components: ``sum w_i value_i`` and ``sum p_i pdf_i`` over
    the components that contribute -> ``(v0, v1, v2, pdf)``."""
    k0 = code[k, KID0]
    v0 = v1 = v2 = pdf = 0.0
    for j in range(code[k, NKIDS]):
        o = ko + (k0 + j) * KR
        c = kids[k0 + j]
        if c == NO_KID:
            ws[o + KON] = 0.0
            continue
        q = c * R
        c0 = ws[o + KW] * ws[q]
        c1 = ws[o + KW + 1] * ws[q + 1]
        c2 = ws[o + KW + 2] * ws[q + 2]
        on = any_pos(c0, c1, c2)
        ws[o + KON] = 1.0 if on else 0.0
        v0 += c0
        v1 += c1
        v2 += c2
        if on:
            pdf += ws[o + KSEL] * ws[q + PDF]
    return v0, v1, v2, pdf


def choose(code, ws, k, ko, u1):
    """The component a sample descends to -> ``(kid slot, u1 rescaled)``, by the
    selection probabilities (kid slot -1: none can be chosen)."""
    k0, nk = code[k, KID0], code[k, NKIDS]
    last = -1
    for jj in range(k0, k0 + nk):
        if ws[ko + jj * KR + KSEL] > 0.0:
            last = jj
    if last < 0:
        return -1, u1
    j = last
    cdf = 0.0
    for jj in range(k0, last + 1):
        p = ws[ko + jj * KR + KSEL]
        if u1 < cdf + p and p > 0.0:
            j = jj
            break
        cdf += p
    p = ws[ko + j * KR + KSEL]
    before = 0.0
    for jj in range(k0, j):
        before += ws[ko + jj * KR + KSEL]
    return j, clamp_u((u1 - before) / p)


def settle(code, ws, k, ko, j):
    """A delta sample through kid slot ``j``: ``(probability of the choice, weight)``."""
    o = ko + j * KR
    return ws[o + KSEL], ws[o + KW], ws[o + KW + 1], ws[o + KW + 2]


def albedo(code, kids, ws, k, ko):
    """Mix ``k``'s directional albedo from its components' (``AL``): ``sum w_i albedo_i``,
    exact."""
    k0 = code[k, KID0]
    a0 = a1 = a2 = 0.0
    for j in range(code[k, NKIDS]):
        c = kids[k0 + j]
        if c != NO_KID:
            o = ko + (k0 + j) * KR
            a0 += ws[o + KW] * ws[c * R + AL]
            a1 += ws[o + KW + 1] * ws[c * R + AL + 1]
            a2 += ws[o + KW + 2] * ws[c * R + AL + 2]
    return a0, a1, a2
