# cython: language_level=3, boundscheck=False, wraparound=False, cdivision=True, initializedcheck=False
"""Compiled convex polytopes: the polytope a convex mesh bounds, and CVMS (the facets of the
exact Minkowski sum of two convex polytopes), each in one call.

:func:`facets` is :func:`cspace.minkowski.cvms._convex_minkowski_sum_reference` step for step
(the same facets, in the same order, with the same labels and provenance;
``tests/test_kernels.py`` holds them identical): supports of each operand's facet normals
among the other's vertices, the facet normals of both merged in lexicographic order, the
translated, corner and planar-sum facets, the edge facets of crossing Gauss arcs, and the
vertex labels (sorted ``(a, b)`` codes).

Exactness: every decision is an integer computation in ``__int128``, without rounding, within
the range the caller checks: ``|coordinate| < 2**40`` and ``|normal component| < 2**61``, so a
dot product is below ``3 * 2**101`` and a 2D turn below ``2**83``. An edge facet's normal is
the cross product of two edge vectors (below ``2**82``, in ``__int128``) divided by its
components' gcd; the result must fit int64 (the reference's range check: twice the largest
selected edge coordinates' product below ``2**61``), else :func:`facets` returns None and the
caller runs the reference, which raises the same named error.

:func:`polytope_of_mesh` proves a closed mesh exactly convex and returns its polytope as
``ConvexPolytope.from_ints`` makes it (its own range, ``|coordinate| < 2**30``, and its proof
are in its docstring); the reference is ``cspace.mesh.closed.ClosedMesh`` then
``cspace.mesh.convex.convex_within_bound``. :func:`hull_of_points` proposes the hull of a point
set incrementally and leaves the proof to :func:`polytope_of_mesh`; its reference is the exact
wrap, ``ConvexPolytope.from_ints(..., method='wrap')``.
"""

import numpy as np

from libc.stdint cimport int64_t, uint8_t
from libc.stdlib cimport malloc, realloc, free, qsort

cdef extern from *:
    """
    typedef __int128 cs_cvms_i128;
    """
    # Cython sees it as a 64-bit type; it is only ever used in C arithmetic here.
    ctypedef long long i128 "cs_cvms_i128"


# --------------------------------------------------------------------------------------------
# growable int64 buffers

cdef struct Buf:
    int64_t* data
    Py_ssize_t n
    Py_ssize_t cap


cdef int _push(Buf* b, int64_t x) except -1:
    cdef int64_t* grown
    if b.n == b.cap:
        b.cap = 2 * b.cap + 16
        grown = <int64_t*> realloc(b.data, b.cap * sizeof(int64_t))
        if grown == NULL:
            raise MemoryError()
        b.data = grown
    b.data[b.n] = x
    b.n += 1
    return 0


cdef object _array(Buf* b):
    out = np.empty(b.n, dtype=np.int64)
    cdef int64_t[::1] o = out
    cdef Py_ssize_t i
    for i in range(b.n):
        o[i] = b.data[i]
    return out


# --------------------------------------------------------------------------------------------
# stable merge sort of indices by integer keys (lexicographic over ``nk`` columns)

cdef inline int _cmp(const int64_t* keys, int nk, int64_t a, int64_t b) noexcept nogil:
    cdef int c
    cdef int64_t x, y
    for c in range(nk):
        x = keys[a * nk + c]
        y = keys[b * nk + c]
        if x < y:
            return -1
        if x > y:
            return 1
    return 0


cdef void _msort(int64_t* idx, int64_t* tmp, Py_ssize_t n, const int64_t* keys,
                 int nk) noexcept nogil:
    """Bottom-up merge sort: equal keys keep their order (as Python's ``sorted``)."""
    cdef Py_ssize_t width = 1, lo, mid, hi, i, j, k
    cdef int64_t* src = idx
    cdef int64_t* dst = tmp
    cdef int64_t* t
    while width < n:
        lo = 0
        while lo < n:
            mid = lo + width if lo + width < n else n
            hi = lo + 2 * width if lo + 2 * width < n else n
            i, j, k = lo, mid, lo
            while i < mid and j < hi:
                if _cmp(keys, nk, src[j], src[i]) < 0:
                    dst[k] = src[j]
                    j += 1
                else:
                    dst[k] = src[i]
                    i += 1
                k += 1
            while i < mid:
                dst[k] = src[i]
                i += 1
                k += 1
            while j < hi:
                dst[k] = src[j]
                j += 1
                k += 1
            lo = hi
        t = src
        src = dst
        dst = t
        width *= 2
    if src != idx:
        for i in range(n):
            idx[i] = src[i]


cdef inline Py_ssize_t _last_at_most(const int64_t* a, Py_ssize_t n, int64_t x) noexcept nogil:
    """In sorted ``a[0:n]`` (n > 0), the last index whose value is at most ``x`` (0 if none)."""
    cdef Py_ssize_t lo = 0, hi = n, mid
    while hi - lo > 1:
        mid = (lo + hi) // 2
        if a[mid] <= x:
            lo = mid
        else:
            hi = mid
    return lo


cdef int _cmp64(const void* a, const void* b) noexcept nogil:
    cdef int64_t x = (<const int64_t*> a)[0], y = (<const int64_t*> b)[0]
    return (x > y) - (x < y)


# --------------------------------------------------------------------------------------------
# exact helpers

# The range in which every product below fits __int128 (see the module's docstring).
cdef int64_t COORD = 1LL << 40
cdef int64_t NORMAL = 1LL << 61


cdef bint _within(const int64_t[:, ::1] X, int64_t bound) noexcept nogil:
    cdef Py_ssize_t i, c
    for i in range(X.shape[0]):
        for c in range(X.shape[1]):
            if not (-bound < X[i, c] < bound):
                return False
    return True

cdef inline int _sign128(i128 v) noexcept nogil:
    return (v > 0) - (v < 0)


cdef inline i128 _dot(const int64_t* u, const int64_t* v) noexcept nogil:
    return <i128> u[0] * v[0] + <i128> u[1] * v[1] + <i128> u[2] * v[2]


