"""Tunnels a sampler misses: a key pose inside a narrow passage, found along the ball's path.

A long robot (a stick) leaves a trap only through its tunnel, and only along the tunnel's
axis: sampling in SE(3) almost never draws a pose inside it. The ball inside the robot passes
by translation alone (:func:`cspace.planning.se3.ball.ball_decision` finds its path). Along that
path, :func:`key_poses` lays the robot's longest axis along a fixed set of directions at each
point: where only a narrow cone of directions is free, the point is in a tunnel and the cone's
axis is the tunnel's; the robot laid along that axis there is a *key pose*.
:func:`tunnel_path` then walks the robot out of the tunnel along its axis on both sides
(certified straight motions, until the clearance opens up) and joins the two mouths to the
start and the goal with :func:`cspace.planning.se3.plan.plan_se3`, each an easier problem than
the whole. Every motion of the joined path is re-certified
(:func:`cspace.planning.se3.plan.certify_path`): the heuristics only find it.
"""

from __future__ import annotations

import time as _time

import numpy as np

from ..solve import PlanResult
from .clearance import PoseClearance
from .plan import _world_quaternions, certify_path, plan_se3, relative_goal

__all__ = ["key_poses", "tunnel_path", "DIRECTIONS", "NARROW"]

#: Directions tried at each point of the guide (a Fibonacci half-sphere: the robot's axis
#: either way is tried as its own direction and the reverse).
DIRECTIONS = 1024
#: A point is in a tunnel when the robot is free along at most this fraction of the
#: directions (and along at least one).
NARROW = 0.03


def _half_sphere(n: int) -> np.ndarray:
    """``(n, 3)`` unit vectors spread over the half-sphere ``z >= 0`` (a Fibonacci lattice)."""
    k = np.arange(n) + 0.5
    z = k / n
    r = np.sqrt(1 - z * z)
    phi = k * np.pi * (3 - np.sqrt(5))
    return np.stack([r * np.cos(phi), r * np.sin(phi), z], axis=1)


def _align(e: np.ndarray, d: np.ndarray) -> np.ndarray:
    """A rotation taking unit vector ``e`` to unit vector ``d`` (the shortest arc)."""
    from scipy.spatial.transform import Rotation

    return Rotation.align_vectors([d], [e])[0].as_matrix()


def _long_axis(scene) -> np.ndarray:
    """The robot's longest principal axis (world frame, its start orientation)."""
    V = np.asarray(scene.robot.vertices, dtype=np.float64)
    return np.linalg.eigh(np.cov((V - V.mean(axis=0)).T))[1][:, -1]


def key_poses(scene, poses: PoseClearance, guide, *, step: float | None = None,
              time: float = np.inf, limit: int = 3) -> list:
    """Up to ``limit`` key poses ``(q, R, axis)`` along ``guide`` (module docstring), the
    narrowest first (fewest free directions): ``q`` a point of the guide, ``R`` the rotation
    (relative to the start) laying the robot's longest axis along ``axis`` (unit), the robot
    free there. ``step``: spacing of the points tried (default a tenth of the robot's
    reach); ``time``: seconds for the scan."""
    t0 = _time.perf_counter()
    P = np.asarray(guide, dtype=np.float64).reshape(-1, 3)
    if len(P) < 2:
        return []
    step = step if step is not None else poses.rho / 10
    pts = np.concatenate([np.linspace(a, b, max(2, int(np.linalg.norm(b - a) / step) + 1))
                          for a, b in zip(P[:-1], P[1:])])
    e = _long_axis(scene)
    D = _half_sphere(DIRECTIONS)
    Rs = [_align(e, s * d) for d in D for s in (1.0, -1.0)]
    found = []
    for x in pts:
        if _time.perf_counter() - t0 > time:
            break
        free = np.array([poses.pose_free(x, R) for R in Rs]).reshape(-1, 2).any(axis=1)
        n = int(free.sum())
        if not 0 < n <= NARROW * len(D):
            continue
        F = D[free]
        axis = np.linalg.eigh(F.T @ F)[1][:, -1]  # the free cone's axis (sign free)
        for s in (1.0, -1.0):
            R = _align(e, s * axis)
            if poses.pose_free(x, R):
                found.append((n, x, R, s * axis))
                break
    found.sort(key=lambda f: f[0])
    out: list = []
    for n, x, R, axis in found:  # distinct tunnels: axes or points apart
        if all(abs(float(axis @ a)) < np.cos(np.radians(5)) or np.linalg.norm(x - y) > poses.rho
               for y, _, a in out):
            out.append((x, R, axis))
        if len(out) == limit:
            break
    return out


