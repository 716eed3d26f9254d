"""Tests of cspace.minkowski.plane_arrangement: exact planar arrangements and net polygon coverage."""

from __future__ import annotations

from fractions import Fraction as Fr

import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from cspace.minkowski.plane_arrangement import Arrangement2D
from cspace.minkowski.coverage import merge_coplanar, polygon_coverage, sampled_coverage
from cspace.geometry.homogeneous import (
    point_on_segment,
    project_homogeneous,
    to_point,
    winding_number,
)
from cspace.minkowski.triangulation import triangulate_face, _strip_spikes


def _signed_area(points) -> Fr:
    """Reference signed area of a closed polyline of Fraction points."""
    n = len(points)
    return sum((points[i][0] * points[(i + 1) % n][1] - points[i][1] * points[(i + 1) % n][0]
                for i in range(n)), Fr(0)) / 2


def ring(poly):
    return [(poly[i], poly[(i + 1) % len(poly)]) for i in range(len(poly))]


def square(x0, y0, s):
    return [(x0, y0), (x0 + s, y0), (x0 + s, y0 + s), (x0, y0 + s)]


TRI = [(0, 0), (6, 0), (0, 6)]


def P(x, y):
    return (Fr(x), Fr(y))


# ------------------------------------------------------------------ structural checker


def _orient(a, b, c):
    d = (b[0] - a[0]) * (c[1] - a[1]) - (b[1] - a[1]) * (c[0] - a[0])
    return (d > 0) - (d < 0)


def _bridges(arr):
    """Brute force: edge k is a bridge iff removing it disconnects its endpoints."""
    E = arr.edges.tolist()
    out = []
    for k in range(len(E)):
        parent = list(range(len(arr.vertices)))

        def find(a):
            while parent[a] != a:
                a = parent[a]
            return a

        for j, (u, v) in enumerate(E):
            if j != k:
                parent[find(u)] = find(v)
        out.append(find(E[k][0]) != find(E[k][1]))
    return out


def check_arrangement(arr, segments=None):
    V = arr.vertices
    E = arr.edges.tolist()
    assert len(set(V)) == len(V)
    assert all(u < v for u, v in E) and len(set(map(tuple, E))) == len(E)
    # a planar subdivision: edges meet only at common endpoints
    for i in range(len(E)):
        a, b = V[E[i][0]], V[E[i][1]]
        for w in range(len(V)):
            if w not in E[i]:
                assert not point_on_segment(V[w], a, b)
        for j in range(i + 1, len(E)):
            c, d = V[E[j][0]], V[E[j][1]]
            o1, o2 = _orient(a, b, c), _orient(a, b, d)
            o3, o4 = _orient(c, d, a), _orient(c, d, b)
            assert not (o1 * o2 < 0 and o3 * o4 < 0), "proper crossing left"
    # Euler: V - E + F = 1 + C (F with the unbounded face)
    assert len(V) - len(E) + len(arr.faces) + 1 == 1 + arr.components
    # areas
    hole_total = Fr(0)
    for c in arr.unbounded.holes:
        hole_total += _signed_area(arr.cycle_points(c))
    assert all(f.area > 0 for f in arr.faces)
    assert sum((f.area for f in arr.faces), Fr(0)) == -hole_total
    # every half-edge is in exactly one cycle of exactly one face
    seen = []
    for f in arr.faces + [arr.unbounded]:
        for c in ([f.outer] if f.outer else []) + f.holes:
            seen.extend(c)
    assert sorted(seen) == list(range(2 * len(E)))
    # two sides are the same face exactly for bridges
    same = [int(l) == int(r) for l, r in arr.edge_faces.tolist()]
    assert same == _bridges(arr)
    # samples strictly inside their own face, and located there
    for fid, f in enumerate(arr.faces + [arr.unbounded]):
        fid = fid if fid < len(arr.faces) else -1
        s = f.sample
        assert arr.locate(s) == fid
        assert s not in set(V)
        for k in range(len(E)):
            assert not point_on_segment(s, V[E[k][0]], V[E[k][1]])
        if f.outer:
            assert winding_number(arr.cycle_points(f.outer), s) == 1
        for h in f.holes:
            assert winding_number(arr.cycle_points(h), s) == 0
        for v in f.isolated:
            assert not V[v] == s
    # labels: the pieces of each input segment cover it exactly
    if segments is not None:
        for i, (p, q) in enumerate(segments):
            p, q = to_point(p), to_point(q)
            if p == q:
                continue
            ax = 0 if p[0] != q[0] else 1
            total = Fr(0)
            for k, (u, v) in enumerate(E):
                if i in arr.edge_labels[k]:
                    a, b = V[u], V[v]
                    assert point_on_segment(a, p, q) and point_on_segment(b, p, q)
                    total += abs(b[ax] - a[ax])
                else:
                    a, b = V[u], V[v]
                    assert not (point_on_segment(a, p, q) and point_on_segment(b, p, q)
                                and point_on_segment(((a[0] + b[0]) / 2, (a[1] + b[1]) / 2), p, q))
            assert total == abs(q[ax] - p[ax])


