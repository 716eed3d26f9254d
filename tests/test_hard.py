"""Hard cases: no answer is ever a false free, and the stated bound holds.

The families come from ``hard.py``, each with translations whose answer is known without
cspace (and confirmed by FCL on the float input itself). The default run sweeps a part of
each family; ``make test-slow`` sweeps all of it.
"""

from __future__ import annotations

from fractions import Fraction

import numpy as np
import pytest
from hard import GAP_ANGLES, TiltCase, VoxelCase, gap_comb, l_cells, l_robot, rotation_z
from oracles import brute_force_sum_distance, raw_scene, sum_support_points
from zoo import comb, grate, grate_occupancy, random_rotation, stairs_occupancy
from scipy.spatial import ConvexHull

from cspace import ClosedMesh, CSpaceObstacle, Grid, minkowski_sum, model_scene
from cspace.check.fcl import FclOracle
from cspace.check.cross_check import cross_check
from cspace.cobstacle.margin import Margin
from cspace.geometry.snapping import snap_deviation
from cspace.scene.scene import Body, Scene

FAST_ANGLES = GAP_ANGLES[:12]


def _box_faces(points: np.ndarray) -> np.ndarray:
    return ConvexHull(points).simplices


def _false_free(co, q: np.ndarray) -> int:
    """How many of the known collisions ``q`` (along one slot) are answered free: by
    ``contains``, by ``segment_free`` along the slot, by ``first_contact`` from its start."""
    n = int((~co.contains(q)).sum())
    n += bool(co.segment_free(q[0], q[-1]))
    n += co.first_contact(q[0], q[-1]) != 0.0
    return n


def _confirmed_by_fcl(case) -> None:
    V, F = case.obstacle
    orc = FclOracle(V, F, case.robot, _box_faces(case.robot), np.zeros(3), convex=True)
    assert orc.collides(case.colliding).all(), "the known collisions must be collisions"


# --------------------------------------------------------------------------------------
# the margin itself


def test_snap_deviation_is_exact():
    rng = np.random.default_rng(1)
    P = rng.normal(size=(200, 3)) * [1.0, 1e-3, 7.0]
    grid = Grid.for_points(P)
    dev = snap_deviation(P, grid)
    k = grid.snap(P)
    exact = [max(abs(Fraction(float(x)) - Fraction(int(i)) * Fraction(grid.step))
                 for x, i in zip(P[:, a], k[:, a])) for a in range(3)]
    assert [Fraction(float(d)) for d in dev] == exact
    assert (dev <= grid.error_bound).all()


@pytest.mark.parametrize("rounded", [False, True])
def test_margin_is_the_least_box_covering_the_deviation(rounded):
    grid = Grid.for_extent(3.0)
    s = Fraction(grid.step)
    for dev in ([0.0, 0.0, 0.0], [grid.step, 0.5 * grid.step, 1.5 * grid.step],
                [1e-30, 2.9 * grid.step, 3 * grid.step]):
        m = Margin.for_deviation(dev, grid, rounded=rounded)
        need = [Fraction(d) + Fraction(m.rounding) for d in dev]
        assert all(g * s >= x for g, x in zip(m.steps, need)) and m.holds_true
        assert all((g - 1) * s < x or g == 0 for g, x in zip(m.steps, need))
    assert Margin.for_deviation([0, 0, 0], grid, rounded=False).error_bound == 0.0
    assert not Margin.for_deviation([grid.step / 3] * 3, grid, rounded=False).without_growth(
    ).holds_true


# --------------------------------------------------------------------------------------
# a slot exactly as wide as the robot, turned by irrational angles: no false free


def test_gap_comb_cracks_exist_without_outward_rounding():
    # The family is hard: the exact C-obstacle of the *snapped* input opens a slit of free
    # space in some of the turned combs (what outward rounding exists for).
    cracked = 0
    for angle in FAST_ANGLES:
        case = gap_comb(angle)
        co = CSpaceObstacle.build(case.obstacle, case.robot, conservative=False)
        cracked += _false_free(co, case.colliding) > 0
    assert cracked >= 1


