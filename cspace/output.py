"""Files cspace writes: checked before the work starts, written whole or not at all.

:func:`output_path` checks a path when a command starts (its format is known from the suffix,
it is not a folder, its nearest existing folder is writable), so hours of work never end in
"unknown format". :func:`write_atomic` writes to a temporary file beside the target and
renames it over the target, so an interruption, a full disk or an error leaves the old file
(or none), never half of a new one. Missing parent folders are created when the file is
written, the same rule for every command. A target that exists and is not a regular file
(``/dev/null``, ``/dev/full``) is written in place.
"""

from __future__ import annotations

import os
import tempfile
from collections.abc import Callable
from pathlib import Path

from .errors import OutputError

__all__ = ["MESH_FORMATS", "output_path", "write_atomic"]

#: Mesh formats trimesh exports, by suffix.
MESH_FORMATS = ("stl", "ply", "obj", "off", "glb", "gltf", "dae", "3mf")


def output_path(path, formats: tuple[str, ...], what: str = "output") -> Path:
    """Check an output path before any work.

    Parameters
    ----------
    path : str or os.PathLike
    formats : tuple of str
        Accepted suffixes, without the dot (lower case).
    what : str
        What the file is, for the message (an option name, e.g. ``'-o'``).

    Raises
    ------
    OutputError
        Unknown suffix, the path is a folder, or its nearest existing folder is not writable.
    """
    p = Path(os.fspath(path))
    suffix = p.suffix.lower().lstrip(".")
    if suffix not in formats:
        raise OutputError(f"{what} '{p}': unknown format {p.suffix or '(no suffix)'!r}: "
                          "expected " + ", ".join(f".{f}" for f in formats))
    if p.is_dir():
        raise OutputError(f"{what} '{p}' is a folder")
    if p.exists():
        if not os.access(p, os.W_OK):
            raise OutputError(f"{what} '{p}' is not writable")
        return p
    folder = p.parent
    while not folder.exists() and folder != folder.parent:
        folder = folder.parent
    if not folder.is_dir() or not os.access(folder, os.W_OK | os.X_OK):
        raise OutputError(f"{what} '{p}': cannot create files in '{folder}'")
    try:  # permissions do not tell everything (/proc, a read-only mount): try one
        fd, probe = tempfile.mkstemp(prefix=".cspace-check-", dir=folder)
        os.close(fd)
        os.unlink(probe)
    except OSError as exc:
        raise OutputError(f"{what} '{p}': cannot create files in '{folder}' "
                          f"({exc.strerror or exc})") from None
    return p


def write_atomic(path, write: Callable[[Path], None]) -> Path:
    """Write a file whole or not at all: ``write(tmp)`` then rename ``tmp`` to ``path``.

    The temporary file keeps the suffix (writers that choose the format from it work
    unchanged) and is removed on any failure or interruption; the file gets the mode a new
    file would (``0666`` less the umask), not the temporary file's ``0600``.

    Raises
    ------
    OutputError
        The file could not be written (the operating system's reason in the message).
    """
    p = Path(os.fspath(path))
    try:
        if p.exists() and not p.is_file():  # a device: no rename over it
            write(p)
            return p
        p.parent.mkdir(parents=True, exist_ok=True)
        fd, tmp = tempfile.mkstemp(prefix=f".{p.name}.", suffix=p.suffix, dir=p.parent)
        os.close(fd)
    except OSError as exc:
        raise OutputError(f"cannot write '{p}': {exc.strerror or exc}") from exc
    try:
        write(Path(tmp))
        # mkstemp makes the file 0600; a file written in place would get the user's umask
        os.chmod(tmp, 0o666 & ~_umask())
        os.replace(tmp, p)
    except BaseException as exc:
        try:
            os.unlink(tmp)
        except OSError:
            pass
        if isinstance(exc, OSError):
            raise OutputError(f"cannot write '{p}': {exc.strerror or exc}") from exc
        raise
    return p


def _umask() -> int:
    """The process's umask (read by setting it and putting it back)."""
    mask = os.umask(0o022)
    os.umask(mask)
    return mask
