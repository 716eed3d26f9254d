"""The FCL oracle shares nothing with the code it checks (issue #27, item 3).

- :class:`cspace.check.oracle.SceneOracle` against brute-force truth on hand-made scenes of
  axis-aligned boxes (closed boxes are solids, open boxes are surfaces; two closed sets of
  boxes and rectangles meet iff their intervals overlap on every axis): a robot whose second
  component sits inside a closed body, a body component inside a closed robot, an open box
  enclosing the robot (no winding test), at the origin, at (250, 150, -300) and at 1e5.
- the regression the old oracle hid: the triangle-pair pieces' boxes shifted by the grid's
  origin again (monkeypatched), on an L robot against a U obstacle at (250, 150, -300):
  ``cspace check`` (``cross_check`` and the CLI) reports false free and the ``--fcl-check``
  path check catches a path through the obstacle; without the patch both report nothing.
"""

from __future__ import annotations

import numpy as np
import pytest
import trimesh

from cspace import CSpace
from cspace.cli import main
from cspace.check.cross_check import PoseCollider, cross_check, path_collisions
from cspace.check.oracle import SceneOracle
from cspace.scene.scene import Body, Scene
from cspace.scene.files import load_scene

# --------------------------------------------------------------------------------------
# hand-made boxes with brute-force truth


def _box(lo, hi):
    """A closed, outward axis-aligned box mesh over ``[lo, hi]``."""
    lo, hi = np.asarray(lo, float), np.asarray(hi, float)
    m = trimesh.creation.box(extents=hi - lo)
    return np.asarray(m.vertices) + (lo + hi) / 2, np.asarray(m.faces, dtype=np.int64)


def _open_box(lo, hi):
    """The box without its top (z = hi) triangles: an open surface, a cup."""
    V, F = _box(lo, hi)
    top = (V[F][:, :, 2] == V[:, 2].max()).all(axis=1)
    return V, F[~top]


def _join(*meshes):
    Vs, Fs, n = [], [], 0
    for V, F in meshes:
        Vs.append(V), Fs.append(F + n)
        n += len(V)
    return np.vstack(Vs), np.vstack(Fs)


def _pieces_of_open_box(lo, hi):
    """The cup's five rectangles as degenerate boxes (one zero-width axis)."""
    lo, hi = np.asarray(lo, float), np.asarray(hi, float)
    out = []
    for axis in range(3):
        for side in ((0, 1) if axis < 2 else (0,)):
            a, b = lo.copy(), hi.copy()
            a[axis] = b[axis] = (lo if side == 0 else hi)[axis]
            out.append((a, b))
    return out


def _truth(robot_pieces, body_pieces, Q, eps):
    """(k,) bool truth and (k,) bool 'clear of the touching configurations by eps'."""
    hit = np.zeros(len(Q), dtype=bool)
    clear = np.ones(len(Q), dtype=bool)
    for rlo, rhi in robot_pieces:
        for blo, bhi in body_pieces:
            # gap per axis (negative: overlap); closed boxes meet iff no axis has a gap > 0,
            # and |largest gap| is how far the translation is from a touching one
            s = np.maximum(blo - (rhi + Q), (rlo + Q) - bhi).max(axis=1)
            hit |= s <= 0
            clear &= np.abs(s) > eps
    return hit, clear


def _scene(robot, bodies, offset, reference=(0.0, 0.0, 0.0)):
    off = np.asarray(offset, float)
    lo, hi = off - 50, off + 50
    return Scene("boxes", None, tuple(Body(f"b{i}", V + off, F, "test")
                                      for i, (V, F) in enumerate(bodies)),
                 Body("robot", *robot, "test"), reference, np.stack([lo, hi]), off, off)


OFFSETS = [(0.0, 0.0, 0.0), (250.0, 150.0, -300.0), (1e5, 1e5, 1e5)]


