"""NCC-CVMS steps 7–16, stage ``traversal``: sub-facet sides grouped into shells.

Around every edge the half-planes of its sub-facets are ordered by angle (exact integer triple
products, float-filtered); from one side of a sub-facet, rotating through the free wedge reaches
the next side. These pairings group sides into shells, the boundary components of the cells of
the arrangement (the paper's plane-angle rule, applied to both sides of every sub-facet, so
non-manifold edges are handled wedge by wedge).
"""

from __future__ import annotations

from dataclasses import dataclass
from functools import cmp_to_key

import numpy as np

from ..errors import ExactnessError
from ..geometry.graphs import component_labels
from ..geometry.tritri import _cross, _dot
from .arrangements import _Complex
from .planes import _Planes


@dataclass
class _Shells:
    """Sides of sub-facets grouped into shells (boundary components of arrangement cells).

    Side node ``2 f + 1`` is the side of sub-facet ``f`` its plane normal (``planes.normal``)
    points into, node ``2 f`` the other one; ``of[node]`` is its shell.
    """

    of: np.ndarray
    n: int


def _edge_vector(cx: _Complex, e: int) -> tuple:
    """An integer vector along edge ``e`` from its smaller to its larger vertex id (scaled by
    the product of their ``W``)."""
    u, v = cx.edges[e].tolist()
    P, Q = cx.points[u], cx.points[v]
    return tuple(Q[k] * P[3] - P[k] * Q[3] for k in range(3))


def _edge_direction(cx: _Complex, planes: _Planes, e: int, normals: list) -> tuple:
    """Integer vector along edge ``e`` from its smaller to its larger vertex id, from two
    non-parallel plane normals of its sub-facets (an edge with three or more half-planes
    always has two)."""
    for i in range(len(normals)):
        for j in range(i + 1, len(normals)):
            d = _cross(normals[i], normals[j])
            if d != (0, 0, 0):
                s = _dot(d, _edge_vector(cx, e))
                if s == 0:  # pragma: no cover - the edge lies on both planes
                    raise ExactnessError(f"edge {e} is not along the line of its planes")
                return d if s > 0 else tuple(-c for c in d)
    raise ExactnessError(f"edge {e}: its half-planes all lie in one plane")  # pragma: no cover


def _angular_order(vectors: list, d: tuple) -> list:
    """Indices of ``vectors`` (all orthogonal to ``d``) in counter-clockwise order about ``d``."""
    r = vectors[0]

    def half(x) -> int:
        c = _dot(_cross(r, x), d)
        return 0 if c > 0 or (c == 0 and _dot(r, x) > 0) else 1

    def cmp(i, j) -> int:
        hi, hj = half(vectors[i]), half(vectors[j])
        if hi != hj:
            return hi - hj
        c = _dot(_cross(vectors[i], vectors[j]), d)
        if c == 0:
            raise ExactnessError("two sub-facets share an edge and a half-plane")
        return -1 if c > 0 else 1

    return sorted(range(len(vectors)), key=cmp_to_key(cmp))


def _crossing_order(cx: _Complex, e: int, inc: list, inc_sign: list, plane_of: list,
                    plane_normal: list) -> list | None:
    """The angular order of :func:`_angular_order` at an edge where two planes cross, each
    with a sub-facet on both sides (four incidences, two per plane, opposite half-edge
    signs), or None for any other edge. The keys ``s_h * m`` come in two opposite pairs
    ``±v`` (plane p) and ``±w`` (plane q); after ``v`` comes the ``w`` with
    ``(v x w) . d > 0``, and ``d = sign(D . delta) D`` for ``D = n_p x n_q`` along the edge
    ``delta``: that product is ``s_v s_w sign(D . delta) |D|^2``, so one exact sign decides."""
    i0 = inc[0]
    p = plane_of[i0]
    same = [i for i in inc[1:] if plane_of[i] == p]
    other = [i for i in inc[1:] if plane_of[i] != p]
    if len(same) != 1 or len(other) != 2 or plane_of[other[0]] != plane_of[other[1]]:
        return None
    i1, (j0, j1) = same[0], other
    if inc_sign[i1] == inc_sign[i0] or inc_sign[j0] == inc_sign[j1]:
        return None
    s = _dot(_cross(plane_normal[p], plane_normal[plane_of[j0]]), _edge_vector(cx, e))
    if s == 0:  # pragma: no cover - the edge lies on both planes
        raise ExactnessError(f"edge {e} is not along the line of its planes")
    nxt, last = (j0, j1) if inc_sign[i0] * inc_sign[j0] * (1 if s > 0 else -1) > 0 else (j1, j0)
    return [i0, nxt, i1, last]


# Bound factor of the float filter of (n_p x n_q) . (P_v - P_u): about 9 eps of the same sum
# on absolute values (conversions, products, differences, the 3-term sum); doubled.
_CROSSING_FILTER = 18 * float(np.finfo(np.float64).eps) / 2


