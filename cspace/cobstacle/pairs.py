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
surface       any            ``triangle pairs``: ``s ⊕ (c - t)`` per obstacle triangle s and
any           solid or       robot triangle t (a convex part's: its hull's facets), plus
              surface        containment terms (below)
============  =============  ===============================================================

An open body against a convex robot part is triangle pairs too. Its former construction, one
exact hull ``t ⊕ (c - R)`` per obstacle triangle t (about a millisecond each), took 77 s of
the 83 s one turn in place of an apartment-class world took (38.7k triangles, a piano's swept
hull), for every turn a planner reaches; with the hull's triangles as ``t`` the box trees
answer the same set (the convex part is closed: a sheet it swallows whole is its containment
term) with no build.

A convex obstacle against a non-convex robot part is triangle pairs too: the swapped sum
``O ⊕ (c - R) = -((R - c) ⊕ (-O))`` (NCC-CVMS on the robot) took 0.1-0.2 s a body, 6.6 s of
the 9 s an apartment-class world took (36 convex bodies against a 1,668-triangle robot), for
every orientation a turning planner reaches; the box trees answer the same set exactly with
no build.

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
surfaces the flat piece is needed and kept, exactly. A degenerate triangle (a segment or a point
that a feature thinner than the grid step snapped to:
:func:`cspace.mesh.components.snapping_losses`) has no normal and is never left out as flat
(:func:`_parallel`).

No pair is enumerated (:class:`PairObstacle`): each piece is the intersection of 17 slabs
whose normals come from the two triangles alone (:func:`pair_planes`), so no hull is built, and
a query finds the pairs whose piece can hold it the way a collision checker does, with a box
tree over the obstacle's triangles and one over the robot's traversed together (compiled,
:mod:`cspace.geometry._kernels.pairquery`); the candidates' slabs are evaluated with a float
filter and what it leaves is settled with Python integers. Building is the two trees, and
memory is linear in the triangles. Pieces grown by the outward-rounding box of
:mod:`cspace.cobstacle.margin` take 38 slabs, still exact. The grown pieces and the (ungrown)
containment terms hold the true C-obstacle: a robot component inside the obstacle for the float
input either stays inside after snapping (the term holds) or lies within the snapping deviation
of the boundary, where a grown pair piece holds it. References: ``pairs_reference._PairsCO`` (every pair
enumerated, numpy slabs) for the compiled engine, and :func:`triangle_pair_pieces` (one exact
hull per pair, 0.6 ms a pair) for both.

All coordinates are grid integers of the scene grid (robot frame for the robot part, the
reference point ``c`` snapped); sums and differences of grid integers are exact.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from ..mesh.convex import ConvexPolytope
from ..errors import DegenerateError
from ..geometry.exact import _FILTER, _TINY
from ..geometry.graphs import component_labels
from .margin import Margin
from .pair_sides import _primitive_normals, _side
from ..geometry.snapping import grow_points
from .obstacle import CSpaceObstacle
from .convex import exact_plane_sign, exact_segment_entry
from ..geometry._kernels import load

_pairquery = load("pairquery")

__all__ = ["CONSTRUCTIONS", "pair_construction", "is_sum", "PairPieces", "TrianglePairs",
           "triangle_pairs", "triangle_pair_pieces", "PairObstacle",
           "component_points", "containment_meshes", "TRIANGLE_BYTES", "pairs_memory"]

#: Every construction a pair can get, with what it computes.
CONSTRUCTIONS = {
    "CVMS": "convex ⊕ convex: one exact convex polytope",
    "NCC-CVMS": "non-convex closed obstacle ⊕ convex robot part: one exact closed surface",
    "triangle pairs": "open obstacle or non-convex robot part: one convex piece s ⊕ (c - t) "
                      "per obstacle triangle s and robot triangle t (found per query by two "
                      "box trees), plus exact containment terms for closed operands",
}

# Robot triangles handled per vectorised block of triangle pairs (memory).
_BLOCK = 1 << 18
# Candidate (query, pair) rows evaluated at once; padding value of unused slab sides.
_PAIRS = 1 << 12
_PAD = -1e300
# Pairs whose slab columns are kept in memory (about 2 KB a pair).
_KEEP = 1 << 15

