"""The free space at one orientation, exactly: the bounds minus the union of the C-obstacles.

:func:`free_space` puts every convex piece of the C-obstacles that meets the planning bounds
on one grid, grown outward (each vertex replaced by the corners of the grid cell holding it,
and the hull taken: the piece only grows, by at most one step per axis). It adds a frame: a
box an eighth of the bounds' size larger, minus the bounds snapped outward (pieces that cross
its outer box are clipped to it exactly, so a floor slab of any size leaves the step to the
bounds). Then it makes the exact arrangement of all their triangles
(:class:`cspace.minkowski.union.UnionCells`). Its cells of winding number 0, other than the
unbounded one, are the free space's components: each lies inside the bounds. The grid depends
on the bounds only, so free spaces of one bounds share it (:meth:`FreeSpace.sample` of one is
located in another: :func:`cspace.planning.decide.decide_turning`).

**What it proves.** Two free points in different components: every path between them meets
the grown union, so no path between them has a clearance above :attr:`FreeSpace.error_bound`
(the C-obstacles' own ``error_bound`` plus the growth, ``sqrt(3)`` steps, or twice that when a
flat piece was widened). The proof is checked on its own (:meth:`FreeSpace.separation`): the
boundary of the start's component, oriented away from it, has different winding numbers at
the two points. Two points in one component: a path joins them (the grown union holds the
C-obstacles) inside the bounds snapped outward, inside the bounds themselves when they are on
the grid (:meth:`FreeSpace.joined`).

**Which C-obstacles.** Those made of convex pieces (kinds ``'convex'``, ``'union'`` of such,
``'surface'``, and ``'pairs'``: each triangle pair's grown piece that can meet the bounds, up
to ``max_pieces``; against a closed convex robot part, one piece per convex patch of
coplanar obstacle triangles), and closed meshes (kind ``'mesh'``: a pair's containment terms)
whose vertices lie on the union's grid, taken whole. A solid body's non-convex sum (NCC-CVMS,
kind ``'mesh'``, off the grid) is taken as the same scene's triangle pairs, the same set
(:func:`_operands`; it needs the C-space's scene). A flat piece (parallel triangles of an open
surface) is grown by one more step on every side, and the error bound says so. Other
C-obstacles (a sum without its scene, a containment term off the grid) raise
:class:`~cspace.errors.UnsupportedError`; :func:`cspace.planning.decide.decide` then decides
with certified cells alone.
"""

from __future__ import annotations

import math
import time as _time
import weakref
from dataclasses import dataclass
from fractions import Fraction

import numpy as np

from ..errors import DegenerateError, ExactnessError, InvalidArgumentError, UnsupportedError
from ..geometry.boxes import box_pairs
from ..geometry.exact import Grid
from ..geometry.polygon import convex_patches
from ..memory import MemoryGuard
from ..mesh.convex import ConvexPolytope
from ..minkowski.output import _to_float_compiled
from ..minkowski.union import UnionCells

#: Default largest number of convex pieces :func:`free_space` unites.
MAX_PIECES = 4000

#: Default largest number of candidate pairs of their triangles (boxes meeting) it goes on
#: with: some 4 us each from the intersections to the cells (the turned bottle: 1.1 million
#: pairs in 4 s), so about 20 s; a 2481-piece bug trap makes 160 million (and took 24 GB).
MAX_PAIRS = 5_000_000

# Pieces whose vertices reach this far from G's origin (grid steps; the outer box reaches
# 2**26) are clipped to the frame's outer box; nearer ones are taken whole (grown by two steps
# at most, and the frame's outer box two beyond everything, they stay below the union's 2**27).
_UNCLIPPED = 2**27 - 16

# How far (grid steps of a C-obstacle's grid) the triangles merged into one convex piece
# (_pair_plan) may lie off one plane: a snapped flat face's are within about a step of it.
# It is not a decision: a patch only grows within it, and error_bound states what it adds.
PATCH_TOLERANCE = 2

# The box of the unit cube's corners, for growing a vertex to its grid cell.
_CORNERS = np.array([[i, j, k] for i in (0, 1) for j in (0, 1) for k in (0, 1)], dtype=np.int64)
# The unit cube's triangles, counter-clockwise seen from outside (corner index i*4 + j*2 + k).
_BOX = np.array([[0, 1, 3], [0, 3, 2], [4, 6, 7], [4, 7, 5], [0, 4, 5], [0, 5, 1],
                 [2, 3, 7], [2, 7, 6], [0, 2, 6], [0, 6, 4], [1, 5, 7], [1, 7, 3]],
                dtype=np.int64)


