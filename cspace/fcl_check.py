"""Cross-checks of C-obstacle queries against python-fcl (float64, solid semantics).

- :class:`FclOracle`: a convex robot translated by ``q`` against one closed obstacle mesh,
  with *solid* semantics: ``fcl.Convex`` is solid, ``fcl.BVHModel`` is a hollow surface, so a
  non-convex obstacle is a BVH plus a containment test (generalized winding number of one
  robot vertex) when FCL finds no surface contact.
- :func:`cross_check`: samples translations (uniform in the bounds and concentrated near the
  C-obstacle surface) and compares membership and distance with FCL.

This is the only module of cspace that imports ``fcl`` (imported here, at use).
"""

from __future__ import annotations

import time

import numpy as np

__all__ = ["FclOracle", "cross_check"]


def _fcl():
    try:
        import fcl
    except ImportError as exc:  # pragma: no cover
        raise ImportError("cspace.fcl_check needs python-fcl: pip install python-fcl") from exc
    return fcl


def _convex(fcl, vertices, faces):
    V = np.ascontiguousarray(vertices, dtype=np.float64)
    F = np.asarray(faces, dtype=np.int64)
    flat = np.hstack([np.full((len(F), 1), 3, dtype=np.int64), F]).ravel()
    return fcl.Convex(V, len(F), flat)


