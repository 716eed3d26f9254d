"""Convex polytopes with polygon facets on an integer grid, and the one definition of "convex".

A :class:`ConvexPolytope` stores grid-integer vertices (int64) and strictly convex polygon
facets, counter-clockwise seen from outside, each with its primitive integer outward normal.
Every decision (which points are on the hull, which facets are coplanar) is exact: see
:mod:`cspace.geometry.exact`. Degenerate directions are not assumed away: a square facet stays
one square facet.

:func:`convex_within_bound` decides whether a snapped closed mesh is convex, or convex within
the bend snapping can make (its hull's ``excess`` then stated and counted in every
``error_bound``). The sum of two polytopes (CVMS) is :mod:`cspace.minkowski.cvms`.

Length: one type and the decisions it rests on (the exact hull of points with its compiled
path and pure-Python references, the convexity test within snapping's bend), which other
modules must not each redo.
"""

from __future__ import annotations

from dataclasses import dataclass, field, replace
from typing import Any

import numpy as np

from ..errors import (
    DegenerateError,
    EmptyMeshError,
    ExactnessError,
    InvalidArgumentError,
    InvalidMeshError,
    NotConvexError,
)
from ..geometry import exact
from ..geometry.exact import Grid
from ..geometry._kernels import load
from ..geometry.polygon import fan_triangles

__all__ = ["ConvexPolytope"]

_compiled = load("convex")


# --------------------------------------------------------------------------------------
# exact 2D hull of a small point set, used for facet polygons


def _hull2d(xy: list[tuple[int, int]]) -> list[int]:
    """Strictly convex hull of 2D integer points, counter-clockwise, as indices into ``xy``.

    Collinear and duplicate points are dropped (only corners are kept). Pure Python ints:
    exact, and faster than numpy on the handful of points a facet has.
    """
    order = sorted(range(len(xy)), key=lambda i: xy[i])
    # Drop exact duplicates, keep the first index of each position.
    uniq = [order[0]]
    for i in order[1:]:
        if xy[i] != xy[uniq[-1]]:
            uniq.append(i)
    if len(uniq) < 3:
        return uniq

    def turn(o, a, b):
        (ox, oy), (ax, ay), (bx, by) = xy[o], xy[a], xy[b]
        return (ax - ox) * (by - oy) - (ay - oy) * (bx - ox)

    lower: list[int] = []
    for i in uniq:
        while len(lower) >= 2 and turn(lower[-2], lower[-1], i) <= 0:
            lower.pop()
        lower.append(i)
    upper: list[int] = []
    for i in reversed(uniq):
        while len(upper) >= 2 and turn(upper[-2], upper[-1], i) <= 0:
            upper.pop()
        upper.append(i)
    return lower[:-1] + upper[:-1]


def _facet_polygon(ints: np.ndarray, idx: np.ndarray, normal: np.ndarray) -> np.ndarray:
    """Corners of the convex polygon spanned by coplanar grid points, CCW about ``normal``."""
    k = int(np.argmax(np.abs(normal)))
    ax1, ax2 = (k + 1) % 3, (k + 2) % 3
    pts = ints[idx]
    xy = list(zip(pts[:, ax1].tolist(), pts[:, ax2].tolist()))
    ring = _hull2d(xy)
    # The projection along axis k keeps orientation iff normal[k] > 0.
    if normal[k] < 0:
        ring = ring[::-1]
    return np.asarray(idx)[ring]


# The unit box's corners and outward triangles (trimesh.creation.box's).
_BOX_CORNERS = np.array([[a, b, c] for a in (-1, 1) for b in (-1, 1) for c in (-1, 1)],
                        dtype=np.int64)
_BOX_FACES = np.array([[1, 3, 0], [4, 1, 0], [0, 3, 2], [2, 4, 0], [1, 7, 3], [5, 1, 4],
                       [5, 7, 1], [3, 7, 2], [6, 4, 2], [2, 7, 6], [6, 5, 4], [7, 5, 6]],
                      dtype=np.int64)


# --------------------------------------------------------------------------------------
# the polytope type


