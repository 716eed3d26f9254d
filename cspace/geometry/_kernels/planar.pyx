# cython: language_level=3, boundscheck=False, wraparound=False, cdivision=True, initializedcheck=False
"""Compiled kernel of :mod:`cspace.minkowski.plane_arrangement`: the exact combinatorics of a segment arrangement
(:func:`arrangement_core`), built once per arrangement plane of every Minkowski sum; and of
:mod:`cspace.minkowski.arrangements`, the steps around it on most planes
(:func:`projected_segments`, :func:`one_facet_plane` reading its faces with
:func:`one_facet_faces`).

It returns exactly what the pure-Python reference ``cspace.minkowski.plane_arrangement._arrangement_core`` returns
(``tests/test_kernels.py``). Every decision is the same exact sign, reached by the first of:

- identity: a point repeated in a predicate (shared endpoints are the common case here);
- 64-bit integers, for points with integer coordinates below 2**30 (triangle corners);
- a float filter with a proven error bound, on the points' correctly rounded coordinates;
- Python's integers, on the homogeneous triples, when neither decides.

Float filter of ``orient(a, b, c)``: each coordinate is ``X / W`` correctly rounded (relative
error ``u = 2**-53``), and ``det = (bx - ax)(cy - ay) - (by - ay)(cx - ax)`` is evaluated in
double precision. With ``s = |bx| + |ax|``, ``t = |cy| + |ay|``, ``s' = |by| + |ay|``,
``t' = |cx| + |ax|``, the computed value is within ``(6u + O(u^2)) (s t + s' t')`` of the
exact orientation of the exact points: each difference carries ``u s (2 + u)`` (inputs,
then its own rounding), each product ``(5u + O(u^2)) s t``, the last subtraction ``u`` of
the sum. The filter decides when ``|det| > 8u (s t + s' t')``; points whose coordinates lie
outside ``[2**-400, 2**400]`` in magnitude (other than 0) skip it, so nothing under- or
overflows. Comparisons of one coordinate use the rounded values alone when they differ
(rounding to nearest is monotone) and the exact ratio when they tie.
"""

from libc.math cimport INFINITY, fabs
from libc.stdlib cimport calloc, free, malloc, qsort, realloc
from cpython.bytes cimport PyBytes_FromStringAndSize

from fractions import Fraction
from math import gcd

cdef double _U = 2.0 ** -53
cdef double _FILTER = 8.0 * 2.0 ** -53
cdef double _TINY = 2.0 ** -400
cdef double _HUGE = 2.0 ** 400
cdef object _SMALL = 2 ** 30

cdef enum:
    SMALL_INT = 0  # integer coordinates, |x|, |y| < 2**30: exact in int64 and in double
    FILTERED = 1   # rounded coordinates in [2**-400, 2**400] or 0: the float filter applies
    EXACT_ONLY = 2  # outside that range: Python integers only


cdef class _Points:
    """Distinct homogeneous points (canonical triples) with their rounded coordinates."""

    cdef list h
    cdef dict ids
    cdef double* x
    cdef double* y
    cdef long long* ix
    cdef long long* iy
    cdef char* kind
    cdef Py_ssize_t n, cap

    def __cinit__(self, Py_ssize_t cap):
        self.h = []
        self.ids = {}
        self.n = 0
        self.cap = cap if cap > 8 else 8
        self.x = <double*> malloc(self.cap * sizeof(double))
        self.y = <double*> malloc(self.cap * sizeof(double))
        self.ix = <long long*> malloc(self.cap * sizeof(long long))
        self.iy = <long long*> malloc(self.cap * sizeof(long long))
        self.kind = <char*> malloc(self.cap * sizeof(char))
        if not (self.x and self.y and self.ix and self.iy and self.kind):
            raise MemoryError()

    def __dealloc__(self):
        free(self.x)
        free(self.y)
        free(self.ix)
        free(self.iy)
        free(self.kind)

    cdef void _grow(self) except *:
        cdef Py_ssize_t cap = 2 * self.cap
        cdef void* p
        p = realloc(self.x, cap * sizeof(double))
        if not p:
            raise MemoryError()
        self.x = <double*> p
        p = realloc(self.y, cap * sizeof(double))
        if not p:
            raise MemoryError()
        self.y = <double*> p
        p = realloc(self.ix, cap * sizeof(long long))
        if not p:
            raise MemoryError()
        self.ix = <long long*> p
        p = realloc(self.iy, cap * sizeof(long long))
        if not p:
            raise MemoryError()
        self.iy = <long long*> p
        p = realloc(self.kind, cap * sizeof(char))
        if not p:
            raise MemoryError()
        self.kind = <char*> p
        self.cap = cap

    cdef Py_ssize_t add(self, tuple h) except -1:
        k = self.ids.get(h)
        if k is not None:
            return <Py_ssize_t> k
        cdef Py_ssize_t i = self.n
        if i == self.cap:
            self._grow()
        self.h.append(h)
        self.ids[h] = i
        self.n = i + 1
        X, Y, W = h
        if W == 1 and -_SMALL < X < _SMALL and -_SMALL < Y < _SMALL:
            self.ix[i] = X
            self.iy[i] = Y
            self.x[i] = <double> self.ix[i]
            self.y[i] = <double> self.iy[i]
            self.kind[i] = SMALL_INT
            return i
        self.x[i] = _rounded(X, W)
        self.y[i] = _rounded(Y, W)
        self.kind[i] = FILTERED if (_filterable(self.x[i]) and _filterable(self.y[i])) else EXACT_ONLY
        return i

    cdef int cmp(self, Py_ssize_t a, Py_ssize_t b, int ax) except -2:
        """Sign of coordinate ``ax`` of point a minus that of point b."""
        cdef double da = self.x[a] if ax == 0 else self.y[a]
        cdef double db = self.x[b] if ax == 0 else self.y[b]
        if da < db:
            return -1
        if da > db:
            return 1
        if a == b or (self.kind[a] == SMALL_INT and self.kind[b] == SMALL_INT):
            return 0
        ha = <tuple> self.h[a]
        hb = <tuple> self.h[b]
        l = ha[ax] * hb[2]
        r = hb[ax] * ha[2]
        return (l > r) - (l < r)

    cdef int orient(self, Py_ssize_t a, Py_ssize_t b, Py_ssize_t c) except -2:
        """Orientation sign of three points (counter-clockwise: +1)."""
        cdef long long ix, iy, jx, jy, d
        cdef double bx, by, cx, cy, det, bound
        if a == b or b == c or a == c:
            return 0
        cdef char ka = self.kind[a], kb = self.kind[b], kc = self.kind[c]
        if ka == SMALL_INT and kb == SMALL_INT and kc == SMALL_INT:
            # |differences| < 2**31, products < 2**62: no overflow
            ix = self.ix[b] - self.ix[a]
            iy = self.iy[b] - self.iy[a]
            jx = self.ix[c] - self.ix[a]
            jy = self.iy[c] - self.iy[a]
            d = ix * jy - iy * jx
            return (d > 0) - (d < 0)
        if ka != EXACT_ONLY and kb != EXACT_ONLY and kc != EXACT_ONLY:
            bx = self.x[b] - self.x[a]
            by = self.y[b] - self.y[a]
            cx = self.x[c] - self.x[a]
            cy = self.y[c] - self.y[a]
            det = bx * cy - by * cx
            bound = _FILTER * ((fabs(self.x[b]) + fabs(self.x[a])) * (fabs(self.y[c]) + fabs(self.y[a]))
                               + (fabs(self.y[b]) + fabs(self.y[a])) * (fabs(self.x[c]) + fabs(self.x[a])))
            if det > bound:
                return 1
            if det < -bound:
                return -1
        # The line a -> b exactly axis-parallel (the common undecided case: points on the
        # axis-aligned edges of boxes, where the filter cannot see 0): the sign is a product
        # of two coordinate comparisons, cheaper than the determinant (equal coordinates
        # have equal floats, so the float test only skips lines that cannot be parallel).
        if self.y[a] == self.y[b] and self.cmp(a, b, 1) == 0:
            return self.cmp(b, a, 0) * self.cmp(c, a, 1)
        if self.x[a] == self.x[b] and self.cmp(a, b, 0) == 0:
            return -self.cmp(b, a, 1) * self.cmp(c, a, 0)
        pa = <tuple> self.h[a]
        pb = <tuple> self.h[b]
        pc = <tuple> self.h[c]
        e = (pa[0] * (pb[1] * pc[2] - pb[2] * pc[1])
             - pa[1] * (pb[0] * pc[2] - pb[2] * pc[0])
             + pa[2] * (pb[0] * pc[1] - pb[1] * pc[0]))
        return (e > 0) - (e < 0)

    cdef bint between(self, Py_ssize_t p, Py_ssize_t q, Py_ssize_t x, int ax) except -1:
        """For x on the line of p != q (``ax``: an axis along which they differ), is x on the
        closed segment?"""
        return self.cmp(x, p, ax) * self.cmp(x, q, ax) <= 0

    cdef int lex(self, Py_ssize_t a, Py_ssize_t b) except -2:
        cdef int c = self.cmp(a, b, 0)
        return c if c != 0 else self.cmp(a, b, 1)

    cdef int angle(self, Py_ssize_t o, Py_ssize_t b, Py_ssize_t c) except -2:
        """Counter-clockwise order, from angle 0 inclusive, of the directions o -> b and
        o -> c (``cspace.minkowski.homogeneous._angle_cmp``)."""
        cdef int by = self.cmp(b, o, 1), cy = self.cmp(c, o, 1)
        cdef int hb = 0 if (by > 0 or (by == 0 and self.cmp(b, o, 0) > 0)) else 1
        cdef int hc = 0 if (cy > 0 or (cy == 0 and self.cmp(c, o, 0) > 0)) else 1
        if hb != hc:
            return hb - hc
        return -self.orient(o, b, c)


