"""Weld, deduplicate and split triangle meshes into parts, exactly on a grid.

Steps 1-3 of :func:`cspace.scene.model.model_scene` (see there), shared with
:meth:`cspace.CSpaceObstacle.build`, which splits a non-manifold obstacle the same way:

- :func:`weld_dedupe`: vertices welded by exact snapped position, collapsed triangles dropped,
  repeated triangles (same three welded vertices) kept once, counted by winding;
  :func:`snapping_losses`: what that took (segments and points thinner than the step, the
  closed 2-cycle of a closed body), for a model to keep.
- :func:`split_parts`: connected parts across manifold edges (a non-manifold edge or vertex
  separates the pieces meeting there); a closed part with a vertex inside another closed
  part's solid (decided exactly) stays with it as a cavity.
"""

from __future__ import annotations

import numpy as np

from ..errors import InvalidMeshError
from ..geometry._kernels import load
from ..geometry.exact import Grid
from ..geometry.graphs import component_labels

__all__ = ["unique_rows", "weld_dedupe", "weld_split", "snapping_losses", "edge_uses",
           "split_parts", "split_mesh", "nested_pairs"]


def _parity(F: np.ndarray) -> np.ndarray:
    """Permutation parity of each triple (equal parity on the same vertices: same winding)."""
    inv = (F[:, 0] > F[:, 1]).astype(np.int8) + (F[:, 0] > F[:, 2]) + (F[:, 1] > F[:, 2])
    return inv % 2


def unique_rows(a: np.ndarray):
    """``np.unique(a, axis=0, return_index=True, return_inverse=True)`` for an (n, k) integer
    array, by one lexicographic sort (numpy's costs four times as much on a small body's
    handful of rows): the distinct rows in lexicographic order, the first index of each, and
    each row's position among them."""
    a = np.asarray(a)
    if not len(a):
        return a.copy(), np.zeros(0, np.int64), np.zeros(0, np.int64)
    order = np.lexsort(a.T[::-1])
    s = a[order]
    new = np.empty(len(a), dtype=bool)
    new[0] = True
    np.any(s[1:] != s[:-1], axis=1, out=new[1:])
    inverse = np.empty(len(a), dtype=np.int64)
    inverse[order] = np.cumsum(new) - 1
    return s[new], order[new], inverse


def weld_dedupe(body, grid: Grid):
    """Welded grid ints, deduplicated faces, the counts of steps 1-2, per kept face whether it
    was also listed with the opposite winding (double-sided), and every input triangle welded
    (collapsed and repeated ones included, in input order: what :func:`snapping_losses`
    reads)."""
    ints, _, inverse = unique_rows(grid.snap(body.vertices))
    F = welded = inverse[body.faces]
    collapsed = _collapsed(F)
    F = F[~collapsed]
    _, first, which = unique_rows(np.sort(F, axis=1))
    keep = np.zeros(len(F), dtype=bool)
    keep[first] = True
    same = _parity(F) == _parity(F[first[which]])
    counts = {"triangles": len(body.faces), "collapsed": int(collapsed.sum()),
              "double_sided": int((~keep & ~same).sum()), "repeated": int((~keep & same).sum())}
    # Per kept triangle: listed with both windings too (the two sides of a sheet).
    reversed_copy = np.zeros(len(first), dtype=bool)
    reversed_copy[which[~same]] = True
    order = np.sort(first)
    return ints, F[order], counts, reversed_copy[which[order]], welded


def cancel_opposite_faces(F: np.ndarray) -> np.ndarray | None:
    """Welded triangles as a 2-chain: a triangle listed once with each winding cancels.

    Where two closed bodies given as one mesh share a face, each lists it facing out of
    itself, so the two copies have opposite windings; the face is interior to their union
    and the chain without both is the union's boundary. Returns the triangles left, each
    once, in input order (collapsed ones dropped: snapping's thin features are handled
    apart); None when a triangle's copies do not cancel to at most one (a face repeated with
    one winding: validation names it) or nothing cancels.
    """
    F = np.asarray(F, dtype=np.int64)
    F = F[~_collapsed(F)]
    if not len(F):
        return None
    _, first, which = unique_rows(np.sort(F, axis=1))
    sign = np.where(_parity(F) == _parity(F[first[which]]), 1, -1)
    net = np.zeros(len(first), dtype=np.int64)
    np.add.at(net, which, sign)
    if np.abs(net).max() > 1 or len(first) == len(F):
        return None
    # the copy with the surviving winding, the first one listed
    keep = np.zeros(len(F), dtype=bool)
    cand = np.nonzero(sign == net[which])[0]
    _, at = np.unique(which[cand], return_index=True)
    keep[cand[at]] = True
    return F[keep]


