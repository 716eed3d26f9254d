"""Clearance of a rigidly moved robot mesh from fixed obstacle triangles, and certified motions.

:class:`MeshClearance` answers "how far is the robot, turned by ``R`` about its reference point
placed at ``q``, from the obstacles?" as a capped query (below ``cap`` the least distance, else
only "at least ``cap``": it stops as soon as that is certain, so a threshold check costs little
more than a collision check), and certifies a whole motion by adaptive bisection on clearances
(Schwarzer, Saha and Latombe, "Exact collision checking of robot paths", 2002): between two
poses whose clearances ``c_a``, ``c_b`` add up to more than the farthest any robot point moves,
``|Δq| + ρ·Δθ`` (``ρ``: the robot's farthest vertex from its reference point; a slerp by ``Δθ``
moves no point farther than ``ρ·Δθ``), the robot touches nothing. No sampling resolution.

These are distances between triangle *surfaces*: a robot wholly inside a closed obstacle is at
a positive distance from it. A motion along which the distance stays positive never changes
what is inside what, so a certified motion from a free pose ends at a free pose; the free
pose itself (containment) is :class:`cspace.planning.se3.clearance.PoseClearance`'s to decide.

Error bound (one-sided: a false collision within it, never a false free)
-------------------------------------------------------------------------
Every distance is float64: the robot's vertices moved by ``R``, ``q``, the triangle-pair
distances and the tree bounds each carry rounding errors of a few ulps of the scene's magnitude
``M`` (the largest coordinate of an obstacle, or of a robot point anywhere in the bounds), and
the normals of non-sliver triangles are conditioned within ``2**16`` (slivers are taken as
their edges, their inradius subtracted explicitly). A misjudged crossing happens only when the
crossing is within such an error of a triangle's boundary or plane, where an edge or corner
distance is as small. All of it is far below ``error_bound = 1e-9 * M``, which every
lower bound subtracts (:meth:`MeshClearance.lower_bound`, :meth:`MeshClearance.motion_free`).
``tests/test_clearance.py`` checks it against FCL's distance on the raw meshes, moved far
from the origin, with slivers.

The hot loop is compiled (:mod:`cspace.geometry._kernels.clearance`); its triangle-pair
distance has the pure-Python reference :func:`_pair_distances_reference` and its query the
brute-force reference :func:`_distance_reference` (every pair), both tested against it.
"""

from __future__ import annotations

import numpy as np

from ._kernels import load
from .boxes import BoxTree
from .distance import _segment_segment_d2, shorter_edge_normals

__all__ = ["MeshClearance", "ERROR_BOUND", "SLIVER", "node_boxes"]

_kernel = load("clearance")

#: The error bound of every clearance, relative to the scene's magnitude (module docstring).
ERROR_BOUND = 1e-9
#: A triangle whose inradius is at most this fraction of its longest edge is a sliver: taken
#: as its three edges, its inradius subtracted from its distances.
SLIVER = 2.0 ** -16


def sliver_radii(T: np.ndarray) -> np.ndarray:
    """``(k,)`` inradius of each ``(k, 3, 3)`` triangle that is a sliver (:data:`SLIVER`), else
    -1. Rounded up: it is subtracted from distances."""
    T = np.asarray(T, dtype=np.float64).reshape(-1, 3, 3)
    e = np.linalg.norm(T[:, [1, 2, 0]] - T, axis=2)
    area2 = np.linalg.norm(np.cross(T[:, 1] - T[:, 0], T[:, 2] - T[:, 0]), axis=1)
    perimeter = e.sum(axis=1)
    with np.errstate(divide="ignore", invalid="ignore"):
        r = np.where(perimeter > 0, area2 / perimeter, 0.0)
    sliver = r <= SLIVER * e.max(axis=1)
    return np.where(sliver, r * (1 + 1e-12) + 1e-300, -1.0)


