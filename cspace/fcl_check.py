"""Cross-checks of C-obstacle queries against python-fcl (float64, solid semantics).

- :class:`SceneOracle`: **the independent oracle.** A scene's robot against all its obstacle
  bodies, built from the raw float meshes of the :class:`cspace.Scene` alone (nothing of the
  C-space: no grid, snapped operand, box, piece or model decision), with its own published
  rule for what is solid (closed, consistently oriented, not self-intersecting components)
  and what is a surface; FCL's ``DynamicAABBTreeCollisionManager`` for surface contact,
  generalized winding numbers for containment, one vertex per connected component.
  Translations (:meth:`SceneOracle.collides`) and full poses
  (:meth:`SceneOracle.collides_poses`).
- :func:`cross_check`: samples translations (uniform in the bounds and concentrated near the
  C-obstacle surfaces) and compares membership and distance with FCL; with a scene the
  verdict is the :class:`SceneOracle`'s.
- :func:`path_collisions`, :func:`pose_path_collisions`, :class:`PoseCollider`: paths and
  poses re-checked against every body of the raw scene (:class:`SceneOracle`).
- :class:`FclOracle`, :func:`co_collider`: one C-obstacle's operands (as it keeps them:
  snapped) against the robot; the per-C-obstacle check of bare C-obstacles
  (``CSpaceObstacle.build``, no scene). They share the C-space's operands, so prefer the
  scene oracle whenever there is a scene.
- :func:`winding_number`: the generalized winding number of a (weighted) triangle mesh,
  float64; an oracle for tests and cross-checks, never a decision inside cspace's exact path.

This is the only module of cspace that imports ``fcl`` (imported here, at use).
"""

from __future__ import annotations

import time

import numpy as np

from .errors import ArgumentTypeError, InvalidArgumentError, InvalidMeshError

__all__ = ["SceneOracle", "FclOracle", "cross_check", "winding_number", "fcl_convex", "co_collider", "path_collisions",
           "PoseCollider", "pose_path_collisions"]


def _fcl():
    try:
        import fcl
    except ImportError as exc:  # pragma: no cover
        raise ImportError("cspace.fcl_check needs python-fcl: pip install python-fcl") from exc
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
        Whether the obstacle is convex (then an ``fcl.Convex``, solid); default: decided by
        :meth:`cspace.ConvexPolytope.from_mesh`.
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
            from .convex import ConvexPolytope
            from .errors import InvalidMeshError

            try:
                ConvexPolytope.from_mesh((self.obstacle_vertices, self.obstacle_faces))
                convex = True
            except InvalidMeshError:
                convex = False
        if robot_kind not in ("convex", "solid", "surface"):
            raise InvalidArgumentError(f"robot_kind must be 'convex', 'solid' or 'surface', got {robot_kind!r}")
        self.robot_kind = robot_kind
        # Containment points: one vertex of each connected component of either mesh.
        from .pairs import component_points

        self._obstacle_points = component_points(self.obstacle_vertices, self.obstacle_faces)
        self._robot_points = component_points(self.robot_vertices, self.robot_faces)
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
            from .errors import NonFiniteError

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


def _near_surface(co, n: int, rng, scale: float) -> np.ndarray:
    """Points on random boundary triangles of a C-obstacle, moved along the normal."""
    # Triangle pairs: the hulls of a few hundred random pieces, not of every piece.
    V, F = co.sample_mesh(rng) if hasattr(co, "sample_mesh") else (co.vertices, co.faces)
    # Triangles with a float normal (a sliver whose rounded corners are collinear has none).
    T = V[F]
    F = F[np.linalg.norm(np.cross(T[:, 1] - T[:, 0], T[:, 2] - T[:, 0]), axis=1) > 0]
    tri = V[F[rng.integers(0, len(F), n)]]
    w = rng.dirichlet(np.ones(3), n)
    p = np.einsum("ki,kij->kj", w, tri)
    nrm = np.cross(tri[:, 1] - tri[:, 0], tri[:, 2] - tri[:, 0])
    nrm /= np.linalg.norm(nrm, axis=1, keepdims=True)
    # Offsets spread over many scales, both sides (and some exactly on the plane).
    mag = scale * 10.0 ** rng.uniform(-12, -1, n)
    off = rng.choice([-1.0, 1.0], n) * mag
    off[rng.random(n) < 0.05] = 0.0
    return p + off[:, None] * nrm


