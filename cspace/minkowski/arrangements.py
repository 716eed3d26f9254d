"""NCC-CVMS steps 2, 3 and 6, stage ``arrangements``: one exact 2D arrangement per supporting plane.

Each plane's arrangement (:class:`cspace.minkowski.plane_arrangement.Arrangement2D`) holds the
cuts from other planes and the edges that can bound a change of coverage; every face gets its
net signed coverage (:mod:`.coverage`: coplanar conjoint facets merge, opposite ones cancel),
faces of non-zero coverage are the sub-facets, triangulated without new vertices
(:mod:`.triangulation`) and lifted back to 3D as exact homogeneous points (:class:`_Complex`).
Planes run in several processes above ``_PARALLEL_FROM`` units of work.
"""

from __future__ import annotations

from dataclasses import dataclass
from math import gcd

import numpy as np

from ..errors import ExactnessError
from ..workers import can_fork, forked_map
from .coverage import Coverage, polygon_coverage, pushed_inside, sample_point, sampled_coverage
from ..geometry.homogeneous import _hnorm, project_homogeneous
from ..geometry._kernels import load
from .intersections import _Cuts
from .plane_arrangement import Arrangement2D
from .planes import _Planes
from .triangulation import inner_point, known_triangles, plain_interior, strict_inner_point


@dataclass
class _Complex:
    """The sub-facets (faces of non-zero support of the plane arrangements) and their edges.

    ``points[i]``: canonical ``(X, Y, Z, W)`` (Python ints, ``W > 0``, primitive) of global
    vertex ``i`` in grid units. Sub-facet ``f`` lies on plane ``face_plane[f]`` with net
    coverage ``face_cov[f]`` counted along ``planes.normal(plane)``; ``_face_tris(cx, f)``
    tiles it with triangles (global ids, counter-clockwise about ``planes.normal``): they are
    ``face_tris[f]``, or, where that is None, made on first use from its boundary cycles
    ``face_rings[f]`` (global ids, outer first) projected along ``plane_axis[plane]``.
    ``face_src[f]`` is a superset facet covering it and ``face_point[f]`` an exact homogeneous
    point strictly inside it (on no edge or vertex of its arrangement), None where the
    centroid of its first triangle is one (lone uncut triangles, faces with a plain interior;
    :func:`cspace.minkowski.membership._face_point` makes it when asked). Incidence ``k``: sub-facet ``inc_face[k]`` has a boundary half-edge on edge ``inc_edge[k]`` (``edges[e] = (u, v)``,
    ``u < v``), running ``u -> v`` when ``inc_sign[k] = +1``; the sub-facet lies on its left
    seen from ``planes.normal``.
    """

    points: list
    edges: np.ndarray
    face_plane: np.ndarray
    face_cov: np.ndarray
    inc_face: np.ndarray
    inc_edge: np.ndarray
    inc_sign: np.ndarray
    face_tris: list
    face_rings: list
    plane_axis: list
    face_src: np.ndarray
    face_point: list


_planar = load("planar")


