"""NCC-CVMS steps 2–18: trimming the superset into the Minkowski-sum polyhedron.

Public entry point: :func:`minkowski_sum` (A closed, possibly non-convex; B convex). Convex
pairs go through CVMS (:func:`cspace.convex.convex_minkowski_sum`); the others through the
superset (:func:`cspace.superset.minkowski_superset`) and the exact trimming below. Both
return a :class:`SumPolyhedron`.
"""

from __future__ import annotations

import time
from dataclasses import dataclass, field
from fractions import Fraction

import numpy as np

from .convex import ConvexPolytope, convex_minkowski_sum
from .errors import NotConvexError
from .exact import Grid
from .mesh import ClosedMesh, as_mesh

__all__ = ["SumPolyhedron", "minkowski_sum"]


@dataclass(frozen=True, eq=False)
class SumPolyhedron:
    """The Minkowski sum A ⊕ B as a closed, oriented polyhedral surface.

    The surface is computed exactly on ``grid`` (every vertex is a rational point, every
    decision an exact predicate) and then rounded to float64 for :attr:`vertices`.

    Attributes
    ----------
    vertices : (n, 3) float64
        Vertex positions, scene units: the exact vertices rounded to the nearest float64.
    faces : (m, 3) int64
        Triangles, counter-clockwise seen from outside the solid (inner shells of holes face
        into the hole). Every edge is used by an even number of triangles with balanced
        orientation (a closed 2-cycle), also at non-manifold edges.
    face_facet : (m,) int64
        The polygon facet each triangle belongs to.
    facet_kind : (f,) int8
        Kind of each polygon facet: an index into ``cspace.SUPERSET_KINDS`` (translated,
        corner, edge), the same kinds as ``cspace.FACET_KINDS`` for convex pairs.
    facet_source_a, facet_source_b : (f, 2) int64
        ``(dimension, index)`` of the features of A and B the facet comes from (for a facet
        merged from several coplanar superset facets: the first of them).
    shell : (m,) int64
        Connected shell of each triangle; ``shell_is_hole[s]`` says whether shell ``s`` bounds a
        polyhedral hole (a bounded void) rather than the outside.
    shell_is_hole : (s,) bool
    nonmanifold_edges : (k, 2) int64
        Vertex pairs ``u < v`` of edges used by four or more triangles.
    nonmanifold_vertices : (k,) int64
        Vertices whose neighbourhood on the surface is not one disc (double vertices,
        pinches), including the endpoints of non-manifold edges.
    rounding_self_intersections : (k, 2) int64
        Pairs of triangles that intersect improperly after rounding to float64 although
        they did not in the exact result (empty when rounding created none).
    grid : Grid
        The snapping grid of the inputs.
    volume_exact : Fraction
        Exact enclosed volume (holes subtracted), scene units cubed, of the exact surface.
    convex : bool
        True when both operands were convex and CVMS produced the result.
    stats : dict
        Seconds per stage and sizes (``superset``, ``merge``, ``pairs``, ``cuts``,
        ``arrangements``, ``traversal``, ``output``, ``total``, counts).
    """

    vertices: np.ndarray
    faces: np.ndarray
    face_facet: np.ndarray
    facet_kind: np.ndarray
    facet_source_a: np.ndarray
    facet_source_b: np.ndarray
    shell: np.ndarray
    shell_is_hole: np.ndarray
    nonmanifold_edges: np.ndarray
    nonmanifold_vertices: np.ndarray
    rounding_self_intersections: np.ndarray
    grid: Grid
    volume_exact: Fraction
    convex: bool = False
    stats: dict = field(default_factory=dict, repr=False)

    @property
    def volume(self) -> float:
        """Enclosed volume (float of :attr:`volume_exact`)."""
        return float(self.volume_exact)

    @property
    def n_holes(self) -> int:
        return int(np.count_nonzero(self.shell_is_hole))

    @property
    def is_manifold(self) -> bool:
        return len(self.nonmanifold_edges) == 0 and len(self.nonmanifold_vertices) == 0

    @property
    def error_bound(self) -> float:
        """Hausdorff distance bound between this sum and the sum of the unsnapped inputs
        (twice the grid's point error bound), plus half a float64 ulp of rounding per
        coordinate of :attr:`vertices`."""
        scale = float(np.abs(self.vertices).max()) if len(self.vertices) else 0.0
        return 2.0 * self.grid.point_error_bound + float(np.spacing(scale))

    def to_trimesh(self):
        import trimesh

        return trimesh.Trimesh(self.vertices, self.faces, process=False)


