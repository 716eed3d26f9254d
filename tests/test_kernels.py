"""The compiled kernels (:mod:`cspace.geometry._kernels`) against their pure-Python references.

Each compiled kernel must give *identical* outputs (not close ones) to the reference beside
the code that calls it, on random, near-degenerate (queries exactly on vertices, edges and
faces; rays through edges) and zoo inputs: the same filter values, the same undecided rows,
the same distances bit for bit.
"""

from __future__ import annotations

import numpy as np
import pytest
from zoo import comb, l_shape, random_rotation, star, torus

from cspace.geometry._kernels import meshquery as compiled
from cspace.geometry._kernels import planar as compiled_planar
from cspace.mesh import query_reference as ref
from cspace.mesh.query import MeshCO
from cspace.mesh.self_intersection import (_undecided_pairs, _undecided_pairs_compiled,
                                           _undecided_pairs_np)
from cspace.minkowski import plane_arrangement, triangulation
from cspace.geometry.homogeneous import _hnorm, _hpoint
from cspace.minkowski.sum import minkowski_sum

MESHES = {
    "torus": lambda: torus(sections=12, ring=8),
    "star": lambda: star(),
    "comb (axis-aligned, rays through edges)": lambda: comb(3, 2),
    "turned L": lambda: (random_rotation(l_shape()[0], seed=4), l_shape()[1]),
}


def _queries(co: MeshCO, n: int, seed: int) -> np.ndarray:
    """Uniform points, vertices, edge midpoints, face centroids, and points a few ulps off
    them: the inputs where the filters cannot decide."""
    rng = np.random.default_rng(seed)
    V, T = co.vertices, co.T.reshape(-1, 3, 3)
    lo, hi = V.min(axis=0) - 0.3, V.max(axis=0) + 0.3
    k = rng.integers(0, len(T), n)
    on = [V[rng.integers(0, len(V), n)], (T[k, 0] + T[k, 1]) / 2, T[k].mean(axis=1)]
    near = [p + rng.choice([-1, 0, 1], p.shape) * np.spacing(np.abs(p) + 1.0) for p in on]
    return np.ascontiguousarray(np.vstack([rng.uniform(lo, hi, (n, 3)), *on, *near]))


@pytest.fixture(scope="module", params=list(MESHES))
def mesh(request):
    V, F = MESHES[request.param]()
    return MeshCO(V, F, name=request.param)


def test_cells_are_identical(mesh):
    g = mesh._grid
    assert compiled.cell_entries(mesh.lo, mesh.hi, *g) == ref._cell_entries(mesh.lo, mesh.hi, *g)
    s1, t1 = compiled.build_cells(mesh.lo, mesh.hi, *g)
    s2, t2 = ref._build_cells(mesh.lo, mesh.hi, *g)
    assert np.array_equal(s1, s2) and np.array_equal(t1, t2)
    for q in _queries(mesh, 20, 1):
        a = compiled.cell_candidates(q, mesh.lo, mesh.hi, mesh.cstart, mesh.ctris, *g)
        b = ref._cell_candidates(q, mesh.lo, mesh.hi, mesh.cstart, mesh.ctris, *g)
        assert np.array_equal(a, b)


def test_membership_is_identical(mesh):
    Q = _queries(mesh, 150, 2)
    outs = []
    for kernel, cast in ((compiled.contains_kernel, lambda a: a.view(np.uint8)),
                         (ref._contains_kernel, lambda a: a)):
        out, unsure = np.zeros(len(Q), bool), np.zeros(len(Q), bool)
        n = kernel(Q, mesh.T, mesh.lo, mesh.hi, mesh.sx, cast(mesh.degen), mesh.cstart,
                   mesh.ctris, *mesh._grid, cast(out), cast(unsure))
        outs.append((int(n), out, unsure))
    (n1, o1, u1), (n2, o2, u2) = outs
    assert n1 == n2 and np.array_equal(o1, o2) and np.array_equal(u1, u2)
    assert n1 > 0  # the near-degenerate queries do reach the exact path


def test_distances_are_identical_bit_for_bit(mesh):
    Q = _queries(mesh, 100, 3)
    args = (Q, mesh.T, mesh.nlo, mesh.nhi, mesh.left, mesh.right, mesh.start, mesh.count)
    a, b = np.zeros(len(Q)), np.zeros(len(Q))
    compiled.nearest_kernel(*args, a)
    ref._nearest_kernel(*args, b)
    assert np.array_equal(a.view(np.int64), b.view(np.int64))


@pytest.mark.parametrize("first_only", [True, False])
def test_segments_are_identical(mesh, first_only):
    Q = _queries(mesh, 80, 4)
    rng = np.random.default_rng(5)
    P0 = Q
    P1 = np.ascontiguousarray(np.vstack([Q[1:], Q[:1]]))
    P1[::7] = P0[::7]  # zero-length segments
    P1[1::7] = P0[1::7] + rng.normal(size=(len(P1[1::7]), 3)) * 1e-12  # very short ones
    args = (P0, P1, mesh.T, None, mesh.nlo, mesh.nhi, mesh.left, mesh.right, mesh.start,
            mesh.count, first_only)
    a = compiled.segment_kernel(*args[:3], mesh.degen.view(np.uint8), *args[4:])
    b = ref._segment_kernel(*args[:3], mesh.degen, *args[4:])
    for x, y in zip(a, b):
        assert x.dtype == y.dtype and np.array_equal(x, y)
    assert (a[0] == 2).any() or (a[0] == 1).any()


def test_compiled_queries_are_the_meshes_answers(mesh):
    # MeshCO uses the compiled kernels; its exact answers on the hard queries agree with the
    # reference kernels followed by the same exact path.
    Q = _queries(mesh, 60, 6)
    out, unsure = np.zeros(len(Q), bool), np.zeros(len(Q), bool)
    ref._contains_kernel(Q, mesh.T, mesh.lo, mesh.hi, mesh.sx, mesh.degen, mesh.cstart,
                         mesh.ctris, *mesh._grid, out, unsure)
    for i in np.nonzero(unsure)[0].tolist():
        out[i] = mesh._contains_exact(Q[i])
    assert np.array_equal(mesh.contains(Q), out)


