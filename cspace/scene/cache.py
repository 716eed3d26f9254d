"""Disk cache of C-obstacles, keyed by a content hash of their exact inputs.

A C-obstacle depends only on the snapped obstacle (grid integers and faces), the snapped
robot and reference point, the grid, the algorithm (``kind``) and the cspace version; the
key is the SHA-256 of exactly those (:func:`co_key`). An entry stores the exact arrays the
query engines are built from (polytope CSR arrays in grid integers, or a mesh's float64
vertices and faces), so a loaded C-obstacle answers every query exactly as the fresh one.

Location: the ``directory`` argument, else ``$CSPACE_CACHE``, else ``~/.cache/cspace``.

Layout: append-only **packs**, ``<dir>/packs/<name>.cspack``, one per build (or per
``PACK_BYTES`` of entries). A build's entries are held in memory (readable at once) and
written together by :meth:`COCache.flush`: one file, written to a temporary name in the same
folder, synced once and renamed (atomic on POSIX), so a pack is whole or absent, never half
written. A pack is its entries' raw array bytes, then an index (JSON: per key its arrays'
names, dtypes, shapes and offsets, and a SHA-256 digest of the arrays), then the index's
length and a magic number. Packs are content-addressed by key, written by any number of
processes side by side (each its own files); where two packs hold a key, the newer one
answers. An entry that fails its digest is dropped and reported as a miss (rebuilt, into a
new pack); a pack whose index does not read is deleted. Entries of the older layout, one
``<dir>/<key[:2]>/<key>.npz`` each, are still read.
"""

from __future__ import annotations

import functools
import hashlib
import json
import mmap
import os
import struct
import tempfile
import threading
import weakref
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


_POLYTOPE = (("ints", 3), ("facet_offsets", 0), ("facet_indices", 0), ("normals", 3),
             ("edges", 2), ("edge_facets", 2))  # field, columns (0: a vector)


def pack_polytope(poly: ConvexPolytope) -> np.ndarray:
    """A convex polytope as one int64 array: its six fields' lengths, then each field's
    values in row-major order (one array to read and digest, not twelve)."""
    parts = [np.ascontiguousarray(getattr(poly, f), dtype=np.int64) for f, _ in _POLYTOPE]
    head = np.array([len(a) for a in parts], dtype=np.int64)
    return np.concatenate([head] + [a.reshape(-1) for a in parts])


def unpack_polytope(packed: np.ndarray, grid: Grid, name: str = "polytope") -> ConvexPolytope:
    """Inverse of :func:`pack_polytope` (views of ``packed``, no copies)."""
    fields, at = {}, len(_POLYTOPE)
    for (field, cols), n in zip(_POLYTOPE, packed[:len(_POLYTOPE)].tolist()):
        size = n * max(cols, 1)
        values = packed[at:at + size]
        fields[field] = values.reshape(n, cols) if cols else values
        at += size
    if at != len(packed):
        raise ValueError(f"a packed polytope of {len(packed)} values holds {at}")
    return ConvexPolytope(grid=grid, name=name, **fields)


#: Pending entries beyond this many bytes are written out as a pack before the build ends.
PACK_BYTES = 64 * 2**20

_MAGIC = b"CSPACK01"
_TRAILER = struct.Struct("<Q8s")  # the index's length, the magic number


