"""Issue #27, item 2 (remainder): what a body is must survive snapping, through the API as
through scenes.

- a closed body whose snapped triangles include zero-area ones (caps: three collinear grid
  corners; needles: two corners welded) is repaired exactly, keeping its point set, and stays
  a solid (:func:`cspace.mesh.closed._repair_degenerate`);
- nesting (cavity or separate body) is decided exactly in ``ClosedMesh`` as in scenes;
- solids sharing an edge or a vertex in one mesh are a union in ``minkowski_sum`` too;
- a hull standing for a bent body counts its excess in ``CSpaceObstacle.error_bound``.
"""

import numpy as np
import pytest
import trimesh
from scipy.spatial.transform import Rotation

import cspace
from cspace.mesh.convex import ConvexPolytope

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


# ---------------------------------------------------------------------------------------
# 1. slivers that snap to zero area do not demote a solid to a surface


def _lattice(m, scale: float, unit: float = 2.0**-4):
    """A mesh scaled and rounded to multiples of ``unit``: its edge midpoints are on any grid
    finer than ``unit / 2``, where an inserted midpoint snaps exactly onto the edge."""
    return np.round(np.asarray(m.vertices) * scale / unit) * unit, np.asarray(m.faces)


def _with_sliver(V, F, edge: int = 0, lift: float = 1e-12):
    """A valid closed mesh with a sliver: a vertex ``w`` within ``lift`` of the midpoint of
    an edge ``uv`` (outwards), the face on one side of ``uv`` split at ``w`` and the sliver
    ``(v, u, w)`` closing the gap. At any grid finer than the edge's midpoint ``w`` snaps onto
    ``uv``: the sliver becomes a cap (zero area, three collinear grid corners)."""
    F = [list(t) for t in F]
    u, v = F[edge][0], F[edge][1]  # half-edge u -> v of face `edge`
    j = next(k for k, t in enumerate(F) if k != edge and u in t and v in t)
    y = next(x for x in F[j] if x not in (u, v))
    n = np.cross(V[F[edge][1]] - V[F[edge][0]], V[F[edge][2]] - V[F[edge][0]])
    n2 = np.cross(V[F[j][1]] - V[F[j][0]], V[F[j][2]] - V[F[j][0]])
    out = n / np.linalg.norm(n) + n2 / np.linalg.norm(n2)
    w_at = (V[u] + V[v]) / 2 + lift * out / np.linalg.norm(out)
    w = len(V)
    F[j] = [v, w, y]  # (v, u, y) split at w: (v, w, y), (w, u, y); the sliver (v, u, w)
    F += [[w, u, y], [v, u, w]]
    return np.vstack([V, w_at]), np.asarray(F, dtype=np.int64)


def _capped_box(scale=100.0, at=FAR):
    V, F = _lattice(trimesh.creation.box((1, 1, 1)), scale)
    return _with_sliver(V + at, F, edge=0)


def _capped_ball(scale=20.0, at=FAR, edge=5):
    V, F = _lattice(trimesh.creation.icosphere(1), scale)
    return _with_sliver(V + at, F, edge=edge)


def _zero_area_on(grid, V, F) -> int:
    """Snapped triangles of zero area (exact integer cross products)."""
    P = grid.snap(V)[F].astype(object)
    n = np.cross(P[:, 1] - P[:, 0], P[:, 2] - P[:, 0])
    return int(sum(not any(r) for r in n))


@pytest.mark.parametrize("make", [_capped_box, _capped_ball])
def test_a_mesh_with_caps_after_snapping_is_repaired_into_its_solid(make):
    V, F = make()
    assert trimesh.Trimesh(V, F, process=False).is_watertight
    mesh = cspace.ClosedMesh.from_arrays(V, F)  # was: DegenerateError (zero area)
    assert _zero_area_on(mesh.grid, V, F) == 1  # the sliver is a cap on this grid
    # the same point set: the volume of the snapped input, and every face of positive area
    assert mesh.volume == pytest.approx(abs(trimesh.Trimesh(V, F).volume), rel=1e-9)
    assert _zero_area_on(mesh.grid, mesh.vertices, mesh.faces) == 0
    assert len(mesh.faces) == len(F)  # the cap dropped, its neighbour split in two


