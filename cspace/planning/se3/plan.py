"""Planning in SE(3): the robot turns while it moves, every motion certified.

:func:`plan_se3` runs an OMPL planner (RRTConnect by default) on OMPL's ``SE3StateSpace``
(the reference point's position within the scene's bounds, and a rotation relative to the
start orientation) with two Python hooks, both on :class:`PoseClearance`:

- :class:`PoseValidityChecker`: a pose is valid when it is certainly free (clearance above the
  error bound, nothing inside anything);
- :class:`CertifiedMotionValidator`: a motion (OMPL's SE(3) interpolation: the position on the
  segment, the rotation on the shortest slerp arc) is valid when adaptive bisection on
  clearances certifies it (:meth:`cspace.geometry.clearance.MeshClearance.motion_free`). No
  sampling resolution anywhere.

The returned path is re-certified motion by motion after OMPL (and its shortcutting) return
it: ``solved`` means each consecutive pair of poses is one certified motion. The poses are
written as OMPL.app's ``.path`` (``x y z qx qy qz qw``: the reference point and the world
orientation).
"""

from __future__ import annotations

import time as _time

import numpy as np

from ...errors import InvalidArgumentError
from ..ompl_plugin import _bounds, _box_bounds, _ompl, planner_names
from ..solve import PlanResult, _seed, _solve
from .clearance import PoseClearance, quaternion_matrix

__all__ = ["plan_se3", "certify_path", "relative_goal", "RANGE"]

#: The default step of planners that have one (``setRange``), in units of the robot's reach
#: ``ρ`` (its farthest point from the reference point). OMPL's default, a fifth of the state
#: space's extent, makes long motions that a narrow passage certifies only in many halvings,
#: and rarely; a quarter of the robot's reach solved every problem of
#: ``benchmarks/bench_se3.py`` that the default solved, and the alpha puzzle, several times
#: faster (its SE(3) section).
RANGE = 0.25

_CLASSES: dict = {}


def _classes() -> dict:
    if _CLASSES:
        return _CLASSES
    ob, _, _ = _ompl()

    class PoseValidityChecker(ob.StateValidityChecker):
        """An ``SE3StateSpace`` state is valid when :meth:`PoseClearance.pose_free`.

        Attributes
        ----------
        calls : int
            :meth:`isValid` calls.
        """

        def __init__(self, si, poses: PoseClearance):
            super().__init__(si)
            self.poses = poses
            self.calls = 0

        def isValid(self, state) -> bool:
            self.calls += 1
            q, Q = _pose(state)
            return self.poses.pose_free(q, quaternion_matrix(Q))

    class CertifiedMotionValidator(ob.MotionValidator):
        """``checkMotion(s1, s2)``: :meth:`PoseClearance.motion_free` of OMPL's interpolation
        from ``s1`` (a valid state, as OMPL's planners and simplifier ask) to ``s2``.

        Attributes
        ----------
        calls, queries, max_depth : int
            Motions checked, the clearance queries they took and the deepest bisection.
        """

        def __init__(self, si, poses: PoseClearance):
            super().__init__(si)
            self.poses = poses
            self.calls = self.queries = self.max_depth = 0

        def checkMotion(self, s1, s2, *last_valid) -> bool:
            self.calls += 1
            q0, Q0 = _pose(s1)
            q1, Q1 = _pose(s2)
            # OMPL's planners and shortcutting move from states already valid (in a tree, on
            # a path): the end is then free when the motion is. The returned path is
            # re-certified from its valid start all the same (certify_path).
            free, depth, n = self.poses.motion_free(q0, Q0, q1, Q1, from_free=True)
            self.queries += n
            self.max_depth = max(self.max_depth, depth)
            return free

    _CLASSES["PoseValidityChecker"] = PoseValidityChecker
    _CLASSES["CertifiedMotionValidator"] = CertifiedMotionValidator
    return _CLASSES


def __getattr__(name: str):
    if name in ("PoseValidityChecker", "CertifiedMotionValidator"):
        return _classes()[name]
    raise AttributeError(name)


def _pose(state) -> tuple[np.ndarray, np.ndarray]:
    r = state.rotation()
    return (np.array((state.getX(), state.getY(), state.getZ())),
            np.array((r.x, r.y, r.z, r.w)))