cdef inline int64_t _gcd(int64_t a, int64_t b) noexcept nogil:
    if a < 0:
        a = -a
    if b < 0:
        b = -b
    while b:
        a, b = b, a % b
    return a


cdef void _support(const int64_t[:, ::1] P, const int64_t[:, ::1] D, uint8_t* mask,
                   int64_t* count, int64_t* first) noexcept nogil:
    """``mask[j, i]``: point ``i`` maximises ``<p, D[j]>`` (exact); per direction the number
    of maximisers and the first."""
    cdef Py_ssize_t n = P.shape[0], m = D.shape[0], i, j
    cdef i128 best, v
    for j in range(m):
        best = _dot(&P[0, 0], &D[j, 0])
        for i in range(1, n):
            v = _dot(&P[i, 0], &D[j, 0])
            if v > best:
                best = v
        count[j] = 0
        first[j] = -1
        for i in range(n):
            v = _dot(&P[i, 0], &D[j, 0])
            mask[j * n + i] = v == best
            if v == best:
                count[j] += 1
                if first[j] < 0:
                    first[j] = i


cdef inline i128 _turn(const int64_t* xy, int64_t o, int64_t a, int64_t b) noexcept nogil:
    """Twice the signed area of the 2D triangle ``(o, a, b)`` (exact: below ``2**83``)."""
    return ((<i128> xy[2 * a] - xy[2 * o]) * (<i128> xy[2 * b + 1] - xy[2 * o + 1])
            - (<i128> xy[2 * a + 1] - xy[2 * o + 1]) * (<i128> xy[2 * b] - xy[2 * o]))


cdef inline Py_ssize_t _chain(const int64_t* xy, int64_t* out, Py_ssize_t h, Py_ssize_t base,
                              int64_t p) noexcept nogil:
    """Append point ``p`` to the chain ``out[base:h]`` after dropping its last points while
    they do not turn left (collinear ones too); the chain's new end."""
    while h - base >= 2 and _turn(xy, out[h - 2], out[h - 1], p) <= 0:
        h -= 1
    out[h] = p
    return h + 1


cdef int _hull2d(const int64_t* xy, Py_ssize_t n, int64_t* out, int64_t* idx,
                 int64_t* tmp) noexcept nogil:
    """Strictly convex hull of 2D integer points ``xy`` (interleaved), counter-clockwise, as
    indices: :func:`cspace.mesh.convex._hull2d` (stable sort, first of duplicates, monotone
    chain dropping collinear points). Returns the count; ``out`` holds up to ``2 n``."""
    cdef Py_ssize_t i, m = 0, h, k
    for i in range(n):
        idx[i] = i
    _msort(idx, tmp, n, xy, 2)
    # drop exact duplicates, keep the first
    for i in range(n):
        if m == 0 or xy[2 * idx[i]] != xy[2 * tmp[m - 1]] or xy[2 * idx[i] + 1] != xy[2 * tmp[m - 1] + 1]:
            tmp[m] = idx[i]
            m += 1
    if m < 3:
        for i in range(m):
            out[i] = tmp[i]
        return <int> m
    h = 0
    for i in range(m):  # lower chain
        h = _chain(xy, out, h, 0, tmp[i])
    k = h - 1  # upper chain: from the lower one's last point (never popped), the rest reversed
    for i in range(m - 2, -1, -1):
        h = _chain(xy, out, h, k, tmp[i])
    return <int> (h - 1)


cdef void _feature(const uint8_t* supp, Py_ssize_t n, const int64_t[:, ::1] edges,
                   const int64_t[::1] f_off, const int64_t[::1] f_idx,
                   int64_t* dim, int64_t* index) noexcept nogil:
    """``(dimension, index)`` of the face spanned by the support mask (as ``cvms._feature``):
    a vertex, an edge of ``edges`` (either way round) or the facet with that vertex set."""
    cdef Py_ssize_t i, c = 0, e, f, first = -1, second = -1, ok
    for i in range(n):
        if supp[i]:
            c += 1
            if first < 0:
                first = i
            elif second < 0:
                second = i
    if c == 1:
        dim[0], index[0] = 0, first
        return
    if c == 2:
        for e in range(edges.shape[0]):
            if ((edges[e, 0] == first and edges[e, 1] == second)
                    or (edges[e, 0] == second and edges[e, 1] == first)):
                dim[0], index[0] = 1, e
                return
        dim[0], index[0] = 1, -1
        return
    index[0] = -1
    for f in range(f_off.shape[0] - 1):
        if f_off[f + 1] - f_off[f] != c:
            continue
        ok = 1
        for i in range(f_off[f], f_off[f + 1]):
            if not supp[f_idx[i]]:
                ok = 0
                break
        if ok:
            index[0] = f  # the reference's dict keeps the last facet of a vertex set
    dim[0] = 2


cdef uint8_t* _on_facet(int64_t other, uint8_t* S, Py_ssize_t n, int64_t own,
                        const int64_t[::1] off, const int64_t[::1] idx, uint8_t[::1] mask):
    """One operand's vertices on a planar-sum facet: its support in the direction of the
    other operand's facet ``other`` (row ``other`` of ``S``), else the vertices of its own
    facet ``own`` (marked in ``mask``)."""
    cdef Py_ssize_t i
    if other >= 0:
        return S + other * n
    mask[:] = 0
    for i in range(off[own], off[own + 1]):
        mask[idx[i]] = 1
    return &mask[0]