@pytest.mark.parametrize("depth", [1e-9, 1e-12])
def test_gap_comb_is_never_reported_free(depth):
    for angle in FAST_ANGLES:
        case = gap_comb(angle, depth=depth)
        _confirmed_by_fcl(case)
        co = CSpaceObstacle.build(case.obstacle, case.robot)
        assert co.margin.holds_true and any(co.margin.steps)
        assert co.error_bound < 1e-6  # a few grid steps of a unit scene
        assert _false_free(co, case.colliding) == 0, f"angle {angle}"


def _l_bracket(offset: float = 0.0) -> VoxelCase:
    """The L bracket (voxels of 0.5) and a 0.3 box robot, the obstacle moved by ``offset``."""
    return VoxelCase(l_cells(), (0.5, 0.5, 0.5), (0.3, 0.3, 0.3), lambda x: x + offset)


@pytest.mark.parametrize("k", [3, 6, 9, 12])
def test_precision_follows_size_not_position(k):
    """#17: the same part moved by 10^k keeps the precision of its size, as far as float64
    resolves coordinates there (the grid is centred on the C-obstacle; its step is never
    below a few ulps of the coordinates), and is never reported free where it collides:
    exact reference (a union of boxes in rationals on the float input)."""
    near, far = _l_bracket(), _l_bracket(10.0 ** k)
    co0 = CSpaceObstacle.build((near.vertices, near.faces), near.robot)
    co = CSpaceObstacle.build((far.vertices, far.faces), far.robot)
    assert any(co.grid.origin) and co.kind == "mesh"
    ulp = float(np.spacing(10.0 ** k))
    # step: the unit scene's, or 2**-52 of the coordinates (2 ulps), whichever is coarser
    assert co.grid.step <= max(co0.grid.step, 2 * ulp)
    assert co.error_bound <= max(2 * co0.error_bound, 16 * ulp)
    _judged(far, co, 3000, k)


def _judged(case, co, n: int, seed: int):
    """No false free on ``n`` samples of an exact reference, false collisions within the
    stated bound, and every sampled segment that ends in the reference blocked."""
    q = case.samples(n, np.random.default_rng(seed))
    ref, ours = case.contains(q), co.contains(q)
    assert not (ref & ~ours).any()
    if (ours & ~ref).any():
        assert case.distance(q[ours & ~ref]).max() <= co.error_bound
    assert (~co.segment_free(q[:-1], q[1:]))[ref[1:] | ref[:-1]].all()
    return q, ref


@pytest.mark.parametrize("k", [3, 9, 15])
def test_near_coplanar_tilts_are_never_reported_free(k):
    """A valley 10^-k deep between two top faces: a non-convex mesh while the grid resolves
    the dip, a convex one once it snaps flat; exact reference in rationals either way."""
    case = TiltCase(10.0 ** -k)
    co = CSpaceObstacle.build((case.vertices, case.faces), case.robot)
    assert co.kind == ("mesh" if k < 9 else "convex")
    _judged(case, co, 3000, k)
    assert co.error_bound < 1e-7


@pytest.mark.parametrize("shape", [
    "stairs", pytest.param("grate", marks=pytest.mark.slow)])
def test_parallel_structure_and_high_genus(shape):
    """Stairs (parallel steps) and a 10 x 10 grate (genus 100, holes just wider than the
    robot): exact union-of-boxes reference; the grate's holes stay free."""
    occ = stairs_occupancy(4, 1) if shape == "stairs" else grate_occupancy(10)
    case = VoxelCase(occ, (0.5, 0.5, 0.5), (0.3, 0.3, 0.3))
    co = CSpaceObstacle.build((case.vertices, case.faces), case.robot)
    _judged(case, co, 2000, 5)
    if shape == "grate":  # the centre of every hole: 0.25 from the bars' C-obstacle
        centres = np.array([[0.5 * i + 0.25, 0.5 * j + 0.25, 0.25]
                            for i in range(1, 21, 2) for j in range(1, 21, 2)])
        assert not co.contains(centres).any()


