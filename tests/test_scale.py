"""Scale-out builds (issue #20): ``model_scene(executor=...)`` on a real Dask ``LocalCluster``
(two worker processes) and a ``ProcessPoolExecutor`` gives the local build's C-obstacles,
exactly; cache hits are read here and never submitted; a worker's error is the body's error.

No mocks: the cluster is a real one on this machine (loopback only), started once for the
module (a few seconds) and closed by its fixture.
"""

from __future__ import annotations

import os
import subprocess
import sys
from concurrent.futures import Executor
from pathlib import Path

import numpy as np
import pytest
import trimesh

from cspace import CSpace, load_scene
from cspace.scene.cache import COCache
from cspace.cli import main as cli
from cspace.errors import BuildError, InvalidArgumentError, MissingDependencyError
from cspace.scene.model import model_scene
from cspace.planning.scale import build_slices, executor_for

# A Dask client leaves a thread in this process and spawned pools a resource tracker: after
# every other test (conftest), so that the fork tests see neither.
pytestmark = pytest.mark.last
from cspace.scene.scene import Body, Scene
from cspace.planning.orientations import Slices
from cspace.planning.turning import TurningCSpace
from zoo import l_shape  # tests/ is on sys.path (rootdir conftest)

distributed = pytest.importorskip("distributed")

ROOT = Path(__file__).resolve().parents[1]
BOUNDS = ((-3.0, -3.0, -1.5), (3.0, 3.0, 1.5))


def _box(name, centre, extents):
    m = trimesh.creation.box(extents=extents)
    return Body(name, m.vertices + np.asarray(centre, float), m.faces, "box")


def _scene(robot: Body, name: str) -> Scene:
    """Boxes, a non-convex solid (NCC-CVMS) and an open sheet (surface semantics)."""
    L, LF = l_shape()
    sheet = Body("sheet", np.array([[1.0, -2.5, 0.3], [2.5, -2.5, 0.3], [2.5, -1.0, 0.3],
                                    [1.0, -1.0, 0.3]]), np.array([[0, 1, 2], [0, 2, 3]]), "test")
    bodies = [_box(f"box{i}", (2.0 * np.cos(i), 2.0 * np.sin(i), 0.2 * i - 0.5),
                   (0.4 + 0.1 * i, 0.3, 0.5)) for i in range(5)]
    bodies += [Body("L", (L - L.mean(axis=0)) * 0.4 + (-0.5, 0.4, 0.0), LF, "zoo"), sheet]
    lo = np.asarray(BOUNDS[0])
    return Scene(name, None, bodies, robot, (0.05, 0.02, 0.0), BOUNDS, lo + 0.01, lo + 0.02)


@pytest.fixture(scope="module")
def scene():
    r = trimesh.creation.box(extents=(0.5, 0.3, 0.2))
    return _scene(Body("robot", r.vertices, r.faces, "box"), "scale")


@pytest.fixture(scope="module")
def l_robot_scene():
    """A non-convex robot: triangle pairs against every body (boxes, the L, the sheet)."""
    L, LF = l_shape()
    return _scene(Body("L-robot", (L - L.mean(axis=0)) * 0.15, LF, "zoo"), "scale-L")


@pytest.fixture(scope="module")
def client():
    with distributed.LocalCluster(n_workers=2, processes=True, threads_per_worker=1,
                                  dashboard_address=None) as cluster, \
            distributed.Client(cluster) as c:
        yield c


@pytest.fixture(scope="module")
def pool():
    with executor_for(None, 2) as ex:  # ProcessPoolExecutor, spawned workers
        yield ex


class Counting(Executor):
    """A real executor that counts what is submitted to it."""

    def __init__(self, inner):
        self.inner, self.submitted = inner, 0

    def submit(self, fn, /, *args, **kwargs):
        self.submitted += 1
        return self.inner.submit(fn, *args, **kwargs)


def _arrays(m):
    """Every C-obstacle's arrays, in the model's order (name, kind, vertices, faces, margin)."""
    return [(b.name, p.part, p.construction, co.kind, np.asarray(co.vertices),
             np.asarray(co.faces), co.margin.steps)
            for b in m.bodies for p in b.pairs for co in p.cos]


def assert_same(a, b, bounds=BOUNDS, n=3000):
    """Same C-obstacle arrays, same C-space answers on random queries."""
    A, B = _arrays(a), _arrays(b)
    assert len(A) == len(B) > 0
    for x, y in zip(A, B):
        assert x[:4] == y[:4] and x[6] == y[6]
        assert np.array_equal(x[4], y[4]) and np.array_equal(x[5], y[5]), x[0]
    ca, cb = a.cspace(), b.cspace()
    q = np.random.default_rng(7).uniform(*bounds, (2 * n, 3))
    assert np.array_equal(ca.contains(q), cb.contains(q))
    assert np.array_equal(ca.segment_free(q[:n], q[n:]), cb.segment_free(q[:n], q[n:]))
    assert ca.contains(q).any() and not ca.contains(q).all()


def test_cluster_and_process_pool_build_what_the_local_build_builds(scene, client, pool):
    local = model_scene(scene)
    kinds = {b.kind for b in local.bodies}
    assert {"convex", "solid", "surface"} <= kinds
    seen = []
    on_cluster = model_scene(scene, executor=client.get_executor(pure=False),
                             progress=lambda f, msg: seen.append(f))
    assert_same(local, on_cluster)
    assert seen and seen[-1] == 1.0 and seen == sorted(seen)
    assert_same(local, model_scene(scene, executor=pool))
    assert all(b.cache == "off" and not b.error for b in on_cluster.bodies)


