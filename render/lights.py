"""Light sources: point, spot, directional, area (emissive geometry) and environments.

These classes hold a light's parameters, checked, and the tables it is sampled by; the
sampling itself is one compiled kernel for every kind (:func:`render.light_sampling.sample_light`,
batch form :func:`render.light_sampling.sample_lights`): for a receiving point ``p`` it picks a
direction ``wi`` toward the light and returns the radiance arriving along it with the
solid-angle density of that choice.  Delta lights (point, spot, directional) have
``pdf = 1`` (times the selection probability) and ``delta = True``: the integrator gives
them full weight (no multiple importance sampling), and BSDF-sampled rays never hit
them.

Units (linear RGB, as Mitsuba 3 uses them, so the side-by-side tests compare like with
like):

* point and spot: radiant ``intensity`` I (W/sr); arriving radiance ``I / d^2`` (times
  the spot's falloff);
* directional: ``irradiance`` E (W/m^2) on a surface facing the light;
* area lights: emissive objects whose material has ``surface.emission`` (MDL's
  ``diffuse_edf`` or ``spot_edf`` times ``intensity``, radiance ``intensity / pi`` for a
  diffuse edf); their radiance is evaluated by the scene (the material) at the sampled
  point, so a varying intensity works too;
* environments: ``radiance`` L seen in every direction (constant), or a lat-long image
  times ``scale``; the sun-and-sky environment (:class:`render.sky.SunAndSky`, the
  Handbook's ``base::sun_and_sky``) gives the sun's irradiance ``E`` on a surface
  facing it and the sky in luminance units (1e-4 per cd/m^2).

World space is right-handed with y up.  The lat-long mapping of an environment image is
``u = 0.5 + atan2(x, -z) / (2 pi)``, ``v = acos(y) / pi`` (top row = straight up,
``-z`` at the centre column), optionally turned about +y by ``rotation`` degrees.
"""

from __future__ import annotations

from typing import Callable

import numpy as np

__all__ = [
    "Light",
    "PointLight",
    "SpotLight",
    "DirectionalLight",
    "ConstantEnvironment",
    "LatLongEnvironment",
    "AreaLight",
    "LightSet",
    "INFINITE_DISTANCE",
]

#: distance reported for lights at infinity (directional, environment); finite so that
#: shadow-ray arithmetic stays defined (Embree's own "no hit" is 1e37).
INFINITE_DISTANCE = 1.0e30


def _rgb(value, name: str) -> np.ndarray:
    a = np.asarray(value, dtype=np.float64)
    if a.ndim == 0:
        a = np.full(3, float(a))
    if a.shape != (3,) or not np.all(np.isfinite(a)) or np.any(a < 0):
        raise ValueError(f"{name} must be a non-negative number or [r, g, b], got {value!r}")
    return a


def _vec3(value, name: str) -> np.ndarray:
    a = np.asarray(value, dtype=np.float64)
    if a.shape != (3,) or not np.all(np.isfinite(a)):
        raise ValueError(f"{name} must be three finite numbers [x, y, z], got {value!r}")
    return a


def _unit3(value, name: str) -> np.ndarray:
    a = _vec3(value, name)
    n = float(np.linalg.norm(a))
    if n <= 0.0:
        raise ValueError(f"{name} must not be the zero vector")
    return a / n


class Light:
    """Base class: a light the integrator can sample for next-event estimation."""

    #: True for point, spot and directional lights.
    delta: bool = False
    #: True for environments (hit by rays that miss every object).
    infinite: bool = False

    def prepare(self, center: np.ndarray, radius: float) -> None:
        """Called once with the scene's bounding sphere (lights at infinity need it)."""


class PointLight(Light):
    """An isotropic point light of radiant ``intensity`` (W/sr, RGB) at ``position``."""

    delta = True

    def __init__(self, position, intensity=1.0):
        self.position = _vec3(position, "point light position")
        self.intensity = _rgb(intensity, "point light intensity")


