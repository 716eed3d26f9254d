"""Hypothesis strategies for the exact kernel (cspace.geometry.exact) and its callers.

Integer strategies draw grid coordinates the way the library produces them:

* snapped coordinates ``|k| <= 2**26`` (``Grid`` default ``bits=26``), with the extreme values
  ``0, +-1, +-(2**26 - 1), +-2**26`` drawn on purpose;
* Minkowski-sum coordinates, sums of two snapped ones, ``|k| <= 2**27``;
* "huge" integers up to ``2**61 - 1``, the largest magnitude the predicates accept (primitive
  facet normals, crosses of sums, reach ``~2**57``).

Degenerate families are built, not hoped for: hypothesis almost never draws four coplanar
points at random, so each family below constructs its degeneracy exactly (with Python ints)
and then lets hypothesis choose everything else. Every configuration is returned as a tuple
of int64 numpy arrays; the tests compute their own exact reference with Python ints.
"""

from __future__ import annotations

import numpy as np
from hypothesis import strategies as st

__all__ = [
    "LIMIT",
    "SUM_LIMIT",
    "HUGE_LIMIT",
    "grid_ints",
    "sum_ints",
    "huge_ints",
    "points",
    "sum_points",
    "huge_vectors",
    "point_clouds",
    "random_quads",
    "coplanar_quads",
    "axis_plane_quads",
    "collinear_quads",
    "duplicate_quads",
    "limit_quads",
    "near_coplanar_quads",
    "degenerate_quads",
    "any_quads",
    "coplanar_huge_triples",
    "near_coplanar_huge_triples",
    "random_triples_2d",
    "collinear_triples_2d",
    "duplicate_triples_2d",
    "limit_triples_2d",
    "near_collinear_triples_2d",
    "degenerate_triples_2d",
    "any_triples_2d",
    "random_vector_pairs",
    "orthogonal_pairs",
    "near_orthogonal_pairs",
    "any_vector_pairs",
    "directions",
    "parallel_pairs",
    "grid_extents",
    "grid_bits",
    "perturbation_axes",
    "perturbation_pairs",
]

#: Snapped coordinates of the default grid satisfy ``|k| <= LIMIT``.
LIMIT = 2**26
#: Coordinates of a Minkowski sum of two snapped points satisfy ``|k| <= SUM_LIMIT``.
SUM_LIMIT = 2**27
#: Largest magnitude accepted by the predicates (``_MAX_INT - 1`` in cspace.geometry.exact).
HUGE_LIMIT = 2**61 - 1


def _as_array(values) -> np.ndarray:
    return np.asarray(values, dtype=np.int64)


