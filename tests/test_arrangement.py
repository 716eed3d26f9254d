"""Steps 4–5 of NCC-CVMS: candidate pairs and exact triangle–triangle intersection.

The reference is written independently of :mod:`cspace.geometry.tritri`: the first triangle is
clipped, with exact rational arithmetic (``fractions.Fraction``), by the half-spaces and
planes that define the second one (a zero-area triangle is a segment: two planes through its
line and two half-spaces), which gives the intersection ``X`` as a convex point set. Its
class follows from its affine dimension, the labels both triangles share and whether the six
corners lie in one plane; its endpoints are compared as canonical homogeneous coordinates.
"""

from __future__ import annotations

import itertools
import math
import time
from fractions import Fraction

import numpy as np
import pytest
import trimesh
from hypothesis import assume, given, settings
from hypothesis import strategies as st

from cspace.geometry.tritri import (
    COPLANAR_OVERLAP,
    COPLANAR_TOUCH,
    DISJOINT,
    EDGE_PLANE,
    NO_POINT,
    POINT,
    SEGMENT,
    SHARED_EDGE,
    SHARED_VERTEX,
    TRITRI_CLASSES,
    VERTEX,
    TriTriResult,
    intersect_pairs,
)
from cspace.geometry.boxes import BoxSweep, box_pairs, candidate_pairs
from cspace.geometry.endpoints import endpoint_coordinates
from cspace.mesh.convex import ConvexPolytope
from cspace.errors import GridRangeError
from cspace.geometry.exact import Grid
from cspace.mesh.closed import ClosedMesh
from cspace.minkowski.superset import minkowski_superset

# --------------------------------------------------------------------------------------
# exact reference (Fractions)


def _sub(a, b):
    return tuple(x - y for x, y in zip(a, b))


def _cross(a, b):
    return (a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0])


def _dot(a, b):
    return sum(x * y for x, y in zip(a, b))


def _rank(vectors) -> int:
    """Rank of a list of 3-vectors (exact Gaussian elimination on Fractions)."""
    rows = [[Fraction(x) for x in v] for v in vectors]
    rank = 0
    for col in range(3):
        piv = next((r for r in range(rank, len(rows)) if rows[r][col] != 0), None)
        if piv is None:
            continue
        rows[rank], rows[piv] = rows[piv], rows[rank]
        for r in range(len(rows)):
            if r != rank and rows[r][col] != 0:
                f = rows[r][col] / rows[rank][col]
                rows[r] = [x - f * y for x, y in zip(rows[r], rows[rank])]
        rank += 1
    return rank


def _constraints(T):
    """Affine functions ``f`` with ``T = {x : f(x) >= 0 for all f}`` (T closed, maybe flat)."""
    a, b, c = T
    n = _cross(_sub(b, a), _sub(c, a))
    out = []
    if n != (0, 0, 0):
        out += [(n, _dot(n, a)), (tuple(-x for x in n), -_dot(n, a))]
        for p, q in ((a, b), (b, c), (c, a)):
            w = _cross(n, _sub(q, p))  # points inside for a counter-clockwise triangle about n
            out.append((w, _dot(w, p)))
        return out
    p, q = min(T), max(T)  # collinear: the segment between the lexicographic extremes
    u = _sub(q, p)
    e = min(((1, 0, 0), (0, 1, 0), (0, 0, 1)), key=lambda e: abs(_dot(e, u)))
    w1 = _cross(u, e)
    w2 = _cross(u, w1)
    for w in (w1, w2):
        out += [(w, _dot(w, p)), (tuple(-x for x in w), -_dot(w, p))]
    out += [(u, _dot(u, p)), (tuple(-x for x in u), -_dot(u, q))]
    return out


def _clip(ring, f):
    """Sutherland–Hodgman: a convex ring of Fraction points clipped by ``{x : w.x >= h}``."""
    w, h = f
    val = [_dot(w, x) - h for x in ring]
    out = []
    n = len(ring)
    for i in range(n):
        x, y, fx, fy = ring[i], ring[(i + 1) % n], val[i], val[(i + 1) % n]
        if fx >= 0:
            out.append(x)
        if fx * fy < 0:
            t = Fraction(fx, 1) / (fx - fy)
            out.append(tuple(xi + t * (yi - xi) for xi, yi in zip(x, y)))
    dedup = []
    for x in out:
        if not dedup or dedup[-1] != x:
            dedup.append(x)
    while len(dedup) > 1 and dedup[0] == dedup[-1]:
        dedup.pop()
    return dedup


