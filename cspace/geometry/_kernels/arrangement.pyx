# cython: language_level=3, boundscheck=False, wraparound=False, cdivision=True, initializedcheck=False
"""Compiled kernel of :mod:`cspace.geometry.tritri`: the box sweep's candidate pairs
(:func:`sweep_pairs`), the exact classification of triangle pairs (:func:`intersect_pairs`)
and the exact coordinates of their symbolic endpoints (:func:`endpoint_coordinates`).

They return exactly what the numpy references return (``BoxSweep._pairs_reference``,
``cspace.geometry.tritri._intersect_pairs_reference`` and ``_endpoint_coordinates_reference``;
``tests/test_kernels_intersections.py``): the same per-pair logic, written pair by pair
instead of vectorised over the pairs, with the same tie-breaks (first index of a minimum).

Every decision is the exact sign of an integer polynomial, evaluated in 64- or 128-bit
integers (``__int128``, GCC and Clang): the inputs are grid integers with ``|k| < 2**29``
(checked by the Python wrappers), and each predicate's bound below keeps every intermediate
value exact. So there is no float filter and no fallback: every sign is the exact one at
once. (A filter does not pay here: one ``orient3d`` is six 64-bit and three 64x64->128-bit
products, no dearer than its float value and permanent; measured, a filtered variant
classified the pairs of Centaur-1000 + ico320 no faster.) Bounds, with ``|k| < 2**29``:

- coordinate differences: ``|d| <= 2**30 - 2 < 2**30``;
- products of two differences: ``< 2**60``; a 2x2 minor or ``orient2d``: ``< 2**61``
  (int64); a face normal ``(b - a) x (c - a)`` likewise ``|N_i| < 2**61``;
- ``orient3d``: three terms ``|d| * |minor| < 2**91``, the sum ``< 2**93`` (int128);
- a side of a plane ``N . (x - a)``: three terms ``< 2**61 * 2**30``, the sum ``< 2**93``;
- a dot product of two differences: ``< 3 * 2**60 < 2**62`` (int64);
- an edge-plane point ``(s_u v - s_v u) / (s_u - s_v)``: ``|s| < 2**93``, ``|v| < 2**29``,
  so ``|X|, |Y|, |Z| < 2**123`` and ``0 < W < 2**94`` (int128; the gcd in unsigned int128).

Floats appear only in the output ``approx`` of :func:`endpoint_coordinates`: ``X / W``
correctly rounded (:func:`_quotient`, integer long division and round-to-nearest-even), the
value of the reference's Python ``int / int``.
"""

import numpy as np

from cpython.long cimport PyLong_FromLongLong
from libc.limits cimport LLONG_MAX, LLONG_MIN
from libc.math cimport ldexp
from libc.stdlib cimport calloc, free, malloc, qsort, realloc

cdef extern from *:
    """
    typedef __int128 cs_i128;
    typedef unsigned __int128 cs_u128;
    """
    # Cython sees them as 64-bit types; they are only ever used in C arithmetic here and
    # converted to Python explicitly (_pylong), never implicitly.
    ctypedef long long i128 "cs_i128"
    ctypedef unsigned long long u128 "cs_u128"
    int __builtin_ctzll(unsigned long long) nogil  # GCC and Clang, as __int128
    int __builtin_clzll(unsigned long long) nogil
    object _PyLong_FromByteArray(const unsigned char*, size_t, int, int)  # CPython's int.from_bytes

# As cspace.geometry.tritri's module constants (a test checks they agree).
cdef enum:
    DISJOINT = 0
    SHARED_EDGE = 1
    SHARED_VERTEX = 2
    POINT = 3
    SEGMENT = 4
    COPLANAR_OVERLAP = 5
    COPLANAR_TOUCH = 6
    NO_POINT = 0
    VERTEX = 1
    EDGE_PLANE = 2
    S_EMPTY = 0     # side-table status (cspace.geometry.tritri._EMPTY ...)
    S_COPLANAR = 1
    S_SINGLE = 2
    S_INTERVAL = 3


#: The codes above by name, for the test that they are cspace.geometry.tritri's.
CODES = {
    "DISJOINT": DISJOINT, "SHARED_EDGE": SHARED_EDGE, "SHARED_VERTEX": SHARED_VERTEX,
    "POINT": POINT, "SEGMENT": SEGMENT, "COPLANAR_OVERLAP": COPLANAR_OVERLAP,
    "COPLANAR_TOUCH": COPLANAR_TOUCH, "NO_POINT": NO_POINT, "VERTEX": VERTEX,
    "EDGE_PLANE": EDGE_PLANE, "_EMPTY": S_EMPTY, "_COPLANAR": S_COPLANAR, "_SINGLE": S_SINGLE,
    "_INTERVAL": S_INTERVAL,
}


# --------------------------------------------------------------------------------------
# exact predicates on grid points (pointers to three int64 coordinates, |k| < 2**29)


cdef inline int _sgn(i128 x) noexcept nogil:
    return (x > 0) - (x < 0)


cdef inline int _orient3d(const long long* a, const long long* b, const long long* c,
                          const long long* d) noexcept nogil:
    """sign(det[b - a; c - a; d - a]), as cspace.geometry.exact.orient3d: int64 minors (< 2**61),
    int128 sum (< 2**93)."""
    cdef long long ux = b[0] - a[0], uy = b[1] - a[1], uz = b[2] - a[2]
    cdef long long vx = c[0] - a[0], vy = c[1] - a[1], vz = c[2] - a[2]
    cdef long long wx = d[0] - a[0], wy = d[1] - a[1], wz = d[2] - a[2]
    cdef long long m0 = vy * wz - vz * wy, m1 = vz * wx - vx * wz, m2 = vx * wy - vy * wx
    return _sgn(<i128> ux * m0 + <i128> uy * m1 + <i128> uz * m2)


cdef inline int _orient2d(const long long* a, const long long* b, const long long* c, int k1,
                          int k2) noexcept nogil:
    """cspace.geometry.exact.orient2d of the points projected to coordinates ``(k1, k2)`` (the
    reference's ``_project``): sign((b - a) x (c - a)), exact in int64 (< 2**61)."""
    cdef long long det = (b[k1] - a[k1]) * (c[k2] - a[k2]) - (b[k2] - a[k2]) * (c[k1] - a[k1])
    return (det > 0) - (det < 0)