cdef int _moved_facets(Out* o, Py_ssize_t nu, const int64_t* own, const int64_t* other,
                       const int64_t* cnt, const int64_t* at, const int64_t[::1] off,
                       const int64_t[::1] idx, const int64_t[:, ::1] normals, Buf* mine,
                       Buf* theirs, int corner) except -1:
    """The facets of one operand (``own`` per distinct normal) that the other meets at one
    vertex (``cnt == 1``: ``at``), moved there: translated facets (A's) or corner facets
    (B's, ``corner``), in the normals' order."""
    cdef Py_ssize_t k, i
    cdef int64_t f
    for k in range(nu):
        f = own[k]
        if f >= 0 and other[k] < 0 and cnt[f] == 1:
            for i in range(off[f], off[f + 1]):
                _push(mine, idx[i])
                _push(theirs, at[f])
            _push(&o.size, off[f + 1] - off[f])
            if corner:
                _facet(o, normals[f, 0], normals[f, 1], normals[f, 2], 0, at[f], 2, f)
            else:
                _facet(o, normals[f, 0], normals[f, 1], normals[f, 2], 2, f, 0, at[f])
    return 0


cdef Py_ssize_t _live(const int64_t[:, ::1] ef, const int64_t* cnt, const int64_t* at,
                      int64_t* out) noexcept nogil:
    """The edges whose Gauss arc can cross the other operand's: not both facets met at one
    and the same vertex of the other. Their indices in ``out``; their count."""
    cdef Py_ssize_t i, n = 0
    for i in range(ef.shape[0]):
        if not (cnt[ef[i, 0]] == 1 and cnt[ef[i, 1]] == 1 and at[ef[i, 0]] == at[ef[i, 1]]):
            out[n] = i
            n += 1
    return n


# --------------------------------------------------------------------------------------------
# the sum's facets

cdef struct Out:
    Buf fa
    Buf fb
    Buf size
    Buf normal
    Buf src_a
    Buf src_b


cdef int _facet(Out* o, int64_t n0, int64_t n1, int64_t n2, int64_t da, int64_t ia,
                int64_t db, int64_t ib) except -1:
    _push(&o.normal, n0)
    _push(&o.normal, n1)
    _push(&o.normal, n2)
    _push(&o.src_a, da)
    _push(&o.src_a, ia)
    _push(&o.src_b, db)
    _push(&o.src_b, ib)
    return 0


