"""NCC-CVMS steps 2–18: the trimming driver, superset in, Minkowski-sum polyhedron out.

:func:`_trim` runs the stages in order, each in the module named for it, and times them
(``SumPolyhedron.stats``; ``progress`` gets the overall fraction):

=================  ==========================================================  =========================
stage              what                                                        module
=================  ==========================================================  =========================
``superset``       the convolution, step 1                                     :mod:`.superset`
``planes``         superset triangles grouped by exact supporting plane        :mod:`.planes`
``intersections``  candidate pairs and exact triangle-pair cuts, steps 4–5     :mod:`.intersections`
``arrangements``   one exact 2D arrangement per plane, steps 2, 3 and 6        :mod:`.arrangements`
``traversal``      sub-facet sides grouped into shells, steps 7–16             :mod:`.traversal`
``membership``     which cells are inside the sum, §3.4                        :mod:`.membership`
``output``         the facets between an inside and an outside cell            :mod:`.output`
``rounding_check`` the float64 output re-checked exactly for new intersections :mod:`.rounding`
=================  ==========================================================  =========================

:func:`_result` assembles the :class:`~cspace.minkowski.polyhedron.SumPolyhedron` (rounding,
non-manifold edges and vertices, the rounding check). How each stage differs from the paper:
``docs/trimming.md``.
"""

from __future__ import annotations

import time

import numpy as np

from ..mesh.closed import ClosedMesh
from ..mesh.convex import ConvexPolytope
from ..memory import MemoryGuard
from .arrangements import _complex
from .intersections import _cuts
from .membership import _classify, _classify_reduced
from .output import _Output, _nonmanifold, _output, _to_float_compiled
from .planes import _plane_groups
from .polyhedron import SumPolyhedron
from .rounding import _rounding_check
from .superset import (Superset, joined_supersets, minkowski_superset, on_common_step,
                       reduced_superset)
from .traversal import _shells


# --------------------------------------------------------------------------------------------
# NCC-CVMS trimming
#
# Reduction. The superset's facets that cannot hold a point of the sum's boundary (edge
# facets of reflex edges of A, corner facets that B's facet cannot support at their vertex)
# are dropped (superset.reduced_superset): they are the folds of A's concave features, most
# of the arrangement's work where B is larger than those. What is left faces out of convex
# pieces of the sum and is not a cycle. ``reduced=False`` trims the whole superset (tests).
#
# Sub-facets. Superset triangles are grouped by exact supporting plane. Each plane gets ONE
# exact 2D arrangement (cspace.minkowski.plane_arrangement) of its triangles' edges and of the segments where the
# other planes' triangles cut them (steps 4–5, cspace.geometry.tritri); every face gets its net
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
# plane of the sum in the direction of a facet normal of B). Of the reduced superset, a cell
# behind a sub-facet is inside; the others are tested exactly, as below, and also for q - B
# inside A. Of the whole superset, the winding number w of the
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


def _trim(A: ClosedMesh, B: ConvexPolytope, t0: float, progress, workers: int,
          guard: MemoryGuard, reduced: bool = True) -> SumPolyhedron:
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
    # A may be several closed bodies (touching, sharing faces, crossing): their supersets
    # joined are a superset of the union, whose boundary lies on theirs; membership is the
    # union's (a cell is inside when it is inside some body's sum).
    bodies = list(A) if isinstance(A, (list, tuple)) else [A]
    if len(bodies) > 1 and not reduced:
        raise ValueError("_trim: several bodies are trimmed with the reduced superset only")
    supersets, snapped = [], []
    stats["superset_facets"] = 0
    for body in bodies:
        Si = minkowski_superset(body, B)
        body, B = on_common_step(body, B)  # the operands as the superset snapped them
        stats["superset_facets"] += Si.n_facets
        if reduced:  # without the facets that cannot hold a point of the sum's boundary
            Si = reduced_superset(Si, body, B)
        supersets.append(Si)
        snapped.append(body)
    S = joined_supersets(supersets, snapped)
    A = snapped[0] if len(snapped) == 1 else _Bodies(snapped)
    t = lap("superset", t)
    stats["reduced_facets"] = S.n_facets

    planes = _plane_groups(S)
    t = lap("planes", t)
    stats["superset_triangles"] = len(planes.faces)
    stats["n_planes"] = len(planes.keys)

    cuts = _cuts(S.ints, planes, workers)
    t = lap("intersections", t)
    stats["candidate_pairs"] = cuts.n_pairs
    stats["cut_pairs"] = cuts.n_cut
    stats["intersection_processes"] = cuts.processes
    check = guard.check
    check("intersections", f" ({cuts.n_cut:,} cutting pairs)")

    cx, stats["arrangement_processes"] = _complex(S.ints, planes, cuts, report, workers, check)
    t = lap("arrangements", t)
    stats["subfacets"] = len(cx.face_plane)
    check("arrangements", f" ({len(cx.face_plane):,} sub-facets from {cuts.n_cut:,} cutting pairs)")

    shells = _shells(cx, planes)
    t = lap("traversal", t)
    stats["shells"] = int(shells.n)
    check("traversal", f" ({int(shells.n):,} shells)")

    inside, n_tested, anchor = (_classify_reduced if reduced else _classify)(
        cx, shells, planes, S, A, B)
    t = lap("membership", t)
    stats["membership_tests"] = n_tested

    out = _output(cx, shells, inside, anchor, planes, S)
    lap("output", t)
    stats["total"] = time.perf_counter() - t0
    result = _result(out, S, stats, workers)
    report("rounding_check", 1.0)
    return result


class _Bodies:
    """Several closed bodies on one grid as the membership test reads A: their triangles,
    one body's after another's (``ints``, ``faces``)."""

    def __init__(self, bodies: list):
        sizes = np.cumsum([0] + [len(b.ints) for b in bodies[:-1]])
        self.ints = np.vstack([b.ints for b in bodies])
        self.faces = np.vstack([b.faces + k for b, k in zip(bodies, sizes)])
        self.grid = bodies[0].grid


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