cdef inline int _side(const long long* N, const long long* a, const long long* x) noexcept nogil:
    """sign(N . (x - a)) for a face normal ``N`` (|N_i| < 2**61): int128 sum (< 2**93)."""
    return _sgn(<i128> N[0] * (x[0] - a[0]) + <i128> N[1] * (x[1] - a[1])
                + <i128> N[2] * (x[2] - a[2]))


cdef inline int _dot_sign(const long long* p, const long long* a, const long long* b) noexcept nogil:
    """sign((a - p) . (b - p)), exact in int64 (< 3 * 2**60)."""
    cdef long long d = ((a[0] - p[0]) * (b[0] - p[0]) + (a[1] - p[1]) * (b[1] - p[1])
                        + (a[2] - p[2]) * (b[2] - p[2]))
    return (d > 0) - (d < 0)


cdef inline long long _abs(long long x) noexcept nogil:
    return -x if x < 0 else x


cdef inline int _argmax_abs(const long long* N) noexcept nogil:
    """numpy's ``np.abs(N).argmax()``: the first index of the largest magnitude."""
    cdef int k = 0
    if _abs(N[1]) > _abs(N[k]):
        k = 1
    if _abs(N[2]) > _abs(N[k]):
        k = 2
    return k


cdef inline int _sign64(long long x) noexcept nogil:
    return (x > 0) - (x < 0)


# --------------------------------------------------------------------------------------
# the box sweep (BoxSweep._pairs_reference)


cdef int _cmp_ll(const void* a, const void* b) noexcept nogil:
    cdef long long x = (<const long long*> a)[0], y = (<const long long*> b)[0]
    return (x > y) - (x < y)


def sweep_pairs(Py_ssize_t start, Py_ssize_t end, Py_ssize_t t, const long long[::1] order,
                const long long[::1] cum, const int[::1] lo1, const int[::1] hi1,
                const int[::1] lo2, const int[::1] hi2):
    """The box-overlap pairs of sweep rows ``[start, end)``: row ``p`` meets rows
    ``p + 1 .. p + cum[p] - cum[p - 1]`` along the sweep axis and is tested on the two others
    (``lo1, hi1``, ``lo2, hi2``, in sweep order). Rows ``(i, j)``, ``i < j`` (triangle ids
    ``order[p]``), sorted lexicographically: ``(k, 2)`` int64."""
    cdef Py_ssize_t cap = 1024, m = 0, p, q, qend
    cdef long long i, j
    cdef long long* buf = <long long*> malloc(2 * cap * sizeof(long long))
    cdef long long* cnt = <long long*> calloc(t + 1, sizeof(long long))
    cdef long long* tmp
    cdef int l1, h1, l2, h2
    if not buf or not cnt:
        free(buf)
        free(cnt)
        raise MemoryError()
    try:
        for p in range(start, end):
            qend = p + 1 + cum[p] - (cum[p - 1] if p else 0)
            l1, h1, l2, h2 = lo1[p], hi1[p], lo2[p], hi2[p]
            for q in range(p + 1, qend):
                # Bitwise, not short-circuit: each test is a coin flip, a branch mispredicts.
                if (lo1[q] <= h1) & (l1 <= hi1[q]) & (lo2[q] <= h2) & (l2 <= hi2[q]):
                    if m == cap:
                        cap *= 2
                        tmp = <long long*> realloc(buf, 2 * cap * sizeof(long long))
                        if not tmp:
                            raise MemoryError()
                        buf = tmp
                    i, j = order[p], order[q]
                    if j < i:
                        i, j = j, i
                    buf[2 * m] = i
                    buf[2 * m + 1] = j
                    cnt[i + 1] += 1
                    m += 1
        out = np.empty((m, 2), dtype=np.int64)
        _sort_pairs(buf, m, cnt, t, out)
        return out
    finally:
        free(buf)
        free(cnt)


cdef void _sort_pairs(const long long* buf, Py_ssize_t m, long long* cnt, Py_ssize_t t,
                      long long[:, ::1] out) noexcept nogil:
    """Write the pairs ``buf`` (``(i, j)`` rows) sorted into ``out``: a counting sort by
    ``i`` (``cnt[i + 1]`` holds the number of rows with that ``i``), then each run of equal
    ``i`` by ``j`` (a triangle's partners: short runs, insertion sort; qsort for long ones)."""
    cdef Py_ssize_t k, r, s, e
    for k in range(t):
        cnt[k + 1] += cnt[k]
    # cnt[i] is now the next free output row of i.
    for r in range(m):
        k = buf[2 * r]
        s = cnt[k]
        cnt[k] = s + 1
        out[s, 0] = k
        out[s, 1] = buf[2 * r + 1]
    s = 0
    while s < m:
        e = s + 1
        while e < m and out[e, 0] == out[s, 0]:
            e += 1
        if e - s > 32:
            _qsort_column(out, s, e)
        else:
            _insertion_column(out, s, e)
        s = e


cdef void _qsort_column(long long[:, ::1] out, Py_ssize_t s, Py_ssize_t e) noexcept nogil:
    """Sort ``out[s:e, 1]`` (rows of equal ``out[:, 0]``) through a scratch buffer."""
    cdef Py_ssize_t r, n = e - s
    cdef long long* tmp = <long long*> malloc(n * sizeof(long long))
    if not tmp:  # pragma: no cover - out of memory: fall back to insertion sort
        _insertion_column(out, s, e)
        return
    for r in range(n):
        tmp[r] = out[s + r, 1]
    qsort(tmp, n, sizeof(long long), _cmp_ll)
    for r in range(n):
        out[s + r, 1] = tmp[r]
    free(tmp)


cdef void _insertion_column(long long[:, ::1] out, Py_ssize_t s, Py_ssize_t e) noexcept nogil:
    """Sort ``out[s:e, 1]`` in place (insertion sort: the runs are short)."""
    cdef Py_ssize_t r, a
    cdef long long x
    for r in range(s + 1, e):
        x = out[r, 1]
        a = r
        while a > s and out[a - 1, 1] > x:
            out[a, 1] = out[a - 1, 1]
            a -= 1
        out[a, 1] = x


# --------------------------------------------------------------------------------------
# step 5: the exact class of each pair (cspace.geometry.tritri._intersect_pairs_reference)


