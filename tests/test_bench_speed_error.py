"""The speed-against-error benchmark (``benchmarks/bench_speed_error.py``) in ``--quick`` mode.

Runs the script once, in a subprocess, into a temporary folder (about 20 s on 2 cores) and
checks what it wrote: the report, both charts and the JSON sidecar, whose numbers are the
run's own. cspace's rows must never be unsafe (no false free state, no unsafe motion) and
every error they make must stay within their stated bound; the references must agree with
FCL; and the approximate methods must show the errors they are known to make (so that a
measurement that returned nothing would fail here, too).
"""

from __future__ import annotations

import json
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
SCRIPT = ROOT / "benchmarks" / "bench_speed_error.py"
BITS = [12, 16, 20, 24, 26, 28]


@pytest.fixture(scope="module")
def run(tmp_path_factory):
    pytest.importorskip("matplotlib", reason="the charts need the bench extra: "
                        "pip install -e '.[bench]'")
    pytest.importorskip("manifold3d", reason="the peers extra: pip install -e '.[peers]'")
    out = tmp_path_factory.mktemp("speed_vs_error")
    sidecar = out / "numbers" / "run.json"
    proc = subprocess.run([sys.executable, str(SCRIPT), "--quick", "--out", str(out),
                           "--json", str(sidecar)], capture_output=True, text=True,
                          timeout=300)
    assert proc.returncode == 0, proc.stderr[-3000:]
    return out, json.loads(sidecar.read_text())


def test_report_and_charts_written(run):
    out, data = run
    text = (out / "speed_vs_error.md").read_text()
    for png in ("speed_vs_error_cobstacle.png", "speed_vs_error_checks.png"):
        assert (out / png).read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
        assert f"]({png})" in text  # embedded in the report
    assert "--quick" in text and "load average" in text
    assert data["mode"] == "quick"
    for res in data["construction"]:
        assert f"### {res['input']}" in text
    for res in data["checks"]:
        assert f"### {res['scene']}" in text


def _rows(res, method):
    return [r for r in res["rows"] if r["method"] == method]


def test_cspace_construction_is_safe_and_within_its_bound(run):
    _, data = run
    assert len(data["construction"]) >= 2
    for res in data["construction"]:
        rows = _rows(res, "cspace")
        assert [r["param"] for r in rows] == [f"{b} bits" for b in BITS]
        for r in rows:
            assert r["result"] == "ok", r
            assert r["n_decided"] == res["n"] - res["n_excluded"] > 1000
            assert r["false_free"] == 0, (res["input"], r)
            assert r["deepest_false_free_rel"] == 0.0
            # every error a false collision within the stated bound: the Hausdorff estimate
            # too, up to the error of the true boundary's samples (the 28-bit C-obstacle)
            assert r["farthest_false_coll_rel"] <= r["bound_rel"], (res["input"], r)
            assert r["hausdorff_rel"] <= r["bound_rel"] + res["reference_bound_rel"], r
            assert r["vol_err"] is not None and r["vol_err"] < 1e-2
        # precision follows the bits: the stated bound shrinks by 2**4 per 4 bits
        bounds = [r["bound_rel"] for r in rows]
        assert all(a > 4 * b for a, b in zip(bounds, bounds[1:4]))
        # most near-boundary states are false collisions at 12 bits, fewer at 28
        assert rows[0]["false_coll"] > rows[-1]["false_coll"]


def test_approximations_show_their_errors(run):
    _, data = run
    L = next(res for res in data["construction"] if res["input"].startswith("L bracket"))
    hull = _rows(L, "convex hull")[0]
    assert hull["false_free"] == 0 and hull["hausdorff_rel"] > 0.1  # fills the L's corner
    voxels = _rows(L, "voxels")
    assert len(voxels) == 3 and all(r["result"] == "ok" for r in voxels)
    assert min(r["hausdorff_rel"] for r in voxels) > 1e-3
    assert sum(r["false_free"] + r["false_coll"] for r in voxels) > 0
    mf = _rows(L, "manifold3d")[0]
    assert mf["result"] == "ok" and mf["hausdorff_rel"] < 1e-12


def test_checks_cspace_never_unsafe_and_truth_agrees_with_fcl(run):
    _, data = run
    assert data["checks"]
    for res in data["checks"]:
        assert res["m"] == data["n_motions"] == 1000
        assert res["cross_check"]["n"] > 0 and res["cross_check"]["disagree"] == 0
        rows = _rows(res, "cspace")
        assert len(rows) == len(BITS)
        for r in rows:
            assert r["state_false_free"] == 0 and r["motion_unsafe"] == 0, (res["scene"], r)
            assert r["state_farthest_false_coll_rel"] <= r["bound_rel"] + 1e-12
        fcl = _rows(res, "FCL")
        assert [r["param"] for r in fcl] == [f"discrete {x:g} S" for x in
                                            (0.1, 0.01, 0.001, 0.0001)]
        # a finer sampling never accepts more colliding motions (same motions, nested
        # samples only when the steps divide; here: never more than the coarsest)
        assert fcl[-1]["motion_unsafe"] <= fcl[0]["motion_unsafe"]
        assert fcl[-1]["motion_s_per_1e6"] > fcl[0]["motion_s_per_1e6"]
