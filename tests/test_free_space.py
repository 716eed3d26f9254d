"""The exact free space (cspace.planning.free_space; its kernel cspace.minkowski.union): the
components of the bounds minus the grown union of convex C-obstacle pieces, point location,
and the separating surface that proves 'no path'.

Oracles that share nothing with the union: FCL on the raw meshes (every sampled point of a
separating surface collides, or lies within the stated clearance of a body), winding numbers
by solid angles for which side of that surface start and goal are on, and the scenes' construction
(a slot narrower than the robot, C-obstacles touching along a face or an edge: closed; at a
vertex, or a gap: open). Each scene is also moved far from the origin, scaled and turned."""

from __future__ import annotations

import sys

import numpy as np
import pytest

import cspace
from cspace.check.oracle import SceneOracle
from cspace.errors import InvalidArgumentError, UnsupportedError
from cspace.planning.free_space import free_space

sys.path.insert(0, str(__import__("pathlib").Path(__file__).parent))
from test_corridor import (FAR, MOVES, TURN, _c_boxes_scene, _flat_seam,  # noqa: E402
                           _place)
from test_decide import CAGE_MOVES, _cage  # noqa: E402

decide = sys.modules["cspace.planning.decide"].decide


def _winding(V, F, p) -> np.ndarray:
    """Generalised winding numbers of the triangles ``V[F]`` at points ``p`` (solid angles,
    van Oosterom and Strackee; floats, no code of ours): an integer for a closed surface."""
    out = []
    for q in np.atleast_2d(p):
        a, b, c = (V[F[:, k]] - q for k in range(3))
        la, lb, lc = (np.linalg.norm(x, axis=1) for x in (a, b, c))
        num = np.einsum("ij,ij->i", a, np.cross(b, c))
        den = (la * lb * lc + np.einsum("ij,ij->i", a, b) * lc
               + np.einsum("ij,ij->i", b, c) * la + np.einsum("ij,ij->i", c, a) * lb)
        out.append(2.0 * np.arctan2(num, den).sum() / (4.0 * np.pi))
    return np.array(out)


def _check_separation(scene, fs, sep, n_points=300, seed=0, bounds=None):
    """The separating surface lies in the grown C-obstacles (FCL on the raw meshes: collides,
    or within ``fs.error_bound`` of a body) or on the bounds' box (snapped outward), and
    start and goal are on different sides of it (its winding numbers by solid angles)."""
    rng = np.random.default_rng(seed)
    V, F = sep.vertices, sep.faces
    w = rng.dirichlet([1.0, 1.0, 1.0], size=n_points)
    t = rng.integers(0, len(F), size=n_points)
    pts = np.vstack([V, np.einsum("ki,kij->kj", w, V[F[t]])])
    b = np.asarray(scene.bounds if bounds is None else bounds, dtype=np.float64)
    size = float(np.abs(b).max())
    on_box = ((np.abs(pts - b[0]) <= 1e-6 * size) | (np.abs(pts - b[1]) <= 1e-6 * size)).any(1)
    oracle = SceneOracle(scene)
    rest = pts[~on_box]
    hit = oracle.collides(rest)
    if not hit.all():
        assert (oracle.distance(rest[~hit]) <= fs.error_bound + 1e-9 * size).all()
    w = _winding(V, F, np.array([scene.start, scene.goal], dtype=np.float64))
    assert np.allclose(w, np.round(w), atol=1e-6) and np.round(w).tolist() == list(sep.winding)


@pytest.mark.parametrize("move", [{}] + CAGE_MOVES)
def test_a_closed_cage_is_two_components_wherever_it_is(tmp_path, move):
    scene, cs = _cage(tmp_path, slot=0.2, **move)
    fs = free_space(cs, scene.bounds)
    assert fs.n_components == 2 and fs.n_pieces == 7
    a, b = fs.component_of(scene.start), fs.component_of(scene.goal)
    assert {a, b} == {0, 1}
    sep = fs.separation(scene.start, scene.goal)
    assert sep is not None and sep.winding == (1, 0)
    _check_separation(scene, fs, sep)
    d = decide(cs, scene.start, scene.goal, bounds=scene.bounds)
    assert d.answer == "no path" and d.separation is not None, d.reason
    assert d.clearance == fs.error_bound < 1e-6 * move.get("scale", 1.0)
    assert "exact free space" in d.reason and len(d.to_trimesh("start").faces) == len(sep.faces)