@dataclass(frozen=True, eq=False)
class ConvexPolytope:
    """A convex polytope with polygon facets, on an integer grid.

    Build with :meth:`from_points` or :meth:`from_mesh`; do not call the constructor.

    Attributes
    ----------
    grid : Grid
        The snapping grid; ``vertices == grid.to_float(ints)``.
    ints : (n, 3) int64
        Vertex coordinates in grid units. Every vertex is a corner of the polytope.
    facet_offsets : (f + 1,) int64
        Facet ``i`` is ``facet_indices[facet_offsets[i]:facet_offsets[i + 1]]``.
    facet_indices : (sum of facet degrees,) int64
        Vertex indices of all facets, each counter-clockwise seen from outside.
    normals : (f, 3) int64
        Primitive integer outward normal of each facet (a canonical key of its direction).
    edges : (e, 2) int64
        Each edge once, as ``(u, v)`` with ``u -> v`` counter-clockwise in facet
        ``edge_facets[:, 0]`` and ``v -> u`` in facet ``edge_facets[:, 1]``.
    edge_facets : (e, 2) int64
        Left and right facet of each edge.
    """

    grid: Grid
    ints: np.ndarray
    facet_offsets: np.ndarray
    facet_indices: np.ndarray
    normals: np.ndarray
    edges: np.ndarray
    edge_facets: np.ndarray
    name: str = "polytope"
    _cache: dict = field(default_factory=dict, repr=False)
    #: How far this polytope may exceed the snapped body it was built for (scene units):
    #: 0 for a hull of points or an exactly convex mesh; for a mesh that snapping bent (see
    #: :func:`convex_within_bound`) the bound proved there. Counted in ``error_bound``.
    excess: float = 0.0

    # ---- construction ---------------------------------------------------------------

    @classmethod
    def from_points(
        cls, points, *, grid: Grid | None = None, name: str = "polytope", method: str = "auto"
    ) -> "ConvexPolytope":
        """Exact convex hull of points, with coplanar triangles merged into polygon facets.

        Parameters
        ----------
        points : (n, 3) float64
            Points in scene units; snapped onto ``grid`` first.
        grid : Grid, optional
            Snapping grid; default ``Grid.for_points(points)``.
        name : str
            Used in error messages.
        method : {'auto', 'qhull', 'wrap'}, default 'auto'
            'qhull' takes Qhull's triangles as candidate facet planes and certifies them
            exactly (raising ExactnessError if the certificate fails); 'wrap' is exact gift
            wrapping over facets, O(n h); 'auto' tries 'qhull' and falls back to 'wrap'.

        Returns
        -------
        ConvexPolytope
            Only the hull's corners are kept as vertices; facets are strictly convex polygons.

        Raises
        ------
        EmptyMeshError, NonFiniteError
            No points, or a NaN/inf coordinate.
        DegenerateError
            All points are collinear or coplanar (the hull has no volume).
        """
        points = _as_points(points, name)
        grid = grid or Grid.for_points(points)
        try:
            return cls.from_ints(grid.snap(points), grid=grid, name=name, method=method)
        except DegenerateError as e:
            raise DegenerateError(f"{e} after snapping to a grid of step {grid.step:.3g}") from None

    @classmethod
    def from_ints(
        cls, ints, *, grid: Grid, name: str = "polytope", method: str = "auto"
    ) -> "ConvexPolytope":
        """Exact convex hull of grid-integer points (see :meth:`from_points`)."""
        if method not in ("auto", "qhull", "wrap"):
            raise InvalidArgumentError(f"'{method}' is not a valid method, must be one of 'auto', 'qhull', 'wrap'")
        ints = np.ascontiguousarray(ints, dtype=np.int64).reshape(-1, 3)
        if method == "auto":
            # Compiled: a hull proposed (incrementally for few points, by Qhull for many)
            # and proved exactly by the kernel over every point; None leaves it to the
            # reference below, which decides and names the reason.
            got = (_compiled.hull_of_points(ints) if len(ints) <= _FEW_POINTS
                   else _qhull_proposal(ints))
            if got is not None:
                return cls._from_kernel(got, grid=grid, name=name)
        ints = np.unique(ints, axis=0)
        if len(ints) == 0:
            raise EmptyMeshError(f"{name}: no points")
        tetra = _find_tetrahedron(ints, name)
        if method in ("auto", "qhull"):
            planes = _qhull_planes(ints, tetra)
            try:
                if planes is not None:
                    return cls._from_planes(ints, planes, grid=grid, name=name)
            except ExactnessError:
                # A certified set of facet planes that does not close up misses a facet.
                pass
            if method == "qhull":
                raise ExactnessError(f"{name}: Qhull's hull failed the exact certificate")
        return cls._from_planes(ints, _wrap_planes(ints, tetra), grid=grid, name=name)

    @classmethod
    def from_convex_mesh(cls, ints, faces, *, grid: Grid, name: str = "polytope"
                         ) -> "ConvexPolytope | None":
        """The polytope a closed mesh on grid integers bounds when it is exactly convex, in
        one compiled call; None when the kernel does not decide (then ask
        :func:`convex_within_bound`, the one definition of "convex", which names the reason).

        ``ints`` (n, 3) int64 grid coordinates (distinct), ``faces`` (m, 3) int64 oriented
        outwards. A polytope returned is the one :meth:`from_ints` makes of ``ints``, and the
        one :func:`convex_within_bound` accepts with ``excess`` 0 (the proof is the kernel's:
        :func:`cspace.geometry._kernels.convex.polytope_of_mesh`; ``tests/test_kernels.py``
        holds them identical).
        """
        got = _compiled.polytope_of_mesh(np.ascontiguousarray(ints, dtype=np.int64),
                                         np.ascontiguousarray(faces, dtype=np.int64))
        return None if got is None else cls._from_kernel(got, grid=grid, name=name)

    @classmethod
    def _from_kernel(cls, got, *, grid: Grid, name: str) -> "ConvexPolytope":
        """From the convex kernel's ``(ints, offsets, flat, normals, edges, edge_facets)``."""
        P, offsets, flat, normals, edges, edge_facets = got
        return cls(grid=grid, ints=P, facet_offsets=offsets, facet_indices=flat,
                   normals=normals, edges=edges, edge_facets=edge_facets, name=name)

    @classmethod
    def box(cls, half, *, grid: Grid, name: str = "box") -> "ConvexPolytope | None":
        """The box ``[-half, half]`` (grid steps per axis, each positive) about the grid's
        origin, as :meth:`from_ints` makes it of its eight corners (no hull computed); None
        for half-sizes of ``2**30`` steps or more (beyond the compiled test's range)."""
        h = np.asarray(half, dtype=np.int64).reshape(3)
        if not (h > 0).all():
            raise DegenerateError(f"{name}: a box of half-sizes {h.tolist()} has no volume")
        return cls.from_convex_mesh(_BOX_CORNERS * h, _BOX_FACES, grid=grid, name=name)

    def canonical(self) -> "ConvexPolytope":
        """The same polytope in :meth:`from_ints`'s order (corners in lexicographic order,
        facets in lexicographic order of their normals, each ring from its projection's
        smallest corner): what ``from_ints(self.ints)`` returns, without a hull. For a
        polytope made another way (a CVMS sum)."""
        ints = np.unique(self.ints, axis=0)
        first = self.ints[self.facet_indices[self.facet_offsets[:-1]]]
        on_plane = exact.plane_side_matrix(ints, first, self.normals) == 0
        out = self._from_planes(ints, (self.normals, on_plane), grid=self.grid, name=self.name)
        return replace(out, excess=self.excess, _cache={}) if self.excess else out

    @classmethod
    def _from_planes(cls, ints, planes, *, grid, name) -> "ConvexPolytope":
        """Polytope from its certified facet planes: each facet is conv(points on its plane),
        the facets in lexicographic order of their normals (so that the polytope does not
        depend on the order in which Qhull or the wrap found them)."""
        normals, on_plane = planes
        order = np.lexsort(np.asarray(normals).T[::-1])
        normals, on_plane = np.asarray(normals)[order], on_plane[:, order]
        polys = [_facet_polygon(ints, np.nonzero(on_plane[:, j])[0], normals[j]) for j in range(len(normals))]
        return cls._from_polygons(ints, polys, normals, grid=grid, name=name)

    @classmethod
    def _from_polygons(cls, ints, polys, normals, *, grid, name) -> "ConvexPolytope":
        """Assemble from facet polygons (indices into ``ints``); drops unused points, checks closedness."""
        used = np.unique(np.concatenate(polys))
        remap = np.full(len(ints), -1, dtype=np.int64)
        remap[used] = np.arange(len(used))
        sizes = np.array([len(p) for p in polys], dtype=np.int64)
        offsets = np.zeros(len(polys) + 1, dtype=np.int64)
        np.cumsum(sizes, out=offsets[1:])
        flat = remap[np.concatenate(polys)]
        return cls._from_csr(ints[used], offsets, flat, normals, grid=grid, name=name)

    @classmethod
    def _from_csr(cls, ints, offsets, flat, normals, *, grid, name) -> "ConvexPolytope":
        """Assemble from CSR facet polygons using every point; checks closedness."""
        edges, edge_facets = _edges_of(flat, offsets, len(ints), name)
        return cls(
            grid=grid, ints=ints, facet_offsets=offsets, facet_indices=flat,
            normals=np.asarray(normals, dtype=np.int64), edges=edges, edge_facets=edge_facets, name=name,
        )

    @classmethod
    def from_mesh(cls, mesh: Any, *, grid: Grid | None = None, name: str | None = None) -> "ConvexPolytope":
        """Convex polytope from a closed mesh said to be convex; raises if it is not.

        Parameters
        ----------
        mesh : ClosedMesh, trimesh.Trimesh, (vertices, faces) or path
            Validated as a closed oriented 2-manifold first (:func:`cspace.mesh.closed.as_mesh`).

        Returns
        -------
        ConvexPolytope
            The exact hull of the snapped vertices when the snapped mesh is convex, or convex
            within the bend that snapping can make (:func:`convex_within_bound`, the one
            definition of "convex"; ``excess`` then says by how much the hull may exceed the
            snapped mesh, and is counted in the sums' ``error_bound``).

        Raises
        ------
        NotConvexError
            Otherwise; the message says why (the first reflex edge beyond the bound, or the
            first face off the hull).
        """
        from .closed import as_mesh

        m = as_mesh(mesh, grid=grid, name=name)
        poly, why = convex_within_bound(m)
        if poly is None:
            raise NotConvexError(f"mesh '{m.name}' is not convex: {why}")
        return poly

    # ---- derived data ---------------------------------------------------------------

    @property
    def vertices(self) -> np.ndarray:
        """(n, 3) float64 vertex coordinates in scene units (exact grid values)."""
        return self.grid.to_float(self.ints)

    @property
    def n_facets(self) -> int:
        return len(self.normals)

    @property
    def facets(self) -> list[np.ndarray]:
        """Facet polygons as a list of int64 index arrays, counter-clockwise from outside."""
        o, f = self.facet_offsets, self.facet_indices
        return [f[o[i] : o[i + 1]] for i in range(len(o) - 1)]

    @property
    def facet_degrees(self) -> np.ndarray:
        """(f,) int64 number of vertices of each facet."""
        return np.diff(self.facet_offsets)

    def triangles(self) -> tuple[np.ndarray, np.ndarray]:
        """Fan triangulation of the facets.

        Returns
        -------
        faces : (m, 3) int64
            Counter-clockwise from outside.
        facet : (m,) int64
            The facet each triangle comes from.
        """
        if "tri" not in self._cache:
            self._cache["tri"] = fan_triangles(self.facet_offsets, self.facet_indices)
        return self._cache["tri"]

    @property
    def faces(self) -> np.ndarray:
        """(m, 3) int64 triangle faces (fan triangulation of the facets)."""
        return self.triangles()[0]

    def volume6(self) -> int:
        """Exact six times the volume, in grid units cubed (a Python int)."""
        faces = self.faces
        t = self.ints[faces].astype(object)
        det = (
            t[:, 0, 0] * (t[:, 1, 1] * t[:, 2, 2] - t[:, 1, 2] * t[:, 2, 1])
            + t[:, 0, 1] * (t[:, 1, 2] * t[:, 2, 0] - t[:, 1, 0] * t[:, 2, 2])
            + t[:, 0, 2] * (t[:, 1, 0] * t[:, 2, 1] - t[:, 1, 1] * t[:, 2, 0])
        )
        return int(sum(det))

    @property
    def volume(self) -> float:
        """Volume in scene units cubed (the exact value, rounded once)."""
        return float(self.volume6()) / 6.0 * self.grid.step**3

    def planes(self) -> set[tuple[int, int, int, int]]:
        """The exact facet planes ``(nx, ny, nz, d)``, ``n . x = d`` in grid units, n primitive."""
        q = self.ints[self.facet_indices[self.facet_offsets[:-1]]]
        return {
            (int(n[0]), int(n[1]), int(n[2]), int(n[0]) * int(p[0]) + int(n[1]) * int(p[1]) + int(n[2]) * int(p[2]))
            for n, p in zip(self.normals.tolist(), q.tolist())
        }

    # ---- operations -----------------------------------------------------------------

    def reflected(self, reference_point=(0.0, 0.0, 0.0)) -> "ConvexPolytope":
        """``-(R - c)``: the points ``c - r``, i.e. R reflected through its reference point ``c``
        and expressed with ``c`` at the origin.

        With ``R`` a robot and ``c`` its reference point, ``O ⊕ R.reflected(c)`` is the
        C-obstacle: the set of positions of ``c`` at which the robot meets ``O``.
        ``reference_point`` is snapped onto the polytope's grid (exact if already on it). The
        result is on the grid of vectors (origin 0) when ``c - r`` fits it, as for a robot
        about its reference point; otherwise (a body far from ``c``) on a grid whose origin is
        ``c`` in this frame.
        """
        c = self.grid.offset(reference_point)
        key = ("reflected", tuple(int(v) for v in c))
        if key not in self._cache:  # a robot is reflected once, not once per obstacle
            self._cache[key] = self._reflected(c)
        return self._cache[key]

    def _reflected(self, c: np.ndarray) -> "ConvexPolytope":
        ints, grid = c[None, :] - self.ints, self.grid.vectors
        if ints.size and np.abs(ints).max() > grid.limit:
            ints, grid = -self.ints, replace(self.grid, origin=tuple(int(v) for v in c))
        # Point reflection reverses orientation: reverse each facet's vertex order.
        o, f = self.facet_offsets, self.facet_indices
        facet = np.repeat(np.arange(len(o) - 1), np.diff(o))
        flat = f[o[facet] + o[facet + 1] - 1 - np.arange(len(f))]
        edges, edge_facets = _edges_of(flat, o, len(ints), self.name)
        return ConvexPolytope(
            grid=grid,
            ints=ints,
            facet_offsets=o.copy(),
            facet_indices=flat,
            normals=-self.normals,
            edges=edges,
            edge_facets=edge_facets,
            name=f"-{self.name}",
            excess=self.excess,
        )

    def on_grid(self, grid: Grid) -> "ConvexPolytope":
        """The same polytope snapped onto another grid (the hull is recomputed if snapping moves points)."""
        if grid == self.grid:
            return self
        out = ConvexPolytope.from_points(self.vertices, grid=grid, name=self.name)
        return replace(out, excess=self.excess, _cache={}) if self.excess else out

    def to_trimesh(self):
        """A ``trimesh.Trimesh`` of the fan-triangulated facets (float64, not re-processed)."""
        import trimesh

        return trimesh.Trimesh(self.vertices, self.faces, process=False)

    def __repr__(self) -> str:
        return (f"ConvexPolytope(name={self.name!r}, vertices={len(self.ints)}, "
                f"facets={self.n_facets}, volume={self.volume:.6g}, step=2**{self.grid.exponent})")


