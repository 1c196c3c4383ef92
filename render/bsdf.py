"""Interfaces of the material model: the Bsdf and Edf base classes, sample records, lobe flags.

No physics here.  Every distribution function in :mod:`render.df` (and, later, every mix,
layer and modifier) is a :class:`Bsdf` or an :class:`Edf`, so tests and the integrator
never special-case one.  Directions and conventions: see :mod:`render.frame`.

Parameters that MDL declares varying (``tint``, ``roughness_u``, ``tangent_u``...) are
constants or per-lane arrays: a scalar, ``(n,)`` for floats, ``(3,)`` or ``(n, 3)`` for
colors and vectors.  They broadcast against the ``n`` lanes of each call
(:func:`lane_float`, :func:`lane_color`, :func:`lane_vector`).
"""

from __future__ import annotations

from abc import ABC, abstractmethod
from dataclasses import dataclass
from enum import IntFlag

import numpy as np

from render._typing import Arr, Arr2, ArrayLike, Rgb, Vec3
from render.numerics import check_finite

__all__ = [
    "Lobe",
    "BsdfSample",
    "EdfSample",
    "Bsdf",
    "Edf",
    "lane_float",
    "lane_color",
    "lane_vector",
    "lanes",
    "check_dirs",
    "check_samples",
]


class Lobe(IntFlag):
    """Kinds of scattering events (libbsdf's event types); combine with ``|``.

    A :class:`BsdfSample` stores one flag per lane (``0`` = the sample failed); a df's
    ``lobes`` attribute is the union of the flags it can produce.

    Examples
    --------
    >>> bool(Lobe.GLOSSY_REFLECTION & Lobe.REFLECTION), bool(Lobe.SPECULAR & Lobe.DIFFUSE)
    (True, False)
    """

    NONE = 0
    DIFFUSE_REFLECTION = 1
    DIFFUSE_TRANSMISSION = 2
    GLOSSY_REFLECTION = 4
    GLOSSY_TRANSMISSION = 8
    SPECULAR_REFLECTION = 16
    SPECULAR_TRANSMISSION = 32

    DIFFUSE = DIFFUSE_REFLECTION | DIFFUSE_TRANSMISSION
    GLOSSY = GLOSSY_REFLECTION | GLOSSY_TRANSMISSION
    SPECULAR = SPECULAR_REFLECTION | SPECULAR_TRANSMISSION
    REFLECTION = DIFFUSE_REFLECTION | GLOSSY_REFLECTION | SPECULAR_REFLECTION
    TRANSMISSION = DIFFUSE_TRANSMISSION | GLOSSY_TRANSMISSION | SPECULAR_TRANSMISSION
    ALL = REFLECTION | TRANSMISSION


@dataclass(frozen=True, slots=True)
class BsdfSample:
    """The result of :meth:`Bsdf.sample`, one row per lane.

    Parameters
    ----------
    wi : (n, 3) float64
        Sampled direction toward the light (local frame); zero rows where failed.
    pdf : (n,) float64
        Solid-angle density of ``wi``; for a specular (delta) event, the discrete
        probability of the chosen event instead (e.g. Fresnel ``F`` for a dielectric
        reflection).  0 where the sample failed.
    weight : (n, 3) float64
        ``eval(wo, wi) / pdf`` (for delta events, the ratio of the delta's
        coefficients).  0 where the sample failed.
    lobe : (n,) int32
        :class:`Lobe` flag of the event, 0 where the sample failed.
    """

    wi: Vec3
    pdf: Arr
    weight: Rgb
    lobe: np.ndarray

    @property
    def valid(self) -> np.ndarray:
        """(n,) bool: lanes whose sample succeeded."""
        return self.lobe != 0

    @property
    def is_delta(self) -> np.ndarray:
        """(n,) bool: lanes that sampled a specular (delta) event."""
        return (self.lobe & int(Lobe.SPECULAR)) != 0

    @classmethod
    def failed(cls, n: int) -> BsdfSample:
        """``n`` failed samples (all zeros)."""
        return cls(np.zeros((n, 3)), np.zeros(n), np.zeros((n, 3)), np.zeros(n, np.int32))

    def checked(self) -> BsdfSample:
        """``self`` after strict-mode checks (finite, non-negative pdf and weight)."""
        check_finite("BsdfSample.wi", self.wi)
        check_finite("BsdfSample.pdf", self.pdf, nonnegative=True)
        check_finite("BsdfSample.weight", self.weight, nonnegative=True)
        return self


