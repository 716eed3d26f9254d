"""Closed, oriented 2-manifold triangle meshes on an exact integer grid.

Works on meshes given as ``(n, 3) float64`` vertices and ``(m, 3) int64`` faces. A
:class:`ClosedMesh` is such a mesh after validation: its vertices are snapped onto a dyadic
:class:`~cspace.geometry.exact.Grid` (integer coordinates, int64), welded by exact snapped position,
and its faces are wound counter-clockwise seen from outside (outward normals).

Every decision made while validating (which vertices weld, whether a face has zero area,
which faces to flip, the sign of a volume) is exact: it uses integer arithmetic on the grid
coordinates. No tolerance decides anything. The only approximation is the snapping itself,
which moves each coordinate by at most ``grid.error_bound`` (half a grid step).

Bad input raises a subclass of :class:`~cspace.errors.InvalidMeshError` whose message says
what is wrong and where (face and vertex indices of the *input* arrays), prefixed with the
mesh name, e.g. ``mesh 'grate.stl': 3 edges shared by more than 2 faces, first between
vertices (12, 40) (faces 7, 9, 31)``.
"""

from __future__ import annotations

import math
import os
from pathlib import Path

import numpy as np

from ..errors import (
    ArgumentTypeError,
    DegenerateError,
    EmptyMeshError,
    GridRangeError,
    InvalidMeshError,
    NonFiniteError,
    OperandTypeError,
)
from ..geometry.exact import Grid, cross
from .validate import _count, _fmt, _validate_faces, _volume6

__all__ = ["ClosedMesh", "as_mesh"]