# ------------------------------------------------------------------ hand cases


def test_triangle_one_chord():
    segs = ring(TRI) + [((0, 0), (3, 3))]
    arr = Arrangement2D(segs)
    check_arrangement(arr, segs)
    assert len(arr.faces) == 2
    assert sorted(f.area for f in arr.faces) == [9, 9]
    chord = next(k for k, l in enumerate(arr.edge_labels) if 3 in l)
    assert sorted(arr.edge_faces[chord].tolist()) == [0, 1]


def test_triangle_two_crossing_chords():
    segs = ring(TRI) + [((1, 0), (1, 5)), ((0, 1), (5, 1))]
    arr = Arrangement2D(segs)
    check_arrangement(arr, segs)
    assert len(arr.faces) == 4
    assert sum(f.area for f in arr.faces) == 18
    assert P(1, 1) in arr.vertices


def test_segment_on_triangle_edge_merges_labels():
    segs = ring(TRI) + [((1, 0), (4, 0)), ((0, 0), (6, 0))]
    arr = Arrangement2D(segs, labels=["a", "b", "c", "d", "e"])
    check_arrangement(arr)
    assert len(arr.faces) == 1
    labs = {
        tuple(arr.vertices[u] + arr.vertices[v]): arr.edge_labels[k]
        for k, (u, v) in enumerate(arr.edges.tolist())
    }
    assert labs[(0, 0, 1, 0)] == {"a", "e"}
    assert labs[(1, 0, 4, 0)] == {"a", "d", "e"}
    assert labs[(4, 0, 6, 0)] == {"a", "e"}


def test_collinear_overlaps():
    segs = [((0, 0), (4, 0)), ((2, 0), (6, 0)), ((1, 0), (3, 0)), ((6, 0), (8, 0))]
    arr = Arrangement2D(segs)
    check_arrangement(arr, segs)
    assert [v[0] for v in arr.vertices] == [0, 1, 2, 3, 4, 6, 8]
    assert [sorted(l) for l in arr.edge_labels] == [[0], [0, 2], [0, 1, 2], [0, 1], [1], [3]]
    assert len(arr.faces) == 0 and arr.components == 1
    assert (arr.edge_faces == -1).all()


def test_t_junction_and_touching():
    segs = ring(TRI) + [((0, 2), (2, 2)), ((2, 2), (2, 0))]  # a square corner hanging on the edges
    arr = Arrangement2D(segs)
    check_arrangement(arr, segs)
    assert sorted(f.area for f in arr.faces) == [4, 14]
    # a dangling segment from an edge into the interior: a bridge with one face on both sides
    segs = ring(TRI) + [((0, 3), (1, 3))]
    arr = Arrangement2D(segs)
    check_arrangement(arr, segs)
    assert len(arr.faces) == 1
    k = next(k for k, l in enumerate(arr.edge_labels) if 3 in l)
    assert arr.edge_faces[k].tolist() == [0, 0]


