"""Open surfaces against a convex robot as a union of exact hulls: the reference construction.

An open (or non-manifold) obstacle surface bounds no solid: the robot meets it exactly when
it meets one of its triangles ``t``, i.e. when its reference point ``q`` lies in the convex
piece ``t ⊕ (c - R)`` (the exact hull of the ``3 |R|`` vertex sums on the scene grid). This is
the semantics of FCL's mesh (BVH) collision: a robot entirely inside a closed-looking but
unclosed surface touches nothing.

Scenes no longer build this (one hull per triangle, about a millisecond each: minutes for an
apartment-class world); they build the same set as triangle pairs
(:mod:`cspace.cobstacle.pairs`). :class:`SurfaceObstacle` stays as the pure-Python reference
those are tested against: any union of exact convex pieces (:meth:`SurfaceObstacle.build` for a
surface and a convex robot, or the hulls of :func:`cspace.cobstacle.pairs.triangle_pair_pieces`),
each decided by the convex engine of :mod:`cspace.cobstacle.convex`. Its broad phase bins the
pieces' bounding boxes (exact: grid coordinates) into a uniform grid of cells
(:class:`_CellGrid`, shared with :mod:`cspace.cobstacle.pairs_reference`), so a point query
looks at the few pieces registered in its cell; every candidate is then tested exactly.
:class:`SurfaceMesh` is the snapped surface a C-obstacle names as its obstacle.

Queries take ``(k, 3)`` float64 translations (scene units, world frame), like every CO.
"""

from __future__ import annotations

import math
import time
from dataclasses import dataclass

import numpy as np

from ..mesh.convex import ConvexPolytope
from ..geometry.exact import _FILTER, _TINY, Grid
from .margin import Margin
from .obstacle import CSpaceObstacle
from .convex import _ConvexCO

__all__ = ["SurfaceMesh", "SurfaceObstacle", "surface_pieces"]

# Candidate (query, piece) pairs evaluated at once.
_PAIRS = 1 << 12
# Padding plane value: never the maximum of a piece's real facet values.
_PAD = -1e300


@dataclass(frozen=True, eq=False)
class SurfaceMesh:
    """The obstacle surface a :class:`SurfaceObstacle` was built from (world frame).

    Attributes
    ----------
    vertices : (n, 3) float64
        Snapped to the scene grid.
    faces : (m, 3) int64
        The triangles whose pieces make up the C-obstacle.
    name : str
    """

    vertices: np.ndarray
    faces: np.ndarray
    name: str = "surface"


def surface_pieces(ints: np.ndarray, faces: np.ndarray, minus_robot: ConvexPolytope,
                   progress=None, *, grid: Grid | None = None) -> list[ConvexPolytope]:
    """The convex pieces ``t ⊕ (c - R)`` of the triangles ``t`` of a surface, exactly.

    Parameters
    ----------
    ints : (n, 3) int64
        Surface vertices in grid units of ``grid``.
    faces : (m, 3) int64
    minus_robot : ConvexPolytope
        ``R.reflected(c)`` on the same step.
    progress : callable, optional
        ``progress(fraction)`` every 64 pieces.
    grid : Grid, optional
        The frame of ``ints`` (default ``minus_robot.grid``'s vectors: origin 0); the pieces
        are in ``grid.plus(minus_robot.grid)``.

    Returns
    -------
    list of ConvexPolytope
        One per triangle (a triangle with collinear corners gives the segment's sum).
    """
    grid = (minus_robot.grid.vectors if grid is None else grid).plus(minus_robot.grid)
    r = minus_robot.ints
    tri = np.asarray(ints, dtype=np.int64)[np.asarray(faces, dtype=np.int64)]  # (m, 3, 3)
    out = []
    for i, t in enumerate(tri):
        pts = (t[:, None, :] + r[None, :, :]).reshape(-1, 3)
        out.append(ConvexPolytope.from_ints(pts, grid=grid, name=f"piece {i}"))
        if progress is not None and (i % 64 == 63 or i + 1 == len(tri)):
            progress((i + 1) / len(tri))
    return out


