"""NCC-CVMS trimming on hand-checkable special cases: exact volumes, holes, non-manifold
contact, change of genus, and the exact re-check of the rounded output."""

from fractions import Fraction

import numpy as np
import pytest
from zoo import box_points, genus3, voxel_solid

from cspace.mesh.self_intersection import _improper
from cspace.minkowski.sum import minkowski_sum


def _closed_and_oriented(r) -> None:
    """Every directed edge is cancelled by its reverse (also at non-manifold edges)."""
    F = r.faces
    u, v = F.reshape(-1), F[:, [1, 2, 0]].reshape(-1)
    n = len(r.vertices)
    fwd = np.unique(u * n + v, return_counts=True)
    bwd = np.unique(v * n + u, return_counts=True)
    assert np.array_equal(fwd[0], bwd[0]) and np.array_equal(fwd[1], bwd[1])


def _cube(s: float) -> np.ndarray:
    return box_points(s, s, s)


def _cavity_block(n_cavities: int) -> tuple[np.ndarray, np.ndarray]:
    """A block of unit voxels with ``n_cavities`` 3x3x3 cavities, each open to the top through
    a 1x1 channel: a 1.5 cube fits in a cavity but not through its channel."""
    occ = np.ones((4 * n_cavities + 1, 5, 5), dtype=bool)
    for k in range(n_cavities):
        occ[4 * k + 1: 4 * k + 4, 1:4, 1:4] = False
        occ[4 * k + 2, 2, 4] = False
    return voxel_solid(occ)


@pytest.mark.parametrize("n", [1, 2])
def test_polyhedral_holes(n):
    r = minkowski_sum(_cavity_block(n), _cube(1.5))
    _closed_and_oriented(r)
    assert r.n_holes == n
    # (outer box ⊕ cube) minus n eroded cavities (3 - 1.5)^3, exactly
    outer = Fraction(8 * n + 5, 2) * Fraction(13, 2) ** 2
    assert r.volume_exact == outer - n * Fraction(3, 2) ** 3
    assert r.is_manifold


def test_channel_wide_enough_leaves_no_hole():
    r = minkowski_sum(_cavity_block(1), _cube(0.5))
    _closed_and_oriented(r)
    assert r.n_holes == 0
    # the 0.5 cube passes the channel: the eroded cavity (2.5^3) and the channel's free
    # column (0.5 x 0.5 cross-section, 1.5 long: cavity top to the outside) stay open
    assert r.volume_exact == Fraction(11, 2) ** 3 - Fraction(5, 2) ** 3 - Fraction(1, 4) * Fraction(3, 2)


def test_non_manifold_edge():
    """Two columns whose sums touch along an edge (diagonal quadrants), joined higher up."""
    occ = np.zeros((3, 3, 3), dtype=bool)
    for c in [(0, 0, 0), (0, 0, 1), (0, 0, 2), (1, 0, 2), (2, 0, 2), (2, 1, 2), (2, 2, 2), (2, 2, 1), (2, 2, 0)]:
        occ[c] = True
    B = _cube(1.0)
    r = minkowski_sum(voxel_solid(occ), B)
    _closed_and_oriented(r)
    assert len(r.nonmanifold_edges) >= 1
    E = r.vertices[r.nonmanifold_edges]
    # the contact line: x = y = 2 in the A frame, shifted by B's minimum corner
    lo = B.min(axis=0)
    assert np.all(E[:, :, 0] == 2 + lo[0]) and np.all(E[:, :, 1] == 2 + lo[1])
    assert set(r.nonmanifold_edges.reshape(-1)) <= set(r.nonmanifold_vertices)
    assert r.volume_exact == 40


def test_tangential_gap_closes():
    """Two walls whose gap is exactly the robot's width: the sums touch along a face, which is
    interior to the sum (no wall is left there)."""
    occ = np.zeros((5, 3, 3), dtype=bool)
    occ[0], occ[4], occ[:, :, 0] = True, True, True
    r = minkowski_sum(voxel_solid(occ), box_points(3.0, 1.0, 1.0))
    _closed_and_oriented(r)
    assert r.is_manifold and r.n_holes == 0
    assert r.volume_exact == 8 * 4 * 4  # the box [0, 8] x [0, 4] x [0, 4]


