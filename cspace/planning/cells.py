"""Cells of the free space at one orientation: their labels, the grid they lie on, and the
polyline through a chain of touching cells.

A closed box (a cell) is ``blocked`` when it lies inside one convex piece of one C-obstacle
(exact), ``free`` when every C-obstacle near it is kept off it (float, with the margins stated
at :func:`_kept_off`: never part of a proof, and every path through free cells is re-proved
by ``segment_free``), else ``mixed``; below the octree, ``near`` when a copy of it moved by
at most a stated distance lies inside one convex piece (exact, :func:`_nudged`). Triangle-pair
C-obstacles get both of their tests compiled (``PairSet.boxes_inside``, ``boxes_apart``; numpy
references kept here). :mod:`.decide` labels an octree of such cells;
:mod:`.corridor` refines cells along one route below the octree's finest level. Cells may
be boxes of a frame turned to the C-obstacles' faces (:class:`_Frame`, :func:`_choose_frame`):
the tests then take their corners turned into the scene. What each label means, and why it is
certain: :mod:`.decide`'s docstring.
"""

from __future__ import annotations

import time as _time

import numpy as np

from ..cobstacle.pairs import _slab_columns
from ..errors import InvalidArgumentError
from ..geometry.exact import _FILTER, _TINY

#: Cell labels. ``NEAR``: blocked within a stated distance (:func:`_nudged`), not inside.
BLOCKED, MIXED, FREE, NEAR = 0, 1, 2, 3
# The free label's margin, relative to the bounds' size (signed_distance's float error is a
# few ulps of the coordinates; 2**-20 is far above it and far below any cell).
_FREE_MARGIN = 2.0 ** -20
# A convex piece keeps a cell off by a plane when the cell's support value is beyond it by
# this much of the magnitudes summed (the value's float error is a few 2**-53 of them; a
# wider margin leaves a band along each face where cells are neither free nor, moved by the
# nudge, inside: routes along a face stalled in it, at 2**-30, about 4e-7 at 400 units).
_PLANE_MARGIN = 2.0 ** -42
_CORNERS = np.array([[i, j, k] for i in (0, 1) for j in (0, 1) for k in (0, 1)], dtype=np.int64)
_NEIGHBOURS = [(i, j, k) for i in (-1, 0, 1) for j in (-1, 0, 1) for k in (-1, 0, 1)
               if (i, j, k) > (0, 0, 0)]


class _OutOfTime(Exception):
    pass


def _box_corners(lo: np.ndarray, hi: np.ndarray) -> np.ndarray:
    """(m, 8, 3): the corners of the boxes ``[lo[r], hi[r]]``, in :data:`_CORNERS` order
    (one box: ``lo, hi`` of shape (3,) give (8, 3))."""
    return np.where(_CORNERS.astype(bool), hi[..., None, :], lo[..., None, :])


# --------------------------------------------------------------------------------------------
# the blocked label: inside one convex piece of one C-obstacle