def facets(const int64_t[:, ::1] A, const int64_t[::1] a_off, const int64_t[::1] a_idx,
           const int64_t[:, ::1] nA, const int64_t[:, ::1] a_edges, const int64_t[:, ::1] a_ef,
           const int64_t[:, ::1] B, const int64_t[::1] b_off, const int64_t[::1] b_idx,
           const int64_t[:, ::1] nB, const int64_t[:, ::1] b_edges, const int64_t[:, ::1] b_ef):
    """The facets of ``A ⊕ B`` from both polytopes' arrays (vertices, CSR facets, normals,
    edges, edge facets): ``(labels (n, 2), offsets, flat, normals (f, 3), source_a (f, 2),
    source_b (f, 2), edges (e, 2), edge_facets (e, 2))``, or None outside the kernel's range
    (coordinates, normals, an edge facet's normal) or when the facets do not close up (the
    caller then runs the reference, which answers or raises the named error)."""
    if not (_within(A, COORD) and _within(B, COORD) and _within(nA, NORMAL)
            and _within(nB, NORMAL)):
        return None
    cdef Py_ssize_t vA = A.shape[0], vB = B.shape[0], fA = nA.shape[0], fB = nB.shape[0]
    cdef Py_ssize_t eA = a_edges.shape[0], eB = b_edges.shape[0]
    cdef Py_ssize_t nc = fA + fB, i, j, k, c, m, h, r, nu, la, lb, p, q, na, nb, most
    cdef int64_t d1, i1, d2, i2
    cdef Out o
    cdef int axis
    o.fa = Buf(NULL, 0, 0)
    o.fb = Buf(NULL, 0, 0)
    o.size = Buf(NULL, 0, 0)
    o.normal = Buf(NULL, 0, 0)
    o.src_a = Buf(NULL, 0, 0)
    o.src_b = Buf(NULL, 0, 0)
    SB_arr = np.empty(max(fA * vB, 1), dtype=np.uint8)
    SA_arr = np.empty(max(fB * vA, 1), dtype=np.uint8)
    cdef uint8_t[::1] SB = SB_arr, SA = SA_arr
    work = np.empty(11 * nc + eA + eB + 8, dtype=np.int64)
    cdef int64_t[::1] w = work
    cdef int64_t* cnt_b = &w[0]
    cdef int64_t* b_of = cnt_b + fA
    cdef int64_t* cnt_a = b_of + fA
    cdef int64_t* a_of = cnt_a + fB
    cdef int64_t* order = a_of + fB
    cdef int64_t* tmp = order + nc
    cdef int64_t* keys = tmp + nc          # 3 per candidate normal
    cdef int64_t* owner_a = keys + 3 * nc   # per distinct normal
    cdef int64_t* owner_b = owner_a + nc
    cdef int64_t* ukey = owner_b + nc       # the distinct normal's first candidate
    cdef int64_t* planar = ukey + nc
    cdef int64_t* ia = planar + nc          # live A edges
    cdef int64_t* ib = ia + eA              # live B edges
    cdef int64_t* xy = NULL                 # per planar facet: its candidate points, ...
    cdef int64_t* pa = NULL
    cdef int64_t* pb = NULL
    cdef int64_t* ring = NULL
    cdef int64_t* hidx = NULL
    cdef int64_t* htmp = NULL
    cdef int64_t[::1] pw
    cdef uint8_t* supp_a
    cdef uint8_t* supp_b
    cdef const int64_t* key
    fa_mask = np.zeros(max(vA, 1), dtype=np.uint8)
    fb_mask = np.zeros(max(vB, 1), dtype=np.uint8)
    cdef uint8_t[::1] fam = fa_mask, fbm = fb_mask
    cdef signed char[:, ::1] T
    try:
        _support(B, nA, &SB[0] if fA * vB else NULL, cnt_b, b_of)
        _support(A, nB, &SA[0] if fB * vA else NULL, cnt_a, a_of)
        # the candidate normals, sorted; one key per distinct normal with its owners
        for i in range(fA):
            keys[3 * i], keys[3 * i + 1], keys[3 * i + 2] = nA[i, 0], nA[i, 1], nA[i, 2]
        for i in range(fB):
            keys[3 * (fA + i)], keys[3 * (fA + i) + 1], keys[3 * (fA + i) + 2] = nB[i, 0], nB[i, 1], nB[i, 2]
        for i in range(nc):
            order[i] = i
        _msort(order, tmp, nc, keys, 3)
        nu = 0
        for i in range(nc):
            c = order[i]
            if nu == 0 or _cmp(keys, 3, c, ukey[nu - 1]) != 0:
                ukey[nu] = c
                owner_a[nu] = -1
                owner_b[nu] = -1
                nu += 1
            if c < fA:
                owner_a[nu - 1] = c
            else:
                owner_b[nu - 1] = c - fA
        # translated facets: an A facet moved by its one contributing B vertex; then corner
        # facets: a B facet placed at its one contributing A vertex
        _moved_facets(&o, nu, owner_a, owner_b, cnt_b, b_of, a_off, a_idx, nA, &o.fa, &o.fb, 0)
        _moved_facets(&o, nu, owner_b, owner_a, cnt_a, a_of, b_off, b_idx, nB, &o.fb, &o.fa, 1)
        # planar sums: shared normals, then A's and B's facets with several contributors
        m = 0
        for k in range(nu):
            if owner_a[k] >= 0 and owner_b[k] >= 0:
                planar[m] = k
                m += 1
        for k in range(nu):
            if owner_a[k] >= 0 and owner_b[k] < 0 and cnt_b[owner_a[k]] != 1:
                planar[m] = k
                m += 1
        for k in range(nu):
            if owner_b[k] >= 0 and owner_a[k] < 0 and cnt_a[owner_b[k]] != 1:
                planar[m] = k
                m += 1
        # room for the largest planar facet's candidate points (support sizes' product)
        most = 0
        for r in range(m):
            k = planar[r]
            na = cnt_a[owner_b[k]] if owner_b[k] >= 0 else a_off[owner_a[k] + 1] - a_off[owner_a[k]]
            nb = cnt_b[owner_a[k]] if owner_a[k] >= 0 else b_off[owner_b[k] + 1] - b_off[owner_b[k]]
            if na * nb > most:
                most = na * nb
        points = np.empty(8 * most + 8, dtype=np.int64)
        pw = points
        xy = &pw[0]
        pa = xy + 2 * most
        pb = pa + most
        ring = pb + most
        hidx = ring + 2 * most
        htmp = hidx + most
        for r in range(m):
            k = planar[r]
            supp_a = _on_facet(owner_b[k], &SA[0], vA, owner_a[k], a_off, a_idx, fam)
            supp_b = _on_facet(owner_a[k], &SB[0], vB, owner_b[k], b_off, b_idx, fbm)
            key = &keys[3 * ukey[k]]
            axis = 0
            for c in range(1, 3):
                if (key[c] if key[c] >= 0 else -key[c]) > (key[axis] if key[axis] >= 0 else -key[axis]):
                    axis = c
            p = 0
            for i in range(vA):
                if not supp_a[i]:
                    continue
                for j in range(vB):
                    if not supp_b[j]:
                        continue
                    pa[p], pb[p] = i, j
                    xy[2 * p] = A[i, (axis + 1) % 3] + B[j, (axis + 1) % 3]
                    xy[2 * p + 1] = A[i, (axis + 2) % 3] + B[j, (axis + 2) % 3]
                    p += 1
            h = _hull2d(xy, p, ring, hidx, htmp)
            for i in range(h):
                q = ring[i] if key[axis] > 0 else ring[h - 1 - i]
                _push(&o.fa, pa[q])
                _push(&o.fb, pb[q])
            _push(&o.size, h)
            _feature(supp_a, vA, a_edges, a_off, a_idx, &d1, &i1)
            _feature(supp_b, vB, b_edges, b_off, b_idx, &d2, &i2)
            _facet(&o, key[0], key[1], key[2], d1, i1, d2, i2)
        # edge facets: pairs of edges whose Gauss arcs cross inside both
        la = _live(a_ef, cnt_b, b_of, ia)
        lb = _live(b_ef, cnt_a, a_of, ib)
        T = np.empty((max(la, 1), max(fB, 1)), dtype=np.int8)
        return _edge_facets(&o, A, B, nA, nB, a_edges, b_edges, a_ef, b_ef, ia, la, ib, lb, T,
                            np.empty((max(la, 1), 3), dtype=np.int64),
                            np.empty((max(lb, 1), 3), dtype=np.int64))
    finally:
        free(o.fa.data)
        free(o.fb.data)
        free(o.size.data)
        free(o.normal.data)
        free(o.src_a.data)
        free(o.src_b.data)


