"""The clearance kernel (robot at any pose against obstacle triangles) and certified motions.

Checked against what shares nothing with it: FCL's distance and collision on the raw meshes
(its own BVH and triangle code), at poses far from the origin, with sliver triangles; the
compiled triangle-pair distance against its pure-Python reference; the tree query against
brute force over every pair; certified motions against FCL sampled densely along them.
"""

from __future__ import annotations

import numpy as np
import pytest
import trimesh
from scipy.spatial.transform import Rotation, Slerp

from cspace.geometry._kernels import load
from cspace.geometry.boxes import BoxTree
from cspace.geometry.clearance import (
    MeshClearance,
    _distance_reference,
    _pair_distances_reference,
    node_boxes,
    sliver_radii,
)

from oracles import fcl_bvh
from real_problems import split_long_edges, t_robot

fcl = pytest.importorskip("fcl")

FAR = np.array([250.0, 150.0, -300.0])


class _Fcl:
    """FCL on the raw meshes: the robot (vertices relative to its reference point) at
    ``(q, R)`` against the obstacle mesh."""

    def __init__(self, OV, OF, RV, RF):
        self.obstacle = fcl.CollisionObject(fcl_bvh(OV, OF))
        self.robot = fcl_bvh(RV, RF)

    def at(self, R, q):
        return fcl.CollisionObject(self.robot, fcl.Transform(np.asarray(R), np.asarray(q)))

    def collides(self, R, q) -> bool:
        return fcl.collide(self.at(R, q), self.obstacle, fcl.CollisionRequest(),
                           fcl.CollisionResult()) > 0

    def distance(self, R, q) -> float:
        return fcl.distance(self.at(R, q), self.obstacle, fcl.DistanceRequest(),
                            fcl.DistanceResult())