@pytest.mark.parametrize("slot", [0.4 + 2.0**-10, 0.6])
def test_a_slot_wider_than_the_robot_is_one_component(tmp_path, slot):
    scene, cs = _cage(tmp_path, slot=slot, offset=FAR)
    fs = free_space(cs, scene.bounds)
    assert fs.n_components == 1
    assert fs.component_of(scene.start) == fs.component_of(scene.goal) == 0
    assert fs.separation(scene.start, scene.goal) is None
    assert fs.bounds_on_grid and fs.joined(scene.start, scene.goal)
    # bounds off the grid: the components are of the bounds snapped outward (a step larger),
    # so one component proves no path inside the bounds themselves
    off_grid = np.asarray(scene.bounds) + [[-0.1], [0.1]]
    fs2 = free_space(cs, off_grid)
    assert not fs2.bounds_on_grid and not fs2.joined(scene.start, scene.goal)
    assert fs2.component_of(scene.start) == fs2.component_of(scene.goal) is not None
    d = decide(cs, scene.start, scene.goal, bounds=scene.bounds, time=30)
    assert d.answer == "path" and d.free_space is not None, d.reason
    assert d.free_space.n_components == 1


def test_a_slot_exactly_the_robots_width_is_closed(tmp_path):
    """The two halves of the +x wall a robot's width apart: their C-obstacles touch along a
    face (touching is a collision), so the start's component is closed."""
    scene, cs = _cage(tmp_path, slot=0.4, offset=FAR)
    fs = free_space(cs, scene.bounds)
    sep = fs.separation(scene.start, scene.goal)
    assert sep is not None
    _check_separation(scene, fs, sep)


@pytest.mark.parametrize("move", MOVES)
def test_c_obstacles_touching_along_an_edge_close_the_pockets(tmp_path, move):
    """test_corridor's edge scene: two pockets meeting only along the line where two
    C-obstacles touch. Exactly: two components, separated."""
    E, t, w = 4.0, 0.5, 0.6
    c_boxes = [((-t, -E, -E), (t, 0, 0)), ((-t, 0, 0), (t, E, E)),
               ((t, 0, -E), (t + w, E, 0)), ((-t - w, -E, 0), (-t, 0, E))]
    scene, cs = _c_boxes_scene(tmp_path, "edge", c_boxes, (-1.5, 0.5, -0.5), (1.5, -0.5, 0.5),
                               **move)
    fs = free_space(cs, scene.bounds)
    sep = fs.separation(scene.start, scene.goal)
    assert sep is not None, fs
    _check_separation(scene, fs, sep)
    # the pockets' points 1e-4 from the line are free, each in its side's component
    pockets = _place([[0, 1e-4, -1e-4], [0, -1e-4, 1e-4]], **move)
    assert fs.component_of(pockets[0]) == fs.component_of(scene.start)
    assert fs.component_of(pockets[1]) == fs.component_of(scene.goal)
    assert fs.component_of(_place([0.0, 0.0, 0.0], **move)) is None  # on the touching line


@pytest.mark.parametrize("move", MOVES)
def test_c_obstacles_touching_along_a_face_are_a_wall(tmp_path, move):
    E, t = 4.0, 0.5
    c_boxes = [((-t, -E, -E), (t, 0.3, E)), ((-t, 0.3, -E), (t, E, E))]
    scene, cs = _c_boxes_scene(tmp_path, "seam", c_boxes, (-1.5, 0.2, 0.1), (1.5, 0.4, -0.3),
                               **move)
    fs = free_space(cs, scene.bounds)
    sep = fs.separation(scene.start, scene.goal)
    assert sep is not None and fs.n_components == 2
    _check_separation(scene, fs, sep)


@pytest.mark.parametrize("move", MOVES)
def test_c_obstacles_touching_at_a_vertex_leave_one_component(tmp_path, move):
    c_boxes = [((-1.0, -1.0, -1.0), (0.0, 0.0, 0.0)), ((0.0, 0.0, 0.0), (1.0, 1.0, 1.0))]
    scene, cs = _c_boxes_scene(tmp_path, "vertex", c_boxes, (-1.5, 1.5, 1.5),
                               (1.5, -1.5, -1.5), half=3.0 if "turn" in move else 2.0, **move)
    fs = free_space(cs, scene.bounds)
    assert fs.n_components == 1 and fs.separation(scene.start, scene.goal) is None
    assert fs.component_of(scene.start) == fs.component_of(scene.goal) == 0
    assert fs.component_of(_place([0.0, 0.0, 0.0], **move)) is None