def _collapsed(F: np.ndarray) -> np.ndarray:
    """Rows of welded triangles with a repeated corner (a segment or a point)."""
    return (F[:, 0] == F[:, 1]) | (F[:, 1] == F[:, 2]) | (F[:, 0] == F[:, 2])


def snapping_losses(n: int, welded: np.ndarray, F: np.ndarray):
    """What welding on the grid took from a body, so that a model can keep it: ``(thin,
    chain)``.

    Parameters
    ----------
    n : int
        Number of welded vertices.
    welded : (m, 3) int64
        Every input triangle welded (:func:`weld_dedupe`'s last value).
    F : (k, 3) int64
        The triangles kept (deduplicated, none collapsed).

    Returns
    -------
    thin : (p, 3) int64
        Features thinner than the grid step: each triangle that collapsed to a segment
        ``(a, b, b)`` or a point ``(a, a, a)``, once, unless a kept triangle holds it (the
        segment is one of its edges, the point one of its corners or of a kept segment's
        ends). A segment or a point is still an obstacle: its sum with ``-R`` is a convex
        piece like any triangle's, never nothing.
    chain : (q, 3) int64 or None
        The welded triangles that did not collapse, each as often as the input lists it,
        when they form a closed 2-cycle (every directed edge balanced by its reverse), else
        None. Snapping is a simplicial map, so the input's cycle stays one (a collapsed
        triangle's boundary cancels), and its winding number off the surface is the input's:
        the region a closed body encloses, even where de-duplication (the two faces of a plate
        thinner than the step, snapped onto one another) or splitting at non-manifold edges
        leaves parts that enclose nothing on their own.
    """
    from .query import unbalanced_edge

    welded = np.asarray(welded, dtype=np.int64).reshape(-1, 3)
    F = np.asarray(F, dtype=np.int64).reshape(-1, 3)
    gone = _collapsed(welded)
    whole = welded[~gone]
    chain = whole if len(whole) and unbalanced_edge(whole, n) is None else None
    if not gone.any():
        return np.zeros((0, 3), dtype=np.int64), chain
    ends = np.sort(welded[gone], axis=1)
    a, b = ends[:, 0], ends[:, 2]
    n64 = np.int64(n)
    edges = np.sort(np.concatenate([F[:, [0, 1]], F[:, [1, 2]], F[:, [2, 0]]]), axis=1)
    seg = a != b
    key = np.unique(a[seg] * n64 + b[seg])
    key = key[~np.isin(key, edges[:, 0] * n64 + edges[:, 1])]
    sa, sb = key // n64, key % n64
    pts = np.unique(a[~seg])
    pts = pts[~np.isin(pts, np.concatenate([F.reshape(-1), sa, sb]))]
    thin = np.concatenate([np.stack([sa, sb, sb], axis=1), np.stack([pts, pts, pts], axis=1)])
    return thin.astype(np.int64), chain


def weld_split(body, grid: Grid):
    """:func:`weld_dedupe` then :func:`split_parts`: ``(ints, F, counts, two_sided, parts,
    welded)``.

    A body whose snapped vertices are distinct and all used, and whose triangles one compiled
    call proves an exactly convex closed mesh (most bodies of a scene: boxes, hulls) is one
    part with nothing collapsed, repeated or listed twice: what the two steps give it, without
    their sorting and labelling."""
    snapped = grid.snap(body.vertices)
    faces = np.asarray(body.faces, dtype=np.int64)
    ints, _, inverse = unique_rows(snapped)
    if len(ints) == len(snapped) and len(faces) and np.bincount(
            faces.reshape(-1), minlength=len(snapped)).all():
        F = inverse[faces]
        if load("convex").polytope_of_mesh(ints, np.ascontiguousarray(F)) is not None:
            counts = {"triangles": len(faces), "collapsed": 0, "double_sided": 0, "repeated": 0}
            return ints, F, counts, np.zeros(len(F), dtype=bool), [np.arange(len(F))], F
    ints, F, counts, two_sided, welded = weld_dedupe(body, grid)
    return (ints, F, counts, two_sided, split_parts(ints, F, two_sided) if len(F) else [],
            welded)


def edge_uses(F: np.ndarray, n: int):
    """Undirected edge key of each half-edge ``3 * face + corner``, and its use count."""
    a, b = F.reshape(-1), F[:, [1, 2, 0]].reshape(-1)
    key = np.minimum(a, b) * n + np.maximum(a, b)
    _, inv, count = np.unique(key, return_inverse=True, return_counts=True)
    return inv.reshape(-1), count


