"""Non-convex robots modelled exactly as parts: every pairing of kinds against FCL.

FCL is the oracle: robot and obstacle as BVH meshes, plus containment tests for the closed
sides (one vertex per component, generalized winding number). 10^4 translations per case,
half near the C-obstacle surfaces; membership must agree everywhere except within 1e-9 of
a C-obstacle boundary (the float band of the oracle, far below the grid's error bound).
"""

from __future__ import annotations

import numpy as np
import pytest
import trimesh
from zoo import l_shape, voxel_solid

from cspace import model_scene
from cspace.check.oracle import SceneOracle
from cspace.check.cross_check import cross_check, path_collisions
from cspace.planning.plan import plan
from cspace.cobstacle.pairs import pair_construction, triangle_pair_pieces
from cspace.scene.scene import Body, Scene
from cspace.cobstacle.surface import SurfaceObstacle


def _u_robot(size=0.5):
    """A U of voxels opening towards +y, its slot one voxel wide, centred on the slot."""
    occ = np.zeros((3, 2, 1), dtype=bool)
    occ[:, 0, 0] = True
    occ[0, 1, 0] = occ[2, 1, 0] = True
    V, F = voxel_solid(occ, size)
    return V - [1.5 * size, 1.5 * size, 0.5 * size], F


def _open(mesh, axis=2, side=1):
    """The mesh without its triangles on its extreme plane ``axis`` (an open surface)."""
    V, F = mesh
    plane = V[:, axis].max() if side > 0 else V[:, axis].min()
    on = (V[F][:, :, axis] == plane).all(axis=1)
    return V, F[~on]


def _box(extents, centre=(0, 0, 0)):
    m = trimesh.creation.box(extents=extents)
    return m.vertices + np.asarray(centre, float), m.faces


def _scene(obstacle, robot, bounds=((-2, -2, -2), (2, 2, 2)), start=None, goal=None, name="t"):
    lo = np.asarray(bounds[0], float)
    return Scene(name, None, (Body("obstacle", *obstacle, "test"),),
                 Body("robot", *robot, "test"), (0.0, 0.0, 0.0), bounds,
                 lo + 0.01 if start is None else start, lo + 0.02 if goal is None else goal)


POST = _box((0.3, 0.3, 2.0))                  # fits the U's 0.5-wide slot
L_SOLID = l_shape(arm=2)                       # 5 voxels: reflex edge along z
CASES = {
    # name: (obstacle, robot, obstacle kind, robot kind)
    "post x U (triangle pairs, convex obstacle)": (POST, _u_robot(), "convex", "solid"),
    "post x open U (triangle pairs, convex obstacle)": (POST, _open(_u_robot()), "convex",
                                                        "surface"),
    "L x U (triangle pairs, both solid)": (L_SOLID, _u_robot(0.4), "solid", "solid"),
    "open box x U (triangle pairs)": (_open(_box((1.0, 1.0, 1.0))), _u_robot(0.4), "surface",
                                      "solid"),
    "L x open U (triangle pairs)": (L_SOLID, _open(_u_robot(0.4)), "solid", "surface"),
    "open box x open U (flat pieces)": (_open(_box((1.0, 1.0, 1.0))),
                                                  _open(_u_robot(0.4), side=-1), "surface",
                                                  "surface"),
}


# The two L pairings (about 25 s together) run in make test-slow: the default run keeps one
# case of each kind of pairing (solid and open triangle pairs, flat pieces, convex).
SLOW_CASES = {"L x U (triangle pairs, both solid)", "L x open U (triangle pairs)"}


@pytest.mark.parametrize("name", [pytest.param(n, marks=pytest.mark.slow) if n in SLOW_CASES else n
                                  for n in CASES])
def test_pairing_agrees_with_fcl(name):
    obstacle, robot, o_kind, r_kind = CASES[name]
    m = model_scene(_scene(obstacle, robot))
    (body,) = [b for b in m.bodies if b.kind != "dropped"]
    (part,) = m.robot_parts
    assert (body.kind, part.kind) == (o_kind, r_kind)
    assert [p.construction for p in body.pairs] == [pair_construction(o_kind, r_kind)]
    assert not body.error
    cs = m.cspace()
    r = cross_check(cs, n=10000, seed=3, band=1e-9)
    assert 500 < r["n_inside"] < 9500
    assert r["n_disagree"] == 0, r["disagreements"][:5]
    assert r["max_distance_error"] <= 1e-9 * r["scene_size"]