@pytest.mark.parametrize("offset", OFFSETS)
def test_second_robot_component_inside_a_closed_body(offset):
    # Robot: a unit cube (vertex 0 is its) and a small cube far from it: two components.
    c1, c2 = ([0, 0, 0], [1, 1, 1]), ([3, 0, 0], [3.4, 0.4, 0.4])
    robot = _join(_box(*c1), _box(*c2))
    body = ([10, 0, 0], [12, 2, 2])
    orc = SceneOracle(_scene(robot, [_box(*body)], offset))
    off = np.asarray(offset)
    q = off + [7.5, 0.5, 0.5]  # c2 at [10.5, 10.9] x [0.5, 0.9]^2: inside; c1 well away
    assert orc.robot.n_components == 2 and orc.robot.closed.all()
    assert orc.collides(q[None])[0]
    # the old test looked at the robot's vertex 0 only: it lies in c1, outside the body
    assert not orc.bodies[0].inside((orc.robot.V[0] + q)[None])[0]
    # random translations against brute force
    rng = np.random.default_rng(1)
    Q = off + rng.uniform([5, -2, -2], [13, 3, 3], (400, 3))
    want, clear = _truth([tuple(map(np.asarray, c1)), tuple(map(np.asarray, c2))],
                         [(np.asarray(body[0]) + off, np.asarray(body[1]) + off)], Q, 1e-6)
    got = orc.collides(Q)
    assert want[clear].any() and (~want[clear]).any()
    assert np.array_equal(got[clear], want[clear])


@pytest.mark.parametrize("offset", OFFSETS)
def test_body_component_inside_a_closed_robot(offset):
    robot = _box([0, 0, 0], [4, 4, 4])
    far, small = ([30, 30, 30], [31, 31, 31]), ([10, 10, 10], [10.5, 10.5, 10.5])
    body = _join(_box(*far), _box(*small))  # vertex 0 is the far component's
    orc = SceneOracle(_scene(robot, [body], offset))
    off = np.asarray(offset)
    assert orc.bodies[0].n_components == 2
    assert orc.collides((off + [8, 8, 8])[None])[0]  # the robot [8, 12]^3 swallows `small`
    rng = np.random.default_rng(2)
    Q = off + rng.uniform(4, 12, (400, 3))
    want, clear = _truth([(np.zeros(3), np.full(3, 4.0))],
                         [(np.asarray(b[0]) + off, np.asarray(b[1]) + off) for b in (far, small)],
                         Q, 1e-6)
    got = orc.collides(Q)
    assert want[clear].any() and (~want[clear]).any()
    assert np.array_equal(got[clear], want[clear])


@pytest.mark.parametrize("offset", OFFSETS)
def test_open_cup_enclosing_the_robot_is_a_surface(offset):
    cup = ([0, 0, 0], [4, 4, 4])
    robot = _box([0, 0, 0], [1, 1, 1])
    orc = SceneOracle(_scene(robot, [_open_box(*cup)], offset))
    off = np.asarray(offset)
    assert not orc.bodies[0].closed.any() and not orc.bodies[0].solid
    q = off + [1.5, 1.5, 1.5]
    assert not orc.collides(q[None])[0]  # in the cup, touching nothing
    # a winding test would have said "inside": the cup's five faces cover 5/6 of the sphere
    from cspace.check.fcl import winding_number

    V, F = orc.bodies[0].V, orc.bodies[0].F
    assert winding_number(V, F, (q + 0.5)[None])[0] > 0.5
    rng = np.random.default_rng(3)
    Q = off + rng.uniform(-1.5, 4.5, (500, 3))
    want, clear = _truth([(np.zeros(3), np.ones(3))],
                         [(a + off, b + off) for a, b in _pieces_of_open_box(*cup)], Q, 1e-6)
    got = orc.collides(Q)
    assert want[clear].any() and (~want[clear]).any()
    assert np.array_equal(got[clear], want[clear])


