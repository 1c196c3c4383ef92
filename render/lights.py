"""Light sources: point, spot, directional, area (emissive geometry) and environments.

Every light answers :meth:`Light.sample_li`: for receiving points ``p`` it picks a
direction ``wi`` toward the light and returns the radiance arriving along it with the
solid-angle density of that choice (:class:`LightSample`).  Delta lights (point, spot,
directional) return ``pdf = 1`` and ``delta = True``: the integrator gives them full
weight (no multiple importance sampling), and BSDF-sampled rays never hit them.

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

from dataclasses import dataclass
from typing import Callable

import numpy as np

from render.numerics import dot, norm, safe_sqrt, unitize
from render.warp import square_to_uniform_sphere

__all__ = [
    "LightSample",
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


@dataclass(frozen=True, slots=True)
class LightSample:
    """A direction toward a light, per receiving point.

    Parameters
    ----------
    wi : (n, 3) float64
        Unit world direction from the receiver toward the light.
    distance : (n,) float64
        Distance to the sampled light point (:data:`INFINITE_DISTANCE` at infinity).
    radiance : (n, 3) float64
        Radiance arriving along ``-wi`` (not divided by the pdf); 0 where the sample
        failed.
    pdf : (n,) float64
        Solid-angle density of ``wi`` (1 for delta lights); 0 where the sample failed.
    delta : bool
        Whether the light is a delta light (no MIS; BSDF sampling cannot find it).
    """

    wi: np.ndarray
    distance: np.ndarray
    radiance: np.ndarray
    pdf: np.ndarray
    delta: bool


class Light:
    """Base class: a light the integrator can sample for next-event estimation."""

    #: True for point, spot and directional lights.
    delta: bool = False
    #: True for environments (hit by rays that miss every object).
    infinite: bool = False

    def sample_li(self, p: np.ndarray, u: np.ndarray) -> LightSample:  # pragma: no cover
        """Sample a direction toward the light from points ``p`` (n, 3), ``u`` (n, 2)."""
        raise NotImplementedError

    def prepare(self, center: np.ndarray, radius: float) -> None:
        """Called once with the scene's bounding sphere (lights at infinity need it)."""


class PointLight(Light):
    """An isotropic point light of radiant ``intensity`` (W/sr, RGB) at ``position``.

    Examples
    --------
    >>> s = PointLight([0, 2, 0], 4.0).sample_li(np.zeros((1, 3)), np.zeros((1, 2)))
    >>> s.wi.tolist(), s.distance.tolist(), s.radiance.tolist()
    ([[0.0, 1.0, 0.0]], [2.0], [[1.0, 1.0, 1.0]])
    """

    delta = True

    def __init__(self, position, intensity=1.0):
        self.position = _vec3(position, "point light position")
        self.intensity = _rgb(intensity, "point light intensity")

    def _towards(self, p: np.ndarray):
        d = self.position - p
        dist = np.linalg.norm(d, axis=1)
        wi, ok = unitize(d)
        ok &= dist > 0.0
        inv_d2 = np.where(ok, 1.0 / np.where(ok, dist * dist, 1.0), 0.0)
        return wi, dist, inv_d2, ok

    def sample_li(self, p, u):
        wi, dist, inv_d2, ok = self._towards(p)
        li = inv_d2[:, None] * self.intensity
        return LightSample(wi, dist, li, ok.astype(np.float64), True)


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

    Examples
    --------
    >>> spot = SpotLight([0, 1, 0], [0, -1, 0], 1.0, cutoff_angle=30, beam_width=20)
    >>> s = spot.sample_li(np.array([[0.0, 0.0, 0.0], [1.0, 0.0, 0.0]]), np.zeros((2, 2)))
    >>> s.radiance[:, 0].tolist()
    [1.0, 0.0]
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

    def falloff(self, cos_theta: np.ndarray) -> np.ndarray:
        """Smoothstep from 0 at the cutoff to 1 inside the beam, of ``cos_theta`` (n,)."""
        span = self.cos_width - self.cos_cutoff
        if span <= 0.0:
            return (cos_theta >= self.cos_cutoff).astype(np.float64)
        t = np.clip((cos_theta - self.cos_cutoff) / span, 0.0, 1.0)
        return t * t * (3.0 - 2.0 * t)

    def sample_li(self, p, u):
        wi, dist, inv_d2, ok = self._towards(p)
        f = self.falloff(dot(-wi, np.broadcast_to(self.direction, wi.shape)))
        li = (inv_d2 * f)[:, None] * self.intensity
        return LightSample(wi, dist, li, ok.astype(np.float64), True)


