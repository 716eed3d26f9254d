# cython: language_level=3, boundscheck=False, wraparound=False, cdivision=True, initializedcheck=False
"""Compiled kernels of :mod:`cspace.minkowski.ncc_cvms`'s rounding check: the float filters over
triangle pairs (which pairs are left to the exact test, :func:`undecided_pairs`), the
float64 coordinates of the exact output points (:func:`to_float`), which of them rounding
moved (:func:`moved_points`) and the triangles' integer boxes (:func:`triangle_boxes`).

:func:`undecided_pairs` is line for line the pure-Python reference
``cspace.mesh.self_intersection._undecided_pairs`` and its helpers, the same float operations in the same
order (compiled without FMA contraction): identical outputs. A filter that cannot decide
returns "not separated", so a pair is only ever passed on to the exact test, never dropped
on a guess. The other three compute what their references compute (the same correctly
rounded operations, or exact integer tests in int64 / __int128 with the bounds stated at
each) and leave what they cannot take to the reference: identical outputs
(``tests/test_kernels_rounding.py``).
"""

import numpy as np

from cpython.long cimport PyLong_AsLongLongAndOverflow, PyLong_AsUnsignedLongLongMask
from libc.math cimport INFINITY, ceil, fabs, floor, frexp, isfinite, ldexp

cdef double _ORIENT_FILTER = 16 * 2.0 ** -52 / 2  # as cspace.minkowski.ncc_cvms (eps = 2**-52)
cdef double _DOT_FILTER = 8 * 2.0 ** -52 / 2


cdef inline double _min(double a, double b) noexcept nogil:
    return b if b < a else a


cdef inline double _max(double a, double b) noexcept nogil:
    return b if b > a else a


cdef inline int _o2f(const double[:, ::1] V, long long u, long long a, long long b, int k0,
                     int k1) noexcept nogil:
    cdef double x1 = V[a, k0] - V[u, k0], y1 = V[a, k1] - V[u, k1]
    cdef double x2 = V[b, k0] - V[u, k0], y2 = V[b, k1] - V[u, k1]
    cdef double det = x1 * y2 - y1 * x2
    if fabs(det) > _ORIENT_FILTER * (fabs(x1 * y2) + fabs(y1 * x2)):
        return 1 if det > 0 else -1
    return 0


cdef inline bint _plane_separates(const double[:, ::1] V, const long long* ti,
                                  const long long* tj) noexcept nogil:
    cdef long long a = ti[0], b = ti[1], c = ti[2], x
    cdef double ux = V[b, 0] - V[a, 0], uy = V[b, 1] - V[a, 1], uz = V[b, 2] - V[a, 2]
    cdef double vx = V[c, 0] - V[a, 0], vy = V[c, 1] - V[a, 1], vz = V[c, 2] - V[a, 2]
    cdef double nx = uy * vz - uz * vy, ny = uz * vx - ux * vz, nz = ux * vy - uy * vx
    cdef double wx, wy, wz, det, perm
    cdef int side = 0, s, k
    for k in range(3):
        x = tj[k]
        if x == a or x == b or x == c:
            continue
        wx = V[x, 0] - V[a, 0]
        wy = V[x, 1] - V[a, 1]
        wz = V[x, 2] - V[a, 2]
        det = nx * wx + ny * wy + nz * wz
        perm = (fabs(ux) * (fabs(vy * wz) + fabs(vz * wy)) + fabs(uy) * (fabs(vz * wx) + fabs(vx * wz))
                + fabs(uz) * (fabs(vx * wy) + fabs(vy * wx)))
        if not fabs(det) > _ORIENT_FILTER * perm:
            return False
        s = 1 if det > 0 else -1
        if side != 0 and s != side:
            return False
        side = s
    return side != 0


cdef inline bint _ray_outside(const double[:, ::1] V, long long u, long long x, long long p,
                              long long q, int k0, int k1) noexcept nogil:
    cdef int o = _o2f(V, u, p, q, k0, k1)
    return o != 0 and (_o2f(V, u, p, x, k0, k1) * o < 0 or _o2f(V, u, x, q, k0, k1) * o < 0)


cdef inline int _dominant_axis(const double[:, ::1] V, const long long* ti) noexcept nogil:
    cdef long long a = ti[0], b = ti[1], c = ti[2]
    cdef double ux = V[b, 0] - V[a, 0], uy = V[b, 1] - V[a, 1], uz = V[b, 2] - V[a, 2]
    cdef double vx = V[c, 0] - V[a, 0], vy = V[c, 1] - V[a, 1], vz = V[c, 2] - V[a, 2]
    cdef double n0 = fabs(uy * vz - uz * vy), n1 = fabs(uz * vx - ux * vz)
    cdef double n2 = fabs(ux * vy - uy * vx)
    return 0 if (n0 >= n1 and n0 >= n2) else (1 if n1 >= n2 else 2)


