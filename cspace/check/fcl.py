"""python-fcl wrappers and the winding number: the pieces the oracles are made of.

:func:`fcl_convex` (a convex polytope as an FCL convex), :class:`FclOracle` (one C-obstacle's
operands in FCL: collision and distance at translations) and :func:`winding_number` (exact
containment of points in a closed surface, for solids FCL sees only as surfaces).
"""

from __future__ import annotations

import numpy as np

from ..errors import InvalidArgumentError, InvalidMeshError

__all__ = ["FclOracle", "winding_number", "fcl_convex"]


def _fcl():
    try:
        import fcl
    except ImportError as exc:  # pragma: no cover
        raise ImportError("cspace.check needs python-fcl: pip install python-fcl") from exc
    return fcl


def fcl_convex(vertices, faces):
    """An ``fcl.Convex`` (a solid) from a convex polytope's float64 vertices and triangles."""
    fcl = _fcl()
    V = np.ascontiguousarray(vertices, dtype=np.float64)
    F = np.asarray(faces, dtype=np.int64)
    flat = np.hstack([np.full((len(F), 1), 3, dtype=np.int64), F]).ravel()
    return fcl.Convex(V, len(F), flat)


def _winding_block(tri, nv_src, idx, p, w) -> np.ndarray:
    """Sum over the triangles of ``w * Omega / 2`` for the points ``p`` (k, 3); see below."""
    (x0, y0, z0), (x1, y1, z1), (x2, y2, z2) = tri
    vx, vy, vz = nv_src
    px, py, pz = p[:, 0:1], p[:, 1:2], p[:, 2:3]
    # Distances from each point to each vertex once, then gathered per triangle corner.
    dx = vx[None, :] - px
    dy = vy[None, :] - py
    dz = vz[None, :] - pz
    dx *= dx
    dy *= dy
    dx += dy
    dz *= dz
    dx += dz
    nv = np.sqrt(dx, out=dx)
    i0, i1, i2 = idx
    na, nb, nc = np.take(nv, i0, axis=1), np.take(nv, i1, axis=1), np.take(nv, i2, axis=1)
    ax, ay, az = x0 - px, y0 - py, z0 - pz
    bx, by, bz = x1 - px, y1 - py, z1 - pz
    cx, cy, cz = x2 - px, y2 - py, z2 - pz
    # num = a . (b x c)
    u = by * cz
    u -= bz * cy
    v = bz * cx
    v -= bx * cz
    t = bx * cy
    t -= by * cx
    num = ax * u
    v *= ay
    num += v
    t *= az
    num += t
    # den = |a||b||c| + (a.b)|c| + (a.c)|b| + (b.c)|a|
    den = na * nb
    den *= nc
    np.multiply(ax, bx, out=u)
    u += ay * by
    u += az * bz
    u *= nc
    den += u
    np.multiply(ax, cx, out=u)
    u += ay * cy
    u += az * cz
    u *= nb
    den += u
    np.multiply(bx, cx, out=u)
    u += by * cy
    u += bz * cz
    u *= na
    den += u
    np.arctan2(num, den, out=num)  # = Omega / 2 for each (point, triangle)
    return num @ w


