# cython: language_level=3, boundscheck=False, wraparound=False, cdivision=True, initializedcheck=False
"""Compiled kernels of :mod:`cspace.cobstacle.pairs`: triangle-pair C-obstacles queried
without enumerating the pairs.

The C-obstacle is ``∪ S_i ⊕ T_j ⊕ box`` over obstacle triangles ``S_i`` and robot vectors
``T_j = c - t_j`` (grid integers, held as exact float64; ``box = [-g, g]``). The piece of pair
``(i, j)`` holds a query ``Q`` only if the k-DOP of ``S_i`` grown by ``g`` meets the k-DOP of
``Q - T_j``: two trees (:class:`cspace.geometry.boxes.BoxTree`, one over the obstacle's
grown triangle k-DOPs, one over those of ``-T_j``, on the directions ``D`` of
:func:`cspace.geometry.boxes.dop_bounds`) are traversed together with the query's k-DOP
added to the robot side. Every comparison is between a difference of two grid integers
(exact in float64 below 2**53) and the query's projection, widened by that projection's
rounding bound: no candidate is missed.

Each candidate is then tested on the slabs of :func:`cspace.cobstacle.pairs.pair_planes`
with the same float filter as the numpy engine (``cspace.cobstacle.pairs_reference._PairsCO``, the reference these are tested
against): the two triangle-normal slabs first, then all 17 (38 when grown), each value with
its rigorous bound (16 unit roundoffs of the sum of absolute products, the normals and
supports rounded to float included). Nothing here decides an undecided sign: such pairs are
returned for the exact path in Python integers.
"""

import numpy as np

from libc.math cimport INFINITY, fabs
from libc.stdint cimport int64_t

cdef double _EPS = 2.0 ** -53
cdef double _FILTER = 16.0 * _EPS
cdef double _TINY = 2.0 ** -1000
cdef int _STACK = 512
cdef int _MAXK = 13


cdef inline bint _boxes_meet(const double* slo, const double* shi, const double* rlo,
                             const double* rhi, const double* qlo, const double* qhi,
                             int K) noexcept nogil:
    # the k-DOP [slo, shi] meets [qlo + rlo, qhi + rhi], as slo - rhi <= qhi and
    # qlo <= shi - rlo on every direction: differences of grid integers below 2**53, exact
    cdef int k
    for k in range(K):
        if slo[k] - rhi[k] > qhi[k] or qlo[k] > shi[k] - rlo[k]:
            return False
    return True


cdef inline double _box_gap2(const double* slo, const double* shi, const double* rlo,
                            const double* rhi, const double* q) noexcept nogil:
    # squared distance between the box [slo, shi] and [q + rlo, q + rhi] (a lower bound for
    # any two triangles in them); the k-DOPs' first three directions are the axes
    cdef double g, s = 0.0
    cdef int k
    for k in range(3):
        g = slo[k] - (q[k] + rhi[k])
        if q[k] + rlo[k] - shi[k] > g:
            g = q[k] + rlo[k] - shi[k]
        if g > 0.0:
            s += g * g
    return s


cdef inline void _cross(const int64_t* a, const int64_t* b, int64_t* out) noexcept nogil:
    out[0] = a[1] * b[2] - a[2] * b[1]
    out[1] = a[2] * b[0] - a[0] * b[2]
    out[2] = a[0] * b[1] - a[1] * b[0]


cdef int _normals(const int64_t* s, const int64_t* t, bint grown, int64_t* N) noexcept nogil:
    """The slab normals of pair_planes (17, or 38 when grown) into N (3 each); their count."""
    cdef int64_t es[18]
    cdef int64_t et[9]
    cdef int64_t ns[3]
    cdef int64_t nt[3]
    cdef int64_t unit[3]
    cdef int64_t m, best
    cdef int a, b, k, n = 0, axis
    for a in range(3):
        b = (a + 1) % 3
        for k in range(3):
            es[3 * a + k] = s[3 * b + k] - s[3 * a + k]
            et[3 * a + k] = t[3 * b + k] - t[3 * a + k]
    # ns = (p1 - p0) x (p2 - p0) = es0 x -es2
    for k in range(3):
        es[9 + k] = -es[6 + k]
    _cross(&es[0], &es[9], ns)
    for k in range(3):
        es[9 + k] = -et[6 + k]
    _cross(&et[0], &es[9], nt)
    for k in range(3):
        N[k] = ns[k]
        N[3 + k] = nt[k]
    n = 2
    for a in range(3):
        for b in range(3):
            _cross(&es[3 * a], &et[3 * b], &N[3 * n])
            n += 1
    # the axis nearest the reference normal (s's, else t's): first largest |component|
    if ns[0] != 0 or ns[1] != 0 or ns[2] != 0:
        unit[0], unit[1], unit[2] = ns[0], ns[1], ns[2]
    else:
        unit[0], unit[1], unit[2] = nt[0], nt[1], nt[2]
    axis, best = 0, -1
    for k in range(3):
        m = unit[k] if unit[k] >= 0 else -unit[k]
        if m > best:
            axis, best = k, m
    n = _turned_edges(axis, es, et, N, n)
    if grown:
        for a in range(3):
            for k in range(3):
                N[3 * n + k] = 1 if k == a else 0
            n += 1
        for a in range(3):
            n = _turned_edges(a, es, et, N, n)
    return n


