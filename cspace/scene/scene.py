"""A planning scene: obstacle bodies, a robot at a fixed orientation, bounds, start and goal.

:class:`Body` is a named mesh as its file gives it (float64 vertices, int64 faces, world frame
for obstacles, robot frame for the robot); :class:`Scene` holds the bodies, the robot's
reference point, the planning bounds and the query. Reading files: :mod:`cspace.scene.files`.
"""

from __future__ import annotations

import warnings
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from ..errors import InvalidMeshError, SceneError
from ..geometry.exact import Grid
from ..mesh.convex import ConvexPolytope

__all__ = ["Body", "Scene"]


# --------------------------------------------------------------------------------------
# data


def _frozen(a: np.ndarray) -> np.ndarray:
    a.flags.writeable = False
    return a


@dataclass(frozen=True, eq=False)
class Body:
    """A named triangle mesh of a scene, as its file gives it (not welded or repaired).

    Attributes
    ----------
    name : str
        Used in reports and error messages.
    vertices : (n, 3) float64
        World frame (pose applied) for obstacles; the robot frame for the robot. Read-only.
    faces : (m, 3) int64
        Vertex indices of the triangles, in the file's order and winding. Read-only.
    source : str
        The file the body came from, or ``'box'``.
    """

    name: str
    vertices: np.ndarray
    faces: np.ndarray
    source: str

    def __post_init__(self):
        vertices = np.array(self.vertices, dtype=np.float64)
        faces = np.array(self.faces, dtype=np.int64)
        where = f"body {self.name!r} ({self.source})"
        if vertices.ndim != 2 or vertices.shape[1] != 3 or len(vertices) == 0:
            raise SceneError(f"{where}: vertices must be (n, 3) with n > 0, got {vertices.shape}")
        if faces.ndim != 2 or faces.shape[1] != 3 or len(faces) == 0:
            raise SceneError(f"{where}: faces must be (m, 3) with m > 0, got {faces.shape}")
        if not np.isfinite(vertices).all():
            row = int(np.argmin(np.isfinite(vertices).all(axis=1)))
            raise SceneError(f"{where}: vertex {row} is not finite: {vertices[row].tolist()}")
        if faces.min() < 0 or faces.max() >= len(vertices):
            raise SceneError(
                f"{where}: face indices must be in [0, {len(vertices)}), "
                f"found {int(faces.min())}..{int(faces.max())}"
            )
        object.__setattr__(self, "vertices", _frozen(vertices))
        object.__setattr__(self, "faces", _frozen(faces))

    @property
    def bounds(self) -> np.ndarray:
        """(2, 3) float64: the lower and upper corner of the vertices' bounding box."""
        return np.stack([self.vertices.min(axis=0), self.vertices.max(axis=0)])

    def __repr__(self) -> str:
        return (
            f"Body(name={self.name!r}, vertices={len(self.vertices)}, faces={len(self.faces)}, "
            f"source={self.source!r})"
        )


