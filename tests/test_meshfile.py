"""Mesh files in the frame the file means: Collada as Assimp places it, and OMPL.app's centre.

The Collada files are written here with pycollada (OMPL.app's own problem files are not
redistributable); coordinates, scales and angles are chosen exactly representable in float32
so that the expected placement is exact and equality is asserted, not closeness.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from cspace.errors import SceneError
from cspace.mesh.files import UP_AXIS_MATRICES, read_mesh_file

collada = pytest.importorskip("collada")  # a core dependency: present on every install
from collada import geometry, material, scene, source  # noqa: E402

TETRA = np.array([[0.0, 0.0, 0.0], [1.5, 0.0, 0.0], [0.0, 2.0, 0.0], [0.25, 0.5, 3.0]])
TETRA_FACES = np.array([[0, 2, 1], [0, 1, 3], [1, 2, 3], [0, 3, 2]])


def _doc(up="Y_UP", unit=None):
    doc = collada.Collada()
    doc.assetInfo.upaxis = up
    if unit is not None:
        doc.assetInfo.unitmeter = unit
        doc.assetInfo.unitname = "u"
    doc.assetInfo.save()
    effect = material.Effect("effect0", [], "phong", diffuse=(1, 0, 0))
    mat = material.Material("material0", "mat", effect)
    doc.effects.append(effect)
    doc.materials.append(mat)
    return doc, mat


def _geometry(doc, name, vertices, faces, normals=None, texcoords=None, polylist=False):
    """A geometry with one primitive; normals/texcoords given per corner ((m, 3, d) arrays)."""
    sources = [source.FloatSource(f"{name}-v", np.asarray(vertices, np.float32).ravel(),
                                  ("X", "Y", "Z"))]
    inputs = source.InputList()
    inputs.addInput(0, "VERTEX", f"#{name}-v")
    columns = [np.asarray(faces).reshape(-1)]
    if normals is not None:
        n = np.asarray(normals, np.float32).reshape(-1, 3)
        sources.append(source.FloatSource(f"{name}-n", n.ravel(), ("X", "Y", "Z")))
        inputs.addInput(len(columns), "NORMAL", f"#{name}-n")
        columns.append(np.arange(len(n)))
    if texcoords is not None:
        t = np.asarray(texcoords, np.float32).reshape(-1, 2)
        sources.append(source.FloatSource(f"{name}-t", t.ravel(), ("S", "T")))
        inputs.addInput(len(columns), "TEXCOORD", f"#{name}-t", set="0")
        columns.append(np.arange(len(t)))
    geom = geometry.Geometry(doc, name, name, sources)
    index = np.stack(columns, axis=1).ravel()
    if polylist:
        prim = geom.createPolylist(index, np.full(len(faces), 3), inputs, "mat")
    else:
        prim = geom.createTriangleSet(index, inputs, "mat")
    geom.primitives.append(prim)
    doc.geometries.append(geom)
    return geom


def _instance(geom, mat):
    return scene.GeometryNode(geom, [scene.MaterialNode("mat", mat, inputs=[])])


def _write(doc, nodes, path):
    s = scene.Scene("scene0", nodes)
    doc.scenes.append(s)
    doc.scene = s
    doc.write(str(path))
    return path


def _corners(mesh):
    """The triangles' corners, (m, 3, 3), in file order."""
    return mesh.vertices[mesh.faces]


def _apply(matrix, points):
    return points @ matrix[:3, :3].T + matrix[:3, 3]


def _outer_inner():
    """Two nested node transforms and the matrices they stand for (exact in float32)."""
    outer = [scene.TranslateTransform(1.0, -2.0, 0.5),
             scene.MatrixTransform(np.array([2, 0, 0, 0.25, 0, 2, 0, 0, 0, 0, 2, -1, 0, 0, 0, 1],
                                            np.float32))]
    inner = [scene.RotateTransform(0.0, 0.0, 1.0, 90.0), scene.ScaleTransform(1.0, 0.5, 4.0)]
    t = np.eye(4)
    t[:3, 3] = [1.0, -2.0, 0.5]
    m = np.array([[2, 0, 0, 0.25], [0, 2, 0, 0], [0, 0, 2, -1], [0, 0, 0, 1]], float)
    rz = np.array([[0, -1, 0, 0], [1, 0, 0, 0], [0, 0, 1, 0], [0, 0, 0, 1]], float)
    sc = np.diag([1.0, 0.5, 4.0, 1.0])
    return outer, inner, t @ m, rz @ sc