def test_star_through_one_point():
    c = (3, 3)
    dirs = [(3, 0), (3, 3), (0, 3), (-3, 3), (-3, 0), (-3, -3), (0, -3), (3, -3)]
    segs = [((c[0] - dx, c[1] - dy), (c[0] + dx, c[1] + dy)) for dx, dy in dirs[:4]]
    segs += ring(square(0, 0, 6))
    arr = Arrangement2D(segs)
    check_arrangement(arr, segs)
    assert len(arr.faces) == 8
    assert all(f.area == Fr(9, 2) for f in arr.faces)
    centre = arr.vertices.index(P(3, 3))
    assert sum(centre in e for e in arr.edges.tolist()) == 8  # its degree


def test_square_with_square_hole():
    segs = ring(square(0, 0, 4)) + ring(square(1, 1, 2))
    arr = Arrangement2D(segs)
    check_arrangement(arr, segs)
    areas = sorted((f.area, len(f.holes)) for f in arr.faces)
    assert areas == [(4, 0), (12, 1)]
    assert arr.components == 2
    assert arr.locate((Fr(1, 2), Fr(1, 2))) == next(i for i, f in enumerate(arr.faces) if f.holes)
    assert arr.locate((2, 2)) == next(i for i, f in enumerate(arr.faces) if not f.holes)
    assert arr.locate((1, 2)) is None and arr.locate((5, 5)) == -1


def test_disconnected_components_and_points():
    half = (Fr(1, 2), Fr(1, 2))
    segs = ring(square(0, 0, 1)) + ring(square(3, 0, 1))
    segs += [((10, 10), (11, 12)), ((5, 5), (5, 5)), (half, half), ((0, 0), (0, 0))]
    arr = Arrangement2D(segs)
    check_arrangement(arr, segs)
    assert len(arr.faces) == 2
    assert arr.components == 5  # 2 squares, 1 segment, 2 isolated points ((0,0) lies on a square)
    assert len(arr.unbounded.holes) == 3 and len(arr.unbounded.isolated) == 1
    inner = arr.faces[arr.locate((Fr(1, 4), Fr(1, 4)))]
    assert [arr.vertices[v] for v in inner.isolated] == [P(Fr(1, 2), Fr(1, 2))]
    assert arr.vertex_labels[arr.vertices.index(P(0, 0))] == {len(segs) - 1}


def test_nested_components_and_holes():
    segs = ring(square(0, 0, 10)) + ring(square(1, 1, 8))
    segs += ring(square(2, 2, 2)) + ring(square(5, 5, 2))
    segs += [((3, 3), (3, 3))]
    arr = Arrangement2D(segs)
    check_arrangement(arr, segs)
    holes = sorted(len(f.holes) for f in arr.faces)
    assert holes == [0, 0, 1, 2]
    assert len(arr.faces[arr.locate((4.5, 4.5))].isolated) == 0
    assert len(arr.faces[arr.locate((3, 2.5))].isolated) == 1


def test_homogeneous_input_and_projection():
    segs = [((0, 0, 1), (6, 0, 2)), ((3, 0, 1), (0, 3, 1)),
            ((0, 3, 1), (0, 0, 1)), ((1, 0, 2), (1, 6, 2))]
    arr = Arrangement2D(segs)
    check_arrangement(arr, segs)
    assert P(Fr(1, 2), 0) in arr.vertices and P(Fr(1, 2), Fr(5, 2)) in arr.vertices
    assert project_homogeneous((1, 2, 3, 4), 0) == (2, 3, 4)
    assert project_homogeneous((1, 2, 3, 4), 1) == (3, 1, 4)
    assert project_homogeneous((1, 2, 3, 4), 2) == (1, 2, 4)


def test_empty():
    arr = Arrangement2D([])
    assert arr.faces == [] and arr.components == 0 and arr.locate((0, 0)) == -1


# ------------------------------------------------------------------ properties

coord = st.integers(0, 4)
pt = st.tuples(coord, coord)
seg = st.tuples(pt, pt)


@given(st.lists(seg, min_size=0, max_size=9))
def test_random_segments(segs):
    arr = Arrangement2D(segs)
    check_arrangement(arr, segs)


