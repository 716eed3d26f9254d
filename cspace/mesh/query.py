"""Exact queries on a closed triangle mesh: the non-convex C-obstacle representation.

Works on a closed, oriented triangle surface given as float64 vertices ``(n, 3)`` and int64
faces ``(m, 3)`` (scene units, world frame), e.g. the output of ``cspace.minkowski_sum``.
The surface may have several shells (inner shells of holes face into the hole) and
non-manifold edges and vertices: it must be a closed 2-cycle, every directed edge balanced by
its reverse. Queries take validated ``(k, 3)`` float64 translations.

:class:`MeshCO` provides the same three queries as the convex representation
(:class:`cspace.cobstacle.convex._ConvexCO`) (``contains``, ``signed_distance``, ``segments``), so a
:class:`~cspace.scene.model.CSpace` mixes convex and mesh C-obstacles freely.

Exactness
---------
Every decision is exact for the stored float64 vertices and float64 queries (both are dyadic
rationals; nothing is snapped):

- ``contains(q)``: ``q`` is on a triangle (exact point-in-closed-triangle test), or the
  winding number of the surface around ``q`` is non-zero. The winding number counts the signed
  crossings of the ray ``q + t e_x`` (``t > 0``). Rays through edges and vertices are resolved
  by Simulation of Simplicity: the ray's ``(y, z)`` is perturbed by ``(eps, eps**2)``, so the
  sign of a zero 2D orientation is read off the edge's direction; the perturbed ray meets no
  edge, vertex or vertical triangle, and the shared edges of adjacent triangles get one
  consistent answer, so the count is a winding number (for a closed 2-cycle it does not
  depend on the ray).
- ``segments``: the closed segment meets the closed solid iff it meets a triangle (exact
  segment-triangle test: transversal crossings, touching, segments lying in a triangle's
  plane, zero-length segments) or its start is inside.
- First contact: the exact rational parameter of the first triangle met, rounded once.

Each predicate (2D and 3D orientations on float64 differences) is evaluated in float64 with
a rigorous semi-static error bound (Shewchuk's form, ``16 eps`` times the permanent, plus
absolute terms for underflow); overflow (inf or NaN) counts as undecided; where the bound cannot certify the sign the query is
redone with Python integers (each float is an integer times a power of two). No epsilon
decides anything. The acceleration structures only prune: a ``(y, z)`` grid of triangle
bounding boxes for the ray (exact comparisons; cell indices are monotone in the coordinate),
and a bounding-volume hierarchy for segments and distances whose box test is conservative
(its parameter interval is widened by more than its rounding error).

Distances are float64: the distance to the nearest triangle (its sign from ``contains``),
error a few ulps of the coordinates.

The hot loops run compiled (:mod:`cspace.geometry._kernels.meshquery`, Cython, built at install time:
the first query in a fresh process is as fast as the hundredth). The functions of
:mod:`cspace.mesh.query_reference` with the same names and a leading underscore are their pure-Python references, operation for operation
(``tests/test_kernels.py`` checks identical outputs); nothing calls them in production.
"""

from __future__ import annotations

from fractions import Fraction

import numpy as np

from ..errors import EmptyMeshError, InvalidMeshError, NonFiniteError, OpenMeshError
from ..geometry._kernels import load
from ..geometry.exact import _FILTER, _TINY, _dyadic
from ..geometry.tritri import _cross3 as _cross, _dot3 as _dot, _sub

__all__ = ["MeshCO"]


_compiled = load("meshquery")


# Leaf size of the bounding-volume hierarchy.
_LEAF = 4


# --------------------------------------------------------------------------------------
# exact predicates (Python integers) for what the filters leave undecided


def _on_segment(X, U, V) -> bool:
    """Point X on the closed segment [U, V] (U == V allowed)."""
    e = _sub(V, U)
    if e == (0, 0, 0):
        return X == U
    w = _sub(X, U)
    return _cross(e, w) == (0, 0, 0) and 0 <= _dot(w, e) <= _dot(e, e)