cdef struct _Ctx:
    const long long* P      # ints (n, 3)
    const long long* F      # faces (t, 3)
    const long long* N      # face normals (t, 3), |N_i| < 2**61
    const signed char* status  # side tables (27,) and (27, 2, 4) as cspace.geometry.tritri
    const long long* ends
    signed char* cls        # outputs, (k,) and (k, 2) row-major
    signed char* kind
    long long* u
    long long* v
    long long* plane


cdef inline const long long* _pt(const _Ctx* c, long long label) noexcept nogil:
    return c.P + 3 * label


cdef inline void _set_vertices(const _Ctx* c, Py_ssize_t r, int cls, long long a,
                               long long b) noexcept nogil:
    """The reference's ``_Out.set_vertices``: class, both kinds VERTEX, ``u = (a, b)``."""
    c.cls[r] = cls
    c.kind[2 * r] = VERTEX
    c.kind[2 * r + 1] = VERTEX
    c.u[2 * r] = a
    c.u[2 * r + 1] = b


cdef inline void _set_point(const _Ctx* c, Py_ssize_t r, int col, int kind, long long u,
                            long long v, long long plane) noexcept nogil:
    c.kind[2 * r + col] = kind
    c.u[2 * r + col] = u
    c.v[2 * r + col] = v
    c.plane[2 * r + col] = plane


cdef inline bint _has(const long long* F, long long x) noexcept nogil:
    return F[0] == x or F[1] == x or F[2] == x


cdef inline void _shared_edge(const _Ctx* c, Py_ssize_t r, const long long* F,
                              const bint* sh) noexcept nogil:
    """SHARED_EDGE between the smallest and the largest shared label of ``F``."""
    cdef long long a = LLONG_MAX, b = -1
    cdef int i
    for i in range(3):
        if sh[i]:
            if F[i] < a:
                a = F[i]
            if F[i] > b:
                b = F[i]
    _set_vertices(c, r, SHARED_EDGE, a, b)


cdef inline int _first(const bint* x) noexcept nogil:
    """numpy's ``argmax`` of three booleans: the first True, else 0."""
    return 0 if x[0] else (1 if x[1] else (2 if x[2] else 0))


cdef inline int _index_of(const long long* F, long long x) noexcept nogil:
    return 0 if F[0] == x else (1 if F[1] == x else (2 if F[2] == x else 0))


cdef inline int _pattern(const int* s) noexcept nogil:
    return 9 * (s[0] + 1) + 3 * (s[1] + 1) + (s[2] + 1)


cdef inline long long _end(const _Ctx* c, int pat, int which, int field) noexcept nogil:
    return c.ends[(pat * 2 + which) * 4 + field]


cdef void _proper(const _Ctx* c, Py_ssize_t r, long long ta, long long tb) noexcept nogil:
    """``_proper``: two non-zero-area triangles."""
    cdef const long long* FA = c.F + 3 * ta
    cdef const long long* FB = c.F + 3 * tb
    cdef bint shA[3]
    cdef bint shB[3]
    cdef int sA[3]
    cdef int sB[3]
    cdef int i, nsh = 0, pa, pb, sta, stb
    for i in range(3):
        shA[i] = _has(FB, FA[i])
        shB[i] = _has(FA, FB[i])
        nsh += shA[i]
    _plane_signs(c, FA, shA, tb, sA)
    if sA[0] == 0 and sA[1] == 0 and sA[2] == 0:
        _coplanar_proper(c, r, ta, tb, shA, nsh)
        return
    if nsh == 2:  # not coplanar: X is exactly the shared edge (proof in the reference)
        _shared_edge(c, r, FA, shA)
        return
    pa = _pattern(sA)
    if _settled_by_plane(c, r, FA, shA, pa):
        return
    # B cannot be coplanar with A here: A has a corner off B's plane.
    _plane_signs(c, FB, shB, ta, sB)
    pb = _pattern(sB)
    if _settled_by_plane(c, r, FB, shB, pb):
        return
    sta, stb = c.status[pa], c.status[pb]
    _interval(c, r, ta, tb, pa, pb, sta, stb)


cdef inline void _plane_signs(const _Ctx* c, const long long* F, const bint* sh, long long t,
                              int* s) noexcept nogil:
    """Signs of the corners ``F`` against the plane of face ``t``; a shared label lies on
    that plane: 0 without computation."""
    cdef int i
    for i in range(3):
        s[i] = 0 if sh[i] else _side(c.N + 3 * t, _pt(c, c.F[3 * t]), _pt(c, F[i]))


cdef inline bint _settled_by_plane(const _Ctx* c, Py_ssize_t r, const long long* F,
                                   const bint* sh, int pat) noexcept nogil:
    """Classify the pair from how ``F`` meets the other's plane (sign pattern ``pat``) when
    that alone decides: it misses the plane (DISJOINT), or meets it only at a shared vertex,
    which is then in the other triangle (SHARED_VERTEX)."""
    cdef int st = c.status[pat], z = <int> _end(c, pat, 0, 1)
    if st == S_EMPTY:
        c.cls[r] = DISJOINT
        return True
    if st == S_SINGLE and sh[z]:
        _set_vertices(c, r, SHARED_VERTEX, F[z], F[z])
        return True
    return False


cdef inline int _cmp(const _Ctx* c, const long long* FA, const long long* ea,
                     const long long* FB, const long long* eb) noexcept nogil:
    """sign(d . (Q - P)) for the end ``ea`` of A and ``eb`` of B (descriptors
    ``(kind, i, j, f)``): one orient3d times the two known factors (module docstring of
    cspace.geometry.tritri); identical vertices give 0 without computation."""
    cdef long long p = FA[ea[1]], q = FA[ea[2]], r = FB[eb[1]], s = FB[eb[2]]
    if ea[0] == VERTEX and eb[0] == VERTEX and p == r:
        return 0
    return _orient3d(_pt(c, p), _pt(c, q), _pt(c, r), _pt(c, s)) * <int> ea[3] * <int> eb[3]


cdef inline void _key(const long long* F, const long long* e, long long* key) noexcept nogil:
    """The reference's description key, as the pair (rank, a, b): a vertex ``p`` is
    ``(0, p, 0)``, an edge ``(p, q)`` is ``(1, min, max)``; ordered as the reference's
    ``p`` and ``n + min * n + max`` (which is below ``n`` exactly for vertices)."""
    cdef long long p = F[e[1]], q = F[e[2]]
    if e[0] == VERTEX:
        key[0], key[1], key[2] = 0, p, 0
    else:
        key[0], key[1], key[2] = 1, (p if p < q else q), (q if p < q else p)