def node_boxes(tree: BoxTree, T: np.ndarray, chunk: int = 1 << 20) -> np.ndarray:
    """``(nodes, 15)``: each node's oriented box over the corners of its triangles ``T (n, 3,
    3)``: centre, three orthonormal axes (rows; the principal directions of the corners), and
    half-extents, each rounded up so that the box holds every corner despite the float
    arithmetic (the axes are orthonormal within ~1e-15; 1e-9 of the box's reach covers it).
    Any orthonormal axes give a valid box (the extents are the corners' own projections), so
    the covariance's rounding costs tightness only.

    A node's triangles are ``tree.order[lo:hi]``: a leaf's range, an inner node's its
    children's union (the tree partitions ``order`` in place, so it is contiguous). Vectorised:
    the covariances from prefix sums over the corners in tree order, the projections over
    every (node, corner) pair in chunks of at most ``chunk`` rows."""
    n = len(tree.first)
    lo = np.zeros(n, dtype=np.int64)
    hi = np.zeros(n, dtype=np.int64)
    leaf = tree.count > 0
    lo[leaf] = tree.first[leaf]
    hi[leaf] = tree.first[leaf] + tree.count[leaf]
    for k in range(n - 1, -1, -1):  # children after their parent
        if not leaf[k]:
            a = tree.first[k]
            lo[k], hi[k] = min(lo[a], lo[a + 1]), max(hi[a], hi[a + 1])
    P = np.asarray(T, dtype=np.float64)[tree.order].reshape(-1, 3)  # corners in tree order
    origin = P.mean(axis=0)
    X = P - origin  # centred: less cancellation in the second moments
    S1 = np.concatenate([np.zeros((1, 3)), np.cumsum(X, axis=0)])
    S2 = np.concatenate([np.zeros((1, 9)),
                         np.cumsum((X[:, :, None] * X[:, None, :]).reshape(-1, 9), axis=0)])
    a, b = 3 * lo, 3 * hi
    m = (b - a).astype(np.float64)
    mean = (S1[b] - S1[a]) / m[:, None]
    cov = ((S2[b] - S2[a]) / m[:, None]).reshape(-1, 3, 3) - mean[:, :, None] * mean[:, None, :]
    _, vec = np.linalg.eigh(cov)
    axes = np.ascontiguousarray(np.swapaxes(vec, 1, 2))  # rows
    amin = np.zeros((n, 3))
    amax = np.zeros((n, 3))
    reach = np.zeros(n)
    counts = b - a
    k0 = 0
    while k0 < n:  # nodes k0..k1-1, at most ``chunk`` (node, corner) rows (a node at least)
        k1 = k0 + max(1, int(np.searchsorted(np.cumsum(counts[k0:]), chunk, side="right")))
        c = counts[k0:k1]
        node = np.repeat(np.arange(k0, k1), c)
        first = np.concatenate([[0], np.cumsum(c)[:-1]])
        idx = np.repeat(a[k0:k1], c) + (np.arange(int(c.sum())) - np.repeat(first, c))
        D = X[idx] - mean[node]
        proj = np.einsum("kj,kij->ki", D, axes[node])
        amin[k0:k1] = np.minimum.reduceat(proj, first, axis=0)
        amax[k0:k1] = np.maximum.reduceat(proj, first, axis=0)
        reach[k0:k1] = np.maximum.reduceat(np.abs(P[idx]).max(axis=1), first)
        k0 = k1
    centre = origin + mean + np.einsum("ki,kij->kj", (amin + amax) / 2, axes)
    reach = reach + np.abs(centre).max(axis=1)
    half = (amax - amin) / 2 * (1 + 1e-9) + 1e-9 * reach[:, None]
    return np.concatenate([centre, axes.reshape(n, 9), half], axis=1)


