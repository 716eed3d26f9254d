"""Orientation sets for a robot that turns, and the robot turned to each.

:class:`Slices` (angles about one axis through the reference point) and :class:`Orientations`
(a near-uniform set of SO(3)); :func:`slice_scene` turns a scene's robot to one of them;
:func:`swept_points` bounds the robot's sweep between neighbours (for certified turns).
"""

from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass

import numpy as np

from ..errors import InvalidArgumentError
from ..geometry.transform import axis_angle, transform

__all__ = ["slice_scene", "turning_frame", "Slices", "Orientations", "swept_points"]


def slice_scene(scene, slices, k: int):
    """The scene with its robot turned to slice ``k`` (``slices.rotation(k)`` about the
    reference point), exactly as :meth:`cspace.planning.turning.TurningCSpace.slice` turns it."""
    from ..scene.scene import Body

    robot = scene.robot
    V = _turned(robot.vertices, scene.reference_point, slices.rotation(k))
    label = (slices.label(k) if hasattr(slices, "label")
             else f"{math.degrees(slices.angles[k]):.6g} deg")
    turned = Body(f"{robot.name} at {label}", V, robot.faces, robot.source)
    return dataclasses.replace(scene, robot=turned)


def turning_frame(scene):
    """What every orientation of the robot shares: ``(modelled, grid)``, the scene without the
    obstacle parts no orientation can reach, and one grid for all orientations and turns.

    At any orientation, and through a turn in place (:func:`swept_points`: both ends within
    ``reach`` of the reference point, grown by at most ``reach`` more), the robot lies in the
    cube of half-side ``3 reach`` about the reference point (``reach``: its farthest vertex).
    That cube stands for the robot when far parts are left out
    (:func:`cspace.scene.classify._without_far_parts`) and the grid is chosen
    (:meth:`cspace.Scene.grid`), so every slice's and turn's C-obstacles fit the grid and each
    obstacle body is welded, split and classified once for all of them
    (:func:`cspace.scene.model.model_scene`'s ``memo``) instead of once per orientation. The
    grid's step may be one power of two coarser than one robot box alone would give.
    """
    from ..scene.classify import _without_far_parts
    from ..scene.scene import Body

    c = np.asarray(scene.reference_point, dtype=np.float64)
    reach = float(np.sqrt(((np.asarray(scene.robot.vertices) - c) ** 2).sum(axis=1)).max())
    unit = np.array([[x, y, z] for x in (-1.0, 1.0) for y in (-1.0, 1.0) for z in (-1.0, 1.0)])
    cube = Body(f"{scene.robot.name} at any orientation", c + 3.0 * max(reach, 1e-300) * unit,
                np.array([[0, 1, 3], [0, 3, 2], [4, 6, 7], [4, 7, 5], [0, 4, 5], [0, 5, 1],
                          [2, 3, 7], [2, 7, 6], [0, 2, 6], [0, 6, 4], [1, 5, 7], [1, 7, 3]],
                         dtype=np.int64), scene.robot.source)
    modelled, _ = _without_far_parts(dataclasses.replace(scene, robot=cube))
    return dataclasses.replace(modelled, robot=scene.robot), modelled.grid()


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
        k = int(np.argmin(near))
        if k and near[k] <= 1e-12:
            # the goal is a step up to the rounding of 2 pi k / n: that slice takes the
            # goal's own angle (no tolerance leaks into the goal orientation)
            steps[k] = g
            return cls(axis, steps, k)
        if near[k] == 0.0:  # the start's angle: the goal is the start
            return cls(axis, steps, 0)
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

    def label(self, k: int) -> str:
        return f"{math.degrees(self.angles[k]):.6g} deg"

    def neighbours(self, i: int, j: int) -> bool:
        n = len(self)
        return (j - i) % n in (1, n - 1)

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


# The 24 rotations of the cube: axis-aligned scenes often need exactly these.
def _cube_rotations() -> np.ndarray:
    out = []
    for perm in ((0, 1, 2), (1, 2, 0), (2, 0, 1), (1, 0, 2), (0, 2, 1), (2, 1, 0)):
        for signs in np.ndindex(2, 2, 2):
            M = np.zeros((3, 3))
            for row, (col, sg) in enumerate(zip(perm, signs)):
                M[row, col] = -1.0 if sg else 1.0
            if np.linalg.det(M) > 0:
                out.append(M)
    return np.array(out)


def _super_fibonacci(n: int) -> np.ndarray:
    """``(n, 4)`` unit quaternions ``(x, y, z, w)`` spread near-uniformly over SO(3)
    (Alexa, "Super-Fibonacci spirals", CVPR 2022)."""
    phi, psi = math.sqrt(2.0), 1.533751168755204288118041
    s = np.arange(n) + 0.5
    r, R = np.sqrt(s / n), np.sqrt(1.0 - s / n)
    a, b = 2 * math.pi * s / phi, 2 * math.pi * s / psi
    return np.stack([r * np.sin(a), r * np.cos(a), R * np.sin(b), R * np.cos(b)], axis=1)


