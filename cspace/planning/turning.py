"""A robot that turns: orientation slices, certified turns in place, and their C-space.

Translational C-obstacles answer "is the robot free at ``q``" for one orientation. A robot
that must turn is planned over a finite set of orientations (:class:`~cspace.planning.orientations.Slices`: angles about
one axis through the reference point, the start's angle 0 and the goal's included;
:class:`~cspace.planning.orientations.Orientations`: a near-uniform set of SO(3) for a free-flying robot, the start and
goal included, each linked to its nearest). Two kinds of motion are certified, exactly and
conservatively:

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
(:func:`cspace.scene.model.model_scene`): C-obstacles are conservative (errors are false
collisions within ``error_bound``, never false free), so a certified motion is free.

Frames: the robot's vertices are in its own frame with the scene's start orientation
applied (:class:`cspace.Scene`); slice ``k`` turns them by ``angles[k]`` about ``axis``
through ``scene.reference_point``. The robot of slice ``k`` *is* those float64 vertices;
the turn's growth also covers their rounding (:func:`swept_points`).
"""

from __future__ import annotations

import dataclasses

import numpy as np

from .orientations import _turned, swept_points, turning_frame
from ..errors import MemoryBudgetError
from ..memory import budget_and_source, format_size

__all__ = ["TurningCSpace"]


