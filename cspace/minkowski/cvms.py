"""CVMS: the exact Minkowski sum of two convex polytopes (:func:`convex_minkowski_sum`).

It follows the convex paper (Barki, Denis, Dupont, FIMS/CVMS): the facets of A ⊕ B are the
*translated* facets (a facet of A moved by its contributing vertex of B), the *corner* facets
(a facet of B placed at its contributing vertex of A) and the *edge* facets (parallelograms of
an edge of A and an edge of B whose Gauss arcs cross) (:data:`FACET_KINDS`). Every decision
(which vertex of B supports a facet of A, whether two Gauss arcs cross) is exact on the grid
integers. Degenerate directions (a facet of A parallel to a facet or an edge of B, ...) are not
assumed away: for each distinct outward normal ``n`` of the sum, its facet is the planar sum of
the support faces ``A(n) ⊕ B(n)``, computed exactly, so a square facet stays one square facet;
each output facet keeps its provenance. :func:`hull_minkowski_sum` is the reference (the exact
hull of all vertex sums).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..geometry import exact
from ..geometry._kernels import load
from ..geometry.exact import Grid
from ..mesh.convex import ConvexPolytope, _facet_polygon

__all__ = ["MinkowskiSum", "convex_minkowski_sum", "hull_minkowski_sum", "FACET_KINDS"]


#: Names of the facet kinds of a Minkowski sum, indexed by ``MinkowskiSum.kind``.
FACET_KINDS = ("translated", "corner", "edge")


TRANSLATED, CORNER, EDGE = 0, 1, 2

_compiled = load("convex")


# --------------------------------------------------------------------------------------
# Minkowski sums


@dataclass(frozen=True, eq=False)
class MinkowskiSum:
    """Result of a convex ⊕ convex Minkowski sum, with provenance.

    Attributes
    ----------
    polytope : ConvexPolytope
        The sum, with polygon facets (degrees preserved) and exact grid vertices.
    labels : (n, 2) int64
        For each vertex of the sum, the vertex of A and the vertex of B it is the sum of.
    kind : (f,) int8
        Facet kind, an index into :data:`FACET_KINDS` (translated, corner, edge).
    source_a, source_b : (f, 2) int64
        The feature of A (resp. B) a facet comes from, as ``(dimension, index)``: dimension
        0 is a vertex index, 1 an edge index (into ``A.edges``), 2 a facet index.
    """

    polytope: ConvexPolytope
    labels: np.ndarray
    kind: np.ndarray
    source_a: np.ndarray
    source_b: np.ndarray

    @property
    def grid(self) -> Grid:
        return self.polytope.grid

    @property
    def vertices(self) -> np.ndarray:
        """(n, 3) float64 vertices in scene units."""
        return self.polytope.vertices

    @property
    def faces(self) -> np.ndarray:
        """(m, 3) int64 triangles (fan triangulation of the polygon facets)."""
        return self.polytope.faces

    def to_trimesh(self):
        """The sum as a ``trimesh.Trimesh`` (float64, not re-processed)."""
        return self.polytope.to_trimesh()

    def __repr__(self) -> str:
        kinds = ", ".join(f"{int((self.kind == k).sum())} {n}" for k, n in enumerate(FACET_KINDS))
        return (f"MinkowskiSum(vertices={len(self.labels)}, facets={len(self.kind)} ({kinds}), "
                f"volume={self.volume:.6g})")

    @property
    def facets(self) -> list[np.ndarray]:
        return self.polytope.facets

    @property
    def volume(self) -> float:
        return self.polytope.volume

    @property
    def error_bound(self) -> float:
        """Largest distance between an input vertex and its snapped grid position.

        The sum of the snapped operands is exact; it differs from the sum of the unsnapped
        operands by at most twice this bound (Hausdorff distance).
        """
        return self.grid.point_error_bound


def _common_grid(A, B) -> tuple[ConvexPolytope, ConvexPolytope]:
    A = A if isinstance(A, ConvexPolytope) else ConvexPolytope.from_points(A, name="A")
    B = B if isinstance(B, ConvexPolytope) else ConvexPolytope.from_points(B, name="B")
    return on_one_step(A, B)


def on_one_step(A, B):
    """Two snapped operands (polytopes or meshes) on grids of one step: as they are when
    their steps agree (integers combine exactly; the sum is in frame ``A.grid.plus(B.grid)``),
    else both re-snapped onto ``Grid.for_operands``, which hold both and their sums."""
    if A.grid.same_step(B.grid):
        return A, B
    ga, gb = Grid.for_operands(A.vertices, B.vertices, bits=min(A.grid.bits, B.grid.bits))
    return A.on_grid(ga), B.on_grid(gb)


def _feature(P: ConvexPolytope, support: np.ndarray) -> tuple[int, int]:
    """(dimension, index) of the face of P spanned by the vertex set ``support`` (a bool mask)."""
    idx = np.nonzero(support)[0]
    if len(idx) == 1:
        return 0, int(idx[0])
    if len(idx) == 2:
        lo, hi = int(idx.min()), int(idx.max())
        e = P._cache.get("edge_index")
        if e is None:
            e = {(int(min(a, b)), int(max(a, b))): i for i, (a, b) in enumerate(P.edges.tolist())}
            P._cache["edge_index"] = e
        return 1, e[(lo, hi)]
    # Three or more support vertices span a facet: find it by its vertex set.
    f = P._cache.get("facet_index")
    if f is None:
        f = {frozenset(fa.tolist()): i for i, fa in enumerate(P.facets)}
        P._cache["facet_index"] = f
    return 2, f[frozenset(idx.tolist())]


def convex_minkowski_sum(A, B) -> MinkowskiSum:
    """Exact Minkowski sum of two convex polytopes (CVMS), facet degrees preserved.

    Parameters
    ----------
    A, B : ConvexPolytope or (n, 3) float64 points
        Operands; points are hulled first. Both are put on one grid.

    Returns
    -------
    MinkowskiSum
        Polygon facets with their kind and provenance, exact grid vertices labelled by the
        pair of vertices they are the sum of.

    Notes
    -----
    Cost: the support of every facet normal of A among B's vertices and vice versa
    (``O(f_A v_B + f_B v_A)``), and the Gauss-arc crossing test on the pairs of edges whose
    two facets have different contributing vertices. The work is one call of the compiled
    kernel (:mod:`cspace.geometry._kernels.convex`), every decision exact in ``__int128``
    (no filter needed); :func:`_convex_minkowski_sum_reference` is the same steps in numpy
    (float filters with exact fallbacks, :mod:`cspace.geometry.exact`), identical output
    (``tests/test_kernels.py``), and runs where the kernel's range does not hold.
    """
    A, B = _common_grid(A, B)
    out = _compiled.facets(*_arrays(A), *_arrays(B))
    if out is None:  # outside the kernel's range, or facets that do not close up
        return _convex_minkowski_sum_reference(A, B)
    labels, offsets, flat, normals, source_a, source_b, edges, edge_facets = out
    poly = ConvexPolytope(grid=A.grid.plus(B.grid), ints=A.ints[labels[:, 0]] + B.ints[labels[:, 1]],
                          facet_offsets=offsets, facet_indices=flat, normals=normals,
                          edges=edges, edge_facets=edge_facets, name=f"{A.name}+{B.name}")
    return _with_kinds(poly, labels, source_a, source_b)


def _arrays(P: ConvexPolytope) -> tuple:
    """The polytope's arrays as the kernel takes them (C-contiguous int64)."""
    c = np.ascontiguousarray
    return (c(P.ints, np.int64), c(P.facet_offsets, np.int64), c(P.facet_indices, np.int64),
            c(P.normals, np.int64), c(P.edges, np.int64), c(P.edge_facets, np.int64))


