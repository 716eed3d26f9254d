"""NCC-CVMS stage ``output``: the sub-facets between an inside and an outside cell, oriented outwards.

:func:`_output` collects the facets and their shells (holes by the sign of their exact volume);
:func:`_to_float` / :func:`_to_float_compiled` round the exact homogeneous points to float64
once (identical outputs); :func:`_nonmanifold` lists non-manifold edges and vertices.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..errors import ExactnessError
from ..geometry._kernels import load
from ..geometry.exact import Grid
from ..geometry.graphs import component_labels
from ..mesh.query import unbalanced_edge
from .arrangements import _Complex
from .membership import _face_tris
from .planes import _Planes
from .polyhedron import _volume_sign
from .superset import Superset
from .traversal import _Shells


_compiled = load("trim")


@dataclass
class _Output:
    points: list  # exact homogeneous points of the output vertices
    faces: np.ndarray
    face_facet: np.ndarray
    facet_superset: np.ndarray  # a superset facet each output facet comes from
    shell: np.ndarray
    shell_is_hole: np.ndarray


def _output(cx: _Complex, sh: _Shells, inside: np.ndarray, anchor: int, planes: _Planes,
            S: Superset) -> _Output:
    nf = len(cx.face_plane)
    plus = inside[sh.of[2 * np.arange(nf) + 1]]
    minus = inside[sh.of[2 * np.arange(nf)]]
    keep = np.nonzero(plus != minus)[0]
    # Outside cells joined through dropped sub-facets form the complement's components.
    parent = list(range(sh.n))

    def find(a: int) -> int:
        while parent[a] != a:
            parent[a] = parent[parent[a]]
            a = parent[a]
        return a

    for f in np.nonzero(~plus & ~minus)[0].tolist():
        ra, rb = find(int(sh.of[2 * f])), find(int(sh.of[2 * f + 1]))
        if ra != rb:
            parent[ra] = rb
    tris, tri_facet, facet_src, outside_cell = [], [], [], []
    for n, f in enumerate(keep.tolist()):
        flip = bool(plus[f])  # inside on the normal's side: the outward normal is reversed
        for a, b, c in _face_tris(cx, f):
            tris.append((a, c, b) if flip else (a, b, c))
            tri_facet.append(n)
        facet_src.append(int(cx.face_src[f]))
        outside_cell.append(find(int(sh.of[2 * f + (0 if flip else 1)])))
    T = np.array(tris, dtype=np.int64).reshape(-1, 3)
    _check_closed(T)
    used, T = np.unique(T, return_inverse=True)
    T = T.reshape(-1, 3)
    points = [cx.points[i] for i in used.tolist()]
    # shells: one per component of the complement a facet faces. The anchor's is unbounded;
    # another one is unbounded too when it faces a separate body (disjoint sums are not
    # joined through dropped sub-facets), bounded when it is a hole. The exact sign of the
    # volume its triangles enclose tells them apart: outward shells enclose positive volume,
    # the shells of holes face inwards.
    cells, facet_shell = np.unique(np.array(outside_cell, dtype=np.int64), return_inverse=True)
    facet_shell = facet_shell.reshape(-1)
    root = find(int(sh.of[anchor]))
    shell_is_hole = cells != root
    tri_shell = facet_shell[np.array(tri_facet, dtype=np.int64)] if len(tri_facet) else None
    for k in np.nonzero(shell_is_hole)[0].tolist():
        shell_is_hole[k] = _volume_sign(points, T[tri_shell == k]) < 0
    return _Output(
        points=points,
        faces=T,
        face_facet=np.array(tri_facet, dtype=np.int64),
        facet_superset=np.array(facet_src, dtype=np.int64),
        shell=tri_shell if tri_shell is not None else np.zeros(0, np.int64),
        shell_is_hole=shell_is_hole,
    )


def _check_closed(T: np.ndarray) -> None:
    """Raise ExactnessError unless the oriented triangles ``T`` (exact point ids) are a
    closed 2-cycle (:func:`cspace.mesh.query.unbalanced_edge`). The sum's boundary is one; a
    flaw upstream (a missed cut, a cell given the wrong side) would show as an open surface,
    which is refused rather than returned."""
    if not len(T):
        return
    edge = unbalanced_edge(T, int(T.max()) + 1)
    if edge is not None:
        raise ExactnessError(f"the sum's surface of {len(T)} triangles is not closed: its "
                             f"directed edge {edge[0]} -> {edge[1]} is not cancelled by its "
                             "reverse")


def _to_float(points: list, grid: Grid) -> np.ndarray:
    """Correctly rounded float64 scene coordinates of homogeneous grid points (Python's
    int / int rounds correctly; the grid's origin is added exactly before)."""
    ox, oy, oz = grid.origin
    V = np.array([((P[0] + ox * P[3]) / P[3], (P[1] + oy * P[3]) / P[3],
                   (P[2] + oz * P[3]) / P[3]) for P in points], dtype=np.float64)
    return np.ldexp(V.reshape(-1, 3), grid.exponent)


def _to_float_compiled(points: list, grid: Grid) -> np.ndarray:
    """:func:`_to_float` compiled (:mod:`cspace.geometry._kernels.trim`): identical output. The rows
    it leaves (integers beyond 2**53) come from :func:`_to_float`."""
    points = points if isinstance(points, list) else list(points)
    V, left = _compiled.to_float(points, tuple(grid.origin), int(grid.exponent))
    rows = np.flatnonzero(left)
    if len(rows):
        V[rows] = _to_float([points[i] for i in rows.tolist()], grid)
    return V


def _nonmanifold(faces: np.ndarray, n_vertices: int) -> tuple[np.ndarray, np.ndarray]:
    """Edges used by more than two triangles, and vertices whose triangles form more than one
    fan (joined across edges used by exactly two triangles)."""
    m = len(faces)
    if not m:
        return np.zeros((0, 2), np.int64), np.zeros(0, np.int64)
    u = faces.reshape(-1)
    v = faces[:, [1, 2, 0]].reshape(-1)
    lo, hi = np.minimum(u, v), np.maximum(u, v)
    key = lo * n_vertices + hi
    # One sort groups the half-edges by edge: runs of equal keys, from start, cnt long.
    order = np.argsort(key, kind="stable")
    sk = key[order]
    new = np.empty(len(sk), dtype=bool)
    new[0], new[1:] = True, sk[1:] != sk[:-1]
    start = np.flatnonzero(new)
    uniq, cnt = sk[start], np.diff(np.append(start, len(sk)))
    bad_edges = np.stack([uniq[cnt > 2] // n_vertices, uniq[cnt > 2] % n_vertices], axis=1)
    # Corner 3 t + i sits at faces[t, i]; half-edge 3 t + i runs from corner 3 t + i to the
    # next corner of t. Two half-edges of a manifold edge join their corners at equal vertices.
    h = np.arange(3 * m)
    cu, cv = h, 3 * (h // 3) + (h % 3 + 1) % 3
    # The two half-edges of each edge of exactly two triangles: the first two of its run
    # (pairing the sorted half-edges two by two instead lost the pairs after a run of odd
    # length, e.g. an edge of three triangles).
    two = start[cnt == 2]
    a, b = order[two], order[two + 1]
    same = u[a] == u[b]
    src = np.concatenate([cu[a], cv[a]])
    dst = np.concatenate([np.where(same, cu[b], cv[b]), np.where(same, cv[b], cu[b])])
    n_fans, comp = component_labels(3 * m, src, dst)
    # Every join above is between corners at one vertex: each fan (component) lies at one
    # vertex, so counting fans per vertex needs no search for distinct (vertex, fan) pairs.
    fan_vertex = np.empty(n_fans, dtype=np.int64)
    fan_vertex[comp] = u
    fans = np.bincount(fan_vertex, minlength=n_vertices)
    return bad_edges.astype(np.int64), np.nonzero(fans > 1)[0].astype(np.int64)
