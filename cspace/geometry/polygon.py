"""Fan triangulation of convex polygons given as vertex-index cycles."""

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
