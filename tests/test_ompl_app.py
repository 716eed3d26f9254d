"""OMPL.app-style problems end to end: Collada files (Z_UP, unit scale, node matrices) written
here with pycollada, a .cfg as OMPL.app's GUI reads it, the robot's centre as Assimp gives it,
and the real (non-convex) robot planned and re-checked with FCL.

OMPL.app's own resources are licensed for non-commercial use without redistribution, so
these are equivalents built from the formats' rules.
"""

from __future__ import annotations

import json
import subprocess
import sys

import numpy as np
import pytest
from test_meshfile import _doc, _geometry, _instance, _write  # tests/ is on sys.path
from test_robot_parts import _box, _u_robot

from cspace import load_scene, model_scene
from cspace.check.oracle import SceneOracle
from cspace.mesh.files import read_mesh_file

collada = pytest.importorskip("collada")
from collada import scene as cs  # noqa: E402


def _dae(path, mesh, up="Z_UP", unit=None, matrix=None):
    doc, mat = _doc(up, unit)
    geom = _geometry(doc, "g", *mesh)
    transforms = [] if matrix is None else [cs.MatrixTransform(
        np.asarray(matrix, np.float32).ravel())]
    return _write(doc, [cs.Node("n", children=[_instance(geom, mat)], transforms=transforms)],
                  path)


def _cfg(path, world, robot, start, goal, bounds):
    keys = "xyz"[:len(start)]
    lines = ["[problem]", f"name = {path.stem}", f"world = {world}", f"robot = {robot}"]
    lines += [f"start.{a} = {v!r}" for a, v in zip(keys, start)]
    lines += [f"goal.{a} = {v!r}" for a, v in zip(keys, goal)]
    if len(start) == 3:
        lines += ["start.axis.x = 0", "start.axis.y = 0", "start.axis.z = 1", "start.theta = 0"]
    lines += [f"volume.{end}.{a} = {v!r}" for end, row in zip(("min", "max"), bounds)
              for a, v in zip(keys, row)]
    path.write_text("\n".join(lines) + "\n")
    return path


def _u_around_post(tmp_path):
    """A Z_UP world (a post, scaled by a node matrix, unit 0.5) and a Z_UP U robot whose slot
    holds the post at the start; the goal slides it along the post and off its end."""
    post = _box((0.6, 0.6, 4.0))  # file units: 0.3 x 0.3 x 2 after the unit scale 0.5
    _dae(tmp_path / "post_env.dae", post, unit=0.5)
    robot = _u_robot(0.5)
    # The robot file puts the U at an offset through a node matrix.
    shift = np.eye(4)
    shift[:3, 3] = [2.0, 1.0, -0.5]
    _dae(tmp_path / "u_robot.dae", robot, matrix=shift)
    centre = read_mesh_file(tmp_path / "u_robot.dae").assimp_centre
    up = np.array([[1.0, 0, 0], [0, 0, 1], [0, -1, 0]])
    slot = up @ (np.array([0.0, 0.0, 0.0]) + [2.0, 1.0, -0.5])  # the slot centre, world frame
    start = np.zeros(3) - slot + centre      # robot at q occupies R - centre + q
    goal = start + [0.0, 1.6, 0.0]           # along the post (its axis is world y): off its end
    bounds = (start - 1.0, goal + 1.0)
    return _cfg(tmp_path / "u.cfg", "post_env.dae", "u_robot.dae", start.tolist(),
                goal.tolist(), [b.tolist() for b in bounds])


def test_start_and_goal_agree_with_fcl_at_omplapps_pose(tmp_path):
    scene = load_scene(_u_around_post(tmp_path))
    # The post, read as Assimp places it: unit 0.5, Z_UP -> its long axis is world y.
    size = np.ptp(scene.obstacles[0].vertices, axis=0)
    assert np.allclose(size, [0.3, 2.0, 0.3])
    m = model_scene(scene)
    assert [p.kind for p in m.robot_parts] == ["solid"]
    space = m.cspace()
    # FCL with the actual robot mesh, centred on OMPL.app's centre, as BVHs: the raw scene
    # (SceneOracle, its own solid rule; the test's U robot is closed: a solid).
    oracle = SceneOracle(scene)
    assert oracle.robot.solid
    q = np.stack([scene.start, scene.goal])
    assert not oracle.collides(q).any()
    assert not space.contains(q).any()
    # The hull would put the start in collision: the real robot is what makes it free.
    assert model_scene(scene, robot_hull=True).cspace().contains(scene.start)


