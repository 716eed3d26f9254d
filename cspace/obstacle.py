"""Translational C-space obstacles ``CO = O ⊕ (-R)``: build once, query many.

Queries take translations of the robot's reference point as ``(k, 3)`` float64 arrays
(``(3,)`` also accepted), in scene units, world frame.

A :class:`CSpaceObstacle` holds one C-obstacle in one of two representations behind the same
four queries. The *convex path* (``kind='convex'``, this module): obstacle and robot convex,
CO their exact Minkowski sum (:func:`cspace.convex_minkowski_sum`) stored as its exact facet
planes ``n . k <= d`` (``n`` primitive int64, ``d`` a Python int, ``k`` in grid units,
``x = step * k`` in scene units). The *mesh path* (``kind='mesh'``, :mod:`cspace.meshquery`):
a non-convex closed obstacle's C-obstacle ``cspace.minkowski_sum(O, R.reflected(c))``, or any
closed triangle surface (:meth:`CSpaceObstacle.from_mesh`), queried exactly on its float64
coordinates.

Exactness
---------
The queries are exact for the *stored* C-obstacle and arbitrary float64 translations (no
snapping of the queries): a float64 ``q`` is a dyadic rational, so ``n . q - d * step`` has
an exact sign. It is evaluated by a float filter (one matrix product with a rigorous error
bound, semi-static: ``16 eps`` times the same sum on absolute values) and, where the filter
cannot decide, with Python integers (every float is an integer times a power of two). No
tolerance decides anything. The stored C-obstacle is the exact one of the *snapped* inputs
grown by the least box that covers how far snapping moved them (and the float64 rounding of a
stored surface): :mod:`cspace.margin`. It therefore holds the true ``O ⊕ (c - R)`` of the float
input, so a collision is never reported free, and a reported collision is within
``error_bound`` of a true one (``conservative=False``: no growth, two-sided error).
"""

from __future__ import annotations

import os
from fractions import Fraction

import numpy as np

from .convex import ConvexPolytope, convex_minkowski_sum
from .errors import (
    InvalidArgumentError,
    InvalidMeshError,
    InvalidQueryError,
    NonFiniteError,
    NotConvexError,
)
from .exact import _EPS, _FILTER, _TINY, Grid, _dyadic
from .margin import Margin

__all__ = ["CSpaceObstacle", "CSpace", "grown_mesh_sum"]

# _FILTER (16 eps, from the kernel) also covers the 4-term products here (3 coordinates and
# the offset, from rounded inputs): they need about 6 eps times the permanent.
# Rows x facets evaluated at once (memory and cache).
_CHUNK = 1 << 17


# --------------------------------------------------------------------------------------
# input checks


def _translations(q, what: str = "q") -> tuple[np.ndarray, bool]:
    """``(k, 3)`` float64 translations and whether a single ``(3,)`` row was given."""
    try:
        a = np.asarray(q, dtype=np.float64)
    except (TypeError, ValueError):
        raise InvalidQueryError(f"{what} must be (3,) or (k, 3) numbers, got "
                                f"{type(q).__name__}") from None
    single = a.ndim == 1
    if single:
        a = a[None, :]
    if a.ndim != 2 or a.shape[1] != 3:
        raise InvalidQueryError(f"{what} must be (3,) or (k, 3), got shape {np.shape(q)}")
    finite = np.isfinite(a)
    if not finite.all():
        row = int(np.nonzero(~finite.all(axis=1))[0][0])
        raise NonFiniteError(f"{what}: row {row} is not finite: {a[row].tolist()}")
    return a, single


# --------------------------------------------------------------------------------------
# exact plane tests shared by the convex engines (one polytope here; pieces elsewhere)


def exact_plane_sign(n, d: int, exponent: int, q) -> int:
    """Exact sign of ``n . q - d * 2**exponent`` for integer ``n`` (3 ints), integer ``d`` and
    one float64 row ``q``: the side of ``q`` against the plane ``n . k = d`` (``k = q / step``)."""
    X, lo = _dyadic(list(q))
    s = min(lo, exponent)
    lhs = (n[0] * X[0] + n[1] * X[1] + n[2] * X[2]) << (lo - s)
    rhs = d << (exponent - s)
    return (lhs > rhs) - (lhs < rhs)


def exact_segment_entry(planes, exponent: int, a, b):
    """Entry parameter (Fraction) of the closed segment ``a -> b`` into the polytope
    ``n . k <= d`` over ``planes`` (``(n, d)`` integer pairs, ``k = x / step``), or None."""
    X, lo = _dyadic(list(a) + list(b))
    s = min(lo, exponent)
    X0, X1 = X[:3], X[3:]
    lo_t, hi_t = Fraction(0), Fraction(1)
    for n, d in planes:
        D = d << (exponent - s)
        w0 = ((n[0] * X0[0] + n[1] * X0[1] + n[2] * X0[2]) << (lo - s)) - D
        w1 = ((n[0] * X1[0] + n[1] * X1[1] + n[2] * X1[2]) << (lo - s)) - D
        if w0 > 0 and w1 > 0:
            return None
        if w0 > 0:  # entering: (1 - t) w0 + t w1 <= 0 iff t >= w0 / (w0 - w1)
            lo_t = max(lo_t, Fraction(w0, w0 - w1))
        elif w1 > 0:  # leaving: t <= w0 / (w0 - w1) = -w0 / (w1 - w0)
            hi_t = min(hi_t, Fraction(-w0, w1 - w0))
        if lo_t > hi_t:
            return None
    return lo_t


def segment_filter(v0, v1, e0, e1):
    """Float filter of closed segments against convex polytopes, one row per (segment,
    polytope): plane values at both ends ``v0, v1`` with rigorous bounds ``e0, e1`` (k, f).

    Returns ``(free, sure_hit, t, terr, enter)``: rows certainly free, rows certainly hitting,
    and per plane the crossing parameter ``t`` with its bound ``terr`` and whether the
    segment enters through it. Rows in neither set need the exact test.
    """
    fin0, fin1 = np.isfinite(v0) & np.isfinite(e0), np.isfinite(v1) & np.isfinite(e1)
    pos0, neg0 = (v0 > e0) & fin0, (v0 < -e0) & fin0
    pos1, neg1 = (v1 > e1) & fin1, (v1 < -e1) & fin1
    # Both ends beyond one plane: free (the common case).
    free = (pos0 & pos1).any(axis=1)
    unknown = (~(pos0 | neg0) | ~(pos1 | neg1)).any(axis=1)
    # Plane j holds on [0, t_j] (leaving) or [t_j, 1] (entering), t_j = |v0| / (|v0| + |v1|)
    # with both signs certain; terr bounds |t_j - exact| (rounding of v0, v1 and of t_j).
    A0, A1 = np.abs(v0), np.abs(v1)
    ssum = A0 + A1
    t = A0 / ssum
    terr = 2.0 * (e0 * A1 + e1 * A0) / (ssum * (ssum - e0 - e1)) + 8 * _EPS * t
    enter = pos0 & neg1
    leave = neg0 & pos1
    lo_dn = np.maximum(0.0, np.where(enter, t - terr, -np.inf).max(axis=1))
    lo_up = np.maximum(0.0, np.where(enter, t + terr, -np.inf).max(axis=1))
    hi_dn = np.minimum(1.0, np.where(leave, t - terr, np.inf).min(axis=1))
    hi_up = np.minimum(1.0, np.where(leave, t + terr, np.inf).min(axis=1))
    free |= lo_dn > hi_up
    sure_hit = ~free & ~unknown & (lo_up <= hi_dn)
    return free, sure_hit, t, terr, enter


# --------------------------------------------------------------------------------------
# one convex C-obstacle


