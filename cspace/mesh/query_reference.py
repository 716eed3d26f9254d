"""Pure-Python references of the compiled mesh-query kernels (:mod:`cspace.geometry._kernels.meshquery`).

Operation for operation the same as the Cython kernels that :class:`cspace.mesh.query.MeshCO`
calls (containment by ray crossings, nearest triangle, segment entry); ``tests/test_kernels.py``
checks identical outputs. Nothing calls them in production.
"""

from __future__ import annotations

import numpy as np

from ..geometry.exact import _FILTER, _TINY


# Relative widening of the BVH slab test's parameters: their rounding error is about
# 3 eps (one subtraction, one division, and the rounding of p1 - p0); 1e-14 >> 3 eps.
_SLAB = 1e-14


_STATUS_UNSURE = 2


# --------------------------------------------------------------------------------------
# float filters: value and a rigorous bound on its rounding error


def _o2(au, av, bu, bv, pu, pv):
    """``(b - a) x (p - a)`` in 2D, and its error bound."""
    l = (bu - au) * (pv - av)
    r = (bv - av) * (pu - au)
    return l - r, _FILTER * (abs(l) + abs(r)) + _TINY


def _o3(ax, ay, az, bx, by, bz, cx, cy, cz, dx, dy, dz):
    """``det[a - d; b - d; c - d]`` (= ``n . (a - d)``, ``n = (b - a) x (c - a)``), error bound."""
    adx, ady, adz = ax - dx, ay - dy, az - dz
    bdx, bdy, bdz = bx - dx, by - dy, bz - dz
    cdx, cdy, cdz = cx - dx, cy - dy, cz - dz
    bdxcdy, cdxbdy = bdx * cdy, cdx * bdy
    cdxady, adxcdy = cdx * ady, adx * cdy
    adxbdy, bdxady = adx * bdy, bdx * ady
    det = adz * (bdxcdy - cdxbdy) + bdz * (cdxady - adxcdy) + cdz * (adxbdy - bdxady)
    perm = (
        (abs(bdxcdy) + abs(cdxbdy)) * abs(adz)
        + (abs(cdxady) + abs(adxcdy)) * abs(bdz)
        + (abs(adxbdy) + abs(bdxady)) * abs(cdz)
    )
    # Underflow: a 2x2 product term may lose up to 2**-1074 absolutely, then scaled by the
    # third factor; 2**-1070 per unit of that factor covers the sum of such losses.
    tiny = (abs(adz) + abs(bdz) + abs(cdz)) * 2.0**-1070 + _TINY
    return det, _FILTER * perm + tiny


def _cell(v, v0, inv, n):
    """Grid cell of coordinate ``v``: monotone non-decreasing in ``v`` (rounding is monotone)."""
    f = (v - v0) * inv
    if not f > 0.0:
        return 0
    if f >= n - 1:
        return n - 1
    return int(f)


# --------------------------------------------------------------------------------------
# membership


def _off_collinear(T, t, qx, qy, qz) -> bool:
    """q is certainly off the degenerate (collinear) triangle ``T[t]``: one of its edges'
    orientations with q, in the (y, z) or the (x, y) projection, is certainly non-zero (q on
    the segment would make every one zero)."""
    ax, ay, az = T[t, 0], T[t, 1], T[t, 2]
    bx, by, bz = T[t, 3], T[t, 4], T[t, 5]
    cx, cy, cz = T[t, 6], T[t, 7], T[t, 8]
    for v, e in (_o2(ay, az, by, bz, qy, qz), _o2(by, bz, cy, cz, qy, qz),
                 _o2(cy, cz, ay, az, qy, qz), _o2(ax, ay, bx, by, qx, qy),
                 _o2(bx, by, cx, cy, qx, qy), _o2(cx, cy, ax, ay, qx, qy)):
        if abs(v) > e:
            return True
    return False


