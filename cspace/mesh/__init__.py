"""What a body *is*: reading mesh files, welding, splitting, validation, convexity, exact queries.

- :mod:`.files` — mesh files (STL, OBJ, PLY, OFF, Collada, BYU …) as float64 vertices and int64 faces;
- :mod:`.components` — exact welding, splitting into parts, nesting of closed parts;
- :mod:`.closed` — :class:`~cspace.mesh.closed.ClosedMesh`: snapped, welded, validated (closed,
  manifold, outward), slivers repaired; :mod:`.validate` its face-level checks;
- :mod:`.self_intersection` — the exact self-intersection test;
- :mod:`.convex` — :class:`~cspace.mesh.convex.ConvexPolytope` and ``convex_within_bound``, the one
  definition of "convex";
- :mod:`.operands` — what an operand is (mesh, path, points, polytope; flat cases);
- :mod:`.query` — :class:`~cspace.mesh.query.MeshCO`: exact containment, distance and segment
  queries on a closed mesh (:mod:`.query_reference` its pure-Python kernels).
"""

from .closed import ClosedMesh, as_mesh
from .convex import ConvexPolytope, convex_within_bound
from .files import MeshFile, read_mesh_file
from .query import MeshCO

__all__ = ["ClosedMesh", "as_mesh", "ConvexPolytope", "convex_within_bound", "MeshFile",
           "read_mesh_file", "MeshCO"]
