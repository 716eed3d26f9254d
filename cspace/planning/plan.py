"""Planning: OMPL planners over the exact C-space, with and without turns.

:func:`plan` (a fixed orientation) and :func:`plan_turning` (orientation slices joined by
certified turns, :mod:`cspace.planning.turning`) return a :class:`PlanResult`: the path, whether
it was solved, certified, and the timings (as does :func:`cspace.planning.sampled.plan_sampled`,
OMPL.app's way, for comparison). The OMPL glue (spaces, checkers, samplers) is :mod:`cspace.planning.ompl_plugin`.
"""

from __future__ import annotations

import time as _time
from dataclasses import replace

import numpy as np

from ..errors import ArgumentTypeError, InvalidArgumentError
from ..scene.model import CSpace
from .decide import decide
from .solve import PlanResult, _seed, _solve
from .ompl_plugin import (
    _bounds,
    _box_bounds,
    _classes,
    _in_bounds,
    _ompl,
    _pool_sampler,
    _vec,
    narrow_passage_samples,
    planner_names,
    state_space,
    verify_path,
)

__all__ = [
    "MOTIONS",
    "DEFAULT_TIME",
    "plan_turning",
    "default_slices",
    "PlanResult",
    "plan",
    "SAMPLERS",
]


MOTIONS = ("exact", "discrete")


SAMPLERS = ("uniform", "narrow")


# With turns, when start and goal share an orientation: the share of the time budget spent
# first on translations alone at that orientation (plan_turning).
FIRST_SHARE = 0.1


# --------------------------------------------------------------------------------------
# planning


def _as_cspace(scene_or_cspace, cache=None, robot_hull: bool = False, memory=None):
    if isinstance(scene_or_cspace, CSpace):
        return scene_or_cspace, None
    if hasattr(scene_or_cspace, "obstacles") and hasattr(scene_or_cspace, "robot"):
        return (CSpace.from_scene(scene_or_cspace, cache=cache, robot_hull=robot_hull,
                                  memory=memory),
                scene_or_cspace)
    raise ArgumentTypeError(f"expected a Scene or a CSpace, got {type(scene_or_cspace).__name__}")


def _endpoint(cspace: CSpace, q, b: np.ndarray, what: str) -> np.ndarray:
    if q is None:
        raise InvalidArgumentError(f"{what} is required when planning on a CSpace (no scene to take it from)")
    a = np.array(q, dtype=np.float64)
    if a.shape != (3,) or not np.isfinite(a).all():
        raise InvalidArgumentError(f"{what} must be a finite (3,) translation, got {np.asarray(q).tolist()}")
    if not _in_bounds(a, b)[0]:
        raise InvalidArgumentError(f"{what} {a.tolist()} is outside the bounds {b.tolist()}")
    # The C-space decides (a lazy one builds what the point meets); then name the culprits
    if cspace.contains(a):
        hits = [i for i, o in enumerate(cspace.obstacles) if o.contains(a)]
        names = []
        for i in hits:
            o = cspace.obstacles[i].obstacle
            names.append(repr(getattr(o, "name", None) or f"#{i}"))
        raise InvalidArgumentError(
            f"{what} {a.tolist()} is in collision (in the closed C-obstacle of "
            f"{', '.join(names)}; touching counts)"
        )
    return a


#: The default planning budget of :func:`plan` and ``cspace plan --time`` (seconds): enough
#: for the auto planner's proofs of "no path" on a loaded machine (the shipped cage is proved
#: in about 1.4 s unloaded; ``tests/test_plan_auto.py`` runs it beside spinning processes).
DEFAULT_TIME = 10.0


