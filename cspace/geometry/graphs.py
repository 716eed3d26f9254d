"""Connected components and breadth-first trees of small undirected graphs given as edge lists.

One place for graph routines: connected components compiled (:mod:`cspace.geometry._kernels.graph`),
breadth-first trees and the components' reference by scipy's sparse routines, imported on first
use: ``import cspace`` does not pay for ``scipy.sparse`` (about 0.12 s) until a mesh is oriented.
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


def bfs_predecessors(n: int, a, b, start: int) -> np.ndarray:
    """``(n,)`` predecessor of each node in a breadth-first tree from ``start`` over the
    undirected edges ``a[k] -- b[k]`` (-9999 for ``start`` and unreached nodes)."""
    from scipy.sparse.csgraph import breadth_first_order

    _, pred = breadth_first_order(_graph(n, a, b), start, directed=False,
                                  return_predecessors=True)
    return pred