def _inside_one_piece(co, lo: np.ndarray, hi: np.ndarray, C: np.ndarray | None = None
                      ) -> np.ndarray:
    """(m,) bool: the closed box ``[lo[r], hi[r]]`` lies in one convex piece of ``co``
    (all eight corners in it, exactly). A non-convex sum (``'mesh'``): the cell's centre is
    inside (exact sign) and its distance to the surface exceeds the half-diagonal by
    ``2**-20`` of the C-obstacle's size (the distance is float, accurate to a few ulps of the
    coordinates, far below that margin), so the ball it spans, and the cell, are inside.

    ``C`` (m, 8, 3): a cell of a turned frame (:class:`_Frame`), its eight corners in the
    scene; ``lo, hi`` are then their bounding box (it only narrows the candidates, and a
    ``'mesh'`` or pair test on it is weaker, never wrong)."""
    m = len(lo)
    if C is None:
        C = _box_corners(lo, hi)
    kind = co.kind
    if kind == "convex":
        return co.contains(C.reshape(-1, 3)).reshape(m, 8).all(axis=1)
    if kind == "union":
        out = np.zeros(m, dtype=bool)
        for part in co.parts:
            rows = np.nonzero(~out)[0]
            if len(rows):
                out[rows] = _inside_one_piece(part, lo[rows], hi[rows], C[rows])
        return out
    if kind == "surface":
        impl, out = co._impl, np.zeros(m, dtype=bool)
        for j, piece in enumerate(impl.impl):
            rows = np.nonzero(~out & (impl.lo[j] <= lo).all(axis=1)
                              & (hi <= impl.hi[j]).all(axis=1))[0]
            if len(rows):
                out[rows] = piece.contains(C[rows].reshape(-1, 3)).reshape(-1, 8).all(axis=1)
        return out
    if kind == "pairs":
        return _inside_a_pair(co._impl, lo, hi, C)
    if kind == "mesh":  # inside, and farther from the surface than any corner of the cell
        B = np.asarray(co.bounds, dtype=np.float64)
        margin = _FREE_MARGIN * float(np.abs(B).max() + (B[1] - B[0]).max())
        sd = co.signed_distance((lo + hi) / 2)
        return (sd < 0) & (-sd > np.linalg.norm(hi - lo, axis=1) / 2 + margin)
    return np.zeros(m, dtype=bool)


def _inside_a_pair(impl, lo, hi, C) -> np.ndarray:
    """:func:`_inside_one_piece` for a triangle-pair C-obstacle, compiled
    (``PairSet.boxes_inside``: the node pairs of the engine's two trees whose k-DOP sum holds
    the cell, then each piece's slabs at the cell's centre and corners, with the engine's
    float filter); the pieces the filter cannot settle get the exact test (Python integers).
    Reference: :func:`_inside_a_pair_reference`, the same answer."""
    status, todo = impl._set.boxes_inside(impl._grid_units(lo), impl._grid_units(hi))
    out = status == 1
    for r, i, j in todo.tolist():
        if not out[r] and all(impl._in_piece(i, j, x) for x in C[r].tolist()):
            out[r] = True
    return out


def _pair_corner_values(impl, lo: np.ndarray, hi: np.ndarray):
    """The references' float filter: every pair whose piece k-DOP meets a cell
    (``cand``: rows ``(cell, i, j)``) and each slab side's value and bound at the cell's eight
    corners (``val, err``: (c, 8, 2K), ``a . [corner, 1] <= 0`` inside; the engine's filter,
    :func:`~cspace.cobstacle.pairs._slab_columns`: normals, supports and products bounded)."""
    X_lo, X_hi = impl._grid_units(lo), impl._grid_units(hi)  # exact: powers of two
    cand = impl._set.candidates(X_lo, X_hi)
    gf = np.asarray(impl.g, dtype=np.float64)
    A, absA = _slab_columns(impl.S[cand[:, 1]], impl.T[cand[:, 2]], bool(gf.any()), gf)
    Q = np.ones((len(cand), 8, 4))
    Q[:, :, :3] = _box_corners(X_lo[cand[:, 0]], X_hi[cand[:, 0]])
    with np.errstate(over="ignore", under="ignore", invalid="ignore"):
        val = np.matmul(Q, A)
        err = _FILTER * np.matmul(np.abs(Q), absA) + _TINY
    return cand, val, err


def _inside_a_pair_reference(impl, lo, hi, C) -> np.ndarray:
    """Reference of :func:`_inside_a_pair` (numpy, every candidate pair at once): a pair
    whose slabs hold the eight corners by the float filter, or, where the filter cannot
    tell, by the exact test (Python integers)."""
    out = np.zeros(len(lo), dtype=bool)
    cand, val, err = _pair_corner_values(impl, lo, hi)
    inside = (val < -err).all(axis=(1, 2))
    out[cand[inside, 0]] = True
    unsure = ~inside & ~(val > err).any(axis=(1, 2))
    for r, i, j in cand[unsure].tolist():
        if not out[r] and all(impl._in_piece(i, j, x) for x in C[r].tolist()):
            out[r] = True
    return out