def plan(scene_or_cspace, start=None, goal=None, *, planner: str | None = None,
         time: float = DEFAULT_TIME, seed: int | None = None, simplify: bool = True, bounds=None,
         motion: str = "exact", resolution: float = 0.01, optimize: bool = False,
         planner_range: float | None = None, cache=None,
         sampler: str = "uniform", robot_hull: bool = False, slices=None,
         memory=None, turns: bool = True) -> PlanResult:
    """Plan a collision-free translation with OMPL, checked exactly; with ``slices``, a
    path that also turns the robot, every motion certified.

    Parameters
    ----------
    scene_or_cspace : Scene or CSpace
        A scene (its C-obstacles are modelled and built by :meth:`CSpace.from_scene`;
        start, goal and bounds default to the scene's) or a built :class:`CSpace`.
    start, goal : (3,) float64, optional
        Reference-point translations; required for a CSpace.
    planner : str, optional
        A geometric planner bound in ``ompl.geometric`` (:func:`planner_names`), or
        ``'auto'``. Default: ``'auto'`` (as ``cspace plan``), or RRTConnect when an option
        only a named planner takes is given (``slices``, ``sampler``, ``motion='discrete'``,
        ``optimize``). ``'auto'``: RRTConnect, the
        decision by certified cells, then (a scene, ``turns``) the robot turns while it
        moves, in SE(3), every motion certified (without turns: PRM with the narrow-passage
        sampler), each within its share of ``time`` (:data:`AUTO_SHARES`), until one
        solves; ``PlanResult.tried`` lists the attempts (:func:`_plan_auto`).
    time : float, default :data:`DEFAULT_TIME` (10 s, as ``cspace plan``)
        Seconds for ``solve()`` (simplification gets ``min(1, time / 2)`` more). The auto
        planner stops at the first answer (a path or a proof): most problems take far less.
    seed : int, optional
        ``ompl.util.RNG.setSeed(seed)`` before building the planner. Runs are then
        reproducible for the same inputs and call order in a process (OMPL derives every
        RNG from one global seed generator and logs an error if it already handed out seeds).
    simplify : bool, default True
        ``og.PathSimplifier.simplify`` (shortcutting; never B-spline smoothing).
    bounds : (2, 3) float64, optional
        Default the scene's bounds, else ``cspace.bounds``.
    motion : {'exact', 'discrete'}, default 'exact'
        ``'exact'`` installs :class:`CSpaceMotionValidator`; ``'discrete'`` keeps OMPL's
        default discrete motion validator (states checked every ``resolution`` times the
        space's maximum extent) — it can miss thin obstacles (for comparison only).
    resolution : float, default 0.01
        ``si.setStateValidityCheckingResolution`` for ``motion='discrete'``.
    optimize : bool, default False
        For optimizing planners (RRTstar, BITstar, ...): use the whole ``time`` to improve
        path length. If False, the objective's cost threshold is infinite, so they stop at
        the first solution.
    planner_range : float, optional
        ``planner.setRange`` for planners that have it.
    cache : COCache, path, True, or None
        For a scene: the disk cache its C-obstacles are built through
        (:func:`cspace.scene.model.model_scene`); None: no cache.
    sampler : {'uniform', 'narrow'}, default 'uniform'
        The valid-state sampler of planners that draw valid states (PRM, PRMstar, ...):
        OMPL's uniform one, or ``'narrow'``: half the samples from
        :func:`narrow_passage_samples` (computed once, exact), half uniform. Planners that
        sample unchecked states (RRT, RRTConnect, ...) ignore it.
    robot_hull : bool, default False
        For a scene: build against the robot's convex hull instead of its exact parts.
    slices : int or cspace.planning.orientations.Slices, optional
        Plan with turns (a scene only): over these orientation slices (an int ``n``: ``n``
        equal steps about the axis of the scene's goal rotation relative to its start, z
        when they are equal, plus the goal's angle). See :func:`plan_turning`.
    memory : int or str, optional
        Memory budget of the build (bytes or a size such as ``"6G"``; default
        ``$CSPACE_MEMORY``, else half of what is available: :mod:`cspace.memory`). Over it,
        :class:`~cspace.errors.MemoryBudgetError` before anything is built; with turns, one
        budget for all the slices built.
    turns : bool, default True
        With ``planner='auto'`` on a scene: whether it may turn the robot (in SE(3)) when
        translations at the start's orientation find no path, or at once when the goal's
        orientation differs from the start's (False: the start's orientation only, the
        goal's ignored).

    Returns
    -------
    PlanResult
        ``path`` is re-proved exactly (:func:`verify_path`) after OMPL returns it; ``solved``
        requires an exact OMPL solution and a valid path. With ``slices``: also
        ``slices``, ``orientations`` and ``built``.

    Raises
    ------
    ValueError
        Unknown planner or motion (the message lists the choices); start or goal outside the
        bounds or in collision (the message says which and which obstacle).
    """
    ob, og, ou = _ompl()
    names = planner_names()
    if planner is None:  # auto, unless the options ask for a planner of their own
        named = sampler != "uniform" or slices is not None or motion != "exact" or optimize
        planner = "RRTConnect" if named else AUTO
    if planner == AUTO:
        if sampler != "uniform" or slices is not None or motion != "exact" or optimize:
            raise InvalidArgumentError("planner='auto' chooses the sampler and the slices "
                                       "itself; give a planner to choose them")
        return _plan_auto(scene_or_cspace, start, goal, time=time, seed=seed,
                          simplify=simplify, bounds=bounds, cache=cache,
                          robot_hull=robot_hull, memory=memory, turns=turns,
                          planner_range=planner_range)
    if planner not in names:
        raise InvalidArgumentError(f"{planner!r} is not a valid planner, must be one of {', '.join(names)}")
    if sampler not in SAMPLERS:
        raise InvalidArgumentError(f"{sampler!r} is not a valid sampler, must be one of "
                         f"{', '.join(SAMPLERS)}")
    if motion not in MOTIONS:
        raise InvalidArgumentError(f"{motion!r} is not a valid motion, must be one of {', '.join(MOTIONS)}")
    if not (time > 0):
        raise InvalidArgumentError(f"time must be positive, got {time}")
    if slices is not None:
        if motion != "exact" or sampler != "uniform":
            raise InvalidArgumentError("planning with turns takes motion='exact' and "
                                       "sampler='uniform' only")
        return plan_turning(scene_or_cspace, slices, start, goal, planner=planner, time=time,
                            seed=seed, simplify=simplify, bounds=bounds, optimize=optimize,
                            planner_range=planner_range, cache=cache, robot_hull=robot_hull,
                            memory=memory)
    cs, scene = _as_cspace(scene_or_cspace, cache, robot_hull, memory)
    if bounds is None:
        bounds = scene.bounds if scene is not None else cs.bounds
    b = _bounds(bounds)
    if scene is not None:
        start = scene.start if start is None else start
        goal = scene.goal if goal is None else goal
    q0 = _endpoint(cs, start, b, "start")
    q1 = _endpoint(cs, goal, b, "goal")

    _seed(ou, seed)
    space = state_space(b)
    si = ob.SpaceInformation(space)
    classes = _classes()
    checker = classes["CSpaceValidityChecker"](si, cs, bounds=b)
    si.setStateValidityChecker(checker)
    mv = None
    if motion == "exact":
        mv = classes["CSpaceMotionValidator"](si, cs, checker)
        si.setMotionValidator(mv)  # keep the Python reference (mv) alive until the end
    else:
        si.setStateValidityCheckingResolution(float(resolution))
    samplers = []  # keep the Python samplers alive while OMPL uses them
    if sampler == "narrow":
        pool = narrow_passage_samples(cs, b, seed=seed)

        def allocate(si_):
            stream = None if seed is None else seed + len(samplers)
            samplers.append(_pool_sampler(si_, pool, stream))
            return samplers[-1]

        si.setValidStateSamplerAllocator(allocate)
    si.setup()

    t0 = _time.perf_counter()
    status, exact, raw, P, solve_time = _solve(
        si, q0.tolist(), q1.tolist(), planner=planner, time=time, optimize=optimize,
        planner_range=planner_range, simplify=simplify, read=_vec, dim=3)
    P = raw if P is None else P
    simplified = P is not raw
    valid = False
    if len(P):
        valid = verify_path(cs, P, b)["valid"]
        if simplified and not valid:
            # Keep the planner's own path if shortcutting produced something we cannot prove.
            raw_valid = verify_path(cs, raw, b)["valid"]
            if raw_valid:
                P, valid, simplified = raw, True, False
    elapsed = _time.perf_counter() - t0
    return PlanResult(
        path=np.ascontiguousarray(P, dtype=np.float64).reshape(-1, 3),
        solved=bool(exact and valid),
        exact=bool(exact),
        valid=bool(valid),
        planner=planner,
        motion=motion,
        time=elapsed,
        solve_time=solve_time,
        n_states=int(len(P)),
        status=status.asString(),
        state_checks=int(checker.calls),
        motion_checks=int(mv.calls) if mv is not None else 0,
        simplified=simplified,
    )


