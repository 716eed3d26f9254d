"""NCC-CVMS steps 4–5: exact pairwise intersections of candidate triangle pairs.

Length: the classification is one case analysis (proper crossings, coplanar overlaps, shared
edges and vertices, segment–triangle contacts) that reads best in one place, beside the
pure-Python reference (:func:`_intersect_pairs_reference`) the compiled kernel is tested against.
Candidate pairs: :mod:`cspace.geometry.boxes`; endpoints: :mod:`cspace.geometry.endpoints`.

Works on a triangle soup on the integer grid: ``ints (n, 3) int64`` positions in grid units
and ``faces (t, 3) int64`` rows of vertex *labels* (indices into ``ints``), e.g.
``Superset.ints`` and ``Superset.triangles()[0]``. Labels are trusted to identify positions:
two labels are equal exactly when their positions are (measured on supersets, design notes
section 7; the caller must ensure it), so a shared label is a shared point, never recomputed.

- :func:`~cspace.geometry.boxes.candidate_pairs` (step 4): all pairs of triangles whose closed integer bounding
  boxes meet, by a sweep along one axis.
- :func:`intersect_pairs` (step 5): the exact class of each pair's intersection
  ``X = T_i ∩ T_j`` (closed triangles, possibly of zero area) and, for non-coplanar
  contacts, the endpoints of ``X`` as *symbolic* points: a vertex label, or an edge of one
  triangle crossing the supporting plane of the other.
- :func:`~cspace.geometry.endpoints.endpoint_coordinates`: canonical exact homogeneous coordinates of those points.

Every decision is the exact sign of an integer polynomial, from :mod:`cspace.geometry.exact` or from
Python integers in the numpy references, in 64/128-bit integers in the compiled kernel
(:mod:`cspace.geometry._kernels.arrangement`, which the public functions use); no tolerance is used
anywhere.

Method (non-coplanar pairs, after Möller 1997 and Guigue & Devillers 2003). With ``N_i``
the integer normal of triangle ``i`` and ``s`` the exact signs of each triangle's vertices
against the other's plane, each triangle meets the other's plane in a segment ``I_i`` on
the common line ``L`` (or not at all), and ``X = I_i ∩ I_j``. The endpoints of ``I_i`` along
``d = N_i x N_j`` follow from the sign pattern alone (a table over the 27 patterns, see
:func:`_side_tables`); each is a vertex of ``T_i`` on ``L`` or a crossing of one of its edges.
Two endpoints of different triangles are ordered along ``d`` by ONE orientation predicate
of input points: if ``P`` lies on the line ``pq`` in plane ``i`` and ``Q`` on the line ``rs``
in plane ``j``, then ``orient3d(p, q, r, s) = λ (s^j_p - s^j_q)(s^i_r - s^i_s)`` where
``Q - P = λ d`` and ``s^j_x = N_j · (x - v_j)`` (expand the determinant with ``p - P ∥ q - p``
and ``r - Q ∥ s - r``, then use ``(u x v)·(N_i x N_j) = -(u·N_j)(v·N_i)`` for ``u`` in plane
``i``, ``v`` in plane ``j``). The two factors are known from the signs, so four
``orient3d`` give the overlap, its endpoints and every coincidence exactly.
"""

from __future__ import annotations

import itertools
from dataclasses import dataclass

import numpy as np

from . import exact
from ..errors import ExactnessError, GridRangeError
from ._kernels import load

__all__ = [
    "TRITRI_CLASSES",
    "DISJOINT",
    "SHARED_EDGE",
    "SHARED_VERTEX",
    "POINT",
    "SEGMENT",
    "COPLANAR_OVERLAP",
    "COPLANAR_TOUCH",
    "NO_POINT",
    "VERTEX",
    "EDGE_PLANE",
    "TriTriResult",
    "intersect_pairs",
]


# The box sweep, the pair classification and the endpoint coordinates run compiled
# (cspace.geometry._kernels.arrangement); their numpy references are BoxSweep._pairs_reference,
# _intersect_pairs_reference and _endpoint_coordinates_reference, which they match exactly.
_compiled = load("arrangement")


#: Names of the pair classes, indexed by ``TriTriResult.cls``.
TRITRI_CLASSES = (
    "disjoint",
    "shared_edge",
    "shared_vertex",
    "point",
    "segment",
    "coplanar_overlap",
    "coplanar_touch",
)


DISJOINT, SHARED_EDGE, SHARED_VERTEX, POINT, SEGMENT, COPLANAR_OVERLAP, COPLANAR_TOUCH = range(7)


NO_POINT, VERTEX, EDGE_PLANE = 0, 1, 2


# Superset coordinates are |k| <= 2**28; below 2**29 every cross product of two coordinate
# differences stays below 2**61 (int64, and within the predicates' input range).
_MAX_COORD = 2**29