def _contains_kernel(Q, T, lo, hi, sx, degen, cstart, ctris, y0, z0, iy, iz, ny, nz, out, unsure):
    """``out[i]``: inside by the float filters; ``unsure[i]``: undecided (exact path).
    Returns the number of undecided queries."""
    n_unsure = 0
    for i in range(Q.shape[0]):
        qx, qy, qz = Q[i, 0], Q[i, 1], Q[i, 2]
        c = _cell(qy, y0, iy, ny) * nz + _cell(qz, z0, iz, nz)
        w = 0
        status = -1
        for k in range(cstart[c], cstart[c + 1]):
            t = ctris[k]
            if qy < lo[t, 1] or qy > hi[t, 1] or qz < lo[t, 2] or qz > hi[t, 2] or qx > hi[t, 0]:
                continue
            inbox = qx >= lo[t, 0]
            if degen[t]:  # no crossing; q may lie on it (the closed surface) unless certainly off
                if inbox and not _off_collinear(T, t, qx, qy, qz):
                    status = _STATUS_UNSURE
                    break
                continue
            ax, ay, az = T[t, 0], T[t, 1], T[t, 2]
            bx, by, bz = T[t, 3], T[t, 4], T[t, 5]
            cx, cy, cz = T[t, 6], T[t, 7], T[t, 8]
            s = sx[t]
            if s != 0:
                # The projection first: q off the projected triangle is off the triangle and
                # not crossed, whatever its plane side (which a sliver cannot certify near it).
                v1, e1 = _o2(ay, az, by, bz, qy, qz)
                v2, e2 = _o2(by, bz, cy, cz, qy, qz)
                v3, e3 = _o2(cy, cz, ay, az, qy, qz)
                # Certainly outside the projected triangle if one certain sign disagrees.
                if (s > 0 and (v1 < -e1 or v2 < -e2 or v3 < -e3)) or (
                    s < 0 and (v1 > e1 or v2 > e2 or v3 > e3)
                ):
                    continue
                if not (abs(v1) > e1 and abs(v2) > e2 and abs(v3) > e3):
                    status = _STATUS_UNSURE
                    break
            dsign = 0
            if inbox:  # q may be on the triangle: its plane side must be certain
                d, e = _o3(ax, ay, az, bx, by, bz, cx, cy, cz, qx, qy, qz)
                if not abs(d) > e:  # (also NaN / inf after overflow)
                    status = _STATUS_UNSURE
                    break
                dsign = 1 if d > 0 else -1
            if s == 0:
                continue
            # Crossing ahead of q: the triangle lies beyond q, or q is behind its plane.
            if not inbox or dsign == s:
                w += s
        if status == _STATUS_UNSURE:
            unsure[i] = True
            n_unsure += 1
        else:
            out[i] = w != 0
    return n_unsure


def _cell_candidates(q, lo, hi, cstart, ctris, y0, z0, iy, iz, ny, nz):
    """Triangles whose closed box holds ``q``'s (y, z) and reaches ``x >= q_x``."""
    qx, qy, qz = q[0], q[1], q[2]
    c = _cell(qy, y0, iy, ny) * nz + _cell(qz, z0, iz, nz)
    out = np.zeros(cstart[c + 1] - cstart[c], dtype=np.int64)
    n = 0
    for k in range(cstart[c], cstart[c + 1]):
        t = ctris[k]
        if qy < lo[t, 1] or qy > hi[t, 1] or qz < lo[t, 2] or qz > hi[t, 2] or qx > hi[t, 0]:
            continue
        out[n] = t
        n += 1
    return out[:n]


def _cell_entries(lo, hi, y0, z0, iy, iz, ny, nz):
    """Total number of (cell, triangle) entries :func:`_build_cells` would make."""
    total = 0
    for t in range(lo.shape[0]):
        a = _cell(hi[t, 1], y0, iy, ny) - _cell(lo[t, 1], y0, iy, ny) + 1
        b = _cell(hi[t, 2], z0, iz, nz) - _cell(lo[t, 2], z0, iz, nz) + 1
        total += a * b
    return total


