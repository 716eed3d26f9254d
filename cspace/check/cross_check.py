"""Cross-checks of C-obstacle queries against python-fcl (float64, solid semantics).

- :class:`~cspace.check.oracle.SceneOracle` (:mod:`cspace.check.oracle`): **the independent oracle.** A scene's robot against all its obstacle
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
- :class:`~cspace.check.fcl.FclOracle` (:mod:`cspace.check.fcl`), :func:`co_collider`: one C-obstacle's operands (as it keeps them:
  snapped) against the robot; the per-C-obstacle check of bare C-obstacles
  (``CSpaceObstacle.build``, no scene). They share the C-space's operands, so prefer the
  scene oracle whenever there is a scene.
- :func:`~cspace.check.fcl.winding_number` (:mod:`cspace.check.fcl`): the generalized winding number of a (weighted) triangle mesh,
  float64; an oracle for tests and cross-checks, never a decision inside cspace's exact path.

Only :mod:`cspace.check` imports ``fcl`` (in :mod:`cspace.check.fcl`, at use).
"""

from __future__ import annotations

import time

import numpy as np

from ..errors import ArgumentTypeError, InvalidArgumentError
from .fcl import FclOracle
from .oracle import SceneOracle

__all__ = ["cross_check", "co_collider", "near_surface", "path_collisions", "PoseCollider",
           "pose_path_collisions"]


def near_surface(co, n: int, rng, scale: float) -> np.ndarray:
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
            more = near_surface(o, (1 if k == 0 else 4) * (len(idx) - len(near)), rng, size)
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
    :mod:`cspace.cobstacle.margin`) is the stated false collision and is counted in ``n_in_margin``, not
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
    from ..scene.model import CSpace
    from ..cobstacle.obstacle import CSpaceObstacle

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
    from ..scene.scene import Scene

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
    (:func:`cspace.planning.plan.plan_turning`) a translation or a turn in place. Each motion
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