cdef inline bint _less(const long long* a, const long long* b) noexcept nogil:
    return a[0] < b[0] or (a[0] == b[0] and (a[1] < b[1] or (a[1] == b[1] and a[2] < b[2])))


cdef void _interval(const _Ctx* c, Py_ssize_t r, long long ta, long long tb, int pa, int pb,
                    int sta, int stb) noexcept nogil:
    """``_interval``: the overlap of the two segments on the common line, by four orient3d."""
    cdef const long long* FA = c.F + 3 * ta
    cdef const long long* FB = c.F + 3 * tb
    # Descriptors: A's ends along d = N_A x N_B, B's along N_B x N_A = -d; in the
    # reference's order (A_lo, B_lo, A_hi, B_hi).
    cdef const long long* desc[4]
    desc[0] = c.ends + (pa * 2 + 0) * 4
    desc[1] = c.ends + (pb * 2 + 1) * 4
    desc[2] = c.ends + (pa * 2 + 1) * 4
    desc[3] = c.ends + (pb * 2 + 0) * 4
    cdef int c_lh = _cmp(c, FA, desc[0], FB, desc[3])
    if c_lh < 0:
        c.cls[r] = DISJOINT
        return
    cdef int c_hl = _cmp(c, FA, desc[2], FB, desc[1])
    if c_hl > 0:
        c.cls[r] = DISJOINT
        return
    cdef int c_ll = _cmp(c, FA, desc[0], FB, desc[1])
    cdef int c_hh = _cmp(c, FA, desc[2], FB, desc[3])
    cdef bint loA = c_ll <= 0, loB = c_ll >= 0  # which lows are the maximum
    cdef bint hiA = c_hh >= 0, hiB = c_hh <= 0  # which highs are the minimum
    cdef bint pt = ((loA and hiA and sta == S_SINGLE) or (loB and hiB and stb == S_SINGLE)
                    or (loA and hiB and c_lh == 0) or (loB and hiA and c_hl == 0))
    cdef bint cand[2][4]
    cand[0][0], cand[0][1], cand[0][2], cand[0][3] = loA, loB, pt and hiA, pt and hiB
    cand[1][0], cand[1][1], cand[1][2], cand[1][3] = pt and loA, pt and loB, hiA, hiB
    cdef long long keys[4][3]
    cdef int col, k, pick
    cdef const long long* F
    cdef const long long* e
    cdef long long p, q, lab
    for k in range(4):
        _key(FB if k & 1 else FA, desc[k], keys[k])
    for col in range(2):
        # The reference's argmin over the candidates (first of equal keys); one of the two
        # lows (highs) is always a candidate.
        pick = -1
        for k in range(4):
            if cand[col][k] and (pick < 0 or _less(keys[k], keys[pick])):
                pick = k
        if pick < 0:  # pragma: no cover - unreachable (see above)
            pick = 0
        e = desc[pick]
        F = FB if pick & 1 else FA
        p, q = F[e[1]], F[e[2]]
        if e[0] == VERTEX:
            _set_point(c, r, col, VERTEX, p, -1, -1)
        else:  # the edge of one triangle crosses the other's plane
            _set_point(c, r, col, EDGE_PLANE, p if p < q else q, q if p < q else p,
                       ta if pick & 1 else tb)
    if not pt:
        c.cls[r] = SEGMENT
        return
    lab = c.u[2 * r]
    c.cls[r] = (SHARED_VERTEX if c.kind[2 * r] == VERTEX and _has(FA, lab) and _has(FB, lab)
                else POINT)


cdef void _coplanar_proper(const _Ctx* c, Py_ssize_t r, long long ta, long long tb,
                           const bint* shA, int nsh) noexcept nogil:
    """``_coplanar_proper``: overlap, touch or disjoint in 2D (dominant axis of N_A dropped)."""
    cdef const long long* FA = c.F + 3 * ta
    cdef const long long* FB = c.F + 3 * tb
    cdef const long long* NA = c.N + 3 * ta
    cdef const long long* NB = c.N + 3 * tb
    cdef int axis = _argmax_abs(NA)
    cdef int k1 = (axis + 1) % 3, k2 = (axis + 2) % 3
    # In the cyclic projection the 2D orientation of a triangle is the sign of N[axis].
    cdef int sgA = _sign64(NA[axis]), sgB = _sign64(NB[axis])
    cdef int oA[3][3]
    cdef int oB[3][3]
    _edge_signs(c, FA, sgA, FB, k1, k2, oA)
    _edge_signs(c, FB, sgB, FA, k1, k2, oB)
    # The reference's separating axes: overlap iff every edge has a corner strictly inside.
    cdef bint overlap = not _outer_edge(oA, False) and not _outer_edge(oB, False)
    cdef bint disjoint = _outer_edge(oA, True) or _outer_edge(oB, True)
    if disjoint:  # the reference assigns DISJOINT last (the two never hold together)
        c.cls[r] = DISJOINT
        return
    if overlap:
        c.cls[r] = COPLANAR_OVERLAP
        return
    if nsh == 0:
        c.cls[r] = COPLANAR_TOUCH
        return
    if nsh >= 2:  # three shared labels always overlap
        _shared_edge(c, r, FA, shA)
        return
    cdef int ia = _first(shA), da, db
    cdef long long v = FA[ia]
    cdef int ib = _index_of(FB, v)
    cdef const long long* pv = _pt(c, v)
    cdef const long long* a
    cdef const long long* b
    # One shared vertex: a common ray (an edge of each, collinear, same direction) touches.
    for da in range(1, 3):
        a = _pt(c, FA[(ia + da) % 3])
        for db in range(1, 3):
            b = _pt(c, FB[(ib + db) % 3])
            if _orient2d(a, pv, b, k1, k2) == 0 and _dot_sign(pv, a, b) > 0:
                c.cls[r] = COPLANAR_TOUCH
                return
    _set_vertices(c, r, SHARED_VERTEX, v, v)


cdef void _edge_signs(const _Ctx* c, const long long* F1, int sg1, const long long* F2, int k1,
                      int k2, int o[3][3]) noexcept nogil:
    """Signs of the corners of 2 against the edges of 1, inside > 0 (0 for an edge's own
    labels)."""
    cdef int e, e1, j
    for e in range(3):
        e1 = (e + 1) % 3
        for j in range(3):
            if F2[j] == F1[e] or F2[j] == F1[e1]:
                o[e][j] = 0
            else:
                o[e][j] = _orient2d(_pt(c, F1[e]), _pt(c, F1[e1]), _pt(c, F2[j]), k1, k2) * sg1