class ClosedMesh:
    """A closed, oriented 2-manifold triangle mesh snapped onto an exact integer grid.

    Build one with :meth:`from_arrays`, :meth:`load` or :func:`as_mesh`; they validate the
    input (see :meth:`from_arrays`). A ClosedMesh is immutable: its arrays are read-only and
    every operation returns a new mesh.

    Attributes
    ----------
    vertices : (n, 3) float64
        Snapped coordinates in scene units, exactly ``grid.to_float(ints)``.
    faces : (m, 3) int64
        Vertex indices, counter-clockwise seen from outside (normals point out of the solid).
        Faces keep the order of the input faces; only their winding may have been reversed,
        except where zero-area faces were repaired (step 5: dropped, and a face split in two
        keeps its first half in its place and appends the second).
    ints : (n, 3) int64
        Grid integer coordinates of the vertices (``|ints| <= grid.limit``).
    grid : Grid
        The snapping grid (step ``grid.step``).
    name : str
        Name used in error messages (the file name for :meth:`load`).
    components : (m,) int64
        Connected-component label of each face (faces sharing an edge are connected), numbered
        in order of each component's first face.

    Notes
    -----
    A mesh may have several components (shells). Each component is a closed, orientable,
    2-manifold surface; its signed volume is positive (an outer shell) or negative (a cavity,
    i.e. an inner shell wound inwards). See step 10 of :meth:`from_arrays`.
    """

    __slots__ = ("_vertices", "_faces", "_ints", "_grid", "_name", "_components")

    def __init__(self, vertices, faces, *, grid: Grid | None = None, name: str = "mesh"):
        """Validate ``(vertices, faces)``; the same as :meth:`from_arrays`."""
        ints, faces, grid, components = _validate(vertices, faces, grid, str(name))
        self._set(ints, faces, grid, str(name), components)

    def _set(self, ints, faces, grid, name, components) -> None:
        ints = np.ascontiguousarray(ints, dtype=np.int64)
        vertices = grid.to_float(ints)
        faces = np.ascontiguousarray(faces, dtype=np.int64)
        components = np.ascontiguousarray(components, dtype=np.int64)
        for a in (ints, vertices, faces, components):
            a.flags.writeable = False
        self._ints, self._vertices, self._faces = ints, vertices, faces
        self._grid, self._name, self._components = grid, name, components

    @classmethod
    def _trusted(cls, ints, faces, grid, name, components) -> "ClosedMesh":
        """A mesh from arrays already validated (no checks)."""
        mesh = cls.__new__(cls)
        mesh._set(ints, faces, grid, name, components)
        return mesh

    # -- construction -------------------------------------------------------------------------

    @classmethod
    def from_arrays(
        cls, vertices, faces, *, grid: Grid | None = None, name: str = "mesh"
    ) -> "ClosedMesh":
        """Snap, weld, validate and orient a triangle mesh.

        Parameters
        ----------
        vertices : (n, 3) float64
            Vertex coordinates in scene units (any real numeric dtype is converted).
        faces : (m, 3) int64
            Vertex indices of the triangles (any integer dtype). The winding may be
            inconsistent or inverted: it is repaired (steps 8 and 10 below).
        grid : Grid, optional
            Snapping grid. Default ``Grid.for_points(vertices[referenced])``: the grid for
            the largest absolute coordinate of the vertices the faces use. Pass the scene's
            grid when the mesh takes part in a scene with other objects.
        name : str, default 'mesh'
            Used in error messages.

        Returns
        -------
        mesh : ClosedMesh

        Raises
        ------
        InvalidMeshError
            Wrong shape or dtype, or a face index out of range.
        EmptyMeshError
            No vertices or no faces.
        NonFiniteError
            A vertex coordinate is NaN or infinite.
        GridRangeError
            A vertex lies beyond the range of the given ``grid``.
        DegenerateError
            A face collapses when welded or has zero area and cannot be repaired (step 5), or
            a component encloses zero volume.
        DuplicateFaceError
            Two faces use the same three vertices (opposite windings: a double-sided surface).
        OpenMeshError
            An edge is used by only one face.
        NonManifoldError
            An edge is used by more than two faces, a component is not orientable, or the
            faces around a vertex form more than one fan.

        Notes
        -----
        The steps, in order (each failure raises the error named, with the indices of the
        first offender in the *input* arrays and the number of offenders):

        1. shapes and dtypes; emptiness;
        2. face indices within ``[0, n)``;
        3. finite coordinates (all input vertices are checked);
        4. snapping with ``grid.snap`` (round half to even to multiples of ``grid.step``),
           then **welding by exact snapped position**: vertices whose integer coordinates are
           equal become one vertex, so points closer than a grid step may merge and points
           that differ after snapping never do. Vertices no face uses are dropped. Welded
           vertices are numbered in the order they are first met in the input vertex array,
           so a clean mesh keeps its vertex numbering;
        5. degenerate faces: a face whose vertices weld together (a *needle*), or whose
           exact integer cross product of edge vectors is zero (a *cap*: three collinear
           vertices). Real meshes have slivers and snapping makes more, so they are
           **repaired exactly** when that keeps a solid: a needle is dropped (welding has
           collapsed its zero-length edge), a cap ``(u, v, w)`` with ``w`` strictly inside
           ``uv`` is dropped and its neighbour across ``uv`` split at ``w`` (an edge split),
           repeated until none is left. The repaired surface is the same point set with the
           same winding number everywhere, so no error bound grows. The repaired mesh must
           pass steps 6-10 and not meet itself (:func:`cspace.mesh.self_intersection.self_intersections`: a
           part thinner than a step flattens into a fin); else, or when a cap's longest edge
           does not have exactly one other face, the degenerate face is the error (with why
           the repair failed);
        6. duplicate faces (the same three vertices);
        7. every edge is used by exactly two faces;
        8. orientation: within each connected component, faces are flipped to agree with
           their neighbours, propagated breadth-first from the component's first face; of the
           two consistent orientations the one that flips fewer input faces is kept (ties:
           the first face's winding). A component that cannot be oriented is refused;
        9. every vertex is manifold: its faces form a single fan;
        10. outward orientation from the exact signed volume of each component. A component
            of zero volume is refused. The component holding the lexicographically greatest
            vertex is an outer shell (nothing encloses it); if its volume is negative the
            whole mesh is inside out and every face is flipped. So a mesh whose components
            are all negative is flipped, one whose components are all positive is kept.
            When signs are mixed, a negative component is a **cavity** (an inner shell of a
            solid with holes, wound inwards) when it lies inside a positive component's
            solid, decided exactly as scenes decide it
            (:func:`cspace.mesh.components.nested_pairs`: a vertex of it inside, by an exact
            winding number); one inside no positive component's solid bounds nothing (its
            inside would be unbounded): it is a separate body wound inside out and is
            turned outwards, as a scene turns it. Self-intersections are not checked here.

        Cost: ``O(m log m)``, vectorised (sorting and scipy graph traversals).

        Examples
        --------
        >>> import trimesh
        >>> box = trimesh.creation.box(extents=(2, 2, 2))
        >>> mesh = ClosedMesh.from_arrays(box.vertices, box.faces[:, ::-1], name="box")
        >>> mesh.volume  # the inside-out input is flipped back; the volume is exact
        8.0
        >>> ClosedMesh.from_arrays(box.vertices, box.faces[1:], name="box")
        ... # doctest: +ELLIPSIS
        Traceback (most recent call last):
        ...
        cspace.errors.OpenMeshError: mesh 'box': 3 boundary edges (open mesh), first between ...
        """
        return cls(vertices, faces, grid=grid, name=name)

    @classmethod
    def load(cls, path, *, grid: Grid | None = None, name: str | None = None) -> "ClosedMesh":
        """Load a mesh file with trimesh, then validate it as :meth:`from_arrays` does.

        Parameters
        ----------
        path : str or os.PathLike
            Any file :func:`cspace.mesh.files.read_mesh_file` reads: Collada as Assimp places it,
            BYU ``.g``, and whatever trimesh loads as a triangle mesh (OBJ, STL, PLY, OFF,
            GLB, ...). A scene of several geometries is concatenated into one mesh.
        grid : Grid, optional
            Snapping grid; default the grid for the mesh's own coordinates.
        name : str, optional
            Name for error messages; default the file name.

        Returns
        -------
        mesh : ClosedMesh

        Raises
        ------
        MeshFileError
            If the file is missing or cannot be read as triangles.
        InvalidMeshError
            Any validation error of :meth:`from_arrays`.

        Notes
        -----
        The file is read with ``process=False``: trimesh does not merge or drop anything.
        OBJ files whose faces carry texture or normal indices come back with split vertices;
        the exact weld of :meth:`from_arrays` merges them again by position.
        """
        from .files import read_mesh_file

        path = Path(os.fspath(path))
        if name is None:
            name = path.name
        loaded = read_mesh_file(path, f"mesh {name!r}")
        vertices, faces = loaded.vertices, loaded.faces
        return cls(vertices, faces, grid=grid, name=name)

    def on_grid(self, grid: Grid) -> "ClosedMesh":
        """The same mesh snapped onto another grid, re-welded and re-validated.

        Parameters
        ----------
        grid : Grid
            The new grid. A coarser grid may weld vertices and so raise
            :class:`~cspace.errors.DegenerateError` (or other validation errors).

        Returns
        -------
        mesh : ClosedMesh
            ``self`` if ``grid`` equals :attr:`grid`.
        """
        if not isinstance(grid, Grid):
            raise ArgumentTypeError(f"grid must be a cspace.Grid, got {type(grid).__name__}")
        if grid == self._grid:
            return self
        return type(self)(self._vertices, self._faces, grid=grid, name=self._name)

    # -- accessors ------------------------------------------------------------------------------

    @property
    def vertices(self) -> np.ndarray:
        """(n, 3) float64: snapped vertex coordinates, exactly ``grid.to_float(ints)``."""
        return self._vertices

    @property
    def faces(self) -> np.ndarray:
        """(m, 3) int64: triangles, counter-clockwise seen from outside."""
        return self._faces

    @property
    def ints(self) -> np.ndarray:
        """(n, 3) int64: grid integer coordinates of the vertices."""
        return self._ints

    @property
    def grid(self) -> Grid:
        """The snapping grid."""
        return self._grid

    @property
    def name(self) -> str:
        """Name used in error messages."""
        return self._name

    @property
    def components(self) -> np.ndarray:
        """(m,) int64: connected-component label per face, numbered by first face."""
        return self._components

    # -- measures -------------------------------------------------------------------------------

    def volume6(self) -> int:
        """Exact six times the enclosed volume, in grid units cubed.

        Returns
        -------
        volume6 : int
            ``sum over faces of det[v0, v1, v2]`` on the integer coordinates, as a Python
            int (it can exceed int64). Cavities count negatively. Positive for every mesh
            whose shells do not intersect.
        """
        return _volume6(self._ints, self._faces)[0]

    @property
    def volume(self) -> float:
        """Enclosed volume in scene units cubed: ``volume6 * step**3 / 6``, rounded once."""
        # int / int is correctly rounded; scaling by a power of two is exact.
        return math.ldexp(self.volume6() / 6, 3 * self._grid.exponent)

    def to_trimesh(self):
        """The mesh as a ``trimesh.Trimesh`` (``process=False``; arrays are copies).

        Returns
        -------
        mesh : trimesh.Trimesh
        """
        import trimesh

        return trimesh.Trimesh(
            vertices=self._vertices.copy(),
            faces=self._faces.copy(),
            process=False,
            metadata={"name": self._name},
        )

    def __repr__(self) -> str:
        ncomp = int(self._components.max()) + 1 if len(self._components) else 0
        return (
            f"ClosedMesh(name={self._name!r}, vertices={len(self._vertices)}, "
            f"faces={len(self._faces)}, components={ncomp}, step=2**{self._grid.exponent})"
        )