class TurningCSpace:
    """The C-space of a scene's robot over orientation slices, built lazily.

    Parameters
    ----------
    scene : Scene
        Obstacles, robot (start orientation applied), reference point, bounds.
    slices : Slices or Orientations
    cache : COCache, path, True, or None
        The disk cache every slice's and turn's C-obstacles go through
        (:func:`cspace.scene.model.model_scene`).
    robot_hull : bool, default False
        Slices against the robot's convex hull instead of its exact parts.
    memory : int or str, optional
        One memory budget for all the slices (:mod:`cspace.memory`; default
        ``$CSPACE_MEMORY``, else half of what is available). A slice that does not fit beside
        those built spills the least recently used ones when there is a disk cache (asked
        for again, they are read back from it: the same C-obstacles); with no cache, or when
        one slice alone does not fit, :class:`~cspace.errors.MemoryBudgetError`.

    Attributes
    ----------
    built_slices, built_turns : dict
        The C-spaces made so far: ``{k: CSpace}``, ``{(i, j): CSpace}`` with ``i < j``
        (a turn's C-space serves both directions).
    far_answers : int
        Queries answered free before any C-space: the robot's ball (radius: its farthest
        vertex from the reference point, which no turn changes) misses every obstacle's box
        there. So a slice or a turn is built only where the robot comes near an obstacle.
    spilled : int
        Slices dropped from memory to keep within the budget (they stay in the disk cache).
    """

    def __init__(self, scene, slices, *, cache=None, robot_hull: bool = False, memory=None):
        self.scene = scene
        # One memory budget for all the slices this builds (cspace.memory): each slice's
        # build gets what the slices already built leave of it; with a disk cache the least
        # recently used slices are spilled to make room (``spilled`` counts them).
        self.memory, self._memory_source = budget_and_source(memory)
        self.spilled = 0
        self.slices = slices
        from ..scene.cache import COCache

        self.cache = COCache.of(cache)  # one cache for every slice and turn
        self.robot_hull = bool(robot_hull)
        self.bounds = np.asarray(scene.bounds, dtype=np.float64)
        self.built_slices: dict = {}
        self.built_turns: dict = {}
        self._parts = None
        # Broad phase, before anything is built: turning about the reference point keeps
        # every robot point within ``reach`` of it, so a robot whose ball of that radius
        # misses every obstacle's box is free at any orientation. The ball is grown by a
        # relative 1e-9 of the coordinates' size, far above the distances' float rounding.
        V = np.asarray(scene.robot.vertices, dtype=np.float64)
        c = np.asarray(scene.reference_point, dtype=np.float64)
        boxes = np.array([b.bounds for b in scene.obstacles]).reshape(-1, 2, 3)
        size = max(float(np.abs(boxes).max(initial=0.0)), float(np.abs(self.bounds).max()),
                   float(np.abs(V).max()), float(np.abs(c).max()))
        self._box_lo, self._box_hi = boxes[:, 0], boxes[:, 1]
        self._reach = float(np.sqrt(((V - c) ** 2).sum(axis=1)).max()) * (1 + 1e-9) + 1e-9 * size
        self.far_answers = 0
        # One grid and one modelling of the obstacles for every slice and turn
        # (orientations.turning_frame): only the robot is modelled and summed per orientation.
        self._frame, self.grid = turning_frame(scene)
        self._memo: dict = {}

    def __repr__(self) -> str:
        return (f"TurningCSpace({self.scene.name!r}, {self.slices!r}, built: "
                f"{len(self.built_slices)} slices, {len(self.built_turns)} turns)")

    # ---------------------------------------------------------------- building

    def _scene_with(self, name: str, vertices: np.ndarray, faces: np.ndarray):
        from ..scene.scene import Body

        robot = Body(name, vertices, faces, self.scene.robot.source)
        return dataclasses.replace(self._frame, robot=robot)

    def _cspace(self, scene, hull: bool, sums: bool = True):
        """The C-space of ``scene`` (a slice or a swept part), modelled on the shared grid and
        built lazily: a pair's C-obstacles the first time a query comes near them."""
        from ..scene.model import LazyCSpace, model_scene

        while True:
            held = sum(cs.memory for cs in self.built_slices.values())
            try:
                model = model_scene(scene, grid=self.grid, robot_hull=hull, memo=self._memo,
                                    build=False)
                return LazyCSpace(model, cache=self.cache, sums=sums,
                                  memory=max(1, self.memory - held))
            except MemoryBudgetError as exc:
                holding = [j for j, cs in self.built_slices.items() if cs.memory]
                if self.cache is not None and holding:
                    # Spill the least recently used slice: its C-obstacles are in the disk
                    # cache, so asking for it again reads them back instead of rebuilding.
                    del self.built_slices[holding[0]]
                    self.spilled += 1
                    continue
                if not held:
                    raise
                raise MemoryBudgetError(
                    f"{exc}. The {len(self.built_slices)} orientation slices built so far hold "
                    f"about {format_size(held)} of the budget of {format_size(self.memory)} "
                    f"({self._memory_source}), and with no disk cache they cannot be spilled: "
                    "fewer orientations need less",
                    needed=exc.needed + held, budget=self.memory) from exc

    def slice(self, k: int):
        """The :class:`~cspace.CSpace` of the robot at slice ``k`` (built on first use)."""
        k = int(k) % len(self.slices)
        cs = self.built_slices.pop(k, None)
        if cs is not None:
            self.built_slices[k] = cs  # the most recently used last: spilled last
        else:
            robot = self.scene.robot
            V = _turned(robot.vertices, self.scene.reference_point, self.slices.rotation(k))
            name = f"{robot.name} at {self.slices.label(k)}"
            cs = self.built_slices[k] = self._cspace(self._scene_with(name, V, robot.faces),
                                                     self.robot_hull)
        return cs

    def prebuild(self, executor=None, ks=None, progress=None) -> None:
        """Build slices ``ks`` (default all) at once, through ``executor`` (any
        ``concurrent.futures.Executor``: a process pool, a Dask cluster's;
        :func:`cspace.planning.scale.build_slices`) instead of lazily, one at a time."""
        from .scale import build_slices

        todo = [k for k in (range(len(self.slices)) if ks is None else ks)
                if int(k) % len(self.slices) not in self.built_slices]
        if todo:
            self.built_slices.update(build_slices(self.scene, self.slices, executor, ks=todo,
                                                  cache=self.cache, robot_hull=self.robot_hull,
                                                  progress=progress))

    def _robot_parts(self) -> list[np.ndarray]:
        """The vertices of each connected part of the robot (by shared vertex indices)."""
        if self._parts is None:
            from ..geometry.graphs import component_labels

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

        n = len(self.slices)
        i, j = int(i) % n, int(j) % n
        key = (min(i, j), max(i, j))
        cs = self.built_turns.get(key)
        if cs is None:
            self.slices.step(i, j)  # neighbours, or a named error
            spaces = []
            for p, V in enumerate(self._robot_parts()):
                P = swept_points(V, self.scene.reference_point, self.slices, *key)
                hull = ConvexHull(P)
                name = (f"{self.scene.robot.name} part {p} turning from "
                        f"{self.slices.label(key[0])} to {self.slices.label(key[1])}")
                scene = self._scene_with(name, P, _outward(P, hull))
                # A turn is asked a few queries: triangle pairs against the swept hull
                # build nothing, where one NCC-CVMS sum per closed body took most of a turn.
                spaces.append(self._cspace(scene, True, sums=False))
            cs = spaces[0] if len(spaces) == 1 else _union_of(spaces, self.bounds)
            self.built_turns[key] = cs
        return cs

    # ---------------------------------------------------------------- queries

    def in_bounds(self, q) -> bool:
        q = np.asarray(q, dtype=np.float64)
        return bool((self.bounds[0] <= q).all() and (q <= self.bounds[1]).all())

    def _far(self, lo, hi) -> bool:
        """The robot's ball about every point of the box ``[lo, hi]`` misses every obstacle's
        box (then it is free there at every orientation)."""
        gap = np.maximum(np.maximum(self._box_lo - hi, lo - self._box_hi), 0.0)
        far = bool(((gap * gap).sum(axis=1) > self._reach * self._reach).all())
        self.far_answers += far
        return far

    def state_free(self, q, k: int) -> bool:
        """The robot at slice ``k`` with its reference point at ``q`` is in bounds and free."""
        q = np.asarray(q, dtype=np.float64)
        return self.in_bounds(q) and (self._far(q, q) or not self.slice(k).contains(q))

    def translation_free(self, q0, q1, k: int) -> bool:
        """The straight translation from ``q0`` to ``q1`` at slice ``k`` is free (exact)."""
        q0, q1 = np.asarray(q0, dtype=np.float64), np.asarray(q1, dtype=np.float64)
        if not (self.in_bounds(q0) and self.in_bounds(q1)):
            return False
        return self._far(np.minimum(q0, q1), np.maximum(q0, q1)) or self.slice(k).segment_free(q0, q1)

    def turn_free(self, q, i: int, j: int) -> bool:
        """Turning in place at ``q`` from slice ``i`` to ``j`` (the shorter way, through
        neighbours) is free: every step's swept C-obstacles miss ``q``."""
        q = np.asarray(q, dtype=np.float64)
        if not self.in_bounds(q):
            return False
        if self._far(q, q):
            return True
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
            elif not (np.array_equal(q0, q1) and self.slices.neighbours(k0, k1)
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


def _union_of(spaces: list, bounds: np.ndarray):
    """One C-space over several lazily built ones (a turn's robot parts), each asked only
    where a query meets its box."""
    from ..cobstacle.union import _UnionOf
    from ..scene.model import CSpace

    cs = CSpace((), bounds=bounds, name="turn")
    lo = np.array([s.box[0] for s in spaces])
    hi = np.array([s.box[1] for s in spaces])
    cs._union = _UnionOf((), lazy=(lo, hi, lambda k: spaces[k]._union))
    return cs


def _outward(P: np.ndarray, hull) -> np.ndarray:
    """The hull's triangles wound counter-clockwise seen from outside (int64)."""
    F = np.asarray(hull.simplices, dtype=np.int64)
    normals = np.cross(P[F[:, 1]] - P[F[:, 0]], P[F[:, 2]] - P[F[:, 0]])
    centre = P[hull.vertices].mean(axis=0)
    flip = (normals * (P[F[:, 0]] - centre)).sum(axis=1) < 0
    F[flip] = F[flip][:, [0, 2, 1]]
    return F