def test_offset_scene_has_the_unit_scenes_grid_step():
    """A scene far from the origin (bounds, obstacles, start and goal moved by 10^6; the
    robot in its own frame) is modelled on the step of the same scene at the origin, and
    no known collision is answered free."""
    case = gap_comb(FAST_ANGLES[0])
    scene = _gap_scene(case, (case.robot, _box_faces(case.robot)), teeth_apart=False)
    d = np.full(3, 1e6)
    moved = Scene("gap far", None, tuple(Body(b.name, b.vertices + d, b.faces, "test")
                                         for b in scene.obstacles),
                  scene.robot, scene.reference_point, tuple(np.asarray(scene.bounds) + d),
                  scene.start + d, scene.goal + d)
    m0, m = model_scene(scene), model_scene(moved)
    assert m.grid.exponent == m0.grid.exponent and any(m.grid.origin)
    assert m.error_bound <= 2 * m0.error_bound
    cs = m.cspace()
    assert _false_free(cs, case.colliding + d) == 0
    assert not cs.contains(moved.start) and not cs.contains(moved.goal)


def _gap_scene(case, robot, teeth_apart: bool) -> Scene:
    V, F = case.obstacle
    if teeth_apart:  # the two teeth of the slot as convex bodies of their own (CVMS)
        w = 0.25
        bodies = []
        for x0 in (0.0, 2 * w):
            box = np.array([[x, y, z] for x in (x0, x0 + w) for y in (w, 3 * w)
                            for z in (0.0, w)]) @ case.rotation.T
            bodies.append(Body(f"tooth at {x0}", box, _box_faces(box), "test"))
        bodies = tuple(bodies)
    else:
        bodies = (Body("comb", V, F, "test"),)
    lo = np.array([-1.0, -1.0, -1.0])
    return Scene("gap", None, bodies, Body("robot", *robot, "test"), (0.0, 0.0, 0.0),
                 (lo, -lo), lo + 0.01, lo + 0.02)


@pytest.mark.parametrize("robot, teeth_apart, construction", [
    ("box", True, "CVMS"), ("box", False, "NCC-CVMS"), ("L", False, "triangle pairs"),
], ids=["teeth convex (CVMS)", "comb solid (NCC-CVMS)", "L robot (triangle pairs)"])
def test_gap_scene_is_never_reported_free(robot, teeth_apart, construction):
    angles = FAST_ANGLES[:6] if robot == "L" else FAST_ANGLES
    for angle in angles:
        case = gap_comb(angle)
        shape = ((case.robot, _box_faces(case.robot)) if robot == "box"
                 else l_robot(angle=angle))
        m = model_scene(_gap_scene(case, shape, teeth_apart))
        assert {p.construction for b in m.bodies for p in b.pairs} == {construction}
        cs = m.cspace()
        assert "never a false free" in m.explain()
        assert _false_free(cs, case.colliding) == 0, f"angle {angle}"
    # and the grown C-obstacles still agree with FCL on the snapped operands away from
    # the growth (checked on the last angle)
    r = cross_check(cs, n=3000, seed=2)
    assert r["n_disagree"] == 0 and r["n_false_free"] == 0


@pytest.mark.slow
@pytest.mark.parametrize("depth", [1e-9, 1e-12, 0.0])
def test_gap_comb_full_sweep(depth):
    # Every angle; depth 0: the robot exactly between the teeth as the float input says
    # (touching or within ~1e-16 of it; never reported free).
    for angle in GAP_ANGLES:
        case = gap_comb(angle, depth=depth)
        if depth:
            _confirmed_by_fcl(case)
        co = CSpaceObstacle.build(case.obstacle, case.robot)
        assert _false_free(co, case.colliding) == 0, f"angle {angle}"


# --------------------------------------------------------------------------------------
# refusals turned into answers: obstacles touching themselves, flat robots


def _touching_boxes(shift, angle: float):
    """Two unit boxes as one mesh, the second moved by ``shift`` (sharing an edge or a
    vertex with the first), welded, turned by ``angle`` about z: a closed 2-cycle that is not
    a 2-manifold."""
    import trimesh

    a = trimesh.creation.box((1.0, 1.0, 1.0))
    V = np.vstack([a.vertices + 0.5, a.vertices + 0.5 + np.asarray(shift, float)])
    F = np.vstack([a.faces, a.faces + 8])
    V, inverse = np.unique(V, axis=0, return_inverse=True)
    return V @ rotation_z(angle).T, inverse.reshape(-1)[F]


