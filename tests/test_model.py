"""Scene modelling (cspace.scene.model), surface C-obstacles (cspace.cobstacle.surface), the disk cache.

Real checks only: classifications are compared with independent inspections of the meshes
(trimesh watertightness and convexity, float bounding boxes with a margin), surface
C-obstacles with FCL's own mesh (BVH) collision, cached C-obstacles with fresh ones.
"""

from __future__ import annotations

import warnings
from pathlib import Path

import numpy as np
import pytest
import trimesh

from cspace import load_scene
from cspace.scene.cache import COCache, cache_dir
from cspace.check.oracle import SceneOracle
from cspace.scene.model import model_scene
from cspace.scene.scene import Body, Scene

from zoo import hollow_box, torus  # tests/ is on sys.path (rootdir conftest)

SCENES = Path(__file__).resolve().parents[1] / "scenes"
CUBE = trimesh.creation.box(extents=(1.0, 1.0, 1.0))


def make_scene(bodies, robot_extent=0.25, bounds=((-3, -3, -3), (3, 3, 3)), name="t"):
    robot = trimesh.creation.box(extents=(robot_extent,) * 3)
    lo = np.asarray(bounds[0], float)
    return Scene(name, None, tuple(bodies), Body("robot", robot.vertices, robot.faces, "box"),
                 (0.0, 0.0, 0.0), bounds, lo + 0.01, lo + 0.02)


def box_body(name, centre=(0, 0, 0), extents=(1, 1, 1)):
    m = trimesh.creation.box(extents=extents)
    return Body(name, m.vertices + np.asarray(centre, float), m.faces, "box")


def sheet(z=0.0, size=1.0):
    """An open square in the plane z, two triangles."""
    s = size / 2
    V = np.array([[-s, -s, z], [s, -s, z], [s, s, z], [-s, s, z]], float)
    return V, np.array([[0, 1, 2], [0, 2, 3]])


# --------------------------------------------------------------------------------------
# steps 1-5 on small hand-made bodies


def test_double_sided_sheet_keeps_one_side_and_is_a_surface():
    V, F = sheet()
    body = Body("sheet", V, np.vstack([F, F[:, ::-1]]), "test")
    m = model_scene(make_scene([body]), build=False)
    assert m.sources["sheet"] == {"triangles": 4, "collapsed": 0, "double_sided": 2,
                                  "repeated": 0, "parts": 1}
    (b,) = m.bodies
    assert b.kind == "surface" and len(b.faces) == 2 and "4 boundary edges" in b.reason
    assert "2 double-sided" in m.explain()


def test_double_sided_closed_box_is_a_sheet_and_repeats_are_counted():
    # Every triangle listed with both windings: the two sides of a sheet (winding number 0,
    # FCL's reading), so the box encloses nothing; a box listed once (or repeated with the
    # same winding) is a solid.
    F = CUBE.faces
    body = Body("box2", CUBE.vertices, np.vstack([F, F[:, ::-1], F[:3]]), "test")
    m = model_scene(make_scene([body]), build=False)
    s = m.sources["box2"]
    assert (s["double_sided"], s["repeated"], s["parts"]) == (12, 3, 1)
    (b,) = m.bodies
    assert b.kind == "surface" and b._encloses is None and "both windings" in b.reason
    once = Body("box1", CUBE.vertices, np.vstack([F, F[:3]]), "test")
    assert [b.kind for b in model_scene(make_scene([once]), build=False).bodies] == ["convex"]
    # one side of one face listed once only: not a sheet, a closed solid as before
    half = Body("box3", CUBE.vertices, np.vstack([F, F[1:, ::-1]]), "test")
    assert [b.kind for b in model_scene(make_scene([half]), build=False).bodies] == ["convex"]


def test_collapsed_triangles_are_dropped_and_counted():
    V = np.vstack([CUBE.vertices, CUBE.vertices[:1] + 1e-12])  # welds onto vertex 0
    F = np.vstack([CUBE.faces, [[0, 8, 1]]])
    m = model_scene(make_scene([Body("b", V, F, "test")]), build=False)
    assert m.sources["b"]["collapsed"] == 1 and m.bodies[0].kind == "convex"