# --------------------------------------------------------------------------------------
# planner='auto': a schedule of attempts within one budget

AUTO = "auto"
#: ``planner='auto'``: each attempt at the start's orientation, its share of the budget and
#: its cap in seconds (turns get what is left). ``'decide'``:
#: :func:`cspace.planning.decide.decide` (a path through free cells, a proof that none
#: exists, or unknown: then the planners go on).
AUTO_SHARES = (("RRTConnect", "uniform", 0.05, 0.5), ("decide", None, 0.2, 2.0),
               ("PRM", "narrow", 0.3, 3.0))
#: ``planner='auto'`` with translations only (``turns=False``, or a C-space without its
#: scene): the decision's share of the budget, uncapped. Only PRM comes after it, and a proof
#: may need most of the time (the Parasol bug trap's: about 7 s of ``--time 10``).
AUTO_DECIDE_ALONE = 0.85
#: ``planner='auto'``: when the start's orientation has no path, the share of what is left for
#: the proof over all orientations by the ball inside the robot
#: (:func:`cspace.planning.se3.ball.no_path_at_any_orientation`) before turning, and its cap
#: in seconds (the cage's and the bottle's take a fraction of a second; where the ball's
#: answer is "unknown", as on the turned plate of ``benchmarks/bench_se3.py``, the seconds are
#: lost to the turning stage).
AUTO_BALL = 0.25
AUTO_BALL_CAP = 3.0
#: ``planner='auto'`` on a scene whose robot may turn: after the first translation attempt,
#: RRTConnect in SE(3) (certified motions) gets this share of the budget, at most this many
#: seconds, before the decisions: a passage that needs a turn (a twisting corridor, the
#: alpha puzzle's easier seeds) is often found in a second or two, where the decisions and the
#: fixed-orientation passages before it took some 7 s of a 30 s budget on the twisting corners
#: of ``benchmarks/bench_se3.py``.
AUTO_SE3_QUICK = 0.1
AUTO_SE3_QUICK_CAP = 3.0