def _triangles(rng, n, spread):
    A = rng.normal(size=(n, 3, 3))
    B = rng.normal(size=(n, 3, 3)) + rng.normal(size=(n, 1, 3)) * spread
    # slivers, degenerate triangles, shared vertices, coplanar pairs
    A[: n // 10, 2] = A[: n // 10, 0] + 1e-9 * (A[: n // 10, 1] - A[: n // 10, 0])
    B[n // 10: n // 5, 2] = B[n // 10: n // 5, 1]
    B[n // 5: n // 4, 0] = A[n // 5: n // 4, 1]
    B[n // 4: n // 3, :, 2] = A[n // 4: n // 3, :, 2] = 0.0
    return A, B


@pytest.mark.parametrize("shift", [0.0, 1e3], ids=["at the origin", "shifted by 1e3"])
def test_pair_distances_match_the_reference(shift):
    rng = np.random.default_rng(0)
    A, B = _triangles(rng, 20000, 0.7)
    A, B = A + shift, B + shift
    ra, rb = sliver_radii(A), sliver_radii(B)
    got = load("clearance").pair_distances(np.ascontiguousarray(A.reshape(-1, 9)),
                                           np.ascontiguousarray(B.reshape(-1, 9)), ra, rb)
    ref = _pair_distances_reference(A, B, ra, rb)
    assert (ra > 0).sum() >= 2000 and ((got == 0) == (ref == 0)).all()
    assert np.abs(got - ref).max() <= 1e-12 * (1 + shift), np.abs(got - ref).max()


def test_pair_distance_is_zero_for_crossing_triangles_and_exact_for_parallel_ones():
    K = load("clearance")
    T = np.array([[0.0, 0, 0], [1, 0, 0], [0, 1, 0]])
    # an X: the second triangle pierces the first's interior, no corner near the other
    X = np.array([[0.2, 0.2, -1], [0.3, 0.2, 1], [0.2, 0.3, 1]])
    # parallel, 0.5 above
    P = T + [0.1, 0.1, 0.5]
    rows = np.array([[T, X], [T, P]])
    d = K.pair_distances(np.ascontiguousarray(rows[:, 0].reshape(-1, 9)),
                         np.ascontiguousarray(rows[:, 1].reshape(-1, 9)),
                         -np.ones(2), -np.ones(2))
    assert d[0] == 0.0 and d[1] == pytest.approx(0.5, abs=1e-15)


@pytest.mark.parametrize("leaf", [1, 3, 8])
@pytest.mark.parametrize("offset", [0.0, 250.0, -3e5])
def test_every_node_box_holds_its_triangles(leaf, offset):
    """The query prunes a node pair by its oriented boxes: each node's box must hold every
    corner of the triangles under it (a needle-thin sliver, a flat patch and a random
    cloud, far from the origin too), with orthonormal axes."""
    rng = np.random.default_rng(leaf)
    T = np.concatenate([rng.normal(size=(300, 3, 3)) * 0.2 + rng.uniform(-5, 5, (300, 1, 3)),
                        np.array([[[0, 0, 0], [1, 1e-9, 0], [2, 2e-9, 1e-12]]]),  # a sliver
                        rng.normal(size=(40, 3, 3)) * [1.0, 1.0, 0.0]]) + offset  # flat
    tree = BoxTree(T.min(axis=1), T.max(axis=1), leaf)
    B = node_boxes(tree, T, chunk=997)  # several chunks
    c, axes, half = B[:, :3], B[:, 3:12].reshape(-1, 3, 3), B[:, 12:]
    assert np.abs(np.einsum("kij,klj->kil", axes, axes) - np.eye(3)).max() < 1e-12
    # each node's triangles: a leaf's own, an inner node's its children's
    under = [None] * len(tree.first)
    for k in range(len(tree.first) - 1, -1, -1):
        f = tree.first[k]
        under[k] = (tree.order[f: f + tree.count[k]] if tree.count[k]
                    else np.concatenate([under[f], under[f + 1]]))
        P = T[under[k]].reshape(-1, 3)
        assert (np.abs((P - c[k]) @ axes[k].T) <= half[k]).all(), k


def test_query_matches_brute_force_over_every_pair():
    rng = np.random.default_rng(1)
    obs = trimesh.creation.icosphere(2, radius=1.0)
    V, F = t_robot(6)
    V = (V - V.mean(axis=0)) * 0.02
    mc = MeshClearance(obs.vertices + FAR, obs.faces, V, F, reach=600.0)
    for k in range(25):
        R = Rotation.random(random_state=k).as_matrix()
        q = FAR + rng.normal(size=3) * 1.2
        assert mc.distance(R, q) == pytest.approx(_distance_reference(mc, R, q), abs=1e-12)


@pytest.mark.parametrize("where", ["origin", "far", "far and scaled"])
def test_clearance_agrees_with_fcl_on_raw_meshes_and_never_over_the_truth(where):
    """Every pose: FCL in collision -> ours within the error bound of 0; free -> ours never
    more than the error bound over FCL's distance (so the lower bound, ours minus the bound,
    is below the truth: never a false free), and short of it by at most that plus the
    slivers' inradii. A non-convex robot with slivers, a non-convex obstacle."""
    shift, scale = {"origin": (0.0, 1.0), "far": (FAR, 1.0), "far and scaled": (FAR, 37.0)}[where]
    rng = np.random.default_rng(2)
    a = trimesh.creation.annulus(r_min=0.5, r_max=1.0, height=0.6, sections=24)
    b = trimesh.creation.box((0.3, 2.5, 0.3))
    OV = np.concatenate([a.vertices, b.vertices + [0.0, 0.0, 1.0]]) * scale + shift
    OF = np.concatenate([a.faces, b.faces + len(a.vertices)])
    # slivers of both kinds: split at 1e-3 (conditioned normals) and 1e-7 (taken as edges)
    V, F = split_long_edges(t_robot(12), 1e-7, 6)
    RV = (V - V.mean(axis=0)) * 0.012 * scale
    mc = MeshClearance(OV, OF, RV, F, reach=float(np.abs(shift).max() + 3 * scale))
    oracle = _Fcl(OV, OF, RV, F)
    slivers = sliver_radii(RV[F])
    assert (slivers > 0).any()
    # a sliver's distances are its edges' less its inradius: ours may be short by that much
    slack = mc.error_bound + slivers.max() + max(sliver_radii(OV[OF]).max(), 0.0)
    hits = free = 0
    for k in range(300):
        R = Rotation.random(random_state=100 + k).as_matrix()
        q = shift + rng.normal(size=3) * 0.8 * scale
        d = mc.distance(R, q)
        if oracle.collides(R, q):
            hits += 1
            assert d <= mc.error_bound, (k, d)
        else:
            free += 1
            truth = oracle.distance(R, q)
            assert truth - slack <= d <= truth + mc.error_bound, (k, d, truth)
            assert mc.lower_bound(R, q) <= truth
    assert hits > 30 and free > 30


def test_a_capped_query_answers_below_the_cap_and_stops_above_it():
    obs = trimesh.creation.box((1.0, 1.0, 1.0))
    rob = trimesh.creation.box((0.2, 0.2, 0.2))
    mc = MeshClearance(obs.vertices + FAR, obs.faces, rob.vertices, rob.faces, reach=600.0)
    q = FAR + [1.5, 0.0, 0.0]  # 0.9 apart
    assert mc.distance(np.eye(3), q) == pytest.approx(0.9, abs=1e-12)
    assert mc.distance(np.eye(3), q, cap=2.0) == pytest.approx(0.9, abs=1e-12)
    assert mc.distance(np.eye(3), q, cap=0.5) >= 0.5
    assert mc.lower_bound(np.eye(3), q, cap=0.5) >= 0.5 - mc.error_bound


def test_a_lower_bound_within_a_factor_is_below_the_truth_and_not_far_below():
    """``grow``: pairs pruned within a factor; what is returned is never above the distance
    (never a false free) and at least the distance over the factor."""
    rng = np.random.default_rng(5)
    a = trimesh.creation.annulus(r_min=0.5, r_max=1.0, height=0.6, sections=24)
    V, F = t_robot(12)
    RV = (V - V.mean(axis=0)) * 0.01
    mc = MeshClearance(a.vertices + FAR, a.faces, RV, F, reach=600.0)
    k = mc._k
    for i in range(200):
        R = Rotation.random(random_state=300 + i).as_matrix()
        q = FAR + rng.normal(size=3) * 1.2
        d = mc.distance(R, q)
        for grow in (1.25, 4.0):
            lb = k.distance(np.ascontiguousarray(R), q, np.inf, grow)
            assert d / grow - 1e-12 <= lb <= d + 1e-12, (i, grow, lb, d)
            capped = k.distance(np.ascontiguousarray(R), q, 0.3, grow)
            assert capped <= d + 1e-12 and (d < 0.3 or capped >= 0.3 / grow - 1e-12)


def _dense_collisions(oracle, q0, Q0, q1, Q1, n=4000) -> int:
    slerp = Slerp([0.0, 1.0], Rotation.from_quat([Q0, Q1]))
    t = np.linspace(0.0, 1.0, n)
    Rs = slerp(t).as_matrix()
    return sum(oracle.collides(R, q0 + s * (q1 - q0)) for s, R in zip(t, Rs))


def test_certified_motions_are_free_and_blocked_ones_are_not_certified():
    """Random motions (translation and slerp together) past a non-convex obstacle: every
    certified one is free at 4000 poses along it by FCL; one that FCL sees collide is never
    certified; a turn in place about the reference point counts its sweep (rho * angle)."""
    rng = np.random.default_rng(3)
    a = trimesh.creation.annulus(r_min=0.5, r_max=1.0, height=0.6, sections=24)
    OV, OF = a.vertices + FAR, a.faces
    V, F = t_robot(12)
    RV = (V - V.mean(axis=0)) * 0.008
    mc = MeshClearance(OV, OF, RV, F, reach=600.0)
    oracle = _Fcl(OV, OF, RV, F)
    certified = blocked = 0
    for k in range(80):
        q0 = FAR + rng.normal(size=3) * 0.9
        q1 = q0 + rng.normal(size=3) * 0.3
        Q0, Q1 = Rotation.random(2, random_state=200 + k).as_quat()
        free, depth, n = mc.motion_free(q0, Q0, q1, Q1)
        bad = _dense_collisions(oracle, q0, Q0, q1, Q1)
        if free:
            certified += 1
            assert bad == 0, k
        elif bad:
            blocked += 1
    assert certified >= 10 and blocked >= 10, (certified, blocked)


def test_a_turn_in_place_counts_its_sweep():
    """A bar turning about its centre: free at both ends, through a cube halfway (not
    certified); a smaller turn that stays clear is certified, and FCL agrees along it."""
    bar = trimesh.creation.box((2.0, 0.1, 0.1))
    cube = trimesh.creation.box((0.1, 0.1, 0.1))
    mc = MeshClearance(cube.vertices + FAR + [0.0, 0.7, 0.0], cube.faces, bar.vertices,
                       bar.faces, reach=600.0)
    oracle = _Fcl(cube.vertices + FAR + [0.0, 0.7, 0.0], cube.faces, bar.vertices, bar.faces)
    I = np.array([0.0, 0.0, 0.0, 1.0])
    far_turn = Rotation.from_euler("z", 170, degrees=True).as_quat()
    near_turn = Rotation.from_euler("z", 30, degrees=True).as_quat()
    assert mc.lower_bound(np.eye(3), FAR) > 0
    assert mc.lower_bound(Rotation.from_quat(far_turn).as_matrix(), FAR) > 0
    assert _dense_collisions(oracle, FAR, I, FAR, far_turn) > 0
    assert not mc.motion_free(FAR, I, FAR, far_turn)[0]
    free, depth, n = mc.motion_free(FAR, I, FAR, near_turn)
    assert free and _dense_collisions(oracle, FAR, I, FAR, near_turn) == 0