def _with_kinds(poly: ConvexPolytope, labels, source_a, source_b) -> MinkowskiSum:
    """The sum with each facet's kind, from its provenance: a facet of A is translated, a
    facet of B a corner, the rest edge facets."""
    kind = np.where(source_a[:, 0] == 2, TRANSLATED,
                    np.where(source_b[:, 0] == 2, CORNER, EDGE)).astype(np.int8)
    return MinkowskiSum(polytope=poly, labels=labels, kind=kind, source_a=source_a,
                        source_b=source_b)


def _convex_minkowski_sum_reference(A, B) -> MinkowskiSum:
    """:func:`convex_minkowski_sum` in numpy, step for step what the compiled kernel does
    (operands on one grid already)."""
    nA, nB = A.normals, B.normals
    SB = exact.support_mask(B.ints, nA)  # (fA, vB): contributing vertices of A's facets
    SA = exact.support_mask(A.ints, nB)  # (fB, vA): contributing vertices of B's facets
    single_b = SB.sum(axis=1) == 1
    single_a = SA.sum(axis=1) == 1
    b_of = SB.argmax(axis=1)  # the contributing vertex where it is unique
    a_of = SA.argmax(axis=1)

    # Facet normals shared by A and B (parallel facets) make one planar-sum facet.
    cand = np.concatenate([nA, nB])
    key, inv = np.unique(cand, axis=0, return_inverse=True)
    inv = inv.reshape(-1)
    owner_a = np.full(len(key), -1, dtype=np.int64)
    owner_b = np.full(len(key), -1, dtype=np.int64)
    owner_a[inv[: len(nA)]] = np.arange(len(nA))
    owner_b[inv[len(nA) :]] = np.arange(len(nB))
    shared = (owner_a >= 0) & (owner_b >= 0)
    a_alone = owner_a[(owner_a >= 0) & ~shared]
    b_alone = owner_b[(owner_b >= 0) & ~shared]

    groups = []  # (flat A labels, flat B labels, sizes, normals, source_a, source_b)

    # Translated facets: a facet of A moved by its unique contributing vertex of B.
    fa = a_alone[single_b[a_alone]]
    la, sz = _gather(A.facet_offsets, A.facet_indices, fa)
    groups.append((la, np.repeat(b_of[fa], sz), sz, nA[fa], _src(2, fa), _src(0, b_of[fa])))
    # Corner facets: a facet of B placed at its unique contributing vertex of A.
    fb = b_alone[single_a[b_alone]]
    lb, sz = _gather(B.facet_offsets, B.facet_indices, fb)
    groups.append((np.repeat(a_of[fb], sz), lb, sz, nB[fb], _src(0, a_of[fb]), _src(2, fb)))

    # Planar sums: a facet of one operand parallel to a facet or an edge of the other. Rare
    # (degenerate directions), so a loop over them is fine.
    planar = np.concatenate([
        np.nonzero(shared)[0],
        inv[a_alone[~single_b[a_alone]]],
        inv[len(nA) + b_alone[~single_a[b_alone]]],
    ])
    A_facets, B_facets = A.facets, B.facets
    rings_a, rings_b, src_a, src_b = [], [], [], []
    for k in planar:
        fa_k, fb_k = owner_a[k], owner_b[k]
        supp_a = SA[fb_k] if fb_k >= 0 else np.isin(np.arange(len(A.ints)), A_facets[fa_k])
        supp_b = SB[fa_k] if fa_k >= 0 else np.isin(np.arange(len(B.ints)), B_facets[fb_k])
        ia_, ib_ = np.nonzero(supp_a)[0], np.nonzero(supp_b)[0]
        pa, pb = np.repeat(ia_, len(ib_)), np.tile(ib_, len(ia_))
        ring = _facet_polygon(A.ints[pa] + B.ints[pb], np.arange(len(pa)), key[k])
        rings_a.append(pa[ring])
        rings_b.append(pb[ring])
        src_a.append(_feature(A, supp_a))
        src_b.append(_feature(B, supp_b))
    if len(planar):
        groups.append((
            np.concatenate(rings_a), np.concatenate(rings_b),
            np.array([len(r) for r in rings_a], dtype=np.int64), key[planar],
            np.asarray(src_a, dtype=np.int64), np.asarray(src_b, dtype=np.int64),
        ))

    # Edge facets: pairs of edges whose Gauss arcs cross at an interior point of both.
    # An arc lying inside one vertex's normal cone crosses no arc of the other polytope.
    efA, efB = A.edge_facets, B.edge_facets
    live_a = ~(single_b[efA[:, 0]] & single_b[efA[:, 1]] & (b_of[efA[:, 0]] == b_of[efA[:, 1]]))
    live_b = ~(single_a[efB[:, 0]] & single_a[efB[:, 1]] & (a_of[efB[:, 0]] == a_of[efB[:, 1]]))
    ia, ib = np.nonzero(live_a)[0], np.nonzero(live_b)[0]
    a_vec = A.ints[A.edges[ia, 1]] - A.ints[A.edges[ia, 0]]  # parallel to n1 x n2 (left x right)
    b_vec = B.ints[B.edges[ib, 1]] - B.ints[B.edges[ib, 0]]
    # With p = a x b, the point s*p is inside both arcs iff (design notes section 1, simplified
    # with a.n1 = a.n2 = b.m1 = b.m2 = 0):
    #   sign(a.m1) = -s, sign(a.m2) = s, sign(b.n1) = s, sign(b.n2) = -s, all non-zero.
    # First the B edges on the horizon of each A edge direction (one sign per B facet), then
    # the two remaining signs on those few candidate pairs only.
    T = exact.dot_sign_matrix(a_vec, nB)  # (live A edges, B facets)
    t1, t2 = T[:, efB[ib, 0]], T[:, efB[ib, 1]]
    i, j = np.nonzero((t1 != 0) & (t1 == -t2))
    s = t2[i, j]
    ok = exact.dot_sign(b_vec[j], nA[efA[ia[i], 0]]) == s
    ok &= exact.dot_sign(b_vec[j], nA[efA[ia[i], 1]]) == -s
    i, j, s = i[ok], j[ok], s[ok].astype(np.int64)
    ua, va = A.edges[ia[i], 0], A.edges[ia[i], 1]
    ub, vb = B.edges[ib[j], 0], B.edges[ib[j], 1]
    # (ua+ub) -> (va+ub) -> (va+vb) -> (ua+vb) turns about a x b; reverse where s < 0.
    ring_a = np.stack([ua, va, va, ua], axis=1)
    ring_b = np.stack([ub, ub, vb, vb], axis=1)
    rev = s < 0
    ring_a[rev] = ring_a[rev, ::-1]
    ring_b[rev] = ring_b[rev, ::-1]
    groups.append((
        ring_a.reshape(-1), ring_b.reshape(-1), np.full(len(i), 4, dtype=np.int64),
        exact.primitive(exact.cross(a_vec[i], b_vec[j]) * s[:, None]),
        _src(1, ia[i]), _src(1, ib[j]),
    ))

    flat_a, flat_b, sizes, normals, source_a, source_b = (
        np.concatenate([g[c] for g in groups]) for c in range(6)
    )
    # One sum vertex per (A vertex, B vertex) label used.
    code = flat_a * len(B.ints) + flat_b
    uniq, flat = np.unique(code, return_inverse=True)
    labels = np.stack([uniq // len(B.ints), uniq % len(B.ints)], axis=1)
    ints = A.ints[labels[:, 0]] + B.ints[labels[:, 1]]
    offsets = np.zeros(len(sizes) + 1, dtype=np.int64)
    np.cumsum(sizes, out=offsets[1:])
    poly = ConvexPolytope._from_csr(ints, offsets, flat.reshape(-1), normals,
                                   grid=A.grid.plus(B.grid), name=f"{A.name}+{B.name}")
    return _with_kinds(poly, labels, source_a, source_b)


def _gather(offsets: np.ndarray, indices: np.ndarray, sel: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Concatenated index lists of the selected CSR rows, and their sizes."""
    sizes = (offsets[sel + 1] - offsets[sel]).astype(np.int64)
    within = np.arange(sizes.sum()) - np.repeat(np.cumsum(sizes) - sizes, sizes)
    return indices[np.repeat(offsets[sel], sizes) + within], sizes


def _src(dim: int, index: np.ndarray) -> np.ndarray:
    """Provenance rows ``(dim, index)``."""
    index = np.asarray(index, dtype=np.int64)
    return np.stack([np.full(len(index), dim, dtype=np.int64), index], axis=1)


def hull_minkowski_sum(A, B, *, method: str = "auto") -> ConvexPolytope:
    """Baseline: the exact convex hull of all pairwise vertex sums ``a + b``.

    Independent of :func:`convex_minkowski_sum` (shares only the exact kernel and the hull),
    O(v_A v_B) points; used to check CVMS and as the benchmark's reference method.
    """
    A, B = _common_grid(A, B)
    pts = (A.ints[:, None, :] + B.ints[None, :, :]).reshape(-1, 3)
    return ConvexPolytope.from_ints(pts, grid=A.grid.plus(B.grid), name=f"hull({A.name}+{B.name})",
                                    method=method)
