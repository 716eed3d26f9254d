"""The decision by certified cells (:mod:`cspace.planning.decide`): "no path" only where none
exists, on scenes moved far from the origin, scaled and permuted; every wall cell checked
by FCL on the raw meshes (it shares nothing with the cells); every "path" re-proved exactly
and by FCL; and the answer through ``plan`` and ``cspace plan`` (exit 3)."""

from __future__ import annotations

import json
import subprocess
import sys

import numpy as np
import pytest

import cspace
from cspace.check.cross_check import path_collisions
from cspace.check.oracle import SceneOracle
from cspace.errors import InvalidArgumentError
from cspace.planning.decide import BLOCKED, NEAR, decide
from cspace.planning.plan import plan, verify_path

ROBOT = 0.4  # the cube robot's side


def cage_toml(slot: float, *, offset=(0.0, 0.0, 0.0), scale: float = 1.0, axes=(0, 1, 2),
              order=None, surfaces: bool = False, tmp=None, turn=None) -> str:
    """A closed cage of six walls around the origin (inner half-width 1), the +x wall in two
    halves with a slot ``slot`` wide (along y) between them; start inside, goal outside.
    Moved by ``offset``, scaled by ``scale``, its axes permuted by ``axes``, its bodies in
    ``order``; ``surfaces``: each wall an open one-sided square (an OBJ in ``tmp``); ``turn``:
    roll, pitch, yaw in degrees (the scene files' extrinsic XYZ) turning the walls and the
    robot about the cage's centre, the bounds staying axis-aligned (and larger)."""
    from scipy.spatial.transform import Rotation

    R = np.eye(3) if turn is None else Rotation.from_euler("xyz", turn, degrees=True).as_matrix()
    walls = [((-1.05, 0, 0), (0.1, 2.2, 2.2)),
             ((1.05, -(0.55 + slot / 4), 0), (0.1, 1.1 - slot / 2, 2.2)),
             ((1.05, 0.55 + slot / 4, 0), (0.1, 1.1 - slot / 2, 2.2)),
             ((0, -1.05, 0), (2.2, 0.1, 2.2)), ((0, 1.05, 0), (2.2, 0.1, 2.2)),
             ((0, 0, -1.05), (2.2, 2.2, 0.1)), ((0, 0, 1.05), (2.2, 2.2, 0.1))]
    order = range(len(walls)) if order is None else order

    def place(p, turned=True):
        p = np.asarray(p, dtype=np.float64)[list(axes)]
        p = (R @ p if turned else p) * scale + np.asarray(offset)
        return "[" + ", ".join(repr(float(x)) for x in p) + "]"

    def size(s):
        return "[" + ", ".join(repr(float(x) * scale) for x in np.asarray(s)[list(axes)]) + "]"

    b = 2.0 if turn is None else 2.9  # holds the turned goal, 1.6 sqrt(3) from the centre
    turned = [] if turn is None else [f"orientation = {[float(a) for a in turn]}"]
    lines = ['name = "cage"', "[robot]", f"box = {[ROBOT * scale] * 3}", *turned, "[planning]",
             f"bounds = [{place((-b, -b, -b), False)}, {place((b, b, b), False)}]",
             f"start = {place((0, 0, 0))}", f"goal = {place((1.6, 1.6, 1.6))}"]
    for k in order:
        c, s = walls[k]
        lines.append("[[obstacles]]")
        lines.append(f'name = "wall{k}"')
        if surfaces:  # the wall's mid-plane as an open square (2 triangles, one-sided)
            c, s = np.asarray(c, float), np.asarray(s, float)
            thin = int(np.argmin(s))
            u, v = [a for a in range(3) if a != thin]
            corners = []
            for du, dv in ((-1, -1), (1, -1), (1, 1), (-1, 1)):
                p = c.copy()
                p[u] += du * s[u] / 2
                p[v] += dv * s[v] / 2
                corners.append(np.asarray(place(p)[1:-1].split(", "), dtype=float))
            path = tmp / f"wall{k}.obj"
            path.write_text("".join(f"v {float(x)!r} {float(y)!r} {float(z)!r}\n" for x, y, z in corners)
                            + "f 1 2 3\nf 1 3 4\n")
            lines.append(f'mesh = "{path}"')
        else:
            lines += [f"box = {size(s)}", f"position = {place(c)}", *turned]
    return "\n".join(lines) + "\n"