@given(st.lists(seg, min_size=2, max_size=12))
def test_sweep_finds_the_pairs_of_the_double_loop(segs):
    """The sort-and-sweep used for many segments gives the same arrangement."""
    import cspace.minkowski.plane_arrangement as planar

    slow = Arrangement2D(segs)
    old = planar._SWEEP_FROM
    planar._SWEEP_FROM = 0
    try:
        fast = Arrangement2D(segs)
    finally:
        planar._SWEEP_FROM = old
    check_arrangement(fast, segs)
    assert fast.vertices == slow.vertices
    assert fast.edges.tolist() == slow.edges.tolist() and fast.edge_labels == slow.edge_labels


hom = st.tuples(st.integers(-6, 6), st.integers(-6, 6), st.integers(1, 3))


@given(st.lists(st.tuples(hom, hom), min_size=1, max_size=7))
def test_random_homogeneous_segments(segs):
    arr = Arrangement2D(segs)
    check_arrangement(arr, segs)


@st.composite
def triangle_with_cuts(draw):
    """A triangle cut by segments between points of it (step 6 shape): convex combinations."""
    tri = draw(st.sampled_from(
        [[(0, 0), (6, 0), (0, 6)], [(0, 0), (6, 2), (2, 5)], [(1, 1), (5, 1), (3, 4)]]
    ))

    def inside():
        w = draw(st.tuples(*[st.integers(0, 3)] * 3).filter(lambda w: sum(w) > 0))
        s = sum(w)
        return tuple(sum(Fr(w[i], s) * tri[i][a] for i in range(3)) for a in (0, 1))

    n = draw(st.integers(1, 6))
    return tri, [(inside(), inside()) for _ in range(n)]


@given(triangle_with_cuts())
def test_triangle_cut(case):
    tri, cuts = case
    segs = ring(tri) + cuts
    arr = Arrangement2D(segs)
    check_arrangement(arr, segs)
    assert sum(f.area for f in arr.faces) == _signed_area([to_point(p) for p in tri])
    isolated = sum(len(f.isolated) for f in arr.faces)
    inner_holes = sum(len(f.holes) for f in arr.faces)
    assert len(arr.unbounded.holes) == 1 and arr.components == 1 + isolated + inner_holes