class _CellGrid:
    """Uniform grid of cells over boxes: which boxes may hold a point (internal).

    ``cell(x) = clip(floor((x - origin) / size), 0, n - 1)`` per axis is monotone in ``x``
    (rounded subtraction and division are monotone), so ``lo <= q <= hi`` implies that
    ``q``'s cell lies in the box's cell range: no box holding ``q`` is missed.
    """

    def __init__(self, lo: np.ndarray, hi: np.ndarray, target: float = 2.0):
        self.origin = lo.min(axis=0)
        extent = np.maximum(hi.max(axis=0) - self.origin, 1e-300)
        # About `target` boxes per cell on average, at most 128 cells per axis.
        per_box = np.maximum(np.median(hi - lo, axis=0), extent / 128.0)
        self.n = np.clip(np.ceil(extent / per_box / target ** (1 / 3)), 1, 128).astype(np.int64)
        self.size = extent / self.n
        i0, i1 = self.cells(lo), self.cells(hi)
        span = i1 - i0 + 1
        count = span.prod(axis=1)
        box = np.repeat(np.arange(len(lo)), count)
        local = np.arange(count.sum()) - np.repeat(np.cumsum(count) - count, count)
        syz = (span[:, 1] * span[:, 2])[box]
        a, rem = np.divmod(local, syz)
        b, c = np.divmod(rem, span[box, 2])
        cell = self._flat(i0[box] + np.stack([a, b, c], axis=1))
        order = np.argsort(cell, kind="stable")
        self.boxes = box[order]
        self.starts = np.searchsorted(cell[order], np.arange(self.n.prod() + 1))
        self._origin, self._size = self.origin.tolist(), self.size.tolist()
        self._n = self.n.tolist()

    def cells(self, x: np.ndarray) -> np.ndarray:
        with np.errstate(invalid="ignore", over="ignore"):
            i = np.floor((x - self.origin) / self.size)
        return np.clip(np.nan_to_num(i, nan=0.0), 0, self.n - 1).astype(np.int64)

    def _flat(self, i: np.ndarray) -> np.ndarray:
        return (i[:, 0] * self.n[1] + i[:, 1]) * self.n[2] + i[:, 2]

    def pairs(self, q: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Candidate ``(row, box)`` pairs: every box registered in each query's cell."""
        if len(q) == 1:  # one query (an OMPL callback): Python floats, the same rounding
            c = 0
            for x, o, s, n in zip(q[0].tolist(), self._origin, self._size, self._n):
                v = min(max((x - o) / s, 0.0), n - 1.0)
                c = c * n + int(math.floor(v))
            boxes = self.boxes[self.starts[c] : self.starts[c + 1]]
            return np.zeros(len(boxes), dtype=np.int64), boxes
        cell = self._flat(self.cells(q))
        s, e = self.starts[cell], self.starts[cell + 1]
        count = e - s
        rows = np.repeat(np.arange(len(q)), count)
        idx = np.arange(count.sum()) - np.repeat(np.cumsum(count) - count, count)
        return rows, self.boxes[np.repeat(s, count) + idx]


class _UnionCO:
    """Exact queries on a union of convex pieces (the engine interface of :mod:`cspace.cobstacle.convex`)."""

    def __init__(self, pieces: list[ConvexPolytope], impl: list[_ConvexCO] | None = None):
        if not pieces:
            raise ValueError("a surface C-obstacle needs at least one piece")
        self.pieces = list(pieces)
        self.exponent = pieces[0].grid.exponent
        self.impl = list(impl) if impl is not None else [_ConvexCO(p) for p in self.pieces]
        V = [p.vertices for p in self.pieces]
        self.lo = np.array([v.min(axis=0) for v in V])
        self.hi = np.array([v.max(axis=0) for v in V])
        fmax = max(c.A.shape[1] for c in self.impl)
        self.A = np.zeros((len(pieces), 4, fmax))
        self.A[:, 3, :] = _PAD
        for j, c in enumerate(self.impl):
            self.A[j, :, : c.A.shape[1]] = c.A
        self.absA = np.abs(self.A)
        self.absA[:, 3, :] = 0.0  # padding: exactly -1e300, no error
        self.cells = _CellGrid(self.lo, self.hi)

    def _in_box(self, q: np.ndarray, j: np.ndarray) -> np.ndarray:
        return ((self.lo[j] <= q) & (q <= self.hi[j])).all(axis=1)

    def candidates(self, q: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """``(row, piece)`` pairs whose piece box holds the query (exact box test)."""
        rows, j = self.cells.pairs(q)
        keep = self._in_box(q[rows], j)
        return rows[keep], j[keep]

    def contains(self, q: np.ndarray) -> np.ndarray:
        out = np.zeros(len(q), dtype=bool)
        rows, js = self.candidates(q)
        for lo in range(0, len(rows), _PAIRS):
            r, j = rows[lo : lo + _PAIRS], js[lo : lo + _PAIRS]
            Q = np.ones((len(r), 1, 4))
            with np.errstate(over="ignore", under="ignore", invalid="ignore"):
                np.ldexp(q[r], -self.exponent, out=Q[:, 0, :3])
                # n . qs - d per (pair, facet), with the per-entry bound of cobstacle/convex.py's
                # convex engine (the facets of a piece have normals of very different sizes).
                val = np.matmul(Q, self.A[j])[:, 0, :]
                err = _FILTER * np.matmul(np.abs(Q), self.absA[j])[:, 0, :] + _TINY
            fin = np.isfinite(val) & np.isfinite(err)
            inside = ((val < -err) & fin).all(axis=1)
            unsure = ~inside & ~((val > err) & fin).any(axis=1)
            for k in np.nonzero(unsure)[0].tolist():
                if not out[r[k]]:
                    inside[k] = bool(self.impl[j[k]]._contains_slow(q[r[k] : r[k] + 1])[0])
            out[r[inside]] = True
        return out

    def _segment_pairs(self, a: np.ndarray, b: np.ndarray):
        lo, hi = np.minimum(a, b), np.maximum(a, b)
        rows, js = [], []
        step = max(1, (1 << 20) // len(self.lo))
        for s in range(0, len(a), step):
            m = ((self.lo[None] <= hi[s : s + step, None]) & (lo[s : s + step, None] <= self.hi[None])).all(axis=2)
            r, j = np.nonzero(m)
            rows.append(r + s)
            js.append(j)
        return np.concatenate(rows), np.concatenate(js)

    def _separated(self, q0, q1, rows, js) -> np.ndarray:
        """Pairs whose segment ends are both strictly beyond one facet plane (certainly free)."""
        out = np.zeros(len(rows), dtype=bool)
        for lo in range(0, len(rows), _PAIRS):
            r, j = rows[lo : lo + _PAIRS], js[lo : lo + _PAIRS]
            beyond = None
            for q in (q0, q1):
                Q = np.ones((len(r), 1, 4))
                with np.errstate(over="ignore", under="ignore", invalid="ignore"):
                    np.ldexp(q[r], -self.exponent, out=Q[:, 0, :3])
                    val = np.matmul(Q, self.A[j])[:, 0, :]
                    err = _FILTER * np.matmul(np.abs(Q), self.absA[j])[:, 0, :] + _TINY
                    side = (val > err) & np.isfinite(val) & np.isfinite(err)
                beyond = side if beyond is None else beyond & side
            out[lo : lo + _PAIRS] = beyond.any(axis=1)
        return out

    def segments(self, q0: np.ndarray, q1: np.ndarray, want_t: bool):
        hit = np.zeros(len(q0), dtype=bool)
        t = np.full(len(q0), np.nan)
        rows, js = self._segment_pairs(q0, q1)
        open_ = ~self._separated(q0, q1, rows, js)
        # No candidate at all (no segment's box meets a piece) is no group, not an empty one.
        for j, r in self._by_piece(rows[open_], js[open_]):
            if not want_t:
                r = r[~hit[r]]  # already hit: no need to look further
                if not r.size:
                    continue
            h, tt = self.impl[j].segments(q0[r], q1[r], want_t)
            hit[r] |= h
            if want_t:
                t[r] = np.fmin(t[r], tt)
        return hit, t

    def signed_distance(self, q: np.ndarray) -> np.ndarray:
        inside = self.contains(q)
        out = np.zeros(len(q))
        if inside.any():
            qi = q[inside]
            rows, js = self.candidates(qi)
            depth = np.zeros(len(qi))
            for j, r in self._by_piece(rows, js):
                hit = self.impl[j].contains(qi[r])
                if hit.any():
                    depth[r[hit]] = np.maximum(depth[r[hit]], self.impl[j].depth(qi[r[hit]]))
            # The deepest containing piece: a lower bound on the union's depth.
            out[inside] = -depth
        if (~inside).any():
            out[~inside] = self._distance_outside(q[~inside])
        return out

    @staticmethod
    def _by_piece(rows: np.ndarray, js: np.ndarray):
        """``(piece, rows)`` groups of candidate pairs."""
        if not len(js):
            return
        order = np.argsort(js, kind="stable")
        rows, js = rows[order], js[order]
        cuts = np.flatnonzero(np.r_[True, js[1:] != js[:-1], True])
        for s, e in zip(cuts[:-1], cuts[1:]):
            yield int(js[s]), rows[s:e]

    def _distance_outside(self, p: np.ndarray) -> np.ndarray:
        """Distance to the nearest piece (points outside every piece), vectorised per piece:
        the nearest box's piece gives an upper bound, then only pieces whose box is nearer
        than the bound are evaluated."""
        best = np.full(len(p), np.inf)
        step = max(1, (1 << 20) // len(self.lo))
        for lo in range(0, len(p), step):
            q = p[lo : lo + step]
            gap = np.maximum(np.maximum(self.lo[None] - q[:, None], q[:, None] - self.hi[None]), 0)
            box = np.sqrt(np.einsum("kpj,kpj->kp", gap, gap))
            b = best[lo : lo + len(q)]
            first = box.argmin(axis=1)
            for j, r in self._by_piece(np.arange(len(q)), first):
                b[r] = self.impl[j].distance_outside(q[r])
            rows, js = np.nonzero(box < b[:, None])
            for j, r in self._by_piece(rows, js):
                b[r] = np.minimum(b[r], self.impl[j].distance_outside(q[r]))
            best[lo : lo + len(q)] = b
        return best


class SurfaceObstacle(CSpaceObstacle):
    """The C-obstacle of an open obstacle surface: the union of its pieces ``t ⊕ (c - R)``.

    Build with :meth:`build`. Answers ``contains``, ``segment_free``, ``first_contact`` and
    ``signed_distance`` exactly like :class:`~cspace.CSpaceObstacle` (touching counts);
    inside, ``signed_distance`` is minus the deepest containing piece's depth, a lower bound
    on the union's penetration depth.

    Attributes
    ----------
    pieces : list of ConvexPolytope
        One convex piece per triangle, exact on :attr:`grid`.
    obstacle : SurfaceMesh
        The snapped surface (world frame).
    robot : ConvexPolytope
        The robot in its frame (reference point not subtracted).
    reference_point : (3,) float64
        Snapped.
    grid : Grid
    kind : 'surface'
    """

    kind = "surface"

    def __init__(self, pieces, *, obstacle: SurfaceMesh, robot: ConvexPolytope,
                 reference_point, grid: Grid, _impl: list | None = None):
        self.pieces = list(pieces)
        self.polytope = None
        self.obstacle = obstacle
        self.robot = robot
        self.reference_point = np.asarray(reference_point, dtype=np.float64).reshape(3)
        self.grid = grid
        self.margin = Margin.none(grid)  # set by model_scene when the robot was grown
        self._impl = _UnionCO(self.pieces, _impl)
        self.stats: dict = {}

    @classmethod
    def build(cls, obstacle, robot: ConvexPolytope, reference_point=(0.0, 0.0, 0.0), *,
              grid: Grid, name: str = "surface", progress=None) -> "SurfaceObstacle":
        """Build the pieces of every triangle of a surface.

        Parameters
        ----------
        obstacle : (vertices (n, 3) float64, faces (m, 3) int64)
            Any triangles (open, non-manifold, repeated: each is one piece), world frame.
        robot : ConvexPolytope
            On ``grid``'s step (re-snapped onto it otherwise), in its own frame.
        reference_point : (3,) float64
        grid : Grid
            The scene grid; it must hold the C-obstacle's coordinates
            (``Scene.grid()``).
        progress : callable, optional
            ``progress(fraction)`` while the pieces are built.
        """
        V, F = obstacle
        F = np.asarray(F, dtype=np.int64)
        ints = grid.snap(np.asarray(V, dtype=np.float64))
        c = np.asarray(reference_point, dtype=np.float64).reshape(3)
        if not robot.grid.same_step(grid):
            robot = robot.on_grid(grid.for_robot(robot.vertices, c))
        rgrid = robot.grid
        t0 = time.perf_counter()
        pieces = surface_pieces(ints, F, robot.reflected(c), progress, grid=grid)
        out = cls(pieces, obstacle=SurfaceMesh(grid.to_float(ints), F, name), robot=robot,
                  reference_point=rgrid.to_float(rgrid.snap(c)), grid=grid)
        out.stats = {"pieces": len(pieces), "seconds": time.perf_counter() - t0}
        return out

    @property
    def n_facets(self) -> int:
        """Facets over all pieces."""
        return int(sum(p.n_facets for p in self.pieces))

    @property
    def vertices(self) -> np.ndarray:
        """(n, 3) float64 vertices of all pieces (overlapping convex pieces, for drawing)."""
        return np.vstack([p.vertices for p in self.pieces])

    @property
    def faces(self) -> np.ndarray:
        """(m, 3) int64 triangles of all pieces' boundaries (pieces overlap)."""
        offsets = np.cumsum([0] + [len(p.ints) for p in self.pieces[:-1]])
        return np.vstack([p.faces + o for p, o in zip(self.pieces, offsets)])

    @property
    def bounds(self) -> np.ndarray:
        impl = self._impl
        return np.stack([impl.lo.min(axis=0), impl.hi.max(axis=0)])

    def plane_signs(self, q) -> np.ndarray:
        raise TypeError("plane_signs is defined for a convex C-obstacle, not a union of pieces")
