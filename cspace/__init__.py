"""cspace: exact translational configuration-space obstacles for motion planning.

A robot R (any mesh, translating at a fixed orientation) meets an obstacle O exactly
when its reference point lies in the C-obstacle ``O ⊕ (-R)``. cspace computes these
Minkowski sums exactly: inputs are snapped to a stated dyadic grid and every decision is an
exact predicate (:mod:`cspace.geometry.exact`).

Public API
----------
- :class:`Grid` — the snapping grid and its error bound.
- :class:`ClosedMesh`, :func:`as_mesh` — validated closed meshes (obstacles).
- :class:`ConvexPolytope` — convex polytopes (robots), exact hull, ``reflected(c)`` = −R.
- :func:`convex_minkowski_sum` → :class:`MinkowskiSum` — CVMS, convex ⊕ convex.
- :func:`minkowski_superset` → :class:`Superset` — NCC-CVMS step 1: the convolution of a
  closed mesh and a convex polytope, an oriented 2-cycle with signed corner multiplicities.
- :func:`minkowski_sum` → :class:`SumPolyhedron` — the exact sum of a closed (non-convex)
  polyhedron and a convex one: NCC-CVMS (superset, exact trimming, holes, non-manifold
  contacts), CVMS when both are convex; for a polyhedron that is several closed bodies
  (touching, sharing faces, crossing), the exact boundary of the union of their sums.
- :class:`CSpaceObstacle`, :class:`CSpace` — C-obstacles and exact queries over translations
  (``contains``, ``signed_distance``, ``segment_free``, ``first_contact``). FCL cross-checks:
  :mod:`cspace.check`.
- :func:`load_scene` → :class:`Scene` — scene files: our TOML, OMPL.app ``.cfg``, Parasol
  ``.env``/``.query``.
- :func:`model_scene` → :class:`SceneModel` — what a scene needs: bodies split, duplicates
  dropped, each body convex / solid / surface / dropped with its reason, C-obstacles built
  through the disk cache (:mod:`cspace.scene.cache`).
- the errors of :mod:`cspace.errors`.

The package's layers, bottom up (imports point down only; ``docs/architecture.md``):
:mod:`cspace.geometry` (exact kernel) ← :mod:`cspace.mesh` (what a body is) ←
:mod:`cspace.minkowski` (CVMS, NCC-CVMS) ← :mod:`cspace.cobstacle` (C-obstacles and queries) ←
:mod:`cspace.scene` (scene files, the scene model, the cache) ← :mod:`cspace.check` (FCL oracle),
:mod:`cspace.viz` (drawing) ← :mod:`cspace.planning` (OMPL, turning, scale-out) ← :mod:`cspace.cli`.

Drawing lives in :mod:`cspace.viz` (meshcat ``SceneView``, offline HTML, screenshots); it
imports meshcat only when used.
"""

from . import errors
from ._version import __version__
from .errors import *  # noqa: F403 (the error classes are public)
from .geometry.exact import Grid
from .mesh.closed import ClosedMesh, as_mesh
from .mesh.convex import ConvexPolytope
from .minkowski.cvms import FACET_KINDS, MinkowskiSum, convex_minkowski_sum
from .minkowski.polyhedron import SumPolyhedron
from .minkowski.sum import minkowski_sum
from .minkowski.superset import SUPERSET_KINDS, Superset, minkowski_superset
from .cobstacle.obstacle import CSpaceObstacle
from .scene.files import load_scene, save_scene
from .scene.model import CSpace, SceneModel, model_scene
from .scene.scene import Body, Scene

__all__ = [
    "__version__",
    "Grid",
    "ClosedMesh",
    "as_mesh",
    "ConvexPolytope",
    "MinkowskiSum",
    "FACET_KINDS",
    "convex_minkowski_sum",
    "Superset",
    "SUPERSET_KINDS",
    "minkowski_superset",
    "minkowski_sum",
    "SumPolyhedron",
    "Body",
    "Scene",
    "load_scene",
    "save_scene",
    "CSpaceObstacle",
    "CSpace",
    "model_scene",
    "SceneModel",
] + list(errors.__all__)
