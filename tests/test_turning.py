"""A robot that turns: orientation slices, certified turns in place, planning over both.

The guarantee is checked from outside: FCL with the actual robot mesh, at dense poses along
every translation and every turn arc of the returned paths, finds no collision; OMPL's own
discrete validation (SE(2)/SE(3) as OMPL.app plans) is shown to return paths that clip.
"""

from __future__ import annotations

import dataclasses
import json
import math
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
from scipy.spatial import ConvexHull
from scipy.spatial.transform import Rotation

from cspace import InvalidArgumentError, load_scene
from cspace.check.cross_check import pose_path_collisions
from cspace.planning.plan import default_slices, plan
from cspace.planning.sampled import plan_sampled
from cspace.scene.scene import Body
from cspace.geometry.transform import axis_angle
from cspace.planning.orientations import Slices, swept_points
from cspace.planning.turning import TurningCSpace
from zoo import rod_and_holed_wall, thin_walled

SCENES = Path(__file__).resolve().parents[1] / "scenes"


@pytest.fixture(scope="module")
def piano():
    return load_scene(SCENES / "piano.toml")


def _relative(scene, quaternions) -> np.ndarray:
    """Rotations relative to the scene's start orientation, from world quaternions."""
    return Rotation.from_quat(quaternions).as_matrix() @ np.asarray(scene.start_rotation).T


# ----------------------------------------------------------------------------- slices


def test_slices_hold_the_goal_and_turn_the_short_way():
    s = Slices.about(8, goal_angle=math.radians(100))
    assert len(s) == 9 and math.isclose(s.angles[s.goal], math.radians(100))
    assert s.way(0, 2) == [0, 1, 2] and s.way(1, 8) == [1, 0, 8]
    assert s.way(3, 3) == [3]
    assert math.isclose(s.step(2, 3), math.radians(10)) and math.isclose(s.step(8, 0), math.radians(45))
    assert Slices.about(8, goal_angle=2 * math.pi / 8 * 3).goal == 3  # on a step: no extra slice
    with pytest.raises(InvalidArgumentError, match="not neighbours"):
        s.step(0, 2)
    with pytest.raises(InvalidArgumentError, match="at most pi apart"):
        Slices((0, 0, 1), [0.0, 0.5])
    with pytest.raises(InvalidArgumentError, match="at least 2"):
        Slices.about(1)


def test_default_slices_follow_the_goal_rotation(piano):
    turned = dataclasses.replace(piano, goal_rotation=axis_angle((1.0, 1.0, 0.0), 2.0))
    s = default_slices(turned, 12)
    assert np.allclose(s.axis, np.array([1.0, 1.0, 0.0]) / math.sqrt(2))
    assert np.allclose(s.rotation(s.goal), turned.goal_rotation, atol=1e-12)
    assert default_slices(piano, 12).goal == 0 and np.allclose(default_slices(piano, 12).axis, (0, 0, 1))


@pytest.mark.parametrize("n", [2, 5, 36])
def test_swept_hull_holds_every_arc(n):
    """Every vertex of a robot (and points inside it) at 2001 instants of each turn lies in
    the hull of swept_points: the arcs stay within their sagitta of the chords."""
    rng = np.random.default_rng(n)
    V = rng.normal(size=(30, 3)) * [1.0, 0.4, 0.2] + [3.0, 1.0, 0.5]
    c = np.array([2.5, 0.5, 0.0])
    s = Slices.about(n, axis=rng.normal(size=3))
    inner = V[ConvexHull(V).vertices].mean(axis=0) * 0.3 + V[:10] * 0.7  # convex combinations
    for i in range(len(s)):
        j = (i + 1) % len(s)
        hull = ConvexHull(swept_points(V, c, s, i, j))
        t = np.linspace(0.0, 1.0, 2001)
        for P in (V, inner):
            pts = np.concatenate([
                (axis_angle(s.axis, s.angles[i] + x * s.step(i, j)) @ (P - c).T).T + c for x in t])
            assert (pts @ hull.equations[:, :3].T + hull.equations[:, 3] <= 0).all()