@pytest.mark.parametrize("offset", [(0.0, 0.0, 0.0), FAR])
@pytest.mark.parametrize("gap", [0.0, 1e-5, -1e-3])
def test_a_seam_in_flat_bounds_is_decided_exactly(tmp_path, offset, gap):
    scene, cs, b = _flat_seam(tmp_path, offset, gap)
    fs = free_space(cs, b)
    sep = fs.separation(scene.start, scene.goal)
    assert (sep is None) == (gap > 0)
    assert not fs.bounds_on_grid and not fs.joined(scene.start, scene.goal)  # flat: a slab
    if sep is not None:
        _check_separation(scene, fs, sep, bounds=b)


def test_a_c_obstacle_far_larger_than_the_bounds_is_clipped(tmp_path):
    """The cage over a floor slab 10^5 wide crossing the bounds (and a slanted one): the
    pieces are clipped to the frame's box, so the grid's step follows the bounds (the error
    bound is the slabs' own, from their grids); the answer is the cage's."""
    from scipy.spatial.transform import Rotation

    scene, cs = _cage(tmp_path, slot=0.2, offset=FAR)
    unit = np.array([[x, y, z] for x in (0, 1) for y in (0, 1) for z in (0, 1)], float)
    slab = (unit - 0.5) * [1e5, 1e5, 0.1] + np.asarray(FAR) + [0.0, 0.0, -1.9]
    turned = ((unit - 0.5) * [1e5, 1e5, 0.1]) @ Rotation.from_euler(
        "xyz", (2.0, -1.5, 40.0), degrees=True).as_matrix().T + np.asarray(FAR) + [0, 0, -1.8]
    robot = 0.4 * (unit - 0.5)
    big = [cspace.CSpaceObstacle.build(v, robot) for v in (slab, turned)]
    plain = free_space(cs, scene.bounds)
    fs = free_space(cspace.CSpace(list(cs.obstacles) + big, bounds=scene.bounds), scene.bounds)
    assert fs.grid.exponent == plain.grid.exponent
    assert fs.error_bound == max(co.error_bound for co in big) + 3**0.5 * fs.grid.step
    sep = fs.separation(scene.start, scene.goal)
    assert sep is not None and fs.n_pieces == 9
    assert fs.component_of(np.asarray(FAR) + [0.0, 0.0, -1.9]) is None  # in the slab
    _check_separation(scene, fs, sep, n_points=50)


@pytest.mark.parametrize("seed", range(6))
def test_clipping_a_piece_to_a_box_keeps_exactly_their_intersection(seed):
    """_clipped's vertices span P ∩ box: the same volume as scipy's half-space intersection
    (floats, its own code), and every vertex in both."""
    from scipy.spatial import ConvexHull, HalfspaceIntersection

    from cspace.mesh.convex import ConvexPolytope
    from cspace.planning.free_space import _clipped

    rng = np.random.default_rng(seed)
    P = ConvexPolytope.from_points(rng.normal(size=(30, 3)) + 250.0)
    lo, hi = 250.0 + rng.uniform(-1.5, 0.0, 3), 250.0 + rng.uniform(0.0, 1.5, 3)
    X = np.array([[float(c) for c in x] for x in _clipped(P, lo, hi)])
    V = P.vertices
    H = ConvexHull(V).equations
    box = np.vstack([np.hstack([-np.eye(3), lo[:, None]]), np.hstack([np.eye(3), -hi[:, None]])])
    inner = np.clip(V.mean(axis=0), lo + 1e-3, hi - 1e-3)
    assert (H[:, :3] @ inner + H[:, 3] < 0).all()  # an interior point of both
    ref = ConvexHull(HalfspaceIntersection(np.vstack([H, box]), inner).intersections).volume
    assert abs(ConvexHull(X).volume - ref) <= 1e-9 * max(ref, 1.0)
    assert (X >= lo - 1e-12).all() and (X <= hi + 1e-12).all()
    assert (H[:, :3] @ X.T + H[:, 3:4] <= 1e-9).all()


# Lattice scenes: seeds of one free component and of 2 to 4 (closed pockets).
LATTICE_SEEDS = (0, 1, 2, 5, 15, 16, 18, 29)
POCKETED = (1, 5, 15, 18, 29)


