"""Bad input and interruption on the command line: one line, exit 2 (130 for Ctrl-C), no
traceback, nothing half-written, no solution file for an unsolved problem."""

from __future__ import annotations

import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest
import trimesh

from cspace.errors import OutputError
from cspace.output import output_path, write_atomic

SCENES = Path(__file__).resolve().parents[1] / "scenes"


def cspace(*args, timeout=120, **kw):
    return subprocess.run([sys.executable, "-m", "cspace", *map(str, args)], capture_output=True,
                          text=True, timeout=timeout, **kw)


def one_line_error(r, code=2):
    assert r.returncode == code, r.stdout + r.stderr
    assert "Traceback" not in r.stderr
    lines = [x for x in r.stderr.splitlines() if x.startswith("cspace: ")]
    assert len(lines) == 1, r.stderr
    return lines[0]


@pytest.fixture
def boxes(tmp_path):
    a, b = tmp_path / "a.stl", tmp_path / "b.stl"
    trimesh.creation.box((2, 2, 2)).export(a)
    trimesh.creation.box((1, 1, 1)).export(b)
    return a, b


def test_bad_paths_and_formats_fail_before_the_work(tmp_path, boxes):
    a, b = boxes
    # Unknown output format: refused up front, nothing written.
    line = one_line_error(cspace("sum", a, b, "-o", tmp_path / "out.xyz1"))
    assert "unknown format '.xyz1'" in line
    assert not (tmp_path / "out.xyz1").exists()
    # A missing input file, a file that is no mesh, a folder that cannot be written.
    assert "mesh file not found" in one_line_error(cspace("convex-sum", tmp_path / "gone.stl", b))
    (tmp_path / "notes.txt").write_text("not a mesh\n")
    assert "notes.txt" in one_line_error(cspace("convex-sum", tmp_path / "notes.txt", b))
    assert "cannot create files" in one_line_error(   # (root may write anywhere: a file
        cspace("convex-sum", a, b, "-o", tmp_path / "notes.txt" / "out.stl"))  # as a folder)
    # Numbers out of range are argparse errors (exit 2, one usage line, no traceback).
    r = cspace("check", SCENES / "window.toml", "-n", "0")
    assert r.returncode == 2 and "Traceback" not in r.stderr and "'0' is not" in r.stderr
    r = cspace("plan", SCENES / "window.toml", "--seed", "-1")
    assert r.returncode == 2 and "Traceback" not in r.stderr and "'-1' is not" in r.stderr


def test_write_atomic_leaves_nothing_half_written(tmp_path):
    target = tmp_path / "deep" / "er" / "out.txt"   # parent folders: created on write
    write_atomic(target, lambda p: p.write_text("whole"))
    assert target.read_text() == "whole"

    def broken(p):
        p.write_text("half")
        raise RuntimeError("interrupted")

    with pytest.raises(RuntimeError):
        write_atomic(target, broken)
    assert target.read_text() == "whole"                 # the old file stands
    assert sorted(x.name for x in target.parent.iterdir()) == ["out.txt"]  # no temp left
    with pytest.raises(OutputError, match="cannot write '/dev/full'"):
        write_atomic("/dev/full", lambda p: p.write_text("x" * 10000))
    with pytest.raises(OutputError, match="unknown format"):
        output_path(tmp_path / "a.stl", ("npz",), "-o")
    (tmp_path / "x.npz").mkdir()
    with pytest.raises(OutputError, match="is a folder"):
        output_path(tmp_path / "x.npz", ("npz",), "-o")


def test_unsolved_plan_writes_no_path_and_says_so(tmp_path):
    # The cage's goal is shut in: RRTConnect (no decision, so no proof) never gets there,
    # however fast the machine.
    path, result = tmp_path / "p.txt", tmp_path / "r.json"
    r = cspace("plan", SCENES / "cage.toml", "--planner", "RRTConnect", "--seed", "1",
               "--time", "0.2", "-q", "-o", path, "--result", result,
               "--html", tmp_path / "v.html")
    assert r.returncode == 1 and "Traceback" not in r.stderr
    assert "NOT solved" in r.stdout and "no path written" in r.stderr
    assert "valid" not in r.stdout  # nothing was re-checked
    assert not path.exists()
    import json

    data = json.loads(result.read_text())
    assert data["solved"] is False and data["path"] is None and data["path_file"] is None
    assert (tmp_path / "v.html").exists()