def _build_cells(lo, hi, y0, z0, iy, iz, ny, nz):
    """CSR lists of the triangles whose (y, z) box meets each cell (same cell function)."""
    m = lo.shape[0]
    count = np.zeros(ny * nz + 1, dtype=np.int64)
    for t in range(m):
        for a in range(_cell(lo[t, 1], y0, iy, ny), _cell(hi[t, 1], y0, iy, ny) + 1):
            for b in range(_cell(lo[t, 2], z0, iz, nz), _cell(hi[t, 2], z0, iz, nz) + 1):
                count[a * nz + b + 1] += 1
    start = np.cumsum(count)
    fill = start[:-1].copy()
    tris = np.zeros(start[-1], dtype=np.int64)
    for t in range(m):
        for a in range(_cell(lo[t, 1], y0, iy, ny), _cell(hi[t, 1], y0, iy, ny) + 1):
            for b in range(_cell(lo[t, 2], z0, iz, nz), _cell(hi[t, 2], z0, iz, nz) + 1):
                tris[fill[a * nz + b]] = t
                fill[a * nz + b] += 1
    return start, tris


# --------------------------------------------------------------------------------------
# bounding-volume hierarchy: distances and segments


def _box_dist2(px, py, pz, lo, hi, n):
    d = 0.0
    for k, p in ((0, px), (1, py), (2, pz)):
        if p < lo[n, k]:
            g = lo[n, k] - p
            d += g * g
        elif p > hi[n, k]:
            g = p - hi[n, k]
            d += g * g
    return d


def _seg_dist2(px, py, pz, ax, ay, az, bx, by, bz):
    ex, ey, ez = bx - ax, by - ay, bz - az
    wx, wy, wz = px - ax, py - ay, pz - az
    ee = ex * ex + ey * ey + ez * ez
    t = 0.0
    if ee > 0.0:
        t = min(1.0, max(0.0, (wx * ex + wy * ey + wz * ez) / ee))
    rx, ry, rz = wx - t * ex, wy - t * ey, wz - t * ez
    return rx * rx + ry * ry + rz * rz


def _tri_dist2(px, py, pz, T, t):
    """Squared distance from p to the closed triangle ``T[t]`` (float).

    The minimum of the three edge distances and, when p projects inside the triangle, the
    distance to its plane. "Inside" is decided by the signs of ``((v - u) x (p - u)) . n``
    for each edge ``u -> v``: each uses local differences, so needle-shaped triangles (common
    among the sum's edge facets) are not sent to the wrong Voronoi region, as the textbook
    region tests do (they lost 2.5e-7 on a 0.64 x 0.008 needle). A wrong sign can only occur
    within rounding of an edge, where both answers agree to rounding.
    """
    ax, ay, az = T[t, 0], T[t, 1], T[t, 2]
    bx, by, bz = T[t, 3], T[t, 4], T[t, 5]
    cx, cy, cz = T[t, 6], T[t, 7], T[t, 8]
    best = min(
        _seg_dist2(px, py, pz, ax, ay, az, bx, by, bz),
        _seg_dist2(px, py, pz, bx, by, bz, cx, cy, cz),
        _seg_dist2(px, py, pz, cx, cy, cz, ax, ay, az),
    )
    # The normal from the two shorter edges: e0 x e1 = e1 x e2 = e2 x e0 (= ab x ac), but the
    # product of the two longest edges of a sliver (a nearly parallel pair) cancels and tilts
    # the plane (3e-6 off at 0.26 from a 3.5 x 6e-13 sliver of a grown sum).
    e0x, e0y, e0z = bx - ax, by - ay, bz - az
    e1x, e1y, e1z = cx - bx, cy - by, cz - bz
    e2x, e2y, e2z = ax - cx, ay - cy, az - cz
    l0 = e0x * e0x + e0y * e0y + e0z * e0z
    l1 = e1x * e1x + e1y * e1y + e1z * e1z
    l2 = e2x * e2x + e2y * e2y + e2z * e2z
    if l0 >= l1 and l0 >= l2:
        ux, uy, uz, vx, vy, vz = e1x, e1y, e1z, e2x, e2y, e2z
    elif l1 >= l2:
        ux, uy, uz, vx, vy, vz = e2x, e2y, e2z, e0x, e0y, e0z
    else:
        ux, uy, uz, vx, vy, vz = e0x, e0y, e0z, e1x, e1y, e1z
    nx, ny, nz = uy * vz - uz * vy, uz * vx - ux * vz, ux * vy - uy * vx
    nn = nx * nx + ny * ny + nz * nz
    if not nn > 0.0:
        return best
    s0 = _edge_side(ax, ay, az, bx, by, bz, px, py, pz, nx, ny, nz)
    s1 = _edge_side(bx, by, bz, cx, cy, cz, px, py, pz, nx, ny, nz)
    s2 = _edge_side(cx, cy, cz, ax, ay, az, px, py, pz, nx, ny, nz)
    if s0 >= 0.0 and s1 >= 0.0 and s2 >= 0.0:
        h = (px - ax) * nx + (py - ay) * ny + (pz - az) * nz
        best = min(best, h * h / nn)
    return best