@pytest.mark.parametrize("conservative", [False, pytest.param(True, marks=pytest.mark.slow)],
                         ids=["exact", "grown"])  # grown (16 s) in make test-slow
def test_triangle_pairs_equal_their_reference_hulls(conservative):
    # PairObstacle (slabs of each pair, no hull) against the reference construction (one
    # exact hull per pair, queried by the surface-piece engine): the same answers, exactly,
    # also for pieces grown by the outward-rounding box (38 slabs against 8x the hull points).
    obstacle, robot = L_SOLID, _u_robot(0.4)
    m = model_scene(_scene(obstacle, robot), conservative=conservative)
    (pair,) = m.bodies[0].pairs
    fast = next(co for co in pair.cos if co.kind == "pairs")
    (part,) = m.robot_parts
    b = m.bodies[0]
    ref = triangle_pair_pieces(b._solid.ints, b._solid.faces, part.ints, part.faces,
                               m.grid.snap(np.zeros(3)), m.grid,
                               np.ldexp(np.asarray(m.scene.bounds), -m.grid.exponent),
                               closed=True, margin=fast.pairs.margin)
    assert fast.pairs.margin.any() == conservative  # 0.4 is not on the grid
    # the engine ranges over every pair; the reference keeps those whose piece meets the bounds
    assert 0 < len(ref.pieces) <= len(fast.pairs.pairs) and ref.thickened == 0
    slow = SurfaceObstacle(ref.pieces, obstacle=None, robot=None, reference_point=np.zeros(3),
                           grid=m.grid)
    rng = np.random.default_rng(11)
    q = np.vstack([rng.uniform(-2, 2, (1500, 3)), fast.vertices[rng.integers(0, len(
        fast.vertices), 500)]])  # hull corners: on piece boundaries, exact ties
    lo, hi = m.scene.bounds
    q = q[((lo <= q) & (q <= hi)).all(axis=1)]  # the reference keeps the pieces meeting these
    assert len(q) > 1000
    assert np.array_equal(fast.contains(q), slow.contains(q))
    q1 = q + rng.normal(scale=0.3, size=q.shape)
    assert np.array_equal(fast.segment_free(q, q1), slow.segment_free(q, q1))
    assert np.array_equal(fast.first_contact(q[:500], q1[:500]),
                          slow.first_contact(q[:500], q1[:500]), equal_nan=True)
    d_fast, d_slow = fast.signed_distance(q[:400]), slow.signed_distance(q[:400])
    assert np.array_equal(np.sign(d_fast), np.sign(d_slow))
    # Outside a grown piece the engine's distance is a lower bound within the box's diagonal.
    slack = float(np.linalg.norm(fast.pairs.margin)) * m.grid.step
    out = d_slow > 0
    assert np.allclose(d_fast[~out], d_slow[~out], rtol=0, atol=1e-12)
    assert (d_fast[out] <= d_slow[out] + 1e-12).all()
    assert (d_fast[out] >= d_slow[out] - slack - 1e-12).all()


def test_coplanar_open_triangles_touch_only_in_their_plane():
    # Two open triangles in one plane: only the flat piece records their contact, exactly.
    # (Dyadic coordinates: snapping moves nothing, so no margin is added.)
    tri = (np.array([[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]]), np.array([[0, 1, 2]]))
    scene = _scene(tri, tri)
    m = model_scene(scene)
    assert m.margin.steps == (0, 0, 0) and m.error_bound == 0.0
    assert [p.construction for p in m.bodies[0].pairs] == ["triangle pairs"]
    cs = m.cspace()
    q = np.array([[0.2, 0.2, 0.0], [0.2, 0.2, 2.0**-30], [-0.5, 0.5, 0.0], [1.0, 0.0, 0.0],
                  [1.0 + 2.0**-30, 0.0, 0.0]])
    assert cs.contains(q).tolist() == [True, False, True, True, False]
    # FCL on the raw scene (two open triangles, surfaces by the oracle's own rule).
    oracle = SceneOracle(scene)
    assert oracle.collides(q).tolist() == [True, False, True, True, False]
    # A translation through the plane is a collision; one beside it is not.
    assert not cs.segment_free([0.2, 0.2, -1.0], [0.2, 0.2, 1.0])
    assert cs.segment_free([3.0, 3.0, -1.0], [3.0, 3.0, 1.0])