def test_a_body_of_collapsed_triangles_is_kept_as_a_point():
    """A triangle thinner than the step collapses to a point; the point is still an obstacle
    (issue #51: it was dropped as empty, and the robot passed through it)."""
    V = np.array([[2.0, 0, 0], [2 + 1e-12, 0, 0], [2, 1e-12, 0]])
    m = model_scene(make_scene([Body("dust", V, [[0, 1, 2]], "test"), box_body("box")]))
    assert [(b.name, b.kind) for b in m.bodies] == [("dust (snapped)", "surface"),
                                                     ("box", "convex")]
    assert "1 segments" not in m.bodies[0].reason and "0 segments and 1 points" in \
        m.bodies[0].reason
    # the robot (a 0.25 cube about its centre) over the point, and just beside it
    hit = m.cspace().contains(np.array([[2.1, 0.1, -0.1], [2.2, 0.0, 0.0]]))
    assert hit.tolist() == [True, False]


def test_split_into_bodies_and_cavity_stays_with_its_solid():
    two = np.vstack([CUBE.vertices, CUBE.vertices + [3.0, 0, 0]])
    body = Body("two", two, np.vstack([CUBE.faces, CUBE.faces + 8]), "test")
    V, F = hollow_box()
    hollow = Body("hollow", V, F, "test")
    m = model_scene(make_scene([body, hollow], bounds=((-4, -4, -4), (6, 6, 6))), build=False)
    assert [b.name for b in m.bodies] == ["two#0", "two#1", "hollow"]
    assert [b.kind for b in m.bodies] == ["convex", "convex", "solid"]
    assert "2 shells" in m.bodies[2].reason and m.sources["hollow"]["parts"] == 1


def test_drop_is_exact_at_the_bounds():
    # Robot half-extent 0.125: a unit box centred at x = c has CO x-range
    # [c - 0.625, c + 0.625]. Bounds end at x = 3: a box at c = 3.625 touches them (kept),
    # one four grid steps further is dropped (all values dyadic: exact on the grid).
    m0 = model_scene(make_scene([box_body("touch", (3.625, 0, 0))]), build=False)
    step = m0.grid.step
    m1 = model_scene(make_scene([box_body("touch", (3.625, 0, 0)),
                                 box_body("beyond", (3.625 + 4 * step, 0, 0))]), build=False,
                     grid=m0.grid)
    assert [b.kind for b in m1.bodies] == ["convex", "dropped"]
    assert "misses the planning bounds" in m1.bodies[1].reason
    # Dropped bodies are never built and not in the C-space.
    cs = model_scene(make_scene([box_body("far", (9, 0, 0)), box_body("near")])).cspace()
    assert len(cs) == 1


def test_surface_triangles_that_cannot_reach_the_bounds_are_left_out():
    # A long open strip: only the triangles near the bounds become pieces.
    xs = np.arange(0, 21, dtype=float)
    V = np.array([[x, y, 0.0] for x in xs for y in (0.0, 1.0)])
    F = np.array([[2 * i, 2 * i + 2, 2 * i + 3] for i in range(20)]
                 + [[2 * i, 2 * i + 3, 2 * i + 1] for i in range(20)])
    m = model_scene(make_scene([Body("strip", V, F, "test")], bounds=((-3, -3, -3), (3, 3, 3))))
    (b,) = m.bodies
    assert b.kind == "surface" and b.pieces == 8  # 4 quads start at x <= 3.125
    assert "32 more cannot reach the bounds" in b.reason
    (co,) = b.cos  # triangle pairs; an open strip encloses nothing: no containment term
    assert co.kind == "pairs" and len(co.S) == 8


# --------------------------------------------------------------------------------------
# surface C-obstacles


