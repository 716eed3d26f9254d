"""C-space obstacles (convex path): exact queries, edge cases, and FCL cross-checks.

- shipped scenes: :func:`cspace.check.cross_check.cross_check` on 10^4 samples, zero membership
  disagreements outside a 1e-9 band and distance errors below 1e-9 x scene size;
- exactness: points exactly on facets and at vertices are inside, one ulp out is outside,
  segments in a facet plane or grazing a vertex touch (not free), zero-length segments,
  NaN input;
- segments: agreement with FCL (dense sampling and the exact swept hull) on 10^3 random
  segments, and a thin wall that 1% sampling misses.
"""

from __future__ import annotations

import time
from fractions import Fraction
from pathlib import Path

import fcl
import numpy as np
import pytest
from scipy.spatial import ConvexHull

from cspace import load_scene
from cspace.mesh.convex import ConvexPolytope
from cspace.minkowski.cvms import hull_minkowski_sum
from cspace.errors import DegenerateError, NonFiniteError
from cspace.check.fcl import FclOracle
from cspace.check.cross_check import cross_check
from cspace.scene.model import CSpace
from cspace.cobstacle.obstacle import CSpaceObstacle
from cspace.scene.scene import Body, Scene
from oracles import raw_fcl_oracle, raw_mesh, raw_scene  # tests/ is on sys.path

SCENES = sorted((Path(__file__).resolve().parents[1] / "scenes").glob("*.toml"))
CUBE = np.array([[x, y, z] for x in (0, 1) for y in (0, 1) for z in (0, 1)], dtype=np.float64)


@pytest.fixture(scope="module")
def box_co() -> CSpaceObstacle:
    """Unit cube obstacle, a 0.5 cube robot with its centre as reference: CO = [-0.25, 1.25]^3."""
    return CSpaceObstacle.build(CUBE, 0.5 * CUBE, (0.25, 0.25, 0.25))


@pytest.fixture(scope="module")
def random_co() -> CSpaceObstacle:
    """A generic CO (random hulls): many edge facets with large primitive normals. Exact for
    its snapped operands (``conservative=False``): these tests check the exact machinery
    against the operands FCL gets; the outward rounding is tested on its own."""
    rng = np.random.default_rng(7)
    O, R = rng.normal(size=(40, 3)), 0.4 * rng.normal(size=(30, 3))
    return CSpaceObstacle.build(O, R, (0.1, -0.2, 0.05), conservative=False)


def _facet_points(co: CSpaceObstacle):
    """(facet index, point) pairs exactly in the relative interior of quadrilateral-or-more
    facets: the midpoint of a diagonal (the sum of two grid points is exact, /2 is exact)."""
    P = co.polytope
    out = []
    for j, f in enumerate(P.facets):
        if len(f) >= 4:
            out.append((j, (P.vertices[f[0]] + P.vertices[f[2]]) / 2))
    return out


# ---- construction --------------------------------------------------------------------


def test_build_matches_hull_baseline(random_co):
    P = random_co.polytope
    H = hull_minkowski_sum(random_co.obstacle, random_co.robot.reflected(random_co.reference_point))
    assert P.planes() == H.planes()
    assert random_co.kind == "convex" and random_co.n_facets == len(P.normals)


def test_box_co_bounds(box_co):
    np.testing.assert_array_equal(box_co.bounds, [[-0.25] * 3, [1.25] * 3])


# ---- contains: exactness edge cases ------------------------------------------------------


def test_contains_vertices_and_facets_exactly(box_co, random_co):
    for co in (box_co, random_co):
        assert co.contains(co.vertices).all()
        pts = np.array([p for _, p in _facet_points(co)])
        assert len(pts) and co.contains(pts).all()
        # Edge midpoints are on the boundary too.
        E = co.polytope.edges
        assert co.contains((co.vertices[E[:, 0]] + co.vertices[E[:, 1]]) / 2).all()


