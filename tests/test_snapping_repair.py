"""Issue #27, item 2 (remainder): what a body is must survive snapping, through the API as
through scenes.

- a closed body whose snapped triangles include zero-area ones (caps: three collinear grid
  corners; needles: two corners welded) is repaired exactly, keeping its point set, and stays
  a solid (:func:`cspace.mesh._repair_degenerate`);
- nesting (cavity or separate body) is decided exactly in ``ClosedMesh`` as in scenes;
- solids sharing an edge or a vertex in one mesh are a union in ``minkowski_sum`` too;
- a hull standing for a bent body counts its excess in ``CSpaceObstacle.error_bound``.
"""

import numpy as np
import pytest
import trimesh
from scipy.spatial.transform import Rotation

import cspace
from cspace.convex import ConvexPolytope

ROBOT_MESH = trimesh.creation.icosphere(1, radius=0.1)
ROBOT = ConvexPolytope.from_points(ROBOT_MESH.vertices)
FAR = np.array([250.0, 150.0, -300.0])


def _bent_box(seed: int):
    """A box rotated and placed at 1e3 scale far from the origin: snapping bends it."""
    m = trimesh.creation.box((1, 2, 3))
    R = Rotation.random(random_state=seed).as_matrix()
    return (m.vertices @ R.T) * 1e3 + FAR, np.asarray(m.faces)


def _fcl_distance(V1, F1, V2, F2) -> float:
    import fcl

    def obj(V, F):
        m = fcl.BVHModel()
        m.beginModel(len(V), len(F))
        m.addSubModel(np.asarray(V, float), np.asarray(F, np.int64))
        m.endModel()
        return fcl.CollisionObject(m, fcl.Transform())

    res = fcl.DistanceResult()
    return fcl.distance(obj(V1, F1), obj(V2, F2), fcl.DistanceRequest(), res)


# ---------------------------------------------------------------------------------------
# 4. CSpaceObstacle.build counts the excess of a bent body's hull


def test_build_counts_the_hull_excess_of_a_bent_obstacle_and_robot():
    V, F = _bent_box(0)  # seed 0 bends it: excess > 0
    co = cspace.CSpaceObstacle.build((V, F), ROBOT)
    assert co.kind == "convex" and co.obstacle.excess > 0
    assert co.excess == co.obstacle.excess
    assert co.error_bound == co.margin.error_bound + co.obstacle.excess
    # one-sided and within the bound: a C-obstacle vertex q puts the raw robot within
    # error_bound of the raw obstacle (FCL distance on the float meshes)
    for q in co.vertices[:: max(1, len(co.vertices) // 12)]:
        d = _fcl_distance(ROBOT_MESH.vertices + q, ROBOT_MESH.faces, V, F)
        assert d <= co.error_bound
    # the same bent box as the robot: its hull's excess counts too
    small = (V - FAR) / 1e3 * 0.1  # the rotated box, 0.1 x 0.2 x 0.3, at the origin
    Vr = small * 1e4 + FAR  # robot coordinates at 1e3 scale far away: bent on its grid
    cube = trimesh.creation.box((1e4, 1e4, 1e4)).vertices + FAR
    co = cspace.CSpaceObstacle.build(cube, (Vr, F), reference_point=FAR)
    assert co.robot.excess > 0 and co.excess == co.robot.excess
    assert co.error_bound == co.margin.error_bound + co.robot.excess