def _cage(tmp_path, name="cage.toml", **kw):
    path = tmp_path / name
    path.write_text(cage_toml(tmp=tmp_path, **kw))
    scene = cspace.load_scene(path)
    return scene, cspace.model_scene(scene).cspace()


def _check_wall_with_fcl(scene, d, n_cells=60, seed=0):
    """Every sampled wall cell's corners, centre and random points collide by FCL on the raw
    meshes, or lie within a tolerance of a body that owes nothing to the decision:
    ``2**-20`` of the bounds' extent (the C-obstacles are grown by grid steps and a nudge,
    far below it; a wall cell in truly free space is far above it). The decision's own stated
    clearance must be below that tolerance too."""
    tol = 2.0**-20 * float(np.ptp(np.asarray(scene.bounds), axis=0).max())
    assert d.clearance <= tol, (d.clearance, tol)
    oracle = SceneOracle(scene)
    rng = np.random.default_rng(seed)
    cells = np.nonzero(d.wall)[0]
    assert len(cells) and np.isin(d.labels[cells], (BLOCKED, NEAR)).all()
    for c in rng.choice(cells, size=min(n_cells, len(cells)), replace=False):
        lo, hi = d.cells_lo[c], d.cells_hi[c]
        corners = np.array([[x, y, z] for x in (lo[0], hi[0]) for y in (lo[1], hi[1])
                            for z in (lo[2], hi[2])])
        pts = np.vstack([corners, (lo + hi) / 2, lo + rng.random((8, 3)) * (hi - lo)])
        pts = pts @ d.frame.T  # the cells' frame: turned to the C-obstacles' faces, or not
        hit = oracle.collides(pts)
        if not hit.all():
            assert (oracle.distance(pts[~hit]) <= tol).all(), (lo, hi)


def test_a_cage_whose_slot_is_narrower_than_the_robot_has_no_path(tmp_path):
    scene, cs = _cage(tmp_path, slot=0.2)
    d = decide(cs, scene.start, scene.goal, bounds=scene.bounds, exact=False)  # cells alone
    assert d.answer == "no path", d.reason
    assert 0 < d.clearance < 1e-6 and d.path is None
    assert d.start_component.any() and not (d.labels[d.start_component] == BLOCKED).any()
    _check_wall_with_fcl(scene, d)
    assert len(d.to_trimesh("blocked").faces) == 12 * int(d.wall.sum())
    assert "no path" in repr(d)


# The cage moved far, scaled, its axes and bodies permuted, turned (test_free_space too).
CAGE_MOVES = [
    dict(offset=(250.0, 150.0, -300.0)),
    dict(offset=(250.0, 150.0, -300.0), scale=3.0),
    dict(scale=0.01),
    dict(axes=(2, 0, 1), order=[6, 5, 4, 3, 2, 1, 0]),
    dict(offset=(-1e4, 3e3, 7.5), scale=7.0, axes=(1, 2, 0)),
    dict(turn=(17.0, -31.0, 52.0)),
    dict(offset=(250.0, 150.0, -300.0), scale=3.0, turn=(-63.0, 11.0, 140.0)),
]


@pytest.mark.parametrize("move", CAGE_MOVES + [dict(turn=(17.0, -31.0, 52.0), surfaces=True)])
def test_no_path_is_the_same_answer_wherever_the_cage_is(tmp_path, move):
    scene, cs = _cage(tmp_path, slot=0.2, **move)
    d = decide(cs, scene.start, scene.goal, bounds=scene.bounds, exact=False)  # cells alone
    assert d.answer == "no path", (move, d.reason)
    _check_wall_with_fcl(scene, d, n_cells=20)


@pytest.mark.parametrize("move", [dict(), dict(offset=(250.0, 150.0, -300.0), scale=3.0),
                                  dict(axes=(1, 2, 0)),
                                  dict(offset=(250.0, 150.0, -300.0), turn=(17.0, -31.0, 52.0))])
