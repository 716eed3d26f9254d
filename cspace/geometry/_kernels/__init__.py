"""Compiled exact kernels (Cython, built at install time). Each serves the modules named below,
where its pure-Python reference lives (same name, leading underscore or ``_reference``):

- ``arrangement`` — :mod:`cspace.geometry.boxes` (box sweep), :mod:`cspace.geometry.tritri`
  (exact triangle-pair classes), :mod:`cspace.geometry.endpoints` (their endpoints);
- ``boxtree`` — :class:`cspace.geometry.boxes.BoxTree` (the median-split build, reference
  ``boxes._tree_reference``; one tree's box queries, the C-space's broad phase);
- ``clearance`` — :mod:`cspace.geometry.clearance` (a robot at any pose against obstacle
  triangles: capped distance, certified motions; references ``clearance._pair_distances_reference``
  and the brute-force ``clearance._distance_reference``, tested in ``tests/test_clearance.py``);
- ``convex`` — :mod:`cspace.minkowski.cvms` (CVMS in one call; reference
  ``cvms._convex_minkowski_sum_reference``) and :mod:`cspace.mesh.convex` (the polytope of an
  exactly convex closed mesh, ``ConvexPolytope.from_convex_mesh``; reference ``ClosedMesh``
  then ``convex_within_bound``);
- ``graph`` — :mod:`cspace.geometry.graphs` (connected components by union-find and
  breadth-first trees; references ``graphs._component_labels_reference`` and
  ``graphs._bfs_predecessors_reference``, scipy's);
- ``meshquery`` — :mod:`cspace.mesh.query` (references in :mod:`cspace.mesh.query_reference`);
- ``pairquery`` — :mod:`cspace.cobstacle.pairs` (triangle pairs found by two box trees; reference
  :mod:`cspace.cobstacle.pairs_reference`, every pair enumerated, tested in
  ``tests/test_pair_engine.py``) and :mod:`cspace.planning.cells` (a cell inside one piece, a
  cell apart from every piece; references ``cells._inside_a_pair_reference`` and
  ``cells._pairs_apart_reference``, tested in ``tests/test_decide.py``);
- ``planar`` — :mod:`cspace.minkowski.plane_arrangement` (each plane's arrangement core),
  :mod:`cspace.minkowski.triangulation`, :mod:`cspace.minkowski.arrangements` (the cuts
  projected into a plane, a one-facet plane's sub-facets; reference
  ``_PlaneJobs.arrange(p, compiled=False)``);
- ``trim`` — :mod:`cspace.mesh.self_intersection` (undecided pairs, triangle boxes),
  :mod:`cspace.minkowski.output` (float rounding) and :mod:`cspace.minkowski.rounding` (moved points).

``tests/test_kernels.py`` and ``tests/test_kernels_intersections.py`` check that compiled and
reference give identical outputs. The extensions are compiled with ``-ffp-contract=off``: no
fused multiply-add, so every float operation rounds exactly as the reference's, and the
filters' error bounds hold.
"""

import importlib
from types import ModuleType


def load(name: str) -> ModuleType:
    """The compiled kernel ``cspace.geometry._kernels.<name>``, or an :class:`ImportError` saying how
    to build it (an install that skipped the build step)."""
    try:
        return importlib.import_module(f"{__name__}.{name}")
    except ImportError as exc:  # pragma: no cover - an install without its build step
        raise ImportError(
            f"cspace's compiled kernels ({__name__}.{name}) are missing: install cspace with "
            "pip (`pip install -e .` in a checkout), which builds them with the system C "
            f"compiler ({exc})"
        ) from exc
