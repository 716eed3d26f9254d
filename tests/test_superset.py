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

from cspace import exact
from cspace.convex import ConvexPolytope, convex_minkowski_sum
from cspace.errors import DegenerateError
from cspace.exact import Grid
from cspace.mesh import ClosedMesh
from cspace.superset import SUPERSET_KINDS, minkowski_superset


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
