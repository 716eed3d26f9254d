"""NCC-CVMS step 3: triangulation of arrangement faces (with holes) without new vertices.

:func:`triangulate_face` / :func:`triangulate_rings` (ear clipping with bridges, exact
predicates), :func:`face_triangles` and :func:`known_triangles` (cached per face),
:func:`inner_point` (a point in a face's closure: the centroid of its first triangle) and
:func:`strict_inner_point` (one on no edge or vertex).
"""

from __future__ import annotations

from ..geometry._kernels import load
from ..geometry.homogeneous import _cross, _dot, _hcentroid, _hdir, _hom, _hon_segment, _horient, _hturn
from .plane_arrangement import Arrangement2D

__all__ = [
    "face_triangles",
    "known_triangles",
    "strict_inner_point",
    "inner_point",
    "plain_interior",
    "triangulate_face",
    "triangulate_rings",
]


_compiled = load("planar")


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


def _bridge_holes_reference(P: list, ids: list, pending: list) -> tuple[list, list]:
    """(Reference of ``cspace.geometry._kernels.planar.bridge_holes``.) Join each hole of
    ``pending`` (``(points, ids)`` pairs) to the polygon ``(P, ids)`` by a segment between two
    mutually visible vertex occurrences (exact cone and crossing tests; holes that only see
    other holes wait for a later round), nearest pairs first; returns the bridged
    ``(P, ids)``."""
    P, ids, pending = list(P), list(ids), list(pending)
    while pending:
        others = [P] + [hp for hp, _ in pending]
        done = False
        for hi, (HP, Hid) in enumerate(pending):
            # nearest pairs first (a heuristic order: any visible pair is correct)
            fp = [(x / w, y / w) for x, y, w in P]
            fh = [(x / w, y / w) for x, y, w in HP]
            cands = sorted(
                ((fh[j][0] - fp[i][0]) * (fh[j][0] - fp[i][0])
                 + (fh[j][1] - fp[i][1]) * (fh[j][1] - fp[i][1]), i, j)
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
    return P, ids


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
    """(Reference of ``cspace.geometry._kernels.planar.straight_runs``.) Drop the vertices where a cycle goes straight on (collinear, same direction) and which
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
    """(Reference of ``cspace.geometry._kernels.planar.clip_simple``.) Ear clipping of a simple counter-clockwise polygon (distinct vertices): an ear is a
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
    """(Reference of ``cspace.geometry._kernels.planar.clip_general``.) Ear clipping of any polygon
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
    pending = [([H[v] for v in h], list(h)) for h in holes]
    P, ids = _compiled.bridge_holes([H[v] for v in poly], list(poly), pending)
    tris = None
    if len(set(ids)) == len(ids):
        if convex and not holes:
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


def inner_point(arr: Arrangement2D, f: int) -> tuple[int, int, int]:
    """Homogeneous integer point in the closure of face ``f`` of ``arr``, in the open face up to an
    isolated vertex or a dangling edge (enough to read a coverage that is constant on the
    face): the centroid of the first triangle of :func:`face_triangles` (cached)."""
    c = arr._centroids.get(f)
    if c is None:
        a, b, d = face_triangles(arr, f)[0]
        c = arr._centroids[f] = _hcentroid(arr._H[a], arr._H[b], arr._H[d])
    return c


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
        return inner_point(arr, f)
    return _hom(arr.faces[f].sample)
