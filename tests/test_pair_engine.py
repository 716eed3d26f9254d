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
    q1 = q + rng.normal(scale=0.2, size=q.shape)
    q1[::7] = q[::7]  # points as segments
    assert np.array_equal(new.segments(q, q1, False)[0], ref.segments(q, q1, False)[0])
    h_new, t_new = new.segments(q[:120], q1[:120], True)
    h_ref, t_ref = ref.segments(q[:120], q1[:120], True)
    assert np.array_equal(h_new, h_ref) and np.array_equal(t_new, t_ref, equal_nan=True)
    d_new, d_ref = new.signed_distance(q[:40]), ref.signed_distance(q[:40])
    assert np.array_equal(np.sign(d_new), np.sign(d_ref))
    assert np.allclose(d_new, d_ref, rtol=0, atol=1e-12)


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


def test_candidates_are_every_pair_whose_box_meets():
    """The trees' candidates equal a brute-force box test over every pair."""
    grid, o_ints, o_faces, r_ints, r_faces = _operands(OFF, 5)
    c_ints = np.zeros(3, np.int64)
    S = o_ints[o_faces] + np.asarray(grid.origin)
    T = c_ints - r_ints[r_faces]
    new = _TreePairsCO(o_ints[o_faces], T, grid, closed=False)
    rng = np.random.default_rng(1)
    Q = np.ldexp(rng.uniform(new.lo[0], new.hi[0], (60, 3)), -grid.exponent)
    lo, hi = np.floor(Q - 300), np.ceil(Q + 300)
    got = {tuple(x) for x in new._set.candidates(lo, hi).tolist()}
    p_lo = S.min(axis=1)[:, None] + T.min(axis=1)[None]
    p_hi = S.max(axis=1)[:, None] + T.max(axis=1)[None]
    want = set()
    for r in range(len(Q)):
        m = ((p_lo <= hi[r]) & (lo[r] <= p_hi)).all(axis=2)
        want |= {(r, i, j) for i, j in zip(*np.nonzero(m))}
    assert got == want and len(want) > 100
