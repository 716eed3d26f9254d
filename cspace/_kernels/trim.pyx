# cython: language_level=3, boundscheck=False, wraparound=False, cdivision=True, initializedcheck=False
"""Compiled kernel of :mod:`cspace.trim`: the rounding check's float filters over triangle
pairs (which pairs are left to the exact test).

Line for line the pure-Python reference ``cspace.trim._undecided_pairs`` and its helpers,
the same float operations in the same order (compiled without FMA contraction): identical
outputs. A filter that cannot decide returns "not separated", so a pair is only ever passed
on to the exact test, never dropped on a guess.
"""

import numpy as np

from libc.math cimport INFINITY, fabs

cdef double _ORIENT_FILTER = 16 * 2.0 ** -52 / 2  # as cspace.trim (eps = 2**-52)
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
    (see the reference ``cspace.trim._undecided_pairs``)."""
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