def _as_points(points, name: str) -> np.ndarray:
    if hasattr(points, "vertices"):
        points = np.asarray(points.vertices)
    points = np.asarray(points, dtype=np.float64)
    if points.size == 0:
        raise EmptyMeshError(f"{name}: no points")
    if points.ndim != 2 or points.shape[1] != 3:
        raise InvalidMeshError(f"{name}: points must be (n, 3), got {points.shape}")
    return points


def _edges_of(flat: np.ndarray, offsets: np.ndarray, n_vertices: int, name: str):
    """Edges of a closed polygon mesh with their left/right facets; raises if not closed.

    Compiled (:func:`cspace.geometry._kernels.convex.edges_of`, the same edges in the same
    order); :func:`_edges_of_reference` decides and names what does not close up."""
    got = _compiled.edges_of(np.ascontiguousarray(flat, dtype=np.int64),
                             np.ascontiguousarray(offsets, dtype=np.int64), n_vertices)
    return got if got is not None else _edges_of_reference(flat, offsets, n_vertices, name)


def _edges_of_reference(flat: np.ndarray, offsets: np.ndarray, n_vertices: int, name: str):
    """:func:`_edges_of` in numpy."""
    deg = np.diff(offsets)
    facet = np.repeat(np.arange(len(deg)), deg)
    nxt = np.arange(len(flat)) + 1
    ends = offsets[1:] - 1
    nxt[ends] = offsets[:-1]
    u, v = flat, flat[nxt]
    key = u * n_vertices + v
    rkey = v * n_vertices + u
    order = np.argsort(key)
    pos = np.searchsorted(key[order], rkey)
    pos = np.minimum(pos, len(key) - 1)
    matched = key[order][pos] == rkey
    dup = np.unique(key).size != key.size
    if not matched.all() or dup:
        raise ExactnessError(
            f"{name}: facet polygons do not form a closed 2-manifold "
            f"({int((~matched).sum())} unmatched directed edges)"
        )
    twin = order[pos]
    keep = u < v
    edges = np.stack([u[keep], v[keep]], axis=1).astype(np.int64)
    edge_facets = np.stack([facet[keep], facet[twin[keep]]], axis=1).astype(np.int64)
    return edges, edge_facets


