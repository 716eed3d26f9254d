"""Properties of the exact kernel, cspace.geometry.exact.

Every sign is compared with a reference evaluated in Python ``int`` (or ``fractions.Fraction``
for the grid and for the symbolic perturbation, checked against an exact rational rotation),
which never rounds. The inputs come from tests/strategies.py (imported as a sibling module, as
tests/oracles.py is): random points, and degenerate families built on purpose (coplanar,
collinear, duplicated, one unit apart at the grid's limit, one unit off a plane), on which a
float evaluation alone is wrong.
"""

from __future__ import annotations

import itertools
import math
from fractions import Fraction

import numpy as np
import pytest
from hypothesis import assume, given, settings
from hypothesis import strategies as st

from cspace.errors import ExactnessError, GridRangeError, NonFiniteError
from cspace.geometry.exact import (
    Grid,
    Perturbation,
    cross,
    dot_sign,
    dot_sign_matrix,
    orient2d,
    orient3d,
    plane_side_matrix,
    primitive,
    support_mask,
    triple_sign,
)

import strategies as cs

# Tests whose every example is a batch of up to ~8 configurations run a quarter of the
# profile's examples (so ci: 50, dev: 250), which keeps the file under ~30 s on 2 cores.
batch_settings = settings(max_examples=max(25, settings().max_examples // 4))

# -- exact references (Python ints only) ---------------------------------------------------


def _py(v) -> list[int]:
    return [int(x) for x in np.asarray(v).reshape(-1)]


def _sign(x: int) -> int:
    return (x > 0) - (x < 0)


def _sub(p, q) -> list[int]:
    return [x - y for x, y in zip(_py(p), _py(q))]


def _det3(u, v, w) -> int:
    u, v, w = _py(u), _py(v), _py(w)
    return (
        u[0] * (v[1] * w[2] - v[2] * w[1])
        - u[1] * (v[0] * w[2] - v[2] * w[0])
        + u[2] * (v[0] * w[1] - v[1] * w[0])
    )


def _orient3d_ref(a, b, c, d) -> int:
    return _sign(_det3(_sub(b, a), _sub(c, a), _sub(d, a)))


def _orient2d_ref(a, b, c) -> int:
    u, v = _sub(b, a), _sub(c, a)
    return _sign(u[0] * v[1] - u[1] * v[0])


def _dot(u, v) -> int:
    return sum(x * y for x, y in zip(_py(u), _py(v)))


def _cross_ref(u, v) -> list[int]:
    u, v = _py(u), _py(v)
    return [u[1] * v[2] - u[2] * v[1], u[2] * v[0] - u[0] * v[2], u[0] * v[1] - u[1] * v[0]]


def _float_det3(u, v, w) -> float:
    """The cofactor expansion evaluated in float64 alone (what the filter computes)."""
    u, v, w = (np.asarray(x, dtype=np.float64) for x in (u, v, w))
    return float(
        u[0] * (v[1] * w[2] - v[2] * w[1])
        + u[1] * (v[2] * w[0] - v[0] * w[2])
        + u[2] * (v[0] * w[1] - v[1] * w[0])
    )


def _stack(rows) -> np.ndarray:
    return np.asarray(np.stack(rows), dtype=np.int64)


def _is_sign_array(result, shape) -> bool:
    result = np.asarray(result)
    return result.dtype == np.int8 and result.shape == shape


# -- triple_sign -----------------------------------------------------------------------------


@given(cs.huge_vectors(), cs.huge_vectors(), cs.huge_vectors())
def test_triple_sign_random_is_exact(u, v, w):
    result = triple_sign(u[None], v[None], w[None])
    assert _is_sign_array(result, (1,))
    assert result[0] == _sign(_det3(u, v, w))


@given(cs.coplanar_huge_triples())
def test_triple_sign_coplanar_huge_is_zero(uvw):
    assert _det3(*uvw) == 0
    assert triple_sign(*(x[None] for x in uvw))[0] == 0


@given(cs.near_coplanar_huge_triples())
def test_triple_sign_near_coplanar_huge_is_exact_and_nonzero(uvw):
    expected = _sign(_det3(*uvw))
    assert expected != 0
    assert triple_sign(*(x[None] for x in uvw))[0] == expected


@given(cs.huge_vectors(), cs.huge_vectors(), cs.huge_vectors())
def test_triple_sign_alternates_under_swaps_and_cycles(u, v, w):
    s = int(triple_sign(u[None], v[None], w[None])[0])
    assert triple_sign(v[None], u[None], w[None])[0] == -s
    assert triple_sign(u[None], w[None], v[None])[0] == -s
    assert triple_sign(w[None], v[None], u[None])[0] == -s
    assert triple_sign(v[None], w[None], u[None])[0] == s
    assert triple_sign(w[None], u[None], v[None])[0] == s
    assert triple_sign(-u[None], v[None], w[None])[0] == -s


def test_float_det_gives_wrong_sign_where_triple_sign_is_right():
    """Inputs near 2**60 round on conversion to float64: the rounded matrix has determinant
    -2**67 (numpy and the plain cofactor expansion both say negative), the exact one is
    positive. The exact fallback is what makes triple_sign right."""
    x = 2**60
    m = np.array([[x + 127, x - 63, 0], [x - 63, x - 65, 0], [0, 0, 1]], dtype=np.int64)
    exact = _det3(*m)
    assert exact > 0
    assert np.sign(np.linalg.det(m.astype(np.float64))) == -1
    assert _float_det3(*m) < 0
    assert triple_sign(m[0][None], m[1][None], m[2][None])[0] == 1


def test_triple_sign_where_float_error_exceeds_eps_times_permanent():
    """Entries near 2**60 whose conversion roundings add up: the float64 value has the wrong
    sign and magnitude 1.4 * eps * permanent, so a filter bound of one eps would trust it."""
    m = [
        [-798793810074370824, -950095959298979482, -685184604826058832],
        [883343233700653416, 719534909246463728, 793507477148104226],
        [84549423626282592, -230561050052515755, 108322872322045394],
    ]
    exact = _det3(*m)
    value = _float_det3(*m)
    perm = sum(abs(m[0][i] * m[1][j] * m[2][k]) for i, j, k in itertools.permutations(range(3)))
    assert exact < 0 < value
    assert Fraction(value) > Fraction(14, 10) * Fraction(2.0**-53) * perm
    assert triple_sign(*(np.array([r]) for r in m))[0] == -1


# -- orient3d --------------------------------------------------------------------------------


@given(cs.random_quads())
def test_orient3d_random_is_exact(quad):
    result = orient3d(*(p[None] for p in quad))
    assert _is_sign_array(result, (1,))
    assert result[0] == _orient3d_ref(*quad)


@pytest.mark.parametrize(
    "family",
    [cs.coplanar_quads(), cs.axis_plane_quads(), cs.collinear_quads(), cs.duplicate_quads()],
    ids=["coplanar", "axis_plane", "collinear", "duplicate"],
)
@given(data=st.data())
def test_orient3d_degenerate_is_zero(family, data):
    quad = data.draw(family)
    assert _orient3d_ref(*quad) == 0
    assert orient3d(*(p[None] for p in quad))[0] == 0


@given(cs.limit_quads())
def test_orient3d_one_unit_apart_at_the_limit_is_exact(quad):
    assert orient3d(*(p[None] for p in quad))[0] == _orient3d_ref(*quad)


@given(cs.near_coplanar_quads())
def test_orient3d_near_coplanar_is_exact_and_nonzero(quad):
    expected = _orient3d_ref(*quad)
    assert expected != 0
    assert orient3d(*(p[None] for p in quad))[0] == expected


def test_orient3d_float_evaluation_is_wrong_on_grid_points():
    """Minkowski-sum grid points (|k| <= 2**27) one unit off a plane: the exact determinant
    is -1, the float64 cofactor expansion of the same differences says about +4.7e5."""
    a = [-63993458, 16893705, 57592506]
    b = [-39666533, 39974983, 78090758]
    c = [-57130950, 23404822, 75383821]
    d = [-32804025, 46486100, 95882072]
    assert all(abs(x) <= cs.SUM_LIMIT for x in a + b + c + d)
    assert _det3(_sub(b, a), _sub(c, a), _sub(d, a)) == -1
    assert _float_det3(_sub(b, a), _sub(c, a), _sub(d, a)) > 0
    assert orient3d(*(np.array([p]) for p in (a, b, c, d)))[0] == -1


_EVEN = [p for p in itertools.permutations(range(4)) if
         sum(p[i] > p[j] for i in range(4) for j in range(i + 1, 4)) % 2 == 0]


@given(cs.any_quads())
def test_orient3d_permutation_parity(quad):
    s = _orient3d_ref(*quad)
    rows = [p[None] for p in quad]
    for i, j in itertools.combinations(range(4), 2):
        swapped = list(rows)
        swapped[i], swapped[j] = swapped[j], swapped[i]
        assert orient3d(*swapped)[0] == -s, (i, j)
    for perm in _EVEN:
        assert orient3d(*(rows[k] for k in perm))[0] == s, perm


@given(cs.any_quads(), st.one_of(cs.sum_points(), cs.points(limit=2**60)))
def test_orient3d_translation_invariant(quad, t):
    s = orient3d(*(p[None] for p in quad))[0]
    assert orient3d(*((p + t)[None] for p in quad))[0] == s


# -- orient2d --------------------------------------------------------------------------------


@given(cs.random_triples_2d())
def test_orient2d_random_is_exact(tri):
    result = orient2d(*(p[None] for p in tri))
    assert _is_sign_array(result, (1,))
    assert result[0] == _orient2d_ref(*tri)


@given(cs.degenerate_triples_2d())
def test_orient2d_collinear_and_duplicates_are_zero(tri):
    assert _orient2d_ref(*tri) == 0
    assert orient2d(*(p[None] for p in tri))[0] == 0


@given(st.one_of(cs.limit_triples_2d(), cs.near_collinear_triples_2d()))
def test_orient2d_near_degenerate_is_exact(tri):
    assert orient2d(*(p[None] for p in tri))[0] == _orient2d_ref(*tri)


@given(cs.near_collinear_triples_2d())
def test_orient2d_near_collinear_is_nonzero(tri):
    assert _orient2d_ref(*tri) != 0


def test_orient2d_float_evaluation_is_wrong_on_grid_points():
    """Grid points with differences ~2**28: exact turn +1, float64 evaluation gives 0."""
    a, b, c = [-63891679, -42347645], [134204192, 126880185], [-134193483, -102404534]
    u, v = _sub(b, a), _sub(c, a)
    assert u[0] * v[1] - u[1] * v[0] == 1
    assert float(u[0]) * float(v[1]) - float(u[1]) * float(v[0]) == 0.0
    assert orient2d(np.array([a]), np.array([b]), np.array([c]))[0] == 1


@given(cs.any_triples_2d(), st.one_of(cs.sum_points(2), cs.points(2, limit=2**60)))
def test_orient2d_symmetries(tri, t):
    a, b, c = (p[None] for p in tri)
    s = _orient2d_ref(*tri)
    assert orient2d(b, a, c)[0] == -s
    assert orient2d(a, c, b)[0] == -s
    assert orient2d(c, b, a)[0] == -s
    assert orient2d(b, c, a)[0] == s
    assert orient2d(c, a, b)[0] == s
    assert orient2d(a + t, b + t, c + t)[0] == s


# -- dot_sign --------------------------------------------------------------------------------


@given(cs.any_vector_pairs())
def test_dot_sign_is_exact(pair):
    u, v = pair
    result = dot_sign(u[None], v[None])
    assert _is_sign_array(result, (1,))
    assert result[0] == _sign(_dot(u, v))
    assert dot_sign(v[None], u[None])[0] == result[0]
    assert dot_sign(-u[None], v[None])[0] == -result[0]


@given(cs.orthogonal_pairs())
def test_dot_sign_orthogonal_is_zero(pair):
    assert _dot(*pair) == 0
    assert dot_sign(pair[0][None], pair[1][None])[0] == 0


@given(cs.near_orthogonal_pairs())
def test_dot_sign_near_orthogonal_is_nonzero(pair):
    expected = _sign(_dot(*pair))
    assert expected != 0
    assert dot_sign(pair[0][None], pair[1][None])[0] == expected


# -- batches, broadcasting, dtypes -----------------------------------------------------------


@batch_settings
@given(st.lists(cs.any_quads(), min_size=1, max_size=8))
def test_orient3d_batch_equals_rows(quads):
    a, b, c, d = (_stack(col) for col in zip(*quads))
    result = orient3d(a, b, c, d)
    assert _is_sign_array(result, (len(quads),))
    rows = [orient3d(a[i : i + 1], b[i : i + 1], c[i : i + 1], d[i : i + 1])[0]
            for i in range(len(quads))]
    assert result.tolist() == rows == [_orient3d_ref(*q) for q in quads]
    u, v, w = b - a, c - a, d - a
    assert triple_sign(u, v, w).tolist() == rows


@batch_settings
@given(st.lists(cs.any_quads(), min_size=1, max_size=6), cs.sum_points())
def test_orient3d_broadcasts(quads, apex):
    """One point (3,) against n rows, and a (k, 1, 3) x (1, m, 3) grid of queries."""
    a, b, c, d = (_stack(col) for col in zip(*quads))
    n = len(quads)
    result = orient3d(apex, b, c, d)
    assert _is_sign_array(result, (n,))
    assert result.tolist() == [_orient3d_ref(apex, b[i], c[i], d[i]) for i in range(n)]
    table = orient3d(a[:, None], b[:, None], c[:, None], d[None, :])
    assert _is_sign_array(table, (n, n))
    assert table.tolist() == [
        [_orient3d_ref(a[i], b[i], c[i], d[j]) for j in range(n)] for i in range(n)
    ]


@batch_settings
@given(st.lists(cs.any_triples_2d(), min_size=1, max_size=8))
def test_orient2d_batch_equals_rows(tris):
    a, b, c = (_stack(col) for col in zip(*tris))
    result = orient2d(a, b, c)
    assert _is_sign_array(result, (len(tris),))
    rows = [orient2d(a[i : i + 1], b[i : i + 1], c[i : i + 1])[0] for i in range(len(tris))]
    assert result.tolist() == rows == [_orient2d_ref(*t) for t in tris]
    assert _is_sign_array(orient2d(a[0], b, c), (len(tris),))


@batch_settings
@given(st.lists(cs.any_vector_pairs(), min_size=1, max_size=8))
def test_dot_sign_batch_equals_rows(pairs):
    u, v = (_stack(col) for col in zip(*pairs))
    result = dot_sign(u, v)
    assert _is_sign_array(result, (len(pairs),))
    assert result.tolist() == [_sign(_dot(p, q)) for p, q in pairs]
    assert dot_sign(u[:, None], v[None, :]).tolist() == [
        [_sign(_dot(p, q)) for q in v] for p in u
    ]


def test_empty_batches():
    e3, e2 = np.zeros((0, 3), np.int64), np.zeros((0, 2), np.int64)
    assert _is_sign_array(orient3d(e3, e3, e3, e3), (0,))
    assert _is_sign_array(triple_sign(e3, e3, e3), (0,))
    assert _is_sign_array(orient2d(e2, e2, e2), (0,))
    assert _is_sign_array(dot_sign(e3, e3), (0,))
    assert _is_sign_array(dot_sign_matrix(e3, np.ones((2, 3), np.int64)), (0, 2))
    assert _is_sign_array(dot_sign_matrix(np.ones((2, 3), np.int64), e3), (2, 0))


@given(st.one_of(cs.any_quads(), cs.degenerate_quads()))
def test_single_unbatched_points(quad):
    """``(3,)`` inputs give a 0-d int8 sign, degenerate ones included.

    Regression: ``_filtered`` used to assign into a numpy scalar (``sign[unsure] = ...``) and
    raised TypeError whenever the float filter could not decide a single unbatched query.
    """
    a, b, c, d = quad
    result = orient3d(a, b, c, d)
    assert _is_sign_array(result, ())
    assert int(result) == _orient3d_ref(*quad)
    assert int(triple_sign(b - a, c - a, d - a)) == _orient3d_ref(*quad)
    assert int(orient2d(a[:2], b[:2], c[:2])) == _orient2d_ref(a[:2], b[:2], c[:2])
    assert int(dot_sign(b - a, d - c)) == _sign(_dot(_sub(b, a), _sub(d, c)))


# -- dot_sign_matrix -------------------------------------------------------------------------


@st.composite
def _matrix_operands(draw):
    """U (n, 3) and V (m, 3) where V holds vectors orthogonal to rows of U, negatives of rows
    of U, near-orthogonal vectors and random huge ones: zeros and tiny dots are frequent."""
    vec = st.one_of(cs.sum_points(), cs.huge_vectors(), cs.directions())
    n, m = draw(st.integers(1, 6)), draw(st.integers(1, 6))
    U = [draw(vec) for _ in range(n)]
    V = []
    for _ in range(m):
        kind = draw(st.sampled_from(["random", "orthogonal", "near", "negative"]))
        base = _py(U[draw(st.integers(0, n - 1))])
        base = [x // (2**34) if abs(x) > 2**27 else x for x in base]
        w = _py(draw(cs.points(limit=2**30)))
        if kind == "random":
            V.append(_py(draw(vec)))
        elif kind == "orthogonal":
            V.append(_cross_ref(w, base))
        elif kind == "near":
            o = _cross_ref(w, base)
            o[draw(st.integers(0, 2))] += draw(st.sampled_from([1, -1]))
            V.append(o)
        else:
            V.append([-x for x in base])
    return _stack(U), np.asarray(V, dtype=np.int64)


@batch_settings
@given(_matrix_operands())
def test_dot_sign_matrix_is_exact(UV):
    U, V = UV
    result = dot_sign_matrix(U, V)
    assert _is_sign_array(result, (len(U), len(V)))
    assert result.tolist() == [[_sign(_dot(u, v)) for v in V] for u in U]
    assert (dot_sign_matrix(V, U) == result.T).all()


# -- support_mask ----------------------------------------------------------------------------


def _support_ref(P, D) -> list[list[bool]]:
    out = []
    for d in D:
        dots = [_dot(p, d) for p in P]
        best = max(dots)
        out.append([x == best for x in dots])
    return out


@st.composite
def _near_tie_support(draw):
    """Direction ``(M, M, c)`` with ``M ~ 2**55`` and points ``p + i*(1, -1, 0) + s*e_z``:
    exact ties (same s) and winners by one unit, invisible to float64 (values ~2**82)."""
    base = _py(draw(cs.points()))
    big = draw(st.integers(2**54, 2**56) | st.integers(-(2**56), -(2**54)))
    c = draw(st.integers(-3, 3))
    pts = []
    for _ in range(draw(st.integers(2, 10))):
        i, s = draw(st.integers(-50, 50)), draw(st.integers(-1, 1))
        pts.append([base[0] + i, base[1] - i, base[2] + s])
    dirs = [[big, big, c], [-big, -big, -c], [big, big + draw(st.integers(-1, 1)), c]]
    return np.asarray(pts, dtype=np.int64), np.asarray(dirs, dtype=np.int64)


@batch_settings
@given(
    st.one_of(
        st.tuples(cs.point_clouds(), st.lists(cs.directions(), min_size=1, max_size=6).map(_stack)),
        _near_tie_support(),
    )
)
def test_support_mask_is_exact_argmax(PD):
    P, D = PD
    mask = support_mask(P, D)
    assert mask.dtype == bool and mask.shape == (len(D), len(P))
    assert mask.tolist() == _support_ref(P, D)


@given(
    st.tuples(cs.sum_ints(), cs.sum_ints()).filter(lambda t: t[0] != t[1]).map(sorted),
    st.tuples(cs.sum_ints(), cs.sum_ints()).filter(lambda t: t[0] != t[1]).map(sorted),
    st.tuples(cs.sum_ints(), cs.sum_ints()).filter(lambda t: t[0] != t[1]).map(sorted),
    st.sampled_from([1, 3, 2**40, 2**55, 2**55 + 1]),
    st.permutations(range(8)),
)
def test_support_mask_box_faces_edges_vertices(xs, ys, zs, scale, order):
    """Box vertices: +z selects the top facet (4), (1,1,0) an edge (2), (1,1,1) a vertex."""
    P = np.array(list(itertools.product(xs, ys, zs)), dtype=np.int64)[list(order)]
    D = scale * np.array([[0, 0, 1], [1, 1, 0], [1, 1, 1], [0, 0, -1], [-1, 0, 0]], np.int64)
    mask = support_mask(P, D)
    assert mask.sum(axis=1).tolist() == [4, 2, 1, 4, 4]
    assert (P[mask[0], 2] == zs[1]).all() and (P[mask[3], 2] == zs[0]).all()
    assert (P[mask[1], :2] == [xs[1], ys[1]]).all()
    assert (P[mask[2]] == [xs[1], ys[1], zs[1]]).all()
    assert mask.tolist() == _support_ref(P, D)


def test_support_mask_empty_inputs():
    """No directions -> (0, n); no points -> (m, 0).

    Regression: with zero points ``value.argmax(axis=1)`` raised ValueError.
    """
    P = np.array([[0, 0, 0], [1, 2, 3]], dtype=np.int64)
    assert support_mask(P, np.zeros((0, 3), np.int64)).shape == (0, 2)
    assert support_mask(np.zeros((0, 3), np.int64), np.array([[0, 0, 1]])).shape == (1, 0)


# -- plane_side_matrix -----------------------------------------------------------------------


@st.composite
def _planes_and_points(draw):
    """Planes through three grid points ``a, b, c`` with normal ``(b - a) x (c - a)`` (up to
    ``2**57``), scaled normals, and points on them, one unit off them, or anywhere."""
    m = draw(st.integers(1, 4))
    Q, N, P = [], [], []
    for _ in range(m):
        a, b, c, d = (_py(x) for x in draw(cs.coplanar_quads()))
        n = _cross_ref(_sub(b, a), _sub(c, a))
        if not any(n) or draw(st.booleans()):
            a, b, c, d = (_py(x) for x in draw(cs.near_coplanar_quads()))
            n = _cross_ref(_sub(b, a), _sub(c, a))
        k = draw(st.sampled_from([1, -1, 3]))
        Q.append(draw(st.sampled_from([a, b, c])))
        N.append([k * x for x in n])
        P.extend([a, b, c, d])
    P.extend(_py(draw(cs.sum_points())) for _ in range(draw(st.integers(0, 3))))
    P = [P[i] for i in draw(st.permutations(range(len(P))))]
    return (np.asarray(P, np.int64), np.asarray(Q, np.int64), np.asarray(N, np.int64),
            draw(st.sampled_from([1 << 22, 1, 2, 5])))


@batch_settings
@given(_planes_and_points())
def test_plane_side_matrix_is_exact(pqnc):
    P, Q, N, chunk = pqnc
    side = plane_side_matrix(P, Q, N, chunk=chunk)
    assert _is_sign_array(side, (len(P), len(N)))
    assert side.tolist() == [[_sign(_dot(_sub(p, q), n)) for q, n in zip(Q, N)] for p in P]
    assert (plane_side_matrix(P, Q, -N) == -side).all()
    assert _is_sign_array(plane_side_matrix(P[:0], Q, N), (0, len(N)))
    assert _is_sign_array(plane_side_matrix(P, Q[:0], N[:0]), (len(P), 0))


# -- primitive -------------------------------------------------------------------------------


@batch_settings
@given(st.lists(st.one_of(cs.huge_vectors(), cs.directions(), st.just(np.zeros(3, np.int64))),
                min_size=1, max_size=8).map(_stack))
def test_primitive_divides_by_the_positive_gcd(V):
    P = primitive(V)
    assert P.dtype == np.int64 and P.shape == V.shape
    for v, p in zip(V, P):
        v, p = _py(v), _py(p)
        g = math.gcd(*v)
        if g == 0:
            assert p == [0, 0, 0]
        else:
            assert math.gcd(*p) == 1
            assert [g * x for x in p] == v
    assert (primitive(V[0]) == P[0]).all()


def _same_direction(u, v) -> bool:
    return any(_py(u)) and any(_py(v)) and _cross_ref(u, v) == [0, 0, 0] and _dot(u, v) > 0


@given(st.one_of(cs.parallel_pairs(), cs.random_vector_pairs(), cs.orthogonal_pairs()))
def test_primitive_equal_iff_same_direction(pair):
    u, v = pair
    assume(any(_py(u)) and any(_py(v)))
    pu, pv = primitive(np.stack([u, v]))
    assert ((pu == pv).all()) == _same_direction(u, v)


# -- cross -----------------------------------------------------------------------------------


@st.composite
def _safe_cross_pairs(draw):
    """Batches with ``2 * max|u| * max|v| < 2**61`` (the documented safe range)."""
    level = draw(st.integers(0, 59))
    n = draw(st.integers(1, 5))
    u = [_py(draw(cs.points(limit=2**level))) for _ in range(n)]
    v = [_py(draw(cs.points(limit=2 ** (59 - level) - 1))) for _ in range(n)]
    return np.asarray(u, dtype=np.int64), np.asarray(v, dtype=np.int64)


@batch_settings
@given(_safe_cross_pairs())
def test_cross_is_exact_on_safe_range(uv):
    u, v = uv
    result = cross(u, v)
    assert result.dtype == np.int64 and result.shape == u.shape
    assert result.tolist() == [_cross_ref(p, q) for p, q in zip(u, v)]
    assert (result == np.cross(u, v)).all()
    assert (cross(u[0], v[0]) == result[0]).all()


@given(st.integers(1, 60), st.data())
def test_cross_raises_when_overflow_is_possible(level, data):
    u = _py(data.draw(cs.points(limit=2**level)))
    v = _py(data.draw(cs.points(limit=2**61 - 1)))
    i, j = data.draw(st.integers(0, 2)), data.draw(st.integers(0, 2))
    u[i] = data.draw(st.sampled_from([1, -1])) * data.draw(st.integers(2**level, 2**61 - 1))
    v[j] = data.draw(st.sampled_from([1, -1])) * data.draw(
        st.integers(-(-(2**60) // abs(u[i])), 2**61 - 1))
    assert 2 * max(map(abs, u)) * max(map(abs, v)) >= 2**61
    with pytest.raises(GridRangeError, match="2\\*\\*61"):
        cross(np.array(u, np.int64), np.array(v, np.int64))


@given(cs.huge_vectors(), cs.huge_vectors())
def test_cross_is_exact_or_raises(u, v):
    try:
        result = cross(u, v)
    except GridRangeError:
        return
    assert _py(result) == _cross_ref(u, v)


# -- input validation ------------------------------------------------------------------------

_CALLS = {
    "triple_sign": lambda x: triple_sign(x, x, x),
    "orient3d": lambda x: orient3d(x, x, x, x),
    "orient2d": lambda x: orient2d(x[..., :2], x[..., :2], x[..., :2]),
    "dot_sign": lambda x: dot_sign(x, x),
    "dot_sign_matrix": lambda x: dot_sign_matrix(x, x),
    "support_mask": lambda x: support_mask(x, x),
    "plane_side_matrix": lambda x: plane_side_matrix(x, x, x),
    "cross": lambda x: cross(x, np.ones((1, 3), np.int64)),
    "primitive": lambda x: primitive(x),
}


@pytest.mark.parametrize("name", sorted(_CALLS))
@pytest.mark.parametrize(
    "values",
    [np.array([[0.0, 1.0, 2.0]]), np.array([[0.5, 1, 2]]), np.array([[True, False, True]]),
     np.array([[0.0, 1.0, np.nan]])],
    ids=["float_integral", "float", "bool", "float_nan"],
)
def test_non_integer_input_raises_type_error(name, values):
    with pytest.raises(TypeError, match="integer grid coordinates"):
        _CALLS[name](values)


@pytest.mark.parametrize(
    "value",
    [
        np.int64(2**61), np.int64(-(2**61)), np.int64(2**62), np.int64(2**63 - 1),
        np.int64(-(2**63)), np.uint64(2**61), np.uint64(2**63), np.uint64(2**64 - 1),
    ],
    ids=["2^61", "-2^61", "2^62", "int64_max", "int64_min", "u2^61", "u2^63", "uint64_max"],
)
def test_integers_beyond_2_61_raise(value):
    """Every predicate refuses ``|k| >= 2**61``, whatever the integer dtype.

    Regression: ``np.abs(-2**63)`` overflows to ``-2**63`` in int64, and uint64 values
    ``>= 2**63`` wrap when cast to int64; a range check made after either let them through.
    """
    x = np.array([[value, 1, 2]], dtype=np.asarray(value).dtype)
    returned = {}
    for name, call in _CALLS.items():
        try:
            returned[name] = call(x)
        except GridRangeError:
            pass
    assert not returned, f"accepted without GridRangeError: {returned}"


def test_wrapped_integers_never_give_wrong_answers():
    """Wrapped integers must raise GridRangeError, never give a wrong answer.

    Regression: with the late range check orient3d returned -1 for a positive orientation
    (``b - a`` wrapped), cross the zero vector instead of ``(0, 0, -2**64)``, primitive
    ``(1, 0, 0)`` for ``(-2**63, 0, 0)``, and triple_sign read uint64 ``2**64 - 1`` as -1.
    """
    lo = np.array([[-(2**63), 0, 0]], dtype=np.int64)
    zero, ey, ez = np.zeros((1, 3), np.int64), np.array([[0, 1, 0]]), np.array([[0, 0, 1]])
    checks = {
        "orient3d": (lambda: orient3d(lo, zero, ey, ez)[0],
                     _orient3d_ref(lo[0], zero[0], ey[0], ez[0])),
        "cross": (lambda: _py(cross(lo, 2 * ey)), _cross_ref(lo[0], 2 * ey[0])),
        "primitive": (lambda: _py(primitive(lo)), [-1, 0, 0]),
        "triple_sign": (lambda: triple_sign(np.array([[2**64 - 1, 0, 0]], np.uint64), ey, ez)[0],
                        1),
    }
    wrong = {}
    for name, (call, expected) in checks.items():
        try:
            got = call()
        except GridRangeError:
            continue
        if got != expected:
            wrong[name] = (got, expected)
    assert not wrong, f"silently wrong (got, exact): {wrong}"


# -- Grid ------------------------------------------------------------------------------------


@st.composite
def _grid_and_points(draw):
    extent = draw(cs.grid_extents())
    bits = draw(cs.grid_bits())
    coord = st.one_of(
        st.floats(-extent, extent, allow_nan=False),
        st.sampled_from([extent, -extent, 0.0, -0.0]),
    )
    n = draw(st.integers(1, 6))
    pts = np.array([[draw(coord) for _ in range(3)] for _ in range(n)], dtype=np.float64)
    return Grid.for_extent(extent, bits=bits), extent, bits, pts


@given(_grid_and_points())
def test_grid_snap_stays_within_limit_and_error_bound(gp):
    grid, _, bits, pts = gp
    k = grid.snap(pts)
    assert k.dtype == np.int64 and k.shape == pts.shape
    assert grid.limit == 2**bits
    assert np.abs(k).max() <= 2**bits
    assert grid.error_bound == grid.step / 2
    assert grid.point_error_bound == pytest.approx(math.sqrt(3) * grid.step / 2, rel=1e-15)
    back = grid.to_float(k)
    step = Fraction(grid.step)
    for x, y, ki in zip(pts.ravel(), back.ravel(), k.ravel()):
        assert abs(Fraction(float(y)) - Fraction(float(x))) <= Fraction(grid.error_bound)
        assert Fraction(float(y)) == int(ki) * step  # an exact multiple of the step


@given(_grid_and_points())
def test_grid_for_points_covers_its_points(gp):
    _, _, bits, pts = gp
    extent = float(np.abs(pts).max())
    try:
        expected = Grid.for_extent(extent, bits=bits)
    except GridRangeError:  # all coordinates tiny (below ~2**-975): refused, by design
        with pytest.raises(GridRangeError):
            Grid.for_points(pts, -pts[:1], np.zeros((0, 3)), bits=bits)
        return
    grid = Grid.for_points(pts, -pts[:1], np.zeros((0, 3)), bits=bits)
    # From the origin, or centred on the points where that is finer (never coarser).
    assert grid == expected or (any(grid.origin) and grid.exponent < expected.exponent)
    assert np.abs(grid.snap(pts)).max() <= grid.limit
    assert np.abs(grid.snap(-pts[:1])).max() <= grid.limit


@given(cs.grid_extents(), cs.grid_bits(), st.data())
def test_grid_round_trip_of_snapped_values(extent, bits, data):
    grid = Grid.for_extent(extent, bits=bits)
    k = np.array(data.draw(st.lists(cs.points(limit=grid.limit), min_size=1, max_size=6)))
    x = grid.to_float(k)
    assert (grid.snap(x) == k).all()
    assert (grid.to_float(grid.snap(x)) == x).all()


def test_grid_extent_zero():
    grid = Grid.for_extent(0.0)
    assert grid.step > 0 and grid.limit == 2**26
    assert (grid.snap(np.zeros((4, 3))) == 0).all()
    assert Grid.for_points(np.zeros((2, 3))) == grid
    assert Grid.for_points() == grid


@pytest.mark.parametrize("extent", [1e200, 2.0**500, 1e-310, 1e-300, 5e-324])
def test_grid_unsupported_extents_raise(extent):
    with pytest.raises(GridRangeError):
        Grid.for_extent(extent)


@pytest.mark.parametrize("extent", [math.nan, math.inf, -math.inf])
def test_grid_non_finite_extent_raises(extent):
    with pytest.raises(NonFiniteError):
        Grid.for_extent(extent)


@pytest.mark.parametrize("bits", [7, 29, -1])
def test_grid_bits_out_of_range_raise(bits):
    with pytest.raises(ValueError, match="bits"):
        Grid.for_extent(1.0, bits=bits)


@given(_grid_and_points(), st.sampled_from([math.nan, math.inf, -math.inf]), st.data())
def test_grid_non_finite_points_raise_with_row(gp, bad, data):
    grid, _, _, pts = gp
    row, col = data.draw(st.integers(0, len(pts) - 1)), data.draw(st.integers(0, 2))
    pts = pts.copy()
    pts[row, col] = bad
    with pytest.raises(NonFiniteError, match=f"row {row}"):
        grid.snap(pts)
    with pytest.raises(NonFiniteError, match=f"row {row}"):
        Grid.for_points(np.zeros((1, 3)), pts)


@given(_grid_and_points(), st.data())
def test_grid_points_beyond_range_raise(gp, data):
    grid, _, _, pts = gp
    row, col = data.draw(st.integers(0, len(pts) - 1)), data.draw(st.integers(0, 2))
    sign = data.draw(st.sampled_from([1.0, -1.0]))
    factor = data.draw(st.sampled_from([1.0, 2.0, 1e10, 1e300]))
    pts = pts.copy()
    # Beyond limit + 1/2 steps: rounds to a grid integer above the limit (or overflows).
    value = sign * (grid.limit + 1) * grid.step * factor
    assume(math.isfinite(value))
    pts[row, col] = value
    with pytest.raises(GridRangeError, match=f"point {row}"):
        grid.snap(pts)


# -- Perturbation ----------------------------------------------------------------------------

_TINY = Fraction(1, 2**300)


def _cayley_rotate(y, w, eps=_TINY) -> list[Fraction]:
    """``R y`` for the exact rational (Cayley) rotation ``R = (I - A)^-1 (I + A)``,
    ``A v = (eps/2) w x v``, about ``w`` by an angle ~ ``eps |w|``.

    ``R = I + eps K + eps^2 K^2 / 2 + O(eps^3)``, the same first terms as ``exp(eps K)``, so
    for a tiny ``eps`` the sign of ``x . R y`` is the sign the perturbation must give. An
    independent reference: it rotates, rather than sums the series the library sums.
    """
    a = [Fraction(eps) * wi / 2 for wi in w]

    def ax(v):
        return [a[1] * v[2] - a[2] * v[1], a[2] * v[0] - a[0] * v[2], a[0] * v[1] - a[1] * v[0]]

    t = [yi + ci for yi, ci in zip(_py(y), ax(_py(y)))]
    at = ax(t)
    aat = ax(at)
    k = 1 + sum(c * c for c in a)
    # (I - A)^-1 = I + (A + A^2) / (1 + |a|^2) for a cross-product matrix A.
    return [ti + (p + q) / k for ti, p, q in zip(t, at, aat)]


def _perturbed_ref(x, y, w) -> int:
    return _sign(sum(Fraction(xi) * ri for xi, ri in zip(_py(x), _cayley_rotate(y, w))))


@given(st.lists(cs.perturbation_pairs(), min_size=1, max_size=6))
def test_perturbation_dot_sign_is_the_limit_of_a_small_rotation(triples):
    """``sign(x . R_eps y)`` equals the sign for a tiny exact rotation, and is zero (reported
    as GridRangeError) only in the configurations where every term of the series vanishes."""
    for w, x, y in triples:
        pert = Perturbation(axis=w)
        expected = _perturbed_ref(x, y, w)
        plain = _sign(_dot(x, y))
        assert plain == 0 or expected == plain
        if expected == 0:
            with pytest.raises(ExactnessError, match="perturbation"):
                pert.dot_sign(x[None], y[None])
            continue
        assert pert.dot_sign(x[None], y[None]).tolist() == [expected]
        assert pert.dot_sign_matrix(x[None], y[None]).tolist() == [[expected]]
        assert pert.dot_sign_big(x[None], [int(c) * 2**70 for c in y]).tolist() == [expected]


@given(st.lists(cs.perturbation_pairs(), min_size=1, max_size=6), cs.perturbation_axes())
def test_perturbation_is_never_zero_off_the_axis(triples, axis):
    """Neither vector zero nor parallel to the axis => a non-zero sign (the case
    Perturbation.avoiding is meant to guarantee), consistent across batch and matrix forms."""
    pert = Perturbation(axis=axis)
    rows = [(x, y) for _, x, y in triples
            if any(_py(x)) and any(_py(y)) and not pert.parallel_to(_py(x))
            and not pert.parallel_to(_py(y))]
    assume(rows)
    X, Y = _stack([r[0] for r in rows]), _stack([r[1] for r in rows])
    signs = pert.dot_sign(X, Y)
    assert _is_sign_array(signs, (len(rows),))
    assert (signs != 0).all()
    assert signs.tolist() == [_perturbed_ref(x, y, axis) for x, y in rows]
    assert (np.diag(pert.dot_sign_matrix(X, Y)) == signs).all()


_axis_multiples = st.builds(
    lambda w, k: np.asarray(w, dtype=np.int64) * k,
    cs.perturbation_axes(),
    st.sampled_from([1, -1, 2, -3, 2**20]),
)


@given(st.lists(st.one_of(cs.directions(), cs.sum_points(), _axis_multiples), min_size=1,
                max_size=8))
def test_perturbation_avoiding_picks_an_axis_parallel_to_no_direction(dirs):
    D = _stack(dirs)
    pert = Perturbation.avoiding(D, D[:1])
    assert not any(pert.parallel_to(_py(d)) for d in D if any(_py(d)))


@pytest.mark.parametrize("k", [1, -1, -3, 2**20])
def test_perturbation_avoiding_rejects_both_orientations(k):
    """An input direction rules out its axis whichever way it points and however scaled."""
    first = [(3, 7, 19), (5, -11, 23), (-13, 17, 29), (31, 2, -37)]
    D = k * np.array(first, dtype=np.int64)
    pert = Perturbation.avoiding(D[:2], D[2:])
    assert not any(pert.parallel_to(list(w)) for w in first)
    assert not Perturbation.avoiding(D[:1]).parallel_to(list(first[0]))


@st.composite
def _second_order_ties(draw):
    """Points tied for direction ``d`` that the first perturbation term cannot separate: they
    differ by multiples of ``q = |d|^2 w - (d.w) d`` (orthogonal to ``d``, in span(d, w)), so
    only the second-order term decides. Plus points below the support plane."""
    w = list(draw(cs.perturbation_axes()))
    d = _py(draw(st.tuples(*[st.integers(-3, 3)] * 3)))
    q = [sum(c * c for c in d) * wi - sum(a * b for a, b in zip(d, w)) * di
         for wi, di in zip(w, d)]
    assume(any(q))
    base = _py(draw(cs.points(limit=2**20)))
    ts = draw(st.lists(st.integers(-5, 5), min_size=2, max_size=5, unique=True))
    P = [[b + t * qi for b, qi in zip(base, q)] for t in ts]
    for _ in range(draw(st.integers(0, 3))):
        k = draw(st.integers(1, 9))
        P.append([b - k * di + draw(st.integers(-2, 2)) * qi for b, di, qi in zip(base, d, q)])
    if not any(d):
        d = [0, 0, 1]
    P = [P[i] for i in draw(st.permutations(range(len(P))))]
    return np.asarray(P, np.int64), np.asarray([d], np.int64), tuple(w)


@batch_settings
@given(
    st.one_of(
        st.tuples(
            cs.point_clouds(min_size=2),
            st.lists(cs.directions(), min_size=1, max_size=4).map(_stack),
            cs.perturbation_axes(),
        ),
        _second_order_ties(),
    )
)
def test_perturbation_argmax_is_the_perturbed_maximiser(PDw):
    """Among exact ties, argmax returns a point maximising ``<R_eps p, d>``."""
    P, D, axis = PDw
    pert = Perturbation(axis=axis)
    mask = support_mask(P, D)
    best = pert.argmax(P, D, mask)
    assert best.shape == (len(D),)
    rotated = [_cayley_rotate(p, axis) for p in P]
    for j, d in enumerate(D):
        assert mask[j, best[j]]
        score = [sum(Fraction(di) * ri for di, ri in zip(_py(d), rotated[i]))
                 for i in np.nonzero(mask[j])[0]]
        chosen = sum(Fraction(di) * ri for di, ri in zip(_py(d), rotated[best[j]]))
        assert chosen == max(score)
