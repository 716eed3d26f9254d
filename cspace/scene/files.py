"""Planning scenes: obstacle meshes, a robot at a fixed orientation, bounds, start and goal.

Works on triangle meshes given as ``(n, 3) float64`` vertices and ``(m, 3) int64`` faces,
exactly as the files give them: nothing is welded, repaired or oriented here
(:mod:`cspace.mesh` does that later, exactly). A :class:`Scene` is what a translational
planner needs: the obstacles in the world frame, the robot in its own frame with its fixed
orientation already applied, the robot's reference point (the point whose position is
planned), the box the reference point may move in, and the start and goal positions.

:func:`load_scene` reads three formats, chosen by the file suffix:

``.toml``
    cspace's own scene format, below.
``.cfg``
    OMPL.app problem files (``[problem]`` section).
``.env`` or ``.query``
    Parasol (PPL) problems: the ``.env`` environment, its ``.query`` and ``.robot`` siblings.

Length: one reader per format with the conventions each follows (OMPL.app's, Parasol's, our
TOML's, documented below and in ``docs/guides/scene-files.md``), and the TOML writer beside
the reader it must match.

Every malformed input raises :class:`SceneError` whose message names the file and the line
(line-based formats) or the key (TOML, ``.cfg``) at fault, e.g.
``scenes/window.toml: robot.orientaton: unknown key (did you mean 'orientation'?)``.
Questionable but usable input (a goal orientation that differs from the start's, bounds
that had to be inferred) gives a :class:`UserWarning` instead.

Rotations
---------
Orientations given as three angles ``[a, b, c]`` in degrees (TOML ``orientation``, Parasol
poses) are **extrinsic XYZ** rotations: first about the fixed x axis by ``a`` (roll), then
about the fixed y axis by ``b`` (pitch), then about the fixed z axis by ``c`` (yaw), i.e.
``R = Rz(c) @ Ry(b) @ Rx(a)`` acting on column vectors (``scipy``:
``Rotation.from_euler('xyz', [a, b, c], degrees=True)``). Multiples of 90 degrees use exact
cosines and sines (0, +-1), so quarter turns of boxes keep exact coordinates. Points are
transformed element by element (no BLAS), so equal input vertices stay equal.

The TOML format
---------------
Paths are relative to the scene file. Lengths are in scene units, angles in degrees. Unknown
keys are errors (typos are caught); every number must be finite. A complete example::

    # A robot passes a wall through a window.
    name = "example"                   # optional; default: the file name without suffix

    [robot]                            # required
    mesh = "meshes/robot.obj"          # a convex mesh file (any format trimesh reads, or BYU .g)
    # box = [0.5, 0.25, 0.25]          # ... OR a box of these full extents, centred at the origin
    scale = 1.0                        # optional, mesh only: a factor or [sx, sy, sz] (> 0)
    orientation = [0.0, 0.0, 30.0]     # optional fixed [roll, pitch, yaw], extrinsic XYZ; default 0
    reference_point = [0.0, 0.0, 0.0]  # optional, default the origin: a point of the robot,
                                       # in the mesh file's (or box's) coordinates

    [planning]                         # required
    bounds = [[-3, -3, 0], [3, 3, 3]]  # lower and upper corner of the reference point's box
    start = [-2, 0, 1]                 # reference-point positions, inside the bounds
    goal = [2, 0, 1]
    goal_orientation = [0, 0, 90]      # optional [roll, pitch, yaw] at the goal (as
                                       # robot.orientation; default: the robot's), reached
                                       # by planning with turns (SE(3) by default)

    [[obstacles]]                      # any number of obstacles, each a box or a mesh
    name = "left-post"                 # optional; default 'obstacle-<index>'; unique
    box = [0.2, 0.2, 2.0]              # full extents of a box centred at `position`
    position = [1.0, 0.0, 1.0]         # optional, default the origin
    orientation = [0, 0, 90]           # optional, turns the box about its centre

    [[obstacles]]
    mesh = "meshes/rock.stl"           # a mesh, closed or not: kept as the file gives it
    scale = [1.0, 1.0, 2.0]            # optional; applied first, about the mesh origin
    orientation = [0, 0, 45]           # optional; then the rotation about the mesh origin
    position = [0, 1.5, 0]             # optional; then the translation

The robot's ``scale`` and ``orientation`` act about the mesh origin (the box centre) and move
the reference point with the robot: :attr:`Scene.robot` and :attr:`Scene.reference_point` are
both in the robot frame after orientation, and the robot placed with its reference point at
``q`` occupies ``robot.vertices - reference_point + q``.

OMPL.app ``.cfg`` files
-----------------------
Read as OMPL.app's GUI reads them (``gui/ompl_app.py``, ``MainWindow.openConfig``):
``[problem]`` ``world`` and ``robot`` are mesh paths relative to the file, read in the frame
Assimp gives them (Collada unit scale and up axis applied, see :mod:`cspace.mesh.files`); the
problem is 3D when ``start.z`` is present. Positions are ``start.x/.y/.z``,
``goal.x/.y/.z``; rotations are axis-angle, ``start.axis.x/.y/.z`` and ``start.theta`` in
radians (the axis is normalised, as OMPL's ``setAxisAngle`` does; a zero axis is the
identity). In 2D (no ``start.z``) the robot turns by ``start.theta`` about z, z is 0 and the
bounds' z range is ``[0, 0]``. The **start** rotation is applied to the robot; the goal's is
:attr:`Scene.goal_rotation`, reached by planning in SE(3) (the default planner turns the robot
while it moves; a warning says translation-only planning keeps the start's). Bounds are ``volume.min.*`` / ``volume.max.*`` (all of them,
or none); without them they are inferred as OMPL.app does: the bounding box of the world,
grown to hold the start and goal. The world mesh is one obstacle body (it may hold several
disjoint parts). The robot's reference point is OMPL.app's robot centre
(``RigidBodyGeometry::getRobotCenter``, :attr:`cspace.mesh.files.MeshFile.assimp_centre`: the
mean of the vertices as Assimp returns them, not of the distinct positions), with z set to
0 in 2D (OMPL.app's ``robotShift``: a planar robot keeps its own z). Other keys and sections
(``objective``, ``[benchmark]``, ``[planner]``, ...) are ignored.

Parasol (PPL) ``.env`` / ``.query`` / ``.robot`` files
------------------------------------------------------
``load_scene`` accepts the ``.env`` or the ``.query`` file and finds the siblings in the same
folder (same stem first, else the only file with that suffix). Conventions, from
parasollab/open-ppl and its math library (mathtool):

- ``.env``: an optional ``Boundary Box [x0:x1 ; y0:y1 ; z0:z1]`` line (the reference point's
  bounds), ``Multibodies``, their count, then per multibody its type and, for ``Passive`` (or
  ``Internal``) obstacles, a body line ``file [-c(r g b a)] [-a(COM|SURFACE|NONE)] x y z rx ry rz``
  with the rotation in degrees, extrinsic XYZ (mathtool reads ``gamma beta alpha`` and builds
  ``Rz(alpha) Ry(beta) Rx(gamma)``). Each obstacle becomes one body.
- Geometry is centred on load (``GMSPolyhedron::Read`` with the default ``COMAdjust::COM``):
  the mean of the file's vertex list is moved to the body origin before the pose is applied
  (``-a(SURFACE)`` centres x and z only, ``-a(NONE)`` not at all).
- ``.robot`` (or an ``Active`` multibody in the ``.env``): body count, then body lines
  ``file [options] Volumetric|Planar Rotational|Translational``, then ``Connections`` and
  their count. One body, no connections (an articulated robot is refused).
- ``.query``: one configuration per line, ``robot-index x y z rx ry rz`` for a volumetric
  rotational robot, with the rotations in units of pi (``MultiBody::GenerateBaseTransformation``:
  ``v * PI``; rx about x, ry about y, rz about z, composed as above). The first line is the
  start, the last the goal (intermediate lines are ignored, with a warning). The start
  rotation is applied to the robot, the goal's kept as :attr:`Scene.goal_rotation` (with a
  warning when it differs: translation-only planning keeps the start's).
- The robot's reference point is its body origin, i.e. the mean of its file's vertex list.
- Without a boundary line the bounds are the obstacles' bounding box padded by the robot's
  radius about its reference point, grown to hold the start and goal (with a warning).
- Meshes: OBJ (read by trimesh) and BYU ``.g`` (header ``nparts nverts npolys nconn``, the
  parts' polygon ranges, the vertices, then 1-based vertex indices where a negative index
  closes a polygon; polygons are triangulated as fans).
"""