def _entry_segment(P0, P1, U, V):
    """Smallest t in [0, 1] with ``P0 + t (P1 - P0)`` on the closed segment [U, V], or None."""
    d, e = _sub(P1, P0), _sub(V, U)
    if d == (0, 0, 0):
        return Fraction(0) if _on_segment(P0, U, V) else None
    if e == (0, 0, 0):
        if not _on_segment(U, P0, P1):
            return None
        return Fraction(_dot(_sub(U, P0), d), _dot(d, d))
    w = _sub(P0, U)
    c = _cross(d, e)
    if c != (0, 0, 0):
        if _dot(w, c) != 0:
            return None  # skew lines
        cc = _dot(c, c)
        tn, sn = _dot(_cross(e, w), c), _dot(_cross(d, w), c)
        if 0 <= tn <= cc and 0 <= sn <= cc:
            return Fraction(tn, cc)
        return None
    if _cross(d, w) != (0, 0, 0):
        return None  # parallel, not collinear
    dd = _dot(d, d)
    a, b = sorted((_dot(_sub(U, P0), d), _dot(_sub(V, P0), d)))
    lo, hi = max(0, a), min(dd, b)
    return Fraction(lo, dd) if lo <= hi else None


def _entry_exact(p0, p1, tri):
    """Exact first parameter in [0, 1] where the segment p0 -> p1 meets the closed triangle.

    ``p0, p1`` float64 (3,), ``tri`` float64 (9,); returns a Fraction or None (no contact).
    A zero-length segment gives 0 iff the point is on the triangle.
    """
    X, _ = _dyadic(list(p0) + list(p1) + list(tri))
    return _entry_ints(*(tuple(X[i : i + 3]) for i in range(0, 15, 3)))


def _on_one_scale(a: tuple, b: tuple) -> tuple[list, list]:
    """Two dyadic forms ``(ints, exponent)`` (:func:`cspace.geometry.exact._dyadic`) as integers on
    the smaller of their exponents."""
    (ia, ea), (ib, eb) = a, b
    lo = min(ea, eb)
    return [x << (ea - lo) for x in ia], [x << (eb - lo) for x in ib]


def _entry_ints(P0, P1, A, B, C):
    """:func:`_entry_exact` on integer points (the floats times one power of two: the
    parameter does not depend on the scale)."""
    n = _cross(_sub(B, A), _sub(C, A))
    if n == (0, 0, 0):
        # A degenerate triangle is the segment between its extreme (collinear) corners.
        U, _, V = sorted((A, B, C))
        return _entry_segment(P0, P1, U, V)
    D0, D1 = _dot(n, _sub(P0, A)), _dot(n, _sub(P1, A))
    if (D0 > 0 and D1 > 0) or (D0 < 0 and D1 < 0):
        return None
    edges = ((A, B), (B, C), (C, A))
    if D0 != 0 or D1 != 0:
        # One crossing point X = P0 + t (P1 - P0), t = D0 / den; test den * X in the triangle.
        den = D0 - D1
        sgn = 1 if den > 0 else -1
        Xd = tuple(P0[j] * den + D0 * (P1[j] - P0[j]) for j in range(3))
        for U, V in edges:
            Ud = (U[0] * den, U[1] * den, U[2] * den)
            if sgn * _dot(_cross(_sub(V, U), _sub(Xd, Ud)), n) < 0:
                return None
        return Fraction(D0, den)
    # The segment lies in the triangle's plane: clip [0, 1] by the three edge half-planes.
    lo, hi = Fraction(0), Fraction(1)
    for U, V in edges:
        e = _sub(V, U)
        g0, g1 = _dot(_cross(e, _sub(P0, U)), n), _dot(_cross(e, _sub(P1, U)), n)
        if g0 < 0 and g1 < 0:
            return None
        if g0 < 0:
            lo = max(lo, Fraction(-g0, g1 - g0))
        elif g1 < 0:
            hi = min(hi, Fraction(g0, g0 - g1))
        if lo > hi:
            return None
    return lo


def _perturbed_side(au, av, bu, bv, pu, pv) -> int:
    """Sign of orient2d(a, b, p + (eps, eps**2)) in the (u, v) = (y, z) plane (a != b)."""
    val = (bu - au) * (pv - av) - (bv - av) * (pu - au)
    if val:
        return 1 if val > 0 else -1
    # d/d eps of the value is -(bv - av); then d/d eps**2 is (bu - au).
    if bv != av:
        return 1 if bv < av else -1
    return 1 if bu > au else -1


def _crossing_exact(q, tri, s: int) -> int:
    """Signed crossing (``s`` or 0) of the perturbed ray ``q + t e_x`` with a triangle that
    does not contain ``q``; ``s`` is the exact sign of the triangle's projected (y, z) area."""
    X, _ = _dyadic(list(q) + list(tri))
    return _crossing_ints(*(tuple(X[i : i + 3]) for i in range(0, 12, 3)), s)