def _winding(V, F, p) -> np.ndarray:
    """Generalized winding number of the closed mesh (V, F) at points p (k, 3)."""
    out = np.zeros(len(p))
    T = V[F]  # (m, 3, 3)
    for s in range(0, len(p), 256):
        a = T[None, :, 0, :] - p[s : s + 256, None, :]
        b = T[None, :, 1, :] - p[s : s + 256, None, :]
        c = T[None, :, 2, :] - p[s : s + 256, None, :]
        na, nb, nc = (np.linalg.norm(x, axis=2) for x in (a, b, c))
        num = np.einsum("kmi,kmi->km", a, np.cross(b, c))
        den = (na * nb * nc + np.einsum("kmi,kmi->km", a, b) * nc
               + np.einsum("kmi,kmi->km", a, c) * nb + np.einsum("kmi,kmi->km", b, c) * na)
        out[s : s + 256] = np.arctan2(num, den).sum(axis=1) / (2 * np.pi)
    return out


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
    """

    def __init__(self, obstacle_vertices, obstacle_faces, robot_vertices, robot_faces,
                 reference_point=(0.0, 0.0, 0.0), *, convex: bool | None = None):
        fcl = self._fcl = _fcl()
        self.obstacle_vertices = np.ascontiguousarray(obstacle_vertices, dtype=np.float64)
        self.obstacle_faces = np.ascontiguousarray(obstacle_faces, dtype=np.int64)
        c = np.asarray(reference_point, dtype=np.float64).reshape(3)
        self.robot_vertices = np.ascontiguousarray(robot_vertices, dtype=np.float64) - c
        self.robot_faces = np.ascontiguousarray(robot_faces, dtype=np.int64)
        if convex is None:
            from .convex import ConvexPolytope
            from .errors import InvalidMeshError

            try:
                ConvexPolytope.from_mesh((self.obstacle_vertices, self.obstacle_faces))
                convex = True
            except InvalidMeshError:
                convex = False
        self.convex = bool(convex)
        if self.convex:
            self._geom = _convex(fcl, self.obstacle_vertices, self.obstacle_faces)
        else:
            bvh = fcl.BVHModel()
            bvh.beginModel(len(self.obstacle_faces), len(self.obstacle_vertices))
            bvh.addSubModel(self.obstacle_vertices, self.obstacle_faces)
            bvh.endModel()
            self._geom = bvh
        self._obs = fcl.CollisionObject(self._geom, fcl.Transform())
        self._rgeom = _convex(fcl, self.robot_vertices, self.robot_faces)
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
        if not self.convex and (~out).any():
            free = np.nonzero(~out)[0]
            out[free] = _winding(self.obstacle_vertices, self.obstacle_faces,
                                 self.robot_vertices[0] + q[free]) > 0.5
        return out

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
    V, F = co.vertices, co.faces
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


def cross_check(cspace_or_obstacle, n: int = 10000, seed: int = 0, band: float = 1e-9) -> dict:
    """Compare membership and distance with FCL on sampled translations.

    Half of the samples are uniform in the bounds (``CSpace.bounds``, or the C-obstacle's
    bounding box grown by 10%), half near the C-obstacle surfaces (random boundary points
    moved along the facet normal by ``10**U(-12, -1)`` times the scene size, or not at all).

    Parameters
    ----------
    cspace_or_obstacle : CSpace or CSpaceObstacle
        Built with operands (``obstacle``, ``robot``); FCL gets the same snapped operands.
    n : int
        Number of translations.
    seed : int
    band : float
        Membership disagreements at points within ``band`` (scene units) of a C-obstacle
        boundary (our distance) are not counted.

    Returns
    -------
    report : dict
        ``n``; ``n_inside`` (ours), ``n_inside_fcl``; ``n_disagree`` beyond the band, with
        ``disagreements`` their ``(j, 3)`` locations and ``disagree_indices``; ``n_in_band``
        disagreements ignored; ``n_fcl_touching`` points FCL calls collision-free with a
        negative distance (its "in contact" answer; a disagreement unless in the band);
        ``max_distance_error`` over points both call outside (FCL distance >= 0);
        ``scene_size``; ``seconds_per_query_ours`` (contains + signed distance) and
        ``seconds_per_query_fcl`` (collide, plus distance where free); ``ok``.
    """
    from .obstacle import CSpace, CSpaceObstacle

    cs = cspace_or_obstacle
    if isinstance(cs, CSpaceObstacle):
        b = cs.bounds
        pad = 0.1 * (b[1] - b[0])
        cs = CSpace([cs], bounds=np.stack([b[0] - pad, b[1] + pad]))
    if not isinstance(cs, CSpace):
        raise TypeError(f"expected a CSpace or CSpaceObstacle, got {type(cs).__name__}")
    rng = np.random.default_rng(seed)
    lo, hi = cs.bounds
    size = float(np.linalg.norm(hi - lo))
    n_uniform = n - n // 2
    parts = [rng.uniform(lo, hi, (n_uniform, 3))]
    per = np.array_split(np.arange(n // 2), len(cs.obstacles))
    for o, idx in zip(cs.obstacles, per):
        if len(idx):
            parts.append(_near_surface(o, len(idx), rng, size))
    q = np.vstack(parts)

    t0 = time.perf_counter()
    ours_in = cs.contains(q)
    ours_d = cs.signed_distance(q)
    t_ours = time.perf_counter() - t0

    oracles = []
    for o in cs.obstacles:
        if o.obstacle is None or o.robot is None:
            raise ValueError("cross_check needs C-obstacles built with CSpaceObstacle.build")
        oracles.append(FclOracle(o.obstacle.vertices, o.obstacle.faces, o.robot.vertices,
                                 o.robot.faces, o.reference_point, convex=o.kind == "convex"))
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

    # FCL can report no collision and yet a negative distance (-1: "in contact") at touching
    # placements; such a point is a disagreement unless it is within the band.
    near = np.abs(ours_d) < band
    fcl_touch = ~fcl_in & (fcl_d < 0)
    differ = (ours_in != fcl_in) | (fcl_touch & ~ours_in)
    in_band = differ & near
    counted = np.nonzero(differ & ~in_band)[0]
    both_out = ~ours_in & ~fcl_in & ~fcl_touch
    err = np.abs(ours_d[both_out] - fcl_d[both_out])
    return {
        "n": int(len(q)),
        "n_inside": int(ours_in.sum()),
        "n_inside_fcl": int(fcl_in.sum()),
        "n_disagree": int(counted.size),
        "disagree_indices": counted,
        "disagreements": q[counted],
        "n_in_band": int(in_band.sum()),
        "n_fcl_touching": int(fcl_touch.sum()),
        "max_distance_error": float(err.max()) if err.size else 0.0,
        "scene_size": size,
        "seconds_per_query_ours": t_ours / len(q),
        "seconds_per_query_fcl": t_fcl / len(q),
        "ok": bool(counted.size == 0),
    }