from __future__ import annotations

import configparser
import difflib
import math
import os
import re
import tomllib
import warnings
from pathlib import Path

import numpy as np

from ..errors import SceneError
from ..geometry.transform import (
    axis_angle as _axis_angle,
    euler_xyz as _euler_xyz,
    transform as _transform,
)
from ..mesh.files import _is_float, read_mesh_file
from .scene import Body, Scene, _inside

__all__ = ["load_scene", "save_scene"]


# --------------------------------------------------------------------------------------
# entry point


def load_scene(path) -> Scene:
    """Read a scene file; the format is chosen by the suffix.

    Parameters
    ----------
    path : str or os.PathLike
        ``.toml`` (cspace's format), ``.cfg`` (OMPL.app problem), ``.env`` or ``.query``
        (Parasol problem; the siblings are found in the same folder). See the module
        docstring for each format and its conventions.

    Returns
    -------
    Scene

    Raises
    ------
    SceneError
        The file is missing or malformed, a mesh file is missing or unreadable, a number is
        not finite, a key is unknown or missing, or the start or goal lies outside the
        bounds. The message names the file and the line or key.

    Warns
    -----
    UserWarning
        The goal orientation differs from the start's (translation-only planning keeps the
        start orientation), bounds had to be inferred, or query waypoints were ignored.
    """
    path = Path(os.fspath(path))
    loaders = {".toml": _load_toml, ".cfg": _load_cfg, ".env": _load_parasol,
               ".query": _load_parasol}
    suffix = path.suffix.lower()
    if suffix not in loaders:
        raise SceneError(f"{path}: unknown scene format {path.suffix!r}: expected one of "
                         + ", ".join(repr(s) for s in loaders))
    if not path.is_file():
        raise SceneError(f"scene file not found: '{path}'")
    notes: list[str] = []
    scene = loaders[suffix](path, notes)
    for note in notes:
        warnings.warn(note, UserWarning, stacklevel=2)
    return scene