def test_a_slot_wider_than_the_robot_is_never_called_closed(tmp_path, move):
    """Slot 0.6 for a robot of 0.4 (C-space gap 0.2, ~6 finest cells): a path through free
    cells, proved exactly and by FCL."""
    scene, cs = _cage(tmp_path, slot=0.6, **move)
    d = decide(cs, scene.start, scene.goal, bounds=scene.bounds, time=20)
    assert d.answer == "path", d.reason
    assert verify_path(cs, d.path, scene.bounds)["valid"]
    np.testing.assert_array_equal(d.path[0], scene.start)
    np.testing.assert_array_equal(d.path[-1], scene.goal)
    bad, n = path_collisions(cs, d.path, scene=scene)
    assert len(bad) == 0 and n > 0


@pytest.mark.parametrize("slot", [ROBOT, ROBOT + 1e-3, ROBOT + 2.0 ** -20])
def test_a_slot_the_robot_barely_fits_gets_the_right_answer(tmp_path, slot):
    """At exactly the robot's width the C-obstacles touch (touching is a collision): no path,
    for clearances above the stated one, which is below a micrometre-scale gap's; a hair
    wider (2**-20: about 16 steps of the C-obstacles' grid), a proved path."""
    scene, cs = _cage(tmp_path, slot=slot)
    d = decide(cs, scene.start, scene.goal, bounds=scene.bounds, time=30)
    if slot == ROBOT:
        assert d.answer == "no path", d.reason
        assert d.clearance < 2.0 ** -21  # a path through the 2**-20 slot has a larger one
    else:
        assert d.answer == "path", d.reason
        assert verify_path(cs, d.path, scene.bounds)["valid"]


def test_open_walls_block_cells_too(tmp_path):
    """Walls as open one-sided squares (surface C-obstacles: a convex piece per triangle)."""
    scene, cs = _cage(tmp_path, slot=0.2, surfaces=True, offset=(250.0, 150.0, -300.0))
    assert {co.kind for co in cs.obstacles} - {"convex"}, [co.kind for co in cs.obstacles]
    d = decide(cs, scene.start, scene.goal, bounds=scene.bounds, time=20, exact=False)
    assert d.answer == "no path", d.reason
    _check_wall_with_fcl(scene, d, n_cells=20)


def test_shipped_scenes_are_never_called_closed_where_a_path_exists():
    """Every shipped scene but the piano has a translation path (the planners find it):
    the decision must not say otherwise; the piano's start orientation has none."""
    from pathlib import Path

    scenes = Path(__file__).resolve().parents[1] / "scenes"
    for name in ("window", "cavity", "comb", "maze", "piano"):
        scene = cspace.load_scene(scenes / f"{name}.toml")
        cs = cspace.model_scene(scene).cspace()
        d = decide(cs, scene.start, scene.goal, bounds=scene.bounds, time=20)
        if name == "piano":
            assert d.answer == "no path", d.reason
        else:
            assert d.answer in ("path", "unknown"), (name, d.reason)
        if d.answer == "path":
            assert verify_path(cs, d.path, scene.bounds)["valid"]


def test_bad_questions_get_named_errors(tmp_path):
    scene, cs = _cage(tmp_path, slot=0.2)
    with pytest.raises(InvalidArgumentError, match="start .* is in collision"):
        decide(cs, [-1.05, 0, 0], scene.goal, bounds=scene.bounds)
    with pytest.raises(InvalidArgumentError, match="goal .* outside the bounds"):
        decide(cs, scene.start, [9, 9, 9], bounds=scene.bounds)
    with pytest.raises(InvalidArgumentError, match="depth"):
        decide(cs, scene.start, scene.goal, depth=0)
    d = decide(cs, scene.start, scene.goal, bounds=scene.bounds, time=0.0)
    assert d.answer == "unknown" and "out of time" in d.reason


def test_plan_and_the_cli_answer_no_path(tmp_path):
    path = tmp_path / "cage.toml"
    path.write_text(cage_toml(slot=0.2))
    r = plan(cspace.load_scene(path), planner="auto", time=60.0, seed=1, turns=False)
    assert not r.solved and r.decision.answer == "no path" and len(r.path) == 0
    out = tmp_path / "r.json"
    # a budget far above the proof's (it ends at the proof): load cannot change the answer
    p = subprocess.run([sys.executable, "-m", "cspace", "plan", str(path), "--time", "60",
                        "--seed", "1", "--no-turns", "--no-cache", "--result", str(out)],
                       capture_output=True, text=True, timeout=300)
    assert p.returncode == 3, (p.stdout, p.stderr)
    assert "no path at the start's orientation, proved" in p.stdout
    assert json.loads(out.read_text())["decision"]["answer"] == "no path"


