"""Float distances between triangles, vectorised over rows: point–segment, point–triangle,
segment–segment and triangle–triangle (the outside distance of triangle-pair C-obstacles).

Arrays in, arrays out: ``(k, 3)`` points and ``(k, 3, 3)`` triangles, float64; squared
distances where the name says ``d2``. They answer ``signed_distance`` (a float measure), never
a membership decision.
"""

from __future__ import annotations

import numpy as np


def _point_segment_d2(p, a, b):
    ab = b - a
    t = np.clip(np.einsum("kj,kj->k", p - a, ab) / np.maximum(np.einsum("kj,kj->k", ab, ab),
                                                                1e-300), 0.0, 1.0)
    d = p - (a + t[:, None] * ab)
    return np.einsum("kj,kj->k", d, d)


def shorter_edge_normals(tri) -> np.ndarray:
    """``(k, 3)`` normals of ``(k, 3, 3)`` triangles, the cross product of their two shorter
    edges (not normalised): on a sliver the better conditioned one (see
    cspace.mesh.query_reference._tri_dist2). Zero for a degenerate triangle."""
    tri = np.asarray(tri, dtype=np.float64)
    E = np.stack([tri[:, 1] - tri[:, 0], tri[:, 2] - tri[:, 1], tri[:, 0] - tri[:, 2]], axis=1)
    longest = np.einsum("kij,kij->ki", E, E).argmax(axis=1)
    r = np.arange(len(tri))
    return np.cross(E[r, (longest + 1) % 3], E[r, (longest + 2) % 3])


def _point_triangle_d2(p, tri):
    """Squared distance from points to triangles (k,), float."""
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
    plane = np.where(inside, h * h * nn, np.inf)
    edges = np.minimum.reduce([_point_segment_d2(p, a, b), _point_segment_d2(p, b, c),
                               _point_segment_d2(p, c, a)])
    return np.minimum(plane, edges)


def _segment_segment_d2(p1, q1, p2, q2):
    """Squared distance between segments (Ericson, Real-Time Collision Detection 5.1.9)."""
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
    d = (p1 + s[:, None] * d1) - (p2 + t[:, None] * d2)
    return np.einsum("kj,kj->k", d, d)


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