# --------------------------------------------------------------------------------------
# geometry helpers


_SIGNS = np.array([[x, y, z] for x in (-1.0, 1.0) for y in (-1.0, 1.0) for z in (-1.0, 1.0)])
# Corner index = 4 * (x > 0) + 2 * (y > 0) + (z > 0); quads counter-clockwise from outside.
_QUADS = [(0, 1, 3, 2), (4, 6, 7, 5), (0, 4, 5, 1), (2, 3, 7, 6), (0, 2, 6, 4), (1, 5, 7, 3)]
_BOX_FACES = np.array([(a, b, c) for a, b, c, d in _QUADS] + [(a, c, d) for a, b, c, d in _QUADS],
                      dtype=np.int64)


def save_scene(scene: Scene, path) -> Path:
    """Write a scene as cspace's TOML, with its meshes as OBJ files beside it.

    Parameters
    ----------
    scene : Scene
        Any scene (built in code with :meth:`Scene.from_meshes`, or loaded).
    path : str or os.PathLike
        The ``.toml`` file; the meshes go to the folder ``<stem>-meshes`` next to it
        (``robot.obj`` and one file per obstacle, by index).

    Returns
    -------
    Path
        The file written. :func:`load_scene` reads it back with the same vertices and faces
        (OBJ coordinates are written with 17 significant digits: exact float64 round trips),
        bounds, start, goal and reference point. The robot is written as the scene holds it,
        its start orientation applied (so the file's ``robot.orientation`` is 0); a goal
        orientation that differs is written as angles relative to it (float64 degrees:
        within rounding of the rotation). Each file is written whole or not at all.
    """
    from ..geometry.transform import euler_xyz_degrees
    from ..output import output_path, write_atomic

    p = output_path(path, ("toml",), "scene")
    folder = p.parent / f"{p.stem}-meshes"

    def obj(body: Body, file: Path) -> str:
        def write(tmp: Path) -> None:
            with open(tmp, "w") as f:
                f.write(f"# {body.name} ({body.source})\n")
                for x, y, z in body.vertices.tolist():
                    f.write(f"v {x!r} {y!r} {z!r}\n")
                for a, b, c in (body.faces + 1).tolist():
                    f.write(f"f {a} {b} {c}\n")
        write_atomic(file, write)
        return f"{folder.name}/{file.name}"

    def vec(v) -> str:
        return "[" + ", ".join(repr(float(x)) for x in np.asarray(v).reshape(-1)) + "]"

    lines = [f"# written by cspace.save_scene", f"name = {_toml_string(scene.name)}", "",
             "[robot]", f"mesh = {_toml_string(obj(scene.robot, folder / 'robot.obj'))}",
             f"reference_point = {vec(scene.reference_point)}", "",
             "[planning]", f"bounds = [{vec(scene.bounds[0])}, {vec(scene.bounds[1])}]",
             f"start = {vec(scene.start)}", f"goal = {vec(scene.goal)}"]
    turn = scene.goal_rotation @ scene.start_rotation.T
    if np.abs(turn - np.eye(3)).max() > 0:
        lines.append(f"goal_orientation = {vec(euler_xyz_degrees(turn))}")
    for i, body in enumerate(scene.obstacles):
        lines += ["", "[[obstacles]]", f"name = {_toml_string(body.name)}",
                  f"mesh = {_toml_string(obj(body, folder / f'obstacle-{i}.obj'))}"]

    def write(tmp: Path) -> None:
        tmp.write_text("\n".join(lines) + "\n")
    return write_atomic(p, write)


def _toml_string(text: str) -> str:
    """A TOML basic string (quotes, backslashes and control characters escaped)."""
    out = []
    for ch in str(text):
        if ch in '"\\':
            out.append("\\" + ch)
        elif ord(ch) < 32 or ord(ch) == 127:
            out.append(f"\\u{ord(ch):04x}")
        else:
            out.append(ch)
    return '"' + "".join(out) + '"'


def _box(extents) -> tuple[np.ndarray, np.ndarray]:
    """The 8 corners and 12 outward triangles of a box of full ``extents`` centred at 0."""
    h = np.asarray(extents, dtype=np.float64) / 2.0
    return _SIGNS * h + 0.0, _BOX_FACES.copy()