@pytest.mark.parametrize("name", list(MESHES))
def test_rounding_check_filter_is_identical(name):
    """cspace.geometry._kernels.trim.undecided_pairs against the reference on a mesh's box-overlapping
    triangle pairs, its vertices moved by a few ulps (near-coplanar neighbours), a random
    half of them marked moved."""
    from cspace.geometry.boxes import box_pairs

    V, F = MESHES[name]()
    rng = np.random.default_rng(7)
    V = V + rng.choice([-1, 0, 1], V.shape) * np.spacing(np.abs(V) + 1.0)
    P = V[F]
    lo = np.floor(P.min(axis=1) * 64).astype(np.int64)
    hi = np.ceil(P.max(axis=1) * 64).astype(np.int64)
    pairs = np.ascontiguousarray(box_pairs(lo, hi), dtype=np.int64)
    moved = rng.random(len(V)) < 0.5
    a = _undecided_pairs_compiled(V, F, pairs, moved)
    b = _undecided_pairs(V, F, pairs, moved)
    assert len(pairs) > 100 and a.dtype == b.dtype == np.bool_
    assert np.array_equal(a, b) and np.array_equal(a, _undecided_pairs_np(V, F, pairs, moved))


# --------------------------------------------------------------------------------------------
# per-plane arrangements (cspace.geometry._kernels.planar)

_CORE_FIELDS = ("order", "vertex_labels", "edges", "edge_labels", "origin", "isolated", "nxt",
                "cycles", "cyc_of", "signs", "comp")


def _same_core(segs: list, labels: list | None = None) -> tuple:
    """Both arrangement cores on one input; every field identical (compared by name)."""
    segs = [(_hpoint(p), _hpoint(q)) for p, q in segs]
    labels = list(range(len(segs))) if labels is None else list(labels)
    a = plane_arrangement._arrangement_core(segs, labels)
    b = compiled_planar.arrangement_core(segs, labels)
    for name, x, y in zip(_CORE_FIELDS, a, b):
        assert x == y, f"{name} differs on {len(segs)} segments"
    return a


def _spy_kernel(monkeypatch, name: str) -> list:
    """Make the module that calls compiled planar kernel ``name``
    (:mod:`cspace.minkowski.plane_arrangement` or :mod:`cspace.minkowski.triangulation`) call it
    through a recorder: the list it returns fills with the (copied) arguments of every call."""
    seen = []
    real = getattr(compiled_planar, name)

    class Spy:
        def __getattr__(self, attr):  # the other kernels as they are
            return getattr(compiled_planar, attr)

    def record(*args):
        seen.append(tuple(list(a) for a in args))
        return real(*args)

    spy = Spy()
    setattr(spy, name, record)
    caller = plane_arrangement if name == "arrangement_core" else triangulation
    monkeypatch.setattr(caller, "_compiled", spy)
    return seen


def _captured_arrangements(monkeypatch, cases) -> list:
    """The inputs of every per-plane arrangement of real Minkowski sums."""
    from cspace.mesh.convex import ConvexPolytope
    from cspace.geometry.exact import Grid
    from cspace.mesh.closed import ClosedMesh

    seen = _spy_kernel(monkeypatch, "arrangement_core")
    for (v, f), b in cases:
        grid = Grid.for_points(v, b)
        minkowski_sum(ClosedMesh.from_arrays(v, f, grid=grid),
                      ConvexPolytope.from_points(b, grid=grid), workers=1)
    monkeypatch.undo()
    return seen


def test_arrangement_core_is_identical_on_minkowski_sums(monkeypatch):
    """Every arrangement of four sums with cut triangles (crossing points with large
    denominators, shared edges, collinear overlaps): the compiled core and the reference
    agree on all of them."""
    from zoo import icosphere_points

    ico = icosphere_points(1, radius=0.3)
    from zoo import grate

    cases = [(star(), ico), (torus(sections=12, ring=8), ico),
             ((random_rotation(l_shape()[0], seed=4), l_shape()[1]), ico), (grate(3), ico)]
    seen = _captured_arrangements(monkeypatch, cases)
    assert len(seen) > 100
    big = 0
    for segs, labels in seen:
        order = _same_core(segs, labels)[0]
        big += any(h[2] > 2**40 for h in order)
    assert big > 10  # the filters and the exact fallback both ran


@pytest.mark.parametrize("seed", range(3))
def test_arrangement_core_is_identical_with_many_lone_points(seed):
    """Many zero-length segments (lone points: on segments, at their ends, on nothing)
    among long axis-parallel and slanted segments on a lattice: the compiled core finds the
    segments through each point by sorted coordinates, the reference by pairs; the same
    arrangement."""
    rng = np.random.default_rng(seed)
    segs = []
    for _ in range(40):  # long horizontal, vertical and slanted segments
        a, b = rng.integers(0, 12, 2).tolist()
        kind = rng.integers(3)
        segs.append(((0, a, 1), (11, a, 1)) if kind == 0 else ((a, 0, 1), (a, 11, 1)) if kind == 1
                    else ((0, a, 1), (11, b, 1)))
    for _ in range(60):
        p = tuple(rng.integers(0, 12, 2).tolist()) + (1,)
        segs.append((p, p))
    _same_core(segs)
    w = 2**61 + 1  # non-integer points: the float filter and the exact fallback
    _same_core([((p[0] * 3, p[1] * 3, w), (q[0] * 3, q[1] * 3, w)) for p, q in segs])


@pytest.mark.parametrize("seed", range(6))
def test_arrangement_core_is_identical_on_degenerate_segments(seed):
    """Segments on a 5 x 5 integer lattice (collinear overlaps, shared endpoints, points on
    segments, zero-length segments), then the same scaled by a huge or tiny power of two and
    given homogeneous weights (the float filter ties or is skipped: exact fallback)."""
    rng = np.random.default_rng(seed)
    P = rng.integers(0, 5, (18, 2, 2)).tolist()
    segs = [(tuple(p), tuple(q)) for p, q in P]
    _same_core(segs)
    for scale, w in ((2**500, 1), (1, 2**450), (3, 2**61 + 1), (2**29 + 7, 1)):
        _same_core([((p[0] * scale, p[1] * scale, w), (q[0] * scale, q[1] * scale, w))
                    for p, q in segs])