def _plan_auto(scene_or_cspace, start, goal, *, time: float, seed, simplify: bool, bounds,
               cache, robot_hull: bool, memory, turns: bool, planner_range) -> PlanResult:
    """``plan(..., planner='auto')``: RRTConnect (most problems: milliseconds), on a scene
    whose robot may turn a short RRTConnect in SE(3) (:data:`AUTO_SE3_QUICK`), then the
    decision by certified cells (a path through free cells; or a proof that there is none at
    this orientation, which skips the samplers). Then, on a scene whose robot may turn
    (``turns``): after a proof at the start's orientation, the proof over all orientations
    by the ball inside the robot (:func:`cspace.planning.se3.ball.no_path_at_any_orientation`,
    :data:`AUTO_BALL` of what is left; a proof ends the search: not solved,
    ``decision.answer == 'no path'``, status "No path at any orientation (proved)"); then the
    robot turns while it moves, with the rest of the budget
    (:func:`cspace.planning.se3.stage.plan_turning_se3`: RRTConnect in SE(3) and passages at
    fixed orientations, every motion certified by clearance). A scene whose goal orientation
    differs from the start's goes to that stage at once. Translations only
    (``turns=False``): the decision gets :data:`AUTO_DECIDE_ALONE` of the budget, PRM with
    the narrow-passage sampler the rest (and the decision again what is left, when it is more
    than the first one had). Stops at the first solution; every answer is certified as
    :func:`plan`'s (:func:`plan_se3`'s for a turning path)."""
    if not (time > 0):
        raise InvalidArgumentError(f"time must be positive, got {time}")
    cs, scene = _as_cspace(scene_or_cspace, cache, robot_hull, memory)
    t0 = _time.perf_counter()  # the budget is for planning, as plan()'s: the build is not in it
    scene = scene if scene is not None else cs.scene
    if scene is not None:  # what plan() takes from a scene, for the translation attempts
        start = scene.start if start is None else start
        goal = scene.goal if goal is None else goal
        bounds = scene.bounds if bounds is None else bounds
    tried: list = []
    r = None
    poses = None  # the SE(3) clearance, once made (shared by the SE(3) attempts)
    guide = None  # the path of the ball inside the robot, when decided
    d, d_budget = None, 0.0
    alone = not (turns and scene is not None)  # translations only: no turns to plan after
    # A goal orientation other than the start's: translations at the start's cannot reach it
    # (plan_se3 checks the start and goal poses instead).
    turn_needed = (not alone and not np.array_equal(np.asarray(scene.goal_rotation),
                                                    np.asarray(scene.start_rotation)))
    if not turn_needed:
        q0, q1 = (_endpoint(cs, q, _bounds(bounds if bounds is not None else cs.bounds), w)
                  for q, w in ((start, "start"), (goal, "goal")))
    for n, (planner, sampler, share, cap) in enumerate(AUTO_SHARES):
        if planner == "PRM" and not alone:
            break  # the robot may turn: the SE(3) stages get the time (their bridge decides
            # translations through narrow passages at fixed orientations)
        budget = (AUTO_DECIDE_ALONE * time if planner == "decide" and alone
                  else min(cap, share * time))
        if n:  # the first planner always runs: there is always a path or a status
            budget = min(budget, time - (_time.perf_counter() - t0))
        if budget <= 0 or turn_needed:
            break
        if planner == "decide":
            d, d_budget = decide(cs, q0, q1, bounds=bounds, time=budget), budget
            tried.append({"planner": "decide", "sampler": None, "slices": None, "time": budget,
                          "answer": d.answer, "seconds": d.time, "solved": d.answer == "path"})
            if d.answer == "path":
                r = _decided(cs, d, bounds)
            if d.answer != "unknown":
                break
            continue
        r = plan(cs, start, goal, planner=planner, sampler=sampler, time=budget, seed=seed,
                 simplify=simplify, bounds=bounds, planner_range=planner_range)
        tried.append({"planner": planner, "sampler": sampler, "slices": None, "time": budget,
                      "seconds": r.time, "solved": r.solved})
        if r.solved:
            break
        if n == 0 and not alone:  # the robot may turn: a short SE(3) attempt first
            from .se3.clearance import PoseClearance
            from .se3.plan import plan_se3

            b = _bounds(bounds)
            poses = PoseClearance(scene, b)
            budget = min(AUTO_SE3_QUICK * time, AUTO_SE3_QUICK_CAP,
                         time - (_time.perf_counter() - t0))
            try:
                quick = plan_se3(scene, time=budget, seed=seed, bounds=b, poses=poses,
                                 planner_range=planner_range) if budget > 0 else None
            except InvalidArgumentError:  # an end within the clearance's error bound of an
                quick = None  # obstacle: the translations decide it exactly, as before
            if quick is not None:
                tried.append({"planner": "RRTConnect", "sampler": "uniform", "slices": None,
                              "space": "SE3", "time": budget, "seconds": quick.time,
                              "solved": quick.solved})
                if quick.solved:
                    r = quick
                    break
    left = time - (_time.perf_counter() - t0)
    if (not (r is not None and r.solved) and alone
            and d is not None and d.answer == "unknown" and left > d_budget):
        # Translations only, nothing found, and more time left than the decision had: the rest
        # goes to deciding again (a proof may take minutes: the Parasol bug trap's,
        # benchmarks/reports/planning.md "Long decisions").
        d = decide(cs, q0, q1, bounds=bounds, time=left)
        tried.append({"planner": "decide", "sampler": None, "slices": None, "time": left,
                      "answer": d.answer, "seconds": d.time, "solved": d.answer == "path"})
        if d.answer == "path":
            r = _decided(cs, d, bounds)
    left = time - (_time.perf_counter() - t0)
    if (d is not None and d.answer == "no path" and turns and scene is not None and left > 0):
        # No translation at the start's orientation. The ball inside the robot that no turn
        # changes: if even it cannot pass, nothing can, at any orientation.
        from .se3.ball import ball_decision

        budget = min(AUTO_BALL * left, AUTO_BALL_CAP)
        tb = _time.perf_counter()
        ball = ball_decision(scene, time=budget, bounds=bounds, cache=cache, memory=memory)
        tried.append({"planner": "decide", "sampler": None, "slices": None, "time": budget,
                      "robot": "inscribed ball",
                      "answer": ball.answer if ball is not None else "unknown",
                      "seconds": _time.perf_counter() - tb, "solved": False})
        if ball is not None and ball.answer == "no path":
            return replace(_decided(cs, d, bounds), tried=tried, time=_time.perf_counter() - t0,
                           decision=ball, status="No path at any orientation (proved)")
        if ball is not None and ball.answer == "path":
            guide = ball.path  # the turning stage looks for a tunnel along it
    left = time - (_time.perf_counter() - t0)
    # The turning stage runs with what is left, or (nothing left and nothing tried: a goal
    # turned, a tiny budget) for a millisecond, so there is always a result.
    if not (r is not None and r.solved) and turns and scene is not None and (left > 0 or r is None):
        from .se3.stage import plan_turning_se3

        decided = d is not None and d.answer != "unknown"
        r = plan_turning_se3(scene, time=left, seed=seed, bounds=bounds, cache=cache,
                             memory=memory, tried=tried, planner_range=planner_range,
                             skip=((0.0, 0.0, 0.0, 1.0),) if decided else (), poses=poses,
                             guide=guide)
    if d is not None and d.answer == "no path" and not (r is not None and r.solved):
        r = r if r is not None and r.certified is not None else _decided(cs, d, bounds)
    return replace(r, tried=tried, time=_time.perf_counter() - t0, decision=d)