def _crossing_ints(Q, A, B, C, s: int) -> int:
    """:func:`_crossing_exact` on integer points (the floats times one power of two)."""
    for U, V in ((A, B), (B, C), (C, A)):
        if _perturbed_side(U[1], U[2], V[1], V[2], Q[1], Q[2]) != s:
            return 0
    n = _cross(_sub(B, A), _sub(C, A))
    D = _dot(n, _sub(A, Q))
    # D != 0: q is off the triangle and inside its (closed) projection, so off its plane.
    return s if (D > 0) == (s > 0) else 0


# --------------------------------------------------------------------------------------
# structure building


def _exact_area_signs(T: np.ndarray) -> np.ndarray:
    """(m, 3) int8 exact signs of the triangle normal's components (projected areas)."""
    m = len(T)
    A, B, C = T[:, 0:3], T[:, 3:6], T[:, 6:9]
    out = np.zeros((m, 3), dtype=np.int8)
    for k, (u, v) in enumerate(((1, 2), (2, 0), (0, 1))):
        bu, cv, bv, cu = B[:, u] - A[:, u], C[:, v] - A[:, v], B[:, v] - A[:, v], C[:, u] - A[:, u]
        l, r = bu * cv, bv * cu
        val = l - r
        err = _FILTER * (np.abs(l) + np.abs(r)) + _TINY
        out[:, k] = np.where(val > err, 1, np.where(val < -err, -1, 0))
        # A float difference is 0 exactly when its operands are equal: both products are then
        # exactly 0 (axis-parallel triangles), no exact re-evaluation needed.
        zero = ((bu == 0) | (cv == 0)) & ((bv == 0) | (cu == 0))
        for t in np.nonzero(~(np.abs(val) > err) & ~zero)[0].tolist():
            X, _ = _dyadic(T[t].tolist())
            a, b, c = X[0:3], X[3:6], X[6:9]
            x = (b[u] - a[u]) * (c[v] - a[v]) - (b[v] - a[v]) * (c[u] - a[u])
            out[t, k] = (x > 0) - (x < 0)
    return out


def _build_bvh(lo: np.ndarray, hi: np.ndarray):
    """Median-split BVH over triangle boxes (:class:`cspace.geometry.boxes.BoxTree`, built
    compiled), as the kernels walk it: ``(order, node_lo, node_hi, left, right, start,
    count)``, leaves (``left == -1``) holding the runs ``order[start:start + count]``."""
    from ..geometry.boxes import BoxTree

    t = BoxTree(lo, hi, leaf=_LEAF)
    inner = t.count == 0
    left = np.where(inner, t.first, -1)
    right = np.where(inner, t.first + 1, -1)
    return t.order, t.lo, t.hi, left, right, np.where(inner, 0, t.first), t.count


def _closed_mesh_arrays(vertices, faces, name: str):
    V = np.ascontiguousarray(vertices, dtype=np.float64)
    F = np.asarray(faces)
    if V.ndim != 2 or V.shape[1] != 3:
        raise InvalidMeshError(f"{name}: vertices must be (n, 3), got shape {V.shape}")
    if F.ndim != 2 or F.shape[1] != 3 or (F.size and F.dtype.kind not in "iu"):
        raise InvalidMeshError(f"{name}: faces must be (m, 3) integers, got {F.dtype} {F.shape}")
    F = np.ascontiguousarray(F, dtype=np.int64)
    if len(F) == 0:
        raise EmptyMeshError(f"{name}: no faces")
    if F.min() < 0 or F.max() >= len(V):
        row = int(np.nonzero(((F < 0) | (F >= len(V))).any(axis=1))[0][0])
        raise InvalidMeshError(f"{name}: face {row} indexes a missing vertex: {F[row].tolist()}")
    used = np.zeros(len(V), dtype=bool)
    used[F.ravel()] = True
    bad = used & ~np.isfinite(V).all(axis=1)
    if bad.any():
        row = int(np.nonzero(bad)[0][0])
        raise NonFiniteError(f"{name}: vertex {row} is not finite: {V[row].tolist()}")
    edge = unbalanced_edge(F, len(V))
    if edge is not None:
        raise OpenMeshError(
            f"{name}: not a closed 2-cycle: edge {edge[0]} -> {edge[1]} is not balanced "
            "by its reverse"
        )
    return V, F