def test_change_of_genus():
    """A genus-3 solid whose handles' holes are smaller than the robot: the sum has genus 0."""
    V, F = genus3()
    r = minkowski_sum((V, F), _cube(float(np.ptp(V, axis=0).max())))
    _closed_and_oriented(r)
    n_edges = len(np.unique(np.sort(np.stack([r.faces.reshape(-1), r.faces[:, [1, 2, 0]].reshape(-1)], 1), 1), axis=0))
    assert len(r.vertices) - n_edges + len(r.faces) == 2


def test_rounding_check_predicates():
    """The exact test behind ``rounding_self_intersections`` on integer coordinates."""
    V = [[0, 0, 0], [4, 0, 0], [0, 4, 0], [1, 1, 0], [1, 1, 5], [1, 1, -5], [9, 9, 9], [0, -4, 0]]
    assert _improper(V, [0, 1, 2], [0, 1, 3])  # shared edge, folded onto each other
    assert not _improper(V, [0, 1, 2], [0, 1, 7])  # shared edge, opposite sides
    assert not _improper(V, [0, 1, 2], [0, 1, 4])  # shared edge, two planes
    assert _improper(V, [0, 1, 2], [4, 5, 6])  # pierced
    assert _improper(V, [0, 1, 2], [0, 3, 4])  # shared vertex, edge 0-3 runs inside the corner
    assert not _improper(V, [0, 1, 2], [0, 7, 5])  # shared vertex only


@pytest.mark.parametrize("seed", range(6))
def test_rounding_filter_never_drops_an_improper_pair(seed):
    """The float filters of the rounding check (compiled and numpy) only set aside pairs the
    exact test finds proper: random triangles on a few points (shared vertices and edges, coplanar
    and crossing pairs, points a few ulps off a plane)."""
    from cspace.mesh.self_intersection import (
        _common_integers,
        _undecided_pairs,
        _undecided_pairs_compiled,
        _undecided_pairs_np,
    )

    rng = np.random.default_rng(seed)
    pool = rng.integers(0, 4, size=(14, 3)).astype(np.float64)
    pool[7:] += rng.choice([0.0, 2.0**-50, -(2.0**-51)], size=(7, 3))  # almost on the grid planes
    pool = np.unique(pool, axis=0)
    T = np.array([t for t in (rng.choice(len(pool), 3, replace=False) for _ in range(120))
                  if np.linalg.norm(np.cross(pool[t[1]] - pool[t[0]], pool[t[2]] - pool[t[0]])) > 0],
                 dtype=np.int64)
    T = T[np.unique(np.sort(T, axis=1), axis=0, return_index=True)[1]]  # no repeated triangle
    i, j = np.triu_indices(len(T), 1)
    pairs = np.stack([i, j], axis=1).astype(np.int64)
    undecided = _undecided_pairs(pool, T, pairs, np.ones(len(pool), dtype=bool))
    # the numpy filters (used for fewer pairs) and the compiled kernel decide the same pairs
    every = np.ones(len(pool), dtype=bool)
    assert np.array_equal(undecided, _undecided_pairs_np(pool, T, pairs, every))
    assert np.array_equal(undecided, _undecided_pairs_compiled(pool, T, pairs, every))
    Vi, Tl = _common_integers(pool), T.tolist()
    improper = np.array([_improper(Vi, Tl[a], Tl[b]) for a, b in pairs.tolist()])
    assert not (improper & ~undecided).any()
    assert improper.sum() > 10 and (~undecided).sum() > 10  # both kinds occur
    # no moved vertex: nothing to check
    assert not _undecided_pairs(pool, T, pairs, np.zeros(len(pool), dtype=bool)).any()


