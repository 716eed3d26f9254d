"""Deciding a translation problem before sampling it: certified cells of the free space.

At one orientation the robot goes from start to goal exactly when both lie in one connected
component of ``F = bounds - U CO``. :func:`decide` labels the cells of an octree over the
planning bounds:

``blocked``
    The closed cell lies inside one convex piece of one C-obstacle: its eight corners are in
    that piece, by the piece's exact point test (a convex piece holds the hull of its
    points). Exact; a cell inside the union of several pieces but no single one is not
    blocked (it stays passable: never a false proof). Inside a non-convex sum (kind
    ``'mesh'``): its centre is inside (exact) and farther from the surface than its
    half-diagonal plus ``2**-20`` of the C-obstacle's size (a float distance, accurate to a
    few ulps: the margin is what makes it certain).
``free``
    Every C-obstacle whose box meets the cell is kept off it: a convex piece by one of its
    facet planes (the cell's support value beyond the plane by more than ``2**-30`` of the
    magnitudes), any other kind by a clearance of the cell's centre above its half-diagonal
    plus ``2**-20`` of the scene's size (:meth:`CSpaceObstacle.signed_distance`, accurate to
    a few ulps). Float, with those margins: this label only stops refinement and routes the
    path below; it never enters a proof, and every segment of a path through free cells is
    re-proved with :meth:`CSpace.segment_free`.
``mixed``
    Neither: split in eight, down to ``depth`` (the finest cells are ``2**-depth`` of the
    bounds per axis); a mixed cell at that depth stays passable.

**"no path"**: the union ``P`` of the closed cells not blocked holds every free translation in
the bounds, so a path would lie in one connected component of ``P``. Closed cells touching at a
face, an edge or a corner are connected (26-connectivity on the finest grid; cell corners are
float64 functions of integer indices, the same for neighbours, strictly increasing, so touching
is decided on the integers). Start and goal in different components of ``P``: no path. The
C-obstacles are grown outward within their ``error_bound`` (principle 2), so the statement is
"no path with a clearance above ``error_bound``"; it is never made where such a path exists.

**"path"**: start and goal joined through free cells (a polyline through the cells' centres and
the middles of their contacts, shortcut), every segment proved by ``segment_free``.

A C-space of the robot's convex hull (``robot_hull=True``) proves nothing about the robot:
its "no path" is reported as "unknown".

**"unknown"**: neither within the depth and the time given (walls whose C-obstacles only
touch, or thinner than a finest cell; a gap narrower than a finest cell). The planners then
run as without the decision.

This is a certified cell decomposition (as in Zhang, Kim and Manocha, "Path non-existence
computation using C-obstacle query", 2008), with the cells' labels decided exactly; the
exact union of the C-obstacles (issue #31) would remove the depth limit.
"""

from __future__ import annotations

import time as _time
import weakref
from dataclasses import dataclass

import numpy as np

from ..errors import InvalidArgumentError

#: Cell labels.
BLOCKED, MIXED, FREE = 0, 1, 2
#: Answers of :func:`decide`.
ANSWERS = ("no path", "path", "unknown")
#: The first level cut into cells (8 per axis), and the default finest level.
FIRST_LEVEL, DEPTH = 3, 7
# The free label's margin, relative to the bounds' size (signed_distance's float error is a
# few ulps of the coordinates; 2**-20 is far above it and far below any cell).
_FREE_MARGIN = 2.0 ** -20
_CORNERS = np.array([[i, j, k] for i in (0, 1) for j in (0, 1) for k in (0, 1)], dtype=np.int64)
_NEIGHBOURS = [(i, j, k) for i in (-1, 0, 1) for j in (-1, 0, 1) for k in (-1, 0, 1)
               if (i, j, k) > (0, 0, 0)]


class _OutOfTime(Exception):
    pass


