"""The turning stage of ``plan(..., planner='auto')``: SE(3) sampling, then passages at fixed
orientations, within one budget.

:func:`plan_turning_se3` runs, until one solves: :func:`cspace.planning.se3.plan.plan_se3`
(RRTConnect in SE(3), certified motions; most problems OMPL.app's planner solves are solved
here) for :data:`SE3_FIRST` of the budget, at most :data:`SE3_FIRST_CAP` seconds; :func:`cspace.planning.se3.bridge.slice_bridge`
(a passage taken at one orientation, which sampling rarely hits) for :data:`BRIDGE` of what is
left; then ``plan_se3`` again with the rest. Each attempt is appended to ``tried``.
"""

from __future__ import annotations

import time as _time

import numpy as np

from ..solve import PlanResult
from .bridge import slice_bridge
from .clearance import PoseClearance
from .plan import plan_se3

__all__ = ["plan_turning_se3", "SE3_FIRST", "SE3_FIRST_CAP", "BRIDGE"]

#: The first SE(3) sampling attempt's share of the turning stage's budget, and its cap in
#: seconds (OMPL.app's own problems that it solves take it seconds; the bridge comes next).
SE3_FIRST = 0.4
SE3_FIRST_CAP = 10.0
#: The bridge's share of what the first attempt leaves.
BRIDGE = 0.6


def plan_turning_se3(scene, *, time: float, seed=None, bounds=None, cache=None, memory=None,
                     tried: list | None = None, planner_range=None, skip=()) -> PlanResult:
    """The certified SE(3) path of the first attempt that solves (module docstring), else the
    last attempt's unsolved result. ``skip``: relative orientations whose translations were
    already decided (not bridged again)."""
    t0 = _time.perf_counter()
    tried = tried if tried is not None else []
    b = np.asarray(scene.bounds if bounds is None else bounds, dtype=np.float64).reshape(2, 3)
    poses = PoseClearance(scene, b)
    r = None
    for stage in ("se3", "bridge", "se3"):
        left = time - (_time.perf_counter() - t0)
        if left <= 0:
            break
        budget = (min(SE3_FIRST * left, SE3_FIRST_CAP) if stage == "se3" and not tried_se3(tried)
                  else BRIDGE * left if stage == "bridge" else left)
        ts = _time.perf_counter()
        if stage == "se3":
            r = plan_se3(scene, time=budget, seed=seed, bounds=b, poses=poses,
                         planner_range=planner_range)
            tried.append({"planner": "RRTConnect", "sampler": "uniform", "slices": None,
                          "space": "SE3", "time": budget, "seconds": r.time,
                          "solved": r.solved})
        else:
            found = slice_bridge(scene, time=budget, seed=seed, bounds=b, cache=cache,
                                 memory=memory, poses=poses, skip=skip)
            tried.append({"planner": "bridge", "sampler": None, "slices": None,
                          "space": "SE3", "time": budget,
                          "seconds": _time.perf_counter() - ts, "solved": found is not None})
            r = found if found is not None else r
        if r is not None and r.solved:
            break
    return r


def tried_se3(tried: list) -> bool:
    """Whether an SE(3) sampling attempt is already in ``tried``."""
    return any(t.get("space") == "SE3" and t["planner"] != "bridge" for t in tried)