def test_turns_between_slices_do_not_open_the_cage(tmp_path):
    """A cube never fits a slot half its width, turned or not: over 8 slices and the turns
    between them there is no path either (``decide_turning``, a proof over those slices);
    `cspace plan` without flags says "no path at any orientation" (exit 3) from the ball
    inside the cube, which no turn changes, not from the slices."""
    from cspace.planning.decide import decide_turning
    from cspace.planning.plan import default_slices
    from cspace.planning.turning import TurningCSpace

    path = tmp_path / "cage.toml"
    path.write_text(cage_toml(slot=0.2, offset=(250.0, 150.0, -300.0)))
    scene = cspace.load_scene(path)
    td = decide_turning(TurningCSpace(scene, default_slices(scene, 8)), scene.start, scene.goal,
                        time=120.0)
    assert td.answer == "no path" and len(td.components) == 8 and td.links > 0, td.reason
    # budgets far above the proofs' (each ends at its proof): load cannot change the answer
    r = plan(scene, planner="auto", time=60.0, seed=1)
    assert not r.solved and r.decision.answer == "no path"
    # translations, a short SE(3) attempt, the decision, the ball's proof
    assert [(t["planner"], t.get("space"), t.get("robot"), t.get("answer"))
            for t in r.tried] == [
        ("RRTConnect", None, None, None), ("RRTConnect", "SE3", None, None),
        ("decide", None, None, "no path"), ("decide", None, "inscribed ball", "no path")]
    assert r.status == "No path at any orientation (proved)"
    p = subprocess.run([sys.executable, "-m", "cspace", "plan", str(path), "--time", "60",
                        "--seed", "1", "--no-cache"], capture_output=True, text=True,
                       timeout=300)
    assert p.returncode == 3, (p.stdout, p.stderr)
    assert "none at any orientation" in p.stdout


def test_turns_between_slices_do_not_open_a_turned_tight_cage(tmp_path):
    """The cage turned generically, far off, its slot 1e-3 narrower than the cube: every
    orientation's cells are cut along the cage's faces (one frame for all, so the slices'
    cells coincide), and over 8 slices and the turns between them there is no path, as for
    the cage in the scene's axes."""
    from cspace.planning.decide import decide_turning
    from cspace.planning.plan import default_slices
    from cspace.planning.turning import TurningCSpace

    path = tmp_path / "cage.toml"
    path.write_text(cage_toml(slot=ROBOT - 1e-3, offset=(250.0, 150.0, -300.0),
                              turn=(17.0, -31.0, 52.0)))
    scene = cspace.load_scene(path)
    tcs = TurningCSpace(scene, default_slices(scene, 8))
    td = decide_turning(tcs, scene.start, scene.goal, time=30.0)  # ~1 s; the budget caps
    assert td.answer == "no path" and len(td.components) == 8 and td.links > 0, td.reason
    eb = max(co.error_bound for k in range(8) for co in tcs.slice(k).obstacles)
    assert eb <= td.clearance < 1e-6


def test_turns_that_open_a_passage_are_not_ruled_out():
    """The piano passes the doorway only turned: at its start orientation there is no path,
    over slices the decision must not say so (and the turning planner then finds the way)."""
    from pathlib import Path

    from cspace.planning.decide import decide_turning
    from cspace.planning.plan import default_slices
    from cspace.planning.turning import TurningCSpace

    scene = cspace.load_scene(Path(__file__).resolve().parents[1] / "scenes" / "piano.toml")
    for n in (4, 8, 16):
        td = decide_turning(TurningCSpace(scene, default_slices(scene, n)), scene.start,
                            scene.goal)
        assert td.answer == "unknown", (n, td.reason)


def test_a_hull_proves_nothing_about_the_robot(tmp_path):
    scene, _ = _cage(tmp_path, slot=0.2)
    cs = cspace.model_scene(scene, robot_hull=True).cspace()
    d = decide(cs, scene.start, scene.goal, bounds=scene.bounds)
    assert d.answer == "unknown" and "convex hull" in d.reason