cdef inline int _turned_edges(int axis, const int64_t* es, const int64_t* et, int64_t* N,
                              int n) noexcept nogil:
    """Append ``e_axis x edge`` for the three edges of each triangle at ``N[3 n]``; the new
    count."""
    cdef int64_t unit[3]
    cdef int a
    unit[0], unit[1], unit[2] = 0, 0, 0
    unit[axis] = 1
    for a in range(3):
        _cross(unit, &es[3 * a], &N[3 * n])
        n += 1
    for a in range(3):
        _cross(unit, &et[3 * a], &N[3 * n])
        n += 1
    return n


cdef inline void _support(const double* n, const double* tri, double* lo, double* hi,
                          double* perm) noexcept nogil:
    # min and max of n . p over the corners (as numpy: products summed left to right), and
    # the permanent sum |n_k| max |p_k|
    cdef int a, k
    cdef double d, m
    lo[0], hi[0], perm[0] = INFINITY, -INFINITY, 0.0
    for a in range(3):
        d = n[0] * tri[3 * a] + n[1] * tri[3 * a + 1] + n[2] * tri[3 * a + 2]
        if d < lo[0]:
            lo[0] = d
        if d > hi[0]:
            hi[0] = d
    for k in range(3):
        m = fabs(tri[k])
        if fabs(tri[3 + k]) > m:
            m = fabs(tri[3 + k])
        if fabs(tri[6 + k]) > m:
            m = fabs(tri[6 + k])
        perm[0] += fabs(n[k]) * m


cdef inline int _sides(const double* nf, const double* s, const double* t, const double* g,
                       const double* q, double* val, double* err) noexcept nogil:
    """Both sides of the slab of normal nf at q: values (<= 0 inside) and bounds."""
    cdef double slo, shi, sperm, tlo, thi, tperm, box, x, ax, a3
    _support(nf, s, &slo, &shi, &sperm)
    _support(nf, t, &tlo, &thi, &tperm)
    box = fabs(nf[0]) * g[0] + fabs(nf[1]) * g[1] + fabs(nf[2]) * g[2]
    x = nf[0] * q[0] + nf[1] * q[1] + nf[2] * q[2]
    ax = fabs(nf[0]) * fabs(q[0]) + fabs(nf[1]) * fabs(q[1]) + fabs(nf[2]) * fabs(q[2])
    a3 = -(shi + thi + box)
    val[0] = x + a3
    err[0] = _FILTER * (ax + fabs(a3) + sperm + tperm + box) + _TINY
    a3 = slo + tlo - box
    val[1] = -x + a3
    err[1] = _FILTER * (ax + fabs(a3) + sperm + tperm + box) + _TINY
    return 2


cdef inline int _face_sides(const double* n, const double* own, const double* other,
                            const double* g, const double* q, double* val,
                            double* err) noexcept nogil:
    """The two sides of a triangle's own normal slab at q (as _PairsCO._face_values)."""
    cdef double base, dmin = INFINITY, dmax = -INFINITY, d, x, e, box, an, own_abs, other_abs
    cdef int a, k
    base = n[0] * own[0] + n[1] * own[1] + n[2] * own[2]
    for a in range(3):
        d = n[0] * other[3 * a] + n[1] * other[3 * a + 1] + n[2] * other[3 * a + 2]
        if d < dmin:
            dmin = d
        if d > dmax:
            dmax = d
    x = n[0] * q[0] + n[1] * q[1] + n[2] * q[2]
    box = fabs(n[0]) * g[0] + fabs(n[1]) * g[1] + fabs(n[2]) * g[2]
    e = 0.0
    for k in range(3):
        an = fabs(n[k])
        own_abs = fabs(own[k])
        if fabs(own[3 + k]) > own_abs:
            own_abs = fabs(own[3 + k])
        if fabs(own[6 + k]) > own_abs:
            own_abs = fabs(own[6 + k])
        other_abs = fabs(other[k])
        if fabs(other[3 + k]) > other_abs:
            other_abs = fabs(other[3 + k])
        if fabs(other[6 + k]) > other_abs:
            other_abs = fabs(other[6 + k])
        e += an * fabs(q[k]) + an * own_abs + an * other_abs
    e = _FILTER * (e + box) + _TINY
    val[0] = x - base - dmax - box
    val[1] = base + dmin - x - box
    err[0] = e
    err[1] = e
    return 2


cdef inline double _dot(const double* a, const double* b) noexcept nogil:
    return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]


cdef inline double _clamp01(double x) noexcept nogil:
    return 0.0 if x < 0.0 else (1.0 if x > 1.0 else x)