def test_provenance_matches_the_facet_normals():
    """Each output facet's normal is the normal of the feature it claims to come from:
    A's face (translated), B's facet (corner), or orthogonal to both edges (edge)."""
    from zoo import torus

    from cspace import SUPERSET_KINDS, ConvexPolytope
    from cspace.minkowski.superset import minkowski_superset

    V, F = torus(sections=16, ring=8)
    B = box_points(0.3, 0.2, 0.25)
    r = minkowski_sum((V, F), B)
    S = minkowski_superset((V, F), B)  # same operands, same grid: same feature indices
    Bp = ConvexPolytope.from_points(B, grid=r.grid)
    A_ints = np.round(V / r.grid.step).astype(np.int64)
    P = r.vertices[r.faces]
    n = np.cross(P[:, 1] - P[:, 0], P[:, 2] - P[:, 0])
    n /= np.linalg.norm(n, axis=1)[:, None]
    fk = r.facet_kind[r.face_facet]
    sa, sb = r.facet_source_a[r.face_facet], r.facet_source_b[r.face_facet]
    seen = set()
    for k, name in enumerate(SUPERSET_KINDS):
        rows = np.nonzero(fk == k)[0]
        seen.add(name) if len(rows) else None
        for i in rows:
            if name == "translated":
                a = A_ints[F[sa[i, 1]]].astype(float)
                m = np.cross(a[1] - a[0], a[2] - a[0])
                assert np.dot(m / np.linalg.norm(m), n[i]) > 1 - 1e-9
            elif name == "corner":
                m = Bp.normals[sb[i, 1]].astype(float)
                assert abs(np.dot(m / np.linalg.norm(m), n[i])) > 1 - 1e-9
            else:
                ea = S.a_edges[sa[i, 1]]
                da = A_ints[ea[1]] - A_ints[ea[0]]
                eb = Bp.edges[sb[i, 1]]
                db = Bp.ints[eb[1]] - Bp.ints[eb[0]]
                assert abs(np.dot(da / np.linalg.norm(da), n[i])) < 1e-9
                assert abs(np.dot(db / np.linalg.norm(db), n[i])) < 1e-9
    assert seen == set(SUPERSET_KINDS)


def test_operands_are_snapped_once_on_one_grid():
    """A robot larger than the obstacle makes the common grid coarser than A's own: the sum
    must be that of both operands snapped once on the common grid (found by a fuzz run: a
    second snap moved A's points, and the volume differed from libigl's by 1e-8)."""
    from zoo import cup, random_rotation

    from cspace import ConvexPolytope, Grid, as_mesh

    V, F = cup()
    V = random_rotation(V, seed=3) * 0.3
    B = np.random.default_rng(7).normal(size=(9, 3)) * 2.0
    ga, gb = Grid.for_operands(V, B)  # one step for both, each centred on itself
    assert not as_mesh((V, F)).grid.same_step(ga)  # the case that used to snap twice
    r = minkowski_sum((V, F), B)
    once = minkowski_sum(as_mesh((V, F), grid=ga), ConvexPolytope.from_points(B, grid=gb))
    assert r.grid == ga.plus(gb) and r.volume_exact == once.volume_exact


def test_forked_arrangements_give_the_same_sum(monkeypatch):
    """The triangle pairs and the per-plane arrangements run in forked workers on large
    builds; the sum must be the same, vertex for vertex and face for face, as the one built
    in this process."""
    from zoo import icosphere_points, torus

    from cspace.minkowski import arrangements, intersections

    monkeypatch.setattr(intersections, "_PARALLEL_OVERLAPS", 0)  # the pairs fork only on huge builds
    monkeypatch.setattr(arrangements, "_PARALLEL_FROM", 0)  # and the arrangements from more work
    V, F = torus()
    B = icosphere_points(2, radius=0.3)  # 51700 candidate pairs, 2300 arrangements
    one = minkowski_sum((V, F), B, workers=1)
    two = minkowski_sum((V, F), B, workers=2)
    assert one.stats["arrangement_processes"] == one.stats["intersection_processes"] == 1
    # the parallel paths really ran
    assert two.stats["arrangement_processes"] == two.stats["intersection_processes"] == 2
    assert np.array_equal(one.vertices, two.vertices) and np.array_equal(one.faces, two.faces)
    assert one.points_exact == two.points_exact and one.volume_exact == two.volume_exact
    assert np.array_equal(one.facet_source_a, two.facet_source_a)
    assert np.array_equal(one.shell, two.shell)


def test_rounding_check_in_two_processes_matches_one(monkeypatch):
    """The rounding check splits the pairs its filter leaves between processes when they
    are many; the pairs it reports are those of one process, in the same order. (Here every
    box pair with a moved vertex is left by the filter and reported, so the lists are long.)"""
    from zoo import icosphere_points, star

    from cspace.mesh import self_intersection
    from cspace.minkowski import ncc_cvms

    seen = {}
    real = ncc_cvms._rounding_check

    def capture(out, V, grid, workers=1):
        seen["args"] = (out, V, grid)
        return real(out, V, grid, workers)

    monkeypatch.setattr(ncc_cvms, "_rounding_check", capture)  # where the driver looks it up
    minkowski_sum(star(), icosphere_points(2, radius=0.3), workers=1)
    monkeypatch.setattr(self_intersection, "_improper", lambda V, s, t: True)
    monkeypatch.setattr(self_intersection, "_undecided_pairs_compiled",
                        lambda V, F, ps, moved: moved[F[ps]].any(axis=(1, 2)))
    one, n1, _ = real(*seen["args"], 1)
    two, n2, _ = real(*seen["args"], 2)
    assert (n1, n2) == (1, 2)
    assert len(one) > 100 and np.array_equal(one, two)


