"""The turning stage of ``plan(..., planner='auto')``: SE(3) sampling and passages at fixed
orientations, within one budget.

:func:`plan_turning_se3` runs, until one solves:

1. :func:`cspace.planning.se3.bridge.slice_bridge` for :data:`BRIDGE_FIRST` of the budget,
   at most :data:`BRIDGE_FIRST_CAP` seconds (a plate through a slot on edge, a T through a
   slot at the goal's orientation: found in a second, where sampling takes tens of seconds
   or more);
2. :func:`cspace.planning.se3.plan.plan_se3` (RRTConnect in SE(3), certified motions, its
   step a quarter of the robot's reach; the problems OMPL.app's planner solves are solved
   here) for :data:`SE3_FIRST` of what is left;
3. a tunnel along the path of the ball inside the robot (that ball's translation decision,
   :func:`cspace.planning.se3.ball.ball_decision`, for :data:`BALL` of what is left, at most
   :data:`BALL_CAP` seconds, unless the caller has its path; then
   :func:`cspace.planning.se3.tunnel.tunnel_path` for :data:`TUNNEL` of what is left: a stick
   leaves the Parasol bug trap only along its tunnel);
4. the bridge again for :data:`BRIDGE` of what is left (the orientations it has not decided);
5. ``plan_se3`` again with the rest, its step :data:`SECOND_RANGE` of the reach (another
   search, with shorter steps: on ``benchmarks/bench_se3.py``'s problems each of the two
   steps was the faster one on some problem and seed).

Each attempt is appended to ``tried``.
"""

from __future__ import annotations

import time as _time

import numpy as np

from ..solve import PlanResult
from .bridge import slice_bridge
from .clearance import PoseClearance
from .plan import plan_se3
from .tunnel import tunnel_path

__all__ = ["plan_turning_se3", "BRIDGE_FIRST", "BRIDGE_FIRST_CAP", "SE3_FIRST", "BRIDGE",
           "SECOND_RANGE", "BALL", "BALL_CAP", "TUNNEL"]

#: The quick bridge's share of the turning stage's budget, and its cap in seconds (the plate
#: turned and moved to (250, 150, -300) of ``benchmarks/bench_se3.py`` needs about 4.5 s of
#: it: with 3 s its passage waited for the second bridge, after 18 s of sampling).
BRIDGE_FIRST = 0.1
BRIDGE_FIRST_CAP = 5.0
#: The first SE(3) sampling attempt's share of what is left.
SE3_FIRST = 0.4
#: The bridge's share of what the first SE(3) attempt leaves.
BRIDGE = 0.6
#: The inscribed ball's decision before the tunnel: its share of what is left and its cap in
#: seconds (the bug trap's ball finds its path in 5-7 s).
BALL = 0.25
BALL_CAP = 8.0
#: The tunnel's share of what is left after the ball's decision.
TUNNEL = 0.5
#: The second SE(3) attempt's step, in units of the robot's reach (the first's is
#: :data:`cspace.planning.se3.plan.RANGE`).
SECOND_RANGE = 0.1


def plan_turning_se3(scene, *, time: float, seed=None, bounds=None, cache=None, memory=None,
                     tried: list | None = None, planner_range=None, skip=(), poses=None,
                     guide=None) -> PlanResult:
    """The certified SE(3) path of the first attempt that solves (module docstring), else an
    SE(3) attempt's unsolved result (one of a millisecond when the budget left none). ``skip``: relative orientations whose translations
    were already decided (not bridged again); ``poses``: the scene's
    :class:`~cspace.planning.se3.clearance.PoseClearance` in these bounds, when the caller has
    one; ``guide``: the ball's path, when the caller has decided it."""
    t0 = _time.perf_counter()
    tried = tried if tried is not None else []
    b = np.asarray(scene.bounds if bounds is None else bounds, dtype=np.float64).reshape(2, 3)
    poses = poses if poses is not None else PoseClearance(scene, b)
    done = set()  # orientations the bridge has decided
    r = None
    stages = ["bridge", "se3", "tunnel", "bridge", "se3"]
    for n, stage in enumerate(stages):
        left = time - (_time.perf_counter() - t0)
        if left <= 0:
            break
        if stage == "bridge":
            budget = (min(BRIDGE_FIRST * left, BRIDGE_FIRST_CAP) if n == 0
                      else BRIDGE * left)
        else:
            budget = SE3_FIRST * left if "se3" in stages[n + 1:] else left
        ts = _time.perf_counter()
        if stage == "tunnel":
            if guide is None:
                from .ball import ball_decision

                budget = min(BALL * left, BALL_CAP)
                ball = ball_decision(scene, time=budget, bounds=b, cache=cache, memory=memory)
                tried.append({"planner": "decide", "sampler": None, "slices": None,
                              "robot": "inscribed ball", "time": budget,
                              "answer": ball.answer if ball is not None else "unknown",
                              "seconds": _time.perf_counter() - ts, "solved": False})
                guide = ball.path if ball is not None and ball.answer == "path" else None
            left = time - (_time.perf_counter() - t0)
            if guide is None or left <= 0:
                continue
            ts = _time.perf_counter()
            found = tunnel_path(scene, time=TUNNEL * left, guide=guide, seed=seed, bounds=b,
                                poses=poses)
            tried.append({"planner": "tunnel", "sampler": None, "slices": None, "space": "SE3",
                          "time": TUNNEL * left, "seconds": _time.perf_counter() - ts,
                          "solved": found is not None})
            r = found if found is not None else r
        elif stage == "se3":
            second = "se3" in stages[:n]
            step = (planner_range if planner_range is not None
                    else SECOND_RANGE * poses.rho if second else None)
            r = plan_se3(scene, time=budget, seed=seed,
                         bounds=b, poses=poses, planner_range=step)
            tried.append({"planner": "RRTConnect", "sampler": "uniform", "slices": None,
                          "space": "SE3", "time": budget, "seconds": r.time,
                          "solved": r.solved})
        else:
            found = slice_bridge(scene, time=budget, seed=seed, bounds=b, cache=cache,
                                 memory=memory, poses=poses, skip=skip, done=done)
            tried.append({"planner": "bridge", "sampler": None, "slices": None,
                          "space": "SE3", "time": budget,
                          "seconds": _time.perf_counter() - ts, "solved": found is not None})
            r = found if found is not None else r
        if r is not None and r.solved:
            break
    if r is None:
        # The budget ran out before any SE(3) attempt (a tiny --time): one that returns at
        # once, so the caller always has a result (unsolved) that names SE(3).
        ts = _time.perf_counter()
        r = plan_se3(scene, time=1e-3, seed=seed, bounds=b, poses=poses,
                     planner_range=planner_range)
        tried.append({"planner": "RRTConnect", "sampler": "uniform", "slices": None,
                      "space": "SE3", "time": 1e-3, "seconds": _time.perf_counter() - ts,
                      "solved": r.solved})
    return r
