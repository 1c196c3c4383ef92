"""What the combiners' Python classes share: child checks and the fast albedo estimate.

What each combiner does in each phase (selection by a defensive mixture of expected
contributions, one descent and one evaluation per sample, the albedo's control
variates) is written in its role's module, :mod:`render.df._layer`, :mod:`render.df._mix`
and :mod:`render.df._modifier`, which :mod:`render.interpreter` compiles; each
combiner's factors are kernels in its own module.
"""

from __future__ import annotations

import numpy as np

from render._typing import ArrayLike, Rgb
from render.bsdf import Bsdf

__all__ = ["check_child", "albedo_estimate"]


def check_child(child, name: str, kind: type = Bsdf):
    """``child`` if it is a ``kind`` (Bsdf or Edf) or None (MDL's ``bsdf()``), else ValueError."""
    if child is None or isinstance(child, kind):
        return child
    article = "an" if kind.__name__[0] in "AEIOU" else "a"
    raise ValueError(
        f"{name} must be {article} {kind.__name__} (a bound render.df distribution function) "
        f"or None for MDL's black {'bsdf' if kind is Bsdf else 'edf'}(), got {type(child).__name__}"
    )


def albedo_estimate(bsdf, wo: ArrayLike) -> Rgb:
    """A fast directional-albedo estimate of a bound bsdf (None: 0), e.g. for an albedo AOV.

    Exact for the elemental dfs, mixes, weighted layers and ``tint``; the directional
    layers and ``directional_factor`` use their factors at ``wo`` times their children's
    estimates (:func:`render.interpreter.cheap_albedo`).

    Parameters
    ----------
    bsdf : ProgramBsdf or None
    wo : (n, 3) float64

    Returns
    -------
    (n, 3) float64

    Examples
    --------
    >>> from render.df import fresnel_layer, specular_bsdf, diffuse_reflection_bsdf
    >>> coat = fresnel_layer(1.5, layer=specular_bsdf(), base=diffuse_reflection_bsdf(tint=0.5))
    >>> albedo_estimate(coat, np.array([[0.0, 0.0, 1.0]])).round(6).tolist()   # 0.04 + 0.96 / 2
    [[0.52, 0.52, 0.52]]
    """
    wo = np.asarray(wo, dtype=np.float64)
    if bsdf is None:
        return np.zeros((len(wo), 3))
    return bsdf.cheap_albedo(wo)