def test_arrangement_core_is_identical_near_ties():
    """Crossing points whose rounded coordinates tie (1 / (2**60 + k)): the filter cannot
    tell them apart and the exact comparison orders them; many unrelated denominators put
    the points beyond one integer scale (``L == 0``)."""
    segs = []
    for k in range(1, 40):
        w = 2**60 + k * 1009
        segs.append(((0, 0, 1), (w + k, 1, w)))  # nearly the same direction, distinct
        segs.append(((1, 0, 1), (0, 1, 1)))
    _same_core(segs)
    assert plane_arrangement.Arrangement2D(segs)._L == 0  # no common scale
    _same_core([((0, 0, 1), (7, 3, 1)), ((0, 3, 1), (7, 0, 1)), ((14, 6, 2), (21, 9, 3))])


def _plane_jobs(v, f, b):
    from cspace.geometry.exact import Grid
    from cspace.mesh.closed import ClosedMesh
    from cspace.minkowski.arrangements import _PlaneJobs
    from cspace.minkowski.intersections import _cuts
    from cspace.minkowski.planes import _plane_groups
    from cspace.minkowski.superset import minkowski_superset

    grid = Grid.for_points(v, b)
    S = minkowski_superset(ClosedMesh.from_arrays(v, f, grid=grid), b)
    planes = _plane_groups(S)
    return _PlaneJobs(S.ints, planes, _cuts(S.ints, planes))


def _count_one_facet_calls(monkeypatch) -> dict:
    """Make the arrangements stage call the one-facet kernel through a counter: ``calls``,
    ``declined`` (returned None), ``bridged`` (read a face holding a dangling cut) and
    ``holes`` (read a face holding a closed loop of cuts)."""
    from cspace.minkowski import arrangements

    count = {"calls": 0, "declined": 0, "bridged": 0, "holes": 0}
    real = compiled_planar.one_facet_plane

    def counted(*args):
        out = real(*args)
        count["calls"] += 1
        count["declined"] += out is None
        count["bridged"] += out is not None and any(f[4] is not None for f in out[1])
        count["holes"] += out is not None and any(len(f[1]) > 1 for f in out[1])
        return out

    class Spy:
        def __getattr__(self, attr):
            return getattr(compiled_planar, attr)

    spy = Spy()
    spy.one_facet_plane = counted
    monkeypatch.setattr(arrangements, "_planar", spy)
    return count


def _same_planes(jobs) -> None:
    """Every plane arranged with the compiled steps and with their Python references."""
    from cspace.minkowski import arrangements

    todo = [p for p in range(len(jobs.members)) if not jobs.trivial(p)]
    assert [jobs.arrange(p) for p in todo] == [jobs.arrange(p, compiled=False) for p in todo]
    for p in todo:
        cut3 = jobs.cuts.segments[p]
        assert (compiled_planar.projected_segments(cut3, jobs.axis[p])
                == arrangements._projected_segments(cut3, jobs.axis[p]))


def test_plane_arrangements_are_identical_on_minkowski_sums(monkeypatch):
    """Every plane of three sums, arranged with the compiled steps (the cuts' projection, a
    one-facet plane's faces) and with their Python references: the same sub-facets, lifted
    points and vertex order."""
    from zoo import icosphere_points

    count = _count_one_facet_calls(monkeypatch)
    ico = icosphere_points(1, radius=0.3)
    for v, f in (star(), torus(sections=12, ring=8), (random_rotation(l_shape()[0], seed=4),
                                                         l_shape()[1])):
        _same_planes(_plane_jobs(v, f, ico))
    assert count["calls"] > 300


def test_the_complex_is_assembled_as_the_reference():
    """The sub-facets of every plane gathered with global vertex ids by the compiled loop and
    by its Python reference: the same vertex table, sub-facets, rings and half-edges (a sum
    with uncut triangles, cut planes, holes and bridges)."""
    from cspace.minkowski import arrangements as T
    from cspace.minkowski.intersections import _cuts
    from cspace.minkowski.planes import _plane_groups
    from cspace.minkowski.superset import minkowski_superset
    from zoo import grate, icosphere_points

    v, f = grate(3)
    S = minkowski_superset((random_rotation(v, seed=2), f), icosphere_points(1, radius=0.3))
    planes = _plane_groups(S)
    cuts = _cuts(S.ints, planes)
    got, _ = T._complex(S.ints, planes, cuts, lambda *a: None)
    ref, _ = T._complex(S.ints, planes, cuts, lambda *a: None, compiled=False)
    assert len(got.face_plane) > 500 and any(r is not None for r in got.face_rings)
    for name in got.__dataclass_fields__:
        a, b = getattr(got, name), getattr(ref, name)
        if isinstance(a, np.ndarray):
            assert a.dtype == b.dtype and np.array_equal(a, b), name
        else:
            assert a == b, name


def test_one_facet_planes_with_bridges_and_loops_are_identical(monkeypatch, shared_data):
    """The one-facet kernel reads planes whose cuts end inside the facet (a bridge in a face)
    or close a loop in it (a hole: a component held by a face of another). The small sums
    hold neither; Parasol's bug trap against a box holds bridges, against a 20-facet hull
    loops: every plane matches the Python reference."""
    from zoo import scaled_robots

    from cspace.mesh.closed import ClosedMesh

    count = _count_one_facet_calls(monkeypatch)
    trap = ClosedMesh.load(shared_data / "parasol_open_ppl_env/bug_trap1.0/trap.obj")
    robots = scaled_robots(float(np.ptp(trap.vertices, axis=0).max()))
    for robot in ("box", "hull20"):
        _same_planes(_plane_jobs(trap.vertices, trap.faces, robots[robot]))
    assert count["calls"] > 2000 and count["bridged"] >= 1 and count["holes"] >= 1


