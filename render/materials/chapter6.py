"""Chapter 6 of the Handbook, "Combining distribution functions": layers and mixes.

Listings 6.1-6.13 and the unnumbered materials of sections 6.2 and 6.5: weighted,
Fresnel and custom-curve layering, normalized and clamped mixing, materials built from
the bsdfs of other materials (``glossy(...).surface.scattering``), and the layer series
of Figures 6.24-6.36.  :func:`fresnel_layer_of` and :func:`mix_of` are the small
helpers chapters 4, 7 and 8 share.

Reading notes:

* ``glossy`` (Listing 6.6: tint 0.5, roughness 0.1) and ``mirror`` (Figure 6.27:
  ``specular_bsdf(tint: white)``) share their names with Part 5's ``glossy`` (Listing
  12.8: tint 0.7, roughness 0.3) and chapter 3's ``mirror`` (Listing 3.5: tint 0.5).
  They are this module's :func:`glossy` and :func:`mirror` and are used by this
  chapter's materials; the registry's ``glossy`` and ``mirror`` stay Listings 12.8 and 3.5.
* Section 6.5.1 prints the listings of section 6.5.2 (``two_layers`` is a
  ``two_glossy_lobes`` mix of orange and yellow) under Figures 6.28-6.30, while its
  text and diagram describe another series: ``two_layers`` layers the wide blue
  glossy over the diffuse green base with ``custom_curve_layer``, ``three_layers``
  the narrow blue glossy over that with ``weighted_layer``, ``four_layers`` the mirror
  over that with ``fresnel_layer``.  The diagram of section 6.5.2 names its series
  ``two_layers_v1`` (clamped mix), ``three_layers_v1`` (custom curve),
  ``four_layers_v1`` (weighted) and ``five_layers`` (Fresnel).  So ``two_layers``,
  ``three_layers`` and ``four_layers`` here are section 6.5.1's series, with the
  layer arguments of the printed listings (custom curve 0 / 1 / exponent 0.5, weight
  0.3, Fresnel ior 1.6); ``two_layers_v1``, ``three_layers_v1``, ``four_layers_v1``
  are the printed listings, and ``five_layers`` (Figure 6.36) layers the mirror over
  ``four_layers_v1``.
* ``fresnel_layer``'s ``ior`` is a ``float`` since MDL 1.4; the listings pass colours
  (``color(1.6)``).  A grey colour is that float; a coloured one uses
  ``df::color_fresnel_layer`` (:func:`fresnel_layer_of`).
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np

from render.material import (
    Color,
    DfNode,
    Float,
    Varying,
    df,
    evaluate,
    material,
    material_surface,
)
from render.materials._common import color
from render.materials.earlier import diffuse

__all__ = [
    "WHITE",
    "BLUE",
    "GREEN",
    "ORANGE",
    "YELLOW",
    "fresnel_layer_of",
    "mix_of",
    "red",
    "shiny",
    "shiny_red",
    "shiny_red_with_let",
    "shiny_red_extract",
    "glossy",
    "glossy_over_diffuse",
    "shiny_red_specialized",
    "light_blue_ceramic",
    "shiny_tint",
    "fresnel_glossy_over_diffuse",
    "two_glossy_lobes",
    "diffuse_green_base",
    "wide_blue_glossy",
    "narrow_blue_glossy",
    "mirror",
    "two_layers",
    "three_layers",
    "four_layers",
    "two_layers_v1",
    "three_layers_v1",
    "four_layers_v1",
    "five_layers",
]

#: Section 6.5.1's ``const color white = color(0.7)``.
WHITE = (0.7, 0.7, 0.7)
#: ``const color blue = color(0.2, 0.3, 0.7)``.
BLUE = (0.2, 0.3, 0.7)
#: ``const color green = color(0.1, 0.3, 0.05)`` (chapter 8's ``green`` differs).
GREEN = (0.1, 0.3, 0.05)
#: Section 6.5.2's ``const color orange = color(0.3, 0.15, 0.0)``.
ORANGE = (0.3, 0.15, 0.0)
#: ``const color yellow = color(0.5, 0.4, 0.1)``.
YELLOW = (0.5, 0.4, 0.1)


# ---------------------------------------------------------------------------
# helpers shared by chapters 4, 6, 7 and 8


def _layer_kwargs(weight, layer, base, normal) -> dict:
    """The given layer arguments (``bsdf()`` defaults and ``state::normal()`` left out)."""
    kw = {"weight": weight}
    if layer is not None:
        kw["layer"] = layer
    if base is not None:
        kw["base"] = base
    if normal is not None:
        kw["normal"] = normal
    return kw


def fresnel_layer_of(ior, weight=1.0, layer: DfNode | None = None, base: DfNode | None = None,
                     normal=None) -> DfNode:
    """``df::fresnel_layer(ior, weight, layer, base, normal)`` for a float or colour ``ior``.

    MDL 1.4 made ``fresnel_layer``'s ``ior`` a float; the Handbook passes colours. A
    float, or a grey constant colour, gives ``df::fresnel_layer`` with that float; a
    coloured constant or a varying colour gives ``df::color_fresnel_layer`` (per-channel
    Fresnel, ``weight`` as ``color(weight)``).

    Parameters
    ----------
    ior : float, color (3,) or callable(state) -> (n, 3)
    weight : float or callable(state) -> (n,)
    layer, base : DfNode (bsdf) or None
        None is MDL's ``bsdf()``.
    normal : float3 or None
        None is ``state::normal()``.

    Returns
    -------
    DfNode

    Raises
    ------
    ValueError
        A constant ior that is not finite and > 0.
    """
    if callable(ior):
        return df.color_fresnel_layer(ior=ior, **_layer_kwargs(_color_weight(weight), layer,
                                                               base, normal))
    a = np.asarray(ior, dtype=np.float64)
    if a.ndim == 0:
        a = np.full(3, float(a))
    if a.shape != (3,) or not np.all(np.isfinite(a)) or np.any(a <= 0.0):
        raise ValueError(f"ior must be a float or a colour > 0 (an index of refraction), "
                         f"got {ior!r}")
    if np.all(a == a[0]):
        return df.fresnel_layer(ior=float(a[0]), **_layer_kwargs(weight, layer, base, normal))
    return df.color_fresnel_layer(ior=tuple(float(x) for x in a),
                                  **_layer_kwargs(_color_weight(weight), layer, base, normal))


def _color_weight(weight):
    """``color(weight)`` for a float weight (constant or varying)."""
    if callable(weight):
        return Varying(lambda s: np.repeat(evaluate(weight, s, "float", "weight")[:, None], 3,
                                           axis=1), "color", {"weight": weight})
    return color(weight, "weight")


def mix_of(kind: str, components: Sequence[tuple[object, DfNode]]) -> DfNode:
    """``df::<kind>(components: df::bsdf_component[](df::bsdf_component(weight, component), ...))``.

    Parameters
    ----------
    kind : {"normalized_mix", "clamped_mix"}
    components : sequence of (weight, DfNode)
        Weights are floats or callables of state.

    Returns
    -------
    DfNode
    """
    if kind not in ("normalized_mix", "clamped_mix"):
        raise ValueError(f"kind must be 'normalized_mix' or 'clamped_mix', got {kind!r}")
    parts = [df.bsdf_component(weight=w, component=c) for w, c in components]
    return getattr(df, kind)(components=parts)


# ---------------------------------------------------------------------------
# section 6.2: weighted layering


def red() -> material:
    """Figure 6.2: ``df::diffuse_reflection_bsdf(tint: color(0.3, 0.03, 0.05))``."""
    return diffuse((0.3, 0.03, 0.05))


def shiny() -> material:
    """Figure 6.3: ``df::simple_glossy_bsdf(tint: color(0.15), roughness_u: 0.08,
    mode: df::scatter_reflect)``."""
    return material(surface=material_surface(scattering=df.simple_glossy_bsdf(
        tint=(0.15, 0.15, 0.15), roughness_u=0.08, mode="scatter_reflect")))


def _shiny_red(shiny_weight) -> material:
    return material(surface=material_surface(scattering=df.weighted_layer(
        weight=shiny_weight, layer=shiny().surface.scattering, base=red().surface.scattering)))


def shiny_red(shiny_weight: Float = 0.5) -> material:
    """Listings 6.1 and 6.2: ``df::weighted_layer(weight: shiny_weight, layer: <shiny>,
    base: <red>)``.

    Examples
    --------
    >>> node = shiny_red().surface.scattering
    >>> node.name, node.kwargs["weight"], node.kwargs["layer"].name, node.kwargs["base"].name
    ('weighted_layer', 0.5, 'simple_glossy_bsdf', 'diffuse_reflection_bsdf')
    """
    return _shiny_red(shiny_weight)


def shiny_red_with_let(shiny_weight: Float = 0.5) -> material:
    """Listing 6.3: ``shiny_red`` written with a let-expression (the same material)."""
    return _shiny_red(shiny_weight)


def shiny_red_extract(shiny_weight: Float = 0.5) -> material:
    """Listing 6.4: ``shiny_red`` from ``shiny().surface.scattering`` and
    ``red().surface.scattering`` (the same material)."""
    return _shiny_red(shiny_weight)


def glossy(tint: Color = (0.5, 0.5, 0.5), roughness: Float = 0.1) -> material:
    """Listing 6.6: ``df::simple_glossy_bsdf(tint, roughness_u: roughness,
    mode: df::scatter_reflect)`` (not Part 5's ``glossy`` of Listing 12.8)."""
    return material(surface=material_surface(scattering=df.simple_glossy_bsdf(
        tint=color(tint, "tint"), roughness_u=roughness, mode="scatter_reflect")))


def glossy_over_diffuse(glossy_tint: Color = (0.1, 0.1, 0.1), glossy_roughness: Float = 0.1,
                        glossy_weight: Float = 0.5,
                        diffuse_tint: Color = (0.5, 0.5, 0.5)) -> material:
    """Listing 6.7: ``df::weighted_layer(weight: glossy_weight, layer: glossy(glossy_tint,
    glossy_roughness).surface.scattering, base: diffuse(diffuse_tint).surface.scattering)``."""
    glossy_bsdf = glossy(tint=glossy_tint, roughness=glossy_roughness).surface.scattering
    diffuse_bsdf = diffuse(tint=color(diffuse_tint, "diffuse_tint")).surface.scattering
    return material(surface=material_surface(scattering=df.weighted_layer(
        weight=glossy_weight, layer=glossy_bsdf, base=diffuse_bsdf)))


def shiny_red_specialized() -> material:
    """Listing 6.8: ``glossy_over_diffuse(glossy_tint: color(0.15), glossy_roughness: 0.08,
    diffuse_tint: color(0.3, 0.03, 0.05))``."""
    return glossy_over_diffuse(glossy_tint=(0.15, 0.15, 0.15), glossy_roughness=0.08,
                               diffuse_tint=(0.3, 0.03, 0.05))


def light_blue_ceramic() -> material:
    """Listing 6.9: ``glossy_over_diffuse(glossy_tint: color(0.1, 0.1, 0.08),
    glossy_roughness: 0.2, diffuse_tint: color(0.7, 0.8, 0.9))`` (Figure 6.8)."""
    return glossy_over_diffuse(glossy_tint=(0.1, 0.1, 0.08), glossy_roughness=0.2,
                               diffuse_tint=(0.7, 0.8, 0.9))


def shiny_tint(tint: Color = (1.0, 1.0, 1.0)) -> material:
    """Listing 6.10: ``glossy_over_diffuse(glossy_tint: color(0.15), glossy_roughness: 0.08,
    diffuse_tint: tint)``."""
    return glossy_over_diffuse(glossy_tint=(0.15, 0.15, 0.15), glossy_roughness=0.08,
                               diffuse_tint=tint)


# ---------------------------------------------------------------------------
# section 6.3: Fresnel layering


def fresnel_glossy_over_diffuse(glossy_roughness: Float = 0.1,
                                diffuse_tint: Color = (0.5, 0.5, 0.5),
                                ior: Color = (1.3, 1.3, 1.3)) -> material:
    """Listing 6.11: ``df::fresnel_layer(ior, weight: 1.0, layer: glossy(tint: color(0.7),
    roughness: glossy_roughness).surface.scattering, base: diffuse(diffuse_tint)...)``.

    Examples
    --------
    >>> node = fresnel_glossy_over_diffuse().surface.scattering
    >>> node.name, node.kwargs["ior"], node.kwargs["layer"].kwargs["tint"]
    ('fresnel_layer', 1.3, (0.7, 0.7, 0.7))
    """
    glossy_bsdf = glossy(tint=(0.7, 0.7, 0.7), roughness=glossy_roughness).surface.scattering
    diffuse_bsdf = diffuse(tint=color(diffuse_tint, "diffuse_tint")).surface.scattering
    return material(surface=material_surface(scattering=fresnel_layer_of(
        color(ior, "ior"), weight=1.0, layer=glossy_bsdf, base=diffuse_bsdf)))


# ---------------------------------------------------------------------------
# section 6.4: mixing


def two_glossy_lobes(roughness_1: Float = 0.1, weight_1: Float = 0.5,
                     tint_1: Color = (0.7, 0.7, 0.7), roughness_2: Float = 0.5,
                     weight_2: Float = 0.5, tint_2: Color = (0.7, 0.7, 0.7)) -> material:
    """Listing 6.13: ``df::clamped_mix`` of two ``df::simple_glossy_bsdf(tint_i,
    roughness_u: roughness_i)`` components weighted ``weight_1`` and ``weight_2``."""
    return material(surface=material_surface(scattering=mix_of("clamped_mix", [
        (weight_1, df.simple_glossy_bsdf(tint=color(tint_1, "tint_1"), roughness_u=roughness_1)),
        (weight_2, df.simple_glossy_bsdf(tint=color(tint_2, "tint_2"), roughness_u=roughness_2)),
    ])))


# ---------------------------------------------------------------------------
# section 6.5: multiple layers


def diffuse_green_base() -> material:
    """Figure 6.24: ``df::diffuse_reflection_bsdf(tint: green)``."""
    return diffuse(GREEN)


def wide_blue_glossy() -> material:
    """Figure 6.25: ``df::simple_glossy_bsdf(tint: blue, roughness_u: 0.5)``."""
    return material(surface=material_surface(scattering=df.simple_glossy_bsdf(
        tint=BLUE, roughness_u=0.5)))


def narrow_blue_glossy() -> material:
    """Figure 6.26: ``df::simple_glossy_bsdf(tint: blue, roughness_u: 0.2)``."""
    return material(surface=material_surface(scattering=df.simple_glossy_bsdf(
        tint=BLUE, roughness_u=0.2)))


def mirror() -> material:
    """Figure 6.27: ``df::specular_bsdf(tint: white, mode: df::scatter_reflect)``, the
    clear coat (not chapter 3's ``mirror`` of Listing 3.5)."""
    return material(surface=material_surface(scattering=df.specular_bsdf(
        tint=WHITE, mode="scatter_reflect")))


def _surface(scattering: DfNode) -> material:
    return material(surface=material_surface(scattering=scattering))


def _custom_curve_over(layer: DfNode, base: DfNode) -> DfNode:
    """The custom curve of Figures 6.29 and 6.34: reflectivity 0 facing, 1 grazing,
    exponent 0.5, weight 1."""
    return df.custom_curve_layer(normal_reflectivity=0.0, grazing_reflectivity=1.0,
                                 exponent=0.5, weight=1.0, layer=layer, base=base)


def _weighted_over(layer: DfNode, base: DfNode) -> DfNode:
    """The weighted layer of Figures 6.30 and 6.35: weight 0.3."""
    return df.weighted_layer(weight=0.3, layer=layer, base=base)


def _fresnel_over(layer: DfNode, base: DfNode) -> DfNode:
    """The Fresnel layer of Figure 6.36: ``ior: color(1.6)``, weight 1."""
    return fresnel_layer_of(1.6, weight=1.0, layer=layer, base=base)


def two_layers() -> material:
    """Section 6.5.1: the wide blue glossy over the diffuse green base by
    ``custom_curve_layer`` (see the module notes)."""
    return _surface(_custom_curve_over(wide_blue_glossy().surface.scattering,
                                       diffuse_green_base().surface.scattering))


def three_layers() -> material:
    """Section 6.5.1: the narrow blue glossy over ``two_layers`` by ``weighted_layer``."""
    return _surface(_weighted_over(narrow_blue_glossy().surface.scattering,
                                   two_layers().surface.scattering))


def four_layers() -> material:
    """Section 6.5.1: the clear-coat ``mirror`` over ``three_layers`` by ``fresnel_layer``."""
    return _surface(_fresnel_over(mirror().surface.scattering, three_layers().surface.scattering))


def two_layers_v1() -> material:
    """Figures 6.28/6.33: ``two_glossy_lobes(weight_1: 0.5, tint_1: orange, roughness_1: 0.6,
    weight_2: 0.5, tint_2: yellow, roughness_2: 0.3)`` (a clamped mix)."""
    return two_glossy_lobes(weight_1=0.5, tint_1=ORANGE, roughness_1=0.6,
                            weight_2=0.5, tint_2=YELLOW, roughness_2=0.3)


def three_layers_v1() -> material:
    """Figures 6.29/6.34: ``df::custom_curve_layer(normal_reflectivity: 0,
    grazing_reflectivity: 1.0, exponent: 0.5, weight: 1, layer: <two_layers_v1>,
    base: <diffuse_green_base>)``."""
    return _surface(_custom_curve_over(two_layers_v1().surface.scattering,
                                       diffuse_green_base().surface.scattering))


def four_layers_v1() -> material:
    """Figures 6.30/6.35: ``df::weighted_layer(weight: 0.3, layer: <narrow_blue_glossy>,
    base: <three_layers_v1>)``."""
    return _surface(_weighted_over(narrow_blue_glossy().surface.scattering,
                                   three_layers_v1().surface.scattering))


def five_layers() -> material:
    """Figure 6.36: ``df::fresnel_layer(ior: color(1.6), weight: 1.0, layer: <mirror>,
    base: <four_layers_v1>)``: five bsdfs in four combinations.

    Examples
    --------
    >>> top = five_layers().surface.scattering
    >>> [top.name, top.kwargs["base"].name, top.kwargs["base"].kwargs["base"].name]
    ['fresnel_layer', 'weighted_layer', 'custom_curve_layer']
    """
    return _surface(_fresnel_over(mirror().surface.scattering,
                                  four_layers_v1().surface.scattering))