cdef inline bint _axes_apart(const double[:, ::1] V, const long long* ti,
                             const long long* tj) noexcept nogil:
    cdef int i, j, k
    cdef long long p, q, r, t, x, y
    cdef double ex, ey, ez, fx, fy, fz, ax, ay, az, d, e, lo_a, lo_b, hi_a, hi_b
    for i in range(3):
        p = ti[i]
        q = ti[(i + 1) % 3]
        ex = V[q, 0] - V[p, 0]
        ey = V[q, 1] - V[p, 1]
        ez = V[q, 2] - V[p, 2]
        for j in range(3):
            r = tj[j]
            t = tj[(j + 1) % 3]
            fx = V[t, 0] - V[r, 0]
            fy = V[t, 1] - V[r, 1]
            fz = V[t, 2] - V[r, 2]
            ax = ey * fz - ez * fy
            ay = ez * fx - ex * fz
            az = ex * fy - ey * fx
            lo_a = INFINITY
            lo_b = INFINITY
            hi_a = -INFINITY
            hi_b = -INFINITY
            for k in range(3):
                x = ti[k]
                d = V[x, 0] * ax + V[x, 1] * ay + V[x, 2] * az
                e = _DOT_FILTER * (fabs(V[x, 0] * ax) + fabs(V[x, 1] * ay) + fabs(V[x, 2] * az))
                lo_a = _min(lo_a, d - e)
                hi_a = _max(hi_a, d + e)
                y = tj[k]
                d = V[y, 0] * ax + V[y, 1] * ay + V[y, 2] * az
                e = _DOT_FILTER * (fabs(V[y, 0] * ax) + fabs(V[y, 1] * ay) + fabs(V[y, 2] * az))
                lo_b = _min(lo_b, d - e)
                hi_b = _max(hi_b, d + e)
            if hi_a < lo_b or hi_b < lo_a:
                return True
    return False


cdef inline bint _apart_in_projection(const double[:, ::1] V, const long long* ti,
                                      const long long* tj, int ax) noexcept nogil:
    cdef int k0 = (ax + 1) % 3, k1 = (ax + 2) % 3
    cdef int mi = 0, mj = 0, shared = 0, r, s, flip, k, m, o, ku, kj
    cdef const long long* A_
    cdef const long long* B_
    cdef long long p, q, o3, ai, aj, e0, e1, u, v, pa, pb, pc, pd
    cdef bint out
    for r in range(3):
        for s in range(3):
            if ti[r] == tj[s]:
                mi |= 1 << r
                mj |= 1 << s
                shared += 1
    if shared == 0:
        for flip in range(2):
            A_ = ti if flip == 0 else tj
            B_ = tj if flip == 0 else ti
            for k in range(3):
                p = A_[k]
                q = A_[(k + 1) % 3]
                o3 = A_[(k + 2) % 3]
                o = _o2f(V, p, q, o3, k0, k1)
                if o == 0:
                    continue
                out = True
                for m in range(3):
                    if not _o2f(V, p, q, B_[m], k0, k1) * o < 0:
                        out = False
                        break
                if out:
                    return True
        return False
    if shared == 2:
        ai = ti[0] if not mi & 1 else (ti[1] if not mi & 2 else ti[2])
        aj = tj[0] if not mj & 1 else (tj[1] if not mj & 2 else tj[2])
        e0 = -1
        e1 = -1
        for r in range(3):
            if mi >> r & 1:
                if e0 < 0:
                    e0 = ti[r]
                else:
                    e1 = ti[r]
        u = e0 if e0 < e1 else e1
        v = e1 if e0 < e1 else e0
        return _o2f(V, u, v, ai, k0, k1) * _o2f(V, u, v, aj, k0, k1) < 0
    if shared == 1:
        ku = 0 if mi & 1 else (1 if mi & 2 else 2)
        kj = 0 if mj & 1 else (1 if mj & 2 else 2)
        u = ti[ku]
        pa = ti[(ku + 1) % 3]
        pb = ti[(ku + 2) % 3]
        pc = tj[(kj + 1) % 3]
        pd = tj[(kj + 2) % 3]
        return (_ray_outside(V, u, pc, pa, pb, k0, k1) and _ray_outside(V, u, pd, pa, pb, k0, k1)
                and _ray_outside(V, u, pa, pc, pd, k0, k1)
                and _ray_outside(V, u, pb, pc, pd, k0, k1))
    return False