def test_contains_one_ulp_outside_a_facet(box_co, random_co):
    x = np.nextafter(1.25, 2.0)
    assert box_co.contains([1.25, 0.5, 0.5]) is True
    assert box_co.contains([x, 0.5, 0.5]) is False
    assert box_co.contains([np.nextafter(-0.25, -1.0), 1.25, 1.25]) is False
    n_checked = 0
    for j, p in _facet_points(random_co):
        n = random_co.polytope.normals[j]
        c = int(np.argmax(np.abs(n)))
        out_p, in_p = p.copy(), p.copy()
        out_p[c] = np.nextafter(p[c], np.sign(n[c]) * np.inf)
        in_p[c] = np.nextafter(p[c], -np.sign(n[c]) * np.inf)
        assert random_co.contains(p)
        assert not random_co.contains(out_p), (j, p)
        assert random_co.contains(in_p), (j, p)
        # The exact plane sign agrees.
        assert random_co.plane_signs(out_p)[0, j] == 1 and random_co.plane_signs(p)[0, j] == 0
        n_checked += 1
    assert n_checked >= 10


def test_contains_shapes_and_bool(box_co):
    assert box_co.contains(np.zeros(3)) is True
    out = box_co.contains(np.zeros((5, 3)))
    assert out.dtype == np.bool_ and out.shape == (5,)
    assert box_co.contains(np.zeros((0, 3))).shape == (0,)
    with pytest.raises(ValueError, match=r"\(3,\) or \(k, 3\)"):
        box_co.contains(np.zeros((4, 2)))


def test_contains_far_and_tiny_coordinates(box_co):
    q = np.array([[1e300, 0, 0], [-1e308, 1e308, 0], [5e-324, 0, 0], [0.5, 1e-300, -1e-300]])
    np.testing.assert_array_equal(box_co.contains(q), [False, False, True, True])


def test_nan_input_is_a_clear_error(box_co):
    q = np.zeros((5, 3))
    q[3, 1] = np.nan
    for call in (box_co.contains, box_co.signed_distance):
        with pytest.raises(NonFiniteError, match="row 3"):
            call(q)
    with pytest.raises(NonFiniteError, match="q1: row 0"):
        box_co.segment_free([0, 0, 0], [np.inf, 0, 0])
    with pytest.raises(NonFiniteError):
        box_co.first_contact([np.nan, 0, 0], [0, 0, 0])


def test_contains_matches_exact_plane_signs(random_co):
    rng = np.random.default_rng(1)
    q = rng.uniform(-3, 3, (20000, 3))
    expected = (random_co.plane_signs(q) <= 0).all(axis=1)
    np.testing.assert_array_equal(random_co.contains(q), expected)


def test_contains_throughput(random_co):
    """Reported, loosely asserted (shared machine): ~5e6/s measured on a 99-facet CO."""
    rng = np.random.default_rng(2)
    q = rng.uniform(-3, 3, (10**6, 3))
    random_co.contains(q[:1000])
    best = min(_timed(random_co.contains, q) for _ in range(3))
    rate = len(q) / best
    print(f"contains: {rate:.3g} queries/s on a {random_co.n_facets}-facet CO")
    assert rate > 2e5


def _timed(f, *args) -> float:
    t = time.perf_counter()
    f(*args)
    return time.perf_counter() - t


# ---- signed distance -----------------------------------------------------------------


def test_signed_distance_box(box_co):
    q = np.array(
        [[0.5, 0.5, 0.5], [2.0, 0.5, 0.5], [2.0, 2.0, 2.0], [1.25, 0.5, 0.5], [0.0, 0.5, 0.5]]
    )
    d = box_co.signed_distance(q)
    np.testing.assert_allclose(d, [-0.75, 0.75, np.sqrt(3) * 0.75, 0.0, -0.25], atol=1e-15)
    d = box_co.signed_distance([2.0, 1.25, 3.0])
    assert d == pytest.approx(np.hypot(0.75, 1.75), abs=1e-15)


def test_signed_distance_against_fcl(random_co):
    """Outside: FCL distance; inside: FCL's Convex-Convex signed distance (EPA depth)."""
    co = random_co
    # Two-sided exactness of the construction on its own (snapped) input: random_co is built
    # with conservative=False, so the oracle is FCL on the snapped operands (co.obstacle,
    # co.robot), not a safety check against the raw input (those use the raw arrays).
    orc = FclOracle(co.obstacle.vertices, co.obstacle.faces, co.robot.vertices, co.robot.faces,
                    co.reference_point, convex=True)
    rng = np.random.default_rng(3)
    q = rng.uniform(-3, 3, (400, 3))
    d = co.signed_distance(q)
    inside = co.contains(q)
    assert (np.sign(d[~inside]) >= 0).all() and (d[inside] <= 0).all()
    out = ~inside
    np.testing.assert_allclose(d[out], orc.distance(q[out]), atol=1e-12)
    robot = fcl.CollisionObject(orc._rgeom, fcl.Transform())
    req = fcl.DistanceRequest(enable_signed_distance=True)
    depth = []
    for p in q[inside]:
        robot.setTranslation(p)
        depth.append(fcl.distance(robot, orc._obs, req, fcl.DistanceResult()))
    np.testing.assert_allclose(d[inside], depth, atol=1e-6)


