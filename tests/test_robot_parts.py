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

from cspace import model_scene
from cspace.fcl_check import _oracle, cross_check, path_collisions
from cspace.ompl_plugin import plan
from cspace.pairs import pair_construction
from cspace.scene import Body, Scene

from zoo import l_shape, voxel_solid


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
    "post x U (NCC-CVMS swapped)": (POST, _u_robot(), "convex", "solid"),
    "post x open U (convex + robot triangles)": (POST, _open(_u_robot()), "convex", "surface"),
    "L x U (triangle pairs, both solid)": (L_SOLID, _u_robot(0.4), "solid", "solid"),
    "open box x U (triangle pairs)": (_open(_box((1.0, 1.0, 1.0))), _u_robot(0.4), "surface",
                                      "solid"),
    "L x open U (triangle pairs)": (L_SOLID, _open(_u_robot(0.4)), "solid", "surface"),
    "open box x open U (flat pieces thickened)": (_open(_box((1.0, 1.0, 1.0))),
                                                  _open(_u_robot(0.4), side=-1), "surface",
                                                  "surface"),
}


@pytest.mark.parametrize("name", list(CASES))
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
    thickened = "thickened" in body.pairs[0].detail
    assert thickened == (o_kind == r_kind == "surface")
    if not thickened:
        assert r["n_disagree"] == 0, r["disagreements"][:5]
        assert r["max_distance_error"] <= 1e-9 * r["scene_size"]
        return
    # Flat pieces of two open surfaces are grown by one grid step: false collisions within
    # that step of the exact C-obstacle, never a false free.
    q = r["disagreements"]
    assert len(q) and cs.contains(q).all()
    oracle = _oracle(cs.obstacles[0])
    assert not oracle.collides(q).any()
    assert (oracle.distance(q) <= m.grid.step * (1 + 1e-6)).all()


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
        assert pair.construction == "triangle pairs" or pair.construction == "NCC-CVMS swapped"
        cos = pair.cos
        assert m.cspace().contains(q)
        if pair.construction == "triangle pairs":
            pieces = [co for co in cos if co.kind == "surface"]
            terms = [co for co in cos if co.kind == "mesh"]
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
    assert {p.construction for b in m.bodies for p in b.pairs} <= {"triangle pairs",
                                                                   "NCC-CVMS swapped"}
    cs = m.cspace()
    r = cross_check(cs, n=10000, seed=5, band=1e-9)
    assert r["n_disagree"] == 0, r["disagreements"][:5]
    result = plan(scene, seed=2, time=10.0)
    assert result.solved
    hits, n = path_collisions(cs, result.path, step=1e-3 * np.linalg.norm(np.ptp(
        np.asarray(bounds), axis=0)))
    assert n > 100 and len(hits) == 0
