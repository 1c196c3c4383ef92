"""Where materials find their profiles (``profiles/*.pwc``) and textures (``gallery/textures``).

Materials that name a resource (``texture_2d("weave_depth.png")``,
``ornament_2::ornament_2``) look it up here.  Profiles are searched as everywhere in the
workbench (:mod:`pwc.files`): the folders given first (a scene's own folder, then
``--profiles`` folders), ``$PWC_PROFILE_PATH``, then the bundled library; textures in
the folder given (the scene's) and then the bundled ``gallery/textures``.  The bundled
folders are package data in an installed package (``render/gallery/...``) and the
checkout's folders in a source tree.  :func:`search_paths` changes the first folders
for a block of code (the expression parser does so with its ``profile_dirs`` and
``base_dir`` arguments).  Loaded curves and textures are cached by path and
modification time, so a material built many times loads each file once (MDL's
``uniform`` values: computed once per render, not per ray).
"""

from __future__ import annotations

import dataclasses
import difflib
import os
from collections.abc import Iterator, Sequence
from contextlib import contextmanager
from contextvars import ContextVar
from pathlib import Path

import numpy as np

from displacement.textures import Texture, read_texture

__all__ = [
    "ResourceError",
    "ROOT",
    "DEFAULT_TEXTURE_DIRS",
    "bundled_scenes",
    "bundled_references",
    "bundled_textures",
    "search_paths",
    "profile_dirs",
    "texture_dirs",
    "find_profile",
    "load_profile",
    "profile_names",
    "find_texture",
    "load_texture",
    "load_measurement",
    "load_light_profile",
    "INVALID_TEXTURE",
    "CURVE_MODES",
    "evaluation",
    "track_loads",
    "with_filter",
]

ROOT = Path(__file__).resolve().parents[2]  # the checkout, or site-packages when installed
_PACKAGE = Path(__file__).resolve().parents[1]


def _bundled(*parts: str) -> Path:
    installed = _PACKAGE.joinpath("gallery", *parts)
    return installed if installed.is_dir() else ROOT.joinpath("gallery", *parts)


def bundled_textures() -> Path:
    """The textures made for the gallery's figures (package data when installed)."""
    return _bundled("textures")


def bundled_scenes() -> Path:
    """The gallery's scene files (package data when installed)."""
    return _bundled("scenes")


def bundled_references() -> Path:
    """The gallery's reference images and thresholds (package data when installed)."""
    return _bundled("reference")


DEFAULT_TEXTURE_DIRS: tuple[Path, ...] = (bundled_textures(),)

#: MDL's ``texture_2d()``: an invalid texture; every lookup returns 0 (MDL spec).
INVALID_TEXTURE = Texture(np.zeros((1, 1, 3)), name="texture_2d()")

class ResourceError(ValueError):
    """A profile or texture that cannot be found or read; ``hint`` suggests a fix."""

    def __init__(self, message: str, hint: str | None = None):
        self.message = message
        self.hint = hint
        super().__init__(message + (f" ({hint})" if hint else ""))


_Dirs = tuple[Path, ...]
_PROFILE_DIRS: ContextVar[_Dirs] = ContextVar("profile_dirs", default=())
_TEXTURE_DIRS: ContextVar[_Dirs] = ContextVar("texture_dirs", default=DEFAULT_TEXTURE_DIRS)
_CURVES: dict = {}
_TEXTURES: dict = {}
#: how loaded profiles are evaluated, and loaded textures filtered (a scene's ``[render]``
#: ``curves``, ``curve_tolerance`` and ``texture_filter``; :func:`evaluation`)
_CURVE_MODE: ContextVar[tuple[str, float]] = ContextVar("curve_mode", default=("exact", 0.0))
#: where :func:`track_loads` collects the profiles and textures loaded in its block
_LOADED: ContextVar[dict | None] = ContextVar("loaded", default=None)
_TEXTURE_FILTER: ContextVar[str] = ContextVar("texture_filter", default="bilinear")
#: the ways a profile may be evaluated (``[render] curves``), most accurate first
CURVE_MODES = ("exact", "float32", "polyline")


def _as_dirs(dirs: Sequence[str | os.PathLike] | str | os.PathLike) -> tuple[Path, ...]:
    if isinstance(dirs, str | os.PathLike):
        dirs = [dirs]
    return tuple(Path(d) for d in dirs)


@contextmanager
def search_paths(profile_dirs=None, texture_dirs=None) -> Iterator[None]:
    """Search ``profile_dirs`` / ``texture_dirs`` first (then ``$PWC_PROFILE_PATH`` and the
    bundled folders) inside the block.

    Parameters
    ----------
    profile_dirs, texture_dirs : path or sequence of paths, optional
    """
    tokens = []
    if profile_dirs is not None:
        dirs = _as_dirs(profile_dirs)
        tokens.append((_PROFILE_DIRS, _PROFILE_DIRS.set(dirs)))
    if texture_dirs is not None:
        dirs = _as_dirs(texture_dirs) + DEFAULT_TEXTURE_DIRS
        tokens.append((_TEXTURE_DIRS, _TEXTURE_DIRS.set(dirs)))
    try:
        yield
    finally:
        for var, token in reversed(tokens):
            var.reset(token)


