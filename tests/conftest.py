"""Shared fixtures: the shared data folder, hypothesis profiles."""

from __future__ import annotations

import os
from pathlib import Path

import pytest
from hypothesis import HealthCheck, settings

# CI: derandomized and bounded; dev: more examples. Chosen by HYPOTHESIS_PROFILE.
settings.register_profile(
    "ci", max_examples=200, derandomize=True, deadline=None,
    suppress_health_check=[HealthCheck.too_slow],
)
settings.register_profile("dev", max_examples=1000, deadline=None)
settings.load_profile(os.environ.get("HYPOTHESIS_PROFILE", "ci"))

# ../shared/data beside the project root (tests/ -> project -> ..).
SHARED_DATA = Path(__file__).resolve().parents[2] / "shared" / "data"


@pytest.fixture(scope="session")
def shared_data() -> Path:
    """The shared real-mesh folder; tests using it skip (with the reason) if it is absent.
    Only tests of real meshes take it: a synthetic case never depends on it."""
    if not SHARED_DATA.is_dir():
        pytest.skip(f"shared data folder not found at {SHARED_DATA}")
    return SHARED_DATA


def shared_file(rel: str) -> Path:
    """The file ``rel`` of the shared data folder; the calling test skips, naming the file,
    when it is absent (and so fails on CI, see :func:`pytest_sessionfinish`)."""
    path = SHARED_DATA / rel
    if not path.exists():
        pytest.skip(f"real mesh {rel} not found under {SHARED_DATA}")
    return path


def pytest_sessionfinish(session, exitstatus):
    """On CI (``$CI`` set, as ``.ci/run`` has it) a skipped test fails the run: CI has
    ``../shared`` and everything else a test needs, so a skip there hides a regression."""
    reporter = session.config.pluginmanager.get_plugin("terminalreporter")
    skipped = reporter.stats.get("skipped", []) if reporter is not None else []
    if os.environ.get("CI") and skipped and exitstatus == 0:
        reporter.write_line(f"CI: {len(skipped)} tests skipped; on CI nothing may skip:",
                            red=True)
        for report in skipped[:20]:
            why = report.longrepr[-1] if isinstance(report.longrepr, tuple) else report.longrepr
            reporter.write_line(f"  {report.nodeid}: {why}")
        session.exitstatus = 1


def pytest_configure(config):
    """``$CSPACE_MUTANT``: run the session on a deliberately broken build (tests/mutants.py,
    for the mutation sweep of benchmarks/bench_mutations.py)."""
    name = os.environ.get("CSPACE_MUTANT")
    if name:
        import mutants

        mutants.apply(name)


def pytest_collection_modifyitems(session, config, items):
    """Tests marked ``last`` run after all others: a Dask client leaves a thread in this
    process (so cspace no longer forks its workers) and spawned pools leave a resource
    tracker child, which the fork tests would otherwise see. (``make test`` runs the others in
    pytest-xdist's workers and these in a process of their own, for the same reason.)"""
    items.sort(key=lambda item: item.get_closest_marker("last") is not None)