def _read_mesh(path: Path, where: str) -> tuple[np.ndarray, np.ndarray]:
    """Vertices and faces of a mesh file in the frame it means (:mod:`cspace.mesh.files`)."""
    mesh = read_mesh_file(path, where)
    return mesh.vertices, mesh.faces


def _obj_vertex_mean(path: Path) -> np.ndarray | None:
    """Mean of the ``v`` lines of an OBJ file (the vertex list PPL loads), or None."""
    rows = []
    with open(path, errors="replace") as f:
        for line in f:
            if line.startswith("v "):
                words = line.split()
                if len(words) < 4:
                    return None
                rows.append(words[1:4])
    try:
        points = np.array(rows, dtype=np.float64)
    except ValueError:
        return None
    return points.mean(axis=0) if len(points) else None


# --------------------------------------------------------------------------------------
# TOML


_TOP_KEYS = ("name", "robot", "planning", "obstacles")


_ROBOT_KEYS = ("mesh", "box", "scale", "orientation", "reference_point")


_OBSTACLE_KEYS = ("name", "mesh", "box", "scale", "position", "orientation")


_PLANNING_KEYS = ("bounds", "start", "goal", "goal_orientation")


class _Toml:
    """Checks on values read from one TOML file; errors name the file and the key."""

    def __init__(self, path: Path):
        self.path = path

    def error(self, key: str, message: str) -> SceneError:
        return SceneError(f"{self.path}: {key}: {message}")

    def table(self, value, key: str, allowed, required=()) -> dict:
        if not isinstance(value, dict):
            raise self.error(key, f"expected a table, got {_kind(value)}")
        for name in value:
            if name not in allowed:
                close = difflib.get_close_matches(name, allowed, n=1)
                hint = (f"did you mean {close[0]!r}?" if close
                        else "valid keys: " + ", ".join(allowed))
                raise self.error(_join(key, name), f"unknown key ({hint})")
        for name in required:
            if name not in value:
                raise self.error(_join(key, name), "missing (required)")
        return value

    def number(self, value, key: str, *, positive: bool = False) -> float:
        if isinstance(value, bool) or not isinstance(value, (int, float)):
            raise self.error(key, f"expected a number, got {_kind(value)}")
        x = float(value)
        if not math.isfinite(x):
            raise self.error(key, f"must be finite, got {value!r}")
        if positive and not x > 0:
            raise self.error(key, f"must be positive, got {value!r}")
        return x

    def vector(self, value, key: str, *, positive: bool = False) -> np.ndarray:
        if not isinstance(value, list) or len(value) != 3:
            got = f"{len(value)} values" if isinstance(value, list) else _kind(value)
            raise self.error(key, f"expected 3 numbers [x, y, z], got {got}")
        return np.array([self.number(v, f"{key}[{i}]", positive=positive)
                         for i, v in enumerate(value)])

    def string(self, value, key: str) -> str:
        if not isinstance(value, str) or not value.strip():
            raise self.error(key, f"expected a non-empty string, got {_kind(value)}")
        return value


def _join(prefix: str, key: str) -> str:
    return f"{prefix}.{key}" if prefix else key


def _kind(value) -> str:
    if isinstance(value, dict):
        return "a table"
    if isinstance(value, list):
        return "an array"
    return f"{type(value).__name__} {value!r}"


