# cython: language_level=3, boundscheck=False, wraparound=False, cdivision=True, initializedcheck=False
"""Compiled kernels of :class:`cspace.geometry.boxes.BoxTree`: building the tree, and one tree's
box queries (:class:`BoxIndex`).

:func:`build` is the median split of :func:`cspace.geometry.boxes._tree_reference` step for step
(the same quickselect, so the same tree; ``tests/test_kernels.py`` holds them identical): each
node's bounds are the minimum and maximum of its items' over every column, an inner node's
items are split at the median of their box centres along the node's longest axis (ties to the
lowest axis), at most ``leaf`` items a leaf. Bounds are only compared and copied: exact.
"""

import numpy as np

from libc.stdint cimport int64_t

cdef int _STACK = 512


cdef void _select(int64_t* idx, Py_ssize_t n, Py_ssize_t k, const double[:, ::1] key,
                  int axis) noexcept nogil:
    """Reorder ``idx[0:n]`` so that ``idx[k]`` has the k-th smallest ``key[., axis]``, none
    after it smaller and none before it larger (Hoare's selection, median-of-three pivot)."""
    cdef Py_ssize_t left = 0, right = n - 1, i, j, m
    cdef double a, b, c, pivot
    cdef int64_t t
    while right > left:
        m = left + (right - left) // 2
        a, b, c = key[idx[left], axis], key[idx[m], axis], key[idx[right], axis]
        if a > b:
            a, b = b, a
        if b > c:
            b = c
            if a > b:
                b = a
        pivot = b
        i, j = left, right
        while i <= j:
            while key[idx[i], axis] < pivot:
                i += 1
            while key[idx[j], axis] > pivot:
                j -= 1
            if i <= j:
                t = idx[i]
                idx[i] = idx[j]
                idx[j] = t
                i += 1
                j -= 1
        if k <= j:
            right = j
        elif k >= i:
            left = i
        else:
            return


def build(const double[:, ::1] lo, const double[:, ::1] hi, int leaf):
    """``(order, node_lo, node_hi, first, count)`` of the tree over the items' bounds ``lo, hi
    (n, k)`` (``k >= 3``, the first three the axes), as :class:`BoxTree` holds them."""
    cdef Py_ssize_t n = lo.shape[0], K = lo.shape[1], node, a, b, half, x, c, nodes = 1
    cdef int top, axis
    cdef double ext, best
    cdef Py_ssize_t st_node[512]
    cdef Py_ssize_t st_a[512]
    cdef Py_ssize_t st_b[512]
    order_arr = np.arange(n, dtype=np.int64)
    centre_arr = np.asarray(lo[:, :3]) + np.asarray(hi[:, :3])
    nlo_arr = np.empty((max(2 * n, 1), K))
    nhi_arr = np.empty((max(2 * n, 1), K))
    first_arr = np.zeros(max(2 * n, 1), dtype=np.int64)
    count_arr = np.zeros(max(2 * n, 1), dtype=np.int64)
    cdef int64_t[::1] order = order_arr
    cdef const double[:, ::1] centre = centre_arr
    cdef double[:, ::1] nlo = nlo_arr
    cdef double[:, ::1] nhi = nhi_arr
    cdef int64_t[::1] first = first_arr
    cdef int64_t[::1] count = count_arr
    if leaf < 1:
        raise ValueError("a leaf holds at least one item")
    st_node[0], st_a[0], st_b[0] = 0, 0, n
    top = 1
    while top > 0:
        top -= 1
        node, a, b = st_node[top], st_a[top], st_b[top]
        for c in range(K):
            nlo[node, c] = lo[order[a], c]
            nhi[node, c] = hi[order[a], c]
        for x in range(a + 1, b):
            for c in range(K):
                if lo[order[x], c] < nlo[node, c]:
                    nlo[node, c] = lo[order[x], c]
                if hi[order[x], c] > nhi[node, c]:
                    nhi[node, c] = hi[order[x], c]
        if b - a <= leaf:
            first[node], count[node] = a, b - a
            continue
        axis, best = 0, nhi[node, 0] - nlo[node, 0]
        for c in range(1, 3):
            ext = nhi[node, c] - nlo[node, c]
            if ext > best:
                axis, best = c, ext
        half = (b - a) // 2
        _select(&order[a], b - a, half, centre, axis)
        first[node] = nodes
        if top + 2 > _STACK:
            raise RuntimeError("box tree deeper than the build stack")
        st_node[top], st_a[top], st_b[top] = nodes, a, a + half
        st_node[top + 1], st_a[top + 1], st_b[top + 1] = nodes + 1, a + half, b
        top += 2
        nodes += 2
    return (order_arr, nlo_arr[:nodes].copy(), nhi_arr[:nodes].copy(), first_arr[:nodes].copy(),
            count_arr[:nodes].copy())


