"""The compiled triangle-pair engine (two box trees, :mod:`cspace.geometry._kernels.pairquery`)
against its pure-Python reference (every pair enumerated, ``_PairsCO``).

Both decide exactly, so their answers must be *identical*: membership, segment freedom and
first contact on uniform queries, on the corners of pieces (exact ties) and a few ulps off
them, for open and closed operands, pieces grown by a margin box, degenerate and coplanar
triangles, at the origin and where real scenes sit.
"""

from __future__ import annotations

import numpy as np
import pytest
from zoo import comb, torus

from cspace.cobstacle.pairs import _TreePairsCO, triangle_pairs
from cspace.cobstacle.pairs_reference import _PairsCO
from cspace.geometry.boxes import BoxTree
from cspace.geometry.exact import Grid

OFF = np.array([250.0, 150.0, -300.0])
EVERYWHERE = np.array([[-2.0**60] * 3, [2.0**60] * 3])


def _operands(offset, seed):
    """An obstacle (a torus plus a soup with a collinear and a coplanar triangle) and a comb
    robot, on a grid whose origin sits at ``offset``."""
    rng = np.random.default_rng(seed)
    grid = Grid(-12, 26, tuple(int(x) for x in np.round(np.asarray(offset) * 2**12)))
    V, F = torus(sections=10, ring=6)
    soup = rng.uniform(-1.5, 1.5, (12, 3))
    soup[3] = (soup[4] + soup[5]) / 2           # collinear corners: a degenerate triangle
    soup[6:9] = [[0.2, 0.1, 0.5], [0.9, 0.3, 0.5], [0.4, 0.8, 0.5]]  # z = 0.5, as a robot face
    F = np.vstack([F, np.arange(12).reshape(4, 3) + len(V)])
    V = np.vstack([np.asarray(V) * 0.8, soup])
    RV, RF = comb(3, 2)
    RV = np.asarray(RV, np.float64) * 0.15
    RV[:, 2] -= RV[:, 2].min() - 0.5             # the comb's base at z = 0.5: coplanar faces
    o_ints = grid.snap(np.asarray(V) + offset)
    r_ints = grid.vectors.snap(RV)
    return grid, o_ints, np.asarray(F, np.int64), r_ints, np.asarray(RF, np.int64)