def _load_toml(path: Path, notes: list[str]) -> Scene:
    try:
        with open(path, "rb") as f:
            doc = tomllib.load(f)
    except tomllib.TOMLDecodeError as exc:
        raise SceneError(f"{path}: not valid TOML: {exc}") from None
    except UnicodeDecodeError as exc:
        raise SceneError(f"{path}: not valid TOML (not UTF-8): {exc}") from None
    t = _Toml(path)
    t.table(doc, "", _TOP_KEYS, required=("robot", "planning"))
    name = t.string(doc["name"], "name") if "name" in doc else path.stem
    base = path.parent

    # Robot.
    spec = t.table(doc["robot"], "robot", _ROBOT_KEYS)
    vertices, faces, source = _toml_shape(t, spec, "robot", base)
    rotation = _euler_xyz(t.vector(spec["orientation"], "robot.orientation")
                          if "orientation" in spec else (0.0, 0.0, 0.0))
    reference = (t.vector(spec["reference_point"], "robot.reference_point")
                 if "reference_point" in spec else np.zeros(3))
    if "mesh" in spec:
        scale = _toml_scale(t, spec, "robot")
        vertices, reference = vertices * scale, reference * scale
    robot = Body(
        name=Path(spec["mesh"]).name if "mesh" in spec else "robot",
        vertices=_transform(vertices, rotation),
        faces=faces,
        source=source,
    )
    reference = _transform(reference[None], rotation)[0]

    # Planning problem.
    plan = t.table(doc["planning"], "planning", _PLANNING_KEYS, required=_PLANNING_KEYS[:3])
    raw = plan["bounds"]
    if not isinstance(raw, list) or len(raw) != 2:
        raise t.error("planning.bounds", "expected [[x0, y0, z0], [x1, y1, z1]] (two corners)")
    bounds = np.stack([t.vector(raw[i], f"planning.bounds[{i}]") for i in range(2)])
    if (bounds[0] > bounds[1]).any():
        axis = "xyz"[int(np.argmax(bounds[0] > bounds[1]))]
        raise t.error("planning.bounds", f"the lower corner exceeds the upper corner in {axis}: "
                                         f"{bounds.tolist()}")
    ends = {}
    for key in ("start", "goal"):
        ends[key] = t.vector(plan[key], f"planning.{key}")
        if not _inside(ends[key], bounds):
            raise t.error(f"planning.{key}", f"{ends[key].tolist()} is outside the bounds "
                                             f"{bounds.tolist()}")

    # Obstacles.
    entries = doc.get("obstacles", [])
    if not isinstance(entries, list):
        raise t.error("obstacles", "expected an array of tables ([[obstacles]] entries)")
    obstacles, names = [], {}
    for i, entry in enumerate(entries):
        key = f"obstacles[{i}]"
        if isinstance(entry, dict) and isinstance(entry.get("name"), str):
            key += f" ({entry['name']!r})"
        t.table(entry, key, _OBSTACLE_KEYS)
        obstacle_name = (t.string(entry["name"], f"{key}.name") if "name" in entry
                         else f"obstacle-{i}")
        if obstacle_name in names:
            raise t.error(f"{key}.name", f"{obstacle_name!r} is already the name of "
                                         f"obstacles[{names[obstacle_name]}]")
        names[obstacle_name] = i
        vertices, faces, source = _toml_shape(t, entry, key, base)
        if "mesh" in entry:
            vertices = vertices * _toml_scale(t, entry, key)
        # its own name: ``rotation`` is the robot's, the scene's start rotation below
        turn = (_euler_xyz(t.vector(entry["orientation"], f"{key}.orientation"))
                if "orientation" in entry else None)
        position = t.vector(entry["position"], f"{key}.position") if "position" in entry else None
        obstacles.append(Body(obstacle_name, _transform(vertices, turn, position), faces,
                              source))

    goal_rotation = (_euler_xyz(t.vector(plan["goal_orientation"], "planning.goal_orientation"))
                     if "goal_orientation" in plan else rotation)
    return Scene(name=name, path=path, obstacles=tuple(obstacles), robot=robot,
                 reference_point=reference, bounds=bounds, start=ends["start"],
                 goal=ends["goal"], start_rotation=rotation, goal_rotation=goal_rotation)


def _toml_shape(t: _Toml, spec: dict, key: str, base: Path):
    """Vertices, faces and source of a ``mesh = ...`` or ``box = [...]`` entry."""
    if ("mesh" in spec) == ("box" in spec):
        raise t.error(key, "give exactly one of 'mesh' (a file) or 'box' (extents)")
    if "box" in spec:
        if "scale" in spec:
            raise t.error(f"{key}.scale", "applies to meshes only; give the box's extents")
        vertices, faces = _box(t.vector(spec["box"], f"{key}.box", positive=True))
        return vertices, faces, "box"
    mesh = (base / t.string(spec["mesh"], f"{key}.mesh")).resolve()
    vertices, faces = _read_mesh(mesh, f"{t.path}: {key}.mesh")
    return vertices, faces, str(mesh)


def _toml_scale(t: _Toml, spec: dict, key: str):
    if "scale" not in spec:
        return 1.0
    value = spec["scale"]
    if isinstance(value, list):
        return t.vector(value, f"{key}.scale", positive=True)
    return t.number(value, f"{key}.scale", positive=True)


# --------------------------------------------------------------------------------------
# OMPL.app .cfg
#
# Format as in ompl/omplapp resources/3D/cubicles.cfg and resources/3D/alpha-1.5.cfg:
#   [problem]  name, robot, world, start.x/.y/.z, start.theta, start.axis.x/.y/.z,
#              goal.*, volume.min.x .. volume.max.z, (objective, control, sampler, ...)
#   [benchmark], [planner]  (ignored here)


