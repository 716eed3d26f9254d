"""Refining cells along routes (:mod:`cspace.planning.corridor`): gaps finer than the decision's
octree are found, every path re-proved exactly and checked by FCL on the raw meshes (which
share nothing with the cells); a closed slot is never opened, wherever the scene and its
cells sit; and a wall the octree could not prove is proved by refining."""

from __future__ import annotations

import sys

import numpy as np
import pytest

import cspace
from cspace.check.cross_check import path_collisions
from cspace.planning.plan import verify_path

sys.path.insert(0, str(__import__("pathlib").Path(__file__).parent))
from test_decide import ROBOT, _cage  # noqa: E402

decide_module = sys.modules["cspace.planning.decide"]
decide = decide_module.decide
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
def test_refining_never_opens_a_closed_slot(tmp_path, slot):
    """Cells shifted off the slot's middle (the bounds moved by a non-dyadic 0.0137), far
    from the origin: never 'path'; a slot narrower by 0.02 is proved closed by refining,
    where the octree alone is not."""
    scene, cs = _cage(tmp_path, slot=slot, offset=FAR)
    b = np.asarray(scene.bounds) + np.array([0.0, 0.0137, 0.0])
    d = decide(cs, scene.start, scene.goal, bounds=b, time=3)
    assert d.answer in ("no path", "unknown"), d.reason
    if slot == ROBOT - 2e-2:
        alone = decide(cs, scene.start, scene.goal, bounds=b, refine=False)
        assert alone.answer == "unknown"
        assert d.answer == "no path" and "refined" in d.reason, d.reason


def test_a_slot_the_robot_barely_fits_through_is_found_or_left_unknown(tmp_path):
    """Wider by 1e-5 (about 100 k cells to cross the wall): within a small budget the answer
    is a proved path or 'unknown', never 'no path'."""
    scene, cs = _cage(tmp_path, slot=ROBOT + 1e-5, offset=FAR)
    d = decide(cs, scene.start, scene.goal, bounds=scene.bounds, time=2)
    assert d.answer in ("path", "unknown"), d.reason
    if d.answer == "path":
        assert verify_path(cs, d.path, scene.bounds)["valid"]


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