def _edge_incidences(A, B):
    """The sub-facet complex of A ⊕ B's superset, with its incidences grouped by edge
    (``order[start[e]: start[e] + counts[e]]``) and the oriented plane normals."""
    from cspace.minkowski.superset import minkowski_superset
    from cspace.minkowski.arrangements import _complex
    from cspace.minkowski.intersections import _cuts
    from cspace.minkowski.planes import _plane_groups

    S = minkowski_superset(A, B)
    planes = _plane_groups(S)
    cx, _ = _complex(S.ints, planes, _cuts(S.ints, planes), lambda *a: None)
    order = np.argsort(cx.inc_edge, kind="stable")
    counts = np.bincount(cx.inc_edge, minlength=len(cx.edges))
    start = np.searchsorted(cx.inc_edge[order], np.arange(len(cx.edges)))
    normal = [planes.normal(p) for p in range(len(planes.keys))]
    return cx, planes, order, counts, start, normal


def test_rounding_check_of_an_empty_output():
    """No triangles: nothing to check, in one process."""
    from cspace.geometry.exact import Grid
    from cspace.minkowski.output import _Output
    from cspace.minkowski.rounding import _rounding_check

    z = np.zeros((0, 3), np.int64)
    out = _Output(points=[], faces=z, face_facet=z[:, 0], facet_superset=z[:, 0],
                  shell=z[:, 0], shell_is_hole=np.zeros(0, bool))
    bad, used, moved = _rounding_check(out, np.zeros((0, 3)), Grid(exponent=-20), workers=2)
    assert bad.shape == (0, 2) and used == 1 and moved.shape == (0,)


def test_crossing_order_matches_the_angular_sort():
    """At edges where two planes cross, the one-sign order of the half-planes equals the
    exact angular sort (up to where the cycle starts), and it applies to most such edges."""
    from zoo import icosphere_points, torus

    from cspace.minkowski.traversal import _angular_order, _crossing_order, _edge_direction

    B = icosphere_points(1, radius=0.3)
    cx, planes, order, counts, start, normal = _edge_incidences(torus(), B)
    sign, plane_of = cx.inc_sign.tolist(), cx.face_plane[cx.inc_face].tolist()
    fast = 0
    for e in np.nonzero(counts == 4)[0].tolist():
        inc = order[start[e]: start[e] + 4].tolist()
        got = _crossing_order(cx, e, inc, sign, plane_of, normal)
        if got is None:
            continue
        fast += 1
        ns = [normal[plane_of[i]] for i in inc]
        d = _edge_direction(cx, planes, e, ns)
        ref = [inc[m] for m in _angular_order([tuple(sign[i] * c for c in n) for i, n in zip(inc, ns)], d)]
        r = ref.index(got[0])
        assert got == ref[r:] + ref[:r], e
    assert fast > 100 and fast > 0.8 * int((counts == 4).sum())


@pytest.mark.parametrize("robot", ["box", "ico80"])
def test_one_facet_planes_match_the_sampled_coverage(robot, monkeypatch):
    """A plane holding one superset facet with its whole boundary pinned takes its coverage
    from the facet without reading it per face; the sub-facets must be those of the sampled
    coverage (with its area certificate), on every such plane."""
    from zoo import icosphere_points, star

    from cspace.minkowski.superset import minkowski_superset
    from cspace.minkowski.intersections import _cuts
    from cspace.minkowski.planes import _plane_groups
    from cspace.minkowski.arrangements import _PlaneJobs

    B = box_points(0.3, 0.25, 0.2) if robot == "box" else icosphere_points(1, radius=0.3)
    S = minkowski_superset(star(), B)
    planes = _plane_groups(S)
    jobs = _PlaneJobs(S.ints, planes, _cuts(S.ints, planes))
    todo = [p for p in range(len(planes.keys)) if not jobs.trivial(p)]
    fast = [p for p in todo if jobs._one_facet(jobs.members[p])]
    assert 40 < len(fast) < len(todo)  # both paths are exercised
    got = [jobs.arrange(p) for p in fast]
    # a facet edge not pinned (not known to be in the arrangement) sends the plane back to
    # the certified path
    t = jobs.members[fast[0]][0]
    k = next(3 * t + j for j in range(3) if jobs.pinned[3 * t + j])
    jobs.pinned[k] = False
    assert not jobs._one_facet(jobs.members[fast[0]])
    jobs.pinned[k] = True
    monkeypatch.setattr(_PlaneJobs, "_one_facet", lambda self, tl: False)
    ref = [jobs.arrange(p) for p in fast]

    def untriangulated(res):  # the fast path leaves triangles to _face_tris
        lifted, faces = res
        return lifted, [(c, rings, src, point) for c, rings, _, src, point in faces]

    assert [untriangulated(r) for r in got] == [untriangulated(r) for r in ref]
    pairs = [(a[2], b[2]) for g, r in zip(got, ref) for a, b in zip(g[1], r[1])]
    assert all(a == b for a, b in pairs if a is not None)
    assert sum(a is None for a, _ in pairs) > 40


