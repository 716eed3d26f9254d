"""The command line mirrors the Python API and reports bad input as an error, not a trace."""

from __future__ import annotations

import subprocess
import sys

import numpy as np
import pytest
import trimesh

from cspace import CSpace, load_scene
from cspace.cli import main


def test_convex_sum_writes_the_sum(tmp_path, capsys):
    a, b, out = tmp_path / "a.stl", tmp_path / "b.stl", tmp_path / "sum.stl"
    trimesh.creation.box((2, 2, 2)).export(a)
    trimesh.creation.box((1, 1, 1)).export(b)
    assert main(["convex-sum", str(a), str(b), "-o", str(out), "--reflect-b", "0", "0", "0"]) == 0
    text = capsys.readouterr().out
    assert "6 facets" in text and "volume 27" in text
    mesh = trimesh.load(out)
    assert mesh.is_watertight
    assert np.isclose(mesh.volume, 27.0)


def test_convex_sum_reports_flat_input(tmp_path, capsys):
    a = tmp_path / "flat.obj"
    a.write_text("v 0 0 0\nv 1 0 0\nv 0 1 0\nv 1 1 0\nf 1 2 3\nf 2 4 3\n")
    assert main(["convex-sum", str(a), str(a)]) == 2
    assert "coplanar" in capsys.readouterr().err


def test_console_script_help_runs():
    out = subprocess.run([sys.executable, "-m", "cspace", "--help"], capture_output=True, text=True, check=True)
    assert "convex-sum" in out.stdout


def test_superset_of_a_torus(tmp_path, capsys):
    a, b = tmp_path / "torus.stl", tmp_path / "box.stl"
    trimesh.creation.torus(1.0, 0.3, major_sections=16, minor_sections=8).export(a)
    trimesh.creation.box((0.2, 0.2, 0.2)).export(b)
    assert main(["superset", str(a), str(b), "--reflect-b", "0", "0", "0", "-o", str(tmp_path / "s.ply")]) == 0
    out = capsys.readouterr().out
    assert "closed: True" in out and "corner multiplicities from -1 to 1" in out
    assert (tmp_path / "s.ply").exists()


def test_sum_of_a_torus_matches_the_python_api(tmp_path, capsys):
    import cspace

    a, b = tmp_path / "torus.stl", tmp_path / "box.stl"
    trimesh.creation.torus(1.0, 0.3, major_sections=16, minor_sections=8).export(a)
    trimesh.creation.box((0.2, 0.2, 0.2)).export(b)
    out_path = tmp_path / "sum.stl"
    assert main(["sum", str(a), str(b), "--reflect-b", "0", "0", "0", "-o", str(out_path), "--stats", "-q",
                 "--workers", "1"]) == 0
    out = capsys.readouterr().out
    assert "NCC-CVMS" in out and "0 hole(s)" in out and "arrangements:" in out
    assert "arrangement_processes: 1" in out
    written = trimesh.load(out_path, process=False)
    A = cspace.ClosedMesh.load(a)
    B = trimesh.load(b).vertices
    r = cspace.minkowski_sum(A, -B)
    assert len(written.faces) == len(r.faces)
    assert f"volume {r.volume:.9g}" in out


def test_superset_reports_an_open_mesh(tmp_path, capsys):
    box = trimesh.creation.box()
    open_box = trimesh.Trimesh(box.vertices, box.faces[:-1], process=False)
    a = tmp_path / "open.ply"
    open_box.export(a)
    assert main(["superset", str(a), str(a)]) == 2
    assert "boundary edges" in capsys.readouterr().err


SCENES = __import__("pathlib").Path(__file__).resolve().parents[1] / "scenes"