def as_mesh(obj, *, grid: Grid | None = None, name: str | None = None) -> ClosedMesh:
    """Coerce a mesh-like object to a validated :class:`ClosedMesh`.

    Parameters
    ----------
    obj : ClosedMesh, trimesh.Trimesh, (vertices, faces) tuple, str or os.PathLike
        - a ClosedMesh is returned as is, or re-snapped with :meth:`ClosedMesh.on_grid` if
          ``grid`` is given and differs from its grid (renamed if ``name`` is given);
        - any object with ``.vertices`` and ``.faces`` (e.g. a ``trimesh.Trimesh``);
        - a ``(vertices, faces)`` pair of arrays;
        - a path to a file, read with :meth:`ClosedMesh.load`.
    grid : Grid, optional
        Snapping grid; default the grid for the object's own coordinates (a ClosedMesh
        keeps its grid).
    name : str, optional
        Name for error messages; default the file name for paths, the ``name`` or
        ``file_name`` metadata of a trimesh, else ``'mesh'``.

    Returns
    -------
    mesh : ClosedMesh

    Raises
    ------
    OperandTypeError
        If ``obj`` is none of the above (also a ``TypeError``).
    InvalidMeshError
        Any validation error of :meth:`ClosedMesh.from_arrays`.
    """
    if isinstance(obj, ClosedMesh):
        mesh = obj if grid is None else obj.on_grid(grid)
        if name is not None and str(name) != mesh.name:
            mesh = ClosedMesh._trusted(mesh.ints, mesh.faces, mesh.grid, str(name), mesh.components)
        return mesh
    if isinstance(obj, (str, os.PathLike)):
        return ClosedMesh.load(obj, grid=grid, name=name)
    if hasattr(obj, "vertices") and hasattr(obj, "faces"):
        if name is None:
            meta = getattr(obj, "metadata", None)
            if isinstance(meta, dict):
                name = meta.get("name") or meta.get("file_name")
        return ClosedMesh.from_arrays(
            np.asarray(obj.vertices), np.asarray(obj.faces), grid=grid, name=name or "mesh"
        )
    if isinstance(obj, (tuple, list)) and len(obj) == 2:
        vertices, faces = obj
        return ClosedMesh.from_arrays(vertices, faces, grid=grid, name=name or "mesh")
    raise OperandTypeError(
        f"cannot make a mesh from {type(obj).__name__}: expected a ClosedMesh, an object with "
        "`.vertices` and `.faces` (e.g. trimesh.Trimesh), a (vertices, faces) pair or a path"
    )


