"""OMPL benchmark logs of a scene: OMPL's own ``Benchmark`` with cspace's certified checks.

:func:`benchmark` runs every planner named, ``runs`` times each, within ``time`` seconds per
run, through ``ompl.tools.Benchmark`` on an ``SE3StateSpace`` whose poses are decided by
:class:`cspace.planning.se3.clearance.PoseClearance` and whose motions are certified by
clearance (:func:`cspace.planning.se3.plan.plan_se3`'s checker and motion validator). The log
is OMPL's own format: ``ompl_benchmark_statistics LOG -d results.db`` reads it into OMPL's
benchmark database, which Planner Arena (plannerarena.org) plots. With ``sampled=True`` a second
log holds the same planners on OMPL.app's way (FCL at each pose, motions checked every
``resolution`` of the space's extent: nothing proved between; :func:`cspace.planning.sampled.plan_sampled`),
for a comparison in the same database.
"""

from __future__ import annotations

import os
from pathlib import Path

import numpy as np

from ..errors import InvalidArgumentError
from .ompl_plugin import _bounds, _box_bounds, _ompl, planner_names
from .solve import _seed

__all__ = ["benchmark"]


def benchmark(scene, out, *, planners=("RRTConnect",), runs: int = 10, time: float = 10.0,
              memory_mb: float = 4096.0, seed: int | None = None, sampled: bool = False,
              resolution: float = 0.01, name: str | None = None) -> dict:
    """Benchmark OMPL planners on a scene with certified checks, into OMPL's log format.

    Parameters
    ----------
    scene : Scene
        The problem: the robot may turn (SE(3)); the goal's orientation is the scene's.
    out : str or os.PathLike
        The ``.log`` file to write (with ``sampled``, also ``<stem>-sampled.log``).
    planners : sequence of str
        Geometric planners bound in ``ompl.geometric`` (:func:`planner_names`).
    runs : int
        Runs per planner.
    time : float
        Seconds per run (OMPL's ``maxTime``).
    memory_mb : float
        OMPL's ``maxMem`` per run, megabytes.
    seed : int, optional
        OMPL's global seed, before the planners are made.
    sampled : bool
        Also run OMPL.app's way (FCL poses, discrete motions) into a second log.
    resolution : float
        The sampled run's motion-check resolution (OMPL.app's default 1% of the extent).
    name : str, optional
        The experiments' stem; default the scene's (spaces become dashes: OMPL's statistics
        script reads a name up to its first space). The experiments are ``<name>.certified``
        and ``<name>.sampled``.

    Returns
    -------
    dict
        ``{"certified": Path, "sampled": Path or None}``: the logs written.
    """
    out = Path(os.fspath(out))
    if out.suffix != ".log":
        raise InvalidArgumentError(f"benchmark log '{out}': expected a .log file")
    names = planner_names()
    for p in planners:
        if p not in names:
            raise InvalidArgumentError(f"{p!r} is not a valid planner, must be one of "
                                       f"{', '.join(sorted(names))}")
    if not (runs >= 1 and time > 0 and memory_mb > 0):
        raise InvalidArgumentError("runs must be at least 1, time and memory positive")
    name = "-".join((name or scene.name).split()) or "scene"
    logs = {"certified": _run(scene, out, planners, runs, time, memory_mb, seed,
                              f"{name}.certified", sampled=False, resolution=resolution),
            "sampled": None}
    if sampled:
        logs["sampled"] = _run(scene, out.with_name(f"{out.stem}-sampled.log"), planners,
                               runs, time, memory_mb, seed, f"{name}.sampled",
                               sampled=True, resolution=resolution)
    return logs


def _run(scene, out: Path, planners, runs, time, memory_mb, seed, experiment, *, sampled,
         resolution) -> Path:
    from ompl import tools as ot

    from ..output import write_atomic

    ob, og, ou = _ompl()
    b = _bounds(scene.bounds)
    space = ob.SE3StateSpace()
    space.setBounds(_box_bounds(ob, b[0], b[1]))
    ss = og.SimpleSetup(space)
    si = ss.getSpaceInformation()
    keep = []  # Python objects OMPL holds: alive until the benchmark is written
    if sampled:
        from ..check.cross_check import PoseCollider
        from .se3.clearance import quaternion_matrix

        collider = PoseCollider(scene)
        lo, hi = b[0], b[1]

        def valid(state) -> bool:
            r = state.rotation()
            q = np.array((state.getX(), state.getY(), state.getZ()))
            if not ((lo <= q) & (q <= hi)).all():
                return False
            R = quaternion_matrix(np.array((r.x, r.y, r.z, r.w)))
            return not bool(collider.collides(R[None], q[None])[0])

        ss.setStateValidityChecker(valid)
        si.setStateValidityCheckingResolution(float(resolution))
        keep.append(valid)
    else:
        from .se3.clearance import PoseClearance
        from .se3.plan import _classes

        poses = PoseClearance(scene, b)
        classes = _classes()
        checker = classes["PoseValidityChecker"](si, poses)
        motion = classes["CertifiedMotionValidator"](si, poses)
        ss.setStateValidityChecker(checker)
        si.setMotionValidator(motion)
        keep += [poses, checker, motion]
    from .se3.plan import _fill, relative_goal

    start, goal = space.allocState(), space.allocState()
    _fill(scene.start, (0.0, 0.0, 0.0, 1.0))(start)
    _fill(scene.goal, relative_goal(scene))(goal)
    ss.setStartAndGoalStates(start, goal)
    _seed(ou, seed)
    bench = ot.Benchmark(ss, experiment)
    for p in planners:
        bench.addPlanner(getattr(og, p)(si))
    req = ot.Request()
    req.maxTime, req.maxMem, req.runCount = float(time), float(memory_mb), int(runs)
    # OMPL would also write each run's console output to ompl_<host>_<time>.console files
    # in the current folder: not asked for, not written
    req.displayProgress = req.saveConsoleOutput = False
    bench.benchmark(req)
    write_atomic(out, lambda tmp: bench.saveResultsToFile(str(tmp)))
    del keep
    return out