cdef inline bint _outer_edge(int o[3][3], bint strict) noexcept nogil:
    """Whether some edge has the three corners of the other triangle on its outer side:
    strictly (``o < 0``, a separating edge) or closed (``o <= 0``, interiors apart)."""
    cdef int e
    for e in range(3):
        if strict and o[e][0] < 0 and o[e][1] < 0 and o[e][2] < 0:
            return True
        if not strict and o[e][0] <= 0 and o[e][1] <= 0 and o[e][2] <= 0:
            return True
    return False


cdef void _extremes(const _Ctx* c, const long long* F, int* lo, int* hi, int* axis) noexcept nogil:
    """``_extremes``: the corners at the ends of a collinear triple, along the axis of its
    largest extent (first maximum; first minimum and maximum corner along it)."""
    cdef const long long* P0 = _pt(c, F[0])
    cdef long long d[3]
    cdef long long x
    cdef int k, j
    for k in range(3):
        d[k] = 0
        for j in range(3):
            x = _abs(_pt(c, F[j])[k] - P0[k])
            if x > d[k]:
                d[k] = x
    k = 0
    if d[1] > d[k]:
        k = 1
    if d[2] > d[k]:
        k = 2
    axis[0] = k
    lo[0] = hi[0] = 0
    for j in range(1, 3):
        x = _pt(c, F[j])[k]
        if x < _pt(c, F[lo[0]])[k]:
            lo[0] = j
        if x > _pt(c, F[hi[0]])[k]:
            hi[0] = j


cdef void _segment_triangle(const _Ctx* c, Py_ssize_t r, long long ts, long long tt) noexcept nogil:
    """``_segment_triangle``: a zero-area triangle ``ts`` (a segment) and a proper ``tt``."""
    cdef const long long* FS = c.F + 3 * ts
    cdef const long long* FT = c.F + 3 * tt
    cdef bint shS[3]
    cdef int s[3]
    cdef int i, j, e, z, helper, nz = 0, npos = 0, nneg = 0
    for i in range(3):
        shS[i] = _has(FT, FS[i])
    _plane_signs(c, FS, shS, tt, s)
    for i in range(3):
        nz += s[i] == 0
        npos += s[i] > 0
        nneg += s[i] < 0
    if nz == 3:
        _segment_triangle_coplanar(c, r, ts, tt, shS)
        return
    if nz == 0 and not (npos and nneg):
        c.cls[r] = DISJOINT
        return
    # The point P where the segment's line meets the plane: a vertex with sign 0 (at most
    # one), else the crossing edge with the smallest label pair.
    z = 0 if s[0] == 0 else (1 if s[1] == 0 else (2 if s[2] == 0 else 0))
    helper = 0 if s[0] != 0 else (1 if s[1] != 0 else (2 if s[2] != 0 else 0))
    cdef long long lo_, hi_, best_lo = LLONG_MAX, best_hi = LLONG_MAX
    e = 0
    for i in range(3):
        j = (i + 1) % 3
        if s[i] * s[j] < 0:
            lo_ = FS[i] if FS[i] < FS[j] else FS[j]
            hi_ = FS[j] if FS[i] < FS[j] else FS[i]
            if lo_ < best_lo or (lo_ == best_lo and hi_ < best_hi):
                best_lo, best_hi, e = lo_, hi_, i
    cdef bint hasz = nz > 0
    cdef long long p = FS[z] if hasz else FS[e]
    cdef long long q = FS[helper] if hasz else FS[(e + 1) % 3]
    cdef int o[3]
    cdef int opos = 0, oneg = 0
    for i in range(3):
        o[i] = _orient3d(_pt(c, p), _pt(c, q), _pt(c, FT[i]), _pt(c, FT[(i + 1) % 3]))
        opos += o[i] > 0
        oneg += o[i] < 0
    if opos and oneg:
        c.cls[r] = DISJOINT
        return
    # Two zero edges: P is their common vertex of the triangle (edge i = (i, i + 1)).
    cdef bint at_t = (o[0] == 0) + (o[1] == 0) + (o[2] == 0) == 2
    cdef int tv = 1 if (o[0] == 0 and o[1] == 0) else (2 if (o[1] == 0 and o[2] == 0) else 0)
    cdef bint isv = hasz or at_t
    cdef long long lab = FT[tv] if at_t else FS[z]
    cdef int col
    for col in range(2):
        if isv:
            _set_point(c, r, col, VERTEX, lab, -1, -1)
        else:
            _set_point(c, r, col, EDGE_PLANE, p if p < q else q, q if p < q else p, tt)
    c.cls[r] = SHARED_VERTEX if (isv and _has(FS, lab) and _has(FT, lab)) else POINT


cdef void _segment_triangle_coplanar(const _Ctx* c, Py_ssize_t r, long long ts, long long tt,
                                     const bint* shS) noexcept nogil:
    """``_segment_triangle_coplanar``: a segment in the plane of a proper triangle, in 2D."""
    cdef const long long* FS = c.F + 3 * ts
    cdef const long long* FT = c.F + 3 * tt
    cdef const long long* N = c.N + 3 * tt
    cdef int axis = _argmax_abs(N)
    cdef int k1 = (axis + 1) % 3, k2 = (axis + 2) % 3
    cdef int sg = _sign64(N[axis])
    cdef int ip, iq, kk, e, j, npos = 0, nneg = 0, o
    _extremes(c, FS, &ip, &iq, &kk)
    cdef const long long* p2 = _pt(c, FS[ip])
    cdef const long long* q2 = _pt(c, FS[iq])
    cdef const long long* e0
    cdef const long long* e1
    for e in range(3):
        e0, e1 = _pt(c, FT[e]), _pt(c, FT[(e + 1) % 3])
        if _orient2d(e0, e1, p2, k1, k2) * sg < 0 and _orient2d(e0, e1, q2, k1, k2) * sg < 0:
            c.cls[r] = DISJOINT
            return
    for j in range(3):
        o = _orient2d(p2, q2, _pt(c, FT[j]), k1, k2)
        npos += o > 0
        nneg += o < 0
    if npos == 3 or nneg == 3:
        c.cls[r] = DISJOINT
        return
    cdef int nsh = shS[0] + shS[1] + shS[2]
    if nsh == 0:
        c.cls[r] = COPLANAR_TOUCH
        return
    if nsh == 2:
        _shared_edge(c, r, FS, shS)
        return
    if nsh != 1:  # three shared labels cannot happen; left unclassified as the reference
        return
    cdef int i_s = _first(shS), dw
    cdef long long v = FS[i_s]
    cdef int i_t = _index_of(FT, v)
    cdef const long long* v2 = _pt(c, v)
    cdef const long long* a2 = _pt(c, FT[(i_t + 1) % 3])
    cdef const long long* b2 = _pt(c, FT[(i_t + 2) % 3])
    cdef const long long* w2
    for dw in range(1, 3):  # _cone_hits: the closed corner cone at v
        w2 = _pt(c, FS[(i_s + dw) % 3])
        if _orient2d(v2, a2, w2, k1, k2) * sg >= 0 and _orient2d(v2, w2, b2, k1, k2) * sg >= 0:
            c.cls[r] = COPLANAR_TOUCH
            return
    _set_vertices(c, r, SHARED_VERTEX, v, v)


