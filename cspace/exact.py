"""Exact geometric predicates on integer grid coordinates, vectorised over numpy arrays.

Every combinatorial decision in cspace (a sign, a side, an order) comes from here.

Inputs are snapped to a dyadic grid (:class:`Grid`): a coordinate ``x`` becomes the integer
``k = round(x / step)`` with ``step = 2**exponent``, stored as int64. Sums and differences of
grid integers are exact, and every predicate below returns the exact sign of a polynomial in
those integers:

1. a floating-point filter evaluates the polynomial in float64 together with a rigorous bound
   on its rounding error (a semi-static bound: a fixed multiple of the permanent, i.e. the
   same polynomial on absolute values); where ``|value| > bound`` the float sign is exact;
2. the rows the filter cannot decide (in practice exact zeros, see design notes section 7) are
   re-evaluated with Python integers, which never round.

No tolerance decides anything here. Signs are returned as int8 arrays in {-1, 0, 1}.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Iterable

import numpy as np

from .errors import ExactnessError, GridRangeError, InvalidArgumentError, NonFiniteError

__all__ = [
    "Grid",
    "triple_sign",
    "orient3d",
    "orient2d",
    "dot_sign",
    "dot_sign_matrix",
    "support_mask",
    "plane_side_matrix",
    "cross",
    "primitive",
    "Perturbation",
]

# Unit roundoff of float64 (round to nearest).
_EPS = 2.0**-53
# Error bound factor for polynomials of degree <= 3 with at most 6 terms, evaluated in float64
# from int64 inputs (each conversion may round once when |k| >= 2**53). The exact requirement
# is about 7 * eps * permanent; 16 leaves room for the rounding of the permanent itself.
_FILTER = 16.0 * _EPS
# Absolute slack covering underflow of scaled queries (ldexp to subnormals).
_TINY = 2.0**-1000


def _dyadic(values: Iterable[float]) -> tuple[list[int], int]:
    """Floats as integers times one common power of two: ``v_i = ints[i] * 2**exp``."""
    ints, exps = [], []
    for v in values:
        m, x = math.frexp(float(v))
        ints.append(int(m * 9007199254740992.0))  # m * 2**53 is an exact integer
        exps.append(x - 53)
    lo = min(exps)
    return [i << (x - lo) for i, x in zip(ints, exps)], lo


# Largest integer magnitude the predicates accept: differences of two such values, and
# their products of three, stay exact in int64 / finite in float64.
_MAX_INT = 2**61

# Sums of two snapped coordinates must stay well inside int64 and be exact as float64.
_MAX_BITS = 28
# Coordinates beyond this magnitude are refused: squared distances would overflow float64.
_MAX_EXTENT_EXP = 500


@dataclass(frozen=True)
class Grid:
    """A dyadic snapping grid: coordinates become integer multiples of ``step = 2**exponent``.

    A grid made by :meth:`for_extent` from a scene's largest absolute coordinate ``L`` has
    ``step = 2**(floor(log2 L) + 1 - bits)`` (the smallest power of two above ``L``, over
    ``2**bits``), so every snapped coordinate ``k`` satisfies
    ``|k| <= 2**bits``. With the default ``bits=26`` the sum of two snapped points and every
    predicate on such sums is exact (orient3d needs about 87 bits, done in the exact path).

    Snapping moves each coordinate by at most :attr:`error_bound` (= step / 2) and each point
    by at most :attr:`point_error_bound` (= sqrt(3) * step / 2) in Euclidean distance.

    Attributes
    ----------
    exponent : int
        The grid step is ``2.0 ** exponent`` scene length units.
    bits : int
        Snapped coordinates satisfy ``|k| <= 2**bits``.
    """

    exponent: int
    bits: int = 26

    @classmethod
    def for_extent(cls, extent: float, *, bits: int = 26) -> "Grid":
        """Grid for a scene whose coordinates satisfy ``|x| <= extent``."""
        if not 8 <= bits <= _MAX_BITS:
            raise InvalidArgumentError(f"bits must be in [8, {_MAX_BITS}], got {bits}")
        extent = float(extent)
        if not math.isfinite(extent):
            raise NonFiniteError(f"grid extent is not finite: {extent}")
        if extent < 0.0:
            raise InvalidArgumentError(f"grid extent must be >= 0, got {extent}")
        if extent <= 0.0:
            return cls(exponent=-bits, bits=bits)
        # frexp: extent = m * 2**e with 0.5 <= m < 1, hence extent < 2**e.
        _, e = math.frexp(extent)
        if e > _MAX_EXTENT_EXP:
            raise GridRangeError(
                f"coordinates up to {extent:.3g} exceed the supported extent 2**{_MAX_EXTENT_EXP} "
                "(squared distances would overflow float64); rescale the scene"
            )
        if e - bits < -1000:
            raise GridRangeError(
                f"coordinates are all below {extent:.3g}: the grid step would be subnormal; "
                "rescale the scene"
            )
        return cls(exponent=e - bits, bits=bits)

    @classmethod
    def for_points(cls, *arrays: np.ndarray, bits: int = 26) -> "Grid":
        """Grid for the union of several ``(n, 3)`` float arrays (their largest |coordinate|)."""
        extent = 0.0
        for i, a in enumerate(arrays):
            a = np.asarray(a, dtype=np.float64)
            if a.size == 0:
                continue
            _check_finite(a, f"array {i}")
            extent = max(extent, float(np.abs(a).max()))
        return cls.for_extent(extent, bits=bits)

    @property
    def step(self) -> float:
        """Grid step in scene length units."""
        return math.ldexp(1.0, self.exponent)

    @property
    def error_bound(self) -> float:
        """Largest change of one coordinate made by snapping (half a step)."""
        return math.ldexp(1.0, self.exponent - 1)

    @property
    def point_error_bound(self) -> float:
        """Largest Euclidean displacement of one point made by snapping."""
        return math.sqrt(3.0) * self.error_bound

    @property
    def limit(self) -> int:
        """Snapped coordinates satisfy ``|k| <= limit``."""
        return 1 << self.bits

    def snap(self, points: np.ndarray) -> np.ndarray:
        """Snap float coordinates to grid integers (round half to even).

        Parameters
        ----------
        points : (..., 3) float64
            Coordinates in scene units.

        Returns
        -------
        ints : (..., 3) int64
            ``round(points / step)``; ``ints * step`` are the snapped coordinates.

        Raises
        ------
        NonFiniteError
            If a coordinate is NaN or infinite (the message gives the first bad row).
        GridRangeError
            If a coordinate is beyond ``limit * step``: the grid was made for a smaller scene.
        """
        points = np.asarray(points, dtype=np.float64)
        _check_finite(points, "points")
        # Division by a power of two is exact (no subnormals: see for_extent), rint is exact.
        with np.errstate(over="ignore"):  # overflow to inf is reported just below
            k = np.rint(np.ldexp(points, -self.exponent))
        if k.size and np.abs(k).max() > self.limit:
            flat = np.abs(k).reshape(-1, k.shape[-1]) if k.ndim > 1 else np.abs(k)[None]
            row = int(np.nonzero(flat.max(axis=-1) > self.limit)[0][0])
            raise GridRangeError(
                f"point {row} has a coordinate beyond the grid's range +-{self.limit * self.step:.6g}; "
                "build the grid from every object of the scene (Grid.for_points)"
            )
        return k.astype(np.int64)

    def to_float(self, ints: np.ndarray) -> np.ndarray:
        """Scene coordinates of grid integers (exact while ``|k| < 2**53``)."""
        return np.ldexp(np.asarray(ints, dtype=np.int64).astype(np.float64), self.exponent)


def _check_finite(a: np.ndarray, what: str) -> None:
    finite = np.isfinite(a)
    if not finite.all():
        bad = np.argwhere(~finite)[0]
        where = f"row {int(bad[0])}" if a.ndim > 1 else f"index {int(bad[0])}"
        raise NonFiniteError(f"{what}: non-finite coordinate {a[tuple(bad)]} at {where}")


def _ints(x) -> np.ndarray:
    a = np.asarray(x)
    if a.dtype.kind not in "iu":
        raise TypeError(f"exact predicates take integer grid coordinates, got dtype {a.dtype}")
    # Check the range before any cast or abs: abs(int64 min) and uint64 -> int64 both wrap.
    if a.size and (int(a.max()) >= _MAX_INT or int(a.min()) <= -_MAX_INT):
        raise GridRangeError(f"integer coordinate beyond +-2**61: range [{int(a.min())}, {int(a.max())}]")
    return a.astype(np.int64, copy=False)


def _sign_of(values: np.ndarray) -> np.ndarray:
    return (values > 0).astype(np.int8) - (values < 0).astype(np.int8)


def _det3(u, v, w):
    # Works on float64 and on object (Python int) arrays alike.
    return (
        u[..., 0] * (v[..., 1] * w[..., 2] - v[..., 2] * w[..., 1])
        + u[..., 1] * (v[..., 2] * w[..., 0] - v[..., 0] * w[..., 2])
        + u[..., 2] * (v[..., 0] * w[..., 1] - v[..., 1] * w[..., 0])
    )


def _perm3(u, v, w):
    u, v, w = np.abs(u), np.abs(v), np.abs(w)
    return (
        u[..., 0] * (v[..., 1] * w[..., 2] + v[..., 2] * w[..., 1])
        + u[..., 1] * (v[..., 2] * w[..., 0] + v[..., 0] * w[..., 2])
        + u[..., 2] * (v[..., 0] * w[..., 1] + v[..., 1] * w[..., 0])
    )


def _filtered(poly, perm, args: tuple[np.ndarray, ...]) -> np.ndarray:
    """Exact sign of ``poly(*args)`` on int64 arrays: float filter, then Python ints."""
    shape = np.broadcast_shapes(*(a.shape[:-1] for a in args))
    scalar = shape == ()
    if scalar:
        # Boolean indexing below needs at least one batch dimension.
        shape = (1,)
    args = tuple(np.broadcast_to(a, shape + a.shape[-1:]) for a in args)
    fargs = tuple(a.astype(np.float64) for a in args)
    value = poly(*fargs)
    permanent = perm(*fargs)
    bound = _FILTER * permanent
    sign = _sign_of(value)
    # A zero permanent means every term is zero: the value is exactly 0, no fallback needed.
    unsure = ~(np.abs(value) > bound) & (permanent > 0)
    sign[permanent == 0] = 0
    if unsure.any():
        exact = poly(*(a[unsure].astype(object) for a in args))
        sign[unsure] = _sign_of(np.asarray(exact, dtype=object)).astype(np.int8)
    return sign[0] if scalar else sign


def triple_sign(u, v, w) -> np.ndarray:
    """Sign of the triple product ``u . (v x w) = det[u; v; w]`` of integer vectors.

    Parameters
    ----------
    u, v, w : (..., 3) int
        Integer vectors (typically differences of grid points); broadcast together.

    Returns
    -------
    sign : (...) int8 in {-1, 0, 1}
    """
    return _filtered(_det3, _perm3, (_ints(u), _ints(v), _ints(w)))


def orient3d(a, b, c, d) -> np.ndarray:
    """Side of point ``d`` against the plane through ``a, b, c``.

    Returns ``sign(det[b - a; c - a; d - a])``: +1 when ``d`` lies on the side the normal
    ``(b - a) x (c - a)`` points to (``a, b, c`` counter-clockwise seen from ``d``), -1 on the
    other side, 0 when the four points are coplanar.

    Parameters
    ----------
    a, b, c, d : (..., 3) int
        Grid coordinates; broadcast together.

    Returns
    -------
    sign : (...) int8
    """
    a = _ints(a)
    return triple_sign(_ints(b) - a, _ints(c) - a, _ints(d) - a)


def _det2(u, v):
    return u[..., 0] * v[..., 1] - u[..., 1] * v[..., 0]


def _perm2(u, v):
    return np.abs(u[..., 0] * v[..., 1]) + np.abs(u[..., 1] * v[..., 0])


def orient2d(a, b, c) -> np.ndarray:
    """Sign of ``(b - a) x (c - a)`` for 2D integer points: +1 when ``a, b, c`` turn left.

    Parameters
    ----------
    a, b, c : (..., 2) int

    Returns
    -------
    sign : (...) int8
    """
    a = _ints(a)
    return _filtered(_det2, _perm2, (_ints(b) - a, _ints(c) - a))


def _dot(u, v):
    return u[..., 0] * v[..., 0] + u[..., 1] * v[..., 1] + u[..., 2] * v[..., 2]


def _absdot(u, v):
    return _dot(np.abs(u), np.abs(v))


def dot_sign(u, v) -> np.ndarray:
    """Sign of the dot product ``u . v`` of integer vectors, ``(..., 3)`` broadcast together."""
    return _filtered(_dot, _absdot, (_ints(u), _ints(v)))


def dot_sign_matrix(U, V) -> np.ndarray:
    """Exact signs of all dot products ``U[i] . V[j]``, an ``(n, m)`` int8 matrix.

    The float filter is one BLAS product; only the entries it cannot decide are recomputed
    with Python integers.

    Parameters
    ----------
    U : (n, 3) int
    V : (m, 3) int

    Returns
    -------
    sign : (n, m) int8
    """
    U, V = _ints(U), _ints(V)
    Uf, Vf = U.astype(np.float64), V.astype(np.float64)
    value = Uf @ Vf.T
    bound = _FILTER * (np.abs(Uf) @ np.abs(Vf).T)
    sign = _sign_of(value)
    i, j = np.nonzero(~(np.abs(value) > bound))
    if i.size:
        exact = _dot(U[i].astype(object), V[j].astype(object))
        sign[i, j] = _sign_of(np.asarray(exact, dtype=object)).astype(np.int8)
    return sign


def support_mask(points, directions) -> np.ndarray:
    """Which points attain ``max_i <p_i, d>`` for each direction, decided exactly.

    Parameters
    ----------
    points : (n, 3) int
        Grid coordinates.
    directions : (m, 3) int
        Integer directions (e.g. primitive facet normals).

    Returns
    -------
    mask : (m, n) bool
        ``mask[j, i]`` is True iff point ``i`` maximises the dot product with direction ``j``
        (ties give several True entries: the support face is an edge or a facet).
    """
    P, D = _ints(points), _ints(directions)
    if not len(P) or not len(D):
        return np.zeros((len(D), len(P)), dtype=bool)
    Pf, Df = P.astype(np.float64), D.astype(np.float64)
    value = Df @ Pf.T
    err = _FILTER * (np.abs(Df) @ np.abs(Pf).T)
    top = value.argmax(axis=1)
    rows = np.arange(len(D))
    # Point i can tie or beat the float maximiser only if value_i + err_i >= value_top - err_top.
    mask = value + err >= (value[rows, top] - err[rows, top])[:, None]
    unsure = np.nonzero(mask.sum(axis=1) > 1)[0]
    if unsure.size:
        Po = P.astype(object)
        for j in unsure:
            cand = np.nonzero(mask[j])[0]
            exact = _dot(Po[cand], D[j].astype(object))
            best = max(exact)
            mask[j, cand] = np.asarray([e == best for e in exact], dtype=bool)
    return mask


def plane_side_matrix(points, plane_points, normals, *, chunk: int = 1 << 22) -> np.ndarray:
    """Exact side of every point against every plane: ``sign((p_i - q_j) . n_j)``.

    Parameters
    ----------
    points : (n, 3) int
        Grid coordinates of the points.
    plane_points : (m, 3) int
        One grid point on each plane.
    normals : (m, 3) int
        Integer normals of the planes (need not be primitive).
    chunk : int, default 2**22
        Largest number of matrix entries evaluated at once (bounds memory).

    Returns
    -------
    side : (n, m) int8
        +1 where point ``i`` lies on the side normal ``j`` points to, 0 on the plane.
    """
    P, Q, N = _ints(points), _ints(plane_points), _ints(normals)
    out = np.zeros((len(P), len(N)), dtype=np.int8)
    if not len(P) or not len(N):
        return out
    Nf, Pf = N.astype(np.float64), P.astype(np.float64)
    qn = _dot(Q.astype(np.float64), Nf)
    qn_err = _absdot(Q.astype(np.float64), Nf)
    absN = np.abs(Nf)
    step = max(1, chunk // len(N))
    for lo in range(0, len(P), step):
        Pc, Pcf = P[lo : lo + step], Pf[lo : lo + step]
        value = Pcf @ Nf.T - qn
        bound = _FILTER * (np.abs(Pcf) @ absN.T + qn_err)
        sign = _sign_of(value)
        i, j = np.nonzero(~(np.abs(value) > bound))
        if i.size:
            exact = _dot((Pc[i] - Q[j]).astype(object), N[j].astype(object))
            sign[i, j] = _sign_of(np.asarray(exact, dtype=object)).astype(np.int8)
        out[lo : lo + step] = sign
    return out


def cross(u, v) -> np.ndarray:
    """Exact cross product of int64 vectors ``(..., 3)``; raises if it could overflow int64."""
    u, v = _ints(u), _ints(v)
    if u.size and v.size:
        bound = 2.0 * float(np.abs(u).max()) * float(np.abs(v).max())
        # Results must stay valid inputs of the predicates (|k| < 2**61).
        if bound >= float(_MAX_INT):
            raise GridRangeError("cross product of these integer vectors could exceed 2**61")
    return np.cross(u, v)


def primitive(v) -> np.ndarray:
    """Divide integer vectors by the gcd of their components: a canonical key per direction.

    Two non-zero integer vectors point the same way iff their primitive forms are equal.
    Zero vectors stay zero.
    """
    v = _ints(v)
    g = np.gcd.reduce(v, axis=-1, keepdims=True)
    g[g == 0] = 1
    return v // g


def _cross_obj(u, v):
    """Cross product on object (Python int) arrays, ``(..., 3)``; never rounds."""
    return np.stack(
        [
            u[..., 1] * v[..., 2] - u[..., 2] * v[..., 1],
            u[..., 2] * v[..., 0] - u[..., 0] * v[..., 2],
            u[..., 0] * v[..., 1] - u[..., 1] * v[..., 0],
        ],
        axis=-1,
    )


# Candidate rotation axes for the symbolic perturbation: small, primitive, not on any
# coordinate plane or diagonal, so that axis-aligned and symmetric inputs never hit them.
_AXES = ((3, 7, 19), (5, -11, 23), (-13, 17, 29), (31, 2, -37), (41, -43, 6), (47, 53, -59))


@dataclass(frozen=True)
class Perturbation:
    """One consistent symbolic perturbation: an infinitesimal rotation of the second operand.

    ``R_eps = exp(eps K)`` with ``K x = w x x`` for an integer axis ``w``. A predicate
    ``sign(x . R_eps y)`` (``x`` fixed, ``y`` rotating) is the sign of the first non-zero
    term of ``x.y, x.(w x y), x.(w x (w x y))`` (positive factors 1, eps, eps^2/2 dropped):
    it is never zero when neither ``x`` nor ``y`` is zero or parallel to ``w`` (the three
    vectors ``y, w x y, w x (w x y)`` then span space, and ``x`` is not orthogonal to all).
    Build it with :meth:`avoiding` over every fixed and every rotating direction used.

    Used so that every tie between directions of two polytopes (parallel facets, an edge
    parallel to a facet, Gauss arcs through each other's vertices) is broken the same way by
    every predicate: the result is the exact limit of the generic configuration.
    """

    axis: tuple[int, int, int]

    @classmethod
    def avoiding(cls, *directions: np.ndarray) -> "Perturbation":
        """A perturbation whose axis is parallel to none of the given integer directions."""
        prims = [primitive(np.asarray(d, dtype=np.int64).reshape(-1, 3)) for d in directions]
        for w in _AXES:
            wv = np.array(w, dtype=np.int64)
            if not any(((p == wv).all(axis=1) | (p == -wv).all(axis=1)).any() for p in prims):
                return cls(axis=w)
        raise GridRangeError("no perturbation axis avoids every input direction")  # pragma: no cover

    def parallel_to(self, y) -> bool:
        """Whether the (Python int) vector ``y`` is parallel to the axis (exact)."""
        w = self.axis
        c = (w[1] * y[2] - w[2] * y[1], w[2] * y[0] - w[0] * y[2], w[0] * y[1] - w[1] * y[0])
        return c == (0, 0, 0)

    def _resolve(self, x: np.ndarray, y: np.ndarray) -> np.ndarray:
        """Perturbed signs for rows whose plain dot product is zero (object arithmetic)."""
        xo, yo = x.astype(object), y.astype(object)
        wo = np.broadcast_to(np.array(self.axis, dtype=object), yo.shape)
        wy = _cross_obj(wo, yo)
        s = _sign_of(np.asarray(_dot(xo, wy), dtype=object)).astype(np.int8)
        z = s == 0
        if z.any():
            wwy = _cross_obj(wo[z], wy[z])
            s[z] = _sign_of(np.asarray(_dot(xo[z], wwy), dtype=object)).astype(np.int8)
        if (s == 0).any():
            raise ExactnessError("perturbation failed: a zero vector or a direction parallel to its axis")
        return s

    def dot_sign(self, x, y) -> np.ndarray:
        """``sign(x . R_eps y)`` for ``(k, 3)`` integer rows (broadcast); never zero."""
        x, y = _ints(x), _ints(y)
        shape = np.broadcast_shapes(x.shape, y.shape)
        x, y = np.broadcast_to(x, shape).reshape(-1, 3), np.broadcast_to(y, shape).reshape(-1, 3)
        s = dot_sign(x, y).reshape(-1)
        z = s == 0
        if z.any():
            s[z] = self._resolve(x[z], y[z])
        return s.reshape(shape[:-1])

    def dot_sign_matrix(self, X, Y) -> np.ndarray:
        """``sign(X[i] . R_eps Y[j])`` as an ``(n, m)`` int8 matrix; never zero."""
        X, Y = _ints(X), _ints(Y)
        s = dot_sign_matrix(X, Y)
        i, j = np.nonzero(s == 0)
        if i.size:
            s[i, j] = self._resolve(X[i], Y[j])
        return s

    def dot_sign_big(self, x: np.ndarray, y) -> np.ndarray:
        """``sign(x[i] . R_eps y)`` for one vector ``y`` of arbitrary size (Python ints)."""
        x = _ints(x)
        yo = np.array([int(c) for c in y], dtype=object)
        s = _sign_of(np.asarray(_dot(x.astype(object), yo), dtype=object)).astype(np.int8)
        z = s == 0
        if z.any():
            s[z] = self._resolve(x[z], np.broadcast_to(yo, (int(z.sum()), 3)))
        return s

    def argmax(self, points, directions, mask: np.ndarray) -> np.ndarray:
        """For each direction, the point maximising ``<R_eps p, d>`` among ``mask``'s exact ties.

        ``mask`` is :func:`support_mask` ``(points, directions)``; rows with a single True
        are returned as is, tied rows are broken by the perturbation's second and third terms.
        """
        P, D = _ints(points), _ints(directions)
        best = mask.argmax(axis=1)
        tied = np.nonzero(mask.sum(axis=1) > 1)[0]
        if tied.size:
            rows, cand = np.nonzero(mask[tied])
            Do, Po = D[tied[rows]].astype(object), P[cand].astype(object)
            w = np.broadcast_to(np.array(self.axis, dtype=object), Po.shape)
            wp = _cross_obj(w, Po)
            k1 = _dot(Do, wp)
            k2 = _dot(Do, _cross_obj(w, wp))
            order = sorted(range(len(rows)), key=lambda t: (rows[t], k1[t], k2[t]))
            # The last candidate of each row in (row, k1, k2) order is its maximiser.
            last = {rows[t]: cand[t] for t in order}
            for r, c in last.items():
                best[tied[r]] = c
        return best
