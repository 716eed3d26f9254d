"""The scale-out benchmark (``benchmarks/bench_scale.py``) in ``--quick`` mode: N = 50 bodies x 4
slices, 1 process, a process pool and a 2-worker Dask ``LocalCluster`` (about 20 s on 2 cores).
Checks that the report is written with the run's own numbers and that every configuration
answered the queries as the 1-process build."""

from __future__ import annotations

import re
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
SCRIPT = ROOT / "benchmarks" / "bench_scale.py"


@pytest.mark.slow  # 15 s: make test-slow (the default run stays under 10 minutes)
def test_quick_report_is_written(tmp_path):
    pytest.importorskip("distributed")
    out = tmp_path / "scale.md"
    proc = subprocess.run([sys.executable, str(SCRIPT), "--quick", "--out", str(out)],
                          capture_output=True, text=True, timeout=300)
    assert proc.returncode == 0, proc.stderr[-3000:]
    text = out.read_text()
    assert "## N = 50 bodies x 4 slices = 200 body-slices" in text
    for label in ("| 1 process |", "| process pool (", "| Dask LocalCluster (2 workers) |",
                  "| 1 process, every pair a cache hit |"):
        row = next(line for line in text.splitlines() if line.startswith(label))
        seconds, per = (float(x) for x in row.split("|")[3:5])
        assert seconds > 0 and per > 0, row
    assert "identically: **True**" in text
    assert re.search(r"\*\*\d+ workers\*\* for the builds", text)
    assert re.search(r"takes \*\*\d+ bytes\*\* on disk", text)