def test_view_writes_offline_html_of_a_shipped_scene(tmp_path, capsys):
    path = tmp_path / "path.txt"
    np.savetxt(path, [[-1.5, 0.7, 1.1], [-0.8, 0.0, 1.5], [0.8, 0.0, 1.5], [1.5, -0.7, 1.9]])
    out = tmp_path / "window.html"
    assert main(["view", str(SCENES / "window.toml"), "-o", str(out), "--path", str(path)]) == 0
    text = capsys.readouterr().out
    assert text.count("C-obstacle (CVMS") == 4 and "wrote" in text
    from test_viz import scene_commands

    html = out.read_text()
    paths = [str(c.get("path", "")) for c in scene_commands(html)]
    assert sum("cobstacles" in p for p in paths) >= 4 and any("/path/" in p for p in paths)
    # Offline: nothing fetched (the one URL in the page is an XML namespace).
    assert set(__import__("re").findall(r"https?://[^\s\"'<>)]+", html)) <= {"http://www.w3.org/1999/xhtml"}


def test_view_draws_the_free_space_or_says_why_not(tmp_path, capsys):
    """--free-space: the cage's two components, each its own node; a scene the exact free
    space does not take (a non-convex sum) is drawn without them, saying why."""
    out = tmp_path / "cage.html"
    assert main(["view", str(SCENES / "cage.toml"), "-o", str(out), "--free-space"]) == 0
    assert "free space: FreeSpace(components=2" in capsys.readouterr().out
    from test_viz import scene_commands

    paths = {str(c.get("path", "")) for c in scene_commands(out.read_text())}
    assert {"/meshcat/cells/free 0", "/meshcat/cells/free 1"} <= paths
    from zoo import l_shape

    V, F = l_shape()  # an L against a turned cube: a non-convex sum, off the union's grid
    trimesh.Trimesh(V, F, process=False).export(tmp_path / "l.obj")
    ell = tmp_path / "ell.toml"
    ell.write_text('name = "ell"\n[robot]\nbox = [0.3, 0.3, 0.3]\n'
                   'orientation = [17.0, -31.0, 52.0]\n[planning]\n'
                   'bounds = [[-2.0, -2.0, -2.0], [5.0, 5.0, 3.0]]\n'
                   'start = [-1.5, -1.5, -1.5]\ngoal = [4.5, 4.5, 2.5]\n'
                   '[[obstacles]]\nmesh = "l.obj"\n')
    assert main(["view", str(ell), "-o", str(tmp_path / "ell.html"), "--free-space"]) == 0
    assert "free space: not drawn: free_space: C-obstacle" in capsys.readouterr().out


def test_free_space_reports_components_and_writes_the_union(tmp_path, capsys):
    out = tmp_path / "union.stl"
    assert main(["free-space", str(SCENES / "cage.toml"), "-o", str(out), "--no-cache"]) == 0
    text = capsys.readouterr().out
    assert "components=2" in text and "separated" in text and "winds 1" in text
    mesh = trimesh.load(out)  # a closed 2-cycle (walls meeting along edges: non-manifold)
    F = np.asarray(mesh.faces)
    directed = {(int(a), int(b)) for f in F for a, b in zip(f, np.roll(f, -1))}
    assert all((b, a) in directed for a, b in directed) and mesh.volume > 0
    assert main(["free-space", str(SCENES / "window.toml"), "--no-cache"]) == 0
    assert "one component: a path exists" in capsys.readouterr().out
    assert main(["free-space", str(SCENES / "cage.toml"), "-o", str(tmp_path / "u.xyz")]) == 2
    assert "unknown format" in capsys.readouterr().err


def test_view_live_serves_and_stops_without_a_terminal(capsys):
    assert main(["view", str(SCENES / "comb.toml"), "--live"]) == 0
    assert "meshcat is serving the scene at http://127.0.0.1:" in capsys.readouterr().out


def test_view_reports_a_bad_scene(tmp_path, capsys):
    bad = tmp_path / "bad.toml"
    text = (SCENES / "window.toml").read_text().replace("[robot]", '[robot]\ncolour = "red"')
    bad.write_text(text.replace('mesh = "meshes/', f'mesh = "{SCENES}/meshes/'))
    assert main(["view", str(bad)]) == 2
    assert "colour" in capsys.readouterr().err


def test_check_cross_checks_a_shipped_scene_with_fcl(capsys):
    assert main(["check", str(SCENES / "comb.toml"), "-n", "2000"]) == 0
    out = capsys.readouterr().out
    assert "membership disagreements beyond 1e-09 of the surface: 0" in out
    assert "time per query" in out