# ---- segments ------------------------------------------------------------------------


def test_segment_in_facet_plane_touches(box_co):
    # Along the facet y = 1.25: crosses the facet polygon, so it touches.
    assert box_co.segment_free([-1.0, 1.25, 0.5], [2.0, 1.25, 0.5]) is False
    assert box_co.first_contact([-1.0, 1.25, 0.5], [2.0, 1.25, 0.5]) == 0.25
    # In the plane of the facet but beside its polygon: free.
    assert box_co.segment_free([-1.0, 1.25, 2.0], [2.0, 1.25, 2.0]) is True
    # One ulp off the plane: free.
    y = np.nextafter(1.25, 2.0)
    assert box_co.segment_free([-1.0, y, 0.5], [2.0, y, 0.5]) is True
    assert np.isnan(box_co.first_contact([-1.0, y, 0.5], [2.0, y, 0.5]))


def test_segment_in_generic_facet_plane(random_co):
    P = random_co.polytope
    n_checked = 0
    for j, p in _facet_points(random_co):
        f = P.facets[j]
        a, b = P.vertices[f[0]], P.vertices[f[2]]
        # The facet's diagonal extended beyond both ends (exact: 2a - p and 2b - p are
        # sums of grid points) lies in the facet plane.
        q0, q1 = 2 * a - p, 2 * b - p
        assert random_co.segment_free(q0, q1) is False
        assert random_co.first_contact(q0, q1) == 0.25
        n_checked += 1
    assert n_checked >= 10


def test_zero_length_segments(box_co, random_co):
    rng = np.random.default_rng(4)
    for co in (box_co, random_co):
        q = np.vstack([rng.uniform(-2, 2, (500, 3)), co.vertices])
        np.testing.assert_array_equal(co.segment_free(q, q), ~co.contains(q))
        t = co.first_contact(q, q)
        np.testing.assert_array_equal(np.isnan(t), ~co.contains(q))
        assert (t[~np.isnan(t)] == 0.0).all()


def test_segment_grazing_a_vertex(box_co):
    v = np.array([-0.25, -0.25, -0.25])
    q0, q1 = v + [-1.0, 1.0, 0.0], v + [1.0, -1.0, 0.0]
    assert box_co.segment_free(q0, q1) is False
    assert box_co.first_contact(q0, q1) == 0.5
    z = np.nextafter(-0.25, -1.0)
    assert box_co.segment_free(q0 + [0, 0, z + 0.25], q1 + [0, 0, z + 0.25]) is True
    # Ending exactly at a vertex.
    assert box_co.first_contact(v - 1.0, v) == 1.0
    # Grazing an edge along a diagonal of a facet's plane.
    assert box_co.segment_free([-1.0, -0.25, -0.25 - 0.75], [0.5, -0.25, 0.5]) is False


def test_first_contact_is_the_rounded_exact_entry(random_co):
    rng = np.random.default_rng(5)
    a, b = rng.uniform(-3, 3, (300, 3)), rng.uniform(-3, 3, (300, 3))
    t = random_co.first_contact(a, b)
    free = random_co.segment_free(a, b)
    np.testing.assert_array_equal(np.isnan(t), free)
    for i in np.nonzero(~free)[0]:
        exact = random_co._impl._exact_segment(a[i], b[i])
        assert isinstance(exact, Fraction) and t[i] == float(exact)
        # Just before the entry the point is outside (unless the start is inside).
        if t[i] > 0:
            s = np.nextafter(t[i], 0.0) * 0.999999
            assert not random_co.contains(a[i] + s * (b[i] - a[i]))


