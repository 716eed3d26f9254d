"""Mesh files as planners read them: vertices in the frame the file means, and OMPL.app's centre.

:func:`read_mesh_file` returns a :class:`MeshFile`: ``(n, 3) float64`` vertices, ``(m, 3)
int64`` triangles, and the point OMPL.app moves a robot by (:attr:`MeshFile.assimp_centre`).
Nothing is welded across different positions, repaired or oriented here (:mod:`cspace.mesh`
and :mod:`cspace.scene.model` do that later, exactly).

Formats
-------
``.dae`` (Collada)
    Read with pycollada and placed the way Assimp's Collada importer places it (OMPL.app
    reads meshes through Assimp and sets none of its Collada options): a vertex ``v`` of a
    geometry instanced under the node chain ``n1 > n2 > ... > nk`` of the file's scene goes to
    ``S @ U @ T(n1) @ ... @ T(nk) @ v``, where ``T(n)`` composes the node's ``<matrix>``,
    ``<translate>``, ``<rotate>`` (degrees), ``<scale>`` and ``<lookat>`` elements in document
    order (``<skew>`` is ignored, as Assimp does), ``S`` scales by ``<unit meter=...>``
    (default 1) and ``U`` turns the file's up axis to +y: ``Z_UP`` maps ``(x, y, z)`` to
    ``(x, z, -y)``, ``X_UP`` maps it to ``(-y, x, z)``, ``Y_UP`` (the default) is the identity.
    Numbers are parsed as float32, as both pycollada and Assimp (``ai_real``) parse them;
    the transforms are then composed and applied in float64. ``<triangles>``,
    ``<polylist>`` and ``<polygons>`` (fan-triangulated) give triangles; ``<lines>`` add only
    to the centre. Instanced geometry appears once per instance.
``.g`` (Movie.BYU)
    Vertices as listed, polygons triangulated as fans (header ``nparts nverts npolys nconn``,
    the parts' polygon ranges, the vertices, then 1-based indices, a negative one closing a
    polygon).
anything else
    trimesh with ``process=False`` (OBJ, STL, PLY, OFF, GLB, ...).

OMPL.app's centre
-----------------
OMPL.app plans the position of a robot's *centre*: ``sceneCenter`` in its
``geometry/detail/assimpUtil.cpp``, the mean over every vertex of every mesh Assimp returns,
node transforms applied. Assimp makes one mesh per Collada primitive, one vertex per face
corner, and (``aiProcess_JoinIdenticalVertices``) keeps one per distinct (position, normal,
texture coordinates) within a mesh; faces without normals in the file get their face normal
(``aiProcess_GenNormals``). :attr:`MeshFile.assimp_centre` reproduces that rule: per
primitive, the distinct rows of (position, normal, texture coordinates) compared exactly,
the normal being the file's or else the face's (rounded to float32), then the mean of their
transformed positions over all primitives and instances. Files read by trimesh count as one
mesh without normals: the distinct (position, face normal) corners. It is not the mean of
the distinct positions: on OMPL.app's robots the two differ by up to 5 units.
"""

from __future__ import annotations

import re
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from ..geometry.polygon import fan_triangles
from ..errors import MeshFileError, MeshFileNotFoundError
from ..geometry.transform import axis_angle_degrees, transform

__all__ = ["MeshFile", "read_mesh_file", "UP_AXIS_MATRICES"]

#: Assimp's Collada up-axis correction (``ColladaLoader::InternReadFile``), acting on columns.
UP_AXIS_MATRICES = {
    "Y_UP": np.eye(3),
    "Z_UP": np.array([[1.0, 0.0, 0.0], [0.0, 0.0, 1.0], [0.0, -1.0, 0.0]]),
    "X_UP": np.array([[0.0, -1.0, 0.0], [1.0, 0.0, 0.0], [0.0, 0.0, 1.0]]),
}


@dataclass(frozen=True, eq=False)
class MeshFile:
    """A triangle mesh read from a file, in the frame the file means.

    Attributes
    ----------
    vertices : (n, 3) float64
        File units times the Collada unit scale, Collada up axis turned to +y.
    faces : (m, 3) int64
        Triangles in the file's order and winding.
    assimp_centre : (3,) float64
        The point OMPL.app moves the mesh by when it is a robot (see the module docstring).
    path : Path
    """

    vertices: np.ndarray
    faces: np.ndarray
    assimp_centre: np.ndarray
    path: Path

    def __repr__(self) -> str:
        return (f"MeshFile('{self.path.name}', vertices={len(self.vertices)}, "
                f"faces={len(self.faces)}, assimp_centre={self.assimp_centre.tolist()})")