def _convex_operand(obj, name: str, grid: Grid | None = None) -> ConvexPolytope | None:
    """``obj`` as a ConvexPolytope, or None when it is a non-convex closed mesh."""
    if isinstance(obj, ConvexPolytope):
        return obj
    if isinstance(obj, np.ndarray) and obj.ndim == 2 and obj.shape[1] == 3:
        return ConvexPolytope.from_points(obj, grid=grid, name=name)
    mesh = as_mesh(obj, grid=grid, name=getattr(obj, "name", None) or name)
    try:
        return ConvexPolytope.from_mesh(mesh, name=mesh.name)
    except NotConvexError:
        return None


def _from_convex(A: ConvexPolytope, B: ConvexPolytope, t0: float) -> SumPolyhedron:
    ms = convex_minkowski_sum(A, B)
    P = ms.polytope
    faces, face_facet = P.triangles()
    n = len(faces)
    empty2 = np.zeros((0, 2), dtype=np.int64)
    total = time.perf_counter() - t0
    return SumPolyhedron(
        vertices=P.vertices,
        faces=faces,
        face_facet=face_facet,
        facet_kind=ms.kind,
        facet_source_a=ms.source_a,
        facet_source_b=ms.source_b,
        shell=np.zeros(n, dtype=np.int64),
        shell_is_hole=np.zeros(1, dtype=bool),
        nonmanifold_edges=empty2,
        nonmanifold_vertices=np.zeros(0, dtype=np.int64),
        rounding_self_intersections=empty2,
        grid=P.grid,
        volume_exact=Fraction(P.volume6()) / 6 * Fraction(P.grid.step) ** 3,
        convex=True,
        stats={"cvms": total, "total": total, "facets": P.n_facets},
    )


def minkowski_sum(A, B, *, progress=None) -> SumPolyhedron:
    """Exact Minkowski sum ``A ⊕ B`` of a closed polyhedron A and a convex polytope B.

    Parameters
    ----------
    A : ClosedMesh, (vertices, faces), trimesh.Trimesh, path, ConvexPolytope or (n, 3) points
        A closed, oriented, non-self-intersecting triangle mesh (any genus, non-convex), or a
        convex polytope.
    B : ConvexPolytope, (n, 3) points (hulled) or a closed convex mesh
    progress : callable, optional
        Called as ``progress(stage: str, fraction: float)`` during long builds.

    Returns
    -------
    SumPolyhedron
        Closed and oriented; CVMS when A is convex too (``result.convex``), NCC-CVMS otherwise.

    Raises
    ------
    InvalidMeshError
        Bad operands (open, non-manifold, NaN, ...), or B not convex (``NotConvexError``).
    """
    t0 = time.perf_counter()
    Bc = _convex_operand(B, "B")
    if Bc is None:
        raise NotConvexError("B must be convex (the robot of a translational C-obstacle)")
    Ac = _convex_operand(A, "A")
    if Ac is not None:
        return _from_convex(Ac, Bc, t0)
    return _trim(as_mesh(A, name=getattr(A, "name", None) or "A"), Bc, t0, progress)


def _trim(A: ClosedMesh, B: ConvexPolytope, t0: float, progress) -> SumPolyhedron:
    raise NotImplementedError("NCC-CVMS trimming is being wired (issue #4)")