@dataclass(repr=False)
class Decision:
    """What :func:`decide` found for one start and goal at one orientation.

    Attributes
    ----------
    answer : {'no path', 'path', 'unknown'}
    path : (n, 3) float64 or None
        With ``'path'``: start to goal, every segment proved free (``segment_free``).
    clearance : float
        With ``'no path'``: the statement holds for paths whose clearance exceeds this
        (the largest ``error_bound`` of the C-obstacles), scene units.
    depth : int
        The finest level reached (cells ``2**-depth`` of the bounds per axis).
    bounds : (2, 3) float64
    cells_lo, cells_hi : (k, 3) float64
        The leaf cells (closed boxes, scene frame), and ``labels`` (k,) int8 of theirs.
    start_component : (k,) bool
        The passable leaves connected to the start (with ``'no path'``: the region the
        robot cannot leave).
    wall : (k,) bool
        The blocked leaves touching the start's component: with ``'no path'``, the wall
        that proves it (each inside one convex piece of a C-obstacle).
    time : float
        Wall seconds.
    reason : str
        Why the answer is what it is, one line.
    """

    answer: str
    path: np.ndarray | None
    clearance: float
    depth: int
    bounds: np.ndarray
    cells_lo: np.ndarray
    cells_hi: np.ndarray
    labels: np.ndarray
    start_component: np.ndarray
    wall: np.ndarray
    time: float
    reason: str

    def __repr__(self) -> str:
        n = {k: int(np.count_nonzero(self.labels == v))
             for k, v in (("blocked", BLOCKED), ("mixed", MIXED), ("free", FREE))}
        return (f"Decision(answer={self.answer!r}, depth={self.depth}, cells={n}, "
                f"time={self.time:.3f})")

    def to_trimesh(self, which: str = "start"):
        """The cells as one mesh of boxes: ``'start'`` the start's component (with
        ``'no path'``: where the robot is confined), ``'blocked'`` the blocked cells around
        it (the wall that proves it)."""
        import trimesh

        if which == "start":
            keep = self.start_component
        elif which == "blocked":
            keep = self.wall
        else:
            raise InvalidArgumentError(f"which must be 'start' or 'blocked', got {which!r}")
        unit = trimesh.creation.box(bounds=[[0.0, 0.0, 0.0], [1.0, 1.0, 1.0]])
        lo, hi = self.cells_lo[keep], self.cells_hi[keep]
        V = lo[:, None, :] + np.asarray(unit.vertices)[None] * (hi - lo)[:, None, :]
        F = np.asarray(unit.faces)[None] + 8 * np.arange(len(lo))[:, None, None]
        return trimesh.Trimesh(V.reshape(-1, 3), F.reshape(-1, 3), process=False)


# --------------------------------------------------------------------------------------------
# the blocked label: inside one convex piece of one C-obstacle


def _inside_one_piece(co, lo: np.ndarray, hi: np.ndarray) -> np.ndarray:
    """(m,) bool: the closed box ``[lo[r], hi[r]]`` lies in one convex piece of ``co``
    (all eight corners in it, exactly). A non-convex sum (``'mesh'``): the cell's centre is
    inside (exact sign) and its distance to the surface exceeds the half-diagonal by
    ``2**-20`` of the C-obstacle's size (the distance is float, accurate to a few ulps of the
    coordinates, far below that margin), so the ball it spans, and the cell, are inside."""
    m = len(lo)
    C = np.where(_CORNERS[None].astype(bool), hi[:, None, :], lo[:, None, :])  # (m, 8, 3)
    kind = co.kind
    if kind == "convex":
        return co.contains(C.reshape(-1, 3)).reshape(m, 8).all(axis=1)
    if kind == "union":
        out = np.zeros(m, dtype=bool)
        for part in co.parts:
            rows = np.nonzero(~out)[0]
            if len(rows):
                out[rows] = _inside_one_piece(part, lo[rows], hi[rows])
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


# Each pair engine's pieces' half-spaces as the decision has needed them: (exact, float).
_HALFSPACES: weakref.WeakKeyDictionary = weakref.WeakKeyDictionary()
# The float filter of a half-space value n . x - d (x = corner / step, exact; n small ints;
# d rounded once to float): a few roundings of relative 2**-53 each; 2**-45 is far above.
_PLANE_FILTER = 2.0 ** -45


