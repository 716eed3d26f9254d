"""What an operand is: a mesh, a path, a point set or a polytope, and its flat special cases.

Helpers shared by the sums and the C-obstacles: :func:`_is_mesh`, :func:`_mesh_arrays`,
:func:`_vertices_of` read any accepted operand as float64 vertices and int64 faces;
:func:`_closed_2cycle` welds a closed 2-cycle exactly; :func:`_flat_hull` /
:func:`_flat_convex_mesh` give an exactly flat convex point set its mesh.
"""

from __future__ import annotations

import os
from fractions import Fraction

import numpy as np

from ..errors import InvalidMeshError
from ..geometry.exact import Grid
from .convex import ConvexPolytope


# --------------------------------------------------------------------------------------
# public classes


def _is_mesh(obj) -> bool:
    """A mesh-like operand: an object with faces, a (vertices, faces) pair, or a path."""
    if hasattr(obj, "faces"):
        return True
    if isinstance(obj, (str, os.PathLike)):
        return True
    return (
        isinstance(obj, tuple) and len(obj) == 2
        and np.ndim(obj[0]) == 2 and np.ndim(obj[1]) == 2
    )


def _as_convex(obj, grid: Grid, name: str) -> ConvexPolytope:
    """ConvexPolytope on ``grid`` from a polytope, an (n, 3) point array or a closed convex mesh."""
    if isinstance(obj, ConvexPolytope):
        return obj.on_grid(grid)
    if _is_mesh(obj):
        return ConvexPolytope.from_mesh(obj, grid=grid, name=name)
    return ConvexPolytope.from_points(np.asarray(obj, dtype=np.float64), grid=grid, name=name)


def _vertices_of(obj) -> np.ndarray:
    """(n, 3) float64 coordinates of an operand, to size the grid."""
    if isinstance(obj, ConvexPolytope) or hasattr(obj, "vertices"):
        return np.asarray(obj.vertices, dtype=np.float64)
    if isinstance(obj, (str, os.PathLike)):  # the file's own floats, not snapped ones
        from .files import read_mesh_file

        return np.asarray(read_mesh_file(obj).vertices, dtype=np.float64)
    if _is_mesh(obj):
        return np.asarray(obj[0], dtype=np.float64)
    a = np.asarray(obj, dtype=np.float64)
    if a.ndim != 2 or a.shape[1] != 3:
        raise InvalidMeshError(
            f"expected a ConvexPolytope, (n, 3) points or a closed convex mesh, got shape {a.shape}"
        )
    return a


def _mesh_arrays(obj) -> tuple[np.ndarray, np.ndarray]:
    """``(vertices float64, faces int64)`` of a mesh-like operand, as given (not validated)."""
    if isinstance(obj, (str, os.PathLike)):
        from .files import read_mesh_file

        f = read_mesh_file(obj)
        return np.asarray(f.vertices, dtype=np.float64), np.asarray(f.faces, dtype=np.int64)
    if hasattr(obj, "vertices") and hasattr(obj, "faces"):
        return np.asarray(obj.vertices, dtype=np.float64), np.asarray(obj.faces, dtype=np.int64)
    return np.asarray(obj[0], dtype=np.float64), np.asarray(obj[1], dtype=np.int64)


def _closed_2cycle(V: np.ndarray, F: np.ndarray):
    """The triangles with vertices welded by exact float position, ``(U, G)``, when they form
    a closed 2-cycle (every directed edge balanced by its reverse: the mesh queries' own
    check), else None."""
    from ..errors import InvalidMeshError
    from .query import _closed_mesh_arrays

    V = np.asarray(V, dtype=np.float64).reshape(-1, 3)
    if F.min() < 0 or F.max() >= len(V):
        return None
    U, inv = np.unique(V, axis=0, return_inverse=True)
    G = inv.reshape(-1)[F]
    try:
        _closed_mesh_arrays(U, G, "obstacle")
    except InvalidMeshError:
        return None
    return U, G


def _hull_excess(*operands) -> float:
    """How far the hulls among ``operands`` may exceed the bodies they stand for (the sum of
    their :attr:`ConvexPolytope.excess`; 0 for anything else)."""
    return float(sum(getattr(op, "excess", 0.0) or 0.0 for op in operands))


def _wider_somewhere(R: np.ndarray, O: np.ndarray) -> bool:
    """Is the robot wider than the obstacle's box on some axis (exact, on the floats)? Then
    it can never lie inside the obstacle (no containment term is needed)."""
    for k in range(3):
        if (Fraction(float(R[:, k].max())) - Fraction(float(R[:, k].min()))
                > Fraction(float(O[:, k].max())) - Fraction(float(O[:, k].min()))):
            return True
    return False


