# cython: language_level=3, boundscheck=False, wraparound=False, cdivision=True, initializedcheck=False
"""Compiled kernels of :mod:`cspace.mesh.query`: ray-crossing membership on a (y, z) cell
grid, BVH nearest-triangle distances and BVH segment-triangle filters.

Line for line the pure-Python references in :mod:`cspace.mesh.query` (same names without the
leading underscore there), with the same float operations in the same order (compiled with
``-ffp-contract=off``): outputs are identical, and the filters' rigorous error bounds (16
unit roundoffs of the permanent, plus absolute terms for underflow) hold unchanged. Nothing
here decides an undecided sign: such queries are reported back for the exact path.
"""

import numpy as np

from libc.math cimport INFINITY, fabs, sqrt

cdef double _EPS = 2.0 ** -53
cdef double _FILTER = 16.0 * _EPS
cdef double _TINY = 2.0 ** -1000
cdef double _TINY3 = 2.0 ** -1070
cdef double _SLAB = 1e-14
cdef int _STATUS_UNSURE = 2


cdef inline double _min(double a, double b) noexcept nogil:
    # Python's min(a, b): a unless b < a
    return b if b < a else a


cdef inline double _max(double a, double b) noexcept nogil:
    # Python's max(a, b): a unless b > a
    return b if b > a else a


cdef inline void _o2(double au, double av, double bu, double bv, double pu, double pv,
                     double* val, double* err) noexcept nogil:
    cdef double l = (bu - au) * (pv - av)
    cdef double r = (bv - av) * (pu - au)
    val[0] = l - r
    err[0] = _FILTER * (fabs(l) + fabs(r)) + _TINY


cdef inline void _o3(double ax, double ay, double az, double bx, double by, double bz,
                     double cx, double cy, double cz, double dx, double dy, double dz,
                     double* val, double* err) noexcept nogil:
    cdef double adx = ax - dx, ady = ay - dy, adz = az - dz
    cdef double bdx = bx - dx, bdy = by - dy, bdz = bz - dz
    cdef double cdx = cx - dx, cdy = cy - dy, cdz = cz - dz
    cdef double bdxcdy = bdx * cdy, cdxbdy = cdx * bdy
    cdef double cdxady = cdx * ady, adxcdy = adx * cdy
    cdef double adxbdy = adx * bdy, bdxady = bdx * ady
    cdef double det = adz * (bdxcdy - cdxbdy) + bdz * (cdxady - adxcdy) + cdz * (adxbdy - bdxady)
    cdef double perm = ((fabs(bdxcdy) + fabs(cdxbdy)) * fabs(adz)
                        + (fabs(cdxady) + fabs(adxcdy)) * fabs(bdz)
                        + (fabs(adxbdy) + fabs(bdxady)) * fabs(cdz))
    cdef double tiny = (fabs(adz) + fabs(bdz) + fabs(cdz)) * _TINY3 + _TINY
    val[0] = det
    err[0] = _FILTER * perm + tiny


cdef inline bint _off_collinear(const double* T, double qx, double qy, double qz) noexcept nogil:
    # as the reference: an edge orientation with q certainly non-zero in (y, z) or (x, y)
    cdef double v, e
    _o2(T[1], T[2], T[4], T[5], qy, qz, &v, &e)
    if fabs(v) > e:
        return True
    _o2(T[4], T[5], T[7], T[8], qy, qz, &v, &e)
    if fabs(v) > e:
        return True
    _o2(T[7], T[8], T[1], T[2], qy, qz, &v, &e)
    if fabs(v) > e:
        return True
    _o2(T[0], T[1], T[3], T[4], qx, qy, &v, &e)
    if fabs(v) > e:
        return True
    _o2(T[3], T[4], T[6], T[7], qx, qy, &v, &e)
    if fabs(v) > e:
        return True
    _o2(T[6], T[7], T[0], T[1], qx, qy, &v, &e)
    return fabs(v) > e


