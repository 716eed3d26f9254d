"""Convex C-obstacles: a convex polytope's exact queries over translations.

:class:`_ConvexCO` answers ``contains``, ``signed_distance`` and ``segments`` for a convex
C-obstacle stored as exact grid-integer half-spaces: float-filtered plane signs
(:func:`segment_filter`) with an exact fallback (:func:`exact_plane_sign`,
:func:`exact_segment_entry`).
"""

from __future__ import annotations

import math
from fractions import Fraction

import numpy as np

from ..errors import InvalidQueryError, NonFiniteError
from ..geometry.exact import _EPS, _FILTER, _TINY, _dyadic
from ..mesh.convex import ConvexPolytope


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
        # one state, as a planner asks: three float checks cost less than a ufunc's call
        if a.shape == (3,) and all(map(math.isfinite, a.tolist())):
            return a[None, :], True
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
    non-convex representations (:class:`cspace.mesh.query.MeshCO` for a closed surface, the
    union of convex pieces in :mod:`cspace.cobstacle.surface`) implement the same three.
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
        self._float_geometry = False

    def _distance_geometry(self) -> None:
        """Float geometry for distances, centred on the polytope (smaller magnitudes): made
        on the first distance asked, since most C-obstacles of a scene are only tested."""
        if self._float_geometry:
            return
        poly, N = self.poly, self.poly.normals.astype(np.int64)
        Nf = N.astype(np.float64)
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
        self._float_geometry = True  # last: a half-made geometry is never used

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
        self._distance_geometry()
        p = q - self.centre
        return (self.dh[None, :] - p @ self.nh.T).min(axis=1)

    def distance_outside(self, q: np.ndarray) -> np.ndarray:
        """Euclidean distance from each (outside) point to the polytope, float."""
        self._distance_geometry()
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