def _canonical(p):
    """Homogeneous canonical tuple of a Fraction point."""
    W = math.lcm(*(x.denominator for x in p))
    P = [int(x * W) for x in p]
    g = math.gcd(*P, W)
    return (P[0] // g, P[1] // g, P[2] // g, W // g)


def reference(PA, PB, LA, LB):
    """(class, set of canonical endpoints) of two triangles given as int points and labels."""
    ring = [tuple(Fraction(x) for x in p) for p in PA]
    for f in _constraints(PB):
        if not ring:
            break
        ring = _clip(ring, f)
    pts = sorted(set(ring))
    if not pts:
        return DISJOINT, set()
    dim = _rank([_sub(p, pts[0]) for p in pts[1:]])
    coplanar = _rank([_sub(p, PA[0]) for p in list(PA[1:]) + list(PB)]) <= 2
    pos = dict(zip(LA, PA))
    shared = sorted(set(LA) & set(LB))
    ends = {pts[0], pts[-1]}  # collinear sets: lexicographic extremes are the ends
    if dim == 0 and any(pts[0] == tuple(Fraction(x) for x in pos[v]) for v in shared):
        return SHARED_VERTEX, {_canonical(pts[0])}
    if dim == 1:
        for u, v in itertools.combinations(shared, 2):
            if ends == {tuple(Fraction(x) for x in pos[u]), tuple(Fraction(x) for x in pos[v])}:
                return SHARED_EDGE, {_canonical(p) for p in ends}
    if coplanar:
        return (COPLANAR_OVERLAP if dim == 2 else COPLANAR_TOUCH), set()
    assert dim <= 1
    return (POINT if dim == 0 else SEGMENT), {_canonical(p) for p in ends}


# --------------------------------------------------------------------------------------
# helpers


def soup(PA, PB):
    """Label the six corners by position (equal positions share a label): ints, faces."""
    labels: dict = {}
    for p in list(PA) + list(PB):
        labels.setdefault(tuple(int(x) for x in p), len(labels))
    ints = np.array(list(labels), dtype=np.int64).reshape(-1, 3)
    fa = [labels[tuple(int(x) for x in p)] for p in PA]
    fb = [labels[tuple(int(x) for x in p)] for p in PB]
    return ints, np.array([fa, fb], dtype=np.int64)


def valid(PA, PB) -> bool:
    return len({tuple(p) for p in PA}) == 3 and len({tuple(p) for p in PB}) == 3


def library(ints, faces, pairs=((0, 1),)):
    res = intersect_pairs(ints, faces, np.array(pairs, dtype=np.int64))
    ex, approx = endpoint_coordinates(ints, faces, res)
    return res, ex, approx


def result_sets(res: TriTriResult, ex, row=0):
    cls = int(res.cls[row])
    if cls in (POINT, SEGMENT, SHARED_EDGE, SHARED_VERTEX):
        pts = {ex[row, c] for c in range(2)}
        sym = {res.endpoint(row, c) for c in range(2)}
    else:
        assert (res.kind[row] == NO_POINT).all()
        pts, sym = set(), set()
    return cls, pts, sym


def check_pair(PA, PB):
    """Library against the reference on one pair; also checks the symbolic descriptions."""
    ints, faces = soup(PA, PB)
    PA = [tuple(int(x) for x in ints[i]) for i in faces[0]]
    PB = [tuple(int(x) for x in ints[i]) for i in faces[1]]
    want_cls, want_pts = reference(PA, PB, list(faces[0]), list(faces[1]))
    res, ex, approx = library(ints, faces)
    cls, pts, sym = result_sets(res, ex)
    assert TRITRI_CLASSES[cls] == TRITRI_CLASSES[want_cls], (PA, PB)
    assert pts == want_pts, (PA, PB)
    vertex_at = {(x, y, z, 1): i for i, (x, y, z) in enumerate(ints.tolist())}
    for c in range(2):
        d = res.endpoint(0, c)
        if d is None:
            continue
        h = ex[0, c]
        assert h[3] > 0 and math.gcd(*h) == 1
        assert np.allclose(approx[0, c], np.array(h[:3], dtype=float) / h[3], rtol=1e-15, atol=0)
        if h in vertex_at:  # a point that is a vertex must be given as that vertex
            assert d == ("v", vertex_at[h]), (PA, PB, d)
        elif d[0] == "e":
            (u, v), t = d[1], d[2]
            assert u < v and t in (0, 1)
            other = faces[1 - t].tolist()
            assert u in other and v in other  # an edge of the other triangle
    return cls, pts, sym


# --------------------------------------------------------------------------------------
# strategies


def small_point(lim=4):
    return st.tuples(*[st.integers(-lim, lim)] * 3)


@st.composite
def small_pairs(draw, lim=4):
    """Two triangles with coordinates in [-lim, lim]: degeneracies abound."""
    PA = [draw(small_point(lim)) for _ in range(3)]
    # Reuse corners of A often, to get shared vertices and edges.
    PB = [draw(st.one_of(small_point(lim), st.sampled_from(PA))) for _ in range(3)]
    assume(valid(PA, PB))
    return PA, PB


def big_int():
    return st.one_of(st.integers(-(2**26), 2**26), st.sampled_from([-(2**26), 2**26, 0, 1, -1]))


@st.composite
def big_pairs(draw):
    PA = [draw(st.tuples(big_int(), big_int(), big_int())) for _ in range(3)]
    PB = [draw(st.one_of(st.tuples(big_int(), big_int(), big_int()), st.sampled_from(PA))) for _ in range(3)]
    assume(valid(PA, PB))
    return PA, PB


# Hand-made degenerate families (small integers) and the class each is built to have.
FAMILIES = {
    "shared_edge_bent": ([(0, 0, 0), (4, 0, 0), (0, 4, 0)], [(4, 0, 0), (0, 0, 0), (0, -2, 3)], SHARED_EDGE),
    "shared_edge_flat": ([(0, 0, 0), (4, 0, 0), (0, 4, 0)], [(4, 0, 0), (0, 0, 0), (1, -3, 0)], SHARED_EDGE),
    "shared_edge_folded": ([(0, 0, 0), (4, 0, 0), (0, 4, 0)], [(0, 0, 0), (4, 0, 0), (1, 2, 0)], COPLANAR_OVERLAP),
    "shared_vertex_only": ([(0, 0, 0), (4, 0, 0), (0, 4, 0)], [(0, 0, 0), (-3, 1, 2), (-1, -3, 2)], SHARED_VERTEX),
    "shared_vertex_cross": ([(0, 0, 0), (4, 0, 0), (0, 4, 0)], [(0, 0, 0), (2, 2, 3), (2, 1, -3)], SEGMENT),
    "shared_vertex_flat": ([(0, 0, 0), (4, 0, 0), (0, 4, 0)], [(0, 0, 0), (-4, 0, 0), (0, -4, 0)], SHARED_VERTEX),
    "shared_vertex_flat_ray": ([(0, 0, 0), (4, 0, 0), (0, 4, 0)], [(0, 0, 0), (2, 0, 0), (1, -3, 0)], COPLANAR_TOUCH),
    "shared_vertex_flat_overlap": ([(0, 0, 0), (4, 0, 0), (0, 4, 0)], [(0, 0, 0), (4, 1, 0), (1, 4, 0)], COPLANAR_OVERLAP),
    "vertex_on_face": ([(0, 0, 0), (4, 0, 0), (0, 4, 0)], [(1, 1, 0), (3, 3, 3), (-1, 2, 4)], POINT),
    "vertex_on_edge": ([(0, 0, 0), (4, 0, 0), (0, 4, 0)], [(2, 0, 0), (3, -3, 3), (-1, -2, 4)], POINT),
    "vertex_on_vertex_tip": ([(0, 0, 0), (4, 0, 0), (0, 4, 0)], [(2, 2, 0), (4, 4, 3), (3, 5, -2)], POINT),
    "edge_through_vertex": ([(0, 0, 0), (4, 0, 0), (0, 4, 0)], [(0, 0, -2), (0, 0, 2), (-3, -1, 0)], POINT),
    "edge_through_vertex_seg": ([(0, 0, 0), (4, 0, 0), (0, 4, 0)], [(-1, -1, -2), (1, 1, 2), (3, 3, 0)], SEGMENT),
    "edge_on_edge_cross": ([(0, 0, 0), (4, 0, 0), (0, 4, 0)], [(2, -1, 0), (2, 1, 0), (2, 0, 3)], SEGMENT),
    "edge_touch_edge": ([(0, 0, 0), (4, 0, 0), (0, 4, 0)], [(2, -1, 0), (2, 1, 0), (2, 0, -3)], SEGMENT),
    "edge_cross_edge_point": ([(0, 0, 0), (4, 0, 0), (0, 4, 0)], [(2, -1, 1), (2, 1, -1), (2, -3, -1)], POINT),
    "edge_in_face": ([(0, 0, 0), (4, 0, 0), (0, 4, 0)], [(1, 1, 0), (2, 1, 0), (1, 2, 3)], SEGMENT),
    "edge_along_edge": ([(0, 0, 0), (4, 0, 0), (0, 4, 0)], [(1, 0, 0), (3, 0, 0), (2, 0, 3)], SEGMENT),
    "collinear_edges_flat": ([(0, 0, 0), (4, 0, 0), (0, 4, 0)], [(2, 0, 0), (6, 0, 0), (4, -3, 0)], COPLANAR_TOUCH),
    "collinear_edges_end": ([(0, 0, 0), (4, 0, 0), (0, 4, 0)], [(4, 0, 0), (6, 0, 0), (5, -3, 0)], SHARED_VERTEX),
    "t_junction": ([(0, 0, 0), (4, 0, 0), (0, 4, 0)], [(2, 0, 0), (5, 0, 0), (3, -2, 0)], COPLANAR_TOUCH),
    "t_junction_3d": ([(0, 0, 0), (4, 0, 0), (0, 4, 0)], [(2, 0, 0), (2, 1, 0), (2, 0, 3)], SEGMENT),
    "t_junction_3d_point": ([(0, 0, 0), (4, 0, 0), (0, 4, 0)], [(2, 0, 0), (2, -3, 0), (2, 0, 3)], POINT),
    "coplanar_overlap": ([(0, 0, 0), (4, 0, 0), (0, 4, 0)], [(1, 1, 0), (5, 1, 0), (1, 5, 0)], COPLANAR_OVERLAP),
    "coplanar_reversed": ([(0, 0, 0), (4, 0, 0), (0, 4, 0)], [(1, 1, 0), (1, 5, 0), (5, 1, 0)], COPLANAR_OVERLAP),
    "coplanar_point": ([(0, 0, 0), (4, 0, 0), (0, 4, 0)], [(2, 2, 0), (5, 3, 0), (3, 5, 0)], COPLANAR_TOUCH),
    "coplanar_disjoint": ([(0, 0, 0), (4, 0, 0), (0, 4, 0)], [(3, 3, 0), (5, 3, 0), (3, 5, 0)], DISJOINT),
    "coplanar_nested": ([(0, 0, 0), (8, 0, 0), (0, 8, 0)], [(1, 1, 0), (2, 1, 0), (1, 2, 0)], COPLANAR_OVERLAP),
    "parallel_planes": ([(0, 0, 0), (4, 0, 0), (0, 4, 0)], [(0, 0, 1), (4, 0, 1), (0, 4, 1)], DISJOINT),
    "touch_plane_outside": ([(0, 0, 0), (4, 0, 0), (0, 4, 0)], [(5, 5, 0), (6, 6, 3), (4, 7, 2)], DISJOINT),
    "line_miss": ([(0, 0, 0), (4, 0, 0), (0, 4, 0)], [(3, 3, -1), (3, 3, 1), (5, 5, 0)], DISJOINT),
    "pierce": ([(0, 0, 0), (4, 0, 0), (0, 4, 0)], [(1, 1, -2), (1, 1, 2), (-4, -4, 0)], SEGMENT),
    "identical": ([(0, 0, 0), (4, 0, 0), (0, 4, 0)], [(4, 0, 0), (0, 4, 0), (0, 0, 0)], COPLANAR_OVERLAP),
    # zero-area triangles (segments)
    "seg_pierces": ([(0, 0, 0), (4, 0, 0), (0, 4, 0)], [(1, 1, -2), (1, 1, 0), (1, 1, 2)], POINT),
    "seg_pierces_mid": ([(0, 0, 0), (4, 0, 0), (0, 4, 0)], [(1, 1, -2), (1, 1, 2), (1, 1, 4)], POINT),
    "seg_through_vertex": ([(0, 0, 0), (4, 0, 0), (0, 4, 0)], [(4, 0, -1), (4, 0, 1), (4, 0, 3)], POINT),
    "seg_end_on_face": ([(0, 0, 0), (4, 0, 0), (0, 4, 0)], [(1, 1, 0), (1, 1, 2), (1, 1, 4)], POINT),
    "seg_shared_end": ([(0, 0, 0), (4, 0, 0), (0, 4, 0)], [(0, 0, 0), (1, 1, 2), (2, 2, 4)], SHARED_VERTEX),
    "seg_in_plane": ([(0, 0, 0), (4, 0, 0), (0, 4, 0)], [(-1, 1, 0), (1, 1, 0), (3, 1, 0)], COPLANAR_TOUCH),
    "seg_on_edge": ([(0, 0, 0), (4, 0, 0), (0, 4, 0)], [(0, 0, 0), (2, 0, 0), (4, 0, 0)], SHARED_EDGE),
    "seg_beyond_edge": ([(0, 0, 0), (4, 0, 0), (0, 4, 0)], [(0, 0, 0), (4, 0, 0), (6, 0, 0)], SHARED_EDGE),
    "seg_seg_cross": ([(0, 0, 0), (2, 0, 0), (4, 0, 0)], [(2, -2, 0), (2, 2, 0), (2, 4, 0)], COPLANAR_TOUCH),
    "seg_seg_skew": ([(0, 0, 0), (2, 0, 0), (4, 0, 0)], [(2, -2, 1), (2, 2, 1), (2, 4, 1)], DISJOINT),
    "seg_seg_overlap": ([(0, 0, 0), (2, 0, 0), (4, 0, 0)], [(3, 0, 0), (5, 0, 0), (7, 0, 0)], COPLANAR_TOUCH),
    "seg_seg_shared_part": ([(0, 0, 0), (2, 0, 0), (4, 0, 0)], [(2, 0, 0), (4, 0, 0), (6, 0, 0)], SHARED_EDGE),
    "seg_seg_same": ([(0, 0, 0), (2, 0, 0), (4, 0, 0)], [(4, 0, 0), (0, 0, 0), (2, 0, 0)], SHARED_EDGE),
    "seg_seg_end": ([(0, 0, 0), (2, 0, 0), (4, 0, 0)], [(4, 0, 0), (5, 1, 0), (6, 2, 0)], SHARED_VERTEX),
}


@st.composite
def affine_maps(draw, big=False):
    """An integer affine map x -> M x + c with det M != 0 (keeps every incidence)."""
    lim = 200 if big else 3
    M = draw(st.lists(st.integers(-lim, lim), min_size=9, max_size=9).map(lambda v: np.array(v).reshape(3, 3)))
    assume(round(np.linalg.det(M.astype(float))) != 0)
    c = np.array(draw(st.tuples(*[st.integers(-(2**25), 2**25) if big else st.integers(-5, 5)] * 3)))
    return M, c


def apply(M, c, P):
    return [tuple(int(x) for x in M @ np.array(p) + c) for p in P]


# --------------------------------------------------------------------------------------
# step 4: candidate pairs


def brute_pairs(ints, faces):
    C = ints[faces]
    lo, hi = C.min(axis=1), C.max(axis=1)
    ov = ((lo[:, None, :] <= hi[None, :, :]) & (lo[None, :, :] <= hi[:, None, :])).all(axis=2)
    i, j = np.nonzero(np.triu(ov, 1))
    return np.stack([i, j], axis=1)


@settings(max_examples=60)
@given(st.integers(0, 2**31), st.integers(2, 120), st.sampled_from([3, 20, 2**26]), st.integers(1, 50))
def test_candidate_pairs_brute_force(seed, t, lim, chunk):
    rng = np.random.default_rng(seed)
    ints = rng.integers(-lim, lim + 1, size=(3 * t, 3))
    faces = rng.permutation(3 * t).reshape(t, 3)
    got = candidate_pairs(ints, faces, chunk=chunk)
    assert got.dtype == np.int64 and got.shape[1] == 2
    assert np.array_equal(got, brute_pairs(ints, faces))


@settings(max_examples=40)
@given(st.integers(0, 2**31), st.integers(0, 120), st.sampled_from([3, 20, 2**26]),
       st.integers(1, 7), st.integers(1, 50))
def test_box_sweep_shares_give_every_pair_once(seed, t, lim, shares, chunk):
    """The shares of one sweep (what the forked workers expand) are disjoint and together
    give exactly the pairs of the whole sweep."""
    rng = np.random.default_rng(seed)
    lo = rng.integers(-lim, lim + 1, size=(t, 3))
    hi = lo + rng.integers(0, lim + 1, size=(t, 3))
    sweep = BoxSweep(lo, hi)
    parts = [sweep.pairs(k, shares, chunk=chunk) for k in range(shares)]
    got = np.concatenate(parts)
    ref = box_pairs(lo, hi)
    assert len(got) == len(ref)  # no pair twice
    assert np.array_equal(got[np.lexsort((got[:, 1], got[:, 0]))], ref)
    assert all(np.array_equal(p, p[np.lexsort((p[:, 1], p[:, 0]))]) for p in parts)


def test_candidate_pairs_edge_cases():
    ints = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0]])
    assert candidate_pairs(ints, np.zeros((0, 3), dtype=np.int64)).shape == (0, 2)
    assert candidate_pairs(ints, [[0, 1, 2]]).shape == (0, 2)
    with pytest.raises(ValueError):
        candidate_pairs(ints, [[0, 1, 1]])
    with pytest.raises(TypeError):
        candidate_pairs(ints.astype(float), [[0, 1, 2]])