def _pairs_apart_reference(impl, lo: np.ndarray, hi: np.ndarray) -> np.ndarray:
    """Reference of ``PairSet.boxes_apart`` (numpy): every piece whose k-DOP meets the cell
    has a slab with the cell's eight corners certainly beyond one of its sides."""
    out = np.ones(len(lo), dtype=bool)
    cand, val, err = _pair_corner_values(impl, lo, hi)
    apart = (val > err).all(axis=1).any(axis=1)
    out[cand[~apart, 0]] = False
    return out


def _kept_off(co, lo: np.ndarray, hi: np.ndarray, margin: float,
              frame: _Frame | None = None) -> np.ndarray:
    """(m,) bool: ``co`` certainly misses the closed box (see the ``free`` label); with a
    ``frame``, ``lo, hi`` are in it (the box turned into the scene)."""
    kind = co.kind
    if kind == "convex":
        e = co._impl.exponent
        A = co._impl.A
        c, h = np.ldexp((lo + hi) / 2, -e), np.ldexp((hi - lo) / 2, -e)
        # a turned box's support along a normal n: its half-sides against |M^T n|
        absA = np.abs(A[:3]) if frame is None else np.abs(frame.M.T @ A[:3])
        if frame is not None:
            c = frame.world(c)
        val = c @ A[:3] + A[3] - h @ absA
        tol = _PLANE_MARGIN * (np.abs(c) @ np.abs(A[:3]) + h @ absA + np.abs(A[3]))
        return (val > tol).any(axis=1)
    if kind in ("union", "surface"):  # every part (a surface's convex pieces) near the cell
        members = ([(np.asarray(p.bounds, dtype=np.float64), p) for p in co.parts]
                   if kind == "union" else
                   [(np.stack([co._impl.lo[j], co._impl.hi[j]]), _Piece(piece))
                    for j, piece in enumerate(co._impl.impl)])
        out = np.ones(len(lo), dtype=bool)
        wlo, whi = (lo, hi) if frame is None else frame.aabb(lo, hi)
        for B, part in members:
            rows = np.nonzero(out & (wlo <= B[1]).all(axis=1) & (B[0] <= whi).all(axis=1))[0]
            if len(rows):
                out[rows] = _kept_off(part, lo[rows], hi[rows], margin, frame)
        return out
    if kind == "pairs":  # each piece near the cell kept off it by one of its slabs
        impl = co._impl  # (a turned cell: its bounding box in the scene; weaker, sound)
        wlo, whi = (lo, hi) if frame is None else frame.aabb(lo, hi)
        return impl._set.boxes_apart(impl._grid_units(wlo), impl._grid_units(whi)) == 1
    # the distance only where the centre is outside: a centre inside is never kept off, and
    # a non-convex C-obstacle's depth inside (its signed distance there) is the costly part
    centre, out = (lo + hi) / 2, np.zeros(len(lo), dtype=bool)
    if frame is not None:  # a turned cell: its centre in the scene (its half-diagonal is)
        centre = frame.world(centre)
    rows = np.nonzero(~np.asarray(co.contains(centre), dtype=bool))[0]
    if len(rows):
        half = np.linalg.norm(hi[rows] - lo[rows], axis=1) / 2
        out[rows] = co.signed_distance(centre[rows]) > half + margin
    return out


class _Piece:
    """A surface's convex piece (its engine) seen as a convex C-obstacle by :func:`_kept_off`:
    its planes are a convex C-obstacle's."""

    kind = "convex"

    def __init__(self, impl):
        self._impl = impl


