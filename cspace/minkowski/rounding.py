"""NCC-CVMS stage ``rounding_check``: the float64 output re-checked exactly.

Rounding the exact vertices to float64 moves them; :func:`_rounding_check` finds the vertices
that moved (:func:`_moved`, compiled beside its reference) and tests every triangle pair near
them exactly for an intersection the rounding created (:mod:`cspace.mesh.self_intersection`).
"""

from __future__ import annotations

import numpy as np

from ..geometry._kernels import load
from ..geometry.exact import Grid
from ..mesh.self_intersection import _improper_pairs
from .output import _Output


_compiled = load("trim")


def _rounding_check(out: _Output, V: np.ndarray, grid: Grid,
                    workers: int = 1) -> tuple[np.ndarray, int, np.ndarray]:
    """Triangle pairs that meet improperly after rounding to float64, the number of
    processes that tested them exactly (several from ``_PARALLEL_CHECK`` pairs left by the
    float filters on), and which vertices rounding moved.

    In the exact result two triangles meet only in shared vertices and edges. Rounding moves
    a vertex by at most half an ulp per coordinate; only pairs with a moved vertex can change,
    and only if their rounded boxes overlap. Those pairs are tested exactly on the rounded
    coordinates (float filter, then Fractions): proper crossings for disjoint triangles,
    fold-over for triangles sharing an edge, and any contact beyond the shared vertex.
    """
    T = out.faces
    if not len(T):
        return np.zeros((0, 2), np.int64), 1, np.zeros(len(V), dtype=bool)
    moved = _moved_compiled(out.points, V, grid)
    if not moved.any():
        return np.zeros((0, 2), np.int64), 1, moved
    return (*_improper_pairs(V, T, grid, moved, workers), moved)


def _moved(points: list, V: np.ndarray, grid: Grid) -> np.ndarray:
    """Which float64 rows ``V[i]`` differ from their exact homogeneous grid points
    ``points[i]``, i.e. ``V[i] != (P[:3] / P[3] + origin) * 2**exponent``: ``(n,)`` bool,
    decided on Python integers."""
    e = grid.exponent
    up, down = (1 << e, 1) if e >= 0 else (1, 1 << -e)
    origin = grid.origin

    def moved_point(P, v) -> bool:
        for k in range(3):
            num, den = v[k].as_integer_ratio()
            if num * P[3] * down != (P[k] + origin[k] * P[3]) * up * den:
                return True
        return False

    return np.array([moved_point(P, v) for P, v in zip(points, V.tolist())], dtype=bool).reshape(-1)


def _moved_compiled(points: list, V: np.ndarray, grid: Grid) -> np.ndarray:
    """:func:`_moved` compiled (:mod:`cspace.geometry._kernels.trim`, int64/__int128 integers):
    identical output. The points it leaves (integers beyond 2**62) go to :func:`_moved`."""
    V = np.ascontiguousarray(V, dtype=np.float64)
    points = points if isinstance(points, list) else list(points)
    state = _compiled.moved_points(points, tuple(grid.origin), int(grid.exponent), V)
    moved = state == 1
    left = np.flatnonzero(state == 2)
    if len(left):
        moved[left] = _moved([points[i] for i in left.tolist()], V[left], grid)
    return moved