# --------------------------------------------------------------------------------------
# exact hull: a non-degenerate tetrahedron, candidate planes, certificate


def _find_tetrahedron(ints: np.ndarray, name: str) -> np.ndarray:
    """Indices of four affinely independent points, or DegenerateError saying why none exist."""
    if len(ints) < 4:
        raise DegenerateError(f"{name}: {len(ints)} distinct points cannot bound a volume")
    i0 = 0
    d = ints - ints[i0]
    i1 = int(np.argmax(np.abs(d).sum(axis=1)))
    c = exact.cross(ints[i1] - ints[i0], d)
    nz = np.nonzero(np.any(c != 0, axis=1))[0]
    if not nz.size:
        raise DegenerateError(f"{name}: all {len(ints)} points are collinear on the grid (no volume)")
    i2 = int(nz[0])
    s = exact.orient3d(ints[i0], ints[i1], ints[i2], ints)
    nz = np.nonzero(s != 0)[0]
    if not nz.size:
        raise DegenerateError(f"{name}: all {len(ints)} points are coplanar on the grid (no volume)")
    return np.array([i0, i1, i2, int(nz[0])], dtype=np.int64)


def _orient_outward(ints, tri_pts, normals, tetra):
    """Flip integer normals so that the tetrahedron (inside the hull) is not on their positive side."""
    side = exact.plane_side_matrix(ints[tetra], tri_pts, normals)  # (4, m)
    # A supporting plane has the whole tetrahedron on one side; use its most populated sign.
    flip = (side > 0).sum(axis=0) > 0
    normals = normals.copy()
    normals[flip] *= -1
    return normals


