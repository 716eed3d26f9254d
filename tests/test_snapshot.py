"""A scene's snapshot (cspace.scene.snapshot): a second build of the same input restores the
model and the convex C-obstacles from one cache entry, and must be the model the build makes.

Checked field by field against a build without any cache (not against the first cached
build: a bug shared by the writer and the reader would hide there), on a scene of every
kind of body, far from the origin, with a convex and a non-convex robot; queries compared on
random points and on the C-obstacles' own vertices.
"""

from __future__ import annotations

import re

import numpy as np
import pytest
import trimesh

from cspace.scene import model as model_module
from cspace.scene.cache import COCache
from cspace.scene.model import model_scene
from cspace.scene.scene import Body, Scene
from cspace.scene import snapshot
from cspace.scene.snapshot import snapshot_key

from zoo import l_shape, pierced_box, random_rotation

AT = np.array([250.0, 150.0, -300.0])


def _box(name, centre, extents=(1.0, 1.0, 1.0), turn=None):
    m = trimesh.creation.box(extents=extents)
    V = m.vertices if turn is None else random_rotation(m.vertices, seed=turn)
    return Body(name, V + AT + np.asarray(centre, float), m.faces, "box")


def _bodies():
    V, F = l_shape()
    L = Body("L", np.asarray(V, float) * 0.5 + AT + [-2.5, 1.0, 0.0], F, "test")
    s = np.array([[0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, 0]], float) + AT + [0.0, -2.5, 0.5]
    sheet = Body("sheet", s, [[0, 1, 2], [0, 2, 3]], "test")
    two_sided = Body("two-sided", s + [0, 0, 1], [[0, 1, 2], [0, 2, 3], [2, 1, 0], [3, 2, 0]],
                     "test")
    near, far = _box("w", (2.0, 2.0, 0.0)), _box("w", (1e6, 0.0, 0.0))
    world = Body("world", np.vstack([near.vertices, far.vertices]),
                 np.vstack([near.faces, far.faces + 8]), "test")
    dust = Body("dust", AT + [[0.0, 0, 0], [1e-12, 0, 0], [0, 1e-12, 0]], [[0, 1, 2]], "test")
    # a box cut through by a sheet thinner than the step: what snapping took is its inside
    V, F = pierced_box("cut", 1e-9)
    cut = Body("cut", V * 0.5 + AT + [2.0, -2.0, -1.5], F, "test")
    return [_box("a", (1.0, 0.0, 0.0)), _box("b", (-1.0, -1.0, 0.5), (0.5, 2.0, 0.3)),
            _box("turned", (0.0, 2.0, -1.0), (0.7, 0.4, 0.9), turn=3), L, sheet, two_sided,
            world, dust, cut, _box("out", (40.0, 0.0, 0.0))]


def _scene(robot: Body, bodies=None) -> Scene:
    lo, hi = AT - 3.0, AT + 3.0
    return Scene("snap", None, tuple(_bodies() if bodies is None else bodies), robot, AT,
                 (lo, hi), lo + 0.01, hi - 0.01)


def _robot(kind: str) -> Body:
    if kind == "box":
        m = trimesh.creation.box(extents=(0.3, 0.2, 0.1))
        return Body("robot", m.vertices + AT, m.faces, "box")
    V, F = l_shape()
    return Body("robot", np.asarray(V, float) * 0.1 + AT, F, "test")


def _same_arrays(a, b, what):
    if a is None or b is None:
        assert a is None and b is None, what
        return
    a, b = np.asarray(a), np.asarray(b)
    assert a.dtype == b.dtype and a.shape == b.shape, what
    np.testing.assert_array_equal(a, b, err_msg=what)


def _same_polytope(p, q, what):
    for f in ("ints", "facet_offsets", "facet_indices", "normals", "edges", "edge_facets"):
        _same_arrays(getattr(p, f), getattr(q, f), f"{what}: {f}")
    assert (p.grid, p.excess, p.name) == (q.grid, q.excess, q.name), what


def _timeless(text: str) -> str:
    text = re.sub(r"; built in [0-9.]+ s \(cache \w+\)", "", text)
    text = re.sub(r"; [0-9.]+ s \(cache \w+\)", "", text)
    return re.sub(r"modelling [0-9.]+ s, building [0-9.]+ s", "", text)