cdef object _edge_facets(Out* o, const int64_t[:, ::1] A, const int64_t[:, ::1] B,
                         const int64_t[:, ::1] nA, const int64_t[:, ::1] nB,
                         const int64_t[:, ::1] a_edges, const int64_t[:, ::1] b_edges,
                         const int64_t[:, ::1] a_ef, const int64_t[:, ::1] b_ef,
                         const int64_t* ia, Py_ssize_t la, const int64_t* ib, Py_ssize_t lb,
                         signed char[:, ::1] T, int64_t[:, ::1] av, int64_t[:, ::1] bv):
    cdef Py_ssize_t i, j, c, fB = nB.shape[0], n
    cdef int64_t s, t1, t2, ua, va, ub, vb, g
    cdef i128 x0, x1, x2
    cdef double ma = 0.0, mb = 0.0, z
    cdef Buf si, sj, ss
    si = Buf(NULL, 0, 0)
    sj = Buf(NULL, 0, 0)
    ss = Buf(NULL, 0, 0)
    try:
        for i in range(la):
            for c in range(3):
                av[i, c] = A[a_edges[ia[i], 1], c] - A[a_edges[ia[i], 0], c]
            for j in range(fB):
                T[i, j] = _sign128(_dot(&av[i, 0], &nB[j, 0]))
        for j in range(lb):
            for c in range(3):
                bv[j, c] = B[b_edges[ib[j], 1], c] - B[b_edges[ib[j], 0], c]
        for i in range(la):
            for j in range(lb):
                t1 = T[i, b_ef[ib[j], 0]]
                t2 = T[i, b_ef[ib[j], 1]]
                if t1 == 0 or t1 != -t2:
                    continue
                s = t2
                if _sign128(_dot(&bv[j, 0], &nA[a_ef[ia[i], 0], 0])) != s:
                    continue
                if _sign128(_dot(&bv[j, 0], &nA[a_ef[ia[i], 1], 0])) != -s:
                    continue
                _push(&si, i)
                _push(&sj, j)
                _push(&ss, s)
        # the reference's range check on the selected edge vectors (exact.cross)
        for n in range(si.n):
            for c in range(3):
                z = <double> (av[si.data[n], c] if av[si.data[n], c] >= 0 else -av[si.data[n], c])
                if z > ma:
                    ma = z
                z = <double> (bv[sj.data[n], c] if bv[sj.data[n], c] >= 0 else -bv[sj.data[n], c])
                if z > mb:
                    mb = z
        if si.n and 2.0 * ma * mb >= 2.0 ** 61:
            return None
        for n in range(si.n):
            i, j, s = si.data[n], sj.data[n], ss.data[n]
            ua, va = a_edges[ia[i], 0], a_edges[ia[i], 1]
            ub, vb = b_edges[ib[j], 0], b_edges[ib[j], 1]
            if s > 0:
                _push(&o.fa, ua); _push(&o.fa, va); _push(&o.fa, va); _push(&o.fa, ua)
                _push(&o.fb, ub); _push(&o.fb, ub); _push(&o.fb, vb); _push(&o.fb, vb)
            else:
                _push(&o.fa, ua); _push(&o.fa, va); _push(&o.fa, va); _push(&o.fa, ua)
                _push(&o.fb, vb); _push(&o.fb, vb); _push(&o.fb, ub); _push(&o.fb, ub)
            _push(&o.size, 4)
            x0 = (<i128> av[i, 1] * bv[j, 2] - <i128> av[i, 2] * bv[j, 1]) * s
            x1 = (<i128> av[i, 2] * bv[j, 0] - <i128> av[i, 0] * bv[j, 2]) * s
            x2 = (<i128> av[i, 0] * bv[j, 1] - <i128> av[i, 1] * bv[j, 0]) * s
            g = _gcd(_gcd(<int64_t> x0, <int64_t> x1), <int64_t> x2)
            if g == 0:
                g = 1
            _facet(o, <int64_t> x0 // g, <int64_t> x1 // g, <int64_t> x2 // g,
                   1, ia[i], 1, ib[j])
        return _labels(o, B.shape[0])
    finally:
        free(si.data)
        free(sj.data)
        free(ss.data)


cdef object _labels(Out* o, Py_ssize_t vB):
    """One sum vertex per distinct ``(a, b)``, in the order of ``a * vB + b`` (as ``np.unique``)."""
    cdef Py_ssize_t n = o.fa.n, i, u = 0, f = o.size.n
    codes_arr = np.empty(max(n, 1), dtype=np.int64)
    cdef int64_t[::1] codes = codes_arr
    for i in range(n):
        codes[i] = o.fa.data[i] * vB + o.fb.data[i]
    qsort(&codes[0], n, sizeof(int64_t), _cmp64)
    for i in range(n):
        if u == 0 or codes[i] != codes[u - 1]:
            codes[u] = codes[i]
            u += 1
    labels_arr = np.empty((u, 2), dtype=np.int64)
    flat_arr = np.empty(n, dtype=np.int64)
    offsets_arr = np.zeros(f + 1, dtype=np.int64)
    cdef int64_t[:, ::1] labels = labels_arr
    cdef int64_t[::1] flat = flat_arr, offsets = offsets_arr
    for i in range(u):
        labels[i, 0] = codes[i] // vB
        labels[i, 1] = codes[i] % vB
    for i in range(n):
        flat[i] = _last_at_most(&codes[0], u, o.fa.data[i] * vB + o.fb.data[i])
    for i in range(f):
        offsets[i + 1] = offsets[i] + o.size.data[i]
    normals = _array(&o.normal).reshape(-1, 3)
    src_a = _array(&o.src_a).reshape(-1, 2)
    src_b = _array(&o.src_b).reshape(-1, 2)
    edges = _edges(flat, offsets, u)
    if edges is None:
        return None
    return labels_arr, offsets_arr, flat_arr, normals, src_a, src_b, edges[0], edges[1]


def edges_of(const int64_t[::1] flat, const int64_t[::1] offsets, Py_ssize_t nv):
    """:func:`cspace.mesh.convex._edges_of` of CSR facet polygons, or None where it raises."""
    return _edges(flat, offsets, nv)


