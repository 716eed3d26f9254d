"""A robot that turns: orientation slices, certified turns in place, and their C-space.

Translational C-obstacles answer "is the robot free at ``q``" for one orientation. A robot
that must turn is planned over a finite set of orientations (:class:`Slices`: angles about
one axis through the reference point, the start's angle 0 and the goal's included). Two
kinds of motion are certified, exactly and conservatively:

- a **translation** within slice ``k``: the segment misses the C-obstacles of the robot at
  ``k`` (:meth:`cspace.CSpace.segment_free`, as for a robot that does not turn);
- a **turn in place** at ``q`` between neighbouring slices ``i``, ``j`` (rotation by
  ``alpha`` about the axis through the reference point): every point ``p`` of the robot
  moves on a circular arc of radius ``r <= |p - c|`` that stays within the sagitta
  ``r (1 - cos(alpha / 2))`` of its chord, so the swept robot lies in
  ``conv(R_i ∪ R_j)`` grown by that much. :func:`swept_points` returns the points of that
  grown hull, per connected part of the robot; the turn is free at ``q`` when ``q`` lies in
  none of the C-obstacles of those convex robots (:class:`TurningCSpace`).

Both C-space families are built lazily, the first time a query enters a slice or a turn,
through the same modelling and disk cache as a scene's C-obstacles
(:func:`cspace.model.model_scene`): C-obstacles are conservative (errors are false
collisions within ``error_bound``, never false free), so a certified motion is free.

Frames: the robot's vertices are in its own frame with the scene's start orientation
applied (:class:`cspace.Scene`); slice ``k`` turns them by ``angles[k]`` about ``axis``
through ``scene.reference_point``. The robot of slice ``k`` *is* those float64 vertices;
the turn's growth also covers their rounding (:func:`swept_points`).
"""

from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass

import numpy as np

from .errors import InvalidArgumentError
from .transform import axis_angle, transform

__all__ = ["Slices", "swept_points", "TurningCSpace"]

# Relative slack over the float64 rounding of a rotated point (Rodrigues' matrix and the
# product each err by a few ulps, 2**-52 each): 2**-40 covers them a thousand times over.
_ROUNDING = 2.0**-40