cdef double _seg_seg_dist2(const double* p1, const double* q1, const double* p2,
                           const double* q2) noexcept nogil:
    """Squared distance of two segments (Ericson, Real-Time Collision Detection 5.1.9)."""
    cdef double d1[3]
    cdef double d2[3]
    cdef double r[3]
    cdef double c1[3]
    cdef double c2[3]
    cdef double a, e, f, c, b, denom, s, t
    cdef int k
    for k in range(3):
        d1[k] = q1[k] - p1[k]
        d2[k] = q2[k] - p2[k]
        r[k] = p1[k] - p2[k]
    a, e, f = _dot(d1, d1), _dot(d2, d2), _dot(d2, r)
    if a <= 0.0 and e <= 0.0:
        s, t = 0.0, 0.0
    elif a <= 0.0:
        s, t = 0.0, _clamp01(f / e)
    else:
        c = _dot(d1, r)
        if e <= 0.0:
            t, s = 0.0, _clamp01(-c / a)
        else:
            b = _dot(d1, d2)
            denom = a * e - b * b
            s = _clamp01((b * f - c * e) / denom) if denom > 0.0 else 0.0
            t = (b * s + f) / e
            if t < 0.0:
                t, s = 0.0, _clamp01(-c / a)
            elif t > 1.0:
                t, s = 1.0, _clamp01((b - c) / a)
    for k in range(3):
        c1[k] = p1[k] + d1[k] * s - p2[k] - d2[k] * t
    return _dot(c1, c1)


cdef double _pt_tri_dist2(const double* p, const double* a, const double* b,
                          const double* c) noexcept nogil:
    """Squared distance of a point to a triangle (Ericson 5.1.5; degenerate triangles fall
    back to their edges)."""
    cdef double ab[3]
    cdef double ac[3]
    cdef double ap[3]
    cdef double n[3]
    cdef double d, nn, best
    cdef int k
    for k in range(3):
        ab[k] = b[k] - a[k]
        ac[k] = c[k] - a[k]
        ap[k] = p[k] - a[k]
    n[0] = ab[1] * ac[2] - ab[2] * ac[1]
    n[1] = ab[2] * ac[0] - ab[0] * ac[2]
    n[2] = ab[0] * ac[1] - ab[1] * ac[0]
    nn = _dot(n, n)
    if nn > 0.0:
        # inside the prism over the triangle: the distance to its plane
        if (_side(a, b, p, n) >= 0.0 and _side(b, c, p, n) >= 0.0
                and _side(c, a, p, n) >= 0.0):
            d = _dot(ap, n)
            return d * d / nn
    best = _seg_seg_dist2(p, p, a, b)
    d = _seg_seg_dist2(p, p, b, c)
    if d < best:
        best = d
    d = _seg_seg_dist2(p, p, c, a)
    if d < best:
        best = d
    return best


cdef inline double _side(const double* u, const double* v, const double* p,
                         const double* n) noexcept nogil:
    # (v - u) x (p - u) . n: p on the inner side of edge uv (>= 0)
    cdef double e0 = v[0] - u[0], e1 = v[1] - u[1], e2 = v[2] - u[2]
    cdef double f0 = p[0] - u[0], f1 = p[1] - u[1], f2 = p[2] - u[2]
    return (e1 * f2 - e2 * f1) * n[0] + (e2 * f0 - e0 * f2) * n[1] + (e0 * f1 - e1 * f0) * n[2]


cdef double _tri_tri_dist2(const double* A, const double* B) noexcept nogil:
    """Squared distance of two disjoint triangles: the least of the six vertex-triangle and
    nine edge-edge distances."""
    cdef double best = INFINITY, d
    cdef int i, j
    for i in range(3):
        d = _pt_tri_dist2(&A[3 * i], &B[0], &B[3], &B[6])
        if d < best:
            best = d
        d = _pt_tri_dist2(&B[3 * i], &A[0], &A[3], &A[6])
        if d < best:
            best = d
    for i in range(3):
        for j in range(3):
            d = _seg_seg_dist2(&A[3 * i], &A[3 * ((i + 1) % 3)], &B[3 * j], &B[3 * ((j + 1) % 3)])
            if d < best:
                best = d
    return best