cdef object _edges(const int64_t[::1] flat, const int64_t[::1] offsets, Py_ssize_t nv):
    """Each edge once, ``(u, v)`` with ``u < v`` in the order of ``flat``, and its left and
    right facets (as ``cspace.mesh.convex._edges_of``); None when the facets do not close up
    (a half-edge unmatched or repeated: the caller's reference raises the named error)."""
    cdef Py_ssize_t n = flat.shape[0], f = offsets.shape[0] - 1, i, k, lo, e = 0
    cdef int64_t u, v, key
    codes_arr = np.empty((max(n, 1), 3), dtype=np.int64)  # (code, facet, v) per half-edge
    cdef int64_t[:, ::1] h = codes_arr
    for k in range(f):
        for i in range(offsets[k], offsets[k + 1]):
            u = flat[i]
            v = flat[i + 1] if i + 1 < offsets[k + 1] else flat[offsets[k]]
            h[i, 0] = u * nv + v
            h[i, 1] = k
            h[i, 2] = v
    sorted_at_arr = np.argsort(codes_arr[:n, 0], kind="stable")
    sorted_codes_arr = np.ascontiguousarray(codes_arr[:n, 0][sorted_at_arr])
    cdef int64_t[::1] sc = sorted_codes_arr, at = sorted_at_arr
    for i in range(1, n):
        if sc[i] == sc[i - 1]:
            return None
    edges_arr = np.empty((n // 2, 2), dtype=np.int64)
    ef_arr = np.empty((n // 2, 2), dtype=np.int64)
    cdef int64_t[:, ::1] E = edges_arr, EF = ef_arr
    for i in range(n):
        u = h[i, 0] // nv
        v = h[i, 2]
        key = v * nv + u
        lo = _last_at_most(&sc[0], n, key)
        if sc[lo] != key:
            return None
        if u < v:
            if e == n // 2:
                return None
            E[e, 0], E[e, 1] = u, v
            EF[e, 0], EF[e, 1] = h[i, 1], h[at[lo], 1]
            e += 1
    if e != n // 2 or 2 * e != n:
        return None
    return edges_arr, ef_arr


# --------------------------------------------------------------------------------------------
# the polytope a convex mesh bounds

# Mesh coordinates below 2**30: a face normal (a cross product of differences below 2**31)
# fits int64, a plane test (normal . difference) and a determinant fit __int128.
cdef int64_t MESH_COORD = 1LL << 30
# The vertex-against-plane test costs planes x vertices; beyond this the caller's reference
# (Qhull certified exactly) is the better algorithm.
cdef int64_t MESH_WORK = 50000000


cdef inline i128 _det3(const int64_t* a, const int64_t* b, const int64_t* c) noexcept nogil:
    """``a . (b x c)``: six times the signed volume of the tetrahedron (0, a, b, c)."""
    return (a[0] * (<i128> b[1] * c[2] - <i128> b[2] * c[1])
            - a[1] * (<i128> b[0] * c[2] - <i128> b[2] * c[0])
            + a[2] * (<i128> b[0] * c[1] - <i128> b[1] * c[0]))


def polytope_of_mesh(const int64_t[:, ::1] P, const int64_t[:, ::1] F):
    """The convex polytope an exactly convex closed mesh bounds, or None.

    ``P`` (n, 3) grid integers, ``F`` (m, 3) triangles into them. The mesh is accepted when
    its vertices are distinct, every directed edge is used once and its reverse once (closed,
    consistently oriented), every triangle has an area, every vertex lies on or below every
    triangle's plane (exact), and the triangles' volume is positive and equals that of the
    polygons they span. Then the triangles lie on supporting planes of the hull H of ``P``, so
    as a 2-cycle they are ``k`` times H's boundary with ``k >= 1`` (every one faces out);
    every facet of H holds some of them, so the polygon spanned per normal is that facet and
    the polygons' volume is H's; equal volumes mean ``k = 1``.

    Returns ``(ints, offsets, flat, normals, edges, edge_facets)``, what
    ``cspace.mesh.convex.ConvexPolytope.from_ints(P)`` returns for the same points: the
    corners in lexicographic order, the facets in lexicographic order of their primitive
    outward normals, each ring as ``mesh.convex._facet_polygon`` makes it. None (the caller
    runs its reference, which decides and names the reason) for anything else: coordinates
    of ``2**30`` or more, a repeated vertex, a face with a repeated index or no area, an
    open or inconsistently oriented or non-manifold edge, a vertex above a plane (not
    convex, or bent by snapping), volumes that differ, or more than ``MESH_WORK`` plane
    tests.
    """
    cdef Py_ssize_t n = P.shape[0], m = F.shape[0], i, j, k, a, g, g0, r, h, cnt, total
    cdef int64_t u, v, key, gg, ax, b1, b2
    cdef int64_t nrm[3]
    cdef int64_t d[3]
    cdef i128 vol_faces = 0, vol_poly = 0
    if n < 4 or m < 4 or F.shape[1] != 3 or P.shape[1] != 3 or not _within(P, MESH_COORD):
        return None
    for i in range(m):
        for k in range(3):
            if not 0 <= F[i, k] < n:
                return None
        if F[i, 0] == F[i, 1] or F[i, 1] == F[i, 2] or F[i, 0] == F[i, 2]:
            return None
    # distinct vertices: the lexicographic order (also the corners' order at the end)
    vorder_arr = np.empty(n, dtype=np.int64)
    tmp_arr = np.empty(max(3 * m, 2 * n + 2), dtype=np.int64)
    cdef int64_t[::1] vorder = vorder_arr, tmp = tmp_arr
    for i in range(n):
        vorder[i] = i
    _msort(&vorder[0], &tmp[0], n, &P[0, 0], 3)
    for i in range(1, n):
        if _cmp(&P[0, 0], 3, vorder[i], vorder[i - 1]) == 0:
            return None
    # directed edges: each once, each with its reverse
    keys_arr = np.empty(3 * m, dtype=np.int64)
    cdef int64_t[::1] keys = keys_arr
    for i in range(m):
        for k in range(3):
            keys[3 * i + k] = F[i, k] * n + F[i, (k + 1) % 3]
    qsort(&keys[0], 3 * m, sizeof(int64_t), _cmp64)
    for i in range(1, 3 * m):
        if keys[i] == keys[i - 1]:
            return None
    for i in range(3 * m):
        u = keys[i] // n
        v = keys[i] % n
        key = v * n + u
        if keys[_last_at_most(&keys[0], 3 * m, key)] != key:
            return None
    # primitive face normals (int64: see MESH_COORD), grouped by normal
    N_arr = np.empty((m, 3), dtype=np.int64)
    cdef int64_t[:, ::1] N = N_arr
    for i in range(m):
        for k in range(3):
            d[k] = P[F[i, 2], k] - P[F[i, 0], k]
        for k in range(3):
            nrm[k] = P[F[i, 1], k] - P[F[i, 0], k]
        N[i, 0] = nrm[1] * d[2] - nrm[2] * d[1]
        N[i, 1] = nrm[2] * d[0] - nrm[0] * d[2]
        N[i, 2] = nrm[0] * d[1] - nrm[1] * d[0]
        gg = _gcd(_gcd(N[i, 0], N[i, 1]), N[i, 2])
        if gg == 0:
            return None
        for k in range(3):
            N[i, k] //= gg
        vol_faces += _det3(&P[F[i, 0], 0], &P[F[i, 1], 0], &P[F[i, 2], 0])
    if vol_faces <= 0:
        return None
    forder_arr = np.empty(m, dtype=np.int64)
    cdef int64_t[::1] forder = forder_arr
    for i in range(m):
        forder[i] = i
    _msort(&forder[0], &tmp[0], m, &N[0, 0], 3)
    # group starts (facets) and the plane test: every vertex on or below one face per group,
    # every face of the group on that face's plane
    starts_arr = np.empty(m + 1, dtype=np.int64)
    cdef int64_t[::1] starts = starts_arr
    g = 0
    for i in range(m):
        if i == 0 or _cmp(&N[0, 0], 3, forder[i], forder[i - 1]) != 0:
            starts[g] = i
            g += 1
    starts[g] = m
    if <int64_t> g * n > MESH_WORK:
        return None
    for j in range(g):
        r = forder[starts[j]]
        for i in range(starts[j] + 1, starts[j + 1]):
            for k in range(3):
                d[k] = P[F[forder[i], 0], k] - P[F[r, 0], k]
            if _dot(&N[r, 0], d) != 0:
                return None
        for a in range(n):
            for k in range(3):
                d[k] = P[a, k] - P[F[r, 0], k]
            if _dot(&N[r, 0], d) > 0:
                return None
    # each facet's ring: the 2D hull of its faces' vertices, projected along the normal's
    # largest component (the first of equals, as numpy's argmax), reversed when it is negative
    xy_arr = np.empty(2 * 3 * m, dtype=np.int64)
    ids_arr = np.empty(3 * m, dtype=np.int64)
    ring_arr = np.empty(2 * 3 * m + 2, dtype=np.int64)
    idx_arr = np.empty(3 * m, dtype=np.int64)
    rings_arr = np.empty(3 * m, dtype=np.int64)
    offsets_arr = np.zeros(g + 1, dtype=np.int64)
    cdef int64_t[::1] xy = xy_arr, ids = ids_arr, ring = ring_arr, idx = idx_arr
    cdef int64_t[::1] rings = rings_arr, offsets = offsets_arr
    total = 0
    for j in range(g):
        r = forder[starts[j]]
        ax = 0
        for k in range(1, 3):
            if (N[r, k] if N[r, k] >= 0 else -N[r, k]) > (N[r, ax] if N[r, ax] >= 0 else -N[r, ax]):
                ax = k
        b1, b2 = (ax + 1) % 3, (ax + 2) % 3
        cnt = 0
        for i in range(starts[j], starts[j + 1]):
            for k in range(3):
                a = F[forder[i], k]
                ids[cnt] = a
                xy[2 * cnt] = P[a, b1]
                xy[2 * cnt + 1] = P[a, b2]
                cnt += 1
        h = _hull2d(&xy[0], cnt, &ring[0], &idx[0], &tmp[0])
        if h < 3:
            return None
        for i in range(h):
            rings[total + i] = ids[ring[h - 1 - i] if N[r, ax] < 0 else ring[i]]
        for i in range(1, h - 1):
            vol_poly += _det3(&P[rings[total], 0], &P[rings[total + i], 0],
                              &P[rings[total + i + 1], 0])
        total += h
        offsets[j + 1] = total
    if vol_poly != vol_faces:
        return None
    # the corners, renumbered in lexicographic order
    new_arr = np.full(n, -1, dtype=np.int64)
    cdef int64_t[::1] new = new_arr
    for i in range(total):
        new[rings[i]] = 0
    cnt = 0
    for i in range(n):
        if new[vorder[i]] == 0:
            new[vorder[i]] = cnt
            cnt += 1
    ints_arr = np.empty((cnt, 3), dtype=np.int64)
    normals_arr = np.empty((g, 3), dtype=np.int64)
    cdef int64_t[:, ::1] I = ints_arr, NO = normals_arr
    for i in range(n):
        if new[i] >= 0:
            for k in range(3):
                I[new[i], k] = P[i, k]
    for i in range(total):
        rings[i] = new[rings[i]]
    for j in range(g):
        for k in range(3):
            NO[j, k] = N[forder[starts[j]], k]
    flat_arr = rings_arr[:total].copy()
    edges = _edges(flat_arr, offsets_arr, cnt)
    if edges is None:
        return None
    return ints_arr, offsets_arr, flat_arr, normals_arr, edges[0], edges[1]


# --------------------------------------------------------------------------------------------
# the exact hull of a point set

# Beyond this many distinct points the incremental hull below (every point tested against
# every live face, O(n h)) loses to the caller's reference (Qhull proposes, an exact
# certificate decides).
cdef Py_ssize_t HULL_POINTS = 2048


cdef inline i128 _side(const int64_t* a, const int64_t* b, const int64_t* c,
                       const int64_t* p) noexcept nogil:
    """``((b - a) x (c - a)) . (p - a)``: positive when ``p`` is above the triangle ``abc``
    (counter-clockwise seen from above). Differences below ``2**31`` make each cross
    component below ``2**63`` and the sum below ``2**96``: exact in ``__int128``."""
    cdef i128 u0 = b[0] - a[0], u1 = b[1] - a[1], u2 = b[2] - a[2]
    cdef i128 v0 = c[0] - a[0], v1 = c[1] - a[1], v2 = c[2] - a[2]
    return ((u1 * v2 - u2 * v1) * (p[0] - a[0]) + (u2 * v0 - u0 * v2) * (p[1] - a[1])
            + (u0 * v1 - u1 * v0) * (p[2] - a[2]))


def hull_of_points(const int64_t[:, ::1] P):
    """The exact convex hull of grid-integer points, as ``ConvexPolytope.from_ints`` makes it.

    ``P`` (n, 3) grid integers, repeats allowed. An incremental hull over the distinct points
    (a point strictly above some live triangle replaces the triangles it sees by a fan from
    their horizon; a point on or below all of them is inside) proposes a closed triangle
    mesh; :func:`polytope_of_mesh` then proves it, over *every* distinct point, exactly
    convex and containing them all, and returns the canonical polytope. So a mistake here
    can only make this return None, never a wrong hull.

    Returns ``polytope_of_mesh``'s tuple, or None (the caller runs its reference, which
    decides and names the reason) for fewer than four distinct points, all of them coplanar,
    coordinates of ``2**30`` or more, or more than ``HULL_POINTS`` distinct points.
    """
    cdef Py_ssize_t n = P.shape[0], i, j, k, q, t, nf, nv, nh, nn, cap, step, found
    cdef int64_t a, b, c, d
    cdef i128 s
    cdef int64_t x0, x1, x2
    if n < 4 or P.shape[1] != 3 or not _within(P, MESH_COORD):
        return None
    # the distinct points, in lexicographic order
    order_arr = np.empty(n, dtype=np.int64)
    tmp_arr = np.empty(n, dtype=np.int64)
    cdef int64_t[::1] order = order_arr, tmp = tmp_arr
    for i in range(n):
        order[i] = i
    _msort(&order[0], &tmp[0], n, &P[0, 0], 3)
    Q_arr = np.empty((n, 3), dtype=np.int64)
    cdef int64_t[:, ::1] Q = Q_arr
    nv = 0
    for i in range(n):
        if nv == 0 or _cmp(&P[0, 0], 3, order[i], order[i - 1]) != 0:
            for k in range(3):
                Q[nv, k] = P[order[i], k]
            nv += 1
    if nv < 4 or nv > HULL_POINTS:
        return None
    Q_arr = Q_arr[:nv]
    Q = Q_arr
    # a tetrahedron: the first and last points, the first off their line, the first off
    # their plane
    a, b = 0, nv - 1
    c = -1
    for i in range(1, nv - 1):
        x0 = (Q[b, 1] - Q[a, 1]) * (Q[i, 2] - Q[a, 2]) - (Q[b, 2] - Q[a, 2]) * (Q[i, 1] - Q[a, 1])
        x1 = (Q[b, 2] - Q[a, 2]) * (Q[i, 0] - Q[a, 0]) - (Q[b, 0] - Q[a, 0]) * (Q[i, 2] - Q[a, 2])
        x2 = (Q[b, 0] - Q[a, 0]) * (Q[i, 1] - Q[a, 1]) - (Q[b, 1] - Q[a, 1]) * (Q[i, 0] - Q[a, 0])
        if x0 != 0 or x1 != 0 or x2 != 0:
            c = i
            break
    if c < 0:
        return None
    d = -1
    for i in range(1, nv - 1):
        s = _side(&Q[a, 0], &Q[b, 0], &Q[c, 0], &Q[i, 0])
        if s != 0:
            d = i
            break
    if d < 0:
        return None
    if s > 0:  # d above abc: turn abc over so that every face looks away from the fourth
        b, c = c, b
    # live faces (double-buffered: the faces a point keeps, then the fan it adds); a hull of
    # v points has 2v - 4 triangles, a fan at most as many as the faces it replaces plus 2
    cap = 4 * nv + 16
    F_arr = np.empty((cap, 3), dtype=np.int64)
    G_arr = np.empty((cap, 3), dtype=np.int64)
    vis_arr = np.empty(cap, dtype=np.uint8)
    hor_arr = np.empty((cap * 3, 2), dtype=np.int64)
    cdef int64_t[:, ::1] F = F_arr, G = G_arr, H = hor_arr
    cdef uint8_t[::1] vis = vis_arr
    F[0, 0], F[0, 1], F[0, 2] = a, b, c
    F[1, 0], F[1, 1], F[1, 2] = a, d, b
    F[2, 0], F[2, 1], F[2, 2] = b, d, c
    F[3, 0], F[3, 1], F[3, 2] = c, d, a
    nf = 4
    # the other points in a stride order (any order gives the same hull; a scattered one
    # meets interior points once the hull is large, and they cost one pass)
    step = 1
    for q in (7919, 104729, 1299709, 15485863):
        if nv % q != 0:
            step = q % nv if q % nv else 1
            break
    j = 0
    for t in range(nv):
        j = (j + step) % nv if t else 0
        if j == a or j == b or j == c or j == d:
            continue
        found = 0
        for i in range(nf):
            vis[i] = _side(&Q[F[i, 0], 0], &Q[F[i, 1], 0], &Q[F[i, 2], 0], &Q[j, 0]) > 0
            found += vis[i]
        if not found:
            continue
        # the horizon: directed edges of seen faces whose reverse no seen face holds
        nh = 0
        for i in range(nf):
            if not vis[i]:
                continue
            for k in range(3):
                x0, x1 = F[i, k], F[i, (k + 1) % 3]
                q = 0
                for nn in range(nf):
                    if vis[nn] and ((F[nn, 0] == x1 and F[nn, 1] == x0)
                                    or (F[nn, 1] == x1 and F[nn, 2] == x0)
                                    or (F[nn, 2] == x1 and F[nn, 0] == x0)):
                        q = 1
                        break
                if not q:
                    H[nh, 0], H[nh, 1] = x0, x1
                    nh += 1
        nn = 0
        for i in range(nf):
            if not vis[i]:
                G[nn, 0], G[nn, 1], G[nn, 2] = F[i, 0], F[i, 1], F[i, 2]
                nn += 1
        if nn + nh > cap:
            return None
        for i in range(nh):
            G[nn, 0], G[nn, 1], G[nn, 2] = H[i, 0], H[i, 1], j
            nn += 1
        F, G = G, F
        nf = nn
    faces = np.asarray(F)[:nf].copy()
    return polytope_of_mesh(Q_arr, faces)
