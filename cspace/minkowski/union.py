"""The exact union of closed integer meshes, and the cells of its complement.

The input is a 2-cycle: the triangles of several closed, outward-oriented meshes on one grid
(integers below ``2**27`` in magnitude, the bound of the trimming's kernels). Its winding
number at a point is the number of meshes holding it, so the union is where it is positive.
The trimming's stages make the arrangement exactly as for a superset (:mod:`.planes`,
:mod:`.intersections`, :mod:`.arrangements`, :mod:`.traversal`): sub-facets, and their sides
grouped into shells (the boundary components of the arrangement's cells).

What the Minkowski sum's membership test does with one anchor, :class:`UnionCells` does with
**lines**: one line parallel to ``x`` per connected component of the complex, through a point
strictly inside one of its sub-facets, moved off every edge and vertex by the symbolic
perturbation ``(y, z) + (eps, eps**2)`` (``eps -> 0+``; a point-in-triangle test in the
``yz`` projection then has no ties, and hits are ordered by their exact ``x`` at the
perturbed point: Python integers and fractions). Along a line:

- two consecutive hits bound a segment in one cell: the shell on the ``+x`` side of the first
  and the one on the ``-x`` side of the next bound the same cell (they are joined); before the
  first hit and after the last the line is in the unbounded cell;
- the winding number is 0 at ``+x`` infinity and changes by the coverage across each hit, so
  every shell the line meets gets its winding number, and the rest of its component follows
  across sub-facets.

The joins are complete: a cell's shells are its outer shell (none for the unbounded cell) and
the outer shell of each component inside it, and the line of such a component, coming from
``-x`` infinity, enters the cell through its outer shell (or starts in it) and passes from one
of its shells to the next up to that component: one chain. So the classes of joined shells are
the cells.

Point location (:meth:`UnionCells.locate`) is the same line through the point: its cell is the
one on the ``-x`` side of the first hit beyond it. A proof that two points lie in different
cells does not rest on the joins (:meth:`UnionCells.winding_of_cell`): the boundary of one
point's cell, oriented away from it, is a closed 2-cycle in the union's surface; its winding
number is constant along any path that avoids that surface, so different values at the two
points prove that every path between them meets the union.
"""

from __future__ import annotations

from dataclasses import dataclass
from fractions import Fraction

import numpy as np

from ..errors import ExactnessError, InvalidArgumentError
from ..geometry.graphs import component_labels
from .arrangements import _complex
from .intersections import _cuts
from .membership import _face_point, _face_tris, _propagate
from .output import _output
from .planes import _plane_groups
from .traversal import _shells

#: Magnitude the integer coordinates must stay below (the trimming kernels' bound).
MAX_COORDINATE = 2**27


@dataclass
class _Cycle:
    """The input triangles as the trimming stages read a superset, each counted once:
    ``facet[t]`` names the convex polygon triangle ``t`` is a fan triangle of."""

    ints: np.ndarray
    faces: np.ndarray
    facet: np.ndarray

    def triangles(self):
        return self.faces, self.facet, np.ones(len(self.faces), dtype=np.int64)


def _sign(x) -> int:
    return (x > 0) - (x < 0)


