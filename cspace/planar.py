"""Exact planar arrangements of segments, and net signed coverage of oriented polygons.

Used by the NCC-CVMS trimming (paper section 3.1-3.2):

* step 6: each superset triangle, projected to a coordinate plane, cut by its intersection
  segments with other triangles -> :class:`Arrangement2D` of the triangle's edges plus the cuts;
* step 2: coplanar facets merged and opposite ones cancelled -> :func:`polygon_coverage` /
  :func:`merge_coplanar` (net signed coverage of oriented polygons in one plane).
* step 3: triangulation of a face with holes, without new vertices -> :func:`triangulate_face`.

Everything is exact: coordinates are :class:`fractions.Fraction` (constructed intersection points
are rationals), every decision is the exact sign of a rational expression. No epsilon, no atan2:
half-edges are ordered around a vertex by a half-plane test and a cross-product sign.

The structures are meant for small inputs (a handful to a few dozen segments); see
:class:`Arrangement2D` for the complexity. The combinatorial core of an arrangement (crossings,
pieces, half-edge cycles) runs compiled (:mod:`cspace._kernels.planar`); its pure-Python
reference is :func:`_arrangement_core`.
"""

from __future__ import annotations

import weakref
from collections import deque
from dataclasses import dataclass, field
from fractions import Fraction
from functools import cached_property, cmp_to_key
from math import gcd
from numbers import Integral, Rational, Real

import numpy as np

from .arrangement import box_pairs

from ._kernels import load

_compiled = load("planar")

__all__ = [
    "Face",
    "Arrangement2D",
    "Coverage",
    "MergeResult",
    "polygon_coverage",
    "sampled_coverage",
    "pushed_inside",
    "face_triangles",
    "known_triangles",
    "strict_inner_point",
    "plain_interior",
    "merge_coplanar",
    "to_point",
    "project_homogeneous",
    "winding_number",
    "point_on_segment",
    "triangulate_face",
    "triangulate_rings",
]

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
    :func:`cspace.arrangement.endpoint_coordinates`) to the plane of the two other coordinates.

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


# --------------------------------------------------------------------------------------------
# arrangement
# --------------------------------------------------------------------------------------------


@dataclass
class Face:
    """One face of an :class:`Arrangement2D`.

    Attributes
    ----------
    outer : list[int]
        The outer boundary as a cycle of half-edge ids, counter-clockwise (face on the left).
        Empty for the unbounded face.
    holes : list[list[int]]
        Inner boundary cycles (half-edge ids, clockwise: face on the left), one per connected
        component of the arrangement lying directly inside this face.
    isolated : list[int]
        Isolated vertices (from zero-length input segments) lying directly inside this face.
    sample : (Fraction, Fraction)
        A point strictly inside the face (not on any edge or vertex of the arrangement).
    area : Fraction or None
        The face's area (outer boundary area minus hole areas), > 0; None for the unbounded face.
    """

    outer: list
    holes: list = field(default_factory=list)
    isolated: list = field(default_factory=list)
    _area: object = field(default=None, repr=False)  # a Fraction, made on first use
    _cycles: list = field(default_factory=list, repr=False)  # ids of its boundary cycles
    _sample: tuple = field(default=None, repr=False)
    _owner: object = field(default=None, repr=False, compare=False)  # weakref to the arrangement

    @property
    def area(self):
        if self._area is None and self._cycles:
            arr = self._owner()
            if arr is None:
                raise ReferenceError("the face's arrangement is gone: read areas while it lives")
            n, d = arr._face_area2(self)
            self._area = Fraction(n, 2 * d)
        return self._area

    @property
    def sample(self) -> tuple:
        # computed on first use: most faces never need one
        if self._sample is None and self._owner is not None:
            self._sample = self._owner()._sample(self)
        return self._sample

    @sample.setter
    def sample(self, value) -> None:
        self._sample = value


# Largest common denominator (in bits) used to put an arrangement's points on one integer
# scale; beyond it the points are kept as Fractions.
_MAX_SCALE_BITS = 1024
# Below this many segments the plain double loop over pairs is cheaper than numpy.
_SWEEP_FROM = 48
# Up to this many polygons sampled_coverage filters them by boxes in plain Python.
_FEW_POLYGONS = 16


def _box_candidates(ids: list, boxes: dict):
    """Pairs ``(i, j)`` (``i`` before ``j`` in ``ids``) whose closed integer boxes
    ``(x0, x1, y0, y1)`` meet: a double loop for few segments, a sort-and-sweep otherwise."""
    n = len(ids)
    if n < max(_SWEEP_FROM, 2):
        yield from _box_candidates_slow(ids, boxes)
        return
    B = np.array([boxes[i] for i in ids], dtype=object).reshape(-1, 4)
    if max(abs(int(B.min())), abs(int(B.max()))) >= 2**28:
        yield from _box_candidates_slow(ids, boxes)  # beyond the grid's range: stay exact
        return
    B = B.astype(np.int64)
    zero = np.zeros((n, 1), dtype=np.int64)
    pairs = box_pairs(np.hstack([B[:, [0, 2]], zero]), np.hstack([B[:, [1, 3]], zero]))
    for x, y in pairs.tolist():
        yield ids[x], ids[y]


def _box_candidates_slow(ids, boxes):
    for a in range(len(ids)):
        for b in range(a + 1, len(ids)):
            bi, bj = boxes[ids[a]], boxes[ids[b]]
            if not (bi[1] < bj[0] or bj[1] < bi[0] or bi[3] < bj[2] or bj[3] < bi[2]):
                yield ids[a], ids[b]