# Between reads of the clock a test call takes about _SWEEP_SECONDS: its first call 256
# cells, each next sized by the last one's rate (a pair C-obstacle answers from hundreds to
# millions of cells a second: the Parasol alpha puzzle's 0.94 million pairs overran a 10 s
# budget by 4 s with 1024 cells a call).
_SWEEP_FIRST, _SWEEP_SECONDS = 256, 0.25


def _labels(obstacles, boxes: np.ndarray, lo: np.ndarray, hi: np.ndarray, margin: float,
            deadline: float, nudge: float = 0.0, frame: _Frame | None = None) -> np.ndarray:
    """The label of each closed cell ``[lo[r], hi[r]]``; with ``nudge`` > 0, a cell within
    ``nudge`` of one convex piece is blocked too (:func:`_nudged`: :data:`NEAR`). With a
    ``frame``, the cells are its boxes, and one wholly outside the bounds is blocked
    (:meth:`_Frame.outside`: no motion goes there)."""
    label = np.full(len(lo), MIXED, dtype=np.int8)
    W = None if frame is None else frame.corners(lo, hi)
    wlo, whi = (lo, hi) if W is None else (W.min(axis=1), W.max(axis=1))
    todo = np.arange(len(lo))
    if W is not None:
        out = frame.outside(W)
        label[out] = BLOCKED
        todo = todo[~out]
    free = _sweep(obstacles, boxes, wlo[todo], whi[todo], True, False,
                  lambda co, r: _kept_off(co, lo[todo[r]], hi[todo[r]], margin, frame),
                  deadline)
    label[todo[free]] = FREE
    rest = todo[~free]
    inside = _inside_any(obstacles, boxes, lo[rest], hi[rest], deadline, frame)
    label[rest[inside]] = BLOCKED
    if nudge > 0:
        rest = rest[~inside]
        label[rest[_nudged(obstacles, boxes, lo[rest], hi[rest], nudge, deadline,
                           frame)]] = NEAR
    return label


def _inside_any(obstacles, boxes, lo, hi, deadline, frame: _Frame | None = None) -> np.ndarray:
    """(m,) bool: the closed cell lies inside one convex piece of one C-obstacle
    (:func:`_inside_one_piece`); with a ``frame``, a box of it."""
    if frame is None:
        return _sweep(obstacles, boxes, lo, hi, False, True,
                      lambda co, r: _inside_one_piece(co, lo[r], hi[r]), deadline)
    W = frame.corners(lo, hi)
    wlo, whi = W.min(axis=1), W.max(axis=1)
    return _sweep(obstacles, boxes, wlo, whi, False, True,
                  lambda co, r: _inside_one_piece(co, wlo[r], whi[r], W[r]), deadline)


# The 26 directions a cell is moved in by _nudged: a cell moves only along its thin sides.
_DIRECTIONS = np.array([d for d in np.ndindex(3, 3, 3) if d != (1, 1, 1)], np.float64) - 1.0


def _nudged(obstacles, boxes, lo: np.ndarray, hi: np.ndarray, delta: float,
            deadline: float, frame: _Frame | None = None) -> np.ndarray:
    """(m,) bool: the closed cell lies within ``delta`` of one convex piece of a C-obstacle:
    its copy moved by some ``v``, ``|v| <= delta``, lies in the piece (the exact blocked test
    on the moved corners), so each of its points has a point of the piece within ``|v|``.

    ``v`` has length ``delta / 2`` along one of 26 directions (axes, face and body diagonals),
    nonzero only on the cell's sides no longer than that: a cell across the plane where two
    C-obstacles touch (an edge, a vertex) and thinner than ``delta / 2`` across it moves into
    one of them. The moved corners are rounded: each coordinate by at most ``2**-53`` of its
    magnitude, so the move is at most ``delta / 2 + 2**-51 * max|x|``, below ``delta`` when
    ``delta > 2**-49 * max|x|``; smaller, the test is skipped (nothing is nudged). In a turned
    ``frame`` the corners turned into the scene add :attr:`_Frame.rho`: the test is skipped
    unless ``delta / 4`` exceeds it too."""
    out = np.zeros(len(lo), dtype=bool)
    t = delta / 2
    if not len(lo) or delta <= 2.0 ** -49 * float(np.abs(np.vstack([lo, hi])).max()) or (
            frame is not None and delta / 4 <= frame.rho):
        return out
    thin = (hi - lo) <= t
    for d in _DIRECTIONS:
        on = d != 0
        rows = np.nonzero(~out & thin[:, on].all(axis=1))[0]
        if len(rows):
            v = d * (t / np.sqrt(np.count_nonzero(on)) * (1 - 2.0 ** -40))
            out[rows] = _inside_any(obstacles, boxes, lo[rows] + v, hi[rows] + v, deadline,
                                    frame)
    return out