cdef inline long _cell(double v, double v0, double inv, long n) noexcept nogil:
    cdef double f = (v - v0) * inv
    if not f > 0.0:
        return 0
    if f >= n - 1:
        return n - 1
    return <long>f


# ---- membership ---------------------------------------------------------------------------

def contains_kernel(const double[:, ::1] Q, const double[:, ::1] T, const double[:, ::1] lo,
                    const double[:, ::1] hi, const signed char[::1] sx,
                    const unsigned char[::1] degen, const long long[::1] cstart,
                    const long long[::1] ctris, double y0, double z0, double iy, double iz,
                    long ny, long nz, unsigned char[::1] out, unsigned char[::1] unsure):
    """``out[i]``: inside by the float filters; ``unsure[i]``: undecided (exact path).
    Returns the number of undecided queries."""
    cdef Py_ssize_t i, k, t
    cdef long c, w, status, s, dsign
    cdef long n_unsure = 0
    cdef double qx, qy, qz, ax, ay, az, bx, by, bz, cx, cy, cz
    cdef double d, e, v1, e1, v2, e2, v3, e3
    cdef bint inbox
    with nogil:
        for i in range(Q.shape[0]):
            qx = Q[i, 0]
            qy = Q[i, 1]
            qz = Q[i, 2]
            c = _cell(qy, y0, iy, ny) * nz + _cell(qz, z0, iz, nz)
            w = 0
            status = -1
            for k in range(cstart[c], cstart[c + 1]):
                t = ctris[k]
                if (qy < lo[t, 1] or qy > hi[t, 1] or qz < lo[t, 2] or qz > hi[t, 2]
                        or qx > hi[t, 0]):
                    continue
                inbox = qx >= lo[t, 0]
                if degen[t]:
                    if inbox and not _off_collinear(&T[t, 0], qx, qy, qz):
                        status = _STATUS_UNSURE
                        break
                    continue
                ax = T[t, 0]; ay = T[t, 1]; az = T[t, 2]
                bx = T[t, 3]; by = T[t, 4]; bz = T[t, 5]
                cx = T[t, 6]; cy = T[t, 7]; cz = T[t, 8]
                s = sx[t]
                if s != 0:
                    # the projection first (see the reference)
                    _o2(ay, az, by, bz, qy, qz, &v1, &e1)
                    _o2(by, bz, cy, cz, qy, qz, &v2, &e2)
                    _o2(cy, cz, ay, az, qy, qz, &v3, &e3)
                    if (s > 0 and (v1 < -e1 or v2 < -e2 or v3 < -e3)) or (
                            s < 0 and (v1 > e1 or v2 > e2 or v3 > e3)):
                        continue
                    if not (fabs(v1) > e1 and fabs(v2) > e2 and fabs(v3) > e3):
                        status = _STATUS_UNSURE
                        break
                dsign = 0
                if inbox:
                    _o3(ax, ay, az, bx, by, bz, cx, cy, cz, qx, qy, qz, &d, &e)
                    if not fabs(d) > e:
                        status = _STATUS_UNSURE
                        break
                    dsign = 1 if d > 0 else -1
                if s == 0:
                    continue
                if not inbox or dsign == s:
                    w += s
            if status == _STATUS_UNSURE:
                unsure[i] = 1
                n_unsure += 1
            else:
                out[i] = w != 0
    return n_unsure


