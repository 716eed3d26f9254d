"""NCC-CVMS step 1: the Minkowski-sum superset (convolution) of a closed mesh A and a convex B.

For a closed, oriented 2-manifold triangle mesh A (any genus, non-convex) and a convex
polytope B, the superset is an oriented 2-cycle whose winding number is positive exactly on
A ⊕ B. Every superset vertex is labelled by a pair (vertex of A, vertex of B) and sits at
their (exact, grid-integer) sum. Its facets are:

- **translated**: each triangle f of A moved by its contributing vertex of B (the vertex
  maximising ``<b, n_f>``);
- **edge**: parallelograms ``e_A ⊕ e_B`` for the pairs of edges whose Gauss arcs cross, oriented
  by the sign of the crossing (one rule for convex and reflex edges of A, design notes §1);
- **corner**: facets g of B placed at vertices v of A with a signed integer multiplicity
  μ(v, g): the degree of v's Gauss image at g's normal, which is negative at saddle vertices
  and may exceed one.

Exactness. Inputs live on one integer grid (:class:`cspace.geometry.exact.Grid`); every decision is an
exact predicate. Ties (an A normal parallel to a B normal, arcs through each other's
endpoints, parallel edges) are all broken by one symbolic perturbation: B is rotated by an
infinitesimal rotation (:class:`cspace.geometry.exact.Perturbation`). The superset is the exact limit of
the generic configuration: degenerate pieces come out as zero-area or coplanar parts of the
same closed cycle, never as holes.

Corner multiplicities. Closedness fixes μ(v, ·) up to a constant per vertex: crossing B's
Gauss arc from facet L to facet R changes μ by the signed count of edge facets of v on that
arc, so μ is a potential on B's dual graph. The constant comes from two exact counts at one
direction x (the perturbed normal of B's facet 0): Banchoff's index
``i(v, x) = 1 - (sign changes of <u - v, x> around v's link) / 2 = μ(x) + μ(-x)``, and the
signed crossings of v's Gauss polygon with an arc from -x to x, ``μ(x) - μ(-x)``.
"""

from __future__ import annotations

from collections import deque
from dataclasses import dataclass, field

import numpy as np

from ..geometry import exact
from ..mesh.convex import ConvexPolytope
from .cvms import _gather, _src, on_one_step
from ..geometry.polygon import fan_triangles
from ..errors import DegenerateError, ExactnessError
from ..geometry.exact import Grid, Perturbation
from ..mesh.closed import ClosedMesh, as_mesh

__all__ = ["Superset", "minkowski_superset", "reduced_superset", "SUPERSET_KINDS"]

#: Names of the superset facet kinds, indexed by ``Superset.kind``.
SUPERSET_KINDS = ("translated", "corner", "edge")
TRANSLATED, CORNER, EDGE = 0, 1, 2