def radial_pairs(ints: np.ndarray, F: np.ndarray, edge: np.ndarray,
                 count: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Faces ``(a, b)`` that bound one wedge of solid at a non-manifold edge, decided exactly.

    Around an edge ``u -> v`` (axis ``d = v - u``), a face using it as ``u -> v`` has its
    outward normal ``d x r`` (``r`` towards its third corner) turned ahead of it, so the solid
    lies just behind it (it *closes* a wedge); a face using ``v -> u`` *opens* one. With the
    faces in angular order about ``d`` (exact integer signs on the grid coordinates ``ints``;
    at one angle, closing faces first: coplanar faces of two bodies that touch bound nothing
    between them), each opening face pairs with the next face, which must close. An edge whose
    faces do not alternate so (solids overlapping, a face repeated) or has a face with no area
    is left unpaired, as before. Every pair is one wedge: the faces of one closed body
    through that edge.

    Parameters
    ----------
    ints : (n, 3) int64
    F : (m, 3) int64
    edge, count : from :func:`edge_uses`.

    Returns
    -------
    a, b : (k,) int64
        Face indices.
    """
    from functools import cmp_to_key

    half = np.nonzero(count[edge] > 2)[0]
    if not len(half):
        return np.zeros(0, np.int64), np.zeros(0, np.int64)
    half = half[np.argsort(edge[half], kind="stable")]
    cuts = np.nonzero(np.diff(edge[half]))[0] + 1
    P = ints.tolist()
    out_a, out_b = [], []

    def sub(x, y):
        return (x[0] - y[0], x[1] - y[1], x[2] - y[2])

    def dot(x, y):
        return x[0] * y[0] + x[1] * y[1] + x[2] * y[2]

    def triple(d, x, y):  # d . (x × y)
        return (d[0] * (x[1] * y[2] - x[2] * y[1]) + d[1] * (x[2] * y[0] - x[0] * y[2])
                + d[2] * (x[0] * y[1] - x[1] * y[0]))

    for group in np.split(half, cuts):
        f, c = (group // 3).tolist(), (group % 3).tolist()
        u0, v0 = int(F[f[0], c[0]]), int(F[f[0], (c[0] + 1) % 3])
        d = sub(P[v0], P[u0])
        dd = dot(d, d)
        rows = []
        for fi, ci in zip(f, c):
            r = sub(P[int(F[fi, (ci + 2) % 3])], P[u0])
            if dot(r, r) * dd == dot(r, d) ** 2:  # no area: no angle
                rows = None
                break
            rows.append((fi, int(F[fi, ci]) == u0, r))  # (face, closes, direction)
        if rows is None or 2 * sum(closes for _, closes, _ in rows) != len(rows):
            continue
        r0 = rows[0][2]

        def side(r, r0=r0, d=d, dd=dd):  # 0: angle in [0, pi) from r0, 1: [pi, 2 pi)
            t = triple(d, r0, r)
            return 0 if t > 0 or (t == 0 and dot(r0, r) * dd - dot(r0, d) * dot(r, d) > 0) else 1

        def cmp(x, y, d=d):
            sx, sy = side(x[2]), side(y[2])
            if sx != sy:
                return sx - sy
            t = triple(d, x[2], y[2])
            if t:
                return -1 if t > 0 else 1
            return (not x[1]) - (not y[1])  # one angle: closing faces first

        ring = sorted(rows, key=cmp_to_key(cmp))
        k0 = next(k for k, row in enumerate(ring) if not row[1])
        ring = ring[k0:] + ring[:k0]
        if all(not ring[k][1] and ring[k + 1][1] for k in range(0, len(ring), 2)):
            out_a += [ring[k][0] for k in range(0, len(ring), 2)]
            out_b += [ring[k + 1][0] for k in range(0, len(ring), 2)]
    return np.array(out_a, dtype=np.int64), np.array(out_b, dtype=np.int64)


def split_parts(ints: np.ndarray, F: np.ndarray, two_sided=None) -> list[np.ndarray]:
    """Face index arrays of the bodies of step 3, in order of their first face.

    ``two_sided`` (per face, from :func:`weld_dedupe`): a closed component all of whose faces
    were listed with both windings is a sheet (it encloses nothing), so nothing nests in it."""
    m = len(F)
    edge, count = edge_uses(F, len(ints))
    face = np.repeat(np.arange(m), 3)
    # Faces sharing a manifold edge (two faces): link each half-edge's face to the first face
    # using that edge. A non-manifold edge (two boxes sharing an edge) links nothing, so such
    # a mesh falls apart into its manifold pieces, each a solid when closed.
    first = np.full(len(count), m, dtype=np.int64)
    np.minimum.at(first, edge, face)
    link = count[edge] == 2
    # At a non-manifold edge, faces that bound one wedge of solid are linked too (two closed
    # boxes welded along a face each side triangulates differently stay two closed boxes).
    pa, pb = radial_pairs(ints, F, edge, count)
    ncomp, label = component_labels(m, np.concatenate([face[link], pa]),
                                    np.concatenate([first[edge][link], pb]))
    if ncomp == 1:  # one body (most are): nothing to nest
        return [np.arange(m)]
    boundary = np.zeros(ncomp, dtype=bool)
    np.logical_or.at(boundary, label[face], count[edge] == 1)
    # Closed components nested in another closed one's solid stay with it (a cavity).
    closed = np.nonzero(~boundary)[0]
    outer = closed
    if two_sided is not None:
        sheet = np.ones(ncomp, dtype=bool)
        np.logical_and.at(sheet, label, np.asarray(two_sided, dtype=bool))
        outer = closed[~sheet[closed]]
    i, j = nested_pairs(ints, F, label, outer, closed)
    _, group = component_labels(ncomp, i, j)
    group = group[label]
    firsts = np.full(group.max() + 1, m)
    np.minimum.at(firsts, group, np.arange(m))
    return [np.nonzero(group == g)[0] for g in np.argsort(firsts) if firsts[g] < m]


def split_mesh(vertices, faces, grid: Grid) -> list[tuple[np.ndarray, np.ndarray]]:
    """A mesh welded and split on ``grid`` as scenes split a body (:func:`weld_dedupe`,
    :func:`split_parts`): one ``(float64 vertices on the grid, faces)`` per part. Closed
    pieces meeting at non-manifold edges or vertices (two boxes sharing an edge) fall apart
    here; :meth:`cspace.CSpaceObstacle.build` and :func:`cspace.minkowski_sum` answer such a
    mesh as the union of its parts."""
    from types import SimpleNamespace

    ints, F, _, _, _ = weld_dedupe(SimpleNamespace(vertices=vertices, faces=faces), grid)
    out = []
    for part in split_parts(ints, F) if len(F) else []:
        used, local = np.unique(F[part], return_inverse=True)
        out.append((grid.to_float(ints[used]), local.reshape(-1, 3)))
    return out


def nested_pairs(ints: np.ndarray, F: np.ndarray, label: np.ndarray, outer, inner):
    """Which closed components lie inside which others' solids, decided exactly: the one
    definition of nesting, for scenes (:func:`split_parts`: a cavity stays with its solid)
    and for :class:`cspace.mesh.closed.ClosedMesh` (an inward shell is a cavity only inside an
    outward one's solid).

    Parameters
    ----------
    ints : (n, 3) int64
        Grid coordinates.
    F : (m, 3) int64
        Triangles.
    label : (m,) int64
        Component of each triangle.
    outer, inner : array of int
        Labels of the candidate enclosing components and of the candidate enclosed ones.

    Returns
    -------
    a, b : (k,) int64
        Pairs of labels ``a`` in ``outer``, ``b`` in ``inner``, ``a != b``, such that ``b``'s
        box lies in ``a``'s and a vertex of ``b`` in ``a``'s solid (winding number from a
        symbolically perturbed ray, boundary included: :class:`cspace.mesh.query.MeshCO`).
        Closed shells that do not cross lie wholly inside or outside each other, so one
        vertex decides. An ``a`` that is not an oriented 2-cycle keeps the boxes' verdict.
    """
    outer = np.asarray(outer, dtype=np.int64)
    inner = np.asarray(inner, dtype=np.int64)
    ncomp = int(label.max()) + 1 if len(label) else 0
    lo = np.full((ncomp, 3), np.iinfo(np.int64).max)
    hi = np.full((ncomp, 3), np.iinfo(np.int64).min)
    corners = ints[F]  # (m, 3, 3)
    np.minimum.at(lo, label, corners.min(axis=1))
    np.maximum.at(hi, label, corners.max(axis=1))
    fits = ((lo[outer, None] <= lo[None, inner]) & (hi[None, inner] <= hi[outer, None])).all(2)
    fits &= outer[:, None] != inner[None, :]
    i, j = np.nonzero(fits)
    a, b = outer[i], inner[j]
    keep = np.ones(len(a), dtype=bool)
    for c in np.unique(a).tolist():
        rows = np.nonzero(a == c)[0]
        try:
            from .query import MeshCO

            solid = MeshCO(ints.astype(np.float64), F[label == c], name="part")
        except InvalidMeshError:  # not an oriented 2-cycle: keep the boxes' verdict
            continue
        probes = np.array([ints[F[label == d][0, 0]] for d in b[rows].tolist()])
        keep[rows] = solid.contains(probes.astype(np.float64))
    return a[keep], b[keep]