class _Lines:
    """The sub-facets not parallel to ``x``, for lines parallel to ``x``: each one's float box
    in the ``yz`` projection (a filter only: it is padded beyond the conversions' error), and,
    made on first use by a line through its box, its triangles' vertices projected to ``yz``
    (fractions); ``across[f]``: sub-facet ``f`` is not parallel to ``x`` (lines meet only
    those). Triangulating only the sub-facets lines come near is most of the saving: lines
    are few (one per component, and the points located)."""

    def __init__(self, cx, planes):
        self.cx, self.planes = cx, planes
        nx = np.array([k[0] for k in planes.keys], dtype=np.int64)
        self.across = nx[cx.face_plane] != 0  # per sub-facet: not parallel to x
        self.face = np.nonzero(self.across)[0]
        P = cx.points
        lo = np.empty((len(self.face), 2))
        hi = np.empty((len(self.face), 2))
        for r, f in enumerate(self.face.tolist()):
            rings = cx.face_rings[f]
            ids = rings[0] if rings is not None else [i for t in cx.face_tris[f] for i in t]
            c = np.array([P[i][1:] for i in ids], dtype=np.float64)  # the outer ring holds it
            yz = c[:, :2] / c[:, 2:]
            lo[r], hi[r] = yz.min(axis=0), yz.max(axis=0)
        pad = 1e-9 * (np.maximum(np.abs(lo), np.abs(hi)).max(axis=1, initial=0.0) + 1.0)
        self.lo, self.hi = lo - pad[:, None], hi + pad[:, None]
        self._q: dict = {}
        # the side nodes on the -x and +x sides of each sub-facet, and the winding number's
        # change from the -x to the +x side (the coverage counts along planes.normal)
        m_x = np.array([planes.normal(p)[0] for p in range(len(planes.keys))],
                       dtype=np.int64)[cx.face_plane]
        f = np.arange(len(cx.face_plane))
        self.minus = np.where(m_x > 0, 2 * f, 2 * f + 1)
        self.plus = np.where(m_x > 0, 2 * f + 1, 2 * f)
        self.drop = np.where(m_x > 0, cx.face_cov, -cx.face_cov)  # w(-x side) - w(+x side)

    def _yz(self, i: int):
        q = self._q.get(i)
        if q is None:
            X, Y, Z, W = self.cx.points[i]
            q = self._q[i] = (Fraction(Y, W), Fraction(Z, W))
        return q

    def hits(self, y0: Fraction, z0: Fraction) -> list:
        """The sub-facets the line ``(t, y0 + eps, z0 + eps**2)`` meets, in increasing order
        of ``t``: ``[(key, f), ...]``; the hit is at ``x = k0 + k1 eps + k2 eps**2`` for
        ``key = (k0, k1, k2)`` (fractions; keys compare as tuples)."""
        yf, zf = float(y0), float(z0)
        cand = np.nonzero((self.lo[:, 0] <= yf) & (yf <= self.hi[:, 0])
                          & (self.lo[:, 1] <= zf) & (zf <= self.hi[:, 1]))[0]
        out = []
        for f in self.face[cand].tolist():
            for t in _face_tris(self.cx, f):
                a, b, c = (self._yz(i) for i in t)
                s = {self._side(a, b, y0, z0), self._side(b, c, y0, z0),
                     self._side(c, a, y0, z0)}
                if len(s) == 1:
                    break  # inside this triangle (the perturbed point is on no edge)
            else:
                continue
            n0, n1, n2, d = self.planes.keys[int(self.cx.face_plane[f])]
            x0 = (d - n1 * y0 - n2 * z0) / n0
            out.append(((x0, Fraction(-n1, n0), Fraction(-n2, n0)), f))
        out.sort(key=lambda h: h[0])
        for (k0, f0), (k1, f1) in zip(out, out[1:]):
            if k0 == k1:  # pragma: no cover - two sub-facets of one plane overlap
                raise ExactnessError(f"sub-facets {f0} and {f1} overlap on a line")
        return out

    @staticmethod
    def _side(a, b, y0, z0) -> int:
        """Side of ``(y0 + eps, z0 + eps**2)`` of the line ``a -> b`` (yz): never 0 for
        ``a != b``."""
        d0 = (b[0] - a[0]) * (z0 - a[1]) - (b[1] - a[1]) * (y0 - a[0])
        if d0:
            return _sign(d0)
        if b[1] != a[1]:
            return _sign(a[1] - b[1])
        return _sign(b[0] - a[0])


