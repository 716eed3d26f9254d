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
from fractions import Fraction
from pathlib import Path
from typing import NamedTuple

import numpy as np

__all__ = [
    "voxel_solid",
    "l_shape",
    "comb",
    "grate",
    "genus3",
    "cup",
    "hollow_box",
    "thin_feature",
    "pierced_box",
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
    "scaled_robots",
    "box_points",
    "icosphere_points",
    "hull20",
    "cube_rotated",
    "voxel_defects",
    "comb_occupancy",
    "grate_occupancy",
    "genus3_occupancy",
    "cup_occupancy",
    "hollow_box_occupancy",
    "stairs_occupancy",
    "SpecialCase",
    "SPECIAL_CASES",
    "double_vertex",
    "nonmanifold_edge",
    "tangent_facets",
    "one_hole",
    "two_holes",
    "genus_change",
    "genus_kept",
    "coplanar_conjoint",
    "opposite_conjoint",
    "torus_icosphere",
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


def voxel_defects(pad: np.ndarray) -> tuple[list[np.ndarray], np.ndarray]:
    """Where the boundary of a padded occupancy is not a 2-manifold.

    Returns ``edges``: for each axis a bool array over the lattice edges along that axis
    (indexed by the 2x2 block of cells around the edge, shape ``pad.shape - 1`` in the
    other two axes), True where two cells touch only along the edge (a checkerboard);
    and ``vertices``: bool over the lattice vertices (the 2x2x2 block of cells around each,
    shape ``pad.shape - 1``), True where the vertex's neighbourhood is not one disc.
    Lattice vertex ``i`` (per axis) is the corner between padded cells ``i`` and ``i + 1``.
    """
    edges = []
    for axis in range(3):
        b, c = [a for a in range(3) if a != axis]

        def cell(db, dc, b=b, c=c):
            sl = [slice(None)] * 3
            sl[b] = slice(db, pad.shape[b] - 1 + db)
            sl[c] = slice(dc, pad.shape[c] - 1 + dc)
            return pad[tuple(sl)]

        x00, x10, x01, x11 = cell(0, 0), cell(1, 0), cell(0, 1), cell(1, 1)
        edges.append((x00 & x11 & ~x10 & ~x01) | (x10 & x01 & ~x00 & ~x11))
    code = np.zeros(tuple(s - 1 for s in pad.shape), dtype=np.int64)
    for dx, dy, dz in itertools.product((0, 1), repeat=3):
        X, Y, Z = pad.shape
        sub = pad[dx : X - 1 + dx, dy : Y - 1 + dy, dz : Z - 1 + dz]
        code |= sub.astype(np.int64) << (4 * dx + 2 * dy + dz)
    return edges, ~_VERTEX_OK[code]


def _check_voxels(pad: np.ndarray) -> None:
    """Raise ValueError if the boundary of the padded occupancy is not a 2-manifold."""
    edges, vertices = voxel_defects(pad)
    # Edges: around every lattice edge the four cells must not be a checkerboard (two
    # cells sharing only that edge).
    for axis, bad in enumerate(edges):
        if bad.any():
            idx = np.argwhere(bad)[0]
            raise ValueError(
                f"voxel set is not a 2-manifold: {int(bad.sum())} lattice edges along axis "
                f"{'xyz'[axis]} have two voxels touching only along the edge, first near "
                f"voxel {tuple(int(i) - 1 for i in idx)}"
            )
    # Vertices: the 2x2x2 block around every lattice vertex.
    if vertices.any():
        idx = np.argwhere(vertices)[0]
        raise ValueError(
            f"voxel set is not a 2-manifold: {int(vertices.sum())} lattice vertices where voxels "
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


def comb_occupancy(teeth: int = 5, length: int = 2) -> np.ndarray:
    """The voxels of :func:`comb` (for :func:`voxel_solid`; unit voxels at the origin)."""
    occ = np.zeros((2 * teeth - 1, 1 + length, 1), dtype=bool)
    occ[:, 0, 0] = True
    occ[::2, 1:, 0] = True
    return occ


def comb(teeth: int = 5, length: int = 2) -> Mesh:
    """A bar of ``2*teeth - 1`` voxels along x with ``teeth`` teeth of ``length`` voxels along +y.

    Defaults: 156 triangles; slots 1 voxel wide between the teeth.
    """
    return voxel_solid(comb_occupancy(teeth, length))


def grate_occupancy(n: int = 3) -> np.ndarray:
    """The voxels of :func:`grate` (for :func:`voxel_solid`; unit voxels at the origin)."""
    occ = np.ones((2 * n + 1, 2 * n + 1, 1), dtype=bool)
    occ[1::2, 1::2, :] = False
    return occ


def grate(n: int = 3) -> Mesh:
    """A flat ``(2n+1) x (2n+1) x 1`` frame with ``n x n`` square through-holes: genus ``n*n``."""
    return voxel_solid(grate_occupancy(n))


def genus3_occupancy() -> np.ndarray:
    """The voxels of :func:`genus3` (for :func:`voxel_solid`; unit voxels at the origin)."""
    occ = np.ones((7, 3, 1), dtype=bool)
    occ[1::2, 1, :] = False
    return occ


def genus3() -> Mesh:
    """A ``7 x 3 x 1`` plate with 3 through-holes in a row: genus 3."""
    return voxel_solid(genus3_occupancy())


def cup_occupancy() -> np.ndarray:
    """The voxels of :func:`cup` (for :func:`voxel_solid`; unit voxels at the origin)."""
    occ = np.ones((3, 3, 3), dtype=bool)
    occ[1, 1, 1:] = False
    return occ


def cup() -> Mesh:
    """A ``3 x 3 x 3`` box with a ``1 x 1 x 2`` well open at the top.

    Genus 0; the well is not a closed cavity (see :func:`hollow_box` for one).
    """
    return voxel_solid(cup_occupancy())


def hollow_box_occupancy() -> np.ndarray:
    """The voxels of :func:`hollow_box` (for :func:`voxel_solid`; unit voxels at the origin)."""
    occ = np.ones((3, 3, 3), dtype=bool)
    occ[1, 1, 1] = False
    return occ


def hollow_box() -> Mesh:
    """A ``3 x 3 x 3`` box with its centre voxel empty: an outer shell and a closed cavity.

    Two components (Euler characteristic 4); the cavity shell is wound inwards.
    """
    return voxel_solid(hollow_box_occupancy())


def stairs_occupancy(steps: int = 5, width: int = 3) -> np.ndarray:
    """The voxels of :func:`stairs` (for :func:`voxel_solid`; unit voxels at the origin)."""
    occ = np.zeros((steps, width, steps), dtype=bool)
    for i in range(steps):
        occ[i, :, : i + 1] = True
    return occ


def stairs(steps: int = 5, width: int = 3) -> Mesh:
    """A staircase: column ``i`` (along x) is ``i + 1`` voxels high, ``width`` voxels deep in y.

    Many coplanar adjacent faces (each unit square is its own pair of triangles).
    """
    return voxel_solid(stairs_occupancy(steps, width))


# --------------------------------------------------------------------------------------
# smooth and star-shaped meshes


def thin_feature(kind: str, t: float):
    """A trimesh of a feature ``t`` thick, about a unit box at the origin: needle (a
    triangular prism along x), plate (y thin, out through two faces), cut (a plate through
    the whole box: it parts the box in two halves joined only through the plate), fin (z
    thin), wedge (a ridge of height t). For :func:`pierced_box` and issue #51's tests."""
    import trimesh

    if kind == "needle":
        sec = np.array([[0, 0, 0], [0, t, 0], [0, 0.5 * t, 0.8 * t]]) + [0, 0.05, 0.1]
        V = np.vstack([sec - [1, 0, 0], sec + [1, 0, 0]])
        F = [[0, 2, 1], [3, 4, 5], [0, 1, 4], [0, 4, 3], [1, 2, 5], [1, 5, 4], [2, 0, 3],
             [2, 3, 5]]
        m = trimesh.Trimesh(V, F, process=False)
        m.fix_normals()
        return m
    if kind == "plate":
        return trimesh.creation.box((2, t, 0.5))
    if kind == "cut":
        return trimesh.creation.box((2, t, 1.6))
    if kind == "fin":
        return trimesh.creation.box((2, 0.3, t)).apply_translation([0, 0, 0.2])
    if kind == "wedge":
        V = np.array([[-1, 0, 0], [1, 0, 0], [1, 0.4, 0], [-1, 0.4, 0], [-1, 0.2, t],
                      [1, 0.2, t]], dtype=float)
        F = [[0, 2, 1], [0, 3, 2], [0, 1, 5], [0, 5, 4], [3, 4, 5], [3, 5, 2], [0, 4, 3],
             [1, 2, 5]]
        m = trimesh.Trimesh(V, F, process=False)
        m.fix_normals()
        return m
    raise ValueError(kind)


def pierced_box(kind: str, t: float) -> Mesh:
    """A unit box united with :func:`thin_feature` ``kind``, ``t`` thick: a feature 1e-3 thick
    united by manifold (whose float32 output would drop a thinner one), then the feature's own
    vertices squeezed towards its mid-plane or axis to ``t``, so that the box's faces keep the
    (now tiny) holes it pierces. A closed, oriented 2-manifold in floats; on a grid coarser
    than ``t`` it snaps to a box with segments, sheets or parted halves (issue #51)."""
    import trimesh

    f = thin_feature(kind, 1e-3)
    A = trimesh.boolean.union([trimesh.creation.box((1, 1, 1)), f], engine="manifold")
    V = np.asarray(A.vertices, dtype=np.float64).copy()
    lo, hi = f.bounds
    near = ((V >= lo - 1e-6) & (V <= hi + 1e-6)).all(axis=1)  # manifold's output is float32
    axes = {"needle": [1, 2], "plate": [1], "cut": [1], "fin": [2], "wedge": [2]}[kind]
    mid = lo if kind == "wedge" else (lo + hi) / 2
    for a in axes:
        V[near, a] = mid[a] + (V[near, a] - mid[a]) * (t / 1e-3)
    return V, np.asarray(A.faces, dtype=np.int64)


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


def scaled_robots(extent: float) -> dict[str, np.ndarray]:
    """The benchmark robots for a mesh of the given extent: a box, a 20-facet hull and a
    320-facet icosphere, each about 8% of ``extent`` across (as in bench_superset)."""
    s = 0.08 * float(extent)
    return {
        "box": box_points(s, 0.8 * s, 0.6 * s),
        "hull20": hull20(0, scale=(s / 2, 0.35 * s, 0.25 * s)),
        "ico320": icosphere_points(2, radius=s / 2),
    }


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


# --------------------------------------------------------------------------------------
# the NCC-CVMS paper's special cases (section 3.3 non-manifold situations, 3.4 holes)
#
# Each returns a SpecialCase: A (a closed, outward, one-component 2-manifold unless said
# otherwise), B (points; the sum is A ⊕ B, the robot of the C-obstacle is -B), and the
# expected exact properties of A ⊕ B derived by hand. For voxel solids with an axis box B,
# ``occupancy`` (unit voxels at the origin, as in :func:`voxel_solid`) lets
# ``oracles.voxel_box_sum`` recompute every expectation exactly: with B = [-h, h]^3 each
# voxel [v, v + 1] becomes the cube [v - h, v + 1 + h], and two such cubes of voxels whose
# indices differ by d overlap along an axis iff |d| < 1 + 2h there, touch iff |d| = 1 + 2h.


class SpecialCase(NamedTuple):
    """A special input pair and what its exact Minkowski sum must show.

    vertices, faces : A
    b : (k, 3) float64
        Points of B (its hull); the sum is ``A ⊕ B``.
    occupancy : (X, Y, Z) bool or None
        A's voxels when A is a voxel solid and B an axis box (for ``oracles.voxel_box_sum``).
    expected : dict
        Hand-derived properties of the exact sum: ``n_holes``, ``euler`` (Euler
        characteristic ``V - E + F`` of the whole boundary surface, an edge shared by four
        faces counted once: ``oracles.complex_euler``), ``manifold`` (bool),
        ``nonmanifold_length`` (total length of edges where the solid touches itself along
        an edge), ``pinch`` ((k, 3) double vertices), ``volume`` (Fraction) when known.
    """

    vertices: np.ndarray
    faces: np.ndarray
    b: np.ndarray
    occupancy: np.ndarray | None
    expected: dict


def _cells(shape, cells) -> np.ndarray:
    occ = np.zeros(shape, dtype=bool)
    for c in cells:
        occ[c] = True
    return occ


def _voxel_case(occ, b, **expected) -> SpecialCase:
    v, f = voxel_solid(occ)
    return SpecialCase(v, f, np.asarray(b, dtype=np.float64), occ, expected)


def double_vertex() -> SpecialCase:
    """A ring of voxels whose two ends, voxels (1,1,1) and (3,3,3), sum to cubes touching at one point.

    A: 11 unit voxels, one component, genus 0: the ends joined by a path
    (1,1,0)-(4,1,0)-(4,1,3)-(4,3,3) that stays outside the block {1,2,3}^3 (only voxels
    in that block can reach the contact). B: the unit cube centred at the origin (h = 1/2),
    so the end cubes [0.5, 2.5]^3 and [2.5, 4.5]^3 share only the corner (2.5, 2.5, 2.5).

    Exhibits the paper's non-manifold situation (1), double vertices. Exact sum: one pinch
    vertex at (2.5, 2.5, 2.5) and no other defect; no hole; the boundary is a sphere with two
    points identified, Euler characteristic 2 - 1 = 1; volume 48.
    """
    path = [(1, 1, 0), (2, 1, 0), (3, 1, 0), (4, 1, 0), (4, 1, 1), (4, 1, 2), (4, 1, 3),
            (4, 2, 3), (4, 3, 3)]
    occ = _cells((5, 5, 5), [(1, 1, 1), (3, 3, 3)] + path)
    return _voxel_case(
        occ, box_points(1.0, 1.0, 1.0), n_holes=0, euler=1, manifold=False,
        nonmanifold_length=0, pinch=np.array([[2.5, 2.5, 2.5]]), volume=48,
    )


def nonmanifold_edge() -> SpecialCase:
    """A flat ring of voxels whose ends (1,1,1) and (3,3,1) sum to cubes touching along an edge.

    A: 9 voxels in the layer z = 1, one component, genus 0: the ends joined by
    (1,0)-(4,0)-(4,3) around the empty 3x3 block; B: the unit cube centred at the origin.
    The end cubes [0.5, 2.5]^2 and [2.5, 4.5]^2 (both z in [0.5, 2.5]) touch along the
    segment x = y = 2.5, z in [0.5, 2.5], and no other voxel's cube reaches it.

    Exhibits situation (4), an edge with four incident faces. Exact sum: one non-manifold
    edge of length 2 (its two end vertices are non-manifold too), no hole, no pinch; the
    solid is a C closed through the edge: its boundary is a sphere with two arcs identified,
    Euler characteristic 2 - 1 = 1 (counting the shared edge once); volume 40.
    """
    ring = [(1, 0, 1), (2, 0, 1), (3, 0, 1), (4, 0, 1), (4, 1, 1), (4, 2, 1), (4, 3, 1)]
    occ = _cells((5, 5, 3), [(1, 1, 1), (3, 3, 1)] + ring)
    return _voxel_case(
        occ, box_points(1.0, 1.0, 1.0), n_holes=0, euler=1, manifold=False,
        nonmanifold_length=2, pinch=np.zeros((0, 3)), volume=40,
    )


def tangent_facets() -> SpecialCase:
    """Two ends of a voxel ring whose sums touch along a face region (facets touching tangentially).

    A: 8 voxels in the layer z = 1, ends (1,1,1) and (3,2,1) joined by (1,0)-(4,0)-(4,2);
    B: the unit cube centred at the origin. The end cubes [0.5, 2.5] x [0.5, 2.5] and
    [2.5, 4.5] x [1.5, 3.5] (z in [0.5, 2.5]) touch in the rectangle x = 2.5,
    y in [1.5, 2.5], z in [0.5, 2.5]: their translated facets there are opposite conjoint
    (situation (6), and (5) along the rim).

    Exact sum: the contact rectangle is interior to the union (the wall vanishes: no face of
    the result lies in it; its centre (2.5, 2, 1.5) is at depth 0.5 from the boundary), the
    rim edges are ordinary reflex edges, and the inside of the ring is filled too: a
    manifold genus-0 solid (Euler characteristic 2), no hole, volume 36.
    """
    ring = [(1, 0, 1), (2, 0, 1), (3, 0, 1), (4, 0, 1), (4, 1, 1), (4, 2, 1)]
    occ = _cells((5, 5, 3), [(1, 1, 1), (3, 2, 1)] + ring)
    return _voxel_case(
        occ, box_points(1.0, 1.0, 1.0), n_holes=0, euler=2, manifold=True,
        nonmanifold_length=0, pinch=np.zeros((0, 3)), volume=36,
        interior_points=np.array([[2.5, 2.0, 1.5]]), interior_depth=0.5,
    )


def _bottle(shape, cavities) -> np.ndarray:
    """A solid block with 3x3x3 cavities at the given corner voxels, each opened to the top
    by a 1x1 channel above its centre."""
    occ = np.ones(shape, dtype=bool)
    for x, y, z in cavities:
        occ[x : x + 3, y : y + 3, z : z + 3] = False
        occ[x + 1, y + 1, z + 3 :] = False
    return occ


def one_hole() -> SpecialCase:
    """A 5x5x5 bottle: a 3x3x3 cavity opened by a 1x1 channel, and a robot (a 2-cube) that
    fits the cavity but not the channel.

    A: one component, genus 0 (the cavity is connected to the outside). B: the cube of edge 2
    centred at the origin (h = 1). The robot's free placements inside are the open cube
    (2, 3)^3 (1 away from every cavity wall), cut off from the outside because the channel
    (width 1 < 2) is closed by the neighbouring voxels' cubes.

    Exhibits section 3.4, a polyhedral hole not reachable from the outer boundary. Exact sum:
    the cube [-1, 6]^3 minus the hole [2, 3]^3: n_holes 1 (the hole shell is a sphere:
    Euler characteristic 2 + 2 = 4), manifold, volume 7^3 - 1 = 342.
    """
    return _voxel_case(
        _bottle((5, 5, 5), [(1, 1, 1)]), box_points(2.0, 2.0, 2.0), n_holes=1, euler=4,
        manifold=True, nonmanifold_length=0, pinch=np.zeros((0, 3)), volume=342,
        hole_points=np.array([[2.5, 2.5, 2.5]]),
    )


def two_holes() -> SpecialCase:
    """A 5x9x5 bottle with two cavities (y in [1, 4] and [5, 8]), each with its own 1x1
    channel, and the same 2-cube robot as :func:`one_hole`.

    Exact sum: the box [-1, 6] x [-1, 10] x [-1, 6] minus the holes [2, 3]^3 and
    [2, 3] x [6, 7] x [2, 3]: n_holes 2, Euler characteristic 6, manifold,
    volume 7 * 11 * 7 - 2 = 537.
    """
    return _voxel_case(
        _bottle((5, 9, 5), [(1, 1, 1), (1, 5, 1)]), box_points(2.0, 2.0, 2.0), n_holes=2,
        euler=6, manifold=True, nonmanifold_length=0, pinch=np.zeros((0, 3)), volume=537,
        hole_points=np.array([[2.5, 2.5, 2.5], [2.5, 6.5, 2.5]]),
    )


def genus_change() -> SpecialCase:
    """The genus-3 plate (:func:`genus3`) and a box wider than its holes: the sum has genus 0.

    B: the box [-0.75, 0.75]^2 x [-0.25, 0.25]. Each hole is a unit square between voxels whose
    cubes grow by 0.75 towards it from both sides (1.5 > 1): every hole closes.

    Exhibits the change of genus (section 4.2.1). Exact sum: the box
    [-0.75, 7.75] x [-0.75, 3.75] x [-0.25, 1.25] (volume 8.5 * 4.5 * 1.5 = 57.375 = 459/8),
    manifold, Euler characteristic 2, no hole.
    """
    return _voxel_case(
        genus3_occupancy(), box_points(1.5, 1.5, 0.5), n_holes=0, euler=2, manifold=True,
        nonmanifold_length=0, pinch=np.zeros((0, 3)), volume=Fraction(459, 8),
    )


def genus_kept() -> SpecialCase:
    """The genus-3 plate and a box narrower than its holes (the contrast to genus_change).

    B: the cube of edge 0.5 centred at the origin: each unit hole shrinks to a 0.5 x 0.5
    square. Exact sum: genus 3 (Euler characteristic -4), manifold, no hole, volume
    7.5 * 3.5 * 1.5 - 3 * 0.25 * 1.5 = 153/4.
    """
    return _voxel_case(
        genus3_occupancy(), box_points(0.5, 0.5, 0.5), n_holes=0, euler=-4, manifold=True,
        nonmanifold_length=0, pinch=np.zeros((0, 3)), volume=Fraction(153, 4),
    )


def coplanar_conjoint() -> SpecialCase:
    """A 3-tooth comb (teeth at x in [0,1], [2,3], [4,5]; slots 1 wide) and a box 1.5 wide in x.

    B: [-0.75, 0.75] x [-0.25, 0.25]^2. The top (and bottom) faces of neighbouring teeth
    translated by B's top (bottom) vertices lie in one plane with the same orientation, and
    after the edge and corner facets each covers x in [2i - 0.75, 2i + 1.75]: they overlap
    in strips 0.5 wide over the slots (coplanar conjoint facets, merged by step 2). The slot
    side faces' sums cross each other inside.

    Exact sum: the slots fill (1.5 > 1): the box [-0.75, 5.75] x [-0.25, 3.25] x [-0.25, 1.25],
    volume 6.5 * 3.5 * 1.5 = 273/8, manifold, Euler characteristic 2.
    """
    return _voxel_case(
        comb_occupancy(3, 2), box_points(1.5, 0.5, 0.5), n_holes=0, euler=2, manifold=True,
        nonmanifold_length=0, pinch=np.zeros((0, 3)), volume=Fraction(273, 8),
    )


def opposite_conjoint() -> SpecialCase:
    """The 3-tooth comb and a box exactly as wide as its slots (1 in x).

    B: [-0.5, 0.5] x [-0.25, 0.25]^2. The facing side faces of neighbouring teeth, moved by
    +-0.5, coincide in the planes x = 1.5 and x = 3.5 with opposite orientations (opposite
    conjoint facets, cancelled by the symmetric difference of step 2; situation (6)).

    Exact sum: the slots close exactly; the walls at x = 1.5 and 3.5 are interior (no face
    of the result lies there; the point (1.5, 1.5, 0.5) is at depth 0.75). The box
    [-0.5, 5.5] x [-0.25, 3.25] x [-0.25, 1.25], volume 6 * 3.5 * 1.5 = 63/2, manifold,
    Euler characteristic 2.
    """
    return _voxel_case(
        comb_occupancy(3, 2), box_points(1.0, 0.5, 0.5), n_holes=0, euler=2, manifold=True,
        nonmanifold_length=0, pinch=np.zeros((0, 3)), volume=Fraction(63, 2),
        interior_points=np.array([[1.5, 1.5, 0.5], [3.5, 1.5, 0.5]]), interior_depth=0.75,
    )


def torus_icosphere() -> SpecialCase:
    """The design notes' case: the 2304-triangle torus (major 1, minor 0.35) and a 320-facet
    icosphere of radius 0.3.

    Exhibits edge and corner facets in one plane with opposite orientations (where libigl's
    winding-number trimming of the convolution kept coincident face pairs inside the sum)
    and corner multiplicities +1 x 320 and -1 x 320 at saddle vertices. Exact sum: the
    sphere (radius < 0.3) is smaller than the torus hole (inner radius about 0.65 - 0.3 >
    0), so the sum stays a solid torus: manifold, genus 1 (Euler characteristic 0), no
    hole; volume from the libigl reference only.
    """
    v, f = torus()
    return SpecialCase(v, f, icosphere_points(2, radius=0.3), None, dict(
        n_holes=0, euler=0, manifold=True, nonmanifold_length=0, pinch=np.zeros((0, 3)),
    ))


#: The special cases by name.
SPECIAL_CASES = {
    "double_vertex": double_vertex,
    "nonmanifold_edge": nonmanifold_edge,
    "tangent_facets": tangent_facets,
    "one_hole": one_hole,
    "two_holes": two_holes,
    "genus_change": genus_change,
    "genus_kept": genus_kept,
    "coplanar_conjoint": coplanar_conjoint,
    "opposite_conjoint": opposite_conjoint,
    "torus_icosphere": torus_icosphere,
}


# --------------------------------------------------------------------------------------
# scenes where the robot must turn (tests/test_turning.py, benchmarks/bench_planning.py)


def thin_walled(scene, thickness: float):
    """``scene`` (the piano's: walls across y = 0) with its walls ``thickness`` thick."""
    import dataclasses

    from cspace.scene.scene import Body

    bodies = []
    for b in scene.obstacles:
        V = np.array(b.vertices)
        V[:, 1] = np.sign(V[:, 1]) * thickness / 2
        bodies.append(Body(b.name, V, b.faces, b.source))
    return dataclasses.replace(scene, obstacles=tuple(bodies),
                               name=f"{scene.name}, {thickness * 1000:g} mm wall")


def rod_and_holed_wall():
    """A rod 1.0 long, upright, in front of a wall with a 0.5 x 0.5 hole: it passes only
    tilted along the hole's axis (a turn about x, not about z)."""
    import trimesh

    from cspace.scene.scene import Body, Scene

    def box(lo, hi, name):
        m = trimesh.creation.box(bounds=[lo, hi])
        return Body(name, m.vertices, m.faces, "box")

    h, t = 0.25, 0.05
    walls = (box([-3, -t, -3], [-h, t, 3], "left"), box([h, -t, -3], [3, t, 3], "right"),
             box([-h, -t, -3], [h, t, -h], "below"), box([-h, -t, h], [h, t, 3], "above"))
    rod = trimesh.creation.box(extents=[0.1, 0.1, 1.0])
    return Scene(name="rod through a hole", path=None, obstacles=walls,
                 robot=Body("rod", rod.vertices, rod.faces, "box"), reference_point=np.zeros(3),
                 bounds=np.array([[-1.2, -1.2, -1.2], [1.2, 1.2, 1.2]]),
                 start=np.array([0.0, -0.9, 0.0]), goal=np.array([0.0, 0.9, 0.0]))