@pytest.mark.parametrize("seed", LATTICE_SEEDS)
def test_components_match_a_lattice_flood_fill(seed):
    """Random boxes on a lattice of 1/4 (a cube robot of 1/2: the C-obstacles are boxes on
    it too), at (250, 150, -300): every open lattice cell is wholly free or wholly inside,
    and the free components are the face-connected free cells (scipy's labels, from the
    cells' centres: nothing of ours). Same number of components, and the centres of a cell of
    each and of 250 random free cells in the component their labels say."""
    cs, b, free, labels, count, centres, off, rng = _lattice(seed)
    fs = free_space(cs, b)
    assert fs.n_components == count
    _check_lattice_components(fs, free, labels, count, centres, off, rng)


def _lattice(seed):
    """A random lattice scene (test_components_match_a_lattice_flood_fill): its C-space,
    bounds, free cells, scipy's labels and count, the cells' centres and the offset."""
    from scipy import ndimage

    rng = np.random.default_rng(seed)
    off, h = np.asarray(FAR), 0.25
    unit = np.array([[x, y, z] for x in (0, 1) for y in (0, 1) for z in (0, 1)], float)
    cos, boxes = [], []
    for _ in range(int(rng.integers(15, 40))):
        lo = rng.integers(0, 15, 3) * h
        hi = lo + rng.integers(1, 7, 3) * h
        cos.append(cspace.CSpaceObstacle.build(off + lo + unit * (hi - lo), unit * 0.5,
                                               reference_point=(0.25, 0.25, 0.25)))
        boxes.append((lo - h, hi + h))
    b = np.stack([off, off + 4.0])
    n = 16
    centres = (np.stack(np.meshgrid(*[np.arange(n)] * 3, indexing="ij"), -1) + 0.5) * h
    free = np.ones((n, n, n), bool)
    for lo, hi in boxes:
        free &= ~((centres >= lo) & (centres <= hi)).all(axis=-1)
    labels, count = ndimage.label(free)
    return cspace.CSpace(cos, bounds=b), b, free, labels, count, centres, off, rng


def _check_lattice_components(fs, free, labels, count, centres, off, rng):
    seen = {}
    cells = np.argwhere(free)
    _, first = np.unique(labels[free], return_index=True)  # one cell of each component
    pick = np.union1d(first, rng.choice(len(cells), size=min(250, len(cells)), replace=False))
    for idx in map(tuple, cells[pick]):
        k = fs.component_of(off + centres[idx])
        assert k is not None
        assert seen.setdefault(labels[idx], k) == k
    assert len(set(seen.values())) == count


def test_a_components_sample_is_located_in_it(tmp_path):
    """sample(k) is a symbolic point inside component k: located back in k, and in the free
    space of more C-obstacles on the same bounds, in the component that holds it there."""
    scene, cs = _cage(tmp_path, slot=0.2, offset=FAR, turn=TURN)
    fs = free_space(cs, scene.bounds)
    for k in range(fs.n_components):
        assert fs.component_at(fs.sample(k)) == k
    start = fs.component_of(scene.start)
    inner = fs.sample(start)  # inside the cage: free of a far box too, in its start's part
    unit = np.array([[x, y, z] for x in (0, 1) for y in (0, 1) for z in (0, 1)], float)
    far_box = cspace.CSpaceObstacle.build(np.asarray(FAR) + 1.6 + 0.2 * unit, 0.4 * unit)
    more = free_space(cspace.CSpace(list(cs.obstacles) + [far_box], bounds=scene.bounds),
                      scene.bounds)
    assert more.component_at(inner) == more.component_of(scene.start) is not None


@pytest.mark.parametrize("move", [dict(), dict(offset=FAR, scale=3.0)])
def test_turning_decisions_on_the_exact_free_spaces(tmp_path, move):
    """Over 8 slices: the cage (a cube never fits its slot) is 'no path' from the exact free
    spaces, as from the cells; the piano (it turns through the door) stays 'unknown', joined
    in them."""
    from pathlib import Path

    from cspace.planning.decide import decide_turning
    from cspace.planning.plan import default_slices
    from cspace.planning.turning import TurningCSpace

    scene, _ = _cage(tmp_path, slot=0.2, **move)
    tcs = TurningCSpace(scene, default_slices(scene, 8))
    td = decide_turning(tcs, scene.start, scene.goal)
    assert td.answer == "no path" and "exact free spaces" in td.reason
    assert len(td.components) == 8 and td.links > 0 and td.clearance < 1e-5 * move.get("scale", 1)
    cells = decide_turning(tcs, scene.start, scene.goal, exact=False)
    assert cells.answer == "no path" and "exact" not in cells.reason
    piano = cspace.load_scene(Path(__file__).parent.parent / "scenes" / "piano.toml")
    tp = TurningCSpace(piano, default_slices(piano, 8))
    td = decide_turning(tp, piano.start, piano.goal)
    assert td.answer == "unknown" and "joined" in td.reason