class MeshClearance:
    """Distances between a robot at any pose and fixed obstacles (module docstring).

    Parameters
    ----------
    obstacle_vertices : (n, 3) float64
    obstacle_faces : (m, 3) int64
        All obstacle triangles, world frame.
    robot_vertices : (v, 3) float64
    robot_faces : (k, 3) int64
        The robot in its own frame, relative to its reference point: at pose ``(q, R)`` a
        vertex ``p`` is at ``R p + q``.
    reach : float, default 0
        The largest ``|q|`` a query will ask for (the bounds' farthest corner): with the
        obstacles' and robot's extents it sets the scene magnitude ``M`` of
        :attr:`error_bound`.
    leaf : int, default 1
        Triangles per leaf of both trees (with oriented node boxes, one a leaf measured
        fastest: on the alpha puzzle and the bug trap a full distance 1.5-2.5x faster than
        with 8, a capped one up to 2x).

    Attributes
    ----------
    rho : float
        The robot's farthest vertex from its reference point (rounded up).
    error_bound : float
        ``ERROR_BOUND * M``: every clearance this reports may be short of the true one by at
        most this, never over (see :meth:`lower_bound`).
    """

    def __init__(self, obstacle_vertices, obstacle_faces, robot_vertices, robot_faces, *,
                 reach: float = 0.0, leaf: int = 1):
        OV = np.ascontiguousarray(obstacle_vertices, dtype=np.float64).reshape(-1, 3)
        OF = np.ascontiguousarray(obstacle_faces, dtype=np.int64).reshape(-1, 3)
        RV = np.ascontiguousarray(robot_vertices, dtype=np.float64).reshape(-1, 3)
        RF = np.ascontiguousarray(robot_faces, dtype=np.int64).reshape(-1, 3)
        if not len(OF) or not len(RF):
            raise ValueError("clearance needs at least one obstacle and one robot triangle")
        OT = np.ascontiguousarray(OV[OF].reshape(-1, 9))
        RT = RV[RF]
        self.rho = float(np.linalg.norm(RV[np.unique(RF)], axis=1).max()) * (1 + 1e-12)
        scale = max(float(np.abs(OV[np.unique(OF)]).max()), float(reach) + self.rho)
        self.magnitude = scale
        self.error_bound = ERROR_BOUND * scale
        o_tree = BoxTree(OT.reshape(-1, 3, 3).min(axis=1), OT.reshape(-1, 3, 3).max(axis=1), leaf)
        r_tree = BoxTree(RT.min(axis=1), RT.max(axis=1), leaf)
        self.n_obstacle_triangles, self.n_robot_triangles = len(OF), len(RF)
        self._k = _kernel.ClearanceKernel(
            OT, sliver_radii(OT), _unit(shorter_edge_normals(OT.reshape(-1, 3, 3))),
            _unit(shorter_edge_normals(RT)), o_tree.order, o_tree.first, o_tree.count,
            RV, RF, sliver_radii(RT), r_tree.order, r_tree.first, r_tree.count,
            node_boxes(r_tree, RT), node_boxes(o_tree, OT.reshape(-1, 3, 3)))
        self._arrays = (OT, RV, RF)

    def __repr__(self) -> str:
        return (f"MeshClearance(obstacle_triangles={self.n_obstacle_triangles}, "
                f"robot_triangles={self.n_robot_triangles}, rho={self.rho:.4g}, "
                f"error_bound={self.error_bound:.3g})")

    @property
    def queries(self) -> int:
        """Clearance queries answered so far (each step of a motion's bisection is one)."""
        return int(self._k.queries)

    def distance(self, R, q, cap: float = np.inf) -> float:
        """The float distance at pose ``(q, R)`` when below ``cap``, else a number ``>= cap``
        (the query stops early). 0 when a robot triangle meets an obstacle triangle."""
        return float(self._k.distance(np.ascontiguousarray(R, dtype=np.float64).reshape(3, 3),
                                      np.ascontiguousarray(q, dtype=np.float64).reshape(3), cap))

    def lower_bound(self, R, q, cap: float = np.inf) -> float:
        """A certain lower bound of the clearance at ``(q, R)`` (``distance - error_bound``), or
        a number ``>= cap - error_bound`` meaning "at least that". Positive: no robot triangle
        meets an obstacle triangle."""
        return self.distance(R, q, cap + self.error_bound) - self.error_bound

    def motion_free(self, q0, Q0, q1, Q1, *, max_depth: int = 40) -> tuple[bool, int, int]:
        """Certify the motion from ``(q0, Q0)`` to ``(q1, Q1)`` (positions; unit quaternions
        ``x, y, z, w``): the reference point on the segment and the rotation on the shortest
        slerp arc, both at constant speed (OMPL's SE(3) interpolation). Bisects until every
        piece's end clearances (lower bounds) add up to more than ``|Δq| + ρ·Δθ`` of the piece.

        Returns ``(free, depth, queries)``: True only when certified (touching, or pieces still
        undecided ``max_depth`` halvings down, are not free), the deepest halving and the
        clearance queries it took."""
        f = np.ascontiguousarray
        free, depth, n = self._k.motion(f(q0, dtype=np.float64).reshape(3),
                                        f(Q0, dtype=np.float64).reshape(4),
                                        f(q1, dtype=np.float64).reshape(3),
                                        f(Q1, dtype=np.float64).reshape(4), self.rho,
                                        self.error_bound, int(max_depth))
        return bool(free), int(depth), int(n)