def _decided(cs, d, bounds) -> PlanResult:
    """A :class:`PlanResult` of a decision alone (its path, re-proved, or none)."""
    P = d.path if d.path is not None else np.zeros((0, 3))
    b = _bounds(bounds if bounds is not None else cs.bounds)
    valid = bool(len(P)) and verify_path(cs, P, b)["valid"]
    status = {"path": "Exact solution",
              "no path": "No path at the start's orientation (proved)"}.get(d.answer, "Unknown")
    return PlanResult(path=P, solved=valid, exact=d.answer == "path", valid=valid,
                      planner="decide", motion="exact", time=d.time, solve_time=d.time,
                      n_states=len(P), status=status, state_checks=0, motion_checks=0,
                      simplified=True)


# --------------------------------------------------------------------------------------
# planning with turns


def default_slices(scene, n: int):
    """``n`` equal orientation steps about the axis of the scene's goal rotation relative to
    its start, plus the goal's angle (:meth:`Slices.about`); about z when the two rotations
    are the same matrix."""
    from scipy.spatial.transform import Rotation

    from .orientations import Slices

    if np.array_equal(scene.goal_rotation, scene.start_rotation):
        return Slices.about(n)
    rel = np.asarray(scene.goal_rotation) @ np.asarray(scene.start_rotation).T
    rv = Rotation.from_matrix(rel).as_rotvec()
    angle = float(np.linalg.norm(rv))
    if angle == 0.0:  # a float product of distinct matrices can still round to the identity
        return Slices.about(n)
    return Slices.about(n, axis=rv / angle, goal_angle=angle)