def test_the_frames_boxes_face_the_right_way():
    from cspace.planning.free_space import _box_faces

    for outward, sign in ((True, 1), (False, -1)):
        V, F = _box_faces(np.array([-1, -2, -3]), np.array([4, 5, 6]), outward)
        a, b, c = (V[F[:, k]].astype(float) for k in range(3))
        volume6 = np.einsum("ij,ij->i", a, np.cross(b, c)).sum()
        assert volume6 == sign * 6 * 5 * 7 * 9


@pytest.mark.parametrize("seed", POCKETED)
def test_the_cells_never_contradict_the_exact_free_space(seed):
    """Two deciders that share only the C-obstacles: on lattice scenes, start and goal in
    different flood-fill components are 'no path' exactly and never 'path' by the cells; in
    one component, never 'no path' by either."""
    cs, b, free, labels, count, centres, off, rng = _lattice(seed)
    cells = np.argwhere(free)
    lab = labels[free]
    assert count > 1  # POCKETED seeds have closed pockets
    pairs = [rng.choice(len(cells), size=2, replace=False) for _ in range(2)]
    for k in range(2):  # and from two different components
        a = rng.choice(np.nonzero(lab == lab[pairs[0][0]])[0])
        pairs.append((a, rng.choice(np.nonzero(lab != lab[a])[0])))
    for i, j in pairs:
        q0, q1 = off + centres[tuple(cells[i])], off + centres[tuple(cells[j])]
        apart = labels[tuple(cells[i])] != labels[tuple(cells[j])]
        d = decide(cs, q0, q1, bounds=b, time=10)
        c = decide(cs, q0, q1, bounds=b, time=3, exact=False)
        if apart:
            assert d.answer == "no path" and d.separation is not None, d.reason
            assert c.answer != "path", c.reason
        else:
            assert d.answer != "no path" and c.answer != "no path", (d.reason, c.reason)


def test_points_in_or_on_the_c_obstacles_or_outside_the_bounds_have_no_component(tmp_path):
    scene, cs = _cage(tmp_path, slot=0.2, offset=FAR)
    fs = free_space(cs, scene.bounds)
    wall = np.asarray(FAR) + [-1.05, 0.0, 0.0]
    assert cs.contains(wall) and fs.component_of(wall) is None
    assert fs.component_of(np.asarray(FAR) + 9.0) is None
    with pytest.raises(InvalidArgumentError, match="not finite"):
        fs.component_of([np.nan, 0.0, 0.0])
    assert "components=2" in repr(fs) and "pieces=7" in repr(fs)


def test_the_union_is_a_closed_surface_that_holds_every_c_obstacle(tmp_path):
    """Random points: inside a C-obstacle (exact query, shares nothing with the union) means
    inside the union's surface (its winding number by solid angles), and points the union
    holds are within its error bound of a C-obstacle."""
    scene, cs = _cage(tmp_path, slot=0.2, offset=FAR, turn=TURN)
    fs = free_space(cs, scene.bounds)
    m = fs.to_trimesh()
    assert m.is_watertight and m.volume > 0
    rng = np.random.default_rng(3)
    b = np.asarray(scene.bounds)
    q = b[0] + rng.random((1000, 3)) * (b[1] - b[0])
    ins = np.round(_winding(np.asarray(m.vertices), np.asarray(m.faces), q)) > 0
    co = cs.contains(q)
    assert not (co & ~ins).any()
    extra = ins & ~co
    assert (cs.signed_distance(q[extra]) >= -1e-12).all()
    assert (cs.signed_distance(q[extra]) <= fs.error_bound + 1e-9).all()


def test_one_component_says_a_path_exists_when_the_cells_find_none():
    """The window's gap is finer than cells at depth 3: the cells answer 'unknown', and the
    exact free space adds that start and goal are in one component (a path exists); without
    it, no such claim."""
    from pathlib import Path

    scene = cspace.load_scene(Path(__file__).parent.parent / "scenes" / "window.toml")
    cs = cspace.model_scene(scene).cspace()
    d = decide(cs, scene.start, scene.goal, bounds=scene.bounds, depth=3, refine=False)
    assert d.answer == "unknown" and d.reason.endswith("a path exists")
    c = decide(cs, scene.start, scene.goal, bounds=scene.bounds, depth=3, refine=False,
               exact=False)
    assert c.answer == "unknown" and "path exists" not in c.reason


