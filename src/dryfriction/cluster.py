"""The one way tasks run on Dask: a quiet cluster, tasks streamed, lost workers survived.

- **Quiet**: Dask's loggers and warnings (``distributed``, ``tornado``, a killed worker's
  ``CommClosedError``, the ``resource_tracker``'s leaked-semaphore warning of a killed process) do
  not reach the user while the client lives: the workers log only what is critical, and the
  client's loggers are silenced for as long as it is open.
- **Streamed**: :func:`stream` submits at most ``in_flight`` tasks at a time and the next one when
  one finishes (:func:`distributed.as_completed`); each task is built from small arguments (a
  chunk's parameters), so the graph the scheduler holds is a few tasks of a few kB, whatever the
  size of the sweep.
- **Nothing scattered**: the workers of a :class:`~distributed.LocalCluster` read the FMU from its
  path; on an external scheduler each task carries the FMU's bytes (written once per machine to a
  temp file named by their hash, :mod:`dryfriction.sweep.runner`). A lost worker takes nothing with
  it that the other tasks need.
- **Lost workers**: a task whose worker died (all of them at once included: the nannies start new
  ones) is submitted again, up to :data:`RETRIES` times; then :class:`ClusterLost` says so in one
  line (a sweep's finished chunks are on disk: run again to resume).
"""

from __future__ import annotations

import logging
import os
import time
import warnings
from collections.abc import Callable, Iterable, Iterator
from contextlib import contextmanager
from pathlib import Path
from typing import Any

__all__ = ["ClusterLost", "Cluster", "stream", "quiet_dask", "RETRIES"]

#: times a task is submitted again after its worker was lost
RETRIES = 4
_LOGGERS = ("distributed", "tornado", "asyncio", "bokeh")
_QUIET = logging.CRITICAL + 10


class ClusterLost(RuntimeError):
    """The Dask workers were lost more often than :data:`RETRIES` while running one task, or the
    cluster could not be reached: one line (finished chunks are kept)."""


@contextmanager
def quiet_dask() -> Iterator[None]:
    """Dask's loggers above critical and its warnings ignored in this process while the block runs
    (restored after)."""
    old = {n: logging.getLogger(n).level for n in _LOGGERS}
    for n in _LOGGERS:
        logging.getLogger(n).setLevel(_QUIET)
    try:
        with warnings.catch_warnings():
            warnings.filterwarnings("ignore", module="distributed")
            warnings.filterwarnings("ignore", module="dask")
            warnings.filterwarnings("ignore", message=".*leaked semaphore.*")
            yield
    finally:
        for n, level in old.items():
            logging.getLogger(n).setLevel(level)


class Cluster:
    """A Dask client: a LocalCluster of ``workers`` single-threaded processes, or an existing
    ``scheduler``. ``fmu_arg(path)`` is what a task gets for the FMU (the path on a LocalCluster,
    the bytes on an external scheduler)."""

    def __init__(self, workers: int, scheduler: str | None = None) -> None:
        self._quiet = quiet_dask()
        self._quiet.__enter__()
        # the workers and the resource tracker inherit this: a killed worker's semaphore is not
        # reported by a process the user never started
        os.environ.setdefault("PYTHONWARNINGS", "ignore:resource_tracker:UserWarning")
        t0 = time.perf_counter()
        from distributed import Client, LocalCluster

        self.cluster: Any = None
        self.external = bool(scheduler)
        try:
            if scheduler:
                self.client = Client(scheduler, timeout="20s")
            else:
                self.cluster = LocalCluster(n_workers=workers, threads_per_worker=1, processes=True,
                                            dashboard_address=None, silence_logs=_QUIET)
                self.client = Client(self.cluster)
        except OSError as e:  # no scheduler there
            self._quiet.__exit__(None, None, None)
            raise ClusterLost(f"cannot reach the Dask scheduler {scheduler}: {e}") from None
        self.workers = max(1, workers if not scheduler else len(self.client.scheduler_info().get("workers", {})))
        self.startup = time.perf_counter() - t0
        self._fmu: dict[str, str | bytes] = {}

    def fmu_arg(self, path: str | os.PathLike[str]) -> str | bytes:
        """The FMU as a task gets it: its absolute path (LocalCluster) or its bytes (external)."""
        key = str(Path(path).resolve())
        if key not in self._fmu:
            self._fmu[key] = Path(key).read_bytes() if self.external else key
        return self._fmu[key]

    def peak_rss(self) -> dict[str, float]:
        """Each worker's peak resident memory so far, bytes (``ru_maxrss``)."""
        def rss() -> float:
            import resource
            import sys

            r = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss
            return float(r if sys.platform == "darwin" else r * 1024)

        return self.client.run(rss)

    def close(self) -> None:
        """Close the client and the LocalCluster (quietly, whatever state the workers are in) and
        give Dask's loggers and warnings back their settings."""
        try:
            self.client.close()
            if self.cluster is not None:
                self.cluster.close()
        except Exception:  # noqa: BLE001 - a cluster that lost its workers closes as it can
            pass
        finally:
            self._quiet.__exit__(None, None, None)


def _lost(exc: BaseException) -> bool:
    """A failure of the cluster (a worker died, a connection closed, a future forgotten), not of
    the task's own code."""
    import asyncio
    import concurrent.futures

    name = type(exc).__name__
    return isinstance(exc, (asyncio.CancelledError, concurrent.futures.CancelledError, ConnectionError,
                            asyncio.TimeoutError)) or name in (
        "KilledWorker", "CommClosedError", "FutureCancelledError", "CancelledError", "StreamClosedError")


def stream(cluster: Cluster, func: Callable[..., Any], tasks: Iterable[tuple[Any, tuple[Any, ...]]],
           in_flight: int | None = None, retries: int = RETRIES) -> Iterator[tuple[Any, Any]]:
    """``(key, func(*args))`` for every ``(key, args)`` of ``tasks``, as they finish, with at most
    ``in_flight`` (default: twice the workers) submitted at a time; a task whose worker was lost is
    submitted again (``retries`` times, then :class:`ClusterLost`); the task's own exception is
    raised as is. Unfinished tasks are cancelled when the iteration stops."""
    from distributed import as_completed

    client = cluster.client
    limit = max(2, in_flight or 2 * cluster.workers)
    it = iter(tasks)
    running: dict[Any, tuple[Any, tuple[Any, ...], int]] = {}

    def submit(key: Any, args: tuple[Any, ...], tries: int) -> Any:
        fut = client.submit(func, *args, pure=False)
        running[fut] = (key, args, tries)
        return fut

    pending = as_completed()
    try:
        for key, args in it:
            pending.add(submit(key, args, 0))
            if len(running) >= limit:
                break
        for fut in pending:
            key, args, tries = running.pop(fut)
            try:
                result = fut.result()
            except Exception as exc:  # noqa: BLE001 - sorted below
                if not _lost(exc) and fut.status != "cancelled":
                    raise
                if tries >= retries:
                    raise ClusterLost(f"the Dask workers were lost {tries + 1} times while one task ran; "
                                      "finished chunks are kept, run again to resume") from None
                pending.add(submit(key, args, tries + 1))
                continue
            finally:
                fut.release()
            yield key, result
            nxt = next(it, None)
            if nxt is not None:
                pending.add(submit(nxt[0], nxt[1], 0))
    finally:
        for fut in list(running):
            fut.cancel()