def test_plan_writes_an_exactly_checked_path(tmp_path, capsys):
    out = tmp_path / "path.txt"
    assert main(["plan", str(SCENES / "comb.toml"), "--time", "2", "--seed", "1", "-o", str(out)]) == 0
    text = capsys.readouterr().out
    assert "solved" in text and "exact re-check: valid" in text
    path = np.loadtxt(out)
    assert path.ndim == 2 and path.shape[1] == 3 and len(path) >= 2
    from cspace import CSpace, load_scene

    cs = CSpace.from_scene(load_scene(SCENES / "comb.toml"))
    assert (cs.segment_free(path[:-1], path[1:])).all() and not cs.contains(path).any()


@pytest.fixture(autouse=True)
def _private_cache(tmp_path, monkeypatch):
    """Every CLI test gets its own cache folder (the default would be ~/.cache/cspace)."""
    monkeypatch.setenv("CSPACE_CACHE", str(tmp_path / "cache"))


def test_build_explains_caches_and_writes(tmp_path, capsys):
    out = tmp_path / "cos.npz"
    assert main(["build", str(SCENES / "cavity.toml"), "--explain", "-o", str(out),
                 "--progress"]) == 0
    captured = capsys.readouterr()
    text = captured.out
    assert "9 obstacle bodies -> 9 modelled: 8 convex, 0 solid, 0 surface, 1 dropped" in text
    assert "floor: dropped (12 triangles): its C-obstacle's bounding box" in text
    assert text.count("(cache miss)") == 8 and "(0 from the cache)" in text
    assert "[100%] 8 C-obstacles" in captured.err  # progress lines on stderr, as asked
    data = np.load(out)
    assert list(data["kinds"]) == ["convex"] * 8 and "wall-xmin" in list(data["names"])
    cs = CSpace.from_scene(load_scene(SCENES / "cavity.toml"))
    np.testing.assert_array_equal(data["vertices_0"], cs.obstacles[0].vertices)
    # Second run: every C-obstacle from the cache; --quiet silences the progress.
    assert main(["build", str(SCENES / "cavity.toml"), "--explain", "-q"]) == 0
    captured = capsys.readouterr()
    assert captured.out.count("(cache hit)") == 8 and captured.err == ""
    assert main(["build", str(SCENES / "cavity.toml"), "--no-cache", "--explain"]) == 0
    captured = capsys.readouterr()  # not a terminal and no --progress: quiet
    assert captured.out.count("(cache off)") == 8 and captured.err == ""


def test_plan_explain_reports_the_model_then_plans(capsys):
    assert main(["plan", str(SCENES / "comb.toml"), "--explain", "--time", "2", "--seed", "1",
                 "-q", "--no-cache"]) == 0
    text = capsys.readouterr().out
    assert "17 obstacle bodies -> 17 modelled: 11 convex, 0 solid, 0 surface, 6 dropped" in text
    assert "front-spine: dropped" in text and "back-tooth-1: convex" in text
    # the stated bound, one-sided (the comb's coordinates are not all on the grid: it grows)
    assert "error bound " in text and "never a false free" in text
    assert text.index("modelled") < text.index("auto (RRTConnect) solved")


def test_build_of_a_solid_body_builds_it(tmp_path, capsys):
    # A closed non-convex body (a torus) takes NCC-CVMS and is built (exit 0).
    from zoo import torus

    V, F = torus(1.0, 0.3, 12, 8)
    trimesh.Trimesh(V, F, process=False).export(tmp_path / "torus.obj")
    (tmp_path / "t.toml").write_text(
        '[robot]\nbox = [0.2, 0.2, 0.2]\n[planning]\nbounds = [[-2, -2, -1], [2, 2, 1]]\n'
        'start = [-1.8, 0, 0]\ngoal = [1.8, 0, 0]\n[[obstacles]]\nname = "ring"\n'
        'mesh = "torus.obj"\n')
    code = main(["build", str(tmp_path / "t.toml"), "--explain", "-q"])
    captured = capsys.readouterr()
    assert f"ring: solid ({len(F)} triangles" in captured.out and "genus 1" in captured.out
    assert code == 0, captured.err
    assert "(cache miss)" in captured.out and "BUILD FAILED" not in captured.out


