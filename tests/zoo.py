"""A zoo of closed 2-manifold test meshes (obstacles A) and convex point sets (robots B).

Every mesh function returns ``(vertices (n, 3) float64, faces (m, 3) int64)``: a closed,
oriented 2-manifold, wound counter-clockwise seen from outside (outward normals), with shared
(welded) vertices and no unused vertex, so :meth:`cspace.ClosedMesh.from_arrays` accepts it
unchanged (same faces, same winding; see ``tests/test_oracles.py``).

Every convex function returns ``(n, 3) float64`` points; hull them with
:meth:`cspace.ConvexPolytope.from_points`.

Used only by tests and benchmarks; nothing here depends on :mod:`cspace`.
"""

from __future__ import annotations

import itertools
from pathlib import Path

import numpy as np

__all__ = [
    "voxel_solid",
    "l_shape",
    "comb",
    "grate",
    "genus3",
    "cup",
    "hollow_box",
    "stairs",
    "torus",
    "star",
    "twisted_prism",
    "random_rotation",
    "euler_characteristic",
    "ZOO",
    "zoo_meshes",
    "SHARED_CLOSED_MESHES",
    "shared_closed_meshes",
    "box_points",
    "icosphere_points",
    "hull20",
    "cube_rotated",
]


#: ``(vertices (n, 3) float64, faces (m, 3) int64)``
Mesh = tuple[np.ndarray, np.ndarray]


# --------------------------------------------------------------------------------------
# voxel solids


def _vertex_table() -> np.ndarray:
    """(256,) bool: is the boundary of the occupied octants manifold at the shared corner?

    Index bit ``4*dx + 2*dy + dz`` says whether the cube at offset ``(dx, dy, dz)`` of a 2x2x2
    block is occupied. Assuming no non-manifold edge (checked separately), the boundary
    surface is a single fan around the block's centre vertex iff the occupied octants and
    the empty octants are each connected through shared faces (octants adjacent in the cube
    graph): on the small sphere about the vertex the number of boundary circles is
    ``components(occupied) + components(empty) - 1``. All-empty and all-full are fine.
    """
    table = np.ones(256, dtype=bool)
    for code in range(1, 255):
        occ = [(code >> i) & 1 for i in range(8)]
        for value in (0, 1):
            cells = [i for i in range(8) if occ[i] == value]
            seen, todo = {cells[0]}, [cells[0]]
            while todo:
                i = todo.pop()
                for b in (1, 2, 4):
                    j = i ^ b
                    if occ[j] == value and j not in seen:
                        seen.add(j)
                        todo.append(j)
            if len(seen) != len(cells):
                table[code] = False
    return table


_VERTEX_OK = _vertex_table()


def _check_voxels(pad: np.ndarray) -> None:
    """Raise ValueError if the boundary of the padded occupancy is not a 2-manifold."""
    # Edges: around every lattice edge the four cells must not be a checkerboard (two
    # cells sharing only that edge).
    for axis in range(3):
        b, c = [a for a in range(3) if a != axis]

        def cell(db, dc, b=b, c=c):
            sl = [slice(None)] * 3
            sl[b] = slice(db, pad.shape[b] - 1 + db)
            sl[c] = slice(dc, pad.shape[c] - 1 + dc)
            return pad[tuple(sl)]

        x00, x10, x01, x11 = cell(0, 0), cell(1, 0), cell(0, 1), cell(1, 1)
        bad = (x00 & x11 & ~x10 & ~x01) | (x10 & x01 & ~x00 & ~x11)
        if bad.any():
            idx = np.argwhere(bad)[0]
            raise ValueError(
                f"voxel set is not a 2-manifold: {int(bad.sum())} lattice edges along axis "
                f"{'xyz'[axis]} have two voxels touching only along the edge, first near "
                f"voxel {tuple(int(i) - 1 for i in idx)}"
            )
    # Vertices: the 2x2x2 block around every lattice vertex.
    code = np.zeros(tuple(s - 1 for s in pad.shape), dtype=np.int64)
    for dx, dy, dz in itertools.product((0, 1), repeat=3):
        X, Y, Z = pad.shape
        sub = pad[dx : X - 1 + dx, dy : Y - 1 + dy, dz : Z - 1 + dz]
        code |= sub.astype(np.int64) << (4 * dx + 2 * dy + dz)
    bad = ~_VERTEX_OK[code]
    if bad.any():
        idx = np.argwhere(bad)[0]
        raise ValueError(
            f"voxel set is not a 2-manifold: {int(bad.sum())} lattice vertices where voxels "
            f"touch only at the vertex (or empty cells do), first at lattice vertex "
            f"{tuple(int(i) for i in idx)}"
        )