#: Bytes a triangle-pair C-obstacle takes per triangle of its two operands (obstacle triangles
#: plus robot triangles) while it lives (``held``) and while it is built (``peak``), its share of
#: the scene model included: tracemalloc measured 682 and 1222 (tests/test_memory.py holds
#: them to it; the trees' 26-DOPs take 13 bounds a side where boxes took 3). Linear: no pair
#: is stored, and a side shared by several engines (_side) is counted in each.
TRIANGLE_BYTES = {"held": 768, "peak": 1408}


def pairs_memory(n_triangles: int) -> tuple[int, int]:
    """``(held, peak)`` bytes of triangle-pair C-obstacles over ``n_triangles`` triangles (each
    C-obstacle's obstacle and robot triangles summed; :data:`TRIANGLE_BYTES`)."""
    return TRIANGLE_BYTES["held"] * int(n_triangles), TRIANGLE_BYTES["peak"] * int(n_triangles)


def pair_construction(obstacle_kind: str, robot_kind: str, sums: bool = True) -> str:
    """The construction an (obstacle body, robot part) pair gets (a key of CONSTRUCTIONS).

    ``sums=False``: a solid body against a convex part is triangle pairs too, not NCC-CVMS
    (the same set, exactly, with nothing built: for a C-space asked a few queries, such as a
    turn in place, where building a sum per body costs more than all its queries)."""
    if robot_kind == "convex" and (obstacle_kind == "convex"
                                   or (obstacle_kind == "solid" and sums)):
        return {"convex": "CVMS", "solid": "NCC-CVMS"}[obstacle_kind]
    return "triangle pairs"


def is_sum(construction: str) -> bool:
    """The construction computes one Minkowski sum (CVMS, NCC-CVMS), not triangle pairs."""
    return construction in ("CVMS", "NCC-CVMS")


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


def _flat(tp: "TrianglePairs", i: np.ndarray, j: np.ndarray) -> np.ndarray:
    """Exact: are the pieces of pairs ``(i, j)`` flat pieces of two parallel triangles? The
    rule :func:`triangle_pairs` and the compiled engine apply."""
    return _parallel(_primitive_normals(tp.S)[i], _primitive_normals(-tp.T)[j])


def _parallel(ns: np.ndarray, nt: np.ndarray) -> np.ndarray:
    """Rows of canonical primitive normals that are equal and not zero: parallel triangles.

    A degenerate triangle (a segment or a point: a feature thinner than the grid step that
    snapping collapsed, or collinear corners) has a zero normal and is never called flat here:
    its piece ``s ⊕ t`` is a prism, not a polygon, unless the segment lies parallel to ``t``,
    and the rule that leaves flat pieces out (a neighbour's contact holds the same
    translations) speaks of two faces, not of a segment, which has no neighbours. Keeping a
    piece that happens to be flat is only redundant, never wrong."""
    return (ns == nt).all(axis=1) & ns.any(axis=1) & nt.any(axis=1)


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
        ``len(pairs)``.
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
                   closed: bool, margin=(0, 0, 0)) -> TrianglePairs:
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
        flat = _parallel(ns[ii], nt[jj])
        if closed:
            out.flat_skipped += int(flat.sum())
            ii, jj, flat = ii[~flat], jj[~flat], flat[~flat]
        out.kept += len(ii)
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


def component_points(ints: np.ndarray, faces: np.ndarray, fits_in=None) -> np.ndarray:
    """``(k, 3)``: one vertex (the first) of each connected component of a mesh (dtype kept)
    (triangles sharing a vertex are connected).

    ``fits_in``: an extent (3,); only components whose box is no larger on any axis are
    kept. A component can lie inside a solid only if it fits in the solid's box, so the
    containment terms of larger ones (walls, floors) can never hold and are not built.
    """
    F = np.asarray(faces, np.int64).reshape(-1, 3)
    if not len(F):
        return np.asarray(ints)[:0]
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


