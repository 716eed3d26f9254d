"""The compiled triangle-pair stage (:mod:`cspace.geometry._kernels.arrangement`) against its numpy
references in :mod:`cspace.geometry.tritri`.

The compiled box sweep, pair classification and endpoint coordinates must give *identical*
outputs (the same arrays, the same tuples, the same floats bit for bit) to
``BoxSweep._pairs_reference``, ``_intersect_pairs_reference`` and
``_endpoint_coordinates_reference``, on random soups full of degeneracies (tiny grids:
shared labels, coplanar pairs, zero-area triangles, touching at vertices and edges,
collinear overlaps), on the same soups and hand-made families mapped by large unimodular
integer maps (every incidence kept, every predicate a cancellation of huge terms), on
supersets of zoo meshes and on the pairs a Minkowski sum intersects. The kernel decides in
64/128-bit integers, without a float filter; the inputs built so that double precision gets
a sign wrong would catch one that trusted floats where it should not.
"""

from __future__ import annotations

import itertools

import numpy as np
import pytest
from test_arrangement import FAMILIES, soup
from zoo import box_points, comb, icosphere_points, star, torus

from cspace.geometry import boxes, endpoints, tritri
from cspace.minkowski import intersections
from cspace.minkowski.sum import minkowski_sum
from cspace.geometry._kernels import arrangement as compiled
from cspace.mesh.convex import ConvexPolytope
from cspace.geometry.exact import Grid
from cspace.mesh.closed import ClosedMesh
from cspace.minkowski.superset import minkowski_superset


def _same(ints, faces, pairs) -> tritri.TriTriResult:
    """Assert the compiled stage equals the reference on these pairs; the compiled result."""
    got = tritri.intersect_pairs(ints, faces, pairs)
    want = tritri._intersect_pairs_reference(ints, faces, pairs)
    for name in ("pairs", "cls", "kind", "u", "v", "plane"):
        a, b = getattr(got, name), getattr(want, name)
        assert a.dtype == b.dtype and a.shape == b.shape, name
        diff = a != b
        bad = np.flatnonzero(diff.any(axis=1) if diff.ndim > 1 else diff)
        assert not bad.size, (name, pairs[bad[:3]].tolist(), ints[faces[pairs[bad[0]]]].tolist())
    ex, approx = endpoints.endpoint_coordinates(ints, faces, got)
    ex_ref, approx_ref = endpoints._endpoint_coordinates_reference(ints, faces, want)
    assert ex.tolist() == ex_ref.tolist()
    assert approx.tobytes() == approx_ref.tobytes()  # bit for bit, NaNs included
    return got


def _random_soup(rng, t: int, lim: int, planes: bool = False):
    """``t`` triangles on distinct grid points in ``[-lim, lim]^3`` (on two planes ``z = 0, 1``
    if ``planes``): every corner is shared by several triangles."""
    pts = rng.integers(-lim, lim + 1, size=(4 * lim + 8, 3))
    if planes:
        pts[:, 2] = rng.integers(0, 2, len(pts))
    ints = np.unique(pts, axis=0)
    faces = np.array([rng.choice(len(ints), 3, replace=False) for _ in range(t)])
    return ints, faces


def _unimodular(rng, big: int) -> np.ndarray:
    """An integer matrix of determinant 1 with entries up to about ``big**2``: it keeps every
    collinearity and coplanarity of integer points, and makes their predicates cancel huge terms."""
    M = np.eye(3, dtype=np.int64)
    for i, j in [(0, 1), (1, 2), (2, 0), (1, 0)]:
        E = np.eye(3, dtype=np.int64)
        E[i, j] = rng.integers(-big, big + 1)
        M = M @ E
    return M


def _mapped(rng, ints, big: int):
    """``ints`` through a large unimodular map (entries smaller while the image would exceed
    2**27) and shifted near the grid's limit (2**29)."""
    out = ints @ _unimodular(rng, big).T
    while np.abs(out).max() >= 2**27:
        big //= 2
        out = ints @ _unimodular(rng, big).T
    shift = (2**28 - int(np.abs(out).max()) - 1) * rng.choice([-1, 1], 3)
    assert np.abs(out + shift).max() < 2**29
    return out + shift


def test_codes_are_the_modules():
    for name, code in compiled.CODES.items():
        assert getattr(tritri, name) == code, name


@pytest.mark.parametrize("seed", range(6))
def test_random_soups_are_identical(seed):
    rng = np.random.default_rng(seed)
    counts = np.zeros(len(tritri.TRITRI_CLASSES), dtype=np.int64)
    for k in range(12):
        ints, faces = _random_soup(rng, 40, lim=1 + k % 3, planes=k % 2 == 1)
        pairs = boxes.candidate_pairs(ints, faces)
        counts += np.bincount(_same(ints, faces, pairs).cls, minlength=len(counts))
        if k % 3 == 0:  # also every ordered pair, including those whose boxes miss
            i, j = np.nonzero(~np.eye(len(faces), dtype=bool))
            _same(ints, faces, np.stack([i, j], axis=1))
    assert (counts > 0).all(), dict(zip(tritri.TRITRI_CLASSES, counts))  # every class is tested