def _certify(ints, plane_pts, normals):
    """Exact certificate for candidate outward facet planes.

    Returns ``(normals, on_plane)`` with duplicates removed when every point is on or below
    every plane and each plane holds three non-collinear points; otherwise None.
    """
    normals = exact.primitive(normals)
    _, first = np.unique(normals, axis=0, return_index=True)
    first = np.sort(first)
    normals, plane_pts = normals[first], plane_pts[first]
    side = exact.plane_side_matrix(ints, plane_pts, normals)
    if (side > 0).any():
        return None
    on_plane = side == 0
    if (on_plane.sum(axis=0) < 3).any():
        return None
    return normals, on_plane


# Up to this many points the kernel's incremental hull beats Qhull's proposal (both proved
# by the same kernel; measured beside scipy's ConvexHull in benchmarks/bench_cvms.py).
_FEW_POINTS = 128


def _qhull_proposal(ints: np.ndarray):
    """Qhull's triangles of the distinct points, each turned to face along Qhull's outward
    plane (a float guess), proved exactly by the kernel (:func:`polytope_of_mesh`: closed,
    consistently oriented, every point on or below every plane, volumes equal); None when
    Qhull fails or the proof does not hold (then the reference decides)."""
    from scipy.spatial import ConvexHull
    from scipy.spatial import QhullError

    pts = np.unique(ints, axis=0)
    if len(pts) < 4:
        return None
    try:
        hull = ConvexHull(pts.astype(np.float64))
    except QhullError:
        return None
    F = hull.simplices.astype(np.int64)
    X = pts.astype(np.float64)
    n = np.cross(X[F[:, 1]] - X[F[:, 0]], X[F[:, 2]] - X[F[:, 0]])
    flip = np.einsum("ij,ij->i", n, hull.equations[:, :3]) < 0
    F[flip] = F[flip][:, ::-1]
    return _compiled.polytope_of_mesh(np.ascontiguousarray(pts), np.ascontiguousarray(F))


