"""Scenes: the TOML format, OMPL.app .cfg and Parasol files, and the shipped scenes."""

from __future__ import annotations

import importlib.util
import itertools
import math
import shutil
import textwrap
import warnings
from pathlib import Path

import numpy as np
import pytest
import trimesh

import cspace.mesh.files as meshfile
import cspace.scene.files as scene_module
from cspace import ConvexPolytope, convex_minkowski_sum
from cspace.scene.scene import Body, Scene
from cspace.errors import SceneError
from cspace.scene.files import load_scene

from zoo import l_shape  # tests/ is on sys.path (rootdir conftest)

SCENES = Path(__file__).resolve().parents[1] / "scenes"
SHIPPED = ("window", "comb", "maze", "cavity")


def load_quietly(path) -> Scene:
    """load_scene with every warning turned into an error."""
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        return load_scene(path)


def write(path: Path, text: str) -> Path:
    path.parent.mkdir(parents=True, exist_ok=True)
    path.write_text(textwrap.dedent(text).lstrip())
    return path


def write_mesh(path: Path, vertices, faces) -> Path:
    path.parent.mkdir(parents=True, exist_ok=True)
    trimesh.Trimesh(np.asarray(vertices, float), np.asarray(faces), process=False).export(path)
    return path


def box_mesh(extents=(1.0, 1.0, 1.0), centre=(0.0, 0.0, 0.0)):
    m = trimesh.creation.box(extents=extents)
    return m.vertices + np.asarray(centre, float), m.faces


def corners(body: Body) -> set[tuple[float, ...]]:
    return {tuple(v) for v in body.vertices.tolist()}


# --------------------------------------------------------------------------------------
# shipped scenes


@pytest.fixture(scope="module", params=SHIPPED)
def shipped(request) -> Scene:
    return load_quietly(SCENES / f"{request.param}.toml")


def test_shipped_scene_loads_and_is_consistent(shipped):
    assert shipped.name in SHIPPED
    assert shipped.path == SCENES / f"{shipped.name}.toml"
    assert 1 <= len(shipped.obstacles) <= 40
    lo, hi = shipped.bounds
    for point in (shipped.start, shipped.goal):
        assert point.shape == (3,) and point.dtype == np.float64
        assert (lo <= point).all() and (point <= hi).all()
    assert len({body.name for body in shipped.obstacles}) == len(shipped.obstacles)
    text = (SCENES / f"{shipped.name}.toml").read_text()
    assert "Narrowest clearance:" in text


def test_shipped_obstacles_are_closed_convex_boxes(shipped):
    for body in shipped.obstacles:
        assert body.vertices.shape == (8, 3) and body.faces.shape == (12, 3)
        assert body.vertices.dtype == np.float64 and body.faces.dtype == np.int64
        poly = ConvexPolytope.from_mesh((body.vertices, body.faces), name=body.name)
        assert poly.n_facets == 6, body.name
        # Axis aligned, and wound outward as given (positive signed volume).
        lo, hi = body.bounds
        assert corners(body) == set(itertools.product(*zip(lo, hi)))
        tri = body.vertices[body.faces]
        signed = np.einsum("ij,ij->i", tri[:, 0], np.cross(tri[:, 1], tri[:, 2])).sum() / 6
        assert math.isclose(signed, np.prod(hi - lo), rel_tol=1e-12)


def test_shipped_robot_is_convex(shipped):
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        robot = shipped.robot_polytope()
    assert robot.n_facets in (6, 8)  # the maze's box, the octahedron


def test_window_opening_is_barely_wider_than_the_robot():
    scene = load_quietly(SCENES / "window.toml")
    walls = {body.name: body.bounds for body in scene.obstacles}
    assert set(walls) == {"left-post", "right-post", "sill", "lintel"}
    opening_y = walls["right-post"][0, 1] - walls["left-post"][1, 1]
    opening_z = walls["lintel"][0, 2] - walls["sill"][1, 2]
    rel = scene.robot.vertices - scene.reference_point
    robot_y, robot_z = np.ptp(rel[:, 1]), np.ptp(rel[:, 2])
    for opening, size in ((opening_y, robot_y), (opening_z, robot_z)):
        assert size < opening < 1.05 * size
    # The window is centred on the wall's height range and the wall is thin.
    thickness = {float(np.ptp(b[:, 0])) for b in walls.values()}
    assert thickness == {0.05}


def test_generated_files_are_up_to_date():
    spec = importlib.util.spec_from_file_location("scene_generate", SCENES / "generate.py")
    generate = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(generate)
    for rel, text in generate.render().items():
        assert (SCENES / rel).read_text() == text, f"{rel} is stale: run scenes/generate.py"


# Paths the scenes were designed around: every point on them is free, while the straight
# segment from start to goal is blocked.
WAYPOINTS = {
    "window": [(-0.8, 0.0, 1.5), (0.8, 0.0, 1.5)],
    "comb": [(-2.0, 0.325, 1.3), (0.0, 0.325, 1.3), (0.0, 0.0, 1.3)],
    "cavity": [(-2.6, 0.0, 2.9), (0.0, 0.0, 2.9), (0.0, 0.0, 1.0)],
    "maze": [tuple((c + 0.5) * 1.2 for c in cell) for cell in [
        (0, 0, 0), (1, 0, 0), (2, 0, 0), (2, 1, 0), (1, 1, 0), (0, 1, 0), (0, 2, 0), (1, 2, 0),
        (2, 2, 0), (2, 2, 1), (2, 1, 1), (2, 0, 1), (1, 0, 1), (1, 1, 1), (1, 2, 1), (0, 2, 1),
        (0, 1, 1), (0, 0, 1)]],
}