@dataclass(frozen=True, eq=False)
class TriTriResult:
    """Exact classification of triangle pairs, with symbolic intersection endpoints.

    Classes (``X`` is the intersection of the two closed triangles; a zero-area triangle is
    the segment between its extreme vertices; "coplanar" means all six vertices lie in one
    plane):

    - ``DISJOINT``: ``X`` is empty.
    - ``SHARED_EDGE``: ``X`` is exactly the segment between two labels of both triangles.
    - ``SHARED_VERTEX``: ``X`` is exactly one label of both triangles.
    - ``POINT``: not coplanar, ``X`` is one point that is not a shared label.
    - ``SEGMENT``: not coplanar, ``X`` is a segment of positive length (not a shared edge).
    - ``COPLANAR_OVERLAP``: coplanar and ``X`` has positive area.
    - ``COPLANAR_TOUCH``: coplanar, ``X`` has zero area and is more than a shared feature.

    Endpoints (columns 0 and 1) are given for ``SEGMENT`` and ``POINT`` (both columns hold
    the same point), and also for ``SHARED_EDGE`` (the two labels, smaller first) and
    ``SHARED_VERTEX`` (the label twice). For ``SEGMENT`` column 0 -> column 1 points along
    ``N_i x N_j`` (``i = pairs[:, 0]``, ``N`` the normal ``(b - a) x (c - a)`` of a face
    ``(a, b, c)``). A point that is a vertex is always given as that vertex; an edge–plane
    point is otherwise given by the edge (of either triangle) with the smallest label pair.

    Attributes
    ----------
    pairs : (k, 2) int64
        The triangle pairs, as given.
    cls : (k,) int8
        Index into :data:`TRITRI_CLASSES`.
    kind : (k, 2) int8
        Index into :data:`cspace.geometry.endpoints.ENDPOINT_KINDS`: no point, a vertex, an edge crossing a plane.
    u : (k, 2) int64
        The vertex label (``VERTEX``) or the smaller label of the edge (``EDGE_PLANE``), else -1.
    v : (k, 2) int64
        The larger label of the edge (``EDGE_PLANE``), else -1.
    plane : (k, 2) int64
        The triangle (row of ``faces``) whose supporting plane the edge crosses
        (``EDGE_PLANE``), else -1. The edge is an edge of the pair's other triangle.
    """

    pairs: np.ndarray
    cls: np.ndarray
    kind: np.ndarray
    u: np.ndarray
    v: np.ndarray
    plane: np.ndarray

    def __len__(self) -> int:
        return len(self.cls)

    def endpoint(self, row: int, col: int):
        """Symbolic endpoint ``col`` of pair ``row``: ``("v", i)``, ``("e", (u, v), t)`` or None."""
        k = int(self.kind[row, col])
        if k == VERTEX:
            return ("v", int(self.u[row, col]))
        if k == EDGE_PLANE:
            return ("e", (int(self.u[row, col]), int(self.v[row, col])), int(self.plane[row, col]))
        return None

    def counts(self) -> dict[str, int]:
        """Number of pairs in each class, by name."""
        c = np.bincount(self.cls.astype(np.int64), minlength=len(TRITRI_CLASSES))
        return {name: int(n) for name, n in zip(TRITRI_CLASSES, c)}


# --------------------------------------------------------------------------------------
# input checks


def _check_soup(ints, faces) -> tuple[np.ndarray, np.ndarray]:
    ints = np.asarray(ints)
    if ints.dtype.kind not in "iu":
        raise TypeError(f"ints must be integer grid coordinates, got dtype {ints.dtype}")
    if ints.ndim != 2 or ints.shape[1] != 3:
        raise ValueError(f"ints must be (n, 3), got shape {ints.shape}")
    ints = ints.astype(np.int64, copy=False)
    if ints.size and int(np.abs(ints).max()) >= _MAX_COORD:
        raise GridRangeError(f"grid coordinates must satisfy |k| < 2**29, got {int(np.abs(ints).max())}")
    faces = np.asarray(faces)
    if faces.dtype.kind not in "iu" or faces.ndim != 2 or faces.shape[1] != 3:
        raise ValueError(f"faces must be (t, 3) integer labels, got shape {faces.shape}, dtype {faces.dtype}")
    faces = faces.astype(np.int64, copy=False)
    if faces.size and (faces.min() < 0 or faces.max() >= len(ints)):
        raise ValueError(f"faces refer to labels outside [0, {len(ints)})")
    rep = (faces[:, 0] == faces[:, 1]) | (faces[:, 1] == faces[:, 2]) | (faces[:, 0] == faces[:, 2])
    if rep.any():
        raise ValueError(f"face {int(np.nonzero(rep)[0][0])} repeats a label; faces need three distinct labels")
    return ints, faces


def _check_pairs(pairs, n_faces: int) -> np.ndarray:
    pairs = np.asarray(pairs)
    if pairs.size == 0:
        return np.zeros((0, 2), dtype=np.int64)
    if pairs.dtype.kind not in "iu" or pairs.ndim != 2 or pairs.shape[1] != 2:
        raise ValueError(f"pairs must be (k, 2) integer, got shape {pairs.shape}, dtype {pairs.dtype}")
    pairs = pairs.astype(np.int64, copy=False)
    if pairs.min() < 0 or pairs.max() >= n_faces:
        raise ValueError(f"pairs refer to triangles outside [0, {n_faces})")
    if (pairs[:, 0] == pairs[:, 1]).any():
        raise ValueError("a pair joins a triangle with itself")
    return pairs


# --------------------------------------------------------------------------------------
# the side tables: where a triangle meets another triangle's plane, from the sign pattern

_EMPTY, _COPLANAR, _SINGLE, _INTERVAL = 0, 1, 2, 3