def test_swept_hull_is_tight():
    """The growth is the sagitta (plus rounding slack): a quarter turn of a unit segment grows
    its hull by r (1 - cos 45 deg) per side, not more."""
    V = np.array([[1.0, 0.0, 0.0], [-1.0, 0.0, 0.0]])
    s = Slices.about(4)
    P = swept_points(V, np.zeros(3), s, 0, 1)
    assert np.isclose(P[:, 2].max(), 1 - math.cos(math.pi / 4), rtol=1e-9)


# ----------------------------------------------------------------------------- the C-space


def test_turning_cspace_is_built_lazily_and_decides(piano):
    t = TurningCSpace(piano, default_slices(piano, 8))
    door_lo, door_hi = np.array([0.0, -1.5, 0.5]), np.array([0.0, 1.5, 0.5])
    assert not t.translation_free(door_lo, door_hi, 0)  # long side along x: stuck
    assert len(t.built_slices) == 1 and not t.built_turns
    assert t.translation_free(door_lo, door_hi, 2)  # turned by 90 degrees: through
    assert t.turn_free(door_lo, 0, 2) and not t.built_turns  # far from the wall: no build
    assert t.far_answers == 1
    assert not t.turn_free(np.array([0.0, -0.6, 0.5]), 0, 2)  # too close to the wall
    assert len(t.built_turns) == 1  # the first step already collides
    # the certified answers agree with FCL along the arcs
    for q, free in ((door_lo, True), (np.array([0.0, -0.6, 0.5]), False)):
        bad, n = pose_path_collisions(piano, [q, q], [t.slices.rotation(0), t.slices.rotation(2)],
                                      per_degree=100)
        assert (bad == 0) == free and n > 9000


def test_a_turn_is_refused_where_only_the_ends_are_free(piano):
    """Two orientations free at q, the arc between them not: a turn in place must not pass
    (what sampling the two ends would miss)."""
    post = Body("post", np.array([[x, y, z] for x in (0.6, 0.7) for y in (0.55, 0.65)
                                  for z in (0.0, 1.0)]),
                np.array([[0, 1, 3], [0, 3, 2], [4, 6, 7], [4, 7, 5], [0, 4, 5], [0, 5, 1],
                          [2, 3, 7], [2, 7, 6], [0, 2, 6], [0, 6, 4], [1, 5, 7], [1, 7, 3]]),
                "box")
    scene = dataclasses.replace(piano, obstacles=(post,), bounds=np.array([[-2, -2, 0.5], [2, 2, 0.5]]))
    t = TurningCSpace(scene, Slices.about(4))
    q = np.array([0.0, 0.0, 0.5])
    assert t.state_free(q, 0) and t.state_free(q, 1)
    assert not t.turn_free(q, 0, 1)
    assert pose_path_collisions(scene, [q, q], [t.slices.rotation(0), t.slices.rotation(1)],
                                per_degree=100)[0] > 0


# ----------------------------------------------------------------------------- planning


def test_the_piano_needs_turns(piano):
    """Translations alone at the start's orientation have no path: proved by the decision
    (a certificate, not a planner's timeout), with a budget far above what it takes so that
    load cannot change the answer."""
    from cspace.planning.decide import decide
    from cspace.scene.model import model_scene

    d = decide(model_scene(piano).cspace(), piano.start, piano.goal, bounds=piano.bounds,
               time=120.0)
    assert d.answer == "no path", d.reason


@pytest.mark.parametrize("seed", [1, pytest.param(2, marks=pytest.mark.slow),
                                  pytest.param(3, marks=pytest.mark.slow)])
def test_planned_turns_pass_fcl_along_every_motion(piano, seed):
    r = plan(piano, slices=8, time=10.0, seed=seed)
    assert r.solved and r.valid
    assert set(np.diff(r.slices).tolist()) - {0} and (np.diff(r.slices) != 0).sum() >= 2
    assert np.array_equal(r.path[0], piano.start) and np.array_equal(r.path[-1], piano.goal)
    assert r.built["slices"] <= 8 and r.built["turns"] <= 8
    assert r.built["start_orientation_only"] is False  # tried first, found nothing
    # each step is a translation within a slice or a turn in place between neighbours
    for (q0, k0), (q1, k1) in zip(zip(r.path, r.slices), zip(r.path[1:], r.slices[1:])):
        assert k0 == k1 or (np.array_equal(q0, q1) and (int(k1) - int(k0)) % 8 in (1, 7))
    bad, n = pose_path_collisions(piano, r.path, _relative(piano, r.orientations),
                                  per_metre=1e3, per_degree=1e3)
    assert bad == 0 and n > 10**5


