"""The exact Minkowski sum of a closed polyhedron and a convex one: :func:`minkowski_sum`.

A is closed (possibly non-convex, any genus, several components); B is convex. Convex pairs go
through CVMS (:func:`cspace.minkowski.cvms.convex_minkowski_sum`); the others through the
superset (:func:`cspace.minkowski.superset.minkowski_superset`) and the exact trimming
(:mod:`cspace.minkowski.ncc_cvms`). A flat convex operand is thickened by one grid step (an
error that can only add collisions, counted in ``error_bound``); closed pieces meeting at
non-manifold edges or vertices are summed piece by piece (:class:`SumUnion`). Operands are
snapped onto one grid of one step (:meth:`cspace.Grid.for_operands`).
"""

from __future__ import annotations

import gc
import time
from pathlib import Path

import numpy as np

from ..errors import (DuplicateFaceError, InvalidMeshError, NonManifoldError, NotConvexError,
                      SelfIntersectionError)
from ..geometry.exact import Grid
from ..memory import MemoryGuard
from ..mesh.closed import ClosedMesh, as_mesh
from ..mesh.convex import ConvexPolytope
from ..mesh.self_intersection import self_intersections
from ..workers import worker_count
from .cvms import convex_minkowski_sum
from .ncc_cvms import _trim
from .polyhedron import SumPolyhedron, SumUnion

__all__ = ["minkowski_sum"]


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
    :func:`cspace.mesh.convex.convex_within_bound` (else None: the non-convex path), and a mesh
    that is not flat but fails validation after snapping (a needle or a plate thinner than a
    step making zero-area triangles) raises its named error. A flat mesh that is not convex
    (a flat L) raises :class:`~cspace.errors.DegenerateError`: it has no solid and is not its
    hull."""
    from ..mesh.convex import _find_tetrahedron
    from ..errors import DegenerateError

    points = _raw_points(obj, name)
    if points is not None and len(points):
        g = grid if grid is not None else Grid.for_points(points)
        ints = np.unique(g.snap(points), axis=0)
        try:
            _find_tetrahedron(ints, name)
        except DegenerateError as exc:
            if not isinstance(obj, np.ndarray):
                from ..mesh.operands import _flat_convex_mesh, _mesh_arrays

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
            from ..geometry.snapping import grow_points

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


def minkowski_sum(A, B, *, progress=None, workers: int | None = None,
                  memory=None) -> SumPolyhedron:
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
    memory : int or str, optional
        How much the build may grow this process's resident memory (bytes or a size such
        as ``"6G"``; default ``$CSPACE_MEMORY``, else half of the memory available:
        :mod:`cspace.memory`). An exact sum's size is known only as it is built (a folded
        superset: 1.2 GB for a block of 840 triangles ⊕ a 320-facet sphere), so the build
        is watched and stopped past the budget (:class:`cspace.memory.MemoryGuard`).

    Returns
    -------
    SumPolyhedron or SumUnion
        Closed and oriented; CVMS when A is convex too (``result.convex``), NCC-CVMS otherwise.
        When A is closed bodies given as one mesh that share faces, a face listed by each
        (with opposite windings) is interior to their union: the two copies cancel and the
        union's boundary is summed as one body when it is one (two welded boxes sharing a
        face). Bodies that stay apart, meeting at faces, non-manifold edges or vertices (two
        concatenated boxes, two boxes sharing an edge), give a :class:`SumUnion`: A split
        into its bodies (as it indexes its vertices, else at the non-manifold edges and
        vertices, as scenes and :meth:`cspace.CSpaceObstacle.build` split it), and the sum of
        each (their union is the sum; its surfaces overlap, see :class:`SumUnion`). When A has features thinner
        than the grid step that snap to segments or points no other face holds (a needle
        through a box), a :class:`SumUnion` too: the sum of A's other faces, and each
        feature's sum with B, the feature grown by one grid step (``stats['thin_features']``;
        within ``error_bound``: a feature is never lost to snapping).

    Raises
    ------
    InvalidMeshError
        Bad operands (open, non-manifold where it does not split into bodies, NaN, ...), a
        body of A intersecting itself (``SelfIntersectionError``, naming two triangles that
        cross), or B not convex (``NotConvexError``). Welded bodies whose shared face is
        triangulated differently on each side do not split (``NonManifoldError``): give them
        as separate vertex sets, or with the same triangles on the shared face.
    MemoryBudgetError
        The build grew past the memory budget; it stopped there and nothing is kept.
    """
    t0 = time.perf_counter()
    guard = MemoryGuard("minkowski_sum", memory)
    A, B = _loaded(A), _loaded(B)
    # Snap both operands once, on grids of one step (snapping on separate grids and then
    # re-snapping onto a common one would move points twice, beyond the stated bound).
    grid_a, grid_b = _shared_grids(A, B)
    Bc, thick_b = _convex_or_thickened(B, "B", grid_b)
    if Bc is None:
        raise NotConvexError("B must be convex (the robot of a translational C-obstacle)")
    A, thin, grid_a = _thin_features(A, grid_a)
    try:
        out = _sum_with(A, Bc, thick_b, grid_a, progress, workers, t0, guard)
    except (NonManifoldError, DuplicateFaceError, SelfIntersectionError) as exc:
        # closed pieces meeting at faces, edges or vertices, or crossing each other?
        out = _sum_of_pieces(A, Bc, thick_b, grid_a, progress, workers, exc, guard)
    return _with_thin_features(out, A, thin, Bc, thick_b, grid_a, t0) if len(thin) else out