def cell_candidates(const double[::1] q, const double[:, ::1] lo, const double[:, ::1] hi,
                    const long long[::1] cstart, const long long[::1] ctris, double y0,
                    double z0, double iy, double iz, long ny, long nz):
    """Triangles whose closed box holds ``q``'s (y, z) and reaches ``x >= q_x``."""
    cdef double qx = q[0], qy = q[1], qz = q[2]
    cdef long c = _cell(qy, y0, iy, ny) * nz + _cell(qz, z0, iz, nz)
    out_arr = np.zeros(cstart[c + 1] - cstart[c], dtype=np.int64)
    cdef long long[::1] out = out_arr
    cdef Py_ssize_t n = 0, k, t
    for k in range(cstart[c], cstart[c + 1]):
        t = ctris[k]
        if qy < lo[t, 1] or qy > hi[t, 1] or qz < lo[t, 2] or qz > hi[t, 2] or qx > hi[t, 0]:
            continue
        out[n] = t
        n += 1
    return out_arr[:n]


def cell_entries(const double[:, ::1] lo, const double[:, ::1] hi, double y0, double z0,
                 double iy, double iz, long ny, long nz):
    """Total number of (cell, triangle) entries :func:`build_cells` would make."""
    cdef long long total = 0
    cdef Py_ssize_t t
    cdef long a, b
    for t in range(lo.shape[0]):
        a = _cell(hi[t, 1], y0, iy, ny) - _cell(lo[t, 1], y0, iy, ny) + 1
        b = _cell(hi[t, 2], z0, iz, nz) - _cell(lo[t, 2], z0, iz, nz) + 1
        total += a * b
    return total


def build_cells(const double[:, ::1] lo, const double[:, ::1] hi, double y0, double z0,
                double iy, double iz, long ny, long nz):
    """CSR lists of the triangles whose (y, z) box meets each cell (same cell function)."""
    cdef Py_ssize_t m = lo.shape[0], t
    cdef long a, b
    count_arr = np.zeros(ny * nz + 1, dtype=np.int64)
    cdef long long[::1] count = count_arr
    for t in range(m):
        for a in range(_cell(lo[t, 1], y0, iy, ny), _cell(hi[t, 1], y0, iy, ny) + 1):
            for b in range(_cell(lo[t, 2], z0, iz, nz), _cell(hi[t, 2], z0, iz, nz) + 1):
                count[a * nz + b + 1] += 1
    start_arr = np.cumsum(count_arr)
    fill_arr = start_arr[:-1].copy()
    tris_arr = np.zeros(start_arr[-1], dtype=np.int64)
    cdef long long[::1] fill = fill_arr
    cdef long long[::1] tris = tris_arr
    for t in range(m):
        for a in range(_cell(lo[t, 1], y0, iy, ny), _cell(hi[t, 1], y0, iy, ny) + 1):
            for b in range(_cell(lo[t, 2], z0, iz, nz), _cell(hi[t, 2], z0, iz, nz) + 1):
                tris[fill[a * nz + b]] = t
                fill[a * nz + b] += 1
    return start_arr, tris_arr


# ---- bounding-volume hierarchy: distances and segments --------------------------------------

cdef inline double _box_dist2(double px, double py, double pz, const double* lo,
                              const double* hi) noexcept nogil:
    # lo, hi: the node's box rows (raw pointers: a memoryview argument would cost an atomic
    # reference count per call)
    cdef double d = 0.0, g
    # the reference's loop over the three axes, unrolled (same operations, same order)
    if px < lo[0]:
        g = lo[0] - px
        d += g * g
    elif px > hi[0]:
        g = px - hi[0]
        d += g * g
    if py < lo[1]:
        g = lo[1] - py
        d += g * g
    elif py > hi[1]:
        g = py - hi[1]
        d += g * g
    if pz < lo[2]:
        g = lo[2] - pz
        d += g * g
    elif pz > hi[2]:
        g = pz - hi[2]
        d += g * g
    return d


cdef inline double _seg_dist2(double px, double py, double pz, double ax, double ay, double az,
                              double bx, double by, double bz) noexcept nogil:
    cdef double ex = bx - ax, ey = by - ay, ez = bz - az
    cdef double wx = px - ax, wy = py - ay, wz = pz - az
    cdef double ee = ex * ex + ey * ey + ez * ez
    cdef double t = 0.0
    if ee > 0.0:
        t = _min(1.0, _max(0.0, (wx * ex + wy * ey + wz * ez) / ee))
    cdef double rx = wx - t * ex, ry = wy - t * ey, rz = wz - t * ez
    return rx * rx + ry * ry + rz * rz


