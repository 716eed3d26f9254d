"""NCC-CVMS steps 4–5, stage ``intersections``: the segments where triangles of other planes cut each plane.

Candidate pairs come from a bounding-box sweep (:mod:`cspace.geometry.boxes`); each pair on
different planes is classified exactly with symbolic endpoints
(:func:`cspace.geometry.tritri.intersect_pairs`, :func:`cspace.geometry.endpoints.endpoint_coordinates`).
Very large builds fork (``_PARALLEL_OVERLAPS``).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..geometry.boxes import BoxSweep
from ..geometry.endpoints import endpoint_coordinates
from ..errors import UnsupportedError
from ..geometry.tritri import POINT, SEGMENT, TriTriResult, intersect_pairs
from ..workers import can_fork, forked_map
from .planes import _Planes


@dataclass
class _Cuts:
    """Exact pieces where triangles of different planes meet (steps 4–5).

    ``segments[p]``: list of ``(X4, Y4)`` homogeneous 3D endpoints (equal for points) of the
    intersections lying on plane ``p``.
    """

    segments: list
    n_pairs: int
    n_cut: int
    processes: int = 1


def _cut_pieces(ints: np.ndarray, faces: np.ndarray, pairs: np.ndarray) -> tuple[np.ndarray, list]:
    """The pairs that meet in a segment or a point, and the exact homogeneous endpoints
    ``(X4, Y4)`` of each meeting."""
    res = intersect_pairs(ints, faces, pairs)
    hit = (res.cls == SEGMENT) | (res.cls == POINT)
    if not hit.any():
        return pairs[:0], []
    sub = TriTriResult(
        pairs=res.pairs[hit], cls=res.cls[hit], kind=res.kind[hit], u=res.u[hit],
        v=res.v[hit], plane=res.plane[hit],
    )
    ex, _ = endpoint_coordinates(ints, faces, sub)
    return sub.pairs, ex.tolist()


# From this many one-axis box overlaps on (the sweep's work; some 10-50 per candidate pair),
# the pairs are found and intersected in several processes. Compiled, the stage takes about
# 6 ns per overlap: serial is faster on every benchmark case (torus(25600) + ico320, 20M
# overlaps: 119 ms serial, 154 ms in two processes, whose fork and results cost more than
# the work they share), so only much larger builds fork.
_PARALLEL_OVERLAPS = 100_000_000


# Serially, the sweep's work is expanded in shares of at most this many one-axis overlaps
# (each share's candidate pairs, at most that many, are intersected before the next is made),
# so that memory follows the share, not the whole: every benchmark sum is one share.
_SHARE_OVERLAPS = 50_000_000


def _cuts(ints: np.ndarray, planes: _Planes, workers: int = 1,
          max_pairs: int | None = None) -> _Cuts:
    """The cuts; with ``max_pairs``, :class:`~cspace.errors.UnsupportedError` as soon as the
    candidate pairs (boxes meeting, on different planes) are more (before the rest is made)."""
    corners = ints[planes.faces]
    sweep = BoxSweep(corners.min(axis=1), corners.max(axis=1))

    def share(k: int, n: int) -> tuple[int, np.ndarray, list]:
        pairs = sweep.pairs(k, n)
        pairs = pairs[planes.plane[pairs[:, 0]] != planes.plane[pairs[:, 1]]]
        return (len(pairs), *_cut_pieces(ints, planes.faces, pairs))

    if workers > 1 and sweep.overlaps >= _PARALLEL_OVERLAPS and can_fork() and not max_pairs:
        n = 2 * workers
        pieces = [r for _, r in forked_map(lambda k: share(k, n), list(range(n)), workers)]
        processes = workers
    else:
        n = max(1, -(-sweep.overlaps // _SHARE_OVERLAPS))
        pieces, processes, found = [], 1, 0
        for k in range(n):
            pieces.append(share(k, n))
            found += pieces[-1][0]
            if max_pairs is not None and found > max_pairs:
                raise UnsupportedError(f"more than {max_pairs:,} candidate triangle pairs "
                                       f"({sweep.overlaps:,} box overlaps)")
    segments: list = [[] for _ in planes.keys]
    n_pairs = n_cut = 0
    for count, hit_pairs, ex in pieces:
        n_pairs += count
        n_cut += len(ex)
        pl = planes.plane[hit_pairs]
        for (pa, pb), (x, y) in zip(pl.tolist(), ex):
            segments[pa].append((x, y))
            segments[pb].append((x, y))
    for seg in segments:  # one order whatever process found which pair
        seg.sort()
    return _Cuts(segments, n_pairs, n_cut, processes)
