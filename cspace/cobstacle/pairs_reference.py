"""Pure-Python reference of the compiled triangle-pair engine (:class:`cspace.cobstacle.pairs._TreePairsCO`).

:class:`_PairsCO` enumerates the pairs it is given and finds a query's candidates with a uniform
grid of cells over their boxes, then evaluates every slab with numpy: the engine triangle
pairs used before the box trees, kept so that ``tests/test_pair_engine.py`` can check that the
compiled engine gives identical answers. Nothing in production calls it.
"""

from __future__ import annotations

import numpy as np

from ..geometry.distance import _tri_tri_distance
from ..geometry.exact import _FILTER, _TINY
from .convex import exact_plane_sign, exact_segment_entry, segment_filter
from .pairs import _KEEP, _PAIRS, _depth_of, _pair_halfspaces, _signed_distance, _slab_columns

__all__ = ["_PairsCO"]


class _PairsCO:
    """Exact queries on ``∪ s_i ⊕ t_j`` over given triangle pairs (the engine interface of
    :mod:`cspace.cobstacle.obstacle`), with no hull built per pair.

    Each pair's piece is the intersection of 17 slabs (:func:`~cspace.cobstacle.pairs.pair_planes`; 38 for pieces grown
    by the margin box ``[-g, g]``). Queries find the
    pairs whose piece box holds them (a uniform grid of cells, as the surface reference's), compute
    the slab values in float with a rigorous bound (16 unit roundoffs of the sum of absolute
    products, the normals and supports rounded to float included), and settle what the bound
    leaves with Python integers. Touching counts as inside.
    """

    def __init__(self, S: np.ndarray, T: np.ndarray, pairs: np.ndarray, grid,
                 margin=(0, 0, 0)):
        from .surface import _CellGrid

        # S (obstacle triangles, in grid's frame) moved to the scene frame by the grid's
        # origin, exactly: T holds vectors (c - t), so every piece and plane is then in the
        # scene frame and a query is only scaled, never shifted.
        self.S = np.asarray(S, np.int64) + np.asarray(grid.origin, np.int64)
        self.T = np.asarray(T, np.int64)
        self.pairs = np.asarray(pairs, np.int64).reshape(-1, 2)
        if not len(self.pairs):
            raise ValueError("a triangle-pair C-obstacle needs at least one pair")
        self.grid, self.exponent = grid.vectors, grid.exponent
        # Pieces grown by the box [-g, g] (outward rounding): 38 slabs instead of 17.
        self.g = np.asarray(margin, dtype=np.int64).reshape(3)
        self.grown = bool(self.g.any())
        self.n_slabs = 38 if self.grown else 17
        self._gf = self.g.astype(np.float64)
        i, j = self.pairs[:, 0], self.pairs[:, 1]
        # S already holds the origin: the boxes are scaled by the vectors' grid, not shifted.
        self.lo = self.grid.to_float(self.S[i].min(axis=1) + self.T[j].min(axis=1) - self.g)
        self.hi = self.grid.to_float(self.S[i].max(axis=1) + self.T[j].max(axis=1) + self.g)
        self.cells = _CellGrid(self.lo, self.hi)
        # The two triangle normals' slabs first: most pairs near a query are separated by
        # one of them, and they cost six dot products a pair.
        ns = np.cross(self.S[:, 1] - self.S[:, 0], self.S[:, 2] - self.S[:, 0])
        nt = np.cross(self.T[:, 1] - self.T[:, 0], self.T[:, 2] - self.T[:, 0])
        self._ns, self._nt = ns.astype(np.float64), nt.astype(np.float64)
        self._Sf, self._Tf = self.S.astype(np.float64), self.T.astype(np.float64)
        self._s_abs = np.abs(self._Sf).max(axis=1)
        self._t_abs = np.abs(self._Tf).max(axis=1)
        # Slab columns of every pair up front when they fit in about 64 MB, else per query.
        fits = len(self.pairs) * self.n_slabs <= _KEEP * 17
        self._all = self._columns(np.arange(len(self.pairs))) if fits else None

    # ---- slabs ------------------------------------------------------------------------

    def _columns(self, p: np.ndarray):
        return _slab_columns(self.S[self.pairs[p, 0]], self.T[self.pairs[p, 1]], self.grown,
                             self._gf)

    def _exact_planes(self, p: int):
        """``(n, d)`` Python-int half-spaces ``n . k <= d`` of pair ``p``'s piece."""
        return _pair_halfspaces(self.S[self.pairs[p, 0]], self.T[self.pairs[p, 1]], self.g)

    def _columns_of(self, p: np.ndarray):
        if self._all is not None:
            return self._all[0][p], self._all[1][p]
        unique, inverse = np.unique(p, return_inverse=True)
        A, absA = self._columns(unique)
        return A[inverse], absA[inverse]

    def _values(self, q: np.ndarray, p: np.ndarray):
        A, absA = self._columns_of(p)
        Q = np.ones((len(q), 1, 4))
        with np.errstate(over="ignore", under="ignore", invalid="ignore"):
            np.ldexp(q, -self.exponent, out=Q[:, 0, :3])
            val = np.matmul(Q, A)[:, 0, :]
            err = _FILTER * np.matmul(np.abs(Q), absA)[:, 0, :] + _TINY
        return val, err

    def _face_values(self, q: np.ndarray, p: np.ndarray):
        """Values and bounds of the four face-normal slab sides of pairs ``p`` at queries
        ``q`` (rows matched), as :meth:`_values` gives for all: a cheap first pass."""
        i, j = self.pairs[p, 0], self.pairs[p, 1]
        Q = np.ldexp(q, -self.exponent)
        out, errs = [], []
        for n, own, other, own_abs, other_abs in (
                (self._ns[i], self._Sf[i], self._Tf[j], self._s_abs[i], self._t_abs[j]),
                (self._nt[j], self._Tf[j], self._Sf[i], self._t_abs[j], self._s_abs[i])):
            base = np.einsum("kj,kj->k", n, own[:, 0])       # constant over its own triangle
            dots = np.einsum("kj,kaj->ka", n, other)
            x = np.einsum("kj,kj->k", n, Q)
            an = np.abs(n)
            box = an @ self._gf  # the margin box's support
            err = _FILTER * (np.einsum("kj,kj->k", an, np.abs(Q))
                             + np.einsum("kj,kj->k", an, own_abs)
                             + np.einsum("kj,kj->k", an, other_abs) + box) + _TINY
            out += [x - base - dots.max(axis=1) - box, base + dots.min(axis=1) - x - box]
            errs += [err, err]
        return np.stack(out, axis=1), np.stack(errs, axis=1)

    # ---- queries ----------------------------------------------------------------------

    def candidates(self, q: np.ndarray):
        rows, p = self.cells.pairs(q)
        keep = ((self.lo[p] <= q[rows]) & (q[rows] <= self.hi[p])).all(axis=1)
        return rows[keep], p[keep]

    def contains(self, q: np.ndarray) -> np.ndarray:
        out = np.zeros(len(q), dtype=bool)
        rows, ps = self.candidates(q)
        if len(rows):
            with np.errstate(over="ignore", under="ignore", invalid="ignore"):
                val, err = self._face_values(q[rows], ps)
            beyond = ((val > err) & np.isfinite(val)).any(axis=1)
            rows, ps = rows[~beyond], ps[~beyond]
        for s in range(0, len(rows), _PAIRS):
            r, p = rows[s:s + _PAIRS], ps[s:s + _PAIRS]
            val, err = self._values(q[r], p)
            fin = np.isfinite(val) & np.isfinite(err)
            inside = ((val < -err) & fin).all(axis=1)
            unsure = ~inside & ~((val > err) & fin).any(axis=1)
            for k in np.nonzero(unsure)[0].tolist():
                if not out[r[k]] and not inside[k]:
                    x = q[r[k]].tolist()
                    inside[k] = all(exact_plane_sign(n, d, self.exponent, x) <= 0
                                    for n, d in self._exact_planes(int(p[k])))
            out[r[inside]] = True
        return out

    def _segment_candidates(self, a: np.ndarray, b: np.ndarray):
        """``(row, pair)`` whose piece box meets the segment's box (cells first, then exact)."""
        rows, ps = [], []
        lo, hi = np.minimum(a, b), np.maximum(a, b)
        if len(self.lo) <= _KEEP // 8 or len(a) * len(self.lo) <= (1 << 16):
            step = max(1, (1 << 20) // len(self.lo))
            for s in range(0, len(a), step):
                m = ((self.lo[None] <= hi[s:s + step, None])
                     & (lo[s:s + step, None] <= self.hi[None])).all(axis=2)
                r, p = np.nonzero(m)
                rows.append(r + s)
                ps.append(p)
            return np.concatenate(rows), np.concatenate(ps)
        c0, c1 = self.cells.cells(lo), self.cells.cells(hi)
        n = self.cells.n
        for r in range(len(a)):
            ranges = [np.arange(c0[r, k], c1[r, k] + 1) for k in range(3)]
            cell = ((ranges[0][:, None, None] * n[1] + ranges[1][None, :, None]) * n[2]
                    + ranges[2][None, None, :]).ravel()
            starts, ends = self.cells.starts[cell], self.cells.starts[cell + 1]
            idx = np.unique(np.concatenate([self.cells.boxes[s:e] for s, e in zip(starts, ends)]))
            keep = ((self.lo[idx] <= hi[r]) & (lo[r] <= self.hi[idx])).all(axis=1)
            ps.append(idx[keep])
            rows.append(np.full(int(keep.sum()), r, dtype=np.int64))
        return np.concatenate(rows), np.concatenate(ps)

    def segments(self, q0: np.ndarray, q1: np.ndarray, want_t: bool):
        hit = np.zeros(len(q0), dtype=bool)
        tout = np.full(len(q0), np.nan)
        rows, ps = self._segment_candidates(q0, q1)
        if len(rows):
            with np.errstate(over="ignore", under="ignore", invalid="ignore"):
                v0, e0 = self._face_values(q0[rows], ps)
                v1, e1 = self._face_values(q1[rows], ps)
            beyond = ((v0 > e0) & (v1 > e1) & np.isfinite(v0) & np.isfinite(v1)).any(axis=1)
            rows, ps = rows[~beyond], ps[~beyond]
        for s in range(0, len(rows), _PAIRS):
            r, p = rows[s:s + _PAIRS], ps[s:s + _PAIRS]
            if not want_t:
                keep = ~hit[r]
                r, p = r[keep], p[keep]
                if not len(r):
                    continue
            v0, e0 = self._values(q0[r], p)
            v1, e1 = self._values(q1[r], p)
            with np.errstate(divide="ignore", invalid="ignore", over="ignore"):
                free, sure, _, _, _ = segment_filter(v0, v1, e0, e1)
            hit[r[sure]] = True
            todo = ~free & (~sure | want_t)
            for k in np.nonzero(todo)[0].tolist():
                if not want_t and hit[r[k]]:
                    continue
                entry = exact_segment_entry(self._exact_planes(int(p[k])), self.exponent,
                                            q0[r[k]].tolist(), q1[r[k]].tolist())
                if entry is not None:
                    hit[r[k]] = True
                    if want_t:
                        tout[r[k]] = np.fmin(tout[r[k]], float(entry))
        return hit, tout

    def signed_distance(self, q: np.ndarray) -> np.ndarray:
        return _signed_distance(self, q)

    def _depth(self, q: np.ndarray) -> np.ndarray:
        """Deepest containing piece: the least slab distance (every slab side supports the
        piece, and its facets' are among them), a lower bound on the union's depth."""
        depth = np.zeros(len(q))
        rows, ps = self.candidates(q)
        if len(rows):
            A, absA = self._columns_of(ps)
            np.maximum.at(depth, rows, _depth_of(q[rows], A, absA, self.exponent,
                                                 self.grid.step))
        return depth

    def _distance_outside(self, q: np.ndarray) -> np.ndarray:
        """Distance to the nearest piece: the distance between triangle ``s`` and the
        triangle ``q - t`` (disjoint outside the piece). The nearest box's pair gives an upper
        bound; then only pairs whose box is nearer are evaluated (float; not a decision)."""
        S = self.grid.to_float(self.S.reshape(-1, 3)).reshape(self.S.shape)
        T = self.grid.to_float(self.T.reshape(-1, 3)).reshape(self.T.shape)
        best = np.full(len(q), np.inf)
        step = max(1, (1 << 20) // len(self.lo))
        for s in range(0, len(q), step):
            x = q[s:s + step]
            gap = np.maximum(np.maximum(self.lo[None] - x[:, None], x[:, None] - self.hi[None]),
                             0.0)
            box = np.sqrt(np.einsum("kpj,kpj->kp", gap, gap))
            first = box.argmin(axis=1)
            b = self._pair_distance(S, T, x, np.arange(len(x)), first)
            rows, ps = np.nonzero(box < b[:, None])
            for c in range(0, len(rows), 1 << 16):
                r, p = rows[c:c + (1 << 16)], ps[c:c + (1 << 16)]
                np.minimum.at(b, r, self._pair_distance(S, T, x, r, p))
            best[s:s + step] = b
        if self.grown:  # the grown piece is nearer by at most the box's half-diagonal
            best = np.maximum(best - float(np.linalg.norm(self._gf)) * self.grid.step, 0.0)
        return best

    def _pair_distance(self, S, T, x, rows, ps):
        i, j = self.pairs[ps, 0], self.pairs[ps, 1]
        return _tri_tri_distance(S[i], x[rows][:, None, :] - T[j])