def test_the_pair_filter_agrees_with_the_exact_piece_test(tmp_path):
    """Blocked cells of open walls (triangle-pair C-obstacles) are found by a float filter
    over the pieces' half-spaces (compiled, and its numpy reference); both must agree with
    the exact test of every corner. Free cells (every piece near the cell off it by one of
    its slabs, compiled): as the numpy reference, and no point of them collides."""
    from cspace.planning.cells import (_CORNERS, _inside_a_pair, _inside_a_pair_reference,
                                       _pairs_apart_reference)

    scene, cs = _cage(tmp_path, slot=0.2, surfaces=True, offset=(250.0, 150.0, -300.0))
    rng = np.random.default_rng(0)
    pairs = [co for co in cs.obstacles if co.kind == "pairs"]
    assert len(pairs) == 7
    for co in pairs[:3]:
        impl = co._impl
        B = np.asarray(co.bounds)
        lo = B[0] + rng.random((80, 3)) * (B[1] - B[0])
        hi = lo + rng.random((80, 3)) * np.array([0.02, 0.2, 0.6])[rng.permutation(3)]
        C = np.where(_CORNERS[None].astype(bool), hi[:, None, :], lo[:, None, :])
        fast = _inside_a_pair(impl, lo, hi, C)
        cand = impl._set.candidates(impl._grid_units(lo), impl._grid_units(hi))
        exact = np.zeros(len(lo), dtype=bool)
        for r, i, j in cand.tolist():
            exact[r] |= all(impl._in_piece(i, j, x) for x in C[r].tolist())
        np.testing.assert_array_equal(fast, exact)
        np.testing.assert_array_equal(_inside_a_pair_reference(impl, lo, hi, C), exact)
        assert exact.any() and not exact.all()
        # cells around the C-obstacle's box too, where some are apart from it
        lo = B[0] - 0.3 + rng.random((80, 3)) * (B[1] - B[0] + 0.6)
        hi = lo + rng.random((80, 3)) * np.array([0.02, 0.2, 0.6])[rng.permutation(3)]
        apart = impl._set.boxes_apart(impl._grid_units(lo), impl._grid_units(hi)) == 1
        np.testing.assert_array_equal(apart, _pairs_apart_reference(impl, lo, hi))
        assert apart.any() and not apart.all()
        C = np.where(_CORNERS[None].astype(bool), hi[:, None, :], lo[:, None, :])
        pts = (lo[:, None] + rng.random((80, 20, 3)) * (hi - lo)[:, None])[apart]
        assert not co.contains(np.vstack([pts.reshape(-1, 3), C[apart].reshape(-1, 3)])).any()


def _hollow(tmp_path, start, goal, offset=(250.0, 150.0, -300.0)):
    """A closed hollow box (outer side 2.4, a cavity of side 2.0 wound inwards): one
    non-convex solid, summed by NCC-CVMS (kind 'mesh')."""
    import trimesh

    off = np.asarray(offset)
    outer, inner = trimesh.creation.box((2.4, 2.4, 2.4)), trimesh.creation.box((2.0, 2.0, 2.0))
    trimesh.Trimesh(np.vstack([outer.vertices, inner.vertices]) + off,
                    np.vstack([outer.faces, inner.faces[:, ::-1] + 8]),
                    process=False).export(tmp_path / "hollow.obj")
    path = tmp_path / "hollow.toml"
    path.write_text(f'name = "hollow"\n[robot]\nbox = [0.4, 0.4, 0.4]\n[planning]\n'
                    f"bounds = [{(off - 2).tolist()}, {(off + 2).tolist()}]\n"
                    f"start = {(off + start).tolist()}\ngoal = {(off + goal).tolist()}\n"
                    '[[obstacles]]\nmesh = "hollow.obj"\n')
    scene = cspace.load_scene(path)
    return scene, cspace.model_scene(scene).cspace()