def _slab_columns(S: np.ndarray, T: np.ndarray, grown: bool, gf: np.ndarray):
    """Upper and lower slab sides of the pieces ``S[k] ⊕ T[k] ⊕ [-g, g]`` as columns
    ``a . [k, 1] <= 0``: ``(A (n, 4, 2K), absA (n, 4, 2K))`` float (K slabs), zero normals
    padded out; ``absA`` bounds the rounding (16 unit roundoffs of the sum of absolute products,
    the normals and supports rounded to float included)."""
    N = pair_planes(S, T, grown)
    K = N.shape[1]
    Nf = N.astype(np.float64)
    s_lo, s_hi, s_perm = _tri_support(Nf, S.astype(np.float64))
    t_lo, t_hi, t_perm = _tri_support(Nf, T.astype(np.float64))
    box = np.abs(Nf) @ gf  # the box's support, g_i |N_i| summed (rounded: in perm)
    valid = N.any(axis=2)
    A = np.zeros((len(S), 4, 2 * K))
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


def _depth_of(q: np.ndarray, A: np.ndarray, absA: np.ndarray, exponent: int, step: float):
    """Per row: the least slab distance of ``q`` in its piece (columns ``A``), 0 when the
    filter does not put it inside: a lower bound on the piece's depth at ``q``."""
    Q = np.ones((len(q), 1, 4))
    with np.errstate(over="ignore", under="ignore", invalid="ignore", divide="ignore"):
        np.ldexp(q, -exponent, out=Q[:, 0, :3])
        val = np.matmul(Q, A)[:, 0, :]
        err = _FILTER * np.matmul(np.abs(Q), absA)[:, 0, :] + _TINY
        norm = np.linalg.norm(A[:, :3, :], axis=1)
        d = np.where(norm > 0, -val / norm, np.inf) * step
    inside = (val <= err).all(axis=1)
    return np.where(inside, np.maximum(d.min(axis=1), 0.0), 0.0)


def _signed_distance(engine, q: np.ndarray) -> np.ndarray:
    """Minus the deepest containing piece's depth inside (exact sign), the distance to the
    nearest piece outside: what both pair engines answer for ``signed_distance``."""
    inside = engine.contains(q)
    out = np.zeros(len(q))
    if inside.any():
        out[inside] = -engine._depth(q[inside])
    if (~inside).any():
        out[~inside] = engine._distance_outside(q[~inside])
    return out


def _pair_halfspaces(S: np.ndarray, T: np.ndarray, g) -> list:
    """``(n, d)`` Python-int half-spaces ``n . k <= d`` of the piece ``S ⊕ T ⊕ [-g, g]`` of one
    pair (grid triangles ``S, T`` (3, 3) int64): the exact test both engines fall back to."""
    g = [int(x) for x in np.asarray(g).reshape(3)]
    N = pair_planes(S[None], T[None], any(g))[0]
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