def _walk(poses: PoseClearance, x, Q, u, *, step: float, open_: float, reach: float):
    """From the free pose ``(x, Q)`` along ``u`` by ``step`` while each straight motion is
    certified, until the clearance reaches ``open_`` or the walk ``reach``: the last pose."""
    from .clearance import quaternion_matrix

    R = quaternion_matrix(Q)
    y, walked = np.asarray(x, dtype=np.float64), 0.0
    while walked < reach:
        z = y + step * u
        if not poses.motion_free(y, Q, z, Q, from_free=True)[0]:
            break
        y, walked = z, walked + step
        if poses.clearance.lower_bound(R, y, cap=open_) >= open_:
            break
    return y


def tunnel_path(scene, *, time: float, guide, seed=None, bounds=None,
                poses: PoseClearance | None = None) -> PlanResult | None:
    """A certified SE(3) path through a tunnel found along ``guide`` (module docstring), or
    None within ``time`` seconds.

    Parameters
    ----------
    scene : Scene
    time : float
        Wall seconds for all of it (the scan, the walks and the two SE(3) plans).
    guide : (n, 3) float64
        A path of the reference point where the ball inside the robot passes.
    seed : int, optional
        For the SE(3) plans.
    bounds : (2, 3) float64, optional
    poses : PoseClearance, optional

    Returns
    -------
    PlanResult or None
        ``planner='tunnel'``; ``certified`` as :func:`plan_se3`'s, with ``'key pose'``.
    """
    from scipy.spatial.transform import Rotation

    t0 = _time.perf_counter()
    b = np.asarray(scene.bounds if bounds is None else bounds, dtype=np.float64).reshape(2, 3)
    poses = poses if poses is not None else PoseClearance(scene, b)
    q0, q1 = np.asarray(scene.start, dtype=np.float64), np.asarray(scene.goal, dtype=np.float64)
    I, Qg = np.array([0.0, 0.0, 0.0, 1.0]), relative_goal(scene)
    keys = key_poses(scene, poses, guide, time=0.3 * time)
    for x, R, axis in keys:
        Qk = Rotation.from_matrix(R).as_quat()
        # the mouths: out along the axis on the start's side and on the goal's
        u = axis if float(axis @ (q0 - x)) > 0 else -axis
        kw = {"step": poses.rho / 20, "open_": poses.rho / 4, "reach": 4 * poses.rho}
        a = _walk(poses, x, Qk, u, **kw)
        z = _walk(poses, x, Qk, -u, **kw)
        left = time - (_time.perf_counter() - t0)
        if left <= 0:
            break
        head = plan_se3(scene, time=left / 2, seed=seed, bounds=b, poses=poses,
                        start=(q0, I), goal=(a, Qk))
        if not head.solved:
            continue
        left = time - (_time.perf_counter() - t0)
        tail = plan_se3(scene, time=left, seed=seed, bounds=b, poses=poses,
                        start=(z, Qk), goal=(q1, Qg))
        if not tail.solved:
            continue
        start_rot = Rotation.from_matrix(np.asarray(scene.start_rotation)).inv()
        rel = [(Rotation.from_quat(r.orientations) * start_rot).as_quat() for r in (head, tail)]
        P = np.concatenate([head.path, [x], tail.path])
        Q = np.concatenate([rel[0], [Qk], rel[1]])
        report = certify_path(poses, P, Q)
        if not report["valid"]:
            continue
        return PlanResult(
            path=P, solved=True, exact=True, valid=True, planner="tunnel",
            motion="certified SE(3)", time=_time.perf_counter() - t0,
            solve_time=head.solve_time + tail.solve_time, n_states=len(P),
            status="Exact solution", state_checks=0, motion_checks=report["motions"],
            simplified=False, orientations=_world_quaternions(scene, Q),
            certified={"motions": report["motions"], "queries": report["queries"],
                       "max_depth": report["max_depth"], "error_bound": poses.error_bound,
                       "rho": poses.rho, "key pose": [x.tolist(), Qk.tolist()]})
    return None