def _sweep(obstacles, boxes, lo, hi, initial: bool, within: bool, test, deadline) -> np.ndarray:
    """A flag per cell, ``initial`` until a C-obstacle whose box the cell (its box in the
    scene, ``lo, hi``) meets (``within``: lies in) answers ``test(co, rows)`` for the cells
    ``rows`` otherwise; past ``deadline``: out of time."""
    flag = np.full(len(lo), initial, dtype=bool)
    for k, co in enumerate(obstacles):
        if _time.perf_counter() > deadline:
            raise _OutOfTime
        B = boxes[k]
        near = ((B[0] <= lo) & (hi <= B[1]) if within else (lo <= B[1]) & (B[0] <= hi))
        rows = np.nonzero((flag == initial) & near.all(axis=1))[0]
        s, n = 0, _SWEEP_FIRST
        while s < len(rows):
            t = _time.perf_counter()
            if s and t > deadline:
                raise _OutOfTime
            part = rows[s:s + n]
            flag[part] = test(co, part)
            s += len(part)
            rate = len(part) / max(_time.perf_counter() - t, 1e-6)
            n = int(min(max(rate * _SWEEP_SECONDS, 64), 1 << 16))
    return flag


# --------------------------------------------------------------------------------------------
# a turned frame: cells aligned with the C-obstacles' faces