def _voxel_surface(occupancy, size=1.0, origin=(0.0, 0.0, 0.0)) -> Mesh:
    """Boundary squares of the voxel set, 2 triangles each, welded; no manifold check."""
    occ = np.asarray(occupancy, dtype=bool)
    if occ.ndim != 3:
        raise ValueError(f"occupancy must be a 3D boolean array, got shape {occ.shape}")
    if not occ.any():
        raise ValueError("occupancy is empty: no voxel is set")
    pad = np.pad(occ, 1)
    dims = np.array(occ.shape) + 1  # lattice vertices per axis
    quads = []
    for axis in range(3):
        b, c = (axis + 1) % 3, (axis + 2) % 3  # e_b x e_c = e_axis
        for sign in (1, -1):
            shifted = np.roll(pad, -sign, axis=axis)  # the neighbour across the face
            cells = np.argwhere(pad & ~shifted) - 1  # voxel indices in occ
            if not len(cells):
                continue
            base = cells.copy()
            if sign > 0:
                base[:, axis] += 1
            corners = []
            for db, dc in ((0, 0), (1, 0), (1, 1), (0, 1)):  # CCW about +e_axis
                p = base.copy()
                p[:, b] += db
                p[:, c] += dc
                corners.append(p)
            if sign < 0:
                corners = corners[::-1]
            quads.append(np.stack([np.ravel_multi_index(p.T, dims) for p in corners], axis=1))
    quads = np.concatenate(quads)
    keys, inverse = np.unique(quads.reshape(-1), return_inverse=True)
    quads = inverse.reshape(-1, 4).astype(np.int64)
    lattice = np.stack(np.unravel_index(keys, dims), axis=1).astype(np.float64)
    vertices = np.asarray(origin, dtype=np.float64) + float(size) * lattice
    faces = np.concatenate([quads[:, [0, 1, 2]], quads[:, [0, 2, 3]]])
    return vertices, faces


def voxel_solid(occupancy, size: float = 1.0, origin=(0.0, 0.0, 0.0)) -> Mesh:
    """Boundary surface of a union of cubes.

    Parameters
    ----------
    occupancy : (X, Y, Z) bool array
        Voxel ``(i, j, k)`` is the cube ``origin + size * ([i, i+1] x [j, j+1] x [k, k+1])``.
    size : float
        Edge length of a voxel.
    origin : (3,) float
        Corner of voxel ``(0, 0, 0)``.

    Returns
    -------
    vertices : (n, 3) float64
        Lattice points used by the surface (welded: each once).
    faces : (m, 3) int64
        Every boundary square split into two triangles, outward. Empty cells enclosed by
        voxels give inner shells (cavities) wound inwards.

    Raises
    ------
    ValueError
        If the array is not 3D, has no voxel, or the surface would not be a 2-manifold: two
        voxels touching only along an edge or only at a vertex (or two empty cells doing
        so), found by checking every 2x2 (edges) and 2x2x2 (vertices) neighbourhood.
    """
    occ = np.asarray(occupancy, dtype=bool)
    if occ.ndim != 3:
        raise ValueError(f"occupancy must be a 3D boolean array, got shape {occ.shape}")
    _check_voxels(np.pad(occ, 1))
    return _voxel_surface(occ, size, origin)


def _grid(shape, cells=(), holes=()) -> np.ndarray:
    occ = np.zeros(shape, dtype=bool)
    for c in cells:
        occ[c] = True
    for h in holes:
        occ[h] = False
    return occ


def l_shape(arm: int = 2, depth: int = 1) -> Mesh:
    """An L of voxels in the xy plane: two arms of ``arm`` voxels beyond the shared corner.

    Defaults: 5 voxels, 44 triangles (one reflex edge line along z).
    """
    occ = np.zeros((arm + 1, arm + 1, depth), dtype=bool)
    occ[:, 0, :] = True
    occ[0, :, :] = True
    return voxel_solid(occ)