def operands(Av, Af, Bpts):
    grid = Grid.for_points(Av, Bpts)
    return ClosedMesh.from_arrays(Av, Af, grid=grid), ConvexPolytope.from_points(Bpts, grid=grid)


@pytest.fixture(scope="module")
def torus_box():
    t = trimesh.creation.torus(1.0, 0.35, 24, 12)
    A, B = operands(t.vertices, t.faces, trimesh.creation.box((0.2, 0.3, 0.25)).vertices)
    S = minkowski_superset(A, B)
    faces, _, _ = S.triangles()
    return S.ints, faces


@pytest.fixture(scope="module")
def torus_ico():
    """The ~6000-triangle superset: torus 48 x 24 and an icosphere(2) of radius 0.3."""
    t = trimesh.creation.torus(1.0, 0.35, 48, 24)
    A, B = operands(t.vertices, t.faces, trimesh.creation.icosphere(2).vertices * 0.3)
    S = minkowski_superset(A, B)
    faces, _, _ = S.triangles()
    return S.ints, faces


@pytest.fixture(scope="module")
def box_box():
    """Axis-aligned: many zero-area triangles (parallel edges) and coplanar pieces."""
    b = trimesh.creation.box((1.0, 1.0, 1.0))
    A, B = operands(b.vertices, b.faces, trimesh.creation.box((0.2, 0.3, 0.4)).vertices)
    S = minkowski_superset(A, B)
    faces, _, _ = S.triangles()
    return S.ints, faces


