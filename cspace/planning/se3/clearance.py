"""A scene's robot at any pose: free or not, and certified motions between poses.

:class:`PoseClearance` joins the distance kernel (:class:`cspace.geometry.clearance.MeshClearance`,
robot triangles against every obstacle triangle of the raw scene) to containment (a robot part
wholly inside a closed obstacle body, or an obstacle part inside the robot's closed parts, is
at a positive distance and yet collides: decided by the exact winding number of
:class:`cspace.mesh.query.MeshCO`).

A pose is ``(q, R)``: the rotation ``R`` (relative to the scene's start orientation, which
:attr:`cspace.Scene.robot` already has) about the reference point ``c``, placed at ``q``; the
robot occupies ``R (v - c) + q`` (as :func:`cspace.check.cross_check.pose_path_collisions`).

Free means: ``q`` within the bounds, the clearance's lower bound positive (no robot triangle
within ``error_bound`` of an obstacle triangle), and no containment. A certified motion keeps
the clearance positive all along, so nothing crosses a surface on the way: what is inside what
is the same at both ends (one end free, the other is).
"""

from __future__ import annotations

import math

import numpy as np

from ...geometry.clearance import MeshClearance
from ...geometry.graphs import component_labels
from ...mesh.components import unique_rows
from ...mesh.query import MeshCO, unbalanced_edge

__all__ = ["PoseClearance", "quaternion_matrix"]


def quaternion_matrix(Q) -> np.ndarray:
    """``(3, 3)`` rotation of a unit quaternion ``(x, y, z, w)`` (normalised first)."""
    x, y, z, w = (float(v) for v in Q)
    n = math.sqrt(x * x + y * y + z * z + w * w)
    x, y, z, w = x / n, y / n, z / n, w / n
    return np.array([[1 - 2 * (y * y + z * z), 2 * (x * y - z * w), 2 * (x * z + y * w)],
                     [2 * (x * y + z * w), 1 - 2 * (x * x + z * z), 2 * (y * z - x * w)],
                     [2 * (x * z - y * w), 2 * (y * z + x * w), 1 - 2 * (x * x + y * y)]])


def _parts(V: np.ndarray, F: np.ndarray):
    """``(points, closed)``: one vertex of each connected part of the triangles (vertices at
    the same coordinates are one), and the faces of the closed parts (every directed edge
    balanced by its reverse), on the welded vertex indices, with the welded vertices."""
    V = np.asarray(V, dtype=np.float64).reshape(-1, 3)
    F = np.asarray(F, dtype=np.int64).reshape(-1, 3)
    W, _, inverse = unique_rows(V)
    F = inverse[F]
    n, label = component_labels(len(W), np.concatenate([F[:, 0], F[:, 1]]),
                                 np.concatenate([F[:, 1], F[:, 2]]))
    used = np.unique(F)
    _, first = np.unique(label[used], return_index=True)
    points = W[used[first]]
    face_part = label[F[:, 0]]
    closed = [F[face_part == p] for p in np.unique(face_part).tolist()
              if unbalanced_edge(F[face_part == p], len(W)) is None]
    return points, (W, np.concatenate(closed) if closed else np.zeros((0, 3), np.int64))