@st.composite
def big_triangle_with_cuts(draw):
    """Grid-scale coordinates (2**26) and cut endpoints with large denominators, as in step 6."""
    big = 1 << 26
    tri = [(0, 0), (big, draw(st.integers(0, 3)) * big // 4), (big // 3, big)]

    def inside():
        w = draw(st.tuples(*[st.integers(0, 1 << 30)] * 3).filter(lambda w: sum(w) > 0))
        s = sum(w)
        return tuple(sum(Fr(w[i], s) * tri[i][a] for i in range(3)) for a in (0, 1))

    def on_edge():
        i = draw(st.integers(0, 2))
        t = Fr(draw(st.integers(0, 1 << 30)), 1 << 30)
        a, b = tri[i], tri[(i + 1) % 3]
        return (a[0] + t * (b[0] - a[0]), a[1] + t * (b[1] - a[1]))

    pts = st.sampled_from(["in", "edge", "corner"])

    def point():
        kind = draw(pts)
        if kind == "in":
            return inside()
        if kind == "edge":
            return on_edge()
        return tri[draw(st.integers(0, 2))]

    n = draw(st.integers(1, 6))
    return tri, [(point(), point()) for _ in range(n)]


@settings(max_examples=100)
@given(big_triangle_with_cuts())
def test_big_triangle_cut(case):
    tri, cuts = case
    segs = ring(tri) + cuts
    arr = Arrangement2D(segs)
    check_arrangement(arr, segs)
    assert sum(f.area for f in arr.faces) == _signed_area([to_point(p) for p in tri])
    check_triangulation(arr)


# ------------------------------------------------------------------ coverage


def brute_coverage(polys, weights, p):
    total = 0
    for poly, w in zip(polys, weights):
        pts = [to_point(q) for q in poly]
        total += w * winding_number(pts, p)
    return total


def test_two_overlapping_squares():
    cov = polygon_coverage([square(0, 0, 2), square(1, 1, 2)])
    got = sorted(zip(cov.coverage, (f.area for f in cov.arrangement.faces)))
    assert got == [(1, 3), (1, 3), (2, 1)]
    m = merge_coplanar([square(0, 0, 2), square(1, 1, 2)])
    assert m.signs == [1, 1, 1]
    # the boundary of the union is the 8 outer half-edges, counter-clockwise
    assert len(m.boundary) == 8 and all(s == 1 for _, s in m.boundary)


def test_square_and_reverse_cancel():
    cov = polygon_coverage([square(0, 0, 2), square(0, 0, 2)[::-1]])
    assert cov.coverage == [0]
    m = merge_coplanar([square(0, 0, 2), square(0, 0, 2)[::-1]])
    assert m.faces == [] and m.boundary == []


def test_opposite_partial_overlap_symmetric_difference():
    m = merge_coplanar([square(0, 0, 2), square(1, 0, 2)[::-1]])
    arr = m.arrangement
    got = sorted((s, arr.faces[f].area) for f, s in zip(m.faces, m.signs))
    assert got == [(-1, 2), (1, 2)]


def test_nested_squares_and_weights():
    cov = polygon_coverage([square(0, 0, 4), square(1, 1, 2)], [1, 3])
    assert sorted(cov.coverage) == [1, 4]
    cov = polygon_coverage([square(0, 0, 4), square(1, 1, 2)[::-1]])
    assert sorted(cov.coverage) == [0, 1]
    m = merge_coplanar([square(0, 0, 4), square(1, 1, 2)[::-1]])
    assert len(m.faces) == 1 and m.arrangement.faces[m.faces[0]].area == 12
    assert len(m.boundary) == 8


poly = st.lists(pt, min_size=3, max_size=5)


@given(st.lists(poly, min_size=1, max_size=4), st.lists(st.integers(-2, 2), min_size=4, max_size=4))
def test_coverage_brute_force(polys, weights):
    weights = weights[: len(polys)]
    cov = polygon_coverage(polys, weights)
    arr = cov.arrangement
    check_arrangement(arr)
    for f, face in enumerate(arr.faces):
        assert cov.coverage[f] == brute_coverage(polys, weights, face.sample)
        if all(len(set(q)) == len(q) == 3 for q in polys):  # simple: support is defined
            assert cov.support[f] == sum(abs(w * winding_number([to_point(q) for q in poly], face.sample))
                                         for poly, w in zip(polys, weights))
    assert brute_coverage(polys, weights, arr.unbounded.sample) == 0
    # integral of the coverage = weighted sum of signed areas
    total = sum((c * f.area for c, f in zip(cov.coverage, arr.faces)), Fr(0))
    areas = [_signed_area([to_point(q) for q in p]) for p in polys]
    assert total == sum((w * a for a, w in zip(areas, weights)), Fr(0))
    m = merge_coplanar(polys, weights)
    assert all(s == (1 if cov.coverage[f] > 0 else -1) for f, s in zip(m.faces, m.signs))
    assert set(m.faces) == {f for f, c in enumerate(cov.coverage) if c}


def test_bad_inputs():
    with pytest.raises(ValueError):
        to_point((1, 2, 0))
    with pytest.raises(ValueError):
        to_point((1,))
    with pytest.raises(ValueError):
        Arrangement2D([((0, 0), (1, 1))], labels=[1, 2])
    with pytest.raises(ValueError):
        to_point((float("nan"), 0))
    assert to_point((0.5, 2)) == (Fr(1, 2), Fr(2))


# ------------------------------------------------------------------ triangulation (step 3)


def _disjoint_interiors(t1, t2):
    """Separating-axis test on exact points: some edge of one triangle has the other triangle
    in its closed right half-plane."""
    for a, b in ((t1, t2), (t2, t1)):
        for i in range(3):
            p, q = a[i], a[(i + 1) % 3]
            if all(_orient(p, q, r) <= 0 for r in b):
                return True
    return False


def check_triangulation(arr):
    V = arr.vertices
    for f, face in enumerate(arr.faces):
        tris = triangulate_face(arr, f)
        pts = [tuple(V[v] for v in t) for t in tris]
        assert all(_orient(*t) > 0 for t in pts)
        assert sum((_signed_area(list(t)) for t in pts), Fr(0)) == face.area
        for i in range(len(pts)):
            for j in range(i + 1, len(pts)):
                assert _disjoint_interiors(pts[i], pts[j])
        rings = [_strip_spikes(arr.cycle_vertices(c)) for c in [face.outer] + face.holes]
        corners = {v for t in tris for v in t}
        for r in rings:
            assert set(r) <= corners  # every boundary vertex is used: no T-junction
            for k in range(len(r)):
                a, b = V[r[k]], V[r[(k + 1) % len(r)]]
                for t in pts:
                    for m in range(3):
                        c, d = t[m], t[(m + 1) % 3]
                        o1, o2 = _orient(a, b, c), _orient(a, b, d)
                        o3, o4 = _orient(c, d, a), _orient(c, d, b)
                        assert not (o1 * o2 < 0 and o3 * o4 < 0)
                    if V[r[k]] not in t:
                        assert not (_orient(t[0], t[1], a) >= 0 and _orient(t[1], t[2], a) >= 0
                                    and _orient(t[2], t[0], a) >= 0)
        for t in pts:
            centroid = (sum(p[0] for p in t) / 3, sum(p[1] for p in t) / 3)
            assert arr.locate(centroid) in (f, None)
    return True


def test_triangulate_hand_cases():
    cases = [
        ring(square(0, 0, 4)) + ring(square(1, 1, 2)),
        ring(TRI) + [((1, 0), (1, 5)), ((0, 1), (5, 1)), ((0, 3), (1, 3))],
        ring(square(0, 0, 4)) + ring([(0, 0), (2, 1), (1, 2)]),  # pinched at a corner
        ring(square(0, 0, 10)) + ring(square(1, 1, 2))
        + ring(square(5, 5, 2)) + ring(square(3, 3, 2)),
        ring(square(0, 0, 10)) + ring(square(2, 2, 2)) + ring(square(4, 2, 2)) + [((1, 1), (2, 2))],
        ring([(0, 0), (4, 0), (4, 4), (2, 1), (0, 4)]) + [((2, 0), (2, 1)), ((3, 2), (3, 3))],
    ]
    for segs in cases:
        arr = Arrangement2D(segs)
        check_triangulation(arr)
    arr = Arrangement2D(ring(square(0, 0, 4)) + ring(square(1, 1, 2)))
    outer = next(i for i, f in enumerate(arr.faces) if f.holes)
    assert len(triangulate_face(arr, outer)) == 8


@settings(max_examples=120)
@given(st.lists(seg, min_size=3, max_size=8))
def test_triangulate_random(segs):
    check_triangulation(Arrangement2D(segs))


@settings(max_examples=60)
@given(st.lists(poly, min_size=1, max_size=3))
def test_triangulate_polygon_unions(polys):
    check_triangulation(polygon_coverage(polys).arrangement)


def test_triangulate_straight_runs():
    """Long runs of collinear boundary vertices (cut points on a facet's edge) are set aside
    for the ear clipping and put back by fans: still a tiling with every boundary vertex a
    corner, also when a run vertex is where a hole touches the outer boundary."""
    ticks = [((k, 0), (k, -1)) for k in range(1, 20)] + [((0, k), (-1, k)) for k in range(1, 20)]
    hole = ring([(5, 5), (10, 5), (10, 10), (5, 10)]) + [((7, 5), (7, 6)), ((8, 10), (8, 9))]
    cases = [
        ring(square(0, 0, 20)) + ticks,
        ring(square(0, 0, 20)) + ticks + hole,
        ring(square(0, 0, 20)) + ticks + ring([(4, 0), (6, 3), (2, 3)]),  # touches a run vertex
        ring([(0, 0), (20, 0), (20, 20), (10, 1), (0, 20)]) + ticks,  # deep reflex corner
    ]
    for segs in cases:
        arr = Arrangement2D(segs)
        check_triangulation(arr)
    arr = Arrangement2D(cases[0])
    big = max(range(len(arr.faces)), key=lambda f: arr.faces[f].area)
    assert len(triangulate_face(arr, big)) == 4 + 2 * 19 - 2  # n - 2 for the 42-gon


def _covered_edges(polys):
    return [(p[k], p[(k + 1) % len(p)]) for p in polys for k in range(len(p))]


@given(st.lists(st.tuples(pt, pt, pt), min_size=1, max_size=4),
       st.lists(st.integers(-2, 2), min_size=4, max_size=4))
def test_sampled_coverage_matches_polygon_coverage(tris, weights):
    """With every polygon edge among the segments the coverage is constant on each face; the
    sampled values must then equal the propagated ones face by face."""
    tris = [t for t in tris if _orient(*map(to_point, t)) != 0]
    if not tris:
        return
    weights = weights[: len(tris)]
    ref = polygon_coverage(tris, weights)
    got = sampled_coverage(tris, weights, _covered_edges(tris))
    py = sampled_coverage(tris, weights, _covered_edges(tris), compiled=False)
    assert (got.coverage, got.support, got.points) == (py.coverage, py.support, py.points)
    assert len(got.arrangement.faces) == len(ref.arrangement.faces)
    for f, face in enumerate(got.arrangement.faces):
        g = ref.arrangement.locate(face.sample)
        assert got.coverage[f] == ref.coverage[g]
        assert (got.support[f] != 0) == (ref.support[g] != 0)


def test_sampled_coverage_without_inner_edges():
    """Two triangles tiling a square, arranged by the square's boundary only: one face whose
    sample may lie on the diagonal; the push (1, eps) moves it into exactly one triangle."""
    tris = [[(0, 0), (4, 0), (4, 4)], [(0, 0), (4, 4), (0, 4)]]
    cov = sampled_coverage(tris, [1, 1], ring(square(0, 0, 4)))
    assert cov.coverage == [1] and cov.support == [1]
    cov = sampled_coverage([t[::-1] for t in tris], [2, 2], ring(square(0, 0, 4)))
    assert cov.coverage == [-2] and cov.support == [2]
    # a point exactly on the diagonal, pushed to each side by its sign
    cov = sampled_coverage(tris, [1, 3], ring(square(0, 0, 4)) + [((0, 0), (4, 4))])
    assert sorted(cov.coverage) == [1, 3]


def test_sampled_coverage_reads_faces_with_holes_and_dangling_edges_as_the_reference():
    """Faces with holes, dangling edges and isolated vertices (points read by the compiled
    loop through ``ring_inner_point`` with the holes' vertices): the same points, coverage
    and support as the Python loop, each point strictly inside its face."""
    big = [(0, 0), (20, 0), (20, 20), (0, 20)]
    tris = [[(0, 0), (20, 0), (20, 20)], [(0, 0), (20, 20), (0, 20)], [(5, 5), (9, 5), (5, 9)]]
    segs = (ring(big) + [((0, 0), (20, 20))] + ring(tris[2]) + [((12, 3), (12, 8))]
            + [((16, 13), (16, 13))] + ring([(2, 12), (4, 12), (4, 14), (2, 14)]))
    got = sampled_coverage(tris, [1, 1, 2], segs)
    py = sampled_coverage(tris, [1, 1, 2], segs, compiled=False)
    assert (got.coverage, got.support, got.points) == (py.coverage, py.support, py.points)
    arr = got.arrangement
    assert any(face.holes for face in arr.faces) and any(face.isolated for face in arr.faces)
    for f, (X, Y, W) in enumerate(got.points):
        assert arr.locate((Fr(X, W), Fr(Y, W))) == f


def test_sampled_coverage_certificate():
    """Segments that miss a place where the coverage changes are refused, not misread."""
    tris = [[(0, 0), (4, 0), (0, 4)], [(1, 1), (2, 1), (1, 2)]]
    with pytest.raises(ValueError, match="not constant"):
        sampled_coverage(tris, [1, 1], ring(tris[0]))
    cov = sampled_coverage(tris, [1, 1], ring(tris[0]) + ring(tris[1]))
    assert sorted(cov.coverage) == [1, 2]