def test_candidate_pairs_superset(torus_box):
    ints, faces = torus_box
    got = candidate_pairs(ints, faces)
    assert np.array_equal(got, brute_pairs(ints, faces))


# --------------------------------------------------------------------------------------
# step 5 against the reference


@given(small_pairs())
def test_small_coordinates(pair):
    check_pair(*pair)


@given(small_pairs(lim=1))
def test_tiny_coordinates(pair):
    check_pair(*pair)


@given(big_pairs())
def test_large_coordinates(pair):
    check_pair(*pair)


@pytest.mark.parametrize("name", sorted(FAMILIES))
def test_family_as_built(name):
    PA, PB, want = FAMILIES[name]
    cls, _, _ = check_pair(PA, PB)
    assert TRITRI_CLASSES[cls] == TRITRI_CLASSES[want]


@settings(max_examples=300)
@given(st.sampled_from(sorted(FAMILIES)), affine_maps(), st.booleans())
def test_families_transformed(name, Mc, big):
    PA, PB, want = FAMILIES[name]
    M, c = Mc
    if big:
        M, c = M * 2**16, c * 2**20  # still |k| <= 2**28
    cls, _, _ = check_pair(apply(M, c, PA), apply(M, c, PB))
    assert TRITRI_CLASSES[cls] == TRITRI_CLASSES[want]


