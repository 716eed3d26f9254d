"""The exact Minkowski sum of a closed polyhedron and a convex one: :func:`minkowski_sum`.

A is closed (possibly non-convex, any genus, several components); B is convex. Convex pairs go
through CVMS (:func:`cspace.minkowski.cvms.convex_minkowski_sum`); the others through the
superset (:func:`cspace.minkowski.superset.minkowski_superset`) and the exact trimming
(:mod:`cspace.minkowski.ncc_cvms`). A flat convex operand is thickened by one grid step (an
error that can only add collisions, counted in ``error_bound``); an A that is several closed
bodies (meeting at faces, edges or vertices, crossing, or with features thinner than the grid
step) is summed as their union, one exact surface. Operands are snapped onto one grid of one
step (:meth:`cspace.Grid.for_operands`).
"""

from __future__ import annotations

import gc
import time
from dataclasses import replace
from functools import partial
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
from .polyhedron import SumPolyhedron

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
    SumPolyhedron
        Closed and oriented; CVMS when A is convex too (``result.convex``), NCC-CVMS otherwise.
        When A is several closed bodies given as one mesh, the exact boundary of the union of
        their sums (``(P1 ∪ P2) ⊕ B = (P1 ⊕ B) ∪ (P2 ⊕ B)``: one surface, its exact volume and
        holes, non-manifold where the bodies' sums touch; the bodies in ``result.pieces``,
        their sums in ``result.parts``). A face two bodies share (listed by each, with
        opposite windings) is interior and cancels: welded alike, they are one body (two
        boxes sharing a face). Otherwise A is split into its bodies as it indexes its
        vertices (two concatenated boxes), else at its non-manifold edges and vertices as
        scenes and :meth:`cspace.CSpaceObstacle.build` split it (two boxes sharing an edge).
        Features thinner than the grid step that snap to segments or points no other face
        holds (a needle through a box) are bodies too: each grown by one grid step
        (``stats['thin_features']``; within ``error_bound``: a feature is never lost to
        snapping).

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
    if not len(thin):
        try:
            return _sum_with(A, Bc, thick_b, grid_a, progress, workers, t0, guard)
        except (NonManifoldError, DuplicateFaceError, SelfIntersectionError) as exc:
            # closed bodies meeting at faces, edges or vertices, or crossing each other?
            bodies, grid_a = _bodies(A, grid_a, exc)
    else:
        bodies = [A] if isinstance(A, ClosedMesh) else None
        if bodies is None:
            try:
                bodies = [as_mesh(A, grid=grid_a, name="A")]
            except (NonManifoldError, DuplicateFaceError) as exc:
                bodies, grid_a = _bodies(A, grid_a, exc)
        bodies += _thin_bodies(thin, grid_a)
    return _sum_of_bodies(bodies, Bc, thick_b, grid_a, progress, workers, t0, guard,
                          thin=len(thin))


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


def _thin_bodies(thin: np.ndarray, grid: Grid) -> list:
    """Each thin feature (a segment or a point, grid integers) as a closed body: its hull
    grown by one grid step on every axis (the flat operand's rule of
    :func:`_convex_or_thickened`, within ``sqrt(3)`` steps: counted in ``error_bound``)."""
    from ..geometry.snapping import grow_points

    out = []
    for k, seg in enumerate(thin):
        P = ConvexPolytope.from_ints(grow_points(np.unique(seg, axis=0), (1, 1, 1)),
                                     grid=grid, name=f"thin feature {k}")
        out.append(ClosedMesh.from_arrays(P.vertices, P.faces, grid=grid,
                                          name=f"thin feature {k}"))
    return out


