"""Convex patches of coplanar triangles (cspace.geometry.polygon.convex_patches): exactly the
union of their triangles on exact input; within the stated bound of it on snapped input,
whose flat faces are flat only within a step. Oracles: exact integer areas, and distances
from sampled hull points to the triangles (trimesh)."""

from __future__ import annotations

import numpy as np
import pytest
import trimesh

from cspace.geometry.polygon import convex_patches


def _grid_of_squares(n: int, m: int, seed: int) -> tuple[np.ndarray, np.ndarray]:
    """An n x m grid of unit squares in the plane z = 0, each cut along a random diagonal,
    counter-clockwise seen from +z."""
    rng = np.random.default_rng(seed)
    V = np.array([[i, j, 0] for i in range(n + 1) for j in range(m + 1)], dtype=np.int64)
    F = []
    for i in range(n):
        for j in range(m):
            a, b, c, d = (i * (m + 1) + j, (i + 1) * (m + 1) + j,
                          (i + 1) * (m + 1) + j + 1, i * (m + 1) + j + 1)
            F += [[a, b, c], [a, c, d]] if rng.random() < 0.5 else [[a, b, d], [b, c, d]]
    return V, np.array(F, dtype=np.int64)


def _turned(V: np.ndarray, scale: float, seed: int) -> np.ndarray:
    """V turned generically and scaled, rounded to integers: coplanar only within a unit."""
    from scipy.spatial.transform import Rotation

    R = Rotation.from_euler("xyz", np.random.default_rng(seed).uniform(0, 360, 3),
                            degrees=True).as_matrix()
    return np.round((V @ R.T) * scale + np.array([3e6, -2e6, 5e5])).astype(np.int64)


def _distance(pts: np.ndarray, T: np.ndarray) -> np.ndarray:
    """Distance from each point to the nearest of the triangles ``T (k, 3, 3)``: to the
    plane where the foot is inside a triangle, else to its edges (floats)."""
    a, b, c = T[:, 0], T[:, 1], T[:, 2]
    n = np.cross(b - a, c - a)
    n = n / np.linalg.norm(n, axis=1)[:, None]
    best = np.full(len(pts), np.inf)
    for q in range(len(T)):
        d = (pts - a[q]) @ n[q]
        foot = pts - d[:, None] * n[q]
        inside = np.ones(len(pts), dtype=bool)
        for u, v in ((a[q], b[q]), (b[q], c[q]), (c[q], a[q])):
            inside &= np.cross(v - u, foot - u) @ n[q] >= 0
        dist = np.where(inside, np.abs(d), np.inf)
        for u, v in ((a[q], b[q]), (b[q], c[q]), (c[q], a[q])):
            t = np.clip((pts - u) @ (v - u) / ((v - u) @ (v - u)), 0.0, 1.0)
            dist = np.minimum(dist, np.linalg.norm(pts - (u + t[:, None] * (v - u)), axis=1))
        best = np.minimum(best, dist)
    return best


def _area2(P: np.ndarray) -> int:
    """Twice the area of the triangles P (k, 3, 2) (exact, Python ints)."""
    P = P.astype(object)
    return sum(abs((b[0] - a[0]) * (c[1] - a[1]) - (b[1] - a[1]) * (c[0] - a[0]))
               for a, b, c in P.tolist())


def _hull_area2(P: np.ndarray) -> int:
    from scipy.spatial import ConvexHull

    h = P[ConvexHull(P.astype(float)).vertices].astype(object).tolist()
    return abs(sum(h[i][0] * h[i - 1][1] - h[i - 1][0] * h[i][1] for i in range(len(h))))


@pytest.mark.parametrize("seed", range(4))
def test_exact_coplanar_squares_merge_into_their_union(seed):
    n, m = 4 + seed, 3
    V, F = _grid_of_squares(n, m, seed)
    patches, patch, dev = convex_patches(V, F)
    assert dev == 0 and len(patch) == len(F)
    assert len(patches) < len(F) // 2  # merged (greedy: not necessarily one rectangle)
    for k, verts in enumerate(patches):
        mine = F[patch == k]
        assert set(np.unique(mine)) == set(verts.tolist())
        # exactly their union: the hull's area is the sum of the triangles' (which lie in it)
        assert _hull_area2(V[verts][:, :2]) == _area2(V[mine][:, :, :2])


def test_what_is_not_coplanar_or_faces_the_other_way_stays_apart():
    ico = trimesh.creation.icosphere(2)
    V = np.round(ico.vertices * 1e6).astype(np.int64)
    patches, patch, dev = convex_patches(V, ico.faces, tol=0)
    assert len(patches) == len(ico.faces) and dev == 0
    V, F = _grid_of_squares(3, 3, 0)
    both = np.vstack([F, F[:, ::-1]])  # a double-sided wall: each side on its own
    patches, patch, _ = convex_patches(V, both)
    assert not set(patch[: len(F)]) & set(patch[len(F):])
    # an L of squares: its reflex corner is never inside a patch's hull
    keep = np.array([not (i >= 2 and j >= 2) for i in range(4) for j in range(4)])
    V, F = _grid_of_squares(4, 4, 1)
    F = F.reshape(16, 2, 3)[keep].reshape(-1, 3)
    patches, patch, _ = convex_patches(V, F)
    for k, verts in enumerate(patches):
        assert _hull_area2(V[verts][:, :2]) == _area2(V[F[patch == k]][:, :, :2])


@pytest.mark.parametrize("seed", range(8))
def test_snapped_flat_faces_merge_within_the_stated_bound(seed):
    """A turned grid of squares rounded to integers (flat within a unit): with ``tol = 0``
    little merges; with ``tol = 2`` most does, and every point of a patch's hull lies within
    ``6 * tol`` of its triangles (sampled; distances to the triangles in floats)."""
    V0, F = _grid_of_squares(6 + seed % 3, 4 + seed % 2, seed)
    V = _turned(V0, 1000.0, seed)
    exact, _, _ = convex_patches(V, F, tol=0)
    patches, patch, dev = convex_patches(V, F, tol=2)
    assert len(patches) < len(exact) and len(patches) <= len(F) // 4
    rng = np.random.default_rng(seed)
    for k, verts in enumerate(patches):
        mine = F[patch == k]
        P = V[verts].astype(float)
        w = rng.dirichlet(np.ones(len(P)), size=200)
        # points on the hull's extreme parts too: pairs of vertices and the vertices
        pts = np.vstack([w @ P, P, (P[:, None] + P[None]).reshape(-1, 3) / 2])
        dist = _distance(pts, V[mine].astype(float))
        assert dist.max() <= 6 * 2 + 1e-6, dist.max()
    assert dev == 1