def read_mesh_file(path, where: str = "") -> MeshFile:
    """Read a mesh file: ``.dae`` as Assimp places it, ``.g`` (BYU), else through trimesh.

    Parameters
    ----------
    path : str or os.PathLike
    where : str
        Prefix of error messages (the scene file and key that named the mesh).

    Returns
    -------
    MeshFile

    Raises
    ------
    MeshFileError
        The file is missing, unreadable, holds no triangles, or has a non-finite vertex; the
        message names the file (and the line, for BYU). A :class:`~cspace.errors.SceneError`
        and an :class:`~cspace.errors.InvalidMeshError`.
    """
    path = Path(path)
    where = where or str(path)
    if not path.is_file():
        raise MeshFileNotFoundError(f"{where}: mesh file not found: '{path}'")
    suffix = path.suffix.lower()
    if suffix == ".dae":
        vertices, faces, centre = _read_collada(path, where)
    else:
        if suffix == ".g":
            vertices, faces = _read_byu(path)
        else:
            vertices, faces = _read_trimesh(path, where)
        centre = None
    if len(faces) == 0 or len(vertices) == 0:
        raise MeshFileError(f"{where}: '{path}' holds no triangles")
    vertices, faces = np.asarray(vertices), np.asarray(faces)
    if vertices.ndim != 2 or vertices.shape[1] != 3:
        raise MeshFileError(f"{where}: '{path}': vertices are not 3D points (read as "
                            f"shape {tuple(vertices.shape)})")
    if faces.ndim != 2 or faces.shape[1] != 3 or faces.min() < 0 or faces.max() >= len(vertices):
        raise MeshFileError(f"{where}: '{path}': faces are not triangles of its "
                            f"{len(vertices)} vertices (indices {int(faces.min())} to "
                            f"{int(faces.max())}, shape {tuple(faces.shape)})")
    if not np.isfinite(vertices).all():
        row = int(np.argmin(np.isfinite(vertices).all(axis=1)))
        raise MeshFileError(f"{where}: '{path}': vertex {row} is not finite: "
                         f"{vertices[row].tolist()}")
    if centre is None:
        total, count = _corner_centre(vertices[faces], None, ())
        centre = total / count
    return MeshFile(vertices, faces, np.asarray(centre, dtype=np.float64), path)


# --------------------------------------------------------------------------------------
# trimesh


def _read_trimesh(path: Path, where: str) -> tuple[np.ndarray, np.ndarray]:
    import trimesh

    try:
        loaded = trimesh.load(str(path), force="mesh", process=False)
        vertices = np.array(loaded.vertices, dtype=np.float64).reshape(-1, 3)
        faces = np.array(loaded.faces, dtype=np.int64)
    except ImportError as exc:  # trimesh guessing the encoding of undecodable text
        raise MeshFileError(
            f"{where}: '{path}' is not a {path.suffix or 'mesh'} file trimesh can decode "
            f"(binary data, or a text encoding it cannot guess: {exc})") from exc
    except Exception as exc:  # noqa: BLE001 - trimesh raises many kinds
        raise MeshFileError(
            f"{where}: trimesh cannot read '{path}' as a triangle mesh: "
            f"{type(exc).__name__}: {exc}"
        ) from exc
    if faces.ndim != 2 or faces.shape[1] != 3:
        raise MeshFileError(f"{where}: '{path}' holds no triangles")
    return vertices, faces


# --------------------------------------------------------------------------------------
# OMPL.app's centre


def _face_normals32(corners: np.ndarray) -> np.ndarray:
    """Unit face normals of ``(m, 3, 3)`` triangles, rounded to float32 (Assimp's precision)."""
    n = np.cross(corners[:, 1] - corners[:, 0], corners[:, 2] - corners[:, 0])
    length = np.linalg.norm(n, axis=1, keepdims=True)
    with np.errstate(invalid="ignore", divide="ignore"):
        n = np.where(length > 0.0, n / length, 0.0)
    return n.astype(np.float32).astype(np.float64)


def _corner_centre(corners: np.ndarray, normals, texcoords, matrix=None) -> tuple[np.ndarray, int]:
    """Sum and count of the distinct corners of one Assimp mesh, positions transformed.

    ``corners`` is ``(m, k, 3)`` (k = 3 for triangles, 2 for lines); ``normals`` the same
    shape or None (face normals then, for triangles); ``texcoords`` a tuple of ``(m, k, d)``.
    """
    m, k = corners.shape[:2]
    if normals is None:
        normals = (np.repeat(_face_normals32(corners)[:, None], k, axis=1) if k == 3
                   else np.zeros_like(corners))
    columns = [corners, normals] + list(texcoords)
    rows = np.concatenate([c.reshape(m * k, -1) for c in columns], axis=1)
    distinct = np.unique(rows, axis=0)[:, :3]
    if matrix is not None:
        distinct = transform(distinct, matrix[:3, :3], matrix[:3, 3])
    return distinct.sum(axis=0), len(distinct)


