"""The NCC-CVMS superset: a closed 2-cycle, equal to CVMS for convex A, right membership.

Exact checks use integer arithmetic on the grid: closedness on labels, and for convex A the
facets compared plane by plane through their exact (doubled) area vectors.
"""

from __future__ import annotations

import math
from collections import defaultdict

import numpy as np
import pytest
import trimesh

from cspace.geometry import exact
from cspace.mesh.convex import ConvexPolytope
from cspace.minkowski.cvms import convex_minkowski_sum
from cspace.errors import DegenerateError
from cspace.geometry.exact import Grid
from cspace.mesh.closed import ClosedMesh
from cspace.minkowski.superset import SUPERSET_KINDS, minkowski_superset


def operands(Av, Af, Bpts, name="A"):
    grid = Grid.for_points(Av, Bpts)
    A = ClosedMesh.from_arrays(Av, Af, grid=grid, name=name)
    B = ConvexPolytope.from_points(Bpts, grid=grid, name="B")
    return A, B


def area_vectors(ints, offsets, indices, mult):
    """Exact doubled area vector of each polygon times its multiplicity (Python ints)."""
    out = []
    for k in range(len(offsets) - 1):
        ring = ints[indices[offsets[k] : offsets[k + 1]]].tolist()
        ax = ay = az = 0
        for (x0, y0, z0), (x1, y1, z1) in zip(ring, ring[1:] + ring[:1]):
            ax += y0 * z1 - z0 * y1
            ay += z0 * x1 - x0 * z1
            az += x0 * y1 - y0 * x1
        m = int(mult[k])
        out.append((ax * m, ay * m, az * m))
    return out


def plane_key(area, point):
    """(primitive normal, offset) of a non-zero area vector through a grid point."""
    g = math.gcd(*(int(c) for c in area))
    n = tuple(int(c) // g for c in area)
    return n + (sum(a * int(b) for a, b in zip(n, point)),)


def assert_same_facets_as_cvms(S, P):
    """Every non-zero-area superset facet lies on a CVMS plane; per plane the areas add up."""
    per_plane = defaultdict(lambda: [0, 0, 0])
    areas = area_vectors(S.ints, S.facet_offsets, S.facet_indices, S.multiplicity)
    for k, a in enumerate(areas):
        if a == (0, 0, 0):
            continue  # a degenerate piece of the cycle (parallel features), zero area
        key = plane_key(a, S.ints[S.facet_indices[S.facet_offsets[k]]])
        acc = per_plane[key]
        for c in range(3):
            acc[c] += a[c]
    Q = P.polytope
    expected = {}
    for k, a in enumerate(area_vectors(Q.ints, Q.facet_offsets, Q.facet_indices, np.ones(Q.n_facets, int))):
        expected[plane_key(a, Q.ints[Q.facet_indices[Q.facet_offsets[k]]])] = list(a)
    assert dict(per_plane) == expected


CUBE = trimesh.creation.box((2.0, 2.0, 2.0))
ROT = trimesh.transformations.random_rotation_matrix(np.random.default_rng(3).random(3))[:3, :3]


@pytest.mark.parametrize(
    "name, mesh, bpts",
    [
        ("cube+cube", CUBE, CUBE.vertices),
        ("cube+icosphere", CUBE, trimesh.creation.icosphere(2).vertices),
        ("icosphere+cube", trimesh.creation.icosphere(2), CUBE.vertices),
        ("icosphere+rotated_cube", trimesh.creation.icosphere(1), CUBE.vertices @ ROT.T),
        ("rotated_icosphere+tetra", trimesh.Trimesh(trimesh.creation.icosphere(1).vertices @ ROT.T,
                                                   trimesh.creation.icosphere(1).faces),
         np.array([[1, 1, 1], [1, -1, -1], [-1, 1, -1], [-1, -1, 1.0]])),
        ("box+parallel_box", trimesh.creation.box((1.0, 2.0, 3.0)), CUBE.vertices * 0.25),
    ],
)
def test_convex_a_gives_exactly_the_cvms_facets(name, mesh, bpts):
    A, B = operands(mesh.vertices, mesh.faces, bpts, name)
    S = minkowski_superset(A, B)
    assert S.is_closed()
    P = convex_minkowski_sum(ConvexPolytope.from_ints(A.ints, grid=A.grid), B)
    assert_same_facets_as_cvms(S, P)
    # Convex vertices never carry negative or multiple corner facets.
    assert set(S.multiplicity[S.kind == SUPERSET_KINDS.index("corner")].tolist()) <= {1}


def test_torus_corner_multiplicities_match_the_design_notes():
    tor = trimesh.creation.torus(1.0, 0.35, major_sections=48, minor_sections=24)
    ico = trimesh.creation.icosphere(2).vertices * 0.3
    A, B = operands(tor.vertices, tor.faces, ico, "torus")
    S = minkowski_superset(A, B)
    assert len(A.faces) == 2304 and B.n_facets == 320
    assert S.is_closed()
    corner = S.multiplicity[S.kind == SUPERSET_KINDS.index("corner")]
    values, counts = np.unique(corner, return_counts=True)
    assert dict(zip(values.tolist(), counts.tolist())) == {-1: 320, 1: 320}


def test_outputs_have_documented_shapes_and_exact_positions():
    tor = trimesh.creation.torus(1.0, 0.35, major_sections=16, minor_sections=8)
    A, B = operands(tor.vertices, tor.faces, CUBE.vertices * 0.2)
    S = minkowski_superset(A, B)
    assert S.labels.dtype == np.int64 and S.labels.shape[1] == 2
    assert (S.ints == A.ints[S.labels[:, 0]] + B.ints[S.labels[:, 1]]).all()
    assert S.vertices.dtype == np.float64
    assert (S.vertices == A.vertices[S.labels[:, 0]] + B.vertices[S.labels[:, 1]]).all()
    faces, facet, weight = S.triangles()
    assert faces.dtype == np.int64 and faces.shape[1] == 3 and (weight >= 1).all()
    deg = np.diff(S.facet_offsets)
    assert (deg[S.kind == 0] == 3).all() and (deg[S.kind == 2] == 4).all()
    # Provenance: translated facets sit at their face of A moved by their vertex of B.
    t = np.nonzero(S.kind == 0)[0]
    ring = S.facet_indices[S.facet_offsets[t][:, None] + np.arange(3)]
    assert (S.labels[ring, 0] == A.faces[S.source_a[t, 1]]).all()
    assert (S.labels[ring, 1] == S.source_b[t, 1][:, None]).all()


def test_a_broken_cycle_is_reported():
    tor = trimesh.creation.torus(1.0, 0.35, major_sections=12, minor_sections=6)
    A, B = operands(tor.vertices, tor.faces, CUBE.vertices * 0.2)
    S = minkowski_superset(A, B)
    mult = S.multiplicity.copy()
    mult[np.nonzero(S.kind == 2)[0][0]] *= -1
    broken = type(S)(**{**S.__dict__, "multiplicity": mult})
    assert not broken.is_closed() and len(broken.boundary()) == 4


def test_back_to_back_faces_are_rejected():
    # A flat "pillow": two triangles glued back to back along all three edges.
    v = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0.0]])
    f = np.array([[0, 1, 2], [0, 2, 1]])
    with pytest.raises((DegenerateError, ValueError)):
        minkowski_superset((v, f), CUBE.vertices)