def _side_tables() -> tuple[np.ndarray, np.ndarray]:
    """For each sign pattern ``(s0, s1, s2)`` of a triangle's vertices against a plane.

    Index ``9 (s0 + 1) + 3 (s1 + 1) + (s2 + 1)``. Returns ``status (27,) int8`` (empty,
    coplanar, single point, interval) and ``ends (27, 2, 4) int64``: for the low (0) and high
    (1) end along ``d = N x M`` (``N`` this triangle's normal, ``M`` the plane's normal) the
    row ``(kind, i, j, f)``: a VERTEX ``i`` (``j`` is a corner off the plane) or an EDGE_PLANE
    crossing of edge ``(i, j)``; ``f = sign(s_i - s_j)`` is the factor the ordering predicate
    needs (see the module docstring).

    Derivation. Seen from ``N`` with the plane's positive side "up", ``d`` points left and the
    triangle is counter-clockwise, so its boundary runs down on the left and up on the right:
    an edge crossing from + to - is the left end (high along ``d``), from - to + the right end
    (low). A vertex on the line behaves like the crossing of the edge from its predecessor to
    its successor; an edge on the line is the bottom edge (traversed left to right) when the
    third corner is up, the top edge otherwise.
    """
    status = np.zeros(27, dtype=np.int8)
    ends = np.zeros((27, 2, 4), dtype=np.int64)
    for s in itertools.product((-1, 0, 1), repeat=3):
        idx = 9 * (s[0] + 1) + 3 * (s[1] + 1) + (s[2] + 1)
        if s == (0, 0, 0):
            status[idx] = _COPLANAR
            continue
        if 0 not in s and len(set(s)) == 1:
            status[idx] = _EMPTY
            continue
        found: dict[int, list] = {0: [], 1: []}
        single = False
        for i in range(3):
            n, p = (i + 1) % 3, (i + 2) % 3
            if s[i] * s[n] < 0:
                found[1 if s[i] > 0 else 0].append((EDGE_PLANE, i, n, s[i]))
            if s[i] != 0:
                continue
            if s[n] == 0:  # edge (i, n) on the line, third corner p
                up = s[p] > 0
                found[1 if up else 0].append((VERTEX, i, p, -s[p]))
                found[0 if up else 1].append((VERTEX, n, p, -s[p]))
            elif s[p] == 0:
                continue  # the edge (p, i): handled when i == p
            elif s[p] == s[n]:
                single = True
                found[0].append((VERTEX, i, n, -s[n]))
                found[1].append((VERTEX, i, n, -s[n]))
            else:
                found[0 if (s[p], s[n]) == (-1, 1) else 1].append((VERTEX, i, n, -s[n]))
        assert len(found[0]) == 1 and len(found[1]) == 1, (s, found)
        status[idx] = _SINGLE if single else _INTERVAL
        ends[idx, 0] = found[0][0]
        ends[idx, 1] = found[1][0]
    return status, ends


_STATUS, _ENDS = _side_tables()


def _pattern(s: np.ndarray) -> np.ndarray:
    s = s.astype(np.int64)
    return 9 * (s[:, 0] + 1) + 3 * (s[:, 1] + 1) + (s[:, 2] + 1)


# --------------------------------------------------------------------------------------
# step 5: exact pair intersection


class _Out:
    """Result arrays being filled (row-aligned with the pairs)."""

    def __init__(self, k: int):
        self.cls = np.full(k, -1, dtype=np.int8)
        self.kind = np.zeros((k, 2), dtype=np.int8)
        self.u = np.full((k, 2), -1, dtype=np.int64)
        self.v = np.full((k, 2), -1, dtype=np.int64)
        self.plane = np.full((k, 2), -1, dtype=np.int64)

    def set_vertices(self, rows, cls, a, b) -> None:
        self.cls[rows] = cls
        self.kind[rows] = VERTEX
        self.u[rows, 0] = a
        self.u[rows, 1] = b


def _plane_signs(ints, faces, normals, labels, plane_tri, skip) -> np.ndarray:
    """Exact signs of ``N_t · (x - t_0)`` for the points ``labels (m, 3)``, 0 where ``skip``."""
    out = np.zeros(labels.shape, dtype=np.int8)
    r, c = np.nonzero(~skip)
    if r.size:
        t = plane_tri[r]
        out[r, c] = exact.dot_sign(normals[t], ints[labels[r, c]] - ints[faces[t, 0]])
    return out