def c_obstacle_depth(scene: Scene, points: np.ndarray) -> np.ndarray:
    """(k,) float: the largest signed distance of each point to a C-obstacle's facet planes
    minimised over obstacles (> 0: free of every obstacle; < 0: inside one)."""
    grid = scene.grid()
    minus_robot = scene.robot_polytope(grid).reflected(scene.reference_point)
    depth = np.full(len(points), np.inf)
    for body in scene.obstacles:
        co = convex_minkowski_sum(ConvexPolytope.from_mesh((body.vertices, body.faces),
                                                           grid=grid), minus_robot).polytope
        normals = co.normals.astype(np.float64)
        normals /= np.linalg.norm(normals, axis=1, keepdims=True)
        anchors = co.vertices[co.facet_indices[co.facet_offsets[:-1]]]
        offsets = np.einsum("ij,ij->i", normals, anchors)
        depth = np.minimum(depth, (points @ normals.T - offsets).max(axis=1))
    return depth


def polyline(points, step=0.005) -> np.ndarray:
    out = [np.asarray(points[0], float)]
    for a, b in zip(points, points[1:]):
        a, b = np.asarray(a, float), np.asarray(b, float)
        n = max(1, int(np.ceil(np.linalg.norm(b - a) / step)))
        out += list(a + (b - a) * (np.arange(1, n + 1)[:, None] / n))
    return np.array(out)


@pytest.mark.parametrize("name", SHIPPED)
def test_designed_path_is_free_and_direct_path_is_blocked(name):
    scene = load_quietly(SCENES / f"{name}.toml")
    path = polyline([scene.start, *WAYPOINTS[name], scene.goal])
    assert (c_obstacle_depth(scene, path) > 1e-9).all()
    assert (c_obstacle_depth(scene, polyline([scene.start, scene.goal])) < 0).any()


# --------------------------------------------------------------------------------------
# TOML: poses and the documented example


def test_box_pose_round_trip(tmp_path):
    path = write(tmp_path / "s.toml", """
        [robot]
        box = [0.2, 0.2, 0.2]
        [planning]
        bounds = [[-5, -5, -5], [5, 5, 5]]
        start = [-4, 0, 0]
        goal = [4, 0, 0]
        [[obstacles]]
        name = "yawed"
        box = [2.0, 1.0, 0.5]
        position = [1.0, 2.0, 3.0]
        orientation = [0, 0, 90]
        [[obstacles]]
        name = "rolled-then-yawed"
        box = [2.0, 1.0, 0.5]
        orientation = [90, 0, 90]
        """)
    scene = load_quietly(path)
    yawed, turned = scene.obstacles
    # Yaw 90: the 2.0 extent now runs along y; exact (quarter turns use exact cos/sin).
    assert corners(yawed) == set(itertools.product((0.5, 1.5), (1.0, 3.0), (2.75, 3.25)))
    # Extrinsic XYZ: roll 90 first (y <-> z extents), then yaw 90 (x <-> y extents).
    assert corners(turned) == set(itertools.product((-0.25, 0.25), (-1.0, 1.0), (-0.5, 0.5)))
    assert yawed.source == "box" and scene.name == "s"


def test_robot_orientation_moves_the_reference_point(tmp_path):
    octa = SCENES / "meshes" / "octahedron.obj"
    path = write(tmp_path / "s.toml", f"""
        [robot]
        mesh = "{octa}"
        scale = 2.0
        orientation = [0, 0, 90]
        reference_point = [0.5, 0, 0]
        [planning]
        bounds = [[-5, -5, -5], [5, 5, 5]]
        start = [0, 0, 0]
        goal = [1, 1, 1]
        """)
    scene = load_quietly(path)
    # The tip (0.5, 0, 0) of the file is scaled to (1, 0, 0), then turned to (0, 1, 0).
    assert scene.reference_point.tolist() == [0.0, 1.0, 0.0]
    assert corners(scene.robot) == {(0.0, 1.0, 0.0), (0.0, -1.0, 0.0), (-0.5, 0.0, 0.0),
                                    (0.5, 0.0, 0.0), (0.0, 0.0, 0.5), (0.0, 0.0, -0.5)}
    assert scene.robot.source == str(octa) and scene.robot.name == "octahedron.obj"


def test_mesh_obstacle_scale_then_rotation_then_position(tmp_path):
    write_mesh(tmp_path / "m" / "unit.stl", *box_mesh(centre=(0.5, 0.5, 0.5)))
    path = write(tmp_path / "s.toml", """
        [robot]
        box = [0.1, 0.1, 0.1]
        [planning]
        bounds = [[-9, -9, -9], [9, 9, 9]]
        start = [5, 5, 5]
        goal = [6, 6, 6]
        [[obstacles]]
        mesh = "m/unit.stl"
        scale = [2, 1, 1]
        orientation = [0, 0, 90]
        position = [10, 0, 0]
        """)
    body = load_quietly(path).obstacles[0]
    # [0,1]^3 -> [0,2]x[0,1]x[0,1] -> yaw 90: [-1,0]x[0,2]x[0,1] -> + (10, 0, 0).
    assert corners(body) == set(itertools.product((9.0, 10.0), (0.0, 2.0), (0.0, 1.0)))
    assert body.name == "obstacle-0" and body.source == str((tmp_path / "m/unit.stl").resolve())