@settings(max_examples=60)
@given(st.sampled_from(sorted(FAMILIES)), affine_maps(big=True))
def test_families_large(name, Mc):
    PA, PB, want = FAMILIES[name]
    cls, _, _ = check_pair(apply(*Mc, PA), apply(*Mc, PB))
    assert TRITRI_CLASSES[cls] == TRITRI_CLASSES[want]


# --------------------------------------------------------------------------------------
# symmetries: swapping, rotating and reversing leave the result unchanged


def batch_variants(PA, PB):
    """One soup, rows: the pair, swapped, rotations of either, reversals of either."""
    ints, faces = soup(PA, PB)
    fa, fb = faces[0].tolist(), faces[1].tolist()
    tris = [fa, fb]
    variants = [(0, 1), (1, 0)]
    for k, f in ((0, fa), (1, fb)):
        for rot in (1, 2):
            tris.append(f[rot:] + f[:rot])
            variants.append((len(tris) - 1, 1) if k == 0 else (0, len(tris) - 1))
        tris.append(f[::-1])
        variants.append((len(tris) - 1, 1) if k == 0 else (0, len(tris) - 1))
    tris.append(fa[::-1])
    tris.append(fb[::-1])
    variants.append((len(tris) - 2, len(tris) - 1))
    variants.append((len(tris) - 1, len(tris) - 2))
    return ints, np.array(tris, dtype=np.int64), variants


