"""Tests for cspace.mesh: validation, welding, orientation and exact volume of closed meshes."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
import trimesh

from cspace.errors import (
    DegenerateError,
    DuplicateFaceError,
    EmptyMeshError,
    GridRangeError,
    InvalidMeshError,
    NonFiniteError,
    NonManifoldError,
    OpenMeshError,
)
from cspace.geometry.exact import Grid
from cspace.mesh.closed import ClosedMesh, as_mesh
from cspace.mesh.validate import _volume6

# -- helpers ----------------------------------------------------------------------------------


def box(lo=-1.0, hi=1.0, offset=(0.0, 0.0, 0.0)):
    """Axis-aligned cube [lo, hi]^3 + offset, outward faces: (8, 3) float64, (12, 3) int64."""
    b = trimesh.creation.box(extents=(hi - lo,) * 3)
    vertices = np.asarray(b.vertices) + (lo + hi) / 2 + np.asarray(offset)
    return vertices, np.asarray(b.faces, dtype=np.int64)


def tetra(offset=(0.0, 0.0, 0.0)):
    """A tetrahedron with outward faces."""
    v = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0], [0, 0, 1]], dtype=np.float64) + offset
    f = np.array([[0, 2, 1], [0, 1, 3], [0, 3, 2], [1, 2, 3]], dtype=np.int64)
    return v, f


def exact_dets(mesh: ClosedMesh) -> list[int]:
    """det[v0, v1, v2] of every face (scene-frame integers: the grid's origin added), with
    Python ints."""
    p = (mesh.ints + np.asarray(mesh.grid.origin, np.int64))[mesh.faces].astype(object)
    return list(
        p[:, 0, 0] * (p[:, 1, 1] * p[:, 2, 2] - p[:, 1, 2] * p[:, 2, 1])
        + p[:, 0, 1] * (p[:, 1, 2] * p[:, 2, 0] - p[:, 1, 0] * p[:, 2, 2])
        + p[:, 0, 2] * (p[:, 1, 0] * p[:, 2, 1] - p[:, 1, 1] * p[:, 2, 0])
    )


def assert_outward_star(mesh: ClosedMesh) -> None:
    """For a mesh star-shaped around the origin: every face sees the origin on its inside."""
    assert all(d > 0 for d in exact_dets(mesh))


def assert_consistent(mesh: ClosedMesh) -> None:
    """Every directed edge appears once, and its reverse once (a closed oriented surface)."""
    f = mesh.faces
    directed = np.concatenate([f[:, [0, 1]], f[:, [1, 2]], f[:, [2, 0]]])
    keys = directed[:, 0] * len(mesh.ints) + directed[:, 1]
    reverse = directed[:, 1] * len(mesh.ints) + directed[:, 0]
    assert len(np.unique(keys)) == len(keys)
    assert np.array_equal(np.sort(keys), np.sort(reverse))


def canonical_faces(faces) -> set[tuple[int, int, int]]:
    """Faces rotated to start at their smallest index (keeps the winding)."""
    out = set()
    for a, b, c in np.asarray(faces).tolist():
        k = [a, b, c].index(min(a, b, c))
        out.add(tuple([a, b, c][k:] + [a, b, c][:k]))
    return out


def check_arrays(mesh: ClosedMesh) -> None:
    n, m = len(mesh.vertices), len(mesh.faces)
    assert mesh.vertices.shape == (n, 3) and mesh.vertices.dtype == np.float64
    assert mesh.ints.shape == (n, 3) and mesh.ints.dtype == np.int64
    assert mesh.faces.shape == (m, 3) and mesh.faces.dtype == np.int64
    assert mesh.components.shape == (m,) and mesh.components.dtype == np.int64
    assert np.array_equal(mesh.vertices, mesh.grid.to_float(mesh.ints))
    assert np.array_equal(np.unique(mesh.faces), np.arange(n))  # no unreferenced vertex
    assert len(np.unique(mesh.ints, axis=0)) == n  # welded
    assert not mesh.vertices.flags.writeable and not mesh.faces.flags.writeable


# -- valid meshes -----------------------------------------------------------------------------


def test_box_exact_volume():
    mesh = ClosedMesh.from_arrays(*box())
    check_arrays(mesh)
    v6 = mesh.volume6()
    assert type(v6) is int
    # |x| <= 1 gives step 2**-25: the cube has side 2**26 grid units.
    assert mesh.grid.exponent == -25
    assert v6 == 6 * 2 ** (3 * 26)
    assert mesh.volume == 8.0
    assert_outward_star(mesh)
    assert canonical_faces(mesh.faces) == canonical_faces(box()[1])  # already outward: kept


def test_icosphere_and_torus():
    s = trimesh.creation.icosphere(subdivisions=3)
    sphere = ClosedMesh.from_arrays(s.vertices, s.faces, name="sphere")
    check_arrays(sphere)
    assert_outward_star(sphere)
    assert sphere.volume == pytest.approx(s.volume, rel=1e-6)  # snapping moves it
    assert sphere.components.max() == 0

    t = trimesh.creation.torus(major_radius=1.0, minor_radius=0.3)
    torus = ClosedMesh.from_arrays(t.vertices, t.faces[:, ::-1], name="torus")  # inverted
    check_arrays(torus)
    assert_consistent(torus)
    assert torus.volume6() > 0
    assert torus.volume == pytest.approx(abs(t.volume), rel=1e-6)  # snapping moves it
    assert torus.volume == pytest.approx(torus.to_trimesh().volume, rel=1e-12)
    nv, nf = len(torus.vertices), len(torus.faces)
    assert nv - 3 * nf // 2 + nf == 0  # genus 1


def test_inverted_box_is_flipped_back():
    v, f = box()
    good = ClosedMesh.from_arrays(v, f)
    bad = ClosedMesh.from_arrays(v, f[:, ::-1])
    assert bad.volume6() == good.volume6() > 0
    assert bad.volume == 8.0
    assert canonical_faces(bad.faces) == canonical_faces(good.faces)


@pytest.mark.parametrize("wrong", [[0], [3, 4, 7], [0, 1, 2, 3, 4, 5, 6], list(range(1, 12))])
def test_inconsistent_winding_repaired(wrong):
    v, f = box()
    f = f.copy()
    f[wrong] = f[wrong][:, ::-1]
    mesh = ClosedMesh.from_arrays(v, f)
    assert_consistent(mesh)
    assert_outward_star(mesh)
    assert mesh.volume == 8.0


def test_duplicated_vertices_are_welded():
    v, f = box()
    soup_v = v[f].reshape(-1, 3)  # 36 vertices, each corner repeated
    soup_f = np.arange(36).reshape(12, 3)
    mesh = ClosedMesh.from_arrays(soup_v, soup_f)
    check_arrays(mesh)
    assert len(mesh.vertices) == 8 and mesh.volume == 8.0
    # Within half a grid step, points weld too.
    jitter = soup_v + np.where(soup_v > 0, 1e-12, -1e-12)
    assert len(ClosedMesh.from_arrays(jitter, soup_f).vertices) == 8


def test_weld_keeps_vertex_order_and_drops_unreferenced():
    v, f = box()
    extra = np.vstack([v, [[5.0, 5.0, 5.0]]])  # unreferenced: dropped, not in the grid
    mesh = ClosedMesh.from_arrays(extra, f)
    assert np.array_equal(mesh.vertices, v)
    assert canonical_faces(mesh.faces) == canonical_faces(f)
    assert mesh.grid == Grid.for_points(v)


def test_faces_keep_input_order_and_volume_invariance():
    rng = np.random.default_rng(7)
    s = trimesh.creation.icosphere(subdivisions=2)
    ref = ClosedMesh.from_arrays(s.vertices, s.faces)
    f = np.asarray(s.faces)[rng.permutation(len(s.faces))]
    f = np.roll(f, 1, axis=1)
    flip = rng.random(len(f)) < 0.3
    f[flip] = f[flip][:, ::-1]
    mesh = ClosedMesh.from_arrays(s.vertices, f, grid=ref.grid)
    assert mesh.volume6() == ref.volume6()
    assert np.array_equal(np.sort(mesh.faces, axis=1), np.sort(f, axis=1))
    assert_outward_star(mesh)


def test_cavity_and_separate_components():
    outer_v, outer_f = box(-2.0, 2.0)
    inner_v, inner_f = box(-1.0, 1.0)
    v = np.vstack([outer_v, inner_v])
    # The inner shell wound inwards is a cavity: volumes of mixed sign are kept.
    cavity = ClosedMesh.from_arrays(v, np.vstack([outer_f, inner_f[:, ::-1] + 8]))
    assert cavity.volume == 64.0 - 8.0
    assert np.array_equal(cavity.components, np.repeat([0, 1], 12))
    # A mis-wound first face does not decide a shell's side: the winding of most faces does.
    inner = inner_f[:, ::-1].copy()
    inner[0] = inner_f[0]
    cavity2 = ClosedMesh.from_arrays(v, np.vstack([outer_f, inner + 8]))
    assert cavity2.volume == 64.0 - 8.0
    assert canonical_faces(cavity2.faces) == canonical_faces(cavity.faces)
    # A hollow box wound inside out: the outer shell is negative, so all is flipped.
    hollow = ClosedMesh.from_arrays(v, np.vstack([outer_f[:, ::-1], inner_f + 8]))
    assert hollow.volume == 56.0
    assert canonical_faces(hollow.faces) == canonical_faces(cavity.faces)
    # Two bodies both inside out: all flipped.
    far_v, far_f = box(offset=(5.0, 0.0, 0.0))
    both = ClosedMesh.from_arrays(
        np.vstack([inner_v, far_v]), np.vstack([inner_f[:, ::-1], far_f[:, ::-1] + 8])
    )
    assert both.volume == 16.0
    assert all(d > 0 for d in exact_dets(both)[:12])


def test_separate_body_wound_inside_out():
    # An inward shell inside no outward shell's solid bounds nothing: a separate body wound
    # inside out, turned outwards (as a scene turns it), not refused.
    a_v, a_f = box()
    b_v, b_f = box(offset=(5.0, 0.0, 0.0))
    mesh = ClosedMesh.from_arrays(np.vstack([a_v, b_v]), np.vstack([a_f[:, ::-1], b_f + 8]))
    assert mesh.volume == 16.0  # both outwards (one inwards would make it 0)


def test_on_grid():
    mesh = ClosedMesh.from_arrays(*box(), name="b")
    assert mesh.on_grid(mesh.grid) is mesh
    fine = mesh.on_grid(Grid(exponent=-27, bits=28))
    assert fine.volume == 8.0 and fine.grid.exponent == -27 and fine.name == "b"
    assert fine.volume6() == mesh.volume6() * 2**6
    # A grid whose step is the whole box welds it away.
    with pytest.raises(DegenerateError, match="mesh 'b': face 0 collapses"):
        mesh.on_grid(Grid(exponent=2, bits=8))


def test_to_trimesh_roundtrip():
    mesh = ClosedMesh.from_arrays(*box())
    tm = mesh.to_trimesh()
    assert isinstance(tm, trimesh.Trimesh)
    assert np.array_equal(tm.vertices, mesh.vertices) and np.array_equal(tm.faces, mesh.faces)
    assert tm.is_watertight and tm.is_winding_consistent and tm.volume == 8.0
    tm.vertices[0] = 100.0  # a copy
    assert mesh.vertices[0, 0] != 100.0


def test_volume6_exact_at_grid_limit():
    # The int64 split summation equals Python-int arithmetic at |coordinates| up to 2**28.
    rng = np.random.default_rng(3)
    lim = 2**28
    ints = rng.integers(-lim, lim + 1, size=(300, 3), dtype=np.int64)
    signs = np.array(np.meshgrid([1, -1], [1, -1], [1, -1], indexing="ij")).reshape(3, -1).T
    ints[:8] = signs * lim
    faces = rng.integers(0, len(ints), size=(5000, 3), dtype=np.int64)
    labels = rng.integers(0, 4, size=len(faces), dtype=np.int64)
    p = ints[faces].astype(object)
    det = (
        p[:, 0, 0] * (p[:, 1, 1] * p[:, 2, 2] - p[:, 1, 2] * p[:, 2, 1])
        + p[:, 0, 1] * (p[:, 1, 2] * p[:, 2, 0] - p[:, 1, 0] * p[:, 2, 2])
        + p[:, 0, 2] * (p[:, 1, 0] * p[:, 2, 1] - p[:, 1, 1] * p[:, 2, 0])
    )
    assert _volume6(ints, faces) == [sum(det)]
    assert _volume6(ints, faces, labels, 4) == [sum(det[labels == g]) for g in range(4)]
    # The extreme corner combinations alone.
    corner = np.array([[0, 1, 2], [7, 2, 4], [6, 5, 3], [1, 6, 4]], dtype=np.int64)
    pc = ints[corner].astype(object)
    expected = sum(
        pc[i, 0] @ np.array(
            [pc[i, 1, 1] * pc[i, 2, 2] - pc[i, 1, 2] * pc[i, 2, 1],
             pc[i, 1, 2] * pc[i, 2, 0] - pc[i, 1, 0] * pc[i, 2, 2],
             pc[i, 1, 0] * pc[i, 2, 1] - pc[i, 1, 1] * pc[i, 2, 0]], dtype=object)
        for i in range(4)
    )
    assert _volume6(ints, corner) == [expected]


# -- errors -----------------------------------------------------------------------------------


def test_empty():
    v, f = box()
    with pytest.raises(EmptyMeshError, match="no faces"):
        ClosedMesh.from_arrays(v, np.zeros((0, 3), dtype=np.int64))
    with pytest.raises(EmptyMeshError, match="no vertices"):
        ClosedMesh.from_arrays(np.zeros((0, 3)), f)
    with pytest.raises(EmptyMeshError, match="no faces"):
        ClosedMesh.from_arrays(v, [])


def test_wrong_shape_and_dtype():
    v, f = box()
    with pytest.raises(InvalidMeshError, match=r"vertices must be \(n, 3\), got \(5, 2\)"):
        ClosedMesh.from_arrays(np.zeros((5, 2)), f)
    with pytest.raises(InvalidMeshError, match=r"faces must be \(m, 3\), got \(6, 4\)"):
        ClosedMesh.from_arrays(v, np.zeros((6, 4), dtype=np.int64))
    msg = "faces must be integer vertex indices, got dtype float64"
    with pytest.raises(InvalidMeshError, match=msg):
        ClosedMesh.from_arrays(v, f.astype(np.float64))
    with pytest.raises(InvalidMeshError, match="vertices must be real numbers"):
        ClosedMesh.from_arrays(v.astype(complex), f)


@pytest.mark.parametrize("bad", [np.nan, np.inf, -np.inf])
def test_non_finite(bad):
    v, f = box()
    v = v.copy()
    v[5, 1] = bad
    msg = rf"mesh 'mesh': vertex 5 has a non-finite coordinate \(.*{bad}"
    with pytest.raises(NonFiniteError, match=msg):
        ClosedMesh.from_arrays(v, f)


def test_index_out_of_range():
    v, f = box()
    f = f.copy()
    f[7, 2] = 99
    msg = "face 7 refers to vertex 99; the mesh has 8 vertices"
    with pytest.raises(InvalidMeshError, match=msg):
        ClosedMesh.from_arrays(v, f)
    f[7, 2] = -1
    with pytest.raises(InvalidMeshError, match="face 7 refers to vertex -1"):
        ClosedMesh.from_arrays(v, f)


def test_grid_too_small():
    with pytest.raises(GridRangeError, match="vertex 0 at .* beyond the grid's range"):
        ClosedMesh.from_arrays(*box(), grid=Grid.for_extent(0.25))


def test_collapsed_face():
    v, f = tetra()
    v = np.vstack([v, v[1] + 1e-12])  # vertex 4 welds onto vertex 1
    f = np.vstack([f, [[4, 1, 2]]])
    # A needle after welding is dropped (its zero-length edge is collapsed): the same point
    # set, and the rest is a valid solid, so it is the tetrahedron.
    mesh = ClosedMesh.from_arrays(v, f)
    assert len(mesh.faces) == 4 and mesh.volume == pytest.approx(1 / 6)
    assert len(ClosedMesh.from_arrays(v, [[1, 1, 1]] + f.tolist()).faces) == 4
    # When what is left is no solid, the collapse is the error, and why the repair failed.
    w = np.vstack([v[:4], v[0] + 1e-12])  # vertex 4 welds onto vertex 0
    g = np.where(f[:4] == 1, 4, f[:4])  # the tetrahedron on vertices 0, 4, 2, 3
    msg = (r"face 0 collapses: its vertices \(0, 2, 4\) weld to 2 distinct .*; 2 faces "
           r"collapse; repairing them leaves no valid solid \(DuplicateFaceError")
    with pytest.raises(DegenerateError, match=msg):
        ClosedMesh.from_arrays(w, g)
    with pytest.raises(DegenerateError, match=r"face 0 collapses: .* weld to one grid point"):
        ClosedMesh.from_arrays(v, [[1, 1, 1]])


def test_zero_area_face():
    v, f = tetra()
    v = np.vstack([v, [[2.0, 0.0, 0.0], [3.0, 0.0, 0.0]]])  # collinear with vertex 1
    f = np.vstack([f, [[1, 4, 5], [5, 4, 1]]])
    msg = r"face 4 has zero area \(collinear vertices \(1, 4, 5\).*; 2 faces"
    with pytest.raises(DegenerateError, match=msg):
        ClosedMesh.from_arrays(v, f)


def test_duplicate_face():
    v, f = box()
    msg = r"faces 3 and 12 use the same vertices .*repeated face"
    with pytest.raises(DuplicateFaceError, match=msg):
        ClosedMesh.from_arrays(v, np.vstack([f, f[3]]))


def test_double_sided_face_pair():
    v, f = box()
    with pytest.raises(DuplicateFaceError, match=r"faces 2 and 12 .*double-sided surface"):
        ClosedMesh.from_arrays(v, np.vstack([f, f[2, ::-1]]))


def test_open_mesh():
    v, f = box()
    msg = r"3 boundary edges \(open mesh\), first between vertices"
    with pytest.raises(OpenMeshError, match=msg):
        ClosedMesh.from_arrays(v, f[1:])


def test_non_manifold_edge():
    a_v, a_f = tetra()
    # A second tetrahedron sharing the edge (0, 1) of the first: that edge has 4 faces.
    b_v = np.array([[0, 0, 0], [1, 0, 0], [0, -1, 0], [0, 0, -1]], dtype=np.float64)
    _, b_f = tetra()
    v = np.vstack([a_v, b_v[2:]])
    remap = np.array([0, 1, 4, 5])
    msg = r"1 edges shared by more than 2 faces, first between vertices \(0, 1\) \(faces 0, 1, 4, 5"
    with pytest.raises(NonManifoldError, match=msg):
        ClosedMesh.from_arrays(v, np.vstack([a_f, remap[b_f]]))


def test_non_manifold_vertex():
    a_v, a_f = tetra()
    b_v = -a_v  # touches the first at the origin only
    v = np.vstack([a_v, b_v[1:]])
    remap = np.array([0, 4, 5, 6])
    msg = "vertex 0 is non-manifold: its faces form 2 separate fans"
    with pytest.raises(NonManifoldError, match=msg):
        ClosedMesh.from_arrays(v, np.vstack([a_f, remap[a_f]]))


def test_non_orientable():
    # The 6-vertex real projective plane: every edge in two faces, every vertex link a
    # 5-cycle, but no consistent winding. Generic positions keep every face non-degenerate.
    faces = [(0, 1, 2), (0, 2, 3), (0, 3, 4), (0, 4, 5), (0, 5, 1),
             (1, 2, 4), (2, 3, 5), (3, 4, 1), (4, 5, 2), (5, 1, 3)]
    v = np.random.default_rng(0).normal(size=(6, 3))
    with pytest.raises(NonManifoldError, match="not orientable: faces .* across the edge"):
        ClosedMesh.from_arrays(v, faces)


def test_zero_volume():
    # An octahedron flattened into the plane z = 0: closed, manifold, no zero-area face.
    v = np.array([[1, 0, 0], [-1, 0, 0], [0, 1, 0], [0, -1, 0], [0.2, 0.1, 0], [-0.1, 0.3, 0]])
    eq = [0, 2, 1, 3]
    f = [(4, eq[i], eq[(i + 1) % 4]) for i in range(4)]
    f += [(5, eq[(i + 1) % 4], eq[i]) for i in range(4)]
    with pytest.raises(DegenerateError, match="encloses zero volume"):
        ClosedMesh.from_arrays(v, f)


def test_load_errors(tmp_path):
    with pytest.raises(FileNotFoundError, match="nowhere.obj"):
        ClosedMesh.load(tmp_path / "nowhere.obj")
    junk = tmp_path / "junk.ply"
    junk.write_bytes(b"ply\nformat nonsense\n\x00\x01\x02")
    with pytest.raises(InvalidMeshError, match="junk.ply"):
        ClosedMesh.load(junk)
    v, f = box()
    path = tmp_path / "open box.obj"
    trimesh.Trimesh(v, f[1:], process=False).export(path)
    with pytest.raises(OpenMeshError, match="mesh 'open box.obj': 3 boundary edges"):
        ClosedMesh.load(path)


# -- coercion ---------------------------------------------------------------------------------


def test_as_mesh(tmp_path):
    v, f = box()
    tm = trimesh.Trimesh(v, f, process=False)
    from_tm = as_mesh(tm)
    from_tuple = as_mesh((v, f), name="t")
    path = tmp_path / "cube.stl"
    tm.export(path)
    from_path = as_mesh(path)
    from_str = as_mesh(str(path), name="s")
    assert from_tuple.name == "t" and from_path.name == "cube.stl" and from_str.name == "s"
    for mesh in (from_tm, from_tuple, from_path, from_str):
        assert isinstance(mesh, ClosedMesh) and mesh.volume == 8.0
    assert as_mesh(from_tm) is from_tm
    assert as_mesh(from_tm, grid=from_tm.grid) is from_tm
    fine = as_mesh(from_tm, grid=Grid(exponent=-27, bits=28), name="fine")
    assert fine.grid.exponent == -27 and fine.name == "fine" and fine.volume == 8.0
    renamed = as_mesh(from_tm, name="other")
    assert renamed.name == "other" and renamed.faces is from_tm.faces
    with pytest.raises(TypeError, match="cannot make a mesh from int"):
        as_mesh(3)
    with pytest.raises(OpenMeshError, match="mesh 'mesh'"):
        as_mesh((v, f[1:]))


# -- real meshes ------------------------------------------------------------------------------

REAL_CLOSED = [
    # path, T, V, Euler characteristic (from ../shared/data/SOURCES.md)
    ("lien_mesh_segmentation/bunny-128.obj", 128, 66, 2),
    ("lien_mesh_segmentation/Centaur-1000.obj", 1000, 502, 2),
    ("lien_mesh_segmentation/yoda-658.obj", 658, 331, 2),
    ("lien_mesh_unfolder/bumpy-528.obj", 528, 266, 2),
    ("parasol_open_ppl_env/alpha1.6/geometries/alphaobstacle.obj", 972, 488, 2),
    ("parasol_open_ppl_env/bug_trap1.0/trap.obj", 3212, 1606, 0),
]


@pytest.mark.parametrize("rel, T, V, chi", REAL_CLOSED, ids=[Path(r[0]).name for r in REAL_CLOSED])
def test_real_closed_meshes(shared_data, rel, T, V, chi):
    mesh = ClosedMesh.load(shared_data / rel)
    check_arrays(mesh)
    assert mesh.name == Path(rel).name
    assert len(mesh.faces) == T and len(mesh.vertices) == V
    assert V - 3 * T // 2 + T == chi
    assert mesh.components.max() == 0
    assert mesh.volume6() > 0 and mesh.volume > 0
    assert_consistent(mesh)
    tm = mesh.to_trimesh()
    assert tm.is_watertight and tm.is_winding_consistent
    assert tm.volume == pytest.approx(mesh.volume, rel=1e-12)


def test_real_open_soup(shared_data):
    with pytest.raises(OpenMeshError, match=r"mesh 'env.obj': \d+ boundary edges \(open mesh\)"):
        ClosedMesh.load(shared_data / "fcl_test_resources/env.obj")


def test_real_doubled_surface(shared_data):
    # Every triangle of stick-bug.obj is listed twice (66 repeats of 66 faces).
    msg = r"mesh 'stick-bug.obj': faces 0 and 66 .*; 66 faces repeat"
    with pytest.raises(DuplicateFaceError, match=msg):
        ClosedMesh.load(shared_data / "parasol_open_ppl_env/bug_trap1.0/stick-bug.obj")