cdef inline double _edge_side(double ux, double uy, double uz, double vx, double vy, double vz,
                              double px, double py, double pz, double nx, double ny,
                              double nz) noexcept nogil:
    cdef double ex = vx - ux, ey = vy - uy, ez = vz - uz
    cdef double wx = px - ux, wy = py - uy, wz = pz - uz
    return (ey * wz - ez * wy) * nx + (ez * wx - ex * wz) * ny + (ex * wy - ey * wx) * nz


cdef inline double _tri_dist2(double px, double py, double pz, const double* T) noexcept nogil:
    # T: the triangle's row of 9 coordinates
    cdef double ax = T[0], ay = T[1], az = T[2]
    cdef double bx = T[3], by = T[4], bz = T[5]
    cdef double cx = T[6], cy = T[7], cz = T[8]
    cdef double best = _min(_min(_seg_dist2(px, py, pz, ax, ay, az, bx, by, bz),
                                 _seg_dist2(px, py, pz, bx, by, bz, cx, cy, cz)),
                            _seg_dist2(px, py, pz, cx, cy, cz, ax, ay, az))
    cdef double e0x = bx - ax, e0y = by - ay, e0z = bz - az
    cdef double e1x = cx - bx, e1y = cy - by, e1z = cz - bz
    cdef double e2x = ax - cx, e2y = ay - cy, e2z = az - cz
    cdef double l0 = e0x * e0x + e0y * e0y + e0z * e0z
    cdef double l1 = e1x * e1x + e1y * e1y + e1z * e1z
    cdef double l2 = e2x * e2x + e2y * e2y + e2z * e2z
    cdef double ux, uy, uz, vx, vy, vz
    if l0 >= l1 and l0 >= l2:
        ux = e1x; uy = e1y; uz = e1z; vx = e2x; vy = e2y; vz = e2z
    elif l1 >= l2:
        ux = e2x; uy = e2y; uz = e2z; vx = e0x; vy = e0y; vz = e0z
    else:
        ux = e0x; uy = e0y; uz = e0z; vx = e1x; vy = e1y; vz = e1z
    cdef double nx = uy * vz - uz * vy, ny = uz * vx - ux * vz, nz = ux * vy - uy * vx
    cdef double nn = nx * nx + ny * ny + nz * nz
    if not nn > 0.0:
        return best
    cdef double s0 = _edge_side(ax, ay, az, bx, by, bz, px, py, pz, nx, ny, nz)
    cdef double s1 = _edge_side(bx, by, bz, cx, cy, cz, px, py, pz, nx, ny, nz)
    cdef double s2 = _edge_side(cx, cy, cz, ax, ay, az, px, py, pz, nx, ny, nz)
    cdef double h
    if s0 >= 0.0 and s1 >= 0.0 and s2 >= 0.0:
        h = (px - ax) * nx + (py - ay) * ny + (pz - az) * nz
        best = _min(best, h * h / nn)
    return best


cdef inline double _tri_box_dist2(double px, double py, double pz, const double* T) noexcept nogil:
    # the squared distance to the triangle's bounding box (the reference's order of operations)
    cdef double d = 0.0, g, lo, hi
    lo = _min(_min(T[0], T[3]), T[6])
    hi = _max(_max(T[0], T[3]), T[6])
    if px < lo:
        g = lo - px
        d += g * g
    elif px > hi:
        g = px - hi
        d += g * g
    lo = _min(_min(T[1], T[4]), T[7])
    hi = _max(_max(T[1], T[4]), T[7])
    if py < lo:
        g = lo - py
        d += g * g
    elif py > hi:
        g = py - hi
        d += g * g
    lo = _min(_min(T[2], T[5]), T[8])
    hi = _max(_max(T[2], T[5]), T[8])
    if pz < lo:
        g = lo - pz
        d += g * g
    elif pz > hi:
        g = pz - hi
        d += g * g
    return d