def _pieces(co, name: str, b: np.ndarray, check=None) -> tuple[list, list, list]:
    """What the stored C-obstacle ``co`` is made of, near the closed box ``b``: its convex
    pieces (ConvexPolytope, or ``(k, 3)`` float64 points: their hull), its closed meshes
    (C-obstacles of kind ``'mesh'``, whose vertices :func:`free_space` needs on its grid) and
    its triangle pairs (:func:`_pair_plan`: counted before any piece is made). ``check()``
    is called between chunks of pairs (the deadline)."""
    if co.kind == "convex":
        return [co.polytope], [], []
    if co.kind == "union":
        got = [_pieces(part, name, b, check) for part in co.parts]
        return tuple([x for g in got for x in g[k]] for k in range(3))
    if co.kind == "surface":
        return list(co._impl.pieces), [], []
    if co.kind == "mesh":
        return [], [co], []
    if co.kind == "pairs":
        return [], [], [_pair_plan(co, b, check)]
    raise UnsupportedError(
        f"free_space: C-obstacle {name} is of kind {co.kind!r}; the exact union takes "
        "C-obstacles made of convex pieces ('convex', 'union', 'surface', 'pairs') and "
        "closed meshes on its grid ('mesh')")


@dataclass
class _PairPlan:
    """The pieces ``S[i] ⊕ T[j] ⊕ box`` of a triangle-pair C-obstacle ``co`` to make, for
    ``(i, j)`` in ``zip(i, j)`` (grid integers of ``co.grid``), their boxes ``lo, hi``, and
    ``extra`` (scene units): how far beyond the C-obstacle a piece may reach."""

    co: object
    S: list
    T: np.ndarray
    i: np.ndarray
    j: np.ndarray
    lo: np.ndarray
    hi: np.ndarray
    extra: float


