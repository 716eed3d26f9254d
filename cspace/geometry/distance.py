"""Float distances between triangles, vectorised over rows: point–segment, point–triangle,
segment–segment and triangle–triangle (the outside distance of triangle-pair C-obstacles),
with the closest points where a witness is wanted (:func:`closest_points`).

Arrays in, arrays out: ``(k, 3)`` points and ``(k, 3, 3)`` triangles, float64; squared
distances where the name says ``d2``. They answer ``signed_distance`` (a float measure), never
a membership decision.
"""

from __future__ import annotations

import numpy as np


def _point_segment(p, a, b):
    """Squared distances from points to segments (k,) and the closest points (k, 3)."""
    ab = b - a
    t = np.clip(np.einsum("kj,kj->k", p - a, ab) / np.maximum(np.einsum("kj,kj->k", ab, ab),
                                                                1e-300), 0.0, 1.0)
    x = a + t[:, None] * ab
    d = p - x
    return np.einsum("kj,kj->k", d, d), x


def _point_segment_d2(p, a, b):
    return _point_segment(p, a, b)[0]


def shorter_edge_normals(tri) -> np.ndarray:
    """``(k, 3)`` normals of ``(k, 3, 3)`` triangles, the cross product of their two shorter
    edges (not normalised): on a sliver the better conditioned one (see
    cspace.mesh.query_reference._tri_dist2). Zero for a degenerate triangle."""
    tri = np.asarray(tri, dtype=np.float64)
    E = np.stack([tri[:, 1] - tri[:, 0], tri[:, 2] - tri[:, 1], tri[:, 0] - tri[:, 2]], axis=1)
    longest = np.einsum("kij,kij->ki", E, E).argmax(axis=1)
    r = np.arange(len(tri))
    return np.cross(E[r, (longest + 1) % 3], E[r, (longest + 2) % 3])


def _point_triangle(p, tri):
    """Squared distances from points to triangles (k,) and the closest points (k, 3), float."""
    a, b, c = tri[:, 0], tri[:, 1], tri[:, 2]
    n = shorter_edge_normals(tri)
    nn = np.einsum("kj,kj->k", n, n)
    with np.errstate(divide="ignore", invalid="ignore"):
        h = np.einsum("kj,kj->k", p - a, n) / nn
    proj = p - h[:, None] * n
    inside = np.ones(len(p), dtype=bool)
    for u, v in ((a, b), (b, c), (c, a)):
        inside &= np.einsum("kj,kj->k", np.cross(v - u, proj - u), n) >= 0
    inside &= nn > 0
    best = np.where(inside, h * h * nn, np.inf)
    x = np.where(inside[:, None], proj, np.nan)
    for u, v in ((a, b), (b, c), (c, a)):
        d2, y = _point_segment(p, u, v)
        closer = d2 < best
        best = np.where(closer, d2, best)
        x = np.where(closer[:, None], y, x)
    return best, x


def _point_triangle_d2(p, tri):
    """Squared distance from points to triangles (k,), float."""
    return _point_triangle(p, tri)[0]


def _segment_segment(p1, q1, p2, q2):
    """Squared distances between segments (k,) and their closest points on each (Ericson,
    Real-Time Collision Detection 5.1.9)."""
    d1, d2, r = q1 - p1, q2 - p2, p1 - p2
    a = np.einsum("kj,kj->k", d1, d1)
    e = np.einsum("kj,kj->k", d2, d2)
    f = np.einsum("kj,kj->k", d2, r)
    c = np.einsum("kj,kj->k", d1, r)
    b = np.einsum("kj,kj->k", d1, d2)
    denom = a * e - b * b
    with np.errstate(divide="ignore", invalid="ignore"):
        s = np.where(denom > 0, np.clip((b * f - c * e) / denom, 0.0, 1.0), 0.0)
        t = np.where(e > 0, (b * s + f) / e, 0.0)
        s = np.where(t < 0, np.where(a > 0, np.clip(-c / a, 0.0, 1.0), 0.0), s)
        s = np.where(t > 1, np.where(a > 0, np.clip((b - c) / a, 0.0, 1.0), 0.0), s)
    t = np.clip(t, 0.0, 1.0)
    x1, x2 = p1 + s[:, None] * d1, p2 + t[:, None] * d2
    d = x1 - x2
    return np.einsum("kj,kj->k", d, d), x1, x2