@pytest.mark.parametrize("move", [dict(), dict(offset=FAR, scale=3.0, turn=TURN)])
def test_open_walls_as_triangle_pairs_are_united(tmp_path, move):
    """Open walls against the cube (triangle-pair C-obstacles): each wall's pieces over the
    cube's triangles are one convex piece (the cube is closed and convex; a wall's two
    triangles, coplanar, are one patch), and the cage is separated, checked by FCL."""
    scene, cs = _cage(tmp_path, slot=0.2, surfaces=True, **move)
    assert {co.kind for co in cs.obstacles} == {"pairs"}
    fs = free_space(cs, scene.bounds)
    assert fs.n_pieces == 7  # the walls (the +x wall in two halves)
    sep = fs.separation(scene.start, scene.goal)
    assert sep is not None
    _check_separation(scene, fs, sep)
    d = decide(cs, scene.start, scene.goal, bounds=scene.bounds)
    assert d.answer == "no path" and d.separation is not None


def test_closed_convex_triangles_are_told_from_others():
    from cspace.planning.free_space import _closed_convex

    cube = np.array([[x, y, z] for x in (0, 2) for y in (0, 2) for z in (0, 2)])
    F = np.array([[0, 1, 3], [0, 3, 2], [4, 6, 7], [4, 7, 5], [0, 4, 5], [0, 5, 1],
                  [2, 3, 7], [2, 7, 6], [0, 2, 6], [0, 6, 4], [1, 5, 7], [1, 7, 3]])
    assert _closed_convex(cube[F]) and _closed_convex(-cube[F])  # either orientation
    assert not _closed_convex(cube[F[:-1]])  # open
    dented = cube.copy()
    dented[7] = [1, 1, 1]  # a corner pushed in: closed, not convex
    assert not _closed_convex(dented[F])


def test_a_hollow_solid_on_the_grid_is_taken_whole(tmp_path):
    """test_decide's hollow box (a closed room with a cube inside, one 'mesh' C-obstacle
    whose vertices are on the union's grid): taken whole, the room is its own component,
    checked by FCL; from outside, one component."""
    from test_decide import _hollow

    scene, cs = _hollow(tmp_path, start=(0, 0, 0), goal=(1.6, 1.6, 1.6))
    fs = free_space(cs, scene.bounds)
    assert fs.n_pieces == 0 and fs.n_components == 2
    sep = fs.separation(scene.start, scene.goal)
    assert sep is not None
    _check_separation(scene, fs, sep)
    outside, cs2 = _hollow(tmp_path, start=(-1.6, -1.6, -1.6), goal=(1.6, 1.6, 1.6))
    fs2 = free_space(cs2, outside.bounds)
    assert fs2.separation(outside.start, outside.goal) is None
    assert fs2.component_of(outside.start) == fs2.component_of(outside.goal) is not None


def test_a_non_convex_sum_off_the_grid_is_declined_by_name():
    """An L ⊕ a turned cube (NCC-CVMS, kind 'mesh'): its vertices are off the union's grid,
    so the exact union declines it, naming it; decide goes on with its cells."""
    from scipy.spatial.transform import Rotation
    from zoo import l_shape

    V, F = l_shape()
    unit = np.array([[x, y, z] for x in (0, 1) for y in (0, 1) for z in (0, 1)], float)
    robot = (0.3 * (unit - 0.5)) @ Rotation.from_euler("xyz", TURN, degrees=True).as_matrix().T
    co = cspace.CSpaceObstacle.build((V + np.asarray(FAR), F), robot)
    assert co.kind == "mesh"
    cs = cspace.CSpace([co], bounds=np.stack([np.asarray(FAR) - 2.0, np.asarray(FAR) + 5.0]))
    with pytest.raises(UnsupportedError, match="kind 'mesh'.*off the union's grid"):
        free_space(cs)
    q0, q1 = np.asarray(FAR) - 1.5, np.asarray(FAR) + 4.5
    d = decide(cs, q0, q1, time=30)
    assert d.answer == "path" and d.free_space is None