def _same_model(m, r):
    """``r`` (restored) is ``m`` (made without a cache), field by field."""
    assert (m.grid, m.margin, m.robot_hull, m.memory) == (r.grid, r.margin, r.robot_hull,
                                                            r.memory)
    assert m.sources == r.sources
    assert [b.name for b in m.bodies] == [b.name for b in r.bodies]
    for a, b in zip(m.bodies, r.bodies):
        what = f"body {a.name}"
        assert (a.source, a.kind, a.reason, a.changed, a.pieces, a._sheet, a.error) == \
               (b.source, b.kind, b.reason, b.changed, b.pieces, b._sheet, b.error), what
        assert (a._encloses is None) == (b._encloses is None), what
        if a._encloses is not None:
            _same_arrays(a._encloses.ints, b._encloses.ints, f"{what}: enclosed ints")
            _same_arrays(a._encloses.faces, b._encloses.faces, f"{what}: enclosed faces")
        for f in ("vertices", "faces", "_ints", "_keep"):
            _same_arrays(getattr(a, f), getattr(b, f), f"{what}: {f}")
        if a.kind == "convex":
            _same_polytope(a._solid, b._solid, what)
        if a.kind == "solid":
            for f in ("ints", "faces", "components"):
                _same_arrays(getattr(a._solid, f), getattr(b._solid, f), f"{what}: solid {f}")
            assert (a._solid.grid, a._solid.name) == (b._solid.grid, b._solid.name), what
        assert [(p.part, p.construction, len(p.cos)) for p in a.pairs] == \
               [(p.part, p.construction, len(p.cos)) for p in b.pairs], what
        assert (a.co is None) == (b.co is None), what
        for x, y in zip(a.cos, b.cos):
            assert (x.kind, x.margin, x.excess, x.error_bound) == \
                   (y.kind, y.margin, y.excess, y.error_bound), what
            _same_arrays(x.vertices, y.vertices, f"{what}: C-obstacle vertices")
            _same_arrays(x.faces, y.faces, f"{what}: C-obstacle faces")
            if x.kind == "convex":
                _same_polytope(x.polytope, y.polytope, f"{what}: C-obstacle")
                assert x.obstacle is a._solid and y.obstacle is b._solid
    assert m.error_bound == r.error_bound
    assert _timeless(m.explain()) == _timeless(r.explain())
    a, b = m.cspace(), r.cspace()
    rng = np.random.default_rng(5)
    Q = np.vstack([rng.uniform(AT - 3, AT + 3, (3000, 3))]
                  + [o.vertices[:40] for o in a.obstacles])
    np.testing.assert_array_equal(a.contains(Q), b.contains(Q))
    np.testing.assert_array_equal(a.segment_free(Q[:1500], Q[1500:3000]),
                                  b.segment_free(Q[:1500], Q[1500:3000]))


@pytest.mark.parametrize("robot", ["box", "L"])
def test_a_restored_model_is_the_model_a_build_makes(tmp_path, robot):
    scene = _scene(_robot(robot))
    reference = model_scene(scene)  # no cache at all
    kinds = {b.kind for b in reference.bodies}
    assert kinds == {"convex", "solid", "surface", "dropped"}, kinds
    assert any(b.changed and b.kind == "convex" for b in reference.bodies)  # the turned box
    cache = COCache(tmp_path)
    first = model_scene(scene, cache=cache)
    key = snapshot_key(scene, None, False, True, True)
    assert key in cache.keys()
    cache = COCache(tmp_path)  # a new process's cache: everything read from the pack
    restored = model_scene(scene, cache=cache)
    _same_model(reference, first)
    _same_model(reference, restored)
    assert all(b.cache == "hit" for b in restored.bodies if b.kind != "dropped")


def test_a_snapshot_restores_convex_bodies_without_modelling_them(tmp_path, monkeypatch):
    rng = np.random.default_rng(0)
    bodies = [_box(f"b{i}", rng.uniform(-2.5, 2.5, 3), rng.uniform(0.1, 0.4, 3))
              for i in range(60)]
    scene = _scene(_robot("box"), bodies)
    model_scene(scene, cache=tmp_path)
    calls = []
    real = model_module.weld_split
    monkeypatch.setattr(model_module, "weld_split", lambda *a: calls.append(a) or real(*a))
    restored = model_scene(scene, cache=tmp_path)
    assert len(calls) == 1  # the robot's; no obstacle body is welded again
    assert restored.counts()["convex"] == 60
    monkeypatch.undo()
    _same_model(model_scene(scene), restored)