@contextmanager
def evaluation(curves: str = "exact", curve_tolerance: float = 1e-4,
               texture_filter: str = "bilinear") -> Iterator[None]:
    """Inside the block, profiles load as ``curves`` says and textures with
    ``texture_filter`` (materials are built, and these resources loaded, when a scene is
    read; the render then uses what was loaded).

    Parameters
    ----------
    curves : {"exact", "float32", "polyline"}
        Exact arcs in float64 (the default); the same in float32 (MDL's ``float``); or
        the polyline within ``curve_tolerance`` of the curve (:meth:`pwc.Curve.as_polyline`).
    curve_tolerance : float
        Of ``"polyline"``, in the curve's normalized units.
    texture_filter : {"bilinear", "nearest"}
    """
    from displacement.textures import FILTERS

    if curves not in CURVE_MODES:
        raise ValueError(f"curves must be one of {', '.join(CURVE_MODES)}, got {curves!r}")
    if not (isinstance(curve_tolerance, int | float) and curve_tolerance > 0):
        raise ValueError(f"curve_tolerance must be a number > 0, got {curve_tolerance!r}")
    if texture_filter not in FILTERS:
        raise ValueError(f"texture_filter must be one of {', '.join(FILTERS)}, got "
                         f"{texture_filter!r}")
    t1 = _CURVE_MODE.set((curves, float(curve_tolerance)))
    t2 = _TEXTURE_FILTER.set(texture_filter)
    try:
        yield
    finally:
        _TEXTURE_FILTER.reset(t2)
        _CURVE_MODE.reset(t1)


@contextmanager
def track_loads() -> Iterator[dict]:
    """Collect the names of the profiles and textures loaded inside the block:
    ``{"profiles": set, "textures": set}`` (what a scene's materials use)."""
    loaded: dict = {"profiles": set(), "textures": set()}
    token = _LOADED.set(loaded)
    try:
        yield loaded
    finally:
        _LOADED.reset(token)


def _note(kind: str, name: str) -> None:
    loaded = _LOADED.get()
    if loaded is not None:
        loaded[kind].add(name)


def profile_dirs() -> tuple[Path, ...]:
    """The directories searched for ``NAME.pwc`` now: those set by :func:`search_paths`,
    then ``$PWC_PROFILE_PATH``, then the bundled library (:func:`pwc.files.profile_path`)."""
    from pwc.files import profile_path

    return profile_path(_PROFILE_DIRS.get())


def texture_dirs() -> tuple[Path, ...]:
    """The directories searched for texture files now."""
    return _TEXTURE_DIRS.get()


def profile_names() -> list[str]:
    """Stems of every ``.pwc`` file on the profile search path, sorted."""
    names = set()
    for d in profile_dirs():
        if d.is_dir():
            names.update(p.stem for p in d.glob("*.pwc"))
    return sorted(names)


def find_profile(name: str) -> Path | None:
    """The first ``NAME.pwc`` on the profile search path, or None."""
    if not name or any(c in name for c in "/\\\0") or name in (".", ".."):
        return None
    for d in profile_dirs():
        path = d / f"{name}.pwc"
        if path.is_file():
            return path
    return None


def load_profile(name: str):
    """The compiled curve ``NAME.pwc``, the first on :func:`profile_dirs` (cached).

    Raises
    ------
    ResourceError
        No such profile (with a suggestion); ``pwc.PwcError`` if it does not compile.
    """
    import pwc

    path = find_profile(name)
    if path is None:
        hint = difflib.get_close_matches(name, profile_names(), 1)
        raise ResourceError(
            f"no profile {name!r}: there is no {name}.pwc in "
            f"{', '.join(str(d) for d in profile_dirs())}",
            f"did you mean {hint[0]!r}?" if hint else None,
        )
    _note("profiles", name)
    mode, tolerance = _CURVE_MODE.get()
    key = (path.resolve(), path.stat().st_mtime_ns)
    if key not in _CURVES:
        _CURVES[key] = pwc.load(path)
    if mode == "exact":
        return _CURVES[key]
    variant = (*key, mode, tolerance if mode == "polyline" else 0.0)
    if variant not in _CURVES:
        curve = _CURVES[key]
        _CURVES[variant] = curve.in_float32() if mode == "float32" else curve.as_polyline(
            tolerance)
    return _CURVES[variant]


def find_texture(file: str, base_dir=None) -> Path | None:
    """``file`` as given if absolute, else the first match in ``base_dir`` (a folder, or a
    sequence of folders searched in order) and the texture search path; None if not
    found."""
    if not file or "\0" in file:
        return None
    candidate = Path(file)
    if candidate.is_absolute():
        return candidate if candidate.is_file() else None
    for d in _searched(base_dir):
        path = d / candidate
        if path.is_file():
            return path
    return None


