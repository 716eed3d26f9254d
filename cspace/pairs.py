"""C-obstacles of one obstacle body against one part of a non-convex robot, exactly.

A robot is modelled like an obstacle (:func:`cspace.model.model_scene`): welded, double-sided
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
*containment terms*, each a closed mesh queried exactly (:mod:`cspace.meshquery`):

- closed robot part R: ``o + c - R`` for one vertex o of each connected component of the
  obstacle (the robot at q holds o);
- closed obstacle O: ``O + c - r`` for one vertex r of each connected component of the part
  (O holds the robot's vertex r).

A component either meets the other operand's boundary (a triangle pair) or lies wholly
inside or outside it, so the terms complete the union exactly.

Flat pieces: ``s ⊕ (c - t)`` of two parallel triangles is a flat polygon. When either operand
is closed such a piece adds nothing: a contact of two coplanar faces reaches the edge of the
coplanar face region of the closed operand, where a non-parallel neighbour triangle meets the
other operand too (or a containment term holds). Those pieces are left out. When both are open
surfaces the flat piece is needed, and it is built as the hull of its sums moved by one grid
step along each axis (the polygon ⊕ an octahedron of radius one step): it contains the exact
piece and lies within one grid step of it, a false collision within that bound and never a
false free. :attr:`PairPieces.thickened` counts them, and the stated error bound grows by one
grid step where it is non-zero.

All coordinates are grid integers of the scene grid (robot frame for the robot part, the
reference point ``c`` snapped); sums and differences of grid integers are exact.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy.sparse import coo_matrix
from scipy.sparse.csgraph import connected_components

from .convex import ConvexPolytope
from .errors import DegenerateError

__all__ = ["CONSTRUCTIONS", "pair_construction", "PairPieces", "triangle_pair_pieces",
           "convex_triangle_pieces", "component_points", "containment_meshes"]

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
        Flat pieces of two open surfaces, grown by one grid step (see the module docstring).
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


def triangle_pair_pieces(o_ints, o_faces, r_ints, r_faces, c_ints, grid, bounds_g, *,
                         closed: bool, progress=None) -> PairPieces:
    """The pieces ``s ⊕ (c - t)`` of every obstacle triangle s and robot triangle t.

    Parameters
    ----------
    o_ints, o_faces : (n, 3) int64, (m, 3) int64
        Obstacle body (grid units, world frame).
    r_ints, r_faces : (k, 3) int64, (l, 3) int64
        Robot part (grid units, robot frame).
    c_ints : (3,) int64
        The snapped reference point.
    grid : Grid
    bounds_g : (2, 3) float64
        Planning bounds in grid units; pieces whose box misses them are left out.
    closed : bool
        Whether either operand is closed (flat pieces are then left out, else thickened).
    progress : callable, optional
        ``progress(fraction)`` while pieces are built.
    """
    S = np.asarray(o_ints, np.int64)[np.asarray(o_faces, np.int64)]          # (m, 3, 3)
    T = np.asarray(c_ints, np.int64) - np.asarray(r_ints, np.int64)[np.asarray(r_faces, np.int64)]
    out = PairPieces([])
    ns, nt = _primitive_normals(S), _primitive_normals(-T)
    s_lo, s_hi, t_lo, t_hi = S.min(axis=1), S.max(axis=1), T.min(axis=1), T.max(axis=1)
    per = max(1, _BLOCK // max(1, len(T)))
    todo = []
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
        todo.append((ii, jj, flat))
    total = sum(len(ii) for ii, _, _ in todo)
    done = 0
    for ii, jj, flat in todo:
        for i, j, f in zip(ii.tolist(), jj.tolist(), flat.tolist()):
            pts = (S[i][:, None, :] + T[j][None, :, :]).reshape(-1, 3)
            out.pieces.append(_piece(pts, f, grid, out, f"pair {i}x{j}"))
            done += 1
            if progress is not None and done % 256 == 0:
                progress(done / total)
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


def component_points(ints: np.ndarray, faces: np.ndarray) -> np.ndarray:
    """``(k, 3)``: one vertex (the first) of each connected component of a mesh (dtype kept)
    (triangles sharing a vertex are connected)."""
    F = np.asarray(faces, np.int64)
    n = len(ints)
    a, b = F.reshape(-1), np.repeat(F[:, 0], 3)
    g = coo_matrix((np.ones(len(a)), (a, b)), shape=(n, n))
    _, label = connected_components(g, directed=False)
    used = np.unique(F)
    _, first = np.unique(label[used], return_index=True)
    return np.asarray(ints)[used[first]]


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