def test_an_obstacle_orientation_is_not_the_robot_start_orientation(tmp_path):
    # The scene's start (and, without goal_orientation, goal) rotation is the robot's own,
    # whatever the obstacles' orientations; the last obstacle's used to leak into both.
    for robot_turn, want in (("", np.eye(3)), ("orientation = [0, 0, 90]\n",
                                                 np.array([[0.0, -1, 0], [1, 0, 0], [0, 0, 1]]))):
        path = write(tmp_path / "s.toml", f"""
            [robot]
            box = [0.1, 0.2, 0.3]
            {robot_turn}
            [planning]
            bounds = [[-9, -9, -9], [9, 9, 9]]
            start = [5, 5, 5]
            goal = [6, 6, 6]
            [[obstacles]]
            box = [1, 2, 3]
            orientation = [0, 0, 45]
            position = [1, 0, 0]
            """)
        scene = load_quietly(path)
        np.testing.assert_array_equal(scene.start_rotation, want)
        np.testing.assert_array_equal(scene.goal_rotation, want)
        assert corners(scene.obstacles[0]) != set(itertools.product((0.5, 1.5), (-1, 1),
                                                                     (-1.5, 1.5)))  # turned


def test_documented_example_loads(tmp_path):
    doc = scene_module.__doc__
    block = doc.split("A complete example::\n\n", 1)[1]
    lines = []
    for line in block.splitlines():
        if line.strip() and not line.startswith("    "):
            break
        lines.append(line)
    write(tmp_path / "example.toml", "\n".join(lines))
    shutil.copy(SCENES / "meshes" / "octahedron.obj", tmp_path / "robot.obj")
    (tmp_path / "meshes").mkdir()
    shutil.copy(SCENES / "meshes" / "octahedron.obj", tmp_path / "meshes" / "robot.obj")
    write_mesh(tmp_path / "meshes" / "rock.stl", *box_mesh((0.4, 0.4, 0.4)))
    scene = load_quietly(tmp_path / "example.toml")
    assert scene.name == "example"
    assert [b.name for b in scene.obstacles] == ["left-post", "obstacle-1"]
    assert np.allclose(scene.robot.vertices.max(axis=0)[:2],
                       [0.5 * math.cos(math.radians(30)), 0.5 * math.sin(math.radians(30))])


def test_grid_covers_the_c_obstacles(tmp_path):
    path = write(tmp_path / "s.toml", """
        [robot]
        box = [2, 2, 2]
        reference_point = [-1, -1, -1]
        [planning]
        bounds = [[0, 0, 0], [1, 1, 1]]
        start = [0, 0, 0]
        goal = [1, 1, 1]
        [[obstacles]]
        box = [1, 1, 1]
        position = [-3, 0, 0]
        """)
    scene = load_quietly(path)
    # Robot relative to its reference point spans [0, 2]^3: at the upper bound it reaches 3;
    # the C-obstacle [-3.5, -2.5] - [0, 2] reaches -5.5. The grid holds all of it.
    grid = scene.grid()
    corners = np.array([[-5.5, -2.5, -2.5], [3.0, 3.0, 3.0], [-5.5, 3.0, -2.5]])
    assert (grid.to_float(grid.snap(corners)) == corners).all()
    assert grid.step <= 2.0**-22  # about 2**-26 of its 8.5 span


# --------------------------------------------------------------------------------------
# TOML errors

BASE = """
    name = "t"
    [robot]
    box = [0.5, 0.5, 0.5]
    [planning]
    bounds = [[-1, -1, -1], [1, 1, 1]]
    start = [-0.5, 0, 0]
    goal = [0.5, 0, 0]
    [[obstacles]]
    name = "block"
    box = [0.1, 0.1, 0.1]
    position = [0, 0.8, 0]
    """


