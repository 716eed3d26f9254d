"""Refining cells along routes (:mod:`cspace.planning.corridor`): gaps finer than the decision's
octree are found, every path re-proved exactly and checked by FCL on the raw meshes (which
share nothing with the cells); a closed slot is never opened, wherever the scene and its
cells sit; and a wall the octree could not prove is proved by refining."""

from __future__ import annotations

import dataclasses
import functools
import sys

import numpy as np
import pytest

import cspace
from cspace.check.cross_check import path_collisions
from cspace.planning.plan import verify_path

sys.path.insert(0, str(__import__("pathlib").Path(__file__).parent))
from test_decide import ROBOT, _cage, _check_wall_with_fcl  # noqa: E402

decide_module = sys.modules["cspace.planning.decide"]
# These tests are of the cells and their refinement: the exact free space, which decides
# most of these scenes first, is tested in test_free_space.py.
decide = functools.partial(decide_module.decide, exact=False)
BLOCKED, NEAR = decide_module.BLOCKED, decide_module.NEAR
FAR = (250.0, 150.0, -300.0)


def _fcl_clean(scene, cs, path):
    """FCL on the raw meshes: no pose along the path collides (every 1e-4 of the bounds'
    diagonal: the gaps here are 1e-3 wide)."""
    b = np.asarray(scene.bounds, dtype=np.float64)
    bad, n = path_collisions(cs, path, step=1e-4 * float(np.linalg.norm(b[1] - b[0])),
                             scene=scene)
    return len(bad) == 0 and n > 0


@pytest.mark.parametrize("move", [dict(), dict(offset=FAR), dict(offset=FAR, scale=3.0),
                                  dict(axes=(2, 0, 1), offset=(-40.0, 7.0, 12.0))])
def test_a_gap_thirty_times_finer_than_a_cell_is_found(tmp_path, move):
    """The slot is wider than the robot by 1e-3 (the octree's finest cell: 4/128 = 0.031):
    the octree alone cannot tell; refining along routes finds the path, moved or not."""
    scene, cs = _cage(tmp_path, slot=ROBOT + 1e-3, **move)
    alone = decide(cs, scene.start, scene.goal, bounds=scene.bounds, refine=False)
    assert alone.answer == "unknown", alone.reason
    d = decide(cs, scene.start, scene.goal, bounds=scene.bounds, time=20)
    assert d.answer == "path", d.reason
    assert verify_path(cs, d.path, scene.bounds)["valid"]
    np.testing.assert_array_equal(d.path[0], scene.start)
    np.testing.assert_array_equal(d.path[-1], scene.goal)
    assert _fcl_clean(scene, cs, d.path)


@pytest.mark.parametrize("slot", [ROBOT, ROBOT - 1e-3, ROBOT - 2e-2])
def test_refining_proves_a_closed_slot_closed(tmp_path, slot):
    """Cells shifted off the slot's middle (the bounds moved by a non-dyadic 0.0137), far
    from the origin: a slot exactly the robot's width (its C-obstacles touch), or narrower,
    is proved closed by refining, where the octree alone cannot. The refined wall is in the
    certificate, and every sampled cell of it collides by FCL on the raw meshes, or lies
    within the stated clearance of a body (the C-obstacles are grown; cells near a piece)."""
    scene, cs = _cage(tmp_path, slot=slot, offset=FAR)
    b = np.asarray(scene.bounds) + np.array([0.0, 0.0137, 0.0])
    alone = decide(cs, scene.start, scene.goal, bounds=b, refine=False)
    assert alone.answer == "unknown"
    # ~1 s; the budget only caps (a loaded machine must not turn the proof into 'unknown')
    d = decide(cs, scene.start, scene.goal, bounds=b, time=30)
    assert d.answer == "no path" and "refined" in d.reason, d.reason
    eb = max(co.error_bound for co in cs.obstacles)
    if slot == ROBOT:  # touching: walled by cells near the pieces; the statement says so
        assert (d.labels[d.wall] == NEAR).any() and eb < d.clearance < 1e-6
    finest = (b[1] - b[0]) / 2 ** d.depth
    fine = d.wall & ((d.cells_hi - d.cells_lo) < 0.75 * finest).any(axis=1)
    assert fine.any() and np.isin(d.labels[d.wall], (BLOCKED, NEAR)).all()
    _check_wall_with_fcl(scene, d, n_cells=40)
    _check_wall_with_fcl(scene, dataclasses.replace(d, wall=fine), n_cells=40, seed=1)
    assert len(d.to_trimesh("blocked").faces) == 12 * int(d.wall.sum())


