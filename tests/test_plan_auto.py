"""``plan(..., planner='auto')`` and ``cspace plan`` without a planner: the shipped scenes
that a default RRTConnect leaves unsolved (window and cavity: a narrow gap; piano: a passage
the robot fits through only turned) are solved without flags, every path re-proved exactly
(and checked here again with our exact ``segment_free`` on the scene's C-space, and for the
turning path by FCL on the raw meshes in ``--fcl-check``)."""

from __future__ import annotations

import json
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

import cspace
from cspace.errors import InvalidArgumentError
from cspace.planning.plan import AUTO_SE3_QUICK, AUTO_SE3_QUICK_CAP, plan, verify_path

SCENES = Path(__file__).resolve().parents[1] / "scenes"


@pytest.mark.parametrize("name, first", [("window", ("decide", "PRM")),
                                         ("cavity", ("decide", "PRM")),
                                         ("comb", ("RRTConnect", "decide"))])
def test_auto_solves_narrow_gaps_at_the_start_orientation(name, first):
    """The gaps of window and cavity are a third of the decision's finest octree cell: its
    refinement along routes finds them (or the narrow sampler after it does); the comb's
    wide slots RRTConnect finds at once (or, on a busy machine, the decision after it).
    Translations only (``turns=False``): the decision then has 85% of the budget, not the 2 s
    a turning stage would take over from (on a busy machine the window's decision once
    outlasted 2 s and a turning path answered). The budget is far above what any of them takes
    (the run ends at the first path), so load decides at most which of them answers, never
    whether one does."""
    scene = cspace.load_scene(SCENES / f"{name}.toml")
    cs = cspace.CSpace.from_scene(scene)
    for seed in (1, 2, 3):
        r = plan(cs, scene.start, scene.goal, bounds=scene.bounds, planner="auto", time=60.0,
                 seed=seed, turns=False)
        assert r.solved and r.slices is None, (name, seed, r.tried)
        assert r.tried[-1]["planner"] in first and r.tried[-1]["solved"]
        if r.tried[-1]["planner"] == "decide":
            assert r.decision.answer == "path"
        assert all(not t["solved"] for t in r.tried[:-1])
        assert verify_path(cs, r.path, scene.bounds)["valid"]
        np.testing.assert_array_equal(r.path[0], scene.start)
        np.testing.assert_array_equal(r.path[-1], scene.goal)


def test_auto_turns_the_robot_when_translations_find_no_path():
    """The piano has no translation path at its start orientation (proved); the ball inside
    it passes the doorway, so there is no proof over all orientations; turning it in SE(3)
    passes, every motion certified. After the first translation attempt, a short SE(3)
    attempt (it usually solves the piano); when it does not, the decision at the start's
    orientation, the ball's, then the turning stage."""
    scene = cspace.load_scene(SCENES / "piano.toml")
    r = plan(scene, planner="auto", time=8.0, seed=1)
    assert r.solved and r.certified is not None, r.tried
    kinds = [(t["planner"], t.get("robot"), t.get("space")) for t in r.tried]
    assert kinds[:2] == [("RRTConnect", None, None), ("RRTConnect", None, "SE3")]
    assert r.tried[1]["time"] == pytest.approx(min(AUTO_SE3_QUICK * 8.0, AUTO_SE3_QUICK_CAP))
    if not r.tried[1]["solved"]:  # a busy machine: the schedule goes on
        assert kinds[2:4] == [("decide", None, None), ("decide", "inscribed ball", None)]
        assert all(t.get("space") == "SE3" for t in r.tried[4:])
        assert r.decision.answer == "no path" and r.tried[3]["answer"] == "unknown"
    assert r.tried[-1]["solved"] and r.tried[-1].get("space") == "SE3"
    assert np.ptp(r.orientations, axis=0).max() > 0  # it did turn
    kept = plan(scene, planner="auto", time=5.0, seed=1, turns=False)
    assert not kept.solved and kept.certified is None and len(kept.path) == 0
    assert [t["planner"] for t in kept.tried] == ["RRTConnect", "decide"]
    assert kept.decision.answer == "no path" and kept.status.startswith("No path")


def test_auto_answers_within_a_tiny_budget():
    scene = cspace.load_scene(SCENES / "window.toml")
    r = plan(scene, planner="auto", time=1e-6, seed=1)
    assert len(r.tried) >= 1 and r.tried[0]["planner"] == "RRTConnect"
    assert not r.solved or verify_path(cspace.CSpace.from_scene(scene), r.path,
                                       scene.bounds)["valid"]


