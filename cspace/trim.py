"""NCC-CVMS steps 2–18: trimming the superset into the Minkowski-sum polyhedron.

Public entry point: :func:`minkowski_sum` (A closed, possibly non-convex; B convex). Convex
pairs go through CVMS (:func:`cspace.convex.convex_minkowski_sum`); the others through the
superset (:func:`cspace.superset.minkowski_superset`) and the exact trimming below. Both
return a :class:`SumPolyhedron`.
"""

from __future__ import annotations

import gc
import time
from collections import deque
from dataclasses import dataclass, field
from fractions import Fraction
from functools import cached_property, cmp_to_key
from math import gcd
from pathlib import Path

import numpy as np

from .arrangement import (
    POINT,
    SEGMENT,
    BoxSweep,
    TriTriResult,
    box_pairs,
    endpoint_coordinates,
    intersect_pairs,
)
from .convex import ConvexPolytope, convex_minkowski_sum
from .errors import (ExactnessError, InvalidMeshError, NonManifoldError, NotConvexError,
                     SelfIntersectionError)
from .exact import Grid
from .graphs import component_labels
from .mesh import ClosedMesh, as_mesh
from .planar import (
    Arrangement2D,
    Coverage,
    _hnorm,
    known_triangles,
    plain_interior,
    polygon_coverage,
    project_homogeneous,
    pushed_inside,
    sampled_coverage,
    strict_inner_point,
    triangulate_rings,
)
from .superset import Superset, minkowski_superset, on_common_step
from .workers import can_fork, forked_map, worker_count

from ._kernels import load

_compiled = load("trim")

__all__ = ["SumPolyhedron", "SumUnion", "minkowski_sum"]


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
    rounding : (3,) float64
        Per axis, a bound on how far rounding to float64 moved a vertex (half the ulp of the
        moved coordinates; zero when every vertex is exactly a float64).
    grid : Grid
        The snapping grid of the inputs.
    points_exact : list or ConvexPolytope
        The exact vertices: homogeneous ``(X, Y, Z, W)`` Python ints in grid units, one per
        row of :attr:`vertices` (for convex pairs: the CVMS polytope, integer vertices).
    volume_exact : Fraction
        Exact enclosed volume (holes subtracted), scene units cubed, of the exact surface
        (computed on first access).
    convex : bool
        True when both operands were convex and CVMS produced the result.
    stats : dict
        Seconds per stage (``superset``, ``planes``, ``intersections``, ``arrangements``,
        ``traversal``, ``membership``, ``output``, ``rounding_check``, ``total``) and sizes
        (``superset_facets``, ``superset_triangles``, ``n_planes``, ``candidate_pairs``,
        ``cut_pairs``, ``subfacets``, ``shells``, ``membership_tests``, ``output_triangles``).
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
    points_exact: list = field(repr=False)
    convex: bool = False
    stats: dict = field(default_factory=dict, repr=False)
    rounding: np.ndarray = field(default_factory=lambda: np.zeros(3), repr=False)

    @cached_property
    def volume_exact(self) -> Fraction:
        """Exact enclosed volume (holes subtracted) of the exact surface, scene units cubed."""
        if self.convex:
            P = self.points_exact
            return ExactVolume(Fraction(P.volume6()) / 6 * Fraction(2) ** (3 * self.grid.exponent))
        six = _six_volume(self.points_exact, self.faces)
        return ExactVolume(six / 6 * Fraction(2) ** (3 * self.grid.exponent))

    @property
    def volume(self) -> float:
        """Enclosed volume (float of :attr:`volume_exact`)."""
        return float(self.volume_exact)

    def __repr__(self) -> str:
        return (
            f"SumPolyhedron(vertices={len(self.vertices)}, faces={len(self.faces)}, "
            f"holes={self.n_holes}, nonmanifold_edges={len(self.nonmanifold_edges)}, "
            f"convex={self.convex})"
        )

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
        coordinate of :attr:`vertices`, plus ``sqrt(3)`` steps per flat operand thickened
        (``stats['thickened_operands']``; the sum then holds the exact one), plus how far the
        hulls of operands that snapping bent may exceed them (``stats['hull_excess']``,
        :func:`cspace.convex.convex_within_bound`; the sum then holds the exact one)."""
        scale = float(np.abs(self.vertices).max()) if len(self.vertices) else 0.0
        thick = self.stats.get("thickened_operands", 0) * np.sqrt(3.0) * self.grid.step
        return (2.0 * self.grid.point_error_bound + float(np.spacing(scale)) + thick
                + self.stats.get("hull_excess", 0.0))

    def to_trimesh(self):
        import trimesh

        return trimesh.Trimesh(self.vertices, self.faces, process=False)


@dataclass(frozen=True, eq=False)
class SumUnion:
    """``A ⊕ B`` for an A made of closed pieces that meet at non-manifold edges or vertices
    (two boxes sharing an edge or a corner): the union of the pieces' sums, each exact, not
    merged into one surface. ``(P1 ∪ P2) ⊕ B = (P1 ⊕ B) ∪ (P2 ⊕ B)``.

    Attributes
    ----------
    parts : tuple of SumPolyhedron
        The sum of each piece (``A`` split exactly as scenes split a body:
        :func:`cspace.components.split_mesh`), each closed and oriented outwards.
    pieces : tuple of (vertices, faces)
        The pieces of A (float64 vertices on the grid, faces).
    grid : Grid
    stats : dict
        ``parts`` (how many), ``total`` seconds, and the largest ``thickened_operands`` and
        ``hull_excess`` of the parts.

    Notes
    -----
    The parts' sums overlap (they share at least the sum of the contact), so
    :attr:`vertices`/:attr:`faces` (and :meth:`to_trimesh`) are the parts' closed surfaces
    joined, **not** the boundary of the union: a point is in ``A ⊕ B`` exactly when it is in
    some part (:meth:`cspace.CSpaceObstacle.build` answers queries on such a union). There is
    no single volume, hole count or non-manifold list of the union; ask each part.
    """

    parts: tuple
    pieces: tuple = field(repr=False)
    grid: Grid = field(repr=False)
    stats: dict = field(default_factory=dict, repr=False)
    convex = False

    @cached_property
    def _joined(self):
        V, F, n = [], [], 0
        for p in self.parts:
            V.append(np.asarray(p.vertices, dtype=np.float64))
            F.append(np.asarray(p.faces, dtype=np.int64) + n)
            n += len(V[-1])
        return np.vstack(V), np.vstack(F)

    @property
    def vertices(self) -> np.ndarray:
        """(n, 3) float64: every part's vertices, one after the other."""
        return self._joined[0]

    @property
    def faces(self) -> np.ndarray:
        """(m, 3) int64: every part's closed surface (overlapping; not the union's boundary)."""
        return self._joined[1]

    @property
    def rounding(self) -> np.ndarray:
        """Per axis, the largest of the parts' float64 rounding bounds."""
        return np.max([p.rounding for p in self.parts], axis=0)

    @property
    def error_bound(self) -> float:
        """The largest of the parts' bounds (a union of sums each within its bound of the
        unsnapped one is within the largest of them)."""
        return max(p.error_bound for p in self.parts)

    def __repr__(self) -> str:
        return (f"SumUnion(parts={len(self.parts)}, vertices={len(self.vertices)}, "
                f"faces={len(self.faces)})")

    def to_trimesh(self):
        """The parts' closed surfaces in one ``trimesh.Trimesh`` (overlapping shells)."""
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


def _convex_or_thickened(obj, name: str, grid: Grid | None):
    """``(ConvexPolytope or None, thickened)``.

    Only a *flat* operand is thickened: its snapped points all coplanar or collinear
    (decided exactly), and, for a mesh, its triangles covering their hull (a convex panel,
    one- or two-sided; exact areas). Such a point set has no volume; it is grown by one grid
    step on every axis (its hull with the corners of the box ``[-1, 1]^3`` steps around each
    point) so that the sum has a solid operand; the sum then holds the exact one and lies
    within ``sqrt(3)`` steps of it.

    Anything else is never hulled: a mesh is convex only by
    :func:`cspace.convex.convex_within_bound` (else None: the non-convex path), and a mesh
    that is not flat but fails validation after snapping (a needle or a plate thinner than a
    step making zero-area triangles) raises its named error. A flat mesh that is not convex
    (a flat L) raises :class:`~cspace.errors.DegenerateError`: it has no solid and is not its
    hull."""
    from .convex import _find_tetrahedron
    from .errors import DegenerateError

    points = _raw_points(obj, name)
    if points is not None and len(points):
        g = grid if grid is not None else Grid.for_points(points)
        ints = np.unique(g.snap(points), axis=0)
        try:
            _find_tetrahedron(ints, name)
        except DegenerateError as exc:
            if not isinstance(obj, np.ndarray):
                from .obstacle import _flat_convex_mesh, _mesh_arrays

                P = g.snap(points)
                F = _mesh_arrays(obj)[1]
                if (F.ndim != 2 or F.shape[1:] != (3,) or not F.size or F.min() < 0
                        or F.max() >= len(P)):
                    return _convex_operand(obj, name, grid), False  # its named error
                if not _flat_convex_mesh(P, F):
                    raise DegenerateError(
                        f"{exc} after snapping to a grid of step {g.step:.3g}, and its "
                        "triangles do not cover their hull (a flat non-convex shape): it has no "
                        "solid and is not its hull; model it as a surface (a scene does)") from None
            from .margin import grow_points

            return ConvexPolytope.from_ints(grow_points(ints, (1, 1, 1)), grid=g,
                                            name=name), True
    return _convex_operand(obj, name, grid), False


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
        points_exact=P,
        convex=True,
        stats={"cvms": total, "total": total, "facets": P.n_facets},
    )


def minkowski_sum(A, B, *, progress=None, workers: int | None = None) -> SumPolyhedron:
    """Exact Minkowski sum ``A ⊕ B`` of a closed polyhedron A and a convex polytope B.

    Parameters
    ----------
    A : ClosedMesh, (vertices, faces), trimesh.Trimesh, path, ConvexPolytope or (n, 3) points
        A closed, oriented, non-self-intersecting triangle mesh (any genus, non-convex), or a
        convex polytope.
    B : ConvexPolytope, (n, 3) points (hulled) or a closed convex mesh
        Flat points (a panel, a triangle, a rod; also as A) are thickened by one grid step
        on every axis (``stats['thickened_operands']``, included in :attr:`error_bound`).
    progress : callable, optional
        Called as ``progress(fraction: float, stage: str)`` during long builds: the overall
        fraction done in ``[0, 1]`` (stages weighted by their usual share of the time) and the
        stage starting or under way (the same order as :func:`cspace.model_scene`'s).
    workers : int, optional
        Processes for the triangle-pair intersections, the per-plane arrangements and the
        rounding check (this one and ``workers - 1`` forked; the result does not depend on
        it). Default: ``$CSPACE_WORKERS``, else the CPUs this process may run on; 1 runs
        everything here. Small builds, and calls from a daemonic process or beside other
        threads, stay in this process whatever the value.

    Returns
    -------
    SumPolyhedron or SumUnion
        Closed and oriented; CVMS when A is convex too (``result.convex``), NCC-CVMS otherwise.
        When A is closed pieces meeting at non-manifold edges or vertices (two boxes sharing
        an edge), a :class:`SumUnion`: A split there exactly, as scenes and
        :meth:`cspace.CSpaceObstacle.build` split it, and the sum of each piece (their union
        is the sum; its surfaces overlap, see :class:`SumUnion`).

    Raises
    ------
    InvalidMeshError
        Bad operands (open, non-manifold where it does not split into pieces, NaN, ...), A
        intersecting itself (``SelfIntersectionError``, naming two triangles that cross), or
        B not convex (``NotConvexError``).
    """
    t0 = time.perf_counter()
    A, B = _loaded(A), _loaded(B)
    # Snap both operands once, on grids of one step (snapping on separate grids and then
    # re-snapping onto a common one would move points twice, beyond the stated bound).
    grid_a, grid_b = _shared_grids(A, B)
    Bc, thick_b = _convex_or_thickened(B, "B", grid_b)
    if Bc is None:
        raise NotConvexError("B must be convex (the robot of a translational C-obstacle)")
    try:
        return _sum_with(A, Bc, thick_b, grid_a, progress, workers, t0)
    except NonManifoldError as exc:  # closed pieces meeting at edges or vertices?
        return _sum_of_pieces(A, Bc, thick_b, grid_a, progress, workers, exc)


def _sum_of_pieces(A, Bc, thick_b, grid_a, progress, workers, why) -> SumUnion:
    """:class:`SumUnion` of A split as scenes split a body; ``why`` stands when A does not
    fall apart (one piece: a surface pinched at a vertex)."""
    from .components import split_mesh
    from .obstacle import _mesh_arrays

    t0 = time.perf_counter()
    if isinstance(A, ClosedMesh):
        raise why
    V, F = _mesh_arrays(A)
    grid = grid_a if grid_a is not None else Grid.for_points(V[np.unique(F)])
    pieces = split_mesh(V, F, grid)
    if len(pieces) < 2:
        raise why
    parts = []
    for k, piece in enumerate(pieces):
        def sub(f, stage, k=k):
            if progress is not None:
                progress((k + f) / len(pieces), f"piece {k + 1} of {len(pieces)}: {stage}")
        try:
            parts.append(_sum_with(piece, Bc, thick_b, grid, sub, workers, time.perf_counter()))
        except InvalidMeshError as exc:
            raise type(exc)(f"A: piece {k} of {len(pieces)} (A split at its non-manifold edges "
                            f"and vertices): {exc}") from None
    stats = {"parts": len(parts), "total": time.perf_counter() - t0,
             "thickened_operands": max(p.stats.get("thickened_operands", 0) for p in parts),
             "hull_excess": max(p.stats.get("hull_excess", 0.0) for p in parts)}
    return SumUnion(tuple(parts), tuple(pieces), grid, stats)