@pytest.mark.parametrize("seed", range(4))
def test_large_mapped_soups_are_identical(seed):
    """The tiny-grid degeneracies at coordinates near 2**28, where double precision fails."""
    rng = np.random.default_rng(100 + seed)
    for k in range(6):
        ints, faces = _random_soup(rng, 30, lim=1 + k % 2, planes=k % 2 == 0)
        big = _mapped(rng, ints, 2**9)
        pairs = boxes.candidate_pairs(big, faces)
        # The map keeps every incidence: the classes are the small soup's.
        small = tritri.intersect_pairs(ints, faces, pairs)
        assert np.array_equal(_same(big, faces, pairs).cls, small.cls)


def test_families_are_identical():
    """The hand-made degenerate pairs of test_arrangement, both orders, as built and mapped."""
    rng = np.random.default_rng(7)
    for name, (PA, PB, cls) in FAMILIES.items():
        ints, faces = soup(PA, PB)
        pairs = np.array([[0, 1], [1, 0]])
        assert (_same(ints, faces, pairs).cls == cls).all(), name
        for _ in range(3):
            assert (_same(_mapped(rng, ints, 2**10), faces, pairs).cls == cls).all(), name


def test_exact_where_doubles_fail():
    """Triangles a few units (of N . x, ~2**56 per grid unit) off a plane whose normal has
    components up to ~2**56: double precision rounds every side to 0, so a kernel deciding on
    floats (or a float filter with a wrong bound) would call them coplanar or touching."""
    M = 2**28 - 1
    a, b, c = (0, 0, 0), (M, 1, 0), (0, M, 1)  # normal (1, -M, M**2)
    N = [float(x) for x in np.cross(np.array(b) - a, np.array(c) - a)]
    seen, wrong = set(), 0
    for d in itertools.product((-2, -1, 0, 1, 2), repeat=3):
        # N . x = d_i exactly: b + c, c, b shifted by d_i along x (N_x = 1).
        B = [(d[0] + M, M + 1, 1), (d[1], M, 1), (d[2] + M, 1, 0)]
        for x, di in zip(B, d):
            naive = N[0] * x[0] + N[1] * x[1] + N[2] * x[2]  # in doubles
            wrong += np.sign(naive) != np.sign(di)
        ints, faces = soup([a, b, c], B)
        res = _same(ints, faces, np.array([[0, 1], [1, 0]]))
        seen.add(tritri.TRITRI_CLASSES[res.cls[0]])
        if all(x > 0 for x in d) or all(x < 0 for x in d):
            assert (res.cls == tritri.DISJOINT).all()
        if not any(d):
            assert res.cls[0] in (tritri.COPLANAR_TOUCH, tritri.SHARED_EDGE, tritri.COPLANAR_OVERLAP)
    assert {"disjoint", "point", "shared_vertex", "shared_edge"} <= seen, seen
    assert wrong >= 3 * 5**3 * 4 // 5 // 2, wrong  # doubles get most nonzero sides wrong


def test_exact_quotients_round_as_python():
    """The endpoints' floats: the kernel's int128 division is Python's correctly rounded
    ``int / int``, ties (to even) included."""
    rng = np.random.default_rng(3)
    cases = []
    for _ in range(20000):
        X = int(rng.integers(0, 2**62)) << int(rng.integers(0, 60)) | int(rng.integers(0, 2**60))
        X = X % 2**123 * int(rng.choice([-1, 1]))
        W = (int(rng.integers(1, 2**62)) << int(rng.integers(0, 32))) % 2**94 or 1
        cases.append((X, W))
    for _ in range(5000):  # exact halves: 55-bit odd quotients over powers of two
        q, j = int(rng.integers(2**54, 2**55)) | 1, int(rng.integers(1, 30))
        odd = int(rng.integers(0, 2**20)) | 1
        cases.append((q * odd * int(rng.choice([-1, 1])), odd << j))
    cases += [(0, 1), (1, 3), (-1, 3), (2**123 - 1, 1), (-(2**123) + 1, 2**94 - 1), (2**53 + 1, 1)]
    for X, W in cases:
        assert compiled.quotient(X, W) == X / W, (X, W)


def _superset(Av, Af, Bpts):
    grid = Grid.for_points(Av, Bpts)
    S = minkowski_superset(ClosedMesh.from_arrays(Av, Af, grid=grid),
                           ConvexPolytope.from_points(Bpts, grid=grid))
    return S.ints, S.triangles()[0]