cdef class BoxIndex:
    """Queries on one :class:`cspace.geometry.boxes.BoxTree` (its first three columns, the
    axes): which items' closed boxes meet a query box. The broad phase of a C-space's union
    (float comparisons of the stored bounds against the query, no arithmetic: exact)."""

    cdef const double[:, ::1] lo
    cdef const double[:, ::1] hi
    cdef const double[:, ::1] blo
    cdef const double[:, ::1] bhi
    cdef const int64_t[::1] first
    cdef const int64_t[::1] count
    cdef const int64_t[::1] order
    cdef object _keep

    def __init__(self, tree):
        self._keep = tree
        self.lo, self.hi, self.first, self.count, self.order = (
            tree.lo, tree.hi, tree.first, tree.count, tree.order)
        self.blo, self.bhi = tree.box_lo, tree.box_hi

    cdef inline bint _meets(self, const double* lo, const double* hi, const double* qlo,
                            const double* qhi) noexcept nogil:
        return not (lo[0] > qhi[0] or lo[1] > qhi[1] or lo[2] > qhi[2]
                    or qlo[0] > hi[0] or qlo[1] > hi[1] or qlo[2] > hi[2])

    cdef int _collect(self, const double* qlo, const double* qhi, list out) except -1:
        cdef int stack[512]
        cdef int top = 1, a
        cdef Py_ssize_t x, i
        stack[0] = 0
        while top > 0:
            top -= 1
            a = stack[top]
            if not self._meets(&self.lo[a, 0], &self.hi[a, 0], qlo, qhi):
                continue
            if self.count[a] > 0:
                for x in range(self.first[a], self.first[a] + self.count[a]):
                    i = self.order[x]
                    if self._meets(&self.blo[i, 0], &self.bhi[i, 0], qlo, qhi):
                        out.append(i)
                continue
            if top + 2 > _STACK:
                raise RuntimeError("box tree deeper than the traversal stack")
            stack[top], stack[top + 1] = self.first[a] + 1, self.first[a]
            top += 2
        return 0

    def point(self, double x, double y, double z):
        """The items whose box holds the point, as a list."""
        cdef double q[3]
        q[0], q[1], q[2] = x, y, z
        out = []
        self._collect(q, q, out)
        return out

    def box(self, double x0, double y0, double z0, double x1, double y1, double z1):
        """The items whose box meets the box ``[(x0, y0, z0), (x1, y1, z1)]``, as a list."""
        cdef double lo[3]
        cdef double hi[3]
        lo[0], lo[1], lo[2], hi[0], hi[1], hi[2] = x0, y0, z0, x1, y1, z1
        out = []
        self._collect(lo, hi, out)
        return out

    def overlaps(self, const double[:, ::1] qlo, const double[:, ::1] qhi):
        """``(rows, items)`` int64: every query row and item whose boxes meet."""
        cdef Py_ssize_t r, n0
        rows, items = [], []
        cdef list found
        for r in range(qlo.shape[0]):
            found = []
            self._collect(&qlo[r, 0], &qhi[r, 0], found)
            if found:
                items += found
                rows += [r] * len(found)
        return np.array(rows, dtype=np.int64), np.array(items, dtype=np.int64)