cdef void _segment_segment(const _Ctx* c, Py_ssize_t r, long long ta, long long tb) noexcept nogil:
    """``_segment_segment``: two zero-area triangles (segments)."""
    cdef const long long* FA = c.F + 3 * ta
    cdef const long long* FB = c.F + 3 * tb
    cdef int ia0, ia1, k, ib0, ib1, kb, i, nsh = 0
    _extremes(c, FA, &ia0, &ia1, &k)
    _extremes(c, FB, &ib0, &ib1, &kb)
    cdef const long long* pa = _pt(c, FA[ia0])
    cdef const long long* qa = _pt(c, FA[ia1])
    cdef const long long* pb = _pt(c, FB[ib0])
    cdef const long long* qb = _pt(c, FB[ib1])
    if _orient3d(pa, qa, pb, qb) != 0:  # skew lines
        c.cls[r] = DISJOINT
        return
    cdef bint shA[3]
    for i in range(3):
        shA[i] = _has(FB, FA[i])
        nsh += shA[i]
    # A normal of the common plane: (qa - pa) x (pb - pa), else (qa - pa) x (qb - pa)
    # (|.| < 2**61, int64).
    cdef long long ux = qa[0] - pa[0], uy = qa[1] - pa[1], uz = qa[2] - pa[2]
    cdef long long w[3]
    cdef long long nrm[3]
    for i in range(3):
        w[i] = pb[i] - pa[i]
    nrm[0], nrm[1], nrm[2] = uy * w[2] - uz * w[1], uz * w[0] - ux * w[2], ux * w[1] - uy * w[0]
    if nrm[0] == 0 and nrm[1] == 0 and nrm[2] == 0:
        for i in range(3):
            w[i] = qb[i] - pa[i]
        nrm[0], nrm[1], nrm[2] = uy * w[2] - uz * w[1], uz * w[0] - ux * w[2], ux * w[1] - uy * w[0]
    cdef int axis, k1, k2
    cdef bint meet
    if nrm[0] != 0 or nrm[1] != 0 or nrm[2] != 0:  # one plane, two lines: at most one point
        axis = _argmax_abs(nrm)
        k1, k2 = (axis + 1) % 3, (axis + 2) % 3
        meet = (_orient2d(pa, qa, pb, k1, k2) * _orient2d(pa, qa, qb, k1, k2) <= 0
                and _orient2d(pb, qb, pa, k1, k2) * _orient2d(pb, qb, qa, k1, k2) <= 0)
        if not meet:
            c.cls[r] = DISJOINT
        elif nsh == 0:
            c.cls[r] = COPLANAR_TOUCH
        else:
            _set_vertices(c, r, SHARED_VERTEX, FA[_first(shA)], FA[_first(shA)])
        return
    # One line: compare the corners' coordinates along A's axis of largest extent.
    cdef long long ca[3]
    cdef long long cb[3]
    for i in range(3):
        ca[i] = _pt(c, FA[i])[k]
        cb[i] = _pt(c, FB[i])[k]
    cdef long long lo = _max3min(ca, cb), hi = _min3max(ca, cb)
    if lo > hi:
        c.cls[r] = DISJOINT
        return
    cdef bint at_lo[3]
    cdef bint at_hi[3]
    for i in range(3):
        at_lo[i] = shA[i] and ca[i] == lo
        at_hi[i] = shA[i] and ca[i] == hi
    if not ((at_lo[0] or at_lo[1] or at_lo[2]) and (at_hi[0] or at_hi[1] or at_hi[2])):
        c.cls[r] = COPLANAR_TOUCH
        return
    cdef long long lab_lo = FA[_first(at_lo)], lab_hi = FA[_first(at_hi)]
    if lo < hi:
        _set_vertices(c, r, SHARED_EDGE, lab_lo if lab_lo < lab_hi else lab_hi,
                      lab_hi if lab_lo < lab_hi else lab_lo)
    else:
        _set_vertices(c, r, SHARED_VERTEX, lab_lo, lab_lo)


cdef inline long long _max3min(const long long* a, const long long* b) noexcept nogil:
    """max(min(a), min(b)) of two triples."""
    cdef long long x = a[0], y = b[0]
    cdef int i
    for i in range(1, 3):
        if a[i] < x:
            x = a[i]
        if b[i] < y:
            y = b[i]
    return x if x > y else y


cdef inline long long _min3max(const long long* a, const long long* b) noexcept nogil:
    """min(max(a), max(b)) of two triples."""
    cdef long long x = a[0], y = b[0]
    cdef int i
    for i in range(1, 3):
        if a[i] > x:
            x = a[i]
        if b[i] > y:
            y = b[i]
    return x if x < y else y


