"""The test oracles and the mesh zoo, proven on cases with known answers.

- ``winding_number``: cube and torus (1 inside, 0 outside), weights, reversed meshes,
  voxel solids against their occupancy arrays (exact membership), blocking invariance.
- ``FclSolid``: box cases (far, overlapping, contained: where plain FCL says False), voxel
  obstacles with an axis-aligned box robot against exact box-box geometry, and convex
  obstacles against the exact convex Minkowski sum of cspace.
- the zoo: every mesh is a valid ClosedMesh, outward, with the expected Euler
  characteristic (genus), watertight for trimesh; voxel manifold checks are exhaustive on
  2x2x2 blocks.
"""

from __future__ import annotations

import itertools
import time
from fractions import Fraction

import fcl
import numpy as np
import pytest
import trimesh

import oracles
import zoo
from cspace import ClosedMesh, ConvexPolytope, Grid, convex_minkowski_sum
from cspace.errors import InvalidMeshError
from oracles import FclSolid, membership_disagreements, winding_number

RNG_SEED = 20240611


def unit_cube():
    return zoo.voxel_solid(np.ones((1, 1, 1), dtype=bool), size=1.0, origin=(-0.5, -0.5, -0.5))


# --------------------------------------------------------------------------------------
# winding number


def test_winding_number_cube():
    V, F = unit_cube()
    rng = np.random.default_rng(RNG_SEED)
    inside = rng.uniform(-0.45, 0.45, (2000, 3))
    outside = rng.uniform(-2, 2, (6000, 3))
    outside = outside[np.abs(outside).max(axis=1) > 0.55]
    assert np.abs(winding_number(V, F, inside) - 1).max() < 1e-12
    assert np.abs(winding_number(V, F, outside)).max() < 1e-12
    # The centre sees each of the 6 faces under 4 pi / 6 exactly (up to rounding).
    assert winding_number(V, F, [[0.0, 0.0, 0.0]])[0] == pytest.approx(1.0, abs=1e-15)


def test_winding_number_torus():
    V, F = zoo.torus()  # major 1, minor 0.35, inscribed polyhedron: tube radius >= 0.346
    rng = np.random.default_rng(RNG_SEED)
    n = 1500
    u, v = rng.uniform(0, 2 * np.pi, n), rng.uniform(0, 2 * np.pi, n)
    r = 0.25 * np.sqrt(rng.uniform(0, 1, n))
    ring = 1 + r * np.cos(v)
    tube = np.stack([ring * np.cos(u), ring * np.sin(u), r * np.sin(v)], axis=1)
    rho = 0.6 * np.sqrt(rng.uniform(0, 1, n))
    hole = np.stack([rho * np.cos(u), rho * np.sin(u), rng.uniform(-0.5, 0.5, n)], axis=1)
    far = rng.uniform(-2, 2, (3 * n, 3))
    radial = np.hypot(far[:, 0], far[:, 1])
    far = far[(np.hypot(radial - 1, far[:, 2]) > 0.4)]
    assert np.abs(winding_number(V, F, tube) - 1).max() < 1e-12
    assert np.abs(winding_number(V, F, hole)).max() < 1e-12
    assert np.abs(winding_number(V, F, far)).max() < 1e-12


def test_winding_number_weights_and_reversal():
    V, F = zoo.star()
    rng = np.random.default_rng(RNG_SEED)
    P = rng.uniform(-1.6, 1.6, (3000, 3))
    w = winding_number(V, F, P)
    twice = np.vstack([F, F])
    assert np.abs(winding_number(V, twice, P, weights=np.full(len(twice), 0.5)) - w).max() < 1e-12
    assert np.abs(winding_number(V, twice, P) - 2 * w).max() < 1e-12
    assert np.abs(winding_number(V, F[:, ::-1], P) + w).max() < 1e-12
    # Integer multiplicities: a mesh with weight 3 plus its reverse with weight 1 -> 2w.
    both = np.vstack([F, F[:, ::-1]])
    weights = np.r_[np.full(len(F), 3.0), np.ones(len(F))]
    assert np.abs(winding_number(V, both, P, weights=weights) - 2 * w).max() < 1e-12
    # Star membership is 0 or 1 away from the surface; both occur.
    assert np.abs(w - np.round(w)).max() < 1e-9
    assert set(np.round(w).astype(int).tolist()) == {0, 1}


