"""Where the per-run work runs: in process, a process pool, or a dask.distributed cluster.

Runs are independent until calibration. :func:`make_executor` gives one object with one
method, :meth:`RunExecutor.map_unordered`, that calls a function on each item and yields
``(index, result)`` as results come in, over an existing engine (no home-made scheduler):

``jobs = 1``, no dask
    In process, in order (:class:`SerialExecutor`).
``jobs > 1``
    :class:`concurrent.futures.ProcessPoolExecutor` with ``jobs`` workers, started with
    ``spawn`` (the parent may hold threads, such as tqdm's monitor: forking a process that
    holds threads can deadlock the child).
``dask = ADDRESS``
    A :class:`distributed.Client` on that scheduler (``tcp://host:8786``); the workers
    write into OUTDIR themselves, so it must be on a file system every worker sees.
``dask = "local"``
    A :class:`distributed.LocalCluster` in this process (``processes=False``: one worker,
    two threads): nothing to pickle or spawn, robust on 2 cores; the NumPy and SciPy kernels
    release the GIL for most of the work.

The first exception a task raises (a write that failed, a bug) cancels what is left and is
raised again here; a bad recording is not an exception (the task returns a failed run).
"""

from __future__ import annotations

import concurrent.futures as cf
import multiprocessing
from collections.abc import Callable, Iterator, Sequence
from typing import Any, Final, Protocol, TypeVar

__all__ = [
    "LOCAL",
    "DaskExecutor",
    "OnDemand",
    "PoolExecutor",
    "RunExecutor",
    "SerialExecutor",
    "make_executor",
]

#: The ``dask`` value that starts a cluster in this process.
LOCAL: Final = "local"
#: Threads of the local dask worker.
_LOCAL_THREADS: Final = 2

T = TypeVar("T")
R = TypeVar("R")


class RunExecutor(Protocol):
    """Calls a function on items somewhere, yielding results as they come."""

    #: A short description for logs (``"serial"``, ``"2 processes"``, ``"dask tcp://..."``).
    description: str

    def map_unordered(self, fn: Callable[..., R], items: Sequence[tuple[Any, ...]]
                      ) -> Iterator[tuple[int, R]]:
        """``(i, fn(*items[i]))`` for every item, in the order they finish."""
        ...

    def close(self) -> None:
        """Release the workers."""
        ...


class SerialExecutor:
    """In process, in order."""

    description = "serial"

    def map_unordered(self, fn: Callable[..., R], items: Sequence[tuple[Any, ...]]
                      ) -> Iterator[tuple[int, R]]:
        """See :class:`RunExecutor`."""
        for i, args in enumerate(items):
            yield i, fn(*args)

    def close(self) -> None:
        """Nothing to release."""


class PoolExecutor:
    """A process pool of ``jobs`` workers (``spawn``).

    Parameters
    ----------
    jobs : int
        Worker processes (>= 1).
    """

    def __init__(self, jobs: int) -> None:
        self.description = f"{jobs} processes"
        self._pool = cf.ProcessPoolExecutor(max_workers=jobs,
                                            mp_context=multiprocessing.get_context("spawn"))

    def map_unordered(self, fn: Callable[..., R], items: Sequence[tuple[Any, ...]]
                      ) -> Iterator[tuple[int, R]]:
        """See :class:`RunExecutor`."""
        futures = {self._pool.submit(fn, *args): i for i, args in enumerate(items)}
        try:
            for fut in cf.as_completed(futures):
                yield futures[fut], fut.result()
        finally:
            for fut in futures:
                fut.cancel()

    def close(self) -> None:
        """Stop the workers (pending work cancelled)."""
        self._pool.shutdown(wait=True, cancel_futures=True)


class DaskExecutor:
    """A dask.distributed client: on a scheduler's address, or a local cluster.

    Parameters
    ----------
    address : str
        ``"local"`` (:data:`LOCAL`) or the scheduler's address.
    """

    def __init__(self, address: str) -> None:
        # dask.distributed takes about a second to import: loaded only when asked for.
        import distributed

        self._distributed = distributed
        self._cluster: Any = None
        if address == LOCAL:
            self._cluster = distributed.LocalCluster(
                n_workers=1, threads_per_worker=_LOCAL_THREADS, processes=False,
                dashboard_address=None)
            self._client = distributed.Client(self._cluster)
            self.description = f"dask local cluster ({_LOCAL_THREADS} threads)"
        else:
            self._client = distributed.Client(address, timeout="30s")
            self.description = f"dask {address}"

    def map_unordered(self, fn: Callable[..., R], items: Sequence[tuple[Any, ...]]
                      ) -> Iterator[tuple[int, R]]:
        """See :class:`RunExecutor`."""
        futures = [self._client.submit(fn, *args, pure=False) for args in items]
        index = {f.key: i for i, f in enumerate(futures)}
        try:
            for fut in self._distributed.as_completed(futures):
                yield index[fut.key], fut.result()
        finally:
            self._client.cancel(futures)

    def close(self) -> None:
        """Close the client (and the local cluster)."""
        self._client.close()
        if self._cluster is not None:
            self._cluster.close()


class OnDemand:
    """The executor of the settings, started on the first work it is given.

    A re-run that reuses every run's outputs starts no process pool and no dask client.

    Parameters
    ----------
    jobs, dask
        As for :func:`make_executor` (checked here, before any work).
    """

    def __init__(self, jobs: int = 1, dask: str | None = None) -> None:
        _check(jobs, dask)
        self._jobs, self._dask = jobs, dask
        self._executor: RunExecutor | None = None
        self.description = (f"dask {'local cluster' if dask == LOCAL else dask}" if dask
                            else "serial" if jobs == 1 else f"{jobs} processes")

    def map_unordered(self, fn: Callable[..., R], items: Sequence[tuple[Any, ...]]
                      ) -> Iterator[tuple[int, R]]:
        """See :class:`RunExecutor`."""
        if self._executor is None:
            self._executor = make_executor(self._jobs, self._dask)
        return self._executor.map_unordered(fn, items)

    def close(self) -> None:
        """Release the workers, if any were started."""
        if self._executor is not None:
            self._executor.close()
            self._executor = None


def _check(jobs: int, dask: str | None) -> None:
    if isinstance(jobs, bool) or not isinstance(jobs, int) or jobs < 1:
        raise ValueError(f"`jobs` must be an integer >= 1, was {jobs!r}")
    if dask is not None and not str(dask).strip():
        raise ValueError("`dask` must be 'local' or a scheduler address, was ''")


def make_executor(jobs: int = 1, dask: str | None = None) -> RunExecutor:
    """The executor of the settings (module notes).

    Parameters
    ----------
    jobs : int
        Worker processes (1: in process).
    dask : str, optional
        ``"local"`` or a scheduler address; takes precedence over ``jobs``.

    Returns
    -------
    RunExecutor

    Raises
    ------
    ValueError
        ``jobs`` below 1, or an empty ``dask``.
    """
    _check(jobs, dask)
    if dask is not None:
        return DaskExecutor(str(dask).strip())
    if jobs == 1:
        return SerialExecutor()
    return PoolExecutor(jobs)