def _capped_l(scale=25.0, at=FAR):
    from zoo import l_shape  # tests/ is on sys.path (rootdir conftest)

    V, F = l_shape(arm=2)
    V, F = _lattice(trimesh.Trimesh(V, F, process=False), scale)
    return _with_sliver(V + at, F, edge=0)


def _scene(obstacles, robot, reference_point, half=120.0):
    from cspace.scene.scene import Body, Scene

    lo, hi = FAR - half, FAR + half
    bodies = tuple(Body(name, V, F, "test") for name, (V, F) in obstacles.items())
    return Scene("slivers", None, bodies, Body("robot", *robot, "test"),
                 np.asarray(reference_point, float), np.stack([lo, hi]), lo + 1.0, lo + 2.0)


def _near_surfaces(scene, n, seed):
    """Translations near where the robot touches an obstacle: random pairs of an obstacle
    vertex and a robot vertex, moved a little (sizes from 1e-9 to 1 of the scene)."""
    rng = np.random.default_rng(seed)
    O = np.vstack([b.vertices for b in scene.obstacles])
    R = scene.robot.vertices - scene.reference_point
    q = O[rng.integers(len(O), size=n)] - R[rng.integers(len(R), size=n)]
    return q + rng.normal(size=(n, 3)) * 10.0 ** rng.uniform(-9, 1, size=(n, 1))


@pytest.mark.parametrize("robot", ["ball", "L"])
def test_capped_bodies_stay_solid_in_a_scene_and_agree_with_fcl(robot):
    from cspace.check.oracle import SceneOracle
    from cspace.scene.model import model_scene

    obstacles = {"box": _capped_box(), "L": _capped_l(at=FAR + (-110, 60, 0))}
    if robot == "ball":
        R = _capped_ball(scale=8.0)
    else:
        R = _capped_l(scale=6.0)
    scene = _scene(obstacles, R, R[0].mean(axis=0))
    model = model_scene(scene)
    kinds = {b.name: b.kind for b in model.bodies}
    assert kinds["box"] == "convex" and kinds["L"] == "solid"  # was: surface, both
    assert [p.kind for p in model.robot_parts] == (["convex"] if robot == "ball" else ["solid"])
    assert not model.meaning_changes()
    cs = model.cspace()
    oracle = SceneOracle(scene)
    Q = _near_surfaces(scene, 1500, seed=1)
    inside = FAR - 40 + np.random.default_rng(2).uniform(0, 80, (200, 3))
    Q = np.vstack([Q, inside])  # deep inside the box: its inside collides
    truth, ours = oracle.collides(Q), cs.contains(Q)
    assert not (truth & ~ours).any()  # no false free
    assert ours[-200:].all() and truth[-200:].all()
    # false collisions only within the stated bound of a true one (FCL distance)
    false = ours & ~truth
    assert truth.sum() > 300 and oracle.distance(Q[false]).max(initial=0) <= model.error_bound


def test_capped_meshes_through_the_api():
    L, box = _capped_l(), _capped_box()
    M = cspace.minkowski_sum(L, ROBOT.reflected((0, 0, 0)))  # was: DegenerateError
    assert not M.convex and M.volume > abs(trimesh.Trimesh(*L).volume)
    co = cspace.CSpaceObstacle.build(L, ROBOT)
    assert co.kind == "mesh"
    q = L[0][L[1][0]].mean(axis=0)  # a point of the L's surface
    assert co.contains(q)
    co = cspace.CSpaceObstacle.build(box, ROBOT)
    assert co.kind == "convex" and co.contains(FAR)


# ---------------------------------------------------------------------------------------
# 2. nesting decided exactly in the API as in scenes (cspace.mesh.components.nested_pairs)


def _l_and_inverted_box(centre):
    from zoo import l_shape

    V, F = l_shape(arm=2)  # [0, 3] x [0, 3] x [0, 1], the notch is [1, 3] x [1, 3]
    small = trimesh.creation.box((0.5, 0.5, 0.5))
    return (np.vstack([V, small.vertices + centre]),
            np.vstack([F, small.faces[:, ::-1] + len(V)]))


