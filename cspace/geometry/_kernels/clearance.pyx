# cython: language_level=3, boundscheck=False, wraparound=False, cdivision=True, initializedcheck=False
"""Compiled kernel of :class:`cspace.geometry.clearance.MeshClearance`: the distance between a
rigidly moved robot mesh and fixed obstacle triangles, capped (a threshold query that stops
early), and the certified motion check built on it (adaptive bisection).

The obstacles are a :class:`cspace.geometry.boxes.BoxTree` of their triangles' boxes (world
frame); the robot is a box tree of its triangles built in its own frame (relative to the
reference point). Every node of both trees also has an oriented box (``obb``: centre, three
orthonormal axes along the principal directions of its triangles' corners, half-extents that
hold every corner), so a query moves only what it visits: a robot node's box is turned to the
pose when first reached, a robot vertex when a leaf pair first needs it. A node pair's lower
bound is the largest gap between the two boxes' projections on the six axes of the two boxes
(the separating-axis test; any unit axis's gap is a lower bound of the distance); pairs are
visited depth first, the nearer child first, and pruned when their bound reaches the least
distance found so far (at first the cap). Tube-like and turned parts, whose axis-aligned boxes
overlap widely, are pruned far earlier than by axis-aligned boxes.

Per triangle pair (:func:`_tri_tri`, reference ``clearance._pair_distances_reference``): the
least of the nine edge-edge distances and the six corner-to-interior distances, 0 when an edge
crosses the other triangle. A sliver (inradius at most ``2**-16`` of its longest edge) is taken
as its three edges and its inradius subtracted (every point of a triangle is within its inradius
of its boundary), so an ill-conditioned normal never decides anything. The float error of what
is returned is bounded in :mod:`cspace.geometry.clearance` (``MeshClearance.error_bound``).
"""

import numpy as np

from libc.math cimport sqrt, fabs, atan2, sin, INFINITY, fmin as min, fmax as max
from libc.stdint cimport int64_t

cdef int _STACK = 4096


cdef inline double _dot(const double* a, const double* b) noexcept nogil:
    return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]


cdef inline void _sub(const double* a, const double* b, double* out) noexcept nogil:
    out[0] = a[0] - b[0]
    out[1] = a[1] - b[1]
    out[2] = a[2] - b[2]


cdef inline void _cross(const double* a, const double* b, double* out) noexcept nogil:
    out[0] = a[1] * b[2] - a[2] * b[1]
    out[1] = a[2] * b[0] - a[0] * b[2]
    out[2] = a[0] * b[1] - a[1] * b[0]


cdef inline double _clip01(double x) noexcept nogil:
    if x < 0.0:
        return 0.0
    if x > 1.0:
        return 1.0
    return x


cdef double _seg_seg_d2(const double* p1, const double* q1, const double* p2,
                        const double* q2) noexcept nogil:
    """Squared distance between segments (Ericson, Real-Time Collision Detection 5.1.9), as
    :func:`cspace.geometry.distance._segment_segment_d2`."""
    cdef double d1[3]
    cdef double d2[3]
    cdef double r[3]
    cdef double a, e, f, c, b, denom, s, t, x, y, z
    _sub(q1, p1, d1)
    _sub(q2, p2, d2)
    _sub(p1, p2, r)
    a = _dot(d1, d1)
    e = _dot(d2, d2)
    f = _dot(d2, r)
    c = _dot(d1, r)
    b = _dot(d1, d2)
    denom = a * e - b * b
    s = _clip01((b * f - c * e) / denom) if denom > 0 else 0.0
    t = (b * s + f) / e if e > 0 else 0.0
    if t < 0:
        s = _clip01(-c / a) if a > 0 else 0.0
    elif t > 1:
        s = _clip01((b - c) / a) if a > 0 else 0.0
    t = _clip01(t)
    x = (p1[0] + s * d1[0]) - (p2[0] + t * d2[0])
    y = (p1[1] + s * d1[1]) - (p2[1] + t * d2[1])
    z = (p1[2] + s * d1[2]) - (p2[2] + t * d2[2])
    return x * x + y * y + z * z