def _load_cfg(path: Path, notes: list[str]) -> Scene:
    parser = configparser.ConfigParser(strict=False, interpolation=None)
    try:
        parser.read_string(path.read_text(errors="replace"), source=str(path))
    except configparser.Error as exc:
        raise SceneError(f"{path}: not a valid .cfg (INI) file: {exc}") from None
    if not parser.has_section("problem"):
        raise SceneError(f"{path}: no [problem] section")
    problem = parser["problem"]

    def text(key: str) -> str:
        value = problem.get(key, "").strip()
        if not value:
            raise SceneError(f"{path}: [problem] {key}: missing (required)")
        return value

    def number(key: str, default: float | None = None) -> float:
        if key not in problem:
            if default is None:
                raise SceneError(f"{path}: [problem] {key}: missing (required)")
            return default
        try:
            x = float(problem[key])
        except ValueError:
            raise SceneError(f"{path}: [problem] {key}: expected a number, "
                             f"got {problem[key]!r}") from None
        if not math.isfinite(x):
            raise SceneError(f"{path}: [problem] {key}: must be finite, got {problem[key]!r}")
        return x

    three_d = "start.z" in problem
    axes = "xyz" if three_d else "xy"
    start = np.array([number(f"start.{a}") for a in axes] + ([] if three_d else [0.0]))
    goal = np.array([number(f"goal.{a}") for a in axes] + ([] if three_d else [0.0]))

    def rotation(which: str) -> np.ndarray:
        if not three_d:
            return _axis_angle((0.0, 0.0, 1.0), number(f"{which}.theta", 0.0))
        keys = [f"{which}.axis.{a}" for a in "xyz"] + [f"{which}.theta"]
        given = [k for k in keys if k in problem]
        if not given:
            return np.eye(3)
        if len(given) < len(keys):
            missing = ", ".join(k for k in keys if k not in problem)
            raise SceneError(f"{path}: [problem] {missing}: missing (a rotation needs "
                             f"{which}.axis.x/.y/.z and {which}.theta)")
        return _axis_angle([number(k) for k in keys[:3]], number(keys[3]))

    r_start, r_goal = rotation("start"), rotation("goal")
    if not np.allclose(r_start, r_goal, rtol=0.0, atol=1e-12):
        notes.append(f"{path}: [problem] the goal rotation differs from the start rotation: "
                     "planning turns the robot on its way (the default); translation-only "
                     "planning (--no-turns) keeps the start orientation")

    base = path.parent
    world_path = (base / text("world")).resolve()
    robot_path = (base / text("robot")).resolve()
    world_v, world_f = _read_mesh(world_path, f"{path}: [problem] world")
    robot_file = read_mesh_file(robot_path, f"{path}: [problem] robot")
    robot_v, robot_f = robot_file.vertices, robot_file.faces
    centre = robot_file.assimp_centre.copy()
    if not three_d:
        centre[2] = 0.0  # OMPL.app: in 2D the robot keeps its own z (robotShift z = 0)
    world = Body(world_path.name, world_v, world_f, str(world_path))
    robot = Body(robot_path.name, _transform(robot_v, r_start), robot_f, str(robot_path))
    reference = _transform(centre[None], r_start)[0]

    volume = [f"volume.{end}.{a}" for end in ("min", "max") for a in axes]
    given = [k for k in volume if k in problem]
    if given and len(given) < len(volume):
        missing = ", ".join(k for k in volume if k not in problem)
        raise SceneError(f"{path}: [problem] {missing}: missing (the volume needs all of "
                         + ", ".join(volume) + ")")
    if given:
        values = np.array([number(k) for k in volume]).reshape(2, len(axes))
        bounds = np.zeros((2, 3))
        bounds[:, : len(axes)] = values
        if (bounds[0] > bounds[1]).any():
            raise SceneError(f"{path}: [problem] volume.min exceeds volume.max: "
                             f"{bounds.tolist()}")
        for key, point in (("start", start), ("goal", goal)):
            if not _inside(point, bounds):
                raise SceneError(f"{path}: [problem] {key} {point.tolist()} is outside the "
                                 f"volume {bounds.tolist()}")
    else:
        bounds = np.stack([np.minimum.reduce([world.bounds[0], start, goal]),
                           np.maximum.reduce([world.bounds[1], start, goal])])
        if not three_d:
            bounds[:, 2] = 0.0
        notes.append(f"{path}: [problem] no volume.min/max given; bounds inferred as "
                     f"OMPL.app does (the world's bounding box with start and goal): "
                     f"{bounds.tolist()}")

    name = problem.get("name", "").strip() or path.stem
    return Scene(name=name, path=path, obstacles=(world,), robot=robot,
                 reference_point=reference, bounds=bounds, start=start, goal=goal,
                 start_rotation=r_start, goal_rotation=r_goal)


# --------------------------------------------------------------------------------------
# Parasol (PPL) .env / .query / .robot


_OPTION = re.compile(r"(?<!\S)-[A-Za-z]\([^)]*\)")


class _Lines:
    """The meaningful lines of a Parasol file: comments ('#' to end of line) and blanks dropped."""

    def __init__(self, path: Path):
        self.path = path
        self.items = []
        for number, line in enumerate(path.read_text(errors="replace").splitlines(), 1):
            line = line.split("#", 1)[0].strip()
            if line:
                self.items.append((number, line))
        self.pos = 0

    def error(self, line: int | None, message: str) -> SceneError:
        return SceneError(f"{self.path}:{line}: {message}" if line else f"{self.path}: {message}")

    def peek(self):
        return self.items[self.pos] if self.pos < len(self.items) else (None, None)

    def next(self, what: str) -> tuple[int, str]:
        if self.pos >= len(self.items):
            last = self.items[-1][0] if self.items else None
            raise self.error(last, f"file ends early: expected {what}")
        self.pos += 1
        return self.items[self.pos - 1]

    def count(self, what: str) -> int:
        line, text = self.next(what)
        if not re.fullmatch(r"\d+", text):
            raise self.error(line, f"expected {what} (a non-negative integer), got {text!r}")
        return int(text)

    def numbers(self, line: int, words: list[str], what: str) -> np.ndarray:
        try:
            values = np.array([float(w) for w in words], dtype=np.float64)
        except ValueError:
            bad = next(w for w in words if not _is_float(w))
            raise self.error(line, f"expected numbers ({what}), got {bad!r}") from None
        if not np.isfinite(values).all():
            raise self.error(line, f"{what} must be finite, got {' '.join(words)}")
        return values