@pytest.mark.parametrize("shift", [(1, 1, 0), (1, 1, 1)], ids=["edge", "vertex"])
@pytest.mark.parametrize("angle", [0.0, GAP_ANGLES[0]], ids=["axis-aligned", "turned"])
def test_obstacle_touching_itself_builds_as_the_union_of_its_pieces(shift, angle):
    from cspace.errors import NonManifoldError

    V, F = _touching_boxes(shift, angle)
    robot = np.array([[x, y, z] for x in (0, .3) for y in (0, .3) for z in (0, .3)]) - 0.15
    with pytest.raises(NonManifoldError):  # not one solid ...
        ClosedMesh.from_arrays(V, F)
    co = CSpaceObstacle.build((V, F), robot)  # ... but the union of two
    assert co.kind == "union" and len(co.parts) == 2
    # the robot squeezed into the shared edge / vertex collides (both pieces touch it)
    corner = np.asarray(shift, float) @ rotation_z(angle).T * 1.0
    assert co.contains(corner)
    r = cross_check(co, n=4000, seed=5, scene=raw_scene((V, F), robot))
    assert r["n_disagree"] == 0 and r["n_false_free"] == 0, r["disagreements"][:3]


@pytest.mark.parametrize("flat", ["panel", "triangle", "rod"])
def test_flat_robot_against_a_non_convex_obstacle(flat):
    from zoo import comb

    V, F = comb()
    R = {"panel": [[0, 0, 0], [0.6, 0, 0], [0.6, 0.4, 0], [0, 0.4, 0]],
         "triangle": [[0, 0, 0], [0.5, 0.1, 0.2], [0.1, 0.4, -0.3]],
         "rod": [[0, 0, 0], [0.3, 0.2, 0.1]]}[flat]
    R = np.asarray(R, dtype=np.float64)
    co = CSpaceObstacle.build((V, F), R, (0.05, 0.0, 0.0))
    assert co.kind == "mesh" and min(co.margin.steps) >= 1 and co.error_bound < 1e-5
    # FCL's fuzz on degenerate triangles; a rod has no triangles for a raw-mesh oracle, so
    # this one is judged on the snapped operands (exactness on its own input)
    r = cross_check(co, n=4000, seed=6, band=1e-6)
    assert r["n_disagree"] == 0 and r["n_false_free"] == 0, r["disagreements"][:3]
    S = minkowski_sum((V, F), R)  # the sum alone: B thickened by one step, stated
    assert S.stats["thickened_operands"] == 1 and S.error_bound < 1e-5


@pytest.mark.parametrize("k", [9, 12, 300])
def test_features_thinner_than_the_grid_are_answered_by_their_surface(k):
    """#17 class 1: an L plate 10^-k thick collapses on the grid. Its surface stands for it
    (the robot is thicker than the plate, so it can never lie inside): one convex piece per
    triangle, grown like every C-obstacle. Never its hull (the notch stays free), never a
    false free, false collisions within the stated bound (exact union-of-boxes reference)."""
    case = VoxelCase(l_cells(), (0.5, 0.5, 10.0 ** -k), (0.3, 0.3, 0.3))
    co = CSpaceObstacle.build((case.vertices, case.faces), case.robot)
    assert co.kind == "union" and "collapses" in co.thin
    assert co.error_bound < 1e-7
    _judged(case, co, 3000, k)
    notch = np.array([1.0, 1.0, 0.0])  # in the L's hull, 0.35 from the arms' C-obstacle
    assert not case.contains(notch[None])[0] and not co.contains(notch)
    assert not co.segment_free([1.0, 1.0, -1.0], [1.0, 0.1, 0.0])  # ends on the arm's CO
    r = cross_check(co, n=2000, seed=k, scene=raw_scene((case.vertices, case.faces), case.robot))
    assert r["n_false_free"] == 0