def comb(teeth: int = 5, length: int = 2) -> Mesh:
    """A bar of ``2*teeth - 1`` voxels along x with ``teeth`` teeth of ``length`` voxels along +y.

    Defaults: 156 triangles; slots 1 voxel wide between the teeth.
    """
    occ = np.zeros((2 * teeth - 1, 1 + length, 1), dtype=bool)
    occ[:, 0, 0] = True
    occ[::2, 1:, 0] = True
    return voxel_solid(occ)


def grate(n: int = 3) -> Mesh:
    """A flat ``(2n+1) x (2n+1) x 1`` frame with ``n x n`` square through-holes: genus ``n*n``."""
    occ = np.ones((2 * n + 1, 2 * n + 1, 1), dtype=bool)
    occ[1::2, 1::2, :] = False
    return voxel_solid(occ)


def genus3() -> Mesh:
    """A ``7 x 3 x 1`` plate with 3 through-holes in a row: genus 3."""
    occ = np.ones((7, 3, 1), dtype=bool)
    occ[1::2, 1, :] = False
    return voxel_solid(occ)


def cup() -> Mesh:
    """A ``3 x 3 x 3`` box with a ``1 x 1 x 2`` well open at the top.

    Genus 0; the well is not a closed cavity (see :func:`hollow_box` for one).
    """
    occ = np.ones((3, 3, 3), dtype=bool)
    occ[1, 1, 1:] = False
    return voxel_solid(occ)


def hollow_box() -> Mesh:
    """A ``3 x 3 x 3`` box with its centre voxel empty: an outer shell and a closed cavity.

    Two components (Euler characteristic 4); the cavity shell is wound inwards.
    """
    occ = np.ones((3, 3, 3), dtype=bool)
    occ[1, 1, 1] = False
    return voxel_solid(occ)


def stairs(steps: int = 5, width: int = 3) -> Mesh:
    """A staircase: column ``i`` (along x) is ``i + 1`` voxels high, ``width`` voxels deep in y.

    Many coplanar adjacent faces (each unit square is its own pair of triangles).
    """
    occ = np.zeros((steps, width, steps), dtype=bool)
    for i in range(steps):
        occ[i, :, : i + 1] = True
    return voxel_solid(occ)


# --------------------------------------------------------------------------------------
# smooth and star-shaped meshes


def torus(major: float = 1.0, minor: float = 0.35, sections: int = 48, ring: int = 24) -> Mesh:
    """A triangulated torus about the z axis: ``sections * ring * 2`` triangles (2304 by default).

    Built here (not with ``trimesh.creation.torus``) so the vertex layout is fixed:
    vertex ``i * ring + j`` is at angle ``2*pi*i/sections`` around z and ``2*pi*j/ring``
    around the tube.
    """
    u = 2 * np.pi * np.arange(sections) / sections
    v = 2 * np.pi * np.arange(ring) / ring
    U, W = np.meshgrid(u, v, indexing="ij")
    r = major + minor * np.cos(W)
    vertices = np.stack([r * np.cos(U), r * np.sin(U), minor * np.sin(W)], axis=-1).reshape(-1, 3)
    i, j = np.meshgrid(np.arange(sections), np.arange(ring), indexing="ij")
    i, j = i.ravel(), j.ravel()
    a = i * ring + j
    b = ((i + 1) % sections) * ring + j
    c = ((i + 1) % sections) * ring + (j + 1) % ring
    d = i * ring + (j + 1) % ring
    # d(position)/du x d(position)/dv points outwards: (a, b, c) runs along +u then +v.
    faces = np.concatenate([np.stack([a, b, c], axis=1), np.stack([a, c, d], axis=1)])
    return vertices.astype(np.float64), faces.astype(np.int64)


def _icosahedron() -> Mesh:
    """Regular icosahedron with vertices on the unit sphere, faces outward."""
    t = (1 + 5**0.5) / 2
    v = np.array(
        [[-1, t, 0], [1, t, 0], [-1, -t, 0], [1, -t, 0], [0, -1, t], [0, 1, t],
         [0, -1, -t], [0, 1, -t], [t, 0, -1], [t, 0, 1], [-t, 0, -1], [-t, 0, 1]],
        dtype=np.float64,
    )
    v /= np.linalg.norm(v, axis=1, keepdims=True)
    f = np.array(
        [[0, 11, 5], [0, 5, 1], [0, 1, 7], [0, 7, 10], [0, 10, 11], [1, 5, 9], [5, 11, 4],
         [11, 10, 2], [10, 7, 6], [7, 1, 8], [3, 9, 4], [3, 4, 2], [3, 2, 6], [3, 6, 8],
         [3, 8, 9], [4, 9, 5], [2, 4, 11], [6, 2, 10], [8, 6, 7], [9, 8, 1]],
        dtype=np.int64,
    )
    return v, f