def test_crossing_orders_at_once_match_one_by_one():
    """The float-filtered orders of all two-plane crossing edges at once equal the exact
    one-sign order of each, and the filter decides nearly all of them."""
    from zoo import icosphere_points, star

    from cspace.minkowski.traversal import _crossing_order, _crossing_orders

    B = icosphere_points(1, radius=0.3)
    cx, planes, order, counts, start, normal = _edge_incidences(star(), B)
    four = np.nonzero(counts == 4)[0]
    inc = order[start[four][:, None] + np.arange(4)]
    L, slow = _crossing_orders(cx, four, inc, normal)
    sign, plane_of = cx.inc_sign.tolist(), cx.face_plane[cx.inc_face].tolist()
    ref = [_crossing_order(cx, e, row, sign, plane_of, normal)
           for e, row in zip(four.tolist(), inc.tolist())]
    assert [r for r, s in zip(ref, slow) if not s] == L.tolist()
    assert len(L) > 500 and all(r is None for r, s in zip(ref, slow) if s)


def test_lone_triangle_sub_facets_get_their_centroid():
    """Uncut lone triangles carry no arrangement point; the membership test's point for them
    is their exact centroid (on their plane, strictly inside)."""
    from zoo import torus

    from cspace.minkowski.superset import minkowski_superset
    from cspace.minkowski.arrangements import _complex, _PlaneJobs
    from cspace.minkowski.intersections import _cuts
    from cspace.minkowski.membership import _face_point
    from cspace.minkowski.planes import _plane_groups

    S = minkowski_superset(torus(), box_points(0.3, 0.25, 0.2))
    planes = _plane_groups(S)
    cuts = _cuts(S.ints, planes)
    cx, _ = _complex(S.ints, planes, cuts, lambda *a: None)
    jobs = _PlaneJobs(S.ints, planes, cuts)
    lone = [f for f in range(len(cx.face_plane)) if jobs.trivial(int(cx.face_plane[f]))]
    assert all(cx.face_point[f] is None for f in lone)
    assert len(lone) > 100
    for f in lone[:200]:
        (a, b, c), = cx.face_tris[f]
        A, B, C = (cx.points[i] for i in (a, b, c))
        assert A[3] == B[3] == C[3] == 1  # superset vertices: grid points
        X, Y, Z, W = _face_point(cx, f)
        assert [3 * x for x in (X, Y, Z)] == [W * (A[k] + B[k] + C[k]) for k in range(3)]


def _python_planes(monkeypatch) -> None:
    """Arrange every plane on the Python path (the one the patched helpers serve; the
    compiled one-facet kernel reads faces without them)."""
    from functools import partialmethod

    from cspace.minkowski.arrangements import _PlaneJobs

    monkeypatch.setattr(_PlaneJobs, "arrange", partialmethod(_PlaneJobs.arrange, compiled=False))


def test_plain_sub_facets_get_the_point_their_arrangement_would_give(monkeypatch):
    """Cut sub-facets with a plain interior carry no point; the one made when the membership
    test asks (the centroid of the first triangle, lifted) is the arrangement's own strict
    inner point."""
    from zoo import icosphere_points, star

    from cspace.minkowski import arrangements as T
    from cspace.minkowski.intersections import _cuts
    from cspace.minkowski.membership import _face_point
    from cspace.minkowski.planes import _plane_groups
    from cspace.minkowski.superset import minkowski_superset

    S = minkowski_superset(star(), icosphere_points(1, radius=0.3))
    planes = _plane_groups(S)
    cuts = _cuts(S.ints, planes)
    lazy, _ = T._complex(S.ints, planes, cuts, lambda *a: None)
    monkeypatch.setattr(T, "plain_interior", lambda arr, f: False)
    _python_planes(monkeypatch)
    eager, _ = T._complex(S.ints, planes, cuts, lambda *a: None)
    assert lazy.face_tris == eager.face_tris
    made = [f for f in range(len(lazy.face_plane))
            if lazy.face_point[f] is None and eager.face_point[f] is not None]
    assert len(made) > 500
    assert all(_face_point(lazy, f) == eager.face_point[f] for f in made)