@dataclass(frozen=True, eq=False)
class Orientations:
    """A near-uniform set of orientations in SO(3), for a robot that flies freely.

    Attributes
    ----------
    rotations : (n, 3, 3) float64
        Relative to the start orientation; ``rotations[0]`` is the identity (the start).
    links : tuple of tuple of int
        The neighbours of each orientation (symmetric; the graph is connected). A turn in
        place between neighbours rotates about the axis of ``R_j R_i^T`` by its angle (at
        most ``max_step``), the shortest arc.
    goal : int
        The goal orientation's index.
    """

    rotations: np.ndarray
    links: tuple
    goal: int = 0

    def __post_init__(self):
        from scipy.spatial.transform import Rotation

        R = np.asarray(self.rotations, dtype=np.float64).reshape(-1, 3, 3)
        if len(R) < 2 or not np.allclose(R[0], np.eye(3), atol=0.0):
            raise InvalidArgumentError("orientations: need at least 2, the first the identity")
        links = tuple(tuple(sorted(set(int(j) for j in row))) for row in self.links)
        if len(links) != len(R) or any(i in row or not all(0 <= j < len(R) for j in row)
                                        for i, row in enumerate(links)):
            raise InvalidArgumentError("orientations: links must name other orientations, one "
                                       "row per orientation")
        if any(i not in links[j] for i, row in enumerate(links) for j in row):
            raise InvalidArgumentError("orientations: links must be symmetric")
        if not 0 <= self.goal < len(R):
            raise InvalidArgumentError(f"orientations: goal {self.goal} is not one of {len(R)}")
        object.__setattr__(self, "rotations", R)
        object.__setattr__(self, "links", links)
        object.__setattr__(self, "_quats", Rotation.from_matrix(R).as_quat())
        if len(self._reach(0)) != len(R):
            raise InvalidArgumentError("orientations: the neighbour graph is not connected")

    @classmethod
    def uniform(cls, n: int, *, goal_rotation=None, degree: int = 8) -> "Orientations":
        """The identity, the goal, the cube's 24 rotations and ``n`` super-Fibonacci ones
        (duplicates within 1e-9 rad dropped), each linked to its ``degree`` nearest (by
        rotation angle), symmetrically."""
        from scipy.spatial.transform import Rotation

        if int(n) != n or n < 0:
            raise InvalidArgumentError(f"orientations: n must be a whole number >= 0, got {n!r}")
        goal = np.eye(3) if goal_rotation is None else np.asarray(goal_rotation, dtype=np.float64)
        cand = np.concatenate([np.eye(3)[None], goal[None], _cube_rotations(),
                               Rotation.from_quat(_super_fibonacci(int(n))).as_matrix()])
        quats = Rotation.from_matrix(cand).as_quat()
        keep: list[int] = []
        for i, q in enumerate(quats):
            if not keep or np.abs(quats[keep] @ q).max() < math.cos(0.5e-9):
                keep.append(i)
        R = cand[keep]
        R[0] = np.eye(3)
        Q = quats[keep]
        angle = 2 * np.arccos(np.clip(np.abs(Q @ Q.T), 0.0, 1.0))
        np.fill_diagonal(angle, np.inf)
        d = min(int(degree), len(R) - 1)
        near = np.argsort(angle, axis=1)[:, :d]
        links = [set(row.tolist()) for row in near]
        for i, row in enumerate(near):
            for j in row.tolist():
                links[j].add(i)
        g = 0 if goal_rotation is None else int(np.argmax(np.abs(Q @ Rotation.from_matrix(goal).as_quat())))
        return cls(R, tuple(tuple(sorted(x)) for x in links), g)

    def __len__(self) -> int:
        return len(self.rotations)

    def __repr__(self) -> str:
        steps = [self.step(i, j) for i, row in enumerate(self.links) for j in row]
        return (f"Orientations({len(self)} in SO(3), {sum(map(len, self.links)) // 2} links, "
                f"steps up to {math.degrees(max(steps)):.3g} deg, goal {self.goal})")

    def rotation(self, k: int) -> np.ndarray:
        return self.rotations[k]

    def label(self, k: int) -> str:
        return f"orientation {k}"

    def neighbours(self, i: int, j: int) -> bool:
        return j in self.links[i]

    def step(self, i: int, j: int) -> float:
        """The angle (radians) of the turn between neighbours ``i`` and ``j``."""
        if not self.neighbours(i, j):
            raise InvalidArgumentError(f"orientations {i} and {j} are not neighbours")
        c = abs(float(self._quats[i] @ self._quats[j]))
        return 2.0 * math.acos(min(1.0, c))

    def nearest(self, quaternion) -> int:
        """The orientation closest to a unit quaternion ``(x, y, z, w)``."""
        return int(np.argmax(np.abs(self._quats @ np.asarray(quaternion, dtype=np.float64))))

    def _reach(self, i: int) -> dict:
        """Dijkstra from ``i`` over the links, by turn angle: ``{node: previous}``."""
        import heapq

        prev, dist, heap = {i: -1}, {i: 0.0}, [(0.0, i)]
        done = set()
        while heap:
            d, a = heapq.heappop(heap)
            if a in done:
                continue
            done.add(a)
            for b in self.links[a]:
                nd = d + 2.0 * math.acos(min(1.0, abs(float(self._quats[a] @ self._quats[b]))))
                if nd < dist.get(b, math.inf):
                    dist[b], prev[b] = nd, a
                    heapq.heappush(heap, (nd, b))
        return prev

    def way(self, i: int, j: int) -> list[int]:
        """The orientations from ``i`` to ``j`` through neighbours, turning the least angle."""
        if i == j:
            return [i]
        prev = self._reach(i)
        out = [j]
        while out[-1] != i:
            out.append(prev[out[-1]])
        return out[::-1]


def _turned(vertices: np.ndarray, c: np.ndarray, R: np.ndarray) -> np.ndarray:
    return transform(np.asarray(vertices, dtype=np.float64) - c, R, c)


def swept_points(vertices: np.ndarray, reference_point, slices, i: int,
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