@dataclass(frozen=True, slots=True)
class EdfSample:
    """The result of :meth:`Edf.sample`, one row per lane.

    Parameters
    ----------
    wo : (n, 3) float64
        Emitted direction (toward the viewer, local frame); zero rows where failed.
    pdf : (n,) float64
        Solid-angle density of ``wo``; 0 where failed.
    weight : (n, 3) float64
        ``eval(wo) * |cos theta_o| / pdf``; 0 where failed.
    """

    wo: Vec3
    pdf: Arr
    weight: Rgb

    @property
    def valid(self) -> np.ndarray:
        """(n,) bool: lanes whose sample succeeded."""
        return self.pdf > 0


class Bsdf(ABC):
    """A bidirectional scattering distribution function over lanes (local frame).

    Subclasses set :attr:`lobes` and implement :meth:`eval`, :meth:`pdf`,
    :meth:`sample` and :meth:`albedo`.  Contract (checked by :mod:`render.testing`):

    * ``eval >= 0`` and ``pdf >= 0`` everywhere, finite, never NaN;
    * ``pdf(wo, wi) > 0`` exactly where ``eval(wo, wi) != 0`` (specular lobes: both 0);
    * ``sample`` draws ``wi`` with density ``pdf`` among its successful lanes and returns
      ``weight = eval / pdf`` there; it fails (lobe 0) where ``eval`` would be 0;
    * ``albedo(wo)`` is the directional albedo ``∫ eval(wo, wi) dwi`` (plus delta
      lobes), what the layerers and energy compensation need.
    """

    #: union of the :class:`Lobe` flags this df can produce.
    lobes: Lobe = Lobe.NONE

    @abstractmethod
    def eval(self, wo: Vec3, wi: Vec3) -> Rgb:
        """``f(wo, wi) * |cos theta_i|``.

        Parameters
        ----------
        wo, wi : (n, 3) float64
            Unit directions in the local frame.

        Returns
        -------
        (n, 3) float64
        """

    @abstractmethod
    def pdf(self, wo: Vec3, wi: Vec3) -> Arr:
        """Solid-angle density with which :meth:`sample` picks ``wi``.

        Parameters
        ----------
        wo, wi : (n, 3) float64

        Returns
        -------
        (n,) float64
        """

    @abstractmethod
    def sample(self, wo: Vec3, u1: Arr, u2: Arr2) -> BsdfSample:
        """Sample ``wi`` given ``wo``.

        Parameters
        ----------
        wo : (n, 3) float64
        u1 : (n,) float64
            Uniform in [0, 1): picks a lobe or component (Fresnel split, mixes).
        u2 : (n, 2) float64
            Uniform in [0, 1)^2: picks the direction within the lobe.

        Returns
        -------
        BsdfSample
        """

    @abstractmethod
    def albedo(self, wo: Vec3) -> Rgb:
        """Directional albedo ``∫ eval(wo, wi) dwi`` (including delta lobes).

        Parameters
        ----------
        wo : (n, 3) float64

        Returns
        -------
        (n, 3) float64
        """

    def eval_pdf(self, wo: Vec3, wi: Vec3) -> tuple[Rgb, Arr]:
        """``(eval(wo, wi), pdf(wo, wi))`` in one call (subclasses may share work)."""
        return self.eval(wo, wi), self.pdf(wo, wi)

    @property
    def is_delta(self) -> bool:
        """True if every lobe is specular (eval and pdf are identically 0)."""
        return self.lobes != Lobe.NONE and (self.lobes & ~Lobe.SPECULAR) == Lobe.NONE

    def __repr__(self) -> str:
        return f"{type(self).__name__}(lobes={self.lobes!r})"


class Edf(ABC):
    """An emission distribution function over lanes (local frame, emits toward ``+z``).

    ``eval(wo)`` is the emitted radiance per unit intensity in direction ``wo``,
    normalised so that ``∫ eval(wo) cos theta_o dwo = 1`` over the hemisphere (MDL's
    radiant-exitance convention: a diffuse_edf of intensity ``I`` has radiance ``I/pi``).
    Only the ``+z`` side emits: the integrator orients the frame toward the emitting
    face (MDL: ``surface.emission`` on the front face only, ``backface.emission`` on
    the back face of thin-walled materials).
    """

    @abstractmethod
    def eval(self, wo: Vec3) -> Rgb:
        """Emitted radiance per unit intensity toward ``wo``: (n, 3) -> (n, 3)."""

    @abstractmethod
    def pdf(self, wo: Vec3) -> Arr:
        """Solid-angle density with which :meth:`sample` emits toward ``wo``: (n,)."""

    @abstractmethod
    def sample(self, u1: Arr, u2: Arr2) -> EdfSample:
        """Sample an emission direction.

        ``u1`` (n,) picks a component (mixes), ``u2`` (n, 2) the direction.
        """

    def __repr__(self) -> str:
        return f"{type(self).__name__}()"


# --- argument handling shared by every df ---------------------------------------------


