"""Convex polygons as vertex-index cycles: their fan triangulation, and the convex patches
that coplanar triangles of a mesh merge into."""

from __future__ import annotations

import numpy as np


def fan_triangles(offsets: np.ndarray, indices: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Fan triangulation of CSR polygons (exact for convex ones, orientation kept).

    Returns ``(faces (m, 3) int64, polygon (m,) int64)``: triangle ``k`` of polygon ``i`` is
    ``(p[0], p[k], p[k + 1])`` for ``k = 1 .. degree - 2``.
    """
    deg = np.diff(offsets)
    polygon = np.repeat(np.arange(len(deg)), deg - 2)
    k = np.arange(len(polygon)) - np.repeat(np.cumsum(deg - 2) - (deg - 2), deg - 2) + 1
    start = offsets[polygon]
    faces = np.stack([indices[start], indices[start + k], indices[start + k + 1]], axis=1)
    return faces.astype(np.int64), polygon.astype(np.int64)


def convex_patches(ints: np.ndarray, faces: np.ndarray,
                   tol: int = 0) -> tuple[list, np.ndarray, int]:
    """Neighbouring, (nearly) coplanar triangles merged into convex patches, exactly.

    Parameters
    ----------
    ints : (n, 3) int64
        Grid integers.
    faces : (m, 3) int64
        Triangles (counter-clockwise from outside for a closed mesh; any orientation).
    tol : int
        How far (grid units) a patch may reach beyond its triangles: 0 merges exactly
        coplanar triangles into exactly their union. A snapped mesh's flat faces are flat,
        and their straight edges straight, only within its snapping.

    Returns
    -------
    patches : list of (k,) int64
        The vertices of each patch's triangles. With ``tol = 0`` the patch is a convex
        polygon (their hull), exactly their union.
    patch : (m,) int64
        The patch each triangle is in.
    deviation : int
        1 if some patch used ``tol`` (a vertex off its plane, a turn dropped), else 0: the
        hull of a patch's vertices then lies within ``6 * tol`` of its triangles.

    Growth, in the projection along the largest axis of the patch's first triangle's normal:
    a triangle joins a patch across one of its boundary edges ``(u, v)`` when it holds that
    edge as ``(v, u)``, faces the same way, and brings a vertex ``w`` strictly across the
    edge, within ``tol`` of the plane. The patch's cycle stays convex: where a turn at a
    vertex becomes reflex, that vertex leaves the cycle if every vertex of the triangles
    between the cycle's new chord and it lies within ``tol`` of the chord (else the triangle
    does not join). With ``tol = 0`` nothing is dropped and the projected cycle is exactly
    the union of the projected triangles (each joins across an edge of a convex polygon). Else
    the projected cycle holds the projected triangles and lies within ``tol`` of them (each
    dropped run of the boundary, a path across the strip of width ``tol`` along its chord), and
    lifted back to 3D with both ends within ``tol`` of the plane (whose slope along the
    projection is at most 1 per axis), a point of the hull is within
    ``(1 + sqrt(2) + 2 sqrt(3)) tol < 6 tol`` of a triangle. Exact integer tests; greedy, from
    each unused triangle in order. Triangles of zero area stay as they are.
    """
    V = np.asarray(ints, dtype=np.int64).reshape(-1, 3)
    F = np.asarray(faces, dtype=np.int64).reshape(-1, 3)
    P = V[F]
    N = np.cross(P[:, 1] - P[:, 0], P[:, 2] - P[:, 0]).astype(object)  # exact: Python ints
    Vo = V.astype(object).tolist()
    by_edge: dict = {}
    for t, (u, v, w) in enumerate(F.tolist()):
        for e, x in (((u, v), w), ((v, w), u), ((w, u), v)):
            by_edge[e] = (t, x)
    out: list = []
    used = np.zeros(len(F), dtype=bool)
    patch = np.empty(len(F), dtype=np.int64)
    deviation = 0
    tt = tol * tol
    for t in range(len(F)):
        if used[t]:
            continue
        used[t] = True
        n = N[t].tolist()
        if not any(n):
            patch[t] = len(out)
            out.append(F[t].copy())  # zero area: on its own
            continue
        ax = max(range(3), key=lambda k: abs(n[k]))
        a, b = (ax + 1) % 3, (ax + 2) % 3
        sense = 1 if n[ax] > 0 else -1  # projected, counter-clockwise means +n
        d = sum(c * x for c, x in zip(n, Vo[F[t, 0]]))
        nn = sum(c * c for c in n)

        def left(p, q, r) -> int:  # orientation of p, q, r projected, in the patch's sense
            (px, py), (qx, qy), (rx, ry) = ((Vo[x][a], Vo[x][b]) for x in (p, q, r))
            return sense * ((qx - px) * (ry - py) - (qy - py) * (rx - px))

        def near_chord(p, q, run) -> bool:  # every vertex of run within tol of p -> q
            (px, py), (qx, qy) = (Vo[p][a], Vo[p][b]), (Vo[q][a], Vo[q][b])
            cc = (qx - px) ** 2 + (qy - py) ** 2
            return all(((qx - px) * (Vo[x][b] - py) - (qy - py) * (Vo[x][a] - px)) ** 2
                       <= tt * cc for x in run)

        # the cycle, and per cycle edge the vertices dropped between its ends
        ring, runs = F[t].tolist(), [[], [], []]
        members = [t]
        grown = True
        while grown:
            grown = False
            for i in range(len(ring)):
                u, v = ring[i], ring[(i + 1) % len(ring)]
                hit = by_edge.get((v, u))
                if hit is None or used[hit[0]] or hit[1] in ring:
                    continue
                s, w = hit
                off = sum(c * x for c, x in zip(n, Vo[w])) - d
                if (sum(c * x for c, x in zip(n, N[s].tolist())) <= 0
                        or off * off > tt * nn or left(u, v, w) >= 0):
                    continue
                joined = _convex_join(ring, runs, i, w, left, near_chord)
                if joined is None:
                    continue
                ring, runs, dropped = joined
                used[s] = True
                members.append(s)
                deviation |= bool(off) or dropped
                grown = True
                break
        # all their vertices: a dropped one may lie off the plane of the cycle's
        patch[members] = len(out)
        out.append(np.unique(F[members]))
    return out, patch, int(deviation)


def _convex_join(ring: list, runs: list, i: int, w: int, left, near_chord):
    """``ring`` with ``w`` inserted after position ``i``, kept convex by dropping reflex
    vertices next to it whose dropped runs stay near the new chord: ``(ring, runs, dropped)``
    (the cycle read from ``w``), or None. ``runs[e]``: the vertices dropped between
    ``ring[e]`` and ``ring[e + 1]``."""
    n = len(ring)
    order = [(i + 1 + j) % n for j in range(n)]  # v = ring[i + 1], ..., u = ring[i]
    ring = [w] + [ring[j] for j in order]  # w, v, ..., u: the edge u -> v split at w
    runs = [[]] + [runs[j] for j in order[:-1]] + [[]]
    dropped = False
    while len(ring) > 3 and left(w, ring[1], ring[2]) < 0:  # reflex after w
        run = runs[0] + [ring[1]] + runs[1]
        if not near_chord(w, ring[2], run):
            return None
        del ring[1]
        runs[0:2] = [run]
        dropped = True
    while len(ring) > 3 and left(ring[-2], ring[-1], w) < 0:  # reflex before w
        run = runs[-2] + [ring[-1]] + runs[-1]
        if not near_chord(ring[-2], w, run):
            return None
        del ring[-1]
        runs[-2:] = [run]
        dropped = True
    if dropped and left(ring[-1], w, ring[1]) < 0:  # w itself turned reflex
        return None
    return ring, runs, dropped