@dataclass(frozen=True, eq=False)
class Scene:
    """A translational planning problem: obstacles, a robot at a fixed orientation, bounds.

    Build one with :func:`cspace.scene.files.load_scene` (or directly; the constructor checks the arrays).

    Attributes
    ----------
    name : str
    path : Path or None
        The file the scene was read from.
    obstacles : tuple of Body
        World frame.
    robot : Body
        The robot in its own frame, its fixed orientation already applied; the reference
        point is not subtracted.
    reference_point : (3,) float64
        The point of the robot whose position is planned, in the robot frame. The robot with
        its reference point at ``q`` occupies ``robot.vertices - reference_point + q``.
    bounds : (2, 3) float64
        Lower and upper corner of the box the reference point moves in.
    start, goal : (3,) float64
        Reference-point positions, inside ``bounds``.
    start_rotation, goal_rotation : (3, 3) float64
        The robot's orientation at the start (already applied to :attr:`robot`) and the one
        asked for at the goal, world frame (rotations acting on column vectors; default the
        identity, the goal's default the start's). Translation-only planning keeps the start
        orientation; planning with turns (:func:`cspace.planning.plan.plan` ``slices=``) reaches
        the goal's.
    """

    name: str
    path: Path | None
    obstacles: tuple[Body, ...]
    robot: Body
    reference_point: np.ndarray
    bounds: np.ndarray
    start: np.ndarray
    goal: np.ndarray
    start_rotation: np.ndarray | None = None
    goal_rotation: np.ndarray | None = None

    def __post_init__(self):
        where = f"scene {self.name!r}"
        if self.start_rotation is None:
            object.__setattr__(self, "start_rotation", np.eye(3))
        if self.goal_rotation is None:
            object.__setattr__(self, "goal_rotation", self.start_rotation)
        arrays = {}
        for key, shape in (("reference_point", (3,)), ("bounds", (2, 3)), ("start", (3,)),
                           ("goal", (3,)), ("start_rotation", (3, 3)), ("goal_rotation", (3, 3))):
            a = np.array(getattr(self, key), dtype=np.float64)
            if a.shape != shape:
                raise SceneError(f"{where}: {key} must have shape {shape}, got {a.shape}")
            if not np.isfinite(a).all():
                raise SceneError(f"{where}: {key} is not finite: {a.tolist()}")
            arrays[key] = a
        for key in ("start_rotation", "goal_rotation"):
            r = arrays[key]
            if not (np.abs(r @ r.T - np.eye(3)).max() <= 1e-9 and np.linalg.det(r) > 0):
                raise SceneError(f"{where}: {key} is not a rotation matrix: {r.tolist()}")
        lo, hi = arrays["bounds"]
        if (lo > hi).any():
            raise SceneError(f"{where}: bounds lower corner {lo.tolist()} exceeds the upper "
                             f"corner {hi.tolist()}")
        for key in ("start", "goal"):
            if not _inside(arrays[key], arrays["bounds"]):
                raise SceneError(f"{where}: {key} {arrays[key].tolist()} is outside the bounds "
                                 f"{arrays['bounds'].tolist()}")
        for key, a in arrays.items():
            object.__setattr__(self, key, _frozen(a))
        object.__setattr__(self, "obstacles", tuple(self.obstacles))
        if self.path is not None:
            object.__setattr__(self, "path", Path(self.path))

    @classmethod
    def from_meshes(cls, robot, obstacles, start, goal, *, bounds=None,
                    reference_point=(0.0, 0.0, 0.0), start_rotation=None, goal_rotation=None,
                    name: str = "scene") -> "Scene":
        """A scene built in code: a robot, obstacles, a start and a goal.

        Parameters
        ----------
        robot : trimesh.Trimesh, (vertices, faces), path or Body
            The robot in its own frame (scene units), as a mesh object, arrays or a mesh
            file (any format :func:`cspace.mesh.files.read_mesh_file` reads).
        obstacles : sequence or dict of the same
            Obstacles in the world frame; a dict names them (``{"wall": mesh}``), else they
            are ``obstacle-0``, ``obstacle-1``, ... (a Body keeps its name).
        start, goal : (3,) float
            Where the robot's reference point starts and ends, world frame.
        bounds : (2, 3) float, optional
            The box the reference point moves in. Default: the box of the obstacles, the
            start and the goal, grown on every side by the robot's reach (its farthest vertex
            from the reference point), so that the robot can pass around every obstacle.
        reference_point : (3,) float, default the origin
            The point of the robot whose position is planned, in the robot's own frame.
        start_rotation, goal_rotation : (3, 3) float, optional
            The robot's orientation at the start (applied to the robot and its reference
            point, as a TOML ``orientation`` is) and the one asked for at the goal; default
            the identity, the goal's the start's.
        name : str
            Used in reports and error messages.

        Returns
        -------
        Scene
            Checked as any scene (start and goal inside the bounds, rotations proper).
            :func:`cspace.save_scene` writes it as a TOML file with its meshes.
        """
        R = np.eye(3) if start_rotation is None else np.asarray(start_rotation, dtype=np.float64)
        body = _as_body(robot, "robot")
        c = np.asarray(reference_point, dtype=np.float64).reshape(3)
        robot_body = Body(body.name, body.vertices @ R.T, body.faces, body.source)
        c = R @ c
        items = obstacles.items() if isinstance(obstacles, dict) else (
            (None, o) for o in obstacles)
        bodies = tuple(_as_body(o, f"obstacle-{i}" if key is None else str(key))
                       for i, (key, o) in enumerate(items))
        start = np.asarray(start, dtype=np.float64).reshape(3)
        goal = np.asarray(goal, dtype=np.float64).reshape(3)
        if bounds is None:
            pts = [start[None], goal[None]] + [b.vertices for b in bodies]
            allp = np.concatenate(pts)
            reach = float(np.linalg.norm(robot_body.vertices - c, axis=1).max())
            bounds = np.stack([allp.min(axis=0) - reach, allp.max(axis=0) + reach])
        return cls(name=name, path=None, obstacles=bodies, robot=robot_body,
                   reference_point=c, bounds=bounds, start=start, goal=goal,
                   start_rotation=R, goal_rotation=goal_rotation)

    def robot_polytope(self, grid=None) -> ConvexPolytope:
        """The robot as an exact convex polytope (robot frame; reference point not subtracted).

        Parameters
        ----------
        grid : Grid, optional
            Snapping grid; default the grid for the robot's own coordinates. Pass the scene's
            grid (e.g. ``scene.grid()``) to combine it with obstacles.

        Returns
        -------
        ConvexPolytope
            ``ConvexPolytope.from_mesh`` of the robot mesh when it is a closed convex mesh.
            Otherwise (not convex, open, double-sided, several shells, ...) the convex hull of
            its vertices, with a :class:`UserWarning` saying why.
        """
        robot = self.robot
        if grid is not None:  # the scene grid's step, about the reference point if far
            grid = grid.for_robot(robot.vertices, self.reference_point)
        try:
            return ConvexPolytope.from_mesh(
                (robot.vertices, robot.faces), grid=grid, name=robot.name
            )
        except InvalidMeshError as exc:
            warnings.warn(
                f"scene {self.name!r}: robot {robot.name!r} ({robot.source}) is not a closed "
                f"convex mesh ({type(exc).__name__}: {exc}); using the convex hull of its "
                f"{len(robot.vertices)} vertices instead",
                UserWarning,
                stacklevel=2,
            )
            return ConvexPolytope.from_points(robot.vertices, grid=grid, name=robot.name)

    def grid(self, *, bits: int = 26) -> Grid:
        """The scene's snapping grid: :meth:`Grid.for_box` of everything the C-obstacles'
        computations meet in the world frame (the bounds, the robot placed at their corners,
        the obstacles and their C-obstacles' boxes ``O ⊕ (c - R)``), with the robot's vectors
        ``c - r`` within reach. Centred on that box when it lies away from the origin, so that
        the step follows the scene's size, not its distance from the origin."""
        rel = self.robot.vertices - self.reference_point
        r_lo, r_hi = rel.min(axis=0), rel.max(axis=0)
        lo, hi = self.bounds
        boxes = [self.bounds, np.stack([lo + r_lo, hi + r_hi])]
        sizes = [len(body.vertices) for body in self.obstacles]
        if sizes and min(sizes) > 0:  # every body's box at once
            V = np.concatenate([body.vertices for body in self.obstacles])
            starts = np.concatenate([[0], np.cumsum(sizes)[:-1]])
            b_lo, b_hi = np.minimum.reduceat(V, starts), np.maximum.reduceat(V, starts)
            boxes += [b_lo, b_hi, b_lo - r_hi, b_hi - r_lo]
        else:
            for body in self.obstacles:
                b_lo, b_hi = body.bounds
                boxes.append(np.stack([b_lo, b_hi, b_lo - r_hi, b_hi - r_lo]))
        allv = np.concatenate(boxes)
        far = max(float(np.abs(self.robot.vertices).max()),
                  float(np.abs(self.reference_point).max()))
        return Grid.for_box(allv.min(axis=0), allv.max(axis=0),
                            reach=float(np.abs(rel).max()), far=far, bits=bits)

    def __repr__(self) -> str:
        return (
            f"Scene(name={self.name!r}, obstacles={len(self.obstacles)}, robot={self.robot!r}, "
            f"bounds={self.bounds.tolist()}, start={self.start.tolist()}, "
            f"goal={self.goal.tolist()})"
        )


def _as_body(obj, name: str) -> Body:
    """A :class:`Body` from a Body, a mesh object (``.vertices``, ``.faces``), a
    ``(vertices, faces)`` pair or a mesh file path."""
    import os

    if isinstance(obj, Body):
        return obj
    if isinstance(obj, (str, os.PathLike)):
        from ..mesh.files import read_mesh_file

        m = read_mesh_file(obj, f"{name} ({os.fspath(obj)})")
        return Body(name, m.vertices, m.faces, os.fspath(obj))
    if hasattr(obj, "vertices") and hasattr(obj, "faces"):
        return Body(name, np.asarray(obj.vertices), np.asarray(obj.faces), "array")
    if isinstance(obj, (tuple, list)) and len(obj) == 2:
        return Body(name, obj[0], obj[1], "array")
    raise SceneError(f"{name}: expected a mesh (trimesh.Trimesh, (vertices, faces), a path or "
                     f"a Body), got {type(obj).__name__}")


def _inside(point: np.ndarray, bounds: np.ndarray) -> bool:
    return bool((bounds[0] <= point).all() and (point <= bounds[1]).all())