def _sum_with(A, Bc: ConvexPolytope, thick_b: bool, grid_a, progress, workers, t0):
    """:func:`minkowski_sum` with B made convex and A's grid decided."""
    Ac, thick_a = _convex_or_thickened(A, "A", grid_a)
    if Ac is not None:
        out = _from_convex(Ac, Bc, t0)
        out.stats["thickened_operands"] = thick_a + thick_b
        out.stats["hull_excess"] = Ac.excess + Bc.excess
        return out
    A = as_mesh(A, grid=grid_a, name=getattr(A, "name", None) or "A")
    crossing = self_intersections(A)
    if len(crossing):
        i, j = crossing[0].tolist()
        raise SelfIntersectionError(
            f"mesh '{A.name}' intersects itself: triangles {i} and {j} meet beyond a shared "
            f"edge or vertex ({len(crossing)} such pairs); its inside is not defined. Repair "
            "it, or model it as an open surface (a scene does: surface semantics)")
    # The trimming makes millions of small tuples and few reference cycles: the cyclic
    # collector's passes over them cost a quarter of the time, and nothing waits for it.
    enabled = gc.isenabled()
    gc.disable()
    try:
        out = _trim(A, Bc, t0, progress, worker_count(workers))
        out.stats["thickened_operands"] = int(thick_b)
        out.stats["hull_excess"] = Bc.excess
        return out
    finally:
        if enabled:
            gc.enable()


class ExactVolume(Fraction):
    """An exact volume: a :class:`fractions.Fraction` that prints whatever its size.

    Python refuses to turn an integer of more than 4300 digits into text; the exact volume
    of a sum with many crossing planes has numerators and denominators that long. Such a
    volume prints as its float and the sizes of its terms; arithmetic is Fraction's.
    """

    _LIMIT_BITS = 4000 * 3  # about 3600 digits: comfortably inside Python's 4300

    def _too_long(self) -> bool:
        return max(abs(self.numerator), self.denominator).bit_length() > self._LIMIT_BITS

    def _digits(self) -> str:
        n, d = abs(self.numerator).bit_length(), self.denominator.bit_length()
        return f"about {int(n * 0.30103) + 1} / {int(d * 0.30103) + 1} digits"

    def __str__(self) -> str:
        if self._too_long():
            return f"{float(self)!r} (exact fraction of {self._digits()})"
        return super().__str__()

    def __repr__(self) -> str:
        if self._too_long():
            return f"ExactVolume({float(self)!r}, {self._digits()})"
        return f"ExactVolume({super().__str__()})"


def _loaded(obj):
    """A mesh file path read (:func:`cspace.meshfile.read_mesh_file`: named errors, Collada
    in Assimp's frame) into a trimesh (no processing); a list of points into an array;
    anything else unchanged."""
    if isinstance(obj, (str, Path)):
        import trimesh

        from .meshfile import read_mesh_file

        name = Path(obj).name
        loaded = read_mesh_file(obj, f"mesh {name!r}")
        return trimesh.Trimesh(loaded.vertices, loaded.faces, process=False,
                               metadata={"name": name})
    if isinstance(obj, list) and len(obj) != 2:
        return np.asarray(obj, dtype=np.float64)
    return obj


def _raw_points(obj, what: str = "operand") -> np.ndarray | None:
    """Unsnapped float vertices of an operand, or None when it already lives on a grid."""
    if isinstance(obj, (ClosedMesh, ConvexPolytope)):
        return None
    if isinstance(obj, np.ndarray):
        points = obj
    elif isinstance(obj, (tuple, list)) and len(obj) == 2:
        points = np.asarray(obj[0], dtype=np.float64)
    elif hasattr(obj, "vertices"):
        points = np.asarray(obj.vertices, dtype=np.float64)
    else:
        return None
    if points.ndim != 2 or points.shape[1] != 3:
        raise InvalidMeshError(f"{what}: vertices must be (n, 3) coordinates, got shape "
                               f"{points.shape}")
    return points


def _shared_grids(A, B) -> tuple[Grid | None, Grid | None]:
    """Grids of one step for two unsnapped operands, each centred on its own points where
    that is finer (``Grid.for_operands``); None: let the operands' own grids decide."""
    a, b = _raw_points(A, "A"), _raw_points(B, "B")
    if a is None or b is None:
        return None, None
    return Grid.for_operands(a, b)


# --------------------------------------------------------------------------------------------
# NCC-CVMS trimming
#
# Sub-facets. Superset triangles are grouped by exact supporting plane. Each plane gets ONE
# exact 2D arrangement (cspace.planar) of its triangles' edges and of the segments where the
# other planes' triangles cut them (steps 4–5, cspace.arrangement); every face gets its net
# coverage (signed multiplicity), so coplanar conjoint facets merge and opposite conjoint ones
# cancel (step 2) inside the same arrangement (step 6). Faces of non-zero coverage are the
# sub-facets; vertices are canonical homogeneous points, so sub-facets of different planes
# meet along identical edges.
#
# Traversal. Around an edge, the half-planes of its sub-facets are ordered by angle (exact
# integer triple products); from one side of a sub-facet, rotating through the free wedge
# reaches the first half-plane, and the side of it facing that wedge. These pairings group
# sub-facet sides into shells: the boundary components of the cells of the arrangement
# (the closeness/two-manifoldness traversal of the paper, with the plane-angle rule, applied
# to both sides of every sub-facet; it handles non-manifold edges because each wedge is
# followed separately).
#
# Membership. Each shell bounds one cell. The unbounded cell is found exactly (the supporting
# plane of the sum in the direction of a facet normal of B). The winding number w of the
# superset is propagated across sub-facets (it jumps by the coverage). w != 0 means inside:
# w is the Euler characteristic of A ∩ (q - B) (tests/test_superset.py), which is 0 for the
# empty set. w == 0 on a bounded cell is either a polyhedral hole or a "ring" cell inside the
# sum; these cells are decided by an exact test at a symbolic point p + eps * v next to a
# sub-facet: q is in the sum iff q - B meets the surface of A (with w == 0, q - B inside A
# would give w == 1), i.e. iff q lies in a convex piece t ⊕ B, decided by separating axes.
# A sub-facet is a facet of the sum exactly when its two sides have different membership.
# --------------------------------------------------------------------------------------------


# The stages of _trim and their usual share of its time (for an overall progress fraction).
# (Rough shares over the 23-case benchmark with the compiled kernels.)
_STAGES = {"superset": 0.08, "planes": 0.04, "intersections": 0.07, "arrangements": 0.55,
           "traversal": 0.07, "membership": 0.04, "output": 0.09, "rounding_check": 0.06}


def _stage_reporter(progress):
    """``report(stage, fraction of the stage)`` calling ``progress(overall fraction, stage)``."""
    names = list(_STAGES)
    starts = dict(zip(names, np.cumsum([0.0] + list(_STAGES.values()))[:-1].tolist()))

    def report(stage: str, fraction: float) -> None:
        if progress is not None:
            progress(min(1.0, starts[stage] + _STAGES[stage] * fraction), stage)
    return report


def _trim(A: ClosedMesh, B: ConvexPolytope, t0: float, progress, workers: int = 1) -> SumPolyhedron:
    stats: dict = {}
    report = _stage_reporter(progress)
    names = list(_STAGES)

    def lap(name: str, since: float) -> float:
        now = time.perf_counter()
        stats[name] = now - since
        following = names[names.index(name) + 1]  # announce the next stage as it starts
        report(following, 0.0)
        return now

    report("superset", 0.0)
    t = time.perf_counter()
    S = minkowski_superset(A, B)
    A, B = on_common_step(A, B)  # the operands as the superset snapped them
    t = lap("superset", t)
    stats["superset_facets"] = S.n_facets

    planes = _plane_groups(S)
    t = lap("planes", t)
    stats["superset_triangles"] = len(planes.faces)
    stats["n_planes"] = len(planes.keys)

    cuts = _cuts(S.ints, planes, workers)
    t = lap("intersections", t)
    stats["candidate_pairs"] = cuts.n_pairs
    stats["cut_pairs"] = cuts.n_cut
    stats["intersection_processes"] = cuts.processes

    cx, stats["arrangement_processes"] = _complex(S.ints, planes, cuts, report, workers)
    t = lap("arrangements", t)
    stats["subfacets"] = len(cx.face_plane)

    shells = _shells(cx, planes)
    t = lap("traversal", t)
    stats["shells"] = int(shells.n)

    inside, n_tested, anchor = _classify(cx, shells, planes, S, A, B)
    t = lap("membership", t)
    stats["membership_tests"] = n_tested

    out = _output(cx, shells, inside, anchor, planes, S)
    lap("output", t)
    stats["total"] = time.perf_counter() - t0
    result = _result(out, S, stats, workers)
    report("rounding_check", 1.0)
    return result


@dataclass
class _Planes:
    """Superset triangles grouped by exact supporting plane.

    ``keys[p] = (n0, n1, n2, d)``: primitive normal with its first non-zero component positive
    and offset ``d = n · x`` (Python ints, grid units). ``sign[t]`` is +1 when triangle ``t``
    turns counter-clockwise around ``n`` (its normal is a positive multiple of ``n``).
    ``axis[p]`` is the coordinate dropped to project plane ``p`` (largest ``|n_i|``) and
    ``sigma[p] = sign(n[axis])``: counter-clockwise in the projection is the orientation of
    ``sigma * n``.
    """

    ints: np.ndarray
    faces: np.ndarray
    facet: np.ndarray
    weight: np.ndarray
    plane: np.ndarray
    sign: np.ndarray
    keys: list
    axis: np.ndarray
    sigma: np.ndarray
    members: list  # triangles of each plane

    def normal(self, p: int) -> tuple[int, int, int]:
        """``sigma * n``: the orientation counter-clockwise projected faces have."""
        s = int(self.sigma[p])
        n = self.keys[p]
        return (s * n[0], s * n[1], s * n[2])


def _plane_groups(S: Superset) -> _Planes:
    faces, facet, weight = S.triangles()
    P = S.ints[faces]
    N = np.cross(P[:, 1] - P[:, 0], P[:, 2] - P[:, 0])  # |k| < 2**29: below 2**61
    keep = (weight > 0) & np.any(N != 0, axis=1)
    faces, facet, weight, N, P = faces[keep], facet[keep], weight[keep], N[keep], P[keep]
    g = np.gcd.reduce(np.abs(N), axis=1)
    n = N // g[:, None]
    first = np.where(n[:, 0] != 0, n[:, 0], np.where(n[:, 1] != 0, n[:, 1], n[:, 2]))
    sign = np.sign(first).astype(np.int8)
    n = n * sign[:, None]
    no, ao = n.astype(object), P[:, 0].astype(object)
    d = no[:, 0] * ao[:, 0] + no[:, 1] * ao[:, 1] + no[:, 2] * ao[:, 2]
    index: dict = {}
    plane = np.empty(len(faces), dtype=np.int64)
    for k, key in enumerate(zip(n[:, 0].tolist(), n[:, 1].tolist(), n[:, 2].tolist(), d.tolist())):
        plane[k] = index.setdefault(key, len(index))
    keys = list(index)
    kn = np.array([k[:3] for k in keys], dtype=np.int64).reshape(-1, 3)
    axis = np.argmax(np.abs(kn), axis=1)
    sigma = np.sign(kn[np.arange(len(kn)), axis]).astype(np.int8)
    order = np.argsort(plane, kind="stable")
    bounds = np.searchsorted(plane[order], np.arange(len(keys) + 1))
    members = [order[bounds[p]: bounds[p + 1]] for p in range(len(keys))]
    return _Planes(S.ints, faces, facet, weight, plane, sign, keys, axis, sigma, members)


@dataclass
class _Cuts:
    """Exact pieces where triangles of different planes meet (steps 4–5).

    ``segments[p]``: list of ``(X4, Y4)`` homogeneous 3D endpoints (equal for points) of the
    intersections lying on plane ``p``.
    """

    segments: list
    n_pairs: int
    n_cut: int
    processes: int = 1


def _cut_pieces(ints: np.ndarray, faces: np.ndarray, pairs: np.ndarray) -> tuple[np.ndarray, list]:
    """The pairs that meet in a segment or a point, and the exact homogeneous endpoints
    ``(X4, Y4)`` of each meeting."""
    res = intersect_pairs(ints, faces, pairs)
    hit = (res.cls == SEGMENT) | (res.cls == POINT)
    if not hit.any():
        return pairs[:0], []
    sub = TriTriResult(
        pairs=res.pairs[hit], cls=res.cls[hit], kind=res.kind[hit], u=res.u[hit],
        v=res.v[hit], plane=res.plane[hit],
    )
    ex, _ = endpoint_coordinates(ints, faces, sub)
    return sub.pairs, ex.tolist()