@pytest.mark.parametrize("wider, move", [(1e-5, dict(offset=FAR)),
                                         (6e-7, dict(offset=FAR)),
                                         (1e-5, dict(axes=(2, 0, 1), offset=(-40.0, 7.0, 12.0)))])
def test_a_slot_a_few_grid_steps_wider_than_the_robot_is_found(tmp_path, wider, move):
    """Wider by 1e-5, or by 6e-7 (ten steps of the C-obstacles' grid, 2**-24; a clearance of
    3e-7 each side, above what a proof would claim): 0.5 long across the wall, so cubes
    along it would number 10**5 and more; slabs across it are few. A proved path, clean by
    FCL on the raw meshes."""
    scene, cs = _cage(tmp_path, slot=ROBOT + wider, **move)
    d = decide(cs, scene.start, scene.goal, bounds=scene.bounds, time=30)
    assert d.answer == "path", d.reason
    assert verify_path(cs, d.path, scene.bounds)["valid"]
    assert _fcl_clean(scene, cs, d.path)


def tight_maze(tmp_path, slot: float, offset=FAR):
    """The shipped maze (scenes/generate.py) with its first passage a slot ``slot`` wide for
    the robot's 0.5, moved by ``offset``: the only route passes it."""
    import importlib.util

    spec = importlib.util.spec_from_file_location(
        "scene_generate", __import__("pathlib").Path(__file__).parents[1] / "scenes" /
        "generate.py")
    generate = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(generate)
    path = tmp_path / f"maze-{slot!r}.toml"
    path.write_text(generate.maze(slot=slot, offset=offset))
    scene = cspace.load_scene(path)
    return scene, cspace.model_scene(scene).cspace()


def test_a_maze_whose_only_route_passes_a_gap_ten_grid_steps_wider_is_solved_every_time(
        tmp_path):
    """Issue #31's maze: a serpentine through 18 cells whose first passage is 6e-7 wider
    than the robot (ten steps of its grid at (250, 150, -300)). ``plan`` without flags but
    ``turns=False`` returns a path for every seed, re-proved exactly and clean by FCL on the
    raw meshes; the slot exactly the robot's width is proved closed."""
    from cspace.planning.plan import plan

    scene, cs = tight_maze(tmp_path, 0.5 + 6e-7)
    for seed in (1, 2, 3):
        r = plan(cs, scene.start, scene.goal, bounds=scene.bounds, planner="auto", time=10,
                 seed=seed, turns=False)
        assert r.solved, (seed, r.decision and r.decision.reason)
        assert verify_path(cs, r.path, scene.bounds)["valid"]
        assert _fcl_clean(scene, cs, r.path)
    scene, cs = tight_maze(tmp_path, 0.5)
    d = decide_module.decide(cs, scene.start, scene.goal, bounds=scene.bounds, time=10)
    assert d.answer == "no path", d.reason


TURN = (17.0, -31.0, 52.0)


