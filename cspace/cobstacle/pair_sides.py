"""The operands of triangle-pair engines (:class:`cspace.cobstacle.pairs.PairObstacle`), as the
compiled kernels read them, made once per content.

A side is one operand: the obstacle's triangles ``S`` or the robot's vectors ``T = c - t``,
with float copies, canonical primitive normals and a k-DOP tree. Sides are shared by content
(:func:`_side`): every body of one build shares the robot's side, and the orientation slices
of one grid share each body's, so a slice holds and builds only what differs.
"""

from __future__ import annotations

import hashlib
import weakref

import numpy as np

__all__: list[str] = []


def _primitive_normals(tri: np.ndarray) -> np.ndarray:
    """``(m, 3)`` int64 primitive normals of grid triangles, sign made canonical (first
    non-zero component positive); zero for collinear corners. Exact: edges of 28-bit grid
    coordinates give cross products below 2**60."""
    n = np.cross(tri[:, 1] - tri[:, 0], tri[:, 2] - tri[:, 0])
    g = np.gcd.reduce(np.abs(n), axis=1)
    n = n // np.maximum(g, 1)[:, None]
    first = np.where(n[:, 0] != 0, n[:, 0], np.where(n[:, 1] != 0, n[:, 1], n[:, 2]))
    return n * np.where(first < 0, -1, 1)[:, None]


class _Side:
    """One operand of triangle-pair engines, as the compiled kernels read it: grid triangles
    ``X (n, 3, 3)`` (obstacle triangles ``S``, or robot vectors ``T = c - t``), float copies,
    canonical primitive normals (of ``X``, or of ``-X`` for ``T``), raw normals of ``X``, and
    the k-DOP tree of ``X`` grown by ``g`` (of ``-X`` for ``T``: the boxes of ``t - c``)."""

    def __init__(self, X: np.ndarray, g: np.ndarray, negate: bool, k: int | None = None):
        from ..geometry.boxes import BoxTree, dop_bounds

        self.X = np.ascontiguousarray(X, dtype=np.int64)
        self.g, self.negate = g, negate
        self.flat = self.X.reshape(-1, 9)
        self.flat_f = self.flat.astype(np.float64)
        self.normals = _primitive_normals(-self.X if negate else self.X)
        self.raw = np.cross(self.X[:, 1] - self.X[:, 0],
                            self.X[:, 2] - self.X[:, 0]).astype(np.float64).ravel()
        lo, hi, D = dop_bounds(-self.X if negate else self.X, g)
        if k is not None and k < len(D):
            lo, hi, D = lo[:, :k], hi[:, :k], D[:k]
        self.directions = D
        self.tree = BoxTree(lo, hi)

    def on(self, k: int) -> "_Side":
        """This side on the first ``k`` directions only."""
        return self if len(self.directions) == k else _Side(self.X, self.g, self.negate, k)

    @property
    def nbytes(self) -> int:
        t = self.tree
        return (self.X.nbytes + self.flat_f.nbytes + self.normals.nbytes + self.raw.nbytes
                + sum(a.nbytes for a in (t.lo, t.hi, t.first, t.count, t.order, t.box_lo,
                                         t.box_hi)))


# Sides alive anywhere, by content: a build's bodies share the robot's, and the orientation
# slices of one grid share each body's (weak: a side lives while an engine holds it).
_SIDES: "weakref.WeakValueDictionary" = weakref.WeakValueDictionary()


def _side(X: np.ndarray, g: np.ndarray, negate: bool) -> _Side:
    """The :class:`_Side` of ``X`` (made once per content; equal bytes are equal operands)."""
    X = np.ascontiguousarray(X, dtype=np.int64)
    key = (X.shape, hashlib.blake2b(X.tobytes(), digest_size=20).digest(),
           tuple(int(x) for x in g), bool(negate))
    side = _SIDES.get(key)
    if side is None or not np.array_equal(side.X, X):
        side = _SIDES[key] = _Side(X, g, negate)
    return side
