"""The sweep engine: parameter tables cut into chunks, run on Dask workers, with restart.

A :class:`SweepSpec` is a table of runs (rows of :data:`~dryfriction.sweep.runner.PARAM_COLUMNS`)
and the settings shared by all of them. :class:`Engine` runs it:

- the table is cut into chunks of ``chunk_runs`` rows; each chunk is one Dask task, run by a
  worker process on its own FMU instance (loaded once per process, reset per run);
- every finished chunk is written to ``<chunk_dir>/<sweep>-<key>/cNNNNN.npy`` (temp name, then
  rename), where ``key`` hashes the table, the settings and the FMU binary, so a changed config or
  a rebuilt FMU never reuses stale chunks;
- on a restart, the chunks on disk are loaded, only the missing ones are computed;
- the result is the table of outputs in row order, whatever the number of workers: each run is
  independent and deterministic, so 1 or N workers give bit-identical numbers.

Workers: ``workers = 0`` runs in this process (no Dask), ``workers = N`` starts a
``LocalCluster`` of N single-threaded worker processes, ``scheduler = "host:port"`` uses an
existing Dask cluster (the FMU binary is sent to the workers, which need this package installed).
"""

from __future__ import annotations

import hashlib
import json
import logging
import shutil
import sys
import time
from collections.abc import Iterator, Mapping
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from ..atomic import atomic_path
from ..diagnostics import emit_new, recorded
from .runner import OUTPUT_COLUMNS, PARAM_COLUMNS, run_batch_timed

__all__ = ["SweepSpec", "EngineOptions", "SweepStats", "SweepInterrupted", "Engine"]


class SweepInterrupted(RuntimeError):
    """The sweep stopped before all chunks were computed (``max_chunks`` reached)."""


