"""Forked workers for the exact trimming's two parallel stages (triangle pairs, plane
arrangements).

The work is pure Python on objects the caller has already built, so the workers are
``fork``ed: they inherit those objects and only results travel back (pickled through a
pipe). This process works too: with ``workers = n`` it forks ``n - 1`` children and takes
chunks alongside them, from one shared queue (a pipe of chunk numbers, so a slow core
takes fewer). Results do not depend on which process ran a chunk.
"""

from __future__ import annotations

import gc
import multiprocessing as mp
import os
import pickle
import signal
import struct
import threading

from .errors import InvalidArgumentError

__all__ = ["can_fork", "forked_map", "worker_count"]

# A chunk number in the queue pipe: 4 bytes, read whole (Linux reads a pipe under a lock
# and returns all requested bytes that are there; the queue is written in one go).
_TOKEN = struct.Struct("<i")
# The queue is written before any child starts: it must fit the pipe's buffer (64 KiB).
_MAX_CHUNKS = 16_000


def can_fork() -> bool:
    """Forking is available and safe here: not in a daemonic process (it may not have
    children) and no other thread (a lock it holds would stay locked in the child)."""
    return ("fork" in mp.get_all_start_methods() and not mp.current_process().daemon
            and threading.active_count() == 1)


def worker_count(workers: int | str | None) -> int:
    """Processes for the forked stages: ``workers``, else ``$CSPACE_WORKERS``, else the CPUs
    this process may run on."""
    if workers is None and os.environ.get("CSPACE_WORKERS", "").strip():
        workers = os.environ["CSPACE_WORKERS"]
    if workers is not None:
        try:
            return max(1, int(workers))
        except ValueError:
            raise InvalidArgumentError(f"workers must be a positive integer, got {workers!r}") from None
    try:
        return max(1, len(os.sched_getaffinity(0)))
    except AttributeError:  # pragma: no cover - not Linux
        return max(1, os.cpu_count() or 1)


def _take(queue: int) -> int | None:
    b = os.read(queue, _TOKEN.size)
    return _TOKEN.unpack(b)[0] if b else None


def _child(task, chunks: list, queue: int, out: int) -> None:
    """Body of a forked worker: chunks from the queue until it is empty, then every result
    (or the first error) pickled to ``out``; never returns."""
    code = 0
    try:
        gc.disable()  # a collection would touch, so copy, every inherited page
        done = []
        while (k := _take(queue)) is not None:
            done.append((k, task(chunks[k])))
        msg = pickle.dumps(("ok", done), protocol=pickle.HIGHEST_PROTOCOL)
    except BaseException as e:  # noqa: BLE001 - sent back to the parent, raised there
        code = 1
        try:
            msg = pickle.dumps(("error", e), protocol=pickle.HIGHEST_PROTOCOL)
        except Exception:  # an unpicklable exception: its text
            msg = pickle.dumps(("error", RuntimeError(repr(e))), protocol=pickle.HIGHEST_PROTOCOL)
    try:
        with os.fdopen(out, "wb") as f:
            f.write(msg)
    finally:
        os._exit(code)  # no atexit handlers, no buffers of the parent flushed twice


def _read_all(fd: int) -> bytes:
    with os.fdopen(fd, "rb") as f:
        return f.read()


def forked_map(task, chunks: list, workers: int):
    """``(k, task(chunks[k]))`` for every chunk, computed by this process and ``workers - 1``
    forked children, yielded in no fixed order: this process's own results as it makes
    them, the children's when they have finished. The children inherit this process's
    memory, so ``task`` may read anything built before the call; only results are pickled.
    Call only where :func:`can_fork` holds. An exception in a child is raised here."""
    n = len(chunks)
    if n > _MAX_CHUNKS:
        raise ValueError(f"forked_map takes at most {_MAX_CHUNKS} chunks, got {n}")
    if workers <= 1 or n <= 1:
        for k in range(n):
            yield k, task(chunks[k])
        return
    queue, fill = os.pipe()
    try:
        os.write(fill, b"".join(_TOKEN.pack(k) for k in range(n)))
    finally:
        os.close(fill)
    children = []  # (pid, read end of its result pipe)
    try:
        for _ in range(min(workers, n) - 1):
            r, w = os.pipe()
            pid = os.fork()
            if pid == 0:  # pragma: no cover - runs in the child, which never returns
                os.close(r)
                _child(task, chunks, queue, w)
            os.close(w)
            children.append((pid, r))
        while (k := _take(queue)) is not None:
            yield k, task(chunks[k])
        while children:
            pid, r = children[0]
            children[0] = (pid, None)  # _read_all closes r, also when interrupted mid-read
            data = _read_all(r)
            children.pop(0)
            _, status = os.waitpid(pid, 0)
            if not data:
                raise RuntimeError(f"a forked worker (pid {pid}) died without a result "
                                   f"(wait status {status})")
            kind, value = pickle.loads(data)
            if kind == "error":
                raise value
            yield from value
    finally:
        os.close(queue)
        for pid, r in children:  # only left on an error or an interrupt: stop, reap them
            try:
                os.kill(pid, signal.SIGKILL)
            except ProcessLookupError:  # pragma: no cover - already gone
                pass
            if r is not None:
                os.close(r)
            os.waitpid(pid, 0)
