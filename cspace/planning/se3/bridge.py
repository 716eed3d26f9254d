"""Passages a sampler misses: translate through at one orientation, turn where there is room.

A sampling planner in SE(3) rarely draws a pose inside a passage the robot fits through only
at one orientation and only by translating (a plate through a slot, on edge). At a fixed
orientation, though, the translational C-space is exact, and :func:`cspace.planning.decide.decide`
finds a path through such a passage or proves there is none. :func:`slice_bridge` tries the
orientations where walls usually want the robot (its axes along the walls' frame, its own start
axes or the world's: the cube's 24 rotations each way, and the goal's), nearest the start first: at each
where start and goal positions are free, it decides the translation from start to goal, and
joins a path found to the start and goal poses by turns (a turn in place when it is certified,
else :func:`cspace.planning.se3.plan.plan_se3` between the two poses).

Every motion of the joined path is then re-certified by clearance
(:func:`cspace.planning.se3.plan.certify_path`), like any SE(3) path: the translational
C-space only finds it.
"""

from __future__ import annotations

import time as _time

import numpy as np

from ..decide import decide
from ..orientations import Orientations
from ..solve import PlanResult
from .clearance import PoseClearance
from .plan import _world_quaternions, certify_path, plan_se3, relative_goal

__all__ = ["slice_bridge"]


def _joined(poses, scene, a, b, *, time: float, seed, bounds) -> tuple | None:
    """Poses ``(P, Q)`` from pose ``a`` to pose ``b`` (each ``(q, Q)``): the direct motion when
    it is certified, else an SE(3) plan within ``time``; None when neither."""
    free, _, _ = poses.motion_free(a[0], a[1], b[0], b[1])
    if free:
        return np.array([a[0], b[0]]), np.array([a[1], b[1]])
    if time <= 0:
        return None
    r = plan_se3(scene, time=time, seed=seed, bounds=bounds, poses=poses, start=a, goal=b)
    if not r.solved:
        return None
    from scipy.spatial.transform import Rotation

    rel = (Rotation.from_quat(r.orientations)
           * Rotation.from_matrix(np.asarray(scene.start_rotation)).inv()).as_quat()
    return r.path, rel


def _walls_frame(scene) -> np.ndarray:
    """The frame the obstacles' faces are square to (most of their normals along its axes:
    :func:`cspace.planning.cells.frame_of_normals`), the world's when none beats it."""
    from ..cells import frame_of_normals

    N = []
    for body in scene.obstacles:
        T = np.asarray(body.vertices, dtype=np.float64)[np.asarray(body.faces)]
        n = np.cross(T[:, 1] - T[:, 0], T[:, 2] - T[:, 0])
        length = np.linalg.norm(n, axis=1)
        N.append(n[length > 0] / length[length > 0, None])
    W = frame_of_normals(np.concatenate(N)) if N else None
    return np.eye(3) if W is None else W


def _candidates(scene, goal: np.ndarray) -> tuple[Orientations, np.ndarray]:
    """The identity, the goal and the rotations that put the robot's own axes along the
    walls' frame ``W`` (``W C S^T`` for the cube's 24 rotations ``C``, ``S`` the start
    orientation), along its own start axes (``S C S^T``: walls square to the robot's start)
    or along the world's (``C S^T``), relative to the start, duplicates dropped; and each
    one's rank for the order of trial (0 the identity and the goal, then by family)."""
    from scipy.spatial.transform import Rotation

    from ..orientations import _cube_rotations

    S = np.asarray(scene.start_rotation, dtype=np.float64)
    W = _walls_frame(scene)
    C = _cube_rotations()
    cand = np.concatenate([np.eye(3)[None], goal[None], W @ C @ S.T, S @ C @ S.T, C @ S.T])
    family = np.concatenate([[0, 0], np.full(len(C), 1), np.full(len(C), 2), np.full(len(C), 3)])
    Q = Rotation.from_matrix(cand).as_quat()
    keep: list[int] = []
    for i, q in enumerate(Q):
        if not keep or np.abs(Q[keep] @ q).max() < 1 - 1e-15:
            keep.append(i)
    R = cand[keep]
    R[0] = np.eye(3)
    links = tuple(tuple(j for j in range(len(R)) if j != i) for i in range(len(R)))
    g = int(np.argmax(np.abs(Q[keep] @ Rotation.from_matrix(goal).as_quat())))
    return Orientations(R, links, g), family[keep]