cdef double _rounded(X, W):
    """``X / W`` correctly rounded (Python's integer true division), infinite beyond the
    double range (still monotone)."""
    try:
        return X / W
    except OverflowError:
        return float("inf") if X > 0 else float("-inf")


cdef inline bint _filterable(double v) noexcept:
    return v == 0.0 or (_TINY <= fabs(v) <= _HUGE)


cdef tuple _hnorm(tuple h):
    X, Y, W = h
    if W < 0:
        X, Y, W = -X, -Y, -W
    g = gcd(X, Y, W)
    return (X // g, Y // g, W // g)


cdef tuple _hcross3(tuple u, tuple v):
    return (u[1] * v[2] - u[2] * v[1], u[2] * v[0] - u[0] * v[2], u[0] * v[1] - u[1] * v[0])


cdef tuple _harea(list H, list origin, list cycle):
    """As ``cspace.minkowski.plane_arrangement._harea``."""
    num, den = 0, 1
    for h in cycle:
        a = <tuple> H[<Py_ssize_t> origin[h]]
        b = <tuple> H[<Py_ssize_t> origin[(<Py_ssize_t> h) ^ 1]]
        t = a[0] * b[1] - a[1] * b[0]
        if t:
            w = a[2] * b[2]
            if w == den:
                num += t
            elif den % w == 0:
                num += t * (den // w)
            else:
                g = gcd(den, w)
                num = num * (w // g) + t * (den // g)
                den = den * (w // g)
    return num, den


cdef int _area_sign(_Points P, Py_ssize_t* ids, list H, Py_ssize_t* origin_c, list origin,
                    list cycle) except -2:
    """Sign of the signed area of a cycle (``sign(cspace.minkowski.plane_arrangement._harea(...)[0])``).

    Float filter on the points' rounded coordinates: twice the area is the sum over the
    cycle's half-edges of ``t = xa yb - ya xb``. With inputs within a relative ``u`` of the
    exact coordinates (exact for 64-bit integer points), each product is within ``3u + O(u^2)``
    of the exact one, each computed ``t`` within ``(4u + O(u^2)) m`` (``m = |xa yb| + |ya xb|``),
    and the sum of the ``n`` terms adds ``(n - 1) u`` of the sum of their magnitudes: the
    computed sum is within ``(n + 3) u (1 + O(u)) M`` of the exact one, ``M`` the sum of the
    ``m``. The filter decides when ``|sum| > 2 (n + 4) u M`` (the factor 2 covers the rounding
    of ``M`` itself); products of coordinates within ``[2**-400, 2**400]`` neither overflow
    nor leave the normal range. Else the exact sum of Python integers decides."""
    cdef Py_ssize_t n = len(cycle), k, h, a, b
    cdef double s = 0.0, mag = 0.0, p, q
    for k in range(n):
        h = <Py_ssize_t> cycle[k]
        a = ids[origin_c[h]]
        b = ids[origin_c[h ^ 1]]
        if P.kind[a] == EXACT_ONLY or P.kind[b] == EXACT_ONLY:
            break
        p = P.x[a] * P.y[b]
        q = P.y[a] * P.x[b]
        s += p - q
        mag += fabs(p) + fabs(q)
    else:
        if fabs(s) > 2.0 * (n + 4) * _U * mag:
            return 1 if s > 0 else -1
    num = _harea(H, origin, cycle)[0]
    return (num > 0) - (num < 0)


cdef inline Py_ssize_t _find(Py_ssize_t* parent, Py_ssize_t a) noexcept:
    while parent[a] != a:
        parent[a] = parent[parent[a]]
        a = parent[a]
    return a


cdef int _merge_sort_lex(_Points P, Py_ssize_t* a, Py_ssize_t* tmp, Py_ssize_t n) except -1:
    """Sort point ids lexicographically (x, then y; the points are distinct)."""
    cdef Py_ssize_t m, i, j, k
    if n < 2:
        return 0
    if n <= 8:
        for i in range(1, n):
            k = a[i]
            j = i - 1
            while j >= 0 and P.lex(a[j], k) > 0:
                a[j + 1] = a[j]
                j -= 1
            a[j + 1] = k
        return 0
    m = n // 2
    _merge_sort_lex(P, a, tmp, m)
    _merge_sort_lex(P, a + m, tmp, n - m)
    i, j, k = 0, m, 0
    while i < m and j < n:
        if P.lex(a[j], a[i]) < 0:
            tmp[k] = a[j]
            j += 1
        else:
            tmp[k] = a[i]
            i += 1
        k += 1
    while i < m:
        tmp[k] = a[i]
        i += 1
        k += 1
    while j < n:
        tmp[k] = a[j]
        j += 1
        k += 1
    for i in range(n):
        a[i] = tmp[i]
    return 0


cdef struct _Vec:
    Py_ssize_t* a
    Py_ssize_t n, cap


cdef int _push(_Vec* v, Py_ssize_t x) except -1:
    cdef Py_ssize_t cap
    cdef void* p
    if v.n == v.cap:
        cap = 2 * v.cap if v.cap else 16
        p = realloc(v.a, cap * sizeof(Py_ssize_t))
        if not p:
            raise MemoryError()
        v.a = <Py_ssize_t*> p
        v.cap = cap
    v.a[v.n] = x
    v.n += 1
    return 0


cdef struct _Piece:
    Py_ssize_t lo, hi, seg


cdef int _piece_cmp(const void* pa, const void* pb) noexcept nogil:
    cdef const _Piece* a = <const _Piece*> pa
    cdef const _Piece* b = <const _Piece*> pb
    if a.lo != b.lo:
        return -1 if a.lo < b.lo else 1
    if a.hi != b.hi:
        return -1 if a.hi < b.hi else 1
    return (a.seg > b.seg) - (a.seg < b.seg)


cdef struct _XKey:
    double x
    Py_ssize_t i


cdef int _xkey_cmp(const void* pa, const void* pb) noexcept nogil:
    cdef const _XKey* a = <const _XKey*> pa
    cdef const _XKey* b = <const _XKey*> pb
    if a.x < b.x:
        return -1
    if a.x > b.x:
        return 1
    return (a.i > b.i) - (a.i < b.i)


cdef Py_ssize_t _first_at_least(_XKey* keys, Py_ssize_t n, double x) noexcept nogil:
    """The first index of ``keys`` (sorted by ``x``) whose ``x`` is at least ``x``."""
    cdef Py_ssize_t lo = 0, hi = n, mid
    while lo < hi:
        mid = (lo + hi) // 2
        if keys[mid].x < x:
            lo = mid + 1
        else:
            hi = mid
    return lo


def arrangement_core(list segs, list labels):
    """The exact combinatorics of the arrangement of ``segs``: see
    ``cspace.minkowski.plane_arrangement._arrangement_core`` (identical outputs). The points live in a
    :class:`_Points` table; which points lie on which segment, the pieces between them and
    the half-edge structure are C arrays, turned into Python lists only for the result."""
    cdef Py_ssize_t n = len(segs), i, j, k, m, nv, nh, ne, a, b, r, s, x, ax, t, v, g, h
    cdef Py_ssize_t lo, hi, npc, ninc, s1, s2, npt
    cdef int o1, o2, o3, o4
    cdef double hi_x
    cdef _XKey* byx = NULL
    cdef _XKey* ptx = NULL
    cdef _XKey* pty = NULL
    cdef _XKey* keys
    cdef _Points P = _Points(2 * n + 8)
    cdef Py_ssize_t* sp = <Py_ssize_t*> malloc((2 * n + 1) * sizeof(Py_ssize_t))
    cdef char* axis = <char*> malloc((n + 1) * sizeof(char))
    cdef double* box = <double*> malloc((4 * n + 1) * sizeof(double))
    cdef Py_ssize_t* prop = <Py_ssize_t*> malloc((n + 1) * sizeof(Py_ssize_t))
    cdef _Vec inc_s, inc_p  # incidences: point inc_p[k] lies on segment inc_s[k]
    cdef Py_ssize_t* start = NULL
    cdef Py_ssize_t* onp = NULL
    cdef char* mark = NULL
    cdef _Piece* pieces = NULL
    cdef Py_ssize_t* ids = NULL
    cdef Py_ssize_t* tmp = NULL
    cdef Py_ssize_t* rank = NULL
    cdef Py_ssize_t* origin_c = NULL
    cdef Py_ssize_t* pos = NULL
    cdef Py_ssize_t* nxt_c = NULL
    cdef Py_ssize_t* cyc_c = NULL
    cdef Py_ssize_t* parent = NULL
    cdef Py_ssize_t* ostart = NULL
    cdef Py_ssize_t* oh = NULL
    inc_s.a = inc_p.a = NULL
    inc_s.n = inc_p.n = inc_s.cap = inc_p.cap = 0
    try:
        if not (sp and axis and box and prop):
            raise MemoryError()
        m = 0
        points_only = []
        for i in range(n):
            p, q = segs[i]
            sp[2 * i] = P.add(p)
            sp[2 * i + 1] = P.add(q)
            if sp[2 * i] != sp[2 * i + 1]:
                prop[m] = i
                m += 1
                axis[i] = 0 if P.cmp(sp[2 * i], sp[2 * i + 1], 0) != 0 else 1
                a, b = sp[2 * i], sp[2 * i + 1]
                # closed boxes of the rounded coordinates: rounding is monotone, so boxes of
                # meeting segments still meet (a filter only)
                box[4 * i] = P.x[a] if P.x[a] < P.x[b] else P.x[b]
                box[4 * i + 1] = P.x[b] if P.x[a] < P.x[b] else P.x[a]
                box[4 * i + 2] = P.y[a] if P.y[a] < P.y[b] else P.y[b]
                box[4 * i + 3] = P.y[b] if P.y[a] < P.y[b] else P.y[a]
                _push(&inc_s, i)
                _push(&inc_p, a)
                _push(&inc_s, i)
                _push(&inc_p, b)
            else:
                points_only.append(i)
        lines = {}
        # Pairs whose boxes meet, by a sweep over the boxes' lower x (a plane of 27k segments
        # has 368 M pairs, most far apart); each pair is met once, as (i, j) with i < j.
        byx = <_XKey*> malloc((m + 1) * sizeof(_XKey))
        if not byx:
            raise MemoryError()
        for a in range(m):
            byx[a].x = box[4 * prop[a]]
            byx[a].i = prop[a]
        qsort(byx, m, sizeof(_XKey), _xkey_cmp)
        for a in range(m):
            s1 = byx[a].i
            for b in range(a + 1, m):
                s2 = byx[b].i
                if box[4 * s1 + 1] < box[4 * s2]:
                    break  # every later box starts right of this one's end
                if box[4 * s1 + 3] < box[4 * s2 + 2] or box[4 * s2 + 3] < box[4 * s1 + 2]:
                    continue
                i, j = (s1, s2) if s1 < s2 else (s2, s1)
                o1 = P.orient(sp[2 * i], sp[2 * i + 1], sp[2 * j])
                o2 = P.orient(sp[2 * i], sp[2 * i + 1], sp[2 * j + 1])
                if o1 == 0 and o2 == 0:  # collinear: overlap or touch
                    for x in (sp[2 * j], sp[2 * j + 1]):
                        if P.between(sp[2 * i], sp[2 * i + 1], x, axis[i]):
                            _push(&inc_s, i)
                            _push(&inc_p, x)
                    for x in (sp[2 * i], sp[2 * i + 1]):
                        if P.between(sp[2 * j], sp[2 * j + 1], x, axis[j]):
                            _push(&inc_s, j)
                            _push(&inc_p, x)
                    continue
                if o1 * o2 > 0:
                    continue
                o3 = P.orient(sp[2 * j], sp[2 * j + 1], sp[2 * i])
                o4 = P.orient(sp[2 * j], sp[2 * j + 1], sp[2 * i + 1])
                if o3 * o4 > 0:
                    continue
                if o1 == 0:
                    x = sp[2 * j]
                elif o2 == 0:
                    x = sp[2 * j + 1]
                elif o3 == 0:
                    x = sp[2 * i]
                elif o4 == 0:
                    x = sp[2 * i + 1]
                else:
                    li = lines.get(i)
                    if li is None:
                        li = lines[i] = _hcross3(P.h[sp[2 * i]], P.h[sp[2 * i + 1]])
                    lj = lines.get(j)
                    if lj is None:
                        lj = lines[j] = _hcross3(P.h[sp[2 * j]], P.h[sp[2 * j + 1]])
                    x = P.add(_hnorm(_hcross3(li, lj)))
                _push(&inc_s, i)
                _push(&inc_p, x)
                _push(&inc_s, j)
                _push(&inc_p, x)
        mark = <char*> calloc(P.n + 1, sizeof(char))
        if not mark:
            raise MemoryError()
        point_label = {}
        npt = 0
        # the distinct lone points, by x and by y (sorted below)
        ptx = <_XKey*> malloc((len(points_only) + 1) * sizeof(_XKey))
        pty = <_XKey*> malloc((len(points_only) + 1) * sizeof(_XKey))
        if not (ptx and pty):
            raise MemoryError()
        for k in points_only:
            x = sp[2 * k]
            if not mark[x]:
                ptx[npt].x, ptx[npt].i = P.x[x], x
                pty[npt].x, pty[npt].i = P.y[x], x
                npt += 1
            mark[x] = 1
            point_label.setdefault(x, set()).add(labels[k])
        if npt:
            # The lone points on each proper segment: the points whose box coordinate along
            # the segment box's narrower side lies in it, by binary search in the points
            # sorted by x and by y (12k points against 15k segments on one plane: the
            # plain double loop took 0.4 s), then the box and the exact test.
            qsort(ptx, npt, sizeof(_XKey), _xkey_cmp)
            qsort(pty, npt, sizeof(_XKey), _xkey_cmp)
            for a in range(m):
                i = prop[a]
                if box[4 * i + 1] - box[4 * i] <= box[4 * i + 3] - box[4 * i + 2]:
                    lo = _first_at_least(ptx, npt, box[4 * i])
                    keys = ptx
                    hi_x = box[4 * i + 1]
                else:
                    lo = _first_at_least(pty, npt, box[4 * i + 2])
                    keys = pty
                    hi_x = box[4 * i + 3]
                for r in range(lo, npt):
                    if keys[r].x > hi_x:
                        break
                    x = keys[r].i
                    if (P.x[x] < box[4 * i] or box[4 * i + 1] < P.x[x]
                            or P.y[x] < box[4 * i + 2] or box[4 * i + 3] < P.y[x]):
                        continue
                    if (P.orient(sp[2 * i], sp[2 * i + 1], x) == 0
                            and P.between(sp[2 * i], sp[2 * i + 1], x, axis[i])):
                        _push(&inc_s, i)
                        _push(&inc_p, x)
        ninc = inc_s.n
        for k in range(ninc):
            mark[inc_p.a[k]] = 1

        # the points sorted lexicographically
        nv = 0
        for x in range(P.n):
            nv += mark[x]
        ids = <Py_ssize_t*> malloc((nv + 1) * sizeof(Py_ssize_t))
        tmp = <Py_ssize_t*> malloc((max(nv, ninc) + 1) * sizeof(Py_ssize_t))
        rank = <Py_ssize_t*> malloc((P.n + 1) * sizeof(Py_ssize_t))
        if not (ids and tmp and rank):
            raise MemoryError()
        k = 0
        for x in range(P.n):
            if mark[x]:
                ids[k] = x
                k += 1
        _merge_sort_lex(P, ids, tmp, nv)
        for k in range(nv):
            rank[ids[k]] = k
        order = [P.h[ids[k]] for k in range(nv)]

        # the points on each segment (counting sort of the incidences by segment)
        start = <Py_ssize_t*> calloc(n + 2, sizeof(Py_ssize_t))
        onp = <Py_ssize_t*> malloc((ninc + 1) * sizeof(Py_ssize_t))
        pieces = <_Piece*> malloc((ninc + 1) * sizeof(_Piece))
        if not (start and onp and pieces):
            raise MemoryError()
        for k in range(ninc):
            start[inc_s.a[k] + 1] += 1
        for i in range(n):
            start[i + 1] += start[i]
        for k in range(ninc):  # start[i] runs ahead while filling, then is shifted back
            i = inc_s.a[k]
            onp[start[i]] = inc_p.a[k]
            start[i] += 1
        for i in range(n, 0, -1):
            start[i] = start[i - 1]
        start[0] = 0
        # pieces: consecutive distinct points along each segment
        npc = 0
        for a in range(m):
            i = prop[a]
            lo, hi = start[i], start[i + 1]
            ax = axis[i]
            for r in range(lo + 1, hi):  # insertion sort along the segment's axis (few points)
                x = onp[r]
                s = r - 1
                while s >= lo and P.cmp(onp[s], x, ax) > 0:
                    onp[s + 1] = onp[s]
                    s -= 1
                onp[s + 1] = x
            t = -1  # the previous distinct point (a point may be recorded more than once)
            for r in range(lo, hi):
                x = onp[r]
                if x == t:
                    continue
                if t >= 0:
                    g, h = rank[t], rank[x]
                    pieces[npc].lo = g if g < h else h
                    pieces[npc].hi = h if g < h else g
                    pieces[npc].seg = i
                    npc += 1
                t = x
        qsort(pieces, npc, sizeof(_Piece), _piece_cmp)
        E = []
        edge_labels = []
        k = 0
        while k < npc:
            lo, hi = pieces[k].lo, pieces[k].hi
            labs = {labels[pieces[k].seg]}
            k += 1
            while k < npc and pieces[k].lo == lo and pieces[k].hi == hi:
                labs.add(labels[pieces[k].seg])
                k += 1
            E.append((lo, hi))
            edge_labels.append(labs)
        vertex_labels = {rank[x]: lab for x, lab in point_label.items()}

        # half-edges: 2k is edge k from u to v, 2k + 1 back
        ne = len(E)
        nh = 2 * ne
        origin_c = <Py_ssize_t*> malloc((nh + 1) * sizeof(Py_ssize_t))
        pos = <Py_ssize_t*> malloc((nh + 1) * sizeof(Py_ssize_t))
        nxt_c = <Py_ssize_t*> malloc((nh + 1) * sizeof(Py_ssize_t))
        cyc_c = <Py_ssize_t*> malloc((nh + 1) * sizeof(Py_ssize_t))
        oh = <Py_ssize_t*> malloc((nh + 1) * sizeof(Py_ssize_t))
        parent = <Py_ssize_t*> malloc((nv + 1) * sizeof(Py_ssize_t))
        ostart = <Py_ssize_t*> calloc(nv + 2, sizeof(Py_ssize_t))
        if not (origin_c and pos and nxt_c and cyc_c and oh and parent and ostart):
            raise MemoryError()
        for k in range(ne):
            lo, hi = E[k]
            origin_c[2 * k] = lo
            origin_c[2 * k + 1] = hi
        # each vertex's outgoing half-edges (in increasing order, then sorted by angle)
        for h in range(nh):
            ostart[origin_c[h] + 1] += 1
        for v in range(nv):
            ostart[v + 1] += ostart[v]
        for h in range(nh):
            v = origin_c[h]
            oh[ostart[v]] = h
            ostart[v] += 1
        for v in range(nv, 0, -1):
            ostart[v] = ostart[v - 1]
        ostart[0] = 0
        isolated = []
        for v in range(nv):
            lo, hi = ostart[v], ostart[v + 1]
            if hi == lo:
                isolated.append(v)
            if hi - lo > 2:  # two half-edges have one cyclic order
                x = ids[v]
                for a in range(lo + 1, hi):
                    g = oh[a]
                    b = a - 1
                    while b >= lo and P.angle(x, ids[origin_c[oh[b] ^ 1]], ids[origin_c[g ^ 1]]) > 0:
                        oh[b + 1] = oh[b]
                        b -= 1
                    oh[b + 1] = g
            for a in range(lo, hi):
                pos[oh[a]] = a
        for h in range(nh):
            t = h ^ 1
            v = origin_c[t]
            # the clockwise neighbour of the twin
            nxt_c[h] = oh[pos[t] - 1 if pos[t] > ostart[v] else ostart[v + 1] - 1]
        nxt = [nxt_c[h] for h in range(nh)]

        for h in range(nh):
            cyc_c[h] = -1
        cycles = []
        for h in range(nh):
            if cyc_c[h] >= 0:
                continue
            c = []
            g = h
            k = len(cycles)
            while cyc_c[g] < 0:
                cyc_c[g] = k
                c.append(g)
                g = nxt_c[g]
            cycles.append(c)
        cyc_of = [cyc_c[h] for h in range(nh)]
        origin = [origin_c[h] for h in range(nh)]
        signs = [_area_sign(P, ids, order, origin_c, origin, c) for c in cycles]

        # components: union-find, the smaller root kept (each root is its component's smallest
        # vertex)
        for v in range(nv):
            parent[v] = v
        for k in range(ne):
            r = _find(parent, origin_c[2 * k])
            s = _find(parent, origin_c[2 * k + 1])
            if r != s:
                if r < s:
                    parent[s] = r
                else:
                    parent[r] = s
        comp = [_find(parent, v) for v in range(nv)]
        return order, vertex_labels, E, edge_labels, origin, isolated, nxt, cycles, cyc_of, signs, comp
    finally:
        free(sp)
        free(axis)
        free(box)
        free(prop)
        free(byx)
        free(ptx)
        free(pty)
        free(inc_s.a)
        free(inc_p.a)
        free(start)
        free(onp)
        free(mark)
        free(pieces)
        free(ids)
        free(tmp)
        free(rank)
        free(origin_c)
        free(pos)
        free(nxt_c)
        free(cyc_c)
        free(oh)
        free(parent)
        free(ostart)


# --------------------------------------------------------------------------------------------
# triangulation of a face (cspace.minkowski.triangulation.triangulate_rings): its predicate-heavy steps


cdef int _dot_sign(_Points P, Py_ssize_t a, Py_ssize_t v, Py_ssize_t b) except -2:
    """Sign of ``(v - a) . (b - v)``: ``sign(_dot(_hdir(a, v), _hdir(v, b)))`` of
    :mod:`cspace.minkowski.plane_arrangement` (the homogeneous vectors are these scaled by positive weights).
    Decided as :meth:`_Points.orient`: 64-bit integers, else the float filter ``|d| > 8u (s t
    + s' t')`` with ``s = |vx| + |ax|``, ``t = |bx| + |vx|``, ``s' = |vy| + |ay|``, ``t' = |by|
    + |vy|`` (the same error analysis: two products of rounded differences, one addition),
    else Python integers."""
    cdef long long ix, iy, jx, jy, d
    cdef double det, bound
    if a == v or v == b:
        return 0
    cdef char ka = P.kind[a], kv = P.kind[v], kb = P.kind[b]
    if ka == SMALL_INT and kv == SMALL_INT and kb == SMALL_INT:
        # |differences| < 2**31, products < 2**62, their sum < 2**63: no overflow
        ix = P.ix[v] - P.ix[a]
        iy = P.iy[v] - P.iy[a]
        jx = P.ix[b] - P.ix[v]
        jy = P.iy[b] - P.iy[v]
        d = ix * jx + iy * jy
        return (d > 0) - (d < 0)
    if ka != EXACT_ONLY and kv != EXACT_ONLY and kb != EXACT_ONLY:
        det = (P.x[v] - P.x[a]) * (P.x[b] - P.x[v]) + (P.y[v] - P.y[a]) * (P.y[b] - P.y[v])
        bound = _FILTER * ((fabs(P.x[v]) + fabs(P.x[a])) * (fabs(P.x[b]) + fabs(P.x[v]))
                           + (fabs(P.y[v]) + fabs(P.y[a])) * (fabs(P.y[b]) + fabs(P.y[v])))
        if det > bound:
            return 1
        if det < -bound:
            return -1
    pa = <tuple> P.h[a]
    pv = <tuple> P.h[v]
    pb = <tuple> P.h[b]
    ux, uy = pv[0] * pa[2] - pa[0] * pv[2], pv[1] * pa[2] - pa[1] * pv[2]
    wx, wy = pb[0] * pv[2] - pv[0] * pb[2], pb[1] * pv[2] - pv[1] * pb[2]
    e = ux * wx + uy * wy
    return (e > 0) - (e < 0)


def straight_runs(list ring, H, dict runs, dict uses):
    """``cspace.minkowski.triangulation._straight_runs`` (identical outputs; the same exact signs through
    filters)."""
    cdef Py_ssize_t n = len(ring), k, m = 0, x, y, j
    cdef _Points P = _Points(n + 1)
    cdef Py_ssize_t* pid = <Py_ssize_t*> malloc((n + 1) * sizeof(Py_ssize_t))
    cdef Py_ssize_t* keep = <Py_ssize_t*> malloc((n + 1) * sizeof(Py_ssize_t))
    cdef int o
    cdef bint convex = True
    if not (pid and keep):
        free(pid)
        free(keep)
        raise MemoryError()
    try:
        for k in range(n):
            pid[k] = P.add(<tuple> H[<Py_ssize_t> ring[k]])
        for k in range(n):
            x = k - 1 if k > 0 else n - 1
            y = k + 1 if k + 1 < n else 0
            o = P.orient(pid[x], pid[k], pid[y])
            if uses[ring[k]] > 1 or o != 0 or _dot_sign(P, pid[x], pid[k], pid[y]) <= 0:
                keep[m] = k
                m += 1
                convex = convex and o > 0
        if m < 3:
            return [], False
        for j in range(m):
            x = keep[j]
            y = keep[j + 1] if j + 1 < m else keep[0]
            between = [ring[k % n] for k in range(x + 1, y if y > x else y + n)]
            if between:
                runs[(ring[x], ring[y])] = between
        return [ring[keep[j]] for j in range(m)], convex
    finally:
        free(pid)
        free(keep)


cdef inline bint _in_closed_triangle(_Points P, Py_ssize_t p, Py_ssize_t a, Py_ssize_t b,
                                     Py_ssize_t c) except -1:
    return P.orient(a, b, p) >= 0 and P.orient(b, c, p) >= 0 and P.orient(c, a, p) >= 0


def clip_simple(list Ps, list ids):
    """``cspace.minkowski.triangulation._clip_simple`` (identical outputs): ear clipping of a simple
    counter-clockwise polygon, None when it stalls."""
    cdef Py_ssize_t n = len(Ps), k, p, q, r, j, left, stall
    cdef _Points P = _Points(n + 1)
    cdef Py_ssize_t* pid = <Py_ssize_t*> malloc((n + 1) * sizeof(Py_ssize_t))
    cdef Py_ssize_t* prv = <Py_ssize_t*> malloc((n + 1) * sizeof(Py_ssize_t))
    cdef Py_ssize_t* nxt = <Py_ssize_t*> malloc((n + 1) * sizeof(Py_ssize_t))
    cdef char* conv = <char*> malloc((n + 1) * sizeof(char))
    cdef char* reflex = <char*> malloc((n + 1) * sizeof(char))  # the reference's set
    cdef bint ear
    if not (pid and prv and nxt and conv and reflex):
        free(pid)
        free(prv)
        free(nxt)
        free(conv)
        free(reflex)
        raise MemoryError()
    try:
        for k in range(n):
            pid[k] = P.add(<tuple> Ps[k])
            prv[k] = k - 1 if k > 0 else n - 1
            nxt[k] = k + 1 if k + 1 < n else 0
        for k in range(n):
            conv[k] = P.orient(pid[prv[k]], pid[k], pid[nxt[k]]) > 0
            reflex[k] = not conv[k]
        tris = []
        k, left, stall = 0, n, 0
        while left > 3:
            p, q = prv[k], nxt[k]
            ear = conv[k]
            if ear:
                for r in range(n):
                    if (reflex[r] and r != p and r != q
                            and _in_closed_triangle(P, pid[r], pid[p], pid[k], pid[q])):
                        ear = False
                        break
            if ear:
                tris.append((ids[p], ids[k], ids[q]))
                nxt[p] = q
                prv[q] = p
                reflex[k] = False
                left -= 1
                for j in (p, q):
                    conv[j] = P.orient(pid[prv[j]], pid[j], pid[nxt[j]]) > 0
                    reflex[j] = not conv[j]
                k, stall = p, 0
            else:
                k, stall = nxt[k], stall + 1
                if stall > left:
                    return None
        p, q = prv[k], nxt[k]
        if P.orient(pid[p], pid[k], pid[q]) > 0:
            tris.append((ids[p], ids[k], ids[q]))
        return tris
    finally:
        free(pid)
        free(prv)
        free(nxt)
        free(conv)
        free(reflex)


cdef bint _ear_ok(_Points P, Py_ssize_t* poly, Py_ssize_t n, Py_ssize_t i) except -1:
    """``cspace.minkowski.triangulation._ear_ok`` on point ids (equal points have one id, so the reference's
    point comparisons are id comparisons). Its cone tests ``_cross(lo, d) > 0`` with
    directions from ``s`` are ``orient(s, lo, t) > 0`` (the homogeneous directions are the
    real ones scaled by positive weights)."""
    cdef Py_ssize_t p = poly[i - 1 if i > 0 else n - 1], v = poly[i], q = poly[i + 1 if i + 1 < n else 0]
    cdef Py_ssize_t k, a, b, s, t, lo, hi, e0 = i - 1 if i > 0 else n - 1, r
    if P.orient(p, v, q) <= 0:
        return False
    for k in range(n):
        a = poly[k]
        b = poly[k + 1 if k + 1 < n else 0]
        if a != p and a != v and a != q and _in_closed_triangle(P, a, p, v, q):
            return False
        if k == e0 or k == i:
            continue
        if (P.orient(a, b, p) * P.orient(a, b, q) < 0
                and P.orient(p, q, a) * P.orient(p, q, b) < 0):
            return False
        for r in range(2):
            s, t = (a, b) if r == 0 else (b, a)
            # the reference's dict {v: .., p: .., q: ..}: a later equal key replaces an earlier
            if s == q:
                lo, hi = p, v
            elif s == p:
                lo, hi = v, q
            elif s == v:
                lo, hi = q, p
            else:
                continue
            if t != s and P.orient(s, lo, t) > 0 and P.orient(s, t, hi) > 0:
                return False
    return True


def clip_general(list Ps, list ids):
    """``cspace.minkowski.triangulation._clip_general`` (identical outputs): the general ear clipping of a
    polygon whose vertices may repeat (holes bridged in)."""
    cdef Py_ssize_t n = len(Ps), k, i
    cdef _Points P = _Points(n + 1)
    cdef Py_ssize_t* poly = <Py_ssize_t*> malloc((n + 1) * sizeof(Py_ssize_t))
    cdef bint found
    if not poly:
        raise MemoryError()
    try:
        for k in range(n):
            poly[k] = P.add(<tuple> Ps[k])
        ids = list(ids)
        tris = []
        while n > 3:
            found = False
            for i in range(n):
                if _ear_ok(P, poly, n, i):
                    tris.append((ids[i - 1 if i > 0 else n - 1], ids[i], ids[i + 1 if i + 1 < n else 0]))
                    for k in range(i, n - 1):
                        poly[k] = poly[k + 1]
                    del ids[i]
                    n -= 1
                    found = True
                    break
            if not found:
                from cspace.geometry.homogeneous import _hturn  # loaded by now: its users imported it

                if _hturn([P.h[poly[k]] for k in range(n)]) == 0:
                    return tris
                raise AssertionError("ear clipping found no ear")
        if n == 3 and P.orient(poly[0], poly[1], poly[2]) > 0:
            tris.append(tuple(ids))
        return tris
    finally:
        free(poly)


def projected_segments(list segs3, int ax):
    """``cspace.minkowski.arrangements._projected_segments`` (identical outputs): each
    segment of homogeneous 3D points ``(X, Y, Z, W)`` projected along axis ``ax`` to the
    canonical homogeneous triples ``(X_a, X_b, W)`` (``W > 0``, primitive), ``a, b`` the
    axes after ``ax`` in cyclic order."""
    cdef int a = (ax + 1) % 3, b = (ax + 2) % 3
    cdef list out = []
    cdef tuple x, y
    for x, y in segs3:
        out.append((_hnorm((x[a], x[b], x[3])), _hnorm((y[a], y[b], y[3]))))
    return out


def ring_inner_point(list H, list ring, others=()):
    """Canonical homogeneous ``(X, Y, W)`` of the point strictly inside the face bounded by
    the cycle through vertices ``ring`` (ids into the canonical points ``H``) that
    ``cspace.minkowski.plane_arrangement.ring_sample(H, ring, others)`` gives (its reference:
    identical outputs, ``tests/test_kernels.py``; ``others``: the face's hole and isolated
    vertices): on the line midway between the lowest and the next y of the ring's and the
    others' vertices, the midpoint of the first gap between crossings of non-zero winding.
    Floats (each ``Y / W`` correctly rounded, so a smaller float means a smaller y) order
    the y's and crossings; ties go to the exact ratios."""
    cdef Py_ssize_t n = len(ring), k, m
    cdef double low = INFINITY, nxt = INFINITY, f, fm
    cdef list fy = [], xs = []
    cdef list every = ring + list(others) if others else ring
    cdef Py_ssize_t ne = len(every)
    for k in range(ne):
        p = H[every[k]]
        f = p[1] / p[2]
        fy.append(f)
        if f < low:
            low = f
    for k in range(ne):
        f = fy[k]
        if f > low and f < nxt:
            nxt = f
    # the exact lowest y and the next distinct one, as integer ratios (W > 0)
    y0 = None
    for k in range(ne):
        if fy[k] == low:
            p = H[every[k]]
            if y0 is None or p[1] * y0[1] < y0[0] * p[2]:
                y0 = (p[1], p[2])
    y1 = None
    for k in range(ne):
        if fy[k] == low or (nxt != INFINITY and fy[k] == nxt):
            p = H[every[k]]
            if p[1] * y0[1] > y0[0] * p[2] and (y1 is None or p[1] * y1[1] < y1[0] * p[2]):
                y1 = (p[1], p[2])
    num = y0[0] * y1[1] + y1[0] * y0[1]
    den = 2 * y0[1] * y1[1]
    g = gcd(num, den)
    N, D = num // g, den // g  # ym = N / D, in lowest terms (as the reference's Fraction)
    fm = N / D
    below = []
    for k in range(n):  # y < ym; never equal (no vertex lies strictly between)
        p = H[ring[k]]
        f = fy[k]
        below.append(f < fm or (f == fm and p[1] * D < N * p[2]))
    for k in range(n):
        m = k + 1 if k + 1 < n else 0
        if below[k] != below[m]:
            Xa, Ya, Wa = H[ring[k]]
            Xb, Yb, Wb = H[ring[m]]
            dy = Yb * Wa - Ya * Wb  # (by - ay) Wa Wb
            num = Xa * D * dy + (N * Wa - Ya * D) * (Xb * Wa - Xa * Wb)
            den = D * Wa * dy
            if den < 0:
                num, den = -num, -den
            xs.append((num / den, num, den, 1 if dy > 0 else -1))
    xs.sort(key=_first)
    for k in range(len(xs) - 1):  # float ties: exact order (rare)
        if xs[k][0] == xs[k + 1][0]:
            xs.sort(key=_exact_key)
            break
    w = 0
    for t in xs:
        w += t[3]
    for k in range(len(xs) - 1):
        a, b = xs[k], xs[k + 1]
        w -= a[3]
        if w != 0 and (a[0] < b[0] or (a[0] == b[0] and a[1] * b[2] < b[1] * a[2])):
            num = a[1] * b[2] + b[1] * a[2]
            den = 2 * a[2] * b[2]
            g = gcd(num, den)
            xn, bx = num // g, den // g
            W = bx * D // gcd(bx, D)
            return (xn * (W // bx), N * (W // D), W)
    raise AssertionError("no interior sample found")


cdef bint _pushed_inside(list poly, int turn, X, Y, W, double xf, double yf) except -1:
    """``cspace.minkowski.coverage.pushed_inside`` (its reference): is ``(X/W, Y/W) + eps (1,
    eps)`` inside the convex integer polygon ``poly`` of orientation ``turn``? ``xf, yf``:
    ``X / W`` and ``Y / W`` correctly rounded, for a float filter of each side's sign.

    Filter: with ``u = 2**-53``, ``xf = x (1 + d1)``, ``|d1| <= u``, the side
    ``ux (y - ay) - uy (x - ax)`` (``ux, uy, ax, ay`` integers below ``2**53``, exact in
    doubles) evaluated in doubles is within ``u (|ux| (4 |y| + 3 |ay|) + |uy| (4 |x| + 3 |ax|))
    + O(u^2)`` of the exact value (each difference carries ``u (2 |x| + |ax|)``, each
    product and the last subtraction ``u`` of their magnitude); it decides when its
    magnitude exceeds ``8 u`` times ``|ux| (|yf| + |ay|) + |uy| (|xf| + |ax|)``. ``W > 0``, so
    that is the sign of ``ux (Y - ay W) - uy (X - ax W)``; else the exact integers decide."""
    cdef Py_ssize_t n = len(poly), k
    cdef int side
    cdef double fux, fuy, fax, fay, df, bound
    for k in range(n):
        a = poly[k]
        b = poly[k + 1 if k + 1 < n else 0]
        ux, uy = b[0] - a[0], b[1] - a[1]
        fux, fuy, fax, fay = ux, uy, a[0], a[1]
        df = fux * (yf - fay) - fuy * (xf - fax)
        bound = _FILTER * (fabs(fux) * (fabs(yf) + fabs(fay)) + fabs(fuy) * (fabs(xf) + fabs(fax)))
        if df > bound:
            side = 1
        elif df < -bound:
            side = -1
        else:
            d = ux * (Y - a[1] * W) - uy * (X - a[0] * W)
            if d:
                side = 1 if d > 0 else -1
            else:  # on the line: the push (1, eps) decides, first along x, then along y
                side = -1 if uy > 0 else (1 if uy < 0 else (1 if ux > 0 else -1))
        if side != turn:
            return False
    return True


def face_coverage(list H, list origin, list face_cycles, list others, list polys, list turn,
                  list weights, list boxes, list source_turn=None):
    """The per-face loop of ``cspace.minkowski.coverage.sampled_coverage`` (its reference;
    identical outputs): each bounded face, given by its half-edge cycles (``face_cycles[f]``,
    the outer one first) and its hole and isolated vertices ``others[f]``, is read at
    ``coverage.sample_point``'s point (the centroid of a triangle without holes, else
    :func:`ring_inner_point`) pushed by ``eps (1, eps)``: ``coverage[f]``, ``support[f]`` and
    twice the integral of the coverage as ``{den: num}`` terms, the points read, and per face
    the first polygon ``i`` whose inside, oriented by ``source_turn[i]`` (when given), holds
    the pushed point (-1: none). ``boxes[i]``: polygon ``i``'s box, widened by 1 (floats
    within an ulp of the point's coordinates stay conservative)."""
    cdef Py_ssize_t nf = len(face_cycles), npoly = len(polys), f, i, k, got
    cdef list coverage = [0] * nf, support = [0] * nf, points = [None] * nf
    cdef list first = [-1] * nf, outer, cyc
    cdef dict terms = {}
    cdef tuple b
    cdef double xf, yf
    cdef int tr
    cdef bint inside
    cdef double* bx = <double*> malloc((4 * npoly + 1) * sizeof(double))
    if not bx:
        raise MemoryError()
    try:
        for i in range(npoly):
            b = boxes[i]
            bx[4 * i], bx[4 * i + 1], bx[4 * i + 2], bx[4 * i + 3] = b[0], b[1], b[2], b[3]
        for f in range(nf):
            cyc = face_cycles[f]
            outer = cyc[0]
            if len(cyc) == 1 and len(outer) == 3 and not others[f]:
                (xa, ya, wa) = H[origin[outer[0]]]
                (xb, yb, wb) = H[origin[outer[1]]]
                (xc, yc, wc) = H[origin[outer[2]]]
                X, Y, W = _hnorm((xa * wb * wc + xb * wa * wc + xc * wa * wb,
                                  ya * wb * wc + yb * wa * wc + yc * wa * wb, 3 * wa * wb * wc))
            else:
                X, Y, W = ring_inner_point(H, [origin[h] for h in outer], others[f])
            points[f] = (X, Y, W)
            xf, yf = X / W, Y / W
            c = s = 0
            got = -1
            for i in range(npoly):
                if not (bx[4 * i] <= xf <= bx[4 * i + 1] and bx[4 * i + 2] <= yf <= bx[4 * i + 3]):
                    continue
                tr = turn[i]
                inside = _pushed_inside(polys[i], tr, X, Y, W, xf, yf)
                if inside:
                    c += weights[i] * tr
                    s += abs(weights[i])
                if got < 0 and source_turn is not None:
                    if <int> source_turn[i] != tr:
                        inside = _pushed_inside(polys[i], source_turn[i], X, Y, W, xf, yf)
                    if inside:
                        got = i
            coverage[f], support[f], first[f] = c, s, got
            if c:  # integral += c * face area, as twice the areas
                num, den = 0, 1
                for k in range(len(cyc)):
                    n_, d_ = _harea(H, origin, cyc[k])
                    num, den = num * d_ + n_ * den, den * d_
                terms[den] = terms.get(den, 0) + c * num
        return coverage, support, terms, points, first
    finally:
        free(bx)


def _first(t):
    return t[0]


def _exact_key(t):
    return (t[0], Fraction(t[1], t[2]))


cdef tuple _lift(tuple h, tuple key, int ax):
    """``cspace.minkowski.arrangements._lift`` (its reference): the canonical homogeneous 3D
    point of the projected point ``h = (x, y, w)`` of plane ``key = (n0, n1, n2, d)``."""
    cdef int a = (ax + 1) % 3, b = (ax + 2) % 3
    x, y, w = h
    na, nb, nx, d = key[a], key[b], key[ax], key[3]
    P = [0, 0, 0]
    P[a], P[b] = x * nx, y * nx
    P[ax] = d * w - na * x - nb * y
    W = w * nx
    if W < 0:
        P[0], P[1], P[2], W = -P[0], -P[1], -P[2], -W
    g = gcd(P[0], P[1], P[2], W)
    return (P[0] // g, P[1] // g, P[2] // g, W // g)


cdef int _hsign_cmp_y(tuple a, tuple p):
    """Sign of ``y(a) - y(p)`` for canonical homogeneous points (``W > 0``)."""
    l = a[1] * p[2]
    r = p[1] * a[2]
    return (l > r) - (l < r)


cdef int _horient3(tuple a, tuple b, tuple p):
    """Orientation of three canonical homogeneous points (``W > 0``: the sign of the 3 x 3
    determinant is the orientation)."""
    d = (a[0] * (b[1] * p[2] - b[2] * p[1]) - a[1] * (b[0] * p[2] - b[2] * p[0])
         + a[2] * (b[0] * p[1] - b[1] * p[0]))
    return (d > 0) - (d < 0)


cdef bint _winds_around(list H, list origin, list cycle, tuple p) except -1:
    """Is the winding number of the half-edge ``cycle`` around ``p`` (not on it) non-zero?
    (``cspace.geometry.homogeneous._hwinding``'s rule.)"""
    cdef Py_ssize_t w = 0, n = len(cycle), i
    cdef tuple a, b
    for i in range(n):
        a = H[origin[cycle[i]]]
        b = H[origin[cycle[i + 1 if i + 1 < n else 0]]]
        if _hsign_cmp_y(a, p) <= 0:
            if _hsign_cmp_y(b, p) > 0 and _horient3(a, b, p) > 0:
                w += 1
        elif _hsign_cmp_y(b, p) <= 0 and _horient3(a, b, p) < 0:
            w -= 1
    return w != 0


cdef list _hole_hosts(list H, list origin, list cycles, list signs, list comp):
    """``host[k]``: for each non-positive cycle ``k`` (a component's outer boundary), the
    positive cycle of another component that holds it innermost (the smallest by exact area
    strictly around the component's lexicographically smallest vertex), -1 for none
    (``Arrangement2D._host``'s answer: nested cycles have distinct areas, so the innermost
    is one cycle however it is searched)."""
    cdef Py_ssize_t ncyc = len(cycles), k, q, v, best
    cdef list host = [-1] * ncyc, pos = [], comp_of = [0] * ncyc
    cdef dict area = {}
    for k in range(ncyc):
        comp_of[k] = comp[origin[cycles[k][0]]]
        if signs[k] > 0:
            pos.append(k)
    for k in range(ncyc):
        if signs[k] > 0:
            continue
        v = min([origin[h] for h in cycles[k]])
        p = H[v]
        best = -1
        for q in pos:
            if comp_of[q] == comp[v] or not _winds_around(H, origin, cycles[q], p):
                continue
            if q not in area:
                area[q] = _harea(H, origin, cycles[q])
            if best < 0 or area[q][0] * area[best][1] < area[best][0] * area[q][1]:
                best = q
        host[k] = best
    return host


def one_facet_faces(list segs, list labels, c, int src, dict known, tuple key, int ax):
    """The sub-facets of a plane covered by one convex superset facet whose whole boundary is
    among ``segs`` (``cspace.minkowski.arrangements._PlaneJobs.arrange``'s one-facet case;
    that Python path is the reference and gives identical outputs): ``(lifted, faces)``, or
    None where the arrangement has an isolated vertex: the Python path then runs.

    Every bounded face lies in the facet, so each is one sub-facet of coverage ``c``: a
    positive cycle with, as holes, the outer boundaries of the components it holds
    innermost (:func:`_hole_hosts`; closed loops of cuts inside the facet), in cycle order;
    ``lifted[v]`` is ``known[H[v]]`` or the point lifted to plane ``key`` (projected along
    axis ``ax``). A face holding a bridge (a cut that ends inside the facet: a half-edge and
    its twin in the face's cycles) gets the lifted :func:`ring_inner_point` of its outer
    ring and holes, the point strictly inside it that the reference makes; the others need
    none."""
    cdef Py_ssize_t k, h, nh, ncyc, roots = 0, f1, f2
    (H, _vl, _E, _el, origin, isolated, _nxt, cycles, cyc_of, signs,
     comp) = arrangement_core(segs, labels)
    if isolated:
        return None
    for k in range(len(comp)):
        if <Py_ssize_t> comp[k] == k:
            roots += 1
    ncyc = len(cycles)
    # The face of each cycle: a positive cycle is its own bounded face; a non-positive one
    # (a component's outer boundary) is a hole of the face holding its component, or of
    # the unbounded face (-1; with one component, all of them).
    face_of = list(range(ncyc))
    holes = {}
    if roots > 1:
        host = _hole_hosts(H, origin, cycles, signs, comp)
    for k in range(ncyc):
        if signs[k] <= 0:
            face_of[k] = host[k] if roots > 1 else -1
            if face_of[k] >= 0:
                holes.setdefault(face_of[k], []).append(k)
    # A bridge (dangling cut, tree, a cut joining a loop to the boundary) has one face on
    # both sides.
    nh = len(cyc_of)
    bridged = set()
    for h in range(0, nh, 2):
        f1 = face_of[cyc_of[h]]
        f2 = face_of[cyc_of[h + 1]]
        if f1 == f2 and f1 >= 0:
            bridged.add(f1)
    lifted = []
    for p in H:
        q = known.get(p)
        lifted.append(q if q is not None else _lift(p, key, ax))
    faces = []
    if c:
        for k in range(ncyc):
            if signs[k] > 0:
                rings = [[origin[h] for h in cycles[k]]]
                for j in holes.get(k, ()):
                    rings.append([origin[h] for h in cycles[j]])
                ring = rings[0]
                if k in bridged:
                    others = [v for r in rings[1:] for v in r]
                    point = _lift(ring_inner_point(H, ring, others), key, ax)
                else:
                    point = None
                tris = [tuple(ring)] if len(ring) == 3 and len(rings) == 1 else None
                faces.append((c, rings, tris, src, point))
    return lifted, faces


def one_facet_plane(list corners, list tl, list pinned, list cut3, int ax, c, int src, tuple key):
    """A one-facet plane from its inputs (``_PlaneJobs.arrange``'s data: the corners of
    triangles ``tl``, the pinned flags by ``3 t + j``, the cuts ``cut3`` as homogeneous 3D
    points, the projection axis ``ax``, the plane's ``key``): the pinned facet edges and the
    projected cuts are arranged and read by :func:`one_facet_faces` (None where it declines).
    The Python
    reference is the same path in ``arrange(p, compiled=False)``; with one facet no edge is
    of the minority orientation, so exactly the pinned edges join the cuts."""
    cdef int a = (ax + 1) % 3, b = (ax + 2) % 3
    cdef Py_ssize_t i, j, t, k
    cdef list segs = [], labels = [], poly
    cdef dict known = {}
    for i in range(len(tl)):
        t = tl[i]
        poly = []
        for q in corners[t]:
            h = (q[a], q[b], 1)
            poly.append(h)
            known[h] = (q[0], q[1], q[2], 1)
        for j in range(3):
            if pinned[3 * t + j]:
                segs.append((poly[j], poly[(j + 1) % 3]))
                labels.append((i, j))
    proj = projected_segments(cut3, ax)
    for k in range(len(proj)):
        x, y = cut3[k]
        px, py = proj[k]
        known[px] = x
        known[py] = y
        segs.append(proj[k])
        labels.append((-1, k))
    return one_facet_faces(segs, labels, c, src, known, key, ax)


# Bridging a face's holes to its outer polygon (the loop of
# cspace.minkowski.triangulation._bridge_holes_reference): every direction below starts at one
# point ``o``, so the signs of the reference's integer cross and dot products of ``_hdir``
# vectors (positive multiples of ``u - o``) are ``orient(o, u, v)`` and the sign of
# ``(u - o) . (v - o)``.

cdef struct _Cand:
    double d
    Py_ssize_t i, j


cdef int _cand_cmp(const void* pa, const void* pb) noexcept nogil:
    cdef const _Cand* a = <const _Cand*> pa
    cdef const _Cand* b = <const _Cand*> pb
    if a.d < b.d:
        return -1
    if a.d > b.d:
        return 1
    if a.i != b.i:
        return -1 if a.i < b.i else 1
    if a.j != b.j:
        return -1 if a.j < b.j else 1
    return 0


cdef inline int _odot(_Points P, Py_ssize_t o, Py_ssize_t u, Py_ssize_t v) except -2:
    """Sign of ``(u - o) . (v - o)`` (``_dot_sign`` is that of ``(o - u) . (v - o)``)."""
    return -_dot_sign(P, u, o, v)


cdef inline int _half_from(_Points P, Py_ssize_t o, Py_ssize_t a, Py_ssize_t d) except -2:
    cdef int c = P.orient(o, a, d)
    return 0 if (c > 0 or (c == 0 and _odot(P, o, a, d) > 0)) else 1


cdef bint _in_cone_from(_Points P, Py_ssize_t o, Py_ssize_t d, Py_ssize_t a,
                        Py_ssize_t b) except -1:
    """The reference's ``_in_cone(_hdir(o, d), _hdir(o, a), _hdir(o, b))``."""
    cdef int hd = _half_from(P, o, a, d), hb
    if hd == 0 and P.orient(o, a, d) == 0:
        return False
    hb = _half_from(P, o, a, b)
    if hb == 0 and P.orient(o, a, b) == 0:
        return True
    if hd != hb:
        return hd < hb
    return P.orient(o, d, b) > 0


cdef bint _on_segment(_Points P, Py_ssize_t x, Py_ssize_t p, Py_ssize_t q) except -1:
    """The reference's ``_hon_segment(x, p, q)``."""
    if P.orient(p, q, x) != 0:
        return False
    if p == q:
        return x == p
    return P.between(p, q, x, 0 if P.cmp(p, q, 0) != 0 else 1)


cdef bint _bridge_ok_c(_Points P, Py_ssize_t* poly, Py_ssize_t n, Py_ssize_t i,
                       Py_ssize_t* hole, Py_ssize_t m, Py_ssize_t j, Py_ssize_t* ea,
                       Py_ssize_t* eb, Py_ssize_t ne) except -1:
    """The reference's ``_bridge_ok`` over the edges ``ea[k] -> eb[k]`` of every ring."""
    cdef Py_ssize_t o = poly[i], h = hole[j], k, a, b
    if o == h:
        return False
    if not _in_cone_from(P, o, h, poly[i + 1 if i + 1 < n else 0], poly[i - 1 if i > 0 else n - 1]):
        return False
    if not _in_cone_from(P, h, o, hole[j + 1 if j + 1 < m else 0], hole[j - 1 if j > 0 else m - 1]):
        return False
    for k in range(ne):
        a, b = ea[k], eb[k]
        if a != o and a != h and _on_segment(P, a, o, h):
            return False
        if (P.orient(a, b, o) * P.orient(a, b, h) < 0
                and P.orient(o, h, a) * P.orient(o, h, b) < 0):
            return False
    return True


def bridge_holes(list Ps, list ids, list pending):
    """``cspace.minkowski.triangulation._bridge_holes_reference`` (identical outputs): join each
    hole of ``pending`` (``(points, ids)`` pairs) to the polygon ``(Ps, ids)`` by a bridge
    between mutually visible occurrences, nearest pairs first; returns the bridged
    ``(points, ids)``. Raises AssertionError when no hole can be bridged (never for a face)."""
    cdef _Points P = _Points(len(Ps) + 1)
    cdef Py_ssize_t n, m, hi, k, r, i, j, ne, nc, c
    cdef Py_ssize_t* poly = NULL
    cdef Py_ssize_t* hole = NULL
    cdef Py_ssize_t* ea = NULL
    cdef Py_ssize_t* eb = NULL
    cdef _Cand* cands = NULL
    cdef bint done
    cdef double dx, dy
    poly_ids = [P.add(<tuple> p) for p in Ps]
    holes = [([P.add(<tuple> p) for p in hp], list(hid)) for hp, hid in pending]
    ids = list(ids)
    try:
        while holes:
            # every ring's edges, the polygon's first (the reference's ``others``)
            ne = len(poly_ids) + sum(len(h) for h, _ in holes)
            free(ea)
            free(eb)
            ea = <Py_ssize_t*> malloc((ne + 1) * sizeof(Py_ssize_t))
            eb = <Py_ssize_t*> malloc((ne + 1) * sizeof(Py_ssize_t))
            if not (ea and eb):
                raise MemoryError()
            c = 0
            for ring in [poly_ids] + [h for h, _ in holes]:
                r = len(ring)
                for k in range(r):
                    ea[c] = <Py_ssize_t> ring[k]
                    eb[c] = <Py_ssize_t> ring[k + 1 if k + 1 < r else 0]
                    c += 1
            n = len(poly_ids)
            free(poly)
            poly = <Py_ssize_t*> malloc((n + 1) * sizeof(Py_ssize_t))
            if not poly:
                raise MemoryError()
            for k in range(n):
                poly[k] = <Py_ssize_t> poly_ids[k]
            done = False
            for hi in range(len(holes)):
                hole_ids, hid = holes[hi]
                m = len(hole_ids)
                free(hole)
                free(cands)
                hole = <Py_ssize_t*> malloc((m + 1) * sizeof(Py_ssize_t))
                cands = <_Cand*> malloc((n * m + 1) * sizeof(_Cand))
                if not (hole and cands):
                    raise MemoryError()
                for k in range(m):
                    hole[k] = <Py_ssize_t> hole_ids[k]
                nc = 0
                for i in range(n):
                    for j in range(m):
                        dx = P.x[hole[j]] - P.x[poly[i]]
                        dy = P.y[hole[j]] - P.y[poly[i]]
                        cands[nc].d = dx * dx + dy * dy
                        cands[nc].i = i
                        cands[nc].j = j
                        nc += 1
                qsort(cands, nc, sizeof(_Cand), _cand_cmp)
                for k in range(nc):
                    i, j = cands[k].i, cands[k].j
                    if _bridge_ok_c(P, poly, n, i, hole, m, j, ea, eb, ne):
                        poly_ids = (poly_ids[:i + 1] + hole_ids[j:] + hole_ids[:j]
                                    + [hole_ids[j], poly_ids[i]] + poly_ids[i + 1:])
                        ids = ids[:i + 1] + hid[j:] + hid[:j] + [hid[j], ids[i]] + ids[i + 1:]
                        holes.pop(hi)
                        done = True
                        break
                if done:
                    break
            if not done:
                raise AssertionError("no bridge found for a hole")
        return [P.h[k] for k in poly_ids], ids
    finally:
        free(poly)
        free(hole)
        free(ea)
        free(eb)
        free(cands)


cdef bytes _vec_bytes(_Vec* v):
    return PyBytes_FromStringAndSize(<char*> v.a, v.n * sizeof(Py_ssize_t)) if v.n else b""


def assemble_complex(dict done, Py_ssize_t n_planes, list members, list sign, list sigma,
                     list corners, list weight, list facet):
    """The sub-facets of every plane gathered with global vertex ids: the loop of
    ``cspace.minkowski.arrangements._assemble_reference`` (identical outputs). ``done[p]``
    is plane ``p``'s ``(lifted, faces)`` (consumed); a plane not in it holds uncut
    triangles, each its own sub-facet, counter-clockwise. Returns the vertex table ``vid``
    (canonical point -> id, in order of first use), the per-sub-facet lists (plane, coverage,
    triangles or None, rings or None, source facet, point) and every boundary half-edge's
    from / to / sub-facet as native ``Py_ssize_t`` bytes."""
    cdef dict vid = {}
    cdef list face_plane = [], face_cov = [], face_tris = [], face_rings = [], face_src = []
    cdef list face_point = [], g, mapped, ring, cs, lifted, faces
    cdef Py_ssize_t p, t, fid, g0, g1, g2, k, n, x
    cdef int ccw
    cdef _Vec ru, rv, rf
    ru.a = rv.a = rf.a = NULL
    ru.n = rv.n = rf.n = ru.cap = rv.cap = rf.cap = 0
    try:
        for p in range(n_planes):
            res = done.pop(p, None)
            if res is None:  # uncut triangles: each its own sub-facet, counter-clockwise
                for t in members[p]:
                    ccw = sign[t] * sigma[p]
                    cs = corners[t]
                    if ccw > 0:
                        c0, c1, c2 = cs[0], cs[1], cs[2]
                    else:
                        c0, c1, c2 = cs[2], cs[1], cs[0]
                    g0 = vid.setdefault((c0[0], c0[1], c0[2], 1), len(vid))
                    g1 = vid.setdefault((c1[0], c1[1], c1[2], 1), len(vid))
                    g2 = vid.setdefault((c2[0], c2[1], c2[2], 1), len(vid))
                    fid = len(face_plane)
                    face_plane.append(p)
                    face_cov.append(ccw * weight[t])
                    face_tris.append([(g0, g1, g2)])
                    face_rings.append(None)
                    face_src.append(facet[t])
                    face_point.append(None)
                    _push(&ru, g0); _push(&ru, g1); _push(&ru, g2)
                    _push(&rv, g1); _push(&rv, g2); _push(&rv, g0)
                    _push(&rf, fid); _push(&rf, fid); _push(&rf, fid)
                continue
            lifted, faces = res
            g = [vid.setdefault(q, len(vid)) for q in lifted]
            for cov, rings, tris, src, point in faces:
                fid = len(face_plane)
                face_plane.append(p)
                face_cov.append(cov)
                mapped = [[g[v] for v in r] for r in rings]
                if tris is None:
                    face_tris.append(None)
                    face_rings.append(mapped)
                else:
                    face_tris.append([(g[a], g[b], g[c]) for a, b, c in tris])
                    face_rings.append(None)
                face_src.append(src)
                face_point.append(point)
                for ring in mapped:
                    n = len(ring)
                    for k in range(n):
                        x = ring[k]
                        _push(&ru, x)
                        _push(&rv, <Py_ssize_t> ring[k + 1 if k + 1 < n else 0])
                        _push(&rf, fid)
        return (vid, face_plane, face_cov, face_tris, face_rings, face_src, face_point,
                _vec_bytes(&ru), _vec_bytes(&rv), _vec_bytes(&rf))
    finally:
        free(ru.a)
        free(rv.a)
        free(rf.a)