def intersect_pairs(ints, faces, pairs) -> TriTriResult:
    """Classify the intersection of each triangle pair exactly, with symbolic endpoints.

    Parameters
    ----------
    ints : (n, 3) int64
        Vertex positions in grid units (``|k| < 2**29``). Equal labels must mean equal
        positions and distinct labels distinct positions.
    faces : (t, 3) int64
        Triangles as three distinct vertex labels; zero-area (collinear) ones are allowed.
    pairs : (k, 2) int64
        Rows ``(i, j)`` of triangle indices, ``i != j`` (e.g. from :func:`cspace.geometry.boxes.candidate_pairs`).

    Returns
    -------
    TriTriResult
        Class and endpoints of every pair; see :class:`TriTriResult`.

    Notes
    -----
    How each case is decided (all predicates exact):

    - shared labels are found by comparing labels; a shared vertex's sign against the other
      plane is 0 without computation;
    - proper (non-zero area) pairs: signs of one triangle against the other's plane
      (``dot_sign`` with the exact int64 normal). All zero: coplanar (below). Two shared
      labels and not coplanar: SHARED_EDGE at once -- the first triangle meets the second's
      plane exactly in the shared edge (its third corner is off that plane), so nothing else
      can meet. One side strictly: DISJOINT. A triangle touching the other's plane only at a
      shared vertex: SHARED_VERTEX. Otherwise the same for the second triangle, then the
      interval overlap on the common line with four ``orient3d`` (module docstring); equal
      endpoints are found as exact zeros, and the description of a point is the vertex if
      any description is a vertex, else the edge with the smallest label pair.
    - a shared vertex alone never skips work: the triangles may also cross beyond it (then
      ``X`` is a SEGMENT starting at the vertex, ``X`` being convex).
    - coplanar proper pairs, in 2D after dropping the dominant axis of the normal
      (``orient2d``): the interiors meet iff no edge of either triangle has all three corners
      of the other on its closed outer side (separating axes: the edges of ``A - B`` are
      parallel to edges of A or B); the triangles are disjoint iff some edge has all three
      strictly outside. Touching pairs sharing an edge are SHARED_EDGE; sharing one vertex
      they are SHARED_VERTEX unless an edge of each leaves it in the same direction
      (collinear, positive dot product): the two corner cones have disjoint interiors, so a
      common ray is an edge of both.
    - one zero-area triangle (a segment) against a proper one, not coplanar: the segment's
      line crosses the plane at one point ``P`` (a vertex on the plane, or any crossing
      edge); ``P`` is in the closed triangle iff ``orient3d(p, q, e0, e1)`` over its three
      edges takes no two opposite strict signs; two zeros mean ``P`` is that triangle's vertex.
    - a segment in the plane of a proper triangle, and pairs of segments: separating axes
      and corner cones with ``orient2d``, or integer comparisons along a common line (see
      :func:`_segment_triangle_coplanar`, :func:`_segment_segment`).

    Cost: compiled (:func:`cspace.geometry._kernels.arrangement.intersect_pairs`), pair by pair, every
    predicate evaluated exactly in 64- or 128-bit integers (the bounds are in that module's
    docstring); about 0.1 µs per candidate pair on generic supersets. Its numpy reference,
    :func:`_intersect_pairs_reference`, gives identical results.

    Examples
    --------
    A triangle pierced by one whose third corner lies in the first one's plane:

    >>> import numpy as np
    >>> from cspace.geometry.boxes import candidate_pairs
    >>> from cspace.geometry.endpoints import endpoint_coordinates
    >>> ints = np.array([[0, 0, 0], [4, 0, 0], [0, 4, 0], [1, 1, -2], [1, 1, 2], [-3, 0, 0]])
    >>> faces = np.array([[0, 1, 2], [3, 4, 5]])
    >>> res = intersect_pairs(ints, faces, candidate_pairs(ints, faces))
    >>> TRITRI_CLASSES[res.cls[0]], res.endpoint(0, 0), res.endpoint(0, 1)
    ('segment', ('e', (0, 2), 1), ('e', (3, 4), 0))
    >>> exact_points, approx = endpoint_coordinates(ints, faces, res)
    >>> exact_points[0].tolist(), approx[0].tolist()
    ([(0, 3, 0, 4), (1, 1, 0, 1)], [[0.0, 0.75, 0.0], [1.0, 1.0, 0.0]])
    """
    ints, faces = _check_soup(ints, faces)
    pairs = _check_pairs(pairs, len(faces))
    cls, kind, u, v, plane = _compiled.intersect_pairs(
        np.ascontiguousarray(ints), np.ascontiguousarray(faces), np.ascontiguousarray(pairs),
        _STATUS, _ENDS,
    )
    if (cls < 0).any():  # every branch assigns a class; this is a certificate
        raise ExactnessError(f"{int((cls < 0).sum())} triangle pairs were left unclassified")
    return TriTriResult(pairs=pairs, cls=cls, kind=kind, u=u, v=v, plane=plane)


def _intersect_pairs_reference(ints, faces, pairs) -> TriTriResult:
    """:func:`intersect_pairs` in numpy, vectorised over the pairs (the reference of the
    compiled kernel, which must return identical arrays): predicates from
    :mod:`cspace.geometry.exact` (float filter, then Python integers)."""
    ints, faces = _check_soup(ints, faces)
    pairs = _check_pairs(pairs, len(faces))
    k = len(pairs)
    out = _Out(k)
    if k == 0:
        return _result(pairs, out)
    V = ints[faces]
    normals = exact.cross(V[:, 1] - V[:, 0], V[:, 2] - V[:, 0])
    deg = ~normals.any(axis=1)
    da, db = deg[pairs[:, 0]], deg[pairs[:, 1]]
    ctx = (ints, faces, normals, pairs, out)
    rows = np.nonzero(~da & ~db)[0]
    if rows.size:
        _proper(ctx, rows)
    rows = np.nonzero(da ^ db)[0]
    if rows.size:
        _segment_triangle(ctx, rows, swap=da[rows])
    rows = np.nonzero(da & db)[0]
    if rows.size:
        _segment_segment(ctx, rows)
    if (out.cls < 0).any():  # every branch above assigns a class; this is a certificate
        raise ExactnessError(f"{int((out.cls < 0).sum())} triangle pairs were left unclassified")
    return _result(pairs, out)


def _result(pairs, out: _Out) -> TriTriResult:
    return TriTriResult(pairs=pairs, cls=out.cls, kind=out.kind, u=out.u, v=out.v, plane=out.plane)


def _shared(FA: np.ndarray, FB: np.ndarray):
    eq = FA[:, :, None] == FB[:, None, :]
    return eq.any(axis=2), eq.any(axis=1)