def test_a_non_convex_solid_shuts_the_robot_in(tmp_path):
    scene, cs = _hollow(tmp_path, start=(0, 0, 0), goal=(1.6, 1.6, 1.6))
    assert [co.kind for co in cs.obstacles] == ["mesh"]
    d = decide(cs, scene.start, scene.goal, bounds=scene.bounds, exact=False)  # the cells'
    assert d.answer == "no path", d.reason
    _check_wall_with_fcl(scene, d, n_cells=30)
    outside, cs2 = _hollow(tmp_path, start=(-1.6, -1.6, -1.6), goal=(1.6, 1.6, 1.6))
    d2 = decide(cs2, outside.start, outside.goal, bounds=outside.bounds)
    assert d2.answer == "path" and verify_path(cs2, d2.path, outside.bounds)["valid"]


def _wall_with_a_hole(rng, tmp_path):
    """A wall across the bounds (x = 0) with a rectangular hole, a box robot, start and goal
    on either side; moved, scaled, its bodies shuffled. The truth by construction: a path
    exists iff the hole is wider than the robot on both axes."""
    off = rng.choice([0.0, 1.0]) * np.array([250.0, 150.0, -300.0]) * rng.choice([1, 10])
    scale = float(rng.choice([1.0, 3.0, 0.1]))
    R = rng.uniform(0.2, 0.6, 3)
    hy, hz = rng.uniform(0.1, 0.8, 2)
    cy, cz = rng.uniform(-1, 1, 2)
    t, E = rng.uniform(0.02, 0.3), 3.0
    y0, y1, z0, z1 = cy - hy / 2, cy + hy / 2, cz - hz / 2, cz + hz / 2
    boxes = [((0, (-E + y0) / 2, 0), (t, y0 + E, 2 * E)), ((0, (y1 + E) / 2, 0), (t, E - y1, 2 * E)),
             ((0, cy, (-E + z0) / 2), (t, hy, z0 + E)), ((0, cy, (z1 + E) / 2), (t, hy, E - z1))]

    def at(p):
        return [float(x) for x in np.asarray(p) * scale + off]

    lines = ['name = "wall"', "[robot]", f"box = {[float(x) for x in R * scale]}", "[planning]",
             f"bounds = [{at((-2, -2, -2))}, {at((2, 2, 2))}]", f"start = {at((-1.5, 0, 0))}",
             f"goal = {at((1.5, 0.3, -0.2))}"]
    for k in rng.permutation(4):
        c, s = boxes[k]
        lines += ["[[obstacles]]", f"box = {[float(x) * scale for x in s]}", f"position = {at(c)}"]
    path = tmp_path / "wall.toml"
    path.write_text("\n".join(lines) + "\n")
    scene = cspace.load_scene(path)
    return scene, hy > R[1] and hz > R[2], min(hy - R[1], hz - R[2]) * scale


def _never_contradicts_the_truth(tmp_path, seed, n):
    rng = np.random.default_rng(seed)
    answers = []
    for _ in range(n):
        scene, fits, spare = _wall_with_a_hole(rng, tmp_path)
        cs = cspace.model_scene(scene).cspace()
        if cs.contains(scene.start) or cs.contains(scene.goal):
            continue
        d = decide(cs, scene.start, scene.goal, bounds=scene.bounds, time=10)
        answers.append(d.answer)
        if d.answer == "no path":  # allowed only where no path with clearance exists
            assert not fits or spare <= d.clearance, (spare, d.reason)
        if d.answer == "path":
            assert fits and verify_path(cs, d.path, scene.bounds)["valid"]
    return answers


def test_walls_with_holes_never_get_a_wrong_answer(tmp_path):
    answers = _never_contradicts_the_truth(tmp_path, 0, 8)
    assert "no path" in answers and "path" in answers


@pytest.mark.slow
def test_walls_with_holes_never_get_a_wrong_answer_200(tmp_path):
    answers = _never_contradicts_the_truth(tmp_path, 1, 200)
    assert answers.count("no path") > 50 and answers.count("path") > 20