@dataclass(frozen=True)
class Slices:
    """Orientations about one axis: the robot turned by ``angles[k]`` radians.

    Attributes
    ----------
    axis : (3,) float64
        Unit axis (world frame) through the robot's reference point.
    angles : (n,) float64
        Sorted, distinct, in ``[0, 2 pi)``; ``angles[0] == 0`` is the start orientation.
        Neighbours are consecutive angles, cyclically.
    goal : int
        The slice of the goal orientation.
    """

    axis: np.ndarray
    angles: np.ndarray
    goal: int = 0

    def __post_init__(self):
        axis = np.asarray(self.axis, dtype=np.float64).reshape(3)
        norm = float(np.linalg.norm(axis))
        if not (np.isfinite(axis).all() and norm > 0):
            raise InvalidArgumentError(f"slices: the axis must be a finite non-zero vector, got {axis.tolist()}")
        angles = np.asarray(self.angles, dtype=np.float64).reshape(-1)
        if (len(angles) < 2 or angles[0] != 0.0 or not (np.diff(angles) > 0).all()
                or angles[-1] >= 2 * math.pi):
            raise InvalidArgumentError("slices: angles must start at 0, increase strictly and "
                                       f"stay below 2 pi, got {angles.tolist()}")
        gaps = np.diff(np.append(angles, 2 * math.pi))
        if gaps.max() > math.pi:  # the arcs stay within their sagitta of the chord up to pi
            raise InvalidArgumentError("slices: neighbouring angles must be at most pi apart, "
                                       f"got a gap of {math.degrees(gaps.max()):.6g} deg")
        if not 0 <= self.goal < len(angles):
            raise InvalidArgumentError(f"slices: goal {self.goal} is not a slice of {len(angles)}")
        object.__setattr__(self, "axis", axis / norm)
        object.__setattr__(self, "angles", angles)

    @classmethod
    def about(cls, n: int, *, axis=(0.0, 0.0, 1.0), goal_angle: float = 0.0) -> "Slices":
        """``n`` equal steps of ``2 pi / n`` about ``axis`` from the start orientation, plus
        the goal's angle (radians) when it is not one of them."""
        if int(n) != n or n < 2:
            raise InvalidArgumentError(f"slices: need at least 2 orientations, got {n!r}")
        g = float(goal_angle) % (2 * math.pi)
        steps = 2 * math.pi * np.arange(int(n)) / int(n)
        near = np.abs(steps - g)
        near = np.minimum(near, 2 * math.pi - near)
        if near.min() <= 1e-12:  # the goal is a step (up to the rounding of 2 pi k / n)
            return cls(axis, steps, int(np.argmin(near)))
        angles = np.sort(np.append(steps, g))
        return cls(axis, angles, int(np.searchsorted(angles, g)))

    def __len__(self) -> int:
        return len(self.angles)

    def __repr__(self) -> str:
        return (f"Slices({len(self)} about {np.round(self.axis, 6).tolist()}, "
                f"goal slice {self.goal} at {math.degrees(self.angles[self.goal]):.6g} deg)")

    def rotation(self, k: int) -> np.ndarray:
        """``(3, 3)`` rotation of slice ``k`` (float64)."""
        return axis_angle(self.axis, float(self.angles[k]))

    def step(self, i: int, j: int) -> float:
        """The angle (radians, > 0) of the turn between neighbours ``i`` and ``j``."""
        n = len(self)
        if (j - i) % n == 1:
            a, b = i, j
        elif (i - j) % n == 1:
            a, b = j, i
        else:
            raise InvalidArgumentError(f"slices {i} and {j} are not neighbours")
        d = float(self.angles[b] - self.angles[a])
        return d if d > 0 else d + 2 * math.pi

    def way(self, i: int, j: int) -> list[int]:
        """The slices from ``i`` to ``j`` through neighbours, the shorter way round (``[i]``
        when equal; ties go up)."""
        n = len(self)
        up, down = (j - i) % n, (i - j) % n
        if up <= down:
            return [(i + s) % n for s in range(up + 1)]
        return [(i - s) % n for s in range(down + 1)]


def _turned(vertices: np.ndarray, c: np.ndarray, R: np.ndarray) -> np.ndarray:
    return transform(np.asarray(vertices, dtype=np.float64) - c, R, c)


def swept_points(vertices: np.ndarray, reference_point, slices: Slices, i: int,
                 j: int) -> np.ndarray:
    """Points whose convex hull holds the robot's part ``vertices`` (robot frame) at every
    instant of the turn in place from slice ``i`` to its neighbour ``j``.

    The hull of the part at ``i`` and at ``j`` (their float64 vertices) grown by the cube of
    half-side ``h = r (1 - cos(alpha / 2)) + e``: ``r`` the largest distance of a vertex from
    the reference point (the arcs' radii are at most that), ``alpha`` the turn's angle,
    ``e`` a bound on the rounding of the turned vertices. The cube holds the ball of radius
    ``h``, so the arcs (within their sagitta of their chords) are inside. Returns
    ``(16 m, 3)`` float64: each vertex at both ends, moved to the cube's 8 corners (the
    additions rounded outward by the slack in ``h``).
    """
    V = np.asarray(vertices, dtype=np.float64)
    c = np.asarray(reference_point, dtype=np.float64)
    alpha = slices.step(i, j)
    ends = np.vstack([_turned(V, c, slices.rotation(i)), _turned(V, c, slices.rotation(j))])
    r = float(np.sqrt(((V - c) ** 2).sum(axis=1)).max())
    size = max(float(np.abs(ends).max()), float(np.abs(c).max()), r)
    sagitta = r * (1.0 - math.cos(alpha / 2.0))
    h = (sagitta + r * 4 * _ROUNDING) * (1.0 + _ROUNDING) + size * _ROUNDING
    corners = np.array([[sx, sy, sz] for sx in (-h, h) for sy in (-h, h) for sz in (-h, h)])
    return (ends[:, None, :] + corners[None, :, :]).reshape(-1, 3)


