"""Minkowski sums: CVMS for convex pairs, NCC-CVMS for a closed non-convex polyhedron and a convex one.

- :mod:`.cvms` — :func:`~cspace.minkowski.cvms.convex_minkowski_sum` (CVMS);
- :mod:`.superset` — NCC-CVMS step 1, the convolution (:func:`~cspace.minkowski.superset.minkowski_superset`);
- :mod:`.sum` — :func:`~cspace.minkowski.sum.minkowski_sum`, the entry point; :mod:`.polyhedron` its results;
- :mod:`.ncc_cvms` — the trimming driver, steps 2–18, one module per stage: :mod:`.planes`,
  :mod:`.intersections` (steps 4–5), :mod:`.arrangements` (steps 2, 3, 6; built on
  :mod:`.plane_arrangement`, :mod:`.coverage`, :mod:`.triangulation`),
  :mod:`.traversal` (steps 7–16), :mod:`.membership` (§3.4), :mod:`.output`, :mod:`.rounding`.
"""

from .cvms import MinkowskiSum, convex_minkowski_sum
from .polyhedron import SumPolyhedron
from .sum import minkowski_sum
from .superset import Superset, minkowski_superset

__all__ = ["MinkowskiSum", "convex_minkowski_sum", "SumPolyhedron", "minkowski_sum",
           "Superset", "minkowski_superset"]