def undecided_pairs(const double[:, ::1] V, const long long[:, ::1] T,
                    const long long[:, ::1] pairs, const unsigned char[::1] moved):
    """Mask of the box-overlapping pairs that the float filters leave to the exact test
    (see the reference ``cspace.mesh.self_intersection._undecided_pairs``)."""
    out_arr = np.zeros(pairs.shape[0], dtype=np.bool_)
    cdef unsigned char[::1] out = out_arr.view(np.uint8)
    cdef Py_ssize_t r
    cdef const long long* ti
    cdef const long long* tj
    cdef int ax, k
    cdef bint lone
    with nogil:
        for r in range(pairs.shape[0]):
            ti = &T[pairs[r, 0], 0]
            tj = &T[pairs[r, 1], 0]
            if not (moved[ti[0]] or moved[ti[1]] or moved[ti[2]] or moved[tj[0]]
                    or moved[tj[1]] or moved[tj[2]]):
                continue
            if _plane_separates(V, ti, tj) or _plane_separates(V, tj, ti):
                continue
            ax = _dominant_axis(V, ti)
            if (_apart_in_projection(V, ti, tj, ax)
                    or _apart_in_projection(V, ti, tj, (ax + 1) % 3)
                    or _apart_in_projection(V, ti, tj, (ax + 2) % 3)):
                continue
            lone = True
            for k in range(3):
                if ti[k] == tj[0] or ti[k] == tj[1] or ti[k] == tj[2]:
                    lone = False
            out[r] = not (lone and _axes_apart(V, ti, tj))
    return out_arr


# --------------------------------------------------------------------------------------------
# which vertices rounding to float64 moved (reference: cspace.minkowski.rounding._moved)

cdef extern from *:
    """
    typedef unsigned __int128 cs_trim_u128;
    typedef __int128 cs_trim_i128;
    """
    # Cython sees them as 64-bit types; they are only ever used in C arithmetic here.
    ctypedef unsigned long long u128 "cs_trim_u128"
    ctypedef long long i128 "cs_trim_i128"
    int __builtin_ctzll(unsigned long long) nogil

# Per-point answers of moved_points: decided kept, decided moved, left to the reference.
cdef enum:
    KEPT = 0
    MOVED = 1
    UNDECIDED = 2

# The fast path takes |num| < 2**62 and 0 < w < 2**62 (int64 with room for the checks).
cdef long long _LIMIT = 1LL << 62


cdef int _read_ints(object P, Py_ssize_t size, long long* p, unsigned long long* pm):
    """Read a tuple of ``size`` Python ints into ``p`` (int64) and ``pm`` (each modulo
    2**64): -1 if ``P`` is not such a tuple (the caller leaves it to the reference), 1 if
    every int fits int64 (then ``p`` holds them), 0 if not (``p`` then holds garbage)."""
    cdef int ov, fits = 1
    cdef Py_ssize_t k
    if type(P) is not tuple or len(<tuple>P) != size:
        return -1
    for k in range(size):
        c = (<tuple>P)[k]
        if type(c) is not int:
            return -1
        p[k] = PyLong_AsLongLongAndOverflow(c, &ov)
        if ov:
            fits = 0
            pm[k] = PyLong_AsUnsignedLongLongMask(c)  # c modulo 2**64
        else:
            pm[k] = <unsigned long long>p[k]
    return fits


cdef inline bint _differs(double x, long long num, long long w, int e) noexcept nogil:
    """``x != num / w * 2**e`` exactly, for a finite ``x``, ``|num| < 2**62``, ``0 < w < 2**62``.

    With ``|x| = m 2**(ex - 53)`` (``m < 2**53`` an integer, from frexp: exact) the two are
    equal iff the signs agree and ``a 2**s == b`` for ``a = m w < 2**115`` (unsigned
    __int128), ``b = |num| < 2**62`` and ``s = ex - 53 - e``: for ``s >= 0`` iff ``b``'s low
    ``s`` bits are zero and ``b >> s == a`` (``s >= 62``: ``a 2**s >= 2**62 > b``); for
    ``s < 0`` iff ``a``'s low ``-s`` bits are zero and ``a >> -s == b`` (``-s >= 115``:
    ``0 < a 2**s < 1`` is no integer). Integer operations only: nothing rounds."""
    cdef int ex, s
    cdef double f
    cdef unsigned long long m, b
    cdef u128 a
    if x == 0:
        return num != 0
    if num == 0 or (x < 0) != (num < 0):
        return True
    f = frexp(fabs(x), &ex)  # |x| = f 2**ex, 1/2 <= f < 1, f with at most 53 bits
    m = <unsigned long long>ldexp(f, 53)
    b = <unsigned long long>(-num if num < 0 else num)
    a = (<u128>m) * (<u128>w)
    s = ex - 53 - e
    if s >= 0:
        if s >= 62:
            return True
        return (b & ((1ULL << s) - 1)) != 0 or (<u128>(b >> s)) != a
    s = -s
    if s >= 115:
        return True
    return (a & (((<u128>1) << s) - 1)) != 0 or (a >> s) != (<u128>b)