@pytest.mark.parametrize("slot", [ROBOT, ROBOT - 1e-3, ROBOT + 1e-5])
def test_a_turned_slot_is_decided_in_the_frame_of_its_faces(tmp_path, slot):
    """The cage turned generically, far off, its bounds moved by a non-dyadic step: the
    slot's walls are slanted to the scene's axes, so the cells are cut along the
    C-obstacles' faces (``frame='auto'``). Closed (the robot's width, or narrower): 'no
    path', its wall colliding by FCL on the raw meshes or within the stated clearance;
    1e-5 wider: a path clean by FCL. The cells' frame is the cage's, not the scene's."""
    scene, cs = _cage(tmp_path, slot=slot, offset=FAR, turn=TURN)
    b = np.asarray(scene.bounds) + np.array([0.0137, 0.0, 0.0])
    d = decide(cs, scene.start, scene.goal, bounds=b, time=30)  # ~1 s; the budget only caps
    assert not np.allclose(d.frame, np.eye(3))
    if slot > ROBOT:
        assert d.answer == "path", d.reason
        assert verify_path(cs, d.path, b)["valid"] and _fcl_clean(scene, cs, d.path)
        return
    assert d.answer == "no path", d.reason
    eb = max(co.error_bound for co in cs.obstacles)
    assert eb < d.clearance < 1e-6
    _check_wall_with_fcl(scene, d, n_cells=40)
    walls = d.to_trimesh("blocked")  # in the scene: the cells turned by the frame
    assert len(walls.faces) == 12 * int(d.wall.sum())
    V = np.asarray(walls.vertices).reshape(-1, 8, 3)  # no wall cell lies outside the bounds
    assert ((V.min(axis=1) <= b[1]) & (V.max(axis=1) >= b[0])).all()


def test_a_turned_slot_in_the_scenes_axes_never_gets_a_wrong_answer(tmp_path):
    """``frame=None`` (the scene's axes) on the turned closed slot: cells along the axes do
    not fit its slanted walls, so within a small budget the answer may be 'unknown'; it is
    never 'path'."""
    scene, cs = _cage(tmp_path, slot=ROBOT, offset=FAR, turn=TURN)
    d = decide(cs, scene.start, scene.goal, bounds=scene.bounds, time=1, frame=None)
    assert d.answer != "path", d.reason
    np.testing.assert_array_equal(d.frame, np.eye(3))


@pytest.mark.parametrize("slot", [0.2, ROBOT + 0.1])
def test_any_frame_gives_a_sound_answer(tmp_path, slot):
    """A frame that fits nothing (a random turn) on the cage in the scene's axes, far off:
    the cells cross every wall at a slant and the bounds' faces too (cells wholly outside
    them are blocked, the rest labelled as usual): the closed slot 'no path', the open one a
    path clean by FCL."""
    from scipy.spatial.transform import Rotation

    M = Rotation.from_euler("xyz", (29.0, -47.0, 71.0), degrees=True).as_matrix()
    scene, cs = _cage(tmp_path, slot=slot, offset=FAR)
    d = decide(cs, scene.start, scene.goal, bounds=scene.bounds, time=30, frame=M)
    np.testing.assert_array_equal(d.frame, M)
    if slot < ROBOT:
        assert d.answer == "no path", d.reason
        _check_wall_with_fcl(scene, d, n_cells=30)
    else:
        assert d.answer == "path", d.reason
        assert verify_path(cs, d.path, scene.bounds)["valid"] and _fcl_clean(scene, cs, d.path)


def test_a_frame_is_checked(tmp_path):
    """A frame that is not orthonormal, not (3, 3), or with flat bounds: a named error."""
    scene, cs = _cage(tmp_path, slot=0.2)
    for bad in (2 * np.eye(3), np.eye(2), "scene"):
        with pytest.raises(cspace.InvalidArgumentError):
            decide(cs, scene.start, scene.goal, bounds=scene.bounds, frame=bad)
    flat = np.asarray(scene.bounds, dtype=float).copy()
    flat[:, 2] = 0.0
    with pytest.raises(cspace.InvalidArgumentError):
        decide(cs, scene.start, scene.goal, bounds=flat, frame=np.eye(3)[[1, 0, 2]])


