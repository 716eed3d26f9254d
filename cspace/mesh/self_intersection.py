"""Exact self-intersection test of a triangle mesh on the grid: :func:`self_intersections`.

Every pair of triangles that is not adjacent (or adjacent in a way that can still cross) is
decided exactly: box candidates, float-filtered separating axes, then Python integers for what
the filters leave (:func:`_undecided_pairs`, compiled beside its reference). Used to validate
closed meshes (what a body *is*) and by the rounding check of the Minkowski sum.
"""

from __future__ import annotations

import numpy as np

from ..geometry._kernels import load
from ..geometry.boxes import box_pairs
from ..geometry.exact import Grid
from ..geometry.tritri import _cross, _orient3
from ..workers import can_fork, forked_map


_compiled = load("trim")


# From this many pairs left by the float filters on, the rounding check's exact test runs in
# several processes (about 30 us a pair in Python against some 10-20 ms to fork and collect).
_PARALLEL_CHECK = 2_000


# Float filter for orientations of float64 points (Shewchuk's bound is below 8 eps).
_ORIENT_FILTER = 16 * float(np.finfo(np.float64).eps) / 2


# Float filter of a dot product of float64 rows: the three products and two sums are off by
# at most 3 unit roundoffs of the sum of absolute products, the bound's own addition by one
# more; 8 leaves room for the rounding of the bound itself.
_DOT_FILTER = 8 * float(np.finfo(np.float64).eps) / 2


def self_intersections(mesh) -> np.ndarray:
    """Pairs of triangles of a closed mesh that meet beyond the vertices and edge they share
    (crossings, overlaps, folds, touching): ``(k, 2)`` int64, empty for a valid solid.

    Exact on the mesh's grid coordinates: box pairs first, the rounding check's float filters,
    then integer predicates for what they leave.

    Parameters
    ----------
    mesh : ClosedMesh
    """
    T = np.asarray(mesh.faces, dtype=np.int64)
    if not len(T):
        return np.zeros((0, 2), np.int64)
    moved = np.ones(len(mesh.vertices), dtype=bool)  # test every pair, not only moved ones
    bad, _ = _improper_pairs(np.asarray(mesh.vertices, dtype=np.float64), T, mesh.grid, moved)
    return bad


def _improper_pairs(V: np.ndarray, T: np.ndarray, grid: Grid, moved: np.ndarray,
                    workers: int = 1) -> tuple[np.ndarray, int]:
    """Pairs of triangles ``T`` over float64 vertices ``V`` (with a vertex in ``moved``) that
    meet improperly, decided exactly; and the number of processes used."""
    pairs = box_pairs(*_triangle_boxes_compiled(V, T, grid.exponent))
    # The compiled float filter (some 40 ns a pair, 20x numpy's): few pairs are left.
    pairs = pairs[_undecided_pairs_compiled(V, T, pairs, moved)]
    if not len(pairs):
        return np.zeros((0, 2), np.int64), 1
    # Exact integers of only the vertices of the pairs left, on triangles renumbered to
    # them: their common scale is another power of two than all vertices', and _improper's
    # predicates (orientations, dominant axis, coordinate comparisons) are homogeneous, so
    # a positive scale changes none of its answers.
    ids = np.unique(T[pairs].reshape(-1))
    Vi, Tl = _common_integers(V[ids]), np.searchsorted(ids, T[pairs]).tolist()

    def check(ks: range) -> list:
        return [k for k in ks if _improper(Vi, Tl[k][0], Tl[k][1])]

    ranges = [range(len(pairs))]
    if workers > 1 and len(pairs) >= _PARALLEL_CHECK and can_fork():
        cuts = np.linspace(0, len(pairs), 2 * workers + 1).astype(int)
        ranges = [range(a, b) for a, b in zip(cuts[:-1], cuts[1:])]
    done = dict(forked_map(check, ranges, workers if len(ranges) > 1 else 1))
    bad = [k for r in range(len(ranges)) for k in done[r]]  # in pair order
    return pairs[np.array(bad, dtype=np.int64)].reshape(-1, 2), min(len(ranges), workers)