@dataclass(frozen=True, eq=False)
class Superset:
    """The convolution of A and B as polygons with labels, kinds, provenance and multiplicity.

    Attributes
    ----------
    grid : Grid
        The frame of the sums (``A.grid.plus(B.grid)``); ``vertices == grid.to_float(ints)``.
    labels : (n, 2) int64
        For each superset vertex, its vertex of A and vertex of B.
    ints : (n, 3) int64
        Exact positions in grid units: ``A.ints[labels[:, 0]] + B.ints[labels[:, 1]]``.
    facet_offsets, facet_indices : (f + 1,), (sum of degrees,) int64
        Polygon ``i`` is ``facet_indices[facet_offsets[i]:facet_offsets[i + 1]]``; translated
        facets are triangles, edge facets parallelograms, corner facets copies of B's facets.
    multiplicity : (f,) int64
        Signed multiplicity: +1 for translated and edge facets (their ring already carries
        their orientation); μ(v, g) for corner facets, whose ring has B's orientation.
    kind : (f,) int8
        Index into :data:`SUPERSET_KINDS`.
    source_a, source_b : (f, 2) int64
        ``(dimension, index)`` of the features of A and B: translated (2 face, 0 vertex),
        edge (1 edge, 1 edge), corner (0 vertex, 2 facet). Edge indices refer to
        ``a_edges`` and ``B.edges``.
    a_edges : (e, 2) int64
        The edges of A used by ``source_a`` (each once, ``u < v``).
    perturbation : Perturbation
        The symbolic perturbation every tie was broken with.
    """

    grid: Grid
    labels: np.ndarray
    ints: np.ndarray
    facet_offsets: np.ndarray
    facet_indices: np.ndarray
    multiplicity: np.ndarray
    kind: np.ndarray
    source_a: np.ndarray
    source_b: np.ndarray
    a_edges: np.ndarray
    perturbation: Perturbation
    timings: dict = field(default_factory=dict, repr=False)

    @property
    def vertices(self) -> np.ndarray:
        """(n, 3) float64 vertex positions in scene units (exact grid values)."""
        return self.grid.to_float(self.ints)

    @property
    def n_facets(self) -> int:
        return len(self.kind)

    @property
    def facets(self) -> list[np.ndarray]:
        o, f = self.facet_offsets, self.facet_indices
        return [f[o[i] : o[i + 1]] for i in range(len(o) - 1)]

    def __repr__(self) -> str:
        kinds = ", ".join(f"{int((self.kind == k).sum())} {n}" for k, n in enumerate(SUPERSET_KINDS))
        return (f"Superset(vertices={len(self.labels)}, facets={self.n_facets} ({kinds}), "
                f"step=2**{self.grid.exponent})")

    def to_trimesh(self):
        """The superset's triangles as a ``trimesh.Trimesh`` (a triangle soup: facets of
        multiplicity ``k`` appear once, reversed where ``k < 0``)."""
        import trimesh

        faces, _, _ = self.triangles()
        return trimesh.Trimesh(self.vertices, faces, process=False)

    def triangles(self) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Fan triangulation with multiplicities folded in.

        Returns
        -------
        faces : (t, 3) int64
            Each facet's triangles, reversed where its multiplicity is negative.
        facet : (t,) int64
            The facet each triangle comes from.
        weight : (t,) int64
            ``|multiplicity|`` of that facet: the cycle counts the triangle this many times.
        """
        faces, facet = fan_triangles(self.facet_offsets, self.facet_indices)
        neg = self.multiplicity[facet] < 0
        faces[neg] = faces[neg][:, ::-1]
        return faces.astype(np.int64), facet.astype(np.int64), np.abs(self.multiplicity[facet])

    def boundary(self) -> np.ndarray:
        """Directed label edges that do not cancel, as ``(k, 3)`` rows ``(u, v, count)``.

        Empty exactly when the superset is an oriented 2-cycle: every directed edge, counted
        with its facet's multiplicity, is cancelled by its reverse.
        """
        o, f = self.facet_offsets, self.facet_indices
        nxt = np.arange(len(f)) + 1
        nxt[o[1:] - 1] = o[:-1]
        u, v = f, f[nxt]
        w = np.repeat(self.multiplicity, np.diff(o))
        lo, hi = np.minimum(u, v), np.maximum(u, v)
        sgn = np.where(u < v, w, -w)
        key = lo * len(self.ints) + hi
        uniq, inv = np.unique(key, return_inverse=True)
        total = np.zeros(len(uniq), dtype=np.int64)
        np.add.at(total, inv.reshape(-1), sgn)
        bad = total != 0
        n = len(self.ints)
        return np.stack([uniq[bad] // n, uniq[bad] % n, total[bad]], axis=1)

    def is_closed(self) -> bool:
        """Whether the superset is an oriented 2-cycle (see :meth:`boundary`)."""
        return len(self.boundary()) == 0

    @property
    def error_bound(self) -> float:
        """Largest displacement of an input vertex by snapping (the sum moves by at most twice this)."""
        return self.grid.point_error_bound


def on_common_step(A, B) -> tuple[ClosedMesh, ConvexPolytope]:
    """The operands as a mesh and a convex polytope on grids of one step (re-snapped onto
    ``Grid.for_operands`` only when their steps differ)."""
    A = as_mesh(A, name=getattr(A, "name", None) or "A")
    B = B if isinstance(B, ConvexPolytope) else ConvexPolytope.from_points(B, name="B")
    return on_one_step(A, B)


def _mesh_edges(F: np.ndarray, n_vertices: int):
    """Edges of a closed triangle mesh: ``(u, v)`` with ``u < v``, left face (has u -> v), right face."""
    u = F.reshape(-1)
    v = F[:, [1, 2, 0]].reshape(-1)
    face = np.repeat(np.arange(len(F)), 3)
    key = u * n_vertices + v
    order = np.argsort(key)
    twin = order[np.searchsorted(key[order], v * n_vertices + u)]
    keep = u < v
    edges = np.stack([u[keep], v[keep]], axis=1)
    return edges, face[keep], face[twin[keep]]


def _edge_convexity(V: np.ndarray, F: np.ndarray):
    """A's face normals and edges: ``(nA, edges, left, right, sigma)``, the primitive
    integer normals, :func:`_mesh_edges`, and each edge's exact convexity ``sigma`` (+1
    convex, -1 reflex, 0 flat or knife)."""
    nA = exact.primitive(exact.cross(V[F[:, 1]] - V[F[:, 0]], V[F[:, 2]] - V[F[:, 0]]))
    edges, left, right = _mesh_edges(F, len(V))
    sigma = exact.triple_sign(nA[left], nA[right], V[edges[:, 1]] - V[edges[:, 0]])
    return nA, edges, left, right, sigma


def minkowski_superset(A, B) -> Superset:
    """The NCC-CVMS superset (convolution) of a closed mesh A and a convex polytope B.

    Parameters
    ----------
    A : ClosedMesh, trimesh.Trimesh, (vertices, faces) or path
        Closed oriented 2-manifold (validated by :func:`cspace.mesh.closed.as_mesh`), any genus.
    B : ConvexPolytope or (k, 3) float64 points
        Convex operand (points are hulled). For a C-obstacle pass ``robot.reflected(c)``.

    Returns
    -------
    Superset
        An oriented 2-cycle (checked before returning) with winding number > 0 exactly on
        A ⊕ B.

    Raises
    ------
    DegenerateError
        If two faces of A sharing an edge are back to back (zero dihedral angle).
    ExactnessError
        If an internal certificate fails (the cycle does not close, a parity is odd).

    Notes
    -----
    Cost: a BLAS product per predicate family over A's faces/edges and B's vertices/facets,
    exact fallbacks on the undecided entries, a pass over B's dual tree per vertex of A for
    the corner multiplicities (``O(v_A f_B)``), and output-sized assembly.
    """
    import time

    clock = time.perf_counter()
    A, B = on_common_step(A, B)
    V, F = A.ints, A.faces
    nV, nB = len(V), len(B.ints)

    # ---- A's face normals and edges -----------------------------------------------------
    nA, edges, left, right, sigma = _edge_convexity(V, F)
    n1, n2 = nA[left], nA[right]
    d = V[edges[:, 1]] - V[edges[:, 0]]
    flat = sigma == 0
    if flat.any():
        knife = flat & (exact.dot_sign(n1, n2) < 0)
        if knife.any():
            e = int(np.nonzero(knife)[0][0])
            raise DegenerateError(
                f"mesh '{A.name}': {int(knife.sum())} edges have their two faces back to back, "
                f"first edge between vertices {tuple(int(x) for x in edges[e])}"
            )
    # a = sigma (v - u) is parallel to n1 x n2: the direction of the edge's Gauss arc. The
    # parallelograms follow the edge itself (u -> v, as in its left face): at a reflex edge
    # (sigma = -1) their orientation flips relative to the crossing normal.
    arc = sigma[:, None].astype(np.int64) * (V[edges[:, 1]] - V[edges[:, 0]])

    bnd = B.ints[B.edges[:, 1]] - B.ints[B.edges[:, 0]]
    # The axis must avoid every direction a predicate holds fixed (A's normals and edge
    # vectors) or rotates (B's normals and edges): see Perturbation.
    pert = Perturbation.avoiding(nA, d, B.normals, bnd)
    t_prep = time.perf_counter()

    # ---- translated facets: contributing vertex of every face of A ---------------------
    mask = exact.support_mask(B.ints, nA)
    b_of = pert.argmax(B.ints, nA, mask)
    t_trans = time.perf_counter()

    # ---- edge facets: crossing Gauss arcs -----------------------------------------------
    efB = B.edge_facets
    live = ~flat & (b_of[left] != b_of[right])
    ia = np.nonzero(live)[0]
    a_vec = arc[ia]
    # sign(a . R m) for every B facet normal; a B edge is on the horizon iff its two facets differ.
    T = pert.dot_sign_matrix(a_vec, B.normals)
    t1, t2 = T[:, efB[:, 0]], T[:, efB[:, 1]]
    i, j = np.nonzero(t1 == -t2)
    s = t2[i, j]
    ok = pert.dot_sign(n1[ia[i]], bnd[j]) == s
    ok &= pert.dot_sign(n2[ia[i]], bnd[j]) == -s
    i, j, s = ia[i[ok]], j[ok], s[ok].astype(np.int64)
    xa, ya = edges[i, 0], edges[i, 1]
    ub, vb = B.edges[j, 0], B.edges[j, 1]
    ring_a = np.stack([xa, ya, ya, xa], axis=1)
    ring_b = np.stack([ub, ub, vb, vb], axis=1)
    rev = s < 0
    ring_a[rev] = ring_a[rev, ::-1]
    ring_b[rev] = ring_b[rev, ::-1]
    t_edge = time.perf_counter()

    # ---- corner facets: multiplicities as a potential on B's dual graph ----------------
    # Crossing B's arc of edge e from its left facet to its right facet adds E[e, v].
    E = np.zeros((len(B.edges), nV), dtype=np.int64)
    np.add.at(E, (j, ya), s)
    np.add.at(E, (j, xa), -s)
    delta = _dual_potential(B, E)  # (f_B, v_A): mu(v, g) - mu(v, g0), g0 = facet 0
    mu0 = _corner_constant(A, B, pert, delta, edges, arc, n1, n2, flat)
    mu = delta + mu0[None, :]
    g_idx, v_idx = np.nonzero(mu)
    mult = mu[g_idx, v_idx]
    t_corner = time.perf_counter()

    # ---- assembly --------------------------------------------------------------------------
    lb, szb = _gather(B.facet_offsets, B.facet_indices, g_idx)
    groups = [
        (F.reshape(-1), np.repeat(b_of, 3), np.full(len(F), 3), np.ones(len(F), np.int64),
         np.full(len(F), TRANSLATED), _src(2, np.arange(len(F))), _src(0, b_of)),
        (ring_a.reshape(-1), ring_b.reshape(-1), np.full(len(i), 4), np.ones(len(i), np.int64),
         np.full(len(i), EDGE), _src(1, i), _src(1, j)),
        (np.repeat(v_idx, szb), lb, szb, mult, np.full(len(g_idx), CORNER), _src(0, v_idx), _src(2, g_idx)),
    ]
    fa, fb, sizes, mult_all, kind, src_a, src_b = (np.concatenate([g[c] for g in groups]) for c in range(7))
    code = fa * nB + fb
    uniq, flat_idx = np.unique(code, return_inverse=True)
    labels = np.stack([uniq // nB, uniq % nB], axis=1)
    offsets = np.zeros(len(sizes) + 1, dtype=np.int64)
    np.cumsum(sizes, out=offsets[1:])
    out = Superset(
        grid=A.grid.plus(B.grid),
        labels=labels,
        ints=V[labels[:, 0]] + B.ints[labels[:, 1]],
        facet_offsets=offsets,
        facet_indices=flat_idx.reshape(-1).astype(np.int64),
        multiplicity=mult_all.astype(np.int64),
        kind=kind.astype(np.int8),
        source_a=src_a,
        source_b=src_b,
        a_edges=edges,
        perturbation=pert,
    )
    t_end = time.perf_counter()
    bad = out.boundary()
    if len(bad):
        raise ExactnessError(
            f"superset of '{A.name}' and '{B.name}' is not closed: {len(bad)} label edges do not cancel"
        )
    out.timings.update(
        prepare=t_prep - clock, translated=t_trans - t_prep, edge=t_edge - t_trans,
        corner=t_corner - t_edge, assemble=t_end - t_corner, check=time.perf_counter() - t_end,
    )
    return out


def reduced_superset(S: Superset, A, B) -> Superset:
    """The superset without the facets that cannot hold a point of the boundary of A ⊕ B.

    A point ``p = x + y`` (x on A, y on B) is on the boundary only if ``p - B`` touches A at
    ``x`` without entering it, so that near ``x`` the cone of ``p - B`` lies in the free cone
    of A. Two kinds of facets never meet that condition (in the perturbed, generic position
    the superset is the limit of):

    - **edge facets at reflex edges of A**: near ``x`` inside a reflex edge the free cone is
      a wedge of angle below π, which holds a line only along the edge; the cone of ``p - B``
      at a point inside an edge of B holds the line of that edge, and the perturbation keeps
      every edge of B off the direction of every edge of A;
    - **corner facets** ``v ⊕ g`` where a neighbour ``w`` of ``v`` in A has
      ``(w - v) · m_g > 0`` (``m_g`` the outward normal of B's facet g, turned by the
      perturbation, so that the sign is never 0): the cone of ``p - B`` at ``v`` is the
      half-space ``(z - v) · m_g >= 0``, which holds A's edge towards ``w``.

    Every other facet lies on the boundary of a convex piece of the sum (``f ⊕ B``,
    ``e ⊕ B`` or ``v ⊕ B``) and faces out of it: its back side is inside the sum. The result
    is not a cycle (its winding number means nothing); it contains the boundary of A ⊕ B, so
    every cell of its arrangement lies inside the sum or outside it, and a cell behind a
    facet is inside (:func:`cspace.minkowski.membership._classify_reduced`). The dropped
    facets are the folds a concave feature of A makes: oblong ⊕ icosphere(320), 72202 cutting
    triangle pairs of the superset, 12608 of the reduced one.

    Parameters
    ----------
    S : Superset
        :func:`minkowski_superset` of ``A`` and ``B``.
    A, B : ClosedMesh, ConvexPolytope
        The operands as ``S`` snapped them (:func:`on_common_step`).

    Returns
    -------
    Superset
        The same labels and points, a subset of the facets (``kind``, sources and
        multiplicities kept; every corner facet kept has multiplicity 1, checked).
    """
    V, F = A.ints, A.faces
    _, edges, _, _, sigma = _edge_convexity(V, F)
    if not np.array_equal(edges, S.a_edges):
        raise ValueError("reduced_superset: A is not the mesh S was made of")
    reflex = sigma < 0
    keep = np.ones(S.n_facets, dtype=bool)
    edge = S.kind == EDGE
    keep[edge] = ~reflex[S.source_a[edge, 1]]
    corner = np.nonzero(S.kind == CORNER)[0]
    if len(corner):
        # every (corner facet, neighbour of its vertex) pair: one exact dot sign each
        ends = np.concatenate([edges, edges[:, ::-1]])
        ends = ends[np.argsort(ends[:, 0], kind="stable")]
        first = np.searchsorted(ends[:, 0], np.arange(len(V) + 1))
        v = S.source_a[corner, 1]
        deg = first[v + 1] - first[v]
        row = np.repeat(np.arange(len(corner)), deg)
        k = np.arange(len(row)) - np.repeat(np.cumsum(deg) - deg, deg) + first[v][row]
        above = S.perturbation.dot_sign(V[ends[k, 1]] - V[v[row]],
                                        B.normals[S.source_b[corner, 1]][row]) > 0
        out = np.zeros(len(corner), dtype=bool)
        np.logical_or.at(out, row, above)
        keep[corner[out]] = False
    kept_corners = keep & (S.kind == CORNER)
    if np.any(S.multiplicity[kept_corners] != 1):
        raise ExactnessError("a corner facet on the boundary of its piece has multiplicity "
                             "other than 1")
    o, f = S.facet_offsets, S.facet_indices
    sizes = np.diff(o)[keep]
    offsets = np.zeros(len(sizes) + 1, dtype=np.int64)
    np.cumsum(sizes, out=offsets[1:])
    take = np.repeat(keep, np.diff(o))
    return Superset(grid=S.grid, labels=S.labels, ints=S.ints, facet_offsets=offsets,
                    facet_indices=f[take], multiplicity=S.multiplicity[keep],
                    kind=S.kind[keep], source_a=S.source_a[keep], source_b=S.source_b[keep],
                    a_edges=S.a_edges, perturbation=S.perturbation, timings=dict(S.timings))


def joined_supersets(supersets: list, pieces: list) -> Superset:
    """The supersets of several bodies ``pieces[i]`` with one B, as one superset of their
    union: points, facets and provenance one body after the other, A's vertices, faces and
    edges numbered likewise (body ``i``'s after those of the bodies before it). Every facet
    keeps what it was made of, so a reduced superset stays one (its facets face out of
    convex pieces of the union, and it holds the union's boundary, which lies on the
    bodies')."""
    if len(supersets) == 1:
        return supersets[0]
    grid = supersets[0].grid
    if any(S.grid != grid for S in supersets):
        raise ValueError("joined_supersets: the bodies' supersets are in different frames")
    labels, ints, offsets, flat, a_edges = [], [], [np.zeros(1, dtype=np.int64)], [], []
    source_a = []
    nv = nf = ne = npts = nflat = 0
    for S, P in zip(supersets, pieces):
        lab = S.labels.copy()
        lab[:, 0] += nv
        labels.append(lab)
        ints.append(S.ints)
        offsets.append(S.facet_offsets[1:] + nflat)
        flat.append(S.facet_indices + npts)
        a_edges.append(S.a_edges + nv)
        src = S.source_a.copy()
        src[:, 1] += np.choose(src[:, 0], [nv, ne, nf])
        source_a.append(src)
        nv += len(P.ints)
        nf += len(P.faces)
        ne += len(S.a_edges)
        npts += len(S.ints)
        nflat += len(S.facet_indices)
    return Superset(grid=grid, labels=np.vstack(labels), ints=np.vstack(ints),
                    facet_offsets=np.concatenate(offsets), facet_indices=np.concatenate(flat),
                    multiplicity=np.concatenate([S.multiplicity for S in supersets]),
                    kind=np.concatenate([S.kind for S in supersets]),
                    source_a=np.vstack(source_a),
                    source_b=np.vstack([S.source_b for S in supersets]),
                    a_edges=np.vstack(a_edges), perturbation=supersets[0].perturbation,
                    timings={})


def _dual_potential(B: ConvexPolytope, E: np.ndarray) -> np.ndarray:
    """Potential on B's facets (rows) from edge differences: delta[R] - delta[L] = E[e].

    A breadth-first tree of B's dual graph from facet 0; path independence is what the
    closedness check certifies afterwards.
    """
    nf = B.n_facets
    adj: list[list[tuple[int, int, int]]] = [[] for _ in range(nf)]
    for e, (L, R) in enumerate(B.edge_facets.tolist()):
        adj[L].append((R, e, 1))
        adj[R].append((L, e, -1))
    delta = np.zeros((nf, E.shape[1]), dtype=np.int64)
    seen = np.zeros(nf, dtype=bool)
    seen[0] = True
    queue = deque([0])
    while queue:
        g = queue.popleft()
        for h, e, sgn in adj[g]:
            if not seen[h]:
                seen[h] = True
                delta[h] = delta[g] + sgn * E[e]
                queue.append(h)
    return delta


def _corner_constant(A, B, pert, delta, edges, arc, n1, n2, flat) -> np.ndarray:
    """μ(v, g0) for every vertex v of A, g0 = B's facet 0, from two exact counts."""
    V, F = A.ints, A.faces
    nV = len(V)
    x = B.normals[0]
    # Banchoff: i(v, x) = 1 - (sign changes of <u - v, R x> around v's link) / 2.
    # Consecutive link vertices of v are the two other corners of each face around v.
    changes = np.zeros(nV, dtype=np.int64)
    for c in range(3):
        p, q, r = F[:, c], F[:, (c + 1) % 3], F[:, (c + 2) % 3]
        hq = pert.dot_sign(V[q] - V[p], x)
        hr = pert.dot_sign(V[r] - V[p], x)
        np.add.at(changes, p, (hq != hr).astype(np.int64))
    index = 1 - changes // 2
    # Crossings of v's Gauss polygon with the arc from -x to the B normal most opposite to x.
    # Any facet g1 != g0 gives the same exact answer; a float argmax only keeps the arc short.
    g1 = int(np.argmax(-(B.normals.astype(np.float64) @ x.astype(np.float64))))
    p1, p2 = -x, B.normals[g1]
    cross_count = np.zeros(nV, dtype=np.int64)
    bv = [int(p1[1]) * int(p2[2]) - int(p1[2]) * int(p2[1]),
          int(p1[2]) * int(p2[0]) - int(p1[0]) * int(p2[2]),
          int(p1[0]) * int(p2[1]) - int(p1[1]) * int(p2[0])]
    if any(bv):
        if pert.parallel_to(bv):
            raise ExactnessError("perturbation axis is parallel to the reference arc")  # pragma: no cover
        live = np.nonzero(~flat)[0]
        a = arc[live]
        s = pert.dot_sign(a, np.broadcast_to(p2, a.shape))
        cand = pert.dot_sign(a, np.broadcast_to(p1, a.shape)) == -s
        cand &= pert.dot_sign_big(n1[live], bv) == s
        cand &= pert.dot_sign_big(n2[live], bv) == -s
        k = live[cand]
        # Same rule as the edge facets' potential: +s at the edge's head v, -s at its tail u.
        np.add.at(cross_count, edges[k, 1], s[cand].astype(np.int64))
        np.add.at(cross_count, edges[k, 0], -s[cand].astype(np.int64))
    # mu(x) - mu(-x) = [mu(p2) - mu(-x)] + [mu(g0) - mu(g1)].
    winding = cross_count - delta[g1]
    twice = index + winding
    if (twice % 2).any():
        v = int(np.nonzero(twice % 2)[0][0])
        raise ExactnessError(f"corner multiplicity of vertex {v} is not an integer (index/winding parity)")
    return twice // 2