def _fill(q, Q):
    def fill(state):
        state.setXYZ(*map(float, q))
        r = state.rotation()
        r.x, r.y, r.z, r.w = map(float, Q)
    return fill


def relative_goal(scene) -> np.ndarray:
    """The goal's rotation relative to the start orientation, a unit quaternion ``x, y, z, w``."""
    from scipy.spatial.transform import Rotation

    rel = np.asarray(scene.goal_rotation) @ np.asarray(scene.start_rotation).T
    return Rotation.from_matrix(rel).as_quat()


def _world_quaternions(scene, Q: np.ndarray) -> np.ndarray:
    """World orientations ``(n, 4)`` of relative rotations ``Q (n, 4)`` (start's applied)."""
    from scipy.spatial.transform import Rotation

    if not len(Q):
        return np.zeros((0, 4))
    return (Rotation.from_quat(Q) * Rotation.from_matrix(np.asarray(scene.start_rotation))).as_quat()


def _check_end(poses: PoseClearance, q, Q, what: str) -> None:
    R = quaternion_matrix(Q)
    if not poses.in_bounds(q):
        raise InvalidArgumentError(f"{what} {np.asarray(q).tolist()} is outside the bounds "
                                   f"{poses.bounds.tolist()}")
    lb = poses.clearance.lower_bound(R, q, cap=poses.error_bound)
    if not lb > 0:
        raise InvalidArgumentError(
            f"{what} pose (position {np.asarray(q).tolist()}) is in collision or within the "
            f"clearance error bound {poses.error_bound:.3g} of an obstacle")
    inside = poses.contained(q, R)
    if inside is not None:
        raise InvalidArgumentError(f"{what} pose (position {np.asarray(q).tolist()}) is in "
                                   f"collision: a part is inside {inside!r}")


def certify_path(poses: PoseClearance, P: np.ndarray, Q: np.ndarray) -> dict:
    """Re-certify a path of poses motion by motion: ``{'valid', 'motions', 'queries',
    'max_depth'}`` (``valid``: every pose in the bounds, the first free and each consecutive
    pair one certified motion, so every pose along it is free)."""
    P = np.asarray(P, dtype=np.float64).reshape(-1, 3)
    Q = np.asarray(Q, dtype=np.float64).reshape(-1, 4)
    out = {"valid": bool(len(P)), "motions": max(len(P) - 1, 0), "queries": 0, "max_depth": 0}
    if not len(P) or not poses.pose_free(P[0], quaternion_matrix(Q[0])):
        out["valid"] = False
        return out
    for k in range(len(P) - 1):
        free, depth, n = poses.motion_free(P[k], Q[k], P[k + 1], Q[k + 1])
        out["queries"] += n
        out["max_depth"] = max(out["max_depth"], depth)
        if not free:
            out["valid"] = False
            break
    return out