def test_one_facet_kernel_reads_dangling_cuts_and_loops():
    """A triangle (its edges labelled as pinned facet edges) with a cut across it is read by
    the kernel; a cut ending inside it (a bridge: the face's cycle runs along both of its
    sides) too, with the reference's strict inner point of that face; a closed loop of cuts
    inside it (two components) makes a face with a hole and the loop's inside; with a lone
    point (an isolated vertex) the kernel returns None and the Python path decides."""
    from cspace.geometry.homogeneous import _hom
    from cspace.minkowski.arrangements import _lift
    from cspace.minkowski.plane_arrangement import Arrangement2D, ring_sample

    tri = [((0, 0, 1), (12, 0, 1)), ((12, 0, 1), (0, 12, 1)), ((0, 12, 1), (0, 0, 1))]
    labels = [(0, 0), (0, 1), (0, 2)]
    key, ax = (0, 0, 1, 0), 2  # the plane z = 0, projected along z
    across = [((0, 3, 1), (9, 3, 1))]
    lifted, faces = compiled_planar.one_facet_faces(tri + across, labels + [(-1, 0)], 2, 7, {},
                                                    key, ax)
    assert sorted(len(r[0]) for _, r, _, _, _ in faces) == [3, 4]
    assert all(c == 2 and src == 7 and pt is None for c, _, _, src, pt in faces)
    assert [t is not None for _, r, t, _, _ in faces] == [len(r[0]) == 3 for _, r, _, _, _ in faces]
    assert all(len(p) == 4 and p[2] == 0 for p in lifted)
    dangling = [((0, 3, 1), (3, 3, 1))]
    segs = tri + dangling
    lifted, faces = compiled_planar.one_facet_faces(segs, labels + [(-1, 0)], 2, 7, {}, key, ax)
    ((c, (ring,), tris, src, point),) = faces
    assert len(ring) == 6 and tris is None  # (0, 3) twice: the cut's two sides
    arr = Arrangement2D(segs, canonical=True)
    assert point == _lift(_hom(ring_sample(arr._H, ring)), key, ax)
    X, Y, Z, W = point
    assert Z == 0 and 0 < X < 12 * W and 0 < Y and X + Y < 12 * W and Y != 3 * W
    assert compiled_planar.ring_inner_point(arr._H, ring) == _hom(ring_sample(arr._H, ring))
    loop = [((2, 2, 1), (4, 2, 1)), ((4, 2, 1), (2, 4, 1)), ((2, 4, 1), (2, 2, 1))]
    segs = tri + loop + [((2, 2, 1), (0, 0, 1))]  # the loop, and then a cut joining it to a corner
    for n_cuts in (3, 4):
        lifted, faces = compiled_planar.one_facet_faces(
            segs[:3 + n_cuts], labels + [(-1, k) for k in range(n_cuts)], 2, 7, {}, key, ax)
        arr = Arrangement2D(segs[:3 + n_cuts], canonical=True)
        assert [len(rings) for _, rings, _, _, _ in faces] == [len(f.holes) + 1 for f in arr.faces]
        assert sorted(len(rings) for _, rings, _, _, _ in faces) == ([1, 2] if n_cuts == 3 else [1, 1])
    lone = [((5, 1, 1), (5, 1, 1))]
    assert compiled_planar.one_facet_faces(tri + lone, labels + [(-1, 0)], 2, 7, {}, key,
                                           ax) is None


@pytest.mark.parametrize("big", [2**30, 2**52, 2**62, 2**200])
def test_area_signs_of_slivers_are_the_references(big):
    """Triangles of area 1/2 (and 0) with corners near ``big``: the float sum of the cycle
    cannot see the area, so the filter must leave the sign to the exact sum (a filter that
    decides on the rounded sum gives 0 or the wrong sign here)."""
    for k in range(1, 6):
        a, b = (big, big + k), (2 * big + 1, 2 * big + 2 * k + 1)
        slim = [((0, 0, 1), (*a, 1)), ((*a, 1), (*b, 1)), ((*b, 1), (0, 0, 1))]
        flat = [((0, 0, 1), (*a, 1)), ((*a, 1), (2 * a[0], 2 * a[1], 1))]
        for segs in (slim, flat, [(q, p) for p, q in slim]):
            signs = _same_core(segs)[9]
            assert sorted(signs) == ([-1, 1] if len(segs) == 3 else [0])


def test_import_compiles_nothing_and_loads_no_graph_library():
    """``import cspace`` loads no JIT compiler (numba is gone) and defers scipy.sparse (about
    0.12 s) to the first mesh that needs a graph: what a fresh process pays before its first
    query."""
    import subprocess
    import sys

    code = ("import sys, cspace\n"
            "heavy = [m for m in ('numba', 'llvmlite', 'scipy.sparse', 'Cython') "
            "if m in sys.modules]\n"
            "assert not heavy, heavy\n"
            "from cspace.geometry._kernels import meshquery, planar, trim\n")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                         timeout=120)
    assert out.returncode == 0, out.stderr


# --------------------------------------------------------------------------------------------
# triangulation steps (cspace.geometry._kernels.planar.straight_runs / clip_simple)


def _same_triangulation_steps(H: list, rings: list) -> None:
    """Both kernels against their references on one face: identical corners, runs,
    convexity and ear-clipping triangles (or both None)."""
    uses: dict = {}
    for ring in rings:
        for v in ring:
            uses[v] = uses.get(v, 0) + 1
    for ring in rings:
        r1, r2 = {}, {}
        a = triangulation._straight_runs(ring, H, r1, uses)
        b = compiled_planar.straight_runs(ring, H, r2, uses)
        assert a == b and r1 == r2
        if a[0] and len(set(a[0])) == len(a[0]):
            P = [H[v] for v in a[0]]
            assert triangulation._clip_simple(P, a[0]) == compiled_planar.clip_simple(P, a[0])


def test_triangulation_steps_are_identical_on_minkowski_sums(monkeypatch):
    """Every face triangulated in three sums (convex and non-convex faces, straight runs,
    crossing points with large denominators)."""
    from zoo import icosphere_points

    seen = []
    real = triangulation.triangulate_rings

    def spy(H, rings):
        seen.append((H, [list(r) for r in rings]))
        return real(H, rings)

    from cspace.minkowski import membership

    # faces are triangulated where an output or membership step asks (membership's import)
    monkeypatch.setattr(triangulation, "triangulate_rings", spy)
    monkeypatch.setattr(membership, "triangulate_rings", spy)
    ico = icosphere_points(1, radius=0.3)
    for (v, f), b in [(star(), ico), (comb(3, 2), ico), (torus(sections=12, ring=8), ico)]:
        from cspace.mesh.convex import ConvexPolytope
        from cspace.geometry.exact import Grid
        from cspace.mesh.closed import ClosedMesh

        grid = Grid.for_points(v, b)
        minkowski_sum(ClosedMesh.from_arrays(v, f, grid=grid),
                      ConvexPolytope.from_points(b, grid=grid), workers=1)
    monkeypatch.undo()
    assert len(seen) > 100
    for H, rings in seen:
        _same_triangulation_steps(H, rings)