def _pair_plan(co, b: np.ndarray, check=None) -> _PairPlan:
    """The pieces of a triangle-pair C-obstacle whose boxes meet ``b`` (flat ones left out
    when an operand is closed, as the C-obstacle leaves them), counted before any is made.
    With a closed convex robot part, one piece per convex patch of (nearly) coplanar
    obstacle triangles (:func:`cspace.geometry.polygon.convex_patches`)."""
    from ..cobstacle.pairs import TrianglePairs, _flat

    S, T, g = co.S, co.T, np.asarray(co._impl.g, dtype=np.int64).reshape(3)
    bg = np.ldexp(b, -co.grid.exponent) - np.asarray(co.grid.origin, dtype=np.float64)
    merged = _closed_convex(T)
    if merged:
        # A closed convex robot part: the pieces of one obstacle triangle s, over all of the
        # part's triangles, and the other pairs (or the containment term, for a part of the
        # obstacle that fits in the robot) cover s ⊕ (c - R), one convex piece. Coplanar
        # triangles whose union is a convex polygon Q give one piece too: Q ⊕ (c - R) is the
        # union of theirs (a sum distributes over a union), and a wall's pieces, one per
        # triangle, would overlap their neighbours on shared planes, the union's costliest
        # arrangements (the pieces of a shell of 400 squares: 140 s, 11 000 planes).
        # Snapping leaves a flat face flat only within a step or so: a patch may reach
        # PATCH_TOLERANCE steps beyond its triangles, its hull then within 6 times that of
        # them (convex_patches), which the bound states. Only triangles near the box count.
        T = np.unique(T.reshape(-1, 3), axis=0)[None]
        near = ((S.min(axis=1) + T.min(axis=1) - g <= bg[1])
                & (S.max(axis=1) + T.max(axis=1) + g >= bg[0])).all(axis=1)
        V, F = np.unique(S[near].reshape(-1, 3), axis=0, return_inverse=True)  # only those
        patches, _, off = convex_patches(V, F.reshape(-1, 3), PATCH_TOLERANCE)
        S = [V[k] for k in patches]
        extra = off * 6.0 * PATCH_TOLERANCE * co.grid.step
    else:
        tp = TrianglePairs(S, T, np.zeros((0, 2), np.int64), np.zeros(0, bool), margin=g)
        extra = 0.0
    s_lo = np.array([x.min(axis=0) for x in S]).reshape(-1, 3)
    s_hi = np.array([x.max(axis=0) for x in S]).reshape(-1, 3)
    t_lo, t_hi = T.min(axis=1), T.max(axis=1)
    I, J = [], []
    rows = max(1, 200_000 // max(len(T), 1))  # pairs tested at once
    for i0 in range(0, len(S), rows):
        if check is not None:
            check("counting the pieces", f" ({i0} of {len(S)} obstacle triangles)")
        lo = s_lo[i0:i0 + rows, None] + t_lo[None] - g
        hi = s_hi[i0:i0 + rows, None] + t_hi[None] + g
        ii, jj = np.nonzero(((lo <= bg[1]) & (hi >= bg[0])).all(axis=2))
        ii += i0
        if co.closed and len(ii) and not merged:
            keep = ~_flat(tp, ii, jj)
            ii, jj = ii[keep], jj[keep]
        I.append(ii)
        J.append(jj)
    I, J = np.concatenate(I), np.concatenate(J)
    return _PairPlan(co, S, T, I, J, s_lo[I] + t_lo[J] - g, s_hi[I] + t_hi[J] + g, extra)


def _piece_pairs(found: list, G: Grid) -> int:
    """How many pairs of the pieces ``found`` (each C-obstacle's ``(name, pieces, plans)``)
    have boxes that meet, from the plans' boxes, before any pair piece is made."""
    lo, hi = [], []
    for _, got, plans in found:
        for p in got:
            V = p.vertices if isinstance(p, ConvexPolytope) else p
            lo.append(V.min(axis=0))
            hi.append(V.max(axis=0))
        for plan in plans:
            lo += list(plan.co.grid.to_float(plan.lo))
            hi += list(plan.co.grid.to_float(plan.hi))
    if len(lo) < 2:
        return 0
    e = G.exponent
    return len(box_pairs(np.floor(np.ldexp(np.array(lo), -e)).astype(np.int64),
                         np.ceil(np.ldexp(np.array(hi), -e)).astype(np.int64)))


def _pair_pieces(plan: _PairPlan, name: str, far) -> list:
    """The pieces of :func:`_pair_plan` as float64 points (exact: grid points of the
    C-obstacle's grid), or, where ``far(points)`` (beyond the union's range), as their hull."""
    from ..geometry.snapping import grow_points

    co, S, T = plan.co, plan.S, plan.T
    g = np.asarray(co._impl.g, dtype=np.int64).reshape(3)
    out = []
    for i, j in zip(plan.i.tolist(), plan.j.tolist()):
        pts = grow_points((S[i][:, None] + T[j][None]).reshape(-1, 3), g)
        V = co.grid.to_float(pts)
        out.append(ConvexPolytope.from_ints(pts, grid=co.grid, name=name) if far(V) else V)
    return out


def _on_grid(co, G: Grid) -> np.ndarray | None:
    """A mesh C-obstacle's vertices in ``G``'s integers, or None when they are not grid
    points of ``G`` within the union's range."""
    e, origin = G.exponent, np.asarray(G.origin, dtype=np.int64)
    k = np.ldexp(np.asarray(co._impl.vertices, dtype=np.float64), -e)
    if not (np.floor(k) == k).all() or np.abs(k - origin).max() >= 2**27 - 8:
        return None
    return k.astype(np.int64) - origin


def _frame_of(b: np.ndarray) -> tuple:
    """The frame around the bounds ``b``: ``(G, (o_lo, o_hi), (s_lo, s_hi), inner)``.

    The outer box: the bounds and an eighth of their size around them. Parts of pieces beyond
    it change nothing inside the bounds (the frame fills the rest), so pieces far beyond it
    are clipped to it (exactly) and the grid ``G``'s step follows the bounds. The inner box:
    the bounds snapped outward (``s_lo, s_hi``, G's integers; ``inner``, scene units; flat
    bounds, a planar problem: a step either side, so that it is a box). Its free space is
    computed whole: every piece that meets it counts, so one component joins its points by
    a path inside it."""
    pad = 0.125 * float((b[1] - b[0]).max()) + 2.0**-20 * float(np.abs(b).max() + 1.0)
    o_lo, o_hi = b[0] - pad, b[1] + pad
    G = Grid.for_box(o_lo, o_hi)
    e, origin = G.exponent, np.asarray(G.origin, dtype=np.int64)
    s_lo = np.floor(np.ldexp(b[0], -e)).astype(np.int64) - origin
    s_hi = np.ceil(np.ldexp(b[1], -e)).astype(np.int64) - origin
    flat = s_lo == s_hi
    s_lo, s_hi = s_lo - flat, s_hi + flat
    inner = np.stack([G.to_float(s_lo), G.to_float(s_hi)])  # exact: grid points
    return G, (o_lo, o_hi), (s_lo, s_hi), inner


def unites_sums_as_pairs(cspace, bounds=None) -> bool:
    """Whether :func:`free_space` would take non-convex sums of ``cspace`` as its scene's
    triangle pairs (:func:`_operands`): a union of many overlapping pieces, slower than
    certified cells' octree, which often decides such scenes at once (so
    :func:`cspace.planning.decide.decide` asks the cells' octree first then). Builds nothing
    new."""
    b = np.asarray(cspace.bounds if bounds is None else bounds, dtype=np.float64).reshape(2, 3)
    G, _, _, inner = _frame_of(b)
    return _pairs_model(cspace, inner, G) is not None


# A C-space's scene modelled again for its triangle pairs (_pairs_model), while it lives.
_REMODELLED: "weakref.WeakKeyDictionary" = weakref.WeakKeyDictionary()


def _pairs_model(cspace, inner: np.ndarray, G: Grid):
    """The scene model whose triangle pairs :func:`free_space` unites instead of the
    C-space's non-convex sums, or None: a lazy C-space's model when it would build a sum (a
    solid body against a convex robot part); a C-space's scene's, modelled again (once per
    C-space, kept while it lives), when one of its closed meshes meeting ``inner`` is off
    ``G`` and the scene has such a pair (a sum read from the cache, too)."""
    from ..cobstacle.pairs import pair_construction
    from ..scene.model import LazyCSpace, model_scene

    if isinstance(cspace, LazyCSpace):
        return cspace.model if cspace.has_sums() else None
    scene = getattr(cspace, "scene", None)
    if scene is None or not any(_off_grid_mesh(co, inner, G) for co in cspace.obstacles):
        return None
    model = _REMODELLED.get(cspace)
    if model is None:  # modelling again is steps 1-5 of a build: once per C-space
        model = _REMODELLED[cspace] = model_scene(scene, build=False,
                                                  robot_hull=cspace.robot_hull)
    solid = any(pair_construction(b.kind, p.kind) == "NCC-CVMS"
                for b in model.bodies if b.kind != "dropped" for p in model.robot_parts)
    return model if solid else None


def _off_grid_mesh(co, inner: np.ndarray, G: Grid) -> bool:
    """``co`` is a closed mesh meeting the box ``inner`` whose vertices are off ``G``."""
    B = np.asarray(co.bounds, dtype=np.float64)
    return (co.kind == "mesh" and not ((B[1] < inner[0]).any() or (B[0] > inner[1]).any())
            and _on_grid(co, G) is None)


def _operands(cspace, inner: np.ndarray, G: Grid) -> tuple:
    """The C-obstacles of ``cspace`` :func:`free_space` unites in the box ``inner`` (a lazy
    C-space's built there now): its own, or, where a solid body's C-obstacle is a non-convex
    sum (NCC-CVMS, kind ``'mesh'``) off ``G``, those of the same scene modelled with
    ``sums=False`` (:func:`_pairs_model`): each solid body against a convex robot part as
    triangle pairs, the same set, with nothing to build (one convex piece per patch of
    coplanar triangles here: :func:`_pair_plan`). A lazy C-space goes to pairs before
    building any sum. This needs the C-space's scene (a C-space made from one has it);
    without it a sum off ``G`` stays, and is declined."""
    from ..scene.model import LazyCSpace

    model = _pairs_model(cspace, inner, G)
    if model is None:
        if isinstance(cspace, LazyCSpace):
            cspace.build(inner[0], inner[1])
        return cspace.obstacles
    pairs = LazyCSpace(model, sums=False)
    pairs.build(inner[0], inner[1])
    return pairs.obstacles


def _closed_convex(T: np.ndarray) -> bool:
    """Whether the triangles ``T (l, 3, 3)`` (grid ints) close up (every directed edge met by
    its reverse) and bound a convex solid (every vertex on one side of every triangle's
    plane, the same side for all, and some strictly: ``c - t`` turns the robot's
    orientation inside out): exact, integers."""
    if len(T) < 4:
        return False
    keys = {}
    for tri in T.tolist():
        for k in range(3):
            e = (tuple(tri[k]), tuple(tri[(k + 1) % 3]))
            keys[e] = keys.get(e, 0) + 1
    if any(keys.get((b, a), 0) != c for (a, b), c in keys.items()):
        return False
    P = np.unique(T.reshape(-1, 3), axis=0).astype(object)
    signs = set()
    for a, b, c in T.astype(object).tolist():
        n = np.cross(np.array(b) - np.array(a), np.array(c) - np.array(a))
        side = (P - np.array(a)) @ n
        if (side > 0).any() and (side < 0).any():
            return False
        signs.add(1 if (side > 0).any() else -1 if (side < 0).any() else 0)
    return len(signs) == 1 and 0 not in signs


def _clipped(P: ConvexPolytope, lo, hi) -> list:
    """The vertices (exact fractions, scene units) of ``P ∩ [lo, hi]``: P's vertices in the
    box, P's edges across the box's faces, the box's corners in P, and the box's edges across
    P's facet planes (empty when they miss)."""
    step, org = Fraction(2) ** P.grid.exponent, P.grid.origin
    L, H = [Fraction(float(c)) for c in lo], [Fraction(float(c)) for c in hi]
    planes = [((n0, n1, n2), d) for n0, n1, n2, d in P.planes()]

    def level(x, n, d):  # n . k - d for the grid units k of x (P's grid)
        return sum(n[i] * (x[i] / step - org[i]) for i in range(3)) - d

    def in_box(x) -> bool:
        return all(L[i] <= x[i] <= H[i] for i in range(3))

    def cross(a, b, sa, sb):  # the point where the level goes from sa to sb along a -> b
        t = sa / (sa - sb)
        return tuple(a[i] + t * (b[i] - a[i]) for i in range(3))

    V = [tuple(Fraction(float(c)) for c in v) for v in P.vertices]
    pts = [v for v in V if in_box(v)]
    for u, w in P.edges.tolist():
        for k in range(3):
            for bound in (L[k], H[k]):
                sa, sb = V[u][k] - bound, V[w][k] - bound
                if sa * sb < 0 and in_box(x := cross(V[u], V[w], sa, sb)):
                    pts.append(x)
    corners = [tuple(H[i] if c[i] else L[i] for i in range(3)) for c in _CORNERS.tolist()]
    pts += [c for c in corners if all(level(c, n, d) <= 0 for n, d in planes)]
    for a in range(8):
        for k in range(3):
            if not _CORNERS[a, k]:
                b = a | (4 >> k)  # the corner across the box along axis k
                for n, d in planes:
                    sa, sb = level(corners[a], n, d), level(corners[b], n, d)
                    if sa * sb < 0:
                        x = cross(corners[a], corners[b], sa, sb)
                        if all(level(x, m, e) <= 0 for m, e in planes):
                            pts.append(x)
    return pts


def _box_faces(lo: np.ndarray, hi: np.ndarray, outward: bool) -> tuple[np.ndarray, np.ndarray]:
    V = np.where(_CORNERS.astype(bool), hi, lo)
    return V, (_BOX if outward else _BOX[:, ::-1])


@dataclass(repr=False)
class Separation:
    """A proof that two points are in different components of the free space.

    Attributes
    ----------
    start, goal : int
        Their components.
    winding : tuple of 2 int
        The winding numbers of the start component's boundary at the two points.
    vertices : (n, 3) float64
    faces : (m, 3) int64
        That boundary (scene units), oriented away from the start's component: a closed
        surface in the grown C-obstacles' union that every path between them meets.
    """

    start: int
    goal: int
    winding: tuple
    vertices: np.ndarray
    faces: np.ndarray

    def __repr__(self) -> str:
        return (f"Separation(start={self.start}, goal={self.goal}, winding={self.winding}, "
                f"triangles={len(self.faces)})")

    def to_trimesh(self):
        import trimesh

        return trimesh.Trimesh(self.vertices, self.faces, process=False)


class FreeSpace:
    """The free space of a C-space at one orientation inside its bounds, exactly (of the
    C-obstacles grown within :attr:`error_bound`). Made by :func:`free_space`.

    Attributes
    ----------
    bounds : (2, 3) float64
    grid : Grid
        The grid every piece was put on.
    error_bound : float
        Scene units: the largest ``error_bound`` of the C-obstacles plus the growth onto the
        grid (``sqrt(3)`` steps, twice that when a flat piece was widened). A proof of
        separation holds for paths whose clearance exceeds it.
    n_pieces : int
        Convex pieces united.
    n_components : int
        Components of the free space inside the bounds (snapped outward).
    bounds_on_grid : bool
        The bounds are grid points and not flat: the frame's inner box is the bounds.
    obstacles : tuple of CSpaceObstacle
        The C-obstacles it united: the C-space's, or for non-convex sums its scene's triangle
        pairs (the same sets).
    time : float
        Seconds taken.
    """

    def __init__(self, cells: UnionCells, grid: Grid, bounds: np.ndarray, error_bound: float,
                 n_pieces: int, seconds: float, *, planes: list, inner: tuple, meshes: list,
                 bounds_on_grid: bool, obstacles: tuple = ()):
        self.cells, self.grid, self.bounds = cells, grid, bounds
        self.obstacles = tuple(obstacles)
        self.bounds_on_grid = bounds_on_grid
        self.error_bound, self.n_pieces, self.time = error_bound, n_pieces, seconds
        # what a point must be strictly outside of, exactly: each grown piece's facet planes
        # (n0, n1, n2, d: n . x <= d inside, Python ints, grid units), the closed meshes
        # taken whole; and strictly inside the frame's inner box (grid units)
        self._planes, self._meshes, self._inner = planes, meshes, inner
        free = np.nonzero(cells.winding == 0)[0]
        free = free[free != cells.unbounded]
        self._component = {int(c): k for k, c in enumerate(free.tolist())}
        self._cell = free
        self.n_components = len(free)
        self._mesh = None

    def __repr__(self) -> str:
        return (f"FreeSpace(components={self.n_components}, pieces={self.n_pieces}, "
                f"error_bound={self.error_bound:.3g}, time={self.time:.3f})")

    def _grid_point(self, q) -> tuple:
        """``q`` (scene units) as an exact homogeneous point ``(X, Y, Z, W)`` in grid units."""
        q = np.asarray(q, dtype=np.float64).reshape(3)
        if not np.isfinite(q).all():
            raise InvalidArgumentError(f"free_space: point {q.tolist()} is not finite")
        step = Fraction(2) ** self.grid.exponent
        x = [Fraction(float(v)) / step - o for v, o in zip(q, self.grid.origin)]
        W = math.lcm(*(v.denominator for v in x))
        return tuple(int(v * W) for v in x) + (W,)

    def _strictly_free(self, P: tuple) -> bool:
        """``P`` outside every grown piece (some facet plane strictly below it) and strictly
        inside the frame's inner box: exact, Python integers."""
        X, Y, Z, W = P
        lo, hi = self._inner
        if not all(lo[k] * W < P[k] < hi[k] * W for k in range(3)):
            return False
        for piece in self._planes:
            if not any(n0 * X + n1 * Y + n2 * Z > d * W for n0, n1, n2, d in piece):
                return False
        return True

    def _off_meshes(self, q) -> bool:
        """``q`` outside every closed mesh taken whole (their exact test: touching counts)."""
        return not any(bool(co.contains(q)) for co in self._meshes)

    def component_of(self, q) -> int | None:
        """The component holding the translation ``q`` (scene units), in
        ``range(n_components)``; None when ``q`` is not strictly outside the grown
        C-obstacles or not strictly inside the bounds (snapped outward)."""
        P = self._grid_point(q)
        if not self._strictly_free(P) or not self._off_meshes(q):
            return None
        cell = self.cells.locate(P)
        return None if cell is None else self._component.get(cell)

    def joined(self, start, goal) -> bool:
        """Whether a path proved to exist joins ``start`` and ``goal`` inside the bounds:
        both in one component, and the bounds on the grid (else the components are of the
        bounds snapped outward, up to a step larger: a path could leave the bounds). The
        grown union holds the C-obstacles, so its free space is free."""
        a = self.component_of(start)
        return self.bounds_on_grid and a is not None and a == self.component_of(goal)

    def sample(self, k: int) -> tuple:
        """A symbolic point strictly inside component ``k``, for :meth:`component_at` of
        this free space or another one of the same bounds (the same grid):
        :meth:`cspace.minkowski.union.UnionCells.sample`."""
        return self.cells.sample(int(self._cell[k]))

    def component_at(self, point: tuple) -> int | None:
        """The component holding a symbolic point of :meth:`sample` (None: on or in the
        grown C-obstacles, or outside the bounds)."""
        cell = self.cells.locate_key(*point)
        return None if cell is None else self._component.get(cell)

    def separation(self, start, goal) -> Separation | None:
        """A proof that ``start`` and ``goal`` are in different components, or None when they
        are in the same one (or either is not strictly free)."""
        a, b = self.component_of(start), self.component_of(goal)
        if a is None or b is None or a == b:
            return None
        cell = int(self._cell[a])
        P, Q = self._grid_point(start), self._grid_point(goal)
        w = (self.cells.winding_of_cell(cell, P), self.cells.winding_of_cell(cell, Q))
        if w[0] == w[1]:  # pragma: no cover - the joins and the windings disagree
            raise ExactnessError("free_space: two cells by the lines, one by the windings")
        points, faces = self.cells.cell_boundary(cell)
        V = _to_float_compiled(points, self.grid)
        return Separation(start=a, goal=b, winding=w, vertices=V, faces=faces)

    def component_mesh(self, k: int):
        """The boundary of component ``k`` as a trimesh (scene units, oriented away from it)."""
        import trimesh

        points, faces = self.cells.cell_boundary(int(self._cell[k]))
        return trimesh.Trimesh(_to_float_compiled(points, self.grid), faces, process=False)

    def to_trimesh(self):
        """The union's surface inside and around the bounds (the frame's inner box is its
        part facing the bounds), scene units, oriented outwards."""
        import trimesh

        if self._mesh is None:
            out = self.cells.boundary()
            self._mesh = (_to_float_compiled(out.points, self.grid), out.faces)
        return trimesh.Trimesh(*self._mesh, process=False)


def free_space(cspace, bounds=None, *, max_pieces: int = MAX_PIECES,
               max_pairs: int = MAX_PAIRS, time: float | None = None,
               memory=None) -> FreeSpace:
    """The exact free space of ``cspace`` (a :class:`~cspace.CSpace` at one orientation)
    inside ``bounds`` (default ``cspace.bounds``).

    Parameters
    ----------
    cspace : CSpace
    bounds : (2, 3) float64, optional
        Scene units; a flat axis (``lo == hi``: a planar problem) is widened by a step.
    max_pieces : int
        The most convex pieces it unites.
    max_pairs : int
        The most candidate pairs of their triangles (boxes meeting) it goes on with, counted
        before they are intersected: a few microseconds and some hundred bytes each.
    time : float, optional
        Wall seconds; past them :class:`TimeoutError` (a union too large to decide in
        the time given).
    memory : int or str, optional
        The memory budget (default ``$CSPACE_MEMORY``, else half of the memory available:
        :mod:`cspace.memory`), watched between stages and every few dozen planes.

    Raises
    ------
    TimeoutError
        Past ``time``.
    UnsupportedError
        A C-obstacle that meets the bounds is not made of convex pieces, or they number more
        than ``max_pieces``, or their triangles make more than ``max_pairs`` candidate pairs.
    MemoryBudgetError
        The union grew past the memory budget (stopped before the system kills it).
    """
    t0 = _time.perf_counter()
    deadline = t0 + time if time is not None else math.inf
    guard = MemoryGuard("free_space", memory)

    def check(stage: str, detail: str = "") -> None:
        if _time.perf_counter() > deadline:
            raise TimeoutError(f"free_space: out of time ({time} s) at {stage}{detail}")
        guard.check(stage, detail)

    b = np.asarray(cspace.bounds if bounds is None else bounds, dtype=np.float64).reshape(2, 3)
    if not (np.isfinite(b).all() and (b[0] <= b[1]).all()):
        raise InvalidArgumentError(f"free_space: bounds {b.tolist()} are not a box")
    G, (o_lo, o_hi), (s_lo, s_hi), inner = _frame_of(b)
    e, origin = G.exponent, np.asarray(G.origin, dtype=np.int64)
    meshes: list = []
    found, count, err = [], 0, 0.0
    operands = _operands(cspace, inner, G)
    for i, co in enumerate(operands):  # what each C-obstacle is made of, counted
        check("counting the pieces", f" (C-obstacle {i} of {len(operands)})")
        B = np.asarray(co.bounds, dtype=np.float64)
        if (B[1] < inner[0]).any() or (B[0] > inner[1]).any():
            continue  # does not meet the closed inner box: nothing inside it changes
        name = f"#{i}" + (f" ({co.name})" if getattr(co, "name", None) else "")
        got, closed, plans = _pieces(co, name, inner, check)
        found.append((name, got, plans))
        count += len(got) + sum(len(p.i) for p in plans)
        if count > max_pieces:
            raise UnsupportedError(
                f"free_space: more than {max_pieces} convex pieces meet the bounds (at "
                f"C-obstacle {name})")
        meshes += closed
        # a patch of nearly coplanar triangles adds its flatness (_pair_plan)
        err = max(err, float(co.error_bound) + max([p.extra for p in plans], default=0.0))
        check("pieces")
    # Before any piece is made: pairs of pieces whose boxes meet each make some hundreds of
    # candidate triangle pairs (the turned bottle: 430), so over max_pairs / 100 of them the
    # union would be declined after its pieces (the bug trap with the robot's hull: 589889
    # pairs of 2481 pieces, 370 s of hulls before the count said so).
    overlapping = _piece_pairs(found, G)
    if overlapping > max_pairs // 100:
        raise UnsupportedError(
            f"free_space: a union too large: {overlapping:,} pairs of its pieces overlap, "
            f"more than {max_pairs // 100:,} (some hundred candidate triangle pairs each)")

    def far(V: np.ndarray) -> bool:
        # Only a piece beyond the union's range on G is clipped to the outer box (exactly,
        # and slowly: fractions); one that merely crosses it is taken whole, and the frame's
        # outer box grows to hold it.
        return bool(np.abs(np.ldexp(V, -e) - origin).max() >= _UNCLIPPED)

    pieces = []
    for name, got, plans in found:
        for plan in plans:
            got = got + _pair_pieces(plan, name, far)
        for p in got:
            V = p.vertices if isinstance(p, ConvexPolytope) else p
            if (V.max(axis=0) >= inner[0]).all() and (V.min(axis=0) <= inner[1]).all():
                pieces.append(p if far(V) else V)
        check("pieces")
    ints, faces, facets, planes, n, n_facets, widened = [], [], [], [], 0, 0, 1
    for co in meshes:  # closed meshes: their own triangles, when their vertices are on G
        k = _on_grid(co, G)
        if k is None:
            raise UnsupportedError(
                f"free_space: C-obstacle {getattr(co, 'name', '')!r} (kind 'mesh') has "
                f"vertices off the union's grid (step 2**{e}) or beyond its range; the exact "
                "union takes closed meshes only on it")
        ints.append(k)
        F = np.asarray(co._impl.faces, dtype=np.int64)
        faces.append(F + n)
        facets.append(np.arange(len(F), dtype=np.int64) + n_facets)  # each on its own
        n += len(k)
        n_facets += len(F)
    for V in pieces:
        check("pieces")
        if not isinstance(V, np.ndarray):  # beyond the range: clipped to the outer box
            if not isinstance(V, ConvexPolytope):  # pragma: no cover - pieces are one of two
                raise TypeError(type(V))
            X = _clipped(V, o_lo, o_hi)
            if not X:
                continue
            step = Fraction(2) ** e
            k_lo = np.array([[math.floor(c / step) for c in x] for x in X], dtype=np.int64)
            k_hi = np.array([[math.ceil(c / step) for c in x] for x in X], dtype=np.int64)
            k_lo, k_hi = k_lo - origin, k_hi - origin
        else:
            s = np.ldexp(V, -e)  # exact: grid steps
            k_lo = np.floor(s).astype(np.int64) - origin
            k_hi = np.ceil(s).astype(np.int64) - origin
        pts = np.where(_CORNERS[None].astype(bool), k_hi[:, None, :], k_lo[:, None, :])
        try:
            P = ConvexPolytope.from_ints(pts.reshape(-1, 3), grid=G, name="piece")
        except DegenerateError:
            # flat (parallel triangles of an open surface, or a clip on the outer box): a
            # step more on every side gives it volume; the growth bound doubles
            widened = 2
            pts = np.where(_CORNERS[None].astype(bool), k_hi[:, None, :] + 1,
                           k_lo[:, None, :] - 1)
            P = ConvexPolytope.from_ints(pts.reshape(-1, 3), grid=G, name="piece")
        F, fid = P.triangles()
        ints.append(P.ints)
        faces.append(F + n)
        facets.append(fid + n_facets)  # one number per facet polygon: arranged whole
        n += len(P.ints)
        n_facets += P.n_facets
        planes.append(sorted(P.planes()))
    allp = np.vstack([s_lo, s_hi] + ints)
    f_lo, f_hi = allp.min(axis=0) - 2, allp.max(axis=0) + 2
    for lo_, hi_, out in ((f_lo, f_hi, True), (s_lo, s_hi, False)):
        V, F = _box_faces(lo_, hi_, out)
        ints.append(V)
        faces.append(F + n)
        facets.append(np.arange(12, dtype=np.int64) // 2 + n_facets)  # _BOX: a face's two
        n += 8
        n_facets += 6
    try:
        cells = UnionCells(np.vstack(ints), np.vstack(faces), check=check,
                           facet=np.concatenate(facets), max_pairs=max_pairs)
    except UnsupportedError as e:
        raise UnsupportedError(f"free_space: a union too large: {e}") from None
    return FreeSpace(cells, G, b, err + widened * math.sqrt(3.0) * G.step, len(pieces),
                     _time.perf_counter() - t0, planes=planes,
                     inner=(s_lo.tolist(), s_hi.tolist()), meshes=meshes,
                     bounds_on_grid=bool((inner == b).all()), obstacles=operands)