def test_one_progress_style_for_builds_and_sums(monkeypatch, capsys):
    # model_scene and minkowski_sum both call progress(fraction, message); a non-convex
    # body reports its NCC-CVMS stages while it is built (no silent long body).
    from cspace import minkowski_sum, model_scene
    from cspace.cli import _Progress
    from cspace.scene.scene import Body, Scene

    from zoo import l_shape

    calls = []
    V, F = l_shape()
    robot = trimesh.creation.box((0.2, 0.2, 0.2))
    scene = Scene("p", None, (Body("L", V, F, "l"),), Body("r", robot.vertices, robot.faces, "b"),
                  (0.0, 0.0, 0.0), ((-1, -1, -1), (4, 4, 2)), (-0.9, -0.9, -0.9),
                  (-0.8, -0.9, -0.9))
    model_scene(scene, progress=lambda f, m: calls.append((f, m)))
    stages = [m for _, m in calls]
    assert "L (solid): arrangements" in stages and stages[-1] == "1 C-obstacles"
    fractions = [f for f, _ in calls]
    assert fractions == sorted(fractions) and 0.0 <= fractions[0] and fractions[-1] == 1.0
    sums = []
    minkowski_sum((V, F), robot.vertices, progress=lambda f, m: sums.append((f, m)), workers=1)
    assert [m for _, m in sums][0] == "superset" and sums[-1] == (1.0, "rounding_check")
    assert [f for f, _ in sums] == sorted(f for f, _ in sums)
    # On a terminal: one status line rewritten in place, ended before other output.
    monkeypatch.setattr(sys.stderr, "isatty", lambda: True, raising=False)
    p = _Progress(quiet=False)
    p(0.25, "arrangements")
    p(0.5, "rounding_check")
    p.close()
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "\r[ 25%] arrangements" in err and "[ 50%]" in err


def test_first_plan_on_a_non_convex_scene_is_as_fast_as_the_next(tmp_path):
    """#18: the first `cspace plan` after an install, every cache empty (no C-obstacle cache,
    no JIT cache of any kind), solves a scene with a non-convex solid (NCC-CVMS, exact mesh
    queries) within a budget of 1 s, 100 times what it needs warm: no kernel is compiled at
    user time (numba's first calls here took about 4 s inside the planner's budget)."""
    import os
    import subprocess
    import sys

    from zoo import torus

    V, F = torus(1.0, 0.3, 24, 12)
    trimesh.Trimesh(V, F, process=False).export(tmp_path / "torus.obj")
    (tmp_path / "t.toml").write_text(
        '[robot]\nbox = [0.2, 0.2, 0.2]\n[planning]\nbounds = [[-2, -2, -1], [2, 2, 1]]\n'
        'start = [-1.8, 0, 0]\ngoal = [0, 0, 0]\n[[obstacles]]\nname = "ring"\n'
        'mesh = "torus.obj"\n')  # from outside the ring to its hole: around the solid
    env = dict(os.environ, CSPACE_CACHE=str(tmp_path / "cache"),
               NUMBA_CACHE_DIR=str(tmp_path / "numba"), PYTHONDONTWRITEBYTECODE="1")
    for run in range(2):
        out = subprocess.run([sys.executable, "-m", "cspace", "plan", str(tmp_path / "t.toml"),
                              "--seed", "1", "--time", "1", "-o",
                              str(tmp_path / f"path{run}.txt")],
                             env=env, capture_output=True, text=True, timeout=300)
        assert out.returncode == 0, out.stderr
        assert "solved" in out.stdout and "NOT solved" not in out.stdout
        assert (tmp_path / f"path{run}.txt").read_text().strip()