@pytest.mark.parametrize("seed", range(8))
def test_triangulation_steps_are_identical_on_degenerate_polygons(seed):
    """Random star-shaped polygons with collinear runs, repeated visits, spikes and reflex
    corners, on a small lattice, then scaled far beyond 2**30 or given huge weights (the
    filters cannot decide: Python integers do) and moved by a few units at 2**60 (slivers)."""
    rng = np.random.default_rng(seed)
    n = int(rng.integers(5, 14))
    ang = np.sort(rng.uniform(0, 2 * np.pi, n))
    rad = rng.integers(1, 5, n)
    pts = [(int(round(r * np.cos(t) * 2)), int(round(r * np.sin(t) * 2))) for r, t in zip(rad, ang)]
    ring = []
    for k, p in enumerate(pts):  # insert midpoints (straight runs) on even edges
        ring.append(p)
        q = pts[(k + 1) % n]
        if k % 2 == 0 and (p[0] + q[0]) % 2 == 0 and (p[1] + q[1]) % 2 == 0:
            ring.append(((p[0] + q[0]) // 2, (p[1] + q[1]) // 2))
    uniq = list(dict.fromkeys(ring))
    for scale, w, shift in ((1, 1, 0), (2**40 + 3, 1, 0), (7, 2**61 + 1, 0), (1, 1, 2**60)):
        H = [_hnorm(x * scale + shift * w, y * scale + shift * w, w) for x, y in uniq]
        ids = [uniq.index(p) for p in ring]
        _same_triangulation_steps(H, [ids])
        _same_triangulation_steps(H, [ids[::-1]])


def test_general_ear_clipping_is_identical(monkeypatch):
    """Every polygon the general ear clipping gets in three sums (faces with holes bridged
    in: repeated vertices) and the degenerate lattice polygons, run by both."""
    from cspace.mesh.convex import ConvexPolytope
    from cspace.geometry.exact import Grid
    from cspace.mesh.closed import ClosedMesh
    from zoo import box_points, icosphere_points

    seen = _spy_kernel(monkeypatch, "clip_general")
    for (v, f), b in [(comb(3, 2), box_points(0.5, 0.5, 0.5)), (comb(4, 3), icosphere_points(1, radius=0.3)),
                      (star(), icosphere_points(1, radius=0.3))]:
        grid = Grid.for_points(v, b)
        minkowski_sum(ClosedMesh.from_arrays(v, f, grid=grid),
                      ConvexPolytope.from_points(b, grid=grid), workers=1)
    monkeypatch.undo()
    assert any(len(set(ids)) < len(ids) for _, ids in seen)  # holes were bridged in
    for P, ids in seen:
        assert compiled_planar.clip_general(P, ids) == triangulation._clip_general(P, ids)
    # a square with a square hole, bridged by hand, at huge scales (Python-integer path)
    for s, w in ((1, 1), (2**40 + 1, 1), (3, 2**61 + 1)):
        pts = [(0, 0), (8, 0), (8, 8), (0, 8), (2, 2), (2, 6), (6, 6), (6, 2)]
        H = [_hnorm(x * s, y * s, w) for x, y in pts]
        ring = [0, 1, 2, 3, 0, 4, 5, 6, 7, 4]  # outer, bridge 0 -> 4, hole clockwise, back
        P = [H[k] for k in ring]
        assert compiled_planar.clip_general(P, ring) == triangulation._clip_general(P, ring)
        assert len(triangulation._clip_general(P, ring)) == 8


def test_hole_bridging_is_identical(monkeypatch):
    """Every face with holes that three sums bridge (a grate's faces with many holes, a
    torus's), run by the compiled kernel and the reference: the same polygon and ids; and a
    square with two holes, one shadowing the other, at huge scales (Python-integer path)."""
    from cspace.mesh.convex import ConvexPolytope
    from cspace.geometry.exact import Grid
    from cspace.mesh.closed import ClosedMesh
    from zoo import box_points, grate, icosphere_points

    seen = _spy_kernel(monkeypatch, "bridge_holes")
    for (v, f), b in [(grate(3), box_points(0.3, 0.2, 0.25)),
                      (grate(2), icosphere_points(1, radius=0.2)),
                      (torus(sections=12, ring=8), box_points(0.1, 0.1, 0.1))]:
        grid = Grid.for_points(v, b)
        minkowski_sum(ClosedMesh.from_arrays(v, f, grid=grid),
                      ConvexPolytope.from_points(b, grid=grid), workers=1)
    monkeypatch.undo()
    assert any(len(pending) > 3 for _, _, pending in seen)  # faces with several holes
    for P, ids, pending in seen:
        want = triangulation._bridge_holes_reference(P, ids, pending)
        assert compiled_planar.bridge_holes(P, ids, pending) == want
    for s, w in ((1, 1), (2**40 + 1, 1), (3, 2**61 + 1)):
        def ring(pts, first):
            return [_hnorm(x * s, y * s, w) for x, y in pts], list(range(first, first + len(pts)))
        outer = ring([(0, 0), (20, 0), (20, 8), (0, 8)], 0)
        holes = [ring([(12, 2), (12, 6), (16, 6), (16, 2)], 4),
                 ring([(4, 3), (4, 5), (8, 5), (8, 3)], 8)]
        want = triangulation._bridge_holes_reference(*outer, holes)
        assert compiled_planar.bridge_holes(*outer, holes) == want
        assert len(want[0]) == 4 + 2 * 6


@pytest.mark.parametrize("n,k,leaf", [(257, 3, 3), (600, 13, 4), (5, 3, 4), (64, 3, 1)])
def test_box_tree_build_is_identical(n, k, leaf):
    """BoxTree's compiled median split against boxes._tree_reference: the same order, node
    bounds and children, with many tied centres (the selection's equal keys)."""
    from cspace.geometry.boxes import BoxTree, _tree_reference

    rng = np.random.default_rng(n + k)
    lo = rng.integers(-1000, 1000, (n, k)).astype(np.float64)
    lo[::7] = lo[0]                  # tied boxes
    lo[1::5, 0] = lo[1, 0]           # tied centres on one axis only
    hi = lo + rng.integers(0, 50, (n, k))
    t = BoxTree(lo, hi, leaf=leaf)
    for got, want in zip((t.order, t.lo, t.hi, t.first, t.count), _tree_reference(lo, hi, leaf)):
        assert np.array_equal(got, want)
    assert sorted(t.order.tolist()) == list(range(n)) and t.count.max() <= leaf


def _polytopes():
    """Convex operands of every kind of facet: aligned boxes (all planar sums), prisms and
    spheres (parallel facets and edges), random hulls, small and large coordinates, off the
    origin, and near-degenerate slivers."""
    import trimesh

    from cspace.mesh.convex import ConvexPolytope

    rng = np.random.default_rng(7)
    shapes = {
        "box": trimesh.creation.box((1.0, 2.0, 3.0)).vertices,
        "cube": trimesh.creation.box((0.3, 0.3, 0.3)).vertices,
        "ico": trimesh.creation.icosphere(1).vertices,
        "sphere": trimesh.creation.icosphere(3).vertices * 0.4,
        "cylinder": trimesh.creation.cylinder(0.5, 1.0, sections=12).vertices,
        "tetra": np.array([[0.0, 0, 0], [1, 0, 0], [0, 1, 0], [0, 0, 1]]),
        "random": rng.normal(size=(40, 3)),
        "sliver": np.array([[0.0, 0, 0], [1, 0, 0], [0, 1, 0], [0.5, 0.5, 1e-7], [1, 1, 0]]),
    }
    out = []
    for na, VA in shapes.items():
        for nb, VB in shapes.items():
            for turn in ("aligned", "about z", "random"):
                R = np.eye(3) if turn == "aligned" else (
                    random_rotation(np.eye(3), seed=3) if turn == "random" else
                    np.array([[0.0, -1, 0], [1, 0, 0], [0, 0, 1]]))
                shift = rng.normal(size=3) * (1.0 if turn != "random" else 300.0)
                out.append((f"{na}+{nb} {turn}", ConvexPolytope.from_points(VA + shift),
                            ConvexPolytope.from_points(VB @ R.T - shift)))
    return out


def test_convex_sum_kernel_is_the_reference():
    """CVMS compiled (one kernel call) against its numpy reference: the same vertices, facets
    in the same order, normals, edges, labels, kinds and provenance, on 192 operand pairs."""
    from cspace.minkowski import cvms

    for name, A, B in _polytopes():
        A, B = cvms._common_grid(A, B)
        got, want = cvms.convex_minkowski_sum(A, B), cvms._convex_minkowski_sum_reference(A, B)
        for field in ("ints", "facet_offsets", "facet_indices", "normals", "edges",
                      "edge_facets"):
            assert np.array_equal(getattr(got.polytope, field), getattr(want.polytope, field)), \
                (name, field)
        for field in ("labels", "kind", "source_a", "source_b"):
            assert np.array_equal(getattr(got, field), getattr(want, field)), (name, field)
        assert got.polytope.grid == want.polytope.grid


def test_convex_sum_kernel_leaves_what_it_cannot_hold_to_the_reference():
    """Coordinates beyond 2**40 or normals beyond 2**61: the kernel answers None (its products
    would not fit __int128) and the reference decides."""
    from cspace.geometry._kernels import convex as kernel
    from cspace.minkowski import cvms

    A = _polytopes()[0][1]
    args = (A.ints, A.facet_offsets, A.facet_indices, A.normals, A.edges, A.edge_facets)
    assert kernel.facets(*args, *args) is not None
    big = (A.ints + 2**40,) + args[1:]
    assert kernel.facets(*big, *args) is None
    wide = args[:3] + (A.normals * 2**60,) + args[4:]
    assert kernel.facets(*args, *wide) is None
    # the sum's edges as convex._edges_of finds them; facets that do not close up: the kernel
    # declines, and the reference names the error
    from cspace.errors import ExactnessError
    from cspace.mesh.convex import _edges_of_reference

    for _, P, Q in _polytopes()[::17]:
        S = cvms.convex_minkowski_sum(P, Q).polytope
        got = kernel.edges_of(S.facet_indices, S.facet_offsets, len(S.ints))
        want = _edges_of_reference(S.facet_indices, S.facet_offsets, len(S.ints), "S")
        assert np.array_equal(got[0], want[0]) and np.array_equal(got[1], want[1])
        open_ = S.facet_offsets[:-1].copy()  # the last facet dropped: a hole
        assert kernel.edges_of(S.facet_indices[:open_[-1]], open_, len(S.ints)) is None
        with pytest.raises(ExactnessError):
            _edges_of_reference(S.facet_indices[:open_[-1]], open_, len(S.ints), "S")


_POLY_FIELDS = ("ints", "facet_offsets", "facet_indices", "normals", "edges", "edge_facets")


def _same_polytope(a, b) -> bool:
    return (all(np.array_equal(getattr(a, f), getattr(b, f)) for f in _POLY_FIELDS)
            and a.grid == b.grid and a.excess == b.excess)


def _closed_meshes():
    """Closed meshes: convex ones (boxes, icospheres, random hulls, cylinders; small, large
    and off the origin; rotated so that snapping bends some), and non-convex or not exactly
    convex ones (torus, L, comb, a dented box, a box wound inwards, a box listed twice)."""
    import trimesh

    rng = np.random.default_rng(11)
    out = []
    for i in range(24):
        M = trimesh.creation.box(rng.uniform(0.01, 3.0, 3))
        if i % 3 == 1:
            M.vertices = random_rotation(M.vertices, seed=i)
        out.append((f"box {i}", M.vertices + rng.normal(size=3) * (300.0 if i % 2 else 1.0),
                    M.faces))
    for k in range(3):
        M = trimesh.creation.icosphere(k)
        out.append((f"ico{k}", M.vertices * 0.7 + [250.0, 150.0, -300.0], M.faces))
    for i in range(16):
        M = trimesh.convex.convex_hull(rng.normal(size=(int(rng.integers(5, 80)), 3)))
        out.append((f"hull {i}", M.vertices, M.faces))
    M = trimesh.creation.cylinder(0.5, 2.0, sections=24)
    out.append(("cylinder", M.vertices, M.faces))
    out += [("torus", *torus(sections=12, ring=8)), ("L", *l_shape()), ("comb", *comb(3, 2))]
    M = trimesh.creation.box((1.0, 1.0, 1.0))
    dented = M.vertices.copy()
    out.append(("inwards", dented, M.faces[:, ::-1]))
    out.append(("twice", np.vstack([dented, dented]), np.vstack([M.faces, M.faces + 8])))
    sub = M.subdivide()
    V = sub.vertices.copy()
    V[np.argmin(np.abs(V - [0.0, 0.0, 0.5]).sum(axis=1))] = [0.0, 0.0, 0.4]  # a dent
    out.append(("dented", V, sub.faces))
    return out


def test_polytope_of_a_convex_mesh_is_the_reference():
    """The compiled test of an exactly convex closed mesh against the reference (validation,
    then ``convex_within_bound``, the one definition of convex): wherever the kernel returns
    a polytope, the reference accepts the mesh with excess 0 and makes the identical polytope
    (and so does ``from_ints`` of its vertices); the kernel declines every mesh the reference
    refuses or bends, and accepts every exactly convex one here."""
    from cspace.errors import CspaceError
    from cspace.geometry.exact import Grid
    from cspace.mesh.closed import ClosedMesh
    from cspace.mesh.convex import ConvexPolytope, convex_within_bound

    accepted = declined = 0
    for name, V, F in _closed_meshes():
        grid = Grid.for_points(np.asarray(V, dtype=np.float64))
        P, inverse = np.unique(grid.snap(V), axis=0, return_inverse=True)
        G = inverse.reshape(-1)[np.asarray(F, dtype=np.int64)]
        got = ConvexPolytope.from_convex_mesh(P, G, grid=grid, name=name)
        try:
            mesh = ClosedMesh.from_arrays(grid.to_float(P), G, grid=grid, name=name)
            want, why = convex_within_bound(mesh)
        except CspaceError:
            want = None
        if got is None:
            declined += 1
            exactly = want is not None and not want.excess
            # the kernel may decline only meshes the reference's validation changes
            assert not exactly or not np.array_equal(mesh.faces, G), name
            continue
        accepted += 1
        assert want is not None and want.excess == 0, name
        assert _same_polytope(got, want), name
        assert _same_polytope(got, ConvexPolytope.from_ints(P, grid=grid, name=name)), name
    assert accepted >= 40 and declined >= 6, (accepted, declined)


def test_polytope_of_mesh_kernel_declines_what_it_cannot_hold():
    """Coordinates of 2**30 or more, an open mesh, a repeated vertex or an index out of range:
    None, and the reference decides."""
    import trimesh

    from cspace.geometry._kernels import convex as kernel

    M = trimesh.creation.box((2.0, 2.0, 2.0))
    P, F = np.rint(M.vertices).astype(np.int64), np.asarray(M.faces, dtype=np.int64)
    assert kernel.polytope_of_mesh(P, F) is not None
    assert kernel.polytope_of_mesh(P + 2**30, F) is None
    assert kernel.polytope_of_mesh(P, F[1:]) is None
    assert kernel.polytope_of_mesh(np.vstack([P, P[:1]]), F) is None
    assert kernel.polytope_of_mesh(P, np.where(F == 7, 8, F)) is None


def _point_sets():
    """Integer point sets for hulls: small coordinates with many coplanar and collinear points
    and repeats, lattice boxes with interior and face points, points on a sphere (all
    corners), coordinates near the kernel's 2**30 range, mostly-coplanar sets with one apex."""
    rng = np.random.default_rng(5)
    out = []
    for t in range(200):
        n = int(rng.integers(4, 60))
        kind = t % 5
        if kind == 0:
            P = rng.integers(-5, 6, size=(n, 3))
        elif kind == 1:
            P = rng.integers(-2**29, 2**29, size=(n, 3))
        elif kind == 2:
            P = rng.integers(0, 3, size=(n, 3)) * 7
        elif kind == 3:
            v = rng.normal(size=(n, 3))
            P = np.rint(v / np.linalg.norm(v, axis=1)[:, None] * 1000)
        else:
            P = rng.integers(-3, 4, size=(n, 3))
            P[:, 2] = P[:, 0] + P[:, 1]
            P = np.vstack([P, [[0, 0, 5]]])
        out.append(np.ascontiguousarray(P, dtype=np.int64))
    return out


def test_hull_of_points_is_the_reference():
    """The compiled hull of points (the kernel's incremental hull for few points, Qhull's
    triangles for many, each proved by ``polytope_of_mesh``) is the exact wrap's polytope,
    identically, on every set where the wrap finds a hull; where there is none (fewer than
    four distinct points, all collinear or coplanar) the kernel declines and ``from_ints``
    raises the reference's named error."""
    from cspace.errors import DegenerateError
    from cspace.geometry._kernels import convex as kernel
    from cspace.geometry.exact import Grid
    from cspace.mesh.convex import ConvexPolytope, _qhull_proposal

    grid = Grid.for_extent(2.0**31)
    proposed = 0
    for P in _point_sets():
        want = ConvexPolytope.from_ints(P, grid=grid, method="wrap")
        got = kernel.hull_of_points(P)
        assert got is not None
        assert _same_polytope(ConvexPolytope._from_kernel(got, grid=grid, name="polytope"), want)
        assert _same_polytope(ConvexPolytope.from_ints(P, grid=grid), want)
        q = _qhull_proposal(P)
        if q is not None:
            proposed += 1
            assert all(np.array_equal(a, b) for a, b in zip(q, got))
    assert proposed >= 190, proposed
    # no volume, and beyond the kernel's range
    line = np.array([[0, 0, 0], [1, 1, 1], [2, 2, 2], [3, 3, 3], [5, 5, 5]], dtype=np.int64)
    flat = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0], [1, 1, 0], [3, 2, 0]], dtype=np.int64)
    few = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0], [0, 1, 0], [0, 0, 0]], dtype=np.int64)
    for P, why in ((line, "collinear"), (flat, "coplanar"), (few, "3 distinct points")):
        assert kernel.hull_of_points(P) is None
        with pytest.raises(DegenerateError, match=why):
            ConvexPolytope.from_ints(P, grid=grid)
    cube = np.array([[a, b, c] for a in (0, 1) for b in (0, 1) for c in (0, 1)], dtype=np.int64)
    assert kernel.hull_of_points(cube + 2**30) is None
    assert _same_polytope(ConvexPolytope.from_ints(cube + 2**30, grid=grid),
                          ConvexPolytope.from_ints(cube + 2**30, grid=grid, method="wrap"))