def _body_line(lines: _Lines, line: int, text: str):
    """``file [-x(...)]... rest``: the file name, the COM adjustment and the other words."""
    options = _OPTION.findall(text)
    words = _OPTION.sub(" ", text).split()
    adjust = "COM"
    for option in options:
        if option[1].lower() == "a":
            adjust = option[3:-1].strip().upper()
            if adjust not in ("COM", "SURFACE", "NONE"):
                raise lines.error(line, f"unknown COM adjustment {option!r} "
                                        "(expected -a(COM), -a(SURFACE) or -a(NONE))")
    if not words:
        raise lines.error(line, "expected a body line: geometry file, then options and pose")
    return words[0], adjust, words[1:]


def _ppl_mesh(lines: _Lines, line: int, name: str, adjust: str):
    """A body's mesh as PPL loads it: vertices with the COM adjustment applied."""
    mesh_path = (lines.path.parent / name).resolve()
    vertices, faces = _read_mesh(mesh_path, f"{lines.path}:{line}")
    centre = _obj_vertex_mean(mesh_path) if mesh_path.suffix.lower() == ".obj" else None
    if centre is None:
        centre = vertices.mean(axis=0)
    if adjust == "SURFACE":
        centre = centre * np.array([1.0, 0.0, 1.0])
    elif adjust == "NONE":
        centre = np.zeros(3)
    return mesh_path, vertices, faces, centre


def _ppl_robot_block(lines: _Lines):
    """A robot multibody: body count, body lines, Connections and their count."""
    line, _ = lines.peek()
    bodies = lines.count("the robot's body count")
    if bodies != 1:
        raise lines.error(line, f"only single-body robots are supported, found {bodies} bodies")
    line, text = lines.next("the robot's body line")
    name, adjust, rest = _body_line(lines, line, text)
    kinds = [w.lower() for w in rest]
    if len(kinds) != 2 or kinds[0] not in ("volumetric", "planar") or kinds[1] not in (
            "rotational", "translational"):
        raise lines.error(line, "expected the robot base as 'Volumetric|Planar "
                                f"Rotational|Translational', got {' '.join(rest)!r}")
    connections = 0
    tag_line, tag = lines.peek()
    if tag is not None and tag.lower() == "connections":
        lines.next("Connections")
        connections = lines.count("the number of connections")
    if connections:
        raise lines.error(tag_line, f"articulated robots are not supported ({connections} "
                                    "connections)")
    return line, name, adjust, kinds[0], kinds[1]


def _sibling(path: Path, suffix: str) -> Path:
    """The file with ``suffix`` beside ``path``: the same stem, else the only such file."""
    same = path.with_suffix(suffix)
    if same.is_file():
        return same
    found = sorted(p for p in path.parent.iterdir() if p.suffix.lower() == suffix and p.is_file())
    if len(found) == 1:
        return found[0]
    if found:
        raise SceneError(f"{path}: cannot tell which {suffix} file belongs to it: "
                         + ", ".join(p.name for p in found) + f" (name one {same.name})")
    raise SceneError(f"{path}: no {suffix} file beside it (looked for '{same}')")