class COCache:
    """A folder of cached C-obstacles (see the module docstring).

    Parameters
    ----------
    directory : path, optional
        Default :func:`cache_dir`.

    Attributes
    ----------
    hits, misses, rebuilt : int
        Counters (``rebuilt``: corrupt entries found and dropped, and unreadable packs
        deleted).

    Notes
    -----
    :meth:`store` keeps an entry in memory; :meth:`flush` writes what is kept as one pack.
    ``model_scene`` flushes at the end of each build; what is still kept when the cache is
    garbage collected or the interpreter exits is flushed then.
    """

    def __init__(self, directory=None):
        self.directory = cache_dir(directory)
        self.hits = self.misses = self.rebuilt = 0
        self._lock = threading.RLock()
        self._pending: dict = {}            # key -> arrays, not yet written
        self._pending_bytes = [0]
        self._index: dict = {}              # key -> (pack path, entry record)
        self._packs: dict = {}              # pack path -> its mtime when read
        self._maps: dict = {}               # pack path -> its bytes, mapped when first read
        self._stamp = None                  # the packs folder's mtime when last scanned
        # what is kept is written when this cache goes away (or at exit)
        self._finalizer = weakref.finalize(self, _write_at_exit, self._packs_dir(),
                                           self._pending, self._pending_bytes)

    @classmethod
    def of(cls, cache) -> "COCache | None":
        """The cache a ``cache=`` argument names: a COCache as it is; True: the default
        folder; a path: that folder; None or False: no cache (None). Open one per build and
        pass it on, so that its packs' indexes are read once."""
        if isinstance(cache, cls):
            return cache
        if cache is None or cache is False:
            return None
        return cls(None if cache is True else cache)

    def __repr__(self) -> str:
        return (f"COCache({str(self.directory)!r}, hits={self.hits}, misses={self.misses}, "
                f"pending={len(self._pending)})")

    def _packs_dir(self) -> Path:
        return self.directory / "packs"

    @property
    def location(self) -> Path:
        """Where entries are written: the packs folder (entries of the older layout are read
        from ``<dir>/<key[:2]>/<key>.npz``)."""
        return self._packs_dir()

    # ---------------------------------------------------------------- reading

    def load(self, key: str, *, count: bool = True) -> dict | None:
        """The stored arrays of ``key``, or None (missing, or corrupt: then dropped).
        ``count=False``: not counted in ``hits`` and ``misses`` (which count C-obstacles)."""
        with self._lock:
            arrays = self._pending.get(key)
            if arrays is None:
                arrays = self._from_packs(key)
            if arrays is None:
                arrays = self._from_npz(key)
            if count:
                if arrays is None:
                    self.misses += 1
                else:
                    self.hits += 1
            return arrays

    def keys(self) -> set:
        """Every key this cache holds: in packs, kept in memory, or in the older layout."""
        with self._lock:
            self._scan()
            old = {p.stem for p in self.directory.glob("??/*.npz")}
            return set(self._index) | set(self._pending) | old

    def _scan(self) -> None:
        """Read the index of every pack not read yet (the folder's mtime says when to look)."""
        folder = self._packs_dir()
        try:
            stamp = folder.stat().st_mtime_ns
        except OSError:
            return
        if stamp == self._stamp:
            return
        self._stamp = stamp
        new = []
        for p in folder.glob("*.cspack"):
            if p not in self._packs:
                try:
                    new.append((p.stat().st_mtime_ns, p.name, p))
                except OSError:
                    continue
        for mtime, _, p in sorted(new):  # the newer pack answers a key both hold
            index = _read_index(p)
            if index is None:
                p.unlink(missing_ok=True)
                self.rebuilt += 1
                continue
            self._packs[p] = mtime
            for key, record in index.items():
                self._index[key] = (p, record)

    def _from_packs(self, key: str) -> dict | None:
        if key not in self._index:
            self._scan()
        found = self._index.get(key)
        if found is None:
            return None
        p, record = found
        if p not in self._maps:
            self._maps[p] = _map(p)
        arrays = _read_entry(self._maps[p], record)
        if arrays is None or _digest(arrays) != record[0]:
            del self._index[key]
            self.rebuilt += 1
            return None
        return arrays

    def _from_npz(self, key: str) -> dict | None:
        """An entry of the older layout, one ``.npz`` per key (deleted when corrupt)."""
        p = self.directory / key[:2] / f"{key}.npz"
        if not p.is_file():
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
            return None
        return arrays

    # ---------------------------------------------------------------- writing

    def store(self, key: str, arrays: dict) -> None:
        """Keep ``arrays`` under ``key`` (readable at once); written by :meth:`flush`, or
        now when what is kept exceeds ``PACK_BYTES``."""
        with self._lock:
            if key in self._pending:
                return
            self._pending[key] = dict(arrays)
            self._pending_bytes[0] += sum(np.asarray(a).nbytes for a in arrays.values())
            if self._pending_bytes[0] > PACK_BYTES:
                self.flush()

    def flush(self) -> Path | None:
        """Write the kept entries as one pack (atomically, synced once); its path, or None
        when nothing was kept. An unwritable folder raises ``OSError``; the entries are then
        dropped (a cache that cannot be written is not retried at exit)."""
        with self._lock:
            try:
                p = _write_pack(self._packs_dir(), self._pending, self._pending_bytes)
            except OSError:
                self._pending.clear()
                self._pending_bytes[0] = 0
                raise
            if p is not None:
                self._scan()
            return p


