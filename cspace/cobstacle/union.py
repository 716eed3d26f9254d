"""The union of several C-obstacles' engines, not built: one query over all of them.

:class:`_UnionOf` asks each engine only for the rows not yet decided; its vertices and faces
are joined on first use (drawing only).
"""

from __future__ import annotations

import numpy as np

from ..mesh.operands import _Mesh


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