def _crossing_orders(cx: _Complex, edges: np.ndarray, inc: np.ndarray,
                     plane_normal: list) -> tuple[np.ndarray, np.ndarray]:
    """:func:`_crossing_order` of many four-incidence edges at once: ``inc (m, 4)`` their
    incidences (in incidence order). Returns the orders ``(m', 4)`` of the edges where two
    planes cross and a float filter decides the sign, and a mask of the other edges (other
    kinds, and the filter's undecided rows): those go to :func:`_crossing_order` and the
    angular sort one by one."""
    plane = cx.face_plane[cx.inc_face[inc]]
    same = plane[:, 1:] == plane[:, :1]
    by = np.argsort(same, axis=1, kind="stable")  # the two other-plane columns, then the same
    rows = np.arange(len(inc))
    j0, j1, i1 = (inc[rows, 1 + by[:, k]] for k in range(3))
    jp0, jp1 = plane[rows, 1 + by[:, 0]], plane[rows, 1 + by[:, 1]]
    i0 = inc[:, 0]
    ok = ((same.sum(axis=1) == 1) & (jp0 == jp1)
          & (cx.inc_sign[i1] != cx.inc_sign[i0]) & (cx.inc_sign[j0] != cx.inc_sign[j1]))
    r = np.nonzero(ok)[0]
    # sign of (n_p x n_q) . (P_v - P_u) in floats, with a bound on its error
    normals = np.array(plane_normal, dtype=np.float64).reshape(-1, 3)
    a, b = normals[plane[r, 0]], normals[jp0[r]]
    D = np.cross(a, b)
    M = (np.abs(a[:, [1, 2, 0]] * b[:, [2, 0, 1]]) + np.abs(a[:, [2, 0, 1]] * b[:, [1, 2, 0]]))
    uv = cx.edges[edges[r]]
    ids, where = np.unique(uv, return_inverse=True)
    pts = cx.points
    P = np.array([[X / W, Y / W, Z / W] for X, Y, Z, W in (pts[i] for i in ids.tolist())],
                 dtype=np.float64).reshape(-1, 3)
    Pu, Pv = P[where.reshape(-1, 2)[:, 0]], P[where.reshape(-1, 2)[:, 1]]
    dot = np.einsum("ij,ij->i", D, Pv - Pu)
    bound = _CROSSING_FILTER * np.einsum("ij,ij->i", M, np.abs(Pu) + np.abs(Pv))
    sure = np.abs(dot) > bound
    r, dot = r[sure], dot[sure]
    slow = np.ones(len(inc), dtype=bool)
    slow[r] = False
    first = cx.inc_sign[i0[r]].astype(np.int64) * cx.inc_sign[j0[r]] * np.sign(dot) > 0
    nxt = np.where(first, j0[r], j1[r])
    last = np.where(first, j1[r], j0[r])
    return np.stack([i0[r], nxt, i1[r], last], axis=1), slow


def _wedge_links(cx: _Complex, L: np.ndarray, positions) -> tuple[list, list]:
    """Side-node pairs across the free wedges of edges whose half-planes (incidences) are in
    cyclic angular order ``L (m, k)``: from side ``s`` of the sub-facet at ``positions`` of
    each row, rotating through the free wedge reaches the next half-plane, and the side of
    it that faces the wedge (the plane-angle rule; with two half-planes, orientation
    coherence)."""
    rows = np.arange(len(L))
    k = L.shape[1]
    a, b = [], []
    for pos in positions:
        i = L[:, pos]
        for s in (1, -1):
            rot = s * cx.inc_sign[i].astype(np.int64)
            j = L[rows, (pos + rot) % k]
            a.append(2 * cx.inc_face[i] + (s > 0))
            b.append(2 * cx.inc_face[j] + (-rot * cx.inc_sign[j] > 0))
    return a, b


def _shells(cx: _Complex, planes: _Planes) -> _Shells:
    order = np.argsort(cx.inc_edge, kind="stable")
    e_sorted = cx.inc_edge[order]
    counts = np.bincount(cx.inc_edge, minlength=len(cx.edges))
    start = np.searchsorted(e_sorted, np.arange(len(cx.edges)))
    # side pairs (node, node); with two half-planes one position gives every link
    two = start[counts == 2]
    fa, ta = _wedge_links(cx, np.stack([order[two], order[two + 1]], axis=1), (0,))
    # A free edge (one half-plane: the rim of a sheet whose superset pieces cancel) joins
    # the two sides of its sub-facet: the cell wraps around the rim.
    one = order[start[counts == 1]]
    fa += [2 * cx.inc_face[one]]
    ta += [2 * cx.inc_face[one] + 1]
    plane_normal = [planes.normal(p) for p in range(len(planes.keys))]
    # Edges where two planes cross: their order from one sign each, decided together.
    four = np.nonzero(counts == 4)[0]
    L4, slow = _crossing_orders(cx, four, order[start[four][:, None] + np.arange(4)], plane_normal)
    a4, b4 = _wedge_links(cx, L4, range(4))
    fa += a4
    ta += b4
    orders: dict = {}  # the other edges' orders, by number of half-planes
    many = np.union1d(np.nonzero((counts > 2) & (counts != 4))[0], four[slow])
    inc_sign = cx.inc_sign.tolist()
    plane_of = cx.face_plane[cx.inc_face].tolist()  # plane of each incidence
    for e, lo, k in zip(many.tolist(), start[many].tolist(), counts[many].tolist()):
        inc = order[lo: lo + k].tolist()
        L = _crossing_order(cx, e, inc, inc_sign, plane_of, plane_normal) if k == 4 else None
        if L is None:
            normals = [plane_normal[plane_of[i]] for i in inc]
            d = _edge_direction(cx, planes, e, normals)
            vec = [tuple(inc_sign[i] * c for c in n) for i, n in zip(inc, normals)]
            L = [inc[m] for m in _angular_order(vec, d)]
        orders.setdefault(k, []).append(L)
    for k, Ls in orders.items():
        a, b = _wedge_links(cx, np.array(Ls, dtype=np.int64), range(k))
        fa += a
        ta += b
    a = np.concatenate(fa)
    b = np.concatenate(ta)
    n_nodes = 2 * len(cx.face_plane)
    n, of = component_labels(n_nodes, a, b)
    return _Shells(of=of.astype(np.int64), n=int(n))
