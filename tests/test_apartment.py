"""An apartment-class world (tests/real_problems.py:apartment, Collada + .cfg as OMPL.app
ships them): open and closed bodies, double-sided walls, floor and ceiling that close up into
a shell, furniture inside it, a non-convex sliver-laden robot, all near (250, 150, -300).

The shell is a set of double-sided sheets: its inside is free space (FCL's reading, winding
number 0), not a solid block, and furniture inside it is not its cavity. Checked against the
scene oracle (FCL on the raw meshes, its own solid rule), which shares nothing with the model.
"""

from __future__ import annotations

import numpy as np
import pytest

import cspace
from cspace.check.cross_check import cross_check
from cspace.check.oracle import SceneOracle

import real_problems as rp


@pytest.fixture(scope="module")
def small_apartment(tmp_path_factory):
    folder = tmp_path_factory.mktemp("apartment")
    problem = rp.apartment(folder, rooms=(2, 2), sheet_cells=(16, 12), furniture=3,
                           sliver_edges=60)
    return problem, cspace.load_scene(problem.cfg)


def test_a_shell_of_double_sided_sheets_encloses_nothing(small_apartment):
    problem, scene = small_apartment
    m = cspace.model_scene(scene, cache=None)
    shell = [b for b in m.bodies if "both windings" in b.reason]
    assert len(shell) == 1 and shell[0]._encloses is None
    # the closed furniture inside the shell stands alone, not as the shell's cavities
    assert sum(b.kind in ("solid", "convex") for b in m.bodies) >= 4
    cs = m.cspace()
    oracle = SceneOracle(scene)
    assert not cs.contains(scene.start) and not cs.contains(scene.goal)
    assert not oracle.collides(np.array([scene.start, scene.goal])).any()


def test_the_apartment_agrees_with_the_oracle(small_apartment):
    _, scene = small_apartment
    cs = cspace.CSpace.from_scene(scene, cache=None)
    r = cross_check(cs, n=600, seed=2, scene=scene)
    assert r["oracle"] == "scene" and r["n_inside"] > 30
    assert r["n_disagree"] == 0, r["disagreements"][:3]