def normalise_symbols(sym, faces, pair):
    """Replace the plane triangle index by its label set (rotated copies are the same plane)."""
    out = set()
    for d in sym:
        if d is not None and d[0] == "e":
            d = ("e", d[1], frozenset(faces[d[2]].tolist()))
        out.add(d)
    return out


@settings(max_examples=300)
@given(st.one_of(small_pairs(), small_pairs(lim=2), st.sampled_from([f[:2] for f in FAMILIES.values()])))
def test_symmetries(pair):
    ints, tris, variants = batch_variants(*pair)
    res, ex, _ = library(ints, tris, variants)
    first = None
    for row, pr in enumerate(variants):
        cls, pts, sym = result_sets(res, ex, row)
        got = (cls, pts, normalise_symbols(sym, tris, pr))
        if first is None:
            first = got
        assert got == first, (pair, pr)


def test_segment_direction():
    """A SEGMENT runs along N_i x N_j (i = first triangle of the pair)."""
    PA, PB, _ = FAMILIES["pierce"]
    ints, faces = soup(PA, PB)
    res, ex, approx = library(ints, faces, [(0, 1), (1, 0)])
    V = ints[faces]
    N = np.cross(V[:, 1] - V[:, 0], V[:, 2] - V[:, 0])
    for row, (i, j) in enumerate([(0, 1), (1, 0)]):
        assert res.cls[row] == SEGMENT
        d = np.cross(N[i], N[j])
        assert (approx[row, 1] - approx[row, 0]) @ d > 0