def test_winding_number_blocking_invariance():
    V, F = zoo.torus(sections=12, ring=8)
    P = np.random.default_rng(RNG_SEED).uniform(-1.5, 1.5, (257, 3))
    ref = winding_number(V, F, P)
    for chunk in (1, 7, 100, 1 << 20):
        sub = slice(None, 20) if chunk == 1 else slice(None)
        assert np.abs(winding_number(V, F, P[sub], chunk=chunk) - ref[sub]).max() < 1e-13
    assert winding_number(V, F, np.zeros((0, 3))).shape == (0,)
    with pytest.raises(ValueError):
        winding_number(V, F, P, weights=np.ones(3))


@pytest.mark.parametrize(
    "name", ["grate", "cup", "hollow_box", "stairs", "comb", "genus3", "l_shape"]
)
def test_winding_number_matches_voxel_occupancy(name):
    """Voxel solids have exact membership: the occupancy of the cell holding the point."""
    occupancy = {
        "grate": lambda: zoo.grate_occupancy(3),
        "cup": zoo.cup_occupancy,
        "hollow_box": zoo.hollow_box_occupancy,
        "stairs": lambda: zoo.stairs_occupancy(5, 3),
        "comb": lambda: zoo.comb_occupancy(5, 2),
        "genus3": zoo.genus3_occupancy,
        "l_shape": lambda: _l_occ(2, 1),
    }[name]()
    V, F = zoo.voxel_solid(occupancy)
    assert np.array_equal(V, getattr(zoo, name)()[0]) and np.array_equal(F, getattr(zoo, name)()[1])
    rng = np.random.default_rng(RNG_SEED)
    shape = np.array(occupancy.shape)
    cells = rng.integers(-1, shape + 1, (4000, 3))
    P = cells + rng.uniform(0.05, 0.95, (4000, 3))  # at least 0.05 from every lattice plane
    padded = np.pad(occupancy, 1)
    truth = padded[tuple((cells + 1).T)]
    w = winding_number(V, F, P)
    assert np.abs(w - truth).max() < 1e-9


def _l_occ(arm, depth):
    occ = np.zeros((arm + 1, arm + 1, depth), dtype=bool)
    occ[:, 0] = True
    occ[0, :] = True
    return occ


def _throughput(n_points: int, sections: int, ring: int) -> tuple[float, float]:
    V, F = zoo.torus(sections=sections, ring=ring)
    P = np.random.default_rng(RNG_SEED).uniform(-1.5, 1.5, (n_points, 3))
    t = time.perf_counter()
    w = winding_number(V, F, P)
    dt = time.perf_counter() - t
    assert np.abs(w - np.round(w)).max() < 1e-6  # random points: none within ~1e-6 of a face
    return dt, n_points * len(F) / dt


def test_winding_number_throughput_small():
    dt, rate = _throughput(1000, 48, 24)  # 1000 x 2304 pairs
    print(f"winding number: 1000 x 2304 pairs in {dt:.3f} s = {rate / 1e6:.1f} M pairs/s")


@pytest.mark.slow
def test_winding_number_throughput_1e4_by_1e4():
    dt, rate = _throughput(10_000, 100, 50)  # 10^4 points x 10^4 triangles
    print(f"winding number: 1e4 x 1e4 pairs in {dt:.2f} s = {rate / 1e6:.1f} M pairs/s")
    assert dt < 60


# --------------------------------------------------------------------------------------
# FclSolid


def box_robot(extent):
    R = ConvexPolytope.from_points(zoo.box_points(extent, extent, extent))
    return R.vertices, R.faces


