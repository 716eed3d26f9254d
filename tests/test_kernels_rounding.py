"""The rounding check's compiled kernels (:mod:`cspace.geometry._kernels.trim`) against their
references in :mod:`cspace.minkowski.ncc_cvms`: identical outputs (bit for bit), on random, near-degenerate
and zoo inputs, with every fast path and every fallback exercised.

- ``to_float`` / ``_to_float``: float64 coordinates of exact homogeneous grid points;
- ``moved_points`` / ``_moved``: which of them rounding moved;
- ``triangle_boxes`` / ``_triangle_boxes``: integer boxes of triangles, rounded outwards;
- ``_improper_pairs``: the exact test on the vertices of the pairs the filter leaves only,
  against every pair tested on all vertices; forked and serial alike;
- ``_nonmanifold`` (one sort, fans counted per vertex): against a brute-force union-find.
"""

from __future__ import annotations

import numpy as np
import pytest
from zoo import comb, icosphere_points, star, torus

from cspace.geometry import boxes
from cspace.mesh import self_intersection
from cspace.minkowski import output, rounding
from cspace.geometry._kernels import trim as compiled
from cspace.geometry.exact import Grid
from cspace.workers import can_fork

KEPT, MOVED, LEFT = 0, 1, 2  # the states of compiled.moved_points


def _points(seed: int, n: int = 400) -> list:
    """Homogeneous grid points ``(x, y, z, w)`` of every kind the kernels tell apart:
    ``w = 1`` small integers; small rationals (``w`` up to 2**20); exact dyadic quotients
    (``num / w`` a short binary fraction, with small and with huge ``w``); integers beyond
    2**53, 2**62 and 2**64; near those bounds, and just beyond 2**53 (one IEEE division
    no longer rounds correctly); negative and zero coordinates; ``w <= 0``."""
    rng = np.random.default_rng(seed)
    out = []
    big = [2**53 - 1, 2**53, 2**53 + 1, 2**62 - 1, 2**62, 2**63 - 1, 2**63, 2**64 + 3, 2**90 + 7]
    for _ in range(n):
        kind = int(rng.integers(0, 10))
        if kind == 0:  # plain grid points
            P = [int(v) for v in rng.integers(-2**29, 2**29, 3)] + [1]
        elif kind == 1:  # small rationals: mostly moved
            w = int(rng.integers(1, 2**20))
            P = [int(v) for v in rng.integers(-2**40, 2**40, 3)] + [w]
        elif kind == 2:  # exact dyadic quotients, w a power of two times an odd factor
            odd, s = int(rng.integers(1, 2**10)) | 1, int(rng.integers(0, 30))
            w = odd << s
            P = [int(v) * odd * (1 << int(rng.integers(0, s + 1))) for v in rng.integers(-2**20, 2**20, 3)] + [w]
        elif kind == 3:  # huge w, still exact quotients (kept, beyond int64)
            w = (int(rng.integers(1, 2**20)) | 1) << 70
            P = [int(v) * w for v in rng.integers(-2**30, 2**30, 3)] + [w]
        elif kind == 4:  # huge rationals (moved, beyond int64)
            w = int(rng.integers(2**40, 2**60)) * 2**40 + 1
            P = [int(v) * 2**50 + int(rng.integers(0, 2**40)) for v in rng.integers(-2**30, 2**30, 3)] + [w]
        elif kind == 5:  # integers at the bounds of the fast paths
            P = [int(rng.choice(big)) * int(rng.choice([-1, 1])) for _ in range(3)] + [1]
        elif kind == 6:  # quotients near the bounds, with w near the bounds
            w = int(rng.choice(big[:6]))
            P = [int(rng.choice(big)) * int(rng.choice([-1, 1])) for _ in range(3)] + [w]
        elif kind == 7:  # zeros and tiny values
            w = int(rng.integers(1, 8))
            P = [int(v) for v in rng.integers(-2, 3, 3)] + [w]
        elif kind == 8:  # just beyond the exact doubles: w or num in (2**53, 2**56)
            w = int(rng.integers(2**53 + 1, 2**56)) | 1 if rng.random() < 0.5 else int(rng.integers(1, 2**10))
            P = [int(rng.integers(2**50, 2**56)) * int(rng.choice([-1, 1])) for _ in range(3)] + [w]
        else:  # w <= 0: left to the reference
            w = -int(rng.integers(1, 2**10))
            P = [int(v) for v in rng.integers(-2**30, 2**30, 3)] + [w]
        out.append(tuple(P))
    return out