def _swept_hit(orc: FclOracle, a, b) -> bool:
    V = orc.robot_vertices
    P = np.vstack([V + a, V + b])
    h = ConvexHull(P)
    flat = np.hstack([np.full((len(h.simplices), 1), 3), h.simplices]).ravel()
    sweep = fcl.CollisionObject(fcl.Convex(P, len(h.simplices), flat))
    return fcl.collide(sweep, orc._obs) > 0


def test_segment_free_against_fcl(random_co):
    co = random_co
    # Exactness on its own input (conservative=False, snapped operands), both sides; the
    # safety of segments against the raw input: test_thin_wall_caught_where_sampling_misses.
    orc = FclOracle(co.obstacle.vertices, co.obstacle.faces, co.robot.vertices, co.robot.faces,
                    co.reference_point, convex=True)
    rng = np.random.default_rng(6)
    a = rng.uniform(-3, 3, (1000, 3))
    b = a + rng.normal(size=(1000, 3)) * 1.0
    free = co.segment_free(a, b)
    ts = np.linspace(0.0, 1.0, 200)
    sampled = np.array(
        [orc.collides(a[i] + ts[:, None] * (b[i] - a[i])).any() for i in range(len(a))]
    )
    swept = np.array([_swept_hit(orc, a[i], b[i]) for i in range(len(a))])
    # Sampling can only miss collisions; the swept hull is exact up to FCL's float error.
    assert not (sampled & free).any()
    bad = np.nonzero(swept == free)[0]
    assert bad.size == 0, (bad, a[bad], b[bad])
    assert 100 < (~free).sum() < 900


def test_thin_wall_caught_where_sampling_misses():
    wall = np.array([[x, y, z] for x in (0.0, 0.001) for y in (-1.0, 1.0) for z in (-1.0, 1.0)])
    robot = 2e-4 * CUBE
    co = CSpaceObstacle.build(wall, robot, (1e-4, 1e-4, 1e-4))
    q0, q1 = np.array([-0.5, 0.0, 0.0]), np.array([0.5053, 0.0, 0.0])
    # FCL on the raw wall and robot the test built from (not the C-obstacle's snapped copies).
    orc = raw_fcl_oracle(wall, robot, (1e-4, 1e-4, 1e-4), convex=True)
    ts = np.linspace(0.0, 1.0, 101)  # 1% resolution
    assert not orc.collides(q0 + ts[:, None] * (q1 - q0)).any()  # sampling says free
    assert co.segment_free(q0, q1) is False  # exact: the wall is crossed
    t = co.first_contact(q0, q1)
    # Entry where the reference point reaches the CO's face x = xmin (snapped operands).
    xmin = Fraction(float(co.bounds[0, 0]))
    assert t == float((xmin - Fraction(q0[0])) / (Fraction(q1[0]) - Fraction(q0[0])))
    assert _swept_hit(orc, q0, q1)
    # Safe against the raw input: the raw wall is not met before the reported entry, and is
    # met within the stated error bound after it.
    L = float(np.linalg.norm(q1 - q0))
    u = (q1 - q0) / L
    assert not orc.collides(q0 + (t * L - np.array([1e-9, 1e-6, 1e-3]))[:, None] * u).any()
    assert orc.collides(q0 + (t * L + co.error_bound + 1e-12) * u)[0]


def test_vectorised_equals_scalar(random_co):
    rng = np.random.default_rng(8)
    a, b = rng.uniform(-3, 3, (50, 3)), rng.uniform(-3, 3, (50, 3))
    free = random_co.segment_free(a, b)
    assert [random_co.segment_free(a[i], b[i]) for i in range(50)] == free.tolist()
    # Broadcasting one start against many ends.
    np.testing.assert_array_equal(
        random_co.segment_free(a[0], b), [random_co.segment_free(a[0], x) for x in b]
    )


# ---- CSpace and scenes -----------------------------------------------------------------


def test_cspace_combines_obstacles(box_co, random_co):
    cs = CSpace([box_co, random_co])
    rng = np.random.default_rng(9)
    q = rng.uniform(-3, 3, (2000, 3))
    np.testing.assert_array_equal(cs.contains(q), box_co.contains(q) | random_co.contains(q))
    np.testing.assert_array_equal(
        cs.signed_distance(q), np.minimum(box_co.signed_distance(q), random_co.signed_distance(q))
    )
    a, b = q[:500], q[500:1000]
    np.testing.assert_array_equal(
        cs.segment_free(a, b), box_co.segment_free(a, b) & random_co.segment_free(a, b)
    )
    np.testing.assert_array_equal(
        cs.first_contact(a, b), np.fmin(box_co.first_contact(a, b), random_co.first_contact(a, b))
    )