class DirectionalLight(Light):
    """Parallel light travelling along ``direction``, of ``irradiance`` E (W/m^2, RGB).

    Examples
    --------
    >>> s = DirectionalLight([0, -1, 0], 2.0).sample_li(np.zeros((1, 3)), np.zeros((1, 2)))
    >>> s.wi.tolist(), s.radiance.tolist()
    ([[-0.0, 1.0, -0.0]], [[2.0, 2.0, 2.0]])
    """

    delta = True
    infinite = False

    def __init__(self, direction, irradiance=1.0):
        self.direction = _unit3(direction, "directional light direction")
        self.irradiance = _rgb(irradiance, "directional light irradiance")

    def sample_li(self, p, u):
        n = len(p)
        wi = np.broadcast_to(-self.direction, (n, 3)).copy()
        return LightSample(
            wi,
            np.full(n, INFINITE_DISTANCE),
            np.broadcast_to(self.irradiance, (n, 3)).copy(),
            np.ones(n),
            True,
        )


class ConstantEnvironment(Light):
    """A uniform environment of ``radiance`` L in every direction (the white furnace).

    Sampled uniformly over the sphere (``pdf = 1 / (4 pi)``).

    Examples
    --------
    >>> env = ConstantEnvironment(1.0)
    >>> env.eval(np.array([[0.0, 1.0, 0.0]])).tolist()
    [[1.0, 1.0, 1.0]]
    >>> round(float(env.pdf(np.zeros((1, 3)))[0] * 4 * np.pi), 12)
    1.0
    """

    infinite = True

    def __init__(self, radiance=1.0):
        self.radiance = _rgb(radiance, "environment radiance")

    def eval(self, d: np.ndarray) -> np.ndarray:
        """Radiance (n, 3) seen along directions ``d`` (n, 3)."""
        return np.broadcast_to(self.radiance, (len(d), 3)).copy()

    def pdf(self, d: np.ndarray) -> np.ndarray:
        """Solid-angle density (n,) with which :meth:`sample_li` picks ``d``."""
        return np.full(len(d), 0.25 / np.pi)

    def sample_li(self, p, u):
        n = len(p)
        wi = square_to_uniform_sphere(u)
        return LightSample(wi, np.full(n, INFINITE_DISTANCE), self.eval(wi), self.pdf(wi), False)


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

    Examples
    --------
    >>> img = np.zeros((4, 8, 3)); img[0] = 1.0          # only the top row (sky) is bright
    >>> env = LatLongEnvironment(img)
    >>> s = env.sample_li(np.zeros((100, 3)), np.random.default_rng(0).random((100, 2)))
    >>> bool(np.all(s.wi[:, 1] > np.cos(np.pi / 4) - 1e-12)), bool(np.all(s.radiance == 1.0))
    (True, True)
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

    def _uv(self, d: np.ndarray):
        c, s = np.cos(self.rotation), np.sin(self.rotation)
        x = c * d[:, 0] - s * d[:, 2]
        z = s * d[:, 0] + c * d[:, 2]
        u = 0.5 + np.arctan2(x, -z) / (2.0 * np.pi)
        v = np.arccos(np.clip(d[:, 1], -1.0, 1.0)) / np.pi
        i = np.clip((u * self.w).astype(np.int64), 0, self.w - 1)
        j = np.clip((v * self.h).astype(np.int64), 0, self.h - 1)
        return i, j, v

    def eval(self, d: np.ndarray) -> np.ndarray:
        """Radiance (n, 3) seen along directions ``d`` (n, 3)."""
        i, j, _ = self._uv(d)
        return self.image[j, i]

    def pdf(self, d: np.ndarray) -> np.ndarray:
        """Solid-angle density (n,) with which :meth:`sample_li` picks ``d``."""
        i, j, v = self._uv(d)
        sin_t = np.sin(np.pi * v)
        ok = sin_t > 1e-12
        return np.where(
            ok,
            self._p[j * self.w + i]
            * self.h
            * self.w
            / (2.0 * np.pi * np.pi * np.where(ok, sin_t, 1.0)),
            0.0,
        )

    def sample_li(self, p, u):
        n = len(p)
        # pick a texel by the CDF, reuse u[:, 0]'s remainder inside it
        k = np.clip(np.searchsorted(self._cdf, u[:, 0], side="right"), 0, len(self._p) - 1)
        lo = np.where(k > 0, self._cdf[np.maximum(k - 1, 0)], 0.0)
        pk = self._p[k]
        du = np.clip(np.where(pk > 0, (u[:, 0] - lo) / np.where(pk > 0, pk, 1.0), 0.5), 0.0, 1.0)
        j, i = np.divmod(k, self.w)
        uu = (i + du) / self.w
        vv = (j + u[:, 1]) / self.h
        phi = (uu - 0.5) * 2.0 * np.pi
        theta = vv * np.pi
        st = np.sin(theta)
        x, z = st * np.sin(phi), -st * np.cos(phi)
        c, s = np.cos(self.rotation), np.sin(self.rotation)
        wi = np.stack([c * x + s * z, np.cos(theta), -s * x + c * z], axis=1)
        pdf = self.pdf(wi)
        li = np.where((pdf > 0)[:, None], self.eval(wi), 0.0)
        return LightSample(wi, np.full(n, INFINITE_DISTANCE), li, pdf, False)