def _inside_a_pair(impl, lo, hi, C) -> np.ndarray:
    """:func:`_inside_one_piece` for a triangle-pair C-obstacle: the pieces whose k-DOPs meet
    a cell (the engine's tree), then each piece's half-spaces at the eight corners, in floats
    with the filter above and exactly (Python integers) where it cannot tell."""
    out = np.zeros(len(lo), dtype=bool)
    cand = impl._set.candidates(impl._grid_units(lo), impl._grid_units(hi))
    if not len(cand):
        return out
    cache = _HALFSPACES.setdefault(impl, {})
    X = np.ldexp(C, -impl.exponent)  # grid units, exact
    key = cand[:, 1] * (int(cand[:, 2].max()) + 1) + cand[:, 2]
    _, first, which = np.unique(key, return_index=True, return_inverse=True)
    for u, f in enumerate(first.tolist()):
        rows = cand[which == u, 0]
        rows = rows[~out[rows]]
        if not len(rows):
            continue
        i, j = int(cand[f, 1]), int(cand[f, 2])
        if (i, j) not in cache:
            H = impl._halfspaces(i, j)
            cache[i, j] = (H, np.array([n for n, _ in H], dtype=np.float64).reshape(-1, 3),
                           np.array([float(d) for _, d in H]))
        H, N, d = cache[i, j]
        val = X[rows] @ N.T - d  # (r, 8, h)
        err = _PLANE_FILTER * (np.abs(X[rows]) @ np.abs(N).T + np.abs(d))
        inside = (val < -err).all(axis=(1, 2))
        unsure = ~inside & ~(val > err).any(axis=(1, 2))
        for r in rows[unsure].tolist():
            inside[rows == r] = all(impl._in_piece(i, j, x) for x in C[r].tolist())
        out[rows[inside]] = True
    return out


def _kept_off(co, lo: np.ndarray, hi: np.ndarray, margin: float) -> np.ndarray:
    """(m,) bool: ``co`` certainly misses the closed box (see the ``free`` label)."""
    kind = co.kind
    if kind == "convex":
        e = co._impl.exponent
        A = co._impl.A
        c, h = np.ldexp((lo + hi) / 2, -e), np.ldexp((hi - lo) / 2, -e)
        val = c @ A[:3] + A[3] - h @ np.abs(A[:3])
        tol = 2.0 ** -30 * ((np.abs(c) + h) @ np.abs(A[:3]) + np.abs(A[3]))
        return (val > tol).any(axis=1)
    if kind in ("union", "surface"):  # every part (a surface's convex pieces) near the cell
        members = ([(np.asarray(p.bounds, dtype=np.float64), p) for p in co.parts]
                   if kind == "union" else
                   [(np.stack([co._impl.lo[j], co._impl.hi[j]]), _Piece(piece))
                    for j, piece in enumerate(co._impl.impl)])
        out = np.ones(len(lo), dtype=bool)
        for B, part in members:
            rows = np.nonzero(out & (lo <= B[1]).all(axis=1) & (B[0] <= hi).all(axis=1))[0]
            if len(rows):
                out[rows] = _kept_off(part, lo[rows], hi[rows], margin)
        return out
    half = np.linalg.norm(hi - lo, axis=1) / 2
    return co.signed_distance((lo + hi) / 2) > half + margin


class _Piece:
    """A surface's convex piece (its engine) seen as a convex C-obstacle by :func:`_kept_off`:
    its planes are a convex C-obstacle's."""

    kind = "convex"

    def __init__(self, impl):
        self._impl = impl


def _labels(obstacles, boxes: np.ndarray, lo: np.ndarray, hi: np.ndarray, margin: float,
            deadline: float) -> np.ndarray:
    """The label of each closed cell ``[lo[r], hi[r]]``."""
    free = _sweep(obstacles, boxes, lo, hi, True, False,
                  lambda co, a, b: _kept_off(co, a, b, margin), deadline)
    label = np.where(free, FREE, MIXED).astype(np.int8)
    rest = np.nonzero(~free)[0]
    label[rest[_sweep(obstacles, boxes, lo[rest], hi[rest], False, True, _inside_one_piece,
                      deadline)]] = BLOCKED
    return label


def _sweep(obstacles, boxes, lo, hi, initial: bool, within: bool, test, deadline) -> np.ndarray:
    """A flag per cell, ``initial`` until a C-obstacle whose box the cell meets (``within``:
    lies in) answers ``test(co, lo, hi)`` for it otherwise; past ``deadline``: out of time."""
    flag = np.full(len(lo), initial, dtype=bool)
    for k, co in enumerate(obstacles):
        if _time.perf_counter() > deadline:
            raise _OutOfTime
        B = boxes[k]
        near = ((B[0] <= lo) & (hi <= B[1]) if within else (lo <= B[1]) & (B[0] <= hi))
        rows = np.nonzero((flag == initial) & near.all(axis=1))[0]
        if len(rows):
            flag[rows] = test(co, lo[rows], hi[rows])
    return flag