def test_too_many_pieces_are_declined_before_any_is_made(tmp_path):
    """Too many triangle pairs near the bounds: declined, by count, before any piece is
    made; decide then proves the cage closed with its cells."""
    scene, cs = _cage(tmp_path, slot=0.2, surfaces=True, turn=TURN)
    with pytest.raises(UnsupportedError, match="more than 5 convex pieces"):
        free_space(cs, scene.bounds, max_pieces=5)
    d = decide(cs, scene.start, scene.goal, bounds=scene.bounds, time=30, exact=False)
    assert d.answer == "no path" and d.separation is None and d.free_space is None


def test_too_many_triangle_pairs_are_declined_share_by_share(tmp_path, monkeypatch):
    """A union too large is declined by name before its work: over ``max_pairs / 100`` pairs
    of pieces overlapping, before any piece is made; over ``max_pairs`` candidate triangle
    pairs, counted share by share of the box sweep before all are made. decide goes on with
    its cells; shares give the cuts one sweep gives."""
    import cspace.minkowski.intersections as inter
    from cspace.minkowski.union import UnionCells

    scene, cs = _cage(tmp_path, slot=0.2, offset=FAR, turn=TURN)
    with pytest.raises(UnsupportedError, match="20 pairs of its pieces overlap, more than 1 "):
        free_space(cs, scene.bounds, max_pairs=100)
    with pytest.raises(UnsupportedError, match="more than 2,000 candidate triangle pairs"):
        free_space(cs, scene.bounds, max_pairs=2000)
    d = decide(cs, scene.start, scene.goal, bounds=scene.bounds, time=30)
    assert d.answer == "no path"
    fs = free_space(cs, scene.bounds)
    ints, faces = fs.cells.planes.ints, fs.cells.planes.faces
    one = UnionCells(ints, faces)
    monkeypatch.setattr(inter, "_SHARE_OVERLAPS", 1000)  # many shares
    shared = UnionCells(ints, faces)
    assert shared.cx.points == one.cx.points and shared.n_cells == one.n_cells
    assert (shared.winding == one.winding).all()


def test_the_free_space_keeps_its_time_budget(tmp_path):
    scene, cs = _cage(tmp_path, slot=0.2)
    with pytest.raises(TimeoutError):
        free_space(cs, scene.bounds, time=0.0)
    with pytest.raises(UnsupportedError, match="more than 3"):
        free_space(cs, scene.bounds, max_pieces=3)


def test_the_shipped_scenes_components(tmp_path):
    """Every shipped scene at its start orientation: the cage, the piano and the plate (which
    must turn) are separated, the others one component."""
    from pathlib import Path

    for path in sorted((Path(__file__).parent.parent / "scenes").glob("*.toml")):
        scene = cspace.load_scene(path)
        cs = cspace.model_scene(scene).cspace()
        fs = free_space(cs, scene.bounds)
        sep = fs.separation(scene.start, scene.goal)
        assert (sep is not None) == (path.stem in ("cage", "piano", "plate")), path.stem


def bottle_scene(tmp_path, robot: float, start, goal, offset=(0.0, 0.0, 0.0), scale=1.0,
                 turn=None):
    """A closed box of 5^3 unit voxels whose 3^3 cavity opens through one unit hole in its
    +x wall (400 triangles, one non-convex solid: its C-obstacle against a ``robot`` cube is
    an NCC-CVMS sum), turned, scaled and moved, with its bounds (4 each side); and its
    C-space."""
    import trimesh
    from zoo import voxel_solid

    occupied = np.ones((5, 5, 5), dtype=bool)
    occupied[1:4, 1:4, 1:4] = False
    occupied[4, 2, 2] = False
    V, F = voxel_solid(occupied, origin=(-2.5, -2.5, -2.5))
    trimesh.Trimesh(_place(V, offset, scale, turn), F, process=False).export(tmp_path / "b.obj")

    def at(p, turned=True):
        return repr(_place(p, offset, scale, turn if turned else None).tolist())

    turned = [] if turn is None else [f"orientation = {[float(a) for a in turn]}"]
    (tmp_path / "bottle.toml").write_text("\n".join(
        ['name = "bottle"', "[robot]", f"box = {[robot * scale] * 3}", *turned, "[planning]",
         f"bounds = [{at((-4, -4, -4), False)}, {at((4, 4, 4), False)}]",
         f"start = {at(start)}", f"goal = {at(goal)}", "[[obstacles]]", 'mesh = "b.obj"']) + "\n")
    scene = cspace.load_scene(tmp_path / "bottle.toml")
    return scene, cspace.model_scene(scene).cspace()