def test_input_checks():
    ints = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0], [0, 0, 1]])
    faces = np.array([[0, 1, 2], [0, 1, 3]])
    with pytest.raises(ValueError, match="itself"):
        intersect_pairs(ints, faces, [[0, 0]])
    with pytest.raises(ValueError, match="outside"):
        intersect_pairs(ints, faces, [[0, 2]])
    with pytest.raises(ValueError, match=r"\(k, 2\)"):
        intersect_pairs(ints, faces, [[0, 1, 1]])
    with pytest.raises(ValueError, match=r"\(n, 3\)"):
        intersect_pairs(ints[:, :2], faces, [[0, 1]])
    with pytest.raises(ValueError, match=r"\(t, 3\)"):
        intersect_pairs(ints, faces[:, :2], [[0, 1]])
    with pytest.raises(ValueError, match="labels outside"):
        intersect_pairs(ints, faces + 1, [[0, 1]])
    with pytest.raises(GridRangeError):
        intersect_pairs(ints * 2**29, faces, [[0, 1]])
    # The largest accepted coordinates: normals stay exact (below 2**61).
    big = np.array([[2**29 - 1, -(2**29 - 1), 0], [-(2**29 - 1), 2**29 - 1, 0], [2**29 - 1, 2**29 - 1, 5],
                    [-(2**29 - 1), -(2**29 - 1), -5]])
    res = intersect_pairs(big, [[0, 1, 2], [0, 1, 3]], [[0, 1]])
    assert res.cls[0] == SHARED_EDGE
    res = intersect_pairs(ints, faces, np.zeros((0, 2), dtype=np.int64))
    assert len(res) == 0 and res.counts()["disjoint"] == 0


