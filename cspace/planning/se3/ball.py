""""No path" over every orientation: the ball inside the robot that no turn changes.

If a closed part of the robot holds the ball ``B(c, r)`` about its reference point ``c``, the
robot holds that ball at *every* orientation (a turn about ``c`` maps the ball onto itself).
So wherever the robot passes, turning as it likes, the ball passes by translation alone; when
the ball cannot get from start to goal, neither can the robot, however it turns. A convex
polytope inside the ball (an icosphere, its vertices within ``r``) is smaller still, so a proof
that *it* has no translation path (:func:`cspace.planning.decide.decide`, exact) is a proof
for the robot over all rotations, for clearances above the decision's bound.

:func:`no_path_at_any_orientation` makes that proof or returns None. It can only succeed where
the robot's fat core is what blocks (a cage whose slot is narrower than the robot's core);
a thin robot (a stick) holds only a small ball and gets no proof this way.
"""

from __future__ import annotations

import dataclasses

import numpy as np

from ...mesh.query import MeshCO
from .clearance import _parts

__all__ = ["inscribed_radius", "ball_decision", "no_path_at_any_orientation"]


def inscribed_radius(scene) -> float:
    """The radius of a ball about the reference point held by the robot's closed parts
    (rounded down, so the ball is inside), or 0 when the reference point is not inside them."""
    c = np.asarray(scene.reference_point, dtype=np.float64)
    _, (W, closed) = _parts(scene.robot.vertices, scene.robot.faces)
    if not len(closed):
        return 0.0
    solid = MeshCO(W, closed, name=scene.robot.name)
    if not solid.contains(c[None])[0]:
        return 0.0
    d = float(solid.distance(c[None])[0])
    # The float distance errs by a few ulps of the coordinates: take a margin far above that.
    scale = float(np.abs(W).max()) + float(np.abs(c).max())
    return max(0.0, d * (1 - 1e-9) - 1e-12 * scale)


def ball_scene(scene, r: float):
    """The scene with its robot replaced by an icosphere (80 triangles) inside ``B(c, r)``."""
    import trimesh

    from ...scene.scene import Body

    s = trimesh.creation.icosphere(subdivisions=1)
    V = np.asarray(s.vertices, dtype=np.float64)
    V = V / np.linalg.norm(V, axis=1).max() * r * (1 - 1e-9)  # every vertex inside the ball
    c = np.asarray(scene.reference_point, dtype=np.float64)
    robot = Body(f"ball of radius {r:.4g} inside {scene.robot.name}", V + c,
                 np.asarray(s.faces, dtype=np.int64), "inscribed ball")
    return dataclasses.replace(scene, robot=robot)


def ball_decision(scene, *, time: float, bounds=None, cache=None, memory=None):
    """The translation decision (:func:`cspace.planning.decide.decide`) for the ball inside
    the robot (module docstring), or None when the robot holds no ball about its reference
    point or ``time`` is spent first. Its ``'no path'`` is a proof over all orientations
    (:func:`no_path_at_any_orientation`); its ``'path'`` shows where a passage is (the turning
    stage looks for a tunnel along it: :mod:`cspace.planning.se3.tunnel`). ``time`` bounds the
    build and the decision."""
    import time as _time

    from ...scene.model import CSpace
    from ..decide import decide

    r = inscribed_radius(scene)
    if r <= 0 or time <= 0:
        return None
    t0 = _time.perf_counter()
    ball = ball_scene(scene, r)
    cs = CSpace.from_scene(ball, cache=cache, memory=memory)
    left = time - (_time.perf_counter() - t0)
    if left <= 0:
        return None
    b = np.asarray(scene.bounds if bounds is None else bounds, dtype=np.float64)
    d = decide(cs, np.asarray(scene.start, float), np.asarray(scene.goal, float), bounds=b,
               time=left)
    return dataclasses.replace(d, reason=f"{d.reason}; for a ball of radius {r:.4g} about the "
                               "reference point, inside the robot at every orientation")


def no_path_at_any_orientation(scene, *, time: float, bounds=None, cache=None, memory=None):
    """:func:`ball_decision` when it is ``'no path'`` (a proof over all orientations), else
    None."""
    d = ball_decision(scene, time=time, bounds=bounds, cache=cache, memory=memory)
    return d if d is not None and d.answer == "no path" else None