class PoseClearance:
    """Free poses and certified motions of ``scene``'s robot (module docstring).

    Parameters
    ----------
    scene : Scene
    bounds : (2, 3) float64, optional
        Where the reference point may be; default ``scene.bounds``.

    Attributes
    ----------
    clearance : MeshClearance
        Its ``error_bound`` (absolute, scene units) is the most a free pose's or a certified
        motion's clearance may be short of the truth: a pose nearer than that to an obstacle
        may be called not free, never the reverse.
    """

    def __init__(self, scene, bounds=None):
        self.scene = scene
        b = np.asarray(scene.bounds if bounds is None else bounds, dtype=np.float64)
        self.bounds = b.reshape(2, 3)
        self._lo, self._hi = self.bounds[0].tolist(), self.bounds[1].tolist()
        c = np.asarray(scene.reference_point, dtype=np.float64)
        self.reference_point = c
        OV, OF, off = [], [], 0
        for body in scene.obstacles:
            OV.append(body.vertices)
            OF.append(np.asarray(body.faces, dtype=np.int64) + off)
            off += len(body.vertices)
        RV = np.asarray(scene.robot.vertices, dtype=np.float64) - c
        self.clearance = MeshClearance(np.concatenate(OV), np.concatenate(OF), RV,
                                       scene.robot.faces,
                                       reach=float(np.abs(self.bounds).max()))
        # Containment: closed obstacle bodies (one winding number each: a cavity stays free)
        # against a point of each robot part; the robot's closed parts against a point of each
        # obstacle part.
        self._solids = []
        points = []
        for body in scene.obstacles:
            p, (W, closed) = _parts(body.vertices, body.faces)
            points.append(p)
            if len(closed):
                self._solids.append((body.name, MeshCO(W, closed, name=body.name),
                                     W[closed].reshape(-1, 3).min(axis=0),
                                     W[closed].reshape(-1, 3).max(axis=0)))
        self._obstacle_points = np.concatenate(points)
        self._obstacles_lo = self._obstacle_points.min(axis=0)
        self._obstacles_hi = self._obstacle_points.max(axis=0)
        self._robot_points, (W, closed) = _parts(RV, scene.robot.faces)
        self._robot_solid = MeshCO(W, closed, name=scene.robot.name) if len(closed) else None

    def __repr__(self) -> str:
        return (f"PoseClearance({self.scene.name!r}, {self.clearance!r}, "
                f"closed obstacle bodies={len(self._solids)})")

    @property
    def error_bound(self) -> float:
        return self.clearance.error_bound

    @property
    def rho(self) -> float:
        return self.clearance.rho

    def in_bounds(self, q) -> bool:
        lo, hi = self._lo, self._hi
        x, y, z = (float(v) for v in q)
        return lo[0] <= x <= hi[0] and lo[1] <= y <= hi[1] and lo[2] <= z <= hi[2]

    def contained(self, q, R) -> str | None:
        """The name of a closed obstacle body holding a robot part at ``(q, R)``, or of the
        robot when its closed parts hold an obstacle part; None when neither. Meaningful where
        the clearance is positive (a part is then wholly inside or wholly outside)."""
        q = np.asarray(q, dtype=np.float64)
        R = np.asarray(R, dtype=np.float64).reshape(3, 3)
        P = None
        for name, solid, lo, hi in self._solids:
            # the robot's ball about q misses the body's box: nothing of it is inside
            if ((q + self.rho < lo) | (q - self.rho > hi)).any():
                continue
            P = self._robot_points @ R.T + q if P is None else P
            near = ((lo <= P) & (P <= hi)).all(axis=1)
            if near.any() and solid.contains(np.ascontiguousarray(P[near])).any():
                return name
        if self._robot_solid is not None and not (
                (q + self.rho < self._obstacles_lo) | (q - self.rho > self._obstacles_hi)).any():
            near = np.linalg.norm(self._obstacle_points - q, axis=1) <= self.rho
            if near.any():
                local = (self._obstacle_points[near] - q) @ R  # R^T (p - q)
                if self._robot_solid.contains(np.ascontiguousarray(local)).any():
                    return self.scene.robot.name
        return None

    def pose_free(self, q, R) -> bool:
        """Whether the robot at ``(q, R)`` is certainly free (module docstring)."""
        if not self.in_bounds(q):
            return False
        if not self.clearance.lower_bound(R, q, cap=self.error_bound) > 0:
            return False
        return self.contained(q, R) is None

    def motion_free(self, q0, Q0, q1, Q1, *, max_depth: int = 40,
                    from_free: bool = False) -> tuple[bool, int, int]:
        """:meth:`cspace.geometry.clearance.MeshClearance.motion_free` (both ends in the bounds,
        a box: the straight segment stays in them), and no containment at the end ``q1``.
        ``from_free``: the caller knows the start pose free (a planner's tree state), so the
        end, reached without touching anything, is free too: containment is not asked."""
        if not (self.in_bounds(q0) and self.in_bounds(q1)):
            return False, 0, 0
        free, depth, n = self.clearance.motion_free(q0, Q0, q1, Q1, max_depth=max_depth)
        if free and not from_free and self.contained(q1, quaternion_matrix(Q1)) is not None:
            return False, depth, n
        return free, depth, n