def test_a_snapshot_restores_solids_without_checking_them_again(tmp_path, monkeypatch):
    """Non-convex solids (L-shapes) come back validated: no classification, no
    self-intersection test per load (they were most of a cached 10^4-body load)."""
    import cspace.scene.classify as classify_module

    V, F = l_shape()
    bodies = [Body(f"L{i}", (V - V.mean(axis=0)) * 0.3 + AT + [i * 0.6 - 2.5, 0, 0], F, "L")
              for i in range(8)]
    scene = _scene(_robot("box"), bodies)
    made = model_scene(scene, cache=tmp_path)
    assert made.counts()["solid"] == 8
    calls = []
    real = classify_module._closed_kind
    monkeypatch.setattr(classify_module, "_closed_kind",
                        lambda *a: calls.append(a) or real(*a))
    restored = model_scene(scene, cache=COCache(tmp_path))
    assert calls == [] and restored.counts()["solid"] == 8
    monkeypatch.undo()
    _same_model(model_scene(scene), restored)


def test_the_snapshot_key_follows_every_input(monkeypatch):
    scene = _scene(_robot("box"))
    key = snapshot_key(scene, None, False, True, True)
    assert key == snapshot_key(_scene(_robot("box")), None, False, True, True)
    bodies = _bodies()
    V = bodies[0].vertices.copy()
    V[0, 0] = np.nextafter(V[0, 0], np.inf)  # one ulp
    moved = [Body(bodies[0].name, V, bodies[0].faces, "box")] + bodies[1:]
    renamed = [Body("A", bodies[0].vertices, bodies[0].faces, "box")] + bodies[1:]
    swapped = [bodies[1], bodies[0]] + bodies[2:]
    others = [snapshot_key(_scene(_robot("box"), b), None, False, True, True)
              for b in (moved, renamed, swapped)]
    others.append(snapshot_key(_scene(_robot("L")), None, False, True, True))
    others += [snapshot_key(scene, None, True, True, True),
               snapshot_key(scene, None, False, False, True),
               snapshot_key(scene, None, False, True, False),
               snapshot_key(scene, model_scene(scene, build=False).grid, False, True, True)]
    wider = Scene("snap", None, scene.obstacles, scene.robot, AT,
                  (AT - 3.0, AT + 3.5), scene.start, scene.goal)
    others.append(snapshot_key(wider, None, False, True, True))
    # other code (the same version number): a snapshot holds the outcome of its rules
    monkeypatch.setattr(snapshot, "_code", lambda: "0.1.0 another source")
    others.append(snapshot_key(scene, None, False, True, True))
    assert len(set(others) | {key}) == len(others) + 1


def test_a_snapshot_that_does_not_read_is_not_used(tmp_path):
    from cspace.scene.snapshot import Snapshot

    assert Snapshot.read(None) is None
    assert Snapshot.read({"meta": np.frombuffer(b"{not json", dtype=np.uint8)}) is None
    scene = _scene(_robot("box"))
    cache = COCache(tmp_path)
    first = model_scene(scene, cache=cache)
    key = snapshot_key(scene, None, False, True, True)
    arrays = dict(cache.load(key, count=False))
    del arrays["codes"]
    assert Snapshot.read(arrays) is None
    # A corrupt pack: every entry fails its digest, the scene is modelled and built again.
    for p in (tmp_path / "packs").glob("*.cspack"):
        data = bytearray(p.read_bytes())
        data[:4096] = bytes(b ^ 0xFF for b in data[:4096])
        p.write_bytes(bytes(data))
    again = model_scene(scene, cache=COCache(tmp_path))
    _same_model(first, again)


def test_builds_sharing_their_obstacles_leave_no_snapshot(tmp_path):
    # Orientation slices (memo): the obstacles are modelled once for all slices; a snapshot
    # per slice would store that model once per slice.
    scene = _scene(_robot("box"))
    cache = COCache(tmp_path)
    m = model_scene(scene, cache=cache, memo={})
    assert snapshot_key(scene, None, False, True, True) not in cache.keys()
    assert len(cache.keys()) == sum(len(b.pairs) for b in m.bodies)  # the C-obstacles' own
    again = model_scene(scene, cache=COCache(tmp_path), memo={})
    _same_model(model_scene(scene), again)