def plan_turning(scene, slices, start=None, goal=None, *, planner: str = "RRTConnect",
                 time: float = 1.0, seed: int | None = None, simplify: bool = True,
                 bounds=None, optimize: bool = False, planner_range: float | None = None,
                 cache=None, robot_hull: bool = False, executor=None, memory=None) -> PlanResult:
    """Plan translations and turns in place over orientation slices, every motion certified.

    A state is a position and an orientation of the set: for :class:`~cspace.planning.orientations.Slices`
    (turns about one axis) the OMPL state is ``(x, y, z, s)`` with slice ``k`` at
    ``s = k w`` (``w`` the arc a step of ``2 pi / n`` moves the robot's farthest point, so
    turning and translating weigh alike) and ``round(s / w)`` its slice; for
    :class:`~cspace.planning.orientations.Orientations` (free flying) it is an SE(3) state whose rotation
    is snapped to the nearest orientation of the set. A state is valid when the robot at
    that orientation is free there; a motion from ``(q0, k0)`` to ``(q1, k1)`` is the
    translation at ``k0`` followed by the turn in place at ``q1`` through neighbouring
    orientations to ``k1``, valid when each is certified free
    (:meth:`cspace.planning.turning.TurningCSpace.motion_free`). Slices and turns are built when the
    planner first enters them. The returned path is expanded to primitive motions and
    re-proved (:meth:`~cspace.planning.turning.TurningCSpace.verify`).

    When the start and goal share an orientation, translations alone at it are tried first
    (:func:`plan` on that slice, ``FIRST_SHARE`` of ``time``); the turning planner gets the
    rest of the budget only if that finds no path. ``built['start_orientation_only']`` says
    which answered; ``time``, ``solve_time`` and the check counts cover both.

    Parameters are those of :func:`plan` (the start and goal orientations are the scene's);
    ``slices`` is a :class:`~cspace.planning.orientations.Slices`, an
    :class:`~cspace.planning.orientations.Orientations`, or a count (:func:`default_slices`). With an
    ``executor`` (a process pool, a Dask cluster's: :func:`cspace.planning.scale.executor_for`) every
    orientation's C-space is built through it before planning
    (:meth:`~cspace.planning.turning.TurningCSpace.prebuild`), not counted in the planning time;
    turns stay lazy.
    """
    from .orientations import Orientations, Slices
    from .turning import TurningCSpace

    ob, _, ou = _ompl()
    if not (hasattr(scene, "obstacles") and hasattr(scene, "robot")):
        raise ArgumentTypeError(f"planning with turns needs a Scene, got {type(scene).__name__}")
    if not isinstance(slices, (Slices, Orientations)):
        if isinstance(slices, bool) or not isinstance(slices, (int, np.integer)):
            raise ArgumentTypeError("slices must be an int, a Slices or an Orientations, got "
                                    f"{type(slices).__name__}")
        slices = default_slices(scene, int(slices))
    rel_goal = np.asarray(scene.goal_rotation) @ np.asarray(scene.start_rotation).T
    if not np.allclose(slices.rotation(slices.goal), rel_goal, rtol=0.0, atol=1e-9):
        raise InvalidArgumentError("the orientation set's goal is not the scene's goal rotation "
                                   "(relative to its start)")
    b = _bounds(scene.bounds if bounds is None else bounds)
    tcs = TurningCSpace(scene, slices, cache=cache, robot_hull=robot_hull, memory=memory)
    tcs.bounds = b
    if executor is not None:
        tcs.prebuild(executor)
    q0 = np.array(scene.start if start is None else start, dtype=np.float64)
    q1 = np.array(scene.goal if goal is None else goal, dtype=np.float64)
    for what, q, k in (("start", q0, 0), ("goal", q1, slices.goal)):
        if q.shape != (3,) or not np.isfinite(q).all() or not tcs.in_bounds(q):
            raise InvalidArgumentError(f"{what} {q.tolist()} is not a finite point inside the "
                                       f"bounds {b.tolist()}")
        if not tcs.state_free(q, k):
            raise InvalidArgumentError(f"{what} {q.tolist()} is in collision at its orientation "
                                       f"({slices.label(k)}; touching counts)")
    first = None
    t_plan = _time.perf_counter()
    if slices.goal == 0:
        # Start and goal share an orientation: try translations alone at it first, with a
        # share of the budget. A planner over every orientation spends most of its samples
        # on orientations the path may not need (the apartment: 1 of 2 seeds solved in 60 s
        # over 64 orientations, 2 of 2 in 0.5 s at the start orientation).
        first = plan(tcs.slice(0), q0, q1, planner=planner, time=FIRST_SHARE * time,
                     seed=seed, simplify=simplify, bounds=b, optimize=optimize,
                     planner_range=planner_range)
        if first.solved:
            wp = [(q, 0) for q in first.path]
            return _turning_result(tcs, first, wp, solved=True,
                                   elapsed=_time.perf_counter() - t_plan, first=True)
        time = max(time - (_time.perf_counter() - t_plan), 1e-3)
    space, start_state, goal_state, position, orientation_of = (
        _yaw_space if isinstance(slices, Slices) else _flying_space)(scene, slices, b, q0, q1)
    classes = _turning_classes()
    _seed(ou, seed)
    si = ob.SpaceInformation(space)
    checker = classes["checker"](si, tcs, position, orientation_of)
    si.setStateValidityChecker(checker)
    mv = classes["motion"](si, tcs, position, orientation_of)
    si.setMotionValidator(mv)
    si.setup()

    def read(state) -> np.ndarray:
        return np.array([*position(state), orientation_of(state)], dtype=np.float64)

    status, exact, raw, simp, solve_time = _solve(
        si, start_state, goal_state, planner=planner, time=time, optimize=optimize,
        planner_range=planner_range, simplify=simplify, read=read, dim=4)

    chosen, valid, simplified = [], False, False
    for P, is_simplified in ((simp, True), (raw, False)):
        if P is None or not len(P):
            continue
        wp = tcs.expand([(p[:3], int(p[3])) for p in P])
        if tcs.verify(wp):
            chosen, valid, simplified = wp, True, is_simplified
            break
        if not chosen:
            chosen = wp
    elapsed = _time.perf_counter() - t_plan
    solved = bool(exact and valid and chosen and np.array_equal(chosen[-1][0], q1)
                  and chosen[-1][1] == slices.goal)
    before = (first.solve_time, first.state_checks, first.motion_checks) if first else (0, 0, 0)
    result = PlanResult(
        path=np.zeros((0, 3)), solved=solved, exact=bool(exact), valid=bool(valid),
        planner=planner, motion="exact", time=elapsed, solve_time=before[0] + solve_time,
        n_states=len(chosen), status=status.asString(),
        state_checks=before[1] + int(checker.calls),
        motion_checks=before[2] + int(mv.calls), simplified=simplified)
    return _turning_result(tcs, result, chosen, solved=solved, elapsed=elapsed,
                           first=False if first is not None else None)