# --------------------------------------------------------------------------------------
# Collada


def _node_matrix(node) -> np.ndarray:
    """The node's local 4x4 transform: its transform elements composed in document order."""
    from collada import scene as cs

    out = np.eye(4)
    for t in node.transforms:
        m = np.eye(4)
        if isinstance(t, cs.TranslateTransform):
            m[:3, 3] = [t.x, t.y, t.z]
        elif isinstance(t, cs.ScaleTransform):
            m[:3, :3] = np.diag([t.x, t.y, t.z])
        elif isinstance(t, cs.RotateTransform):
            m[:3, :3] = axis_angle_degrees([t.x, t.y, t.z], float(t.angle))
        elif isinstance(t, cs.LookAtTransform):
            eye = np.asarray(t.eye, dtype=np.float64)
            up = np.asarray(t.upvector, dtype=np.float64)
            up = up / np.linalg.norm(up)
            direction = np.asarray(t.interest, dtype=np.float64) - eye
            direction = direction / np.linalg.norm(direction)
            right = np.cross(direction, up)
            right = right / np.linalg.norm(right)
            m[:3, 0], m[:3, 1], m[:3, 2], m[:3, 3] = right, up, -direction, eye
        elif isinstance(t, cs.MatrixTransform):
            m = np.asarray(t.matrix, dtype=np.float64).reshape(4, 4)
        out = out @ m
    return out


def _instances(nodes, matrix: np.ndarray, depth: int = 0):
    """``(geometry, world matrix)`` for every geometry instance below ``nodes``."""
    from collada import scene as cs

    if depth > 256:
        raise ValueError("node instances nest more than 256 deep (a cycle?)")
    for node in nodes:
        if isinstance(node, cs.GeometryNode):
            yield node.geometry, matrix
        elif isinstance(node, cs.NodeNode):
            yield from _instances([node.node], matrix, depth + 1)
        elif isinstance(node, cs.Node):
            yield from _instances(node.children, matrix @ _node_matrix(node), depth + 1)


def _read_collada(path: Path, where: str):
    try:
        import collada
        from collada import lineset, polylist, triangleset
    except ImportError as exc:  # a dependency: only a broken install gets here
        raise MeshFileError(f"{where}: reading '{path}' needs pycollada ({exc})") from exc
    try:
        dae = collada.Collada(str(path), ignore=[collada.common.DaeUnsupportedError,
                                                 collada.common.DaeBrokenRefError])
        if dae.scene is None:
            raise ValueError("the file has no <scene> to instance")
        up = str(getattr(dae.assetInfo, "upaxis", None) or "Y_UP").strip().upper()
        unit = getattr(dae.assetInfo, "unitmeter", None)
        unit = 1.0 if unit is None else float(np.float32(unit))
        if up not in UP_AXIS_MATRICES:
            up = "Y_UP"  # Assimp treats anything else as Y_UP
        root = np.eye(4)
        root[:3, :3] = unit * UP_AXIS_MATRICES[up]
        vertices, total, count = [], np.zeros(3), 0
        for geometry, matrix in _instances(dae.scene.nodes, root):
            for prim in geometry.primitives:
                if isinstance(prim, polylist.Polylist):
                    prim = prim.triangleset()
                if isinstance(prim, triangleset.TriangleSet):
                    index = np.asarray(prim.vertex_index, dtype=np.int64).reshape(-1, 3)
                elif isinstance(prim, lineset.LineSet):
                    index = np.asarray(prim.vertex_index, dtype=np.int64).reshape(-1, 2)
                else:
                    continue
                if not len(index):
                    continue
                corners = np.asarray(prim.vertex, dtype=np.float64)[index]
                normals = None
                if getattr(prim, "normal_index", None) is not None and prim.normal is not None:
                    normal_index = np.asarray(prim.normal_index, dtype=np.int64)
                    normals = np.asarray(prim.normal, dtype=np.float64)[
                        normal_index.reshape(index.shape)]
                tex = tuple(
                    np.asarray(t, dtype=np.float64)[np.asarray(i, dtype=np.int64).reshape(
                        index.shape)]
                    for t, i in zip(getattr(prim, "texcoordset", ()) or (),
                                    getattr(prim, "texcoord_indexset", ()) or ()))
                s, n = _corner_centre(corners, normals, tex, matrix)
                total, count = total + s, count + n
                if index.shape[1] == 3:
                    flat = corners.reshape(-1, 3)
                    vertices.append(transform(flat, matrix[:3, :3], matrix[:3, 3]))
    except MeshFileError:
        raise
    except Exception as exc:  # noqa: BLE001 - pycollada and lxml raise many kinds
        raise MeshFileError(f"{where}: cannot read '{path}' as Collada: "
                         f"{type(exc).__name__}: {exc}") from exc
    if not vertices:
        raise MeshFileError(f"{where}: '{path}' holds no triangles in its scene")
    corners = np.concatenate(vertices) + 0.0
    # One row per distinct position (exact equality only): compact, nothing moved.
    unique, inverse = np.unique(corners, axis=0, return_inverse=True)
    return unique, inverse.reshape(-1, 3).astype(np.int64), total / count