def test_fcl_solid_box_cases():
    V, F = zoo.voxel_solid(np.ones((1, 1, 1), dtype=bool), size=4.0, origin=(-2, -2, -2))
    rv, rf = box_robot(0.5)
    S = FclSolid(V, F)
    q = np.array([[10.0, 0, 0], [2.0, 0, 0], [0.0, 0, 0], [1.5, 0.3, -1.2]])
    assert S.collides(rv, rf, q).tolist() == [False, True, True, True]
    # Plain FCL against the hollow BVH misses the contained robots: why the oracle exists.
    assert S.surface_contacts(rv, rf, q).tolist() == [False, True, False, False]
    bvh = fcl.BVHModel()
    bvh.beginModel(len(F), len(V))
    bvh.addSubModel(np.asarray(V, np.float64), np.asarray(F, np.int64))
    bvh.endModel()
    robot = fcl.CollisionObject(oracles._convex(rv, rf), fcl.Transform(np.eye(3), np.zeros(3)))
    assert fcl.collide(robot, fcl.CollisionObject(bvh, fcl.Transform())) == 0
    # Distances: 10 - 0.25 - 2 outside; to the surface for contained robots.
    d = S.distance(rv, rf, q)
    assert d[0] == pytest.approx(7.75, abs=1e-12)
    assert d[2] == pytest.approx(1.75, abs=1e-12)
    assert d[3] == pytest.approx(0.25, abs=1e-12)
    c = S.classify(rv, rf, q)
    assert c.inside.tolist() == [False, True, True, True]
    assert c.contained.tolist() == [False, False, True, True]
    assert np.isnan(c.distance[1])
    assert c.clearance.tolist() == pytest.approx([7.75, 1e-9, 1.75, 0.25], abs=1e-12)


def test_fcl_solid_band_depth_test():
    """A surface contact gets clearance ``band`` only if it is at least ``band`` deep."""
    V, F = zoo.voxel_solid(np.ones((1, 1, 1), dtype=bool), size=4.0, origin=(-2, -2, -2))
    rv, rf = box_robot(0.5)
    S = FclSolid(V, F)
    band = 1e-6
    q = np.array([[2.25 - 1e-7, 0.1, 0.2], [2.25 - 1e-5, 0.1, 0.2], [2.25 + 1e-5, 0.1, 0.2]])
    c = S.classify(rv, rf, q, band=band)
    assert c.inside.tolist() == [True, True, False]
    assert c.surface.tolist() == [True, True, False]
    assert c.clearance[0] == 0.0  # 1e-7 deep: within the band, undecided
    assert c.clearance[1] == band  # 1e-5 deep: certified deeper than the band
    assert c.clearance[2] == pytest.approx(1e-5, rel=1e-6)


def test_fcl_solid_translations_validation():
    V, F = unit_cube()
    rv, rf = box_robot(0.1)
    S = FclSolid(V, F)
    assert S.collides(rv, rf, [0, 0, 0]).tolist() == [True]  # one translation, any dtype
    assert S.collides(rv, rf, np.array([[3, 0, 0]], dtype=np.int32)).tolist() == [False]
    with pytest.raises(ValueError):
        S.collides(rv, rf, [[np.nan, 0, 0]])


def _box_voxel_truth(occ, q, h):
    """Exact: does the closed box [q-h, q+h] meet the closed union of voxels, and how far is it?"""
    lo, hi = q - h, q + h
    cells = np.argwhere(occ)  # voxel [c, c+1]
    # Per-axis gap between intervals [lo, hi] and [c, c+1] (0 if they overlap).
    gap = np.maximum(0.0, np.maximum(cells[None] - hi[:, None], lo[:, None] - (cells[None] + 1)))
    dist = np.sqrt((gap**2).sum(axis=2)).min(axis=1)
    return dist == 0, dist


