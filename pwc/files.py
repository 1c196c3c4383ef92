"""Where the workbench's commands find profiles by name and how they treat output paths.

Profiles are found by name (``ornament_2``, or ``myprof`` for ``myprof.pwc``) on a
search path, first match wins:

1. the folders the caller puts first (a scene's own folder, or the current folder on
   the command line);
2. ``--profiles DIR`` options, in order;
3. ``$PWC_PROFILE_PATH``: folders separated by ``os.pathsep`` (``:`` on Linux);
4. the bundled library: ``pwc/profiles`` in an installed package, ``profiles/`` in a
   source checkout.

Every command writes its outputs by one rule (:func:`prepare_output`): missing parent
folders are created, and a path that cannot be written is reported in one line *before*
any long work starts.
"""

from __future__ import annotations

import difflib
import errno
import os
from collections.abc import Iterable
from pathlib import Path

__all__ = [
    "PROFILE_PATH_ENV",
    "OutputError",
    "ProfileNotFound",
    "bundled_profiles",
    "profile_path",
    "resolve_profile",
    "prepare_output",
]

#: environment variable of extra profile folders (``os.pathsep``-separated)
PROFILE_PATH_ENV = "PWC_PROFILE_PATH"

_PACKAGE = Path(__file__).resolve().parent


def bundled_profiles() -> Path:
    """The bundled profile library: package data when installed, else the checkout's
    ``profiles/``."""
    installed = _PACKAGE / "profiles"
    return installed if installed.is_dir() else _PACKAGE.parent / "profiles"


def profile_path(first: Iterable[str | os.PathLike] = (),
                 extra: Iterable[str | os.PathLike] = ()) -> tuple[Path, ...]:
    """The folders searched for ``NAME.pwc``, in order (duplicates dropped).

    Parameters
    ----------
    first : paths
        Searched before everything (a scene's folder; the current folder).
    extra : paths
        ``--profiles`` folders, searched before ``$PWC_PROFILE_PATH``.

    Examples
    --------
    >>> profile_path(["a"], ["b"])[:2]
    (PosixPath('a'), PosixPath('b'))
    >>> profile_path()[-1] == bundled_profiles()
    True
    """
    env = [d for d in os.environ.get(PROFILE_PATH_ENV, "").split(os.pathsep) if d]
    out: list[Path] = []
    for d in (*first, *extra, *env, bundled_profiles()):
        p = Path(d)
        if p not in out:
            out.append(p)
    return tuple(out)


class ProfileNotFound(FileNotFoundError):
    """A profile given by file or name that is on no search folder; the message says
    where it looked and suggests a close name."""


def _looks_like_name(arg: str) -> bool:
    return bool(arg) and not any(c in arg for c in "/\\\0") and arg not in (".", "..")


def resolve_profile(arg: str | os.PathLike, first: Iterable[str | os.PathLike] = (".",),
                    extra: Iterable[str | os.PathLike] = ()) -> Path:
    """The ``.pwc`` file a command-line argument means: an existing file as given, else a
    profile name (``ornament_2`` or ``ornament_2.pwc``) found on :func:`profile_path`.

    Raises
    ------
    ProfileNotFound
        Neither; the message lists the folders searched and a close name.

    Examples
    --------
    >>> resolve_profile("ornament_2").name
    'ornament_2.pwc'
    >>> resolve_profile("ornament2")
    Traceback (most recent call last):
    ...
    pwc.files.ProfileNotFound: ornament2: no such file, ... (did you mean 'ornament_2'?)
    """
    text = os.fspath(arg)
    given = Path(text)
    if given.is_file():
        return given
    if given.is_dir():
        raise IsADirectoryError(f"{text}: is a directory; give a .pwc file (e.g. {text}/*.pwc)")
    dirs = profile_path(first, extra)
    name = text[:-4] if text.endswith(".pwc") else text
    if _looks_like_name(name):
        for d in dirs:
            if (d / f"{name}.pwc").is_file():
                return d / f"{name}.pwc"
    names = sorted({p.stem for d in dirs if d.is_dir() for p in d.glob("*.pwc")})
    close = difflib.get_close_matches(Path(name).name, names, 1)
    hint = f" (did you mean {close[0]!r}?)" if close else ""
    raise ProfileNotFound(
        f"{text}: no such file, and no profile {Path(name).name!r} in "
        f"{', '.join(str(d) for d in dirs)}{hint}")


class OutputError(OSError):
    """An output path that cannot be written, with a one-line reason."""


def prepare_output(path: str | os.PathLike, what: str = "output") -> Path:
    """Make ``path`` ready to write: create its missing parent folders, and check that the
    file can be created there (an existing file is left as it is).

    Call it before any long work, so a bad path fails at once.

    Raises
    ------
    OutputError
        With what is wrong: a parent that is a file, a read-only or missing location,
        a directory in the file's place.

    Examples
    --------
    >>> import tempfile, pathlib
    >>> d = pathlib.Path(tempfile.mkdtemp())
    >>> prepare_output(d / "new" / "x.stl").parent.is_dir()
    True
    >>> (d / "f").write_text("")
    0
    >>> prepare_output(d / "f" / "x.stl")  # doctest: +ELLIPSIS
    Traceback (most recent call last):
    ...
    pwc.files.OutputError: cannot write output .../f/x.stl: .../f is a file, not a folder
    """
    p = Path(path)
    label = f"cannot write {what} {p}"
    for parent in reversed((p.parent, *p.parent.parents)):
        if parent.exists() and not parent.is_dir():
            raise OutputError(f"{label}: {parent} is a file, not a folder")
    if p.is_dir():
        raise OutputError(f"{label}: it is a folder; give a file name")
    try:
        p.parent.mkdir(parents=True, exist_ok=True)
    except OSError as e:
        raise OutputError(f"{label}: cannot create folder {p.parent}: {_why(e)}") from None
    existed = p.exists()
    try:
        with open(p, "ab"):
            pass
    except OSError as e:
        raise OutputError(f"{label}: {_why(e)}") from None
    if not existed:
        p.unlink(missing_ok=True)
    return p


def _why(e: OSError) -> str:
    """The reason an OS error gives, said for an output (ENOENT after the parents exist
    means a location that takes no new files, such as /proc)."""
    if e.errno == errno.ENOENT:
        return "this location does not accept new files (choose another folder)"
    if e.errno in (errno.EACCES, errno.EPERM, errno.EROFS):
        return f"{e.strerror.lower()} (choose a folder you can write to)"
    return e.strerror or str(e)
