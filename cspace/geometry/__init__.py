"""The exact kernel: the snapping grid, exact predicates, and the compiled kernels.

- :mod:`.exact` — :class:`~cspace.geometry.exact.Grid` (dyadic snapping, its error bound),
  filtered exact predicates (``orient3d``, ``dot_sign``, ``plane_side_matrix`` …) and
  :class:`~cspace.geometry.exact.Perturbation` (symbolic perturbation);
- :mod:`.snapping` — a point's exact snap deviation, grid points grown by a box;
- :mod:`.tritri`, :mod:`.endpoints`, :mod:`.boxes` — exact triangle–triangle intersection,
  its segment endpoints, candidate pairs by box sweep;
- :mod:`.homogeneous` — exact planar points (rationals, homogeneous integer triples) and their predicates;
- :mod:`.transform`, :mod:`.graphs`, :mod:`.polygon`, :mod:`.distance` — rotations, graph
  components, polygon fans, float triangle distances;
- ``_kernels/`` — the Cython extension modules (built at install time), each tested identical
  to its pure-Python reference.

Imports nothing of cspace above it (only :mod:`cspace.errors`).
"""

from .exact import Grid

__all__ = ["Grid"]