def _validate(vertices, faces, grid, name):
    """The :meth:`ClosedMesh.from_arrays` pipeline.

    Returns
    -------
    ints : (k, 3) int64
        Welded grid coordinates.
    faces : (m, 3) int64
        Oriented faces into ``ints``.
    grid : Grid
    components : (m,) int64
    """

    def fail(error, message):
        return error(f"mesh {name!r}: {message}")

    # 1. Shapes and dtypes, then emptiness.
    arrays = []
    for value, what, letter in ((vertices, "vertices", "n"), (faces, "faces", "m")):
        try:
            a = np.asarray(value)
        except (ValueError, TypeError) as exc:
            raise fail(InvalidMeshError, f"{what} are not a rectangular array: {exc}") from exc
        if not ((a.ndim == 2 and a.shape[1] == 3) or (a.ndim == 1 and a.size == 0)):
            raise fail(InvalidMeshError, f"{what} must be ({letter}, 3), got {a.shape}")
        arrays.append(a)
    v, f = arrays
    if len(v) == 0:
        raise fail(EmptyMeshError, "the mesh has no vertices")
    if len(f) == 0:
        raise fail(EmptyMeshError, "the mesh has no faces")
    if v.dtype.kind not in "iuf":
        raise fail(InvalidMeshError, f"vertices must be real numbers, got dtype {v.dtype}")
    if f.dtype.kind not in "iu":
        raise fail(InvalidMeshError, f"faces must be integer vertex indices, got dtype {f.dtype}")
    n, m = len(v), len(f)

    # 2. Face indices in range.
    bad = (f < 0) | (f >= n)
    if bad.any():
        rows = np.nonzero(bad.any(axis=1))[0]
        i = int(rows[0])
        raise fail(
            InvalidMeshError,
            f"face {i} refers to vertex {int(f[i][bad[i]][0])}; the mesh has {n} vertices"
            + _count(len(rows), "faces have out-of-range indices"),
        )
    f = f.astype(np.int64)

    # 3. Finite coordinates.
    v = v.astype(np.float64)
    finite = np.isfinite(v).all(axis=1)
    if not finite.all():
        rows = np.nonzero(~finite)[0]
        i = int(rows[0])
        raise fail(
            NonFiniteError,
            f"vertex {i} has a non-finite coordinate {_fmt(v[i])}"
            + _count(len(rows), "vertices are not finite"),
        )

    # 4. Snap, then weld by exact snapped position.
    used = np.unique(f)  # referenced input vertices, sorted
    if grid is None:
        grid = Grid.for_points(v[used])
    elif not isinstance(grid, Grid):
        raise ArgumentTypeError(f"grid must be a cspace.Grid, got {type(grid).__name__}")
    try:
        snapped = grid.snap(v[used])
    except GridRangeError as exc:
        k = np.rint(np.ldexp(v[used], -grid.exponent)) - np.asarray(grid.origin, np.float64)
        over = ~(np.abs(k).max(axis=1) <= grid.limit)
        i = int(used[np.argmax(over)])
        raise fail(
            GridRangeError,
            f"vertex {i} at {_fmt(v[i])} is beyond the grid's range "
            f"+-{grid.limit * grid.step:.6g}; build the grid from every object of the scene "
            "(Grid.for_points)",
        ) from exc
    uniq, first, inverse = np.unique(snapped, axis=0, return_index=True, return_inverse=True)
    inverse = inverse.reshape(-1)
    by_first = np.argsort(first, kind="stable")
    rank = np.zeros(len(uniq), dtype=np.int64)
    rank[by_first] = np.arange(len(uniq), dtype=np.int64)
    ints = uniq[by_first]  # welded vertices, in order of first use
    rep = used[first[by_first]]  # the input index naming each welded vertex
    remap = np.full(n, -1, dtype=np.int64)
    remap[used] = rank[inverse]
    F = remap[f]
    k = len(ints)

    # 5. Degenerate faces: collapsed by welding, then exactly zero area. They are repaired
    #    when that keeps a valid solid with the same point set (_repair_degenerate).
    collapsed = (F[:, 0] == F[:, 1]) | (F[:, 1] == F[:, 2]) | (F[:, 2] == F[:, 0])
    P = ints[F]  # (m, 3, 3)
    normal = cross(P[:, 1] - P[:, 0], P[:, 2] - P[:, 0])
    flat = ~normal.any(axis=1) & ~collapsed
    if collapsed.any():
        rows = np.nonzero(collapsed)[0]
        i = int(rows[0])
        distinct = len(set(F[i].tolist()))
        points = "one grid point" if distinct == 1 else f"{distinct} distinct grid points"
        message = (f"face {i} collapses: its vertices {_fmt(f[i])} weld to {points} "
                   f"(grid step 2**{grid.exponent})" + _count(len(rows), "faces collapse"))
    elif flat.any():
        rows = np.nonzero(flat)[0]
        i = int(rows[0])
        message = (f"face {i} has zero area (collinear vertices {_fmt(rep[F[i]])} on the grid "
                   f"of step 2**{grid.exponent})" + _count(len(rows), "faces have zero area"))
    if collapsed.any() or flat.any():
        return _repaired(ints, F, collapsed, flat, rep, grid, name, message)
    return _validate_faces(ints, F, rep, grid, name)