def test_triangles_made_when_asked_are_the_arrangements_own(monkeypatch):
    """Sub-facets whose triangles were not made in their arrangement (most of them are never
    output) are triangulated from their cycles when asked: the same triangles, vertex for
    vertex, as triangulating in the arrangement."""
    from zoo import icosphere_points, star

    from cspace.minkowski import arrangements as T
    from cspace.minkowski.intersections import _cuts
    from cspace.minkowski.membership import _face_tris
    from cspace.minkowski.planes import _plane_groups
    from cspace.minkowski.superset import minkowski_superset
    from cspace.minkowski.triangulation import face_triangles

    S = minkowski_superset(star(), icosphere_points(1, radius=0.3))
    planes = _plane_groups(S)
    cuts = _cuts(S.ints, planes)
    lazy, _ = T._complex(S.ints, planes, cuts, lambda *a: None)
    monkeypatch.setattr(T, "known_triangles", face_triangles)
    _python_planes(monkeypatch)
    eager, _ = T._complex(S.ints, planes, cuts, lambda *a: None)
    assert all(t is not None for t in eager.face_tris)
    waiting = [f for f, t in enumerate(lazy.face_tris) if t is None]
    assert len(waiting) > 200
    assert all(lazy.face_rings[f] is not None for f in waiting)
    assert [_face_tris(lazy, f) for f in range(len(lazy.face_tris))] == eager.face_tris
    assert all(lazy.face_rings[f] is None for f in waiting)  # made once


def test_no_fork_beside_other_threads():
    """With another thread running, the build stays in this process (a fork would copy the
    other thread's locks in whatever state they are)."""
    import threading

    from zoo import icosphere_points, torus

    stop = threading.Event()
    t = threading.Thread(target=stop.wait)
    t.start()
    try:
        S = minkowski_sum(torus(), icosphere_points(2, radius=0.3), workers=2)
    finally:
        stop.set()
        t.join()
    assert S.stats["arrangement_processes"] == S.stats["intersection_processes"] == 1


def test_collector_state_is_restored():
    """The build pauses the cyclic garbage collector and leaves it as it found it."""
    import gc

    from zoo import l_shape

    V, F = l_shape()
    B = box_points(0.2, 0.3, 0.4)
    assert gc.isenabled()
    minkowski_sum((V, F), B)
    assert gc.isenabled()
    gc.disable()
    try:
        minkowski_sum((V, F), B)
        assert not gc.isenabled()
    finally:
        gc.enable()


@pytest.mark.slow
@pytest.mark.peers
@pytest.mark.parametrize("seed", range(12))
def test_random_operands_match_the_exact_union(seed):
    """Random small meshes (rotated or not) ⊕ random boxes, point-cloud hulls and rotated
    cubes: the exact volume equals libigl's exact CGAL union of the pieces t ⊕ B and A + b."""
    from oracles import exact_sum_volume
    from zoo import ZOO, cube_rotated, random_rotation

    from cspace import Grid

    rng = np.random.default_rng(seed)
    name = ["l_shape", "cup", "comb", "twisted_prism", "genus3", "stairs", "star"][seed % 7]
    V, F = ZOO[name][0]()
    if rng.random() < 0.5:
        V = random_rotation(V, seed=int(rng.integers(1000)))
    ext = float(np.ptp(V, axis=0).max())
    kind = seed % 3
    if kind == 0:
        B = box_points(*(rng.uniform(0.05, 0.5, 3) * ext))
    elif kind == 1:
        B = rng.normal(size=(int(rng.integers(4, 15)), 3)) * rng.uniform(0.05, 0.4) * ext
    else:
        B = cube_rotated(float(rng.uniform(0, 3)), size=float(rng.uniform(0.05, 0.6) * ext))
    r = minkowski_sum((V, F), B)
    _closed_and_oriented(r)
    ga, gb = Grid.for_operands(V, B)  # the operands as minkowski_sum snaps them
    assert r.grid == ga.plus(gb)
    ref = exact_sum_volume(ga.to_float(ga.snap(V)), F, gb.to_float(gb.snap(B)))
    assert abs(r.volume - ref) <= 1e-12 * ref
