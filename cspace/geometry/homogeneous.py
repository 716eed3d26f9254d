"""Exact planar points: rationals and homogeneous integer triples, and the predicates on them.

Points are ``(Fraction, Fraction)`` pairs or homogeneous integer triples ``(X, Y, W)``, ``W > 0``
(:func:`_hom`, :func:`_hnorm`); orientations, comparisons along an axis, winding numbers and
turns are exact signs of integer expressions. The building blocks of :mod:`cspace.minkowski.plane_arrangement`,
:mod:`cspace.minkowski.coverage` and :mod:`cspace.minkowski.triangulation`.
"""

from __future__ import annotations

from fractions import Fraction
from math import gcd
from numbers import Integral, Rational, Real

import numpy as np

__all__ = ["to_point", "project_homogeneous", "winding_number", "point_on_segment"]


Point = tuple  # (Fraction, Fraction)


# --------------------------------------------------------------------------------------------
# exact point helpers
# --------------------------------------------------------------------------------------------


def _frac(x) -> Fraction:
    if isinstance(x, Fraction):
        return x
    if isinstance(x, (Integral, np.integer)):
        return Fraction(int(x))
    if isinstance(x, Rational):
        return Fraction(x.numerator, x.denominator)
    if isinstance(x, (Real, np.floating)):
        xf = float(x)
        if xf != xf or xf in (float("inf"), float("-inf")):
            raise ValueError(f"non-finite coordinate {x!r}")
        return Fraction(xf)  # the exact binary value of the float
    raise TypeError(f"cannot read {x!r} as an exact rational coordinate")


def to_point(p) -> Point:
    """Read one 2D point exactly.

    Accepts a pair ``(x, y)`` of ints / Fractions / other rationals (floats are taken at their
    exact binary value) or a homogeneous integer triple ``(x, y, w)`` with ``w != 0``, meaning
    ``(x / w, y / w)``. Returns a pair of :class:`Fraction` (canonical: equal points give equal,
    equally hashing tuples).
    """
    p = tuple(p)
    if len(p) == 2:
        return (_frac(p[0]), _frac(p[1]))
    if len(p) == 3:
        w = _frac(p[2])
        if w == 0:
            raise ValueError(f"homogeneous point {p!r} has w == 0")
        return (_frac(p[0]) / w, _frac(p[1]) / w)
    raise ValueError(f"a point is (x, y) or (x, y, w), got {p!r}")


def project_homogeneous(p4, drop: int) -> tuple[int, int, int]:
    """Project a homogeneous 3D point ``(X, Y, Z, W)`` (see
    :func:`cspace.geometry.endpoints.endpoint_coordinates`) to the plane of the two other coordinates.

    ``drop`` is the axis removed (0, 1 or 2); the remaining axes keep their cyclic order
    ``(drop + 1, drop + 2)`` so that a normal whose ``drop`` component is positive projects to
    a counter-clockwise orientation. Returns the homogeneous triple ``(a, b, W)``.
    """
    a, b = (drop + 1) % 3, (drop + 2) % 3
    return (p4[a], p4[b], p4[3])


def _cross(u, v):
    return u[0] * v[1] - u[1] * v[0]


def _dot(u, v):
    return u[0] * v[0] + u[1] * v[1]


def _orient(a, b, c) -> int:
    d = (b[0] - a[0]) * (c[1] - a[1]) - (b[1] - a[1]) * (c[0] - a[0])
    return (d > 0) - (d < 0)


def point_on_segment(p, a, b) -> bool:
    """Exact: is ``p`` on the closed segment ``[a, b]`` (``a == b`` allowed)."""
    if _orient(a, b, p) != 0:
        return False
    return min(a[0], b[0]) <= p[0] <= max(a[0], b[0]) and min(a[1], b[1]) <= p[1] <= max(a[1], b[1])


def winding_number(points, p) -> int:
    """Exact winding number of the closed polyline ``points`` (last joined to first) around ``p``.

    ``p`` must not lie on the polyline (the result would be meaningless); check with
    :func:`point_on_segment` first. Sunday's crossing rule with exact orientation signs.
    """
    w = 0
    n = len(points)
    py = p[1]
    for i in range(n):
        a = points[i]
        b = points[(i + 1) % n]
        if a[1] <= py:
            if b[1] > py and _orient(a, b, p) > 0:
                w += 1
        elif b[1] <= py and _orient(a, b, p) < 0:
            w -= 1
    return w


def _angle_cmp(u, v) -> int:
    """Counter-clockwise angular order of non-zero directions, starting at angle 0 (inclusive)."""
    hu = 0 if (u[1] > 0 or (u[1] == 0 and u[0] > 0)) else 1
    hv = 0 if (v[1] > 0 or (v[1] == 0 and v[0] > 0)) else 1
    if hu != hv:
        return hu - hv
    c = _cross(u, v)
    return -1 if c > 0 else (1 if c < 0 else 0)


