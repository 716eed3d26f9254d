"""Planning on the exact C-space: OMPL, a robot that turns, scale-out executors.

- :mod:`.ompl_plugin` — OMPL state-validity checker, motion validator, spaces and samplers;
- :mod:`.free_space` — :func:`~cspace.planning.free_space.free_space`: the exact free space at one
  orientation (the union of convex C-obstacle pieces, its components, point location, the
  surface that separates two of them);
- :mod:`.decide` — :func:`~cspace.planning.decide.decide`: a path through certified free cells,
  or a proof that none exists (the exact free space's separating surface, or cells inside the
  C-obstacles that separate start and goal);
- :mod:`.plan` — :func:`~cspace.planning.plan.plan`, :func:`~cspace.planning.plan.plan_turning`
  → :class:`~cspace.planning.solve.PlanResult` (:mod:`.solve`: the result and OMPL's solve step); :mod:`.sampled` —
  :func:`~cspace.planning.sampled.plan_sampled` (OMPL.app's way, for comparison);
- :mod:`.se3` — the robot turns while it moves: :func:`~cspace.planning.se3.plan.plan_se3`
  (OMPL in SE(3), every pose and motion certified by clearance,
  :class:`~cspace.planning.se3.clearance.PoseClearance`), passages at fixed orientations
  (:mod:`.se3.bridge`), "no path" over all orientations (:mod:`.se3.ball`), the auto
  planner's turning stage (:mod:`.se3.stage`);
- :mod:`.orientations` — orientation slices and sets; :mod:`.turning` — certified turns in
  place between slices and :class:`~cspace.planning.turning.TurningCSpace`;
- :mod:`.scale` — executors (process pool, Dask) and building many slices at once.
"""

from .decide import Decision, decide
from .free_space import FreeSpace, free_space
from .plan import PlanResult, plan, plan_turning
from .sampled import plan_sampled
from .se3.plan import plan_se3
from .turning import TurningCSpace

__all__ = ["Decision", "decide", "FreeSpace", "free_space", "PlanResult", "plan", "plan_turning",
           "plan_sampled", "plan_se3", "TurningCSpace"]