def test_a_flat_mesh_is_its_hull_only_when_it_is_convex():
    # A robot that could lie inside the collapsed L (it fits in the L's box on every axis):
    # the grown triangle pieces and the containment term of the snapped (flat) surface hold
    # every position inside, since the robot there lies within the snapping deviation of the
    # surface (the plate is 1e-9 thick); never hulled.
    from zoo import voxel_solid

    from cspace.check.oracle import SceneOracle

    occ = np.zeros((3, 3, 1), dtype=bool)
    occ[:, 0, 0] = occ[0, :, 0] = True
    V, F = voxel_solid(occ, 1.0)
    box = np.array([[x, y, z] for x in (-.15, .15) for y in (-.15, .15) for z in (-.15, .15)])
    plate, tiny = (V * [0.5, 0.5, 1e-9], F), box * 1e-12
    co = CSpaceObstacle.build(plate, tiny)
    assert co.kind == "union" and co.thin
    inside = np.array([[0.2, 0.2, 5e-10], [1.2, 0.2, 2e-10], [0.2, 1.3, 8e-10]])
    outside = np.array([[1.2, 1.2, 5e-10], [0.2, 0.2, 1e-3]])
    oracle = SceneOracle(raw_scene(plate, (tiny, _box_faces(tiny))))
    assert oracle.collides(inside).all() and co.contains(inside).all()
    assert not oracle.collides(outside).any() and not co.contains(outside).any()
    # A panel modelled two-sided (each triangle twice, opposite windings) is a flat convex
    # robot: accepted, and FCL agrees.
    P = np.array([[0, 0, 0], [.6, 0, 0], [.6, .4, 0], [0, .4, 0]], dtype=np.float64)
    PF = np.array([[0, 1, 2], [0, 2, 3], [2, 1, 0], [3, 2, 0]])
    co = CSpaceObstacle.build(3 * box, (P, PF))
    assert co.kind == "convex"
    r = cross_check(co, n=2000, seed=7, scene=raw_scene(3 * box, (P, PF)))
    assert r["n_disagree"] == 0 and r["n_false_free"] == 0


_TURNED = [("comb", 4, 0), ("comb", 8, 1), ("comb", 16, 2), ("grate", 3, 3), ("grate", 4, 4)]


@pytest.mark.parametrize("offset", [(0.0, 0.0, 0.0), (250.0, 150.0, -300.0)], ids=["origin", "far"])
@pytest.mark.parametrize("shape, teeth, seed", _TURNED + [
    pytest.param("comb", t, s, marks=pytest.mark.slow) for t in (5, 6, 7, 10, 12, 14) for s in (5, 6)])
def test_turned_combs_and_grates_keep_the_stated_bound(shape, teeth, seed, offset):
    """Combs (4-16 teeth) and grates turned by a random rotation, unit size, near the origin
    and far from it, summed with a turned box and an icosphere (issue #51: a turned comb
    once missed by 2.4 times the bound). Every point the raw inputs' exact sum holds on its
    boundary (``sum_support_points``) is held, or within ``error_bound`` of the surface; and
    points of our surface moved out by three times the bound are free for the raw inputs
    (brute-force feature distances in the scene's own frame, no FCL: its GJK tolerance
    reports contacts 1e-11 apart on robots this small)."""
    V, F = comb(teeth, 2) if shape == "comb" else grate(teeth)
    V = np.asarray(V, dtype=np.float64)
    V = random_rotation((V - V.mean(axis=0)) / np.ptp(V, axis=0).max(), seed) + offset
    for robot in (np.array([[x, y, z] for x in (-0.06, 0.07) for y in (-0.03, 0.04)
                            for z in (-0.02, 0.025)]),
                  __import__("trimesh").creation.icosphere(1, radius=0.05).vertices):
        R = random_rotation(robot, seed + 100)
        M = minkowski_sum((V, F), -R)
        co = CSpaceObstacle.from_mesh(M.vertices, M.faces)
        q = sum_support_points(V, F, -R, 1500, seed)
        out = ~co.contains(q)
        d = np.abs(co.signed_distance(q[out])) if out.any() else np.zeros(0)
        assert (d <= M.error_bound).all(), (d.max(), M.error_bound)
        # outwards: sample our surface, push out by 3 bounds, check free for the raw inputs
        rng = np.random.default_rng(seed)
        tri = M.vertices[M.faces]
        n = np.cross(tri[:, 1] - tri[:, 0], tri[:, 2] - tri[:, 0])
        area = np.linalg.norm(n, axis=1)
        f = rng.choice(len(tri), 40, p=area / area.sum())
        p = (np.einsum("ij,ijk->ik", rng.dirichlet([1, 1, 1], 40), tri[f])
             + n[f] / area[f, None] * 3 * M.error_bound)
        p = p[~co.contains(p)]  # pushed into another part of the sum: not a boundary point
        hull = ConvexHull(R)
        c = V.mean(axis=0)
        gap = brute_force_sum_distance(V - c, F, -R, hull.simplices[:, ::-1], p - c)
        assert (gap > 0).all(), gap.min()