def _hom(p) -> tuple[int, int, int]:
    """Canonical homogeneous integer triple ``(X, Y, W)``, ``W > 0``, ``gcd == 1`` of a
    Fraction pair."""
    x, y = p
    b, d = x.denominator, y.denominator
    w = b * d // gcd(b, d)
    return (x.numerator * (w // b), y.numerator * (w // d), w)


class _Ratio:
    """The exact number ``n / d`` (``d > 0``), compared by cross-multiplication: the tie-breaker
    of :func:`_float_key`, cheaper than a :class:`Fraction` (no gcd on construction)."""

    __slots__ = ("n", "d")

    def __init__(self, n: int, d: int):
        self.n, self.d = n, d

    def __lt__(self, o) -> bool:
        return self.n * o.d < o.n * self.d

    def __gt__(self, o) -> bool:
        return self.n * o.d > o.n * self.d

    def __le__(self, o) -> bool:
        return self.n * o.d <= o.n * self.d

    def __ge__(self, o) -> bool:
        return self.n * o.d >= o.n * self.d

    def __eq__(self, o) -> bool:
        return self.n * o.d == o.n * self.d

    __hash__ = None


def _float_key(h) -> tuple:
    """Order-exact comparison keys of a homogeneous point's coordinates: ``(float, exact)``
    per coordinate. Python's int division is correctly rounded, hence monotone: the floats
    never reverse an order, and the exact parts decide when they tie."""
    X, Y, W = h
    return ((X / W, _Ratio(X, W)), (Y / W, _Ratio(Y, W)))


def _hpoint(p) -> tuple[int, int, int]:
    """Canonical homogeneous triple of any point :func:`to_point` accepts (no Fractions made
    for integer pairs and integer triples)."""
    if type(p) is tuple and len(p) == 3 and type(p[0]) is int and type(p[1]) is int and type(p[2]) is int:
        return _hnorm(*p) if p[2] != 1 else p
    p = tuple(p)
    if all(isinstance(c, (int, np.integer)) for c in p):
        if len(p) == 2:
            return (int(p[0]), int(p[1]), 1)
        if len(p) == 3 and p[2] != 0:
            return _hnorm(int(p[0]), int(p[1]), int(p[2]))
    return _hom(to_point(p))


def _hnorm(X: int, Y: int, W: int) -> tuple[int, int, int]:
    if W == 1:
        return (X, Y, 1)
    if W < 0:
        X, Y, W = -X, -Y, -W
    g = gcd(X, Y, W)
    return (X // g, Y // g, W // g)


def _horient(a, b, c) -> int:
    """Orientation sign of three homogeneous points (all ``W > 0``): the 3x3 determinant."""
    d = (
        a[0] * (b[1] * c[2] - b[2] * c[1])
        - a[1] * (b[0] * c[2] - b[2] * c[0])
        + a[2] * (b[0] * c[1] - b[1] * c[0])
    )
    return (d > 0) - (d < 0)


def _hcentroid(a, b, c) -> tuple[int, int, int]:
    """Canonical homogeneous centroid of three homogeneous points."""
    (xa, ya, wa), (xb, yb, wb), (xc, yc, wc) = a, b, c
    return _hnorm(xa * wb * wc + xb * wa * wc + xc * wa * wb,
                  ya * wb * wc + yb * wa * wc + yc * wa * wb, 3 * wa * wb * wc)


def _hcross3(u, v):
    return (u[1] * v[2] - u[2] * v[1], u[2] * v[0] - u[0] * v[2], u[0] * v[1] - u[1] * v[0])


def _hcmp(a, b, ax: int) -> int:
    """Compare coordinate ``ax`` of two homogeneous points."""
    l, r = a[ax] * b[2], b[ax] * a[2]
    return (l > r) - (l < r)


def _hbetween(p, q, x, ax: int) -> bool:
    """For ``x`` on the line of ``p != q`` (``ax``: an axis along which they differ), is ``x``
    on the closed segment?"""
    c1, c2 = _hcmp(x, p, ax), _hcmp(x, q, ax)
    return c1 * c2 <= 0


def _hdir(a, b):
    """An integer vector with the direction of ``b - a`` (scaled by ``Wa * Wb > 0``)."""
    return (b[0] * a[2] - a[0] * b[2], b[1] * a[2] - a[1] * b[2])


def _hwinding(poly, p) -> int:
    """Winding number of the closed homogeneous polyline around ``p`` (not on it)."""
    w = 0
    n = len(poly)
    for i in range(n):
        a = poly[i]
        b = poly[(i + 1) % n]
        if _hcmp(a, p, 1) <= 0:
            if _hcmp(b, p, 1) > 0 and _horient(a, b, p) > 0:
                w += 1
        elif _hcmp(b, p, 1) <= 0 and _horient(a, b, p) < 0:
            w -= 1
    return w


def _hon_segment(x, p, q) -> bool:
    if _horient(p, q, x) != 0:
        return False
    if p == q:
        return x == p
    return _hbetween(p, q, x, 0 if p[0] * q[2] != q[0] * p[2] else 1)


def _hturn(poly) -> int:
    """Sign of the signed area of a closed polyline of homogeneous points (0 if none)."""
    num, den = 0, 1
    n = len(poly)
    for j in range(n):
        a, b = poly[j], poly[(j + 1) % n]
        t = a[0] * b[1] - a[1] * b[0]
        if t:
            w = a[2] * b[2]
            g = gcd(den, w)
            num, den = num * (w // g) + t * (den // g), den * (w // g)
    return (num > 0) - (num < 0)
