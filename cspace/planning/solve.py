"""What every planner returns, and OMPL's solve step they share.

:class:`PlanResult` is the outcome of :func:`cspace.planning.plan.plan`,
:func:`cspace.planning.plan.plan_turning`, :func:`cspace.planning.se3.plan.plan_se3` and
:func:`cspace.planning.sampled.plan_sampled`; :func:`_solve` runs one OMPL planner on a set-up
``SpaceInformation`` and reads its raw and simplified paths.
"""

from __future__ import annotations

import time as _time
from dataclasses import dataclass

import numpy as np

from .ompl_plugin import _ompl

__all__ = ["PlanResult"]


@dataclass(frozen=True)
class PlanResult:
    """Outcome of :func:`plan`.

    Attributes
    ----------
    path : (n, 3) float64
        The returned path (after simplification), ``(0, 3)`` if OMPL returned none.
    solved : bool
        OMPL found an exact solution *and* the path was re-proved valid exactly.
    exact : bool
        OMPL reported an exact (not approximate) solution.
    valid : bool
        The exact re-proof of ``path`` (:func:`verify_path`): every waypoint outside the
        closed C-obstacles and in bounds, every segment ``segment_free``.
    planner : str
    motion : {'exact', 'discrete'}
    time : float
        Wall seconds for solve, simplification and re-proof.
    solve_time : float
        Wall seconds in ``solve()`` alone.
    n_states : int
        Waypoints in ``path``.
    status : str
        OMPL's ``PlannerStatus.asString()``.
    state_checks, motion_checks : int
        Python ``isValid`` / ``checkMotion`` calls (motion checks are 0 for ``'discrete'``:
        OMPL's discrete validator calls ``isValid`` at each resolution step).
    simplified : bool
        Whether ``path`` is the simplified path (else the raw one; simplification is dropped
        if its result fails the exact re-proof).
    slices : (n,) int64 or None
        For a turning robot (``plan(..., slices=...)``): the orientation slice of each
        waypoint. Consecutive waypoints differ by a translation within one slice or by a
        turn in place between neighbouring slices, each certified.
    orientations : (n, 4) float64 or None
        For a turning robot: each waypoint's orientation as a unit quaternion ``(x, y, z, w)``
        (world frame, the scene's start rotation included).
    built : dict or None
        For a turning robot: ``{'slices': k, 'turns': t, 'of': (n slices, n turns)}``, the
        C-spaces built (lazily, only those the planner entered) out of those there are;
        with ``'start_orientation_only'`` when the start and goal share an orientation (True:
        the path is translations at it alone, found before any turn was tried).
    tried : list of dict or None
        With ``planner='auto'``: each attempt in order, ``{'planner', 'sampler', 'slices',
        'time', 'seconds', 'solved'}`` (``slices`` None: translations at the start's
        orientation; planner ``'decide'``: :func:`cspace.planning.decide.decide`, with its
        ``answer``); this result is the last attempt's, its ``time`` all of theirs (the
        narrow sampler's pool and the turning attempt's builds included, the start's
        C-space not).
    certified : dict or None
        For a path planned in SE(3) (:func:`cspace.planning.se3.plan.plan_se3`): how its
        motions were certified, ``{'motions', 'queries', 'max_depth', 'error_bound', 'rho'}``
        (the path's consecutive poses, each one certified motion; the clearance queries and
        the deepest bisection their re-check took; the clearance error bound and the robot's
        radius about its reference point).
    decision : Decision or None
        With ``planner='auto'``: the decision at the start's orientation. ``'no path'`` and
        not solved: no translation path exists there (with a clearance above
        ``decision.clearance``); without turns that is the answer (``cspace plan`` exit 3).
    """

    path: np.ndarray
    solved: bool
    exact: bool
    valid: bool
    planner: str
    motion: str
    time: float
    solve_time: float
    n_states: int
    status: str
    state_checks: int
    motion_checks: int
    simplified: bool
    slices: np.ndarray | None = None
    orientations: np.ndarray | None = None
    built: dict | None = None
    tried: list | None = None
    decision: object = None
    certified: dict | None = None

    @property
    def length(self) -> float:
        """Euclidean length of ``path``."""
        return float(np.linalg.norm(np.diff(self.path, axis=0), axis=1).sum())


def _seed(ou, seed) -> None:
    ou.setLogLevel(ou.LOG_ERROR)
    if seed is not None:
        # OMPL logs an error when seeds were already handed out, but still reseeds its seed
        # generator, so the RNGs created from here on are reproducible.
        ou.setLogLevel(ou.LOG_NONE)
        ou.RNG.setSeed(int(seed))
        ou.setLogLevel(ou.LOG_ERROR)


def _solve(si, start, goal, *, planner: str, time: float, optimize: bool,
           planner_range, simplify: bool, read, dim: int, simplify_time: float | None = None):
    """Solve from ``start`` to ``goal`` on the set-up ``si``: each a list of state
    coordinates, or a function that fills an allocated state.

    Returns ``(status, exact, raw, simplified, solve_time)``: OMPL's status, whether the
    solution is exact, the planner's states read by ``read`` into ``(n, dim)`` rows (none:
    ``(0, dim)``), the simplified ones (None when not simplified) and the seconds in
    ``solve()``. Shortcutting gets ``simplify_time`` seconds, default ``min(1, time / 2)``.
    """
    ob, og, _ = _ompl()
    s0, s1 = si.allocState(), si.allocState()
    for state, value in ((s0, start), (s1, goal)):
        if callable(value):
            value(state)
        else:
            state[0:len(value)] = value
    pdef = ob.ProblemDefinition(si)
    pdef.setStartAndGoalStates(s0, s1)
    objective = ob.PathLengthOptimizationObjective(si)
    if not optimize:
        objective.setCostThreshold(ob.Cost(float("inf")))
    pdef.setOptimizationObjective(objective)
    p = getattr(og, planner)(si)
    if planner_range is not None and hasattr(p, "setRange"):
        p.setRange(float(planner_range))
    p.setProblemDefinition(pdef)
    p.setup()
    t0 = _time.perf_counter()
    status = p.solve(float(time))
    solve_time = _time.perf_counter() - t0
    exact = status.getStatus() == ob.PlannerStatus.EXACT_SOLUTION
    have = exact or status.getStatus() == ob.PlannerStatus.APPROXIMATE_SOLUTION
    raw = np.zeros((0, dim))
    simplified = None
    if have:
        path = pdef.getSolutionPath()
        raw = np.array([read(x) for x in path.getStates()]).reshape(-1, dim)
        if simplify and exact and len(raw) > 2:
            og.PathSimplifier(si).simplify(
                path, min(1.0, time / 2.0) if simplify_time is None else simplify_time)
            simplified = np.array([read(x) for x in path.getStates()]).reshape(-1, dim)
    return status, exact, raw, simplified, solve_time