def test_non_convex_robot_parts_through_the_cluster(l_robot_scene, client):
    local = model_scene(l_robot_scene)
    constructions = {p.construction for b in local.bodies for p in b.pairs}
    assert constructions == {"triangle pairs"}
    assert_same(local, model_scene(l_robot_scene, executor=client.get_executor(pure=False)))


def test_cache_hits_are_read_here_and_never_submitted(scene, client, tmp_path):
    ex = Counting(client.get_executor(pure=False))
    first = model_scene(scene, cache=tmp_path, executor=ex)
    built = sum(len(b.pairs) for b in first.bodies)
    assert ex.submitted > 0 and all(b.cache == "miss" for b in first.bodies if b.pairs)
    assert len(COCache(tmp_path).keys()) == built + 1  # written here, and the scene's snapshot
    ex.submitted = 0
    second = model_scene(scene, cache=tmp_path, executor=ex)
    assert ex.submitted == 0
    assert all(b.cache == "hit" for b in second.bodies if b.pairs)
    assert_same(model_scene(scene), second)
    assert_same(first, model_scene(scene, cache=tmp_path))  # the local build reads them too


def test_a_worker_error_is_the_bodys_error(scene, client, monkeypatch):
    # A real failure: NCC-CVMS reads $CSPACE_WORKERS and refuses a value that is no number.
    client.run(lambda: os.environ.__setitem__("CSPACE_WORKERS", "many"))
    try:
        remote = model_scene(scene, executor=client.get_executor(pure=False))
    finally:
        client.run(lambda: os.environ.pop("CSPACE_WORKERS", None))
    failed = {b.name: b.error for b in remote.bodies if b.error}
    assert list(failed) == ["L"]
    assert failed["L"].startswith("InvalidArgumentError: workers must be a positive integer")
    with pytest.raises(BuildError, match=r"body 'L' \(solid"):
        remote.cspace()
    monkeypatch.setenv("CSPACE_WORKERS", "many")
    local = model_scene(scene)
    assert {b.name: b.error for b in local.bodies if b.error} == failed


def test_build_slices_builds_what_turning_cspace_builds(scene, client, tmp_path):
    slices = Slices.about(3)
    built = build_slices(scene, slices, client.get_executor(pure=False), cache=tmp_path)
    assert sorted(built) == [0, 1, 2] and all(isinstance(cs, CSpace) for cs in built.values())
    files = sorted(tmp_path.rglob("*.cspack"))
    turning = TurningCSpace(scene, slices, cache=tmp_path)
    q = np.random.default_rng(3).uniform(*BOUNDS, (3000, 3))
    for k, cs in built.items():
        assert np.array_equal(cs.contains(q), turning.slice(k).contains(q)), k
    assert sorted(tmp_path.rglob("*.cspack")) == files  # the slices read what was built
    assert not np.array_equal(built[0].contains(q), built[1].contains(q))  # it turned
    assert build_slices(scene, slices, ks=[1])[1].contains(q).tolist() == \
        built[1].contains(q).tolist()


def test_executor_for(monkeypatch):
    assert executor_for(None, None) is None and executor_for(None, 1) is None
    with pytest.raises(InvalidArgumentError, match="workers"):
        executor_for(None, 0)
    with pytest.raises(InvalidArgumentError, match="its own"):
        executor_for("tcp://127.0.0.1:8786", 2)
    monkeypatch.setitem(sys.modules, "distributed", None)  # as if not installed
    with pytest.raises(MissingDependencyError, match=r"pip install 'dask\[distributed\]'"):
        executor_for("tcp://127.0.0.1:8786")


def test_cli_build_on_the_cluster(client, capsys):
    maze = str(ROOT / "scenes" / "maze.toml")
    address = client.scheduler.address
    assert cli(["build", maze, "--no-cache", "-q", "--scheduler", address]) == 0
    out = capsys.readouterr().out
    assert "built 22 C-obstacles" in out and f"on the Dask cluster at {address}" in out
    assert cli(["build", maze, "--no-cache", "-q", "--scheduler", address,
                "--workers", "2"]) == 2
    assert "its own workers" in capsys.readouterr().err
    assert len(client.scheduler_info()["workers"]) == 2  # the CLI closed only its client


def test_the_default_path_never_imports_dask():
    code = ("import sys, cspace, cspace.cli, cspace.planning.scale\n"
            "from cspace.scene.model import model_scene\n"
            f"model_scene(cspace.load_scene({str(ROOT / 'scenes' / 'window.toml')!r})).cspace()\n"
            "assert 'distributed' not in sys.modules and 'dask' not in sys.modules\n")
    proc = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                          timeout=120)
    assert proc.returncode == 0, proc.stderr[-2000:]


def test_maze_from_scene_through_the_pool(pool):
    maze = load_scene(ROOT / "scenes" / "maze.toml")
    q = np.random.default_rng(0).uniform(*maze.bounds, (2000, 3))
    assert np.array_equal(CSpace.from_scene(maze, executor=pool).contains(q),
                          CSpace.from_scene(maze).contains(q))