def intersect_pairs(const long long[:, ::1] ints, const long long[:, ::1] faces,
                    const long long[:, ::1] pairs, const signed char[::1] status,
                    const long long[:, :, ::1] ends):
    """``(cls, kind, u, v, plane)`` of :class:`cspace.geometry.tritri.TriTriResult` for checked
    inputs (``ints`` ``|k| < 2**29``, faces of three distinct labels, pairs of distinct
    faces) and the side tables ``cspace.geometry.tritri._STATUS``, ``_ENDS``. A pair left
    unclassified keeps class -1 (the caller raises)."""
    cdef Py_ssize_t k = pairs.shape[0], t = faces.shape[0], r, f
    cls = np.full(k, -1, dtype=np.int8)
    kind = np.zeros((k, 2), dtype=np.int8)
    u = np.full((k, 2), -1, dtype=np.int64)
    v = np.full((k, 2), -1, dtype=np.int64)
    plane = np.full((k, 2), -1, dtype=np.int64)
    if k == 0:
        return cls, kind, u, v, plane
    normals = np.empty((t, 3), dtype=np.int64)
    cdef long long[:, ::1] N = normals
    cdef signed char[::1] cls_v = cls
    cdef signed char[:, ::1] kind_v = kind
    cdef long long[:, ::1] u_v = u, v_v = v, plane_v = plane
    cdef const long long* a
    cdef const long long* b
    cdef const long long* cc
    cdef long long ux, uy, uz, vx, vy, vz, ta, tb
    cdef _Ctx c
    c.P = &ints[0, 0]
    c.F = &faces[0, 0]
    c.N = &N[0, 0]
    c.status = &status[0]
    c.ends = &ends[0, 0, 0]
    c.cls = &cls_v[0]
    c.kind = &kind_v[0, 0]
    c.u = &u_v[0, 0]
    c.v = &v_v[0, 0]
    c.plane = &plane_v[0, 0]
    with nogil:
        for f in range(t):  # normals (b - a) x (c - a), |N_i| < 2**61 (int64)
            a, b, cc = _pt(&c, faces[f, 0]), _pt(&c, faces[f, 1]), _pt(&c, faces[f, 2])
            ux, uy, uz = b[0] - a[0], b[1] - a[1], b[2] - a[2]
            vx, vy, vz = cc[0] - a[0], cc[1] - a[1], cc[2] - a[2]
            N[f, 0] = uy * vz - uz * vy
            N[f, 1] = uz * vx - ux * vz
            N[f, 2] = ux * vy - uy * vx
        for r in range(k):
            ta, tb = pairs[r, 0], pairs[r, 1]
            if _degenerate(&c, ta):
                if _degenerate(&c, tb):
                    _segment_segment(&c, r, ta, tb)
                else:
                    _segment_triangle(&c, r, ta, tb)
            elif _degenerate(&c, tb):
                _segment_triangle(&c, r, tb, ta)
            else:
                _proper(&c, r, ta, tb)
    return cls, kind, u, v, plane


cdef inline bint _degenerate(const _Ctx* c, long long f) noexcept nogil:
    cdef const long long* n = c.N + 3 * f
    return n[0] == 0 and n[1] == 0 and n[2] == 0


# --------------------------------------------------------------------------------------
# coordinates of the symbolic points (cspace.geometry.endpoints._endpoint_coordinates_reference)


cdef inline u128 _uabs(i128 x) noexcept nogil:
    return <u128> (-x) if x < 0 else <u128> x


cdef u128 _gcd(u128 a, u128 b) noexcept nogil:
    """gcd of two unsigned 128-bit integers (gcd(0, b) = b): Euclid's remainders until both
    fit 64 bits (a few 128-bit divisions: W has at most 94 bits), then :func:`_gcd64`."""
    cdef u128 t
    if a < b:
        a, b = b, a
    while a >> 64:  # a >= b throughout
        if b == 0:
            return a
        t = a % b
        a = b
        b = t
    return _gcd64(<unsigned long long> a, <unsigned long long> b)


cdef unsigned long long _gcd64(unsigned long long a, unsigned long long b) noexcept nogil:
    """gcd of two 64-bit words, by the binary (Stein) algorithm (no divisions)."""
    cdef unsigned long long t
    cdef int shift
    if a == 0:
        return b
    if b == 0:
        return a
    shift = __builtin_ctzll(a | b)
    a >>= __builtin_ctzll(a)
    while True:
        b >>= __builtin_ctzll(b)
        if a > b:
            t = a
            a = b
            b = t
        b -= a
        if b == 0:
            return a << shift


cdef object _pylong(i128 x):
    """The Python int of a 128-bit integer (exactly)."""
    if LLONG_MIN <= x <= LLONG_MAX:
        return PyLong_FromLongLong(<long long> x)
    cdef unsigned char b[16]
    cdef u128 m = <u128> x  # two's complement, written out little-endian
    cdef int i
    for i in range(16):
        b[i] = <unsigned char> (m >> (8 * i))
    return _PyLong_FromByteArray(b, 16, 1, 1)


cdef inline int _bitlen(u128 x) noexcept nogil:
    cdef unsigned long long hi = <unsigned long long> (x >> 64)
    if hi:
        return 128 - __builtin_clzll(hi)
    if <unsigned long long> x:
        return 64 - __builtin_clzll(<unsigned long long> x)
    return 0


cdef double _quotient(i128 x, u128 w) noexcept nogil:
    """``x / w`` correctly rounded (to nearest, ties to even), as Python's ``int / int``;
    ``|x| < 2**127``, ``0 < w < 2**126``, and the quotient within double's normal range
    (here ``|x / w| < 2**123`` and ``>= 2**-94``, or 0).

    The integer quotient ``q = floor(|x| 2**s / w)`` with ``s`` chosen so that ``q`` has 55 or
    56 bits, and whether a remainder is left (sticky), determine the rounding of the 53-bit
    significand exactly: the dropped bits (2 or 3) against their half, the remainder
    breaking ties."""
    cdef u128 a = _uabs(x), q, rem, d
    if a == 0:
        return 0.0
    cdef int lb = _bitlen(w), s = 55 - (_bitlen(a) - lb), k, drop
    cdef bint sticky
    if s < 0:  # w << -s has _bitlen(a) - 55 < 73 bits
        d = w << (-s)
        q = a / d
        sticky = a % d != 0
    else:  # long division, k <= 127 - lb bits at a time (the remainder stays below 2**127)
        q = a / w
        rem = a % w
        k = s
        while k > 0:
            drop = k if k < 127 - lb else 127 - lb
            q = (q << drop) | ((rem << drop) / w)
            rem = (rem << drop) % w
            k -= drop
        sticky = rem != 0
    drop = _bitlen(q) - 53  # 2 or 3
    cdef u128 low = q & ((<u128> 1 << drop) - 1), half = <u128> 1 << (drop - 1)
    q >>= drop
    if low > half or (low == half and (sticky or (q & 1))):
        q += 1  # 2**53 at most: still exact
    cdef double v = ldexp(<double> <unsigned long long> q, drop - s)
    return -v if x < 0 else v