def _unit(n: np.ndarray) -> np.ndarray:
    """Rows normalised; zero rows (degenerate triangles: slivers, whose plane is never used)
    stay zero."""
    length = np.linalg.norm(n, axis=1)
    return np.ascontiguousarray(n / np.where(length > 0, length, 1.0)[:, None])


def _one_way_reference(A: np.ndarray, B: np.ndarray, best2: np.ndarray) -> np.ndarray:
    """``A``'s corners against ``B``'s interior, its edges crossing ``B`` (-1), row-wise."""
    n = shorter_edge_normals(B)
    nn = np.einsum("kj,kj->k", n, n)
    ok = nn > 0

    def inside(x):
        inn = np.ones(len(x), dtype=bool)
        for i in range(3):
            c = np.cross(B[:, (i + 1) % 3] - B[:, i], x - B[:, i])
            inn &= np.einsum("kj,kj->k", c, n) >= 0
        return inn

    out = best2.copy()
    with np.errstate(divide="ignore", invalid="ignore"):
        for i in range(3):
            h = np.einsum("kj,kj->k", A[:, i] - B[:, 0], n) / nn
            x = A[:, i] - h[:, None] * n
            d2 = h * h * nn
            out = np.where(ok & inside(x) & (d2 < out), d2, out)
        for i in range(3):
            p, q = A[:, i], A[:, (i + 1) % 3]
            sp = np.einsum("kj,kj->k", p - B[:, 0], n)
            sq = np.einsum("kj,kj->k", q - B[:, 0], n)
            cross = ~(((sp > 0) & (sq > 0)) | ((sp < 0) & (sq < 0)) | ((sp == 0) & (sq == 0)))
            x = p + (sp / (sp - sq))[:, None] * (q - p)
            out = np.where(ok & cross & inside(x), -1.0, out)
    return out


def _pair_distances_reference(A, B, ra, rb) -> np.ndarray:
    """Pure-Python reference of the kernel's triangle-pair distance, row-wise: ``(k, 3, 3)``
    triangles, their sliver radii (:func:`sliver_radii`)."""
    A = np.asarray(A, dtype=np.float64).reshape(-1, 3, 3)
    B = np.asarray(B, dtype=np.float64).reshape(-1, 3, 3)
    ra, rb = np.asarray(ra, dtype=np.float64), np.asarray(rb, dtype=np.float64)
    best2 = np.minimum.reduce([_segment_segment_d2(A[:, i], A[:, (i + 1) % 3], B[:, j],
                                                   B[:, (j + 1) % 3])
                               for i in range(3) for j in range(3)])
    b1 = _one_way_reference(A, B, best2)
    best2 = np.where(rb < 0, b1, best2)
    crossed = best2 < 0
    b2 = _one_way_reference(B, A, np.where(crossed, np.inf, best2))
    best2 = np.where(ra < 0, b2, best2)
    crossed |= best2 < 0
    d = np.sqrt(np.maximum(best2, 0.0)) - np.maximum(ra, 0.0) - np.maximum(rb, 0.0)
    return np.where(crossed, 0.0, np.maximum(d, 0.0))


def _distance_reference(clearance: MeshClearance, R, q) -> float:
    """Brute force: the least pair distance over every robot and obstacle triangle pair."""
    OT, RV, RF = clearance._arrays
    R = np.asarray(R, dtype=np.float64).reshape(3, 3)
    A = (RV @ R.T + np.asarray(q, dtype=np.float64))[RF]
    B = OT.reshape(-1, 3, 3)
    i, j = np.meshgrid(np.arange(len(A)), np.arange(len(B)), indexing="ij")
    i, j = i.ravel(), j.ravel()
    return float(_pair_distances_reference(A[i], B[j], sliver_radii(RV[RF])[i],
                                           sliver_radii(B)[j]).min())