def _proper(ctx, rows: np.ndarray) -> None:
    """Pairs of two non-zero-area triangles."""
    ints, faces, normals, pairs, out = ctx
    ta, tb = pairs[rows, 0], pairs[rows, 1]
    FA, FB = faces[ta], faces[tb]
    shA, shB = _shared(FA, FB)
    nsh = shA.sum(axis=1)
    sA = _plane_signs(ints, faces, normals, FA, tb, shA)
    cop = ~sA.any(axis=1)
    if cop.any():
        _coplanar_proper(ctx, rows[cop])
    live = ~cop

    # Two shared labels, not coplanar: X is exactly the shared edge, nothing else to do.
    # Proof: A's two shared corners lie on B's plane and its third corner does not (else
    # coplanar), so A meets B's plane exactly in the shared edge; X is inside A ∩ plane(B)
    # and contains the edge. (One shared vertex proves nothing: the triangles may also cross
    # elsewhere, X then being a segment from that vertex; those pairs go on below.)
    se = live & (nsh == 2)
    if se.any():
        a = np.where(shA[se], FA[se], np.iinfo(np.int64).max).min(axis=1)
        b = np.where(shA[se], FA[se], -1).max(axis=1)
        out.set_vertices(rows[se], SHARED_EDGE, a, b)
    live &= ~se

    pa = _pattern(sA)
    sta = _STATUS[pa]
    dis = live & (sta == _EMPTY)
    out.cls[rows[dis]] = DISJOINT
    live &= ~dis
    # A meets B's plane only at a shared vertex: that vertex is in B, so X is that vertex.
    z = _ENDS[pa, 0, 1]
    sv = live & (sta == _SINGLE) & shA[np.arange(len(rows)), z]
    if sv.any():
        lab = FA[sv, z[sv]]
        out.set_vertices(rows[sv], SHARED_VERTEX, lab, lab)
    live &= ~sv
    if not live.any():
        return

    sel = np.nonzero(live)[0]
    rows, ta, tb, FA, FB, shA, shB, pa = rows[sel], ta[sel], tb[sel], FA[sel], FB[sel], shA[sel], shB[sel], pa[sel]
    sB = _plane_signs(ints, faces, normals, FB, ta, shB)
    pb = _pattern(sB)
    stb = _STATUS[pb]
    # B cannot be coplanar with A here: A has a corner off B's plane.
    dis = stb == _EMPTY
    out.cls[rows[dis]] = DISJOINT
    z = _ENDS[pb, 0, 1]
    sv = ~dis & (stb == _SINGLE) & shB[np.arange(len(rows)), z]
    if sv.any():
        lab = FB[sv, z[sv]]
        out.set_vertices(rows[sv], SHARED_VERTEX, lab, lab)
    live = ~dis & ~sv
    if not live.any():
        return
    sel = np.nonzero(live)[0]
    _interval(ctx, rows[sel], FA[sel], FB[sel], pa[sel], pb[sel], _STATUS[pa[sel]], stb[sel])


def _interval(ctx, rows, FA, FB, pa, pb, sta, stb) -> None:
    """Overlap of the two segments on the common line, decided with four orient3d."""
    ints, faces, normals, pairs, out = ctx
    m = len(rows)
    n = len(ints)
    ar = np.arange(m)
    # Descriptors (kind, i, j, f): A's ends along d = N_A x N_B, B's along N_B x N_A = -d.
    A_lo, A_hi = _ENDS[pa, 0], _ENDS[pa, 1]
    B_lo, B_hi = _ENDS[pb, 1], _ENDS[pb, 0]

    def labels(F, e):
        return F[ar, e[:, 1]], F[ar, e[:, 2]]

    def key(F, e):
        p, q = labels(F, e)
        lo_, hi_ = np.minimum(p, q), np.maximum(p, q)
        return np.where(e[:, 0] == VERTEX, p, n + lo_ * n + hi_)

    def cmp(ea, eb):
        """sign(d · (Q - P)) for P = ea (on A), Q = eb (on B)."""
        p, q = labels(FA, ea)
        r, s = labels(FB, eb)
        res = np.zeros(m, dtype=np.int8)
        # Identical vertices (a shared label) coincide; skip the trivially zero predicate.
        same = (ea[:, 0] == VERTEX) & (eb[:, 0] == VERTEX) & (p == r)
        c = ~same
        if c.any():
            o = exact.orient3d(ints[p[c]], ints[q[c]], ints[r[c]], ints[s[c]])
            res[c] = o * ea[c, 3] * eb[c, 3]
        return res

    c_ll = cmp(A_lo, B_lo)  # > 0: B_lo above A_lo
    c_hh = cmp(A_hi, B_hi)
    c_lh = cmp(A_lo, B_hi)
    c_hl = cmp(A_hi, B_lo)
    dis = (c_lh < 0) | (c_hl > 0)
    out.cls[rows[dis]] = DISJOINT
    live = ~dis
    loA, loB = c_ll <= 0, c_ll >= 0  # which lows are the maximum
    hiA, hiB = c_hh >= 0, c_hh <= 0  # which highs are the minimum
    pt = (
        (loA & hiA & (sta == _SINGLE))
        | (loB & hiB & (stb == _SINGLE))
        | (loA & hiB & (c_lh == 0))
        | (loB & hiA & (c_hl == 0))
    )
    big = np.iinfo(np.int64).max
    keys = np.stack([key(FA, A_lo), key(FB, B_lo), key(FA, A_hi), key(FB, B_hi)], axis=1)
    cand_lo = np.stack([loA, loB, pt & hiA, pt & hiB], axis=1)
    cand_hi = np.stack([pt & loA, pt & loB, hiA, hiB], axis=1)
    pick_lo = np.where(cand_lo, keys, big).argmin(axis=1)
    pick_hi = np.where(cand_hi, keys, big).argmin(axis=1)
    desc = np.stack([A_lo, B_lo, A_hi, B_hi], axis=1)  # (m, 4, 4)
    side = np.array([0, 1, 0, 1])
    sel = np.nonzero(live)[0]
    r = rows[sel]
    for col, pick in ((0, pick_lo), (1, pick_hi)):
        e = desc[sel, pick[sel]]
        onB = side[pick[sel]] == 1
        F = np.where(onB[:, None], FB[sel], FA[sel])
        p = F[np.arange(len(sel)), e[:, 1]]
        q = F[np.arange(len(sel)), e[:, 2]]
        isv = e[:, 0] == VERTEX
        out.kind[r, col] = e[:, 0]
        out.u[r, col] = np.where(isv, p, np.minimum(p, q))
        out.v[r, col] = np.where(isv, -1, np.maximum(p, q))
        # The edge of one triangle crosses the other's plane.
        other = np.where(onB, pairs[r, 0], pairs[r, 1])
        out.plane[r, col] = np.where(isv, -1, other)
    lab = out.u[r, 0]
    shared_v = (
        pt[sel]
        & (out.kind[r, 0] == VERTEX)
        & (FA[sel] == lab[:, None]).any(axis=1)
        & (FB[sel] == lab[:, None]).any(axis=1)
    )
    out.cls[r] = np.where(pt[sel], np.where(shared_v, SHARED_VERTEX, POINT), SEGMENT)