def test_from_scene_splits_a_body_into_its_convex_parts():
    # One scene body made of two disjoint boxes: modelled as two convex bodies (model_scene).
    two = np.vstack([CUBE, CUBE + [3.0, 0, 0]])
    F = ConvexPolytope.from_points(CUBE).faces
    body = Body("two-boxes", two, np.vstack([F, F + 8]), "test")
    robot = Body("robot", 0.5 * CUBE, F, "test")
    scene = Scene("nc", None, (body,), robot, (0.25, 0.25, 0.25), [[-2, -2, -2], [6, 3, 3]],
                  [-1.0, -1, -1], [5.0, 2, 2])
    cs = CSpace.from_scene(scene)
    assert [o.kind for o in cs.obstacles] == ["convex", "convex"]
    first = CSpaceObstacle.build(CUBE, 0.5 * CUBE, (0.25, 0.25, 0.25))
    second = CSpaceObstacle.build(CUBE + [3.0, 0, 0], 0.5 * CUBE, (0.25, 0.25, 0.25))
    q = np.random.default_rng(0).uniform([-2, -2, -2], [6, 3, 3], (2000, 3))
    np.testing.assert_array_equal(cs.contains(q), first.contains(q) | second.contains(q))


@pytest.mark.parametrize("path", SCENES, ids=[p.stem for p in SCENES])
def test_shipped_scene_cross_check(path):
    cs = CSpace.from_scene(load_scene(path))
    report = cross_check(cs, n=10_000, seed=0, band=1e-9)
    assert report["n"] == 10_000
    assert report["n_disagree"] == 0, report["disagreements"][:10]
    assert report["max_distance_error"] <= 1e-9 * report["scene_size"]
    # The samples cover both sides; FCL's own tolerance only shows within the band.
    assert 1000 < report["n_inside"] < 9000
    assert report["n_in_band"] < 100


def test_cross_check_single_obstacle(random_co):
    # Two-sided exactness of the construction on its own input (random_co:
    # conservative=False, so the snapped operands are its input), judged by the scene oracle
    # with its own semantics (Qhull hulls as solids), not by what co.kind says.
    co = random_co
    scene = raw_scene((co.obstacle.vertices, co.obstacle.faces),
                      (co.robot.vertices, co.robot.faces), co.reference_point)
    report = cross_check(co, n=2000, seed=1, scene=scene)
    assert report["oracle"] == "scene"
    assert report["ok"] and report["n_disagree"] == 0
    assert report["max_distance_error"] <= 1e-12
    assert report["seconds_per_query_ours"] > 0 and report["seconds_per_query_fcl"] > 0
    assert report["disagreements"].shape == (0, 3)


def test_build_from_meshes_and_polytopes():
    import trimesh

    box = trimesh.creation.box(extents=[1.0, 1.0, 1.0])
    small = trimesh.creation.box(extents=[0.5, 0.5, 0.5])
    a = CSpaceObstacle.build(box, small)
    pair = (np.asarray(box.vertices), np.asarray(box.faces))
    b = CSpaceObstacle.build(pair, np.asarray(small.vertices))
    c = CSpaceObstacle.build(
        ConvexPolytope.from_points(box.vertices), ConvexPolytope.from_points(small.vertices)
    )
    assert a.polytope.planes() == b.polytope.planes()
    np.testing.assert_array_equal(a.bounds, c.bounds)
    np.testing.assert_array_equal(a.bounds, [[-0.75] * 3, [0.75] * 3])


def test_segments_with_huge_coordinates(box_co):
    q0 = np.array([[-1e300, 0.5, 0.5], [-1e308, 0.5, 0.5], [-1e308, 1e308, 0.5]])
    q1 = np.array([[1e300, 0.5, 0.5], [1e308, 0.5, 0.5], [1e308, -1e308, 0.5]])
    np.testing.assert_array_equal(box_co.segment_free(q0, q1), [False, False, False])
    assert box_co.segment_free([-1e308, 5.0, 0.5], [1e308, 5.0, 0.5]) is True