def _triangle_boxes(V: np.ndarray, T: np.ndarray, exponent: int) -> tuple[np.ndarray, np.ndarray]:
    """``(lo, hi)``, ``(t, 3)`` int64: the boxes of triangles ``T`` over float64 rows ``V``
    in grid units (step ``2**exponent``), rounded outwards: they contain the float boxes."""
    P = V[T]
    lo = np.floor(np.ldexp(P.min(axis=1), -exponent)).astype(np.int64)
    hi = np.ceil(np.ldexp(P.max(axis=1), -exponent)).astype(np.int64)
    return lo.reshape(-1, 3), hi.reshape(-1, 3)


def _triangle_boxes_compiled(V: np.ndarray, T: np.ndarray, exponent: int) -> tuple[np.ndarray, np.ndarray]:
    """:func:`_triangle_boxes` compiled (:mod:`cspace.geometry._kernels.trim`): identical output (the
    reference's when a coordinate is not finite or a box end not below 2**62)."""
    lo, hi, ok = _compiled.triangle_boxes(np.ascontiguousarray(V, np.float64),
                                          np.ascontiguousarray(T, np.int64).reshape(-1, 3),
                                          int(exponent))
    return (lo, hi) if ok else _triangle_boxes(V, T, exponent)


def _separated(V: np.ndarray, T: np.ndarray, i: np.ndarray, j: np.ndarray) -> np.ndarray:
    """Pairs where every vertex of triangle ``j`` not shared with ``i`` lies strictly on one
    side of the plane of ``i`` (float filter; undecided pairs are False): then the two
    triangles meet at most in their shared vertices and edge."""
    a, b, c = (V[T[i, k]] for k in range(3))
    u, v = b - a, c - a
    n = np.cross(u, v)
    side = np.zeros((len(i), 3), dtype=np.int8)
    for k in range(3):
        w = V[T[j, k]] - a
        det = np.einsum("ij,ij->i", n, w)
        perm = (np.abs(u[:, 0]) * (np.abs(v[:, 1] * w[:, 2]) + np.abs(v[:, 2] * w[:, 1]))
                + np.abs(u[:, 1]) * (np.abs(v[:, 2] * w[:, 0]) + np.abs(v[:, 0] * w[:, 2]))
                + np.abs(u[:, 2]) * (np.abs(v[:, 0] * w[:, 1]) + np.abs(v[:, 1] * w[:, 0])))
        sure = np.abs(det) > _ORIENT_FILTER * perm
        shared = np.any(T[i] == T[j, k][:, None], axis=1)
        side[:, k] = np.where(shared, 2, np.where(sure, np.sign(det), 0))
    free = side != 2
    pos = np.all((side == 1) | ~free, axis=1)
    neg = np.all((side == -1) | ~free, axis=1)
    return (pos | neg) & free.any(axis=1)


def _o2_filtered(u, a, b) -> np.ndarray:
    """Sign of orient2d(u, a, b) on float rows, 0 where the float filter cannot decide."""
    x1, y1 = a[:, 0] - u[:, 0], a[:, 1] - u[:, 1]
    x2, y2 = b[:, 0] - u[:, 0], b[:, 1] - u[:, 1]
    det = x1 * y2 - y1 * x2
    sure = np.abs(det) > _ORIENT_FILTER * (np.abs(x1 * y2) + np.abs(y1 * x2))
    return np.where(sure, np.sign(det), 0)