ZOO = {
    "star + box": lambda: _superset(*star(), box_points(0.2, 0.3, 0.25)),
    "comb + box (axis-aligned: coplanar and zero-area pieces)": lambda: _superset(*comb(3, 2), box_points(0.2, 0.3, 0.4)),
    "torus + icosphere": lambda: _superset(*torus(sections=12, ring=8), icosphere_points(1, 0.3)),
}


@pytest.mark.parametrize("name", list(ZOO))
def test_zoo_supersets_are_identical(name):
    ints, faces = ZOO[name]()
    C = ints[faces]
    sweep = boxes.BoxSweep(C.min(axis=1), C.max(axis=1))
    pairs = sweep.pairs()
    assert np.array_equal(pairs, sweep._pairs_reference())
    for shares in (2, 5):
        for k in range(shares):
            assert np.array_equal(sweep.pairs(k, shares), sweep._pairs_reference(k, shares, chunk=1000))
    counts = _same(ints, faces, pairs).counts()
    assert counts["segment"] and counts["shared_edge"] and counts["disjoint"], counts


def test_minkowski_sum_pairs_are_identical(monkeypatch):
    """The pairs a Minkowski sum intersects (its _cuts), compiled and reference."""
    seen = []

    def spy(ints, faces, pairs):
        seen.append(_same(ints, faces, pairs))
        return real(ints, faces, pairs)

    real = intersections._cut_pieces
    monkeypatch.setattr(intersections, "_cut_pieces", spy)
    v, f = star()
    b = icosphere_points(1, 0.3)
    grid = Grid.for_points(v, b)
    minkowski_sum(ClosedMesh.from_arrays(v, f, grid=grid),
                  ConvexPolytope.from_points(b, grid=grid), workers=1)
    assert seen and sum(int((r.cls == tritri.SEGMENT).sum()) for r in seen) > 100


@pytest.mark.parametrize("seed", range(3))
def test_box_sweep_is_identical(seed):
    """Random integer boxes (many equal bounds), every share split."""
    rng = np.random.default_rng(seed)
    for t, lim in [(0, 3), (1, 3), (2, 3), (300, 3), (300, 40), (2000, 2**28)]:
        lo = rng.integers(-lim, lim + 1, size=(t, 3))
        hi = lo + rng.integers(0, max(2, lim // 4), size=(t, 3))
        sweep = boxes.BoxSweep(lo, hi)
        for shares in (1, 3):
            for k in range(shares):
                got, want = sweep.pairs(k, shares), sweep._pairs_reference(k, shares, chunk=97)
                assert got.dtype == want.dtype == np.int64 and np.array_equal(got, want)
        assert np.array_equal(boxes.box_pairs(lo, hi), sweep._pairs_reference())


def _overlapping_pairs(lo, hi):
    """Every pair of boxes that meet, by brute force over all pairs (nothing of the sweep)."""
    meet = ((lo[:, None] <= hi[None]) & (lo[None] <= hi[:, None])).all(axis=2)
    i, j = np.nonzero(np.triu(meet, 1))
    return np.stack([i, j], axis=1).astype(np.int64)


@pytest.mark.parametrize("centre", [0, 3 * 2**31, -(2**33) + 5, 2**45],
                         ids=["origin", "3*2^31", "-2^33", "2^45"])
@pytest.mark.parametrize("span", [2**20, 2**33], ids=["narrow", "wide"])
def test_box_pairs_far_from_the_origin(centre, span):
    """Boxes in grid units of absolute coordinates lie far beyond int32 (a scene at
    (250, 150, -300) on a fine grid): every meeting pair is found wherever they lie, also
    where they straddle a multiple of 2**31 (an int32 cast wrapped there and lost pairs) and
    when they span more than 2**31 (the numpy sweep)."""
    rng = np.random.default_rng(span % 97 + centre % 89)
    lo = centre + rng.integers(-span // 2, span // 2, size=(400, 3))
    hi = lo + rng.integers(0, span // 8, size=(400, 3))
    want = _overlapping_pairs(lo, hi)
    assert len(want) > 100
    sweep = boxes.BoxSweep(lo, hi)
    assert sweep.wide == (span > 2**31)
    assert np.array_equal(boxes.box_pairs(lo, hi), want)
    assert np.array_equal(sweep._pairs_reference(chunk=97), want)


def test_empty_inputs():
    ints = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0]])
    faces = np.array([[0, 1, 2]])
    _same(ints, faces, np.zeros((0, 2), dtype=np.int64))
    res = tritri.intersect_pairs(ints, faces, np.zeros((0, 2), dtype=np.int64))
    ex, approx = endpoints.endpoint_coordinates(ints, faces, res)
    assert ex.shape == (0, 2) and approx.shape == (0, 2, 3)