@pytest.mark.parametrize("up", ["Y_UP", "Z_UP", "X_UP"])
@pytest.mark.parametrize("unit", [None, 0.25])
@pytest.mark.parametrize("polylist", [False, True])
def test_collada_placement_is_assimps(tmp_path, up, unit, polylist):
    doc, mat = _doc(up, unit)
    geom = _geometry(doc, "tetra", TETRA, TETRA_FACES, polylist=polylist)
    outer, inner, m_outer, m_inner = _outer_inner()
    child = scene.Node("inner", children=[_instance(geom, mat)], transforms=inner)
    path = _write(doc, [scene.Node("outer", children=[child], transforms=outer)],
                  tmp_path / "t.dae")
    mesh = read_mesh_file(path)
    root = np.eye(4)
    root[:3, :3] = (1.0 if unit is None else unit) * UP_AXIS_MATRICES[up]
    expected = _apply(root @ m_outer @ m_inner, TETRA)[TETRA_FACES]
    assert np.array_equal(_corners(mesh), expected)
    # The up-axis rules themselves, as Assimp's ColladaLoader states them.
    x, y, z = 1.0, 2.0, 3.0
    turned = {"Y_UP": [x, y, z], "Z_UP": [x, z, -y], "X_UP": [-y, x, z]}[up]
    assert (UP_AXIS_MATRICES[up] @ [x, y, z]).tolist() == turned


def test_collada_instances_count_once_each(tmp_path):
    # One geometry under two nodes: both placements appear, and both count in the centre.
    doc, mat = _doc("Z_UP")
    geom = _geometry(doc, "tetra", TETRA, TETRA_FACES)
    a = scene.Node("a", children=[_instance(geom, mat)],
                   transforms=[scene.TranslateTransform(8.0, 0.0, 0.0)])
    b = scene.Node("b", children=[_instance(geom, mat)])
    mesh = read_mesh_file(_write(doc, [a, b], tmp_path / "two.dae"))
    up = UP_AXIS_MATRICES["Z_UP"]
    first = (TETRA + [8.0, 0.0, 0.0]) @ up.T
    assert np.array_equal(_corners(mesh), np.concatenate([first[TETRA_FACES],
                                                          (TETRA @ up.T)[TETRA_FACES]]))
    # No normals in the file: each tetra corner has a distinct face normal at each of its
    # three faces, so every one of the 12 corners is an Assimp vertex, per instance.
    corners = np.concatenate([first[TETRA_FACES], (TETRA @ up.T)[TETRA_FACES]]).reshape(-1, 3)
    assert np.allclose(mesh.assimp_centre, corners.mean(axis=0), rtol=0, atol=1e-15)