def _queries(ref, grid, rng, n=300):
    lo, hi = ref.lo.min(axis=0), ref.hi.max(axis=0)
    k = rng.integers(0, len(ref.pairs), n // 3)
    corners = np.array([grid.vectors.to_float(
        (ref.S[i][:, None] + ref.T[j][None]).reshape(-1, 3)[rng.integers(0, 9)] + ref.g
        * rng.choice([-1, 0, 1], 3)) for i, j in ref.pairs[k].tolist()])
    near = corners + rng.choice([-1, 0, 1], corners.shape) * np.spacing(np.abs(corners))
    return np.ascontiguousarray(np.vstack([rng.uniform(lo, hi, (n, 3)), corners, near]))


@pytest.mark.parametrize("offset", [np.zeros(3), OFF], ids=["origin", "off-origin"])
@pytest.mark.parametrize("closed", [False, True], ids=["open", "closed"])
@pytest.mark.parametrize("margin", [(0, 0, 0), (2, 1, 3)], ids=["exact", "grown"])
def test_the_compiled_engine_answers_as_the_reference(offset, closed, margin):
    grid, o_ints, o_faces, r_ints, r_faces = _operands(offset, 3)
    c_ints = grid.vectors.snap(np.array([0.05, -0.02, 0.1]))
    tp = triangle_pairs(o_ints, o_faces, r_ints, r_faces, c_ints, EVERYWHERE, closed=closed,
                        margin=margin)
    assert tp.flat.any() != closed  # coplanar faces: kept when open, left out when closed
    ref = _PairsCO(tp.S, tp.T, tp.pairs, grid, margin)
    new = _TreePairsCO(tp.S, tp.T, grid, closed=closed, margin=margin)
    rng = np.random.default_rng(7)
    q = _queries(ref, grid, rng)
    inside = ref.contains(q)
    assert 50 < inside.sum() < len(q) - 50
    assert np.array_equal(new.contains(q), inside)
    # one state at a time (the planner's path: no arrays through the kernel)
    assert [bool(new.contains(x[None])[0]) for x in q] == inside.tolist()
    q1 = q + rng.normal(scale=0.2, size=q.shape)
    q1[::7] = q[::7]  # points as segments
    free = ref.segments(q, q1, False)[0]
    assert np.array_equal(new.segments(q, q1, False)[0], free)
    assert [bool(new.segments(a[None], b[None], False)[0][0]) for a, b in zip(q, q1)] \
        == free.tolist()
    h_new, t_new = new.segments(q[:120], q1[:120], True)
    h_ref, t_ref = ref.segments(q[:120], q1[:120], True)
    assert np.array_equal(h_new, h_ref) and np.array_equal(t_new, t_ref, equal_nan=True)
    d_new, d_ref = new.signed_distance(q[:40]), ref.signed_distance(q[:40])
    assert np.array_equal(np.sign(d_new), np.sign(d_ref))
    assert np.allclose(d_new, d_ref, rtol=0, atol=1e-12)


@pytest.mark.parametrize("margin", [(0, 0, 0), (1, 1, 1)], ids=["exact", "grown"])
def test_a_segment_or_a_point_is_never_left_out_as_flat(margin):
    """Issue #51: a feature thinner than the step snaps to a segment ``(a, b, b)`` or a point
    ``(a, a, a)``; against a closed robot none of its pairs is left out as flat (the old rule
    dropped every pair of a zero normal: the obstacle vanished), and the compiled engine and
    the reference agree on it, far from the origin."""
    grid = Grid(-12, 26, tuple(int(x) for x in np.round(OFF * 2**12)))
    seg = grid.snap(np.array([[0.0, 0.0, 0.0], [1.0, 0.3, -0.2], [0.4, -0.5, 0.7]]) + OFF)
    o_faces = np.array([[0, 1, 1], [2, 2, 2]])  # a segment and a point
    RV, RF = comb(3, 2)
    r_ints = grid.vectors.snap(np.asarray(RV, np.float64) * 0.15)
    c_ints = grid.vectors.snap(np.array([0.05, -0.02, 0.1]))
    tp = triangle_pairs(seg, o_faces, r_ints, np.asarray(RF, np.int64), c_ints, EVERYWHERE,
                        closed=True, margin=margin)
    assert tp.flat_skipped == 0 and len(tp.pairs) == 2 * len(RF)
    ref = _PairsCO(tp.S, tp.T, tp.pairs, grid, margin)
    new = _TreePairsCO(tp.S, tp.T, grid, closed=True, margin=margin)
    q = _queries(ref, grid, np.random.default_rng(4))
    inside = ref.contains(q)
    assert 50 < inside.sum() < len(q) - 50
    assert np.array_equal(new.contains(q), inside)


def test_box_tree_nodes_hold_their_boxes():
    rng = np.random.default_rng(2)
    lo = rng.integers(-1000, 1000, (257, 3)).astype(np.float64)
    hi = lo + rng.integers(0, 50, (257, 3))
    t = BoxTree(lo, hi, leaf=3)
    assert sorted(t.order.tolist()) == list(range(257))
    for k in range(len(t.first)):
        if t.count[k]:
            idx = t.order[t.first[k]:t.first[k] + t.count[k]]
        else:
            a, b = t.first[k], t.first[k] + 1
            assert (t.lo[k] <= t.lo[a]).all() and (t.hi[b] <= t.hi[k]).all()
            continue
        assert (t.lo[k] <= lo[idx]).all() and (hi[idx] <= t.hi[k]).all() and t.count[k] <= 3


def test_candidates_are_every_pair_whose_dop_meets():
    """The trees' candidates hold every pair whose k-DOP meets the query box's (brute force in
    integers over every pair), and nothing whose axis box misses it: the diagonals only prune."""
    grid, o_ints, o_faces, r_ints, r_faces = _operands(OFF, 5)
    c_ints = np.zeros(3, np.int64)
    S = o_ints[o_faces] + np.asarray(grid.origin)
    T = c_ints - r_ints[r_faces]
    new = _TreePairsCO(o_ints[o_faces], T, grid, closed=False)
    D = new.directions
    assert len(D) == 13
    rng = np.random.default_rng(1)
    Q = np.ldexp(rng.uniform(new.lo[0], new.hi[0], (60, 3)), -grid.exponent)
    lo, hi = np.floor(Q - 300), np.ceil(Q + 300)
    got = {tuple(x) for x in new._set.candidates(lo, hi).tolist()}
    # the query box's k-DOP: its corners' projections (integers, exact)
    corners = np.array([[a, b, c] for a in (0, 1) for b in (0, 1) for c in (0, 1)])
    box = np.where(corners[None], hi[:, None], lo[:, None]).astype(np.int64) @ D.T
    ps, pt = S @ D.T, T @ D.T  # (n, 3, k)
    p_lo = ps.min(axis=1)[:, None] + pt.min(axis=1)[None]
    p_hi = ps.max(axis=1)[:, None] + pt.max(axis=1)[None]
    want, axes = set(), set()
    for r in range(len(Q)):
        meet = (p_lo <= box[r].max(axis=0)) & (box[r].min(axis=0) <= p_hi)
        want |= {(r, i, j) for i, j in zip(*np.nonzero(meet.all(axis=2)))}
        axes |= {(r, i, j) for i, j in zip(*np.nonzero(meet[..., :3].all(axis=2)))}
    assert want <= got <= axes and len(want) > 100 and len(axes) > len(want)


@pytest.mark.parametrize("offset", [np.zeros(3), OFF], ids=["origin", "off-origin"])
def test_the_box_index_finds_every_box_a_query_meets(offset):
    """The union's broad phase (a compiled walk of one box tree) against brute force, with
    boxes touching the queries exactly (closed boxes: touching counts)."""
    from cspace.geometry._kernels import load

    rng = np.random.default_rng(4)
    lo = rng.uniform(-50, 50, (300, 3)) + offset
    hi = lo + rng.uniform(0, 8, (300, 3))
    index = load("boxtree").BoxIndex(BoxTree(lo, hi, leaf=3))
    q_lo = np.vstack([rng.uniform(-60, 60, (200, 3)) + offset, hi[:50], lo[50:100]])
    q_hi = q_lo + np.vstack([rng.uniform(0, 5, (200, 3)), np.zeros((100, 3))])
    rows, items = index.overlaps(q_lo, q_hi)
    want = ((lo[None] <= q_hi[:, None]) & (q_lo[:, None] <= hi[None])).all(axis=2)
    assert {(int(r), int(i)) for r, i in zip(rows, items)} == set(zip(*map(list, np.nonzero(want))))
    assert want.sum() > 100
    for r in range(200, 300):  # corners: the point queries
        assert sorted(index.point(*q_lo[r])) == np.flatnonzero(want[r]).tolist()
