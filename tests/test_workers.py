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


def test_this_process_and_a_child_share_the_chunks():
    """With two workers one chunk queue feeds this process and one forked child: a slow
    parent leaves most chunks to the child."""
    def task(c):
        # The child is quicker, but not instant: under load it could otherwise drain the
        # queue before this process takes its first chunk.
        time.sleep(0.05 if _in_parent() else 0.01)
        return os.getpid()

    pids = dict(forked_map(task, list(range(20)), 2))
    assert len(pids) == 20
    mine = sum(p == PARENT for p in pids.values())
    assert 1 <= mine < 10 and len(set(pids.values())) == 2
    assert _no_children_left()


def test_an_error_in_a_child_is_raised_here():
    def task(c):
        if _in_parent():
            time.sleep(0.05)  # leave chunks to the child
            return c
        raise ZeroDivisionError(f"chunk {c}")

    with pytest.raises(ZeroDivisionError, match="chunk"):
        list(forked_map(task, list(range(8)), 2))
    assert _no_children_left()


def test_a_child_that_dies_is_reported():
    def task(c):
        if _in_parent():
            time.sleep(0.05)
            return c
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