def _turning_result(tcs, result: PlanResult, waypoints, *, solved: bool, elapsed: float,
                    first) -> PlanResult:
    """``result`` with the turning robot's waypoints ``[(q, k), ...]``: path, slices,
    orientations and what was built (``first``: whether the path came from the start
    orientation alone; None when that was not tried)."""
    import dataclasses

    from .orientations import Slices

    slices = tcs.slices
    n = len(slices)
    ks = np.array([k for _, k in waypoints], dtype=np.int64)
    links = n if isinstance(slices, Slices) else sum(map(len, slices.links)) // 2
    built = {"slices": len(tcs.built_slices), "turns": len(tcs.built_turns), "of": (n, links)}
    if first is not None:
        built["start_orientation_only"] = bool(first)
    return dataclasses.replace(
        result,
        path=np.array([q for q, _ in waypoints], dtype=np.float64).reshape(-1, 3),
        solved=solved, time=elapsed, n_states=len(waypoints), slices=ks,
        orientations=tcs.orientations(ks) if len(ks) else np.zeros((0, 4)), built=built)


def _yaw_space(scene, slices, b: np.ndarray, q0: np.ndarray, q1: np.ndarray):
    """``(x, y, z, s)`` over turns about one axis: the space, start and goal coordinates,
    and readers of a state's position and slice."""
    ob = _ompl()[0]
    n = len(slices)
    reach = float(np.linalg.norm(scene.robot.vertices - scene.reference_point, axis=1).max())
    w = max(reach, 1e-9 * float(np.ptp(b, axis=0).max())) * 2 * np.pi / n
    space = ob.RealVectorStateSpace(4)
    space.setBounds(_box_bounds(ob, [*b[0], -0.5 * w], [*b[1], (n - 0.5) * w]))

    def position(state) -> tuple:
        return (state[0], state[1], state[2])

    def slice_of(state) -> int:
        return int(np.floor(state[3] / w + 0.5)) % n

    return (space, [*q0.tolist(), 0.0], [*q1.tolist(), slices.goal * w], position, slice_of)


