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
from dataclasses import dataclass, replace
from typing import Iterable

import numpy as np

from ..errors import ExactnessError, GridRangeError, InvalidArgumentError, NonFiniteError

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
# Grid origins (in steps) stay exact as float64.
_MAX_ORIGIN = 2**53
# Coordinates beyond this magnitude are refused: squared distances would overflow float64.
_MAX_EXTENT_EXP = 500


@dataclass(frozen=True)
class Grid:
    """A dyadic snapping grid: a coordinate ``x`` becomes the integer
    ``k = round(x / step) - origin`` with ``step = 2**exponent``.

    The integers are taken relative to an ``origin`` (a grid point, in steps per axis), so that
    precision depends on the size of what is modelled, not on where it is: a unit part at
    ``10**9`` gets the same ~26-bit grid as at the origin, as far as float64 resolves it there
    (``step`` is never below the float64 spacing of the coordinates, so that every grid point
    is a float64 and ``to_float`` is exact).

    A grid made by :meth:`for_extent` from a largest absolute coordinate ``L`` has origin 0 and
    ``step = 2**(floor(log2 L) + 1 - bits)`` (the smallest power of two above ``L``, over
    ``2**bits``), so every snapped coordinate satisfies ``|k| <= 2**bits``. :meth:`for_points`
    and :meth:`for_box` centre the grid on the points' box when that makes the step finer.
    With the default ``bits=26`` the sum of two snapped points and every predicate on such sums
    is exact (orient3d needs about 87 bits, done in the exact path).

    Frames: integers of one point set are relative to its grid's origin. A difference of two
    points of one frame is a vector (origin 0, :attr:`vectors`); the sum of points of frames
    ``a`` and ``b`` is in frame ``a + b`` (:meth:`plus`). Grids of one step and bits combine
    this way without re-snapping; their predicates see only integers of one frame at a time.

    Snapping moves each coordinate by at most :attr:`error_bound` (= step / 2) and each point
    by at most :attr:`point_error_bound` (= sqrt(3) * step / 2) in Euclidean distance; the
    origin moves nothing (it is a whole number of steps).

    Attributes
    ----------
    exponent : int
        The grid step is ``2.0 ** exponent`` scene length units.
    bits : int
        Snapped coordinates satisfy ``|k| <= 2**bits``.
    origin : tuple of 3 int
        The grid point ``origin * step`` is integer 0 (default the scene origin).
    """

    exponent: int
    bits: int = 26
    origin: tuple = (0, 0, 0)

    def __post_init__(self):
        o = tuple(int(x) for x in self.origin)
        if len(o) != 3:
            raise InvalidArgumentError(f"grid origin must have 3 coordinates, got {self.origin}")
        if max(abs(x) for x in o) >= _MAX_ORIGIN:
            raise GridRangeError(f"grid origin {o} is beyond +-2**53 steps")
        object.__setattr__(self, "origin", o)

    @classmethod
    def for_extent(cls, extent: float, *, bits: int = 26) -> "Grid":
        """Grid centred on the scene origin for coordinates satisfying ``|x| <= extent``."""
        return cls(exponent=_extent_exponent(extent, bits), bits=bits)

    @classmethod
    def for_box(cls, lo, hi, *, reach: float = 0.0, far: float = 0.0,
                bits: int = 26) -> "Grid":
        """Grid for points in the box ``[lo, hi]`` and vectors up to ``reach`` per coordinate.

        The grid is centred on the box (a grid point near its centre is integer 0) when that
        gives a finer step than :meth:`for_extent` of the largest ``|x|``: the step then
        follows the box's half-size (and ``reach``), but never drops below what float64
        resolves at the box's coordinates (``|x| / step < 2**52``: two ulps of the largest,
        so that a point of the box plus a vector as large is a float64 number too). Every point of the box
        snaps within ``|k| <= 2**bits``, and every vector of length ``reach`` too. ``far``:
        a magnitude the grid's frames must also resolve exactly (a robot's coordinates).
        """
        # Python floats: the same IEEE arithmetic as numpy's, at a fraction of the cost on
        # three coordinates (this runs for every hull of a few points).
        lo = [float(x) for x in np.asarray(lo, dtype=np.float64).reshape(3)]
        hi = [float(x) for x in np.asarray(hi, dtype=np.float64).reshape(3)]
        if not all(math.isfinite(x) for x in lo + hi):
            _check_finite(np.array([lo, hi]), "grid box")
        reach, also = float(reach), float(far)
        far = max(abs(x) for x in lo + hi)
        plain = _extent_exponent(max(far, reach, also), bits)
        half = max((h - l) / 2.0 for l, h in zip(lo, hi))
        if not far or not half >= 0.0:
            return cls(exponent=plain, bits=bits)
        # Room for the centre's rounding to a grid point: half a step, below 2**-bits of size.
        size = max(half * (1.0 + 2.0**-20), reach)
        _, e_far = math.frexp(max(far, also))
        exponent = max(_extent_exponent(size, bits), e_far - 52)
        if exponent >= plain:
            return cls(exponent=plain, bits=bits)
        # the centre (no overflow; its rounding is absorbed by the room above) as origin:
        # what at() makes of it (round() on a float rounds half to even, as np.rint)
        return cls(exponent=exponent, bits=bits,
                   origin=tuple(round(math.ldexp(l / 2.0 + h / 2.0, -exponent))
                                for l, h in zip(lo, hi)))

    @classmethod
    def for_points(cls, *arrays: np.ndarray, bits: int = 26) -> "Grid":
        """Grid for the union of several ``(n, 3)`` float arrays (:meth:`for_box` of their box)."""
        if len(arrays) == 1:
            a = np.asarray(arrays[0], dtype=np.float64)
            if a.ndim == 2 and a.shape[1] == 3 and len(a) and np.isfinite(a).all():
                return cls.for_box(a.min(axis=0), a.max(axis=0), bits=bits)
        lo = np.full(3, np.inf)
        hi = np.full(3, -np.inf)
        extent, boxed = 0.0, True
        for i, a in enumerate(arrays):
            a = np.asarray(a, dtype=np.float64)
            if a.size == 0:
                continue
            _check_finite(a, f"array {i}")
            extent = max(extent, float(np.abs(a).max()))
            if a.shape[-1:] != (3,):
                boxed = False  # not points: validation names it; size the grid from |x|
                continue
            a = a.reshape(-1, 3)
            lo, hi = np.minimum(lo, a.min(axis=0)), np.maximum(hi, a.max(axis=0))
        if not boxed or not np.isfinite(lo).all():
            return cls.for_extent(extent, bits=bits)
        return cls.for_box(lo, hi, bits=bits)

    @classmethod
    def for_operands(cls, a, b, *, bits: int = 26) -> tuple["Grid", "Grid"]:
        """Grids of one step for the two operands of a sum ``A ⊕ B`` (``(n, 3)`` float arrays),
        each centred on its own points when that gives a finer step than one grid from the
        origin: the sum is then in frame ``ga.plus(gb)``, and the step follows the operands'
        sizes, not where they are."""
        a = np.asarray(a, dtype=np.float64).reshape(-1, 3)
        b = np.asarray(b, dtype=np.float64).reshape(-1, 3)
        plain = cls.for_points(a, b, bits=bits)
        if not len(a) or not len(b):
            return plain, plain
        _check_finite(a, "A")
        _check_finite(b, "B")
        boxes = [(a.min(axis=0), a.max(axis=0)), (b.min(axis=0), b.max(axis=0))]
        size = max(float(((hi - lo) / 2.0).max()) for lo, hi in boxes) * (1.0 + 2.0**-20)
        far = max(float(np.abs(v).max()) for box in boxes for v in box)
        _, e_far = math.frexp(2.0 * far)  # sums of the two included
        exponent = max(cls.for_extent(size, bits=bits).exponent, e_far - 52)
        if exponent >= plain.exponent:
            return plain, plain
        ga, gb = (cls(exponent=exponent, bits=bits).at(lo / 2.0 + hi / 2.0) for lo, hi in boxes)
        return ga, gb

    @classmethod
    def for_cobstacle(cls, obstacle_points, robot_points, reference_point, *,
                      bits: int = 26) -> "Grid":
        """The grid of a C-obstacle ``O ⊕ (c - R)`` from the operands' float coordinates.

        :meth:`for_box` of the obstacle's and the C-obstacle's box, with the vectors ``c - r``
        within reach: centred on them when that is finer than a grid from the origin, so that
        a part far from the origin keeps the precision of its size (as far as float64 resolves
        it there). The robot's own coordinates need only be resolved (``far``); it is snapped
        with :meth:`for_robot`.
        """
        O = np.asarray(obstacle_points, dtype=np.float64)
        R = np.asarray(robot_points, dtype=np.float64)
        c = np.asarray(reference_point, dtype=np.float64).reshape(3)
        if (O.ndim != 2 or R.ndim != 2 or O.shape[1:] != (3,) or R.shape[1:] != (3,)
                or not len(O) or not len(R) or not (np.isfinite(O).all() and np.isfinite(R).all())):
            return cls.for_points(O, R, c[None, :], bits=bits)  # validation names the bad one
        v_lo, v_hi = c - R.max(axis=0), c - R.min(axis=0)  # the box of c - R
        lo = np.minimum(O.min(axis=0), O.min(axis=0) + v_lo)
        hi = np.maximum(O.max(axis=0), O.max(axis=0) + v_hi)
        reach = float(np.abs(np.stack([v_lo, v_hi])).max())
        far = max(float(np.abs(R).max()), float(np.abs(c).max()))
        return cls.for_box(lo, hi, reach=reach, far=far, bits=bits)

    # ---- frames ---------------------------------------------------------------------------

    def at(self, point) -> "Grid":
        """The same step, with the grid point nearest ``point`` (scene units) as origin: the
        frame for a robot given around its reference point."""
        p = np.asarray(point, dtype=np.float64).reshape(3)
        _check_finite(p, "grid origin point")
        return replace(self, origin=tuple(int(v) for v in np.rint(np.ldexp(p, -self.exponent))))

    @property
    def vectors(self) -> "Grid":
        """The same step with origin 0: the frame of differences of points of one frame."""
        return replace(self, origin=(0, 0, 0))

    def plus(self, other: "Grid") -> "Grid":
        """The frame of sums ``a + b`` of a point of this frame and one of ``other``'s."""
        self._check_step(other)
        return replace(self, origin=tuple(a + b for a, b in zip(self.origin, other.origin)))

    def for_robot(self, robot_points, reference_point) -> "Grid":
        """The grid a robot is snapped on: this one when the robot and its reference point fit
        its range, else the same step about the reference point (:meth:`at`). Either way the
        vectors ``c - r`` are of this step, so ``O ⊕ (c - R)`` is in this grid's frame."""
        R = np.asarray(robot_points, dtype=np.float64)
        c = np.asarray(reference_point, dtype=np.float64).reshape(1, 3)
        if R.ndim != 2 or R.shape[1:] != (3,):
            return self  # validation names the bad operand
        P = np.concatenate([R, c])
        if not np.isfinite(P).all():
            return self  # validation names the bad coordinate
        k = np.rint(np.ldexp(P, -self.exponent)) - np.asarray(self.origin, dtype=np.float64)
        # exact: both terms are integers below 2**53 wherever the test can pass
        return self if np.abs(k).max() <= self.limit else self.at(c)

    def same_step(self, other: "Grid") -> bool:
        """Whether integers of the two grids combine exactly (same step and bits)."""
        return self.exponent == other.exponent and self.bits == other.bits

    def _check_step(self, other: "Grid") -> None:
        if not self.same_step(other):
            raise InvalidArgumentError(
                f"grids of different steps or bits do not combine: 2**{self.exponent} "
                f"({self.bits} bits) and 2**{other.exponent} ({other.bits} bits)")

    # ---- properties -----------------------------------------------------------------------

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

    @property
    def magnitude_exponent(self) -> int:
        """``W``: scene coordinates of this frame's points within ``4 * limit`` steps of the
        origin (sums of three snapped operands and a growth box) are below ``2**W`` in
        magnitude."""
        return (max(abs(o) for o in self.origin) + 4 * self.limit - 1).bit_length() + self.exponent

    def snap(self, points: np.ndarray) -> np.ndarray:
        """Snap float coordinates to grid integers (round half to even).

        Parameters
        ----------
        points : (..., 3) float64
            Coordinates in scene units.

        Returns
        -------
        ints : (..., 3) int64
            ``round(points / step) - origin``; ``(ints + origin) * step`` are the snapped
            coordinates.

        Raises
        ------
        NonFiniteError
            If a coordinate is NaN or infinite (the message gives the first bad row).
        GridRangeError
            If a coordinate is beyond ``limit * step`` of the origin: the grid was made for a
            smaller scene.
        """
        points = np.asarray(points, dtype=np.float64)
        _check_finite(points, "points")
        # Division by a power of two is exact (no subnormals: see for_extent), rint is exact;
        # beyond 2**53 the quotient is already an integer. The origin is subtracted in int64.
        with np.errstate(over="ignore"):  # overflow to inf is reported just below
            k = np.rint(np.ldexp(points, -self.exponent))
        if not k.size or np.abs(k).max() < 2.0**62:
            k = k.astype(np.int64) - np.asarray(self.origin, dtype=np.int64)
            over = np.abs(k) > self.limit
        else:
            over = np.abs(k) >= 2.0**62
        if over.any():
            flat = over.reshape(-1, 3) if over.ndim > 1 else over[None]
            row = int(np.nonzero(flat.any(axis=-1))[0][0])
            where = ("" if not any(self.origin) else
                     f" around {self.to_float(np.zeros(3, np.int64)).tolist()}")
            raise GridRangeError(
                f"point {row} has a coordinate beyond the grid's range +-{self.limit * self.step:.6g}"
                f"{where}; build the grid from every object of the scene (Grid.for_points)"
            )
        return k.astype(np.int64)

    def offset(self, point) -> np.ndarray:
        """``(3,)`` int64 ``round(point / step) - origin`` without the range check: where a
        point lies in this frame, however far (for frames of reflections and sums)."""
        p = np.asarray(point, dtype=np.float64).reshape(3)
        _check_finite(p, "point")
        k = np.rint(np.ldexp(p, -self.exponent))
        if np.abs(k).max() >= 2.0**61:
            raise GridRangeError(f"point {p.tolist()} is beyond 2**61 grid steps of the origin")
        return k.astype(np.int64) - np.asarray(self.origin, dtype=np.int64)

    def to_float(self, ints: np.ndarray) -> np.ndarray:
        """Scene coordinates of grid integers (exact while ``|k + origin| < 2**53``, which the
        grid's construction ensures for its points and their sums)."""
        k = np.asarray(ints, dtype=np.int64)
        if any(self.origin):
            k = k + np.asarray(self.origin, dtype=np.int64)
        return np.ldexp(k.astype(np.float64), self.exponent)

    def inner_box(self, lo, hi) -> np.ndarray:
        """``(2, 3)`` int64: the grid integers ``k`` (this frame) with ``lo <= world(k) <= hi``
        are exactly those with ``box[0] <= k <= box[1]`` (ceil and floor, exact)."""
        lo = np.ceil(np.ldexp(np.asarray(lo, dtype=np.float64), -self.exponent))
        hi = np.floor(np.ldexp(np.asarray(hi, dtype=np.float64), -self.exponent))
        lim = 2.0**62
        o = np.asarray(self.origin, dtype=np.int64)
        lo = np.clip(lo, -lim, lim).astype(np.int64) - o
        hi = np.clip(hi, -lim, lim).astype(np.int64) - o
        return np.stack([lo, hi])


def _extent_exponent(extent: float, bits: int) -> int:
    """The exponent of :meth:`Grid.for_extent`'s step, or the named error."""
    if not 8 <= bits <= _MAX_BITS:
        raise InvalidArgumentError(f"bits must be in [8, {_MAX_BITS}], got {bits}")
    extent = float(extent)
    if not math.isfinite(extent):
        raise NonFiniteError(f"grid extent is not finite: {extent}")
    if extent < 0.0:
        raise InvalidArgumentError(f"grid extent must be >= 0, got {extent}")
    if extent <= 0.0:
        return -bits
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
    return e - bits


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