def nearest_kernel(const double[:, ::1] Q, const double[:, ::1] T, const double[:, ::1] nlo,
                   const double[:, ::1] nhi, const long long[::1] left,
                   const long long[::1] right, const long long[::1] start,
                   const long long[::1] count, double[::1] out):
    """Distance from each query to the nearest triangle (BVH, nearest child first)."""
    stack_arr = np.zeros(256, dtype=np.int64)
    cdef long long[::1] stack = stack_arr
    dist_arr = np.zeros(256, dtype=np.float64)
    cdef double[::1] dist = dist_arr
    cdef Py_ssize_t i, sp, n, t, a, b
    cdef double px, py, pz, best, d, da, db
    with nogil:
        for i in range(Q.shape[0]):
            px = Q[i, 0]
            py = Q[i, 1]
            pz = Q[i, 2]
            best = INFINITY
            sp = 1
            stack[0] = 0
            dist[0] = _box_dist2(px, py, pz, &nlo[0, 0], &nhi[0, 0])
            while sp > 0:
                sp -= 1
                n = stack[sp]
                if dist[sp] >= best:
                    continue
                if left[n] < 0:
                    for t in range(start[n], start[n] + count[n]):
                        if _tri_box_dist2(px, py, pz, &T[t, 0]) >= best:
                            continue
                        d = _tri_dist2(px, py, pz, &T[t, 0])
                        if d < best:
                            best = d
                else:
                    a = left[n]
                    b = right[n]
                    da = _box_dist2(px, py, pz, &nlo[a, 0], &nhi[a, 0])
                    db = _box_dist2(px, py, pz, &nlo[b, 0], &nhi[b, 0])
                    if da < db:
                        a, b = b, a
                        da, db = db, da
                    if da < best:
                        stack[sp] = a
                        dist[sp] = da
                        sp += 1
                    if db < best:
                        stack[sp] = b
                        dist[sp] = db
                        sp += 1
            out[i] = sqrt(best)


cdef inline bint _seg_box(double p0x, double p0y, double p0z, double dx, double dy, double dz,
                          const double* nlo, const double* nhi) noexcept nogil:
    # nlo, nhi: the node's box rows
    cdef double t0 = 0.0, t1 = 1.0, p, d, ta, tb, tmp
    cdef int k
    if not (fabs(dx) < INFINITY and fabs(dy) < INFINITY and fabs(dz) < INFINITY):
        return True
    for k in range(3):
        if k == 0:
            p = p0x; d = dx
        elif k == 1:
            p = p0y; d = dy
        else:
            p = p0z; d = dz
        if d == 0.0:
            if p < nlo[k] or p > nhi[k]:
                return False
        else:
            ta = (nlo[k] - p) / d
            tb = (nhi[k] - p) / d
            if ta > tb:
                tmp = ta
                ta = tb
                tb = tmp
            ta = _min(ta * (1.0 - _SLAB), ta * (1.0 + _SLAB)) - 1e-300
            tb = _max(tb * (1.0 - _SLAB), tb * (1.0 + _SLAB)) + 1e-300
            if ta > t0:
                t0 = ta
            if tb < t1:
                t1 = tb
            if t0 > t1:
                return False
    return True