@pytest.mark.parametrize("name", ["grate", "hollow_box", "cup"])
def test_fcl_solid_matches_exact_box_geometry(name):
    occ = {"grate": zoo.grate_occupancy(2), "hollow_box": zoo.hollow_box_occupancy(), "cup": zoo.cup_occupancy()}[name]
    V, F = zoo.voxel_solid(occ)
    h = 0.1875  # dyadic: the snapped robot is exactly [-h, h]^3
    rv, rf = box_robot(2 * h)
    assert rv.max() == h and rv.min() == -h
    rng = np.random.default_rng(RNG_SEED)
    q = rng.uniform(-1, np.array(occ.shape) + 1, (3000, 3))
    # Keep the robot's faces at least 1e-3 from every lattice plane (no touching cases).
    frac = lambda x: np.abs(x - np.round(x))  # noqa: E731
    q = q[(np.minimum(frac(q - h), frac(q + h)) > 1e-3).all(axis=1)]
    truth, dist = _box_voxel_truth(occ, q, h)
    S = FclSolid(V, F)
    c = S.classify(rv, rf, q)
    assert np.array_equal(c.inside, truth)
    assert c.contained.sum() > 0 and (c.surface.sum() > 0) and (~c.inside).sum() > 0
    out = ~c.inside
    assert np.abs(c.distance[out] - dist[out]).max() < 1e-12  # exact distance to the C-obstacle
    if name == "hollow_box":  # a robot floating in the cavity is free
        centre = np.array([[1.5, 1.5, 1.5]])
        assert S.collides(rv, rf, centre).tolist() == [False]
        assert S.surface_contacts(rv, rf, centre).tolist() == [False]


def _convex_case(seed):
    rng = np.random.default_rng(seed)
    pts_o = zoo.hull20(seed)
    robots = [zoo.cube_rotated(rng.uniform(0, np.pi), size=0.25),
              zoo.icosphere_points(1, radius=0.15), zoo.hull20(seed + 100, scale=(0.2, 0.15, 0.1))]
    pts_r = robots[seed % 3] + rng.uniform(-0.05, 0.05, 3)  # reference point off-centre
    grid = Grid.for_points(pts_o, pts_r)
    O = ConvexPolytope.from_points(pts_o, grid=grid, name="O")
    R = ConvexPolytope.from_points(pts_r, grid=grid, name="R")
    return O, R, convex_minkowski_sum(O, R.reflected())


@pytest.mark.parametrize("seed", [0, 1, 2])
def test_fcl_solid_matches_convex_minkowski_sum(seed):
    """For convex O and R, q collides iff q is in O ⊕ (-R), computed exactly by cspace."""
    O, R, CO = _convex_case(seed)
    rng = np.random.default_rng(RNG_SEED + seed)
    lo, hi = CO.vertices.min(axis=0) - 0.2, CO.vertices.max(axis=0) + 0.2
    uniform = rng.uniform(lo, hi, (10_000, 3))
    # Near the boundary too: surface samples of CO moved along the normal by +-1e-8 .. 1e-3.
    co = trimesh.Trimesh(CO.vertices, CO.faces, process=False)
    pts, fid = trimesh.sample.sample_surface(co, 2000, seed=seed)
    offset = rng.choice([-1, 1], 2000) * 10 ** rng.uniform(-8, -3, 2000)
    near = pts + co.face_normals[fid] * offset[:, None]
    Q = np.vstack([uniform, near])
    S = FclSolid(O.vertices, O.faces)
    c = S.classify(R.vertices, R.faces, Q)
    ours = winding_number(CO.vertices, CO.faces, Q) > 0.5
    assert np.array_equal(S.collides(R.vertices, R.faces, Q[::10]), c.inside[::10])
    report = membership_disagreements(ours, c.inside, c.clearance, band=1e-9)
    assert report["ok"], report
    assert report["n_in_band"] == 0
    assert c.contained.sum() > 0 and c.surface.sum() > 0 and (~c.inside).sum() > 0
    # Outside CO, the FCL distance is the distance from q to CO (checked on a subset).
    out = np.nonzero(~c.inside)[0][:300]
    tri = CO.vertices[CO.faces]
    rep = np.repeat(Q[out], len(tri), axis=0)
    cp = trimesh.triangles.closest_point(np.tile(tri, (len(out), 1, 1)), rep)
    exact = np.linalg.norm(cp - rep, axis=1).reshape(len(out), -1).min(axis=1)
    assert np.abs(c.distance[out] - exact).max() < 1e-12