def star(spikes: str = "icosahedron", height: float = 1.5) -> Mesh:
    """A star polyhedron: a pyramid spike raised on each face of a unit icosahedron.

    The apex of each spike is at distance ``height`` from the centre along the face normal
    (the icosahedron's inradius is about 0.795). 32 vertices, 60 triangles; the 12 original
    vertices are saddles (reflex and convex edges alternate around them).
    """
    if spikes != "icosahedron":
        raise ValueError(f"unknown spikes {spikes!r}: only 'icosahedron' is available")
    v, f = _icosahedron()
    centroid = v[f].mean(axis=1)
    apex = centroid / np.linalg.norm(centroid, axis=1, keepdims=True) * float(height)
    k = len(v) + np.arange(len(f))
    faces = np.concatenate([
        np.stack([f[:, 0], f[:, 1], k], axis=1),
        np.stack([f[:, 1], f[:, 2], k], axis=1),
        np.stack([f[:, 2], f[:, 0], k], axis=1),
    ])
    return np.vstack([v, apex]), faces.astype(np.int64)


def twisted_prism(
    sides: int = 3, twist: float = np.pi / 6, height: float = 1.0, seed: int | None = 3
) -> Mesh:
    """A twisted prism (Schönhardt polyhedron for ``sides=3``) with reflex edges at a slant.

    The top ``sides``-gon is the bottom one turned by ``twist`` (0 < twist < 2*pi/sides) and
    raised by ``height``; each side quad is split along its inward diagonal, which makes a
    reflex edge. Then the whole solid is rotated by :func:`random_rotation` with ``seed``
    (``None``: keep the axis along z), so no edge or face is axis aligned.
    """
    if not 0 < twist < 2 * np.pi / sides:
        raise ValueError(f"twist must be in (0, 2*pi/sides), got {twist}")
    th = 2 * np.pi * np.arange(sides) / sides
    bottom = np.stack([np.cos(th), np.sin(th), np.zeros(sides)], axis=1)
    top = np.stack([np.cos(th + twist), np.sin(th + twist), np.full(sides, float(height))], axis=1)
    vertices = np.vstack([bottom, top])
    b = np.arange(sides)
    t = sides + b
    b1, t1 = np.roll(b, -1), np.roll(t, -1)
    # Diagonal b_i - t_{i+1} is the long chord, inside the hull: a reflex edge.
    sides_f = np.concatenate([np.stack([b, b1, t1], axis=1), np.stack([b, t1, t], axis=1)])
    k = np.arange(1, sides - 1)
    bottom_f = np.stack([np.zeros_like(k), k + 1, k], axis=1)
    top_f = np.stack([np.full_like(k, sides), sides + k, sides + k + 1], axis=1)
    faces = np.concatenate([sides_f, bottom_f, top_f]).astype(np.int64)
    if seed is not None:
        vertices = random_rotation(vertices, seed)
    return vertices, faces


def random_rotation(vertices, seed: int = 0) -> np.ndarray:
    """``vertices`` rotated about the origin by a uniformly random rotation (reproducible)."""
    from scipy.spatial.transform import Rotation

    R = Rotation.random(random_state=np.random.default_rng(seed)).as_matrix()
    return np.asarray(vertices, dtype=np.float64) @ R.T


