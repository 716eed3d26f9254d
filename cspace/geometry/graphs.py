"""Connected components and breadth-first trees of small undirected graphs given as edge lists.

One place for graph routines: connected components and breadth-first trees compiled
(:mod:`cspace.geometry._kernels.graph`), their references by scipy's sparse routines, imported
only by the references: a first mesh validation in a fresh process does not pay for importing
``scipy.sparse.csgraph`` (0.1-0.25 s, more than a whole small Minkowski sum).
"""

from __future__ import annotations

import numpy as np

__all__ = ["component_labels", "bfs_predecessors"]


def _graph(n: int, a, b):
    from scipy.sparse import coo_matrix

    a = np.asarray(a, dtype=np.int64).reshape(-1)
    b = np.asarray(b, dtype=np.int64).reshape(-1)
    # float weights: repeated edges add up without wrapping (int8 would at 256 repeats)
    return coo_matrix((np.ones(len(a)), (a, b)), shape=(n, n)).tocsr()


def component_labels(n: int, a, b) -> tuple[int, np.ndarray]:
    """``(count, labels)``: the connected components of the undirected graph on ``n`` nodes
    with edges ``a[k] -- b[k]`` (labels ``(n,)`` int32 in ``[0, count)``, numbered in the
    order of each component's lowest node).

    Compiled union-find (:mod:`cspace.geometry._kernels.graph`); the reference is scipy's
    ``connected_components`` (:func:`_component_labels_reference`), identical labels."""
    from ._kernels import load

    out = load("graph").component_labels(
        int(n), np.ascontiguousarray(np.asarray(a, dtype=np.int64).reshape(-1)),
        np.ascontiguousarray(np.asarray(b, dtype=np.int64).reshape(-1)))
    return out if out is not None else _component_labels_reference(n, a, b)


def _component_labels_reference(n: int, a, b) -> tuple[int, np.ndarray]:
    """:func:`component_labels` by scipy's sparse ``connected_components``."""
    from scipy.sparse.csgraph import connected_components

    count, labels = connected_components(_graph(n, a, b), directed=False)
    return int(count), labels


def _adjacency(n: int, a, b) -> tuple[np.ndarray, np.ndarray]:
    """``(indptr, indices)``: each node's neighbours in the order scipy's undirected
    breadth-first search visits them: the distinct ``b`` of its edges ``v -- b`` ascending
    (its row of the CSR matrix), then the distinct ``a`` of its edges ``a -- v`` ascending
    (its row of the transpose)."""
    a = np.asarray(a, dtype=np.int64).reshape(-1)
    b = np.asarray(b, dtype=np.int64).reshape(-1)
    # rows: (node, part 0 = out-neighbours / 1 = in-neighbours, neighbour), distinct, sorted
    rows = np.unique(np.stack([np.concatenate([a, b]),
                               np.repeat([0, 1], len(a)),
                               np.concatenate([b, a])], axis=1), axis=0)
    indptr = np.zeros(n + 1, dtype=np.int64)
    np.cumsum(np.bincount(rows[:, 0], minlength=n), out=indptr[1:])
    return indptr, np.ascontiguousarray(rows[:, 2])


def bfs_predecessors(n: int, a, b, start: int) -> np.ndarray:
    """``(n,)`` predecessor of each node in a breadth-first tree from ``start`` over the
    undirected edges ``a[k] -- b[k]`` (-9999 for ``start`` and unreached nodes).

    Compiled (:mod:`cspace.geometry._kernels.graph`); the reference is scipy's
    ``breadth_first_order`` (:func:`_bfs_predecessors_reference`), identical trees."""
    from ._kernels import load

    a = np.asarray(a, dtype=np.int64).reshape(-1)
    b = np.asarray(b, dtype=np.int64).reshape(-1)
    if len(a) and not (0 <= min(a.min(), b.min()) and max(a.max(), b.max()) < n):
        return _bfs_predecessors_reference(n, a, b, start)
    indptr, indices = _adjacency(n, a, b)
    out = load("graph").bfs_predecessors(int(n), indptr, indices, int(start))
    return out if out is not None else _bfs_predecessors_reference(n, a, b, start)


def _bfs_predecessors_reference(n: int, a, b, start: int) -> np.ndarray:
    """:func:`bfs_predecessors` by scipy's sparse ``breadth_first_order``."""
    from scipy.sparse.csgraph import breadth_first_order

    _, pred = breadth_first_order(_graph(n, a, b), start, directed=False,
                                  return_predecessors=True)
    return pred