@pytest.mark.parametrize("move", [(0, 0, 0), (250, 150, -300)])
def test_translations_at_the_shared_orientation_come_first(piano, move):
    """Start and goal on one side of the wall, one orientation: the path is translations at
    it alone, with no other orientation and no turn built (a planner over every orientation
    would spend its samples turning)."""
    m = np.array(move, dtype=np.float64)
    scene = dataclasses.replace(
        piano, obstacles=tuple(dataclasses.replace(o, vertices=o.vertices + m)
                               for o in piano.obstacles),
        robot=dataclasses.replace(piano.robot, vertices=piano.robot.vertices + m),
        reference_point=piano.reference_point + m, bounds=piano.bounds + m,
        start=piano.start + m, goal=np.array([1.2, -1.6, 0.5]) + m)
    r = plan(scene, slices=8, time=4.0, seed=1)
    assert r.solved and r.built["start_orientation_only"] is True
    assert (r.slices == 0).all() and r.built["slices"] == 1 and r.built["turns"] == 0
    assert np.array_equal(r.path[0], scene.start) and np.array_equal(r.path[-1], scene.goal)
    bad, n = pose_path_collisions(scene, r.path, _relative(scene, r.orientations),
                                  per_metre=1e3)
    assert bad == 0 and n > 1000
    # a goal that needs a turn: the shared orientation is tried, then the turning planner
    through = dataclasses.replace(scene, goal=piano.goal + m)
    r = plan(through, slices=8, time=10.0, seed=1)
    assert r.solved and r.built["start_orientation_only"] is False and (r.slices != 0).any()


@pytest.mark.slow
def test_planned_turns_pass_fcl_at_ten_thousand_poses_per_metre_and_degree(piano):
    r = plan(piano, slices=8, time=10.0, seed=4)
    assert r.solved
    bad, n = pose_path_collisions(piano, r.path, _relative(piano, r.orientations),
                                  per_metre=1e4, per_degree=1e4)
    assert bad == 0 and n > 10**6


def test_ompl_discrete_validation_clips_a_thin_wall_where_certified_turns_do_not(piano):
    """A wall 5 mm thick: OMPL's SE(3) planning with FCL state checks and its default
    discrete motion validation (states every 1% of the space's extent) returns paths that
    clip it (the piano's corners sweep through the doorway's edges between checked states);
    planning with certified turns returns one FCL finds free along every motion."""
    thin = thin_walled(piano, 0.005)
    seen = []
    for seed in range(1, 9):  # until one clips: OMPL's runs depend on the process's call order
        r = plan_sampled(thin, space="SE3", time=2.0, seed=seed)
        if r.solved:
            bad, _ = pose_path_collisions(thin, r.path, _relative(thin, r.orientations),
                                          per_metre=1e3, per_degree=100)
            seen.append(bad)
            if bad:
                break
    assert seen and max(seen) > 0, f"colliding poses per returned path: {seen}"
    ours = plan(thin, slices=8, time=10.0, seed=1)
    assert ours.solved
    bad, n = pose_path_collisions(thin, ours.path, _relative(thin, ours.orientations),
                                  per_metre=1e3, per_degree=1e3)
    assert bad == 0 and n > 10**5


def test_cli_writes_an_omplapp_path_that_turns(tmp_path):
    out = subprocess.run(
        [sys.executable, "-m", "cspace", "plan", str(SCENES / "piano.toml"), "--slices", "8",
         "--seed", "1", "--time", "10", "--no-cache", "--fcl-check", "--explain",
         "-o", str(tmp_path / "piano.path"), "--result", str(tmp_path / "r.json")],
        capture_output=True, text=True, timeout=300)
    assert out.returncode == 0, out.stdout + out.stderr
    assert "built lazily" in out.stdout
    rows = np.loadtxt(tmp_path / "piano.path")
    assert rows.shape[1] == 7 and np.allclose(np.linalg.norm(rows[:, 3:], axis=1), 1.0)
    r = json.loads((tmp_path / "r.json").read_text())
    assert r["solved"] and r["fcl_recheck"]["colliding_samples"] == 0
    assert np.allclose(rows[:, :3], r["path"]) and len(set(r["slice_ids"])) > 1
    # consecutive quaternions in one hemisphere: slerp takes the short arc
    assert ((rows[1:, 3:] * rows[:-1, 3:]).sum(axis=1) > 0).all()


