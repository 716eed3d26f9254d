"""Planning on the exact C-space: OMPL, a robot that turns, scale-out executors.

- :mod:`.ompl_plugin` — OMPL state-validity checker, motion validator, spaces and samplers;
- :mod:`.free_space` — :func:`~cspace.planning.free_space.free_space`: the exact free space at one
  orientation (the union of convex C-obstacle pieces, its components, point location, the
  surface that separates two of them);
- :mod:`.decide` — :func:`~cspace.planning.decide.decide`: a path through certified free cells,
  or a proof that none exists (the exact free space's separating surface, or cells inside the
  C-obstacles that separate start and goal);
- :mod:`.plan` — :func:`~cspace.planning.plan.plan`, :func:`~cspace.planning.plan.plan_turning`
  → :class:`~cspace.planning.plan.PlanResult`; :mod:`.sampled` —
  :func:`~cspace.planning.sampled.plan_sampled` (OMPL.app's way, for comparison);
- :mod:`.orientations` — orientation slices and sets; :mod:`.turning` — certified turns and
  :class:`~cspace.planning.turning.TurningCSpace`;
- :mod:`.scale` — executors (process pool, Dask) and building many slices at once.
"""

from .decide import Decision, decide
from .free_space import FreeSpace, free_space
from .plan import PlanResult, plan, plan_turning
from .sampled import plan_sampled
from .turning import TurningCSpace

__all__ = ["Decision", "decide", "FreeSpace", "free_space", "PlanResult", "plan", "plan_turning",
           "plan_sampled", "TurningCSpace"]