class _ConvexCO:
    """Exact queries on one convex polytope given by its facet planes (internal).

    The interface a C-obstacle representation provides to :class:`CSpaceObstacle`, on
    validated ``(k, 3)`` float64 arrays: ``contains(q) -> (k,) bool``,
    ``signed_distance(q) -> (k,) float64``, ``segments(q0, q1, want_t) -> (hit, t)``. The
    non-convex representations (:class:`cspace.meshquery.MeshCO` for a closed surface, the
    union of convex pieces in :mod:`cspace.surface`) implement the same three.
    """

    def __init__(self, poly: ConvexPolytope):
        self.poly = poly
        self.exponent = poly.grid.exponent
        N = poly.normals.astype(np.int64)
        first = poly.ints[poly.facet_indices[poly.facet_offsets[:-1]]]
        self.n_int = [tuple(int(c) for c in n) for n in N.tolist()]
        # Planes in the scene frame (the grid's origin added, exactly, as Python ints): a query
        # is then only scaled, never shifted, and the filter's bound covers d's rounding.
        o = poly.grid.origin
        self.d_int = [sum(a * (b + c) for a, b, c in zip(n, p, o))
                      for n, p in zip(self.n_int, first.tolist())]
        Nf = N.astype(np.float64)
        df = np.array([float(d) for d in self.d_int])
        # value = [qs, 1] @ A = n . qs - d   (qs = q / step, exact scaling)
        self.A = np.ascontiguousarray(np.vstack([Nf.T, -df[None, :]]))
        self.absA = np.abs(self.A)
        self.l1max = float(np.abs(Nf).sum(axis=1).max())
        self.dmax = float(np.abs(df).max())
        # Float geometry for distances, centred on the polytope (smaller magnitudes).
        V = poly.vertices
        self.centre = (V.min(axis=0) + V.max(axis=0)) / 2.0
        Vc = V - self.centre
        self.V = Vc
        nh = Nf / np.linalg.norm(Nf, axis=1, keepdims=True)
        self.nh = nh
        o, idx = poly.facet_offsets, poly.facet_indices
        fv = Vc[idx]
        self.dh = np.einsum("ij,ij->i", nh, Vc[idx[o[:-1]]])
        # Half-edges u -> v of each facet (CSR order), inward edge normals m = n x (v - u).
        facet_of = np.repeat(np.arange(len(N)), np.diff(o))
        pos = np.arange(len(idx))
        nxt = np.where(pos + 1 == o[facet_of + 1], o[facet_of], pos + 1)
        M = np.cross(nh[facet_of], Vc[idx[nxt]] - fv)
        self.M = M
        self.mc = np.einsum("ij,ij->i", M, fv)
        self.he_starts = o[:-1].copy()
        E = poly.edges
        self.ea = Vc[E[:, 0]]
        self.ev = Vc[E[:, 1]] - Vc[E[:, 0]]
        self.ell = np.einsum("ij,ij->i", self.ev, self.ev)
        self.radius = float(np.linalg.norm(Vc, axis=1).max())

    # ---- exact plane signs --------------------------------------------------------------

    def _scaled(self, q: np.ndarray) -> np.ndarray:
        """Rows ``[q / step, 1]`` (exact scaling by a power of two, barring under/overflow)."""
        Q = np.ones((len(q), 4))
        with np.errstate(over="ignore", under="ignore"):
            np.ldexp(q, -self.exponent, out=Q[:, :3])
        return Q

    def _values(self, Q: np.ndarray):
        """``n . qs - d`` per (row, facet) and a rigorous bound on its rounding error."""
        with np.errstate(over="ignore", invalid="ignore"):
            val = Q @ self.A
            err = _FILTER * (np.abs(Q) @ self.absA) + _TINY
        return val, err

    def _exact_sign(self, q: np.ndarray, j: int) -> int:
        """Exact sign of ``n_j . q - d_j * step`` for one float64 row ``q``."""
        return exact_plane_sign(self.n_int[j], self.d_int[j], self.exponent, q.tolist())

    def plane_signs(self, q: np.ndarray) -> np.ndarray:
        """Exact ``(k, f)`` int8 signs of ``n . q - d * step`` (positive: outside that plane)."""
        Q = self._scaled(q)
        val, err = self._values(Q)
        finite = np.isfinite(val) & np.isfinite(err)
        pos, neg = (val > err) & finite, (val < -err) & finite
        sign = pos.astype(np.int8) - neg.astype(np.int8)
        i, j = np.nonzero(~(pos | neg))
        for a, b in zip(i.tolist(), j.tolist()):
            sign[a, b] = self._exact_sign(q[a], b)
        return sign

    # ---- queries ------------------------------------------------------------------------

    def contains(self, q: np.ndarray) -> np.ndarray:
        out = np.zeros(len(q), dtype=bool)
        f = self.A.shape[1]
        step = max(1, _CHUNK // f)
        for lo in range(0, len(q), step):
            qc = q[lo : lo + step]
            Q = self._scaled(qc)
            with np.errstate(over="ignore", invalid="ignore"):
                mx = (Q @ self.A).max(axis=1)
                # Uniform per-row bound: >= the per-entry bound of every facet.
                B = _FILTER * (np.abs(Q[:, :3]).max(axis=1) * self.l1max + self.dmax) + _TINY
            inside = mx < -B
            # Non-finite values (overflow of huge queries) go to the exact path.
            unsure = ~(inside | (mx > B)) | ~np.isfinite(mx) | ~np.isfinite(B)
            if unsure.any():
                rows = np.nonzero(unsure)[0]
                inside[rows] = self._contains_slow(qc[rows])
            out[lo : lo + step] = inside
        return out

    def _contains_slow(self, q: np.ndarray) -> np.ndarray:
        Q = self._scaled(q)
        val, err = self._values(Q)
        finite = np.isfinite(val) & np.isfinite(err)
        pos, neg = (val > err) & finite, (val < -err) & finite
        out_sure = pos.any(axis=1)
        in_sure = neg.all(axis=1)
        res = in_sure.copy()
        for r in np.nonzero(~(out_sure | in_sure))[0].tolist():
            cols = np.nonzero(~neg[r])[0].tolist()
            res[r] = all(self._exact_sign(q[r], j) <= 0 for j in cols)
        return res

    def signed_distance(self, q: np.ndarray) -> np.ndarray:
        inside = self.contains(q)
        out = np.zeros(len(q))
        if inside.any():
            out[inside] = -np.maximum(self.depth(q[inside]), 0.0)
        if (~inside).any():
            out[~inside] = self.distance_outside(q[~inside])
        return out

    def depth(self, q: np.ndarray) -> np.ndarray:
        """``min_j (d_j - n_j . q) / |n_j|`` in float (>= 0 inside)."""
        p = q - self.centre
        return (self.dh[None, :] - p @ self.nh.T).min(axis=1)

    def distance_outside(self, q: np.ndarray) -> np.ndarray:
        """Euclidean distance from each (outside) point to the polytope, float."""
        out = np.zeros(len(q))
        f, H, E = len(self.nh), len(self.M), len(self.ea)
        step = max(1, _CHUNK // (f + H + 3 * E))
        for lo in range(0, len(q), step):
            p = q[lo : lo + step] - self.centre
            plane = p @ self.nh.T - self.dh[None, :]  # (k, f) signed plane distances
            side = p @ self.M.T - self.mc[None, :]  # (k, H) >= 0: inside the facet's edge
            in_facet = np.minimum.reduceat(side, self.he_starts, axis=1) >= 0
            # A facet whose polygon holds the projection of p gives the distance |plane| when
            # p is on its outer side; rounding can put p a few ulps behind the plane, then p is
            # within that rounding of the facet (distance ~0), so a slack of the error bound.
            slack = 64.0 * _EPS * (self.radius + np.abs(p).sum(axis=1))
            ok = in_facet & (plane >= -slack[:, None])
            best = np.where(ok, np.maximum(plane, 0.0), np.inf).min(axis=1)
            # Edges (and so vertices): distance to each closed segment.
            w = p[:, None, :] - self.ea[None, :, :]  # (k, E, 3)
            t = np.clip(np.einsum("kej,ej->ke", w, self.ev) / self.ell[None, :], 0.0, 1.0)
            r = w - t[:, :, None] * self.ev[None, :, :]
            edge = np.sqrt(np.einsum("kej,kej->ke", r, r)).min(axis=1)
            out[lo : lo + step] = np.minimum(best, edge)
        return out

    def segments(self, q0: np.ndarray, q1: np.ndarray, want_t: bool):
        """Exact hit test for the closed segments; entry parameters where asked.

        Returns ``(hit (k,) bool, t (k,) float)``; ``t`` is NaN where not hit or not asked.
        """
        n_rows = len(q0)
        hit = np.zeros(n_rows, dtype=bool)
        tout = np.full(n_rows, np.nan)
        step = max(1, _CHUNK // (4 * self.A.shape[1]))
        with np.errstate(divide="ignore", invalid="ignore", over="ignore"):
            for lo in range(0, n_rows, step):
                a, b = q0[lo : lo + step], q1[lo : lo + step]
                h, tt = self._segments_chunk(a, b, want_t)
                hit[lo : lo + step] = h
                tout[lo : lo + step] = tt
        return hit, tout

    def _segments_chunk(self, a: np.ndarray, b: np.ndarray, want_t: bool):
        m = len(a)
        val, err = self._values(self._scaled(np.vstack([a, b])))
        tt = np.full(m, np.nan)
        free, sure_hit, t, terr, enter = segment_filter(val[:m], val[m:], err[:m], err[m:])
        if free.all():
            return np.zeros(m, dtype=bool), tt
        h = sure_hit.copy()
        todo = np.nonzero(~free & ~sure_hit)[0].tolist()
        if want_t and sure_hit.any():
            # The entry is the largest entering parameter. Where the filter's intervals
            # single out one entering facet, only its ratio is evaluated exactly; ties
            # (entry through an edge or a vertex) take the full exact path.
            rows = np.nonzero(sure_hit)[0]
            te = np.where(enter[rows], t[rows], -np.inf)
            j = te.argmax(axis=1)
            ar = np.arange(len(rows))
            inside0 = ~enter[rows].any(axis=1)  # no facet entered: q0 is strictly inside
            tt[rows[inside0]] = 0.0
            up = np.where(enter[rows], t[rows] + terr[rows], -np.inf)
            up[ar, j] = -np.inf
            unique = ~inside0 & ((t[rows, j] - terr[rows, j]) > up.max(axis=1))
            for r, jj in zip(rows[unique].tolist(), j[unique].tolist()):
                tt[r] = float(self._exact_entry(a[r], b[r], jj))
            todo = sorted(set(todo) | set(rows[~inside0 & ~unique].tolist()))
        for r in todo:
            entry = self._exact_segment(a[r], b[r])
            h[r] = entry is not None
            if entry is not None and want_t:
                tt[r] = float(entry)
        return h, tt

    def _exact_entry(self, a: np.ndarray, b: np.ndarray, j: int) -> Fraction:
        """Exact parameter where the segment a -> b crosses facet plane ``j``."""
        X, lo = _dyadic(a.tolist() + b.tolist())
        e = self.exponent
        s = min(lo, e)
        n, D = self.n_int[j], self.d_int[j] << (e - s)
        w0 = ((n[0] * X[0] + n[1] * X[1] + n[2] * X[2]) << (lo - s)) - D
        w1 = ((n[0] * X[3] + n[1] * X[4] + n[2] * X[5]) << (lo - s)) - D
        return Fraction(w0, w0 - w1)

    def _exact_segment(self, a: np.ndarray, b: np.ndarray):
        """Entry parameter (Fraction) of the closed segment a -> b into the polytope, or None."""
        return exact_segment_entry(zip(self.n_int, self.d_int), self.exponent, a.tolist(),
                                   b.tolist())


# --------------------------------------------------------------------------------------
# public classes


def _is_mesh(obj) -> bool:
    """A mesh-like operand: an object with faces, a (vertices, faces) pair, or a path."""
    if hasattr(obj, "faces"):
        return True
    if isinstance(obj, (str, os.PathLike)):
        return True
    return (
        isinstance(obj, tuple) and len(obj) == 2
        and np.ndim(obj[0]) == 2 and np.ndim(obj[1]) == 2
    )


def _as_convex(obj, grid: Grid, name: str) -> ConvexPolytope:
    """ConvexPolytope on ``grid`` from a polytope, an (n, 3) point array or a closed convex mesh."""
    if isinstance(obj, ConvexPolytope):
        return obj.on_grid(grid)
    if _is_mesh(obj):
        return ConvexPolytope.from_mesh(obj, grid=grid, name=name)
    return ConvexPolytope.from_points(np.asarray(obj, dtype=np.float64), grid=grid, name=name)


def _vertices_of(obj) -> np.ndarray:
    """(n, 3) float64 coordinates of an operand, to size the grid."""
    if isinstance(obj, ConvexPolytope) or hasattr(obj, "vertices"):
        return np.asarray(obj.vertices, dtype=np.float64)
    if isinstance(obj, (str, os.PathLike)):  # the file's own floats, not snapped ones
        from .meshfile import read_mesh_file

        return np.asarray(read_mesh_file(obj).vertices, dtype=np.float64)
    if _is_mesh(obj):
        return np.asarray(obj[0], dtype=np.float64)
    a = np.asarray(obj, dtype=np.float64)
    if a.ndim != 2 or a.shape[1] != 3:
        raise InvalidMeshError(
            f"expected a ConvexPolytope, (n, 3) points or a closed convex mesh, got shape {a.shape}"
        )
    return a


def _mesh_arrays(obj) -> tuple[np.ndarray, np.ndarray]:
    """``(vertices float64, faces int64)`` of a mesh-like operand, as given (not validated)."""
    if isinstance(obj, (str, os.PathLike)):
        from .meshfile import read_mesh_file

        f = read_mesh_file(obj)
        return np.asarray(f.vertices, dtype=np.float64), np.asarray(f.faces, dtype=np.int64)
    if hasattr(obj, "vertices") and hasattr(obj, "faces"):
        return np.asarray(obj.vertices, dtype=np.float64), np.asarray(obj.faces, dtype=np.int64)
    return np.asarray(obj[0], dtype=np.float64), np.asarray(obj[1], dtype=np.int64)


def _closed_2cycle(V: np.ndarray, F: np.ndarray):
    """The triangles with vertices welded by exact float position, ``(U, G)``, when they form
    a closed 2-cycle (every directed edge balanced by its reverse: the mesh queries' own
    check), else None."""
    from .errors import InvalidMeshError
    from .meshquery import _closed_mesh_arrays

    V = np.asarray(V, dtype=np.float64).reshape(-1, 3)
    if F.min() < 0 or F.max() >= len(V):
        return None
    U, inv = np.unique(V, axis=0, return_inverse=True)
    G = inv.reshape(-1)[F]
    try:
        _closed_mesh_arrays(U, G, "obstacle")
    except InvalidMeshError:
        return None
    return U, G


def _hull_excess(*operands) -> float:
    """How far the hulls among ``operands`` may exceed the bodies they stand for (the sum of
    their :attr:`ConvexPolytope.excess`; 0 for anything else)."""
    return float(sum(getattr(op, "excess", 0.0) or 0.0 for op in operands))


def _wider_somewhere(R: np.ndarray, O: np.ndarray) -> bool:
    """Is the robot wider than the obstacle's box on some axis (exact, on the floats)? Then
    it can never lie inside the obstacle (no containment term is needed)."""
    for k in range(3):
        if (Fraction(float(R[:, k].max())) - Fraction(float(R[:, k].min()))
                > Fraction(float(O[:, k].max())) - Fraction(float(O[:, k].min()))):
            return True
    return False


class _Mesh:
    """Vertices and faces of several operands joined (for FCL checks and drawing)."""

    def __init__(self, vertices: np.ndarray, faces: np.ndarray, name: str = "mesh"):
        self.vertices, self.faces, self.name = vertices, faces, name

    @classmethod
    def join(cls, meshes) -> "_Mesh":
        V, F, n = [], [], 0
        for m in meshes:
            V.append(np.asarray(m.vertices, dtype=np.float64))
            F.append(np.asarray(m.faces, dtype=np.int64) + n)
            n += len(V[-1])
        return cls(np.vstack(V), np.vstack(F), "+".join(getattr(m, "name", "mesh") for m in meshes))


class _UnionOf:
    """The engine interface over several C-obstacles' engines: their union, not built
    (:class:`CSpace` and ``kind='union'`` C-obstacles). Each query stops asking engines for
    rows already decided; vertices and faces are joined on first use (drawing only)."""

    def __init__(self, cos):
        self.cos = tuple(cos)
        self.engines = [co._impl for co in self.cos]
        self._joined = None

    @property
    def vertices(self) -> np.ndarray:
        if self._joined is None:
            self._joined = _Mesh.join(self.cos)
        return self._joined.vertices

    @property
    def faces(self) -> np.ndarray:
        if self._joined is None:
            self._joined = _Mesh.join(self.cos)
        return self._joined.faces

    def contains(self, q: np.ndarray) -> np.ndarray:
        out = np.zeros(len(q), dtype=bool)
        for e in self.engines:
            rest = np.nonzero(~out)[0]
            if not rest.size:
                break
            out[rest] = e.contains(q[rest])
        return out

    def segments(self, q0: np.ndarray, q1: np.ndarray, want_t: bool):
        hit, t = np.zeros(len(q0), dtype=bool), np.full(len(q0), np.nan)
        for e in self.engines:
            if want_t:  # the earliest contact over all
                h, te = e.segments(q0, q1, True)
                hit |= h
                t = np.fmin(t, te)
                continue
            rest = np.nonzero(~hit)[0]
            if not rest.size:
                break
            hit[rest], _ = e.segments(q0[rest], q1[rest], False)
        return hit, t

    def signed_distance(self, q: np.ndarray) -> np.ndarray:
        out = np.full(len(q), np.inf)
        for e in self.engines:
            out = np.minimum(out, e.signed_distance(q))
        return out


class _FlatOperand:
    """A flat convex operand (a polygon or a segment) on the grid: its points and, for
    drawing and FCL, a fan of triangles over its hull (internal)."""

    kind = "flat"

    def __init__(self, ints: np.ndarray, grid: Grid):
        self.ints, self.faces = _flat_hull(ints)
        self.grid = grid

    @property
    def vertices(self) -> np.ndarray:
        return self.grid.to_float(self.ints)


def _flat_hull(P: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The hull of coplanar (or collinear) grid points as ``(corners, fan triangles)``,
    exact: Andrew's monotone chain on the projection along the axis nearest the normal."""
    P = np.unique(np.asarray(P, dtype=np.int64), axis=0)
    d = P - P[0]
    n = np.zeros(3, dtype=object)
    for k in range(1, len(P)):  # a normal from the first non-collinear triple
        n = np.cross(d[1].astype(object), d[k].astype(object))
        if any(n):
            break
    drop = int(np.argmax([abs(int(x)) for x in n])) if any(n) else int(np.argmin(np.ptp(P, 0)))
    keep = [a for a in range(3) if a != drop]
    pts = sorted(range(len(P)), key=lambda i: (int(P[i, keep[0]]), int(P[i, keep[1]])))

    def cross(o, a, b):
        (ox, oy), (ax, ay), (bx, by) = (P[i, keep].tolist() for i in (o, a, b))
        return (ax - ox) * (by - oy) - (ay - oy) * (bx - ox)

    hull = []
    for seq in (pts, pts[::-1]):
        part = []
        for i in seq:
            while len(part) >= 2 and cross(part[-2], part[-1], i) <= 0:
                part.pop()
            part.append(i)
        hull += part[:-1]
    corners = P[hull] if len(hull) >= 2 else P[:1]
    if len(corners) == 2:  # a segment: one degenerate triangle for FCL and drawing
        corners = np.vstack([corners, corners[1:]])
    faces = np.array([[0, k, k + 1] for k in range(1, len(corners) - 1)], dtype=np.int64)
    return corners, faces


def _flat_convex_mesh(P: np.ndarray, F: np.ndarray) -> bool:
    """Is a mesh whose grid points ``P`` are coplanar a convex polygon (or segment), modelled
    one- or two-sided: do its triangles cover their hull exactly once or twice? Exact: twice
    the projected areas, in integers, along the axis nearest the plane's normal."""
    corners, _ = _flat_hull(P)
    if len(corners) < 3 or not len(F):
        return True  # a segment: no area to compare
    U = np.unique(P, axis=0)
    d = (U - U[0]).astype(object)
    n = next((c for k in range(2, len(U)) for c in [np.cross(d[1], d[k])] if any(c)), None)
    if n is None:
        return True  # collinear
    if any(int(np.dot(n, x)) for x in d):
        return False  # not flat: some other degeneracy (a collapsed face)
    drop = int(np.argmax([abs(int(x)) for x in n]))
    keep = [a for a in range(3) if a != drop]

    def twice_area(tri) -> int:
        (ax, ay), (bx, by), (cx, cy) = ([int(v) for v in p[keep]] for p in tri)
        return abs((bx - ax) * (cy - ay) - (by - ay) * (cx - ax))

    hull = sum(twice_area((corners[0], corners[k], corners[k + 1]))
               for k in range(1, len(corners) - 1))
    total = sum(twice_area(P[f]) for f in np.asarray(F, np.int64))
    return total in (hull, 2 * hull)


def _flat_operands(obstacle, robot, c, grid, rgrid, margin: Margin):
    """``(C-obstacle polytope, O, R, margin)`` when an operand is a flat convex point set (a
    polygon or a segment): ``O ⊕ (c - R)`` is the hull of the pairwise sums of their points
    (exact on the grid), grown by ``margin``'s box. When both are flat in parallel planes the
    sum is flat too; it is then grown by at least one grid step on every axis (a solid within
    the returned margin's bound: an error that can only add collisions). None when both
    operands have volume, or the obstacle is not a point set or convex mesh."""
    from .errors import DegenerateError, DuplicateFaceError, NonManifoldError

    def points(obj, name, grid):
        try:
            return _as_convex(obj, grid, name), None
        except (DegenerateError, DuplicateFaceError):
            P = grid.snap(_vertices_of(obj))
            if _is_mesh(obj) and not _flat_convex_mesh(P, _mesh_arrays(obj)[1]):
                raise  # a thin non-convex mesh (a flat L) is not its hull
            return None, P
        except (NotConvexError, NonManifoldError):
            return None, None

    O, o_pts = points(obstacle, "obstacle", grid)
    R, r_pts = points(robot, "robot", rgrid)
    if o_pts is None and r_pts is None:
        return None
    if (O is None and o_pts is None) or (R is None and r_pts is None):
        return None  # a non-convex mesh with a flat operand: NCC-CVMS takes solids only
    A = O.ints if O is not None else o_pts
    B = rgrid.snap(c) - (R.ints if R is not None else r_pts)  # vectors: sums in grid's frame
    sums = (A[:, None, :] + B[None, :, :]).reshape(-1, 3)
    try:
        co = ConvexPolytope.from_ints(margin.grow_ints(sums), grid=grid, name="cobstacle")
    except DegenerateError:
        margin = margin.at_least(1)
        co = ConvexPolytope.from_ints(margin.grow_ints(sums), grid=grid, name="cobstacle")
    return (co, O if O is not None else _FlatOperand(o_pts, grid),
            R if R is not None else _FlatOperand(r_pts, rgrid), margin)


def grown_mesh_sum(A, B, margin: Margin, progress=None):
    """``minkowski_sum(A, B ⊕ box)`` with the box of ``margin`` (chosen for the snapping
    deviation alone), and the margin that holds for the float64 surface returned.

    ``B`` is a ConvexPolytope or ``(n, 3)`` grid ints of a convex set of vectors (``c - r``)
    on ``margin.grid``'s step; a
    flat one (a panel, a rod) is grown by at least one step on every axis, so that the sum has
    a solid operand (an error that only adds collisions, within the returned bound).

    The surface's vertices are rounded to float64 (at most half an ulp per coordinate, which
    the sum measures). When the box also covers that rounding the sum is returned as is;
    otherwise (rare: a deviation just below a whole number of steps, or none at all with
    inexact vertices) it is built once more with the box that covers the a-priori rounding
    bound, so that the stored surface holds the true C-obstacle.

    Returns ``(SumPolyhedron, Margin)``.
    """
    from .errors import DegenerateError
    from .trim import minkowski_sum

    def grown(m: Margin) -> ConvexPolytope:
        if isinstance(B, ConvexPolytope):
            return m.grow(B)
        return ConvexPolytope.from_ints(m.grow_ints(B), grid=m.grid.vectors, name="B")

    try:
        Bg = grown(margin)
    except DegenerateError:  # flat: give it volume
        margin = margin.at_least(1)
        Bg = grown(margin)
    S = minkowski_sum(A, Bg, progress=progress)
    m = margin.with_rounding(S.rounding)
    if not margin.conservative or m.holds_true:
        return S, m
    wider = Margin.for_deviation(margin.deviation, margin.grid, rounded=True)
    wider = Margin(tuple(max(a, b) for a, b in zip(wider.steps, margin.steps)),
                   wider.deviation, wider.grid, wider.rounding)
    S = minkowski_sum(A, grown(wider), progress=progress)
    return S, wider.with_rounding(S.rounding)


class CSpaceObstacle:
    """One translational C-obstacle ``CO = O ⊕ (-R)``, exact, with vectorised queries.

    Build with :meth:`build` (or wrap a closed C-obstacle surface with :meth:`from_mesh`).
    The robot with its reference point at ``q`` meets the obstacle (touching counts) exactly
    when ``q`` is in the closed set CO.

    Attributes
    ----------
    polytope : ConvexPolytope or None
        The C-obstacle (convex path), exact grid vertices and primitive integer normals;
        None on the mesh path.
    obstacle : ConvexPolytope, ClosedMesh or None
        The snapped obstacle (a ClosedMesh when non-convex).
    robot : ConvexPolytope or None
        The snapped robot (in its own frame, reference point not subtracted).
    reference_point : (3,) float64
        The robot's reference point, snapped to the grid.
    grid : Grid
    kind : {'convex', 'mesh', 'union'}
        The representation: exact facet planes, a closed triangle surface
        (:class:`cspace.meshquery.MeshCO`) for non-convex C-obstacles, or the union of
        several (``parts``; an obstacle whose pieces meet at non-manifold edges or vertices).
    margin : Margin
        The outward rounding it was grown by (:mod:`cspace.margin`); ``error_bound``.
    excess : float
        How far the hulls standing for operands that snapping bent may exceed the snapped
        operands (the obstacle's and the robot's :attr:`ConvexPolytope.excess`, from
        :func:`cspace.convex.convex_within_bound`); a hull holds its body, so this only adds
        collisions. Counted in ``error_bound``; 0 when no hull stands for a bent body.
    sum : SumPolyhedron or None
        The ``cspace.minkowski_sum`` result a mesh C-obstacle was built from (provenance,
        holes, non-manifold features), when built by :meth:`build`.

    Notes
    -----
    Every query validates its input once: ``(3,)`` or ``(k, 3)`` float64, and raises
    :class:`~cspace.errors.NonFiniteError` naming the first row with a NaN or inf.

    Examples
    --------
    >>> import numpy as np
    >>> cube = np.array([[x, y, z] for x in (0, 1) for y in (0, 1) for z in (0, 1)], float)
    >>> co = CSpaceObstacle.build(cube, 0.5 * cube, reference_point=(0.25, 0.25, 0.25))
    >>> co.bounds.tolist()
    [[-0.25, -0.25, -0.25], [1.25, 1.25, 1.25]]
    >>> co.contains([1.25, 0.5, 0.5]), co.contains([np.nextafter(1.25, 2), 0.5, 0.5])
    (True, False)
    >>> co.segment_free([-1, 1.25, 0.5], [2, 1.25, 0.5])  # slides along a facet: touches
    False
    >>> co.first_contact([-1, 0.5, 0.5], [2, 0.5, 0.5]), co.signed_distance([2, 0.5, 0.5])
    (0.25, 0.75)

    Measured here (numpy, one core, a 103-facet CO, batches of 10^5 to 10^6): ``contains``
    about 6e6 queries/s (7.7e4/s when every query is exactly on the boundary, all exact
    fallback); ``signed_distance`` 1.5e5/s; ``segment_free`` 5.5e5 segments/s, about 40 us
    for one segment per call (numpy call overhead; 30 us on a box CO); ``first_contact``
    3.7e5/s; one ``contains`` per call about 20 us. Mesh path (12848 and 3816 triangles,
    ``benchmarks/reports/queries.md``): ``contains`` 6e6 to 8.7e6/s, ``signed_distance``
    2.8e5 to 3.9e5/s, ``segment_free`` 1e6 to 1.5e6/s, one ``contains`` call about 4 us.
    """

    excess = 0.0  # hulls of bent operands (each construction that uses one sets it)

    def __init__(
        self, polytope: ConvexPolytope, *, obstacle=None, robot=None, reference_point=None,
        margin: Margin | None = None,
    ):
        self.polytope = polytope
        self.margin = margin if margin is not None else Margin.none(polytope.grid)
        self.obstacle = obstacle
        self.robot = robot
        self.reference_point = (
            np.zeros(3)
            if reference_point is None
            else np.asarray(reference_point, dtype=np.float64)
        )
        self.grid = polytope.grid
        self.kind = "convex"
        self.sum = None
        self._impl = _ConvexCO(polytope)

    @classmethod
    def from_mesh(
        cls, vertices, faces, *, obstacle=None, robot=None, reference_point=(0.0, 0.0, 0.0),
        grid: Grid | None = None, sum=None, name: str = "cobstacle", margin: Margin | None = None,
    ) -> "CSpaceObstacle":
        """Wrap a closed triangle surface as a C-obstacle (``kind='mesh'``).

        Parameters
        ----------
        vertices : (n, 3) float64
        faces : (m, 3) int64
            A closed 2-cycle (every directed edge balanced by its reverse), counter-clockwise
            seen from outside; several shells (holes facing inwards) and non-manifold edges
            are allowed. Queries are exact on these float64 coordinates.
        obstacle, robot : optional
            The operands it is the C-obstacle of (used by :func:`cspace.fcl_check.cross_check`).
        reference_point : (3,) float64
        grid : Grid, optional
            Default ``Grid.for_points(vertices)`` (kept for reference; queries do not snap).
        sum : SumPolyhedron, optional
        name : str
            Used in error messages.
        margin : Margin, optional
            How the surface was grown from its operands (default: not at all).

        Raises
        ------
        InvalidMeshError, OpenMeshError, NonFiniteError, EmptyMeshError
            Bad arrays, named (see :class:`cspace.meshquery.MeshCO`).
        """
        from .meshquery import MeshCO

        impl = MeshCO(vertices, faces, name=name)
        self = cls.__new__(cls)
        self.polytope = None
        self.obstacle = obstacle
        self.robot = robot
        self.reference_point = np.asarray(reference_point, dtype=np.float64).reshape(3)
        self.grid = grid if grid is not None else Grid.for_points(impl.vertices)
        self.margin = margin if margin is not None else Margin.none(self.grid)
        self.kind = "mesh"
        self.sum = sum
        self._impl = impl
        return self

    @classmethod
    def build(
        cls, obstacle, robot, reference_point=(0.0, 0.0, 0.0), *, grid: Grid | None = None,
        progress=None, conservative: bool = True,
    ) -> "CSpaceObstacle":
        """Compute ``CO = O ⊕ (c - R)`` exactly, grown just enough to hold the true one.

        A convex obstacle gives a convex C-obstacle (``kind='convex'``, CVMS); a non-convex
        closed mesh gives ``cspace.minkowski_sum(O, R.reflected(c))`` held as a closed
        surface (``kind='mesh'``, exact queries by :mod:`cspace.meshquery`).

        Parameters
        ----------
        obstacle : ConvexPolytope, (n, 3) float64 points, or a closed mesh
            Points are hulled; a mesh (ClosedMesh, trimesh, ``(vertices, faces)``, path)
            may be non-convex, and may touch itself at edges or vertices (two boxes sharing
            an edge: split there, the C-obstacle is the union of the pieces'). Coplanar or
            collinear points (a panel, a rod) are a flat convex operand.
        robot : ConvexPolytope, (n, 3) float64 points, or a closed convex mesh
            In its own frame; flat points (a panel, a rod) too: against a convex obstacle the
            C-obstacle is the hull of the pairwise sums, against a non-convex one the robot
            is thickened by at least one grid step (within ``error_bound``).
        reference_point : (3,) float64
            The robot point whose position ``q`` is planned (robot frame).
        grid : Grid, optional
            The obstacle's (and the C-obstacle's) snapping grid; default
            ``Grid.for_cobstacle``: centred on the C-obstacle when that is finer, so that
            precision follows its size, not its distance from the origin. The robot is
            snapped on the same step (about its reference point when far from the grid).
        progress : callable, optional
            ``progress(fraction, stage)`` during a non-convex build (see ``minkowski_sum``).
        conservative : bool, default True
            Grow the C-obstacle of the snapped operands by the least box (:mod:`cspace.margin`)
            that makes it hold the C-obstacle of the float input, so that no translation is
            ever reported free that is not (every error is a false collision within
            :attr:`error_bound`). Inputs on the grid get no growth where the result is stored
            exactly (convex path). False: the exact C-obstacle of the snapped operands, whose
            error is two-sided.

        Returns
        -------
        CSpaceObstacle
            ``margin`` says by how much it was grown; ``error_bound`` how far a reported
            collision can be from a true one.

        Raises
        ------
        NotConvexError
            The robot mesh is not convex.
        NonFiniteError, EmptyMeshError, DegenerateError, OpenMeshError
            Bad operands.
        """
        c = np.asarray(reference_point, dtype=np.float64).reshape(3)
        if not np.isfinite(c).all():
            raise NonFiniteError(f"reference_point is not finite: {c.tolist()}")
        if grid is None:
            grid = Grid.for_cobstacle(_vertices_of(obstacle), _vertices_of(robot), c)
        m = Margin.for_operands(grid, _vertices_of(obstacle), _vertices_of(robot), c[None, :],
                                rounded=False)
        return cls._grown(obstacle, robot, c, grid, m if conservative else m.without_growth(),
                          progress)

    @classmethod
    def _grown(cls, obstacle, robot, c, grid: Grid, margin: Margin, progress=None):
        """:meth:`build` with the margin decided (from the float operands)."""
        from .errors import DegenerateError, NonManifoldError, SelfIntersectionError
        from .mesh import as_mesh

        rgrid = grid.for_robot(_vertices_of(robot), c)
        c_snapped = rgrid.to_float(rgrid.snap(c))
        try:
            flat = _flat_operands(obstacle, robot, c, grid, rgrid, margin)
        except DegenerateError as exc:  # a non-convex mesh flat on the grid (a thin L plate)
            return cls._thin(obstacle, robot, c, grid, rgrid, margin, exc)
        if flat is not None:
            co, O, R, m = flat
            out = cls(co, obstacle=O, robot=R, reference_point=c_snapped, margin=m)
            out.excess = _hull_excess(O, R)
            # FCL's view: each operand a solid where it has volume, a surface where flat.
            o_flat, r_flat = isinstance(O, _FlatOperand), isinstance(R, _FlatOperand)
            out.semantics = (not o_flat, "surface" if r_flat else "convex")
            return out
        try:
            R = _as_convex(robot, rgrid, "robot")
        except DegenerateError:  # flat, against a non-convex obstacle: NCC-CVMS thickens it
            R = _FlatOperand(rgrid.snap(_vertices_of(robot)), rgrid)
        try:
            O = _as_convex(obstacle, grid, "obstacle")
        except (NotConvexError, NonManifoldError):
            try:
                O = as_mesh(obstacle, grid=grid, name="obstacle")
            except NonManifoldError as exc:  # pieces meeting at edges or vertices: one CO each
                return cls._of_parts(obstacle, robot, c, grid, margin, progress, exc)
            except DegenerateError as exc:  # thinner than a grid step somewhere
                return cls._thin(obstacle, robot, c, grid, rgrid, margin, exc)
            B = R.reflected(c) if isinstance(R, ConvexPolytope) else rgrid.snap(c) - R.ints
            try:
                S, m = grown_mesh_sum(O, B, margin, progress)
            except SelfIntersectionError as exc:  # snapping folded it: its surface and inside
                return cls._thin(obstacle, robot, c, grid, rgrid, margin, exc)
            out = cls.from_mesh(S.vertices, S.faces, obstacle=O, robot=R,
                                reference_point=c_snapped, grid=grid, sum=S, margin=m)
            out.excess = _hull_excess(R)
            if isinstance(R, _FlatOperand):
                out.semantics = (True, "surface")
            return out
        co = convex_minkowski_sum(O, margin.grow(R).reflected(c)).polytope
        out = cls(co, obstacle=O, robot=R, reference_point=c_snapped, margin=margin)
        out.excess = _hull_excess(O, R)
        return out

    @classmethod
    def _thin(cls, obstacle, robot, c, grid: Grid, rgrid: Grid, margin: Margin, why):
        """A closed obstacle whose snapped solid does not exist (features thinner than a grid
        step, a plate 1e-9 thick; or a surface that snapping folds through itself) while its
        surface does. The C-obstacle of a closed solid is that of its surface, ``union over
        triangles t of t ⊕ (c - R)`` (each piece grown by ``margin``: ``kind='union'``, one
        convex piece per triangle), plus the positions where the robot lies wholly inside it:
        when the robot fits in the obstacle's box, the containment term ``O + c - r`` for one
        robot vertex r, a mesh C-obstacle on the snapped closed 2-cycle whose inside is its
        non-zero winding number (exact). Snapping moves the surface by at most the snapping
        bound, so away from it the snapped winding number is the input's, and a robot nearer
        to it meets the grown pieces. Not a closed 2-cycle: ``why`` (the named error the
        snapped solid gave) stands.
        """
        from .errors import DegenerateError

        if not _is_mesh(obstacle):
            raise why
        V, F = _mesh_arrays(obstacle)
        cycle = (_closed_2cycle(V, F) if F.ndim == 2 and F.shape[1:] == (3,) and len(F)
                 else None)
        if cycle is None:
            raise why  # not a closed surface: the snapped solid's error is the answer
        Rv = np.asarray(_vertices_of(robot), dtype=np.float64).reshape(-1, 3)
        try:
            hull = _as_convex(robot, rgrid, "robot")
            excess, R = _hull_excess(hull), margin.grow(hull)
        except DegenerateError:  # a flat robot: give it volume
            excess = 0.0
            margin = margin.at_least(1)
            R = ConvexPolytope.from_ints(margin.grow_ints(rgrid.snap(Rv)), grid=rgrid, name="robot")
        B = R.reflected(c)
        T = grid.snap(V)[np.asarray(F, np.int64)]
        c_snapped = rgrid.to_float(rgrid.snap(c))
        cos = []
        for k, t in enumerate(T):
            piece = ConvexPolytope.from_ints((t[:, None, :] + B.ints[None]).reshape(-1, 3),
                                             grid=grid.plus(B.grid), name=f"triangle {k}")
            co = cls(piece, obstacle=_FlatOperand(t, grid), robot=R, reference_point=c_snapped,
                     margin=margin)
            co.excess = excess
            co.semantics = (False, "convex")  # FCL: the obstacle's triangles, as a surface
            cos.append(co)
        U, G = cycle
        if not _wider_somewhere(Rv, U):  # the robot may lie wholly inside: what O encloses
            ints = grid.snap(U) + (rgrid.snap(c) - rgrid.snap(Rv[0]))  # O + c - r, exact
            co = cls.from_mesh(grid.to_float(ints), G, obstacle=_Mesh(U, G, "obstacle"),
                               robot=R, reference_point=c_snapped, grid=grid, margin=margin,
                               name="containment")
            co.excess = excess
            co.semantics = (True, "convex")  # FCL: the obstacle as the solid it encloses
            cos.append(co)
        out = cls.union(cos)
        out.thin = str(why)
        return out

    @classmethod
    def _of_parts(cls, obstacle, robot, c, grid: Grid, margin: Margin, progress=None,
                  why=None):
        """A closed obstacle whose pieces meet at non-manifold edges or vertices (two boxes
        sharing an edge): split there into closed manifold pieces (exactly, as scenes are,
        :func:`cspace.components.split_mesh`); the C-obstacle is the union of theirs. One
        part (a surface pinched at a vertex, not split apart): ``why`` stands."""
        from .components import split_mesh
        from .errors import NonManifoldError

        parts = split_mesh(*_mesh_arrays(obstacle), grid)
        if len(parts) < 2 and why is not None:
            raise why
        cos = []
        for k, piece in enumerate(parts):
            try:
                cos.append(cls._grown(piece, robot, c, grid, margin, progress))
            except NonManifoldError as exc:  # a part pinched at a vertex
                raise NonManifoldError(f"obstacle: piece {k} of {len(parts)}: {exc}") from None
        return cls.union(cos)

    @classmethod
    def union(cls, cos: list) -> "CSpaceObstacle":
        """One C-obstacle answering for several (their union, not built): ``contains`` and
        ``segment_free`` over all, ``first_contact`` the earliest, ``signed_distance`` the
        least (inside: minus the deepest containing one's depth, a lower bound on the union's).
        ``kind='union'``; ``parts`` holds them."""
        if len(cos) == 1:
            return cos[0]
        self = cls.__new__(cls)
        self.parts = list(cos)
        first = cos[0]
        self.polytope, self.sum, self.kind = None, None, "union"
        self.obstacle = _Mesh.join([co.obstacle for co in cos])
        self.robot, self.reference_point, self.grid = first.robot, first.reference_point, first.grid
        self.margin = max((co.margin for co in cos), key=lambda m: m.error_bound)
        self.semantics = getattr(first, "semantics", None)
        self._impl = _UnionOf(cos)
        return self

    # ---- properties ---------------------------------------------------------------------

    @property
    def n_facets(self) -> int:
        """Polygon facets (mesh path: of the SumPolyhedron if known, else triangles)."""
        if self.polytope is not None:
            return self.polytope.n_facets
        if self.sum is not None and len(self.sum.face_facet):
            return int(self.sum.face_facet.max()) + 1
        return len(self._impl.faces)

    @property
    def vertices(self) -> np.ndarray:
        """(n, 3) float64 vertices of the C-obstacle (exact on the convex path; the stored
        float64 surface, on which queries are exact, on the mesh path)."""
        if self.polytope is None:
            return self._impl.vertices
        return self.polytope.vertices

    @property
    def faces(self) -> np.ndarray:
        """(m, 3) int64 triangles of the C-obstacle's boundary, counter-clockwise from outside."""
        if self.polytope is None:
            return self._impl.faces
        return self.polytope.faces

    @property
    def bounds(self) -> np.ndarray:
        """(2, 3) float64 bounding box of the C-obstacle."""
        V = self.vertices
        return np.stack([V.min(axis=0), V.max(axis=0)])

    @property
    def error_bound(self) -> float:
        """How far (scene units) a translation reported in collision can be from the true
        C-obstacle of the float input: :attr:`margin`'s bound plus :attr:`excess` (a hull
        standing for a body that snapping bent); a union's is the largest of its parts'.
        Built with ``conservative=True`` the error is one-sided: every true collision is
        reported."""
        parts = getattr(self, "parts", None)
        if self.kind == "union" and parts:
            return max(co.error_bound for co in parts)
        return self.margin.error_bound + self.excess

    def __repr__(self) -> str:
        return (
            f"CSpaceObstacle(kind={self.kind!r}, facets={self.n_facets}, "
            f"vertices={len(self.vertices)})"
        )

    def to_trimesh(self):
        """The C-obstacle's boundary triangles as a ``trimesh.Trimesh`` (float64, not
        re-processed; for a union of pieces, their overlapping boundaries)."""
        import trimesh

        return trimesh.Trimesh(self.vertices, self.faces, process=False)

    # ---- queries ------------------------------------------------------------------------

    def contains(self, q) -> np.ndarray | bool:
        """Is the robot at translation ``q`` in collision (``q`` in the closed CO)?

        Exact for every float64 ``q`` (no snapping, no tolerance); the boundary counts as
        inside (touching is a collision). Convex path: one ``(k, 4) x (4, f)`` product and a
        max; rows within the filter's bound of a facet plane are decided with Python integers.
        Mesh path: on a triangle, or a non-zero winding number from a symbolically perturbed
        ray (see :mod:`cspace.meshquery`).

        Parameters
        ----------
        q : (k, 3) or (3,) float64

        Returns
        -------
        inside : (k,) bool, or a Python bool for a ``(3,)`` input
        """
        q, single = _translations(q)
        out = self._impl.contains(q)
        return bool(out[0]) if single else out

    def plane_signs(self, q) -> np.ndarray:
        """Exact ``(k, f)`` int8 side of each ``q`` against each facet plane (+1 outside it)."""
        if self.kind != "convex":
            raise TypeError(f"plane_signs is defined for a convex C-obstacle, not kind {self.kind!r}")
        q, _ = _translations(q)
        return self._impl.plane_signs(q)

    def signed_distance(self, q) -> np.ndarray | float:
        """Euclidean distance from ``q`` to the CO boundary, negative inside.

        The sign is exact (:meth:`contains`; boundary points give ``-0.0`` or ``0.0``).
        Outside: the distance to the nearest point of the polytope, the minimum over facets
        whose projection holds ``q`` (plane distance) and over all edges (segment distance).
        Inside: ``-min_j (d_j - n_j . q) / |n_j|``, the exact translational penetration depth
        of a convex C-obstacle (the shortest translation that frees the robot).

        The magnitude is computed in float64 on coordinates centred on the CO: its error is
        a few ulps of ``r + |q - centre|`` (``r`` the CO's radius); the a-priori bound used
        in the tests is ``64 eps (r + |q - centre|)`` (checked against FCL, see
        :mod:`cspace.fcl_check`). Mesh path: the distance to the nearest triangle, outside
        and inside alike (inside, the translational penetration depth of the C-obstacle).

        Parameters
        ----------
        q : (k, 3) or (3,) float64

        Returns
        -------
        distance : (k,) float64, or a float for a ``(3,)`` input
        """
        q, single = _translations(q)
        out = self._signed_distance(q)
        return float(out[0]) if single else out

    def _signed_distance(self, q: np.ndarray) -> np.ndarray:
        return self._impl.signed_distance(q)

    def segment_free(self, q0, q1) -> np.ndarray | bool:
        """Does the straight translation from ``q0`` to ``q1`` stay out of CO?

        An exact continuous check, no sampling. Mesh path: the closed segment meets CO iff it
        meets a triangle (exact segment-triangle tests, coplanar and touching included) or
        ``q0`` is inside. Convex path: the closed segment misses the closed convex
        CO iff no ``t`` in ``[0, 1]`` satisfies every facet inequality. The parameter interval
        is clipped facet by facet; each clip is a ratio of two plane values whose signs are
        exact (float filter), the interval test uses ratios with rigorous error bounds, and
        segments the filter cannot decide (touching, lying in a facet plane, ...) are redone
        with Python integers and fractions. Touching counts as a collision (not free). A
        zero-length segment is free iff ``not contains(q0)``.

        Parameters
        ----------
        q0, q1 : (k, 3) or (3,) float64
            Start and end translations (broadcast to a common ``(k, 3)``).

        Returns
        -------
        free : (k,) bool, or a Python bool if both inputs are ``(3,)``
        """
        q0, q1, single = self._pair(q0, q1)
        hit, _ = self._impl.segments(q0, q1, want_t=False)
        return bool(not hit[0]) if single else ~hit

    def first_contact(self, q0, q1) -> np.ndarray | float:
        """Parameter ``t`` in ``[0, 1]`` of the first contact along ``q0 + t (q1 - q0)``.

        The exact entry parameter (a rational) rounded to the nearest float64; ``0.0`` when
        ``q0`` is in CO (touching included); NaN when the segment stays free.

        Parameters
        ----------
        q0, q1 : (k, 3) or (3,) float64

        Returns
        -------
        t : (k,) float64, or a float if both inputs are ``(3,)``

        Notes
        -----
        Free segments are decided by the float filter; each colliding segment is resolved
        exactly with Python integers (about ``f`` fraction operations).
        """
        q0, q1, single = self._pair(q0, q1)
        _, t = self._impl.segments(q0, q1, want_t=True)
        return float(t[0]) if single else t

    @staticmethod
    def _pair(q0, q1):
        a, s0 = _translations(q0, "q0")
        b, s1 = _translations(q1, "q1")
        if len(a) != len(b):
            if len(a) == 1:
                a = np.broadcast_to(a, b.shape)
            elif len(b) == 1:
                b = np.broadcast_to(b, a.shape)
            else:
                raise InvalidQueryError(f"q0 and q1 have {len(a)} and {len(b)} rows")
        return np.ascontiguousarray(a), np.ascontiguousarray(b), s0 and s1


_NON_CONVEX = "non-convex C-obstacles need cspace.minkowski_sum (issue #4)"


class CSpace:
    """Several C-obstacles answering the same queries over all of them (no union built).

    Parameters
    ----------
    obstacles : sequence of CSpaceObstacle
    bounds : (2, 3) float64, optional
        The box translations are planned in (used by sampling checks); default the bounding
        box of the C-obstacles.
    scene : Scene, optional
        The scene the C-obstacles were built from: checks against FCL use its raw meshes.
    robot_hull : bool, default False
        The C-obstacles are of the robot's convex hull (checks use the hull too).
    """

    def __init__(self, obstacles, *, bounds=None, name: str = "cspace", scene=None,
                 robot_hull: bool = False):
        self.obstacles = tuple(obstacles)
        self._union = _UnionOf(self.obstacles)
        self.name = name
        # The scene as loaded (set by SceneModel.cspace): FCL cross-checks judge on its raw
        # meshes (cspace.fcl_check.SceneOracle), never on anything built here.
        self.scene = scene
        self.robot_hull = bool(robot_hull)
        if bounds is None:
            if not self.obstacles:
                raise InvalidArgumentError("a CSpace without obstacles needs bounds")
            b = np.stack([o.bounds for o in self.obstacles])
            bounds = np.stack([b[:, 0].min(axis=0), b[:, 1].max(axis=0)])
        self.bounds = np.asarray(bounds, dtype=np.float64).reshape(2, 3)

    @classmethod
    def from_scene(cls, scene, *, grid: Grid | None = None, cache=None,
                   progress=None, robot_hull: bool = False, executor=None) -> "CSpace":
        """The C-obstacles a scene needs, built: :func:`cspace.model.model_scene` decides per
        body (split, deduplicated; convex, solid, surface or dropped) and builds each.

        Parameters
        ----------
        scene : Scene
        grid : Grid, optional
            Default ``scene.grid()`` (centred on the scene).
        cache : COCache, path, True, or None
            Disk cache of C-obstacles (:mod:`cspace.cache`); None: none.
        progress : callable, optional
            ``progress(fraction, message)``, see :func:`cspace.model.model_scene`.
        robot_hull : bool, default False
            Use the robot's convex hull instead of its exact parts (see ``model_scene``).
        executor : concurrent.futures.Executor, optional
            Build the C-obstacles there (a process pool, a Dask cluster:
            :func:`cspace.scale.executor_for`); same answers as the local build.

        Raises
        ------
        BuildError
            A body's C-obstacle could not be built; the message names the body and why.
        """
        from .model import model_scene

        return model_scene(scene, grid=grid, cache=cache, progress=progress,
                           robot_hull=robot_hull, executor=executor).cspace()

    def __len__(self) -> int:
        return len(self.obstacles)

    def __repr__(self) -> str:
        return f"CSpace(name={self.name!r}, obstacles={len(self.obstacles)})"

    def contains(self, q) -> np.ndarray | bool:
        """In collision with any obstacle (exact, touching counts).

        See :meth:`CSpaceObstacle.contains`.
        """
        q, single = _translations(q)
        out = self._union.contains(q)
        return bool(out[0]) if single else out

    def signed_distance(self, q) -> np.ndarray | float:
        """Minimum of the obstacles' signed distances.

        Outside every C-obstacle this is the exact clearance (distance to the union).
        Inside, it is ``-max`` of the penetration depths of the C-obstacles containing ``q``:
        a lower bound on the penetration depth of the union (overlapping C-obstacles can
        make the true depth larger); the sign is exact either way.
        """
        q, single = _translations(q)
        out = self._union.signed_distance(q)
        return float(out[0]) if single else out

    def segment_free(self, q0, q1) -> np.ndarray | bool:
        """Free of every obstacle (exact); see :meth:`CSpaceObstacle.segment_free`."""
        a, b, single = CSpaceObstacle._pair(q0, q1)
        free = ~self._union.segments(a, b, want_t=False)[0]
        return bool(free[0]) if single else free

    def first_contact(self, q0, q1) -> np.ndarray | float:
        """Smallest first-contact parameter over the obstacles (NaN if the segment is free)."""
        a, b, single = CSpaceObstacle._pair(q0, q1)
        t = self._union.segments(a, b, want_t=True)[1]
        return float(t[0]) if single else t