def _segment_segment_d2(p1, q1, p2, q2):
    """Squared distance between segments (Ericson, Real-Time Collision Detection 5.1.9)."""
    return _segment_segment(p1, q1, p2, q2)[0]


def _segment_triangle_hits(p, q, tri):
    """Where segments ``p -> q`` cross triangles (k, 3), NaN where they do not (a proper
    crossing, float: a witness of two triangles that intersect, not a decision)."""
    a, b, c = tri[:, 0], tri[:, 1], tri[:, 2]
    n = np.cross(b - a, c - a)
    dp, dq = np.einsum("kj,kj->k", p - a, n), np.einsum("kj,kj->k", q - a, n)
    ok = dp * dq < 0  # the ends on either side: the division below is by a non-zero
    s = np.where(ok, dp, 0.0) / np.where(ok, dp - dq, 1.0)
    x = p + s[:, None] * (q - p)
    for u, v in ((a, b), (b, c), (c, a)):
        ok &= np.einsum("kj,kj->k", np.cross(v - u, x - u), n) >= 0
    return np.where(ok[:, None], x, np.nan)


def closest_points(A: np.ndarray, B: np.ndarray):
    """The closest points of two sets of triangles, float: ``(distance, a, b)`` with ``a`` on
    a triangle of ``A (m, 3, 3)`` and ``b`` on one of ``B (n, 3, 3)``; where two triangles
    cross, a point of their intersection as both (distance 0). Every pair is compared (pass
    the triangles near each other). A witness, never a decision."""
    A = np.asarray(A, dtype=np.float64).reshape(-1, 3, 3)
    B = np.asarray(B, dtype=np.float64).reshape(-1, 3, 3)
    i, j = np.meshgrid(np.arange(len(A)), np.arange(len(B)), indexing="ij")
    TA, TB = A[i.ravel()], B[j.ravel()]
    best, pa, pb = np.full(len(TA), np.inf), np.zeros((len(TA), 3)), np.zeros((len(TA), 3))

    def take(d2, xa, xb):
        nonlocal best, pa, pb
        closer = d2 < best
        best = np.where(closer, d2, best)
        pa = np.where(closer[:, None], xa, pa)
        pb = np.where(closer[:, None], xb, pb)

    for k in range(3):
        d2, x = _point_triangle(TA[:, k], TB)
        take(d2, TA[:, k], x)
        d2, x = _point_triangle(TB[:, k], TA)
        take(d2, x, TB[:, k])
        for m in range(3):
            d2, xa, xb = _segment_segment(TA[:, k], TA[:, (k + 1) % 3], TB[:, m],
                                          TB[:, (m + 1) % 3])
            take(d2, xa, xb)
    for k in range(3):  # crossing triangles: an edge of one through the other
        for P, T in ((TA, TB), (TB, TA)):
            x = _segment_triangle_hits(P[:, k], P[:, (k + 1) % 3], T)
            hit = ~np.isnan(x[:, 0])
            take(np.where(hit, 0.0, np.inf), np.where(hit[:, None], x, 0.0),
                 np.where(hit[:, None], x, 0.0))
    if not len(best):
        return np.inf, None, None
    k = int(np.argmin(best))
    return float(np.sqrt(best[k])), pa[k], pb[k]


def _tri_tri_distance(A: np.ndarray, B: np.ndarray) -> np.ndarray:
    """Distance between disjoint triangles (k,): the least of the corner-triangle and
    edge-edge distances, float."""
    d2 = [_point_triangle_d2(A[:, i], B) for i in range(3)]
    d2 += [_point_triangle_d2(B[:, i], A) for i in range(3)]
    for i in range(3):
        for j in range(3):
            d2.append(_segment_segment_d2(A[:, i], A[:, (i + 1) % 3], B[:, j],
                                          B[:, (j + 1) % 3]))
    return np.sqrt(np.minimum.reduce(d2))