def _qhull_planes(ints: np.ndarray, tetra: np.ndarray):
    """Qhull's triangles as candidate facet planes, certified exactly; None if not certified."""
    from scipy.spatial import ConvexHull
    from scipy.spatial import QhullError

    try:
        hull = ConvexHull(ints.astype(np.float64))
    except QhullError:
        return None
    tri = ints[hull.simplices]
    n = np.cross(tri[:, 1] - tri[:, 0], tri[:, 2] - tri[:, 0])
    keep = np.any(n != 0, axis=1)
    tri, n = tri[keep], n[keep]
    if not len(n):
        return None
    n = _orient_outward(ints, tri[:, 0], n, tetra)
    return _certify(ints, tri[:, 0], n)


def _wrap_planes(ints: np.ndarray, tetra: np.ndarray):
    """Exact gift wrapping over facets: each facet found by rotating a supporting plane about
    a known hull edge until no point is beyond it. O(n h) vectorised exact predicates."""
    n_pts = len(ints)

    def rotate(u: np.ndarray, v: np.ndarray, p: int) -> int:
        # Rotate the plane (v, u, p) about line uv until no point lies on its positive side.
        while True:
            s = exact.orient3d(v, u, ints[p], ints)
            beyond = np.nonzero(s > 0)[0]
            if not beyond.size:
                return p
            nrm = np.cross(u - v, ints[p] - v).astype(np.float64)
            height = (ints[beyond] - v).astype(np.float64) @ nrm
            p = int(beyond[np.argmax(height)])

    # First facet: wrap about the line through the lexicographically smallest point along +y,
    # starting from the supporting plane x = min x, then about the edge found.
    a = int(np.lexsort(ints.T[::-1])[0])
    pa = ints[a]
    virtual = pa + np.array([0, 1, 0])
    off_line = np.nonzero(np.any(exact.cross(virtual - pa, ints - pa) != 0, axis=1))[0]
    b = rotate(virtual, pa, int(off_line[0]))
    # Now plane (pa, virtual, b) supports the set; wrap about edge (a, b) to a true facet.
    start = [i for i in range(n_pts) if np.any(exact.cross(ints[b] - pa, ints[i] - pa) != 0)]
    c = rotate(ints[b], pa, start[0])
    normals, on_planes, done = [], [], set()
    first_n = exact.primitive(exact.cross(ints[b] - pa, ints[c] - pa))
    # Orientation: outward normal has every point on its non-positive side.
    if (exact.dot_sign(ints - pa, first_n) > 0).any():
        first_n = -first_n
    todo = [(first_n, a)]
    while todo:
        nrm, anchor = todo.pop()
        key = tuple(nrm.tolist())
        if key in done:
            continue
        done.add(key)
        side = exact.dot_sign(ints - ints[anchor], nrm)
        if (side > 0).any():
            raise ExactnessError("gift wrapping produced a non-supporting plane")
        idx = np.nonzero(side == 0)[0]
        normals.append(nrm)
        on_planes.append(side == 0)
        ring = _facet_polygon(ints, idx, nrm)
        for k in range(len(ring)):
            u, v = ints[ring[k]], ints[ring[(k + 1) % len(ring)]]
            # Neighbour facet across u -> v contains v -> u: start from a point of this facet.
            w = ring[(k + 2) % len(ring)]
            p = rotate(u, v, int(w))
            nn = exact.primitive(exact.cross(u - v, ints[p] - v))
            if tuple(nn.tolist()) not in done:
                todo.append((nn, int(ring[k])))
    return np.asarray(normals, dtype=np.int64), np.stack(on_planes, axis=1)