def test_an_inside_out_box_in_the_notch_of_an_l_is_a_body_not_a_dropped_cavity():
    """Inside the L's box but outside its solid: it bounds nothing wound inwards, so it is a
    separate body turned outwards, as scenes model it (was: accepted as a cavity by the box
    test and dropped from the sum silently)."""
    A = _l_and_inverted_box((2.0, 2.0, 0.5))
    mesh = cspace.ClosedMesh.from_arrays(*A)
    assert mesh.volume == pytest.approx(5.0 + 0.125)  # both outwards
    M = cspace.minkowski_sum(A, ROBOT.reflected((0, 0, 0)))
    L = cspace.minkowski_sum((A[0][:-8], A[1][:-12]), ROBOT.reflected((0, 0, 0)))
    assert M.volume > L.volume + 0.125
    co = cspace.CSpaceObstacle.build(A, ROBOT)
    assert co.contains([2.0, 2.0, 0.5]) and not co.contains([1.6, 1.6, 0.5])
    # the scene answers the same
    from cspace.scene.model import model_scene
    from cspace.scene.scene import Body, Scene

    robot = Body("robot", ROBOT_MESH.vertices, ROBOT_MESH.faces, "test")
    scene = Scene("notch", None, (Body("w", *A, "test"),), robot, np.zeros(3),
                  np.array([[-1.0, -1, -1], [4, 4, 2]]), np.array([-0.9, -0.9, -0.9]),
                  np.array([-0.8, -0.9, -0.9]))
    cs = model_scene(scene).cspace()
    Q = np.random.default_rng(0).uniform((-0.5, -0.5, -0.5), (3.5, 3.5, 1.5), (3000, 3))
    assert np.array_equal(cs.contains(Q), co.contains(Q))


def test_an_inside_out_box_inside_a_solid_is_its_cavity():
    big = trimesh.creation.box((2.0, 2.0, 2.0))
    small = trimesh.creation.box((1.0, 1.0, 1.0))
    A = (np.vstack([big.vertices, small.vertices]),
         np.vstack([big.faces, small.faces[:, ::-1] + 8]))
    assert cspace.ClosedMesh.from_arrays(*A).volume == 7.0
    M = cspace.minkowski_sum(A, ROBOT.reflected((0, 0, 0)))
    assert M.n_holes == 1
    co = cspace.CSpaceObstacle.build(A, ROBOT)
    assert not co.contains([0.0, 0.0, 0.0]) and co.contains([0.0, 0.0, 0.45])


# ---------------------------------------------------------------------------------------
# 3. solids sharing an edge or a vertex in one mesh: a union in minkowski_sum too


def _two_boxes(shared: str):
    a = trimesh.creation.box((1.0, 1.0, 1.0))
    shift = {"edge": (1.0, 1.0, 0.0), "vertex": (1.0, 1.0, 1.0)}[shared]
    return (np.vstack([a.vertices, a.vertices + shift]), np.vstack([a.faces, a.faces + 8]))


@pytest.mark.parametrize("shared", ["edge", "vertex"])
def test_minkowski_sum_of_solids_sharing_an_edge_or_a_vertex_is_their_union(shared):
    A = _two_boxes(shared)
    with pytest.raises(cspace.NonManifoldError):
        cspace.ClosedMesh.from_arrays(*A)
    B = ROBOT.reflected((0, 0, 0))
    M = cspace.minkowski_sum(A, B)  # was: NonManifoldError, then two overlapping shells
    assert isinstance(M, cspace.SumPolyhedron) and len(M.pieces) == len(M.parts) == 2
    one = cspace.minkowski_sum(trimesh.creation.box((1.0, 1.0, 1.0)), B)
    # each piece's exact sum: translates of each other (one frame for both: B's step
    # differs from the boxes', so they were snapped together), and of one box's sum within
    # the bound
    a, b = M.parts
    assert a.convex and b.convex and a.volume_exact == b.volume_exact
    assert abs(a.volume - one.volume) < 6 * 4 * M.error_bound
    # one surface: the union's boundary, closed, its exact volume the two sums' less their
    # overlap (they overlap where the boxes meet: less than both, more than one)
    assert a.volume_exact < M.volume_exact < a.volume_exact + b.volume_exact
    assert len(M.nonmanifold_edges) == 0 and M.n_holes == 0
    # a point is in the sum exactly when it is in some part: the same as build's union
    co = cspace.CSpaceObstacle.build(A, ROBOT, conservative=False)
    assert co.kind == "union"
    Q = np.random.default_rng(3).uniform(-0.8, 2.8, (4000, 3))
    ours = cspace.CSpaceObstacle.from_mesh(M.vertices, M.faces).contains(Q)
    assert np.array_equal(ours, co.contains(Q)) and 0 < ours.sum() < len(Q)