def _flying_space(scene, orientations, b: np.ndarray, q0: np.ndarray, q1: np.ndarray):
    """SE(3) with rotations snapped to the nearest orientation of the set: the space, start
    and goal fillers, and readers of a state's position and orientation index."""
    from scipy.spatial.transform import Rotation

    ob = _ompl()[0]
    space = ob.SE3StateSpace()
    space.setBounds(_box_bounds(ob, b[0], b[1]))

    def filler(q, k):
        rv = Rotation.from_matrix(orientations.rotation(k)).as_rotvec()
        angle = float(np.linalg.norm(rv))

        def fill(state):
            state.setXYZ(*map(float, q))
            if angle > 0:
                state.rotation().setAxisAngle(*map(float, rv / angle), angle)
            else:
                state.rotation().setIdentity()
        return fill

    def position(state) -> tuple:
        return (state.getX(), state.getY(), state.getZ())

    def orientation_of(state) -> int:
        r = state.rotation()
        return orientations.nearest((r.x, r.y, r.z, r.w))

    return space, filler(q0, 0), filler(q1, orientations.goal), position, orientation_of


_TURNING: dict[str, type] = {}


def _turning_classes() -> dict[str, type]:
    if _TURNING:
        return _TURNING
    ob = _ompl()[0]

    class TurningValidityChecker(ob.StateValidityChecker):
        """A state is valid when the robot at its orientation (``orientation_of(state)``) is
        free at its position (``position(state)``)."""

        def __init__(self, si, tcs, position, orientation_of):
            super().__init__(si)
            self.tcs, self.position, self.orientation_of, self.calls = tcs, position, orientation_of, 0

        def isValid(self, state) -> bool:
            self.calls += 1
            return bool(self.tcs.state_free(self.position(state), self.orientation_of(state)))

    class TurningMotionValidator(ob.MotionValidator):
        """A translation at the first state's orientation, then a turn in place to the
        second's, each certified (:meth:`TurningCSpace.motion_free`)."""

        def __init__(self, si, tcs, position, orientation_of):
            super().__init__(si)
            self.tcs, self.position, self.orientation_of, self.calls = tcs, position, orientation_of, 0

        def checkMotion(self, s1, s2, *last_valid) -> bool:
            self.calls += 1
            return bool(self.tcs.motion_free(self.position(s1), self.orientation_of(s1),
                                             self.position(s2), self.orientation_of(s2)))

    _TURNING["checker"] = TurningValidityChecker
    _TURNING["motion"] = TurningMotionValidator
    return _TURNING