GRIDS = [Grid(-25, (0, 0, 0)), Grid(-23, (73400320, -23068672, 6291456)), Grid(3, (5, 0, -7)),
         Grid(-1070, (0, 1, 0))]  # the last rounds into (and below) the subnormals


def _same_bits(a: np.ndarray, b: np.ndarray) -> bool:
    return a.shape == b.shape and np.array_equal(a.view(np.int64), b.view(np.int64))


@pytest.mark.parametrize("seed", range(3))
@pytest.mark.parametrize("grid", GRIDS, ids=lambda g: f"e{g.exponent}")
def test_to_float_is_identical(seed, grid):
    pts = _points(seed)
    with np.errstate(all="ignore"):
        want = output._to_float(pts, grid)
    V, left = compiled.to_float(pts, tuple(grid.origin), grid.exponent)
    assert not left.any()
    assert _same_bits(V, want) and _same_bits(output._to_float_compiled(pts, grid), want)
    # points of other types (numpy ints, lists) are left to the reference, which agrees
    small = [p for p in pts if max(abs(c) for c in p) < 2**30][:20]
    odd = [tuple(np.int64(c) for c in p) if k % 2 else list(p) for k, p in enumerate(small)]
    V, left = compiled.to_float(odd, tuple(grid.origin), grid.exponent)
    assert left.all() and _same_bits(output._to_float_compiled(odd, grid), output._to_float(odd, grid))
    assert _same_bits(output._to_float_compiled([], grid), output._to_float([], grid))


@pytest.mark.parametrize("seed", range(3))
@pytest.mark.parametrize("grid", GRIDS, ids=lambda g: f"e{g.exponent}")
def test_moved_is_identical(seed, grid):
    """On the correctly rounded rows, on rows one ulp off them (so kept points too can
    move) and on rows far off (scaled by powers of two, other points' rows, mirrored): the compiled answer, with the reference deciding what it leaves, is the
    reference's; and each of the kernel's paths decides some points."""
    pts = _points(seed)
    V = output._to_float(pts, grid)
    rng = np.random.default_rng(seed)
    off = V.copy()
    rows = rng.random(len(V)) < 0.3
    off[rows] = np.nextafter(off[rows], rng.choice([-np.inf, np.inf], (int(rows.sum()), 3)))
    far = V * np.ldexp(1.0, rng.integers(-200, 200, V.shape))  # far off: every shift
    far[::3] = V[rng.permutation(len(V))][::3]  # another point's row
    far[1::3] = -V[1::3]  # the mirror image
    states = []
    for W in (V, off, far):
        finite = np.isfinite(W).all(axis=1)  # the reference cannot take an infinity
        P, W = [p for p, f in zip(pts, finite) if f], W[finite]
        want = rounding._moved(P, W, grid)
        assert np.array_equal(rounding._moved_compiled(P, W, grid), want)
        state = compiled.moved_points(P, tuple(grid.origin), grid.exponent, W)
        decided = state != LEFT
        assert np.array_equal(state[decided] == MOVED, want[decided])
        states.append(state)
    state = np.concatenate(states)
    assert (state == KEPT).sum() > 20 and (state == MOVED).sum() > 20 and (state == LEFT).any()
    assert rounding._moved_compiled([], np.zeros((0, 3)), grid).shape == (0,)


def test_moved_paths_each_decide():
    """Each path of the kernel alone, on points built for it: int64 kept and moved (both
    ways decided), beyond int64 moved (modulo 2**64) and kept (left to the reference)."""
    g = Grid(-10, (0, 0, 0))
    pts = [(3, -5, 7, 1), (1, 2, 3, 3), (3 * 2**62, 0, 0, 3 * 2**62), (2**70 + 1, 0, 0, 2**70)]
    V = output._to_float(pts, g)
    state = compiled.moved_points(pts, (0, 0, 0), -10, V)
    assert state.tolist() == [KEPT, MOVED, LEFT, MOVED]
    assert rounding._moved(pts, V, g).tolist() == [False, True, False, True]
    # a row off by one ulp, or by a sign, is moved on every path
    W = -V
    W[0, 0] = np.nextafter(V[0, 0], 0.0)
    assert compiled.moved_points(pts, (0, 0, 0), -10, W).tolist() == [MOVED] * 4