def segment_kernel(const double[:, ::1] P0, const double[:, ::1] P1, const double[:, ::1] T,
                   const unsigned char[::1] degen, const double[:, ::1] nlo,
                   const double[:, ::1] nhi, const long long[::1] left,
                   const long long[::1] right, const long long[::1] start,
                   const long long[::1] count, bint first_only):
    """Filtered segment-triangle tests over the BVH (see the reference for the contract):
    ``status`` per segment (1 certain hit, 2 undecided pairs, 0 none) and the pairs
    ``(segment, triangle, t_lo, t_hi)`` of certain hits and of undecided pairs
    (``t_lo = -1``)."""
    cdef Py_ssize_t k = P0.shape[0]
    status_arr = np.zeros(k, dtype=np.int8)
    cdef signed char[::1] status = status_arr
    stack_arr = np.zeros(256, dtype=np.int64)
    cdef long long[::1] stack = stack_arr
    ps_l, pt_l, plo_l, phi_l = [], [], [], []
    cdef Py_ssize_t i, sp, n, t
    cdef double px, py, pz, qx, qy, qz, dx, dy, dz
    cdef double ax, ay, az, bx, by, bz, cx, cy, cz
    cdef double d0, e0, d1, e1, o1, f1, o2, f2, o3, f3, a0, a1, tlo, thi
    cdef int st
    cdef bint certain
    for i in range(k):
        px = P0[i, 0]; py = P0[i, 1]; pz = P0[i, 2]
        qx = P1[i, 0]; qy = P1[i, 1]; qz = P1[i, 2]
        dx = qx - px; dy = qy - py; dz = qz - pz
        st = 0
        sp = 1
        stack[0] = 0
        while sp > 0:
            sp -= 1
            n = stack[sp]
            if not _seg_box(px, py, pz, dx, dy, dz, &nlo[n, 0], &nhi[n, 0]):
                continue
            if left[n] >= 0:
                stack[sp] = left[n]
                stack[sp + 1] = right[n]
                sp += 2
                continue
            for t in range(start[n], start[n] + count[n]):
                tlo = -1.0
                thi = 1.0
                certain = False
                if not degen[t]:
                    ax = T[t, 0]; ay = T[t, 1]; az = T[t, 2]
                    bx = T[t, 3]; by = T[t, 4]; bz = T[t, 5]
                    cx = T[t, 6]; cy = T[t, 7]; cz = T[t, 8]
                    _o3(ax, ay, az, bx, by, bz, cx, cy, cz, px, py, pz, &d0, &e0)
                    _o3(ax, ay, az, bx, by, bz, cx, cy, cz, qx, qy, qz, &d1, &e1)
                    if (d0 > e0 and d1 > e1) or (d0 < -e0 and d1 < -e1):
                        continue
                    if fabs(d0) > e0 and fabs(d1) > e1:
                        _o3(px, py, pz, qx, qy, qz, ax, ay, az, bx, by, bz, &o1, &f1)
                        _o3(px, py, pz, qx, qy, qz, bx, by, bz, cx, cy, cz, &o2, &f2)
                        _o3(px, py, pz, qx, qy, qz, cx, cy, cz, ax, ay, az, &o3, &f3)
                        if (o1 > f1 or o2 > f2 or o3 > f3) and (o1 < -f1 or o2 < -f2 or o3 < -f3):
                            continue
                        if (o1 > f1 and o2 > f2 and o3 > f3) or (
                                o1 < -f1 and o2 < -f2 and o3 < -f3):
                            certain = True
                            a0 = fabs(d0)
                            a1 = fabs(d1)
                            tlo = (a0 - e0) / (a0 + a1 + e0 + e1) * (1.0 - 8 * _EPS)
                            thi = _min(1.0, (a0 + e0) / (a0 + a1 - e0 - e1) * (1.0 + 8 * _EPS))
                ps_l.append(i)
                pt_l.append(t)
                plo_l.append(tlo)
                phi_l.append(thi)
                if certain:
                    st = 1
                    if first_only:
                        break
                elif st == 0:
                    st = 2
            if st == 1 and first_only:
                break
        status[i] = st
    return (status_arr, np.array(ps_l, dtype=np.int64), np.array(pt_l, dtype=np.int64),
            np.array(plo_l, dtype=np.float64), np.array(phi_l, dtype=np.float64))