class UnionCells:
    """The arrangement of a 2-cycle of closed meshes' triangles, its cells, and their winding
    numbers (the number of meshes holding each cell).

    Parameters
    ----------
    ints : (n, 3) int64
        Grid integers, ``|k| < 2**27``.
    faces : (m, 3) int64
        Triangles of closed meshes, counter-clockwise seen from outside each.
    workers : int
        Processes for the intersections and arrangements (as the trimming's).
    check : callable, optional
        ``check(stage, detail='')``, called between stages, every 64 planes and every
        line: it may raise to stop the work (a deadline, a memory budget).
    facet : (m,) int64, optional
        Triangles with one number are the fan of one convex polygon (a facet of a convex
        piece): a plane holding only those is arranged whole, in one compiled call (as the
        trimming's planes of one superset facet). Default: each triangle on its own.
    max_pairs : int, optional
        The most candidate triangle pairs (boxes meeting, on different planes) it goes on
        with: beyond, :class:`~cspace.errors.UnsupportedError`, found share by share before
        they are all made (their cuts take some microseconds each, their arrays memory).

    Attributes
    ----------
    n_cells : int
        Cells of the arrangement (the unbounded one included).
    cell_of_shell : (s,) int64
        The cell each shell bounds; ``unbounded`` is the unbounded cell's number.
    winding : (n_cells,) int64
        The input's winding number in each cell (> 0: inside the union).
    """

    def __init__(self, ints: np.ndarray, faces: np.ndarray, *, workers: int = 1, check=None,
                 facet: np.ndarray | None = None, max_pairs: int | None = None):
        ints = np.asarray(ints, dtype=np.int64).reshape(-1, 3)
        faces = np.asarray(faces, dtype=np.int64).reshape(-1, 3)
        if len(ints) and np.abs(ints).max() >= MAX_COORDINATE:
            raise InvalidArgumentError(
                f"union: coordinates must be below 2**27 in magnitude, got {np.abs(ints).max()}")
        if not len(faces):
            raise InvalidArgumentError("union: no triangles")
        if check is None:
            check = lambda stage, detail="": None  # noqa: E731 - nothing watched
        facet = (np.arange(len(faces), dtype=np.int64) if facet is None
                 else np.asarray(facet, dtype=np.int64).reshape(len(faces)))
        S = _Cycle(ints, faces, facet)
        planes = _plane_groups(S)
        cuts = _cuts(ints, planes, workers, max_pairs)
        check("intersections")
        cx, _ = _complex(ints, planes, cuts, lambda *a: None, workers, check)
        check("arrangements")
        sh = _shells(cx, planes)
        check("traversal")
        self.cx, self.planes, self.shells = cx, planes, sh
        self.lines = _Lines(cx, planes)
        nf = len(cx.face_plane)
        # components of the complex: sub-facets joined across shared edges
        order = np.argsort(cx.inc_edge, kind="stable")
        same = cx.inc_edge[order[1:]] == cx.inc_edge[order[:-1]]
        _, comp = component_labels(nf, cx.inc_face[order[:-1]][same], cx.inc_face[order[1:]][same])
        n_comp = int(comp.max()) + 1 if nf else 0
        U = sh.n  # the unbounded cell's node among the shells joined below
        ja: list = []  # shells joined: (ja[k], jb[k]) bound one cell
        jb: list = []
        w = [None] * sh.n

        def put(s: int, v: int) -> None:
            if w[s] is None:
                w[s] = v
            elif w[s] != v:
                raise ExactnessError("inconsistent winding numbers along a line")

        of, lines = sh.of.tolist(), self.lines
        minus, plus, drop = lines.minus.tolist(), lines.plus.tolist(), lines.drop.tolist()
        first = np.full(n_comp, -1, dtype=np.int64)
        cand = np.nonzero(lines.across)[0]
        first[comp[cand][::-1]] = cand[::-1]  # each component's first sub-facet not along x
        if (first < 0).any():  # pragma: no cover - a closed surface has one
            raise ExactnessError("a component of the union has no sub-facet across x")
        self.anchor = None
        for f in first.tolist():
            check("lines")
            X, Y, Z, W = _face_point(cx, f)
            hits = lines.hits(Fraction(Y, W), Fraction(Z, W))
            sides = [(of[minus[g]], of[plus[g]]) for _, g in hits]
            ja += [U, sides[-1][1]] + [b for _, b in sides[:-1]]
            jb += [sides[0][0], U] + [c for c, _ in sides[1:]]
            v = 0
            for (_, g), (a, b) in zip(reversed(hits), reversed(sides)):
                put(b, v)
                v += drop[g]
                put(a, v)
            if self.anchor is None:
                self.anchor = minus[hits[0][1]]
        _propagate(cx, sh, w)  # the rest of each component's shells, across sub-facets
        self.n_cells, cell_of = component_labels(sh.n + 1, np.array(ja, dtype=np.int64),
                                                 np.array(jb, dtype=np.int64))
        cell_of = cell_of.astype(np.int64)
        self.cell_of_shell = cell_of[:-1]
        self.unbounded = int(cell_of[-1])
        wind = np.zeros(self.n_cells, dtype=np.int64)
        seen = np.zeros(self.n_cells, dtype=bool)
        for s, c in enumerate(self.cell_of_shell.tolist()):
            if seen[c] and wind[c] != w[s]:
                raise ExactnessError("two shells of one cell with different winding numbers")
            wind[c], seen[c] = w[s], True
        if wind[self.unbounded] != 0:
            raise ExactnessError("the unbounded cell has a non-zero winding number")
        self.winding = wind

    def __repr__(self) -> str:
        return (f"UnionCells(subfacets={len(self.cx.face_plane)}, shells={self.shells.n}, "
                f"cells={self.n_cells}, outside={int((self.winding == 0).sum())})")

    # ---- points ---------------------------------------------------------------------------

    def locate(self, P4: tuple) -> int | None:
        """The cell holding the point ``(X, Y, Z, W)`` (homogeneous grid units, ``W > 0``),
        or None when it lies on a sub-facet the line through it meets. (A point on a
        sub-facet parallel to ``x``, or on an edge, may be given a cell beside it: callers
        test that the point is off the union's surface first.)"""
        X, Y, Z, W = (int(v) for v in P4)
        x = Fraction(X, W)
        hits = self.lines.hits(Fraction(Y, W), Fraction(Z, W))
        for key, g in hits:
            if key[0] == x:
                return None
            if key[0] > x:
                return int(self.cell_of_shell[self.shells.of[self.lines.minus[g]]])
        return self.unbounded

    def locate_key(self, y0: Fraction, z0: Fraction, key: tuple) -> int | None:
        """The cell holding the symbolic point ``(k0 + k1 eps + k2 eps**2, y0 + eps,
        z0 + eps**2)`` (:meth:`sample`'s), or None when it lies on the union's surface
        (exact: such a point is on no sub-facet parallel to ``x``, and on another only
        where the line's hit there has its key)."""
        for k, g in self.lines.hits(y0, z0):
            if k == key:
                return None
            if k > key:
                return int(self.cell_of_shell[self.shells.of[self.lines.minus[g]]])
        return self.unbounded

    def sample(self, cell: int) -> tuple:
        """A symbolic point strictly inside ``cell``: ``(y0, z0, key)`` for
        :meth:`locate_key` (here or in another arrangement on the same grid). On the line
        through a point of a sub-facet the cell bounds, between that hit and the next one
        on the cell's side."""
        cs, of, L = self.cell_of_shell, self.shells.of, self.lines
        for f in np.nonzero(L.across)[0].tolist():
            below, above = cs[of[L.minus[f]]] == cell, cs[of[L.plus[f]]] == cell
            if not (below or above):
                continue
            X, Y, Z, W = _face_point(self.cx, f)
            y0, z0 = Fraction(Y, W), Fraction(Z, W)
            hits = L.hits(y0, z0)
            at = next(i for i, (_, g) in enumerate(hits) if g == f)
            key = hits[at][0]
            nxt = at - 1 if below else at + 1
            if 0 <= nxt < len(hits):
                other = hits[nxt][0]
                return y0, z0, tuple((a + b) / 2 for a, b in zip(key, other))
            step = -1 if below else 1  # no hit beyond: one unit further out
            return y0, z0, (key[0] + step, key[1], key[2])
        raise InvalidArgumentError(f"union: cell {cell} has no sub-facet across x")

    def winding_of_cell(self, cell: int, P4: tuple) -> int:
        """Winding number at ``P4`` of the boundary of ``cell``, oriented away from it: the
        sub-facets with the cell on one side only, counted ``+1`` where the line from the
        point leaves through them towards ``+x`` from the cell's side, ``-1`` where it
        enters. ``P4`` must not lie on the boundary."""
        X, Y, Z, W = (int(v) for v in P4)
        x = Fraction(X, W)
        cs, of = self.cell_of_shell, self.shells.of
        n = 0
        for (x0, _, _), g in self.lines.hits(Fraction(Y, W), Fraction(Z, W)):
            if x0 <= x:
                if x0 == x:
                    raise InvalidArgumentError("the point lies on the union's surface")
                continue
            a = cs[of[self.lines.minus[g]]] == cell
            b = cs[of[self.lines.plus[g]]] == cell
            n += int(a) - int(b)
        return n

    # ---- surfaces -------------------------------------------------------------------------

    def boundary(self):
        """The union's surface: :class:`cspace.minkowski.output._Output` (exact points,
        triangles oriented outwards)."""
        inside = self.winding[self.cell_of_shell] > 0
        return _output(self.cx, self.shells, inside, self.anchor, self.planes, None)

    def cell_boundary(self, cell: int) -> tuple[list, np.ndarray]:
        """The sub-facets with ``cell`` on one side only, as triangles oriented away from it:
        ``(points, faces)`` (exact homogeneous points in grid units, ``(t, 3)`` int64)."""
        cs = self.cell_of_shell[self.shells.of]
        nf = len(self.cx.face_plane)
        on_plus = cs[2 * np.arange(nf) + 1] == cell
        on_minus = cs[2 * np.arange(nf)] == cell
        tris = []
        for f in np.nonzero(on_plus != on_minus)[0].tolist():
            for a, b, c in _face_tris(self.cx, f):
                # the cell on the side the normal points into: away from it is reversed
                tris.append((a, c, b) if on_plus[f] else (a, b, c))
        T = np.array(tris, dtype=np.int64).reshape(-1, 3)
        used, T = np.unique(T, return_inverse=True)
        return [self.cx.points[i] for i in used.tolist()], T.reshape(-1, 3)
