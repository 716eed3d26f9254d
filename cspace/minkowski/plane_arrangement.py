"""Exact planar arrangements of segments: NCC-CVMS step 6, one arrangement per supporting plane.

Each plane of the superset, projected to a coordinate plane, gets one :class:`Arrangement2D` of
its triangles' edges and of the segments where other planes' triangles cut it (paper §3.1–3.2;
the paper builds one per triangle, ``docs/trimming.md`` says why one per plane). Net signed
coverage of its faces (step 2): :mod:`cspace.minkowski.coverage`; triangulation of its faces
(step 3): :mod:`cspace.minkowski.triangulation`.

Everything is exact: coordinates are :class:`fractions.Fraction` (constructed intersection points
are rationals), every decision is the exact sign of a rational expression. No epsilon, no atan2:
half-edges are ordered around a vertex by a half-plane test and a cross-product sign.

The structures are meant for small inputs (a handful to a few dozen segments); see
:class:`Arrangement2D` for the complexity. The combinatorial core of an arrangement (crossings,
pieces, half-edge cycles) runs compiled (:mod:`cspace.geometry._kernels.planar`); its pure-Python
reference is :func:`_arrangement_core`.
"""

from __future__ import annotations

import weakref
from dataclasses import dataclass, field
from fractions import Fraction
from functools import cached_property, cmp_to_key
from math import gcd

import numpy as np

from ..geometry._kernels import load
from ..geometry.boxes import box_pairs
from ..geometry.homogeneous import (
    _Ratio,
    _angle_cmp,
    _float_key,
    _hbetween,
    _hcross3,
    _hdir,
    _hnorm,
    _hom,
    _hon_segment,
    _hpoint,
    _hwinding,
    to_point,
)

__all__ = ["Face", "Arrangement2D"]


_compiled = load("planar")


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
    :func:`cspace.geometry._kernels.planar.arrangement_core`, which returns the same.

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


def ring_sample(H: list, ring: list, others=()) -> tuple:
    """A point strictly inside the bounded face whose outer cycle visits the vertices ``ring``
    (ids into the canonical homogeneous points ``H``) and whose holes and isolated vertices are
    ``others``: an exact Fraction pair (:meth:`Arrangement2D._sample`'s; the reference of the
    compiled ``_kernels.planar.ring_inner_point``).

    Let ``y0`` be the lowest y of the outer boundary and ``y1`` the next distinct y among the
    face's boundary vertices and isolated vertices (holes lie strictly above ``y0``). In the
    open slab ``y0 < y < y1`` only outer-boundary edges are present and none ends there, so
    on the line ``y = (y0 + y1) / 2`` some gap between consecutive crossings lies in the face:
    the first gap with non-zero winding of the outer cycle.
    """
    ids = set(ring)
    ids.update(others)
    # Exact y's are Fractions only where the floats (each y = Y / W correctly rounded, so
    # a smaller float means a smaller y) do not decide: the lowest y and the next one up.
    fy = {v: H[v][1] / H[v][2] for v in ids}
    low = min(fy.values())
    first = [Fraction(H[v][1], H[v][2]) for v in ids if fy[v] == low]
    y0 = min(first)
    above = [y for y in first if y > y0]
    rest = [fy[v] for v in ids if fy[v] > low]
    if rest:
        nxt = min(rest)
        above += [Fraction(H[v][1], H[v][2]) for v in ids if fy[v] == nxt]
    y1 = min(above)
    ym = (y0 + y1) / 2
    fm, N, D = float(ym), ym.numerator, ym.denominator

    def below(v) -> bool:  # y(v) < ym; never equal (no vertex lies strictly between)
        return fy[v] < fm or (fy[v] == fm and H[v][1] * D < N * H[v][2])

    # Each crossing of the line y = ym as an integer ratio ``num / den`` (den > 0), with
    # its float for sorting; equal floats are ordered exactly.
    xs = []
    for k, u in enumerate(ring):
        v = ring[k + 1] if k + 1 < len(ring) else ring[0]
        if below(u) != below(v):
            (Xa, Ya, Wa), (Xb, Yb, Wb) = H[u], H[v]
            dy = Yb * Wa - Ya * Wb  # (by - ay) Wa Wb
            num = Xa * D * dy + (N * Wa - Ya * D) * (Xb * Wa - Xa * Wb)
            den = D * Wa * dy
            if den < 0:
                num, den = -num, -den
            xs.append((num / den, num, den, 1 if dy > 0 else -1))
    xs.sort(key=lambda t: t[0])
    for k in range(len(xs) - 1):  # float ties: exact order (rare)
        if xs[k][0] == xs[k + 1][0]:
            xs.sort(key=lambda t: (t[0], Fraction(t[1], t[2])))
            break

    def less(a, b) -> bool:
        return a[0] < b[0] or (a[0] == b[0] and a[1] * b[2] < b[1] * a[2])

    # winding of a point at x: edges to the right going up count +1 (ccw), down -1
    w = sum(t[3] for t in xs)
    for a, b in zip(xs, xs[1:]):
        w -= a[3]
        if w != 0 and less(a, b):
            return ((Fraction(a[1], a[2]) + Fraction(b[1], b[2])) / 2, ym)
    raise AssertionError("no interior sample found")  # pragma: no cover


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
        """A point strictly inside a bounded face (:func:`ring_sample` of its outer cycle,
        its holes' and isolated vertices bounding the slab)."""
        if face is self.unbounded:  # left of the smallest point
            if not self._H:
                return (Fraction(0), Fraction(0))
            h0 = self._H[0]
            return (Fraction(h0[0], h0[2]) - 1, Fraction(h0[1], h0[2]))
        origin = self.half_edge_origin
        others = [origin[h] for c in face.holes for h in c]
        others += face.isolated
        return ring_sample(self._H, [origin[h] for h in face.outer], others)

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