def test_the_perturbation_axis_avoids_every_input_direction():
    A, B = operands(CUBE.vertices, CUBE.faces, CUBE.vertices * 0.5)
    S = minkowski_superset(A, B)
    w = np.array(S.perturbation.axis)
    for d in (B.normals, np.array([[1, 0, 0], [0, 1, 0], [0, 0, 1]])):
        assert (exact.cross(exact.primitive(d), w) != 0).any(axis=1).all()


# ---- membership: winding number of the superset against FCL ---------------------------

import zoo  # noqa: E402  (tests/ is on sys.path under pytest's rootdir conftest)
from oracles import FclSolid, membership_disagreements, voxel_intersection_euler, winding_number  # noqa: E402

N_POINTS = 10_000


def sample_translations(S, rng, n):
    """Half uniform in the superset's padded box, half near its vertices (where errors live)."""
    V = S.vertices
    lo, hi = V.min(0), V.max(0)
    pad = 0.1 * (hi - lo)
    uniform = rng.uniform(lo - pad, hi + pad, size=(n // 2, 3))
    near = V[rng.integers(0, len(V), n - n // 2)] + rng.normal(scale=0.02 * (hi - lo).max(), size=(n - n // 2, 3))
    return np.vstack([uniform, near])


def assert_membership_matches_fcl(A, R, seed=0, n=N_POINTS):
    """winding(superset of A ⊕ (−R), q) > 0 exactly when R + q meets A (solid), off a 1e-9 band."""
    S = minkowski_superset(A, R.reflected((0.0, 0.0, 0.0)))
    assert S.is_closed()
    q = sample_translations(S, np.random.default_rng(seed), n)
    faces, _, weight = S.triangles()
    w = winding_number(S.vertices, faces, q, weights=weight)
    # The superset's winding number is an integer (to float rounding) and never negative.
    assert np.abs(w - np.round(w)).max() < 1e-6
    assert np.round(w).min() >= 0
    cls = FclSolid(A.vertices, A.faces).classify(R.vertices, R.faces, q, band=1e-9)
    report = membership_disagreements(np.round(w) > 0, cls.inside, cls.clearance, band=1e-9)
    assert report["n_disagree"] == 0, report
    assert 0 < cls.inside.sum() < n  # both outcomes were exercised
    return S


MEMBERSHIP_CASES = {
    # name: (mesh builder, robot points). Robots small enough against the features that
    # A ∩ (R + q) is never a ring or shell: there the winding number is positive exactly on
    # A ⊕ (−R) (see test_winding_number_is_the_euler_characteristic for why not always).
    "torus+hull20": (zoo.torus, zoo.hull20(0, scale=(0.2, 0.15, 0.1))),
    "genus3+box": (zoo.genus3, zoo.box_points(0.5, 0.25, 0.75)),
    "star+icosphere": (zoo.star, zoo.icosphere_points(1, radius=0.3)),
    "l_shape+rotated_cube": (zoo.l_shape, zoo.cube_rotated(0.4, size=0.5)),
    "comb+box": (zoo.comb, zoo.box_points(0.5, 0.5, 0.5)),
    "grate+box": (lambda: zoo.grate(2), zoo.box_points(0.5, 0.5, 0.5)),
    "stairs+hull20": (zoo.stairs, zoo.hull20(1, scale=(0.6, 0.4, 0.3))),
    # An axis-aligned box meeting the three walls of a pit pairwise contains the pit's
    # corner: no ring, so the cup (which has pits) qualifies with a box robot only.
    "cup+box": (zoo.cup, zoo.box_points(0.5, 0.4, 0.3)),
    "twisted_prism+box": (zoo.twisted_prism, zoo.box_points(0.2, 0.1, 0.3)),
    "hollow_box+small_box": (zoo.hollow_box, zoo.box_points(0.25, 0.25, 0.25)),
}


@pytest.mark.parametrize("name", list(MEMBERSHIP_CASES))
def test_superset_membership_matches_fcl(name):
    build, robot = MEMBERSHIP_CASES[name]
    v, f = build()
    A, R = operands(v, f, robot, name)
    assert_membership_matches_fcl(A, R)


def winding_and_fcl(A, R, q):
    """Superset winding numbers (rounded) and FCL's solid classification at translations q."""
    S = minkowski_superset(A, R.reflected((0.0, 0.0, 0.0)))
    assert S.is_closed()
    faces, _, weight = S.triangles()
    w = winding_number(S.vertices, faces, q, weights=weight)
    assert np.abs(w - np.round(w)).max() < 1e-6
    cls = FclSolid(A.vertices, A.faces).classify(R.vertices, R.faces, q, band=1e-9)
    return S, np.round(w).astype(int), cls


def assert_sound_against_fcl(w, cls):
    """What holds for every input: outside the sum the winding is 0; non-zero winding is inside.

    Returns the indices of points inside the sum (off the 1e-9 band) whose winding is 0:
    there A ∩ (R + q) has Euler characteristic 0 (a ring, ...), see the test below.
    """
    off_band = cls.clearance >= 1e-9
    outside = off_band & ~cls.inside
    assert (w[outside] == 0).all(), f"{int((w[outside] != 0).sum())} outside points with non-zero winding"
    assert (cls.inside | ~off_band)[w != 0].all(), "non-zero winding outside the sum"
    return np.nonzero(off_band & cls.inside & (w == 0))[0]


PIT_CASES = {
    # Voxel solids with a pit (an inner corner where three reflex edges meet), and robots
    # big enough to span it without reaching the corner.
    "notch+icosphere": zoo.icosphere_points(1, radius=0.4),
    "notch+hull20": zoo.hull20(0, scale=(0.4, 0.3, 0.2)),
    "cup+icosphere": zoo.icosphere_points(1, radius=0.4),
}


def pit_occupancy(name):
    if name.startswith("cup"):
        occ = np.ones((3, 3, 3), dtype=bool)
        occ[1, 1, 1:] = False
    else:
        occ = np.ones((2, 2, 2), dtype=bool)
        occ[1, 1, 1] = False
    return occ


@pytest.mark.parametrize("name", list(PIT_CASES))
def test_winding_number_is_the_euler_characteristic(name):
    """The convolution's winding number at q is χ(A ∩ (q − B)), not an indicator of A ⊕ B.

    Near a pit a robot can meet the three walls pairwise without reaching the corner: the
    intersection is a ring (χ = 0) although the robot collides. The superset must (and does)
    give winding 0 there; χ is computed independently from the voxels by the nerve theorem.
    """
    occ = pit_occupancy(name)
    A, R = operands(*zoo.voxel_solid(occ), PIT_CASES[name], name)
    S = minkowski_superset(A, R.reflected((0.0, 0.0, 0.0)))
    q = sample_translations(S, np.random.default_rng(0), N_POINTS)
    S, w, cls = winding_and_fcl(A, R, q)
    ring = assert_sound_against_fcl(w, cls)
    assert len(ring) > 0  # colliding placements with winding 0 exist on these inputs
    # Every one of them is a χ = 0 intersection, and on a random sample w equals χ too.
    chi = np.array([voxel_intersection_euler(occ, R.vertices, q[k]) for k in ring])
    assert (chi == 0).all()
    rng = np.random.default_rng(1)
    sample = rng.choice(np.nonzero(cls.clearance >= 1e-9)[0], 150, replace=False)
    chi = np.array([voxel_intersection_euler(occ, R.vertices, q[k]) for k in sample])
    assert (w[sample] == chi).all()
    assert len(set(chi.tolist())) >= 3  # the sample sees several values (0, 1, 2, ...)
SHARED_ROBOTS = {
    "bunny-128": zoo.hull20(2, scale=(0.01, 0.008, 0.006)),
    "bumpy-528": zoo.box_points(0.05, 0.05, 0.05),
    "yoda-658": zoo.icosphere_points(2, radius=0.02),
    "Centaur-1000": zoo.hull20(3, scale=(0.03, 0.02, 0.02)),
    "alphaobstacle": zoo.box_points(1.0, 1.5, 0.5),
    "trap": zoo.icosphere_points(2, radius=0.5),
}


@pytest.mark.parametrize("name", list(SHARED_ROBOTS))
def test_shared_meshes_superset_closed_and_membership(shared_data, name):
    path = zoo.shared_closed_meshes(shared_data)[name]
    mesh = ClosedMesh.load(path)
    # Scale the robot to the mesh so the sum has structure at every scale of the model.
    extent = float(np.ptp(mesh.vertices, axis=0).max())
    robot = SHARED_ROBOTS[name] / np.abs(SHARED_ROBOTS[name]).max() * 0.08 * extent
    A, R = operands(mesh.vertices, mesh.faces, robot, name)
    S = minkowski_superset(A, R.reflected((0.0, 0.0, 0.0)))
    q = sample_translations(S, np.random.default_rng(0), N_POINTS)
    S, w, cls = winding_and_fcl(A, R, q)
    # Inside points with winding 0 (χ = 0 intersections: the robot spans a concave feature
    # without reaching its apex) are allowed here; the benchmark report counts them.
    assert_sound_against_fcl(w, cls)
    assert 0 < cls.inside.sum() < len(q)


# --------------------------------------------------------------------------------------
# the reduced superset (what the trimming arranges)

FAR = np.array([250.0, 150.0, -300.0])


@pytest.mark.parametrize("name", list(MEMBERSHIP_CASES))
@pytest.mark.parametrize("offset", [0.0, 1.0])
def test_every_facet_of_the_reduced_superset_faces_out_of_its_convex_piece(name, offset):
    """What ``_classify_reduced`` rests on: each facet kept lies on the boundary of its piece
    ``f ⊕ B``, ``e ⊕ B`` or ``v ⊕ B`` (all the piece's vertices on its back side, some on
    its plane), with its orientation and multiplicity: exact integer dot products on the
    grid, the scene at the origin and at (250, 150, -300). The dropped facets are the
    reflex edges' and the unsupported corners' (counted: the concave inputs drop some)."""
    from cspace.minkowski.superset import reduced_superset

    build, robot = MEMBERSHIP_CASES[name]
    v, f = build()
    A, B = operands(v + offset * FAR, f, robot, name)
    S = minkowski_superset(A, B)
    R = reduced_superset(S, A, B)
    assert R.n_facets < S.n_facets  # every case here has a reflex edge
    Bi = B.ints.astype(object)
    areas = area_vectors(R.ints, R.facet_offsets, R.facet_indices, R.multiplicity)
    for k, n in enumerate(areas):
        if n == (0, 0, 0):
            continue
        dim, i = R.source_a[k].tolist()
        feature = (A.faces[i] if dim == 2 else R.a_edges[i] if dim == 1 else [i])
        piece = [a + b for a in A.ints[np.asarray(feature)].astype(object) for b in Bi]
        p0 = R.ints[R.facet_indices[R.facet_offsets[k]]].astype(object)
        heights = [sum(c * int(x) for c, x in zip(n, q - p0)) for q in piece]
        assert max(heights) == 0, (name, k, SUPERSET_KINDS[R.kind[k]], max(heights))