# The exact wrap (pure Python) takes seconds a hull of ~1000 vertices: the default run
# compares it on the smaller sums, `make test-slow` on the others.
_WRAP_DEFAULT = 400


@pytest.mark.parametrize("large", [False, pytest.param(True, marks=pytest.mark.slow)])
def test_canonical_order_and_grown_polytopes_are_from_ints(large):
    """``canonical()`` of a CVMS sum is ``from_ints`` of its vertices, and ``Margin.grow`` (the
    sum with a box) is the hull of the grown points, identically; Qhull's and the exact wrap's
    hulls are the same polytope (sums of more than ``_WRAP_DEFAULT`` vertices: slow)."""
    from cspace.cobstacle.margin import Margin
    from cspace.mesh.convex import ConvexPolytope
    from cspace.minkowski import cvms

    rng = np.random.default_rng(3)
    for name, A, B in _polytopes()[::5]:
        A, B = cvms._common_grid(A, B)
        S = cvms.convex_minkowski_sum(A, B).polytope
        want = ConvexPolytope.from_ints(S.ints, grid=S.grid, name=S.name)
        assert _same_polytope(S.canonical(), want), name
        if (len(S.ints) > _WRAP_DEFAULT) == large:
            assert _same_polytope(ConvexPolytope.from_ints(S.ints, grid=S.grid, name=S.name,
                                                           method="wrap"), want), name
        steps = tuple(int(x) for x in rng.integers(1, 5000, 3))
        m = Margin(steps, (0.0, 0.0, 0.0), A.grid, 0.0, True)
        assert _same_polytope(m.grow(A), ConvexPolytope.from_ints(
            m.grow_ints(A.ints), grid=A.grid, name=A.name)), name