def test_cli_plans_with_the_real_robot_and_fcl_rechecks(tmp_path):
    cfg = _u_around_post(tmp_path)
    out = subprocess.run(
        [sys.executable, "-m", "cspace", "plan", str(cfg), "--seed", "1", "--time", "5",
         "--no-cache", "--fcl-check", "--explain", "-q", "--result", str(tmp_path / "r.json")],
        capture_output=True, text=True, timeout=300)
    assert out.returncode == 0, out.stdout + out.stderr
    r = json.loads((tmp_path / "r.json").read_text())
    assert r["solved"] and r["fcl_recheck"]["colliding_samples"] == 0
    assert r["fcl_recheck"]["samples"] > 100
    assert "triangle pairs" in out.stdout  # the convex post against the non-convex robot


def test_2d_cfg_plans(tmp_path):
    # OMPL.app's 2D problems: no start.z, the robot turns by theta about z, bounds z [0, 0].
    wall = _box((0.4, 3.0, 1.0), centre=(0.0, -0.8, 0.0))
    _dae(tmp_path / "wall.dae", wall, up="Y_UP")
    _dae(tmp_path / "car.dae", _box((0.5, 0.3, 0.2)), up="Y_UP")
    cfg = _cfg(tmp_path / "planar.cfg", "wall.dae", "car.dae", [-1.5, 0.0], [1.5, 0.0],
               [[-2.0, -2.0], [2.0, 2.0]])
    scene = load_scene(cfg)
    assert scene.bounds[:, 2].tolist() == [0.0, 0.0] and scene.reference_point[2] == 0.0
    out = subprocess.run(
        [sys.executable, "-m", "cspace", "plan", str(cfg), "--seed", "1", "--time", "5",
         "--no-cache", "--fcl-check", "-q", "--result", str(tmp_path / "r.json")],
        capture_output=True, text=True, timeout=300)
    assert out.returncode == 0, out.stdout + out.stderr
    r = json.loads((tmp_path / "r.json").read_text())
    assert r["solved"] and np.array(r["path"])[:, 2].tolist() == [0.0] * len(r["path"])


@pytest.mark.parametrize("rel", [
    "bug_trap1.0/bug-trap.env",
    pytest.param("alpha1.6/alpha.env", marks=pytest.mark.slow),
    pytest.param("flange_1.0/flange.env", marks=pytest.mark.slow),
])
def test_real_robots_start_and_goal_agree_with_fcl(shared_data, rel):
    # Parasol's problems with their real, non-convex robots (the stick bug, the alpha robot,
    # the three-part flange), modelled exactly: start and goal validity as FCL sees them with
    # the actual robot mesh (BVH, plus containment), and near the start.
    import warnings

    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        scene = load_scene(shared_data / "parasol_open_ppl_env" / rel)
    m = model_scene(scene)
    assert all(p.kind != "convex" for p in m.robot_parts)
    space = m.cspace()
    rng = np.random.default_rng(4)
    q = np.vstack([scene.start, scene.goal, scene.start + rng.normal(scale=2.0, size=(40, 3))])
    q = q[((scene.bounds[0] <= q) & (q <= scene.bounds[1])).all(axis=1)]
    # FCL on the raw scene, every body, with the oracle's own solid/surface rule (was: the
    # robot's kind as the model classified it).
    hit = SceneOracle(scene).collides(q)
    assert not hit[:2].any()  # a valid problem: start and goal free
    assert np.array_equal(space.contains(q), hit), (hit.sum(), space.contains(q).sum())