@dataclass
class SweepSpec:
    """One sweep: a parameter table and the settings shared by its runs."""

    name: str
    params: np.ndarray
    settings: Mapping[str, Any] = field(default_factory=dict)
    chunk_runs: int = 1000

    def __post_init__(self) -> None:
        self.params = np.ascontiguousarray(self.params, dtype=np.float64)
        if self.params.ndim != 2 or self.params.shape[1] != len(PARAM_COLUMNS):
            raise ValueError(f"sweep {self.name}: params must have shape (n, {len(PARAM_COLUMNS)})")
        if self.chunk_runs < 1:
            raise ValueError(f"sweep {self.name}: chunk_runs must be >= 1")

    @property
    def n_runs(self) -> int:
        return int(self.params.shape[0])

    @property
    def n_chunks(self) -> int:
        return -(-self.n_runs // self.chunk_runs)

    def chunk(self, i: int) -> np.ndarray:
        return self.params[i * self.chunk_runs:(i + 1) * self.chunk_runs]

    def key(self, fmu_digest: str) -> str:
        h = hashlib.sha256()
        h.update(self.params.tobytes())
        h.update(json.dumps(dict(self.settings), sort_keys=True).encode())
        h.update(str(self.chunk_runs).encode())
        h.update(fmu_digest.encode())
        return h.hexdigest()[:16]


@dataclass
class EngineOptions:
    fmu: Path
    workers: int = 0                 # 0: in this process; N: LocalCluster of N processes
    scheduler: str | None = None     # address of an existing Dask scheduler
    progress: bool = True
    max_chunks: int | None = None    # compute at most this many new chunks (then SweepInterrupted)


@dataclass
class SweepStats:
    name: str
    runs: int
    chunks: int
    loaded: int = 0
    computed: int = 0
    wall: float = 0.0
    startup: float = 0.0   # Dask client / LocalCluster start inside this sweep's wall time
    task_cpu: float = 0.0  # CPU seconds of the computed chunks' tasks (summed over workers)
    task_wall: float = 0.0  # wall seconds of the computed chunks' tasks (summed over workers)

    def line(self) -> str:
        rate = f", {self.runs / self.wall:,.0f} runs/s" if self.computed and self.wall > 0 else ""
        return (f"{self.name}: {self.runs:,} runs in {self.chunks} chunks "
                f"({self.loaded} loaded from disk, {self.computed} computed) in {self.wall:.1f} s{rate}")


def _atomic_save_npy(path: Path, arr: np.ndarray) -> None:
    with atomic_path(path) as tmp, open(tmp, "wb") as f:
        np.save(f, arr)


def _load_chunk(path: Path, n_rows: int) -> np.ndarray | None:
    try:
        arr = np.load(path)
    except (OSError, ValueError):
        return None
    if arr.shape != (n_rows, len(OUTPUT_COLUMNS)) or arr.dtype != np.float64:
        return None
    return arr


class Engine:
    """Runs sweeps; starts its Dask client lazily (only if some chunk must be computed)."""

    def __init__(self, options: EngineOptions) -> None:
        self.opt = options
        self._fmu_bytes = Path(options.fmu).read_bytes()
        self.fmu_digest = hashlib.sha256(self._fmu_bytes).hexdigest()
        self._client: Any = None
        self._cluster: Any = None
        self._fmu_future: Any = None
        self.stats: list[SweepStats] = []
        self._new_chunks = 0
        self.startup = 0.0

    # ---- Dask ----
    def _ensure_client(self) -> Any:
        if self._client is not None:
            return self._client
        t0 = time.perf_counter()
        from distributed import Client, LocalCluster

        if self.opt.scheduler:
            self._client = Client(self.opt.scheduler, timeout="20s")
        else:
            self._cluster = LocalCluster(
                n_workers=self.opt.workers,
                threads_per_worker=1,
                processes=True,
                dashboard_address=None,
                silence_logs=logging.ERROR,
            )
            self._client = Client(self._cluster)
        self._fmu_future = self._client.scatter(self._fmu_bytes, broadcast=True, hash=True)
        self.startup = time.perf_counter() - t0
        return self._client

    def close(self) -> None:
        if self._client is not None:
            self._client.close()
            self._client = None
        if self._cluster is not None:
            self._cluster.close()
            self._cluster = None

    def __enter__(self) -> "Engine":
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()

    @property
    def uses_dask(self) -> bool:
        return bool(self.opt.scheduler) or self.opt.workers > 0

    # ---- chunks ----
    def _chunk_path(self, folder: Path, i: int) -> Path:
        return folder / f"c{i:05d}.npy"

    def _compute_local(self, spec: SweepSpec, todo: list[int]) -> Iterator[tuple[int, Any]]:
        settings = dict(spec.settings)
        fmu = str(self.opt.fmu)
        for i in todo:
            yield i, run_batch_timed(fmu, settings, spec.chunk(i))

    def _compute_dask(self, spec: SweepSpec, todo: list[int]) -> Iterator[tuple[int, Any]]:
        from distributed import as_completed

        client = self._ensure_client()
        settings = dict(spec.settings)
        futures = {}
        for i in todo:
            fut = client.submit(recorded, run_batch_timed, self._fmu_future, settings, spec.chunk(i), pure=False)
            futures[fut] = i
        seen: set[str] = set()
        try:
            for fut in as_completed(futures):
                result, msgs = fut.result()
                emit_new(msgs, seen)  # the worker's FMU warnings, once each
                yield futures[fut], result
        finally:
            for fut in futures:
                fut.cancel()

    def run(self, spec: SweepSpec, chunk_root: Path) -> np.ndarray:
        """All outputs of the sweep (shape ``(n_runs, len(OUTPUT_COLUMNS))``), loading finished
        chunks from ``chunk_root`` and writing new ones there."""
        t0 = time.perf_counter()
        key = spec.key(self.fmu_digest)
        folder = Path(chunk_root) / f"{spec.name}-{key}"
        folder.mkdir(parents=True, exist_ok=True)
        for tmp in folder.glob(".c*.tmp"):  # half-written chunks of a killed run
            tmp.unlink(missing_ok=True)
        # chunks of an older config or FMU of the same sweep are stale: remove them
        for old in Path(chunk_root).glob(f"{spec.name}-*"):
            suffix = old.name[len(spec.name) + 1:]
            if old != folder and old.is_dir() and len(suffix) == 16 and all(c in "0123456789abcdef" for c in suffix):
                shutil.rmtree(old, ignore_errors=True)

        out = np.empty((spec.n_runs, len(OUTPUT_COLUMNS)))
        stats = SweepStats(spec.name, spec.n_runs, spec.n_chunks)
        todo: list[int] = []
        for i in range(spec.n_chunks):
            rows = spec.chunk(i).shape[0]
            arr = _load_chunk(self._chunk_path(folder, i), rows)
            if arr is None:
                todo.append(i)
            else:
                out[i * spec.chunk_runs:i * spec.chunk_runs + rows] = arr
                stats.loaded += 1

        if todo:
            budget = None if self.opt.max_chunks is None else max(self.opt.max_chunks - self._new_chunks, 0)
            done_runs = spec.n_runs - sum(spec.chunk(i).shape[0] for i in todo)
            bar = None
            if self.opt.progress:
                from tqdm import tqdm

                bar = tqdm(total=spec.n_runs, initial=done_runs, unit="run", desc=spec.name,
                           file=sys.stderr, dynamic_ncols=True, smoothing=0.05)
            compute = self._compute_dask if self.uses_dask else self._compute_local
            if self.uses_dask and self._client is None:
                self._ensure_client()
                stats.startup = self.startup
            interrupted = False
            try:
                if budget == 0:
                    interrupted = True
                else:
                    for i, (arr, cpu, wall) in compute(spec, todo):
                        stats.task_cpu += cpu
                        stats.task_wall += wall
                        _atomic_save_npy(self._chunk_path(folder, i), arr)
                        rows = arr.shape[0]
                        out[i * spec.chunk_runs:i * spec.chunk_runs + rows] = arr
                        stats.computed += 1
                        self._new_chunks += 1
                        if bar is not None:
                            bar.update(rows)
                        if budget is not None and stats.computed >= budget:
                            interrupted = stats.computed < len(todo)
                            break
            finally:
                if bar is not None:
                    bar.close()
            if interrupted:
                stats.wall = time.perf_counter() - t0
                self.stats.append(stats)
                raise SweepInterrupted(
                    f"{spec.name}: stopped after {stats.computed} new chunk(s) "
                    f"({stats.loaded + stats.computed} of {spec.n_chunks} done); run again to finish")
        stats.wall = time.perf_counter() - t0
        self.stats.append(stats)
        return out