def _apart_in_projection_np(V: np.ndarray, T: np.ndarray, pairs: np.ndarray,
                            ax: np.ndarray) -> np.ndarray:
    """Pairs whose projections along coordinate axis ``ax`` (per pair) meet only in their
    shared vertices or edge, decided by a float filter (undecided: False). The 3D triangles
    then meet only there too (the projection of their intersection lies in the intersection
    of their projections)."""
    i, j = pairs[:, 0], pairs[:, 1]
    Ti, Tj = T[i], T[j]
    eq = Ti[:, :, None] == Tj[:, None, :]  # (k, 3, 3): vertex a of i equals vertex b of j
    n_shared = eq.sum(axis=(1, 2))
    out = np.zeros(len(pairs), dtype=bool)
    keep = np.stack([(ax + 1) % 3, (ax + 2) % 3], axis=1)
    rows = np.arange(len(pairs))

    def P(ids, r):
        return np.stack([V[ids, keep[r, 0]], V[ids, keep[r, 1]]], axis=1)

    # disjoint: an edge line of one triangle strictly separates the other (2D axes)
    z = n_shared == 0
    if z.any():
        r = rows[z]
        sep = np.zeros(len(r), dtype=bool)
        for A_, B_ in ((Ti[r], Tj[r]), (Tj[r], Ti[r])):
            for k in range(3):
                p, q, o3 = P(A_[:, k], r), P(A_[:, (k + 1) % 3], r), P(A_[:, (k + 2) % 3], r)
                o = _o2_filtered(p, q, o3)
                allout = o != 0
                for m in range(3):
                    allout &= _o2_filtered(p, q, P(B_[:, m], r)) * o < 0
                sep |= allout
        out[r] = sep
    si = eq.any(axis=2)  # vertices of i that are shared
    sj = eq.any(axis=1)
    # shared edge (u, v): the two apexes strictly on opposite sides of the edge's line
    e = n_shared == 2
    if e.any():
        r = rows[e]
        ai = Ti[r, np.argmin(si[r], axis=1)]
        aj = Tj[r, np.argmin(sj[r], axis=1)]
        uv = np.sort(np.where(si[r], Ti[r], -1), axis=1)[:, 1:]
        u, v = P(uv[:, 0], r), P(uv[:, 1], r)
        s1 = _o2_filtered(u, v, P(ai, r))
        s2 = _o2_filtered(u, v, P(aj, r))
        out[r] = s1 * s2 < 0
    # shared vertex u: each edge ray at u strictly outside the other triangle's corner
    w = n_shared == 1
    if w.any():
        r = rows[w]
        ku = np.argmax(si[r], axis=1)
        u_id = Ti[r, ku]
        a_id, b_id = Ti[r, (ku + 1) % 3], Ti[r, (ku + 2) % 3]
        kj = np.argmax(sj[r], axis=1)
        c_id, d_id = Tj[r, (kj + 1) % 3], Tj[r, (kj + 2) % 3]
        u, a, b, c, d = (P(x, r) for x in (u_id, a_id, b_id, c_id, d_id))

        def outside(x, p, q):  # ray u->x strictly outside the convex corner (p, q) at u
            o = _o2_filtered(u, p, q)
            return (o != 0) & ((_o2_filtered(u, p, x) * o < 0) | (_o2_filtered(u, x, q) * o < 0))

        out[r] = outside(c, a, b) & outside(d, a, b) & outside(a, c, d) & outside(b, c, d)
    return out


def _axes_apart_np(V: np.ndarray, T: np.ndarray, pairs: np.ndarray) -> np.ndarray:
    """Pairs (no shared vertex) strictly separated along one of the cross products of an
    edge of each triangle, decided by a float filter (undecided: False). Any axis is a valid
    certificate, so only the dot products need a bound, not the axes."""
    A, B = V[T[pairs[:, 0]]], V[T[pairs[:, 1]]]  # (k, 3 corners, 3)
    eA, eB = A[:, [1, 2, 0]] - A, B[:, [1, 2, 0]] - B
    out = np.zeros(len(pairs), dtype=bool)
    for i in range(3):
        for j in range(3):
            a = np.cross(eA[:, i], eB[:, j])[:, None, :]
            pa, pb = (A * a).sum(axis=2), (B * a).sum(axis=2)
            ea = _DOT_FILTER * np.abs(A * a).sum(axis=2)
            eb = _DOT_FILTER * np.abs(B * a).sum(axis=2)
            out |= (((pa + ea).max(axis=1) < (pb - eb).min(axis=1))
                    | ((pb + eb).max(axis=1) < (pa - ea).min(axis=1)))
    return out


