"""Planning on the exact C-space: OMPL, a robot that turns, scale-out executors.

- :mod:`.ompl_plugin` — OMPL state-validity checker, motion validator, spaces and samplers;
- :mod:`.plan` — :func:`~cspace.planning.plan.plan`, :func:`~cspace.planning.plan.plan_turning`,
  :func:`~cspace.planning.plan.plan_sampled` → :class:`~cspace.planning.plan.PlanResult`;
- :mod:`.orientations` — orientation slices and sets; :mod:`.turning` — certified turns and
  :class:`~cspace.planning.turning.TurningCSpace`;
- :mod:`.scale` — executors (process pool, Dask) and building many slices at once.
"""

from .plan import PlanResult, plan, plan_sampled, plan_turning
from .turning import TurningCSpace

__all__ = ["PlanResult", "plan", "plan_turning", "plan_sampled", "TurningCSpace"]