def test_segments_match_exact_reference_on_degenerate_inputs(random_co):
    """Filter + fallback against the pure rational reference, on segments the filter finds
    hard: between CO vertices, edge midpoints and facet points, and from them outwards."""
    co = random_co
    rng = np.random.default_rng(10)
    V = co.vertices
    E = co.polytope.edges
    special = np.vstack([V, (V[E[:, 0]] + V[E[:, 1]]) / 2, [p for _, p in _facet_points(co)]])
    i, j = rng.integers(0, len(special), (2, 1500))
    a = special[i]
    b = np.where(rng.random((1500, 1)) < 0.5, special[j], 2 * special[i] - special[j])
    free = co.segment_free(a, b)
    t = co.first_contact(a, b)
    for r in range(len(a)):
        ref = co._impl._exact_segment(a[r], b[r])
        assert free[r] == (ref is None)
        assert (np.isnan(t[r]) and ref is None) or t[r] == float(ref)
    # Every special point is on the boundary: no such segment is free.
    assert not free.any()


def _fraction_contains(co: CSpaceObstacle, q) -> bool:
    """Independent reference: every facet inequality in exact rationals."""
    step = Fraction(2) ** co.grid.exponent
    P = co.polytope
    first = P.ints[P.facet_indices[P.facet_offsets[:-1]]]
    qf = [Fraction(float(x)) for x in q]
    for n, p in zip(P.normals.tolist(), first.tolist()):
        d = sum(a * b for a, b in zip(n, p))
        if sum(a * x for a, x in zip(n, qf)) > d * step:
            return False
    return True


def test_contains_against_rationals_near_the_boundary(random_co):
    rng = np.random.default_rng(11)
    pts = np.array([p for _, p in _facet_points(random_co)] + list(random_co.vertices))
    base = pts[rng.integers(0, len(pts), 400)]
    # A few ulps away in random directions, per coordinate.
    k = rng.integers(-3, 4, base.shape)
    q = base.copy()
    for _ in range(3):
        q = np.where(k > 0, np.nextafter(q, np.inf), np.where(k < 0, np.nextafter(q, -np.inf), q))
        k = k - np.sign(k)
    ours = random_co.contains(q)
    ref = np.array([_fraction_contains(random_co, x) for x in q])
    np.testing.assert_array_equal(ours, ref)
    assert ours.any() and not ours.all()


@pytest.mark.parametrize("scale", [1e-6, 3.0, 1e9])
def test_exact_at_any_scale(scale):
    """Grid steps below and above 1 (ldexp scaling of the queries both ways)."""
    co = CSpaceObstacle.build(scale * CUBE, 0.5 * scale * CUBE, (0.25 * scale,) * 3)
    hi = co.bounds[1, 0]
    mid = co.vertices.mean(axis=0)
    assert co.contains(co.vertices).all()
    assert co.contains([hi, mid[1], mid[2]]) is True
    assert co.contains([np.nextafter(hi, np.inf), mid[1], mid[2]]) is False
    q0 = np.array([-2 * scale, hi, mid[2]])
    q1 = np.array([3 * scale, hi, mid[2]])
    assert co.segment_free(q0, q1) is False
    y = np.nextafter(hi, np.inf)
    assert co.segment_free([-2 * scale, y, mid[2]], [3 * scale, y, mid[2]]) is True
    d = co.signed_distance([hi + scale, mid[1], mid[2]])
    assert d == pytest.approx(scale, rel=1e-14)


