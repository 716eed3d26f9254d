"""Refining cells along one route: a path through gaps finer than the decision's octree.

When :func:`.decide`'s octree ends with start and goal in one component of passable cells but
not joined by free ones (a gap narrower than its finest cell), :func:`refine_route` goes on
below that level, but only where a route needs it:

1. The graph: one node per component of the octree's free cells, one per box of passable mixed cells
   of the start's component (aligned pairs merged, :func:`_coarsen`); an edge where two closed cells
   touch (a face, an edge or a corner), decided on integers (cells are boxes of a grid ``2**EXTRA``
   times finer than the octree's finest, with float corners monotone in the integers, so touching
   boxes touch in floats too).
2. The cheapest route from the cells holding the start to those holding the goal (a mixed
   cell costs 1, a free one nothing). If every cell on it is free, the route is a path:
   the cells' centres and contacts, shortcut, every segment proved by ``segment_free``.
3. Otherwise each mixed cell on the route, and each mixed cell touching one of them, is
   split in eight and its children labelled
   (:func:`.cells._labels`); mixed children are merged back along the axes their labels do
   not change on (:func:`_children`: slabs across a slot, bars along an edge); blocked
   children leave the graph, the others join it with the edges of the cells they touch (a
   child touches only what its parent or a split neighbour's children touch). Back to 2.

A mixed cell at the finest level (``2**-(depth + EXTRA)`` of the bounds on every axis) is never
split; a route through one costs ``STUCK``, so routes avoid it while another exists. With
``nudge`` > 0 a child within ``nudge`` of one convex piece is blocked too (``NEAR``,
:func:`.cells._nudged`): C-obstacles that touch are walled where they meet, and "no path"
then holds for clearances above ``error_bound + nudge``.

**"no path"**: the graph always holds every passable cell of the start's component (a split
only removes blocked children, each inside one convex piece of a C-obstacle, exactly, or
within ``nudge`` of one), so
goal cells out of the start's reach prove that no path exists, as in :func:`.decide`. A
"path" is proved segment by segment; the labels ``free`` steer, they prove nothing.
"""

from __future__ import annotations

import time as _time

import numpy as np

from .cells import (BLOCKED, FREE, MIXED, NEAR, _CORNERS, _NEIGHBOURS, _components,
                    _free_leaf_graph, _labels, _OutOfTime, _polyline, _shift)

#: Levels below the octree's finest that a route may refine to.
EXTRA = 20
#: The cost of a route through a mixed cell that cannot be split.
STUCK = 1e6
#: The cost of a mixed cell whose centre collides, per unit of its side (1 when the centre is
#: free): routes go first where the cells' free parts are (a gap), not where C-obstacles only
#: overlap (cells covered by several pieces never turn free); and a cost by size keeps a
#: refined route cheaper than its untouched neighbours (depth first, not every parallel one).
CENTRE_IN_COLLISION = 8.0
#: The most cells split at once (the route's first ones): bounds the time past the deadline.
BATCH = 4096
_FREE_COST = 1e-9  # not zero: scipy's graphs drop explicit zeros