def test_membership_disagreements_report():
    ours = np.array([True, False, True, False, True])
    fcl_in = np.array([True, True, False, False, False])
    d = np.array([0.5, 0.3, 1e-12, 0.2, 2e-9])
    r = membership_disagreements(ours, fcl_in, d, band=1e-9)
    assert r["n"] == 5 and r["n_disagree"] == 2 and r["n_in_band"] == 1
    assert r["indices"].tolist() == [1, 4]
    assert r["false_inside"] == 1 and r["false_outside"] == 1
    assert r["max_clearance"] == 0.3 and not r["ok"]
    assert membership_disagreements(ours, ours, d)["ok"]
    with pytest.raises(ValueError, match="non-negative"):
        membership_disagreements(ours, fcl_in, -np.ones(5))
    with pytest.raises(ValueError, match="length"):
        membership_disagreements(ours, fcl_in[:3], d)


# --------------------------------------------------------------------------------------
# the zoo


@pytest.mark.parametrize("name", list(zoo.ZOO))
def test_zoo_mesh_is_valid_closed_mesh(name):
    build, chi = zoo.ZOO[name]
    V, F = build()
    assert V.dtype == np.float64 and V.shape[1] == 3 and F.dtype == np.int64 and F.shape[1] == 3
    m = ClosedMesh.from_arrays(V, F, name=name)
    assert np.array_equal(m.faces, F), "faces must come out unchanged: already outward"
    assert len(m.vertices) == len(V), "every vertex used, none welded"
    assert m.volume > 0
    assert zoo.euler_characteristic(V, F) == chi
    t = trimesh.Trimesh(V, F, process=False)
    assert t.is_watertight and t.is_winding_consistent
    assert t.volume == pytest.approx(m.volume, rel=1e-6)