# --------------------------------------------------------------------------------------
# real supersets


def check_superset(ints, faces, sample=400, seed=0):
    pairs = candidate_pairs(ints, faces)
    res = intersect_pairs(ints, faces, pairs)
    ex, _ = endpoint_coordinates(ints, faces, res)
    assert (res.cls >= 0).all() and len(res) == len(pairs)
    FA, FB = faces[pairs[:, 0]], faces[pairs[:, 1]]
    nsh = (FA[:, :, None] == FB[:, None, :]).any(axis=2).sum(axis=1)
    V = ints[faces]
    N = np.cross(V[:, 1] - V[:, 0], V[:, 2] - V[:, 0]).astype(object)
    # Label-edge pairs of two proper triangles that are not coplanar: all SHARED_EDGE.
    for r in np.nonzero(nsh == 2)[0]:
        i, j = pairs[r]
        proper = N[i].any() and N[j].any()
        coplanar = tuple(np.cross(N[i], N[j])) == (0, 0, 0)  # parallel normals + a shared edge
        if proper and not coplanar:
            assert res.cls[r] == SHARED_EDGE
    # A sample of pairs against the reference, every non-trivial class included.
    rng = np.random.default_rng(seed)
    interesting = np.nonzero(~np.isin(res.cls, [DISJOINT, SHARED_EDGE, SHARED_VERTEX]))[0]
    rows = np.concatenate([rng.choice(len(pairs), size=min(sample, len(pairs)), replace=False), interesting[:sample]])
    for r in rows:
        i, j = pairs[r]
        PA = [tuple(int(x) for x in ints[v]) for v in faces[i]]
        PB = [tuple(int(x) for x in ints[v]) for v in faces[j]]
        want_cls, want_pts = reference(PA, PB, faces[i].tolist(), faces[j].tolist())
        cls, pts, _ = result_sets(res, ex, r)
        assert (cls, pts) == (want_cls, want_pts), (i, j)
    return res


def test_superset_torus_box(torus_box):
    ints, faces = torus_box
    res = check_superset(ints, faces)
    c = res.counts()
    assert c["segment"] > 0 and c["shared_edge"] > 0 and c["shared_vertex"] > 0


def test_superset_torus_icosphere(torus_ico):
    ints, faces = torus_ico
    assert 6000 <= len(faces) <= 7000
    res = check_superset(ints, faces, sample=300)
    c = res.counts()
    assert c["segment"] > 0 and c["point"] > 0


def test_superset_box_box(box_box):
    ints, faces = box_box
    V = ints[faces]
    assert (~np.cross(V[:, 1] - V[:, 0], V[:, 2] - V[:, 0]).any(axis=1)).sum() > 0  # flat triangles present
    check_superset(ints, faces, sample=10**6)


def test_superset_speed(torus_box):
    """Loose guard: all candidates of a ~1000-triangle superset in well under a second."""
    ints, faces = torus_box
    t0 = time.perf_counter()
    intersect_pairs(ints, faces, candidate_pairs(ints, faces))
    assert time.perf_counter() - t0 < 2.0