@pytest.mark.parametrize(
    "old, new, match",
    [
        ('name = "t"', 'name = "t"\ncolour = "red"', r"colour: unknown key"),
        ("[robot]", "[robot]\norientaton = [0, 0, 1]",
         r"robot\.orientaton: unknown key \(did you mean 'orientation'\?\)"),
        ('name = "block"', 'name = "block"\npostion = [0, 0, 0]',
         r"obstacles\[0\] \('block'\)\.postion: unknown key \(did you mean 'position'\?\)"),
        ("start = [-0.5, 0, 0]\n", "", r"planning\.start: missing \(required\)"),
        ("[robot]\nbox = [0.5, 0.5, 0.5]\n", "", r"robot: missing \(required\)"),
        ("start = [-0.5, 0, 0]", "start = [-2, 0, 0]",
         r"planning\.start: \[-2\.0, 0\.0, 0\.0\] is outside the bounds"),
        ("goal = [0.5, 0, 0]", "goal = [0.5, nan, 0]", r"planning\.goal\[1\]: must be finite"),
        ("position = [0, 0.8, 0]", "position = [0, inf, 0]",
         r"obstacles\[0\] \('block'\)\.position\[1\]: must be finite"),
        ("box = [0.1, 0.1, 0.1]", "box = [0.1, 0, 0.1]", r"\.box\[1\]: must be positive"),
        ("box = [0.1, 0.1, 0.1]", "box = [0.1, 0.1]", r"\.box: expected 3 numbers"),
        ("box = [0.1, 0.1, 0.1]", "box = [0.1, true, 0.1]", r"\.box\[1\]: expected a number"),
        ("box = [0.5, 0.5, 0.5]", 'box = [0.5, 0.5, 0.5]\nmesh = "r.obj"',
         r"robot: give exactly one of 'mesh'"),
        ("box = [0.5, 0.5, 0.5]", "box = [0.5, 0.5, 0.5]\nscale = 2",
         r"robot\.scale: applies to meshes only"),
        ("bounds = [[-1, -1, -1], [1, 1, 1]]", "bounds = [[1, -1, -1], [-1, 1, 1]]",
         r"planning\.bounds: the lower corner exceeds the upper corner in x"),
        ('name = "t"', 'name = "t"\n[[obstacles]]\nname = "block"\nbox = [1, 1, 1]',
         r"obstacles\[1\] \('block'\)\.name: 'block' is already the name of obstacles\[0\]"),
        ("[planning]", "[planning", r"not valid TOML"),
    ],
)
def test_toml_errors_name_the_key(tmp_path, old, new, match):
    text = textwrap.dedent(BASE)
    assert old in text
    path = write(tmp_path / "bad.toml", text.replace(old, new, 1))
    with pytest.raises(SceneError, match=match) as info:
        load_scene(path)
    assert str(path) in str(info.value)


def test_missing_mesh_file_names_the_resolved_path(tmp_path):
    text = textwrap.dedent(BASE).replace("box = [0.5, 0.5, 0.5]", 'mesh = "meshes/../gone.obj"')
    path = write(tmp_path / "sub" / "s.toml", text)
    with pytest.raises(SceneError, match=r"robot\.mesh: mesh file not found") as info:
        load_scene(path)
    assert f"'{(tmp_path / 'sub' / 'gone.obj').resolve()}'" in str(info.value)


def test_unreadable_mesh_and_missing_scene(tmp_path):
    (tmp_path / "junk.obj").write_text("this is not a mesh\n")
    text = textwrap.dedent(BASE).replace("box = [0.5, 0.5, 0.5]", 'mesh = "junk.obj"')
    with pytest.raises(SceneError, match=r"robot\.mesh: .*junk\.obj"):
        load_scene(write(tmp_path / "s.toml", text))
    with pytest.raises(SceneError, match="scene file not found"):
        load_scene(tmp_path / "nowhere.toml")
    with pytest.raises(SceneError, match=r"unknown scene format '\.yaml'"):
        load_scene(tmp_path / "s.yaml")


def test_scene_constructor_checks_its_arrays():
    body = Body("b", *box_mesh(), source="box")
    args = dict(name="x", path=None, obstacles=(body,), robot=body, reference_point=[0, 0, 0],
                bounds=[[0, 0, 0], [1, 1, 1]], start=[0, 0, 0], goal=[1, 1, 1])
    scene = Scene(**args)
    assert not scene.start.flags.writeable and not body.vertices.flags.writeable
    with pytest.raises(SceneError, match="goal .* is outside the bounds"):
        Scene(**{**args, "goal": [2, 0, 0]})
    with pytest.raises(SceneError, match="bounds must have shape"):
        Scene(**{**args, "bounds": [0, 1]})
    with pytest.raises(SceneError, match="face indices"):
        Body("b", np.zeros((3, 3)), [[0, 1, 3]], source="x")
    with pytest.raises(SceneError):  # a SceneError is a ValueError and a CspaceError
        raise SceneError("x")
    assert issubclass(SceneError, ValueError)


# --------------------------------------------------------------------------------------
# robots that are not convex


def robot_scene(tmp_path, vertices, faces, name="robot.obj") -> Path:
    write_mesh(tmp_path / name, vertices, faces)
    return write(tmp_path / "s.toml", f"""
        [robot]
        mesh = "{name}"
        [planning]
        bounds = [[-5, -5, -5], [5, 5, 5]]
        start = [0, 0, 0]
        goal = [1, 1, 1]
        """)


def test_non_convex_robot_warns_and_uses_the_hull(tmp_path):
    vertices, faces = l_shape()
    scene = load_quietly(robot_scene(tmp_path, vertices, faces))
    with pytest.warns(UserWarning, match=r"robot 'robot\.obj' .* is not a closed convex mesh "
                                         r"\(NotConvexError"):
        robot = scene.robot_polytope()
    hull = ConvexPolytope.from_points(vertices)
    assert robot.volume6() == hull.volume6() and robot.n_facets == hull.n_facets


def test_open_robot_mesh_warns_and_uses_the_hull(tmp_path):
    vertices, faces = box_mesh()
    scene = load_quietly(robot_scene(tmp_path, vertices, faces[:-1], name="open.stl"))
    with pytest.warns(UserWarning, match=r"OpenMeshError"):
        robot = scene.robot_polytope()
    assert robot.n_facets == 6


# --------------------------------------------------------------------------------------
# OMPL.app .cfg
#
# Mimics ompl/omplapp resources/3D/cubicles.cfg (and alpha-1.5.cfg): a [problem] section with
# robot, world, start.x/.y/.z, start.theta, start.axis.x/.y/.z, goal.*, volume.min/max.*, then
# [benchmark] and [planner] sections this loader ignores.