def test_zoo_genus_and_sizes():
    genus = {name: (2 - zoo.euler_characteristic(*zoo.ZOO[name][0]())) // 2 for name in zoo.ZOO}
    assert genus["torus"] == 1 and genus["genus3"] == 3 and genus["grate"] == 9
    for name in ("l_shape", "comb", "cup", "stairs", "star", "twisted_prism"):
        assert genus[name] == 0, name
    for n in (1, 2, 4):
        V, F = zoo.grate(n)
        ClosedMesh.from_arrays(V, F)
        assert zoo.euler_characteristic(V, F) == 2 - 2 * n * n
    sizes = {name: len(zoo.ZOO[name][0]()[1]) for name in zoo.ZOO}
    assert sizes["torus"] == 2304 and sizes["star"] == 60 and sizes["twisted_prism"] == 8
    print("zoo triangle counts:", sizes)


def test_zoo_non_convex_shapes():
    for name in ("star", "twisted_prism", "l_shape", "torus"):
        V, F = zoo.ZOO[name][0]()
        m = ClosedMesh.from_arrays(V, F)
        hull = ConvexPolytope.from_ints(m.ints, grid=m.grid)
        assert m.volume < 0.99 * hull.volume, name
    # The twisted prism is rotated: no face normal is along an axis.
    V, F = zoo.twisted_prism()
    n = np.cross(V[F[:, 1]] - V[F[:, 0]], V[F[:, 2]] - V[F[:, 0]])
    n /= np.linalg.norm(n, axis=1, keepdims=True)
    assert np.abs(n).max() < 0.99


def test_voxel_manifold_check_is_exhaustive_on_2x2x2():
    """voxel_solid refuses exactly the 2x2x2 voxel sets whose surface ClosedMesh refuses."""
    refused = 0
    for code in range(1, 256):
        occ = np.array([(code >> i) & 1 for i in range(8)], dtype=bool).reshape(2, 2, 2)
        try:
            zoo.voxel_solid(occ)
            ok = True
        except ValueError:
            ok = False
            refused += 1
        V, F = zoo._voxel_surface(occ)
        try:
            ClosedMesh.from_arrays(V, F)
            valid = True
        except InvalidMeshError:
            valid = False
        assert ok == valid, (code, occ.astype(int).tolist())
    assert refused > 0


def test_voxel_manifold_check_random_3x3x3():
    rng = np.random.default_rng(RNG_SEED)
    agree = refused = 0
    for _ in range(150):
        occ = rng.uniform(size=(3, 3, 3)) < rng.uniform(0.3, 0.9)
        if not occ.any():
            continue
        try:
            zoo.voxel_solid(occ)
            ok = True
        except ValueError:
            ok, refused = False, refused + 1
        try:
            ClosedMesh.from_arrays(*zoo._voxel_surface(occ))
            valid = True
        except InvalidMeshError:
            valid = False
        assert ok == valid, occ.astype(int).tolist()
        agree += 1
    assert refused > 0 and agree > refused


def test_voxel_solid_errors():
    edge = np.zeros((2, 2, 1), dtype=bool)
    edge[0, 0, 0] = edge[1, 1, 0] = True
    with pytest.raises(ValueError, match="along the edge"):
        zoo.voxel_solid(edge)
    corner = np.zeros((2, 2, 2), dtype=bool)
    corner[0, 0, 0] = corner[1, 1, 1] = True
    with pytest.raises(ValueError, match="vertex"):
        zoo.voxel_solid(corner)
    with pytest.raises(ValueError, match="empty"):
        zoo.voxel_solid(np.zeros((2, 2, 2), dtype=bool))
    with pytest.raises(ValueError, match="3D"):
        zoo.voxel_solid(np.ones((2, 2), dtype=bool))
    V, F = zoo.voxel_solid(np.ones((1, 1, 1), dtype=bool), size=0.5, origin=(1, 2, 3))
    assert len(F) == 12
    assert V.min(axis=0).tolist() == [1, 2, 3] and V.max(axis=0).tolist() == [1.5, 2.5, 3.5]


def test_random_rotation():
    V, _ = zoo.star()
    W = zoo.random_rotation(V, seed=5)
    assert np.allclose(np.linalg.norm(W, axis=1), np.linalg.norm(V, axis=1), atol=1e-14)
    assert np.array_equal(W, zoo.random_rotation(V, seed=5)) and not np.allclose(W, V)
    G = V @ np.linalg.lstsq(V, W, rcond=None)[0]
    assert np.allclose(G, W, atol=1e-12)


def test_convex_b_shapes():
    assert ConvexPolytope.from_points(zoo.box_points(0.2, 0.3, 0.4)).n_facets == 6
    assert np.allclose(np.ptp(zoo.box_points(0.2, 0.3, 0.4), axis=0), [0.2, 0.3, 0.4])
    assert ConvexPolytope.from_points(zoo.icosphere_points(2)).n_facets == 320
    assert ConvexPolytope.from_points(zoo.icosphere_points(1, radius=0.1)).n_facets == 80
    for seed in range(5):
        assert ConvexPolytope.from_points(zoo.hull20(seed)).n_facets == 20
    P = zoo.cube_rotated(0.7)
    assert ConvexPolytope.from_points(P).n_facets == 6
    assert ConvexPolytope.from_points(P).volume == pytest.approx(1.0, rel=1e-5)
    assert not np.allclose(np.abs(P), 0.5)  # really turned
    for size in (0.01, 0.3, 7.0):
        assert ConvexPolytope.from_points(zoo.cube_rotated(1.1, size=size)).n_facets == 6


def test_shared_closed_meshes(shared_data):
    meshes = zoo.shared_closed_meshes(shared_data)
    assert len(meshes) == 6
    for name, path in meshes.items():
        assert path.exists(), path
        m = ClosedMesh.load(path)
        assert m.volume > 0, name
        assert trimesh.Trimesh(m.vertices, m.faces, process=False).is_watertight, name


def test_zoo_helpers_used_by_name():
    """Every public name of zoo and oracles exists (the module APIs other tests rely on)."""
    for mod in (zoo, oracles):
        for name in mod.__all__:
            assert hasattr(mod, name), (mod.__name__, name)
    assert set(zoo.zoo_meshes()) == set(zoo.ZOO)
    assert list(itertools.islice(zoo.SHARED_CLOSED_MESHES, 1)) == ["bunny-128"]


# --------------------------------------------------------------------------------------
# exact A ⊕ B references (libigl union of convex pieces; voxel ⊕ box)


def _on_grid(v, b):
    grid = Grid.for_points(v, b)
    return grid.to_float(grid.snap(v)), grid.to_float(grid.snap(b))


@pytest.mark.parametrize(
    "arm, hand",
    [
        # voxels (0..arm, 0) and (0, 1..arm), one layer, grown by 0.25 on every side: an
        # (arm + 1.5) x 1.5 strip plus a 1.5 x arm strip, 1.5 thick
        (1, Fraction(63, 8)),  # (3.75 + 1.5) * 1.5
        pytest.param(2, Fraction(99, 8), marks=pytest.mark.slow),  # (5.25 + 3) * 1.5; ~15 s
    ],
)
def test_exact_sum_volume_l_shape_box_by_hand(arm, hand):
    v, f = zoo.l_shape(arm)
    b = zoo.box_points(0.5, 0.5, 0.5)
    assert oracles.exact_sum_volume(v, f, b) == pytest.approx(float(hand), rel=1e-14)
    occ = np.zeros((arm + 1, arm + 1, 1), dtype=bool)
    occ[:, 0] = occ[0, :] = True
    ref = oracles.voxel_box_sum(occ, b.min(0), b.max(0))
    assert ref.volume == hand and ref.n_holes == 0 and ref.euler == 2


def test_exact_sum_volume_convex_pair_matches_cvms():
    v = zoo.icosphere_points(0)  # 20 triangles: a few seconds of CGAL
    b = zoo.cube_rotated(0.4, size=0.5)
    v, b = _on_grid(v, b)
    grid = Grid.for_points(v, b)
    A = ConvexPolytope.from_points(v, grid=grid)
    B = ConvexPolytope.from_points(b, grid=grid)
    P = convex_minkowski_sum(A, B).polytope
    exact = float(Fraction(P.volume6()) / 6 * Fraction(grid.step) ** 3)
    assert oracles.exact_sum_volume(A.vertices, A.faces, B.vertices) == pytest.approx(exact, rel=1e-12)


def test_exact_sum_mesh_refuses_off_grid_coordinates():
    v, f = zoo.l_shape()
    with pytest.raises(ValueError, match="grid"):
        oracles.exact_sum_mesh(v + 1e-12, f, zoo.box_points(0.5, 0.5, 0.5))


def test_voxel_box_sum_known_answers():
    one = np.ones((1, 1, 1), dtype=bool)
    r = oracles.voxel_box_sum(one, [-0.25, -0.5, 0.0], [0.25, 0.5, 1.0])
    assert r.volume == Fraction(3, 2) * 2 * 2 and r.n_holes == 0 and r.euler == 2
    # hollow 3x3x3 with a 0.25 cube: the 1-voxel cavity shrinks to a 0.75 cube (a hole)
    occ = np.ones((3, 3, 3), dtype=bool)
    occ[1, 1, 1] = False
    r = oracles.voxel_box_sum(occ, [-0.125] * 3, [0.125] * 3)
    assert r.n_holes == 1 and r.euler == 4
    assert r.volume == Fraction(13, 4) ** 3 - Fraction(3, 4) ** 3
    # two voxels touching diagonally after the sum: one pinch, at the touching corner
    two = np.zeros((3, 3, 3), dtype=bool)
    two[0, 0, 0] = two[2, 2, 2] = True
    r = oracles.voxel_box_sum(two, [-0.5] * 3, [0.5] * 3)
    assert r.pinch_vertices.tolist() == [[1.5, 1.5, 1.5]] and r.nonmanifold_length == 0
    assert r.volume == 16


def test_brute_force_sum_distance_box_plus_box():
    # [0, 1]^3 ⊕ [-0.25, 0.25]^3 = [-0.25, 1.25]^3: distances of outside points are analytic.
    A = zoo.voxel_solid(np.ones((1, 1, 1), dtype=bool))
    B = ConvexPolytope.from_points(zoo.box_points(0.5, 0.5, 0.5))
    rng = np.random.default_rng(RNG_SEED)
    q = rng.uniform(-2, 3, (300, 3))
    gap = np.maximum(np.maximum(-0.25 - q, q - 1.25), 0.0)
    out = np.linalg.norm(gap, axis=1) > 0
    want = np.linalg.norm(gap[out], axis=1)
    got = oracles.brute_force_sum_distance(*A, B.vertices, B.faces, q[out])
    assert np.abs(got - want).max() < 1e-14
