"""What snapping does to a point: its exact deviation, and the grid points that cover it.

:func:`snap_deviation` is the exact largest ``|x − snap(x)|`` per axis; :func:`grow_points` adds
the corners of a box of grid steps to grid points (their hull is the points' hull grown by the
box). :class:`cspace.cobstacle.margin.Margin` builds the outward rounding of C-obstacles on these.
"""

from __future__ import annotations

import numpy as np

from .exact import Grid

__all__ = ["snap_deviation", "grow_points"]


def grow_points(ints: np.ndarray, steps) -> np.ndarray:
    """``(m, 3)`` int64: every grid point plus every corner of the box ``[-steps, steps]``
    (per axis), duplicates removed; their hull is the points' hull grown by the box. The
    points themselves when ``steps`` is zero."""
    P = np.asarray(ints, dtype=np.int64).reshape(-1, 3)
    g = np.asarray(steps, dtype=np.int64).reshape(3)
    if not g.any():
        return P
    C = np.unique(np.array([[a, b, c] for a in (-1, 1) for b in (-1, 1) for c in (-1, 1)],
                           dtype=np.int64) * g, axis=0)
    return np.unique((P[:, None, :] + C[None, :, :]).reshape(-1, 3), axis=0)


def snap_deviation(points, grid: Grid) -> np.ndarray:
    """``(3,)`` float64: the largest ``|x - snap(x)|`` per axis over ``(n, 3)`` points, exact.

    ``step * k`` is a float and ``x`` lies within half a step of it, so their difference is
    exact (Sterbenz; for ``k = 0`` it is ``x`` itself). The grid's origin, a whole number of
    steps, changes nothing: any frame of this step will do.
    """
    P = np.asarray(points, dtype=np.float64).reshape(-1, 3)
    if not len(P):
        return np.zeros(3)
    snapped = np.ldexp(np.rint(np.ldexp(P, -grid.exponent)), grid.exponent)
    return np.abs(P - snapped).max(axis=0)