def test_cfg_goal_orientation_is_reached(tmp_path):
    """An OMPL.app 2D problem whose goal turns the car by 90 degrees: planned end to end, the
    path ends at the goal's orientation, FCL finds it free."""
    pytest.importorskip("collada")
    from test_ompl_app import _dae
    from test_robot_parts import _box

    _dae(tmp_path / "wall.dae", _box((0.4, 3.0, 1.0), centre=(0.0, -0.8, 0.0)), up="Y_UP")
    _dae(tmp_path / "car.dae", _box((0.5, 0.3, 0.2)), up="Y_UP")
    (tmp_path / "turn.cfg").write_text("\n".join([
        "[problem]", "name = turn", "world = wall.dae", "robot = car.dae",
        "start.x = -1.5", "start.y = 0.0", "start.theta = 0.0",
        "goal.x = 1.5", "goal.y = 0.0", f"goal.theta = {math.pi / 2!r}",
        "volume.min.x = -2.0", "volume.min.y = -2.0", "volume.max.x = 2.0", "volume.max.y = 2.0",
    ]) + "\n")
    with pytest.warns(UserWarning, match="goal rotation differs"):
        scene = load_scene(tmp_path / "turn.cfg")
    r = plan(scene, slices=8, time=10.0, seed=1)
    assert r.solved
    assert np.allclose(Rotation.from_quat(r.orientations[-1]).as_matrix(), scene.goal_rotation,
                       atol=1e-12)
    bad, _ = pose_path_collisions(scene, r.path, _relative(scene, r.orientations),
                                  per_metre=1e3, per_degree=1e3)
    assert bad == 0


# ----------------------------------------------------------------------------- free flying


def test_orientations_are_linked_near_uniformly():
    from cspace.planning.orientations import Orientations

    goal = axis_angle((0.3, -1.0, 0.2), 2.5)
    O = Orientations.uniform(100, goal_rotation=goal)
    assert np.array_equal(O.rotation(0), np.eye(3)) and np.allclose(O.rotation(O.goal), goal)
    assert len(O) == 1 + 24 + 100  # the identity is a cube rotation; nothing else repeats
    assert all(i in O.links[j] for i, row in enumerate(O.links) for j in row)
    steps = [O.step(i, j) for i, row in enumerate(O.links) for j in row]
    assert max(steps) < math.radians(80)  # near-uniform: no long jump
    way = O.way(0, O.goal)
    assert way[0] == 0 and way[-1] == O.goal and all(O.neighbours(a, b) for a, b in zip(way, way[1:]))
    assert O.nearest(Rotation.from_matrix(O.rotation(17)).as_quat()) == 17
    # the swept hull holds a turn about a tilted axis too
    V = np.random.default_rng(0).normal(size=(20, 3))
    a, b = way[0], way[1]
    hull = ConvexHull(swept_points(V, np.zeros(3), O, a, b))
    rel = Rotation.from_matrix(O.rotation(b) @ O.rotation(a).T).as_rotvec()
    for t in np.linspace(0, 1, 501):
        P = (Rotation.from_rotvec(t * rel).as_matrix() @ O.rotation(a) @ V.T).T
        assert (P @ hull.equations[:, :3].T + hull.equations[:, 3] <= 0).all()
    with pytest.raises(InvalidArgumentError, match="not neighbours"):
        O.step(0, next(j for j in range(len(O)) if j not in O.links[0] and j != 0))


@pytest.mark.slow  # 8 s: make test-slow (the default run stays under 10 minutes)
def test_a_free_flying_rod_tilts_through_a_hole():
    from cspace.planning.orientations import Orientations

    scene = rod_and_holed_wall()
    assert not plan(scene, slices=8, time=1.0, seed=1).solved  # turns about z do not help
    r = plan(scene, slices=Orientations.uniform(0, degree=6), time=20.0, seed=1)
    assert r.solved and r.valid
    tilted = Rotation.from_quat(r.orientations).as_matrix()[:, :, 2]  # the rod's axis
    assert np.abs(tilted[:, 1]).max() > 0.99  # it went through along y
    bad, n = pose_path_collisions(scene, r.path, Rotation.from_quat(r.orientations).as_matrix(),
                                  per_metre=1e3, per_degree=1e3)
    assert bad == 0 and n > 10**5