cdef inline bint _inside(const double* T, const double* n, const double* x) noexcept nogil:
    """Whether ``x`` (in the plane of ``T``, or its projection) is on the inner side of all three
    edges of ``T`` about the normal ``n`` (boundary included)."""
    cdef double e[3]
    cdef double w[3]
    cdef double c[3]
    cdef int i
    for i in range(3):
        _sub(&T[3 * ((i + 1) % 3)], &T[3 * i], e)
        _sub(x, &T[3 * i], w)
        _cross(e, w, c)
        if _dot(c, n) < 0:
            return False
    return True


cdef inline void _normal(const double* T, double* n) noexcept nogil:
    """The normal of ``T`` from its two shorter edges (slivers: see the module docstring)."""
    cdef double e0[3]
    cdef double e1[3]
    cdef double e2[3]
    cdef double l0, l1, l2
    _sub(&T[3], &T[0], e0)
    _sub(&T[6], &T[3], e1)
    _sub(&T[0], &T[6], e2)
    l0, l1, l2 = _dot(e0, e0), _dot(e1, e1), _dot(e2, e2)
    if l0 >= l1 and l0 >= l2:
        _cross(e1, e2, n)
    elif l1 >= l2:
        _cross(e2, e0, n)
    else:
        _cross(e0, e1, n)


cdef double _one_way(const double* A, const double* B, double best2) noexcept nogil:
    """``A``'s corners against ``B``'s interior and ``A``'s edges crossing ``B`` (``B`` not a
    sliver): the least squared distance found, below ``best2``, or ``-1`` for a crossing."""
    cdef double n[3]
    cdef double w[3]
    cdef double x[3]
    cdef double nn, h, sp, sq, f
    cdef int i, k
    _normal(B, n)
    nn = _dot(n, n)
    if not (nn > 0):
        return best2
    for i in range(3):
        _sub(&A[3 * i], &B[0], w)
        h = _dot(w, n) / nn
        for k in range(3):
            x[k] = A[3 * i + k] - h * n[k]
        if _inside(B, n, x) and h * h * nn < best2:
            best2 = h * h * nn
    for i in range(3):
        _sub(&A[3 * i], &B[0], w)
        sp = _dot(w, n)
        _sub(&A[3 * ((i + 1) % 3)], &B[0], w)
        sq = _dot(w, n)
        if (sp > 0 and sq > 0) or (sp < 0 and sq < 0) or (sp == 0 and sq == 0):
            continue  # no crossing (in-plane contact is found by the edge and corner distances)
        f = sp / (sp - sq)
        for k in range(3):
            x[k] = A[3 * i + k] + f * (A[3 * ((i + 1) % 3) + k] - A[3 * i + k])
        if _inside(B, n, x):
            return -1.0
    return best2


cdef double _tri_tri(const double* A, const double* B, double ra, double rb) noexcept nogil:
    """Distance between triangles ``A`` and ``B`` (9 doubles each); ``ra``, ``rb`` their
    inradii when slivers (taken as their edges), else -1."""
    cdef double best2 = INFINITY, d
    cdef int i, j
    for i in range(3):
        for j in range(3):
            d = _seg_seg_d2(&A[3 * i], &A[3 * ((i + 1) % 3)], &B[3 * j], &B[3 * ((j + 1) % 3)])
            if d < best2:
                best2 = d
    if rb < 0:
        best2 = _one_way(A, B, best2)
        if best2 < 0:
            return 0.0
    if ra < 0:
        best2 = _one_way(B, A, best2)
        if best2 < 0:
            return 0.0
    d = sqrt(best2)
    if ra > 0:
        d -= ra
    if rb > 0:
        d -= rb
    return d if d > 0 else 0.0


def pair_distances(const double[:, ::1] A, const double[:, ::1] B, const double[::1] ra,
                   const double[::1] rb):
    """Row-wise :func:`_tri_tri` of ``(k, 9)`` triangles (tests against the reference)."""
    cdef Py_ssize_t k, n = A.shape[0]
    out = np.empty(n)
    cdef double[::1] o = out
    for k in range(n):
        o[k] = _tri_tri(&A[k, 0], &B[k, 0], ra[k], rb[k])
    return out