def test_poses_rotate_about_the_reference_point():
    # Robot: a rod [0, 3] x [-0.1, 0.1]^2 about the reference point (0, 0, 0) and a far cube
    # component; the body: a closed box above the rod's end once turned 90 degrees about z.
    robot = _join(_box([0, -0.1, -0.1], [3, 0.1, 0.1]), _box([-5, -5, -5], [-4.9, -4.9, -4.9]))
    body = _box([-0.5, 2.0, -0.5], [0.5, 4.0, 0.5])
    orc = SceneOracle(_scene(robot, [body], (250.0, 150.0, -300.0)))
    q = np.array([250.0, 150.0, -300.0])
    turn = np.array([[0.0, -1, 0], [1, 0, 0], [0, 0, 1]])  # x -> y
    assert not orc.collides_poses(np.eye(3)[None], q[None])[0]
    assert orc.collides_poses(turn[None], q[None])[0]  # the rod's end is inside the body
    assert np.array_equal(PoseCollider(_scene(robot, [body], (250.0, 150.0, -300.0))).collides(
        np.stack([np.eye(3), turn]), np.stack([q, q])), [False, True])


def test_self_intersecting_closed_mesh_holds_what_it_encloses():
    # Two overlapping boxes written as one closed mesh (its surfaces cross): solid where the
    # winding number is not zero, the overlap (w = 2) included; an inside-out box (w = -1)
    # is solid too; an open box is a surface.
    a, b = _box([0, 0, 0], [1, 1, 1]), _box([0.5, 0.5, 0.5], [1.5, 1.5, 1.5])
    both = (np.vstack([a[0], b[0]]), np.vstack([a[1], b[1] + len(a[0])]))
    inverted = (_box([5, 5, 5], [6, 6, 6])[0], _box([5, 5, 5], [6, 6, 6])[1][:, ::-1])
    open_box = (_box([10, 0, 0], [11, 1, 1])[0], _box([10, 0, 0], [11, 1, 1])[1][2:])
    tiny = _box([-0.01, -0.01, -0.01], [0.01, 0.01, 0.01])
    for shift in (np.zeros(3), np.array([250.0, 150.0, -300.0])):
        orc = SceneOracle(_scene(tiny, [both, inverted, open_box], shift))
        assert [m.solid for m in orc.bodies] == [True, True, False]
        q = np.array([[0.75, 0.75, 0.75], [0.25, 0.25, 0.25], [1.25, 1.25, 1.25],
                      [5.5, 5.5, 5.5], [10.5, 0.5, 0.5], [3.0, 3.0, 3.0]]) + shift
        assert orc.collides(q).tolist() == [True, True, True, True, False, False]


# --------------------------------------------------------------------------------------
# the shifted piece boxes, re-introduced


def _prism(poly, faces2d, height):
    m = trimesh.creation.extrude_triangulation(np.asarray(poly, float), np.asarray(faces2d),
                                               height)
    assert m.is_watertight and m.is_winding_consistent and m.volume > 0
    return m


L_POLY = [(0, 0), (2, 0), (2, 1), (1, 1), (1, 2), (0, 2)]
L_TRIS = [(3, 4, 5), (3, 5, 0), (3, 0, 1), (3, 1, 2)]
U_POLY = [(0, 0), (3, 0), (3, 2), (2, 2), (2, 1), (1, 1), (1, 2), (0, 2)]
U_TRIS = [(0, 1, 4), (1, 2, 4), (2, 3, 4), (0, 4, 5), (0, 5, 7), (5, 6, 7)]


