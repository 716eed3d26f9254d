"""OMPL.app's way, for comparison: sampled poses checked by FCL, motions by discrete sampling
(:func:`plan_sampled`; nothing is proved between the sampled states)."""

from __future__ import annotations

import time as _time

import numpy as np

from ..errors import InvalidArgumentError
from .ompl_plugin import _bounds, _box_bounds, _ompl, planner_names
from .solve import PlanResult, _seed, _solve

__all__ = ["SAMPLED_SPACES", "plan_sampled"]


SAMPLED_SPACES = ("SE2", "SE3")


def plan_sampled(scene, *, space: str = "SE3", planner: str = "RRTConnect", time: float = 1.0,
                 seed: int | None = None, resolution: float = 0.01,
                 simplify: bool = True) -> PlanResult:
    """Plan as OMPL.app does, for comparison: poses checked by FCL, motions by sampling.

    The state is the robot's pose: ``'SE3'`` (position and a rotation relative to the start
    orientation) or ``'SE2'`` (x, y and a turn about z; z stays the start's). A state is
    valid when FCL finds the robot mesh at that pose free of every obstacle body (solid
    semantics, :class:`cspace.check.cross_check.PoseCollider`); a motion is valid when OMPL's
    default discrete validator finds the states every ``resolution`` times the space's
    maximum extent valid. Nothing is proved between those states: a returned path can clip
    a thin obstacle or a corner (:func:`cspace.check.cross_check.pose_path_collisions` finds out).

    Returns a :class:`PlanResult` whose ``valid`` is only OMPL's discrete verdict, with
    ``orientations`` (world frame quaternions ``(x, y, z, w)``).
    """
    from scipy.spatial.transform import Rotation

    from ..check.cross_check import PoseCollider

    ob, og, ou = _ompl()
    if space not in SAMPLED_SPACES:
        raise InvalidArgumentError(f"{space!r} is not a valid space, must be one of {', '.join(SAMPLED_SPACES)}")
    if planner not in planner_names():
        raise InvalidArgumentError(f"{planner!r} is not a valid planner")
    b = _bounds(scene.bounds)
    start_rot = np.asarray(scene.start_rotation, dtype=np.float64)
    rel_goal = Rotation.from_matrix(np.asarray(scene.goal_rotation) @ start_rot.T)
    collider = PoseCollider(scene)
    z0 = float(scene.start[2])
    if space == "SE3":
        sp = ob.SE3StateSpace()
        rb = _box_bounds(ob, b[0], b[1])
    else:
        if scene.start[2] != scene.goal[2]:
            raise InvalidArgumentError("SE2 keeps z: the start and goal must share it")
        rv = rel_goal.as_rotvec()
        if abs(rv[0]) > 1e-12 or abs(rv[1]) > 1e-12:
            raise InvalidArgumentError("SE2 turns about z: the goal rotation is not a turn about z")
        sp = ob.SE2StateSpace()
        rb = _box_bounds(ob, b[0, :2], b[1, :2])
    sp.setBounds(rb)

    def pose(state) -> tuple[np.ndarray, np.ndarray]:
        if space == "SE3":
            r = state.rotation()
            R = Rotation.from_quat([r.x, r.y, r.z, r.w]).as_matrix()
            return np.array([state.getX(), state.getY(), state.getZ()]), R
        R = Rotation.from_euler("z", state.getYaw()).as_matrix()
        return np.array([state.getX(), state.getY(), z0]), R

    lo, hi = b[0], b[1]

    def valid(state) -> bool:
        q, R = pose(state)
        if not ((lo <= q) & (q <= hi)).all():
            return False
        return not bool(collider.collides(R[None], q[None])[0])

    def setter(q, rot):
        def fill(state):
            if space == "SE3":
                state.setXYZ(*map(float, q))
                angle = rot.magnitude()
                if angle > 0:
                    state.rotation().setAxisAngle(*map(float, rot.as_rotvec() / angle), float(angle))
                else:
                    state.rotation().setIdentity()
            else:
                state.setXY(float(q[0]), float(q[1]))
                state.setYaw(float(rot.as_rotvec()[2]))
        return fill

    def read(state) -> np.ndarray:
        q, R = pose(state)
        return np.concatenate([q, R.ravel()])

    _seed(ou, seed)
    si = ob.SpaceInformation(sp)
    si.setStateValidityChecker(valid)
    si.setStateValidityCheckingResolution(float(resolution))
    si.setup()
    t0 = _time.perf_counter()
    status, exact, raw, simp, solve_time = _solve(
        si, setter(scene.start, Rotation.identity()), setter(scene.goal, rel_goal),
        planner=planner, time=time, optimize=False, planner_range=None, simplify=simplify,
        read=read, dim=12)
    rows = (simp if simp is not None else raw) if exact else np.zeros((0, 12))
    simplified = simp is not None and exact
    poses = [(row[:3], row[3:].reshape(3, 3)) for row in rows]
    P = np.array([q for q, _ in poses], dtype=np.float64).reshape(-1, 3)
    R = np.array([r @ start_rot for _, r in poses]).reshape(-1, 3, 3)
    return PlanResult(
        path=P, solved=bool(exact), exact=bool(exact), valid=bool(exact), planner=planner,
        motion=f"discrete {space}", time=_time.perf_counter() - t0, solve_time=solve_time,
        n_states=len(P), status=status.asString(), state_checks=0, motion_checks=0,
        simplified=simplified,
        orientations=Rotation.from_matrix(R).as_quat() if len(R) else np.zeros((0, 4)))