def test_fine_cells_tile_the_octree_cells():
    """The fine corners are the octree's at a voxel's corners and increase with the integers
    (so touching on integers is touching in floats), far from the origin too."""
    from cspace.planning.cells import _Grid
    from cspace.planning.corridor import _Cells

    b = np.array([[249.3, 149.1, -301.7], [251.1, 152.9, -298.2]])
    g = _Grid(b, 5)
    size = np.array([2, 2, 2])
    fcomp = np.zeros((16, 16, 16), dtype=np.int32)
    cells = _Cells(g, size, fcomp, np.zeros((0, 3), np.int64), 0)
    S = cells.S
    I = np.stack([np.arange(0, 16 * S + 1, S // 8)] * 3, axis=1)
    X = cells.floats(I)
    assert (np.diff(X, axis=0) > 0).all()
    on = I[:, 0] % S == 0
    for a in range(3):
        np.testing.assert_array_equal(X[on, a], g.x[a][(I[on, a] // S) * 2])
    assert X[0].tolist() == b[0].tolist() and X[-1].tolist() == b[1].tolist()


def test_the_shipped_narrow_gaps_are_decided():
    """window and cavity: the gaps are a third of a finest cell; the decision now returns a
    proved path for both (deterministic: no sampling)."""
    from pathlib import Path

    scenes = Path(__file__).resolve().parents[1] / "scenes"
    for name in ("window", "cavity"):
        scene = cspace.load_scene(scenes / f"{name}.toml")
        cs = cspace.model_scene(scene).cspace()
        d = decide(cs, scene.start, scene.goal, bounds=scene.bounds, time=20)
        assert d.answer == "path", (name, d.reason)
        assert verify_path(cs, d.path, scene.bounds)["valid"]
        assert _fcl_clean(scene, cs, d.path)


def _place(p, offset=(0.0, 0.0, 0.0), scale=1.0, turn=None) -> np.ndarray:
    """Points of the unit scene turned (roll, pitch, yaw in degrees), scaled and moved."""
    from scipy.spatial.transform import Rotation

    p = np.asarray(p, dtype=np.float64)
    if turn is not None:
        p = p @ Rotation.from_euler("xyz", turn, degrees=True).as_matrix().T
    return p * scale + np.asarray(offset, dtype=np.float64)


def _c_boxes_scene(tmp_path, name, c_boxes, start, goal, offset, scale, turn=None, half=2.0):
    """Obstacle boxes whose C-obstacles (against the ROBOT cube) are the boxes ``c_boxes``
    ((lo, hi) pairs): each shrunk by the robot's half-width; then turned (the robot too),
    moved and scaled; the bounds (``half`` wide each side) stay axis-aligned."""
    h, n = ROBOT / 2, -half

    def at(p, turned=True):
        return repr(_place(p, offset, scale, turn if turned else None).tolist())

    turned = [] if turn is None else [f"orientation = {[float(a) for a in turn]}"]
    lines = [f'name = "{name}"', "[robot]", f"box = {[ROBOT * scale] * 3}", *turned,
             "[planning]", f"bounds = [{at((n, n, n), False)}, {at((half, half, half), False)}]",
             f"start = {at(start)}", f"goal = {at(goal)}"]
    for lo, hi in c_boxes:
        lo, hi = np.asarray(lo, float) + h, np.asarray(hi, float) - h
        lines += ["[[obstacles]]", f"box = {[float(x) * scale for x in hi - lo]}",
                  f"position = {at((lo + hi) / 2)}", *turned]
    path = tmp_path / f"{name}.toml"
    path.write_text("\n".join(lines) + "\n")
    scene = cspace.load_scene(path)
    return scene, cspace.model_scene(scene).cspace()


MOVES = [dict(offset=(0, 0, 0), scale=1.0), dict(offset=FAR, scale=3.0),
         dict(offset=FAR, scale=3.0, turn=TURN)]


@pytest.mark.parametrize("move", MOVES[:2] + [pytest.param(MOVES[2], marks=pytest.mark.slow)])
def test_c_obstacles_touching_along_an_edge_are_walled_where_they_meet(tmp_path, move):
    """A wall (x in [-0.5, 0.5], beyond the bounds in y and z) whose C-obstacles fill the
    quadrants y, z <= 0 and y, z >= 0; the pocket y >= 0, z <= 0 opens to the start's side
    only, the pocket y <= 0, z >= 0 to the goal's only (caps). The two pockets meet only along
    the line y = z = 0, where the two C-obstacles touch: touching is a collision, so there is
    no path. No cell inside one C-obstacle covers the line; cells near one do (bars along it):
    'no path', for clearances above the stated one, and the wall checked by FCL. Turned,
    the walls (4 from the middle) still cross the axis-aligned bounds (3.5 to a corner); the
    C-obstacles' faces are up to 4e-7 rad off the frame (each snapped to its grid), so the bar
    along the edge takes about 12 000 cells and 8 s: slow."""
    E, t, w = 4.0, 0.5, 0.6
    c_boxes = [((-t, -E, -E), (t, 0, 0)), ((-t, 0, 0), (t, E, E)),
               ((t, 0, -E), (t + w, E, 0)), ((-t - w, -E, 0), (-t, 0, E))]
    scene, cs = _c_boxes_scene(tmp_path, "edge", c_boxes, (-1.5, 0.5, -0.5), (1.5, -0.5, 0.5),
                               **move)
    assert not cs.contains(scene.start) and not cs.contains(scene.goal)
    # the pockets are free (1e-4 from the line too: above the C-obstacles' error_bound, the
    # outward growth) and the line between them, where the C-obstacles touch, is not
    pockets = _place([[0, 0.5, -0.5], [0, -0.5, 0.5], [0, 1e-4, -1e-4], [0, -1e-4, 1e-4]],
                     **move)
    assert not cs.contains(pockets).any()
    line = _place(np.outer(np.linspace(-0.4, 0.4, 9), [1.0, 0, 0]), **move)
    assert cs.contains(line).all()
    assert not cs.segment_free(pockets[2], pockets[3])
    d = decide(cs, scene.start, scene.goal, bounds=scene.bounds, time=30.0)
    assert d.answer == "no path", d.reason
    eb = max(co.error_bound for co in cs.obstacles)
    assert (d.labels[d.wall] == NEAR).any() and eb < d.clearance < 1e-5 * move["scale"]
    _check_wall_with_fcl(scene, d, n_cells=40)


@pytest.mark.parametrize("move", MOVES)
def test_c_obstacles_touching_along_a_face_are_walled_where_they_meet(tmp_path, move):
    """A wall across the bounds in two halves whose C-obstacles meet at y = 0.3 (the
    obstacles a robot's width apart: a gap exactly the robot's width), start on one side, goal
    on the other: 'no path', walled along the seam."""
    E, t = 4.0, 0.5
    c_boxes = [((-t, -E, -E), (t, 0.3, E)), ((-t, 0.3, -E), (t, E, E))]
    scene, cs = _c_boxes_scene(tmp_path, "seam", c_boxes, (-1.5, 0.2, 0.1), (1.5, 0.4, -0.3),
                               **move)
    seam = _place([[0, 0.3, z] for z in np.linspace(-1.5, 1.5, 7)], **move)
    assert cs.contains(seam).all()
    d = decide(cs, scene.start, scene.goal, bounds=scene.bounds, time=30.0)
    assert d.answer == "no path", d.reason
    _check_wall_with_fcl(scene, d, n_cells=40)


@pytest.mark.parametrize("move", MOVES)
def test_a_path_never_slips_between_c_obstacles_touching_at_a_vertex(tmp_path, move):
    """Two C-obstacle boxes touching at one point, the straight line from start to goal
    through it; around them the bounds are free. The answer must be a path (around) whose
    every segment is re-proved and which FCL finds clean on the raw meshes, never one through
    the vertex (a point of both C-obstacles)."""
    c_boxes = [((-1.0, -1.0, -1.0), (0.0, 0.0, 0.0)), ((0.0, 0.0, 0.0), (1.0, 1.0, 1.0))]
    scene, cs = _c_boxes_scene(tmp_path, "vertex", c_boxes, (-1.5, 1.5, 1.5),
                               (1.5, -1.5, -1.5), half=3.0 if "turn" in move else 2.0, **move)
    vertex = _place([0.0, 0.0, 0.0], **move)
    assert cs.contains(vertex) and not cs.segment_free(scene.start, scene.goal)
    d = decide(cs, scene.start, scene.goal, bounds=scene.bounds, time=30.0)
    assert d.answer == "path", d.reason
    assert verify_path(cs, d.path, scene.bounds)["valid"]
    assert _fcl_clean(scene, cs, d.path)


def _flat_seam(tmp_path, offset, gap):
    """A wall in two halves meeting at y = 0.3 (``gap`` between their C-obstacles), moved by
    ``offset``, in bounds flat in z: ``(scene, cspace, bounds)``."""
    E, t = 3.0, 0.5
    c_boxes = [((-t, -E, -E), (t, 0.3, E)), ((-t, 0.3 + gap, -E), (t, E, E))]
    scene, cs = _c_boxes_scene(tmp_path, "seam", c_boxes, (-1.5, 0.2, 0.0), (1.5, 0.4, 0.0),
                               offset, 1.0)
    b = np.asarray(scene.bounds).copy()
    b[:, 2] = scene.start[2]
    return scene, cs, b


@pytest.mark.parametrize("offset", [(0.0, 0.0, 0.0), FAR])
@pytest.mark.parametrize("gap", [0.0, 1e-5, -1e-3])
def test_a_seam_in_flat_bounds_is_decided(tmp_path, offset, gap):
    """Bounds flat in z (a planar problem, as OMPL.app's 2D ones): the refinement's cells do
    not split the flat axis. A wall in two halves whose C-obstacles meet (gap 0), overlap
    (-1e-3) or leave a gap of 1e-5 at y = 0.3: 'no path' for the first two, a proved path
    through the gap for the last, wherever the scene sits."""
    scene, cs, b = _flat_seam(tmp_path, offset, gap)
    d = decide(cs, scene.start, scene.goal, bounds=b, time=30)
    assert d.answer == ("path" if gap > 0 else "no path"), d.reason
    if d.answer == "path":
        assert verify_path(cs, d.path, b)["valid"]
        assert (d.path[:, 2] == scene.start[2]).all()


def test_a_turned_frames_rounding_is_within_its_bound():
    """The turned corners (floats) against the exact ones (rationals of the same float
    frame and box): within ``rho`` per coordinate, far from the origin; and a cell called
    outside the bounds is, exactly (every exact corner beyond the same face)."""
    from fractions import Fraction

    from scipy.spatial.transform import Rotation

    from cspace.planning.cells import _Frame

    rng = np.random.default_rng(7)
    b = np.array([[244.0, 144.0, -306.0], [256.0, 156.0, -294.0]])
    M = Rotation.from_euler("xyz", (29.0, -47.0, 71.0), degrees=True).as_matrix()
    F = _Frame(M, b)
    lo = F.domain[0] + rng.random((300, 3)) * (F.domain[1] - F.domain[0])
    hi = lo + rng.random((300, 3)) * 0.5
    W = F.corners(lo, hi)
    out = F.outside(W)
    assert out.any() and not out.all()
    Mq = [[Fraction(x) for x in row] for row in M.tolist()]
    for r in range(len(lo)):
        exact = [[sum(Mq[i][j] * Fraction(float(x[j])) for j in range(3)) for i in range(3)]
                 for x in np.where(np.array([[i, j, k] for i in (0, 1) for j in (0, 1)
                                             for k in (0, 1)], bool), hi[r], lo[r])]
        err = max(abs(Fraction(float(W[r, c, i])) - exact[c][i]) for c in range(8)
                  for i in range(3))
        assert err <= Fraction(F.rho)
        if out[r]:
            assert any(all(p[i] < Fraction(float(b[0, i])) for p in exact)
                       or all(p[i] > Fraction(float(b[1, i])) for p in exact)
                       for i in range(3))
