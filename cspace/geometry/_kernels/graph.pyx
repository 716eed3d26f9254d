# cython: language_level=3, boundscheck=False, wraparound=False, cdivision=True, initializedcheck=False
"""Compiled kernel of :func:`cspace.geometry.graphs.component_labels`: connected components of
an undirected graph by union-find, labelled as scipy's ``connected_components`` labels them
(in the order of each component's lowest node), so that the two are identical
(``tests/test_kernels.py``). Integers only: exact."""

import numpy as np

from libc.stdint cimport int64_t


cdef inline int64_t _root(int64_t* parent, int64_t x) noexcept nogil:
    cdef int64_t r = x, t
    while parent[r] != r:
        r = parent[r]
    while parent[x] != r:  # path compression
        t = parent[x]
        parent[x] = r
        x = t
    return r


def component_labels(Py_ssize_t n, const int64_t[::1] a, const int64_t[::1] b):
    """``(count, labels)`` of the graph on ``n`` nodes with edges ``a[k] -- b[k]``; None when
    an edge names a node outside ``[0, n)`` (the caller's reference then raises)."""
    cdef Py_ssize_t k, i, m = a.shape[0]
    cdef int64_t ra, rb, count = 0
    parent_arr = np.arange(n, dtype=np.int64)
    labels_arr = np.full(n, -1, dtype=np.int32)
    cdef int64_t[::1] parent = parent_arr
    cdef int[::1] labels = labels_arr
    if b.shape[0] != m:
        return None
    for k in range(m):
        if not (0 <= a[k] < n and 0 <= b[k] < n):
            return None
    with nogil:
        for k in range(m):
            ra = _root(&parent[0], a[k])
            rb = _root(&parent[0], b[k])
            if ra != rb:
                if ra < rb:
                    parent[rb] = ra
                else:
                    parent[ra] = rb
        # every root is its component's lowest node: number them in node order
        for i in range(n):
            ra = _root(&parent[0], i)
            if labels[ra] < 0:
                labels[ra] = count
                count += 1
            labels[i] = labels[ra]
    return int(count), labels_arr


def bfs_predecessors(Py_ssize_t n, const int64_t[::1] indptr, const int64_t[::1] indices,
                     Py_ssize_t start):
    """``(n,)`` int32 predecessor of each node in the breadth-first tree from ``start`` over
    the adjacency ``indices[indptr[v]:indptr[v + 1]]`` of each node ``v``, in that order
    (-9999 for ``start`` and unreached nodes, as scipy's ``breadth_first_order``)."""
    cdef Py_ssize_t head = 0, tail = 1, k
    cdef int64_t v, w
    pred_arr = np.full(n, -9999, dtype=np.int32)
    queue_arr = np.zeros(max(n, 1), dtype=np.int64)
    seen_arr = np.zeros(n, dtype=np.uint8)
    cdef int[::1] pred = pred_arr
    cdef int64_t[::1] queue = queue_arr
    cdef unsigned char[::1] seen = seen_arr
    if not 0 <= start < n:
        return None
    queue[0] = start
    seen[start] = 1
    with nogil:
        while head < tail:
            v = queue[head]
            head += 1
            for k in range(indptr[v], indptr[v + 1]):
                w = indices[k]
                if not seen[w]:
                    seen[w] = 1
                    pred[w] = <int>v
                    queue[tail] = w
                    tail += 1
    return pred_arr