cdef inline Py_ssize_t _seen(long long[::1] table, Py_ssize_t mask, long long a, long long b,
                             long long t, Py_ssize_t here, const long long* U, const long long* V,
                             const long long* T) noexcept nogil:
    """The endpoint index already holding the crossing ``(a, b, t)``, else -1 (and ``here``
    is recorded for it)."""
    cdef unsigned long long h = (<unsigned long long> a * 0x9E3779B97F4A7C15ULL
                                 ^ <unsigned long long> b * 0xC2B2AE3D27D4EB4FULL
                                 ^ <unsigned long long> t * 0x165667B19E3779F9ULL)
    cdef Py_ssize_t slot = <Py_ssize_t> ((h ^ (h >> 29)) & <unsigned long long> mask), j
    while True:
        j = table[slot]
        if j < 0:
            table[slot] = here
            return -1
        if U[j] == a and V[j] == b and T[j] == t:
            return j
        slot = (slot + 1) & mask


def endpoint_coordinates(const long long[:, ::1] ints, const long long[:, ::1] faces,
                         const signed char[:, ::1] kind, const long long[:, ::1] u,
                         const long long[:, ::1] v, const long long[:, ::1] plane):
    """``(exact, approx)`` of :func:`cspace.geometry.endpoints.endpoint_coordinates` for checked
    inputs: canonical ``(X, Y, Z, W)`` Python-int tuples (``W > 0``, primitive) and ``X / W``
    correctly rounded. An edge ``(u, v)`` crossing the plane of ``t`` is
    ``(s_u v - s_v u) / (s_u - s_v)`` with ``s_x = N_t . (x - t_0)``: int128 (bounds in the
    module docstring)."""
    cdef Py_ssize_t k = kind.shape[0], r, col, i
    ex = np.empty((k, 2), dtype=object)  # filled with None
    approx = np.full((k, 2, 3), np.nan)
    if k == 0:
        return ex, approx
    cdef object[:, ::1] exv = ex
    # Open addressing on (u, v, plane): slots hold an endpoint index 2 * row + col, or -1.
    cdef Py_ssize_t mask = 1, first
    while mask < 4 * k:
        mask *= 2
    table_arr = np.full(mask, -1, dtype=np.int64)
    cdef long long[::1] table = table_arr
    mask -= 1
    cdef double[:, :, ::1] ap = approx
    cdef const long long* a
    cdef const long long* b
    cdef const long long* c
    cdef const long long* pu
    cdef const long long* pv
    cdef long long ux, uy, uz, vx, vy, vz, nx, ny, nz
    cdef i128 su, sv, W
    cdef i128 H[3]
    cdef u128 g
    cdef int kd
    for r in range(k):
        for col in range(2):
            kd = kind[r, col]
            if kd == VERTEX:
                pu = &ints[u[r, col], 0]
                exv[r, col] = (pu[0], pu[1], pu[2], 1)
                for i in range(3):
                    ap[r, col, i] = <double> pu[i]
            elif kd == EDGE_PLANE:
                # The same crossing recurs (an edge's two triangles against one plane):
                # computed once, its tuple shared, as the reference's np.unique.
                first = _seen(table, mask, u[r, col], v[r, col], plane[r, col], 2 * r + col, &u[0, 0],
                              &v[0, 0], &plane[0, 0])
                if first >= 0:
                    exv[r, col] = exv[first // 2, first % 2]
                    for i in range(3):
                        ap[r, col, i] = ap[first // 2, first % 2, i]
                    continue
                a, b, c = &ints[faces[plane[r, col], 0], 0], &ints[faces[plane[r, col], 1], 0], \
                    &ints[faces[plane[r, col], 2], 0]
                pu, pv = &ints[u[r, col], 0], &ints[v[r, col], 0]
                ux, uy, uz = b[0] - a[0], b[1] - a[1], b[2] - a[2]
                vx, vy, vz = c[0] - a[0], c[1] - a[1], c[2] - a[2]
                nx, ny, nz = uy * vz - uz * vy, uz * vx - ux * vz, ux * vy - uy * vx
                su = <i128> nx * (pu[0] - a[0]) + <i128> ny * (pu[1] - a[1]) + <i128> nz * (pu[2] - a[2])
                sv = <i128> nx * (pv[0] - a[0]) + <i128> ny * (pv[1] - a[1]) + <i128> nz * (pv[2] - a[2])
                W = su - sv
                if W == 0:
                    raise ValueError(
                        f"the edge {[pu[0], pu[1], pu[2]]} {[pv[0], pv[1], pv[2]]} does not cross "
                        f"the plane of {[[a[0], a[1], a[2]], [b[0], b[1], b[2]], [c[0], c[1], c[2]]]}")
                for i in range(3):
                    H[i] = su * pv[i] - sv * pu[i]
                if W < 0:
                    W = -W
                    for i in range(3):
                        H[i] = -H[i]
                g = _gcd(_gcd(_gcd(<u128> W, _uabs(H[0])), _uabs(H[1])), _uabs(H[2]))
                if g != 1:
                    W = <i128> (<u128> W / g)
                    for i in range(3):
                        H[i] = -<i128> (_uabs(H[i]) / g) if H[i] < 0 else <i128> (<u128> H[i] / g)
                exv[r, col] = (_pylong(H[0]), _pylong(H[1]), _pylong(H[2]), _pylong(W))
                for i in range(3):
                    ap[r, col, i] = _quotient(H[i], <u128> W)
    return ex, approx




def quotient(X: int, W: int) -> float:
    """``X / W`` by the kernel's correctly rounded division (a test hook: it must equal
    Python's ``X / W``); ``|X| < 2**123``, ``0 < W < 2**94`` as the endpoints' bounds."""
    if not (-(2**123) < X < 2**123 and 0 < W < 2**94):
        raise ValueError("quotient needs |X| < 2**123 and 0 < W < 2**94")
    cdef i128 x = (<i128> <long long> (X >> 64) << 64) | <i128> <unsigned long long> (X & 0xFFFFFFFFFFFFFFFF)
    cdef u128 w = (<u128> <unsigned long long> (W >> 64) << 64) | <u128> <unsigned long long> (W & 0xFFFFFFFFFFFFFFFF)
    return _quotient(x, w)