class SpotLight(PointLight):
    """A point light restricted to a cone around ``direction`` (pbrt's smooth falloff).

    Parameters
    ----------
    position, direction : (3,)
        Apex and axis (the direction the light shines toward).
    intensity : float or (3,)
        Radiant intensity on the axis (W/sr).
    cutoff_angle : float
        Half-angle of the cone, degrees, in (0, 180]; nothing outside.
    beam_width : float
        Half-angle (degrees, <= ``cutoff_angle``) inside which the intensity is full;
        between the two it falls off smoothly (``smoothstep`` of the cosine).
    """

    def __init__(
        self,
        position,
        direction,
        intensity=1.0,
        cutoff_angle: float = 20.0,
        beam_width: float | None = None,
    ):
        super().__init__(position, intensity)
        self.direction = _unit3(direction, "spot light direction")
        cutoff = float(cutoff_angle)
        width = cutoff * 0.75 if beam_width is None else float(beam_width)
        if not (0.0 < cutoff <= 180.0) or not (0.0 <= width <= cutoff):
            raise ValueError(
                f"spot light needs 0 < cutoff_angle <= 180 and 0 <= beam_width <= "
                f"cutoff_angle (degrees), got {cutoff_angle!r}, {beam_width!r}"
            )
        self.cos_cutoff = float(np.cos(np.radians(cutoff)))
        self.cos_width = float(np.cos(np.radians(width)))


class DirectionalLight(Light):
    """Parallel light travelling along ``direction``, of ``irradiance`` E (W/m^2, RGB).
    """

    delta = True
    infinite = False

    def __init__(self, direction, irradiance=1.0):
        self.direction = _unit3(direction, "directional light direction")
        self.irradiance = _rgb(irradiance, "directional light irradiance")


class ConstantEnvironment(Light):
    """A uniform environment of ``radiance`` L in every direction (the white furnace).

    Sampled uniformly over the sphere (``pdf = 1 / (4 pi)``).
    """

    infinite = True

    def __init__(self, radiance=1.0):
        self.radiance = _rgb(radiance, "environment radiance")


class LatLongEnvironment(Light):
    """An environment map in latitude-longitude layout, importance-sampled by luminance.

    Parameters
    ----------
    image : (h, w, 3) float
        Linear RGB radiance, e.g. from an EXR (``(h, w)`` or ``(h, w, 1)``: grey; a 4th
        channel is ignored); negative and non-finite texels are set to 0.
    scale : float
        Multiplies the radiance.
    rotation : float
        Degrees about +y.

    Notes
    -----
    Radiance is piecewise constant per texel (nearest lookup), so the sampling density
    (texel probability ∝ luminance * sin(theta), spread uniformly in (phi, theta)) and
    the radiance agree exactly: ``pdf = p_texel * h * w / (2 pi^2 sin theta)``.
    """

    infinite = True

    def __init__(self, image, scale: float = 1.0, rotation: float = 0.0):
        img = np.asarray(image, dtype=np.float64)
        if img.ndim == 2:
            img = img[:, :, None]
        if img.ndim == 3 and img.shape[2] in (1, 2):
            img = np.repeat(img[:, :, :1], 3, axis=2)  # grey (or grey + alpha)
        if img.ndim != 3 or img.shape[2] < 3 or img.shape[0] < 1 or img.shape[1] < 1:
            raise ValueError(f"environment image must be (h, w, 3), got shape {img.shape}")
        img = img[:, :, :3]
        img = np.where(np.isfinite(img) & (img > 0), img, 0.0) * float(scale)
        self.image = img
        self.h, self.w = img.shape[:2]
        self.rotation = np.radians(float(rotation))
        rows = (np.arange(self.h) + 0.5) / self.h
        sin_t = np.sin(np.pi * rows)
        lum = img @ np.array([0.212671, 0.715160, 0.072169])
        weight = lum * sin_t[:, None]
        total = weight.sum()
        if total <= 0.0:
            weight = np.broadcast_to(sin_t[:, None], (self.h, self.w)).copy()
            total = weight.sum()
        self._p = (weight / total).ravel()
        self._cdf = np.cumsum(self._p)
        self._cdf[-1] = 1.0


#: an emissive object of many triangles is sampled as up to GROUPS lights of at least
#: GROUP_FACES triangles each (:meth:`AreaLight.groups`)
GROUPS, GROUP_FACES = 32, 16