def test_weld_split_shortcut_is_weld_dedupe_then_split_parts(monkeypatch):
    """The compiled shortcut for exactly convex bodies gives what the two steps give, and
    every other body (open, non-convex, welded, unused vertices, repeated faces) takes them."""
    from types import SimpleNamespace

    from cspace.geometry.exact import Grid
    from cspace.mesh import components
    from cspace.mesh.components import split_parts, weld_dedupe, weld_split

    slow = []
    monkeypatch.setattr(components, "weld_dedupe",
                        lambda *a: slow.append(1) or weld_dedupe(*a))

    cases = list(_closed_meshes())
    V, F = cases[0][1], cases[0][2]
    cases += [("open", V, F[1:]), ("unused vertex", np.vstack([V, [[9.0, 9.0, 9.0]]]), F),
              ("repeated face", V, np.vstack([F, F[:1]])),
              ("welded", np.vstack([V, V[:1] + 1e-12]), np.vstack([F, [[0, 1, 8]]]))]
    for name, V, F in cases:
        body = SimpleNamespace(vertices=np.asarray(V, dtype=np.float64),
                               faces=np.asarray(F, dtype=np.int64))
        grid = Grid.for_points(body.vertices)
        got = weld_split(body, grid)
        ints, G, counts, two_sided, welded = weld_dedupe(body, grid)
        want = (ints, G, counts, two_sided, split_parts(ints, G, two_sided), welded)
        for g, w in zip(got[:2] + got[3:4] + got[5:], want[:2] + want[3:4] + want[5:]):
            assert np.array_equal(g, w), name
        assert got[2] == want[2], name
        assert len(got[4]) == len(want[4]) and all(
            np.array_equal(a, b) for a, b in zip(got[4], want[4])), name
    assert 10 <= len(slow) <= len(cases) - 30, len(slow)  # both ways were taken


