"""The union of several C-obstacles' engines, not built: one query over all of them.

:class:`_UnionOf` asks each engine only for the rows not yet decided; its vertices and faces
are joined on first use (drawing only).
"""

from __future__ import annotations

import numpy as np

from ..geometry._kernels import load
from ..geometry.boxes import BoxTree
from ..mesh.operands import _Mesh

_boxtree = load("boxtree")


class _UnionOf:
    """The engine interface over several C-obstacles' engines: their union, not built
    (:class:`CSpace` and ``kind='union'`` C-obstacles). A query asks only the engines whose
    box it meets (one broad phase over all boxes, a compiled box tree), and not for rows
    already decided; vertices and faces are joined on first use (drawing only). With
    ``lazy=(lo, hi, make)`` its members are made the first time a query meets their box
    (:class:`cspace.scene.model.LazyCSpace`)."""

    def __init__(self, cos, *, lazy=None):
        self._joined = None
        self._index = None
        if lazy is not None:
            # Members made on first use: ``lazy = (lo, hi, make)``, member k's engine
            # ``make(k)`` (a _UnionOf) answering only inside the box ``[lo[k], hi[k]]``
            # (scene units).
            lo, hi, self._make = lazy
            self.cos = None  # every member's C-obstacles: made all at once when drawn
            self.engines = [None] * len(lo)
            if len(lo):
                self._index = _boxtree.BoxIndex(BoxTree(lo, hi))
            return
        self.cos = tuple(cos)
        self.engines = [None] * len(self.cos)  # each made when a query first meets it
        self._make = self._member
        # Broad phase: each C-obstacle's box, widened by 2**-40 of its coordinates (float
        # vertices of rational points are off by an ulp at most): a query outside a box is
        # outside that C-obstacle. Only prunes; each engine still decides exactly.
        if self.cos:
            B = np.array([np.asarray(co.bounds, dtype=np.float64) for co in self.cos])
            pad = np.ldexp(np.abs(B).max(axis=1), -40) + 1e-300
            self._index = _boxtree.BoxIndex(BoxTree(B[:, 0] - pad, B[:, 1] + pad))

    def _member(self, k: int):
        return self.cos[k]._impl

    def _engine(self, k: int):
        """Member ``k``'s engine (a lazy member's: the union of its C-obstacles, made now)."""
        e = self.engines[k]
        if e is None:
            e = self.engines[k] = self._make(k)
        return e

    def _near(self, lo: np.ndarray, hi: np.ndarray):
        """Per engine, the rows whose box ``[lo, hi]`` meets the engine's box (a box tree over
        the engines' boxes, compiled)."""
        if self._index is None or not len(lo):
            return []
        rows, items = self._index.overlaps(np.ascontiguousarray(lo, dtype=np.float64),
                                           np.ascontiguousarray(hi, dtype=np.float64))
        order = np.lexsort((rows, items))
        rows, items = rows[order], items[order]
        cut = np.flatnonzero(np.diff(items)) + 1
        return [(int(k[0]), r) for k, r in zip(np.split(items, cut), np.split(rows, cut))
                if len(k)]

    def all_cos(self) -> tuple:
        """Every member's C-obstacles (a lazy union makes all its members)."""
        if self.cos is not None:
            return self.cos
        return tuple(co for k in range(len(self.engines)) for co in self._engine(k).all_cos())

    def _join(self):
        if self._joined is None:
            self._joined = _Mesh.join(self.all_cos())
        return self._joined

    @property
    def vertices(self) -> np.ndarray:
        return self._join().vertices

    @property
    def faces(self) -> np.ndarray:
        return self._join().faces

    def contains_point(self, x: list) -> bool:
        """One state (three finite floats, scene frame), as a planner asks: no arrays on the
        way to the engines that answer points (``contains_point``), exact like ``contains``."""
        if self._index is None:
            return False
        for k in self._index.point(*x):
            e = self._engine(k)
            point = getattr(e, "contains_point", None)
            if point(x) if point is not None else e.contains(np.array([x]))[0]:
                return True
        return False

    def contains(self, q: np.ndarray) -> np.ndarray:
        if len(q) == 1 and self._index is not None:  # one state, as a planner asks
            return np.array([self.contains_point(q[0].tolist())])
        out = np.zeros(len(q), dtype=bool)
        for k, rows in self._near(q, q):
            rest = rows[~out[rows]]
            if rest.size:
                out[rest] = self._engine(k).contains(q[rest])
        return out

    def segments(self, q0: np.ndarray, q1: np.ndarray, want_t: bool):
        hit, t = np.zeros(len(q0), dtype=bool), np.full(len(q0), np.nan)
        if len(q0) == 1 and not want_t and self._index is not None:  # one motion
            ks = self._index.box(*np.minimum(q0[0], q1[0]).tolist(),
                                 *np.maximum(q0[0], q1[0]).tolist())
            hit[0] = any(self._engine(k).segments(q0, q1, False)[0][0] for k in ks)
            return hit, t
        for k, rows in self._near(np.minimum(q0, q1), np.maximum(q0, q1)):
            e = self._engine(k)
            if want_t:  # the earliest contact over all
                h, te = e.segments(q0[rows], q1[rows], True)
                hit[rows] |= h
                t[rows] = np.fmin(t[rows], te)
                continue
            rest = rows[~hit[rows]]
            if rest.size:
                hit[rest], _ = e.segments(q0[rest], q1[rest], False)
        return hit, t

    def signed_distance(self, q: np.ndarray) -> np.ndarray:
        out = np.full(len(q), np.inf)
        for k in range(len(self.engines)):
            out = np.minimum(out, self._engine(k).signed_distance(q))
        return out