def _undecided_pairs_np(V: np.ndarray, T: np.ndarray, pairs: np.ndarray, moved: np.ndarray) -> np.ndarray:
    """:func:`_undecided_pairs` with numpy (the same filters, pair arrays at a time)."""
    rows = np.nonzero(moved[T[pairs]].any(axis=(1, 2)))[0]
    for x, y in ((0, 1), (1, 0)):  # a plane of either triangle may separate them
        rows = rows[~_separated(V, T, pairs[rows, x], pairs[rows, y])]
    Ti = T[pairs[rows, 0]]
    ax = np.argmax(np.abs(np.cross(V[Ti[:, 1]] - V[Ti[:, 0]], V[Ti[:, 2]] - V[Ti[:, 0]])), axis=1)
    for step in (0, 1, 2):  # the dominant projection of the first triangle, then the others
        left = ~_apart_in_projection_np(V, T, pairs[rows], (ax + step) % 3)
        rows, ax = rows[left], ax[left]
    if len(rows):
        lone = ~(T[pairs[rows, 0]][:, :, None] == T[pairs[rows, 1]][:, None, :]).any(axis=(1, 2))
        rows = rows[~(lone & _axes_apart_np(V, T, pairs[rows]))]
    out = np.zeros(len(pairs), dtype=bool)
    out[rows] = True
    return out


def _o2f(V, u, a, b, k0, k1) -> int:
    """Sign of orient2d(u, a, b) on coordinates ``k0, k1`` of float rows of ``V``, 0 where the
    float filter cannot decide."""
    x1, y1 = V[a, k0] - V[u, k0], V[a, k1] - V[u, k1]
    x2, y2 = V[b, k0] - V[u, k0], V[b, k1] - V[u, k1]
    det = x1 * y2 - y1 * x2
    if abs(det) > _ORIENT_FILTER * (abs(x1 * y2) + abs(y1 * x2)):
        return 1 if det > 0 else -1
    return 0


def _plane_separates(V, ti, tj) -> bool:
    """Every vertex of triangle ``tj`` not shared with ``ti`` lies strictly on one side of
    the plane of ``ti`` (float filter; undecided: False): then the two triangles meet at
    most in their shared vertices and edge."""
    a, b, c = ti[0], ti[1], ti[2]
    ux, uy, uz = V[b, 0] - V[a, 0], V[b, 1] - V[a, 1], V[b, 2] - V[a, 2]
    vx, vy, vz = V[c, 0] - V[a, 0], V[c, 1] - V[a, 1], V[c, 2] - V[a, 2]
    nx, ny, nz = uy * vz - uz * vy, uz * vx - ux * vz, ux * vy - uy * vx
    side = 0
    for k in range(3):
        x = tj[k]
        if x == a or x == b or x == c:
            continue
        wx, wy, wz = V[x, 0] - V[a, 0], V[x, 1] - V[a, 1], V[x, 2] - V[a, 2]
        det = nx * wx + ny * wy + nz * wz
        perm = (abs(ux) * (abs(vy * wz) + abs(vz * wy)) + abs(uy) * (abs(vz * wx) + abs(vx * wz))
                + abs(uz) * (abs(vx * wy) + abs(vy * wx)))
        if not abs(det) > _ORIENT_FILTER * perm:
            return False
        s = 1 if det > 0 else -1
        if side != 0 and s != side:
            return False
        side = s
    return side != 0