cdef class PairSet:
    """The operands of one triangle-pair C-obstacle, as the kernels read them.

    ``S (m, 9)`` obstacle triangles and ``T (l, 9)`` robot vectors ``c - t`` (grid integers,
    scene frame, int64, and ``Sf, Tf`` the same as float64); ``ns, nt`` their canonical primitive normals
    (flat pairs are skipped when ``closed``); ``g (3,)`` the margin box; the two trees'
    arrays (obstacle boxes grown by ``g``; robot boxes of ``-T``).
    """

    cdef const int64_t[:, ::1] S
    cdef const int64_t[:, ::1] T
    cdef const double[:, ::1] Sf
    cdef const double[:, ::1] Tf
    cdef const int64_t[:, ::1] ns
    cdef const int64_t[:, ::1] nt
    cdef const double[::1] nsf
    cdef const double[::1] ntf
    cdef double g[3]
    cdef bint closed, grown
    cdef const double[:, ::1] a_lo
    cdef const double[:, ::1] a_hi
    cdef const int64_t[::1] a_first
    cdef const int64_t[::1] a_count
    cdef const int64_t[::1] a_order
    cdef const double[:, ::1] a_blo
    cdef const double[:, ::1] a_bhi
    cdef const double[:, ::1] b_lo
    cdef const double[:, ::1] b_hi
    cdef const int64_t[::1] b_first
    cdef const int64_t[::1] b_count
    cdef const int64_t[::1] b_order
    cdef const double[:, ::1] b_blo
    cdef const double[:, ::1] b_bhi
    cdef object _keep
    cdef double D[3 * 13]
    cdef int nz[13]
    cdef int K

    def __init__(self, S, T, Sf, Tf, ns, nt, nsf, ntf, g, bint closed, tree_s, tree_r, D):
        self._keep = (S, T, Sf, Tf, ns, nt, nsf, ntf, tree_s, tree_r)
        D = np.asarray(D, dtype=np.int64).reshape(-1, 3)
        if not 3 <= len(D) <= _MAXK or tree_s.lo.shape[1] != len(D) \
                or tree_r.lo.shape[1] != len(D) or (np.abs(D) > 1).any():
            raise ValueError("the trees' bounds must have one column per direction of D "
                             "(3 to 13 directions, entries -1, 0, 1)")
        self.K = len(D)
        for k in range(self.K):
            self.nz[k] = int((D[k] != 0).sum())
            for c in range(3):
                self.D[3 * k + c] = float(D[k, c])
        self.S, self.T, self.Sf, self.Tf = S, T, Sf, Tf
        self.ns, self.nt, self.nsf, self.ntf = ns, nt, nsf, ntf
        for k in range(3):
            self.g[k] = float(g[k])
        self.grown = g[0] != 0 or g[1] != 0 or g[2] != 0
        self.closed = closed
        self.a_lo, self.a_hi, self.a_first, self.a_count, self.a_order = (
            tree_s.lo, tree_s.hi, tree_s.first, tree_s.count, tree_s.order)
        self.a_blo, self.a_bhi = tree_s.box_lo, tree_s.box_hi
        self.b_lo, self.b_hi, self.b_first, self.b_count, self.b_order = (
            tree_r.lo, tree_r.hi, tree_r.first, tree_r.count, tree_r.order)
        self.b_blo, self.b_bhi = tree_r.box_lo, tree_r.box_hi

    cdef void _dop(self, const double* lo, const double* hi, double* out_lo,
                   double* out_hi) noexcept nogil:
        """The query's bounds on every direction: of the box ``[lo, hi]`` (a point when
        ``lo == hi``), widened on a diagonal by the rounding of its two sums (each within
        2**-53 of a partial sum below ``m``; 2**-50 m covers them and the widening's own)."""
        cdef int k, c
        cdef double a, b, m, d, e
        for k in range(self.K):
            a, b, m = 0.0, 0.0, 0.0
            for c in range(3):
                d = self.D[3 * k + c]
                if d > 0:
                    a += lo[c]
                    b += hi[c]
                elif d < 0:
                    a -= hi[c]
                    b -= lo[c]
                if d != 0:
                    m += fabs(lo[c]) if fabs(lo[c]) > fabs(hi[c]) else fabs(hi[c])
            e = m * 2.0 ** -50 if self.nz[k] > 1 else 0.0
            out_lo[k], out_hi[k] = a - e, b + e

    cdef void _dop_segment(self, const double* q0, const double* q1, double* out_lo,
                           double* out_hi) noexcept nogil:
        """The bounds of the segment ``q0 q1`` on every direction (of its two ends)."""
        cdef double lo1[13]
        cdef double hi1[13]
        cdef int k
        self._dop(q0, q0, out_lo, out_hi)
        self._dop(q1, q1, lo1, hi1)
        for k in range(self.K):
            if lo1[k] < out_lo[k]:
                out_lo[k] = lo1[k]
            if hi1[k] > out_hi[k]:
                out_hi[k] = hi1[k]

    cdef inline bint _flat_skipped(self, Py_ssize_t i, Py_ssize_t j) noexcept nogil:
        # Parallel triangles only: a degenerate one (zero normal: a segment or a point, a
        # feature thinner than the grid step) is a prism's edge, never skipped
        # (pairs._parallel, its reference).
        if not self.closed:
            return False
        if self.ns[i, 0] == 0 and self.ns[i, 1] == 0 and self.ns[i, 2] == 0:
            return False
        if self.nt[j, 0] == 0 and self.nt[j, 1] == 0 and self.nt[j, 2] == 0:
            return False
        return (self.ns[i, 0] == self.nt[j, 0] and self.ns[i, 1] == self.nt[j, 1]
                and self.ns[i, 2] == self.nt[j, 2])

    cdef int _point(self, Py_ssize_t i, Py_ssize_t j, const double* q) noexcept nogil:
        """0: q certainly outside the piece of (i, j); 1: certainly inside; 2: undecided."""
        cdef double val[2]
        cdef double err[2]
        cdef int64_t N[3 * 38]
        cdef double nf[3]
        cdef int n, k, c
        cdef bint unsure = False
        _face_sides(&self.nsf[3 * i], &self.Sf[i, 0], &self.Tf[j, 0], self.g, q, val, err)
        if val[0] > err[0] or val[1] > err[1]:
            return 0
        _face_sides(&self.ntf[3 * j], &self.Tf[j, 0], &self.Sf[i, 0], self.g, q, val, err)
        if val[0] > err[0] or val[1] > err[1]:
            return 0
        n = _normals(&self.S[i, 0], &self.T[j, 0], self.grown, N)
        for k in range(n):
            if N[3 * k] == 0 and N[3 * k + 1] == 0 and N[3 * k + 2] == 0:
                continue
            for c in range(3):
                nf[c] = <double>N[3 * k + c]
            _sides(nf, &self.Sf[i, 0], &self.Tf[j, 0], self.g, q, val, err)
            for c in range(2):
                if val[c] > err[c]:
                    return 0
                if not val[c] < -err[c]:
                    unsure = True
        return 2 if unsure else 1

    cdef int _segment(self, Py_ssize_t i, Py_ssize_t j, const double* q0,
                      const double* q1) noexcept nogil:
        """0: the closed segment certainly misses the piece; 1: certainly meets it; 2:
        undecided (the filter of cspace.cobstacle.convex.segment_filter, one row)."""
        cdef double v0[2]
        cdef double e0[2]
        cdef double v1[2]
        cdef double e1[2]
        cdef int64_t N[3 * 38]
        cdef double nf[3]
        cdef int n, k, c
        cdef bint unknown = False, pos0, neg0, pos1, neg1
        cdef double lo_dn = 0.0, lo_up = 0.0, hi_dn = 1.0, hi_up = 1.0, A0, A1, ssum, t, terr
        _face_sides(&self.nsf[3 * i], &self.Sf[i, 0], &self.Tf[j, 0], self.g, q0, v0, e0)
        _face_sides(&self.nsf[3 * i], &self.Sf[i, 0], &self.Tf[j, 0], self.g, q1, v1, e1)
        if (v0[0] > e0[0] and v1[0] > e1[0]) or (v0[1] > e0[1] and v1[1] > e1[1]):
            return 0
        _face_sides(&self.ntf[3 * j], &self.Tf[j, 0], &self.Sf[i, 0], self.g, q0, v0, e0)
        _face_sides(&self.ntf[3 * j], &self.Tf[j, 0], &self.Sf[i, 0], self.g, q1, v1, e1)
        if (v0[0] > e0[0] and v1[0] > e1[0]) or (v0[1] > e0[1] and v1[1] > e1[1]):
            return 0
        n = _normals(&self.S[i, 0], &self.T[j, 0], self.grown, N)
        for k in range(n):
            if N[3 * k] == 0 and N[3 * k + 1] == 0 and N[3 * k + 2] == 0:
                continue
            for c in range(3):
                nf[c] = <double>N[3 * k + c]
            _sides(nf, &self.Sf[i, 0], &self.Tf[j, 0], self.g, q0, v0, e0)
            _sides(nf, &self.Sf[i, 0], &self.Tf[j, 0], self.g, q1, v1, e1)
            for c in range(2):
                pos0, neg0 = v0[c] > e0[c], v0[c] < -e0[c]
                pos1, neg1 = v1[c] > e1[c], v1[c] < -e1[c]
                if pos0 and pos1:
                    return 0
                if not (pos0 or neg0) or not (pos1 or neg1):
                    unknown = True
                    continue
                if pos0 == pos1:
                    continue  # both ends inside this side
                A0, A1 = fabs(v0[c]), fabs(v1[c])
                ssum = A0 + A1
                t = A0 / ssum
                terr = 2.0 * (e0[c] * A1 + e1[c] * A0) / (ssum * (ssum - e0[c] - e1[c])) \
                    + 8 * _EPS * t
                if pos0:  # entering
                    if t - terr > lo_dn:
                        lo_dn = t - terr
                    if t + terr > lo_up:
                        lo_up = t + terr
                else:     # leaving
                    if t - terr < hi_dn:
                        hi_dn = t - terr
                    if t + terr < hi_up:
                        hi_up = t + terr
        if lo_dn > hi_up:
            return 0
        if not unknown and lo_up <= hi_dn:
            return 1
        return 2

    def contains(self, const double[:, ::1] Q):
        """Per query row (grid units, scene frame): status 0 free, 1 inside, 2 undecided,
        and the undecided pairs ``(row, i, j)`` of the rows with status 2."""
        return self._rows(Q, Q, 0)

    cdef tuple _rows(self, const double[:, ::1] lo, const double[:, ::1] hi, int mode):
        """Per box row: :meth:`_traverse`'s status (mode 0, 4 or 5) and the undecided pairs
        ``(row, i, j)`` of the rows with status 2."""
        cdef Py_ssize_t r, nq = lo.shape[0]
        cdef double qlo[13]
        cdef double qhi[13]
        status = np.zeros(nq, dtype=np.int8)
        cdef signed char[::1] st = status
        out = []
        cdef list found
        for r in range(nq):
            found = []
            self._dop(&lo[r, 0], &hi[r, 0], qlo, qhi)
            if mode == 5:  # the query's ends swapped: a node pair's k-DOP sum [s - r]
                # "meets" [qhi, qlo] exactly when it holds [qlo, qhi]
                st[r] = self._traverse(qhi, qlo, &lo[r, 0], &hi[r, 0], False, found, 5)
            else:
                st[r] = self._traverse(qlo, qhi, &lo[r, 0], &hi[r, 0], False, found, mode)
            if st[r] == 2:
                out += [(r, i, j) for i, j in found]
        return status, np.array(out, dtype=np.int64).reshape(-1, 3)

    def contains_one(self, double x, double y, double z, double scale):
        """One query ``(x, y, z)`` in the scene's units, times ``scale`` (a power of two: exact)
        into grid units: ``(status, pairs)`` as one row of :meth:`contains`, the undecided
        pairs ``(i, j)`` a list. A planner's single state without array round trips."""
        cdef double q[3]
        cdef double lo[13]
        cdef double hi[13]
        q[0], q[1], q[2] = x * scale, y * scale, z * scale
        found = []
        self._dop(q, q, lo, hi)
        return self._traverse(lo, hi, q, q, False, found, 0), found

    def segment_one(self, double x0, double y0, double z0, double x1, double y1, double z1,
                    double scale):
        """One segment, as :meth:`contains_one`: ``(status, pairs)`` as one row of
        :meth:`segments`."""
        cdef double q0[3]
        cdef double q1[3]
        cdef double lo[13]
        cdef double hi[13]
        q0[0], q0[1], q0[2] = x0 * scale, y0 * scale, z0 * scale
        q1[0], q1[1], q1[2] = x1 * scale, y1 * scale, z1 * scale
        found = []
        self._dop_segment(q0, q1, lo, hi)
        return self._traverse(lo, hi, q0, q1, True, found, 0), found

    def segments(self, const double[:, ::1] Q0, const double[:, ::1] Q1):
        """Per segment row: status 0 free, 1 certainly hits, 2 undecided, and the undecided
        pairs ``(row, i, j)`` of the rows with status 2."""
        cdef Py_ssize_t r, nq = Q0.shape[0]
        cdef double lo[13]
        cdef double hi[13]
        status = np.zeros(nq, dtype=np.int8)
        cdef signed char[::1] st = status
        out = []
        cdef list found
        for r in range(nq):
            self._dop_segment(&Q0[r, 0], &Q1[r, 0], lo, hi)
            found = []
            st[r] = self._traverse(lo, hi, &Q0[r, 0], &Q1[r, 0], True, found, 0)
            if st[r] == 2:
                out += [(r, i, j) for i, j in found]
        return status, np.array(out, dtype=np.int64).reshape(-1, 3)

    def segment_pairs(self, const double[:, ::1] Q0, const double[:, ::1] Q1):
        """Every pair ``(row, i, j)`` the segment filter does not rule out (certain hits
        included): the pairs whose exact entry parameter gives the first contact."""
        cdef Py_ssize_t r
        cdef double lo[13]
        cdef double hi[13]
        out = []
        cdef list found
        for r in range(Q0.shape[0]):
            self._dop_segment(&Q0[r, 0], &Q1[r, 0], lo, hi)
            found = []
            self._traverse(lo, hi, &Q0[r, 0], &Q1[r, 0], True, found, 2)
            out += [(r, i, j) for i, j in found]
        return np.array(out, dtype=np.int64).reshape(-1, 3)

    def distances(self, const double[:, ::1] Q):
        """Per query (grid units, outside the union): the float distance, in grid units, to
        the nearest piece ``S_i ⊕ T_j`` (flat pairs of a closed operand left out), i.e. of
        triangle ``S_i`` to triangle ``Q - T_j``: a branch and bound over both trees, boxes
        giving the lower bounds. Not a decision (float throughout)."""
        cdef Py_ssize_t r, nq = Q.shape[0]
        out = np.empty(nq)
        cdef double[::1] o = out
        for r in range(nq):
            o[r] = self._nearest(&Q[r, 0])
        return out

    cdef double _nearest(self, const double* q) except? -1:
        cdef int a_stack[512]
        cdef int b_stack[512]
        cdef int top, a, b, k
        cdef Py_ssize_t x, y, i, j
        cdef double best = INFINITY, d
        cdef double tri[9]
        a_stack[0], b_stack[0] = 0, 0
        top = 1
        while top > 0:
            top -= 1
            a, b = a_stack[top], b_stack[top]
            if _box_gap2(&self.a_lo[a, 0], &self.a_hi[a, 0], &self.b_lo[b, 0],
                         &self.b_hi[b, 0], q) >= best:
                continue
            if self.a_count[a] > 0 and self.b_count[b] > 0:
                for x in range(self.a_first[a], self.a_first[a] + self.a_count[a]):
                    i = self.a_order[x]
                    for y in range(self.b_first[b], self.b_first[b] + self.b_count[b]):
                        j = self.b_order[y]
                        if self._flat_skipped(i, j):
                            continue
                        if _box_gap2(&self.a_blo[i, 0], &self.a_bhi[i, 0], &self.b_blo[j, 0],
                                     &self.b_bhi[j, 0], q) >= best:
                            continue
                        for k in range(9):
                            tri[k] = q[k % 3] - self.Tf[j, k]
                        d = _tri_tri_dist2(&self.Sf[i, 0], tri)
                        if d < best:
                            best = d
                continue
            top = self._split(a, b, a_stack, b_stack, top)
        return best ** 0.5

    cdef int _box(self, Py_ssize_t i, Py_ssize_t j, const double* lo, const double* hi,
                  bint apart) noexcept nogil:
        """The closed box [lo, hi] against the piece of (i, j), by the piece's slabs (each
        side's value and bound as :func:`_face_sides` and :func:`_sides`, the supports
        computed once per slab).

        ``apart`` False: 0 when the box is certainly not inside (its centre or a corner
        certainly beyond a side), 1 when certainly inside (its eight corners certainly
        inside every slab: the piece is convex), 2 undecided. ``apart`` True: 1 when the
        eight corners are certainly beyond one side of one slab (box and piece apart), else
        0."""
        cdef double P[27]
        cdef double val[2]
        cdef double err[2]
        cdef int64_t N[3 * 38]
        cdef double nf[3]
        cdef double slo, shi, sperm, tlo, thi, tperm, box, x, ax, up, dn, eu, ed
        cdef int n, k, c, p, first = 1 if apart else 0
        cdef bint unsure = False, beyond, all0, all1
        for c in range(3):  # the centre (rounded: still in the box), then the corners
            P[c] = (lo[c] + hi[c]) * 0.5
        for p in range(8):
            P[3 + 3 * p] = hi[0] if p & 4 else lo[0]
            P[4 + 3 * p] = hi[1] if p & 2 else lo[1]
            P[5 + 3 * p] = hi[2] if p & 1 else lo[2]
        n = _normals(&self.S[i, 0], &self.T[j, 0], self.grown, N)
        for k in range(-2, n):  # the two triangles' own slabs first
            if k >= 0:
                if N[3 * k] == 0 and N[3 * k + 1] == 0 and N[3 * k + 2] == 0:
                    continue
                for c in range(3):
                    nf[c] = <double>N[3 * k + c]
                _support(nf, &self.Sf[i, 0], &slo, &shi, &sperm)
                _support(nf, &self.Tf[j, 0], &tlo, &thi, &tperm)
                box = (fabs(nf[0]) * self.g[0] + fabs(nf[1]) * self.g[1]
                       + fabs(nf[2]) * self.g[2])
                up, dn = -(shi + thi + box), slo + tlo - box
                eu, ed = fabs(up) + sperm + tperm + box, fabs(dn) + sperm + tperm + box
            beyond, all0, all1 = False, True, True
            for p in range(first, 9):
                if k == -2:
                    _face_sides(&self.nsf[3 * i], &self.Sf[i, 0], &self.Tf[j, 0], self.g,
                                &P[3 * p], val, err)
                elif k == -1:
                    _face_sides(&self.ntf[3 * j], &self.Tf[j, 0], &self.Sf[i, 0], self.g,
                                &P[3 * p], val, err)
                else:  # as _sides, at this point
                    x = nf[0] * P[3 * p] + nf[1] * P[3 * p + 1] + nf[2] * P[3 * p + 2]
                    ax = (fabs(nf[0]) * fabs(P[3 * p]) + fabs(nf[1]) * fabs(P[3 * p + 1])
                          + fabs(nf[2]) * fabs(P[3 * p + 2]))
                    val[0], err[0] = x + up, _FILTER * (ax + eu) + _TINY
                    val[1], err[1] = -x + dn, _FILTER * (ax + ed) + _TINY
                all0 = all0 and val[0] > err[0]
                all1 = all1 and val[1] > err[1]
                beyond = beyond or val[0] > err[0] or val[1] > err[1]
                if p and not (val[0] < -err[0] and val[1] < -err[1]):
                    unsure = True
            if apart:
                if all0 or all1:
                    return 1
            elif beyond:
                return 0
        if apart:
            return 0
        return 2 if unsure else 1

    def boxes_inside(self, const double[:, ::1] lo, const double[:, ::1] hi):
        """Per query box ``[lo[row], hi[row]]`` (grid units): status 1 when it lies certainly
        inside one piece, 2 when no piece certainly holds it but some may (the undecided
        pairs ``(row, i, j)`` returned, for the exact test), 0 when none does (a box inside a
        piece lies inside the piece's k-DOP: node pairs whose k-DOP sum does not hold it are
        skipped)."""
        return self._rows(lo, hi, 5)

    def boxes_apart(self, const double[:, ::1] lo, const double[:, ::1] hi):
        """Per query box (grid units): 1 when every piece whose k-DOP meets it is certainly
        apart from it (:meth:`_box`): the box misses the union; else 0."""
        status, _ = self._rows(lo, hi, 4)
        return 1 - status

    def candidates(self, const double[:, ::1] lo, const double[:, ::1] hi):
        """Every pair ``(row, i, j)`` whose piece k-DOP meets the query box ``lo[row], hi[row]``
        (flat pairs of a closed operand left out); no slab is evaluated."""
        cdef Py_ssize_t r
        cdef double qlo[13]
        cdef double qhi[13]
        out = []
        cdef list found
        for r in range(lo.shape[0]):
            found = []
            self._dop(&lo[r, 0], &hi[r, 0], qlo, qhi)
            self._traverse(qlo, qhi, &lo[r, 0], &hi[r, 0], False, found, 1)
            out += [(r, i, j) for i, j in found]
        return np.array(out, dtype=np.int64).reshape(-1, 3)

    cdef int _split(self, int a, int b, int* a_stack, int* b_stack, int top) except -1:
        """Push the children of the node with the larger box (or of the inner one) paired with
        the other node; the new stack top."""
        if top + 2 > _STACK:
            raise RuntimeError("box tree deeper than the traversal stack")
        if self.b_count[b] > 0 or (self.a_count[a] == 0 and (
                self.a_hi[a, 0] - self.a_lo[a, 0] + self.a_hi[a, 1] - self.a_lo[a, 1]
                + self.a_hi[a, 2] - self.a_lo[a, 2]
                >= self.b_hi[b, 0] - self.b_lo[b, 0] + self.b_hi[b, 1] - self.b_lo[b, 1]
                + self.b_hi[b, 2] - self.b_lo[b, 2])):
            a_stack[top], b_stack[top] = self.a_first[a] + 1, b
            a_stack[top + 1], b_stack[top + 1] = self.a_first[a], b
        else:
            a_stack[top], b_stack[top] = a, self.b_first[b] + 1
            a_stack[top + 1], b_stack[top + 1] = a, self.b_first[b]
        return top + 2

    cdef int _traverse(self, const double* qlo, const double* qhi, const double* q0,
                       const double* q1, bint segment, list found, int mode) except -1:
        """Both trees together over the query box. mode 0: stop at the first pair certainly
        hit (1), else 2 with the undecided pairs in ``found``, else 0. mode 1: collect every
        candidate pair in ``found``. mode 2: collect every pair not certainly missed. mode 4
        (``q0``, ``q1`` a box's corners): 1 at the first candidate pair not certainly apart
        from the box (:meth:`_box`), else 0. mode 5 (``q0``, ``q1`` a box's corners, ``qlo``
        and ``qhi`` swapped by the caller: node pairs that hold the box): as mode 0, with
        :meth:`_box`'s inside test for the point's."""
        cdef int a_stack[512]
        cdef int b_stack[512]
        cdef int top = 0, status = 0, res, a, b
        cdef Py_ssize_t x, y, i, j
        cdef bint a_leaf, b_leaf
        a_stack[0], b_stack[0] = 0, 0
        top = 1
        while top > 0:
            top -= 1
            a, b = a_stack[top], b_stack[top]
            if not _boxes_meet(&self.a_lo[a, 0], &self.a_hi[a, 0], &self.b_lo[b, 0],
                               &self.b_hi[b, 0], qlo, qhi, self.K):
                continue
            a_leaf, b_leaf = self.a_count[a] > 0, self.b_count[b] > 0
            if a_leaf and b_leaf:
                for x in range(self.a_first[a], self.a_first[a] + self.a_count[a]):
                    i = self.a_order[x]
                    for y in range(self.b_first[b], self.b_first[b] + self.b_count[b]):
                        j = self.b_order[y]
                        if not _boxes_meet(&self.a_blo[i, 0], &self.a_bhi[i, 0],
                                           &self.b_blo[j, 0], &self.b_bhi[j, 0], qlo, qhi,
                                           self.K):
                            continue
                        if self._flat_skipped(i, j):
                            continue
                        if mode == 4 and not self._box(i, j, q0, q1, True):
                            return 1
                        if mode == 1:
                            found.append((i, j))
                            continue
                        res = (self._box(i, j, q0, q1, False) if mode == 5 else
                               self._segment(i, j, q0, q1) if segment else
                               self._point(i, j, q0))
                        if mode == 2:
                            if res != 0:
                                found.append((i, j))
                            continue
                        if res == 1:
                            return 1
                        if res == 2:
                            status = 2
                            found.append((i, j))
                continue
            top = self._split(a, b, a_stack, b_stack, top)
        return status

