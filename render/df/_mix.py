"""The mixing framework shared by the normalized and clamped mixes, and the component structs.

``reference/mdl-distribution-functions.md`` §3.3.  A mix holds components with
effective weights ``w_i`` (colours, per lane), computed by the subclass from the MDL
weights (normalised or clamped)::

    eval = sum_i w_i eval_i(wo, wi),      pdf = sum_i p_i pdf_i(wo, wi) [w_i eval_i > 0]

Sampling picks component ``i`` with probability ``p_i`` (a defensive mixture of the
expected contributions ``w_i albedo_i``, :func:`render.df._combine.selection`; libbsdf
uses ``w_i / sum(w)``), reuses ``u1`` rescaled, and returns ``weight = eval / pdf``
(delta events: ``w_i weight_i / p_i``); nested combiners sample in one descent and one
evaluation of the whole tree (``_draw`` and ``_settle``, :mod:`render.df._combine`).
``albedo = sum_i w_i albedo_i`` exactly.

EDF mixes (``normalized_mix`` over ``edf_component``) weight the emission the same way;
the component is picked with probability proportional to ``luminance(w_i)`` (every
EDF is normalised to unit exitance).
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np

from render._typing import Arr, Arr2, ArrayLike, Rgb, Vec3
from render.bsdf import (
    Bsdf,
    BsdfSample,
    Edf,
    EdfSample,
    check_dirs,
    check_samples,
    lane_color,
    lane_float,
    lanes,
)
from render.df._combine import (
    Draw,
    Memo,
    any_positive,
    cheap_albedo,
    check_child,
    child_draw,
    child_settle,
    drawn,
    lum,
    pick,
    sample_by_draw,
    selection,
    union_lobes,
)
from render.df._signature import REQUIRED, Param, Signature
from render.numerics import check_finite

__all__ = [
    "BSDF_COMPONENT_SIGNATURE",
    "COLOR_BSDF_COMPONENT_SIGNATURE",
    "EDF_COMPONENT_SIGNATURE",
    "COLOR_EDF_COMPONENT_SIGNATURE",
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
    "MixBsdf",
    "MixEdf",
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
#: slots of one packed component (its weight as a colour)
COMPONENT_WIDTH = 3


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

    def __init__(self, weight: ArrayLike = 0.0, component=None):
        name = type(self).__name__
        if self._color:
            self.weight = lane_color(weight, f"{name}.weight")
        else:
            w = lane_float(weight, f"{name}.weight")
            self.weight = w[:, None] * np.ones(3) if w.ndim else np.full((1, 3), float(w))
        self.component = check_child(component, f"{name}.component", self._kind)

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


bsdf_component = BsdfComponent
color_bsdf_component = ColorBsdfComponent
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
            kind = EdfComponent if isinstance(c[1], Edf) else BsdfComponent
            if color:
                kind = ColorEdfComponent if kind is EdfComponent else ColorBsdfComponent
            out.append(kind(*c))
        else:
            raise ValueError(
                f"{mix}: components[{i}] must be a component struct or a (weight, df) pair, "
                f"got {type(c).__name__}"
            )
    edf = [c._kind is Edf for c in out]
    if any(edf) and not all(edf):
        raise ValueError(f"{mix}: components mix bsdf and edf components; use one kind")
    return out


class _Weights:
    """Effective per-lane weights of a mix (the subclass's normalisation or clamping)."""

    def _raw(self, n: int) -> np.ndarray:
        """(n, k, 3) MDL weights per lane."""
        k = len(self.components)
        if k == 0:
            return np.zeros((n, 0, 3))
        return np.stack(
            [np.broadcast_to(lanes(c.weight, n, "weight"), (n, 3)) for c in self.components],
            axis=1,
        )

    def weights(self, n: int) -> np.ndarray:
        """(n, k, 3) effective weights ``w_i`` (see the mix's docstring)."""
        raise NotImplementedError


class MixBsdf(_Weights, Bsdf):
    """Base of the Bsdf mixes; subclasses implement :meth:`weights`."""

    def __init__(self, components):
        comps = as_components(components, self._color, self._mdl_name)
        self.components = comps
        self.lobes = union_lobes(*(c.component for c in comps))
        self._probs_memo, self._cheap_memo = Memo(), Memo()

    _color = False
    _mdl_name = "mix"

    def __repr__(self) -> str:
        return f"{self._mdl_name}(components={self.components!r})"

    def _probs(self, wo: Vec3, w: np.ndarray) -> np.ndarray:
        return self._probs_memo.get(wo, lambda: self._probs_now(wo, w))

    def _probs_now(self, wo: Vec3, w: np.ndarray) -> np.ndarray:
        n = len(wo)
        est = np.stack(
            [lum(w[:, i] * cheap_albedo(c.component, wo)) for i, c in enumerate(self.components)],
            axis=1,
        ) if self.components else np.zeros((n, 0))
        possible = np.stack(
            [np.full(n, c.component is not None) & np.any(w[:, i] > 0, axis=1)
             for i, c in enumerate(self.components)],
            axis=1,
        ) if self.components else np.zeros((n, 0), dtype=bool)
        return selection(est, possible)

    def _parts(self, wo: Vec3, wi: Vec3, draws=None):
        """Everything eval, pdf and sample need at ``(wo, wi)``.

        ``draws``: the components' draws to settle at ``wi`` (:meth:`_settle`, None for
        a component not drawn); their settled samples are returned last.
        """
        n = len(wo)
        w = self.weights(n)
        probs = self._probs(wo, w)
        value = np.zeros((n, 3))
        pdf = np.zeros(n)
        on = np.zeros((n, len(self.components)), dtype=bool)
        samples = [None] * len(self.components)
        for i, c in enumerate(self.components):
            if c.component is None:
                continue
            d = draws[i] if draws is not None else None
            e, p, samples[i] = child_settle(c.component, wo, wi, d)
            contrib = w[:, i] * e
            on[:, i] = any_positive(contrib)
            value += contrib
            pdf += probs[:, i] * p * on[:, i]
        value = np.where((pdf > 0)[:, None], value, 0.0)
        return value, pdf, w, probs, on, samples

    def eval_pdf(self, wo: Vec3, wi: Vec3) -> tuple[Rgb, Arr]:
        wo, wi = check_dirs(wo, wi)
        value, pdf = self._parts(wo, wi)[:2]
        return (check_finite(f"{self._mdl_name}.eval", value, True),
                check_finite(f"{self._mdl_name}.pdf", pdf, True))

    def eval(self, wo: Vec3, wi: Vec3) -> Rgb:
        return self.eval_pdf(wo, wi)[0]

    def pdf(self, wo: Vec3, wi: Vec3) -> Arr:
        return self.eval_pdf(wo, wi)[1]

    def sample(self, wo: Vec3, u1: Arr, u2: Arr2) -> BsdfSample:
        return sample_by_draw(self, wo, u1, u2)

    def _draw(self, wo: Vec3, u1: Arr, u2: Arr2) -> Draw:
        """Pick a component per lane and descend into it (no evaluation)."""
        n = len(wo)
        draws = [None] * len(self.components)
        wi = np.zeros((n, 3))
        on = np.zeros(n, dtype=bool)
        if not self.components:
            return Draw(wi, on, (None, None, None, draws))
        w = self.weights(n)
        idx, u, p_sel = pick(u1, self._probs(wo, w))
        for i, c in enumerate(self.components):
            mine = idx == i
            if c.component is None or not np.any(mine):
                continue
            draws[i] = child_draw(c.component, wo, np.where(mine, u, 0.0), u2)
            take = mine & drawn(draws[i])
            wi = np.where(take[:, None], draws[i].wi, wi)
            on |= take
        return Draw(wi, on, (w, idx, p_sel, draws))

    def _settle(self, wo: Vec3, wi: Vec3, d: Draw) -> tuple[Rgb, Arr, BsdfSample]:
        """``eval_pdf(wo, wi)`` and the sample ``d`` settled at ``wi`` (its drawn direction
        wherever it was drawn), from one evaluation of the subtree."""
        n = len(wo)
        if not self.components:
            return np.zeros((n, 3)), np.zeros(n), BsdfSample.failed(n)
        w, idx, p_sel, draws = d.state
        value, pdf, _, _, on, samples = self._parts(wo, wi, draws)
        cw = np.zeros((n, 3))  # the chosen component's weight times its mix weight
        cpdf = np.zeros(n)
        valid = np.zeros(n, dtype=bool)
        delta = np.zeros(n, dtype=bool)
        lobe = np.zeros(n, dtype=np.int32)
        for i, s in enumerate(samples):
            if s is None:
                continue
            take = (idx == i) & s.valid
            cw = np.where(take[:, None], w[:, i] * s.weight, cw)
            cpdf = np.where(take, s.pdf, cpdf)
            valid |= take
            delta |= take & s.is_delta
            lobe = np.where(take, s.lobe, lobe)
        rows = np.arange(n)
        chosen_on = on[rows, np.maximum(idx, 0)] & (idx >= 0)
        ok_nd = valid & ~delta & chosen_on & (pdf > 0)
        w_nd = value / np.where(ok_nd, pdf, 1.0)[:, None]
        w_d = cw / np.where(p_sel > 0, p_sel, 1.0)[:, None]
        pdf_d = p_sel * cpdf
        ok_d = valid & delta & any_positive(w_d) & (pdf_d > 0)
        ok = ok_nd | ok_d
        s = BsdfSample(
            np.where(ok[:, None], wi, 0.0),
            np.where(ok_nd, pdf, np.where(ok_d, pdf_d, 0.0)),
            np.where(ok_nd[:, None], w_nd, np.where(ok_d[:, None], w_d, 0.0)),
            np.where(ok, lobe, 0).astype(np.int32),
        ).checked()
        return (check_finite(f"{self._mdl_name}.eval", value, True),
                check_finite(f"{self._mdl_name}.pdf", pdf, True), s)

    def albedo(self, wo: Vec3) -> Rgb:
        (wo,) = check_dirs(wo, names=("wo",))
        n = len(wo)
        w = self.weights(n)
        out = np.zeros((n, 3))
        for i, c in enumerate(self.components):
            if c.component is not None:
                out += w[:, i] * c.component.albedo(wo)
        return out

    def _cheap_albedo(self, wo: Vec3) -> Rgb:
        return self._cheap_memo.get(wo, lambda: self._cheap_albedo_now(wo))

    def _cheap_albedo_now(self, wo: Vec3) -> Rgb:
        n = len(wo)
        w = self.weights(n)
        out = np.zeros((n, 3))
        for i, c in enumerate(self.components):
            out += w[:, i] * cheap_albedo(c.component, wo)
        return out


class MixEdf(_Weights, Edf):
    """Base of the EDF mixes (``normalized_mix`` / ``clamped_mix`` over ``edf_component``)."""

    _color = False
    _mdl_name = "mix"

    def __init__(self, components):
        self.components = as_components(components, self._color, self._mdl_name)

    def __repr__(self) -> str:
        return f"{self._mdl_name}(components={self.components!r})"

    def _probs(self, n: int, w: np.ndarray) -> np.ndarray:
        k = len(self.components)
        if k == 0:
            return np.zeros((n, 0))
        possible = np.stack(
            [np.full(n, c.component is not None) for c in self.components], axis=1
        ) & np.any(w > 0, axis=2)
        return selection(lum(w.reshape(-1, 3)).reshape(n, k), possible)

    def _parts(self, wo: Vec3):
        n = len(wo)
        w = self.weights(n)
        probs = self._probs(n, w)
        value = np.zeros((n, 3))
        pdf = np.zeros(n)
        for i, c in enumerate(self.components):
            if c.component is None:
                continue
            contrib = w[:, i] * c.component.eval(wo)
            value += contrib
            pdf += probs[:, i] * c.component.pdf(wo) * any_positive(contrib)
        return np.where((pdf > 0)[:, None], value, 0.0), pdf

    def eval(self, wo: Vec3) -> Rgb:
        (wo,) = check_dirs(wo, names=("wo",))
        return self._parts(wo)[0]

    def pdf(self, wo: Vec3) -> Arr:
        (wo,) = check_dirs(wo, names=("wo",))
        return self._parts(wo)[1]

    def sample(self, u1: Arr, u2: Arr2) -> EdfSample:
        n = len(np.asarray(u2))
        u1, u2 = check_samples(n, u1, u2)
        w = self.weights(n)
        idx, u, _ = pick(u1, self._probs(n, w))
        wo = np.zeros((n, 3))
        ok = np.zeros(n, dtype=bool)
        for i, c in enumerate(self.components):
            mine = idx == i
            if c.component is None or not np.any(mine):
                continue
            s = c.component.sample(np.where(mine, u, 0.0), u2)
            take = mine & s.valid
            wo = np.where(take[:, None], s.wo, wo)
            ok |= take
        wo_eval = np.where(ok[:, None], wo, np.array([0.0, 0.0, 1.0]))
        value, pdf = self._parts(wo_eval)
        ok &= pdf > 0
        weight = value * (wo_eval[:, 2] / np.where(ok, pdf, 1.0))[:, None]
        return EdfSample(
            np.where(ok[:, None], wo, 0.0),
            np.where(ok, pdf, 0.0),
            np.where(ok[:, None], weight, 0.0),
        )
