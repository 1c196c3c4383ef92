"""What the stability suite (tests/stability, docs/stability.md) asks of every render at
the extremes: finite, non-negative radiance, no sample the film had to drop as
non-finite, and no energy created (a white furnace stays at or below 1)."""

from __future__ import annotations

import math

import numpy as np

from render.camera import Camera
from render.integrator import render
from render.lights import ConstantEnvironment
from render.scene import RenderSettings, Scene

#: standard errors of the pixel mean a furnace may exceed 1 by (Monte Carlo noise)
FURNACE_SIGMAS = 4.0
#: and the absolute tolerance on top (the albedo tables of the layered dfs, 1e-3)
FURNACE_TOL = 1e-3


def assert_valid_radiance(film) -> np.ndarray:
    """The film's image is finite and non-negative, and no sample was non-finite;
    returns the image (h, w, 3)."""
    img = film.rgb()
    assert np.all(np.isfinite(img)), "non-finite radiance in the image"
    assert img.min() >= 0.0, f"negative radiance {img.min()}"
    assert film.stats.get("nonfinite_samples", 0) == 0, (
        f"{film.stats['nonfinite_samples']} non-finite samples were dropped by the film")
    return img


def mean_and_error(pixels: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Per-channel mean of pixels (n, 3) and its standard error."""
    return pixels.mean(axis=0), pixels.std(axis=0, ddof=1) / math.sqrt(max(len(pixels), 1))


def assert_no_energy_gain(pixels: np.ndarray, exact: bool = False) -> np.ndarray:
    """A white furnace (environment 1, every surface's tint <= 1): the mean radiance is at
    most 1 within :data:`FURNACE_SIGMAS` standard errors plus :data:`FURNACE_TOL`, and,
    with ``exact``, also at least 1 so (lossless surfaces).  Returns the mean."""
    assert len(pixels) > 0, "no pixel to check"
    mean, err = mean_and_error(pixels)
    bound = FURNACE_SIGMAS * err + FURNACE_TOL
    assert np.all(mean <= 1.0 + bound), f"energy gain: mean {mean} > 1 + {bound}"
    if exact:
        assert np.all(mean >= 1.0 - bound), f"energy loss: mean {mean} < 1 - {bound}"
    return mean


def furnace(objects, camera: Camera, spp: int = 16, **settings):
    """Render ``objects`` in a uniform white environment (radiance 1); returns the film
    after :func:`assert_valid_radiance`."""
    scene = Scene(camera, list(objects), [ConstantEnvironment(1.0)],
                  RenderSettings(camera.width, camera.height, spp=spp,
                                 **{"max_depth": -1, **settings}))
    film = render(scene, progress=False)
    assert_valid_radiance(film)
    return film