def plan_se3(scene, *, planner: str = "RRTConnect", time: float = 10.0, seed: int | None = None,
             simplify: bool = True, bounds=None, planner_range: float | None = None,
             poses: PoseClearance | None = None, start=None, goal=None) -> PlanResult:
    """Plan the robot's motion in SE(3) from the scene's start pose to its goal pose, every
    motion certified (module docstring).

    Parameters
    ----------
    scene : Scene
        Start and goal positions (reference point) and orientations (``start_rotation``,
        ``goal_rotation``), bounds.
    planner : str, default 'RRTConnect'
        A geometric planner bound in ``ompl.geometric`` (:func:`planner_names`).
    time : float, default 10
        Wall seconds for all of it: the clearance trees, ``solve()``, shortcutting (up to
        ``min(1, 0.15 time)``) and the path's re-certification (milliseconds a motion).
    seed : int, optional
        OMPL's global seed (as :func:`cspace.planning.plan.plan`).
    simplify : bool, default True
        ``og.PathSimplifier.simplify`` (every shortcut it keeps is a certified motion).
    bounds : (2, 3) float64, optional
        Where the reference point may be; default the scene's.
    planner_range : float, optional
        ``planner.setRange`` for planners that have it (scene units); default
        :data:`RANGE` times the robot's reach ``ρ``.
    poses : PoseClearance, optional
        Reuse one (its distance trees are built in milliseconds; a caller planning several
        times may keep it).
    start, goal : (position, quaternion), optional
        Poses other than the scene's: the reference point's position and the rotation
        relative to the start orientation, a unit quaternion ``(x, y, z, w)``.

    Returns
    -------
    PlanResult
        ``path`` the positions, ``orientations`` the world quaternions ``(x, y, z, w)``,
        ``certified`` the re-certification's counts; ``solved`` when OMPL found an exact
        solution and every motion of the returned path is certified.

    Raises
    ------
    InvalidArgumentError
        Unknown planner, a non-positive time, start or goal outside the bounds or not free
        (the message says which, and what holds it).
    """
    ob, og, ou = _ompl()
    if planner not in planner_names():
        raise InvalidArgumentError(f"{planner!r} is not a valid planner, must be one of "
                                   f"{', '.join(planner_names())}")
    if not (time > 0):
        raise InvalidArgumentError(f"time must be positive, got {time}")
    b = _bounds(scene.bounds if bounds is None else bounds)
    t0 = _time.perf_counter()
    poses = poses if poses is not None else PoseClearance(scene, b)
    q0, Q0 = ((scene.start, (0.0, 0.0, 0.0, 1.0)) if start is None else start)
    q1, Q1 = ((scene.goal, relative_goal(scene)) if goal is None else goal)
    q0, q1 = np.asarray(q0, dtype=np.float64), np.asarray(q1, dtype=np.float64)
    Q0, Q1 = np.asarray(Q0, dtype=np.float64), np.asarray(Q1, dtype=np.float64)
    _check_end(poses, q0, Q0, "start")
    _check_end(poses, q1, Q1, "goal")

    _seed(ou, seed)
    space = ob.SE3StateSpace()
    space.setBounds(_box_bounds(ob, b[0], b[1]))
    si = ob.SpaceInformation(space)
    classes = _classes()
    checker = classes["PoseValidityChecker"](si, poses)
    si.setStateValidityChecker(checker)
    mv = classes["CertifiedMotionValidator"](si, poses)
    si.setMotionValidator(mv)  # keep the Python reference (mv) alive until the end
    si.setup()

    def read(state) -> np.ndarray:
        q, Q = _pose(state)
        return np.concatenate([q, Q])

    # ``time`` is the whole budget: solve, shortcutting (a share) and the re-certification
    # (milliseconds a motion) within it.
    shortcut = min(1.0, 0.15 * time)
    left = time - (_time.perf_counter() - t0)
    status, exact, raw, simp, solve_time = _solve(
        si, _fill(q0, Q0), _fill(q1, Q1), planner=planner, time=max(left - shortcut, 1e-3) * 0.97,
        optimize=False, planner_range=RANGE * poses.rho if planner_range is None else planner_range, simplify=simplify, read=read, dim=7,
        simplify_time=shortcut)
    rows = simp if simp is not None else raw
    report = certify_path(poses, rows[:, :3], rows[:, 3:]) if len(rows) else {
        "valid": False, "motions": 0, "queries": 0, "max_depth": 0}
    simplified = simp is not None
    if simplified and not report["valid"] and len(raw):
        raw_report = certify_path(poses, raw[:, :3], raw[:, 3:])
        if raw_report["valid"]:
            rows, report, simplified = raw, raw_report, False
    return PlanResult(
        path=np.ascontiguousarray(rows[:, :3]), solved=bool(exact and report["valid"]),
        exact=bool(exact), valid=bool(report["valid"]), planner=planner,
        motion="certified SE(3)", time=_time.perf_counter() - t0, solve_time=solve_time,
        n_states=len(rows), status=status.asString(), state_checks=int(checker.calls),
        motion_checks=int(mv.calls), simplified=simplified,
        orientations=_world_quaternions(scene, rows[:, 3:]),
        certified={"motions": report["motions"], "queries": report["queries"],
                   "max_depth": report["max_depth"], "error_bound": poses.error_bound,
                   "rho": poses.rho, "planner_queries": mv.queries,
                   "planner_max_depth": mv.max_depth})