def test_slices_that_stop_at_different_levels_are_compared_on_one_grid(tmp_path):
    """One small obstacle in a corner: some slices need no refinement at all, others do; the
    components are still compared cell for cell (and nothing here is closed)."""
    from cspace.planning.decide import decide_turning
    from cspace.planning.plan import default_slices
    from cspace.planning.turning import TurningCSpace

    path = tmp_path / "corner.toml"
    path.write_text('name = "corner"\n[robot]\nbox = [1.0, 0.1, 0.1]\n[planning]\n'
                    "bounds = [[0, 0, 0], [4, 4, 4]]\nstart = [1, 1, 1]\ngoal = [3, 1, 1]\n"
                    "[[obstacles]]\nbox = [0.2, 0.2, 0.2]\nposition = [4.5, 4.5, 3.95]\n")
    scene = cspace.load_scene(path)
    td = decide_turning(TurningCSpace(scene, default_slices(scene, 4)), scene.start, scene.goal)
    assert td.answer == "unknown" and len(td.components) == 4, td.reason


def test_surface_pieces_block_as_the_pairs_do(tmp_path):
    """The same open walls as convex pieces per triangle (SurfaceObstacle, the reference the
    scene's triangle pairs are tested against): the same proof, the wall checked by FCL."""
    from cspace.cobstacle.surface import SurfaceObstacle

    scene, cs = _cage(tmp_path, slot=0.2, surfaces=True, offset=(250.0, 150.0, -300.0))
    m = cspace.model_scene(scene)
    (part,) = m.robot_parts
    robot = m.margin.grow(part.operand)
    walls = [SurfaceObstacle.build((b.vertices, b.faces), robot, scene.reference_point,
                                   grid=m.grid) for b in m.bodies]
    assert {co.kind for co in walls} == {"surface"}
    d = decide(cspace.CSpace(walls, bounds=scene.bounds), scene.start, scene.goal, exact=False)
    assert d.answer == "no path", d.reason
    _check_wall_with_fcl(scene, d, n_cells=20)


def test_a_real_pair_scene_keeps_the_budget(shared_data):
    """The Parasol bug trap (3212 obstacle triangles against a non-convex 66-triangle robot,
    a triangle-pair C-obstacle): every pair a coarse cell met was once tested, and a 3 s
    decision took minutes. The decision answers within its budget (how long it overruns is
    a duration, measured by the project's stop check on the same scene, not asserted here:
    a busy machine would decide it) and what it answers is certified."""
    import warnings

    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # the robot's hull is warned about, not used here
        scene = cspace.load_scene(shared_data / "parasol_open_ppl_env/bug_trap1.0/bug-trap.env")
    cs = cspace.model_scene(scene).cspace()
    assert "pairs" in {co.kind for co in cs.obstacles}
    d = decide(cs, scene.start, scene.goal, bounds=scene.bounds, time=3.0)
    assert d.answer != "path" or verify_path(cs, d.path, scene.bounds)["valid"]
    assert d.answer != "unknown" or "time" in d.reason, d.reason


@pytest.mark.slow
def test_the_bug_trap_is_proved_closed_at_its_start_orientation(shared_data):
    """The Parasol bug trap, translations only at the stick bug's start orientation: 'no
    path', proved in about 7 s (the octree, then some 67 000 cells refined along routes)
    by ``plan(planner='auto', turns=False)``, in its first decision.
    The proof's wall, octree and refined cells alike, is checked by FCL on the raw meshes
    (which share nothing with the cells): every sampled cell collides, or lies within the
    stated clearance of the trap."""
    import warnings

    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # the robot's hull is warned about, not used here
        scene = cspace.load_scene(shared_data / "parasol_open_ppl_env/bug_trap1.0/bug-trap.env")
    cs = cspace.model_scene(scene).cspace()
    # as `cspace plan --no-turns --time 20` asks (twice `--time 10`, for a loaded machine):
    # RRTConnect fails, and the decision, with 85% of the budget, proves it
    r = plan(cs, scene.start, scene.goal, bounds=scene.bounds, planner="auto", time=20.0,
             seed=1, turns=False)
    d = r.decision
    assert not r.solved and d.answer == "no path", (d.reason, r.tried)
    assert [t["planner"] for t in r.tried] == ["RRTConnect", "decide"]
    b = np.asarray(scene.bounds)
    fine = d.wall & ((d.cells_hi - d.cells_lo) < 0.75 * (b[1] - b[0]) / 2 ** d.depth).any(axis=1)
    assert fine.any()
    _check_wall_with_fcl(scene, d, n_cells=60)
    import dataclasses

    _check_wall_with_fcl(scene, dataclasses.replace(d, wall=fine), n_cells=60, seed=1)