def test_assimp_centre_rule(tmp_path):
    # Primitive 1: a square as two triangles with one normal given per corner: the four
    # distinct corners count once, the shared diagonal's two are not doubled.
    # Primitive 2: the same positions, but its two triangles face opposite ways and have no
    # normals: their face normals differ, so the diagonal's corners count twice.
    # Primitive 3: a triangle whose corners share a position but not a texture coordinate.
    square = np.array([[0.0, 0, 0], [4, 0, 0], [4, 4, 0], [0, 4, 0]])
    doc, mat = _doc("Y_UP")
    up = np.zeros((2, 3, 3)) + [0.0, 0.0, 1.0]
    g1 = _geometry(doc, "g1", square, np.array([[0, 1, 2], [0, 2, 3]]), normals=up)
    g2 = _geometry(doc, "g2", square, np.array([[0, 1, 2], [0, 3, 2]]))
    tri = np.array([[0.0, 0, 8], [1, 0, 8], [0, 1, 8]])
    uv = np.array([[[0.0, 0.0], [1.0, 0.0], [0.0, 1.0]], [[0.5, 0.5], [1.0, 0.0], [0.0, 1.0]]])
    g3 = _geometry(doc, "g3", tri, np.array([[0, 1, 2], [0, 1, 2]]), texcoords=uv)
    nodes = [scene.Node("n", children=[_instance(g, mat) for g in (g1, g2, g3)])]
    mesh = read_mesh_file(_write(doc, nodes, tmp_path / "c.dae"))
    counted = np.concatenate([square, square, square[[0, 2]], tri, tri[[0]]])
    assert len(counted) == 4 + 6 + 4
    assert np.array_equal(mesh.assimp_centre, counted.mean(axis=0))
    distinct = np.unique(np.concatenate([square, tri]), axis=0).mean(axis=0)
    assert not np.allclose(mesh.assimp_centre, distinct)


def test_trimesh_formats_count_distinct_position_and_face_normal(tmp_path):
    # A square of two coplanar triangles (same normal: 4 corners) next to a fold (the
    # shared edge's corners count once per face normal: +2).
    v = np.array([[0.0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, 0], [0, 0, 1]])
    f = np.array([[0, 1, 2], [0, 2, 3], [0, 4, 1]])
    import trimesh

    trimesh.Trimesh(v, f, process=False).export(tmp_path / "m.obj")
    mesh = read_mesh_file(tmp_path / "m.obj")
    counted = np.concatenate([v[:4], v[[0, 4, 1]]])
    assert np.allclose(mesh.assimp_centre, counted.mean(axis=0), rtol=0, atol=1e-15)


def test_bad_collada_is_a_scene_error(tmp_path):
    (tmp_path / "bad.dae").write_text("<COLLADA><broken")
    with pytest.raises(SceneError, match=r"cannot read '.*bad\.dae' as Collada"):
        read_mesh_file(tmp_path / "bad.dae")
    doc, _ = _doc()
    with pytest.raises(SceneError, match="holds no triangles"):
        read_mesh_file(_write(doc, [scene.Node("empty")], tmp_path / "empty.dae"))
    with pytest.raises(SceneError, match="mesh file not found"):
        read_mesh_file(tmp_path / "gone.dae")


HELD_OUT = Path(__file__).resolve().parents[1] / "benchmarks" / "data" / "held_out"


def test_held_out_benchmark_meshes_are_the_listed_closed_bodies():
    """The benchmark's held-out meshes (CGAL's data, kept in the repository) are the files
    SOURCES.md lists, byte for byte (sha256 prefix), and each reads as one closed body with
    the listed triangle count and Euler characteristic."""
    import hashlib

    from cspace.mesh.closed import ClosedMesh

    rows = [line.split("|")[1:-1] for line in (HELD_OUT / "SOURCES.md").read_text().splitlines()
            if line.startswith("| ") and line.split("|")[1].strip().endswith(".off")]
    assert sorted(c[0].strip() for c in rows) == sorted(p.name for p in HELD_OUT.glob("*.off"))
    assert len(rows) == 6
    for cells in rows:
        name, _, size, digest, T, V, chi = (c.strip() for c in cells[:7])
        data = (HELD_OUT / name).read_bytes()
        assert len(data) == int(size) and hashlib.sha256(data).hexdigest().startswith(digest), name
        m = read_mesh_file(HELD_OUT / name)
        A = ClosedMesh.from_arrays(np.asarray(m.vertices), np.asarray(m.faces))
        assert (len(A.faces), len(A.vertices)) == (int(T), int(V)), name
        e = np.sort(A.faces[:, [0, 1, 1, 2, 2, 0]].reshape(-1, 2), axis=1)
        assert len(A.vertices) - len(np.unique(e, axis=0)) + len(A.faces) == int(chi), name
        assert A.components.max() == 0, name  # one body