# --------------------------------------------------------------------------------------
# the one definition of a convex mesh


_MAX_FLIP_ROUNDS = 64


def convex_within_bound(mesh, bend: float | None = None):
    """Whether a snapped closed mesh is convex, within the bend snapping can make, exactly.

    This is the one place where "convex" is decided for a mesh (``ConvexPolytope.from_mesh``,
    ``cspace.minkowski_sum``, ``CSpaceObstacle.build`` and scene modelling all call it).

    Rule. Let B be the snapped mesh (closed, oriented outwards) and H the exact hull of its
    vertices. An edge ``u -> v`` whose faces ``(u, v, w)`` and ``(v, u, x)`` turn outwards
    (``orient3d(u, v, w, x) > 0``, exact) is *reflex*. B is convex within ``bend`` (default
    ``2 * grid.point_error_bound``) when flipping reflex edges, in rounds, makes it exactly
    convex:

    1. in each round, reflex edges that share no face (greedily, in order) are flipped from
       ``uv`` to ``wx``; each must be *thin*: with ``c = (v - u) x (x - w)`` oriented so that
       ``c . n(u, v, w) > 0``, all four triangles ``(u, v, w)``, ``(v, u, x)``,
       ``(u, x, w)``, ``(x, v, w)`` face along ``c`` (exact signs), ``wx`` is not an edge
       yet, and the distance between the lines ``uv`` and ``wx``,
       ``g = |orient3d(u, v, w, x)| / |c|``, is at most ``bend`` (exact, in rationals:
       ``det^2 <= bend^2 |c|^2``);
    2. the sum over rounds of each round's largest ``g`` (rounded up) stays within
       ``2 * bend``; that sum is ``excess``;
    3. when no reflex edge is left, every face lies on a facet plane of H with H's outward
       normal (exact) and the faces enclose H's volume (exact).

    With no reflex edge this is the exact test (``excess`` 0).

    Proof of the bound. Flipping ``uv`` to ``wx`` changes the surface (as a 2-chain) by the
    boundary of the tetrahedron ``T = conv(u, v, w, x)``; the flipped surface is H (3), so
    B's winding number is H's (1) outside the ``T``'s: ``H \\ B ⊆ ∪ T``. Seen along ``c``
    the four triangles of a ``T`` are graphs over one convex quadrilateral (1), the pair of
    the surface before the flip below, the flipped pair above; the vertical gap is linear on
    the overlay of the two triangulations, zero at the corners and ``g`` where the diagonals
    cross, so every point of ``T`` is within ``g`` of the surface before the flip, whose
    points are within the earlier rounds' sum of B (induction). Hence
    ``B ⊆ H ⊆ B ⊕ ball(excess)``: using H for B can only add collisions, at most ``excess``
    away.

    Why ``2 * point_error_bound``: a convex input's nearly planar quad (a rotated box's
    face) whose four corners each moved by at most ``e = point_error_bound``: the images of
    the two diagonals' common point are at most ``2 e`` apart, so the lines are. A larger
    bend, a vertex strictly inside H (a cylinder's cap centre snapped inwards, a dent), a
    fold that is not thin: not convex, and the body takes the non-convex path (exact,
    slower) -- it is never hulled.

    Parameters
    ----------
    mesh : ClosedMesh
        A validated closed oriented mesh on its grid.
    bend : float, optional
        The largest accepted bend, scene units.

    Returns
    -------
    (ConvexPolytope or None, str)
        The hull (``excess`` set) or None, and the reason (why it is not convex, or how many
        edges snapping bent).
    """
    from fractions import Fraction

    ints, faces, grid = mesh.ints, mesh.faces, mesh.grid
    if bend is None:
        bend = 2.0 * grid.point_error_bound
    bend_steps = Fraction(bend) / Fraction(grid.step)
    m, n = len(faces), int(ints.shape[0])
    P = [tuple(int(c) for c in row) for row in ints.tolist()]

    from ..geometry.tritri import _cross3 as cross  # exact on Python-int tuples
    from ..geometry.tritri import _dot3 as dot
    from ..geometry.tritri import _sub as sub

    flipped = faces.copy()
    total = Fraction(0)  # the sum over rounds of the round's largest gap, grid steps
    n_flips = rounds = 0
    while True:
        u = flipped.reshape(-1)
        v = flipped[:, [1, 2, 0]].reshape(-1)
        w = flipped[:, [2, 0, 1]].reshape(-1)
        key = u * n + v
        order = np.argsort(key)
        twin = order[np.searchsorted(key[order], v * n + u)]  # the half-edge v -> u
        far = w[twin]
        side = exact.orient3d(ints[u], ints[v], ints[w], ints[far])
        reflex = np.nonzero((side > 0) & (u < v))[0]
        if not reflex.size:
            break
        rounds += 1
        if rounds > _MAX_FLIP_ROUNDS:
            return None, f"{reflex.size} reflex edges left after {_MAX_FLIP_ROUNDS} rounds of flips"
        edges = {(min(a, b), max(a, b)) for a, b in zip(u.tolist(), v.tolist())}
        used = np.zeros(m, dtype=bool)
        widest = Fraction(0)
        new = flipped.copy()
        for k in reflex.tolist():
            f, g_ = k // 3, int(twin[k]) // 3
            a, b, cw, cx = int(u[k]), int(v[k]), int(w[k]), int(far[k])
            where = f"its edge ({a}, {b}) of face {f} is reflex"
            if used[f] or used[g_]:
                continue  # next round
            if cw == cx or (min(cw, cx), max(cw, cx)) in edges:
                return None, where + " and cannot be flipped (its flip is an edge already)"
            pu, pv, pw, px = P[a], P[b], P[cw], P[cx]
            c = cross(sub(pv, pu), sub(px, pw))
            if dot(c, cross(sub(pv, pu), sub(pw, pu))) < 0:
                c = (-c[0], -c[1], -c[2])
            tris = ((pu, pv, pw), (pv, pu, px), (pu, px, pw), (px, pv, pw))
            if any(dot(c, cross(sub(q, p), sub(r, p))) <= 0 for p, q, r in tris):
                return None, where + " (the turn is not a thin fold of a quadrilateral)"
            det = dot(cross(sub(pv, pu), sub(pw, pu)), sub(px, pu))
            gap2 = Fraction(det * det, dot(c, c))
            if gap2 > bend_steps * bend_steps:
                return None, where + (f" by {float(gap2) ** 0.5 * grid.step:.3g}, beyond the "
                                      f"{bend:.3g} snapping can bend")
            used[f] = used[g_] = True
            edges.add((min(cw, cx), max(cw, cx)))
            new[f] = (a, cx, cw)
            new[g_] = (cx, b, cw)
            widest = max(widest, gap2)
            n_flips += 1
        flipped = new
        # a bound, never below the exact gap: the square root of an upper float, rounded up
        total += Fraction(float(widest) ** 0.5 * (1.0 + 1e-12))
        if total > 2 * bend_steps:
            return None, (f"snapping would have bent it by more than {2 * bend:.3g} "
                          f"({rounds} rounds of flips)")
    hull = ConvexPolytope.from_ints(ints, grid=grid, name=mesh.name)
    tri = ints[flipped]
    tri_n = exact.primitive(exact.cross(tri[:, 1] - tri[:, 0], tri[:, 2] - tri[:, 0]))
    # A face is on the hull iff its normal is a hull facet's and its vertices are on that plane.
    facet = {tuple(nn): j for j, nn in enumerate(hull.normals.tolist())}
    facet_of = np.array([facet.get(tuple(nn), -1) for nn in tri_n.tolist()], dtype=np.int64)
    bad = np.nonzero(facet_of < 0)[0]
    if not bad.size:
        q = hull.ints[hull.facet_indices[hull.facet_offsets[facet_of]]]
        bad = np.nonzero(exact.dot_sign(tri[:, 0] - q, hull.normals[facet_of]) != 0)[0]
    if bad.size:
        return None, (f"{bad.size} of {m} faces are not on its convex hull (reflex or "
                      f"interior), first face {int(bad[0])} with vertices "
                      f"{tuple(int(i) for i in faces[bad[0]])}")
    vol6 = _volume6_faces(ints, flipped)
    if vol6 != hull.volume6():
        return None, "its faces lie on its hull but its volume differs (faces cover the hull more than once)"
    excess = 0.0
    why = "exactly convex"
    if n_flips:
        excess = float(total * Fraction(grid.step)) * (1.0 + 1e-12)
        why = (f"convex within {excess:.3g}: snapping bent {n_flips} edge"
               f"{'s' if n_flips != 1 else ''} (the hull exceeds it by at most that)")
    return replace(hull, name=mesh.name, excess=excess, _cache={}), why


def _volume6_faces(ints: np.ndarray, faces: np.ndarray) -> int:
    """Six times the enclosed volume of a closed triangle mesh on grid ints (exact)."""
    total = 0
    for a, b, c in ints[faces].tolist():
        total += (a[0] * (b[1] * c[2] - b[2] * c[1]) - a[1] * (b[0] * c[2] - b[2] * c[0])
                  + a[2] * (b[0] * c[1] - b[1] * c[0]))
    return total