def unbalanced_edge(faces: np.ndarray, n: int) -> tuple[int, int] | None:
    """A directed edge ``(u, v)`` of the triangles ``faces`` (indices below ``n``) used more
    often than its reverse ``(v, u)``, or None when there is none: the triangles are then a
    closed 2-cycle (a closed oriented surface, self-intersecting or not), whose winding number
    is defined everywhere off it. Exact integer counts."""
    F = np.asarray(faces, dtype=np.int64).reshape(-1, 3)
    u = F.ravel()
    v = np.roll(F, -1, axis=1).ravel()
    n = np.int64(n)
    key = np.concatenate([u * n + v, v * n + u])
    sign = np.concatenate([np.ones(len(u), np.int64), -np.ones(len(u), np.int64)])
    keys, inv = np.unique(key, return_inverse=True)
    bal = np.bincount(inv.ravel(), weights=sign, minlength=len(keys)).astype(np.int64)
    if (bal != 0).any():
        k = int(keys[np.nonzero(bal > 0)[0][0]])
        return k // int(n), k % int(n)
    return None


# --------------------------------------------------------------------------------------
# the representation


class MeshCO:
    """Exact queries on a closed triangle surface (a non-convex C-obstacle).

    Parameters
    ----------
    vertices : (n, 3) float64
    faces : (m, 3) int64
        A closed 2-cycle (every directed edge balanced by its reverse), counter-clockwise seen
        from outside; several shells and non-manifold edges and vertices are allowed.
    name : str
        Used in error messages.

    Notes
    -----
    Interface (as the convex representation), on validated ``(k, 3)`` float64 arrays:
    ``contains(q) -> (k,) bool`` (closed set: the surface is inside), ``signed_distance(q)``,
    ``segments(q0, q1, want_t) -> (hit (k,) bool, t (k,) float64)``. Membership is "winding
    number non-zero or on the surface", so it is exact for any closed 2-cycle whose winding
    number is 0 or 1 (a solid with holes).

    Raises
    ------
    InvalidMeshError, EmptyMeshError, NonFiniteError, OpenMeshError
        Bad arrays, an empty mesh, a non-finite vertex, an unbalanced edge (named).
    """

    def __init__(self, vertices, faces, *, name: str = "mesh"):
        V, F = _closed_mesh_arrays(vertices, faces, name)
        self.vertices, self.faces, self.name = V, F, name
        T0 = V[F].reshape(-1, 9)
        lo0 = np.minimum(np.minimum(T0[:, 0:3], T0[:, 3:6]), T0[:, 6:9])
        hi0 = np.maximum(np.maximum(T0[:, 0:3], T0[:, 3:6]), T0[:, 6:9])
        order, self.nlo, self.nhi, self.left, self.right, self.start, self.count = _build_bvh(
            lo0, hi0
        )
        # Triangles in BVH leaf order (locality); self.order maps back to face indices.
        self.order = order
        self.T = np.ascontiguousarray(T0[order])
        self.lo = np.ascontiguousarray(lo0[order])
        self.hi = np.ascontiguousarray(hi0[order])
        area = _exact_area_signs(self.T)
        self.sx = np.ascontiguousarray(area[:, 0])
        self.degen = np.ascontiguousarray((area == 0).all(axis=1))
        self._exact_tris: dict = {}  # triangle -> its dyadic integers, for the exact path
        # (y, z) grid for the +x rays: about two cells per triangle, square-ish cells, fewer
        # if large triangles would make the cell lists long (at most 32 entries per triangle).
        m = len(F)
        ylo, yhi = self.lo[:, 1].min(), self.hi[:, 1].max()
        zlo, zhi = self.lo[:, 2].min(), self.hi[:, 2].max()
        Ly, Lz = max(yhi - ylo, 1e-300), max(zhi - zlo, 1e-300)
        cells = 2.0 * m
        while True:  # ny <= cells, so the count shrinks to one cell (a mesh flat in z too)
            ny = int(np.clip(np.sqrt(cells * Ly / Lz), 1, min(4096.0, max(cells, 1.0))))
            nz = int(np.clip(cells / ny, 1, 4096))
            self._grid = (float(ylo), float(zlo), float(ny / Ly), float(nz / Lz), ny, nz)
            if ny * nz == 1 or _compiled.cell_entries(self.lo, self.hi, *self._grid) <= 32 * m:
                break
            cells = ny * nz / 4.0
        self.cstart, self.ctris = _compiled.build_cells(self.lo, self.hi, *self._grid)

    # ---- membership ---------------------------------------------------------------------

    def contains(self, q: np.ndarray) -> np.ndarray:
        """(k,) bool: ``q`` on the surface or inside (winding number non-zero), exact."""
        q = np.ascontiguousarray(q, dtype=np.float64)
        out = np.zeros(len(q), dtype=np.bool_)
        unsure = np.zeros(len(q), dtype=np.bool_)
        if _compiled.contains_kernel(q, self.T, self.lo, self.hi, self.sx,
                                     self.degen.view(np.uint8), self.cstart, self.ctris,
                                     *self._grid, out.view(np.uint8), unsure.view(np.uint8)):
            for i in np.nonzero(unsure)[0].tolist():
                out[i] = self._contains_exact(q[i])
        return out

    def _contains_exact(self, q: np.ndarray) -> bool:
        cand = _compiled.cell_candidates(q, self.lo, self.hi, self.cstart, self.ctris,
                                         *self._grid)
        qd = _dyadic(q.tolist())
        w = 0
        for t in cand.tolist():
            # triangles' integer forms are kept: near-surface queries revisit them
            td = self._exact_tris.get(t)
            if td is None:
                td = self._exact_tris[t] = _dyadic(self.T[t].tolist())
            Q, X = _on_one_scale(qd, td)
            Q, A, B, C = tuple(Q), tuple(X[0:3]), tuple(X[3:6]), tuple(X[6:9])
            if _entry_ints(Q, Q, A, B, C) is not None:
                return True  # on the surface
            s = int(self.sx[t])
            if s:
                w += _crossing_ints(Q, A, B, C, s)
        return w != 0

    # ---- distances ----------------------------------------------------------------------

    def distance(self, q: np.ndarray) -> np.ndarray:
        """(k,) float64 Euclidean distance to the nearest triangle (unsigned)."""
        q = np.ascontiguousarray(q, dtype=np.float64)
        out = np.zeros(len(q))
        _compiled.nearest_kernel(q, self.T, self.nlo, self.nhi, self.left, self.right,
                                 self.start, self.count, out)
        return out

    def signed_distance(self, q: np.ndarray) -> np.ndarray:
        """Distance to the surface, negative inside (sign exact; ``-0.0`` on the surface)."""
        d = self.distance(q)
        return np.where(self.contains(q), -d, d)

    def depth(self, q: np.ndarray) -> np.ndarray:
        """Penetration depth of inside points: the distance to the surface (float)."""
        return self.distance(q)

    distance_outside = distance

    # ---- segments -----------------------------------------------------------------------

    def segments(self, q0: np.ndarray, q1: np.ndarray, want_t: bool):
        """Exact hit test of the closed segments; entry parameters where asked.

        Returns ``(hit (k,) bool, t (k,) float64)``; ``t`` is NaN where not hit or not asked.
        """
        q0 = np.ascontiguousarray(q0, dtype=np.float64)
        q1 = np.ascontiguousarray(q1, dtype=np.float64)
        k = len(q0)
        tout = np.full(k, np.nan)
        status, ps, pt, plo, phi = _compiled.segment_kernel(
            q0, q1, self.T, self.degen.view(np.uint8), self.nlo, self.nhi, self.left,
            self.right, self.start, self.count, not want_t,
        )
        if not want_t:
            hit = status == 1
            unsure = status == 2
            if unsure.any():
                sel = unsure[ps] & (plo < 0.0)
                for i, t in zip(ps[sel].tolist(), pt[sel].tolist()):
                    if not hit[i] and _entry_exact(q0[i].tolist(), q1[i].tolist(),
                                                   self.T[t].tolist()) is not None:
                        hit[i] = True
            rest = np.nonzero(~hit)[0]
            if rest.size:  # no surface contact: the whole segment is inside iff q0 is
                hit[rest] = self.contains(q0[rest])
            return hit, tout
        inside0 = self.contains(q0)
        tout[inside0] = 0.0
        hit = inside0.copy()
        # Group the pairs by segment; only pairs that can beat the best certain hit matter.
        keep = ~inside0[ps]
        ps, pt, plo, phi = ps[keep], pt[keep], plo[keep], phi[keep]
        if len(ps):
            cert = plo >= 0.0
            best = np.full(k, np.inf)
            np.minimum.at(best, ps[cert], phi[cert])
            sel = plo <= best[ps]
            entry: dict[int, Fraction] = {}
            for i, t in zip(ps[sel].tolist(), pt[sel].tolist()):
                e = _entry_exact(q0[i].tolist(), q1[i].tolist(), self.T[t].tolist())
                if e is not None and (i not in entry or e < entry[i]):
                    entry[i] = e
            for i, e in entry.items():
                hit[i] = True
                tout[i] = float(e)
        return hit, tout