@pytest.mark.parametrize("move", [{}, dict(offset=FAR, scale=3.0), pytest.param(
    dict(offset=FAR, scale=3.0, turn=TURN), marks=pytest.mark.slow)])
def test_a_solid_non_convex_body_is_united_as_convex_patches(tmp_path, move):
    """The bottle: a robot cube wider than its neck is shut in. Its C-obstacle is a
    non-convex sum off the union's grid, so the free space takes the scene's triangle pairs
    instead (the same set), one piece per convex patch of the walls' coplanar triangles (400
    triangles; turned, snapped, coplanar within a step): the cavity is its own component, the
    proof checked by FCL on the raw meshes and by solid angles; a narrower cube gets out.
    Where the sum is on the grid (moved, not turned) it is taken whole."""
    scene, cs = bottle_scene(tmp_path, 1.5, (0, 0, 0), (3.5, 0, 0), **move)
    assert [co.kind for co in cs.obstacles] == ["mesh"]
    fs = free_space(cs, scene.bounds)
    assert fs.n_components == 2 and fs.n_pieces < 100  # not one per triangle
    sep = fs.separation(scene.start, scene.goal)
    assert sep is not None and sep.winding == (1, 0)
    _check_separation(scene, fs, sep)
    assert fs.error_bound < 1e-5 * move.get("scale", 1.0)
    # decide: the octree's levels first (milliseconds here, where the pairs' union takes
    # seconds); stopped above the level that decides, the exact free space after them
    d = decide(cs, scene.start, scene.goal, bounds=scene.bounds, time=30)
    assert d.answer == "no path" and d.time < 1.0, d.reason
    shallow = decide(cs, scene.start, scene.goal, bounds=scene.bounds, time=30, depth=3,
                     refine=False)
    assert shallow.answer == "no path" and shallow.separation is not None, shallow.reason
    scene2, cs2 = bottle_scene(tmp_path, 0.8, (0, 0, 0), (3.5, 0, 0), **move)
    fs2 = free_space(cs2, scene2.bounds)
    assert fs2.separation(scene2.start, scene2.goal) is None
    assert fs2.component_of(scene2.start) == fs2.component_of(scene2.goal) is not None


@pytest.mark.parametrize("move", [dict(offset=FAR, scale=3.0), pytest.param(
    dict(offset=FAR, scale=3.0, turn=TURN), marks=pytest.mark.slow)])
def test_cspace_plan_proves_the_bottle_shut_without_flags(tmp_path, move):
    """``cspace plan SCENE``, as a new user runs it: the cube cannot leave the bottle at any
    orientation (exit 3, the proof's scope said): even the ball inside the cube, which no
    turn changes, cannot pass the neck."""
    import subprocess

    scene, _ = bottle_scene(tmp_path, 1.5, (0, 0, 0), (3.5, 0, 0), **move)
    # --time far above the proofs' (the run ends at them): the turning decision's share
    # (0.3 of it) once took 3.04 s of 3.0 s on a busy machine with --time 10
    run = subprocess.run([sys.executable, "-m", "cspace", "plan", str(tmp_path / "bottle.toml"),
                          "--time", "60", "--seed", "1", "--no-cache"], capture_output=True,
                         text=True, timeout=300)
    assert run.returncode == 3, run.stdout + run.stderr
    assert "no path, proved: none at any orientation" in run.stdout


def test_a_real_union_too_large_is_declined_at_once(shared_data, monkeypatch):
    """The Parasol bug trap against its robot's hull (3212 triangles of a solid trap: its sum,
    then taken as 2481 patches' pieces): their union would make 160 million candidate
    triangle pairs, and once grew to 24 GB until the system killed it (after 370 s of
    pieces). It is declined by name from the pieces' boxes, before any piece is made."""
    import warnings

    fs_module = sys.modules["cspace.planning.free_space"]

    def no_piece(*args, **kwargs):
        raise AssertionError("a piece was made")

    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # the robot's hull is warned about
        scene = cspace.load_scene(shared_data / "parasol_open_ppl_env/bug_trap1.0/bug-trap.env")
    cs = cspace.model_scene(scene, robot_hull=True).cspace()
    monkeypatch.setattr(fs_module, "_pair_pieces", no_piece)
    with pytest.raises(UnsupportedError, match="589,889 pairs of its pieces overlap"):
        free_space(cs, scene.bounds)