def _write_pack(folder: Path, pending: dict, size: list) -> Path | None:
    """Write ``pending`` (key -> arrays) as one pack in ``folder`` and empty it."""
    if not pending:
        return None
    folder.mkdir(parents=True, exist_ok=True)
    fd, tmp = tempfile.mkstemp(dir=folder, prefix=".pack-", suffix=".tmp")
    try:
        index, at = {}, 0
        with os.fdopen(fd, "wb") as f:
            for key, arrays in pending.items():
                entry = []
                for name in sorted(arrays):
                    a = np.asarray(arrays[name])  # 0-d stays 0-d; tobytes is C order
                    if a.dtype.hasobject or "\t" in name or "\n" in name:
                        raise TypeError(f"cache entry {key}: array {name!r} holds objects "
                                        "or its name a tab or a newline")
                    data = a.tobytes()
                    f.write(data)
                    f.write(b"\0" * (-len(data) % 8))  # 8-byte aligned
                    shape = ",".join(map(str, a.shape))
                    entry.append(f"{name}\t{a.dtype.str}\t{shape}\t{at}\t{len(data)}")
                    at += len(data) + (-len(data) % 8)
                # one string per entry: the index of a pack of thousands parses in
                # milliseconds, each entry's spans only when it is read
                index[key] = [_digest(arrays), "\n".join(entry)]
            head = json.dumps({"format": FORMAT, "entries": index}).encode()
            f.write(head)
            f.write(_TRAILER.pack(len(head), _MAGIC))
            f.flush()
            os.fsync(f.fileno())
        final = folder / f"{Path(tmp).stem.lstrip('.')}.cspack"
        os.replace(tmp, final)
    except BaseException:
        Path(tmp).unlink(missing_ok=True)
        raise
    pending.clear()
    size[0] = 0
    return final


def _write_at_exit(folder: Path, pending: dict, size: list) -> None:
    """:func:`_write_pack` when the cache goes away: a folder that cannot be written only
    warns (the entries are lost, never half written)."""
    try:
        _write_pack(folder, pending, size)
    except OSError as exc:
        import warnings

        warnings.warn(f"C-obstacle cache: cannot write {len(pending)} entries to {folder}: "
                      f"{exc}", UserWarning, stacklevel=2)


def _read_index(p: Path) -> dict | None:
    """A pack's index (key -> record), or None when the pack does not read as one."""
    try:
        with open(p, "rb") as f:
            f.seek(0, os.SEEK_END)
            end = f.tell()
            if end < _TRAILER.size:
                return None
            f.seek(end - _TRAILER.size)
            n, magic = _TRAILER.unpack(f.read(_TRAILER.size))
            if magic != _MAGIC or n > end - _TRAILER.size:
                return None
            f.seek(end - _TRAILER.size - n)
            head = json.loads(f.read(n))
        if head.get("format") != FORMAT:
            return {}  # another layout's pack: nothing of it is ours to read
        body = end - _TRAILER.size - n
        entries = head["entries"]
        for record in entries.values():
            if not (isinstance(record, list) and len(record) == 2):
                return None
        return {key: (digest, spans, body) for key, (digest, spans) in entries.items()}
    except (OSError, ValueError, KeyError, TypeError, struct.error):
        return None


@functools.lru_cache(maxsize=64)
def _dtype(text: str) -> np.dtype:
    return np.dtype(text)


def _map(p: Path):
    """The pack's bytes, mapped copy-on-write (arrays read from it are writable; nothing is
    written back), or None when it does not open. Packs are never changed once written."""
    try:
        with open(p, "rb") as f:
            return mmap.mmap(f.fileno(), 0, access=mmap.ACCESS_COPY)
    except (OSError, ValueError):
        return None


def _read_entry(buf, record: tuple) -> dict | None:
    """One entry's arrays from its pack's mapped bytes (None when the record does not
    read)."""
    _, text, body = record
    if buf is None:
        return None
    out = {}
    try:
        for item in text.split("\n") if text else ():
            name, dtype, shape, at, size = item.split("\t")
            dt, at, size = _dtype(dtype), int(at), int(size)
            if at < 0 or at + size > body or at + size > len(buf):
                return None
            count = size // dt.itemsize if dt.itemsize else 0
            out[name] = np.frombuffer(buf, dtype=dt, count=count, offset=at).reshape(
                tuple(int(d) for d in shape.split(",") if d))
    except (TypeError, ValueError):
        return None
    return out