def _project(P: np.ndarray, axis: np.ndarray) -> np.ndarray:
    """Drop coordinate ``axis`` of ``P (m, c, 3)``, keeping the cyclic order of the others."""
    m = len(P)
    k1, k2 = (axis + 1) % 3, (axis + 2) % 3
    ar = np.arange(m)[:, None]
    c = np.arange(P.shape[1])[None, :]
    return np.stack([P[ar, c, k1[:, None]], P[ar, c, k2[:, None]]], axis=-1)


def _coplanar_proper(ctx, rows: np.ndarray) -> None:
    """Coplanar pairs of two non-zero-area triangles: overlap, touch or disjoint in 2D."""
    ints, faces, normals, pairs, out = ctx
    m = len(rows)
    ta, tb = pairs[rows, 0], pairs[rows, 1]
    FA, FB = faces[ta], faces[tb]
    NA, NB = normals[ta], normals[tb]
    ar = np.arange(m)
    axis = np.abs(NA).argmax(axis=1)
    # In the cyclic projection the 2D orientation of a triangle is the sign of N[axis].
    sgA = np.sign(NA[ar, axis]).astype(np.int8)
    sgB = np.sign(NB[ar, axis]).astype(np.int8)
    A2, B2 = _project(ints[FA], axis), _project(ints[FB], axis)

    def edge_signs(F1, P1, sg1, F2, P2):
        """(m, 3 edges, 3 points) signs of the points of 2 against the edges of 1, inside > 0."""
        o = np.zeros((m, 3, 3), dtype=np.int8)
        for e in range(3):
            e1 = (e + 1) % 3
            for j in range(3):
                skip = (F2[:, j] == F1[:, e]) | (F2[:, j] == F1[:, e1])
                c = ~skip
                if c.any():
                    o[c, e, j] = exact.orient2d(P1[c, e], P1[c, e1], P2[c, j]) * sg1[c]
        return o

    oA = edge_signs(FA, A2, sgA, FB, B2)
    oB = edge_signs(FB, B2, sgB, FA, A2)
    overlap = (oA > 0).any(axis=2).all(axis=1) & (oB > 0).any(axis=2).all(axis=1)
    disjoint = (oA < 0).all(axis=2).any(axis=1) | (oB < 0).all(axis=2).any(axis=1)
    out.cls[rows[overlap]] = COPLANAR_OVERLAP
    out.cls[rows[disjoint]] = DISJOINT
    touch = ~overlap & ~disjoint
    shA, _ = _shared(FA, FB)
    nsh = shA.sum(axis=1)
    t = touch & (nsh == 0)
    out.cls[rows[t]] = COPLANAR_TOUCH
    t = touch & (nsh >= 2)  # three shared labels always overlap
    if t.any():
        a = np.where(shA[t], FA[t], np.iinfo(np.int64).max).min(axis=1)
        b = np.where(shA[t], FA[t], -1).max(axis=1)
        out.set_vertices(rows[t], SHARED_EDGE, a, b)
    t = np.nonzero(touch & (nsh == 1))[0]
    if t.size:
        ia = shA[t].argmax(axis=1)
        v = FA[t, ia]
        ib = (FB[t] == v[:, None]).argmax(axis=1)
        ray = np.zeros(len(t), dtype=bool)
        pv = ints[v]
        for da in (1, 2):
            a = ints[FA[t, (ia + da) % 3]]
            for db in (1, 2):
                b = ints[FB[t, (ib + db) % 3]]
                col = exact.orient2d(A2[t, (ia + da) % 3], A2[t, ia], B2[t, (ib + db) % 3]) == 0
                ray |= col & (exact.dot_sign(a - pv, b - pv) > 0)
        out.cls[rows[t[ray]]] = COPLANAR_TOUCH
        nr = ~ray
        out.set_vertices(rows[t[nr]], SHARED_VERTEX, v[nr], v[nr])