def _extremes(limit: int) -> list[int]:
    values = [0, 1, -1, limit, -limit, limit - 1, -(limit - 1), limit // 2, -(limit // 2)]
    return sorted({v for v in values if abs(v) <= limit})


def grid_ints(limit: int = LIMIT) -> st.SearchStrategy[int]:
    """Integers in ``[-limit, limit]``, with the extremes and their neighbours drawn often."""
    small = min(16, limit)
    return st.one_of(
        st.integers(-limit, limit),
        st.sampled_from(_extremes(limit)),
        st.integers(-small, small),
    )


#: Sums of two extreme snapped coordinates, e.g. ``2**26 + (2**26 - 1)``.
_SUM_EXTREMES = sorted({x + y for x in _extremes(LIMIT) for y in _extremes(LIMIT)})


def sum_ints() -> st.SearchStrategy[int]:
    """Coordinates of a Minkowski sum of two snapped points: ``|k| <= 2**27``.

    Any integer in range, or a sum of two extreme snapped values (``+-2**27``,
    ``+-(2**27 - 1)``, ``2**26 - 1``, ...). Kept flat: it is drawn thousands of times.
    """
    return st.one_of(
        st.integers(-SUM_LIMIT, SUM_LIMIT),
        st.sampled_from(_SUM_EXTREMES),
        st.integers(-16, 16),
    )


def huge_ints() -> st.SearchStrategy[int]:
    """Integers up to ``2**61 - 1`` in magnitude (the predicates' whole input range)."""
    return st.one_of(
        st.integers(-HUGE_LIMIT, HUGE_LIMIT),
        st.sampled_from(_extremes(HUGE_LIMIT) + [2**55, -(2**55), 2**53 + 1, -(2**53 + 1)]),
        sum_ints(),
    )


def _vectors(ints: st.SearchStrategy[int], dim: int) -> st.SearchStrategy[np.ndarray]:
    return st.tuples(*([ints] * dim)).map(_as_array)


def points(dim: int = 3, limit: int = LIMIT) -> st.SearchStrategy[np.ndarray]:
    """One snapped point, ``(dim,)`` int64 with ``|k| <= limit``."""
    return _vectors(grid_ints(limit), dim)


def sum_points(dim: int = 3) -> st.SearchStrategy[np.ndarray]:
    """One point of a Minkowski sum, ``(dim,)`` int64 with ``|k| <= 2**27``."""
    return _vectors(sum_ints(), dim)


def huge_vectors(dim: int = 3) -> st.SearchStrategy[np.ndarray]:
    """One integer vector with components up to ``2**61 - 1``."""
    return _vectors(huge_ints(), dim)


@st.composite
def point_clouds(draw, min_size: int = 1, max_size: int = 12, dim: int = 3) -> np.ndarray:
    """``(n, dim)`` int64 points of a Minkowski sum, often with duplicates and shared planes."""
    n = draw(st.integers(min_size, max_size))
    pts = [list(map(int, draw(sum_points(dim)))) for _ in range(n)]
    # Force ties: copy whole points or single coordinates between points.
    for _ in range(draw(st.integers(0, n))):
        i, j = draw(st.integers(0, n - 1)), draw(st.integers(0, n - 1))
        if draw(st.booleans()):
            pts[i] = list(pts[j])
        else:
            axis = draw(st.integers(0, dim - 1))
            pts[i][axis] = pts[j][axis]
    return np.asarray(pts, dtype=np.int64).reshape(n, dim)


def _permuted(draw, items: list) -> tuple:
    return tuple(draw(st.permutations(items)))


def _within(vec: list[int], limit: int) -> bool:
    return all(abs(x) <= limit for x in vec)


# -- 3D point quadruples (orient3d) ---------------------------------------------------------


@st.composite
def random_quads(draw) -> tuple[np.ndarray, ...]:
    """Four arbitrary Minkowski-sum points."""
    return tuple(draw(sum_points()) for _ in range(4))


@st.composite
def _plane_frame(draw):
    """``a, u, v, s, t`` with ``a + s*u + t*v`` etc. inside ``|k| <= 2**27``.

    The scale ``2**level`` of ``u, v`` trades against that of ``s, t`` so both large spans
    with small multipliers and small spans with large multipliers are drawn.
    """
    a = [int(x) for x in draw(points())]
    level = draw(st.integers(0, 24))
    span = st.one_of(st.integers(-(2**level), 2**level), st.sampled_from([2**level, -(2**level)]))
    u = [draw(span) for _ in range(3)]
    v = [draw(span) for _ in range(3)]
    mult = st.integers(-(2 ** (24 - level)), 2 ** (24 - level))
    return a, u, v, mult


def _affine(a, u, v, s, t):
    return [a[i] + s * u[i] + t * v[i] for i in range(3)]


@st.composite
def coplanar_quads(draw) -> tuple[np.ndarray, ...]:
    """Four coplanar points ``a, a+u, a+v, a + s*u + t*v`` (integer s, t), in random order."""
    a, u, v, mult = draw(_plane_frame())
    s, t = draw(mult), draw(mult)
    pts = [a, _affine(a, u, v, 1, 0), _affine(a, u, v, 0, 1), _affine(a, u, v, s, t)]
    return tuple(_as_array(p) for p in _permuted(draw, pts))


@st.composite
def axis_plane_quads(draw) -> tuple[np.ndarray, ...]:
    """Four points sharing one large coordinate (an axis-parallel plane), other coords huge."""
    axis = draw(st.integers(0, 2))
    level = draw(st.sampled_from([SUM_LIMIT, -SUM_LIMIT, SUM_LIMIT - 1, -LIMIT]) | sum_ints())
    pts = []
    for _ in range(4):
        p = [int(x) for x in draw(sum_points(2))]
        p.insert(axis, level)
        pts.append(p)
    return tuple(_as_array(p) for p in pts)


@st.composite
def collinear_quads(draw) -> tuple[np.ndarray, ...]:
    """Three collinear points ``a, a+s*u, a+t*u`` plus any fourth point, in random order."""
    a, u, _, mult = draw(_plane_frame())
    pts = [a, _affine(a, u, u, draw(mult), 0), _affine(a, u, u, draw(mult), 0)]
    pts.append([int(x) for x in draw(sum_points())])
    return tuple(_as_array(p) for p in _permuted(draw, pts))


@st.composite
def duplicate_quads(draw) -> tuple[np.ndarray, ...]:
    """Three arbitrary points and a copy of one of them, in random order."""
    pts = [[int(x) for x in draw(sum_points())] for _ in range(3)]
    pts.append(list(pts[draw(st.integers(0, 2))]))
    return tuple(_as_array(p) for p in _permuted(draw, pts))


@st.composite
def limit_quads(draw) -> tuple[np.ndarray, ...]:
    """Points at the grid's limit differing by one unit: coordinates in ``{L, L - 1}`` per axis.

    ``L`` is ``+-2**26`` (snapped points) or ``+-2**27`` (sums). All differences are 0/1
    vectors, so the determinant is tiny (often zero) against coordinates of ``2**26``.
    """
    limit = draw(st.sampled_from([LIMIT, SUM_LIMIT]))
    signs = [draw(st.sampled_from([1, -1])) for _ in range(3)]
    pts = [
        [signs[i] * (limit - draw(st.integers(0, 1))) for i in range(3)] for _ in range(4)
    ]
    return tuple(_as_array(p) for p in pts)


def _cross(u, v):
    return [u[1] * v[2] - u[2] * v[1], u[2] * v[0] - u[0] * v[2], u[0] * v[1] - u[1] * v[0]]


@st.composite
def near_coplanar_quads(draw) -> tuple[np.ndarray, ...]:
    """A coplanar quadruple with one coordinate of ``d`` moved by one unit off the plane.

    The unit move is along an axis ``i`` where the plane normal ``n = u x v`` has ``n_i != 0``,
    so ``orient3d(a, b, c, d) = +-sign(n_i)``: exactly non-zero, tiny against the permanent.
    """
    a, u, v, mult = draw(_plane_frame())
    n = _cross(u, v)
    axes = [i for i in range(3) if n[i] != 0]
    if not axes:
        # u, v parallel: replace v by a vector surely independent of u.
        v = [-u[1] or 1, u[0] or 1, u[2] + 1]
        n = _cross(u, v)
        axes = [i for i in range(3) if n[i] != 0]
    if not axes:
        u, v = [1, 0, 0], [0, 1, 0]
        n, axes = [0, 0, 1], [2]
    d = _affine(a, u, v, draw(mult), draw(mult))
    i = draw(st.sampled_from(axes))
    step = draw(st.sampled_from([1, -1]))
    if abs(d[i] + step) > SUM_LIMIT:
        step = -step
    d[i] += step
    pts = [a, _affine(a, u, v, 1, 0), _affine(a, u, v, 0, 1)]
    assert all(_within(p, SUM_LIMIT) for p in pts + [d])
    return tuple(_as_array(p) for p in pts + [d])


def degenerate_quads() -> st.SearchStrategy[tuple[np.ndarray, ...]]:
    """Exactly coplanar quadruples (orient3d must return 0), of every family above."""
    return st.one_of(coplanar_quads(), axis_plane_quads(), collinear_quads(), duplicate_quads())


def any_quads() -> st.SearchStrategy[tuple[np.ndarray, ...]]:
    """Random, degenerate, limit and nearly-degenerate quadruples mixed."""
    return st.one_of(random_quads(), degenerate_quads(), limit_quads(), near_coplanar_quads())


# -- huge vector triples (triple_sign on the predicates' full range) -----------------------


@st.composite
def coplanar_huge_triples(draw) -> tuple[np.ndarray, ...]:
    """``u, v, s*u + t*v`` with components up to ``2**61 - 1``: triple product exactly 0."""
    level = draw(st.integers(0, 58))
    span = st.integers(-(2**level), 2**level)
    u = [draw(span) for _ in range(3)]
    v = [draw(span) for _ in range(3)]
    mult = st.integers(-(2 ** (59 - level)), 2 ** (59 - level))
    w = _affine([0, 0, 0], u, v, draw(mult), draw(mult))
    return tuple(_as_array(x) for x in _permuted(draw, [u, v, w]))


@st.composite
def near_coplanar_huge_triples(draw) -> tuple[np.ndarray, ...]:
    """``u, v, s*u + t*v + e_i`` with ``(u x v)_i != 0``: triple product ``+-(u x v)_i``."""
    u, v, w = (list(map(int, x)) for x in draw(coplanar_huge_triples()))
    n = _cross(u, v)
    axes = [i for i in range(3) if n[i] != 0]
    if not axes:
        # u, v parallel (or zero): use a fixed independent pair, w in their plane.
        u, v, w = [2**60, 1, 0], [3, 2**59, 5], [0, 0, 0]
        n = _cross(u, v)
        axes = [i for i in range(3) if n[i] != 0]
    i = draw(st.sampled_from(axes))
    w[i] += 1 if w[i] < HUGE_LIMIT else -1
    return tuple(_as_array(x) for x in (u, v, w))


# -- 2D point triples (orient2d) -------------------------------------------------------------


@st.composite
def random_triples_2d(draw) -> tuple[np.ndarray, ...]:
    return tuple(draw(sum_points(2)) for _ in range(3))


@st.composite
def _line_frame(draw):
    a = [int(x) for x in draw(points(2))]
    level = draw(st.integers(0, 24))
    span = st.one_of(st.integers(-(2**level), 2**level), st.sampled_from([2**level, -(2**level)]))
    u = [draw(span) for _ in range(2)]
    mult = st.integers(-(2 ** (24 - level)), 2 ** (24 - level))
    return a, u, mult


@st.composite
def collinear_triples_2d(draw) -> tuple[np.ndarray, ...]:
    """``a, a + s*u, a + t*u`` in random order: orient2d exactly 0."""
    a, u, mult = draw(_line_frame())
    s, t = draw(mult), draw(mult)
    pts = [a, [a[0] + s * u[0], a[1] + s * u[1]], [a[0] + t * u[0], a[1] + t * u[1]]]
    return tuple(_as_array(p) for p in _permuted(draw, pts))


@st.composite
def duplicate_triples_2d(draw) -> tuple[np.ndarray, ...]:
    pts = [[int(x) for x in draw(sum_points(2))] for _ in range(2)]
    pts.append(list(pts[draw(st.integers(0, 1))]))
    return tuple(_as_array(p) for p in _permuted(draw, pts))


@st.composite
def limit_triples_2d(draw) -> tuple[np.ndarray, ...]:
    limit = draw(st.sampled_from([LIMIT, SUM_LIMIT]))
    signs = [draw(st.sampled_from([1, -1])) for _ in range(2)]
    return tuple(
        _as_array([signs[i] * (limit - draw(st.integers(0, 1))) for i in range(2)])
        for _ in range(3)
    )


@st.composite
def near_collinear_triples_2d(draw) -> tuple[np.ndarray, ...]:
    """Collinear ``a, a+u, a+t*u`` with ``c`` moved one unit along an axis ``i`` with
    ``u_(1-i) != 0``: orient2d is ``+-1`` times ``sign(u_(1-i))``, never 0."""
    a, u, mult = draw(_line_frame())
    if u == [0, 0]:
        u = [1, draw(st.integers(-5, 5))]
    t = draw(mult)
    c = [a[0] + t * u[0], a[1] + t * u[1]]
    i = draw(st.sampled_from([i for i in range(2) if u[1 - i] != 0]))
    step = draw(st.sampled_from([1, -1]))
    if abs(c[i] + step) > SUM_LIMIT:
        step = -step
    c[i] += step
    return _as_array(a), _as_array([a[0] + u[0], a[1] + u[1]]), _as_array(c)


def degenerate_triples_2d() -> st.SearchStrategy[tuple[np.ndarray, ...]]:
    return st.one_of(collinear_triples_2d(), duplicate_triples_2d())


def any_triples_2d() -> st.SearchStrategy[tuple[np.ndarray, ...]]:
    return st.one_of(
        random_triples_2d(),
        degenerate_triples_2d(),
        limit_triples_2d(),
        near_collinear_triples_2d(),
    )


# -- vector pairs (dot_sign) -----------------------------------------------------------------


@st.composite
def random_vector_pairs(draw) -> tuple[np.ndarray, np.ndarray]:
    vec = st.one_of(sum_points(), huge_vectors())
    return draw(vec), draw(vec)


@st.composite
def orthogonal_pairs(draw) -> tuple[np.ndarray, np.ndarray]:
    """``u`` and ``v = w x u`` (so ``u . v == 0`` exactly), components up to ``2**61``."""
    u = [int(x) for x in draw(sum_points())]
    w = [int(x) for x in draw(_vectors(st.integers(-(2**32), 2**32), 3))]
    v = _cross(w, u)
    pair = [u, v]
    if draw(st.booleans()):
        pair.reverse()
    return _as_array(pair[0]), _as_array(pair[1])


@st.composite
def near_orthogonal_pairs(draw) -> tuple[np.ndarray, np.ndarray]:
    """An orthogonal pair with one component of ``v`` moved by one: ``u . v = +-u_i != 0``."""
    u, v = (list(map(int, x)) for x in draw(orthogonal_pairs()))
    axes = [i for i in range(3) if u[i] != 0]
    if not axes:
        u, v, axes = [1, 0, 0], [0, v[1], v[2]], [0]
    i = draw(st.sampled_from(axes))
    v[i] += draw(st.sampled_from([1, -1]))
    return _as_array(u), _as_array(v)


def any_vector_pairs() -> st.SearchStrategy[tuple[np.ndarray, np.ndarray]]:
    return st.one_of(random_vector_pairs(), orthogonal_pairs(), near_orthogonal_pairs())


def directions() -> st.SearchStrategy[np.ndarray]:
    """Integer directions: small, axis-aligned, and huge (``~2**55``, like primitive facet
    normals of a Minkowski sum)."""
    huge = st.integers(-(2**56), 2**56)
    return st.one_of(
        _vectors(st.integers(-3, 3), 3),
        st.sampled_from(
            [[0, 0, 1], [0, 0, -1], [1, 0, 0], [0, -1, 0], [1, 1, 0], [1, -1, 1]]
        ).map(_as_array),
        _vectors(huge, 3),
        _vectors(st.sampled_from([0, 2**55, -(2**55), 2**55 + 1, 2**55 - 1]), 3),
    )


@st.composite
def parallel_pairs(draw) -> tuple[np.ndarray, np.ndarray]:
    """Two integer vectors ``m*p`` and ``n*p`` (same or opposite direction, or one zero)."""
    p = [int(x) for x in draw(_vectors(st.integers(-(2**20), 2**20), 3))]
    scale = st.integers(-(2**30), 2**30)
    m, n = draw(scale), draw(scale)
    return _as_array([m * x for x in p]), _as_array([n * x for x in p])


# -- grids -----------------------------------------------------------------------------------


def grid_bits() -> st.SearchStrategy[int]:
    """Valid ``bits`` for ``Grid.for_extent``, the default 26 drawn most."""
    return st.one_of(st.just(26), st.integers(8, 28))


def grid_extents() -> st.SearchStrategy[float]:
    """Scene extents a grid supports: zero, and positive floats from ~1e-290 to ~1e150."""
    return st.one_of(
        st.just(0.0),
        st.floats(min_value=2.0**-960, max_value=2.0**499, allow_nan=False, allow_infinity=False),
        st.sampled_from([1.0, 0.5, 3.0, 1e-3, 1e3, 2.0**26, 2.0**499, 2.0**-960]),
    )


# -- symbolic perturbation (Perturbation: infinitesimal rotation about an integer axis) ------

#: Axes Perturbation.avoiding chooses from, plus a coordinate axis and a diagonal.
_PERTURBATION_AXES = [(3, 7, 19), (5, -11, 23), (-13, 17, 29), (31, 2, -37), (0, 0, 1), (1, 1, 1)]


def perturbation_axes() -> st.SearchStrategy[tuple[int, int, int]]:
    return st.sampled_from(_PERTURBATION_AXES)


def _scaled(v, k):
    return [k * x for x in v]


@st.composite
def perturbation_pairs(draw):
    """``(axis, x, y)`` exercising each term of the perturbed sign ``x . R_eps y``.

    Families: random pairs (first term decides), orthogonal pairs (second term), ``y`` in
    ``span(x, w)`` orthogonal to ``x`` (third term), and the two configurations where every
    term vanishes (``x`` along the axis with ``y`` orthogonal to it, or ``y`` along the axis
    with ``x`` orthogonal to it) or a zero vector.
    """
    w = list(draw(perturbation_axes()))
    small = _vectors(st.integers(-(2**20), 2**20), 3).map(lambda a: [int(c) for c in a])
    x = draw(small)
    kind = draw(
        st.sampled_from(["random", "orthogonal", "second_order", "x_on_axis", "y_on_axis", "zero"])
    )
    if kind == "random":
        y = [int(c) for c in draw(sum_points())]
    elif kind == "orthogonal":
        y = _cross(draw(small), x)
    elif kind == "second_order":
        xw = sum(a * b for a, b in zip(x, w))
        xx = sum(a * a for a in x)
        y = [xx * wi - xw * xi for wi, xi in zip(w, x)]
    elif kind == "x_on_axis":
        x = _scaled(w, draw(st.integers(-(2**20), 2**20)))
        y = _cross(w, draw(small))
    elif kind == "y_on_axis":
        y = _scaled(w, draw(st.integers(-(2**20), 2**20)))
        x = _cross(w, draw(small))
    else:
        y = [0, 0, 0]
    if draw(st.booleans()):
        x, y = y, x
    return tuple(w), _as_array(x), _as_array(y)