def check_dirs(*dirs: ArrayLike, names: tuple[str, ...] = ("wo", "wi")) -> tuple[np.ndarray, ...]:
    """Validate direction arrays: each ``(n, 3)`` float64 with the same ``n``.

    Raises
    ------
    ValueError
        Wrong shape or mismatched lane counts.

    Examples
    --------
    >>> check_dirs(np.zeros((2, 3)))[0].shape
    (2, 3)
    >>> check_dirs(np.zeros(3))
    Traceback (most recent call last):
    ...
    ValueError: wo must have shape (n, 3) (one unit direction per lane), got (3,)
    """
    out = []
    for a, name in zip(dirs, names, strict=False):
        a = np.asarray(a, dtype=np.float64)
        if a.ndim != 2 or a.shape[1] != 3:
            raise ValueError(
                f"{name} must have shape (n, 3) (one unit direction per lane), got {a.shape}"
            )
        if out and len(a) != len(out[0]):
            raise ValueError(f"{name} has {len(a)} lanes but {names[0]} has {len(out[0])}")
        out.append(a)
    return tuple(out)


def check_samples(n: int, u1: ArrayLike, u2: ArrayLike) -> tuple[Arr, Arr2]:
    """Validate random numbers: ``u1`` (n,) and ``u2`` (n, 2), clamped into [0, 1).

    Examples
    --------
    >>> check_samples(1, [0.5], [[0.1, 0.2]])[1].tolist()
    [[0.1, 0.2]]
    """
    from render.numerics import ONE_MINUS_EPS

    u1 = np.asarray(u1, dtype=np.float64)
    u2 = np.asarray(u2, dtype=np.float64)
    if u1.shape != (n,):
        raise ValueError(
            f"u1 must have shape ({n},) (one uniform variate per lane), got {u1.shape}"
        )
    if u2.shape != (n, 2):
        raise ValueError(
            f"u2 must have shape ({n}, 2) (two uniform variates per lane), got {u2.shape}"
        )
    return np.clip(u1, 0.0, ONE_MINUS_EPS), np.clip(u2, 0.0, ONE_MINUS_EPS)


def lane_float(x: ArrayLike, name: str) -> np.ndarray:
    """A float parameter: a scalar (0-d) or one value per lane ``(n,)``.

    Examples
    --------
    >>> lane_float(0.5, "roughness").shape
    ()
    >>> lane_float([[1.0]], "roughness")
    Traceback (most recent call last):
    ...
    ValueError: roughness must be a float or an (n,) array of per-lane values, got shape (1, 1)
    """
    a = np.asarray(x, dtype=np.float64)
    if a.ndim > 1:
        raise ValueError(
            f"{name} must be a float or an (n,) array of per-lane values, got shape {a.shape}"
        )
    if not np.all(np.isfinite(a)):
        raise ValueError(f"{name} must be finite, got {x!r}")
    return a


def lane_color(x: ArrayLike, name: str) -> np.ndarray:
    """A color parameter: a scalar (grey), ``(3,)`` RGB or ``(n, 3)`` per lane.

    Returns an array that broadcasts against ``(n, 3)``: shape ``(1, 3)`` or ``(n, 3)``.

    Examples
    --------
    >>> lane_color(0.5, "tint").tolist()
    [[0.5, 0.5, 0.5]]
    """
    a = np.asarray(x, dtype=np.float64)
    if a.ndim == 0:
        a = np.full((1, 3), float(a))
    elif a.shape == (3,):
        a = a[None, :]
    elif not (a.ndim == 2 and a.shape[1] == 3):
        raise ValueError(
            f"{name} must be a float, an RGB triple or an (n, 3) array, got shape {a.shape}"
        )
    if not np.all(np.isfinite(a)):
        raise ValueError(f"{name} must be finite")
    return a


def lane_vector(x: ArrayLike, name: str) -> np.ndarray:
    """A vector parameter: ``(3,)`` or ``(n, 3)``; returned as ``(1, 3)`` or ``(n, 3)``."""
    a = np.asarray(x, dtype=np.float64)
    if a.shape == (3,):
        a = a[None, :]
    elif not (a.ndim == 2 and a.shape[1] == 3):
        raise ValueError(f"{name} must be a 3-vector or an (n, 3) array, got shape {a.shape}")
    if not np.all(np.isfinite(a)):
        raise ValueError(f"{name} must be finite")
    return a


def lanes(param: np.ndarray, n: int, name: str) -> np.ndarray:
    """Check that a per-lane parameter matches ``n`` lanes (scalars always match)."""
    if param.ndim >= 1 and param.shape[0] not in (1, n):
        raise ValueError(f"{name} has {param.shape[0]} per-lane values but the call has {n} lanes")
    return param