def _edge_side(ux, uy, uz, vx, vy, vz, px, py, pz, nx, ny, nz):
    """``((v - u) x (p - u)) . n``: positive when p projects to the left of u -> v."""
    ex, ey, ez = vx - ux, vy - uy, vz - uz
    wx, wy, wz = px - ux, py - uy, pz - uz
    return (ey * wz - ez * wy) * nx + (ez * wx - ex * wz) * ny + (ex * wy - ey * wx) * nz


def _tri_box_dist2(px, py, pz, T, t):
    """Squared distance from p to the bounding box of triangle ``T[t]``: no more than the
    distance to the triangle, a cheap test before it."""
    d = 0.0
    for k, p in ((0, px), (1, py), (2, pz)):
        lo = min(min(T[t, k], T[t, 3 + k]), T[t, 6 + k])
        hi = max(max(T[t, k], T[t, 3 + k]), T[t, 6 + k])
        if p < lo:
            g = lo - p
            d += g * g
        elif p > hi:
            g = p - hi
            d += g * g
    return d


def _nearest_kernel(Q, T, nlo, nhi, left, right, start, count, out):
    """Distance from each query to the nearest triangle (BVH, nearest child first; each
    node's box distance is kept with it on the stack, each triangle's box tested first)."""
    stack = np.zeros(256, dtype=np.int64)
    dist = np.zeros(256, dtype=np.float64)
    for i in range(Q.shape[0]):
        px, py, pz = Q[i, 0], Q[i, 1], Q[i, 2]
        best = np.inf
        sp = 1
        stack[0] = 0
        dist[0] = _box_dist2(px, py, pz, nlo, nhi, 0)
        while sp > 0:
            sp -= 1
            n = stack[sp]
            if dist[sp] >= best:
                continue
            if left[n] < 0:
                for t in range(start[n], start[n] + count[n]):
                    if _tri_box_dist2(px, py, pz, T, t) >= best:
                        continue
                    d = _tri_dist2(px, py, pz, T, t)
                    if d < best:
                        best = d
            else:
                a, b = left[n], right[n]
                da = _box_dist2(px, py, pz, nlo, nhi, a)
                db = _box_dist2(px, py, pz, nlo, nhi, b)
                if da < db:  # push the far child first: the near one is popped next
                    a, b, da, db = b, a, db, da
                if da < best:
                    stack[sp], dist[sp] = a, da
                    sp += 1
                if db < best:
                    stack[sp], dist[sp] = b, db
                    sp += 1
        out[i] = np.sqrt(best)


def _seg_box(p0x, p0y, p0z, dx, dy, dz, nlo, nhi, n):
    """False only if the segment ``p0 + t d``, ``t in [0, 1]``, surely misses the closed box.

    The slab parameters are widened by ``_SLAB`` relative (far more than their rounding), so
    a segment touching the box is never pruned.
    """
    t0, t1 = 0.0, 1.0
    if not (abs(dx) < np.inf and abs(dy) < np.inf and abs(dz) < np.inf):
        return True  # p1 - p0 overflowed: no pruning
    for k, p, d in ((0, p0x, dx), (1, p0y, dy), (2, p0z, dz)):
        if d == 0.0:
            if p < nlo[n, k] or p > nhi[n, k]:
                return False
        else:
            ta = (nlo[n, k] - p) / d
            tb = (nhi[n, k] - p) / d
            if ta > tb:
                ta, tb = tb, ta
            ta = min(ta * (1.0 - _SLAB), ta * (1.0 + _SLAB)) - 1e-300
            tb = max(tb * (1.0 - _SLAB), tb * (1.0 + _SLAB)) + 1e-300
            if ta > t0:
                t0 = ta
            if tb < t1:
                t1 = tb
            if t0 > t1:
                return False
    return True


