"""NCC-CVMS §3.4, stage ``membership``: which cells of the arrangement are inside the sum.

The unbounded cell is found exactly. Of the reduced superset (the default,
:func:`_classify_reduced`) a cell behind a facet is inside; of the whole superset
(:func:`_classify`) its winding number is propagated across sub-facets (non-zero: inside). The
other bounded cells (holes, rings inside the sum) are decided by an exact separating-axis test
at a symbolic point beside a sub-facet (:class:`_PieceTest`): q is in the sum iff q − B meets
A's surface or lies inside A.
"""

from __future__ import annotations

from collections import deque
from math import gcd

import numpy as np

from ..errors import ExactnessError
from ..geometry.tritri import _dot, _orient3
from ..mesh.closed import ClosedMesh
from ..mesh.convex import ConvexPolytope
from .arrangements import _Complex
from ..geometry.homogeneous import _hnorm
from .planes import _Planes
from .superset import Superset
from .traversal import _Shells
from .triangulation import triangulate_rings


def _anchor(cx: _Complex, planes: _Planes, S: Superset, B: ConvexPolytope) -> int:
    """Side node facing the unbounded cell: on the supporting plane of the sum in the direction
    ``u`` of B's first facet normal, the side towards ``+u`` (nothing of the superset lies
    beyond that plane, and the corner facets there have coverage 1)."""
    u = tuple(int(c) for c in B.normals[0])
    pts = S.ints.astype(object)
    h = max((pts[:, 0] * u[0] + pts[:, 1] * u[1] + pts[:, 2] * u[2]).tolist())
    g = gcd(u[0], u[1], u[2], h)
    n, d = tuple(c // g for c in u), h // g
    if next(c for c in n if c != 0) < 0:
        n, d = tuple(-c for c in n), -d
    try:
        p = planes.keys.index((*n, d))
    except ValueError:
        raise ExactnessError("no sub-facet on the supporting plane of the sum") from None
    faces = np.nonzero(cx.face_plane == p)[0]
    if not len(faces):
        raise ExactnessError("no sub-facet on the supporting plane of the sum")
    s = _dot(planes.normal(p), u) > 0
    return 2 * int(faces[0]) + int(s)


def _winding(cx: _Complex, sh: _Shells, anchor: int) -> np.ndarray:
    """Winding number of the superset on each shell's cell, propagated from the unbounded
    cell (0) across sub-facets: it is larger by the coverage on the side a sub-facet's
    normal points away from."""
    w = [None] * sh.n
    w[int(sh.of[anchor])] = 0
    _propagate(cx, sh, w)
    # Shells of complex components not connected to the outer one (A with several surface
    # components, e.g. an inner cavity) get no winding number here: marked unknown.
    return np.array([_UNKNOWN if v is None else v for v in w], dtype=np.int64)


def _propagate(cx: _Complex, sh: _Shells, w: list) -> None:
    """Fill in ``w`` (winding number per shell, None where unknown) from the shells known,
    across sub-facets: ``w(minus side) = w(plus side) + coverage``. Raises ExactnessError
    where two routes disagree."""
    nf = len(cx.face_plane)
    plus, minus = sh.of[2 * np.arange(nf) + 1], sh.of[2 * np.arange(nf)]
    adj: list = [[] for _ in range(sh.n)]
    for a, b, c in zip(plus.tolist(), minus.tolist(), cx.face_cov.tolist()):
        adj[a].append((b, c))
        adj[b].append((a, -c))
    queue = deque(s for s in range(sh.n) if w[s] is not None)
    while queue:
        x = queue.popleft()
        for y, c in adj[x]:
            if w[y] is None:
                w[y] = w[x] + c
                queue.append(y)
            elif w[y] != w[x] + c:
                raise ExactnessError("inconsistent winding numbers across the sub-facet complex")


_UNKNOWN = np.iinfo(np.int64).min


# Float filter of _PieceTest: each separating-axis value is a sum of a few products of
# float64 numbers; its rounding error is below a few ulps of ``mag`` (the sum of the absolute
# products). Values within this bound are re-decided with Python integers.
_FILTER = 64 * float(np.finfo(np.float64).eps)


class _PieceTest:
    """Exact test of ``q = p + eps * v`` (eps -> 0+) against the convex pieces ``t ⊕ B`` of A⊕B
    (t a triangle of A), by separating axes: the normals of t, of B's facets and the cross
    products of their edges contain every facet normal of ``t ⊕ B``."""

    def __init__(self, A: ClosedMesh, B: ConvexPolytope):
        T = A.ints[A.faces].astype(np.int64)
        self.T = T
        self.lo = T.min(axis=1) + B.ints.min(axis=0)
        self.hi = T.max(axis=1) + B.ints.max(axis=0)
        self.Bv = B.ints.astype(np.int64)
        self.nB = B.normals.astype(np.int64)
        be = B.ints[B.edges[:, 1]] - B.ints[B.edges[:, 0]]
        self.eB = be.astype(np.int64)
        self.Bo = B.ints.astype(object)
        # the normals of the two facets at each edge of B (its Gauss arc)
        self.n1 = self.nB[B.edge_facets[:, 0]].astype(np.float64)
        self.n2 = self.nB[B.edge_facets[:, 1]].astype(np.float64)
        self.Bf = self.Bv.astype(np.float64)
        self._Bmax = np.abs(self.Bf).max(axis=0)
        self._pieces: dict = {}  # triangle -> _piece(t), reused by every point tested

    # Pieces kept for reuse: a folded superset asks for the same triangles of A for many
    # cells (oblong ⊕ ico320: 100135 piece tests over 20322 cells); one piece holds a few
    # hundred axes (some 10-20 KB), so the cache stays below about 80 MB.
    _MAX_PIECES = 4096

    def _piece(self, t: int) -> tuple:
        """Per triangle ``t`` of A: its axes ``U`` (ints, :meth:`axes`), as floats, the
        float support ``h(u) = max_T u.x + max_B u.y`` per axis, and the part of the filter's
        magnitude that does not depend on the point."""
        p = self._pieces.get(t)
        if p is None:
            if len(self._pieces) >= self._MAX_PIECES:
                self._pieces.clear()
            U = self.axes(t)
            Uf = U.astype(np.float64)
            Tf = self.T[t].astype(np.float64)
            h = (Uf @ Tf.T).max(axis=1) + (Uf @ self.Bf.T).max(axis=1)
            mag = np.abs(Uf) @ (np.abs(Tf).max(axis=0) + self._Bmax)
            p = self._pieces[t] = (U, Uf, h, mag, np.abs(Uf))
        return p

    def axes(self, t: int) -> np.ndarray:
        """Candidate separating axes of ``t ⊕ B``: ``±n_t``, B's facet normals, and the cross
        products ``±(e_t x e_B)`` whose direction lies in the normal cone of ``e_B`` (only
        then is it a facet normal of ``t ⊕ B``). The cone test is a float filter that only
        drops an axis when it is certainly outside the cone; extra axes are harmless."""
        a, b, c = self.T[t]
        et = np.stack([b - a, c - b, a - c])
        nt = np.cross(b - a, c - a)
        cr = np.cross(et[:, None, :], self.eB[None, :, :])  # (3, e, 3)
        u = cr.astype(np.float64)
        e = self.eB.astype(np.float64)[None]
        n1, n2 = self.n1[None], self.n2[None]
        s1 = np.einsum("kij,kij->ki", np.cross(n1, u), e)
        s2 = np.einsum("kij,kij->ki", np.cross(u, n2), e)
        s0 = np.einsum("kij,kij->ki", np.cross(n1, n2), e)
        mag = np.einsum("kij,kij->ki", np.abs(n1) + np.abs(n2), np.abs(u)) * np.abs(e).sum(axis=2)
        tol = _FILTER * 4 * mag  # each s is a sum of 6 products of 3 float factors
        sure_pos = ((s1 * np.sign(s0) > tol) | (s2 * np.sign(s0) > tol)) & (np.abs(s0) > tol)
        sure_neg = ((s1 * np.sign(s0) < -tol) | (s2 * np.sign(s0) < -tol)) & (np.abs(s0) > tol)
        # +u is outside the cone when one sign is surely negative; -u when one is surely positive
        keep_plus = ~sure_neg
        keep_minus = ~sure_pos
        U = np.concatenate([nt[None], -nt[None], self.nB, cr[keep_plus], -cr[keep_minus]])
        return U[np.any(U != 0, axis=1)]

    def inside_a(self, P4: tuple) -> bool:
        """Is ``x = p - c`` inside A, for ``c`` the vertex centroid of B (interior to B)?

        Called when ``p + eps * v - B`` misses the surface of A: then the interior of
        ``p - B`` misses it too, ``x`` is not on the surface, and ``x`` is in A exactly when
        ``q - B`` is. Decided by the winding number of A at ``x``: the proper crossings of a
        segment from ``x`` to a point outside A's bounding box, each +1 leaving a triangle's
        back and -1 entering it; a segment through an edge or vertex of A (detected exactly)
        is replaced by another one. Positive means inside: for one closed body that is the
        parity, for A made of several (:func:`cspace.minkowski.ncc_cvms._trim` of pieces) the
        union, wherever the bodies overlap or touch.
        """
        nb = len(self.Bv)
        c = [int(v) for v in self.Bv.sum(axis=0)]
        W = P4[3] * nb
        X = [P4[k] * nb - c[k] * P4[3] for k in range(3)]  # x = X / W
        lo, hi = self.T.reshape(-1, 3).min(axis=0), self.T.reshape(-1, 3).max(axis=0)
        span = int((hi - lo).max()) + 1
        rng = np.random.default_rng(0)
        xf = np.array([X[k] / W for k in range(3)])
        for _ in range(64):
            d = rng.integers(-1000, 1001, size=3)
            if not d.any():
                continue
            # far end, integer grid point: beyond the box in the direction d
            scale = 4 * span // int(np.abs(d).max()) + 4
            y = [int(round(xf[k])) + int(d[k]) * scale for k in range(3)]
            winding = self._crossings(X, W, y)
            if winding is not None:
                return winding > 0
        raise ExactnessError("no non-degenerate ray found for a point-in-solid test")  # pragma: no cover

    def _crossings(self, X: list, W: int, y: list):
        """Signed proper crossings of the segment ``X / W -> y`` with A's triangles (+1 from a
        triangle's back to its front: the winding number at ``X / W``, ``y`` being outside),
        None if the segment passes through an edge or a vertex of A."""
        Y = [c * W for c in y]
        lo = np.minimum([X[k] / W for k in range(3)], y) - 2
        hi = np.maximum([X[k] / W for k in range(3)], y) + 2
        tlo, thi = self.T.min(axis=1), self.T.max(axis=1)
        cand = np.nonzero(np.all((thi >= lo) & (tlo <= hi), axis=1))[0]
        n = 0
        for t in cand.tolist():
            a, b, c = ([int(x) * W for x in r] for r in self.T[t].tolist())
            s1, s2 = _orient3(a, b, c, X), _orient3(a, b, c, Y)
            if s1 == 0 or s2 == 0 or (s1 > 0) == (s2 > 0):
                continue  # x is on no triangle and y is outside the box: no crossing here
            e = (_orient3(X, Y, a, b), _orient3(X, Y, b, c), _orient3(X, Y, c, a))
            if 0 in e:
                if all(v >= 0 for v in e) or all(v <= 0 for v in e):
                    return None  # through an edge or a vertex
                continue
            if e[0] == e[1] == e[2]:
                n += 1 if s1 < 0 else -1
        return n

    def contains(self, P4: tuple, v: tuple) -> bool:
        W = P4[3]
        pf = np.array([P4[0] / W, P4[1] / W, P4[2] / W])
        cand = np.nonzero(np.all((self.lo - 1 <= pf) & (pf <= self.hi + 1), axis=1))[0]
        for t in cand.tolist():
            if self._in_piece(t, P4, pf, v):
                return True
        return False

    def _in_piece(self, t: int, P4: tuple, pf: np.ndarray, v: tuple) -> bool:
        # g = u.p - h(u) in floats: a few roundings of products and sums, each within an ulp
        # of the magnitude |u|.(|p| + max|T| + max|B|) (it bounds every term); the filter
        # allows 64 ulps of it, so rows within the bound go to the exact test.
        U, Uf, h, mag0, absU = self._piece(t)
        g = Uf @ pf - h
        bound = _FILTER * (absU @ np.abs(pf) + mag0)
        if np.any(g > bound):
            return False  # a separating axis, decided in floating point
        close = np.nonzero(np.abs(g) <= bound)[0]
        W = P4[3]
        To = self.T[t].astype(object)
        for k in close.tolist():
            u = tuple(int(c) for c in U[k])
            hu = max(_dot(u, r) for r in To.tolist()) + max(_dot(u, r) for r in self.Bo.tolist())
            s = _dot(u, P4[:3]) - W * hu
            if s > 0 or (s == 0 and _dot(u, v) > 0):
                return False
        return True


def _face_tris(cx: _Complex, f: int) -> list:
    """The triangles of sub-facet ``f`` (global ids, counter-clockwise about its plane's
    normal), triangulated on first use from its cycles: the triangles its arrangement would
    have made, since its vertices project back to the same canonical 2D points."""
    tris = cx.face_tris[f]
    if tris is None:
        ax = cx.plane_axis[cx.face_plane[f]]
        a, b = (ax + 1) % 3, (ax + 2) % 3
        rings, P = cx.face_rings[f], cx.points
        H = {v: _hnorm(P[v][a], P[v][b], P[v][3]) for ring in rings for v in ring}
        tris = cx.face_tris[f] = triangulate_rings(H, rings)
        cx.face_rings[f] = None
    return tris


def _face_point(cx: _Complex, f: int) -> tuple:
    """Exact homogeneous point strictly inside sub-facet ``f``: the one its arrangement gave,
    else the centroid of its first triangle (strictly inside it, and nothing of the
    arrangement meets that open triangle)."""
    if cx.face_point[f] is not None:
        return cx.face_point[f]
    a, b, c = _face_tris(cx, f)[0]
    (xa, ya, za, wa), (xb, yb, zb, wb), (xc, yc, zc, wc) = cx.points[a], cx.points[b], cx.points[c]
    bc, ac, ab = wb * wc, wa * wc, wa * wb
    s = (xa * bc + xb * ac + xc * ab, ya * bc + yb * ac + yc * ab, za * bc + zb * ac + zc * ab,
         3 * wa * bc)
    h = gcd(s[0], s[1], s[2], s[3])
    return (s[0] // h, s[1] // h, s[2] // h, s[3] // h)


def _classify(cx: _Complex, sh: _Shells, planes: _Planes, S: Superset, A: ClosedMesh,
              B: ConvexPolytope) -> tuple[np.ndarray, int, int]:
    """Membership of each shell's cell in A ⊕ B (True: inside), for the whole superset (a
    cycle): by its winding number, and exact tests where that is 0 or unknown."""
    anchor = _anchor(cx, planes, S, B)
    w = _winding(cx, sh, anchor)
    unknown = w == _UNKNOWN
    inside = (w != 0) & ~unknown
    return _tested(cx, sh, planes, A, B, inside, unknown, anchor)


def _classify_reduced(cx: _Complex, sh: _Shells, planes: _Planes, S: Superset, A: ClosedMesh,
                      B: ConvexPolytope) -> tuple[np.ndarray, int, int]:
    """Membership of each shell's cell in A ⊕ B (True: inside), for the reduced superset
    (:func:`cspace.minkowski.superset.reduced_superset`): every facet of it faces out of a
    convex piece of the sum, so a cell on the back side of a sub-facet is inside (behind a
    point inside one of its facets lie interior points of the piece, and no cell crosses the
    sum's boundary, which the reduced superset holds). The back side of sub-facet ``f`` is
    the side its net coverage (along the plane normal) faces away from; both sides where
    it is 0 (facets of both orientations cover it). The other cells are tested exactly: the
    unbounded one must be among them (checked), the rest are holes or cells that only the
    fronts of facets bound (few: 1 of 9260 shells on oblong ⊕ icosphere(320))."""
    anchor = _anchor(cx, planes, S, B)
    f = np.arange(len(cx.face_plane))
    inside = np.zeros(sh.n, dtype=bool)
    inside[sh.of[2 * f[cx.face_cov >= 0]]] = True
    inside[sh.of[2 * f[cx.face_cov <= 0] + 1]] = True
    if inside[int(sh.of[anchor])]:
        raise ExactnessError("the unbounded cell lies behind a facet of the reduced superset")
    return _tested(cx, sh, planes, A, B, inside, np.ones(sh.n, dtype=bool), anchor)


def _tested(cx: _Complex, sh: _Shells, planes: _Planes, A: ClosedMesh, B: ConvexPolytope,
            inside: np.ndarray, unknown: np.ndarray, anchor: int) -> tuple[np.ndarray, int, int]:
    """``inside`` completed by exact tests of the shells not yet inside (but the unbounded
    one): ``q - B`` meets A's surface, or (where ``unknown``: the winding number does not
    rule it out) lies inside A."""
    root = int(sh.of[anchor])
    todo = np.nonzero(~inside)[0]
    todo = todo[todo != root]
    if not len(todo):
        return inside, 0, anchor
    _, node = np.unique(sh.of, return_index=True)  # first side node of each shell
    test = _PieceTest(A, B)
    for s in todo.tolist():
        k = int(node[s])
        f, side = k // 2, 1 if k % 2 else -1
        m = planes.normal(int(cx.face_plane[f]))
        P4 = _face_point(cx, f)
        inside[s] = test.contains(P4, tuple(side * c for c in m))
        if not inside[s] and unknown[s]:
            # q - B may lie inside A without touching its surface
            inside[s] = test.inside_a(P4)
    return inside, len(todo), anchor