def _repaired(ints, F, collapsed, flat, rep, grid, name, message):
    """Steps 6-10 on the mesh with its degenerate faces repaired (step 5), or the
    :class:`DegenerateError` of ``message`` saying why the repair cannot keep a solid."""

    def fail(why: str):
        return DegenerateError(f"mesh {name!r}: {message}; {why}")

    G, why = _repair_degenerate(ints, F, collapsed, flat)
    if G is None or not len(G):
        raise fail(f"not repairable: {why or 'every face collapses'}")
    # The repair keeps the point set only where each collapsed face's segment or point lies on
    # a face left: a needle or a fin thinner than the step collapses to segments no face holds,
    # and dropping them would lose an obstacle (issue #51). Such a body has no solid here.
    from .components import snapping_losses

    thin, _ = snapping_losses(len(ints), F, G)
    if len(thin):
        n_seg = int((thin[:, 0] != thin[:, 1]).sum())
        raise fail(f"not repairable: {n_seg} segments and {len(thin) - n_seg} points of "
                   "features thinner than the step (the first between input vertices "
                   f"{_fmt(rep[thin[0, :2]])}) lie on no face left, so dropping the collapsed "
                   "faces would lose them")
    used = np.unique(G)
    if len(used) < len(ints):  # vertices only collapsed faces used
        G = np.searchsorted(used, G)
        ints, rep = ints[used], rep[used]
    try:
        ints, G, grid, components = _validate_faces(ints, G, rep, grid, name)
        repaired = ClosedMesh._trusted(ints, G, grid, name, components)
        from .self_intersection import self_intersections

        crossing = self_intersections(repaired)
    except InvalidMeshError as exc:
        detail = str(exc).removeprefix(f"mesh {name!r}: ")
        raise fail(f"repairing them leaves no valid solid ({type(exc).__name__}: {detail})"
                   ) from None
    if len(crossing):  # snapping folded it, or flattened a part thinner than a step
        i, j = crossing[0].tolist()
        raise fail(f"repairing them leaves a surface meeting itself (triangles {i} and {j} of "
                   f"the repaired mesh; {len(crossing)} pairs): snapping moved faces through "
                   "each other or flattened a part thinner than the step, so it bounds no solid")
    return ints, G, grid, components