@pytest.mark.parametrize("seed", range(3))
def test_triangle_boxes_are_identical(seed):
    rng = np.random.default_rng(seed)
    V = rng.normal(size=(60, 3)) * rng.choice([1e-3, 1.0, 1e3], (60, 1))
    V[::5] = np.round(V[::5] * 2**10) / 2**10  # on the grid: floor and ceil coincide
    V[1::7] = -0.0
    T = rng.integers(0, len(V), (200, 3)).astype(np.int64)
    for e in (-25, -10, 0, 4):
        lo, hi, ok = compiled.triangle_boxes(V, T, e)
        rlo, rhi = self_intersection._triangle_boxes(V, T, e)
        assert ok and np.array_equal(lo, rlo) and np.array_equal(hi, rhi)
    # a coordinate the cast cannot take, or not finite: the reference decides
    for bad in (1e30, np.nan, np.inf):
        W = V.copy()
        W[T[7, 1], 2] = bad
        assert not compiled.triangle_boxes(W, T, -25)[2]
        with np.errstate(all="ignore"):
            a, b = self_intersection._triangle_boxes_compiled(W, T, -25), self_intersection._triangle_boxes(W, T, -25)
        assert np.array_equal(a[0], b[0]) and np.array_equal(a[1], b[1])
    assert compiled.triangle_boxes(V, np.zeros((0, 3), np.int64), -25)[0].shape == (0, 3)


def _soup(seed: int):
    """Random triangles on a few points, some a few ulps off the grid planes (shared
    vertices and edges, coplanar, crossing and folded pairs; see test_trim_cases)."""
    rng = np.random.default_rng(seed)
    pool = rng.integers(0, 4, size=(14, 3)).astype(np.float64)
    pool[7:] += rng.choice([0.0, 2.0**-50, -(2.0**-51)], size=(7, 3))
    pool = np.unique(pool, axis=0)
    T = np.array([t for t in (rng.choice(len(pool), 3, replace=False) for _ in range(150))
                  if np.linalg.norm(np.cross(pool[t[1]] - pool[t[0]], pool[t[2]] - pool[t[0]])) > 0],
                 dtype=np.int64)
    T = T[np.unique(np.sort(T, axis=1), axis=0, return_index=True)[1]]
    moved = rng.random(len(pool)) < 0.6
    return pool, T, moved


@pytest.mark.parametrize("seed", range(4))
def test_improper_pairs_are_every_improper_pair(seed, monkeypatch):
    """The exact test on only the pairs' own vertices (a smaller common scale, renumbered
    triangles) finds exactly the improper pairs with a moved vertex among all pairs, each
    tested on all vertices' integers; in pair order; forked over two processes alike."""
    V, T, moved = _soup(seed)
    grid = Grid(-20, (0, 0, 0))
    Vi, Tl = self_intersection._common_integers(V), T.tolist()
    want = [(a, b) for a in range(len(T)) for b in range(a + 1, len(T))
            if moved[T[[a, b]]].any() and self_intersection._improper(Vi, Tl[a], Tl[b])]
    got, used = self_intersection._improper_pairs(V, T, grid, moved)
    assert got.dtype == np.int64 and got.tolist() == [list(p) for p in want] and used == 1
    assert len(want) > 20
    if can_fork():
        monkeypatch.setattr(self_intersection, "_PARALLEL_CHECK", 1)
        two, used = self_intersection._improper_pairs(V, T, grid, moved, workers=2)
        assert used == 2 and np.array_equal(two, got)
    none, _ = self_intersection._improper_pairs(V, T, grid, np.zeros(len(V), dtype=bool))
    assert none.shape == (0, 2)