def test_version_and_exit_statuses_in_every_subcommands_help():
    from cspace import __version__

    r = subprocess.run([sys.executable, "-m", "cspace", "--version"], capture_output=True,
                       text=True)
    assert r.returncode == 0 and r.stdout.strip() == f"cspace {__version__}"
    for cmd in ("convex-sum", "superset", "sum", "check", "build", "plan", "benchmark",
                "free-space", "view"):
        r = subprocess.run([sys.executable, "-m", "cspace", cmd, "--help"], capture_output=True,
                           text=True)
        assert r.returncode == 0 and "exit status: 0 " in r.stdout, cmd
        assert "2 bad input" in r.stdout, cmd


def test_every_command_that_builds_takes_the_cache_memory_and_progress_flags(tmp_path, capsys):
    scene = str(SCENES / "comb.toml")
    assert main(["check", scene, "-n", "500", "-q", "--no-cache", "--memory", "2G"]) == 0
    assert main(["check", scene, "-n", "500", "-q", "--cache-dir", str(tmp_path)]) == 0
    assert any(tmp_path.iterdir())  # the check built through that cache
    out = tmp_path / "comb.html"
    assert main(["view", scene, "-o", str(out), "-q", "--no-cache", "--memory", "2G"]) == 0
    assert main(["free-space", str(SCENES / "cage.toml"), "-q", "--no-cache", "--memory",
                 "2G"]) == 0
    assert out.stat().st_size > 10000
    capsys.readouterr()


def test_an_open_robot_is_said_in_the_normal_output(tmp_path):
    """A robot mesh with two faces removed is planned as a surface: the normal output says
    so (not only --explain)."""
    box = trimesh.creation.box((0.3, 0.3, 0.3))
    box.faces = box.faces[2:]
    box.export(tmp_path / "robot.obj")
    (tmp_path / "s.toml").write_text(
        '[robot]\nmesh = "robot.obj"\n[planning]\nbounds = [[-2, -2, -2], [2, 2, 2]]\n'
        'start = [-1.5, 0, 0]\ngoal = [1.5, 0, 0]\n[[obstacles]]\nbox = [0.2, 1, 1]\n')
    r = subprocess.run([sys.executable, "-m", "cspace", "plan", str(tmp_path / "s.toml"),
                        "--seed", "1", "--no-cache"], capture_output=True, text=True)
    assert r.returncode == 0, r.stderr
    assert "robot robot.obj: modelled as a surface, not a solid (open: 4 boundary edges)" in r.stdout


def test_benchmark_writes_logs_that_ompls_statistics_script_reads(tmp_path, capsys):
    """``cspace benchmark`` runs OMPL's own Benchmark with the certified checks (and, with
    --sampled, OMPL.app's way beside it); OMPL's statistics script (the real one, as a user
    runs it) reads both logs into its database, one experiment each, every run recorded."""
    import sqlite3

    log, db = tmp_path / "comb.log", tmp_path / "comb.db"
    assert main(["benchmark", str(SCENES / "comb.toml"), "--planners", "RRTConnect",
                 "--runs", "2", "--time", "3", "--seed", "1", "--sampled", "-o", str(log),
                 "--db", str(db)]) == 0
    out = capsys.readouterr().out
    assert "comb.certified: RRTConnect: solved 2 of 2 runs" in out
    assert (tmp_path / "comb-sampled.log").exists()
    r = subprocess.run([sys.executable, "-m", "ompl.ompl_benchmark_statistics", str(log),
                        str(tmp_path / "comb-sampled.log"), "-d", str(tmp_path / "again.db")],
                       capture_output=True, text=True)
    assert r.returncode == 0, r.stderr
    for path in (db, tmp_path / "again.db"):
        with sqlite3.connect(path) as c:
            rows = c.execute("SELECT e.name, COUNT(*) FROM runs r JOIN experiments e "
                             "ON r.experimentid = e.id GROUP BY e.name").fetchall()
        assert sorted(rows) == [("comb.certified", 2), ("comb.sampled", 2)]
    assert main(["benchmark", str(SCENES / "comb.toml"), "--planners", "NoSuchPlanner",
                 "-o", str(tmp_path / "x.log")]) == 2
    assert not (tmp_path / "x.log").exists()
