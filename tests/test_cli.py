"""The command line mirrors the Python API and reports bad input as an error, not a trace."""

from __future__ import annotations

import subprocess
import sys

import numpy as np
import trimesh

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


def test_superset_reports_an_open_mesh(tmp_path, capsys):
    box = trimesh.creation.box()
    open_box = trimesh.Trimesh(box.vertices, box.faces[:-1], process=False)
    a = tmp_path / "open.ply"
    open_box.export(a)
    assert main(["superset", str(a), str(a)]) == 2
    assert "boundary edges" in capsys.readouterr().err
