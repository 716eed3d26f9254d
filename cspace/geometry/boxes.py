"""Candidate pairs by bounding boxes: the sweep every triangle-pair search starts from.

:class:`BoxSweep` sorts integer boxes along one axis once and reports overlapping pairs;
:func:`box_pairs` and :func:`candidate_pairs` wrap it for one set or two (compiled sweep,
pure-Python reference beside it). Only prunes: every decision is made afterwards, exactly.
"""

from __future__ import annotations

import numpy as np

from ._kernels import load
from .tritri import _check_soup

__all__ = ["candidate_pairs", "box_pairs", "BoxSweep", "BoxTree", "DOP_DIRECTIONS", "dop_bounds"]


# The box sweep, the pair classification and the endpoint coordinates run compiled
# (cspace.geometry._kernels.arrangement); their numpy references are BoxSweep._pairs_reference,
# _intersect_pairs_reference and _endpoint_coordinates_reference, which they match exactly.
_compiled = load("arrangement")
# BoxTree's build (cspace.geometry._kernels.boxtree); its reference is _tree_reference.
_boxtree = load("boxtree")


# Default bound on the number of expanded candidate pairs held at once (~8 int64 arrays).
_CHUNK = 1 << 21


# --------------------------------------------------------------------------------------
# step 4: candidate pairs


def candidate_pairs(ints, faces, *, chunk: int = _CHUNK) -> np.ndarray:
    """All pairs of triangles whose closed axis-aligned integer bounding boxes intersect.

    Sweep: triangles are sorted by their box minimum along the axis that yields the fewest
    one-axis overlaps; each triangle's partners after it in that order form a contiguous run
    (found by ``searchsorted`` of its box maximum). The runs are scanned and filtered by
    the two other axes (compiled: :func:`cspace.geometry._kernels.arrangement.sweep_pairs`).

    Parameters
    ----------
    ints : (n, 3) int64
        Vertex positions in grid units.
    faces : (t, 3) int64
        Triangles as vertex labels.
    chunk : int, default 2**21
        The numpy reference sweep's bound on the one-axis overlaps expanded at once
        (:meth:`BoxSweep._pairs_reference`); the compiled sweep holds only its output
        (at most 48 bytes per pair while it collects and sorts them), so it does not use it.

    Returns
    -------
    pairs : (k, 2) int64
        Rows ``(i, j)`` with ``i < j``, sorted lexicographically, each unordered pair once.
    """
    ints, faces = _check_soup(ints, faces)
    corners = ints[faces]
    return box_pairs(corners.min(axis=1), corners.max(axis=1), chunk=chunk)


def box_pairs(lo, hi, *, chunk: int = _CHUNK) -> np.ndarray:
    """All pairs of closed integer boxes ``[lo_i, hi_i]`` that intersect (the sweep of
    :func:`candidate_pairs`); ``lo, hi (t, 3)`` int64, any values (boxes far from the origin
    included: see :class:`BoxSweep`). Rows ``(i, j)``, ``i < j``, sorted, each unordered pair
    once."""
    return BoxSweep(lo, hi).pairs(chunk=chunk)