cdef inline bint _differs_mod(double x, unsigned long long num, unsigned long long w,
                              int e) noexcept nogil:
    """A sure ``x != num / w * 2**e`` (``num``, ``w``: the integers modulo 2**64, any size),
    for a finite ``x`` and ``w > 0``; False: undecided.

    With ``x = m 2**k`` (``m`` odd, ``|m| < 2**53``) and ``d = k - e`` equality means the
    integer identity ``num == m w 2**d`` (``d >= 0``) or ``num 2**-d == m w`` (``d < 0``);
    it then holds modulo 2**64 too, so sides that differ there (unsigned 64-bit arithmetic
    wraps modulo 2**64, exactly) prove the point moved."""
    cdef int ex, d, tz
    cdef double f
    cdef long long mi
    cdef unsigned long long m, lhs, rhs
    if x == 0:
        return num != 0
    f = frexp(x, &ex)  # x = f 2**ex, 1/2 <= |f| < 1
    mi = <long long>ldexp(f, 53)  # exact integer, |mi| < 2**53, nonzero
    tz = __builtin_ctzll(<unsigned long long>mi)
    mi = mi >> tz  # odd (arithmetic shift of the exact integer: exact)
    d = ex - 53 + tz - e
    m = <unsigned long long>mi  # modulo 2**64
    if d >= 0:
        lhs = num
        rhs = 0 if d >= 64 else (m * w) << d
    else:
        lhs = 0 if d <= -64 else num << (-d)
        rhs = m * w
    return lhs != rhs


def moved_points(list points, tuple origin, int e, const double[:, ::1] V):
    """Per homogeneous grid point ``P = points[i]`` (a tuple of 4 Python ints) whether its
    float64 row ``V[i]`` differs from ``(P[:3] / P[3] + origin) * 2**e`` (see the reference
    ``cspace.minkowski.rounding._moved``): int8, 0 kept, 1 moved, 2 left to the reference.

    Integers within int64: ``num = P[k] + origin[k] P[3]`` in __int128 (``< 2**127``), then
    :func:`_differs` decides both ways when ``|num| < 2**62`` and ``0 < P[3] < 2**62``.
    Larger integers (``P[3] > 0``): :func:`_differs_mod` on them modulo 2**64 proves most
    moved points moved; the rest (and a non-int, ``P[3] <= 0``, a non-finite row) are left."""
    cdef Py_ssize_t n = len(points), i
    state_arr = np.zeros(n, dtype=np.int8)
    cdef signed char[::1] state = state_arr
    cdef long long o[3]
    cdef long long p[4]
    cdef unsigned long long om[3]
    cdef unsigned long long pm[4]
    cdef i128 num
    cdef int k, read
    cdef double x
    if n and (not -2000 < e < 2000 or _read_ints(origin, 3, o, om) != 1):
        state_arr[:] = UNDECIDED
        return state_arr
    for i in range(n):
        P = points[i]
        read = _read_ints(P, 4, p, pm)
        if read < 0:
            state[i] = UNDECIDED
            continue
        if read == 0:
            state[i] = UNDECIDED
            if (<tuple>P)[3] > 0:
                for k in range(3):
                    if not isfinite(V[i, k]):
                        break
                    if _differs_mod(V[i, k], pm[k] + om[k] * pm[3], pm[3], e):
                        state[i] = MOVED
                        break
            continue
        if p[3] <= 0 or p[3] >= _LIMIT:
            state[i] = UNDECIDED
            continue
        for k in range(3):
            num = (<i128>p[k]) + (<i128>o[k]) * (<i128>p[3])
            x = V[i, k]
            if num >= <i128>_LIMIT or num <= -<i128>_LIMIT or not isfinite(x):
                state[i] = UNDECIDED
                break
            if _differs(x, <long long>num, p[3], e):
                state[i] = MOVED
                break
    return state_arr