def slice_bridge(scene, *, time: float, seed=None, bounds=None, cache=None, memory=None,
                 poses: PoseClearance | None = None, skip=(), done: set | None = None
                 ) -> PlanResult | None:
    """A certified SE(3) path through a passage taken at one fixed orientation (module
    docstring), or None when none is found within ``time`` seconds.

    Parameters
    ----------
    scene : Scene
    time : float
        Wall-second budget for all of it (builds of the orientations' C-spaces included).
    seed : int, optional
        For the SE(3) plans of turns that are not certified in place.
    bounds : (2, 3) float64, optional
        Default the scene's.
    cache, memory
        As :class:`cspace.planning.turning.TurningCSpace`'s (each orientation's C-space is
        built through the scene model and the disk cache, within one memory budget).
    poses : PoseClearance, optional
    skip : iterable of (4,) float64
        Relative orientations (unit quaternions) already decided (the start's, by the
        translational stage): not tried again.
    done : set, optional
        The candidates' indices decided so far (no path, or a path that could not be joined):
        updated, and skipped by a later call given the same set.

    Returns
    -------
    PlanResult or None
        ``planner='bridge'``; ``certified`` as :func:`plan_se3`'s, with ``'orientation'``: the
        relative rotation of the passage (a quaternion).
    """
    from ..turning import TurningCSpace

    t0 = _time.perf_counter()
    b = np.asarray(scene.bounds if bounds is None else bounds, dtype=np.float64).reshape(2, 3)
    poses = poses if poses is not None else PoseClearance(scene, b)
    Qg = relative_goal(scene)
    from scipy.spatial.transform import Rotation

    orients, family = _candidates(scene, Rotation.from_quat(Qg).as_matrix())
    quats = Rotation.from_matrix(orients.rotations).as_quat()
    # Nearest the start and goal orientations first (the least turning), the walls' frame
    # before the robot's and the world's at equal turning.
    cost = [round(min(2 * np.arccos(min(1.0, abs(float(q @ ref)))) for ref in ((0, 0, 0, 1.0), Qg)), 9)
            for q in quats]
    order = [k for k in np.lexsort((family, cost)).tolist()
             if not any(abs(float(quats[k] @ np.asarray(s))) > 1 - 1e-12 for s in skip)
             and k not in (done if done is not None else ())]
    done = done if done is not None else set()
    tcs = TurningCSpace(scene, orients, cache=cache, memory=memory)
    q0, q1 = np.asarray(scene.start, dtype=np.float64), np.asarray(scene.goal, dtype=np.float64)
    I = np.array([0.0, 0.0, 0.0, 1.0])
    build = 0.0  # the longest a slice's C-space took to build: none is started without it
    for n, k in enumerate(order):
        left = time - (_time.perf_counter() - t0)
        if left <= build:
            break
        Qk, Rk = quats[k], orients.rotations[k]
        if not (poses.pose_free(q0, Rk) and poses.pose_free(q1, Rk)):
            done.add(k)
            continue  # this orientation does not fit at the start or the goal
        tb = _time.perf_counter()
        cs = tcs.slice(k)
        build = max(build, _time.perf_counter() - tb)
        left = time - (_time.perf_counter() - t0)
        if left <= 0:
            break
        # Each orientation at least a quarter of what is left: a passage found late is not
        # lost to the first orientations' long undecided searches.
        d = decide(cs, q0, q1, bounds=b, time=left / min(4, len(order) - n))
        if d.answer != "unknown":
            done.add(k)
        if d.answer != "path":
            continue
        left = time - (_time.perf_counter() - t0)
        head = _joined(poses, scene, (q0, I), (q0, Qk), time=left / 2, seed=seed, bounds=b)
        if head is None:
            continue
        left = time - (_time.perf_counter() - t0)
        tail = _joined(poses, scene, (q1, Qk), (q1, Qg), time=left, seed=seed, bounds=b)
        if tail is None:
            continue
        P = np.concatenate([head[0], d.path[1:-1], tail[0]])
        Q = np.concatenate([head[1], np.tile(Qk, (len(d.path) - 2, 1)), tail[1]])
        report = certify_path(poses, P, Q)
        if not report["valid"]:
            continue
        return PlanResult(
            path=P, solved=True, exact=True, valid=True, planner="bridge",
            motion="certified SE(3)", time=_time.perf_counter() - t0, solve_time=d.time,
            n_states=len(P), status="Exact solution", state_checks=0,
            motion_checks=report["motions"], simplified=False,
            orientations=_world_quaternions(scene, Q),
            certified={"motions": report["motions"], "queries": report["queries"],
                       "max_depth": report["max_depth"], "error_bound": poses.error_bound,
                       "rho": poses.rho, "orientation": Qk.tolist()})
    return None