def _two_boxes(kind: str):
    """Two closed unit boxes given as one mesh, sharing a face: concatenated (each box its own
    vertices; the shared square's diagonals cross), welded with the same triangles on the
    shared square (they cancel), welded with each box's own diagonal on it (the square's
    edges have four faces each: non-manifold), or a 2 x 2 box resting on a unit one (no
    vertex shared)."""
    import trimesh

    a = trimesh.creation.box((1.0, 1.0, 1.0))
    if kind == "big on small":
        b = trimesh.creation.box((2.0, 2.0, 1.0))
        b.apply_translation([0.0, 0.0, 1.0])
        boxes = [(-0.5, -0.5, -0.5, 0.5, 0.5, 0.5), (-1.0, -1.0, 0.5, 1.0, 1.0, 1.5)]
    else:
        b = trimesh.creation.box((1.0, 1.0, 1.0))
        if kind == "welded":  # the shared square triangulated alike from both sides
            b.apply_transform(trimesh.transformations.rotation_matrix(np.pi / 2, [1, 0, 0]))
        b.apply_translation([1.0, 0.0, 0.0])
        boxes = [(-0.5, -0.5, -0.5, 0.5, 0.5, 0.5), (0.5, -0.5, -0.5, 1.5, 0.5, 0.5)]
    m = trimesh.util.concatenate([a, b])
    if kind.startswith("welded"):
        m.merge_vertices()
    return np.asarray(m.vertices), np.asarray(m.faces), np.array(boxes)


@pytest.mark.parametrize("offset", [(0.0, 0.0, 0.0), (250.0, 150.0, -300.0)], ids=["origin", "far"])
@pytest.mark.parametrize("kind", ["concatenated", "welded", "welded, triangulated differently",
                                  "big on small"])
def test_closed_bodies_sharing_a_face_are_summed_as_their_union(kind, offset):
    """Issue #51: two closed boxes sharing a face, given as one mesh, are a valid solid (their
    union), not a refused one. Welded with the same triangles on the shared square, the two
    copies of each cancel (interior) and the union's boundary is summed as one body;
    welded with each box's own diagonal on the square, the faces at its non-manifold edges
    pair into the two closed boxes; otherwise too the bodies' sums are united exactly: one
    surface either way. Checked against
    the exact sum of the raw boxes (each box ⊕ -R is a box: exact bounds), at the origin
    and far."""
    V, F, boxes = _two_boxes(kind)
    if kind == "welded, triangulated differently":  # as the test says: 4 edges, 4 faces each
        from cspace.mesh.components import edge_uses

        assert (edge_uses(F, len(V))[1] == 4).sum() == 4
    V = V + offset
    boxes = boxes + np.tile(offset, 2)
    R = np.array([[x, y, z] for x in (-0.1, 0.15) for y in (-0.2, 0.1) for z in (-0.05, 0.1)])
    M = minkowski_sum((V, F), -R)
    assert len(M.pieces) == (0 if kind == "welded" else 2)  # welded: one body
    lo = boxes[:, :3] - R.max(axis=0)
    hi = boxes[:, 3:] - R.min(axis=0)
    # one surface: the union's exact volume (two boxes less their overlap)
    union = (np.prod(hi - lo, axis=1).sum()
             - np.prod(np.maximum(0.0, np.minimum(hi[0], hi[1]) - np.maximum(lo[0], lo[1]))))
    assert abs(M.volume - union) < 1e-6 * union
    rng = np.random.default_rng(3)
    q = rng.uniform(lo.min(axis=0) - 0.2, hi.max(axis=0) + 0.2, (3000, 3))
    truth = ((q[:, None] >= lo[None]) & (q[:, None] <= hi[None])).all(axis=2).any(axis=1)
    # nearest face of the truth, to leave out points within the bound of the boundary
    gap = np.min(np.abs(np.concatenate([q[:, None] - lo[None], q[:, None] - hi[None]], 1)),
                 axis=(1, 2))
    ours = CSpaceObstacle.from_mesh(M.vertices, M.faces).contains(q)
    clear = gap > M.error_bound
    assert (ours[clear] == truth[clear]).all()
    assert truth.sum() > 500 and (~truth).sum() > 500