# --------------------------------------------------------------------------------------------
# the octree


class _Grid:
    """The finest grid over the bounds: ``N[a]`` cells on axis ``a`` (1 on a flat axis), cell
    corner ``i`` at ``x[a][i]`` (float64, strictly increasing, the bounds' ends exact)."""

    def __init__(self, b: np.ndarray, depth: int):
        self.b = b
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

    def cells_at(self, q: np.ndarray, step: np.ndarray) -> np.ndarray:
        """Indices (in units of ``step``) of every cell of that size whose closed box holds
        ``q``: one or two per axis (``q`` on a corner plane belongs to both sides)."""
        per_axis = []
        for a in range(3):
            xs = self.x[a][:: int(step[a])]
            lo = max(int(np.searchsorted(xs, q[a], side="left")) - 1, 0)
            hi = min(int(np.searchsorted(xs, q[a], side="right")) - 1, len(xs) - 2)
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


def _octree(obstacles, boxes, margin: float, g: _Grid, depth: int, deadline: float):
    """Label the octree level by level. Yields ``(level, size, lo, sizes, labels, more)``
    after each: the leaves so far (integer corners and sizes in finest cells), with this
    level's cells still to split counted as mixed leaves; ``more``: some remain to split."""
    first = min(FIRST_LEVEL, depth)
    size = np.where(g.split, 1 << (depth - first), 1)
    n0 = g.N // size
    todo = np.stack(np.meshgrid(*[np.arange(n) for n in n0], indexing="ij"),
                    -1).reshape(-1, 3) * size
    leaves_lo, leaves_size, leaves_label = [], [], []
    for level in range(first, depth + 1):
        label = _labels(obstacles, boxes, g.floats(todo), g.floats(todo + size), margin, deadline)
        split = (label == MIXED) & (level < depth)
        keep = ~split
        leaves_lo.append(todo[keep])
        leaves_size.append(np.broadcast_to(size, (int(keep.sum()), 3)))
        leaves_label.append(label[keep])
        yield (level, size, np.concatenate(leaves_lo + [todo[split]]),
               np.concatenate(leaves_size + [np.broadcast_to(size, (int(split.sum()), 3))]),
               np.concatenate(leaves_label + [label[split]]), bool(split.any()))
        if not split.any():
            return
        half = np.where(g.split, size // 2, 1)
        offs = np.unique(_CORNERS * g.split, axis=0) * half  # flat axes: not cut
        todo = (todo[split][:, None, :] + offs[None]).reshape(-1, 3)
        size = half


def _paint(g: _Grid, size, L_lo, L_sz, L_lab):
    """The leaves on the grid of cells of ``size`` (leaves of earlier levels cover blocks of
    it): ``(ids, labels)`` per cell."""
    n = g.N // size
    ids = np.full(tuple(n.tolist()), -1, dtype=np.int64)
    I, W = L_lo // size, L_sz // size
    for w in np.unique(W, axis=0):  # leaves of one size at once: their blocks of voxels
        k = np.nonzero((W == w).all(axis=1))[0]
        off = np.stack(np.meshgrid(*[np.arange(x) for x in w], indexing="ij"), -1).reshape(-1, 3)
        V = (I[k][:, None, :] + off[None]).reshape(-1, 3)
        ids[V[:, 0], V[:, 1], V[:, 2]] = np.repeat(k, len(off))
    return ids, np.where(ids >= 0, L_lab[np.maximum(ids, 0)], BLOCKED)


def _endpoints(cspace, b, start, goal, check=True):
    q0 = np.asarray(start, dtype=np.float64).reshape(3)
    q1 = np.asarray(goal, dtype=np.float64).reshape(3)
    for name, q in (("start", q0), ("goal", q1)):
        if not ((b[0] <= q) & (q <= b[1])).all():
            raise InvalidArgumentError(f"{name} {q.tolist()} is outside the bounds {b.tolist()}")
        if check and cspace.contains(q):
            raise InvalidArgumentError(f"{name} {q.tolist()} is in collision")
    return q0, q1


#: The deepest level: the cells are painted on a dense grid of ``2**(3 depth)`` (at 8, 16.8 M
#: cells: about 0.4 GB of labels while components are found).
MAX_DEPTH = 8


def _depth(depth) -> int:
    if isinstance(depth, bool) or not isinstance(depth, (int, np.integer)) or not (
            1 <= int(depth) <= MAX_DEPTH):
        raise InvalidArgumentError(f"depth must be an int in 1..{MAX_DEPTH} (memory grows as "
                                   f"8**depth), got {depth!r}")
    return int(depth)


def decide(cspace, start, goal, *, bounds=None, depth: int = DEPTH, time: float = 2.0,
           progress=None) -> Decision:
    """Decide whether the robot can translate from ``start`` to ``goal``, by certified cells.

    Parameters
    ----------
    cspace : CSpace
        The C-obstacles at one orientation (``model_scene(scene).cspace()``; a lazy one's
        pairs near the bounds are built first).
    start, goal : (3,) float64
        Free translations inside ``bounds`` (scene units, scene frame).
    bounds : (2, 3) float64, optional
        Where the robot may go; default ``cspace.bounds``.
    depth : int, default 7
        The finest cells are ``2**-depth`` of the bounds per axis.
    time : float, default 2.0
        Wall-second budget; past it the answer is ``'unknown'`` (the levels done still say
        "no path" if they proved it).
    progress : callable, optional
        ``progress(fraction, message)`` after each level.

    Returns
    -------
    Decision
        ``'no path'`` (proved, for clearances above ``Decision.clearance``), ``'path'`` (a
        proved polyline) or ``'unknown'``. See the module docstring for what each means.
    """
    t0 = _time.perf_counter()
    deadline = t0 + float(time)
    depth = _depth(depth)
    b = np.asarray(cspace.bounds if bounds is None else bounds, dtype=np.float64).reshape(2, 3)
    q0, q1 = _endpoints(cspace, b, start, goal)
    g = _Grid(b, depth)
    obstacles, boxes, clearance, margin = _setup(cspace, b)
    first = min(FIRST_LEVEL, depth)
    answer, reason, reached, path = "unknown", "", first - 1, None
    L = (np.zeros((0, 3), np.int64), np.zeros((0, 3), np.int64), np.zeros(0, np.int8))
    comp_start = wall = None
    try:
        for level, size, L_lo, L_sz, L_lab, more in _octree(obstacles, boxes, margin, g, depth,
                                                            deadline):
            reached, L = level, (L_lo, L_sz, L_lab)
            answer, reason, path, comp_start, wall = _decide_level(
                cspace, g, q0, q1, L_lo, L_sz, L_lab, size, level)
            if progress is not None:
                progress((level - first + 1) / (depth - first + 1), f"level {level}: {answer}")
            if answer != "unknown":
                break
    except _OutOfTime:
        reason, comp_start = f"out of time at level {reached + 1}", None
    if answer == "no path" and getattr(cspace, "robot_hull", False):
        answer = "unknown"
        reason = f"no path for the robot's convex hull ({reason}): no proof for the robot"
    if answer == "unknown" and not reason:
        reason = f"no wall found and no free route at depth {reached}"
    L_lo, L_sz, L_lab = L
    if comp_start is None or len(comp_start) != len(L_lo):  # out of time: none
        comp_start = wall = np.zeros(len(L_lo), dtype=bool)
    return Decision(answer=answer, path=path, clearance=clearance, depth=reached, bounds=b,
                    cells_lo=g.floats(L_lo), cells_hi=g.floats(L_lo + L_sz), labels=L_lab,
                    start_component=comp_start, wall=wall,
                    time=_time.perf_counter() - t0, reason=reason)


def _decide_level(cspace, g: _Grid, q0, q1, L_lo, L_sz, L_lab, size, level):
    """Components of the passable and of the free leaves on this level's grid:
    ``(answer, reason, path, start component mask, wall mask)``."""
    ids, lab = _paint(g, size, L_lo, L_sz, L_lab)
    comp = _components(lab != BLOCKED)
    at0, at1 = g.cells_at(q0, size), g.cells_at(q1, size)
    c0 = {int(comp[tuple(i)]) for i in at0} - {0}
    c1 = {int(comp[tuple(i)]) for i in at1} - {0}
    start_mask, wall = np.zeros(len(L_lo), dtype=bool), np.zeros(len(L_lo), dtype=bool)
    if c0:
        from scipy import ndimage

        cells = np.isin(comp, list(c0))
        start_mask[np.unique(ids[cells])] = True
        around = ndimage.binary_dilation(cells, structure=np.ones((3, 3, 3), dtype=bool))
        wall[np.unique(ids[around & (lab == BLOCKED)])] = True
    if c0 and c1 and not (c0 & c1):
        return ("no path", f"start and goal in different components at level {level}", None,
                start_mask, wall)
    path = _free_route(cspace, g, q0, q1, ids, lab, L_lo, L_sz, size, at0, at1)
    if path is not None:
        return "path", f"a route through free cells at level {level}", path, start_mask, wall
    return "unknown", "", None, start_mask, wall


def _free_route(cspace, g, q0, q1, ids, lab, L_lo, L_sz, size, at0, at1):
    """A polyline through free leaves from ``q0`` to ``q1`` (both in free cells), every segment
    proved, or None."""
    from scipy.sparse import coo_matrix
    from scipy.sparse.csgraph import breadth_first_order

    free = lab == FREE
    s0 = [int(ids[tuple(i)]) for i in at0 if free[tuple(i)]]
    s1 = [int(ids[tuple(i)]) for i in at1 if free[tuple(i)]]
    if not s0 or not s1:
        return None
    # leaf adjacency through touching free voxels (26 neighbours)
    a_all, b_all = [], []
    shape = ids.shape
    for d in _NEIGHBOURS:
        src, dst = _shift(shape, d)
        both = free[src] & free[dst]
        a, c = ids[src][both], ids[dst][both]
        keep = a != c
        a_all.append(a[keep])
        b_all.append(c[keep])
    A, B = np.concatenate(a_all), np.concatenate(b_all)
    n = len(L_lo)
    G = coo_matrix((np.ones(len(A)), (A, B)), shape=(n, n)).tocsr()
    G = G + G.T
    order, pred = breadth_first_order(G, s0[0], directed=False, return_predecessors=True)
    target = next((t for t in s1 if t == s0[0] or pred[t] >= 0), None)
    if target is None:
        return None
    chain = [target]
    while chain[-1] != s0[0]:
        chain.append(int(pred[chain[-1]]))
    chain.reverse()
    lo = g.floats(L_lo)
    hi = g.floats(L_lo + L_sz)
    pts = [q0, (lo[chain[0]] + hi[chain[0]]) / 2]
    for u, v in zip(chain, chain[1:]):
        pts.append((np.maximum(lo[u], lo[v]) + np.minimum(hi[u], hi[v])) / 2)  # their contact
        pts.append((lo[v] + hi[v]) / 2)
    pts.append(q1)
    P = _shortcut(cspace, np.array(pts))
    ok = cspace.segment_free(P[:-1], P[1:])
    return P if bool(np.all(ok)) else None


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


# --------------------------------------------------------------------------------------------
# with turns: the components of every orientation, joined where a turn could join them


@dataclass(repr=False)
class TurningDecision:
    """What :func:`decide_turning` found over a set of orientations.

    ``answer`` is ``'no path'`` or ``'unknown'``: no sequence of translations at the set's
    orientations and turns in place between neighbouring ones (as
    :meth:`cspace.planning.turning.TurningCSpace.motion_free` certifies them) joins start
    and goal, with a clearance above ``clearance``. Not a proof over all rotations.
    ``components``: the passable components of each orientation; ``links``: the pairs of
    components of neighbouring orientations a turn could join."""

    answer: str
    reason: str
    clearance: float
    depth: int
    components: list
    links: int
    time: float

    def __repr__(self) -> str:
        return (f"TurningDecision(answer={self.answer!r}, orientations={len(self.components)}, "
                f"components={sum(self.components)}, links={self.links}, time={self.time:.3f})")


def decide_turning(tcs, start, goal, *, depth: int = 6, time: float = 10.0) -> TurningDecision:
    """Decide over orientations: can the robot go from ``start`` (at orientation 0) to
    ``goal`` (at ``tcs.slices.goal``) by translations at the orientations of ``tcs`` and turns
    in place between neighbouring ones?

    Each orientation's cells are labelled to ``depth`` as in :func:`decide`, and its passable
    cells split into components (closed cells, 26-connected). A certified turn in place at
    ``q`` between neighbouring orientations ``i`` and ``j`` needs ``q`` free at both, so ``q``
    lies in a passable cell of each: those two cells coincide or touch. Components of ``i``
    and ``j`` with cells that coincide or touch are linked (a superset of the turns there
    are). Start and goal in different classes of the linked components: ``'no path'``.

    Parameters
    ----------
    tcs : TurningCSpace
        The orientations (``tcs.slices``) and their C-spaces (``tcs.slice(k)``), over
        ``tcs.bounds``.
    start, goal : (3,) float64
    depth : int, default 6
    time : float, default 10.0
        Past it: ``'unknown'``.
    """
    from scipy.sparse import coo_matrix
    from scipy.sparse.csgraph import connected_components

    t0 = _time.perf_counter()
    deadline = t0 + float(time)
    depth = _depth(depth)
    b = np.asarray(tcs.bounds, dtype=np.float64).reshape(2, 3)
    slices = tcs.slices
    n = len(slices)
    g = _Grid(b, depth)
    labels, counts, clearance = [], [], 0.0
    try:
        for k in range(n):
            cs = tcs.slice(k)
            obstacles, boxes, bound, margin = _setup(cs, b)
            clearance = max(clearance, bound)
            for _, _size, L_lo, L_sz, L_lab, _more in _octree(obstacles, boxes, margin, g, depth,
                                                              deadline):
                pass
            # on the finest grid, whatever level the slice stopped at: one shape for all
            _, lab = _paint(g, np.ones(3, dtype=np.int64), L_lo, L_sz, L_lab)
            comp = _components(lab != BLOCKED)
            labels.append(comp)
            counts.append(int(comp.max()))
    except _OutOfTime:
        return TurningDecision("unknown", f"out of time at orientation {len(labels)} of {n}",
                               clearance, depth, counts, 0, _time.perf_counter() - t0)
    offset = np.concatenate([[0], np.cumsum(counts)])  # node of (k, c): offset[k] + c - 1
    A, B = [], []
    shape = labels[0].shape
    for i in range(n):
        for j in range(i + 1, n):
            if not slices.neighbours(i, j):
                continue
            for d in [(x, y, z) for x in (-1, 0, 1) for y in (-1, 0, 1) for z in (-1, 0, 1)]:
                src, dst = _shift(shape, d)
                u, v = labels[i][src], labels[j][dst]
                both = (u > 0) & (v > 0)
                key = np.unique(u[both].astype(np.int64) * (counts[j] + 1) + v[both])
                A.append(offset[i] + key // (counts[j] + 1) - 1)
                B.append(offset[j] + key % (counts[j] + 1) - 1)
    A = np.concatenate(A) if A else np.zeros(0, np.int64)
    B = np.concatenate(B) if B else np.zeros(0, np.int64)
    m = int(offset[-1])
    _, cls = connected_components(coo_matrix((np.ones(len(A)), (A, B)), shape=(m, m)),
                                  directed=False)
    one = np.ones(3, dtype=np.int64)
    q0, q1 = (np.asarray(q, dtype=np.float64).reshape(3) for q in (start, goal))

    def classes(q, k):
        return {int(cls[offset[k] + c - 1]) for c in
                (int(labels[k][tuple(i)]) for i in g.cells_at(q, one)) if c > 0}

    c0, c1 = classes(q0, 0), classes(q1, slices.goal)
    links = len(np.unique(A * max(m, 1) + B))
    if c0 and c1 and not (c0 & c1) and getattr(tcs, "robot_hull", False):
        answer, reason = "unknown", "no path for the robot's convex hull: no proof for the robot"
    elif c0 and c1 and not (c0 & c1):
        answer, reason = "no path", (f"start and goal in different components over {n} "
                                     "orientations joined by turns between neighbours")
    else:
        answer, reason = "unknown", f"start and goal may be joined at depth {depth}"
    return TurningDecision(answer, reason, clearance, depth, counts, links,
                           _time.perf_counter() - t0)