def _ray_outside(V, u, x, p, q, k0, k1) -> bool:
    """The ray ``u -> x`` lies strictly outside the convex corner ``(p, q)`` at ``u``."""
    o = _o2f(V, u, p, q, k0, k1)
    return o != 0 and (_o2f(V, u, p, x, k0, k1) * o < 0 or _o2f(V, u, x, q, k0, k1) * o < 0)


def _dominant_axis(V, ti) -> int:
    """The coordinate axis of the largest component of triangle ``ti``'s float normal."""
    a, b, c = ti[0], ti[1], ti[2]
    ux, uy, uz = V[b, 0] - V[a, 0], V[b, 1] - V[a, 1], V[b, 2] - V[a, 2]
    vx, vy, vz = V[c, 0] - V[a, 0], V[c, 1] - V[a, 1], V[c, 2] - V[a, 2]
    n0, n1, n2 = abs(uy * vz - uz * vy), abs(uz * vx - ux * vz), abs(ux * vy - uy * vx)
    return 0 if (n0 >= n1 and n0 >= n2) else (1 if n1 >= n2 else 2)


def _axes_apart(V, ti, tj) -> bool:
    """:func:`_axes_apart_np` for one pair: strictly separated along the cross product of an
    edge of each triangle (float filter of the dot products; undecided: False)."""
    for i in range(3):
        p, q = ti[i], ti[(i + 1) % 3]
        ex, ey, ez = V[q, 0] - V[p, 0], V[q, 1] - V[p, 1], V[q, 2] - V[p, 2]
        for j in range(3):
            r, t = tj[j], tj[(j + 1) % 3]
            fx, fy, fz = V[t, 0] - V[r, 0], V[t, 1] - V[r, 1], V[t, 2] - V[r, 2]
            ax, ay, az = ey * fz - ez * fy, ez * fx - ex * fz, ex * fy - ey * fx
            lo_a = lo_b = np.inf
            hi_a = hi_b = -np.inf
            for k in range(3):
                x = ti[k]
                d = V[x, 0] * ax + V[x, 1] * ay + V[x, 2] * az
                e = _DOT_FILTER * (abs(V[x, 0] * ax) + abs(V[x, 1] * ay) + abs(V[x, 2] * az))
                lo_a, hi_a = min(lo_a, d - e), max(hi_a, d + e)
                y = tj[k]
                d = V[y, 0] * ax + V[y, 1] * ay + V[y, 2] * az
                e = _DOT_FILTER * (abs(V[y, 0] * ax) + abs(V[y, 1] * ay) + abs(V[y, 2] * az))
                lo_b, hi_b = min(lo_b, d - e), max(hi_b, d + e)
            if hi_a < lo_b or hi_b < lo_a:
                return True
    return False


def _apart_in_projection(V, ti, tj, ax) -> bool:
    """Triangles whose projections along coordinate axis ``ax`` meet only in their shared
    vertices or edge, decided by a float filter (undecided: False). The 3D triangles then
    meet only there too."""
    k0, k1 = (ax + 1) % 3, (ax + 2) % 3
    # bit r of mi / mj: vertex r of ti / tj is shared (scalars: no allocation per pair)
    mi = mj = shared = 0
    for r in range(3):
        for s in range(3):
            if ti[r] == tj[s]:
                mi |= 1 << r
                mj |= 1 << s
                shared += 1
    if shared == 0:
        # an edge line of one triangle strictly separates the other
        for flip in range(2):
            A_ = ti if flip == 0 else tj
            B_ = tj if flip == 0 else ti
            for k in range(3):
                p, q, o3 = A_[k], A_[(k + 1) % 3], A_[(k + 2) % 3]
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
        # the two apexes strictly on opposite sides of the shared edge's line
        ai = ti[0] if not mi & 1 else (ti[1] if not mi & 2 else ti[2])
        aj = tj[0] if not mj & 1 else (tj[1] if not mj & 2 else tj[2])
        e0, e1 = -1, -1
        for r in range(3):
            if mi >> r & 1:
                if e0 < 0:
                    e0 = ti[r]
                else:
                    e1 = ti[r]
        u, v = min(e0, e1), max(e0, e1)
        return _o2f(V, u, v, ai, k0, k1) * _o2f(V, u, v, aj, k0, k1) < 0
    if shared == 1:
        # each edge ray at the shared vertex strictly outside the other triangle's corner
        ku = 0 if mi & 1 else (1 if mi & 2 else 2)
        kj = 0 if mj & 1 else (1 if mj & 2 else 2)
        u = ti[ku]
        pa, pb = ti[(ku + 1) % 3], ti[(ku + 2) % 3]
        pc, pd = tj[(kj + 1) % 3], tj[(kj + 2) % 3]
        return (_ray_outside(V, u, pc, pa, pb, k0, k1) and _ray_outside(V, u, pd, pa, pb, k0, k1)
                and _ray_outside(V, u, pa, pc, pd, k0, k1) and _ray_outside(V, u, pb, pc, pd, k0, k1))
    return False