def _lift(H, key, ax: int) -> tuple:
    """Canonical homogeneous 3D point of the projected point ``H = (x, y, w)`` of plane ``key``
    (the reference of the compiled one-facet planes' lift)."""
    x, y, w = H
    n0, n1, n2, d = key
    n = (n0, n1, n2)
    a, b = (ax + 1) % 3, (ax + 2) % 3
    P = [0, 0, 0]
    P[a], P[b] = x * n[ax], y * n[ax]
    P[ax] = d * w - n[a] * x - n[b] * y
    W = w * n[ax]
    if W < 0:
        P, W = [-c for c in P], -W
    g = gcd(P[0], P[1], P[2], W)
    return (P[0] // g, P[1] // g, P[2] // g, W // g)


def _projected_segments(segs3: list, ax: int) -> list:
    """Segments of homogeneous 3D points projected along axis ``ax`` to canonical homogeneous
    2D points (reference of ``_kernels.planar.projected_segments``)."""
    return [(_hnorm(*project_homogeneous(x, ax)), _hnorm(*project_homogeneous(y, ax)))
            for x, y in segs3]


def _pinned_edges(planes: _Planes) -> np.ndarray:
    """``pinned[3 t + j]``: edge ``j`` (corners ``j -> j + 1``) of triangle ``t`` is, by its
    labels, also an edge of a triangle of another plane, or its uses (with their directions
    and weights) do not cancel. The first kind is SHARED_EDGE for
    :func:`cspace.geometry.tritri.intersect_pairs`, so no cut marks the edge; along the second
    (a rim of the reduced superset, which is not a cycle) the coverage changes. Either must
    stay in its plane's arrangement."""
    F = planes.faces
    u = F.reshape(-1)
    v = F[:, [1, 2, 0]].reshape(-1)
    lo, hi = np.minimum(u, v), np.maximum(u, v)
    pl = np.repeat(planes.plane, 3)
    use = np.where(u < v, 1, -1) * np.repeat(planes.weight, 3)
    order = np.lexsort((pl, hi, lo))
    lo_s, hi_s, pl_s = lo[order], hi[order], pl[order]
    new = np.ones(len(order), dtype=bool)
    new[1:] = (lo_s[1:] != lo_s[:-1]) | (hi_s[1:] != hi_s[:-1])
    group = np.cumsum(new) - 1
    first = np.nonzero(new)[0]
    last = np.append(first[1:], len(order)) - 1
    pin = pl_s[first] != pl_s[last]  # sorted by plane inside each group: on two planes
    pin |= np.add.reduceat(use[order], first) != 0  # or its uses do not cancel
    pinned = np.zeros(len(order), dtype=bool)
    pinned[order] = pin[group]
    return pinned


class _PlaneJobs:
    """What the per-plane arrangements read, as Python lists (a forked worker inherits it)."""

    def __init__(self, ints: np.ndarray, planes: _Planes, cuts: _Cuts):
        self.planes = planes
        self.cuts = cuts
        self.corners = ints[planes.faces].tolist()
        self.weight = planes.weight.tolist()
        self.facet = planes.facet.tolist()
        self.sign = planes.sign.tolist()
        self.sigma = planes.sigma.tolist()
        self.axis = planes.axis.tolist()
        self.members = [m.tolist() for m in planes.members]
        self.pinned = _pinned_edges(planes).tolist()
        self.vertex_ids = planes.faces.tolist()

    def trivial(self, p: int) -> bool:
        """Uncut triangles of one superset facet (a fan of a convex polygon: they do not
        overlap) are sub-facets as they are; no arrangement needed."""
        return not self.cuts.segments[p] and self._one_source(self.members[p])

    def _one_source(self, tl: list) -> bool:
        """The triangles ``tl`` are all of one superset facet."""
        f = self.facet[tl[0]]
        return all(self.facet[t] == f for t in tl)

    def cost(self, p: int) -> int:
        """Rough work of plane ``p``'s arrangement (its inputs; quadratic beyond a few tens),
        a quarter of it for the triangles of one facet (mostly one compiled call:
        :meth:`arrange`; measured on star ⊕ ico320, about 2 us a unit against 8)."""
        tl = self.members[p]
        n = len(tl) + len(self.cuts.segments[p])
        return (n + n * n // 64) // (4 if self._one_source(tl) else 1)

    def arrange(self, p: int, compiled: bool = True):
        """Sub-facets of arrangement plane ``p``: ``(lifted, faces)`` with ``lifted[v]`` the
        canonical 3D point of local vertex ``v`` and, per face of non-zero support,
        ``(coverage, boundary cycles, triangles or None, source facet, inner point or None)``
        in local vertex ids (cycles: the outer one, then the holes, as vertex lists).
        ``compiled=False`` runs the pure-Python reference of the compiled steps (identical
        outputs, ``tests/test_kernels.py``)."""
        ax = self.axis[p]
        a, b = (ax + 1) % 3, (ax + 2) % 3
        tl = self.members[p]
        key = self.planes.keys[p]
        one = self._one_facet(tl)
        if one:
            # One convex facet whose whole boundary is in the arrangement: every bounded face
            # lies in it (nothing is drawn outside), so each is covered once, by the facet.
            c = self.weight[tl[0]] * self.sign[tl[0]] * self.sigma[p]
            if compiled:  # most planes: set up, arranged and read in one compiled call
                done = _planar.one_facet_plane(self.corners, tl, self.pinned, self.cuts.segments[p],
                                               ax, c, self.facet[tl[0]], tuple(key))
                if done is not None:
                    return done
        polys = [[(q[a], q[b], 1) for q in self.corners[t]] for t in tl]
        cut3 = self.cuts.segments[p]
        segs = _planar.projected_segments(cut3, ax) if compiled else _projected_segments(cut3, ax)
        # The net coverage changes only where another plane's sheet meets this one or a
        # sheet ends: along the cuts, the edges shared by label with other planes' triangles
        # and the edges whose uses do not cancel (the pinned edges). Where the net coverage
        # is 0, the sheets of one orientation cover exactly where those of the other do, so
        # the edges of the less frequent orientation bound the kept (support != 0) part.
        # Other triangle edges stay out.
        sg = [self.sign[t] for t in tl]
        minority = -1 if sg.count(1) >= sg.count(-1) else 1
        pinned = self.pinned
        pin = [(i, j) for i, t in enumerate(tl) for j in range(3) if pinned[3 * t + j] or sg[i] == minority]
        seg2 = [(polys[i][j], polys[i][(j + 1) % 3]) for i, j in pin] + segs
        lab2 = pin + [(-1, k) for k in range(len(segs))]
        # the 3D points of the inputs are known; only crossings made in the plane are lifted
        known = {(q[a], q[b], 1): (q[0], q[1], q[2], 1) for t in tl for q in self.corners[t]}
        for (x, y), (px, py) in zip(cut3, segs):
            known[px] = x
            known[py] = y
        if one:
            arr = Arrangement2D(seg2, lab2, canonical=True)
            cov = Coverage(arr, [c] * len(arr.faces), [abs(c)] * len(arr.faces))
        else:
            weights = [self.weight[t] for t in tl]
            try:
                cov = sampled_coverage(polys, weights, seg2, lab2, canonical=True,
                                       compiled=compiled,
                                       source_turn=[self.sign[t] * self.sigma[p] for t in tl])
            except ValueError:  # pragma: no cover - the certificate failed: cut by every edge
                cov = polygon_coverage(polys, weights, segs)
            arr = cov.arrangement
        lifted = [known.get(h) or _lift(h, key, ax) for h in arr._H]
        origin = arr.half_edge_origin
        faces = []
        for f, (c, support) in enumerate(zip(cov.coverage, cov.support)):
            if support == 0:
                continue  # covered by no superset triangle
            face = arr.faces[f]
            rings = [[origin[h] for h in cyc] for cyc in (face.outer, *face.holes)]
            # Most sub-facets are not output (a fifth to a half of them are) and few need a
            # membership point, so triangles not made already wait until asked (_face_tris).
            tris = known_triangles(arr, f)
            src = self.facet[tl[0]] if one else self._source_facet(
                p, arr, f, tl, cov.first[f] if cov.first else None)
            # where the centroid of the first triangle is a strict inner point, it too is made
            # only when asked (_face_point)
            point = None if plain_interior(arr, f) else _lift(strict_inner_point(arr, f), key, ax)
            faces.append((c, rings, tris, src, point))
        return lifted, faces

    def _one_facet(self, tl: list) -> bool:
        """The triangles ``tl`` of a plane are the fan of one superset facet (one weight,
        one orientation) and every edge of the fan's boundary is pinned (so in the
        arrangement): the edges used once in the fan, by their vertex labels."""
        if not self._one_source(tl):
            return False
        once: dict = {}
        for t in tl:
            ids = self.vertex_ids[t]
            for j in range(3):
                u, v = ids[j], ids[(j + 1) % 3]
                key = (u, v) if u < v else (v, u)
                once[key] = None if key in once else 3 * t + j
        pinned = self.pinned
        return all(k is None or pinned[k] for k in once.values())

    def _source_facet(self, p: int, arr, f: int, tl: list, first=None) -> int:
        """A superset facet whose triangle covers (part of) face ``f``: one whose edge bounds
        the face from the covered side, else the first in plane order covering the face's
        inner point (``first``: its index in ``tl`` as the coverage found it, -1 for none;
        else tested here at its :func:`sample_point`). (A face may be covered by several
        coplanar facets of one orientation: the merge of step 2; it names one of them.)"""
        if len(tl) == 1:
            return self.facet[tl[0]]
        ax = self.axis[p]
        a, b = (ax + 1) % 3, (ax + 2) % 3
        face = arr.faces[f]
        H, origin = arr._H, arr.half_edge_origin
        ccw = self.sigma[p]
        # A triangle with an edge along the face's boundary, on the face's side of it,
        # covers the face next to that edge.
        for h in face.outer:
            for i, j in arr.edge_labels[h // 2]:
                if i < 0:
                    continue
                t = tl[i]
                c = self.corners[t]
                u, v = c[j], c[(j + 1) % 3]
                d_tri = (v[a] - u[a], v[b] - u[b])
                p0, p1 = H[origin[h]], H[origin[h ^ 1]]
                d_face = (p1[0] * p0[2] - p0[0] * p1[2], p1[1] * p0[2] - p0[1] * p1[2])
                same = d_tri[0] * d_face[0] + d_tri[1] * d_face[1] > 0
                if same == (self.sign[t] * ccw > 0):
                    return self.facet[t]
        if first is not None:
            if first >= 0:
                return self.facet[tl[first]]
        else:
            X, Y, W = sample_point(arr, f)
            for t in tl:
                if pushed_inside([(c[a], c[b]) for c in self.corners[t]], self.sign[t] * ccw,
                                 X, Y, W):
                    return self.facet[t]
        raise ExactnessError(f"face {f} of plane {p} is covered by no superset triangle")  # pragma: no cover


# Below this much estimated work (sum of _PlaneJobs.cost) the arrangements run in this
# process: forking and collecting results (some 15-20 ms, copy-on-write faults, the results
# pickled back) would cost more than they save. Measured with the one-facet kernel, the
# arrangement stage in 2 processes against 1: star ⊕ ico320 (4546 units) 0.95x,
# Centaur-1000 ⊕ ico320 (5342) 0.91x, flange-part-1042 ⊕ box (14872: one plane holds most
# of it) 0.84x; flange-990 ⊕ ico320 (15482) 1.16x, trap ⊕ ico320 (60255) 1.18x.
_PARALLEL_FROM = 15000


def _run_arrangements(jobs: _PlaneJobs, todo: list, workers: int, report,
                      check=None) -> tuple[dict, int]:
    """``{plane: jobs.arrange(plane)}`` for the planes ``todo``, in this process and
    ``workers - 1`` forked ones when there is enough work (results do not depend on the
    number of workers), and the number of processes used. ``check(stage, detail)`` (a
    :class:`cspace.memory.MemoryGuard`'s) is called every 64 planes, in the workers too."""
    n = len(todo)
    total = sum(jobs.cost(p) for p in todo)
    out: dict = {}
    if check is None:
        check = lambda stage, detail="": None  # noqa: E731 - nothing watched

    def chunk(ps: list) -> list:
        check("arrangements")
        return [(p, jobs.arrange(p)) for p in ps]

    if workers > 1 and n >= 16 and total >= _PARALLEL_FROM and can_fork():
        # largest first, then chunks small enough to balance the two ends
        order = sorted(todo, key=jobs.cost, reverse=True)
        size = max(1, min(64, n // (8 * workers)))
        chunks = [order[k: k + size] for k in range(0, n, size)]
        for _, res in forked_map(chunk, chunks, workers):
            out.update(res)
            report("arrangements", len(out) / n)
        return out, workers
    for k, p in enumerate(todo):
        out[p] = jobs.arrange(p)
        if k % 64 == 0:
            check("arrangements", f" ({k:,} of {n:,} planes)")
            if k % 256 == 0:
                report("arrangements", k / max(n, 1))
    return out, 1


def _assemble_reference(done: dict, n_planes: int, members: list, sign: list, sigma: list,
                        corners: list, weight: list, facet: list) -> tuple:
    """The sub-facets of every plane with global vertex ids (the reference of
    ``_kernels.planar.assemble_complex``, the same outputs but the half-edges as lists)."""
    vid: dict = {}
    face_plane, face_cov, face_tris, face_rings, face_src, face_point = [], [], [], [], [], []
    ring_u, ring_v, ring_f = [], [], []  # every boundary half-edge: from, to, sub-facet
    for p in range(n_planes):
        if p not in done:  # uncut triangles: each its own sub-facet, counter-clockwise
            for t in members[p]:
                ccw = sign[t] * sigma[p]
                c0, c1, c2 = corners[t] if ccw > 0 else corners[t][::-1]
                g0 = vid.setdefault((*c0, 1), len(vid))
                g1 = vid.setdefault((*c1, 1), len(vid))
                g2 = vid.setdefault((*c2, 1), len(vid))
                fid = len(face_plane)
                face_plane.append(p)
                face_cov.append(ccw * weight[t])
                face_tris.append([(g0, g1, g2)])
                face_rings.append(None)
                face_src.append(facet[t])
                face_point.append(None)
                ring_u += (g0, g1, g2)
                ring_v += (g1, g2, g0)
                ring_f += (fid, fid, fid)
            continue
        lifted, faces = done.pop(p)
        g = [vid.setdefault(x, len(vid)) for x in lifted]
        for cov, rings, tris, src, point in faces:
            fid = len(face_plane)
            face_plane.append(p)
            face_cov.append(cov)
            rings = [[g[v] for v in ring] for ring in rings]
            if tris is None:
                face_tris.append(None)
                face_rings.append(rings)
            else:
                face_tris.append([(g[x], g[y], g[z]) for x, y, z in tris])
                face_rings.append(None)
            face_src.append(src)
            face_point.append(point)
            for ring in rings:
                ring_u += ring
                ring_v += ring[1:]
                ring_v.append(ring[0])
                ring_f += [fid] * len(ring)
    return (vid, face_plane, face_cov, face_tris, face_rings, face_src, face_point,
            ring_u, ring_v, ring_f)


def _complex(ints: np.ndarray, planes: _Planes, cuts: _Cuts, report, workers: int = 1,
             check=None, compiled: bool = True) -> tuple[_Complex, int]:
    jobs = _PlaneJobs(ints, planes, cuts)
    n_planes = len(planes.keys)
    todo = [p for p in range(n_planes) if not jobs.trivial(p)]
    done, used = _run_arrangements(jobs, todo, workers, report, check)
    args = (done, n_planes, jobs.members, jobs.sign, jobs.sigma, jobs.corners, jobs.weight,
            jobs.facet)
    if compiled:
        (vid, face_plane, face_cov, face_tris, face_rings, face_src, face_point,
         *half_edges) = _planar.assemble_complex(*args)
        u, v, ring_f = (np.frombuffer(b, dtype=np.intp).astype(np.int64) for b in half_edges)
    else:
        (vid, face_plane, face_cov, face_tris, face_rings, face_src, face_point,
         ring_u, ring_v, ring_f) = _assemble_reference(*args)
        u = np.array(ring_u, dtype=np.int64)
        v = np.array(ring_v, dtype=np.int64)
        ring_f = np.array(ring_f, dtype=np.int64)
    # Edges are numbered in order of first appearance along the rings, as (u, v), u < v.
    lo, hi = np.minimum(u, v), np.maximum(u, v)
    _, first, inverse = np.unique(lo * max(len(vid), 1) + hi, return_index=True, return_inverse=True)
    order = np.argsort(first)  # first appearances are distinct
    rank = np.empty(len(order), dtype=np.int64)
    rank[order] = np.arange(len(order))
    firsts = first[order]
    return _Complex(
        points=list(vid),
        edges=np.stack([lo[firsts], hi[firsts]], axis=1).reshape(-1, 2),
        face_plane=np.array(face_plane, dtype=np.int64),
        face_cov=np.array(face_cov, dtype=np.int64),
        inc_face=ring_f,
        inc_edge=rank[inverse.reshape(-1)],
        inc_sign=np.where(u < v, 1, -1).astype(np.int8),
        face_tris=face_tris,
        face_rings=face_rings,
        plane_axis=jobs.axis,
        face_src=np.array(face_src, dtype=np.int64),
        face_point=face_point,
    ), used