class TurningCSpace:
    """The C-space of a scene's robot over orientation slices, built lazily.

    Parameters
    ----------
    scene : Scene
        Obstacles, robot (start orientation applied), reference point, bounds.
    slices : Slices
    cache : COCache, path, True, or None
        The disk cache every slice's and turn's C-obstacles go through
        (:func:`cspace.model.model_scene`).
    robot_hull : bool, default False
        Slices against the robot's convex hull instead of its exact parts.

    Attributes
    ----------
    built_slices, built_turns : dict
        The C-spaces made so far: ``{k: CSpace}``, ``{(i, j): CSpace}`` with ``i < j``
        (a turn's C-space serves both directions).
    """

    def __init__(self, scene, slices: Slices, *, cache=None, robot_hull: bool = False):
        self.scene = scene
        self.slices = slices
        self.cache = cache
        self.robot_hull = bool(robot_hull)
        self.bounds = np.asarray(scene.bounds, dtype=np.float64)
        self.built_slices: dict = {}
        self.built_turns: dict = {}
        self._parts = None

    def __repr__(self) -> str:
        return (f"TurningCSpace({self.scene.name!r}, {self.slices!r}, built: "
                f"{len(self.built_slices)} slices, {len(self.built_turns)} turns)")

    # ---------------------------------------------------------------- building

    def _scene_with(self, name: str, vertices: np.ndarray, faces: np.ndarray):
        from .scene import Body

        robot = Body(name, vertices, faces, self.scene.robot.source)
        return dataclasses.replace(self.scene, robot=robot)

    def _cspace(self, scene, hull: bool):
        from .obstacle import CSpace

        return CSpace.from_scene(scene, cache=self.cache, robot_hull=hull)

    def slice(self, k: int):
        """The :class:`~cspace.CSpace` of the robot at slice ``k`` (built on first use)."""
        k = int(k) % len(self.slices)
        cs = self.built_slices.get(k)
        if cs is None:
            robot = self.scene.robot
            V = _turned(robot.vertices, self.scene.reference_point, self.slices.rotation(k))
            name = f"{robot.name} at {math.degrees(self.slices.angles[k]):.6g} deg"
            cs = self.built_slices[k] = self._cspace(self._scene_with(name, V, robot.faces),
                                                     self.robot_hull)
        return cs

    def _robot_parts(self) -> list[np.ndarray]:
        """The vertices of each connected part of the robot (by shared vertex indices)."""
        if self._parts is None:
            from .graphs import component_labels

            F = self.scene.robot.faces
            used = np.unique(F)
            count, labels = component_labels(len(self.scene.robot.vertices),
                                             F[:, [0, 1, 2]].reshape(-1), F[:, [1, 2, 0]].reshape(-1))
            V = self.scene.robot.vertices
            self._parts = [V[used[labels[used] == k]] for k in np.unique(labels[used])]
        return self._parts

    def turn(self, i: int, j: int):
        """The :class:`~cspace.CSpace` of the turn in place between neighbouring slices
        ``i`` and ``j``: the union over the robot's parts of the C-obstacles of their swept
        hulls (:func:`swept_points`). Built on first use."""
        from scipy.spatial import ConvexHull

        from .obstacle import CSpace

        n = len(self.slices)
        i, j = int(i) % n, int(j) % n
        key = (min(i, j), max(i, j))
        cs = self.built_turns.get(key)
        if cs is None:
            self.slices.step(i, j)  # neighbours, or a named error
            obstacles = []
            for p, V in enumerate(self._robot_parts()):
                P = swept_points(V, self.scene.reference_point, self.slices, *key)
                hull = ConvexHull(P)
                name = (f"{self.scene.robot.name} part {p} turning "
                        f"{math.degrees(self.slices.angles[key[0]]):.6g}-"
                        f"{math.degrees(self.slices.angles[key[1]]):.6g} deg")
                scene = self._scene_with(name, P, _outward(P, hull))
                obstacles += list(self._cspace(scene, True).obstacles)
            cs = self.built_turns[key] = CSpace(obstacles, bounds=self.bounds, name="turn")
        return cs

    # ---------------------------------------------------------------- queries

    def in_bounds(self, q) -> bool:
        q = np.asarray(q, dtype=np.float64)
        return bool((self.bounds[0] <= q).all() and (q <= self.bounds[1]).all())

    def state_free(self, q, k: int) -> bool:
        """The robot at slice ``k`` with its reference point at ``q`` is in bounds and free."""
        return self.in_bounds(q) and not self.slice(k).contains(np.asarray(q, dtype=np.float64))

    def translation_free(self, q0, q1, k: int) -> bool:
        """The straight translation from ``q0`` to ``q1`` at slice ``k`` is free (exact)."""
        return (self.in_bounds(q0) and self.in_bounds(q1)
                and self.slice(k).segment_free(np.asarray(q0, dtype=np.float64),
                                               np.asarray(q1, dtype=np.float64)))

    def turn_free(self, q, i: int, j: int) -> bool:
        """Turning in place at ``q`` from slice ``i`` to ``j`` (the shorter way, through
        neighbours) is free: every step's swept C-obstacles miss ``q``."""
        if not self.in_bounds(q):
            return False
        q = np.asarray(q, dtype=np.float64)
        way = self.slices.way(int(i), int(j))
        return all(not self.turn(a, b).contains(q) for a, b in zip(way, way[1:]))

    def motion_free(self, q0, k0: int, q1, k1: int) -> bool:
        """The motion from ``(q0, k0)`` to ``(q1, k1)``: translate at ``k0``, then turn in
        place at ``q1`` to ``k1``. Free when both parts are."""
        return self.translation_free(q0, q1, k0) and (k0 == k1 or self.turn_free(q1, k0, k1))

    def expand(self, states) -> list[tuple[np.ndarray, int]]:
        """The path of ``(q, k)`` states as its primitive motions' waypoints: each motion
        becomes the translation's end, then one waypoint per slice of the turn, so that
        consecutive waypoints differ by a translation or a turn between neighbours."""
        out: list[tuple[np.ndarray, int]] = []
        for q, k in states:
            q = np.asarray(q, dtype=np.float64)
            if not out:
                out.append((q, int(k)))
                continue
            k0 = out[-1][1]
            if not np.array_equal(out[-1][0], q):
                out.append((q, k0))
            for s in self.slices.way(k0, int(k))[1:]:
                out.append((q, s))
        return out

    def verify(self, waypoints) -> bool:
        """Re-prove expanded waypoints (:meth:`expand`): every state free, every step a free
        translation or a free turn between neighbours."""
        if not waypoints:
            return False
        q, k = waypoints[0]
        if not self.state_free(q, k):
            return False
        for (q0, k0), (q1, k1) in zip(waypoints, waypoints[1:]):
            if k0 == k1:
                if not self.translation_free(q0, q1, k0):
                    return False
            elif not (np.array_equal(q0, q1) and len(self.slices.way(k0, k1)) == 2
                      and self.turn_free(q0, k0, k1)):
                return False
        return True

    def orientations(self, ks) -> np.ndarray:
        """``(n, 4)`` unit quaternions ``(x, y, z, w)`` of slices ``ks`` in the world frame:
        the slice's turn after the scene's start rotation (``scene.start_rotation``), signs
        chosen so that consecutive ones lie in one hemisphere."""
        from scipy.spatial.transform import Rotation

        start = np.asarray(self.scene.start_rotation, dtype=np.float64)
        mats = np.stack([self.slices.rotation(k) @ start for k in ks])
        Q = Rotation.from_matrix(mats).as_quat()
        # q and -q are one orientation: keep neighbours in one hemisphere, so that slerp
        # between consecutive waypoints (as OMPL.app interpolates) takes the short arc
        for i in range(1, len(Q)):
            if Q[i] @ Q[i - 1] < 0:
                Q[i] = -Q[i]
        return Q


def _outward(P: np.ndarray, hull) -> np.ndarray:
    """The hull's triangles wound counter-clockwise seen from outside (int64)."""
    F = np.asarray(hull.simplices, dtype=np.int64)
    normals = np.cross(P[F[:, 1]] - P[F[:, 0]], P[F[:, 2]] - P[F[:, 0]])
    centre = P[hull.vertices].mean(axis=0)
    flip = (normals * (P[F[:, 0]] - centre)).sum(axis=1) < 0
    F[flip] = F[flip][:, [0, 2, 1]]
    return F