def _undecided_pairs(V, T, pairs, moved) -> np.ndarray:
    """Mask of the box-overlapping pairs that the float filters leave to the exact test: a
    pair with a moved vertex that no plane separation (either way), no separation in any of
    the three coordinate projections and, for pairs with no shared vertex, no separation
    along an edge-edge cross product sets apart."""
    out = np.zeros(len(pairs), dtype=np.bool_)
    for r in range(len(pairs)):
        ti, tj = T[pairs[r, 0]], T[pairs[r, 1]]
        if not (moved[ti[0]] or moved[ti[1]] or moved[ti[2]] or moved[tj[0]] or moved[tj[1]]
                or moved[tj[2]]):
            continue
        if _plane_separates(V, ti, tj) or _plane_separates(V, tj, ti):
            continue
        ax = _dominant_axis(V, ti)
        if (_apart_in_projection(V, ti, tj, ax) or _apart_in_projection(V, ti, tj, (ax + 1) % 3)
                or _apart_in_projection(V, ti, tj, (ax + 2) % 3)):
            continue
        lone = True
        for k in range(3):
            if ti[k] == tj[0] or ti[k] == tj[1] or ti[k] == tj[2]:
                lone = False
        out[r] = not (lone and _axes_apart(V, ti, tj))
    return out


def _undecided_pairs_compiled(V, T, pairs, moved) -> np.ndarray:
    """:func:`_undecided_pairs` compiled (:mod:`cspace.geometry._kernels.trim`): identical output."""
    return _compiled.undecided_pairs(np.ascontiguousarray(V, np.float64),
                                     np.ascontiguousarray(T, np.int64),
                                     np.ascontiguousarray(pairs, np.int64).reshape(-1, 2),
                                     np.ascontiguousarray(moved, np.bool_).view(np.uint8))


