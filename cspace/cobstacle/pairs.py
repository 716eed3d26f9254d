"""C-obstacles of one obstacle body against one part of a non-convex robot, exactly.

A robot is modelled like an obstacle (:func:`cspace.scene.model.model_scene`): welded, double-sided
duplicates dropped, split into parts, each part ``convex``, ``solid`` (closed, not convex) or
``surface`` (open). The C-obstacle of the robot is the union over its parts, and a planner only
needs membership, so each (obstacle body, robot part) pair gets its own C-obstacles and no
union is built. :func:`pair_construction` names the cheapest exact construction per pairing:

============  =============  ===============================================================
obstacle      robot part     construction
============  =============  ===============================================================
convex        convex         ``CVMS``: one convex polytope
solid         convex         ``NCC-CVMS``: one closed surface
surface       convex         ``surface pieces``: ``t ⊕ (c - R)`` per obstacle triangle t
convex        solid          ``NCC-CVMS swapped``: ``O ⊕ (c - R) = -((R - c) ⊕ (-O))``
convex        surface        ``convex ⊕ robot triangles``: ``O ⊕ (c - t)`` per robot triangle
solid or      solid or       ``triangle pairs``: ``s ⊕ (c - t)`` per obstacle triangle s and
surface       surface        robot triangle t, plus containment terms (below)
============  =============  ===============================================================

Triangle pairs and containment
------------------------------
Two surfaces meet exactly when two of their triangles do, so for open operands
``CO = ∪ s ⊕ (c - t)`` (FCL's mesh semantics). A closed operand is a solid: the robot may
also lie wholly inside a closed obstacle, or swallow an obstacle component. These are the
*containment terms*, each a closed mesh queried exactly (:mod:`cspace.mesh.query`):

- closed robot part R: ``o + c - R`` for one vertex o of each connected component of the
  obstacle (the robot at q holds o);
- closed obstacle O: ``O + c - r`` for one vertex r of each connected component of the part
  (O holds the robot's vertex r).

A component either meets the other operand's boundary (a triangle pair) or lies wholly
inside or outside it, so the terms complete the union exactly.

Flat pieces: ``s ⊕ (c - t)`` of two parallel triangles is a flat polygon. When either operand
is closed such a piece adds nothing: a contact of two coplanar faces reaches the edge of the
coplanar face region of the closed operand, where a non-parallel neighbour triangle meets the
other operand too (or a containment term holds). Those pairs are left out. When both are open
surfaces the flat piece is needed and kept, exactly.

Pairs are held as index arrays (:class:`PairObstacle`): each piece is the intersection of 17
slabs whose normals come from the two triangles alone (:func:`pair_planes`), so no hull is
built; queries evaluate the slabs of the pairs near them with a float filter and settle what
it leaves with Python integers. Pieces grown by the outward-rounding box of
:mod:`cspace.cobstacle.margin` take 38 slabs, still exact. The grown pieces and the (ungrown) containment
terms hold the true C-obstacle: a robot component inside the obstacle for the float input
either stays inside after snapping (the term holds) or lies within the snapping deviation of
the boundary, where a grown pair piece holds it. :func:`triangle_pair_pieces` builds one exact hull per pair
instead, the reference the fast path is tested against (0.6 ms a pair).

All coordinates are grid integers of the scene grid (robot frame for the robot part, the
reference point ``c`` snapped); sums and differences of grid integers are exact.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from ..mesh.convex import ConvexPolytope
from ..errors import DegenerateError
from ..geometry.exact import _FILTER, _TINY
from ..geometry.distance import _tri_tri_distance
from ..geometry.graphs import component_labels
from .margin import Margin
from ..geometry.snapping import grow_points
from .obstacle import CSpaceObstacle
from .convex import exact_plane_sign, exact_segment_entry, segment_filter

__all__ = ["CONSTRUCTIONS", "pair_construction", "PairPieces", "TrianglePairs",
           "triangle_pairs", "triangle_pair_pieces", "PairObstacle", "convex_triangle_pieces",
           "component_points", "containment_meshes", "PAIR_BYTES", "pairs_memory"]

#: Every construction a pair can get, with what it computes.
CONSTRUCTIONS = {
    "CVMS": "convex ⊕ convex: one exact convex polytope",
    "NCC-CVMS": "non-convex closed obstacle ⊕ convex robot part: one exact closed surface",
    "surface pieces": "one convex piece t ⊕ (c - R) per obstacle triangle t (open obstacle)",
    "NCC-CVMS swapped": "convex obstacle, non-convex closed robot part: O ⊕ (c - R) = "
                        "-((R - c) ⊕ (-O)), one exact closed surface",
    "convex ⊕ robot triangles": "convex obstacle, open robot part: one convex piece "
                                "O ⊕ (c - t) per robot triangle t",
    "triangle pairs": "both non-convex: one convex piece s ⊕ (c - t) per obstacle triangle s "
                      "and robot triangle t, plus exact containment terms for closed operands",
}

# Robot triangles handled per vectorised block of triangle pairs (memory).
_BLOCK = 1 << 18
# Candidate (query, pair) rows evaluated at once; padding value of unused slab sides.
_PAIRS = 1 << 12
_PAD = -1e300
# Pairs whose slab columns are kept in memory (about 2 KB a pair).
_KEEP = 1 << 15

#: Bytes a triangle pair takes while its C-obstacle lives (``held``) and while it is built
#: (``peak``): tracemalloc measured 105-113 and 575-655 (tests/test_memory.py holds them to it).
PAIR_BYTES = {"held": 160, "peak": 768}


def pairs_memory(n_pairs: int) -> tuple[int, int]:
    """``(held, peak)`` bytes of at most ``n_pairs`` triangle pairs (:data:`PAIR_BYTES`)."""
    return PAIR_BYTES["held"] * int(n_pairs), PAIR_BYTES["peak"] * int(n_pairs)


def pair_construction(obstacle_kind: str, robot_kind: str) -> str:
    """The construction an (obstacle body, robot part) pair gets (a key of CONSTRUCTIONS)."""
    if robot_kind == "convex":
        return {"convex": "CVMS", "solid": "NCC-CVMS", "surface": "surface pieces"}[obstacle_kind]
    if obstacle_kind == "convex":
        return "NCC-CVMS swapped" if robot_kind == "solid" else "convex ⊕ robot triangles"
    return "triangle pairs"


@dataclass(eq=False)
class PairPieces:
    """Convex pieces of a pair and what was left out.

    Attributes
    ----------
    pieces : list of ConvexPolytope
    thickened : int
        Flat pieces of two open surfaces grown by one grid step (the hull reference only;
        :class:`PairObstacle` keeps them exact).
    flat_skipped : int
        Flat pieces left out because an operand is closed.
    out_of_bounds : int
        Pieces whose bounding box misses the planning bounds (decided exactly).
    """

    pieces: list
    thickened: int = 0
    flat_skipped: int = 0
    out_of_bounds: int = 0


def _meets(lo: np.ndarray, hi: np.ndarray, blo: np.ndarray, bhi: np.ndarray) -> np.ndarray:
    """Exact: do the boxes ``[lo, hi]`` (grid ints, (k, 3)) meet ``[blo, bhi]`` (grid units)?"""
    return ((lo.astype(np.float64) <= bhi) & (blo <= hi.astype(np.float64))).all(axis=-1)


def _primitive_normals(tri: np.ndarray) -> np.ndarray:
    """``(m, 3)`` int64 primitive normals of grid triangles, sign made canonical (first
    non-zero component positive); zero for collinear corners. Exact: edges of 28-bit grid
    coordinates give cross products below 2**60."""
    n = np.cross(tri[:, 1] - tri[:, 0], tri[:, 2] - tri[:, 0])
    g = np.gcd.reduce(np.abs(n), axis=1)
    n = n // np.maximum(g, 1)[:, None]
    first = np.where(n[:, 0] != 0, n[:, 0], np.where(n[:, 1] != 0, n[:, 1], n[:, 2]))
    return n * np.where(first < 0, -1, 1)[:, None]


_OCTAHEDRON = np.array([[0, 0, 0], [1, 0, 0], [-1, 0, 0], [0, 1, 0], [0, -1, 0], [0, 0, 1],
                        [0, 0, -1]], dtype=np.int64)


@dataclass(eq=False)
class TrianglePairs:
    """The triangle pairs of an (obstacle, robot part) pair that can matter.

    Attributes
    ----------
    S : (m, 3, 3) int64
        Obstacle triangles (grid units, world frame).
    T : (l, 3, 3) int64
        ``c - t`` for the robot triangles t (grid units): the piece of pair ``(i, j)`` is
        ``S[i] ⊕ T[j]``.
    pairs : (p, 2) int64
        The kept ``(i, j)``.
    flat : (p,) bool
        Pieces of parallel triangles (flat polygons).
    flat_skipped, out_of_bounds : int
        Pairs left out: flat with a closed operand (redundant), or whose piece box misses the
        planning bounds (decided exactly).
    kept : int
        ``len(pairs)`` (with ``count_only``: the pairs that would be kept, none stored).
    margin : (3,) int64
        Every piece is grown by the box ``[-margin, margin]`` (grid steps per axis; outward
        rounding, :mod:`cspace.cobstacle.margin`): ``S[i] ⊕ T[j] ⊕ box``.
    """

    S: np.ndarray
    T: np.ndarray
    pairs: np.ndarray
    flat: np.ndarray
    flat_skipped: int = 0
    out_of_bounds: int = 0
    kept: int = 0
    margin: np.ndarray = field(default_factory=lambda: np.zeros(3, np.int64))

    def __post_init__(self):
        self.margin = np.asarray(self.margin, dtype=np.int64).reshape(3)

    def piece_points(self, i: int, j: int) -> np.ndarray:
        """``(k, 3)`` int64 points whose hull is the (grown) piece of pair ``(i, j)``."""
        return grow_points((self.S[i][:, None, :] + self.T[j][None, :, :]).reshape(-1, 3),
                           self.margin)


def triangle_pairs(o_ints, o_faces, r_ints, r_faces, c_ints, bounds_g, *,
                   closed: bool, margin=(0, 0, 0), count_only: bool = False) -> TrianglePairs:
    """The pairs (obstacle triangle s, robot triangle t) whose piece ``s ⊕ (c - t)`` can meet
    the bounds; flat ones are left out when either operand is closed (see the module).

    Parameters
    ----------
    o_ints, o_faces : (n, 3) int64, (m, 3) int64
        Obstacle body (grid units, world frame).
    r_ints, r_faces : (k, 3) int64, (l, 3) int64
        Robot part (grid units, robot frame).
    c_ints : (3,) int64
        The snapped reference point.
    bounds_g : (2, 3) float64
        Planning bounds in grid units.
    closed : bool
        Whether either operand is closed.
    margin : (3,) int
        Grow every piece by this box (grid steps per axis), see :class:`TrianglePairs`.
    count_only : bool, default False
        Only count them (``kept``), storing none: for a memory estimate before the build.
    """
    g = np.asarray(margin, dtype=np.int64).reshape(3)
    S = np.asarray(o_ints, np.int64)[np.asarray(o_faces, np.int64)]
    T = np.asarray(c_ints, np.int64) - np.asarray(r_ints, np.int64)[np.asarray(r_faces, np.int64)]
    ns, nt = _primitive_normals(S), _primitive_normals(-T)
    s_lo, s_hi = S.min(axis=1) - g, S.max(axis=1) + g
    t_lo, t_hi = T.min(axis=1), T.max(axis=1)
    per = max(1, _BLOCK // max(1, len(T)))
    out = TrianglePairs(S, T, np.zeros((0, 2), np.int64), np.zeros(0, bool), margin=g)
    kept, flats = [], []
    for a in range(0, len(S), per):
        i = np.arange(a, min(a + per, len(S)))
        ii, jj = np.repeat(i, len(T)), np.tile(np.arange(len(T)), len(i))
        keep = _meets(s_lo[ii] + t_lo[jj], s_hi[ii] + t_hi[jj], *bounds_g)
        out.out_of_bounds += int((~keep).sum())
        ii, jj = ii[keep], jj[keep]
        flat = (ns[ii] == nt[jj]).all(axis=1) | ~ns[ii].any(axis=1) | ~nt[jj].any(axis=1)
        if closed:
            out.flat_skipped += int(flat.sum())
            ii, jj, flat = ii[~flat], jj[~flat], flat[~flat]
        out.kept += len(ii)
        if not count_only:
            kept.append(np.stack([ii, jj], axis=1))
            flats.append(flat)
    if kept:
        out.pairs, out.flat = np.concatenate(kept), np.concatenate(flats)
    return out


def triangle_pair_pieces(o_ints, o_faces, r_ints, r_faces, c_ints, grid, bounds_g, *,
                         closed: bool, progress=None, margin=(0, 0, 0)) -> PairPieces:
    """Reference construction: one exact hull per triangle pair of :func:`triangle_pairs`.

    About 0.6 ms a pair; :class:`PairObstacle` answers the same queries from the pairs alone
    and is tested against these hulls. Flat pieces (two open operands) are thickened by one
    grid step here, so that each is a polytope.
    """
    tp = triangle_pairs(o_ints, o_faces, r_ints, r_faces, c_ints, bounds_g, closed=closed,
                        margin=margin)
    out = PairPieces([], flat_skipped=tp.flat_skipped, out_of_bounds=tp.out_of_bounds)
    for k, ((i, j), f) in enumerate(zip(tp.pairs.tolist(), tp.flat.tolist())):
        pts = tp.piece_points(i, j)
        out.pieces.append(_piece(pts, f and not tp.margin.any(), grid, out, f"pair {i}x{j}"))
        if progress is not None and k % 256 == 255:
            progress((k + 1) / len(tp.pairs))
    return out


def _piece(pts: np.ndarray, flat: bool, grid, out: PairPieces, name: str) -> ConvexPolytope:
    if not flat:
        try:
            return ConvexPolytope.from_ints(pts, grid=grid, name=name)
        except DegenerateError:  # collinear corners of an open surface's triangle
            pass
    out.thickened += 1
    grown = (pts[:, None, :] + _OCTAHEDRON[None, :, :]).reshape(-1, 3)
    return ConvexPolytope.from_ints(grown, grid=grid, name=name)


def convex_triangle_pieces(o_ints, r_ints, r_faces, c_ints, grid, bounds_g) -> PairPieces:
    """``O ⊕ (c - t)`` per robot triangle t of an open robot part, O a convex body's points
    (full-dimensional, so no piece is flat)."""
    O = np.asarray(o_ints, np.int64)
    T = np.asarray(c_ints, np.int64) - np.asarray(r_ints, np.int64)[np.asarray(r_faces, np.int64)]
    keep = _meets(O.min(axis=0) + T.min(axis=1), O.max(axis=0) + T.max(axis=1), *bounds_g)
    out = PairPieces([], out_of_bounds=int((~keep).sum()))
    for j in np.nonzero(keep)[0].tolist():
        pts = (O[:, None, :] + T[j][None, :, :]).reshape(-1, 3)
        out.pieces.append(ConvexPolytope.from_ints(pts, grid=grid, name=f"robot triangle {j}"))
    return out


def component_points(ints: np.ndarray, faces: np.ndarray, fits_in=None) -> np.ndarray:
    """``(k, 3)``: one vertex (the first) of each connected component of a mesh (dtype kept)
    (triangles sharing a vertex are connected).

    ``fits_in``: an extent (3,); only components whose box is no larger on any axis are
    kept. A component can lie inside a solid only if it fits in the solid's box, so the
    containment terms of larger ones (walls, floors) can never hold and are not built.
    """
    F = np.asarray(faces, np.int64)
    n = len(ints)
    a, b = F.reshape(-1), np.repeat(F[:, 0], 3)
    _, label = component_labels(n, a, b)
    used = np.unique(F)
    roots, first = np.unique(label[used], return_index=True)
    points = np.asarray(ints)[used[first]]
    if fits_in is None:
        return points
    V = np.asarray(ints)
    lo = np.full((label.max() + 1, 3), np.inf)
    hi = np.full((label.max() + 1, 3), -np.inf)
    np.minimum.at(lo, label[used], V[used])
    np.maximum.at(hi, label[used], V[used])
    fits = ((hi[roots] - lo[roots]) <= np.asarray(fits_in)).all(axis=1)
    return points[fits]


def containment_meshes(points, solid_ints, solid_faces, c_ints, *, robot_solid: bool):
    """Closed meshes (grid ints, faces) of the containment terms of a pair.

    ``robot_solid=True``: ``o + c - R`` for each obstacle point o (the robot part R =
    ``solid_ints, solid_faces`` holds o); reflecting turns the mesh inside out, so the faces
    are reversed to keep it outward. ``robot_solid=False``: ``O + c - r`` for each robot point
    r (the obstacle O holds r).
    """
    V = np.asarray(solid_ints, np.int64)
    F = np.asarray(solid_faces, np.int64)
    c = np.asarray(c_ints, np.int64)
    out = []
    for p in np.asarray(points, np.int64).reshape(-1, 3):
        if robot_solid:
            out.append((p + c - V, F[:, ::-1].copy()))
        else:
            out.append((V + c - p, F))
    return out


# --------------------------------------------------------------------------------------
# triangle pairs held as arrays: exact queries without a hull per pair


def _edges(tri: np.ndarray) -> np.ndarray:
    """``(k, 3, 3)`` edge vectors ``p1 - p0, p2 - p1, p0 - p2`` of grid triangles."""
    return tri[:, [1, 2, 0]] - tri


def pair_planes(S: np.ndarray, T: np.ndarray, grown: bool = False) -> np.ndarray:
    """``(k, 17, 3)`` int64 normals whose slabs bound the pieces ``s ⊕ t`` exactly
    (``(k, 38, 3)`` when ``grown``: also ``s ⊕ t ⊕ box``).

    For triangles ``s`` (rows of S) and ``t`` (rows of T), grid integers: the two triangle
    normals, the nine cross products of an edge of each (every facet normal of a 3D sum of two
    polytopes is a facet normal of one or such a cross product), and the six edges turned a
    quarter about the coordinate axis nearest to ``s``'s normal (``e_axis x edge``): in the
    plane of two parallel triangles these bound the flat polygon ``s ⊕ t``. With the slabs
    ``min over the piece <= N . x <= max over the piece`` of every normal the piece is exactly
    their intersection, flat or not. Zero rows (parallel edges) bound nothing. Exact: edges of
    28-bit coordinates give entries below 2**58.

    ``grown``: 21 more, the three coordinate axes and each edge crossed with each axis. The
    facet normals of ``P ⊕ box`` are facet normals of P or of the box, or cross products of an
    edge of each (P's edges are edges of s or t; flat P's own are ``±n``): with the box's
    support ``sum_i g_i |N_i|`` added to every slab, their intersection is ``P ⊕ box`` exactly.
    """
    Es, Et = _edges(S), _edges(T)
    ns = np.cross(Es[:, 0], -Es[:, 2])
    nt = np.cross(Et[:, 0], -Et[:, 2])
    cross = np.cross(Es[:, :, None, :], Et[:, None, :, :]).reshape(len(S), 9, 3)
    ref = np.where(ns.any(axis=1)[:, None], ns, nt)
    axis = np.abs(ref).argmax(axis=1)
    unit = np.zeros((len(S), 3), dtype=np.int64)
    unit[np.arange(len(S)), axis] = 1
    edges = np.concatenate([Es, Et], axis=1)
    turned = np.cross(unit[:, None, :], edges)
    out = [ns[:, None], nt[:, None], cross, turned]
    if grown:
        axes = np.broadcast_to(np.eye(3, dtype=np.int64), (len(S), 3, 3))
        out += [axes, np.cross(axes[:, :, None, :], edges[:, None, :, :]).reshape(len(S), 18, 3)]
    return np.concatenate(out, axis=1)


def _tri_support(N: np.ndarray, tri: np.ndarray):
    """Float min and max of ``N . p`` over a triangle's corners, and the permanent bound
    ``sum |N_k| max |p_k|`` (k, K)."""
    d = np.einsum("kmj,kaj->kma", N, tri)
    perm = np.einsum("kmj,kj->km", np.abs(N), np.abs(tri).max(axis=1))
    return d.min(axis=2), d.max(axis=2), perm


class _PairsCO:
    """Exact queries on ``∪ s_i ⊕ t_j`` over given triangle pairs (the engine interface of
    :mod:`cspace.cobstacle.obstacle`), with no hull built per pair.

    Each pair's piece is the intersection of 17 slabs (:func:`pair_planes`; 38 for pieces grown
    by the margin box ``[-g, g]``). Queries find the
    pairs whose piece box holds them (a uniform grid of cells, as for surface pieces), compute
    the slab values in float with a rigorous bound (16 unit roundoffs of the sum of absolute
    products, the normals and supports rounded to float included), and settle what the bound
    leaves with Python integers. Touching counts as inside.
    """

    def __init__(self, S: np.ndarray, T: np.ndarray, pairs: np.ndarray, grid,
                 margin=(0, 0, 0)):
        from .surface import _CellGrid

        # S (obstacle triangles, in grid's frame) moved to the scene frame by the grid's
        # origin, exactly: T holds vectors (c - t), so every piece and plane is then in the
        # scene frame and a query is only scaled, never shifted.
        self.S = np.asarray(S, np.int64) + np.asarray(grid.origin, np.int64)
        self.T = np.asarray(T, np.int64)
        self.pairs = np.asarray(pairs, np.int64).reshape(-1, 2)
        if not len(self.pairs):
            raise ValueError("a triangle-pair C-obstacle needs at least one pair")
        self.grid, self.exponent = grid.vectors, grid.exponent
        # Pieces grown by the box [-g, g] (outward rounding): 38 slabs instead of 17.
        self.g = np.asarray(margin, dtype=np.int64).reshape(3)
        self.grown = bool(self.g.any())
        self.n_slabs = 38 if self.grown else 17
        self._gf = self.g.astype(np.float64)
        i, j = self.pairs[:, 0], self.pairs[:, 1]
        # S already holds the origin: the boxes are scaled by the vectors' grid, not shifted.
        self.lo = self.grid.to_float(self.S[i].min(axis=1) + self.T[j].min(axis=1) - self.g)
        self.hi = self.grid.to_float(self.S[i].max(axis=1) + self.T[j].max(axis=1) + self.g)
        self.cells = _CellGrid(self.lo, self.hi)
        # The two triangle normals' slabs first: most pairs near a query are separated by
        # one of them, and they cost six dot products a pair.
        ns = np.cross(self.S[:, 1] - self.S[:, 0], self.S[:, 2] - self.S[:, 0])
        nt = np.cross(self.T[:, 1] - self.T[:, 0], self.T[:, 2] - self.T[:, 0])
        self._ns, self._nt = ns.astype(np.float64), nt.astype(np.float64)
        self._Sf, self._Tf = self.S.astype(np.float64), self.T.astype(np.float64)
        self._s_abs = np.abs(self._Sf).max(axis=1)
        self._t_abs = np.abs(self._Tf).max(axis=1)
        # Slab columns of every pair up front when they fit in about 64 MB, else per query.
        fits = len(self.pairs) * self.n_slabs <= _KEEP * 17
        self._all = self._columns(np.arange(len(self.pairs))) if fits else None

    # ---- slabs ------------------------------------------------------------------------

    def _columns(self, p: np.ndarray):
        """Upper and lower slab sides of pairs ``p`` as columns ``a . [k, 1] <= 0``:
        ``(A (n, 4, 2K), absA (n, 4, 2K))`` float (K slabs), zero normals padded out."""
        S, T = self.S[self.pairs[p, 0]], self.T[self.pairs[p, 1]]
        N = pair_planes(S, T, self.grown)
        K = N.shape[1]
        Nf = N.astype(np.float64)
        s_lo, s_hi, s_perm = _tri_support(Nf, S.astype(np.float64))
        t_lo, t_hi, t_perm = _tri_support(Nf, T.astype(np.float64))
        box = np.abs(Nf) @ self._gf  # the box's support, g_i |N_i| summed (rounded: in perm)
        valid = N.any(axis=2)
        A = np.zeros((len(p), 4, 2 * K))
        A[:, :3, :K] = Nf.transpose(0, 2, 1)
        A[:, 3, :K] = -(s_hi + t_hi + box)
        A[:, :3, K:] = -Nf.transpose(0, 2, 1)
        A[:, 3, K:] = s_lo + t_lo - box
        absA = np.abs(A)
        # The supports are rounded sums of rounded products: their error is covered by the
        # permanent (bounded below like the products of the query itself).
        absA[:, 3, :K] += s_perm + t_perm + box
        absA[:, 3, K:] += s_perm + t_perm + box
        pad = ~np.concatenate([valid, valid], axis=1)
        A[:, :3, :][np.repeat(pad[:, None, :], 3, axis=1)] = 0.0
        A[:, 3, :][pad] = _PAD
        absA[pad[:, None, :].repeat(4, axis=1)] = 0.0
        return A, absA

    def _exact_planes(self, p: int):
        """``(n, d)`` Python-int half-spaces ``n . k <= d`` of pair ``p``'s piece."""
        S, T = self.S[self.pairs[p, 0]], self.T[self.pairs[p, 1]]
        N = pair_planes(S[None], T[None], self.grown)[0]
        g = self.g.tolist()
        out = []
        for n in N.tolist():
            if not any(n):
                continue
            vs = [sum(a * b for a, b in zip(n, v)) for v in S.tolist()]
            vt = [sum(a * b for a, b in zip(n, v)) for v in T.tolist()]
            box = sum(gi * abs(ni) for gi, ni in zip(g, n))
            out.append((n, max(vs) + max(vt) + box))
            out.append(([-x for x in n], -(min(vs) + min(vt) - box)))
        return out

    def _columns_of(self, p: np.ndarray):
        if self._all is not None:
            return self._all[0][p], self._all[1][p]
        unique, inverse = np.unique(p, return_inverse=True)
        A, absA = self._columns(unique)
        return A[inverse], absA[inverse]

    def _values(self, q: np.ndarray, p: np.ndarray):
        A, absA = self._columns_of(p)
        Q = np.ones((len(q), 1, 4))
        with np.errstate(over="ignore", under="ignore", invalid="ignore"):
            np.ldexp(q, -self.exponent, out=Q[:, 0, :3])
            val = np.matmul(Q, A)[:, 0, :]
            err = _FILTER * np.matmul(np.abs(Q), absA)[:, 0, :] + _TINY
        return val, err

    def _face_values(self, q: np.ndarray, p: np.ndarray):
        """Values and bounds of the four face-normal slab sides of pairs ``p`` at queries
        ``q`` (rows matched), as :meth:`_values` gives for all: a cheap first pass."""
        i, j = self.pairs[p, 0], self.pairs[p, 1]
        Q = np.ldexp(q, -self.exponent)
        out, errs = [], []
        for n, own, other, own_abs, other_abs in (
                (self._ns[i], self._Sf[i], self._Tf[j], self._s_abs[i], self._t_abs[j]),
                (self._nt[j], self._Tf[j], self._Sf[i], self._t_abs[j], self._s_abs[i])):
            base = np.einsum("kj,kj->k", n, own[:, 0])       # constant over its own triangle
            dots = np.einsum("kj,kaj->ka", n, other)
            x = np.einsum("kj,kj->k", n, Q)
            an = np.abs(n)
            box = an @ self._gf  # the margin box's support
            err = _FILTER * (np.einsum("kj,kj->k", an, np.abs(Q))
                             + np.einsum("kj,kj->k", an, own_abs)
                             + np.einsum("kj,kj->k", an, other_abs) + box) + _TINY
            out += [x - base - dots.max(axis=1) - box, base + dots.min(axis=1) - x - box]
            errs += [err, err]
        return np.stack(out, axis=1), np.stack(errs, axis=1)

    # ---- queries ----------------------------------------------------------------------

    def candidates(self, q: np.ndarray):
        rows, p = self.cells.pairs(q)
        keep = ((self.lo[p] <= q[rows]) & (q[rows] <= self.hi[p])).all(axis=1)
        return rows[keep], p[keep]

    def contains(self, q: np.ndarray) -> np.ndarray:
        out = np.zeros(len(q), dtype=bool)
        rows, ps = self.candidates(q)
        if len(rows):
            with np.errstate(over="ignore", under="ignore", invalid="ignore"):
                val, err = self._face_values(q[rows], ps)
            beyond = ((val > err) & np.isfinite(val)).any(axis=1)
            rows, ps = rows[~beyond], ps[~beyond]
        for s in range(0, len(rows), _PAIRS):
            r, p = rows[s:s + _PAIRS], ps[s:s + _PAIRS]
            val, err = self._values(q[r], p)
            fin = np.isfinite(val) & np.isfinite(err)
            inside = ((val < -err) & fin).all(axis=1)
            unsure = ~inside & ~((val > err) & fin).any(axis=1)
            for k in np.nonzero(unsure)[0].tolist():
                if not out[r[k]] and not inside[k]:
                    x = q[r[k]].tolist()
                    inside[k] = all(exact_plane_sign(n, d, self.exponent, x) <= 0
                                    for n, d in self._exact_planes(int(p[k])))
            out[r[inside]] = True
        return out

    def _segment_candidates(self, a: np.ndarray, b: np.ndarray):
        """``(row, pair)`` whose piece box meets the segment's box (cells first, then exact)."""
        rows, ps = [], []
        lo, hi = np.minimum(a, b), np.maximum(a, b)
        if len(self.lo) <= _KEEP // 8 or len(a) * len(self.lo) <= (1 << 16):
            step = max(1, (1 << 20) // len(self.lo))
            for s in range(0, len(a), step):
                m = ((self.lo[None] <= hi[s:s + step, None])
                     & (lo[s:s + step, None] <= self.hi[None])).all(axis=2)
                r, p = np.nonzero(m)
                rows.append(r + s)
                ps.append(p)
            return np.concatenate(rows), np.concatenate(ps)
        c0, c1 = self.cells.cells(lo), self.cells.cells(hi)
        n = self.cells.n
        for r in range(len(a)):
            ranges = [np.arange(c0[r, k], c1[r, k] + 1) for k in range(3)]
            cell = ((ranges[0][:, None, None] * n[1] + ranges[1][None, :, None]) * n[2]
                    + ranges[2][None, None, :]).ravel()
            starts, ends = self.cells.starts[cell], self.cells.starts[cell + 1]
            idx = np.unique(np.concatenate([self.cells.boxes[s:e] for s, e in zip(starts, ends)]))
            keep = ((self.lo[idx] <= hi[r]) & (lo[r] <= self.hi[idx])).all(axis=1)
            ps.append(idx[keep])
            rows.append(np.full(int(keep.sum()), r, dtype=np.int64))
        return np.concatenate(rows), np.concatenate(ps)

    def segments(self, q0: np.ndarray, q1: np.ndarray, want_t: bool):
        hit = np.zeros(len(q0), dtype=bool)
        tout = np.full(len(q0), np.nan)
        rows, ps = self._segment_candidates(q0, q1)
        if len(rows):
            with np.errstate(over="ignore", under="ignore", invalid="ignore"):
                v0, e0 = self._face_values(q0[rows], ps)
                v1, e1 = self._face_values(q1[rows], ps)
            beyond = ((v0 > e0) & (v1 > e1) & np.isfinite(v0) & np.isfinite(v1)).any(axis=1)
            rows, ps = rows[~beyond], ps[~beyond]
        for s in range(0, len(rows), _PAIRS):
            r, p = rows[s:s + _PAIRS], ps[s:s + _PAIRS]
            if not want_t:
                keep = ~hit[r]
                r, p = r[keep], p[keep]
                if not len(r):
                    continue
            v0, e0 = self._values(q0[r], p)
            v1, e1 = self._values(q1[r], p)
            with np.errstate(divide="ignore", invalid="ignore", over="ignore"):
                free, sure, _, _, _ = segment_filter(v0, v1, e0, e1)
            hit[r[sure]] = True
            todo = ~free & (~sure | want_t)
            for k in np.nonzero(todo)[0].tolist():
                if not want_t and hit[r[k]]:
                    continue
                entry = exact_segment_entry(self._exact_planes(int(p[k])), self.exponent,
                                            q0[r[k]].tolist(), q1[r[k]].tolist())
                if entry is not None:
                    hit[r[k]] = True
                    if want_t:
                        tout[r[k]] = np.fmin(tout[r[k]], float(entry))
        return hit, tout

    def signed_distance(self, q: np.ndarray) -> np.ndarray:
        inside = self.contains(q)
        out = np.zeros(len(q))
        if inside.any():
            out[inside] = -self._depth(q[inside])
        if (~inside).any():
            out[~inside] = self._distance_outside(q[~inside])
        return out

    def _depth(self, q: np.ndarray) -> np.ndarray:
        """Deepest containing piece: the least slab distance (every slab side supports the
        piece, and its facets' are among them), a lower bound on the union's depth."""
        depth = np.zeros(len(q))
        rows, ps = self.candidates(q)
        if not len(rows):
            return depth
        val, err = self._values(q[rows], ps)
        A, _ = self._columns_of(ps)
        norm = np.linalg.norm(A[:, :3, :], axis=1)
        with np.errstate(divide="ignore", invalid="ignore"):
            d = np.where(norm > 0, -val / norm, np.inf) * self.grid.step
        inside = (val <= err).all(axis=1)
        best = np.where(inside, np.maximum(d.min(axis=1), 0.0), 0.0)
        np.maximum.at(depth, rows, best)
        return depth

    def _distance_outside(self, q: np.ndarray) -> np.ndarray:
        """Distance to the nearest piece: the distance between triangle ``s`` and the
        triangle ``q - t`` (disjoint outside the piece). The nearest box's pair gives an upper
        bound; then only pairs whose box is nearer are evaluated (float; not a decision)."""
        S = self.grid.to_float(self.S.reshape(-1, 3)).reshape(self.S.shape)
        T = self.grid.to_float(self.T.reshape(-1, 3)).reshape(self.T.shape)
        best = np.full(len(q), np.inf)
        step = max(1, (1 << 20) // len(self.lo))
        for s in range(0, len(q), step):
            x = q[s:s + step]
            gap = np.maximum(np.maximum(self.lo[None] - x[:, None], x[:, None] - self.hi[None]),
                             0.0)
            box = np.sqrt(np.einsum("kpj,kpj->kp", gap, gap))
            first = box.argmin(axis=1)
            b = self._pair_distance(S, T, x, np.arange(len(x)), first)
            rows, ps = np.nonzero(box < b[:, None])
            for c in range(0, len(rows), 1 << 16):
                r, p = rows[c:c + (1 << 16)], ps[c:c + (1 << 16)]
                np.minimum.at(b, r, self._pair_distance(S, T, x, r, p))
            best[s:s + step] = b
        if self.grown:  # the grown piece is nearer by at most the box's half-diagonal
            best = np.maximum(best - float(np.linalg.norm(self._gf)) * self.grid.step, 0.0)
        return best

    def _pair_distance(self, S, T, x, rows, ps):
        i, j = self.pairs[ps, 0], self.pairs[ps, 1]
        return _tri_tri_distance(S[i], x[rows][:, None, :] - T[j])


class PairObstacle(CSpaceObstacle):
    """The C-obstacle ``∪ s ⊕ (c - t)`` of triangle pairs, exact, with no hull per pair.

    Built by :func:`cspace.scene.model.model_scene` for the ``triangle pairs`` construction. Answers
    ``contains``, ``segment_free``, ``first_contact`` and ``signed_distance`` like every
    C-obstacle (touching counts; inside, ``signed_distance`` is minus the deepest containing
    piece's depth, a lower bound on the union's).

    Attributes
    ----------
    pairs : TrianglePairs
    obstacle, robot :
        The operands (for FCL cross-checks); ``semantics`` says which are solid.
    kind : 'pairs'
    """

    kind = "pairs"

    def __init__(self, pairs: TrianglePairs, *, obstacle, robot, reference_point, grid):
        self.pairs = pairs
        self.polytope = None
        self.obstacle = obstacle
        self.robot = robot
        self.reference_point = np.asarray(reference_point, dtype=np.float64).reshape(3)
        self.grid = grid
        self.sum = None
        self._impl = _PairsCO(pairs.S, pairs.T, pairs.pairs, grid, pairs.margin)
        self.margin = Margin.none(grid)  # set by model_scene with the growth's deviation
        self._mesh = None

    @property
    def n_facets(self) -> int:
        """Slab sides over all pairs (17 slabs a pair, 38 when grown; two sides each)."""
        return 2 * self._impl.n_slabs * len(self.pairs.pairs)

    def _hull_mesh(self, which) -> tuple[np.ndarray, np.ndarray]:
        """The pieces ``which`` (indices into the pairs) as hulls in one mesh (flat ones
        thickened by a grid step): for drawing and sampling only; about 0.6 ms a pair."""
        tp, V, F, n = self.pairs, [], [], 0
        scratch = PairPieces([])
        for (i, j), f in zip(tp.pairs[which].tolist(), tp.flat[which].tolist()):
            piece = _piece(tp.piece_points(i, j), f and not tp.margin.any(), self.grid, scratch,
                           "piece")
            V.append(piece.vertices)
            F.append(piece.faces + n)
            n += len(piece.vertices)
        return np.vstack(V), np.vstack(F)

    def _hulls(self):
        if self._mesh is None:
            self._mesh = self._hull_mesh(np.arange(len(self.pairs.pairs)))
        return self._mesh

    def sample_mesh(self, rng, pieces: int = 256) -> tuple[np.ndarray, np.ndarray]:
        """Hulls of at most ``pieces`` random pieces (for sampling near the surface without
        building every hull)."""
        n = len(self.pairs.pairs)
        if n <= pieces:
            return self._hulls()
        return self._hull_mesh(np.sort(rng.choice(n, pieces, replace=False)))

    @property
    def vertices(self) -> np.ndarray:
        """(n, 3) float64 vertices of every piece's hull (overlapping; built on first use)."""
        return self._hulls()[0]

    @property
    def faces(self) -> np.ndarray:
        """(m, 3) int64 triangles of every piece's hull (overlapping; built on first use)."""
        return self._hulls()[1]

    @property
    def bounds(self) -> np.ndarray:
        return np.stack([self._impl.lo.min(axis=0), self._impl.hi.max(axis=0)])

    def __repr__(self) -> str:
        return f"PairObstacle(pairs={len(self.pairs.pairs)})"

    def plane_signs(self, q) -> np.ndarray:
        raise TypeError("plane_signs is defined for a convex C-obstacle, not triangle pairs")