class _TreePairsCO:
    """Exact queries on ``∪ s_i ⊕ t_j ⊕ box`` over *all* pairs of obstacle triangles ``S`` and
    robot vectors ``T`` (flat pairs left out when ``closed``), none enumerated (the engine of
    :class:`PairObstacle`).

    A query finds its candidate pairs the way a collision checker does: a box tree over the
    obstacle's triangles and one over the robot's, traversed together with the query added to
    the robot side (:mod:`cspace.geometry._kernels.pairquery`, compiled). Each candidate is
    tested on its 17 (38 grown) slabs with the float filter of :class:`_PairsCO`, which
    enumerates the pairs and is this engine's pure-Python reference
    (:mod:`cspace.cobstacle.pairs_reference`); a pair the filter leaves
    undecided is settled with Python integers (:func:`_pair_halfspaces`). Building is the two
    trees: O(n log n) time and O(n) memory in the triangles, not in the pairs.
    """

    def __init__(self, S: np.ndarray, T: np.ndarray, grid, *, closed: bool,
                 margin=(0, 0, 0)):
        # S (obstacle triangles, in grid's frame) moved to the scene frame by the grid's
        # origin, exactly: T holds vectors (c - t), so every piece is in the scene frame and a
        # query is only scaled (by a power of two), never shifted.
        S = np.asarray(S, np.int64) + np.asarray(grid.origin, np.int64)
        T = np.asarray(T, np.int64)
        if not len(S) or not len(T):
            raise ValueError("a triangle-pair C-obstacle needs triangles on both sides")
        self.grid, self.exponent = grid.vectors, grid.exponent
        self.g = np.asarray(margin, dtype=np.int64).reshape(3)
        self.grown = bool(self.g.any())
        self.closed = bool(closed)
        self.n_slabs = 38 if self.grown else 17
        # Each side (triangles, normals, k-DOP tree) is shared by every engine with the same
        # operand: the robot's by every body of a build, a body's by every orientation on
        # one grid (_side). k-DOPs on the directions both sides share.
        self.side_s, self.side_t = _side(S, self.g, False), _side(T, np.zeros(3, np.int64), True)
        if len(self.side_s.directions) != len(self.side_t.directions):
            k = min(len(self.side_s.directions), len(self.side_t.directions))
            self.side_s, self.side_t = self.side_s.on(k), self.side_t.on(k)
        self.S, self.T = self.side_s.X, self.side_t.X
        self.directions = self.side_s.directions
        self.tree_s, self.tree_r = self.side_s.tree, self.side_t.tree
        # the union's box (grid units, scene frame): the axis columns
        self.lo = self.grid.to_float(self.tree_s.lo[0, :3] - self.tree_r.hi[0, :3])[None]
        self.hi = self.grid.to_float(self.tree_s.hi[0, :3] - self.tree_r.lo[0, :3])[None]
        self._set = self._pair_set(self.tree_s, self.tree_r)
        self._scale = float(np.ldexp(1.0, -self.exponent))  # scene units to grid units, exact

    def _pair_set(self, tree_s, tree_r):
        """The compiled engine's view of the operands and the two trees."""
        s, t = self.side_s, self.side_t
        return _pairquery.PairSet(s.flat, t.flat, s.flat_f, t.flat_f, s.normals, t.normals,
                                  s.raw, t.raw, self.g, self.closed, tree_s, tree_r,
                                  self.directions)

    @property
    def nbytes(self) -> int:
        """Bytes this engine's two sides hold (triangles, normals, trees; a side shared with
        other engines counted in each)."""
        return self.side_s.nbytes + self.side_t.nbytes

    def _grid_units(self, q: np.ndarray) -> np.ndarray:
        with np.errstate(over="ignore", under="ignore"):
            return np.ascontiguousarray(np.ldexp(q, -self.exponent))

    def _halfspaces(self, i: int, j: int) -> list:
        return _pair_halfspaces(self.S[i], self.T[j], self.g)

    def _in_piece(self, i: int, j: int, x: list) -> bool:
        """Exactly: the point ``x`` (scene frame, floats) lies in the piece of pair ``(i, j)``."""
        return all(exact_plane_sign(n, d, self.exponent, x) <= 0
                   for n, d in self._halfspaces(i, j))

    def _meets_piece(self, i: int, j: int, x0: list, x1: list) -> bool:
        """Exactly: the closed segment ``x0 x1`` meets the piece of pair ``(i, j)``."""
        return exact_segment_entry(self._halfspaces(i, j), self.exponent, x0, x1) is not None

    def contains_point(self, x: list) -> bool:
        """One state (three floats, scene frame): the compiled filter, then the exact piece
        test on the pairs it leaves."""
        status, todo = self._set.contains_one(*x, self._scale)
        return status == 1 or (status == 2 and any(self._in_piece(i, j, x) for i, j in todo))

    def contains(self, q: np.ndarray) -> np.ndarray:
        if len(q) == 1:  # one state, as a planner asks: no array round trips
            return np.array([self.contains_point(q[0].tolist())])
        status, todo = self._set.contains(self._grid_units(q))
        out = status == 1
        for r, i, j in todo.tolist():
            if not out[r]:
                out[r] = self._in_piece(i, j, q[r].tolist())
        return out

    def segments(self, q0: np.ndarray, q1: np.ndarray, want_t: bool):
        hit = np.zeros(len(q0), dtype=bool)
        tout = np.full(len(q0), np.nan)
        if not want_t and len(q0) == 1:
            x0, x1 = q0[0].tolist(), q1[0].tolist()
            status, todo = self._set.segment_one(*x0, *x1, self._scale)
            hit[0] = status == 1 or (status == 2 and any(
                self._meets_piece(i, j, x0, x1) for i, j in todo))
            return hit, tout
        if not want_t:
            status, todo = self._set.segments(self._grid_units(q0), self._grid_units(q1))
            hit[status == 1] = True
            for r, i, j in todo.tolist():
                if not hit[r] and self._meets_piece(i, j, q0[r].tolist(), q1[r].tolist()):
                    hit[r] = True
            return hit, tout
        # first contact: the exact entry of every pair the filter does not rule out
        todo = self._set.segment_pairs(self._grid_units(q0), self._grid_units(q1))
        for r, i, j in todo.tolist():
            entry = exact_segment_entry(self._halfspaces(i, j), self.exponent,
                                        q0[r].tolist(), q1[r].tolist())
            if entry is not None:
                hit[r] = True
                tout[r] = np.fmin(tout[r], float(entry))
        return hit, tout

    def signed_distance(self, q: np.ndarray) -> np.ndarray:
        return _signed_distance(self, q)

    def _depth(self, q: np.ndarray) -> np.ndarray:
        """Deepest containing piece: the least slab distance (every slab side supports the
        piece, and its facets' are among them), a lower bound on the union's depth."""
        depth = np.zeros(len(q))
        Q = self._grid_units(q)
        cand = self._set.candidates(Q, Q)
        if len(cand):
            r, i, j = cand.T
            A, absA = _slab_columns(self.S[i], self.T[j], self.grown,
                                    self.g.astype(np.float64))
            np.maximum.at(depth, r, _depth_of(q[r], A, absA, self.exponent, self.grid.step))
        return depth

    def _distance_outside(self, q: np.ndarray) -> np.ndarray:
        """Distance to the nearest piece (float; not a decision): of triangle ``s`` to the
        triangle ``q - t``, minimised by a branch and bound over the two trees (compiled)."""
        best = self._set.distances(self._grid_units(q)) * self.grid.step
        if self.grown:  # the grown piece is nearer by at most the box's half-diagonal
            best = np.maximum(best - float(np.linalg.norm(self.g.astype(np.float64)))
                              * self.grid.step, 0.0)
        return best


