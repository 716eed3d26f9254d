"""Use cspace's exact checks inside your own OMPL ``SimpleSetup``.

The state space is the translation of the robot's reference point (``RealVectorStateSpace(3)``).
``CSpaceValidityChecker`` decides states exactly (``CSpace.contains``; touching is a
collision) and ``CSpaceMotionValidator`` decides motions exactly (``CSpace.segment_free``: no
sampling resolution, a thin wall cannot be stepped over). Everything else is plain OMPL.

Run: ``python examples/own_ompl_setup.py``
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
from ompl import base as ob, geometric as og, util as ou

import cspace
from cspace.planning.ompl_plugin import CSpaceMotionValidator, CSpaceValidityChecker, state_space

ROOT = Path(__file__).resolve().parents[1]


def main() -> int:
    ou.setLogLevel(ou.LOG_WARN)
    ou.RNG.setSeed(7)  # before any OMPL object draws random numbers: reproducible runs
    scene = cspace.load_scene(ROOT / "scenes" / "comb.toml")
    cs = cspace.CSpace.from_scene(scene)  # exact C-obstacles of the bodies the robot can reach

    space = state_space(scene.bounds)  # RealVectorStateSpace(3) with the scene's bounds
    ss = og.SimpleSetup(space)
    si = ss.getSpaceInformation()
    checker = CSpaceValidityChecker(si, cs, bounds=scene.bounds)
    motion = CSpaceMotionValidator(si, cs, checker)
    ss.setStateValidityChecker(checker)
    si.setMotionValidator(motion)  # keep `motion` referenced while OMPL uses it

    start, goal = space.allocState(), space.allocState()
    start[0:3] = scene.start.tolist()
    goal[0:3] = scene.goal.tolist()
    ss.setStartAndGoalStates(start, goal)
    ss.setPlanner(og.RRTConnect(si))
    status = ss.solve(2.0)
    print(f"status: {status.asString()}; {checker.calls} state checks, {motion.calls} motion checks")
    if status.getStatus() != ob.PlannerStatus.EXACT_SOLUTION:
        return 1
    ss.simplifySolution(0.5)
    path = np.array([[s[0], s[1], s[2]] for s in ss.getSolutionPath().getStates()])
    # Our own re-check, exact: every waypoint free, every straight segment free.
    free = bool((~cs.contains(path)).all() and cs.segment_free(path[:-1], path[1:]).all())
    print(f"{len(path)} waypoints from {path[0].tolist()} to {path[-1].tolist()}; "
          f"exactly collision-free: {free}")
    return 0 if free else 1


if __name__ == "__main__":
    raise SystemExit(main())