CFG = """
    [problem]
    name = tiny
    robot = meshes/robot.stl
    world = meshes/world.obj
    start.x = -3.0
    start.y = 0.5
    start.z = 1.0
    start.theta = 1.5707963267948966
    start.axis.x = 0
    start.axis.y = 0
    start.axis.z = 2
    goal.x = 3.0
    goal.y = 0.5
    goal.z = 1.0
    goal.theta = 1.5707963267948966
    goal.axis.x = 0
    goal.axis.y = 0
    goal.axis.z = 1
    volume.min.x = -4
    volume.min.y = -4
    volume.min.z = -4
    volume.max.x = 4
    volume.max.y = 4
    volume.max.z = 4
    sampler = obstacle_based

    [benchmark]
    time_limit = 20.0

    [planner]
    rrt =
    """


@pytest.fixture()
def cfg_dir(tmp_path) -> Path:
    a, b = box_mesh(centre=(0, 2, 0)), box_mesh(centre=(0, -2, 0))
    world = trimesh.util.concatenate([trimesh.Trimesh(*a, process=False),
                                      trimesh.Trimesh(*b, process=False)])
    (tmp_path / "meshes").mkdir()
    world.export(tmp_path / "meshes" / "world.obj")
    write_mesh(tmp_path / "meshes" / "robot.stl", *box_mesh((0.4, 0.2, 0.2), centre=(1, 0, 0)))
    return tmp_path


def test_ompl_cfg_loads(cfg_dir):
    path = write(cfg_dir / "tiny.cfg", CFG)
    scene = load_quietly(path)
    assert scene.name == "tiny"
    (world,) = scene.obstacles  # both boxes stay one body
    assert len(world.faces) == 24 and len(np.unique(world.vertices, axis=0)) == 16
    assert scene.bounds.tolist() == [[-4.0] * 3, [4.0] * 3]
    assert scene.start.tolist() == [-3.0, 0.5, 1.0] and scene.goal.tolist() == [3.0, 0.5, 1.0]
    # Start rotation: 90 degrees about z (the axis is normalised). The reference point is the
    # robot's vertex centre (1, 0, 0), turned with it.
    assert np.allclose(scene.reference_point, [0.0, 1.0, 0.0], atol=1e-15)
    rel = scene.robot.vertices - scene.reference_point
    assert np.allclose(np.ptp(rel, axis=0), [0.2, 0.4, 0.2])


def test_ompl_cfg_goal_rotation_and_inferred_volume_warn(cfg_dir):
    text = textwrap.dedent(CFG).replace("goal.theta = 1.5707963267948966", "goal.theta = 0.5")
    text = "\n".join(line for line in text.splitlines() if not line.startswith("volume."))
    path = write(cfg_dir / "tiny.cfg", text)
    with pytest.warns(UserWarning) as record:
        scene = load_scene(path)
    messages = " | ".join(str(w.message) for w in record)
    assert "goal rotation differs from the start rotation" in messages
    assert "bounds inferred" in messages
    # The world's bounding box, grown to hold the start and goal.
    assert scene.bounds.tolist() == [[-3.0, -2.5, -0.5], [3.0, 2.5, 1.0]]


def test_ompl_cfg_2d(cfg_dir):
    path = write(cfg_dir / "flat.cfg", """
        [problem]
        robot = meshes/robot.stl
        world = meshes/world.obj
        start.x = 0.0
        start.y = 0.0
        start.theta = 0.0
        goal.x = 1.0
        goal.y = 0.5
        goal.theta = 0.0
        volume.min.x = -5
        volume.min.y = -5
        volume.max.x = 5
        volume.max.y = 5
        """)
    scene = load_quietly(path)
    assert scene.name == "flat"
    assert scene.bounds.tolist() == [[-5.0, -5.0, 0.0], [5.0, 5.0, 0.0]]
    assert scene.goal.tolist() == [1.0, 0.5, 0.0]


@pytest.mark.parametrize(
    "edit, match",
    [
        (("start.y = 0.5\n", ""), r"\[problem\] start\.y: missing"),
        (("world = meshes/world.obj", "world = meshes/nope.obj"), r"world: mesh file not found"),
        (("volume.max.z = 4\n", ""), r"volume\.max\.z: missing \(the volume needs all"),
        (("start.x = -3.0", "start.x = -9.0"), r"start \[-9\.0, 0\.5, 1\.0\] is outside"),
        (("goal.z = 1.0", "goal.z = nan"), r"goal\.z: must be finite"),
        (("start.axis.y = 0\n", ""), r"start\.axis\.y: missing \(a rotation needs"),
        (("[problem]", "[problems]"), r"no \[problem\] section"),
    ],
)
def test_ompl_cfg_errors(cfg_dir, edit, match):
    text = textwrap.dedent(CFG)
    assert edit[0] in text
    with pytest.raises(SceneError, match=match):
        load_scene(write(cfg_dir / "bad.cfg", text.replace(*edit, 1)))


# --------------------------------------------------------------------------------------
# Parasol (PPL): the shared benchmark scenes