def test_ctrl_c_during_a_long_build_is_one_line_and_leaves_nothing(tmp_path):
    # A torus sum big enough to be in its forked stages when the interrupt comes.
    from zoo import torus

    V, F = torus(sections=160, ring=80)
    trimesh.Trimesh(V, F, process=False).export(tmp_path / "torus.stl")
    trimesh.creation.icosphere(subdivisions=2, radius=0.1).export(tmp_path / "ball.stl")
    out = tmp_path / "sum.stl"
    p = subprocess.Popen([sys.executable, "-m", "cspace", "sum", str(tmp_path / "torus.stl"),
                          str(tmp_path / "ball.stl"), "-o", str(out), "--workers", "2",
                          "--progress"],
                         stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
                         start_new_session=True,
                         # as from a terminal: a test run started in the background (nohup,
                         # `cmd &`) ignores SIGINT, and Python keeps an inherited SIG_IGN
                         preexec_fn=lambda: signal.signal(signal.SIGINT, signal.SIG_DFL))
    # Interrupt in the middle of the forked arrangements (progress lines on stderr).
    seen = []
    for line in p.stderr:
        seen.append(line)
        if "arrangements" in line and len([x for x in seen if "arrangements" in x]) >= 5:
            break
    assert p.poll() is None, "the build finished before the interrupt"
    os.killpg(p.pid, signal.SIGINT)  # as a terminal's Ctrl-C: the whole process group
    _, rest = p.communicate(timeout=60)
    err = "".join(seen) + rest
    assert p.returncode == 130, err
    assert "Traceback" not in err, err
    assert err.strip().splitlines()[-1] == "cspace: interrupted", err
    assert not out.exists() and list(tmp_path.glob(".sum.stl*")) == []
    # No process of that group is left (its children may take a moment to go on a busy
    # machine: waited for, up to a minute, never a fixed sleep).
    for _ in range(600):
        try:
            os.killpg(p.pid, 0)
        except ProcessLookupError:
            break
        time.sleep(0.1)
    with pytest.raises(ProcessLookupError):
        os.killpg(p.pid, 0)


def _bad_invocations(tmp: Path):
    """(arguments, expected words) of bad command lines: every one a one-line error."""
    box, ok = tmp / "box.stl", SCENES / "window.toml"
    trimesh.creation.box((1, 1, 1)).export(box)
    (tmp / "random.obj").write_bytes(bytes(range(256)) * 8)
    (tmp / "random.toml").write_bytes(bytes(range(256)) * 8)
    (tmp / "empty.obj").write_text("")
    (tmp / "nan.obj").write_text("v nan 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n")
    (tmp / "open.obj").write_text("v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n")
    (tmp / "typo.toml").write_text("[robot]\nboxx = [1, 1, 1]\n")
    (tmp / "x.cfg").write_text("[problem]\nworld = gone.dae\nrobot = gone.dae\n")
    return [
        # (trimesh reads the bytes as text or not, by whether a charset detector is there)
        (["sum", tmp / "random.obj", box], "random.obj"),
        (["sum", tmp / "empty.obj", box], "empty.obj"),
        (["sum", tmp / "nan.obj", box], "not finite"),
        (["sum", tmp / "open.obj", box], "boundary edges"),
        (["sum", box, tmp / "gone.stl"], "not found"),
        (["superset", tmp / "open.obj", box], "boundary edges"),
        (["convex-sum", tmp / "nan.obj", box], "not finite"),
        (["convex-sum", box, box, "-o", tmp / "out.unknown"], "unknown format"),
        (["convex-sum", box, box, "--grid-bits", "99"], "bits"),
        (["build", tmp / "random.toml"], "not valid TOML"),
        (["build", tmp / "typo.toml"], "planning: missing"),
        (["build", tmp / "gone.toml"], "not found"),
        (["build", tmp / "x.cfg"], "x.cfg"),
        (["build", ok, "-o", tmp / "out.txt"], "unknown format"),
        (["plan", ok, "--planner", "Nope"], "not a valid planner"),
        (["plan", ok, "--time", "0"], "'0' is not"),
        (["plan", ok, "-o", tmp / "p.xyz"], "unknown format"),
        (["plan", ok, "--result", tmp / "r.txt"], "unknown format"),
        (["view", ok, "-o", tmp / "v.png"], "unknown format"),
        (["view", tmp / "scene.unknown"], "unknown scene format"),
        (["check", ok, "--band", "-1"], "'-1' is not"),
        (["sum", box, box, "--workers", "0"], "'0' is not"),
    ]


def test_a_few_dozen_bad_command_lines(tmp_path):
    for args, words in _bad_invocations(tmp_path):
        r = cspace(*args)
        assert r.returncode == 2, (args, r.stdout, r.stderr)
        assert "Traceback" not in r.stderr, (args, r.stderr)
        assert words in r.stderr, (args, words, r.stderr)
        # One error line (argparse puts its usage lines above its own).
        errors = [x for x in r.stderr.splitlines() if x.startswith("cspace") and "error:" in x]
        assert len(errors) == 1, (args, r.stderr)
    assert sorted(p.name for p in tmp_path.iterdir() if p.name.startswith(("out", "p.", "r.",
                                                                            "v.", "."))) == []


def test_an_output_the_system_refuses_is_named_before_any_work():
    """``/proc`` passes a permission check but takes no new file: ``-o /proc/x.path`` is an
    error before the scene is even modelled (no planning output at all)."""
    r = cspace("plan", SCENES / "window.toml", "--seed", "1", "-o", "/proc/x.path")
    assert r.returncode == 2 and "cannot create files in '/proc'" in r.stderr
    assert "auto:" not in r.stdout and "solved" not in r.stdout