class AreaLight(Light):
    """The emissive triangles of one object, sampled uniformly by area.

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
    ``d^2 / (A |cos theta_x|)`` with ``A`` the object's total area; the integrator uses
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

    def sample_points(self, u: np.ndarray):
        """Points uniformly distributed over the object's area.

        Parameters
        ----------
        u : (n, 2) float64

        Returns
        -------
        index : (n,) int64
            Row in :attr:`faces` of the chosen triangle.
        bary : (n, 3) float64
        position : (n, 3) float64
        """
        k = np.clip(np.searchsorted(self._cdf, u[:, 0], side="right"), 0, len(self.faces) - 1)
        lo = np.where(k > 0, self._cdf[np.maximum(k - 1, 0)], 0.0)
        width = self._cdf[k] - lo
        u0 = np.clip(
            np.where(width > 0, (u[:, 0] - lo) / np.where(width > 0, width, 1.0), 0.5), 0.0, 1.0
        )
        # uniform triangle sampling (Heitz's low-distortion variant is not needed here)
        su = safe_sqrt(u0)
        b1 = 1.0 - su
        b2 = u[:, 1] * su
        bary = np.stack([1.0 - b1 - b2, b1, b2], axis=1)
        c = self.corners[k]  # summed in einsum's order, without its overhead
        pos = bary[:, 0:1] * c[:, 0] + bary[:, 1:2] * c[:, 1] + bary[:, 2:3] * c[:, 2]
        return k, bary, pos

    def sample_li(self, p, u):
        k, bary, x = self.sample_points(u)
        d = x - p
        dist = norm(d)
        wi, ok = unitize(d)
        nrm = self.normals[k]
        cos_l = np.abs(dot(wi, nrm))
        ok &= (dist > 0.0) & (cos_l > 1e-12)
        pdf = np.where(ok, dist * dist / np.where(ok, cos_l, 1.0) * self.pdf_area, 0.0)
        li = self.emission(self.faces[k], bary, -wi)
        li = np.where(ok[:, None], li, 0.0)
        return LightSample(wi, dist, li, pdf, False)


class LightSet:
    """All the lights of a scene, one picked uniformly per next-event estimate.

    Parameters
    ----------
    lights : list of Light
        At most one environment (:attr:`Light.infinite`).

    Attributes
    ----------
    environment : Light or None
        The environment seen by rays that leave the scene.
    area_by_object : dict[int, AreaLight]
    select_pdf : float
        ``1 / len(lights)`` (0 without lights).
    """

    def __init__(self, lights: list[Light]):
        self.lights = list(lights)
        envs = [light for light in self.lights if light.infinite]
        if len(envs) > 1:
            raise ValueError("a scene can have at most one environment light")
        self.environment = envs[0] if envs else None
        self.area_by_object = {
            light.object_id: light for light in self.lights if isinstance(light, AreaLight)
        }
        self.select_pdf = 1.0 / len(self.lights) if self.lights else 0.0

    def __len__(self) -> int:
        return len(self.lights)

    def sample_li(self, p: np.ndarray, u_select: np.ndarray, u: np.ndarray):
        """One light sample per point: a uniformly chosen light, sampled.

        Parameters
        ----------
        p : (n, 3) float64
        u_select : (n,) float64
        u : (n, 2) float64

        Returns
        -------
        wi, distance, radiance, pdf : arrays as in :class:`LightSample`; ``pdf`` already
            includes the selection probability; for delta lights it is the selection
            probability alone.
        delta : (n,) bool
        """
        n = len(p)
        wi = np.zeros((n, 3))
        dist = np.zeros(n)
        li = np.zeros((n, 3))
        pdf = np.zeros(n)
        delta = np.zeros(n, dtype=bool)
        if not self.lights:
            return wi, dist, li, pdf, delta
        k = np.minimum((u_select * len(self.lights)).astype(np.int64), len(self.lights) - 1)
        for j, light in enumerate(self.lights):
            sel = np.flatnonzero(k == j)
            if len(sel) == 0:
                continue
            s = light.sample_li(p[sel], u[sel])
            wi[sel] = s.wi
            dist[sel] = s.distance
            li[sel] = s.radiance
            pdf[sel] = s.pdf * self.select_pdf
            delta[sel] = s.delta
        return wi, dist, li, pdf, delta
