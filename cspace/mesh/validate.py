"""Face-level validation of a welded triangle mesh: closed, manifold, oriented, non-degenerate.

The checks :meth:`cspace.mesh.closed.ClosedMesh.from_arrays` runs after welding: every edge used
exactly twice with opposite directions (:func:`_validate_faces`), connected components
(:func:`_components`), orientation propagated across edges and checked outward by exact volume
(:func:`_propagate_flips`, :func:`_volume6`), non-manifold vertices (:func:`_fans`). Errors name
the face or edge and why.
"""

from __future__ import annotations

import numpy as np

from ..errors import DegenerateError, DuplicateFaceError, NonManifoldError, OpenMeshError
from ..geometry.graphs import bfs_predecessors, component_labels


_MASK32 = np.int64(0xFFFFFFFF)


# -- validation ------------------------------------------------------------------------------------


def _fmt(values) -> str:
    """``(a, b, c)`` from an array or sequence of numbers."""
    return "(" + ", ".join(repr(x) for x in np.asarray(values).tolist()) + ")"


def _count(k: int, what: str) -> str:
    """``'; 4 <what>'`` when there is more than one offender, else ``''``."""
    return f"; {k} {what}" if k > 1 else ""


def _validate_faces(ints, F, rep, grid, name):
    """Steps 6-10 of :func:`cspace.mesh.closed._validate` on welded faces without zero area."""

    def fail(error, message):
        return error(f"mesh {name!r}: {message}")

    k = len(ints)
    m = len(F)

    # 6. Duplicate faces: the same sorted vertex triple.
    S = np.sort(F, axis=1)
    order = np.lexsort((S[:, 2], S[:, 1], S[:, 0]))  # stable: equal triples by face index
    repeat = (S[order[1:]] == S[order[:-1]]).all(axis=1)
    if repeat.any():
        later = order[1:][repeat]
        j = int(np.argmin(later))
        a, b = int(order[:-1][repeat][j]), int(later[j])
        # Winding parity: the number of inversions of the triple, mod 2.
        inversions = (F[:, 0] > F[:, 1]).astype(np.int8) + (F[:, 0] > F[:, 2]) + (F[:, 1] > F[:, 2])
        opposite = inversions[a] % 2 != inversions[b] % 2
        raise fail(
            DuplicateFaceError,
            f"faces {a} and {b} use the same vertices {_fmt(np.sort(rep[F[a]]))}"
            + (
                " (double-sided surface: drop one copy of each)"
                if opposite
                else " (the same winding: a repeated face, drop the copy)"
            )
            + _count(len(later), "faces repeat an earlier face"),
        )

    # 7. Edges: half-edge h = 3 * face + corner runs from tail[h] to head[h].
    tail = F.reshape(-1)
    head = F[:, [1, 2, 0]].reshape(-1)
    key = np.minimum(tail, head) * k + np.maximum(tail, head)
    order = np.argsort(key, kind="stable")
    sorted_key = key[order]
    starts = np.flatnonzero(np.r_[True, sorted_key[1:] != sorted_key[:-1]])
    counts = np.diff(np.r_[starts, len(sorted_key)])
    lone = counts == 1
    if lone.any():
        h = int(order[starts[lone]].min())
        raise fail(
            OpenMeshError,
            f"{int(lone.sum())} boundary edges (open mesh), first between vertices "
            f"({rep[tail[h]]}, {rep[head[h]]}) of face {h // 3}",
        )
    crowded = counts > 2
    if crowded.any():
        g = np.flatnonzero(crowded)[np.argmin(order[starts[crowded]])]
        hs = np.sort(order[starts[g] : starts[g] + counts[g]])
        h = int(hs[0])
        users = ", ".join(str(x) for x in hs // 3)
        raise fail(
            NonManifoldError,
            f"{int(crowded.sum())} edges shared by more than 2 faces, first between vertices "
            f"{_fmt(np.sort(rep[[tail[h], head[h]]]))} (faces {users})",
        )
    # Every edge has exactly two half-edges: pair them.
    h0, h1 = order[0::2], order[1::2]
    fa, fb = h0 // 3, h1 // 3
    same_way = tail[h0] == tail[h1]  # both run u -> v: exactly one of the faces must flip

    # 8. Consistent orientation per component.
    components, roots = _components(fa, fb, m)
    flip = _propagate_flips(fa, fb, same_way, roots, m)
    wrong = (flip[fa] != flip[fb]) != same_way
    if wrong.any():
        e = int(np.argmin(np.where(wrong, h0, 3 * m)))
        h = int(h0[e])
        raise fail(
            NonManifoldError,
            f"the surface through face {int(roots[components[h // 3]])} is not orientable: "
            f"faces {int(fa[e])} and {int(fb[e])} cannot be wound consistently across the edge "
            f"between vertices ({rep[tail[h]]}, {rep[head[h]]})",
        )
    ncomp = len(roots)
    size = np.bincount(components, minlength=ncomp)
    flipped = np.bincount(components, weights=flip, minlength=ncomp)
    flip ^= (2 * flipped > size)[components]  # keep the orientation flipping fewer faces

    # 9. Manifold vertices: one fan of faces around each vertex.
    fans = _fans(tail, h0, h1, same_way, k)
    pinched = fans > 1
    if pinched.any():
        rows = np.nonzero(pinched)[0]
        w = int(rows[np.argmin(rep[rows])])
        raise fail(
            NonManifoldError,
            f"vertex {int(rep[w])} is non-manifold: its faces form {int(fans[w])} separate fans"
            + _count(len(rows), "vertices are non-manifold"),
        )

    # 10. Outward orientation from the exact signed volume of each component.
    F = np.where(flip[:, None], F[:, [0, 2, 1]], F)
    volumes = _volume6(ints, F, components, ncomp)
    zero = [c for c, vol in enumerate(volumes) if vol == 0]
    if zero:
        raise fail(
            DegenerateError,
            f"the closed surface through face {int(roots[zero[0]])} encloses zero volume "
            f"({int(size[zero[0]])} faces)" + _count(len(zero), "components have zero volume"),
        )
    # The component holding the lexicographically greatest vertex is enclosed by no other
    # (shells do not cross, and touching at that vertex would make it non-manifold): it must
    # be an outer shell. When it is not, the whole mesh is inside out.
    top = np.lexsort((ints[:, 2], ints[:, 1], ints[:, 0]))[-1]
    outer = components[np.argmax((F == top).any(axis=1))]
    if volumes[outer] < 0:
        F = F[:, [0, 2, 1]]
        volumes = [-vol for vol in volumes]
    cavities = np.array([c for c, vol in enumerate(volumes) if vol < 0], dtype=np.int64)
    if len(cavities):
        # A cavity is an inward shell inside an outward shell's solid, decided exactly as
        # scenes decide it (cspace.mesh.components.nested_pairs). One inside none bounds nothing
        # (its inside would be unbounded): a separate body wound inside out, turned outwards
        # as a scene turns it.
        from .components import nested_pairs

        shells = np.setdiff1d(np.arange(ncomp), cavities)
        _, held = nested_pairs(ints, F, components, shells, cavities)
        stray = np.setdiff1d(cavities, held)
        if len(stray):
            turn = np.isin(components, stray)
            F[turn] = F[turn][:, [0, 2, 1]]
    return ints, F, grid, components


def _components(fa: np.ndarray, fb: np.ndarray, m: int):
    """Connected components of faces linked through edges.

    Returns
    -------
    labels : (m,) int64
        Component of each face, numbered in order of first face.
    roots : (c,) int64
        First (smallest) face of each component.
    """
    _, labels = component_labels(m, fa, fb)
    _, first = np.unique(labels, return_index=True)
    by_first = np.argsort(first)
    relabel = np.zeros(len(first), dtype=np.int64)
    relabel[by_first] = np.arange(len(first), dtype=np.int64)
    return relabel[labels], first[by_first].astype(np.int64)


def _propagate_flips(fa, fb, same_way, roots, m) -> np.ndarray:
    """Flip flags that make windings agree along a breadth-first spanning forest.

    A virtual node ``m`` is linked to every component's root, so one breadth-first search
    spans all components. The flip of a face is the parity of ``same_way`` along its tree
    path to the root, computed by pointer jumping (``O(m log depth)``, vectorised). Edges off
    the tree are not checked here.

    Returns
    -------
    flip : (m,) bool
    """
    rows = np.r_[fa, np.full(len(roots), m, dtype=np.int64)]
    cols = np.r_[fb, roots]
    pred = bfs_predecessors(m + 1, rows, cols, m)
    parent = pred[:m].astype(np.int64)
    is_root = parent == m
    # Parity of the tree edge (face, parent): look the face pair up among the edges.
    lo, hi = np.minimum(fa, fb), np.maximum(fa, fb)
    edge_key = lo * m + hi
    by_key = np.argsort(edge_key)
    child = np.flatnonzero(~is_root)
    tree_key = np.minimum(child, parent[child]) * m + np.maximum(child, parent[child])
    found = by_key[np.searchsorted(edge_key[by_key], tree_key)]
    parity = np.zeros(m, dtype=bool)
    parity[child] = same_way[found]
    ancestor = parent.copy()
    ancestor[is_root] = np.flatnonzero(is_root)
    while True:
        nxt = ancestor[ancestor]
        if np.array_equal(nxt, ancestor):
            return parity
        parity = parity ^ parity[ancestor]
        ancestor = nxt


def _fans(tail, h0, h1, same_way, k) -> np.ndarray:
    """Number of fans of faces around each vertex.

    The corners of the faces (corner ``h = 3 * face + i`` sits at vertex ``tail[h]``) are
    linked when their faces share an edge at that vertex; the fans at a vertex are the
    connected components of its corners.

    Returns
    -------
    fans : (k,) int64
    """

    def nxt(h):
        return h - h % 3 + (h % 3 + 1) % 3

    # Half-edge h0 runs tail[h0] -> head[h0]; its corners there are h0 and nxt(h0). The twin
    # h1 has its corner at tail[h0] at h1 if it runs the same way, else at nxt(h1).
    at_tail = np.where(same_way, h1, nxt(h1))
    at_head = np.where(same_way, nxt(h1), h1)
    rows = np.r_[h0, nxt(h0)]
    cols = np.r_[at_tail, at_head]
    n = len(tail)
    count, labels = component_labels(n, rows, cols)
    vertex_of = np.zeros(count, dtype=np.int64)
    vertex_of[labels] = tail
    return np.bincount(vertex_of, minlength=k)


def _volume6(ints, faces, labels=None, count: int = 1) -> list[int]:
    """Exact ``sum det[v0, v1, v2]`` over the faces of each label, as Python ints.

    Vectorised in int64 without overflow for ``|ints| <= 2**28`` (any :class:`Grid`) and
    fewer than ``2**31`` faces: the cross product ``v1 x v2`` (below ``2**58``) is split into
    32-bit halves, each partial dot product (below ``2**62``) again, and the halves are
    summed separately, then recombined with Python ints.

    Parameters
    ----------
    ints : (n, 3) int64
        Grid coordinates.
    faces : (m, 3) int64
    labels : (m,) int64, optional
        Group of each face; default all in group 0.
    count : int
        Number of groups.

    Returns
    -------
    volume6 : list of int
        Six times the signed volume of each group, in grid units cubed.
    """
    v0, v1, v2 = ints[faces[:, 0]], ints[faces[:, 1]], ints[faces[:, 2]]
    c = np.cross(v1, v2)
    d_hi = (v0 * (c >> 32)).sum(axis=1)  # weight 2**32
    d_lo = (v0 * (c & _MASK32)).sum(axis=1)  # weight 1
    parts = (d_hi >> 32, (d_hi & _MASK32) + (d_lo >> 32), d_lo & _MASK32)  # 2**64, 2**32, 1
    if labels is None:
        sums = [[int(p.sum())] for p in parts]
    else:
        sums = []
        for p in parts:
            s = np.zeros(count, dtype=np.int64)
            np.add.at(s, labels, p)
            sums.append(s.tolist())
    return [(a << 64) + (b << 32) + c for a, b, c in zip(*sums)]