cdef class ClearanceKernel:
    """One robot against one set of obstacles; see the module docstring.

    Parameters (arrays as :class:`cspace.geometry.clearance.MeshClearance` prepares them):
    ``OT (m, 9)`` obstacle triangles, ``o_r (m,)`` their sliver inradii (-1: not a sliver),
    ``o_n (m, 3)`` and ``r_n (k, 3)`` the obstacle and robot triangles' unit normals from their
    shorter edges (robot frame; only non-slivers' are used),
    the obstacle tree (``order, first, count``); ``RV (v, 3)`` robot vertices minus
    the reference point, ``RF (k, 3)``, ``r_r (k,)`` and the robot tree's ``order, first,
    count``; ``r_obb`` and ``o_obb`` (``(nodes, 15)``: centre, axes, half-extents) the two
    trees' oriented boxes (:func:`cspace.geometry.clearance.node_boxes`).
    """

    cdef const double[:, ::1] OT
    cdef const double[::1] o_r
    cdef const int64_t[::1] o_order
    cdef const int64_t[::1] o_first
    cdef const int64_t[::1] o_count
    cdef const double[:, ::1] ob_lo   # each obstacle triangle's box
    cdef const double[:, ::1] ob_hi
    cdef const double[:, ::1] on      # unit normals of the obstacle triangles (not slivers)
    cdef const double[::1] od         # and their planes' offsets
    cdef const double[:, ::1] rn      # unit normals of the robot's triangles, its frame
    cdef const double[:, ::1] RV
    cdef const int64_t[:, ::1] RF
    cdef const double[::1] r_r
    cdef const int64_t[::1] r_order
    cdef const int64_t[::1] r_first
    cdef const int64_t[::1] r_count
    cdef const double[:, ::1] r_obb   # robot nodes' oriented boxes, its frame (module docstring)
    cdef const double[:, ::1] o_obb   # obstacle nodes' oriented boxes, world frame
    cdef double[:, ::1] wv      # robot vertices moved to this query's pose
    cdef double[:, ::1] wobb    # robot nodes' oriented boxes turned to it
    cdef int64_t[::1] v_stamp   # the query that moved each vertex / turned each node's box
    cdef int64_t[::1] n_stamp
    cdef double R[9]
    cdef double q[3]
    cdef public int64_t queries
    cdef public int64_t pairs
    cdef object _keep
    cdef object _boxes

    def __init__(self, OT, o_r, o_n, r_n, o_order, o_first, o_count, RV, RF, r_r, r_order,
                 r_first, r_count, r_obb, o_obb):
        self._keep = (OT, o_r, o_n, r_n, o_order, o_first, o_count, RV, RF, r_r, r_order,
                      r_first, r_count, r_obb, o_obb)
        self.r_obb, self.o_obb = r_obb, o_obb
        self.OT, self.o_r, self.o_order = OT, o_r, o_order
        self.o_first, self.o_count = o_first, o_count
        self._boxes = (np.ascontiguousarray(np.asarray(OT).reshape(-1, 3, 3).min(axis=1)),
                       np.ascontiguousarray(np.asarray(OT).reshape(-1, 3, 3).max(axis=1)))
        self.ob_lo, self.ob_hi = self._boxes
        od = np.einsum("kj,kj->k", np.asarray(o_n), np.asarray(OT)[:, :3])
        self.on, self.od, self.rn = o_n, od, r_n
        self._boxes = self._boxes + (od,)
        self.RV, self.RF, self.r_r, self.r_order = RV, RF, r_r, r_order
        self.r_first, self.r_count = r_first, r_count
        self.wv = np.zeros((RV.shape[0], 3))
        self.wobb = np.zeros((r_first.shape[0], 12))
        self.v_stamp = np.full(RV.shape[0], -1, dtype=np.int64)
        self.n_stamp = np.full(r_first.shape[0], -1, dtype=np.int64)
        self.queries = 0
        self.pairs = 0

    cdef inline void _move(self, const double* p, double* out) noexcept nogil:
        cdef double* R = self.R
        out[0] = R[0] * p[0] + R[1] * p[1] + R[2] * p[2] + self.q[0]
        out[1] = R[3] * p[0] + R[4] * p[1] + R[5] * p[2] + self.q[1]
        out[2] = R[6] * p[0] + R[7] * p[1] + R[8] * p[2] + self.q[2]

    cdef inline double* _vertex(self, Py_ssize_t v) noexcept nogil:
        """Robot vertex ``v`` moved to this query's pose (moved once per query)."""
        if self.v_stamp[v] != self.queries:
            self._move(&self.RV[v, 0], &self.wv[v, 0])
            self.v_stamp[v] = self.queries
        return &self.wv[v, 0]

    cdef inline double* _node_box(self, Py_ssize_t i) noexcept nogil:
        """Robot node ``i``'s oriented box turned to this query's pose: centre, then its three
        axes (turned once per query)."""
        cdef double* w = &self.wobb[i, 0]
        if self.n_stamp[i] != self.queries:
            self._move(&self.r_obb[i, 0], w)
            self._turn(&self.r_obb[i, 3], &w[3])
            self._turn(&self.r_obb[i, 6], &w[6])
            self._turn(&self.r_obb[i, 9], &w[9])
            self.n_stamp[i] = self.queries
        return w

    cdef inline void _turn(self, const double* p, double* out) noexcept nogil:
        cdef double* R = self.R
        out[0] = R[0] * p[0] + R[1] * p[1] + R[2] * p[2]
        out[1] = R[3] * p[0] + R[4] * p[1] + R[5] * p[2]
        out[2] = R[6] * p[0] + R[7] * p[1] + R[8] * p[2]

    cdef inline double _bound(self, Py_ssize_t i, Py_ssize_t j) noexcept nogil:
        """Lower bound of the distance between robot node ``i`` (at this pose) and obstacle
        node ``j`` from their oriented boxes. On each axis ``u`` of box ``A``, every point of
        ``B`` lies outside ``A``'s slab by at least the gap ``g_u`` between their projections
        (0 when they overlap), so every point of ``B`` is at least ``sqrt(sum g_u^2)`` from
        ``A`` (the distance to a box is the root of the squared slab distances on its axes);
        the larger of that root over ``A``'s axes and over ``B``'s (for axis-aligned boxes: the
        gap between them). 0 when no axis separates."""
        cdef double* A = self._node_box(i)
        cdef const double* B = &self.o_obb[j, 0]
        cdef const double* ha = &self.r_obb[i, 12]
        cdef const double* hb = &B[12]
        cdef double M[9]
        cdef double d[3]
        cdef double ga = 0.0, gb = 0.0, g
        cdef int k, m
        for k in range(3):
            d[k] = A[k] - B[k]
        for k in range(3):
            for m in range(3):
                M[3 * k + m] = fabs(_dot(&A[3 + 3 * k], &B[3 + 3 * m]))
        for k in range(3):  # the robot box's axes
            g = (fabs(_dot(&A[3 + 3 * k], d)) - ha[k]
                 - (hb[0] * M[3 * k] + hb[1] * M[3 * k + 1] + hb[2] * M[3 * k + 2]))
            if g > 0:
                ga += g * g
        for m in range(3):  # the obstacle box's axes
            g = (fabs(_dot(&B[3 + 3 * m], d)) - hb[m]
                 - (ha[0] * M[m] + ha[1] * M[3 + m] + ha[2] * M[6 + m]))
            if g > 0:
                gb += g * g
        return sqrt(ga if ga > gb else gb)

    cdef double _leaves(self, Py_ssize_t i, Py_ssize_t j, double best, double grow) noexcept nogil:
        cdef double A[9]
        cdef double lo[3]
        cdef double hi[3]
        cdef double n[3]
        cdef Py_ssize_t a, b, t, o, k
        cdef double* w
        cdef double d, g, g2, na, s0, s1, s2, thr
        cdef bint flat_a
        for a in range(self.r_first[i], self.r_first[i] + self.r_count[i]):
            t = self.r_order[a]
            for k in range(3):
                w = self._vertex(self.RF[t, k])
                A[3 * k], A[3 * k + 1], A[3 * k + 2] = w[0], w[1], w[2]
            for k in range(3):
                lo[k] = min(A[k], min(A[3 + k], A[6 + k]))
                hi[k] = max(A[k], max(A[3 + k], A[6 + k]))
            flat_a = self.r_r[t] < 0  # not a sliver: its plane may separate
            if flat_a:
                self._turn(&self.rn[t, 0], n)
                na = _dot(n, A)
            for b in range(self.o_first[j], self.o_first[j] + self.o_count[j]):
                o = self.o_order[b]
                # The gap between the two triangles' boxes first: most pairs end there.
                g2 = 0.0
                for k in range(3):
                    g = self.ob_lo[o, k] - hi[k]
                    if g > 0:
                        g2 += g * g
                    else:
                        g = lo[k] - self.ob_hi[o, k]
                        if g > 0:
                            g2 += g * g
                thr = best / grow  # a pair at least this far apart is pruned
                if g2 >= thr * thr:
                    continue
                # Then each triangle's plane: all three corners of the other beyond ``thr``.
                if self.o_r[o] < 0:
                    s0 = _dot(&self.on[o, 0], A) - self.od[o]
                    s1 = _dot(&self.on[o, 0], &A[3]) - self.od[o]
                    s2 = _dot(&self.on[o, 0], &A[6]) - self.od[o]
                    if min(s0, min(s1, s2)) >= thr or max(s0, max(s1, s2)) <= -thr:
                        continue
                if flat_a:
                    s0 = _dot(n, &self.OT[o, 0]) - na
                    s1 = _dot(n, &self.OT[o, 3]) - na
                    s2 = _dot(n, &self.OT[o, 6]) - na
                    if min(s0, min(s1, s2)) >= thr or max(s0, max(s1, s2)) <= -thr:
                        continue
                self.pairs += 1
                d = _tri_tri(A, &self.OT[o, 0], self.r_r[t], self.o_r[o])
                if d < best:
                    best = d
                    if best <= 0:
                        return 0.0
        return best

    cdef double _query(self, const double* R, const double* q, double cap,
                       double grow=1.0) noexcept nogil:
        """Least distance at the pose ``(q, R)`` when below ``cap``, else at least ``cap``.
        With ``grow > 1``, a lower bound within that factor: pairs are pruned once their bound
        times ``grow`` reaches the least distance found, ``best``, so every pair pruned or
        measured is at least ``best / grow`` apart, which is returned (at least
        ``cap / grow`` when nothing is found below ``cap``). Far fewer pairs are measured."""
        cdef Py_ssize_t si[4096]
        cdef Py_ssize_t sj[4096]
        cdef double sb[4096]
        cdef int top = 0, k
        cdef Py_ssize_t i, j, i1, i2, j1, j2
        cdef double best = cap, b1, b2
        cdef bint split_robot
        for k in range(9):
            self.R[k] = R[k]
        for k in range(3):
            self.q[k] = q[k]
        self.queries += 1  # also this query's stamp: nothing moved for it yet
        b1 = self._bound(0, 0)
        if b1 * grow >= best:
            return best / grow
        si[0], sj[0], sb[0] = 0, 0, b1
        top = 1
        while top > 0:
            top -= 1
            i, j = si[top], sj[top]
            if sb[top] * grow >= best:
                continue
            if self.r_count[i] > 0 and self.o_count[j] > 0:
                best = self._leaves(i, j, best, grow)
                if best <= 0:
                    return 0.0
                continue
            # Split the robot node unless it is a leaf or clearly the smaller one.
            split_robot = self.o_count[j] > 0 or (
                self.r_count[i] == 0 and _half_diagonal(&self.r_obb[i, 12])
                >= _half_diagonal(&self.o_obb[j, 12]))
            if split_robot:
                i1, i2 = self.r_first[i], self.r_first[i] + 1
                b1, b2 = self._bound(i1, j), self._bound(i2, j)
                j1 = j2 = j
            else:
                j1, j2 = self.o_first[j], self.o_first[j] + 1
                b1, b2 = self._bound(i, j1), self._bound(i, j2)
                i1 = i2 = i
            if top + 2 > 4096:
                return -1.0  # never: the trees are far shallower; -1 reads as a collision
            # The nearer pair on top: visited first, it lowers ``best`` for the farther one.
            if b1 < b2:
                i1, j1, b1, i2, j2, b2 = i2, j2, b2, i1, j1, b1
            if b1 * grow < best:
                si[top], sj[top], sb[top] = i1, j1, b1
                top += 1
            if b2 * grow < best:
                si[top], sj[top], sb[top] = i2, j2, b2
                top += 1
        return best / grow

    def distance(self, const double[:, ::1] R, const double[::1] q, double cap=INFINITY,
                 double grow=1.0) -> float:
        """The robot turned by ``R`` about its reference point, which is at ``q``: its least
        distance to the obstacles if below ``cap``, else a number at least ``cap``; with
        ``grow > 1`` a lower bound within that factor (:meth:`_query`)."""
        return self._query(&R[0, 0], &q[0], cap, grow)

    def distances(self, const double[:, :, ::1] R, const double[:, ::1] q, double cap=INFINITY):
        """:meth:`distance` of each pose ``(R[k], q[k])``."""
        cdef Py_ssize_t k, n = q.shape[0]
        out = np.empty(n)
        cdef double[::1] o = out
        for k in range(n):
            o[k] = self._query(&R[k, 0, 0], &q[k, 0], cap)
        return out

    def motion(self, const double[::1] q0, const double[::1] Q0, const double[::1] q1,
               const double[::1] Q1, double rho, double delta, int max_depth=40,
               double grow=4.0):
        """Certify the motion from pose ``(q0, Q0)`` to ``(q1, Q1)`` (positions; unit
        quaternions ``x, y, z, w``): the reference point on the segment, the rotation on the
        shortest slerp arc, both at constant speed. See
        :meth:`cspace.geometry.clearance.MeshClearance.motion_free`. Its clearances are lower
        bounds within the factor ``grow`` (:meth:`_query`): cheaper, at the cost of a little
        more halving.

        Returns ``(free, depth, queries)``."""
        cdef double sa[128]
        cdef double sb_[128]
        cdef double la[128]
        cdef double lb[128]
        cdef int dep[128]
        cdef int top, depth = 0, d
        cdef double D, a, b, m, La, Lb, Lm, need, theta, dq
        cdef int64_t before = self.queries
        cdef double p0[4]
        cdef double p1[4]
        cdef int k
        for k in range(4):
            p0[k], p1[k] = Q0[k], Q1[k]
        dq = p0[0] * p1[0] + p0[1] * p1[1] + p0[2] * p1[2] + p0[3] * p1[3]
        if dq < 0:  # the shortest arc, as OMPL's SO(3) interpolation
            for k in range(4):
                p1[k] = -p1[k]
        theta = _angle(p0, p1)
        D = (sqrt((q1[0] - q0[0]) ** 2 + (q1[1] - q0[1]) ** 2 + (q1[2] - q0[2]) ** 2)
             + rho * theta)
        D = D * (1.0 + 1e-12) + 1e-300  # rounded up
        # A motion that fails mostly meets an obstacle well inside it: look there first, at the
        # midpoints of the first three halvings (breadth first), with collision-only queries
        # (capped at the error bound: nearly every pair is pruned). Nothing is certified by
        # them; they only end a blocked motion early.
        for k in range(1, 8):
            d = 0  # k's level: 1 | 2, 3 | 4 .. 7
            while k >> (d + 1):
                d += 1
            # k = 1..7 -> s = 1/2, 1/4, 3/4, 1/8, 3/8, 5/8, 7/8
            m = (2.0 * (k - (1 << d)) + 1.0) / (2 << d)
            if D * m * (1.0 - m) <= delta:
                continue
            if not (self._between(q0, q1, p0, p1, m, theta, 2.0 * delta, 1.0) > delta):
                return False, 0, self.queries - before
        # Each end needs half the sweep for the whole motion to pass at once: the capped
        # queries stop there (a larger cap costs more and helps no more). The far end first:
        # a motion that fails usually fails there.
        Lb = self._at(q1, p0, p1, 1.0, theta, 0.5 * D * (1.0 + 1e-9) + delta, grow) - delta
        if not (Lb > 0):
            return False, 0, self.queries - before
        La = self._at(q0, p0, p1, 0.0, theta, D - Lb + delta, grow) - delta
        if not (La > 0):
            return False, 0, self.queries - before
        sa[0], sb_[0], la[0], lb[0], dep[0] = 0.0, 1.0, La, Lb, 0
        top = 1
        while top > 0:
            top -= 1
            a, b, La, Lb, d = sa[top], sb_[top], la[top], lb[top], dep[top]
            if d > depth:
                depth = d
            if La + Lb > D * (b - a):
                continue
            if d >= max_depth or top + 2 > 128:
                return False, depth, self.queries - before  # undecided: reported not free
            m = 0.5 * (a + b)
            need = D * (m - a) - La
            if D * (b - m) - Lb > need:
                need = D * (b - m) - Lb
            # What both halves need of the middle: a capped query stops once that is certain.
            if need < 0:
                need = 0
            Lm = self._between(q0, q1, p0, p1, m, theta,
                               need * (1.0 + 1e-9) + 1e-12 * D * (b - a) + delta, grow) - delta
            if not (Lm > 0):
                return False, d + 1, self.queries - before
            sa[top], sb_[top], la[top], lb[top], dep[top] = m, b, Lm, Lb, d + 1
            sa[top + 1], sb_[top + 1], la[top + 1], lb[top + 1], dep[top + 1] = a, m, La, Lm, d + 1
            top += 2
        return True, depth, self.queries - before

    cdef double _at(self, const double[::1] q, const double* p0, const double* p1, double s,
                    double theta, double cap, double grow):
        cdef double Q[4]
        cdef double R[9]
        _slerp(p0, p1, s, theta, Q)
        _matrix(Q, R)
        return self._query(R, &q[0], cap * grow, grow)

    cdef double _between(self, const double[::1] q0, const double[::1] q1, const double* p0,
                         const double* p1, double s, double theta, double cap, double grow):
        cdef double q[3]
        cdef double Q[4]
        cdef double R[9]
        cdef int k
        for k in range(3):
            q[k] = q0[k] + s * (q1[k] - q0[k])
        _slerp(p0, p1, s, theta, Q)
        _matrix(Q, R)
        return self._query(R, q, cap * grow, grow)