class _Cells:
    """The graph's nodes: ``nF`` free components (nodes ``0..nF-1``), then leaves, each a box
    ``[lo, lo + sz]`` in fine units (``S`` per voxel of the painted grid) with its float box,
    label and ``alive`` flag; and its undirected edges ``ea, eb``."""

    def __init__(self, g, size, fcomp, mixed_voxels, nF: int, extent=None):
        self.g, self.size, self.S = g, np.asarray(size, dtype=np.int64), 1 << EXTRA
        self.n_vox = fcomp.shape
        self.fcomp = fcomp
        self.nF = nF
        k = len(mixed_voxels)
        self.lo = np.zeros((nF + k, 3), np.int64)
        self.sz = np.zeros((nF + k, 3), np.int64)  # per axis: 0 on a flat one
        self.lo[nF:] = mixed_voxels * self.S
        self.sz[nF:] = self.S * self.flat() * (1 if extent is None else extent)
        self.label = np.full(nF + k, MIXED, np.int8)
        self.weight = np.ones(nF + k)  # a mixed cell's cost: see CENTRE_IN_COLLISION
        self.label[:nF] = FREE
        self.alive = np.ones(nF + k, bool)
        self.flo, self.fhi = np.zeros((nF + k, 3)), np.zeros((nF + k, 3))
        self.flo[nF:] = self.floats(self.lo[nF:])
        self.fhi[nF:] = self.floats(self.upper(self.lo[nF:], self.sz[nF:]))
        self.ea = [np.zeros(0, np.int64)]  # [unique edges, then new ones to add]
        self.eb = [np.zeros(0, np.int64)]
        self.walls = []  # (lo, hi, label) of the children proved blocked, per split
        self._holding = {}  # the nodes holding a point (holding)
        # each node's cost, made by graph() for the nodes added since: a node's size, label
        # and weight never change once it is added (the first graph() follows the weights)
        self._cost = np.zeros(0)

    def wall(self) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Every cell a split proved blocked (closed boxes in the grid's frame, and labels:
        ``BLOCKED`` inside a piece, ``NEAR`` within the nudge of one): with 'no path', the
        refined part of the wall (a superset of what touches the start's region)."""
        if not self.walls:
            return np.zeros((0, 3)), np.zeros((0, 3)), np.zeros(0, np.int8)
        return tuple(np.concatenate([w[k] for w in self.walls]) for k in range(3))

    def floats(self, I: np.ndarray) -> np.ndarray:
        """Float coordinates of fine integer corners: the octree's grid corner at a voxel's
        corner, linear inside a voxel (clipped to it), so monotone in ``I``."""
        out = np.empty(I.shape)
        for a in range(3):
            v, r = np.divmod(I[:, a], self.S)
            x = self.g.x[a]
            n = self.n_vox[a]
            lo = x[np.minimum(v, n) * self.size[a]]
            hi = x[np.minimum(v + 1, n) * self.size[a]]
            out[:, a] = np.clip(lo + (hi - lo) * (r / self.S), lo, hi)
        return out

    def flat(self) -> np.ndarray:
        """(3,) int64: 1 on the axes the grid cuts, 0 on flat ones."""
        return self.g.split.astype(np.int64)

    @staticmethod
    def upper(lo: np.ndarray, sz: np.ndarray) -> np.ndarray:
        """The upper corners of cells at ``lo`` of sides ``sz`` (0 on a flat axis)."""
        return lo + sz

    def side(self, sz: np.ndarray) -> np.ndarray:
        """A cell's size for its cost, in fine units: the geometric mean of its sides on the
        axes the grid cuts (a slab thin across a gap is cheaper than its cube)."""
        cut = self.flat().astype(bool)
        return np.exp(np.log(np.maximum(sz[:, cut], 1)).mean(axis=1))

    def voxels_touching(self, lo: np.ndarray, hi: np.ndarray):
        """``(rows, voxels)``: every voxel of the painted grid whose closed box touches the
        closed fine box ``[lo[r], hi[r]]``."""
        first = np.maximum((lo + self.S - 1) // self.S - 1, 0)
        last = np.minimum(hi // self.S, np.array(self.n_vox) - 1)
        rows, vox = [], []
        for off in np.array([[i, j, k] for i in range(3) for j in range(3) for k in range(3)]):
            V = first + off
            ok = (V <= last).all(axis=1)
            rows.append(np.nonzero(ok)[0])
            vox.append(V[ok])
        return np.concatenate(rows), np.concatenate(vox)

    def add(self, lo, sz, label, weight) -> np.ndarray:
        n = len(self.sz)
        self.weight = np.concatenate([self.weight, weight])
        self.lo = np.concatenate([self.lo, lo])
        self.sz = np.concatenate([self.sz, sz])
        self.label = np.concatenate([self.label, label])
        self.alive = np.concatenate([self.alive, np.ones(len(sz), bool)])
        self.flo = np.concatenate([self.flo, self.floats(lo)])
        self.fhi = np.concatenate([self.fhi, self.floats(self.upper(lo, sz))])
        return np.arange(n, n + len(sz))

    def graph(self):
        from scipy.sparse import coo_matrix

        n = len(self.sz)
        # every edge once: the kept ones are unique already; new ones all meet a new node
        A, B = np.concatenate(self.ea[1:]), np.concatenate(self.eb[1:])
        key = np.unique(np.minimum(A, B) * n + np.maximum(A, B))
        A, B = np.concatenate([self.ea[0], key // n]), np.concatenate([self.eb[0], key % n])
        keep = self.alive[A] & self.alive[B]
        A, B = A[keep], B[keep]
        self.ea, self.eb = [A], [B]
        m = len(self._cost)
        if m < n:
            sz, lab, w = self.sz[m:], self.label[m:], self.weight[m:]
            self._cost = np.concatenate([self._cost, np.where(
                lab == FREE, _FREE_COST,
                np.where((sz > 1).any(axis=1), w * (self.side(sz) / self.S), STUCK))])
        cost = self._cost
        M = coo_matrix((np.concatenate([cost[B], cost[A]]),
                        (np.concatenate([A, B]), np.concatenate([B, A]))), shape=(n, n))
        # Every edge is here once each way (A < B, unique), so there is nothing to sum: the
        # flag spares tocsr its duplicate pass, which sorts every row (two thirds of the
        # graph's time on the bug trap). Dijkstra reads the rows in any order.
        M.has_canonical_format = True
        return M.tocsr()

    def holding(self, q: np.ndarray, at: np.ndarray) -> list:
        """Nodes whose closed cell holds ``q``: free components of the voxels ``at`` (those
        of the painted grid holding it) and the live leaves whose float box holds it. Kept
        while they all live: a new leaf holds ``q`` only if its parent, split, did."""
        key = (q.tobytes(), at.tobytes())
        known = self._holding.get(key)
        if known is not None and self.alive[known].all():
            return known
        comps = {int(self.fcomp[tuple(v)]) - 1 for v in at} - {-1}
        x, pad = self.g.local(q), self.g.pad  # in a turned frame: every leaf near it
        leaf = self.alive & (self.flo <= x + pad).all(axis=1) & (x - pad <= self.fhi).all(axis=1)
        leaf[: self.nF] = False
        self._holding[key] = sorted(comps | set(np.nonzero(leaf)[0].tolist()))
        return self._holding[key]


def _weights(cspace, lo: np.ndarray, hi: np.ndarray, deadline: float, frame=None) -> np.ndarray:
    """The cost of mixed cells: :data:`CENTRE_IN_COLLISION` where the centre collides, else 1
    (the exact test steers the routes; it decides nothing). The clock is read every
    :data:`BATCH` cells (a pair C-obstacle's ``contains`` takes ~10 us a point). With a turned
    ``frame`` the cells are its boxes."""
    out = np.ones(len(lo))
    for s in range(0, len(lo), BATCH):
        if s and _time.perf_counter() > deadline:
            raise _OutOfTime
        centre = (lo[s:s + BATCH] + hi[s:s + BATCH]) / 2
        inside = cspace.contains(centre if frame is None else frame.world(centre))
        out[s:s + BATCH][inside] = CENTRE_IN_COLLISION
    return out


def _initial(cells: _Cells, node_of: np.ndarray) -> None:
    """Edges between touching nodes of the painted grid (26 neighbours of each voxel)."""
    shape = node_of.shape
    for d in _NEIGHBOURS:
        src, dst = _shift(shape, d)
        u, v = node_of[src], node_of[dst]
        ok = (u >= 0) & (v >= 0) & (u != v)
        cells.ea.append(u[ok])
        cells.eb.append(v[ok])


# octant index 4i + 2j + k (as _CORNERS): the octants low on each axis, and the bit of an axis
_LOW = [np.nonzero(_CORNERS[:, a] == 0)[0] for a in range(3)]
_BIT = np.array([4, 2, 1])


def _children(cells: _Cells, parents: np.ndarray, obstacles, boxes, margin, deadline,
              nudge: float):
    """The children of ``parents``: ``(lo, sz, label, parent)``.

    Each parent is cut in two on every axis where its side exceeds one fine unit, and the
    octants labelled. Where the labels change along some axis but not along another, the
    mixed octants are merged along the unchanging one: across a slot between two walls the
    octants on a wall's side are blocked and the others mixed, so the mixed half stays one
    slab (it thins across the slot, keeps its length along it); along an edge where two
    C-obstacles meet it stays one bar. A merged cell is labelled mixed without a test (a
    mixed label proves nothing; the decided octants keep theirs), so a route through a gap
    needs cells in proportion to its length, not to its length over its width."""
    psz = cells.sz[parents]
    can = psz > 1
    half = np.where(can, psz // 2, psz)
    valid = ~(_CORNERS.astype(bool)[None] & ~can[:, None, :]).any(axis=2)  # (p, 8)
    olo = cells.lo[parents][:, None, :] + _CORNERS[None] * half[:, None, :]
    osz = np.broadcast_to(half[:, None, :], olo.shape)
    pi, oi = np.nonzero(valid)
    lab = np.full(valid.shape, -1, np.int8)
    lab[pi, oi] = _labels(obstacles, boxes, cells.floats(olo[pi, oi]),
                          cells.floats(cells.upper(olo[pi, oi], osz[pi, oi])), margin, deadline,
                          nudge, cells.g.frame)
    same = np.stack([(lab[:, _LOW[a]] == lab[:, _LOW[a] + _BIT[a]]).all(axis=1)
                     for a in range(3)], axis=1)
    merge = can & same & (can & ~same).any(axis=1)[:, None]  # (p, 3)
    mixed = lab == MIXED
    first = ((_CORNERS[None] * merge[:, None, :]) == 0).all(axis=2)  # (p, 8): a group's low
    keep = valid & (~mixed | first)
    csz = np.where((mixed[:, :, None] & merge[:, None, :]), psz[:, None, :], osz)
    pi, oi = np.nonzero(keep)
    return olo[pi, oi], csz[pi, oi], lab[pi, oi], parents[pi]


def _split(cspace, cells: _Cells, G, parents: np.ndarray, obstacles, boxes, margin,
           deadline, nudge: float) -> int:
    """Split ``parents`` (mixed leaves) in eight and label the octants; then merge the mixed
    octants of a parent back along each axis on which its octants' labels do not change,
    when they change on another (:func:`_children`); keep the children not blocked, with
    their edges. Returns how many children were kept."""
    lo, sz, label, parent = _children(cells, parents, obstacles, boxes, margin, deadline,
                                      nudge)
    keep = (label != BLOCKED) & (label != NEAR)
    if not keep.all():
        cells.walls.append((cells.floats(lo[~keep]),
                            cells.floats(cells.upper(lo[~keep], sz[~keep])), label[~keep]))
    lo, sz, parent, label = lo[keep], sz[keep], parent[keep], label[keep]
    weight = np.ones(len(sz))
    mixed = label == MIXED
    weight[mixed] = _weights(cspace, cells.floats(lo[mixed]),
                             cells.floats(cells.upper(lo[mixed], sz[mixed])), deadline,
                             cells.g.frame)
    new = cells.add(lo, sz, label, weight)
    cells.alive[parents] = False
    # candidates of each child: its parent's neighbours (leaves), its siblings, and the
    # children of split neighbours
    kids: dict = {}
    for c, p in zip(new.tolist(), parent.tolist()):
        kids.setdefault(p, []).append(c)
    ca, cb = [], []
    for p in parents.tolist():
        mine = kids.get(p, [])
        if not mine:
            continue
        nb = G.indices[G.indptr[p]:G.indptr[p + 1]]
        cand = [x for x in nb.tolist() if x >= cells.nF and cells.alive[x]]
        for q in [p] + nb.tolist():
            cand.extend(kids.get(q, []))
        cand = np.unique(np.array(cand, dtype=np.int64))
        a = np.repeat(np.array(mine), len(cand))
        b = np.tile(cand, len(mine))
        ca.append(a)
        cb.append(b)
    if ca:
        a, b = np.concatenate(ca), np.concatenate(cb)
        hi_a, hi_b = cells.upper(cells.lo[a], cells.sz[a]), cells.upper(cells.lo[b], cells.sz[b])
        touch = (a != b) & ((cells.lo[a] <= hi_b) & (cells.lo[b] <= hi_a)).all(axis=1)
        a, b = a[touch], b[touch]
        cells.ea.append(np.minimum(a, b))
        cells.eb.append(np.maximum(a, b))
    # the free components each child touches
    rows, vox = cells.voxels_touching(lo, cells.upper(lo, sz))
    comp = cells.fcomp[vox[:, 0], vox[:, 1], vox[:, 2]].astype(np.int64) - 1
    ok = comp >= 0
    cells.ea.append(comp[ok])
    cells.eb.append(new[rows[ok]])
    return len(new)


def _coarsen(vox: np.ndarray):
    """Mixed voxels merged into boxes: ``(lo, extent, owner)`` in voxels, ``owner`` the box
    of each voxel (in the order of ``vox``).

    Two boxes merge along an axis when they are the two halves of an aligned box twice as
    long there (the same on the other axes); repeated on each axis until none merges. The
    boxes are mixed (a mixed label is never a proof), and :func:`_children` splits them only
    where a route needs it: a wall where two C-obstacles touch is walled column by column,
    and a column is as long as the voxels along it allow, not one voxel."""
    lo = vox.astype(np.int64)
    ext = np.ones_like(lo)
    owner = np.arange(len(lo))
    # a box's key packs six 9-bit fields: the painted grid has at most 2**MAX_DEPTH = 256
    # voxels per axis, so corners and extents stay below 512
    assert not len(lo) or int(lo.max()) < 256

    def keys(lo, ext):
        return ((((lo[:, 0] << 9 | lo[:, 1]) << 9 | lo[:, 2]) << 9 | ext[:, 0]) << 9
                | ext[:, 1]) << 9 | ext[:, 2]

    merged = True
    while merged and len(lo):
        merged = False
        for a in range(3):
            k = keys(lo, ext)
            order = np.argsort(k)
            low = np.nonzero(lo[:, a] % (2 * ext[:, a]) == 0)[0]
            mate = lo[low].copy()
            mate[:, a] += ext[low, a]
            want = keys(mate, ext[low])
            at = np.minimum(np.searchsorted(k, want, sorter=order), len(k) - 1)
            hit = k[order[at]] == want
            if not hit.any():
                continue
            merged = True
            low, high = low[hit], order[at[hit]]
            ext[low, a] *= 2
            gone = np.zeros(len(lo), dtype=bool)
            gone[high] = True
            target = np.arange(len(lo))
            target[high] = low
            renum = np.cumsum(~gone) - 1
            owner = renum[target[owner]]
            lo, ext = lo[~gone], ext[~gone]
    return lo, ext, owner


def refine_route(cspace, g, q0, q1, ids, lab, L_lo, L_sz, size, obstacles, boxes,
                 margin: float, deadline: float, at0, at1, nudge: float = 0.0):
    """Refine along routes until one is free, the goal is out of reach, or time is up.

    ``g``, ``ids``, ``lab``, ``L_lo``, ``L_sz`` and ``size``: the octree's last level as
    :func:`.decide` painted it (voxels of ``size`` finest cells; ``ids`` the leaf of each,
    ``lab`` its label); ``at0``, ``at1``: the voxels holding start and goal.

    Returns ``(answer, reason, path, (wall_lo, wall_hi, wall_labels))``: ``'path'`` with a
    proved polyline,
    ``'no path'``, or ``'unknown'`` (out of time, or every route passes a cell that cannot be
    split), and the cells the splits proved blocked (:meth:`_Cells.wall`).
    """
    from scipy.sparse.csgraph import dijkstra

    t0 = _time.perf_counter()
    fcomp = _components(lab == FREE)
    nF = int(fcomp.max())
    passable = _components(lab != BLOCKED)
    mine = ({int(passable[tuple(v)]) for v in at0} | {int(passable[tuple(v)]) for v in at1}) - {0}
    mixed = (lab == MIXED) & np.isin(passable, list(mine))
    vox, extent, owner = _coarsen(np.argwhere(mixed))
    cells = _Cells(g, size, fcomp, vox, nF, extent)
    try:
        cells.weight[nF:] = _weights(cspace, cells.flo[nF:], cells.fhi[nF:], deadline, g.frame)
    except _OutOfTime:
        return ("unknown", f"out of time weighing {len(vox)} cells to refine", None,
                cells.wall())
    node_of = np.where(fcomp > 0, fcomp.astype(np.int64) - 1, -1)
    node_of[mixed] = nF + owner
    _initial(cells, node_of)
    split = 0
    while _time.perf_counter() < deadline:
        G = cells.graph()
        src, dst = cells.holding(q0, at0), cells.holding(q1, at1)
        dist, pred, _ = dijkstra(G, indices=src, min_only=True, return_predecessors=True)
        t = min(dst, key=lambda x: dist[x])
        if not np.isfinite(dist[t]):
            return ("no path", f"start and goal in different components after {split} cells "
                    f"refined along routes ({_time.perf_counter() - t0:.2f} s)", None,
                    cells.wall())
        route = [t]
        while route[-1] not in src:
            route.append(int(pred[route[-1]]))
        route.reverse()
        route = np.array(route)
        todo = route[(route >= nF) & (cells.label[route] == MIXED)]
        if not len(todo):
            path = _route_path(cspace, cells, g, q0, q1, ids, lab, L_lo, L_sz, size, route,
                               at0, at1)
            if path is None:
                return ("unknown", "a route through free cells failed its exact proof", None,
                        cells.wall())
            cut = cells.flat().astype(bool)
            finest = cells.sz[route[route >= nF]][:, cut].min(initial=cells.S)
            below = int(np.log2(cells.S // max(int(finest), 1)))
            return ("path", f"a route through free cells after {split} cells refined along "
                    f"routes, down to {below} levels below the octree", path, cells.wall())
        # with the route's mixed cells, their mixed neighbours: a 'no path' must refine the
        # whole rim of the start's region anyway, and each round (a new graph and a shortest
        # path over all of it) costs more than splitting a few more cells
        nb = np.concatenate([G.indices[G.indptr[k]:G.indptr[k + 1]] for k in todo.tolist()])
        nb = nb[(nb >= nF) & cells.alive[nb]]
        todo = np.union1d(todo, nb[cells.label[nb] == MIXED])
        todo = todo[(cells.sz[todo] > 1).any(axis=1)][:BATCH]
        if not len(todo):
            return ("unknown", f"every route passes a cell {EXTRA} levels below the octree's "
                    "finest that is neither free nor blocked", None, cells.wall())
        try:
            split += _split(cspace, cells, G, todo, obstacles, boxes, margin, deadline,
                            nudge)
        except _OutOfTime:
            break
    return ("unknown", f"out of time refining routes ({split} cells)", None, cells.wall())


def _route_path(cspace, cells: _Cells, g, q0, q1, ids, lab, L_lo, L_sz, size, route, at0, at1):
    """The route's cells as a chain of boxes (each free component expanded to a chain of the
    octree's free leaves between its neighbours on the route), then :func:`_polyline`."""
    from scipy.sparse.csgraph import dijkstra

    GF = _free_leaf_graph(ids, lab == FREE, len(L_lo))
    lo_d, hi_d = g.floats(L_lo), g.floats(L_lo + L_sz)

    def leaves(c, vox):
        """The octree's leaves of free component ``c`` among the voxels ``vox``."""
        return sorted({int(ids[tuple(v)]) for v in vox if int(cells.fcomp[tuple(v)]) == c + 1})

    def near(k):
        """The voxels touching route cell ``k`` (a leaf of ``cells``)."""
        lo = cells.lo[k][None]
        return cells.voxels_touching(lo, cells.upper(lo, cells.sz[k]))[1]

    boxes_lo, boxes_hi = [], []
    for i, k in enumerate(route.tolist()):
        if k >= cells.nF:
            boxes_lo.append(cells.flo[k])
            boxes_hi.append(cells.fhi[k])
            continue
        src = leaves(k, at0 if i == 0 else near(route[i - 1]))
        dst = leaves(k, at1 if i == len(route) - 1 else near(route[i + 1]))
        if not src or not dst:
            return None
        dist, pred, _ = dijkstra(GF, indices=src, min_only=True, unweighted=True,
                                 return_predecessors=True)
        t = min(dst, key=lambda x: dist[x])
        if not np.isfinite(dist[t]):
            return None
        chain = [t]
        while chain[-1] not in src:
            chain.append(int(pred[chain[-1]]))
        for leaf in reversed(chain):
            boxes_lo.append(lo_d[leaf])
            boxes_hi.append(hi_d[leaf])
    lo, hi = np.array(boxes_lo), np.array(boxes_hi)
    return _polyline(cspace, q0, q1, lo, hi, list(range(len(lo))), g.frame)