def _thin_features(A, grid_a):
    """``(A, thin, grid)``: a mesh operand with features thinner than the grid step (faces
    that collapse to segments or points no other face holds: a needle through a box) as the
    mesh of its other faces, and those segments and points ``(k, 2, 3)`` grid integers;
    anything else unchanged with no thin feature. The grid is A's (decided here when the
    operands did not decide it, as :func:`cspace.mesh.closed.as_mesh` would)."""
    from types import SimpleNamespace

    from ..mesh.components import snapping_losses, weld_dedupe
    from ..mesh.operands import _is_mesh, _mesh_arrays

    none = np.zeros((0, 2, 3), dtype=np.int64)
    if isinstance(A, (ClosedMesh, ConvexPolytope)) or not _is_mesh(A):
        return A, none, grid_a
    V, F = _mesh_arrays(A)
    if (F.ndim != 2 or F.shape[1:] != (3,) or not len(F) or F.min() < 0 or F.max() >= len(V)
            or not np.isfinite(V[np.unique(F)]).all()):
        return A, none, grid_a  # malformed: as_mesh names what is wrong
    grid = grid_a if grid_a is not None else Grid.for_points(V[np.unique(F)])
    ints, kept, counts, _, welded = weld_dedupe(SimpleNamespace(vertices=V, faces=F), grid)
    if not counts["collapsed"]:
        return A, none, grid_a
    thin, _ = snapping_losses(len(ints), welded, kept)
    if not len(thin) or not len(kept):
        return A, none, grid_a  # nothing lost, or nothing else: the operand's own answer
    # the other faces, as given (a repeated face stays: validation names it)
    rest = np.asarray(F)[~((welded[:, 0] == welded[:, 1]) | (welded[:, 1] == welded[:, 2])
                           | (welded[:, 0] == welded[:, 2]))]
    return (V, rest), ints[thin[:, :2]], grid


def _with_thin_features(out, A, thin, Bc: ConvexPolytope, thick_b: bool, grid: Grid,
                        t0: float) -> SumUnion:
    """``out`` (the sum of A's other faces) and the sum of each thin feature with B: a
    segment or point grown by one grid step on every axis (the flat operand's rule of
    :func:`_convex_or_thickened`, within ``sqrt(3)`` steps, in each part's ``error_bound``),
    as one :class:`SumUnion`."""
    from ..geometry.snapping import grow_points
    from ..mesh.operands import _mesh_arrays

    parts = list(out.parts) if isinstance(out, SumUnion) else [out]
    pieces = list(out.pieces) if isinstance(out, SumUnion) else [_mesh_arrays(A)]
    for k, seg in enumerate(thin):
        piece = ConvexPolytope.from_ints(grow_points(np.unique(seg, axis=0), (1, 1, 1)),
                                         grid=grid, name=f"thin feature {k}")
        s = _from_convex(piece, Bc, time.perf_counter())
        s.stats["thickened_operands"] = 1 + int(thick_b)
        s.stats["hull_excess"] = Bc.excess
        parts.append(s)
        pieces.append((grid.to_float(seg), np.array([[0, 1, 1]], dtype=np.int64)))
    stats = {"parts": len(parts), "thin_features": len(thin),
             "total": time.perf_counter() - t0,
             "thickened_operands": max(p.stats.get("thickened_operands", 0) for p in parts),
             "hull_excess": max(p.stats.get("hull_excess", 0.0) for p in parts)}
    return SumUnion(tuple(parts), tuple(pieces), grid, stats)