def test_auto_chooses_what_it_chooses():
    scene = cspace.load_scene(SCENES / "comb.toml")
    with pytest.raises(InvalidArgumentError, match="chooses the sampler and the slices"):
        plan(scene, planner="auto", sampler="narrow")
    with pytest.raises(InvalidArgumentError, match="chooses the sampler and the slices"):
        plan(scene, planner="auto", slices=4)


def _cli(*args):
    return subprocess.run([sys.executable, "-m", "cspace", "plan", *map(str, args)],
                          capture_output=True, text=True, timeout=300)


def test_cspace_plan_without_flags_answers_every_shipped_scene(tmp_path):
    """A path, proved, for every scene with one; the proof that none exists (exit 3) for the
    cage, the one shipped scene without a path."""
    for scene in sorted(SCENES.glob("*.toml")):
        out = tmp_path / f"{scene.stem}.json"
        # a budget far above what any scene takes (each run ends at its path or proof):
        # load cannot change an answer
        p = _cli(scene, "--time", 60, "--seed", 1, "--no-cache", "--result", out,
                 "--fcl-check")
        if scene.stem == "cage":
            assert p.returncode == 3, (p.stdout[-1500:], p.stderr[-1500:])
            summary = json.loads(out.read_text())
            assert summary["decision"]["answer"] == "no path"
            continue
        assert p.returncode == 0, (scene.name, p.stdout[-1500:], p.stderr[-1500:])
        summary = json.loads(out.read_text())
        assert summary["solved"] and summary["valid_exact_recheck"]
        assert summary["fcl_recheck"]["colliding_samples"] == 0
        assert summary["tried"] and summary["tried"][-1]["solved"]
        assert "auto:" in p.stdout


def test_cspace_plan_no_turns_keeps_auto_at_the_start_orientation(tmp_path):
    """The piano has no translation path at its start orientation: with --no-turns that is
    proved (exit 3), and no sampler is run after the proof."""
    out = tmp_path / "r.json"
    p = _cli(SCENES / "piano.toml", "--time", 5, "--seed", 1, "--no-cache", "--no-turns",
             "--result", out)
    assert p.returncode == 3, p.stdout
    assert "orientation slices" not in p.stdout and "auto: PRM" not in p.stdout
    assert "no path at the start's orientation, proved" in p.stdout
    summary = json.loads(out.read_text())
    assert summary["decision"]["answer"] == "no path" and summary["path"] is None
    assert not summary["solved"]


def test_translations_only_give_the_rest_of_the_budget_to_the_decision(monkeypatch):
    """With turns=False and nothing found, what is left of the budget goes to deciding again
    (a proof may take minutes). The first decision is given far too little time here (its
    share set to 1e-4 s of the 10), so it ends 'unknown'; the second proves the cage
    closed."""
    plan_module = sys.modules["cspace.planning.plan"]  # the package shadows it by plan()
    shares = [(p, s, 1e-5 if p == "decide" else f, 1e-4 if p == "decide" else c)
              for p, s, f, c in plan_module.AUTO_SHARES]
    monkeypatch.setattr(plan_module, "AUTO_SHARES", tuple(shares))
    monkeypatch.setattr(plan_module, "AUTO_DECIDE_ALONE", 1e-5)
    r = plan(cspace.load_scene(SCENES / "cage.toml"), planner="auto", time=10.0, seed=1,
             turns=False)
    assert [t["planner"] for t in r.tried] == ["RRTConnect", "decide", "PRM", "decide"]
    assert r.tried[1]["answer"] == "unknown" and r.tried[3]["answer"] == "no path"
    assert not r.solved and r.decision.answer == "no path" and r.time < 10.0


def test_the_cage_is_proved_shut_with_default_settings_beside_busy_cores():
    """Issue #53: ``cspace plan scenes/cage.toml`` with no option (the default time, 10 s,
    the auto planner) exits 3 with both cores busy (two spinning processes), and Python's
    ``plan(scene)`` with its defaults (the same) gives the same proof."""
    # plain processes, killed and waited for: no child (nor multiprocessing's resource
    # tracker) outlives the test (test_workers counts this process's children)
    spinners = [subprocess.Popen([sys.executable, "-c", "while True: pass"]) for _ in range(2)]
    try:
        p = subprocess.run([sys.executable, "-m", "cspace", "plan", str(SCENES / "cage.toml"),
                            "--seed", "1", "--no-cache"], capture_output=True, text=True,
                           timeout=300)
        r = plan(cspace.load_scene(SCENES / "cage.toml"), seed=1)
    finally:
        for s in spinners:
            s.kill()
            s.wait()
    assert p.returncode == 3, (p.stdout[-1500:], p.stderr[-1500:])
    assert "no path at any orientation, proved" in p.stdout
    assert not r.solved and "proved" in r.status, r.status