def test_cli_turns_by_default_when_the_goal_does(tmp_path):
    """A scene whose goal orientation differs from the start's is planned in SE(3) unless
    --no-turns says otherwise (by auto, and by a planner named); --slices still plans over
    slices, prebuilt through a process pool."""
    scene = tmp_path / "turn.toml"
    text = (SCENES / "piano.toml").read_text()
    scene.write_text(text.replace("[planning]\n", "[planning]\ngoal_orientation = [0, 0, 90]\n"))
    base = [sys.executable, "-m", "cspace", "plan", str(scene), "--seed", "1", "--time", "20",
            "--no-cache", "-q"]
    for extra in ([], ["--planner", "RRTConnect"]):
        out = subprocess.run(base + extra + ["-o", str(tmp_path / "p.path")],
                             capture_output=True, text=True, timeout=300)
        assert out.returncode == 0, out.stdout + out.stderr
        assert "in SE(3) solved" in out.stdout
        rows = np.loadtxt(tmp_path / "p.path")
        assert np.allclose(Rotation.from_quat(rows[-1, 3:]).as_euler("xyz", degrees=True),
                           [0, 0, 90])
    sliced = subprocess.run(base + ["--slices", "36", "--workers", "2", "-o",
                                    str(tmp_path / "s.path")],
                            capture_output=True, text=True, timeout=300)
    assert sliced.returncode == 0, sliced.stdout + sliced.stderr
    assert "with 36 orientations solved" in sliced.stdout
    fixed = subprocess.run(base + ["--no-turns", "--time", "5"], capture_output=True, text=True,
                           timeout=300)
    # kept at the start's orientation, the piano has no path: proved (exit 3; the decision's
    # share of 5 s is 1 s, far above what it takes), not turned
    assert fixed.returncode == 3 and "SE(3)" not in fixed.stdout
    assert "no path, proved: none at the start's orientation" in fixed.stdout


@pytest.mark.parametrize("move", [0, 1], ids=["as given", "at (250, 150, -300)"])
@pytest.mark.parametrize("case", ["NCC-CVMS", "convex robot off its origin", "triangle pairs"])
def test_turns_as_triangle_pairs_answer_as_the_sums(case, move):
    """A turn's C-space is built as triangle pairs (sums=False: nothing built per closed
    body): the same set, exactly, as the NCC-CVMS sums of the swept hull on the same grid;
    and the orientation slices share one modelling of the obstacles."""
    from metamorphic import CASES, GRID_MOVES, moved_scene, samples

    from cspace.planning.turning import _outward
    from cspace.scene.model import model_scene

    scene = moved_scene(CASES[case], GRID_MOVES[move])
    t = TurningCSpace(scene, Slices.about(6))
    t.slice(0)
    welds = sorted(k for k in t._memo if k[0] == "weld")
    t.slice(1)
    assert sorted(k for k in t._memo if k[0] == "weld") == welds and welds  # modelled once
    turn = t.turn(0, 1)
    assert not turn.obstacles  # built lazily, where queries come
    (part,) = t._robot_parts()
    P = swept_points(part, scene.reference_point, t.slices, 0, 1)
    swept = t._scene_with("swept", P, _outward(P, ConvexHull(P)))
    sums = model_scene(swept, grid=t.grid, robot_hull=True).cspace()
    Q = samples(swept, 900, 3)
    inside = turn.contains(Q)
    assert np.array_equal(inside, sums.contains(Q))
    assert 0 < inside.sum() < len(Q)
    assert [bool(turn.contains(q)) for q in Q[:200]] == inside[:200].tolist()
    if case == "NCC-CVMS":  # the closed L: one sum against pairs and containment terms
        assert [co.kind for co in sums.obstacles] == ["mesh"]
        assert sorted(co.kind for co in turn.obstacles) == ["mesh", "pairs"]
