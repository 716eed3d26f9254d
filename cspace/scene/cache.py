"""Disk cache of C-obstacles, keyed by a content hash of their exact inputs.

A C-obstacle depends only on the snapped obstacle (grid integers and faces), the snapped
robot and reference point, the grid, the algorithm (``kind``) and the cspace version; the
key is the SHA-256 of exactly those (:func:`co_key`). An entry stores the exact arrays the
query engines are built from (polytope CSR arrays in grid integers, or a mesh's float64
vertices and faces), so a loaded C-obstacle answers every query exactly as the fresh one.

Location: the ``directory`` argument, else ``$CSPACE_CACHE``, else ``~/.cache/cspace``.
Entries are ``<dir>/<key[:2]>/<key>.npz``, written to a temporary file in the same folder
and renamed (atomic on POSIX), with a digest of the payload; a file that does not load,
belongs to another key or fails its digest is deleted and reported as a miss (rebuilt).
"""

from __future__ import annotations

import hashlib
import os
import tempfile
import zipfile
from pathlib import Path

import numpy as np

from ..mesh.convex import ConvexPolytope
from ..geometry.exact import Grid

__all__ = ["COCache", "cache_dir", "co_key", "FORMAT"]

# Bump when the stored layout or an algorithm's output changes.
FORMAT = 4  # 3: C-obstacles grown by their margin (cspace.cobstacle.margin), stored with it;
# 4: grids centred on the scene (Grid.origin)


def cache_dir(directory=None) -> Path:
    """The cache folder: ``directory``, else ``$CSPACE_CACHE``, else ``~/.cache/cspace``."""
    if directory is not None:
        return Path(directory).expanduser()
    env = os.environ.get("CSPACE_CACHE")
    if env:
        return Path(env).expanduser()
    return Path.home() / ".cache" / "cspace"


def co_key(kind: str, grid: Grid, obstacle_ints, obstacle_faces, robot_ints,
           reference_ints) -> str:
    """SHA-256 hex key of a C-obstacle's exact inputs.

    Parameters
    ----------
    kind : str
        The algorithm ('convex', 'solid', 'surface').
    grid : Grid
        The obstacle's grid (its step, bits and origin name the frame of the integers).
    obstacle_ints : (n, 3) int64
        Snapped obstacle vertices (grid units); ``obstacle_faces`` (m, 3) int64 or None.
    robot_ints : (r, 3) int64
        Snapped robot vertices (its own frame); ``reference_ints`` (3,) int64.
    """
    from .._version import __version__

    h = hashlib.sha256()
    h.update(f"cspace {__version__} format {FORMAT} kind {kind} grid {grid.exponent} "
             f"{grid.bits} origin {list(grid.origin)}".encode())
    for name, a in (("obstacle", obstacle_ints), ("faces", obstacle_faces),
                    ("robot", robot_ints), ("reference", reference_ints)):
        a = np.zeros((0, 3), np.int64) if a is None else np.ascontiguousarray(a, dtype=np.int64)
        h.update(f"|{name} {a.shape}|".encode())
        h.update(a.tobytes())
    return h.hexdigest()


def _digest(arrays: dict) -> str:
    h = hashlib.sha256()
    for name in sorted(arrays):
        a = np.ascontiguousarray(arrays[name])
        h.update(f"{name} {a.dtype.str} {a.shape}".encode())
        h.update(a.tobytes())
    return h.hexdigest()


def pack_polytopes(polys, prefix: str) -> dict:
    """Concatenated CSR arrays of a list of convex polytopes (one grid)."""
    fields = ("ints", "facet_offsets", "facet_indices", "normals", "edges", "edge_facets")
    out = {}
    for f in fields:
        parts = [getattr(p, f) for p in polys]
        out[f"{prefix}{f}"] = np.concatenate(parts) if parts else np.zeros((0,), np.int64)
        out[f"{prefix}{f}_n"] = np.array([len(a) for a in parts], dtype=np.int64)
    return out


def unpack_polytopes(arrays: dict, prefix: str, grid: Grid) -> list[ConvexPolytope]:
    """Inverse of :func:`pack_polytopes`."""
    fields = ("ints", "facet_offsets", "facet_indices", "normals", "edges", "edge_facets")
    split = {}
    for f in fields:
        cuts = np.cumsum(arrays[f"{prefix}{f}_n"])[:-1]
        split[f] = np.split(arrays[f"{prefix}{f}"], cuts)
    n = len(arrays[f"{prefix}ints_n"])
    return [ConvexPolytope(grid=grid, **{f: np.ascontiguousarray(split[f][i]) for f in fields})
            for i in range(n)]


class COCache:
    """A folder of cached C-obstacles (see the module docstring).

    Parameters
    ----------
    directory : path, optional
        Default :func:`cache_dir`.

    Attributes
    ----------
    hits, misses, rebuilt : int
        Counters (``rebuilt``: corrupt entries found and deleted).
    """

    def __init__(self, directory=None):
        self.directory = cache_dir(directory)
        self.hits = self.misses = self.rebuilt = 0

    def path(self, key: str) -> Path:
        return self.directory / key[:2] / f"{key}.npz"

    def load(self, key: str) -> dict | None:
        """The stored arrays of ``key``, or None (missing, or corrupt: then deleted)."""
        p = self.path(key)
        if not p.is_file():
            self.misses += 1
            return None
        try:
            with np.load(p, allow_pickle=False) as z:
                arrays = {k: z[k] for k in z.files}
            meta = {k: str(arrays.pop(k)) for k in ("_key", "_digest", "_format")}
            ok = (meta["_key"] == key and meta["_format"] == str(FORMAT)
                  and meta["_digest"] == _digest(arrays))
        except (OSError, ValueError, KeyError, EOFError, zipfile.BadZipFile):
            ok = False
        if not ok:
            p.unlink(missing_ok=True)
            self.rebuilt += 1
            self.misses += 1
            return None
        self.hits += 1
        return arrays

    def store(self, key: str, arrays: dict) -> Path:
        """Write ``arrays`` under ``key`` atomically (temporary file, then rename)."""
        p = self.path(key)
        p.parent.mkdir(parents=True, exist_ok=True)
        payload = dict(arrays)
        payload["_key"] = np.array(key)
        payload["_digest"] = np.array(_digest(arrays))
        payload["_format"] = np.array(str(FORMAT))
        fd, tmp = tempfile.mkstemp(dir=p.parent, prefix=f".{key[:8]}-", suffix=".tmp")
        try:
            with os.fdopen(fd, "wb") as f:
                np.savez(f, **payload)
                f.flush()
                os.fsync(f.fileno())
            os.replace(tmp, p)
        except BaseException:
            Path(tmp).unlink(missing_ok=True)
            raise
        return p