# SOURCES.md: triangles T and vertices V after welding by position.
PARASOL = {
    "bug_trap1.0/bug-trap.env": ("trap.obj", 3212, 1606, "stick-bug.obj", 132, 35),
    "alpha1.6/alpha.env": ("alphaobstacle.obj", 972, 488, "alpharobot.obj", 972, 488),
    "flange_1.0/flange.env": ("obstacle.g", 990, 487, "robot.g", 5306, 2650),
}


@pytest.mark.parametrize("rel", sorted(PARASOL))
def test_parasol_scene_loads(shared_data, rel):
    obstacle, t_obs, v_obs, robot, t_rob, v_rob = PARASOL[rel]
    path = shared_data / "parasol_open_ppl_env" / rel
    with warnings.catch_warnings(record=True) as record:
        warnings.simplefilter("always")
        scene = load_scene(path)
        again = load_scene(path.with_suffix(".query"))
    assert scene.name == path.stem and len(scene.obstacles) == 1
    (body,) = scene.obstacles
    assert body.name == obstacle and len(body.faces) == t_obs
    assert len(np.unique(body.vertices, axis=0)) == v_obs
    assert scene.robot.name == robot and len(scene.robot.faces) == t_rob
    assert len(np.unique(scene.robot.vertices, axis=0)) == v_rob
    lo, hi = scene.bounds
    for point in (scene.start, scene.goal):
        assert (lo <= point).all() and (point <= hi).all()
    # The same problem from the .query file.
    assert np.array_equal(again.robot.vertices, scene.robot.vertices)
    assert np.array_equal(again.obstacles[0].vertices, body.vertices)
    assert np.array_equal(again.start, scene.start) and np.array_equal(again.goal, scene.goal)
    goal_warnings = [w for w in record if "goal orientation differs" in str(w.message)]
    assert len(goal_warnings) == (2 if "alpha" in rel else 0)


def test_parasol_bug_trap_pose(shared_data):
    scene = load_scene(shared_data / "parasol_open_ppl_env" / "bug_trap1.0" / "bug-trap.env")
    assert scene.bounds.tolist() == [[-50.0] * 3, [50.0] * 3]
    assert scene.start.tolist() == [0.0, 0.0, 10.0] and scene.goal.tolist() == [-5.0, 3.0, -25.0]
    # The trap's vertex mean is moved to the origin, turned, then placed at (0, 2, 0).
    assert np.allclose(np.unique(scene.obstacles[0].vertices, axis=0).mean(axis=0),
                       [0.0, 2.0, 0.0], atol=1e-9)
    # The stick bug is double-sided: its hull is used, with a warning.
    with pytest.warns(UserWarning, match="DuplicateFaceError"):
        robot = scene.robot_polytope()
    assert robot.n_facets > 4


# --------------------------------------------------------------------------------------
# Parasol: conventions pinned on small files


def parasol_dir(tmp_path, env_pose="1 2 3 0 0 90", query=None, boundary=True, robot=True,
                obstacle="cube.obj -c(1 1 0 1)"):
    # A unit cube with a corner at the origin (vertex mean (0.5, 0.5, 0.5)), a 2 x 1 x 0.5 slab
    # centred at (1, 0.5, 0.25), and a bar robot whose vertex mean is (1, 0, 0).
    write_mesh(tmp_path / "cube.obj", *box_mesh(centre=(0.5, 0.5, 0.5)))
    write_mesh(tmp_path / "slab.obj", *box_mesh((2.0, 1.0, 0.5), centre=(1.0, 0.5, 0.25)))
    write_mesh(tmp_path / "bar.obj", *box_mesh((2.0, 0.2, 0.2), centre=(1.0, 0.0, 0.0)))
    env = ("Boundary Box [-10:10 ; -10:10 ; -10:10]\n\n" if boundary else "") + textwrap.dedent(f"""
        Multibodies
        1

        Passive
        {obstacle} {env_pose}
        """).lstrip()
    (tmp_path / "p.env").write_text(env)
    if robot:
        (tmp_path / "bar.robot").write_text(
            "1\n#VIZMO_COLOR 0.4 0.8 0.9\nbar.obj -c(0 1 0 1) Volumetric Rotational\n"
            "Connections\n0\n")
    (tmp_path / "p.query").write_text(query or "0 0 0 5 0 0 0.5\n0 0 0 -5 0 0 0.5\n")
    return tmp_path / "p.env"


def test_parasol_conventions(tmp_path):
    scene = load_quietly(parasol_dir(tmp_path))
    (cube,) = scene.obstacles
    # Centred at its vertex mean, turned 90 degrees about z, moved to (1, 2, 3).
    assert corners(cube) == set(itertools.product((0.5, 1.5), (1.5, 2.5), (2.5, 3.5)))
    # Query rotations are in units of pi: rz = 0.5 is +90 degrees about z (x -> y). The bar's
    # vertex mean (1, 0, 0) is its reference point, turned with it.
    assert scene.reference_point.tolist() == [0.0, 1.0, 0.0]
    assert corners(scene.robot) == set(itertools.product((-0.1, 0.1), (0.0, 2.0), (-0.1, 0.1)))
    assert scene.start.tolist() == [0.0, 0.0, 5.0]
    assert scene.bounds.tolist() == [[-10.0] * 3, [10.0] * 3]