class _Mesh:
    """Vertices and faces of several operands joined (for FCL checks and drawing)."""

    def __init__(self, vertices: np.ndarray, faces: np.ndarray, name: str = "mesh"):
        self.vertices, self.faces, self.name = vertices, faces, name

    @classmethod
    def join(cls, meshes) -> "_Mesh":
        V, F, n = [], [], 0
        for m in meshes:
            V.append(np.asarray(m.vertices, dtype=np.float64))
            F.append(np.asarray(m.faces, dtype=np.int64) + n)
            n += len(V[-1])
        return cls(np.vstack(V), np.vstack(F), "+".join(getattr(m, "name", "mesh") for m in meshes))


class _FlatOperand:
    """A flat convex operand (a polygon or a segment) on the grid: its points and, for
    drawing and FCL, a fan of triangles over its hull (internal)."""

    kind = "flat"

    def __init__(self, ints: np.ndarray, grid: Grid):
        self.ints, self.faces = _flat_hull(ints)
        self.grid = grid

    @property
    def vertices(self) -> np.ndarray:
        return self.grid.to_float(self.ints)


def _flat_hull(P: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The hull of coplanar (or collinear) grid points as ``(corners, fan triangles)``,
    exact: Andrew's monotone chain on the projection along the axis nearest the normal."""
    P = np.unique(np.asarray(P, dtype=np.int64), axis=0)
    d = P - P[0]
    n = np.zeros(3, dtype=object)
    for k in range(1, len(P)):  # a normal from the first non-collinear triple
        n = np.cross(d[1].astype(object), d[k].astype(object))
        if any(n):
            break
    drop = int(np.argmax([abs(int(x)) for x in n])) if any(n) else int(np.argmin(np.ptp(P, 0)))
    keep = [a for a in range(3) if a != drop]
    pts = sorted(range(len(P)), key=lambda i: (int(P[i, keep[0]]), int(P[i, keep[1]])))

    def cross(o, a, b):
        (ox, oy), (ax, ay), (bx, by) = (P[i, keep].tolist() for i in (o, a, b))
        return (ax - ox) * (by - oy) - (ay - oy) * (bx - ox)

    hull = []
    for seq in (pts, pts[::-1]):
        part = []
        for i in seq:
            while len(part) >= 2 and cross(part[-2], part[-1], i) <= 0:
                part.pop()
            part.append(i)
        hull += part[:-1]
    corners = P[hull] if len(hull) >= 2 else P[:1]
    if len(corners) == 2:  # a segment: one degenerate triangle for FCL and drawing
        corners = np.vstack([corners, corners[1:]])
    # (0, 3) for a point: joined with other operands' faces, the shape must still stack
    faces = np.array([[0, k, k + 1] for k in range(1, len(corners) - 1)],
                     dtype=np.int64).reshape(-1, 3)
    return corners, faces


def _flat_convex_mesh(P: np.ndarray, F: np.ndarray) -> bool:
    """Is a mesh whose grid points ``P`` are coplanar a convex polygon (or segment), modelled
    one- or two-sided: do its triangles cover their hull exactly once or twice? Exact: twice
    the projected areas, in integers, along the axis nearest the plane's normal."""
    corners, _ = _flat_hull(P)
    if len(corners) < 3 or not len(F):
        return True  # a segment: no area to compare
    U = np.unique(P, axis=0)
    d = (U - U[0]).astype(object)
    n = next((c for k in range(2, len(U)) for c in [np.cross(d[1], d[k])] if any(c)), None)
    if n is None:
        return True  # collinear
    if any(int(np.dot(n, x)) for x in d):
        return False  # not flat: some other degeneracy (a collapsed face)
    drop = int(np.argmax([abs(int(x)) for x in n]))
    keep = [a for a in range(3) if a != drop]

    def twice_area(tri) -> int:
        (ax, ay), (bx, by), (cx, cy) = ([int(v) for v in p[keep]] for p in tri)
        return abs((bx - ax) * (cy - ay) - (by - ay) * (cx - ax))

    hull = sum(twice_area((corners[0], corners[k], corners[k + 1]))
               for k in range(1, len(corners) - 1))
    total = sum(twice_area(P[f]) for f in np.asarray(F, np.int64))
    return total in (hull, 2 * hull)