class PairObstacle(CSpaceObstacle):
    """The C-obstacle ``∪ s ⊕ (c - t)`` over every pair of an obstacle triangle s and a robot
    triangle t, exact, with no pair enumerated and no hull built.

    Built by :func:`cspace.scene.model.model_scene` for the ``triangle pairs`` construction:
    two box trees, O(n log n) in the triangles (:class:`_TreePairsCO`). Answers ``contains``,
    ``segment_free``, ``first_contact`` and ``signed_distance`` like every C-obstacle
    (touching counts; inside, ``signed_distance`` is minus the deepest containing piece's
    depth, a lower bound on the union's).

    Attributes
    ----------
    S : (m, 3, 3) int64
        Obstacle triangles (grid units, the grid's frame).
    T : (l, 3, 3) int64
        ``c - t`` for the robot triangles t (grid units).
    closed : bool
        Whether an operand is closed (flat pieces are then left out, see the module).
    margin : (3,) int64
        Every piece is grown by the box ``[-margin, margin]`` (grid steps).
    obstacle, robot :
        The operands (for FCL cross-checks); ``semantics`` says which are solid.
    kind : 'pairs'
    """

    kind = "pairs"

    def __init__(self, S, T, *, closed: bool, margin=(0, 0, 0), obstacle, robot,
                 reference_point, grid):
        self.S = np.asarray(S, dtype=np.int64).reshape(-1, 3, 3)
        self.T = np.asarray(T, dtype=np.int64).reshape(-1, 3, 3)
        self.closed = bool(closed)
        self.polytope = None
        self.obstacle = obstacle
        self.robot = robot
        self.reference_point = np.asarray(reference_point, dtype=np.float64).reshape(3)
        self.grid = grid
        self.sum = None
        self._impl = _TreePairsCO(self.S, self.T, grid, closed=self.closed, margin=margin)
        self.margin = Margin.none(grid)  # set by model_scene with the growth's deviation
        self._mesh = None
        self._pairs = None

    @property
    def n_pairs(self) -> int:
        """Triangle pairs the union ranges over (flat ones of a closed operand included)."""
        return len(self.S) * len(self.T)

    @property
    def nbytes(self) -> int:
        """Bytes the query engine holds: linear in the triangles, not in the pairs."""
        return self._impl.nbytes

    @property
    def pairs(self) -> TrianglePairs:
        """Every pair enumerated (:func:`triangle_pairs`, no bounds): O(pairs) memory, for
        the reference construction and drawing only, never for queries."""
        if self._pairs is None:
            tp = TrianglePairs(self.S, self.T, np.zeros((0, 2), np.int64), np.zeros(0, bool),
                               margin=self._impl.g)
            ii, jj = np.divmod(np.arange(self.n_pairs, dtype=np.int64), len(self.T))
            flat = _flat(tp, ii, jj)
            keep = ~flat if self.closed else np.ones(len(ii), bool)
            tp.pairs, tp.flat = np.stack([ii[keep], jj[keep]], axis=1), flat[keep]
            tp.flat_skipped, tp.kept = int((~keep).sum()), int(keep.sum())
            self._pairs = tp
        return self._pairs

    @property
    def n_facets(self) -> int:
        """Slab sides over all pairs (17 slabs a pair, 38 when grown; two sides each)."""
        return 2 * self._impl.n_slabs * self.n_pairs

    def _hull_mesh(self, pairs: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """The pieces of ``pairs`` ((k, 2) indices ``(i, j)``) as hulls in one mesh (flat ones
        thickened by a grid step): for drawing and sampling only; about 0.6 ms a pair."""
        tp = TrianglePairs(self.S, self.T, pairs, np.zeros(len(pairs), bool),
                           margin=self._impl.g)
        flat = _flat(tp, pairs[:, 0], pairs[:, 1])
        V, F, n = [], [], 0
        scratch = PairPieces([])
        for (i, j), f in zip(pairs.tolist(), flat.tolist()):
            piece = _piece(tp.piece_points(i, j), f and not tp.margin.any(), self.grid,
                           scratch, "piece")
            V.append(piece.vertices)
            F.append(piece.faces + n)
            n += len(piece.vertices)
        return np.vstack(V), np.vstack(F)

    def _hulls(self):
        if self._mesh is None:
            self._mesh = self._hull_mesh(self.pairs.pairs)
        return self._mesh

    def sample_mesh(self, rng, pieces: int = 256) -> tuple[np.ndarray, np.ndarray]:
        """Hulls of at most ``pieces`` random pieces (for sampling near the surface without
        building every hull): pairs drawn uniformly, flat ones of a closed operand redrawn."""
        if self.n_pairs <= pieces:
            return self._hulls()
        tp = TrianglePairs(self.S, self.T, np.zeros((0, 2), np.int64), np.zeros(0, bool))
        chosen = np.zeros((0, 2), np.int64)
        for _ in range(64):
            k = np.sort(rng.choice(self.n_pairs, min(4 * pieces, self.n_pairs), replace=False))
            ij = np.stack(np.divmod(k, len(self.T)), axis=1)
            if self.closed:
                ij = ij[~_flat(tp, ij[:, 0], ij[:, 1])]
            chosen = np.unique(np.vstack([chosen, ij]), axis=0)
            if len(chosen) >= pieces:
                break
        if not len(chosen):
            return self._hulls()
        return self._hull_mesh(chosen[np.sort(rng.choice(len(chosen), min(pieces, len(chosen)),
                                                         replace=False))])

    @property
    def vertices(self) -> np.ndarray:
        """(n, 3) float64 vertices of every piece's hull (overlapping; built on first use,
        about 0.6 ms a pair)."""
        return self._hulls()[0]

    @property
    def faces(self) -> np.ndarray:
        """(m, 3) int64 triangles of every piece's hull (overlapping; built on first use)."""
        return self._hulls()[1]

    @property
    def bounds(self) -> np.ndarray:
        return np.concatenate([self._impl.lo, self._impl.hi])

    def __repr__(self) -> str:
        return (f"PairObstacle(obstacle_triangles={len(self.S)}, robot_triangles={len(self.T)}, "
                f"closed={self.closed})")

    def plane_signs(self, q) -> np.ndarray:
        raise TypeError("plane_signs is defined for a convex C-obstacle, not triangle pairs")