def _samples(cs, n: int, rng) -> np.ndarray:
    """Half uniform in the bounds, half near the C-obstacle surfaces (inside the bounds)."""
    lo, hi = cs.bounds
    size = float(np.linalg.norm(hi - lo))
    n_uniform = n - n // 2
    parts = [rng.uniform(lo, hi, (n_uniform, 3))]
    per = np.array_split(np.arange(n // 2), max(1, len(cs.obstacles)))
    for o, idx in zip(cs.obstacles, per):
        # A scene's C-space is modelled inside its bounds only (pieces that cannot reach them
        # are never built), so near-surface samples outside the bounds are drawn again.
        if not len(idx):
            continue
        near = np.zeros((0, 3))
        for k in range(16):
            if len(near) >= len(idx):
                break
            more = _near_surface(o, (1 if k == 0 else 4) * (len(idx) - len(near)), rng, size)
            near = np.vstack([near, more[((lo <= more) & (more <= hi)).all(axis=1)]])
        if len(near) < len(idx):  # a surface nearly all outside the bounds: uniform points
            near = np.vstack([near, rng.uniform(lo, hi, (len(idx) - len(near), 3))])
        parts.append(near[:len(idx)])
    if not cs.obstacles:
        parts.append(rng.uniform(lo, hi, (n // 2, 3)))
    return np.vstack(parts)


def cross_check(cspace_or_obstacle, n: int = 10000, seed: int = 0, band: float = 1e-9, *,
                scene=None, robot_hull: bool = False) -> dict:
    """Compare membership and distance with FCL on sampled translations.

    Half of the samples are uniform in the bounds (``CSpace.bounds``, or the C-obstacle's
    bounding box grown by 10%), half near the C-obstacle surfaces (those outside the bounds,
    where a scene's C-space is not modelled, are drawn again) (random boundary points
    moved along the facet normal by ``10**U(-12, -1)`` times the scene size, or not at all).
    Where the samples are drawn uses the C-space; the verdict does not:

    - **with a scene** (``scene=``, or a ``scene`` attribute of the C-space): FCL's verdict
      and distance come from a :class:`SceneOracle` on the scene's raw meshes, every body
      (also those the model dropped or split), with the oracle's own solid/surface rule;
    - **without** (a bare :class:`CSpaceObstacle` from ``CSpaceObstacle.build``, or a
      ``CSpace`` of such): one :class:`FclOracle` per C-obstacle from the operands it keeps,
      which are the *snapped* ones (``build`` does not keep the raw float input), with the
      semantics recorded on the C-obstacle. This path shares the C-space's operands; prefer
      the scene path whenever there is a scene.

    Parameters
    ----------
    cspace_or_obstacle : CSpace or CSpaceObstacle
    n : int
        Number of translations.
    seed : int
    band : float
        Membership disagreements at points within ``band`` (scene units) of a C-obstacle
        boundary (our distance) are not counted. FCL's own tolerance is a few ulp of the
        scene's coordinates (:class:`SceneOracle`).
    scene : Scene, optional
        The scene the C-space was built from (``CSpace.from_scene``).
    robot_hull : bool, default False
        The C-space was built with ``robot_hull=True``: the oracle's robot is the hull too.

    "Ours in collision, FCL free" within the C-space's stated error bound (FCL's distance at
    most ``error_bound``, :attr:`CSpaceObstacle.error_bound`: the outward rounding,
    :mod:`cspace.margin`) is the stated false collision and is counted in ``n_in_margin``, not
    as a disagreement; "ours free, FCL in collision" (a false free) always counts. Distances
    are compared where both say free, up to the distance to the outside of the bounds (a
    scene's C-space models the bounds only: bodies beyond them may be dropped).

    Returns
    -------
    report : dict
        ``n``; ``n_inside`` (ours), ``n_inside_fcl``; ``n_disagree`` beyond the band, with
        ``disagreements`` their ``(j, 3)`` locations and ``disagree_indices``; ``n_in_band``
        disagreements ignored; ``n_fcl_touching`` points FCL calls collision-free with a
        negative distance (its "in contact" answer; a disagreement unless in the band);
        ``n_false_free``: counted disagreements where we say free; ``n_in_margin``;
        ``max_distance_error`` over points both call outside; ``scene_size``;
        ``seconds_per_query_ours`` (contains + signed distance) and ``seconds_per_query_fcl``
        (collide, plus distance where free); ``ok``; ``oracle`` (``'scene'`` or
        ``'per C-obstacle'``) and ``error_bound``.
    """
    from .obstacle import CSpace, CSpaceObstacle

    cs = cspace_or_obstacle
    if isinstance(cs, CSpaceObstacle):
        b = cs.bounds
        pad = 0.1 * (b[1] - b[0])
        cs = CSpace([cs], bounds=np.stack([b[0] - pad, b[1] + pad]))
    if not isinstance(cs, CSpace):
        raise ArgumentTypeError(f"expected a CSpace or CSpaceObstacle, got {type(cs).__name__}")
    if scene is None:  # a C-space built from a scene keeps it (SceneModel.cspace)
        scene = getattr(cs, "scene", None)
        robot_hull = robot_hull or getattr(cs, "robot_hull", False)
    rng = np.random.default_rng(seed)
    lo, hi = cs.bounds
    size = float(np.linalg.norm(hi - lo))
    q = _samples(cs, n, rng)

    t0 = time.perf_counter()
    ours_in = np.asarray(cs.contains(q), dtype=bool).reshape(-1)
    ours_d = np.asarray(cs.signed_distance(q), dtype=np.float64).reshape(-1)
    t_ours = time.perf_counter() - t0

    if scene is not None:
        oracle = SceneOracle(scene, robot_hull=robot_hull)
        t0 = time.perf_counter()
        fcl_in = oracle.collides(q)
        fcl_d = np.full(len(q), np.inf)
        free = np.nonzero(~fcl_in)[0]
        if free.size:
            fcl_d[free] = oracle.distance(q[free])
        t_fcl = time.perf_counter() - t0
        bound = max([_error_bound(o) for o in cs.obstacles] + [0.0])
        # The C-space is modelled inside the bounds only: distances beyond the bounds' outside
        # are not compared.
        reach = np.minimum((q - lo).min(axis=1), (hi - q).min(axis=1))
    else:
        oracles = [_oracle(o) for o in cs.obstacles]
        t0 = time.perf_counter()
        fcl_in = np.zeros(len(q), dtype=bool)
        fcl_d = np.full(len(q), np.inf)
        for orc in oracles:
            hit = orc.collides(q)
            fcl_in |= hit
            free = np.nonzero(~hit)[0]
            if free.size:
                fcl_d[free] = np.minimum(fcl_d[free], orc.distance(q[free]))
        t_fcl = time.perf_counter() - t0
        bound = max([_growth(o) for o in cs.obstacles] + [0.0])
        reach = np.full(len(q), np.inf)

    # FCL can report no collision and yet a negative distance (-1: "in contact") at touching
    # placements; such a point is a disagreement unless it is within the band.
    near = np.abs(ours_d) < band
    fcl_touch = ~fcl_in & (fcl_d < 0)
    differ = (ours_in != fcl_in) | (fcl_touch & ~ours_in)
    in_margin = differ & ours_in & ~fcl_in & (fcl_d <= bound + band)
    in_band = differ & near & ~in_margin
    counted = np.nonzero(differ & ~in_band & ~in_margin)[0]
    both_out = ~ours_in & ~fcl_in & ~fcl_touch
    d, f, e = ours_d[both_out], fcl_d[both_out], reach[both_out]
    err = np.maximum(np.maximum(np.minimum(d, e) - np.minimum(f, e), (f - bound) - d), 0.0)
    return {
        "n": int(len(q)),
        "n_inside": int(ours_in.sum()),
        "n_inside_fcl": int(fcl_in.sum()),
        "n_disagree": int(counted.size),
        "disagree_indices": counted,
        "disagreements": q[counted],
        "n_in_band": int(in_band.sum()),
        "n_in_margin": int(in_margin.sum()),
        "n_false_free": int((~ours_in[counted]).sum()),
        "n_fcl_touching": int(fcl_touch.sum()),
        "max_distance_error": float(err.max()) if err.size else 0.0,
        "scene_size": size,
        "seconds_per_query_ours": t_ours / len(q),
        "seconds_per_query_fcl": t_fcl / len(q),
        "ok": bool(counted.size == 0),
        "oracle": "scene" if scene is not None else "per C-obstacle",
        "error_bound": float(bound),
    }


def _error_bound(co) -> float:
    """A C-obstacle's stated error bound (scene units: its margin's plus a hull's excess; 0
    for an object without one)."""
    return float(getattr(co, "error_bound", 0.0) or 0.0)


def _growth(co) -> float:
    """How far a C-obstacle was grown beyond its snapped operands' (scene units): the margin
    box's half-diagonal plus its rounding slack."""
    m = getattr(co, "margin", None)
    if m is None:
        return 0.0
    g = np.asarray(m.steps, dtype=np.float64) * m.grid.step + m.rounding
    return float(np.linalg.norm(g)) * (1 + 1e-12)


def _oracle(co) -> "FclOracle":
    """The FCL oracle of one C-obstacle, with the semantics of the pair it was built for:
    a part of a non-convex robot carries ``co.semantics = (obstacle solid, robot kind)``."""
    if co.obstacle is None or co.robot is None:
        raise InvalidArgumentError("FCL checks need C-obstacles built from operands (CSpaceObstacle.build "
                         "or cspace.model_scene)")
    semantics = getattr(co, "semantics", None)
    if semantics is None:
        return FclOracle(co.obstacle.vertices, co.obstacle.faces, co.robot.vertices,
                         co.robot.faces, co.reference_point, convex=co.kind == "convex",
                         surface=co.kind == "surface")
    obstacle_solid, robot_kind = semantics
    return FclOracle(co.obstacle.vertices, co.obstacle.faces, co.robot.vertices, co.robot.faces,
                     co.reference_point, convex=False, surface=not obstacle_solid,
                     robot_kind=robot_kind)


def co_collider(co):
    """FCL collision test ``collides(q) -> (k,) bool`` for one C-obstacle's operands.

    Convex and mesh (solid) C-obstacles: :class:`FclOracle` on their operands (solid
    semantics). Surface C-obstacles (``kind='surface'``, open meshes): FCL's plain mesh
    collision against the surface, no containment.
    """
    return _oracle(co).collides


def _segment_samples(P: np.ndarray, step: float) -> np.ndarray:
    """Waypoints and points every ``step`` (at most) along each segment, both ends included."""
    parts = [P[:1]]
    for a, b in zip(P[:-1], P[1:]):
        n = max(1, int(np.ceil(np.linalg.norm(b - a) / step)))
        parts.append(a + (np.arange(1, n + 1)[:, None] / n) * (b - a))
    return np.vstack(parts)


def path_collisions(cspace, path, step: float | None = None, *, scene=None,
                    robot_hull: bool = False) -> tuple[np.ndarray, int]:
    """Re-check a piecewise-linear translation path with FCL, sampled along every segment.

    With a scene (``scene=``, a ``scene`` attribute of ``cspace``, or a :class:`Scene` as
    ``cspace``) every sample is checked against **every** body of the raw scene by a
    :class:`SceneOracle` (no C-obstacle box, nothing the model dropped or failed left out).
    Without one (a ``CSpace`` of bare C-obstacles), every sample is checked against every
    C-obstacle's operands (:func:`co_collider`; snapped operands, see :func:`cross_check`),
    again without any box.

    Parameters
    ----------
    cspace : CSpace or Scene
    path : (n, 3) float64
        Reference-point waypoints.
    step : float, optional
        Sampling step along segments (the samples are at most ``step`` apart, waypoints
        included); default ``1e-3`` of the bounds' diagonal (the scene's bounds with a scene).
    scene : Scene, optional
    robot_hull : bool, default False
        Check the robot's convex hull instead (a C-space built with ``robot_hull=True``).

    Returns
    -------
    colliding : (j, 3) float64
        The samples at which FCL finds a collision.
    n_samples : int
    """
    from .scene import Scene

    if isinstance(cspace, Scene):
        scene, cspace = cspace, None
    elif scene is None:
        scene = getattr(cspace, "scene", None)
    P = np.asarray(path, dtype=np.float64).reshape(-1, 3)
    lo, hi = (scene.bounds if scene is not None else cspace.bounds)
    step = step or 1e-3 * float(np.linalg.norm(np.asarray(hi) - np.asarray(lo)))
    if not step > 0:
        raise InvalidArgumentError(f"step must be positive, got {step}")
    Q = _segment_samples(P, step)
    if scene is not None:
        hit = SceneOracle(scene, robot_hull=robot_hull).collides(Q)
    else:
        hit = np.zeros(len(Q), dtype=bool)
        for o in cspace.obstacles:
            rest = np.nonzero(~hit)[0]
            if rest.size:
                hit[rest] = co_collider(o)(Q[rest])
    return Q[hit], int(len(Q))


# --------------------------------------------------------------------------------------
# a turning robot: poses along certified motions


class PoseCollider:
    """FCL collision of a scene's robot at arbitrary poses against all its obstacle bodies:
    :meth:`SceneOracle.collides_poses` (see :class:`SceneOracle` for the semantics).

    A pose is a rotation ``R`` about the robot's reference point ``c`` and the reference
    point's position ``q``: the robot occupies ``R (v - c) + q`` for its vertices ``v``
    (robot frame, :attr:`cspace.Scene.robot`).
    """

    def __init__(self, scene):
        self.oracle = SceneOracle(scene)

    def collides(self, rotations, translations) -> np.ndarray:
        """``(k,)`` bool for ``(k, 3, 3)`` rotations and ``(k, 3)`` positions."""
        return self.oracle.collides_poses(rotations, translations)


def pose_path_collisions(scene, positions, rotations, *, per_metre: float = 1e4,
                         per_degree: float = 1e4, chunk: int = 20000) -> tuple[int, int]:
    """Re-check a path of poses with FCL along its continuous motions.

    Between consecutive waypoints the reference point moves on the straight segment while
    the robot turns about it on the shortest arc (slerp), both at constant speed and
    together: the motion OMPL's SE(2) and SE(3) spaces interpolate, and for a turning path
    (:func:`cspace.ompl_plugin.plan_turning`) a translation or a turn in place. Each motion
    is sampled at ``max(per_metre * length, per_degree * angle in degrees)`` poses (at least
    one step), both ends included: consecutive samples are at most ``1 / per_metre`` apart
    and ``1 / per_degree`` degrees apart. Every pose is checked against every body of the raw
    scene (:class:`SceneOracle`).

    Parameters
    ----------
    scene : Scene
    positions : (n, 3) float64
        Reference-point positions.
    rotations : (n, 3, 3) float64
        The robot's rotations relative to its start orientation (the one applied to
        ``scene.robot``), about the reference point.

    Returns
    -------
    (colliding, samples) : the number of poses FCL finds in collision and of poses checked.
    """
    from scipy.spatial.transform import Rotation, Slerp

    oracle = SceneOracle(scene)
    P = np.asarray(positions, dtype=np.float64).reshape(-1, 3)
    Rs = np.asarray(rotations, dtype=np.float64).reshape(-1, 3, 3)
    if len(P) != len(Rs):
        raise InvalidArgumentError(f"{len(P)} positions but {len(Rs)} rotations")
    rots, pos = [], []
    colliding = total = 0

    def flush():
        nonlocal colliding, total, rots, pos
        if pos:
            colliding += int(oracle.collides_poses(np.concatenate(rots), np.concatenate(pos)).sum())
            total += sum(len(x) for x in pos)
            rots, pos = [], []

    for i in range(len(P) - 1):
        ends = Rotation.from_matrix(Rs[i: i + 2])
        angle = float((ends[0].inv() * ends[1]).magnitude())
        n = max(1, int(np.ceil(max(np.linalg.norm(P[i + 1] - P[i]) * per_metre,
                                   np.degrees(angle) * per_degree))))
        t = np.arange(n + 1) / n
        pos.append(P[i] + t[:, None] * (P[i + 1] - P[i]))
        rots.append(Slerp([0.0, 1.0], ends)(t).as_matrix() if angle > 0
                    else np.broadcast_to(Rs[i], (n + 1, 3, 3)))
        if sum(len(x) for x in pos) >= chunk:
            flush()
    if len(P) == 1:
        pos.append(P), rots.append(Rs)
    flush()
    return colliding, total


# --------------------------------------------------------------------------------------
# the independent scene oracle: raw meshes, FCL's broad phase, its own solid semantics


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


def _balanced(W: np.ndarray, comp: np.ndarray, n_comp: int) -> np.ndarray:
    """(n_comp,) bool: the component is a closed 2-cycle, every edge used as often in one
    direction as in the other (a closed, consistently oriented surface; two solids sharing
    an edge too). Edges from a vertex to itself (welded-away triangles) are ignored."""
    a = W.reshape(-1)
    b = np.roll(W, -1, axis=1).reshape(-1)
    fc = np.repeat(comp, 3)
    keep = a != b
    a, b, fc = a[keep], b[keep], fc[keep]
    lo, hi = np.minimum(a, b), np.maximum(a, b)
    sign = np.where(a < b, 1, -1)
    keys, inv = np.unique(np.stack([lo, hi], axis=1), axis=0, return_inverse=True)
    total = np.bincount(inv.reshape(-1), weights=sign, minlength=len(keys))
    closed = np.ones(n_comp, dtype=bool)
    open_edges = total[inv.reshape(-1)] != 0
    closed[np.unique(fc[open_edges])] = False
    closed[np.setdiff1d(np.arange(n_comp), fc)] = False  # nothing but welded-away triangles
    return closed


class _Mesh:
    """One raw mesh of the scene as :class:`SceneOracle` sees it (see its docstring)."""

    def __init__(self, fcl, name, V, F):
        self.name = name
        self.V = np.ascontiguousarray(V, dtype=np.float64)
        self.F = np.ascontiguousarray(F, dtype=np.int64)
        W = _welded(self.V, self.F)
        comp = _components(W, len(self.V))
        n_comp = int(comp.max()) + 1
        closed = _balanced(W, comp, n_comp)
        self.n_components = n_comp
        self.closed = closed
        # One vertex of every component (the first corner of its first face).
        first = np.unique(comp, return_index=True)[1]
        self.points = self.V[self.F[first, 0]]
        sf = self.F[closed[comp]]  # |winding number| does not depend on the orientation
        self.solid_faces = np.ascontiguousarray(sf)
        used = self.V[np.unique(sf)] if len(sf) else np.zeros((0, 3))
        self.solid_box = (np.stack([used.min(axis=0), used.max(axis=0)]) if len(used) else None)
        self.bvh = fcl.BVHModel()
        self.bvh.beginModel(len(self.F), len(self.V))
        self.bvh.addSubModel(self.V, self.F)
        self.bvh.endModel()

    @property
    def solid(self) -> bool:
        return self.solid_box is not None

    def inside(self, p: np.ndarray) -> np.ndarray:
        """(k,) bool: points inside the solid part (winding number not 0: |w| > 1/2)."""
        out = np.zeros(len(p), dtype=bool)
        if self.solid_box is None or not len(p):
            return out
        lo, hi = self.solid_box
        cand = np.nonzero(((p >= lo) & (p <= hi)).all(axis=1))[0]  # outside the box: w = 0
        if cand.size:
            out[cand] = np.abs(winding_number(self.V, self.solid_faces, p[cand])) > 0.5
        return out

    def describe(self) -> str:
        kinds = ("solid" if self.closed.all() else "surface" if not self.closed.any()
                 else f"{int(self.closed.sum())} of {self.n_components} components solid")
        return f"{self.name}: {len(self.F)} triangles, {self.n_components} components, {kinds}"


class SceneOracle:
    """FCL's verdict on a scene's robot against all its obstacle bodies, from the raw meshes.

    Built from the :class:`cspace.Scene` as loaded and nothing else: ``scene.robot``,
    ``scene.reference_point`` and ``scene.obstacles`` (float64 vertices and faces after the
    scene file's transforms). No grid, snapped coordinate, C-obstacle, box, piece or model
    decision of cspace enters, so a bug in those cannot hide itself here.

    **Semantics (the published rule).** Each mesh (the robot, every obstacle body) is split
    into connected components (triangles sharing a vertex, after welding vertices with
    bit-identical coordinates). A component is *closed* when every edge is used as often in
    one direction as in the other (a closed, consistently oriented surface; solids meeting at
    an edge included). A closed component is **solid**; every other component (open, or
    inconsistently oriented) is a **surface**. A mesh's solid is the region where the
    generalized winding number (:func:`winding_number`) of all its closed components
    together is not zero (``|w| > 1/2``): the inside of a plain closed surface, either way it
    is wound; cavities, wound against their shell, stay holes; a closed surface that meets
    itself (overlapping parts written as one mesh, or folds) holds everything it encloses.
    :mod:`cspace.model` states the same rule (a closed surface whose snapped form bounds no
    valid solid is modelled as its surface and the region it encloses), decided on its own
    grid; it also re-orients inconsistently wound components and splits at non-manifold
    edges, so where the two differ the disagreement is reported, never hidden.

    A pose collides when

    1. FCL finds surface contact between the robot mesh and any body mesh (BVH against BVH:
       the bodies registered once in a ``fcl.DynamicAABBTreeCollisionManager``, the robot the
       query object); touching counts; or
    2. (no surface contact) one vertex of **every** robot component lies inside some body's
       solid, or one vertex of **every** component of every body lies inside the robot's
       solid. Without surface contact a connected component lies wholly inside or wholly
       outside a solid, so one vertex per component decides it. Surfaces get no winding test.

    Poses: :meth:`collides` takes translations ``q`` (the robot occupies
    ``v - reference_point + q``), :meth:`collides_poses` rotations and positions (the robot
    occupies ``R (v - reference_point) + q``).

    **Tolerance.** Everything here is float64: contact is resolved to about ``|x| * 2**-52``
    times a small factor at coordinates of size ``|x|`` (FCL composes the transforms and tests
    the triangles in float64). Measured (``SceneOracle`` itself, against exact rational
    orientation tests): a unit box robot against a unit box body at (X, X, X), moved k ulp of
    X into or out of face contact, k = 1..64, was right every time at X = 1, 10^3, 10^4,
    10^5 and 10^6 (touching: collision); a small tetrahedron's apex moved along the normal of
    a randomly tilted triangle of a body at X (6000 placements per X, offsets 10^-17..10^-8
    times X) was wrong only within 0.62 ulp of X of the exact contact at X = 1, and never at
    X = 10^3..10^6 (where the placements themselves sit on X's ulp grid). :attr:`band` states
    16 ulp of the scene's largest coordinate (``scale * 2**-48``): compare with exact answers
    outside it. Winding numbers decide containment only away from the surfaces (contact
    covers the rest).

    Parameters
    ----------
    scene : Scene
    robot_hull : bool, default False
        The robot's convex hull (scipy's qhull on its vertices) instead of its mesh: the robot
        a C-space built with ``robot_hull=True`` stands for.

    Attributes
    ----------
    robot : the robot's mesh analysis; ``bodies``: one per obstacle body (``describe()``).
    band : float
        FCL's float band at this scene's coordinates: ``2**-48`` times the largest coordinate
        magnitude of the bounds, the bodies and the robot's reach beyond the bounds.
    """

    def __init__(self, scene, *, robot_hull: bool = False):
        fcl = self._fcl = _fcl()
        c = np.asarray(scene.reference_point, dtype=np.float64).reshape(3)
        RV = np.asarray(scene.robot.vertices, dtype=np.float64) - c
        RF = np.asarray(scene.robot.faces, dtype=np.int64)
        if robot_hull:
            RV, RF = _hull(RV)
        self.robot = _Mesh(fcl, scene.robot.name, RV, RF)
        self.bodies = [_Mesh(fcl, b.name, b.vertices, b.faces) for b in scene.obstacles]
        self._robot_obj = fcl.CollisionObject(self.robot.bvh, fcl.Transform())
        self._objects = [fcl.CollisionObject(b.bvh, fcl.Transform()) for b in self.bodies]
        self._manager = fcl.DynamicAABBTreeCollisionManager()
        if self._objects:
            self._manager.registerObjects(self._objects)
        self._manager.setup()
        self._solid_bodies = [b for b in self.bodies if b.solid]
        reach = float(np.abs(RV).max()) if len(RV) else 0.0
        scale = float(np.abs(np.asarray(scene.bounds, dtype=np.float64)).max()) + reach
        for b in self.bodies:
            scale = max(scale, float(np.abs(b.V).max()))
        self.band = scale * 2.0**-48
        # Body component points, all bodies together, for the robot-solid test.
        self._body_points = (np.vstack([b.points for b in self.bodies]) if self.bodies
                             else np.zeros((0, 3)))

    def describe(self) -> str:
        return "\n".join(["robot " + self.robot.describe()] + [b.describe() for b in self.bodies])

    # ---- surface contact (FCL broad and narrow phase) ------------------------------------

    def _contact(self, Rs, Q) -> np.ndarray:
        fcl = self._fcl
        out = np.zeros(len(Q), dtype=bool)
        if not self._objects:
            return out
        rob, mgr = self._robot_obj, self._manager
        cb = fcl.defaultCollisionCallback
        for i in range(len(Q)):
            if Rs is None:
                rob.setTranslation(Q[i])
            else:
                rob.setTransform(fcl.Transform(Rs[i], Q[i]))
            data = fcl.CollisionData(request=fcl.CollisionRequest())
            mgr.collide(rob, data, cb)
            out[i] = data.result.is_collision
        return out

    def _contained(self, Rs, Q, idx) -> np.ndarray:
        """(len(idx),) bool: containment (rule 2) at the poses ``idx``."""
        hit = np.zeros(len(idx), dtype=bool)
        if not idx.size:
            return hit
        Qi = Q[idx]
        Ri = None if Rs is None else Rs[idx]
        # every robot component's vertex, placed, against every solid body
        for p in self.robot.points:
            world = Qi + (p if Ri is None else Ri @ p)
            for b in self._solid_bodies:
                rest = np.nonzero(~hit)[0]
                if not rest.size:
                    return hit
                hit[rest] |= b.inside(world[rest])
        # every body component's vertex, in the robot's frame, against the robot's solid
        if self.robot.solid:
            for p in self._body_points:
                rest = np.nonzero(~hit)[0]
                if not rest.size:
                    break
                d = p - Qi[rest]
                local = d if Ri is None else np.einsum("kji,kj->ki", Ri[rest], d)
                hit[rest] |= self.robot.inside(local)
        return hit

    def _verdict(self, Rs, Q) -> np.ndarray:
        out = self._contact(Rs, Q)
        free = np.nonzero(~out)[0]
        out[free] = self._contained(Rs, Q, free)
        return out

    def collides(self, q) -> np.ndarray:
        """(k,) bool: the robot with its reference point at ``q`` (k, 3) meets some body."""
        return self._verdict(None, FclOracle._q(q))

    def collides_poses(self, rotations, positions) -> np.ndarray:
        """(k,) bool for ``(k, 3, 3)`` rotations about the reference point and ``(k, 3)``
        reference-point positions."""
        Q = FclOracle._q(positions)
        Rs = np.ascontiguousarray(rotations, dtype=np.float64).reshape(-1, 3, 3)
        if len(Rs) != len(Q):
            raise InvalidArgumentError(f"{len(Rs)} rotations but {len(Q)} positions")
        if not np.isfinite(Rs).all():
            from .errors import NonFiniteError

            raise NonFiniteError("rotations: not finite")
        return self._verdict(Rs, Q)

    def distance(self, q) -> np.ndarray:
        """(k,) float64 FCL distance between the robot at translation ``q`` and the nearest
        body surface (BVH against BVH through the manager); meaningful where the robot is
        free (0 or negative in contact; inside a solid it is the distance to its surface)."""
        fcl, q = self._fcl, FclOracle._q(q)
        out = np.full(len(q), np.inf)
        if not self._objects:
            return out
        rob, mgr = self._robot_obj, self._manager
        for i in range(len(q)):
            rob.setTranslation(q[i])
            data = fcl.DistanceData()
            mgr.distance(rob, data, fcl.defaultDistanceCallback)
            out[i] = data.result.min_distance
        return out


def _hull(V: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The convex hull of points as outward triangles (scipy's qhull); flat points: refused."""
    from scipy.spatial import ConvexHull, QhullError

    try:
        h = ConvexHull(V)
    except QhullError as exc:
        raise InvalidMeshError(f"the robot's convex hull is flat or degenerate: {exc}") from None
    F = h.simplices.astype(np.int64)
    T = V[F]
    n = np.cross(T[:, 1] - T[:, 0], T[:, 2] - T[:, 0])
    flip = np.einsum("ij,ij->i", n, h.equations[:, :3]) < 0
    F[flip] = F[flip][:, ::-1]
    return np.ascontiguousarray(V), F