# From this many one-axis box overlaps on (the sweep's work; some 10-50 per candidate pair),
# the pairs are found and intersected in several processes. Compiled, the stage takes about
# 6 ns per overlap: serial is faster on every benchmark case (torus(25600) + ico320, 20M
# overlaps: 119 ms serial, 154 ms in two processes, whose fork and results cost more than
# the work they share), so only much larger builds fork.
_PARALLEL_OVERLAPS = 100_000_000


def _cuts(ints: np.ndarray, planes: _Planes, workers: int = 1) -> _Cuts:
    corners = ints[planes.faces]
    sweep = BoxSweep(corners.min(axis=1), corners.max(axis=1))

    def share(k: int, n: int) -> tuple[int, np.ndarray, list]:
        pairs = sweep.pairs(k, n)
        pairs = pairs[planes.plane[pairs[:, 0]] != planes.plane[pairs[:, 1]]]
        return (len(pairs), *_cut_pieces(ints, planes.faces, pairs))

    if workers > 1 and sweep.overlaps >= _PARALLEL_OVERLAPS and can_fork():
        n = 2 * workers
        pieces = [r for _, r in forked_map(lambda k: share(k, n), list(range(n)), workers)]
        processes = workers
    else:
        pieces, processes = [share(0, 1)], 1
    segments: list = [[] for _ in planes.keys]
    n_pairs = n_cut = 0
    for count, hit_pairs, ex in pieces:
        n_pairs += count
        n_cut += len(ex)
        pl = planes.plane[hit_pairs]
        for (pa, pb), (x, y) in zip(pl.tolist(), ex):
            segments[pa].append((x, y))
            segments[pb].append((x, y))
    for seg in segments:  # one order whatever process found which pair
        seg.sort()
    return _Cuts(segments, n_pairs, n_cut, processes)


@dataclass
class _Complex:
    """The sub-facets (faces of non-zero support of the plane arrangements) and their edges.

    ``points[i]``: canonical ``(X, Y, Z, W)`` (Python ints, ``W > 0``, primitive) of global
    vertex ``i`` in grid units. Sub-facet ``f`` lies on plane ``face_plane[f]`` with net
    coverage ``face_cov[f]`` counted along ``planes.normal(plane)``; ``_face_tris(cx, f)``
    tiles it with triangles (global ids, counter-clockwise about ``planes.normal``): they are
    ``face_tris[f]``, or, where that is None, made on first use from its boundary cycles
    ``face_rings[f]`` (global ids, outer first) projected along ``plane_axis[plane]``.
    ``face_src[f]`` is a superset facet covering it and ``face_point[f]`` an exact homogeneous
    point strictly inside it (on no edge or vertex of its arrangement), None where the
    centroid of its first triangle is one (lone uncut triangles, faces with a plain interior;
    :func:`_face_point` makes it when asked). Incidence ``k``: sub-facet ``inc_face[k]`` has a boundary half-edge on edge ``inc_edge[k]`` (``edges[e] = (u, v)``,
    ``u < v``), running ``u -> v`` when ``inc_sign[k] = +1``; the sub-facet lies on its left
    seen from ``planes.normal``.
    """

    points: list
    edges: np.ndarray
    face_plane: np.ndarray
    face_cov: np.ndarray
    inc_face: np.ndarray
    inc_edge: np.ndarray
    inc_sign: np.ndarray
    face_tris: list
    face_rings: list
    plane_axis: list
    face_src: np.ndarray
    face_point: list