def _arrangement_core(segs: list, labels: list) -> tuple:
    """The exact combinatorics of the arrangement of ``segs`` (canonical homogeneous endpoint
    pairs, one label each): the pure-Python reference of
    :func:`cspace._kernels.planar.arrangement_core`, which returns the same.

    Returns ``(order, vertex_labels, edges, edge_labels, origin, isolated, nxt, cycles, cyc_of,
    signs, comp)``:

    - ``order``: the distinct points, homogeneous, sorted lexicographically (x, then y);
    - ``vertex_labels``: labels of the zero-length segments, by vertex;
    - ``edges``: ``(u, v)``, ``u < v``, sorted; ``edge_labels``: the label set of each;
    - ``origin``: the origin vertex of each half-edge;
    - ``isolated``: the vertices on no edge (half-edge ``2k`` is edge k from u to v,
      ``2k + 1`` back); ``nxt``: the successor of each half-edge along its face (the
      clockwise neighbour of its twin, the outgoing half-edges of a vertex being ordered
      counter-clockwise from angle 0);
    - ``cycles``: the face cycles (half-edge lists, each from its smallest half-edge, in
      order of it), ``cyc_of``: each half-edge's cycle;
    - ``signs``: the sign of each cycle's signed area (:func:`_harea`; the exact areas are
      made only where asked for, :meth:`Arrangement2D._cycle_area`);
    - ``comp``: per vertex, the smallest vertex of its connected component.
    """
    H = segs
    H = segs
    proper = [i for i, (p, q) in enumerate(H) if p != q]
    points_only = [i for i, (p, q) in enumerate(H) if p == q]
    on = {i: {H[i][0], H[i][1]} for i in proper}
    axis = {i: (0 if H[i][0][0] * H[i][1][2] != H[i][1][0] * H[i][0][2] else 1) for i in proper}
    lines = {i: _hcross3(H[i][0], H[i][1]) for i in proper}
    # conservative integer boxes (floor / ceil): a cheap exact filter, decides nothing alone
    boxes = {}
    for i in proper:
        (p, q) = H[i]
        xa, xb = sorted((p[0] // p[2], q[0] // q[2]))
        ya, yb = sorted((p[1] // p[2], q[1] // q[2]))
        boxes[i] = (xa, xb + 1, ya, yb + 1)
    for i, j in _box_candidates(proper, boxes):
        p, q = H[i]
        r, s = H[j]
        # orient(p, q, x) = (p x q) . x: one dot product with the segment's line
        li, lj = lines[i], lines[j]
        d1 = li[0] * r[0] + li[1] * r[1] + li[2] * r[2]
        d2 = li[0] * s[0] + li[1] * s[1] + li[2] * s[2]
        o1, o2 = (d1 > 0) - (d1 < 0), (d2 > 0) - (d2 < 0)
        if o1 == 0 and o2 == 0:  # collinear: overlap or touch
            for x in (r, s):
                if _hbetween(p, q, x, axis[i]):
                    on[i].add(x)
            for x in (p, q):
                if _hbetween(r, s, x, axis[j]):
                    on[j].add(x)
            continue
        if o1 * o2 > 0:
            continue
        d3 = lj[0] * p[0] + lj[1] * p[1] + lj[2] * p[2]
        d4 = lj[0] * q[0] + lj[1] * q[1] + lj[2] * q[2]
        o3, o4 = (d3 > 0) - (d3 < 0), (d4 > 0) - (d4 < 0)
        if o3 * o4 > 0:
            continue
        if o1 == 0:
            x = r
        elif o2 == 0:
            x = s
        elif o3 == 0:
            x = p
        elif o4 == 0:
            x = q
        else:
            x = _hnorm(*_hcross3(lines[i], lines[j]))
        on[i].add(x)
        on[j].add(x)
    vertex_set = set()
    point_label = {}
    if points_only:
        B = np.array([boxes[i] for i in proper], dtype=object).reshape(-1, 4)
    for k in points_only:
        x = H[k][0]
        vertex_set.add(x)
        point_label.setdefault(x, set()).add(labels[k])
        xi, yi = x[0] // x[2], x[1] // x[2]
        near = np.nonzero((B[:, 0] <= xi) & (xi <= B[:, 1]) & (B[:, 2] <= yi) & (yi <= B[:, 3]))[0]
        for n in near.tolist():
            i = proper[n]
            if _hon_segment(x, *H[i]):
                on[i].add(x)
    for i in proper:
        vertex_set.update(on[i])
    _, S = _scaled(list(vertex_set))
    scaled = dict(zip(vertex_set, S))
    pieces = {}
    for i in proper:
        ax = axis[i]
        pts = sorted(on[i], key=lambda h: scaled[h][ax])
        for a, b in zip(pts, pts[1:]):
            key = (a, b) if a < b else (b, a)
            pieces.setdefault(key, set()).add(labels[i])

    order = sorted(vertex_set, key=scaled.__getitem__)
    index = {h: n for n, h in enumerate(order)}
    vertex_labels = {index[x]: s for x, s in point_label.items()}
    keyed = sorted(((index[a], index[b]) if index[a] < index[b] else (index[b], index[a]), lab)
                   for (a, b), lab in pieces.items())
    E = [k for k, _ in keyed]
    edge_labels = [lab for _, lab in keyed]

    nh = 2 * len(E)
    origin = [0] * nh
    for k, (u, v) in enumerate(E):
        origin[2 * k] = u
        origin[2 * k + 1] = v
    out = [[] for _ in order]
    for h in range(nh):
        out[origin[h]].append(h)
    pos = [0] * nh
    for v, hs in enumerate(out):
        if len(hs) > 2:  # two half-edges have one cyclic order
            o = order[v]
            dirs = {h: _hdir(o, order[origin[h ^ 1]]) for h in hs}
            hs.sort(key=cmp_to_key(lambda a, b: _angle_cmp(dirs[a], dirs[b])))
        for n, h in enumerate(hs):
            pos[h] = n
    nxt = [0] * nh
    for h in range(nh):
        t = h ^ 1
        ring = out[origin[t]]
        nxt[h] = ring[pos[t] - 1]

    cyc_of = [-1] * nh
    cycles = []
    for h in range(nh):
        if cyc_of[h] >= 0:
            continue
        c = []
        g = h
        while cyc_of[g] < 0:
            cyc_of[g] = len(cycles)
            c.append(g)
            g = nxt[g]
        cycles.append(c)
    signs = []
    for c in cycles:
        num = _harea(order, origin, c)[0]
        signs.append((num > 0) - (num < 0))

    # components: union-find over edges, the smaller root kept (so each root is its
    # component's smallest vertex)
    parent = list(range(len(order)))

    def find(a):
        while parent[a] != a:
            parent[a] = parent[parent[a]]
            a = parent[a]
        return a

    for u, v in E:
        ru, rv = find(u), find(v)
        if ru != rv:
            parent[max(ru, rv)] = min(ru, rv)
    comp = [find(a) for a in range(len(order))]
    isolated = [v for v in range(len(order)) if not out[v]]
    return order, vertex_labels, E, edge_labels, origin, isolated, nxt, cycles, cyc_of, signs, comp


def _scaled(points: list) -> tuple[int, list]:
    """The points (canonical homogeneous triples) on one integer scale: their common
    denominator ``L`` and the scaled integer pairs, which compare and orient exactly like the
    rational points (a similarity) without Fractions; over :data:`_MAX_SCALE_BITS` bits
    (many unrelated denominators, where Fractions are cheaper than one huge scale), ``L = 0``
    and their :func:`_float_key`."""
    L = 1
    for h in points:
        if L % h[2]:
            L = L * h[2] // gcd(L, h[2])
            if L.bit_length() > _MAX_SCALE_BITS:
                return 0, [_float_key(h) for h in points]
    return L, [(h[0] * (L // h[2]), h[1] * (L // h[2])) for h in points]


def _harea(H: list, origin: list, cycle: list) -> tuple[int, int]:
    """Signed area of a half-edge cycle as ``(num, den)``, ``area = num / (2 den)``,
    ``den > 0``: the sum of (Xa Yb - Ya Xb) / (Wa Wb) / 2 over a common denominator,
    unreduced."""
    num, den = 0, 1
    for h in cycle:
        a, b = H[origin[h]], H[origin[h ^ 1]]
        t = a[0] * b[1] - a[1] * b[0]
        if t:
            w = a[2] * b[2]
            if w == den:
                num += t
            elif den % w == 0:
                num += t * (den // w)
            else:
                g = gcd(den, w)
                num = num * (w // g) + t * (den // g)
                den = den * (w // g)
    return num, den


class Arrangement2D:
    """Exact planar subdivision induced by a set of segments with rational endpoints.

    Parameters
    ----------
    segments : sequence of (p, q)
        Endpoints as accepted by :func:`to_point` (Fraction / int pairs or homogeneous integer
        triples ``(x, y, w)``). Zero-length segments become vertices: isolated vertices if they
        touch no other segment, otherwise they split the segments they lie on.
    labels : sequence, optional
        A hashable label per segment (default: the segment's index). Every edge records the set
        of labels of the input segments covering it; zero-length segments record theirs in
        :attr:`vertex_labels`.
    canonical : bool
        The endpoints are already canonical homogeneous triples of Python ints ``(x, y, w)``
        (``w > 0``, ``gcd(x, y, w) == 1``): taken as they are, without checking (callers
        inside cspace that made them so).

    Attributes
    ----------
    vertices : list[(Fraction, Fraction)]
        Distinct points, sorted lexicographically (x, then y).
    edges : (e, 2) int64 array
        Undirected edges ``(u, v)`` with ``u < v``; edge ``k`` has half-edges ``2k`` (u -> v) and
        ``2k + 1`` (v -> u). Collinear overlapping inputs give one edge per elementary piece.
    edge_labels : list[set]
        Labels of the input segments covering each edge.
    vertex_labels : dict[int, set]
        Labels of zero-length input segments, by vertex.
    faces : list[Face]
        Bounded faces (ids 0 .. F-1). The unbounded face is :attr:`unbounded`, id -1.
    unbounded : Face
        Its ``holes`` are the outer boundaries of the top-level connected components.
    edge_faces : (e, 2) int64 array
        ``[left, right]`` face ids of each edge seen from ``u`` to ``v`` (-1: unbounded). Both
        sides are the same face exactly when the edge is a bridge of the graph (its removal
        disconnects its component): dangling edges, trees, edges joining a hole to a boundary.
    half_edge_face : list[int]
        The face on the left of each half-edge.
    next_half_edge : list[int]
        Successor of each half-edge along its face cycle.
    components : int
        Number of connected components (isolated vertices included).

    Notes
    -----
    Algorithm: all O(n^2) segment pairs are intersected exactly (proper crossings, touching
    endpoints, collinear overlaps); each segment is split at the sorted points found on it, and
    equal pieces are merged. Outgoing half-edges are sorted around each vertex exactly; face
    cycles follow ``next(h) = clockwise neighbour of twin(h)`` around the head of h. Cycles of
    positive signed area are outer boundaries of bounded faces; the others (clockwise, or of
    zero area for trees) are holes, attached to the smallest positive cycle strictly containing
    their lexicographically smallest vertex (exact winding number). Cost is
    O(n^2 + k log k + C * H) Fraction operations for n segments, k pieces, C cycles and H
    half-edges: fine for tens of segments, not meant for thousands.
    """

    def __init__(self, segments, labels=None, *, canonical: bool = False):
        segs = (list(segments) if canonical
                else [(_hpoint(p), _hpoint(q)) for p, q in segments])
        if labels is None:
            labels = list(range(len(segs)))
        else:
            labels = list(labels)
            if len(labels) != len(segs):
                raise ValueError("labels must have one entry per segment")
        self._tris: dict = {}  # face id -> triangles (face_triangles)
        self._centroids: dict = {}  # face id -> centroid of its first triangle
        self._build(segs, labels)

    # ---------------------------------------------------------------- construction

    def _build(self, segs, labels):
        (self._H, self.vertex_labels, E, self.edge_labels, origin, isolated, nxt, cycles, cyc_of,
         signs, comp) = _compiled.arrangement_core(segs, labels)
        self._vertices = None
        self._E = E
        nh = 2 * len(E)
        self.half_edge_origin = origin
        self.next_half_edge = nxt
        self._cycles = cycles
        self._comp = comp
        self.components = sum(1 for a, c in enumerate(comp) if a == c)
        self._areas: dict = {}  # cycle -> exact (num, den), made when asked for
        self._bbox, self._hpoly = {}, {}  # per positive cycle, made when first asked for

        positive = [c for c in range(len(cycles)) if signs[c] > 0]
        self._positive_cycles = positive
        face_of_cycle = {c: n for n, c in enumerate(positive)}
        self._face_of_cycle = face_of_cycle
        self.faces = [Face(outer=cycles[c], _cycles=[c]) for c in positive]
        self.unbounded = Face(outer=[])
        # Every non-positive cycle (a component's outer boundary) is a hole of the face that
        # holds its component; with one component (and no isolated vertex) that is the
        # unbounded face, with no search.
        several = self.components > 1
        cycle_face = [0] * len(cycles)
        for c in range(len(cycles)):
            if c in face_of_cycle:
                cycle_face[c] = face_of_cycle[c]
                continue
            f = self._host(min(origin[h] for h in cycles[c])) if several else -1
            cycle_face[c] = f
            face = self.faces[f] if f >= 0 else self.unbounded
            face.holes.append(cycles[c])
            if f >= 0:
                face._cycles.append(c)
        for v in isolated:
            f = self._host(v)
            (self.faces[f] if f >= 0 else self.unbounded).isolated.append(v)
        self.half_edge_face = [cycle_face[cyc_of[h]] for h in range(nh)]
        owner = weakref.ref(self)  # no reference cycle: freed without the collector
        for f in self.faces:
            f._owner = owner
        self.unbounded._owner = owner

    def _host(self, v: int) -> int:
        """The face holding vertex ``v``, a lexicographically smallest vertex of its
        component: the innermost positive cycle of another component strictly containing it
        (smallest area first), -1 if none. No cycle of its own component strictly contains
        it, and cycles of other components do not pass through it."""
        return self._innermost(self._S[v], self._H[v], self._comp[v])

    def _innermost(self, p, hp, component: int = -1) -> int:
        """The face of the smallest positive cycle (not of ``component``) strictly around the
        point ``hp`` (homogeneous; ``p`` its box key, :attr:`_S`'s form), -1 if none."""
        comp_of_cycle = self._comp_of_cycle
        for c in self._positive:
            if comp_of_cycle[c] == component:
                continue
            b = self._cycle_box(c)
            if not (b[0] < p[0] < b[1] and b[2] < p[1] < b[3]):
                continue
            if _hwinding(self._cycle_hpoints(c), hp) != 0:
                return self._face_of_cycle[c]
        return -1

    @cached_property
    def _cluttered(self) -> set:
        """Faces holding an isolated vertex or a bridge (an edge with this face on both
        sides: dangling edges, trees, edges joining a hole to a boundary)."""
        hf = self.half_edge_face
        out = {hf[h] for h in range(0, len(hf), 2) if hf[h] == hf[h + 1]}
        out.update(f for f, face in enumerate(self.faces) if face.isolated)
        return out

    @cached_property
    def _comp_of_cycle(self) -> list:
        return [self._comp[self.half_edge_origin[c[0]]] for c in self._cycles]

    @cached_property
    def _positive(self) -> list:
        """The positive cycles by area; Python's int division is correctly rounded, so the
        floats keep the order and the exact ratios decide their ties."""
        def key(c):
            a = self._cycle_area(c)
            return a[0] / a[1], _Ratio(*a)

        return sorted(self._positive_cycles, key=key)

    def _cycle_area(self, c: int) -> tuple[int, int]:
        """Exact signed area of cycle ``c``: ``(num, den)``, area ``num / (2 den)``, ``den > 0``."""
        a = self._areas.get(c)
        if a is None:
            a = self._areas[c] = _harea(self._H, self.half_edge_origin, self._cycles[c])
        return a

    def _face_area2(self, face: Face) -> tuple[int, int]:
        """Twice the exact area of a bounded face: ``(num, den)``, ``den > 0`` (the sum of its
        cycles' signed areas; holes count negatively)."""
        num, den = 0, 1
        for c in face._cycles:
            n, d = self._cycle_area(c)
            num, den = num * d + n * den, den * d
        return num, den

    @cached_property
    def _scale(self) -> tuple[int, list]:
        return _scaled(self._H)

    @property
    def _L(self) -> int:
        """The points' common denominator, 0 when they are kept as float keys (:func:`_scaled`)."""
        return self._scale[0]

    @property
    def _S(self) -> list:
        """The points scaled by :attr:`_L` (integer pairs), or their float keys."""
        return self._scale[1]

    @cached_property
    def _index(self) -> dict:
        return {h: n for n, h in enumerate(self._H)}

    @cached_property
    def edges(self) -> np.ndarray:
        return np.array(self._E, dtype=np.int64).reshape(-1, 2)

    @cached_property
    def edge_faces(self) -> np.ndarray:
        hf = self.half_edge_face
        return np.array([(hf[2 * k], hf[2 * k + 1]) for k in range(len(self._E))],
                        dtype=np.int64).reshape(-1, 2)

    @property
    def vertices(self) -> list:
        """Distinct points as Fraction pairs, sorted lexicographically (made on first use)."""
        if self._vertices is None:
            self._vertices = [(Fraction(h[0], h[2]), Fraction(h[1], h[2])) for h in self._H]
        return self._vertices

    def _cycle_hpoints(self, c: int) -> list:
        """Homogeneous points along cycle ``c``."""
        pts = self._hpoly.get(c)
        if pts is None:
            origin = self.half_edge_origin
            pts = self._hpoly[c] = [self._H[origin[h]] for h in self._cycles[c]]
        return pts

    def _cycle_box(self, c: int) -> tuple:
        """Box ``(x0, x1, y0, y1)`` of cycle ``c`` in the stored point form (scaled integers,
        or float-then-exact keys)."""
        b = self._bbox.get(c)
        if b is None:
            V, origin = self._S, self.half_edge_origin
            xs = [V[origin[h]][0] for h in self._cycles[c]]
            ys = [V[origin[h]][1] for h in self._cycles[c]]
            b = self._bbox[c] = (min(xs), max(xs), min(ys), max(ys))
        return b

    def _sample(self, face: Face):
        """A point strictly inside a bounded face.

        Let ``y0`` be the lowest y of the outer boundary and ``y1`` the next distinct y among the
        face's boundary vertices and isolated vertices (holes lie strictly above ``y0``). In the
        open slab
        ``y0 < y < y1`` only outer-boundary edges are present and none ends there, so on the line
        ``y = (y0 + y1) / 2`` some gap between consecutive crossings lies in the face: the first
        gap with non-zero winding of the outer cycle.
        """
        if face is self.unbounded:  # left of the smallest point
            if not self._H:
                return (Fraction(0), Fraction(0))
            h0 = self._H[0]
            return (Fraction(h0[0], h0[2]) - 1, Fraction(h0[1], h0[2]))
        V, origin = self.vertices, self.half_edge_origin
        ids = {origin[h] for h in face.outer}
        ids.update(origin[h] for c in face.holes for h in c)
        ids.update(face.isolated)
        ys = [V[v][1] for v in ids]
        y0 = min(ys)
        y1 = min(y for y in ys if y > y0)
        ym = (y0 + y1) / 2
        xs = []
        for h in face.outer:
            a, b = V[origin[h]], V[origin[h ^ 1]]
            if (a[1] < ym) != (b[1] < ym):
                x = a[0] + (ym - a[1]) * (b[0] - a[0]) / (b[1] - a[1])
                xs.append((x, 1 if b[1] > a[1] else -1))
        xs.sort()
        # winding of a point at x: edges to the right going up count +1 (ccw), down -1
        w = sum(d for _, d in xs)
        for (xa, da), (xb, _) in zip(xs, xs[1:]):
            w -= da
            if w != 0 and xa < xb:
                return ((xa + xb) / 2, ym)
        raise AssertionError("no interior sample found")  # pragma: no cover

    def _inner_point(self, f: int) -> tuple[int, int, int]:
        """Homogeneous integer point in the closure of face ``f``, in the open face up to an
        isolated vertex or a dangling edge (enough to read a coverage that is constant on the
        face): the centroid of the first triangle of :func:`face_triangles` (cached)."""
        c = self._centroids.get(f)
        if c is None:
            a, b, d = face_triangles(self, f)[0]
            c = self._centroids[f] = _hcentroid(self._H[a], self._H[b], self._H[d])
        return c

    # ---------------------------------------------------------------- queries

    def cycle_vertices(self, cycle) -> list:
        """Vertex ids along a half-edge cycle."""
        return [self.half_edge_origin[h] for h in cycle]

    def cycle_points(self, cycle) -> list:
        """Exact points along a half-edge cycle."""
        return [self.vertices[self.half_edge_origin[h]] for h in cycle]

    def face(self, f: int) -> Face:
        """Face by id (-1: the unbounded face)."""
        return self.unbounded if f < 0 else self.faces[f]

    def on_edge(self, point) -> int | None:
        """The id of an edge containing ``point`` (its endpoints included), or None."""
        x = _hom(to_point(point))
        H = self._H
        for k, (u, v) in enumerate(self.edges.tolist()):
            if _hon_segment(x, H[u], H[v]):
                return k
        return None

    def locate(self, point) -> int | None:
        """Exact face id containing ``point`` (-1: unbounded), or None when the point lies on
        an edge or a vertex of the arrangement."""
        p = to_point(point)
        x = _hom(p)
        if x in self._index or self.on_edge(p) is not None:
            return None
        # the form of the stored boxes: scaled integers, or float-then-exact keys
        p = (p[0] * self._L, p[1] * self._L) if self._L else _float_key(_hom(p))
        return self._innermost(p, x)

    def __repr__(self) -> str:
        return (
            f"Arrangement2D({len(self.vertices)} vertices, {len(self.edges)} edges, "
            f"{len(self.faces)} bounded faces, {self.components} components)"
        )


# --------------------------------------------------------------------------------------------
# coverage of oriented polygons (step 2)
# --------------------------------------------------------------------------------------------


@dataclass
class Coverage:
    """Result of :func:`polygon_coverage`.

    Attributes
    ----------
    arrangement : Arrangement2D
        Arrangement of all polygon edges; edge labels are ``(polygon index, edge index)``.
    coverage : list[int]
        Net coverage of each bounded face (the unbounded face always has 0).
    support : list[int]
        Unsigned coverage of each bounded face: ``sum_i |weights[i] * winding(polygon_i)|``
        for simple polygons; non-zero exactly where some polygon of non-zero weight covers
        the face, even where opposite polygons cancel in :attr:`coverage`.
    """

    arrangement: Arrangement2D
    coverage: list
    support: list = None

    def of(self, f: int) -> int:
        return 0 if f < 0 else self.coverage[f]


@dataclass
class MergeResult:
    """Result of :func:`merge_coplanar`.

    Attributes
    ----------
    arrangement : Arrangement2D
    faces : list[int]
        Ids of the faces with non-zero net coverage.
    signs : list[int]
        ``sign(coverage)`` of each of them: +1 counter-clockwise (same orientation as the
        plane's positive side), -1 clockwise.
    coverage : list[int]
        The net coverage of each of them.
    boundary : list[tuple[int, int]]
        The oriented boundary of the merged region: ``(half-edge id, sign)`` for each half-edge
        whose left face has non-zero sign ``sign`` and whose right face has a different sign.
        For sign +1 these half-edges run counter-clockwise around the region.
    """

    arrangement: Arrangement2D
    faces: list
    signs: list
    coverage: list
    boundary: list


def _polygons(polygons, weights):
    polys = [[_hpoint(p) for p in poly] for poly in polygons]
    if weights is None:
        weights = [1] * len(polys)
    weights = [int(w) for w in weights]
    if len(weights) != len(polys):
        raise ValueError("weights must have one entry per polygon")
    return polys, weights


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


def polygon_coverage(polygons, weights=None, cuts=()) -> Coverage:
    """Net signed coverage of oriented closed polygons in one plane.

    Parameters
    ----------
    polygons : sequence of sequences of points
        Each polygon is a closed polyline (last vertex joined to the first), vertices as
        accepted by :func:`to_point`. Counter-clockwise polygons count positively. Simple
        polygons are the intended input, but any closed polyline works (it counts by its winding
        number); repeated consecutive vertices are ignored.
    weights : sequence of int, optional
        Integer weight per polygon (default 1).
    cuts : sequence of (p, q), optional
        Extra segments (zero-length ones are points) that split faces without changing any
        coverage; their edge labels are ``(-1, k)`` for cut ``k``.

    Returns
    -------
    Coverage
        The arrangement of all polygon edges and, for each bounded face ``f``,
        ``coverage[f] = sum_i weights[i] * winding(polygon_i, sample_f)``. This is constant on
        each face. It is computed by propagation across edges from the unbounded face
        (coverage 0): crossing a directed edge from its right to its left adds the weights of the
        polygon edges covering it in the same direction and subtracts those in the opposite one.
    """
    polys, weights = _polygons(polygons, weights)
    segs, labels, dirs = [], [], {}
    turn = [_hturn(poly) for poly in polys]  # +1 counter-clockwise, -1 clockwise
    for i, poly in enumerate(polys):
        n = len(poly)
        for j in range(n):
            a, b = poly[j], poly[(j + 1) % n]
            if a == b:
                continue
            segs.append((a, b))
            labels.append((i, j))
            dirs[(i, j)] = _hdir(a, b)
    for k, (a, b) in enumerate(cuts):
        segs.append((a, b))
        labels.append((-1, k))
    arr = Arrangement2D(segs, labels)
    H = arr._H
    nf = len(arr.faces)
    adj = {}
    for k, (u, v) in enumerate(arr.edges.tolist()):
        d = _hdir(H[u], H[v])
        delta = total = 0
        for lab in arr.edge_labels[k]:
            if lab[0] >= 0:
                along = 1 if _dot(dirs[lab], d) > 0 else -1
                w = weights[lab[0]]
                delta += w * along
                # entering the polygon (its inside is on the left: counter-clockwise and
                # crossed along, or clockwise and crossed against) adds |w|
                total += abs(w) * turn[lab[0]] * along
        left, right = arr.edge_faces[k]
        left, right = int(left), int(right)
        adj.setdefault(right, []).append((left, delta, total))
        adj.setdefault(left, []).append((right, -delta, -total))
    cov = {-1: (0, 0)}
    queue = deque([-1])
    while queue:
        f = queue.popleft()
        c, a = cov[f]
        for g, d, t in adj.get(f, ()):
            if g not in cov:
                cov[g] = (c + d, a + t)
                queue.append(g)
            elif cov[g] != (c + d, a + t):  # pragma: no cover - impossible for closed polylines
                raise AssertionError("inconsistent coverage propagation")
    return Coverage(arr, [cov[f][0] for f in range(nf)], [cov[f][1] for f in range(nf)])


def _pushed_side(a, b, X: int, Y: int, W: int) -> int:
    """Side of the point ``(X/W, Y/W) + eps * (1, eps)`` (eps -> 0+) of the directed line
    ``a -> b`` (integer points, ``a != b``): +1 left, -1 right, never 0."""
    ux, uy = b[0] - a[0], b[1] - a[1]
    d = ux * (Y - a[1] * W) - uy * (X - a[0] * W)
    if d:
        return 1 if d > 0 else -1
    # on the line: the push (1, eps) decides, first along x, then along y
    return -1 if uy > 0 else (1 if uy < 0 else (1 if ux > 0 else -1))


def pushed_inside(poly, turn: int, X: int, Y: int, W: int) -> bool:
    """Is the point ``(X/W, Y/W) + eps * (1, eps)`` (eps -> 0+) inside the convex polygon
    ``poly`` (integer points) of orientation ``turn`` (+1 counter-clockwise, -1 clockwise)?
    Never on its boundary: the push decides."""
    n = len(poly)
    return all(_pushed_side(poly[k], poly[(k + 1) % n], X, Y, W) == turn for k in range(n))


def sampled_coverage(polygons, weights, segments, labels=None, *, canonical: bool = False) -> Coverage:
    """Net and unsigned coverage of the faces of the arrangement of ``segments`` by convex
    oriented polygons, read at one point per face.

    Unlike :func:`polygon_coverage` the polygon edges are not in the arrangement, so its faces
    are not cut by them. The result is right only when the coverage is constant on every
    face, i.e. when ``segments`` contain every point where the net or the unsigned coverage
    changes: the caller's invariant (:mod:`cspace.trim` derives it from the closedness of the
    superset). It is certified in part: the integral of the coverage over the faces must equal
    ``sum_i weights[i] * signed_area(polygon_i)``, else :class:`ValueError`.

    Parameters
    ----------
    polygons : sequence of sequences of integer pairs
        Convex polygons (counter-clockwise ones count positively), at least three distinct
        vertices each, integer coordinates.
    weights : sequence of int
        Integer weight per polygon.
    segments, labels, canonical
        As for :class:`Arrangement2D`.

    Returns
    -------
    Coverage
        ``coverage[f] = sum_i weights[i] * winding(polygon_i, q_f)`` and ``support[f] =
        sum_i |weights[i] * winding(polygon_i, q_f)|`` at ``q_f = sample_f + eps * (1, eps)``
        (the push moves a sample lying on a polygon edge off it, into the face).
    """
    polys = [[(int(p[0]), int(p[1])) for p in poly] for poly in polygons]
    weights = [int(w) for w in weights]
    if len(weights) != len(polys):
        raise ValueError("weights must have one entry per polygon")
    arr = Arrangement2D(segments, labels, canonical=canonical)
    turn, boxes, area2 = [], [], 0
    for i, poly in enumerate(polys):
        n = len(poly)
        a2 = sum(poly[k][0] * poly[(k + 1) % n][1] - poly[k][1] * poly[(k + 1) % n][0] for k in range(n))
        turn.append((a2 > 0) - (a2 < 0))
        area2 += weights[i] * a2
        xs, ys = [p[0] for p in poly], [p[1] for p in poly]
        boxes.append((min(xs) - 1, max(xs) + 1, min(ys) - 1, max(ys) + 1))
    box = np.array(boxes, dtype=np.float64).reshape(-1, 4) if len(polys) > _FEW_POLYGONS else None
    nf = len(arr.faces)
    coverage, support = [0] * nf, [0] * nf
    num, den = 0, 1  # twice the integral of the coverage: num / den
    for f, face in enumerate(arr.faces):
        X, Y, w = arr._inner_point(f)
        xf, yf = X / w, Y / w
        # conservative box filter: floats are within an ulp; integer boxes, margin 1
        if box is None:
            near = [i for i, b in enumerate(boxes) if b[0] <= xf <= b[1] and b[2] <= yf <= b[3]]
        else:
            near = np.nonzero((box[:, 0] <= xf) & (xf <= box[:, 1])
                              & (box[:, 2] <= yf) & (yf <= box[:, 3]))[0].tolist()
        c = s = 0
        for i in near:
            if pushed_inside(polys[i], turn[i], X, Y, w):
                c += weights[i] * turn[i]
                s += abs(weights[i])
        coverage[f], support[f] = c, s
        if c:  # integral += c * face.area, as twice the areas over a growing denominator
            n, d = arr._face_area2(face)
            g = gcd(den, d)
            num, den = num * (d // g) + c * n * (den // g), den * (d // g)
    if num != area2 * den:
        raise ValueError("the coverage is not constant on the faces: the segments miss a place "
                         "where it changes")
    return Coverage(arr, coverage, support)


def merge_coplanar(polygons, weights=None) -> MergeResult:
    """Union of coplanar same-orientation facets, cancellation of opposite ones.

    Semantics: the plane is split into the faces of the arrangement of all polygon edges and
    each face gets its net coverage ``c`` (see :func:`polygon_coverage`; with unit weights,
    ``c = #(CCW polygons containing it) - #(CW polygons containing it)``). The result is the
    set of faces with ``c != 0``, each oriented by ``sign(c)``. Hence overlapping facets with
    the same orientation merge into their union (sign kept), a facet and an opposite one cancel
    where they overlap (symmetric difference of opposite conjoint facets), and where more of one
    orientation than the other overlap, the majority orientation survives. Edges and vertices
    are measure-zero and not reported as regions; :attr:`MergeResult.boundary` gives the
    region boundaries.
    """
    cov = polygon_coverage(polygons, weights)
    arr = cov.arrangement
    faces = [f for f, c in enumerate(cov.coverage) if c != 0]
    signs = [1 if cov.coverage[f] > 0 else -1 for f in faces]
    sign_of = {-1: 0}
    for f, c in enumerate(cov.coverage):
        sign_of[f] = (c > 0) - (c < 0)
    boundary = []
    for h, f in enumerate(arr.half_edge_face):
        s = sign_of[f]
        if s != 0 and sign_of[arr.half_edge_face[h ^ 1]] != s:
            boundary.append((h, s))
    return MergeResult(arr, faces, signs, [cov.coverage[f] for f in faces], boundary)


# --------------------------------------------------------------------------------------------
# triangulation of a face (step 3)
# --------------------------------------------------------------------------------------------


def _strip_spikes(cycle: list) -> list:
    """Remove back-and-forth excursions ``a b a`` (dangling edges) from a cyclic vertex list;
    an empty list when nothing with area is left."""
    out = list(cycle)
    while len(out) >= 3:
        n = len(out)
        for k in range(n):
            if out[k - 1] == out[(k + 1) % n]:
                for idx in sorted({k, (k + 1) % n}, reverse=True):
                    del out[idx]
                break
        else:
            return out
    return []


def _half(a, d) -> int:
    c = _cross(a, d)
    return 0 if (c > 0 or (c == 0 and _dot(a, d) > 0)) else 1


def _in_cone(d, a, b) -> bool:
    """Is the direction ``d`` strictly inside the counter-clockwise sweep from ``a`` to ``b``?
    When ``b`` has the direction of ``a`` the sweep is a full turn (all but that direction)."""
    hd = _half(a, d)
    if hd == 0 and _cross(a, d) == 0:  # d along a
        return False
    hb = _half(a, b)
    if hb == 0 and _cross(a, b) == 0:  # full turn
        return True
    if hd != hb:
        return hd < hb
    return _cross(d, b) > 0


def _proper_cross(a, b, c, d) -> bool:
    """Do the open segments ``ab`` and ``cd`` (homogeneous points) cross at a single interior
    point of both."""
    o1, o2 = _horient(a, b, c), _horient(a, b, d)
    o3, o4 = _horient(c, d, a), _horient(c, d, b)
    return o1 * o2 < 0 and o3 * o4 < 0


def _in_closed_triangle(p, a, b, c) -> bool:
    return _horient(a, b, p) >= 0 and _horient(b, c, p) >= 0 and _horient(c, a, p) >= 0


def _bridge_ok(P, i, H, j, others) -> bool:
    """Can the polygon occurrence ``P[i]`` be joined to the hole occurrence ``H[j]``?"""
    o, h = P[i], H[j]
    if o == h:
        return False
    d = _hdir(o, h)
    if not _in_cone(d, _hdir(o, P[(i + 1) % len(P)]), _hdir(o, P[i - 1])):
        return False
    e = _hdir(h, o)
    if not _in_cone(e, _hdir(h, H[(j + 1) % len(H)]), _hdir(h, H[j - 1])):
        return False
    for ring in others:
        n = len(ring)
        for k in range(n):
            a, b = ring[k], ring[(k + 1) % n]
            if a != o and a != h and _hon_segment(a, o, h):
                return False
            if _proper_cross(a, b, o, h):
                return False
    return True


def _ear_ok(poly, i) -> bool:
    """The general ear test (repeated vertices allowed, e.g. after bridging holes)."""
    n = len(poly)
    p, v, q = poly[i - 1], poly[i], poly[(i + 1) % n]
    if _horient(p, v, q) <= 0:
        return False
    corners = (p, v, q)
    ears = {(i - 1) % n, i}  # edge k joins poly[k] -> poly[k + 1]
    cones = {
        v: (_hdir(v, q), _hdir(v, p)),
        p: (_hdir(p, v), _hdir(p, q)),
        q: (_hdir(q, p), _hdir(q, v)),
    }
    for k in range(n):
        a, b = poly[k], poly[(k + 1) % n]
        if a not in corners and _in_closed_triangle(a, p, v, q):
            return False
        if k in ears:
            continue
        if _proper_cross(a, b, p, q):
            return False
        for s, t in ((a, b), (b, a)):
            if s in cones and t != s:
                lo, hi = cones[s]
                d = _hdir(s, t)
                if _cross(lo, d) > 0 and _cross(d, hi) > 0:
                    return False
    return True


def _straight_runs(ring: list, H: list, runs: dict, uses: dict) -> tuple[list, bool]:
    """(Reference of ``cspace._kernels.planar.straight_runs``.) Drop the vertices where a cycle goes straight on (collinear, same direction) and which
    no other cycle or other visit uses (``uses[v] == 1``); record each dropped run in
    ``runs[(a, b)]`` under the directed edge ``a -> b`` of the corners around it. Returns the
    corners (``[]`` if fewer than three are left) and whether every corner turns strictly
    left (the runs lie on the segments between corners, so the turn at a corner is the one
    between its cycle neighbours)."""
    n = len(ring)
    keep = []
    convex = True
    for k in range(n):
        a, v, b = H[ring[k - 1]], H[ring[k]], H[ring[(k + 1) % n]]
        o = _horient(a, v, b)
        if uses[ring[k]] > 1 or o != 0 or _dot(_hdir(a, v), _hdir(v, b)) <= 0:
            keep.append(k)
            convex = convex and o > 0
    if len(keep) < 3:
        return [], False
    for x, y in zip(keep, keep[1:] + keep[:1]):
        between = [ring[k % n] for k in range(x + 1, y if y > x else y + n)]
        if between:
            runs[(ring[x], ring[y])] = between
    return [ring[k] for k in keep], convex


def _clip_simple(P: list, ids: list):
    """(Reference of ``cspace._kernels.planar.clip_simple``.) Ear clipping of a simple counter-clockwise polygon (distinct vertices): an ear is a
    convex corner whose closed triangle holds no other non-convex vertex (a vertex inside a
    simple polygon's ear triangle implies a reflex one inside). Returns the triangles, or None
    when it stalls (degenerate input: the caller falls back to the general test)."""
    n = len(P)
    prv = [k - 1 for k in range(n)]
    prv[0] = n - 1
    nxt = [k + 1 for k in range(n)]
    nxt[-1] = 0

    def convex(k):
        return _horient(P[prv[k]], P[k], P[nxt[k]]) > 0

    conv = [convex(k) for k in range(n)]
    reflex = {k for k in range(n) if not conv[k]}
    tris = []
    k, left, stall = 0, n, 0
    while left > 3:
        p, q = prv[k], nxt[k]
        if conv[k] and not any(
            r != p and r != q and _in_closed_triangle(P[r], P[p], P[k], P[q]) for r in reflex
        ):
            tris.append((ids[p], ids[k], ids[q]))
            nxt[p], prv[q] = q, p
            reflex.discard(k)
            left -= 1
            for j in (p, q):
                conv[j] = convex(j)
                if conv[j]:
                    reflex.discard(j)
                else:
                    reflex.add(j)
            k, stall = p, 0
        else:
            k, stall = nxt[k], stall + 1
            if stall > left:
                return None
    p, q = prv[k], nxt[k]
    if _horient(P[p], P[k], P[q]) > 0:
        tris.append((ids[p], ids[k], ids[q]))
    return tris


def _clip_general(P: list, ids: list) -> list:
    """(Reference of ``cspace._kernels.planar.clip_general``.) Ear clipping of any polygon
    (vertices may repeat, as after bridging holes), with the general ear test."""
    tris = []
    P, ids = list(P), list(ids)
    while len(P) > 3:
        n = len(P)
        for i in range(n):
            if _ear_ok(P, i):
                tris.append((ids[i - 1], ids[i], ids[(i + 1) % n]))
                del P[i]
                del ids[i]
                break
        else:
            if _hturn(P) == 0:
                return tris
            raise AssertionError("ear clipping found no ear")  # pragma: no cover
    if len(P) == 3 and _horient(*P) > 0:
        tris.append(tuple(ids))
    return tris


def _split_runs(tris: list, runs: dict) -> list:
    """Put the dropped straight-run vertices back: a triangle with a boundary edge ``a -> b``
    carrying a run is fanned from its opposite corner (the run lies on that edge, so no
    T-junction is left)."""
    if not runs:
        return tris
    out, work = [], list(tris)
    while work:
        t = work.pop()
        for k in range(3):
            a, b, c = t[k], t[(k + 1) % 3], t[(k + 2) % 3]
            run = runs.get((a, b))
            if run:
                chain = [a, *run, b]
                work.extend((x, y, c) for x, y in zip(chain, chain[1:]))
                break
        else:
            out.append(t)
    return out


def triangulate_face(arr: Arrangement2D, f: int) -> list:
    """Triangulate a bounded face (with its holes) without new vertices, exactly: the
    :func:`triangulate_rings` of its cycles."""
    face = arr.faces[f]
    return triangulate_rings(arr._H, [arr.cycle_vertices(c) for c in (face.outer, *face.holes)])


def triangulate_rings(H, rings: list) -> list:
    """Triangulate a face given by its boundary cycles, without new vertices, exactly.

    ``H[v]`` is the canonical homogeneous point ``(x, y, w)`` (primitive, ``w > 0``: points
    are compared as tuples) of vertex id ``v``; ``rings`` are the face's cycles as vertex-id
    lists, the outer one (counter-clockwise) first, then the holes, as an
    :class:`Arrangement2D` traces them (dangling excursions included). Returns
    counter-clockwise triangles as triples of vertex ids. The triangles tile the face (their
    areas sum to ``face.area``) and meet the face boundary only at its
    vertices: every vertex lying on the outer boundary or on a hole boundary with non-zero
    extent is a triangle corner (no T-junctions there). Dangling edges, tree-shaped holes and
    isolated vertices carry no area and are *not* constraints: their vertices may lie inside
    a triangle or on one of its edges.

    Algorithm (homogeneous integer points, exact predicates): strip dangling excursions from
    the cycles and set aside the vertices where a cycle goes straight on; bridge each hole to
    the outer polygon by a segment joining two mutually visible vertex occurrences (exact cone
    and crossing tests; holes that only see other holes wait for a later round); ear clipping
    (simple polygons: convex corners tested against the non-convex vertices only; after
    bridging, an ear test that also rejects any edge crossing the diagonal and any edge
    leaving a corner into the ear); last, each set-aside run is put back by fanning the
    triangle on its edge from the opposite corner. About O(n r) predicates for n corners and r
    non-convex ones on simple faces, O(n^3) with holes.
    """
    rings = [_strip_spikes(ring) for ring in rings]
    uses: dict = {}
    for ring in rings:
        for v in ring:
            uses[v] = uses.get(v, 0) + 1
    runs: dict = {}
    rings = [_compiled.straight_runs(ring, H, runs, uses) for ring in rings]
    (poly, convex), holes = rings[0], [h for h, _ in rings[1:] if h]
    if not poly:
        return []
    P = [H[v] for v in poly]
    ids = list(poly)
    pending = [([H[v] for v in h], list(h)) for h in holes]
    pending_holes = bool(pending)
    while pending:
        others = [P] + [hp for hp, _ in pending]
        done = False
        for hi, (HP, Hid) in enumerate(pending):
            # nearest pairs first (a heuristic order: any visible pair is correct)
            fp = [(x / w, y / w) for x, y, w in P]
            fh = [(x / w, y / w) for x, y, w in HP]
            cands = sorted(
                ((fh[j][0] - fp[i][0]) ** 2 + (fh[j][1] - fp[i][1]) ** 2, i, j)
                for i in range(len(P)) for j in range(len(HP))
            )
            for _, i, j in cands:
                if _bridge_ok(P, i, HP, j, others):
                    P = P[: i + 1] + HP[j:] + HP[:j] + [HP[j], P[i]] + P[i + 1:]
                    ids = ids[: i + 1] + Hid[j:] + Hid[:j] + [Hid[j], ids[i]] + ids[i + 1:]
                    pending.pop(hi)
                    done = True
                    break
            if done:
                break
        if not done:  # pragma: no cover - a visible pair always exists
            raise AssertionError("no bridge found for a hole")
    tris = None
    if len(set(ids)) == len(ids):
        if convex and not pending_holes:
            # strictly convex corners: a fan (the straight runs go back in below)
            tris = [(ids[0], ids[k], ids[k + 1]) for k in range(1, len(P) - 1)]
        else:
            tris = _compiled.clip_simple(P, ids)
    if tris is None:
        tris = _compiled.clip_general(P, ids)
    return _split_runs(tris, runs)


def known_triangles(arr: Arrangement2D, f: int) -> list | None:
    """The triangles of face ``f`` if they cost nothing: already made by
    :func:`face_triangles`, or the face itself when it is a triangle without holes; else
    None."""
    tris = arr._tris.get(f)
    if tris is None:
        face = arr.faces[f]
        if not face.holes and len(face.outer) == 3:
            tris = arr._tris[f] = [tuple(arr.cycle_vertices(face.outer))]
    return tris


def face_triangles(arr: Arrangement2D, f: int) -> list:
    """:func:`triangulate_face`, computed once per face (cached on the arrangement); a
    triangle face without holes is its own triangle."""
    tris = known_triangles(arr, f)
    if tris is None:
        tris = arr._tris[f] = triangulate_face(arr, f)
    return tris


def plain_interior(arr: Arrangement2D, f: int) -> bool:
    """No dangling edge, bridge or isolated vertex lies in face ``f``: then nothing of the
    arrangement meets the open triangles of :func:`face_triangles`."""
    return f not in arr._cluttered


def strict_inner_point(arr: Arrangement2D, f: int) -> tuple[int, int, int]:
    """Canonical homogeneous point strictly inside face ``f``: on no edge and no vertex of
    the arrangement (isolated vertices included). The centroid of the first triangle of
    :func:`face_triangles` when the face has a :func:`plain_interior`, else
    :attr:`Face.sample`."""
    if plain_interior(arr, f):
        return arr._inner_point(f)
    return _hom(arr.faces[f].sample)