def _write_scene(tmp_path):
    robot = _prism(L_POLY, L_TRIS, 1.0)  # 20 triangles, non-convex
    robot.apply_scale(0.4)
    robot.apply_translation(-robot.bounds.mean(axis=0))
    obstacle = _prism(U_POLY, U_TRIS, 1.0)  # 28 triangles, non-convex
    obstacle.apply_translation([-1.5, -1.0, -0.5])
    robot.export(tmp_path / "l_robot.obj")
    obstacle.export(tmp_path / "u_obstacle.stl")
    path = tmp_path / "far.toml"
    path.write_text(
        'name = "far L in U"\n\n'
        '[robot]\nmesh = "l_robot.obj"\n\n'
        "[planning]\n"
        "bounds = [[247.0, 147.5, -302.0], [253.0, 152.5, -298.0]]\n"
        "start = [247.5, 150.0, -300.0]\ngoal = [252.5, 150.0, -300.0]\n\n"
        '[[obstacles]]\nname = "U"\nmesh = "u_obstacle.stl"\n'
        "position = [250.0, 150.0, -300.0]\n")
    return path


@pytest.fixture
def shifted_boxes():
    """The old bug: the pieces' boxes converted by the grid that adds its origin (S already
    holds it), so every box sits one grid origin away from its piece."""
    from metamorphic import shifted_piece_boxes

    with shifted_piece_boxes():
        yield


# Along the U's bar (y in [149, 150]) with the robot (0.8 wide) overlapping it by 0.4 and its
# reference point outside the obstacle: only the triangle-pair pieces see this collision.
GRAZE = [[247.5, 148.8, -300.0], [252.5, 148.8, -300.0]]
AROUND = [[247.5, 150.0, -300.0], [247.5, 152.2, -300.0], [252.5, 152.2, -300.0],
          [252.5, 150.0, -300.0]]


def _uses_triangle_pairs(cs):
    import cspace.cobstacle.pairs as pairs

    return any(isinstance(getattr(o, "_impl", None), pairs._TreePairsCO) for o in cs.obstacles)


def _run(tmp_path, capsys):
    path = _write_scene(tmp_path)
    scene = load_scene(path)
    cs = CSpace.from_scene(scene)
    assert _uses_triangle_pairs(cs)
    r = cross_check(cs, n=600, seed=4, scene=scene)
    assert r["oracle"] == "scene"
    rc = main(["check", str(path), "-n", "600", "--seed", "4"])
    out = capsys.readouterr().out
    through, n_through = path_collisions(cs, GRAZE, scene=scene)
    around, n_around = path_collisions(cs, AROUND, scene=scene)
    return cs, r, rc, out, len(through), len(around)


def test_shifted_piece_boxes_are_caught(tmp_path, capsys, shifted_boxes):
    cs, r, rc, out, through, around = _run(tmp_path, capsys)
    # the C-space is blind: it certifies the grazing segment free
    assert not cs.contains(np.array([250.0, 148.8, -300.0]))
    assert cs.segment_free(np.array(GRAZE[0]), np.array(GRAZE[1]))
    assert r["n_false_free"] > 0 and not r["ok"]
    assert rc == 1
    assert "membership disagreements beyond 1e-09 of the surface: 0 " not in out
    assert through > 0  # the --fcl-check path check catches the grazing path
    assert around == 0


def test_correct_piece_boxes_pass(tmp_path, capsys):
    cs, r, rc, out, through, around = _run(tmp_path, capsys)
    assert cs.contains(np.array([250.0, 148.8, -300.0]))
    assert not cs.segment_free(np.array(GRAZE[0]), np.array(GRAZE[1]))
    assert r["ok"] and r["n_false_free"] == 0 and r["n_disagree"] == 0
    assert rc == 0
    assert "membership disagreements beyond 1e-09 of the surface: 0 " in out
    assert through > 0 and around == 0
    assert cs.segment_free(np.array(AROUND[:-1]), np.array(AROUND[1:])).all()
    # the scene may be given as the first argument; without one, the C-obstacles' operands
    scene = load_scene(tmp_path / "far.toml")
    assert len(path_collisions(scene, GRAZE)[0]) == through
    assert len(path_collisions(cs, GRAZE)[0]) > 0 and len(path_collisions(cs, AROUND)[0]) == 0
    band = SceneOracle(scene).band
    assert 300 * 2.0**-48 <= band < 1e-11  # 16 ulp of the scene's largest coordinate