cdef inline double _half_diagonal(const double* h) noexcept nogil:
    """Half the diagonal of a box with half-extents ``h``."""
    return sqrt(h[0] * h[0] + h[1] * h[1] + h[2] * h[2])


cdef inline double _angle(const double* p0, const double* p1) noexcept nogil:
    """Rotation angle between unit quaternions on the same hemisphere: ``2 atan2(|v|, w)`` of
    ``conj(p0) p1`` (accurate for small angles, unlike ``acos``)."""
    cdef double w = p0[3] * p1[3] + p0[0] * p1[0] + p0[1] * p1[1] + p0[2] * p1[2]
    cdef double x = p0[3] * p1[0] - p0[0] * p1[3] - p0[1] * p1[2] + p0[2] * p1[1]
    cdef double y = p0[3] * p1[1] + p0[0] * p1[2] - p0[1] * p1[3] - p0[2] * p1[0]
    cdef double z = p0[3] * p1[2] - p0[0] * p1[1] + p0[1] * p1[0] - p0[2] * p1[3]
    return 2.0 * atan2(sqrt(x * x + y * y + z * z), fabs(w))


cdef inline void _slerp(const double* p0, const double* p1, double s, double theta,
                        double* out) noexcept nogil:
    """``p0`` turned towards ``p1`` (same hemisphere) by the fraction ``s`` of the arc
    ``theta / 2`` between them (quaternion angle), normalised."""
    cdef double h = 0.5 * theta, w0, w1, n
    cdef int k
    if h < 1e-9:
        w0, w1 = 1.0 - s, s
    else:
        w0, w1 = sin((1.0 - s) * h) / sin(h), sin(s * h) / sin(h)
    for k in range(4):
        out[k] = w0 * p0[k] + w1 * p1[k]
    n = sqrt(out[0] * out[0] + out[1] * out[1] + out[2] * out[2] + out[3] * out[3])
    for k in range(4):
        out[k] /= n


cdef inline void _matrix(const double* Q, double* R) noexcept nogil:
    """Rotation matrix (row major) of the unit quaternion ``x, y, z, w``."""
    cdef double x = Q[0], y = Q[1], z = Q[2], w = Q[3]
    R[0] = 1 - 2 * (y * y + z * z)
    R[1] = 2 * (x * y - z * w)
    R[2] = 2 * (x * z + y * w)
    R[3] = 2 * (x * y + z * w)
    R[4] = 1 - 2 * (x * x + z * z)
    R[5] = 2 * (y * z - x * w)
    R[6] = 2 * (x * z - y * w)
    R[7] = 2 * (y * z + x * w)
    R[8] = 1 - 2 * (x * x + y * y)
