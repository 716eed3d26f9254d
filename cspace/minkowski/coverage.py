"""NCC-CVMS step 2: net signed coverage of oriented polygons in one plane.

:func:`polygon_coverage` and :func:`sampled_coverage` give every face of an arrangement its
signed multiplicity (coplanar conjoint facets merge, opposite conjoint ones cancel);
:func:`merge_coplanar` merges a plane's polygons; :func:`pushed_inside` reads the coverage just
inside an edge. Exact throughout (:mod:`cspace.geometry.homogeneous`).
"""

from __future__ import annotations

from collections import deque
from dataclasses import dataclass
from fractions import Fraction
from math import gcd

import numpy as np

from ..geometry._kernels import load
from ..geometry.homogeneous import _dot, _hdir, _hom, _hpoint, _hturn
from .plane_arrangement import Arrangement2D
from .triangulation import inner_point

_planar = load("planar")

__all__ = [
    "Coverage",
    "MergeResult",
    "polygon_coverage",
    "sampled_coverage",
    "pushed_inside",
    "merge_coplanar",
]


# Up to this many polygons sampled_coverage filters them by boxes in plain Python.
_FEW_POLYGONS = 16


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
    points : list or None
        Where :func:`sampled_coverage` read each face (its :func:`sample_point`), else None.
    first : list or None
        Per face, the first polygon holding that point, oriented by :func:`sampled_coverage`'s
        ``source_turn`` (-1: none; None where not asked).
    """

    arrangement: Arrangement2D
    coverage: list
    support: list = None
    points: list = None
    first: list = None

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


def polygon_coverage(polygons, weights=None, cuts=()) -> Coverage:
    """Net signed coverage of oriented closed polygons in one plane.

    Parameters
    ----------
    polygons : sequence of sequences of points
        Each polygon is a closed polyline (last vertex joined to the first), vertices as
        accepted by :func:`cspace.geometry.homogeneous.to_point`. Counter-clockwise polygons count positively. Simple
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


def _rational_sum(terms: list) -> tuple[int, int]:
    """``sum(num / den for den, num in terms)`` as ``(num, den)``, ``den > 0``, summed in pairs
    (a balanced tree): a running sum's denominator grows with every term, and adding the
    next term to it costs in proportion, so summing a plane's faces one by one took time
    quadratic in the bits (seconds on a plane of a few thousand faces)."""
    terms = [(n, d) for d, n in terms if n]
    while len(terms) > 1:
        nxt = []
        for k in range(0, len(terms) - 1, 2):
            (a, b), (c, d) = terms[k], terms[k + 1]
            g = gcd(b, d)
            nxt.append((a * (d // g) + c * (b // g), b // g * d))
        if len(terms) % 2:
            nxt.append(terms[-1])
        terms = nxt
    return terms[0] if terms else (0, 1)


def sample_point(arr: Arrangement2D, f: int) -> tuple[int, int, int]:
    """The canonical homogeneous point strictly inside bounded face ``f`` at which
    :func:`sampled_coverage` reads it: the centroid of a triangle without holes or isolated
    vertices, else the face's :attr:`~cspace.minkowski.plane_arrangement.Face.sample`
    (no triangulation: most faces are never output)."""
    face = arr.faces[f]
    if not face.holes and not face.isolated and len(face.outer) == 3:
        return inner_point(arr, f)
    return _hom(face.sample)


def _face_coverage(arr: Arrangement2D, polys: list, turn: list, weights: list,
                   boxes: list, source_turn=None) -> tuple[list, list, dict, list, list]:
    """The per-face loop of :func:`sampled_coverage` (the reference of the compiled
    ``_kernels.planar.face_coverage``): coverage and support of each face at its
    :func:`sample_point`, twice the integral of the coverage as ``{den: num}``, the points,
    and the first polygon holding each point oriented by ``source_turn`` (-1: none)."""
    box = np.array(boxes, dtype=np.float64).reshape(-1, 4) if len(polys) > _FEW_POLYGONS else None
    nf = len(arr.faces)
    coverage, support, points, first = [0] * nf, [0] * nf, [None] * nf, [-1] * nf
    terms: dict = {}
    for f, face in enumerate(arr.faces):
        X, Y, w = points[f] = sample_point(arr, f)
        xf, yf = X / w, Y / w
        # conservative box filter: floats are within an ulp; integer boxes, margin 1
        if box is None:
            near = [i for i, b in enumerate(boxes) if b[0] <= xf <= b[1] and b[2] <= yf <= b[3]]
        else:
            near = np.nonzero((box[:, 0] <= xf) & (xf <= box[:, 1])
                              & (box[:, 2] <= yf) & (yf <= box[:, 3]))[0].tolist()
        c = s = 0
        for i in near:
            inside = pushed_inside(polys[i], turn[i], X, Y, w)
            if inside:
                c += weights[i] * turn[i]
                s += abs(weights[i])
            if first[f] < 0 and source_turn is not None:
                if source_turn[i] != turn[i]:
                    inside = pushed_inside(polys[i], source_turn[i], X, Y, w)
                if inside:
                    first[f] = i
        coverage[f], support[f] = c, s
        if c:  # integral += c * face.area, as twice the areas
            n, d = arr._face_area2(face)
            terms[d] = terms.get(d, 0) + c * n
    return coverage, support, terms, points, first


def sampled_coverage(polygons, weights, segments, labels=None, *, canonical: bool = False,
                     compiled: bool = True, source_turn=None) -> Coverage:
    """Net and unsigned coverage of the faces of the arrangement of ``segments`` by convex
    oriented polygons, read at one point per face.

    Unlike :func:`polygon_coverage` the polygon edges are not in the arrangement, so its faces
    are not cut by them. The result is right only when the coverage is constant on every
    face, i.e. when ``segments`` contain every point where the net or the unsigned coverage
    changes: the caller's invariant (:class:`cspace.minkowski.arrangements._PlaneJobs` passes
    the cuts and every edge shared with another plane or whose uses do not cancel). It is
    certified in part: the integral of the coverage over the faces must equal
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
        (``sample_f``: :func:`sample_point`; the push moves a sample lying on a polygon edge
        off it, into the face). ``compiled=False`` runs the per-face loop's Python reference;
        with ``source_turn`` (an orientation per polygon) :attr:`Coverage.first` names, per
        face, the first polygon so oriented that holds the pushed point.
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
    if compiled:
        cycles = arr._cycles
        face_cycles = [[cycles[c] for c in face._cycles] for face in arr.faces]
        others = [[v for c in face.holes for v in arr.cycle_vertices(c)] + face.isolated
                  for face in arr.faces]
        coverage, support, terms, points, first = _planar.face_coverage(
            arr._H, arr.half_edge_origin, face_cycles, others, polys, turn, weights, boxes,
            source_turn)
        # a face holding a bridge or an isolated vertex was read at its strict sample: keep
        # it (strict_inner_point asks for it again)
        for f in arr._cluttered:
            if f >= 0:
                X, Y, W = points[f]
                arr.faces[f].sample = (Fraction(X, W), Fraction(Y, W))
    else:
        coverage, support, terms, points, first = _face_coverage(arr, polys, turn, weights,
                                                                 boxes, source_turn)
    num, den = _rational_sum(list(terms.items()))
    if num != area2 * den:
        raise ValueError("the coverage is not constant on the faces: the segments miss a place "
                         "where it changes")
    return Coverage(arr, coverage, support, points, first if source_turn is not None else None)


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