def euler_characteristic(vertices, faces) -> int:
    """``V - E + F`` of a closed triangle mesh (``E = 3F/2``).

    The genus of a single shell is ``(2 - chi) / 2``; shells add their characteristics.
    """
    faces = np.asarray(faces)
    used = np.unique(faces).size
    return int(used - 3 * len(faces) // 2 + len(faces))


#: Default zoo members: name -> (builder, expected Euler characteristic).
ZOO = {
    "l_shape": (l_shape, 2),
    "comb": (comb, 2),
    "grate": (grate, 2 - 2 * 9),
    "genus3": (genus3, 2 - 2 * 3),
    "cup": (cup, 2),
    "hollow_box": (hollow_box, 4),
    "stairs": (stairs, 2),
    "torus": (torus, 0),
    "star": (star, 2),
    "twisted_prism": (twisted_prism, 2),
}


def zoo_meshes() -> dict[str, tuple[np.ndarray, np.ndarray]]:
    """Every :data:`ZOO` member built with its default parameters."""
    return {name: build() for name, (build, _) in ZOO.items()}


# --------------------------------------------------------------------------------------
# real meshes from the shared data folder

#: Closed 2-manifold meshes of the shared data folder (all accepted by ClosedMesh.load).
SHARED_CLOSED_MESHES = {
    "bunny-128": "lien_mesh_segmentation/bunny-128.obj",
    "Centaur-1000": "lien_mesh_segmentation/Centaur-1000.obj",
    "yoda-658": "lien_mesh_segmentation/yoda-658.obj",
    "bumpy-528": "lien_mesh_unfolder/bumpy-528.obj",
    "alphaobstacle": "parasol_open_ppl_env/alpha1.6/geometries/alphaobstacle.obj",
    "trap": "parasol_open_ppl_env/bug_trap1.0/trap.obj",
}


def shared_closed_meshes(shared_data_path) -> dict[str, Path]:
    """Name -> path of the closed meshes in the shared data folder (the fixture ``shared_data``).

    All six are listed whether or not the files exist; check ``path.exists()``.
    """
    root = Path(shared_data_path)
    return {name: root / rel for name, rel in SHARED_CLOSED_MESHES.items()}


# --------------------------------------------------------------------------------------
# convex robots B (point sets)


def box_points(sx: float, sy: float, sz: float) -> np.ndarray:
    """The 8 corners of the box of extents ``(sx, sy, sz)`` centred at the origin."""
    h = np.array([sx, sy, sz], dtype=np.float64) / 2
    return np.array(list(itertools.product((-1.0, 1.0), repeat=3))) * h


def icosphere_points(subdivisions: int = 2, radius: float = 1.0) -> np.ndarray:
    """Vertices of a geodesic icosphere: hull has ``20 * 4**subdivisions`` facets (320 for 2).

    Built by midpoint subdivision of the icosahedron, projected on the sphere (the same
    construction as ``trimesh.creation.icosphere``).
    """
    v, f = _icosahedron()
    v = list(map(tuple, v))
    for _ in range(subdivisions):
        index = {}

        def mid(i, j):
            key = (min(i, j), max(i, j))
            if key not in index:
                m = (np.asarray(v[i]) + np.asarray(v[j])) / 2
                v.append(tuple(m / np.linalg.norm(m)))
                index[key] = len(v) - 1
            return index[key]

        new = []
        for a, b, c in f.tolist():
            ab, bc, ca = mid(a, b), mid(b, c), mid(c, a)
            new += [[a, ab, ca], [b, bc, ab], [c, ca, bc], [ab, bc, ca]]
        f = np.array(new, dtype=np.int64)
    return np.array(v, dtype=np.float64) * float(radius)


def hull20(seed: int = 0, scale=(1.0, 0.7, 0.5)) -> np.ndarray:
    """12 random points on an ellipsoid: a simplicial hull with 2*12 - 4 = 20 facets.

    (Generically; checked exactly for seeds 0-4 in the tests.)
    """
    rng = np.random.default_rng(seed)
    p = rng.normal(size=(12, 3))
    p /= np.linalg.norm(p, axis=1, keepdims=True)
    return p * np.asarray(scale, dtype=np.float64)


def cube_rotated(angle: float, axis=(1.0, 2.0, 3.0), size: float = 1.0) -> np.ndarray:
    """Corners of a cube of edge ``size`` centred at the origin, turned by ``angle`` about ``axis``.

    Exactly a parallelepiped: its three half-edge vectors are rounded to multiples of
    ``2**(floor(log2(size)) - 20)`` and each corner is their signed sum, so the corners are
    dyadic and every face stays exactly planar on a cspace grid (6 facets). Rounding each
    corner of a truly rotated cube separately would make its squares non-planar after
    snapping (12 triangle facets). The edges are orthogonal and of length ``size`` to within
    about ``1e-6 * size``.
    """
    from scipy.spatial.transform import Rotation

    axis = np.asarray(axis, dtype=np.float64)
    R = Rotation.from_rotvec(axis / np.linalg.norm(axis) * float(angle)).as_matrix()
    quantum = 2.0 ** (np.floor(np.log2(float(size))) - 20)
    half = np.round(R.T * (float(size) / 2) / quantum) * quantum  # rows: rotated half edges
    signs = np.array(list(itertools.product((-1.0, 1.0), repeat=3)))
    return signs @ half