def _bodies(A, grid_a, why) -> tuple[list, Grid]:
    """A that is closed bodies given as one mesh, as its bodies ``(vertices, faces)``, and
    its grid: faces two bodies share (listed by each, facing out of it) cancel as a 2-chain,
    leaving the union's boundary, one body when it is one (two welded boxes sharing a face);
    else the bodies as the mesh indexes them (two concatenated boxes), else A split at its
    non-manifold edges and vertices as scenes split a body (two boxes sharing an edge).
    ``why`` stands when none of these helps (one body crossing itself, a surface pinched at
    a vertex, a face repeated with one winding)."""
    from types import SimpleNamespace

    from ..mesh.components import cancel_opposite_faces, split_mesh, weld_dedupe
    from ..mesh.operands import _mesh_arrays

    if isinstance(A, ClosedMesh):
        raise why
    V, F = _mesh_arrays(A)
    grid = grid_a if grid_a is not None else Grid.for_points(V[np.unique(F)])
    ints, _, _, _, welded = weld_dedupe(SimpleNamespace(vertices=V, faces=F), grid)
    union = cancel_opposite_faces(welded)
    if union is not None:
        used, local = np.unique(union, return_inverse=True)
        body = (grid.to_float(ints[used]), local.reshape(-1, 3))
        try:
            return [as_mesh(body, grid=grid, name="A")], grid  # validated once, kept
        except (NonManifoldError, SelfIntersectionError):
            V, F = body  # split what is left
        except InvalidMeshError:
            raise why from None  # the shared faces were a body's own (a double-sided face)
    pieces = _bodies_as_given(V, F, grid) or split_mesh(V, F, grid)
    if len(pieces) < 2:
        raise why
    return pieces, grid


def _sum_of_bodies(bodies: list, Bc: ConvexPolytope, thick_b: bool, grid: Grid, progress,
                   workers, t0: float, guard, thin: int = 0) -> SumPolyhedron:
    """The sum of A's bodies (``(vertices, faces)`` or closed meshes on ``grid``) as one
    surface: one body's sum, or the exact union's boundary (NCC-CVMS of the bodies'
    supersets joined, membership in the union: :func:`cspace.minkowski.ncc_cvms._trim`),
    with the bodies and B kept for :attr:`SumPolyhedron.parts`."""
    meshes = []
    for k, body in enumerate(bodies):
        name = f"A: body {k + 1} of {len(bodies)}" if len(bodies) > 1 else "A"
        try:
            m = body if isinstance(body, ClosedMesh) else as_mesh(body, grid=grid, name=name)
            _no_self_intersection(m)
        except InvalidMeshError as exc:
            raise type(exc)(f"{exc} (A split into {len(bodies)} closed bodies at the faces, "
                            "edges and vertices they share)") from None
        meshes.append(m)
    if len(meshes) == 1:
        return _sum_with(meshes[0], Bc, thick_b, grid, progress, workers, t0, guard)
    if not meshes[0].grid.same_step(Bc.grid):
        # one frame for every body's superset: re-snapped together, as on_common_step
        # re-snaps one body and B whose steps differ
        ga, gb = Grid.for_operands(np.vstack([m.vertices for m in meshes]), Bc.vertices,
                                   bits=min(meshes[0].grid.bits, Bc.grid.bits))
        meshes, Bc = [m.on_grid(ga) for m in meshes], Bc.on_grid(gb)
    enabled = gc.isenabled()
    gc.disable()  # as in _sum_with: the trimming's small tuples, no cycles worth a pass
    try:
        out = _trim(meshes, Bc, t0, progress, worker_count(workers), guard)
    finally:
        if enabled:
            gc.enable()
    out.stats["bodies"] = len(meshes)
    out.stats["thin_features"] = thin
    out.stats["thickened_operands"] = int(thick_b) + (1 if thin else 0)
    out.stats["hull_excess"] = Bc.excess
    return replace(out, pieces=tuple(meshes), operand_b=Bc,
                   sum_of_body=partial(minkowski_sum, B=Bc, workers=workers))


def _no_self_intersection(A: ClosedMesh) -> None:
    """SelfIntersectionError naming two triangles of A that cross, if any do."""
    crossing = self_intersections(A)
    if len(crossing):
        i, j = crossing[0].tolist()
        raise SelfIntersectionError(
            f"mesh '{A.name}' intersects itself: triangles {i} and {j} meet beyond a shared "
            f"edge or vertex ({len(crossing)} such pairs); its inside is not defined. Repair "
            "it, or model it as an open surface (a scene does: surface semantics)")


def _bodies_as_given(V: np.ndarray, F: np.ndarray, grid: Grid) -> list:
    """The bodies of a mesh by its own vertex indices (two boxes concatenated, sharing a
    face whose triangles differ, before welding joins them), each validated once as a
    :class:`ClosedMesh` on ``grid``, when there are several and each is valid; else []."""
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
            out.append(as_mesh(body, grid=grid, name=f"A: body {len(out) + 1}"))
        except InvalidMeshError:
            return []
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
    _no_self_intersection(A)
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