def winding_number(vertices, faces, points, *, weights=None, chunk: int = 1 << 12) -> np.ndarray:
    """Generalized winding number of a triangle mesh at points.

    ``w(p) = sum_t weights[t] * Omega_t(p) / (4 pi)`` with ``Omega_t`` the signed solid angle
    of triangle ``t`` seen from ``p`` (Van Oosterom and Strackee 1983):
    ``tan(Omega / 2) = a.(b x c) / (|a||b||c| + (a.b)|c| + (a.c)|b| + (b.c)|a|)`` with
    ``a, b, c`` the corners relative to ``p``, evaluated with ``arctan2`` so ``Omega`` is in
    ``(-2 pi, 2 pi]``.

    Parameters
    ----------
    vertices : (n, 3) float
    faces : (m, 3) int
        Counter-clockwise seen from outside for a positive winding number inside.
    points : (k, 3) float
    weights : (m,) float, optional
        Multiplier of each triangle's contribution (default 1): integer multiplicities of
        superset facets, or 0.5 for a mesh listed twice.
    chunk : int
        Point x triangle pairs per block; triangles are split into blocks of at most
        ``chunk`` too. About 20 float64 arrays of ``chunk`` entries are alive at once, so the
        default 2**12 (~0.6 MB) stays in a core's L2 cache: measured here, 2**13 and more
        ran 3x slower (cache misses) and 2**11 1.5x slower (numpy call overhead).

    Returns
    -------
    w : (k,) float64
        For a closed oriented mesh: 1 inside, 0 outside (an integer up to rounding, about
        1e-14 for points well away from the surface), 1/2 on a face, other fractions on edges
        and vertices. A point on a vertex contributes 0 for the triangles at that vertex.

    Notes
    -----
    The corner vectors are differences ``v - p`` formed directly (not expanded into
    ``v.v - 2 p.v + p.p``), so a point at distance ``d`` from a face of size ``L`` gets the
    right sign of ``Omega`` while ``d * L**2`` exceeds about ``1e-16 * L**3`` plus the
    rounding of the differences. Throughput: see ``tests/test_oracles.py``
    (``test_winding_number_throughput``); about 2e7 point x triangle pairs per second on one
    core here (numpy, no numba).
    """
    V = np.asarray(vertices, dtype=np.float64)
    F = np.asarray(faces, dtype=np.int64)
    P = np.asarray(points, dtype=np.float64).reshape(-1, 3)
    if V.ndim != 2 or V.shape[1] != 3 or F.ndim != 2 or F.shape[1] != 3:
        raise InvalidMeshError(f"expected (n, 3) vertices and (m, 3) faces, got {V.shape} and {F.shape}")
    m = len(F)
    w = np.ones(m) if weights is None else np.asarray(weights, dtype=np.float64).reshape(-1)
    if len(w) != m:
        raise InvalidArgumentError(f"weights has {len(w)} entries for {m} faces")
    out = np.zeros(len(P))
    if m == 0 or len(P) == 0:
        return out
    # Centre the coordinates: smaller magnitudes, smaller rounding in the differences.
    centre = (V.min(axis=0) + V.max(axis=0)) / 2
    V = V - centre
    P = P - centre
    tb = max(1, min(m, int(chunk)))
    for t0 in range(0, m, tb):
        Ft = F[t0 : t0 + tb]
        used, local = np.unique(Ft, return_inverse=True)
        local = local.reshape(-1, 3)
        Vu = V[used]
        nv_src = tuple(np.ascontiguousarray(Vu[:, c]) for c in range(3))
        tri = tuple(
            tuple(np.ascontiguousarray(V[Ft[:, j], c])[None, :] for c in range(3)) for j in range(3)
        )
        idx = tuple(np.ascontiguousarray(local[:, j]) for j in range(3))
        wt = np.ascontiguousarray(w[t0 : t0 + tb])
        kp = max(1, int(chunk) // len(Ft))
        for s in range(0, len(P), kp):
            out[s : s + kp] += _winding_block(tri, nv_src, idx, P[s : s + kp], wt)
    return out / (2 * np.pi)


def _welded(V: np.ndarray, F: np.ndarray) -> np.ndarray:
    """Faces re-indexed so that vertices with bit-identical coordinates (-0.0 = 0.0) share an
    index, the first such vertex's (so the faces still index ``V``): the topology of the
    float mesh as its file gives it, nothing snapped."""
    _, first, inv = np.unique(V + 0.0, axis=0, return_index=True, return_inverse=True)
    return first[inv.reshape(-1)][F]


def _components(W: np.ndarray, n: int) -> np.ndarray:
    """(m,) component label of each face: faces sharing a (welded) vertex are connected."""
    from scipy.sparse import coo_matrix
    from scipy.sparse.csgraph import connected_components

    a = np.concatenate([W[:, 0], W[:, 1]])
    b = np.concatenate([W[:, 1], W[:, 2]])
    g = coo_matrix((np.ones(len(a), dtype=np.int8), (a, b)), shape=(n, n))
    _, labels = connected_components(g, directed=False)
    _, comp = np.unique(labels[W[:, 0]], return_inverse=True)
    return comp.reshape(-1)


def _component_points(V: np.ndarray, F: np.ndarray) -> np.ndarray:
    """(k, 3): the first vertex of each connected component of the float mesh (faces sharing
    a bit-identical vertex are connected)."""
    V = np.asarray(V, dtype=np.float64)
    F = np.asarray(F, dtype=np.int64).reshape(-1, 3)
    if not len(F):
        return np.zeros((0, 3))
    W = _welded(V, F)
    comp = _components(W, len(V))
    _, first = np.unique(comp, return_index=True)
    return V[W[first, 0]]


def _convex_mesh(V: np.ndarray, F: np.ndarray) -> bool:
    """Whether a closed float mesh bounds a convex solid, the oracle's own way: Qhull's hull
    of its vertices has the mesh's volume (within 1e-9 of it: a float judgement for choosing
    FCL's solid ``Convex`` over a hollow BVH, never one of cspace's decisions)."""
    from scipy.spatial import ConvexHull, QhullError

    V = np.asarray(V, dtype=np.float64)
    F = np.asarray(F, dtype=np.int64).reshape(-1, 3)
    if len(F) < 4:
        return False
    used = V[np.unique(F)]
    c = used.mean(axis=0)
    P = V[F] - c
    volume = float(np.einsum("ij,ij->i", P[:, 0], np.cross(P[:, 1], P[:, 2])).sum()) / 6.0
    try:
        hull = ConvexHull(used - c)
    except QhullError:  # flat or degenerate: no solid
        return False
    return volume > 0 and abs(hull.volume - volume) <= 1e-9 * hull.volume


class FclOracle:
    """FCL collision and distance for a convex robot translating against one solid obstacle.

    Parameters
    ----------
    obstacle_vertices : (n, 3) float64
    obstacle_faces : (m, 3) int64
        A closed, outward-oriented obstacle surface (world frame).
    robot_vertices : (r, 3) float64
    robot_faces : (t, 3) int64
        The convex robot in its own frame.
    reference_point : (3,) float64
        The robot with its reference point at ``q`` occupies ``robot - reference_point + q``.
    convex : bool, optional
        Whether the obstacle is convex (then an ``fcl.Convex``, solid); default: decided here
        in floats, independently of cspace's model (:func:`_convex_mesh`: Qhull's hull holds
        every vertex and has the mesh's volume).
    surface : bool, default False
        Surface semantics instead (an open mesh, ``kind='surface'`` C-obstacles): FCL's plain
        mesh collision, no containment of the robot in the obstacle.
    robot_kind : {'convex', 'solid', 'surface'}, default 'convex'
        The robot's semantics: a convex solid, a non-convex closed solid (a BVH plus a winding
        test of one vertex of each obstacle component inside it), or an open surface (no
        containment). Anything but ``'convex'`` uses BVH-vs-BVH with containment tests for
        the solid sides (one vertex per connected component).
    """

    def __init__(self, obstacle_vertices, obstacle_faces, robot_vertices, robot_faces,
                 reference_point=(0.0, 0.0, 0.0), *, convex: bool | None = None,
                 surface: bool = False, robot_kind: str = "convex"):
        fcl = self._fcl = _fcl()
        self.obstacle_vertices = np.ascontiguousarray(obstacle_vertices, dtype=np.float64)
        self.obstacle_faces = np.ascontiguousarray(obstacle_faces, dtype=np.int64)
        c = np.asarray(reference_point, dtype=np.float64).reshape(3)
        self.robot_vertices = np.ascontiguousarray(robot_vertices, dtype=np.float64) - c
        self.robot_faces = np.ascontiguousarray(robot_faces, dtype=np.int64)
        self.surface = bool(surface)
        if self.surface:
            convex = False
        if convex is None:
            convex = _convex_mesh(self.obstacle_vertices, self.obstacle_faces)
        if robot_kind not in ("convex", "solid", "surface"):
            raise InvalidArgumentError(f"robot_kind must be 'convex', 'solid' or 'surface', got {robot_kind!r}")
        self.robot_kind = robot_kind
        # Containment points: one vertex of each connected component of either mesh (the
        # oracle's own components, of the float mesh as given: nothing of cspace's model).
        self._obstacle_points = _component_points(self.obstacle_vertices, self.obstacle_faces)
        self._robot_points = _component_points(self.robot_vertices, self.robot_faces)
        self.convex = bool(convex) and robot_kind == "convex"
        if self.convex:
            self._geom = fcl_convex(self.obstacle_vertices, self.obstacle_faces)
        else:
            bvh = fcl.BVHModel()
            bvh.beginModel(len(self.obstacle_faces), len(self.obstacle_vertices))
            bvh.addSubModel(self.obstacle_vertices, self.obstacle_faces)
            bvh.endModel()
            self._geom = bvh
        self._obs = fcl.CollisionObject(self._geom, fcl.Transform())
        if self.convex:
            self._rgeom = fcl_convex(self.robot_vertices, self.robot_faces)
        else:
            # Against a mesh, FCL's Convex-vs-BVH (GJK per triangle) was measured off by up to
            # 2e-5 relative in distance and missed penetrations of 5.8e-7 on a size-100
            # obstacle; BVH-vs-BVH agrees with brute force to 1e-16. The robot mesh is then
            # hollow: an obstacle lying inside the robot is found by a half-space test.
            self._rgeom = fcl.BVHModel()
            self._rgeom.beginModel(len(self.robot_faces), len(self.robot_vertices))
            self._rgeom.addSubModel(self.robot_vertices, self.robot_faces)
            self._rgeom.endModel()
        self._robot = fcl.CollisionObject(self._rgeom, fcl.Transform())

    @staticmethod
    def _q(q) -> np.ndarray:
        q = np.ascontiguousarray(q, dtype=np.float64).reshape(-1, 3)
        if not np.isfinite(q).all():
            from ..errors import NonFiniteError

            row = int(np.nonzero(~np.isfinite(q).all(axis=1))[0][0])
            raise NonFiniteError(f"q: row {row} is not finite: {q[row].tolist()}")
        return q

    def collides(self, q) -> np.ndarray:
        """(k,) bool: the robot at translation ``q`` meets the solid obstacle."""
        fcl, q = self._fcl, self._q(q)
        out = np.zeros(len(q), dtype=bool)
        rob, obs = self._robot, self._obs
        for i in range(len(q)):
            rob.setTranslation(q[i])  # float64 row (lists raise in python-fcl)
            out[i] = fcl.collide(rob, obs, fcl.CollisionRequest(), fcl.CollisionResult()) > 0
        if self.convex:
            return out
        for p in self._obstacle_points:  # an obstacle component inside the robot
            free = np.nonzero(~out)[0]
            if not free.size or self.robot_kind == "surface":
                break
            if self.robot_kind == "convex":
                out[free] = self._swallowed(q[free], p)
            else:
                out[free] = winding_number(self.robot_vertices, self.robot_faces,
                                           p - q[free]) > 0.5
        for p in self._robot_points:  # a robot component inside the solid obstacle
            free = np.nonzero(~out)[0]
            if not free.size or self.surface:
                break
            out[free] = winding_number(self.obstacle_vertices, self.obstacle_faces,
                                       p + q[free]) > 0.5
        return out

    def _swallowed(self, q: np.ndarray, point: np.ndarray) -> np.ndarray:
        """An obstacle point inside the (convex, closed) robot at ``q``: a whole obstacle
        component inside the hollow robot mesh, which BVH-vs-BVH contact does not see."""
        V, F = self.robot_vertices, self.robot_faces
        n = np.cross(V[F[:, 1]] - V[F[:, 0]], V[F[:, 2]] - V[F[:, 0]])
        d = np.einsum("ij,ij->i", n, V[F[:, 0]])
        x = point - q  # in the robot's frame
        return np.all(x @ n.T <= d, axis=1)

    def distance(self, q) -> np.ndarray:
        """(k,) float64 ``fcl.distance`` of the robot at ``q`` to the obstacle.

        The Euclidean distance from ``q`` to the C-obstacle where the robot is free;
        not meaningful in collision (FCL returns -1 or a local depth).
        """
        fcl, q = self._fcl, self._q(q)
        out = np.zeros(len(q))
        rob, obs = self._robot, self._obs
        for i in range(len(q)):
            rob.setTranslation(q[i])
            out[i] = fcl.distance(rob, obs, fcl.DistanceRequest(), fcl.DistanceResult())
        return out