def _segment_triangle(ctx, rows: np.ndarray, swap: np.ndarray) -> None:
    """Pairs of one zero-area triangle (a segment) and one proper triangle."""
    ints, faces, normals, pairs, out = ctx
    ts = np.where(swap, pairs[rows, 0], pairs[rows, 1])  # the segment
    tt = np.where(swap, pairs[rows, 1], pairs[rows, 0])  # the triangle
    FS, FT = faces[ts], faces[tt]
    shS, shT = _shared(FS, FT)
    s = _plane_signs(ints, faces, normals, FS, tt, shS)
    cop = ~s.any(axis=1)
    if cop.any():
        _segment_triangle_coplanar(ctx, rows[cop], ts[cop], tt[cop])
    pos, neg = (s > 0).any(axis=1), (s < 0).any(axis=1)
    dis = ~cop & ~(pos & neg) & ~(s == 0).any(axis=1)
    out.cls[rows[dis]] = DISJOINT
    live = np.nonzero(~cop & ~dis)[0]
    if not live.size:
        return
    rows, FS, FT, shT, s, tt = rows[live], FS[live], FT[live], shT[live], s[live], tt[live]
    m = len(rows)
    ar = np.arange(m)
    n = len(ints)
    # The point P where the segment's line meets the plane: a vertex with sign 0 (at most one:
    # two would put the whole line in the plane), else any edge with opposite strict signs
    # (all give P; the smallest label pair describes it).
    zero = s == 0
    hasz = zero.any(axis=1)
    z = zero.argmax(axis=1)
    helper = (s != 0).argmax(axis=1)
    big = np.iinfo(np.int64).max
    ekeys = np.full((m, 3), big, dtype=np.int64)
    for e in range(3):
        i, j = e, (e + 1) % 3
        cr = s[:, i] * s[:, j] < 0
        lo_, hi_ = np.minimum(FS[:, i], FS[:, j]), np.maximum(FS[:, i], FS[:, j])
        ekeys[cr, e] = (lo_ * n + hi_)[cr]
    e = ekeys.argmin(axis=1)
    p = np.where(hasz, FS[ar, z], FS[ar, e])
    q = np.where(hasz, FS[ar, helper], FS[ar, (e + 1) % 3])
    o = np.stack(
        [exact.orient3d(ints[p], ints[q], ints[FT[:, c]], ints[FT[:, (c + 1) % 3]]) for c in range(3)],
        axis=1,
    )
    inside = ~((o > 0).any(axis=1) & (o < 0).any(axis=1))
    out.cls[rows[~inside]] = DISJOINT
    zo = o == 0
    # Two zero edges: P is their common vertex of the triangle (edge c = (c, c + 1)).
    at_t = zo.sum(axis=1) == 2
    tv = np.where(zo[:, 0] & zo[:, 1], 1, np.where(zo[:, 1] & zo[:, 2], 2, 0))
    isv = hasz | at_t
    lab = np.where(at_t, FT[ar, tv], FS[ar, z])
    kind = np.where(isv, VERTEX, EDGE_PLANE).astype(np.int8)
    uu = np.where(isv, lab, np.minimum(p, q))
    vv = np.where(isv, -1, np.maximum(p, q))
    pl = np.where(isv, -1, tt)
    shared_v = isv & (FS == lab[:, None]).any(axis=1) & (FT == lab[:, None]).any(axis=1)
    sel = np.nonzero(inside)[0]
    r = rows[sel]
    out.cls[r] = np.where(shared_v[sel], SHARED_VERTEX, POINT)
    for col in (0, 1):
        out.kind[r, col] = kind[sel]
        out.u[r, col] = uu[sel]
        out.v[r, col] = vv[sel]
        out.plane[r, col] = pl[sel]


# --------------------------------------------------------------------------------------
# zero-area triangles (segments) in coplanar configurations


def _extremes(P: np.ndarray):
    """Corner indices ``(lo, hi)`` of the ends of collinear triples ``P (m, 3, 3)``, and the axis.

    Distinct points on a line differ in the coordinate where the line's direction is largest,
    so the minimum and maximum of that coordinate are the segment's ends.
    """
    ar = np.arange(len(P))
    d = np.abs(P - P[:, :1]).max(axis=1)  # (m, 3): extent along each axis
    k = d.argmax(axis=1)
    c = P[ar, :, k]
    return c.argmin(axis=1), c.argmax(axis=1), k


def _cone_hits(v2, a2, b2, sg, w2) -> np.ndarray:
    """Whether the points ``w2`` lie in the closed corner cone at ``v2`` of triangles ``v a b``.

    ``v, a, b`` are in counter-clockwise order after multiplying by ``sg`` (2D rows).
    """
    first = exact.orient2d(v2, a2, w2) * sg >= 0
    return first & (exact.orient2d(v2, w2, b2) * sg >= 0)


def _segment_triangle_coplanar(ctx, rows, ts, tt) -> None:
    """A segment (zero-area triangle ``ts``) in the plane of the proper triangle ``tt``.

    In 2D (dominant axis of the triangle's normal dropped): the sets are disjoint iff an edge
    of the triangle has both ends of the segment strictly outside, or the segment's line has
    the three corners strictly on one side (separating axes). Otherwise ``X`` is a point or a
    segment: with two shared labels it is exactly that edge of the triangle (the triangle
    meets the line only there); with one shared label ``v`` it is ``{v}`` unless one of the
    segment's other points lies in the triangle's closed corner cone at ``v``.
    """
    ints, faces, normals, pairs, out = ctx
    m = len(rows)
    ar = np.arange(m)
    FS, FT = faces[ts], faces[tt]
    N = normals[tt]
    axis = np.abs(N).argmax(axis=1)
    sg = np.sign(N[ar, axis]).astype(np.int8)
    S2, T2 = _project(ints[FS], axis), _project(ints[FT], axis)
    ip, iq, _ = _extremes(ints[FS])
    p2, q2 = S2[ar, ip], S2[ar, iq]
    sep = np.zeros(m, dtype=bool)
    for e in range(3):
        e0, e1 = T2[:, e], T2[:, (e + 1) % 3]
        sep |= (exact.orient2d(e0, e1, p2) * sg < 0) & (exact.orient2d(e0, e1, q2) * sg < 0)
    side = np.stack([exact.orient2d(p2, q2, T2[:, j]) for j in range(3)], axis=1)
    sep |= (side > 0).all(axis=1) | (side < 0).all(axis=1)
    out.cls[rows[sep]] = DISJOINT
    shS, _ = _shared(FS, FT)
    nsh = shS.sum(axis=1)
    out.cls[rows[~sep & (nsh == 0)]] = COPLANAR_TOUCH
    t = ~sep & (nsh == 2)
    if t.any():
        a = np.where(shS[t], FS[t], np.iinfo(np.int64).max).min(axis=1)
        b = np.where(shS[t], FS[t], -1).max(axis=1)
        out.set_vertices(rows[t], SHARED_EDGE, a, b)
    t = np.nonzero(~sep & (nsh == 1))[0]
    if t.size:
        i_s = shS[t].argmax(axis=1)
        v = FS[t, i_s]
        i_t = (FT[t] == v[:, None]).argmax(axis=1)
        v2, a2, b2 = T2[t, i_t], T2[t, (i_t + 1) % 3], T2[t, (i_t + 2) % 3]
        hit = np.zeros(len(t), dtype=bool)
        for dw in (1, 2):
            hit |= _cone_hits(v2, a2, b2, sg[t], S2[t, (i_s + dw) % 3])
        out.cls[rows[t[hit]]] = COPLANAR_TOUCH
        out.set_vertices(rows[t[~hit]], SHARED_VERTEX, v[~hit], v[~hit])