def test_u_robot_around_a_post_is_free_where_its_hull_collides():
    # The post stands in the U's slot: free for the real robot, a collision for its hull.
    scene = _scene(POST, _u_robot())
    exact = model_scene(scene).cspace()
    hull = model_scene(scene, robot_hull=True).cspace()
    q = np.array([0.0, 0.0, 0.0])
    assert not exact.contains(q) and hull.contains(q)
    # Sliding the U along the post (z) stays free; pushing it into the post does not.
    assert exact.segment_free(q, q + [0, 0, 0.5])
    assert not exact.segment_free(q, q + [0.4, 0, 0])
    assert "as asked (robot_hull)" in model_scene(scene, robot_hull=True, build=False).explain()


def test_containment_terms_count():
    # A small closed robot wholly inside a closed obstacle touches no triangle: only the
    # containment term O + c - r says it collides; an obstacle inside the robot likewise.
    q = np.zeros(3)
    for obstacle, robot in [(_box((3.0, 3.0, 3.0)), _u_robot(0.2)),
                            (_box((0.1, 0.1, 0.1), centre=(0.0, -0.5, 0.0)), _u_robot(0.5))]:
        m = model_scene(_scene(obstacle, robot))
        (pair,) = [p for b in m.bodies for p in b.pairs]
        assert pair.construction == "triangle pairs"
        cos = pair.cos
        assert m.cspace().contains(q)
        pieces = [co for co in cos if co.kind == "pairs"]
        terms = [co for co in cos if co.kind == "mesh"]
        assert len(pieces) == 1 and len(terms) >= 1
        assert not any(co.contains(q) for co in pieces)
        assert any(co.contains(q) for co in terms)


def test_l_robot_plans_through_an_l_corridor_and_fcl_agrees():
    # An L-shaped robot (arms 0.3 long, 0.1 thick) in an L-shaped corridor (0.5 wide, 0.25
    # high) cut out of a block, planned round the corner with the exact robot.
    occ = np.ones((7, 7, 1), dtype=bool)
    occ[1:6, 1:3, :] = False   # corridor along x
    occ[4:6, 1:6, :] = False   # then along y
    walls = voxel_solid(np.pad(occ, ((0, 0), (0, 0), (1, 1)), constant_values=True), 0.25,
                        origin=(-0.875, -0.875, -0.375))
    robot = l_shape(arm=2)
    robot = (robot[0] * [0.1, 0.1, 0.1], robot[1])
    c = robot[0].mean(axis=0)
    robot = (robot[0] - c, robot[1])
    bounds = ((-0.6, -0.6, -0.02), (0.6, 0.6, 0.02))
    scene = _scene(walls, robot, bounds, start=(-0.375, -0.375, 0.0), goal=(0.375, 0.4, 0.0),
                   name="l-corridor")
    m = model_scene(scene)
    assert {p.construction for b in m.bodies for p in b.pairs} == {"triangle pairs"}
    cs = m.cspace()
    r = cross_check(cs, n=10000, seed=5, band=1e-9)
    assert r["n_disagree"] == 0, r["disagreements"][:5]
    result = plan(scene, seed=2, time=10.0)
    assert result.solved
    # Re-checked on the raw scene's meshes (SceneOracle), nothing of the C-space.
    hits, n = path_collisions(scene, result.path, step=1e-3 * np.linalg.norm(np.ptp(
        np.asarray(bounds), axis=0)))
    assert n > 100 and len(hits) == 0


def test_containment_terms_only_where_they_can_hold():
    # A robot smaller than an obstacle component can never hold it: no "o + c - R" term; the
    # obstacle can hold the robot: one "O + c - r" term.
    m = model_scene(_scene(L_SOLID, _u_robot(0.2)))
    (pair,) = m.bodies[0].pairs
    assert [co.kind for co in pair.cos] == ["pairs", "mesh"]
    # A small obstacle inside a large U's reach: the robot may hold it; it cannot hold the U.
    m = model_scene(_scene(_box((0.1, 0.1, 0.1), centre=(0.0, -0.5, 0.0)), _u_robot(0.5)))
    (pair,) = m.bodies[0].pairs
    assert pair.construction == "triangle pairs"  # a convex obstacle too
    assert [co.kind for co in pair.cos] == ["pairs", "mesh"]  # the robot may hold it
    tiny = _box((0.05, 0.05, 0.05))
    m = model_scene(_scene(_open(tiny), _u_robot(0.5)))  # an open speck: surface body
    (pair,) = m.bodies[0].pairs
    assert [co.kind for co in pair.cos] == ["pairs", "mesh"]
    assert m.cspace().contains([0.0, 0.5, 0.0])  # the speck deep in the U's base