def _lift(H, key, ax: int) -> tuple:
    """Canonical homogeneous 3D point of the projected point ``H = (x, y, w)`` of plane ``key``."""
    x, y, w = H
    n0, n1, n2, d = key
    n = (n0, n1, n2)
    a, b = (ax + 1) % 3, (ax + 2) % 3
    P = [0, 0, 0]
    P[a], P[b] = x * n[ax], y * n[ax]
    P[ax] = d * w - n[a] * x - n[b] * y
    W = w * n[ax]
    if W < 0:
        P, W = [-c for c in P], -W
    g = gcd(P[0], P[1], P[2], W)
    return (P[0] // g, P[1] // g, P[2] // g, W // g)


def _pinned_edges(planes: _Planes) -> np.ndarray:
    """``pinned[3 t + j]``: edge ``j`` (corners ``j -> j + 1``) of triangle ``t`` is, by its
    labels, also an edge of a triangle of another plane. Such a pair is SHARED_EDGE for
    :func:`intersect_pairs`, so no cut marks the edge: it must stay in its plane's
    arrangement."""
    F = planes.faces
    u = F.reshape(-1)
    v = F[:, [1, 2, 0]].reshape(-1)
    lo, hi = np.minimum(u, v), np.maximum(u, v)
    pl = np.repeat(planes.plane, 3)
    order = np.lexsort((pl, hi, lo))
    lo_s, hi_s, pl_s = lo[order], hi[order], pl[order]
    new = np.ones(len(order), dtype=bool)
    new[1:] = (lo_s[1:] != lo_s[:-1]) | (hi_s[1:] != hi_s[:-1])
    group = np.cumsum(new) - 1
    first = np.nonzero(new)[0]
    last = np.append(first[1:], len(order)) - 1
    mixed = pl_s[first] != pl_s[last]  # sorted by plane inside each group
    pinned = np.zeros(len(order), dtype=bool)
    pinned[order] = mixed[group]
    return pinned


class _PlaneJobs:
    """What the per-plane arrangements read, as Python lists (a forked worker inherits it)."""

    def __init__(self, ints: np.ndarray, planes: _Planes, cuts: _Cuts):
        self.planes = planes
        self.cuts = cuts
        self.corners = ints[planes.faces].tolist()
        self.weight = planes.weight.tolist()
        self.facet = planes.facet.tolist()
        self.sign = planes.sign.tolist()
        self.sigma = planes.sigma.tolist()
        self.axis = planes.axis.tolist()
        self.members = [m.tolist() for m in planes.members]
        self.pinned = _pinned_edges(planes).tolist()
        self.vertex_ids = planes.faces.tolist()

    def trivial(self, p: int) -> bool:
        """Uncut triangles of one superset facet (a fan of a convex polygon: they do not
        overlap) are sub-facets as they are; no arrangement needed."""
        tl = self.members[p]
        return not self.cuts.segments[p] and (len(tl) == 1 or len({self.facet[t] for t in tl}) == 1)

    def cost(self, p: int) -> int:
        """Rough work of plane ``p``'s arrangement (its inputs; quadratic beyond a few tens)."""
        n = len(self.members[p]) + len(self.cuts.segments[p])
        return n + n * n // 64

    def arrange(self, p: int):
        """Sub-facets of arrangement plane ``p``: ``(lifted, faces)`` with ``lifted[v]`` the
        canonical 3D point of local vertex ``v`` and, per face of non-zero support,
        ``(coverage, boundary cycles, triangles or None, source facet, inner point or None)``
        in local vertex ids (cycles: the outer one, then the holes, as vertex lists)."""
        ax = self.axis[p]
        a, b = (ax + 1) % 3, (ax + 2) % 3
        tl = self.members[p]
        polys = [[(c[a], c[b], 1) for c in self.corners[t]] for t in tl]
        cut3 = self.cuts.segments[p]
        segs = [(_hnorm(*project_homogeneous(x, ax)), _hnorm(*project_homogeneous(y, ax))) for x, y in cut3]
        # The net coverage changes only where another plane's sheet meets this one
        # (closedness of the superset): along the cuts and the edges shared by label with
        # other planes' triangles. Where the net coverage is 0, the sheets of one orientation
        # cover exactly where those of the other do, so the edges of the less frequent
        # orientation bound the kept (support != 0) part. Other triangle edges stay out.
        sg = [self.sign[t] for t in tl]
        minority = -1 if sg.count(1) >= sg.count(-1) else 1
        pinned = self.pinned
        pin = [(i, j) for i, t in enumerate(tl) for j in range(3) if pinned[3 * t + j] or sg[i] == minority]
        seg2 = [(polys[i][j], polys[i][(j + 1) % 3]) for i, j in pin] + segs
        lab2 = pin + [(-1, k) for k in range(len(segs))]
        one = self._one_facet(tl)
        if one:
            # One convex facet whose whole boundary is in the arrangement: every bounded face
            # lies in it (nothing is drawn outside), so each is covered once, by the facet.
            arr = Arrangement2D(seg2, lab2, canonical=True)
            c = self.weight[tl[0]] * self.sign[tl[0]] * self.sigma[p]
            cov = Coverage(arr, [c] * len(arr.faces), [abs(c)] * len(arr.faces))
        else:
            weights = [self.weight[t] for t in tl]
            try:
                cov = sampled_coverage(polys, weights, seg2, lab2, canonical=True)
            except ValueError:  # pragma: no cover - the certificate failed: cut by every edge
                cov = polygon_coverage(polys, weights, segs)
            arr = cov.arrangement
        key = self.planes.keys[p]
        # the 3D points of the inputs are known; only crossings made in the plane are lifted
        known = {(c[a], c[b], 1): (c[0], c[1], c[2], 1) for t in tl for c in self.corners[t]}
        for (x, y), (px, py) in zip(cut3, segs):
            known[px] = x
            known[py] = y
        lifted = [known.get(h) or _lift(h, key, ax) for h in arr._H]
        origin = arr.half_edge_origin
        faces = []
        for f, (c, support) in enumerate(zip(cov.coverage, cov.support)):
            if support == 0:
                continue  # covered by no superset triangle
            face = arr.faces[f]
            rings = [[origin[h] for h in cyc] for cyc in (face.outer, *face.holes)]
            # Most sub-facets are not output (a fifth to a half of them are) and few need a
            # membership point, so triangles not made already wait until asked (_face_tris).
            tris = known_triangles(arr, f)
            src = self.facet[tl[0]] if one else self._source_facet(p, arr, f, tl)
            # where the centroid of the first triangle is a strict inner point, it too is made
            # only when asked (_face_point)
            point = None if plain_interior(arr, f) else _lift(strict_inner_point(arr, f), key, ax)
            faces.append((c, rings, tris, src, point))
        return lifted, faces

    def _one_facet(self, tl: list) -> bool:
        """The triangles ``tl`` of a plane are the fan of one superset facet (one weight,
        one orientation) and every edge of the fan's boundary is pinned (so in the
        arrangement): the edges used once in the fan, by their vertex labels."""
        facet = self.facet[tl[0]]
        if any(self.facet[t] != facet for t in tl):
            return False
        once: dict = {}
        for t in tl:
            ids = self.vertex_ids[t]
            for j in range(3):
                u, v = ids[j], ids[(j + 1) % 3]
                key = (u, v) if u < v else (v, u)
                once[key] = None if key in once else 3 * t + j
        pinned = self.pinned
        return all(k is None or pinned[k] for k in once.values())

    def _source_facet(self, p: int, arr, f: int, tl: list) -> int:
        """A superset facet whose triangle covers (part of) face ``f``: one whose edge bounds
        the face from the covered side, else the first in plane order covering the face's
        inner point. (A face may be covered by several coplanar facets of one orientation:
        the merge of step 2; it names one of them.)"""
        if len(tl) == 1:
            return self.facet[tl[0]]
        ax = self.axis[p]
        a, b = (ax + 1) % 3, (ax + 2) % 3
        face = arr.faces[f]
        H, origin = arr._H, arr.half_edge_origin
        ccw = self.sigma[p]
        # A triangle with an edge along the face's boundary, on the face's side of it,
        # covers the face next to that edge.
        for h in face.outer:
            for i, j in arr.edge_labels[h // 2]:
                if i < 0:
                    continue
                t = tl[i]
                c = self.corners[t]
                u, v = c[j], c[(j + 1) % 3]
                d_tri = (v[a] - u[a], v[b] - u[b])
                p0, p1 = H[origin[h]], H[origin[h ^ 1]]
                d_face = (p1[0] * p0[2] - p0[0] * p1[2], p1[1] * p0[2] - p0[1] * p1[2])
                same = d_tri[0] * d_face[0] + d_tri[1] * d_face[1] > 0
                if same == (self.sign[t] * ccw > 0):
                    return self.facet[t]
        X, Y, W = arr._inner_point(f)
        for t in tl:
            if pushed_inside([(c[a], c[b]) for c in self.corners[t]], self.sign[t] * ccw, X, Y, W):
                return self.facet[t]
        raise ExactnessError(f"face {f} of plane {p} is covered by no superset triangle")  # pragma: no cover


# Below this much estimated work (sum of _PlaneJobs.cost, about 10 us a unit with the
# compiled kernels) the arrangements run in this process: forking and collecting results
# (some 15-20 ms, and copy-on-write faults adding about a tenth to the work) would cost
# more than they save. Measured, 2 processes against 1: 3000-7600 units (bunny-128 ⊕
# ico320, alphaobstacle ⊕ ico320, Centaur-1000 ⊕ box) 0.9-1.0x; 8000-11000 (yoda-658 ⊕
# box, star ⊕ ico320) 1.15-1.3x.
_PARALLEL_FROM = 8000


def _run_arrangements(jobs: _PlaneJobs, todo: list, workers: int, report) -> tuple[dict, int]:
    """``{plane: jobs.arrange(plane)}`` for the planes ``todo``, in this process and
    ``workers - 1`` forked ones when there is enough work (results do not depend on the
    number of workers), and the number of processes used."""
    n = len(todo)
    total = sum(jobs.cost(p) for p in todo)
    out: dict = {}
    if workers > 1 and n >= 16 and total >= _PARALLEL_FROM and can_fork():
        # largest first, then chunks small enough to balance the two ends
        order = sorted(todo, key=jobs.cost, reverse=True)
        size = max(1, min(64, n // (8 * workers)))
        chunks = [order[k: k + size] for k in range(0, n, size)]
        for _, res in forked_map(lambda ps: [(p, jobs.arrange(p)) for p in ps], chunks, workers):
            out.update(res)
            report("arrangements", len(out) / n)
        return out, workers
    for k, p in enumerate(todo):
        out[p] = jobs.arrange(p)
        if k % 256 == 0:
            report("arrangements", k / max(n, 1))
    return out, 1


def _complex(ints: np.ndarray, planes: _Planes, cuts: _Cuts, report, workers: int = 1) -> tuple[_Complex, int]:
    vid: dict = {}
    face_plane, face_cov, face_tris, face_rings, face_src, face_point = [], [], [], [], [], []
    ring_u, ring_v, ring_f = [], [], []  # every boundary half-edge: from, to, sub-facet
    jobs = _PlaneJobs(ints, planes, cuts)
    n_planes = len(planes.keys)
    todo = [p for p in range(n_planes) if not jobs.trivial(p)]
    done, used = _run_arrangements(jobs, todo, workers, report)
    members, sign, sigma, corners = jobs.members, jobs.sign, jobs.sigma, jobs.corners
    weight, facet = jobs.weight, jobs.facet
    for p in range(n_planes):
        if p not in done:  # uncut triangles: each its own sub-facet, counter-clockwise
            for t in members[p]:
                ccw = sign[t] * sigma[p]
                c0, c1, c2 = corners[t] if ccw > 0 else corners[t][::-1]
                g0 = vid.setdefault((*c0, 1), len(vid))
                g1 = vid.setdefault((*c1, 1), len(vid))
                g2 = vid.setdefault((*c2, 1), len(vid))
                fid = len(face_plane)
                face_plane.append(p)
                face_cov.append(ccw * weight[t])
                face_tris.append([(g0, g1, g2)])
                face_rings.append(None)
                face_src.append(facet[t])
                face_point.append(None)
                ring_u += (g0, g1, g2)
                ring_v += (g1, g2, g0)
                ring_f += (fid, fid, fid)
            continue
        lifted, faces = done.pop(p)
        g = [vid.setdefault(x, len(vid)) for x in lifted]
        for cov, rings, tris, src, point in faces:
            fid = len(face_plane)
            face_plane.append(p)
            face_cov.append(cov)
            rings = [[g[v] for v in ring] for ring in rings]
            if tris is None:
                face_tris.append(None)
                face_rings.append(rings)
            else:
                face_tris.append([(g[x], g[y], g[z]) for x, y, z in tris])
                face_rings.append(None)
            face_src.append(src)
            face_point.append(point)
            for ring in rings:
                ring_u += ring
                ring_v += ring[1:]
                ring_v.append(ring[0])
                ring_f += [fid] * len(ring)
    # Edges are numbered in order of first appearance along the rings, as (u, v), u < v.
    u = np.array(ring_u, dtype=np.int64)
    v = np.array(ring_v, dtype=np.int64)
    lo, hi = np.minimum(u, v), np.maximum(u, v)
    _, first, inverse = np.unique(lo * max(len(vid), 1) + hi, return_index=True, return_inverse=True)
    order = np.argsort(first)  # first appearances are distinct
    rank = np.empty(len(order), dtype=np.int64)
    rank[order] = np.arange(len(order))
    firsts = first[order]
    return _Complex(
        points=list(vid),
        edges=np.stack([lo[firsts], hi[firsts]], axis=1).reshape(-1, 2),
        face_plane=np.array(face_plane, dtype=np.int64),
        face_cov=np.array(face_cov, dtype=np.int64),
        inc_face=np.array(ring_f, dtype=np.int64),
        inc_edge=rank[inverse.reshape(-1)],
        inc_sign=np.where(u < v, 1, -1).astype(np.int8),
        face_tris=face_tris,
        face_rings=face_rings,
        plane_axis=jobs.axis,
        face_src=np.array(face_src, dtype=np.int64),
        face_point=face_point,
    ), used


@dataclass
class _Shells:
    """Sides of sub-facets grouped into shells (boundary components of arrangement cells).

    Side node ``2 f + 1`` is the side of sub-facet ``f`` its plane normal (``planes.normal``)
    points into, node ``2 f`` the other one; ``of[node]`` is its shell.
    """

    of: np.ndarray
    n: int


def _cross(a, b):
    return (a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0])


def _dot(a, b) -> int:
    return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]


def _orient3(a, b, c, d) -> int:
    """Sign of det[b - a, c - a, d - a] (Python ints)."""
    u = (b[0] - a[0], b[1] - a[1], b[2] - a[2])
    v = (c[0] - a[0], c[1] - a[1], c[2] - a[2])
    w = (d[0] - a[0], d[1] - a[1], d[2] - a[2])
    x = _dot(u, _cross(v, w))
    return (x > 0) - (x < 0)


def _edge_vector(cx: _Complex, e: int) -> tuple:
    """An integer vector along edge ``e`` from its smaller to its larger vertex id (scaled by
    the product of their ``W``)."""
    u, v = cx.edges[e].tolist()
    P, Q = cx.points[u], cx.points[v]
    return tuple(Q[k] * P[3] - P[k] * Q[3] for k in range(3))


def _edge_direction(cx: _Complex, planes: _Planes, e: int, normals: list) -> tuple:
    """Integer vector along edge ``e`` from its smaller to its larger vertex id, from two
    non-parallel plane normals of its sub-facets (an edge with three or more half-planes
    always has two)."""
    for i in range(len(normals)):
        for j in range(i + 1, len(normals)):
            d = _cross(normals[i], normals[j])
            if d != (0, 0, 0):
                s = _dot(d, _edge_vector(cx, e))
                if s == 0:  # pragma: no cover - the edge lies on both planes
                    raise ExactnessError(f"edge {e} is not along the line of its planes")
                return d if s > 0 else tuple(-c for c in d)
    raise ExactnessError(f"edge {e}: its half-planes all lie in one plane")  # pragma: no cover


def _angular_order(vectors: list, d: tuple) -> list:
    """Indices of ``vectors`` (all orthogonal to ``d``) in counter-clockwise order about ``d``."""
    r = vectors[0]

    def half(x) -> int:
        c = _dot(_cross(r, x), d)
        return 0 if c > 0 or (c == 0 and _dot(r, x) > 0) else 1

    def cmp(i, j) -> int:
        hi, hj = half(vectors[i]), half(vectors[j])
        if hi != hj:
            return hi - hj
        c = _dot(_cross(vectors[i], vectors[j]), d)
        if c == 0:
            raise ExactnessError("two sub-facets share an edge and a half-plane")
        return -1 if c > 0 else 1

    return sorted(range(len(vectors)), key=cmp_to_key(cmp))


def _crossing_order(cx: _Complex, e: int, inc: list, inc_sign: list, plane_of: list,
                    plane_normal: list) -> list | None:
    """The angular order of :func:`_angular_order` at an edge where two planes cross, each
    with a sub-facet on both sides (four incidences, two per plane, opposite half-edge
    signs), or None for any other edge. The keys ``s_h * m`` come in two opposite pairs
    ``±v`` (plane p) and ``±w`` (plane q); after ``v`` comes the ``w`` with
    ``(v x w) . d > 0``, and ``d = sign(D . delta) D`` for ``D = n_p x n_q`` along the edge
    ``delta``: that product is ``s_v s_w sign(D . delta) |D|^2``, so one exact sign decides."""
    i0 = inc[0]
    p = plane_of[i0]
    same = [i for i in inc[1:] if plane_of[i] == p]
    other = [i for i in inc[1:] if plane_of[i] != p]
    if len(same) != 1 or len(other) != 2 or plane_of[other[0]] != plane_of[other[1]]:
        return None
    i1, (j0, j1) = same[0], other
    if inc_sign[i1] == inc_sign[i0] or inc_sign[j0] == inc_sign[j1]:
        return None
    s = _dot(_cross(plane_normal[p], plane_normal[plane_of[j0]]), _edge_vector(cx, e))
    if s == 0:  # pragma: no cover - the edge lies on both planes
        raise ExactnessError(f"edge {e} is not along the line of its planes")
    nxt, last = (j0, j1) if inc_sign[i0] * inc_sign[j0] * (1 if s > 0 else -1) > 0 else (j1, j0)
    return [i0, nxt, i1, last]


# Bound factor of the float filter of (n_p x n_q) . (P_v - P_u): about 9 eps of the same sum
# on absolute values (conversions, products, differences, the 3-term sum); doubled.
_CROSSING_FILTER = 18 * float(np.finfo(np.float64).eps) / 2


def _crossing_orders(cx: _Complex, edges: np.ndarray, inc: np.ndarray,
                     plane_normal: list) -> tuple[np.ndarray, np.ndarray]:
    """:func:`_crossing_order` of many four-incidence edges at once: ``inc (m, 4)`` their
    incidences (in incidence order). Returns the orders ``(m', 4)`` of the edges where two
    planes cross and a float filter decides the sign, and a mask of the other edges (other
    kinds, and the filter's undecided rows): those go to :func:`_crossing_order` and the
    angular sort one by one."""
    plane = cx.face_plane[cx.inc_face[inc]]
    same = plane[:, 1:] == plane[:, :1]
    by = np.argsort(same, axis=1, kind="stable")  # the two other-plane columns, then the same
    rows = np.arange(len(inc))
    j0, j1, i1 = (inc[rows, 1 + by[:, k]] for k in range(3))
    jp0, jp1 = plane[rows, 1 + by[:, 0]], plane[rows, 1 + by[:, 1]]
    i0 = inc[:, 0]
    ok = ((same.sum(axis=1) == 1) & (jp0 == jp1)
          & (cx.inc_sign[i1] != cx.inc_sign[i0]) & (cx.inc_sign[j0] != cx.inc_sign[j1]))
    r = np.nonzero(ok)[0]
    # sign of (n_p x n_q) . (P_v - P_u) in floats, with a bound on its error
    normals = np.array(plane_normal, dtype=np.float64).reshape(-1, 3)
    a, b = normals[plane[r, 0]], normals[jp0[r]]
    D = np.cross(a, b)
    M = (np.abs(a[:, [1, 2, 0]] * b[:, [2, 0, 1]]) + np.abs(a[:, [2, 0, 1]] * b[:, [1, 2, 0]]))
    uv = cx.edges[edges[r]]
    ids, where = np.unique(uv, return_inverse=True)
    pts = cx.points
    P = np.array([[X / W, Y / W, Z / W] for X, Y, Z, W in (pts[i] for i in ids.tolist())],
                 dtype=np.float64).reshape(-1, 3)
    Pu, Pv = P[where.reshape(-1, 2)[:, 0]], P[where.reshape(-1, 2)[:, 1]]
    dot = np.einsum("ij,ij->i", D, Pv - Pu)
    bound = _CROSSING_FILTER * np.einsum("ij,ij->i", M, np.abs(Pu) + np.abs(Pv))
    sure = np.abs(dot) > bound
    r, dot = r[sure], dot[sure]
    slow = np.ones(len(inc), dtype=bool)
    slow[r] = False
    first = cx.inc_sign[i0[r]].astype(np.int64) * cx.inc_sign[j0[r]] * np.sign(dot) > 0
    nxt = np.where(first, j0[r], j1[r])
    last = np.where(first, j1[r], j0[r])
    return np.stack([i0[r], nxt, i1[r], last], axis=1), slow


def _wedge_links(cx: _Complex, L: np.ndarray, positions) -> tuple[list, list]:
    """Side-node pairs across the free wedges of edges whose half-planes (incidences) are in
    cyclic angular order ``L (m, k)``: from side ``s`` of the sub-facet at ``positions`` of
    each row, rotating through the free wedge reaches the next half-plane, and the side of
    it that faces the wedge (the plane-angle rule; with two half-planes, orientation
    coherence)."""
    rows = np.arange(len(L))
    k = L.shape[1]
    a, b = [], []
    for pos in positions:
        i = L[:, pos]
        for s in (1, -1):
            rot = s * cx.inc_sign[i].astype(np.int64)
            j = L[rows, (pos + rot) % k]
            a.append(2 * cx.inc_face[i] + (s > 0))
            b.append(2 * cx.inc_face[j] + (-rot * cx.inc_sign[j] > 0))
    return a, b


def _shells(cx: _Complex, planes: _Planes) -> _Shells:
    order = np.argsort(cx.inc_edge, kind="stable")
    e_sorted = cx.inc_edge[order]
    counts = np.bincount(cx.inc_edge, minlength=len(cx.edges))
    start = np.searchsorted(e_sorted, np.arange(len(cx.edges)))
    # side pairs (node, node); with two half-planes one position gives every link
    two = start[counts == 2]
    fa, ta = _wedge_links(cx, np.stack([order[two], order[two + 1]], axis=1), (0,))
    # A free edge (one half-plane: the rim of a sheet whose superset pieces cancel) joins
    # the two sides of its sub-facet: the cell wraps around the rim.
    one = order[start[counts == 1]]
    fa += [2 * cx.inc_face[one]]
    ta += [2 * cx.inc_face[one] + 1]
    plane_normal = [planes.normal(p) for p in range(len(planes.keys))]
    # Edges where two planes cross: their order from one sign each, decided together.
    four = np.nonzero(counts == 4)[0]
    L4, slow = _crossing_orders(cx, four, order[start[four][:, None] + np.arange(4)], plane_normal)
    a4, b4 = _wedge_links(cx, L4, range(4))
    fa += a4
    ta += b4
    orders: dict = {}  # the other edges' orders, by number of half-planes
    many = np.union1d(np.nonzero((counts > 2) & (counts != 4))[0], four[slow])
    inc_sign = cx.inc_sign.tolist()
    plane_of = cx.face_plane[cx.inc_face].tolist()  # plane of each incidence
    for e, lo, k in zip(many.tolist(), start[many].tolist(), counts[many].tolist()):
        inc = order[lo: lo + k].tolist()
        L = _crossing_order(cx, e, inc, inc_sign, plane_of, plane_normal) if k == 4 else None
        if L is None:
            normals = [plane_normal[plane_of[i]] for i in inc]
            d = _edge_direction(cx, planes, e, normals)
            vec = [tuple(inc_sign[i] * c for c in n) for i, n in zip(inc, normals)]
            L = [inc[m] for m in _angular_order(vec, d)]
        orders.setdefault(k, []).append(L)
    for k, Ls in orders.items():
        a, b = _wedge_links(cx, np.array(Ls, dtype=np.int64), range(k))
        fa += a
        ta += b
    a = np.concatenate(fa)
    b = np.concatenate(ta)
    n_nodes = 2 * len(cx.face_plane)
    n, of = component_labels(n_nodes, a, b)
    return _Shells(of=of.astype(np.int64), n=int(n))


def _anchor(cx: _Complex, planes: _Planes, S: Superset, B: ConvexPolytope) -> int:
    """Side node facing the unbounded cell: on the supporting plane of the sum in the direction
    ``u`` of B's first facet normal, the side towards ``+u`` (nothing of the superset lies
    beyond that plane, and the corner facets there have coverage 1)."""
    u = tuple(int(c) for c in B.normals[0])
    pts = S.ints.astype(object)
    h = max((pts[:, 0] * u[0] + pts[:, 1] * u[1] + pts[:, 2] * u[2]).tolist())
    g = gcd(u[0], u[1], u[2], h)
    n, d = tuple(c // g for c in u), h // g
    if next(c for c in n if c != 0) < 0:
        n, d = tuple(-c for c in n), -d
    try:
        p = planes.keys.index((*n, d))
    except ValueError:
        raise ExactnessError("no sub-facet on the supporting plane of the sum") from None
    faces = np.nonzero(cx.face_plane == p)[0]
    if not len(faces):
        raise ExactnessError("no sub-facet on the supporting plane of the sum")
    s = _dot(planes.normal(p), u) > 0
    return 2 * int(faces[0]) + int(s)


def _winding(cx: _Complex, sh: _Shells, anchor: int) -> np.ndarray:
    """Winding number of the superset on each shell's cell, propagated from the unbounded
    cell (0) across sub-facets: it is larger by the coverage on the side a sub-facet's
    normal points away from."""
    nf = len(cx.face_plane)
    plus, minus = sh.of[2 * np.arange(nf) + 1], sh.of[2 * np.arange(nf)]
    adj: list = [[] for _ in range(sh.n)]
    for a, b, c in zip(plus.tolist(), minus.tolist(), cx.face_cov.tolist()):
        adj[a].append((b, c))
        adj[b].append((a, -c))
    w = [None] * sh.n
    root = int(sh.of[anchor])
    w[root] = 0
    queue = deque([root])
    while queue:
        x = queue.popleft()
        for y, c in adj[x]:
            if w[y] is None:
                w[y] = w[x] + c
                queue.append(y)
            elif w[y] != w[x] + c:
                raise ExactnessError("inconsistent winding numbers across the sub-facet complex")
    # Shells of complex components not connected to the outer one (A with several surface
    # components, e.g. an inner cavity) get no winding number here: marked unknown.
    return np.array([_UNKNOWN if v is None else v for v in w], dtype=np.int64)


_UNKNOWN = np.iinfo(np.int64).min
# From this many pairs left by the float filters on, the rounding check's exact test runs in
# several processes (about 30 us a pair in Python against some 10-20 ms to fork and collect).
_PARALLEL_CHECK = 2_000
# Float filter for orientations of float64 points (Shewchuk's bound is below 8 eps).
_ORIENT_FILTER = 16 * float(np.finfo(np.float64).eps) / 2
# Float filter of a dot product of float64 rows: the three products and two sums are off by
# at most 3 unit roundoffs of the sum of absolute products, the bound's own addition by one
# more; 8 leaves room for the rounding of the bound itself.
_DOT_FILTER = 8 * float(np.finfo(np.float64).eps) / 2


# Float filter of _PieceTest: each separating-axis value is a sum of a few products of
# float64 numbers; its rounding error is below a few ulps of ``mag`` (the sum of the absolute
# products). Values within this bound are re-decided with Python integers.
_FILTER = 64 * float(np.finfo(np.float64).eps)


class _PieceTest:
    """Exact test of ``q = p + eps * v`` (eps -> 0+) against the convex pieces ``t ⊕ B`` of A⊕B
    (t a triangle of A), by separating axes: the normals of t, of B's facets and the cross
    products of their edges contain every facet normal of ``t ⊕ B``."""

    def __init__(self, A: ClosedMesh, B: ConvexPolytope):
        T = A.ints[A.faces].astype(np.int64)
        self.T = T
        self.lo = T.min(axis=1) + B.ints.min(axis=0)
        self.hi = T.max(axis=1) + B.ints.max(axis=0)
        self.Bv = B.ints.astype(np.int64)
        self.nB = B.normals.astype(np.int64)
        be = B.ints[B.edges[:, 1]] - B.ints[B.edges[:, 0]]
        self.eB = be.astype(np.int64)
        self.Bo = B.ints.astype(object)
        # the normals of the two facets at each edge of B (its Gauss arc)
        self.n1 = self.nB[B.edge_facets[:, 0]].astype(np.float64)
        self.n2 = self.nB[B.edge_facets[:, 1]].astype(np.float64)

    def axes(self, t: int) -> np.ndarray:
        """Candidate separating axes of ``t ⊕ B``: ``±n_t``, B's facet normals, and the cross
        products ``±(e_t x e_B)`` whose direction lies in the normal cone of ``e_B`` (only
        then is it a facet normal of ``t ⊕ B``). The cone test is a float filter that only
        drops an axis when it is certainly outside the cone; extra axes are harmless."""
        a, b, c = self.T[t]
        et = np.stack([b - a, c - b, a - c])
        nt = np.cross(b - a, c - a)
        cr = np.cross(et[:, None, :], self.eB[None, :, :])  # (3, e, 3)
        u = cr.astype(np.float64)
        e = self.eB.astype(np.float64)[None]
        n1, n2 = self.n1[None], self.n2[None]
        s1 = np.einsum("kij,kij->ki", np.cross(n1, u), e)
        s2 = np.einsum("kij,kij->ki", np.cross(u, n2), e)
        s0 = np.einsum("kij,kij->ki", np.cross(n1, n2), e)
        mag = np.einsum("kij,kij->ki", np.abs(n1) + np.abs(n2), np.abs(u)) * np.abs(e).sum(axis=2)
        tol = _FILTER * 4 * mag  # each s is a sum of 6 products of 3 float factors
        sure_pos = ((s1 * np.sign(s0) > tol) | (s2 * np.sign(s0) > tol)) & (np.abs(s0) > tol)
        sure_neg = ((s1 * np.sign(s0) < -tol) | (s2 * np.sign(s0) < -tol)) & (np.abs(s0) > tol)
        # +u is outside the cone when one sign is surely negative; -u when one is surely positive
        keep_plus = ~sure_neg
        keep_minus = ~sure_pos
        U = np.concatenate([nt[None], -nt[None], self.nB, cr[keep_plus], -cr[keep_minus]])
        return U[np.any(U != 0, axis=1)]

    def inside_a(self, P4: tuple) -> bool:
        """Is ``x = p - c`` inside A, for ``c`` the vertex centroid of B (interior to B)?

        Called when ``p + eps * v - B`` misses the surface of A: then the interior of
        ``p - B`` misses it too, ``x`` is not on the surface, and ``x`` is in A exactly when
        ``q - B`` is. Decided by the parity of proper crossings of a segment from ``x`` to a
        point outside A's bounding box; a segment through an edge or vertex of A (detected
        exactly) is replaced by another one.
        """
        nb = len(self.Bv)
        c = [int(v) for v in self.Bv.sum(axis=0)]
        W = P4[3] * nb
        X = [P4[k] * nb - c[k] * P4[3] for k in range(3)]  # x = X / W
        lo, hi = self.T.reshape(-1, 3).min(axis=0), self.T.reshape(-1, 3).max(axis=0)
        span = int((hi - lo).max()) + 1
        rng = np.random.default_rng(0)
        xf = np.array([X[k] / W for k in range(3)])
        for _ in range(64):
            d = rng.integers(-1000, 1001, size=3)
            if not d.any():
                continue
            # far end, integer grid point: beyond the box in the direction d
            scale = 4 * span // int(np.abs(d).max()) + 4
            y = [int(round(xf[k])) + int(d[k]) * scale for k in range(3)]
            crossings = self._crossings(X, W, y)
            if crossings is not None:
                return crossings % 2 == 1
        raise ExactnessError("no non-degenerate ray found for a point-in-solid test")  # pragma: no cover

    def _crossings(self, X: list, W: int, y: list):
        """Proper crossings of the segment ``X / W -> y`` with A's triangles, None if the
        segment passes through an edge or a vertex of A."""
        Y = [c * W for c in y]
        lo = np.minimum([X[k] / W for k in range(3)], y) - 2
        hi = np.maximum([X[k] / W for k in range(3)], y) + 2
        tlo, thi = self.T.min(axis=1), self.T.max(axis=1)
        cand = np.nonzero(np.all((thi >= lo) & (tlo <= hi), axis=1))[0]
        n = 0
        for t in cand.tolist():
            a, b, c = ([int(x) * W for x in r] for r in self.T[t].tolist())
            s1, s2 = _orient3(a, b, c, X), _orient3(a, b, c, Y)
            if s1 == 0 or s2 == 0 or (s1 > 0) == (s2 > 0):
                continue  # x is on no triangle and y is outside the box: no crossing here
            e = (_orient3(X, Y, a, b), _orient3(X, Y, b, c), _orient3(X, Y, c, a))
            if 0 in e:
                if all(v >= 0 for v in e) or all(v <= 0 for v in e):
                    return None  # through an edge or a vertex
                continue
            if e[0] == e[1] == e[2]:
                n += 1
        return n

    def contains(self, P4: tuple, v: tuple) -> bool:
        W = P4[3]
        pf = np.array([P4[0] / W, P4[1] / W, P4[2] / W])
        cand = np.nonzero(np.all((self.lo - 1 <= pf) & (pf <= self.hi + 1), axis=1))[0]
        for t in cand.tolist():
            if self._in_piece(t, P4, pf, v):
                return True
        return False

    def _in_piece(self, t: int, P4: tuple, pf: np.ndarray, v: tuple) -> bool:
        U = self.axes(t)
        Uf = U.astype(np.float64)
        Tf = self.T[t].astype(np.float64)
        hA = (Uf @ Tf.T).max(axis=1)
        hB = (Uf @ self.Bv.T.astype(np.float64)).max(axis=1)
        g = Uf @ pf - hA - hB
        mag = np.abs(Uf) @ (np.abs(pf) + np.abs(Tf).max(axis=0) + np.abs(self.Bv).max(axis=0))
        bound = _FILTER * mag
        if np.any(g > bound):
            return False  # a separating axis, decided in floating point
        close = np.nonzero(np.abs(g) <= bound)[0]
        W = P4[3]
        To = self.T[t].astype(object)
        for k in close.tolist():
            u = tuple(int(c) for c in U[k])
            h = max(_dot(u, r) for r in To.tolist()) + max(_dot(u, r) for r in self.Bo.tolist())
            s = _dot(u, P4[:3]) - W * h
            if s > 0 or (s == 0 and _dot(u, v) > 0):
                return False
        return True


def _face_tris(cx: _Complex, f: int) -> list:
    """The triangles of sub-facet ``f`` (global ids, counter-clockwise about its plane's
    normal), triangulated on first use from its cycles: the triangles its arrangement would
    have made, since its vertices project back to the same canonical 2D points."""
    tris = cx.face_tris[f]
    if tris is None:
        ax = cx.plane_axis[cx.face_plane[f]]
        a, b = (ax + 1) % 3, (ax + 2) % 3
        rings, P = cx.face_rings[f], cx.points
        H = {v: _hnorm(P[v][a], P[v][b], P[v][3]) for ring in rings for v in ring}
        tris = cx.face_tris[f] = triangulate_rings(H, rings)
        cx.face_rings[f] = None
    return tris


def _face_point(cx: _Complex, f: int) -> tuple:
    """Exact homogeneous point strictly inside sub-facet ``f``: the one its arrangement gave,
    else the centroid of its first triangle (strictly inside it, and nothing of the
    arrangement meets that open triangle)."""
    if cx.face_point[f] is not None:
        return cx.face_point[f]
    a, b, c = _face_tris(cx, f)[0]
    (xa, ya, za, wa), (xb, yb, zb, wb), (xc, yc, zc, wc) = cx.points[a], cx.points[b], cx.points[c]
    bc, ac, ab = wb * wc, wa * wc, wa * wb
    s = (xa * bc + xb * ac + xc * ab, ya * bc + yb * ac + yc * ab, za * bc + zb * ac + zc * ab,
         3 * wa * bc)
    h = gcd(s[0], s[1], s[2], s[3])
    return (s[0] // h, s[1] // h, s[2] // h, s[3] // h)


def _classify(cx: _Complex, sh: _Shells, planes: _Planes, S: Superset, A: ClosedMesh,
              B: ConvexPolytope) -> tuple[np.ndarray, int, int]:
    """Membership of each shell's cell in A ⊕ B (True: inside)."""
    anchor = _anchor(cx, planes, S, B)
    w = _winding(cx, sh, anchor)
    unknown = w == _UNKNOWN
    inside = (w != 0) & ~unknown
    root = int(sh.of[anchor])
    todo = np.nonzero(~inside)[0]
    todo = todo[todo != root]
    if not len(todo):
        return inside, 0, anchor
    _, node = np.unique(sh.of, return_index=True)  # first side node of each shell
    test = _PieceTest(A, B)
    for s in todo.tolist():
        k = int(node[s])
        f, side = k // 2, 1 if k % 2 else -1
        m = planes.normal(int(cx.face_plane[f]))
        P4 = _face_point(cx, f)
        inside[s] = test.contains(P4, tuple(side * c for c in m))
        if not inside[s] and unknown[s]:
            # w is unknown, so q - B may lie inside A without touching its surface
            inside[s] = test.inside_a(P4)
    return inside, len(todo), anchor


@dataclass
class _Output:
    points: list  # exact homogeneous points of the output vertices
    faces: np.ndarray
    face_facet: np.ndarray
    facet_superset: np.ndarray  # a superset facet each output facet comes from
    shell: np.ndarray
    shell_is_hole: np.ndarray


def _output(cx: _Complex, sh: _Shells, inside: np.ndarray, anchor: int, planes: _Planes,
            S: Superset) -> _Output:
    nf = len(cx.face_plane)
    plus = inside[sh.of[2 * np.arange(nf) + 1]]
    minus = inside[sh.of[2 * np.arange(nf)]]
    keep = np.nonzero(plus != minus)[0]
    # Outside cells joined through dropped sub-facets form the complement's components.
    parent = list(range(sh.n))

    def find(a: int) -> int:
        while parent[a] != a:
            parent[a] = parent[parent[a]]
            a = parent[a]
        return a

    for f in np.nonzero(~plus & ~minus)[0].tolist():
        ra, rb = find(int(sh.of[2 * f])), find(int(sh.of[2 * f + 1]))
        if ra != rb:
            parent[ra] = rb
    tris, tri_facet, facet_src, outside_cell = [], [], [], []
    for n, f in enumerate(keep.tolist()):
        flip = bool(plus[f])  # inside on the normal's side: the outward normal is reversed
        for a, b, c in _face_tris(cx, f):
            tris.append((a, c, b) if flip else (a, b, c))
            tri_facet.append(n)
        facet_src.append(int(cx.face_src[f]))
        outside_cell.append(find(int(sh.of[2 * f + (0 if flip else 1)])))
    T = np.array(tris, dtype=np.int64).reshape(-1, 3)
    used, T = np.unique(T, return_inverse=True)
    T = T.reshape(-1, 3)
    points = [cx.points[i] for i in used.tolist()]
    # shells: one per component of the complement a facet faces. The anchor's is unbounded;
    # another one is unbounded too when it faces a separate body (disjoint sums are not
    # joined through dropped sub-facets), bounded when it is a hole. The exact sign of the
    # volume its triangles enclose tells them apart: outward shells enclose positive volume,
    # the shells of holes face inwards.
    cells, facet_shell = np.unique(np.array(outside_cell, dtype=np.int64), return_inverse=True)
    facet_shell = facet_shell.reshape(-1)
    root = find(int(sh.of[anchor]))
    shell_is_hole = cells != root
    tri_shell = facet_shell[np.array(tri_facet, dtype=np.int64)] if len(tri_facet) else None
    for k in np.nonzero(shell_is_hole)[0].tolist():
        shell_is_hole[k] = _volume_sign(points, T[tri_shell == k]) < 0
    return _Output(
        points=points,
        faces=T,
        face_facet=np.array(tri_facet, dtype=np.int64),
        facet_superset=np.array(facet_src, dtype=np.int64),
        shell=tri_shell if tri_shell is not None else np.zeros(0, np.int64),
        shell_is_hole=shell_is_hole,
    )


def _six_volume(points: list, faces: np.ndarray) -> Fraction:
    """Six times the volume the triangles enclose, exactly, in grid units cubed (homogeneous
    grid points ``(x, y, z, w)``)."""
    num, den = 0, 1
    for a, b, c in faces.tolist():
        P, Q, R = points[a], points[b], points[c]
        det = _dot(P[:3], _cross(Q[:3], R[:3]))
        if det:
            w = P[3] * Q[3] * R[3]
            g = gcd(den, w)
            num, den = num * (w // g) + det * (den // g), den * (w // g)
    return Fraction(num, den)


def _volume_sign(points: list, faces: np.ndarray) -> int:
    """Exact sign of the volume the triangles enclose (homogeneous grid points).

    Float filter first: six times the volume is the sum over the triangles of the triple
    products ``a . (b x c)`` of their corners. On coordinates correctly rounded from the exact
    ratios (relative error ``u = 2**-53``), each computed triple product is within ``(3u +
    5u + O(u^2)) m`` of the exact one (three rounded factors, then at most five roundings of
    the products and sums), ``m`` the sum of the absolute values of its six products; the
    sum of the ``n`` terms adds at most ``(n - 1) u`` of the sum of their magnitudes. So the
    computed sum is within ``(n + 8) u (1 + O(u)) M`` (``M`` the sum of the ``m``), and its
    sign is the exact one when ``|sum| > 2 (n + 10) u M`` (the factor 2 covers the rounding
    of ``M``). Coordinates beyond ``[2**-300, 2**300]`` in magnitude (other than 0) skip the
    filter (no under- or overflow). Else the exact sum (:func:`_six_volume`) decides."""
    if len(faces):
        ids = np.unique(faces)
        P = np.array([(p[0] / p[3], p[1] / p[3], p[2] / p[3]) for p in (points[i] for i in ids.tolist())],
                     dtype=np.float64).reshape(-1, 3)
        a = np.abs(P)
        if (((a == 0) | ((a >= 2.0 ** -300) & (a <= 2.0 ** 300))).all()):
            F = np.searchsorted(ids, faces)
            A, B, C = P[F[:, 0]], P[F[:, 1]], P[F[:, 2]]
            total = float(np.einsum("ij,ij->i", A, np.cross(B, C)).sum())
            aA, aB, aC = np.abs(A), np.abs(B), np.abs(C)
            mag = float((aA[:, 0] * (aB[:, 1] * aC[:, 2] + aB[:, 2] * aC[:, 1])
                         + aA[:, 1] * (aB[:, 2] * aC[:, 0] + aB[:, 0] * aC[:, 2])
                         + aA[:, 2] * (aB[:, 0] * aC[:, 1] + aB[:, 1] * aC[:, 0])).sum())
            if abs(total) > 2.0 * (len(faces) + 10) * 2.0 ** -53 * mag:
                return 1 if total > 0 else -1
    six = _six_volume(points, faces)
    return (six > 0) - (six < 0)


def _to_float(points: list, grid: Grid) -> np.ndarray:
    """Correctly rounded float64 scene coordinates of homogeneous grid points (Python's
    int / int rounds correctly; the grid's origin is added exactly before)."""
    ox, oy, oz = grid.origin
    V = np.array([((P[0] + ox * P[3]) / P[3], (P[1] + oy * P[3]) / P[3],
                   (P[2] + oz * P[3]) / P[3]) for P in points], dtype=np.float64)
    return np.ldexp(V.reshape(-1, 3), grid.exponent)


def _to_float_compiled(points: list, grid: Grid) -> np.ndarray:
    """:func:`_to_float` compiled (:mod:`cspace._kernels.trim`): identical output. The rows
    it leaves (integers beyond 2**53) come from :func:`_to_float`."""
    points = points if isinstance(points, list) else list(points)
    V, left = _compiled.to_float(points, tuple(grid.origin), int(grid.exponent))
    rows = np.flatnonzero(left)
    if len(rows):
        V[rows] = _to_float([points[i] for i in rows.tolist()], grid)
    return V


def _nonmanifold(faces: np.ndarray, n_vertices: int) -> tuple[np.ndarray, np.ndarray]:
    """Edges used by more than two triangles, and vertices whose triangles form more than one
    fan (joined across edges used by exactly two triangles)."""
    m = len(faces)
    if not m:
        return np.zeros((0, 2), np.int64), np.zeros(0, np.int64)
    u = faces.reshape(-1)
    v = faces[:, [1, 2, 0]].reshape(-1)
    lo, hi = np.minimum(u, v), np.maximum(u, v)
    key = lo * n_vertices + hi
    # One sort groups the half-edges by edge: runs of equal keys, from start, cnt long.
    order = np.argsort(key, kind="stable")
    sk = key[order]
    new = np.empty(len(sk), dtype=bool)
    new[0], new[1:] = True, sk[1:] != sk[:-1]
    start = np.flatnonzero(new)
    uniq, cnt = sk[start], np.diff(np.append(start, len(sk)))
    bad_edges = np.stack([uniq[cnt > 2] // n_vertices, uniq[cnt > 2] % n_vertices], axis=1)
    # Corner 3 t + i sits at faces[t, i]; half-edge 3 t + i runs from corner 3 t + i to the
    # next corner of t. Two half-edges of a manifold edge join their corners at equal vertices.
    h = np.arange(3 * m)
    cu, cv = h, 3 * (h // 3) + (h % 3 + 1) % 3
    # The two half-edges of each edge of exactly two triangles: the first two of its run
    # (pairing the sorted half-edges two by two instead lost the pairs after a run of odd
    # length, e.g. an edge of three triangles).
    two = start[cnt == 2]
    a, b = order[two], order[two + 1]
    same = u[a] == u[b]
    src = np.concatenate([cu[a], cv[a]])
    dst = np.concatenate([np.where(same, cu[b], cv[b]), np.where(same, cv[b], cu[b])])
    n_fans, comp = component_labels(3 * m, src, dst)
    # Every join above is between corners at one vertex: each fan (component) lies at one
    # vertex, so counting fans per vertex needs no search for distinct (vertex, fan) pairs.
    fan_vertex = np.empty(n_fans, dtype=np.int64)
    fan_vertex[comp] = u
    fans = np.bincount(fan_vertex, minlength=n_vertices)
    return bad_edges.astype(np.int64), np.nonzero(fans > 1)[0].astype(np.int64)


def _result(out: _Output, S: Superset, stats: dict, workers: int = 1) -> SumPolyhedron:
    t = time.perf_counter()
    grid = S.grid
    V = _to_float_compiled(out.points, grid)
    nm_edges, nm_vertices = _nonmanifold(out.faces, len(V))
    crossings, stats["rounding_processes"], moved = _rounding_check(out, V, grid, workers)
    # Correct rounding moves a coordinate by at most half its ulp: per axis, over moved points.
    rounding = (0.5 * np.spacing(np.abs(V[moved])).max(axis=0) if moved.any()
                else np.zeros(3))
    stats["rounding_check"] = time.perf_counter() - t
    stats["total"] += stats["rounding_check"]
    stats["output_triangles"] = len(out.faces)
    n_facets = len(out.facet_superset)
    src = out.facet_superset
    return SumPolyhedron(
        vertices=V,
        faces=out.faces,
        face_facet=out.face_facet,
        facet_kind=S.kind[src] if n_facets else np.zeros(0, np.int8),
        facet_source_a=S.source_a[src] if n_facets else np.zeros((0, 2), np.int64),
        facet_source_b=S.source_b[src] if n_facets else np.zeros((0, 2), np.int64),
        shell=out.shell,
        shell_is_hole=out.shell_is_hole,
        nonmanifold_edges=nm_edges,
        nonmanifold_vertices=nm_vertices,
        rounding_self_intersections=crossings,
        grid=grid,
        points_exact=out.points,
        convex=False,
        stats=stats,
        rounding=rounding,
    )


def _rounding_check(out: _Output, V: np.ndarray, grid: Grid,
                    workers: int = 1) -> tuple[np.ndarray, int, np.ndarray]:
    """Triangle pairs that meet improperly after rounding to float64, the number of
    processes that tested them exactly (several from ``_PARALLEL_CHECK`` pairs left by the
    float filters on), and which vertices rounding moved.

    In the exact result two triangles meet only in shared vertices and edges. Rounding moves
    a vertex by at most half an ulp per coordinate; only pairs with a moved vertex can change,
    and only if their rounded boxes overlap. Those pairs are tested exactly on the rounded
    coordinates (float filter, then Fractions): proper crossings for disjoint triangles,
    fold-over for triangles sharing an edge, and any contact beyond the shared vertex.
    """
    T = out.faces
    if not len(T):
        return np.zeros((0, 2), np.int64), 1, np.zeros(len(V), dtype=bool)
    moved = _moved_compiled(out.points, V, grid)
    if not moved.any():
        return np.zeros((0, 2), np.int64), 1, moved
    return (*_improper_pairs(V, T, grid, moved, workers), moved)


def _moved(points: list, V: np.ndarray, grid: Grid) -> np.ndarray:
    """Which float64 rows ``V[i]`` differ from their exact homogeneous grid points
    ``points[i]``, i.e. ``V[i] != (P[:3] / P[3] + origin) * 2**exponent``: ``(n,)`` bool,
    decided on Python integers."""
    e = grid.exponent
    up, down = (1 << e, 1) if e >= 0 else (1, 1 << -e)
    origin = grid.origin

    def moved_point(P, v) -> bool:
        for k in range(3):
            num, den = v[k].as_integer_ratio()
            if num * P[3] * down != (P[k] + origin[k] * P[3]) * up * den:
                return True
        return False

    return np.array([moved_point(P, v) for P, v in zip(points, V.tolist())], dtype=bool).reshape(-1)


def _moved_compiled(points: list, V: np.ndarray, grid: Grid) -> np.ndarray:
    """:func:`_moved` compiled (:mod:`cspace._kernels.trim`, int64/__int128 integers):
    identical output. The points it leaves (integers beyond 2**62) go to :func:`_moved`."""
    V = np.ascontiguousarray(V, dtype=np.float64)
    points = points if isinstance(points, list) else list(points)
    state = _compiled.moved_points(points, tuple(grid.origin), int(grid.exponent), V)
    moved = state == 1
    left = np.flatnonzero(state == 2)
    if len(left):
        moved[left] = _moved([points[i] for i in left.tolist()], V[left], grid)
    return moved


def self_intersections(mesh) -> np.ndarray:
    """Pairs of triangles of a closed mesh that meet beyond the vertices and edge they share
    (crossings, overlaps, folds, touching): ``(k, 2)`` int64, empty for a valid solid.

    Exact on the mesh's grid coordinates: box pairs first, the rounding check's float filters,
    then integer predicates for what they leave.

    Parameters
    ----------
    mesh : ClosedMesh
    """
    T = np.asarray(mesh.faces, dtype=np.int64)
    if not len(T):
        return np.zeros((0, 2), np.int64)
    moved = np.ones(len(mesh.vertices), dtype=bool)  # test every pair, not only moved ones
    bad, _ = _improper_pairs(np.asarray(mesh.vertices, dtype=np.float64), T, mesh.grid, moved)
    return bad


def _improper_pairs(V: np.ndarray, T: np.ndarray, grid: Grid, moved: np.ndarray,
                    workers: int = 1) -> tuple[np.ndarray, int]:
    """Pairs of triangles ``T`` over float64 vertices ``V`` (with a vertex in ``moved``) that
    meet improperly, decided exactly; and the number of processes used."""
    pairs = box_pairs(*_triangle_boxes_compiled(V, T, grid.exponent))
    # The compiled float filter (some 40 ns a pair, 20x numpy's): few pairs are left.
    pairs = pairs[_undecided_pairs_compiled(V, T, pairs, moved)]
    if not len(pairs):
        return np.zeros((0, 2), np.int64), 1
    # Exact integers of only the vertices of the pairs left, on triangles renumbered to
    # them: their common scale is another power of two than all vertices', and _improper's
    # predicates (orientations, dominant axis, coordinate comparisons) are homogeneous, so
    # a positive scale changes none of its answers.
    ids = np.unique(T[pairs].reshape(-1))
    Vi, Tl = _common_integers(V[ids]), np.searchsorted(ids, T[pairs]).tolist()

    def check(ks: range) -> list:
        return [k for k in ks if _improper(Vi, Tl[k][0], Tl[k][1])]

    ranges = [range(len(pairs))]
    if workers > 1 and len(pairs) >= _PARALLEL_CHECK and can_fork():
        cuts = np.linspace(0, len(pairs), 2 * workers + 1).astype(int)
        ranges = [range(a, b) for a, b in zip(cuts[:-1], cuts[1:])]
    done = dict(forked_map(check, ranges, workers if len(ranges) > 1 else 1))
    bad = [k for r in range(len(ranges)) for k in done[r]]  # in pair order
    return pairs[np.array(bad, dtype=np.int64)].reshape(-1, 2), min(len(ranges), workers)


def _triangle_boxes(V: np.ndarray, T: np.ndarray, exponent: int) -> tuple[np.ndarray, np.ndarray]:
    """``(lo, hi)``, ``(t, 3)`` int64: the boxes of triangles ``T`` over float64 rows ``V``
    in grid units (step ``2**exponent``), rounded outwards: they contain the float boxes."""
    P = V[T]
    lo = np.floor(np.ldexp(P.min(axis=1), -exponent)).astype(np.int64)
    hi = np.ceil(np.ldexp(P.max(axis=1), -exponent)).astype(np.int64)
    return lo.reshape(-1, 3), hi.reshape(-1, 3)


def _triangle_boxes_compiled(V: np.ndarray, T: np.ndarray, exponent: int) -> tuple[np.ndarray, np.ndarray]:
    """:func:`_triangle_boxes` compiled (:mod:`cspace._kernels.trim`): identical output (the
    reference's when a coordinate is not finite or a box end not below 2**62)."""
    lo, hi, ok = _compiled.triangle_boxes(np.ascontiguousarray(V, np.float64),
                                          np.ascontiguousarray(T, np.int64).reshape(-1, 3),
                                          int(exponent))
    return (lo, hi) if ok else _triangle_boxes(V, T, exponent)


def _separated(V: np.ndarray, T: np.ndarray, i: np.ndarray, j: np.ndarray) -> np.ndarray:
    """Pairs where every vertex of triangle ``j`` not shared with ``i`` lies strictly on one
    side of the plane of ``i`` (float filter; undecided pairs are False): then the two
    triangles meet at most in their shared vertices and edge."""
    a, b, c = (V[T[i, k]] for k in range(3))
    u, v = b - a, c - a
    n = np.cross(u, v)
    side = np.zeros((len(i), 3), dtype=np.int8)
    for k in range(3):
        w = V[T[j, k]] - a
        det = np.einsum("ij,ij->i", n, w)
        perm = (np.abs(u[:, 0]) * (np.abs(v[:, 1] * w[:, 2]) + np.abs(v[:, 2] * w[:, 1]))
                + np.abs(u[:, 1]) * (np.abs(v[:, 2] * w[:, 0]) + np.abs(v[:, 0] * w[:, 2]))
                + np.abs(u[:, 2]) * (np.abs(v[:, 0] * w[:, 1]) + np.abs(v[:, 1] * w[:, 0])))
        sure = np.abs(det) > _ORIENT_FILTER * perm
        shared = np.any(T[i] == T[j, k][:, None], axis=1)
        side[:, k] = np.where(shared, 2, np.where(sure, np.sign(det), 0))
    free = side != 2
    pos = np.all((side == 1) | ~free, axis=1)
    neg = np.all((side == -1) | ~free, axis=1)
    return (pos | neg) & free.any(axis=1)


def _o2_filtered(u, a, b) -> np.ndarray:
    """Sign of orient2d(u, a, b) on float rows, 0 where the float filter cannot decide."""
    x1, y1 = a[:, 0] - u[:, 0], a[:, 1] - u[:, 1]
    x2, y2 = b[:, 0] - u[:, 0], b[:, 1] - u[:, 1]
    det = x1 * y2 - y1 * x2
    sure = np.abs(det) > _ORIENT_FILTER * (np.abs(x1 * y2) + np.abs(y1 * x2))
    return np.where(sure, np.sign(det), 0)


def _apart_in_projection_np(V: np.ndarray, T: np.ndarray, pairs: np.ndarray,
                            ax: np.ndarray) -> np.ndarray:
    """Pairs whose projections along coordinate axis ``ax`` (per pair) meet only in their
    shared vertices or edge, decided by a float filter (undecided: False). The 3D triangles
    then meet only there too (the projection of their intersection lies in the intersection
    of their projections)."""
    i, j = pairs[:, 0], pairs[:, 1]
    Ti, Tj = T[i], T[j]
    eq = Ti[:, :, None] == Tj[:, None, :]  # (k, 3, 3): vertex a of i equals vertex b of j
    n_shared = eq.sum(axis=(1, 2))
    out = np.zeros(len(pairs), dtype=bool)
    keep = np.stack([(ax + 1) % 3, (ax + 2) % 3], axis=1)
    rows = np.arange(len(pairs))

    def P(ids, r):
        return np.stack([V[ids, keep[r, 0]], V[ids, keep[r, 1]]], axis=1)

    # disjoint: an edge line of one triangle strictly separates the other (2D axes)
    z = n_shared == 0
    if z.any():
        r = rows[z]
        sep = np.zeros(len(r), dtype=bool)
        for A_, B_ in ((Ti[r], Tj[r]), (Tj[r], Ti[r])):
            for k in range(3):
                p, q, o3 = P(A_[:, k], r), P(A_[:, (k + 1) % 3], r), P(A_[:, (k + 2) % 3], r)
                o = _o2_filtered(p, q, o3)
                allout = o != 0
                for m in range(3):
                    allout &= _o2_filtered(p, q, P(B_[:, m], r)) * o < 0
                sep |= allout
        out[r] = sep
    si = eq.any(axis=2)  # vertices of i that are shared
    sj = eq.any(axis=1)
    # shared edge (u, v): the two apexes strictly on opposite sides of the edge's line
    e = n_shared == 2
    if e.any():
        r = rows[e]
        ai = Ti[r, np.argmin(si[r], axis=1)]
        aj = Tj[r, np.argmin(sj[r], axis=1)]
        uv = np.sort(np.where(si[r], Ti[r], -1), axis=1)[:, 1:]
        u, v = P(uv[:, 0], r), P(uv[:, 1], r)
        s1 = _o2_filtered(u, v, P(ai, r))
        s2 = _o2_filtered(u, v, P(aj, r))
        out[r] = s1 * s2 < 0
    # shared vertex u: each edge ray at u strictly outside the other triangle's corner
    w = n_shared == 1
    if w.any():
        r = rows[w]
        ku = np.argmax(si[r], axis=1)
        u_id = Ti[r, ku]
        a_id, b_id = Ti[r, (ku + 1) % 3], Ti[r, (ku + 2) % 3]
        kj = np.argmax(sj[r], axis=1)
        c_id, d_id = Tj[r, (kj + 1) % 3], Tj[r, (kj + 2) % 3]
        u, a, b, c, d = (P(x, r) for x in (u_id, a_id, b_id, c_id, d_id))

        def outside(x, p, q):  # ray u->x strictly outside the convex corner (p, q) at u
            o = _o2_filtered(u, p, q)
            return (o != 0) & ((_o2_filtered(u, p, x) * o < 0) | (_o2_filtered(u, x, q) * o < 0))

        out[r] = outside(c, a, b) & outside(d, a, b) & outside(a, c, d) & outside(b, c, d)
    return out


def _axes_apart_np(V: np.ndarray, T: np.ndarray, pairs: np.ndarray) -> np.ndarray:
    """Pairs (no shared vertex) strictly separated along one of the cross products of an
    edge of each triangle, decided by a float filter (undecided: False). Any axis is a valid
    certificate, so only the dot products need a bound, not the axes."""
    A, B = V[T[pairs[:, 0]]], V[T[pairs[:, 1]]]  # (k, 3 corners, 3)
    eA, eB = A[:, [1, 2, 0]] - A, B[:, [1, 2, 0]] - B
    out = np.zeros(len(pairs), dtype=bool)
    for i in range(3):
        for j in range(3):
            a = np.cross(eA[:, i], eB[:, j])[:, None, :]
            pa, pb = (A * a).sum(axis=2), (B * a).sum(axis=2)
            ea = _DOT_FILTER * np.abs(A * a).sum(axis=2)
            eb = _DOT_FILTER * np.abs(B * a).sum(axis=2)
            out |= (((pa + ea).max(axis=1) < (pb - eb).min(axis=1))
                    | ((pb + eb).max(axis=1) < (pa - ea).min(axis=1)))
    return out


def _undecided_pairs_np(V: np.ndarray, T: np.ndarray, pairs: np.ndarray, moved: np.ndarray) -> np.ndarray:
    """:func:`_undecided_pairs` with numpy (the same filters, pair arrays at a time)."""
    rows = np.nonzero(moved[T[pairs]].any(axis=(1, 2)))[0]
    for x, y in ((0, 1), (1, 0)):  # a plane of either triangle may separate them
        rows = rows[~_separated(V, T, pairs[rows, x], pairs[rows, y])]
    Ti = T[pairs[rows, 0]]
    ax = np.argmax(np.abs(np.cross(V[Ti[:, 1]] - V[Ti[:, 0]], V[Ti[:, 2]] - V[Ti[:, 0]])), axis=1)
    for step in (0, 1, 2):  # the dominant projection of the first triangle, then the others
        left = ~_apart_in_projection_np(V, T, pairs[rows], (ax + step) % 3)
        rows, ax = rows[left], ax[left]
    if len(rows):
        lone = ~(T[pairs[rows, 0]][:, :, None] == T[pairs[rows, 1]][:, None, :]).any(axis=(1, 2))
        rows = rows[~(lone & _axes_apart_np(V, T, pairs[rows]))]
    out = np.zeros(len(pairs), dtype=bool)
    out[rows] = True
    return out


def _o2f(V, u, a, b, k0, k1) -> int:
    """Sign of orient2d(u, a, b) on coordinates ``k0, k1`` of float rows of ``V``, 0 where the
    float filter cannot decide."""
    x1, y1 = V[a, k0] - V[u, k0], V[a, k1] - V[u, k1]
    x2, y2 = V[b, k0] - V[u, k0], V[b, k1] - V[u, k1]
    det = x1 * y2 - y1 * x2
    if abs(det) > _ORIENT_FILTER * (abs(x1 * y2) + abs(y1 * x2)):
        return 1 if det > 0 else -1
    return 0


def _plane_separates(V, ti, tj) -> bool:
    """Every vertex of triangle ``tj`` not shared with ``ti`` lies strictly on one side of
    the plane of ``ti`` (float filter; undecided: False): then the two triangles meet at
    most in their shared vertices and edge."""
    a, b, c = ti[0], ti[1], ti[2]
    ux, uy, uz = V[b, 0] - V[a, 0], V[b, 1] - V[a, 1], V[b, 2] - V[a, 2]
    vx, vy, vz = V[c, 0] - V[a, 0], V[c, 1] - V[a, 1], V[c, 2] - V[a, 2]
    nx, ny, nz = uy * vz - uz * vy, uz * vx - ux * vz, ux * vy - uy * vx
    side = 0
    for k in range(3):
        x = tj[k]
        if x == a or x == b or x == c:
            continue
        wx, wy, wz = V[x, 0] - V[a, 0], V[x, 1] - V[a, 1], V[x, 2] - V[a, 2]
        det = nx * wx + ny * wy + nz * wz
        perm = (abs(ux) * (abs(vy * wz) + abs(vz * wy)) + abs(uy) * (abs(vz * wx) + abs(vx * wz))
                + abs(uz) * (abs(vx * wy) + abs(vy * wx)))
        if not abs(det) > _ORIENT_FILTER * perm:
            return False
        s = 1 if det > 0 else -1
        if side != 0 and s != side:
            return False
        side = s
    return side != 0


def _ray_outside(V, u, x, p, q, k0, k1) -> bool:
    """The ray ``u -> x`` lies strictly outside the convex corner ``(p, q)`` at ``u``."""
    o = _o2f(V, u, p, q, k0, k1)
    return o != 0 and (_o2f(V, u, p, x, k0, k1) * o < 0 or _o2f(V, u, x, q, k0, k1) * o < 0)


def _dominant_axis(V, ti) -> int:
    """The coordinate axis of the largest component of triangle ``ti``'s float normal."""
    a, b, c = ti[0], ti[1], ti[2]
    ux, uy, uz = V[b, 0] - V[a, 0], V[b, 1] - V[a, 1], V[b, 2] - V[a, 2]
    vx, vy, vz = V[c, 0] - V[a, 0], V[c, 1] - V[a, 1], V[c, 2] - V[a, 2]
    n0, n1, n2 = abs(uy * vz - uz * vy), abs(uz * vx - ux * vz), abs(ux * vy - uy * vx)
    return 0 if (n0 >= n1 and n0 >= n2) else (1 if n1 >= n2 else 2)


def _axes_apart(V, ti, tj) -> bool:
    """:func:`_axes_apart_np` for one pair: strictly separated along the cross product of an
    edge of each triangle (float filter of the dot products; undecided: False)."""
    for i in range(3):
        p, q = ti[i], ti[(i + 1) % 3]
        ex, ey, ez = V[q, 0] - V[p, 0], V[q, 1] - V[p, 1], V[q, 2] - V[p, 2]
        for j in range(3):
            r, t = tj[j], tj[(j + 1) % 3]
            fx, fy, fz = V[t, 0] - V[r, 0], V[t, 1] - V[r, 1], V[t, 2] - V[r, 2]
            ax, ay, az = ey * fz - ez * fy, ez * fx - ex * fz, ex * fy - ey * fx
            lo_a = lo_b = np.inf
            hi_a = hi_b = -np.inf
            for k in range(3):
                x = ti[k]
                d = V[x, 0] * ax + V[x, 1] * ay + V[x, 2] * az
                e = _DOT_FILTER * (abs(V[x, 0] * ax) + abs(V[x, 1] * ay) + abs(V[x, 2] * az))
                lo_a, hi_a = min(lo_a, d - e), max(hi_a, d + e)
                y = tj[k]
                d = V[y, 0] * ax + V[y, 1] * ay + V[y, 2] * az
                e = _DOT_FILTER * (abs(V[y, 0] * ax) + abs(V[y, 1] * ay) + abs(V[y, 2] * az))
                lo_b, hi_b = min(lo_b, d - e), max(hi_b, d + e)
            if hi_a < lo_b or hi_b < lo_a:
                return True
    return False


def _apart_in_projection(V, ti, tj, ax) -> bool:
    """Triangles whose projections along coordinate axis ``ax`` meet only in their shared
    vertices or edge, decided by a float filter (undecided: False). The 3D triangles then
    meet only there too."""
    k0, k1 = (ax + 1) % 3, (ax + 2) % 3
    # bit r of mi / mj: vertex r of ti / tj is shared (scalars: no allocation per pair)
    mi = mj = shared = 0
    for r in range(3):
        for s in range(3):
            if ti[r] == tj[s]:
                mi |= 1 << r
                mj |= 1 << s
                shared += 1
    if shared == 0:
        # an edge line of one triangle strictly separates the other
        for flip in range(2):
            A_ = ti if flip == 0 else tj
            B_ = tj if flip == 0 else ti
            for k in range(3):
                p, q, o3 = A_[k], A_[(k + 1) % 3], A_[(k + 2) % 3]
                o = _o2f(V, p, q, o3, k0, k1)
                if o == 0:
                    continue
                out = True
                for m in range(3):
                    if not _o2f(V, p, q, B_[m], k0, k1) * o < 0:
                        out = False
                        break
                if out:
                    return True
        return False
    if shared == 2:
        # the two apexes strictly on opposite sides of the shared edge's line
        ai = ti[0] if not mi & 1 else (ti[1] if not mi & 2 else ti[2])
        aj = tj[0] if not mj & 1 else (tj[1] if not mj & 2 else tj[2])
        e0, e1 = -1, -1
        for r in range(3):
            if mi >> r & 1:
                if e0 < 0:
                    e0 = ti[r]
                else:
                    e1 = ti[r]
        u, v = min(e0, e1), max(e0, e1)
        return _o2f(V, u, v, ai, k0, k1) * _o2f(V, u, v, aj, k0, k1) < 0
    if shared == 1:
        # each edge ray at the shared vertex strictly outside the other triangle's corner
        ku = 0 if mi & 1 else (1 if mi & 2 else 2)
        kj = 0 if mj & 1 else (1 if mj & 2 else 2)
        u = ti[ku]
        pa, pb = ti[(ku + 1) % 3], ti[(ku + 2) % 3]
        pc, pd = tj[(kj + 1) % 3], tj[(kj + 2) % 3]
        return (_ray_outside(V, u, pc, pa, pb, k0, k1) and _ray_outside(V, u, pd, pa, pb, k0, k1)
                and _ray_outside(V, u, pa, pc, pd, k0, k1) and _ray_outside(V, u, pb, pc, pd, k0, k1))
    return False


def _undecided_pairs(V, T, pairs, moved) -> np.ndarray:
    """Mask of the box-overlapping pairs that the float filters leave to the exact test: a
    pair with a moved vertex that no plane separation (either way), no separation in any of
    the three coordinate projections and, for pairs with no shared vertex, no separation
    along an edge-edge cross product sets apart."""
    out = np.zeros(len(pairs), dtype=np.bool_)
    for r in range(len(pairs)):
        ti, tj = T[pairs[r, 0]], T[pairs[r, 1]]
        if not (moved[ti[0]] or moved[ti[1]] or moved[ti[2]] or moved[tj[0]] or moved[tj[1]]
                or moved[tj[2]]):
            continue
        if _plane_separates(V, ti, tj) or _plane_separates(V, tj, ti):
            continue
        ax = _dominant_axis(V, ti)
        if (_apart_in_projection(V, ti, tj, ax) or _apart_in_projection(V, ti, tj, (ax + 1) % 3)
                or _apart_in_projection(V, ti, tj, (ax + 2) % 3)):
            continue
        lone = True
        for k in range(3):
            if ti[k] == tj[0] or ti[k] == tj[1] or ti[k] == tj[2]:
                lone = False
        out[r] = not (lone and _axes_apart(V, ti, tj))
    return out


def _undecided_pairs_compiled(V, T, pairs, moved) -> np.ndarray:
    """:func:`_undecided_pairs` compiled (:mod:`cspace._kernels.trim`): identical output."""
    return _compiled.undecided_pairs(np.ascontiguousarray(V, np.float64),
                                     np.ascontiguousarray(T, np.int64),
                                     np.ascontiguousarray(pairs, np.int64).reshape(-1, 2),
                                     np.ascontiguousarray(moved, np.bool_).view(np.uint8))


def _common_integers(V: np.ndarray) -> list:
    """Float64 coordinates as Python ints at one common power-of-two scale (exact): the
    exact predicates below then run on integers."""
    ratios = [x.as_integer_ratio() for x in V.reshape(-1).tolist()]
    den = max(d for _, d in ratios)
    flat = [n * (den // d) for n, d in ratios]
    return [flat[k: k + 3] for k in range(0, len(flat), 3)]





def _segment_meets_triangle(p, q, tri, V) -> bool:
    """Does the closed segment ``pq`` meet the closed triangle ``tri`` (vertex ids)?"""
    a, b, c = (V[k] for k in tri)
    s1, s2 = _orient3(a, b, c, p), _orient3(a, b, c, q)
    if s1 * s2 > 0:
        return False
    if s1 == 0 and s2 == 0:  # coplanar
        return _coplanar_seg_tri(*_in_plane_2d([a, b, c], [p, q]))
    e = (_orient3(p, q, a, b), _orient3(p, q, b, c), _orient3(p, q, c, a))
    return all(x >= 0 for x in e) or all(x <= 0 for x in e)


def _o2(a, b, c) -> int:
    d = (b[0] - a[0]) * (c[1] - a[1]) - (b[1] - a[1]) * (c[0] - a[0])
    return (d > 0) - (d < 0)


def _coplanar_seg_tri(a, b, c, p, q) -> bool:
    if _o2(a, b, c) < 0:
        b, c = c, b
    inside = lambda x: _o2(a, b, x) >= 0 and _o2(b, c, x) >= 0 and _o2(c, a, x) >= 0  # noqa: E731
    if inside(p) or inside(q):
        return True
    for u, v in ((a, b), (b, c), (c, a)):
        o1, o2, o3, o4 = _o2(p, q, u), _o2(p, q, v), _o2(u, v, p), _o2(u, v, q)
        if o1 * o2 <= 0 and o3 * o4 <= 0 and not (o1 == o2 == o3 == o4 == 0):
            return True
        if o1 == o2 == 0 and o3 == o4 == 0 and (
            min(p[0], q[0]) <= max(u[0], v[0]) and min(u[0], v[0]) <= max(p[0], q[0])
            and min(p[1], q[1]) <= max(u[1], v[1]) and min(u[1], v[1]) <= max(p[1], q[1])
        ):
            return True
    return False


def _in_plane_2d(tri_pts, pts):
    """Exact coordinates of ``pts`` projected along the dominant axis of the exact normal of
    ``tri_pts`` (orientation-preserving projection up to one global sign)."""
    a, b, c = tri_pts
    n = _cross([b[i] - a[i] for i in range(3)], [c[i] - a[i] for i in range(3)])
    ax = max(range(3), key=lambda i: abs(n[i]))
    k = [(ax + 1) % 3, (ax + 2) % 3]
    return [[p[i] for i in k] for p in (*tri_pts, *pts)]


def _improper(V: list, s: list, t: list) -> bool:
    """Do triangles ``s`` and ``t`` (vertex ids into ``V``, exact integer coordinates of the
    rounded vertices) meet beyond the
    vertices and edge they share? A triangle that rounding made degenerate counts as
    meeting its neighbours."""
    shared = set(s) & set(t)
    if not shared:
        return any(_segment_meets_triangle(V[s[k]], V[s[(k + 1) % 3]], t, V) for k in range(3)) or any(
            _segment_meets_triangle(V[t[k]], V[t[(k + 1) % 3]], s, V) for k in range(3))
    if len(shared) == 2:
        u, v = sorted(shared)
        a = next(x for x in s if x not in shared)
        b = next(x for x in t if x not in shared)
        if _orient3(V[u], V[v], V[a], V[b]) != 0:
            return False  # two planes: they meet only along their common edge
        pu, pv, pa, pb = _in_plane_2d([V[u], V[v], V[a]], [V[b]])
        sa, sb = _o2(pu, pv, pa), _o2(pu, pv, pb)
        return sa == 0 or sb == 0 or sa == sb  # folded onto each other
    (u,) = shared
    a, b = (x for x in s if x != u)
    c, d = (x for x in t if x != u)
    if _segment_meets_triangle(V[a], V[b], t, V) or _segment_meets_triangle(V[c], V[d], s, V):
        return True
    # an edge at u lying in the other triangle's plane and pointing into its corner at u
    for x, (o0, o1) in ((a, (c, d)), (b, (c, d)), (c, (a, b)), (d, (a, b))):
        if _orient3(V[u], V[o0], V[o1], V[x]) == 0:
            pu, p0, p1, px = _in_plane_2d([V[u], V[o0], V[o1]], [V[x]])
            o = _o2(pu, p0, p1)
            if o == 0 or (_o2(pu, p0, px) * o >= 0 and _o2(pu, px, p1) * o >= 0):
                return True
    return False