@pytest.mark.parametrize("offset", [(0.0, 0.0, 0.0), (250.0, 150.0, -300.0)])
def test_surface_co_agrees_with_fcl_mesh_collision_and_with_its_pieces(offset):
    """An open body against a convex robot is built as triangle pairs (the robot's facets as
    its triangles): the same set, exactly, as the union of one exact hull t ⊕ (c - R) per
    obstacle triangle (SurfaceObstacle.build, the reference), and FCL's answers."""
    from cspace.cobstacle.surface import SurfaceObstacle

    V, F = torus(1.0, 0.3, 24, 12)
    keep = np.arange(len(F)) % 7 != 0  # punch holes: an open surface
    off = np.asarray(offset)
    scene = make_scene([Body("open-torus", np.asarray(V) + off, F[keep], "test")],
                       robot_extent=0.25, bounds=((-1.6, -1.6, -0.6) + off, (1.6, 1.6, 0.6) + off))
    m = model_scene(scene)
    (b,) = m.bodies
    assert b.kind == "surface" and b.pieces == int(keep.sum())
    assert [p.construction for p in b.pairs] == ["triangle pairs"]
    co = m.cspace()
    (part,) = m.robot_parts
    ref = SurfaceObstacle.build((b.vertices, b.faces[b._keep]),
                                m.margin.grow(part.operand), scene.reference_point, grid=m.grid)
    rng = np.random.default_rng(0)
    Q = rng.uniform(scene.bounds[0], scene.bounds[1], (3000, 3))
    ours = co.contains(Q)
    np.testing.assert_array_equal(ours, ref.contains(Q))
    # FCL on the raw scene (SceneOracle: the open torus a surface by its own rule), not the
    # C-obstacle's snapped pieces. Exact agreement on these samples (the stated one-sided
    # error, error_bound 7.5e-8, is not hit by uniform samples).
    fcl_hit = SceneOracle(scene).collides(Q)
    assert 300 < ours.sum() < 2700
    assert (ours != fcl_hit).sum() == 0
    # Segments and first contact: exact, as the reference's.
    a, b2 = Q[:300], Q[300:600]
    free = ref.segment_free(a, b2)
    np.testing.assert_array_equal(co.segment_free(a, b2), free)
    np.testing.assert_array_equal([co.segment_free(x, y) for x, y in zip(a, b2)], free)
    np.testing.assert_array_equal(co.first_contact(a[:100], b2[:100]),
                                  ref.first_contact(a[:100], b2[:100]))
    # Signed distance: sign exact; outside, the distance to the nearest piece (pieces grown
    # by the margin box: a lower bound within the box's half-diagonal).
    d = co.signed_distance(Q[:200])
    assert ((d <= 0) == ours[:200]).all()
    out = ~ours[:200]
    slack = float(np.linalg.norm(m.margin.steps)) * m.grid.step + 1e-12
    gap = ref.signed_distance(Q[:200][out]) - d[out]
    assert (gap >= -1e-12).all() and (gap <= slack).all()


def test_surface_co_touching_counts():
    V, F = sheet(z=0.0)
    m = model_scene(make_scene([Body("sheet", V, F, "test")]))
    co = m.cspace()
    # Robot half-extent 0.125: touching the sheet from above at z = 0.125, free just above.
    assert co.contains([0.2, 0.2, 0.125])
    assert not co.contains([0.2, 0.2, np.nextafter(0.125, 1)])
    # A segment ending on the CO's corner edge touches; one stopping an ulp above is free.
    assert not co.segment_free([0.0, 0.0, 1.0], [0.625, 0.0, 0.125])
    assert co.first_contact([0.0, 0.0, 1.0], [0.625, 0.0, 0.125]) == 1.0
    assert co.segment_free([0.0, 0.0, 1.0], [0.0, 0.0, np.nextafter(0.125, 1)])


# --------------------------------------------------------------------------------------
# cache


def _cached_vs_fresh(scene, tmp_path):
    cache = COCache(tmp_path / "cache")
    fresh = model_scene(scene, cache=cache)
    assert all(b.cache == "miss" for b in fresh.bodies if b.kind != "dropped")
    again = model_scene(scene, cache=cache)
    assert all(b.cache == "hit" for b in again.bodies if b.kind != "dropped")
    return fresh.cspace(), again.cspace(), cache


def test_cached_c_obstacles_answer_exactly_as_fresh_ones(tmp_path):
    V, F = sheet(z=0.5)
    scene = make_scene([box_body("box", (1, 0, 0)), Body("sheet", V, F, "t"),
                        box_body("far", (20, 0, 0))])
    a, b, _ = _cached_vs_fresh(scene, tmp_path)
    rng = np.random.default_rng(1)
    Q = rng.uniform(-2, 2, (4000, 3))
    # Points exactly on C-obstacle vertices too (touching decided exactly).
    Q = np.vstack([Q] + [o.vertices[:50] for o in a.obstacles])
    np.testing.assert_array_equal(a.contains(Q), b.contains(Q))
    np.testing.assert_array_equal(a.segment_free(Q[:1000], Q[1000:2000]),
                                  b.segment_free(Q[:1000], Q[1000:2000]))
    np.testing.assert_array_equal(a.first_contact(Q[:1000], Q[1000:2000]),
                                  b.first_contact(Q[:1000], Q[1000:2000]))
    np.testing.assert_array_equal(a.signed_distance(Q[:300]), b.signed_distance(Q[:300]))