def _segment_kernel(P0, P1, T, degen, nlo, nhi, left, right, start, count, first_only):
    """Filtered segment-triangle tests over the BVH.

    Returns ``status`` per segment (1: a certain hit, 2: no certain hit but undecided pairs,
    0: surely meets no triangle) and the pairs ``(segment, triangle, t_lo, t_hi)`` of certain
    hits (with an enclosure of the crossing parameter) and of undecided pairs (``t_lo = -1``).
    With ``first_only`` the traversal stops at the first certain hit.
    """
    k = P0.shape[0]
    status = np.zeros(k, dtype=np.int8)
    cap = 1024
    ps = np.zeros(cap, dtype=np.int64)
    pt = np.zeros(cap, dtype=np.int64)
    plo = np.zeros(cap)
    phi = np.zeros(cap)
    np_ = 0
    stack = np.zeros(256, dtype=np.int64)
    for i in range(k):
        px, py, pz = P0[i, 0], P0[i, 1], P0[i, 2]
        qx, qy, qz = P1[i, 0], P1[i, 1], P1[i, 2]
        dx, dy, dz = qx - px, qy - py, qz - pz
        st = 0
        sp = 1
        stack[0] = 0
        while sp > 0:
            sp -= 1
            n = stack[sp]
            if not _seg_box(px, py, pz, dx, dy, dz, nlo, nhi, n):
                continue
            if left[n] >= 0:
                stack[sp] = left[n]
                stack[sp + 1] = right[n]
                sp += 2
                continue
            for t in range(start[n], start[n] + count[n]):
                tlo, thi = -1.0, 1.0  # t_lo < 0 marks an undecided pair
                certain = False
                if not degen[t]:
                    ax, ay, az = T[t, 0], T[t, 1], T[t, 2]
                    bx, by, bz = T[t, 3], T[t, 4], T[t, 5]
                    cx, cy, cz = T[t, 6], T[t, 7], T[t, 8]
                    d0, e0 = _o3(ax, ay, az, bx, by, bz, cx, cy, cz, px, py, pz)
                    d1, e1 = _o3(ax, ay, az, bx, by, bz, cx, cy, cz, qx, qy, qz)
                    if (d0 > e0 and d1 > e1) or (d0 < -e0 and d1 < -e1):
                        continue  # both ends strictly on one side of the plane
                    if abs(d0) > e0 and abs(d1) > e1:
                        # Strict crossing of the plane: does the line pass through the triangle?
                        o1, f1 = _o3(px, py, pz, qx, qy, qz, ax, ay, az, bx, by, bz)
                        o2, f2 = _o3(px, py, pz, qx, qy, qz, bx, by, bz, cx, cy, cz)
                        o3, f3 = _o3(px, py, pz, qx, qy, qz, cx, cy, cz, ax, ay, az)
                        if (o1 > f1 or o2 > f2 or o3 > f3) and (o1 < -f1 or o2 < -f2 or o3 < -f3):
                            continue  # certain opposite signs: the line misses
                        if (o1 > f1 and o2 > f2 and o3 > f3) or (
                            o1 < -f1 and o2 < -f2 and o3 < -f3
                        ):
                            certain = True
                            a0, a1 = abs(d0), abs(d1)
                            tlo = (a0 - e0) / (a0 + a1 + e0 + e1) * (1.0 - 8 * 2.0**-53)
                            thi = min(1.0, (a0 + e0) / (a0 + a1 - e0 - e1) * (1.0 + 8 * 2.0**-53))
                if np_ == cap:
                    cap *= 2
                    ps2 = np.zeros(cap, dtype=np.int64)
                    pt2 = np.zeros(cap, dtype=np.int64)
                    plo2, phi2 = np.zeros(cap), np.zeros(cap)
                    ps2[:np_] = ps
                    pt2[:np_] = pt
                    plo2[:np_] = plo
                    phi2[:np_] = phi
                    ps, pt, plo, phi = ps2, pt2, plo2, phi2
                ps[np_], pt[np_], plo[np_], phi[np_] = i, t, tlo, thi
                np_ += 1
                if certain:
                    st = 1
                    if first_only:
                        break
                elif st == 0:
                    st = 2
            if st == 1 and first_only:
                break
        status[i] = st
    return status, ps[:np_], pt[:np_], plo[:np_], phi[:np_]