class _Frame:
    """Cells as boxes of a turned frame: frame point ``x`` is the scene point ``M @ x``
    (``M`` float64, its columns the frame's axes, orthonormal to within ``2**-45``).

    ``M`` is a fixed linear map, so the turned boxes of a frame grid tile the scene exactly;
    only their corners are computed in floats: each coordinate of ``M @ x`` rounded by at
    most ``3 * 2**-53 * sum_j |M_ij| |x_j|``, so every true corner lies within
    :attr:`rho` ``= 2**-48 * X`` of its computed one (``X`` the largest frame coordinate of
    :attr:`domain`), and every point of a true cell within ``rho`` of the hull of its
    computed corners. A cell proved inside a piece from those corners therefore has no point
    with a clearance above ``rho``: a "no path" in the frame holds for clearances above
    ``error_bound + rho`` (``Decision.clearance`` adds it).

    :attr:`domain`: the frame box that holds the scene ``bounds`` turned into the frame
    (their corners' frame coordinates, computed as ``M^T c``, grown by ``2**-40`` of their
    magnitude, far above the at most ``~2**-45`` by which ``M^T`` differs from ``M^-1``).
    """

    def __init__(self, M: np.ndarray, bounds: np.ndarray):
        self.M = np.asarray(M, dtype=np.float64).reshape(3, 3)
        self.bounds = np.asarray(bounds, dtype=np.float64).reshape(2, 3)
        if not np.abs(self.M.T @ self.M - np.eye(3)).max() <= 2.0 ** -45:
            raise InvalidArgumentError("a frame must be orthonormal (to within 2**-45)")
        F = self.local(_box_corners(self.bounds[0], self.bounds[1]))
        pad = 2.0 ** -40 * float(np.abs(F).max() + 1.0)
        #: where a point given in the scene may be in the frame (point location's margin)
        self.pad = pad
        self.domain = np.stack([F.min(axis=0) - pad, F.max(axis=0) + pad])
        self.rho = 2.0 ** -48 * float(np.abs(self.domain).max())

    def world(self, P: np.ndarray) -> np.ndarray:
        """Frame points ``(..., 3)`` as scene points (rounded: :attr:`rho`)."""
        return P @ self.M.T

    def local(self, q: np.ndarray) -> np.ndarray:
        """Scene points ``(..., 3)`` in the frame (within :attr:`pad`)."""
        return q @ self.M

    def corners(self, lo: np.ndarray, hi: np.ndarray) -> np.ndarray:
        """(m, 8, 3): the frame boxes' corners in the scene."""
        return self.world(_box_corners(lo, hi))

    def aabb(self, lo: np.ndarray, hi: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """The frame boxes' bounding boxes in the scene, grown by :attr:`rho`."""
        W = self.corners(lo, hi)
        return W.min(axis=1) - self.rho, W.max(axis=1) + self.rho

    def outside(self, W: np.ndarray) -> np.ndarray:
        """(m,) bool: cells (their scene corners ``W``, (m, 8, 3)) wholly outside the bounds:
        every corner beyond one face of them by more than :attr:`rho`, so every true point
        of the cell is (exact on the floats given)."""
        b = self.bounds
        return ((W < b[0] - self.rho).all(axis=1) | (W > b[1] + self.rho).all(axis=1)).any(
            axis=1)

    def clip(self, P: np.ndarray) -> np.ndarray:
        """Scene points moved into the bounds: a path's waypoints (a free cell may cross the
        bounds' faces; every segment is re-proved after)."""
        return np.clip(P, self.bounds[0], self.bounds[1])


def _facet_normals(co) -> np.ndarray:
    """(n, 3) unit facet normals of a C-obstacle's convex pieces (none for pairs, sums)."""
    kind = co.kind
    if kind == "convex":
        A = [co._impl.A[:3].T]
    elif kind == "union":
        A = [_facet_normals(p) for p in co.parts]
    elif kind == "surface":
        A = [np.asarray(piece.A, dtype=np.float64)[:3].T for piece in co._impl.impl]
    else:
        return np.zeros((0, 3))
    A = np.vstack([np.zeros((0, 3))] + A).astype(np.float64)
    n = np.linalg.norm(A, axis=1)
    return A[n > 0] / n[n > 0, None]


#: Most frames tried by :func:`_choose_frame` (one per frequent normal), and most normals
#: it weighs them by.
_FRAME_CANDIDATES, _FRAME_NORMALS = 8, 20000
#: A normal counts as along an axis of a frame when its cosine to it is within this of 1
#: (an angle of 4e-5), and two normals as square when their cosine is below ``_SQUARE`` (the
#: normals are grouped rounded to 1e-9). The choice is a heuristic: it decides which cells
#: are cut, never a label.
_ALIGNED, _SQUARE = 1e-9, 1e-6


def _choose_frame(obstacles, bounds: np.ndarray) -> np.ndarray | None:
    """A frame (3, 3 orthonormal) in which more of the C-obstacles' facet normals lie along
    an axis than in the scene's own, or None (the scene's axes: no turned frame, also when
    the bounds are flat on an axis). Each candidate pairs one of the most frequent normals
    with one of the most frequent normals square to it; the best scored wins. Only where the
    cells are cut depends on it; their labels stay exact."""
    b = np.asarray(bounds, dtype=np.float64)
    if not (b[1] > b[0]).all():
        return None
    return frame_of_normals(np.vstack([np.zeros((0, 3))] + [_facet_normals(co) for co in obstacles]))


def frame_of_normals(N: np.ndarray) -> np.ndarray | None:
    """:func:`_choose_frame` on unit normals ``N (k, 3)``: a frame in which more of them lie
    along an axis than in the scene's own, or None."""
    if len(N) < 3:
        return None
    N = N[:: -(-len(N) // _FRAME_NORMALS)]  # many bodies: an even sample of their normals
    N = N * np.where(N[np.arange(len(N)), np.abs(N).argmax(axis=1)] < 0, -1.0, 1.0)[:, None]

    def score(M):
        return int(np.count_nonzero(np.abs(N @ M).max(axis=1) >= 1 - _ALIGNED))

    _, first, count = np.unique(np.round(N, 9), axis=0, return_index=True, return_counts=True)
    D = N[first]  # a normal of each group, as it is (the rounding only groups them)
    order = np.argsort(-count, kind="stable")[:_FRAME_CANDIDATES]
    best, best_score = None, score(np.eye(3))
    for i in order:
        n1 = D[i] / np.linalg.norm(D[i])
        square = np.nonzero(np.abs(D @ n1) < _SQUARE)[0]
        for j in square[np.argsort(-count[square], kind="stable")][:_FRAME_CANDIDATES]:
            n2 = D[j] - (D[j] @ n1) * n1
            n2 /= np.linalg.norm(n2)
            M = np.stack([n1, n2, np.cross(n1, n2)], axis=1)
            sc = score(M)
            if sc > best_score:
                best, best_score = M, sc
    return best


# --------------------------------------------------------------------------------------------
# the octree


class _Grid:
    """The finest grid over the bounds: ``N[a]`` cells on axis ``a`` (1 on a flat axis), cell
    corner ``i`` at ``x[a][i]`` (float64, strictly increasing, the bounds' ends exact). With a
    turned ``frame``, over its :attr:`_Frame.domain` instead (``b`` is then that box, in the
    frame)."""

    def __init__(self, b: np.ndarray, depth: int, frame: _Frame | None = None):
        b = b if frame is None else frame.domain
        self.b = b
        self.frame = frame
        self.pad = 0.0 if frame is None else frame.pad
        self.split = b[1] > b[0]
        self.N = np.where(self.split, 1 << depth, 1).astype(np.int64)
        self.x = []
        for a in range(3):
            i = np.arange(self.N[a] + 1, dtype=np.float64)
            x = b[0, a] + (b[1, a] - b[0, a]) * (i / self.N[a])
            x[0], x[-1] = b[0, a], b[1, a]
            x = np.clip(x, b[0, a], b[1, a])
            if self.split[a] and not (np.diff(x) > 0).all():
                raise InvalidArgumentError("the bounds are too small for the decision's cells")
            self.x.append(x)

    def floats(self, I: np.ndarray) -> np.ndarray:
        """Float coordinates of integer corner indices ``I (k, 3)``."""
        return np.stack([self.x[a][I[:, a]] for a in range(3)], axis=1)

    def local(self, q: np.ndarray) -> np.ndarray:
        """A scene point in the grid's frame (itself without a turned frame)."""
        return q if self.frame is None else self.frame.local(q)

    def cells_at(self, q: np.ndarray, step: np.ndarray) -> np.ndarray:
        """Indices (in units of ``step``) of every cell of that size whose closed box holds
        the scene point ``q``: one or two per axis (``q`` on a corner plane belongs to both
        sides); in a turned frame, every cell within the frame's ``pad`` of it."""
        q = self.local(q)
        per_axis = []
        for a in range(3):
            xs = self.x[a][:: int(step[a])]
            lo = max(int(np.searchsorted(xs, q[a] - self.pad, side="left")) - 1, 0)
            hi = min(int(np.searchsorted(xs, q[a] + self.pad, side="right")) - 1, len(xs) - 2)
            per_axis.append(range(lo, max(hi, lo) + 1))
        return np.array([(i, j, k) for i in per_axis[0] for j in per_axis[1]
                         for k in per_axis[2]], dtype=np.int64)


def _shift(shape, d) -> tuple[tuple, tuple]:
    """Slices pairing each cell of a grid of ``shape`` with its neighbour at offset ``d``:
    ``grid[src]`` and ``grid[dst]`` line up."""
    src = tuple(slice(max(0, -x), shape[a] - max(0, x)) for a, x in enumerate(d))
    dst = tuple(slice(max(0, x), shape[a] - max(0, -x)) for a, x in enumerate(d))
    return src, dst


def _components(mask: np.ndarray) -> np.ndarray:
    from scipy import ndimage

    labels, _ = ndimage.label(mask, structure=np.ones((3, 3, 3), dtype=bool))
    return labels


def _setup(cspace, b: np.ndarray):
    """The C-obstacles to label cells with (a lazy C-space's pairs near the bounds built
    first), their boxes, the largest ``error_bound`` and the free label's margin."""
    if hasattr(cspace, "build"):  # LazyCSpace: every pair that may meet the bounds, now
        cspace.build(b[0], b[1])
    obstacles = list(cspace.obstacles)
    boxes = np.array([np.asarray(co.bounds, dtype=np.float64)
                      for co in obstacles]).reshape(-1, 2, 3)
    clearance = max((float(co.error_bound) for co in obstacles), default=0.0)
    margin = _FREE_MARGIN * float(np.abs(b).max() + (b[1] - b[0]).max())
    return obstacles, boxes, clearance, margin


def _free_leaf_graph(ids: np.ndarray, free: np.ndarray, n: int):
    """(n, n) csr: leaves ``i`` and ``j`` (of the painted grid ``ids``) touch through two free
    voxels, 26-neighbours."""
    from scipy.sparse import coo_matrix

    a_all, b_all = [], []
    for d in _NEIGHBOURS:
        src, dst = _shift(ids.shape, d)
        both = free[src] & free[dst]
        a, c = ids[src][both], ids[dst][both]
        a_all.append(a[a != c])
        b_all.append(c[a != c])
    A, B = np.concatenate(a_all), np.concatenate(b_all)
    G = coo_matrix((np.ones(len(A)), (A, B)), shape=(n, n)).tocsr()
    return G + G.T


def _shortcut(cspace, P: np.ndarray) -> np.ndarray:
    """Greedy: from each kept waypoint, the farthest later one in straight sight (exact)."""
    out, i = [P[0]], 0
    while i < len(P) - 1:
        later = np.arange(len(P) - 1, i, -1)
        ok = cspace.segment_free(np.broadcast_to(P[i], (len(later), 3)), P[later])
        j = int(later[np.argmax(ok)]) if ok.any() else i + 1
        out.append(P[j])
        i = j
    return np.array(out)


def _polyline(cspace, q0, q1, lo: np.ndarray, hi: np.ndarray, chain,
              frame: _Frame | None = None) -> np.ndarray | None:
    """From ``q0`` in the closed box ``chain[0]`` to ``q1`` in ``chain[-1]`` through the boxes
    ``[lo[i], hi[i]]`` of ``chain``, each touching the next: their centres and the middles of
    their contacts (two waypoints in a row share a box, a convex set), shortcut; every segment
    proved by ``segment_free``, else None. With a turned ``frame`` the boxes are its own: the
    waypoints are turned into the scene and moved into its bounds (a box may cross them)."""
    pts = [(lo[chain[0]] + hi[chain[0]]) / 2]
    for u, v in zip(chain, chain[1:]):
        pts.append((np.maximum(lo[u], lo[v]) + np.minimum(hi[u], hi[v])) / 2)  # their contact
        pts.append((lo[v] + hi[v]) / 2)
    pts = np.array(pts)
    if frame is not None:
        pts = frame.clip(frame.world(pts))
    P = _shortcut(cspace, np.vstack([q0, pts, q1]))
    ok = cspace.segment_free(P[:-1], P[1:])
    return P if bool(np.all(ok)) else None
