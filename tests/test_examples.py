"""The examples a user copies from run, as scripts, and print what they promise."""

from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

pytest.importorskip("ompl")
pytest.importorskip("fcl")

ROOT = Path(__file__).resolve().parents[1]


def run(tmp_path, script, *args) -> str:
    env = {**os.environ, "CSPACE_CACHE": str(tmp_path / "cache")}
    r = subprocess.run([sys.executable, str(ROOT / "examples" / script), *map(str, args)],
                       capture_output=True, text=True, env=env, timeout=120, cwd=tmp_path)
    assert r.returncode == 0, r.stdout + r.stderr
    return r.stdout


def test_plan_in_scene(tmp_path):
    out = run(tmp_path, "plan_in_scene.py", ROOT / "scenes" / "comb.toml", 2)
    assert "17 obstacle bodies -> 17 modelled: 11 convex, 0 solid, 0 surface, 6 dropped" in out
    assert "solved (exact and re-proved): True" in out
    assert "exact re-check: valid=True; FCL re-check: 0 colliding of" in out
    assert "(cache miss)" in out
    # The second run loads every C-obstacle from the cache.
    again = run(tmp_path, "plan_in_scene.py", ROOT / "scenes" / "comb.toml", 2)
    assert "(cache miss)" not in again and again.count("(cache hit)") == 11


def test_decide_scenes(tmp_path):
    out = run(tmp_path, "decide_scenes.py", "--out", tmp_path)
    assert "cage: no path (start and goal in different components" in out
    assert "comb: path (a route through free cells" in out
    for name in ("cage", "comb"):  # offline pages (their drawing is tested in test_viz)
        assert (tmp_path / f"decide_{name}.html").stat().st_size > 10_000


def test_own_ompl_setup(tmp_path):
    out = run(tmp_path, "own_ompl_setup.py")
    assert "status: Exact solution" in out and "exactly collision-free: True" in out


def test_penetration_depth(tmp_path):
    out = run(tmp_path, "penetration_depth.py")
    assert "kind 'mesh'" in out  # a non-convex C-obstacle
    assert "tube centre (deep inside)    q = (1.0, 0.0, 0.0): in collision, penetration depth 0.4000" in out
    assert "centre of the hole (free)" in out and "free, clearance 0.5478" in out
    assert "moved up by depth + 1e-6 -> in collision: False" in out


def test_plan_with_turns(tmp_path):
    out = run(tmp_path, "plan_with_turns.py")
    assert "without turning: solved False" in out
    assert "with 8 orientations: solved True" in out
    assert "FCL re-check along translations and turns: 0 colliding of" in out


def test_plan_in_se3(tmp_path):
    out = run(tmp_path, "plan_in_se3.py")
    assert "tried decide: no path" in out and "solved True" in out
    assert "FCL re-check along the motions: 0 colliding of" in out
    rows = np.loadtxt(tmp_path / "out" / "plate.path")
    assert rows.shape[1] == 7 and (tmp_path / "out" / "plate.html").stat().st_size > 10000