# --------------------------------------------------------------------------------------
# Movie.BYU


def _read_byu(path: Path) -> tuple[np.ndarray, np.ndarray]:
    """A Movie.BYU ``.g`` file: vertices as listed, polygons triangulated as fans."""
    tokens, lines = [], []
    for number, line in enumerate(path.read_text(errors="replace").splitlines(), 1):
        words = line.split()
        tokens += words
        lines += [number] * len(words)

    def fail(i: int, message: str) -> MeshFileError:
        line = lines[min(i, len(lines) - 1)] if lines else 1
        return MeshFileError(f"{path}:{line}: {message}")

    def ints(start: int, count: int, what: str) -> np.ndarray:
        chunk = tokens[start:start + count]
        try:
            return np.array([int(t) for t in chunk], dtype=np.int64)
        except ValueError:
            bad = next(k for k, t in enumerate(chunk) if not re.fullmatch(r"[+-]?\d+", t))
            raise fail(start + bad, f"expected an integer ({what}), got {chunk[bad]!r}") from None

    if len(tokens) < 4:
        raise fail(0, "BYU header 'nparts nverts npolys nconn' is missing")
    nparts, nverts, npolys, nconn = ints(0, 4, "BYU header").tolist()
    if min(nparts, nverts, npolys, nconn) <= 0:
        raise fail(0, f"BYU header counts must be positive, got {nparts} {nverts} {npolys} {nconn}")
    first_vertex = 4 + 2 * nparts
    first_index = first_vertex + 3 * nverts
    need = first_index + nconn
    if len(tokens) < need:
        raise fail(len(tokens), f"file ends early: the header announces {need} numbers, "
                                f"found {len(tokens)}")
    if len(tokens) > need:
        raise fail(need, f"unexpected data after the {nconn} vertex indices: {tokens[need]!r}")
    ints(4, 2 * nparts, "part polygon range")
    chunk = tokens[first_vertex:first_index]
    try:
        vertices = np.array([float(t) for t in chunk], dtype=np.float64).reshape(-1, 3)
    except ValueError:
        bad = next(k for k, t in enumerate(chunk) if not _is_float(t))
        message = f"expected a vertex coordinate, got {chunk[bad]!r}"
        raise fail(first_vertex + bad, message) from None
    if not np.isfinite(vertices).all():
        bad = int(np.argmin(np.isfinite(vertices).ravel()))
        raise fail(first_vertex + bad, f"vertex {bad // 3 + 1} is not finite")
    conn = ints(first_index, nconn, "vertex index")
    bad = np.flatnonzero((conn == 0) | (np.abs(conn) > nverts))
    if len(bad):
        raise fail(first_index + int(bad[0]),
                   f"vertex index {int(conn[bad[0]])} is out of range 1..{nverts}")
    if conn[-1] > 0:
        raise fail(need - 1, "the last polygon is not closed (its last index must be negative)")
    offsets = np.r_[0, np.flatnonzero(conn < 0) + 1]
    if len(offsets) - 1 != npolys:
        raise fail(first_index, f"the header announces {npolys} polygons, the indices "
                                f"give {len(offsets) - 1}")
    degree = np.diff(offsets)
    if (degree < 3).any():
        k = int(np.argmax(degree < 3))
        raise fail(first_index + int(offsets[k]), f"polygon {k + 1} has {int(degree[k])} "
                                                  "vertices (at least 3 needed)")
    faces, _ = fan_triangles(offsets.astype(np.int64), np.abs(conn) - 1)
    return vertices, faces



def _is_float(text: str) -> bool:
    try:
        float(text)
    except ValueError:
        return False
    return True