def _repair_degenerate(ints, F, collapsed, flat):
    """Faces with the zero-area triangles of a welded mesh repaired exactly, keeping the
    point set of the surface: ``(faces, None)``, or ``(None, why)`` when they cannot be.

    - a *needle* (two corners welded to one grid point) is dropped: welding has already
      collapsed its zero-length edge, and its two other edges are one edge now, shared by
      its neighbours;
    - a *cap* ``(u, v, w)``, three distinct collinear corners with ``w`` strictly between
      ``u`` and ``v`` (exact integer predicates), is dropped and its neighbour across
      ``uv``, ``(u, v, x)`` in its own winding, becomes ``(u, w, x)`` and ``(w, v, x)``: an
      edge split, which covers the same points, keeps every edge used twice and each face's
      winding. Caps made by a split (the neighbour was a cap) are split in turn.

    The surface is the same point set and its winding number is the same everywhere (a face
    of zero area adds none), so nothing is added to any error bound. Not repairable: a
    cap's long edge used by other than two faces, or its neighbour already using the middle
    corner. Faces keep their order; a split face's second half is appended.
    """
    keep = ~collapsed
    faces = [tuple(t) for t in F[keep].tolist()]
    caps = np.nonzero(flat[keep])[0].tolist()
    if not caps:
        return np.asarray(faces, dtype=np.int64).reshape(-1, 3), None
    X = [tuple(p) for p in ints.tolist()]  # exact Python ints
    alive = [True] * len(faces)
    edges: dict = {}

    def key(a, b):
        return (a, b) if a < b else (b, a)

    def link(i, on=True):
        for a, b in ((0, 1), (1, 2), (2, 0)):
            users = edges.setdefault(key(faces[i][a], faces[i][b]), [])
            users.append(i) if on else users.remove(i)

    def zero_area(t) -> bool:
        (ax, ay, az), (bx, by, bz), (cx, cy, cz) = (X[k] for k in t)
        ux, uy, uz, vx, vy, vz = bx - ax, by - ay, bz - az, cx - ax, cy - ay, cz - az
        return uy * vz == uz * vy and uz * vx == ux * vz and ux * vy == uy * vx

    def between(w, u, v) -> bool:  # collinear, distinct: is w strictly inside uv?
        return sum((X[u][k] - X[w][k]) * (X[v][k] - X[w][k]) for k in range(3)) < 0

    for i in range(len(faces)):
        link(i)
    budget = 4 * len(faces) + 16  # each split shortens the caps' long edges: it ends
    while caps:
        i = caps.pop()
        if not alive[i]:
            continue
        a, b, c = faces[i]
        u, v, w = next(t for t in ((a, b, c), (b, c, a), (c, a, b)) if between(t[2], t[0], t[1]))
        others = [j for j in edges[key(u, v)] if j != i]
        if len(others) != 1:
            return None, (f"a zero-area face's longest edge is used by {len(others) + 1} faces "
                          "(a split needs exactly one neighbour)")
        j = others[0]
        if w in faces[j]:
            return None, ("a zero-area face's neighbour across its longest edge already uses its "
                          "middle corner (a flap of zero width)")
        budget -= 1
        if budget < 0:
            return None, "splitting zero-area faces does not end"
        link(i, False)
        link(j, False)
        alive[i] = False
        old = faces[j]
        faces[j] = tuple(w if k == v else k for k in old)  # (u, w, x) in old's winding
        faces.append(tuple(w if k == u else k for k in old))  # (w, v, x)
        alive.append(True)
        for n in (j, len(faces) - 1):
            link(n)
            if zero_area(faces[n]):
                caps.append(n)
    out = [t for t, ok in zip(faces, alive) if ok]
    return np.asarray(out, dtype=np.int64).reshape(-1, 3), None