def test_parasol_com_adjustment_none_and_rotation_sense(tmp_path):
    # -a(NONE): the cube [0, 1]^3 is not centred; +90 degrees about z sends x to y.
    path = parasol_dir(tmp_path, obstacle="cube.obj -a(NONE)", env_pose="0 0 0 0 0 90")
    expected = itertools.product((-1.0, 0.0), (0.0, 1.0), (0.0, 1.0))
    assert corners(load_quietly(path).obstacles[0]) == set(expected)


def test_parasol_euler_order_is_extrinsic_xyz(tmp_path):
    # (90, 0, 90): roll first (the slab's y and z extents swap: 2 x 0.5 x 1), then yaw (x and y
    # swap: 0.5 x 2 x 1). The intrinsic order would give 1 x 0.5 x 2.
    scene = load_quietly(parasol_dir(tmp_path, obstacle="slab.obj", env_pose="0 0 0 90 0 90"))
    assert corners(scene.obstacles[0]) == set(itertools.product((-0.25, 0.25), (-1.0, 1.0),
                                                                (-0.5, 0.5)))


def test_parasol_inferred_bounds_and_waypoints_warn(tmp_path):
    query = "0 0 0 5 0 0 0\n0 1 1 1 0 0 0\n0 0 0 -5 0 0 0.25\n"
    path = parasol_dir(tmp_path, query=query, boundary=False)
    with pytest.warns(UserWarning) as record:
        scene = load_scene(path)
    messages = " | ".join(str(w.message) for w in record)
    assert "no boundary box" in messages and "1 intermediate configurations" in messages
    assert "goal orientation differs" in messages
    lo, hi = scene.bounds
    assert (lo <= scene.goal).all() and (scene.goal <= hi).all()
    assert (lo < np.array([0.5, 1.5, 2.5])).all()


@pytest.mark.parametrize(
    "kwargs, match",
    [
        ({"query": "0 0 0 5 0 0\n0 0 0 -5 0 0 0\n"}, r"p\.query:1: expected a robot index and 6"),
        ({"query": "0 0 0 5 0 0 0\n"}, r"expected a start and a goal"),
        ({"query": "0 0 0 50 0 0 0\n0 0 0 -5 0 0 0\n"}, r"p\.query:1: the start .* is outside"),
        ({"env_pose": "1 2 3 0 0"}, r"p\.env:7: expected the pose 'x y z rx ry rz'"),
        ({"env_pose": "1 2 3 0 zero 90"}, r"p\.env:7: expected numbers \(pose\), got 'zero'"),
        ({"robot": False}, r"no \.robot file beside it"),
    ],
)
def test_parasol_errors_name_file_and_line(tmp_path, kwargs, match):
    with pytest.raises(SceneError, match=match):
        load_scene(parasol_dir(tmp_path, **kwargs))


def test_parasol_missing_geometry(tmp_path):
    path = parasol_dir(tmp_path)
    path.write_text(path.read_text().replace("cube.obj", "gone.obj"))
    with pytest.raises(SceneError, match=r"p\.env:7: mesh file not found: '.*gone\.obj'"):
        load_scene(path)


def test_byu_reader(tmp_path):
    # Two parts: a square (fan-triangulated) and a triangle; 1-based, negative closes.
    good = "2 5 2 7\n1 1\n2 2\n0 0 0 1 0 0 1 1 0\n0 1 0\n5 5 5\n1 2 3 -4\n2 5 -3\n"
    (tmp_path / "m.g").write_text(good)
    vertices, faces = meshfile._read_byu(tmp_path / "m.g")
    assert vertices.shape == (5, 3) and vertices[4].tolist() == [5.0, 5.0, 5.0]
    assert faces.tolist() == [[0, 1, 2], [0, 2, 3], [1, 4, 2]]
    for bad, match in [
        (good.replace("-4", "4"), r"m\.g:7: the header announces 2 polygons"),
        (good.replace("2 5 -3", "2 9 -3"), r"m\.g:8: vertex index 9 is out of range 1\.\.5"),
        (good.replace("5 5 5", "5 x 5"), r"m\.g:6: expected a vertex coordinate, got 'x'"),
        (good + "9\n", r"m\.g:9: unexpected data"),
        (good.replace("2 5 -3\n", ""), r"m\.g:7: file ends early"),
    ]:
        (tmp_path / "m.g").write_text(bad)
        with pytest.raises(SceneError, match=match):
            meshfile._read_byu(tmp_path / "m.g")