def _sum_of_pieces(A, Bc, thick_b, grid_a, progress, workers, why, guard):
    """A that is closed bodies given as one mesh, summed as their union: faces two bodies
    share (listed by each, facing out of it) cancel as a 2-chain, leaving the union's
    boundary, summed as one body when it is one (two boxes sharing a face); else a
    :class:`SumUnion` of A split as scenes split a body (at non-manifold edges and vertices,
    into connected components: bodies that touch or cross each other; the sum of a union is
    the union of the sums). ``why`` stands when neither helps (one body crossing itself, a
    surface pinched at a vertex, a face repeated with one winding)."""
    from types import SimpleNamespace

    from ..mesh.components import cancel_opposite_faces, split_mesh, weld_dedupe
    from ..mesh.operands import _mesh_arrays

    t0 = time.perf_counter()
    if isinstance(A, ClosedMesh):
        raise why
    V, F = _mesh_arrays(A)
    grid = grid_a if grid_a is not None else Grid.for_points(V[np.unique(F)])
    ints, _, _, _, welded = weld_dedupe(SimpleNamespace(vertices=V, faces=F), grid)
    union = cancel_opposite_faces(welded)
    if union is not None:
        used, local = np.unique(union, return_inverse=True)
        try:
            return _sum_with((grid.to_float(ints[used]), local.reshape(-1, 3)), Bc, thick_b,
                             grid, progress, workers, t0, guard)
        except (NonManifoldError, SelfIntersectionError):
            V, F = grid.to_float(ints[used]), local.reshape(-1, 3)  # split what is left
        except InvalidMeshError:
            raise why from None  # the shared faces were a body's own (a double-sided face)
    pieces = _bodies_as_given(V, F, grid) or split_mesh(V, F, grid)
    if len(pieces) < 2:
        raise why
    parts = []
    for k, piece in enumerate(pieces):
        def sub(f, stage, k=k):
            if progress is not None:
                progress((k + f) / len(pieces), f"piece {k + 1} of {len(pieces)}: {stage}")
        try:
            parts.append(_sum_with(piece, Bc, thick_b, grid, sub, workers, time.perf_counter(),
                                   guard))
        except InvalidMeshError as exc:
            raise type(exc)(f"A: piece {k} of {len(pieces)} (A split at its non-manifold edges "
                            f"and vertices): {exc}") from None
    stats = {"parts": len(parts), "total": time.perf_counter() - t0,
             "thickened_operands": max(p.stats.get("thickened_operands", 0) for p in parts),
             "hull_excess": max(p.stats.get("hull_excess", 0.0) for p in parts)}
    return SumUnion(tuple(parts), tuple(pieces), grid, stats)


def _bodies_as_given(V: np.ndarray, F: np.ndarray, grid: Grid) -> list:
    """The bodies of a mesh by its own vertex indices (two boxes concatenated, sharing a
    face whose triangles differ, before welding joins them), each ``(vertices, faces)``,
    when there are several and each is a valid closed mesh on ``grid``; else []."""
    from ..geometry.graphs import component_labels

    F = np.asarray(F, dtype=np.int64)
    n, label = component_labels(len(V), F[:, 0].repeat(2), F[:, 1:].reshape(-1))
    if n < 2:
        return []
    face_label = label[F[:, 0]]
    out = []
    for c in np.unique(face_label):
        used, local = np.unique(F[face_label == c], return_inverse=True)
        body = (np.asarray(V, dtype=np.float64)[used], local.reshape(-1, 3))
        try:
            as_mesh(body, grid=grid, name="A")
        except InvalidMeshError:
            return []
        out.append(body)
    return out if len(out) > 1 else []


def _sum_with(A, Bc: ConvexPolytope, thick_b: bool, grid_a, progress, workers, t0, guard):
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
        out = _trim(A, Bc, t0, progress, worker_count(workers), guard)
        out.stats["thickened_operands"] = int(thick_b)
        out.stats["hull_excess"] = Bc.excess
        return out
    finally:
        if enabled:
            gc.enable()


def _loaded(obj):
    """A mesh file path read (:func:`cspace.mesh.files.read_mesh_file`: named errors, Collada
    in Assimp's frame) into a trimesh (no processing); a list of points into an array;
    anything else unchanged."""
    if isinstance(obj, (str, Path)):
        import trimesh

        from ..mesh.files import read_mesh_file

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