def _searched(base_dir) -> tuple[Path, ...]:
    """The folders a resource is looked for in: ``base_dir`` (one or several, None
    skipped), then the texture search path; each once, in that order."""
    bases = () if base_dir is None else tuple(
        d for d in ([base_dir] if isinstance(base_dir, str | os.PathLike) else base_dir)
        if d is not None)
    return tuple(dict.fromkeys(_as_dirs(bases) + texture_dirs()))


def load_texture(file: str, gamma: str = "linear", base_dir=None) -> Texture:
    """Read a texture file found by :func:`find_texture` (cached).

    Parameters
    ----------
    file : str
    gamma : {"linear", "srgb", "default"}
        As :func:`displacement.textures.read_texture`.
    base_dir : path or sequence of paths, optional
        Searched first.

    Raises
    ------
    ResourceError
        Not found (with suggestions of files of the same stem) or unreadable.
    """
    path = find_texture(file, base_dir)
    if path is None:
        dirs = _searched(base_dir)
        stem = Path(file).stem
        same_stem = sorted({p.name for d in dirs if d.is_dir() for p in d.glob(f"{stem}.*")})
        names = sorted({p.name for d in dirs if d.is_dir() for p in d.iterdir() if p.is_file()})
        hint = (difflib.get_close_matches(Path(file).name, same_stem, 1) or same_stem
                or difflib.get_close_matches(Path(file).name, names, 1))
        raise ResourceError(
            f"texture {file!r} not found in {', '.join(str(d) for d in dirs)}",
            f"did you mean {hint[0]!r}?" if hint else None,
        )
    _note("textures", file)
    key = (path.resolve(), path.stat().st_mtime_ns, gamma)
    if key not in _TEXTURES:
        try:
            _TEXTURES[key] = read_texture(path, gamma=gamma)
        except (OSError, ValueError) as e:
            raise ResourceError(f"cannot read texture {str(path)!r}: {e}") from None
    return with_filter(_TEXTURES[key])


def load_measurement(file: str, base_dir=None):
    """Read the MBSDF file of ``bsdf_measurement("file.mbsdf")`` (cached), found as
    textures are (:func:`find_texture`: absolute as given, else ``base_dir`` -- the module's
    or the scene's folder -- then the texture search path).

    Returns
    -------
    render.df.Measurement

    Raises
    ------
    ResourceError
        Not found (with the folders searched and a close name), or malformed (the file's
        path and what is wrong, from :func:`render.df.read_mbsdf`).
    """
    from render.df._mbsdf import MbsdfError, read_mbsdf

    path = find_texture(file, base_dir)
    if path is None:
        dirs = _searched(base_dir)
        names = sorted({p.name for d in dirs if d.is_dir() for p in d.glob("*.mbsdf")})
        hint = difflib.get_close_matches(Path(file).name, names, 1)
        raise ResourceError(
            f"bsdf_measurement: no file {file!r} in {', '.join(str(d) for d in dirs)}",
            f"did you mean {hint[0]!r}?" if hint else
            "give the MBSDF file's path, relative to the scene file or the module")
    key = (path.resolve(), path.stat().st_mtime_ns, "mbsdf")
    if key not in _TEXTURES:
        try:
            _TEXTURES[key] = read_mbsdf(path)
        except MbsdfError as e:
            raise ResourceError(str(e), "give an MBSDF file (the MDL spec, Appendix B)") \
                from None
    return _TEXTURES[key]


def load_light_profile(file: str, base_dir=None):
    """Read the IES LM-63 file of ``light_profile("file.ies")`` (cached), found as textures
    and measurements are (:func:`find_texture`: absolute as given, else ``base_dir`` -- the
    module's or the scene's folder -- then the texture search path).

    Returns
    -------
    render.df.LightProfile

    Raises
    ------
    ResourceError
        Not found (with the folders searched and a close name), or malformed (the file's
        path, line and what is wrong, from :func:`render.df.read_ies`).
    """
    from render.df._ies import IesError, read_ies

    path = find_texture(file, base_dir)
    if path is None:
        dirs = _searched(base_dir)
        names = sorted({p.name for d in dirs if d.is_dir() for p in d.iterdir()
                        if p.is_file() and p.suffix.lower() == ".ies"})
        hint = difflib.get_close_matches(Path(file).name, names, 1)
        raise ResourceError(
            f"light_profile: no file {file!r} in {', '.join(str(d) for d in dirs)}",
            f"did you mean {hint[0]!r}?" if hint else
            "give the IES file's path, relative to the scene file or the module")
    key = (path.resolve(), path.stat().st_mtime_ns, "ies")
    if key not in _TEXTURES:
        try:
            _TEXTURES[key] = read_ies(path)
        except IesError as e:
            raise ResourceError(str(e)) from None
    return _TEXTURES[key]


def with_filter(texture: Texture) -> Texture:
    """``texture`` filtered as the current :func:`evaluation` block says (cached)."""
    wanted = _TEXTURE_FILTER.get()
    if texture.filter == wanted:
        return texture
    key = (id(texture), wanted)
    if key not in _TEXTURES or _TEXTURES[key][0] is not texture:
        _TEXTURES[key] = (texture, dataclasses.replace(texture, filter=wanted))
    return _TEXTURES[key][1]