def _nonmanifold_reference(faces: np.ndarray, n_vertices: int):
    """Brute force: edges of more than two triangles (sorted); vertices whose triangles
    form several fans, the triangles at a vertex joined (union-find) across its edges of
    exactly two triangles."""
    F = faces.tolist()
    uses: dict = {}
    for t, f in enumerate(F):
        for k in range(3):
            uses.setdefault(tuple(sorted((f[k], f[(k + 1) % 3]))), []).append(t)
    edges = sorted(e for e, ts in uses.items() if len(ts) > 2)
    parent = {(t, x): (t, x) for t, f in enumerate(F) for x in f}  # corners

    def root(c):
        while parent[c] != c:
            c = parent[c]
        return c

    for (x, y), ts in uses.items():
        if len(ts) == 2:
            for v in (x, y):
                parent[root((ts[0], v))] = root((ts[1], v))
    fans = [set() for _ in range(n_vertices)]
    for t, x in parent:
        fans[x].add(root((t, x)))
    return (np.array(edges, dtype=np.int64).reshape(-1, 2),
            np.array([x for x in range(n_vertices) if len(fans[x]) > 1], dtype=np.int64))


def _tetrahedra_glued(rng) -> tuple[np.ndarray, int]:
    """Surfaces of tetrahedra with some vertices identified (pinch vertices, edges of four
    or six triangles) and two triangles doubled."""
    tet = np.array([[0, 2, 1], [0, 1, 3], [1, 2, 3], [0, 3, 2]])
    k = 6
    F = np.concatenate([tet + 4 * i for i in range(k)])
    ids = np.arange(4 * k)
    ids[4] = 0  # tetrahedra 0 and 1 share a vertex
    ids[8], ids[9] = 0, 1  # tetrahedron 2 shares an edge with 0
    ids[12], ids[13] = 0, 1  # ... and 3 too: an edge of six triangles
    ids[20] = 17  # 4 and 5 share a vertex
    F = ids[F]
    F = np.concatenate([F, F[rng.integers(0, len(F), 2)]])  # doubled triangles
    _, F = np.unique(F, return_inverse=True)
    return F.reshape(-1, 3).astype(np.int64), int(F.max()) + 1


@pytest.mark.parametrize("seed", range(3))
def test_nonmanifold_is_identical(seed):
    rng = np.random.default_rng(seed)
    cases = [_tetrahedra_glued(rng)]
    for V, F in (torus(sections=12, ring=8), star(), comb(3, 2)):
        F = np.asarray(F, dtype=np.int64)
        cases.append((F, len(V)))
        cases.append((np.concatenate([F, F[rng.integers(0, len(F), 4)]]), len(V)))  # doubled
    for F, n in cases:
        a, b = output._nonmanifold(F, n), _nonmanifold_reference(F, n)
        assert all(np.array_equal(x, y) and x.dtype == y.dtype for x, y in zip(a, b))
    F, n = cases[0]
    edges, vertices = output._nonmanifold(F, n)
    assert len(edges) and len(vertices)


def test_rounding_check_on_a_sum(monkeypatch):
    """On a real Minkowski sum's output (star + icosphere): the compiled conversion, moved
    points and boxes are the references', and the exact test on the pairs' own vertices
    agrees with all vertices' integers on every box pair with a moved vertex."""
    from cspace.minkowski.sum import minkowski_sum

    S = minkowski_sum(star(), icosphere_points(1, radius=0.3), workers=1)
    points, V, T, grid = S.points_exact, S.vertices, S.faces, S.grid
    assert _same_bits(V, output._to_float(points, grid))
    moved = rounding._moved(points, V, grid)
    assert np.array_equal(rounding._moved_compiled(points, V, grid), moved) and moved.any()
    lo, hi = self_intersection._triangle_boxes(V, T, grid.exponent)
    lo2, hi2 = self_intersection._triangle_boxes_compiled(V, T, grid.exponent)
    assert np.array_equal(lo, lo2) and np.array_equal(hi, hi2)
    monkeypatch.setattr(self_intersection, "_undecided_pairs_compiled",
                        lambda V, T, ps, mv: mv[T[ps]].any(axis=(1, 2)))
    pairs = boxes.box_pairs(lo, hi)
    pairs = pairs[moved[T[pairs]].any(axis=(1, 2))]
    Vi, Tl = self_intersection._common_integers(V), T.tolist()
    want = [(a, b) for a, b in pairs.tolist() if self_intersection._improper(Vi, Tl[a], Tl[b])]
    got, _ = self_intersection._improper_pairs(V, T, grid, moved)
    assert len(pairs) > 1000 and got.tolist() == [list(p) for p in want]
