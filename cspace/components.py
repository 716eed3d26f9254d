"""Weld, deduplicate and split triangle meshes into parts, exactly on a grid.

Steps 1-3 of :func:`cspace.model.model_scene` (see there), shared with
:meth:`cspace.CSpaceObstacle.build`, which splits a non-manifold obstacle the same way:

- :func:`weld_dedupe`: vertices welded by exact snapped position, collapsed triangles dropped,
  repeated triangles (same three welded vertices) kept once, counted by winding.
- :func:`split_parts`: connected parts across manifold edges (a non-manifold edge or vertex
  separates the pieces meeting there); a closed part with a vertex inside another closed
  part's solid (decided exactly) stays with it as a cavity.
"""

from __future__ import annotations

import numpy as np

from .errors import InvalidMeshError
from .exact import Grid
from .graphs import component_labels

__all__ = ["weld_dedupe", "edge_uses", "split_parts"]


def _parity(F: np.ndarray) -> np.ndarray:
    """Permutation parity of each triple (equal parity on the same vertices: same winding)."""
    inv = (F[:, 0] > F[:, 1]).astype(np.int8) + (F[:, 0] > F[:, 2]) + (F[:, 1] > F[:, 2])
    return inv % 2


def weld_dedupe(body, grid: Grid):
    """Welded grid ints, deduplicated faces and the counts of steps 1-2."""
    ints, inverse = np.unique(grid.snap(body.vertices), axis=0, return_inverse=True)
    F = inverse.reshape(-1)[body.faces]
    collapsed = (F[:, 0] == F[:, 1]) | (F[:, 1] == F[:, 2]) | (F[:, 0] == F[:, 2])
    F = F[~collapsed]
    _, first, which = np.unique(np.sort(F, axis=1), axis=0, return_index=True,
                                return_inverse=True)
    which = which.reshape(-1)
    keep = np.zeros(len(F), dtype=bool)
    keep[first] = True
    same = _parity(F) == _parity(F[first[which]])
    counts = {"triangles": len(body.faces), "collapsed": int(collapsed.sum()),
              "double_sided": int((~keep & ~same).sum()), "repeated": int((~keep & same).sum())}
    return ints, F[np.sort(first)], counts


def edge_uses(F: np.ndarray, n: int):
    """Undirected edge key of each half-edge ``3 * face + corner``, and its use count."""
    a, b = F.reshape(-1), F[:, [1, 2, 0]].reshape(-1)
    key = np.minimum(a, b) * n + np.maximum(a, b)
    _, inv, count = np.unique(key, return_inverse=True, return_counts=True)
    return inv.reshape(-1), count


def split_parts(ints: np.ndarray, F: np.ndarray) -> list[np.ndarray]:
    """Face index arrays of the bodies of step 3, in order of their first face."""
    m = len(F)
    edge, count = edge_uses(F, len(ints))
    face = np.repeat(np.arange(m), 3)
    # Faces sharing a manifold edge (two faces): link each half-edge's face to the first face
    # using that edge. A non-manifold edge (two boxes sharing an edge) links nothing, so such
    # a mesh falls apart into its manifold pieces, each a solid when closed.
    first = np.full(len(count), m, dtype=np.int64)
    np.minimum.at(first, edge, face)
    link = count[edge] == 2
    ncomp, label = component_labels(m, face[link], first[edge][link])
    boundary = np.zeros(ncomp, dtype=bool)
    np.logical_or.at(boundary, label[face], count[edge] == 1)
    # Closed components nested in another closed one's box stay with it (possible cavity).
    lo = np.full((ncomp, 3), np.iinfo(np.int64).max)
    hi = np.full((ncomp, 3), np.iinfo(np.int64).min)
    corners = ints[F]  # (m, 3, 3)
    np.minimum.at(lo, label, corners.min(axis=1))
    np.maximum.at(hi, label, corners.max(axis=1))
    closed = np.nonzero(~boundary)[0]
    inside = ((lo[closed, None] <= lo[None, closed])
              & (hi[None, closed] <= hi[closed, None])).all(2)
    np.fill_diagonal(inside, False)
    i, j = np.nonzero(inside)
    # A box inside a box is not a cavity yet: one vertex of the inner component must lie in
    # the outer one's solid, decided exactly (winding number from a symbolically perturbed
    # ray, boundary included).
    keep = np.ones(len(i), dtype=bool)
    for a in np.unique(i).tolist():
        rows = np.nonzero(i == a)[0]
        outer = F[label == closed[a]]
        try:
            from .meshquery import MeshCO

            solid = MeshCO(ints.astype(np.float64), outer, name="part")
        except InvalidMeshError:  # not an oriented 2-cycle: keep the boxes' verdict
            continue
        probes = np.array([ints[F[label == closed[b]][0, 0]] for b in j[rows].tolist()])
        keep[rows] = solid.contains(probes.astype(np.float64))
    i, j = i[keep], j[keep]
    _, group = component_labels(ncomp, closed[i], closed[j])
    group = group[label]
    firsts = np.full(group.max() + 1, m)
    np.minimum.at(firsts, group, np.arange(m))
    return [np.nonzero(group == g)[0] for g in np.argsort(firsts) if firsts[g] < m]