# --------------------------------------------------------------------------------------------
# float64 coordinates of the exact points (reference: cspace.minkowski.output._to_float)

# Integers up to 2**53 are exact doubles.
cdef long long _EXACT = 1LL << 53


def to_float(list points, tuple origin, int e):
    """``(V, left)``: per homogeneous grid point ``P = points[i]`` (a tuple of 4 Python
    ints) the correctly rounded float64 ``(P[:3] + origin P[3]) / P[3]``, times ``2**e``
    (ldexp), as the reference ``cspace.minkowski.output._to_float`` computes it; ``left`` (bool) marks
    the rows this leaves to the reference (zeros here: not a tuple of 4 Python ints).

    Rows with ``|P[k] + origin[k] P[3]| <= 2**53`` (formed in __int128) and
    ``0 < P[3] <= 2**53``: both are exact doubles, so one IEEE division is the correctly
    rounded quotient, as Python's ``int / int`` (which does just that for such operands).
    Other rows: the reference's expression on Python ints (exact sum, correctly rounded
    ``int / int``; ``P[3] == 0`` raises ZeroDivisionError as there)."""
    cdef Py_ssize_t n = len(points), i
    V_arr = np.zeros((n, 3), dtype=np.float64)
    left_arr = np.zeros(n, dtype=np.bool_)
    cdef double[:, ::1] V = V_arr
    cdef unsigned char[::1] left = left_arr.view(np.uint8)
    cdef long long o[3]
    cdef long long p[4]
    cdef unsigned long long om[3]
    cdef unsigned long long pm[4]
    cdef i128 num[3]
    cdef int k, read
    cdef bint fits
    if n and (not -2000 < e < 2000 or _read_ints(origin, 3, o, om) != 1):
        left_arr[:] = True
        return V_arr, left_arr
    for i in range(n):
        P = points[i]
        read = _read_ints(P, 4, p, pm)
        if read < 0:
            left[i] = 1
            continue
        fits = read == 1 and 0 < p[3] <= _EXACT
        if fits:
            for k in range(3):
                num[k] = (<i128>p[k]) + (<i128>o[k]) * (<i128>p[3])
                if num[k] > <i128>_EXACT or num[k] < -<i128>_EXACT:
                    fits = False
        if fits:
            for k in range(3):
                V[i, k] = ldexp((<double>(<long long>num[k])) / (<double>p[3]), e)
        else:  # the reference's own Python int arithmetic and correctly rounded int / int
            w = (<tuple>P)[3]
            for k in range(3):
                V[i, k] = ldexp(<double>(((<tuple>P)[k] + origin[k] * w) / w), e)
    return V_arr, left_arr


def triangle_boxes(const double[:, ::1] V, const long long[:, ::1] T, int e):
    """``(lo, hi, ok)``: per triangle of ``T`` over float64 rows ``V`` the box
    ``floor(min * 2**-e)``, ``ceil(max * 2**-e)`` per axis (``(t, 3)`` int64), as the
    reference ``cspace.mesh.self_intersection._triangle_boxes`` computes it: the same min/max, ldexp,
    floor/ceil, then the cast. ``ok`` is False on a coordinate that is not finite or a box
    end not below 2**62 in magnitude (the cast would not be exact): the reference decides."""
    cdef Py_ssize_t t = T.shape[0], i
    lo_arr = np.zeros((t, 3), dtype=np.int64)
    hi_arr = np.zeros((t, 3), dtype=np.int64)
    cdef long long[:, ::1] lo = lo_arr
    cdef long long[:, ::1] hi = hi_arr
    cdef int k
    cdef double a, b, c, x, y, limit = 2.0 ** 62
    cdef bint ok = True
    with nogil:
        for i in range(t):
            for k in range(3):
                a = V[T[i, 0], k]
                b = V[T[i, 1], k]
                c = V[T[i, 2], k]
                if not (isfinite(a) and isfinite(b) and isfinite(c)):  # numpy's NaN rule
                    ok = False
                    break
                x = floor(ldexp(_min(_min(a, b), c), -e))
                y = ceil(ldexp(_max(_max(a, b), c), -e))
                if not (fabs(x) < limit and fabs(y) < limit):
                    ok = False
                    break
                lo[i, k] = <long long>x
                hi[i, k] = <long long>y
            if not ok:
                break
    return lo_arr, hi_arr, ok