@pytest.mark.parametrize("offset", [(0.0, 0.0, 0.0), (250.0, 150.0, -300.0)], ids=["origin", "far"])
def test_a_scene_built_in_code_is_written_and_read_back_exactly(tmp_path, offset):
    """``Scene.from_meshes`` from trimesh objects and arrays (default bounds: the obstacles,
    start and goal grown by the robot's reach), written by ``save_scene`` as TOML with OBJ
    meshes, read back by ``load_scene`` with the same vertices, faces, bounds, start, goal and
    reference point, bit for bit; the file gets the umask's mode, not a temporary file's."""
    import os

    import cspace
    from cspace.geometry.transform import euler_xyz

    off = np.asarray(offset)
    wall = trimesh.creation.box((0.2, 4.0, 3.0))
    wall.apply_translation(off + [0.1, 0.0, 0.0])
    post = trimesh.creation.cylinder(0.1, 2.0)
    post.apply_translation(off + [1.3, 0.7, 0.0])
    robot = trimesh.creation.icosphere(1, radius=0.3)
    turn = euler_xyz([10.0, 20.0, 30.0])
    s = cspace.Scene.from_meshes(robot, {"wall": wall, "post": (post.vertices, post.faces)},
                                 start=off - [1.0, 0.0, 0.0], goal=off + [1.0, 0.0, 0.0],
                                 reference_point=[0.0, 0.1, 0.0], start_rotation=turn,
                                 goal_rotation=euler_xyz([0.0, 90.0, 0.0]), name="in code")
    reach = np.linalg.norm(s.robot.vertices - s.reference_point, axis=1).max()
    assert np.allclose(s.bounds[0], np.minimum(wall.bounds[0], s.start) - reach)
    assert np.allclose(s.reference_point, turn @ [0.0, 0.1, 0.0])
    assert [b.name for b in s.obstacles] == ["wall", "post"]
    old = os.umask(0o027)
    try:
        path = cspace.save_scene(s, tmp_path / "mine.toml")
    finally:
        os.umask(old)
    assert path.stat().st_mode & 0o777 == 0o640
    back = load_scene(path)
    assert back.name == "in code"
    for key in ("bounds", "start", "goal", "reference_point"):
        assert np.array_equal(getattr(back, key), getattr(s, key)), key
    assert np.array_equal(back.robot.vertices, s.robot.vertices)
    for a, b in zip(back.obstacles, s.obstacles):
        assert a.name == b.name
        assert np.array_equal(a.vertices, b.vertices) and np.array_equal(a.faces, b.faces)
    # the goal's turn relative to the start's, within rounding of the written angles
    rel = back.goal_rotation @ back.start_rotation.T
    assert np.abs(rel - s.goal_rotation @ s.start_rotation.T).max() < 1e-12


def test_scene_from_meshes_names_what_is_wrong(tmp_path):
    import cspace
    from cspace.errors import OutputError

    box = trimesh.creation.box((1.0, 1.0, 1.0))
    with pytest.raises(SceneError, match="obstacle-1: expected a mesh"):
        cspace.Scene.from_meshes(box, [box, 3.0], start=[2, 0, 0], goal=[3, 0, 0])
    with pytest.raises(SceneError, match="start .* is outside the bounds"):
        cspace.Scene.from_meshes(box, [box], start=[9, 0, 0], goal=[3, 0, 0],
                                 bounds=[[-4, -4, -4], [4, 4, 4]])
    s = cspace.Scene.from_meshes(box, [box], start=[2, 0, 0], goal=[-2, 0, 0])
    with pytest.raises(OutputError, match="expected .toml"):
        cspace.save_scene(s, tmp_path / "mine.json")
    with pytest.raises(OutputError, match="cannot"):
        cspace.save_scene(s, "/proc/x/mine.toml")
    assert not list(tmp_path.iterdir())  # nothing half-written


@pytest.mark.parametrize("offset", [(0.0, 0.0, 0.0), (250.0, 150.0, -300.0)], ids=["origin", "far"])
def test_contact_names_the_body_and_a_witness_pair(offset):
    """``CSpace.contact``: the first contact of a straight motion (exact: the parameter
    ``first_contact`` gives), the body hit first, and a witness pair on the raw meshes (the
    robot's point and the obstacle's, within the error bound of each other); standing in
    collision, t = 0 and the pair is a point where the two cross. Checked against geometry
    the test knows: two boxes along x, the robot moving in +x meets the nearer one's face."""
    import cspace

    off = np.asarray(offset)
    near = trimesh.creation.box((0.5, 2.0, 2.0))
    near.apply_translation(off + [1.0, 0.0, 0.0])  # face at x = 0.75
    far = trimesh.creation.box((0.5, 2.0, 2.0))
    far.apply_translation(off + [3.0, 0.0, 0.0])
    robot = trimesh.creation.box((0.2, 0.2, 0.2))
    s = cspace.Scene.from_meshes(robot, {"near": near, "far": far}, start=off + [-1, 0, 0],
                                 goal=off + [-1, 0.5, 0])
    cs = cspace.CSpace.from_scene(s)
    a, b = off + [-1.0, 0.1, 0.2], off + [4.0, 0.1, 0.2]
    c = cs.contact(a, b)
    assert c.t == cs.first_contact(a, b)
    assert c.body == "near"
    bound = cs.obstacles[0].error_bound
    # the robot's +x face (x = q + 0.1) reaches the near box's face at x = 0.75
    assert abs(c.position[0] - (off[0] + 0.65)) <= 2 * bound
    assert c.gap <= 2 * bound
    assert abs(c.obstacle_point[0] - (off[0] + 0.75)) <= 2 * bound
    assert abs(c.robot_point[0] - (c.position[0] + 0.1)) <= 1e-9 * (1 + abs(off).max())
    assert np.abs(c.obstacle_point[1:] - c.robot_point[1:]).max() <= 2 * bound
    # standing inside the far box's reach: t = 0, a crossing point as both witnesses
    inside = cs.contact(off + [2.8, 0.0, 0.0])
    assert inside.t == 0.0 and inside.body == "far" and inside.gap == 0.0
    assert np.array_equal(inside.robot_point, inside.obstacle_point)
    free = cs.contact(off + [-1.0, 0.0, 0.0], off + [-1.0, 0.5, 0.0])
    assert np.isnan(free.t) and free.body is None