def test_unique_rows_is_numpys():
    from cspace.mesh.components import unique_rows

    rng = np.random.default_rng(0)
    for n in (0, 1, 2, 7, 50, 400):
        a = rng.integers(-3, 3, (n, 3)).astype(np.int64)
        got = unique_rows(a)
        want = np.unique(a, axis=0, return_index=True, return_inverse=True)
        for g, w in zip(got, want):
            assert np.array_equal(g, np.asarray(w).reshape(g.shape)), n


@pytest.mark.parametrize("seed", range(4))
def test_component_labels_are_scipys(seed):
    """Union-find components against scipy's connected_components: the same count and the
    same labels (numbered by each component's lowest node), with repeated edges, loops,
    isolated nodes and empty graphs."""
    from cspace.geometry.graphs import _component_labels_reference, component_labels

    rng = np.random.default_rng(seed)
    for _ in range(200):
        n = int(rng.integers(0, 120))
        m = int(rng.integers(0, 3 * n + 1)) if n else 0
        a, b = rng.integers(0, max(n, 1), m), rng.integers(0, max(n, 1), m)
        a[::5] = b[::5]  # self loops
        got, want = component_labels(n, a, b), _component_labels_reference(n, a, b)
        assert got[0] == want[0] and np.array_equal(got[1], want[1])
        assert got[1].dtype == want[1].dtype


@pytest.mark.parametrize("seed", range(4))
def test_bfs_predecessors_are_scipys(seed):
    """The compiled breadth-first tree against scipy's breadth_first_order: the same
    predecessor for every node (neighbours visited in scipy's order), with repeated edges,
    loops, unreached nodes and edgeless graphs."""
    from cspace.geometry.graphs import _bfs_predecessors_reference, bfs_predecessors

    rng = np.random.default_rng(seed)
    for _ in range(200):
        n = int(rng.integers(1, 120))
        m = int(rng.integers(0, 3 * n + 1))
        a, b = rng.integers(0, n, m), rng.integers(0, n, m)
        a[::5] = b[::5]  # self loops
        start = int(rng.integers(0, n))
        got, want = bfs_predecessors(n, a, b, start), _bfs_predecessors_reference(n, a, b, start)
        assert got.dtype == want.dtype and np.array_equal(got, want)