@pytest.mark.parametrize("case", ["panel robot", "rod robot", "panel obstacle", "triangle robot"])
def test_flat_convex_operands_against_fcl(case):
    # A panel, a rod or a triangle (coplanar or collinear points) is a flat convex operand:
    # against a convex one the C-obstacle is the exact hull of the pairwise sums, and FCL
    # (the flat one a surface, the other a solid) agrees.
    import trimesh

    from cspace.check.cross_check import cross_check

    box = trimesh.creation.box((1.0, 1.0, 1.0)).vertices
    flat = {"panel robot": [[0, 0, 0], [0.6, 0, 0], [0.6, 0.4, 0], [0, 0.4, 0]],
            "rod robot": [[0, 0, 0], [0.3, 0.2, 0.1]],
            "panel obstacle": [[0, 0, 0], [0.6, 0, 0], [0.6, 0.4, 0], [0, 0.4, 0]],
            "triangle robot": [[0, 0, 0], [0.5, 0.1, 0.2], [0.1, 0.4, -0.3]]}[case]
    flat = np.array(flat, dtype=np.float64)
    o, r = (flat, box) if case == "panel obstacle" else (box, flat)
    co = CSpaceObstacle.build(o, r, (0.05, 0.0, 0.0))
    assert co.kind == "convex"
    # FCL judges the raw operands (a scene of them, SceneOracle: the box its float hull, a
    # solid; the flat one its raw triangles, a surface), not the C-obstacle's snapped copies.
    report = cross_check(co, n=4000, seed=3,
                         scene=raw_scene(_flat_mesh(o), _flat_mesh(r), (0.05, 0.0, 0.0)))
    assert report["oracle"] == "scene"
    assert report["n_disagree"] == 0, report["disagreements"][:5]
    assert 500 < report["n_inside"] < 3500
    # Flat against flat in parallel planes: a flat sum, held as a solid grown by at least one
    # grid step (a false collision within the stated bound, never a false free).
    o = flat[:3] if len(flat) >= 3 else flat
    co = CSpaceObstacle.build(o, flat)
    assert min(co.margin.steps) >= 1 and co.error_bound < 1e-6
    # FCL's collide on two degenerate (segment) triangles answers within about 1e-7 of
    # contact either way (its distance there is positive): a wider band for its fuzz.
    report = cross_check(co, n=2000, seed=4, band=1e-6,
                         scene=raw_scene(_flat_mesh(o), _flat_mesh(flat)))
    assert report["n_disagree"] == 0 and report["n_inside"] > 0


def _flat_mesh(points):
    """A raw operand of test_flat_convex_operands_against_fcl as a float mesh: a box by its
    hull; a rod (2 points) as one degenerate triangle, a triangle as itself, a 4-point panel
    (convex, in order) as two triangles."""
    P = np.asarray(points, dtype=np.float64)
    F = {2: [[0, 1, 1]], 3: [[0, 1, 2]], 4: [[0, 1, 2], [0, 2, 3]]}.get(len(P))
    return raw_mesh(P) if F is None else (P, np.array(F, dtype=np.int64))


@pytest.mark.parametrize("offset", [(0.0, 0.0, 0.0), (250.0, 150.0, -300.0)])
def test_first_contact_of_segments_that_meet_no_surface_piece(offset):
    """Surface pieces (an open sheet, a convex robot): segments whose boxes meet no piece have
    no first contact (nan, not an IndexError), alone or beside segments that do."""
    from cspace import model_scene

    o = np.asarray(offset)
    sheet = Body("sheet", np.array([[0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, 0]], float) + o,
                 np.array([[0, 1, 2], [0, 2, 3]]), "sheet")
    cube = np.array([[x, y, z] for x in (-0.1, 0.1) for y in (-0.1, 0.1) for z in (-0.1, 0.1)])
    robot = Body("cube", cube, np.array(ConvexHull(cube).simplices, dtype=np.int64), "cube")
    scene = Scene("sheet", None, (sheet,), robot, np.zeros(3),
                  np.array([[-1.0, -1.0, -1.0], [2.0, 2.0, 1.0]]) + o,
                  np.array([-0.9, -0.9, 0.9]) + o, np.array([1.9, 1.9, 0.9]) + o)
    space = model_scene(scene, cache=None).cspace()
    assert [b.kind for b in model_scene(scene, build=False).bodies] == ["surface"]
    far0, far1 = o + [-0.9, -0.9, 0.9], o + [1.9, -0.9, 0.9]  # high above, beside the sheet
    assert np.isnan(space.first_contact(far0, far1)) and space.segment_free(far0, far1)
    down0, down1 = o + [0.5, 0.5, 0.9], o + [0.5, 0.5, -0.9]  # through the sheet at z = 0.1
    t = space.first_contact(np.stack([far0, down0]), np.stack([far1, down1]))
    assert np.isnan(t[0]) and abs(t[1] - 0.8 / 1.8) <= 1e-6