def _segment_segment(ctx, rows) -> None:
    """Pairs of two zero-area triangles (two segments).

    Skew lines (``orient3d`` of the four ends non-zero): DISJOINT. Coplanar, distinct lines:
    in 2D (dominant axis of a normal of their plane dropped) the classic four ``orient2d``;
    a meeting point is a shared label if they share one. One common line: 1D intervals along
    the line's dominant axis, compared as integers.
    """
    ints, faces, normals, pairs, out = ctx
    m = len(rows)
    ar = np.arange(m)
    FA, FB = faces[pairs[rows, 0]], faces[pairs[rows, 1]]
    PA, PB = ints[FA], ints[FB]
    ia0, ia1, k = _extremes(PA)
    ib0, ib1, _ = _extremes(PB)
    pa, qa, pb, qb = PA[ar, ia0], PA[ar, ia1], PB[ar, ib0], PB[ar, ib1]
    skew = exact.orient3d(pa, qa, pb, qb) != 0
    out.cls[rows[skew]] = DISJOINT
    n1 = exact.cross(qa - pa, pb - pa)
    n2 = exact.cross(qa - pa, qb - pa)
    nrm = np.where(n1.any(axis=1)[:, None], n1, n2)
    line = ~nrm.any(axis=1)
    shA, _ = _shared(FA, FB)
    nsh = shA.sum(axis=1)

    t = np.nonzero(~skew & ~line)[0]  # one plane, two distinct lines: at most one point
    if t.size:
        axis = np.abs(nrm[t]).argmax(axis=1)
        pts = _project(np.stack([pa[t], qa[t], pb[t], qb[t]], axis=1), axis)
        a0, a1, b0, b1 = pts[:, 0], pts[:, 1], pts[:, 2], pts[:, 3]
        meet = (exact.orient2d(a0, a1, b0) * exact.orient2d(a0, a1, b1) <= 0) & (
            exact.orient2d(b0, b1, a0) * exact.orient2d(b0, b1, a1) <= 0
        )
        out.cls[rows[t[~meet]]] = DISJOINT
        out.cls[rows[t[meet & (nsh[t] == 0)]]] = COPLANAR_TOUCH
        sv = t[meet & (nsh[t] >= 1)]
        lab = FA[sv, shA[sv].argmax(axis=1)]
        out.set_vertices(rows[sv], SHARED_VERTEX, lab, lab)

    t = np.nonzero(~skew & line)[0]  # one line: compare coordinates along its dominant axis
    if t.size:
        ca = PA[t, :, k[t]]  # (mt, 3): coordinates of A's corners along the axis
        cb = PB[t, :, k[t]]
        lo = np.maximum(ca.min(axis=1), cb.min(axis=1))
        hi = np.minimum(ca.max(axis=1), cb.max(axis=1))
        empty = lo > hi
        out.cls[rows[t[empty]]] = DISJOINT
        sh = shA[t]
        at_lo = sh & (ca == lo[:, None])
        at_hi = sh & (ca == hi[:, None])
        ends_shared = ~empty & at_lo.any(axis=1) & at_hi.any(axis=1)
        lab_lo = FA[t, at_lo.argmax(axis=1)]
        lab_hi = FA[t, at_hi.argmax(axis=1)]
        out.cls[rows[t[~empty & ~ends_shared]]] = COPLANAR_TOUCH
        e = ends_shared & (lo < hi)
        a, b = np.minimum(lab_lo, lab_hi)[e], np.maximum(lab_lo, lab_hi)[e]
        out.set_vertices(rows[t[e]], SHARED_EDGE, a, b)
        v = ends_shared & (lo == hi)
        out.set_vertices(rows[t[v]], SHARED_VERTEX, lab_lo[v], lab_lo[v])


def _sub(a, b):
    return (a[0] - b[0], a[1] - b[1], a[2] - b[2])


def _cross3(a, b):
    return (a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0])


def _dot3(a, b):
    return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]


def _object_array(items: list) -> np.ndarray:
    """1-D object array of tuples (numpy would otherwise make a 2-D array of them)."""
    out = np.empty(len(items), dtype=object)
    for i, x in enumerate(items):
        out[i] = x
    return out


def _cross(a, b):
    return (a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0])


def _dot(a, b) -> int:
    return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]


def _orient3(a, b, c, d) -> int:
    """Sign of det[b - a, c - a, d - a] (Python ints)."""
    u = (b[0] - a[0], b[1] - a[1], b[2] - a[2])
    v = (c[0] - a[0], c[1] - a[1], c[2] - a[2])
    w = (d[0] - a[0], d[1] - a[1], d[2] - a[2])
    x = _dot(u, _cross(v, w))
    return (x > 0) - (x < 0)