def _load_parasol(path: Path, notes: list[str]) -> Scene:
    if path.suffix.lower() == ".query":
        env_path, query_path = _sibling(path, ".env"), path
    else:
        env_path, query_path = path, _sibling(path, ".query")

    # Environment: boundary and passive multibodies.
    env = _Lines(env_path)
    bounds = None
    line, text = env.next("'Multibodies'")
    if text.lower().startswith("boundary"):
        match = re.fullmatch(r"boundary\s+(\w+)\s*\[(.*)\]", text, flags=re.IGNORECASE)
        if not match:
            raise env.error(line, f"expected 'Boundary Box [x0:x1 ; y0:y1 ; z0:z1]', got {text!r}")
        if match.group(1).lower() in ("box", "bbx", "boundingbox"):
            ranges = [r.split(":") for r in match.group(2).split(";")]
            if len(ranges) != 3 or any(len(r) != 2 for r in ranges):
                raise env.error(line, "expected three ranges 'lo:hi' in the boundary box, got "
                                      f"[{match.group(2)}]")
            bounds = env.numbers(line, [v for r in ranges for v in r], "boundary box")
            bounds = bounds.reshape(3, 2).T.copy()
            if (bounds[0] > bounds[1]).any():
                raise env.error(line, f"boundary box lower end exceeds the upper end: "
                                      f"{bounds.tolist()}")
        else:
            notes.append(f"{env_path}:{line}: boundary type {match.group(1)!r} is not a box; "
                         "bounds are inferred from the obstacles")
        line, text = env.next("'Multibodies'")
    if text.lower() != "multibodies":
        raise env.error(line, f"expected 'Multibodies', got {text!r}")
    count = env.count("the number of multibodies")
    obstacles, active = [], None
    for _ in range(count):
        line, kind = env.next("a multibody type (Passive, Active or Internal)")
        kind = kind.lower()
        if kind in ("passive", "internal"):
            line, text = env.next("an obstacle body line")
            name, adjust, rest = _body_line(env, line, text)
            if rest and rest[0].lower() == "fixed":
                rest = rest[1:]
            if len(rest) != 6:
                raise env.error(line, f"expected the pose 'x y z rx ry rz' after {name!r}, got "
                                      f"{len(rest)} values")
            pose = env.numbers(line, rest, "pose")
            mesh_path, vertices, faces, centre = _ppl_mesh(env, line, name, adjust)
            world = _transform(_transform(vertices, None, -centre), _euler_xyz(pose[3:]), pose[:3])
            obstacles.append(Body(Path(name).name, world, faces, str(mesh_path)))
        elif kind == "active":
            if active is not None:
                raise env.error(line, "only one robot (Active multibody) is supported")
            active = (env, _ppl_robot_block(env))
        else:
            raise env.error(line, f"unknown multibody type {kind!r} (expected Passive, Active "
                                  "or Internal)")

    # Robot: an Active multibody of the .env (old self-contained format), else the .robot.
    if active is not None:
        spec = active
    else:
        robot_lines = _Lines(_sibling(env_path, ".robot"))
        spec = (robot_lines, _ppl_robot_block(robot_lines))
    robot_lines, (robot_line, robot_name, adjust, base, movement) = spec
    mesh_path, robot_v, robot_f, centre = _ppl_mesh(robot_lines, robot_line, robot_name, adjust)

    # Query: start and goal.
    query = _Lines(query_path)
    positional = 3 if base == "volumetric" else 2
    rotational = 0 if movement == "translational" else (3 if base == "volumetric" else 1)
    configs = []
    for line, text in query.items:
        values = query.numbers(line, text.split(), "configuration")
        if len(values) != 1 + positional + rotational:
            raise query.error(line, f"expected a robot index and {positional + rotational} DOF "
                                    f"values ({base} {movement} robot), got {len(values)} numbers")
        position = np.zeros(3)
        position[:positional] = values[1:1 + positional]
        turns = values[1 + positional:] * 180.0  # units of pi -> degrees
        angles = turns if rotational == 3 else np.r_[0.0, 0.0, turns.sum()]
        configs.append((line, position, _euler_xyz(angles)))
    if len(configs) < 2:
        raise query.error(None, f"expected a start and a goal configuration, found {len(configs)}")
    if len(configs) > 2:
        notes.append(f"{query_path}: {len(configs) - 2} intermediate configurations (lines "
                     f"{configs[1][0]}..{configs[-2][0]}) are ignored; planning from the first "
                     "to the last")
    (start_line, start, r_start), (goal_line, goal, r_goal) = configs[0], configs[-1]
    if not np.allclose(r_start, r_goal, rtol=0.0, atol=1e-12):
        notes.append(f"{query_path}:{goal_line}: the goal orientation differs from the start's "
                     f"(line {start_line}): planning turns the robot on its way (the default); "
                     "translation-only planning (--no-turns) keeps the start orientation")

    robot = Body(Path(robot_name).name, _transform(robot_v, r_start), robot_f, str(mesh_path))
    reference = _transform(centre[None], r_start)[0]

    if bounds is None:
        radius = float(np.linalg.norm(robot.vertices - reference, axis=1).max())
        boxes = [b.bounds for b in obstacles] or [np.stack([start, start])]
        bounds = np.stack([np.minimum.reduce([b[0] for b in boxes]) - radius,
                           np.maximum.reduce([b[1] for b in boxes]) + radius])
        bounds = np.stack([np.minimum.reduce([bounds[0], start, goal]),
                           np.maximum.reduce([bounds[1], start, goal])])
        notes.append(f"{env_path}: no boundary box; bounds inferred from the obstacles padded by "
                     f"the robot's radius {radius:.6g}: {bounds.tolist()}")
    else:
        for key, point, line in (("start", start, start_line), ("goal", goal, goal_line)):
            if not _inside(point, bounds):
                raise query.error(line, f"the {key} {point.tolist()} is outside the boundary "
                                        f"box {bounds.tolist()} of {env_path.name}")

    return Scene(name=env_path.stem, path=path, obstacles=tuple(obstacles), robot=robot,
                 reference_point=reference, bounds=bounds, start=start, goal=goal,
                 start_rotation=r_start, goal_rotation=r_goal)