def test_a_double_sided_face_of_one_body_is_still_named():
    """A face listed with both windings on one closed box is not two bodies' shared face:
    without both copies the box is open, so the operand's own error stands."""
    from cspace.errors import DuplicateFaceError
    import trimesh

    b = trimesh.creation.box((1.0, 1.0, 1.0))
    F = np.vstack([b.faces, b.faces[2, ::-1]])
    with pytest.raises(DuplicateFaceError, match="double-sided"):
        minkowski_sum((b.vertices, F), 0.1 * b.vertices)


@pytest.mark.parametrize("offset", [(0.0, 0.0, 0.0), (250.0, 150.0, -300.0)], ids=["origin", "far"])
def test_closed_bodies_crossing_each_other_are_summed_as_their_union(offset):
    """Two closed boxes given as one mesh that pass through each other (each valid, the
    mesh crossing itself only where the bodies cross) are a union, not a refused solid: one
    surface, its exact volume the union's, and every point decided as the raw boxes' exact
    sum decides it (a single body folded through itself is still named:
    ``test_bad_input.test_self_intersecting_obstacle_is_named_not_built``)."""
    import trimesh

    a = trimesh.creation.box((1.0, 0.4, 0.4))
    b = trimesh.creation.box((0.4, 1.0, 0.4))
    b.apply_translation([0.2, 0.1, 0.05])
    m = trimesh.util.concatenate([a, b])
    V, F = np.asarray(m.vertices) + offset, np.asarray(m.faces)
    boxes = np.array([[-0.5, -0.2, -0.2, 0.5, 0.2, 0.2],
                      [0.0, -0.4, -0.15, 0.4, 0.6, 0.25]]) + np.tile(offset, 2)
    R = np.array([[x, y, z] for x in (-0.05, 0.1) for y in (-0.1, 0.05) for z in (-0.05, 0.05)])
    M = minkowski_sum((V, F), -R)
    assert len(M.pieces) == 2 and len(M.parts) == 2
    lo, hi = boxes[:, :3] - R.max(axis=0), boxes[:, 3:] - R.min(axis=0)
    union = (np.prod(hi - lo, axis=1).sum()
             - np.prod(np.maximum(0.0, np.minimum(hi[0], hi[1]) - np.maximum(lo[0], lo[1]))))
    assert abs(M.volume - union) < 1e-6 * union
    q = np.random.default_rng(4).uniform(lo.min(axis=0) - 0.1, hi.max(axis=0) + 0.1, (3000, 3))
    truth = ((q[:, None] >= lo[None]) & (q[:, None] <= hi[None])).all(axis=2).any(axis=1)
    gap = np.min(np.abs(np.concatenate([q[:, None] - lo[None], q[:, None] - hi[None]], 1)),
                 axis=(1, 2))
    ours = CSpaceObstacle.from_mesh(M.vertices, M.faces).contains(q)
    clear = gap > M.error_bound
    assert (ours[clear] == truth[clear]).all() and 500 < truth.sum() < 2500
