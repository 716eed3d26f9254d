"""The forked map of the exact trimming's parallel stages (cspace.workers)."""

import os
import time

import pytest

from cspace.workers import can_fork, forked_map, worker_count



@pytest.fixture(autouse=True)
def _forkable():
    """Forking must be possible when each test runs (checked then, not at import: a thread
    alive while tests are collected said nothing of the tests). A thread of an earlier test
    still shutting down is waited for, a little; one that stays is a leak to name."""
    import threading

    for _ in range(100):
        if can_fork():
            return
        time.sleep(0.05)
    pytest.fail("cspace cannot fork here: other threads alive "
                f"{[t.name for t in threading.enumerate() if t is not threading.main_thread()]}")

PARENT = os.getpid()


def _in_parent() -> bool:
    return os.getpid() == PARENT


def _no_children_left() -> bool:
    try:
        os.waitpid(-1, os.WNOHANG)
    except ChildProcessError:
        return True
    return False


@pytest.mark.parametrize("workers", [1, 2, 3])
def test_every_chunk_once_with_its_result(workers):
    chunks = [list(range(k, k + 5)) for k in range(0, 200, 5)]
    got = dict(forked_map(lambda c: (sum(x * x for x in c), os.getpid()), chunks, workers))
    assert sorted(got) == list(range(len(chunks)))
    assert all(got[k][0] == sum(x * x for x in chunks[k]) for k in got)
    assert _no_children_left()


def _wait_for(path) -> None:
    """This process waits for the file ``path`` (up to 60 s: a loaded machine is slow,
    never this slow), so that a child is sure to take a chunk whatever the load."""
    for _ in range(6000):
        if path.exists():
            return
        time.sleep(0.01)


def test_this_process_and_a_child_share_the_chunks(tmp_path):
    """With two workers one chunk queue feeds this process and one forked child: both take
    chunks. Each process's task marks that it ran and waits for the other's mark (no sleep
    decides it: on a busy machine the child could drain the queue before this process took
    a chunk; with the marks, neither can finish alone)."""
    def task(c):
        mine, other = ("parent", "child") if _in_parent() else ("child", "parent")
        (tmp_path / mine).touch()
        _wait_for(tmp_path / other)
        return os.getpid()

    pids = dict(forked_map(task, list(range(20)), 2))
    assert len(pids) == 20
    assert len(set(pids.values())) == 2 and PARENT in pids.values()
    assert _no_children_left()


def test_an_error_in_a_child_is_raised_here(tmp_path):
    def task(c):
        if _in_parent():
            _wait_for(tmp_path / "child")  # leave chunks to the child
            return c
        (tmp_path / "child").touch()
        raise ZeroDivisionError(f"chunk {c}")

    with pytest.raises(ZeroDivisionError, match="chunk"):
        list(forked_map(task, list(range(8)), 2))
    assert _no_children_left()


def test_a_child_that_dies_is_reported(tmp_path):
    def task(c):
        if _in_parent():
            _wait_for(tmp_path / "child")
            return c
        (tmp_path / "child").touch()
        os._exit(3)

    with pytest.raises(RuntimeError, match="died without a result"):
        list(forked_map(task, list(range(8)), 2))
    assert _no_children_left()


def test_leaving_early_stops_the_children():
    gen = forked_map(lambda c: time.sleep(0.01) or c, list(range(50)), 3)
    next(gen)
    gen.close()
    assert _no_children_left()


def test_worker_count(monkeypatch):
    monkeypatch.delenv("CSPACE_WORKERS", raising=False)
    assert worker_count(3) == 3 and worker_count(0) == 1
    assert worker_count(None) == len(os.sched_getaffinity(0))
    monkeypatch.setenv("CSPACE_WORKERS", "2")
    assert worker_count(None) == 2
    with pytest.raises(ValueError, match="positive integer"):
        worker_count("many")