def test_cached_solid_c_obstacle_answers_exactly_as_the_fresh_one(tmp_path):
    V, F = torus(1.0, 0.3, 12, 8)
    scene = make_scene([Body("torus", V, F, "test")], bounds=((-2, -2, -1), (2, 2, 1)))
    a, b, _ = _cached_vs_fresh(scene, tmp_path)
    assert a.obstacles[0].kind == b.obstacles[0].kind == "mesh"
    np.testing.assert_array_equal(a.obstacles[0].vertices, b.obstacles[0].vertices)
    rng = np.random.default_rng(3)
    Q = np.vstack([rng.uniform(-1.6, 1.6, (3000, 3)), a.obstacles[0].vertices[:200]])
    np.testing.assert_array_equal(a.contains(Q), b.contains(Q))
    np.testing.assert_array_equal(a.segment_free(Q[:1000], Q[1000:2000]),
                                  b.segment_free(Q[:1000], Q[1000:2000]))
    np.testing.assert_array_equal(a.signed_distance(Q[:500]), b.signed_distance(Q[:500]))


def test_corrupt_and_partial_cache_files_are_rebuilt(tmp_path):
    """A pack cut short is deleted, an entry that fails its digest is dropped: both rebuilt
    (into a new pack, which then answers); no temporary file is left."""
    from cspace.scene import cache as cache_module

    scene = make_scene([box_body("box", (1, 0, 0))])
    folder = tmp_path / "cache"
    _cached_vs_fresh(scene, tmp_path)
    (pack,) = list(folder.rglob("*.cspack"))
    data = pack.read_bytes()
    pack.write_bytes(data[: len(data) // 2])  # a partial write
    cache = COCache(folder)  # a new process reads what is on disk
    m = model_scene(scene, cache=cache)
    assert m.bodies[0].cache == "miss" and cache.rebuilt == 1 and not pack.exists()
    (pack,) = list(folder.rglob("*.cspack"))
    flipped = bytearray(pack.read_bytes())
    index = cache_module._read_index(pack)
    assert len(index) == 2  # the C-obstacle and the scene's snapshot (cspace.scene.snapshot)
    for _, spans, _ in index.values():  # a flipped bit inside each entry's payload
        flipped[int(spans.split("\n")[0].split("\t")[3]) + 8] ^= 0xFF
    pack.write_bytes(bytes(flipped))
    cache = COCache(folder)
    m = model_scene(scene, cache=cache)
    assert m.bodies[0].cache == "miss" and cache.rebuilt == 2
    assert len(list(folder.rglob("*.cspack"))) == 2  # the corrupt one and the rebuilt one
    cache = COCache(folder)
    assert model_scene(scene, cache=cache).bodies[0].cache == "hit"  # the newer pack answers
    assert cache.rebuilt == 0
    assert not list(folder.rglob("*.tmp"))


def test_cache_packs_are_shared_between_writers_and_old_entries_still_read(tmp_path):
    """Two caches on one folder (two processes) each write their own pack; a third reads both.
    An entry of the older layout (one .npz per key) is read as before."""
    from cspace.scene import cache as cache_module

    folder = tmp_path / "cache"
    one, two = COCache(folder), COCache(folder)
    a = {"x": np.arange(5, dtype=np.int64), "y": np.eye(3)}
    b = {"x": np.arange(3, dtype=np.int32).reshape(1, 3), "s": np.array("text")}
    one.store("a" * 64, a)
    two.store("b" * 64, b)
    assert one.load("a" * 64) is not None and not list(folder.rglob("*.cspack"))  # kept
    assert one.flush() and two.flush() and one.flush() is None
    third = COCache(folder)
    for key, want in (("a" * 64, a), ("b" * 64, b)):
        got = third.load(key)
        assert sorted(got) == sorted(want)
        for name in want:
            assert got[name].dtype == want[name].dtype and np.array_equal(got[name], want[name])
    assert third.keys() == {"a" * 64, "b" * 64} and third.load("c" * 64) is None
    # the older layout
    key = "c" * 64
    old = folder / key[:2] / f"{key}.npz"
    old.parent.mkdir(parents=True)
    np.savez(old, x=a["x"], _key=np.array(key), _digest=np.array(cache_module._digest({"x": a["x"]})),
             _format=np.array(str(cache_module.FORMAT)))
    assert np.array_equal(COCache(folder).load(key)["x"], a["x"])


def test_a_cache_writes_what_it_kept_when_it_goes_away(tmp_path):
    import gc

    cache = COCache(tmp_path)
    cache.store("d" * 64, {"x": np.ones(4)})
    del cache
    gc.collect()
    assert COCache(tmp_path).load("d" * 64) is not None


def test_an_unwritable_cache_warns_and_still_builds(tmp_path):
    blocker = tmp_path / "not-a-folder"
    blocker.write_text("a file where the cache folder should be")
    scene = make_scene([box_body("box", (1, 0, 0))])
    with pytest.warns(UserWarning, match="cannot write"):
        m = model_scene(scene, cache=blocker / "cache")
    assert m.bodies[0].cache == "miss" and not m.bodies[0].error
    assert len(m.cspace()) == 1


def test_cache_key_follows_the_inputs_and_location_follows_the_environment(tmp_path,
                                                                          monkeypatch):
    monkeypatch.setenv("CSPACE_CACHE", str(tmp_path / "env-cache"))
    assert cache_dir() == tmp_path / "env-cache"
    assert cache_dir(tmp_path / "x") == tmp_path / "x"
    scene = make_scene([box_body("box", (1, 0, 0))])
    assert model_scene(scene, cache=True).bodies[0].cache == "miss"
    assert len(COCache(tmp_path / "env-cache").keys()) == 2  # the C-obstacle, the scene's snapshot
    assert model_scene(scene, cache=True).bodies[0].cache == "hit"
    # Another robot size: another key.
    other = make_scene([box_body("box", (1, 0, 0))], robot_extent=0.3)
    assert model_scene(other, cache=True).bodies[0].cache == "miss"
    monkeypatch.delenv("CSPACE_CACHE")
    assert cache_dir() == Path.home() / ".cache" / "cspace"


# --------------------------------------------------------------------------------------
# shipped scenes and solids


def test_shipped_scenes_drop_what_the_robot_cannot_reach():
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        counts = {n: model_scene(load_scene(SCENES / f"{n}.toml"), build=False).counts()
                  for n in ("window", "comb", "maze", "cavity")}
    assert counts["window"] == {"convex": 4, "solid": 0, "surface": 0, "dropped": 0}
    assert counts["cavity"] == {"convex": 8, "solid": 0, "surface": 0, "dropped": 1}
    assert counts["comb"]["dropped"] > 0 and counts["comb"]["surface"] == 0


def test_solid_body_builds_and_agrees_with_fcl():
    V, F = torus(1.0, 0.3, 12, 8)
    scene = make_scene([Body("torus", V, F, "test")], bounds=((-2, -2, -1), (2, 2, 1)))
    m = model_scene(scene)
    (b,) = m.bodies
    assert b.kind == "solid" and "genus 1" in b.reason
    assert not b.error and b.co is not None and b.co.kind == "mesh"
    cs = m.cspace()
    rng = np.random.default_rng(0)
    Q = rng.uniform(scene.bounds[0], scene.bounds[1], (2000, 3))
    # FCL on the raw scene (m.robot is the model's snapped hull: not the oracle's).
    inside = SceneOracle(scene).collides(Q)
    assert 200 < inside.sum() < 1800  # the samples meet the torus's C-obstacle and miss it
    assert (cs.contains(Q) != inside).sum() == 0


# --------------------------------------------------------------------------------------
# shared data: what the report says, checked against independent inspection


def fcl_env_scene(shared_data) -> Scene:
    """scenes/shared/fcl_env.toml: FCL's test environment (85 bodies in one open triangle
    soup) with its robot, planned in the central part of the environment."""
    assert shared_data.is_dir()
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # rob.obj is not closed: its hull is used
        return load_scene(SCENES / "shared" / "fcl_env.toml")


def test_fcl_environment_report(shared_data):
    scene = fcl_env_scene(shared_data)
    m = model_scene(scene, build=False)
    assert m.sources["env.obj"]["parts"] == 85
    assert m.counts() == {"convex": 13, "solid": 0, "surface": 21, "dropped": 51}
    # Independent inspection of each part: trimesh's watertightness and convexity, and a
    # float bounding-box test with a margin far above the grid step.
    welded = trimesh.Trimesh(scene.obstacles[0].vertices, scene.obstacles[0].faces)
    labels = trimesh.graph.connected_components(
        welded.face_adjacency, nodes=np.arange(len(welded.faces)), engine="scipy")
    parts = welded.submesh(labels, append=False)
    assert len(parts) == 85
    r = m.robot.vertices - scene.reference_point
    lo_b, hi_b = scene.bounds
    by_box = {}
    for p in parts:
        key = tuple(np.round(p.bounds.ravel(), 3))
        by_box[key] = p
    explain = m.explain()
    for b in m.bodies:
        p = by_box[tuple(np.round(np.stack([b.vertices.min(0), b.vertices.max(0)]).ravel(), 3))]
        co_lo, co_hi = p.bounds[0] - r.max(0), p.bounds[1] - r.min(0)
        misses = (co_hi < lo_b - 1e-6).any() or (co_lo > hi_b + 1e-6).any()
        meets = (co_hi > lo_b + 1e-6).all() and (co_lo < hi_b - 1e-6).all()
        assert misses or meets  # no part is within rounding of the bounds
        if misses:
            assert b.kind == "dropped", b.line()
        elif not p.is_watertight:
            assert b.kind == "surface" and "open" in b.reason, b.line()
        else:
            assert p.is_convex and b.kind == "convex", b.line()
        assert b.line() in explain


PARASOL_SOLIDS = {
    "bug_trap1.0/bug-trap.env": ("trap.obj", 3212, "genus 1"),
    "alpha1.6/alpha.env": ("alphaobstacle.obj", 972, "genus 0"),
    "flange_1.0/flange.env": ("obstacle.g", 990, "genus 5"),
}


@pytest.mark.parametrize("rel", sorted(PARASOL_SOLIDS))
def test_parasol_scenes_report_one_solid(shared_data, rel):
    # SOURCES.md: each obstacle is one closed 2-manifold (trap genus 1, alpha genus 0,
    # flange genus 5), none convex; no duplicates.
    name, triangles, genus = PARASOL_SOLIDS[rel]
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        scene = load_scene(shared_data / "parasol_open_ppl_env" / rel)
    m = model_scene(scene, build=False)
    assert m.counts() == {"convex": 0, "solid": 1, "surface": 0, "dropped": 0}
    (b,) = m.bodies
    assert b.name == name and len(b.faces) == triangles and genus in b.reason
    assert m.sources[name] == {"triangles": triangles, "collapsed": 0, "double_sided": 0,
                               "repeated": 0, "parts": 1}
    mesh = trimesh.Trimesh(b.vertices, b.faces)
    assert mesh.is_watertight and not mesh.is_convex
    assert f"{name}: solid" in m.explain()


def test_stick_bug_as_an_obstacle_is_closed_after_dropping_its_repeated_faces(shared_data):
    # SOURCES.md: stick-bug.obj lists every face twice (132 triangles, 66 duplicates; cspace's
    # mesh check names them "the same winding: a repeated face"); one copy of each is a
    # closed genus-0 body.
    m0 = trimesh.load(shared_data / "parasol_open_ppl_env" / "bug_trap1.0" / "stick-bug.obj",
                      force="mesh", process=False)
    scene = make_scene([Body("bug", m0.vertices * 0.05, m0.faces, "stick-bug.obj")],
                       bounds=((-30, -30, -30), (30, 30, 30)))
    m = model_scene(scene, build=False)
    assert m.sources["bug"]["repeated"] == 66 and m.sources["bug"]["double_sided"] == 0
    assert [b.kind for b in m.bodies] in (["solid"], ["convex"])
    assert trimesh.Trimesh(m.bodies[0].vertices, m.bodies[0].faces).is_watertight


def test_fcl_environment_builds_and_agrees_with_fcl(shared_data):
    # The robot's hull, as asked (its exact 4 open parts: test_fcl_environment_exact_robot).
    scene = fcl_env_scene(shared_data)
    m = model_scene(scene, robot_hull=True)
    cs = m.cspace()
    # 13 convex bodies (CVMS); 21 open ones as triangle pairs against the hull's facets, each
    # with the containment term of a sheet the robot could swallow whole
    kinds = [o.kind for o in cs.obstacles]
    assert kinds.count("convex") == 13 and kinds.count("pairs") == 21
    assert len(kinds) == 13 + 2 * 21 and kinds.count("mesh") == 21
    # FCL with each body's semantics: fcl.Convex solids for the convex parts, plain mesh
    # collision for the open ones; membership and distance on uniform and near-surface points.
    from cspace.check.cross_check import cross_check

    r = cross_check(cs, n=800, seed=2, band=1e-9)
    assert 100 < r["n_inside"] < 750
    assert r["n_disagree"] == 0, r["disagreements"][:5]
    assert r["max_distance_error"] <= 1e-9 * r["scene_size"]


@pytest.mark.slow
@pytest.mark.parametrize("rel", ["bug_trap1.0/bug-trap.env", "alpha1.6/alpha.env", "flange_1.0/flange.env"])
def test_parasol_solid_builds_and_agrees_with_fcl(shared_data, tmp_path, rel):
    # flange: a genus-5 obstacle and a 900-facet robot hull, about 80 s of NCC-CVMS here.
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        scene = load_scene(shared_data / "parasol_open_ppl_env" / rel)
    # The robot's hull, as asked: this test is about NCC-CVMS on real solids (the exact
    # robots of these problems: tests/test_ompl_app.py::test_real_robots_...).
    m = model_scene(scene, cache=tmp_path / "cache", robot_hull=True)
    (b,) = m.bodies
    assert b.kind == "solid" and not b.error and b.co.kind == "mesh"
    cs = m.cspace()
    from cspace.check.cross_check import cross_check

    r = cross_check(cs, n=4000, seed=0, band=1e-9)
    assert r["n_disagree"] == 0, r["disagreements"][:5]
    # FCL on the raw scene, with the robot's hull as the C-space was built (robot_hull=True).
    fcl_hit = SceneOracle(scene, robot_hull=True).collides(np.stack([scene.start, scene.goal]))
    ours = cs.contains(np.stack([scene.start, scene.goal]))
    np.testing.assert_array_equal(ours, fcl_hit)
    # The bug trap's query is free; the alpha puzzle's start interlocks the two alpha shapes and
    # the flange's robot starts threaded on the flange, so the robot's convex hull (what a
    # translational C-obstacle uses) meets the obstacle at the start (FCL agrees, above).
    assert ours.tolist() == ([False, False] if "bug_trap" in rel else [True, False])
    again = model_scene(scene, cache=tmp_path / "cache", robot_hull=True)
    assert again.bodies[0].cache == "hit"


@pytest.mark.slow
def test_fcl_environment_exact_robot(shared_data, tmp_path):
    # rob.obj exactly: 6 parts (two closed boxes split off at non-manifold edges, open and
    # non-manifold rest), every body paired with each part.
    m = model_scene(fcl_env_scene(shared_data), cache=tmp_path / "cache")
    assert sorted(p.kind for p in m.robot_parts) == ["convex"] * 2 + ["surface"] * 4
    cs = m.cspace()
    from cspace.check.cross_check import cross_check

    r = cross_check(cs, n=2000, seed=2, band=1e-9)
    assert r["n_disagree"] == 0, r["disagreements"][:5]


def test_a_far_unreachable_obstacle_does_not_coarsen_the_grid():
    # An obstacle at x = 1e12, as its own body and as a far part of the world's body: both
    # dropped before the grid is chosen, so the grid is the one of the scene without it.
    near = box_body("near", (1.0, 0.0, 0.0))
    far = box_body("far", (1e12, 0.0, 0.0))
    reference = model_scene(make_scene([near]), build=False)
    for bodies in ([near, far], [Body("world", np.vstack([near.vertices, far.vertices]),
                                      np.vstack([near.faces, far.faces + 8]), "w")]):
        m = model_scene(make_scene(bodies))
        assert m.grid.exponent == reference.grid.exponent
        dropped = [b for b in m.bodies if b.kind == "dropped"]
        assert len(dropped) == 1 and "far from the bounds" in dropped[0].reason
        kept = [b for b in m.bodies if b.kind != "dropped"]
        assert [b.kind for b in kept] == ["convex"]
        assert m.cspace().contains([0.4, 0.0, 0.0]) and not m.cspace().contains([-1.0, 0, 0])


def test_nesting_is_decided_exactly_not_by_boxes():
    # An inside-out box in the notch of an L (inside the L's box, outside its solid) is a body
    # of its own, turned outwards; the same box inside a big box's solid is a cavity.
    from zoo import l_shape

    V, F = l_shape(arm=2)  # [0, 3] x [0, 3] x [0, 1], the notch is [1, 3] x [1, 3]
    small = trimesh.creation.box((0.5, 0.5, 0.5))
    inverted = (small.vertices + [2.0, 2.0, 0.5], small.faces[:, ::-1])
    notch = Body("w", np.vstack([V, inverted[0]]), np.vstack([F, inverted[1] + len(V)]), "x")
    m = model_scene(make_scene([notch], bounds=((-1, -1, -1), (4, 4, 2))))
    assert [b.kind for b in m.bodies] == ["solid", "convex"]
    assert m.cspace().contains([2.0, 2.0, 0.5])
    big = trimesh.creation.box((2.0, 2.0, 2.0))
    hollow = Body("h", np.vstack([big.vertices, small.vertices]),
                  np.vstack([big.faces, small.faces[:, ::-1] + 8]), "x")
    m = model_scene(make_scene([hollow], bounds=((-3, -3, -3), (3, 3, 3))))
    assert [b.kind for b in m.bodies] == ["solid"] and "2 shells" in m.bodies[0].reason
    assert not m.cspace().contains([0.0, 0.0, 0.0])  # the cavity is wider than the robot


def test_boxes_touching_along_an_edge_or_at_a_vertex_are_two_solids():
    # One mesh of two closed boxes sharing an edge (a non-manifold edge of four triangles) or
    # a vertex: split into two convex solids, so a robot inside either box collides.
    a = trimesh.creation.box((1.0, 1.0, 1.0))
    for shift in ([1.0, 1.0, 0.0], [1.0, 1.0, 1.0]):
        b = trimesh.creation.box((1.0, 1.0, 1.0))
        b.apply_translation(shift)
        both = trimesh.util.concatenate([a, b])
        m = model_scene(make_scene([Body("two", both.vertices, both.faces, "x")],
                                   robot_extent=0.1))
        assert [b.kind for b in m.bodies] == ["convex", "convex"]
        assert m.cspace().contains([[0.0, 0.0, 0.0], shift]).all()


def test_surface_distance_with_no_candidates_left():
    # _by_piece on no rows yielded a piece of an empty array (IndexError): a surface
    # C-obstacle queried where every nearer box has been ruled out.
    from cspace.cobstacle.surface import _UnionCO

    assert list(_UnionCO._by_piece(np.zeros(0, np.int64), np.zeros(0, np.int64))) == []


@pytest.mark.parametrize("move", [0, 1], ids=["as given", "at (250, 150, -300)"])
@pytest.mark.parametrize("case", ["NCC-CVMS", "several bodies", "open obstacle x convex robot",
                                  "folded closed body"])
def test_lazy_cspace_answers_as_the_built_one(case, move):
    """LazyCSpace builds a pair only when a query meets its box: the same answers as the
    eager build, one state at a time and in batches, with only the pairs near queries built."""
    from metamorphic import CASES, GRID_MOVES, moved_scene, samples

    from cspace.scene.model import LazyCSpace

    scene = moved_scene(CASES[case], GRID_MOVES[move])
    eager = model_scene(scene).cspace()
    lazy = LazyCSpace(model_scene(scene, build=False))
    assert not lazy.obstacles and lazy.memory == model_scene(scene).memory
    Q = samples(scene, 600, 5)
    want = eager.contains(Q)
    assert [bool(lazy.contains(q)) for q in Q[:150]] == want[:150].tolist()
    assert np.array_equal(lazy.contains(Q), want)
    Q1 = Q[::-1].copy()
    assert np.array_equal(lazy.segment_free(Q, Q1), eager.segment_free(Q, Q1))
    assert [bool(lazy.segment_free(a, b)) for a, b in zip(Q[:100], Q1[:100])] \
        == eager.segment_free(Q[:100], Q1[:100]).tolist()
    assert np.array_equal(lazy.first_contact(Q[:80], Q1[:80]), eager.first_contact(Q[:80], Q1[:80]),
                          equal_nan=True)
    assert 0 < want.sum() < len(Q)