class AreaLight(Light):
    """The emissive triangles of one object (or a group of them,
    :meth:`groups`), sampled uniformly by area.

    Parameters
    ----------
    object_id : int
        The emitting object (its Embree geometry id).
    faces : (m,) int64
        Global triangle indices of the object.
    corners : (m, 3, 3) float64
        World positions of each triangle's vertices.
    normals : (m, 3) float64
        Unit geometric normals of the triangles (oriented like the shading normals).
    emission : callable
        ``emission(faces (n,), bary (n, 3), wo_world (n, 3)) -> (n, 3)``: radiance the
        material emits from those points toward ``wo_world`` (0 from the back).

    Notes
    -----
    The solid-angle density of a point ``x`` seen from ``p`` is
    ``d^2 / (A |cos theta_x|)`` with ``A`` the triangles' total area; the integrator uses
    :attr:`pdf_area` (= ``1/A``) to weigh BSDF-sampled hits on the light (MIS).
    """

    def __init__(
        self,
        object_id: int,
        faces: np.ndarray,
        corners: np.ndarray,
        normals: np.ndarray,
        emission: Callable,
    ):
        self.object_id = int(object_id)
        self.faces = np.asarray(faces, dtype=np.int64)
        self.corners = np.asarray(corners, dtype=np.float64)
        self.normals = np.asarray(normals, dtype=np.float64)
        self.emission = emission
        area = 0.5 * np.linalg.norm(
            np.cross(
                self.corners[:, 1] - self.corners[:, 0], self.corners[:, 2] - self.corners[:, 0]
            ),
            axis=1,
        )
        self.area = float(area.sum())
        if not self.area > 0.0:
            raise ValueError(f"emissive object {object_id} has zero area")
        self.pdf_area = 1.0 / self.area
        self._cdf = np.cumsum(area) / self.area
        self._cdf[-1] = 1.0
        self._tri_area = area

    def groups(self, most: int = GROUPS, least_faces: int = GROUP_FACES) -> list[AreaLight]:
        """The object's triangles as up to ``most`` lights of at least ``least_faces``
        triangles each, split where they are farthest apart in position or orientation,
        so that next-event estimation picks the part of an emitter that faces the point
        and is near it (as the leaves of pbrt-v4's and Cycles' light trees do).

        A group is split in two at the median of the coordinate of its triangles'
        centroids (over the object's bounding diagonal) or normals (half-weighted) that
        spreads most; the largest group is split first.  An object of fewer than
        ``2 * least_faces`` triangles stays one light."""
        m = len(self.faces)
        if m < 2 * least_faces or most < 2:
            return [self]
        centroid = self.corners.mean(axis=1)
        diag = float(np.linalg.norm(centroid.max(axis=0) - centroid.min(axis=0))) or 1.0
        key = np.hstack([centroid / diag, 0.5 * self.normals])
        parts = [np.arange(m)]
        while len(parts) < most:
            parts.sort(key=len)
            big = parts[-1]
            if len(big) < 2 * least_faces:
                break
            axis = int(np.argmax(np.ptp(key[big], axis=0)))
            order = big[np.argsort(key[big, axis], kind="stable")]
            half = len(order) // 2
            parts[-1:] = [np.sort(order[:half]), np.sort(order[half:])]
        return [AreaLight(self.object_id, self.faces[p], self.corners[p], self.normals[p],
                          self.emission) for p in parts if self._tri_area[p].sum() > 0.0]


class LightSet:
    """All the lights of a scene (next-event estimation picks among them with
    :func:`render.light_sampling.select_light`).

    Parameters
    ----------
    lights : list of Light
        At most one environment (:attr:`Light.infinite`).

    Attributes
    ----------
    environment : Light or None
        The environment seen by rays that leave the scene.
    select_pdf : float
        ``1 / len(lights)`` (0 without lights): a light's probability under
        ``light_selection = "uniform"``.
    """

    def __init__(self, lights: list[Light]):
        self.lights = list(lights)
        envs = [light for light in self.lights if light.infinite]
        if len(envs) > 1:
            raise ValueError("a scene can have at most one environment light")
        self.environment = envs[0] if envs else None
        self.select_pdf = 1.0 / len(self.lights) if self.lights else 0.0

    def __len__(self) -> int:
        return len(self.lights)
