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
    facet planes (the cell's support value beyond the plane by more than ``2**-42`` of the
    magnitudes), a triangle-pair C-obstacle by a slab of each piece whose k-DOP meets the cell
    (the eight corners beyond it, by the engine's float filter; compiled), any other kind by a
    clearance of the cell's centre above its half-diagonal
    plus ``2**-20`` of the scene's size (:meth:`CSpaceObstacle.signed_distance`, accurate to
    a few ulps). Float, with those margins: this label only stops refinement and routes the
    path below; it never enters a proof, and every segment of a path through free cells is
    re-proved with :meth:`CSpace.segment_free`.
``mixed``
    Neither: split in eight, down to ``depth`` (the finest cells are ``2**-depth`` of the
    bounds per axis); a mixed cell at that depth stays passable.

**"no path"**: the union ``P`` of the closed cells not blocked holds every free translation in the
bounds (every translation with a clearance above ``Decision.clearance``, when the refinement below
blocked cells near a piece: see there), so a path would lie in one connected component of ``P``.
Closed cells touching at a face, an edge or a corner are connected (26-connectivity on the finest
grid; cell corners are float64 functions of integer indices, the same for neighbours, strictly
increasing, so touching is decided on the integers). Start and goal in different components of
``P``: no path. The C-obstacles are grown outward within their ``error_bound`` (principle 2), so the
statement is "no path with a clearance above ``Decision.clearance``" (``error_bound``, plus the
refinement's nudge when its wall used it); it is never made where such a path exists.

**"path"**: start and goal joined through free cells (a polyline through the cells' centres and
the middles of their contacts, shortcut), every segment proved by ``segment_free``.

A C-space of the robot's convex hull (``robot_hull=True``) proves nothing about the robot:
its "no path" is reported as "unknown".

**Below the finest level**: undecided there, :func:`.corridor.refine_route` splits the mixed
cells along the cheapest route between start and goal, again and again (a gap narrower than a
cell; a wall the octree's cells could not fill), into slabs and bars where the labels change
across one axis only. Its "path" means the same. Its cells may also be blocked ``near`` a piece:
a cell whose copy moved by at most ``nudge`` lies inside one convex piece (exact test on the
moved corners; :func:`.cells._nudged`). That is how C-obstacles that only touch (along a face,
an edge, at a vertex; a slot exactly the robot's width) are walled, which no cell inside one
piece can do. ``nudge`` is half the largest ``error_bound``, at least four of the refinement's
finest sides; a proof that used such cells holds for clearances above ``error_bound + nudge``,
and ``Decision.clearance`` says so.

**The cells' frame**: the cells are boxes along the scene's axes, or, where more of the
C-obstacles' facet normals lie along a turned frame's axes (a turned cage, a slanted slot),
boxes of that frame (``frame='auto'``; :class:`.cells._Frame`): cells along a slanted wall or
gap then fill it as the scene's axes fill an aligned one. The labels are the same exact tests
on the cells' corners turned into the scene; the corners' rounding (``2**-48`` of the
coordinates) is added to ``Decision.clearance``, and cells wholly outside the bounds (the
frame's box is larger than theirs) are blocked: no motion leaves the bounds.

**"unknown"**: neither within the time given (a wall too large to fill with the cells the
budget allows). The planners then run as without the decision.

This is a certified cell decomposition (as in Zhang, Kim and Manocha, "Path non-existence
computation using C-obstacle query", 2008), with the cells' labels decided exactly.

**First, exactly**: where every C-obstacle meeting the bounds is made of convex pieces,
:func:`decide` first makes the exact free space (:func:`cspace.planning.free_space.free_space`:
the pieces grown onto one grid, their union's arrangement and its cells). Start and goal in
different components answer "no path" at once, with the closed surface that separates them
(``Decision.separation``; clearance: its ``error_bound``). In one component, the cells above
look for the path, and if they find none in time the reason says that a path exists (the grown
union holds the C-obstacles, so its free space is free). A solid body's non-convex sum, which
the free space takes as the scene's triangle pairs (many overlapping pieces: seconds), waits
for the octree's levels, which decide most such scenes in milliseconds; the exact free space
comes before the refinement along routes. Scenes of more pieces than the free space takes are
decided by the cells alone.
"""

from __future__ import annotations

import time as _time
from dataclasses import dataclass

import numpy as np

from ..errors import ExactnessError, InvalidArgumentError, MemoryBudgetError, UnsupportedError
from ..scene.model import CSpace
from .cells import (BLOCKED, FREE, MIXED, NEAR, _CORNERS, _choose_frame, _components, _Frame,
                    _free_leaf_graph, _Grid, _labels, _OutOfTime, _polyline, _setup, _shift)
from .corridor import EXTRA, refine_route
from .free_space import FreeSpace, Separation, free_space, unites_sums_as_pairs

#: Answers of :func:`decide`.
ANSWERS = ("no path", "path", "unknown")
#: The first level cut into cells (8 per axis), and the default finest level.
FIRST_LEVEL, DEPTH = 3, 7
#: The share of its budget :func:`decide` gives the exact free space (the cells get the rest).
EXACT_SHARE = 0.5


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
        (the largest ``error_bound`` of the C-obstacles, plus the refinement's ``nudge``
        when its wall has cells near a piece), scene units.
    depth : int
        The finest level reached (cells ``2**-depth`` of the bounds per axis).
    bounds : (2, 3) float64
    frame : (3, 3) float64
        The cells' frame: a cell's point ``x`` is the scene point ``frame @ x`` (the
        identity, or a frame turned to the C-obstacles' faces: :func:`decide`'s ``frame``).
    cells_lo, cells_hi : (k, 3) float64
        The leaf cells (closed boxes in ``frame``), and ``labels`` (k,) int8 of theirs: the
        octree's finest level reached, then the cells the refinement below it proved
        blocked (``BLOCKED`` inside a piece, or, in a turned frame, wholly outside the
        bounds; ``NEAR`` within the nudge of one).
    start_component : (k,) bool
        The passable leaves connected to the start (with ``'no path'``: the region the
        robot cannot leave).
    wall : (k,) bool
        The blocked leaves touching the start's component: with ``'no path'``, the wall
        that proves it (each inside one convex piece of a C-obstacle, or near one; the cells
        outside the bounds that close it in a turned frame are not listed); a proof
        found by the refinement adds every cell it proved blocked (a superset of the wall's
        refined part).
    time : float
        Wall seconds.
    reason : str
        Why the answer is what it is, one line.
    free_space : FreeSpace or None
        The exact free space, when the C-obstacles are made of convex pieces
        (:func:`cspace.planning.free_space.free_space`).
    separation : Separation or None
        With ``'no path'`` from the exact free space: the closed surface of the grown
        C-obstacles' union around the start's component that proves it (the cells are then
        empty).
    """

    answer: str
    path: np.ndarray | None
    clearance: float
    depth: int
    bounds: np.ndarray
    frame: np.ndarray
    cells_lo: np.ndarray
    cells_hi: np.ndarray
    labels: np.ndarray
    start_component: np.ndarray
    wall: np.ndarray
    time: float
    reason: str
    free_space: FreeSpace | None = None
    separation: Separation | None = None

    def __repr__(self) -> str:
        n = {k: int(np.count_nonzero(self.labels == v))
             for k, v in (("blocked", BLOCKED), ("near", NEAR), ("mixed", MIXED),
                          ("free", FREE))}
        return (f"Decision(answer={self.answer!r}, depth={self.depth}, cells={n}, "
                f"time={self.time:.3f})")

    def to_trimesh(self, which: str = "start"):
        """The cells as one mesh of boxes: ``'start'`` the start's component (with
        ``'no path'``: where the robot is confined), ``'blocked'`` the blocked cells around
        it (the wall that proves it)."""
        import trimesh

        if self.separation is not None and which in ("start", "blocked"):
            return self.separation.to_trimesh()  # the start component's boundary: the wall
        if which == "start":
            keep = self.start_component
        elif which == "blocked":
            keep = self.wall
        else:
            raise InvalidArgumentError(f"which must be 'start' or 'blocked', got {which!r}")
        unit = trimesh.creation.box(bounds=[[0.0, 0.0, 0.0], [1.0, 1.0, 1.0]])
        lo, hi = self.cells_lo[keep], self.cells_hi[keep]
        V = lo[:, None, :] + np.asarray(unit.vertices)[None] * (hi - lo)[:, None, :]
        V = V @ self.frame.T
        F = np.asarray(unit.faces)[None] + 8 * np.arange(len(lo))[:, None, None]
        return trimesh.Trimesh(V.reshape(-1, 3), F.reshape(-1, 3), process=False)


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
        label = _labels(obstacles, boxes, g.floats(todo), g.floats(todo + size), margin, deadline,
                        frame=g.frame)
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


def _nudge(b: np.ndarray, depth: int, clearance: float) -> float:
    """How near a piece a refined cell may be to count as blocked (:func:`.cells._nudged`):
    half the C-obstacles' ``error_bound``, and at least four of the refinement's finest
    sides (its cells must get thinner than half of it), scene units."""
    return max(clearance / 2, 4.0 * float((b[1] - b[0]).max()) / 2.0 ** (depth + EXTRA))


def _depth(depth) -> int:
    if isinstance(depth, bool) or not isinstance(depth, (int, np.integer)) or not (
            1 <= int(depth) <= MAX_DEPTH):
        raise InvalidArgumentError(f"depth must be an int in 1..{MAX_DEPTH} (memory grows as "
                                   f"8**depth), got {depth!r}")
    return int(depth)


def decide(cspace, start, goal, *, bounds=None, depth: int = DEPTH, time: float = 2.0,
           refine: bool = True, frame="auto", exact: bool = True, progress=None) -> Decision:
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
    refine : bool, default True
        When the octree ends undecided, go on below ``depth`` along routes between start
        and goal (:func:`cspace.planning.corridor.refine_route`), up to
        ``2**-(depth + 20)`` of the bounds: gaps finer than the octree's cells.
    frame : 'auto', None or (3, 3) float64
        The axes the cells are cut along (columns, orthonormal). ``'auto'``: turned to the
        C-obstacles' faces where more of their facet normals lie along its axes than along
        the scene's (a turned box, a turned slot: cells along them fill a wall or a gap that
        the scene's axes would need ever finer cells for); None: the scene's axes. Only
        where cells are cut depends on it: the labels stay exact, and a proof in a turned
        frame holds for clearances above ``error_bound`` plus ``2**-48`` of the coordinates
        (the turned corners' rounding, :class:`cspace.planning.cells._Frame`).
    exact : bool, default True
        First make the exact free space (:func:`cspace.planning.free_space.free_space`), when
        the C-obstacles are made of convex pieces: start and goal in different components
        answer ``'no path'`` at once (for clearances above its ``error_bound``); in the same
        one, the cells below look for the path. It gets at most ``EXACT_SHARE`` (half) of
        the time left; past that the cells decide alone. Where it would take a non-convex sum
        as triangle pairs, it comes after the octree's levels, before the refinement.
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
    obstacles, boxes, clearance, margin = _setup(cspace, b)
    F = _frame(frame, obstacles, b)
    fs, one = None, False

    def exact_first() -> tuple:
        """The exact free space, in EXACT_SHARE of the time left at most: (fs, separation,
        start and goal joined), or Nones."""
        try:
            # a union too large for its share leaves the cells the rest
            left = max(0.0, deadline - _time.perf_counter())
            got = free_space(cspace, b, time=EXACT_SHARE * left)
            sep = got.separation(q0, q1)
            return got, sep, sep is None and got.joined(q0, q1)
        except (UnsupportedError, TimeoutError, MemoryBudgetError):
            return None, None, False  # too many pieces, or too large: the cells alone
        except ExactnessError:  # pragma: no cover - the lines' joins and the windings differ
            return None, None, False  # no proof from it: the cells decide

    # A non-convex sum the free space would unite as triangle pairs (many overlapping
    # pieces: seconds) waits for the octree, which decides most such scenes in milliseconds;
    # otherwise the exact free space comes first (milliseconds for convex pieces).
    exact = exact and not getattr(cspace, "robot_hull", False)
    deferred = exact and unites_sums_as_pairs(cspace, b)
    if exact and not deferred:
        fs, sep, one = exact_first()
        if sep is not None:
            return _separated(fs, sep, b, t0)
    g = _Grid(b, depth, F)
    first = min(FIRST_LEVEL, depth)
    answer, reason, reached, path = "unknown", "", first - 1, None
    L = (np.zeros((0, 3), np.int64), np.zeros((0, 3), np.int64), np.zeros(0, np.int8))
    comp_start = wall = None
    # cells the refinement proved blocked, and their labels
    refined = (np.zeros((0, 3)), np.zeros((0, 3)), np.zeros(0, np.int8))
    nudge = _nudge(g.b, depth, clearance)  # the grid's box: a turned frame's is larger
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
        else:  # the octree ended undecided: on below its finest level, along routes
            if deferred:
                fs, sep, one = exact_first()
                if sep is not None:
                    return _separated(fs, sep, b, t0)
            if refine and L[0].size:
                ids, lab = _paint(g, size, *L)
                answer, reason, path, refined = refine_route(
                    cspace, g, q0, q1, ids, lab, L[0], L[1], size, obstacles, boxes, margin,
                    deadline, g.cells_at(q0, size), g.cells_at(q1, size), nudge)
                if answer == "no path" and (refined[2] == NEAR).any():
                    clearance += nudge  # the wall holds cells within the nudge of a piece
    except _OutOfTime:
        reason, comp_start = f"out of time at level {reached + 1}", None
    if answer == "no path" and getattr(cspace, "robot_hull", False):
        answer = "unknown"
        reason = f"no path for the robot's convex hull ({reason}): no proof for the robot"
    if answer == "unknown" and not reason:
        reason = f"no wall found and no free route at depth {reached}"
    if answer == "unknown" and one:
        # one component of the grown union's complement: a path exists (the grown union
        # holds the C-obstacles), the cells only did not find it in time
        reason += ("; start and goal are in one component of the exact free space: a path "
                   "exists")
    L_lo, L_sz, L_lab = L
    if comp_start is None or len(comp_start) != len(L_lo):  # out of time: none
        comp_start = wall = np.zeros(len(L_lo), dtype=bool)
    k = len(refined[0])  # the refined wall after the octree's leaves
    lo = np.vstack([g.floats(L_lo), refined[0]])
    hi = np.vstack([g.floats(L_lo + L_sz), refined[1]])
    wall = np.concatenate([wall, np.full(k, answer == "no path")])
    if F is not None:  # cells outside the bounds close the wall; they are not C-obstacles'
        wall &= ~F.outside(F.corners(lo, hi))
        if answer == "no path":
            clearance += F.rho
    return Decision(answer=answer, path=path, clearance=clearance, depth=reached, bounds=b,
                    frame=np.eye(3) if F is None else F.M, cells_lo=lo, cells_hi=hi,
                    labels=np.concatenate([L_lab, refined[2]]),
                    start_component=np.concatenate([comp_start, np.zeros(k, bool)]),
                    wall=wall, time=_time.perf_counter() - t0, reason=reason, free_space=fs)


def _separated(fs: FreeSpace, sep: Separation, b: np.ndarray, t0: float) -> Decision:
    """The decision 'no path' from the exact free space's separation."""
    none = np.zeros((0, 3))
    reason = (f"start and goal in different components of the exact free space "
              f"({fs.n_components} components of the bounds minus {fs.n_pieces} convex pieces "
              f"grown onto one grid; the start's component's boundary, {len(sep.faces)} "
              f"triangles, winds {sep.winding[0]} about the start and {sep.winding[1]} about "
              f"the goal)")
    return Decision(answer="no path", path=None, clearance=fs.error_bound, depth=0, bounds=b,
                    frame=np.eye(3), cells_lo=none, cells_hi=none, labels=np.zeros(0, np.int8),
                    start_component=np.zeros(0, bool), wall=np.zeros(0, bool),
                    time=_time.perf_counter() - t0, reason=reason, free_space=fs,
                    separation=sep)


def _frame(frame, obstacles, b: np.ndarray) -> _Frame | None:
    """:func:`decide`'s ``frame`` argument as a :class:`_Frame` (None: the scene's axes)."""
    if isinstance(frame, str):
        if frame != "auto":
            raise InvalidArgumentError(f"frame must be 'auto', None or a (3, 3) array, got "
                                       f"{frame!r}")
        M = _choose_frame(obstacles, b)
    elif frame is None:
        return None
    else:
        M = np.asarray(frame, dtype=np.float64)
        if M.shape != (3, 3) or not np.isfinite(M).all():
            raise InvalidArgumentError(f"frame must be a (3, 3) array, got shape {M.shape}")
        if not (b[1] > b[0]).all():
            raise InvalidArgumentError("a turned frame needs bounds with a width on every axis")
    return None if M is None else _Frame(M, b)


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
    from scipy.sparse.csgraph import breadth_first_order

    free = lab == FREE
    s0 = [int(ids[tuple(i)]) for i in at0 if free[tuple(i)]]
    s1 = [int(ids[tuple(i)]) for i in at1 if free[tuple(i)]]
    if not s0 or not s1:
        return None
    comp = _components(free)
    if not {int(comp[tuple(i)]) for i in at0} & {int(comp[tuple(i)]) for i in at1} - {0}:
        return None  # not joined by free cells: no need for the leaves' graph
    order, pred = breadth_first_order(_free_leaf_graph(ids, free, len(L_lo)), s0[0],
                                      directed=False, return_predecessors=True)
    target = next((t for t in s1 if t == s0[0] or pred[t] >= 0), None)
    if target is None:
        return None
    chain = [target]
    while chain[-1] != s0[0]:
        chain.append(int(pred[chain[-1]]))
    chain.reverse()
    return _polyline(cspace, q0, q1, g.floats(L_lo), g.floats(L_lo + L_sz), chain, g.frame)


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


def decide_turning(tcs, start, goal, *, depth: int = 6, time: float = 10.0,
                   frame="auto", exact: bool = True) -> TurningDecision:
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
    frame : 'auto', None or (3, 3) float64
        As :func:`decide`'s, one for every orientation (so their cells coincide): ``'auto'``
        turns it to the start orientation's C-obstacles (the obstacles' faces are in every
        orientation's).
    exact : bool, default True
        First, where every orientation's C-obstacles are convex pieces: the exact free
        space of each orientation (:func:`cspace.planning.free_space.free_space`), and
        components of neighbours linked where their free spaces meet (each component of the
        free space of both orientations' C-obstacles together, located in each): a superset
        of the turns, exactly. Within ``EXACT_SHARE`` of ``time``; else the cells. Where the
        free spaces would take non-convex sums as triangle pairs, after the cells, with the
        time they leave.
    """
    from scipy.sparse import coo_matrix
    from scipy.sparse.csgraph import connected_components

    t0 = _time.perf_counter()
    deadline = t0 + float(time)
    depth = _depth(depth)
    b = np.asarray(tcs.bounds, dtype=np.float64).reshape(2, 3)
    slices = tcs.slices
    n = len(slices)
    exact = exact and not getattr(tcs, "robot_hull", False)
    # as in decide: non-convex sums united as triangle pairs (seconds a slice) wait for the
    # cells, which often decide such scenes faster; the exact free spaces then get what is left
    deferred = exact and unites_sums_as_pairs(tcs.slice(0), b)
    if exact and not deferred:
        td = _turning_exact(tcs, start, goal, b, t0, t0 + EXACT_SHARE * float(time))
        if td is not None:
            return td
    g = F = None
    labels, counts, clearance = [], [], 0.0
    try:
        for k in range(n):
            cs = tcs.slice(k)
            obstacles, boxes, bound, margin = _setup(cs, b)
            clearance = max(clearance, bound)
            if g is None:  # the cells of every orientation: the start's frame
                F = _frame(frame, obstacles, b)
                g = _Grid(b, depth, F)
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
        clearance += 0.0 if F is None else F.rho  # the turned corners' rounding
    else:
        answer, reason = "unknown", f"start and goal may be joined at depth {depth}"
        if deferred and _time.perf_counter() < deadline:
            td = _turning_exact(tcs, start, goal, b, t0, deadline)
            if td is not None:
                return td
    return TurningDecision(answer, reason, clearance, depth, counts, links,
                           _time.perf_counter() - t0)


def _turning_exact(tcs, start, goal, b: np.ndarray, t0: float, deadline: float):
    """:func:`decide_turning` on the exact free spaces (see its ``exact``): 'no path', or
    'unknown' when start and goal are joined there inside the bounds (the cells' components
    hold the free spaces', so they would be joined too); None when the free spaces cannot be
    made in time, start or goal is not strictly free in them, or they are joined in bounds
    snapped outward (perhaps just outside the bounds). Every
    free space has the same bounds, so the same grid: a component of the free space of two
    neighbours' C-obstacles together lies in one component of each, and every point free at
    both lies in one of them."""
    from scipy.sparse import coo_matrix
    from scipy.sparse.csgraph import connected_components

    slices = tcs.slices
    n = len(slices)

    def left() -> float:
        if (t := deadline - _time.perf_counter()) <= 0:
            raise TimeoutError
        return t

    try:
        spaces = [free_space(tcs.slice(k), b, time=left()) for k in range(n)]
        offset = np.concatenate([[0], np.cumsum([fs.n_components for fs in spaces])])
        A, B, bound = [], [], max(fs.error_bound for fs in spaces)
        for i in range(n):
            for j in range(i + 1, n):
                if not slices.neighbours(i, j):
                    continue
                # (what each free space united: a non-convex sum as its scene's triangle pairs)
                both = CSpace(spaces[i].obstacles + spaces[j].obstacles, bounds=b)
                U = free_space(both, b, time=left())
                bound = max(bound, U.error_bound)
                for z in range(U.n_components):
                    point = U.sample(z)
                    a, c = spaces[i].component_at(point), spaces[j].component_at(point)
                    if a is None or c is None:  # pragma: no cover - U's are inside both
                        raise ExactnessError("a component free at both orientations is not")
                    A.append(offset[i] + a)
                    B.append(offset[j] + c)
    except (UnsupportedError, TimeoutError, ExactnessError, MemoryBudgetError):
        return None
    k0 = spaces[0].component_of(start)
    k1 = spaces[slices.goal].component_of(goal)
    if k0 is None or k1 is None:
        return None
    m = int(offset[-1])
    _, cls = connected_components(coo_matrix((np.ones(len(A)), (A, B)), shape=(m, m)),
                                  directed=False)
    counts, links = [fs.n_components for fs in spaces], len(set(zip(A, B)))
    if cls[offset[0] + k0] == cls[offset[slices.goal] + k1]:
        if not spaces[0].bounds_on_grid:  # joined perhaps just outside the bounds: the cells
            return None
        return TurningDecision("unknown", f"start and goal joined over {n} orientations in "
                               "their exact free spaces (by a superset of the turns)", bound, 0,
                               counts, links, _time.perf_counter() - t0)
    reason = (f"start and goal in different components of the exact free spaces of {n} "
              f"orientations ({sum(counts)} components), joined where neighbours' free "
              f"spaces meet ({links} links: a superset of the turns)")
    return TurningDecision("no path", reason, bound, 0, counts, links,
                           _time.perf_counter() - t0)
