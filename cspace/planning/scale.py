"""Scale-out: build many C-obstacles through any ``concurrent.futures.Executor``.

A world with many bodies and many orientations outgrows one process. The pairs' builds go
through an Executor (:func:`cspace.scene.model.model_scene` ``executor=``): a local
``ProcessPoolExecutor``, or a Dask cluster (``dask.distributed``, the documented cluster
engine), with the content-hash disk cache (:mod:`cspace.scene.cache`) as the shared store. This
process models the scenes, reads cache hits and writes what the workers built; the workers
only build. Answers are those of the local build.

- :func:`executor_for` — ``None`` (build here), a process pool, or a Dask cluster's
  executor, from a scheduler address and a worker count (the CLI's ``--scheduler`` and
  ``--workers``). Dask is imported only here, and only when a scheduler is named.
- :func:`build_slices` — the C-spaces of many orientation slices of a scene's robot at once,
  through one executor: ``{k: CSpace}``, each what :meth:`TurningCSpace.slice(k)
  <cspace.planning.turning.TurningCSpace.slice>` builds.
"""

from __future__ import annotations

import multiprocessing as mp
import threading
from concurrent.futures import Executor, ProcessPoolExecutor, ThreadPoolExecutor

from ..errors import BuildError, InvalidArgumentError, MissingDependencyError
from .orientations import slice_scene, turning_frame

__all__ = ["executor_for", "DaskExecutor", "build_slices"]


class DaskExecutor(Executor):
    """A Dask client's ``concurrent.futures`` executor (``client.get_executor()``) that
    also closes the client (and the local cluster it started, if any) on ``shutdown``."""

    def __init__(self, client, cluster=None):
        self.client = client
        self.cluster = cluster
        self._executor = client.get_executor(pure=False)  # no hashing of the arguments

    def __repr__(self) -> str:
        return f"DaskExecutor({self.client.scheduler.address!r})"

    def submit(self, fn, /, *args, **kwargs):
        return self._executor.submit(fn, *args, **kwargs)

    def shutdown(self, wait: bool = True, *, cancel_futures: bool = False) -> None:
        self._executor.shutdown(wait=wait and not cancel_futures)
        self.client.close()
        if self.cluster is not None:
            self.cluster.close()


def _dask():
    try:
        import distributed
    except ImportError as exc:
        raise MissingDependencyError(
            "a Dask scheduler was named but dask.distributed is not installed: "
            "pip install 'dask[distributed]'") from exc
    return distributed


def executor_for(scheduler: str | None = None, workers: int | None = None):
    """The Executor the CLI's ``--scheduler`` and ``--workers`` name.

    Parameters
    ----------
    scheduler : str, optional
        A Dask scheduler's address (``tcp://host:8786``): its cluster's workers build;
        ``"local"``: a Dask ``LocalCluster`` of ``workers`` processes (one thread each)
        started here. None: no Dask.
    workers : int, optional
        Without a scheduler: None or 1 builds in this process (returns None); ``n > 1`` a
        ``ProcessPoolExecutor`` of ``n`` processes (started with ``spawn``: safe beside
        threads). With ``"local"``: the cluster's worker processes (default: the CPUs).
        A remote cluster's workers are its own: not allowed with an address.

    Returns
    -------
    None, ProcessPoolExecutor or DaskExecutor
        Use it as a context manager (``shutdown`` stops the pool, or closes the Dask client
        and any local cluster).

    Raises
    ------
    MissingDependencyError
        A scheduler is named and ``dask.distributed`` is not installed.
    InvalidArgumentError
        ``workers`` below 1, or given with a scheduler address.
    """
    if workers is not None and (int(workers) != workers or workers < 1):
        raise InvalidArgumentError(f"workers must be a whole number >= 1, got {workers!r}")
    if scheduler is None:
        if workers is None or workers == 1:
            return None
        return ProcessPoolExecutor(int(workers), mp_context=mp.get_context("spawn"))
    distributed = _dask()
    if scheduler == "local":
        cluster = distributed.LocalCluster(n_workers=workers, processes=True,
                                           threads_per_worker=1, dashboard_address=None)
        try:
            return DaskExecutor(distributed.Client(cluster), cluster)
        except BaseException:
            cluster.close()
            raise
    if workers is not None:
        raise InvalidArgumentError(f"workers: the cluster at {scheduler!r} has its own "
                                   "workers; --workers is for a local pool or --scheduler local")
    return DaskExecutor(distributed.Client(scheduler))


def build_slices(scene, slices, executor=None, *, ks=None, cache=None,
                 robot_hull: bool = False, progress=None) -> dict:
    """The C-spaces of orientation slices, built at once through one executor.

    Parameters
    ----------
    scene : Scene
    slices : Slices (or anything with ``rotation(k)``, ``len`` and ``label(k)``)
    executor : concurrent.futures.Executor, optional
        Where the pairs are built (:func:`executor_for`); None: here, slice after slice.
        With an executor a few slices are modelled at once (threads here), so that the
        workers build one slice while this process models the next.
    ks : iterable of int, optional
        The slices (default all).
    cache : COCache, path, True, or None
        The disk cache (the shared store): slices built before are read, not built.
    robot_hull : bool, default False
    progress : callable, optional
        ``progress(fraction, message)`` over all slices.

    Returns
    -------
    dict
        ``{k: CSpace}``: each what ``TurningCSpace(scene, slices, cache=cache,
        robot_hull=robot_hull).slice(k)`` builds (same modelling, same C-obstacles).

    Raises
    ------
    BuildError
        A body failed in a slice; the message names the slice and the body.
    """
    from ..scene.cache import COCache
    from ..scene.model import model_scene

    cache = COCache.of(cache)  # one cache for all slices: its packs are read once
    n = len(slices)
    ks = list(range(n)) if ks is None else sorted({int(k) % n for k in ks})
    frame, grid = turning_frame(scene)  # one grid, one modelling of the obstacles
    memo: dict = {}  # steps 1-3 and 5 once per body for all slices
    done: dict = {}
    lock = threading.Lock()

    def one(k):
        def sub(f, message):
            if progress is not None:
                with lock:
                    done[k] = f
                    progress(sum(done.values()) / len(ks), f"slice {k}: {message}")
        s = slice_scene(frame, slices, k)
        m = model_scene(s, grid=grid, cache=cache, robot_hull=robot_hull, executor=executor,
                        memo=memo, progress=sub)
        try:
            return k, m.cspace()
        except BuildError as exc:
            raise BuildError(f"slice {k} ({s.robot.name}): {exc}") from exc

    if executor is None or len(ks) < 2:
        return dict(one(k) for k in ks)
    with ThreadPoolExecutor(min(3, len(ks)), thread_name_prefix="cspace-slice") as threads:
        return dict(threads.map(one, ks))