class BoxSweep:
    """The sweep of :func:`box_pairs`, set up once (three sorts), so that its work can be
    split: :meth:`pairs` expands one share of it. ``overlaps`` is its work, the number of
    one-axis overlaps along the sweep axis.

    The boxes are translated to start at 0 on every axis first: overlaps do not change, and
    the two filter axes are then held in int32 whenever the boxes span less than 2**31 grid
    units, wherever they lie. Callers box triangles in grid units of their absolute
    coordinates (a scene at (250, 150, -300) on a fine grid: beyond 2**32), where a plain
    int32 cast wrapped and lost pairs. Spans of 2**31 or more keep int64 and are swept by
    :meth:`_pairs_reference`.
    """

    def __init__(self, lo, hi):
        lo, hi = np.asarray(lo, dtype=np.int64), np.asarray(hi, dtype=np.int64)
        t = self.t = len(lo)
        self.overlaps = 0
        if t < 2:
            return
        base = lo.min(axis=0)
        # Grid units of float64 coordinates are below 2**53 (a step is never under 2 ulps of
        # the coordinates), so the differences cannot overflow int64.
        lo, hi = lo - base, hi - base
        self.wide = bool(hi.max() >= 2**31)
        first = np.arange(1, t + 1)
        sweeps = []
        for ax in range(3):
            order = np.argsort(lo[:, ax], kind="stable")
            end = np.searchsorted(lo[order, ax], hi[order, ax], side="right")
            count = end - first  # partners after position p: p+1 .. end-1 (end > p: lo <= hi)
            sweeps.append((int(count.sum()), ax, order, count))
        # Sweep along the most selective axis, filter by the next most selective first.
        sweeps.sort(key=lambda s: s[0])
        (self.overlaps, _, self.order, count), others = sweeps[0], [s[1] for s in sweeps[1:]]
        # Translated coordinates fit int32 unless ``wide``: half the memory traffic of the
        # gathers below.
        self.itype = np.int32 if t < 2**31 else np.int64
        ctype = np.int64 if self.wide else np.int32
        self.los = [np.ascontiguousarray(lo[self.order, a], dtype=ctype) for a in others]
        self.his = [np.ascontiguousarray(hi[self.order, a], dtype=ctype) for a in others]
        self.count = count.astype(self.itype)
        self.cum = np.cumsum(self.count, dtype=np.int64)
        # Position of the first partner of each row, minus where its run starts in the chunk.
        self.shift = np.arange(1, t + 1, dtype=np.int64) - (self.cum - self.count)

    def _rows(self, share: int, shares: int) -> tuple[int, int]:
        """The sweep rows ``[start, end)`` of share ``share`` of ``shares``."""
        def row(k: int) -> int:  # first sweep row of share k
            return int(np.searchsorted(self.cum, k * self.overlaps // shares, side="right"))

        return (0 if share == 0 else row(share)), (self.t if share == shares - 1 else row(share + 1))

    def pairs(self, share: int = 0, shares: int = 1, *, chunk: int = _CHUNK) -> np.ndarray:
        """The intersecting pairs found from share ``share`` of ``shares`` (consecutive
        sweep rows holding about ``overlaps / shares`` one-axis overlaps each): sorted rows
        ``(i, j)``, ``i < j``, int64 ``(k, 2)``; the shares together give every pair once.

        Compiled (:func:`cspace.geometry._kernels.arrangement.sweep_pairs`, the same pairs as
        :meth:`_pairs_reference`); it holds only its output, so ``chunk`` (the reference's
        memory bound) is not used."""
        if self.overlaps == 0:
            return np.zeros((0, 2), dtype=np.int64)
        if self.wide:  # the compiled sweep holds int32 coordinates
            return self._pairs_reference(share, shares, chunk=chunk)
        start, end = self._rows(share, shares)
        (lo1, lo2), (hi1, hi2) = self.los, self.his
        return _compiled.sweep_pairs(start, end, self.t, self.order, self.cum, lo1, hi1, lo2, hi2)

    def _pairs_reference(self, share: int = 0, shares: int = 1, *, chunk: int = _CHUNK) -> np.ndarray:
        """:meth:`pairs` in numpy (the reference): the one-axis overlaps are expanded in
        chunks of at most ``chunk`` rows and filtered by the two other axes."""
        if self.overlaps == 0:
            return np.zeros((0, 2), dtype=np.int64)
        count, cum, shift, itype = self.count, self.cum, self.shift, self.itype
        start, end = self._rows(share, shares)
        out = []
        while start < end:
            base = int(cum[start - 1]) if start else 0
            stop = min(max(int(np.searchsorted(cum, base + chunk, side="right")), start + 1), end)
            c = count[start:stop]
            n = int(cum[stop - 1]) - base
            if n:
                rows = np.repeat(np.arange(start, stop, dtype=itype), c)
                cols = np.arange(base, base + n, dtype=np.int64)
                cols += np.repeat(shift[start:stop], c)
                cols = cols.astype(itype, copy=False)
                # Filter by one axis, compress, then the other: the second test sees few rows.
                for lo_a, hi_a in zip(self.los, self.his):
                    keep = np.flatnonzero((lo_a[cols] <= hi_a[rows]) & (lo_a[rows] <= hi_a[cols]))
                    rows, cols = rows[keep], cols[keep]
                i, j = self.order[rows], self.order[cols]
                out.append(np.stack([np.minimum(i, j), np.maximum(i, j)], axis=1))
            start = stop
        if not out:
            return np.zeros((0, 2), dtype=np.int64)
        pairs = np.concatenate(out)
        return pairs[np.lexsort((pairs[:, 1], pairs[:, 0]))]


# --------------------------------------------------------------------------------------
# a bounding-box tree, for queries whose boxes move (a robot at a translation)


class BoxTree:
    """A binary tree of integer boxes or k-DOPs (a BVH): each node's bounds hold its children's.

    ``lo, hi (n, k)`` bound each item on ``k >= 3`` directions, the first three the axes (a box
    when ``k == 3``; :func:`dop_bounds` gives the k-DOPs of triangles). Built top-down,
    splitting at the median centre along the node's longest axis, with at most ``leaf`` items a
    leaf. Node ``k``'s bounds are ``lo[k], hi[k]`` (float64 of grid integers below 2**53, so
    exact); an inner node's children are ``first[k]`` and ``first[k] + 1`` (``count[k] == 0``);
    a leaf holds the items ``order[first[k]:first[k] + count[k]]``. Node 0 is the root. Only
    prunes: what a query keeps is decided exactly after.
    """

    def __init__(self, lo: np.ndarray, hi: np.ndarray, leaf: int = 4):
        lo, hi = np.asarray(lo, dtype=np.float64), np.asarray(hi, dtype=np.float64)
        k = lo.shape[-1] if lo.ndim == 2 else 3
        lo, hi = lo.reshape(-1, k), hi.reshape(-1, k)
        if k < 3 or hi.shape != lo.shape:
            raise ValueError(f"box tree bounds must be (n, k >= 3) pairs, got {lo.shape}, {hi.shape}")
        if not len(lo):
            raise ValueError("a box tree needs at least one box")
        if leaf < 1:
            raise ValueError("a leaf holds at least one item")
        lo, hi = np.ascontiguousarray(lo), np.ascontiguousarray(hi)
        self.order, self.lo, self.hi, self.first, self.count = _boxtree.build(lo, hi, int(leaf))
        self.box_lo, self.box_hi = np.ascontiguousarray(lo), np.ascontiguousarray(hi)

    def __len__(self) -> int:
        return len(self.order)

    def __repr__(self) -> str:
        return f"BoxTree(boxes={len(self.order)}, nodes={len(self.first)})"


def _tree_reference(lo: np.ndarray, hi: np.ndarray, leaf: int):
    """Pure-Python reference of :func:`cspace.geometry._kernels.boxtree.build`, step for step:
    ``(order, node_lo, node_hi, first, count)``."""
    lo, hi = np.asarray(lo, dtype=np.float64), np.asarray(hi, dtype=np.float64)
    n, k = lo.shape
    centre = (lo[:, :3] + hi[:, :3]).tolist()
    L, H = lo.tolist(), hi.tolist()
    order = list(range(n))
    nlo, nhi, first, count = [], [], [], []

    def select(a: int, b: int, kth: int, axis: int) -> None:
        # Hoare's selection with a median-of-three pivot on order[a:b], as the kernel's
        left, right = a, b - 1
        kth += a
        key = lambda x: centre[order[x]][axis]  # noqa: E731
        while right > left:
            m = left + (right - left) // 2
            pivot = sorted((key(left), key(m), key(right)))[1]
            i, j = left, right
            while i <= j:
                while key(i) < pivot:
                    i += 1
                while key(j) > pivot:
                    j -= 1
                if i <= j:
                    order[i], order[j] = order[j], order[i]
                    i, j = i + 1, j - 1
            if kth <= j:
                right = j
            elif kth >= i:
                left = i
            else:
                return

    stack, nodes = [(0, 0, n)], 1
    while stack:
        node, a, b = stack.pop()
        while len(nlo) <= node:
            nlo.append(None), nhi.append(None), first.append(0), count.append(0)
        items = order[a:b]
        nlo[node] = [min(L[x][c] for x in items) for c in range(k)]
        nhi[node] = [max(H[x][c] for x in items) for c in range(k)]
        if b - a <= leaf:
            first[node], count[node] = a, b - a
            continue
        ext = [nhi[node][c] - nlo[node][c] for c in range(3)]
        axis = max(range(3), key=lambda c: (ext[c], -c))
        half = (b - a) // 2
        select(a, b, half, axis)
        first[node] = nodes
        stack += [(nodes, a, a + half), (nodes + 1, a + half, b)]
        nodes += 2
    return (np.array(order, dtype=np.int64), np.array(nlo, dtype=np.float64).reshape(-1, k),
            np.array(nhi, dtype=np.float64).reshape(-1, k), np.array(first, dtype=np.int64),
            np.array(count, dtype=np.int64))


# The directions the pair trees bound triangles on: the 3 axes, the 6 face diagonals and the
# 4 body diagonals (a 26-DOP). Only translations move a robot's tree, so a k-DOP stays a
# k-DOP under every query; on the alpha puzzle's near-contact states it keeps 16x fewer
# triangle pairs than the axis boxes (37 against 594 per free state).
DOP_DIRECTIONS = np.array([[1, 0, 0], [0, 1, 0], [0, 0, 1],
                           [1, 1, 0], [1, -1, 0], [1, 0, 1], [1, 0, -1], [0, 1, 1], [0, 1, -1],
                           [1, 1, 1], [1, 1, -1], [1, -1, 1], [-1, 1, 1]], dtype=np.int64)


def dop_bounds(tris: np.ndarray, grow=(0, 0, 0)) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The k-DOPs of grid-integer triangles ``tris (n, m, 3)`` grown by the box ``[-grow,
    grow]``: ``lo, hi (n, k)`` float64 and the directions ``(k, 3)`` used.

    The projections are integers, exact in float64 while every one stays below 2**52 in
    magnitude; beyond that (a grid origin near its 2**53 limit) only the axes are used, which
    is the plain box.
    """
    tris = np.asarray(tris, dtype=np.int64)
    g = np.abs(np.asarray(grow, dtype=np.int64).reshape(3))
    D = DOP_DIRECTIONS if np.abs(tris).max(initial=0) + g.max() < 2 ** 50 else DOP_DIRECTIONS[:3]
    P = tris @ D.T  # (n, m, k) exact integers
    G = np.abs(D) @ g
    return ((P.min(axis=1) - G).astype(np.float64), (P.max(axis=1) + G).astype(np.float64),
            np.ascontiguousarray(D))