def _common_integers(V: np.ndarray) -> list:
    """Float64 coordinates as Python ints at one common power-of-two scale (exact): the
    exact predicates below then run on integers."""
    ratios = [x.as_integer_ratio() for x in V.reshape(-1).tolist()]
    den = max(d for _, d in ratios)
    flat = [n * (den // d) for n, d in ratios]
    return [flat[k: k + 3] for k in range(0, len(flat), 3)]


def _segment_meets_triangle(p, q, tri, V) -> bool:
    """Does the closed segment ``pq`` meet the closed triangle ``tri`` (vertex ids)?"""
    a, b, c = (V[k] for k in tri)
    s1, s2 = _orient3(a, b, c, p), _orient3(a, b, c, q)
    if s1 * s2 > 0:
        return False
    if s1 == 0 and s2 == 0:  # coplanar
        return _coplanar_seg_tri(*_in_plane_2d([a, b, c], [p, q]))
    e = (_orient3(p, q, a, b), _orient3(p, q, b, c), _orient3(p, q, c, a))
    return all(x >= 0 for x in e) or all(x <= 0 for x in e)


def _o2(a, b, c) -> int:
    d = (b[0] - a[0]) * (c[1] - a[1]) - (b[1] - a[1]) * (c[0] - a[0])
    return (d > 0) - (d < 0)


def _coplanar_seg_tri(a, b, c, p, q) -> bool:
    if _o2(a, b, c) < 0:
        b, c = c, b
    inside = lambda x: _o2(a, b, x) >= 0 and _o2(b, c, x) >= 0 and _o2(c, a, x) >= 0  # noqa: E731
    if inside(p) or inside(q):
        return True
    for u, v in ((a, b), (b, c), (c, a)):
        o1, o2, o3, o4 = _o2(p, q, u), _o2(p, q, v), _o2(u, v, p), _o2(u, v, q)
        if o1 * o2 <= 0 and o3 * o4 <= 0 and not (o1 == o2 == o3 == o4 == 0):
            return True
        if o1 == o2 == 0 and o3 == o4 == 0 and (
            min(p[0], q[0]) <= max(u[0], v[0]) and min(u[0], v[0]) <= max(p[0], q[0])
            and min(p[1], q[1]) <= max(u[1], v[1]) and min(u[1], v[1]) <= max(p[1], q[1])
        ):
            return True
    return False


def _in_plane_2d(tri_pts, pts):
    """Exact coordinates of ``pts`` projected along the dominant axis of the exact normal of
    ``tri_pts`` (orientation-preserving projection up to one global sign)."""
    a, b, c = tri_pts
    n = _cross([b[i] - a[i] for i in range(3)], [c[i] - a[i] for i in range(3)])
    ax = max(range(3), key=lambda i: abs(n[i]))
    k = [(ax + 1) % 3, (ax + 2) % 3]
    return [[p[i] for i in k] for p in (*tri_pts, *pts)]


def _improper(V: list, s: list, t: list) -> bool:
    """Do triangles ``s`` and ``t`` (vertex ids into ``V``, exact integer coordinates of the
    rounded vertices) meet beyond the
    vertices and edge they share? A triangle that rounding made degenerate counts as
    meeting its neighbours."""
    shared = set(s) & set(t)
    if not shared:
        return any(_segment_meets_triangle(V[s[k]], V[s[(k + 1) % 3]], t, V) for k in range(3)) or any(
            _segment_meets_triangle(V[t[k]], V[t[(k + 1) % 3]], s, V) for k in range(3))
    if len(shared) == 2:
        u, v = sorted(shared)
        a = next(x for x in s if x not in shared)
        b = next(x for x in t if x not in shared)
        if _orient3(V[u], V[v], V[a], V[b]) != 0:
            return False  # two planes: they meet only along their common edge
        pu, pv, pa, pb = _in_plane_2d([V[u], V[v], V[a]], [V[b]])
        sa, sb = _o2(pu, pv, pa), _o2(pu, pv, pb)
        return sa == 0 or sb == 0 or sa == sb  # folded onto each other
    (u,) = shared
    a, b = (x for x in s if x != u)
    c, d = (x for x in t if x != u)
    if _segment_meets_triangle(V[a], V[b], t, V) or _segment_meets_triangle(V[c], V[d], s, V):
        return True
    # an edge at u lying in the other triangle's plane and pointing into its corner at u
    for x, (o0, o1) in ((a, (c, d)), (b, (c, d)), (c, (a, b)), (d, (a, b))):
        if _orient3(V[u], V[o0], V[o1], V[x]) == 0:
            pu, p0, p1, px = _in_plane_2d([V[u], V[o0], V[o1]], [V[x]])
            o = _o2(pu, p0, p1)
            if o == 0 or (_o2(pu, p0, px) * o >= 0 and _o2(pu, px, p1) * o >= 0):
                return True
    return False
