"""Environment lights written in MDL: a call of a ``color`` function of
``state::direction()``.

MDL gives a scene's environment as a function that returns the radiance arriving along
``state::direction()`` (a world-space unit vector).  :func:`environment_from_call` turns
such a call into one of the core's lights:

* ``base::sun_and_sky(...)`` (the workbench's ``::sky``) is the core's own
  :class:`render.sky.SunAndSky`, evaluated and sampled analytically;
* a call whose value does not vary is a :class:`render.lights.ConstantEnvironment`;
* any other function is evaluated once per texel centre of a latitude-longitude image
  (``resolution = (rows, columns)``, the layout of :mod:`render.lights`) and becomes a
  :class:`render.lights.LatLongEnvironment`: piecewise constant per texel, so detail
  finer than a texel (a sun disk) is averaged away -- give the resolution it needs.

Examples
--------
>>> light = environment_from_call("base::sun_and_sky(sun_direction: float3(-1, 1, -1))")
>>> type(light).__name__
'SunAndSky'
>>> env = environment_from_call("color(0.25, 0.5, 1.0)")
>>> env.radiance.tolist()
[0.25, 0.5, 1.0]
"""

from __future__ import annotations

import numpy as np

from mdl import lanes as LN
from mdl.diagnostics import MdlError, Source

__all__ = ["environment_from_call", "direction_grid"]


def direction_grid(rows: int, columns: int) -> np.ndarray:
    """``(rows, columns, 3)`` unit directions at the texel centres of a lat-long image
    (``u = 0.5 + atan2(x, -z) / (2 pi)``, ``v = acos(y) / pi``)."""
    theta = np.pi * (np.arange(rows) + 0.5) / rows
    phi = 2.0 * np.pi * ((np.arange(columns) + 0.5) / columns - 0.5)
    st, ct = np.sin(theta)[:, None], np.cos(theta)[:, None]
    x = st * np.sin(phi)[None, :]
    z = -st * np.cos(phi)[None, :]
    y = np.broadcast_to(ct, x.shape)
    return np.stack([x, y, z], axis=-1)


def _direction_state(d: np.ndarray):
    from displacement.state import ShadingState

    n = len(d)
    zero = np.zeros((n, 3))
    return ShadingState(zero, -d, np.zeros((n, 2)), np.tile([1.0, 0.0, 0.0], (n, 1)),
                        np.tile([0.0, 1.0, 0.0], (n, 1)), direction=d)


def environment_from_call(call: str, module: str | None = None, *, base_dir=None,
                          mdl_paths=(), resolution=(256, 512),
                          source_name: str = "<environment call>", line: int = 1,
                          col: int = 1):
    """The light of an MDL environment call (see the module docstring).

    Parameters
    ----------
    call : str
        ``base::sun_and_sky(sun_direction: float3(-1, 1, -1))``, ``color(0.2)``, or a call
        of a ``color`` function exported by ``module``.
    module : str, optional
        As for materials (:func:`render.mdlc.material_from_call`).
    resolution : (rows, columns)
        The lat-long image a varying function is baked into.

    Raises
    ------
    MdlError
        Syntax, name and type errors (located), or a call that is not a colour.
    """
    from render.lights import ConstantEnvironment, LatLongEnvironment
    from render.mdlc import MaterialInstanceError, Session
    from render.mdlc.instance import Const, Vary
    from render.mdlc.natives import SkyFunction

    session = Session(base_dir, mdl_paths)
    src = Source(source_name, call, line - 1, col - 1)
    try:
        value, info = session.material(call, src, module)
    except MaterialInstanceError as e:
        raise MdlError([e.diagnostic()]) from None
    from mdl import types as T

    if info.type != T.COLOR:
        raise MdlError([src.diagnostic(
            "error", f"an environment is a color function of state::direction(); this call "
            f"gives {info.type}", 0, len(call),
            "call a function returning color, such as base::sun_and_sky(...)")])
    if isinstance(value, Vary) and isinstance(value.core, SkyFunction):
        return value.core.sky
    if isinstance(value, Const):
        rgb = np.asarray(LN.to_python(value.value, T.COLOR), dtype=np.float64)
        return ConstantEnvironment(np.maximum(rgb, 0.0))
    rows, columns = (int(x) for x in resolution)
    d = direction_grid(rows, columns).reshape(-1, 3)
    with np.errstate(all="ignore"):
        rgb = np.asarray(value.lanes(_direction_state(d)), dtype=np.float64)
    rgb = np.broadcast_to(rgb, (len(d), 3)).reshape(rows, columns, 3)
    return LatLongEnvironment(rgb)
